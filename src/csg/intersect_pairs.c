/*
 * The pair tests of the intersection stage (paper §4.1): every candidate pair of faces
 * from the octree is intersected exactly once (exact/tri_tri.c), in fixed chunks on the
 * threads, and the contacts are kept as hits (intersect_internal.h). Each face's plane
 * is computed once, and the edge-plane points that the two faces along an edge both
 * find are one definition.
 */
#include "base/parallel.h"
#include "csg/intersect_internal.h"

#include <stdlib.h>
#include <string.h>

/* The pair tests build only two kinds of points: input vertices and edge lines meeting
 * the plane of f or of g (its corners say which). */
static bool push_hit(const mci_ctx *ctx, mci_hit_list *h, uint32_t f, uint32_t g,
                     const mci_tt_result *r, const mci_plane_cache *planes)
{
    int ends = r->kind == MCI_TT_SEGMENT ? 2 : r->kind == MCI_TT_POINT ? 1 : 0;
    mci_pair_hit *hit;
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
        const mci_plane *pf = mci_cached_plane(planes, f);
        mci_end_def *d;
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
typedef struct plane_job {
    const mci_scene *s;
    mci_plane_cache *c;
} plane_job;

static mcsg_status plane_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const plane_job *j = user;
    (void)err;
    for (size_t f = begin; f < end; f++)
        if (j->c->slot[f] != MCI_NONE)
            mci_scene_face_plane(j->s, (uint32_t)f, &j->c->planes[j->c->slot[f]]);
    return MCSG_OK;
}

static bool cache_planes(const mci_ctx *ctx, const mci_scene *s, const uint64_t *pairs,
                         size_t count, mci_plane_cache *c)
{
    plane_job job;
    size_t used = 0;
    c->slot = mci_malloc_array(ctx, s->face_count + 1, sizeof *c->slot);
    if (!c->slot)
        return false;
    /* Slots in face order: faces in pairs are marked, then numbered (a numbering in
     * order of first appearance branched on every face id of every pair). */
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
    return mci_parallel_for_ranges(ctx, s->face_count, MCI_FACE_CHUNK, plane_chunk, &job,
                                   NULL) == MCSG_OK;
}

/* The pair tests run in fixed-size chunks, each with its own hit list; the lists are
 * joined in chunk order, so the hits come out in pair order whatever the thread count. */
#define PAIR_CHUNK 4096

typedef struct pair_chunk {
    mci_hit_list hits;
    size_t crossing, points, coplanar;
} pair_chunk;

typedef struct pair_job {
    const mci_ctx *ctx;
    const uint64_t *pairs;
    size_t count;
    const mci_plane_cache *cache;
    pair_chunk *chunks;
} pair_job;

/* The lists cut to their contents. */
static bool trim_hits(const mci_ctx *ctx, mci_hit_list *h)
{
    mci_pair_hit *v = mci_realloc_array(ctx, h->v, h->count + 1, sizeof *v);
    mci_end_def *defs;
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

/* Whether coplanar faces f and g (planes p and q), their insides apart, touch at one
 * common corner only (exact/tri_tri.h): the contact adds nothing to either arrangement. */
static bool touch_at_common_corner_only(const mci_plane *p, const mci_plane *q)
{
    const double *a[3] = {p->a, p->b, p->c}, *b[3] = {q->a, q->b, q->c};
    int sign, axis = mci_plane_projection_axis(p, &sign);
    return axis >= 0 && mci_coplanar_touch_at_corner_only(a, b, axis);
}

/* Every other coplanar pair is kept, touching or not: faces that only share an edge
 * still exchange the points on it. */
static mcsg_status intersect_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    pair_job *j = user;
    pair_chunk *c = &j->chunks[begin / PAIR_CHUNK];
    size_t pairs = end - begin;
    mci_hit_list *h = &c->hits;
    /* Room for a hit per pair and two ends each, trimmed after: growing by doubling
     * copied every chunk's records about twice, and room never written takes no memory
     * from the system allocator. */
    if (!mci_grow_array(j->ctx, (void **)&h->v, &h->capacity, pairs, sizeof *h->v, 1) ||
        !mci_grow_array(j->ctx, (void **)&h->defs, &h->def_capacity, 2 * pairs,
                        sizeof *h->defs, 1))
        return mci_fail_nomem(err, "intersecting faces");
    for (size_t i = begin; i < end; i++) {
        uint32_t f = (uint32_t)(j->pairs[i] >> 32), g = (uint32_t)j->pairs[i];
        mci_tt_result r;
        mci_triangle_intersection_defined(mci_cached_plane(j->cache, f),
                                          mci_cached_plane(j->cache, g), &r);
        c->crossing += r.kind == MCI_TT_SEGMENT;
        c->points += r.kind == MCI_TT_POINT;
        c->coplanar += r.kind == MCI_TT_COPLANAR && r.overlap;
        if (r.kind == MCI_TT_COPLANAR && !r.overlap &&
            touch_at_common_corner_only(mci_cached_plane(j->cache, f),
                                        mci_cached_plane(j->cache, g)))
            continue;
        if (r.kind != MCI_TT_DISJOINT && !push_hit(j->ctx, &c->hits, f, g, &r, j->cache))
            return mci_fail_nomem(err, "intersecting faces");
    }
    return trim_hits(j->ctx, h) ? MCSG_OK : mci_fail_nomem(err, "intersecting faces");
}

/* The hash of a point's definition (kind and vertices), as intersect_numbering.c hashes
 * a built point. */
static uint64_t end_def_hash(const mci_end_def *d)
{
    return mci_hash_vertices(0x9e3779b97f4a7c15u ^ (uint64_t)MCI_POINT_LPI, d->v, 5);
}

static bool same_definition(const mci_end_def *a, const mci_end_def *b)
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
static bool merge_definitions(const mci_ctx *ctx, mci_hit_list *hits, const mci_end_def **at,
                              size_t n)
{
    size_t size = 16, distinct = 0;
    uint32_t *rep, *bucket;
    mci_end_def *fit;
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
    mci_hit_list *hits;
    size_t *first_hit, *first_def; /* per chunk: where its hits and definitions go */
    const mci_end_def **at;            /* by number across the chunks: the definition */
} join_job;

static mcsg_status join_chunk(void *user, size_t c, mcsg_error *err)
{
    const join_job *j = user;
    mci_hit_list *from = &j->chunks[c].hits;
    uint32_t base = (uint32_t)j->first_def[c];
    (void)err;
    for (size_t i = 0; i < from->count; i++) {
        mci_pair_hit h = from->v[i];
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
                               size_t n, mci_hit_list *hits, mcsg_error *err)
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

void mci_plane_cache_free(const mci_ctx *ctx, mci_plane_cache *c)
{
    mci_free(ctx, c->slot);
    mci_free(ctx, c->planes);
    c->slot = NULL;
    c->planes = NULL;
}

/* The hits of the candidate pairs, and in *cache the planes of their faces (the
 * arrangements use them again). */
mcsg_status mci_intersect_pairs(const mci_ctx *ctx, mci_scene *s, const uint64_t *pairs,
                                size_t count, mci_plane_cache *cache, mci_hit_list *hits,
                                mcsg_error *err)
{
    size_t n = (count + PAIR_CHUNK - 1) / PAIR_CHUNK;
    pair_job job = {ctx, pairs, count, cache, mci_calloc_array(ctx, n + 1, sizeof *job.chunks)};
    mcsg_status st = job.chunks && cache_planes(ctx, s, pairs, count, cache)
                         ? MCSG_OK
                         : mci_fail_nomem(err, "intersecting faces");
    if (st == MCSG_OK)
        st = mci_parallel_for_ranges(ctx, count, PAIR_CHUNK, intersect_chunk, &job, err);
    if (st == MCSG_OK)
        st = join_chunks(ctx, s, job.chunks, n, hits, err);
    for (size_t c = 0; job.chunks && c < n; c++) {
        mci_free(ctx, job.chunks[c].hits.v);
        mci_free(ctx, job.chunks[c].hits.defs);
    }
    mci_free(ctx, job.chunks);
    return st;
}

void mci_hit_list_free(const mci_ctx *ctx, mci_hit_list *hits)
{
    mci_free(ctx, hits->v);
    mci_free(ctx, hits->defs);
    memset(hits, 0, sizeof *hits);
}
