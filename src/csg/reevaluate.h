/*
 * When rounding the exact result to doubles broke one of its guarantees (a sliver folded
 * onto a neighbour, parts welded into an edge of four triangles, triangles made to
 * cross): the rounded mesh is snapped to a coarser grid and evaluated again, exactly, as
 * the only leaf of a union by its winding number, and rounded again. See reevaluate.c.
 */
#ifndef MESHCSG_CSG_REEVALUATE_H
#define MESHCSG_CSG_REEVALUATE_H

#include "base/core.h"

/* A tree whose root is the union of one leaf, a copy of mesh (mcsg_mesh_repair, and the
 * rounds below). *out is NULL on failure. */
mcsg_status mci_tree_of_one_mesh(const mcsg_options *opts, const mcsg_mesh *mesh,
                                 const char *label, mcsg_tree **out, mcsg_error *err);

/* mcsg_eval on a context that the caller owns (its pool borrowed), without the
 * re-evaluation below: the step that mci_reevaluate_rounded repeats. */
mcsg_status mci_eval_in_context(const mcsg_tree *tree, const mci_ctx *ctx, mcsg_mesh *out,
                                mcsg_provenance **provenance, mcsg_eval_stats *stats,
                                mcsg_error *err);

/* out: mcsg_eval's result, whose check (stats->output_check) failed; provenance (may be
 * NULL) its per-triangle sources; touching[6 * i ..] the rounded ends of the edges where
 * the tree's exact result touches itself (mci_list_touching_edges). Up to six rounds,
 * each snapping its starting mesh to a grid (finer first), evaluating the snapped mesh
 * and then the starting mesh alone, and checking each of these with ctx's options, where
 * only those edges (snapped alike) may have more than two triangles (a round's own exact
 * result may touch where rounding made parts meet: that still breaks the guarantee). The
 * first that passes replaces out and *provenance (mapped back to the tree's leaves), with
 * stats->output_check, the output counts and stats->rounding_snap_grid. When none
 * passes, or the evaluations fail, out is left as it was. Counts the evaluations in
 * stats->rounding_reevaluations. Before the rounds (and alone, when allow_rounds is
 * false), the corners of triangles that rounding made cross are moved apart where that
 * mends them.
 * Fails only when memory runs out or the check fails (out then as it was). */
mcsg_status mci_reevaluate_rounded(const mci_ctx *ctx, const double *touching,
                                   size_t touching_count, bool allow_rounds,
                                   mcsg_mesh *out, mcsg_provenance **provenance,
                                   mcsg_eval_stats *stats,
                                   mcsg_error *err);

#endif
