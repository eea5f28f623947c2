/*
 * Exact points kept for the exact stage (exact/exact_cache.c): a per-thread table of
 * constructed points' exact homogeneous coordinates, so that a point met by many exact
 * predicates is computed once.
 *
 * Why: where many constructed points lie closer together than the spacing of doubles
 * (a Menger sponge exported with six digits, cubes turned by 15 degrees around one
 * centre), sorting a face's points and triangulating it call the exact stage hundreds of
 * thousands of times on the same few thousand points, and each call rebuilt every point
 * from its defining planes in big integers (tens of thousands of instructions).
 *
 * An entry is keyed by the point's kind, its defining vertices' addresses and their
 * coordinates (compared on every hit): a point is a function of those coordinates, so
 * an entry can never answer for another point, even when a vertex's memory is reused.
 * The table lives in the thread's scratch (mci_thread_scratch: a loop's, an
 * evaluation's or a pool worker's): outside these, or when its allocation fails, there
 * is no table and the kernel computes as before. Answers never depend on the table,
 * only the time does.
 */
#ifndef MESHCSG_EXACT_EXACT_CACHE_H
#define MESHCSG_EXACT_EXACT_CACHE_H

#include "exact/kernel.h"

#include <gmp.h>

/* Limbs per number: TPI numerators of inputs spanning 2^120 (far offsets, 1e-17
 * components) need about 14; larger numbers are not kept. */
#define MCI_EXACT_LIMBS 24

/* A point as x[k] / w * 2^e0 (coordinate k): x[0..2] and w are signed integers of
 * size[i] limbs (negative size: negative number) in limb[i]; approx: the same
 * coordinates to about 106 bits with an error bound, which decide most predicates on
 * nearly coincident points before the integers are multiplied. */
typedef struct mci_exact_point {
    mci_point_kind kind;
    int e0;
    int size[4];
    bool has_approx; /* approx is set (scaling kept its parts normal) */
    double approx[3][3]; /* coordinate k as a double-word value {hi, lo, e} (kernel.h) */
    const double *v[9];
    double coords[9][3];
    mp_limb_t limb[4][MCI_EXACT_LIMBS];
} mci_exact_point;

/* The entry of this thread's table where p is kept or would be, NULL when the thread
 * has no table; *held tells whether it holds p now (else the caller may fill it and
 * call mci_exact_cache_claim). Distinct points may share an entry: a caller that uses
 * several entries at once must check that they differ. */
mci_exact_point *mci_exact_cache_find(const mci_point *p, bool *held);

/* Marks e, p's entry (from mci_exact_cache_find), as holding p (its numbers filled by
 * the caller). */
void mci_exact_cache_claim(mci_exact_point *e, const mci_point *p);

/* Marks p's entry as holding nothing (a fill that failed half-way). */
void mci_exact_cache_clear(const mci_point *p);

/* The number of points this thread's table holds (0 without a table): for tests. */
size_t mci_exact_cache_count(void);

#endif
