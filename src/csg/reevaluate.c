/*
 * Snapping and evaluating the rounded result again (reevaluate.h).
 *
 * Rounding moves each vertex by at most half a unit in the last place, and where the
 * exact result has features thinner than that (a sliver between nearly coplanar faces,
 * vertices closer than the spacing of doubles) the rounded mesh can fold, weld two parts
 * into an edge of four triangles, or cross itself. The rounded mesh is still closed as a
 * chain, so it is a valid leaf: evaluated alone by its winding number (its shells tested
 * for crossings and cut where they cross, coincident faces of opposite orientation
 * cancelled, edges of four triangles paired by angle), its exact result has none of
 * those defects, and only the new intersection vertices are rounded again. Those can
 * break a guarantee in turn where many nearly coincide; snapped to a coarser grid
 * (snap_round.c) they are one point. Each round tries its starting mesh snapped, the
 * snapped mesh evaluated again, and the starting mesh evaluated again; the first whose
 * check passes is kept, and otherwise the first result stays (with its report). A
 * round starts from the last round's evaluation, unless that failed or is no mesh to
 * start from (open, misoriented, inside out, another solid, or with no fewer defects
 * than the first result: rounds that built on such a candidate wandered off, their
 * crossings growing round by round): then from the first result, on the next grid.
 * Every round's evaluation moves apart the parts that touch where the first result's
 * exact result does not: rounding made that contact. Before any round, where the first
 * result's triangles cross, moving their corners by one unit is tried.
 */
#include "csg/reevaluate.h"
#include "csg/output_check.h"
#include "csg/separate_copies.h"
#include "csg/self_intersect.h"
#include "csg/snap_round.h"
#include "mesh/validate.h"

#include <math.h>
#include <string.h>

enum { REEVALUATION_ROUNDS = 5 };

/* The grid each round's starting mesh is snapped to, in bits across the result's largest
 * coordinate (the last: the last round's result): finer first, each grid's points on the
 * next one's coarser grid. */
static const int snap_bits[REEVALUATION_ROUNDS + 1] = {48, 44, 40, 36, 32, 28};

static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

/* The context of one round: the caller's allocator, threads and pool, no log or
 * progress of its own (the round is a step of the caller's evaluation), and every
 * shell tested for crossings, which rounding may have made. */
static mci_ctx round_context(const mci_ctx *ctx, const mci_exact_result *exact)
{
    mci_ctx inner = *ctx;
    inner.allowed_touching = exact->touching;
    inner.allowed_touching_count = exact->touching_count;
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
static mcsg_status evaluate_alone(const mci_ctx *ctx, const mci_exact_result *exact,
                                  const mcsg_mesh *mesh, mcsg_mesh *next,
                                  mcsg_provenance **faces, mcsg_eval_stats *st,
                                  mcsg_error *err)
{
    mci_ctx inner = round_context(ctx, exact);
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
    bool no_start;           /* refused as no round's start: open, misoriented, inside
                                out, not the first result's solid, or with no fewer
                                defects than the first result */
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
static mcsg_status one_round(const mci_ctx *ctx, const mci_exact_result *exact,
                             const mcsg_mesh *from,
                             const mcsg_provenance *from_source, bool want_source,
                             round_state *to, mcsg_eval_stats *st, mcsg_error *err)
{
    mcsg_error ignored;
    mcsg_status s = evaluate_alone(ctx, exact, from, &to->mesh,
                                   want_source ? &to->source : NULL, st, &ignored);
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

/* from (and its sources) snapped to the grid 2^e: *to. */
static mcsg_status snap_round(const mci_ctx *ctx, const mcsg_mesh *from,
                              const mcsg_provenance *from_source, bool want_source, int e,
                              round_state *to, mcsg_error *err)
{
    uint32_t *face_of = NULL;
    mcsg_status s = mci_snap_to_grid(ctx, from, e, &to->mesh, &face_of, err);
    if (s == MCSG_OK && want_source) {
        to->source = mci_malloc_array(ctx, to->mesh.triangle_count + 1, sizeof *to->source);
        if (!to->source)
            s = mci_fail_nomem(err, "snapping the rounded result to a grid");
        for (size_t t = 0; s == MCSG_OK && t < to->mesh.triangle_count; t++)
            to->source[t] = from_source[face_of[t]];
    }
    mci_free(ctx, face_of);
    if (s != MCSG_OK)
        round_state_free(ctx, to);
    return s;
}

/* The touching edges' ends on the grid 2^e (snapping is monotone: still sorted). */
static double *snap_touching(const mci_ctx *ctx, const double *touching, size_t count, int e)
{
    double *snapped = mci_malloc_array(ctx, 6 * count + 1, sizeof *snapped);
    for (size_t i = 0; snapped && i < 6 * count; i++)
        snapped[i] = mci_snap_coordinate(touching[i], e);
    return snapped;
}

/* The size of a mesh's solid, in doubles: its signed volume, the sum of the volume's
 * terms' magnitudes (the scale of its rounding error) and its surface's area. */
typedef struct solid_size {
    double volume, magnitude, area;
} solid_size;

static solid_size size_of(const mcsg_mesh *m)
{
    mci_volume_sum v = {0, 0, 0, 0};
    solid_size z = {0, 0, 0};
    for (size_t t = 0; t < m->triangle_count; t++) {
        const double *a = m->vertices + 3 * (size_t)m->triangles[3 * t],
                     *b = m->vertices + 3 * (size_t)m->triangles[3 * t + 1],
                     *c = m->vertices + 3 * (size_t)m->triangles[3 * t + 2];
        double u[3], w[3], n[3];
        mci_volume_sum_add(&v, a, b, c);
        for (int k = 0; k < 3; k++)
            u[k] = b[k] - a[k], w[k] = c[k] - a[k];
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        z.area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    z.volume = v.sum / 6;
    z.magnitude = v.magnitude / 6;
    return z;
}

/* What the rounds share: the caller's result (replaced by the first candidate that
 * passes), the first result's crossings and size, and how far the rounds so far may
 * have moved the surface. */
typedef struct rounds {
    const mci_ctx *ctx;
    mcsg_mesh *out;
    mcsg_provenance **provenance;
    mcsg_eval_stats *stats;
    bool want_source, kept;
    size_t first_pairs; /* SIZE_MAX until counted */
    solid_size first;
    double moved;       /* a bound on how far any point of a candidate is from the first
                           result's surface */
    const double *touching;
    size_t touching_count;
    size_t most_triangles; /* a round's evaluated mesh beyond this is abandoned */
    size_t first_defects;  /* what the first result's check counts (defects()) */
} rounds;

/* Whether the candidate's volume is the first result's within what moving its surface
 * by r->moved can change (both areas times that distance), plus the sums' rounding. A
 * candidate whose evaluation lost or added a part (a misclassified region of a shell
 * crossing itself) is refused: its check alone would pass it. */
static bool keeps_the_solid(const rounds *r, const mcsg_mesh *candidate)
{
    solid_size c = size_of(candidate);
    double bound = (r->first.area + c.area) * r->moved +
                   0x1p-40 * (r->first.magnitude + c.magnitude);
    return fabs(c.volume - r->first.volume) <= bound;
}

/* Why a candidate is not kept, for --verbose. */
static void log_refused(const mci_ctx *ctx, const round_state *candidate, const char *why)
{
    mci_log(ctx, MCSG_LOG_INFO, "a candidate of %zu triangles is not kept: %s",
            candidate->mesh.triangle_count, why);
}

/* The same for a candidate whose check failed. */
static void log_check_refused(const mci_ctx *ctx, const round_state *candidate,
                              const mcsg_output_check *check)
{
    char what[512];
    mci_describe_output_check(check, what, sizeof what);
    log_refused(ctx, candidate, what[0] ? what : "more crossing triangles");
}

/* Checks candidate; when it passes, it replaces the result (and is emptied). */
static mcsg_status keep_if_it_passes(rounds *r, const mci_exact_result *exact,
                                     round_state *candidate, mcsg_error *err)
{
    mcsg_output_check check;
    bool passes = false;
    mcsg_status s;
    if (candidate->mesh.triangle_count == 0)
        return MCSG_OK; /* a solid result is never kept empty */
    candidate->no_start = true;
    if (!keeps_the_solid(r, &candidate->mesh)) {
        log_refused(r->ctx, candidate, "its volume is not the first result's");
        return MCSG_OK;
    }
    /* Snapping can turn a sliver over: closed and oriented edge by edge, inside out as
     * a whole (the volume bound above is wider than such a sliver). */
    if (mci_triangles_volume_sign(candidate->mesh.vertices, candidate->mesh.triangles, NULL,
                                  candidate->mesh.triangle_count, NULL) < 0) {
        log_refused(r->ctx, candidate, "it is inside out");
        return MCSG_OK;
    }
    s = mci_check_output(r->ctx, &candidate->mesh, exact, &check, err);
    if (s == MCSG_OK) {
        candidate->no_start = check.open_edges > 0 || check.misoriented_edges > 0 ||
                              mci_output_check_defects(&check) >= r->first_defects;
        s = round_passes(r->ctx, r->out, &r->first_pairs, &candidate->mesh, &check, &passes,
                         err);
    }
    if (s == MCSG_OK && !passes)
        log_check_refused(r->ctx, candidate, &check);
    if (s != MCSG_OK || !passes)
        return s;
    mci_mesh_free(r->ctx, r->out);
    *r->out = candidate->mesh;
    if (candidate->source) {
        mci_free(r->ctx, *r->provenance);
        *r->provenance = candidate->source;
    }
    memset(candidate, 0, sizeof *candidate);
    r->stats->output_check = check;
    r->stats->output_vertices = r->out->vertex_count;
    r->stats->output_triangles = r->out->triangle_count;
    r->stats->rounding_reevaluation_kept = 1;
    r->kept = true;
    return MCSG_OK;
}

/* from evaluated alone and rounded: *next, kept when it passes. A mesh that grew to
 * several times the first result is no cleanup of it but a tangle rounding made worse:
 * it is dropped (next empty), before its crossings are counted or it starts a round (a
 * fuzz tree's third round reached 150,000 triangles from 2,750, and a run ran out of
 * memory). */
static mcsg_status evaluate_round(rounds *r, const round_state *from,
                                  const mci_exact_result *exact, round_state *next,
                                  mcsg_error *err)
{
    mcsg_eval_stats st;
    mcsg_status s =
        one_round(r->ctx, exact, &from->mesh, from->source, r->want_source, next, &st, err);
    r->stats->rounding_reevaluations++;
    if (s == MCSG_OK && next->mesh.triangle_count > r->most_triangles) {
        mci_log(r->ctx, MCSG_LOG_INFO, "evaluating the rounded result again gave %zu "
                "triangles from %zu: abandoned", next->mesh.triangle_count,
                r->out->triangle_count);
        round_state_free(r->ctx, next);
    }
    if (s == MCSG_OK)
        s = keep_if_it_passes(r, exact, next, err);
    if (s == MCSG_OK && next->no_start)
        round_state_free(r->ctx, next);
    return s;
}

/* One round, each step kept if it passes: from snapped to the grid 2^e; when evaluate,
 * the snapped mesh evaluated alone and rounded, then, when evaluate_from, from itself
 * (candidates that snapping loses). *next: the last evaluation, for the next round
 * (empty when both failed). */
static mcsg_status snap_and_evaluate(rounds *r, const round_state *from, int e, bool evaluate,
                                     bool evaluate_from, round_state *next, mcsg_error *err)
{
    double *ends = snap_touching(r->ctx, r->touching, r->touching_count, e);
    mci_exact_result snapped_exact = {NULL, 0, NULL, NULL, ends, r->touching_count};
    mci_exact_result exact = {NULL, 0, NULL, NULL, r->touching, r->touching_count};
    round_state snapped = {{0}, NULL, false}, from_snapped = {{0}, NULL, false};
    mcsg_status s = ends ? snap_round(r->ctx, &from->mesh, from->source, r->want_source, e,
                                      &snapped, err)
                         : mci_fail_nomem(err, "snapping the rounded result to a grid");
    memset(next, 0, sizeof *next);
    r->moved += 2 * ldexp(1.0, e); /* half the grid's diagonal, and more */
    if (s == MCSG_OK)
        s = keep_if_it_passes(r, &snapped_exact, &snapped, err);
    if (s == MCSG_OK && !r->kept && evaluate && snapped.mesh.triangle_count > 0)
        s = evaluate_round(r, &snapped, &snapped_exact, &from_snapped, err);
    if (s == MCSG_OK && r->kept)
        r->stats->rounding_snap_grid = ldexp(1.0, e);
    if (s == MCSG_OK && !r->kept && evaluate && evaluate_from)
        s = evaluate_round(r, from, &exact, next, err);
    if (s == MCSG_OK && next->mesh.triangle_count == 0) {
        round_state_free(r->ctx, next);
        *next = from_snapped;
    } else {
        round_state_free(r->ctx, &from_snapped);
    }
    round_state_free(r->ctx, &snapped);
    mci_free(r->ctx, ends);
    return s;
}

/* The first candidate, nearest the exact result: where the first result's triangles
 * cross or touch, their corners moved by one unit in the last place
 * (separate_copies.c), when that mends every crossing pair. */
static mcsg_status move_crossing_corners(rounds *r, mcsg_error *err)
{
    const mci_ctx *ctx = r->ctx;
    mci_exact_result exact = {NULL, 0, NULL, NULL, r->touching, r->touching_count};
    round_state moved = {{0}, NULL, false};
    uint64_t *pairs = NULL;
    size_t n = 0, count = 0, nv = r->out->vertex_count, nt = r->out->triangle_count;
    mcsg_status s = mci_crossing_pairs(ctx, r->out, &pairs, &n, err);
    if (s == MCSG_OK && n > 0)
        s = mci_mesh_alloc(ctx, &moved.mesh, nv, nt, err);
    if (s == MCSG_OK && n > 0) {
        memcpy(moved.mesh.vertices, r->out->vertices, 3 * nv * sizeof(double));
        memcpy(moved.mesh.triangles, r->out->triangles, 3 * nt * sizeof(uint32_t));
        if (!mci_separate_crossing_corners(ctx, &moved.mesh, pairs, n, &count))
            s = mci_fail_nomem(err, "moving the corners of crossing triangles");
    }
    if (s == MCSG_OK && count > 0 && r->want_source) {
        moved.source = mci_malloc_array(ctx, nt + 1, sizeof *moved.source);
        if (moved.source)
            memcpy(moved.source, *r->provenance, nt * sizeof *moved.source);
        else
            s = mci_fail_nomem(err, "moving the corners of crossing triangles");
    }
    if (s == MCSG_OK && count > 0)
        s = keep_if_it_passes(r, &exact, &moved, err);
    if (s == MCSG_OK && r->kept)
        r->stats->rounding_separated_vertices += count;
    round_state_free(ctx, &moved);
    mci_free(ctx, pairs);
    return s;
}

mcsg_status mci_reevaluate_rounded(const mci_ctx *ctx, const double *touching,
                                   size_t touching_count, bool allow_rounds,
                                   mcsg_mesh *out, mcsg_provenance **provenance,
                                   mcsg_eval_stats *stats,
                                   mcsg_error *err)
{
    int top = mci_snap_exponent(out, 0);
    rounds r = {ctx, out, provenance, stats, provenance && *provenance, false, SIZE_MAX,
                size_of(out), ldexp(1.0, top - 48), touching, touching_count,
                4 * out->triangle_count + 1000, mci_output_check_defects(&stats->output_check)};
    round_state last = {{0}, NULL, false}, next;
    mcsg_status s = MCSG_OK;
    if (stats->output_check.crossing_pairs > 0)
        s = move_crossing_corners(&r, err);
    for (int round = 0;
         s == MCSG_OK && allow_rounds && !r.kept && round <= REEVALUATION_ROUNDS; round++) {
        round_state first = {*out, r.want_source ? *provenance : NULL, false};
        /* Where the last round left no start (its evaluations failed or were refused as
         * starts), the next grid is tried on the first result: coarser, it may join what
         * the finer one left apart. */
        const round_state *from = last.mesh.triangle_count > 0 ? &last : &first;
        s = snap_and_evaluate(&r, from, top - snap_bits[round], round < REEVALUATION_ROUNDS,
                              round == 0 || from == &last, &next, err);
        round_state_free(ctx, &last);
        last = next;
    }
    round_state_free(ctx, &last);
    return s;
}
