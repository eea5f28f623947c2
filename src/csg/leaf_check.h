/* The evaluator's input contract (leaf_check.c). */
#ifndef MESHCSG_CSG_LEAF_CHECK_H
#define MESHCSG_CSG_LEAF_CHECK_H

#include "csg/csgtree.h"

/* MCSG_OK when every primitive of ptree is a closed, consistently oriented,
 * edge-manifold mesh with finite coordinates and no zero-area or repeated triangles, and
 * encloses some volume if it has one shell (and, with ctx->check_self_intersections, no
 * shell of it intersects itself); otherwise MCSG_ERR_INVALID_MESH naming the first such leaf
 * (lowest primitive number) and its first problem. Sets ptree->leaf_winding for the
 * primitives with several shells or a negative volume. */
mcsg_status mci_check_leaves(const mci_ctx *ctx, const mcsg_tree *tree, mci_ptree *ptree,
                             mcsg_error *err);

/* Called when evaluation failed with MCSG_ERR_INTERNAL: if a primitive intersects
 * itself (two of its triangles cross or overlap: a shell crossing itself, or shells that
 * touch, break the input contract in ways the stages cannot always notice), returns
 * MCSG_ERR_INVALID_MESH with a message naming it; otherwise MCSG_ERR_INTERNAL with *err
 * unchanged. */
mcsg_status mci_explain_internal_error(const mci_ctx *ctx, const mcsg_tree *tree,
                                       const mci_ptree *ptree, mcsg_error *err);

#endif
