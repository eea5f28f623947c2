/*
 * From the pair tests' hits to per-face arrangements (paper §4.2): the faces across each
 * edge, the records of each touched face (crossing segments, contact points, creases of
 * coplanar faces), the points on a face's edge given to the face across that edge (so
 * both tessellations have them: no T-junctions), and the splitting of every arrangement
 * at its crossings. mci_scene_arrange and mci_scene_split (intersect.h) run the steps.
 */
#include "base/parallel.h"
#include "csg/intersect_internal.h"

#include <stdlib.h>
#include <string.h>

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

/* The face having the directed edge w -> u (canonical vertices), or MCI_NONE; at an edge
 * of more than two faces, f's mate there where its shell meets itself (`mates`, the
 * leaf check's pairing by angle), else one of the shell of global face f first: the
 * other half of f's surface there. */
static uint32_t face_with_edge(const mci_scene *s, const mcsg_mesh *m, const leaf_adjacency *a,
                               uint32_t w, uint32_t u, uint32_t base, uint32_t f,
                               const mci_edge_mates *mates)
{
    uint32_t first = MCI_NONE, same = MCI_NONE;
    uint32_t shell = mci_octree_face_shell(&s->octree, base + f);
    for (uint32_t k = a->start[w]; k < a->start[w + 1]; k++) {
        const uint32_t *t = m->triangles + 3 * (size_t)a->faces[k];
        for (int i = 0; i < 3; i++) {
            if (a->canon[t[i]] != w || a->canon[t[(i + 1) % 3]] != u)
                continue;
            if (mates && mci_edge_mates_has(mates, f, a->faces[k]))
                return a->faces[k];
            if (same == MCI_NONE &&
                mci_octree_face_shell(&s->octree, base + a->faces[k]) == shell)
                same = a->faces[k];
            if (first == MCI_NONE)
                first = a->faces[k];
        }
    }
    return same != MCI_NONE ? same : first;
}

static bool leaf_neighbours(const mci_ctx *ctx, mci_scene *s, size_t leaf, const bool *wanted)
{
    const mcsg_mesh *m = s->octree.leaves[leaf];
    uint32_t base = s->octree.face_base[leaf];
    leaf_adjacency a = {NULL, NULL, NULL};
    const mci_edge_mates *mates =
        s->leaf_mates && s->leaf_mates[leaf].count > 0 ? &s->leaf_mates[leaf] : NULL;
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
            uint32_t nb = face_with_edge(s, m, &a, a.canon[t[(i + 1) % 3]], a.canon[t[i]], base,
                                         f, mates);
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
mcsg_status mci_scene_build_neighbours(const mci_ctx *ctx, mci_scene *s, const mci_hit_list *hits,
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
static bool index_hits(const mci_ctx *ctx, const mci_scene *s, const mci_hit_list *hits,
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

/* Whether two vertices are one point: a leaf may hold copies of a vertex (where parts
 * touch), and faces are neighbours across an edge by coordinates. */
static bool same_vertex(const double *u, const double *v)
{
    return u == v || (u[0] == v[0] && u[1] == v[1] && u[2] == v[2]);
}

/* Whether the surface bends at edge i of face f: the face across is not coplanar, or
 * lies folded back onto f (its third corner in f's half-plane about the edge: a shell
 * crossing itself, a sliver turned over by rounding), where the sheets covering the
 * plane change as at a bend; an open edge counts as a crease. Across any other edge the
 * flat region goes on, and faces lying on it take the edge as no constraint. */
static bool edge_is_crease(const mci_scene *s, const mci_plane *plane, uint32_t f, int i)
{
    uint32_t nb = s->neighbour[3 * (size_t)f + i];
    const double *corners[3] = {plane->a, plane->b, plane->c};
    mci_point far;
    if (nb == MCI_NONE)
        return true;
    for (int k = 0; k < 3; k++) {
        const double *v = mci_scene_corner(s, nb, k);
        if (same_vertex(v, plane->a) || same_vertex(v, plane->b) || same_vertex(v, plane->c))
            continue;
        mci_point_explicit(&far, v);
        return mci_orient3d(&far, plane) != 0 ||
               mci_half_plane_class(corners[i], corners[(i + 1) % 3], corners[(i + 2) % 3],
                                    v) == 0;
    }
    return false;
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
    const mci_plane_cache *planes;
    const uint8_t *in_hits;
    face_facts *ff;
} crease_job;

static mcsg_status crease_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const crease_job *j = user;
    const mci_scene *s = j->s;
    (void)err;
    for (uint32_t f = (uint32_t)begin; f < end; f++) {
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

static bool compute_face_facts(const mci_ctx *ctx, const mci_scene *s, const mci_hit_list *hits,
                               const mci_plane_cache *planes, face_facts *ff)
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
        if (mci_parallel_for_ranges(ctx, s->face_count, MCI_FACE_CHUNK, crease_chunk, &job,
                                    NULL) != MCSG_OK) { /* cannot happen: no task fails */
            mci_free(ctx, in_hits);
            free_face_facts(ctx, ff);
            return false;
        }
    }
    for (uint32_t f = 0; f < s->face_count; f++) {
        for (int i = 0; in_hits[f] && i < 3; i++) {
            uint32_t nb = s->neighbour[3 * (size_t)f + i];
            if (nb != MCI_NONE && nb > f && in_hits[nb] && !((ff->crease[f] >> i) & 1))
                parent[mci_find_root(parent, nb)] = mci_find_root(parent, f);
        }
    }
    for (uint32_t f = 0; f < s->face_count; f++)
        parent[f] = mci_find_root(parent, f);
    mci_free(ctx, in_hits);
    return true;
}

/* One explicit point per vertex of an arranged face, which every arrangement with that
 * vertex refers to (a vertex is a corner of six faces and an end of many hits: copies
 * took much of the arrangement memory of dense scenes). `slot` maps global vertex ids
 * (leaf by leaf, from `first`) to points; it lives while arranging, the points as long
 * as the arrangements (mci_scene.vertex_points). */
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
 * over every vertex: a large model minus a shifted copy arranges few of its faces). */
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
                                mci_face_arr *arr, const mci_pair_hit *h, int k)
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
    const mci_hit_list *hits;
    const uint32_t *start, *list, *face_of;
    const face_facts *ff;
    const mci_plane_cache *planes;
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

static bool add_hit(const arrange_job *j, mci_face_arr *arr, const mci_pair_hit *h)
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
                                    mci_scene_face_group(s, other),
                                    h->along_edge[h->f == arr->face ? 1 : 0], where);
    case MCI_TT_POINT:
        a = hit_end(j->ctx, s, j->vt, arr, h, 0);
        return a && mci_arr_add_point(j->ctx, arr, a);
    default:
        /* A face of the same leaf lying on this one (a sheet overlapping itself, in a
         * leaf crossing itself): which of the two outputs their common part is decided
         * face by face (classify_labels.c, add_sheet), so every edge of the other face
         * bounds where the decision may change, flat or not. */
        for (int i = 0; i < 3; i++)
            crease[i] = ((j->ff->crease[other] >> i) & 1) ||
                        s->octree.face_leaf[other] == s->octree.face_leaf[arr->face];
        return mci_arr_add_coplanar(j->ctx, arr, other, plane, crease,
                                    mci_scene_face_group(s, other));
    }
}

/* The arrangement of face f with its n hits ids[]. */
static mcsg_status arrange_face(const arrange_job *j, uint32_t f, const uint32_t *ids, size_t n,
                                mci_face_arr *arr, mcsg_error *err)
{
    const mci_scene *s = j->s;
    const mci_pair_hit *hits = j->hits->v;
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
 * points on its edge `at` (an MCI_AT_EDGE location; MCI_AT_INSIDE: on any edge). Nearly
 * always so: the neighbour across an edge meets the same surfaces there and builds the
 * same edge-plane points itself (on the bench scenes every shared point is such a copy).
 * Sharing adds only what a face lacks, so most receivers stay merged: no copy, no second
 * merge. Only the points on that one edge are compared: a face cut by hundreds of others
 * has thousands of points, and comparing each edge point's definition with all of them
 * grew with the square of the cuts (the level-4 Menger sponge's faces). */
static bool has_edge_point(const mci_face_arr *t, uint8_t at, const mci_point *p)
{
    for (size_t q = 3; q < t->where_count; q++) {
        bool on_edge = at == MCI_AT_INSIDE
                           ? t->where[q] >= MCI_AT_EDGE && t->where[q] < MCI_AT_INSIDE
                           : t->where[q] == at;
        if (on_edge && mci_points_same_definition(t->points[q], p))
            return true;
    }
    return false;
}

/* The edge of face nb across which face f lies, as an MCI_AT_EDGE location; MCI_AT_INSIDE
 * if none (where a leaf's edges pair unevenly). */
static uint8_t edge_toward(const mci_scene *s, uint32_t nb, uint32_t f)
{
    for (int k = 0; k < 3; k++)
        if (s->neighbour[3 * (size_t)nb + k] == f)
            return (uint8_t)(MCI_AT_EDGE + k);
    return MCI_AT_INSIDE;
}

/* The arrangement that point p of arr should also be in (its edge neighbour's), or NULL
 * when there is none or it has the point already. */
static mci_face_arr *share_target(const mci_scene *s, const mci_face_arr *arr, size_t p)
{
    uint32_t nb;
    mci_face_arr *t;
    uint8_t at;
    if (arr->where[p] < MCI_AT_EDGE || arr->where[p] >= MCI_AT_INSIDE)
        return NULL;
    nb = s->neighbour[3 * (size_t)arr->face + (arr->where[p] - MCI_AT_EDGE)];
    if (nb == MCI_NONE || is_dropped(s, s->arr_of[nb]))
        return NULL; /* a face dropped whole has no pieces to join (see collect_walls) */
    t = &s->arrs[s->arr_of[nb]];
    at = edge_toward(s, nb, arr->face);
    return has_edge_point(t, at, arr->points[p]) ? NULL : t;
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

static mcsg_status find_lacking(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const lack_job *j = user;
    (void)err;
    for (size_t k = begin; k < end; k++) {
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
        st = mci_parallel_for_ranges(ctx, s->arr_count, LACK_CHUNK, find_lacking, &job, err);
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
 * the segments were a sizeable part of the dense scenes' peak memory. */
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
 * quadratic. */
static bool record_touches(const mci_ctx *ctx, mci_scene *s, const mci_hit_list *hits,
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
            const mci_pair_hit *h = &hits->v[list[i]];
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

void mci_free_point_blocks(const mci_ctx *ctx, mci_point **blocks, size_t count)
{
    for (size_t b = 0; blocks && b < count; b++)
        mci_free(ctx, blocks[b]);
    mci_free(ctx, blocks);
}

/* The pair tests' records from mci_scene_build_touched to mci_scene_arrange. */
struct mci_scene_pending {
    mci_hit_list hits;
    mci_plane_cache planes;
    face_facts ff;
    uint32_t *start, *list; /* index_hits */
    uint32_t *face_of;      /* arrangement -> face */
    vertex_table vt;        /* its points belong to the scene (vertex_points) */
};

/* Everything but the vertex table's map. */
static void free_pending_records(const mci_ctx *ctx, struct mci_scene_pending *pd)
{
    mci_hit_list_free(ctx, &pd->hits);
    mci_plane_cache_free(ctx, &pd->planes);
    free_face_facts(ctx, &pd->ff);
    mci_free(ctx, pd->start);
    mci_free(ctx, pd->list);
    mci_free(ctx, pd->face_of);
    pd->start = pd->list = pd->face_of = NULL;
}

void mci_scene_free_pending(const mci_ctx *ctx, mci_scene *s)
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
static uint8_t end_edges(const mci_hit_list *hits, const mci_plane_cache *planes, uint32_t f,
                         const double *const c[3], const mci_pair_hit *h, int k)
{
    mci_point p, corner[3];
    uint8_t mask = 0;
    int axis, sign;
    if ((h->stored >> k) & 1) {
        const mci_end_def *d = &hits->defs[h->point[k].index];
        uint8_t where = line_end_location(c, d->v[0], d->v[1], (h->strict_ends >> k) & 1);
        if (where == MCI_AT_INSIDE)
            return 0;
        if (where != MCI_AT_UNKNOWN)
            return (uint8_t)(1u << (where - MCI_AT_EDGE));
        (void)mci_point_lpi(&p, d->v[0], d->v[1], mci_cached_plane(planes, d->plane_face));
    } else {
        mci_point_explicit(&p, h->vertex[k]);
    }
    axis = mci_plane_projection_axis(mci_cached_plane(planes, f), &sign);
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
        const mci_pair_hit *h = &pd->hits.v[pd->list[i]];
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

static mcsg_status contact_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    mci_scene *s = user;
    (void)err;
    for (size_t k = begin; k < end; k++)
        s->arr_contact[k] = face_contact(s, s->pending, s->pending->face_of[k]);
    return MCSG_OK;
}

/* Takes the hits and the plane cache into s->pending, with what arranging will need:
 * face facts, the hit index, arrangement numbers, touch lists, the vertex table and
 * each face's contacts. */
mcsg_status mci_scene_prepare_arrangements(const mci_ctx *ctx, mci_scene *s, mci_hit_list *hits,
                                        mci_plane_cache *planes, mcsg_error *err)
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
    return mci_parallel_for_ranges(ctx, s->arr_count, CONTACT_CHUNK, contact_chunk, s, err);
}

/* Building the stored ends that arranged faces use: in parallel chunks of definitions,
 * each built into its own slot of one block. */
typedef struct build_job {
    const mci_hit_list *hits;
    const mci_plane_cache *planes;
    const uint32_t *slot; /* per definition: its place in block, or MCI_NONE */
    mci_point *block;
} build_job;

enum { BUILD_CHUNK = 4096 };

static mcsg_status build_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const build_job *j = user;
    (void)err;
    for (size_t i = begin; i < end; i++) {
        const mci_end_def *d = &j->hits->defs[i];
        if (j->slot[i] != MCI_NONE) /* the pair test built it once: it exists */
            (void)mci_point_lpi(&j->block[j->slot[i]], d->v[0], d->v[1],
                                mci_cached_plane(j->planes, d->plane_face));
    }
    return MCSG_OK;
}

/* The points of the stored ends of hits with a face that is arranged (not dropped
 * whole), in the scene's hit_blocks; each hit's stored ends then point to them (NULL:
 * both faces dropped). */
static mcsg_status build_points(const mci_ctx *ctx, mci_scene *s, mci_hit_list *hits,
                                const mci_plane_cache *planes, mcsg_error *err)
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
        const mci_pair_hit *x = &hits->v[h];
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
    st = job.block ? mci_parallel_for_ranges(ctx, hits->def_count, BUILD_CHUNK, build_chunk,
                                             &job, err)
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
    mci_scene_free_pending(ctx, s);
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

