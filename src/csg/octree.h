/*
 * Adaptive octree over the faces of all CSG leaves (paper §3.1), built on the bounding
 * box of the whole scene. A face belongs to every cell its triangle touches (closed
 * sets; a certified floating-point test may list it in a few more, never fewer). A cell
 * is critical when it holds faces of two or more leaves;
 * only critical cells with many faces are subdivided. Candidate pairs for the
 * intersection stage are the pairs of faces of different leaves that share a critical
 * cell and whose bounding boxes overlap, each reported once.
 */
#ifndef MESHCSG_CSG_OCTREE_H
#define MESHCSG_CSG_OCTREE_H

#include "base/core.h"

/* A leaf cell's faces are face_ids[first .. first + count), in increasing order (global
 * face ids: faces of leaf i are numbered from face_base[i], so a leaf's faces in a cell
 * are one run). Leaf cells have child == UINT32_MAX; otherwise
 * the eight children are cells child .. child + 7 (bit 0 of the index: upper half in x,
 * bit 1: in y, bit 2: in z), and the built tree keeps no list for the cell (first and
 * count are 0). */
typedef struct mci_cell {
    double lo[3], hi[3];
    uint32_t first, count;
    uint32_t child;
    uint16_t depth;
    uint8_t critical;
} mci_cell;

typedef struct mci_octree {
    const mcsg_mesh *const *leaves;
    size_t leaf_count;
    uint32_t *face_base;   /* leaf_count + 1 entries: global id of each leaf's face 0 */
    uint32_t *face_leaf;   /* owning leaf per global face id */
    const uint32_t *face_group; /* per global face id (mci_octree_params), or NULL */
    const uint32_t *face_shell; /* per global face id (mci_octree_params), or NULL */
    mci_cell *cells;
    size_t cell_count;
    uint32_t *face_ids;    /* the leaf cells' face lists */
    float *face_box;       /* per face: its box rounded outward to floats (min x, y, z, max
                              x, y, z), from the build, for the candidate pairs; freed by
                              mci_octree_free_boxes (24 bytes per face) */
    size_t face_id_count;
    size_t critical_leaf_cells;
    unsigned max_depth;
} mci_octree;

/* Tuning: a critical cell with more faces than this is subdivided, up to the depth
 * (zero: the defaults). */
typedef struct mci_octree_params {
    uint32_t max_cell_faces;
    unsigned max_depth;
    /* Optional (NULL: none): leaves whose faces are left out of the cells (they keep
     * their global face ids, but meet no other face and no ray). */
    const uint8_t *skip_leaf;
    /* Optional (NULL: none): per global face, its group; faces of different groups are
     * paired as faces of different leaves are. A leaf's faces have the leaf's index as
     * group, or, for a leaf whose shells may cross each other, one group per shell
     * numbered from the leaf count on. Must outlive the octree. */
    const uint32_t *face_group;
    /* Optional (NULL: the groups): per global face, its shell, where a shell that crosses
     * itself has a group per face. Faces of one shell sharing an edge are not paired:
     * they meet only there (unless folded onto each other). Must outlive the octree. */
    const uint32_t *face_shell;
} mci_octree_params;

/* Build the octree over the given leaves (which must outlive it). params may be NULL
 * for defaults. Fails only on allocation failure or more than 2^32-1 faces in total. */
mcsg_status mci_octree_build(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                             size_t leaf_count, const mci_octree_params *params,
                             mci_octree *out, mcsg_error *err);
void mci_octree_free(const mci_ctx *ctx, mci_octree *tree);

/* The group of face f: its leaf, or its shell in a leaf whose shells may cross (see
 * mci_octree_params.face_group). Segments of one group do not cross. */
static inline uint32_t mci_octree_face_group(const mci_octree *tree, uint32_t f)
{
    return tree->face_group ? tree->face_group[f] : tree->face_leaf[f];
}

/* The shell of face f (mci_octree_params.face_shell): pieces of one shell join across
 * edges, and coincident shells are told apart by it. */
static inline uint32_t mci_octree_face_shell(const mci_octree *tree, uint32_t f)
{
    return tree->face_shell ? tree->face_shell[f] : mci_octree_face_group(tree, f);
}

/* Free the face boxes (once the candidate pairs are taken). */
void mci_octree_free_boxes(const mci_ctx *ctx, mci_octree *tree);

/* Free the cells, their face lists and the face boxes only: the face indexing (leaves,
 * face_base, face_leaf) stays usable. mci_octree_free is still needed afterwards. */
void mci_octree_free_cells(const mci_ctx *ctx, mci_octree *tree);

/* Corner k (0..2) of a face given by its global id. Inline: the octree's and the
 * arrangements' passes call it millions of times. */
static inline const double *mci_octree_face_vertex(const mci_octree *t, uint32_t face, int k)
{
    const mcsg_mesh *m = t->leaves[t->face_leaf[face]];
    uint32_t local = face - t->face_base[t->face_leaf[face]];
    return m->vertices + 3 * (size_t)m->triangles[3 * (size_t)local + (size_t)k];
}

/* Candidate pairs, each as (smaller global id << 32) | larger id, sorted, unique. The
 * array is allocated with ctx; the caller frees it. */
mcsg_status mci_octree_candidate_pairs(const mci_ctx *ctx, const mci_octree *tree,
                                       uint64_t **pairs, size_t *count, mcsg_error *err);

/* Exact test: does the closed triangle a, b, c touch the closed box [lo, hi]? (The
 * separating axis theorem with the box axes, the triangle normal and the nine edge x
 * axis directions, each decided with exact predicates.) */
bool mci_triangle_touches_box(const double *a, const double *b, const double *c,
                              const double lo[3], const double hi[3]);

#endif
