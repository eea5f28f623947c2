/*
 * The intersection stage over a whole scene (paper §3, §4): octree, candidate pairs,
 * exact triangle-triangle intersection of each pair once, per-face records and
 * arrangements, points on shared edges given to both faces, and a global exact
 * identity of all points. The classification stage works on this.
 */
#ifndef MESHCSG_CSG_INTERSECT_H
#define MESHCSG_CSG_INTERSECT_H

#include "csg/arrange.h"
#include "csg/octree.h"
#include "csg/point_values.h"
#include "mesh/validate.h"

typedef struct mci_scene {
    mci_octree octree;        /* faces have global ids; octree.face_leaf / face_base */
    size_t face_count;
    uint32_t *neighbour;      /* 3 per face: the face across edge i (corner i to i + 1); where
                                 a shell meets itself at the edge, its mate there */
    const mci_edge_mates *leaf_mates; /* per leaf (mci_ptree.leaf_mates), or NULL */
    uint32_t *arr_of;         /* per face: index in arrs, or MCI_NONE if untouched */
    mci_face_arr *arrs;       /* in increasing face order */
    /* The points the arrangements refer to, besides their own pools: the pair tests'
     * (segment ends and contact points not at a vertex, built by mci_scene_arrange in
     * one block, those that an arranged face uses) and one per vertex of an arranged
     * face (see intersect.c). Arrangements refer to
     * each other's pools too (shared edge points): a scene's arrangements are freed
     * together. */
    mci_point **hit_blocks;
    size_t hit_block_count;
    mci_point *vertex_points;
    size_t arr_count;
    /* Global identity (mci_scene_number_points): gid[gid_start[k] + i] numbers point
     * i of arrs[k]; equal points have equal numbers, across all faces. */
    uint32_t *gid_start, *gid;
    /* Double-word values of the numbered points, as predicates need them (each
     * arrangement's `gid` and `values` point here once the points are numbered). */
    mci_point_values values;
    uint8_t *explicit_slot; /* per gid slot: 1 when the point is an input vertex (kept so
                               that later passes need not read every point again) */
    size_t point_count;
    /* Per face, the leaves whose surface it meets: touch_leaf[touch_start[f] ..
     * touch_start[f + 1]), from the pair tests (which report every contact, so a face
     * whose list lacks a leaf does not meet that leaf's surface). */
    uint32_t *touch_start, *touch_leaf;
    /* Per arrangement: MCI_CONTACT_* flags from the pair tests (mci_scene_build_touched),
     * what the whole-face decision must know before any arrangement is built. */
    uint8_t *arr_contact;
    /* Per arrangement: 1 when the face is dropped whole (mci_decide_whole_faces; NULL
     * before): its arrangement holds its corners only, it is not split nor tessellated,
     * and has no pieces. */
    uint8_t *arr_dropped;
    /* The pair tests' records between mci_scene_build_touched and mci_scene_arrange
     * (intersect.c); NULL outside. */
    struct mci_scene_pending *pending;
    /* Per leaf (NULL: none): the leaf it is a copy of (itself if none). A copy's faces
     * are left out of the octree: the leaf it copies stands for it (see eval.c). */
    const uint32_t *alias;
    mcsg_intersect_stats stats;
} mci_scene;

/* Contacts of a touched face that the whole-face decision needs (arr_contact). */
enum {
    MCI_CONTACT_COPLANAR = 1, /* a coplanar face of another leaf overlaps it */
    MCI_CONTACT_BORDER = 2    /* a crossing segment has both ends on one of its closed
                                 edges: another surface meets it along its border */
};

/* Build the octree over the leaves (which must outlive the scene), intersect, and build
 * and split every touched face's arrangement. Leaves must be closed and edge-manifold
 * for the edge sharing to be complete. */
mcsg_status mci_scene_build(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                            size_t leaf_count, mci_scene *scene, mcsg_error *err);

/* mci_scene_build in three steps. First the octree, the pair tests and what they tell
 * each touched face (arr_of, touch lists, neighbours, arr_contact), their records kept
 * in `pending`; alias (NULL: none) names each leaf's stand-in (see mci_scene.alias);
 * face_group and face_shell (NULL: none; see mci_octree_params) let shells of one leaf,
 * and faces of a shell that crosses itself, meet; leaf_mates (NULL: none; per leaf, see
 * mci_ptree.leaf_mates, outliving the scene) pair the faces where a shell meets itself
 * at an edge. Faces dropped whole can be decided then (mci_decide_whole_faces), before
 * anything is built for them. */
mcsg_status mci_scene_build_touched(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                                    size_t leaf_count, const uint32_t *alias,
                                    const uint32_t *face_group, const uint32_t *face_shell,
                                    const mci_edge_mates *leaf_mates, mci_scene *scene,
                                    mcsg_error *err);

/* Second, the arrangements from the pending records (then freed): those flagged in
 * arr_dropped (if any) get their corners only, and neither give nor receive points on
 * their edges; the others get their crossings, merged, and the points on their edges
 * that the face across lacks. */
mcsg_status mci_scene_arrange(const mci_ctx *ctx, mci_scene *scene, mcsg_error *err);

/* The leaf that stands for leaf m (m itself unless it is a copy). */
static inline uint32_t mci_scene_leaf_stand_in(const mci_scene *scene, uint32_t m)
{
    return scene->alias ? scene->alias[m] : m;
}

/* Third, the splitting of the arrangements k without skip[k] (skip may be NULL); skipped
 * ones are only merged if they received points. Splitting frees every arrangement's
 * segments (only the elementary edges are used after it). */
mcsg_status mci_scene_split(const mci_ctx *ctx, mci_scene *scene, const uint8_t *skip,
                            mcsg_error *err);

/* Whether face f meets the surface of leaf m (see touch_start). */
bool mci_scene_face_touches(const mci_scene *scene, uint32_t f, uint32_t m);

/* Number all arrangement points by exact identity (fills gid_start, gid, point_count). */
mcsg_status mci_scene_number_points(const mci_ctx *ctx, mci_scene *scene, mcsg_error *err);

void mci_scene_free(const mci_ctx *ctx, mci_scene *scene);

/* Free everything but the face indexing of the octree (leaves, face_base, face_leaf:
 * what maps result triangles back to input faces): the arrangements, point numbers,
 * adjacency, contacts and cells. mci_scene_free is still needed afterwards. */
void mci_scene_free_geometry(const mci_ctx *ctx, mci_scene *scene);

/* Corner k of global face f. */
/* The group of face f (mci_octree_face_group). */
static inline uint32_t mci_scene_face_group(const mci_scene *scene, uint32_t f)
{
    return mci_octree_face_group(&scene->octree, f);
}

static inline const double *mci_scene_corner(const mci_scene *scene, uint32_t f, int k)
{
    return mci_octree_face_vertex(&scene->octree, f, k);
}

/* The plane of global face f. */
static inline void mci_scene_face_plane(const mci_scene *scene, uint32_t f, mci_plane *plane)
{
    mci_plane_init(plane, mci_scene_corner(scene, f, 0), mci_scene_corner(scene, f, 1),
                   mci_scene_corner(scene, f, 2));
}

/* The arrangement of global face f, or NULL when it was not touched. */
static inline const mci_face_arr *mci_scene_arr_of_face(const mci_scene *scene, uint32_t f)
{
    return scene->arr_of[f] == MCI_NONE ? NULL : &scene->arrs[scene->arr_of[f]];
}

#endif
