/*
 * CSG tree machinery (src/csg/csgtree.c): label algebra, positive trees, and CSGlists
 * checked against an independent reference on random trees.
 *
 * The reference looks at one spot of space where some primitives' surfaces pass (each
 * with its outward normal +n or -n) and the others contain the spot or not. It
 * evaluates the original tree (differences and all) as plain booleans at the two points
 * just behind and just in front of the spot (p - en, p + en). The result has a face
 * there facing +n exactly when it contains p - en and not p + en (and -n conversely),
 * and it must have exactly one such face: the CSGlists of all the primitives passing
 * there, given the labels of their faces, must accept exactly one face, with that
 * normal, or none.
 */
#include "testlib.h"
#include "csg/csgtree.h"

#include <stdlib.h>
#include <string.h>

TEST(label_rules)
{
    CHECK(mci_label_union(MCI_LABEL_SAME, MCI_LABEL_OPPO) == MCI_LABEL_IN);
    CHECK(mci_label_intersection(MCI_LABEL_SAME, MCI_LABEL_OPPO) == MCI_LABEL_OUT);
    CHECK(mci_label_union(MCI_LABEL_SAME, MCI_LABEL_OUT) == MCI_LABEL_SAME);
    CHECK(mci_label_intersection(MCI_LABEL_OPPO, MCI_LABEL_IN) == MCI_LABEL_OPPO);
    CHECK(mci_label_union(MCI_LABEL_UNKNOWN, MCI_LABEL_IN) == MCI_LABEL_IN);
    CHECK(mci_label_union(MCI_LABEL_UNKNOWN, MCI_LABEL_OUT) == MCI_LABEL_UNKNOWN);
    CHECK(mci_label_intersection(MCI_LABEL_UNKNOWN, MCI_LABEL_OUT) == MCI_LABEL_OUT);
    CHECK(mci_label_complement(MCI_LABEL_SAME) == MCI_LABEL_OPPO);
    CHECK(mci_label_complement(MCI_LABEL_IN) == MCI_LABEL_OUT);
    CHECK(mci_label_reverse(MCI_LABEL_IN) == MCI_LABEL_IN);
}

/* ---------------------------------------------------------------------------------- */
/* Random trees                                                                        */

enum spot { SPOT_OUT, SPOT_IN, SPOT_FACING_PLUS, SPOT_FACING_MINUS };

typedef struct random_tree {
    mcsg_tree *tree;
    mcsg_node_id leaf_ids[16];
    int leaf_count;
} random_tree;

static uint64_t rng = 0xc5c5c5c5u;

static void random_tree_build(random_tree *r, const mcsg_mesh *cube, const mcsg_mesh *empty)
{
    mcsg_error err;
    mcsg_node_id pending[16];
    int count = test_random_int(&rng, 1, 8);
    r->leaf_count = 0;
    CHECK_OK(mcsg_tree_create(NULL, &r->tree, &err), &err);
    for (int i = 0; i < count; i++) {
        /* One leaf in ten is empty: a constant in the positive tree. */
        bool is_empty = test_random_int(&rng, 0, 9) == 0;
        CHECK_OK(mcsg_tree_add_leaf(r->tree, is_empty ? empty : cube, NULL, NULL, &pending[i],
                                    &err), &err);
        if (!is_empty)
            r->leaf_ids[r->leaf_count++] = pending[i];
    }
    while (count > 1) {
        int take = test_random_int(&rng, 2, count < 3 ? count : 3);
        int at = test_random_int(&rng, 0, count - take);
        mcsg_node_kind op = (mcsg_node_kind)test_random_int(&rng, 1, 3);
        mcsg_node_id id;
        CHECK_OK(mcsg_tree_add_op(r->tree, op, pending + at, (size_t)take, NULL, &id, &err),
                 &err);
        pending[at] = id;
        memmove(pending + at + 1, pending + at + take,
                (size_t)(count - at - take) * sizeof *pending);
        count -= take - 1;
    }
    CHECK_OK(mcsg_tree_set_root(r->tree, pending[0], &err), &err);
}

/* Membership of the original tree at p - en (side 0) or p + en (side 1). Nodes are
 * numbered children first, so one pass in id order evaluates everything. */
static bool member(const random_tree *r, const enum spot *spot_of_node, int side)
{
    size_t n = mcsg_tree_node_count(r->tree);
    bool *in = calloc(n, sizeof *in), result;
    for (mcsg_node_id id = 0; id < n; id++) {
        mcsg_node_kind kind = mcsg_tree_node_kind(r->tree, id);
        size_t k = mcsg_tree_child_count(r->tree, id);
        if (kind == MCSG_NODE_LEAF) {
            enum spot s = spot_of_node[id];
            in[id] = s == SPOT_IN || (s == SPOT_FACING_PLUS && side == 0) ||
                     (s == SPOT_FACING_MINUS && side == 1);
            continue;
        }
        in[id] = kind == MCSG_NODE_INTERSECTION && k > 0;
        for (size_t c = 0; c < k; c++) {
            bool x = in[mcsg_tree_child(r->tree, id, c)];
            if (kind == MCSG_NODE_UNION)
                in[id] = in[id] || x;
            else if (kind == MCSG_NODE_INTERSECTION)
                in[id] = in[id] && x;
            else
                in[id] = c == 0 ? x : in[id] && !x;
        }
    }
    result = in[mcsg_tree_root(r->tree)];
    free(in);
    return result;
}

/* Label of the spot with respect to primitive `s`, for a face whose output normal is
 * +n (plus) or -n. */
static mci_label label_for(enum spot s, bool plus)
{
    if (s == SPOT_IN)
        return MCI_LABEL_IN;
    if (s == SPOT_OUT)
        return MCI_LABEL_OUT;
    return (s == SPOT_FACING_PLUS) == plus ? MCI_LABEL_SAME : MCI_LABEL_OPPO;
}

/* Faces the CSGlists keep at the spot: count[0] facing +n, count[1] facing -n. */
static void kept_faces(const mci_ptree *t, const enum spot *spot_of_leaf, int count[2])
{
    mci_csg_entry *list = malloc(t->node_count * sizeof *list);
    mci_label *scratch = malloc(t->node_count * sizeof *scratch);
    mci_label labels[16];
    count[0] = count[1] = 0;
    for (uint32_t m = 0; m < t->leaf_count; m++) {
        bool complement = t->nodes[t->leaf_node[m]].complement, plus;
        size_t n;
        if (spot_of_leaf[m] != SPOT_FACING_PLUS && spot_of_leaf[m] != SPOT_FACING_MINUS)
            continue;
        /* A complemented primitive contributes its face reversed. */
        plus = (spot_of_leaf[m] == SPOT_FACING_PLUS) != complement;
        for (uint32_t k = 0; k < t->leaf_count; k++)
            labels[k] = label_for(spot_of_leaf[k], plus);
        n = mci_csglist(t, m, list);
        if (mci_csglist_accepts(t, list, n, labels, scratch) == 1)
            count[plus ? 0 : 1]++;
    }
    free(list);
    free(scratch);
}

static void check_one_configuration(const random_tree *r, const mci_ptree *t)
{
    size_t n = mcsg_tree_node_count(r->tree);
    enum spot *spot_of_node = calloc(n, sizeof *spot_of_node), spot_of_leaf[16];
    bool behind, ahead;
    int count[2];
    for (int i = 0; i < r->leaf_count; i++)
        spot_of_node[r->leaf_ids[i]] = (enum spot)test_random_int(&rng, 0, 3);
    for (uint32_t m = 0; m < t->leaf_count; m++)
        spot_of_leaf[m] = spot_of_node[t->leaf_source[m]];
    behind = member(r, spot_of_node, 0);
    ahead = member(r, spot_of_node, 1);
    kept_faces(t, spot_of_leaf, count);
    CHECK_MSG(count[0] == (behind && !ahead) && count[1] == (!behind && ahead),
              "faces kept +n %d, -n %d; result behind %d, ahead %d", count[0], count[1],
              behind, ahead);
    free(spot_of_node);
}

typedef void (*tree_check)(const random_tree *r, const mci_ptree *t, const mci_ctx *ctx);

/* Run `check` on 3000 random trees of unit cubes (one leaf in ten empty). */
static void for_random_trees(tree_check check)
{
    mcsg_mesh cube, empty = {0};
    double size[3] = {1, 1, 1};
    mcsg_error err;
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    for (int trial = 0; trial < 3000; trial++) {
        random_tree r;
        mci_ptree t;
        random_tree_build(&r, &cube, &empty);
        CHECK_OK(mci_ptree_build(&ctx, r.tree, &t, &err), &err);
        CHECK_EQ_SIZE(t.leaf_count, (size_t)r.leaf_count);
        check(&r, &t, &ctx);
        mci_ptree_free(&ctx, &t);
        mcsg_tree_free(r.tree);
    }
    mcsg_mesh_free(&cube, NULL);
}

static void check_configurations(const random_tree *r, const mci_ptree *t, const mci_ctx *ctx)
{
    (void)ctx;
    for (int c = 0; c < 20; c++)
        check_one_configuration(r, t);
}

TEST(csglists_keep_exactly_the_result_faces)
{
    for_random_trees(check_configurations);
}

/* Blist: for a primitive's CSGlist trimmed by some leaves known OUT (as the classifier
 * trims by boxes), the compiled walk must agree with evaluating the whole list, for
 * every IN/OUT labelling of the other leaves; and defer (-1) on SAME/OPPO. */
static void check_blist(const mci_ptree *t, uint32_t m, const mci_ctx *ctx)
{
    mci_csg_entry *list = malloc((t->node_count + 1) * sizeof *list);
    mci_label *scratch = malloc((t->node_count + 1) * sizeof *scratch), trim[16], labels[16];
    size_t n = mci_csglist(t, m, list), kept = 0;
    bool rejected = false;
    mci_blist b;
    for (uint32_t k = 0; k < t->leaf_count; k++)
        trim[k] = k != m && test_random_int(&rng, 0, 2) == 0 ? MCI_LABEL_OUT : MCI_LABEL_UNKNOWN;
    mci_csg_entry *full = malloc((n + 1) * sizeof *full);
    memcpy(full, list, n * sizeof *list);
    for (size_t i = 0; i < n; i++) {
        mci_label l = mci_ptree_eval(t, list[i].node, trim, scratch);
        if (l == MCI_LABEL_UNKNOWN)
            list[kept++] = list[i];
        else if (!(list[i].desired & MCI_LABEL_BIT(l)))
            rejected = true;
    }
    CHECK(mci_blist_build(ctx, t, list, kept, trim, &b));
    CHECK(b.count <= t->leaf_count);
    for (int trial = 0; trial < 16; trial++) {
        int expected;
        for (uint32_t k = 0; k < t->leaf_count; k++)
            labels[k] = trim[k] == MCI_LABEL_OUT ? MCI_LABEL_OUT
                                                 : (mci_label)test_random_int(&rng, 0, 1);
        expected = mci_csglist_accepts(t, full, n, labels, scratch);
        CHECK_MSG(expected == (rejected ? 0 : mci_blist_accepts(&b, labels)),
                  "primitive %u: list says %d, blist %d", m, expected,
                  mci_blist_accepts(&b, labels));
    }
    for (uint32_t k = 0; k < t->leaf_count; k++)
        labels[k] = trim[k] == MCI_LABEL_OUT ? MCI_LABEL_OUT : MCI_LABEL_SAME;
    CHECK(b.count == 0 || mci_blist_accepts(&b, labels) == -1);
    mci_blist_free(ctx, &b);
    free(full);
    free(list);
    free(scratch);
}

static void check_blists(const random_tree *r, const mci_ptree *t, const mci_ctx *ctx)
{
    (void)r;
    for (uint32_t m = 0; m < t->leaf_count; m++)
        check_blist(t, m, ctx);
}

TEST(blists_agree_with_csglists)
{
    for_random_trees(check_blists);
}

/* The sparse trimming must give mci_csglist_trim's answer: the same rejection, and when
 * not rejected the same entries with the same desired labels in the same order, for the
 * labels OUT everywhere but UNKNOWN at the given primitives. */
static void check_sparse_trim(const mci_ptree *t, const mci_trim_base *base, uint32_t m,
                              const uint32_t *unknown, size_t k, const mci_ctx *ctx)
{
    mci_csg_entry *want = malloc((t->node_count + 1) * sizeof *want);
    mci_csg_entry *got = malloc((t->node_count + 1) * sizeof *got);
    mci_label *labels = malloc((t->leaf_count + 1) * sizeof *labels);
    mci_label *scratch = malloc((t->node_count + 1) * sizeof *scratch);
    size_t n_want, n_got;
    bool rej_want, rej_got;
    for (uint32_t l = 0; l < t->leaf_count; l++)
        labels[l] = MCI_LABEL_OUT;
    for (size_t i = 0; i < k; i++)
        labels[unknown[i]] = MCI_LABEL_UNKNOWN;
    n_want = mci_csglist_trim(t, m, labels, scratch, want, &rej_want);
    CHECK(mci_csglist_trim_sparse(ctx, t, base, m, unknown, k, got, &n_got, &rej_got));
    CHECK_MSG(rej_want == rej_got, "primitive %u: rejected %d, sparse %d", m, rej_want, rej_got);
    if (!rej_want && rej_want == rej_got) {
        CHECK_MSG(n_want == n_got, "primitive %u: %zu entries, sparse %zu", m, n_want, n_got);
        for (size_t i = 0; i < n_want && n_want == n_got; i++)
            CHECK_MSG(want[i].node == got[i].node && want[i].desired == got[i].desired,
                      "primitive %u entry %zu: node %u/%u desired %u/%u", m, i, want[i].node,
                      got[i].node, want[i].desired, got[i].desired);
    }
    free(want);
    free(got);
    free(labels);
    free(scratch);
}

/* Every primitive of the tree with random unknown sets (each other primitive unknown
 * with probability `p` in 1/8ths). */
static void check_sparse_trims(const mci_ptree *t, const mci_ctx *ctx, int p, int rounds)
{
    mci_trim_base base;
    uint32_t *unknown = malloc((t->leaf_count + 1) * sizeof *unknown);
    CHECK(mci_trim_base_init(ctx, t, &base));
    for (uint32_t m = 0; m < t->leaf_count; m++)
        for (int round = 0; round < rounds; round++) {
            size_t k = 0;
            for (uint32_t l = 0; l < t->leaf_count; l++)
                if (l != m && test_random_int(&rng, 0, 7) < p)
                    unknown[k++] = l;
            check_sparse_trim(t, &base, m, unknown, k, ctx);
        }
    mci_trim_base_free(ctx, &base);
    free(unknown);
}

static void check_sparse_trims_random(const random_tree *r, const mci_ptree *t,
                                      const mci_ctx *ctx)
{
    (void)r;
    check_sparse_trims(t, ctx, test_random_int(&rng, 0, 8), 4);
}

TEST(sparse_trimming_agrees_with_trimming)
{
    for_random_trees(check_sparse_trims_random);
}

/* A plate minus 300 holes, some holes a union of two (so that unions sit under the
 * difference), then unioned with bars: a flat tree like a CAD part's, where the sparse
 * trimming skips the unknown-free siblings by their counts. */
TEST(sparse_trimming_on_flat_trees)
{
    mcsg_mesh cube;
    double size[3] = {1, 1, 1};
    mcsg_error err;
    mcsg_tree *tree;
    mcsg_node_id ops[302], bars[4], pair[2];
    size_t nops = 0;
    mci_ptree t;
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &cube, NULL, NULL, &ops[nops++], &err), &err);
    for (int i = 0; i < 300; i++) {
        CHECK_OK(mcsg_tree_add_leaf(tree, &cube, NULL, NULL, &pair[0], &err), &err);
        if (i % 10 == 3) {
            CHECK_OK(mcsg_tree_add_leaf(tree, &cube, NULL, NULL, &pair[1], &err), &err);
            CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, pair, 2, NULL, &pair[0], &err),
                     &err);
        }
        ops[nops++] = pair[0];
    }
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_DIFFERENCE, ops, nops, NULL, &bars[0], &err),
             &err);
    for (int i = 1; i < 4; i++)
        CHECK_OK(mcsg_tree_add_leaf(tree, &cube, NULL, NULL, &bars[i], &err), &err);
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, bars, 4, NULL, &pair[0], &err), &err);
    CHECK_OK(mcsg_tree_set_root(tree, pair[0], &err), &err);
    CHECK_OK(mci_ptree_build(&ctx, tree, &t, &err), &err);
    CHECK_EQ_SIZE(t.leaf_count, 334);
    for (int p = 0; p <= 2; p++)
        check_sparse_trims(&t, &ctx, p, 3);
    mci_ptree_free(&ctx, &t);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&cube, NULL);
}

TEST(difference_becomes_intersection_with_complements)
{
    mcsg_mesh cube;
    double size[3] = {1, 1, 1};
    mcsg_error err;
    mcsg_tree *tree;
    mcsg_node_id leaf[3], diff;
    mci_ptree t;
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    for (int i = 0; i < 3; i++)
        CHECK_OK(mcsg_tree_add_leaf(tree, &cube, NULL, NULL, &leaf[i], &err), &err);
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_DIFFERENCE, leaf, 3, NULL, &diff, &err), &err);
    CHECK_OK(mci_ptree_build(&ctx, tree, &t, &err), &err);
    CHECK_EQ_SIZE(t.node_count, 4);
    CHECK(t.nodes[3].kind == MCI_PNODE_INTERSECTION);
    CHECK(!t.nodes[t.leaf_node[0]].complement);
    CHECK(t.nodes[t.leaf_node[1]].complement && t.nodes[t.leaf_node[2]].complement);
    mci_ptree_free(&ctx, &t);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&cube, NULL);
}

/* 100,000 nested differences: no recursion anywhere. */
TEST(deep_trees_build)
{
    mcsg_mesh cube;
    double size[3] = {1, 1, 1};
    mcsg_error err;
    mcsg_tree *tree;
    mcsg_node_id node, pair[2];
    mci_ptree t;
    mci_ctx ctx;
    mci_csg_entry *list;
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &cube, NULL, NULL, &node, &err), &err);
    for (int i = 0; i < 100000; i++) {
        pair[1] = node;
        CHECK_OK(mcsg_tree_add_leaf(tree, &cube, NULL, NULL, &pair[0], &err), &err);
        CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_DIFFERENCE, pair, 2, NULL, &node, &err),
                 &err);
    }
    CHECK_OK(mci_ptree_build(&ctx, tree, &t, &err), &err);
    CHECK_EQ_SIZE(t.leaf_count, 100001);
    list = malloc(t.node_count * sizeof *list);
    /* The innermost leaf hangs under every level: one sibling per level. */
    CHECK_EQ_SIZE(mci_csglist(&t, (uint32_t)t.leaf_count - 1, list), 100000);
    free(list);
    mci_ptree_free(&ctx, &t);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&cube, NULL);
}

int main(void)
{
    RUN(label_rules);
    RUN(csglists_keep_exactly_the_result_faces);
    RUN(blists_agree_with_csglists);
    RUN(sparse_trimming_agrees_with_trimming);
    RUN(sparse_trimming_on_flat_trees);
    RUN(difference_becomes_intersection_with_complements);
    RUN(deep_trees_build);
    return test_summary();
}
