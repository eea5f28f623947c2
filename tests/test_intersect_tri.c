/*
 * Exact triangle-triangle intersection against a rational reference written from the
 * definitions: each triangle is cut by the other's plane (edge parameters in GMP
 * rationals), the two sections are projected on the common line's direction n1 x n2 and
 * overlapped; coplanar pairs are clipped polygon-by-half-plane and the area checked.
 * The kernel's result points are converted to exact coordinates from their definitions
 * and compared with the reference's ends.
 */
#include "testlib.h"
#include "exact/tri_tri.h"

#include <gmp.h>
#include <math.h>
#include <string.h>

static uint64_t rng = 0xd1b54a32d192ed03ULL;
static uint64_t next_random(void)
{
    return test_xorshift(&rng);
}

typedef struct qvec {
    mpq_t c[3];
} qvec;

static void qv_init(qvec *v) { mpq_inits(v->c[0], v->c[1], v->c[2], NULL); }
static void qv_clear(qvec *v) { mpq_clears(v->c[0], v->c[1], v->c[2], NULL); }
static void qv_set_d(qvec *v, const double *x)
{
    for (int k = 0; k < 3; k++)
        mpq_set_d(v->c[k], x[k]);
}
static void qv_sub(qvec *r, const qvec *a, const qvec *b)
{
    for (int k = 0; k < 3; k++)
        mpq_sub(r->c[k], a->c[k], b->c[k]);
}
static void qv_dot(mpq_t r, const qvec *a, const qvec *b)
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
static void qv_cross(qvec *r, const qvec *a, const qvec *b)
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
/* r = a + t (b - a) */
static void qv_lerp(qvec *r, const qvec *a, const qvec *b, mpq_t t)
{
    mpq_t d;
    mpq_init(d);
    for (int k = 0; k < 3; k++) {
        mpq_sub(d, b->c[k], a->c[k]);
        mpq_mul(d, d, t);
        mpq_add(r->c[k], a->c[k], d);
    }
    mpq_clear(d);
}
static bool qv_equal(const qvec *a, const qvec *b)
{
    return mpq_equal(a->c[0], b->c[0]) && mpq_equal(a->c[1], b->c[1]) &&
           mpq_equal(a->c[2], b->c[2]);
}

/* Exact coordinates of a kernel point from its definition. */
static void point_value(qvec *r, const mci_point *p)
{
    qvec l0, l1, a, b, c, e1, e2, n, d;
    mpq_t num, den;
    if (p->kind == MCI_POINT_EXPLICIT) {
        qv_set_d(r, p->v[0]);
        return;
    }
    CHECK(p->kind == MCI_POINT_LPI);
    qv_init(&l0), qv_init(&l1), qv_init(&a), qv_init(&b), qv_init(&c);
    qv_init(&e1), qv_init(&e2), qv_init(&n), qv_init(&d);
    mpq_inits(num, den, NULL);
    qv_set_d(&l0, p->v[0]), qv_set_d(&l1, p->v[1]);
    qv_set_d(&a, p->v[2]), qv_set_d(&b, p->v[3]), qv_set_d(&c, p->v[4]);
    qv_sub(&e1, &b, &a), qv_sub(&e2, &c, &a), qv_cross(&n, &e1, &e2);
    qv_sub(&d, &a, &l0), qv_dot(num, &n, &d);
    qv_sub(&d, &l1, &l0), qv_dot(den, &n, &d);
    mpq_div(num, num, den);
    qv_lerp(r, &l0, &l1, num);
    qv_clear(&l0), qv_clear(&l1), qv_clear(&a), qv_clear(&b), qv_clear(&c);
    qv_clear(&e1), qv_clear(&e2), qv_clear(&n), qv_clear(&d);
    mpq_clears(num, den, NULL);
}

typedef struct reference {
    mci_tt_kind kind;
    bool overlap;
    qvec end[2];
} reference;

/* Section of triangle v by the plane through `a` with normal n: up to two points. */
static int section(qvec out[2], qvec v[3], const qvec *n, const qvec *a)
{
    mpq_t side[3], t, den;
    qvec d;
    int count = 0;
    qv_init(&d);
    mpq_inits(side[0], side[1], side[2], t, den, NULL);
    for (int i = 0; i < 3; i++) {
        qv_sub(&d, &v[i], a);
        qv_dot(side[i], n, &d);
    }
    for (int i = 0; i < 3 && count < 2; i++) {
        int j = (i + 1) % 3;
        if (mpq_sgn(side[i]) == 0) {
            for (int k = 0; k < 3; k++)
                mpq_set(out[count].c[k], v[i].c[k]);
            count++;
        }
        if (count < 2 && mpq_sgn(side[i]) * mpq_sgn(side[j]) < 0) {
            mpq_sub(den, side[i], side[j]);
            mpq_div(t, side[i], den);
            qv_lerp(&out[count++], &v[i], &v[j], t);
        }
    }
    qv_clear(&d);
    mpq_clears(side[0], side[1], side[2], t, den, NULL);
    return count;
}

static int sides_class(qvec v[3], const qvec *n, const qvec *a)
{
    /* 1: strictly one side, 0: all on the plane, 2: otherwise */
    mpq_t s;
    qvec d;
    int pos = 0, neg = 0;
    mpq_init(s);
    qv_init(&d);
    for (int i = 0; i < 3; i++) {
        qv_sub(&d, &v[i], a);
        qv_dot(s, n, &d);
        pos += mpq_sgn(s) > 0;
        neg += mpq_sgn(s) < 0;
    }
    mpq_clear(s);
    qv_clear(&d);
    return pos == 3 || neg == 3 ? 1 : pos + neg == 0 ? 0 : 2;
}

/* Positive area of t2 clipped by t1's three closed inner half-planes (same plane). */
static bool coplanar_overlap(qvec t1[3], qvec t2[3], const qvec *n)
{
    qvec poly[2][9], e, d, c;
    mpq_t f[9], t, den, area;
    int count[2] = {3, 0}, cur = 0;
    bool result;
    qv_init(&e), qv_init(&d), qv_init(&c);
    mpq_inits(t, den, area, NULL);
    for (int i = 0; i < 9; i++) {
        qv_init(&poly[0][i]), qv_init(&poly[1][i]);
        mpq_init(f[i]);
    }
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            mpq_set(poly[0][i].c[k], t2[i].c[k]);
    for (int edge = 0; edge < 3 && count[cur] > 0; edge++) {
        int nxt = 1 - cur, m = 0;
        qv_sub(&e, &t1[(edge + 1) % 3], &t1[edge]);
        for (int i = 0; i < count[cur]; i++) {
            qv_sub(&d, &poly[cur][i], &t1[edge]);
            qv_cross(&c, &e, &d);
            qv_dot(f[i], &c, n);
        }
        for (int i = 0; i < count[cur]; i++) {
            int j = (i + 1) % count[cur];
            if (mpq_sgn(f[i]) >= 0) {
                for (int k = 0; k < 3; k++)
                    mpq_set(poly[nxt][m].c[k], poly[cur][i].c[k]);
                m++;
            }
            if (mpq_sgn(f[i]) * mpq_sgn(f[j]) < 0) {
                mpq_sub(den, f[i], f[j]);
                mpq_div(t, f[i], den);
                qv_lerp(&poly[nxt][m++], &poly[cur][i], &poly[cur][j], t);
            }
        }
        count[nxt] = m;
        cur = nxt;
    }
    for (int i = 0; i < count[cur]; i++) {
        qv_cross(&c, &poly[cur][i], &poly[cur][(i + 1) % count[cur]]);
        qv_dot(t, &c, n);
        mpq_add(area, area, t);
    }
    result = count[cur] >= 3 && mpq_sgn(area) != 0;
    for (int i = 0; i < 9; i++) {
        qv_clear(&poly[0][i]), qv_clear(&poly[1][i]);
        mpq_clear(f[i]);
    }
    qv_clear(&e), qv_clear(&d), qv_clear(&c);
    mpq_clears(t, den, area, NULL);
    return result;
}

/* Index of the point with the smallest (want_max: largest) projection on dir. */
static int extreme(qvec *pts, int n, const qvec *dir, bool want_max, mpq_t value)
{
    mpq_t v;
    int best = 0;
    mpq_init(v);
    qv_dot(value, dir, &pts[0]);
    for (int i = 1; i < n; i++) {
        qv_dot(v, dir, &pts[i]);
        if (want_max ? mpq_cmp(v, value) > 0 : mpq_cmp(v, value) < 0) {
            mpq_set(value, v);
            best = i;
        }
    }
    mpq_clear(v);
    return best;
}

static void reference_intersection(const double *t1[3], const double *t2[3], reference *r)
{
    qvec v1[3], v2[3], n1, n2, e1, e2, dir, s1[2], s2[2];
    mpq_t lo1, hi1, lo2, hi2;
    int c1, c2;
    for (int i = 0; i < 3; i++) {
        qv_init(&v1[i]), qv_init(&v2[i]);
        qv_set_d(&v1[i], t1[i]), qv_set_d(&v2[i], t2[i]);
    }
    qv_init(&n1), qv_init(&n2), qv_init(&e1), qv_init(&e2), qv_init(&dir);
    for (int i = 0; i < 2; i++)
        qv_init(&s1[i]), qv_init(&s2[i]);
    mpq_inits(lo1, hi1, lo2, hi2, NULL);
    qv_sub(&e1, &v1[1], &v1[0]), qv_sub(&e2, &v1[2], &v1[0]), qv_cross(&n1, &e1, &e2);
    qv_sub(&e1, &v2[1], &v2[0]), qv_sub(&e2, &v2[2], &v2[0]), qv_cross(&n2, &e1, &e2);
    c1 = sides_class(v1, &n2, &v2[0]);
    c2 = sides_class(v2, &n1, &v1[0]);
    r->kind = MCI_TT_DISJOINT;
    r->overlap = false;
    if (c1 == 1 || c2 == 1) {
        /* disjoint */
    } else if (c1 == 0) {
        r->kind = MCI_TT_COPLANAR;
        r->overlap = coplanar_overlap(v1, v2, &n1);
    } else {
        int n1c = section(s1, v1, &n2, &v2[0]), n2c = section(s2, v2, &n1, &v1[0]);
        qv_cross(&dir, &n1, &n2);
        int a1 = extreme(s1, n1c, &dir, false, lo1), b1 = extreme(s1, n1c, &dir, true, hi1);
        int a2 = extreme(s2, n2c, &dir, false, lo2), b2 = extreme(s2, n2c, &dir, true, hi2);
        bool first_lo = mpq_cmp(lo1, lo2) >= 0, first_hi = mpq_cmp(hi1, hi2) <= 0;
        int cmp = mpq_cmp(first_lo ? lo1 : lo2, first_hi ? hi1 : hi2);
        if (cmp <= 0) {
            r->kind = cmp == 0 ? MCI_TT_POINT : MCI_TT_SEGMENT;
            for (int k = 0; k < 3; k++) {
                mpq_set(r->end[0].c[k], first_lo ? s1[a1].c[k] : s2[a2].c[k]);
                mpq_set(r->end[1].c[k], first_hi ? s1[b1].c[k] : s2[b2].c[k]);
            }
        }
    }
    for (int i = 0; i < 3; i++)
        qv_clear(&v1[i]), qv_clear(&v2[i]);
    qv_clear(&n1), qv_clear(&n2), qv_clear(&e1), qv_clear(&e2), qv_clear(&dir);
    for (int i = 0; i < 2; i++)
        qv_clear(&s1[i]), qv_clear(&s2[i]);
    mpq_clears(lo1, hi1, lo2, hi2, NULL);
}

static bool nondegenerate(const double *v[3])
{
    mci_plane p;
    int sign;
    mci_plane_init(&p, v[0], v[1], v[2]);
    return mci_plane_projection_axis(&p, &sign) >= 0;
}

static long kind_counts[4];
static long coplanar_overlaps;
static long strict_inside_ends, strict_tied_ends;

/* Every corner of t strictly off the plane. */
static bool strictly_off(const double *t[3], const mci_plane *plane)
{
    return mci_orient3d_vertex(t[0], plane) != 0 && mci_orient3d_vertex(t[1], plane) != 0 &&
           mci_orient3d_vertex(t[2], plane) != 0;
}

/* strict_ends (the arrangements skip locating such ends): in a segment between
 * triangles whose corners are all strictly off the other's plane, end e is an edge
 * line of one triangle, strictly inside that edge; it is strictly inside the other
 * triangle exactly when its bit is set. */
static void check_strict_ends(const mci_plane *p1, const mci_plane *p2, const double *t1[3],
                              const double *t2[3], const mci_tt_result *got, const char *what)
{
    bool strict = got->kind == MCI_TT_SEGMENT && strictly_off(t1, p2) && strictly_off(t2, p1);
    CHECK_MSG(strict || got->strict_ends == 0, "%s: strict_ends set on a non-strict pair", what);
    for (int e = 0; strict && e < 2; e++) {
        const mci_point *x = &got->end[e];
        bool of_t1 = (x->v[0] == t1[0] || x->v[0] == t1[1] || x->v[0] == t1[2]) &&
                     (x->v[1] == t1[0] || x->v[1] == t1[1] || x->v[1] == t1[2]);
        const mci_plane *own = of_t1 ? p1 : p2, *other = of_t1 ? p2 : p1;
        int which;
        bool inside = mci_point_in_triangle(x, other, &which) == MCI_INSIDE;
        CHECK_MSG(x->kind == MCI_POINT_LPI && mci_point_in_triangle(x, own, &which) == MCI_ON_EDGE,
                  "%s: strict end %d is not inside an edge of its triangle", what, e);
        CHECK_MSG(inside == ((got->strict_ends >> e) & 1), "%s: strict end %d: inside %d, bit %d",
                  what, e, inside, (got->strict_ends >> e) & 1);
        strict_inside_ends += inside;
        strict_tied_ends += !inside;
    }
}

static bool same_fv(mci_fv a, mci_fv b)
{
    return a.v == b.v && a.e == b.e;
}

static bool same_built_point(const mci_point *x, const mci_point *y)
{
    bool same = x->exact_axes == y->exact_axes && x->w_sign == y->w_sign &&
                same_fv(x->w, y->w) && x->r == y->r;
    for (int k = 0; k < 3; k++)
        same = same && same_fv(x->y[k], y->y[k]) && x->c[k] == y->c[k];
    return same;
}

/* mci_triangle_intersection_defined gives the same result with the strict overlaps'
 * ends as definitions only (kind and vertices), and every other result whole. */
static long defined_only_results;

static void check_defined(const mci_plane *p1, const mci_plane *p2, const mci_tt_result *built,
                          const char *what)
{
    mci_tt_result got;
    int ends = built->kind == MCI_TT_SEGMENT ? 2 : built->kind == MCI_TT_POINT ? 1 : 0;
    mci_triangle_intersection_defined(p1, p2, &got);
    CHECK_MSG(got.kind == built->kind && got.overlap == built->overlap &&
              got.along_edge[0] == built->along_edge[0] &&
              got.along_edge[1] == built->along_edge[1] &&
              got.strict_ends == built->strict_ends,
              "%s: the defined-only result differs", what);
    CHECK_MSG(!got.defined_only || got.kind == MCI_TT_SEGMENT || got.kind == MCI_TT_POINT,
              "%s: defined only, but no end", what);
    defined_only_results += got.defined_only;
    for (int e = 0; e < ends && got.kind == built->kind; e++) {
        const mci_point *x = &got.end[e], *y = &built->end[e];
        int n = mci_point_vertex_count(y);
        CHECK_MSG(x->kind == y->kind && memcmp(x->v, y->v, (size_t)n * sizeof x->v[0]) == 0,
                  "%s: end %d is defined differently", what, e);
        if (!got.defined_only)
            CHECK_MSG(same_built_point(x, y), "%s: end %d is built differently", what, e);
    }
}

static void check_pair(const double *t1[3], const double *t2[3], const char *what)
{
    mci_plane p1, p2;
    mci_tt_result got;
    reference want;
    qvec value;
    if (!nondegenerate(t1) || !nondegenerate(t2))
        return;
    qv_init(&want.end[0]), qv_init(&want.end[1]), qv_init(&value);
    mci_plane_init(&p1, t1[0], t1[1], t1[2]);
    mci_plane_init(&p2, t2[0], t2[1], t2[2]);
    mci_triangle_intersection(&p1, &p2, &got);
    reference_intersection(t1, t2, &want);
    kind_counts[want.kind]++;
    coplanar_overlaps += want.overlap;
    CHECK_MSG(got.kind == want.kind, "%s: kind %d, want %d", what, got.kind, want.kind);
    if (got.kind == want.kind && want.kind == MCI_TT_COPLANAR)
        CHECK_MSG(got.overlap == want.overlap, "%s: coplanar overlap %d", what, got.overlap);
    check_strict_ends(&p1, &p2, t1, t2, &got, what);
    check_defined(&p1, &p2, &got, what);
    for (int e = 0; got.kind == want.kind && e < (int)want.kind && e < 2; e++) {
        if (want.kind == MCI_TT_COPLANAR)
            break;
        point_value(&value, &got.end[e]);
        CHECK_MSG(qv_equal(&value, &want.end[e]), "%s: end %d differs", what, e);
    }
    qv_clear(&want.end[0]), qv_clear(&want.end[1]), qv_clear(&value);
}

static double small_int(void)
{
    return (double)((int)(next_random() % 5) - 2);
}

static double unit(void)
{
    return (double)(next_random() >> 11) / 9007199254740992.0 * 2 - 1;
}

TEST(random_and_degenerate_pairs_match_the_reference)
{
    for (int n = 0; n < 60000; n++) {
        double a[6][3];
        const double *t1[3] = {a[0], a[1], a[2]}, *t2[3] = {a[3], a[4], a[5]};
        int regime = n % 4;
        for (int i = 0; i < 6; i++)
            for (int k = 0; k < 3; k++)
                a[i][k] = regime == 3 ? unit() : small_int();
        if (regime == 1) /* share a vertex (same storage, as in a mesh) */
            t2[0] = t1[next_random() % 3];
        if (regime == 2) { /* share an edge */
            int e = (int)(next_random() % 3);
            t2[0] = t1[(e + 1) % 3];
            t2[1] = t1[e];
        }
        check_pair(t1, t2, regime == 3 ? "unit" : regime == 2 ? "shared edge" : "small ints");
    }
    printf("kinds: disjoint %ld, point %ld, segment %ld, coplanar %ld (%ld overlapping)\n",
           kind_counts[0], kind_counts[1], kind_counts[2], kind_counts[3], coplanar_overlaps);
    printf("strict segment ends: %ld inside the other triangle, %ld on its boundary\n",
           strict_inside_ends, strict_tied_ends);
    CHECK(kind_counts[1] > 100 && kind_counts[2] > 100 && kind_counts[3] > 100);
    CHECK(coplanar_overlaps > 50);
    CHECK(strict_inside_ends > 1000 && strict_tied_ends > 100);
    printf("defined only: %ld results\n", defined_only_results);
    CHECK(defined_only_results > 1000);
}

TEST(shared_edge_crossing_is_defined_identically)
{
    /* Faces (a, b, c) and (b, a, d) share edge ab; a third face crosses that edge. The
     * crossing point must have the same definition from both faces. */
    double a[3] = {0, 0, 0}, b[3] = {2, 0, 0}, c[3] = {1, 1, 0.5}, d[3] = {1, -1, 0.5};
    double p[3] = {1, -2, -1}, q[3] = {1, 2, -1}, r[3] = {1, 0, 3};
    mci_plane f1, f2, cut;
    mci_tt_result x1, x2;
    mci_plane_init(&f1, a, b, c);
    mci_plane_init(&f2, b, a, d);
    mci_plane_init(&cut, p, q, r);
    mci_triangle_intersection(&f1, &cut, &x1);
    mci_triangle_intersection(&f2, &cut, &x2);
    CHECK(x1.kind == MCI_TT_SEGMENT && x2.kind == MCI_TT_SEGMENT);
    bool found = false;
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            if (x1.end[i].kind == MCI_POINT_LPI && x2.end[j].kind == MCI_POINT_LPI &&
                memcmp(x1.end[i].v, x2.end[j].v, 5 * sizeof x1.end[i].v[0]) == 0)
                found = true;
    CHECK_MSG(found, "the edge crossing is not defined by the same vertices from both faces");
}

int main(void)
{
    RUN(random_and_degenerate_pairs_match_the_reference);
    RUN(shared_edge_crossing_is_defined_identically);
    return test_summary();
}
