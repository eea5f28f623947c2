/*
 * The intersection stage over a whole scene (paper §3, §4): octree, candidate pairs,
 * exact triangle-triangle intersection of each pair once, per-face records and
 * arrangements, points on shared edges given to both faces, and a global exact
 * identity of all points. The classification stage works on this.
 */
#ifndef MESHCSG_SCENE_H
#define MESHCSG_SCENE_H

#include "arrange.h"
#include "octree.h"

#define MCI_NONE UINT32_MAX

typedef struct mci_scene {
    mci_octree octree;        /* faces have global ids; octree.face_leaf / face_base */
    size_t face_count;
    uint32_t *neighbour;      /* 3 per face: the face across edge i (corner i to i + 1) */
    uint32_t *arr_of;         /* per face: index in arrs, or MCI_NONE if untouched */
    mci_face_arr *arrs;       /* in increasing face order */
    size_t arr_count;
    /* Global identity (mci_scene_number_points): gid[gid_start[k] + i] numbers point
     * i of arrs[k]; equal points have equal numbers, across all faces. */
    uint32_t *gid_start, *gid;
    size_t point_count;
    mcsg_intersect_stats stats;
} mci_scene;

/* Build the octree over the leaves (which must outlive the scene), intersect, and build
 * and split every touched face's arrangement. Leaves must be closed and edge-manifold
 * for the edge sharing to be complete. */
mcsg_status mci_scene_build(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                            size_t leaf_count, mci_scene *scene, mcsg_error *err);

/* Number all arrangement points by exact identity (fills gid_start, gid, point_count). */
mcsg_status mci_scene_number_points(const mci_ctx *ctx, mci_scene *scene, mcsg_error *err);

void mci_scene_free(const mci_ctx *ctx, mci_scene *scene);

/* Corner k of global face f. */
const double *mci_scene_corner(const mci_scene *scene, uint32_t f, int k);

#endif
