/*
 * Where rounding made parts of the result touch that the exact result keeps apart: the
 * vertex copies of such an edge are moved apart by one unit in the last place, each
 * where its triangles keep their orientation and cross nothing. See separate_copies.c.
 */
#ifndef MESHCSG_CSG_SEPARATE_COPIES_H
#define MESHCSG_CSG_SEPARATE_COPIES_H

#include "base/core.h"
#include "csg/output_check.h"

typedef struct mci_copy_separation {
    size_t edges; /* edges with more than two triangles once welded, not in the exact
                     result */
    size_t moved; /* vertices moved */
} mci_copy_separation;

/* m: the closed, oriented, index-manifold output (mci_split_touching done), allocated
 * with ctx; exact: where the exact result touches itself. Moves vertices of m in place.
 * Returns false only when out of memory (m is then valid, possibly with some vertices
 * moved). */
bool mci_separate_welded_copies(const mci_ctx *ctx, mcsg_mesh *m, const mci_exact_result *exact,
                                mci_copy_separation *result);

/* Where rounding made triangles cross or touch (pairs: s << 32 | t, from
 * mci_crossing_pairs): each corner of those triangles whose triangles cross a triangle
 * near them is moved, as a copy above, to the first neighbouring double where its
 * triangles keep their orientation and cross nothing; *moved counts the moves. m is
 * closed and oriented, allocated with ctx. Returns false only when out of memory (m
 * valid, possibly with some vertices moved). */
bool mci_separate_crossing_corners(const mci_ctx *ctx, mcsg_mesh *m, const uint64_t *pairs,
                                   size_t n, size_t *moved);

#endif
