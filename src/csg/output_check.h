/*
 * The check of mcsg_eval's result against the guarantees of docs/robustness.md
 * (csg/output_check.c), on the mesh as the next program sees it: with its vertex indices,
 * and with its vertices welded by coordinates (STL has no indices; slicers, viewers and
 * mesh libraries weld).
 */
#ifndef MESHCSG_CSG_OUTPUT_CHECK_H
#define MESHCSG_CSG_OUTPUT_CHECK_H

#include "base/core.h"

/* The exact result before rounding: its triangles by exact vertex id, and where each id's
 * rounded coordinates are (xyz + 3 * dense[id]). Read only where the welded mesh has an
 * edge of more than two triangles, to tell whether the exact result touches itself
 * there. */
typedef struct mci_exact_result {
    const uint32_t *tris;
    size_t count;
    const uint32_t *dense;
    const double *xyz;
    /* Or, when tris is NULL: those edges already listed by mci_list_touching_edges (the
     * exact result of an earlier evaluation, to judge a mesh derived from it). */
    const double *touching;
    size_t touching_count;
} mci_exact_result;

/* The edges where the exact result touches itself (more than two triangles by exact
 * identity), as their rounded ends (6 doubles each, sorted): *ends allocated with ctx,
 * *n of them. False when out of memory. */
bool mci_list_touching_edges(const mci_ctx *ctx, const mci_exact_result *exact, double **ends,
                             size_t *n);

/* The edges of m with more than two triangles once its vertices are welded by
 * coordinates, where the exact result does not touch itself (what the check counts in
 * welded_nonmanifold_edges): keys u << 32 | v of welded ids u < v, sorted, in *edges
 * (allocated with ctx; *n of them), where canon[i] (room for m's vertices) is set to the
 * welded id of vertex i: the first vertex with its coordinates. False when out of memory
 * or with 2^31 vertices or more. */
bool mci_welded_overfull_edges(const mci_ctx *ctx, const mcsg_mesh *m,
                               const mci_exact_result *x, uint32_t *canon, uint64_t **edges,
                               size_t *n);

/* Fills *check for mesh m (see mcsg_output_check); crossings only when
 * ctx->check_output_crossings. Fails only when out of memory. */
mcsg_status mci_check_output(const mci_ctx *ctx, const mcsg_mesh *m,
                             const mci_exact_result *exact, mcsg_output_check *check,
                             mcsg_error *err);

/* The pairs of m's triangles that cross (mcsg_mesh_self_intersections on ctx's
 * allocator, threads and pool). */
mcsg_status mci_count_crossings(const mci_ctx *ctx, const mcsg_mesh *m, size_t *pairs,
                                mcsg_error *err);

/* What the check found broken, as "N what, N what" (empty when nothing): into what,
 * at most size bytes with the terminating zero. */
void mci_describe_output_check(const mcsg_output_check *check, char *what, size_t size);

/* One warning line naming what the check found broken, if anything. */
void mci_log_output_check(const mci_ctx *ctx, const mcsg_output_check *check);

/* Everything a check counts broken, crossing pairs included where counted. */
size_t mci_output_check_defects(const mcsg_output_check *c);

#endif
