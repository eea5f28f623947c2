/*
 * Tests of the exact plane-based kernel (src/exact/kernel.h) against an independent exact
 * reference written here with GMP from the geometric definitions: an LPI by solving
 * n.(p + t(q - p) - a) = 0 for t, a TPI by rational Gaussian elimination, and each
 * predicate as the sign of its defining expression on exact coordinates. The reference
 * shares no formula with the kernel (no Cramer numerators, no cached approximations), so
 * agreement means that both are right, not that both copy one mistake.
 *
 * Every case checks three things: the combined predicate equals the reference; the exact
 * stage equals the reference (on every case, not only where the filter gives up); the
 * filtered stage returns MCI_UNCERTAIN or the reference sign. Constructors' return
 * values and the certified error bounds of the cached normals and offsets
 * (|v - exact| <= e) are checked as well, since every filter relies on them.
 *
 * Cases come in scenarios: a few input vertices, planes through them, explicit, LPI and
 * TPI points, and the predicates over all (or sampled) combinations of those, so every
 * kind of point appears in every predicate slot. Scenario classes:
 *   random/REGIME   vertices drawn from one coordinate regime (draw_coord)
 *   nearpar/REGIME  nearly parallel planes and lines (copies nudged by a few ulps)
 *   same, line, par adversarial scenarios on exact lattices: one point defined in many
 *                   ways; points on a common line; exactly parallel and singular
 *                   configurations. Each is followed by "+ulp" runs with an input
 *                   coordinate moved by one ulp.
 * MCSG_TEST_SCALE (default 1) multiplies the number of scenarios; MCSG_TEST_SEED sets the
 * random seed. The tables at the end count the cases and the filter's decisions.
 */
#include "exact/big.h"
#include "exact/kernel.h"
#include "testlib.h"

#include <float.h>
#include <gmp.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAXV        48
#define MAXPL       16
#define MAXPT       28
#define MAX_CLASSES 40
#define MAX_PRINTED 12     /* mismatches printed in full; all are counted */
#define NONE        (-100) /* "this stage does not exist" in a result triple */

/* ---------------------------------------------------------------- random numbers */

static uint64_t rng_state = 0x5eed2024u;

static uint64_t rng_next(void) /* splitmix64 */
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double rng_unit(void) { return (double)(rng_next() >> 11) * 0x1p-53; }

static int rng_int(int lo, int hi) /* inclusive */
{
    return lo + (int)(rng_next() % (uint64_t)(hi - lo + 1));
}

static bool rng_chance(double p) { return rng_unit() < p; }

static double rng_sign(void) { return (rng_next() & 1) ? -1.0 : 1.0; }

/* ---------------------------------------------------------------- coordinate regimes */

enum { R_UNIT, R_INT, R_EXP, R_MIX, R_FAR, R_FARGRID, R_SCALES, R_BITS, R_COUNT };
static const char *const regime_names[R_COUNT] = {
    "unit", "smallint", "exp", "mix", "far", "fargrid", "scales", "bits"};

/* The "bits" regime's integer width for the current scenario (set per scenario). */
static int bits_width = 1;

/* A b-bit integer times 2^-20, often at the extremes +-(2^b - 1) and +-2^(b-1): the
 * exact stage's 128-bit path is taken when a degree bound proves the polynomial fits,
 * and widths from 1 to 40 bits (half of them up to 8, where the degree-20 predicates
 * change paths) put every predicate on both sides of that bound, with the largest
 * intermediates it admits. */
static double draw_bits(void)
{
    int64_t top = ((int64_t)1 << bits_width) - 1, x;
    switch (rng_int(0, 3)) {
    case 0:
        x = top;
        break;
    case 1:
        x = (int64_t)1 << (bits_width - 1);
        break;
    default:
        x = (int64_t)(rng_unit() * (double)(top + 1));
        break;
    }
    return rng_sign() * ldexp((double)x, -20);
}

/* One coordinate. smallint and fargrid make exact coplanarity frequent; exp spans the
 * whole double range (subnormals included); mix puts 1e-300, 1e300, 3.4e38 and 1e-3 in
 * one case; far clusters points 1e6 from the origin; bits: see draw_bits. */
static double draw_coord(int regime)
{
    static const double mix[] = {0, 1e-300, 1e300, 3.4e38, 1e-3, 1};
    switch (regime) {
    case R_UNIT:
        return 2 * rng_unit() - 1;
    case R_INT:
        return rng_int(-6, 6);
    case R_EXP:
        return rng_chance(0.03) ? 0
                                : rng_sign() * ldexp(1 + rng_unit(), rng_int(-1074, 1023));
    case R_MIX:
        return rng_sign() * mix[rng_int(0, 5)] * (rng_chance(0.5) ? 1 : 1 + rng_unit());
    case R_FAR:
        return 1e6 + (2 * rng_unit() - 1) * 1e-3;
    case R_FARGRID:
        return 1e6 + rng_int(-4, 4) * 0x1p-30;
    default: /* R_BITS */
        return draw_bits();
    }
}

/* A vertex. "scales" mixes a 50-unit part with coordinates like 1e-17 that should have
 * been 0, per vertex. */
static void draw_vertex(int regime, double out[3])
{
    static const double scales[] = {50, 1e-17, 1};
    double s = scales[rng_int(0, 2)];
    for (int k = 0; k < 3; k++) {
        if (regime != R_SCALES)
            out[k] = draw_coord(regime);
        else
            out[k] = rng_chance(0.1) ? 0 : s * (2 * rng_unit() - 1);
    }
}

/* x moved by n ulps in a random direction (stays finite). */
static double nudge(double x, int n)
{
    double dir = rng_chance(0.5) ? INFINITY : -INFINITY;
    for (int i = 0; i < n; i++) {
        double y = nextafter(x, dir);
        if (!isfinite(y))
            break;
        x = y;
    }
    return x;
}

/* ---------------------------------------------------------------- scenarios */

typedef struct point_def {
    mci_point_kind kind;
    int v[2];  /* explicit: v[0]; LPI: line v[0], v[1] */
    int pl[3]; /* LPI: plane pl[0]; TPI: pl[0..2] */
} point_def;

typedef struct scenario {
    int cls; /* class index (class_id) */
    int nv, npl, npt;
    double v[MAXV][3];
    int plv[MAXPL][3];
    point_def pt[MAXPT];
    /* Pairs of planes through a common line and pairs of vertices on that line: the
     * order_on_plane_line / order_on_edge_line queries (run where the reference confirms
     * that both points lie on the line). */
    int nlp, line_planes[6][2];
    int nle, line_edges[4][2];
    /* The generator's claim, checked against the reference before the kernel is trusted
     * with it: the points group[] lie on all planes onpl[] (and are all equal if
     * group_equal). Cleared in perturbed copies. */
    int ngroup, group[MAXPT];
    int nonpl, onpl[MAXPL];
    bool group_equal;
} scenario;

static int sc_vertex(scenario *s, const double x[3])
{
    if (s->nv >= MAXV)
        abort();
    memcpy(s->v[s->nv], x, sizeof s->v[0]);
    return s->nv++;
}

static int sc_plane(scenario *s, int a, int b, int c)
{
    if (s->npl >= MAXPL)
        abort();
    s->plv[s->npl][0] = a;
    s->plv[s->npl][1] = b;
    s->plv[s->npl][2] = c;
    return s->npl++;
}

/* A plane through a, b, c in a random one of its three rotations (same orientation). */
static int sc_plane_rotated(scenario *s, int a, int b, int c)
{
    int r = rng_int(0, 2), t[3] = {a, b, c};
    return sc_plane(s, t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
}

static int sc_point(scenario *s, mci_point_kind kind, int v0, int v1, int p0, int p1,
                    int p2)
{
    if (s->npt >= MAXPT)
        abort();
    s->pt[s->npt] = (point_def){kind, {v0, v1}, {p0, p1, p2}};
    return s->npt++;
}

static int sc_explicit(scenario *s, int v)
{
    return sc_point(s, MCI_POINT_EXPLICIT, v, v, 0, 0, 0);
}

static int sc_lpi(scenario *s, int l0, int l1, int pl)
{
    return sc_point(s, MCI_POINT_LPI, l0, l1, pl, pl, pl);
}

static int sc_tpi(scenario *s, int p0, int p1, int p2)
{
    return sc_point(s, MCI_POINT_TPI, 0, 0, p0, p1, p2);
}

static void sc_line_planes(scenario *s, int p0, int p1)
{
    s->line_planes[s->nlp][0] = p0;
    s->line_planes[s->nlp++][1] = p1;
}

static void sc_line_edge(scenario *s, int v0, int v1)
{
    s->line_edges[s->nle][0] = v0;
    s->line_edges[s->nle++][1] = v1;
}

/* ---------------------------------------------------------------- classes and counts */

enum {
    PR_ORIENT3D,
    PR_CMP,
    PR_LEX,
    PR_EQ,
    PR_ORIENT2D,
    PR_LINEDIR,
    PR_ORDER_PL,
    PR_ORDER_EDGE,
    PR_LPI,
    PR_TPI,
    PR_BOUNDS,
    PR_COUNT
};
static const char *const pred_names[PR_COUNT] = {
    "orient3d",  "compare_coord", "compare_lex",    "points_equal",
    "orient2d",  "line_dir_sign", "order_plane_ln", "order_edge_ln",
    "point_lpi", "point_tpi",     "cached_bounds"};

typedef struct pstat {
    long calls, zero;   /* cases, and those whose reference result is 0 */
    long filt, decided; /* cases with a filtered stage, and those it decided */
    long decided_zero;  /* ... decided although the reference is 0 */
    long mismatches;
} pstat;

static pstat stats[MAX_CLASSES][PR_COUNT];
static char class_names[MAX_CLASSES][24];
static long class_scenarios[MAX_CLASSES];
static double class_seconds[MAX_CLASSES];
static int nclasses;

static int class_id(const char *prefix, const char *name)
{
    char buf[24];
    snprintf(buf, sizeof buf, "%s%s", prefix, name);
    for (int i = 0; i < nclasses; i++)
        if (strcmp(class_names[i], buf) == 0)
            return i;
    if (nclasses >= MAX_CLASSES)
        abort();
    memcpy(class_names[nclasses], buf, sizeof buf);
    return nclasses++;
}

/* ---------------------------------------------------------------- exact reference */

/* Rational 3-vectors. */
typedef struct qvec {
    mpq_t c[3];
} qvec;

/* A point as homogeneous integers: X_k = n[k] / d with d > 0. */
typedef struct zpoint {
    mpz_t n[3], d;
} zpoint;

/* A plane: n = (b - a) x (c - a) and a, rational; and h, a positive integer multiple of
 * (n, -n.a), so that sign(h.(X, 1)) is the side of X. */
typedef struct zplane {
    qvec n, a;
    mpz_t h[4];
} zplane;

static void qvec_init(qvec *v)
{
    for (int k = 0; k < 3; k++)
        mpq_init(v->c[k]);
}

static void qvec_clear(qvec *v)
{
    for (int k = 0; k < 3; k++)
        mpq_clear(v->c[k]);
}

static void qvec_set_d(qvec *r, const double *x)
{
    for (int k = 0; k < 3; k++)
        mpq_set_d(r->c[k], x[k]); /* exact for every finite double */
}

static void qvec_sub(qvec *r, const qvec *a, const qvec *b)
{
    for (int k = 0; k < 3; k++)
        mpq_sub(r->c[k], a->c[k], b->c[k]);
}

static void qvec_cross(qvec *r, const qvec *a, const qvec *b) /* r must not alias */
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

static void qvec_dot(mpq_t r, const qvec *a, const qvec *b)
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
static void to_integers(mpz_t *out, mpz_ptr scale, mpq_t *in, int count)
{
    mpz_set_ui(scale, 1);
    for (int k = 0; k < count; k++)
        mpz_lcm(scale, scale, mpq_denref(in[k]));
    for (int k = 0; k < count; k++) {
        mpz_divexact(out[k], scale, mpq_denref(in[k]));
        mpz_mul(out[k], out[k], mpq_numref(in[k]));
    }
}

static void zpoint_from_qvec(zpoint *p, qvec *x) { to_integers(p->n, p->d, x->c, 3); }

static void ref_plane_set(zplane *p, const double *a, const double *b, const double *c)
{
    qvec qb, qc;
    mpq_t coef[4];
    mpz_t scale;
    qvec_init(&qb);
    qvec_init(&qc);
    mpz_init(scale);
    for (int k = 0; k < 4; k++)
        mpq_init(coef[k]);
    qvec_set_d(&p->a, a);
    qvec_set_d(&qb, b);
    qvec_set_d(&qc, c);
    qvec_sub(&qb, &qb, &p->a);
    qvec_sub(&qc, &qc, &p->a);
    qvec_cross(&p->n, &qb, &qc);
    for (int k = 0; k < 3; k++)
        mpq_set(coef[k], p->n.c[k]);
    qvec_dot(coef[3], &p->n, &p->a);
    mpq_neg(coef[3], coef[3]);
    to_integers(p->h, scale, coef, 4);
    for (int k = 0; k < 4; k++)
        mpq_clear(coef[k]);
    mpz_clear(scale);
    qvec_clear(&qb);
    qvec_clear(&qc);
}

/* Line p q meets the plane where n.(p + t u - a) = 0, u = q - p: t = n.(a - p) / n.u.
 * Returns false when n.u = 0 (no single point). *w = n.u. */
static bool ref_lpi(qvec *x, mpq_ptr w, const double *p, const double *q, const zplane *pl)
{
    qvec qp, u, ap;
    mpq_t t;
    bool ok;
    qvec_init(&qp);
    qvec_init(&u);
    qvec_init(&ap);
    mpq_init(t);
    qvec_set_d(&qp, p);
    qvec_set_d(&u, q);
    qvec_sub(&u, &u, &qp);
    qvec_dot(w, &pl->n, &u);
    ok = mpq_sgn(w) != 0;
    if (ok) {
        qvec_sub(&ap, &pl->a, &qp);
        qvec_dot(t, &pl->n, &ap);
        mpq_div(t, t, w);
        for (int k = 0; k < 3; k++) {
            mpq_mul(x->c[k], t, u.c[k]);
            mpq_add(x->c[k], x->c[k], qp.c[k]);
        }
    }
    mpq_clear(t);
    qvec_clear(&qp);
    qvec_clear(&u);
    qvec_clear(&ap);
    return ok;
}

/* Forward elimination with row swaps on m = [N | rhs]; false if singular. *det gets the
 * determinant of N (product of the pivots, sign flipped per swap). */
static bool eliminate(mpq_t m[3][4], mpq_ptr det)
{
    mpq_t f, t;
    bool ok = true;
    mpq_init(f);
    mpq_init(t);
    mpq_set_ui(det, 1, 1);
    for (int col = 0; col < 3 && ok; col++) {
        int piv = col;
        while (piv < 3 && mpq_sgn(m[piv][col]) == 0)
            piv++;
        ok = piv < 3;
        if (!ok)
            break;
        if (piv != col) {
            for (int j = 0; j < 4; j++)
                mpq_swap(m[piv][j], m[col][j]);
            mpq_neg(det, det);
        }
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
    mpq_clear(f);
    mpq_clear(t);
    return ok;
}

/* x from the upper-triangular system left by eliminate(). */
static void back_substitute(qvec *x, mpq_t m[3][4])
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

/* The point on three planes: solve n_k . x = n_k . a_k. Returns false when the normals
 * are dependent; *det = det[n1; n2; n3]. */
static bool ref_tpi(qvec *x, mpq_ptr det, const zplane *p0, const zplane *p1,
                    const zplane *p2)
{
    const zplane *pl[3] = {p0, p1, p2};
    mpq_t m[3][4];
    bool ok;
    for (int r = 0; r < 3; r++) {
        for (int j = 0; j < 4; j++)
            mpq_init(m[r][j]);
        for (int j = 0; j < 3; j++)
            mpq_set(m[r][j], pl[r]->n.c[j]);
        qvec_dot(m[r][3], &pl[r]->n, &pl[r]->a);
    }
    ok = eliminate(m, det);
    if (ok)
        back_substitute(x, m);
    for (int r = 0; r < 3; r++)
        for (int j = 0; j < 4; j++)
            mpq_clear(m[r][j]);
    return ok;
}

/* r = a[k] * b.d - b[k] * a.d: the k-th coordinate of a - b times a.d * b.d > 0. */
static void zdiff(mpz_t r, const zpoint *a, const zpoint *b, int k)
{
    mpz_mul(r, a->n[k], b->d);
    mpz_submul(r, b->n[k], a->d);
}

static int ref_orient3d(const zpoint *p, const zplane *pl)
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

static int ref_compare_coord(const zpoint *a, const zpoint *b, int axis)
{
    mpz_t s;
    int r;
    mpz_init(s);
    zdiff(s, a, b, axis);
    r = mpz_sgn(s);
    mpz_clear(s);
    return r;
}

static int ref_compare_lex(const zpoint *a, const zpoint *b)
{
    for (int k = 0; k < 3; k++) {
        int c = ref_compare_coord(a, b, k);
        if (c)
            return c;
    }
    return 0;
}

/* 2D cross product of (q - p) and (r - p) in coordinates (i, j). */
static int ref_orient2d(const zpoint *p, const zpoint *q, const zpoint *r, int axis)
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

/* sign((a - b) . dir) */
static int ref_dot_dir(const zpoint *a, const zpoint *b, mpz_t *dir)
{
    mpz_t s, t;
    int r;
    mpz_inits(s, t, NULL);
    for (int k = 0; k < 3; k++) {
        zdiff(t, a, b, k);
        mpz_addmul(s, t, dir[k]);
    }
    r = mpz_sgn(s);
    mpz_clears(s, t, NULL);
    return r;
}

/* A positive multiple of n1 x n2. */
static void ref_plane_line_dir(mpz_t *dir, const zplane *p1, const zplane *p2)
{
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mpz_mul(dir[k], p1->h[i], p2->h[j]);
        mpz_submul(dir[k], p1->h[j], p2->h[i]);
    }
}

/* ---------------------------------------------------------------- workspace */

/* Kernel objects and their references for the scenario being run. Kept for the whole
 * run so that the GMP numbers are allocated once. */
static struct {
    mci_plane kpl[MAXPL];
    mci_point kpt[MAXPT];
    bool ok[MAXPT]; /* both kernel and reference constructed the point */
    zplane rpl[MAXPL];
    zpoint rpt[MAXPT];
    zpoint rv[MAXV]; /* the input vertices */
    qvec rx[MAXPT];  /* rational coordinates */
    mpq_t rw[MAXPT]; /* W as the header defines it: n.u (LPI), det (TPI) */
} ws;

static void zpoint_init(zpoint *p) { mpz_inits(p->n[0], p->n[1], p->n[2], p->d, NULL); }

static void zpoint_clear(zpoint *p) { mpz_clears(p->n[0], p->n[1], p->n[2], p->d, NULL); }

static void ws_init(void)
{
    for (int i = 0; i < MAXPL; i++) {
        qvec_init(&ws.rpl[i].n);
        qvec_init(&ws.rpl[i].a);
        mpz_inits(ws.rpl[i].h[0], ws.rpl[i].h[1], ws.rpl[i].h[2], ws.rpl[i].h[3], NULL);
    }
    for (int i = 0; i < MAXPT; i++) {
        zpoint_init(&ws.rpt[i]);
        qvec_init(&ws.rx[i]);
        mpq_init(ws.rw[i]);
    }
    for (int i = 0; i < MAXV; i++)
        zpoint_init(&ws.rv[i]);
}

static void ws_clear(void)
{
    for (int i = 0; i < MAXPL; i++) {
        qvec_clear(&ws.rpl[i].n);
        qvec_clear(&ws.rpl[i].a);
        mpz_clears(ws.rpl[i].h[0], ws.rpl[i].h[1], ws.rpl[i].h[2], ws.rpl[i].h[3], NULL);
    }
    for (int i = 0; i < MAXPT; i++) {
        zpoint_clear(&ws.rpt[i]);
        qvec_clear(&ws.rx[i]);
        mpq_clear(ws.rw[i]);
    }
    for (int i = 0; i < MAXV; i++)
        zpoint_clear(&ws.rv[i]);
}

/* ---------------------------------------------------------------- reporting */

typedef struct query {
    int pred;
    int pt[3], pl[2], lv[2], axis;
} query;

static const char *vstr(const double *x)
{
    static char buf[8][96];
    static int slot;
    char *out = buf[slot++ & 7];
    snprintf(out, sizeof buf[0], "{%a, %a, %a}", x[0], x[1], x[2]);
    return out;
}

static void print_plane(const scenario *s, const char *label, int p)
{
    fprintf(stderr, "    %s plane %s %s %s\n", label, vstr(s->v[s->plv[p][0]]),
            vstr(s->v[s->plv[p][1]]), vstr(s->v[s->plv[p][2]]));
}

static void print_point(const scenario *s, const char *label, int i)
{
    const point_def *d = &s->pt[i];
    static const char *const kinds[] = {"explicit", "LPI", "TPI"};
    fprintf(stderr, "  %s = %s", label, kinds[d->kind]);
    if (d->kind == MCI_POINT_EXPLICIT)
        fprintf(stderr, " %s\n", vstr(s->v[d->v[0]]));
    if (d->kind == MCI_POINT_LPI) {
        fprintf(stderr, " line %s %s\n", vstr(s->v[d->v[0]]), vstr(s->v[d->v[1]]));
        print_plane(s, "", d->pl[0]);
    }
    if (d->kind == MCI_POINT_TPI) {
        fputc('\n', stderr);
        for (int k = 0; k < 3; k++)
            print_plane(s, "", d->pl[k]);
    }
}

static int operand_points(int pred)
{
    static const int n[PR_COUNT] = {1, 2, 2, 2, 3, 0, 2, 2, 1, 1, 0};
    return n[pred];
}

static int operand_planes(int pred)
{
    return pred == PR_ORIENT3D ? 1 : pred == PR_LINEDIR || pred == PR_ORDER_PL ? 2 : 0;
}

static void print_query(const scenario *s, const query *q)
{
    static const char *const names[] = {"A", "B", "C"};
    for (int k = 0; k < operand_points(q->pred); k++)
        print_point(s, names[k], q->pt[k]);
    for (int k = 0; k < operand_planes(q->pred); k++)
        print_plane(s, k ? "P2 =" : "P1 =", q->pl[k]);
    if (q->pred == PR_ORDER_EDGE)
        fprintf(stderr, "  edge line %s %s\n", vstr(s->v[q->lv[0]]), vstr(s->v[q->lv[1]]));
}

static int printed_mismatches;

static void mismatch(const scenario *s, const query *q, const int got[3], int ref)
{
    char g[3][8];
    test_failures++;
    stats[s->cls][q->pred].mismatches++;
    if (printed_mismatches++ >= MAX_PRINTED)
        return;
    for (int k = 0; k < 3; k++) {
        if (got[k] == NONE)
            snprintf(g[k], sizeof g[k], "-");
        else
            snprintf(g[k], sizeof g[k], "%d", got[k]);
    }
    fprintf(stderr,
            "MISMATCH %s axis %d (%s): combined %s, exact %s, filtered %s, "
            "reference %d\n",
            pred_names[q->pred], q->axis, class_names[s->cls], g[0], g[1], g[2], ref);
    print_query(s, q);
}

/* Counts a case and checks its three stages against the reference. */
static void check_case(const scenario *s, const query *q, const int got[3], int ref)
{
    pstat *st = &stats[s->cls][q->pred];
    bool bad = (got[0] != NONE && got[0] != ref) || (got[1] != NONE && got[1] != ref) ||
               (got[2] != NONE && got[2] != MCI_UNCERTAIN && got[2] != ref);
    test_checks++;
    st->calls++;
    st->zero += ref == 0;
    if (got[2] != NONE) {
        st->filt++;
        if (got[2] != MCI_UNCERTAIN) {
            st->decided++;
            st->decided_zero += ref == 0;
        }
    }
    if (bad)
        mismatch(s, q, got, ref);
}

/* ---------------------------------------------------------------- cached bounds */

static long uninformative_bounds; /* cached values with bound +inf or NaN */

/* |f.v - x| <= f.e. A bound of +inf or NaN (after an overflow) says nothing and holds
 * trivially: every filter comparison |v| > e fails on it, so the exact stage decides. */
static bool fv_holds(mci_fv f, mpq_srcptr x)
{
    mpq_t d, e;
    bool ok;
    if (isnan(f.e) || (isinf(f.e) && f.e > 0)) {
        uninformative_bounds++;
        return true;
    }
    if (!isfinite(f.v) || !isfinite(f.e) || f.e < 0)
        return false;
    mpq_inits(d, e, NULL);
    mpq_set_d(d, f.v);
    mpq_sub(d, d, x);
    mpq_abs(d, d);
    mpq_set_d(e, f.e);
    ok = mpq_cmp(d, e) <= 0;
    mpq_clears(d, e, NULL);
    return ok;
}

static void print_bound(const char *what, int k, mci_fv f, mpq_srcptr x)
{
    fprintf(stderr, "  cached %s[%d] = %a +- %a, exact %a\n", what, k, f.v, f.e,
            mpq_get_d(x));
}

/* The cached normal's bounds hold; with `print`, shows those that do not. */
static bool plane_bounds_ok(int p, bool print)
{
    bool ok = true;
    for (int k = 0; k < 3; k++)
        if (!fv_holds(ws.kpl[p].n[k], ws.rpl[p].n.c[k])) {
            ok = false;
            if (print)
                print_bound("normal", k, ws.kpl[p].n[k], ws.rpl[p].n.c[k]);
        }
    return ok;
}

static void check_plane_bounds(const scenario *s, int p)
{
    query q = {PR_BOUNDS, {0, 0, 0}, {p, p}, {0, 0}, 0};
    int got[3] = {plane_bounds_ok(p, false), NONE, NONE};
    check_case(s, &q, got, 1);
    if (!got[0] && printed_mismatches <= MAX_PRINTED) {
        print_plane(s, "of", p);
        plane_bounds_ok(p, true);
    }
}

/* The stored (y, w) approximate sign(W) * (Y, W) with Y = W (X - base) (that is the
 * header's Y: u n.(a - p) for an LPI, the Cramer numerators for a TPI), and w_sign = 1. */
static bool point_bounds_ok(int i, bool print)
{
    const mci_point *p = &ws.kpt[i];
    bool ok = p->w_sign == 1;
    mpq_t w, y, base;
    mpq_inits(w, y, base, NULL);
    mpq_abs(w, ws.rw[i]);
    if (print)
        fprintf(stderr, "  w_sign %d\n", p->w_sign);
    if (!fv_holds(p->w, w)) {
        ok = false;
        if (print)
            print_bound("w", 0, p->w, w);
    }
    for (int k = 0; k < 3; k++) {
        mpq_set_d(base, p->v[0][k]);
        mpq_sub(y, ws.rx[i].c[k], base);
        mpq_mul(y, y, w);
        if (!fv_holds(p->y[k], y)) {
            ok = false;
            if (print)
                print_bound("y", k, p->y[k], y);
        }
    }
    mpq_clears(w, y, base, NULL);
    return ok;
}

static void check_point_bounds(const scenario *s, int i)
{
    query q = {PR_BOUNDS, {i, 0, 0}, {0, 0}, {0, 0}, 0};
    int got[3] = {point_bounds_ok(i, false), NONE, NONE};
    check_case(s, &q, got, 1);
    if (!got[0] && printed_mismatches <= MAX_PRINTED) {
        print_point(s, "of", i);
        point_bounds_ok(i, true);
    }
}

/* ---------------------------------------------------------------- point boxes */

static long box_points, box_infinite, box_tight; /* mci_point_bounds of implicit points */
static int box_printed;

/* lo <= x (upper: x <= hi), exactly. An infinite bound on its own side always holds. */
static bool box_bound_holds(double b, mpq_srcptr x, bool upper)
{
    mpq_t q;
    int c;
    if (isinf(b) && (b > 0) == upper)
        return true;
    if (!isfinite(b))
        return false;
    mpq_init(q);
    mpq_set_d(q, b);
    c = mpq_cmp(q, x);
    mpq_clear(q);
    return upper ? c >= 0 : c <= 0;
}

/* x - b rounded to a double (the size of a miss), or NaN when b is not finite. */
static double box_gap(mpq_srcptr x, double b)
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

/* The box of mci_point_bounds contains the exact point; counts infinite and tight boxes
 * (tight: hi - lo <= 1e-10 (|lo| + |hi|) + 1e-300 on every axis). */
static void check_point_box(const scenario *s, int i)
{
    const mci_point *p = &ws.kpt[i];
    double lo[3], hi[3];
    bool infinite = false, tight = true;
    mci_point_bounds(p, lo, hi);
    for (int k = 0; k < 3; k++) {
        mpq_srcptr x = ws.rx[i].c[k];
        bool ok = box_bound_holds(lo[k], x, false) && box_bound_holds(hi[k], x, true);
        CHECK_MSG(ok, "mci_point_bounds (%s) axis %d: [%a, %a] misses exact %a",
                  class_names[s->cls], k, lo[k], hi[k], mpq_get_d(x));
        if (!ok && box_printed++ < MAX_PRINTED) {
            print_point(s, "of", i);
            fprintf(stderr, "  base %a, y = %a +- %a, w = %a +- %a; exact - lo = %a, "
                    "exact - hi = %a\n", p->v[0][k], p->y[k].v, p->y[k].e, p->w.v,
                    p->w.e, box_gap(x, lo[k]), box_gap(x, hi[k]));
        }
        infinite |= isinf(lo[k]) || isinf(hi[k]);
        tight &= hi[k] - lo[k] <= 1e-10 * (fabs(lo[k]) + fabs(hi[k])) + 1e-300;
    }
    if (p->kind != MCI_POINT_EXPLICIT) {
        box_points++;
        box_infinite += infinite;
        box_tight += tight && !infinite;
    }
}

/* ---------------------------------------------------------------- correct rounding */

static long rounded_coordinates;

/* r is a nearest double to x: x lies between the midpoints to r's neighbours. */
static bool is_nearest_double(double r, mpq_srcptr x)
{
    double below = nextafter(r, -INFINITY), above = nextafter(r, INFINITY);
    mpq_t lo, hi, t;
    bool ok;
    if (!isfinite(r))
        return false;
    mpq_inits(lo, hi, t, NULL);
    mpq_set_d(lo, r);
    mpq_set_d(t, below);
    mpq_add(lo, lo, t);
    mpq_div_2exp(lo, lo, 1);
    mpq_set_d(hi, r);
    mpq_set_d(t, above);
    mpq_add(hi, hi, t);
    mpq_div_2exp(hi, hi, 1);
    ok = (!isfinite(below) || mpq_cmp(lo, x) <= 0) && (!isfinite(above) || mpq_cmp(x, hi) <= 0);
    mpq_clears(lo, hi, t, NULL);
    return ok;
}

/* mci_point_round gives the nearest double on every axis; mci_point_approx is finite. */
/* The double-double rounding stage on its own, from the approximation and from a guess
 * two steps off (it must walk to the nearest double or give up). */
static long dd_rounded, dd_round_tries;

static void check_point_round_dd(const scenario *s, int i, const double approx[3])
{
    for (int shift = 0; shift < 2; shift++) {
        double guess[3], r[3];
        unsigned left;
        for (int k = 0; k < 3; k++)
            guess[k] = shift ? nextafter(nextafter(approx[k], INFINITY), INFINITY) : approx[k];
        left = mci_point_round_dd(&ws.kpt[i], 7, guess, r);
        for (int k = 0; k < 3; k++) {
            if (fabs(mpq_get_d(ws.rx[i].c[k])) > 0x1p1020)
                continue;
            dd_round_tries++;
            if ((left >> k) & 1)
                continue;
            dd_rounded++;
            CHECK_MSG(is_nearest_double(r[k], ws.rx[i].c[k]), "mci_point_round_dd (%s) axis "
                      "%d: %a, exact %a", class_names[s->cls], k, r[k],
                      mpq_get_d(ws.rx[i].c[k]));
        }
    }
}

static void check_point_round(const scenario *s, int i)
{
    double r[3], a[3];
    mci_point_round(&ws.kpt[i], r);
    mci_point_approx(&ws.kpt[i], a);
    for (int k = 0; k < 3; k++) {
        if (fabs(mpq_get_d(ws.rx[i].c[k])) > 0x1p1020)
            continue; /* near or beyond the double range: not a point of any mesh */
        CHECK_MSG(is_nearest_double(r[k], ws.rx[i].c[k]), "mci_point_round (%s) axis %d: "
                  "%a, exact %a", class_names[s->cls], k, r[k], mpq_get_d(ws.rx[i].c[k]));
        CHECK_MSG(isfinite(a[k]), "mci_point_approx (%s) axis %d: %a", class_names[s->cls],
                  k, a[k]);
        rounded_coordinates++;
    }
    check_point_round_dd(s, i, a);
}

/* ---------------------------------------------------------------- building a scenario */

static void build_point(const scenario *s, int i)
{
    const point_def *d = &s->pt[i];
    mci_point *kp = &ws.kpt[i];
    bool kok = true, rok = true;
    if (d->kind == MCI_POINT_EXPLICIT) {
        mci_point_explicit(kp, s->v[d->v[0]]);
        qvec_set_d(&ws.rx[i], s->v[d->v[0]]);
    } else if (d->kind == MCI_POINT_LPI) {
        kok = mci_point_lpi(kp, s->v[d->v[0]], s->v[d->v[1]], &ws.kpl[d->pl[0]]);
        rok = ref_lpi(&ws.rx[i], ws.rw[i], s->v[d->v[0]], s->v[d->v[1]], &ws.rpl[d->pl[0]]);
    } else {
        kok = mci_point_tpi(kp, &ws.kpl[d->pl[0]], &ws.kpl[d->pl[1]], &ws.kpl[d->pl[2]]);
        rok = ref_tpi(&ws.rx[i], ws.rw[i], &ws.rpl[d->pl[0]], &ws.rpl[d->pl[1]],
                      &ws.rpl[d->pl[2]]);
    }
    if (d->kind != MCI_POINT_EXPLICIT) {
        query q = {
            d->kind == MCI_POINT_LPI ? PR_LPI : PR_TPI, {i, 0, 0}, {0, 0}, {0, 0}, 0};
        int got[3] = {kok, NONE, NONE};
        check_case(s, &q, got, rok);
    }
    ws.ok[i] = kok && rok;
    if (!ws.ok[i])
        return;
    zpoint_from_qvec(&ws.rpt[i], &ws.rx[i]);
    if (d->kind != MCI_POINT_EXPLICIT)
        check_point_bounds(s, i);
    check_point_box(s, i);
    check_point_round(s, i);
}

static void build(const scenario *s)
{
    for (int i = 0; i < s->nv; i++) {
        qvec_set_d(&ws.rx[0], s->v[i]);
        zpoint_from_qvec(&ws.rv[i], &ws.rx[0]);
    }
    for (int p = 0; p < s->npl; p++) {
        const double *a = s->v[s->plv[p][0]], *b = s->v[s->plv[p][1]],
                     *c = s->v[s->plv[p][2]];
        mci_plane_init(&ws.kpl[p], a, b, c);
        ref_plane_set(&ws.rpl[p], a, b, c);
        check_plane_bounds(s, p);
    }
    for (int i = 0; i < s->npt; i++)
        build_point(s, i);
}

/* ---------------------------------------------------------------- running queries */

static void kernel_eval(const scenario *s, const query *q, int got[3])
{
    const mci_point *a = &ws.kpt[q->pt[0]], *b = &ws.kpt[q->pt[1]], *c = &ws.kpt[q->pt[2]];
    const mci_plane *p1 = &ws.kpl[q->pl[0]], *p2 = &ws.kpl[q->pl[1]];
    int ax = q->axis;
    got[0] = got[1] = got[2] = NONE;
    switch (q->pred) {
    case PR_ORIENT3D:
        got[0] = mci_orient3d(a, p1);
        got[1] = mci_orient3d_exact(a, p1);
        got[2] = mci_orient3d_filtered(a, p1);
        break;
    case PR_CMP:
        got[0] = mci_compare_coord(a, b, ax);
        got[1] = mci_compare_coord_exact(a, b, ax);
        got[2] = mci_compare_coord_filtered(a, b, ax);
        break;
    case PR_LEX:
        got[0] = mci_compare_lex(a, b);
        break;
    case PR_EQ:
        got[0] = mci_points_equal(a, b);
        break;
    case PR_ORIENT2D:
        got[0] = mci_orient2d_projected(a, b, c, ax);
        got[1] = mci_orient2d_projected_exact(a, b, c, ax);
        got[2] = mci_orient2d_projected_filtered(a, b, c, ax);
        break;
    case PR_LINEDIR:
        got[1] = mci_line_direction_sign_exact(p1, p2, ax);
        got[2] = mci_line_direction_sign_filtered(p1, p2, ax);
        break;
    case PR_ORDER_PL:
        got[0] = mci_order_on_plane_line(a, b, p1, p2);
        break;
    default: /* PR_ORDER_EDGE */
        got[0] = mci_order_on_edge_line(a, b, s->v[q->lv[0]], s->v[q->lv[1]]);
        break;
    }
}

/* sign((a - b) . (n1 x n2)) if a and b lie on both planes and those are not parallel,
 * else NONE. */
static int ref_order_plane_line(const zpoint *a, const zpoint *b, const zplane *p1,
                                const zplane *p2)
{
    mpz_t dir[3];
    int r = NONE;
    bool on = !ref_orient3d(a, p1) && !ref_orient3d(a, p2) && !ref_orient3d(b, p1) &&
              !ref_orient3d(b, p2);
    mpz_inits(dir[0], dir[1], dir[2], NULL);
    ref_plane_line_dir(dir, p1, p2);
    if (on && (mpz_sgn(dir[0]) || mpz_sgn(dir[1]) || mpz_sgn(dir[2])))
        r = ref_dot_dir(a, b, dir);
    mpz_clears(dir[0], dir[1], dir[2], NULL);
    return r;
}

/* Whether p lies on the line through l0 != l1: collinear in all three projections. */
static bool ref_on_line(const zpoint *p, const zpoint *l0, const zpoint *l1)
{
    return ref_orient2d(l0, l1, p, 0) == 0 && ref_orient2d(l0, l1, p, 1) == 0 &&
           ref_orient2d(l0, l1, p, 2) == 0;
}

/* sign((a - b) . (l1 - l0)) if l0 != l1 and a, b lie on their line, else NONE. */
static int ref_order_edge_line(const zpoint *a, const zpoint *b, const zpoint *l0,
                               const zpoint *l1)
{
    mpz_t dir[3];
    int r = NONE;
    if (ref_compare_lex(l0, l1) == 0 || !ref_on_line(a, l0, l1) || !ref_on_line(b, l0, l1))
        return NONE;
    mpz_inits(dir[0], dir[1], dir[2], NULL);
    for (int k = 0; k < 3; k++)
        zdiff(dir[k], l1, l0, k);
    r = ref_dot_dir(a, b, dir);
    mpz_clears(dir[0], dir[1], dir[2], NULL);
    return r;
}

static int ref_line_direction_sign(const zplane *p1, const zplane *p2, int axis)
{
    mpz_t dir[3];
    int r;
    mpz_inits(dir[0], dir[1], dir[2], NULL);
    ref_plane_line_dir(dir, p1, p2);
    r = mpz_sgn(dir[axis]);
    mpz_clears(dir[0], dir[1], dir[2], NULL);
    return r;
}

/* The reference result, or NONE where the predicate's precondition does not hold. */
static int ref_eval(const query *q)
{
    const zpoint *a = &ws.rpt[q->pt[0]], *b = &ws.rpt[q->pt[1]], *c = &ws.rpt[q->pt[2]];
    const zplane *p1 = &ws.rpl[q->pl[0]], *p2 = &ws.rpl[q->pl[1]];
    switch (q->pred) {
    case PR_ORIENT3D:
        return ref_orient3d(a, p1);
    case PR_CMP:
        return ref_compare_coord(a, b, q->axis);
    case PR_LEX:
        return ref_compare_lex(a, b);
    case PR_EQ:
        return ref_compare_lex(a, b) == 0;
    case PR_ORIENT2D:
        return ref_orient2d(a, b, c, q->axis);
    case PR_LINEDIR:
        return ref_line_direction_sign(p1, p2, q->axis);
    case PR_ORDER_PL:
        return ref_order_plane_line(a, b, p1, p2);
    default: /* PR_ORDER_EDGE */
        return ref_order_edge_line(a, b, &ws.rv[q->lv[0]], &ws.rv[q->lv[1]]);
    }
}

/* The double-double stage of orient2d, checked on every case: a sign it gives must be
 * the reference's. Counted where the first filter gave up (where it is used). */
static long dd_after_filter, dd_decided;

static long box_filter_cases, box_filter_decided;

/* The box filter (mci_orient2d_projected_quick, inline) alone: a sign it gives must be
 * the reference's, and it never answers 0. */
static void check_orient2d_boxes(const scenario *s, const query *q, int ref)
{
    const mci_point *a = &ws.kpt[q->pt[0]], *b = &ws.kpt[q->pt[1]], *c = &ws.kpt[q->pt[2]];
    int got = mci_orient2d_projected_quick(a, b, c, q->axis);
    CHECK_MSG(got == MCI_UNCERTAIN || (got != 0 && got == ref),
              "mci_orient2d_projected_quick (%s): %d, reference %d", class_names[s->cls], got,
              ref);
    box_filter_cases++;
    box_filter_decided += got != MCI_UNCERTAIN;
}

static void check_orient2d_dd(const scenario *s, const query *q, int filtered, int ref)
{
    const mci_point *a = &ws.kpt[q->pt[0]], *b = &ws.kpt[q->pt[1]], *c = &ws.kpt[q->pt[2]];
    int got = mci_orient2d_projected_dd(a, b, c, q->axis);
    CHECK_MSG(got == MCI_UNCERTAIN || got == ref,
              "mci_orient2d_projected_dd (%s): %d, reference %d", class_names[s->cls], got,
              ref);
    if (filtered == MCI_UNCERTAIN) {
        dd_after_filter++;
        dd_decided += got != MCI_UNCERTAIN;
    }
}

/* The vertex forms of orient3d (an input vertex against a plane, and against the plane
 * of three input vertices): full predicate equal to the reference, filter never wrong. */
static long vertex_filter_cases, vertex_filter_decided, vertex_dd_cases, vertex_dd_decided;

/* The double-double stage between them: a sign it gives must be the reference's. */
static void check_orient3d_vertex_dd(const scenario *s, const mci_plane *p, const double *x,
                                     int filtered, int ref)
{
    int got = mci_orient3d_vertices_dd(p->a, p->b, p->c, x);
    CHECK_MSG(got == MCI_UNCERTAIN || got == ref, "mci_orient3d_vertices_dd (%s): %d, "
              "reference %d", class_names[s->cls], got, ref);
    if (filtered == MCI_UNCERTAIN) {
        vertex_dd_cases++;
        vertex_dd_decided += got != MCI_UNCERTAIN;
    }
}

static void check_orient3d_vertex(const scenario *s, const query *q, int ref)
{
    const mci_point *a = &ws.kpt[q->pt[0]];
    const mci_plane *p = &ws.kpl[q->pl[0]];
    const double *x = a->v[0];
    int f1, f2;
    if (a->kind != MCI_POINT_EXPLICIT)
        return;
    f1 = mci_orient3d_vertex_filtered(x, p);
    f2 = mci_orient3d_vertices_filtered(p->a, p->b, p->c, x);
    CHECK_MSG(mci_orient3d_vertex(x, p) == ref, "mci_orient3d_vertex (%s): reference %d",
              class_names[s->cls], ref);
    CHECK_MSG(mci_orient3d_vertices(p->a, p->b, p->c, x) == ref,
              "mci_orient3d_vertices (%s): reference %d", class_names[s->cls], ref);
    CHECK_MSG(f1 == MCI_UNCERTAIN || f1 == ref, "mci_orient3d_vertex_filtered (%s): %d, "
              "reference %d", class_names[s->cls], f1, ref);
    CHECK_MSG(f2 == MCI_UNCERTAIN || f2 == ref, "mci_orient3d_vertices_filtered (%s): %d, "
              "reference %d", class_names[s->cls], f2, ref);
    check_orient3d_vertex_dd(s, p, x, f2, ref);
    vertex_filter_cases += 2;
    vertex_filter_decided += (f1 != MCI_UNCERTAIN) + (f2 != MCI_UNCERTAIN);
}

static void run_query(const scenario *s, const query *q)
{
    int got[3], ref = ref_eval(q);
    if (ref == NONE)
        return; /* precondition fails: the kernel must not be asked */
    kernel_eval(s, q, got);
    check_case(s, q, got, ref);
    if (q->pred == PR_ORIENT2D) {
        check_orient2d_boxes(s, q, ref);
        check_orient2d_dd(s, q, got[2], ref);
    }
    if (q->pred == PR_ORIENT3D)
        check_orient3d_vertex(s, q, ref);
}

/* Indices of the points that exist; returns their count. */
static int usable_points(const scenario *s, int *idx)
{
    int n = 0;
    for (int i = 0; i < s->npt; i++)
        if (ws.ok[i])
            idx[n++] = i;
    return n;
}

static void queries_orient3d(const scenario *s, const int *idx, int n)
{
    for (int i = 0; i < n; i++)
        for (int p = 0; p < s->npl; p++) {
            query q = {PR_ORIENT3D, {idx[i], 0, 0}, {p, p}, {0, 0}, 0};
            run_query(s, &q);
        }
}

/* compare_coord on every axis, lex, equality, and the line orders, for every pair
 * (including a point with itself), in a random order of the two operands. */
static void queries_pairs(const scenario *s, const int *idx, int n)
{
    for (int i = 0; i < n; i++)
        for (int j = i; j < n; j++) {
            bool swap = rng_chance(0.5);
            query q = {PR_CMP,
                       {swap ? idx[j] : idx[i], swap ? idx[i] : idx[j], 0},
                       {0, 0},
                       {0, 0},
                       0};
            for (q.axis = 0; q.axis < 3; q.axis++)
                run_query(s, &q);
            q.axis = 0;
            q.pred = PR_LEX;
            run_query(s, &q);
            q.pred = PR_EQ;
            run_query(s, &q);
            q.pred = PR_ORDER_PL;
            for (int l = 0; l < s->nlp; l++) {
                q.pl[0] = s->line_planes[l][0];
                q.pl[1] = s->line_planes[l][1];
                run_query(s, &q);
            }
            q.pred = PR_ORDER_EDGE;
            for (int l = 0; l < s->nle; l++) {
                q.lv[0] = s->line_edges[l][0];
                q.lv[1] = s->line_edges[l][1];
                run_query(s, &q);
            }
        }
}

static void orient2d_all_axes(const scenario *s, int a, int b, int c)
{
    query q = {PR_ORIENT2D, {a, b, c}, {0, 0}, {0, 0}, 0};
    for (q.axis = 0; q.axis < 3; q.axis++)
        run_query(s, &q);
}

/* Every triple when there are few points (in a random order of the three), otherwise a
 * sample drawn with replacement (so repeated points occur too). */
static void queries_orient2d(const scenario *s, const int *idx, int n)
{
    enum { SAMPLE = 90 };
    if (n > 10) {
        for (int t = 0; t < SAMPLE; t++)
            orient2d_all_axes(s, idx[rng_int(0, n - 1)], idx[rng_int(0, n - 1)],
                              idx[rng_int(0, n - 1)]);
        return;
    }
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            for (int k = j + 1; k < n; k++) {
                int t[3] = {idx[i], idx[j], idx[k]}, r = rng_int(0, 2);
                if (rng_chance(0.5))
                    orient2d_all_axes(s, t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
                else
                    orient2d_all_axes(s, t[r], t[(r + 2) % 3], t[(r + 1) % 3]);
            }
}

static void queries_linedir(const scenario *s)
{
    for (int p = 0; p < s->npl; p++)
        for (int r = p + 1; r < s->npl; r++) {
            query q = {PR_LINEDIR, {0, 0, 0}, {p, r}, {0, 0}, 0};
            for (q.axis = 0; q.axis < 3; q.axis++)
                run_query(s, &q);
        }
}

/* The generator's claims (group points on the onpl planes, and equal) hold exactly: a
 * failure here is a bug of this test, not of the kernel. */
static void check_claims(const scenario *s)
{
    for (int g = 0; g < s->ngroup; g++) {
        int i = s->group[g];
        if (!ws.ok[i])
            continue;
        for (int p = 0; p < s->nonpl; p++)
            CHECK_MSG(ref_orient3d(&ws.rpt[i], &ws.rpl[s->onpl[p]]) == 0,
                      "%s: generator: point %d not on plane %d", class_names[s->cls], i,
                      s->onpl[p]);
        if (s->group_equal && ws.ok[s->group[0]])
            CHECK_MSG(ref_compare_lex(&ws.rpt[i], &ws.rpt[s->group[0]]) == 0,
                      "%s: generator: point %d differs from %d", class_names[s->cls], i,
                      s->group[0]);
    }
}

static double seconds(void) { return (double)clock() / CLOCKS_PER_SEC; }

/* MCSG_TEST_ONLY=TEXT runs only the classes whose name contains TEXT. */
static bool class_selected(int cls)
{
    const char *only = getenv("MCSG_TEST_ONLY");
    return !only || strstr(class_names[cls], only);
}

static void run_scenario(const scenario *s)
{
    int idx[MAXPT], n;
    double t = seconds();
    if (!class_selected(s->cls))
        return;
    build(s);
    check_claims(s);
    n = usable_points(s, idx);
    queries_orient3d(s, idx, n);
    queries_pairs(s, idx, n);
    queries_orient2d(s, idx, n);
    queries_linedir(s);
    class_scenarios[s->cls]++;
    class_seconds[s->cls] += seconds() - t;
}

/* The scenario, then `runs` copies with one input coordinate (sometimes two) moved by one
 * ulp: exact degeneracies become near-degeneracies the reference still decides. */
static void run_with_perturbations(const scenario *base, int runs, int ulp_cls)
{
    run_scenario(base);
    for (int r = 0; r < runs; r++) {
        scenario s = *base;
        int moves = rng_chance(0.25) ? 2 : 1;
        s.cls = ulp_cls;
        s.ngroup = s.nonpl = 0;
        for (int m = 0; m < moves; m++) {
            double *x = &s.v[rng_int(0, s.nv - 1)][rng_int(0, 2)];
            *x = nudge(*x, 1);
        }
        run_scenario(&s);
    }
}

/* ---------------------------------------------------------------- random scenarios */

static int random_vertex(scenario *s, int regime)
{
    double x[3];
    draw_vertex(regime, x);
    return sc_vertex(s, x);
}

/* Random vertices; planes 0..2 share the line v0 v1 (in both orientations) so that
 * points on it can be ordered; LPIs and TPIs on that line and elsewhere. A few cases are
 * degenerate on purpose (repeated vertex in a plane, repeated plane in a TPI, p = q). */
static void scenario_random(scenario *s, int regime)
{
    const int nv = 12;
    memset(s, 0, sizeof *s);
    s->cls = class_id("random/", regime_names[regime]);
    bits_width = rng_chance(0.5) ? rng_int(1, 8) : rng_int(9, 40);
    for (int i = 0; i < nv; i++)
        random_vertex(s, regime);
    sc_plane(s, 0, 1, 2);
    sc_plane(s, 1, 0, 3);
    sc_plane(s, 4, 0, 1);
    for (int p = 3; p < 8; p++) {
        int a = rng_int(2, nv - 1), b = rng_int(2, nv - 1), c = rng_int(2, nv - 1);
        if (!rng_chance(0.03))
            while (b == a || c == a || c == b)
                b = rng_int(2, nv - 1), c = rng_int(2, nv - 1);
        sc_plane(s, a, b, c);
    }
    sc_explicit(s, 0);
    sc_explicit(s, 1);
    sc_explicit(s, rng_int(2, nv - 1));
    sc_explicit(s, rng_int(2, nv - 1));
    sc_lpi(s, 0, 1, rng_int(3, 7));
    sc_lpi(s, 1, 0, rng_int(3, 7));
    for (int k = 0; k < 3; k++) {
        int a = rng_int(0, nv - 1), b = rng_chance(0.02) ? a : rng_int(0, nv - 1);
        sc_lpi(s, a, b, rng_int(0, 7));
    }
    sc_tpi(s, 0, 1, rng_int(3, 7));
    sc_tpi(s, 2, 0, rng_int(3, 7));
    for (int k = 0; k < 3; k++) {
        int a = rng_int(0, 7), b = rng_int(0, 7), c = rng_int(0, 7);
        if (!rng_chance(0.03))
            while (b == a || c == a || c == b)
                b = rng_int(0, 7), c = rng_int(0, 7);
        sc_tpi(s, a, b, c);
    }
    sc_line_planes(s, 0, 1);
    sc_line_planes(s, 2, 0);
    sc_line_edge(s, 0, 1);
    sc_line_edge(s, 1, 0);
}

/* ---------------------------------------------------------------- nearly parallel */

/* A copy of vertex v with n_coords of its coordinates nudged by 1..3 ulps. */
static int nudged_vertex(scenario *s, int v, int n_coords)
{
    double x[3];
    memcpy(x, s->v[v], sizeof x);
    for (int k = 0; k < n_coords; k++) {
        int a = rng_int(0, 2);
        x[a] = nudge(x[a], rng_int(1, 3));
    }
    return sc_vertex(s, x);
}

/* q = p + (b - a) rounded: a line nearly parallel to any plane through a and b (exactly
 * parallel when the sum is exact). Falls back to a nudged p if the sum overflows. */
static int parallel_end(scenario *s, int p, int a, int b)
{
    double x[3];
    for (int k = 0; k < 3; k++) {
        x[k] = s->v[p][k] + (s->v[b][k] - s->v[a][k]);
        if (!isfinite(x[k]))
            x[k] = nudge(s->v[p][k], 4);
    }
    return sc_vertex(s, x);
}

/* Planes that are copies of P0 = (v0, v1, v2) nudged by a few ulps: TPIs of nearly
 * parallel planes, LPIs of lines nearly parallel to planes. P0 and P2 share the line
 * v0 v1 exactly (P2's third vertex is a nudged v2), so points on it are ordered too. */
static void scenario_near_parallel(scenario *s, int regime)
{
    memset(s, 0, sizeof *s);
    s->cls = class_id("nearpar/", regime_names[regime]);
    bits_width = rng_chance(0.5) ? rng_int(1, 8) : rng_int(9, 40);
    for (int i = 0; i < 8; i++)
        random_vertex(s, regime);
    int w0 = nudged_vertex(s, 0, 1), w1 = nudged_vertex(s, 1, 2),
        w2 = nudged_vertex(s, 2, 1);
    int w2b = nudged_vertex(s, 2, 1), q1 = parallel_end(s, 3, 0, 1);
    int q2 = parallel_end(s, 6, 0, 2), q3 = nudged_vertex(s, parallel_end(s, 5, 1, 2), 1);
    int p0 = sc_plane(s, 0, 1, 2), p1 = sc_plane_rotated(s, w0, w1, w2);
    int p2 = sc_plane(s, 0, 1, w2b), p3 = sc_plane(s, 3, 4, 5), p4 = sc_plane(s, 5, 6, 7);
    sc_tpi(s, p0, p1, p3);
    sc_tpi(s, p0, p2, p3);
    sc_tpi(s, p2, p0, p4);
    sc_tpi(s, p1, p2, p4);
    sc_tpi(s, p3, p0, p4);
    sc_lpi(s, 3, q1, p0);
    sc_lpi(s, 3, q1, p1);
    sc_lpi(s, 6, q2, p2);
    sc_lpi(s, 5, q3, p0);
    sc_lpi(s, 0, 1, p1);
    sc_lpi(s, 0, 1, p3);
    sc_lpi(s, 1, 0, p4);
    sc_explicit(s, 0);
    sc_explicit(s, 1);
    sc_explicit(s, 3);
    sc_line_planes(s, p0, p2);
    sc_line_edge(s, 0, 1);
}

/* ---------------------------------------------------------------- exact lattices */

/* Points off[a] + i[a] * 2^k[a] per axis, i integer. Every integer combination of lattice
 * points computed in integers is an exact double while |off + i| < 2^53 (so the
 * adversarial constructions below are exact by design; check_claims verifies it).
 * Different scales per axis put 3.4e38, 1e-3 and 1e300 into one point. */
typedef struct lattice {
    const char *name;
    int k[3];
    int64_t off[3];
    int count; /* scenarios per adversarial builder at scale 1 */
} lattice;

/* Lattices whose coordinates span a wide range of exponents (and any scenario with an
 * outlier) cost the exact stage far more, hence the smaller counts. */
static const lattice lattices[] = {
    {"int", {0, 0, 0}, {0, 0, 0}, 8},
    {"far", {-20, -20, -20}, {1000000ll << 20, 1000000ll << 20, -(1000000ll << 20)}, 8},
    {"farmix", {-10, -10, -3}, {-(3000000ll << 10), 500000ll << 10, 70000000ll << 3}, 8},
    {"subnormal", {-1074, -1074, -1074}, {0, 0, 0}, 8},
    {"subnormal-off", {-1074, -1074, -1074}, {1ll << 40, -(1ll << 41), 0}, 8},
    {"huge", {985, 985, 985}, {0, 0, 0}, 2},
    {"mixed-axes", {116, -22, 985}, {0, 0, 0}, 2},
    {"mixed-axes2", {-997, 0, -1074}, {0, 1ll << 45, 0}, 2},
    {"tiny-huge-far", {-1000, 900, -30}, {0, 0, 1000000ll << 30}, 2},
};
#define N_LATTICES (int)(sizeof lattices / sizeof lattices[0])

typedef struct ivec {
    int64_t c[3];
} ivec;

static ivec iv_rand(int64_t range)
{
    ivec r;
    for (int k = 0; k < 3; k++)
        r.c[k] = rng_int(-(int)range, (int)range);
    return r;
}

/* a + s b */
static ivec iv_axpy(ivec a, int64_t s, ivec b)
{
    for (int k = 0; k < 3; k++)
        a.c[k] += s * b.c[k];
    return a;
}

static ivec iv_sub(ivec a, ivec b) { return iv_axpy(a, -1, b); }

static int lat_vertex(scenario *s, const lattice *L, ivec i)
{
    double x[3];
    for (int k = 0; k < 3; k++)
        x[k] = ldexp((double)(L->off[k] + i.c[k]), L->k[k]);
    return sc_vertex(s, x);
}

/* A vertex far off the lattice (1e300, 3.4e38, 1e-300, ...), used only where it cannot
 * spoil exactness: as a plane's or line's other vertex next to the point of interest. */
static int outlier_vertex(scenario *s)
{
    double x[3];
    draw_vertex(R_MIX, x);
    return sc_vertex(s, x);
}

/* A plane through lattice point X (vertex x), exactly, in one of three ways: X as a
 * vertex (the other two sometimes outliers); c = X + i(X - a) + j(X - b) (X inside the
 * span of a, b, c); X the centroid of a, b, c. */
static int plane_through(scenario *s, const lattice *L, ivec X, int x, int64_t range,
                         int kind)
{
    ivec a = iv_axpy(X, 1, iv_rand(range)), b = iv_axpy(X, 1, iv_rand(range));
    if (kind == 0) {
        bool far = rng_chance(0.3);
        int vb = far ? outlier_vertex(s) : lat_vertex(s, L, a);
        int vc = far ? outlier_vertex(s) : lat_vertex(s, L, b);
        return sc_plane_rotated(s, x, vb, vc);
    }
    if (kind == 1) {
        int i = rng_int(-2, 2), j = rng_int(-2, 2);
        if (i == 0 && j == 0)
            i = 1;
        ivec c = iv_axpy(iv_axpy(X, i, iv_sub(X, a)), j, iv_sub(X, b));
        return sc_plane_rotated(s, lat_vertex(s, L, a), lat_vertex(s, L, b),
                                lat_vertex(s, L, c));
    }
    ivec u = iv_sub(a, X), v = iv_sub(b, X), c = iv_axpy(iv_sub(X, u), -1, v);
    return sc_plane_rotated(s, lat_vertex(s, L, a), lat_vertex(s, L, b),
                            lat_vertex(s, L, c));
}

/* A line through X: X the midpoint, outside the segment, an endpoint (either end), or
 * an endpoint with an outlier as the other. Returns the two vertices in l[]. */
static void line_through(scenario *s, const lattice *L, ivec X, int x, int64_t range,
                         int l[2])
{
    ivec d = iv_rand(range);
    switch (rng_int(0, 4)) {
    case 0:
        l[0] = lat_vertex(s, L, iv_axpy(X, -1, d)),
        l[1] = lat_vertex(s, L, iv_axpy(X, 1, d));
        break;
    case 1:
        l[0] = lat_vertex(s, L, iv_axpy(X, 1, d)),
        l[1] = lat_vertex(s, L, iv_axpy(X, 3, d));
        break;
    case 2:
        l[0] = x, l[1] = lat_vertex(s, L, iv_axpy(X, 1, d));
        break;
    case 3:
        l[0] = lat_vertex(s, L, iv_axpy(X, 1, d)), l[1] = x;
        break;
    default:
        l[0] = x, l[1] = outlier_vertex(s);
        break;
    }
}

/* A plane through three random lattice points (rarely through anything of interest). */
static int lat_random_plane(scenario *s, const lattice *L, int64_t range)
{
    int a = lat_vertex(s, L, iv_rand(range));
    int b = lat_vertex(s, L, iv_rand(range));
    int c = lat_vertex(s, L, iv_rand(range));
    return sc_plane(s, a, b, c);
}

static int64_t lattice_range(void) { return rng_chance(0.3) ? 8 : 1024; }

/* One point X defined many ways: explicit; LPIs of lines through X with planes through
 * X; TPIs of three planes through X. All must be equal and on all those planes. A few
 * unrelated points (one lattice step away, an LPI and a TPI with a plane missing X)
 * keep the comparisons honest. */
static void scenario_same(scenario *s, const lattice *L)
{
    int64_t range = lattice_range();
    ivec X = iv_rand(range);
    int pl[6], lines[4][2], x;
    memset(s, 0, sizeof *s);
    s->cls = class_id("same", "");
    x = lat_vertex(s, L, X);
    for (int k = 0; k < 6; k++)
        s->onpl[s->nonpl++] = pl[k] = plane_through(s, L, X, x, range, k % 3);
    for (int k = 0; k < 4; k++)
        line_through(s, L, X, x, range, lines[k]);
    s->group[s->ngroup++] = sc_explicit(s, x);
    for (int k = 0; k < 4; k++)
        s->group[s->ngroup++] = sc_lpi(s, lines[k][0], lines[k][1], pl[rng_int(0, 5)]);
    for (int k = 0; k < 4; k++) {
        int a = rng_int(0, 5), b = (a + rng_int(1, 5)) % 6, c = rng_int(0, 5);
        while (c == a || c == b)
            c = rng_int(0, 5);
        s->group[s->ngroup++] = sc_tpi(s, pl[a], pl[b], pl[c]);
    }
    s->group_equal = true;
    ivec step = {{0, 0, 0}};
    step.c[rng_int(0, 2)] = rng_chance(0.5) ? 1 : -1;
    int other = lat_random_plane(s, L, range);
    sc_explicit(s, lat_vertex(s, L, iv_axpy(X, 1, step)));
    sc_lpi(s, lines[0][0], lines[0][1], other);
    sc_tpi(s, pl[0], other, pl[1]);
}

/* Points on one line L = e0 e1: lattice points, LPIs of L (given by two different vertex
 * pairs) with other planes, TPIs of two planes through L with a third. LPI(L, Q) and
 * TPI(P, P', Q) are the same point; order along L by planes and by edge. */
static void scenario_line(scenario *s, const lattice *L)
{
    int64_t range = lattice_range();
    ivec e0 = iv_rand(range), d = iv_rand(range / 2 + 1);
    ivec f0 = iv_axpy(e0, rng_int(-3, 3), d), f1 = iv_axpy(e0, rng_int(2, 4), d);
    int ve0, ve1, vf0, vf1, p[4], q[4];
    memset(s, 0, sizeof *s);
    s->cls = class_id("line", "");
    ve0 = lat_vertex(s, L, e0), ve1 = lat_vertex(s, L, iv_axpy(e0, 1, d));
    vf0 = lat_vertex(s, L, f0), vf1 = lat_vertex(s, L, f1);
    p[0] = sc_plane(s, ve0, ve1, lat_vertex(s, L, iv_rand(range)));
    p[1] = sc_plane(s, ve1, ve0, lat_vertex(s, L, iv_rand(range)));
    p[2] = sc_plane(s, vf0, lat_vertex(s, L, iv_rand(range)), vf1);
    p[3] =
        sc_plane(s, rng_chance(0.3) ? outlier_vertex(s) : lat_vertex(s, L, iv_rand(range)),
                 vf1, ve0);
    for (int k = 0; k < 3; k++)
        q[k] = lat_random_plane(s, L, range);
    int far = outlier_vertex(s);
    q[3] = sc_plane_rotated(s, vf0, far, lat_vertex(s, L, iv_rand(range)));
    for (int k = 0; k < 4; k++)
        s->onpl[s->nonpl++] = p[k];
    /* Every point of the scenario is on L: all form the group. */
    sc_explicit(s, ve0);
    sc_explicit(s, ve1);
    sc_explicit(s, vf0);
    sc_explicit(s, vf1);
    sc_lpi(s, ve0, ve1, q[0]);
    sc_lpi(s, vf0, vf1, q[0]);
    sc_lpi(s, vf1, ve0, q[1]);
    sc_lpi(s, ve1, vf0, q[2]);
    sc_lpi(s, ve0, ve1, q[3]);
    sc_tpi(s, p[0], p[1], q[0]);
    sc_tpi(s, p[2], q[1], p[0]);
    sc_tpi(s, q[2], p[3], p[1]);
    sc_tpi(s, p[1], p[2], q[3]);
    for (int k = 0; k < s->npt; k++)
        s->group[s->ngroup++] = k;
    sc_line_planes(s, p[0], p[1]);
    sc_line_planes(s, p[2], p[0]);
    sc_line_planes(s, p[1], p[3]);
    sc_line_planes(s, p[3], p[2]);
    sc_line_edge(s, ve0, ve1);
    sc_line_edge(s, vf1, vf0);
}

/* Exactly degenerate configurations (constructors must say no) next to valid ones:
 * a line parallel to a plane and a line inside it (LPI), parallel planes and three planes
 * through one line (TPI). The +ulp runs turn them into near-degeneracies. */
static void scenario_parallel(scenario *s, const lattice *L)
{
    int64_t range = lattice_range();
    ivec a = iv_rand(range), b = iv_rand(range), c = iv_rand(range), t = iv_rand(range);
    ivec p = iv_rand(range), e0 = iv_rand(range), e1 = iv_rand(range);
    int i = rng_int(-2, 2), j = rng_int(1, 2), va, vb, vc;
    memset(s, 0, sizeof *s);
    s->cls = class_id("par", "");
    va = lat_vertex(s, L, a), vb = lat_vertex(s, L, b), vc = lat_vertex(s, L, c);
    int P = sc_plane(s, va, vb, vc);
    int Pt =
        sc_plane(s, lat_vertex(s, L, iv_axpy(a, 1, t)), lat_vertex(s, L, iv_axpy(b, 1, t)),
                 lat_vertex(s, L, iv_axpy(c, 1, t)));
    int vp = lat_vertex(s, L, p);
    int vq = lat_vertex(s, L, iv_axpy(iv_axpy(p, i, iv_sub(b, a)), j, iv_sub(c, a)));
    int vin0 = lat_vertex(s, L, iv_axpy(a, j, iv_sub(c, b)));
    int vin1 = lat_vertex(s, L, iv_axpy(iv_axpy(b, i, iv_sub(c, a)), -j, iv_sub(b, a)));
    int ve0 = lat_vertex(s, L, e0), ve1 = lat_vertex(s, L, e1);
    int R1 = sc_plane(s, ve0, ve1, lat_vertex(s, L, iv_rand(range)));
    int R2 = sc_plane(s, lat_vertex(s, L, iv_rand(range)), ve1, ve0);
    int R3 = sc_plane(s, ve1, lat_vertex(s, L, iv_axpy(e0, 2, iv_sub(e1, e0))),
                      lat_vertex(s, L, iv_rand(range)));
    int Q = lat_random_plane(s, L, range);
    sc_lpi(s, vp, vq, P);
    sc_lpi(s, vq, vp, Pt);
    sc_lpi(s, vp, vq, Q);
    sc_lpi(s, vin0, vin1, P);
    sc_lpi(s, vin0, vin1, Q);
    sc_lpi(s, ve0, ve1, R3);
    sc_tpi(s, P, Pt, Q);
    sc_tpi(s, R1, R2, R3);
    sc_tpi(s, R1, R2, Q);
    sc_tpi(s, P, R1, Q);
    sc_tpi(s, Pt, R2, R3);
    sc_explicit(s, va);
    sc_explicit(s, vp);
    sc_line_planes(s, R1, R2);
    sc_line_planes(s, R3, R1);
    sc_line_edge(s, ve0, ve1);
}

/* ---------------------------------------------------------------- axis-aligned grids */

/* A grid coordinate: a multiple of 1/4 in [-64, 64] (a plate's holes and bars). */
static double grid_coord(void)
{
    return rng_int(-256, 256) / 4.0;
}

/* A vertex on the grid with coordinate k set to c. */
static int grid_vertex_at(scenario *s, int k, double c)
{
    double x[3] = {grid_coord(), grid_coord(), grid_coord()};
    x[k] = c;
    return sc_vertex(s, x);
}

/* What a plate with a grid of holes is made of: planes x_k = c (three vertices sharing
 * coordinate k; now and then collinear, so that the constructors must say no), lines
 * that are translates of one another along the plane (the holes' wall diagonals), and
 * their LPIs, which lie on one line of the plane: exact zeros in the orientations, on
 * inputs short enough for 128-bit integers once the plane's normal cancels (EVAL(lpi)).
 * A second aligned plane, a general one and TPIs through the aligned ones besides. */
static void scenario_axis_grid(scenario *s)
{
    int k = rng_int(0, 2), i = (k + 1) % 3, j = (k + 2) % 3, pl[3], lines[4][2];
    double c = grid_coord(), d[3], t[3] = {0, 0, 0};
    memset(s, 0, sizeof *s);
    s->cls = class_id("axisgrid", "");
    int a = grid_vertex_at(s, k, c), b = grid_vertex_at(s, k, c);
    int e = rng_chance(0.05) ? a : grid_vertex_at(s, k, c);
    pl[0] = sc_plane_rotated(s, a, b, e);
    pl[1] = sc_plane_rotated(s, grid_vertex_at(s, i, c), grid_vertex_at(s, i, c),
                             grid_vertex_at(s, i, c));
    pl[2] = sc_plane(s, random_vertex(s, R_INT), random_vertex(s, R_INT),
                     grid_vertex_at(s, k, c));
    for (int m = 0; m < 3; m++)
        d[m] = rng_int(-8, 8) / 4.0;
    if (d[k] == 0)
        d[k] = 0.75;
    t[i] = rng_int(-8, 8) / 4.0;
    t[j] = rng_int(-8, 8) / 4.0;
    double base[3] = {grid_coord() / 2, grid_coord() / 2, grid_coord() / 2};
    for (int n = 0; n < 4; n++) {
        double p0[3], p1[3];
        for (int m = 0; m < 3; m++) {
            p0[m] = base[m] + n * t[m];
            p1[m] = p0[m] + d[m];
        }
        lines[n][0] = sc_vertex(s, p0);
        lines[n][1] = sc_vertex(s, p1);
    }
    s->onpl[s->nonpl++] = pl[0];
    for (int n = 0; n < 4; n++)
        s->group[s->ngroup++] = sc_lpi(s, lines[n][rng_int(0, 1)], lines[n][0] ^ lines[n][1] ^
                                       lines[n][rng_int(0, 1)], pl[0]);
    s->group[s->ngroup++] = sc_explicit(s, a);
    s->group[s->ngroup++] = sc_explicit(s, b);
    sc_lpi(s, lines[0][0], lines[0][1], pl[1]);
    sc_lpi(s, lines[1][0], lines[2][1], pl[2]);
    sc_tpi(s, pl[0], pl[1], pl[2]);
}

/* ---------------------------------------------------------------- driver */

static double test_scale(void)
{
    const char *env = getenv("MCSG_TEST_SCALE");
    double f = env ? atof(env) : 1.0;
    return f > 0 ? f : 1.0;
}

static long scaled(long n) { return (long)((double)n * test_scale() + 0.5); }

/* Scenarios per class at MCSG_TEST_SCALE=1, chosen so that the sanitizer (Debug) build
 * stays under 90 s. The exp and mix regimes (and the adversarial lattices with mixed
 * scales) make the exact stage work on integers of ~2000 bits, some 0.2 ms per case, so
 * they get fewer scenarios than the well-scaled regimes. */
static const int random_counts[R_COUNT] = {220, 220, 25, 25, 220, 220, 220, 220};
static const int nearpar_counts[R_COUNT] = {50, 50, 10, 10, 50, 50, 50, 50};

TEST(kernel_random)
{
    scenario s;
    double t = seconds();
    for (int r = 0; r < R_COUNT; r++)
        for (long n = scaled(random_counts[r]); n > 0; n--) {
            scenario_random(&s, r);
            run_scenario(&s);
        }
    printf("  random scenarios: %.1f s\n", seconds() - t);
}

TEST(kernel_near_parallel)
{
    scenario s;
    double t = seconds();
    for (int r = 0; r < R_COUNT; r++)
        for (long n = scaled(nearpar_counts[r]); n > 0; n--) {
            scenario_near_parallel(&s, r);
            run_scenario(&s);
        }
    printf("  nearly parallel scenarios: %.1f s\n", seconds() - t);
}

TEST(kernel_adversarial)
{
    static void (*const builders[])(scenario *, const lattice *) = {
        scenario_same, scenario_line, scenario_parallel};
    static const char *const names[] = {"same+ulp", "line+ulp", "par+ulp"};
    scenario s;
    double t = seconds();
    for (int b = 0; b < 3; b++) {
        int ulp_cls = class_id(names[b], "");
        for (int l = 0; l < N_LATTICES; l++)
            for (long n = scaled(lattices[l].count); n > 0; n--) {
                builders[b](&s, &lattices[l]);
                run_with_perturbations(&s, b == 2 ? 6 : 3, ulp_cls);
            }
    }
    printf("  adversarial scenarios: %.1f s\n", seconds() - t);
}

TEST(kernel_axis_grid)
{
    scenario s;
    double t = seconds();
    int ulp_cls = class_id("axisgrid+ulp", "");
    for (long n = scaled(400); n > 0; n--) {
        scenario_axis_grid(&s);
        run_with_perturbations(&s, 2, ulp_cls);
    }
    printf("  axis-aligned grid scenarios: %.1f s\n", seconds() - t);
}

/* mpq_set_d must be exact on the whole range (the reference relies on it). */
TEST(reference_sanity)
{
    const double xs[] = {0x1p-1074, 3 * 0x1p-1074, 0x1.fffffffffffffp+1023,
                         1e-300,    3.4e38,        -0x1.123456789abcdp-1030};
    mpq_t q;
    mpq_init(q);
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        mpq_set_d(q, xs[i]);
        CHECK(mpq_get_d(q) == xs[i]);
    }
    mpq_clear(q);
}

static void print_class_table(void)
{
    printf("\n%-18s %5s %8s %8s %6s %6s  %6s %6s %6s %6s  %s\n", "class", "scen", "cases",
           "ref=0", "time", "filt%", "o3d%", "cmp%", "o2d%", "ldir%", "mismatch");
    for (int c = 0; c < nclasses; c++) {
        long calls = 0, zero = 0, filt = 0, dec = 0, bad = 0;
        for (int p = 0; p < PR_COUNT; p++) {
            calls += stats[c][p].calls, zero += stats[c][p].zero,
                bad += stats[c][p].mismatches;
            filt += stats[c][p].filt, dec += stats[c][p].decided;
        }
        const pstat *o = stats[c];
        printf(
            "%-18s %5ld %8ld %8ld %5.1fs %5.1f%%  %6.1f %6.1f %6.1f %6.1f  %ld\n",
            class_names[c], class_scenarios[c], calls, zero, class_seconds[c],
            filt ? 100.0 * dec / filt : 0.0,
            100.0 * o[PR_ORIENT3D].decided / (o[PR_ORIENT3D].filt + !o[PR_ORIENT3D].filt),
            100.0 * o[PR_CMP].decided / (o[PR_CMP].filt + !o[PR_CMP].filt),
            100.0 * o[PR_ORIENT2D].decided / (o[PR_ORIENT2D].filt + !o[PR_ORIENT2D].filt),
            100.0 * o[PR_LINEDIR].decided / (o[PR_LINEDIR].filt + !o[PR_LINEDIR].filt),
            bad);
    }
}

static void print_predicate_table(void)
{
    long total = 0;
    printf("\n%-15s %10s %9s %10s %8s %10s %13s %8s\n", "predicate", "cases", "ref=0",
           "filtered", "decided", "of ref!=0", "decided,ref=0", "mismatch");
    for (int p = 0; p < PR_COUNT; p++) {
        pstat t = {0, 0, 0, 0, 0, 0};
        for (int c = 0; c < nclasses; c++) {
            t.calls += stats[c][p].calls, t.zero += stats[c][p].zero;
            t.filt += stats[c][p].filt, t.decided += stats[c][p].decided;
            t.decided_zero += stats[c][p].decided_zero,
                t.mismatches += stats[c][p].mismatches;
        }
        total += t.calls;
        long nonzero = t.filt ? t.calls - t.zero : 0;
        printf("%-15s %10ld %9ld %10ld %7.1f%% %9.1f%% %13ld %8ld\n", pred_names[p],
               t.calls, t.zero, t.filt, t.filt ? 100.0 * t.decided / t.filt : 0.0,
               nonzero ? 100.0 * (t.decided - t.decided_zero) / nonzero : 0.0,
               t.decided_zero, t.mismatches);
    }
    printf("total cases: %ld; cached values with an uninformative bound (inf/NaN): %ld\n",
           total, uninformative_bounds);
    printf("coordinates rounded by mci_point_round (checked nearest): %ld\n", rounded_coordinates);
    printf("coordinates rounded by the double-double stage: %ld of %ld\n", dd_rounded,
           dd_round_tries);
    printf("orient2d box filter: %ld cases, %ld decided\n", box_filter_cases,
           box_filter_decided);
    printf("orient2d cases the first filter left: %ld, double-double stage decided %ld\n",
           dd_after_filter, dd_decided);
    printf("orient3d of input vertices: %ld filter cases, %ld decided by the filter\n",
           vertex_filter_cases, vertex_filter_decided);
    printf("orient3d of input vertices the filter left: %ld, double-double stage decided %ld\n",
           vertex_dd_cases, vertex_dd_decided);
    printf("implicit point boxes: %ld, infinite %ld, tight (1e-10) %ld\n\n", box_points,
           box_infinite, box_tight);
}

static bool same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* The inline steps agree with nextafter on special values and random bit patterns. */
TEST(next_double)
{
    static const double special[] = {0.0, -0.0, 0x1p-1074, -0x1p-1074, 0x1p-1022, -0x1p-1022,
                                     1.0, -1.0, DBL_MAX, -DBL_MAX, INFINITY, -INFINITY};
    for (size_t i = 0; i < sizeof special / sizeof special[0]; i++) {
        double x = special[i];
        CHECK_MSG(same_bits(mci_next_up(x), nextafter(x, INFINITY)), "next_up(%a)", x);
        CHECK_MSG(same_bits(mci_next_down(x), nextafter(x, -INFINITY)), "next_down(%a)", x);
    }
    CHECK(isnan(mci_next_up(NAN)) && isnan(mci_next_down(NAN)));
    for (int i = 0; i < 200000; i++) {
        uint64_t bits = rng_next();
        double x;
        memcpy(&x, &bits, sizeof x);
        if (isnan(x))
            continue;
        CHECK_MSG(same_bits(mci_next_up(x), nextafter(x, INFINITY)), "next_up(%a)", x);
        CHECK_MSG(same_bits(mci_next_down(x), nextafter(x, -INFINITY)), "next_down(%a)", x);
    }
}

/* The bit range read from a double's fields agrees with ilogb and with the lowest set
 * bit of the significand, on special values and random bit patterns. */
static void check_bit_range(double x)
{
    int lsb, msb;
    double scaled;
    mci_bit_range(x, &lsb, &msb);
    CHECK_MSG(msb == ilogb(x), "msb of %a: %d, ilogb %d", x, msb, ilogb(x));
    scaled = ldexp(x, -lsb); /* exact: an odd integer */
    CHECK_MSG(scaled == trunc(scaled) && fmod(scaled, 2.0) != 0, "lsb of %a: %d", x, lsb);
}

TEST(bit_range)
{
    static const double special[] = {0x1p-1074, -0x1p-1074, 0x1.8p-1073, 0x1p-1022,
                                     0x1.fffffffffffffp-1023, 1.0, -1.0, 0.1, 3.0, DBL_MAX,
                                     -DBL_MAX, 0x1p1023};
    for (size_t i = 0; i < sizeof special / sizeof special[0]; i++)
        check_bit_range(special[i]);
    for (int i = 0; i < 200000; i++) {
        uint64_t bits = rng_next();
        double x;
        memcpy(&x, &bits, sizeof x);
        if (isfinite(x) && x != 0)
            check_bit_range(x);
    }
}

/* Exact det[b - a, c - a, d - a] of four doubles, by rationals. */
static int ref_orient3d_doubles(const double *a, const double *b, const double *c,
                                const double *d)
{
    const double *v[3] = {b, c, d};
    mpq_t r[3][3], t, u, det;
    int sign;
    mpq_inits(t, u, det, NULL);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            mpq_init(r[i][k]);
            mpq_set_d(r[i][k], v[i][k]);
            mpq_set_d(t, a[k]);
            mpq_sub(r[i][k], r[i][k], t);
        }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mpq_mul(t, r[1][i], r[2][j]);
        mpq_mul(u, r[1][j], r[2][i]);
        mpq_sub(t, t, u);
        mpq_mul(t, t, r[0][k]);
        mpq_add(det, det, t);
    }
    sign = mpq_sgn(det);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            mpq_clear(r[i][k]);
    mpq_clears(t, u, det, NULL);
    return sign;
}

/* Four vertices in every order, against the reference, through both vertex forms. */
static void check_four_vertices(const double *const q[4], long *zeros)
{
    for (int r = 0; r < 4; r++) {
        const double *a = q[r], *b = q[(r + 1) % 4], *c = q[(r + 2) % 4], *d = q[(r + 3) % 4];
        int ref = ref_orient3d_doubles(a, b, c, d);
        mci_plane plane;
        mci_plane_init(&plane, a, b, c);
        CHECK_MSG(mci_orient3d_vertices(a, b, c, d) == ref, "mci_orient3d_vertices: ref %d",
                  ref);
        CHECK_MSG(mci_orient3d_vertex(d, &plane) == ref, "mci_orient3d_vertex: ref %d", ref);
        *zeros += ref == 0;
    }
}

/* The shapes the coordinate rule and the double-word stage of orient3d of vertices are
 * for: a cylinder's side rectangle and cap (coplanar by their coordinates, which no
 * filter decides), a UV sphere's quad (nearly coplanar after rounding), and each with one
 * coordinate moved by an ulp (then the answer is not 0 for the rule's shapes). */
TEST(vertex_orient3d_shapes)
{
    long zeros = 0, cases = 0;
    for (int i = 0; i < 20000; i++) {
        double t1 = rng_unit() * 6.283185307179586, t2 = t1 + 0.01 + rng_unit() * 0.5;
        double p1 = rng_unit() * 3.14159, p2 = p1 + 0.01 + rng_unit() * 0.3;
        double rad = ldexp(0.5 + rng_unit(), rng_int(-30, 30)), z0 = rng_unit() * rad,
               z1 = z0 + rad * (0.1 + rng_unit());
        double side[4][3] = {{rad * cos(t1), rad * sin(t1), z0},
                             {rad * cos(t2), rad * sin(t2), z0},
                             {rad * cos(t2), rad * sin(t2), z1},
                             {rad * cos(t1), rad * sin(t1), z1}};
        double cap[4][3] = {{0, 0, z0}, {rad * cos(t1), rad * sin(t1), z0},
                            {rad * cos(t2), rad * sin(t2), z0}, {rad * cos(p2), rad * sin(p1), z0}};
        double quad[4][3];
        double (*shapes[3])[3] = {side, cap, quad};
        for (int k = 0; k < 4; k++) {
            double t = k == 0 || k == 3 ? t1 : t2, p = k < 2 ? p1 : p2;
            quad[k][0] = rad * cos(t) * sin(p);
            quad[k][1] = rad * sin(t) * sin(p);
            quad[k][2] = rad * cos(p);
        }
        for (int sh = 0; sh < 3; sh++) {
            const double *q[4] = {shapes[sh][0], shapes[sh][1], shapes[sh][2], shapes[sh][3]};
            int v = rng_int(0, 3), axis = rng_int(0, 2);
            check_four_vertices(q, &zeros);
            shapes[sh][v][axis] = mci_next_up(shapes[sh][v][axis]);
            check_four_vertices(q, &zeros);
            cases += 8;
        }
    }
    printf("vertex orient3d shapes: %ld cases, %ld coplanar\n", cases, zeros);
    CHECK(zeros > cases / 4); /* the rule's shapes were there */
}

/* The coordinates of x cyclically moved by `shift` axes (the shapes below along any axis). */
static void rotate_axes(double x[3], int shift)
{
    double t[3] = {x[0], x[1], x[2]};
    for (int k = 0; k < 3; k++)
        x[(k + shift) % 3] = t[k];
}

/* Two crossings of one plane that contains an axis direction (a side of a cylindrical
 * hole) with two lines whose ends project to the same points along that axis (a
 * cylinder's top and bottom cap edges): equal on the two other axes by definition
 * (mci_compare_coord's rule), and compared with the exact stage on every axis, also
 * after an end is moved by one ulp (the rule must then not apply). */
TEST(lpi_equal_by_projection)
{
    long cases = 0, equal = 0;
    for (int i = 0; i < 20000; i++) {
        double r = 0.2 + rng_unit(), big = 5 + 5 * rng_unit(), t1 = rng_unit() * 6.2831853;
        double t2 = t1 + 0.05 + rng_unit() * 0.5, u = rng_unit() * 6.2831853;
        double cx = (big - 2 * r) * cos(u + 0.01), cy = (big - 2 * r) * sin(u + 0.01);
        double z0 = -1 - rng_unit(), z1 = 1 + rng_unit();
        double v[7][3] = {{cx + r * cos(t1), cy + r * sin(t1), 2 * z0},
                          {cx + r * cos(t2), cy + r * sin(t2), 2 * z0},
                          {cx + r * cos(t1), cy + r * sin(t1), 2 * z1},
                          {0, 0, z1}, {big * cos(u), big * sin(u), z1},
                          {0, 0, z0}, {big * cos(u), big * sin(u), z0}};
        int shift = rng_int(0, 2), moved = rng_int(0, 1);
        mci_plane plane;
        mci_point a, b;
        for (int k = 0; k < 7; k++)
            rotate_axes(v[k], shift);
        if (moved) /* one end of the lower line moved across: no longer the same projection */
            v[6][(shift + rng_int(0, 1)) % 3] = mci_next_up(v[6][(shift + rng_int(0, 1)) % 3]);
        mci_plane_init(&plane, v[0], v[1], v[2]);
        if (!mci_point_lpi(&a, v[3], v[4], &plane) || !mci_point_lpi(&b, v[5], v[6], &plane))
            continue;
        for (int axis = 0; axis < 3; axis++) {
            int got = mci_compare_coord(&a, &b, axis), ref = mci_compare_coord_exact(&a, &b, axis);
            CHECK_MSG(got == ref, "case %d axis %d (shift %d, moved %d): %d, exact %d", i, axis,
                      shift, moved, got, ref);
            equal += ref == 0;
        }
        cases++;
    }
    printf("lpi equal by projection: %ld pairs, %ld equal coordinates\n", cases, equal);
    CHECK(cases > 10000 && equal > cases / 2); /* the rule's shapes were there */
}

int main(void)
{
    const char *seed = getenv("MCSG_TEST_SEED");
    if (seed)
        rng_state = strtoull(seed, NULL, 0);
    printf("seed 0x%llx, scale %g\n", (unsigned long long)rng_state, test_scale());
    ws_init();
    RUN(next_double);
    RUN(bit_range);
    RUN(vertex_orient3d_shapes);
    RUN(lpi_equal_by_projection);
    RUN(reference_sanity);
    RUN(kernel_adversarial);
    RUN(kernel_near_parallel);
    RUN(kernel_random);
    RUN(kernel_axis_grid);
    print_class_table();
    print_predicate_table();
    /* The box filter's check was not vacuous: it decided some cases and left others. */
    CHECK(box_filter_decided > 0 && box_filter_decided < box_filter_cases);
    ws_clear();
    return test_summary();
}
