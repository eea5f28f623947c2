/*
 * The classification stage (paper §5): which pieces of the leaves' surfaces belong to
 * the result. Works on a scene whose arrangements are split, numbered and triangulated.
 * See classify.c for the method and docs/classification.md for its relation to the
 * paper.
 */
#ifndef MESHCSG_CSG_CLASSIFY_H
#define MESHCSG_CSG_CLASSIFY_H

#include "csg/csgtree.h"
#include "csg/intersect.h"
#include "csg/rays.h"

/* The kept pieces: triangle t has output vertices tris[3t..3t+2] (counter-clockwise
 * seen from outside the result) and comes from face faces[t] (global face id). */
typedef struct mci_kept {
    uint32_t *tris;
    uint32_t *faces;
    size_t count, capacity;
} mci_kept;

void mci_kept_free(const mci_ctx *ctx, mci_kept *kept);

/* What classification needs about the whole scene, built once.
 *
 * Output vertex ids: below scene->point_count they are the scene's global point
 * numbers; a leaf vertex equal to an explicit arrangement point gets that point's
 * number (the output is welded by exact identity), any other leaf vertex a new id
 * point_count + k whose coordinates are new_vertex[k]. */
typedef struct mci_classifier {
    mci_scene *scene; /* its arrangements are re-tessellated as leaves are classified */
    const mci_ptree *tree;
    size_t *vertex_first;          /* per leaf: index of its vertex 0 in vertex_id */
    uint32_t *vertex_id;
    const double **new_vertex;
    size_t new_vertex_count;
    double (*box)[6];              /* per leaf: lo[3], hi[3] of its vertices */
    /* Per leaf: the other leaves whose boxes meet its box (mci_box_overlaps). */
    uint32_t *overlap_start, *overlap;
    mci_trim_base trim_base; /* for the trimmed CSGlists */
    /* Copies (scene->alias): copy_of[copy_start[l] .. copy_start[l + 1]) are the leaves
     * that are copies of leaf l, in increasing order (NULL when there is none). */
    uint32_t *copy_start, *copy_of;
    /* Per leaf (NULL: none): its trimmed CSGlist and Blist if an earlier pass made them
     * (mci_decide_whole_faces); the leaf's classification takes them over. Not owned. */
    mci_trimmed_list *trimmed;
} mci_classifier;

mcsg_status mci_classifier_init(const mci_ctx *ctx, mci_scene *scene,
                                const mci_ptree *tree, mci_classifier *cl, mcsg_error *err);
void mci_classifier_free(const mci_ctx *ctx, mci_classifier *cl);

typedef struct mci_classify_stats {
    size_t pieces, regions, rays, local_tests;
    size_t rejected_leaves; /* dropped whole by their trimmed CSGlist */
} mci_classify_stats;

/* Classify every piece of primitive `leaf` (the scene's leaf of the same index) and
 * append those that belong to the result to kept[leaf] (reversed for a complemented
 * primitive); for a leaf with copies (scene->alias), to each copy's kept[] as well, and
 * nothing for a copy itself. Fails with MCSG_ERR_INTERNAL when the leaf's pieces do not close up (an
 * input that is not closed as a chain) or a label cannot be decided. */
mcsg_status mci_classify_leaf(const mci_ctx *ctx, const mci_classifier *cl, uint32_t leaf,
                              mci_kept *kept, mci_classify_stats *stats, mcsg_error *err);

#endif
