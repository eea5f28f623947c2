/*
 * The intersection stage over a whole scene (see intersect.h): octree (paper §3.1),
 * candidate pairs (§3.2), exact triangle-triangle intersection of each pair once
 * (§4.1), per-face records turned into arrangements (§4.2), points on a face's edge
 * given to the face across that edge (so both tessellations have them: no T-junctions),
 * and one number per distinct point over the whole scene (exact identity, not welding
 * by distance).
 */
#include "exact/tri_tri.h"
#include "base/parallel.h"
#include "base/sort.h"
#include "csg/intersect.h"

#include <stdlib.h>
#include <string.h>

/* A hit keeps its end points compactly: an input vertex (most contacts of meshes that
 * share vertices or faces) as its address, other points (edge lines crossing a plane)
 * by their definition. A full point is 176 bytes, and is built only once the faces
 * dropped whole are known: on ring-800 a fifth of the crossings lie between two such
 * faces, and every crossing is found twice (by the two faces along the edge). bunny ∩
 * bunny has 375K hits, nearly all at vertices. */
typedef struct pair_hit {
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
} pair_hit;

/* A stored end: the line through v[0], v[1] (an edge, in canonical order) meeting the
 * plane of face plane_face, whose corners are v[2..4]. */
typedef struct end_def {
    const double *v[5];
    uint32_t plane_face;
} end_def;

/* A chunk's hits and end definitions; joined, the hits of all chunks and their distinct
 * definitions. */
typedef struct hit_list {
    pair_hit *v;
    size_t count, capacity;
    end_def *defs;
    size_t def_count, def_capacity;
} hit_list;


static void face_plane(const mci_scene *s, uint32_t f, mci_plane *plane)
{
    mci_plane_init(plane, mci_scene_corner(s, f, 0), mci_scene_corner(s, f, 1),
                   mci_scene_corner(s, f, 2));
}

/* Planes of the faces that appear in candidate pairs, computed once each. */
typedef struct plane_cache {
    uint32_t *slot; /* per face: index in planes, or MCI_NONE */
    mci_plane *planes;
} plane_cache;

static const mci_plane *cached_plane(const plane_cache *c, uint32_t f)
{
    return &c->planes[c->slot[f]];
}

/* The pair tests build only two kinds of points: input vertices and edge lines meeting
 * the plane of f or of g (its corners say which). */
static bool push_hit(const mci_ctx *ctx, hit_list *h, uint32_t f, uint32_t g,
                     const mci_tt_result *r, const plane_cache *planes)
{
    int ends = r->kind == MCI_TT_SEGMENT ? 2 : r->kind == MCI_TT_POINT ? 1 : 0;
    pair_hit *hit;
    if (!mci_grow_array(ctx, (void **)&h->v, &h->capacity, h->count + 1, sizeof *h->v, 1024))
        return false;
    hit = &h->v[h->count];
    memset(hit, 0, sizeof *hit);
    hit->f = f;
    hit->g = g;
    hit->kind = (uint8_t)r->kind;
    hit->along_edge[0] = r->along_edge[0];
    hit->along_edge[1] = r->along_edge[1];
    hit->strict_ends = r->strict_ends;
    for (int k = 0; k < ends; k++) {
        if (r->end[k].kind == MCI_POINT_EXPLICIT) {
            hit->vertex[k] = r->end[k].v[0];
            continue;
        }
        const mci_point *p = &r->end[k];
        const mci_plane *pf = cached_plane(planes, f);
        end_def *d;
        if (!mci_grow_array(ctx, (void **)&h->defs, &h->def_capacity, h->def_count + 1,
                            sizeof *h->defs, 64))
            return false;
        hit->stored |= (uint8_t)(1u << k);
        hit->point[k].index = (uint32_t)h->def_count;
        d = &h->defs[h->def_count++];
        memcpy(d->v, p->v, sizeof d->v);
        d->plane_face = p->v[2] == pf->a && p->v[3] == pf->b && p->v[4] == pf->c ? f : g;
    }
    h->count++;
    return true;
}

/* The planes are computed in parallel chunks of faces (each face writes its own slot). */
enum { PLANE_CHUNK = 8192 };

typedef struct plane_job {
    const mci_scene *s;
    plane_cache *c;
} plane_job;

static mcsg_status plane_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const plane_job *j = user;
    size_t n = j->s->face_count;
    size_t end = mci_chunk_end(n, chunk, PLANE_CHUNK);
    (void)err;
    for (size_t f = chunk * PLANE_CHUNK; f < end; f++)
        if (j->c->slot[f] != MCI_NONE)
            face_plane(j->s, (uint32_t)f, &j->c->planes[j->c->slot[f]]);
    return MCSG_OK;
}

static bool cache_planes(const mci_ctx *ctx, const mci_scene *s, const uint64_t *pairs,
                         size_t count, plane_cache *c)
{
    plane_job job;
    size_t used = 0;
    c->slot = mci_malloc_array(ctx, s->face_count + 1, sizeof *c->slot);
    if (!c->slot)
        return false;
    /* Slots in face order: faces in pairs are marked, then numbered (a numbering in
     * order of first appearance branched on every one of the 1.5M face ids). */
    for (size_t f = 0; f < s->face_count; f++)
        c->slot[f] = MCI_NONE;
    for (size_t i = 0; i < count; i++) {
        c->slot[pairs[i] >> 32] = 0;
        c->slot[(uint32_t)pairs[i]] = 0;
    }
    for (size_t f = 0; f < s->face_count; f++)
        if (c->slot[f] != MCI_NONE)
            c->slot[f] = (uint32_t)used++;
    c->planes = mci_malloc_array(ctx, used + 1, sizeof *c->planes);
    if (!c->planes)
        return false;
    job.s = s;
    job.c = c;
    return mci_parallel_for(ctx, (s->face_count + PLANE_CHUNK - 1) / PLANE_CHUNK, plane_chunk,
                            &job, NULL) == MCSG_OK;
}

/* The pair tests run in fixed-size chunks, each with its own hit list; the lists are
 * joined in chunk order, so the hits come out in pair order whatever the thread count. */
#define PAIR_CHUNK 4096

typedef struct pair_chunk {
    hit_list hits;
    size_t crossing, points, coplanar;
} pair_chunk;

typedef struct pair_job {
    const mci_ctx *ctx;
    const uint64_t *pairs;
    size_t count;
    const plane_cache *cache;
    pair_chunk *chunks;
} pair_job;

/* The lists cut to their contents. */
static bool trim_hits(const mci_ctx *ctx, hit_list *h)
{
    pair_hit *v = mci_realloc_array(ctx, h->v, h->count + 1, sizeof *v);
    end_def *defs;
    if (v) {
        h->v = v;
        h->capacity = h->count + 1;
    }
    defs = v ? mci_realloc_array(ctx, h->defs, h->def_count + 1, sizeof *defs) : NULL;
    if (defs) {
        h->defs = defs;
        h->def_capacity = h->def_count + 1;
    }
    return defs != NULL;
}

/* Every coplanar pair is kept, touching or not: faces that only share an edge still
 * exchange the points on it. */
static mcsg_status intersect_chunk(void *user, size_t chunk, mcsg_error *err)
{
    pair_job *j = user;
    pair_chunk *c = &j->chunks[chunk];
    size_t end = (chunk + 1) * PAIR_CHUNK < j->count ? (chunk + 1) * PAIR_CHUNK : j->count;
    size_t pairs = end - chunk * PAIR_CHUNK;
    hit_list *h = &c->hits;
    /* Room for a hit per pair and two ends each, trimmed after: growing by doubling
     * copied every chunk's records about twice, and room never written takes no memory
     * from the system allocator. */
    if (!mci_grow_array(j->ctx, (void **)&h->v, &h->capacity, pairs, sizeof *h->v, 1) ||
        !mci_grow_array(j->ctx, (void **)&h->defs, &h->def_capacity, 2 * pairs,
                        sizeof *h->defs, 1))
        return mci_fail_nomem(err, "intersecting faces");
    for (size_t i = chunk * PAIR_CHUNK; i < end; i++) {
        uint32_t f = (uint32_t)(j->pairs[i] >> 32), g = (uint32_t)j->pairs[i];
        mci_tt_result r;
        mci_triangle_intersection_defined(cached_plane(j->cache, f), cached_plane(j->cache, g),
                                          &r);
        c->crossing += r.kind == MCI_TT_SEGMENT;
        c->points += r.kind == MCI_TT_POINT;
        c->coplanar += r.kind == MCI_TT_COPLANAR && r.overlap;
        if (r.kind != MCI_TT_DISJOINT && !push_hit(j->ctx, &c->hits, f, g, &r, j->cache))
            return mci_fail_nomem(err, "intersecting faces");
    }
    return trim_hits(j->ctx, h) ? MCSG_OK : mci_fail_nomem(err, "intersecting faces");
}

static uint64_t vertices_hash(uint64_t h, const double *const *v, int n)
{
    for (int i = 0; i < n; i++) {
        h ^= (uint64_t)(uintptr_t)v[i];
        h *= 0xff51afd7ed558ccdu;
        h ^= h >> 32;
    }
    return h;
}

/* The hash of a point's definition (kind and vertices), as definition_hash below. */
static uint64_t end_def_hash(const end_def *d)
{
    return vertices_hash(0x9e3779b97f4a7c15u ^ (uint64_t)MCI_POINT_LPI, d->v, 5);
}

static uint64_t definition_hash(const mci_point *p)
{
    return vertices_hash(0x9e3779b97f4a7c15u ^ (uint64_t)p->kind, p->v,
                         mci_point_vertex_count(p));
}

static bool same_definition(const end_def *a, const end_def *b)
{
    for (int i = 0; i < 5; i++)
        if (a->v[i] != b->v[i])
            return false;
    return true;
}

/* Pair tests of the two faces along an edge with a third face find the same
 * edge-plane point (one definition, so one value): the hits' stored ends, numbered
 * across the chunks (`at`: each number's definition), are renumbered among the distinct
 * definitions, kept in order of first appearance in hits->defs. False when out of
 * memory. */
static bool merge_definitions(const mci_ctx *ctx, hit_list *hits, const end_def **at,
                              size_t n)
{
    size_t size = 16, distinct = 0;
    uint32_t *rep, *bucket;
    end_def *fit;
    while (size < 2 * n)
        size *= 2;
    rep = mci_malloc_array(ctx, n + size, sizeof *rep);
    hits->defs = mci_malloc_array(ctx, n + 1, sizeof *hits->defs);
    if (!rep || !hits->defs) {
        mci_free(ctx, rep);
        return false;
    }
    bucket = rep + n;
    for (size_t i = 0; i < size; i++)
        bucket[i] = MCI_NONE;
    for (size_t i = 0; i < n; i++) {
        size_t slot = end_def_hash(at[i]) & (size - 1);
        while (bucket[slot] != MCI_NONE && !same_definition(&hits->defs[bucket[slot]], at[i]))
            slot = (slot + 1) & (size - 1);
        if (bucket[slot] == MCI_NONE) {
            bucket[slot] = (uint32_t)distinct;
            hits->defs[distinct++] = *at[i];
        }
        rep[i] = bucket[slot];
    }
    fit = mci_realloc_array(ctx, hits->defs, distinct + 1, sizeof *fit);
    if (!fit) {
        mci_free(ctx, rep);
        return false;
    }
    hits->defs = fit;
    hits->def_count = hits->def_capacity = distinct;
    for (size_t h = 0; h < hits->count; h++)
        for (int k = 0; k < 2; k++)
            if ((hits->v[h].stored >> k) & 1)
                hits->v[h].point[k].index = rep[hits->v[h].point[k].index];
    mci_free(ctx, rep);
    return true;
}

/* Moves the chunks' hits into *hits (in chunk order; the offsets serially, the copies on
 * the threads), then keeps their distinct end definitions. */
typedef struct join_job {
    pair_chunk *chunks;
    hit_list *hits;
    size_t *first_hit, *first_def; /* per chunk: where its hits and definitions go */
    const end_def **at;            /* by number across the chunks: the definition */
} join_job;

static mcsg_status join_chunk(void *user, size_t c, mcsg_error *err)
{
    const join_job *j = user;
    hit_list *from = &j->chunks[c].hits;
    uint32_t base = (uint32_t)j->first_def[c];
    (void)err;
    for (size_t i = 0; i < from->count; i++) {
        pair_hit h = from->v[i];
        for (int k = 0; k < 2; k++)
            if ((h.stored >> k) & 1)
                h.point[k].index += base;
        j->hits->v[j->first_hit[c] + i] = h;
    }
    for (size_t i = 0; i < from->def_count; i++)
        j->at[base + i] = &from->defs[i];
    return MCSG_OK;
}

static mcsg_status join_chunks(const mci_ctx *ctx, mci_scene *s, pair_chunk *chunks,
                               size_t n, hit_list *hits, mcsg_error *err)
{
    join_job j = {chunks, hits, mci_malloc_array(ctx, n + 1, sizeof *j.first_hit),
                  mci_malloc_array(ctx, n + 1, sizeof *j.first_def), NULL};
    size_t total = 0, total_defs = 0;
    mcsg_status st = j.first_hit && j.first_def ? MCSG_OK
                                                : mci_fail_nomem(err, "intersecting faces");
    for (size_t c = 0; st == MCSG_OK && c < n; c++) {
        j.first_hit[c] = total;
        j.first_def[c] = total_defs;
        total += chunks[c].hits.count;
        total_defs += chunks[c].hits.def_count;
        s->stats.intersecting_pairs += chunks[c].crossing;
        s->stats.point_contacts += chunks[c].points;
        s->stats.coplanar_pairs += chunks[c].coplanar;
    }
    if (st == MCSG_OK && total_defs >= UINT32_MAX)
        st = mci_fail(err, MCSG_ERR_LIMIT, "too many intersection points (%zu)", total_defs);
    if (st == MCSG_OK) {
        hits->v = mci_malloc_array(ctx, total + 1, sizeof *hits->v);
        j.at = mci_malloc_array(ctx, total_defs + 1, sizeof *j.at);
        if (!hits->v || !j.at)
            st = mci_fail_nomem(err, "intersecting faces");
    }
    if (st == MCSG_OK) {
        hits->capacity = hits->count = total;
        st = mci_parallel_for(ctx, n, join_chunk, &j, err);
    }
    if (st == MCSG_OK && !merge_definitions(ctx, hits, j.at, total_defs))
        st = mci_fail_nomem(err, "intersecting faces");
    for (size_t c = 0; c < n; c++) {
        mci_free(ctx, chunks[c].hits.v);
        mci_free(ctx, chunks[c].hits.defs);
        chunks[c].hits.v = NULL;
        chunks[c].hits.defs = NULL;
    }
    mci_free(ctx, j.at);
    mci_free(ctx, j.first_hit);
    mci_free(ctx, j.first_def);
    return st;
}

static void free_plane_cache(const mci_ctx *ctx, plane_cache *c)
{
    mci_free(ctx, c->slot);
    mci_free(ctx, c->planes);
    c->slot = NULL;
    c->planes = NULL;
}

/* The hits of the candidate pairs, and in *cache the planes of their faces (the
 * arrangements use them again). */
static mcsg_status intersect_pairs(const mci_ctx *ctx, mci_scene *s, const uint64_t *pairs,
                                   size_t count, plane_cache *cache, hit_list *hits,
                                   mcsg_error *err)
{
    size_t n = (count + PAIR_CHUNK - 1) / PAIR_CHUNK;
    pair_job job = {ctx, pairs, count, cache, mci_calloc_array(ctx, n + 1, sizeof *job.chunks)};
    mcsg_status st = job.chunks && cache_planes(ctx, s, pairs, count, cache)
                         ? MCSG_OK
                         : mci_fail_nomem(err, "intersecting faces");
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, n, intersect_chunk, &job, err);
    if (st == MCSG_OK)
        st = join_chunks(ctx, s, job.chunks, n, hits, err);
    for (size_t c = 0; job.chunks && c < n; c++) {
        mci_free(ctx, job.chunks[c].hits.v);
        mci_free(ctx, job.chunks[c].hits.defs);
    }
    mci_free(ctx, job.chunks);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Face adjacency (for the faces that take part in hits only: linear time)             */

typedef struct leaf_adjacency {
    uint32_t *canon;      /* per vertex: the first vertex with the same coordinates */
    uint32_t *start;      /* vertex -> incident faces (CSR over canonical vertices) */
    uint32_t *faces;
} leaf_adjacency;

static bool build_adjacency(const mci_ctx *ctx, const mcsg_mesh *m, leaf_adjacency *a)
{
    size_t n = m->triangle_count;
    a->canon = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *a->canon);
    a->start = mci_calloc_array(ctx, m->vertex_count + 2, sizeof *a->start);
    a->faces = mci_malloc_array(ctx, 3 * n + 1, sizeof *a->faces);
    if (!a->canon || !a->start || !a->faces || !mci_first_equal_coordinates(ctx, m->vertices, m->vertex_count, a->canon))
        return false;
    for (size_t c = 0; c < 3 * n; c++)
        a->start[a->canon[m->triangles[c]] + 2]++;
    for (size_t v = 2; v < m->vertex_count + 2; v++)
        a->start[v] += a->start[v - 1];
    for (size_t c = 0; c < 3 * n; c++)
        a->faces[a->start[a->canon[m->triangles[c]] + 1]++] = (uint32_t)(c / 3);
    return true;
}

static void free_adjacency(const mci_ctx *ctx, leaf_adjacency *a)
{
    mci_free(ctx, a->canon);
    mci_free(ctx, a->start);
    mci_free(ctx, a->faces);
}

/* The face having the directed edge w -> u (canonical vertices), or MCI_NONE. */
static uint32_t face_with_edge(const mcsg_mesh *m, const leaf_adjacency *a, uint32_t w,
                               uint32_t u)
{
    for (uint32_t k = a->start[w]; k < a->start[w + 1]; k++) {
        const uint32_t *t = m->triangles + 3 * (size_t)a->faces[k];
        for (int i = 0; i < 3; i++)
            if (a->canon[t[i]] == w && a->canon[t[(i + 1) % 3]] == u)
                return a->faces[k];
    }
    return MCI_NONE;
}

static bool leaf_neighbours(const mci_ctx *ctx, mci_scene *s, size_t leaf, const bool *wanted)
{
    const mcsg_mesh *m = s->octree.leaves[leaf];
    uint32_t base = s->octree.face_base[leaf];
    leaf_adjacency a = {NULL, NULL, NULL};
    bool any = false, ok;
    for (uint32_t f = 0; f < m->triangle_count && !any; f++)
        any = wanted[base + f];
    if (!any)
        return true;
    ok = build_adjacency(ctx, m, &a);
    for (uint32_t f = 0; ok && f < m->triangle_count; f++) {
        const uint32_t *t = m->triangles + 3 * (size_t)f;
        if (!wanted[base + f])
            continue;
        for (int i = 0; i < 3; i++) {
            uint32_t nb = face_with_edge(m, &a, a.canon[t[(i + 1) % 3]], a.canon[t[i]]);
            s->neighbour[3 * (size_t)(base + f) + i] = nb == MCI_NONE ? MCI_NONE : base + nb;
        }
    }
    free_adjacency(ctx, &a);
    return ok;
}

/* Leaves in parallel, the largest first (each writes only its own faces' entries). */
typedef struct neighbour_job {
    const mci_ctx *ctx;
    mci_scene *s;
    const bool *wanted;
} neighbour_job;

static mcsg_status neighbours_of_leaf(void *user, size_t leaf, mcsg_error *err)
{
    const neighbour_job *j = user;
    return leaf_neighbours(j->ctx, j->s, leaf, j->wanted)
               ? MCSG_OK
               : mci_fail_nomem(err, "finding neighbouring faces");
}

static uint32_t leaf_size(const void *user, size_t leaf)
{
    const neighbour_job *j = user;
    return (uint32_t)j->s->octree.leaves[leaf]->triangle_count;
}

/* Neighbours of every face that takes part in a hit (the others are never asked). */
static mcsg_status build_neighbours(const mci_ctx *ctx, mci_scene *s, const hit_list *hits,
                                    mcsg_error *err)
{
    bool *wanted = mci_calloc_array(ctx, s->face_count + 1, sizeof *wanted);
    neighbour_job job = {ctx, s, wanted};
    mcsg_status st;
    s->neighbour = mci_malloc_array(ctx, 3 * s->face_count + 1, sizeof *s->neighbour);
    if (!wanted || !s->neighbour) {
        mci_free(ctx, wanted);
        return mci_fail_nomem(err, "finding neighbouring faces");
    }
    for (size_t h = 0; h < hits->count; h++)
        wanted[hits->v[h].f] = wanted[hits->v[h].g] = true;
    for (size_t i = 0; i < 3 * s->face_count; i++)
        s->neighbour[i] = MCI_NONE;
    st = mci_parallel_for_heaviest_first(ctx, s->octree.leaf_count, leaf_size,
                                         neighbours_of_leaf, &job, err);
    mci_free(ctx, wanted);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Arrangements                                                                        */

/* hit_start[f] .. hit_start[f + 1]: indices of the hits face f takes part in. */
static bool index_hits(const mci_ctx *ctx, const mci_scene *s, const hit_list *hits,
                       uint32_t **start_out, uint32_t **list_out)
{
    uint32_t *start = mci_calloc_array(ctx, s->face_count + 2, sizeof *start);
    uint32_t *list = mci_malloc_array(ctx, 2 * hits->count + 1, sizeof *list);
    if (!start || !list) {
        mci_free(ctx, start);
        mci_free(ctx, list);
        return false;
    }
    for (size_t h = 0; h < hits->count; h++) {
        start[hits->v[h].f + 2]++;
        start[hits->v[h].g + 2]++;
    }
    for (size_t f = 2; f < s->face_count + 2; f++)
        start[f] += start[f - 1];
    for (size_t h = 0; h < hits->count; h++) {
        list[start[hits->v[h].f + 1]++] = (uint32_t)h;
        list[start[hits->v[h].g + 1]++] = (uint32_t)h;
    }
    *start_out = start;
    *list_out = list;
    return true;
}

/* Whether the surface bends at edge i of face f (the face across is not coplanar; an
 * open edge counts as a crease). */
static bool edge_is_crease(const mci_scene *s, const mci_plane *plane, uint32_t f, int i)
{
    uint32_t nb = s->neighbour[3 * (size_t)f + i];
    mci_point far;
    if (nb == MCI_NONE)
        return true;
    for (int k = 0; k < 3; k++) {
        const double *v = mci_scene_corner(s, nb, k);
        if (v == plane->a || v == plane->b || v == plane->c)
            continue;
        mci_point_explicit(&far, v);
        if (mci_orient3d(&far, plane) != 0)
            return true;
    }
    return false;
}

static uint32_t find_root(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/* What the arrangements need to know about the faces that take part in hits, computed
 * once per face edge: crease bit i says the surface bends at edge i (edge_is_crease), and
 * plane_rep names the face's flat region among those faces (neighbours across flat
 * edges are joined), so that crossing segments from one region are known to lie on one
 * line of the face they cross. */
typedef struct face_facts {
    uint32_t *plane_rep;
    uint8_t *crease;
} face_facts;

static void free_face_facts(const mci_ctx *ctx, face_facts *ff)
{
    mci_free(ctx, ff->plane_rep);
    mci_free(ctx, ff->crease);
    ff->plane_rep = NULL;
    ff->crease = NULL;
}

/* Crease tests cost an exact zero on planar quads: only the bits used are computed
 * (edges between two faces in hits, for the union below, and coplanar faces), in parallel
 * chunks of faces, from the cached planes. */
typedef struct crease_job {
    const mci_scene *s;
    const plane_cache *planes;
    const uint8_t *in_hits;
    face_facts *ff;
} crease_job;

static mcsg_status crease_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const crease_job *j = user;
    const mci_scene *s = j->s;
    size_t end = mci_chunk_end(s->face_count, chunk, PLANE_CHUNK);
    (void)err;
    for (uint32_t f = (uint32_t)(chunk * PLANE_CHUNK); f < end; f++) {
        const mci_plane *plane;
        j->ff->plane_rep[f] = f;
        if (!j->in_hits[f])
            continue;
        plane = &j->planes->planes[j->planes->slot[f]]; /* a face in a hit was in a pair */
        for (int i = 0; i < 3; i++) {
            uint32_t nb = s->neighbour[3 * (size_t)f + i];
            bool used = (j->in_hits[f] & 2) || (nb != MCI_NONE && nb > f && j->in_hits[nb]);
            if (used)
                j->ff->crease[f] |= (uint8_t)(edge_is_crease(s, plane, f, i) << i);
        }
    }
    return MCSG_OK;
}

static bool compute_face_facts(const mci_ctx *ctx, const mci_scene *s, const hit_list *hits,
                               const plane_cache *planes, face_facts *ff)
{
    uint32_t *parent = mci_malloc_array(ctx, s->face_count + 1, sizeof *parent);
    uint8_t *in_hits = mci_calloc_array(ctx, s->face_count + 1, sizeof *in_hits);
    ff->plane_rep = parent;
    ff->crease = mci_calloc_array(ctx, s->face_count + 1, sizeof *ff->crease);
    if (!parent || !in_hits || !ff->crease) {
        mci_free(ctx, in_hits);
        free_face_facts(ctx, ff);
        return false;
    }
    /* in_hits: 1 in a hit, 2 in a coplanar hit (all its crease bits are needed). */
    for (size_t h = 0; h < hits->count; h++) {
        uint8_t mark = hits->v[h].kind == MCI_TT_COPLANAR ? 2 : 1;
        in_hits[hits->v[h].f] |= mark;
        in_hits[hits->v[h].g] |= mark;
    }
    {
        crease_job job = {s, planes, in_hits, ff};
        if (mci_parallel_for(ctx, (s->face_count + PLANE_CHUNK - 1) / PLANE_CHUNK, crease_chunk,
                             &job, NULL) != MCSG_OK) { /* cannot happen: no task fails */
            mci_free(ctx, in_hits);
            free_face_facts(ctx, ff);
            return false;
        }
    }
    for (uint32_t f = 0; f < s->face_count; f++) {
        for (int i = 0; in_hits[f] && i < 3; i++) {
            uint32_t nb = s->neighbour[3 * (size_t)f + i];
            if (nb != MCI_NONE && nb > f && in_hits[nb] && !((ff->crease[f] >> i) & 1))
                parent[find_root(parent, nb)] = find_root(parent, f);
        }
    }
    for (uint32_t f = 0; f < s->face_count; f++)
        parent[f] = find_root(parent, f);
    mci_free(ctx, in_hits);
    return true;
}

/* One explicit point per vertex of an arranged face, which every arrangement with that
 * vertex refers to (a vertex is a corner of six faces and an end of many hits: copies
 * took a sixth of ring-800's arrangement memory). `slot` maps global vertex ids (leaf
 * by leaf, from `first`) to points; it lives while arranging, the points as long as the
 * arrangements (mci_scene.vertex_points). */
typedef struct vertex_table {
    size_t *first;  /* per leaf, its vertex 0's global id */
    uint32_t *slot; /* per global vertex: 1 + index in points, or 0 */
    mci_point *points;
} vertex_table;

static size_t corner_vertex_id(const mci_scene *s, const vertex_table *vt, uint32_t f, int k)
{
    uint32_t leaf = s->octree.face_leaf[f];
    size_t local = f - s->octree.face_base[leaf];
    return vt->first[leaf] + s->octree.leaves[leaf]->triangles[3 * local + (size_t)k];
}

static void free_vertex_map(const mci_ctx *ctx, vertex_table *vt)
{
    mci_free(ctx, vt->first);
    mci_free(ctx, vt->slot);
    vt->first = NULL;
    vt->slot = NULL;
}

/* Slots for the corners of the arranged faces (face_of: in face order), and their
 * points. Only the arranged faces are visited, and the slot map starts zeroed (no pass
 * over every vertex: the 3.2M-face scene arranges 0.4% of its faces). */
static bool build_vertex_table(const mci_ctx *ctx, const mci_scene *s, const uint32_t *face_of,
                               vertex_table *vt)
{
    size_t total = 0, n = 0;
    vt->first = mci_malloc_array(ctx, s->octree.leaf_count + 1, sizeof *vt->first);
    for (size_t l = 0; vt->first && l < s->octree.leaf_count; l++) {
        vt->first[l] = total;
        total += s->octree.leaves[l]->vertex_count;
    }
    vt->slot = mci_calloc_array(ctx, total + 1, sizeof *vt->slot);
    if (!vt->first || !vt->slot)
        return false;
    for (size_t a = 0; a < s->arr_count; a++)
        for (int k = 0; k < 3; k++) {
            size_t id = corner_vertex_id(s, vt, face_of[a], k);
            if (vt->slot[id] == 0)
                vt->slot[id] = (uint32_t)++n;
        }
    if (!(vt->points = mci_malloc_array(ctx, n + 1, sizeof *vt->points)))
        return false;
    /* The same walk meets each vertex first in slot order: each point is built once. */
    n = 0;
    for (size_t a = 0; a < s->arr_count; a++)
        for (int k = 0; k < 3; k++)
            if (vt->slot[corner_vertex_id(s, vt, face_of[a], k)] == n + 1)
                mci_point_explicit(&vt->points[n++], mci_scene_corner(s, face_of[a], k));
    return true;
}

/* The table's point for corner k of face f, or NULL when it has none. */
static const mci_point *corner_point(const mci_scene *s, const vertex_table *vt, uint32_t f,
                                     int k)
{
    uint32_t slot = vt->slot ? vt->slot[corner_vertex_id(s, vt, f, k)] : 0;
    return slot ? &vt->points[slot - 1] : NULL;
}

/* The corner points of face f, or false if the table lacks one. */
static bool corner_points(const mci_scene *s, const vertex_table *vt, uint32_t f,
                          const mci_point *out[3])
{
    for (int k = 0; k < 3; k++)
        if (!(out[k] = corner_point(s, vt, f, k)))
            return false;
    return true;
}

/* End k of hit h as a point that arr may refer to: a stored point, or a vertex (a
 * corner of h's faces: the table's point; else kept by arr). NULL when out of memory. */
static const mci_point *hit_end(const mci_ctx *ctx, const mci_scene *s, const vertex_table *vt,
                                mci_face_arr *arr, const pair_hit *h, int k)
{
    mci_point vertex;
    if ((h->stored >> k) & 1)
        return h->point[k].at;
    for (int c = 0; c < 6; c++) {
        uint32_t face = c < 3 ? h->f : h->g;
        const mci_point *p;
        if (mci_scene_corner(s, face, c % 3) == h->vertex[k] &&
            (p = corner_point(s, vt, face, c % 3)) != NULL)
            return p;
    }
    mci_point_explicit(&vertex, h->vertex[k]);
    return mci_arr_keep(ctx, arr, &vertex);
}

/* Faces are arranged independently (each writes only its own arrs[k]), in parallel. */
typedef struct arrange_job {
    const mci_ctx *ctx;
    mci_scene *s;
    const hit_list *hits;
    const uint32_t *start, *list, *face_of;
    const face_facts *ff;
    const plane_cache *planes;
    const vertex_table *vt;
} arrange_job;

/* Where an end of a crossing lies in face f, when the pair test knows: an edge line of f
 * meets the other plane strictly inside that edge (the pair test builds such points
 * only for edges whose ends lie strictly on both sides), and an end flagged in
 * mci_tt_result.strict_ends lies strictly inside f. */
static uint8_t line_end_location(const double *const corner[3], const double *a,
                                 const double *b, bool strictly_inside)
{
    for (int e = 0; e < 3; e++) {
        const double *u = corner[e], *w = corner[(e + 1) % 3];
        if ((a == u && b == w) || (a == w && b == u))
            return (uint8_t)(MCI_AT_EDGE + e);
    }
    return strictly_inside ? MCI_AT_INSIDE : MCI_AT_UNKNOWN;
}

static uint8_t end_location(const double *const corner[3], const mci_point *p,
                            bool strictly_inside)
{
    if (p->kind == MCI_POINT_LPI)
        return line_end_location(corner, p->v[0], p->v[1], strictly_inside);
    return strictly_inside ? MCI_AT_INSIDE : MCI_AT_UNKNOWN;
}

static bool add_hit(const arrange_job *j, mci_face_arr *arr, const pair_hit *h)
{
    const mci_scene *s = j->s;
    uint32_t other = h->f == arr->face ? h->g : h->f;
    const mci_plane *plane = &j->planes->planes[j->planes->slot[other]];
    const double *const corner[3] = {arr->plane.a, arr->plane.b, arr->plane.c};
    bool crease[3];
    uint8_t where[2];
    const mci_point *a, *b;
    switch (h->kind) {
    case MCI_TT_SEGMENT:
        a = hit_end(j->ctx, s, j->vt, arr, h, 0);
        b = a ? hit_end(j->ctx, s, j->vt, arr, h, 1) : NULL;
        if (!b)
            return false;
        where[0] = end_location(corner, a, h->strict_ends & 1);
        where[1] = end_location(corner, b, h->strict_ends & 2);
        return mci_arr_add_crossing(j->ctx, arr, a, b, other, plane, j->ff->plane_rep[other],
                                    s->octree.face_leaf[other],
                                    h->along_edge[h->f == arr->face ? 1 : 0], where);
    case MCI_TT_POINT:
        a = hit_end(j->ctx, s, j->vt, arr, h, 0);
        return a && mci_arr_add_point(j->ctx, arr, a);
    default:
        for (int i = 0; i < 3; i++)
            crease[i] = (j->ff->crease[other] >> i) & 1;
        return mci_arr_add_coplanar(j->ctx, arr, other, plane, crease,
                                    s->octree.face_leaf[other]);
    }
}

/* The arrangement of face f with its n hits ids[]. */
static mcsg_status arrange_face(const arrange_job *j, uint32_t f, const uint32_t *ids, size_t n,
                                mci_face_arr *arr, mcsg_error *err)
{
    const mci_scene *s = j->s;
    const pair_hit *hits = j->hits->v;
    const mci_point *corners[3];
    size_t coplanar = 0, crossing = 0;
    mcsg_status st;
    for (size_t i = 0; i < n; i++) {
        coplanar += hits[ids[i]].kind == MCI_TT_COPLANAR;
        crossing += hits[ids[i]].kind == MCI_TT_SEGMENT;
    }
    /* A crossing adds two points and a segment, a contact one point, a coplanar face up
     * to three segments (its points are counted as they come: corner copies, the most
     * common, are not appended). */
    st = mci_arr_init(j->ctx, arr, f, mci_scene_corner(s, f, 0), mci_scene_corner(s, f, 1),
                      mci_scene_corner(s, f, 2), corner_points(s, j->vt, f, corners) ? corners
                                                                                     : NULL,
                      coplanar, 3 + n - coplanar + crossing, err);
    if (st == MCSG_OK && !mci_arr_reserve(j->ctx, arr, 0, crossing + 3 * coplanar))
        st = mci_fail_nomem(err, "arranging faces");
    for (size_t i = 0; st == MCSG_OK && i < n; i++)
        if (!add_hit(j, arr, &hits[ids[i]]))
            st = mci_fail_nomem(err, "arranging faces");
    return st == MCSG_OK ? mci_arr_merge(j->ctx, arr, err) : st;
}

/* Whether arrangement k is a face dropped whole (corners only: see mci_scene_arrange). */
static bool is_dropped(const mci_scene *s, size_t k)
{
    return s->arr_dropped && s->arr_dropped[k];
}

/* Faces that are untouched themselves but receive a point on an edge. */
static void mark_receivers(const mci_scene *s, bool *needs)
{
    for (size_t k = 0; k < s->arr_count; k++) {
        const mci_face_arr *arr = &s->arrs[k];
        for (size_t p = 3; p < arr->point_count; p++) {
            uint32_t nb;
            if (arr->where[p] < MCI_AT_EDGE || arr->where[p] >= MCI_AT_INSIDE)
                continue;
            nb = s->neighbour[3 * (size_t)arr->face + (arr->where[p] - MCI_AT_EDGE)];
            if (nb != MCI_NONE && s->arr_of[nb] == MCI_NONE)
                needs[nb] = true;
        }
    }
}

/* A per-arrangement flag array (NULL: none) renumbered with the arrangements: new
 * index i was old_of[i], or is a receiver (MCI_NONE: flags 0). */
static bool renumber_flags(const mci_ctx *ctx, uint8_t **flags, const uint32_t *old_of,
                           size_t n)
{
    uint8_t *fresh;
    if (!*flags)
        return true;
    if (!(fresh = mci_calloc_array(ctx, n + 1, 1)))
        return false;
    for (size_t i = 0; i < n; i++)
        if (old_of[i] != MCI_NONE)
            fresh[i] = (*flags)[old_of[i]];
    mci_free(ctx, *flags);
    *flags = fresh;
    return true;
}

/* Rebuild arrs in face order with new (empty) arrangements for the marked faces. */
static mcsg_status add_receivers(const mci_ctx *ctx, mci_scene *s, const vertex_table *vt,
                                 const bool *needs, mcsg_error *err)
{
    size_t extra = 0, k = 0, out = 0;
    mci_face_arr *all;
    uint32_t *old_of;
    mcsg_status st = MCSG_OK;
    for (size_t f = 0; f < s->face_count; f++)
        extra += needs[f];
    if (extra == 0)
        return MCSG_OK;
    all = mci_calloc_array(ctx, s->arr_count + extra, sizeof *all);
    old_of = mci_malloc_array(ctx, s->arr_count + extra, sizeof *old_of);
    if (!all || !old_of) {
        mci_free(ctx, all);
        mci_free(ctx, old_of);
        return mci_fail_nomem(err, "arranging faces");
    }
    for (uint32_t f = 0; f < s->face_count; f++) {
        old_of[out] = MCI_NONE;
        if (s->arr_of[f] != MCI_NONE) {
            old_of[out] = (uint32_t)k;
            all[out] = s->arrs[k++];
        } else if (needs[f] && st == MCSG_OK) {
            const mci_point *corners[3];
            st = mci_arr_init(ctx, &all[out], f, mci_scene_corner(s, f, 0),
                              mci_scene_corner(s, f, 1), mci_scene_corner(s, f, 2),
                              corner_points(s, vt, f, corners) ? corners : NULL, 0, 3, err);
        } else {
            continue;
        }
        s->arr_of[f] = (uint32_t)out++;
    }
    mci_free(ctx, s->arrs);
    s->arrs = all;
    s->arr_count = out;
    if (st == MCSG_OK && (!renumber_flags(ctx, &s->arr_dropped, old_of, out) ||
                          !renumber_flags(ctx, &s->arr_contact, old_of, out)))
        st = mci_fail_nomem(err, "arranging faces");
    mci_free(ctx, old_of);
    return st;
}

/* Whether arrangement t already has point p with the same definition among its located
 * points on an edge. Nearly always so: the neighbour across an edge meets the same
 * surfaces there and builds the same edge-plane points itself (on the bench scenes every
 * shared point is such a copy). Sharing adds only what a face lacks, so most receivers
 * stay merged: no copy, no second merge. */
static bool has_edge_point(const mci_face_arr *t, const mci_point *p)
{
    for (size_t q = 3; q < t->where_count; q++)
        if (t->where[q] >= MCI_AT_EDGE && t->where[q] < MCI_AT_INSIDE &&
            mci_points_same_definition(t->points[q], p))
            return true;
    return false;
}

/* The arrangement that point p of arr should also be in (its edge neighbour's), or NULL
 * when there is none or it has the point already. */
static mci_face_arr *share_target(const mci_scene *s, const mci_face_arr *arr, size_t p)
{
    uint32_t nb;
    mci_face_arr *t;
    if (arr->where[p] < MCI_AT_EDGE || arr->where[p] >= MCI_AT_INSIDE)
        return NULL;
    nb = s->neighbour[3 * (size_t)arr->face + (arr->where[p] - MCI_AT_EDGE)];
    if (nb == MCI_NONE || is_dropped(s, s->arr_of[nb]))
        return NULL; /* a face dropped whole has no pieces to join (see collect_walls) */
    t = &s->arrs[s->arr_of[nb]];
    return has_edge_point(t, arr->points[p]) ? NULL : t;
}

/* Which arrangements have an edge point their neighbour lacks: a read-only pass over
 * every edge point, in parallel; the sharing loop then visits only those. */
typedef struct lack_job {
    const mci_scene *s;
    uint8_t *lacking;
} lack_job;

/* In chunks of arrangements: one task per arrangement wrote neighbouring bytes of
 * `lacking` from both threads, and the step ran slower on two threads than on one. */
enum { LACK_CHUNK = 256 };

static mcsg_status find_lacking(void *user, size_t chunk, mcsg_error *err)
{
    const lack_job *j = user;
    size_t end = mci_chunk_end(j->s->arr_count, chunk, LACK_CHUNK);
    (void)err;
    for (size_t k = chunk * LACK_CHUNK; k < end; k++) {
        const mci_face_arr *arr = &j->s->arrs[k];
        bool lacking = false;
        for (size_t p = 3; p < arr->point_count && !lacking; p++)
            lacking = share_target(j->s, arr, p) != NULL;
        j->lacking[k] = lacking;
    }
    return MCSG_OK;
}

/* Room in each arrangement for the points the loop below will give it (the loop, and
 * which arrangements it skips, replayed without the points). */
static mcsg_status reserve_shared(const mci_ctx *ctx, mci_scene *s, const uint8_t *lacking,
                                  mcsg_error *err)
{
    uint32_t *extra = mci_calloc_array(ctx, s->arr_count + 1, sizeof *extra);
    mcsg_status st = extra ? MCSG_OK : mci_fail_nomem(err, "arranging faces");
    for (size_t k = 0; st == MCSG_OK && k < s->arr_count; k++) {
        const mci_face_arr *arr = &s->arrs[k];
        if (!lacking[k] || arr->dirty || extra[k]) /* received points: the loop skips it */
            continue;
        for (size_t p = 3; p < arr->point_count; p++) {
            const mci_face_arr *t = share_target(s, arr, p);
            if (t)
                extra[t - s->arrs]++;
        }
    }
    for (size_t k = 0; st == MCSG_OK && k < s->arr_count; k++)
        if (extra[k] && !mci_arr_reserve(ctx, &s->arrs[k], s->arrs[k].point_count + extra[k], 0))
            st = mci_fail_nomem(err, "arranging faces");
    mci_free(ctx, extra);
    return st;
}

/* Points on a face's edge go to the arrangement across that edge where it lacks them
 * (in arrangement order; an arrangement that received points shares none itself, its
 * new points are not located yet). */
static mcsg_status share_edge_points(const mci_ctx *ctx, mci_scene *s, const vertex_table *vt,
                                     mcsg_error *err)
{
    bool *needs = mci_calloc_array(ctx, s->face_count + 1, sizeof *needs);
    lack_job job = {s, NULL};
    mcsg_status st;
    if (!needs)
        return mci_fail_nomem(err, "arranging faces");
    mark_receivers(s, needs);
    st = add_receivers(ctx, s, vt, needs, err);
    mci_free(ctx, needs);
    if (st == MCSG_OK && !(job.lacking = mci_calloc_array(ctx, s->arr_count + 1, 1)))
        st = mci_fail_nomem(err, "arranging faces");
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, (s->arr_count + LACK_CHUNK - 1) / LACK_CHUNK, find_lacking,
                              &job, err);
    if (st == MCSG_OK)
        st = reserve_shared(ctx, s, job.lacking, err);
    for (size_t k = 0; st == MCSG_OK && k < s->arr_count; k++) {
        const mci_face_arr *arr = &s->arrs[k];
        for (size_t p = 3; job.lacking[k] && p < arr->point_count && !arr->dirty; p++) {
            mci_face_arr *t = share_target(s, arr, p);
            if (t && !mci_arr_add_point(ctx, t, arr->points[p]))
                st = mci_fail_nomem(err, "arranging faces");
        }
    }
    mci_free(ctx, job.lacking);
    return st;
}

static mcsg_status arrange_one(void *user, size_t k, mcsg_error *err)
{
    const arrange_job *j = user;
    uint32_t f = j->face_of[k];
    const mci_point *corners[3];
    if (is_dropped(j->s, k))
        return mci_arr_init_corners(j->ctx, &j->s->arrs[k], f, mci_scene_corner(j->s, f, 0),
                                    mci_scene_corner(j->s, f, 1), mci_scene_corner(j->s, f, 2),
                                    corner_points(j->s, j->vt, f, corners) ? corners : NULL,
                                    err);
    return arrange_face(j, f, j->list + j->start[f], j->start[f + 1] - j->start[f],
                        &j->s->arrs[k], err);
}

/* Faces with the most hits first: a face cut by hundreds of others (a cylinder's cap)
 * would otherwise often come last and run alone. */
static uint32_t arrange_cost(const void *user, size_t k)
{
    const arrange_job *j = user;
    if (is_dropped(j->s, k))
        return 0;
    return j->start[j->face_of[k] + 1] - j->start[j->face_of[k]];
}

/* Splitting runs after arranging and sharing, possibly skipping some faces. */
typedef struct split_job {
    const mci_ctx *ctx;
    mci_scene *s;
    const uint8_t *skip;
} split_job;

/* The segments are freed once split: later steps read only the elementary edges, and
 * the segments were a tenth of ring-800's peak. */
static mcsg_status split_one(void *user, size_t k, mcsg_error *err)
{
    const split_job *j = user;
    mci_face_arr *arr = &j->s->arrs[k];
    mcsg_status st = MCSG_OK;
    if (!j->skip || !j->skip[k])
        st = mci_arr_split(j->ctx, arr, err);
    else if (arr->dirty)
        st = mci_arr_merge(j->ctx, arr, err);
    if (st == MCSG_OK)
        mci_arr_free_segments(j->ctx, arr);
    return st;
}

/* touch_start / touch_leaf from the hits (each face's list once per leaf, in hit
 * order). A leaf is listed for face f when its mark is not f + 1 yet: a plate's face
 * meets thousands of leaves (its holes), which a search of the face's list made
 * quadratic (drill_plate_64: 1.6G instructions). */
static bool record_touches(const mci_ctx *ctx, mci_scene *s, const hit_list *hits,
                           const uint32_t *start, const uint32_t *list)
{
    size_t out = 0;
    uint32_t *listed_for = mci_calloc_array(ctx, s->octree.leaf_count + 1, sizeof *listed_for);
    s->touch_start = mci_malloc_array(ctx, s->face_count + 1, sizeof *s->touch_start);
    s->touch_leaf = mci_malloc_array(ctx, 2 * hits->count + 1, sizeof *s->touch_leaf);
    if (!listed_for || !s->touch_start || !s->touch_leaf) {
        mci_free(ctx, listed_for);
        return false;
    }
    for (uint32_t f = 0; f < s->face_count; f++) {
        s->touch_start[f] = (uint32_t)out;
        for (uint32_t i = start[f]; i < start[f + 1]; i++) {
            const pair_hit *h = &hits->v[list[i]];
            uint32_t leaf = s->octree.face_leaf[h->f == f ? h->g : h->f];
            if (listed_for[leaf] != f + 1) {
                listed_for[leaf] = f + 1;
                s->touch_leaf[out++] = leaf;
            }
        }
    }
    mci_free(ctx, listed_for);
    s->touch_start[s->face_count] = (uint32_t)out;
    {
        /* Sized for two entries per hit; most faces meet one leaf several times. */
        uint32_t *fit = mci_realloc_array(ctx, s->touch_leaf, out + 1, sizeof *fit);
        if (!fit)
            return false;
        s->touch_leaf = fit;
    }
    return true;
}

bool mci_scene_face_touches(const mci_scene *s, uint32_t f, uint32_t m)
{
    for (uint32_t i = s->touch_start[f]; i < s->touch_start[f + 1]; i++)
        if (s->touch_leaf[i] == m)
            return true;
    return false;
}

/* arr_of, arr_count and face_of (arrangement index -> face) from the hit index. */
static bool number_arranged_faces(const mci_ctx *ctx, mci_scene *s, const uint32_t *start,
                                  uint32_t **face_of)
{
    s->arr_of = mci_malloc_array(ctx, s->face_count + 1, sizeof *s->arr_of);
    if (!s->arr_of)
        return false;
    for (uint32_t f = 0; f < s->face_count; f++)
        s->arr_of[f] = start[f + 1] > start[f] ? (uint32_t)s->arr_count++ : MCI_NONE;
    *face_of = mci_malloc_array(ctx, s->arr_count + 1, sizeof **face_of);
    s->arrs = mci_calloc_array(ctx, s->arr_count + 1, sizeof *s->arrs);
    if (!*face_of || !s->arrs)
        return false;
    for (uint32_t f = 0; f < s->face_count; f++)
        if (s->arr_of[f] != MCI_NONE)
            (*face_of)[s->arr_of[f]] = f;
    return true;
}

static void free_point_blocks(const mci_ctx *ctx, mci_point **blocks, size_t count)
{
    for (size_t b = 0; blocks && b < count; b++)
        mci_free(ctx, blocks[b]);
    mci_free(ctx, blocks);
}

static void free_hits(const mci_ctx *ctx, hit_list *hits)
{
    mci_free(ctx, hits->v);
    mci_free(ctx, hits->defs);
    memset(hits, 0, sizeof *hits);
}

/* The pair tests' records from mci_scene_build_touched to mci_scene_arrange. */
struct mci_scene_pending {
    hit_list hits;
    plane_cache planes;
    face_facts ff;
    uint32_t *start, *list; /* index_hits */
    uint32_t *face_of;      /* arrangement -> face */
    vertex_table vt;        /* its points belong to the scene (vertex_points) */
};

/* Everything but the vertex table's map. */
static void free_pending_records(const mci_ctx *ctx, struct mci_scene_pending *pd)
{
    free_hits(ctx, &pd->hits);
    free_plane_cache(ctx, &pd->planes);
    free_face_facts(ctx, &pd->ff);
    mci_free(ctx, pd->start);
    mci_free(ctx, pd->list);
    mci_free(ctx, pd->face_of);
    pd->start = pd->list = pd->face_of = NULL;
}

static void free_pending(const mci_ctx *ctx, mci_scene *s)
{
    if (!s->pending)
        return;
    free_pending_records(ctx, s->pending);
    free_vertex_map(ctx, &s->pending->vt);
    mci_free(ctx, s->pending);
    s->pending = NULL;
}

/* Edges of face f (corners c) whose closed segment holds end k of hit h (bit e: edge
 * e). The end lies in f, as in the other face of the hit; where neither the pair test
 * nor the point's definition tells, an exact zero of its orientation against an edge's
 * line puts it on that edge (what merging the arrangement would find). */
static uint8_t end_edges(const hit_list *hits, const plane_cache *planes, uint32_t f,
                         const double *const c[3], const pair_hit *h, int k)
{
    mci_point p, corner[3];
    uint8_t mask = 0;
    int axis, sign;
    if ((h->stored >> k) & 1) {
        const end_def *d = &hits->defs[h->point[k].index];
        uint8_t where = line_end_location(c, d->v[0], d->v[1], (h->strict_ends >> k) & 1);
        if (where == MCI_AT_INSIDE)
            return 0;
        if (where != MCI_AT_UNKNOWN)
            return (uint8_t)(1u << (where - MCI_AT_EDGE));
        (void)mci_point_lpi(&p, d->v[0], d->v[1], cached_plane(planes, d->plane_face));
    } else {
        mci_point_explicit(&p, h->vertex[k]);
    }
    axis = mci_plane_projection_axis(cached_plane(planes, f), &sign);
    if (axis < 0)
        return 7; /* cannot happen (faces in hits are not degenerate): keep the face */
    for (int e = 0; e < 3; e++)
        mci_point_explicit(&corner[e], c[e]);
    for (int e = 0; e < 3; e++)
        if (mci_orient2d_projected(&corner[e], &corner[(e + 1) % 3], &p, axis) == 0)
            mask |= (uint8_t)(1u << e);
    return mask;
}

/* MCI_CONTACT_* of face f from its hits, as its arrangement would show them: a coplanar
 * face added, or a crossing segment with both ends on one closed edge (one that merges
 * to a single point counts too: the face is then kept, which is always safe). */
static uint8_t face_contact(const mci_scene *s, const struct mci_scene_pending *pd,
                            uint32_t f)
{
    const double *c[3] = {mci_scene_corner(s, f, 0), mci_scene_corner(s, f, 1),
                          mci_scene_corner(s, f, 2)};
    uint8_t contact = 0;
    for (uint32_t i = pd->start[f]; i < pd->start[f + 1]; i++) {
        const pair_hit *h = &pd->hits.v[pd->list[i]];
        uint8_t a;
        if (h->kind != MCI_TT_SEGMENT && h->kind != MCI_TT_POINT)
            contact |= MCI_CONTACT_COPLANAR;
        else if (h->kind == MCI_TT_SEGMENT && !(contact & MCI_CONTACT_BORDER) &&
                 (a = end_edges(&pd->hits, &pd->planes, f, c, h, 0)) != 0 &&
                 (a & end_edges(&pd->hits, &pd->planes, f, c, h, 1)) != 0)
            contact |= MCI_CONTACT_BORDER;
    }
    return contact;
}

enum { CONTACT_CHUNK = 1024 };

static mcsg_status contact_chunk(void *user, size_t chunk, mcsg_error *err)
{
    mci_scene *s = user;
    size_t end = mci_chunk_end(s->arr_count, chunk, CONTACT_CHUNK);
    (void)err;
    for (size_t k = chunk * CONTACT_CHUNK; k < end; k++)
        s->arr_contact[k] = face_contact(s, s->pending, s->pending->face_of[k]);
    return MCSG_OK;
}

/* Takes the hits and the plane cache into s->pending, with what arranging will need:
 * face facts, the hit index, arrangement numbers, touch lists, the vertex table and
 * each face's contacts. */
static mcsg_status prepare_arrangements(const mci_ctx *ctx, mci_scene *s, hit_list *hits,
                                        plane_cache *planes, mcsg_error *err)
{
    struct mci_scene_pending *pd = mci_calloc_array(ctx, 1, sizeof *pd);
    if (!pd)
        return mci_fail_nomem(err, "arranging faces");
    pd->hits = *hits;
    pd->planes = *planes;
    memset(hits, 0, sizeof *hits);
    planes->slot = NULL;
    planes->planes = NULL;
    s->pending = pd;
    if (!compute_face_facts(ctx, s, &pd->hits, &pd->planes, &pd->ff) ||
        !index_hits(ctx, s, &pd->hits, &pd->start, &pd->list) ||
        !number_arranged_faces(ctx, s, pd->start, &pd->face_of) ||
        !record_touches(ctx, s, &pd->hits, pd->start, pd->list) ||
        !build_vertex_table(ctx, s, pd->face_of, &pd->vt) ||
        !(s->arr_contact = mci_malloc_array(ctx, s->arr_count + 1, 1))) {
        s->vertex_points = pd->vt.points;
        return mci_fail_nomem(err, "arranging faces");
    }
    s->vertex_points = pd->vt.points; /* the arrangements refer to them */
    return mci_parallel_for(ctx, (s->arr_count + CONTACT_CHUNK - 1) / CONTACT_CHUNK,
                            contact_chunk, s, err);
}

/* Building the stored ends that arranged faces use: in parallel chunks of definitions,
 * each built into its own slot of one block. */
typedef struct build_job {
    const hit_list *hits;
    const plane_cache *planes;
    const uint32_t *slot; /* per definition: its place in block, or MCI_NONE */
    mci_point *block;
} build_job;

enum { BUILD_CHUNK = 4096 };

static mcsg_status build_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const build_job *j = user;
    size_t end = mci_chunk_end(j->hits->def_count, chunk, BUILD_CHUNK);
    (void)err;
    for (size_t i = chunk * BUILD_CHUNK; i < end; i++) {
        const end_def *d = &j->hits->defs[i];
        if (j->slot[i] != MCI_NONE) /* the pair test built it once: it exists */
            (void)mci_point_lpi(&j->block[j->slot[i]], d->v[0], d->v[1],
                                cached_plane(j->planes, d->plane_face));
    }
    return MCSG_OK;
}

/* The points of the stored ends of hits with a face that is arranged (not dropped
 * whole), in the scene's hit_blocks; each hit's stored ends then point to them (NULL:
 * both faces dropped). */
static mcsg_status build_points(const mci_ctx *ctx, mci_scene *s, hit_list *hits,
                                const plane_cache *planes, mcsg_error *err)
{
    uint32_t *slot = mci_malloc_array(ctx, hits->def_count + 1, sizeof *slot);
    build_job job = {hits, planes, slot, NULL};
    size_t n = 0;
    mcsg_status st;
    s->hit_blocks = mci_calloc_array(ctx, 1, sizeof *s->hit_blocks);
    if (!slot || !s->hit_blocks) {
        mci_free(ctx, slot);
        return mci_fail_nomem(err, "arranging faces");
    }
    for (size_t i = 0; i < hits->def_count; i++)
        slot[i] = MCI_NONE;
    for (size_t h = 0; h < hits->count; h++) {
        const pair_hit *x = &hits->v[h];
        bool used = !is_dropped(s, s->arr_of[x->f]) || !is_dropped(s, s->arr_of[x->g]);
        for (int k = 0; used && k < 2; k++)
            if ((x->stored >> k) & 1)
                slot[x->point[k].index] = 0;
    }
    for (size_t i = 0; i < hits->def_count; i++)
        if (slot[i] != MCI_NONE)
            slot[i] = (uint32_t)n++;
    s->hit_blocks[0] = job.block = mci_malloc_array(ctx, n + 1, sizeof *job.block);
    s->hit_block_count = 1;
    st = job.block ? mci_parallel_for(ctx, (hits->def_count + BUILD_CHUNK - 1) / BUILD_CHUNK,
                                      build_chunk, &job, err)
                   : mci_fail_nomem(err, "arranging faces");
    for (size_t h = 0; st == MCSG_OK && h < hits->count; h++)
        for (int k = 0; k < 2; k++)
            if ((hits->v[h].stored >> k) & 1) {
                uint32_t at = slot[hits->v[h].point[k].index];
                hits->v[h].point[k].at = at == MCI_NONE ? NULL : &job.block[at];
            }
    mci_free(ctx, slot);
    mci_free(ctx, hits->defs); /* the points stand for them now */
    hits->defs = NULL;
    hits->def_count = hits->def_capacity = 0;
    return st;
}

/* The hits and the plane cache are freed as soon as the faces have taken their records,
 * before the arrangements grow (splitting, edge points); the built points stay with the
 * scene (the arrangements refer to them). */
mcsg_status mci_scene_arrange(const mci_ctx *ctx, mci_scene *s, mcsg_error *err)
{
    double t0 = mci_seconds_now();
    struct mci_scene_pending *pd = s->pending;
    arrange_job job;
    mcsg_status st;
    if (!pd)
        return mci_fail(err, MCSG_ERR_INTERNAL, "arranging a scene twice");
    job = (arrange_job){ctx, s, &pd->hits, pd->start, pd->list, pd->face_of, &pd->ff,
                        &pd->planes, &pd->vt};
    st = build_points(ctx, s, &pd->hits, &pd->planes, err);
    if (st == MCSG_OK)
        st = mci_parallel_for_heaviest_first(ctx, s->arr_count, arrange_cost, arrange_one,
                                             &job, err);
    free_pending_records(ctx, pd);
    if (st == MCSG_OK)
        st = share_edge_points(ctx, s, &pd->vt, err);
    free_pending(ctx, s);
    s->stats.seconds_arrange += mci_seconds_now() - t0;
    return st;
}

static uint32_t split_cost(const void *user, size_t k)
{
    const mci_face_arr *arr = &((const split_job *)user)->s->arrs[k];
    return (uint32_t)(arr->point_count + arr->segment_count);
}

mcsg_status mci_scene_split(const mci_ctx *ctx, mci_scene *s, const uint8_t *skip,
                            mcsg_error *err)
{
    double t0 = mci_seconds_now();
    split_job job = {ctx, s, skip};
    mcsg_status st = mci_parallel_for_heaviest_first(ctx, s->arr_count, split_cost, split_one,
                                                     &job, err);
    s->stats.seconds_arrange += mci_seconds_now() - t0;
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* The whole stage                                                                     */

static mcsg_status intersect_scene(const mci_ctx *ctx, mci_scene *s, mcsg_error *err)
{
    uint64_t *pairs = NULL;
    size_t count = 0;
    hit_list hits = {NULL, 0, 0, NULL, 0, 0};
    plane_cache planes = {NULL, NULL};
    double t0 = mci_seconds_now(), t1, t2;
    mcsg_status st = mci_octree_candidate_pairs(ctx, &s->octree, &pairs, &count, err);
    mci_octree_free_boxes(ctx, &s->octree);
    if (st != MCSG_OK)
        return st;
    t1 = mci_seconds_now();
    s->stats.candidate_pairs = count;
    st = intersect_pairs(ctx, s, pairs, count, &planes, &hits, err);
    mci_free(ctx, pairs);
    t2 = mci_seconds_now();
    if (st == MCSG_OK)
        st = build_neighbours(ctx, s, &hits, err);
    if (st == MCSG_OK)
        st = prepare_arrangements(ctx, s, &hits, &planes, err);
    free_hits(ctx, &hits);
    free_plane_cache(ctx, &planes);
    s->stats.seconds_pairs = t1 - t0;
    s->stats.seconds_intersect = t2 - t1;
    s->stats.seconds_arrange = mci_seconds_now() - t2;
    s->stats.arranged_faces = s->arr_count;
    return st;
}

mcsg_status mci_scene_build(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                            size_t leaf_count, mci_scene *scene, mcsg_error *err)
{
    mcsg_status st = mci_scene_build_touched(ctx, leaves, leaf_count, NULL, scene, err);
    if (st != MCSG_OK)
        return st;
    st = mci_scene_arrange(ctx, scene, err);
    if (st == MCSG_OK)
        st = mci_scene_split(ctx, scene, NULL, err);
    if (st != MCSG_OK)
        mci_scene_free(ctx, scene);
    return st;
}

mcsg_status mci_scene_build_touched(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                                    size_t leaf_count, const uint32_t *alias,
                                    mci_scene *scene, mcsg_error *err)
{
    double t0 = mci_seconds_now();
    mci_octree_params params = {0, 0, NULL};
    uint8_t *skip = NULL;
    mcsg_status st;
    memset(scene, 0, sizeof *scene);
    scene->alias = alias;
    if (alias) {
        if (!(skip = mci_malloc_array(ctx, leaf_count + 1, 1)))
            return mci_fail_nomem(err, "building the octree");
        for (size_t l = 0; l < leaf_count; l++)
            skip[l] = alias[l] != l;
    }
    params.skip_leaf = skip;
    st = mci_octree_build(ctx, leaves, leaf_count, alias ? &params : NULL, &scene->octree, err);
    mci_free(ctx, skip);
    if (st != MCSG_OK)
        return st;
    scene->stats.seconds_octree = mci_seconds_now() - t0;
    scene->face_count = scene->octree.face_base[scene->octree.leaf_count];
    scene->stats.faces = scene->face_count;
    scene->stats.cells = scene->octree.cell_count;
    scene->stats.critical_cells = scene->octree.critical_leaf_cells;
    st = intersect_scene(ctx, scene, err);
    if (st != MCSG_OK)
        mci_scene_free(ctx, scene);
    return st;
}

void mci_scene_free_geometry(const mci_ctx *ctx, mci_scene *scene)
{
    for (size_t k = 0; scene->arrs && k < scene->arr_count; k++)
        mci_arr_free(ctx, &scene->arrs[k]);
    mci_free(ctx, scene->arrs);
    mci_free(ctx, scene->arr_of);
    mci_free(ctx, scene->neighbour);
    mci_free(ctx, scene->gid_start);
    mci_free(ctx, scene->gid);
    mci_free(ctx, scene->explicit_slot);
    mci_free(ctx, scene->touch_start);
    mci_free(ctx, scene->touch_leaf);
    mci_free(ctx, scene->arr_dropped);
    mci_free(ctx, scene->arr_contact);
    free_pending(ctx, scene);
    free_point_blocks(ctx, scene->hit_blocks, scene->hit_block_count);
    mci_free(ctx, scene->vertex_points);
    scene->hit_blocks = NULL;
    scene->hit_block_count = 0;
    scene->vertex_points = NULL;
    scene->arrs = NULL;
    scene->arr_of = scene->neighbour = scene->gid_start = scene->gid = NULL;
    scene->explicit_slot = scene->arr_dropped = scene->arr_contact = NULL;
    scene->touch_start = scene->touch_leaf = NULL;
    scene->arr_count = scene->point_count = 0;
    mci_octree_free_cells(ctx, &scene->octree);
}

void mci_scene_free(const mci_ctx *ctx, mci_scene *scene)
{
    mci_scene_free_geometry(ctx, scene);
    mci_octree_free(ctx, &scene->octree);
    memset(scene, 0, sizeof *scene);
}

/* Numbering in three steps, each deterministic:
 *   1. copies with the same definition (kind and defining vertices) are one point:
 *      found by hashing, no arithmetic (most shared points are defined identically by
 *      the faces that share them: canonical edge order, canonical TPI plane order);
 *   2. distinct definitions of one point (e.g. a crossing exactly at a vertex) are
 *      found among points whose certified boxes overlap, by a sweep along x, and
 *      joined after an exact equality test;
 *   3. numbers follow the first occurrence in (face, local index) order. */
typedef struct numbering {
    const mci_ctx *ctx;
    const mci_point **table; /* by slot */
    uint8_t *explicit_slot;  /* by slot, filled with the hashes */
    uint32_t *parent;        /* union-find over slots */
    size_t total;
} numbering;

/* Join with the smaller slot as root, so that roots are first occurrences. */
static void join(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a < b)
        parent[b] = a;
    else if (b < a)
        parent[a] = b;
}

/* Copies with one definition are found with one hash table per part of the hash space
 * (parts by the top bits, filled in parallel): a class of copies lies in one part, each
 * part takes its slots in increasing order, so every copy is joined to the first slot of
 * its class as a single table would do. */
enum { HASH_PARTS = 64, HASH_CHUNK = 16384 };

typedef struct same_job {
    numbering *nb;
    uint64_t *hash;                   /* by slot */
    uint32_t *by_part;                /* slots grouped by part, increasing within a part */
    size_t part_start[HASH_PARTS + 1];
} same_job;

static mcsg_status hash_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const same_job *j = user;
    size_t end = mci_chunk_end(j->nb->total, chunk, HASH_CHUNK);
    (void)err;
    for (size_t slot = chunk * HASH_CHUNK; slot < end; slot++) {
        j->hash[slot] = definition_hash(j->nb->table[slot]);
        j->nb->explicit_slot[slot] = j->nb->table[slot]->kind == MCI_POINT_EXPLICIT;
    }
    return MCSG_OK;
}

static mcsg_status join_part(void *user, size_t part, mcsg_error *err)
{
    const same_job *j = user;
    const numbering *nb = j->nb;
    size_t first = j->part_start[part], n = j->part_start[part + 1] - first, size = 16;
    uint32_t *bucket;
    while (size < 2 * n)
        size *= 2;
    if (!(bucket = mci_malloc_array(nb->ctx, size, sizeof *bucket)))
        return mci_fail_nomem(err, "numbering points");
    for (size_t i = 0; i < size; i++)
        bucket[i] = MCI_NONE;
    for (size_t i = 0; i < n; i++) {
        uint32_t slot = j->by_part[first + i];
        size_t at = j->hash[slot] & (size - 1);
        while (bucket[at] != MCI_NONE &&
               (j->hash[bucket[at]] != j->hash[slot] ||
                !mci_points_same_definition(nb->table[bucket[at]], nb->table[slot])))
            at = (at + 1) & (size - 1);
        if (bucket[at] == MCI_NONE)
            bucket[at] = slot;
        else
            nb->parent[slot] = bucket[at]; /* both are roots: the first of the class wins */
    }
    mci_free(nb->ctx, bucket);
    return MCSG_OK;
}

static mcsg_status join_same_definitions(const mci_ctx *ctx, numbering *nb, mcsg_error *err)
{
    same_job j = {nb, mci_malloc_array(ctx, nb->total + 1, sizeof *j.hash),
                  mci_malloc_array(ctx, nb->total + 1, sizeof *j.by_part), {0}};
    mcsg_status st = j.hash && j.by_part ? MCSG_OK : mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, (nb->total + HASH_CHUNK - 1) / HASH_CHUNK, hash_chunk, &j, err);
    if (st == MCSG_OK) { /* a stable counting sort of the slots by part */
        size_t at[HASH_PARTS] = {0};
        for (size_t slot = 0; slot < nb->total; slot++)
            j.part_start[(j.hash[slot] >> 58) + 1]++;
        for (size_t q = 0; q < HASH_PARTS; q++)
            j.part_start[q + 1] += j.part_start[q];
        for (size_t q = 0; q < HASH_PARTS; q++)
            at[q] = j.part_start[q];
        for (size_t slot = 0; slot < nb->total; slot++)
            j.by_part[at[j.hash[slot] >> 58]++] = (uint32_t)slot;
        st = mci_parallel_for(ctx, HASH_PARTS, join_part, &j, err);
    }
    mci_free(ctx, j.hash);
    mci_free(ctx, j.by_part);
    return st;
}

/* The certified box rounded outward to floats: the table of these is the peak of the
 * dense scenes' runs (ring-800: 238K roots), and a larger box only adds pairs to test. */
typedef struct boxed_slot {
    float lo[3], hi[3];
    uint32_t slot;
} boxed_slot;

/* A key whose unsigned order is the numeric order of x (not NaN; -0 counts as +0). */
static uint32_t orderable_float(float x)
{
    uint32_t bits;
    x += 0.0f; /* -0 -> +0 */
    memcpy(&bits, &x, sizeof bits);
    return bits >> 31 ? ~bits : bits | (UINT32_C(1) << 31);
}

typedef struct bounds_job {
    const numbering *nb;
    boxed_slot *items;
    uint64_t *order; /* per item: its low x (orderable_float) << 32 | its index */
    size_t n;
} bounds_job;

/* The certified boxes (the cost of this step: LPI and TPI bounds), in parallel. */
static mcsg_status bound_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const bounds_job *j = user;
    size_t end = mci_chunk_end(j->n, chunk, HASH_CHUNK);
    (void)err;
    for (size_t i = chunk * HASH_CHUNK; i < end; i++) {
        boxed_slot *item = &j->items[i];
        double lo[3], hi[3];
        mci_point_bounds(j->nb->table[item->slot], lo, hi);
        for (int k = 0; k < 3; k++) { /* a NaN bound (overflow) bounds nothing */
            item->lo[k] = isnan(lo[k]) ? -INFINITY : mci_float_below(lo[k]);
            item->hi[k] = isnan(hi[k]) ? INFINITY : mci_float_above(hi[k]);
        }
        j->order[i] = (uint64_t)orderable_float(item->lo[0]) << 32 | i;
    }
    return MCSG_OK;
}

/* Sorted by low x (radix), then each run of equal low x by low y: the run's keys become
 * low y << 32 | index. run_end[i] is the first later position with another low x. */
static void sort_by_low_x_then_y(const boxed_slot *items, uint64_t *order, size_t n,
                                 uint32_t *run_end)
{
    for (size_t i = n; i-- > 0;)
        run_end[i] = i + 1 < n && order[i + 1] >> 32 == order[i] >> 32 ? run_end[i + 1]
                                                                       : (uint32_t)(i + 1);
    for (size_t i = 0; i < n; i = run_end[i]) {
        if (run_end[i] - i < 2)
            continue;
        for (size_t k = i; k < run_end[i]; k++)
            order[k] = (uint64_t)orderable_float(items[(uint32_t)order[k]].lo[1]) << 32 |
                       (uint32_t)order[k];
        mci_sort_u64(order + i, run_end[i] - i);
    }
}

static bool boxes_meet_in_yz(const boxed_slot *a, const boxed_slot *b)
{
    return !(a->lo[1] > b->hi[1] || b->lo[1] > a->hi[1] || a->lo[2] > b->hi[2] ||
             b->lo[2] > a->hi[2]);
}

/* Distinct definitions of one point: a sweep along x over the certified boxes, each
 * pair whose boxes overlap tested exactly. Items are sorted by low x, then low y: within
 * a run of equal low x every item overlaps the first in x, and the run is in y order, so
 * its scan stops at the first item beyond the first's y range. Axis-aligned input puts
 * hundreds of points on one x (a column of a grid of holes), which a sweep on x alone
 * compared pairwise (box_grid_64: quadratic per column). The joins do not depend on the
 * order, only on the pairs. */
static void join_overlapping(numbering *nb, const boxed_slot *items, const uint64_t *order,
                             const uint32_t *run_end, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const boxed_slot *a = &items[(uint32_t)order[i]];
        size_t k = i + 1;
        for (; k < run_end[i]; k++) {
            const boxed_slot *b = &items[(uint32_t)order[k]];
            if (b->lo[1] > a->hi[1]) {
                k = run_end[i];
                break;
            }
            if (boxes_meet_in_yz(a, b) && mci_points_equal(nb->table[a->slot], nb->table[b->slot]))
                join(nb->parent, a->slot, b->slot);
        }
        for (; k < n && items[(uint32_t)order[k]].lo[0] <= a->hi[0]; k++) {
            const boxed_slot *b = &items[(uint32_t)order[k]];
            if (boxes_meet_in_yz(a, b) && mci_points_equal(nb->table[a->slot], nb->table[b->slot]))
                join(nb->parent, a->slot, b->slot);
        }
    }
}

static mcsg_status join_equal_points(const mci_ctx *ctx, numbering *nb, mcsg_error *err)
{
    size_t roots = 0;
    bounds_job j = {nb, NULL, NULL, 0};
    uint32_t *run_end;
    mcsg_status st;
    /* Sized for the roots only: most slots are copies (ring-800: 797K slots). */
    for (uint32_t slot = 0; slot < nb->total; slot++)
        roots += nb->parent[slot] == slot;
    j.items = mci_malloc_array(ctx, roots + 1, sizeof *j.items);
    j.order = mci_malloc_array(ctx, roots + 1, sizeof *j.order);
    run_end = mci_malloc_array(ctx, roots + 1, sizeof *run_end);
    st = j.items && j.order && run_end ? MCSG_OK : mci_fail_nomem(err, "numbering points");
    for (uint32_t slot = 0; st == MCSG_OK && slot < nb->total; slot++)
        if (nb->parent[slot] == slot) /* not a copy of an earlier definition */
            j.items[j.n++].slot = slot;
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, (j.n + HASH_CHUNK - 1) / HASH_CHUNK, bound_chunk, &j, err);
    if (st == MCSG_OK && !mci_radix_sort_u64(ctx, j.order, j.n))
        st = mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK) {
        sort_by_low_x_then_y(j.items, j.order, j.n, run_end);
        join_overlapping(nb, j.items, j.order, run_end, j.n);
    }
    mci_free(ctx, j.items);
    mci_free(ctx, j.order);
    mci_free(ctx, run_end);
    return st;
}

/* The table and the identity parents, on the threads in chunks of arrangements
 * (gid_start set); then, after the joins, the numbers: roots (first occurrences) are
 * numbered in slot order through per-chunk counts, so the numbering does not depend on
 * the threads. Both loops ran on one thread: 797K slots on ring-800. */
enum { SLOT_ARR_CHUNK = 4096 };

typedef struct slots_job {
    mci_scene *s;
    numbering *nb;
    uint32_t *first_id; /* per chunk of slots: the number of its first root */
} slots_job;

static mcsg_status fill_slot_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const slots_job *j = user;
    const mci_scene *s = j->s;
    size_t end = mci_chunk_end(s->arr_count, chunk, SLOT_ARR_CHUNK);
    (void)err;
    for (size_t k = chunk * SLOT_ARR_CHUNK; k < end; k++)
        for (uint32_t p = 0, slot = s->gid_start[k]; p < s->arrs[k].point_count; p++, slot++) {
            j->nb->table[slot] = s->arrs[k].points[p];
            j->nb->parent[slot] = slot;
        }
    return MCSG_OK;
}

static mcsg_status fill_slots(const mci_ctx *ctx, mci_scene *s, numbering *nb, mcsg_error *err)
{
    slots_job j = {s, nb, NULL};
    return mci_parallel_for(ctx, (s->arr_count + SLOT_ARR_CHUNK - 1) / SLOT_ARR_CHUNK,
                            fill_slot_chunk, &j, err);
}

/* Pass 1: gid[slot] = its root (parent is only read: no path compression on the threads),
 * and the chunk's count of roots in first_id. */
static mcsg_status root_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const slots_job *j = user;
    const uint32_t *parent = j->nb->parent;
    size_t end = mci_chunk_end(j->nb->total, chunk, HASH_CHUNK);
    uint32_t roots = 0;
    (void)err;
    for (size_t slot = chunk * HASH_CHUNK; slot < end; slot++) {
        uint32_t x = (uint32_t)slot;
        while (parent[x] != x)
            x = parent[x];
        j->s->gid[slot] = x;
        roots += x == slot;
    }
    j->first_id[chunk] = roots;
    return MCSG_OK;
}

/* Pass 2: each root's number into parent (no longer needed as such). */
static mcsg_status number_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const slots_job *j = user;
    size_t end = mci_chunk_end(j->nb->total, chunk, HASH_CHUNK);
    uint32_t id = j->first_id[chunk];
    (void)err;
    for (size_t slot = chunk * HASH_CHUNK; slot < end; slot++)
        if (j->s->gid[slot] == slot)
            j->nb->parent[slot] = id++;
    return MCSG_OK;
}

/* Pass 3: every slot takes its root's number. */
static mcsg_status renumber_chunk(void *user, size_t chunk, mcsg_error *err)
{
    const slots_job *j = user;
    size_t end = mci_chunk_end(j->nb->total, chunk, HASH_CHUNK);
    (void)err;
    for (size_t slot = chunk * HASH_CHUNK; slot < end; slot++)
        j->s->gid[slot] = j->nb->parent[j->s->gid[slot]];
    return MCSG_OK;
}

static mcsg_status number_roots(const mci_ctx *ctx, mci_scene *s, numbering *nb, uint32_t *count,
                                mcsg_error *err)
{
    size_t chunks = (nb->total + HASH_CHUNK - 1) / HASH_CHUNK;
    slots_job j = {s, nb, mci_malloc_array(ctx, chunks + 1, sizeof *j.first_id)};
    mcsg_status st = j.first_id ? mci_parallel_for(ctx, chunks, root_chunk, &j, err)
                                : mci_fail_nomem(err, "numbering points");
    *count = 0;
    for (size_t c = 0; st == MCSG_OK && c < chunks; c++) { /* counts -> first numbers */
        uint32_t roots = j.first_id[c];
        j.first_id[c] = *count;
        *count += roots;
    }
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, chunks, number_chunk, &j, err);
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, chunks, renumber_chunk, &j, err);
    mci_free(ctx, j.first_id);
    return st;
}

mcsg_status mci_scene_number_points(const mci_ctx *ctx, mci_scene *s, mcsg_error *err)
{
    numbering nb = {ctx, NULL, NULL, NULL, 0};
    uint32_t id = 0;
    bool ok;
    mcsg_status st;
    double t0 = mci_seconds_now();
    for (size_t k = 0; k < s->arr_count; k++)
        nb.total += s->arrs[k].point_count;
    if (nb.total >= UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "too many intersection points (%zu)", nb.total);
    s->gid_start = mci_malloc_array(ctx, s->arr_count + 1, sizeof *s->gid_start);
    s->explicit_slot = nb.explicit_slot = mci_malloc_array(ctx, nb.total + 1, 1);
    nb.table = mci_malloc_array(ctx, nb.total + 1, sizeof *nb.table);
    nb.parent = mci_malloc_array(ctx, nb.total + 1, sizeof *nb.parent);
    ok = s->gid_start && s->explicit_slot && nb.table && nb.parent;
    for (size_t k = 0, slot = 0; ok && k < s->arr_count; k++) {
        s->gid_start[k] = (uint32_t)slot;
        slot += s->arrs[k].point_count;
    }
    if (ok)
        s->gid_start[s->arr_count] = (uint32_t)nb.total;
    st = ok ? fill_slots(ctx, s, &nb, err) : mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK)
        st = join_same_definitions(ctx, &nb, err);
    if (st == MCSG_OK)
        st = join_equal_points(ctx, &nb, err);
    /* Allocated last: the joins' tables were this step's peak. */
    if (st == MCSG_OK && !(s->gid = mci_malloc_array(ctx, nb.total + 1, sizeof *s->gid)))
        st = mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK)
        st = number_roots(ctx, s, &nb, &id, err);
    s->point_count = st == MCSG_OK ? id : 0;
    mci_free(ctx, nb.table);
    mci_free(ctx, nb.parent);
    s->stats.seconds_merge = mci_seconds_now() - t0;
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Public entry: the curves                                                            */

/* Every elementary edge of every arrangement, once (both faces along a curve have it). */
static uint64_t *curve_edges(const mci_ctx *ctx, const mci_scene *s, size_t *count)
{
    size_t n = 0;
    uint64_t *keys;
    for (size_t k = 0; k < s->arr_count; k++)
        n += s->arrs[k].edge_count;
    keys = mci_malloc_array(ctx, n + 1, sizeof *keys);
    if (!keys)
        return NULL;
    for (size_t k = 0, i = 0; k < s->arr_count; k++) {
        const uint32_t *gid = s->gid + s->gid_start[k];
        for (size_t e = 0; e < s->arrs[k].edge_count; e++) {
            uint64_t a = gid[s->arrs[k].edges[e].a], b = gid[s->arrs[k].edges[e].b];
            keys[i++] = a < b ? a << 32 | b : b << 32 | a;
        }
    }
    mci_sort_u64(keys, n);
    *count = mci_unique_u64(keys, n);
    return keys;
}

/* Renumber the points the curves use, densely (corners off the curves are left out). */
static size_t compact_points(const mci_scene *s, const uint64_t *keys, size_t count,
                             uint32_t *new_id)
{
    size_t used = 0;
    for (size_t i = 0; i < s->point_count; i++)
        new_id[i] = MCI_NONE;
    for (size_t i = 0; i < 2 * count; i++) {
        uint32_t g = (uint32_t)(i % 2 ? keys[i / 2] : keys[i / 2] >> 32);
        if (new_id[g] == MCI_NONE)
            new_id[g] = (uint32_t)used++;
    }
    return used;
}

static mcsg_status export_curves(const mci_ctx *ctx, const mci_scene *s, mcsg_curves *out,
                                 mcsg_error *err)
{
    size_t count = 0, used = 0;
    uint64_t *keys = curve_edges(ctx, s, &count);
    uint32_t *new_id = mci_malloc_array(ctx, s->point_count + 1, sizeof *new_id);
    if (keys && new_id)
        used = compact_points(s, keys, count, new_id);
    out->points = mci_malloc_array(ctx, used + 1, 3 * sizeof(double));
    out->segments = mci_malloc_array(ctx, 2 * count + 1, sizeof(uint32_t));
    if (!keys || !new_id || !out->points || !out->segments) {
        mci_free(ctx, keys);
        mci_free(ctx, new_id);
        mci_free(ctx, out->points);
        mci_free(ctx, out->segments);
        memset(out, 0, sizeof *out);
        return mci_fail_nomem(err, "collecting the curves");
    }
    for (size_t k = 0; k < s->arr_count; k++)
        for (size_t p = 0; p < s->arrs[k].point_count; p++) {
            uint32_t id = new_id[s->gid[s->gid_start[k] + p]];
            if (id != MCI_NONE)
                mci_point_round(s->arrs[k].points[p], out->points + 3 * (size_t)id);
        }
    for (size_t i = 0; i < count; i++) {
        out->segments[2 * i] = new_id[keys[i] >> 32];
        out->segments[2 * i + 1] = new_id[(uint32_t)keys[i]];
    }
    out->point_count = used;
    out->segment_count = count;
    mci_free(ctx, keys);
    mci_free(ctx, new_id);
    return MCSG_OK;
}

static size_t collect_leaves(const mcsg_tree *tree, const mcsg_mesh **leaves)
{
    size_t n = 0;
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++) {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(tree, id);
        if (m && m->triangle_count > 0)
            leaves[n++] = m;
    }
    return n;
}

mcsg_status mcsg_intersect(const mcsg_tree *tree, const mcsg_options *opts, mcsg_curves *out,
                           mcsg_intersect_stats *stats, mcsg_error *err)
{
    mci_ctx ctx;
    mci_scene scene;
    const mcsg_mesh **leaves;
    mcsg_status st;
    mci_ctx_init(&ctx, opts);
    memset(out, 0, sizeof *out);
    memset(&scene, 0, sizeof scene);
    if (!tree)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_intersect: NULL tree");
    leaves = mci_malloc_array(&ctx, mcsg_tree_node_count(tree) + 1, sizeof *leaves);
    if (!leaves)
        return mci_fail_nomem(err, "intersecting faces");
    mci_pool_start(&ctx);
    st = mci_progress(&ctx, "intersect", 0, err);
    if (st == MCSG_OK)
        st = mci_scene_build(&ctx, leaves, collect_leaves(tree, leaves), &scene, err);
    if (st == MCSG_OK)
        st = mci_scene_number_points(&ctx, &scene, err);
    if (st == MCSG_OK)
        st = mci_progress(&ctx, "intersect", 1, err);
    if (st == MCSG_OK)
        st = export_curves(&ctx, &scene, out, err);
    if (stats)
        *stats = scene.stats;
    mci_scene_free(&ctx, &scene);
    mci_free(&ctx, leaves);
    mci_pool_stop(&ctx);
    return st;
}

void mcsg_curves_free(mcsg_curves *curves, const mcsg_options *opts)
{
    mci_ctx ctx;
    if (!curves)
        return;
    mci_ctx_init(&ctx, opts);
    mci_free(&ctx, curves->points);
    mci_free(&ctx, curves->segments);
    memset(curves, 0, sizeof *curves);
}
