/*
 * Double-word values of a scene's numbered points (mci_scene_number_points), computed
 * once per point, the first time a predicate needs more than the point's box, and shared
 * by every face and thread of the evaluation.
 *
 * Why: crossings of faces a few ulps from coplanar (exported Menger sponges) come in
 * crowds of nearly coincident points; every triangulation of a face that holds them
 * (the first, then the output's) meets them in orientations that only such values
 * decide, and each face computed them again from their definitions.
 */
#ifndef MCI_CSG_POINT_VALUES_H
#define MCI_CSG_POINT_VALUES_H

#include "base/core.h"
#include "exact/kernel.h"

#include <stdatomic.h>

typedef struct mci_point_values {
    const mci_ctx *ctx;
    size_t count;
    atomic_uchar *state;      /* per point: unknown, being computed, known or none */
    _Atomic(void *) *blocks;  /* values in blocks of 512 points, allocated on demand */
} mci_point_values;

/* A table for points 0..count-1; fails only with MCSG_ERR_NOMEM. */
mcsg_status mci_point_values_init(const mci_ctx *ctx, mci_point_values *t, size_t count,
                                  mcsg_error *err);
void mci_point_values_free(mci_point_values *t);

/* Point `id`'s coordinates as double-word values (mci_point_dd_values; coordinate k at
 * index 3k), p being that point: from the table, or computed into `scratch` when another
 * thread is computing them or a block cannot be allocated. NULL when the point has no
 * such values. Safe from several threads at once. */
const double *mci_point_values_get(mci_point_values *t, uint32_t id, const mci_point *p,
                                   double scratch[3][3]);

/* The same when the table holds them already, else NULL (nothing computed). */
const double *mci_point_values_known(mci_point_values *t, uint32_t id);

#endif
