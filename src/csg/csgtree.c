/*
 * CSG tree machinery (see csgtree.h): Requicha and Tilove's label combination rules as
 * stated in the paper's Eq. 3, Rossignac and Voelcker's positive form (Eq. 4), and the
 * paper's CSGlist (§5.3) with the desired labels of Eq. 2, and Hable and Rossignac's
 * Blist for the lists' fast evaluation (§5.4).
 *
 * The positive tree is built and evaluated without recursion: nodes are stored in
 * post-order with their subtree sizes, so a subtree is a contiguous range evaluated
 * left to right (children before parents).
 */
#include "csg/csgtree.h"
#include "base/sort.h"

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
    out->leaf_winding = mci_calloc_array(ctx, n, 1);
    out->leaf_shell = mci_calloc_array(ctx, n, sizeof *out->leaf_shell);
    out->leaf_shells = mci_calloc_array(ctx, n, sizeof *out->leaf_shells);
    out->leaf_crossing = mci_calloc_array(ctx, n, 1);
    out->leaf_mates = mci_calloc_array(ctx, n, sizeof *out->leaf_mates);
    out->leaf_cleaned = mci_calloc_array(ctx, n, sizeof *out->leaf_cleaned);
    out->leaf_face_of = mci_calloc_array(ctx, n, sizeof *out->leaf_face_of);
    b.stack = mci_malloc_array(ctx, n, sizeof *b.stack);
    b.done = mci_malloc_array(ctx, n, sizeof *b.done);
    if (!out->nodes || !out->child || !out->leaf_node || !out->leaf_mesh ||
        !out->leaf_source || !out->leaf_winding || !out->leaf_shell || !out->leaf_shells ||
        !out->leaf_crossing || !out->leaf_mates || !out->leaf_cleaned ||
        !out->leaf_face_of || !b.stack || !b.done) {
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
    mci_free(ctx, t->leaf_winding);
    for (size_t l = 0; t->leaf_shell && l < t->leaf_count; l++)
        mci_free(ctx, t->leaf_shell[l]);
    mci_free(ctx, t->leaf_shell);
    mci_free(ctx, t->leaf_shells);
    mci_free(ctx, t->leaf_crossing);
    for (size_t l = 0; t->leaf_mates && l < t->leaf_count; l++)
        mci_edge_mates_free(ctx, &t->leaf_mates[l]);
    mci_free(ctx, t->leaf_mates);
    for (size_t l = 0; t->leaf_cleaned && l < t->leaf_count; l++) {
        if (t->leaf_cleaned[l])
            mci_mesh_free(ctx, t->leaf_cleaned[l]);
        mci_free(ctx, t->leaf_cleaned[l]);
        mci_free(ctx, t->leaf_face_of[l]);
    }
    mci_free(ctx, t->leaf_cleaned);
    mci_free(ctx, t->leaf_face_of);
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

/* mci_ptree_eval, without the loop for a primitive (most entries of a long chain's lists
 * are one). */
static mci_label subtree_label(const mci_ptree *t, uint32_t node, const mci_label *leaf_labels,
                               mci_label *scratch)
{
    const mci_pnode *p = &t->nodes[node];
    if (p->kind == MCI_PNODE_LEAF)
        return p->complement ? mci_label_complement(leaf_labels[p->leaf]) : leaf_labels[p->leaf];
    return mci_ptree_eval(t, node, leaf_labels, scratch);
}

size_t mci_csglist_trim(const mci_ptree *t, uint32_t leaf, const mci_label *leaf_labels,
                        mci_label *scratch, mci_csg_entry *list, bool *rejected)
{
    size_t n = mci_csglist(t, leaf, list), kept = 0;
    *rejected = false;
    for (size_t i = 0; i < n && !*rejected; i++) {
        mci_label l = subtree_label(t, list[i].node, leaf_labels, scratch);
        if (l == MCI_LABEL_UNKNOWN)
            list[kept++] = list[i];
        else if (!(list[i].desired & MCI_LABEL_BIT(l)))
            *rejected = true;
    }
    return kept;
}

/* ---------------------------------------------------------------------------------- */
/* Trimming when few primitives are unknown                                            */

static mci_label absorbing_value(const mci_pnode *p)
{
    return p->kind == MCI_PNODE_UNION ? MCI_LABEL_IN : MCI_LABEL_OUT;
}

/* The value of an operation none of whose children has the absorbing value. */
static mci_label neutral_value(const mci_pnode *p)
{
    return p->kind == MCI_PNODE_UNION ? MCI_LABEL_OUT : MCI_LABEL_IN;
}

static bool is_operation(const mci_pnode *p)
{
    return p->kind == MCI_PNODE_UNION || p->kind == MCI_PNODE_INTERSECTION;
}

bool mci_trim_base_init(const mci_ctx *ctx, const mci_ptree *t, mci_trim_base *base)
{
    base->all_out = mci_malloc_array(ctx, t->node_count + 1, sizeof *base->all_out);
    base->absorbing = mci_calloc_array(ctx, t->node_count + 1, sizeof *base->absorbing);
    base->path_bad = mci_malloc_array(ctx, t->node_count + 1, sizeof *base->path_bad);
    if (!base->all_out || !base->absorbing || !base->path_bad) {
        mci_trim_base_free(ctx, base);
        return false;
    }
    for (uint32_t i = 0; i < t->node_count; i++) { /* post-order: children first */
        const mci_pnode *p = &t->nodes[i];
        mci_label v;
        if (p->kind == MCI_PNODE_LEAF)
            v = p->complement ? MCI_LABEL_IN : MCI_LABEL_OUT;
        else if (!is_operation(p))
            v = p->kind == MCI_PNODE_FULL ? MCI_LABEL_IN : MCI_LABEL_OUT;
        else {
            for (uint32_t c = 0; c < p->count; c++)
                base->absorbing[i] += base->all_out[t->child[p->first + c]] == absorbing_value(p);
            v = base->absorbing[i] > 0 ? absorbing_value(p) : neutral_value(p);
        }
        base->all_out[i] = (uint8_t)v;
    }
    for (uint32_t i = (uint32_t)t->node_count; i-- > 0;) { /* parents first */
        uint32_t a = t->nodes[i].parent;
        base->path_bad[i] = a == NONE ? 0
                                      : base->path_bad[a] + base->absorbing[a] -
                                            (base->all_out[i] == absorbing_value(&t->nodes[a]));
    }
    return true;
}

void mci_trim_base_free(const mci_ctx *ctx, mci_trim_base *base)
{
    mci_free(ctx, base->all_out);
    mci_free(ctx, base->absorbing);
    mci_free(ctx, base->path_bad);
    memset(base, 0, sizeof *base);
}

/* The subtrees hanging off the path of the primitive being trimmed (branches) that hold
 * unknown primitives, and the nodes between those and the branch (marked). */
typedef struct sparse_trim {
    const mci_ptree *t;
    const mci_trim_base *base;
    uint32_t path_node;   /* the primitive's node: its ancestors are the path */
    uint8_t *value;       /* per node: its value once known; 0xFF where not marked */
    uint32_t *absorbing;  /* per marked operation: children holding its absorbing value */
    uint32_t *unknowns;   /* per marked operation: children UNKNOWN */
    uint32_t *pending;    /* per marked operation: marked children not evaluated yet */
    uint32_t *ready;      /* marked nodes whose children are all evaluated (a stack) */
    size_t nready;
    uint64_t *branches;   /* parent << 32 | node */
    size_t nbranches;
} sparse_trim;

/* Whether node a is an ancestor of the primitive's node (its subtree range holds it). */
static bool on_path(const sparse_trim *st, uint32_t a)
{
    return a >= st->path_node && a + 1 - st->t->nodes[a].size <= st->path_node;
}

static void mark(sparse_trim *st, uint32_t x)
{
    st->value[x] = MCI_LABEL_UNKNOWN; /* until evaluated */
    st->absorbing[x] = st->base->absorbing[x];
}

/* Marks each unknown primitive's node and its ancestors below the path (each once),
 * counting marked children in their parents; the last one below the path is a branch. */
static void mark_unknown_paths(sparse_trim *st, const uint32_t *unknown, size_t k)
{
    const mci_ptree *t = st->t;
    for (size_t i = 0; i < k; i++) {
        uint32_t x = t->leaf_node[unknown[i]], parent;
        if (st->value[x] != 0xFF)
            continue;
        mark(st, x);
        st->ready[st->nready++] = x;
        for (;; x = parent) {
            parent = t->nodes[x].parent;
            if (on_path(st, parent)) { /* never NONE: the root is on every path */
                st->branches[st->nbranches++] = (uint64_t)parent << 32 | x;
                break;
            }
            st->pending[parent]++;
            if (st->value[parent] != 0xFF)
                break;
            mark(st, parent);
        }
    }
}

/* The marked nodes' values, each once its marked children have theirs: an unknown
 * primitive is UNKNOWN; an operation is absorbing when a child is, else UNKNOWN when a
 * child is, else neutral; each value then corrects its parent's counts (which held the
 * all-OUT values), up to the branches. */
static void evaluate_marked(sparse_trim *st)
{
    const mci_ptree *t = st->t;
    while (st->nready > 0) {
        uint32_t x = st->ready[--st->nready], parent = t->nodes[x].parent;
        const mci_pnode *p = &t->nodes[x];
        mci_label v = MCI_LABEL_UNKNOWN;
        if (is_operation(p))
            v = st->absorbing[x] > 0   ? absorbing_value(p)
                : st->unknowns[x] > 0 ? MCI_LABEL_UNKNOWN
                                      : neutral_value(p);
        st->value[x] = (uint8_t)v;
        if (on_path(st, parent))
            continue;
        st->absorbing[parent] += (v == absorbing_value(&t->nodes[parent])) -
                                 (st->base->all_out[x] == absorbing_value(&t->nodes[parent]));
        st->unknowns[parent] += v == MCI_LABEL_UNKNOWN;
        if (--st->pending[parent] == 0)
            st->ready[st->nready++] = parent;
    }
}

/* The entries from the branches, from the primitive upwards and in child order (post-
 * order numbers: ancestors above their descendants, later children above earlier
 * ones); false on a rejection: a sibling of the path with its parent's absorbing value
 * (by the all-OUT counts along the path, corrected at the branches). */
static bool entries_from_branches(sparse_trim *st, mci_csg_entry *list, size_t *n)
{
    const mci_ptree *t = st->t;
    uint32_t bad = st->base->path_bad[st->path_node];
    mci_sort_u64(st->branches, st->nbranches);
    for (size_t i = 0; i < st->nbranches; i++) {
        uint32_t a = (uint32_t)(st->branches[i] >> 32), s = (uint32_t)st->branches[i];
        bad -= st->base->all_out[s] == absorbing_value(&t->nodes[a]);
    }
    if (bad > 0)
        return false;
    for (size_t i = 0; i < st->nbranches; i++) {
        uint32_t a = (uint32_t)(st->branches[i] >> 32), s = (uint32_t)st->branches[i];
        /* s comes after the path's child of a (the child whose range holds the
         * primitive) exactly when s is numbered after the primitive */
        bool after = s > st->path_node;
        if (st->value[s] == absorbing_value(&t->nodes[a]))
            return false;
        if (st->value[s] == MCI_LABEL_UNKNOWN) {
            list[*n].node = s;
            list[(*n)++].desired = (uint8_t)(MCI_LABEL_BIT(neutral_value(&t->nodes[a])) |
                                             (after ? MCI_LABEL_BIT(MCI_LABEL_SAME) : 0));
        }
    }
    return true;
}

bool mci_csglist_trim_sparse(const mci_ctx *ctx, const mci_ptree *t, const mci_trim_base *base,
                             uint32_t leaf, const uint32_t *unknown, size_t k,
                             mci_csg_entry *list, size_t *count, bool *rejected)
{
    sparse_trim st = {t, base, t->leaf_node[leaf], NULL, NULL, NULL, NULL, NULL, 0, NULL, 0};
    size_t nodes = t->node_count + 1;
    bool ok;
    st.value = mci_malloc_array(ctx, nodes, sizeof *st.value);
    st.absorbing = mci_malloc_array(ctx, nodes, sizeof *st.absorbing);
    st.unknowns = mci_calloc_array(ctx, nodes, sizeof *st.unknowns);
    st.pending = mci_calloc_array(ctx, nodes, sizeof *st.pending);
    st.ready = mci_malloc_array(ctx, k + 1, sizeof *st.ready);
    st.branches = mci_malloc_array(ctx, k + 1, sizeof *st.branches);
    ok = st.value && st.absorbing && st.unknowns && st.pending && st.ready && st.branches;
    *count = 0;
    *rejected = false;
    if (ok) {
        memset(st.value, 0xFF, nodes);
        mark_unknown_paths(&st, unknown, k);
        evaluate_marked(&st);
        *rejected = !entries_from_branches(&st, list, count);
    }
    mci_free(ctx, st.value);
    mci_free(ctx, st.absorbing);
    mci_free(ctx, st.unknowns);
    mci_free(ctx, st.pending);
    mci_free(ctx, st.ready);
    mci_free(ctx, st.branches);
    return ok;
}

/* ---------------------------------------------------------------------------------- */
/* Blist                                                                               */

typedef struct blist_builder {
    const mci_ptree *t;
    mci_label *value;  /* per node: IN / OUT if decided by the trimming labels, else UNKNOWN */
    int32_t *first;    /* per undecided node: the step evaluated first in its subtree */
    int32_t *on_true, *on_false; /* per undecided node: where its value IN / OUT leads */
    mci_blist *out;
} blist_builder;

/* Bottom-up over the subtree: steps for undecided leaves, in post-order, and the first
 * step of every undecided node (that of its first undecided child; decided children
 * are neutral: OUT under a union, IN under an intersection). */
static void number_steps(blist_builder *b, uint32_t node)
{
    const mci_ptree *t = b->t;
    for (uint32_t i = node + 1 - t->nodes[node].size; i <= node; i++) {
        const mci_pnode *p = &t->nodes[i];
        b->first[i] = MCI_BLIST_REJECT;
        if (b->value[i] != MCI_LABEL_UNKNOWN)
            continue;
        if (p->kind == MCI_PNODE_LEAF) {
            b->out->steps[b->out->count] =
                (mci_blist_step){p->leaf, MCI_BLIST_REJECT, MCI_BLIST_REJECT};
            b->first[i] = (int32_t)b->out->count++;
            continue;
        }
        for (uint32_t c = 0; c < p->count && b->first[i] < 0; c++)
            b->first[i] = b->first[t->child[p->first + c]];
    }
}

/* Top-down (reverse post-order visits parents first): in a union, a child that is IN
 * makes the union IN and one that is OUT passes on to the next child; dually for an
 * intersection. A leaf's step jumps on its label (swapped when complemented). */
static void link_steps(blist_builder *b, uint32_t node)
{
    const mci_ptree *t = b->t;
    for (uint32_t i = node + 1; i-- > node + 1 - t->nodes[node].size;) {
        const mci_pnode *p = &t->nodes[i];
        int32_t next = b->on_false[i], next_true = b->on_true[i];
        if (b->value[i] != MCI_LABEL_UNKNOWN)
            continue;
        if (p->kind == MCI_PNODE_LEAF) {
            mci_blist_step *s = &b->out->steps[b->first[i]];
            s->on_in = p->complement ? b->on_false[i] : b->on_true[i];
            s->on_out = p->complement ? b->on_true[i] : b->on_false[i];
            continue;
        }
        /* Children right to left: each one's "continue" target is the next child's
         * first step (or the node's own target for the last). */
        for (uint32_t c = p->count; c-- > 0;) {
            uint32_t k = t->child[p->first + c];
            if (b->value[k] != MCI_LABEL_UNKNOWN)
                continue;
            if (p->kind == MCI_PNODE_UNION) {
                b->on_true[k] = next_true;
                b->on_false[k] = next;
                next = b->first[k];
            } else {
                b->on_true[k] = next_true;
                b->on_false[k] = b->on_false[i];
                next_true = b->first[k];
            }
        }
    }
}

bool mci_blist_build(const mci_ctx *ctx, const mci_ptree *t, const mci_csg_entry *list,
                     size_t n, const mci_label *leaf_labels, mci_blist *out)
{
    blist_builder b = {t, NULL, NULL, NULL, NULL, out};
    int32_t next = MCI_BLIST_ACCEPT;
    size_t nodes = t->node_count + 1;
    bool ok;
    memset(out, 0, sizeof *out);
    b.value = mci_malloc_array(ctx, nodes, sizeof *b.value);
    b.first = mci_malloc_array(ctx, nodes, sizeof *b.first);
    b.on_true = mci_malloc_array(ctx, nodes, sizeof *b.on_true);
    b.on_false = mci_malloc_array(ctx, nodes, sizeof *b.on_false);
    out->steps = mci_malloc_array(ctx, t->leaf_count + 1, sizeof *out->steps);
    ok = b.value && b.first && b.on_true && b.on_false && out->steps;
    /* Targets of nodes under a decided node are never linked (nothing reaches them):
     * they stay REJECT rather than undefined, for passes that read every step. */
    for (size_t i = 0; ok && i < nodes; i++)
        b.on_true[i] = b.on_false[i] = MCI_BLIST_REJECT;
    if (ok) {
        for (size_t i = 0; i < n; i++) {
            (void)mci_ptree_eval(t, list[i].node, leaf_labels, b.value);
            number_steps(&b, list[i].node);
        }
        /* Entries right to left: the desired value goes on to the next entry. */
        for (size_t i = n; i-- > 0;) {
            uint32_t node = list[i].node;
            bool want_in = list[i].desired & MCI_LABEL_BIT(MCI_LABEL_IN);
            if (b.value[node] != MCI_LABEL_UNKNOWN) {
                if (!(list[i].desired & MCI_LABEL_BIT(b.value[node])))
                    next = MCI_BLIST_REJECT;
                continue;
            }
            b.on_true[node] = want_in ? next : MCI_BLIST_REJECT;
            b.on_false[node] = want_in ? MCI_BLIST_REJECT : next;
            link_steps(&b, node);
            next = b.first[node];
        }
        out->start = next;
    }
    mci_free(ctx, b.value);
    mci_free(ctx, b.first);
    mci_free(ctx, b.on_true);
    mci_free(ctx, b.on_false);
    if (!ok)
        mci_blist_free(ctx, out);
    return ok;
}

void mci_blist_free(const mci_ctx *ctx, mci_blist *b)
{
    mci_free(ctx, b->steps);
    memset(b, 0, sizeof *b);
}

int mci_blist_accepts(const mci_blist *b, const mci_label *leaf_labels)
{
    int32_t at = b->start;
    while (at >= 0) {
        const mci_blist_step *s = &b->steps[at];
        mci_label l = leaf_labels[s->leaf];
        if (l == MCI_LABEL_IN)
            at = s->on_in;
        else if (l == MCI_LABEL_OUT)
            at = s->on_out;
        else
            return -1;
    }
    return at == MCI_BLIST_ACCEPT;
}

void mci_trimmed_lists_clear(const mci_ctx *ctx, mci_trimmed_list *lists, size_t n)
{
    for (size_t i = 0; lists && i < n; i++) {
        mci_free(ctx, lists[i].list);
        mci_blist_free(ctx, &lists[i].blist);
        memset(&lists[i], 0, sizeof lists[i]);
    }
}
