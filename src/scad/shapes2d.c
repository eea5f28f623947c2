/*
 * The 2D primitives of the CSG language, following OpenSCAD 2021.01's primitives.cc:
 *  - circle(r | d): `fragments` points at 360 * i / n degrees (OpenSCAD's degree trig),
 *    nothing unless r > 0 and finite;
 *  - square(size, center): the rectangle [0, x] x [0, y] (centred: moved by half), nothing
 *    unless both sides are positive and finite;
 *  - polygon(points, paths, convexity): the points as one outline, or each path of point
 *    indices as an outline (indices out of range are skipped with a warning), filled by
 *    the even-odd rule as OpenSCAD's Clipper sanitising does.
 * Transforms act on 2D shapes through the 2D part of their matrix (rows and columns x, y
 * and the translation), as in OpenSCAD; one with a zero determinant removes the shape.
 * Each shape becomes a prism over its region (shape/region.h) in the tree being built.
 */
#include "mesh/tree.h"
#include "base/degree_trig.h"
#include "scad/scad.h"
#include "shape/region.h"
#include "io/dxf.h"
#include "io/svg.h"
#include "text/text.h"

#include <math.h>
#include <string.h>

enum { CIRCLE_R, CIRCLE_D };
enum { SQUARE_SIZE, SQUARE_CENTER };
enum { POLYGON_POINTS, POLYGON_PATHS };
enum { IMPORT_LAYER = 1, IMPORT_ORIGIN = 3, IMPORT_SCALE = 4, IMPORT_LAYERNAME = 8,
       IMPORT_CENTER = 9, IMPORT_DPI = 10 };
enum { TEXT_TEXT, TEXT_SIZE, TEXT_FONT, TEXT_DIRECTION, TEXT_LANGUAGE, TEXT_SCRIPT,
       TEXT_HALIGN, TEXT_VALIGN, TEXT_SPACING, TEXT_STRINGS = TEXT_SPACING };

/* More points than this in one shape is refused rather than allocated. */
#define MAX_SHAPE_POINTS (UINT32_C(1) << 26)

static mcsg_status alloc_outlines(const mci_ctx *ctx, mci_outlines *o, size_t points,
                                  size_t loops, mcsg_error *err)
{
    memset(o, 0, sizeof *o);
    o->xy = mci_malloc_array(ctx, points + 1, 2 * sizeof *o->xy);
    o->loop_start = mci_calloc_array(ctx, loops + 1, sizeof *o->loop_start);
    if (!o->xy || !o->loop_start) {
        mci_outlines_free(ctx, o);
        return mci_fail_nomem(err, "making a 2D shape");
    }
    return MCSG_OK;
}

static mcsg_status circle_outline(scad_context *sc, const scad_call_args *ca, mci_outlines *o,
                                  mci_buf *label, mcsg_error *err)
{
    double r = 1;
    bool defined;
    mcsg_resolution res;
    int n;
    mcsg_status st = scad_arg_radius(sc, ca, CIRCLE_D, CIRCLE_R, &r, &defined, err);
    if (st == MCSG_OK)
        st = scad_get_resolution(sc, ca, &res, err);
    if (st != MCSG_OK)
        return st;
    n = r > 0 && isfinite(r) ? mcsg_fragments(r, res.fn, res.fa, res.fs) : 0;
    if ((uint32_t)n > MAX_SHAPE_POINTS)
        return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, MCSG_ERR_LIMIT,
                            "circle(): %d fragments, more than %u", n, MAX_SHAPE_POINTS);
    st = alloc_outlines(sc->ev.ctx, o, (size_t)n, 1, err);
    for (int i = 0; st == MCSG_OK && i < n; i++) {
        double phi = (360.0 * i) / n;
        o->xy[2 * i] = r * mci_cos_degrees(phi);
        o->xy[2 * i + 1] = r * mci_sin_degrees(phi);
    }
    if (st == MCSG_OK && n > 0) {
        o->point_count = (size_t)n;
        o->loop_count = 1;
        o->loop_start[1] = (uint32_t)n;
    }
    if (st == MCSG_OK && (!scad_put_number(sc->ev.ctx, label, "circle(r=", r) ||
                          !scad_put_resolution(sc->ev.ctx, label, &res) ||
                          !mci_buf_printf(sc->ev.ctx, label, ")")))
        st = mci_fail_nomem(err, "reading CSG text");
    return st;
}

static mcsg_status square_outline(scad_context *sc, const scad_call_args *ca, mci_outlines *o,
                                  mci_buf *label, mcsg_error *err)
{
    const scad_value *size = &ca->slot[SQUARE_SIZE].value;
    double s[3] = {1, 1, 0}, x0 = 0, y0 = 0;
    bool center = false;
    mcsg_status st = MCSG_OK;
    if (size->type == VAL_NUMBER)
        s[0] = s[1] = size->number;
    else if (scad_given(ca, SQUARE_SIZE) &&
             (size->count != 2 || !scad_get_vec3(sc, size, true, 0, s)))
        st = scad_wrong_type(sc, ca, SQUARE_SIZE, "a number or a vector of 2 numbers", err);
    if (st == MCSG_OK)
        st = scad_arg_bool(sc, ca, SQUARE_CENTER, &center, err);
    if (st == MCSG_OK)
        st = alloc_outlines(sc->ev.ctx, o, 4, 1, err);
    if (st != MCSG_OK)
        return st;
    if (center) {
        x0 = -s[0] / 2;
        y0 = -s[1] / 2;
    }
    if (s[0] > 0 && s[1] > 0 && isfinite(s[0]) && isfinite(s[1])) {
        double x1 = center ? x0 + s[0] : s[0], y1 = center ? y0 + s[1] : s[1];
        memcpy(o->xy, (double[8]){x0, y0, x1, y0, x1, y1, x0, y1}, sizeof(double[8]));
        o->point_count = 4;
        o->loop_count = 1;
        o->loop_start[1] = 4;
    }
    if (!scad_put_number(sc->ev.ctx, label, "square(size=[", s[0]) ||
        !scad_put_number(sc->ev.ctx, label, ", ", s[1]) ||
        !mci_buf_printf(sc->ev.ctx, label, "], center=%s)", center ? "true" : "false"))
        return mci_fail_nomem(err, "reading CSG text");
    return MCSG_OK;
}

/* polygon()'s points, checked: each a vector of 2 numbers. */
static mcsg_status polygon_points(scad_context *sc, const scad_call_args *ca, double *xy,
                                  mcsg_error *err)
{
    const scad_bound_arg *a = &ca->slot[POLYGON_POINTS];
    for (uint32_t i = 0; i < a->value.count; i++) {
        const scad_value *p = scad_element(sc, &a->value, i);
        double v[3];
        if (p->type != VAL_VECTOR || p->count != 2 || !scad_get_vec3(sc, p, true, 0, v) ||
            !isfinite(v[0]) || !isfinite(v[1]))
            return scad_fail_at(sc->name, a->line, a->col, err, MCSG_ERR_PARSE,
                                "polygon(): points[%u] is not a vector of 2 finite numbers", i);
        xy[2 * i] = v[0];
        xy[2 * i + 1] = v[1];
    }
    return MCSG_OK;
}

/* One path of point indices appended to the outlines (indices out of range skipped). */
static mcsg_status polygon_path(scad_context *sc, const scad_call_args *ca, const double *xy,
                                uint32_t points, uint32_t p, mci_outlines *o, mcsg_error *err)
{
    const scad_bound_arg *a = &ca->slot[POLYGON_PATHS];
    const scad_value *path = scad_element(sc, &a->value, p);
    if (path->type != VAL_VECTOR)
        return scad_fail_at(sc->name, a->line, a->col, err, MCSG_ERR_PARSE, "polygon(): "
                            "paths[%u] is %s, not a vector of point indices", p,
                            scad_type_name((scad_type)path->type));
    for (uint32_t k = 0; k < path->count; k++) {
        const scad_value *index = scad_element(sc, path, k);
        double x = index->number;
        if (index->type != VAL_NUMBER)
            return scad_fail_at(sc->name, a->line, a->col, err, MCSG_ERR_PARSE, "polygon(): "
                                "paths[%u][%u] is %s, not a point index", p, k,
                                scad_type_name((scad_type)index->type));
        if (!(x >= 0 && x < points)) {
            scad_warn_at(sc->ev.ctx, sc->name, a->line, a->col, "polygon(): point index %.17g "
                         "is out of bounds (from paths[%u][%u]): skipping it", x, p, k);
            continue;
        }
        memcpy(o->xy + 2 * o->point_count++, xy + 2 * (uint32_t)x, 2 * sizeof *xy);
    }
    o->loop_start[++o->loop_count] = (uint32_t)o->point_count;
    return MCSG_OK;
}

static mcsg_status polygon_outlines(scad_context *sc, const scad_call_args *ca,
                                    mci_outlines *o, mci_buf *label, mcsg_error *err)
{
    const scad_value *points = &ca->slot[POLYGON_POINTS].value;
    const scad_value *paths = &ca->slot[POLYGON_PATHS].value;
    bool by_paths = paths->type == VAL_VECTOR && paths->count > 0;
    size_t total = 0;
    double *xy;
    mcsg_status st;
    if (points->type != VAL_VECTOR)
        return scad_wrong_type(sc, ca, POLYGON_POINTS, "a vector of points", err);
    if (scad_given(ca, POLYGON_PATHS) && paths->type != VAL_VECTOR)
        return scad_wrong_type(sc, ca, POLYGON_PATHS, "a vector of paths", err);
    for (uint32_t p = 0; by_paths && p < paths->count; p++)
        total += scad_element(sc, paths, p)->count;
    if (!by_paths)
        total = points->count;
    if (total > MAX_SHAPE_POINTS || points->count > MAX_SHAPE_POINTS)
        return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, MCSG_ERR_LIMIT,
                            "polygon(): more than %u points", MAX_SHAPE_POINTS);
    st = alloc_outlines(sc->ev.ctx, o, total, by_paths ? paths->count : 1, err);
    xy = st == MCSG_OK ? mci_malloc_array(sc->ev.ctx, points->count + 1, 2 * sizeof *xy) : NULL;
    if (st == MCSG_OK && !xy)
        st = mci_fail_nomem(err, "making a 2D shape");
    if (st == MCSG_OK)
        st = polygon_points(sc, ca, xy, err);
    for (uint32_t p = 0; st == MCSG_OK && by_paths && p < paths->count; p++)
        st = polygon_path(sc, ca, xy, points->count, p, o, err);
    if (st == MCSG_OK && !by_paths && points->count > 2) {
        memcpy(o->xy, xy, 2 * sizeof *xy * points->count);
        o->point_count = points->count;
        o->loop_count = 1;
        o->loop_start[1] = points->count;
    }
    mci_free(sc->ev.ctx, xy);
    if (st == MCSG_OK && !mci_buf_printf(sc->ev.ctx, label, "polygon(%u points, %u paths)",
                                         points->count, by_paths ? paths->count : 1))
        st = mci_fail_nomem(err, "reading CSG text");
    return st;
}

/* text()'s string arguments as C strings (NULL when not given): the text itself may be
 * any value, printed as OpenSCAD prints it. */
static mcsg_status text_strings(scad_context *sc, const scad_call_args *ca,
                                char *strings[TEXT_STRINGS], mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    for (int i = 0; i < TEXT_STRINGS; i++) {
        const scad_value *v = &ca->slot[i].value;
        mci_buf buf = {0};
        bool ok;
        strings[i] = NULL;
        if (i == TEXT_SIZE || !scad_given(ca, i))
            continue;
        if (v->type != VAL_STRING && i != TEXT_TEXT)
            return scad_wrong_type(sc, ca, i, "a string", err);
        ok = v->type == VAL_STRING ? mci_buf_append(ctx, &buf, scad_string(sc->prog, v), v->count)
                                   : scad_format_value(&sc->ev, v, &buf);
        if (!ok || !mci_buf_append(ctx, &buf, "", 1)) {
            mci_buf_free(ctx, &buf);
            return mci_fail_nomem(err, "making text");
        }
        strings[i] = (char *)buf.data;
    }
    return MCSG_OK;
}

static mcsg_status text_outlines(scad_context *sc, const scad_call_args *ca, mci_outlines *o,
                                 mci_buf *label, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    char *strings[TEXT_STRINGS] = {NULL};
    mci_text_params p;
    mcsg_resolution res;
    mci_region check = {0};
    mci_outlines filled = {0};
    mcsg_status st;
    memset(&p, 0, sizeof p);
    p.size = 10;
    p.spacing = 1;
    st = scad_arg_number(sc, ca, TEXT_SIZE, &p.size, err);
    if (st == MCSG_OK)
        st = scad_arg_number(sc, ca, TEXT_SPACING, &p.spacing, err);
    if (st == MCSG_OK)
        st = scad_get_resolution(sc, ca, &res, err);
    if (st == MCSG_OK)
        st = text_strings(sc, ca, strings, err);
    if (st == MCSG_OK) {
        p.text = strings[TEXT_TEXT];
        p.font = strings[TEXT_FONT];
        p.halign = strings[TEXT_HALIGN];
        p.valign = strings[TEXT_VALIGN];
        p.direction = strings[TEXT_DIRECTION];
        p.language = strings[TEXT_LANGUAGE];
        p.script = strings[TEXT_SCRIPT];
        p.fn = res.fn;
        p.fa = res.fa;
        p.fs = res.fs;
        st = mci_text_outlines(ctx, &p, o, err);
        st = st == MCSG_OK || st == MCSG_ERR_NOMEM ? st : scad_at_call(sc, ca, st, err);
    }
    /* Loops that cross (composite glyphs, glyphs set close) are filled non-zero first. */
    if (st == MCSG_OK && mci_region_from_outlines(ctx, o, &check, err) == MCSG_ERR_UNSUPPORTED) {
        st = scad_fill_nonzero(sc, o, &filled, err);
        if (st == MCSG_OK) {
            mci_outlines_free(ctx, o);
            *o = filled;
        }
    }
    mci_region_free(ctx, &check);
    if (st == MCSG_OK &&
        (!mci_buf_printf(ctx, label, "text(\"%s\"", p.text ? p.text : "") ||
         !scad_put_number(ctx, label, ", size=", p.size) ||
         !mci_buf_printf(ctx, label, "%s%s%s)", p.font ? ", font=\"" : "",
                         p.font ? p.font : "", p.font ? "\"" : "")))
        st = mci_fail_nomem(err, "reading CSG text");
    for (int i = 0; i < TEXT_STRINGS; i++)
        mci_free(ctx, strings[i]);
    return st;
}

/* The 2D part of a 3D transform (x, y and the translation), applied to the points;
 * false when it flattens the plane. */
static bool transform_outlines(const double m[12], mci_outlines *o)
{
    if (m[0] * m[5] - m[1] * m[4] == 0)
        return false;
    for (size_t i = 0; i < o->point_count; i++) {
        double x = o->xy[2 * i], y = o->xy[2 * i + 1];
        o->xy[2 * i] = m[0] * x + m[1] * y + m[3];
        o->xy[2 * i + 1] = m[4] * x + m[5] * y + m[7];
    }
    return true;
}

mcsg_status scad_add_shape(scad_context *sc, const scad_call_args *ca,
                           const scad_transform *t, struct mci_outlines *o, mci_buf *label,
                           mcsg_node_id *node, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mci_region region = {0};
    mcsg_mesh prism = {0};
    bool flat = !transform_outlines(t->m, o);
    mcsg_status st = MCSG_OK;
    if (!flat) {
        st = mci_region_from_outlines(ctx, o, &region, err);
        st = st == MCSG_ERR_NOMEM ? st : scad_at_call(sc, ca, st, err);
    }
    if (st == MCSG_OK && region.tri_count > 0)
        st = mci_region_prism(ctx, &region, &prism, err);
    mci_region_free(ctx, &region);
    if (st == MCSG_OK &&
        !mci_buf_printf(ctx, label, " at %s:%u:%u%s", sc->name, ca->stmt->line, ca->stmt->col,
                        prism.triangle_count ? "" : flat ? " (empty: flattened by a transform)"
                                                         : " (empty)"))
        st = mci_fail_nomem(err, "reading CSG text");
    if (st != MCSG_OK) {
        mci_mesh_free(ctx, &prism);
        return st;
    }
    if (prism.triangle_count)
        return scad_at_call(sc, ca, mci_tree_add_leaf_owned(sc->tree, &prism,
                                                            (const char *)label->data, node,
                                                            err), err);
    if (flat)
        scad_warn_at(ctx, sc->name, ca->stmt->line, ca->stmt->col, "%s() is scaled to zero "
                     "area: removing it", ca->module);
    else
        scad_warn_at(ctx, sc->name, ca->stmt->line, ca->stmt->col, "%s() is empty", ca->module);
    return scad_at_call(sc, ca, mcsg_tree_add_op(sc->tree, MCSG_NODE_UNION, NULL, 0,
                                                 (const char *)label->data, node, err), err);
}

/* import()'s layer (or the legacy layername), origin and scale for a DXF drawing. */
static mcsg_status dxf_args(scad_context *sc, const scad_call_args *ca, char **layer,
                            double origin[2], double *scale, mcsg_error *err)
{
    int slot = !scad_given(ca, IMPORT_LAYER) && scad_given(ca, IMPORT_LAYERNAME) ? IMPORT_LAYERNAME
                                                                                : IMPORT_LAYER;
    const scad_value *l = &ca->slot[slot].value, *o = &ca->slot[IMPORT_ORIGIN].value;
    double v[3];
    mcsg_status st = scad_arg_number(sc, ca, IMPORT_SCALE, scale, err);
    *layer = NULL;
    if (st == MCSG_OK && scad_given(ca, IMPORT_ORIGIN)) {
        if (o->type != VAL_VECTOR || o->count != 2 || !scad_get_vec3(sc, o, true, 0, v) ||
            !isfinite(v[0]) || !isfinite(v[1]))
            return scad_wrong_type(sc, ca, IMPORT_ORIGIN, "a vector of 2 finite numbers", err);
        origin[0] = v[0];
        origin[1] = v[1];
    }
    if (st == MCSG_OK && !(*scale > 0 && isfinite(*scale)))
        *scale = 1; /* OpenSCAD: a scale of 0 or less is 1 */
    if (st == MCSG_OK && scad_given(ca, slot)) {
        if (l->type != VAL_STRING)
            return scad_wrong_type(sc, ca, slot, "a layer name (a string)", err);
        if (!(*layer = mci_malloc(sc->ev.ctx, l->count + 1)))
            return mci_fail_nomem(err, "reading a DXF file");
        memcpy(*layer, scad_string(sc->prog, l), l->count);
        (*layer)[l->count] = 0;
    }
    return st;
}

mcsg_status scad_add_dxf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                         const char *file, uint32_t file_len, const char *path,
                         const scad_dxf_view *view, mcsg_node_id *node, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    const char *layer = view->layer;
    const mcsg_resolution *res = &view->res;
    mci_outlines o = {0};
    mci_buf label = {0};
    mcsg_error read_err = {MCSG_OK, ""};
    mcsg_status st = mci_dxf_read(ctx, path, layer, view->origin, view->scale, res->fn,
                                  res->fa, res->fs, &o, &read_err);
    if (st != MCSG_OK && st != MCSG_ERR_NOMEM)
        st = scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, st,
                          "%s(\"%.*s\"): %s", ca->module, (int)file_len, file,
                          read_err.message);
    else if (st != MCSG_OK)
        *err = read_err;
    if (st == MCSG_OK &&
        !mci_buf_printf(ctx, &label, "import(\"%.*s\"%s%s%s)", (int)file_len, file,
                        layer ? ", layer=\"" : "", layer ? layer : "", layer ? "\"" : ""))
        st = mci_fail_nomem(err, "reading CSG text");
    if (st == MCSG_OK)
        st = scad_add_shape(sc, ca, t, &o, &label, node, err);
    mci_outlines_free(ctx, &o);
    mci_buf_free(ctx, &label);
    return st;
}

mcsg_status scad_import_dxf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                            const char *file, uint32_t file_len, const char *path,
                            mcsg_node_id *node, mcsg_error *err)
{
    scad_dxf_view view = {NULL, {0, 0}, 1, {0, 0, 0}};
    char *layer = NULL;
    mcsg_status st = dxf_args(sc, ca, &layer, view.origin, &view.scale, err);
    if (st == MCSG_OK)
        st = scad_get_resolution(sc, ca, &view.res, err);
    view.layer = layer;
    if (st == MCSG_OK)
        st = scad_add_dxf(sc, ca, t, file, file_len, path, &view, node, err);
    mci_free(sc->ev.ctx, layer);
    return st;
}

/* import()'s center and dpi for an SVG drawing, as OpenSCAD reads them: center only
 * when a boolean, dpi only when a number of at least 0.001 (else 72, with a warning). */
static void svg_args(scad_context *sc, const scad_call_args *ca, bool *center, double *dpi)
{
    const scad_value *c = &ca->slot[IMPORT_CENTER].value, *d = &ca->slot[IMPORT_DPI].value;
    *center = c->type == VAL_BOOL && c->number != 0;
    *dpi = 72;
    if (d->type != VAL_NUMBER)
        return;
    if (d->number >= 0.001)
        *dpi = d->number;
    else
        scad_warn_at(sc->ev.ctx, sc->name, ca->slot[IMPORT_DPI].line, ca->slot[IMPORT_DPI].col,
                     "Invalid dpi value giving, using default of 72 dpi. Value must be "
                     "positive and >= 0.001");
}

/* Shape k of the drawing as outlines of its own, filled by the even-odd rule as
 * OpenSCAD fills it; when its loops cross (which that fill cannot take here), by the
 * non-zero rule instead, with a warning. *empty when it encloses nothing. */
static mcsg_status svg_shape(scad_context *sc, const scad_call_args *ca, const mci_svg *svg,
                             size_t k, const char *file, uint32_t file_len, mci_outlines *o,
                             bool *empty, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    uint32_t first = svg->shape_start[k], end = svg->shape_start[k + 1];
    uint32_t p0 = svg->outlines.loop_start[first], points = svg->outlines.loop_start[end] - p0;
    mci_region r = {0};
    mcsg_status st = alloc_outlines(ctx, o, points, end - first, err);
    if (st != MCSG_OK)
        return st;
    memcpy(o->xy, svg->outlines.xy + 2 * (size_t)p0, 2 * sizeof *o->xy * points);
    for (uint32_t i = first; i <= end; i++)
        o->loop_start[i - first] = svg->outlines.loop_start[i] - p0;
    o->point_count = points;
    o->loop_count = end - first;
    st = mci_region_from_outlines(ctx, o, &r, err);
    *empty = st == MCSG_OK && r.tri_count == 0;
    mci_region_free(ctx, &r);
    if (st == MCSG_ERR_UNSUPPORTED) {
        mci_outlines filled = {0};
        scad_warn_at(ctx, sc->name, ca->stmt->line, ca->stmt->col,
                     "import(\"%.*s\"): the outlines of the shape at line %u cross: filled by "
                     "the non-zero rule, not OpenSCAD's even-odd rule", (int)file_len, file,
                     (unsigned)svg->shape_line[k]);
        st = scad_fill_nonzero(sc, o, &filled, err);
        if (st == MCSG_OK) {
            mci_outlines_free(ctx, o);
            *o = filled;
            *empty = o->loop_count == 0;
        }
    }
    return st;
}

/* The drawing's non-empty shapes as leaves, united under *node. */
static mcsg_status svg_leaves(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                              const mci_svg *svg, const char *file, uint32_t file_len,
                              mcsg_node_id *node, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_node_id *ids = mci_malloc_array(ctx, svg->shape_count + 1, sizeof *ids);
    size_t count = 0;
    mci_buf label = {0};
    mcsg_status st = ids ? MCSG_OK : mci_fail_nomem(err, "reading an SVG file");
    for (size_t k = 0; st == MCSG_OK && k < svg->shape_count; k++) {
        mci_outlines o = {0};
        bool empty = false;
        st = svg_shape(sc, ca, svg, k, file, file_len, &o, &empty, err);
        label.len = 0;
        if (st == MCSG_OK && !empty &&
            !mci_buf_printf(ctx, &label, "import(\"%.*s\") shape at line %u", (int)file_len,
                            file, (unsigned)svg->shape_line[k]))
            st = mci_fail_nomem(err, "reading CSG text");
        if (st == MCSG_OK && !empty)
            st = scad_add_shape(sc, ca, t, &o, &label, &ids[count++], err);
        mci_outlines_free(ctx, &o);
    }
    label.len = 0;
    if (st == MCSG_OK && count != 1 &&
        !mci_buf_printf(ctx, &label, "import(\"%.*s\")", (int)file_len, file))
        st = mci_fail_nomem(err, "reading CSG text");
    if (st == MCSG_OK && count == 0) {
        mci_outlines none = {0};
        st = scad_add_shape(sc, ca, t, &none, &label, node, err);
    } else if (st == MCSG_OK && count == 1) {
        *node = ids[0];
    } else if (st == MCSG_OK) {
        st = mci_buf_printf(ctx, &label, " at %s:%u:%u", sc->name, ca->stmt->line, ca->stmt->col)
                 ? mcsg_tree_add_op(sc->tree, MCSG_NODE_UNION, ids, count,
                                    (const char *)label.data, node, err)
                 : mci_fail_nomem(err, "reading CSG text");
    }
    mci_buf_free(ctx, &label);
    mci_free(ctx, ids);
    return st;
}

mcsg_status scad_import_svg(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                            const char *file, uint32_t file_len, const char *path,
                            mcsg_node_id *node, mcsg_error *err)
{
    mci_svg svg = {0};
    mcsg_error read_err = {MCSG_OK, ""};
    bool center;
    double dpi;
    mcsg_status st;
    svg_args(sc, ca, &center, &dpi);
    st = mci_svg_read(sc->ev.ctx, path, dpi, center, &svg, &read_err);
    if (st != MCSG_OK && st != MCSG_ERR_NOMEM)
        return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, st,
                            "import(\"%.*s\"): %s", (int)file_len, file, read_err.message);
    if (st != MCSG_OK) {
        *err = read_err;
        return st;
    }
    st = svg_leaves(sc, ca, t, &svg, file, file_len, node, err);
    mci_svg_free(sc->ev.ctx, &svg);
    return st;
}

mcsg_status scad_make_shape2d(scad_context *sc, const scad_call_args *ca,
                              const scad_transform *t, mcsg_node_id *node, mcsg_error *err)
{
    mci_outlines o = {0};
    mci_buf label = {0};
    mcsg_status st;
    switch ((scad_module)ca->stmt->module) {
    case MOD_CIRCLE: st = circle_outline(sc, ca, &o, &label, err); break;
    case MOD_SQUARE: st = square_outline(sc, ca, &o, &label, err); break;
    case MOD_TEXT: st = text_outlines(sc, ca, &o, &label, err); break;
    default: st = polygon_outlines(sc, ca, &o, &label, err); break;
    }
    if (st == MCSG_OK)
        st = scad_add_shape(sc, ca, t, &o, &label, node, err);
    mci_outlines_free(sc->ev.ctx, &o);
    mci_buf_free(sc->ev.ctx, &label);
    return st;
}
