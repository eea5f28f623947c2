/*
 * The exact plane-based geometry kernel. Every geometric decision of the pipeline goes
 * through the predicates below; see docs/exact-arithmetic.md for degrees and bounds.
 *
 * Inputs are the leaves' vertex coordinates exactly as given (finite doubles, no
 * snapping). New points are never stored as coordinates: an implicit point is defined
 * by the input vertices it comes from, and carries only a cached floating-point
 * approximation of its homogeneous coordinates with a certified error bound:
 *
 *   explicit  an input vertex p
 *   LPI       line through input vertices p, q  ∩  plane through input vertices a, b, c
 *             (an edge crossing a face: the edge line depends on the edge alone, so a
 *             point on an edge is defined identically from both faces sharing it)
 *   TPI       intersection of three planes, each through three input vertices
 *
 * A point is stored as  base + Y / W  with `base` an input vertex (p for LPI, the first
 * plane's first vertex for TPI) and (Y, W) homogeneous offsets:
 *   LPI: u = q - p, n = (b - a) x (c - a),  W = n.u,  Y = u (n.(a - p))
 *   TPI: n_k = normal of plane k, r_k = n_k.(a_k - base),  W = det[n1; n2; n3],
 *        Y = Cramer numerators of n_k . y = r_k
 * Each predicate first evaluates in doubles with a running error bound (mci_fv); when
 * the bound does not prove the sign, it recomputes everything from the input doubles in
 * exact integer arithmetic (mci_big on the stack: no heap, never fails).
 */
#ifndef MESHCSG_EXACT_KERNEL_H
#define MESHCSG_EXACT_KERNEL_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* What a filter stage returns when it cannot decide a sign. */
#define MCI_UNCERTAIN 2

/* nextafter(x, +INFINITY) and nextafter(x, -INFINITY), inline: certified boxes step
 * outward millions of times per evaluation and the library call dominated. Same results
 * for every input (NaN stays NaN, +-0 steps to +-2^-1074, -inf up to -DBL_MAX). */
static inline double mci_next_up(double x)
{
    uint64_t bits;
    if (isnan(x) || x == INFINITY)
        return x;
    if (x == 0)
        return 0x1p-1074;
    memcpy(&bits, &x, sizeof bits);
    bits = x > 0 ? bits + 1 : bits - 1; /* the magnitude grows for x > 0, shrinks below */
    memcpy(&x, &bits, sizeof x);
    return x;
}

static inline double mci_next_down(double x)
{
    return -mci_next_up(-x);
}

/* The larger and the smaller of two doubles, inline: fmax and fmin are library calls,
 * and each spilled the live doubles. Unlike those they return y when either is NaN;
 * callers use them where no operand can be NaN, or where a NaN result is as safe. */
static inline double mci_max(double x, double y)
{
    return x > y ? x : y;
}

static inline double mci_min(double x, double y)
{
    return x < y ? x : y;
}

/* A float at or below x (mci_float_above: at or above), for boxes that only cull (half
 * the bytes of doubles): x is moved down by at least a float unit in its last place
 * (2^-23 relative, 2^-149 absolute) before rounding to nearest, which moves it back by
 * at most half of one; beyond the float range the bound is the largest float, or an
 * infinity on the safe side. A NaN gives the largest float (below) or its negative
 * (above): callers that may have NaN must map it themselves. No branch: the rounding
 * direction is random, and mispredicted branches made the octree's pass over the faces
 * cost more than it saved. */
static inline float mci_float_below(double x)
{
    return (float)mci_min(x - fabs(x) * 0x1p-23 - 0x1p-149, FLT_MAX);
}

static inline float mci_float_above(double x)
{
    return (float)mci_max(x + fabs(x) * 0x1p-23 + 0x1p-149, -FLT_MAX);
}

/* A value known to within an error bound: |exact - v| <= e. After an overflow e (and
 * v) may be +inf or NaN, which carries no information: every sign test fails on it and
 * the exact stage decides. */
typedef struct mci_fv {
    double v, e;
} mci_fv;

/* A plane through three input points, oriented by n = (b - a) x (c - a): for a triangle
 * a, b, c counter-clockwise seen from outside, n points outward. The normal is cached
 * with its error bound. Requires a, b, c not collinear for the predicates that divide by
 * the plane (LPI, TPI); orient3d works for any plane. */
typedef struct mci_plane {
    const double *a, *b, *c;
    mci_fv n[3];
} mci_plane;

void mci_plane_init(mci_plane *plane, const double *a, const double *b, const double *c);

/* A total order on input vertices by coordinates (lexicographic), then by address among
 * vertices with equal coordinates. Canonical definitions (edge ends, TPI plane order)
 * use it so that a point's definition, and hence its floating-point approximation and
 * rounded output, never depends on where the meshes happen to sit in memory. */
bool mci_vertex_before(const double *a, const double *b);

/* Whether plane p comes before plane q: mci_vertex_before on their defining vertices. */
bool mci_plane_before(const mci_plane *p, const mci_plane *q);

typedef enum mci_point_kind {
    MCI_POINT_EXPLICIT = 0,
    MCI_POINT_LPI = 1,
    MCI_POINT_TPI = 2
} mci_point_kind;

typedef struct mci_point {
    mci_point_kind kind;
    /* These three sit in kind's padding (points are stored and copied by the million). */
    uint8_t exact_axes; /* bit k: coordinate k is exactly c[k] (see the box below) */
    int8_t w_sign; /* exact sign of the stored w (+1), or 0 if W is exactly 0 (no point) */
    /* W tiny against its error bound (nearly parallel planes): the box was tightened
     * exactly (kernel.c, tighten_wide_box), and predicates on the point tend to need the
     * exact stage. */
    uint8_t ill_conditioned;
    /* Defining input vertices. explicit: v[0]. LPI: line v[0], v[1]; plane v[2..4].
     * TPI: planes v[0..2], v[3..5], v[6..8]. base = v[0] in every case. */
    const double *v[9];
    /* Cached offset from v[0]: point = v[0] + (y[0], y[1], y[2]) / w, with w.v >= 0
     * whenever the sign of W is known (the offsets are negated to make it so). */
    mci_fv y[3], w;
    /* Cached certified box, set by the constructors: |coordinate k - c[k]| <= r, and
     * coordinate k equals c[k] exactly when bit k of exact_axes is set (explicit
     * points; a coordinate fixed by an axis-aligned plane or by a line that keeps it
     * constant). First-stage filters use it; axis-aligned input (CAD parts, coplanar
     * grids) then decides ties without the exact stage. */
    double c[3], r;
} mci_point;

/* Constructors. Each returns true when the point exists: always for explicit points;
 * for LPI when the line is not parallel to the plane (n.u != 0, decided exactly); for
 * TPI when the three normals are independent (det != 0, decided exactly). On false the
 * point must not be used in predicates. Pointers must stay valid while the point is
 * used: nothing is copied. */
void mci_point_explicit(mci_point *p, const double *x);
bool mci_point_lpi(mci_point *p, const double *l0, const double *l1, const mci_plane *plane);
/* An LPI's definition only (kind and v[]; nothing else set): a record to build later
 * with mci_point_lpi, never an argument of a predicate. */
void mci_point_lpi_define(mci_point *p, const double *l0, const double *l1,
                          const mci_plane *plane);
bool mci_point_tpi(mci_point *p, const mci_plane *p1, const mci_plane *p2, const mci_plane *p3);

/* Side of point p with respect to the plane: +1 in front (the side n points to),
 * -1 behind, 0 on the plane. */
int mci_orient3d(const mci_point *p, const mci_plane *plane);

/* mci_orient3d for the input vertex x (same result as for an explicit point at x). */
int mci_orient3d_vertex(const double *x, const mci_plane *plane);

/* Side of input vertex d against the plane through input vertices a, b, c oriented by
 * (b - a) x (c - a): sign((b - a) x (c - a) . (d - a)); 0 when a, b, c are collinear. */
int mci_orient3d_vertices(const double *a, const double *b, const double *c, const double *d);

/* Half-planes about the axis u -> v, each bounded by the axis and holding an input
 * vertex off it (a triangle on edge u-v, by its third corner). The class of half-plane
 * w relative to the reference r: 0 the same half-plane, 1 within (0, pi) of r in the
 * positive turn about u -> v (the side (v - u) x (r - u) points to), 2 opposite, 3
 * within (pi, 2 pi). */
int mci_half_plane_class(const double *u, const double *v, const double *r, const double *w);

/* Whether half-plane w1 comes strictly before w2 in the positive turn about u -> v
 * that starts at r. */
bool mci_half_plane_before(const double *u, const double *v, const double *r,
                           const double *w1, const double *w2);

/* sign(a[axis] - b[axis]), axis in 0..2. */
int mci_compare_coord(const mci_point *a, const mci_point *b, int axis);

/* Lexicographic order of (x, y, z): -1, 0 or +1. */
int mci_compare_lex(const mci_point *a, const mci_point *b);

/* Number of input vertices defining a point (1, 5 or 9: its used entries of v[]). */
int mci_point_vertex_count(const mci_point *p);

/* True when a and b have the same definition (kind and defining vertices, by address):
 * then they are the same point, without any arithmetic. */
bool mci_points_same_definition(const mci_point *a, const mci_point *b);

/* True when a and b are the same point (whatever their definitions). */
bool mci_points_equal(const mci_point *a, const mci_point *b);

/* Orientation of p, q, r projected along `axis` onto the plane of the two other axes
 * (i, j) = ((axis + 1) % 3, (axis + 2) % 3): +1 counter-clockwise seen from +axis, -1
 * clockwise, 0 collinear in the projection. */
int mci_orient2d_projected(const mci_point *p, const mci_point *q, const mci_point *r,
                           int axis);
/* mci_orient2d_projected in two halves, for callers that know collinear cases of their
 * own (a face's lines): the first, a few operations on the cached boxes, decides most
 * calls (+1 or -1) and returns MCI_UNCERTAIN otherwise; the second decides the rest.
 * The boxes come first because for points close together but defined far away
 * (consecutive points of a curve) the homogeneous determinant's bound grows with the
 * distances to the defining vertices, while differences of the boxes stay small.
 * The first is inline: triangulation calls it millions of times.
 *
 * Its bound: each difference of centres is within e1 (q - p) or e2 (r - p) of the true
 * difference, e = the two radii + u times the larger difference of its pair (the
 * rounding of a subtraction is at most u times its result, and exact when subnormal).
 * Then |AD - ad| <= m1 e2 + m2 e1 + e1 e2 for each product of the determinant, with m
 * the larger difference of each pair; the products' rounding adds u m1 m2 + eta each,
 * the final subtraction u |det|. The factor and the extra eta absorb the rounding of the
 * bound's own few operations (all on nonnegative values; see kernel.c). Overflow
 * or NaN fails the comparison: uncertain. It never returns 0. mci_orient2d_boxes is
 * the filter on projected boxes (mci_point_projected_box). */
static inline int mci_orient2d_boxes(const double p[3], const double q[3], const double r[3])
{
    const double u = 0x1p-53, eta = 0x1p-1074, safety = 1.0 + 0x1p-30;
    double a = q[0] - p[0], b = q[1] - p[1], c = r[0] - p[0], d = r[1] - p[1];
    double m1 = mci_max(fabs(a), fabs(b)), m2 = mci_max(fabs(c), fabs(d));
    double e1 = p[2] + q[2] + u * m1, e2 = p[2] + r[2] + u * m2;
    double det = a * d - b * c;
    double bound = 2 * (m1 * e2 + m2 * e1 + e1 * e2) + 2 * u * (m1 * m2) + u * fabs(det) +
                   8 * eta;
    if (fabs(det) > bound * safety)
        return det > 0 ? 1 : -1;
    return MCI_UNCERTAIN;
}

/* A point's box as mci_orient2d_boxes reads it: the centre's coordinates i and j (the
 * two axes other than `axis`, in that order) and the radius. Callers that test the same
 * points many times (a face's triangulation) keep these 24 bytes per point instead of
 * reading the 176-byte points again. */
static inline void mci_point_projected_box(const mci_point *p, int axis, double out[3])
{
    int i = axis == 2 ? 0 : axis + 1, j = axis == 0 ? 2 : axis - 1;
    out[0] = p->c[i];
    out[1] = p->c[j];
    out[2] = p->r;
}

static inline int mci_orient2d_projected_quick(const mci_point *p, const mci_point *q,
                                               const mci_point *r, int axis)
{
    double bp[3], bq[3], br[3];
    mci_point_projected_box(p, axis, bp);
    mci_point_projected_box(q, axis, bq);
    mci_point_projected_box(r, axis, br);
    return mci_orient2d_boxes(bp, bq, br);
}
int mci_orient2d_projected_rest(const mci_point *p, const mci_point *q, const mci_point *r,
                                int axis);
/* The stages of mci_orient2d_projected_rest that compute no exact point (definitional
 * zeros, exact centres, the double filter, 128-bit integers for short coordinates):
 * the sign, or MCI_UNCERTAIN. Callers that keep points' double-word values try this
 * before computing those. */
int mci_orient2d_projected_cheap(const mci_point *p, const mci_point *q, const mci_point *r,
                                 int axis);

/* Order of two points lying on the line of intersection of two planes, along the
 * direction n1 x n2 (paper Eq. 1): sign((a - b) . (n1 x n2)). +1: a is ahead of b. The
 * points must lie on both planes and the planes must not be parallel. */
int mci_order_on_plane_line(const mci_point *a, const mci_point *b, const mci_plane *p1,
                            const mci_plane *p2);

/* An axis along which the line of two non-parallel planes moves (the direction
 * n1 x n2 has a nonzero component there, decided exactly), with that component's sign
 * in *sign; -1 for parallel planes. Order along the line is then
 * sign * mci_compare_coord(a, b, axis): callers ordering many points compute it once. */
int mci_plane_line_axis(const mci_plane *p1, const mci_plane *p2, int *sign);

/* Order of two points lying on the line through input vertices l0 != l1, along
 * l1 - l0: sign((a - b) . (l1 - l0)). */
int mci_order_on_edge_line(const mci_point *a, const mci_point *b, const double *l0,
                           const double *l1);

/* A projection axis for the plane: an axis k with (n)_k != 0 (decided exactly), the
 * one with the largest approximate |n_k|. Projecting along k maps the plane onto the
 * coordinate plane bijectively; *sign receives sign(n_k), the orientation of the
 * triangle a, b, c in that projection. Returns -1 for a degenerate plane (n = 0). */
int mci_plane_projection_axis(const mci_plane *plane, int *sign);
/* The exact sign of the plane's normal component `axis`: the turn of its triangle a, b, c
 * seen along that axis. */
int mci_plane_normal_sign(const mci_plane *plane, int axis);

typedef enum mci_containment {
    MCI_OUTSIDE = 0,
    MCI_INSIDE = 1,   /* in the open triangle */
    MCI_ON_EDGE = 2,  /* in the relative interior of edge *which (0: ab, 1: bc, 2: ca) */
    MCI_ON_VERTEX = 3 /* equal to vertex *which (0: a, 1: b, 2: c) */
} mci_containment;

/* Where a point lying on the plane of a non-degenerate triangle a, b, c is with respect
 * to the triangle: the paper's plane-based inside test. Each edge's bounding plane is
 * the plane through the edge parallel to the projection axis, so the side of the point
 * is the projected orientation (e0, e1, p) times the triangle's own orientation. The
 * point must lie on the plane (else this classifies its projection). */
mci_containment mci_point_in_triangle(const mci_point *p, const mci_plane *triangle,
                                      int *which);

/* Approximate coordinates of a point (the nearest double is not guaranteed; used for
 * output only after rounding decisions elsewhere, and for display). */
void mci_point_approx(const mci_point *p, double out[3]);

/* Coordinates of a point within about 2^-26 of their magnitude each: the approximation
 * where its error bound proves that, else the rounded point (for points that must lie
 * near the exact one, such as the seeds of rays inside a piece). */
void mci_point_near(const mci_point *p, double out[3]);

/* The point's coordinates correctly rounded: each is the double nearest to the exact
 * coordinate (ties to even), computed exactly (output vertices). */
void mci_point_round(const mci_point *p, double out[3]);

/* A box certainly containing the point (possibly infinite when the cached W is too
 * uncertain): the cached box, a single value on the exactly known axes. For culling
 * only: decisions stay with the predicates. Inline: the arrangements' sweeps and merges
 * and the point numbering ask it millions of times. */
static inline void mci_point_bounds(const mci_point *p, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        if ((p->exact_axes >> k) & 1) {
            lo[k] = hi[k] = p->c[k];
        } else {
            /* one step outward covers the rounding of c -+ r */
            lo[k] = mci_next_down(p->c[k] - p->r);
            hi[k] = mci_next_up(p->c[k] + p->r);
        }
    }
}

/* Each predicate above is the combination of two stages, exposed for tests (which check
 * the exact stage on every case, not only where the filter gives up) and benchmarks
 * (which measure how often the filter decides):
 *   *_filtered: the floating-point stage; returns the sign, or MCI_UNCERTAIN;
 *   *_exact:    the exact integer stage; always returns the sign.
 * (MCI_UNCERTAIN is defined above.) */

int mci_orient3d_filtered(const mci_point *p, const mci_plane *plane);
int mci_orient3d_vertex_filtered(const double *x, const mci_plane *plane);
int mci_orient3d_vertices_filtered(const double *a, const double *b, const double *c,
                                   const double *d);
int mci_orient3d_exact(const mci_point *p, const mci_plane *plane);
int mci_compare_coord_filtered(const mci_point *a, const mci_point *b, int axis);
int mci_compare_coord_exact(const mci_point *a, const mci_point *b, int axis);
int mci_orient2d_projected_filtered(const mci_point *p, const mci_point *q,
                                    const mci_point *r, int axis);
int mci_orient2d_projected_exact(const mci_point *p, const mci_point *q, const mci_point *r,
                                 int axis);
/* Between the two for orient2d: the same formulas in double-double arithmetic with an
 * error bound (kernel_dd.c), for every kind of point; MCI_UNCERTAIN when undecided. */
int mci_orient2d_projected_dd(const mci_point *p, const mci_point *q, const mci_point *r,
                              int axis);
/* The same stage for orient3d of four input vertices (det[b - a, c - a, d - a], the
 * sign of mci_orient3d_vertices): the rounded coordinates of a UV sphere's quad are
 * nearly coplanar, and the exact stage cost thousands of instructions per crease test. */
int mci_orient3d_vertices_dd(const double *a, const double *b, const double *c,
                             const double *d);
/* The double-double stage of mci_point_round, for every kind of point: rounds each
 * coordinate k with bit k set in `pending`, starting from guess[k] (any nearby double),
 * into out[k] when it can prove the result; returns the bits it could not decide. */
unsigned mci_point_round_dd(const mci_point *p, unsigned pending, const double guess[3],
                            double out[3]);
/* Double-word values {hi, lo, e} (the value lies within e of hi + lo) of exact
 * coordinates, for the points exact/exact_cache.c keeps. mci_dd_from_chunks: the value
 * of sign (T + g) 2^exponent, T the integer of the 32-bit chunks c[0..n) (c[0] the least
 * significant), 0 <= g < 1; false when scaling could leave the normal range. The two
 * predicates give the sign of orient2d of three points in the plane normal to `axis`
 * (each point nine doubles, coordinate k's value from index 3k) and of a - b, or
 * MCI_UNCERTAIN. */
bool mci_dd_from_chunks(const uint32_t *chunk, int n, int exponent, int sign, double out[3]);
int mci_orient2d_dd_values(const double *p, const double *q, const double *r, int axis);
int mci_compare_dd_values(const double a[3], const double b[3]);
/* p's coordinates as such values, from its exact ones (what exact/exact_cache.c keeps:
 * taken from the thread's table, or computed into it); false when they are not kept
 * (a number too large, or scaling out of range). */
bool mci_point_dd_values(const mci_point *p, double approx[3][3]);
/* Sign of component `axis` of n1 x n2 (the direction of a plane-plane line). */
int mci_line_direction_sign_filtered(const mci_plane *p1, const mci_plane *p2, int axis);
int mci_line_direction_sign_exact(const mci_plane *p1, const mci_plane *p2, int axis);

#endif
