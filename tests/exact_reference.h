/*
 * An exact reference for the predicates and constructions of the plane-based kernel
 * (src/exact/kernel.h): the oracle test_exact_kernel checks the kernel against.
 *
 * What it computes: from finite input doubles, the exact rational coordinates of the
 * kernel's points (an input vertex; an LPI, a line through two vertices meeting a plane
 * through three; a TPI, the meeting point of three such planes) and the exact sign of each
 * predicate the kernel offers (orient3d against a plane or of four points, compare_coord,
 * compare_lex, orient2d in a projection, the sign of a plane-plane line's direction, the
 * order of two points along a line), plus exact comparisons of a double with a rational,
 * for checking the kernel's certified error bounds, boxes and rounding.
 *
 * How: GMP rationals and integers, from the geometric definitions.
 *   plane   n = (b - a) x (c - a) through a, kept as rationals (n, a) and as the integer
 *           row h, a positive multiple of (n, -n.a): sign(h.(X, 1)) is the side of X.
 *   LPI     solve n.(p + t (q - p) - a) = 0 for t; none when n.(q - p) = 0.
 *   TPI     solve n_k.x = n_k.a_k (k = 0, 1, 2) by Gaussian elimination with row swaps;
 *           none when the normals are dependent.
 *   points  the rational coordinates, then as homogeneous integers X_k = n[k] / d, d > 0
 *           (the lcm of the denominators), so that each predicate is the sign of one
 *           integer polynomial in its defining form: orient3d = sign(h.(X, 1)), orient2d
 *           = the 2D cross product of differences, compare = sign of a difference.
 *
 * Why it is independent of src/exact: this header and exact_reference.c include nothing
 * from src/ and call nothing of the library, so no code is shared. Nor is any method: the
 * kernel evaluates closed formulas of the input doubles (the LPI's and TPI's homogeneous
 * coordinates, Cramer numerators) behind floating-point filters with error bounds, then
 * in int128 or its own big integers; the reference solves each construction as a linear
 * system in rationals and has no filter, approximation or degree bound. Agreement of the
 * two therefore means that both are right, not that both copy one mistake. Its one
 * trusted primitive is mpq_set_d, exact for every finite double (test_exact_kernel checks
 * it on the extremes of the range).
 *
 * Every object must be initialised (ref_*_init) before use and cleared after (GMP
 * allocates; the objects are meant to be kept and reused across cases).
 */
#ifndef MCSG_EXACT_REFERENCE_H
#define MCSG_EXACT_REFERENCE_H

#include <gmp.h>
#include <stdbool.h>

/* A rational 3-vector: a point's exact coordinates, or a plane's normal. */
typedef struct ref_vec {
    mpq_t c[3];
} ref_vec;

/* A point as homogeneous integers: X_k = n[k] / d with d > 0. */
typedef struct ref_point {
    mpz_t n[3], d;
} ref_point;

/* A line, by a positive multiple of its direction (integers). */
typedef struct ref_line {
    mpz_t dir[3];
} ref_line;

/* A plane through three doubles a, b, c: normal n = (b - a) x (c - a) and the point a,
 * rational; and h, a positive integer multiple of (n, -n.a). */
typedef struct ref_plane {
    ref_vec n, a;
    mpz_t h[4];
} ref_plane;

void ref_vec_init(ref_vec *v);
void ref_vec_clear(ref_vec *v);
/* v = x exactly. */
void ref_vec_set_d(ref_vec *v, const double x[3]);

void ref_point_init(ref_point *p);
void ref_point_clear(ref_point *p);
/* p = x: the same point as homogeneous integers. */
void ref_point_set_vec(ref_point *p, const ref_vec *x);
/* p = the input vertex x. */
void ref_point_set_d(ref_point *p, const double x[3]);

void ref_plane_init(ref_plane *p);
void ref_plane_clear(ref_plane *p);
/* p = the plane through a, b, c (any three points, collinear or equal included). */
void ref_plane_set(ref_plane *p, const double a[3], const double b[3], const double c[3]);

/* The line through p and q meets plane pl at x. False (x unchanged) when n.(q - p) = 0:
 * the line is parallel to the plane, lies in it, or p = q. *w = n.(q - p) (the kernel's
 * W of an LPI). */
bool ref_lpi(ref_vec *x, mpq_ptr w, const double p[3], const double q[3],
             const ref_plane *pl);
/* The three planes meet at x. False (x unchanged) when their normals are dependent.
 * *det = det[n0; n1; n2] (the kernel's W of a TPI). */
bool ref_tpi(ref_vec *x, mpq_ptr det, const ref_plane *p0, const ref_plane *p1,
             const ref_plane *p2);

/* Side of p: the sign of n.(p - a). */
int ref_orient3d(const ref_point *p, const ref_plane *pl);
/* sign(a_axis - b_axis). */
int ref_compare_coord(const ref_point *a, const ref_point *b, int axis);
/* Lexicographic order of the coordinates: -1, 0, 1. */
int ref_compare_lex(const ref_point *a, const ref_point *b);
/* Orientation of p, q, r projected along `axis`: the sign of the 2D cross product of
 * q - p and r - p in the coordinates (axis + 1, axis + 2) mod 3. */
int ref_orient2d(const ref_point *p, const ref_point *q, const ref_point *r, int axis);
/* sign(det[b - a; c - a; d - a]): orient3d of four points, with no plane built (the
 * kernel's orient3d of four input vertices). */
int ref_orient3d_points(const ref_point *a, const ref_point *b, const ref_point *c,
                        const ref_point *d);
/* sign((n1 x n2)_axis): the direction of the line where the planes meet. */
int ref_line_direction_sign(const ref_plane *p1, const ref_plane *p2, int axis);

/* The order of two points along a line is sign((a - b).dir) for the line's direction
 * dir; it exists when the line does and both points lie on it. The kernel's two line
 * orders are: along the line where planes p1 and p2 meet, dir = n1 x n2, for points on
 * both planes (ref_on_planes); along the edge line l0 l1, dir = l1 - l0, for points on it
 * (ref_on_line). Set the line once and test each point once: a scenario orders every
 * pair of its points. */
void ref_line_init(ref_line *l);
void ref_line_clear(ref_line *l);
/* l = the line where p1 and p2 meet; false if they are parallel (no line). */
bool ref_line_set_planes(ref_line *l, const ref_plane *p1, const ref_plane *p2);
/* l = the line from l0 to l1; false if l0 = l1 (no line). */
bool ref_line_set_points(ref_line *l, const ref_point *l0, const ref_point *l1);
/* p lies on both planes. */
bool ref_on_planes(const ref_point *p, const ref_plane *p1, const ref_plane *p2);
/* p lies on the line through l0 and l1 (any p when l0 = l1). */
bool ref_on_line(const ref_point *p, const ref_point *l0, const ref_point *l1);
/* sign((a - b).dir) for the direction of l (a and b on l, l set and existing). */
int ref_order_on_line(const ref_point *a, const ref_point *b, const ref_line *l);

/* Exact comparisons of doubles with a rational x (all doubles finite unless stated). */
/* |v - x| <= e. */
bool ref_within(double v, double e, mpq_srcptr x);
/* sign(b - x). */
int ref_cmp_d(double b, mpq_srcptr x);
/* x - b rounded to a double (the size of a miss, for messages); NaN if b is not finite. */
double ref_gap(mpq_srcptr x, double b);
/* r is a nearest double to x: r is finite and x lies between the midpoints from r to its
 * neighbours (an infinite neighbour bounds nothing on its side). */
bool ref_is_nearest_double(double r, mpq_srcptr x);

#endif
