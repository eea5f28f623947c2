/*
 * The built-in modules of the CSG language, following OpenSCAD's src/core/primitives.cc,
 * TransformNode.cc, ImportNode.cc and Parameters.cc:
 *  - arguments bind as in OpenSCAD's Parameters::parse: positional ones fill the
 *    parameter list in order (named-only parameters such as sphere's d come last in that
 *    list and can be reached positionally too), skipping those already given by name; a
 *    later duplicate overrides with a warning; unknown names and surplus positional
 *    arguments are ignored with a warning; $-arguments bind special variables for the
 *    call and its children; undef counts as not given;
 *  - where OpenSCAD warns about a value of the wrong type and falls back to a default,
 *    meshcsg stops with an error at the argument's line and column;
 *  - sphere r/d and cylinder r/d/r1/r2/d1/d2 follow OpenSCAD's precedence (a diameter
 *    beats its radius, r1/r2 beat r); $fa and $fs below 0.01 are clamped with a warning;
 *  - transforms: translate(v), rotate(a) with a about z or [x,y,z] as Rz*Ry*Rx,
 *    rotate(a, v) about an axis, scale(v or s), mirror(v) (reflection through the plane
 *    normal to v), multmatrix(m) padded with the identity and divided by m[3][3]; a
 *    transform that flattens space (zero scale, singular matrix) makes its leaves empty;
 *  - polyhedron faces are clockwise seen from outside, so each is reversed, then
 *    triangulated as OpenSCAD's export does (shape/tess.h: libtess2's triangles, which
 *    decide a non-planar face's volume); import reads OFF/OBJ/STL/PLY relative to the
 *    file's directory, 3MF as a leaf per build item and AMF as a leaf per object
 *    (OpenSCAD unions an AMF file's objects), DXF as 2D outlines.
 * The empty set is always a union node without children (e.g. cube(0), an empty mesh
 * from import or polyhedron, a leaf under a flattening transform).
 */
#include "base/numparse.h"
#include "io/amf.h"
#include "io/surface.h"
#include "mesh/tree.h"
#include "base/degree_trig.h"
#include "scad/scad.h"
#include "shape/tess.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define F_MINIMUM 0.01

/* Each module's parameter list in OpenSCAD's order (required, then optional). */
static const char *const module_params[MOD_COUNT][SCAD_MAX_PARAMS] = {
    [MOD_UNION] = {NULL},
    [MOD_DIFFERENCE] = {NULL},
    [MOD_INTERSECTION] = {NULL},
    [MOD_GROUP] = {NULL},
    [MOD_RENDER] = {"convexity", NULL},
    [MOD_COLOR] = {"c", "alpha", NULL},
    [MOD_TRANSLATE] = {"v", NULL},
    [MOD_ROTATE] = {"a", "v", NULL},
    [MOD_SCALE] = {"v", NULL},
    [MOD_MIRROR] = {"v", NULL},
    [MOD_MULTMATRIX] = {"m", NULL},
    [MOD_CUBE] = {"size", "center", NULL},
    [MOD_SPHERE] = {"r", "d", NULL},
    [MOD_CYLINDER] = {"h", "r1", "r2", "center", "r", "d", "d1", "d2", NULL},
    [MOD_POLYHEDRON] = {"points", "faces", "convexity", "triangles", NULL},
    [MOD_IMPORT] = {"file", "layer", "convexity", "origin", "scale", "width", "height",
                    "filename", "layername", "center", "dpi", "id", "timestamp", NULL},
    [MOD_SURFACE] = {"file", "center", "convexity", "invert", NULL},
    [MOD_CIRCLE] = {"r", "d", NULL},
    [MOD_SQUARE] = {"size", "center", NULL},
    [MOD_POLYGON] = {"points", "paths", "convexity", NULL},
    [MOD_TEXT] = {"text", "size", "font", "direction", "language", "script", "halign", "valign",
                  "spacing", NULL},
    [MOD_LINEAR_EXTRUDE] = {"file", "layer", "height", "origin", "scale", "center", "twist",
                            "slices", "convexity", NULL},
    [MOD_ROTATE_EXTRUDE] = {"file", "layer", "origin", "scale", "convexity", "angle", NULL},
    [MOD_HULL] = {NULL},
    [MOD_MINKOWSKI] = {"convexity", NULL},
    [MOD_OFFSET] = {"r", "delta", "chamfer", NULL},
    [MOD_PROJECTION] = {"cut", "convexity", NULL},
    [MOD_RESIZE] = {"newsize", "auto", "convexity", NULL},
};

enum { CUBE_SIZE, CUBE_CENTER };
enum { SPHERE_R, SPHERE_D };
enum { CYL_H, CYL_R1, CYL_R2, CYL_CENTER, CYL_R, CYL_D, CYL_D1, CYL_D2 };
enum { POLY_POINTS, POLY_FACES, POLY_CONVEXITY, POLY_TRIANGLES };
enum { IMPORT_FILE, IMPORT_FILENAME = 7 };

mcsg_status scad_fail_at(const char *name, uint32_t line, uint32_t col, mcsg_error *err,
                         mcsg_status status, const char *fmt, ...)
{
    char where[MCSG_ERROR_MESSAGE_SIZE];
    va_list ap;
    snprintf(where, sizeof where, "%s:%u:%u", name, line, col);
    va_start(ap, fmt);
    mci_vfail(err, status, where, fmt, ap);
    va_end(ap);
    return status;
}

void scad_warn_at(const mci_ctx *ctx, const char *name, uint32_t line, uint32_t col,
                  const char *fmt, ...)
{
    char where[MCSG_ERROR_MESSAGE_SIZE];
    va_list ap;
    snprintf(where, sizeof where, "%s:%u:%u", name, line, col);
    va_start(ap, fmt);
    mci_vlog(ctx, MCSG_LOG_WARNING, where, fmt, ap);
    va_end(ap);
}

static int param_slot(scad_module module, const char *name, uint32_t len)
{
    for (int i = 0; module_params[module][i]; i++) {
        if (strlen(module_params[module][i]) == len &&
            memcmp(module_params[module][i], name, len) == 0)
            return i;
    }
    return -1;
}

/* The next parameter a positional argument fills, or -1. */
static int next_positional(const scad_call_args *ca, scad_module module, int *position)
{
    while (*position < SCAD_MAX_PARAMS && module_params[module][*position]) {
        int slot = (*position)++;
        if (!ca->slot[slot].named)
            return slot;
    }
    return -1;
}

/* Put a named argument's value in its parameter slot (or warn that it has none). */
static void bind_named(scad_context *sc, scad_call_args *ca, const scad_arg *arg,
                       const scad_value *value)
{
    const char *name = sc->prog->text + arg->name_start;
    int slot = param_slot((scad_module)ca->stmt->module, name, arg->name_len);
    if (slot < 0) {
        scad_warn_at(sc->ev.ctx, sc->name, arg->line, arg->col, "%s(): ignoring unknown "
                     "argument `%.*s`", ca->module, (int)arg->name_len, name);
        return;
    }
    if (ca->slot[slot].named || ca->slot[slot].line)
        scad_warn_at(sc->ev.ctx, sc->name, arg->line, arg->col, "%s(): argument `%.*s` %s",
                     ca->module, (int)arg->name_len, name, ca->slot[slot].named
                     ? "supplied more than once (the last one counts)"
                     : "overrides a positional argument");
    ca->slot[slot].value = *value;
    ca->slot[slot].line = arg->line;
    ca->slot[slot].col = arg->col;
    ca->slot[slot].named = true;
}

/* Evaluate and bind every argument of the call; $-arguments are bound as special
 * variables once all arguments are evaluated (they are evaluated in the caller's scope,
 * like the others). */
mcsg_status scad_bind_arguments(scad_context *sc, const scad_stmt *stmt, scad_call_args *ca,
                                  mcsg_error *err)
{
    const scad_arg *args = stmt->arg_count ? sc->prog->args + stmt->arg_begin : NULL;
    scad_module module = (scad_module)stmt->module;
    int position = 0;
    bool warned_surplus = false;
    uint32_t first_binding = sc->ev.binding_len;
    mcsg_status st = MCSG_OK;
    memset(ca, 0, sizeof *ca);
    ca->stmt = stmt;
    ca->module = scad_module_name(module);
    for (uint32_t i = 0; i < stmt->arg_count && st == MCSG_OK; i++) {
        const scad_arg *arg = &args[i];
        scad_value value;
        int slot;
        if (arg->var != SCAD_NONE)
            continue;
        st = scad_eval_expr(&sc->ev, arg->expr_begin, arg->expr_end, &value, err);
        if (st != MCSG_OK)
            break;
        if (arg->name_len) {
            bind_named(sc, ca, arg, &value);
        } else if ((slot = next_positional(ca, module, &position)) >= 0) {
            ca->slot[slot].value = value;
            ca->slot[slot].line = arg->line;
            ca->slot[slot].col = arg->col;
        } else if (!warned_surplus) {
            scad_warn_at(sc->ev.ctx, sc->name, arg->line, arg->col, "%s(): ignoring surplus "
                         "positional arguments", ca->module);
            warned_surplus = true;
        }
    }
    /* The special variables, all evaluated in the caller's scope before any of them
     * takes effect. */
    for (uint32_t i = 0; i < stmt->arg_count && st == MCSG_OK; i++) {
        scad_value value;
        if (args[i].var == SCAD_NONE)
            continue;
        st = scad_eval_expr(&sc->ev, args[i].expr_begin, args[i].expr_end, &value, err);
        if (st == MCSG_OK)
            st = scad_bind(&sc->ev, args[i].var, &value, false, err);
    }
    if (st == MCSG_OK)
        scad_activate_bindings(&sc->ev, first_binding);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Argument access */

bool scad_given(const scad_call_args *ca, int slot) { return ca->slot[slot].value.type != VAL_UNDEF; }

const scad_value *scad_element(const scad_context *sc, const scad_value *v, uint32_t i)
{
    return &sc->ev.heap[v->start + i];
}

mcsg_status scad_wrong_type(const scad_context *sc, const scad_call_args *ca, int slot,
                              const char *expected, mcsg_error *err)
{
    const scad_bound_arg *a = &ca->slot[slot];
    bool missing = a->line == 0; /* not given at all: point at the call */
    return scad_fail_at(sc->name, missing ? ca->stmt->line : a->line,
                        missing ? ca->stmt->col : a->col, err, MCSG_ERR_PARSE,
                        "%s(): `%s` must be %s, not %s", ca->module,
                        module_params[ca->stmt->module][slot], expected,
                        scad_type_name((scad_type)a->value.type));
}

/* A number, if given (else *x is left alone). */
mcsg_status scad_arg_number(const scad_context *sc, const scad_call_args *ca, int slot, double *x,
                              mcsg_error *err)
{
    if (!scad_given(ca, slot))
        return MCSG_OK;
    if (ca->slot[slot].value.type != VAL_NUMBER)
        return scad_wrong_type(sc, ca, slot, "a number", err);
    *x = ca->slot[slot].value.number;
    return MCSG_OK;
}

mcsg_status scad_arg_bool(const scad_context *sc, const scad_call_args *ca, int slot, bool *b,
                            mcsg_error *err)
{
    if (!scad_given(ca, slot))
        return MCSG_OK;
    if (ca->slot[slot].value.type != VAL_BOOL)
        return scad_wrong_type(sc, ca, slot, "true or false", err);
    *b = ca->slot[slot].value.number != 0;
    return MCSG_OK;
}

/* A vector of 3 numbers, or of 2 when two_ok (the third is then `z`). */
bool scad_get_vec3(const scad_context *sc, const scad_value *v, bool two_ok, double z,
                     double out[3])
{
    if (v->type != VAL_VECTOR || !(v->count == 3 || (two_ok && v->count == 2)))
        return false;
    for (uint32_t i = 0; i < v->count; i++) {
        if (scad_element(sc, v, i)->type != VAL_NUMBER)
            return false;
    }
    for (uint32_t i = 0; i < 3; i++)
        out[i] = i < v->count ? scad_element(sc, v, i)->number : z;
    return true;
}

mcsg_status scad_arg_finite_vec3(const scad_context *sc, const scad_call_args *ca, int slot,
                                   double z, double out[3], mcsg_error *err)
{
    if (!scad_get_vec3(sc, &ca->slot[slot].value, true, z, out))
        return scad_wrong_type(sc, ca, slot, "a vector of 2 or 3 numbers", err);
    if (!isfinite(out[0]) || !isfinite(out[1]) || !isfinite(out[2]))
        return scad_fail_at(sc->name, ca->slot[slot].line, ca->slot[slot].col, err,
                            MCSG_ERR_PARSE, "%s(): `%s` must be finite", ca->module,
                            module_params[ca->stmt->module][slot]);
    return MCSG_OK;
}

/* OpenSCAD's lookup_radius: the diameter, halved, if given; else the radius. */
mcsg_status scad_arg_radius(const scad_context *sc, const scad_call_args *ca, int d_slot,
                              int r_slot, double *r, bool *defined, mcsg_error *err)
{
    double d = 0;
    mcsg_status st = scad_arg_number(sc, ca, d_slot, &d, err);
    if (st == MCSG_OK)
        st = scad_arg_number(sc, ca, r_slot, r, err);
    *defined = scad_given(ca, d_slot) || scad_given(ca, r_slot);
    if (st != MCSG_OK || !scad_given(ca, d_slot))
        return st;
    if (scad_given(ca, r_slot))
        scad_warn_at(sc->ev.ctx, sc->name, ca->slot[r_slot].line, ca->slot[r_slot].col,
                     "%s(): ignoring `%s` as `%s` is given too", ca->module,
                     module_params[ca->stmt->module][r_slot],
                     module_params[ca->stmt->module][d_slot]);
    *r = d / 2.0;
    return MCSG_OK;
}

/* $fn, $fa, $fs in scope, with OpenSCAD's clamping of $fa and $fs. */
mcsg_status scad_get_resolution(scad_context *sc, const scad_call_args *ca, mcsg_resolution *res,
                                  mcsg_error *err)
{
    static const uint32_t vars[3] = {VAR_FN, VAR_FA, VAR_FS};
    static const char *const names[3] = {"$fn", "$fa", "$fs"};
    double v[3];
    for (int i = 0; i < 3; i++) {
        scad_value value = scad_lookup(&sc->ev, vars[i]);
        if (value.type != VAL_NUMBER)
            return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, MCSG_ERR_PARSE,
                                "%s(): %s must be a number, not %s", ca->module, names[i],
                                scad_type_name((scad_type)value.type));
        v[i] = value.number;
        if (i > 0 && v[i] < F_MINIMUM) {
            scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col,
                         "%s(): %s too small, clamping to 0.01", ca->module, names[i]);
            v[i] = F_MINIMUM;
        }
    }
    res->fn = v[0];
    res->fa = v[1];
    res->fs = v[2];
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */
/* Labels and leaves */

bool scad_put_number(const mci_ctx *ctx, mci_buf *buf, const char *prefix, double x)
{
    char text[MCI_DOUBLE_TEXT_MAX];
    mci_format_double(text, x);
    return mci_buf_printf(ctx, buf, "%s%s", prefix, text);
}

bool scad_put_resolution(const mci_ctx *ctx, mci_buf *buf, const mcsg_resolution *res)
{
    if (res->fn > 0)
        return scad_put_number(ctx, buf, ", $fn=", res->fn);
    return scad_put_number(ctx, buf, ", $fa=", res->fa) && scad_put_number(ctx, buf, ", $fs=", res->fs);
}

bool scad_is_identity(const double m[12])
{
    static const double id[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    for (int i = 0; i < 12; i++) {
        if (m[i] != id[i])
            return false;
    }
    return true;
}

/* Give a failure from a library call (a size limit, say) the call's position; an
 * allocation failure keeps its plain message. */
mcsg_status scad_at_call(const scad_context *sc, const scad_call_args *ca, mcsg_status st,
                           mcsg_error *err)
{
    char message[MCSG_ERROR_MESSAGE_SIZE];
    if (st == MCSG_OK || st == MCSG_ERR_NOMEM || !err)
        return st;
    memcpy(message, err->message, sizeof message);
    message[sizeof message - 1] = 0;
    return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, st, "%s(): %s",
                        ca->module, message);
}

/* The leaf's mesh in the coordinates of its innermost frame (mesh/tree.h), made from the
 * untransformed mesh when a frame is open; else left empty. */
static mcsg_status frame_local_mesh(const mci_ctx *ctx, const scad_transform *t,
                                    const mcsg_mesh *mesh, mcsg_mesh *local, mcsg_error *err)
{
    mcsg_status st;
    memset(local, 0, sizeof *local);
    if (!t->in_frame)
        return MCSG_OK;
    st = mci_mesh_alloc(ctx, local, mesh->vertex_count, mesh->triangle_count, err);
    if (st != MCSG_OK)
        return st;
    memcpy(local->vertices, mesh->vertices, mesh->vertex_count * 3 * sizeof(double));
    memcpy(local->triangles, mesh->triangles, mesh->triangle_count * 3 * sizeof(uint32_t));
    if (!scad_is_identity(t->rel))
        mcsg_mesh_transform(local, t->rel);
    return MCSG_OK;
}

/* Add the transformed leaf, and its local mesh inside a frame (both taken). */
static mcsg_status add_framed_leaf(scad_context *sc, const scad_call_args *ca, mcsg_mesh *mesh,
                                   mcsg_mesh *local, const char *label, mcsg_node_id *node,
                                   mcsg_error *err)
{
    mcsg_status st = mci_tree_add_leaf_owned(sc->tree, mesh, label, node, err);
    if (st == MCSG_OK && local->vertices)
        mci_tree_set_local(sc->tree, *node, local);
    mci_mesh_free(sc->ev.ctx, local);
    return scad_at_call(sc, ca, st, err);
}

/* Add the leaf for `mesh` (taking it) under transform t, labelled "<label> at F:L:C";
 * an empty mesh or a flattening transform gives the empty set instead. */
mcsg_status scad_add_leaf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                            mcsg_mesh *mesh, mci_buf *label, mcsg_node_id *node,
                            mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    bool empty = t->degenerate || mesh->triangle_count == 0;
    int call_len = (int)label->len; /* the call as written, e.g. import("a.off") */
    mcsg_status st;
    if (!mci_buf_printf(ctx, label, " at %s:%u:%u%s", sc->name, ca->stmt->line, ca->stmt->col,
                        !empty ? "" : t->degenerate ? " (empty: flattened by a transform)"
                                                    : " (empty)")) {
        mci_mesh_free(ctx, mesh);
        return mci_fail_nomem(err, "reading CSG text");
    }
    if (!empty) {
        mcsg_mesh local;
        st = frame_local_mesh(ctx, t, mesh, &local, err);
        if (st != MCSG_OK) {
            mci_mesh_free(ctx, mesh);
            return st;
        }
        if (!scad_is_identity(t->m))
            mcsg_mesh_transform(mesh, t->m);
        for (size_t i = 0; i < 3 * mesh->vertex_count; i++) {
            if (!isfinite(mesh->vertices[i])) {
                mci_mesh_free(ctx, mesh);
                mci_mesh_free(ctx, &local);
                return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err,
                                    MCSG_ERR_PARSE, "%.*s: vertex %zu is not finite%s",
                                    call_len, (const char *)label->data, i / 3,
                                    scad_is_identity(t->m) ? ""
                                    : " after the transforms above it");
            }
        }
        return add_framed_leaf(sc, ca, mesh, &local, (const char *)label->data, node, err);
    }
    if (!t->degenerate)
        scad_warn_at(ctx, sc->name, ca->stmt->line, ca->stmt->col, "%s() is empty",
                     ca->module);
    mci_mesh_free(ctx, mesh);
    st = mcsg_tree_add_op(sc->tree, MCSG_NODE_UNION, NULL, 0, (const char *)label->data, node,
                          err);
    return scad_at_call(sc, ca, st, err);
}

mcsg_status scad_nomem_label(mcsg_mesh *mesh, const mci_ctx *ctx, mcsg_error *err)
{
    mci_mesh_free(ctx, mesh);
    return mci_fail_nomem(err, "reading CSG text");
}

static mcsg_status make_cube(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                             mci_buf *label, mcsg_node_id *node, mcsg_error *err)
{
    const scad_value *size = &ca->slot[CUBE_SIZE].value;
    double s[3] = {1, 1, 1};
    bool center = false;
    mcsg_mesh mesh;
    mcsg_status st = MCSG_OK;
    if (size->type == VAL_NUMBER)
        s[0] = s[1] = s[2] = size->number;
    else if (scad_given(ca, CUBE_SIZE) && !scad_get_vec3(sc, size, false, 0, s))
        st = scad_wrong_type(sc, ca, CUBE_SIZE, "a number or a vector of 3 numbers", err);
    if (st == MCSG_OK)
        st = scad_arg_bool(sc, ca, CUBE_CENTER, &center, err);
    if (st == MCSG_OK)
        st = scad_at_call(sc, ca, mcsg_make_cube(s, center, sc->opts, &mesh, err), err);
    if (st != MCSG_OK)
        return st;
    if (!scad_put_number(sc->ev.ctx, label, "cube(size=[", s[0]) ||
        !scad_put_number(sc->ev.ctx, label, ", ", s[1]) || !scad_put_number(sc->ev.ctx, label, ", ", s[2]) ||
        !mci_buf_printf(sc->ev.ctx, label, "], center=%s)", center ? "true" : "false"))
        return scad_nomem_label(&mesh, sc->ev.ctx, err);
    return scad_add_leaf(sc, ca, t, &mesh, label, node, err);
}

static mcsg_status make_sphere(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                               mci_buf *label, mcsg_node_id *node, mcsg_error *err)
{
    double r = 1;
    bool defined;
    mcsg_resolution res;
    mcsg_mesh mesh;
    mcsg_status st = scad_arg_radius(sc, ca, SPHERE_D, SPHERE_R, &r, &defined, err);
    if (st == MCSG_OK)
        st = scad_get_resolution(sc, ca, &res, err);
    if (st == MCSG_OK)
        st = scad_at_call(sc, ca, mcsg_make_sphere(r, res, sc->opts, &mesh, err), err);
    if (st != MCSG_OK)
        return st;
    if (!scad_put_number(sc->ev.ctx, label, "sphere(r=", r) ||
        !scad_put_resolution(sc->ev.ctx, label, &res) || !mci_buf_printf(sc->ev.ctx, label, ")"))
        return scad_nomem_label(&mesh, sc->ev.ctx, err);
    return scad_add_leaf(sc, ca, t, &mesh, label, node, err);
}

/* OpenSCAD's cylinder radii: r sets both, r1/d1 and r2/d2 override it. */
static mcsg_status cylinder_radii(scad_context *sc, const scad_call_args *ca, double *r1,
                                  double *r2, mcsg_error *err)
{
    double r = 1, one = 1, two = 1;
    bool has_r, has_r1, has_r2;
    mcsg_status st = scad_arg_radius(sc, ca, CYL_D, CYL_R, &r, &has_r, err);
    if (st == MCSG_OK)
        st = scad_arg_radius(sc, ca, CYL_D1, CYL_R1, &one, &has_r1, err);
    if (st == MCSG_OK)
        st = scad_arg_radius(sc, ca, CYL_D2, CYL_R2, &two, &has_r2, err);
    if (st != MCSG_OK)
        return st;
    if (has_r && (has_r1 || has_r2))
        scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col,
                     "cylinder(): parameters ambiguous (r or d together with r1, r2, d1 or d2)");
    *r1 = has_r1 ? one : has_r ? r : 1;
    *r2 = has_r2 ? two : has_r ? r : 1;
    return MCSG_OK;
}

static mcsg_status make_cylinder(scad_context *sc, const scad_call_args *ca,
                                 const scad_transform *t, mci_buf *label, mcsg_node_id *node,
                                 mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    double h = 1, r1, r2;
    bool center = false;
    mcsg_resolution res;
    mcsg_mesh mesh;
    mcsg_status st = scad_arg_number(sc, ca, CYL_H, &h, err);
    if (st == MCSG_OK)
        st = cylinder_radii(sc, ca, &r1, &r2, err);
    if (st == MCSG_OK)
        st = scad_arg_bool(sc, ca, CYL_CENTER, &center, err);
    if (st == MCSG_OK)
        st = scad_get_resolution(sc, ca, &res, err);
    if (st == MCSG_OK)
        st = scad_at_call(sc, ca, mcsg_make_cylinder(h, r1, r2, center, res, sc->opts, &mesh, err),
                     err);
    if (st != MCSG_OK)
        return st;
    if (!scad_put_number(ctx, label, "cylinder(h=", h) || !scad_put_number(ctx, label, ", r1=", r1) ||
        !scad_put_number(ctx, label, ", r2=", r2) ||
        !mci_buf_printf(ctx, label, ", center=%s", center ? "true" : "false") ||
        !scad_put_resolution(ctx, label, &res) || !mci_buf_printf(ctx, label, ")"))
        return scad_nomem_label(&mesh, ctx, err);
    return scad_add_leaf(sc, ca, t, &mesh, label, node, err);
}

/* ---------------------------------------------------------------------------------- */
/* polyhedron and import */

static mcsg_status polyhedron_points(scad_context *sc, const scad_call_args *ca, mcsg_mesh *mesh,
                                     mcsg_error *err)
{
    const scad_bound_arg *a = &ca->slot[POLY_POINTS];
    for (uint32_t i = 0; i < a->value.count; i++) {
        double *p = mesh->vertices + 3 * (size_t)i;
        if (!scad_get_vec3(sc, scad_element(sc, &a->value, i), true, 0.0, p) || !isfinite(p[0]) ||
            !isfinite(p[1]) || !isfinite(p[2]))
            return scad_fail_at(sc->name, a->line, a->col, err, MCSG_ERR_PARSE,
                                "polyhedron(): points[%u] is not a vector of 2 or 3 finite "
                                "numbers", i);
    }
    return MCSG_OK;
}

/* Check one face's indices; *corners receives its size. */
static mcsg_status polyhedron_face(scad_context *sc, const scad_bound_arg *a, uint32_t f,
                                   uint32_t points, uint32_t *corners, mcsg_error *err)
{
    const scad_value *face = scad_element(sc, &a->value, f);
    if (face->type != VAL_VECTOR)
        return scad_fail_at(sc->name, a->line, a->col, err, MCSG_ERR_PARSE, "polyhedron(): "
                            "faces[%u] is %s, not a vector of point indices", f,
                            scad_type_name((scad_type)face->type));
    for (uint32_t k = 0; k < face->count; k++) {
        const scad_value *index = scad_element(sc, face, k);
        double x = index->number;
        if (index->type != VAL_NUMBER || !(x >= 0 && x < points) || x != floor(x)) {
            char text[MCI_DOUBLE_TEXT_MAX] = "";
            if (index->type == VAL_NUMBER)
                mci_format_double(text, x);
            return scad_fail_at(sc->name, a->line, a->col, err, MCSG_ERR_PARSE,
                                "polyhedron(): faces[%u][%u] = %s is not a point index "
                                "(the polyhedron has %u points)", f, k,
                                index->type == VAL_NUMBER ? text
                                : scad_type_name((scad_type)index->type), points);
        }
    }
    *corners = face->count;
    return MCSG_OK;
}

/* Each point's vertex: the first point with the same float coordinates (OpenSCAD
 * merges vertices by their float values before triangulating faces). */
static mcsg_status polyhedron_vertex_ids(const mci_ctx *ctx, const mcsg_mesh *mesh,
                                         uint32_t **ids, mcsg_error *err)
{
    size_t n = mesh->vertex_count;
    double *rounded = mci_malloc_array(ctx, 3 * (n ? n : 1), sizeof *rounded);
    *ids = mci_malloc_array(ctx, n ? n : 1, sizeof **ids);
    bool ok = rounded && *ids;
    for (size_t i = 0; ok && i < 3 * n; i++)
        rounded[i] = (double)(float)mesh->vertices[i];
    ok = ok && mci_first_equal_coordinates(ctx, rounded, n, *ids);
    mci_free(ctx, rounded);
    if (ok)
        return MCSG_OK;
    mci_free(ctx, *ids);
    *ids = NULL;
    return mci_fail_nomem(err, "triangulating polyhedron faces");
}

/* One face reversed (OpenSCAD's faces are clockwise from outside) and triangulated as
 * OpenSCAD does (shape/tess.h); its triangles appended at *t. */
static mcsg_status polyhedron_face_triangles(scad_context *sc, const scad_value *face,
                                             const mcsg_mesh *mesh, const uint32_t *canon,
                                             mci_tess **tess, mci_buf *scratch, uint32_t **t,
                                             mci_tess_how *how, mcsg_error *err)
{
    uint32_t n = face->count, count = 0;
    size_t need = (size_t)n * (3 * sizeof(double) + 2 * sizeof(uint32_t));
    if (!mci_buf_reserve(sc->ev.ctx, scratch, need))
        return mci_fail_nomem(err, "triangulating polyhedron faces");
    double *xyz = (double *)scratch->data;
    uint32_t *point = (uint32_t *)(xyz + 3 * (size_t)n), *ids = point + n;
    for (uint32_t k = 0; k < n; k++) {
        point[k] = canon[(uint32_t)scad_element(sc, face, n - 1 - k)->number];
        ids[k] = point[k];
        memcpy(xyz + 3 * (size_t)k, mesh->vertices + 3 * (size_t)point[k], 3 * sizeof *xyz);
    }
    mcsg_status st = mci_tess_face(sc->ev.ctx, tess, xyz, ids, n, *t, &count, how, err);
    for (uint32_t k = 0; st == MCSG_OK && k < 3 * count; k++)
        (*t)[k] = point[(*t)[k]];
    *t += 3 * (size_t)count;
    return st;
}

/* All faces' triangles; mesh->triangle_count becomes their number (at most the
 * n - 2 per face allocated). Faces that OpenSCAD's triangulation is not reproduced for
 * are fanned, with one warning. */
static mcsg_status polyhedron_triangles(scad_context *sc, const scad_bound_arg *a,
                                        mcsg_mesh *mesh, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    uint32_t *canon = NULL, *t = mesh->triangles, fans = 0;
    mci_tess *tess = NULL;
    mci_buf scratch = {0};
    mcsg_status st = polyhedron_vertex_ids(ctx, mesh, &canon, err);
    for (uint32_t f = 0; st == MCSG_OK && f < a->value.count; f++) {
        mci_tess_how how;
        st = polyhedron_face_triangles(sc, scad_element(sc, &a->value, f), mesh, canon, &tess,
                                       &scratch, &t, &how, err);
        fans += how == MCI_TESS_FAN;
    }
    mci_tess_free(ctx, &tess);
    mci_buf_free(ctx, &scratch);
    mci_free(ctx, canon);
    mesh->triangle_count = (size_t)(t - mesh->triangles) / 3;
    if (st == MCSG_OK && fans > 0)
        scad_warn_at(ctx, sc->name, a->line, a->col, "polyhedron(): %u faces cross or touch "
                     "themselves seen along their normal; triangulated as fans, which may "
                     "differ from OpenSCAD's triangles", fans);
    return st;
}

static const scad_bound_arg *polyhedron_faces_arg(scad_context *sc, const scad_call_args *ca)
{
    if (!scad_given(ca, POLY_FACES) && scad_given(ca, POLY_TRIANGLES)) {
        scad_warn_at(sc->ev.ctx, sc->name, ca->slot[POLY_TRIANGLES].line,
                     ca->slot[POLY_TRIANGLES].col, "polyhedron(): `triangles` is deprecated, "
                     "use `faces`");
        return &ca->slot[POLY_TRIANGLES];
    }
    return &ca->slot[POLY_FACES];
}

static mcsg_status make_polyhedron(scad_context *sc, const scad_call_args *ca,
                                   const scad_transform *t, mci_buf *label, mcsg_node_id *node,
                                   mcsg_error *err)
{
    const scad_bound_arg *faces = polyhedron_faces_arg(sc, ca);
    uint64_t triangles = 0;
    mcsg_mesh mesh;
    mcsg_status st = MCSG_OK;
    if (ca->slot[POLY_POINTS].value.type != VAL_VECTOR)
        return scad_wrong_type(sc, ca, POLY_POINTS, "a vector of points", err);
    if (faces->value.type != VAL_VECTOR)
        return scad_wrong_type(sc, ca, (int)(faces - ca->slot), "a vector of faces", err);
    for (uint32_t f = 0; f < faces->value.count && st == MCSG_OK; f++) {
        uint32_t corners = 0;
        st = polyhedron_face(sc, faces, f, ca->slot[POLY_POINTS].value.count, &corners, err);
        if (st == MCSG_OK && corners < 3)
            scad_warn_at(sc->ev.ctx, sc->name, faces->line, faces->col, "polyhedron(): "
                         "ignoring faces[%u], which has fewer than 3 points", f);
        triangles += corners >= 3 ? corners - 2 : 0;
    }
    if (st == MCSG_OK && triangles > UINT32_MAX)
        st = scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, MCSG_ERR_LIMIT,
                          "polyhedron(): more than %u triangles", UINT32_MAX);
    if (st == MCSG_OK)
        st = scad_at_call(sc, ca, mci_mesh_alloc(sc->ev.ctx, &mesh, ca->slot[POLY_POINTS].value.count,
                                            (size_t)triangles, err), err);
    if (st != MCSG_OK)
        return st;
    st = polyhedron_points(sc, ca, &mesh, err);
    if (st != MCSG_OK) {
        mci_mesh_free(sc->ev.ctx, &mesh);
        return st;
    }
    st = polyhedron_triangles(sc, faces, &mesh, err);
    if (st != MCSG_OK) {
        mci_mesh_free(sc->ev.ctx, &mesh);
        return scad_at_call(sc, ca, st, err);
    }
    if (!mci_buf_printf(sc->ev.ctx, label, "polyhedron(%zu points, %u faces)",
                        mesh.vertex_count, faces->value.count))
        return scad_nomem_label(&mesh, sc->ev.ctx, err);
    return scad_add_leaf(sc, ca, t, &mesh, label, node, err);
}

mcsg_status scad_file_path(scad_context *sc, const scad_call_args *ca, int slot,
                           const char **file, uint32_t *file_len, mci_buf *path,
                           mcsg_error *err)
{
    const scad_value *v = &ca->slot[slot].value;
    const char *dir = sc->base_dir;
    size_t dir_len = dir ? strlen(dir) : 0;
    if (v->type != VAL_STRING)
        return scad_wrong_type(sc, ca, slot, "a file name (a string)", err);
    *file = scad_string(sc->prog, v);
    *file_len = v->count;
    if (v->count == 0 || memchr(*file, 0, v->count))
        return scad_fail_at(sc->name, ca->slot[slot].line, ca->slot[slot].col, err,
                            MCSG_ERR_PARSE, "%s(): invalid file name", ca->module);
    if ((*file)[0] == '/' || dir_len == 0)
        dir_len = 0;
    if (!mci_buf_append(sc->ev.ctx, path, dir, dir_len) ||
        (dir_len && dir[dir_len - 1] != '/' && !mci_buf_append(sc->ev.ctx, path, "/", 1)) ||
        !mci_buf_append(sc->ev.ctx, path, *file, *file_len) ||
        !mci_buf_append(sc->ev.ctx, path, "", 1))
        return mci_fail_nomem(err, "reading CSG text");
    return MCSG_OK;
}

/* The file to import, resolved against the base directory, into `path`. */
static mcsg_status import_path(scad_context *sc, const scad_call_args *ca, const char **file,
                               uint32_t *file_len, mci_buf *path, mcsg_error *err)
{
    int slot = !scad_given(ca, IMPORT_FILE) && scad_given(ca, IMPORT_FILENAME) ? IMPORT_FILENAME
                                                                      : IMPORT_FILE;
    return scad_file_path(sc, ca, slot, file, file_len, path, err);
}

/* Leaves for the parts of an imported file, "import("f") WORD K (NAME)" with K numbers[k]
 * (k + 1 without numbers) and NAME names[k] (left out when ""), under a union when there
 * are several. Each mesh given to the tree (or freed by it on failure) is zeroed; the
 * caller frees the rest. */
static mcsg_status import_parts(scad_context *sc, const scad_call_args *ca,
                                const scad_transform *t, const char *file, uint32_t file_len,
                                const char *word, mcsg_mesh *meshes, char *const *names,
                                const size_t *numbers, size_t count, mcsg_node_id *node,
                                mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_node_id *leaves = mci_malloc_array(ctx, count, sizeof *leaves);
    mci_buf label = {0};
    mcsg_status st = leaves ? MCSG_OK : mci_fail_nomem(err, "reading CSG text");
    for (size_t k = 0; st == MCSG_OK && k < count; k++) {
        label.len = 0;
        if (!mci_buf_printf(ctx, &label, "import(\"%.*s\") %s %zu%s%s%s", (int)file_len, file,
                            word, numbers ? numbers[k] : k + 1, names[k][0] ? " (" : "",
                            names[k], names[k][0] ? ")" : ""))
            st = mci_fail_nomem(err, "reading CSG text"); /* meshes[k] left to the caller */
        else {
            st = scad_add_leaf(sc, ca, t, &meshes[k], &label, &leaves[k], err);
            memset(&meshes[k], 0, sizeof meshes[k]); /* the tree's now, or freed */
        }
    }
    if (st == MCSG_OK && count == 1)
        *node = leaves[0];
    else if (st == MCSG_OK) {
        label.len = 0;
        if (!mci_buf_printf(ctx, &label, "import(\"%.*s\") at %s:%u:%u", (int)file_len, file,
                            sc->name, ca->stmt->line, ca->stmt->col))
            st = mci_fail_nomem(err, "reading CSG text");
        else
            st = mcsg_tree_add_op(sc->tree, MCSG_NODE_UNION, leaves, count,
                                  (const char *)label.data, node, err);
    }
    mci_buf_free(ctx, &label);
    mci_free(ctx, leaves);
    return st;
}

/* A 3MF file's build items, one leaf each ("import("f.3mf") item 2 (Cylinder)"), under
 * a union when there are several. */
static mcsg_status import_3mf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                              const char *file, uint32_t file_len, const char *path,
                              mcsg_node_id *node, mcsg_error *err)
{
    mcsg_error read_err = {MCSG_OK, ""};
    mcsg_mesh *meshes;
    char **names;
    size_t count;
    mcsg_status st = mcsg_3mf_read(path, sc->opts, &meshes, &names, &count, &read_err);
    if (st != MCSG_OK)
        return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, st,
                            "import(\"%.*s\"): %s", (int)file_len, file, read_err.message);
    st = import_parts(sc, ca, t, file, file_len, "item", meshes, names, NULL, count, node, err);
    mcsg_3mf_free(meshes, names, count, sc->opts);
    return st;
}

/* An AMF file's objects with triangles, one leaf each ("import("f.amf") object 2
 * (Pyramid)", numbered in the file), under a union when there are several: OpenSCAD
 * unions its objects, each the triangles of all its volumes. Without any, the import is
 * empty, as OpenSCAD's is. */
static mcsg_status import_amf(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                              const char *file, uint32_t file_len, const char *path,
                              mcsg_node_id *node, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_error read_err = {MCSG_OK, ""};
    mci_amf_objects objects;
    size_t *numbers, kept = 0;
    mcsg_status st = mci_amf_read_file(ctx, path, &objects, &read_err);
    if (st == MCSG_ERR_NOMEM)
        return mci_fail_nomem(err, "reading CSG text");
    if (st != MCSG_OK)
        return scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, st,
                            "import(\"%.*s\"): %s", (int)file_len, file, read_err.message);
    if (!(numbers = mci_malloc_array(ctx, objects.count + 1, sizeof *numbers))) {
        mci_amf_objects_free(ctx, &objects);
        return mci_fail_nomem(err, "reading CSG text");
    }
    for (size_t k = 0; k < objects.count; k++) { /* empty objects to the back */
        if (objects.meshes[k].triangle_count == 0)
            continue;
        mcsg_mesh m = objects.meshes[kept];
        char *name = objects.names[kept];
        objects.meshes[kept] = objects.meshes[k], objects.meshes[k] = m;
        objects.names[kept] = objects.names[k], objects.names[k] = name;
        numbers[kept++] = k + 1;
    }
    if (kept > 0)
        st = import_parts(sc, ca, t, file, file_len, "object", objects.meshes, objects.names,
                          numbers, kept, node, err);
    else {
        mcsg_mesh empty = {0};
        mci_buf label = {0};
        st = mci_buf_printf(ctx, &label, "import(\"%.*s\")", (int)file_len, file)
                 ? scad_add_leaf(sc, ca, t, &empty, &label, node, err)
                 : mci_fail_nomem(err, "reading CSG text");
        mci_buf_free(ctx, &label);
    }
    mci_free(ctx, numbers);
    mci_amf_objects_free(ctx, &objects);
    return st;
}

static bool import_is_2d(const scad_context *sc, const scad_call_args *ca)
{
    int slot = !scad_given(ca, IMPORT_FILE) && scad_given(ca, IMPORT_FILENAME) ? IMPORT_FILENAME
                                                                              : IMPORT_FILE;
    const scad_value *v = &ca->slot[slot].value;
    return v->type == VAL_STRING && (scad_is_dxf_name(scad_string(sc->prog, v), v->count) ||
                                     scad_is_svg_name(scad_string(sc->prog, v), v->count));
}

/* surface(file, center, convexity | invert): a height map as a closed mesh. */
static mcsg_status make_surface(scad_context *sc, const scad_call_args *ca,
                                const scad_transform *t, mci_buf *label, mcsg_node_id *node,
                                mcsg_error *err)
{
    mci_buf path = {0};
    const char *file = "";
    uint32_t file_len = 0;
    bool center = false, invert = false;
    mcsg_error read_err = {MCSG_OK, ""};
    mcsg_mesh mesh = {0};
    mcsg_status st = import_path(sc, ca, &file, &file_len, &path, err);
    if (st == MCSG_OK)
        st = scad_arg_bool(sc, ca, 1, &center, err);
    if (st == MCSG_OK)
        st = scad_arg_bool(sc, ca, 3, &invert, err);
    if (st == MCSG_OK) {
        st = mci_surface_read(sc->ev.ctx, (const char *)path.data, center, invert, &mesh,
                              &read_err);
        if (st != MCSG_OK && st != MCSG_ERR_NOMEM)
            st = scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, st,
                              "surface(\"%.*s\"): %s", (int)file_len, file, read_err.message);
        else if (st != MCSG_OK)
            *err = read_err;
    }
    mci_buf_free(sc->ev.ctx, &path);
    if (st != MCSG_OK)
        return st;
    if (!mci_buf_printf(sc->ev.ctx, label, "surface(\"%.*s\", center=%s, invert=%s)",
                        (int)file_len, file, center ? "true" : "false",
                        invert ? "true" : "false"))
        return scad_nomem_label(&mesh, sc->ev.ctx, err);
    return scad_add_leaf(sc, ca, t, &mesh, label, node, err);
}

static mcsg_status make_import(scad_context *sc, const scad_call_args *ca, const scad_transform *t,
                               mci_buf *label, mcsg_node_id *node, mcsg_error *err)
{
    mci_buf path = {0};
    const char *file = "";
    uint32_t file_len = 0;
    mcsg_error read_err = {MCSG_OK, ""};
    mcsg_mesh mesh;
    bool prefetched = false;
    mcsg_status st = import_path(sc, ca, &file, &file_len, &path, err);
    if (st == MCSG_OK && scad_is_dxf_name(file, file_len)) {
        st = scad_import_dxf(sc, ca, t, file, file_len, (const char *)path.data, node, err);
        mci_buf_free(sc->ev.ctx, &path);
        return st;
    }
    if (st == MCSG_OK && scad_is_svg_name(file, file_len)) {
        st = scad_import_svg(sc, ca, t, file, file_len, (const char *)path.data, node, err);
        mci_buf_free(sc->ev.ctx, &path);
        return st;
    }
    if (st == MCSG_OK && scad_is_3mf_name(file, file_len)) {
        st = import_3mf(sc, ca, t, file, file_len, (const char *)path.data, node, err);
        mci_buf_free(sc->ev.ctx, &path);
        return st;
    }
    if (st == MCSG_OK && scad_is_amf_name(file, file_len)) {
        st = import_amf(sc, ca, t, file, file_len, (const char *)path.data, node, err);
        mci_buf_free(sc->ev.ctx, &path);
        return st;
    }
    if (st == MCSG_OK)
        st = scad_prefetch_take(sc, (const char *)path.data, &mesh, &prefetched, err);
    if (st == MCSG_OK && !prefetched) {
        st = mcsg_mesh_read((const char *)path.data, MCSG_FORMAT_AUTO, sc->opts, &mesh,
                            &read_err);
        if (st != MCSG_OK)
            st = scad_fail_at(sc->name, ca->stmt->line, ca->stmt->col, err, st,
                              "import(\"%.*s\"): %s", (int)file_len, file, read_err.message);
    }
    mci_buf_free(sc->ev.ctx, &path);
    if (st != MCSG_OK)
        return st;
    if (!mci_buf_printf(sc->ev.ctx, label, "import(\"%.*s\")", (int)file_len, file))
        return scad_nomem_label(&mesh, sc->ev.ctx, err);
    return scad_add_leaf(sc, ca, t, &mesh, label, node, err);
}

/* ---------------------------------------------------------------------------------- */
/* Transforms, as row-major 3x4 matrices */

static void set_linear(double m[12], const double l[9], const double t[3])
{
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++)
            m[4 * r + c] = l[3 * r + c];
        m[4 * r + 3] = t ? t[r] : 0.0;
    }
}

static mcsg_status translate_matrix(scad_context *sc, const scad_call_args *ca, double m[12],
                                    mcsg_error *err)
{
    static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double v[3] = {0, 0, 0};
    mcsg_status st = MCSG_OK;
    if (scad_given(ca, 0))
        st = scad_arg_finite_vec3(sc, ca, 0, 0.0, v, err);
    else
        scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col,
                     "translate(): no vector given");
    set_linear(m, id, v);
    return st;
}

/* rotate(a=[x, y, z]): OpenSCAD's Rz * Ry * Rx, written out term by term. */
static mcsg_status rotate_euler(scad_context *sc, const scad_call_args *ca, double l[9],
                                mcsg_error *err)
{
    const scad_value *a = &ca->slot[0].value;
    double s[3] = {0, 0, 0}, c[3] = {1, 1, 1};
    if (a->count > 3)
        return scad_wrong_type(sc, ca, 0, "a number or a vector of up to 3 numbers", err);
    for (uint32_t i = 0; i < a->count; i++) {
        const scad_value *angle = scad_element(sc, a, i);
        if (angle->type != VAL_NUMBER || !isfinite(angle->number))
            return scad_wrong_type(sc, ca, 0, "a number or a vector of up to 3 finite numbers", err);
        s[i] = mci_sin_degrees(angle->number);
        c[i] = mci_cos_degrees(angle->number);
    }
    if (scad_given(ca, 1))
        scad_warn_at(sc->ev.ctx, sc->name, ca->slot[1].line, ca->slot[1].col,
                     "rotate(): `v` is ignored when `a` is a vector");
    l[0] = c[1] * c[2];
    l[1] = c[2] * s[0] * s[1] - c[0] * s[2];
    l[2] = c[0] * c[2] * s[1] + s[0] * s[2];
    l[3] = c[1] * s[2];
    l[4] = c[0] * c[2] + s[0] * s[1] * s[2];
    l[5] = -c[2] * s[0] + c[0] * s[1] * s[2];
    l[6] = -s[1];
    l[7] = c[1] * s[0];
    l[8] = c[0] * c[1];
    return MCSG_OK;
}

static mcsg_status rotate_matrix(scad_context *sc, const scad_call_args *ca, double m[12],
                                 mcsg_error *err)
{
    double l[9], a = 0, axis[3] = {0, 0, 1};
    mcsg_status st = MCSG_OK;
    if (ca->slot[0].value.type == VAL_VECTOR) {
        st = rotate_euler(sc, ca, l, err);
    } else {
        if (!scad_given(ca, 0))
            scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col,
                         "rotate(): no angle given");
        st = scad_arg_number(sc, ca, 0, &a, err);
        if (st == MCSG_OK && !isfinite(a))
            st = scad_wrong_type(sc, ca, 0, "a finite number", err);
        if (st == MCSG_OK && scad_given(ca, 1))
            st = scad_arg_finite_vec3(sc, ca, 1, 0.0, axis, err);
        mci_angle_axis_degrees(a, axis, l);
    }
    set_linear(m, l, NULL);
    return st;
}

static mcsg_status scale_matrix(scad_context *sc, const scad_call_args *ca, double m[12],
                                mcsg_error *err)
{
    double v[3] = {1, 1, 1}, l[9] = {0};
    mcsg_status st = MCSG_OK;
    if (ca->slot[0].value.type == VAL_NUMBER)
        v[0] = v[1] = v[2] = ca->slot[0].value.number;
    else if (scad_given(ca, 0))
        st = scad_arg_finite_vec3(sc, ca, 0, 1.0, v, err);
    else
        scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col,
                     "scale(): no factor given");
    if (st == MCSG_OK && !(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2])))
        st = scad_wrong_type(sc, ca, 0, "finite", err);
    l[0] = v[0];
    l[4] = v[1];
    l[8] = v[2];
    set_linear(m, l, NULL);
    return st;
}

/* Reflection through the plane through the origin normal to v (identity for v = 0). */
static mcsg_status mirror_matrix(scad_context *sc, const scad_call_args *ca, double m[12],
                                 mcsg_error *err)
{
    double v[3] = {1, 0, 0}, l[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, a;
    mcsg_status st = MCSG_OK;
    if (scad_given(ca, 0))
        st = scad_arg_finite_vec3(sc, ca, 0, 0.0, v, err);
    else
        scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col,
                     "mirror(): no vector given, mirroring x");
    a = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if (st == MCSG_OK && (v[0] != 0.0 || v[1] != 0.0 || v[2] != 0.0)) {
        /* OpenSCAD's expressions: divide inside each term rather than normalising v. */
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 3; c++)
                l[3 * r + c] = (r == c) ? 1 - 2 * v[r] * v[r] / a : -2 * v[c] * v[r] / a;
        }
    }
    set_linear(m, l, NULL);
    return st;
}

/* multmatrix(m): up to 4 rows of up to 4 numbers over the identity, then divided by
 * m[3][3] when that is not 1; the bottom row is otherwise ignored (an affine map). */
static mcsg_status multmatrix_matrix(scad_context *sc, const scad_call_args *ca, double m[12],
                                     mcsg_error *err)
{
    const scad_value *rows = &ca->slot[0].value;
    double full[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, w;
    if (!scad_given(ca, 0))
        scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col,
                     "multmatrix(): no matrix given");
    else if (rows->type != VAL_VECTOR || rows->count > 4)
        return scad_wrong_type(sc, ca, 0, "a matrix of up to 4 rows of up to 4 numbers", err);
    for (uint32_t r = 0; scad_given(ca, 0) && r < rows->count; r++) {
        const scad_value *row = scad_element(sc, rows, r);
        if (row->type != VAL_VECTOR || row->count > 4)
            return scad_wrong_type(sc, ca, 0, "a matrix of up to 4 rows of up to 4 numbers", err);
        for (uint32_t c = 0; c < row->count; c++) {
            if (scad_element(sc, row, c)->type != VAL_NUMBER)
                return scad_wrong_type(sc, ca, 0, "a matrix of numbers", err);
            full[4 * r + c] = scad_element(sc, row, c)->number;
        }
    }
    w = full[15];
    for (int i = 0; i < 12; i++) {
        m[i] = w != 1.0 ? full[i] / w : full[i];
        if (!isfinite(m[i]))
            return scad_fail_at(sc->name, ca->slot[0].line, ca->slot[0].col, err,
                                MCSG_ERR_PARSE, "multmatrix(): the matrix is not finite%s",
                                w == 0 ? " (m[3][3] is 0)" : "");
    }
    return MCSG_OK;
}

/* parent * own, with Eigen's order of operations for a 4x4 affine product. */
static void compose(const double p[12], const double o[12], double out[12])
{
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 4; c++) {
            double sum = p[4 * r] * o[c] + p[4 * r + 1] * o[4 + c] + p[4 * r + 2] * o[8 + c];
            out[4 * r + c] = c == 3 ? sum + p[4 * r + 3] : sum;
        }
    }
}

/* Whether a linear map can tilt a plane off the axes' directions: some row has two
 * non-zero entries (a scaling along the axes, with the axes permuted or mirrored, keeps
 * axis-aligned planes coincident after rounding, as each coordinate is rounded alone). */
static bool turns_space(const double m[12])
{
    for (int r = 0; r < 3; r++) {
        if ((m[4 * r] != 0) + (m[4 * r + 1] != 0) + (m[4 * r + 2] != 0) > 1)
            return true;
    }
    return false;
}

static double determinant(const double m[12])
{
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
           m[2] * (m[4] * m[9] - m[5] * m[8]);
}

/* The transform for the children of a transform module. */
static mcsg_status child_transform(scad_context *sc, const scad_call_args *ca,
                                   const scad_transform *parent, scad_transform *child,
                                   mcsg_error *err)
{
    double own[12];
    mcsg_status st;
    switch ((scad_module)ca->stmt->module) {
    case MOD_TRANSLATE: st = translate_matrix(sc, ca, own, err); break;
    case MOD_ROTATE: st = rotate_matrix(sc, ca, own, err); break;
    case MOD_SCALE: st = scale_matrix(sc, ca, own, err); break;
    case MOD_MIRROR: st = mirror_matrix(sc, ca, own, err); break;
    case MOD_MULTMATRIX: st = multmatrix_matrix(sc, ca, own, err); break;
    default: *child = *parent; return MCSG_OK;
    }
    if (st != MCSG_OK)
        return st;
    compose(parent->m, own, child->m);
    child->in_frame = parent->in_frame;
    child->opens_frame = turns_space(own);
    if (child->opens_frame) {
        static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
        compose(parent->rel, own, child->frame_rel);
        memcpy(child->rel, identity, sizeof identity);
        child->in_frame = true;
    } else {
        compose(parent->rel, own, child->rel);
    }
    child->degenerate = parent->degenerate || determinant(own) == 0 ||
                        determinant(child->m) == 0;
    if (child->degenerate && !parent->degenerate)
        scad_warn_at(sc->ev.ctx, sc->name, ca->stmt->line, ca->stmt->col, "%s() flattens its "
                     "children to zero volume: they are treated as empty (OpenSCAD makes them "
                     "degenerate)", ca->module);
    return MCSG_OK;
}

mcsg_status scad_instantiate(scad_context *sc, uint32_t stmt, const scad_transform *parent,
                             scad_transform *child, scad_role *role, mcsg_node_id *node,
                             scad_dim *dim, mcsg_error *err)
{
    const scad_stmt *s = &sc->prog->stmts[stmt];
    scad_call_args ca;
    mci_buf label = {0};
    mcsg_status st = scad_bind_arguments(sc, s, &ca, err);
    *node = MCSG_NO_NODE;
    *dim = (s->module >= MOD_CIRCLE && s->module <= MOD_TEXT) ? DIM_2D : DIM_3D;
    *role = (s->module <= MOD_INTERSECTION) ? ROLE_OP : ROLE_GROUP;
    if (st != MCSG_OK)
        return st;
    switch ((scad_module)s->module) {
    case MOD_CUBE: st = make_cube(sc, &ca, parent, &label, node, err); break;
    case MOD_SPHERE: st = make_sphere(sc, &ca, parent, &label, node, err); break;
    case MOD_CYLINDER: st = make_cylinder(sc, &ca, parent, &label, node, err); break;
    case MOD_POLYHEDRON: st = make_polyhedron(sc, &ca, parent, &label, node, err); break;
    case MOD_IMPORT:
        st = make_import(sc, &ca, parent, &label, node, err);
        *dim = import_is_2d(sc, &ca) ? DIM_2D : DIM_3D;
        break;
    case MOD_SURFACE: st = make_surface(sc, &ca, parent, &label, node, err); break;
    case MOD_CIRCLE:
    case MOD_SQUARE:
    case MOD_POLYGON:
    case MOD_TEXT: st = scad_make_shape2d(sc, &ca, parent, node, err); break;
    default: st = child_transform(sc, &ca, parent, child, err); break;
    }
    mci_buf_free(sc->ev.ctx, &label);
    return st;
}
