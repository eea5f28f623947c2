/*
 * Whether a shell of a mesh crosses itself, decided exactly (csg/shell_crossing.c): most
 * pairs of neighbouring triangles are proven apart a patch at a time, and only the rest
 * are tested one by one.
 */
#ifndef MESHCSG_CSG_SHELL_CROSSING_H
#define MESHCSG_CSG_SHELL_CROSSING_H

#include "base/core.h"

/* What the test did, for the log and the tests. */
typedef struct mci_shell_crossing_stats {
    size_t patches;          /* connected parts facing one way along one axis */
    size_t proven_patches;   /* of more than one triangle, proven not to cross themselves */
    size_t proven_triangles; /* triangles in those */
    size_t boundary_edges;   /* patch boundary edges examined */
    size_t grid_entries;     /* (cell, triangle) entries of the grid */
    size_t pairs_tested;     /* pairs decided by the exact triangle-triangle test */
} mci_shell_crossing_stats;

/* Whether m is proven star-shaped (exactly, in one pass): the mean of its triangles'
 * corners lies strictly behind every triangle's plane, and a ray from it crosses exactly
 * one triangle. Then, m being closed as a chain, no two of its triangles meet other than
 * in the corners and edges they share. Every convex mesh but the flattest is; most scans
 * are not (and are rejected within a pass). */
bool mci_star_shaped(const mcsg_mesh *m);

/* Whether two triangles of one shell of m cross or meet other than in the vertices and
 * edge they share (the rules of mci_triangles_cross, vertices identified by
 * coordinates): *crosses, and the first pair found in example[2] (triangle indices,
 * MCI_NONE when none). shell (optional) gives each triangle's shell (pairs of different
 * shells are not tested); twin (from mci_mesh_check_shells, 3 per triangle) each
 * half-edge's other use. stats is optional. */
mcsg_status mci_find_shell_crossing(const mci_ctx *ctx, const mcsg_mesh *m,
                                    const uint32_t *shell, const uint32_t *twin,
                                    bool *crosses, uint32_t example[2],
                                    mci_shell_crossing_stats *stats, mcsg_error *err);

/* Where pairs may meet, for a mesh that is another one moved by a map rounded vertex by
 * vertex (a frame's turned result, csg/frames.c): triangle t of m can meet triangle u
 * only if the boxes of t and u in `mesh` (same triangles, other coordinates), each grown
 * by `margin`, meet. Tight boxes where m's are not (long thin triangles turned off the
 * axes have large boxes). */
typedef struct mci_crossing_boxes {
    const mcsg_mesh *mesh;
    double margin;
} mci_crossing_boxes;

/* mci_find_shell_crossing with the pairs' boxes from `boxes` (NULL: m's own). */
mcsg_status mci_find_shell_crossing_boxed(const mci_ctx *ctx, const mcsg_mesh *m,
                                          const uint32_t *shell, const uint32_t *twin,
                                          const mci_crossing_boxes *boxes, bool *crosses,
                                          uint32_t example[2],
                                          mci_shell_crossing_stats *stats, mcsg_error *err);

/* Every pair of m's triangles that cross (rules as above; one shell or several, all
 * tested), with the boxes of `boxes` (NULL: m's own): *pairs (s << 32 | t, s < t,
 * sorted; allocated with ctx, NULL when none), *count of them. */
mcsg_status mci_list_shell_crossings(const mci_ctx *ctx, const mcsg_mesh *m,
                                     const uint32_t *twin, const mci_crossing_boxes *boxes,
                                     uint64_t **pairs, size_t *count, mcsg_error *err);

#endif
