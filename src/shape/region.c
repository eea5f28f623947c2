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
    edge_set raw, kept;
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

/* Split every edge at the points inside it, then keep the undirected edges that occur
 * an odd number of times. */
static mcsg_status split_and_cancel(builder *b, mcsg_error *err)
{
    edge_set split = {0};
    xy_point *on = NULL;
    size_t on_cap = 0;
    uint64_t *keys = NULL;
    mcsg_status st = MCSG_OK;
    for (size_t i = 0; i < b->raw.count; i++) {
        if (!split_edge(b, b->raw.e[2 * i], b->raw.e[2 * i + 1], &split, &on, &on_cap)) {
            st = mci_fail_nomem(err, "making a 2D shape");
            break;
        }
    }
    if (st == MCSG_OK && !(keys = mci_malloc_array(b->ctx, split.count + 1, sizeof *keys)))
        st = mci_fail_nomem(err, "making a 2D shape");
    for (size_t i = 0; st == MCSG_OK && i < split.count; i++)
        keys[i] = mci_edge_key(split.e[2 * i], split.e[2 * i + 1]);
    if (st == MCSG_OK)
        mci_sort_u64(keys, split.count);
    for (size_t i = 0; st == MCSG_OK && i < split.count;) {
        size_t j = i;
        while (j < split.count && keys[j] == keys[i])
            j++;
        if ((j - i) % 2 == 1 &&
            !add_edge(b->ctx, &b->kept, (uint32_t)(keys[i] >> 32), (uint32_t)keys[i]))
            st = mci_fail_nomem(err, "making a 2D shape");
        i = j;
    }
    mci_free(b->ctx, split.e);
    mci_free(b->ctx, on);
    mci_free(b->ctx, keys);
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

/* inside[t]: parity of the constraints crossed from outside the big triangle. */
static mcsg_status mark_inside(const mci_ctx *ctx, const mci_cdt_output *cdt, uint8_t *inside,
                               mcsg_error *err)
{
    size_t n = cdt->tri_count, len = 0;
    uint32_t *queue = mci_malloc_array(ctx, n + 1, sizeof *queue);
    uint8_t *seen = mci_calloc_array(ctx, n + 1, 1);
    if (!queue || !seen) {
        mci_free(ctx, queue);
        mci_free(ctx, seen);
        return mci_fail_nomem(err, "making a 2D shape");
    }
    for (size_t t = 0; t < n; t++) {
        for (int i = 0; i < 3; i++) {
            if (cdt->adj[3 * t + i] == UINT32_MAX && !seen[t]) {
                seen[t] = 1;
                inside[t] = 0;
                queue[len++] = (uint32_t)t;
            }
        }
    }
    for (size_t head = 0; head < len; head++) {
        uint32_t t = queue[head];
        for (int i = 0; i < 3; i++) {
            uint32_t a = cdt->adj[3 * (size_t)t + i], u;
            if (a == UINT32_MAX)
                continue;
            u = (a & ~MCI_CDT_CONSTRAINT) / 3;
            if (seen[u])
                continue;
            seen[u] = 1;
            inside[u] = inside[t] ^ ((a & MCI_CDT_CONSTRAINT) != 0);
            queue[len++] = u;
        }
    }
    mci_free(ctx, queue);
    mci_free(ctx, seen);
    return MCSG_OK;
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
            edges += (cdt->adj[3 * t + i] & MCI_CDT_CONSTRAINT) != 0;
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
            if (cdt->adj[3 * t + i] & MCI_CDT_CONSTRAINT) {
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
    builder b;
    mci_cdt_output cdt = {0};
    uint8_t *inside = NULL;
    mcsg_status st;
    memset(&b, 0, sizeof b);
    memset(out, 0, sizeof *out);
    b.ctx = ctx;
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
            st = mark_inside(ctx, &cdt, inside, err);
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
