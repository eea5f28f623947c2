/*
 * Evaluation of a tree with frames (mesh/tree.h): each frame's subtree is evaluated on
 * its own in its own coordinates, innermost first, and its result, turned into the
 * enclosing frame, stands in for the subtree as a leaf of the next evaluation; the last
 * evaluation is the root's. Faces that a group's own frame makes coplanar stay coplanar,
 * where turning each leaf alone would leave them ~1e-16 apart (features below the
 * spacing of doubles, which rounding cannot keep valid). Provenance goes through the
 * frames back to the tree's own leaves.
 */
#include "csg/frames.h"

#include "base/sort.h"
#include "csg/output_check.h"
#include "csg/self_intersect.h"
#include "csg/separate_copies.h"
#include "csg/shell_crossing.h"
#include "mesh/tree.h"
#include "mesh/validate.h"

#include <math.h>
#include <string.h>

/* Log lines held back until it is known whether the evaluation that wrote them gives the
 * result: the frames' path and, where that breaks a guarantee, the flattened one. */
typedef struct held_log {
    const mci_ctx *outer; /* the caller's logger and allocator */
    const char *prefix;   /* put before each line (a frame's own evaluation), or NULL */
    char **lines;
    uint8_t *levels;
    size_t count, cap;
} held_log;

static void hold_line(void *user, mcsg_log_level level, const char *message)
{
    held_log *h = user;
    const mci_ctx *ctx = h->outer;
    mci_buf line = {0};
    if (h->count == h->cap) {
        size_t cap = h->cap ? 2 * h->cap : 16;
        char **lines = mci_realloc_array(ctx, h->lines, cap, sizeof *lines);
        uint8_t *levels = lines ? mci_realloc_array(ctx, h->levels, cap, sizeof *levels) : NULL;
        h->lines = lines ? lines : h->lines;
        h->levels = levels ? levels : h->levels;
        if (!levels) { /* out of memory: the line goes out now rather than never */
            ctx->log(ctx->log_user, level, message);
            return;
        }
        h->cap = cap;
    }
    if (!mci_buf_printf(ctx, &line, "%s%s", h->prefix ? h->prefix : "", message)) {
        ctx->log(ctx->log_user, level, message);
        return;
    }
    h->lines[h->count] = (char *)line.data;
    h->levels[h->count++] = (uint8_t)level;
}

/* Options whose log goes into h (unless the caller logs nothing). */
static mcsg_options holding(const mcsg_options *opts, held_log *h)
{
    mcsg_options held = opts ? *opts : (mcsg_options){0};
    if (h->outer->log) {
        held.log = hold_line;
        held.log_user = h;
    }
    return held;
}

/* Pass the held lines on, as warnings where they were, or all as information (the
 * result they speak of is not the one returned), and forget them. */
static void release_lines(held_log *h, bool as_written)
{
    for (size_t i = 0; i < h->count; i++) {
        mcsg_log_level level = (mcsg_log_level)h->levels[i];
        if (!as_written && level > MCSG_LOG_INFO)
            level = MCSG_LOG_INFO;
        h->outer->log(h->outer->log_user, level, h->lines[i]);
        mci_free(h->outer, h->lines[i]);
    }
    mci_free(h->outer, h->lines);
    mci_free(h->outer, h->levels);
    h->lines = NULL;
    h->levels = NULL;
    h->count = h->cap = 0;
}

/* A frame's result in the coordinates of the frame around it. */
typedef struct frame_result {
    mcsg_mesh mesh;
    mcsg_mesh own;               /* the same in the frame's own coordinates */
    double margin;               /* how far apart in `own` its triangles may be and still
                                    meet once turned (mci_turn_margin), or -1 */
    bool clean;                  /* proven not to cross itself once turned */
    size_t mended;               /* corners moved to mend crossings the turn made */
    mcsg_provenance *provenance; /* per triangle: a leaf of the original tree and its face */
} frame_result;

typedef struct frames {
    const mcsg_tree *tree;
    const mcsg_options *opts;
    mci_ctx ctx;
    uint32_t *slot;          /* node -> its frame's index in `results` (frame nodes only) */
    mcsg_node_id *map;       /* node -> its node in the tree being built */
    mcsg_node_id *source;    /* built tree's leaf -> original leaf, or MCSG_NO_NODE ... */
    uint32_t *source_frame;  /* ... and then the frame whose result it is */
    mcsg_node_id *list;      /* nodes of one subtree */
    mcsg_node_id *order;     /* the frames, innermost first */
    mcsg_node_id *stack;
    frame_result *results;
    size_t frame_count;
    double frame_seconds;    /* the frames' evaluations, turns and mending */
    held_log log;            /* what the frames' path logs */
    mcsg_options held;       /* f->opts with that log */
    mci_ctx held_ctx;        /* the same as a context, for this file's own lines */
} frames;

static mcsg_status alloc_state(frames *f, mcsg_error *err)
{
    size_t n = mcsg_tree_node_count(f->tree);
    f->slot = mci_malloc_array(&f->ctx, n, sizeof *f->slot);
    f->map = mci_malloc_array(&f->ctx, n, sizeof *f->map);
    f->source = mci_malloc_array(&f->ctx, n, sizeof *f->source);
    f->source_frame = mci_malloc_array(&f->ctx, n, sizeof *f->source_frame);
    f->list = mci_malloc_array(&f->ctx, n, sizeof *f->list);
    f->order = mci_malloc_array(&f->ctx, n, sizeof *f->order);
    f->stack = mci_malloc_array(&f->ctx, n, sizeof *f->stack);
    f->results = mci_calloc_array(&f->ctx, mci_tree_frame_count(f->tree), sizeof *f->results);
    if (!f->slot || !f->map || !f->source || !f->source_frame || !f->list || !f->order ||
        !f->stack || !f->results)
        return mci_fail_nomem(err, "evaluating frames");
    return MCSG_OK;
}

static void free_state(frames *f)
{
    for (size_t i = 0; f->results && i < f->frame_count; i++) {
        mci_mesh_free(&f->ctx, &f->results[i].mesh);
        mci_mesh_free(&f->ctx, &f->results[i].own);
        mci_free(&f->ctx, f->results[i].provenance);
    }
    mci_free(&f->ctx, f->results);
    mci_free(&f->ctx, f->slot);
    mci_free(&f->ctx, f->map);
    mci_free(&f->ctx, f->source);
    mci_free(&f->ctx, f->source_frame);
    mci_free(&f->ctx, f->list);
    mci_free(&f->ctx, f->order);
    mci_free(&f->ctx, f->stack);
}

static bool is_frame(const frames *f, mcsg_node_id node)
{
    return mci_tree_frame(f->tree, node) != NULL;
}

/* The nodes under `top` (itself included), ascending, into f->list; with `whole` the
 * walk goes through frames, else it stops at every frame but `top`. Returns the count. */
static size_t collect(frames *f, mcsg_node_id top, bool whole)
{
    size_t len = 0, count = 0;
    f->stack[len++] = top;
    while (len > 0) {
        mcsg_node_id n = f->stack[--len];
        size_t children = mcsg_tree_child_count(f->tree, n);
        f->list[count++] = n;
        if (n != top && !whole && is_frame(f, n))
            continue;
        for (size_t i = 0; i < children; i++)
            f->stack[len++] = mcsg_tree_child(f->tree, n, i);
    }
    mci_sort_u32(f->list, count);
    return count;
}

/* Add `n` (a leaf, or a frame other than the subject standing in as its result) to the
 * tree being built, recording where its faces come from. */
static mcsg_status add_leaf_for(frames *f, mcsg_tree *sub, mcsg_node_id n, bool in_frame,
                                mcsg_error *err)
{
    bool stand_in = mcsg_tree_node_kind(f->tree, n) != MCSG_NODE_LEAF;
    const frame_result *r = stand_in ? &f->results[f->slot[n]] : NULL;
    const mcsg_mesh *local = stand_in ? NULL : mci_tree_leaf_local(f->tree, n);
    const mcsg_mesh *mesh = stand_in ? &r->mesh
                            : (in_frame && local) ? local : mcsg_tree_leaf_mesh(f->tree, n);
    const char *label = mcsg_tree_node_label(f->tree, n);
    mci_buf result_label = {0};
    mcsg_node_id id;
    mcsg_status st;
    /* messages about a stand-in must not pass it off as the user's own leaf */
    if (stand_in && !mci_buf_printf(&f->ctx, &result_label, "the turned result of %s",
                                    label[0] ? label : "a group"))
        return mci_fail_nomem(err, "evaluating frames");
    if (stand_in)
        label = (const char *)result_label.data;
    if (mesh->triangle_count == 0)
        st = mcsg_tree_add_op(sub, MCSG_NODE_UNION, NULL, 0, label, &id, err);
    else
        st = mcsg_tree_add_leaf(sub, mesh, NULL, label, &id, err);
    mci_buf_free(&f->ctx, &result_label);
    if (st != MCSG_OK)
        return st;
    f->map[n] = id;
    f->source[id] = stand_in ? MCSG_NO_NODE : n;
    f->source_frame[id] = stand_in ? f->slot[n] : 0;
    if (!stand_in || mesh->triangle_count == 0)
        return MCSG_OK;
    mci_tree_set_made(sub, id);
    /* Turned and rounded, a frame's result may cross itself where two of its triangles
     * came within a unit in the last place of each other (a thin triangle folded over
     * its neighbour), unless mend_turned proved it clean: evaluated as a clean leaf, it
     * could come out wrong */
    if (!r->clean) {
        mci_tree_set_tests_crossing(sub, id);
        if (r->margin >= 0) /* boxes where the result lies along the axes, tight */
            mci_tree_set_crossing_boxes(sub, id, &r->own, r->margin);
    }
    return MCSG_OK;
}

static mcsg_status add_op_for(frames *f, mcsg_tree *sub, mcsg_node_id n, mcsg_error *err)
{
    size_t children = mcsg_tree_child_count(f->tree, n);
    mcsg_node_id *ids = mci_malloc_array(&f->ctx, children ? children : 1, sizeof *ids);
    mcsg_status st;
    if (!ids)
        return mci_fail_nomem(err, "evaluating frames");
    for (size_t i = 0; i < children; i++)
        ids[i] = f->map[mcsg_tree_child(f->tree, n, i)];
    st = mcsg_tree_add_op(sub, mcsg_tree_node_kind(f->tree, n), ids, children,
                          mcsg_tree_node_label(f->tree, n), &f->map[n], err);
    mci_free(&f->ctx, ids);
    return st;
}

/* The tree of `top`'s subtree, its inner frames as leaves holding their results, its
 * leaves in `top`'s coordinates when `top` is a frame (else in the world's). The root's
 * tree (`root`) holds the root's result if the root itself is a frame. */
static mcsg_status build_tree(frames *f, mcsg_node_id top, bool root, mcsg_tree **out,
                              mcsg_error *err)
{
    bool in_frame = !root && is_frame(f, top);
    size_t count = 1;
    mcsg_status st = mcsg_tree_create(f->opts, out, err);
    if (root && is_frame(f, top))
        f->list[0] = top; /* the whole tree is one frame: its result alone */
    else
        count = collect(f, top, false);
    for (size_t i = 0; i < count && st == MCSG_OK; i++) {
        mcsg_node_id n = f->list[i];
        bool stands_in = (n != top || root) && is_frame(f, n);
        if (stands_in || mcsg_tree_node_kind(f->tree, n) == MCSG_NODE_LEAF)
            st = add_leaf_for(f, *out, n, in_frame, err);
        else
            st = add_op_for(f, *out, n, err);
    }
    if (st == MCSG_OK)
        st = mcsg_tree_set_root(*out, f->map[top], err);
    return st;
}

/* Rewrite a built tree's provenance in terms of the original tree's leaves. */
static void map_provenance(const frames *f, mcsg_provenance *p, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        mcsg_node_id leaf = p[i].leaf;
        if (f->source[leaf] != MCSG_NO_NODE)
            p[i].leaf = f->source[leaf];
        else
            p[i] = f->results[f->source_frame[leaf]].provenance[p[i].face];
    }
}

/* Whether the map's linear part has an inverse whose infinity norm is provably at most
 * *bound: X, the inverse by cofactors in doubles, bounds it by ||X|| / (1 - r) where r
 * bounds ||I - X M|| (computed, plus what rounding the products can hide), when r < 1/2.
 * Rounding errors are covered by factors far larger than they can be. */
static bool inverse_norm_bound(const double m[12], double *bound)
{
    const double a[3][3] = {{m[0], m[1], m[2]}, {m[4], m[5], m[6]}, {m[8], m[9], m[10]}};
    double x[3][3], det, norm_x = 0, norm_m = 0, residual = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) /* x = adj(a) / det: x[i][j] is cofactor (j, i) */
            x[i][j] = a[(j + 1) % 3][(i + 1) % 3] * a[(j + 2) % 3][(i + 2) % 3] -
                      a[(j + 1) % 3][(i + 2) % 3] * a[(j + 2) % 3][(i + 1) % 3];
    det = a[0][0] * x[0][0] + a[0][1] * x[1][0] + a[0][2] * x[2][0];
    if (!(fabs(det) > 0x1p-500) || !isfinite(det))
        return false;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            x[i][j] /= det;
    for (int i = 0; i < 3; i++) {
        double row_x = 0, row_m = 0, row_r = 0;
        for (int j = 0; j < 3; j++) {
            double xm = x[i][0] * a[0][j] + x[i][1] * a[1][j] + x[i][2] * a[2][j];
            row_x += fabs(x[i][j]);
            row_m += fabs(a[i][j]);
            row_r += fabs((i == j ? 1.0 : 0.0) - xm);
        }
        norm_x = fmax(norm_x, row_x);
        norm_m = fmax(norm_m, row_m);
        residual = fmax(residual, row_r);
    }
    /* each entry of X M is off by at most ~4u ||X|| ||M|| (3 products, 2 sums, the
     * divisions): 64u covers it with room */
    residual += 0x1p-47 * norm_x * norm_m + 0x1p-60;
    if (!(residual < 0.5) || !isfinite(norm_x))
        return false;
    *bound = norm_x / (1 - residual) * (1 + 0x1p-40);
    return true;
}

/* How far apart, along any axis, two points of `own` may be and still meet once mapped
 * by m (mcsg_mesh_transform) with each coordinate rounded: each mapped coordinate is off
 * by at most gamma_4 (|m_r0 x| + |m_r1 y| + |m_r2 z| + |m_r3|), gamma_4 = 4u / (1 - 4u)
 * (three products and three sums), so two rounded points that coincide come from points
 * at most ||M^-1|| * 2 * that apart. -1 when no bound is proven. */
double mci_turn_margin(const double m[12], const mcsg_mesh *own)
{
    double largest[3] = {0, 0, 0}, error = 0, inverse;
    if (!inverse_norm_bound(m, &inverse))
        return -1;
    for (size_t v = 0; v < own->vertex_count; v++)
        for (int c = 0; c < 3; c++)
            largest[c] = fmax(largest[c], fabs(own->vertices[3 * v + c]));
    for (int r = 0; r < 3; r++) {
        double sum = fabs(m[4 * r + 3]);
        for (int c = 0; c < 3; c++)
            sum += fabs(m[4 * r + c]) * largest[c];
        error = fmax(error, sum);
    }
    error *= 0x1p-50; /* > gamma_4 = 2^-51 / (1 - 2^-51), the sums' rounding included */
    return isfinite(error * inverse) ? 2 * error * inverse * (1 + 0x1p-40) : -1;
}

/* The turned result's crossing pairs (boxes before the turn where a margin is proven). */
static mcsg_status turned_crossings(frames *f, const frame_result *r, const uint32_t *twin,
                                    uint64_t **pairs, size_t *count, mcsg_error *err)
{
    mci_crossing_boxes boxes = {&r->own, r->margin};
    return mci_list_shell_crossings(&f->ctx, &r->mesh, twin, r->margin >= 0 ? &boxes : NULL,
                                    pairs, count, err);
}

/* The pairs that still cross, of those listed. */
static size_t still_crossing(const mcsg_mesh *m, const uint64_t *pairs, size_t count)
{
    size_t left = 0;
    for (size_t i = 0; i < count; i++)
        left += mci_triangles_cross(m, (uint32_t)(pairs[i] >> 32), (uint32_t)pairs[i]);
    return left;
}

/* Turning rounds every vertex on its own, which can fold a triangle thinner than a unit
 * in the last place over its neighbour: the crossing pairs are listed and their corners
 * moved by a unit in the last place where that mends them (as for the output's rounding,
 * separate_copies.h). A corner moves only where its triangles cross nothing near them,
 * so only the listed pairs can still cross; r->clean when none does (else the mesh is a
 * leaf that crosses itself, evaluated by its winding number). */
static mcsg_status mend_turned(frames *f, frame_result *r, mcsg_error *err)
{
    mcsg_check_report report;
    uint64_t *pairs = NULL;
    size_t count = 0;
    uint32_t *twin = mci_malloc_array(&f->ctx, r->mesh.triangle_count + 1, 3 * sizeof *twin);
    mcsg_status st = twin ? mci_mesh_check_shells(&f->ctx, &r->mesh, &report, NULL, twin, NULL,
                                                  err)
                          : mci_fail_nomem(err, "evaluating frames");
    if (st == MCSG_OK)
        st = turned_crossings(f, r, twin, &pairs, &count, err);
    if (st == MCSG_OK && count > 0 &&
        !mci_separate_crossing_corners(&f->ctx, &r->mesh, pairs, count, &r->mended))
        st = mci_fail_nomem(err, "evaluating frames");
    r->clean = st == MCSG_OK && (count == 0 || still_crossing(&r->mesh, pairs, count) == 0);
    if (st == MCSG_OK && count > 0)
        mci_log(&f->held_ctx, MCSG_LOG_INFO, "turning a group's result made %zu pairs of its "
                "triangles cross; %zu corners moved by a unit in the last place %s", count,
                r->mended, r->clean ? "mend them" : "do not mend them all: it is evaluated "
                "as a mesh that crosses itself");
    mci_free(&f->ctx, pairs);
    mci_free(&f->ctx, twin);
    return st;
}

/* Evaluate one frame and keep its result, turned into the enclosing frame. */
static mcsg_status evaluate_frame(frames *f, mcsg_node_id node, mcsg_error *err)
{
    frame_result *r = &f->results[f->slot[node]];
    const char *label = mcsg_tree_node_label(f->tree, node);
    double t0 = mci_seconds_now();
    mcsg_tree *sub = NULL;
    mci_buf prefix = {0};
    mcsg_status st = build_tree(f, node, false, &sub, err);
    if (st == MCSG_OK && !mci_buf_printf(&f->ctx, &prefix, "%s, in its own coordinates: ",
                                         label[0] ? label : "a turned group"))
        st = mci_fail_nomem(err, "evaluating frames");
    f->log.prefix = (const char *)prefix.data;
    if (st == MCSG_OK)
        st = mcsg_eval(sub, &f->held, &r->mesh, &r->provenance, NULL, err);
    f->log.prefix = NULL;
    mci_buf_free(&f->ctx, &prefix);
    if (st == MCSG_OK) {
        map_provenance(f, r->provenance, r->mesh.triangle_count);
        st = mcsg_mesh_copy(&r->mesh, f->opts, &r->own, err);
    }
    if (st == MCSG_OK) {
        r->margin = mci_turn_margin(mci_tree_frame(f->tree, node), &r->own);
        mcsg_mesh_transform(&r->mesh, mci_tree_frame(f->tree, node));
        st = mend_turned(f, r, err);
    }
    mcsg_tree_free(sub);
    f->frame_seconds += mci_seconds_now() - t0;
    return st;
}

/* The frames the root reaches, innermost first (ascending ids: children come first). */
static size_t order_frames(frames *f, mcsg_node_id root)
{
    size_t count = collect(f, root, true), frames_found = 0;
    for (size_t i = 0; i < count; i++) {
        if (is_frame(f, f->list[i])) {
            f->slot[f->list[i]] = (uint32_t)frames_found;
            f->order[frames_found++] = f->list[i];
        }
    }
    return frames_found;
}

static mcsg_status evaluate_all(frames *f, mcsg_mesh *out, mcsg_provenance **provenance,
                                mcsg_eval_stats *stats, mcsg_error *err)
{
    mcsg_node_id root = mcsg_tree_root(f->tree);
    mcsg_provenance *own = NULL;
    mcsg_tree *top = NULL;
    mcsg_status st;
    f->frame_count = order_frames(f, root);
    for (size_t i = 0; i < f->frame_count; i++) {
        st = evaluate_frame(f, f->order[i], err);
        if (st != MCSG_OK)
            return st;
    }
    st = build_tree(f, root, true, &top, err);
    if (st == MCSG_OK)
        st = mcsg_eval(top, &f->held, out, &own, stats, err);
    if (st == MCSG_OK) {
        map_provenance(f, own, out->triangle_count);
        stats->frames_evaluated = f->frame_count;
        stats->seconds_frames = f->frame_seconds;
        stats->seconds_total += f->frame_seconds;
        if (provenance)
            *provenance = own;
        else
            mci_free(&f->ctx, own);
    }
    mcsg_tree_free(top);
    return st;
}

/* The frames' result broke a guarantee: where turning the leaves one by one does better
 * (the group's own evaluation may be what broke), that result is kept instead. Only the
 * kept result's log lines keep their level. */
static mcsg_status try_flattened(frames *f, mcsg_mesh *out, mcsg_provenance **provenance,
                                 mcsg_eval_stats *stats, mcsg_error *err)
{
    mcsg_mesh flat;
    mcsg_provenance *flat_provenance = NULL;
    mcsg_eval_stats flat_stats;
    held_log flat_log = {&f->ctx, NULL, NULL, NULL, 0, 0};
    mcsg_options held = holding(f->opts, &flat_log);
    mcsg_status st;
    bool better;
    if (!mcsg_output_check_failed(&stats->output_check)) {
        release_lines(&f->log, true);
        return MCSG_OK;
    }
    st = mci_eval_flattened(f->tree, &held, &flat, provenance ? &flat_provenance : NULL,
                            &flat_stats, err);
    better = st == MCSG_OK && mci_output_check_defects(&flat_stats.output_check) <
                                  mci_output_check_defects(&stats->output_check);
    release_lines(better ? &f->log : &flat_log, false);
    release_lines(better ? &flat_log : &f->log, true);
    if (st != MCSG_OK)
        return st;
    flat_stats.seconds_total += stats->seconds_total;
    if (!better) {
        stats->seconds_total = flat_stats.seconds_total;
        mci_mesh_free(&f->ctx, &flat);
        mci_free(&f->ctx, flat_provenance);
        return MCSG_OK;
    }
    mci_log(&f->ctx, MCSG_LOG_INFO, "the result of turned groups evaluated in their own "
            "coordinates broke a guarantee; the tree with each leaf turned on its own breaks "
            "fewer and is returned");
    flat_stats.seconds_frames = stats->seconds_frames;
    flat_stats.frames_evaluated = stats->frames_evaluated;
    flat_stats.frames_flattened = 1;
    mci_mesh_free(&f->ctx, out);
    *out = flat;
    if (provenance) {
        mci_free(&f->ctx, *provenance);
        *provenance = flat_provenance;
    }
    *stats = flat_stats;
    return MCSG_OK;
}

/* The frames' path failed (a frame's turned result may cross itself in a way that no
 * evaluation takes): the tree flattened gives the result, or the error that names the
 * user's own leaf. */
static mcsg_status flattened_after_error(frames *f, mcsg_mesh *out,
                                         mcsg_provenance **provenance, mcsg_eval_stats *stats,
                                         mcsg_error *err)
{
    mcsg_status st;
    size_t count = f->frame_count;
    release_lines(&f->log, false);
    mci_log(&f->ctx, MCSG_LOG_INFO, "turned groups evaluated in their own coordinates "
            "failed (%s); the tree is evaluated with each leaf turned on its own",
            err ? err->message : "no message");
    mci_mesh_free(&f->ctx, out);
    if (provenance) {
        mci_free(&f->ctx, *provenance);
        *provenance = NULL;
    }
    st = mci_eval_flattened(f->tree, f->opts, out, provenance, stats, err);
    if (st == MCSG_OK) {
        stats->frames_evaluated = count;
        stats->frames_flattened = 1;
        stats->seconds_frames = f->frame_seconds;
        stats->seconds_total += f->frame_seconds;
    }
    return st;
}

mcsg_status mci_eval_frames(const mcsg_tree *tree, const mcsg_options *opts, mcsg_mesh *out,
                            mcsg_provenance **provenance, mcsg_eval_stats *stats,
                            mcsg_error *err)
{
    frames f;
    mcsg_eval_stats own_stats;
    mcsg_status st;
    memset(&f, 0, sizeof f);
    memset(&own_stats, 0, sizeof own_stats);
    f.tree = tree;
    f.opts = opts;
    mci_ctx_init(&f.ctx, opts);
    f.log.outer = &f.ctx;
    f.held = holding(opts, &f.log);
    mci_ctx_init(&f.held_ctx, &f.held);
    stats = stats ? stats : &own_stats;
    st = alloc_state(&f, err);
    if (st == MCSG_OK)
        st = evaluate_all(&f, out, provenance, stats, err);
    free_state(&f);
    if (st == MCSG_OK)
        st = try_flattened(&f, out, provenance, stats, err);
    else if (st == MCSG_ERR_NOMEM || st == MCSG_ERR_CANCELLED)
        release_lines(&f.log, true);
    else
        st = flattened_after_error(&f, out, provenance, stats, err);
    if (st != MCSG_OK) {
        mci_mesh_free(&f.ctx, out);
        if (provenance) {
            mci_free(&f.ctx, *provenance);
            *provenance = NULL;
        }
    }
    return st;
}
