/*
 * The evaluator's input contract, checked before any geometry (docs/robustness.md):
 * every primitive must be closed as a chain (each edge used as often one way as the
 * other, vertices identified by coordinates) with finite coordinates. Zero-area
 * triangles bound nothing and are removed (mesh/zero_area.h) when they can be; the
 * primitive is then evaluated as that copy. It may have several shells (paired at
 * edges of more than two triangles, mcsg_check_report), apart, nested, crossing or
 * lying in each other, facing out or in: the primitive's solid is where its winding
 * number is positive.
 * Such primitives are marked for classification by winding numbers
 * (mci_ptree.leaf_winding). A leaf that breaks the contract is named in a one-line
 * message (its label says which file or primitive it came from, and where in the CSG
 * text) with the first offending edge, triangle or vertex; nothing is evaluated.
 * Shells crossing themselves are looked for (csg/shell_crossing.c, exact, about a third
 * of an evaluation on scanned models) when the options ask, in every primitive marked
 * for winding numbers (several shells, an inward volume, a shell meeting itself at an
 * edge: rare in clean input, so clean scenes pay nothing), in the leaves a tree asks
 * for (a frame's turned result), in the others when the result comes out open or
 * crossing itself (mci_mark_untested_crossing_leaves), and, by the test that counts every
 * pair, when evaluation stops on an internal consistency check; the primitives with one
 * are marked (mci_ptree.leaf_crossing) and evaluated with their faces intersected with
 * each other.
 */
#include "csg/leaf_check.h"
#include "base/parallel.h"
#include "csg/shell_crossing.h"
#include "mesh/tree.h"
#include "mesh/validate.h"
#include "mesh/zero_area.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef struct leaf_check_job {
    const mcsg_tree *tree;
    mci_ptree *ptree;
    const mci_ctx *ctx;
    mci_buf *notes; /* per leaf: its messages, each a level byte and a line with its NUL */
} leaf_check_job;

/* A message about leaf k, kept until the leaves are done: the log callback is called
 * from the caller's thread only (meshcsg.h), and in leaf order the log does not depend
 * on the threads. False when out of memory. */
static bool note(const leaf_check_job *job, size_t k, mcsg_log_level level, const char *fmt,
                 ...) MCI_PRINTF(4, 5);

static bool note(const leaf_check_job *job, size_t k, mcsg_log_level level, const char *fmt,
                 ...)
{
    char line[1024];
    unsigned char tag = (unsigned char)level;
    va_list ap;
    if (!job->ctx->log)
        return true;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    return mci_buf_append(job->ctx, &job->notes[k], &tag, 1) &&
           mci_buf_append(job->ctx, &job->notes[k], line, strlen(line) + 1);
}

/* fn over the leaves in parallel, then every leaf's messages logged, in leaf order. */
static mcsg_status run_over_leaves(leaf_check_job *job, mci_task_fn fn, mcsg_error *err)
{
    size_t n = job->ptree->leaf_count;
    mcsg_status st;
    job->notes = mci_calloc_array(job->ctx, n + 1, sizeof *job->notes);
    if (!job->notes)
        return mci_fail_nomem(err, "checking the leaves");
    st = mci_parallel_for(job->ctx, n, fn, job, err);
    for (size_t k = 0; k < n; k++) {
        const mci_buf *b = &job->notes[k];
        for (size_t i = 0; i < b->len; i += strlen((const char *)b->data + i + 1) + 2)
            mci_log(job->ctx, (mcsg_log_level)b->data[i], "%s", (const char *)b->data + i + 1);
        mci_buf_free(job->ctx, &job->notes[k]);
    }
    mci_free(job->ctx, job->notes);
    job->notes = NULL;
    return st;
}

static void format_point(char *buf, size_t size, const mcsg_mesh *m, uint32_t v)
{
    const double *p = m->vertices + 3 * (size_t)v;
    snprintf(buf, size, "(%.17g %.17g %.17g)", p[0], p[1], p[2]);
}

/* The first problem of the report as a phrase, with an example; empty when none. */
static void describe_problem(const mcsg_mesh *m, const mcsg_check_report *r, char *out,
                             size_t size)
{
    char a[80], b[80];
    out[0] = '\0';
    if (r->nonfinite_vertices) {
        format_point(a, sizeof a, m, r->example_nonfinite_vertex);
        snprintf(out, size, "%zu vertices have NaN or infinite coordinates, e.g. vertex %u %s",
                 r->nonfinite_vertices, r->example_nonfinite_vertex, a);
    } else if (r->boundary_edges) {
        format_point(a, sizeof a, m, r->example_boundary_edge[0]);
        format_point(b, sizeof b, m, r->example_boundary_edge[1]);
        snprintf(out, size, "the surface is open: %zu boundary edges, e.g. from %s to %s",
                 r->boundary_edges, a, b);
    } else if (r->unbalanced_edges) {
        format_point(a, sizeof a, m, r->example_unbalanced_edge[0]);
        format_point(b, sizeof b, m, r->example_unbalanced_edge[1]);
        snprintf(out, size, "the surface does not close up: %zu edges of more than two "
                 "triangles are used more often one way than the other, e.g. from %s to %s",
                 r->unbalanced_edges, a, b);
    } else if (r->inconsistent_edges) {
        format_point(a, sizeof a, m, r->example_inconsistent_edge[0]);
        format_point(b, sizeof b, m, r->example_inconsistent_edge[1]);
        snprintf(out, size, "not consistently oriented: %zu edges where neighbouring "
                 "triangles face opposite ways, e.g. from %s to %s", r->inconsistent_edges,
                 a, b);
    } else if (r->degenerate_triangles) {
        snprintf(out, size, "%zu triangles of zero area (no plane), e.g. triangle %u",
                 r->degenerate_triangles, r->example_degenerate_triangle);
    } else if (r->self_touching_edges) {
        format_point(a, sizeof a, m, r->example_self_touching_edge[0]);
        format_point(b, sizeof b, m, r->example_self_touching_edge[1]);
        snprintf(out, size, "not supported: %zu edges where one shell meets itself with "
                 "more than 64 triangles, e.g. from %s to %s", r->self_touching_edges, a, b);
    }
}

/* Whether zero-area triangles are the report's first problem (the surface closed, the
 * coordinates finite): then removing them is worth trying. */
static bool only_zero_area(const mcsg_check_report *r)
{
    return r->degenerate_triangles > 0 && r->out_of_range_indices == 0 &&
           r->nonfinite_vertices == 0 && r->boundary_edges == 0 && r->unbalanced_edges == 0 &&
           r->inconsistent_edges == 0;
}

/* Leaf k's mesh without its zero-area triangles (mesh/zero_area.c) in place of its own;
 * *removed: how many went. */
static mcsg_status remove_zero_area(const leaf_check_job *job, size_t k, size_t *removed,
                                    mcsg_error *err)
{
    mci_ptree *t = job->ptree;
    mcsg_mesh *copy = mci_malloc_array(job->ctx, 1, sizeof *copy);
    mci_zero_area res;
    uint32_t *face_of;
    *removed = 0;
    if (!copy || !mci_remove_zero_area(job->ctx, t->leaf_mesh[k], copy, &face_of, &res)) {
        mci_free(job->ctx, copy);
        return mci_fail_nomem(err, "checking the leaves");
    }
    t->leaf_cleaned[k] = copy;
    t->leaf_face_of[k] = face_of;
    t->leaf_mesh[k] = copy;
    *removed = res.removed;
    if (!note(job, k, mci_tree_is_made(job->tree, t->leaf_source[k]) ? MCSG_LOG_INFO
              : MCSG_LOG_WARNING, "leaf %u%s%s: %zu triangle%s of zero area removed "
              "(they bound nothing), %zu triangle%s added by splitting neighbours at their "
              "corners to keep the surface closed", t->leaf_source[k],
              mcsg_tree_node_label(job->tree, t->leaf_source[k])[0] ? ", " : "",
              mcsg_tree_node_label(job->tree, t->leaf_source[k]), res.removed,
              res.removed == 1 ? "" : "s", res.split, res.split == 1 ? "" : "s"))
        return mci_fail_nomem(err, "checking the leaves");
    return MCSG_OK;
}

/* Room for a half-edge twin list of leaf k (3 per triangle), or NULL when out of
 * memory. */
static uint32_t *twin_room(const leaf_check_job *job, size_t k)
{
    return mci_malloc_array(job->ctx, job->ptree->leaf_mesh[k]->triangle_count + 1,
                            3 * sizeof(uint32_t));
}

/* Leaf k's report and shells (per triangle, in shell[]), after removing its zero-area
 * triangles if they are its only problem (*shell reallocated then). With *twin (a leaf
 * that will be tested for crossing itself), its half-edge twins as well, from the same
 * pass (*twin reallocated with the shells). */
static mcsg_status check_shells(const leaf_check_job *job, size_t k, mcsg_check_report *report,
                                uint32_t **shell, uint32_t **twin, mcsg_error *err)
{
    mci_edge_mates *mates = &job->ptree->leaf_mates[k];
    size_t removed;
    mcsg_status st = mci_mesh_check_shells(job->ctx, job->ptree->leaf_mesh[k], report, *shell,
                                           *twin, mates, err);
    if (st != MCSG_OK || !only_zero_area(report))
        return st;
    if ((st = remove_zero_area(job, k, &removed, err)) != MCSG_OK || removed == 0)
        return st;
    mci_free(job->ctx, *shell);
    mci_edge_mates_free(job->ctx, mates);
    *shell = mci_malloc_array(job->ctx, job->ptree->leaf_mesh[k]->triangle_count + 1,
                              sizeof **shell);
    if (*twin) {
        mci_free(job->ctx, *twin);
        *twin = twin_room(job, k);
    }
    if (!*shell || (!*twin && job->ctx->check_self_intersections))
        return mci_fail_nomem(err, "checking the leaves");
    return mci_mesh_check_shells(job->ctx, job->ptree->leaf_mesh[k], report, *shell, *twin,
                                 mates, err);
}

/* Boxes from the leaf's mesh before it was turned (a frame's result), while the leaf is
 * that mesh turned, triangle for triangle (no zero-area triangle removed). */
static const mci_crossing_boxes *crossing_boxes(const leaf_check_job *job, size_t k,
                                                mci_crossing_boxes *boxes)
{
    mcsg_node_id node = job->ptree->leaf_source[k];
    const mcsg_mesh *own = mcsg_tree_leaf_mesh(job->tree, node);
    boxes->mesh = mci_tree_crossing_boxes(job->tree, node, &boxes->margin);
    if (!boxes->mesh || job->ptree->leaf_mesh[k] != own ||
        boxes->mesh->triangle_count != own->triangle_count)
        return NULL;
    return boxes;
}

/* Marks leaf k (leaf_crossing, leaf_winding) when a shell of it crosses itself: the fast
 * exact test of csg/shell_crossing.c, on the half-edge twins of the mesh check (`known`,
 * when it listed them; else from a second pass, which only the leaves tested pay for). */
static mcsg_status find_crossing(const leaf_check_job *job, size_t k, const uint32_t *known,
                                 mcsg_error *err)
{
    mci_crossing_boxes boxes;
    mci_ptree *t = job->ptree;
    const mcsg_mesh *m = t->leaf_mesh[k];
    mci_shell_crossing_stats stats;
    mcsg_check_report report;
    uint32_t example[2];
    bool crosses = false;
    uint32_t *twin;
    mcsg_status st;
    if (mci_star_shaped(m))
        return note(job, k, MCSG_LOG_DEBUG, "leaf %u: proven star-shaped: it does not cross "
                    "itself", t->leaf_source[k])
                   ? MCSG_OK
                   : mci_fail_nomem(err, "checking the leaves");
    twin = known ? NULL : twin_room(job, k);
    st = known ? MCSG_OK
         : twin ? mci_mesh_check_shells(job->ctx, m, &report, NULL, twin, NULL, err)
                : mci_fail_nomem(err, "checking the leaves");
    if (st == MCSG_OK)
        st = mci_find_shell_crossing_boxed(job->ctx, m, t->leaf_shell[k], known ? known : twin,
                                           crossing_boxes(job, k, &boxes), &crosses, example,
                                           &stats, err);
    mci_free(job->ctx, twin);
    if (st != MCSG_OK)
        return st;
    if (!note(job, k, MCSG_LOG_DEBUG, "leaf %u: tested for crossing itself: %zu of %zu "
              "triangles in %zu patches proven apart, %zu pairs tested in a grid of %zu "
              "entries", t->leaf_source[k], stats.proven_triangles, m->triangle_count,
              stats.proven_patches, stats.pairs_tested, stats.grid_entries))
        return mci_fail_nomem(err, "checking the leaves");
    if (!crosses)
        return MCSG_OK;
    t->leaf_crossing[k] = t->leaf_winding[k] = 1;
    if (!note(job, k, MCSG_LOG_INFO, "leaf %u%s%s: a shell crosses itself (e.g. triangles %u "
              "and %u): its solid is where its winding number is positive, and its faces are "
              "intersected with each other", t->leaf_source[k],
              mcsg_tree_node_label(job->tree, t->leaf_source[k])[0] ? ", " : "",
              mcsg_tree_node_label(job->tree, t->leaf_source[k]), example[0], example[1]))
        return mci_fail_nomem(err, "checking the leaves");
    return MCSG_OK;
}

/* Whether leaf k is tested for crossing itself before evaluation: every leaf when the
 * options ask, one told by winding numbers, one the tree asks for. */
static bool tested_up_front(const leaf_check_job *job, size_t k)
{
    const mci_ptree *t = job->ptree;
    return job->ctx->check_self_intersections || t->leaf_winding[k] ||
           mci_tree_tests_crossing(job->tree, t->leaf_source[k]);
}

/* The leaf's shells and kind from a report without problems: leaf_winding where only
 * winding numbers tell, leaf_crossing where its faces must be intersected with each
 * other. */
static mcsg_status mark_kind(const leaf_check_job *job, size_t k, const mcsg_check_report *report,
                             const uint32_t *twin, mcsg_error *err)
{
    mci_ptree *t = job->ptree;
    /* Where one shell meets itself at an edge, parts of it may lie inside others or face
     * inward (pair_neighbours in validate.c): only winding numbers tell. A single shell
     * enclosing no volume folds onto itself (nothing is inside it) or crosses itself into
     * lobes whose numbers cancel: its faces are intersected with each other without a
     * test. */
    bool no_volume = report->components == 1 && report->volume_sign == 0;
    t->leaf_crossing[k] |= no_volume;
    t->leaf_winding[k] = report->components > 1 || report->volume_sign < 0 ||
                         t->leaf_mates[k].count > 0 || no_volume;
    /* A leaf that only winding numbers tell (several shells, an inward volume, a shell
     * meeting itself at an edge) is rare in clean input and often crosses itself: a
     * shell folded through itself mostly encloses a negative volume, and a part nested
     * in another and joined to it at an edge overlaps it in their common faces. Such
     * leaves are always tested; every leaf when the options ask. */
    if (t->leaf_crossing[k] || !tested_up_front(job, k))
        return MCSG_OK;
    return find_crossing(job, k, twin, err);
}

static mcsg_status check_one(void *user, size_t k, mcsg_error *err)
{
    leaf_check_job *job = user;
    mcsg_node_id node = job->ptree->leaf_source[k];
    const char *label = mcsg_tree_node_label(job->tree, node);
    mcsg_check_report report;
    char problem[400];
    uint32_t *shell = mci_malloc_array(job->ctx, job->ptree->leaf_mesh[k]->triangle_count + 1,
                                       sizeof *shell);
    /* A leaf sure to be tested for crossing itself gets its twins from the check's pass. */
    bool tested = job->ctx->check_self_intersections || mci_tree_tests_crossing(job->tree, node);
    uint32_t *twin = tested ? twin_room(job, k) : NULL;
    mcsg_status st = shell && (twin || !job->ctx->check_self_intersections)
                         ? check_shells(job, k, &report, &shell, &twin, err)
                         : mci_fail_nomem(err, "checking the leaves");
    if (st == MCSG_OK) {
        describe_problem(job->ptree->leaf_mesh[k], &report, problem, sizeof problem);
        if (problem[0] == '\0' && report.components > 1) {
            job->ptree->leaf_shell[k] = shell;
            job->ptree->leaf_shells[k] = (uint32_t)report.components;
            shell = NULL;
        }
        if (problem[0] == '\0')
            st = mark_kind(job, k, &report, twin, err);
        else
            st = mci_fail(err, MCSG_ERR_INVALID_MESH, "leaf %u%s%s: %s", node,
                          label[0] ? ", " : "", label, problem);
    }
    mci_free(job->ctx, shell);
    mci_free(job->ctx, twin);
    return st;
}

static mcsg_status scan_leaves(const mci_ctx *ctx, const mcsg_tree *tree, mci_ptree *ptree,
                               bool whole, size_t *count, mcsg_error *err);

mcsg_status mci_check_leaves(const mci_ctx *ctx, const mcsg_tree *tree, mci_ptree *ptree,
                             mcsg_error *err)
{
    leaf_check_job job = {tree, ptree, ctx, NULL};
    return run_over_leaves(&job, check_one, err);
}

/* The crossing pairs of leaf k's mesh, within each of its shells (shells may cross each
 * other), or over the whole mesh: *pairs and an example (triangle indices of the whole
 * mesh). */
static mcsg_status shell_self_intersections(const mci_ctx *ctx, const mci_ptree *ptree, size_t k,
                                            bool whole, const mcsg_options *opts, size_t *pairs,
                                            uint32_t example[2], mcsg_error *err)
{
    const mcsg_mesh *m = ptree->leaf_mesh[k];
    const uint32_t *shell = whole ? NULL : ptree->leaf_shell[k];
    uint32_t shells = ptree->leaf_shells[k], *tris, *index, *start;
    mcsg_status st = MCSG_OK;
    if (!shell)
        return mcsg_mesh_self_intersections(m, opts, pairs, example, err);
    tris = mci_malloc_array(ctx, 3 * m->triangle_count + 1, sizeof *tris);
    index = mci_malloc_array(ctx, m->triangle_count + 1, sizeof *index);
    start = mci_calloc_array(ctx, (size_t)shells + 2, sizeof *start);
    *pairs = 0;
    if (!tris || !index || !start)
        st = mci_fail_nomem(err, "checking the leaves");
    /* Triangles by shell (a counting sort): a file of thousands of parts is one pass. */
    for (size_t t = 0; st == MCSG_OK && t < m->triangle_count; t++)
        start[shell[t] + 2]++;
    for (uint32_t s = 2; st == MCSG_OK && s < shells + 2; s++)
        start[s] += start[s - 1];
    for (size_t t = 0; st == MCSG_OK && t < m->triangle_count; t++) {
        uint32_t at = start[shell[t] + 1]++;
        memcpy(tris + 3 * (size_t)at, m->triangles + 3 * t, 3 * sizeof *tris);
        index[at] = (uint32_t)t;
    }
    for (uint32_t s = 0; st == MCSG_OK && s < shells && *pairs == 0; s++) {
        mcsg_mesh part = {m->vertices, tris + 3 * (size_t)start[s], m->vertex_count,
                          start[s + 1] - start[s]};
        st = mcsg_mesh_self_intersections(&part, opts, pairs, example, err);
        if (st == MCSG_OK && *pairs > 0)
            example[0] = index[start[s] + example[0]], example[1] = index[start[s] + example[1]];
    }
    mci_free(ctx, tris);
    mci_free(ctx, index);
    mci_free(ctx, start);
    return st;
}

/* Every leaf a shell of which crosses itself is marked (mci_ptree.leaf_crossing) and
 * counted in *count; with `whole`, the first leaf any two of whose triangles cross
 * (shells touching each other too) is an INVALID_MESH error instead. */
static mcsg_status scan_leaves(const mci_ctx *ctx, const mcsg_tree *tree, mci_ptree *ptree,
                               bool whole, size_t *count, mcsg_error *err)
{
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    opts.allocator = ctx->alloc;
    opts.log = ctx->log;
    opts.log_user = ctx->log_user;
    opts.threads = ctx->threads;
    *count = 0;
    for (size_t k = 0; k < ptree->leaf_count; k++) {
        mcsg_node_id node = ptree->leaf_source[k];
        const char *label = mcsg_tree_node_label(tree, node);
        size_t pairs;
        uint32_t example[2];
        mcsg_status st;
        st = shell_self_intersections(ctx, ptree, k, whole, &opts, &pairs, example, err);
        if (st != MCSG_OK)
            return st;
        if (pairs > 0 && whole)
            return mci_fail(err, MCSG_ERR_INVALID_MESH, "leaf %u%s%s intersects itself: %zu "
                            "pairs of its triangles cross or overlap, e.g. triangles %u and %u",
                            node, label[0] ? ", " : "", label, pairs, example[0], example[1]);
        if (pairs > 0 && !ptree->leaf_crossing[k]) {
            ptree->leaf_crossing[k] = ptree->leaf_winding[k] = 1;
            ++*count;
        }
    }
    return MCSG_OK;
}

static mcsg_status test_untested_one(void *user, size_t k, mcsg_error *err)
{
    leaf_check_job *job = user;
    return job->ptree->leaf_crossing[k] || tested_up_front(job, k)
               ? MCSG_OK
               : find_crossing(job, k, NULL, err);
}

mcsg_status mci_mark_untested_crossing_leaves(const mci_ctx *ctx, const mcsg_tree *tree,
                                              mci_ptree *ptree, size_t *marked,
                                              mcsg_error *err)
{
    leaf_check_job job = {tree, ptree, ctx, NULL};
    uint8_t *before = mci_malloc_array(ctx, ptree->leaf_count + 1, 1);
    mcsg_status st;
    *marked = 0;
    if (!before)
        return mci_fail_nomem(err, "checking the leaves");
    memcpy(before, ptree->leaf_crossing, ptree->leaf_count);
    st = run_over_leaves(&job, test_untested_one, err);
    for (size_t k = 0; st == MCSG_OK && k < ptree->leaf_count; k++)
        *marked += ptree->leaf_crossing[k] && !before[k];
    mci_free(ctx, before);
    return st;
}

mcsg_status mci_mark_crossing_leaves(const mci_ctx *ctx, const mcsg_tree *tree,
                                     mci_ptree *ptree, size_t *marked, mcsg_error *err)
{
    return scan_leaves(ctx, tree, ptree, false, marked, err);
}

mcsg_status mci_explain_internal_error(const mci_ctx *ctx, const mcsg_tree *tree,
                                       mci_ptree *ptree, mcsg_error *err)
{
    mcsg_error saved, probe;
    mcsg_status st;
    size_t count;
    if (err)
        saved = *err;
    /* Every pair that meets, shells against each other too: the leaf whose surfaces
     * cross or touch is the likeliest cause, and naming it helps more than a bug report. */
    st = scan_leaves(ctx, tree, ptree, true, &count, &probe);
    if (st == MCSG_ERR_INVALID_MESH) {
        if (err)
            *err = probe;
        return st;
    }
    if (err)
        *err = saved;
    return MCSG_ERR_INTERNAL;
}

