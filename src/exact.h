/*
 * Exact arithmetic base: a fixed-capacity signed big integer on GMP's mpn layer (no heap
 * allocation, so GMP's abort-on-out-of-memory allocator is never reached), and the few
 * exact predicates that mesh validation needs. Every finite double is m * 2^e with an
 * integer m < 2^53; scaling all inputs of one predicate by the smallest such 2^e turns
 * them into integers of at most ~2150 bits, and the predicate's polynomial is then
 * evaluated exactly. The exact-arithmetic kernel of the pipeline builds on this.
 */
#ifndef MESHCSG_EXACT_H
#define MESHCSG_EXACT_H

#include <gmp.h>
#include <stdbool.h>

/* Capacity in limbs: a product of three 2150-bit integers plus 64 bits of sums. */
#define MCI_BIG_LIMBS 108

typedef struct mci_big {
    int size; /* number of limbs used, negative for negative numbers, 0 for zero */
    mp_limb_t limb[MCI_BIG_LIMBS];
} mci_big;

/* Exponent of the lowest bit of a finite double's 53-bit integer significand: x is an
 * integer multiple of 2^mci_lsb_exponent(x). Returns INT_MAX for 0. */
int mci_lsb_exponent(double x);

/* *r = x * 2^-e0 exactly; requires x finite and e0 <= mci_lsb_exponent(x). */
void mci_big_from_double(mci_big *r, double x, int e0);
void mci_big_add(mci_big *r, const mci_big *a, const mci_big *b);
void mci_big_sub(mci_big *r, const mci_big *a, const mci_big *b);
void mci_big_mul(mci_big *r, const mci_big *a, const mci_big *b);
int mci_big_sign(const mci_big *a);

/* Sign of (a-c) x (b-c) in 2D: +1 counter-clockwise, -1 clockwise, 0 collinear. Exact
 * for all finite inputs (floating-point filter first). */
int mci_orient2d(double ax, double ay, double bx, double by, double cx, double cy);

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
