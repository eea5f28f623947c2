/*
 * Constrained triangulation of one face (a triangle) with points and constraint edges,
 * decided by exact orientation tests on implicit points only. See triangulate.c.
 */
#ifndef MESHCSG_CSG_TRIANGULATE_H
#define MESHCSG_CSG_TRIANGULATE_H

#include "base/core.h"
#include "exact/kernel.h"

/* The face and what to put into it. points[0..2] are the face's corners, counter-
 * clockwise in the face's orientation; every other point must lie in the closed face
 * and differ from every other point. Orientation in the face is `sign` times
 * mci_orient2d_projected(..., axis) (see mci_plane_projection_axis).
 *
 * `insert` lists the ids of the points to insert besides the corners (each once).
 * `edges` lists constraint edges as pairs of point ids, all inserted: constraints may
 * share end points but must not cross, and no point may lie in a constraint's
 * interior. Constraints along the face's boundary are allowed and ignored. */
typedef struct mci_cdt_input {
    const mci_point *const *points; /* by id */
    size_t point_count;
    int axis, sign;
    const uint32_t *insert;
    size_t insert_count;
    const uint32_t *edges;
    size_t edge_count;
    /* Optional (may be NULL): true when points a, b, c are known to be collinear by
     * construction (e.g. all on one segment's line). Such triples are answered without
     * a predicate, whose exact stage is slow on the exact zeros they produce. */
    bool (*known_collinear)(const void *user, uint32_t a, uint32_t b, uint32_t c);
    const void *user;
    /* Optional (NULL: none): the points' numbers in a table of point values, which
     * decides orientations the boxes leave open before the general predicate. */
    const uint32_t *ids;
    struct mci_point_values *values;
} mci_cdt_input;

/* The triangles (point ids, counter-clockwise in the face's orientation) tile the face
 * exactly: every one is non-degenerate, and every constraint edge is an edge of the
 * triangulation. `tris` has 3 * tri_count ids, allocated with ctx (caller frees).
 * `adj` (same size, also the caller's) gives for side i of triangle t (tris[3t + i] ->
 * tris[3t + (i + 1) % 3]) the side 3t' + j of the triangle across it, with the bit
 * MCI_CDT_CONSTRAINT set when that edge is a constraint, or UINT32_MAX on the face's
 * boundary: callers pair the sides inside the face without sorting them. */
#define MCI_CDT_CONSTRAINT UINT32_C(0x80000000)

typedef struct mci_cdt_output {
    uint32_t *tris;
    uint32_t *adj;
    size_t tri_count;
} mci_cdt_output;

/* Fails with MCSG_ERR_NOMEM, or MCSG_ERR_INTERNAL when the input breaks the contract
 * above (a point outside the face, coincident points, crossing constraints). */
mcsg_status mci_triangulate(const mci_ctx *ctx, const mci_cdt_input *in, mci_cdt_output *out,
                            mcsg_error *err);

#endif
