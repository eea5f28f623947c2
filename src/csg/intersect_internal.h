/*
 * Shared by the files of the intersection stage (csg/intersect*.c) only; the rest of the
 * pipeline sees csg/intersect.h. The pair tests (intersect_pairs.c) leave their results
 * as compact records, hits, which the arrangements (intersect_arrange.c) consume.
 */
#ifndef MESHCSG_CSG_INTERSECT_INTERNAL_H
#define MESHCSG_CSG_INTERSECT_INTERNAL_H

#include "csg/intersect.h"
#include "exact/tri_tri.h"

/* A hit keeps its end points compactly: an input vertex (most contacts of meshes that
 * share vertices or faces) as its address, other points (edge lines crossing a plane)
 * by their definition. A full point is 176 bytes, and is built only once the faces
 * dropped whole are known (many crossings of a dense scene lie between two such
 * faces), and every crossing is found twice (by the two faces along the edge). */
typedef struct mci_pair_hit {
    uint32_t f, g;
    uint8_t kind; /* mci_tt_kind */
    bool along_edge[2]; /* of f, of g */
    uint8_t strict_ends; /* mci_tt_result.strict_ends */
    uint8_t stored;     /* bit k: end k is a stored point, else the vertex vertex[k] */
    const double *vertex[2];
    /* Stored end k: its index in the chunk's definitions, then in the joined list of
     * distinct definitions (join_chunks), and finally the point itself, or NULL when no
     * arranged face needs it (build_points). */
    union {
        uint32_t index;
        const mci_point *at;
    } point[2];
} mci_pair_hit;

/* A stored end: the line through v[0], v[1] (an edge, in canonical order) meeting the
 * plane of face plane_face, whose corners are v[2..4]. */
typedef struct mci_end_def {
    const double *v[5];
    uint32_t plane_face;
} mci_end_def;

/* A chunk's hits and end definitions; joined, the hits of all chunks and their distinct
 * definitions. */
typedef struct mci_hit_list {
    mci_pair_hit *v;
    size_t count, capacity;
    mci_end_def *defs;
    size_t def_count, def_capacity;
} mci_hit_list;

/* Planes of the faces that appear in candidate pairs, computed once each. */
typedef struct mci_plane_cache {
    uint32_t *slot; /* per face: index in planes, or MCI_NONE */
    mci_plane *planes;
} mci_plane_cache;

static inline const mci_plane *mci_cached_plane(const mci_plane_cache *c, uint32_t f)
{
    return &c->planes[c->slot[f]];
}

static inline uint64_t mci_hash_vertices(uint64_t h, const double *const *v, int n)
{
    for (int i = 0; i < n; i++) {
        h ^= (uint64_t)(uintptr_t)v[i];
        h *= 0xff51afd7ed558ccdu;
        h ^= h >> 32;
    }
    return h;
}

/* Loops over the faces run in chunks of this many faces (fixed, so that nothing depends
 * on the thread count). */
enum { MCI_FACE_CHUNK = 8192 };

/* The hits of the candidate pairs (in pair order, whatever the thread count), and in
 * *cache the planes of their faces, which the arrangements use again
 * (intersect_pairs.c). */
mcsg_status mci_intersect_pairs(const mci_ctx *ctx, mci_scene *s, const uint64_t *pairs,
                                size_t count, mci_plane_cache *cache, mci_hit_list *hits,
                                mcsg_error *err);
void mci_plane_cache_free(const mci_ctx *ctx, mci_plane_cache *c);
void mci_hit_list_free(const mci_ctx *ctx, mci_hit_list *hits);

/* From intersect_arrange.c: the face across each edge of the faces in hits
 * (scene->neighbour); the pending records of mci_scene_arrange, taking over the hits and
 * planes; and the release of those records and of blocks of points. */
mcsg_status mci_scene_build_neighbours(const mci_ctx *ctx, mci_scene *s,
                                       const mci_hit_list *hits, mcsg_error *err);
mcsg_status mci_scene_prepare_arrangements(const mci_ctx *ctx, mci_scene *s,
                                           mci_hit_list *hits, mci_plane_cache *planes,
                                           mcsg_error *err);
void mci_scene_free_pending(const mci_ctx *ctx, mci_scene *s);
void mci_free_point_blocks(const mci_ctx *ctx, mci_point **blocks, size_t count);

#endif
