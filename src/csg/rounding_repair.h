/*
 * Output repair after rounding to doubles, when distinct exact vertices were joined
 * because they round to the same doubles: pairs of opposite triangles on the same
 * corners cancel, and triangles that rounding made exactly flat (three collinear
 * corners), turned over or folded onto their neighbour are removed by splitting that
 * neighbour across the long edge at the third corner (two flat triangles back to back
 * are zipped). See rounding_repair.c.
 */
#ifndef MESHCSG_CSG_ROUNDING_REPAIR_H
#define MESHCSG_CSG_ROUNDING_REPAIR_H

#include "base/core.h"

typedef struct mci_flat_repair {
    size_t split;     /* flat triangles removed (each by splitting a neighbour, or two
                         back to back by zipping their sides) */
    size_t turned;    /* triangles turned over, removed the same way */
    size_t remaining; /* flat triangles left (a neighbour flat as well, not zippable) */
    bool twins;       /* a new triangle has an opposite twin (mci_cancel_opposite_triangles
                         has work) */
} mci_flat_repair;

/* How the exact result's triangle with tag `tag` turns: projected along *axis (that
 * coordinate dropped, the other two in cyclic order), +1 counter-clockwise, -1
 * clockwise, 0 when not known. */
typedef int (*mci_turn_fn)(const void *user, uint32_t tag, int *axis);

/* The turn of triangle a, b, c (+1 counter-clockwise, -1 clockwise, 0 flat), exactly,
 * projected along *axis: the axis its normal is largest along, in doubles (any axis with
 * a nonzero exact turn would do). */
int mci_triangle_turn(const double *a, const double *b, const double *c, int *axis);

typedef struct mci_expected_turns {
    mci_turn_fn turn;
    const void *user;
} mci_expected_turns;

/* tris: nt triangles over the vertices xyz (distinct coordinates per vertex id), closed
 * and consistently oriented. Rewrites flat triangles and their neighbours in place;
 * source[t] (optional) is a per-triangle tag copied from the neighbour into the
 * triangle that replaces a flat one. With `turns` (and source), a thin triangle that
 * rounding turned over (a corner moved across the opposite edge) is removed the same
 * way, by splitting the neighbour across that edge at the corner, where the two new
 * triangles turn as the neighbour does. Returns false only when out of memory. */
bool mci_split_flat_triangles(const mci_ctx *ctx, const double *xyz, uint32_t *tris,
                              uint32_t *source, size_t nt, const mci_expected_turns *turns,
                              mci_flat_repair *result);

/* Remove pairs of triangles on the same three corners with opposite orientations (a
 * sliver folded flat when its vertices were joined by rounding): their edges cancel, so
 * the mesh stays closed and oriented. Compacts tris and source (optional) in place,
 * updates *nt and sets *cancelled to the number of triangles removed. Returns false
 * only when out of memory. */
bool mci_cancel_opposite_triangles(const mci_ctx *ctx, uint32_t *tris, uint32_t *source,
                                   size_t *nt, size_t *cancelled);

#endif
