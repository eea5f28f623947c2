/*
 * Modules that use their children's evaluated geometry, following OpenSCAD 2021.01
 * (linear_extrude, rotate_extrude, hull, minkowski, offset, projection, resize): the
 * walk builds their children into a tree of their own, in their own coordinates; when
 * the children are done, geometry.c evaluates that tree exactly with the engine (2D
 * children are prisms, read back as a region from the faces at z = 0), makes the
 * module's result, and adds it as one leaf (or a 2D prism) to the enclosing tree. The
 * sweeps are in extrude.c, the hulls and offset pieces in src/shape. See
 * docs/csg-language.md for each module's rules.
 */
#include "base/sort.h"
#include "exact/kernel.h"
#include "exact/predicates.h"
#include "mesh/tree.h"
#include "base/degree_trig.h"
#include "scad/geometry.h"
#include "shape/hull.h"
#include "shape/offset.h"

#include <math.h>
#include <string.h>

enum { LE_FILE, LE_LAYER, LE_HEIGHT, LE_ORIGIN, LE_SCALE, LE_CENTER, LE_TWIST, LE_SLICES };
enum { RE_FILE, RE_LAYER, RE_ORIGIN, RE_SCALE, RE_CONVEXITY, RE_ANGLE };
enum { OFFSET_R, OFFSET_DELTA, OFFSET_CHAMFER };
enum { RESIZE_NEWSIZE, RESIZE_AUTO };

/* More point sums than this in one minkowski step is refused rather than allocated. */
#define MAX_SUM_POINTS 67108864.0
/* More convex sums than this to unite is refused: they overlap heavily. */
#define MAX_SUM_PIECES 4096

static mcsg_status finite_number(const scad_context *sc, const scad_call_args *ca, int slot,
                                 double *x, mcsg_error *err)
{
    mcsg_status st = scad_arg_number(sc, ca, slot, x, err);
    if (st == MCSG_OK && !isfinite(*x))
        st = scad_wrong_type(sc, ca, slot, "a finite number", err);
    return st;
}

/* The deprecated `file` parameter: a DXF drawing to extrude, in place of the children. */
static void warn_file(const scad_context *sc, const scad_call_args *ca, int slot)
{
    if (ca->slot[slot].value.type == VAL_STRING)
        scad_warn_at(sc->ev.ctx, sc->name, ca->slot[slot].line, ca->slot[slot].col,
                     "%s(): `file` is deprecated (OpenSCAD will remove it): extrude a child "
                     "import() instead", ca->module);
}

static mcsg_status linear_extrude_args(scad_context *sc, scad_geometry_op *op, mcsg_error *err)
{
    const scad_call_args *ca = &op->ca;
    const scad_value *scale = &ca->slot[LE_SCALE].value;
    double slices = 0;
    mcsg_status st = MCSG_OK;
    warn_file(sc, ca, LE_FILE);
    op->height = 100;
    op->scale[0] = op->scale[1] = 1;
    /* OpenSCAD: without `height`, a first positional number is the height. */
    if (st == MCSG_OK && !scad_given(ca, LE_HEIGHT) && !ca->slot[LE_FILE].named &&
        ca->slot[LE_FILE].value.type == VAL_NUMBER)
        st = finite_number(sc, ca, LE_FILE, &op->height, err);
    else if (st == MCSG_OK)
        st = finite_number(sc, ca, LE_HEIGHT, &op->height, err);
    if (st == MCSG_OK && scale->type == VAL_NUMBER) {
        op->scale[0] = op->scale[1] = scale->number;
    } else if (st == MCSG_OK && scad_given(ca, LE_SCALE)) {
        double v[3];
        if (scale->count != 2 || !scad_get_vec3(sc, scale, true, 0, v))
            st = scad_wrong_type(sc, ca, LE_SCALE, "a number or a vector of 2 numbers", err);
        op->scale[0] = v[0];
        op->scale[1] = v[1];
    }
    if (st == MCSG_OK && !(isfinite(op->scale[0]) && isfinite(op->scale[1])))
        st = scad_wrong_type(sc, ca, LE_SCALE, "finite", err);
    if (st == MCSG_OK)
        st = scad_arg_bool(sc, ca, LE_CENTER, &op->center, err);
    if (st == MCSG_OK)
        st = finite_number(sc, ca, LE_TWIST, &op->twist, err);
    if (st == MCSG_OK)
        st = finite_number(sc, ca, LE_SLICES, &slices, err);
    if (st != MCSG_OK)
        return st;
    op->height = op->height > 0 ? op->height : 0;
    op->scale[0] = fmax(op->scale[0], 0);
    op->scale[1] = fmax(op->scale[1], 0);
    op->slices = slices >= 1 && slices < 1e6 ? (int)slices : slices >= 1e6 ? -1 : 0;
    if (op->slices < 0)
        return scad_fail_at(sc->name, ca->slot[LE_SLICES].line, ca->slot[LE_SLICES].col, err,
                            MCSG_ERR_LIMIT, "linear_extrude(): more than a million slices");
    return MCSG_OK;
}

static mcsg_status rotate_extrude_args(scad_context *sc, scad_geometry_op *op, mcsg_error *err)
{
    mcsg_status st;
    warn_file(sc, &op->ca, RE_FILE);
    op->angle = 360;
    st = finite_number(sc, &op->ca, RE_ANGLE, &op->angle, err);
    if (op->angle <= -360 || op->angle > 360)
        op->angle = 360;
    return st;
}

/* The drawing a deprecated `file` names, read as OpenSCAD's extrusions read it: layer,
 * origin, and as scale the extrusion's x scale (linear_extrude) or its own `scale`
 * (rotate_extrude, 1 unless above 0). */
static mcsg_status file_view(scad_context *sc, const scad_geometry_op *op, int layer_slot,
                             int origin_slot, scad_dxf_view *view, mcsg_error *err)
{
    const scad_call_args *ca = &op->ca;
    const scad_value *l = &ca->slot[layer_slot].value, *o = &ca->slot[origin_slot].value;
    double v[3];
    view->res = op->res;
    if (scad_given(ca, origin_slot)) {
        if (o->type != VAL_VECTOR || o->count != 2 || !scad_get_vec3(sc, o, true, 0, v) ||
            !isfinite(v[0]) || !isfinite(v[1]))
            return scad_wrong_type(sc, ca, origin_slot, "a vector of 2 finite numbers", err);
        view->origin[0] = v[0];
        view->origin[1] = v[1];
    }
    if (scad_given(ca, layer_slot) && l->type != VAL_STRING)
        return scad_wrong_type(sc, ca, layer_slot, "a layer name (a string)", err);
    if (scad_given(ca, layer_slot) && l->count > 0 &&
        !memchr(scad_string(sc->prog, l), 0, l->count)) { /* "" and "\0..." name no layer */
        char *layer = mci_malloc(sc->ev.ctx, l->count + 1);
        if (!layer)
            return mci_fail_nomem(err, "reading a DXF file");
        memcpy(layer, scad_string(sc->prog, l), l->count);
        layer[l->count] = 0;
        view->layer = layer;
    }
    return MCSG_OK;
}

mcsg_status scad_geometry_file(scad_context *sc, scad_geometry_op *op, mcsg_node_id *node,
                               bool *given, mcsg_error *err)
{
    static const scad_transform identity = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
                                            {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
                                            {0}, false, false, false};
    const scad_call_args *ca = &op->ca;
    bool linear = ca->stmt->module == MOD_LINEAR_EXTRUDE;
    int file_slot = linear ? LE_FILE : RE_FILE;
    const scad_value *scale = &ca->slot[RE_SCALE].value;
    scad_dxf_view view = {NULL, {0, 0}, 1, {0, 0, 0}};
    const char *file;
    uint32_t file_len;
    mci_buf path = {0};
    mcsg_status st;
    *given = (linear || ca->stmt->module == MOD_ROTATE_EXTRUDE) &&
             ca->slot[file_slot].value.type == VAL_STRING;
    if (!*given)
        return MCSG_OK;
    view.scale = linear ? op->scale[0] : scale->type == VAL_NUMBER && scale->number > 0 ?
                 scale->number : 1;
    st = file_view(sc, op, linear ? LE_LAYER : RE_LAYER, linear ? LE_ORIGIN : RE_ORIGIN,
                   &view, err);
    if (st == MCSG_OK)
        st = scad_file_path(sc, ca, file_slot, &file, &file_len, &path, err);
    if (st == MCSG_OK)
        st = scad_add_dxf(sc, ca, &identity, file, file_len, (const char *)path.data, &view,
                          node, err);
    mci_buf_free(sc->ev.ctx, &path);
    mci_free(sc->ev.ctx, (void *)view.layer);
    return st;
}

/* offset(r | delta, chamfer): r wins and rounds; delta mitres, or chamfers; offset()
 * is offset(r = 1). */
static mcsg_status offset_args(scad_context *sc, scad_geometry_op *op, mcsg_error *err)
{
    const scad_call_args *ca = &op->ca;
    bool chamfer = false;
    mcsg_status st = scad_arg_bool(sc, ca, OFFSET_CHAMFER, &chamfer, err);
    op->delta = 1;
    op->join = SCAD_JOIN_ROUND;
    if (st == MCSG_OK && scad_given(ca, OFFSET_R)) {
        st = finite_number(sc, ca, OFFSET_R, &op->delta, err);
    } else if (st == MCSG_OK && scad_given(ca, OFFSET_DELTA)) {
        st = finite_number(sc, ca, OFFSET_DELTA, &op->delta, err);
        op->join = chamfer ? SCAD_JOIN_SQUARE : SCAD_JOIN_MITER;
    }
    return st;
}

/* resize(newsize, auto): sizes per axis (0 keeps), auto per axis or for all. */
static mcsg_status resize_args(scad_context *sc, scad_geometry_op *op, mcsg_error *err)
{
    const scad_call_args *ca = &op->ca;
    const scad_value *size = &ca->slot[RESIZE_NEWSIZE].value, *a = &ca->slot[RESIZE_AUTO].value;
    if (scad_given(ca, RESIZE_NEWSIZE) &&
        (size->type != VAL_VECTOR || size->count < 1 || size->count > 3))
        return scad_wrong_type(sc, ca, RESIZE_NEWSIZE, "a vector of 1 to 3 numbers", err);
    for (uint32_t k = 0; size->type == VAL_VECTOR && k < size->count; k++) {
        const scad_value *x = scad_element(sc, size, k);
        if (x->type != VAL_NUMBER || !isfinite(x->number))
            return scad_wrong_type(sc, ca, RESIZE_NEWSIZE, "a vector of finite numbers", err);
        op->newsize[k] = x->number;
    }
    if (a->type == VAL_BOOL)
        op->autosize[0] = op->autosize[1] = op->autosize[2] = a->number != 0;
    else if (a->type == VAL_VECTOR && a->count <= 3) {
        for (uint32_t k = 0; k < a->count; k++) {
            const scad_value *x = scad_element(sc, a, k);
            op->autosize[k] = x->type == VAL_BOOL ? x->number != 0
                              : x->type == VAL_NUMBER && x->number != 0;
        }
    } else if (scad_given(ca, RESIZE_AUTO)) {
        return scad_wrong_type(sc, ca, RESIZE_AUTO, "true, false or a vector of them", err);
    }
    return MCSG_OK;
}

mcsg_status scad_geometry_begin(scad_context *sc, uint32_t stmt, scad_geometry_op *op,
                                mcsg_error *err)
{
    const scad_stmt *s = &sc->prog->stmts[stmt];
    mcsg_status st;
    memset(op, 0, sizeof *op);
    op->stmt = stmt;
    st = scad_bind_arguments(sc, s, &op->ca, err);
    if (st == MCSG_OK)
        st = scad_get_resolution(sc, &op->ca, &op->res, err);
    if (st != MCSG_OK)
        return st;
    switch ((scad_module)s->module) {
    case MOD_LINEAR_EXTRUDE: return linear_extrude_args(sc, op, err);
    case MOD_ROTATE_EXTRUDE: return rotate_extrude_args(sc, op, err);
    case MOD_OFFSET: return offset_args(sc, op, err);
    case MOD_PROJECTION: return scad_arg_bool(sc, &op->ca, 0, &op->cut, err);
    case MOD_RESIZE: return resize_args(sc, op, err);
    default: return MCSG_OK;
    }
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Evaluating the children */

static mcsg_options part_options(const scad_context *sc)
{
    mcsg_options opts;
    if (sc->opts)
        opts = *sc->opts;
    else
        memset(&opts, 0, sizeof opts);
    opts.progress = NULL; /* the steps of a part would read as the whole's */
    return opts;
}

/* Evaluate `tree` from `node` (a lone leaf is taken as it is). */
static mcsg_status evaluate_node(scad_context *sc, mcsg_tree *tree, mcsg_node_id node,
                                 mcsg_mesh *out, mcsg_error *err)
{
    mcsg_options opts = part_options(sc);
    mcsg_eval_stats stats;
    mcsg_status st;
    memset(out, 0, sizeof *out);
    if (mcsg_tree_node_kind(tree, node) == MCSG_NODE_LEAF)
        return mcsg_mesh_copy(mcsg_tree_leaf_mesh(tree, node), sc->opts, out, err);
    st = mcsg_tree_set_root(tree, node, err);
    if (st == MCSG_OK)
        st = mcsg_eval(tree, &opts, out, NULL, &stats, err);
    if (st == MCSG_OK && mcsg_output_check_failed(&stats.output_check))
        mci_log(sc->ev.ctx, MCSG_LOG_WARNING, "%s: the result of its children breaks a "
                "guarantee once rounded (see mcsg_output_check)",
                mcsg_tree_node_label(tree, node));
    return st;
}

/* The union of the children, evaluated. */
static mcsg_status evaluate_union(scad_context *sc, const scad_geometry_op *op,
                                  const mcsg_node_id *children, size_t count, mcsg_mesh *out,
                                  mcsg_error *err)
{
    mcsg_node_id node = count == 1 ? children[0] : MCSG_NO_NODE;
    mcsg_status st = MCSG_OK;
    memset(out, 0, sizeof *out);
    if (count == 0)
        return MCSG_OK;
    if (count > 1)
        st = mcsg_tree_add_op(sc->tree, MCSG_NODE_UNION, children, count, op->ca.module,
                              &node, err);
    return st == MCSG_OK ? evaluate_node(sc, sc->tree, node, out, err) : st;
}

/* A region read back from evaluated prisms, with its outlines. */
typedef struct shape2d {
    mci_region r;
    mci_outlines o;
} shape2d;

static void shape2d_free(const mci_ctx *ctx, shape2d *s)
{
    mci_region_free(ctx, &s->r);
    mci_outlines_free(ctx, &s->o);
}

static mcsg_status read_shape(const mci_ctx *ctx, const mcsg_mesh *prisms, shape2d *s,
                              mcsg_error *err)
{
    mcsg_status st = mci_region_from_prisms(ctx, prisms, &s->r, err);
    memset(&s->o, 0, sizeof s->o);
    return st == MCSG_OK ? mci_region_outlines(ctx, &s->r, &s->o, err) : st;
}

/* Evaluate a tree of prisms: `base` (taken, may be empty) and one prism per piece of
 * `pieces` (a piece is loops group[k] .. group[k + 1] - 1, filled by the even-odd rule;
 * each loop alone when group is NULL), under `kind` (union, or base minus the pieces),
 * read back. */
static mcsg_status combine_groups(scad_context *sc, mcsg_mesh *base, const mci_outlines *pieces,
                                  const uint32_t *group, size_t groups, mcsg_node_kind kind,
                                  shape2d *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_tree *tree = NULL;
    mcsg_node_id *ids = mci_malloc_array(ctx, groups + 2, sizeof *ids), root;
    size_t count = 0;
    mcsg_mesh result = {0};
    mcsg_status st = ids ? mcsg_tree_create(sc->opts, &tree, err)
                         : mci_fail_nomem(err, "combining 2D shapes");
    memset(out, 0, sizeof *out);
    if (st == MCSG_OK && base->triangle_count)
        st = mcsg_tree_add_leaf_take(tree, base, NULL, "the children", &ids[count++], err);
    for (size_t k = 0; st == MCSG_OK && k < groups; k++) {
        uint32_t first = group ? group[k] : (uint32_t)k, end = group ? group[k + 1] : first + 1;
        mci_outlines one = {pieces->xy, NULL, pieces->point_count, pieces->loop_start + first,
                            end - first};
        mci_region r;
        mcsg_mesh prism = {0};
        st = mci_region_from_outlines(ctx, &one, &r, err);
        if (st == MCSG_OK && r.tri_count)
            st = mci_region_prism(ctx, &r, &prism, err);
        if (st == MCSG_OK && prism.triangle_count)
            st = mcsg_tree_add_leaf_take(tree, &prism, NULL, "a piece", &ids[count++], err);
        mci_region_free(ctx, &r);
    }
    if (st == MCSG_OK && count > 0)
        st = mcsg_tree_add_op(tree, kind, ids, count, "pieces", &root, err);
    if (st == MCSG_OK && count > 0)
        st = evaluate_node(sc, tree, root, &result, err);
    if (st == MCSG_OK)
        st = read_shape(ctx, &result, out, err);
    mci_mesh_free(ctx, base);
    mci_mesh_free(ctx, &result);
    mcsg_tree_free(tree);
    mci_free(ctx, ids);
    return st;
}

static mcsg_status combine_pieces(scad_context *sc, mcsg_mesh *base, const mci_outlines *pieces,
                                  mcsg_node_kind kind, shape2d *out, mcsg_error *err)
{
    return combine_groups(sc, base, pieces, NULL, pieces->loop_count, kind, out, err);
}

/* Where point p is against loop k: 1 inside, 0 outside, -1 on its boundary (exact
 * crossing count of a ray towards +x). */
static int inside_loop(const mci_outlines *o, size_t k, const double *p)
{
    const double *v = o->xy + 2 * (size_t)o->loop_start[k];
    size_t n = o->loop_start[k + 1] - o->loop_start[k];
    bool inside = false;
    for (size_t i = 0; i < n; i++) {
        const double *a = v + 2 * i, *b = v + 2 * ((i + 1) % n);
        int side = mci_orient2d(a[0], a[1], b[0], b[1], p[0], p[1]);
        if (side == 0 && p[0] >= fmin(a[0], b[0]) && p[0] <= fmax(a[0], b[0]) &&
            p[1] >= fmin(a[1], b[1]) && p[1] <= fmax(a[1], b[1]))
            return -1;
        if ((a[1] > p[1]) != (b[1] > p[1]) && (side > 0) == (b[1] > a[1]))
            inside = !inside;
    }
    return inside;
}

/* Whether loop h lies inside loop m: no vertex outside, one inside. */
static bool loop_inside(const mci_outlines *o, size_t h, size_t m)
{
    bool some = false;
    for (uint32_t i = o->loop_start[h]; i < o->loop_start[h + 1]; i++) {
        int where = inside_loop(o, m, o->xy + 2 * (size_t)i);
        if (where == 0)
            return false;
        some = some || where == 1;
    }
    return some;
}

mcsg_status scad_fill_nonzero(scad_context *sc, mci_outlines *o, mci_outlines *filled,
                              mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mci_outlines grouped = {0};
    uint32_t *group = NULL;
    size_t groups = 0, largest = 0, points = 0;
    shape2d s = {0};
    mcsg_mesh none = {0};
    mcsg_status st;
    for (size_t k = 0; k < o->loop_count; k++) {
        if (fabs(mci_outline_area2(o, k)) > fabs(mci_outline_area2(o, largest)))
            largest = k;
    }
    grouped.xy = mci_malloc_array(ctx, o->point_count * (o->loop_count + 1) + 1,
                                  2 * sizeof *grouped.xy);
    grouped.loop_start = mci_malloc_array(ctx, o->loop_count * o->loop_count + 2,
                                          sizeof *grouped.loop_start);
    group = mci_malloc_array(ctx, o->loop_count + 2, sizeof *group);
    if (!grouped.xy || !grouped.loop_start || !group) {
        st = mci_fail_nomem(err, "filling a 2D shape");
        goto done;
    }
    /* One piece per loop turning the way the largest does (material), with every loop
     * inside it (its holes, their islands...: properly nested, so that the even-odd fill
     * of the piece is its non-zero fill). */
    grouped.loop_start[0] = 0;
    for (size_t m = 0; m < o->loop_count; m++) {
        bool material = (mci_outline_area2(o, m) > 0) == (mci_outline_area2(o, largest) > 0);
        if (!material)
            continue;
        group[groups++] = (uint32_t)grouped.loop_count;
        for (size_t h = 0; h < o->loop_count; h++) {
            size_t n = o->loop_start[h + 1] - o->loop_start[h];
            if (h != m && !loop_inside(o, h, m))
                continue;
            memcpy(grouped.xy + 2 * points, o->xy + 2 * (size_t)o->loop_start[h],
                   2 * n * sizeof *o->xy);
            points += n;
            grouped.loop_start[++grouped.loop_count] = (uint32_t)points;
        }
    }
    group[groups] = (uint32_t)grouped.loop_count;
    grouped.point_count = points;
    st = combine_groups(sc, &none, &grouped, group, groups, MCSG_NODE_UNION, &s, err);
    if (st == MCSG_OK) {
        *filled = s.o;
        memset(&s.o, 0, sizeof s.o);
    }
done:
    mci_outlines_free(ctx, &grouped);
    mci_free(ctx, group);
    shape2d_free(ctx, &s);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Results into the enclosing tree */

static mcsg_status put_3d(scad_context *sc, scad_geometry_op *op, const scad_transform *t,
                          mcsg_mesh *mesh, mci_buf *label, mcsg_node_id *out, mcsg_error *err)
{
    mcsg_tree *own = sc->tree;
    mcsg_status st;
    sc->tree = op->outer;
    st = scad_add_leaf(sc, &op->ca, t, mesh, label, out, err);
    sc->tree = own;
    return st;
}

/* The outlines as a 2D leaf (transformed in place). */
static mcsg_status put_2d(scad_context *sc, scad_geometry_op *op, const scad_transform *t,
                          mci_outlines *o, mci_buf *label, mcsg_node_id *out, mcsg_error *err)
{
    mcsg_tree *own = sc->tree;
    mcsg_status st;
    sc->tree = op->outer;
    st = scad_add_shape(sc, &op->ca, t, o, label, out, err);
    sc->tree = own;
    return st;
}

static bool put_label(const mci_ctx *ctx, const scad_geometry_op *op, mci_buf *label)
{
    switch ((scad_module)op->ca.stmt->module) {
    case MOD_ROTATE_EXTRUDE:
        return scad_put_number(ctx, label, "rotate_extrude(angle=", op->angle) &&
               scad_put_resolution(ctx, label, &op->res) && mci_buf_printf(ctx, label, ")");
    case MOD_LINEAR_EXTRUDE:
        return scad_put_number(ctx, label, "linear_extrude(height=", op->height) &&
               mci_buf_printf(ctx, label, ", center=%s", op->center ? "true" : "false") &&
               scad_put_number(ctx, label, ", twist=", op->twist) &&
               scad_put_number(ctx, label, ", scale=[", op->scale[0]) &&
               scad_put_number(ctx, label, ", ", op->scale[1]) &&
               (op->slices > 0 ? scad_put_number(ctx, label, "], slices=", op->slices)
                               : mci_buf_printf(ctx, label, "]") &&
                                     scad_put_resolution(ctx, label, &op->res)) &&
               mci_buf_printf(ctx, label, ")");
    case MOD_OFFSET:
        return scad_put_number(ctx, label, op->join == SCAD_JOIN_ROUND ? "offset(r=" :
                               "offset(delta=", op->delta) &&
               (op->join == SCAD_JOIN_ROUND ||
                mci_buf_printf(ctx, label, ", chamfer=%s",
                               op->join == SCAD_JOIN_SQUARE ? "true" : "false")) &&
               scad_put_resolution(ctx, label, &op->res) && mci_buf_printf(ctx, label, ")");
    case MOD_PROJECTION:
        return mci_buf_printf(ctx, label, "projection(cut=%s)", op->cut ? "true" : "false");
    case MOD_RESIZE:
        return scad_put_number(ctx, label, "resize(newsize=[", op->newsize[0]) &&
               scad_put_number(ctx, label, ", ", op->newsize[1]) &&
               scad_put_number(ctx, label, ", ", op->newsize[2]) &&
               mci_buf_printf(ctx, label, "], auto=[%s, %s, %s])",
                              op->autosize[0] ? "true" : "false",
                              op->autosize[1] ? "true" : "false",
                              op->autosize[2] ? "true" : "false");
    default:
        return mci_buf_printf(ctx, label, "%s()", op->ca.module);
    }
}

/* ---------------------------------------------------------------------------------- */
/* The modules */

static mcsg_status finish_extrude(scad_context *sc, scad_geometry_op *op,
                                  const mcsg_node_id *children, size_t count, scad_dim dim,
                                  mcsg_mesh *result, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_mesh prisms;
    shape2d s = {0};
    mcsg_status st = MCSG_OK;
    memset(result, 0, sizeof *result);
    if (dim != DIM_2D)
        return MCSG_OK;
    st = evaluate_union(sc, op, children, count, &prisms, err);
    if (st == MCSG_OK)
        st = read_shape(ctx, &prisms, &s, err);
    if (st == MCSG_OK && s.r.tri_count > 0) {
        if (op->ca.stmt->module == MOD_LINEAR_EXTRUDE)
            st = op->height > 0 ? scad_linear_extrude(sc, op, &s.r, &s.o, result, err) : MCSG_OK;
        else
            st = op->angle != 0 ? scad_rotate_extrude(sc, op, &s.r, &s.o, result, err) : MCSG_OK;
    }
    mci_mesh_free(ctx, &prisms);
    shape2d_free(ctx, &s);
    return st;
}

/* Whether the subtrees hold only unions and leaves: their union's points are then the
 * leaves' points (exact, nothing evaluated). */
static bool only_unions(const mcsg_tree *tree, const mcsg_node_id *children, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        mcsg_node_kind kind = mcsg_tree_node_kind(tree, children[i]);
        if (kind == MCSG_NODE_LEAF)
            continue;
        if (kind != MCSG_NODE_UNION)
            return false;
        for (size_t k = 0; k < mcsg_tree_child_count(tree, children[i]); k++) {
            mcsg_node_id c = mcsg_tree_child(tree, children[i], k);
            if (!only_unions(tree, &c, 1))
                return false;
        }
    }
    return true;
}

/* Append a mesh's points to xyz. */
static bool append_points(const mci_ctx *ctx, const mcsg_mesh *m, double **xyz, size_t *n,
                          size_t *cap)
{
    if (!mci_grow_array(ctx, (void **)xyz, cap, 3 * (*n + m->vertex_count), sizeof **xyz, 96))
        return false;
    memcpy(*xyz + 3 * *n, m->vertices, 3 * m->vertex_count * sizeof **xyz);
    *n += m->vertex_count;
    return true;
}

static bool leaf_points(const mcsg_tree *tree, mcsg_node_id node, const mci_ctx *ctx,
                        double **xyz, size_t *n, size_t *cap)
{
    if (mcsg_tree_node_kind(tree, node) == MCSG_NODE_LEAF)
        return append_points(ctx, mcsg_tree_leaf_mesh(tree, node), xyz, n, cap);
    for (size_t k = 0; k < mcsg_tree_child_count(tree, node); k++) {
        if (!leaf_points(tree, mcsg_tree_child(tree, node, k), ctx, xyz, n, cap))
            return false;
    }
    return true;
}

/* The points of the children's union: the leaves' when only unions are above them,
 * else the evaluated union's. */
static mcsg_status union_points(scad_context *sc, const scad_geometry_op *op,
                                const mcsg_node_id *children, size_t count, double **xyz,
                                size_t *n, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    size_t cap = 0;
    mcsg_mesh m;
    mcsg_status st;
    *xyz = NULL;
    *n = 0;
    if (only_unions(sc->tree, children, count)) {
        for (size_t i = 0; i < count; i++) {
            if (!leaf_points(sc->tree, children[i], ctx, xyz, n, &cap))
                return mci_fail_nomem(err, "making a convex hull");
        }
        return MCSG_OK;
    }
    st = evaluate_union(sc, op, children, count, &m, err);
    if (st == MCSG_OK && !append_points(ctx, &m, xyz, n, &cap))
        st = mci_fail_nomem(err, "making a convex hull");
    mci_mesh_free(ctx, &m);
    return st;
}

static mcsg_status finish_hull(scad_context *sc, scad_geometry_op *op, const scad_transform *t,
                               const mcsg_node_id *children, size_t count, scad_dim dim,
                               mci_buf *label, mcsg_node_id *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    double *xyz = NULL;
    size_t n = 0;
    mcsg_mesh hull = {0};
    mci_outlines o = {0};
    mcsg_status st = union_points(sc, op, children, count, &xyz, &n, err);
    if (st == MCSG_OK && dim == DIM_3D) {
        st = mci_hull3d(ctx, xyz, n, &hull, err);
        if (st == MCSG_OK)
            st = put_3d(sc, op, t, &hull, label, out, err);
    } else if (st == MCSG_OK) {
        for (size_t i = 0; i < n; i++) /* prisms: keep x and y */
            memmove(xyz + 2 * i, xyz + 3 * i, 2 * sizeof *xyz);
        st = mci_hull2d(ctx, xyz, n, &o, err);
        if (st == MCSG_OK)
            st = put_2d(sc, op, t, &o, label, out, err);
    }
    mci_mesh_free(ctx, &hull);
    mci_outlines_free(ctx, &o);
    mci_free(ctx, xyz);
    return st;
}

/* Clipper's arc steps per full turn for OpenSCAD's offset(r): `fragments` is
 * get_fragments_from_r(|r|, $fn, $fs, $fa); OpenSCAD sets the arc tolerance to
 * |r| (1 - cos(180 / fragments)) and Clipper clamps it to a quarter of |r|. */
static double round_steps(int fragments)
{
    double ratio = fmin(1 - mci_cos_degrees(180.0 / fragments), 0.25);
    return 3.14159265358979323846 / acos(1 - ratio);
}

static mcsg_status finish_offset(scad_context *sc, scad_geometry_op *op, const scad_transform *t,
                                 const mcsg_node_id *children, size_t count, mci_buf *label,
                                 mcsg_node_id *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_mesh prisms;
    shape2d s = {0}, grown = {0};
    mci_outlines pieces = {0};
    int fragments = mcsg_fragments(fabs(op->delta), op->res.fn, op->res.fa, op->res.fs);
    mcsg_status st = evaluate_union(sc, op, children, count, &prisms, err);
    if (st == MCSG_OK)
        st = read_shape(ctx, &prisms, &s, err);
    if (st == MCSG_OK && op->delta != 0 && s.r.tri_count > 0) {
        st = mci_offset_pieces(ctx, &s.o, op->delta, (mci_join)op->join,
                               round_steps(fragments), &pieces, err);
        if (st == MCSG_OK)
            st = combine_pieces(sc, &prisms, &pieces, op->delta > 0 ? MCSG_NODE_UNION
                                : MCSG_NODE_DIFFERENCE, &grown, err);
        if (st == MCSG_OK) {
            shape2d_free(ctx, &s);
            s = grown;
            memset(&grown, 0, sizeof grown);
        }
    }
    if (st == MCSG_OK)
        st = put_2d(sc, op, t, &s.o, label, out, err);
    mci_mesh_free(ctx, &prisms);
    mci_outlines_free(ctx, &pieces);
    shape2d_free(ctx, &s);
    shape2d_free(ctx, &grown);
    return st;
}

static void mesh_bounds(const mcsg_mesh *m, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (size_t i = 0; i < m->vertex_count; i++) {
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->vertices[3 * i + k]);
            hi[k] = fmax(hi[k], m->vertices[3 * i + k]);
        }
    }
}

/* The shadow of a closed mesh is the union of its triangles facing up, projected. */
typedef struct shadow {
    scad_context *sc;
    const mcsg_mesh *mesh;
    uint32_t *up;        /* the triangles facing up */
    mci_outlines loops;  /* one loop per triangle of `up`, in that order */
    mcsg_tree *tree;     /* one prism per piece */
    mcsg_node_id *ids;
    size_t count;
} shadow;

/* Reorder up[0 .. n) breadth first over shared edges, so that a range of it is mostly
 * a connected patch: patches of a surface facing up seldom overlap themselves in
 * projection, and their triangles then make one piece. */
static mcsg_status order_patches(const mci_ctx *ctx, const mcsg_mesh *m, uint32_t *up, size_t n,
                                 mcsg_error *err)
{
    mci_keyed *sides = mci_malloc_array(ctx, 3 * n + 1, sizeof *sides);
    uint32_t *order = mci_malloc_array(ctx, n + 1, sizeof *order);
    uint8_t *seen = mci_calloc_array(ctx, n + 1, 1);
    size_t len = 0;
    if (!sides || !order || !seen) {
        mci_free(ctx, sides);
        mci_free(ctx, order);
        mci_free(ctx, seen);
        return mci_fail_nomem(err, "projecting a 3D object");
    }
    for (size_t i = 0; i < n; i++) {
        const uint32_t *c = m->triangles + 3 * (size_t)up[i];
        for (int k = 0; k < 3; k++)
            sides[3 * i + k] = (mci_keyed){mci_edge_key(c[k], c[(k + 1) % 3]), (uint32_t)i};
    }
    mci_sort_keyed(sides, 3 * n);
    for (size_t start = 0; start < n; start++) {
        if (seen[start])
            continue;
        seen[start] = 1;
        order[len++] = (uint32_t)start;
        for (size_t head = len - 1; head < len; head++) {
            const uint32_t *c = m->triangles + 3 * (size_t)up[order[head]];
            for (int k = 0; k < 3; k++) {
                uint64_t key = mci_edge_key(c[k], c[(k + 1) % 3]);
                for (size_t j = mci_find_key(sides, 3 * n, key);
                     j < 3 * n && sides[j].key == key; j++) {
                    if (!seen[sides[j].ref]) {
                        seen[sides[j].ref] = 1;
                        order[len++] = sides[j].ref;
                    }
                }
            }
        }
    }
    for (size_t i = 0; i < n; i++)
        order[i] = up[order[i]];
    memcpy(up, order, n * sizeof *up);
    mci_free(ctx, sides);
    mci_free(ctx, order);
    mci_free(ctx, seen);
    return MCSG_OK;
}

static mcsg_status shadow_loops(const mci_ctx *ctx, shadow *sh, mcsg_error *err)
{
    const mcsg_mesh *m = sh->mesh;
    mci_outlines *o = &sh->loops;
    size_t count = 0;
    mcsg_status st;
    sh->up = mci_malloc_array(ctx, m->triangle_count + 1, sizeof *sh->up);
    o->xy = mci_malloc_array(ctx, 3 * m->triangle_count + 1, 2 * sizeof *o->xy);
    o->loop_start = mci_malloc_array(ctx, m->triangle_count + 2, sizeof *o->loop_start);
    if (!sh->up || !o->xy || !o->loop_start)
        return mci_fail_nomem(err, "projecting a 3D object");
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *c = m->triangles + 3 * t;
        const double *a = m->vertices + 3 * (size_t)c[0], *b = m->vertices + 3 * (size_t)c[1];
        const double *d = m->vertices + 3 * (size_t)c[2];
        if (mci_orient2d(a[0], a[1], b[0], b[1], d[0], d[1]) > 0)
            sh->up[count++] = (uint32_t)t;
    }
    st = order_patches(ctx, m, sh->up, count, err);
    o->loop_start[0] = 0;
    for (size_t i = 0; st == MCSG_OK && i < count; i++) {
        const uint32_t *c = m->triangles + 3 * (size_t)sh->up[i];
        for (int k = 0; k < 3; k++)
            memcpy(o->xy + 6 * i + 2 * k, m->vertices + 3 * (size_t)c[k], 2 * sizeof *o->xy);
        o->loop_start[i + 1] = (uint32_t)(3 * (i + 1));
    }
    o->point_count = 3 * count;
    o->loop_count = count;
    return st;
}

/* The positive fill of triangles [first, end) of `up`: MCSG_ERR_UNSUPPORTED when their
 * outline crosses itself. */
static mcsg_status shadow_fill(shadow *sh, size_t first, size_t end, mci_region *r,
                               mcsg_error *err)
{
    mci_outlines part = {sh->loops.xy, NULL, sh->loops.point_count,
                         sh->loops.loop_start + first, end - first};
    mcsg_status st = mci_region_fill(sh->sc->ev.ctx, &part, MCI_FILL_POSITIVE, r, err);
    if (st == MCSG_ERR_UNSUPPORTED && err)
        memset(err, 0, sizeof *err); /* a shorter run will do */
    return st;
}

/* How many triangles from `first` on make one piece: the longest run whose outline does
 * not cross itself, found by doubling then halving (a lone triangle always does). */
static mcsg_status shadow_run(shadow *sh, size_t first, size_t *run, mcsg_error *err)
{
    size_t left = sh->loops.loop_count - first, good = 1, bad = left + 1;
    mcsg_status st = MCSG_OK;
    while (st == MCSG_OK && good < bad - 1) {
        size_t len = bad > left ? (2 * good < left ? 2 * good : left) : good + (bad - good) / 2;
        mci_region r;
        st = shadow_fill(sh, first, first + len, &r, err);
        mci_region_free(sh->sc->ev.ctx, &r);
        if (st == MCSG_OK)
            good = len;
        else if (st == MCSG_ERR_UNSUPPORTED)
            bad = len;
        st = st == MCSG_ERR_UNSUPPORTED ? MCSG_OK : st;
    }
    *run = good;
    return st;
}

/* The outline of run [first, first + run) of `up`, without ids. */
static mcsg_status run_outline(shadow *sh, size_t first, size_t run, mci_outlines *o,
                               mcsg_error *err)
{
    const mci_ctx *ctx = sh->sc->ev.ctx;
    mci_region r;
    mcsg_status st = shadow_fill(sh, first, first + run, &r, err);
    memset(o, 0, sizeof *o);
    if (st == MCSG_OK)
        st = mci_region_outlines(ctx, &r, o, err);
    mci_region_free(ctx, &r);
    if (st == MCSG_OK) {
        mci_free(ctx, o->ids);
        o->ids = NULL;
        mci_outlines_drop_straight(o);
    }
    return st;
}

/* Add outline o to the first group whose outline it does not cross, or start a group. */
static mcsg_status add_to_group(shadow *sh, mci_outlines *groups, size_t *count,
                                const mci_outlines *o, mcsg_error *err)
{
    const mci_ctx *ctx = sh->sc->ev.ctx;
    for (size_t g = 0; g <= *count; g++) {
        mci_outlines both = {0};
        mci_region r;
        mcsg_status st = MCSG_OK;
        if (!mci_outlines_append(ctx, &both, &groups[g]) || !mci_outlines_append(ctx, &both, o))
            st = mci_fail_nomem(err, "projecting a 3D object");
        if (st == MCSG_OK && g < *count) {
            st = mci_region_fill(ctx, &both, MCI_FILL_POSITIVE, &r, err);
            mci_region_free(ctx, &r);
        }
        if (st == MCSG_OK) {
            mci_outlines_free(ctx, &groups[g]);
            groups[g] = both;
            *count += g == *count;
            return MCSG_OK;
        }
        mci_outlines_free(ctx, &both);
        if (st != MCSG_ERR_UNSUPPORTED)
            return st;
        if (err)
            memset(err, 0, sizeof *err); /* another group may take it */
    }
    return MCSG_OK; /* not reached: a new group always takes it */
}

/* The shadow's pieces: runs of triangles of `up` whose outline does not cross itself,
 * gathered into groups whose outlines do not cross each other, a prism over each group
 * (the fewer, the faster the union). */
static mcsg_status shadow_pieces(shadow *sh, mcsg_error *err)
{
    const mci_ctx *ctx = sh->sc->ev.ctx;
    size_t groups = 0, n = sh->loops.loop_count;
    mci_outlines *group = mci_calloc_array(ctx, n + 1, sizeof *group);
    mcsg_status st = group ? MCSG_OK : mci_fail_nomem(err, "projecting a 3D object");
    for (size_t first = 0, run = 0; st == MCSG_OK && first < n; first += run) {
        mci_outlines o = {0};
        st = shadow_run(sh, first, &run, err);
        if (st == MCSG_OK)
            st = run_outline(sh, first, run, &o, err);
        if (st == MCSG_OK)
            st = add_to_group(sh, group, &groups, &o, err);
        mci_outlines_free(ctx, &o);
    }
    for (size_t g = 0; st == MCSG_OK && g < groups; g++) {
        mci_region r;
        mcsg_mesh prism = {0};
        st = mci_region_fill(ctx, &group[g], MCI_FILL_POSITIVE, &r, err);
        if (st == MCSG_OK && r.tri_count)
            st = mci_region_prism(ctx, &r, &prism, err);
        if (st == MCSG_OK && prism.triangle_count)
            st = mcsg_tree_add_leaf_take(sh->tree, &prism, NULL, "a piece",
                                         &sh->ids[sh->count++], err);
        mci_mesh_free(ctx, &prism);
        mci_region_free(ctx, &r);
    }
    for (size_t g = 0; group && g < groups; g++)
        mci_outlines_free(ctx, &group[g]);
    mci_free(ctx, group);
    return st;
}

/* The shadow of closed mesh m on z = 0. */
static mcsg_status shadow_shape(scad_context *sc, const mcsg_mesh *m, shape2d *out,
                                mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    shadow sh = {sc, m, NULL, {0}, NULL, NULL, 0};
    mcsg_mesh result = {0};
    mcsg_node_id root;
    mcsg_status st = shadow_loops(ctx, &sh, err);
    memset(out, 0, sizeof *out);
    if (st == MCSG_OK && !(sh.ids = mci_malloc_array(ctx, sh.loops.loop_count + 1,
                                                     sizeof *sh.ids)))
        st = mci_fail_nomem(err, "projecting a 3D object");
    if (st == MCSG_OK)
        st = mcsg_tree_create(sc->opts, &sh.tree, err);
    if (st == MCSG_OK && sh.loops.loop_count)
        st = shadow_pieces(&sh, err);
    if (st == MCSG_OK && sh.count)
        st = mcsg_tree_add_op(sh.tree, MCSG_NODE_UNION, sh.ids, sh.count, "pieces", &root,
                              err);
    if (st == MCSG_OK && sh.count)
        st = evaluate_node(sc, sh.tree, root, &result, err);
    if (st == MCSG_OK)
        st = read_shape(ctx, &result, out, err);
    if (st == MCSG_OK)
        mci_outlines_drop_straight(&out->o);
    mci_mesh_free(ctx, &result);
    mcsg_tree_free(sh.tree);
    mci_free(ctx, sh.ids);
    mci_free(ctx, sh.up);
    mci_outlines_free(ctx, &sh.loops);
    return st;
}

/* The section at z = 0: the mesh cut by a box from z = 0 up, read at z = 0. */
static mcsg_status section(scad_context *sc, mcsg_mesh *m, shape2d *out, mcsg_error *err)
{
    double lo[3], hi[3], size[3], move[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    mcsg_tree *tree = NULL;
    mcsg_mesh box = {0}, cut = {0};
    mcsg_node_id ids[2], root;
    mcsg_status st;
    memset(out, 0, sizeof *out);
    mesh_bounds(m, lo, hi);
    if (!(hi[2] >= 0 && lo[2] <= 0))
        return MCSG_OK;
    for (int k = 0; k < 3; k++)
        size[k] = k < 2 ? hi[k] - lo[k] + 2 : hi[2] + 1;
    move[3] = lo[0] - 1;
    move[7] = lo[1] - 1;
    st = mcsg_make_cube(size, 0, sc->opts, &box, err);
    if (st == MCSG_OK)
        st = mcsg_tree_create(sc->opts, &tree, err);
    if (st == MCSG_OK)
        st = mcsg_tree_add_leaf_take(tree, m, NULL, "the children", &ids[0], err);
    if (st == MCSG_OK)
        st = mcsg_tree_add_leaf_take(tree, &box, move, "z >= 0", &ids[1], err);
    if (st == MCSG_OK)
        st = mcsg_tree_add_op(tree, MCSG_NODE_INTERSECTION, ids, 2, "section", &root, err);
    if (st == MCSG_OK)
        st = evaluate_node(sc, tree, root, &cut, err);
    if (st == MCSG_OK)
        st = read_shape(sc->ev.ctx, &cut, out, err);
    mci_mesh_free(sc->ev.ctx, &box);
    mci_mesh_free(sc->ev.ctx, &cut);
    mcsg_tree_free(tree);
    return st;
}

static mcsg_status finish_projection(scad_context *sc, scad_geometry_op *op,
                                     const scad_transform *t, const mcsg_node_id *children,
                                     size_t count, mci_buf *label, mcsg_node_id *out,
                                     mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_mesh m;
    shape2d s = {0};
    mcsg_status st = evaluate_union(sc, op, children, count, &m, err);
    if (st == MCSG_OK)
        st = op->cut ? section(sc, &m, &s, err) : shadow_shape(sc, &m, &s, err);
    if (st == MCSG_OK)
        st = put_2d(sc, op, t, &s.o, label, out, err);
    mci_mesh_free(ctx, &m);
    shape2d_free(ctx, &s);
    return st;
}

/* OpenSCAD's resize factors (PolySet::resize and Polygon2d::resize): each axis given a
 * positive size is scaled to it; an axis marked auto takes the factor of the largest
 * size given; the others stay. */
static void resize_factors(const scad_geometry_op *op, const double lo[3], const double hi[3],
                           int axes, double f[3])
{
    int max = 0;
    double autoscale;
    for (int k = 0; k < axes; k++) {
        f[k] = op->newsize[k] > 0 ? op->newsize[k] / (hi[k] - lo[k]) : 1;
        if (axes == 3 ? op->newsize[k] > op->newsize[max]
                      : k == 1 && op->newsize[1] != 0 && op->newsize[1] > op->newsize[0])
            max = k;
    }
    autoscale = op->newsize[max] > 0 ? op->newsize[max] / (hi[max] - lo[max]) : 1;
    for (int k = 0; k < axes; k++)
        f[k] = !op->autosize[k] || op->newsize[k] > 0 ? f[k] : autoscale;
    if (axes == 2)
        f[2] = 1;
}

static mcsg_status finish_resize(scad_context *sc, scad_geometry_op *op, const scad_transform *t,
                                 const mcsg_node_id *children, size_t count, scad_dim dim,
                                 mci_buf *label, mcsg_node_id *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    double lo[3], hi[3], f[3];
    mcsg_mesh m;
    shape2d s = {0};
    mcsg_status st = evaluate_union(sc, op, children, count, &m, err);
    if (st != MCSG_OK)
        return st;
    mesh_bounds(&m, lo, hi);
    resize_factors(op, lo, hi, dim == DIM_3D ? 3 : 2, f);
    for (int k = 0; k < 3; k++) {
        if (!isfinite(f[k]) && m.vertex_count) {
            mci_mesh_free(ctx, &m);
            return scad_fail_at(sc->name, op->ca.stmt->line, op->ca.stmt->col, err,
                                MCSG_ERR_PARSE, "resize(): the children have no extent along "
                                "%c to resize", "xyz"[k]);
        }
    }
    mcsg_mesh_transform(&m, (double[12]){f[0], 0, 0, 0, 0, f[1], 0, 0, 0, 0, f[2], 0});
    if (dim == DIM_3D)
        return put_3d(sc, op, t, &m, label, out, err);
    st = read_shape(ctx, &m, &s, err);
    if (st == MCSG_OK)
        st = put_2d(sc, op, t, &s.o, label, out, err);
    mci_mesh_free(ctx, &m);
    shape2d_free(ctx, &s);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* minkowski: a sum with a convex operand is the union of the other moved by one of its
 * points and of the hulls of the other's faces (3D) or edges (2D) summed with it: for a
 * sum point x = a + b, the copy x - B of the convex operand either lies inside A, or
 * meets A's boundary at a face f, and then x is in f + B, which is convex. */

/* A closed mesh of one shell whose every edge is convex (the other triangle's far corner
 * on or behind the plane): convex, by local convexity. */
static mcsg_status mesh_is_convex(const mci_ctx *ctx, const mcsg_mesh *m, bool *convex,
                                  mcsg_error *err)
{
    size_t n = 3 * m->triangle_count, reached = 1, len = 0;
    mci_keyed *edges = mci_malloc_array(ctx, n + 1, sizeof *edges);
    uint32_t *queue = mci_malloc_array(ctx, m->triangle_count + 1, sizeof *queue);
    uint8_t *seen = mci_calloc_array(ctx, m->triangle_count + 1, 1);
    *convex = m->triangle_count >= 4;
    if (!edges || !queue || !seen) {
        mci_free(ctx, edges);
        mci_free(ctx, queue);
        mci_free(ctx, seen);
        return mci_fail_nomem(err, "summing shapes");
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t a = m->triangles[i], b = m->triangles[i - i % 3 + (i % 3 + 1) % 3];
        edges[i] = (mci_keyed){(uint64_t)a << 32 | b, (uint32_t)i};
    }
    mci_sort_keyed(edges, n);
    queue[len++] = 0;
    seen[0] = 1;
    for (size_t head = 0; *convex && head < len; head++) {
        const uint32_t *t = m->triangles + 3 * (size_t)queue[head];
        for (int k = 0; *convex && k < 3; k++) {
            uint64_t twin = (uint64_t)t[(k + 1) % 3] << 32 | t[k];
            size_t at = mci_find_key(edges, n, twin), u;
            if (at >= n || (at + 1 < n && edges[at + 1].key == twin)) {
                *convex = false; /* open, or more than two triangles on an edge */
                break;
            }
            u = edges[at].ref / 3;
            *convex = mci_orient3d_vertices(m->vertices + 3 * (size_t)t[0],
                                             m->vertices + 3 * (size_t)t[1],
                                             m->vertices + 3 * (size_t)t[2],
                                             m->vertices + 3 * (size_t)m->triangles[3 * u + (edges[at].ref % 3 + 2) % 3]) <= 0;
            if (!seen[u]) {
                seen[u] = 1;
                queue[len++] = (uint32_t)u;
                reached++;
            }
        }
    }
    *convex = *convex && reached == m->triangle_count;
    mci_free(ctx, edges);
    mci_free(ctx, queue);
    mci_free(ctx, seen);
    return MCSG_OK;
}

/* All sums of a point of `p` (np points, dim coordinates each) with a point of `q`. */
static double *point_sums(const mci_ctx *ctx, const double *p, size_t np, const double *q,
                          size_t nq, int dim)
{
    double *s = mci_malloc_array(ctx, np * nq + 1, (size_t)dim * sizeof *s);
    for (size_t i = 0; s && i < np; i++) {
        for (size_t j = 0; j < nq; j++) {
            for (int k = 0; k < dim; k++)
                s[(i * nq + j) * (size_t)dim + (size_t)k] = p[(size_t)dim * i + (size_t)k] +
                                                            q[(size_t)dim * j + (size_t)k];
        }
    }
    return s;
}

/* An operand's convex parts, as point sets: the whole mesh when it is convex, else the
 * tetrahedra from a point c to each face when every face has c strictly behind it (the
 * mesh is star-shaped around c: a sphere whose rings are not quite planar). */
typedef struct convex_parts {
    double *points;   /* 3 per point */
    size_t *start;    /* part k: points start[k] .. start[k + 1] - 1 */
    size_t count;
} convex_parts;

static void parts_free(const mci_ctx *ctx, convex_parts *p)
{
    mci_free(ctx, p->points);
    mci_free(ctx, p->start);
    memset(p, 0, sizeof *p);
}

static bool star_centre(const mcsg_mesh *m, double c[3])
{
    c[0] = c[1] = c[2] = 0;
    for (size_t i = 0; i < m->vertex_count; i++) {
        for (int k = 0; k < 3; k++)
            c[k] += m->vertices[3 * i + k] / (double)m->vertex_count;
    }
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *g = m->triangles + 3 * t;
        if (mci_orient3d_vertices(m->vertices + 3 * (size_t)g[0], m->vertices + 3 * (size_t)g[1],
                                  m->vertices + 3 * (size_t)g[2], c) >= 0)
            return false;
    }
    return m->triangle_count >= 4;
}

/* Whether every vertex of the mesh is on its hull's boundary. */
static mcsg_status convex_position(const mci_ctx *ctx, const mcsg_mesh *m, bool *yes,
                                   mcsg_error *err)
{
    mcsg_mesh hull = {0};
    uint32_t *canon = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *canon);
    size_t unique = 0;
    mcsg_status st = canon ? mci_hull3d(ctx, m->vertices, m->vertex_count, &hull, err)
                           : mci_fail_nomem(err, "summing shapes");
    if (st == MCSG_OK && !mci_first_equal_coordinates(ctx, m->vertices, m->vertex_count, canon))
        st = mci_fail_nomem(err, "summing shapes");
    for (size_t i = 0; st == MCSG_OK && i < m->vertex_count; i++)
        unique += canon[i] == i;
    *yes = st == MCSG_OK && hull.vertex_count == unique;
    mci_free(ctx, canon);
    mci_mesh_free(ctx, &hull);
    return st;
}

/* The parts, or none (count 0) when the mesh is neither convex nor star-shaped. A mesh
 * star-shaped around c with every vertex on its hull is taken as its hull: the mesh of a
 * sphere is convex in exact terms but for its rings, which rounding leaves a few units
 * in the last place off their planes (OpenSCAD likewise sums "approximately convex"
 * operands as convex); anything else keeps its exact shape. */
static mcsg_status convex_parts_of(const mci_ctx *ctx, const mcsg_mesh *m, convex_parts *p,
                                   mcsg_error *err)
{
    bool convex, star, hull_like = false;
    double c[3];
    mcsg_status st = mesh_is_convex(ctx, m, &convex, err);
    size_t parts;
    memset(p, 0, sizeof *p);
    star = st == MCSG_OK && !convex && star_centre(m, c);
    if (star)
        st = convex_position(ctx, m, &hull_like, err);
    convex = convex || hull_like;
    parts = convex ? 1 : m->triangle_count;
    if (st != MCSG_OK || (!convex && !star))
        return st;
    p->start = mci_malloc_array(ctx, parts + 1, sizeof *p->start);
    p->points = mci_malloc_array(ctx, convex ? m->vertex_count : 4 * parts, 3 * sizeof *p->points);
    if (!p->start || !p->points) {
        parts_free(ctx, p);
        return mci_fail_nomem(err, "summing shapes");
    }
    p->count = parts;
    for (size_t k = 0; k <= parts; k++)
        p->start[k] = convex ? k * m->vertex_count : 4 * k;
    if (convex)
        memcpy(p->points, m->vertices, 3 * m->vertex_count * sizeof *p->points);
    for (size_t t = 0; !convex && t < parts; t++) {
        memcpy(p->points + 12 * t, c, 3 * sizeof *c);
        for (int k = 0; k < 3; k++)
            memcpy(p->points + 12 * t + 3 * (size_t)(k + 1),
                   m->vertices + 3 * (size_t)m->triangles[3 * t + (size_t)k], 3 * sizeof(double));
    }
    return MCSG_OK;
}

/* Add the hull of P + Q (point sets) as a leaf. */
static mcsg_status add_sum_hull(const mci_ctx *ctx, mcsg_tree *tree, const double *p, size_t np,
                                const double *q, size_t nq, mcsg_node_id *ids, size_t *count,
                                mcsg_error *err)
{
    double *sums = point_sums(ctx, p, np, q, nq, 3);
    mcsg_mesh hull = {0};
    mcsg_status st = sums ? mci_hull3d(ctx, sums, np * nq, &hull, err)
                          : mci_fail_nomem(err, "summing shapes");
    if (st == MCSG_OK && hull.triangle_count)
        st = mcsg_tree_add_leaf_take(tree, &hull, NULL, "a sum of convex parts", &ids[(*count)++],
                                     err);
    mci_free(ctx, sums);
    mci_mesh_free(ctx, &hull);
    return st;
}

/* A + B with B's convex parts: when A has parts too, the union of the hulls of every
 * pair's sums; else A moved by a point of B and the hulls of each of A's faces summed
 * with each part of B. */
static mcsg_status sum_parts(scad_context *sc, mcsg_mesh *a, const convex_parts *pa,
                             const convex_parts *pb, mcsg_mesh *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    size_t first = pa->count ? pa->count : a->triangle_count, count = 0;
    mcsg_tree *tree = NULL;
    mcsg_node_id *ids = mci_malloc_array(ctx, first * pb->count + 2, sizeof *ids), root;
    double move[12] = {1, 0, 0, pb->points[0], 0, 1, 0, pb->points[1], 0, 0, 1, pb->points[2]};
    mcsg_status st = ids ? mcsg_tree_create(sc->opts, &tree, err)
                         : mci_fail_nomem(err, "summing shapes");
    for (size_t i = 0; st == MCSG_OK && i < first; i++) {
        double face[9];
        const double *p = pa->count ? pa->points + 3 * pa->start[i] : face;
        size_t np = pa->count ? pa->start[i + 1] - pa->start[i] : 3;
        for (int k = 0; !pa->count && k < 3; k++)
            memcpy(face + 3 * k, a->vertices + 3 * (size_t)a->triangles[3 * i + (size_t)k],
                   3 * sizeof(double));
        for (size_t j = 0; st == MCSG_OK && j < pb->count; j++)
            st = add_sum_hull(ctx, tree, p, np, pb->points + 3 * pb->start[j],
                              pb->start[j + 1] - pb->start[j], ids, &count, err);
    }
    if (st == MCSG_OK && !pa->count)
        st = mcsg_tree_add_leaf_take(tree, a, move, "moved", &ids[count++], err);
    if (st == MCSG_OK)
        st = mcsg_tree_add_op(tree, MCSG_NODE_UNION, ids, count, "minkowski", &root, err);
    if (st == MCSG_OK)
        st = evaluate_node(sc, tree, root, out, err);
    mcsg_tree_free(tree);
    mci_free(ctx, ids);
    return st;
}

static mcsg_status sum_3d(scad_context *sc, const scad_geometry_op *op, mcsg_mesh *a,
                          mcsg_mesh *b, mcsg_mesh *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    convex_parts pa = {0}, pb = {0};
    double pairs;
    mcsg_status st = convex_parts_of(ctx, a, &pa, err);
    if (st == MCSG_OK)
        st = convex_parts_of(ctx, b, &pb, err);
    if (st == MCSG_OK && !pb.count && pa.count)
        st = sum_3d(sc, op, b, a, out, err); /* the one with parts second */
    else if (st == MCSG_OK && !pb.count)
        st = scad_fail_at(sc->name, op->ca.stmt->line, op->ca.stmt->col, err,
                          MCSG_ERR_UNSUPPORTED, "minkowski(): neither operand is convex or "
                          "star-shaped (meshcsg sums an object only with one of those)");
    else if (st == MCSG_OK) {
        pairs = (double)(pa.count ? pa.count : a->triangle_count) * (double)pb.count;
        if (pairs * (double)(pb.start[1] - pb.start[0]) > MAX_SUM_POINTS ||
            pairs > MAX_SUM_PIECES)
            st = scad_fail_at(sc->name, op->ca.stmt->line, op->ca.stmt->col, err,
                              MCSG_ERR_LIMIT, "minkowski(): %.0f convex sums to unite, more "
                              "than %d (decompose the operands into convex parts)", pairs,
                              MAX_SUM_PIECES);
        else
            st = sum_parts(sc, a, &pa, &pb, out, err);
    }
    parts_free(ctx, &pa);
    parts_free(ctx, &pb);
    return st;
}

static bool region_is_convex(const shape2d *s)
{
    const double *p = s->o.xy;
    size_t n = s->o.point_count;
    if (s->o.loop_count != 1)
        return false;
    for (size_t i = 0; i < n; i++) {
        const double *a = p + 2 * i, *b = p + 2 * ((i + 1) % n), *c = p + 2 * ((i + 2) % n);
        if (mci_orient2d(a[0], a[1], b[0], b[1], c[0], c[1]) < 0)
            return false;
    }
    return true;
}

/* Append the outlines of `from` to `to` as more loops. */
static bool append_loops(const mci_ctx *ctx, mci_outlines *to, const mci_outlines *from,
                         size_t *point_cap, size_t *loop_cap)
{
    if (!mci_grow_array(ctx, (void **)&to->xy, point_cap, 2 * (to->point_count + from->point_count),
                        sizeof *to->xy, 256) ||
        !mci_grow_array(ctx, (void **)&to->loop_start, loop_cap,
                        to->loop_count + from->loop_count + 1, sizeof *to->loop_start, 64))
        return false;
    if (to->loop_count == 0)
        to->loop_start[0] = 0;
    memcpy(to->xy + 2 * to->point_count, from->xy, 2 * from->point_count * sizeof *to->xy);
    for (size_t k = 1; k <= from->loop_count; k++)
        to->loop_start[to->loop_count + k] = (uint32_t)(to->point_count + from->loop_start[k]);
    to->point_count += from->point_count;
    to->loop_count += from->loop_count;
    return true;
}

/* The hulls of each edge of r summed with the convex s, as loops. */
static mcsg_status edge_sums(const mci_ctx *ctx, const shape2d *r, const shape2d *s,
                             mci_outlines *pieces, mcsg_error *err)
{
    size_t point_cap = 0, loop_cap = 0;
    mcsg_status st = MCSG_OK;
    memset(pieces, 0, sizeof *pieces);
    for (size_t e = 0; st == MCSG_OK && e < r->r.edge_count; e++) {
        double ends[4], *sums;
        mci_outlines hull = {0};
        memcpy(ends, r->r.xy + 2 * (size_t)r->r.edges[2 * e], 2 * sizeof(double));
        memcpy(ends + 2, r->r.xy + 2 * (size_t)r->r.edges[2 * e + 1], 2 * sizeof(double));
        sums = point_sums(ctx, ends, 2, s->o.xy, s->o.point_count, 2);
        st = sums ? mci_hull2d(ctx, sums, 2 * s->o.point_count, &hull, err)
                  : mci_fail_nomem(err, "summing shapes");
        if (st == MCSG_OK && !append_loops(ctx, pieces, &hull, &point_cap, &loop_cap))
            st = mci_fail_nomem(err, "summing shapes");
        mci_free(ctx, sums);
        mci_outlines_free(ctx, &hull);
    }
    return st;
}

static mcsg_status sum_2d(scad_context *sc, const scad_geometry_op *op, shape2d *a, shape2d *b,
                          shape2d *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    bool convex_a = region_is_convex(a), convex_b = region_is_convex(b);
    shape2d *r = convex_b ? a : b, *s = convex_b ? b : a;
    mci_outlines pieces = {0};
    mcsg_mesh base = {0};
    mcsg_status st = MCSG_OK;
    memset(out, 0, sizeof *out);
    if (convex_a && convex_b) {
        double *sums = point_sums(ctx, a->o.xy, a->o.point_count, b->o.xy, b->o.point_count, 2);
        st = sums ? mci_hull2d(ctx, sums, a->o.point_count * b->o.point_count, &pieces, err)
                  : mci_fail_nomem(err, "summing shapes");
        mci_free(ctx, sums);
        if (st == MCSG_OK)
            st = combine_pieces(sc, &base, &pieces, MCSG_NODE_UNION, out, err);
        mci_outlines_free(ctx, &pieces);
        return st;
    }
    if (!convex_a && !convex_b)
        return scad_fail_at(sc->name, op->ca.stmt->line, op->ca.stmt->col, err,
                            MCSG_ERR_UNSUPPORTED, "minkowski(): two 2D operands that are both "
                            "not convex (meshcsg sums any shape with convex ones only)");
    st = edge_sums(ctx, r, s, &pieces, err);
    if (st == MCSG_OK)
        st = mci_region_prism(ctx, &r->r, &base, err);
    if (st == MCSG_OK)
        mcsg_mesh_transform(&base, (double[12]){1, 0, 0, s->o.xy[0], 0, 1, 0, s->o.xy[1], 0, 0,
                                                1, 0});
    if (st == MCSG_OK)
        st = combine_pieces(sc, &base, &pieces, MCSG_NODE_UNION, out, err);
    mci_mesh_free(ctx, &base);
    mci_outlines_free(ctx, &pieces);
    return st;
}

static mcsg_status finish_minkowski(scad_context *sc, scad_geometry_op *op,
                                    const scad_transform *t, const mcsg_node_id *children,
                                    size_t count, scad_dim dim, mci_buf *label,
                                    mcsg_node_id *out, mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    mcsg_mesh acc = {0}, next = {0}, sum = {0};
    shape2d acc2 = {0}, next2 = {0}, sum2 = {0};
    bool have = false;
    mcsg_status st = MCSG_OK;
    for (size_t i = 0; st == MCSG_OK && i < count; i++) {
        st = evaluate_node(sc, sc->tree, children[i], &next, err);
        if (st == MCSG_OK && dim == DIM_2D)
            st = read_shape(ctx, &next, &next2, err);
        if (st != MCSG_OK || next.triangle_count == 0) {
            /* an empty child adds nothing (OpenSCAD drops it) */
        } else if (!have) {
            acc = next, acc2 = next2, have = true;
            memset(&next, 0, sizeof next);
            memset(&next2, 0, sizeof next2);
        } else if (dim == DIM_3D) {
            st = sum_3d(sc, op, &acc, &next, &sum, err);
            mci_mesh_free(ctx, &acc);
            acc = sum;
            memset(&sum, 0, sizeof sum);
        } else {
            st = sum_2d(sc, op, &acc2, &next2, &sum2, err);
            shape2d_free(ctx, &acc2);
            acc2 = sum2;
            memset(&sum2, 0, sizeof sum2);
        }
        mci_mesh_free(ctx, &next);
        shape2d_free(ctx, &next2);
    }
    if (st == MCSG_OK && dim == DIM_3D)
        st = put_3d(sc, op, t, &acc, label, out, err);
    else if (st == MCSG_OK)
        st = put_2d(sc, op, t, &acc2.o, label, out, err);
    mci_mesh_free(ctx, &acc);
    shape2d_free(ctx, &acc2);
    return st;
}

mcsg_status scad_geometry_finish(scad_context *sc, scad_geometry_op *op,
                                 const mcsg_node_id *children, size_t count, scad_dim dim,
                                 const scad_transform *t, mcsg_node_id *out, scad_dim *out_dim,
                                 mcsg_error *err)
{
    const mci_ctx *ctx = sc->ev.ctx;
    scad_module module = (scad_module)op->ca.stmt->module;
    bool wants_2d = module == MOD_LINEAR_EXTRUDE || module == MOD_ROTATE_EXTRUDE ||
                    module == MOD_OFFSET;
    mci_buf label = {0};
    mcsg_mesh mesh = {0};
    mcsg_status st = MCSG_OK;
    *out_dim = module == MOD_OFFSET || module == MOD_PROJECTION ? DIM_2D
               : wants_2d ? DIM_3D : dim;
    if ((wants_2d && dim == DIM_3D) || (module == MOD_PROJECTION && dim == DIM_2D)) {
        scad_warn_at(ctx, sc->name, op->ca.stmt->line, op->ca.stmt->col, "%s(): ignoring %s "
                     "children (it takes %s ones)", op->ca.module, dim == DIM_3D ? "3D" : "2D",
                     dim == DIM_3D ? "2D" : "3D");
        count = 0;
        dim = DIM_NONE;
    }
    if (!put_label(ctx, op, &label))
        return mci_fail_nomem(err, "reading CSG text");
    if (*out_dim == DIM_NONE) /* no children: the empty set of no dimension */
        st = mcsg_tree_add_op(op->outer, MCSG_NODE_UNION, NULL, 0, (const char *)label.data,
                              out, err);
    else if (module == MOD_LINEAR_EXTRUDE || module == MOD_ROTATE_EXTRUDE) {
        st = finish_extrude(sc, op, children, count, dim, &mesh, err);
        if (st == MCSG_OK)
            st = put_3d(sc, op, t, &mesh, &label, out, err);
    } else if (module == MOD_HULL)
        st = finish_hull(sc, op, t, children, count, dim, &label, out, err);
    else if (module == MOD_OFFSET)
        st = finish_offset(sc, op, t, children, dim == DIM_2D ? count : 0, &label, out, err);
    else if (module == MOD_PROJECTION)
        st = finish_projection(sc, op, t, children, count, &label, out, err);
    else if (module == MOD_RESIZE)
        st = finish_resize(sc, op, t, children, count, dim, &label, out, err);
    else
        st = finish_minkowski(sc, op, t, children, count, dim, &label, out, err);
    mci_mesh_free(ctx, &mesh);
    mci_buf_free(ctx, &label);
    return st;
}
