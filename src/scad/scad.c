/*
 * The CSG-language reader's entry points and its walk over the parsed statements.
 * The walk is an explicit-stack depth-first traversal (files may nest 100,000 levels),
 * creating each tree node after its children, as mcsg_tree requires. It follows
 * OpenSCAD's evaluation rules:
 *  - a scope's assignments ($fn = 8;) are all evaluated before its calls, in source
 *    order; assigning one variable twice in a scope keeps the first position with the
 *    last value (with a warning), as OpenSCAD does;
 *  - special variables are dynamically scoped: a call's $-arguments and its scope's
 *    assignments hold for the call and everything inside it;
 *  - transforms multiply down the tree and are applied to each leaf's mesh;
 *  - `*` (disable) drops a call without evaluating it; `%` (background) is likewise left
 *    out of the result (OpenSCAD only previews it); `#` (highlight) changes nothing;
 *  - union/difference/intersection always make an operation node; group, render, color,
 *    the transforms and the file itself unite their children implicitly: no node for a
 *    single child, a union node for several, the empty set (a childless union) for none.
 */
#include "mesh/tree.h"
#include "scad/scad.h"

#include <string.h>

typedef struct walk_frame {
    uint32_t stmt;      /* the call (or the root) whose scope is being walked */
    uint32_t next;      /* next statement of that scope, or SCAD_NONE */
    uint32_t results;   /* height of the result stack when the scope was entered */
    uint32_t bindings;  /* binding-stack height before the call's arguments */
    uint32_t heap;      /* value-heap height before the call's arguments */
    uint32_t transform; /* index of the children's transform */
    uint32_t geom;      /* a module using its children's geometry: its index in
                           walker.geoms (its children are built in a tree of their own);
                           else SCAD_NONE */
    bool own_transform; /* that transform was pushed for this frame */
    uint8_t role;       /* scad_role */
} walk_frame;

typedef struct walker {
    scad_context *sc;
    walk_frame *frames;
    uint32_t frame_len, frame_cap;
    scad_transform *transforms;
    uint32_t transform_len, transform_cap;
    mcsg_node_id *results;
    uint8_t *dims;           /* each result's scad_dim */
    uint32_t result_len, result_cap, dim_cap;
    scad_geometry_op *geoms; /* open geometry modules, outermost first */
    uint32_t geom_len, geom_cap;
    uint32_t *seen_in_scope; /* var -> serial of the last scope that assigned it */
    uint32_t *last_assign;   /* var -> that scope's last assignment to it */
    uint32_t scope_serial;
    mcsg_node_id *pending; /* nodes still to visit when counting a frame's leaves */
    uint32_t pending_cap;
} walker;

/* Make room for one more element; false on allocation failure. */
static bool room(const mci_ctx *ctx, void **data, uint32_t *cap, uint32_t len, size_t elem)
{
    void *grown;
    uint32_t new_cap;
    if (len < *cap)
        return true;
    if (*cap >= UINT32_MAX / 2)
        return false;
    new_cap = *cap ? *cap * 2 : 64;
    grown = mci_realloc_array(ctx, *data, new_cap, elem);
    if (!grown)
        return false;
    *data = grown;
    *cap = new_cap;
    return true;
}

static mcsg_status push_result(walker *w, mcsg_node_id id, scad_dim dim, mcsg_error *err)
{
    void *data = w->results, *dims = w->dims;
    bool ok = room(w->sc->ev.ctx, &data, &w->result_cap, w->result_len, sizeof *w->results);
    w->results = data;
    ok = ok && room(w->sc->ev.ctx, &dims, &w->dim_cap, w->result_len, sizeof *w->dims);
    w->dims = dims;
    if (!ok)
        return mci_fail_nomem(err, "reading CSG text");
    w->dims[w->result_len] = (uint8_t)dim;
    w->results[w->result_len++] = id;
    return MCSG_OK;
}

/* Evaluate the assignments of the scope of `stmt` (hoisted, OpenSCAD-style). */
static mcsg_status enter_scope(walker *w, uint32_t stmt, mcsg_error *err)
{
    const scad_program *prog = w->sc->prog;
    uint32_t serial = ++w->scope_serial;
    mcsg_status st = MCSG_OK;
    for (uint32_t c = prog->stmts[stmt].first_child; c != SCAD_NONE; c = prog->stmts[c].next) {
        if (prog->stmts[c].kind == ST_ASSIGN)
            w->last_assign[prog->stmts[c].var] = c;
    }
    for (uint32_t c = prog->stmts[stmt].first_child; c != SCAD_NONE && st == MCSG_OK;
         c = prog->stmts[c].next) {
        const scad_stmt *s = &prog->stmts[c], *last;
        scad_value value;
        if (s->kind != ST_ASSIGN || w->seen_in_scope[s->var] == serial)
            continue;
        w->seen_in_scope[s->var] = serial;
        last = &prog->stmts[w->last_assign[s->var]];
        if (last != s)
            scad_warn_at(w->sc->ev.ctx, w->sc->name, last->line, last->col, "%.*s was "
                         "assigned on line %u but is overwritten here (the last value counts, "
                         "from the first position)", (int)prog->vars[s->var].len,
                         prog->vars[s->var].text, s->line);
        st = scad_eval_expr(&w->sc->ev, last->expr_begin, last->expr_end, &value, err);
        if (st == MCSG_OK)
            st = scad_bind(&w->sc->ev, s->var, &value, true, err);
    }
    return st;
}

static mcsg_status push_frame(walker *w, uint32_t stmt, uint32_t bindings, uint32_t heap,
                              uint32_t transform, bool own_transform, scad_role role,
                              mcsg_error *err)
{
    void *data = w->frames;
    walk_frame *f;
    if (!room(w->sc->ev.ctx, &data, &w->frame_cap, w->frame_len, sizeof *f))
        return mci_fail_nomem(err, "reading CSG text");
    w->frames = data;
    f = &w->frames[w->frame_len++];
    f->stmt = stmt;
    f->next = w->sc->prog->stmts[stmt].first_child;
    f->results = w->result_len;
    f->bindings = bindings;
    f->heap = heap;
    f->transform = transform;
    f->own_transform = own_transform;
    f->geom = SCAD_NONE;
    f->role = (uint8_t)role;
    return enter_scope(w, stmt, err);
}

static bool is_transform(scad_module m) { return m >= MOD_TRANSLATE && m <= MOD_MULTMATRIX; }

static mcsg_status push_transform(walker *w, const scad_transform *t, mcsg_error *err)
{
    void *data = w->transforms;
    if (!room(w->sc->ev.ctx, &data, &w->transform_cap, w->transform_len, sizeof *t))
        return mci_fail_nomem(err, "reading CSG text");
    w->transforms = data;
    w->transforms[w->transform_len++] = *t;
    return MCSG_OK;
}

/* A module that uses its children's geometry: its arguments are read, and its children
 * go into a tree of their own, in their own coordinates. */
static mcsg_status enter_geometry(walker *w, uint32_t stmt, uint32_t bindings, uint32_t heap,
                                  mcsg_error *err)
{
    static const scad_transform identity = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
                                            {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
                                            {0}, false, false, false};
    scad_context *sc = w->sc;
    void *data = w->geoms;
    scad_geometry_op *op;
    mcsg_tree *tree;
    mcsg_node_id file_node;
    bool file_given = false;
    mcsg_status st;
    if (!room(sc->ev.ctx, &data, &w->geom_cap, w->geom_len, sizeof *w->geoms))
        return mci_fail_nomem(err, "reading CSG text");
    w->geoms = data;
    op = &w->geoms[w->geom_len];
    st = scad_geometry_begin(sc, stmt, op, err);
    if (st == MCSG_OK)
        st = mcsg_tree_create(sc->opts, &tree, err);
    if (st != MCSG_OK)
        return st;
    op->outer = sc->tree;
    sc->tree = tree;
    w->geom_len++;
    st = push_transform(w, &identity, err);
    if (st == MCSG_OK)
        st = push_frame(w, stmt, bindings, heap, w->transform_len - 1, true, ROLE_GROUP, err);
    if (st == MCSG_OK)
        w->frames[w->frame_len - 1].geom = w->geom_len - 1;
    if (st == MCSG_OK)
        st = scad_geometry_file(sc, op, &file_node, &file_given, err);
    if (st == MCSG_OK && file_given)
        st = push_result(w, file_node, DIM_2D, err);
    return st;
}

/* Evaluate one call: a leaf goes onto the result stack, anything else opens a frame. */
static mcsg_status visit_call(walker *w, uint32_t stmt, uint32_t parent_transform,
                              mcsg_error *err)
{
    scad_context *sc = w->sc;
    const scad_stmt *s = &sc->prog->stmts[stmt];
    uint32_t bindings = sc->ev.binding_len, heap = sc->ev.heap_len;
    scad_transform child;
    scad_role role;
    scad_dim dim;
    mcsg_node_id node;
    mcsg_status st;
    if (s->modifiers & (MODIFIER_DISABLE | MODIFIER_BACKGROUND)) {
        mci_log(sc->ev.ctx, MCSG_LOG_INFO, "%s:%u:%u: %s %s() is left out of the result",
                sc->name, s->line, s->col, (s->modifiers & MODIFIER_DISABLE) ? "disabled (*)"
                : "background (%)", scad_module_name((scad_module)s->module));
        return MCSG_OK;
    }
    if (scad_is_geometry_module((scad_module)s->module))
        return enter_geometry(w, stmt, bindings, heap, err);
    st = scad_instantiate(sc, stmt, &w->transforms[parent_transform], &child, &role, &node,
                          &dim, err);
    if (st == MCSG_OK && node != MCSG_NO_NODE) {
        if (s->first_child != SCAD_NONE)
            scad_warn_at(sc->ev.ctx, sc->name, s->line, s->col, "%s() takes no children: "
                         "ignoring them", scad_module_name((scad_module)s->module));
        scad_unbind_to(&sc->ev, bindings);
        sc->ev.heap_len = heap;
        return push_result(w, node, dim, err);
    }
    if (st == MCSG_OK && is_transform((scad_module)s->module)) {
        st = push_transform(w, &child, err);
        if (st == MCSG_OK)
            st = push_frame(w, stmt, bindings, heap, w->transform_len - 1, true, role, err);
    } else if (st == MCSG_OK) {
        st = push_frame(w, stmt, bindings, heap, parent_transform, false, role, err);
    }
    return st;
}

static mcsg_status frame_label(const walker *w, const walk_frame *f, mci_buf *label)
{
    const scad_context *sc = w->sc;
    const scad_stmt *s = &sc->prog->stmts[f->stmt];
    bool ok = s->kind == ST_ROOT
                  ? mci_buf_printf(sc->ev.ctx, label, "top level of %s", sc->name)
                  : mci_buf_printf(sc->ev.ctx, label, "%s() at %s:%u:%u",
                                   scad_module_name((scad_module)s->module), sc->name,
                                   s->line, s->col);
    return ok ? MCSG_OK : MCSG_ERR_NOMEM;
}

/* Up to two leaves of the subtree at `node` (a frame counts as two): *leaves and the
 * first one found. */
static mcsg_status first_leaves(walker *w, mcsg_node_id node, size_t *leaves,
                                mcsg_node_id *leaf, mcsg_error *err)
{
    const mcsg_tree *tree = w->sc->tree;
    uint32_t len = 0;
    *leaves = 0;
    *leaf = MCSG_NO_NODE;
    w->pending[len++] = node; /* room for one: made by the caller */
    while (len > 0 && *leaves < 2) {
        mcsg_node_id n = w->pending[--len];
        size_t children = mcsg_tree_child_count(tree, n);
        if (mcsg_tree_node_kind(tree, n) == MCSG_NODE_LEAF) {
            *leaves += 1;
            *leaf = *leaf == MCSG_NO_NODE ? n : *leaf;
            continue;
        }
        if (mci_tree_frame(tree, n) && n != node) {
            *leaves += 2;
            continue;
        }
        for (size_t i = 0; i < children; i++) {
            void *data = w->pending;
            if (!room(w->sc->ev.ctx, &data, &w->pending_cap, len, sizeof *w->pending))
                return mci_fail_nomem(err, "reading CSG text");
            w->pending = data;
            w->pending[len++] = mcsg_tree_child(tree, n, i);
        }
    }
    return MCSG_OK;
}

/* A transform that turns space is done with its children (mesh/tree.h): two or more
 * leaves under it make its node a frame; a lone leaf is simply transformed, its local
 * mesh moved into the enclosing frame (if any). */
static mcsg_status close_frame(walker *w, const scad_transform *t,
                               const scad_transform *parent, mcsg_node_id node,
                               mcsg_error *err)
{
    void *data = w->pending;
    size_t leaves;
    mcsg_node_id leaf;
    mcsg_status st;
    if (!room(w->sc->ev.ctx, &data, &w->pending_cap, 0, sizeof *w->pending))
        return mci_fail_nomem(err, "reading CSG text");
    w->pending = data;
    st = first_leaves(w, node, &leaves, &leaf, err);
    if (st != MCSG_OK || leaves == 0)
        return st;
    if (leaves >= 2)
        return mci_tree_set_frame(w->sc->tree, node, t->frame_rel, err);
    mci_tree_close_frame(w->sc->tree, leaf, parent->in_frame ? t->frame_rel : NULL);
    return MCSG_OK;
}

/* OpenSCAD's rule for a scope's results: the first of some dimension sets it, those of
 * the other are left out with a warning. Returns the dimension; *count is updated. */
static scad_dim keep_one_dimension(walker *w, const walk_frame *f, uint32_t *count)
{
    const scad_stmt *s = &w->sc->prog->stmts[f->stmt];
    bool intersection = f->role == ROLE_OP && s->module == MOD_INTERSECTION;
    scad_dim dim = DIM_NONE;
    uint32_t kept = 0;
    bool warned = false;
    for (uint32_t i = 0; i < *count; i++) {
        scad_dim d = (scad_dim)w->dims[f->results + i];
        if (dim == DIM_NONE)
            dim = d;
        if (d != DIM_NONE && d != dim) {
            if (!warned)
                scad_warn_at(w->sc->ev.ctx, w->sc->name, s->line, s->col, "mixing 2D and 3D "
                             "objects is not supported: the %s ones are empty%s",
                             d == DIM_2D ? "2D" : "3D", intersection ? ", and so is the "
                             "intersection" : "");
            warned = true;
            continue;
        }
        w->results[f->results + kept] = w->results[f->results + i];
        w->dims[f->results + kept++] = (uint8_t)d;
    }
    /* OpenSCAD replaces them by the empty set where they stand: the other operations
     * lose nothing when they are left out, an intersection everything. */
    *count = intersection && warned ? 0 : kept;
    return dim;
}

/* A geometry module's children are done (in its own tree): its result goes into the
 * enclosing tree in place of them. */
static mcsg_status exit_geometry(walker *w, const walk_frame *f, uint32_t count,
                                 mcsg_node_id *node, scad_dim *dim, mcsg_error *err)
{
    scad_context *sc = w->sc;
    scad_geometry_op *op = &w->geoms[f->geom];
    mcsg_tree *own = sc->tree;
    mcsg_status st = scad_geometry_finish(sc, op, w->results + f->results, count, *dim,
                                          &w->transforms[w->frames[w->frame_len - 1].transform],
                                          node, dim, err);
    sc->tree = op->outer;
    mcsg_tree_free(own);
    w->geom_len--;
    return st;
}

/* A scope is done: combine its results into one node for the enclosing scope. */
static mcsg_status exit_frame(walker *w, mcsg_error *err)
{
    static const mcsg_node_kind ops[3] = {MCSG_NODE_UNION, MCSG_NODE_DIFFERENCE,
                                          MCSG_NODE_INTERSECTION};
    walk_frame f = w->frames[--w->frame_len];
    const scad_stmt *s = &w->sc->prog->stmts[f.stmt];
    uint32_t count = w->result_len - f.results;
    scad_dim dim = keep_one_dimension(w, &f, &count);
    mcsg_node_id node;
    mci_buf label = {0};
    mcsg_status st = MCSG_OK;
    if (f.geom != SCAD_NONE) {
        st = exit_geometry(w, &f, count, &node, &dim, err);
    } else if (f.role == ROLE_GROUP && count == 1) {
        node = w->results[f.results];
    } else if (frame_label(w, &f, &label) != MCSG_OK) {
        st = mci_fail_nomem(err, "reading CSG text");
    } else {
        mcsg_node_kind kind = f.role == ROLE_OP ? ops[s->module] : MCSG_NODE_UNION;
        st = mcsg_tree_add_op(w->sc->tree, kind, count ? w->results + f.results : NULL, count,
                              (const char *)label.data, &node, err);
        if (st != MCSG_OK && st != MCSG_ERR_NOMEM) /* the node limit */
            st = scad_fail_at(w->sc->name, s->line, s->col, err, st, "too many nodes");
    }
    mci_buf_free(w->sc->ev.ctx, &label);
    if (st != MCSG_OK)
        return st;
    w->result_len = f.results;
    scad_unbind_to(&w->sc->ev, f.bindings);
    w->sc->ev.heap_len = f.heap;
    if (st == MCSG_OK && dim != DIM_2D && f.own_transform &&
        w->transforms[f.transform].opens_frame)
        st = close_frame(w, &w->transforms[f.transform],
                         &w->transforms[w->frames[w->frame_len - 1].transform], node, err);
    if (st != MCSG_OK)
        return st;
    if (f.own_transform)
        w->transform_len--;
    return push_result(w, node, dim, err);
}

static mcsg_status walk_steps(walker *w, mcsg_error *err)
{
    const scad_program *prog = w->sc->prog;
    mcsg_status st = MCSG_OK;
    while (st == MCSG_OK && w->frame_len > 0) {
        walk_frame *top = &w->frames[w->frame_len - 1];
        uint32_t stmt = top->next;
        if (stmt == SCAD_NONE) {
            st = exit_frame(w, err);
            continue;
        }
        top->next = prog->stmts[stmt].next;
        if (prog->stmts[stmt].kind == ST_CALL)
            st = visit_call(w, stmt, top->transform, err);
    }
    return st;
}

/* Bind OpenSCAD's defaults for the predefined special variables ($preview is false:
 * meshcsg renders, like `openscad -o`). */
static mcsg_status bind_defaults(scad_eval *ev, mcsg_error *err)
{
    static const double defaults[VAR_PREDEFINED] = {0, 12, 2, 0, 0};
    mcsg_status st = MCSG_OK;
    for (uint32_t var = 0; var < VAR_PREDEFINED && st == MCSG_OK; var++) {
        scad_value v;
        memset(&v, 0, sizeof v);
        v.type = var == VAR_PREVIEW ? VAL_BOOL : VAL_NUMBER;
        v.number = defaults[var];
        st = scad_bind(ev, var, &v, true, err);
    }
    return st;
}

static mcsg_status walk(scad_context *sc, mcsg_error *err)
{
    static const scad_transform identity = {{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
                                            {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
                                            {0}, false, false, false};
    const mci_ctx *ctx = sc->ev.ctx;
    walker w;
    mcsg_status st;
    memset(&w, 0, sizeof w);
    w.sc = sc;
    w.seen_in_scope = mci_calloc_array(ctx, sc->prog->var_count, sizeof *w.seen_in_scope);
    w.last_assign = mci_calloc_array(ctx, sc->prog->var_count, sizeof *w.last_assign);
    st = (w.seen_in_scope && w.last_assign) ? MCSG_OK
                                            : mci_fail_nomem(err, "reading CSG text");
    if (st == MCSG_OK)
        st = bind_defaults(&sc->ev, err);
    if (st == MCSG_OK)
        st = push_transform(&w, &identity, err);
    if (st == MCSG_OK)
        st = push_frame(&w, 0, sc->ev.binding_len, sc->ev.heap_len, 0, false, ROLE_GROUP, err);
    if (st == MCSG_OK)
        st = walk_steps(&w, err);
    if (st == MCSG_OK && w.dims[0] == DIM_2D)
        st = mci_fail(err, MCSG_ERR_UNSUPPORTED, "%s: the top level is a 2D object: meshcsg "
                      "evaluates 3D objects (extrude it with linear_extrude or rotate_extrude)",
                      sc->name);
    if (st == MCSG_OK)
        st = mcsg_tree_set_root(sc->tree, w.results[0], err);
    /* On failure, the trees of geometry modules still open. */
    while (w.geom_len > 0) {
        mcsg_tree_free(sc->tree);
        sc->tree = w.geoms[--w.geom_len].outer;
    }
    mci_free(ctx, w.frames);
    mci_free(ctx, w.transforms);
    mci_free(ctx, w.results);
    mci_free(ctx, w.dims);
    mci_free(ctx, w.geoms);
    mci_free(ctx, w.seen_in_scope);
    mci_free(ctx, w.last_assign);
    mci_free(ctx, w.pending);
    return st;
}

mcsg_status mcsg_scad_read_memory(const char *text, size_t size, const char *name,
                                  const char *base_dir, const mcsg_options *opts,
                                  mcsg_tree **out, mcsg_error *err)
{
    mci_ctx ctx;
    scad_program prog;
    scad_context sc;
    mcsg_status st;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_scad_read_memory: NULL output");
    *out = NULL;
    if (!text && size)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_scad_read_memory: NULL text");
    name = name ? name : "<memory>";
    if (size >= UINT32_MAX - 16)
        return mci_fail(err, MCSG_ERR_LIMIT, "%s: CSG text of 4 GiB or more", name);
    mci_ctx_init(&ctx, opts);
    memset(&sc, 0, sizeof sc);
    sc.prog = &prog;
    sc.opts = opts;
    sc.base_dir = base_dir;
    sc.name = name;
    st = scad_parse(&prog, &ctx, text ? text : "", (uint32_t)size, name, err);
    if (st == MCSG_OK)
        st = scad_eval_init(&sc.ev, &prog, err);
    if (st == MCSG_OK)
        st = mcsg_tree_create(opts, &sc.tree, err);
    if (st == MCSG_OK)
        st = scad_prefetch_imports(&sc, err);
    if (st == MCSG_OK)
        st = walk(&sc, err);
    scad_prefetch_free(&sc);
    scad_eval_free(&sc.ev);
    scad_program_free(&prog);
    if (st != MCSG_OK) {
        mcsg_tree_free(sc.tree);
        return st;
    }
    *out = sc.tree;
    return MCSG_OK;
}

mcsg_status mcsg_scad_read(const char *path, const mcsg_options *opts, mcsg_tree **out,
                           mcsg_error *err)
{
    mci_ctx ctx;
    unsigned char *text;
    char *dir = NULL;
    const char *slash;
    size_t size;
    mcsg_status st;
    if (out)
        *out = NULL;
    if (!path || !out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_scad_read: NULL argument");
    mci_ctx_init(&ctx, opts);
    slash = strrchr(path, '/');
    if (slash) {
        size_t n = (size_t)(slash - path) + (slash == path); /* keep "/" for the root */
        dir = mci_malloc(&ctx, n + 1);
        if (!dir)
            return mci_fail_nomem(err, "reading a CSG file");
        memcpy(dir, path, n);
        dir[n] = 0;
    }
    st = mci_read_file(&ctx, path, &text, &size, err);
    if (st == MCSG_OK) {
        st = mcsg_scad_read_memory((const char *)text, size, path, dir, opts, out, err);
        mci_free(&ctx, text);
    }
    mci_free(&ctx, dir);
    return st;
}
