/*
 * Whether a shell of a mesh crosses itself (mci_find_shell_crossing), exactly, at about
 * a third of an evaluation's cost on scanned models (testing every nearby pair through
 * the octree, as mcsg_mesh_self_intersections does, costs about two evaluations).
 *
 * Each triangle faces one way along one axis: the axis of a nonzero component of its
 * normal (the largest in floating point) and that component's exact sign (the
 * orientation of its projection along the axis). Triangles joined across manifold edges
 * that face the same way form patches. A patch is proven not to cross itself when its
 * projection along the axis is one to one, which its boundary alone tells: every
 * projected triangle turns counter-clockwise (those facing down seen mirrored), so the
 * number of triangles covering a point off the projected boundary is the winding number
 * of that boundary around it. When the boundary loops are simple and disjoint (or touch
 * in a vertex where the patch's sectors keep apart: a pinch, where its triangles may
 * meet in that vertex only) and no counter-clockwise loop lies where the winding number
 * is already one, it is at most one everywhere, and the projection is one to one (an
 * interior vertex whose triangles wound twice around it would make it two nearby). A
 * patch whose boundary is not like that is split in halves, which are tried in turn.
 *
 * Every other pair (triangles of different patches, or both of an unproven patch, in
 * one shell) whose bounding boxes meet is found in a uniform grid and decided by the
 * exact triangle-triangle test (mci_triangles_cross). On a scanned model 98% of the
 * triangles lie in proven patches, and the grid's cells inside one are skipped whole;
 * the grid over every triangle is most of the cost.
 *
 * A mesh proven star-shaped (mci_star_shaped, one pass: every convex mesh but the
 * flattest) needs none of this; its callers try that first.
 */
#include "csg/shell_crossing.h"
#include "base/sort.h"
#include "csg/self_intersect.h"
#include "exact/kernel.h"
#include "exact/predicates.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { NO_FACING = 6 };

/* A patch boundary edge, projected; the patch lies on its left. */
typedef struct segment {
    double a[2], b[2];
    uint32_t half; /* its half-edge, 3 t + k */
    uint32_t next; /* the segment leaving its end */
    uint32_t loop;
} segment;

typedef struct keyed {
    double x, y;
    uint32_t seg;
} keyed;

/* A triangle of a bucket, with its box's extent along the sweep axis. */
typedef struct swept {
    double lo, hi;
    uint32_t tri, patch;
} swept;

typedef struct test_state {
    const mci_ctx *ctx;
    const mcsg_mesh *m;
    const uint32_t *shell, *twin;
    uint8_t *facing;       /* per triangle: 2 axis + (1 when facing down the axis) */
    uint32_t *patch;       /* per triangle */
    uint32_t *by_patch;    /* triangles, each patch's a run */
    uint32_t *patch_first; /* per patch: its run in by_patch */
    uint32_t *patch_size;
    uint8_t *proven;       /* per patch */
    uint32_t patch_count;
    uint32_t *seg_of;      /* per half-edge: its segment while its patch is examined */
    segment *segs;         /* room for seg_room of these and of the next four */
    keyed *order;
    uint32_t *scratch;
    uint32_t *prev;        /* per segment: the one arriving at its start */
    uint8_t *pinch;        /* per segment: its end is a pinch (boundary_is_simple) */
    size_t seg_room;
    mci_shell_crossing_stats stats;
    bool collect;          /* list every crossing pair, not only the first */
    bool nomem;            /* the list could not grow */
    uint64_t *found;       /* when collecting: the pairs, s << 32 | t with s < t */
    mci_keyed *sweep;      /* a bucket's triangles, sorted along the sweep axis */
    swept *swept;          /* the same with their extents along it */
    mci_plane *planes;     /* per triangle, when plane_ready */
    uint8_t *plane_ready;
    size_t found_count, found_cap;
} test_state;

static const double *corner(const mcsg_mesh *m, uint32_t t, uint32_t k)
{
    return m->vertices + 3 * (size_t)m->triangles[3 * (size_t)t + k];
}

/* The mean of the corners of m's triangles, in doubles: a point inside any convex mesh
 * but the flattest. */
static void corner_mean(const mcsg_mesh *m, double o[3])
{
    double sum[3] = {0, 0, 0};
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        for (int k = 0; k < 3; k++)
            sum[k] += m->vertices[3 * (size_t)m->triangles[i] + k];
    for (int k = 0; k < 3; k++)
        o[k] = sum[k] / (3 * (double)m->triangle_count);
}

/* Sign of det[u - o, v - o, d'] for the direction d' = (q - o) + e x + e^2 y + e^3 z
 * with e infinitesimal: the first nonzero of the exact det[u - o, v - o, q - o] and the
 * components of (u - o) x (v - o). Zero only where o lies on the line uv. */
static int side_of_ray(const double *o, const double *q, const double *u, const double *v)
{
    int s = mci_orient3d_vertices(o, u, v, q);
    if (s == 0)
        s = mci_orient2d(u[1], u[2], v[1], v[2], o[1], o[2]);
    if (s == 0)
        s = mci_orient2d(u[2], u[0], v[2], v[0], o[2], o[0]);
    if (s == 0)
        s = mci_orient2d(u[0], u[1], v[0], v[1], o[0], o[1]);
    return s;
}

/* m proven star-shaped from the mean of its corners: that point o lies
 * strictly behind every triangle's plane (each seen from o turns one way, and has an
 * area), and a ray from o crosses exactly one triangle (the cone from o over the
 * triangle holds its direction, perturbed symbolically off every edge). Projected from
 * o onto a sphere, the triangles then cover each direction as often as the ray's, since
 * the edges are used as often one way as the other (the leaf contract): once. So their
 * projections have disjoint interiors, and two triangles that met other than in common
 * corners and edges would overlap there (a corner on another's edge included: the
 * triangle on that edge's other side would cover the same directions as the corner's).
 * Every convex mesh but the flattest passes; a scan mostly does not, cheaply. */
bool mci_star_shaped(const mcsg_mesh *m)
{
    size_t n = m->triangle_count, hits = 0;
    double o[3], q[3];
    corner_mean(m, o);
    q[0] = o[0] + (1 + fabs(o[0])), q[1] = o[1], q[2] = o[2];
    if (!isfinite(o[0]) || !isfinite(o[1]) || !isfinite(o[2]) || !isfinite(q[0]))
        return false;
    for (size_t t = 0; t < n; t++)
        if (mci_orient3d_vertices(corner(m, (uint32_t)t, 0), corner(m, (uint32_t)t, 1),
                                  corner(m, (uint32_t)t, 2), o) >= 0)
            return false;
    for (size_t t = 0; t < n && hits < 2; t++) {
        const double *a = corner(m, (uint32_t)t, 0), *b = corner(m, (uint32_t)t, 1),
                     *c = corner(m, (uint32_t)t, 2);
        hits += side_of_ray(o, q, a, b) > 0 && side_of_ray(o, q, b, c) > 0 &&
                side_of_ray(o, q, c, a) > 0;
    }
    return hits == 1;
}

/* The facing of triangle abc: NO_FACING when it has no area. */
static uint8_t facing_of(const double *a, const double *b, const double *c)
{
    double u[3], v[3], n[3];
    int axes[3] = {0, 1, 2};
    for (int k = 0; k < 3; k++)
        u[k] = b[k] - a[k], v[k] = c[k] - a[k];
    n[0] = fabs(u[1] * v[2] - u[2] * v[1]);
    n[1] = fabs(u[2] * v[0] - u[0] * v[2]);
    n[2] = fabs(u[0] * v[1] - u[1] * v[0]);
    for (int i = 1; i < 3; i++) /* largest first */
        for (int j = i; j > 0 && n[axes[j]] > n[axes[j - 1]]; j--) {
            int x = axes[j];
            axes[j] = axes[j - 1], axes[j - 1] = x;
        }
    for (int i = 0; i < 3; i++) {
        int ax = axes[i], i1 = (ax + 1) % 3, i2 = (ax + 2) % 3;
        int s = mci_orient2d(a[i1], a[i2], b[i1], b[i2], c[i1], c[i2]);
        if (s != 0)
            return (uint8_t)(2 * ax + (s < 0));
    }
    return NO_FACING;
}

/* p projected along the facing's axis, mirrored when it faces down: its triangles then
 * turn counter-clockwise. */
static void project(const double *p, uint8_t facing, double out[2])
{
    int ax = facing / 2, i1 = (ax + 1) % 3, i2 = (ax + 2) % 3;
    out[0] = p[(facing & 1) ? i2 : i1];
    out[1] = p[(facing & 1) ? i1 : i2];
}

/* Patches: triangles joined across manifold edges with the same facing, numbered in
 * the order of their first triangles, listed patch by patch in by_patch. */
static void find_patches(test_state *s)
{
    size_t n = s->m->triangle_count, listed = 0;
    for (size_t t = 0; t < n; t++)
        s->patch[t] = MCI_NONE;
    for (size_t t = 0; t < n; t++) {
        uint32_t id;
        if (s->patch[t] != MCI_NONE)
            continue;
        id = s->patch_count++;
        s->patch_first[id] = (uint32_t)listed;
        s->by_patch[listed++] = (uint32_t)t;
        s->patch[t] = id;
        for (size_t q = s->patch_first[id]; q < listed; q++) {
            uint32_t u = s->by_patch[q];
            for (uint32_t k = 0; k < 3 && s->facing[u] != NO_FACING; k++) {
                uint32_t h = s->twin[3 * (size_t)u + k], w = h / 3;
                if (h == MCI_NONE || s->patch[w] != MCI_NONE || s->facing[w] != s->facing[u])
                    continue;
                s->patch[w] = id;
                s->by_patch[listed++] = w;
            }
        }
        s->patch_size[id] = (uint32_t)listed - s->patch_first[id];
    }
}

static bool on_boundary(const test_state *s, uint32_t half, uint32_t p)
{
    uint32_t h = s->twin[half];
    return h == MCI_NONE || s->patch[h / 3] != p;
}

static uint32_t next_in_triangle(uint32_t half)
{
    return half - half % 3 + (half % 3 + 1) % 3;
}

static bool make_room(test_state *s, size_t n)
{
    if (n <= s->seg_room)
        return true;
    n = n < 2 * s->seg_room ? 2 * s->seg_room : n;
    mci_free(s->ctx, s->segs);
    mci_free(s->ctx, s->order);
    mci_free(s->ctx, s->scratch);
    mci_free(s->ctx, s->prev);
    mci_free(s->ctx, s->pinch);
    s->segs = mci_malloc_array(s->ctx, n, sizeof *s->segs);
    s->order = mci_malloc_array(s->ctx, n, sizeof *s->order);
    s->scratch = mci_malloc_array(s->ctx, n, sizeof *s->scratch);
    s->prev = mci_malloc_array(s->ctx, n, sizeof *s->prev);
    s->pinch = mci_malloc_array(s->ctx, n, sizeof *s->pinch);
    s->seg_room = s->segs && s->order && s->scratch && s->prev && s->pinch ? n : 0;
    return s->seg_room != 0;
}

/* Patch p's boundary edges as segments, each with the one leaving its end (found by
 * turning about that end inside the patch); *count of them. False when a turn does not
 * end (half-edges not forming a surface there). */
static bool boundary_segments(test_state *s, uint32_t p, size_t *count)
{
    uint32_t first = s->patch_first[p], end = first + s->patch_size[p];
    uint8_t facing = s->facing[s->by_patch[first]];
    size_t n = 0;
    for (uint32_t i = first; i < end; i++)
        for (uint32_t k = 0; k < 3; k++) {
            uint32_t t = s->by_patch[i], half = 3 * t + k;
            if (!on_boundary(s, half, p))
                continue;
            s->seg_of[half] = (uint32_t)n;
            s->segs[n].half = half;
            project(corner(s->m, t, k), facing, s->segs[n].a);
            project(corner(s->m, t, (k + 1) % 3), facing, s->segs[n].b);
            n++;
        }
    for (size_t i = 0; i < n; i++) {
        uint32_t e = next_in_triangle(s->segs[i].half);
        for (size_t steps = 0; !on_boundary(s, e, p); steps++) {
            if (steps > 3 * (size_t)(end - first))
                return false;
            e = next_in_triangle(s->twin[e]);
        }
        s->segs[i].next = s->seg_of[e];
        s->prev[s->seg_of[e]] = (uint32_t)i;
        s->pinch[i] = 0;
    }
    *count = n;
    return true;
}

static bool between(const double *p, const double *q, const double *x)
{
    for (int k = 0; k < 2; k++)
        if (!((p[k] <= x[k] && x[k] <= q[k]) || (q[k] <= x[k] && x[k] <= p[k])))
            return false;
    return true;
}

static int orient(const double *a, const double *b, const double *c)
{
    return mci_orient2d(a[0], a[1], b[0], b[1], c[0], c[1]);
}

/* Whether the closed segments pq and rs meet. */
static bool segments_meet(const double *p, const double *q, const double *r, const double *x)
{
    int o1 = orient(p, q, r), o2 = orient(p, q, x), o3 = orient(r, x, p), o4 = orient(r, x, q);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return true;
    return (o1 == 0 && between(p, q, r)) || (o2 == 0 && between(p, q, x)) ||
           (o3 == 0 && between(r, x, p)) || (o4 == 0 && between(r, x, q));
}

/* Segment j leaves where i ends: they must not fold back onto each other. */
static bool turn_is_clean(const segment *i, const segment *j)
{
    int k = i->a[0] != i->b[0] ? 0 : 1;
    if (orient(i->a, i->b, j->b) != 0)
        return true;
    return (i->a[k] < i->b[k]) != (j->b[k] < i->b[k]);
}

static bool same(const double *p, const double *q)
{
    return p[0] == q[0] && p[1] == q[1];
}

/* Segments i and j, not consecutive, meeting only in an end of each: the boundary passes
 * there twice (a pinch, where the patch's triangles meet in a vertex only), which is
 * allowed when the patch's sectors there keep apart (pinches_keep_apart). Marks the
 * segments arriving there. */
static bool touch_at_an_end(test_state *s, uint32_t i, uint32_t j)
{
    const segment *g = &s->segs[i], *h = &s->segs[j];
    const double *p, *x, *y;
    if (same(g->a, h->a) + same(g->a, h->b) + same(g->b, h->a) + same(g->b, h->b) != 1)
        return false;
    p = same(g->a, h->a) || same(g->a, h->b) ? g->a : g->b;
    x = p == g->a ? g->b : g->a;
    y = same(h->a, p) ? h->b : h->a;
    if (orient(p, x, y) == 0 && (x[0] < p[0]) == (y[0] < p[0]) && (x[1] < p[1]) == (y[1] < p[1]))
        return false; /* along one line, on one side of p: overlapping */
    s->pinch[p == g->b ? i : s->prev[i]] = 1;
    s->pinch[same(h->b, p) ? j : s->prev[j]] = 1;
    return true;
}

static bool pair_is_clean(test_state *s, uint32_t i, uint32_t j)
{
    const segment *segs = s->segs;
    if (segs[i].next == j)
        return turn_is_clean(&segs[i], &segs[j]) &&
               (segs[j].next != i || turn_is_clean(&segs[j], &segs[i]));
    if (segs[j].next == i)
        return turn_is_clean(&segs[j], &segs[i]);
    return touch_at_an_end(s, i, j) ||
           !segments_meet(segs[i].a, segs[i].b, segs[j].a, segs[j].b);
}

static int keyed_compare(const void *p, const void *q)
{
    const keyed *a = p, *b = q;
    if (a->x != b->x)
        return (a->x > b->x) - (a->x < b->x);
    return (a->y > b->y) - (a->y < b->y);
}

static double lo_of(const segment *g, int k)
{
    return g->a[k] < g->b[k] ? g->a[k] : g->b[k];
}

static double hi_of(const segment *g, int k)
{
    return g->a[k] < g->b[k] ? g->b[k] : g->a[k];
}

/* Whether the n segments meet only where one leaves another's end (without folding
 * back) or in an end of each (pinches, marked for pinches_keep_apart): a sweep along x
 * over their boxes. False also when the sweep would cost more than a small multiple of
 * n (the patch stays unproven). */
static bool boundary_is_simple(test_state *s, size_t n)
{
    size_t active = 0, work = 0, budget = 64 * n + 4096;
    for (size_t i = 0; i < n; i++)
        s->order[i].x = lo_of(&s->segs[i], 0), s->order[i].y = 0, s->order[i].seg = (uint32_t)i;
    qsort(s->order, n, sizeof *s->order, keyed_compare);
    for (size_t o = 0; o < n; o++) {
        uint32_t i = s->order[o].seg;
        const segment *g = &s->segs[i];
        for (size_t a = 0; a < active;) {
            const segment *h = &s->segs[s->scratch[a]];
            if (hi_of(h, 0) < s->order[o].x) {
                s->scratch[a] = s->scratch[--active];
                continue;
            }
            if (++work > budget)
                return false;
            if (hi_of(h, 1) >= lo_of(g, 1) && hi_of(g, 1) >= lo_of(h, 1) &&
                !pair_is_clean(s, i, s->scratch[a]))
                return false;
            a++;
        }
        s->scratch[active++] = i;
    }
    return true;
}

/* Whether ray p->q comes before p->r turning counter-clockwise from the direction of +x
 * (+1), after it (-1), or they point the same way (0). */
static int ray_order(const double *p, const double *q, const double *r)
{
    int hq = q[1] > p[1] || (q[1] == p[1] && q[0] > p[0]) ? 0 : 1;
    int hr = r[1] > p[1] || (r[1] == p[1] && r[0] > p[0]) ? 0 : 1;
    return hq != hr ? (hq < hr ? 1 : -1) : orient(p, q, r);
}

enum { PINCH_MAX = 16 };

/* The k segments in[] all end at one point p, where the patch's sector after each runs
 * counter-clockwise from the ray along the segment leaving p to the ray back along the
 * segment arriving: whether the sectors keep apart (in turn order around p, each
 * sector's first ray is followed by its own last, no two rays along one line). */
static bool sectors_keep_apart(const test_state *s, const uint32_t *in, size_t k)
{
    const double *p = s->segs[in[0]].b, *ray[2 * PINCH_MAX];
    int tag[2 * PINCH_MAX] = {0}; /* 2 sector + (1 for its last ray) */
    size_t n = 2 * k, start = 0;
    if (k > PINCH_MAX)
        return false;
    for (size_t i = 0; i < k; i++) {
        ray[2 * i] = s->segs[s->segs[in[i]].next].b, tag[2 * i] = (int)(2 * i);
        ray[2 * i + 1] = s->segs[in[i]].a, tag[2 * i + 1] = (int)(2 * i + 1);
    }
    for (size_t i = 1; i < n; i++) /* insertion sort: a pinch has few sectors */
        for (size_t j = i; j > 0 && ray_order(p, ray[j], ray[j - 1]) > 0; j--) {
            const double *r = ray[j];
            int t = tag[j];
            ray[j] = ray[j - 1], tag[j] = tag[j - 1];
            ray[j - 1] = r, tag[j - 1] = t;
        }
    for (size_t i = 0; i < n; i++)
        if (ray_order(p, ray[i], ray[(i + 1) % n]) == 0)
            return false;
    while (tag[start] & 1)
        start++;
    for (size_t i = 0; i < n; i += 2)
        if (tag[(start + i + 1) % n] != tag[(start + i) % n] + 1)
            return false;
    return true;
}

/* Whether the patch's sectors keep apart at every pinch of its boundary: the segments
 * arriving at pinches, grouped by point. */
static bool pinches_keep_apart(test_state *s, size_t n)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (s->pinch[i])
            s->order[m].x = s->segs[i].b[0], s->order[m].y = s->segs[i].b[1],
            s->order[m++].seg = (uint32_t)i;
    qsort(s->order, m, sizeof *s->order, keyed_compare);
    for (size_t a = 0, b; a < m; a = b) {
        for (b = a + 1; b < m && s->order[b].x == s->order[a].x && s->order[b].y == s->order[a].y;
             b++)
            ;
        if (b - a > PINCH_MAX)
            return false;
        for (size_t i = a; i < b; i++)
            s->scratch[i - a] = s->order[i].seg;
        if (!sectors_keep_apart(s, s->scratch, b - a))
            return false;
    }
    return true;
}

/* Whether q lies inside the loop starting at segment first (q off it). */
static bool inside_loop(const segment *segs, uint32_t first, const double *q)
{
    bool in = false;
    uint32_t i = first;
    do {
        const segment *g = &segs[i];
        if ((g->a[1] > q[1]) != (g->b[1] > q[1])) {
            int o = orient(g->a, g->b, q);
            if (g->b[1] > g->a[1] ? o > 0 : o < 0)
                in = !in;
        }
        i = g->next;
    } while (i != first);
    return in;
}

/* +1 when the loop starting at segment first turns counter-clockwise, -1 otherwise: the
 * turn at its lowest vertex (smallest x, then y), which no simple loop makes straight;
 * 0 when that vertex is a pinch (the loop may pass it twice: not decided here). */
static int loop_sign(const test_state *s, uint32_t first)
{
    const segment *segs = s->segs;
    uint32_t i = first, prev = first, best = first, best_prev = first;
    do {
        const double *a = segs[i].a, *b = segs[best].a;
        if (a[0] < b[0] || (a[0] == b[0] && a[1] < b[1]))
            best = i, best_prev = prev;
        prev = i;
        i = segs[i].next;
    } while (i != first);
    if (best == first)
        best_prev = prev; /* the loop's last segment ends where it starts */
    if (s->pinch[best_prev])
        return 0;
    return orient(segs[best_prev].a, segs[best].a, segs[best].b) > 0 ? 1 : -1;
}

/* The loops of the n segments (segment.loop), each in loops[] by a segment whose start
 * is no pinch (its sample point) and its sign; the number of loops, or 0 when a loop has
 * no such segment or no decided sign. */
static uint32_t find_loops(test_state *s, size_t n, keyed *loops)
{
    uint32_t count = 0;
    for (size_t i = 0; i < n; i++)
        s->segs[i].loop = MCI_NONE;
    for (size_t i = 0; i < n; i++) {
        uint32_t j = (uint32_t)i, sample = MCI_NONE;
        if (s->segs[i].loop != MCI_NONE)
            continue;
        do {
            s->segs[j].loop = count;
            if (sample == MCI_NONE && !s->pinch[s->prev[j]])
                sample = j;
            j = s->segs[j].next;
        } while (s->segs[j].loop == MCI_NONE);
        if (j != i || sample == MCI_NONE)
            return 0; /* next does not cycle back, or pinches everywhere */
        loops[count].seg = sample;
        loops[count].x = loop_sign(s, sample);
        if (loops[count++].x == 0)
            return 0;
    }
    return count;
}

/* With the boundary simple and its pinches apart: whether the winding number stays at
 * most one, that is, whether no counter-clockwise loop lies inside loops whose signs sum
 * above zero (by a point of it that no other loop touches). */
static bool winding_at_most_one(test_state *s, size_t n)
{
    keyed *loops = s->order;
    uint32_t count = find_loops(s, n, loops);
    if (count == 1 || count == 0)
        return count == 1 && loops[0].x > 0;
    if ((size_t)count * n > ((size_t)1 << 22))
        return false;
    for (uint32_t l = 0; l < count; l++) {
        int around = 0;
        if (loops[l].x < 0)
            continue;
        for (uint32_t k = 0; k < count; k++)
            if (k != l && inside_loop(s->segs, loops[k].seg, s->segs[loops[l].seg].a))
                around += (int)loops[k].x;
        if (around > 0)
            return false;
    }
    return true;
}

/* Whether patch p's projection is proven one to one (the file comment); false on
 * allocation failure too (*nomem set). */
static bool prove_patch(test_state *s, uint32_t p, bool *nomem)
{
    uint32_t size = s->patch_size[p];
    size_t n;
    if (size == 1)
        return true;
    if (s->facing[s->by_patch[s->patch_first[p]]] == NO_FACING)
        return false;
    if (!make_room(s, 3 * (size_t)size)) {
        *nomem = true;
        return false;
    }
    if (!boundary_segments(s, p, &n) || n < 3)
        return false;
    s->stats.boundary_edges += n;
    return boundary_is_simple(s, n) && pinches_keep_apart(s, n) && winding_at_most_one(s, n);
}

/* The grid: cell edge h, origin lo; a coordinate's cell along one axis (by the
 * reciprocal: any monotone rounding will do, the same everywhere). */
typedef struct grid {
    double lo[3], h, per_h;
} grid;

static uint32_t cell_of(const grid *g, double x, int k)
{
    return (uint32_t)((x - g->lo[k]) * g->per_h);
}

static uint32_t cell_hash(uint32_t x, uint32_t y, uint32_t z)
{
    uint64_t h = (uint64_t)x | (uint64_t)y << 21 | (uint64_t)z << 42;
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    return (uint32_t)(h >> 32);
}

static double min2(double a, double b)
{
    return a < b ? a : b;
}

static double max2(double a, double b)
{
    return a < b ? b : a;
}

static void triangle_box(const mcsg_mesh *m, uint32_t t, double box[6])
{
    for (int k = 0; k < 3; k++) {
        double a = corner(m, t, 0)[k], b = corner(m, t, 1)[k], c = corner(m, t, 2)[k];
        box[k] = min2(a, min2(b, c));
        box[k + 3] = max2(a, max2(b, c));
    }
}

/* The grid's cell size: about four times a triangle's mean extent, and
 * coarser while the triangles would fill more than `limit` (cell, triangle) entries. */
static size_t choose_grid(const test_state *s, const double *box, size_t limit, grid *g)
{
    size_t n = s->m->triangle_count, entries = 0;
    double hi[3], extent = 0;
    for (int k = 0; k < 3; k++)
        g->lo[k] = INFINITY, hi[k] = -INFINITY;
    for (size_t t = 0; t < n; t++) {
        double e = 0;
        for (int k = 0; k < 3; k++) {
            g->lo[k] = min2(g->lo[k], box[6 * t + k]);
            hi[k] = max2(hi[k], box[6 * t + k + 3]);
            e = max2(e, box[6 * t + k + 3] - box[6 * t + k]);
        }
        extent += e / (double)n;
    }
    g->h = 4 * extent;
    for (int k = 0; k < 3; k++) /* at most 2^20 cells along an axis: they fit the hash */
        g->h = fmax(g->h, (hi[k] - g->lo[k]) * 0x1.00001p-20);
    if (!(g->h > 0))
        g->h = 1;
    for (int tries = 0; tries < 64; tries++, g->h *= 2) {
        g->per_h = 1 / g->h;
        entries = 0;
        for (size_t t = 0; t < n && entries <= limit; t++) {
            size_t cells = 1;
            for (int k = 0; k < 3; k++)
                cells *= 1 + (size_t)(cell_of(g, box[6 * t + k + 3], k) -
                                      cell_of(g, box[6 * t + k], k));
            entries += cells;
        }
        if (entries <= limit)
            break;
    }
    return entries;
}

static bool same3(const double *p, const double *q)
{
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

static bool boxes_meet(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] > b[k + 3] || b[k] > a[k + 3])
            return false;
    return true;
}

/* Whether the pair must be tested in this bucket: the one of the cell where the lowest
 * corner of their boxes' common part lies (each pair is tested in one bucket). */
static bool pair_belongs_here(const grid *g, const double *a, const double *b,
                              uint32_t bucket, uint32_t mask)
{
    uint32_t c[3];
    for (int k = 0; k < 3; k++)
        c[k] = cell_of(g, max2(a[k], b[k]), k);
    return (cell_hash(c[0], c[1], c[2]) & mask) == bucket;
}

static bool needs_test(const test_state *s, uint32_t t, uint32_t u)
{
    if (s->shell && s->shell[t] != s->shell[u])
        return false;
    return s->patch[t] != s->patch[u] || !s->proven[s->patch[t]];
}

/* Triangle t's plane, built on first use (the pair tests ask it again and again). */
static const mci_plane *plane_of(test_state *s, uint32_t t)
{
    if (!s->plane_ready[t]) {
        mci_plane_init(&s->planes[t], corner(s->m, t, 0), corner(s->m, t, 1),
                       corner(s->m, t, 2));
        s->plane_ready[t] = 1;
    }
    return &s->planes[t];
}

/* Whether the corners of triangle u other than those it shares with t lie strictly on
 * one side of t's plane: then the two meet at most in their common corners. */
static bool off_plane(test_state *s, uint32_t t, uint32_t u)
{
    const mci_plane *plane = plane_of(s, t);
    int side = 0;
    for (uint32_t i = 0; i < 3; i++) {
        const double *x = corner(s->m, u, i);
        int o;
        if (same3(x, plane->a) || same3(x, plane->b) || same3(x, plane->c))
            continue;
        o = mci_orient3d_vertex(x, plane);
        if (o == 0 || (side != 0 && o != side))
            return false;
        side = o;
    }
    return side != 0;
}

/* A quick proof that triangles t and u do not cross (most pairs of neighbours in
 * different patches); false when it does not apply. */
static bool apart(test_state *s, uint32_t t, uint32_t u)
{
    return off_plane(s, t, u) || off_plane(s, u, t);
}

/* The grid's (cell, triangle) entries, bucketed by cell hash (several cells may share a
 * bucket): bucket b's triangles are tri[start[b] .. start[b + 1]), in increasing order. */
typedef struct buckets {
    uint32_t mask;
    uint32_t *start, *tri;
} buckets;

/* Adds the pair to the list; false when out of memory (then the test stops). */
static bool keep_pair(test_state *s, uint32_t t, uint32_t u)
{
    if (s->found_count == s->found_cap) {
        size_t cap = s->found_cap ? 2 * s->found_cap : 64;
        uint64_t *grown = mci_realloc_array(s->ctx, s->found, cap, sizeof *grown);
        if (!grown) {
            s->nomem = true;
            return false;
        }
        s->found = grown;
        s->found_cap = cap;
    }
    s->found[s->found_count++] = t < u ? (uint64_t)t << 32 | u : (uint64_t)u << 32 | t;
    return true;
}

/* A key whose unsigned order is the order of the double x (not NaN). */
static uint64_t order_key(double x)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    return bits >> 63 ? ~bits : bits | (uint64_t)1 << 63;
}

/* The axis along which the n triangles' boxes overlap least: the smallest sum of
 * extents against the span of the lower ends. */
static int sweep_axis(const double *box, const uint32_t *run, size_t n)
{
    int best = 0;
    double best_ratio = INFINITY;
    for (int k = 0; k < 3; k++) {
        double lo = INFINITY, hi = -INFINITY, sum = 0;
        for (size_t i = 0; i < n; i++) {
            const double *b = box + 6 * (size_t)run[i];
            lo = min2(lo, b[k]);
            hi = max2(hi, b[k]);
            sum += b[k + 3] - b[k];
        }
        if (hi > lo && sum / (hi - lo) < best_ratio)
            best = k, best_ratio = sum / (hi - lo);
    }
    return best;
}

/* Bucket b's distinct triangles in s->swept with their extents along the sweep axis,
 * by the lower end (then by index); returns how many. */
static size_t sort_for_sweep(test_state *s, const double *box, const uint32_t *run, size_t n,
                             int *axis)
{
    size_t count = 0;
    *axis = sweep_axis(box, run, n);
    for (size_t i = 0; i < n; i++)
        if (i == 0 || run[i] != run[i - 1])
            s->sweep[count++] = (mci_keyed){order_key(box[6 * (size_t)run[i] + *axis]), run[i]};
    mci_sort_keyed(s->sweep, count);
    for (size_t i = 0; i < count; i++) {
        uint32_t t = s->sweep[i].ref;
        s->swept[i] = (swept){box[6 * (size_t)t + *axis], box[6 * (size_t)t + *axis + 3], t,
                              s->patch[t]};
    }
    return count;
}

/* Tests pair t < u (one whose boxes meet along the sweep axis); true when it crosses and
 * the test is to stop. *first keeps the least crossing pair (the one a loop over the
 * bucket's pairs in index order meets first). */
static bool test_pair(test_state *s, const grid *g, const double *box, const buckets *k,
                      uint32_t b, uint32_t t, uint32_t u, uint64_t *first)
{
    uint64_t key = (uint64_t)t << 32 | u;
    if (!needs_test(s, t, u) || !boxes_meet(box + 6 * (size_t)t, box + 6 * (size_t)u) ||
        !pair_belongs_here(g, box + 6 * (size_t)t, box + 6 * (size_t)u, b, k->mask) ||
        (!s->collect && key > *first))
        return false;
    s->stats.pairs_tested++;
    if (apart(s, t, u) || !mci_triangles_cross(s->m, t, u))
        return false;
    if (key < *first)
        *first = key;
    return s->collect && !keep_pair(s, t, u);
}

/* Tests the pairs of bucket b; true when a pair crosses (when collecting: only when the
 * list could not grow; the pairs are in s->found). The pairs whose boxes meet come from a
 * sweep along one axis: buckets of long thin triangles hold thousands, and looping over
 * all their pairs took 70 steps per pair tested (35 million on a turned
 * Menger sponge). */
static bool test_bucket(test_state *s, const grid *g, const double *box, const buckets *k,
                        uint32_t b, uint32_t example[2])
{
    const uint32_t *run = k->tri + k->start[b];
    size_t n = k->start[b + 1] - k->start[b], i = 1, count;
    uint64_t first = UINT64_MAX;
    int axis;
    while (i < n && s->patch[run[i]] == s->patch[run[0]])
        i++;
    if (i == n && s->proven[s->patch[run[0]]])
        return false; /* inside one proven patch */
    count = sort_for_sweep(s, box, run, n, &axis);
    for (i = 0; i < count; i++) {
        const swept *x = &s->swept[i];
        bool own_proven = s->proven[x->patch];
        for (const swept *y = x + 1; y < s->swept + count && y->lo <= x->hi; y++) {
            uint32_t t = x->tri < y->tri ? x->tri : y->tri, u = x->tri ^ y->tri ^ t;
            if ((y->patch != x->patch || !own_proven) &&
                test_pair(s, g, box, k, b, t, u, &first))
                return true;
        }
    }
    if (first == UINT64_MAX)
        return false;
    if (example[0] == MCI_NONE)
        example[0] = (uint32_t)(first >> 32), example[1] = (uint32_t)first;
    return !s->collect;
}

/* The buckets of the count entries: each triangle's cells' buckets listed in turn
 * (bucket_of), counted, and the triangles placed (a counting sort, stable). */
static void fill_buckets(const test_state *s, const grid *g, const double *box,
                         uint32_t *bucket_of, buckets *k)
{
    size_t e = 0;
    for (uint32_t t = 0; t < s->m->triangle_count; t++) {
        uint32_t lo[3], hi[3];
        for (int a = 0; a < 3; a++)
            lo[a] = cell_of(g, box[6 * (size_t)t + a], a),
            hi[a] = cell_of(g, box[6 * (size_t)t + a + 3], a);
        for (uint32_t x = lo[0]; x <= hi[0]; x++)
            for (uint32_t y = lo[1]; y <= hi[1]; y++)
                for (uint32_t z = lo[2]; z <= hi[2]; z++) {
                    uint32_t b = cell_hash(x, y, z) & k->mask;
                    bucket_of[e++] = b;
                    k->start[b + 1]++;
                }
    }
    for (uint32_t b = 0; b <= k->mask; b++)
        k->start[b + 1] += k->start[b];
    e = 0;
    for (uint32_t t = 0; t < s->m->triangle_count; t++) {
        size_t cells = 1;
        for (int a = 0; a < 3; a++)
            cells *= 1 + (size_t)(cell_of(g, box[6 * (size_t)t + a + 3], a) -
                                  cell_of(g, box[6 * (size_t)t + a], a));
        for (size_t c = 0; c < cells; c++)
            k->tri[k->start[bucket_of[e++]]++] = t;
    }
    for (uint32_t b = k->mask + 1; b > 0; b--) /* start[b] was advanced to start[b + 1] */
        k->start[b] = k->start[b - 1];
    k->start[0] = 0;
}

static size_t largest_bucket(const buckets *k)
{
    size_t largest = 0;
    for (uint32_t b = 0; b <= k->mask; b++)
        largest = k->start[b + 1] - k->start[b] > largest ? k->start[b + 1] - k->start[b]
                                                           : largest;
    return largest;
}

/* Triangle t's box in the other mesh, grown by the margin (rounded outward: a whole unit
 * in the last place beyond the rounded sum). */
static void grown_box(const mci_crossing_boxes *b, uint32_t t, double box[6])
{
    triangle_box(b->mesh, t, box);
    for (int k = 0; k < 3; k++) {
        box[k] = nextafter(box[k] - b->margin, -INFINITY);
        box[k + 3] = nextafter(box[k + 3] + b->margin, INFINITY);
    }
}

/* Every pair that no proven patch covers, through the grid. */
static mcsg_status test_remaining_pairs(test_state *s, const mci_crossing_boxes *boxes,
                                        bool *crosses, uint32_t example[2], mcsg_error *err)
{
    size_t n = s->m->triangle_count, count;
    double *box = mci_malloc_array(s->ctx, n, 6 * sizeof *box);
    uint32_t *bucket_of = NULL;
    buckets k = {1, NULL, NULL};
    grid g;
    mcsg_status st = MCSG_OK;
    if (box) {
        for (uint32_t t = 0; t < n; t++) {
            if (boxes)
                grown_box(boxes, t, box + 6 * (size_t)t);
            else
                triangle_box(s->m, t, box + 6 * (size_t)t);
        }
        count = choose_grid(s, box, 8 * n + 1024, &g);
        while (k.mask < count && k.mask < UINT32_MAX / 4)
            k.mask = 2 * k.mask + 1;
        bucket_of = mci_malloc_array(s->ctx, count, sizeof *bucket_of);
        k.tri = mci_malloc_array(s->ctx, count, sizeof *k.tri);
        k.start = mci_calloc_array(s->ctx, (size_t)k.mask + 2, sizeof *k.start);
    }
    if (box && bucket_of && k.tri && k.start) {
        fill_buckets(s, &g, box, bucket_of, &k);
        size_t largest = largest_bucket(&k) + 1;
        s->sweep = mci_malloc_array(s->ctx, largest, sizeof *s->sweep);
        s->swept = mci_malloc_array(s->ctx, largest, sizeof *s->swept);
        s->planes = mci_malloc_array(s->ctx, n, sizeof *s->planes);
        s->plane_ready = mci_calloc_array(s->ctx, n, 1);
    }
    if (!box || !bucket_of || !k.tri || !k.start || !s->sweep || !s->swept || !s->planes ||
        !s->plane_ready) {
        st = mci_fail_nomem(err, "testing the leaves for self-intersections");
    } else {
        s->stats.grid_entries = count;
        for (uint32_t b = 0; b <= k.mask && !*crosses; b++)
            if (k.start[b + 1] - k.start[b] > 1)
                *crosses = test_bucket(s, &g, box, &k, b, example);
        *crosses = *crosses || s->found_count > 0;
        if (s->nomem)
            st = mci_fail_nomem(err, "listing the pairs of triangles that cross");
    }
    mci_free(s->ctx, box);
    mci_free(s->ctx, bucket_of);
    mci_free(s->ctx, k.tri);
    mci_free(s->ctx, k.start);
    return st;
}

static void free_state(test_state *s)
{
    mci_free(s->ctx, s->facing);
    mci_free(s->ctx, s->patch);
    mci_free(s->ctx, s->by_patch);
    mci_free(s->ctx, s->patch_first);
    mci_free(s->ctx, s->patch_size);
    mci_free(s->ctx, s->proven);
    mci_free(s->ctx, s->seg_of);
    mci_free(s->ctx, s->segs);
    mci_free(s->ctx, s->order);
    mci_free(s->ctx, s->scratch);
    mci_free(s->ctx, s->prev);
    mci_free(s->ctx, s->pinch);
    mci_free(s->ctx, s->sweep);
    mci_free(s->ctx, s->swept);
    mci_free(s->ctx, s->planes);
    mci_free(s->ctx, s->plane_ready);
}

enum { SPLIT_MIN = 32 };

/* Splits patch p in two halves of its run (by_patch lists a patch in breadth-first
 * order, so each half is a compact piece): the second becomes a new patch. A patch need
 * not be connected for its proof. */
static void split_patch(test_state *s, uint32_t p)
{
    uint32_t q = s->patch_count++, half = s->patch_size[p] / 2;
    s->patch_first[q] = s->patch_first[p] + half;
    s->patch_size[q] = s->patch_size[p] - half;
    s->patch_size[p] = half;
    for (uint32_t i = 0; i < s->patch_size[q]; i++)
        s->patch[s->by_patch[s->patch_first[q] + i]] = q;
}

/* Facings, patches, and their proofs; a large patch that is not proven (it overlaps
 * itself seen along its axis, or its boundary is too tangled) is split in halves, which
 * are tried in turn. */
static mcsg_status prove_patches(test_state *s, mcsg_error *err)
{
    const mcsg_mesh *m = s->m;
    bool nomem = false;
    for (uint32_t t = 0; t < m->triangle_count; t++)
        s->facing[t] = facing_of(corner(m, t, 0), corner(m, t, 1), corner(m, t, 2));
    find_patches(s);
    for (uint32_t p = 0; p < s->patch_count && !nomem;) {
        s->proven[p] = prove_patch(s, p, &nomem);
        if (!s->proven[p] && s->patch_size[p] >= SPLIT_MIN && !nomem) {
            split_patch(s, p);
            continue;
        }
        s->stats.proven_patches += s->proven[p] && s->patch_size[p] > 1;
        s->stats.proven_triangles += s->proven[p] && s->patch_size[p] > 1 ? s->patch_size[p] : 0;
        p++;
    }
    s->stats.patches = s->patch_count;
    return nomem ? mci_fail_nomem(err, "testing the leaves for self-intersections") : MCSG_OK;
}

mcsg_status mci_find_shell_crossing(const mci_ctx *ctx, const mcsg_mesh *m,
                                    const uint32_t *shell, const uint32_t *twin,
                                    bool *crosses, uint32_t example[2],
                                    mci_shell_crossing_stats *stats, mcsg_error *err)
{
    return mci_find_shell_crossing_boxed(ctx, m, shell, twin, NULL, crosses, example, stats,
                                         err);
}

static mcsg_status run_test(test_state *s, const mcsg_mesh *m, const uint32_t *shell,
                            const uint32_t *twin, const mci_crossing_boxes *boxes,
                            bool *crosses, uint32_t example[2],
                            mci_shell_crossing_stats *stats, mcsg_error *err);

mcsg_status mci_list_shell_crossings(const mci_ctx *ctx, const mcsg_mesh *m,
                                     const uint32_t *twin, const mci_crossing_boxes *boxes,
                                     uint64_t **pairs, size_t *count, mcsg_error *err)
{
    test_state s;
    bool crosses;
    uint32_t example[2];
    mcsg_status st;
    memset(&s, 0, sizeof s);
    s.ctx = ctx;
    s.collect = true;
    st = run_test(&s, m, NULL, twin, boxes, &crosses, example, NULL, err);
    *pairs = NULL;
    *count = 0;
    if (st == MCSG_OK && s.found_count) {
        mci_sort_u64(s.found, s.found_count);
        *pairs = s.found;
        *count = s.found_count;
        s.found = NULL;
    }
    mci_free(ctx, s.found);
    return st;
}

mcsg_status mci_find_shell_crossing_boxed(const mci_ctx *ctx, const mcsg_mesh *m,
                                          const uint32_t *shell, const uint32_t *twin,
                                          const mci_crossing_boxes *boxes, bool *crosses,
                                          uint32_t example[2],
                                          mci_shell_crossing_stats *stats, mcsg_error *err)
{
    test_state s;
    memset(&s, 0, sizeof s);
    s.ctx = ctx;
    return run_test(&s, m, shell, twin, boxes, crosses, example, stats, err);
}

/* The test on s (zeroed but for ctx and collect). */
static mcsg_status run_test(test_state *s, const mcsg_mesh *m, const uint32_t *shell,
                            const uint32_t *twin, const mci_crossing_boxes *boxes,
                            bool *crosses, uint32_t example[2],
                            mci_shell_crossing_stats *stats, mcsg_error *err)
{
    const mci_ctx *ctx = s->ctx;
    size_t n = m->triangle_count;
    mcsg_status st;
    *crosses = false;
    example[0] = example[1] = MCI_NONE;
    if (n == 0)
        return MCSG_OK;
    if (n > UINT32_MAX / 3)
        return mci_fail(err, MCSG_ERR_LIMIT, "mesh too large to test for self-intersections");
    s->m = m, s->shell = shell, s->twin = twin;
    s->facing = mci_malloc_array(ctx, n, 1);
    s->patch = mci_malloc_array(ctx, n, sizeof *s->patch);
    s->by_patch = mci_malloc_array(ctx, n, sizeof *s->by_patch);
    s->patch_first = mci_malloc_array(ctx, n, sizeof *s->patch_first);
    s->patch_size = mci_malloc_array(ctx, n, sizeof *s->patch_size);
    s->proven = mci_malloc_array(ctx, n, 1);
    s->seg_of = mci_malloc_array(ctx, n, 3 * sizeof *s->seg_of);
    if (!s->facing || !s->patch || !s->by_patch || !s->patch_first || !s->patch_size ||
        !s->proven || !s->seg_of)
        st = mci_fail_nomem(err, "testing the leaves for self-intersections");
    else
        st = prove_patches(s, err);
    if (st == MCSG_OK)
        st = test_remaining_pairs(s, boxes, crosses, example, err);
    if (stats)
        *stats = s->stats;
    free_state(s);
    return st;
}
