/*
 * Vertices that carry no shape (mci_remove_flat_vertices). The exact result keeps every
 * point where two curves of the arrangement met, and every input vertex of a kept face:
 * a cube minus a cylinder gets a vertex wherever a diagonal of the cylinder's side quads
 * crosses the cube's face, and a fan's centre stays inside its flat face. Such a vertex
 * lies inside a flat part of the surface, or inside a straight edge between two flat
 * parts; removing it and triangulating the hole it leaves changes nothing of the shape.
 *
 * Only vertices of touched faces are looked at: elsewhere the vertices are the leaves'
 * own, as the user made them (and testing every vertex of a scanned model cost 5% of
 * its evaluation). A vertex v is removable when its triangles form one fan (every edge
 * at v has exactly two triangles, one each way, and a walk around v meets them all) and,
 * walking around, consecutive triangles change plane (faces not in one plane facing one
 * way, decided exactly on the faces' input corners) either never, or exactly twice
 * between two planes that are not one plane facing both ways. In the second case both
 * edges where the plane changes lie on the line where the two planes meet, so each side
 * of v is a half-disc and v lies inside the straight segment between those edges' other
 * ends. Removing a vertex never changes whether another one is removable: its
 * neighbours' edges stay where they were, merged into longer ones on the same lines.
 *
 * The hole a removed vertex leaves is, on each side, a polygon (its fan's outer edges,
 * closed by the straight segment through v in the second case). It is filled by joining
 * v onto a corner of its fan (onto an end of the straight segment in the second case)
 * where every triangle then turns counter-clockwise in its plane, which exact
 * orientations in the plane's projection decide; else by clipping ears. Vertices are
 * removed in rounds, each a set of vertices no two of which share a triangle, until none
 * is left; each round groups again only the triangles that still have a removable
 * corner. A new edge can have more than two triangles only where another part of the
 * result touches a flat region along a segment that was no edge: the removal is then
 * undone whole (the touching parts would become an edge of four triangles once welded).
 */
#include "csg/flat_vertices.h"
#include "base/sort.h"

#include <stdlib.h>
#include <string.h>

/* Fans with more triangles are left alone: filling their holes costs up to the square of
 * their corners, and a fan this large is rare outside meshes made of fans. */
enum { MAX_POLYGON = 1024 };

/* Planes of recently used faces, by face id modulo the size: neighbouring vertices
 * share faces, and a plane per face of a scanned model would cost more memory than the
 * rest of the pass. The pairs of faces tested, by a hash of the pair. */
enum { PLANE_CACHE = 4096, PAIR_MEMO_BITS = 13 };

/* A triangle's corner at a vertex v: the triangle is (v, next, prev). A fan walk reads
 * only its vertex's run of these (reading the triangles instead cost a cache miss per
 * step on large results). */
typedef struct corner {
    uint32_t tri, next, prev, face;
} corner;

typedef struct flat_state {
    const mci_ctx *ctx;
    const mci_flat_source *src;
    uint32_t *tris, *faces;  /* the result's triangles, removed ones marked dead */
    uint8_t *dead, *taken;   /* per triangle; taken: its fan changed this round */
    size_t count, cap;
    uint32_t *origin;        /* per triangle copied from kept: its index there */
    size_t origin_count;     /* the copied ones come first */
    mci_plane planes[PLANE_CACHE];
    uint32_t plane_face[PLANE_CACHE];
    uint64_t pair_key[1 << PAIR_MEMO_BITS];
    uint8_t pair_relation[1 << PAIR_MEMO_BITS];
    uint8_t *removable;      /* per vertex id: still to be removed */
    uint32_t *local;         /* per vertex id: its number in the grouping plus one, or 0
                                (zeroed pages a scan's vertices never touch) */
    uint32_t *verts;         /* the grouping's vertices, by number */
    uint32_t *pending;       /* a round's vertices to remove */
    size_t group_cap;        /* triangles the grouping's arrays have room for */
    uint32_t vertex_count;
    uint32_t *start;         /* per grouped vertex: its run in corners */
    corner *corners;         /* the work triangles' corners, grouped by vertex */
    /* one vertex's fan and hole */
    uint32_t *fan, *ring, *poly, *prev, *next;
    uint8_t *apart;          /* per fan position: the filter proved a change of plane */
    size_t fan_cap;
    uint32_t *fresh;         /* new triangles of the vertex: 3 ids + face each */
    size_t fresh_count, fresh_cap;
    bool nomem;
} flat_state;

static uint32_t next_side(uint32_t r)
{
    return r - r % 3 + (r % 3 + 1) % 3;
}

static uint32_t prev_side(uint32_t r)
{
    return r - r % 3 + (r % 3 + 2) % 3;
}

/* ---- planes --------------------------------------------------------------------- */

static const mci_plane *plane_of(flat_state *s, uint32_t f)
{
    size_t slot = f % PLANE_CACHE;
    if (s->plane_face[slot] != f) {
        const mci_flat_source *src = s->src;
        mci_plane_init(&s->planes[slot], src->corner(src->user, f, 0),
                       src->corner(src->user, f, 1), src->corner(src->user, f, 2));
        s->plane_face[slot] = f;
    }
    return &s->planes[slot];
}

/* Whether every corner of face g lies in face f's plane. */
static bool coplanar_faces(flat_state *s, uint32_t f, uint32_t g)
{
    const mci_plane *q = plane_of(s, g);
    const double *corners[3] = {q->a, q->b, q->c};
    const mci_plane *p = plane_of(s, f); /* after g's: it may take g's slot */
    for (int k = 0; k < 3; k++)
        if (mci_orient3d_vertex(corners[k], p) != 0)
            return false;
    return true;
}

/* The kept triangles' facing of face f along axis: its normal's sign there, turned
 * where its leaf is complemented. */
static int facing(flat_state *s, uint32_t f, int axis)
{
    int sign = mci_plane_normal_sign(plane_of(s, f), axis);
    return s->src->complemented(s->src->user, f) ? -sign : sign;
}

/* What is known of a pair of faces (memo_of): the filter proved them apart or could
 * not, or the exact test found them in one plane facing one way or not. */
enum { PAIR_APART = 1, PAIR_FLAT = 2, PAIR_UNSURE = 3 };

/* The pair's entry in the memo (a slot by hash, the last pair there kept); *hit when
 * it held this pair. */
static uint8_t *memo_of(flat_state *s, uint32_t f, uint32_t g, bool *hit)
{
    uint64_t key = mci_edge_key(f, g);
    size_t slot = (size_t)((key * UINT64_C(0x9E3779B97F4A7C15)) >> (64 - PAIR_MEMO_BITS));
    *hit = s->pair_key[slot] == key;
    if (!*hit) {
        s->pair_key[slot] = key;
        s->pair_relation[slot] = 0;
    }
    return &s->pair_relation[slot];
}

/* Whether kept triangles of faces f and g lie in one plane facing one way. */
static bool decide_flat(flat_state *s, uint32_t f, uint32_t g)
{
    int sign, axis;
    if (!coplanar_faces(s, f, g))
        return false;
    axis = mci_plane_projection_axis(plane_of(s, f), &sign);
    if (axis < 0)
        return false;
    sign = facing(s, f, axis);
    return sign == facing(s, g, axis);
}

static bool same_flat(flat_state *s, uint32_t f, uint32_t g)
{
    bool hit;
    uint8_t *known;
    if (f == g)
        return true;
    known = memo_of(s, f, g, &hit);
    if (hit && (*known == PAIR_APART || *known == PAIR_FLAT))
        return *known == PAIR_FLAT;
    *known = decide_flat(s, f < g ? f : g, f < g ? g : f) ? PAIR_FLAT : PAIR_APART;
    return *known == PAIR_FLAT;
}

/* ---- fans ----------------------------------------------------------------------- */

/* Vertices with more corners than this have their run sorted by `next`, searched by
 * halves (a fan's centre has as many as its face has triangles). */
enum { SHORT_RUN = 12 };

/* Vertex v's run of corners (v a corner of the grouped triangles). */
static uint32_t first_corner(const flat_state *s, uint32_t v)
{
    return s->start[s->local[v] - 1];
}

static uint32_t end_corner(const flat_state *s, uint32_t v)
{
    return s->start[s->local[v]];
}

static int compare_next(const void *a, const void *b)
{
    uint32_t x = ((const corner *)a)->next, y = ((const corner *)b)->next;
    return (x > y) - (x < y);
}

/* The corners of the live work triangles grouped by vertex (a counting sort). */
static void group_corners(flat_state *s, const uint32_t *work, size_t work_count)
{
    uint32_t n = 0;
    for (uint32_t k = 0; k < s->vertex_count; k++) /* the last grouping's numbers go */
        s->local[s->verts[k]] = 0;
    for (size_t w = 0; w < work_count; w++)
        for (int i = 0; i < 3; i++) {
            uint32_t v = s->tris[3 * (size_t)work[w] + i];
            if (s->local[v] == 0) {
                s->verts[n++] = v;
                s->local[v] = n;
                s->start[n] = 0;
            }
            s->start[s->local[v]]++;
        }
    s->vertex_count = n;
    s->start[0] = 0;
    for (uint32_t k = 0; k < n; k++)
        s->start[k + 1] += s->start[k];
    for (size_t w = 0; w < work_count; w++)
        for (uint32_t i = 0; i < 3; i++) {
            uint32_t r = 3 * work[w] + i;
            s->corners[s->start[s->local[s->tris[r]] - 1]++] =
                (corner){work[w], s->tris[next_side(r)], s->tris[prev_side(r)],
                         s->faces[work[w]]};
        }
    for (uint32_t k = n; k > 0; k--)
        s->start[k] = s->start[k - 1];
    s->start[0] = 0;
}

static bool grow_fan(flat_state *s, size_t n)
{
    size_t cap = s->fan_cap;
    if (n <= cap)
        return true;
    while (cap < n)
        cap = cap ? 2 * cap : 64;
    uint32_t **arrays[] = {&s->fan, &s->ring, &s->poly, &s->prev, &s->next};
    for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++) {
        uint32_t *grown = mci_realloc_array(s->ctx, *arrays[k], cap + 1, sizeof **arrays[k]);
        if (!grown)
            return false;
        *arrays[k] = grown;
    }
    uint8_t *apart = mci_realloc_array(s->ctx, s->apart, cap + 1, 1);
    if (!apart)
        return false;
    s->apart = apart;
    s->fan_cap = cap;
    return true;
}

/* The corner at v of the triangle after corner c's around v, counter-clockwise: c's
 * triangle is (v, x, y), the next one (v, y, z). MCI_NONE unless exactly one. */
static uint32_t turn_around(const flat_state *s, uint32_t v, uint32_t c)
{
    uint32_t target = s->corners[c].prev, found = MCI_NONE, lo = first_corner(s, v),
             hi = end_corner(s, v);
    if (hi - lo > SHORT_RUN) {
        while (lo < hi) { /* the first corner with next >= target */
            uint32_t mid = lo + (hi - lo) / 2;
            if (s->corners[mid].next < target)
                lo = mid + 1;
            else
                hi = mid;
        }
        hi = end_corner(s, v);
        if (lo == hi || s->corners[lo].next != target ||
            (lo + 1 < hi && s->corners[lo + 1].next == target))
            return MCI_NONE;
        return lo;
    }
    for (uint32_t k = lo; k < hi; k++) {
        if (s->corners[k].next == target) {
            if (found != MCI_NONE)
                return MCI_NONE;
            found = k;
        }
    }
    return found;
}

/* v's fan in s->fan (its corners, counter-clockwise around v) and s->ring (the corner
 * after v of each, so that fan triangle k is (v, ring[k], ring[k + 1])). False when v's
 * triangles are not one fan. */
static bool walk_fan(flat_state *s, uint32_t v, size_t *n)
{
    size_t degree = end_corner(s, v) - first_corner(s, v), k = 0;
    uint32_t c = first_corner(s, v);
    if (degree < 3 || !grow_fan(s, degree)) {
        s->nomem = s->nomem || degree >= 3;
        return false;
    }
    if (degree > SHORT_RUN) /* for turn_around's search by halves */
        qsort(s->corners + c, degree, sizeof *s->corners, compare_next);
    do {
        if (k == degree)
            return false;
        s->fan[k] = c;
        s->ring[k++] = s->corners[c].next;
        c = turn_around(s, v, c);
    } while (c != MCI_NONE && c != s->fan[0]);
    *n = k;
    return c == s->fan[0] && k == degree;
}

static uint32_t fan_face(const flat_state *s, size_t k)
{
    return s->corners[s->fan[k]].face;
}

static uint32_t fan_tri(const flat_state *s, size_t k)
{
    return s->corners[s->fan[k]].tri;
}

/* Whether faces f and g are surely not in one plane: the filter alone puts a corner of
 * g off f's plane. */
static bool filter_apart(flat_state *s, uint32_t f, uint32_t g)
{
    const mci_plane *p = plane_of(s, f);
    for (int k = 0; k < 3; k++) {
        const double *x = s->src->corner(s->src->user, g, k);
        int side;
        if (x == p->a || x == p->b || x == p->c)
            continue; /* a shared corner: on the plane */
        side = mci_orient3d_vertex_filtered(x, p);
        if (side == 1 || side == -1)
            return true;
    }
    return false;
}

/* filter_apart on the pair in a fixed order, remembered (neighbouring vertices ask about
 * the same pairs of faces). */
static bool surely_apart(flat_state *s, uint32_t f, uint32_t g)
{
    bool hit;
    uint8_t *known = memo_of(s, f, g, &hit);
    if (hit && *known)
        return *known == PAIR_APART;
    *known = filter_apart(s, f < g ? f : g, f < g ? g : f) ? PAIR_APART : PAIR_UNSURE;
    return *known == PAIR_APART;
}

/* Where, walking v's fan, the plane changes: the positions k whose triangle is not in
 * one plane facing one way with the one before; at most `limit` + 1 are counted. The
 * changes the filter proves come first: a vertex of a curved surface has three of them
 * and needs no exact test. */
static size_t plane_changes(flat_state *s, size_t n, size_t *at, size_t limit)
{
    size_t changes = 0;
    for (size_t k = 0; k < n; k++) {
        uint32_t f = fan_face(s, k), g = fan_face(s, (k + n - 1) % n);
        s->apart[k] = f != g && surely_apart(s, f, g);
        if (s->apart[k]) {
            if (changes == limit)
                return changes + 1;
            at[changes++] = k;
        }
    }
    for (size_t k = 0; k < n; k++) {
        uint32_t f = fan_face(s, k), g = fan_face(s, (k + n - 1) % n);
        if (!s->apart[k] && !same_flat(s, f, g)) {
            if (changes == limit)
                return changes + 1;
            at[changes++] = k;
        }
    }
    return changes;
}

/* Whether v's triangles surely lie in three planes or more: faces f0, f1 and f2 among
 * them that the filter proves pairwise apart (most vertices of curved surfaces), found
 * without walking the fan. */
static bool surely_three_planes(flat_state *s, uint32_t v)
{
    uint32_t f0 = s->corners[first_corner(s, v)].face, f1 = MCI_NONE;
    for (uint32_t k = first_corner(s, v) + 1; k < end_corner(s, v); k++) {
        uint32_t f = s->corners[k].face;
        if (f == f0 || f == f1 || !surely_apart(s, f0, f))
            continue;
        if (f1 == MCI_NONE)
            f1 = f;
        else if (surely_apart(s, f1, f))
            return true;
    }
    return false;
}

/* Whether v is removable (see the file's comment); the fan is left in s->fan. */
static bool removable_vertex(flat_state *s, uint32_t v, size_t *n, size_t at[2])
{
    size_t changes;
    if (surely_three_planes(s, v) || !walk_fan(s, v, n) || *n > MAX_POLYGON)
        return false;
    for (size_t k = 0; k < *n; k++) /* new triangles take the faces of the fan's */
        if (!s->src->own_plane(s->src->user, fan_face(s, k)))
            return false;
    changes = plane_changes(s, *n, at, 2);
    if (changes == 0)
        return true;
    if (changes != 2)
        return false;
    /* two planes: not one plane facing both ways */
    return !coplanar_faces(s, fan_face(s, at[0]), fan_face(s, at[1]));
}

/* ---- holes ---------------------------------------------------------------------- */

typedef struct hole {
    int axis, sign; /* counter-clockwise in the plane: sign * orient2d along axis > 0 */
    uint32_t face;
} hole;

static int turn(const flat_state *s, const hole *h, uint32_t a, uint32_t b, uint32_t c)
{
    const mci_flat_source *src = s->src;
    return h->sign * mci_orient2d_projected(src->point(src->user, a), src->point(src->user, b),
                                            src->point(src->user, c), h->axis);
}

/* Whether point q lies in the closed triangle a, b, c (counter-clockwise). */
static bool in_closed(const flat_state *s, const hole *h, uint32_t a, uint32_t b, uint32_t c,
                      uint32_t q)
{
    return turn(s, h, a, b, q) >= 0 && turn(s, h, b, c, q) >= 0 && turn(s, h, c, a, q) >= 0;
}

static bool add_fresh(flat_state *s, uint32_t a, uint32_t b, uint32_t c, uint32_t face)
{
    if (!mci_grow_array(s->ctx, (void **)&s->fresh, &s->fresh_cap, s->fresh_count + 1,
                        4 * sizeof *s->fresh, 16)) {
        s->nomem = true;
        return false;
    }
    uint32_t *t = s->fresh + 4 * s->fresh_count++;
    t[0] = a, t[1] = b, t[2] = c, t[3] = face;
    return true;
}

/* Whether corner i of the polygon's remaining corners is an ear: strictly convex, and
 * no other corner in its closed triangle. */
static bool is_ear(const flat_state *s, const hole *h, uint32_t i)
{
    const uint32_t *p = s->poly;
    uint32_t a = s->prev[i], c = s->next[i];
    if (turn(s, h, p[a], p[i], p[c]) <= 0)
        return false;
    for (uint32_t q = s->next[c]; q != a; q = s->next[q])
        if (in_closed(s, h, p[a], p[i], p[c], p[q]))
            return false;
    return true;
}

/* Triangulates the polygon s->poly[0 .. m) (counter-clockwise, corners distinct) by
 * clipping ears into s->fresh; false when no ear is left (the hole is then kept). */
static bool clip_ears(flat_state *s, const hole *h, size_t m)
{
    size_t left = m, misses = 0;
    uint32_t i = 0;
    for (uint32_t k = 0; k < m; k++) {
        s->prev[k] = (k + (uint32_t)m - 1) % (uint32_t)m;
        s->next[k] = (k + 1) % (uint32_t)m;
    }
    while (left > 3) {
        if (is_ear(s, h, i)) {
            uint32_t a = s->prev[i], c = s->next[i];
            if (!add_fresh(s, s->poly[a], s->poly[i], s->poly[c], h->face))
                return false;
            s->next[a] = c, s->prev[c] = a;
            left--, misses = 0;
            i = a;
        } else if (++misses > left) {
            return false;
        } else {
            i = s->next[i];
        }
    }
    return turn(s, h, s->poly[s->prev[i]], s->poly[i], s->poly[s->next[i]]) > 0 &&
           add_fresh(s, s->poly[s->prev[i]], s->poly[i], s->poly[s->next[i]], h->face);
}

/* The orientation of the plane of face f as its kept triangles face. */
static bool hole_of_face(flat_state *s, uint32_t f, hole *h)
{
    h->face = f;
    h->axis = mci_plane_projection_axis(plane_of(s, f), &h->sign);
    if (h->axis < 0)
        return false;
    h->sign = facing(s, f, h->axis);
    return true;
}

/* The hole of fan positions [from, from + len) (cyclically, len < n means one side of a
 * vertex on a straight edge): its ring corners, with the closing corner after the last
 * triangle, triangulated. The hole's face is the smallest of its triangles'. */
static bool fill_side(flat_state *s, size_t n, size_t from, size_t len)
{
    hole h;
    uint32_t face = MCI_NONE;
    size_t m = 0;
    for (size_t k = 0; k < len; k++) {
        uint32_t f = fan_face(s, (from + k) % n);
        face = f < face ? f : face;
        s->poly[m++] = s->ring[(from + k) % n];
    }
    if (len < n) /* the far corner of the side's last triangle closes the segment */
        s->poly[m++] = s->ring[(from + len) % n];
    return hole_of_face(s, face, &h) && clip_ears(s, &h, m);
}

/* Whether fan position k lies on the side that starts at at[0]. */
static bool first_side(size_t k, const size_t at[2], size_t n)
{
    return (k + n - at[0]) % n < (at[1] + n - at[0]) % n;
}

/* The fan joined onto its ring corner j (an edge collapse): triangle k becomes
 * (ring[j], ring[k], ring[k + 1]), keeping its face, and the two at ring[j] go. Valid
 * when every one turns counter-clockwise in its plane: then, the hole being a simple
 * polygon, they tile it once (their signed areas count the winding number of its
 * boundary, one inside and none outside). The cheap case: a fan whose hole is convex
 * (or star-shaped from a corner) needs no search for ears. */
static bool collapse_onto(flat_state *s, size_t n, size_t j, const hole side[2],
                          const size_t at[2], size_t changes)
{
    uint32_t u = s->ring[j];
    s->fresh_count = 0;
    for (size_t k = 0; k < n; k++) {
        const hole *h = &side[changes == 0 || first_side(k, at, n) ? 0 : 1];
        uint32_t x = s->ring[k], y = s->ring[(k + 1) % n];
        if (k == j || (k + 1) % n == j)
            continue;
        if (turn(s, h, u, x, y) <= 0 || !add_fresh(s, u, x, y, fan_face(s, k)))
            return false;
    }
    return true;
}

enum { COLLAPSE_TRIES = 4 };

/* The triangles that fill v's hole, in s->fresh: a collapse onto a ring corner where one
 * is valid (onto an end of the straight edge for a vertex inside one), else ears. */
static bool fill_hole(flat_state *s, size_t n, const size_t at[2], size_t changes)
{
    bool filled = false;
    hole side[2];
    if (!hole_of_face(s, fan_face(s, changes ? at[0] : 0), &side[0]) ||
        (changes && !hole_of_face(s, fan_face(s, at[1]), &side[1])))
        return false;
    if (changes)
        filled = collapse_onto(s, n, at[0], side, at, changes) ||
                 collapse_onto(s, n, at[1], side, at, changes);
    for (size_t j = 0; !changes && !filled && j < n && j < COLLAPSE_TRIES; j++)
        filled = collapse_onto(s, n, j, side, at, changes);
    if (!filled && !s->nomem) {
        s->fresh_count = 0;
        filled = changes == 0 ? fill_side(s, n, 0, n)
                              : fill_side(s, n, at[0], (at[1] + n - at[0]) % n) &&
                                    fill_side(s, n, at[1], (at[0] + n - at[1]) % n);
    }
    return filled;
}

/* Room for n triangles in every per-triangle array. */
static bool reserve(flat_state *s, size_t n)
{
    size_t cap = s->cap;
    if (n <= cap)
        return true;
    while (cap < n)
        cap = 2 * cap + 64;
    uint32_t *tris = mci_realloc_array(s->ctx, s->tris, cap, 3 * sizeof *tris);
    if (tris)
        s->tris = tris;
    uint32_t *faces = mci_realloc_array(s->ctx, s->faces, cap, sizeof *faces);
    if (faces)
        s->faces = faces;
    uint8_t *dead = mci_realloc_array(s->ctx, s->dead, cap, 1);
    if (dead)
        s->dead = dead;
    uint8_t *taken = mci_realloc_array(s->ctx, s->taken, cap, 1);
    if (taken)
        s->taken = taken;
    if (!tris || !faces || !dead || !taken) {
        s->nomem = true;
        return false;
    }
    s->cap = cap;
    return true;
}

/* Replaces v's fan (in s->fan, its plane changes at `at`) by the triangulation of its
 * hole; false when the hole has none that fits (v is then kept). */
static bool remove_vertex(flat_state *s, size_t n, const size_t at[2], size_t changes)
{
    if (!fill_hole(s, n, at, changes) || !reserve(s, s->count + s->fresh_count))
        return false;
    for (size_t k = 0; k < n; k++) {
        uint32_t t = fan_tri(s, k);
        s->dead[t] = s->taken[t] = 1;
    }
    for (size_t k = 0; k < s->fresh_count; k++) {
        const uint32_t *f = s->fresh + 4 * k;
        size_t t = s->count++;
        memcpy(s->tris + 3 * t, f, 3 * sizeof *f);
        s->faces[t] = f[3];
        s->dead[t] = 0, s->taken[t] = 1;
    }
    return true;
}

/* Whether triangle t of tris has a corner whose flag is `value`. */
static bool corner_flagged(const uint32_t *tris, size_t t, const uint8_t *flag, uint8_t value)
{
    return flag[tris[3 * t]] == value || flag[tris[3 * t + 1]] == value ||
           flag[tris[3 * t + 2]] == value;
}

static bool has_removable_corner(const flat_state *s, size_t t)
{
    return !s->dead[t] && corner_flagged(s->tris, t, s->removable, 1);
}

/* How many triangles find_work lists. */
static size_t count_work(const flat_state *s, const uint32_t *work, size_t count,
                         size_t since)
{
    size_t n = 0;
    for (size_t w = 0; w < count; w++)
        n += has_removable_corner(s, work[w]);
    for (size_t t = since; t < s->count; t++)
        n += has_removable_corner(s, (uint32_t)t);
    return n;
}

/* The live triangles with a corner still to be removed: those of the last work list
 * (*count of them) that still are, then the triangles added since `since` that are
 * (work has room for count_work's number). */
static void find_work(const flat_state *s, uint32_t *work, size_t *count, size_t since)
{
    size_t n = 0;
    for (size_t w = 0; w < *count; w++)
        if (has_removable_corner(s, work[w]))
            work[n++] = work[w];
    for (size_t t = since; t < s->count; t++)
        if (has_removable_corner(s, t))
            work[n++] = (uint32_t)t;
    *count = n;
}

/* One round: every vertex still to be removed whose fan no removal of this round touched
 * is removed (or given up); returns how many were removed. */
static size_t removal_round(flat_state *s, const uint32_t *work, size_t work_count,
                            bool grouped)
{
    size_t removed = 0;
    if (!grouped)
        group_corners(s, work, work_count);
    for (size_t w = 0; w < work_count; w++)
        s->taken[work[w]] = 0;
    size_t pending = 0;
    /* in order of id, which spreads a round's removals (in the triangles' order, one
     * vertex's removal touched the next one's fan far more often) */
    for (uint32_t i = 0; i < s->vertex_count; i++)
        if (s->removable[s->verts[i]])
            s->pending[pending++] = s->verts[i];
    mci_sort_u32(s->pending, pending);
    for (size_t i = 0; i < pending && !s->nomem; i++) {
        uint32_t v = s->pending[i];
        size_t n, at[2], changes;
        bool touched = false;
        if (!walk_fan(s, v, &n)) {
            s->removable[v] = 0;
            continue;
        }
        for (size_t k = 0; k < n; k++)
            touched = touched || s->taken[fan_tri(s, k)];
        if (touched)
            continue; /* next round, with its new fan */
        changes = plane_changes(s, n, at, 2);
        removed += remove_vertex(s, n, at, changes);
        s->removable[v] = 0;
    }
    return removed;
}

/* Per vertex id, what one pass over the triangles tells of its faces: up to two that
 * the filter proves apart, or that it has three (REJECTED). */
enum { UNSEEN = 0, CANDIDATE = 1, REJECTED = 2 };

typedef struct vertex_faces {
    uint32_t f0, f1;
} vertex_faces;

static void see_face(flat_state *s, vertex_faces *vf, uint8_t *state, uint32_t f)
{
    if (*state == UNSEEN) {
        *state = CANDIDATE;
        vf->f0 = f, vf->f1 = MCI_NONE;
    } else if (*state == CANDIDATE && f != vf->f0 && f != vf->f1 &&
               surely_apart(s, vf->f0, f)) {
        if (vf->f1 == MCI_NONE)
            vf->f1 = f;
        else if (surely_apart(s, vf->f1, f))
            *state = REJECTED;
    }
}

/* The vertices that may be removable, marked CANDIDATE in state (per id): corners of
 * touched faces whose faces the filter does not already prove to lie in three planes
 * (as at nearly every vertex of a curved surface). Two passes over the triangles: the
 * touched faces', then the others' at the vertices the first one saw. */
static bool find_candidates(flat_state *s, const mci_kept *kept, uint8_t *state)
{
    const mci_flat_source *src = s->src;
    vertex_faces *vf = mci_malloc_array(s->ctx, src->id_count + 1, sizeof *vf);
    if (!vf)
        return false;
    for (int pass = 0; pass < 2; pass++)
        for (size_t t = 0; t < kept->count; t++) {
            uint32_t f = kept->faces[t];
            if (src->touched(src->user, f) != (pass == 0))
                continue;
            for (int i = 0; i < 3; i++) {
                uint32_t v = kept->tris[3 * t + i];
                if (pass == 0 || state[v] == CANDIDATE)
                    see_face(s, &vf[v], &state[v], f);
            }
        }
    mci_free(s->ctx, vf);
    return true;
}

/* Copies the kept triangles with a candidate corner (state) into the flat state (their
 * index in kept in s->origin); returns false when out of memory. */
static bool take_work(flat_state *s, const mci_kept *kept, const uint8_t *state)
{
    size_t n = 0;
    for (size_t t = 0; t < kept->count; t++)
        n += corner_flagged(kept->tris, t, state, CANDIDATE);
    /* room for the new triangles too: pages not written cost nothing, a copy does */
    if (!reserve(s, 2 * n) || !(s->origin = mci_malloc_array(s->ctx, n + 1, sizeof *s->origin)))
        return false;
    for (size_t t = 0; t < kept->count; t++)
        if (corner_flagged(kept->tris, t, state, CANDIDATE)) {
            for (int i = 0; i < 3; i++)
                s->tris[3 * s->count + i] = kept->tris[3 * t + i];
            s->faces[s->count] = kept->faces[t];
            s->dead[s->count] = s->taken[s->count] = 0;
            s->origin[s->count++] = (uint32_t)t;
        }
    s->origin_count = s->count;
    return true;
}

/* Marks the removable vertices among the candidates (every triangle at a candidate is in
 * the state); returns how many. */
static size_t mark_removable(flat_state *s, const uint8_t *state, uint32_t *work)
{
    size_t found = 0;
    for (size_t t = 0; t < s->count; t++)
        work[t] = (uint32_t)t;
    group_corners(s, work, s->count);
    for (uint32_t k = 0; k < s->vertex_count && !s->nomem; k++) {
        uint32_t v = s->verts[k];
        size_t n, at[2];
        if (state[v] == CANDIDATE && removable_vertex(s, v, &n, at)) {
            s->removable[v] = 1;
            found++;
        }
    }
    return found;
}

static void free_state(flat_state *s)
{
    const mci_ctx *ctx = s->ctx;
    void *arrays[] = {s->tris, s->faces, s->dead, s->taken, s->origin, s->removable,
                      s->local, s->verts, s->pending, s->start, s->corners, s->fan, s->ring,
                      s->poly, s->prev, s->next, s->apart, s->fresh};
    for (size_t k = 0; k < sizeof arrays / sizeof *arrays; k++)
        mci_free(ctx, arrays[k]);
}

/* kept without the removed triangles (in order), then the new ones that live (never
 * more than kept had). */
static bool write_back(const flat_state *s, mci_kept *kept)
{
    size_t n = 0;
    uint8_t *gone = mci_calloc_array(s->ctx, kept->count + 1, 1);
    if (!gone)
        return false;
    for (size_t t = 0; t < s->origin_count; t++)
        gone[s->origin[t]] = s->dead[t];
    for (size_t t = 0; t < kept->count; t++)
        if (!gone[t]) {
            for (int i = 0; i < 3; i++)
                kept->tris[3 * n + i] = kept->tris[3 * t + i];
            kept->faces[n++] = kept->faces[t];
        }
    for (size_t t = s->origin_count; t < s->count; t++)
        if (!s->dead[t]) {
            for (int i = 0; i < 3; i++)
                kept->tris[3 * n + i] = s->tris[3 * t + i];
            kept->faces[n++] = s->faces[t];
        }
    kept->count = n;
    mci_free(s->ctx, gone);
    return true;
}

/* Room in the work list and the grouping for `need` triangles. The live triangles at
 * vertices still to go never grow in number (a hole of n corners takes n - 2 for n), so
 * the first size, every copied triangle, almost always lasts: growing copies. */
static bool size_grouping(flat_state *s, uint32_t **work, size_t need)
{
    size_t n = need + 1;
    if (n <= s->group_cap)
        return true;
    n = n > s->group_cap + s->group_cap / 2 ? n : s->group_cap + s->group_cap / 2;
    uint32_t *grown_work = mci_realloc_array(s->ctx, *work, n, sizeof **work);
    corner *grown_corners = mci_realloc_array(s->ctx, s->corners, 3 * n, sizeof *s->corners);
    uint32_t *grown_verts = mci_realloc_array(s->ctx, s->verts, 3 * n, sizeof *s->verts);
    uint32_t *grown_pending = mci_realloc_array(s->ctx, s->pending, 3 * n, sizeof *s->pending);
    uint32_t *grown_start = mci_realloc_array(s->ctx, s->start, 3 * n + 1, sizeof *s->start);
    if (grown_work)
        *work = grown_work;
    if (grown_corners)
        s->corners = grown_corners;
    if (grown_verts)
        s->verts = grown_verts;
    if (grown_pending)
        s->pending = grown_pending;
    if (grown_start)
        s->start = grown_start;
    if (!grown_work || !grown_corners || !grown_verts || !grown_pending || !grown_start)
        return false;
    s->group_cap = n;
    return true;
}

/* Sides counted by undirected edge, in a table sized for the new triangles' edges. */
typedef struct side_table {
    uint64_t *key;
    uint8_t *count; /* stops at 3: more than two is all that matters */
    size_t mask;
} side_table;

static uint8_t *side_slot(side_table *h, uint64_t key, bool add)
{
    size_t i = (size_t)((key * UINT64_C(0x9E3779B97F4A7C15)) >> 20) & h->mask;
    while (h->key[i] != key) {
        if (h->key[i] == UINT64_MAX) {
            if (!add)
                return NULL;
            h->key[i] = key;
            break;
        }
        i = (i + 1) & h->mask;
    }
    return &h->count[i];
}

static void count_side(uint8_t *count)
{
    *count += *count < 3;
}

static bool counts_ok(const side_table *h)
{
    for (size_t i = 0; i <= h->mask; i++)
        if (h->count[i] > 2)
            return false;
    return true;
}

/* Whether an edge of the new triangles has more than two triangles: a diagonal that
 * was already an edge elsewhere, where another part of the result touches the flat
 * region along it. `near` has room for every vertex id. */
static bool new_edges_shared(const flat_state *s, const mci_kept *kept, uint8_t *near,
                             bool *shared)
{
    size_t fresh = 0, size = 64;
    side_table h = {NULL, NULL, 0};
    for (size_t t = s->origin_count; t < s->count; t++)
        fresh += !s->dead[t];
    while (size < 4 * fresh) /* fewer than 3 * fresh edges: never more than 3/4 full */
        size *= 2;
    h.mask = size - 1;
    h.key = mci_malloc_array(s->ctx, size, sizeof *h.key);
    h.count = mci_calloc_array(s->ctx, size, sizeof *h.count);
    if (!h.key || !h.count) {
        mci_free(s->ctx, h.key);
        mci_free(s->ctx, h.count);
        return false;
    }
    memset(h.key, 0xff, size * sizeof *h.key);
    memset(near, 0, s->src->id_count + 1);
    for (size_t t = s->origin_count; t < s->count; t++)
        for (int i = 0; i < 3 && !s->dead[t]; i++) {
            near[s->tris[3 * t + i]] = 1;
            count_side(side_slot(&h, mci_edge_key(s->tris[3 * t + i],
                                                  s->tris[3 * t + (i + 1) % 3]), true));
        }
    /* the old triangles that stay: those not copied, and the copies not removed */
    for (size_t t = 0, o = 0; t < kept->count; t++) {
        const uint32_t *c = kept->tris + 3 * t;
        bool copied = o < s->origin_count && s->origin[o] == t;
        o += copied;
        if ((copied && s->dead[o - 1]) || near[c[0]] + near[c[1]] + near[c[2]] < 2)
            continue;
        for (int i = 0; i < 3; i++) {
            uint8_t *n = near[c[i]] && near[c[(i + 1) % 3]]
                             ? side_slot(&h, mci_edge_key(c[i], c[(i + 1) % 3]), false)
                             : NULL;
            if (n)
                count_side(n);
        }
    }
    *shared = !counts_ok(&h);
    mci_free(s->ctx, h.key);
    mci_free(s->ctx, h.count);
    return true;
}

/* The removal's rounds, once the removable vertices are marked (work lists the
 * triangles at them, count of them). */
static void remove_marked(flat_state *s, uint32_t **work, size_t count, mci_flat_stats *stats)
{
    size_t since = s->count;
    while (!s->nomem && count > 0) {
        stats->rounds++;
        /* the first round walks the fans as the marking grouped them */
        stats->removed += removal_round(s, *work, count, stats->rounds == 1);
        if (!size_grouping(s, work, count_work(s, *work, count, since))) {
            s->nomem = true;
            return;
        }
        find_work(s, *work, &count, since);
        since = s->count;
    }
}

mcsg_status mci_remove_flat_vertices(const mci_ctx *ctx, mci_kept *kept,
                                     const mci_flat_source *src, mci_flat_stats *stats,
                                     mcsg_error *err)
{
    flat_state *s = mci_calloc_array(ctx, 1, sizeof *s);
    size_t ids = src->id_count;
    uint8_t *state = mci_calloc_array(ctx, ids + 1, 1);
    uint32_t *work = NULL;
    mcsg_status st;
    memset(stats, 0, sizeof *stats);
    if (!s || !state) {
        mci_free(ctx, s);
        mci_free(ctx, state);
        return mci_fail_nomem(err, "removing flat vertices");
    }
    s->ctx = ctx, s->src = src;
    for (size_t k = 0; k < PLANE_CACHE; k++)
        s->plane_face[k] = MCI_NONE;
    memset(s->pair_key, 0xff, sizeof s->pair_key);
    s->nomem = !find_candidates(s, kept, state);
    s->nomem = s->nomem || !take_work(s, kept, state);
    if (!s->nomem && s->count > 0) {
        s->removable = mci_calloc_array(ctx, ids + 1, 1);
        s->local = mci_calloc_array(ctx, ids + 1, sizeof *s->local);
        s->nomem = !s->removable || !s->local || !size_grouping(s, &work, s->count);
    }
    if (!s->nomem && s->count > 0)
        stats->removable = mark_removable(s, state, work);
    if (!s->nomem && stats->removable > 0) {
        size_t count = 0;
        find_work(s, work, &count, 0);
        remove_marked(s, &work, count, stats);
    }
    if (!s->nomem && stats->removed > 0) {
        bool shared = false;
        s->nomem = !new_edges_shared(s, kept, state, &shared);
        if (shared) /* kept whole rather than touching along a new edge */
            stats->removed = 0, stats->gave_up = true;
    }
    if (!s->nomem && stats->removed > 0)
        s->nomem = !write_back(s, kept);

    st = s->nomem ? mci_fail_nomem(err, "removing flat vertices") : MCSG_OK;
    mci_free(ctx, work);
    mci_free(ctx, state);
    free_state(s);
    mci_free(ctx, s);
    return st;
}
