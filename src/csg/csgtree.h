/*
 * CSG tree machinery of the classification stage (paper §5.1-5.3): space labels and
 * their combination rules (Eq. 3), the positive tree (differences pushed down to
 * complemented leaves, Eq. 4), and the CSGlist of a primitive (the subtrees hanging off
 * its critical path, each with its desired labels), which decides whether a face of the
 * primitive belongs to the result (Eq. 2, regularized: a face shared by several
 * primitives is kept once).
 */
#ifndef MESHCSG_CSG_CSGTREE_H
#define MESHCSG_CSG_CSGTREE_H

#include "base/core.h"
#include "mesh/validate.h"

/* Where a face (or a point of it) is with respect to a solid. SAME / OPPO: on the
 * solid's boundary, with the solid's outward normal equal / opposite to the face's. */
typedef enum mci_label {
    MCI_LABEL_OUT = 0,
    MCI_LABEL_IN = 1,
    MCI_LABEL_SAME = 2,
    MCI_LABEL_OPPO = 3,
    MCI_LABEL_UNKNOWN = 4
} mci_label;

#define MCI_LABEL_BIT(l) (1u << (l))

/* The label with respect to the complement of the solid. */
mci_label mci_label_complement(mci_label l);
/* SAME <-> OPPO (the face's normal reversed), IN and OUT unchanged. */
mci_label mci_label_reverse(mci_label l);
/* The label with respect to A op B from those with respect to A and B (paper Eq. 3);
 * UNKNOWN propagates unless the other operand decides (IN for union, OUT for
 * intersection). */
mci_label mci_label_union(mci_label a, mci_label b);
mci_label mci_label_intersection(mci_label a, mci_label b);

typedef enum mci_pnode_kind {
    MCI_PNODE_LEAF = 0, /* a primitive, possibly complemented */
    MCI_PNODE_UNION,
    MCI_PNODE_INTERSECTION,
    MCI_PNODE_EMPTY, /* constant: the empty set */
    MCI_PNODE_FULL   /* constant: all of space (a complemented empty set) */
} mci_pnode_kind;

/* Nodes are in post-order: the subtree of node i is nodes i - size + 1 .. i. */
typedef struct mci_pnode {
    uint8_t kind;
    uint8_t complement; /* leaves only */
    uint32_t leaf;      /* leaves only: the primitive's index */
    uint32_t first, count; /* children: child[first .. first + count) */
    uint32_t parent;    /* UINT32_MAX for the root */
    uint32_t size;
} mci_pnode;

typedef struct mci_ptree {
    mci_pnode *nodes;
    size_t node_count;
    uint32_t *child;
    uint32_t *leaf_node;          /* per primitive: its node */
    const mcsg_mesh **leaf_mesh;  /* per primitive */
    mcsg_node_id *leaf_source;    /* per primitive: the mcsg_tree leaf */
    /* Per primitive: 1 when its solid must be found by winding numbers (several shells,
     * or inside out), set by mci_check_leaves; 0 for one outward shell. */
    uint8_t *leaf_winding;
    /* Per primitive of several shells (NULL for the others): each triangle's shell,
     * 0 .. leaf_shells[l] - 1 (set by mci_check_leaves, owned). */
    uint32_t **leaf_shell;
    uint32_t *leaf_shells;
    /* Per primitive: where one of its shells meets itself at an edge of more than two
     * triangles, the triangles paired there by angle (empty for the others; set by
     * mci_check_leaves, owned). Its pieces at such an edge are paired the same way. */
    mci_edge_mates *leaf_mates;
    /* Per primitive: 1 when one of its shells crosses itself (found only when the options
     * ask, mci_check_leaves): its faces are then intersected with each other one by one
     * (see mci_octree_params.face_shell). Such a primitive is a winding one. */
    uint8_t *leaf_crossing;
    /* Per primitive whose mesh had zero-area triangles: the copy without them that
     * leaf_mesh then points to (mesh/zero_area.h; owned), and per triangle of the copy,
     * the triangle of the leaf's own mesh it is part of (for provenance). NULL for the
     * others. */
    mcsg_mesh **leaf_cleaned;
    uint32_t **leaf_face_of;
    size_t leaf_count;
} mci_ptree;

/* The positive tree of the subtree under mcsg_tree_root: primitives are the leaves with
 * at least one triangle, numbered in post-order; empty leaves, empty operations and the
 * complements of empty sets become constants. No recursion (trees may be 100,000 deep). */
mcsg_status mci_ptree_build(const mci_ctx *ctx, const mcsg_tree *tree, mci_ptree *out,
                            mcsg_error *err);
void mci_ptree_free(const mci_ctx *ctx, mci_ptree *t);

/* The label of a face with respect to the subtree of `node`, from its labels with
 * respect to each primitive as it is (not complemented: complements are applied here).
 * scratch holds node_count labels. */
mci_label mci_ptree_eval(const mci_ptree *t, uint32_t node, const mci_label *leaf_labels,
                         mci_label *scratch);

/* One subtree off a primitive's critical path and the labels it must have (bit set of
 * MCI_LABEL_BIT) for the primitive's face to be kept. */
typedef struct mci_csg_entry {
    uint32_t node;
    uint8_t desired;
} mci_csg_entry;

/* The CSGlist of primitive `leaf` (paper §5.3, Fig. 9): for every ancestor on the path
 * to the root and every sibling subtree s of the path there, one entry; desired OUT
 * under a union and IN under an intersection, plus SAME when s comes after the path
 * (Eq. 2 keeps A's face in A op B when it is SAME on B, not B's). `out` needs room for
 * node_count entries; returns the number written. */
size_t mci_csglist(const mci_ptree *t, uint32_t leaf, mci_csg_entry *out);

/* Whether the face belongs to the result: 1 yes, 0 no, -1 not decided (some entry is
 * UNKNOWN and none is undesired). Labels as for mci_ptree_eval, relative to the face's
 * normal as it will be output (reversed for a complemented primitive's face: see
 * mci_label_reverse). */
int mci_csglist_accepts(const mci_ptree *t, const mci_csg_entry *list, size_t n,
                        const mci_label *leaf_labels, mci_label *scratch);

/* The CSGlist of `leaf` trimmed by labels known for all its faces (leaf_labels: IN or
 * OUT where known, UNKNOWN elsewhere): writes into list (room for node_count entries)
 * the entries still undecided and returns their number; *rejected when a decided entry
 * has an undesired label, i.e. no face of the leaf belongs to the result. scratch holds
 * node_count labels. */
size_t mci_csglist_trim(const mci_ptree *t, uint32_t leaf, const mci_label *leaf_labels,
                        mci_label *scratch, mci_csg_entry *list, bool *rejected);

/* What mci_csglist_trim_sparse needs of a tree, computed once: every node's value when
 * every primitive is OUT, and how many of its children then hold its absorbing value
 * (IN under a union, OUT under an intersection; the value is that when any does). */
typedef struct mci_trim_base {
    uint8_t *all_out;    /* per node: MCI_LABEL_IN or MCI_LABEL_OUT */
    uint32_t *absorbing; /* per operation node: children whose all_out is absorbing */
    /* per node: siblings of its path to the root whose all_out is their parent's
     * absorbing value (an entry that would reject the node's primitive) */
    uint32_t *path_bad;
} mci_trim_base;

bool mci_trim_base_init(const mci_ctx *ctx, const mci_ptree *t, mci_trim_base *base);
void mci_trim_base_free(const mci_ctx *ctx, mci_trim_base *base);

/* mci_csglist_trim for the labels OUT everywhere but UNKNOWN at the k distinct
 * primitives unknown[] (`leaf` not among them), the trimming labels of the whole-face
 * decision and the classification: the same entries in the same order, or the same
 * rejection. Costs the unknown primitives' paths up to `leaf`'s (and a few arrays of
 * node_count set), instead of every sibling of the path evaluated: with thousands of
 * primitives in one flat difference, the whole tree per primitive. False when out of
 * memory. */
bool mci_csglist_trim_sparse(const mci_ctx *ctx, const mci_ptree *t, const mci_trim_base *base,
                             uint32_t leaf, const uint32_t *unknown, size_t k,
                             mci_csg_entry *list, size_t *count, bool *rejected);

/* Blist (Hable and Rossignac; paper §5.4): a trimmed CSGlist compiled into a walk over
 * its undecided primitives. Each step reads one primitive's label and jumps to the next
 * step (or accepts, or rejects) on IN or OUT, so a region is decided after reading a few
 * labels instead of evaluating every subtree of the list. Valid only when all labels
 * the walk reads are IN or OUT (no face coplanar with a primitive of the list); use
 * mci_csglist_accepts otherwise. */
#define MCI_BLIST_ACCEPT (-1)
#define MCI_BLIST_REJECT (-2)

typedef struct mci_blist_step {
    uint32_t leaf;           /* the primitive whose label is read */
    int32_t on_in, on_out;   /* next step, or MCI_BLIST_ACCEPT / MCI_BLIST_REJECT */
} mci_blist_step;

typedef struct mci_blist {
    mci_blist_step *steps;
    size_t count;
    int32_t start; /* first step, or MCI_BLIST_ACCEPT for an empty list */
} mci_blist;

/* Compile the entries of `list` whose value depends on leaves labelled UNKNOWN in
 * `leaf_labels` (every other leaf IN or OUT, as for trimming); entries must all be
 * undecided (a trimmed list). Returns false when out of memory. No recursion. */
bool mci_blist_build(const mci_ctx *ctx, const mci_ptree *t, const mci_csg_entry *list,
                     size_t n, const mci_label *leaf_labels, mci_blist *out);
void mci_blist_free(const mci_ctx *ctx, mci_blist *b);

/* 1 if the face is kept, 0 if not, -1 if a label read is neither IN nor OUT (then ask
 * mci_csglist_accepts). */
int mci_blist_accepts(const mci_blist *b, const mci_label *leaf_labels);

/* A leaf's CSGlist trimmed by the leaves whose boxes miss its box (every other leaf
 * UNKNOWN), and its Blist, made by one pass for a later one (see whole_faces.h): the same
 * lists cost the same walk over the whole tree each time, O(nodes) per leaf. `valid` when
 * made; no blist when rejected. */
typedef struct mci_trimmed_list {
    mci_csg_entry *list;
    size_t count;
    bool valid, rejected;
    mci_blist blist;
} mci_trimmed_list;

/* Frees the n lists' contents (leaving them not valid). */
void mci_trimmed_lists_clear(const mci_ctx *ctx, mci_trimmed_list *lists, size_t n);

#endif
