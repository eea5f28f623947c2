/*
 * CSG trees: building leaves (copied and transformed) and operations, the queries,
 * every invalid use (bad child, second parent, duplicate child, bad kind, bad mesh),
 * deep and wide trees built and freed without recursion, the owning leaf (internal and
 * public: mcsg_tree_add_leaf_take), and allocation failures at every step.
 */
#include "testlib.h"
#include "mesh/tree.h"

#include <stdlib.h>
#include <string.h>

static const double tetra_vertices[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const uint32_t tetra_triangles[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

static mcsg_mesh tetra(void)
{
    mcsg_mesh m;
    m.vertices = (double *)tetra_vertices;
    m.triangles = (uint32_t *)tetra_triangles;
    m.vertex_count = 4;
    m.triangle_count = 4;
    return m;
}

TEST(empty_tree)
{
    mcsg_tree *tree;
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK(mcsg_tree_root(tree) == MCSG_NO_NODE);
    CHECK_EQ_SIZE(mcsg_tree_node_count(tree), 0);
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 0);
    CHECK(mcsg_tree_set_root(tree, 0, &err) == MCSG_ERR_INVALID_ARG);
    mcsg_tree_free(tree);
    mcsg_tree_free(NULL);
    CHECK(mcsg_tree_create(NULL, NULL, &err) == MCSG_ERR_INVALID_ARG);
}

TEST(leaves_are_copied_and_transformed)
{
    const double shift[12] = {1, 0, 0, 10, 0, 1, 0, 20, 0, 0, 1, 30};
    const double mirror[12] = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    mcsg_mesh m = tetra();
    char label[32] = "tetra at t.scad:1:1";
    mcsg_tree *tree;
    mcsg_node_id a, b, c;
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &m, NULL, label, &a, &err), &err);
    label[0] = 'X'; /* the tree keeps its own copy */
    CHECK_OK(mcsg_tree_add_leaf(tree, &m, shift, NULL, &b, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &m, mirror, "", &c, &err), &err);
    CHECK(a == 0 && b == 1 && c == 2);
    CHECK(strcmp(mcsg_tree_node_label(tree, a), "tetra at t.scad:1:1") == 0);
    CHECK(strcmp(mcsg_tree_node_label(tree, b), "") == 0);
    CHECK(mcsg_tree_leaf_mesh(tree, a)->vertices != m.vertices);
    CHECK_EQ_DOUBLE(mcsg_tree_leaf_mesh(tree, a)->vertices[3], 1);
    CHECK_EQ_DOUBLE(mcsg_tree_leaf_mesh(tree, b)->vertices[3], 11);
    CHECK_EQ_DOUBLE(mcsg_tree_leaf_mesh(tree, b)->vertices[11], 31);
    CHECK_EQ_DOUBLE(tetra_vertices[3], 1); /* the input is untouched */
    /* A mirror keeps the leaf outward: the transform reverses its triangles. */
    CHECK_EQ_DOUBLE(mcsg_tree_leaf_mesh(tree, c)->vertices[3], -1);
    CHECK(test_signed_volume(mcsg_tree_leaf_mesh(tree, c)) > 0);
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 3);
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_LEAF);
    CHECK(mcsg_tree_root(tree) == c); /* default root: the last node */
    mcsg_tree_free(tree);
}

TEST(operations_and_queries)
{
    mcsg_mesh m = tetra();
    mcsg_tree *tree;
    mcsg_node_id leaf[3], diff, inter, root;
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    for (int i = 0; i < 3; i++)
        CHECK_OK(mcsg_tree_add_leaf(tree, &m, NULL, NULL, &leaf[i], &err), &err);
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_DIFFERENCE, leaf, 2, "difference() at x:1:1",
                              &diff, &err), &err);
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_INTERSECTION, NULL, 0, NULL, &inter, &err), &err);
    {
        mcsg_node_id kids[3] = {diff, leaf[2], inter};
        CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, kids, 3, NULL, &root, &err), &err);
    }
    CHECK_EQ_SIZE(mcsg_tree_node_count(tree), 6);
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 3);
    CHECK(mcsg_tree_root(tree) == root);
    CHECK(mcsg_tree_node_kind(tree, diff) == MCSG_NODE_DIFFERENCE);
    CHECK(mcsg_tree_node_kind(tree, inter) == MCSG_NODE_INTERSECTION);
    CHECK(mcsg_tree_node_kind(tree, root) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, root), 3);
    CHECK(mcsg_tree_child(tree, root, 0) == diff && mcsg_tree_child(tree, root, 2) == inter);
    CHECK(mcsg_tree_child(tree, diff, 1) == leaf[1]);
    CHECK(mcsg_tree_child(tree, diff, 2) == MCSG_NO_NODE);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, inter), 0);
    CHECK(mcsg_tree_leaf_mesh(tree, diff) == NULL);
    CHECK(strcmp(mcsg_tree_node_label(tree, diff), "difference() at x:1:1") == 0);
    CHECK_OK(mcsg_tree_set_root(tree, diff, &err), &err);
    CHECK(mcsg_tree_root(tree) == diff);
    /* Out-of-range ids. */
    CHECK(mcsg_tree_child(tree, 99, 0) == MCSG_NO_NODE);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, 99), 0);
    CHECK(mcsg_tree_node_kind(tree, 99) == MCSG_NODE_LEAF);
    CHECK(mcsg_tree_leaf_mesh(tree, 99) == NULL);
    CHECK(strcmp(mcsg_tree_node_label(tree, MCSG_NO_NODE), "") == 0);
    CHECK(strcmp(mcsg_node_kind_name(MCSG_NODE_LEAF), "leaf") == 0);
    CHECK(strcmp(mcsg_node_kind_name(MCSG_NODE_UNION), "union") == 0);
    CHECK(strcmp(mcsg_node_kind_name(MCSG_NODE_INTERSECTION), "intersection") == 0);
    CHECK(strcmp(mcsg_node_kind_name(MCSG_NODE_DIFFERENCE), "difference") == 0);
    CHECK(mcsg_tree_node_count(NULL) == 0 && mcsg_tree_root(NULL) == MCSG_NO_NODE);
    mcsg_tree_free(tree);
}

TEST(invalid_operations_change_nothing)
{
    mcsg_mesh m = tetra();
    mcsg_tree *tree;
    mcsg_node_id a, b, u, out = 0;
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &m, NULL, NULL, &a, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &m, NULL, NULL, &b, &err), &err);
    {
        mcsg_node_id bad[2] = {a, 7};
        CHECK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, bad, 2, NULL, &out, &err) ==
              MCSG_ERR_INVALID_ARG);
        CHECK(out == MCSG_NO_NODE);
        CHECK_CONTAINS(err.message, "node 7");
    }
    {
        mcsg_node_id twice[3] = {a, b, a};
        CHECK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, twice, 3, NULL, NULL, &err) ==
              MCSG_ERR_INVALID_ARG);
        CHECK_CONTAINS(err.message, "listed twice");
    }
    CHECK(mcsg_tree_add_op(tree, MCSG_NODE_LEAF, &a, 1, NULL, NULL, &err) ==
          MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_tree_add_op(tree, (mcsg_node_kind)42, &a, 1, NULL, NULL, &err) ==
          MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, NULL, 2, NULL, NULL, &err) ==
          MCSG_ERR_INVALID_ARG);
    CHECK_EQ_SIZE(mcsg_tree_node_count(tree), 2);
    /* The failed calls left a and b free to be used. */
    {
        mcsg_node_id both[2] = {b, a};
        CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_DIFFERENCE, both, 2, NULL, &u, &err), &err);
        CHECK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, &a, 1, NULL, NULL, &err) ==
              MCSG_ERR_INVALID_ARG);
        CHECK_CONTAINS(err.message, "already has a parent");
    }
    CHECK_EQ_SIZE(mcsg_tree_node_count(tree), 3);
    mcsg_tree_free(tree);
}

TEST(invalid_leaves)
{
    uint32_t bad_triangles[3] = {0, 1, 4};
    mcsg_mesh m = tetra(), empty = {NULL, NULL, 0, 0};
    mcsg_tree *tree;
    mcsg_node_id id;
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    m.triangles = bad_triangles;
    m.triangle_count = 1;
    CHECK(mcsg_tree_add_leaf(tree, &m, NULL, NULL, &id, &err) == MCSG_ERR_INVALID_MESH);
    CHECK(id == MCSG_NO_NODE);
    m.triangles = NULL;
    CHECK(mcsg_tree_add_leaf(tree, &m, NULL, NULL, &id, &err) == MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_tree_add_leaf(tree, NULL, NULL, NULL, &id, &err) == MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_tree_add_leaf(NULL, &empty, NULL, NULL, &id, &err) == MCSG_ERR_INVALID_ARG);
    CHECK_EQ_SIZE(mcsg_tree_node_count(tree), 0);
    /* An empty mesh is a valid (empty) leaf. */
    CHECK_OK(mcsg_tree_add_leaf(tree, &empty, NULL, NULL, &id, &err), &err);
    CHECK_EQ_SIZE(mcsg_tree_leaf_mesh(tree, id)->triangle_count, 0);
    mcsg_tree_free(tree);
}

TEST(owned_leaf_takes_the_mesh)
{
    mcsg_tree *tree;
    mcsg_mesh m, bad;
    mcsg_node_id id;
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_mesh_copy(&(mcsg_mesh){(double *)tetra_vertices, (uint32_t *)tetra_triangles,
                                         4, 4}, NULL, &m, &err), &err);
    {
        double *arrays = m.vertices;
        CHECK_OK(mci_tree_add_leaf_owned(tree, &m, "owned", &id, &err), &err);
        CHECK(m.vertices == NULL && m.vertex_count == 0);
        CHECK(mcsg_tree_leaf_mesh(tree, id)->vertices == arrays);
    }
    /* On failure the mesh is released too (LSan checks it). */
    CHECK_OK(mcsg_mesh_copy(&(mcsg_mesh){(double *)tetra_vertices, (uint32_t *)tetra_triangles,
                                         4, 4}, NULL, &bad, &err), &err);
    bad.triangles[0] = 9;
    CHECK(mci_tree_add_leaf_owned(tree, &bad, NULL, &id, &err) == MCSG_ERR_INVALID_MESH);
    CHECK(bad.vertices == NULL && bad.triangles == NULL);
    CHECK(mci_tree_ctx(tree) != NULL);
    mcsg_tree_free(tree);
}

TEST(public_take_moves_and_transforms)
{
    const double shift[12] = {1, 0, 0, 5, 0, 1, 0, 0, 0, 0, 1, 0};
    mcsg_tree *tree;
    mcsg_mesh m, bad;
    mcsg_node_id id;
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_mesh_copy(&(mcsg_mesh){(double *)tetra_vertices, (uint32_t *)tetra_triangles,
                                         4, 4}, NULL, &m, &err), &err);
    {
        double *arrays = m.vertices;
        const mcsg_mesh *leaf;
        CHECK_OK(mcsg_tree_add_leaf_take(tree, &m, shift, "taken", &id, &err), &err);
        CHECK(m.vertices == NULL && m.triangles == NULL && m.vertex_count == 0);
        leaf = mcsg_tree_leaf_mesh(tree, id);
        CHECK(leaf->vertices == arrays); /* no copy */
        CHECK(leaf->vertices[0] == 5 && leaf->vertices[3] == 6 && leaf->vertex_count == 4);
        CHECK(strcmp(mcsg_tree_node_label(tree, id), "taken") == 0);
    }
    /* A bad mesh is refused and released (LSan checks it); *mesh is zeroed. */
    CHECK_OK(mcsg_mesh_copy(&(mcsg_mesh){(double *)tetra_vertices, (uint32_t *)tetra_triangles,
                                         4, 4}, NULL, &bad, &err), &err);
    bad.triangles[5] = 4;
    CHECK(mcsg_tree_add_leaf_take(tree, &bad, shift, NULL, &id, &err) == MCSG_ERR_INVALID_MESH);
    CHECK(id == MCSG_NO_NODE && bad.vertices == NULL && bad.triangles == NULL);
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 1);
    /* Without a tree nothing is taken. */
    m = tetra();
    CHECK(mcsg_tree_add_leaf_take(NULL, &m, NULL, NULL, &id, &err) == MCSG_ERR_INVALID_ARG);
    CHECK(m.vertices == tetra_vertices);
    CHECK(mcsg_tree_add_leaf_take(tree, NULL, NULL, NULL, &id, &err) == MCSG_ERR_INVALID_ARG);
    mcsg_tree_free(tree);
}

/* Depth of the tree below the root, by an explicit stack. */
static size_t tree_depth(const mcsg_tree *tree)
{
    size_t n = mcsg_tree_node_count(tree), top = 0, deepest = 0;
    mcsg_node_id *node = malloc(n * sizeof *node);
    size_t *depth = malloc(n * sizeof *depth);
    node[top] = mcsg_tree_root(tree);
    depth[top++] = 0;
    while (top > 0) {
        mcsg_node_id id = node[--top];
        size_t d = depth[top];
        deepest = d > deepest ? d : deepest;
        for (size_t i = 0; i < mcsg_tree_child_count(tree, id); i++) {
            node[top] = mcsg_tree_child(tree, id, i);
            depth[top++] = d + 1;
        }
    }
    free(node);
    free(depth);
    return deepest;
}

TEST(deep_and_wide_trees)
{
    const size_t depth = 200000, width = 100000;
    mcsg_mesh m = tetra();
    mcsg_tree *tree;
    mcsg_node_id id, *ids = malloc(width * sizeof *ids);
    mcsg_error err;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &m, NULL, "leaf", &id, &err), &err);
    for (size_t i = 0; i < depth; i++)
        CHECK_OK(mcsg_tree_add_op(tree, i % 2 ? MCSG_NODE_UNION : MCSG_NODE_DIFFERENCE, &id, 1,
                                  "level", &id, &err), &err);
    CHECK_EQ_SIZE(tree_depth(tree), depth);
    mcsg_tree_free(tree); /* freed without recursion */
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    for (size_t i = 0; i < width; i++)
        CHECK_OK(mcsg_tree_add_leaf(tree, &m, NULL, NULL, &ids[i], &err), &err);
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, ids, width, NULL, &id, &err), &err);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, id), width);
    CHECK(mcsg_tree_child(tree, id, width - 1) == ids[width - 1]);
    mcsg_tree_free(tree);
    free(ids);
}

/* Build a small tree and free it; stop at the first failure and return its status. */
static mcsg_status build_small_tree(const void *ctx, const mcsg_options *opts, mcsg_error *err)
{
    const double shift[12] = {1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0};
    mcsg_mesh m = tetra();
    mcsg_node_id ids[40], id;
    mcsg_tree *tree = NULL;
    mcsg_status st = mcsg_tree_create(opts, &tree, err);
    (void)ctx;
    for (int i = 0; i < 40 && st == MCSG_OK; i++) {
        mcsg_mesh copy;
        if (i % 3)
            st = mcsg_tree_add_leaf(tree, &m, i % 2 ? shift : NULL, "a leaf label", &ids[i], err);
        else if ((st = mcsg_mesh_copy(&m, opts, &copy, err)) == MCSG_OK)
            st = mcsg_tree_add_leaf_take(tree, &copy, i % 2 ? shift : NULL, "taken", &ids[i],
                                         err);
    }
    for (int i = 0; i < 40 && st == MCSG_OK; i += 4)
        st = mcsg_tree_add_op(tree, MCSG_NODE_DIFFERENCE, ids + i, 4, "op", &ids[i / 4], err);
    if (st == MCSG_OK)
        st = mcsg_tree_add_op(tree, MCSG_NODE_UNION, ids, 10, "root", &id, err);
    mcsg_tree_free(tree);
    return st;
}

TEST(every_allocation_failure_is_clean)
{
    CHECK(test_allocation_failures("small tree", build_small_tree, NULL, false) > 10);
}

int main(void)
{
    RUN(empty_tree);
    RUN(leaves_are_copied_and_transformed);
    RUN(operations_and_queries);
    RUN(invalid_operations_change_nothing);
    RUN(invalid_leaves);
    RUN(owned_leaf_takes_the_mesh);
    RUN(public_take_moves_and_transforms);
    RUN(deep_and_wide_trees);
    RUN(every_allocation_failure_is_clean);
    return test_summary();
}
