/*
 * Per-face arrangement (paper §4.2, §5.4; design brief §3), exact throughout:
 *
 *   inputs     crossing segments (this face ∩ another leaf's face), single contact
 *              points, coplanar faces of other leaves (their edges clipped to this
 *              face), points on this face's edges found by its neighbours;
 *   merge      coincident points become one (exact lexicographic sort + equality),
 *              each point classified as corner / on edge i / inside;
 *   split      every segment is cut at each point lying inside it and at each proper
 *              crossing with another segment; a crossing is a new implicit point
 *              (TPI of this face's plane and the two segments' planes, or the LPI of a
 *              coplanar edge line with the other segment's plane), so triple points of
 *              three leaves come out exactly;
 *   triangulate  any subset of the elementary edges (triangulate.c).
 *
 * Every segment's line is the intersection of this face's plane with a second plane:
 * the other face's plane for a crossing, and for a coplanar edge u-v the plane through
 * u, v and an auxiliary vertex `aux` = u moved along the projection axis (so off this
 * face's plane: the plane contains the edge and is transversal to the face). The
 * auxiliary vertices are stored in the arrangement so that points may refer to them.
 *
 * Candidate pairs for splitting come from a sweep over certified bounding boxes
 * (mci_point_bounds), so a face crossed by thousands of segments is not quadratic
 * unless their boxes overlap.
 */
#include "csg/arrange.h"
#include "base/sort_template.h"
#include "csg/triangulate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double *corner(const mci_face_arr *arr, int i)
{
    return i == 0 ? arr->plane.a : i == 1 ? arr->plane.b : arr->plane.c;
}

/* A vertex off the face's plane: x moved along the projection axis. */
static const double *add_aux(mci_face_arr *arr, const double *x)
{
    double *r;
    if (arr->aux_count == arr->aux_capacity)
        return NULL;
    r = arr->aux[arr->aux_count++];
    memcpy(r, x, 3 * sizeof *r);
    r[arr->axis] = x[arr->axis] + 1.0 != x[arr->axis] ? x[arr->axis] + 1.0
                                                      : x[arr->axis] / 2; /* |x| >= 2^53 */
    return r;
}

/* Blocks of points an arrangement made itself. A block is never moved (points are
 * referred to by address); a full one is followed by one twice its size. */
struct mci_point_pool {
    mci_point_pool *next;
    uint32_t count, capacity;
    mci_point p[];
};

static const mci_point *pool_copy(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p)
{
    mci_point_pool *pool = arr->own;
    if (!pool || pool->count == pool->capacity) {
        uint32_t capacity = pool ? 2 * pool->capacity : 4;
        mci_point_pool *block =
            mci_malloc(ctx, sizeof *block + (size_t)capacity * sizeof block->p[0]);
        if (!block)
            return NULL;
        block->next = pool;
        block->count = 0;
        block->capacity = capacity;
        arr->own = pool = block;
    }
    pool->p[pool->count] = *p;
    return &pool->p[pool->count++];
}

static void free_pool(const mci_ctx *ctx, mci_point_pool *pool)
{
    while (pool) {
        mci_point_pool *next = pool->next;
        mci_free(ctx, pool);
        pool = next;
    }
}

mcsg_status mci_arr_init(const mci_ctx *ctx, mci_face_arr *arr, uint32_t face,
                         const double *a, const double *b, const double *c,
                         const mci_point *const corners[3], size_t max_coplanar,
                         size_t points, mcsg_error *err)
{
    memset(arr, 0, sizeof *arr);
    arr->face = face;
    mci_plane_init(&arr->plane, a, b, c);
    arr->axis = mci_plane_projection_axis(&arr->plane, &arr->sign);
    if (arr->axis < 0)
        return mci_fail(err, MCSG_ERR_INVALID_MESH, "face %u is degenerate", face);
    /* Only coplanar faces use auxiliary vertices (72 bytes for the corners' alone, in
     * every arrangement, showed in the peak memory of dense scenes). */
    arr->aux_capacity = max_coplanar ? 3 + 3 * (uint32_t)max_coplanar : 0;
    if (max_coplanar)
        arr->aux = mci_malloc_array(ctx, arr->aux_capacity, sizeof *arr->aux);
    if ((max_coplanar && !arr->aux) || !mci_arr_reserve(ctx, arr, points > 3 ? points : 3, 0)) {
        mci_arr_free(ctx, arr);
        return mci_fail_nomem(err, "arranging a face");
    }
    for (int i = 0; i < 3; i++) {
        const mci_point *kept = corners ? corners[i] : NULL;
        if (max_coplanar)
            add_aux(arr, corner(arr, i)); /* aux[i]: for the face's edge i */
        if (!kept) {
            mci_point p;
            mci_point_explicit(&p, corner(arr, i));
            kept = pool_copy(ctx, arr, &p);
        }
        if (!kept || !mci_arr_add_point(ctx, arr, kept)) {
            mci_arr_free(ctx, arr);
            return mci_fail_nomem(err, "arranging a face");
        }
    }
    return MCSG_OK;
}

/* What merging the three corners would give: they stay in place, located, with no
 * line (without the merge's allocation and sort: in dense scenes many touched faces
 * are dropped whole). */
mcsg_status mci_arr_init_corners(const mci_ctx *ctx, mci_face_arr *arr, uint32_t face,
                                 const double *a, const double *b, const double *c,
                                 const mci_point *const corners[3], mcsg_error *err)
{
    mcsg_status st = mci_arr_init(ctx, arr, face, a, b, c, corners, 0, 3, err);
    if (st != MCSG_OK)
        return st;
    for (int i = 0; i < 3; i++)
        arr->where[i] = (uint8_t)(MCI_AT_CORNER + i);
    arr->where_count = 3;
    arr->dirty = false;
    return MCSG_OK;
}

void mci_arr_free(const mci_ctx *ctx, mci_face_arr *arr)
{
    mci_free(ctx, arr->points); /* and the lines and locations, in the same block */
    mci_free(ctx, arr->segments);
    mci_free(ctx, arr->edges);
    mci_free(ctx, arr->aux);
    mci_free(ctx, arr->tris);
    mci_free(ctx, arr->adj);
    free_pool(ctx, arr->own);
    memset(arr, 0, sizeof *arr);
}

void mci_arr_free_segments(const mci_ctx *ctx, mci_face_arr *arr)
{
    mci_free(ctx, arr->segments);
    arr->segments = NULL;
    arr->segment_count = arr->segment_capacity = 0;
    arr->segments_freed = true;
}

/* A block for `capacity` points followed by their line lists and their locations (one
 * allocation where there were three: arrangements are many and small). */
static const mci_point **point_block(const mci_ctx *ctx, size_t capacity,
                                     mci_point_lines **lines, uint8_t **where)
{
    const mci_point **points = mci_malloc_array(ctx, capacity ? capacity : 1,
                                         sizeof *points + sizeof **lines + sizeof **where);
    *lines = points ? (mci_point_lines *)(void *)(points + capacity) : NULL;
    *where = points ? (uint8_t *)(void *)(*lines + capacity) : NULL;
    return points;
}

/* A new block of `capacity` (at least point_count) points, keeping the contents. */
static bool resize_points(const mci_ctx *ctx, mci_face_arr *arr, size_t capacity)
{
    mci_point_lines *lines;
    const mci_point **points;
    uint8_t *where;
    if (capacity > UINT32_MAX || !(points = point_block(ctx, capacity, &lines, &where)))
        return false;
    if (arr->point_count) { /* the first block has nothing to copy (and memcpy no NULL) */
        memcpy(points, arr->points, arr->point_count * sizeof *points);
        memcpy(lines, arr->lines, arr->point_count * sizeof *lines);
        /* locations, and the appended points' known ones */
        memcpy(where, arr->where, arr->point_count * sizeof *where);
    }
    mci_free(ctx, arr->points);
    arr->points = points;
    arr->lines = lines;
    arr->where = where;
    arr->point_capacity = (uint32_t)capacity;
    return true;
}

/* Room for one more point: the block doubles (at least 8). */
static bool grow_points(const mci_ctx *ctx, mci_face_arr *arr)
{
    size_t capacity = arr->point_capacity < 4 ? 8 : 2 * arr->point_capacity;
    if (arr->point_count < arr->point_capacity)
        return true;
    return resize_points(ctx, arr, capacity);
}

bool mci_arr_reserve(const mci_ctx *ctx, mci_face_arr *arr, size_t points, size_t segments)
{
    if (points > arr->point_capacity && !resize_points(ctx, arr, points))
        return false;
    if (segments > arr->segment_capacity) {
        mci_arr_segment *grown = segments > UINT32_MAX ? NULL
                                 : mci_realloc_array(ctx, arr->segments, segments, sizeof *grown);
        if (!grown)
            return false;
        arr->segments = grown;
        arr->segment_capacity = (uint32_t)segments;
    }
    return true;
}

static uint64_t line_id(const mci_point_lines *l, int i)
{
    return (uint64_t)l->high[i] << 32 | l->low[i];
}

static void add_line(mci_point_lines *l, uint64_t line)
{
    for (int i = 0; i < l->count; i++)
        if (line_id(l, i) == line)
            return;
    if (line != 0 && l->count < 3) {
        l->low[l->count] = (uint32_t)line;
        l->high[l->count++] = (uint8_t)(line >> 32);
    }
}

/* Add a point known to lie on `line` (0: none known), at `where` (MCI_AT_*, or
 * MCI_AT_UNKNOWN): until the next merge, where[] holds the appended points' known
 * locations, which merging keeps instead of locating them again. */
static bool add_point_on(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p,
                         uint64_t line, uint8_t where)
{
    if (!grow_points(ctx, arr))
        return false;
    arr->lines[arr->point_count].count = 0;
    add_line(&arr->lines[arr->point_count], line);
    arr->where[arr->point_count] = where;
    arr->points[arr->point_count++] = p;
    arr->dirty = true;
    return true;
}

/* The corner an explicit point coincides with, or -1. */
static int coinciding_corner(const mci_face_arr *arr, const mci_point *p)
{
    const double *x = p->v[0];
    if (p->kind != MCI_POINT_EXPLICIT || arr->point_count < 3)
        return -1;
    for (int i = 0; i < 3; i++) {
        const double *c = corner(arr, i);
        if (x[0] == c[0] && x[1] == c[1] && x[2] == c[2])
            return i;
    }
    return -1;
}

/* add_point_on, except that an explicit copy of a corner replaces the corner's stored
 * copy instead of being appended: merging would join them, keep an explicit copy and
 * every line, so the result is the same, without sorting the copies (a face with a
 * coplanar twin and touching neighbours receives each corner a dozen times).
 * Returns the point's index, or UINT32_MAX when out of memory. */
static uint32_t add_point_once(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p,
                               uint64_t line, uint8_t where)
{
    int k = coinciding_corner(arr, p);
    if (k < 0)
        return add_point_on(ctx, arr, p, line, where) ? (uint32_t)arr->point_count - 1
                                                      : UINT32_MAX;
    arr->points[k] = p;
    add_line(&arr->lines[k], line);
    arr->dirty = true;
    return (uint32_t)k;
}

bool mci_arr_add_point(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p)
{
    return add_point_once(ctx, arr, p, 0, MCI_AT_UNKNOWN) != UINT32_MAX;
}

/* The stored corner when p is an explicit point at the same vertex (p's very
 * definition: a face receives copies of its corners from every neighbour and twin),
 * else a copy in the pool. */
const mci_point *mci_arr_keep(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p)
{
    int k = coinciding_corner(arr, p);
    if (k >= 0 && arr->points[k]->kind == MCI_POINT_EXPLICIT && arr->points[k]->v[0] == p->v[0])
        return arr->points[k];
    return pool_copy(ctx, arr, p);
}

static bool add_point_copy(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p)
{
    const mci_point *kept = mci_arr_keep(ctx, arr, p);
    return kept && mci_arr_add_point(ctx, arr, kept);
}

/* where: the ends' known locations (NULL: unknown). */
static bool add_segment(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *a,
                        const mci_point *b, const mci_arr_segment *s, const uint8_t *where)
{
    uint32_t ia, ib;
    size_t capacity = arr->segment_capacity;
    if (arr->segments_freed)
        return false;
    ia = add_point_once(ctx, arr, a, s->line, where ? where[0] : MCI_AT_UNKNOWN);
    ib = ia == UINT32_MAX ? UINT32_MAX
         : add_point_once(ctx, arr, b, s->line, where ? where[1] : MCI_AT_UNKNOWN);
    if (ib == UINT32_MAX || arr->segment_count == UINT32_MAX ||
        !mci_grow_array(ctx, (void **)&arr->segments, &capacity, arr->segment_count + 1,
                        sizeof *arr->segments, 8) || capacity > UINT32_MAX)
        return false;
    arr->segment_capacity = (uint32_t)capacity;
    arr->segments[arr->segment_count] = *s;
    arr->segments[arr->segment_count].a = ia;
    arr->segments[arr->segment_count++].b = ib;
    return true;
}

/* Line ids: a crossing's line is this face's plane ∩ the other plane, named by the
 * plane's id (+1, so that 0 means none: at most 2^32); a coplanar edge's line is named
 * by the edge (2^39 + 3 face + edge < 2^40). Point line lists keep 40 bits. */
#define COPLANAR_LINE (1ull << 39)

bool mci_arr_add_crossing(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *a,
                          const mci_point *b, uint32_t other, const mci_plane *other_plane,
                          uint32_t plane_id, uint32_t group, bool on_edge,
                          const uint8_t where[2])
{
    mci_arr_segment s = {0, 0, other, 0, {other_plane->a, other_plane->b, other_plane->c},
                         (uint64_t)plane_id + 1, group, on_edge, 0};
    return add_segment(ctx, arr, a, b, &s, where);
}

/* ---------------------------------------------------------------------------------- */
/* Coplanar faces: clip each of their edges to this face                               */

/* Corner i as a point: points 0..2 are the corners (merging and add_point_once keep
 * them there), stored as built or as a coincident copy; the sign of a predicate does not
 * depend on which definition of a point it gets, only its cost does, so any explicit
 * copy will do. */
static const mci_point *corner_point(const mci_face_arr *arr, int i, mci_point *scratch)
{
    const mci_point *p = arr->point_count > (size_t)i ? arr->points[i] : NULL;
    if (p && p->kind == MCI_POINT_EXPLICIT)
        return p;
    mci_point_explicit(scratch, corner(arr, i));
    return scratch;
}

static int side_of_edge(const mci_face_arr *arr, int e, const mci_point *p)
{
    mci_point s0, s1;
    const mci_point *c0 = corner_point(arr, e, &s0), *c1 = corner_point(arr, (e + 1) % 3, &s1);
    return arr->sign * mci_orient2d_projected(c0, c1, p, arr->axis);
}

/* The part of the line u->v inside the face is [*start, *end]: each face edge the
 * segment crosses moves one of them (entering or leaving). */
typedef struct clip_state {
    mci_point cut[3];
    const mci_point *start, *end;
    bool empty, on_boundary;
} clip_state;

static void clip_by_edge(mci_face_arr *arr, int e, const mci_point *pu, const mci_point *pv,
                         clip_state *c)
{
    int su = side_of_edge(arr, e, pu), sv = side_of_edge(arr, e, pv);
    const double *u = pu->v[0], *v = pv->v[0];
    const mci_point *enter = NULL, *leave = NULL;
    if (su == 0 && sv == 0) {
        c->on_boundary = true;
        return;
    }
    if (su < 0 && sv < 0) {
        c->empty = true;
        return;
    }
    if (su * sv < 0) {
        mci_plane edge_plane;
        mci_plane_init(&edge_plane, corner(arr, e), corner(arr, (e + 1) % 3), arr->aux[e]);
        (void)mci_point_lpi(&c->cut[e], u, v, &edge_plane); /* strict sides: exists */
        *(su < 0 ? &enter : &leave) = &c->cut[e];
    } else if (su == 0 && sv < 0) {
        leave = pu;
    } else if (su < 0 && sv == 0) {
        enter = pv;
    }
    if (enter && mci_order_on_edge_line(enter, c->start, u, v) > 0)
        c->start = enter;
    if (leave && mci_order_on_edge_line(leave, c->end, u, v) < 0)
        c->end = leave;
}

static bool clip_coplanar_edge(const mci_ctx *ctx, mci_face_arr *arr, uint32_t other,
                               uint32_t group, int edge, const double *u, const double *v,
                               bool crease)
{
    mci_point pu, pv;
    clip_state c;
    int order;
    mci_point_explicit(&pu, u);
    mci_point_explicit(&pv, v);
    memset(&c, 0, sizeof c);
    c.start = &pu;
    c.end = &pv;
    for (int e = 0; e < 3 && !c.empty; e++)
        clip_by_edge(arr, e, &pu, &pv, &c);
    if (c.empty || (order = mci_order_on_edge_line(c.start, c.end, u, v)) > 0)
        return true;
    if (order == 0)
        return add_point_copy(ctx, arr, c.start);
    if (c.on_boundary)
        return add_point_copy(ctx, arr, c.start) && add_point_copy(ctx, arr, c.end);
    {
        const double *aux = add_aux(arr, u);
        const mci_point *start = mci_arr_keep(ctx, arr, c.start);
        const mci_point *end = start ? mci_arr_keep(ctx, arr, c.end) : NULL;
        mci_arr_segment s = {0, 0, other, 1, {u, v, aux},
                             COPLANAR_LINE + 3 * (uint64_t)other + (uint64_t)edge, group, 1,
                             !crease};
        return aux && end && add_segment(ctx, arr, start, end, &s, NULL);
    }
}

static bool same_point(const double *a, const double *b)
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* Whether the three vertices are this face's corners (in any order). */
static bool is_twin(const mci_face_arr *arr, const double *const v[3])
{
    for (int i = 0; i < 3; i++)
        if (!same_point(v[i], corner(arr, 0)) && !same_point(v[i], corner(arr, 1)) &&
            !same_point(v[i], corner(arr, 2)))
            return false;
    return !same_point(v[0], v[1]) && !same_point(v[1], v[2]) && !same_point(v[0], v[2]);
}

bool mci_arr_add_coplanar(const mci_ctx *ctx, mci_face_arr *arr, uint32_t other,
                          const mci_plane *other_plane, const bool crease[3], uint32_t group)
{
    const double *v[3] = {other_plane->a, other_plane->b, other_plane->c};
    if (!arr->aux || arr->segments_freed) /* not announced to mci_arr_init, or too late */
        return false;
    arr->coplanar = true;
    /* An identical face (identical operands): every edge lies along an edge of this face,
     * so clipping would only add its two ends; the same points, without the tests. */
    if (is_twin(arr, v)) {
        for (int i = 0; i < 3; i++) {
            mci_point a, b;
            mci_point_explicit(&a, v[i]);
            mci_point_explicit(&b, v[(i + 1) % 3]);
            if (!add_point_copy(ctx, arr, &a) || !add_point_copy(ctx, arr, &b))
                return false;
        }
        return true;
    }
    for (int i = 0; i < 3; i++)
        if (!clip_coplanar_edge(ctx, arr, other, group, i, v[i], v[(i + 1) % 3], crease[i]))
            return false;
    return true;
}

/* ---------------------------------------------------------------------------------- */
/* Exact merging                                                                       */

/* A point for sorting, with certified bounds of its x coordinate: points whose bounds
 * are apart (most pairs) are ordered without reading the point. */
typedef struct point_key {
    const mci_point *p;
    double lo, hi;
} point_key;

static void set_key(point_key *k, const mci_point *p)
{
    k->p = p;
    if (p->exact_axes & 1) {
        k->lo = k->hi = p->c[0];
    } else { /* as mci_point_bounds: one step outward covers the rounding of c -+ r */
        k->lo = mci_next_down(p->c[0] - p->r);
        k->hi = mci_next_up(p->c[0] + p->r);
    }
}

/* mci_compare_lex of the two points. */
static int compare_keys(const point_key *a, const point_key *b)
{
    if (a->hi < b->lo)
        return -1;
    if (a->lo > b->hi)
        return 1;
    return mci_compare_lex(a->p, b->p);
}

/* Merges two runs of point ids sorted by mci_compare_lex (a before b on ties, as a
 * stable sort keeps the lower ids of run a first) into out. */
static void merge_runs(const point_key *table, const uint32_t *a, size_t na,
                       const uint32_t *b, size_t nb, uint32_t *out)
{
    size_t i = 0, j = 0, k = 0;
    while (i < na && j < nb)
        out[k++] = compare_keys(&table[b[j]], &table[a[i]]) < 0 ? b[j++] : a[i++];
    while (i < na)
        out[k++] = a[i++];
    while (j < nb)
        out[k++] = b[j++];
}

/* Sort ids by the exact lexicographic order of the points table[id] (stable merge sort;
 * tmp has n entries). */
static void sort_point_ids(const point_key *table, uint32_t *ids, uint32_t *tmp, size_t n)
{
    for (size_t width = 1; width < n; width *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * width) {
            size_t mid = lo + width < n ? lo + width : n;
            size_t hi = lo + 2 * width < n ? lo + 2 * width : n;
            merge_runs(table, ids + lo, mid - lo, ids + mid, hi - mid, tmp + lo);
        }
        memcpy(ids, tmp, n * sizeof *ids);
    }
}

/* New id of every point after merging (corners keep 0..2, the rest follow in sorted
 * order). Returns the number of distinct points. */
static size_t merge_ids(const mci_face_arr *arr, const uint32_t *sorted, uint32_t *remap)
{
    size_t n = arr->point_count, next = 3;
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        uint32_t id = UINT32_MAX;
        while (j < n && mci_points_equal(arr->points[sorted[j]], arr->points[sorted[i]]))
            j++;
        for (size_t k = i; k < j; k++)
            if (sorted[k] < 3)
                id = sorted[k];
        if (id == UINT32_MAX)
            id = (uint32_t)next++;
        for (size_t k = i; k < j; k++)
            remap[sorted[k]] = id;
        i = j;
    }
    return next;
}

/* Whether p lies on the line of face edge e by its very definition (an end point of
 * the edge, or an LPI on the edge's line): the predicate would be an exact zero, which
 * only the slow exact stage can confirm. */
static bool defined_on_edge(const mci_face_arr *arr, int e, const mci_point *p)
{
    const double *u = corner(arr, e), *w = corner(arr, (e + 1) % 3);
    if (p->kind == MCI_POINT_EXPLICIT)
        return p->v[0] == u || p->v[0] == w;
    return p->kind == MCI_POINT_LPI &&
           ((p->v[0] == u && p->v[1] == w) || (p->v[0] == w && p->v[1] == u));
}

/* MCI_AT_* of a point of the face, or UINT8_MAX if it is off the face. */
static uint8_t locate_in_face(const mci_face_arr *arr, const mci_point *p)
{
    int side[3], zeros = 0;
    for (int e = 0; e < 3; e++) {
        side[e] = defined_on_edge(arr, e, p) ? 0 : side_of_edge(arr, e, p);
        if (side[e] < 0)
            return UINT8_MAX;
        zeros += side[e] == 0;
    }
    if (zeros == 0)
        return MCI_AT_INSIDE;
    for (int e = 0; e < 3; e++) {
        if (zeros == 1 && side[e] == 0)
            return (uint8_t)(MCI_AT_EDGE + e);
        if (zeros == 2 && side[e] == 0 && side[(e + 2) % 3] == 0)
            return (uint8_t)(MCI_AT_CORNER + e); /* edges e - 1 and e meet at corner e */
    }
    return UINT8_MAX;
}

/* MCI_AT_* of the points whose location is not known yet (after a merge: the points
 * added since the previous one and not given with their location; a location depends
 * on the point alone, not on which of its copies is stored, so the others kept theirs).
 * Debug builds check the given locations too. */
static mcsg_status locate_new_points(mci_face_arr *arr, mcsg_error *err)
{
    uint8_t *where = arr->where;
    for (size_t i = 0; i < arr->point_count; i++) {
        if (where[i] != MCI_AT_UNKNOWN)
            continue;
        where[i] = i < 3 ? (uint8_t)(MCI_AT_CORNER + i) : locate_in_face(arr, arr->points[i]);
        if (i >= 3 && where[i] < MCI_AT_EDGE)
            return mci_fail(err, MCSG_ERR_INTERNAL, "arrangement of face %u: a corner "
                            "appears twice", arr->face);
        if (where[i] == UINT8_MAX)
            return mci_fail(err, MCSG_ERR_INTERNAL, "arrangement of face %u: a point is off "
                            "the face", arr->face);
    }
#ifndef NDEBUG
    for (size_t i = 3; i < arr->point_count; i++)
        if (where[i] != locate_in_face(arr, arr->points[i]))
            return mci_fail(err, MCSG_ERR_INTERNAL, "arrangement of face %u: point %zu was "
                            "given at the wrong place", arr->face, i);
#endif
    return MCSG_OK;
}

/* The order sort_point_ids gives all n points when the first `merged` are the
 * result of the previous merge (corners 0..2, then distinct points in lexicographic
 * order) and the rest were added since: the corners are merged into the sorted run,
 * the new points sorted alone, and the two runs merged. The same stable order for far
 * fewer comparisons: faces receiving a few points from their neighbours' edges are
 * merged again. idx and tmp hold n ids. */
static void sort_after_merge(const point_key *table, size_t merged, size_t n,
                             uint32_t *idx, uint32_t *tmp)
{
    uint32_t corners[3] = {0, 1, 2}, scratch[3];
    for (size_t i = 3; i < n; i++)
        tmp[i] = (uint32_t)i;
    sort_point_ids(table, corners, scratch, 3);
    merge_runs(table, corners, 3, tmp + 3, merged - 3, idx);
    sort_point_ids(table, tmp + merged, idx + merged, n - merged);
    /* Into tmp itself: output slot i + j never passes the unread new ids at merged + j. */
    merge_runs(table, idx, merged, tmp + merged, n - merged, tmp);
    memcpy(idx, tmp, n * sizeof *idx);
}

/* A point where a segment is cut (found by the splitter, consumed by build_edges). */
typedef struct arr_cut {
    uint32_t segment, point;
} arr_cut;

/* Merge; the `cut_count` cuts (segment, point) given get their point ids renumbered. */
static mcsg_status merge_points(const mci_ctx *ctx, mci_face_arr *arr, arr_cut *cuts,
                                size_t cut_count, mcsg_error *err)
{
    size_t n = arr->point_count, kept = 0;
    /* One block for the key table, the two id arrays of the sort and the id map (four
     * allocations per merge were a sizeable part of the merge's cost on small faces). */
    point_key *table = mci_malloc_array(ctx, n + 1, sizeof *table + 3 * sizeof(uint32_t));
    uint32_t *idx = table ? (uint32_t *)(void *)(table + n + 1) : NULL;
    uint32_t *tmp = idx ? idx + n + 1 : NULL;
    uint32_t *remap = tmp ? tmp + n + 1 : NULL;
    const mci_point **merged = NULL;
    mci_point_lines *merged_lines = NULL;
    uint8_t *merged_where = NULL;
    mcsg_status st = table ? MCSG_OK : mci_fail_nomem(err, "arranging a face");
    /* After a merge, where_count is its point count and only appends follow. */
    size_t before = arr->where_count >= 3 && arr->where_count <= n ? arr->where_count : 0;
    for (size_t i = 0; table && i < n; i++)
        set_key(&table[i], arr->points[i]);
    if (st == MCSG_OK) {
        if (before) {
            sort_after_merge(table, before, n, idx, tmp);
        } else {
            for (size_t i = 0; i < n; i++)
                idx[i] = (uint32_t)i;
            sort_point_ids(table, idx, tmp, n);
        }
        kept = merge_ids(arr, idx, remap);
        /* Sized after merging: faces with twins or many neighbours along their edges
         * collect several copies of each point, and the arrangement keeps this array. */
        if (!(merged = point_block(ctx, kept, &merged_lines, &merged_where)))
            st = mci_fail_nomem(err, "arranging a face");
    }
    if (st == MCSG_OK) {
        size_t out = 0;
        for (size_t i = 0; i < kept; i++)
            merged_lines[i].count = 0;
        for (size_t i = 0; i < n; i++) {
            /* A corner stays explicit: an implicit copy (an LPI exactly there) has the
             * same value, but rounding it would lose the input's sign of zero. Other
             * points keep their last copy. */
            if (remap[i] >= 3 || arr->points[i]->kind == MCI_POINT_EXPLICIT)
                merged[remap[i]] = arr->points[i];
            for (int l = 0; l < arr->lines[i].count; l++)
                add_line(&merged_lines[remap[i]], line_id(&arr->lines[i], l));
        }
        for (size_t s = 0; s < arr->segment_count; s++) {
            mci_arr_segment seg = arr->segments[s];
            seg.a = remap[seg.a];
            seg.b = remap[seg.b];
            if (seg.a != seg.b)
                arr->segments[out++] = seg;
        }
        arr->segment_count = out;
        for (size_t k = 0; k < cut_count; k++)
            cuts[k].point = remap[cuts[k].point];
        memset(merged_where, MCI_AT_UNKNOWN, kept);
        for (size_t i = 0; i < before; i++)
            merged_where[remap[i]] = arr->where[i];
        for (size_t i = before; i < n; i++) /* known locations of appended points */
            if (merged_where[remap[i]] == MCI_AT_UNKNOWN)
                merged_where[remap[i]] = arr->where[i];
        mci_free(ctx, arr->points);
        arr->points = merged;
        arr->lines = merged_lines;
        arr->where = merged_where;
        arr->point_count = arr->point_capacity = arr->where_count = kept;
        merged = NULL;
        st = locate_new_points(arr, err);
        arr->dirty = false;
    }
    mci_free(ctx, table);
    mci_free(ctx, merged);
    return st;
}

mcsg_status mci_arr_merge(const mci_ctx *ctx, mci_face_arr *arr, mcsg_error *err)
{
    return merge_points(ctx, arr, NULL, 0, err);
}

/* ---------------------------------------------------------------------------------- */
/* Splitting                                                                           */

/* The face edges a classified point lies on (corner i is on edges i and i - 1). */
static uint8_t edge_mask_of(const mci_face_arr *arr, uint32_t p)
{
    uint8_t where = p < arr->where_count ? arr->where[p] : MCI_AT_INSIDE;
    if (where < MCI_AT_EDGE)
        return (uint8_t)(1u << where | 1u << (where + 2) % 3);
    return where < MCI_AT_INSIDE ? (uint8_t)(1u << (where - MCI_AT_EDGE)) : 0;
}

static bool shares_line(const mci_point_lines *l, uint64_t line)
{
    for (int i = 0; i < l->count; i++)
        if (line_id(l, i) == line)
            return true;
    return false;
}

/* Collinear by construction: a repeated point, one face edge or one known line through
 * all three. */
static bool known_collinear(const void *user, uint32_t a, uint32_t b, uint32_t c)
{
    const mci_face_arr *arr = user;
    const mci_point_lines *la = &arr->lines[a];
    if (a == b || b == c || a == c)
        return true;
    if (edge_mask_of(arr, a) & edge_mask_of(arr, b) & edge_mask_of(arr, c))
        return true;
    for (int i = 0; i < la->count; i++)
        if (shares_line(&arr->lines[b], line_id(la, i)) &&
            shares_line(&arr->lines[c], line_id(la, i)))
            return true;
    return false;
}

/* Orientation of three points of the face in its own orientation. */
static int orient_ids(const mci_face_arr *arr, uint32_t a, uint32_t b, uint32_t c)
{
    const mci_point *const *p = arr->points;
    int s = mci_orient2d_projected_quick(p[a], p[b], p[c], arr->axis);
    if (s != MCI_UNCERTAIN)
        return arr->sign * s; /* never where known_collinear holds: the filter is exact */
    if (known_collinear(arr, a, b, c))
        return 0;
    return arr->sign * mci_orient2d_projected_rest(p[a], p[b], p[c], arr->axis);
}

/* A sweep item: a segment or a lone point, with a certified box in the projection. */
typedef struct sweep_item {
    double lo[2], hi[2];
    uint32_t id;
    bool is_point;
} sweep_item;

typedef struct splitter {
    const mci_ctx *ctx;
    mci_face_arr *arr;
    arr_cut *cuts;
    size_t cut_count, cut_capacity;
    bool ok;
} splitter;

static void cut(splitter *sp, uint32_t s, uint32_t p)
{
    if (!sp->ok || !mci_grow_array(sp->ctx, (void **)&sp->cuts, &sp->cut_capacity,
                                   sp->cut_count + 1, sizeof *sp->cuts, 8)) {
        sp->ok = false;
        return;
    }
    sp->cuts[sp->cut_count++] = (arr_cut){s, p};
}

/* Cut segment s at p if p, known to lie on its line, is strictly between its ends. */
static void cut_if_inside(splitter *sp, uint32_t s, uint32_t p)
{
    const mci_arr_segment *seg = &sp->arr->segments[s];
    const mci_point *const *pts = sp->arr->points;
    if (p != seg->a && p != seg->b &&
        mci_compare_lex(pts[seg->a], pts[p]) * mci_compare_lex(pts[p], pts[seg->b]) > 0) {
        cut(sp, s, p);
        add_line(&sp->arr->lines[p], seg->line);
    }
}

/* The TPI of three planes given in a canonical order (mci_plane_before), so
 * that the three faces of a triple point define it identically: their arrangements'
 * copies are then recognised as one point by definition, without arithmetic. */
static bool canonical_tpi(mci_point *out, const mci_plane *p1, const mci_plane *p2,
                          const mci_plane *p3)
{
    const mci_plane *q[3] = {p1, p2, p3}, *t;
    for (int m = 0; m < 2; m++)
        for (int k = 0; k < 2 - m; k++)
            if (mci_plane_before(q[k + 1], q[k]))
                t = q[k], q[k] = q[k + 1], q[k + 1] = t;
    return mci_point_tpi(out, q[0], q[1], q[2]);
}

/* The crossing point of two segments that cross properly. */
static bool crossing_point(const mci_face_arr *arr, const mci_arr_segment *s,
                           const mci_arr_segment *t, mci_point *out)
{
    mci_plane ps, pt;
    if (t->coplanar && !s->coplanar) {
        const mci_arr_segment *swap = s;
        s = t;
        t = swap;
    }
    mci_plane_init(&pt, t->l[0], t->l[1], t->l[2]);
    if (s->coplanar)
        return mci_point_lpi(out, s->l[0], s->l[1], &pt);
    mci_plane_init(&ps, s->l[0], s->l[1], s->l[2]);
    return canonical_tpi(out, &arr->plane, &ps, &pt);
}

static void relate_segments(splitter *sp, uint32_t s, uint32_t t)
{
    mci_face_arr *arr = sp->arr;
    mci_arr_segment S = arr->segments[s], T = arr->segments[t];
    bool same_line = S.line == T.line;
    int oc = same_line ? 0 : orient_ids(arr, S.a, S.b, T.a);
    int od = same_line ? 0 : orient_ids(arr, S.a, S.b, T.b), oa, ob;
    if (oc == 0 && od == 0) { /* collinear: each cuts the other at its ends */
        cut_if_inside(sp, s, T.a);
        cut_if_inside(sp, s, T.b);
        cut_if_inside(sp, t, S.a);
        cut_if_inside(sp, t, S.b);
        return;
    }
    oa = orient_ids(arr, T.a, T.b, S.a);
    ob = orient_ids(arr, T.a, T.b, S.b);
    if (oc * od < 0 && oa * ob < 0) {
        mci_point x;
        const mci_point *kept;
        uint32_t id = (uint32_t)arr->point_count;
        if (!crossing_point(arr, &S, &T, &x) || !(kept = pool_copy(sp->ctx, arr, &x)) ||
            !add_point_on(sp->ctx, arr, kept, S.line, MCI_AT_UNKNOWN)) {
            sp->ok = false;
            return;
        }
        add_line(&arr->lines[id], T.line);
        cut(sp, s, id);
        cut(sp, t, id);
        return;
    }
    if (oc == 0)
        cut_if_inside(sp, s, T.a);
    if (od == 0)
        cut_if_inside(sp, s, T.b);
    if (oa == 0)
        cut_if_inside(sp, t, S.a);
    if (ob == 0)
        cut_if_inside(sp, t, S.b);
}

static void relate_point(splitter *sp, uint32_t p, uint32_t s)
{
    const mci_arr_segment *seg = &sp->arr->segments[s];
    if (orient_ids(sp->arr, seg->a, seg->b, p) == 0)
        cut_if_inside(sp, s, p);
}

static void item_bounds(const mci_face_arr *arr, const double face_lo[2],
                        const double face_hi[2], const mci_point *p, sweep_item *it,
                        bool first)
{
    double lo[3], hi[3];
    mci_point_bounds(p, lo, hi);
    for (int k = 0; k < 2; k++) {
        int axis = (arr->axis + 1 + k) % 3;
        double l = mci_max(lo[axis], face_lo[k]), h = mci_min(hi[axis], face_hi[k]);
        it->lo[k] = first || l < it->lo[k] ? l : it->lo[k];
        it->hi[k] = first || h > it->hi[k] ? h : it->hi[k];
    }
}

/* Segments of one leaf, neither along an edge of its face: they meet only at shared
 * end points (see mci_arr_add_crossing). */
static bool one_surface(const mci_face_arr *arr, uint32_t s, uint32_t t)
{
    const mci_arr_segment *S = &arr->segments[s], *T = &arr->segments[t];
    return S->group == T->group && !S->on_edge && !T->on_edge;
}

/* (lo[0], segments before points, id): a total order (ids are unique within each
 * kind), so the unstable sort's result is unique. */
static inline bool item_less(const sweep_item *a, const sweep_item *b)
{
    if (a->lo[0] != b->lo[0])
        return a->lo[0] < b->lo[0];
    if (a->is_point != b->is_point)
        return b->is_point;
    return a->id < b->id;
}

MCI_DEFINE_SORT(sort_items, sweep_item, item_less)

/* Segments, and the points that are no segment's end (those are seen through their
 * segments). */
static sweep_item *sweep_items(const mci_ctx *ctx, const mci_face_arr *arr, size_t *count)
{
    double face_lo[2], face_hi[2];
    size_t n = 0, slots = arr->segment_count + arr->point_count;
    /* One block: the items, then a flag per point (in room for as many more items). */
    sweep_item *items = mci_malloc_array(ctx, slots + arr->point_count, sizeof *items);
    bool *is_end = items ? (bool *)(void *)(items + slots) : NULL;
    if (!items)
        return NULL;
    memset(is_end, 0, arr->point_count * sizeof *is_end);
    for (int k = 0; k < 2; k++) {
        int axis = (arr->axis + 1 + k) % 3;
        face_lo[k] = mci_min(mci_min(arr->plane.a[axis], arr->plane.b[axis]), arr->plane.c[axis]);
        face_hi[k] = mci_max(mci_max(arr->plane.a[axis], arr->plane.b[axis]), arr->plane.c[axis]);
    }
    for (size_t s = 0; s < arr->segment_count; s++, n++) {
        const mci_arr_segment *seg = &arr->segments[s];
        items[n].id = (uint32_t)s;
        items[n].is_point = false;
        item_bounds(arr, face_lo, face_hi, arr->points[seg->a], &items[n], true);
        item_bounds(arr, face_lo, face_hi, arr->points[seg->b], &items[n], false);
        is_end[seg->a] = is_end[seg->b] = true;
    }
    for (size_t p = 0; p < arr->point_count; p++) {
        if (is_end[p])
            continue;
        items[n].id = (uint32_t)p;
        items[n].is_point = true;
        item_bounds(arr, face_lo, face_hi, arr->points[p], &items[n], true);
        n++;
    }
    sort_items(items, n);
    *count = n;
    return items;
}

/* Relate every two items whose boxes overlap. */
static bool sweep(splitter *sp)
{
    size_t n;
    sweep_item *items = sweep_items(sp->ctx, sp->arr, &n);
    if (!items)
        return false;
    for (size_t i = 0; i < n && sp->ok; i++) {
        for (size_t j = i + 1; j < n && items[j].lo[0] <= items[i].hi[0] && sp->ok; j++) {
            const sweep_item *a = &items[i], *b = &items[j];
            if (a->lo[1] > b->hi[1] || b->lo[1] > a->hi[1] || (a->is_point && b->is_point))
                continue;
            if (!a->is_point && !b->is_point && !one_surface(sp->arr, a->id, b->id) &&
                !(sp->arr->segments[a->id].phantom && sp->arr->segments[b->id].phantom))
                relate_segments(sp, a->id, b->id);
            else if (!a->is_point && !b->is_point)
                continue;
            else if (!sp->arr->segments[a->is_point ? b->id : a->id].phantom)
                relate_point(sp, a->is_point ? a->id : b->id, a->is_point ? b->id : a->id);
        }
    }
    mci_free(sp->ctx, items);
    return sp->ok;
}

static inline bool cut_less(const arr_cut *a, const arr_cut *b)
{
    return a->segment != b->segment ? a->segment < b->segment : a->point < b->point;
}

MCI_DEFINE_SORT(sort_cuts, arr_cut, cut_less)

static inline bool edge_less(const mci_arr_edge *a, const mci_arr_edge *b)
{
    if (a->a != b->a)
        return a->a < b->a;
    if (a->b != b->b)
        return a->b < b->b;
    if (a->other != b->other)
        return a->other < b->other;
    return a->coplanar < b->coplanar;
}

/* Equal edges are equal in every field, so the unstable sort's order is unique. */
MCI_DEFINE_SORT(sort_edges, mci_arr_edge, edge_less)

static bool same_edge(const mci_arr_edge *a, const mci_arr_edge *b)
{
    return a->a == b->a && a->b == b->b && a->other == b->other && a->coplanar == b->coplanar;
}

/* The elementary edges of segment s: its ends and cuts (ids[0..n)) in order along it. */
static void emit_pieces(mci_face_arr *arr, const point_key *table,
                        const mci_arr_segment *s, uint32_t *ids, uint32_t *tmp, size_t n)
{
    sort_point_ids(table, ids, tmp, n);
    for (size_t k = 0; k + 1 < n; k++) {
        mci_arr_edge *e = &arr->edges[arr->edge_count];
        uint32_t u = ids[k], w = ids[k + 1];
        if (u == w)
            continue;
        e->a = u < w ? u : w;
        e->b = u < w ? w : u;
        e->other = s->other;
        e->coplanar = s->coplanar;
        arr->edge_count++;
    }
}

static bool build_edges(const mci_ctx *ctx, mci_face_arr *arr, arr_cut *cuts,
                        size_t cut_count)
{
    size_t max_pieces = arr->segment_count + cut_count, c = 0, out = 0;
    /* One block: the key table, then two id arrays of 2 + cut_count each (in room for
     * as many keys: a key is larger than two ids). */
    point_key *table = mci_malloc_array(ctx, arr->point_count + 2 + cut_count, sizeof *table);
    uint32_t *ids = table ? (uint32_t *)(void *)(table + arr->point_count) : NULL;
    uint32_t *tmp = ids ? ids + 2 + cut_count : NULL;
    for (size_t i = 0; table && i < arr->point_count; i++)
        set_key(&table[i], arr->points[i]);
    mci_free(ctx, arr->edges);
    arr->edge_count = 0;
    arr->edges = mci_malloc_array(ctx, max_pieces ? max_pieces : 1, sizeof *arr->edges);
    if (!table || !arr->edges) {
        mci_free(ctx, table);
        return false;
    }
    sort_cuts(cuts, cut_count);
    for (uint32_t s = 0; s < arr->segment_count; s++) {
        size_t n = 0;
        ids[n++] = arr->segments[s].a;
        ids[n++] = arr->segments[s].b;
        for (; c < cut_count && cuts[c].segment == s; c++)
            ids[n++] = cuts[c].point;
        if (!arr->segments[s].phantom)
            emit_pieces(arr, table, &arr->segments[s], ids, tmp, n);
    }
    sort_edges(arr->edges, arr->edge_count);
    for (size_t e = 0; e < arr->edge_count; e++)
        if (out == 0 || !same_edge(&arr->edges[e], &arr->edges[out - 1]))
            arr->edges[out++] = arr->edges[e];
    arr->edge_count = out;
    mci_free(ctx, table);
    return true;
}

mcsg_status mci_arr_split(const mci_ctx *ctx, mci_face_arr *arr, mcsg_error *err)
{
    splitter sp = {ctx, arr, NULL, 0, 0, true};
    mcsg_status st = MCSG_OK;
    size_t before;
    if (arr->segments_freed)
        return mci_fail(err, MCSG_ERR_INTERNAL, "face %u split after its segments were freed",
                        arr->face);
    if (arr->dirty && (st = merge_points(ctx, arr, NULL, 0, err)) != MCSG_OK)
        return st;
    before = arr->point_count;
    if (!sweep(&sp))
        st = mci_fail_nomem(err, "arranging a face");
    /* Crossing points may coincide with each other or with earlier points. */
    if (st == MCSG_OK && arr->point_count > before)
        st = merge_points(ctx, arr, sp.cuts, sp.cut_count, err);
    if (st == MCSG_OK && !build_edges(ctx, arr, sp.cuts, sp.cut_count))
        st = mci_fail_nomem(err, "arranging a face");
    mci_free(ctx, sp.cuts);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Triangulation                                                                       */

static size_t chosen_points(const mci_face_arr *arr, const bool *use, bool *mark,
                            uint32_t *insert)
{
    size_t n = 0;
    for (size_t e = 0; e < arr->edge_count; e++)
        if (!use || use[e])
            mark[arr->edges[e].a] = mark[arr->edges[e].b] = true;
    for (size_t p = 3; p < arr->point_count; p++)
        if (!use || mark[p] || edge_mask_of(arr, (uint32_t)p) != 0)
            insert[n++] = (uint32_t)p;
    return n;
}

static size_t chosen_edges(const mci_face_arr *arr, const bool *use, uint32_t *pairs)
{
    size_t n = 0;
    for (size_t e = 0; e < arr->edge_count; e++) {
        const mci_arr_edge *edge = &arr->edges[e];
        if ((use && !use[e]) ||
            (n > 0 && pairs[2 * n - 2] == edge->a && pairs[2 * n - 1] == edge->b))
            continue;
        pairs[2 * n] = edge->a;
        pairs[2 * n + 1] = edge->b;
        n++;
    }
    return n;
}

mcsg_status mci_arr_triangulate(const mci_ctx *ctx, mci_face_arr *arr, const bool *use,
                                mcsg_error *err)
{
    /* One block: insert (point_count ids), pairs (2 edge_count + 1 ids), then mark (one
     * flag per point, in room for as many ids). */
    size_t ids = arr->point_count + 2 * arr->edge_count + 1;
    uint32_t stack_ids[512]; /* most faces: no allocation */
    bool on_heap = ids + arr->point_count > sizeof stack_ids / sizeof *stack_ids;
    uint32_t *insert = on_heap ? mci_malloc_array(ctx, ids + arr->point_count, sizeof *insert)
                               : stack_ids;
    uint32_t *pairs = insert ? insert + arr->point_count : NULL;
    bool *mark = insert ? (bool *)(void *)(insert + ids) : NULL;
    mcsg_status st = MCSG_OK;
    if (mark)
        memset(mark, 0, arr->point_count * sizeof *mark);
    if (arr->dirty)
        st = mci_fail(err, MCSG_ERR_INTERNAL, "face %u triangulated before splitting", arr->face);
    mci_free(ctx, arr->tris);
    mci_free(ctx, arr->adj);
    arr->tris = NULL;
    arr->adj = NULL;
    arr->tri_count = 0;
    if (st == MCSG_OK && (!mark || !insert || !pairs)) {
        st = mci_fail_nomem(err, "triangulating a face");
    } else if (st == MCSG_OK) {
        mci_cdt_input in = {arr->points, arr->point_count, arr->axis, arr->sign, insert, 0,
                            pairs, 0, known_collinear, arr, arr->gid, arr->values};
        mci_cdt_output out;
        in.insert_count = chosen_points(arr, use, mark, insert);
        in.edge_count = chosen_edges(arr, use, pairs);
        st = mci_triangulate(ctx, &in, &out, err);
        if (st == MCSG_OK) {
            arr->tris = out.tris;
            arr->adj = out.adj;
            arr->tri_count = out.tri_count;
        }
    }
    if (on_heap)
        mci_free(ctx, insert);
    return st;
}
