/*
 * Exact plane-based kernel (see kernel.h and docs/exact-arithmetic.md).
 *
 * Follows the plane-based representation of Sugihara & Iri and Campen & Kobbelt, with
 * points defined implicitly by the input, and the filtered-then-exact evaluation of
 * Shewchuk; implicit points are kept in the "indirect" homogeneous form of Attene
 * (2020, "Indirect predicates for geometric constructions"): base vertex plus an offset
 * (Y, W), so that predicates evaluate small local differences.
 *
 * Filter: every double operation carries a running bound (mci_fv). For v = a op b
 * computed in round-to-nearest with unit roundoff u = 2^-53:
 *   add/sub: e = ea + eb + u|v| + eta
 *   mul:     e = |a|eb + |b|ea + ea eb + u|v| + eta
 * where eta = 2^-1074 covers underflow (a subnormal result's absolute rounding error).
 * The sign of v is certain when |v| > e (1 + 2^-30): the factor absorbs the rounding of
 * the bound's own computation (relative error below 3u per operation, and predicates are
 * far shallower than 2^20 operations). An overflow makes v or e infinite or NaN, and the
 * comparison then fails, so overflow always falls through to the exact stage.
 *
 * Exact stage: all input coordinates of one predicate are scaled to integers at their
 * smallest lsb exponent and the same formulas are evaluated with mci_big.
 */
#include "exact/kernel.h"
#include "exact/big.h"
#include "exact/exact_cache.h"
#include "exact/predicates.h"
#include "exact/wide.h"

#include <float.h>
#include <limits.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

#define UNIT_ROUNDOFF 0x1p-53
#define UNDERFLOW_ERROR 0x1p-1074
#define BOUND_SAFETY (1.0 + 0x1p-30)

/* ---------------------------------------------------------------------------------- */
/* Filtered arithmetic                                                                 */

static inline mci_fv fv_exact(double x)
{
    return (mci_fv){x, 0.0};
}

static inline mci_fv fv_add(mci_fv a, mci_fv b)
{
    double v = a.v + b.v;
    return (mci_fv){v, a.e + b.e + UNIT_ROUNDOFF * fabs(v) + UNDERFLOW_ERROR};
}

static inline mci_fv fv_sub(mci_fv a, mci_fv b)
{
    double v = a.v - b.v;
    return (mci_fv){v, a.e + b.e + UNIT_ROUNDOFF * fabs(v) + UNDERFLOW_ERROR};
}

static inline mci_fv fv_mul(mci_fv a, mci_fv b)
{
    double v = a.v * b.v;
    return (mci_fv){v, fabs(a.v) * b.e + fabs(b.v) * a.e + a.e * b.e +
                           UNIT_ROUNDOFF * fabs(v) + UNDERFLOW_ERROR};
}

static inline mci_fv fv_neg(mci_fv a)
{
    return (mci_fv){-a.v, a.e};
}

/* Difference of two input coordinates. */
static inline mci_fv fv_diff(double a, double b)
{
    return fv_sub(fv_exact(a), fv_exact(b));
}

static inline int fv_sign(mci_fv a)
{
    if (a.e == 0)
        return (a.v > 0) - (a.v < 0);
    if (fabs(a.v) > a.e * BOUND_SAFETY)
        return a.v > 0 ? 1 : -1;
    return MCI_UNCERTAIN;
}

static mci_fv fv_dot(const mci_fv x[3], const mci_fv y[3])
{
    return fv_add(fv_add(fv_mul(x[0], y[0]), fv_mul(x[1], y[1])), fv_mul(x[2], y[2]));
}

/* Component k of x cross y. */
static mci_fv fv_cross_component(const mci_fv x[3], const mci_fv y[3], int k)
{
    int i = (k + 1) % 3, j = (k + 2) % 3;
    return fv_sub(fv_mul(x[i], y[j]), fv_mul(x[j], y[i]));
}

/* Determinant of the rows r0, r1, r2. */
static mci_fv fv_det3(const mci_fv r0[3], const mci_fv r1[3], const mci_fv r2[3])
{
    mci_fv c[3];
    for (int k = 0; k < 3; k++)
        c[k] = fv_cross_component(r1, r2, k);
    return fv_dot(r0, c);
}

/* ---------------------------------------------------------------------------------- */
/* Exact stage: two instantiations of the same formulas                                */

int mci_point_vertex_count(const mci_point *p)
{
    return p->kind == MCI_POINT_EXPLICIT ? 1 : p->kind == MCI_POINT_LPI ? 5 : 9;
}

/* The axis k when an LPI's plane is x_k = const (its three vertices share coordinate k),
 * else -1. Such a plane's normal is (0, 0, n_k) up to order, and n_k cancels from
 * Y / W: W = (q - p)_k, Y = (q - p) (a - p)_k, of degrees 1 and 2 instead of 3 and 4.
 * Axis-aligned input (CAD plates, grids of holes) is full of these, and the lower
 * degree keeps their exact zeros within 128-bit integers. */
static int lpi_plane_axis(const mci_point *p)
{
    for (int k = 0; k < 3; k++)
        if (p->v[2][k] == p->v[3][k] && p->v[2][k] == p->v[4][k])
            return k;
    return -1;
}

/* Degrees of a point's X (offset from an origin vertex) and W in the coordinates. */
static int x_degree(const mci_point *p)
{
    if (p->kind == MCI_POINT_LPI)
        return lpi_plane_axis(p) >= 0 ? 2 : 4;
    return p->kind == MCI_POINT_EXPLICIT ? 1 : 7;
}

static int w_degree(const mci_point *p)
{
    return x_degree(p) - 1;
}

/* The integer scale of one predicate's inputs: e0 is the smallest lsb exponent (every
 * coordinate is an integer multiple of 2^e0), top the largest msb exponent. */
typedef struct input_scale {
    int e0, top;
} input_scale;

static void scale_vertices(input_scale *s, const double *const *v, int n)
{
    for (int i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) {
            double x = v[i][k];
            int lsb, msb;
            if (x == 0)
                continue;
            mci_bit_range(x, &lsb, &msb);
            s->e0 = lsb < s->e0 ? lsb : s->e0;
            s->top = msb > s->top ? msb : s->top;
        }
    }
}

static input_scale scale_of(const mci_point *const *points, int npoints,
                            const mci_plane *const *planes, int nplanes)
{
    input_scale s = {INT_MAX, INT_MIN};
    for (int i = 0; i < npoints; i++)
        scale_vertices(&s, points[i]->v, mci_point_vertex_count(points[i]));
    for (int i = 0; i < nplanes; i++) {
        const double *v[3] = {planes[i]->a, planes[i]->b, planes[i]->c};
        scale_vertices(&s, v, 3);
    }
    if (s.e0 == INT_MAX) /* every coordinate is zero */
        s.e0 = s.top = 0;
    return s;
}

/* Whether every intermediate of a polynomial of this degree fits a signed 128-bit
 * integer. Scaled coordinates are below 2^(top+1-e0), differences below 2^D with
 * D = top + 2 - e0. Each formula of the kernel stays below 2^(degree (D + 1) + 8): a
 * normal is below 2^(2D+1), a TPI's W below 2^(6D+6) and X below 2^(7D+9), orient2d of
 * three TPIs below 2^(20D+27), and so on (docs/exact-arithmetic.md lists each). */
static bool fits_i128(input_scale s, int degree)
{
    return degree * (s.top + 2 - s.e0 + 1) + 8 <= 126;
}

__extension__ typedef __int128 i128;
__extension__ typedef unsigned __int128 u128;

static i128 i128_from_double(double x, int e0)
{
    uint64_t m;
    int e;
    u128 magnitude;
    if (x == 0)
        return 0;
    /* x 2^-e0 is an integer (e0 is at most x's lowest bit exponent); multiplying by a
     * normal power of two is exact, and so is the conversion below 2^63. */
    if (e0 >= -1023 && e0 <= 1022) {
        uint64_t bits = (uint64_t)(1023 - e0) << 52;
        double scale, scaled;
        memcpy(&scale, &bits, sizeof scale);
        scaled = x * scale;
        if (scaled > -0x1p63 && scaled < 0x1p63)
            return (i128)(int64_t)scaled;
    }
    mci_split_double(x, &m, &e);
    magnitude = (u128)m << (e - e0);
    return x < 0 ? -(i128)magnitude : (i128)magnitude;
}

#define NUM i128
#define NUM_FROM_DOUBLE(r, x, e0) (*(r) = i128_from_double((x), (e0)))
#define NUM_ADD(r, a, b) (*(r) = *(a) + *(b))
#define NUM_SUB(r, a, b) (*(r) = *(a) - *(b))
#define NUM_MUL(r, a, b) (*(r) = *(a) * *(b))
#define NUM_SET_INT(r, i) (*(r) = (i))
#define NUM_SIGN(a) ((*(a) > 0) - (*(a) < 0))
#define EVAL(name) i128_##name
#include "exact/kernel_eval.inc"

#define NUM mci_big
#define NUM_FROM_DOUBLE(r, x, e0) mci_big_from_double((r), (x), (e0))
#define NUM_ADD(r, a, b) mci_big_add((r), (a), (b))
#define NUM_SUB(r, a, b) mci_big_sub((r), (a), (b))
#define NUM_MUL(r, a, b) mci_big_mul((r), (a), (b))
#define NUM_SET_INT(r, i) mci_big_set_int((r), (i))
#define NUM_SIGN(a) mci_big_sign(a)
#define EVAL(name) big_##name
#include "exact/kernel_eval.inc"

/* ---------------------------------------------------------------------------------- */
/* The exact stage in short integers (exact/wide.h)                                    */

/* Whether a point's scaled coordinates fit the short path below: differences below
 * 2^62 (D = top + 2 - e0 <= 62), so they are int64, a normal's components (below
 * 2^(2D+1)) __int128, and an LPI's numbers (below 2^(4D+4)) and a TPI's (below
 * 2^(7D+9), the bound of fits_i128) stay below 2^511, within mci_wide. */
static bool fits_short(input_scale s)
{
    return s.top + 2 - s.e0 <= 62;
}

/* The scaled coordinates x 2^-e0 of a point's defining vertices (each below 2^61
 * under fits_short), converted once: each vertex enters several differences. */
static void scaled_vertices(int64_t c[9][3], const mci_point *p, int e0)
{
    for (int i = 0; i < mci_point_vertex_count(p); i++)
        for (int k = 0; k < 3; k++)
            c[i][k] = (int64_t)i128_from_double(p->v[i][k], e0);
}

static void short_vector(int64_t r[3], const int64_t a[3], const int64_t b[3])
{
    for (int k = 0; k < 3; k++)
        r[k] = a[k] - b[k];
}

/* Normal (b - a) x (c - a) of the plane through a, b, c: components below 2^(2D+1). */
static void short_normal(i128 n[3], const int64_t a[3], const int64_t b[3], const int64_t c[3])
{
    int64_t d1[3], d2[3];
    short_vector(d1, b, a);
    short_vector(d2, c, a);
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        n[k] = (i128)d1[i] * d2[j] - (i128)d1[j] * d2[i];
    }
}

/* r = n . v. */
static void short_dot(mci_wide *r, const mci_wide n[3], const int64_t v[3])
{
    mci_wide t;
    mci_wide_mul_i64(r, &n[0], v[0]);
    for (int k = 1; k < 3; k++) {
        mci_wide_mul_i64(&t, &n[k], v[k]);
        mci_wide_add(r, r, &t);
    }
}

/* r = n . v for a normal n in __int128 (products below 2^(3D+1)). */
static void lpi_dot(mci_wide4 *r, const i128 n[3], const int64_t v[3])
{
    mci_wide4 t;
    mci_wide4_mul_i128_i64(r, n[0], v[0]);
    for (int k = 1; k < 3; k++) {
        mci_wide4_mul_i128_i64(&t, n[k], v[k]);
        mci_wide4_add(r, r, &t);
    }
}

/* The general LPI's numbers from the origin (l0 its base, n its plane's normal):
 * W = n . u and s = n . (a - l0) below 2^(3D+3), x[k] = u_k s + l0_k W below 2^(4D+4),
 * all within four limbs. */
static void lpi_general(mci_wide x[3], mci_wide *w, const int64_t l0[3], const i128 n[3],
                        const int64_t u[3], const int64_t to_plane[3])
{
    mci_wide4 w4, s4;
    lpi_dot(&w4, n, u);
    lpi_dot(&s4, n, to_plane);
    for (int k = 0; k < 3; k++) {
        mci_wide4 a, b;
        mci_wide4_mul_i64(&a, &s4, u[k]);
        mci_wide4_mul_i64(&b, &w4, l0[k]);
        mci_wide4_add(&a, &a, &b);
        mci_wide_from_wide4(&x[k], &a);
    }
    mci_wide_from_wide4(w, &w4);
}

/* The LPI numbers of EVAL(lpi) (the reduced formula on an axis-aligned plane, whose
 * numbers fit __int128), from the origin: x[k] = u_k s + l0_k W. */
static void short_lpi(mci_wide x[3], mci_wide *w, const mci_point *p, int e0)
{
    int64_t c[9][3], u[3], to_plane[3];
    int axis = lpi_plane_axis(p);
    scaled_vertices(c, p, e0);
    short_vector(u, c[1], c[0]);
    short_vector(to_plane, c[2], c[0]);
    if (axis < 0) {
        i128 n[3];
        short_normal(n, c[2], c[3], c[4]);
        lpi_general(x, w, c[0], n, u, to_plane);
        return;
    }
    mci_wide_from_i128(w, u[axis]);
    for (int k = 0; k < 3; k++)
        mci_wide_from_i128(&x[k], (i128)u[k] * to_plane[axis] + (i128)c[0][k] * u[axis]);
}

/* Determinant of rows given by pointers to entries, expanded along row 0. */
static void short_det3(mci_wide *r, const mci_wide *m[3][3])
{
    mci_wide_from_i128(r, 0);
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mci_wide t, u;
        mci_wide_mul(&t, m[1][i], m[2][j]);
        mci_wide_mul(&u, m[1][j], m[2][i]);
        mci_wide_sub(&t, &t, &u);
        mci_wide_mul(&t, m[0][k], &t);
        mci_wide_add(r, r, &t);
    }
}

/* The TPI numbers of EVAL(tpi) from the origin: W = det N, x[col] = Cramer's numerator
 * for col (N with that column replaced by the right-hand sides) + base_col W. */
static void short_tpi(mci_wide x[3], mci_wide *w, const mci_point *p, int e0)
{
    int64_t c[9][3];
    mci_wide n[3][3], rhs[3];
    const mci_wide *m[3][3];
    scaled_vertices(c, p, e0);
    for (int i = 0; i < 3; i++) {
        int64_t to_plane[3];
        i128 normal[3];
        short_normal(normal, c[3 * i], c[3 * i + 1], c[3 * i + 2]);
        for (int k = 0; k < 3; k++)
            mci_wide_from_i128(&n[i][k], normal[k]);
        short_vector(to_plane, c[3 * i], c[0]);
        short_dot(&rhs[i], n[i], to_plane);
    }
    for (int col = -1; col < 3; col++) {
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                m[i][k] = k == col ? &rhs[i] : &n[i][k];
        short_det3(col < 0 ? w : &x[col], m);
    }
    for (int k = 0; k < 3; k++) {
        mci_wide t;
        mci_wide_mul_i64(&t, w, c[0][k]);
        mci_wide_add(&x[k], &x[k], &t);
    }
}

/* A point's numbers from the origin under fits_short: those of EVAL(point_at). */
static void short_point(mci_wide x[3], mci_wide *w, const mci_point *p, int e0)
{
    if (p->kind == MCI_POINT_EXPLICIT) {
        mci_wide_from_i128(w, 1);
        for (int k = 0; k < 3; k++)
            mci_wide_from_i128(&x[k], i128_from_double(p->v[0][k], e0));
    } else if (p->kind == MCI_POINT_LPI) {
        short_lpi(x, w, p, e0);
    } else {
        short_tpi(x, w, p, e0);
    }
}

static int wide4_sign(const mci_wide4 *a)
{
    if (a->limb[3] >> 63)
        return -1;
    return (a->limb[0] | a->limb[1] | a->limb[2] | a->limb[3]) != 0;
}

/* The sign of EVAL(w_sign)'s W under fits_short: an LPI's by the general formula (an
 * LPI's W on an axis-aligned plane is computed there too, see EVAL(lpi)), a TPI's the
 * determinant of its normals. */
static int short_w_sign(const mci_point *p, int e0)
{
    int64_t c[9][3], u[3];
    mci_wide n[3][3], w;
    const mci_wide *m[3][3];
    scaled_vertices(c, p, e0);
    if (p->kind == MCI_POINT_LPI) {
        i128 normal[3];
        mci_wide4 w4;
        short_vector(u, c[1], c[0]);
        short_normal(normal, c[2], c[3], c[4]);
        lpi_dot(&w4, normal, u);
        return wide4_sign(&w4);
    }
    for (int i = 0; i < 3; i++) {
        i128 normal[3];
        short_normal(normal, c[3 * i], c[3 * i + 1], c[3 * i + 2]);
        for (int k = 0; k < 3; k++) {
            mci_wide_from_i128(&n[i][k], normal[k]);
            m[i][k] = &n[i][k];
        }
    }
    short_det3(&w, m);
    return mci_wide_sign(&w);
}

/* ---------------------------------------------------------------------------------- */
/* Planes and points                                                                   */

bool mci_vertex_before(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k];
    return (uintptr_t)a < (uintptr_t)b;
}

bool mci_plane_before(const mci_plane *p, const mci_plane *q)
{
    const double *a[3] = {p->a, p->b, p->c}, *b[3] = {q->a, q->b, q->c};
    for (int i = 0; i < 3; i++)
        if (a[i] != b[i])
            return mci_vertex_before(a[i], b[i]);
    return false;
}

void mci_plane_init(mci_plane *plane, const double *a, const double *b, const double *c)
{
    mci_fv d1[3], d2[3];
    plane->a = a;
    plane->b = b;
    plane->c = c;
    for (int k = 0; k < 3; k++) {
        d1[k] = fv_diff(b[k], a[k]);
        d2[k] = fv_diff(c[k], a[k]);
    }
    for (int k = 0; k < 3; k++)
        plane->n[k] = fv_cross_component(d1, d2, k);
}

void mci_point_explicit(mci_point *p, const double *x)
{
    memset(p, 0, sizeof *p);
    p->kind = MCI_POINT_EXPLICIT;
    p->v[0] = x;
    p->w = fv_exact(1.0);
    p->w_sign = 1;
    memcpy(p->c, x, sizeof p->c);
    p->r = 0;
    p->exact_axes = 7;
}

/* A certified box from the cached Y and W (the cached box's source). */
static void compute_bounds(const mci_point *p, double lo[3], double hi[3])
{
    double wl = p->w.v - p->w.e, wh = p->w.v + p->w.e;
    /* Reciprocals instead of six divisions: one more rounding, well within the slack. */
    double inv_wl = 1 / wl, inv_wh = 1 / wh;
    for (int k = 0; k < 3; k++) {
        double base = p->v[0][k], yl, yh, ql, qh, slack;
        lo[k] = hi[k] = base;
        if (p->kind == MCI_POINT_EXPLICIT)
            continue;
        yl = p->y[k].v - p->y[k].e;
        yh = p->y[k].v + p->y[k].e;
        /* Interval quotient for W > 0; the slack covers the rounding of these few
         * operations (relative) and underflow (absolute). */
        ql = yl >= 0 ? yl * inv_wh : yl * inv_wl;
        qh = yh >= 0 ? yh * inv_wl : yh * inv_wh;
        slack = 0x1p-48 * (fabs(base) + mci_max(fabs(ql), fabs(qh))) + 0x1p-1060;
        lo[k] = base + ql - slack;
        hi[k] = base + qh + slack;
        if (!(wl > 0) || !(lo[k] <= hi[k])) {
            lo[k] = -INFINITY;
            hi[k] = INFINITY;
        }
    }
}

/* A point of nearly parallel planes has a W that is tiny against its error bound, so
 * its box is wide: every predicate on it would go to the exact stage, and every box test
 * against it (sweeps, the point numbering) would pass. Its correctly rounded coordinates
 * are computed once instead, exactly, and bound it within a unit in the last place each.
 * "Wide" only chooses the cheaper path; both boxes are certified. */
#define WIDE_BOX_RELATIVE 0x1p-26

static void tighten_wide_box(mci_point *p)
{
    double rounded[3], largest = 0, r = 0;
    for (int k = 0; k < 3; k++)
        if (!((p->exact_axes >> k) & 1))
            largest = mci_max(largest, fabs(p->c[k]));
    if (!(p->r > largest * WIDE_BOX_RELATIVE))
        return;
    mci_point_round(p, rounded);
    for (int k = 0; k < 3; k++) {
        if ((p->exact_axes >> k) & 1)
            continue;
        if (!isfinite(rounded[k]) || fabs(rounded[k]) == DBL_MAX)
            return; /* beyond the double range: keep the wide box */
        /* the exact coordinate is within half the gap on its side of the rounded one */
        r = mci_max(r, mci_max(mci_next_up(rounded[k]) - rounded[k],
                               rounded[k] - mci_next_down(rounded[k])));
    }
    for (int k = 0; k < 3; k++)
        if (!((p->exact_axes >> k) & 1))
            p->c[k] = rounded[k];
    p->r = r;
    p->ill_conditioned = 1;
}

/* The cached box of a constructed point (see mci_point): centre and radius from the
 * certified bounds (infinite radius when they are), then the coordinates the definition
 * fixes exactly. */
static void set_box(mci_point *p, const double exact[3], unsigned exact_axes)
{
    double lo[3], hi[3];
    compute_bounds(p, lo, hi);
    p->r = 0;
    for (int k = 0; k < 3; k++) {
        double c = lo[k] / 2 + hi[k] / 2;
        /* |c - lo|, |hi - c| <= (hi - lo) / 2 up to the rounding of c and the halving */
        double r = mci_max(hi[k] - c, c - lo[k]) * (1 + 0x1p-50) + 0x1p-1070;
        p->c[k] = isfinite(c) ? c : 0;
        p->r = mci_max(p->r, isfinite(c) && isfinite(r) ? r : INFINITY);
    }
    p->exact_axes = (uint8_t)exact_axes;
    p->ill_conditioned = 0;
    for (int k = 0; k < 3; k++)
        if ((exact_axes >> k) & 1)
            p->c[k] = exact[k];
    tighten_wide_box(p);
}

/* Axis k if the plane's three vertices share coordinate k (the plane is x_k = const),
 * else -1. */
static int aligned_axis(const mci_plane *plane)
{
    for (int k = 0; k < 3; k++)
        if (plane->a[k] == plane->b[k] && plane->a[k] == plane->c[k])
            return k;
    return -1;
}

/* Exact sign of a constructed point's W, computed from scratch. */
static int exact_w_sign(const mci_point *p)
{
    input_scale s = scale_of(&p, 1, NULL, 0);
    /* The degree bound is X's, as for the other predicates (W alone is of lower degree);
     * an LPI's W is the general formula's here (see EVAL(lpi)). */
    if (fits_i128(s, p->kind == MCI_POINT_LPI ? 4 : x_degree(p)))
        return i128_w_sign(p, s.e0);
    if (fits_short(s) && p->kind != MCI_POINT_EXPLICIT)
        return short_w_sign(p, s.e0);
    return big_w_sign(p, s.e0);
}

/* Make the stored W positive (negating the offsets with it); false if W is 0. */
static bool normalize_w(mci_point *p)
{
    int sign = fv_sign(p->w);
    if (sign == MCI_UNCERTAIN)
        sign = exact_w_sign(p);
    if (sign == 0) {
        p->w_sign = 0;
        return false;
    }
    if (sign < 0) {
        p->w = fv_neg(p->w);
        for (int k = 0; k < 3; k++)
            p->y[k] = fv_neg(p->y[k]);
    }
    p->w_sign = 1;
    return true;
}

static void lpi_box(mci_point *p, const double *l0, const double *l1, const mci_plane *plane)
{
    double exact[3];
    unsigned axes = 0;
    int k = aligned_axis(plane);
    for (int j = 0; j < 3; j++) {
        if (l0[j] == l1[j]) { /* the line keeps coordinate j */
            exact[j] = l0[j];
            axes |= 1u << j;
        }
    }
    if (k >= 0) {
        exact[k] = plane->a[k];
        axes |= 1u << k;
    }
    set_box(p, exact, axes);
}

void mci_point_lpi_define(mci_point *p, const double *l0, const double *l1,
                          const mci_plane *plane)
{
    p->kind = MCI_POINT_LPI;
    p->v[0] = l0;
    p->v[1] = l1;
    p->v[2] = plane->a;
    p->v[3] = plane->b;
    p->v[4] = plane->c;
}

bool mci_point_lpi(mci_point *p, const double *l0, const double *l1, const mci_plane *plane)
{
    mci_fv u[3], to_plane[3], s;
    mci_point_lpi_define(p, l0, l1, plane);
    for (int k = 0; k < 3; k++) {
        u[k] = fv_diff(l1[k], l0[k]);
        to_plane[k] = fv_diff(plane->a[k], l0[k]);
    }
    p->w = fv_dot(plane->n, u);
    s = fv_dot(plane->n, to_plane);
    for (int k = 0; k < 3; k++)
        p->y[k] = fv_mul(u[k], s);
    if (!normalize_w(p))
        return false;
    lpi_box(p, l0, l1, plane);
    return true;
}

static void tpi_box(mci_point *p, const mci_plane *const planes[3])
{
    double exact[3];
    unsigned axes = 0;
    for (int i = 0; i < 3; i++) {
        int k = aligned_axis(planes[i]);
        if (k >= 0) {
            exact[k] = planes[i]->a[k];
            axes |= 1u << k;
        }
    }
    set_box(p, exact, axes);
}

bool mci_point_tpi(mci_point *p, const mci_plane *p1, const mci_plane *p2, const mci_plane *p3)
{
    const mci_plane *planes[3] = {p1, p2, p3};
    mci_fv rows[3][3], rhs[3], swapped[3][3];
    p->kind = MCI_POINT_TPI;
    for (int i = 0; i < 3; i++) {
        mci_fv to_plane[3];
        p->v[3 * i] = planes[i]->a;
        p->v[3 * i + 1] = planes[i]->b;
        p->v[3 * i + 2] = planes[i]->c;
        for (int k = 0; k < 3; k++) {
            rows[i][k] = planes[i]->n[k];
            to_plane[k] = fv_diff(planes[i]->a[k], p1->a[k]);
        }
        rhs[i] = i == 0 ? fv_exact(0.0) : fv_dot(planes[i]->n, to_plane);
    }
    p->w = fv_det3(rows[0], rows[1], rows[2]);
    for (int col = 0; col < 3; col++) {
        for (int i = 0; i < 3; i++) {
            for (int k = 0; k < 3; k++)
                swapped[i][k] = k == col ? rhs[i] : rows[i][k];
        }
        p->y[col] = fv_det3(swapped[0], swapped[1], swapped[2]);
    }
    if (!normalize_w(p))
        return false;
    tpi_box(p, planes);
    return true;
}

void mci_point_approx(const mci_point *p, double out[3])
{
    for (int k = 0; k < 3; k++) {
        out[k] = p->v[0][k] + p->y[k].v / p->w.v;
        /* W's approximation can be 0 or of the wrong sign where the filter could not
         * decide it (the exact sign is positive): then compute the point exactly. */
        if (!isfinite(out[k]) || !(p->w.v > 0)) {
            mci_point_round(p, out);
            return;
        }
    }
}

void mci_point_near(const mci_point *p, double out[3])
{
    for (int k = 0; k < 3; k++) {
        double q = p->y[k].v / p->w.v, wl = p->w.v - p->w.e;
        out[k] = p->v[0][k] + q;
        /* The quotient's error bound against the coordinate: three nearly parallel
         * planes give a W so uncertain that the quotient is anywhere (a point of a face
         * computed metres off it). */
        if (!isfinite(out[k]) || !(wl > 0) ||
            !(fabs(q) * p->w.e + p->y[k].e <= 0x1p-26 * wl * (fabs(out[k]) + fabs(q)))) {
            mci_point_round(p, out);
            return;
        }
    }
}

/* Coordinate k of p correctly rounded, when the filter proves it: base + q is summed
 * exactly as hi + lo (two-sum), q's error bound E is certified, and hi is the nearest
 * double to every value within |lo| + E of it (strictly inside its rounding interval,
 * whose half-width is half the smaller gap to a neighbouring double). */
static bool round_filtered(const mci_point *p, int k, double *out, double *guess)
{
    double base = p->v[0][k], y = p->y[k].v, w = p->w.v, wl = w - p->w.e, q, hi, lo, bv;
    double err, gap;
    /* Far from underflow only: the bound below would lose its own tiny terms there. */
    if (!(wl >= 0x1p-900) || !isfinite(y) || !isfinite(p->y[k].e) || !isfinite(p->w.e))
        return false;
    q = y / w;
    err = fabs(q) * (p->w.e / wl) + p->y[k].e / wl + fabs(q) * 0x1p-53;
    err = err * (1 + 0x1p-40) + 0x1p-1060; /* the rounding of this bound itself */
    hi = base + q;
    *guess = hi;
    bv = hi - base;
    lo = (base - (hi - bv)) + (q - bv);
    /* NaN only when hi is not finite, which the test below rejects first. */
    gap = mci_min(mci_next_up(hi) - hi, hi - mci_next_down(hi)) / 2;
    if (!isfinite(hi) || !(fabs(hi) >= 0x1p-900) || !((fabs(lo) + err) * (1 + 0x1p-50) < gap))
        return false;
    *out = hi;
    return true;
}

/* p's numbers from the origin computed in short integers, as mci_big (whose quotient
 * rounds them): the same integers as big_point_at's, at a tenth of the cost. */
static void big_point_from_short(big_point *out, const mci_point *p, int e0)
{
    mci_wide x[3], w;
    short_point(x, &w, p, e0);
    for (int k = 0; k < 4; k++) {
        mci_big *r = k < 3 ? &out->x[k] : &out->w;
        r->size = mci_wide_export(k < 3 ? &x[k] : &w, r->limb, MCI_BIG_LIMBS);
    }
}

void mci_point_round(const mci_point *p, double out[3])
{
    static const double zero[3] = {0, 0, 0};
    big_point exact;
    input_scale s;
    double guess[3] = {0, 0, 0};
    unsigned pending = 0;
    for (int k = 0; k < 3; k++) {
        if (p->kind == MCI_POINT_EXPLICIT)
            out[k] = p->v[0][k];
        else if ((p->exact_axes >> k) & 1) /* the definition fixes this coordinate */
            out[k] = p->c[k];
        else if (!round_filtered(p, k, &out[k], &guess[k]))
            pending |= 1u << k;
    }
    if (pending)
        pending = mci_point_round_dd(p, pending, guess, out);
    if (!pending)
        return;
    /* X / W is the point in units of 2^e0 once X is measured from the origin. */
    s = scale_of(&p, 1, NULL, 0);
    if (fits_short(s))
        big_point_from_short(&exact, p, s.e0);
    else
        big_point_at(&exact, p, zero, s.e0, pending);
    for (int k = 0; k < 3; k++)
        if ((pending >> k) & 1)
            out[k] = mci_big_ratio_to_double(&exact.x[k], &exact.w, s.e0);
}

/* Offset of p from `origin`, scaled by p's W: (base - origin) W + Y. */
static void fv_offset(const mci_point *p, const double *origin, mci_fv out[3])
{
    for (int k = 0; k < 3; k++) {
        if (p->kind == MCI_POINT_EXPLICIT) /* W = 1, Y = 0 */
            out[k] = fv_diff(p->v[0][k], origin[k]);
        else if (p->v[0] == origin)
            out[k] = p->y[k];
        else
            out[k] = fv_add(fv_mul(fv_diff(p->v[0][k], origin[k]), p->w), p->y[k]);
    }
}

/* ---------------------------------------------------------------------------------- */
/* orient3d                                                                            */

int mci_orient3d_filtered(const mci_point *p, const mci_plane *plane)
{
    mci_fv x[3];
    fv_offset(p, plane->a, x);
    return fv_sign(fv_dot(plane->n, x));
}

int mci_orient3d_exact(const mci_point *p, const mci_plane *plane)
{
    input_scale s = scale_of(&p, 1, &plane, 1);
    if (fits_i128(s, x_degree(p) + 2))
        return i128_orient3d(p, plane, s.e0);
    return big_orient3d(p, plane, s.e0);
}

static bool same_coordinates(const double *a, const double *b)
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* An explicit point at p's exact coordinates (p must be exact on every axis). */
static void exact_twin(const mci_point *p, mci_point *twin)
{
    mci_point_explicit(twin, p->c);
}

/* A point at known coordinates (explicit, or exact on every axis) is an input vertex
 * for the predicate: the vertex form decides it without the running bounds. */
int mci_orient3d(const mci_point *p, const mci_plane *plane)
{
    int s;
    if (p->kind == MCI_POINT_EXPLICIT || p->exact_axes == 7)
        return mci_orient3d_vertex(p->c, plane);
    s = mci_orient3d_filtered(p, plane);
    return s != MCI_UNCERTAIN ? s : mci_orient3d_exact(p, plane);
}

/* The double filters of the two vertex predicates below, written out rather than with
 * the running bounds of mci_fv: the pair test asks them six and two times per candidate
 * pair. Differences of doubles are rounded by at most u = 2^-53 relative (exact when
 * subnormal); each product and sum adds u relative and, through underflow, at most
 * 2^-1074 absolute. Any overflow makes the value or the bound inf or NaN, and the
 * comparison in filter_sign is then false: uncertain. */
static int filter_sign(double value, double bound)
{
    if (fabs(value) > bound * BOUND_SAFETY)
        return value > 0 ? 1 : -1;
    return MCI_UNCERTAIN;
}

/* value = n.(x - a) from the plane's cached normal (n_k with error e_k). With d_k the
 * rounded differences and N, D the exact ones: |N.D - n.d| <= (1 + 2u) sum e_k |d_k| +
 * 2u (1 + 2u) sum |n_k d_k|, and rounding the three products and two sums adds
 * 3u (1 + 3u) sum |n_k d_k| + 5 * 2^-1074: 2^-50 (8u) covers both coefficients of
 * sum |n_k d_k|; the (1 + 2u) on the error terms is taken as 1 + 2^-50. */
int mci_orient3d_vertex_filtered(const double *x, const mci_plane *plane)
{
    const mci_fv *n = plane->n;
    double d0 = x[0] - plane->a[0], d1 = x[1] - plane->a[1], d2 = x[2] - plane->a[2];
    double p0 = n[0].v * d0, p1 = n[1].v * d1, p2 = n[2].v * d2;
    double value = p0 + p1 + p2;
    double errors = n[0].e * fabs(d0) + n[1].e * fabs(d1) + n[2].e * fabs(d2);
    double bound = errors * (1 + 0x1p-50) + (fabs(p0) + fabs(p1) + fabs(p2)) * 0x1p-50 +
                   16 * UNDERFLOW_ERROR;
    return filter_sign(value, bound);
}

static bool same_projection(const double *p, const double *q, int axis)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    return p[i] == q[i] && p[j] == q[j];
}

/* Whether four input vertices are coplanar by their coordinates alone: they share a
 * coordinate (a cap, a box's face), or along some axis they project to at most two
 * points (they lie on at most two lines parallel to the axis: a cylinder's side, an
 * extrusion's wall). The filters cannot decide these zeros, and the exact stage costs
 * thousands of instructions each. */
static bool coplanar_by_coordinates(const double *a, const double *b, const double *c,
                                    const double *d)
{
    const double *v[4] = {a, b, c, d};
    for (int k = 0; k < 3; k++) {
        const double *second = NULL;
        bool two = true;
        if (a[k] == b[k] && a[k] == c[k] && a[k] == d[k])
            return true;
        for (int i = 1; i < 4 && two; i++) {
            if (same_projection(v[i], a, k))
                continue;
            if (!second)
                second = v[i];
            else
                two = same_projection(v[i], second, k);
        }
        if (two)
            return true;
    }
    return false;
}

/* The stages after the double filter for an input vertex against the plane of three:
 * the coordinate rule, the double-word stage, then exact. */
static int orient3d_vertex_beyond_filter(const double *x, const mci_plane *plane)
{
    int s;
    mci_point p;
    if (coplanar_by_coordinates(plane->a, plane->b, plane->c, x))
        return 0;
    s = mci_orient3d_vertices_dd(plane->a, plane->b, plane->c, x);
    if (s != MCI_UNCERTAIN)
        return s;
    mci_point_explicit(&p, x);
    return mci_orient3d_exact(&p, plane);
}

/* The same predicate for an input vertex, without building a point. A vertex equal to
 * one that defines the plane lies on it: the common case of shared and duplicated
 * vertices (identical operands), which the filter cannot decide (the value is 0). */
/* The filter first: a sign it gives is exact, and most calls (the pair tests' corner
 * sides) are decided by it; a vertex at one of the plane's corners, whose zero the
 * filter cannot confirm, is then caught before the exact stage. */
int mci_orient3d_vertex(const double *x, const mci_plane *plane)
{
    int s = mci_orient3d_vertex_filtered(x, plane);
    if (s != MCI_UNCERTAIN)
        return s;
    if (same_coordinates(x, plane->a) || same_coordinates(x, plane->b) ||
        same_coordinates(x, plane->c))
        return 0;
    return orient3d_vertex_beyond_filter(x, plane);
}

/* det[b - a, c - a, d - a] in doubles with Shewchuk's bound for orient3d (errboundA =
 * (7 + 56u) u times the permanent, for the same expression from rounded differences;
 * 2^-50 = 8u covers it) plus underflow: a 2x2 minor's products may each lose 2^-1074,
 * which the outer product scales by |r0_k|. */
int mci_orient3d_vertices_filtered(const double *a, const double *b, const double *c,
                                   const double *d)
{
    double r0[3], r1[3], r2[3], m[3], mabs[3], value = 0, permanent = 0, outer = 0;
    for (int k = 0; k < 3; k++) {
        r0[k] = b[k] - a[k];
        r1[k] = c[k] - a[k];
        r2[k] = d[k] - a[k];
    }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        double x = r1[i] * r2[j], y = r1[j] * r2[i];
        m[k] = x - y;
        mabs[k] = fabs(x) + fabs(y);
    }
    for (int k = 0; k < 3; k++) {
        value += r0[k] * m[k];
        permanent += fabs(r0[k]) * mabs[k];
        outer += fabs(r0[k]);
    }
    return filter_sign(value, permanent * 0x1p-50 + (outer + 1) * 16 * UNDERFLOW_ERROR);
}

int mci_orient3d_vertices(const double *a, const double *b, const double *c, const double *d)
{
    int s = mci_orient3d_vertices_filtered(a, b, c, d);
    mci_plane plane;
    mci_point p;
    if (s != MCI_UNCERTAIN)
        return s;
    /* orient3d_vertex_beyond_filter's stages, the plane built only for the last */
    if (coplanar_by_coordinates(a, b, c, d))
        return 0;
    s = mci_orient3d_vertices_dd(a, b, c, d);
    if (s != MCI_UNCERTAIN)
        return s;
    mci_plane_init(&plane, a, b, c);
    mci_point_explicit(&p, d);
    return mci_orient3d_exact(&p, &plane);
}

/* For a and b in one plane with the axis u -> v: whether they are on the same side of
 * it (the first projection where the axis is not a point decides). */
static bool same_side_of_axis(const double *u, const double *v, const double *a,
                              const double *b)
{
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        int sa = mci_orient2d(u[i], u[j], v[i], v[j], a[i], a[j]);
        if (sa != 0)
            return sa == mci_orient2d(u[i], u[j], v[i], v[j], b[i], b[j]);
    }
    return true;
}

int mci_half_plane_class(const double *u, const double *v, const double *r, const double *w)
{
    int t = mci_orient3d_vertices(u, v, r, w);
    if (t != 0)
        return t > 0 ? 1 : 3;
    return same_side_of_axis(u, v, r, w) ? 0 : 2;
}

bool mci_half_plane_before(const double *u, const double *v, const double *r,
                           const double *w1, const double *w2)
{
    int c1 = mci_half_plane_class(u, v, r, w1), c2 = mci_half_plane_class(u, v, r, w2);
    if (c1 != c2)
        return c1 < c2;
    return (c1 == 1 || c1 == 3) && mci_orient3d_vertices(u, v, w1, w2) > 0;
}

/* ---------------------------------------------------------------------------------- */
/* Coordinate comparison, lexicographic order, equality                                */

int mci_compare_coord_filtered(const mci_point *a, const mci_point *b, int axis)
{
    mci_fv xa[3];
    fv_offset(a, b->v[0], xa);
    return fv_sign(fv_sub(fv_mul(xa[axis], b->w), fv_mul(b->y[axis], a->w)));
}

/* ---------------------------------------------------------------------------------- */
/* Exact points from the thread's cache (exact/exact_cache.h)                          */

static const double cache_origin[3] = {0, 0, 0};

/* Quotient limbs kept for a double-word value: 192 bits, where a value has 106. */
#define APPROX_LIMBS 3

/* e's coordinate k as a double-word value into out; false when scaling could leave the
 * normal range. With |x| shifted left by `words` limbs so that the quotient has at least
 * APPROX_LIMBS limbs, |x| / |w| 2^e0 = (q + f) 2^(e0 - 64 words), 0 <= f < 1; the top
 * APPROX_LIMBS limbs of q are kept and the rest, with f, is below one unit of them. */
static bool coordinate_approx(const mci_exact_point *e, int k, double out[3])
{
    int nx = abs(e->size[k]), nw = abs(e->size[3]);
    int words = nw + APPROX_LIMBS > nx ? nw + APPROX_LIMBS - nx : 0, nn = nx + words;
    int qn = nn - nw + 1, base, sign = (e->size[k] < 0) == (e->size[3] < 0) ? 1 : -1;
    mp_limb_t num[2 * MCI_EXACT_LIMBS + APPROX_LIMBS], q[2 * MCI_EXACT_LIMBS + APPROX_LIMBS];
    mp_limb_t rem[MCI_EXACT_LIMBS];
    uint32_t chunk[2 * APPROX_LIMBS];
    if (nx == 0) {
        out[0] = out[1] = out[2] = 0;
        return true;
    }
    memset(num, 0, (size_t)words * sizeof num[0]);
    memcpy(num + words, e->limb[k], (size_t)nx * sizeof num[0]);
    mpn_tdiv_qr(q, rem, 0, num, nn, e->limb[3], nw);
    while (qn > APPROX_LIMBS && q[qn - 1] == 0)
        qn--;
    base = qn - APPROX_LIMBS;
    for (int i = 0; i < APPROX_LIMBS; i++) {
        chunk[2 * i] = (uint32_t)q[base + i];
        chunk[2 * i + 1] = (uint32_t)(q[base + i] >> 32);
    }
    return mci_dd_from_chunks(chunk, 2 * APPROX_LIMBS, e->e0 + 64 * (base - words), sign,
                              out);
}

/* p's exact homogeneous coordinates from the origin in units of 2^e->e0 into e's
 * numbers, for a point under fits_short: the same integers as big_point_at's, at a
 * few hundred instructions a point instead of thousands. False when a number does not
 * fit an entry. */
static bool short_entry_numbers(mci_exact_point *e, const mci_point *p)
{
    mci_wide x[3], w;
    short_point(x, &w, p, e->e0);
    for (int k = 0; k < 4; k++)
        if ((e->size[k] = mci_wide_export(k < 3 ? &x[k] : &w, e->limb[k],
                                          MCI_EXACT_LIMBS)) == INT_MIN)
            return false;
    return true;
}

/* The same numbers in mci_big, for any point. */
static bool big_entry_numbers(mci_exact_point *e, const mci_point *p)
{
    big_point x;
    big_point_at(&x, p, cache_origin, e->e0, 7u); /* every coordinate */
    for (int k = 0; k < 4; k++)
        if ((e->size[k] = mci_big_export(k < 3 ? &x.x[k] : &x.w, e->limb[k],
                                         MCI_EXACT_LIMBS)) == INT_MIN)
            return false;
    return true;
}

/* p's exact coordinates into e (nothing else of e set); false when a number does not
 * fit an entry. */
static bool compute_entry(mci_exact_point *e, const mci_point *p)
{
    const mci_point *points[1] = {p};
    input_scale s = scale_of(points, 1, NULL, 0);
    e->e0 = s.e0;
    if (!(fits_short(s) ? short_entry_numbers(e, p) : big_entry_numbers(e, p)))
        return false;
    e->has_approx = e->size[3] != 0;
    for (int k = 0; k < 3 && e->has_approx; k++)
        e->has_approx = coordinate_approx(e, k, e->approx[k]);
    return true;
}

/* Entry e (p's, from mci_exact_cache_find) made to hold p; false when a number does not
 * fit an entry. */
static bool fill_entry(mci_exact_point *e, const mci_point *p)
{
    if (!compute_entry(e, p)) {
        mci_exact_cache_clear(p); /* e held another point, now overwritten */
        return false;
    }
    mci_exact_cache_claim(e, p);
    return true;
}

bool mci_point_dd_values(const mci_point *p, double approx[3][3])
{
    bool held = false;
    mci_exact_point fresh, *e = mci_exact_cache_find(p, &held);
    /* Computed into the thread's table, where the exact stage finds the point when
     * these values leave a predicate undecided. */
    if (!held && !(e ? fill_entry(e, p) : compute_entry(e = &fresh, p)))
        return false;
    if (!e->has_approx)
        return false;
    memcpy(approx, e->approx, sizeof e->approx);
    return true;
}

/* When cached_points computes the points its cache does not hold yet. */
typedef enum fill_rule {
    FILL_ALWAYS,
    /* Only where a point is held already or ill-conditioned (mci_point): such points
     * come in crowds (crossings of nearly coplanar faces), meet the same predicates
     * again and again, and cost the double-double stage far more each time, from their
     * definitions, than they cost once exactly. Elsewhere that stage decides most cases
     * at a fraction of an exact point's cost. */
    FILL_NEAR_TROUBLE,
    /* Only points held already. */
    FILL_NEVER,
} fill_rule;

/* Entries holding points[0..n) (n <= 3), in distinct slots, computing those not held as
 * `rule` allows; false when the thread has no cache, two points share a slot, or a point
 * is not held (and not computed, or too large for an entry). */
static bool cached_points(const mci_point *const *points, int n, fill_rule rule,
                          mci_exact_point **out)
{
    bool held[3], trouble = false, all_held = true;
    for (int i = 0; i < n; i++) {
        if (!(out[i] = mci_exact_cache_find(points[i], &held[i])) ||
            (rule == FILL_NEVER && !held[i]))
            return false;
        for (int j = 0; j < i; j++)
            if (out[j] == out[i])
                return false;
        trouble |= held[i] || points[i]->ill_conditioned;
        all_held &= held[i];
    }
    if (!all_held && (rule == FILL_NEVER || (rule == FILL_NEAR_TROUBLE && !trouble)))
        return false;
    for (int i = 0; i < n; i++)
        if (!held[i] && !fill_entry(out[i], points[i]))
            return false;
    return true;
}

/* Number k of e (x[0..2], or w for k = 3) times 2^shift. */
static void entry_number(mci_big *r, const mci_exact_point *e, int k, unsigned shift)
{
    mci_big_import(r, e->limb[k], e->size[k]);
    if (shift)
        mci_big_shift_left(r, r, shift);
}

static int entry_w_sign(const mci_exact_point *e)
{
    return (e->size[3] > 0) - (e->size[3] < 0);
}

/* sign(xa / wa 2^ea - xb / wb 2^eb) = sign(xa wb 2^(ea-m) - xb wa 2^(eb-m)) times the
 * signs of wa and wb, m the smaller exponent. */
static int cached_compare_coord(const mci_exact_point *a, const mci_exact_point *b, int axis)
{
    int m = a->e0 < b->e0 ? a->e0 : b->e0;
    mci_big l, r, w;
    if (a->has_approx && b->has_approx) {
        int s = mci_compare_dd_values(a->approx[axis], b->approx[axis]);
        if (s != MCI_UNCERTAIN)
            return s;
    }
    entry_number(&l, a, axis, (unsigned)(a->e0 - m));
    entry_number(&w, b, 3, 0);
    mci_big_mul(&l, &l, &w);
    entry_number(&r, b, axis, (unsigned)(b->e0 - m));
    entry_number(&w, a, 3, 0);
    mci_big_mul(&r, &r, &w);
    mci_big_sub(&l, &l, &r);
    return mci_big_sign(&l) * entry_w_sign(a) * entry_w_sign(b);
}

/* orient2d of the rows (x_i 2^e, x_j 2^e, w): the common factor 2^m of the first two
 * columns (m the smallest exponent) leaves integer rows of the same sign, which is
 * then the sign of the projected points' orientation times the signs of the w. */
static int cached_orient2d(mci_exact_point *const e[3], int axis)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3, m = e[0]->e0, sign = 1;
    mci_big entries[3][3], det;
    const mci_big *rows[3][3];
    if (e[0]->has_approx && e[1]->has_approx && e[2]->has_approx) {
        int s = mci_orient2d_dd_values(e[0]->approx[0], e[1]->approx[0], e[2]->approx[0], axis);
        if (s != MCI_UNCERTAIN)
            return s;
    }
    for (int k = 1; k < 3; k++)
        m = e[k]->e0 < m ? e[k]->e0 : m;
    for (int k = 0; k < 3; k++) {
        unsigned shift = (unsigned)(e[k]->e0 - m);
        entry_number(&entries[k][0], e[k], i, shift);
        entry_number(&entries[k][1], e[k], j, shift);
        entry_number(&entries[k][2], e[k], 3, 0);
        for (int c = 0; c < 3; c++)
            rows[k][c] = &entries[k][c];
        sign *= entry_w_sign(e[k]);
    }
    big_det3(&det, rows);
    return mci_big_sign(&det) * sign;
}

int mci_compare_coord_exact(const mci_point *a, const mci_point *b, int axis)
{
    const mci_point *points[2] = {a, b};
    mci_exact_point *e[2];
    input_scale s = scale_of(points, 2, NULL, 0);
    int da = x_degree(a) + w_degree(b), db = x_degree(b) + w_degree(a);
    if (fits_i128(s, da > db ? da : db))
        return i128_compare_coord(a, b, axis, s.e0);
    if (cached_points(points, 2, FILL_ALWAYS, e))
        return cached_compare_coord(e[0], e[1], axis);
    return big_compare_coord(a, b, axis, s.e0);
}

bool mci_points_same_definition(const mci_point *a, const mci_point *b)
{
    /* Arrangements refer to shared points: one point is often compared with itself. */
    return a == b || (a->kind == b->kind &&
           memcmp(a->v, b->v, (size_t)mci_point_vertex_count(a) * sizeof a->v[0]) == 0);
}

/* Whether the three vertices project to at most two points along axis k: then the
 * plane through them contains the direction of k (its normal's k component is 0). */
static bool plane_along_axis(const double *const v[3], int k)
{
    return same_projection(v[0], v[1], k) || same_projection(v[0], v[2], k) ||
           same_projection(v[1], v[2], k);
}

/* Whether LPIs a and b have equal coordinates on `axis` by their definitions: the same
 * plane, which contains the direction of another axis k, and lines whose ends project
 * to the same two points along k. Plane membership then depends only on the projection
 * along k, where both points are the one crossing of the projected line and plane, so
 * they agree on both axes other than k. Such pairs (a cylinder's top and bottom cap
 * edges cut by one side of a hole: equal x and y, different z) left every filter
 * undecided, and the exact stage took over ten thousand instructions a coordinate (on a
 * cylinder with holes, every comparison that reached it was of this kind). */
static bool equal_by_projection(const mci_point *a, const mci_point *b, int axis)
{
    if (a->kind != MCI_POINT_LPI || b->kind != MCI_POINT_LPI || a->v[2] != b->v[2] ||
        a->v[3] != b->v[3] || a->v[4] != b->v[4])
        return false;
    for (int k = 0; k < 3; k++) {
        if (k == axis || !plane_along_axis(a->v + 2, k))
            continue;
        if ((same_projection(a->v[0], b->v[0], k) && same_projection(a->v[1], b->v[1], k)) ||
            (same_projection(a->v[0], b->v[1], k) && same_projection(a->v[1], b->v[0], k)))
            return true;
    }
    return false;
}

/* Whether input vertex x lies on the plane through v[0..2] (three vertices that span
 * one: they define a point that exists). */
static bool on_plane_of(const double *const v[3], const double *x)
{
    return same_coordinates(x, v[0]) || same_coordinates(x, v[1]) ||
           same_coordinates(x, v[2]) || mci_orient3d_vertices(v[0], v[1], v[2], x) == 0;
}

/* Whether LPIs a and b are one point by their definitions, decided on input vertices
 * (exact predicates far cheaper than comparing the points' coordinates exactly):
 * - the same line and the same plane;
 * - crossing lines: a's line lies in b's plane, b's in a's, and the two lines are
 *   coplanar. They cannot be parallel (b's line lies in a's plane, which a's line
 *   crosses), so they meet, and their common point is on both lines and both planes:
 *   it is a and it is b.
 * Where two triangles' edges meet exactly (boxes, grids, symmetric models), the point
 * is reached both ways, and such pairs were most of the exact comparisons of a Menger
 * sponge. False says nothing. */
static bool equal_by_lines(const mci_point *a, const mci_point *b)
{
    const double *const *pa = a->v + 2, *const *pb = b->v + 2;
    if (a->kind != MCI_POINT_LPI || b->kind != MCI_POINT_LPI)
        return false;
    if ((same_coordinates(a->v[0], b->v[0]) && same_coordinates(a->v[1], b->v[1])) ||
        (same_coordinates(a->v[0], b->v[1]) && same_coordinates(a->v[1], b->v[0])))
        return on_plane_of(pa, pb[0]) && on_plane_of(pa, pb[1]) && on_plane_of(pa, pb[2]);
    return on_plane_of(pb, a->v[0]) && on_plane_of(pb, a->v[1]) &&
           on_plane_of(pa, b->v[0]) && on_plane_of(pa, b->v[1]) &&
           mci_orient3d_vertices(a->v[0], a->v[1], b->v[0], b->v[1]) == 0;
}

/* mci_compare_coord; *same set when a and b are proven one point (every coordinate
 * then compares equal). */
static int compare_coord(const mci_point *a, const mci_point *b, int axis, bool *same)
{
    int s;
    if ((a->exact_axes & b->exact_axes) >> axis & 1)
        return (a->c[axis] > b->c[axis]) - (a->c[axis] < b->c[axis]);
    s = fv_sign(fv_sub((mci_fv){a->c[axis], a->r}, (mci_fv){b->c[axis], b->r}));
    if (s != MCI_UNCERTAIN)
        return s;
    if (mci_points_same_definition(a, b)) {
        *same = true;
        return 0;
    }
    if (equal_by_projection(a, b, axis))
        return 0;
    s = mci_compare_coord_filtered(a, b, axis);
    if (s != MCI_UNCERTAIN)
        return s;
    if (equal_by_lines(a, b)) {
        *same = true;
        return 0;
    }
    return mci_compare_coord_exact(a, b, axis);
}

/* The box test first: it decides most comparisons of distinct points and never returns 0
 * (its error bound is positive), so the definitional equalities may follow it. */
int mci_compare_coord(const mci_point *a, const mci_point *b, int axis)
{
    bool same = false;
    return compare_coord(a, b, axis, &same);
}

int mci_compare_lex(const mci_point *a, const mci_point *b)
{
    bool same = false;
    if (a == b)
        return 0;
    for (int axis = 0; axis < 3 && !same; axis++) {
        int s = compare_coord(a, b, axis, &same);
        if (s != 0)
            return s;
    }
    return 0;
}

bool mci_points_equal(const mci_point *a, const mci_point *b)
{
    return mci_compare_lex(a, b) == 0;
}

/* ---------------------------------------------------------------------------------- */
/* orient2d in a projection                                                            */

int mci_orient2d_projected_filtered(const mci_point *p, const mci_point *q,
                                    const mci_point *r, int axis)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    mci_fv xp[3], xq[3], rows[3][3];
    fv_offset(p, r->v[0], xp);
    fv_offset(q, r->v[0], xq);
    rows[0][0] = xp[i], rows[0][1] = xp[j], rows[0][2] = p->w;
    rows[1][0] = xq[i], rows[1][1] = xq[j], rows[1][2] = q->w;
    rows[2][0] = r->y[i], rows[2][1] = r->y[j], rows[2][2] = r->w;
    return fv_sign(fv_det3(rows[0], rows[1], rows[2]));
}

int mci_orient2d_projected_exact(const mci_point *p, const mci_point *q, const mci_point *r,
                                 int axis)
{
    const mci_point *points[3] = {p, q, r};
    mci_exact_point *e[3];
    input_scale s = scale_of(points, 3, NULL, 0);
    if (fits_i128(s, x_degree(p) + x_degree(q) + x_degree(r)))
        return i128_orient2d(points, axis, s.e0);
    if (cached_points(points, 3, FILL_ALWAYS, e))
        return cached_orient2d(e, axis);
    return big_orient2d(points, axis, s.e0);
}

/* Whether the projected coordinates of p are exact in the box (axes other than axis). */
static bool exact_in_projection(const mci_point *p, int axis)
{
    unsigned need = 7u & ~(1u << axis);
    return (p->exact_axes & need) == need;
}

/* orient2d of the exact centres (all projected coordinates exact): explicit points with
 * those coordinates (the projection axis's coordinate is irrelevant). */
static int orient2d_exact_centres(const mci_point *p, const mci_point *q, const mci_point *r,
                                  int axis)
{
    mci_point tp, tq, tr;
    exact_twin(p, &tp);
    exact_twin(q, &tq);
    exact_twin(r, &tr);
    return mci_orient2d_projected_exact(&tp, &tq, &tr, axis);
}

static bool explicit_twins(const mci_point *a, const mci_point *b)
{
    return a->kind == MCI_POINT_EXPLICIT && b->kind == MCI_POINT_EXPLICIT &&
           same_coordinates(a->v[0], b->v[0]);
}

/* Whether x is an LPI on the line through the explicit points a and b. */
static bool lpi_on_line(const mci_point *x, const mci_point *a, const mci_point *b)
{
    return x->kind == MCI_POINT_LPI && a->kind == MCI_POINT_EXPLICIT &&
           b->kind == MCI_POINT_EXPLICIT &&
           ((same_coordinates(x->v[0], a->v[0]) && same_coordinates(x->v[1], b->v[0])) ||
            (same_coordinates(x->v[0], b->v[0]) && same_coordinates(x->v[1], a->v[0])));
}

/* Collinear by definition: an exact zero, which only the slow exact stage could confirm
 * (a repeated explicit point; a crossing point on a face edge, tested against the edge's
 * ends). */
static bool collinear_by_definition(const mci_point *p, const mci_point *q, const mci_point *r)
{
    return explicit_twins(p, q) || explicit_twins(q, r) || explicit_twins(p, r) ||
           lpi_on_line(r, p, q) || lpi_on_line(q, p, r) || lpi_on_line(p, q, r);
}

/* Whether the coordinates of p's base vertex have at most 11 significant bits (the low
 * 42 bits of each significand are zero): a quick guess that the exact stage may fit
 * 128-bit integers, only used to choose the order of the stages. */
static bool short_base(const mci_point *p)
{
    for (int k = 0; k < 3; k++) {
        uint64_t bits;
        memcpy(&bits, &p->v[0][k], sizeof bits);
        if (bits & ((UINT64_C(1) << 42) - 1))
            return false;
    }
    return true;
}

/* Inputs that fit 128-bit integers (short coordinates: CAD grids) skip the double-double
 * stage: the exact one is cheaper there, and only it decides the exact zeros such inputs
 * are full of. The scale is worth computing for that only when the points' base
 * vertices have short coordinates. MCI_UNCERTAIN for other inputs. */
static int orient2d_short(const mci_point *p, const mci_point *q, const mci_point *r,
                          int axis)
{
    if (short_base(p) && short_base(q) && short_base(r)) {
        const mci_point *points[3] = {p, q, r};
        input_scale sc = scale_of(points, 3, NULL, 0);
        if (fits_i128(sc, x_degree(p) + x_degree(q) + x_degree(r)))
            return i128_orient2d(points, axis, sc.e0);
    }
    return MCI_UNCERTAIN;
}

/* The stages after the box filter. */
static int orient2d_beyond_boxes(const mci_point *p, const mci_point *q, const mci_point *r,
                                 int axis)
{
    int s;
    if (exact_in_projection(p, axis) && exact_in_projection(q, axis) &&
        exact_in_projection(r, axis))
        return orient2d_exact_centres(p, q, r, axis);
    /* Points the thread's cache holds already are decided there before the double
     * filter: they needed the exact stage before, and the filter, whose bound grows with
     * the distances to their far defining vertices, then almost never decides (on a
     * Menger sponge it failed on all of 1.3 million calls, at 470 instructions each).
     * Short coordinates (CAD grids) skip the lookups: the filter and 128-bit integers
     * decide those. */
    if (!(short_base(p) && short_base(q) && short_base(r))) {
        const mci_point *points[3] = {p, q, r};
        mci_exact_point *e[3];
        if (cached_points(points, 3, FILL_NEVER, e))
            return cached_orient2d(e, axis);
    }
    s = mci_orient2d_projected_filtered(p, q, r, axis);
    if (s != MCI_UNCERTAIN)
        return s;
    s = orient2d_short(p, q, r, axis);
    if (s != MCI_UNCERTAIN)
        return s;
    /* Points that needed the exact stage before are in the thread's cache, with their
     * coordinates to 106 bits: that decides before the double-double stage on their
     * definitions, which left them undecided once already (nearly collinear points
     * closer together than the spacing of doubles). */
    {
        const mci_point *points[3] = {p, q, r};
        mci_exact_point *e[3];
        if (cached_points(points, 3, FILL_NEAR_TROUBLE, e))
            return cached_orient2d(e, axis);
    }
    s = mci_orient2d_projected_dd(p, q, r, axis);
    return s != MCI_UNCERTAIN ? s : mci_orient2d_projected_exact(p, q, r, axis);
}

/* The definitional zeros first: callers like the edge tests of arrangements meet them
 * more often than anything else. */
int mci_orient2d_projected(const mci_point *p, const mci_point *q, const mci_point *r,
                           int axis)
{
    int s;
    if (collinear_by_definition(p, q, r))
        return 0;
    s = mci_orient2d_projected_quick(p, q, r, axis);
    return s != MCI_UNCERTAIN ? s : orient2d_beyond_boxes(p, q, r, axis);
}

int mci_orient2d_projected_cheap(const mci_point *p, const mci_point *q, const mci_point *r,
                                 int axis)
{
    int s;
    if (collinear_by_definition(p, q, r))
        return 0;
    if (exact_in_projection(p, axis) && exact_in_projection(q, axis) &&
        exact_in_projection(r, axis))
        return orient2d_exact_centres(p, q, r, axis);
    s = mci_orient2d_projected_filtered(p, q, r, axis);
    return s != MCI_UNCERTAIN ? s : orient2d_short(p, q, r, axis);
}

/* After mci_orient2d_projected_quick: its box filter never returns 0 (the error bound is
 * positive), so skipping the definitional zeros before it changes no answer. */
int mci_orient2d_projected_rest(const mci_point *p, const mci_point *q, const mci_point *r,
                                int axis)
{
    return collinear_by_definition(p, q, r) ? 0 : orient2d_beyond_boxes(p, q, r, axis);
}

/* ---------------------------------------------------------------------------------- */
/* Order along lines                                                                   */

int mci_line_direction_sign_filtered(const mci_plane *p1, const mci_plane *p2, int axis)
{
    return fv_sign(fv_cross_component(p1->n, p2->n, axis));
}

int mci_line_direction_sign_exact(const mci_plane *p1, const mci_plane *p2, int axis)
{
    const mci_plane *planes[2] = {p1, p2};
    input_scale s = scale_of(NULL, 0, planes, 2);
    if (fits_i128(s, 4))
        return i128_direction_sign(p1, p2, axis, s.e0);
    return big_direction_sign(p1, p2, axis, s.e0);
}

static int line_direction_sign(const mci_plane *p1, const mci_plane *p2, int axis)
{
    int s = mci_line_direction_sign_filtered(p1, p2, axis);
    return s != MCI_UNCERTAIN ? s : mci_line_direction_sign_exact(p1, p2, axis);
}

/* Along a line, the order of two of its points is their order in any coordinate in
 * which the direction is nonzero, times the sign of that component. The largest
 * approximate component is tried first: it is nonzero unless the planes are parallel. */
int mci_plane_line_axis(const mci_plane *p1, const mci_plane *p2, int *sign)
{
    double magnitude[3];
    int order[3] = {0, 1, 2};
    for (int k = 0; k < 3; k++)
        magnitude[k] = fabs(fv_cross_component(p1->n, p2->n, k).v);
    for (int m = 0; m < 2; m++) {
        for (int k = 0; k < 2 - m; k++) {
            if (magnitude[order[k]] < magnitude[order[k + 1]]) {
                int t = order[k];
                order[k] = order[k + 1];
                order[k + 1] = t;
            }
        }
    }
    for (int m = 0; m < 3; m++) {
        *sign = line_direction_sign(p1, p2, order[m]);
        if (*sign != 0)
            return order[m];
    }
    return -1;
}

int mci_order_on_plane_line(const mci_point *a, const mci_point *b, const mci_plane *p1,
                            const mci_plane *p2)
{
    int sign, axis = mci_plane_line_axis(p1, p2, &sign);
    return axis < 0 ? 0 : sign * mci_compare_coord(a, b, axis);
}

int mci_order_on_edge_line(const mci_point *a, const mci_point *b, const double *l0,
                           const double *l1)
{
    int axis = 0;
    for (int k = 1; k < 3; k++) {
        if (fabs(l1[k] - l0[k]) > fabs(l1[axis] - l0[axis]))
            axis = k;
    }
    if (l1[axis] == l0[axis])
        return 0;
    return (l1[axis] > l0[axis] ? 1 : -1) * mci_compare_coord(a, b, axis);
}

/* ---------------------------------------------------------------------------------- */
/* Containment in a triangle                                                           */

static int normal_sign_exact(const mci_plane *plane, int axis)
{
    mci_point a, b, c;
    /* n_axis is twice the signed area of the triangle projected along `axis`. */
    mci_point_explicit(&a, plane->a);
    mci_point_explicit(&b, plane->b);
    mci_point_explicit(&c, plane->c);
    return mci_orient2d_projected_exact(&a, &b, &c, axis);
}

int mci_plane_normal_sign(const mci_plane *plane, int axis)
{
    int s = fv_sign(plane->n[axis]);
    return s != MCI_UNCERTAIN ? s : normal_sign_exact(plane, axis);
}

int mci_plane_projection_axis(const mci_plane *plane, int *sign)
{
    int order[3] = {0, 1, 2};
    for (int m = 0; m < 2; m++) {
        for (int k = 0; k < 2 - m; k++) {
            if (fabs(plane->n[order[k]].v) < fabs(plane->n[order[k + 1]].v)) {
                int t = order[k];
                order[k] = order[k + 1];
                order[k + 1] = t;
            }
        }
    }
    for (int m = 0; m < 3; m++) {
        int s = fv_sign(plane->n[order[m]]);
        if (s == MCI_UNCERTAIN)
            s = normal_sign_exact(plane, order[m]);
        if (s != 0) {
            *sign = s;
            return order[m];
        }
    }
    *sign = 0;
    return -1;
}

mci_containment mci_point_in_triangle(const mci_point *p, const mci_plane *triangle,
                                      int *which)
{
    mci_point corner[3];
    int side[3], zeros = 0, sign, axis = mci_plane_projection_axis(triangle, &sign);
    *which = -1;
    if (axis < 0)
        return MCI_OUTSIDE;
    mci_point_explicit(&corner[0], triangle->a);
    mci_point_explicit(&corner[1], triangle->b);
    mci_point_explicit(&corner[2], triangle->c);
    for (int e = 0; e < 3; e++) {
        side[e] = sign * mci_orient2d_projected(&corner[e], &corner[(e + 1) % 3], p, axis);
        if (side[e] < 0)
            return MCI_OUTSIDE;
        zeros += side[e] == 0;
    }
    if (zeros == 0)
        return MCI_INSIDE;
    for (int e = 0; e < 3; e++) {
        if (zeros == 1 && side[e] == 0) {
            *which = e;
            return MCI_ON_EDGE;
        }
        /* Two zero sides meet at the vertex they share: edge e-1 ends where e starts. */
        if (zeros == 2 && side[e] == 0 && side[(e + 2) % 3] == 0) {
            *which = e;
            return MCI_ON_VERTEX;
        }
    }
    return MCI_OUTSIDE; /* not reached for a non-degenerate triangle */
}
