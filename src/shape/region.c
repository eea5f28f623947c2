/*
 * Regions of the plane from outlines, and back (shape/region.h).
 *
 * From outlines: the points are merged by coordinates, every edge is split at the points
 * lying inside it (exact orientation), and edges that then occur an even number of
 * times cancel, which is the even-odd rule along shared boundaries. What remains is a
 * set of constraint edges meeting only at their ends, unless two cross, which is
 * refused. A constrained triangulation (csg/triangulate.h) of a triangle around all the
 * points inserts them; a walk over its triangles, toggling at each constraint, marks the
 * inside ones. Every decision is an exact predicate; no coordinate is computed.
 */
#include "shape/region.h"

#include "base/sort.h"
#include "base/sort_template.h"
#include "csg/triangulate.h"
#include "exact/kernel.h"
#include "exact/predicates.h"

#include <math.h>
#include <string.h>

void mci_outlines_free(const mci_ctx *ctx, mci_outlines *o)
{
    mci_free(ctx, o->xy);
    mci_free(ctx, o->ids);
    mci_free(ctx, o->loop_start);
    memset(o, 0, sizeof *o);
}

void mci_region_free(const mci_ctx *ctx, mci_region *r)
{
    mci_free(ctx, r->xy);
    mci_free(ctx, r->tris);
    mci_free(ctx, r->edges);
    memset(r, 0, sizeof *r);
}

double mci_outline_area2(const mci_outlines *o, size_t k)
{
    const double *p = o->xy + 2 * (size_t)o->loop_start[k];
    size_t n = o->loop_start[k + 1] - o->loop_start[k];
    double sum = 0;
    for (size_t i = 0; i < n; i++) {
        const double *a = p + 2 * i, *b = p + 2 * ((i + 1) % n);
        sum += a[0] * b[1] - a[1] * b[0];
    }
    return sum;
}

/* ---------------------------------------------------------------------------------- */
/* Points and edges */

typedef struct xy_point {
    double x, y;
    uint32_t id;
} xy_point;

#define XY_LESS(a, b) ((a)->x < (b)->x || ((a)->x == (b)->x && (a)->y < (b)->y))
MCI_DEFINE_SORT(sort_xy_points, xy_point, XY_LESS)

typedef struct edge_set {
    uint32_t *e; /* pairs */
    size_t count, cap;
} edge_set;

static bool add_edge(const mci_ctx *ctx, edge_set *s, uint32_t a, uint32_t b)
{
    if (!mci_grow_array(ctx, (void **)&s->e, &s->cap, 2 * (s->count + 1), sizeof *s->e, 64))
        return false;
    s->e[2 * s->count] = a;
    s->e[2 * s->count + 1] = b;
    s->count++;
    return true;
}

/* The state of one conversion: unique points (xyz, z = 0, for the triangulation's
 * explicit points) and the edges between them. */
typedef struct builder {
    const mci_ctx *ctx;
    double *xyz;      /* 3 per unique point, after the 3 corners of the big triangle */
    size_t points;    /* unique points, corners excluded */
    xy_point *sorted; /* unique points by x, then y */
    edge_set raw, kept; /* kept: in increasing mci_edge_key order */
    mci_fill_rule rule;
    uint32_t *weight;   /* MCI_FILL_POSITIVE: how many more times each kept edge is given
                           in its direction than against it */
    size_t weight_cap;
} builder;

#define PT(b, i) ((b)->xyz + 3 * ((size_t)(i) + 3))

/* Merge equal points; the edges of each loop in unique ids. */
static mcsg_status collect(builder *b, const mci_outlines *o, mcsg_error *err)
{
    const mci_ctx *ctx = b->ctx;
    size_t n = o->point_count;
    double *all = mci_malloc_array(ctx, n + 1, 3 * sizeof *all);
    uint32_t *canon = mci_malloc_array(ctx, n + 1, sizeof *canon);
    uint32_t *unique = mci_malloc_array(ctx, n + 1, sizeof *unique);
    mcsg_status st = MCSG_OK;
    b->xyz = mci_malloc_array(ctx, n + 3, 3 * sizeof *b->xyz);
    if (!all || !canon || !unique || !b->xyz)
        st = mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; st == MCSG_OK && i < n; i++) {
        all[3 * i] = o->xy[2 * i] == 0 ? 0.0 : o->xy[2 * i]; /* -0 is 0 */
        all[3 * i + 1] = o->xy[2 * i + 1] == 0 ? 0.0 : o->xy[2 * i + 1];
        all[3 * i + 2] = 0;
        if (!isfinite(all[3 * i]) || !isfinite(all[3 * i + 1]))
            st = mci_fail(err, MCSG_ERR_INVALID_ARG, "point %zu is not finite", i);
    }
    if (st == MCSG_OK && !mci_first_equal_coordinates(ctx, all, n, canon))
        st = mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; st == MCSG_OK && i < n; i++) {
        if (canon[i] == i) {
            unique[i] = (uint32_t)b->points++;
            memcpy(PT(b, unique[i]), all + 3 * i, 3 * sizeof *all);
        } else {
            unique[i] = unique[canon[i]];
        }
    }
    for (size_t k = 0; st == MCSG_OK && k < o->loop_count; k++) {
        uint32_t first = o->loop_start[k], end = o->loop_start[k + 1];
        for (uint32_t i = first; i < end; i++) {
            uint32_t u = unique[i], v = unique[i + 1 < end ? i + 1 : first];
            if (u != v && !add_edge(ctx, &b->raw, u, v)) {
                st = mci_fail_nomem(err, "making a 2D shape");
                break;
            }
        }
    }
    mci_free(ctx, all);
    mci_free(ctx, canon);
    mci_free(ctx, unique);
    return st;
}

static mcsg_status sort_points(builder *b, mcsg_error *err)
{
    b->sorted = mci_malloc_array(b->ctx, b->points + 1, sizeof *b->sorted);
    if (!b->sorted)
        return mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; i < b->points; i++) {
        b->sorted[i].x = PT(b, i)[0];
        b->sorted[i].y = PT(b, i)[1];
        b->sorted[i].id = (uint32_t)i;
    }
    sort_xy_points(b->sorted, b->points);
    return MCSG_OK;
}

/* Whether point p lies inside segment u-v (not at an end). */
static bool inside_segment(const double *u, const double *v, const double *p)
{
    if (p[0] < fmin(u[0], v[0]) || p[0] > fmax(u[0], v[0]) || p[1] < fmin(u[1], v[1]) ||
        p[1] > fmax(u[1], v[1]))
        return false;
    if ((p[0] == u[0] && p[1] == u[1]) || (p[0] == v[0] && p[1] == v[1]))
        return false;
    return mci_orient2d(u[0], u[1], v[0], v[1], p[0], p[1]) == 0;
}

/* First sorted point with x >= x0. */
static size_t first_at_x(const builder *b, double x0)
{
    size_t lo = 0, hi = b->points;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (b->sorted[mid].x < x0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Split edge u-v at every point inside it, in order from u; the pieces go to `out`. */
static bool split_edge(builder *b, uint32_t u, uint32_t v, edge_set *out, xy_point **on,
                       size_t *on_cap)
{
    const double *a = PT(b, u), *c = PT(b, v);
    size_t count = 0;
    uint32_t prev = u;
    bool forward = XY_LESS(&((xy_point){a[0], a[1], 0}), &((xy_point){c[0], c[1], 0}));
    for (size_t i = first_at_x(b, fmin(a[0], c[0]));
         i < b->points && b->sorted[i].x <= fmax(a[0], c[0]); i++) {
        if (!inside_segment(a, c, PT(b, b->sorted[i].id)))
            continue;
        if (!mci_grow_array(b->ctx, (void **)on, on_cap, count + 1, sizeof **on, 8))
            return false;
        (*on)[count++] = b->sorted[i];
    }
    /* `sorted` order is along the segment from its lexicographically smaller end. */
    for (size_t k = 0; k < count; k++) {
        uint32_t p = (*on)[forward ? k : count - 1 - k].id;
        if (!add_edge(b->ctx, out, prev, p))
            return false;
        prev = p;
    }
    return add_edge(b->ctx, out, prev, v);
}

/* Keep the undirected edge of the sorted items [first, end) (one per time it is given,
 * ref 1 when given from its larger id): by the even-odd rule when it is given an odd
 * number of times; by the positive rule when it is given more often one way than the
 * other, in that direction, weighted by the difference. */
static bool keep_edge(builder *b, const mci_keyed *items, size_t first, size_t end)
{
    uint32_t lo = (uint32_t)(items[first].key >> 32), hi = (uint32_t)items[first].key;
    int64_t net = 0;
    if (b->rule == MCI_FILL_EVEN_ODD)
        return (end - first) % 2 == 0 || add_edge(b->ctx, &b->kept, lo, hi);
    for (size_t i = first; i < end; i++)
        net += items[i].ref ? -1 : 1;
    if (net == 0)
        return true;
    if (!add_edge(b->ctx, &b->kept, net > 0 ? lo : hi, net > 0 ? hi : lo))
        return false;
    if (!mci_grow_array(b->ctx, (void **)&b->weight, &b->weight_cap, b->kept.count,
                        sizeof *b->weight, 64))
        return false;
    b->weight[b->kept.count - 1] = (uint32_t)(net > 0 ? net : -net);
    return true;
}

/* Split every edge at the points inside it, then keep the undirected edges that the fill
 * rule keeps. */
static mcsg_status split_and_cancel(builder *b, mcsg_error *err)
{
    edge_set split = {0};
    xy_point *on = NULL;
    size_t on_cap = 0;
    mci_keyed *items = NULL;
    mcsg_status st = MCSG_OK;
    for (size_t i = 0; i < b->raw.count; i++) {
        if (!split_edge(b, b->raw.e[2 * i], b->raw.e[2 * i + 1], &split, &on, &on_cap)) {
            st = mci_fail_nomem(err, "making a 2D shape");
            break;
        }
    }
    if (st == MCSG_OK && !(items = mci_malloc_array(b->ctx, split.count + 1, sizeof *items)))
        st = mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; st == MCSG_OK && i < split.count; i++) {
        uint32_t u = split.e[2 * i], v = split.e[2 * i + 1];
        items[i] = (mci_keyed){mci_edge_key(u, v), u > v};
    }
    if (st == MCSG_OK)
        mci_sort_keyed(items, split.count);
    for (size_t i = 0; st == MCSG_OK && i < split.count;) {
        size_t j = i;
        while (j < split.count && items[j].key == items[i].key)
            j++;
        if (!keep_edge(b, items, i, j))
            st = mci_fail_nomem(err, "making a 2D shape");
        i = j;
    }
    mci_free(b->ctx, split.e);
    mci_free(b->ctx, on);
    mci_free(b->ctx, items);
    return st;
}

typedef struct sweep_edge {
    double x0, x1;
    uint32_t e;
} sweep_edge;

#define SWEEP_LESS(a, b) ((a)->x0 < (b)->x0 || ((a)->x0 == (b)->x0 && (a)->e < (b)->e))
MCI_DEFINE_SORT(sort_sweep_edges, sweep_edge, SWEEP_LESS)

/* Whether the interiors of segments p-q and r-s cross at one point. After splitting,
 * edges meet otherwise only at shared ends. */
static bool segments_cross(const double *p, const double *q, const double *r, const double *s)
{
    int a = mci_orient2d(p[0], p[1], q[0], q[1], r[0], r[1]);
    int c = mci_orient2d(p[0], p[1], q[0], q[1], s[0], s[1]);
    if (a == 0 || c == 0 || a == c)
        return false;
    a = mci_orient2d(r[0], r[1], s[0], s[1], p[0], p[1]);
    c = mci_orient2d(r[0], r[1], s[0], s[1], q[0], q[1]);
    return a != 0 && c != 0 && a != c;
}

/* Refuse crossing edges, naming a place near the crossing. */
static mcsg_status check_crossings(builder *b, mcsg_error *err)
{
    size_t n = b->kept.count;
    sweep_edge *s = mci_malloc_array(b->ctx, n + 1, sizeof *s);
    mcsg_status st = MCSG_OK;
    if (!s)
        return mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; i < n; i++) {
        const double *p = PT(b, b->kept.e[2 * i]), *q = PT(b, b->kept.e[2 * i + 1]);
        s[i] = (sweep_edge){fmin(p[0], q[0]), fmax(p[0], q[0]), (uint32_t)i};
    }
    sort_sweep_edges(s, n);
    for (size_t i = 0; i < n && st == MCSG_OK; i++) {
        const uint32_t *e = b->kept.e + 2 * (size_t)s[i].e;
        for (size_t j = i + 1; j < n && s[j].x0 <= s[i].x1; j++) {
            const uint32_t *f = b->kept.e + 2 * (size_t)s[j].e;
            const double *p = PT(b, e[0]), *q = PT(b, e[1]);
            if (!segments_cross(p, q, PT(b, f[0]), PT(b, f[1])))
                continue;
            st = mci_fail(err, MCSG_ERR_UNSUPPORTED, "the outline crosses itself between "
                          "(%.9g, %.9g) and (%.9g, %.9g): meshcsg fills only outlines that "
                          "do not cross", p[0], p[1], q[0], q[1]);
            break;
        }
    }
    mci_free(b->ctx, s);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Triangulation and the inside triangles */

/* Corners of a triangle around every point, with a wide margin. */
static mcsg_status big_triangle(builder *b, mcsg_error *err)
{
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, d, x0, y0;
    for (size_t i = 0; i < b->points; i++) {
        for (int k = 0; k < 2; k++) {
            lo[k] = fmin(lo[k], PT(b, i)[k]);
            hi[k] = fmax(hi[k], PT(b, i)[k]);
        }
    }
    d = fmax(hi[0] - lo[0], hi[1] - lo[1]) + 1;
    x0 = lo[0] - d;
    y0 = lo[1] - d;
    memcpy(b->xyz, (double[9]){x0, y0, 0, x0 + 6 * d, y0, 0, x0, y0 + 6 * d, 0},
           9 * sizeof(double));
    for (int i = 0; i < 9; i++) {
        if (!isfinite(b->xyz[i]))
            return mci_fail(err, MCSG_ERR_LIMIT, "a 2D shape with coordinates too large "
                            "(beyond 1e307) to triangulate");
    }
    return MCSG_OK;
}

static mcsg_status triangulate(builder *b, mci_cdt_output *out, mcsg_error *err)
{
    size_t n = b->points + 3;
    mci_point *pts = mci_malloc_array(b->ctx, n, sizeof *pts);
    const mci_point **ptrs = mci_malloc_array(b->ctx, n, sizeof *ptrs);
    uint32_t *insert = mci_malloc_array(b->ctx, b->points + 1, sizeof *insert);
    uint32_t *edges = mci_malloc_array(b->ctx, 2 * b->kept.count + 1, sizeof *edges);
    mcsg_status st = MCSG_OK;
    if (!pts || !ptrs || !insert || !edges)
        st = mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; st == MCSG_OK && i < n; i++) {
        mci_point_explicit(&pts[i], b->xyz + 3 * i);
        ptrs[i] = &pts[i];
    }
    for (size_t i = 0; st == MCSG_OK && i < b->points; i++)
        insert[i] = (uint32_t)i + 3;
    for (size_t i = 0; st == MCSG_OK && i < 2 * b->kept.count; i++)
        edges[i] = b->kept.e[i] + 3;
    if (st == MCSG_OK) {
        mci_cdt_input in;
        memset(&in, 0, sizeof in);
        in.points = ptrs;
        in.point_count = n;
        in.axis = 2;
        in.sign = 1;
        in.insert = insert;
        in.insert_count = b->points;
        in.edges = edges;
        in.edge_count = b->kept.count;
        st = mci_triangulate(b->ctx, &in, out, err);
    }
    mci_free(b->ctx, pts);
    mci_free(b->ctx, ptrs);
    mci_free(b->ctx, insert);
    mci_free(b->ctx, edges);
    return st;
}

/* How much the winding number drops crossing the kept edge p-q (CDT ids) from its
 * left: its weight when it runs from p to q, minus that when it runs the other way. */
static int64_t edge_weight(const builder *b, uint32_t p, uint32_t q)
{
    uint64_t key = mci_edge_key(p - 3, q - 3);
    size_t lo = 0, hi = b->kept.count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (mci_edge_key(b->kept.e[2 * mid], b->kept.e[2 * mid + 1]) < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo == b->kept.count || mci_edge_key(b->kept.e[2 * lo], b->kept.e[2 * lo + 1]) != key)
        return 0; /* not reached: every constraint is a kept edge */
    return b->kept.e[2 * lo] == p - 3 ? (int64_t)b->weight[lo] : -(int64_t)b->weight[lo];
}

/* inside[t] from a walk out of the big triangle: by the even-odd rule the parity of the
 * constraints crossed; by the positive rule whether the winding number, changed by each
 * crossed edge's weight, is above zero. */
static mcsg_status mark_inside(const builder *b, const mci_cdt_output *cdt, uint8_t *inside,
                               mcsg_error *err)
{
    const mci_ctx *ctx = b->ctx;
    size_t n = cdt->tri_count, len = 0;
    uint32_t *queue = mci_malloc_array(ctx, n + 1, sizeof *queue);
    uint8_t *seen = mci_calloc_array(ctx, n + 1, 1);
    int64_t *winding = mci_calloc_array(ctx, n + 1, sizeof *winding);
    if (!queue || !seen || !winding) {
        mci_free(ctx, queue);
        mci_free(ctx, seen);
        mci_free(ctx, winding);
        return mci_fail_nomem(err, "making a 2D shape");
    }
    for (size_t t = 0; t < n; t++) {
        for (int i = 0; i < 3; i++) {
            if (cdt->adj[3 * t + i] == UINT32_MAX && !seen[t]) {
                seen[t] = 1;
                queue[len++] = (uint32_t)t;
            }
        }
    }
    for (size_t head = 0; head < len; head++) {
        uint32_t t = queue[head];
        for (int i = 0; i < 3; i++) {
            uint32_t a = cdt->adj[3 * (size_t)t + i], u;
            const uint32_t *c = cdt->tris + 3 * (size_t)t;
            if (a == UINT32_MAX)
                continue;
            u = (a & ~MCI_CDT_CONSTRAINT) / 3;
            if (seen[u])
                continue;
            seen[u] = 1;
            if (!(a & MCI_CDT_CONSTRAINT))
                winding[u] = winding[t];
            else if (b->rule == MCI_FILL_EVEN_ODD)
                winding[u] = !winding[t];
            else
                winding[u] = winding[t] - edge_weight(b, c[i], c[(i + 1) % 3]);
            queue[len++] = u;
        }
    }
    for (size_t t = 0; t < n; t++)
        inside[t] = winding[t] > 0;
    mci_free(ctx, queue);
    mci_free(ctx, seen);
    mci_free(ctx, winding);
    return MCSG_OK;
}

/* Whether edge i of inside triangle t bounds the region: a constraint with no inside
 * triangle across it (by the positive rule a constraint may separate two windings above
 * zero). */
static bool on_boundary(const mci_cdt_output *cdt, const uint8_t *inside, size_t t, int i)
{
    uint32_t a = cdt->adj[3 * t + i];
    if (!(a & MCI_CDT_CONSTRAINT))
        return false;
    return a == UINT32_MAX || !inside[(a & ~MCI_CDT_CONSTRAINT) / 3];
}

/* The inside triangles and their boundary, over the points they use. */
static mcsg_status inside_region(builder *b, const mci_cdt_output *cdt, const uint8_t *inside,
                                 mci_region *out, mcsg_error *err)
{
    const mci_ctx *ctx = b->ctx;
    size_t n = b->points + 3, tris = 0, edges = 0;
    uint32_t *map = mci_malloc_array(ctx, n, sizeof *map);
    if (!map)
        return mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; i < n; i++)
        map[i] = UINT32_MAX;
    for (size_t t = 0; t < cdt->tri_count; t++) {
        tris += inside[t];
        for (int i = 0; inside[t] && i < 3; i++) {
            uint32_t p = cdt->tris[3 * t + i];
            edges += on_boundary(cdt, inside, t, i);
            if (map[p] == UINT32_MAX)
                map[p] = (uint32_t)out->vertex_count++;
        }
    }
    out->xy = mci_malloc_array(ctx, out->vertex_count + 1, 2 * sizeof *out->xy);
    out->tris = mci_malloc_array(ctx, tris + 1, 3 * sizeof *out->tris);
    out->edges = mci_malloc_array(ctx, edges + 1, 2 * sizeof *out->edges);
    if (!out->xy || !out->tris || !out->edges) {
        mci_free(ctx, map);
        mci_region_free(ctx, out);
        return mci_fail_nomem(err, "making a 2D shape");
    }
    for (size_t i = 0; i < n; i++) {
        if (map[i] != UINT32_MAX)
            memcpy(out->xy + 2 * (size_t)map[i], b->xyz + 3 * i, 2 * sizeof(double));
    }
    for (size_t t = 0; t < cdt->tri_count; t++) {
        const uint32_t *c = cdt->tris + 3 * t;
        if (!inside[t])
            continue;
        for (int i = 0; i < 3; i++) {
            out->tris[3 * out->tri_count + i] = map[c[i]];
            if (on_boundary(cdt, inside, t, i)) {
                out->edges[2 * out->edge_count] = map[c[i]];
                out->edges[2 * out->edge_count++ + 1] = map[c[(i + 1) % 3]];
            }
        }
        out->tri_count++;
    }
    mci_free(ctx, map);
    return MCSG_OK;
}

mcsg_status mci_region_from_outlines(const mci_ctx *ctx, const mci_outlines *o,
                                     mci_region *out, mcsg_error *err)
{
    return mci_region_fill(ctx, o, MCI_FILL_EVEN_ODD, out, err);
}

mcsg_status mci_region_fill(const mci_ctx *ctx, const mci_outlines *o, mci_fill_rule rule,
                            mci_region *out, mcsg_error *err)
{
    builder b;
    mci_cdt_output cdt = {0};
    uint8_t *inside = NULL;
    mcsg_status st;
    memset(&b, 0, sizeof b);
    memset(out, 0, sizeof *out);
    b.ctx = ctx;
    b.rule = rule;
    st = collect(&b, o, err);
    if (st == MCSG_OK)
        st = sort_points(&b, err);
    if (st == MCSG_OK)
        st = split_and_cancel(&b, err);
    if (st == MCSG_OK)
        st = check_crossings(&b, err);
    if (st == MCSG_OK && b.kept.count > 0) {
        st = big_triangle(&b, err);
        if (st == MCSG_OK)
            st = triangulate(&b, &cdt, err);
        if (st == MCSG_OK && !(inside = mci_malloc_array(ctx, cdt.tri_count + 1, 1)))
            st = mci_fail_nomem(err, "making a 2D shape");
        if (st == MCSG_OK)
            st = mark_inside(&b, &cdt, inside, err);
        if (st == MCSG_OK)
            st = inside_region(&b, &cdt, inside, out, err);
    }
    mci_free(ctx, inside);
    mci_free(ctx, cdt.tris);
    mci_free(ctx, cdt.adj);
    mci_free(ctx, b.xyz);
    mci_free(ctx, b.sorted);
    mci_free(ctx, b.raw.e);
    mci_free(ctx, b.kept.e);
    mci_free(ctx, b.weight);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Prisms and back */

mcsg_status mci_region_prism(const mci_ctx *ctx, const mci_region *r, mcsg_mesh *out,
                             mcsg_error *err)
{
    size_t n = r->vertex_count;
    uint32_t *t;
    mcsg_status st = mci_mesh_alloc(ctx, out, 2 * n, 2 * r->tri_count + 2 * r->edge_count, err);
    if (st != MCSG_OK)
        return st;
    for (size_t i = 0; i < n; i++) {
        for (int z = 0; z < 2; z++) {
            double *v = out->vertices + 3 * (i + z * n);
            v[0] = r->xy[2 * i];
            v[1] = r->xy[2 * i + 1];
            v[2] = z;
        }
    }
    t = out->triangles;
    for (size_t k = 0; k < r->tri_count; k++, t += 6) {
        const uint32_t *c = r->tris + 3 * k;
        memcpy(t, (uint32_t[6]){c[0], c[2], c[1], c[0] + (uint32_t)n, c[1] + (uint32_t)n,
                                c[2] + (uint32_t)n}, sizeof(uint32_t[6]));
    }
    for (size_t k = 0; k < r->edge_count; k++, t += 6) {
        uint32_t a = r->edges[2 * k], b = r->edges[2 * k + 1];
        uint32_t a1 = a + (uint32_t)n, b1 = b + (uint32_t)n;
        memcpy(t, (uint32_t[6]){a, b, b1, a, b1, a1}, sizeof(uint32_t[6]));
    }
    return MCSG_OK;
}

/* The directed edges of the triangles without a reverse twin among them. */
static mcsg_status boundary_edges(const mci_ctx *ctx, mci_region *r, mcsg_error *err)
{
    size_t n = 3 * r->tri_count;
    uint64_t *keys = mci_malloc_array(ctx, n + 1, sizeof *keys);
    if (!keys)
        return mci_fail_nomem(err, "reading a 2D result");
    for (size_t i = 0; i < n; i++) {
        uint32_t a = r->tris[i], b = r->tris[i - i % 3 + (i % 3 + 1) % 3];
        keys[i] = (uint64_t)a << 32 | b;
    }
    mci_sort_u64(keys, n);
    r->edges = mci_malloc_array(ctx, n + 1, 2 * sizeof *r->edges);
    for (size_t i = 0; r->edges && i < n; i++) {
        uint64_t twin = keys[i] << 32 | keys[i] >> 32;
        size_t lo = 0, hi = n;
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (keys[mid] < twin)
                lo = mid + 1;
            else
                hi = mid;
        }
        if (lo < n && keys[lo] == twin)
            continue;
        r->edges[2 * r->edge_count] = (uint32_t)(keys[i] >> 32);
        r->edges[2 * r->edge_count++ + 1] = (uint32_t)keys[i];
    }
    mci_free(ctx, keys);
    return r->edges ? MCSG_OK : mci_fail_nomem(err, "reading a 2D result");
}

mcsg_status mci_region_from_prisms(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_region *out,
                                   mcsg_error *err)
{
    uint32_t *map = mci_malloc_array(ctx, mesh->vertex_count + 1, sizeof *map);
    size_t tris = 0;
    memset(out, 0, sizeof *out);
    if (!map)
        return mci_fail_nomem(err, "reading a 2D result");
    for (size_t i = 0; i < mesh->vertex_count; i++)
        map[i] = UINT32_MAX;
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *c = mesh->triangles + 3 * t;
        bool bottom = true;
        for (int i = 0; i < 3; i++)
            bottom = bottom && mesh->vertices[3 * (size_t)c[i] + 2] == 0;
        if (!bottom)
            continue;
        tris++;
        for (int i = 0; i < 3; i++) {
            if (map[c[i]] == UINT32_MAX)
                map[c[i]] = (uint32_t)out->vertex_count++;
        }
    }
    out->xy = mci_malloc_array(ctx, out->vertex_count + 1, 2 * sizeof *out->xy);
    out->tris = mci_malloc_array(ctx, tris + 1, 3 * sizeof *out->tris);
    if (!out->xy || !out->tris) {
        mci_free(ctx, map);
        mci_region_free(ctx, out);
        return mci_fail_nomem(err, "reading a 2D result");
    }
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        if (map[i] != UINT32_MAX)
            memcpy(out->xy + 2 * (size_t)map[i], mesh->vertices + 3 * i, 2 * sizeof(double));
    }
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        const uint32_t *c = mesh->triangles + 3 * t;
        if (map[c[0]] == UINT32_MAX || map[c[1]] == UINT32_MAX || map[c[2]] == UINT32_MAX ||
            mesh->vertices[3 * (size_t)c[0] + 2] != 0 || mesh->vertices[3 * (size_t)c[1] + 2] != 0 ||
            mesh->vertices[3 * (size_t)c[2] + 2] != 0)
            continue;
        out->tris[3 * out->tri_count] = map[c[0]];
        out->tris[3 * out->tri_count + 1] = map[c[2]];
        out->tris[3 * out->tri_count++ + 2] = map[c[1]];
    }
    mci_free(ctx, map);
    return boundary_edges(ctx, out, err);
}

/* ---------------------------------------------------------------------------------- */
/* Outlines of a region */

mcsg_status mci_region_outlines(const mci_ctx *ctx, const mci_region *r, mci_outlines *out,
                                mcsg_error *err)
{
    size_t n = r->edge_count, loops = 0, len = 0;
    mci_keyed *from = mci_malloc_array(ctx, n + 1, sizeof *from);
    uint8_t *used = mci_calloc_array(ctx, n + 1, 1);
    memset(out, 0, sizeof *out);
    out->xy = mci_malloc_array(ctx, n + 1, 2 * sizeof *out->xy);
    out->ids = mci_malloc_array(ctx, n + 1, sizeof *out->ids);
    out->loop_start = mci_malloc_array(ctx, n + 2, sizeof *out->loop_start);
    if (!from || !used || !out->xy || !out->ids || !out->loop_start) {
        mci_free(ctx, from);
        mci_free(ctx, used);
        mci_outlines_free(ctx, out);
        return mci_fail_nomem(err, "reading a 2D result");
    }
    for (size_t i = 0; i < n; i++)
        from[i] = (mci_keyed){r->edges[2 * i], (uint32_t)i};
    mci_sort_keyed(from, n);
    for (size_t s = 0; s < n; s++) {
        size_t e = from[s].ref;
        if (used[e])
            continue;
        out->loop_start[loops++] = (uint32_t)len;
        /* Follow the chain: at a vertex where the region touches itself, any unused
         * outgoing edge closes a valid loop. */
        while (!used[e]) {
            uint32_t to = r->edges[2 * e + 1];
            size_t k;
            used[e] = 1;
            out->ids[len] = r->edges[2 * e];
            memcpy(out->xy + 2 * len++, r->xy + 2 * (size_t)r->edges[2 * e], 2 * sizeof(double));
            for (k = mci_find_key(from, n, to); k < n && from[k].key == to; k++) {
                if (!used[from[k].ref])
                    break;
            }
            if (k >= n || from[k].key != to)
                break;
            e = from[k].ref;
        }
    }
    out->loop_start[loops] = (uint32_t)len;
    out->loop_count = loops;
    out->point_count = len;
    mci_free(ctx, from);
    mci_free(ctx, used);
    return MCSG_OK;
}

/* Whether b lies strictly inside segment a-c (a straight point between its neighbours). */
static bool straight_between(const double *a, const double *b, const double *c)
{
    if (mci_orient2d(a[0], a[1], b[0], b[1], c[0], c[1]) != 0)
        return false;
    return (a[0] != c[0] ? (a[0] < b[0]) == (b[0] < c[0]) && b[0] != a[0] && b[0] != c[0]
                         : (a[1] < b[1]) == (b[1] < c[1]) && b[1] != a[1] && b[1] != c[1]);
}

/* Dropping every straight point at once is safe: a run of them is monotone along its
 * line, so the edge that replaces the run covers the same segment. */
void mci_outlines_drop_straight(mci_outlines *o)
{
    size_t out = 0;
    uint32_t start = 0;
    for (size_t k = 0; k < o->loop_count; k++) {
        uint32_t first = o->loop_start[k], end = o->loop_start[k + 1], n = end - first;
        /* Points are moved down over the ones dropped; the loop's first point is read
         * again at its end. */
        double head[2] = {o->xy[2 * (size_t)first], o->xy[2 * (size_t)first + 1]};
        for (uint32_t i = 0; i < n; i++) {
            const double *a = o->xy + 2 * (size_t)(first + (i + n - 1) % n);
            const double *b = o->xy + 2 * (size_t)(first + i);
            const double *c = i + 1 < n ? b + 2 : head;
            if (n > 3 && straight_between(a, b, c))
                continue;
            memmove(o->xy + 2 * out, b, 2 * sizeof *o->xy);
            if (o->ids)
                o->ids[out] = o->ids[first + i];
            out++;
        }
        o->loop_start[k] = start;
        start = (uint32_t)out;
    }
    o->loop_start[o->loop_count] = start;
    o->point_count = out;
}

bool mci_outlines_append(const mci_ctx *ctx, mci_outlines *dst, const mci_outlines *src)
{
    size_t points = dst->point_count + src->point_count, loops = dst->loop_count + src->loop_count;
    double *xy;
    uint32_t *start;
    if (src->loop_count == 0)
        return true;
    if (dst->ids || src->ids || points > UINT32_MAX)
        return false;
    xy = mci_realloc_array(ctx, dst->xy, points + 1, 2 * sizeof *xy);
    if (!xy)
        return false;
    dst->xy = xy;
    start = mci_realloc_array(ctx, dst->loop_start, loops + 2, sizeof *start);
    if (!start)
        return false;
    dst->loop_start = start;
    memcpy(xy + 2 * dst->point_count, src->xy, 2 * src->point_count * sizeof *xy);
    for (size_t k = 0; k <= src->loop_count; k++)
        start[dst->loop_count + k] = (uint32_t)dst->point_count + src->loop_start[k];
    dst->point_count = points;
    dst->loop_count = loops;
    return true;
}
