/*
 * Internal additions to the CSG tree API (mesh/tree.c) for the modules that build trees,
 * such as the CSG-language reader: adding a leaf without copying its mesh.
 */
#ifndef MESHCSG_MESH_TREE_H
#define MESHCSG_MESH_TREE_H

#include "base/core.h"

/* Add a leaf that takes ownership of *mesh's arrays (allocated with the tree's
 * allocator): on success and on failure alike the tree (or this function) becomes
 * responsible for them and *mesh is zeroed. The mesh is used as it is (no transform).
 * Like mcsg_tree_add_leaf, indices are checked against the vertex count. */
mcsg_status mci_tree_add_leaf_owned(mcsg_tree *tree, mcsg_mesh *mesh, const char *label,
                                    mcsg_node_id *out, mcsg_error *err);

/*
 * Frames. A transform that turns space (its linear part is not a scaling along the axes,
 * possibly with the axes permuted or mirrored) keeps planes coplanar only up to rounding:
 * leaves turned one by one get faces ~1e-16 apart that were meant to coincide. A node
 * can be marked as a frame: its subtree is evaluated on its own, in its own
 * coordinates, where each leaf under it has a `local` mesh, and the result, turned by the
 * frame's matrix into the enclosing frame (or the world), takes the node's place. Every
 * leaf's `mesh` stays the flattened one (the world coordinates), as for any tree.
 */

/* Frames marked in the tree (0: evaluation is the plain one). */
size_t mci_tree_frame_count(const mcsg_tree *tree);
/* A frame's matrix into the enclosing frame (or the world), or NULL if `node` is none. */
const double *mci_tree_frame(const mcsg_tree *tree, mcsg_node_id node);
/* A leaf's mesh in the coordinates of its innermost frame, or NULL. */
const mcsg_mesh *mci_tree_leaf_local(const mcsg_tree *tree, mcsg_node_id node);
/* Give a leaf its local mesh (the tree takes the arrays; *local is zeroed). */
void mci_tree_set_local(mcsg_tree *tree, mcsg_node_id leaf, mcsg_mesh *local);
/* A frame that will not be marked closes over `leaf`: its local mesh is moved into the
 * enclosing frame by `matrix`, or dropped when there is none (matrix NULL). */
void mci_tree_close_frame(mcsg_tree *tree, mcsg_node_id leaf, const double *matrix);
/* Mark `node` as a frame with `matrix` into the enclosing frame; a node already marked
 * (a frame directly inside another) gets the product, its own matrix applied first. */
mcsg_status mci_tree_set_frame(mcsg_tree *tree, mcsg_node_id node, const double matrix[12],
                               mcsg_error *err);

/* Ask for a leaf to be tested for crossing itself in every evaluation (a mesh that
 * rounding may have made cross itself, such as a frame's turned result). */
void mci_tree_set_tests_crossing(mcsg_tree *tree, mcsg_node_id leaf);
bool mci_tree_tests_crossing(const mcsg_tree *tree, mcsg_node_id leaf);
/* For that test: the leaf's mesh is `mesh` (same triangles; borrowed, it must outlive the
 * tree's evaluations) moved vertex by vertex, so that two of its triangles can meet only
 * where their boxes in `mesh`, grown by `margin`, meet (csg/shell_crossing.h). */
void mci_tree_set_crossing_boxes(mcsg_tree *tree, mcsg_node_id leaf, const mcsg_mesh *mesh,
                                 double margin);
/* The mesh set above (NULL if none) and its margin. */
const mcsg_mesh *mci_tree_crossing_boxes(const mcsg_tree *tree, mcsg_node_id leaf,
                                         double *margin);

/* A leaf the library made (a frame's turned result): what rounding left in it, such as
 * triangles of zero area, is logged as information, not as a warning about the input. */
void mci_tree_set_made(mcsg_tree *tree, mcsg_node_id leaf);
bool mci_tree_is_made(const mcsg_tree *tree, mcsg_node_id leaf);

/* The resolved options the tree was created with. */
const mci_ctx *mci_tree_ctx(const mcsg_tree *tree);

#endif
