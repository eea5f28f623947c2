/*
 * Where parts of a result touch along an edge or at a point (two boxes sharing only an
 * edge, a cone tip on a face), the exact result is not a manifold: an edge has four (or
 * more) triangles, or a vertex has two umbrellas. The output is made edge- and
 * vertex-manifold by giving each umbrella its own copy of the vertex (same coordinates),
 * which changes no geometry.
 *
 * At an edge with 2k triangles, the triangles are sorted by angle around the edge and
 * paired: a triangle's solid side is at decreasing angle about its own edge direction
 * (its normal points to increasing angle), so each triangle running u->v is paired with
 * the one just before it in the turn about u->v, which runs v->u. Then, at every vertex,
 * the triangles around it are grouped by crossing its edges (to the unique other triangle
 * at a manifold edge, to the paired one at a non-manifold edge); each group beyond the
 * first gets a new vertex. All angle comparisons are exact predicates on the rounded
 * coordinates.
 */
#include "manifold_split.h"

#include "exact.h"
#include "exact_kernel.h"
#include "scene.h"

#include <string.h>

typedef struct splitter {
    const mci_ctx *ctx;
    mcsg_mesh *m;
    uint32_t *mate; /* per edge slot 3t + i (corner i -> i + 1): the paired slot */
    uint32_t *start, *corner; /* corners (= outgoing edge slots) of vertex v:
                                 corner[start[v] .. start[v + 1]) */
    size_t bad_edges;
} splitter;

static const double *vertex(const mcsg_mesh *m, uint32_t v)
{
    return m->vertices + 3 * (size_t)v;
}

static uint32_t slot_from(const mcsg_mesh *m, uint32_t s)
{
    return m->triangles[s];
}

/* The next and the previous corner of slot s's triangle (no division: these run for
 * every corner of the output several times). */
static uint32_t next_in_triangle(uint32_t s)
{
    return s % 3 == 2 ? s - 2 : s + 1;
}

static uint32_t prev_in_triangle(uint32_t s)
{
    return s % 3 == 0 ? s + 2 : s - 1;
}

static uint32_t slot_to(const mcsg_mesh *m, uint32_t s)
{
    return m->triangles[next_in_triangle(s)];
}

static uint32_t slot_third(const mcsg_mesh *m, uint32_t s)
{
    return m->triangles[prev_in_triangle(s)];
}

/* Sign of the turn from half-plane a to half-plane b about the axis u -> v: +1 when b
 * is within (0, pi) counter-clockwise of a. */
static int turn(const double *u, const double *v, const double *a, const double *b)
{
    mci_plane plane;
    mci_point p;
    mci_plane_init(&plane, u, v, a);
    mci_point_explicit(&p, b);
    return mci_orient3d(&p, &plane);
}

/* For a and b in one plane with the axis: whether they are on the same side of it. */
static bool same_side(const double *u, const double *v, const double *a, const double *b)
{
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        int sa = mci_orient2d(u[i], u[j], v[i], v[j], a[i], a[j]);
        if (sa != 0)
            return sa == mci_orient2d(u[i], u[j], v[i], v[j], b[i], b[j]);
    }
    return true;
}

/* Angle class of half-plane w relative to the reference r: 0 same, 1 in (0, pi), 2 pi,
 * 3 in (pi, 2 pi). */
static int angle_class(const double *u, const double *v, const double *r, const double *w)
{
    int t = turn(u, v, r, w);
    if (t != 0)
        return t > 0 ? 1 : 3;
    return same_side(u, v, r, w) ? 0 : 2;
}

/* Whether w1 comes before w2 in the turn about u -> v starting at r. */
static bool angle_before(const double *u, const double *v, const double *r, const double *w1,
                         const double *w2)
{
    int c1 = angle_class(u, v, r, w1), c2 = angle_class(u, v, r, w2);
    if (c1 != c2)
        return c1 < c2;
    return (c1 == 1 || c1 == 3) && turn(u, v, w1, w2) > 0;
}

/* Pair the 2k slots of one edge (slots[0 .. n)) by angle; false if they do not
 * alternate in direction (then the edge is left unpaired). */
static bool pair_around_edge(splitter *sp, uint32_t *slots, size_t n)
{
    const mcsg_mesh *m = sp->m;
    uint32_t u = slot_from(m, slots[0]), v = slot_to(m, slots[0]);
    const double *pu = vertex(m, u), *pv = vertex(m, v), *r = vertex(m, slot_third(m, slots[0]));
    for (size_t i = 1; i < n; i++) /* insertion sort: n is small */
        for (size_t j = i; j > 0 && angle_before(pu, pv, r, vertex(m, slot_third(m, slots[j])),
                                                 vertex(m, slot_third(m, slots[j - 1])));
             j--) {
            uint32_t t = slots[j];
            slots[j] = slots[j - 1];
            slots[j - 1] = t;
        }
    for (size_t i = 0; i < n; i++) {
        uint32_t s = slots[i], before = slots[(i + n - 1) % n];
        if (slot_from(m, s) != u)
            continue;
        if (slot_from(m, before) != v)
            return false;
        sp->mate[s] = before;
        sp->mate[before] = s;
    }
    return true;
}

static uint32_t find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
    return x;
}

/* One stable counting sort of corners by their edge's target vertex (by_target) or by
 * their own vertex: in[] (NULL: all corners in order) into out[], with start[v] the first
 * position of key v. */
static void sort_corners_by(const mcsg_mesh *m, bool by_target, const uint32_t *in,
                            uint32_t *out, uint32_t *start)
{
    size_t n = 3 * m->triangle_count;
    memset(start, 0, (m->vertex_count + 2) * sizeof *start);
    for (size_t c = 0; c < n; c++)
        start[(by_target ? slot_to(m, (uint32_t)c) : slot_from(m, (uint32_t)c)) + 2]++;
    for (size_t v = 2; v < m->vertex_count + 2; v++)
        start[v] += start[v - 1];
    for (size_t k = 0; k < n; k++) {
        uint32_t c = in ? in[k] : (uint32_t)k;
        out[start[(by_target ? slot_to(m, c) : slot_from(m, c)) + 1]++] = c;
    }
}

/* Corners (3t + i) grouped by vertex in CSR form, each vertex's corners ordered by the
 * vertex their edge goes to. Corner 3t + i is also the edge slot leaving its vertex, so
 * this lists each vertex's outgoing edges, and the edges u -> v form one run: a fan
 * centre with a thousand edges costs a binary search, not a scan per edge. Two stable
 * counting sorts: by edge target, then by vertex. */
static bool corners_by_vertex(splitter *sp)
{
    const mcsg_mesh *m = sp->m;
    size_t n = 3 * m->triangle_count;
    uint32_t *start = mci_calloc_array(sp->ctx, m->vertex_count + 2, sizeof *start);
    uint32_t *corner = mci_malloc_array(sp->ctx, n + 1, sizeof *corner);
    uint32_t *by_target = mci_malloc_array(sp->ctx, n + 1, sizeof *by_target);
    sp->start = start;
    sp->corner = corner;
    if (start && corner && by_target) {
        sort_corners_by(m, true, NULL, by_target, start);
        sort_corners_by(m, false, by_target, corner, start);
    }
    mci_free(sp->ctx, by_target);
    return start && corner && by_target;
}

/* The run of vertex u's corners whose edge goes to v, from *cursor on: cursor[u] only
 * moves forward, which is enough because the queries to each vertex come with
 * increasing targets (pair_edges walks u in order and asks v for its edges back to u).
 * Returns the run's start; *count is its length. */
static uint32_t run_to(const splitter *sp, uint32_t *cursor, uint32_t u, uint32_t v,
                       size_t *count)
{
    uint32_t k = cursor[u], end = sp->start[u + 1], first;
    while (k < end && slot_to(sp->m, sp->corner[k]) < v)
        k++;
    cursor[u] = first = k;
    while (k < end && slot_to(sp->m, sp->corner[k]) == v)
        k++;
    *count = k - first;
    return first;
}

/* Pair every edge's slots: the two opposite ones of a manifold edge directly, the 2k
 * of a non-manifold edge by angle. Each edge is handled once, from its smaller vertex:
 * the corners of u (ordered by target) come in runs u -> v, and the run v -> u is found
 * with v's cursor. */
static bool pair_edges(splitter *sp)
{
    const mcsg_mesh *m = sp->m;
    size_t room = 64;
    uint32_t *slots = mci_malloc_array(sp->ctx, room, sizeof *slots);
    uint32_t *cursor = mci_malloc_array(sp->ctx, m->vertex_count + 1, sizeof *cursor);
    if (!slots || !cursor) {
        mci_free(sp->ctx, slots);
        mci_free(sp->ctx, cursor);
        return false;
    }
    for (size_t s = 0; s < 3 * m->triangle_count; s++)
        sp->mate[s] = MCI_NONE;
    memcpy(cursor, sp->start, m->vertex_count * sizeof *cursor);
    for (uint32_t u = 0; u < m->vertex_count; u++)
        for (uint32_t k = sp->start[u]; k < sp->start[u + 1];) {
            uint32_t v = slot_to(m, sp->corner[k]), back_first;
            size_t ahead, back;
            uint32_t ahead_first = run_to(sp, cursor, u, v, &ahead);
            k = ahead_first + (uint32_t)ahead;
            if (v < u)
                continue;
            back_first = run_to(sp, cursor, v, u, &back);
            if (ahead == 1 && back == 1) {
                sp->mate[sp->corner[ahead_first]] = sp->corner[back_first];
                sp->mate[sp->corner[back_first]] = sp->corner[ahead_first];
                continue;
            }
            if (ahead != back || ahead + back > room) {
                sp->bad_edges++;
                continue;
            }
            memcpy(slots, sp->corner + ahead_first, ahead * sizeof *slots);
            memcpy(slots + ahead, sp->corner + back_first, back * sizeof *slots);
            if (!pair_around_edge(sp, slots, ahead + back))
                sp->bad_edges++;
        }
    mci_free(sp->ctx, slots);
    mci_free(sp->ctx, cursor);
    return true;
}

/* The corner of the triangle holding slot s (paired with an edge at vertex x) at x. */
static uint32_t corner_at(const mcsg_mesh *m, uint32_t s, uint32_t x)
{
    uint32_t t = s - s % 3;
    for (uint32_t i = 0; i < 3; i++)
        if (m->triangles[t + i] == x)
            return t + i;
    return MCI_NONE;
}

/* Union the corners of one vertex across its edges; parent is indexed by corner. */
static void group_corners(const splitter *sp, const uint32_t *corners, size_t n,
                          uint32_t *parent)
{
    const mcsg_mesh *m = sp->m;
    for (size_t k = 0; k < n; k++) {
        uint32_t c = corners[k], x = m->triangles[c];
        uint32_t at_x[2] = {c, c - c % 3 + (c % 3 + 2) % 3}; /* x -> next, prev -> x */
        for (int e = 0; e < 2; e++) {
            uint32_t other = sp->mate[at_x[e]], d;
            if (other == MCI_NONE || (d = corner_at(m, other, x)) == MCI_NONE)
                continue;
            d = find(parent, d);
            c = find(parent, c);
            if (c != d)
                parent[c > d ? c : d] = c < d ? c : d;
        }
    }
}

/* New vertices for every umbrella of a vertex but the one with its first corner. */
static bool split_vertices(splitter *sp, size_t *added)
{
    mcsg_mesh *m = sp->m;
    size_t n = 3 * m->triangle_count, nv = m->vertex_count, extra = 0;
    const uint32_t *start = sp->start, *corner = sp->corner;
    uint32_t *parent = mci_malloc_array(sp->ctx, n + 1, sizeof *parent);
    uint32_t *copy = mci_malloc_array(sp->ctx, n + 1, sizeof *copy);
    bool ok = parent && copy;
    if (!ok) {
        mci_free(sp->ctx, parent);
        mci_free(sp->ctx, copy);
        return false;
    }
    for (size_t c = 0; c < n; c++)
        parent[c] = (uint32_t)c, copy[c] = MCI_NONE;
    for (size_t v = 0; v < nv; v++)
        group_corners(sp, corner + start[v], start[v + 1] - start[v], parent);
    for (size_t v = 0; v < nv; v++) {
        uint32_t first_root = start[v] < start[v + 1] ? find(parent, corner[start[v]]) : 0;
        for (uint32_t k = start[v]; k < start[v + 1]; k++) {
            uint32_t c = corner[k], root = find(parent, c);
            if (root == first_root)
                continue;
            if (copy[root] == MCI_NONE)
                copy[root] = (uint32_t)(nv + extra++);
            m->triangles[c] = copy[root];
        }
    }
    /* Second pass over the roots to fill the new vertices' coordinates. */
    if (extra > 0) {
        double *grown = mci_realloc_array(sp->ctx, m->vertices, nv + extra, 3 * sizeof(double));
        ok = grown != NULL;
        if (ok) {
            m->vertices = grown;
            for (size_t v = 0; v < nv; v++)
                for (uint32_t k = start[v]; k < start[v + 1]; k++) {
                    uint32_t id = m->triangles[corner[k]];
                    if (id >= nv)
                        memcpy(m->vertices + 3 * (size_t)id, m->vertices + 3 * v,
                               3 * sizeof(double));
                }
            m->vertex_count = nv + extra;
        }
    }
    *added = extra;
    mci_free(sp->ctx, parent);
    mci_free(sp->ctx, copy);
    return ok;
}

bool mci_split_touching(const mci_ctx *ctx, mcsg_mesh *m, mci_touching_split *result)
{
    splitter sp = {ctx, m, NULL, NULL, NULL, 0};
    bool ok;
    memset(result, 0, sizeof *result);
    if (m->triangle_count == 0)
        return true;
    sp.mate = mci_malloc_array(ctx, 3 * m->triangle_count + 1, sizeof *sp.mate);
    ok = sp.mate && corners_by_vertex(&sp) && pair_edges(&sp) &&
         split_vertices(&sp, &result->new_vertices);
    result->unpaired_edges = sp.bad_edges;
    mci_free(ctx, sp.mate);
    mci_free(ctx, sp.start);
    mci_free(ctx, sp.corner);
    return ok;
}
