/*
 * The basic exact predicates of predicates.h.
 *
 * Filters follow Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
 * Geometric Predicates" (1997): a double evaluation whose error bound proves the sign,
 * else an exact evaluation. The bounds assume no overflow or underflow, so the filter
 * also refuses when a value is not finite or its magnitude sum is below 2^-960 (where
 * products could lose bits to underflow); the exact path has no such limits.
 */
#include "exact/predicates.h"

#include <float.h>
#include <limits.h>
#include <math.h>

/* Unit roundoff of double arithmetic. */
#define EPS (DBL_EPSILON / 2)
/* Below this magnitude sum a product may be subnormal and the relative bounds fail. */
#define FILTER_MIN_MAGNITUDE 0x1p-960

/* Smallest lsb exponent among n doubles (INT_MAX if all are zero). */
static int min_lsb_exponent(const double *v, int n)
{
    int e0 = INT_MAX;
    for (int i = 0; i < n; i++) {
        int e = mci_lsb_exponent(v[i]);
        if (e < e0)
            e0 = e;
    }
    return e0;
}

static int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy)
{
    double v[6] = {ax, ay, bx, by, cx, cy};
    mci_big big[6], l, r;
    int e0 = min_lsb_exponent(v, 6);
    if (e0 == INT_MAX)
        return 0;
    for (int i = 0; i < 6; i++)
        mci_big_from_double(&big[i], v[i], e0);
    mci_big_sub(&big[0], &big[0], &big[4]); /* ax - cx */
    mci_big_sub(&big[1], &big[1], &big[5]); /* ay - cy */
    mci_big_sub(&big[2], &big[2], &big[4]); /* bx - cx */
    mci_big_sub(&big[3], &big[3], &big[5]); /* by - cy */
    mci_big_mul(&l, &big[0], &big[3]);
    mci_big_mul(&r, &big[1], &big[2]);
    mci_big_sub(&l, &l, &r);
    return mci_big_sign(&l);
}

int mci_orient2d(double ax, double ay, double bx, double by, double cx, double cy)
{
    double left = (ax - cx) * (by - cy);
    double right = (ay - cy) * (bx - cx);
    double det = left - right;
    double magnitude = fabs(left) + fabs(right);
    /* Shewchuk's ccwerrboundA. */
    double bound = (3.0 + 16.0 * EPS) * EPS * magnitude;
    if (isfinite(magnitude) && magnitude >= FILTER_MIN_MAGNITUDE && fabs(det) > bound)
        return det > 0 ? 1 : -1;
    /* A zero factor in each product (points sharing a coordinate, as on axis-aligned
     * faces): exactly 0, since a floating-point difference is 0 only for equal inputs. */
    if ((ax == cx || by == cy) && (ay == cy || bx == cx))
        return 0;
    return orient2d_exact(ax, ay, bx, by, cx, cy);
}

static int cross2_diff_exact(const double p[2], const double q[2], const double r[2],
                             const double c[2])
{
    double v[8] = {p[0], p[1], q[0], q[1], r[0], r[1], c[0], c[1]};
    mci_big x[8], l, t;
    int e0 = min_lsb_exponent(v, 8);
    if (e0 == INT_MAX)
        return 0;
    for (int i = 0; i < 8; i++)
        mci_big_from_double(&x[i], v[i], e0);
    mci_big_sub(&x[2], &x[2], &x[0]); /* q - p */
    mci_big_sub(&x[3], &x[3], &x[1]);
    mci_big_sub(&x[6], &x[6], &x[4]); /* c - r */
    mci_big_sub(&x[7], &x[7], &x[5]);
    mci_big_mul(&l, &x[2], &x[7]);
    mci_big_mul(&t, &x[3], &x[6]);
    mci_big_sub(&l, &l, &t);
    return mci_big_sign(&l);
}

int mci_cross2_diff_sign(const double p[2], const double q[2], const double r[2],
                         const double c[2])
{
    double left = (q[0] - p[0]) * (c[1] - r[1]);
    double right = (q[1] - p[1]) * (c[0] - r[0]);
    double det = left - right;
    double magnitude = fabs(left) + fabs(right);
    /* Four rounded differences and two products: each product is within 3 eps (plus
     * second-order terms) of exact, the subtraction adds one more. */
    if (isfinite(magnitude) && magnitude >= FILTER_MIN_MAGNITUDE &&
        fabs(det) > (4.0 + 16.0 * EPS) * EPS * magnitude)
        return det > 0 ? 1 : -1;
    return cross2_diff_exact(p, q, r, c);
}

bool mci_triangle_is_degenerate(const double a[3], const double b[3], const double c[3])
{
    /* The cross product (b-a) x (c-a) vanishes iff its three components, the
     * orientations of the projections onto the yz, zx and xy planes, all vanish. */
    return mci_orient2d(a[1], a[2], b[1], b[2], c[1], c[2]) == 0 &&
           mci_orient2d(a[2], a[0], b[2], b[0], c[2], c[0]) == 0 &&
           mci_orient2d(a[0], a[1], b[0], b[1], c[0], c[1]) == 0;
}

void mci_det3_big(mci_big *r, const double a[3], const double b[3], const double c[3],
                  int e0)
{
    const double *rows[3] = {a, b, c};
    mci_big x[9], minor, t, u;
    for (int i = 0; i < 9; i++)
        mci_big_from_double(&x[i], rows[i / 3][i % 3], e0);
    r->size = 0;
    for (int i = 0; i < 3; i++) {
        /* Cofactor expansion along a: a_i * (b_j c_k - b_k c_j), (i,j,k) cyclic. */
        int j = (i + 1) % 3, k = (i + 2) % 3;
        mci_big_mul(&t, &x[3 + j], &x[6 + k]);
        mci_big_mul(&u, &x[3 + k], &x[6 + j]);
        mci_big_sub(&minor, &t, &u);
        mci_big_mul(&t, &x[i], &minor);
        mci_big_add(r, r, &t);
    }
}

static int det3_exact(const double a[3], const double b[3], const double c[3])
{
    double v[9] = {a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]};
    mci_big det;
    int e0 = min_lsb_exponent(v, 9);
    if (e0 == INT_MAX)
        return 0;
    mci_det3_big(&det, a, b, c, e0);
    return mci_big_sign(&det);
}

int mci_det3_sign(const double a[3], const double b[3], const double c[3])
{
    double det = 0, magnitude = 0, amplified_underflow = 0;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        double p = b[j] * c[k], q = b[k] * c[j];
        det += a[i] * (p - q);
        magnitude += fabs(a[i]) * (fabs(p) + fabs(q));
        amplified_underflow += fabs(a[i]);
    }
    /* Each of the three terms carries at most 3 roundings, the sum 2 more: 5 eps of the
     * magnitude, and 8 eps leaves slack for rounding `magnitude` itself and for underflow
     * in the last products (<= 2^-1074 each, far below 3 eps * 2^-960). An underflow in
     * p or q (absolute error <= 2^-1075 each) is multiplied by |a_i|: that term is added
     * explicitly, since |a_i| can be as large as 2^1024. */
    double bound = 8.0 * EPS * magnitude + amplified_underflow * 0x1p-1072;
    if (isfinite(bound) && magnitude >= FILTER_MIN_MAGNITUDE && fabs(det) > bound)
        return det > 0 ? 1 : -1;
    return det3_exact(a, b, c);
}
