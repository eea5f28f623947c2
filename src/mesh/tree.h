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

/* The resolved options the tree was created with. */
const mci_ctx *mci_tree_ctx(const mcsg_tree *tree);

#endif
