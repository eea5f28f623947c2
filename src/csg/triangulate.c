/*
 * Constrained triangulation of a face with exact predicates only.
 *
 *   1. Points are inserted one by one in Morton order of their approximate positions
 *      (so consecutive points are close and walks are short). Each is located by the
 *      remembering stochastic walk (Devillers, Pion, Teillaud, "Walking in a
 *      triangulation", 2002), which terminates in any triangulation, Delaunay or not,
 *      and splits the triangle (1 -> 3) or the edge (2 -> 4, or 1 -> 2 on the boundary)
 *      it lies in. In faces with many points (FLIPPED_INSERTION_POINTS), the edges
 *      opposite the new point are then flipped while a rough circle test in doubles
 *      prefers the other diagonal (Lawson's flips, make_delaunayish), so that edges stay
 *      short and the walks and the recovery below stay local.
 *   2. Each constraint edge is recovered by edge flips (Sloan, "A fast algorithm for
 *      generating constrained Delaunay triangulations", 1993, without the Delaunay
 *      step): the edges it crosses are queued, and a queued edge whose quadrilateral is
 *      strictly convex is flipped; the new diagonal is queued again if it still crosses.
 *
 * No exact incircle test is needed: the result only has to tile the face exactly, and
 * the orientation test on implicit points (mci_orient2d_projected) is the only
 * predicate. The rough circle test only chooses between two valid diagonals.
 * New edges never contain a point in their interior: an inserted point's edges lie
 * inside the triangle it split, and a flipped diagonal inside a convex quadrilateral.
 *
 * Notation: triangle t has vertices v[0..2] counter-clockwise in the face's
 * orientation; "edge i" is the edge opposite v[i], from v[i+1] to v[i+2]; n[i] is the
 * triangle across edge i (NONE on the face's boundary).
 */
#include "csg/triangulate.h"
#include "base/sort.h"
#include "csg/point_values.h"

#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

typedef struct tri {
    uint32_t v[3];
    uint32_t n[3];
    uint8_t fixed; /* bit i: edge i is a constraint */
} tri;

typedef struct queued_edge {
    uint32_t u, w;  /* the edge's end points */
    uint32_t t;     /* a triangle that had it when queued (checked before use) */
} queued_edge;

typedef struct cdt {
    const mci_ctx *ctx;
    const mci_cdt_input *in;
    tri *t;
    size_t count;
    uint32_t *vt; /* a triangle incident to each inserted point */
    double (*box)[3]; /* each point's projected box (mci_point_projected_box) */
    uint64_t *order; /* insertion order (see insertion_order) */
    void *block;  /* box, order, t and vt in one allocation (or the caller's stack) */
    uint64_t rng;
    queued_edge *queue;
    size_t queue_head, queue_len, queue_cap;
    bool block_on_heap, queue_on_heap;
} cdt;

/* Most faces have a handful of points: their scratch lives on mci_triangulate's stack
 * (4 KiB and 1.5 KiB), which saves two allocations and frees per face. */
enum { STACK_BLOCK_WORDS = 512, STACK_QUEUE_EDGES = 128 };

static int next3(int i)
{
    return i == 2 ? 0 : i + 1;
}

static int prev3(int i)
{
    return i == 0 ? 2 : i - 1;
}

/* orient2d on the values the caller's table (see csg/point_values.h) holds already,
 * MCI_UNCERTAIN where one is missing or they do not decide. *near_trouble tells whether
 * values are worth computing should the cheap stages fail too: as for the thread's table
 * of exact points (FILL_NEAR_TROUBLE in exact/kernel.c), only near crowds of nearly
 * coincident points, where one of the three is ill-conditioned or has its values
 * already. Elsewhere the double-double stage on the points' definitions decides at a
 * fraction of the cost of computing three points. */
static int orient_known_dd(const cdt *c, uint32_t a, uint32_t b, uint32_t p,
                           bool *near_trouble)
{
    const mci_cdt_input *in = c->in;
    const uint32_t at[3] = {a, b, p};
    const double *v[3];
    bool all = true;
    *near_trouble = false;
    for (int k = 0; k < 3; k++) {
        v[k] = mci_point_values_known(in->values, in->ids[at[k]]);
        all &= v[k] != NULL;
        *near_trouble |= v[k] != NULL || in->points[at[k]]->ill_conditioned;
    }
    return all ? mci_orient2d_dd_values(v[0], v[1], v[2], in->axis) : MCI_UNCERTAIN;
}

/* The same on values computed where the table lacks them. */
static int orient_computed_dd(const cdt *c, uint32_t a, uint32_t b, uint32_t p)
{
    const mci_cdt_input *in = c->in;
    const uint32_t at[3] = {a, b, p};
    double scratch[3][3][3];
    const double *v[3];
    for (int k = 0; k < 3; k++)
        if (!(v[k] = mci_point_values_get(in->values, in->ids[at[k]], in->points[at[k]],
                                          scratch[k])))
            return MCI_UNCERTAIN;
    return mci_orient2d_dd_values(v[0], v[1], v[2], in->axis);
}

/* The quick filter first: it decides most calls, and never where the points are known
 * to be collinear (it does not return 0). With a table of point values, values known
 * already decide next (crowds of nearly coincident points meet the same orientations
 * again and again, where the double filter fails), then the stages that compute no
 * exact point, then the values computed near trouble. */
static int orient(const cdt *c, uint32_t a, uint32_t b, uint32_t p)
{
    const mci_cdt_input *in = c->in;
    const mci_point *const *pts = in->points;
    int s = mci_orient2d_boxes(c->box[a], c->box[b], c->box[p]);
    bool near_trouble;
    if (s != MCI_UNCERTAIN)
        return in->sign * s;
    if (in->known_collinear && in->known_collinear(in->user, a, b, p))
        return 0;
    if (in->values) {
        s = orient_known_dd(c, a, b, p, &near_trouble);
        if (s == MCI_UNCERTAIN)
            s = mci_orient2d_projected_cheap(pts[a], pts[b], pts[p], in->axis);
        if (s == MCI_UNCERTAIN && near_trouble)
            s = orient_computed_dd(c, a, b, p);
        if (s != MCI_UNCERTAIN)
            return in->sign * s;
    }
    return in->sign * mci_orient2d_projected_rest(pts[a], pts[b], pts[p], in->axis);
}

static int vertex_index(const tri *t, uint32_t v)
{
    return t->v[0] == v ? 0 : t->v[1] == v ? 1 : t->v[2] == v ? 2 : -1;
}

/* Index of the edge from u to w in t (directed), or -1. */
static int edge_index(const tri *t, uint32_t u, uint32_t w)
{
    int i = vertex_index(t, u);
    return i >= 0 && t->v[next3(i)] == w ? prev3(i) : -1;
}

/* edge_index for an edge that the adjacency invariant guarantees (the edge of a
 * neighbour across a known edge); never -1, so that indexing stays in bounds. */
static int known_edge(const tri *t, uint32_t u, uint32_t w)
{
    int i = edge_index(t, u, w);
    return i < 0 ? 0 : i;
}

static uint32_t random_below(cdt *c, uint32_t n)
{
    c->rng ^= c->rng << 13;
    c->rng ^= c->rng >> 7;
    c->rng ^= c->rng << 17;
    return (uint32_t)(c->rng % n);
}

/* Edge i of fresh triangle t lies against triangle s (NONE on the face's boundary),
 * which is not being rebuilt: link both ways; the constraint flag is s's (a triangle on
 * the boundary side keeps none, as nothing reads it there). */
static void link_outer(cdt *c, uint32_t t, int i, uint32_t s)
{
    tri *a = &c->t[t];
    a->n[i] = s;
    if (s != NONE) {
        int j = known_edge(&c->t[s], a->v[prev3(i)], a->v[next3(i)]);
        c->t[s].n[j] = t;
        a->fixed |= (uint8_t)(((c->t[s].fixed >> j) & 1) << i);
    }
}

/* Edge i of fresh triangle t and edge j of fresh triangle s are the same edge. */
static void link_fresh(cdt *c, uint32_t t, int i, uint32_t s, int j)
{
    c->t[t].n[i] = s;
    c->t[s].n[j] = t;
}

static void set_triangle(cdt *c, uint32_t t, uint32_t a, uint32_t b, uint32_t d)
{
    c->t[t] = (tri){{a, b, d}, {NONE, NONE, NONE}, 0};
}

/* p inside t = (v0, v1, v2): t becomes (v0, v1, p), and (v1, v2, p), (v2, v0, p) are
 * added; the edge opposite p in each is an old edge of t. */
static void split_triangle(cdt *c, uint32_t t, uint32_t p)
{
    tri old = c->t[t];
    uint32_t t1 = (uint32_t)c->count, t2 = (uint32_t)c->count + 1;
    c->count += 2;
    set_triangle(c, t, old.v[0], old.v[1], p);
    set_triangle(c, t1, old.v[1], old.v[2], p);
    set_triangle(c, t2, old.v[2], old.v[0], p);
    link_fresh(c, t, 0, t1, 1);
    link_fresh(c, t, 1, t2, 0);
    link_fresh(c, t1, 0, t2, 1);
    link_outer(c, t, 2, old.n[2]);
    link_outer(c, t1, 2, old.n[0]);
    link_outer(c, t2, 2, old.n[1]);
    c->vt[old.v[0]] = c->vt[old.v[1]] = c->vt[p] = t;
    c->vt[old.v[2]] = t1;
}

/* p lies inside edge i of t = (x, u, w) (edge u-w): t becomes (x, u, p) and (x, p, w) is
 * added; the triangle s = (y, w, u) across, if any, becomes (y, w, p) and (y, p, u) is
 * added. Returns s (NONE on the face's boundary). */
static uint32_t split_edge(cdt *c, uint32_t t, int i, uint32_t p)
{
    tri ot = c->t[t];
    uint32_t x = ot.v[i], u = ot.v[next3(i)], w = ot.v[prev3(i)], s = ot.n[i];
    uint32_t t1 = (uint32_t)c->count++;
    set_triangle(c, t, x, u, p);
    set_triangle(c, t1, x, p, w);
    link_fresh(c, t, 1, t1, 2);
    link_outer(c, t, 2, ot.n[prev3(i)]);
    link_outer(c, t1, 1, ot.n[next3(i)]);
    c->vt[x] = c->vt[u] = c->vt[p] = t;
    c->vt[w] = t1;
    if (s != NONE) {
        tri os = c->t[s];
        int j = known_edge(&os, w, u);
        uint32_t y = os.v[j], s1 = (uint32_t)c->count++;
        set_triangle(c, s, y, w, p);
        set_triangle(c, s1, y, p, u);
        link_fresh(c, t, 0, s1, 0);
        link_fresh(c, t1, 0, s, 0);
        link_fresh(c, s, 1, s1, 2);
        link_outer(c, s, 2, os.n[prev3(j)]);
        link_outer(c, s1, 1, os.n[next3(j)]);
        c->vt[y] = s;
    }
    return s;
}

/* The triangle around u after t, turning counter-clockwise (ccw) or clockwise. */
static uint32_t fan_step(const cdt *c, uint32_t t, uint32_t u, bool ccw)
{
    int iu = vertex_index(&c->t[t], u);
    return c->t[t].n[ccw ? next3(iu) : prev3(iu)];
}

/* Flip edge i of t = (x, u, w) (edge u-w) with s = (y, w, u) across: t becomes
 * (x, u, y) and s becomes (y, w, x). */
static void flip(cdt *c, uint32_t t, int i)
{
    tri ot = c->t[t];
    uint32_t s = ot.n[i];
    tri os = c->t[s];
    uint32_t x = ot.v[i], u = ot.v[next3(i)], w = ot.v[prev3(i)];
    int j = known_edge(&os, w, u);
    uint32_t y = os.v[j];
    set_triangle(c, t, x, u, y);
    set_triangle(c, s, y, w, x);
    link_fresh(c, t, 1, s, 1);
    link_outer(c, t, 0, os.n[next3(j)]);
    link_outer(c, t, 2, ot.n[prev3(i)]);
    link_outer(c, s, 0, ot.n[next3(i)]);
    link_outer(c, s, 2, os.n[prev3(j)]);
    c->vt[x] = c->vt[u] = t;
    c->vt[y] = c->vt[w] = s;
}

static bool push_edge(cdt *c, uint32_t u, uint32_t w, uint32_t t)
{
    if (c->queue_head + c->queue_len == c->queue_cap) {
        if (c->queue_head > 0) {
            memmove(c->queue, c->queue + c->queue_head, c->queue_len * sizeof *c->queue);
            c->queue_head = 0;
        } else {
            size_t cap = 2 * c->queue_cap;
            queued_edge *q = c->queue_on_heap
                                 ? mci_realloc_array(c->ctx, c->queue, cap, sizeof *q)
                                 : mci_malloc_array(c->ctx, cap, sizeof *q);
            if (!q)
                return false;
            if (!c->queue_on_heap)
                memcpy(q, c->queue, c->queue_len * sizeof *q);
            c->queue = q;
            c->queue_cap = cap;
            c->queue_on_heap = true;
        }
    }
    c->queue[c->queue_head + c->queue_len++] = (queued_edge){u, w, t};
    return true;
}

/* Whether d lies inside the circle through p, a, b (counter-clockwise in the face),
 * judged on the projected boxes' centres in doubles. Only a preference: it picks which
 * diagonal of a convex quadrilateral to keep, and every flip it asks for is checked
 * exactly (make_delaunayish), so a wrong answer costs quality, never validity. */
static bool roughly_in_circle(const cdt *c, uint32_t p, uint32_t a, uint32_t b, uint32_t d)
{
    const double *P = c->box[p], *A = c->box[a], *B = c->box[b], *D = c->box[d];
    double px = P[0] - D[0], py = P[1] - D[1], ax = A[0] - D[0], ay = A[1] - D[1];
    double bx = B[0] - D[0], by = B[1] - D[1];
    double det = (px * px + py * py) * (ax * by - bx * ay) -
                 (ax * ax + ay * ay) * (px * by - bx * py) +
                 (bx * bx + by * by) * (px * ay - ax * py);
    return c->in->sign * det > 0;
}

/* At most this many flips per inserted point. Inside a round hole the corners and the
 * points where the walls' diagonals cross the plate lie on or just inside one circle,
 * and every new corner flipped its way across the hole: several times the flips per
 * point of random points. Six keep the edges local where it matters (a plate with round
 * holes gains more than one with square holes loses, against no limit). */
enum { FLIPS_PER_POINT = 6 };

/* After p was inserted: flip the edges opposite p while the point across lies in the
 * circle of p's triangle (Lawson), so that the triangulation stays close to Delaunay.
 * Without this, early points kept long edges across the whole face: a plate with
 * thousands of holes had every hole's edges crossed by dozens of them, and the walks
 * and constraint recovery went quadratic. Each flip adds an edge at p, and edges at p
 * are never flipped here, so the loop ends whatever the rough test says (and
 * FLIPS_PER_POINT ends it sooner); a flip is made only where the quadrilateral is
 * strictly convex (exact tests). No constraint exists yet while points are inserted. */
static bool make_delaunayish(cdt *c, uint32_t p)
{
    int flips = 0;
    while (c->queue_len > 0 && flips < FLIPS_PER_POINT) {
        queued_edge e = c->queue[c->queue_head + --c->queue_len];
        uint32_t t = e.t, s, a, b, d;
        int i = vertex_index(&c->t[t], p);
        if (i < 0 || (s = c->t[t].n[i]) == NONE)
            continue;
        a = c->t[t].v[next3(i)];
        b = c->t[t].v[prev3(i)];
        d = c->t[s].v[known_edge(&c->t[s], b, a)];
        if (!roughly_in_circle(c, p, a, b, d) || orient(c, p, d, a) * orient(c, p, d, b) >= 0)
            continue;
        flip(c, t, i); /* t = (p, a, d), s = (d, b, p) */
        flips++;
        if (!push_edge(c, p, d, t) || !push_edge(c, d, p, s))
            return false;
    }
    c->queue_len = 0;
    return true;
}

/* Queue the triangles of the point just inserted for make_delaunayish: t, which it
 * split, `across` (the triangle split on the far side of an edge, or NONE) and those
 * the split added from `first` on. */
static bool queue_new_triangles(cdt *c, uint32_t p, uint32_t t, uint32_t across, size_t first)
{
    bool ok = push_edge(c, p, p, t) && (across == NONE || push_edge(c, p, p, across));
    for (size_t k = first; ok && k < c->count; k++)
        ok = push_edge(c, p, p, (uint32_t)k);
    return ok;
}

/* Find the triangle containing p by the remembering stochastic walk from `t`. On
 * success *edge is -1 (p inside t) or the edge of t that p lies on. */
static mcsg_status locate(cdt *c, uint32_t p, uint32_t t, uint32_t *found, int *edge,
                          mcsg_error *err)
{
    uint32_t prev = NONE;
    for (size_t steps = 0; steps <= 64 * c->count + 1024; steps++) {
        const tri *tr = &c->t[t];
        int start = (int)random_below(c, 3), side[3], zeros = 0, moved = 0;
        for (int k = 0; k < 3 && !moved; k++) {
            int i = (start + k) % 3;
            side[i] = prev != NONE && tr->n[i] == prev
                          ? 1 /* p was strictly beyond that edge as seen from prev */
                          : orient(c, tr->v[next3(i)], tr->v[prev3(i)], p);
            if (side[i] < 0) {
                if (tr->n[i] == NONE)
                    return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: a point lies "
                                    "outside its face");
                prev = t;
                t = tr->n[i];
                moved = 1;
            }
        }
        if (moved)
            continue;
        *found = t;
        *edge = -1;
        for (int i = 0; i < 3; i++)
            if (side[i] == 0)
                zeros++, *edge = i;
        if (zeros > 1)
            return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: coincident points");
        return MCSG_OK;
    }
    return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: point location did not end");
}

/* The 16 low bits of x, spread to the even bit positions. */
static uint32_t spread_bits(uint32_t x)
{
    x &= 0xffffu;
    x = (x | x << 8) & 0x00ff00ffu;
    x = (x | x << 4) & 0x0f0f0f0fu;
    x = (x | x << 2) & 0x33333333u;
    return (x | x << 1) & 0x55555555u;
}

/* Interleave the bits of two 16-bit values (x in the even positions). */
static uint32_t morton(uint32_t x, uint32_t y)
{
    return spread_bits(x) | spread_bits(y) << 1;
}

/* Quantised position of a point in the face's bounding box (only orders the insertion:
 * any order gives a valid triangulation). */
static uint32_t insertion_key(const mci_cdt_input *in, const double lo[2],
                              const double span[2], uint32_t p)
{
    double x[3], q[2];
    uint32_t cell[2];
    mci_point_approx(in->points[p], x);
    q[0] = x[(in->axis + 1) % 3];
    q[1] = x[(in->axis + 2) % 3];
    for (int k = 0; k < 2; k++) {
        double f = span[k] > 0 ? (q[k] - lo[k]) / span[k] : 0;
        f = f > 0 ? (f < 1 ? f : 1) : 0; /* also maps NaN to 0 */
        cell[k] = (uint32_t)(f * 65535.0);
    }
    return morton(cell[0], cell[1]);
}

/* Fills order[0..insert_count) with the insertion order (key << 32 | index). */
static void insertion_order(const mci_cdt_input *in, uint64_t *order)
{
    double lo[2] = {0, 0}, hi[2] = {0, 0}, span[2];
    for (int i = 0; i < 3; i++) {
        double x[3];
        mci_point_approx(in->points[i], x);
        for (int k = 0; k < 2; k++) {
            double q = x[(in->axis + 1 + k) % 3];
            lo[k] = i == 0 || q < lo[k] ? q : lo[k];
            hi[k] = i == 0 || q > hi[k] ? q : hi[k];
        }
    }
    span[0] = hi[0] - lo[0];
    span[1] = hi[1] - lo[1];
    for (size_t i = 0; i < in->insert_count; i++)
        order[i] = (uint64_t)insertion_key(in, lo, span, in->insert[i]) << 32 | i;
    mci_sort_u64(order, in->insert_count);
}

/* Faces with fewer points to insert keep the plain insertion: their walks and recovery
 * stay short, and the circle tests and their flips would cost more than they save
 * (as on the dense scenes when every face had them). From 64 points on, the benchmark
 * scenes cost about as much as with no flips at all (cylinder_28_holes +0.65%), and the
 * plates with grids of holes keep the whole gain. The bound was 128, but faces of 64 to
 * 127 points, full of slivers, then made 90% of a Menger sponge export's orientation
 * tests (14 per point inserted, 29 per constraint recovered, against 4.6 and 2.2 on the
 * cylinder plate); 64 takes 16% off its instructions. */
enum { FLIPPED_INSERTION_POINTS = 64 };

static mcsg_status insert_points(cdt *c, mcsg_error *err)
{
    uint32_t last = 0;
    mcsg_status st = MCSG_OK;
    insertion_order(c->in, c->order);
    for (size_t k = 0; st == MCSG_OK && k < c->in->insert_count; k++) {
        uint32_t p = c->in->insert[(uint32_t)c->order[k]], t = 0, across = NONE;
        size_t first = c->count;
        int edge = -1;
        if (p >= c->in->point_count || c->vt[p] != NONE) {
            st = mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: bad point id %u", p);
            break;
        }
        st = locate(c, p, c->vt[last], &t, &edge, err);
        if (st != MCSG_OK)
            break;
        if (edge < 0)
            split_triangle(c, t, p);
        else
            across = split_edge(c, t, edge, p);
        if (c->in->insert_count >= FLIPPED_INSERTION_POINTS &&
            (!queue_new_triangles(c, p, t, across, first) || !make_delaunayish(c, p)))
            st = mci_fail_nomem(err, "triangulating a face");
        last = p;
    }
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Constraint recovery                                                                 */

/* What find_around looks for in the triangle t = (u, q, r) around u. FAN_SEES_ROUGHLY
 * is FAN_SEES tested exactly only where a rough test in doubles (the projected boxes'
 * centres, borders included) agrees: it may miss, never finds a wrong triangle. */
typedef enum fan_goal { FAN_HAS_EDGE, FAN_SEES, FAN_SEES_ROUGHLY } fan_goal;

/* Whether the direction from u to w lies within the angle q-u-r, roughly. */
static bool roughly_sees(const cdt *c, uint32_t u, uint32_t q, uint32_t r, uint32_t w)
{
    const double *U = c->box[u], *Q = c->box[q], *R = c->box[r], *W = c->box[w];
    double wx = W[0] - U[0], wy = W[1] - U[1];
    double to_q = (Q[0] - U[0]) * wy - (Q[1] - U[1]) * wx;
    double to_r = (R[0] - U[0]) * wy - (R[1] - U[1]) * wx;
    return c->in->sign * to_q >= 0 && c->in->sign * to_r <= 0;
}

static bool fan_match(const cdt *c, uint32_t t, uint32_t u, uint32_t w, fan_goal goal)
{
    const tri *tr = &c->t[t];
    int iu = vertex_index(tr, u);
    uint32_t q = tr->v[next3(iu)], r = tr->v[prev3(iu)];
    if (q == w || r == w)
        return true;
    if (goal == FAN_HAS_EDGE || (goal == FAN_SEES_ROUGHLY && !roughly_sees(c, u, q, r, w)))
        return false;
    /* w strictly inside the angle q-u-r: the segment u w leaves through edge q r. */
    return orient(c, u, q, w) > 0 && orient(c, u, r, w) < 0;
}

/* A triangle around u that has the edge u-w, or (FAN_SEES) whose angle at u contains
 * the direction to w; NONE if there is none. */
static uint32_t find_around(const cdt *c, uint32_t u, uint32_t w, fan_goal goal)
{
    uint32_t start = c->vt[u], t = start;
    do {
        if (fan_match(c, t, u, w, goal))
            return t;
        t = fan_step(c, t, u, true);
    } while (t != NONE && t != start);
    if (t == start)
        return NONE;
    for (t = fan_step(c, start, u, false); t != NONE; t = fan_step(c, t, u, false))
        if (fan_match(c, t, u, w, goal))
            return t;
    return NONE;
}

/* find_around(FAN_SEES) where u-w is no edge. At most one triangle around u has the
 * direction to w strictly inside its angle (w is not on the line of an edge at u: no
 * point lies inside a constraint), so which one is tested first changes nothing but the
 * cost: a rough walk first tests about one triangle exactly instead of half the fan,
 * and the exact walk remains for what the rough test misses. */
static uint32_t find_seeing(const cdt *c, uint32_t u, uint32_t w)
{
    uint32_t t = find_around(c, u, w, FAN_SEES_ROUGHLY);
    return t != NONE ? t : find_around(c, u, w, FAN_SEES);
}

/* Edge index of u-w (either direction) in t, or -1. */
static int undirected_edge(const tri *t, uint32_t u, uint32_t w)
{
    int i = edge_index(t, u, w);
    return i >= 0 ? i : edge_index(t, w, u);
}

static void mark_fixed(cdt *c, uint32_t t, int i)
{
    uint32_t s = c->t[t].n[i];
    c->t[t].fixed |= (uint8_t)(1u << i);
    if (s != NONE) {
        int j = known_edge(&c->t[s], c->t[t].v[prev3(i)], c->t[t].v[next3(i)]);
        c->t[s].fixed |= (uint8_t)(1u << j);
    }
}

/* Queue the edges that the segment a-b crosses, walking from a to b. */
static mcsg_status queue_crossed_edges(cdt *c, uint32_t a, uint32_t b, uint32_t t,
                                       mcsg_error *err)
{
    int i = vertex_index(&c->t[t], a);
    /* In t = (a, q, r): q lies right of a->b, r left; the crossed edge is q-r. */
    uint32_t q = c->t[t].v[next3(i)], r = c->t[t].v[prev3(i)];
    for (;;) {
        uint32_t s = c->t[t].n[i], z;
        int j, side;
        if (!push_edge(c, q, r, t))
            return mci_fail_nomem(err, "triangulating a face");
        if (s == NONE)
            return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: constraint leaves the face");
        j = known_edge(&c->t[s], r, q);
        z = c->t[s].v[j];
        if (z == b)
            return MCSG_OK;
        side = orient(c, a, b, z);
        if (side == 0)
            return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: a point lies inside a "
                            "constraint");
        /* s = (z, r, q): the walk leaves through q-z (opposite r) or z-r (opposite q). */
        if (side > 0)
            r = z, i = next3(j);
        else
            q = z, i = prev3(j);
        t = s;
    }
}

static bool segments_cross(const cdt *c, uint32_t a, uint32_t b, uint32_t x, uint32_t y)
{
    return orient(c, a, b, x) * orient(c, a, b, y) < 0 &&
           orient(c, x, y, a) * orient(c, x, y, b) < 0;
}

/* Locate a queued edge again (flips may have moved it to other triangles). */
static bool find_queued(const cdt *c, const queued_edge *e, uint32_t *t, int *i)
{
    *t = e->t;
    if (*t < c->count && (*i = undirected_edge(&c->t[*t], e->u, e->w)) >= 0)
        return true;
    *t = find_around(c, e->u, e->w, FAN_HAS_EDGE);
    return *t != NONE && (*i = undirected_edge(&c->t[*t], e->u, e->w)) >= 0;
}

/* Flip queued edges until none crosses a-b (Sloan's loop). */
static mcsg_status flip_crossed_edges(cdt *c, uint32_t a, uint32_t b, mcsg_error *err)
{
    size_t budget = 64 * (c->queue_len + 16) * (c->queue_len + 16);
    while (c->queue_len > 0) {
        queued_edge e = c->queue[c->queue_head++];
        uint32_t t, x, y;
        int i;
        c->queue_len--;
        if (budget-- == 0 || !find_queued(c, &e, &t, &i) || c->t[t].n[i] == NONE)
            return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: constraint recovery failed");
        x = c->t[t].v[i];
        y = c->t[c->t[t].n[i]].v[known_edge(&c->t[c->t[t].n[i]], c->t[t].v[prev3(i)],
                                             c->t[t].v[next3(i)])];
        if (orient(c, x, y, e.u) * orient(c, x, y, e.w) < 0) {
            flip(c, t, i);
            if (x == a || x == b || y == a || y == b || !segments_cross(c, a, b, x, y))
                continue;
            e = (queued_edge){x, y, t};
        }
        if (!push_edge(c, e.u, e.w, e.t))
            return mci_fail_nomem(err, "triangulating a face");
    }
    c->queue_head = 0;
    return MCSG_OK;
}

static mcsg_status insert_constraint(cdt *c, uint32_t a, uint32_t b, mcsg_error *err)
{
    uint32_t t;
    int i;
    mcsg_status st;
    if (a == b || a >= c->in->point_count || b >= c->in->point_count || c->vt[a] == NONE ||
        c->vt[b] == NONE)
        return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: bad constraint %u-%u", a, b);
    /* The edge is often there already: looked for first without predicates. */
    t = find_around(c, a, b, FAN_HAS_EDGE);
    if (t == NONE)
        t = find_seeing(c, a, b);
    if (t == NONE)
        return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: constraint %u-%u not found",
                        a, b);
    if (undirected_edge(&c->t[t], a, b) < 0) {
        st = queue_crossed_edges(c, a, b, t, err);
        if (st == MCSG_OK)
            st = flip_crossed_edges(c, a, b, err);
        if (st != MCSG_OK)
            return st;
        t = find_around(c, a, b, FAN_HAS_EDGE);
        if (t == NONE)
            return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: constraint not recovered");
    }
    i = undirected_edge(&c->t[t], a, b);
    if (i < 0)
        return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: constraint not recovered");
    mark_fixed(c, t, i);
    return MCSG_OK;
}

static mcsg_status setup(cdt *c, const mci_ctx *ctx, const mci_cdt_input *in,
                         uint64_t *stack_block, queued_edge *stack_queue, mcsg_error *err)
{
    memset(c, 0, sizeof *c);
    c->ctx = ctx;
    c->in = in;
    c->rng = 0x9e3779b97f4a7c15u;
    c->queue = stack_queue;
    c->queue_cap = STACK_QUEUE_EDGES;
    if (in->point_count < 3 || in->insert_count > in->point_count)
        return mci_fail(err, MCSG_ERR_INTERNAL, "triangulation: bad point counts");
    if (in->point_count > SIZE_MAX / 64)
        return mci_fail(err, MCSG_ERR_LIMIT, "too many points in one face (%zu)",
                        in->point_count);
    /* One block: the boxes, order (64-bit keys), the triangles, vt. */
    {
        size_t tris = 1 + 2 * in->insert_count, words = in->insert_count + 1;
        size_t box_words = 3 * in->point_count;
        size_t tri_words = (tris * sizeof *c->t + sizeof *c->order - 1) / sizeof *c->order;
        size_t vt_words = (in->point_count * sizeof *c->vt + sizeof *c->order - 1) /
                          sizeof *c->order;
        size_t total = box_words + words + tri_words + vt_words;
        c->block_on_heap = total > STACK_BLOCK_WORDS;
        c->block = c->block_on_heap ? mci_malloc_array(ctx, total, sizeof *c->order) : stack_block;
        if (!c->block)
            return mci_fail_nomem(err, "triangulating a face");
        c->box = c->block;
        c->order = (uint64_t *)(void *)(c->box + in->point_count);
        c->t = (tri *)(void *)(c->order + words);
        c->vt = (uint32_t *)(void *)(c->order + words + tri_words);
    }
    for (size_t i = 0; i < in->point_count; i++) {
        c->vt[i] = i < 3 ? 0 : NONE;
        mci_point_projected_box(in->points[i], in->axis, c->box[i]);
    }
    c->t[0] = (tri){{0, 1, 2}, {NONE, NONE, NONE}, 0};
    c->count = 1;
    return MCSG_OK;
}

/* mci_cdt_output's adj entry for side i of triangle t (from v[i] to v[i + 1], which is
 * edge prev3(i) here: the edge opposite v[i + 2]). */
static uint32_t side_across(const cdt *c, uint32_t t, int i)
{
    const tri *a = &c->t[t];
    int e = prev3(i), j;
    uint32_t s = a->n[e];
    if (s == NONE)
        return NONE;
    j = edge_index(&c->t[s], a->v[next3(i)], a->v[i]); /* the same edge, reversed */
    return (uint32_t)(3 * s + (uint32_t)next3(j)) | ((a->fixed >> e) & 1 ? MCI_CDT_CONSTRAINT : 0);
}

mcsg_status mci_triangulate(const mci_ctx *ctx, const mci_cdt_input *in, mci_cdt_output *out,
                            mcsg_error *err)
{
    uint64_t stack_block[STACK_BLOCK_WORDS];
    queued_edge stack_queue[STACK_QUEUE_EDGES];
    cdt c;
    mcsg_status st = setup(&c, ctx, in, stack_block, stack_queue, err);
    if (st == MCSG_OK)
        st = insert_points(&c, err);
    for (size_t k = 0; st == MCSG_OK && k < in->edge_count; k++)
        st = insert_constraint(&c, in->edges[2 * k], in->edges[2 * k + 1], err);
    out->tris = NULL;
    out->adj = NULL;
    out->tri_count = 0;
    if (st == MCSG_OK && c.count >= MCI_CDT_CONSTRAINT / 3)
        st = mci_fail(err, MCSG_ERR_LIMIT, "too many triangles in one face (%zu)", c.count);
    if (st == MCSG_OK) {
        out->tris = mci_malloc_array(ctx, c.count, 3 * sizeof *out->tris);
        out->adj = mci_malloc_array(ctx, c.count, 3 * sizeof *out->adj);
        if (!out->tris || !out->adj) {
            mci_free(ctx, out->tris);
            mci_free(ctx, out->adj);
            out->tris = out->adj = NULL;
            st = mci_fail_nomem(err, "triangulating a face");
        }
        for (size_t k = 0; st == MCSG_OK && k < c.count; k++) {
            memcpy(out->tris + 3 * k, c.t[k].v, sizeof c.t[k].v);
            for (int i = 0; i < 3; i++)
                out->adj[3 * k + i] = side_across(&c, (uint32_t)k, i);
        }
        out->tri_count = st == MCSG_OK ? c.count : 0;
    }
    if (c.block_on_heap)
        mci_free(ctx, c.block);
    if (c.queue_on_heap)
        mci_free(ctx, c.queue);
    return st;
}
