/*
 * Second filter stage: the homogeneous formulas of the exact stage (kernel_eval.inc)
 * evaluated in double-double arithmetic with a running error bound.
 *
 * Why: points of a face that are nearly but not exactly collinear (the crossings of a
 * face with the two triangles of a UV sphere's quad, planar before rounding) leave the
 * double filter undecided although the determinant is far from zero at twice the
 * precision; the exact stage costs tens of thousands of instructions per call there,
 * this one a few thousand.
 *
 * A value is hi + lo with an error bound e: the true value lies within e of hi + lo.
 * The algorithms are those of Joldes, Muller and Popescu (2017, "Tight and rigorous error
 * bounds for basic building blocks of double-word arithmetic"): AccurateDWPlusDW has
 * relative error below 3u^2 / (1 - 4u) and DWTimesDW3 below 4u^2 (u = 2^-53, no underflow
 * or overflow). The bound charges each addition 2^-103 and each product 2^-101 of the
 * result's magnitude (generous), plus 2^-1060 absolute for underflow (a subnormal
 * result's error is below 2^-1074 per floating-point operation, a dozen per step). Error
 * propagation: add e = ex + ey, product e = |x| ey + |y| ex + ex ey. The bound's own
 * rounding is absorbed by the factor (1 + 2^-30) when the sign is read, as in the
 * first filter. Overflow makes a part infinite or NaN, and the sign is then uncertain.
 */
#include "exact/kernel.h"

#include <math.h>

#define DD_REL_ADD 0x1p-103
#define DD_REL_MUL 0x1p-101
#define DD_UNDERFLOW 0x1p-1060
#define DD_BOUND_SAFETY (1.0 + 0x1p-30)

typedef struct dd {
    double hi, lo, e;
} dd;

/* a + b = s + t exactly (Knuth's TwoSum). */
static inline double two_sum(double a, double b, double *t)
{
    double s = a + b, bb = s - a;
    *t = (a - (s - bb)) + (b - bb);
    return s;
}

/* a + b = s + t exactly when |a| >= |b| or a = 0 (Dekker's Fast2Sum). */
static inline double fast_two_sum(double a, double b, double *t)
{
    double s = a + b;
    *t = b - (s - a);
    return s;
}

static inline double magnitude(dd x)
{
    return fabs(x.hi) + fabs(x.lo);
}

/* The difference of two input coordinates, exactly. */
static inline dd dd_diff(double a, double b)
{
    dd r;
    r.hi = two_sum(a, -b, &r.lo);
    r.e = 0;
    return r;
}

static inline dd dd_add(dd x, dd y)
{
    double sl, tl, th, vl;
    dd r;
    double sh = two_sum(x.hi, y.hi, &sl);
    th = two_sum(x.lo, y.lo, &tl);
    sl += th;
    sh = fast_two_sum(sh, sl, &vl);
    vl += tl;
    r.hi = fast_two_sum(sh, vl, &r.lo);
    r.e = x.e + y.e + DD_REL_ADD * magnitude(r) + DD_UNDERFLOW;
    return r;
}

static inline dd dd_neg(dd x)
{
    return (dd){-x.hi, -x.lo, x.e};
}

static inline dd dd_sub(dd x, dd y)
{
    return dd_add(x, dd_neg(y));
}

#ifndef FP_FAST_FMA
/* a = hi + lo with halves of at most 26 significant bits (Veltkamp's split); an
 * overflow of the scaled value makes both parts NaN. */
static inline double split(double a, double *lo)
{
    double scaled = 134217729.0 * a, hi = scaled - (scaled - a);
    *lo = a - hi;
    return hi;
}

/* a b = p + *err exactly, barring underflow and overflow (Dekker's product). */
static inline double two_prod(double a, double b, double *err)
{
    double p = a * b, al, bl, ah = split(a, &al), bh = split(b, &bl);
    *err = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    return p;
}
#endif

/* Where fma is a call rather than an instruction (x86-64 without -mfma), the exact
 * product comes from Dekker's algorithm and the cross terms are rounded separately:
 * the error is then at most u^2 (x.lo y.lo, dropped) + 2u^2 (the two cross products) +
 * u^2 (their sum added to the exact product's tail) + O(u^3), below 5u^2 of the result,
 * where DD_REL_MUL charges 32u^2; under underflow each of the two dozen operations
 * loses at most 2^-1074 (Dekker's product at most 3.5 times that), within
 * DD_UNDERFLOW. Either way the signs and roundings decided are the exact ones. */
static inline dd dd_mul(dd x, dd y)
{
    dd r;
#ifdef FP_FAST_FMA
    double ch = x.hi * y.hi, cl1 = fma(x.hi, y.hi, -ch);
    double tl1 = fma(x.hi, y.lo, x.lo * y.lo), cl2 = fma(x.lo, y.hi, tl1);
#else
    double cl1, ch = two_prod(x.hi, y.hi, &cl1);
    double cl2 = x.hi * y.lo + x.lo * y.hi;
#endif
    r.hi = fast_two_sum(ch, cl1 + cl2, &r.lo);
    r.e = magnitude(x) * y.e + magnitude(y) * x.e + x.e * y.e + DD_REL_MUL * magnitude(r) +
          DD_UNDERFLOW;
    return r;
}

/* +1, -1, or MCI_UNCERTAIN. */
static int dd_sign(dd x)
{
    if (!isfinite(x.hi) || !isfinite(x.lo) || !isfinite(x.e))
        return MCI_UNCERTAIN;
    if (fabs(x.hi) * (1 - 0x1p-50) > (x.e + fabs(x.lo)) * DD_BOUND_SAFETY)
        return x.hi > 0 ? 1 : -1;
    return MCI_UNCERTAIN;
}

static dd dd_dot(const dd x[3], const dd y[3])
{
    return dd_add(dd_add(dd_mul(x[0], y[0]), dd_mul(x[1], y[1])), dd_mul(x[2], y[2]));
}

/* A point as origin + X / W. */
typedef struct dd_point {
    dd x[3], w;
} dd_point;

/* LPI (line v[0] v[1], plane v[2..4]): offset u s from v[0] over W = n.u, with
 * u = v[1] - v[0] and s = n.(v[2] - v[0]); then rebased to the origin. */
static void dd_lpi(dd_point *out, const mci_point *p, const double *origin)
{
    const double *const *v = p->v;
    dd u[3], d1[3], d2[3], n[3], to_plane[3], s;
    for (int k = 0; k < 3; k++) {
        u[k] = dd_diff(v[1][k], v[0][k]);
        d1[k] = dd_diff(v[3][k], v[2][k]);
        d2[k] = dd_diff(v[4][k], v[2][k]);
        to_plane[k] = dd_diff(v[2][k], v[0][k]);
    }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        n[k] = dd_sub(dd_mul(d1[i], d2[j]), dd_mul(d1[j], d2[i]));
    }
    out->w = dd_dot(n, u);
    s = dd_dot(n, to_plane);
    for (int k = 0; k < 3; k++)
        out->x[k] = dd_add(dd_mul(dd_diff(v[0][k], origin[k]), out->w), dd_mul(u[k], s));
}

static void dd_cross(const dd a[3], const dd b[3], dd out[3])
{
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        out[k] = dd_sub(dd_mul(a[i], b[j]), dd_mul(a[j], b[i]));
    }
}

int mci_orient3d_vertices_dd(const double *a, const double *b, const double *c,
                             const double *d)
{
    dd d1[3], d2[3], to_d[3], n[3];
    for (int k = 0; k < 3; k++) {
        d1[k] = dd_diff(b[k], a[k]);
        d2[k] = dd_diff(c[k], a[k]);
        to_d[k] = dd_diff(d[k], a[k]);
    }
    dd_cross(d1, d2, n);
    return dd_sign(dd_dot(n, to_d));
}

/* TPI of planes (v[0], v[1], v[2]), (v[3], v[4], v[5]), (v[6], v[7], v[8]): with normals
 * n_i and s_i = n_i.(a_i - origin) (a_i the plane's first vertex), the offset from the
 * origin is (s_0 n_1 x n_2 + s_1 n_2 x n_0 + s_2 n_0 x n_1) / W, W = n_0.(n_1 x n_2)
 * (Cramer's rule; the orientation of each normal cancels). */
static void dd_tpi(dd_point *out, const mci_point *p, const double *origin)
{
    const double *const *v = p->v;
    dd n[3][3], s[3], c[3][3];
    for (int pl = 0; pl < 3; pl++) {
        const double *a = v[3 * pl], *b = v[3 * pl + 1], *cc = v[3 * pl + 2];
        dd d1[3], d2[3], to_plane[3];
        for (int k = 0; k < 3; k++) {
            d1[k] = dd_diff(b[k], a[k]);
            d2[k] = dd_diff(cc[k], a[k]);
            to_plane[k] = dd_diff(a[k], origin[k]);
        }
        dd_cross(d1, d2, n[pl]);
        s[pl] = dd_dot(n[pl], to_plane);
    }
    for (int pl = 0; pl < 3; pl++)
        dd_cross(n[(pl + 1) % 3], n[(pl + 2) % 3], c[pl]);
    out->w = dd_dot(n[0], c[0]);
    for (int k = 0; k < 3; k++)
        out->x[k] = dd_add(dd_add(dd_mul(s[0], c[0][k]), dd_mul(s[1], c[1][k])),
                           dd_mul(s[2], c[2][k]));
}

static void dd_point_at(dd_point *out, const mci_point *p, const double *origin)
{
    if (p->kind == MCI_POINT_EXPLICIT) {
        for (int k = 0; k < 3; k++)
            out->x[k] = dd_diff(p->v[0][k], origin[k]);
        out->w = (dd){1, 0, 0};
    } else if (p->kind == MCI_POINT_LPI) {
        dd_lpi(out, p, origin);
    } else {
        dd_tpi(out, p, origin);
    }
}

int mci_orient2d_projected_dd(const mci_point *p, const mci_point *q, const mci_point *r,
                              int axis)
{
    const mci_point *points[3] = {p, q, r};
    int i = (axis + 1) % 3, j = (axis + 2) % 3, sign = 1;
    dd_point e[3];
    dd det = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        int w_sign;
        dd_point_at(&e[k], points[k], r->v[0]);
        w_sign = dd_sign(e[k].w);
        if (w_sign == MCI_UNCERTAIN)
            return MCI_UNCERTAIN;
        sign *= w_sign;
    }
    /* Cofactor expansion along the W column (row k: x_i, x_j, w). */
    for (int k = 0; k < 3; k++) {
        const dd_point *a = &e[(k + 1) % 3], *b = &e[(k + 2) % 3];
        dd minor = dd_sub(dd_mul(a->x[i], b->x[j]), dd_mul(a->x[j], b->x[i]));
        det = dd_add(det, dd_mul(e[k].w, minor));
    }
    {
        int s = dd_sign(det);
        return s == MCI_UNCERTAIN ? s : s * sign;
    }
}

/* Sign of the true coordinate minus the double-word m (exact sign of W is w_sign). */
static int side_of(const dd_point *e, int w_sign, int k, dd m)
{
    int s = dd_sign(dd_sub(e->x[k], dd_mul(m, e->w)));
    return s == MCI_UNCERTAIN ? s : s * w_sign;
}

/* The nearest double to coordinate k, starting from the guess c: c is it when the value
 * lies strictly between the midpoints to c's neighbours (both are double-words: c plus
 * or minus half a gap, a power of two). Otherwise the side found moves c by one. */
static bool round_coordinate(const dd_point *e, int w_sign, int k, double c, double *out)
{
    for (int step = 0; step < 3; step++) {
        double up = mci_next_up(c), down = mci_next_down(c);
        int above, below;
        /* Far from underflow (half gaps stay exact) and from overflow. */
        if (!(fabs(c) >= 0x1p-900) || !isfinite(up) || !isfinite(down))
            return false;
        above = side_of(e, w_sign, k, (dd){c, (up - c) / 2, 0});
        below = side_of(e, w_sign, k, (dd){c, -(c - down) / 2, 0});
        if (above == MCI_UNCERTAIN || below == MCI_UNCERTAIN)
            return false;
        if (above < 0 && below > 0) {
            *out = c;
            return true;
        }
        c = above > 0 ? up : down;
    }
    return false;
}

unsigned mci_point_round_dd(const mci_point *p, unsigned pending, const double guess[3],
                            double out[3])
{
    static const double origin[3] = {0, 0, 0};
    dd_point e;
    int w_sign;
    dd_point_at(&e, p, origin);
    if ((w_sign = dd_sign(e.w)) == MCI_UNCERTAIN)
        return pending;
    for (int k = 0; k < 3; k++)
        if (((pending >> k) & 1) && round_coordinate(&e, w_sign, k, guess[k], &out[k]))
            pending &= ~(1u << k);
    return pending;
}

/* ---------------------------------------------------------------------------------- */
/* Double-word values of exact coordinates (kept by exact/exact_cache.c)               */

bool mci_dd_from_chunks(const uint32_t *chunk, int n, int exponent, int sign, double out[3])
{
    dd sum = {0, 0, 0};
    /* The top chunk's bits and the unit of the error must stay normal doubles after
     * scaling: 2^(exponent + 32 n) below 2^1000, 2^exponent above 2^-900. */
    if (n <= 0 || exponent + 32 * n > 1000 || exponent < -900)
        return false;
    double unit = 1; /* 2^(32 i): exact while 32 n stays below the exponent range */
    if (n > 30)
        return false;
    for (int i = 0; i < n; i++, unit *= 0x1p32) {
        dd term = {(double)chunk[i] * unit, 0, 0}; /* exact: 32 bits */
        sum = dd_add(term, sum);
    }
    sum.e += 1; /* the fraction g below one unit */
    out[0] = sign * ldexp(sum.hi, exponent);
    out[1] = sign * ldexp(sum.lo, exponent);
    out[2] = ldexp(sum.e * DD_BOUND_SAFETY, exponent);
    return true;
}

static dd dd_value(const double v[3])
{
    return (dd){v[0], v[1], v[2]};
}

int mci_orient2d_dd_values(const double *p, const double *q, const double *r, int axis)
{
    int i = 3 * ((axis + 1) % 3), j = 3 * ((axis + 2) % 3);
    dd qx = dd_sub(dd_value(q + i), dd_value(p + i)), qy = dd_sub(dd_value(q + j), dd_value(p + j));
    dd rx = dd_sub(dd_value(r + i), dd_value(p + i)), ry = dd_sub(dd_value(r + j), dd_value(p + j));
    return dd_sign(dd_sub(dd_mul(qx, ry), dd_mul(qy, rx)));
}

int mci_compare_dd_values(const double a[3], const double b[3])
{
    return dd_sign(dd_sub(dd_value(a), dd_value(b)));
}
