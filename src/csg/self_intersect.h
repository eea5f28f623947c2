/*
 * The exact test of mcsg_mesh_self_intersections for one pair of a mesh's triangles
 * (csg/self_intersect.c), for callers that test a few pairs of their own.
 */
#ifndef MESHCSG_CSG_SELF_INTERSECT_H
#define MESHCSG_CSG_SELF_INTERSECT_H

#include "base/core.h"

/* Whether triangles s and t of m meet anywhere other than in the vertices and the edge
 * they share, vertices identified by coordinates (the rules of self_intersect.c); false
 * when either has zero area. */
bool mci_triangles_cross(const mcsg_mesh *m, uint32_t s, uint32_t t);

/* The pairs of m's triangles that cross (the test of mcsg_mesh_self_intersections), as
 * s << 32 | t with s < t: *pairs allocated with ctx (NULL when none), *n of them. */
mcsg_status mci_crossing_pairs(const mci_ctx *ctx, const mcsg_mesh *m, uint64_t **pairs,
                               size_t *n, mcsg_error *err);

#endif
