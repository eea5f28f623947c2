/*
 * A rounded result snapped onto a grid coarser than the doubles (snap_round.c): the
 * step of mci_reevaluate_rounded that makes nearly coincident points one.
 */
#ifndef MESHCSG_CSG_SNAP_ROUND_H
#define MESHCSG_CSG_SNAP_ROUND_H

#include "base/core.h"

/* The exponent e of a grid of spacing 2^e that `bits` bits resolve across m: the
 * largest absolute coordinate of m is below 2^(e + bits). */
int mci_snap_exponent(const mcsg_mesh *m, int bits);

/* x rounded to the nearest multiple of 2^e (ties to even; exact), -0 as +0. */
double mci_snap_coordinate(double x, int e);

/* in (finite, closed as a chain) with every coordinate rounded to the nearest multiple
 * of 2^e (ties to even), vertices at one grid point welded, and what the snap made of
 * zero area removed: triangles with a repeated corner, pairs with the same corners in
 * opposite orders, and collinear ones where mesh/zero_area.c can (see snap_round.c).
 * *out stays closed as a chain, with the same winding number as the snapped in off it;
 * (*face_of)[t] is the triangle of in that triangle t of *out comes from. Fails only
 * when out of memory (nothing allocated then). */
mcsg_status mci_snap_to_grid(const mci_ctx *ctx, const mcsg_mesh *in, int e, mcsg_mesh *out,
                             uint32_t **face_of, mcsg_error *err);

#endif
