/*
 * The basic exact predicates on input coordinates (exact/predicates.c): 2D orientation,
 * degeneracy of a triangle, the 3x3 determinant. A floating-point filter decides when
 * its error bound allows, big integers (exact/big.h) otherwise; exact for every finite
 * input.
 */
#ifndef MESHCSG_EXACT_PREDICATES_H
#define MESHCSG_EXACT_PREDICATES_H

#include "exact/big.h"

/* Sign of (a-c) x (b-c) in 2D: +1 counter-clockwise, -1 clockwise, 0 collinear. Exact
 * for all finite inputs (floating-point filter first). */
int mci_orient2d(double ax, double ay, double bx, double by, double cx, double cy);

/* Sign of (q - p) x (c - r) in 2D for input coordinates: where c lies relative to the
 * line through r parallel to p->q (the far end of a triangle's projection interval in
 * the separating-axis test). Exact for all finite inputs. */
int mci_cross2_diff_sign(const double p[2], const double q[2], const double r[2],
                         const double c[2]);

/* True when the triangle has exactly zero area: repeated or collinear corners. */
bool mci_triangle_is_degenerate(const double a[3], const double b[3], const double c[3]);

/* *r = det[a; b; c] * 2^(-3 e0) exactly; e0 must not exceed the lsb exponent of any
 * coordinate. */
void mci_det3_big(mci_big *r, const double a[3], const double b[3], const double c[3],
                  int e0);

/* Sign of det[a; b; c] (six times the signed volume of the tetrahedron (0, a, b, c)),
 * computed exactly; inputs finite. */
int mci_det3_sign(const double a[3], const double b[3], const double c[3]);

#endif
