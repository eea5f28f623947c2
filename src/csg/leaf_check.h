/* The evaluator's input contract (leaf_check.c). */
#ifndef MESHCSG_CSG_LEAF_CHECK_H
#define MESHCSG_CSG_LEAF_CHECK_H

#include "csg/csgtree.h"

/* MCSG_OK when every primitive of ptree is closed as a chain (each edge used as often
 * one way as the other) with finite coordinates and no zero-area triangles, no shell
 * meeting itself at an edge with more than two triangles, and encloses some volume if
 * it has one shell; otherwise MCSG_ERR_INVALID_MESH naming the first such leaf (lowest
 * primitive number) and its first problem. Sets ptree->leaf_winding for the primitives
 * with several shells or a negative volume, and numbers their shells; marks those with
 * a shell crossing itself (leaf_crossing, by csg/shell_crossing.c), testing every
 * primitive with ctx->check_self_intersections, otherwise those where a surface of a
 * shell enters another's wedge at an edge. */
mcsg_status mci_check_leaves(const mci_ctx *ctx, const mcsg_tree *tree, mci_ptree *ptree,
                             mcsg_error *err);

/* Tests every shell of every primitive for self-intersections (exact), and marks those
 * with a shell that crosses itself (ptree->leaf_crossing, and leaf_winding): their
 * faces are then intersected with each other. *marked: how many were newly marked. */
mcsg_status mci_mark_crossing_leaves(const mci_ctx *ctx, const mcsg_tree *tree,
                                     mci_ptree *ptree, size_t *marked, mcsg_error *err);

/* The fast test of mci_check_leaves (csg/shell_crossing.c) on every primitive that it
 * skipped (one shell enclosing a positive volume, without the options asking), marking
 * those with a shell that crosses itself; *marked: how many. For a result that came out
 * open (clean input cannot make one, a shell crossing itself can) or crossing itself. */
mcsg_status mci_mark_untested_crossing_leaves(const mci_ctx *ctx, const mcsg_tree *tree,
                                              mci_ptree *ptree, size_t *marked,
                                              mcsg_error *err);

/* Called when evaluation failed with MCSG_ERR_INTERNAL (after self-crossing shells were
 * marked and evaluated again): if two triangles of a primitive cross or meet other than
 * in their shared edge (the likeliest cause of such a failure), returns
 * MCSG_ERR_INVALID_MESH with a message naming it; otherwise MCSG_ERR_INTERNAL with *err
 * unchanged. */
mcsg_status mci_explain_internal_error(const mci_ctx *ctx, const mcsg_tree *tree,
                                       mci_ptree *ptree, mcsg_error *err);

#endif
