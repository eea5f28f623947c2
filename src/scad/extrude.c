/*
 * linear_extrude and rotate_extrude of a region, following OpenSCAD 2021.01
 * (GeometryEvaluator.cc: extrudePolygon, add_slice, rotatePolygon, fill_ring; calc.cc):
 *  - linear_extrude: caps from the region's triangles, walls slice by slice, each slice's
 *    outline turned by -twist * k / slices degrees and scaled by 1 - (1 - scale) * k /
 *    slices; each wall quad split along its shorter diagonal by OpenSCAD's rule, so that
 *    twisted walls are the same surface; slices default as OpenSCAD computes them from
 *    $fn, $fa, $fs (a helix, a conical helix, or the widest move of a point);
 *  - rotate_extrude: the region swept about the z axis (x becomes the radius, y the
 *    height) in fragments from the widest x, starting on the -x axis for a full turn and
 *    on the +x axis otherwise, with caps when the angle is not 360.
 * OpenSCAD's faces are clockwise seen from outside; here they are reversed. Every point of
 * a level (a slice, a ring) is computed once and shared by the caps and walls, then points
 * with equal coordinates are welded, so that the result is closed even where a ring
 * meets the axis or a scale of zero pinches the top.
 */
#include "base/degree_trig.h"
#include "base/sort_template.h"
#include "scad/geometry.h"

#include <math.h>
#include <string.h>

/* More levels times points than this is refused rather than allocated. */
#define MAX_SWEPT_POINTS (UINT64_C(1) << 28)
/* OpenSCAD's GRID_FINE: below this radius a circle gets 3 fragments. */
#define GRID_FINE 0.00000095367431640625
#define PI_DOUBLE 3.14159265358979323846

/* ---------------------------------------------------------------------------------- */
/* A swept mesh: levels of points over the region's vertices, then welded */

typedef struct sweep {
    const mci_ctx *ctx;
    size_t per_level;  /* the region's vertices */
    size_t levels;
    double *points;    /* 3 per point, level by level */
    uint32_t *tris;
    size_t tri_count, tri_cap;
} sweep;

static uint32_t at(const sweep *s, size_t level, uint32_t v)
{
    return (uint32_t)((level % s->levels) * s->per_level + v);
}

static bool add_tri(sweep *s, uint32_t a, uint32_t b, uint32_t c)
{
    if (!mci_grow_array(s->ctx, (void **)&s->tris, &s->tri_cap, 3 * (s->tri_count + 1),
                        sizeof *s->tris, 192))
        return false;
    memcpy(s->tris + 3 * s->tri_count++, (uint32_t[3]){a, b, c}, sizeof(uint32_t[3]));
    return true;
}

/* The region's triangles at a level, facing up or (reversed) down. */
static bool add_cap(sweep *s, const mci_region *r, size_t level, bool reversed)
{
    for (size_t t = 0; t < r->tri_count; t++) {
        const uint32_t *c = r->tris + 3 * t;
        uint32_t a = at(s, level, c[0]), b = at(s, level, c[1]), d = at(s, level, c[2]);
        if (!(reversed ? add_tri(s, a, d, b) : add_tri(s, a, b, d)))
            return false;
    }
    return true;
}

static mcsg_status sweep_alloc(scad_context *sc, const scad_geometry_op *op, sweep *s,
                               size_t per_level, size_t levels, mcsg_error *err)
{
    memset(s, 0, sizeof *s);
    s->ctx = sc->ev.ctx;
    s->per_level = per_level;
    s->levels = levels;
    if ((uint64_t)per_level * levels > MAX_SWEPT_POINTS)
        return scad_fail_at(sc->name, op->ca.stmt->line, op->ca.stmt->col, err,
                            MCSG_ERR_LIMIT, "%s(): %zu levels of %zu points, more than %llu "
                            "points", op->ca.module, levels, per_level,
                            (unsigned long long)MAX_SWEPT_POINTS);
    s->points = mci_malloc_array(s->ctx, per_level * levels + 1, 3 * sizeof *s->points);
    return s->points ? MCSG_OK : mci_fail_nomem(err, "extruding a 2D shape");
}

/* Weld points of equal coordinates and drop triangles that lose a corner to it. */
static mcsg_status sweep_mesh(sweep *s, mcsg_mesh *out, mcsg_error *err)
{
    size_t n = s->per_level * s->levels, kept = 0, used = 0;
    uint32_t *canon = mci_malloc_array(s->ctx, n + 1, sizeof *canon);
    uint32_t *map = mci_malloc_array(s->ctx, n + 1, sizeof *map);
    mcsg_status st = MCSG_OK;
    memset(out, 0, sizeof *out);
    if (!canon || !map || !mci_first_equal_coordinates(s->ctx, s->points, n, canon))
        st = mci_fail_nomem(err, "extruding a 2D shape");
    for (size_t i = 0; st == MCSG_OK && i < n; i++)
        map[i] = canon[i] == i ? (uint32_t)used++ : UINT32_MAX;
    for (size_t t = 0; st == MCSG_OK && t < s->tri_count; t++) {
        uint32_t *c = s->tris + 3 * t;
        for (int k = 0; k < 3; k++)
            c[k] = map[canon[c[k]]];
        if (c[0] != c[1] && c[1] != c[2] && c[2] != c[0])
            memmove(s->tris + 3 * kept++, c, 3 * sizeof *c);
    }
    if (st == MCSG_OK)
        st = mci_mesh_alloc(s->ctx, out, kept ? used : 0, kept, err);
    for (size_t i = 0; st == MCSG_OK && kept && i < n; i++) {
        if (map[i] != UINT32_MAX)
            memcpy(out->vertices + 3 * (size_t)map[i], s->points + 3 * i, 3 * sizeof(double));
    }
    if (st == MCSG_OK)
        memcpy(out->triangles, s->tris, 3 * kept * sizeof *s->tris);
    mci_free(s->ctx, canon);
    mci_free(s->ctx, map);
    mci_free(s->ctx, s->points);
    mci_free(s->ctx, s->tris);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* linear_extrude */

/* OpenSCAD's helix length for a twist (Calc::get_helix_slices). */
static double helix_length(double r2, double height, double twist)
{
    double t = twist * PI_DOUBLE / 180, c = height / t;
    return t * sqrt(r2 + c * c);
}

static double archimedes_length(double a, double theta)
{
    return 0.5 * a * (theta * sqrt(1 + theta * theta) + asinh(theta));
}

static int helix_slices(const scad_geometry_op *op, double r2)
{
    double twist = fabs(op->twist), fn = op->res.fn;
    int min_slices = (int)fmax(ceil(twist / 120.0), 1), fs_slices;
    bool conical = op->scale[0] == op->scale[1] && op->scale[0] != 1.0;
    if (sqrt(r2) < GRID_FINE || isinf(fn) || isnan(fn))
        return min_slices;
    if (fn > 0.0)
        return (int)fmax(ceil(twist / 360.0 * fn), min_slices);
    if (!conical) {
        fs_slices = (int)ceil(helix_length(r2, op->height, twist) / op->res.fs);
    } else {
        /* The path of a point is a piece of an Archimedes spiral, lifted. */
        double s = op->scale[0], rads = twist * PI_DOUBLE / 180;
        double end = s > 1 ? rads * s / (s - 1) : rads / (1 - s), start = end - rads;
        double a = sqrt(r2) / end;
        double spiral = archimedes_length(a, end) - archimedes_length(a, start);
        fs_slices = (int)ceil(sqrt(spiral * spiral + op->height * op->height) / op->res.fs);
    }
    return (int)fmax(fmin(ceil(twist / op->res.fa), fs_slices), min_slices);
}

/* OpenSCAD's slice count: given, or from the twist, or for a scale differing by axis. */
static size_t linear_slices(const scad_geometry_op *op, const mci_region *r)
{
    double max_r2 = 0, max_d2 = 0;
    if (op->slices > 0)
        return (size_t)op->slices;
    for (size_t i = 0; i < r->vertex_count; i++) {
        double x = r->xy[2 * i], y = r->xy[2 * i + 1];
        double dx = x - x * op->scale[0], dy = y - y * op->scale[1];
        max_r2 = fmax(max_r2, x * x + y * y);
        max_d2 = fmax(max_d2, dx * dx + dy * dy);
    }
    if (op->twist != 0)
        return (size_t)helix_slices(op, max_r2);
    if (op->scale[0] == op->scale[1] || sqrt(max_d2) < GRID_FINE || !isfinite(op->res.fn))
        return 1;
    if (op->res.fn > 0)
        return (size_t)fmax(op->res.fn, 1);
    return (size_t)fmax(ceil(sqrt(max_d2 + op->height * op->height) / op->res.fs), 1);
}

/* Level k's points: the region turned by -twist k / n degrees, scaled, lifted. */
static void linear_level(const scad_geometry_op *op, const mci_region *r, sweep *s, size_t k,
                         double z)
{
    size_t n = s->levels - 1;
    double rot = -(op->twist * (double)k / (double)n);
    double sx = 1 - (1 - op->scale[0]) * (double)k / (double)n;
    double sy = 1 - (1 - op->scale[1]) * (double)k / (double)n;
    double c = mci_cos_degrees(rot), si = mci_sin_degrees(rot);
    double m[4] = {sx * c, -sx * si, sy * si, sy * c};
    for (size_t i = 0; i < r->vertex_count; i++) {
        double x = r->xy[2 * i], y = r->xy[2 * i + 1], *p = s->points + 3 * (k * s->per_level + i);
        p[0] = m[0] * x + m[1] * y;
        p[1] = m[2] * x + m[3] * y;
        p[2] = z;
    }
}

/* OpenSCAD's sgn_vdiff: which diagonal is shorter, equal within 10 parts per million.
 * This chooses between two triangulations of a wall quad as OpenSCAD does, so that the
 * surface is the same; it decides nothing about existing geometry. */
static int shorter_diagonal(const double *a, const double *b, const double *c, const double *d)
{
    double l1 = hypot(a[0] - b[0], a[1] - b[1]), l2 = hypot(c[0] - d[0], c[1] - d[1]);
    return 2 * fabs(l1 - l2) * 1e5 > l1 + l2 ? (l1 < l2 ? -1 : 1) : 0;
}

/* The walls between levels k and k + 1 of one outline (OpenSCAD's add_slice). */
static bool linear_walls(const scad_geometry_op *op, sweep *s, const mci_outlines *o,
                         size_t loop, size_t k)
{
    size_t first = o->loop_start[loop], count = o->loop_start[loop + 1] - first;
    size_t n = s->levels - 1;
    double s2x = 1 - (1 - op->scale[0]) * (double)(k + 1) / (double)n;
    double s2y = 1 - (1 - op->scale[1]) * (double)(k + 1) / (double)n;
    bool any_zero = s2x == 0 || s2y == 0, any_non_zero = s2x != 0 || s2y != 0;
    double rot1 = op->twist * (double)k / (double)n, rot2 = op->twist * (double)(k + 1) / (double)n;
    bool flip = (mci_outline_area2(o, loop) <= 0) != (rot2 <= rot1);
    for (size_t i = 0; i < count; i++) {
        uint32_t v0 = o->ids[first + i], v1 = o->ids[first + (i + 1) % count];
        uint32_t p1 = at(s, k, v0), c1 = at(s, k, v1), p2 = at(s, k + 1, v0), c2 = at(s, k + 1, v1);
        const double *P = s->points;
        int diff = shorter_diagonal(P + 3 * (size_t)p1, P + 3 * (size_t)c2, P + 3 * (size_t)c1,
                                    P + 3 * (size_t)p2);
        bool split_first = diff == -1 || (diff == 0 && !flip);
        bool second = !any_zero || (any_non_zero && (P[3 * (size_t)p2] != P[3 * (size_t)c2] ||
                                                     P[3 * (size_t)p2 + 1] != P[3 * (size_t)c2 + 1]));
        /* OpenSCAD's triangles, reversed: they face outward counter-clockwise here. */
        bool ok = split_first != any_zero
                      ? add_tri(s, p1, c1, c2) && (!second || add_tri(s, c2, p2, p1))
                      : add_tri(s, p1, c1, p2) && (!second || add_tri(s, p2, c1, c2));
        if (!ok)
            return false;
    }
    return true;
}

/* A top scaled to zero along one axis is a segment: every region vertex goes to the
 * image of its other coordinate u. The last walls' top edges run along it, and the two
 * sides of the outline have corners at different u (a notch on one side only), so each
 * top edge is split at every image strictly between its ends, fanned from its wall's
 * third corner: the walls then meet edge to edge once welded. */
typedef struct top_value {
    double u;
    uint32_t v; /* a region vertex with that u */
} top_value;

#define TOP_LESS(a, b) ((a)->u < (b)->u)
MCI_DEFINE_SORT(sort_top_values, top_value, TOP_LESS)

static size_t first_above(const top_value *t, size_t n, double u)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (t[mid].u <= u)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Split triangle t's top edge (corners k, k + 1 on the top level, the third below). */
static bool split_top_edge(sweep *s, const mci_region *r, const top_value *tv, size_t n,
                           int axis, size_t t, int k)
{
    uint32_t c[3], top = (uint32_t)((s->levels - 1) * s->per_level);
    memcpy(c, s->tris + 3 * t, sizeof c);
    uint32_t a = c[k], b = c[(k + 1) % 3], apex = c[(k + 2) % 3], prev = a;
    double ua = r->xy[2 * (size_t)(a - top) + axis], ub = r->xy[2 * (size_t)(b - top) + axis];
    bool up = ua < ub;
    size_t lo = first_above(tv, n, fmin(ua, ub)), hi = first_above(tv, n, fmax(ua, ub));
    size_t inside = hi > lo && tv[hi - 1].u == fmax(ua, ub) ? hi - 1 - lo : hi - lo;
    for (size_t j = 0; j < inside; j++) {
        uint32_t q = top + tv[up ? lo + j : lo + inside - 1 - j].v;
        if (j == 0)
            memcpy(s->tris + 3 * t, (uint32_t[3]){prev, q, apex}, sizeof(uint32_t[3]));
        else if (!add_tri(s, prev, q, apex))
            return false;
        prev = q;
    }
    return inside == 0 || add_tri(s, prev, b, apex);
}

static bool split_top(sweep *s, const mci_region *r, int axis)
{
    size_t n = r->vertex_count, kept = 0, count = s->tri_count;
    uint32_t top = (uint32_t)((s->levels - 1) * s->per_level);
    top_value *tv = mci_malloc_array(s->ctx, n + 1, sizeof *tv);
    bool ok = tv != NULL;
    for (size_t i = 0; ok && i < n; i++)
        tv[i] = (top_value){r->xy[2 * i + axis], (uint32_t)i};
    if (ok)
        sort_top_values(tv, n);
    for (size_t i = 0; ok && i < n; i++) { /* one vertex per value */
        if (kept == 0 || tv[kept - 1].u != tv[i].u)
            tv[kept++] = tv[i];
    }
    for (size_t t = 0; ok && t < count; t++) {
        const uint32_t *c = s->tris + 3 * t;
        for (int k = 0; k < 3; k++) {
            if (c[k] >= top && c[(k + 1) % 3] >= top && c[(k + 2) % 3] < top) {
                ok = split_top_edge(s, r, tv, kept, axis, t, k);
                break;
            }
        }
    }
    mci_free(s->ctx, tv);
    return ok;
}

mcsg_status scad_linear_extrude(scad_context *sc, const scad_geometry_op *op,
                                  const mci_region *r, const mci_outlines *o, mcsg_mesh *out,
                                  mcsg_error *err)
{
    size_t slices = linear_slices(op, r);
    double h1 = op->center ? -op->height / 2.0 : 0, h2 = op->center ? op->height / 2.0 : op->height;
    sweep s;
    bool ok;
    mcsg_status st = sweep_alloc(sc, op, &s, r->vertex_count, slices + 1, err);
    if (st != MCSG_OK)
        return st;
    for (size_t k = 0; k <= slices; k++)
        linear_level(op, r, &s, k, k == slices ? h2 : h1 + (h2 - h1) * (double)k / (double)slices);
    ok = add_cap(&s, r, 0, true);
    if (ok && op->scale[0] > 0 && op->scale[1] > 0)
        ok = add_cap(&s, r, slices, false);
    for (size_t k = 0; ok && k < slices; k++) {
        for (size_t loop = 0; ok && loop < o->loop_count; loop++)
            ok = linear_walls(op, &s, o, loop, k);
    }
    if (ok && (op->scale[0] == 0) != (op->scale[1] == 0))
        ok = split_top(&s, r, op->scale[0] == 0 ? 1 : 0);
    if (!ok) {
        mci_free(s.ctx, s.points);
        mci_free(s.ctx, s.tris);
        return mci_fail_nomem(err, "extruding a 2D shape");
    }
    return sweep_mesh(&s, out, err);
}

/* ---------------------------------------------------------------------------------- */
/* rotate_extrude */

/* Ring j's points: (x sin a, x cos a, y), a in degrees (OpenSCAD's fill_ring). */
static void rotate_ring(const mci_region *r, sweep *s, size_t j, double a)
{
    double sa = mci_sin_degrees(a), ca = mci_cos_degrees(a);
    for (size_t i = 0; i < r->vertex_count; i++) {
        double *p = s->points + 3 * (j * s->per_level + i);
        p[0] = r->xy[2 * i] * sa;
        p[1] = r->xy[2 * i] * ca;
        p[2] = r->xy[2 * i + 1];
    }
}

static mcsg_status rotate_fragments(scad_context *sc, const scad_geometry_op *op,
                                    const mci_region *r, size_t *fragments, bool *flip,
                                    mcsg_error *err)
{
    double min_x = 0, max_x = 0, f;
    for (size_t i = 0; i < r->vertex_count; i++) {
        min_x = fmin(min_x, r->xy[2 * i]);
        max_x = fmax(max_x, r->xy[2 * i]);
    }
    if (max_x - min_x > max_x && max_x - min_x > fabs(min_x))
        return scad_fail_at(sc->name, op->ca.stmt->line, op->ca.stmt->col, err, MCSG_ERR_PARSE,
                            "rotate_extrude(): all points must have the same X coordinate sign "
                            "(range is %.2f -> %.2f)", min_x, max_x);
    f = mcsg_fragments(max_x - min_x, op->res.fn, op->res.fa, op->res.fs) * fabs(op->angle) / 360;
    *fragments = (size_t)fmin(fmax(f, 1), 1e9);
    *flip = (min_x >= 0 && op->angle > 0 && op->angle != 360) ||
            (min_x < 0 && (op->angle < 0 || op->angle == 360));
    return MCSG_OK;
}

static bool rotate_walls(sweep *s, const mci_outlines *o, size_t loop, size_t j, bool flip)
{
    size_t first = o->loop_start[loop], count = o->loop_start[loop + 1] - first;
    for (size_t i = 0; i < count; i++) {
        size_t i0 = flip ? count - 1 - i : i, i1 = flip ? (2 * count - 2 - i) % count : (i + 1) % count;
        uint32_t v0 = o->ids[first + i0], v1 = o->ids[first + i1];
        if (!add_tri(s, at(s, j, v0), at(s, j, v1), at(s, j + 1, v1)) ||
            !add_tri(s, at(s, j, v0), at(s, j + 1, v1), at(s, j + 1, v0)))
            return false;
    }
    return true;
}

mcsg_status scad_rotate_extrude(scad_context *sc, const scad_geometry_op *op,
                                  const mci_region *r, const mci_outlines *o, mcsg_mesh *out,
                                  mcsg_error *err)
{
    bool full = op->angle == 360, flip = false, ok = true;
    size_t fragments = 1, rings;
    sweep s;
    mcsg_status st = rotate_fragments(sc, op, r, &fragments, &flip, err);
    if (st != MCSG_OK)
        return st;
    rings = full ? fragments : fragments + 1;
    st = sweep_alloc(sc, op, &s, r->vertex_count, rings, err);
    if (st != MCSG_OK)
        return st;
    for (size_t j = 0; j < rings; j++)
        rotate_ring(r, &s, j, full ? -90 + (double)j * 360.0 / (double)fragments
                                   : 90 - (double)j * op->angle / (double)fragments);
    if (!full)
        ok = add_cap(&s, r, 0, !flip) && add_cap(&s, r, fragments, flip);
    for (size_t j = 0; ok && j < fragments; j++) {
        for (size_t loop = 0; ok && loop < o->loop_count; loop++)
            ok = rotate_walls(&s, o, loop, j, flip);
    }
    if (!ok) {
        mci_free(s.ctx, s.points);
        mci_free(s.ctx, s.tris);
        return mci_fail_nomem(err, "extruding a 2D shape");
    }
    return sweep_mesh(&s, out, err);
}

