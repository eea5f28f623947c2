/*
 * CSG trees: leaves own a mesh (already transformed), inner nodes are union,
 * intersection or difference over earlier nodes. Nodes live in one array in creation
 * order and children are index ranges into one shared array of node ids; since a child
 * is always created before its parent and has at most one parent, the structure is a
 * forest that every consumer can walk without recursion, whatever its depth.
 */
#include "mesh/tree.h"

#include <string.h>

typedef struct tree_node {
    mcsg_mesh mesh;      /* leaves only; zeroed for operations */
    mcsg_mesh local;     /* leaves inside a frame: the mesh in that frame; else zeroed */
    double *frame;       /* owned: this node's subtree is a frame (mesh/tree.h), or NULL */
    char *label;         /* owned copy, or NULL for "" */
    size_t first_child;  /* index into mcsg_tree.children */
    uint32_t child_count;
    uint8_t kind;        /* mcsg_node_kind */
    uint8_t has_parent;
    uint8_t tests_crossing; /* leaves: always tested for crossing themselves */
    uint8_t made;           /* leaves: made by the library (tree.h) */
    const mcsg_mesh *box_mesh; /* leaves: borrowed, for that test's boxes (tree.h) */
    double box_margin;
} tree_node;

struct mcsg_tree {
    mci_ctx ctx;
    tree_node *nodes;
    size_t node_count, node_cap;
    mcsg_node_id *children;
    size_t children_len, children_cap;
    size_t leaf_count;
    size_t frame_count;
    mcsg_node_id root; /* MCSG_NO_NODE: the last node added */
};

const char *mcsg_node_kind_name(mcsg_node_kind kind)
{
    switch (kind) {
    case MCSG_NODE_LEAF: return "leaf";
    case MCSG_NODE_UNION: return "union";
    case MCSG_NODE_INTERSECTION: return "intersection";
    case MCSG_NODE_DIFFERENCE: return "difference";
    }
    return "invalid";
}

mcsg_status mcsg_tree_create(const mcsg_options *opts, mcsg_tree **out, mcsg_error *err)
{
    mci_ctx ctx;
    mcsg_tree *tree;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_tree_create: NULL output");
    *out = NULL;
    mci_ctx_init(&ctx, opts);
    tree = mci_malloc(&ctx, sizeof *tree);
    if (!tree)
        return mci_fail_nomem(err, "creating a CSG tree");
    memset(tree, 0, sizeof *tree);
    tree->ctx = ctx;
    tree->root = MCSG_NO_NODE;
    *out = tree;
    return MCSG_OK;
}

void mcsg_tree_free(mcsg_tree *tree)
{
    mci_ctx ctx;
    if (!tree)
        return;
    ctx = tree->ctx;
    for (size_t i = 0; i < tree->node_count; i++) {
        mci_mesh_free(&ctx, &tree->nodes[i].mesh);
        mci_mesh_free(&ctx, &tree->nodes[i].local);
        mci_free(&ctx, tree->nodes[i].frame);
        mci_free(&ctx, tree->nodes[i].label);
    }
    mci_free(&ctx, tree->nodes);
    mci_free(&ctx, tree->children);
    mci_free(&ctx, tree);
}

const mci_ctx *mci_tree_ctx(const mcsg_tree *tree) { return &tree->ctx; }

/* Make room for one more node and `child_count` more child ids. */
static bool reserve(mcsg_tree *tree, size_t child_count)
{
    if (tree->node_count == tree->node_cap) {
        size_t cap = tree->node_cap ? tree->node_cap * 2 : 16;
        tree_node *grown = mci_realloc_array(&tree->ctx, tree->nodes, cap, sizeof *grown);
        if (!grown)
            return false;
        tree->nodes = grown;
        tree->node_cap = cap;
    }
    if (child_count > tree->children_cap - tree->children_len) {
        size_t cap = tree->children_cap ? tree->children_cap : 16;
        mcsg_node_id *grown;
        while (cap - tree->children_len < child_count) {
            if (cap > SIZE_MAX / 2)
                return false;
            cap *= 2;
        }
        grown = mci_realloc_array(&tree->ctx, tree->children, cap, sizeof *grown);
        if (!grown)
            return false;
        tree->children = grown;
        tree->children_cap = cap;
    }
    return true;
}

/* Reserve space and copy the label: everything that can fail before a node is added. */
static mcsg_status prepare_node(mcsg_tree *tree, size_t child_count, const char *label,
                                char **label_copy, mcsg_error *err)
{
    *label_copy = NULL;
    if (tree->node_count >= MCSG_NO_NODE)
        return mci_fail(err, MCSG_ERR_LIMIT, "CSG tree: more than %u nodes",
                        (unsigned)MCSG_NO_NODE - 1);
    if (!reserve(tree, child_count))
        return mci_fail_nomem(err, "adding a CSG tree node");
    if (label && label[0]) {
        *label_copy = mci_strdup(&tree->ctx, label);
        if (!*label_copy)
            return mci_fail_nomem(err, "adding a CSG tree node");
    }
    return MCSG_OK;
}

/* Append a node whose space prepare_node reserved. */
static mcsg_node_id commit_node(mcsg_tree *tree, mcsg_node_kind kind, char *label,
                                const mcsg_node_id *children, size_t child_count)
{
    tree_node *node = &tree->nodes[tree->node_count];
    memset(node, 0, sizeof *node);
    node->kind = (uint8_t)kind;
    node->label = label;
    node->first_child = tree->children_len;
    node->child_count = (uint32_t)child_count;
    for (size_t i = 0; i < child_count; i++)
        tree->nodes[children[i]].has_parent = 1;
    if (child_count)
        memcpy(tree->children + tree->children_len, children, child_count * sizeof *children);
    tree->children_len += child_count;
    return (mcsg_node_id)tree->node_count++;
}

static mcsg_status check_leaf_mesh(const mcsg_mesh *mesh, mcsg_error *err)
{
    if ((mesh->vertex_count && !mesh->vertices) || (mesh->triangle_count && !mesh->triangles))
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "CSG tree leaf: mesh arrays are NULL");
    if (mesh->vertex_count > UINT32_MAX || mesh->triangle_count > UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "CSG tree leaf: mesh too large");
    for (size_t i = 0; i < 3 * mesh->triangle_count; i++) {
        if (mesh->triangles[i] >= mesh->vertex_count)
            return mci_fail(err, MCSG_ERR_INVALID_MESH, "CSG tree leaf: triangle %zu uses "
                            "vertex %u of %zu", i / 3, mesh->triangles[i], mesh->vertex_count);
    }
    return MCSG_OK;
}

/* Report a new node's id (or MCSG_NO_NODE); done last, so that `out` may point into
 * the caller's array of children. */
static mcsg_status report(mcsg_node_id *out, mcsg_node_id id, mcsg_status st)
{
    if (out)
        *out = st == MCSG_OK ? id : MCSG_NO_NODE;
    return st;
}

mcsg_status mci_tree_add_leaf_owned(mcsg_tree *tree, mcsg_mesh *mesh, const char *label,
                                    mcsg_node_id *out, mcsg_error *err)
{
    char *label_copy;
    mcsg_node_id id;
    mcsg_status st = check_leaf_mesh(mesh, err);
    if (st == MCSG_OK)
        st = prepare_node(tree, 0, label, &label_copy, err);
    if (st != MCSG_OK) {
        mci_mesh_free(&tree->ctx, mesh);
        return report(out, MCSG_NO_NODE, st);
    }
    id = commit_node(tree, MCSG_NODE_LEAF, label_copy, NULL, 0);
    tree->nodes[id].mesh = *mesh;
    memset(mesh, 0, sizeof *mesh);
    tree->leaf_count++;
    return report(out, id, MCSG_OK);
}

mcsg_status mcsg_tree_add_leaf(mcsg_tree *tree, const mcsg_mesh *mesh, const double matrix[12],
                               const char *label, mcsg_node_id *out, mcsg_error *err)
{
    mcsg_mesh copy;
    mcsg_status st;
    if (!tree || !mesh)
        return report(out, MCSG_NO_NODE, mci_fail(err, MCSG_ERR_INVALID_ARG,
                                                  "mcsg_tree_add_leaf: NULL argument"));
    st = check_leaf_mesh(mesh, err);
    if (st == MCSG_OK)
        st = mci_mesh_alloc(&tree->ctx, &copy, mesh->vertex_count, mesh->triangle_count, err);
    if (st != MCSG_OK)
        return report(out, MCSG_NO_NODE, st);
    if (mesh->vertex_count)
        memcpy(copy.vertices, mesh->vertices, mesh->vertex_count * 3 * sizeof(double));
    if (mesh->triangle_count)
        memcpy(copy.triangles, mesh->triangles, mesh->triangle_count * 3 * sizeof(uint32_t));
    if (matrix)
        mcsg_mesh_transform(&copy, matrix);
    return mci_tree_add_leaf_owned(tree, &copy, label, out, err);
}

mcsg_status mcsg_tree_add_leaf_take(mcsg_tree *tree, mcsg_mesh *mesh, const double matrix[12],
                                    const char *label, mcsg_node_id *out, mcsg_error *err)
{
    mcsg_status st;
    if (!tree || !mesh)
        return report(out, MCSG_NO_NODE, mci_fail(err, MCSG_ERR_INVALID_ARG,
                                                  "mcsg_tree_add_leaf_take: NULL argument"));
    /* Checked before the transform, which reads the vertices the indices name. */
    st = check_leaf_mesh(mesh, err);
    if (st != MCSG_OK) {
        mci_mesh_free(&tree->ctx, mesh);
        return report(out, MCSG_NO_NODE, st);
    }
    if (matrix)
        mcsg_mesh_transform(mesh, matrix);
    return mci_tree_add_leaf_owned(tree, mesh, label, out, err);
}

/* Every child must exist, have no parent yet, and appear once. Marks the children as
 * having a parent (in O(child_count), however many there are); on failure every mark
 * made here is undone. */
static mcsg_status mark_children(mcsg_tree *tree, const mcsg_node_id *children,
                                 size_t child_count, mcsg_error *err)
{
    for (size_t i = 0; i < child_count; i++) {
        mcsg_node_id c = children[i];
        int twice = 0;
        if (c < tree->node_count && !tree->nodes[c].has_parent) {
            tree->nodes[c].has_parent = 1;
            continue;
        }
        for (size_t j = 0; j < i; j++) {
            twice |= children[j] == c;
            tree->nodes[children[j]].has_parent = 0;
        }
        if (c >= tree->node_count)
            return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_tree_add_op: child %zu is "
                            "node %u, but the tree has %zu nodes", i, c, tree->node_count);
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_tree_add_op: node %u %s", c,
                        twice ? "is listed twice" : "already has a parent");
    }
    return MCSG_OK;
}

mcsg_status mcsg_tree_add_op(mcsg_tree *tree, mcsg_node_kind op, const mcsg_node_id *children,
                             size_t child_count, const char *label, mcsg_node_id *out,
                             mcsg_error *err)
{
    char *label_copy;
    mcsg_status st;
    if (!tree || (child_count && !children))
        return report(out, MCSG_NO_NODE, mci_fail(err, MCSG_ERR_INVALID_ARG,
                                                  "mcsg_tree_add_op: NULL argument"));
    if (op != MCSG_NODE_UNION && op != MCSG_NODE_INTERSECTION && op != MCSG_NODE_DIFFERENCE)
        return report(out, MCSG_NO_NODE, mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_tree_add_op:"
                                                  " %d is not an operation", (int)op));
    st = prepare_node(tree, child_count, label, &label_copy, err);
    if (st == MCSG_OK) {
        st = mark_children(tree, children, child_count, err);
        if (st != MCSG_OK)
            mci_free(&tree->ctx, label_copy);
    }
    if (st != MCSG_OK)
        return report(out, MCSG_NO_NODE, st);
    return report(out, commit_node(tree, op, label_copy, children, child_count), MCSG_OK);
}

mcsg_status mcsg_tree_set_root(mcsg_tree *tree, mcsg_node_id node, mcsg_error *err)
{
    if (!tree)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_tree_set_root: NULL tree");
    if (node >= tree->node_count)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_tree_set_root: node %u, but the "
                        "tree has %zu nodes", node, tree->node_count);
    tree->root = node;
    return MCSG_OK;
}

mcsg_node_id mcsg_tree_root(const mcsg_tree *tree)
{
    if (!tree || tree->node_count == 0)
        return MCSG_NO_NODE;
    return tree->root != MCSG_NO_NODE ? tree->root : (mcsg_node_id)(tree->node_count - 1);
}

size_t mcsg_tree_node_count(const mcsg_tree *tree) { return tree ? tree->node_count : 0; }

size_t mcsg_tree_leaf_count(const mcsg_tree *tree) { return tree ? tree->leaf_count : 0; }

static const tree_node *find_node(const mcsg_tree *tree, mcsg_node_id node)
{
    return (tree && node < tree->node_count) ? &tree->nodes[node] : NULL;
}

mcsg_node_kind mcsg_tree_node_kind(const mcsg_tree *tree, mcsg_node_id node)
{
    const tree_node *n = find_node(tree, node);
    /* As the header says, 0 (MCSG_NODE_LEAF) for a bad id; its leaf mesh is NULL. */
    return n ? (mcsg_node_kind)n->kind : MCSG_NODE_LEAF;
}

size_t mcsg_tree_child_count(const mcsg_tree *tree, mcsg_node_id node)
{
    const tree_node *n = find_node(tree, node);
    return n ? n->child_count : 0;
}

mcsg_node_id mcsg_tree_child(const mcsg_tree *tree, mcsg_node_id node, size_t index)
{
    const tree_node *n = find_node(tree, node);
    if (!n || index >= n->child_count)
        return MCSG_NO_NODE;
    return tree->children[n->first_child + index];
}

const char *mcsg_tree_node_label(const mcsg_tree *tree, mcsg_node_id node)
{
    const tree_node *n = find_node(tree, node);
    return (n && n->label) ? n->label : "";
}

const mcsg_mesh *mcsg_tree_leaf_mesh(const mcsg_tree *tree, mcsg_node_id node)
{
    const tree_node *n = find_node(tree, node);
    return (n && n->kind == MCSG_NODE_LEAF) ? &n->mesh : NULL;
}

size_t mci_tree_frame_count(const mcsg_tree *tree) { return tree->frame_count; }

const double *mci_tree_frame(const mcsg_tree *tree, mcsg_node_id node)
{
    const tree_node *n = find_node(tree, node);
    return n ? n->frame : NULL;
}

const mcsg_mesh *mci_tree_leaf_local(const mcsg_tree *tree, mcsg_node_id node)
{
    const tree_node *n = find_node(tree, node);
    return (n && n->kind == MCSG_NODE_LEAF && n->local.vertices) ? &n->local : NULL;
}

void mci_tree_set_local(mcsg_tree *tree, mcsg_node_id leaf, mcsg_mesh *local)
{
    tree_node *n = &tree->nodes[leaf];
    mci_mesh_free(&tree->ctx, &n->local);
    n->local = *local;
    memset(local, 0, sizeof *local);
}

void mci_tree_close_frame(mcsg_tree *tree, mcsg_node_id leaf, const double *matrix)
{
    tree_node *n = &tree->nodes[leaf];
    if (matrix && n->local.vertices)
        mcsg_mesh_transform(&n->local, matrix);
    else
        mci_mesh_free(&tree->ctx, &n->local);
}

/* (a after b) as row-major 3x4 matrices: apply b first. */
static void compose_after(const double a[12], const double b[12], double out[12])
{
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 4; c++) {
            double sum = a[4 * r] * b[c] + a[4 * r + 1] * b[4 + c] + a[4 * r + 2] * b[8 + c];
            out[4 * r + c] = c == 3 ? sum + a[4 * r + 3] : sum;
        }
    }
}

mcsg_status mci_tree_set_frame(mcsg_tree *tree, mcsg_node_id node, const double matrix[12],
                               mcsg_error *err)
{
    tree_node *n = &tree->nodes[node];
    if (n->frame) {
        double inner[12];
        memcpy(inner, n->frame, sizeof inner);
        compose_after(matrix, inner, n->frame);
        return MCSG_OK;
    }
    n->frame = mci_malloc(&tree->ctx, 12 * sizeof *n->frame);
    if (!n->frame)
        return mci_fail_nomem(err, "marking a frame in a CSG tree");
    memcpy(n->frame, matrix, 12 * sizeof *n->frame);
    tree->frame_count++;
    return MCSG_OK;
}

void mci_tree_set_tests_crossing(mcsg_tree *tree, mcsg_node_id leaf)
{
    tree->nodes[leaf].tests_crossing = 1;
}

void mci_tree_set_crossing_boxes(mcsg_tree *tree, mcsg_node_id leaf, const mcsg_mesh *mesh,
                                 double margin)
{
    tree->nodes[leaf].box_mesh = mesh;
    tree->nodes[leaf].box_margin = margin;
}

const mcsg_mesh *mci_tree_crossing_boxes(const mcsg_tree *tree, mcsg_node_id leaf,
                                         double *margin)
{
    const tree_node *n = find_node(tree, leaf);
    *margin = n ? n->box_margin : 0;
    return n ? n->box_mesh : NULL;
}

void mci_tree_set_made(mcsg_tree *tree, mcsg_node_id leaf) { tree->nodes[leaf].made = 1; }

bool mci_tree_is_made(const mcsg_tree *tree, mcsg_node_id leaf)
{
    const tree_node *n = find_node(tree, leaf);
    return n && n->made;
}

bool mci_tree_tests_crossing(const mcsg_tree *tree, mcsg_node_id leaf)
{
    const tree_node *n = find_node(tree, leaf);
    return n && n->tests_crossing;
}
