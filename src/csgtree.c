/*
 * CSG tree machinery (see csgtree.h): Requicha and Tilove's label combination rules as
 * stated in the paper's Eq. 3, Rossignac and Voelcker's positive form (Eq. 4), and the
 * paper's CSGlist (§5.3) with the desired labels of Eq. 2.
 *
 * The positive tree is built and evaluated without recursion: nodes are stored in
 * post-order with their subtree sizes, so a subtree is a contiguous range evaluated
 * left to right (children before parents).
 */
#include "csgtree.h"

#include <string.h>

#define NONE UINT32_MAX

mci_label mci_label_complement(mci_label l)
{
    static const mci_label flip[] = {MCI_LABEL_IN, MCI_LABEL_OUT, MCI_LABEL_OPPO,
                                     MCI_LABEL_SAME, MCI_LABEL_UNKNOWN};
    return flip[l];
}

mci_label mci_label_reverse(mci_label l)
{
    return l == MCI_LABEL_SAME ? MCI_LABEL_OPPO : l == MCI_LABEL_OPPO ? MCI_LABEL_SAME : l;
}

mci_label mci_label_union(mci_label a, mci_label b)
{
    if (a == MCI_LABEL_IN || b == MCI_LABEL_IN)
        return MCI_LABEL_IN;
    if (a == MCI_LABEL_OUT)
        return b;
    if (b == MCI_LABEL_OUT)
        return a;
    if (a == MCI_LABEL_UNKNOWN || b == MCI_LABEL_UNKNOWN)
        return MCI_LABEL_UNKNOWN;
    return a == b ? a : MCI_LABEL_IN; /* SAME u OPPO: the two sides meet inside */
}

mci_label mci_label_intersection(mci_label a, mci_label b)
{
    if (a == MCI_LABEL_OUT || b == MCI_LABEL_OUT)
        return MCI_LABEL_OUT;
    if (a == MCI_LABEL_IN)
        return b;
    if (b == MCI_LABEL_IN)
        return a;
    if (a == MCI_LABEL_UNKNOWN || b == MCI_LABEL_UNKNOWN)
        return MCI_LABEL_UNKNOWN;
    return a == b ? a : MCI_LABEL_OUT; /* SAME n OPPO: a sheet of no volume */
}

/* ---------------------------------------------------------------------------------- */
/* Positive tree                                                                       */

typedef struct frame {
    mcsg_node_id node;
    uint8_t complement;
    uint32_t next_child;
} frame;

typedef struct builder {
    const mcsg_tree *tree;
    mci_ptree *t;
    frame *stack;
    size_t depth;
    uint32_t *done; /* emitted nodes waiting for their parent */
    size_t done_count;
    size_t child_used; /* entries of t->child filled (each node is a child once) */
} builder;

/* A node's positive kind: De Morgan turns a complemented union into an intersection
 * of complements and so on; A - B - C is A n B^c n C^c. */
static uint8_t positive_kind(mcsg_node_kind kind, bool complement)
{
    bool union_like = kind == MCSG_NODE_UNION;
    return union_like != complement ? MCI_PNODE_UNION : MCI_PNODE_INTERSECTION;
}

static void emit(builder *b, const frame *f)
{
    mci_ptree *t = b->t;
    mcsg_node_kind kind = mcsg_tree_node_kind(b->tree, f->node);
    size_t n = kind == MCSG_NODE_LEAF ? 0 : mcsg_tree_child_count(b->tree, f->node);
    uint32_t index = (uint32_t)t->node_count++;
    mci_pnode *p = &t->nodes[index];
    memset(p, 0, sizeof *p);
    p->parent = NONE;
    p->size = 1;
    if (kind == MCSG_NODE_LEAF) {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(b->tree, f->node);
        if (m && m->triangle_count > 0) {
            p->kind = MCI_PNODE_LEAF;
            p->complement = f->complement;
            p->leaf = (uint32_t)t->leaf_count;
            t->leaf_node[t->leaf_count] = index;
            t->leaf_mesh[t->leaf_count] = m;
            t->leaf_source[t->leaf_count++] = f->node;
        } else {
            p->kind = f->complement ? MCI_PNODE_FULL : MCI_PNODE_EMPTY;
        }
    } else if (n == 0) {
        p->kind = f->complement ? MCI_PNODE_FULL : MCI_PNODE_EMPTY;
    } else {
        p->kind = positive_kind(kind, f->complement);
        p->count = (uint32_t)n;
        /* The children are the last n nodes emitted and not yet claimed. */
        p->first = (uint32_t)b->child_used;
        b->child_used += n;
        for (size_t i = 0; i < n; i++) {
            uint32_t c = b->done[b->done_count - n + i];
            t->child[p->first + i] = c;
            t->nodes[c].parent = index;
            p->size += t->nodes[c].size;
        }
        b->done_count -= n;
    }
    b->done[b->done_count++] = index;
}

static void walk(builder *b, mcsg_node_id root)
{
    b->stack[b->depth++] = (frame){root, 0, 0};
    while (b->depth > 0) {
        frame *f = &b->stack[b->depth - 1];
        mcsg_node_kind kind = mcsg_tree_node_kind(b->tree, f->node);
        size_t n = kind == MCSG_NODE_LEAF ? 0 : mcsg_tree_child_count(b->tree, f->node);
        if (f->next_child < n) {
            mcsg_node_id c = mcsg_tree_child(b->tree, f->node, f->next_child);
            /* The subtrahends of a difference are complemented. */
            uint8_t cc = kind == MCSG_NODE_DIFFERENCE && f->next_child > 0 ? !f->complement
                                                                          : f->complement;
            f->next_child++;
            b->stack[b->depth++] = (frame){c, cc, 0};
            continue;
        }
        emit(b, f);
        b->depth--;
    }
}

mcsg_status mci_ptree_build(const mci_ctx *ctx, const mcsg_tree *tree, mci_ptree *out,
                            mcsg_error *err)
{
    size_t n = tree ? mcsg_tree_node_count(tree) : 0;
    builder b = {tree, out, NULL, 0, NULL, 0, 0};
    memset(out, 0, sizeof *out);
    if (n == 0 || mcsg_tree_root(tree) == MCSG_NO_NODE)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "the CSG tree is empty");
    out->nodes = mci_malloc_array(ctx, n, sizeof *out->nodes);
    out->child = mci_malloc_array(ctx, n, sizeof *out->child);
    out->leaf_node = mci_malloc_array(ctx, n, sizeof *out->leaf_node);
    out->leaf_mesh = mci_malloc_array(ctx, n, sizeof *out->leaf_mesh);
    out->leaf_source = mci_malloc_array(ctx, n, sizeof *out->leaf_source);
    b.stack = mci_malloc_array(ctx, n, sizeof *b.stack);
    b.done = mci_malloc_array(ctx, n, sizeof *b.done);
    if (!out->nodes || !out->child || !out->leaf_node || !out->leaf_mesh ||
        !out->leaf_source || !b.stack || !b.done) {
        mci_free(ctx, b.stack);
        mci_free(ctx, b.done);
        mci_ptree_free(ctx, out);
        return mci_fail_nomem(err, "preparing the CSG tree");
    }
    walk(&b, mcsg_tree_root(tree));
    mci_free(ctx, b.stack);
    mci_free(ctx, b.done);
    return MCSG_OK;
}

void mci_ptree_free(const mci_ctx *ctx, mci_ptree *t)
{
    mci_free(ctx, t->nodes);
    mci_free(ctx, t->child);
    mci_free(ctx, t->leaf_node);
    mci_free(ctx, t->leaf_mesh);
    mci_free(ctx, t->leaf_source);
    memset(t, 0, sizeof *t);
}

/* ---------------------------------------------------------------------------------- */
/* Evaluation and CSGlists                                                             */

mci_label mci_ptree_eval(const mci_ptree *t, uint32_t node, const mci_label *leaf_labels,
                         mci_label *scratch)
{
    for (uint32_t i = node + 1 - t->nodes[node].size; i <= node; i++) {
        const mci_pnode *p = &t->nodes[i];
        mci_label l;
        switch (p->kind) {
        case MCI_PNODE_LEAF:
            l = leaf_labels[p->leaf];
            l = p->complement ? mci_label_complement(l) : l;
            break;
        case MCI_PNODE_EMPTY:
            l = MCI_LABEL_OUT;
            break;
        case MCI_PNODE_FULL:
            l = MCI_LABEL_IN;
            break;
        case MCI_PNODE_UNION:
            l = MCI_LABEL_OUT;
            for (uint32_t c = 0; c < p->count; c++)
                l = mci_label_union(l, scratch[t->child[p->first + c]]);
            break;
        default:
            l = MCI_LABEL_IN;
            for (uint32_t c = 0; c < p->count; c++)
                l = mci_label_intersection(l, scratch[t->child[p->first + c]]);
            break;
        }
        scratch[i] = l;
    }
    return scratch[node];
}

size_t mci_csglist(const mci_ptree *t, uint32_t leaf, mci_csg_entry *out)
{
    size_t n = 0;
    uint32_t node = t->leaf_node[leaf];
    while (t->nodes[node].parent != NONE) {
        const mci_pnode *a = &t->nodes[t->nodes[node].parent];
        uint8_t base = a->kind == MCI_PNODE_UNION ? MCI_LABEL_BIT(MCI_LABEL_OUT)
                                                  : MCI_LABEL_BIT(MCI_LABEL_IN);
        bool after_path = false;
        for (uint32_t c = 0; c < a->count; c++) {
            uint32_t s = t->child[a->first + c];
            if (s == node) {
                after_path = true;
                continue;
            }
            out[n].node = s;
            out[n++].desired = (uint8_t)(base | (after_path ? MCI_LABEL_BIT(MCI_LABEL_SAME) : 0));
        }
        node = t->nodes[node].parent;
    }
    return n;
}

int mci_csglist_accepts(const mci_ptree *t, const mci_csg_entry *list, size_t n,
                        const mci_label *leaf_labels, mci_label *scratch)
{
    bool unknown = false;
    for (size_t i = 0; i < n; i++) {
        mci_label l = mci_ptree_eval(t, list[i].node, leaf_labels, scratch);
        if (l == MCI_LABEL_UNKNOWN)
            unknown = true;
        else if (!(list[i].desired & MCI_LABEL_BIT(l)))
            return 0;
    }
    return unknown ? -1 : 1;
}
