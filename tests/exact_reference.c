/*
 * The exact reference of exact_reference.h: rational vectors, planes and homogeneous
 * integer points built from input doubles with GMP, the LPI and TPI constructions, the
 * predicates as signs of their defining expressions, and exact comparisons of doubles
 * with rationals. Nothing here comes from src/: see the header for why that matters.
 */
#include "exact_reference.h"

#include <math.h>

/* ---------------------------------------------------------------- rational vectors */

void ref_vec_init(ref_vec *v)
{
    for (int k = 0; k < 3; k++)
        mpq_init(v->c[k]);
}

void ref_vec_clear(ref_vec *v)
{
    for (int k = 0; k < 3; k++)
        mpq_clear(v->c[k]);
}

void ref_vec_set_d(ref_vec *v, const double x[3])
{
    for (int k = 0; k < 3; k++)
        mpq_set_d(v->c[k], x[k]); /* exact for every finite double */
}

static void vec_sub(ref_vec *r, const ref_vec *a, const ref_vec *b)
{
    for (int k = 0; k < 3; k++)
        mpq_sub(r->c[k], a->c[k], b->c[k]);
}

static void vec_cross(ref_vec *r, const ref_vec *a, const ref_vec *b) /* r must not alias */
{
    mpq_t t;
    mpq_init(t);
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mpq_mul(r->c[k], a->c[i], b->c[j]);
        mpq_mul(t, a->c[j], b->c[i]);
        mpq_sub(r->c[k], r->c[k], t);
    }
    mpq_clear(t);
}

static void vec_dot(mpq_ptr r, const ref_vec *a, const ref_vec *b)
{
    mpq_t t;
    mpq_init(t);
    mpq_mul(r, a->c[0], b->c[0]);
    for (int k = 1; k < 3; k++) {
        mpq_mul(t, a->c[k], b->c[k]);
        mpq_add(r, r, t);
    }
    mpq_clear(t);
}

/* out[k] = in[k] * L with L > 0 the lcm of the denominators: integers with the signs and
 * ratios of in[]. *scale = L. */
static void to_integers(mpz_t *out, mpz_ptr scale, const mpq_srcptr *in, int count)
{
    mpz_set_ui(scale, 1);
    for (int k = 0; k < count; k++)
        mpz_lcm(scale, scale, mpq_denref(in[k]));
    for (int k = 0; k < count; k++) {
        mpz_divexact(out[k], scale, mpq_denref(in[k]));
        mpz_mul(out[k], out[k], mpq_numref(in[k]));
    }
}

/* ---------------------------------------------------------------- points and planes */

void ref_point_init(ref_point *p) { mpz_inits(p->n[0], p->n[1], p->n[2], p->d, NULL); }

void ref_point_clear(ref_point *p) { mpz_clears(p->n[0], p->n[1], p->n[2], p->d, NULL); }

void ref_point_set_vec(ref_point *p, const ref_vec *x)
{
    mpq_srcptr in[3] = {x->c[0], x->c[1], x->c[2]};
    to_integers(p->n, p->d, in, 3);
}

void ref_point_set_d(ref_point *p, const double x[3])
{
    ref_vec v;
    ref_vec_init(&v);
    ref_vec_set_d(&v, x);
    ref_point_set_vec(p, &v);
    ref_vec_clear(&v);
}

void ref_plane_init(ref_plane *p)
{
    ref_vec_init(&p->n);
    ref_vec_init(&p->a);
    mpz_inits(p->h[0], p->h[1], p->h[2], p->h[3], NULL);
}

void ref_plane_clear(ref_plane *p)
{
    ref_vec_clear(&p->n);
    ref_vec_clear(&p->a);
    mpz_clears(p->h[0], p->h[1], p->h[2], p->h[3], NULL);
}

/* h = the integer row of (n, -n.a). */
static void plane_set_row(ref_plane *p)
{
    mpq_t offset;
    mpz_t scale;
    mpq_init(offset);
    mpz_init(scale);
    vec_dot(offset, &p->n, &p->a);
    mpq_neg(offset, offset);
    {
        mpq_srcptr coef[4] = {p->n.c[0], p->n.c[1], p->n.c[2], offset};
        to_integers(p->h, scale, coef, 4);
    }
    mpz_clear(scale);
    mpq_clear(offset);
}

void ref_plane_set(ref_plane *p, const double a[3], const double b[3], const double c[3])
{
    ref_vec ab, ac;
    ref_vec_init(&ab);
    ref_vec_init(&ac);
    ref_vec_set_d(&p->a, a);
    ref_vec_set_d(&ab, b);
    ref_vec_set_d(&ac, c);
    vec_sub(&ab, &ab, &p->a);
    vec_sub(&ac, &ac, &p->a);
    vec_cross(&p->n, &ab, &ac);
    plane_set_row(p);
    ref_vec_clear(&ab);
    ref_vec_clear(&ac);
}

/* ---------------------------------------------------------------- LPI and TPI */

/* x = p + t u where t = n.(a - p) / w, w = n.u != 0. */
static void lpi_point(ref_vec *x, mpq_srcptr w, const ref_vec *p, const ref_vec *u,
                      const ref_plane *pl)
{
    ref_vec ap;
    mpq_t t;
    ref_vec_init(&ap);
    mpq_init(t);
    vec_sub(&ap, &pl->a, p);
    vec_dot(t, &pl->n, &ap);
    mpq_div(t, t, w);
    for (int k = 0; k < 3; k++) {
        mpq_mul(x->c[k], t, u->c[k]);
        mpq_add(x->c[k], x->c[k], p->c[k]);
    }
    mpq_clear(t);
    ref_vec_clear(&ap);
}

/* Line p q meets the plane where n.(p + t u - a) = 0, u = q - p: t = n.(a - p) / n.u. */
bool ref_lpi(ref_vec *x, mpq_ptr w, const double p[3], const double q[3],
             const ref_plane *pl)
{
    ref_vec qp, u;
    bool ok;
    ref_vec_init(&qp);
    ref_vec_init(&u);
    ref_vec_set_d(&qp, p);
    ref_vec_set_d(&u, q);
    vec_sub(&u, &u, &qp);
    vec_dot(w, &pl->n, &u);
    ok = mpq_sgn(w) != 0;
    if (ok)
        lpi_point(x, w, &qp, &u, pl);
    ref_vec_clear(&qp);
    ref_vec_clear(&u);
    return ok;
}

/* Swaps row `col` with the first row at or below it whose entry in column `col` is not
 * 0, negating *det if they differ. False if there is none (the matrix is singular). */
static bool pivot(mpq_t m[3][4], int col, mpq_ptr det)
{
    int piv = col;
    while (piv < 3 && mpq_sgn(m[piv][col]) == 0)
        piv++;
    if (piv == 3)
        return false;
    if (piv != col) {
        for (int j = 0; j < 4; j++)
            mpq_swap(m[piv][j], m[col][j]);
        mpq_neg(det, det);
    }
    return true;
}

/* Forward elimination with row swaps on m = [N | rhs]; false if singular. *det gets the
 * determinant of N (product of the pivots, sign flipped per swap), 0 if singular. */
static bool eliminate(mpq_t m[3][4], mpq_ptr det)
{
    mpq_t f, t;
    bool ok = true;
    mpq_inits(f, t, NULL);
    mpq_set_ui(det, 1, 1);
    for (int col = 0; col < 3 && ok; col++) {
        ok = pivot(m, col, det);
        if (!ok)
            break;
        mpq_mul(det, det, m[col][col]);
        for (int row = col + 1; row < 3; row++) {
            mpq_div(f, m[row][col], m[col][col]);
            for (int j = col; j < 4; j++) {
                mpq_mul(t, f, m[col][j]);
                mpq_sub(m[row][j], m[row][j], t);
            }
        }
    }
    if (!ok)
        mpq_set_ui(det, 0, 1);
    mpq_clears(f, t, NULL);
    return ok;
}

/* x from the upper-triangular system left by eliminate(). */
static void back_substitute(ref_vec *x, mpq_t m[3][4])
{
    mpq_t t;
    mpq_init(t);
    for (int row = 2; row >= 0; row--) {
        mpq_set(x->c[row], m[row][3]);
        for (int j = row + 1; j < 3; j++) {
            mpq_mul(t, m[row][j], x->c[j]);
            mpq_sub(x->c[row], x->c[row], t);
        }
        mpq_div(x->c[row], x->c[row], m[row][row]);
    }
    mpq_clear(t);
}

/* The point on three planes: solve n_k . x = n_k . a_k. */
bool ref_tpi(ref_vec *x, mpq_ptr det, const ref_plane *p0, const ref_plane *p1,
             const ref_plane *p2)
{
    const ref_plane *pl[3] = {p0, p1, p2};
    mpq_t m[3][4];
    bool ok;
    for (int r = 0; r < 3; r++) {
        for (int j = 0; j < 4; j++)
            mpq_init(m[r][j]);
        for (int j = 0; j < 3; j++)
            mpq_set(m[r][j], pl[r]->n.c[j]);
        vec_dot(m[r][3], &pl[r]->n, &pl[r]->a);
    }
    ok = eliminate(m, det);
    if (ok)
        back_substitute(x, m);
    for (int r = 0; r < 3; r++)
        for (int j = 0; j < 4; j++)
            mpq_clear(m[r][j]);
    return ok;
}

/* ---------------------------------------------------------------- predicates */

/* r = a[k] * b.d - b[k] * a.d: the k-th coordinate of a - b times a.d * b.d > 0. */
static void zdiff(mpz_ptr r, const ref_point *a, const ref_point *b, int k)
{
    mpz_mul(r, a->n[k], b->d);
    mpz_submul(r, b->n[k], a->d);
}

int ref_orient3d(const ref_point *p, const ref_plane *pl)
{
    mpz_t s;
    int r;
    mpz_init(s);
    mpz_mul(s, pl->h[3], p->d);
    for (int k = 0; k < 3; k++)
        mpz_addmul(s, pl->h[k], p->n[k]);
    r = mpz_sgn(s);
    mpz_clear(s);
    return r;
}

int ref_compare_coord(const ref_point *a, const ref_point *b, int axis)
{
    mpz_t s;
    int r;
    mpz_init(s);
    zdiff(s, a, b, axis);
    r = mpz_sgn(s);
    mpz_clear(s);
    return r;
}

int ref_compare_lex(const ref_point *a, const ref_point *b)
{
    for (int k = 0; k < 3; k++) {
        int c = ref_compare_coord(a, b, k);
        if (c)
            return c;
    }
    return 0;
}

int ref_orient2d(const ref_point *p, const ref_point *q, const ref_point *r, int axis)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3, s;
    mpz_t ui, uj, vi, vj;
    mpz_inits(ui, uj, vi, vj, NULL);
    zdiff(ui, q, p, i);
    zdiff(uj, q, p, j);
    zdiff(vi, r, p, i);
    zdiff(vj, r, p, j);
    mpz_mul(ui, ui, vj);
    mpz_submul(ui, uj, vi);
    s = mpz_sgn(ui);
    mpz_clears(ui, uj, vi, vj, NULL);
    return s;
}

/* sign(r0 . (r1 x r2)) */
static int det3_sign(mpz_t r[3][3])
{
    mpz_t t, det;
    int sign;
    mpz_inits(t, det, NULL);
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mpz_mul(t, r[1][i], r[2][j]);
        mpz_submul(t, r[1][j], r[2][i]);
        mpz_addmul(det, t, r[0][k]);
    }
    sign = mpz_sgn(det);
    mpz_clears(t, det, NULL);
    return sign;
}

/* Row i of det[b - a; c - a; d - a] is (v_i - a) times a.d * v_i.d > 0, which leaves
 * the determinant's sign alone: integers throughout, no rationals to reduce. */
int ref_orient3d_points(const ref_point *a, const ref_point *b, const ref_point *c,
                        const ref_point *d)
{
    const ref_point *v[3] = {b, c, d};
    mpz_t r[3][3];
    int sign;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            mpz_init(r[i][k]);
            zdiff(r[i][k], v[i], a, k);
        }
    sign = det3_sign(r);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            mpz_clear(r[i][k]);
    return sign;
}

/* ---------------------------------------------------------------- lines */

void ref_line_init(ref_line *l) { mpz_inits(l->dir[0], l->dir[1], l->dir[2], NULL); }

void ref_line_clear(ref_line *l) { mpz_clears(l->dir[0], l->dir[1], l->dir[2], NULL); }

static bool line_exists(const ref_line *l)
{
    return mpz_sgn(l->dir[0]) || mpz_sgn(l->dir[1]) || mpz_sgn(l->dir[2]);
}

/* dir = n1 x n2 times a positive integer (the rows h are positive multiples of the
 * normals). */
bool ref_line_set_planes(ref_line *l, const ref_plane *p1, const ref_plane *p2)
{
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mpz_mul(l->dir[k], p1->h[i], p2->h[j]);
        mpz_submul(l->dir[k], p1->h[j], p2->h[i]);
    }
    return line_exists(l);
}

/* dir = (l1 - l0) l0.d l1.d. */
bool ref_line_set_points(ref_line *l, const ref_point *l0, const ref_point *l1)
{
    for (int k = 0; k < 3; k++)
        zdiff(l->dir[k], l1, l0, k);
    return line_exists(l);
}

bool ref_on_planes(const ref_point *p, const ref_plane *p1, const ref_plane *p2)
{
    return ref_orient3d(p, p1) == 0 && ref_orient3d(p, p2) == 0;
}

/* Collinear with l0 and l1 in all three projections. */
bool ref_on_line(const ref_point *p, const ref_point *l0, const ref_point *l1)
{
    return ref_orient2d(l0, l1, p, 0) == 0 && ref_orient2d(l0, l1, p, 1) == 0 &&
           ref_orient2d(l0, l1, p, 2) == 0;
}

int ref_order_on_line(const ref_point *a, const ref_point *b, const ref_line *l)
{
    mpz_t s, t;
    int r;
    mpz_inits(s, t, NULL);
    for (int k = 0; k < 3; k++) {
        zdiff(t, a, b, k);
        mpz_addmul(s, t, l->dir[k]);
    }
    r = mpz_sgn(s);
    mpz_clears(s, t, NULL);
    return r;
}

int ref_line_direction_sign(const ref_plane *p1, const ref_plane *p2, int axis)
{
    ref_line l;
    int r;
    ref_line_init(&l);
    ref_line_set_planes(&l, p1, p2);
    r = mpz_sgn(l.dir[axis]);
    ref_line_clear(&l);
    return r;
}

/* ---------------------------------------------------------------- doubles vs rationals */

bool ref_within(double v, double e, mpq_srcptr x)
{
    mpq_t d, q;
    bool ok;
    mpq_inits(d, q, NULL);
    mpq_set_d(d, v);
    mpq_sub(d, d, x);
    mpq_abs(d, d);
    mpq_set_d(q, e);
    ok = mpq_cmp(d, q) <= 0;
    mpq_clears(d, q, NULL);
    return ok;
}

int ref_cmp_d(double b, mpq_srcptr x)
{
    mpq_t q;
    int c;
    mpq_init(q);
    mpq_set_d(q, b);
    c = mpq_cmp(q, x);
    mpq_clear(q);
    return c > 0 ? 1 : c < 0 ? -1 : 0;
}

double ref_gap(mpq_srcptr x, double b)
{
    mpq_t d;
    double g;
    if (!isfinite(b))
        return NAN;
    mpq_init(d);
    mpq_set_d(d, b);
    mpq_sub(d, x, d);
    g = mpq_get_d(d);
    mpq_clear(d);
    return g;
}

/* sign(x - (r + s) / 2): where x lies against the midpoint of r and s. */
static int cmp_midpoint(mpq_srcptr x, double r, double s)
{
    mpq_t m, t;
    int c;
    mpq_inits(m, t, NULL);
    mpq_set_d(m, r);
    mpq_set_d(t, s);
    mpq_add(m, m, t);
    mpq_div_2exp(m, m, 1);
    c = mpq_cmp(x, m);
    mpq_clears(m, t, NULL);
    return c;
}

bool ref_is_nearest_double(double r, mpq_srcptr x)
{
    double below, above;
    if (!isfinite(r))
        return false;
    below = nextafter(r, -INFINITY);
    above = nextafter(r, INFINITY);
    return (!isfinite(below) || cmp_midpoint(x, r, below) >= 0) &&
           (!isfinite(above) || cmp_midpoint(x, r, above) <= 0);
}
