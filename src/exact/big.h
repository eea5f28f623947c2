/*
 * Exact arithmetic base (exact/big.c): a fixed-capacity signed big integer on GMP's mpn
 * layer (no heap allocation, so GMP's abort-on-out-of-memory allocator is never
 * reached). Every finite double is m * 2^e with an integer m < 2^53; scaling all inputs
 * of one predicate by the smallest such 2^e turns them into integers of at most ~2150
 * bits, and the predicate's polynomial is then evaluated exactly. The basic predicates
 * (exact/predicates.h) and the kernel of the pipeline (exact/kernel.h) build on this.
 */
#ifndef MESHCSG_EXACT_BIG_H
#define MESHCSG_EXACT_BIG_H

#include <gmp.h>
#include <stdbool.h>
#include <stdint.h>

/* Capacity in limbs. Scaled to a common exponent, a finite double is an integer of at
 * most 53 + 971 + 1074 = 2098 bits, a difference 2099; the kernel's highest-degree
 * polynomial (orient2d of three three-plane points) has degree 20 in such numbers:
 * 20 * 2099 bits + carries < 657 limbs. Operations touch only the limbs in use. */
#define MCI_BIG_LIMBS 704

typedef struct mci_big {
    int size; /* number of limbs used, negative for negative numbers, 0 for zero */
    mp_limb_t limb[MCI_BIG_LIMBS];
} mci_big;

/* x = significand * 2^exponent with an odd significand; x finite and nonzero. */
void mci_split_double(double x, uint64_t *significand, int *exponent);

/* Exponent of the lowest bit of a finite double's 53-bit integer significand: x is an
 * integer multiple of 2^mci_lsb_exponent(x). Returns INT_MAX for 0. */
int mci_lsb_exponent(double x);

/* The exponents of the lowest and the highest set bit of x (finite, nonzero): x is an
 * integer multiple of 2^lsb and 2^msb <= |x| < 2^(msb + 1) (msb is ilogb(x)). */
void mci_bit_range(double x, int *lsb, int *msb);

/* *r = x * 2^-e0 exactly; requires x finite and e0 <= mci_lsb_exponent(x). */
void mci_big_from_double(mci_big *r, double x, int e0);
void mci_big_set_int(mci_big *r, int value);
void mci_big_copy(mci_big *r, const mci_big *a);
void mci_big_neg(mci_big *r, const mci_big *a);
void mci_big_add(mci_big *r, const mci_big *a, const mci_big *b);
void mci_big_sub(mci_big *r, const mci_big *a, const mci_big *b);
void mci_big_mul(mci_big *r, const mci_big *a, const mci_big *b);
int mci_big_sign(const mci_big *a);
/* *r = a * 2^bits, for a result within the capacity (r may alias a). */
void mci_big_shift_left(mci_big *r, const mci_big *a, unsigned bits);
/* a's limbs into out[0..capacity): its signed limb count, or INT_MIN when it needs more
 * than `capacity` limbs (out is then unspecified). */
int mci_big_export(const mci_big *a, mp_limb_t *out, int capacity);
/* *r = the number that mci_big_export wrote as limbs[0..|size|) with size's sign. */
void mci_big_import(mci_big *r, const mp_limb_t *limbs, int size);
/* num / den * 2^exp2 rounded to the nearest double (ties to even), subnormal results
 * included; 0 if num = 0 or den = 0. Requires exp2 >= -1074 (the lsb exponent of a
 * double: the unit of mci_big_from_double's integers) and a result that does not
 * overflow. Uses thread-local scratch. */
double mci_big_ratio_to_double(const mci_big *num, const mci_big *den, int exp2);

#endif
