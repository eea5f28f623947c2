/*
 * Evaluating the rounded result again (reevaluate.h).
 *
 * Rounding moves each vertex by at most half a unit in the last place, and where the
 * exact result has features thinner than that (a sliver between nearly coplanar faces,
 * two vertices closer than the spacing of doubles) the rounded mesh can fold, weld two
 * parts into an edge of four triangles, or cross itself. The rounded mesh is still
 * closed as a chain, so it is a valid leaf: evaluated alone by its winding number (its
 * shells tested for crossings and cut where they cross, coincident faces of opposite
 * orientation cancelled, edges of four triangles paired by angle), its exact result has
 * none of those defects, and only the new intersection vertices are rounded again. Those
 * can break a guarantee in turn, so a round is kept only when its own check passes, up to
 * three rounds are tried, and otherwise the first result stays (with its report).
 */
#include "csg/reevaluate.h"
#include "csg/output_check.h"

#include <string.h>

enum { REEVALUATION_ROUNDS = 3 };

static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

/* The context of one round: the caller's allocator, threads and pool, no log or
 * progress of its own (the round is a step of the caller's evaluation), and every
 * shell tested for crossings, which rounding may have made. */
static mci_ctx round_context(const mci_ctx *ctx)
{
    mci_ctx inner = *ctx;
    inner.log = NULL;
    inner.progress = NULL;
    inner.check_self_intersections = 1;
    inner.check_output_crossings = 0; /* the round is checked once, by the caller's rules */
    inner.reevaluation_round = true;
    inner.owns_pool = false;
    return inner;
}

mcsg_status mci_tree_of_one_mesh(const mcsg_options *opts, const mcsg_mesh *mesh,
                                 const char *label, mcsg_tree **out, mcsg_error *err)
{
    mcsg_node_id leaf, root;
    mcsg_status s = mcsg_tree_create(opts, out, err);
    if (s == MCSG_OK)
        s = mcsg_tree_add_leaf(*out, mesh, identity, label, &leaf, err);
    if (s == MCSG_OK)
        s = mcsg_tree_add_op(*out, MCSG_NODE_UNION, &leaf, 1, NULL, &root, err);
    if (s == MCSG_OK)
        s = mcsg_tree_set_root(*out, root, err);
    if (s != MCSG_OK) {
        mcsg_tree_free(*out);
        *out = NULL;
    }
    return s;
}

/* mesh as the only leaf of a union, evaluated: *next, and its per-triangle faces of mesh
 * in *faces when faces is not NULL. */
static mcsg_status evaluate_alone(const mci_ctx *ctx, const mcsg_mesh *mesh, mcsg_mesh *next,
                                  mcsg_provenance **faces, mcsg_eval_stats *st,
                                  mcsg_error *err)
{
    mci_ctx inner = round_context(ctx);
    mcsg_options opts;
    mcsg_tree *tree = NULL;
    mcsg_status s;
    memset(&opts, 0, sizeof opts);
    opts.allocator = ctx->alloc;
    opts.threads = ctx->threads;
    s = mci_tree_of_one_mesh(&opts, mesh, "the rounded result", &tree, err);
    if (s == MCSG_OK)
        s = mci_eval_in_context(tree, &inner, next, faces, st, err);
    mcsg_tree_free(tree);
    return s;
}

/* The sources of the new mesh's triangles: faces[t].face is a triangle of the mesh whose
 * sources are `before`. Rewrites faces in place. */
static void map_provenance(mcsg_provenance *faces, size_t n, const mcsg_provenance *before)
{
    for (size_t t = 0; t < n; t++)
        faces[t] = before[faces[t].face];
}

typedef struct round_state {
    mcsg_mesh mesh;          /* the last round's result (zero before the first) */
    mcsg_provenance *source; /* its triangles' sources in the tree, or NULL */
} round_state;

static void round_state_free(const mci_ctx *ctx, round_state *r)
{
    mci_mesh_free(ctx, &r->mesh);
    mci_free(ctx, r->source);
    memset(r, 0, sizeof *r);
}

/* One round from `from` (mesh and sources): *to, with its sources mapped back to the
 * tree's leaves. A round that fails for any reason but memory (a region whose winding
 * number no ray decides, a leaf refused) is logged and leaves *to empty. */
static mcsg_status one_round(const mci_ctx *ctx, const mcsg_mesh *from,
                             const mcsg_provenance *from_source, bool want_source,
                             round_state *to, mcsg_eval_stats *st, mcsg_error *err)
{
    mcsg_error ignored;
    mcsg_status s = evaluate_alone(ctx, from, &to->mesh, want_source ? &to->source : NULL, st,
                                   &ignored);
    if (s == MCSG_ERR_NOMEM)
        return mci_fail_nomem(err, "evaluating the rounded result again");
    if (s != MCSG_OK) {
        round_state_free(ctx, to);
        mci_log(ctx, MCSG_LOG_INFO, "evaluating the rounded result again failed: %s",
                ignored.message);
        return MCSG_OK;
    }
    if (want_source)
        map_provenance(to->source, to->mesh.triangle_count, from_source);
    return MCSG_OK;
}

/* Whether the round's check passes. Crossings count in it when ctx asks; otherwise a
 * round must at least not add any to the first result's (both counted only here, where
 * rounding broke something: *first_pairs is SIZE_MAX until counted). */
static mcsg_status round_passes(const mci_ctx *ctx, const mcsg_mesh *first, size_t *first_pairs,
                                const mcsg_mesh *mesh, const mcsg_output_check *check,
                                bool *passes, mcsg_error *err)
{
    size_t pairs = 0;
    mcsg_status s = MCSG_OK;
    *passes = !mcsg_output_check_failed(check);
    if (!*passes || ctx->check_output_crossings)
        return MCSG_OK;
    if (*first_pairs == SIZE_MAX)
        s = mci_count_crossings(ctx, first, first_pairs, err);
    if (s == MCSG_OK)
        s = mci_count_crossings(ctx, mesh, &pairs, err);
    *passes = s == MCSG_OK && pairs <= *first_pairs;
    return s;
}

mcsg_status mci_reevaluate_rounded(const mci_ctx *ctx, const double *touching,
                                   size_t touching_count, mcsg_mesh *out,
                                   mcsg_provenance **provenance, mcsg_eval_stats *stats,
                                   mcsg_error *err)
{
    mci_exact_result exact = {NULL, 0, NULL, NULL, touching, touching_count};
    round_state last = {{0}, NULL}, next;
    bool want_source = provenance && *provenance, passes = false;
    size_t first_pairs = SIZE_MAX;
    for (int round = 0; round < REEVALUATION_ROUNDS; round++) {
        mcsg_eval_stats st;
        mcsg_output_check check;
        const mcsg_mesh *from = round == 0 ? out : &last.mesh;
        mcsg_status s;
        memset(&next, 0, sizeof next);
        s = one_round(ctx, from, round == 0 ? (want_source ? *provenance : NULL) : last.source,
                      want_source, &next, &st, err);
        stats->rounding_reevaluations++;
        round_state_free(ctx, &last);
        if (s == MCSG_OK && next.mesh.triangle_count == 0 && out->triangle_count > 0) {
            round_state_free(ctx, &next);
            return MCSG_OK; /* the round failed (or emptied a solid result) */
        }
        if (s == MCSG_OK)
            s = mci_check_output(ctx, &next.mesh, &exact, &check, err);
        if (s == MCSG_OK)
            s = round_passes(ctx, out, &first_pairs, &next.mesh, &check, &passes, err);
        if (s != MCSG_OK) {
            round_state_free(ctx, &next);
            return s;
        }
        last = next;
        if (passes) {
            mci_mesh_free(ctx, out);
            *out = last.mesh;
            if (want_source) {
                mci_free(ctx, *provenance);
                *provenance = last.source;
            }
            stats->output_check = check;
            stats->output_vertices = out->vertex_count;
            stats->output_triangles = out->triangle_count;
            stats->rounding_reevaluation_kept = 1;
            return MCSG_OK;
        }
    }
    round_state_free(ctx, &last);
    return MCSG_OK;
}
