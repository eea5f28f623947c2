/*
 * Zero-area triangles of a leaf, removed (docs/robustness.md, the input contract). Seen
 * from any point off it, a triangle of zero area spans no solid angle, so it changes no
 * winding number: the leaf without it is the same solid. Only its edges matter, for the
 * surface to stay closed as a chain:
 *   - two corners at the same coordinates: its other two edges are one edge used both
 *     ways, so it goes alone;
 *   - three distinct collinear corners u, b, v (b between): it goes together with a
 *     split at b of a triangle holding its long edge the other way, (v, u, x) becoming
 *     (v, b, x) and (b, u, x); the halves use v -> b and b -> u, which the removed
 *     triangle used the other way, and share b - x both ways. Halves may be split again.
 * Triangles whose long edge only zero-area triangles hold the other way (two of them
 * back to back with different middle corners) go together, after every other triangle
 * with an edge through a corner of theirs is split there (refine_at_pending_corners):
 * on the refined edges the removed triangles' boundaries cancel, so the rest is closed.
 * Every decision is exact: corners are input doubles, and "between" is a comparison of
 * coordinates along an axis where they differ.
 */
#include "mesh/zero_area.h"
#include "base/sort_template.h"
#include "exact/predicates.h"

#include <string.h>

enum { LIVE, PENDING, REMOVED };

typedef struct edge_slot {
    uint64_t key; /* (from << 32 | to) of canonical vertices */
    uint32_t tri; /* MCI_NONE: empty */
} edge_slot;

typedef struct zero_state {
    const mcsg_mesh *m;
    uint32_t *canon;   /* per vertex: the lowest vertex with its coordinates */
    uint32_t *tris;    /* 3 per triangle: m's, then the second halves of splits */
    uint32_t *face_of; /* per triangle: m's triangle it is (part of) */
    uint8_t *state;    /* per triangle: LIVE, PENDING (zero area, to go) or REMOVED */
    size_t count;
    size_t cap[3];     /* capacities of tris (in uint32_t), face_of and state */
    edge_slot *table;  /* directed edges of triangles not of zero area (entries may be
                          stale after a split: checked on lookup) */
    size_t mask;
} zero_state;

static const double *corner(const zero_state *s, size_t t, int k)
{
    return s->m->vertices + 3 * (size_t)s->tris[3 * t + (size_t)k];
}

/* canon: the lowest vertex with the same coordinates (-0 and 0 alike, as vertices are
 * identified). */
static bool identify_vertices(const mci_ctx *ctx, zero_state *s)
{
    return mci_first_equal_coordinates(ctx, s->m->vertices, s->m->vertex_count, s->canon);
}

static uint64_t edge_key(const zero_state *s, uint32_t from, uint32_t to)
{
    return (uint64_t)s->canon[from] << 32 | s->canon[to];
}

static size_t slot_of(const zero_state *s, uint64_t key)
{
    uint64_t h = key * 0x9e3779b97f4a7c15u;
    return (size_t)(h ^ h >> 29) & s->mask;
}

static void insert_edge(zero_state *s, uint32_t from, uint32_t to, uint32_t tri)
{
    uint64_t key = edge_key(s, from, to);
    size_t i = slot_of(s, key);
    while (s->table[i].tri != MCI_NONE)
        i = (i + 1) & s->mask;
    s->table[i] = (edge_slot){key, tri};
}

/* Which corner of live triangle t starts the directed edge from -> to (canonical), or -1. */
static int edge_at(const zero_state *s, size_t t, uint64_t key)
{
    if (s->state[t] != LIVE)
        return -1;
    for (int i = 0; i < 3; i++)
        if (edge_key(s, s->tris[3 * t + (size_t)i], s->tris[3 * t + (size_t)(i + 1) % 3]) == key)
            return i;
    return -1;
}

/* A live triangle holding the directed edge from -> to, and where (*at), or MCI_NONE. */
static uint32_t find_holder(const zero_state *s, uint32_t from, uint32_t to, int *at)
{
    uint64_t key = edge_key(s, from, to);
    for (size_t i = slot_of(s, key); s->table[i].tri != MCI_NONE; i = (i + 1) & s->mask)
        if (s->table[i].key == key && (*at = edge_at(s, s->table[i].tri, key)) >= 0)
            return s->table[i].tri;
    return MCI_NONE;
}

/* The corner of a zero-area triangle with three distinct corners that lies between the
 * other two: along an axis where the corners differ they are all distinct (collinear). */
static int middle_corner(const zero_state *s, size_t t)
{
    const double *p[3] = {corner(s, t, 0), corner(s, t, 1), corner(s, t, 2)};
    int k = 0;
    while (k < 2 && p[0][k] == p[1][k] && p[1][k] == p[2][k])
        k++;
    for (int i = 0; i < 3; i++) {
        double a = p[(i + 1) % 3][k], x = p[i][k], b = p[(i + 2) % 3][k];
        if ((a < x && x < b) || (b < x && x < a))
            return i;
    }
    return -1; /* not reached for collinear distinct corners */
}

static bool repeated_corner(const zero_state *s, size_t t)
{
    const uint32_t *v = s->tris + 3 * t;
    return s->canon[v[0]] == s->canon[v[1]] || s->canon[v[1]] == s->canon[v[2]] ||
           s->canon[v[2]] == s->canon[v[0]];
}

/* Removes pending triangle t (corners b, u, v from its middle one) by splitting a live
 * triangle holding v -> u at b; false when there is none. */
static bool remove_collinear(zero_state *s, size_t t)
{
    int mid = middle_corner(s, t), at;
    uint32_t b, u, v, f, x, n = (uint32_t)s->count;
    uint32_t *ft;
    if (mid < 0)
        return false;
    b = s->tris[3 * t + (size_t)mid];
    u = s->tris[3 * t + (size_t)(mid + 1) % 3];
    v = s->tris[3 * t + (size_t)(mid + 2) % 3];
    if ((f = find_holder(s, v, u, &at)) == MCI_NONE)
        return false;
    ft = s->tris + 3 * (size_t)f;
    v = ft[at], u = ft[(at + 1) % 3], x = ft[(at + 2) % 3];
    ft[(at + 1) % 3] = b; /* f: (v, b, x) */
    s->tris[3 * (size_t)n] = b, s->tris[3 * (size_t)n + 1] = u, s->tris[3 * (size_t)n + 2] = x;
    s->face_of[n] = s->face_of[f];
    s->state[n] = LIVE;
    s->count++;
    s->state[t] = REMOVED;
    insert_edge(s, v, b, f);
    insert_edge(s, b, x, f);
    insert_edge(s, b, u, n);
    insert_edge(s, u, x, n);
    insert_edge(s, x, b, n);
    return true;
}

/* Marks the zero-area triangles (removing those with a repeated corner); returns how
 * many have three distinct corners. */
static size_t mark_zero_area(zero_state *s, mci_zero_area *res)
{
    size_t collinear = 0;
    for (size_t t = 0; t < s->count; t++) {
        s->face_of[t] = (uint32_t)t;
        s->state[t] = LIVE;
        if (!mci_triangle_is_degenerate(corner(s, t, 0), corner(s, t, 1), corner(s, t, 2)))
            continue;
        s->state[t] = repeated_corner(s, t) ? REMOVED : PENDING;
        res->removed += s->state[t] == REMOVED;
        collinear += s->state[t] == PENDING;
    }
    return collinear;
}

static bool build_table(const mci_ctx *ctx, zero_state *s, size_t collinear)
{
    size_t entries = 3 * s->count + 5 * collinear, size = 16;
    while (size < 2 * entries)
        size *= 2;
    if (!(s->table = mci_malloc_array(ctx, size, sizeof *s->table)))
        return false;
    s->mask = size - 1;
    for (size_t i = 0; i < size; i++)
        s->table[i].tri = MCI_NONE;
    for (size_t t = 0; t < s->count; t++)
        for (int i = 0; s->state[t] == LIVE && i < 3; i++)
            insert_edge(s, s->tris[3 * t + (size_t)i], s->tris[3 * t + (size_t)(i + 1) % 3],
                        (uint32_t)t);
    return true;
}

/* Passes over the pending triangles until one removes none (a split may give the edge
 * another one needs); returns how many are left. */
static size_t remove_all_collinear(zero_state *s, size_t collinear, mci_zero_area *res)
{
    size_t first = s->count;
    bool progress = true;
    while (progress && collinear > 0) {
        progress = false;
        for (size_t t = 0; t < first; t++)
            if (s->state[t] == PENDING && remove_collinear(s, t)) {
                res->removed++;
                res->split++;
                collinear--;
                progress = true;
            }
    }
    return collinear;
}

/* Room for `need` triangles. */
static bool reserve(const mci_ctx *ctx, zero_state *s, size_t need)
{
    return mci_grow_array(ctx, (void **)&s->tris, &s->cap[0], 3 * need, sizeof *s->tris, 16) &&
           mci_grow_array(ctx, (void **)&s->face_of, &s->cap[1], need, sizeof *s->face_of, 16) &&
           mci_grow_array(ctx, (void **)&s->state, &s->cap[2], need, 1, 16);
}

typedef struct x_vertex {
    double x;
    uint32_t v;
} x_vertex;

#define X_LESS(a, b) ((a)->x < (b)->x || ((a)->x == (b)->x && (a)->v < (b)->v))
MCI_DEFINE_SORT(sort_x_vertices, x_vertex, X_LESS)

/* The pending triangles' corners (canonical, each once), by x; *n of them. */
static x_vertex *pending_corners(const mci_ctx *ctx, const zero_state *s, size_t *n)
{
    size_t k = 0;
    x_vertex *z = mci_malloc_array(ctx, 3 * s->count + 1, sizeof *z);
    for (size_t t = 0; z && t < s->count; t++)
        for (int i = 0; s->state[t] == PENDING && i < 3; i++) {
            uint32_t v = s->canon[s->tris[3 * t + (size_t)i]];
            z[k++] = (x_vertex){s->m->vertices[3 * (size_t)v], v};
        }
    if (z)
        sort_x_vertices(z, k);
    for (size_t i = 0; z && i < k; i++)
        if (*n == 0 || z[*n - 1].v != z[i].v)
            z[(*n)++] = z[i];
    return z;
}

/* The axis along which p and q differ first. */
static int differing_axis(const double *p, const double *q)
{
    return p[0] != q[0] ? 0 : p[1] != q[1] ? 1 : 2;
}

/* The corners in z[0 .. nz) strictly inside segment p q, in order from p: *k of them,
 * into at[]. Collinear and strictly between along an axis where p and q differ. */
static void corners_inside(const zero_state *s, const x_vertex *z, size_t nz, uint32_t p,
                           uint32_t q, uint32_t *at, size_t *k)
{
    const double *a = s->m->vertices + 3 * (size_t)p, *b = s->m->vertices + 3 * (size_t)q;
    double lo = a[0] < b[0] ? a[0] : b[0], hi = a[0] < b[0] ? b[0] : a[0];
    int axis = differing_axis(a, b), dir = a[axis] < b[axis] ? 1 : -1;
    size_t first = 0, last = nz;
    *k = 0;
    while (first < last) { /* the first corner with x >= lo */
        size_t mid = first + (last - first) / 2;
        if (z[mid].x < lo)
            first = mid + 1;
        else
            last = mid;
    }
    for (size_t i = first; i < nz && z[i].x <= hi; i++) {
        const double *c = s->m->vertices + 3 * (size_t)z[i].v;
        size_t j;
        if (!(dir * (c[axis] - a[axis]) > 0 && dir * (b[axis] - c[axis]) > 0) ||
            !mci_triangle_is_degenerate(a, b, c))
            continue;
        for (j = *k; j > 0 && dir * (s->m->vertices[3 * (size_t)at[j - 1] + axis] - c[axis]) > 0;
             j--)
            at[j] = at[j - 1];
        at[j] = z[i].v;
        ++*k;
    }
}

/* Splits live triangle t across its edge from corner i at the k points at[]: t keeps
 * (p, at[0], x), and (at[j], at[j + 1], x) ... (at[k - 1], q, x) are added. */
static void split_edge(zero_state *s, size_t t, int i, const uint32_t *at, size_t k)
{
    uint32_t q = s->tris[3 * t + (size_t)(i + 1) % 3], x = s->tris[3 * t + (size_t)(i + 2) % 3];
    s->tris[3 * t + (size_t)(i + 1) % 3] = at[0];
    for (size_t j = 0; j < k; j++) {
        uint32_t *n = s->tris + 3 * s->count;
        n[0] = at[j], n[1] = j + 1 < k ? at[j + 1] : q, n[2] = x;
        s->face_of[s->count] = s->face_of[t];
        s->state[s->count++] = LIVE;
    }
}

/* The pending triangles that no single split removes go all at once: every live
 * triangle's edge through a corner of theirs is split there (also the halves' new
 * edges), so that the edges on their lines are refined at the same points; there the
 * boundary of each pending triangle (its two short edges one way, the long one back)
 * cancels, and the rest of the leaf, closed with them, is closed without them. */
static bool refine_at_pending_corners(const mci_ctx *ctx, zero_state *s, mci_zero_area *res)
{
    size_t nz = 0, k;
    x_vertex *z = pending_corners(ctx, s, &nz);
    uint32_t *at = mci_malloc_array(ctx, nz + 1, sizeof *at);
    bool ok = z && at;
    for (size_t t = 0; ok && t < s->count; t++)
        for (int i = 0; ok && s->state[t] == LIVE && i < 3; i++) {
            const uint32_t *c = s->tris + 3 * t;
            corners_inside(s, z, nz, c[i], c[(i + 1) % 3], at, &k);
            if (k == 0 || !(ok = reserve(ctx, s, s->count + k)))
                continue;
            split_edge(s, t, i, at, k);
            res->split += k;
            i = -1; /* the new edge from at[0] may hold corners too */
        }
    for (size_t t = 0; ok && t < s->count; t++)
        if (s->state[t] == PENDING) {
            s->state[t] = REMOVED;
            res->removed++;
        }
    mci_free(ctx, z);
    mci_free(ctx, at);
    return ok;
}

/* The live triangles, in order, as a mesh with m's vertices. */
static bool build_copy(const mci_ctx *ctx, const zero_state *s, mcsg_mesh *out,
                       uint32_t **face_of)
{
    size_t live = 0, k = 0;
    mcsg_error err;
    for (size_t t = 0; t < s->count; t++)
        live += s->state[t] == LIVE;
    if (mci_mesh_alloc(ctx, out, s->m->vertex_count, live, &err) != MCSG_OK)
        return false;
    if (!(*face_of = mci_malloc_array(ctx, live + 1, sizeof **face_of))) {
        mci_mesh_free(ctx, out);
        return false;
    }
    if (s->m->vertex_count > 0)
        memcpy(out->vertices, s->m->vertices, 3 * s->m->vertex_count * sizeof *out->vertices);
    for (size_t t = 0; t < s->count; t++) {
        if (s->state[t] != LIVE)
            continue;
        memcpy(out->triangles + 3 * k, s->tris + 3 * t, 3 * sizeof *out->triangles);
        (*face_of)[k++] = s->face_of[t];
    }
    return true;
}

static void free_state(const mci_ctx *ctx, zero_state *s)
{
    mci_free(ctx, s->canon);
    mci_free(ctx, s->tris);
    mci_free(ctx, s->face_of);
    mci_free(ctx, s->state);
    mci_free(ctx, s->table);
}

bool mci_remove_zero_area(const mci_ctx *ctx, const mcsg_mesh *m, mcsg_mesh *out,
                          uint32_t **face_of, mci_zero_area *res)
{
    size_t n = m->triangle_count, cap = 2 * n + 1; /* a single split adds one triangle */
    zero_state s = {m, NULL, NULL, NULL, NULL, n, {3 * cap, cap, cap}, NULL, 0};
    size_t collinear, left = 0;
    bool ok;
    memset(res, 0, sizeof *res);
    memset(out, 0, sizeof *out);
    *face_of = NULL;
    s.canon = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *s.canon);
    s.tris = mci_malloc_array(ctx, 3 * cap, sizeof *s.tris);
    s.face_of = mci_malloc_array(ctx, cap, sizeof *s.face_of);
    s.state = mci_malloc_array(ctx, cap, 1);
    ok = s.canon && s.tris && s.face_of && s.state && identify_vertices(ctx, &s);
    if (ok && n > 0)
        memcpy(s.tris, m->triangles, 3 * n * sizeof *s.tris);
    collinear = ok ? mark_zero_area(&s, res) : 0;
    if (ok && collinear > 0 && (ok = build_table(ctx, &s, collinear)))
        left = remove_all_collinear(&s, collinear, res);
    if (ok && left > 0)
        ok = refine_at_pending_corners(ctx, &s, res);
    if (ok)
        ok = build_copy(ctx, &s, out, face_of);
    free_state(ctx, &s);
    return ok;
}
