/*
 * mcsg_eval: the whole pipeline, in one pass over the tree (no intermediate result of an
 * inner node is ever built), exact until the output vertices are rounded at the end.
 *
 * The method is Rui Wang, Xudong Jiang, Hongbo Fu, Bin Sheng, Enhua Wu, "Efficient
 * Non-incremental Constructive Solid Geometry Evaluation for Triangular Meshes" (published
 * in Graphical Models 97 (2018) 1-16, doi:10.1016/j.gmod.2018.03.001, under the authors
 * Bin Sheng, Ping Li, Hongbo Fu, Lizhuang Ma, Enhua Wu), cited below by section; meshcsg
 * makes its every decision an exact predicate.
 *
 * Key: stage -> function -> file -> paper. In the order run() calls them.
 *
 *   positive tree, CSGlists   mci_ptree_build             csgtree.c          §5.1, §5.3
 *   input contract            mci_check_leaves            leaf_check.c       -
 *   shells as groups          group_shells                eval.c             -
 *   copies of a leaf          find_copies                 eval.c             -
 *   octree                    mci_octree_build            octree.c           §3.1
 *   candidate pairs           mci_octree_candidate_pairs  octree.c           §3.1, §4.1
 *   pair tests                mci_intersect_pairs         intersect_pairs.c  §4.1
 *     one pair, exactly       mci_triangle_intersection_defined
 *                                                         exact/tri_tri.c    §4.1
 *   faces dropped whole       mci_decide_whole_faces      whole_faces.c      §5.2, §5.3
 *   per-face records          mci_scene_arrange           intersect_arrange.c
 *                                                                            §4.2
 *   splitting at crossings    mci_scene_split             intersect_arrange.c,
 *                                                         arrange.c          §4.2
 *   global point identity     mci_scene_number_points     intersect_numbering.c
 *                                                                            -
 *   tessellation              mci_arr_triangulate         arrange.c,
 *                                                         triangulate.c      §5.4
 *   classification            mci_classify_leaf           classify*.c        §5.2, §5.5
 *     first seeds (rays)      mci_ray_label_octree        rays.c             §5.2, §5.5
 *     across a separator      mci_local_label             local_test.c       Prop. 2
 *     winding numbers         mci_wind_sheet,             classify_winding.c -
 *       (leaves of several    mci_ray_windings_on_plane   rays.c
 *       shells)
 *     trimmed CSGlist         mci_csglist_trim_sparse     csgtree.c          §5.3
 *     output tessellation     mci_arr_retessellate        retessellate.c     §5.4
 *   assembly                  assemble                    eval.c             -
 *     flat vertices removed   mci_remove_flat_vertices    flat_vertices.c    -
 *     rounding                mci_point_round             exact/kernel.c     -
 *     folds and flat ones     mci_cancel_opposite_triangles,
 *                             mci_split_flat_triangles    rounding_repair.c  -
 *     touching parts          mci_split_touching          manifold_split.c   -
 *     void shells             mci_drop_void_shells        void_shells.c      -
 *     copies rounding made    mci_separate_welded_copies  separate_copies.c  -
 *       touch, moved apart
 *     guarantees checked      mci_check_output            output_check.c     -
 *   rounding broke them       mci_reevaluate_rounded      reevaluate.c       -
 *
 * Glossary.
 *   leaf        a mesh of the CSG tree (mcsg_tree), as the user gave it.
 *   primitive   a leaf of the positive tree (differences pushed into complemented
 *               leaves, paper Eq. 4) that the root reaches and that has triangles;
 *               numbered 0 .. n-1. Code says "leaf" for primitive where no confusion
 *               arises.
 *   face        an input triangle of a primitive; global face ids number all faces.
 *   touched     a face that meets another primitive's surface: it gets an
 *               arrangement (mci_face_arr).
 *   LPI, TPI    the two kinds of implicit points: a line (an edge) meeting a plane,
 *               three planes meeting. Points are exact definitions, never coordinates
 *               (docs/exact-arithmetic.md).
 *   piece       a triangle of a touched face's tessellation, or an untouched face.
 *   separator   an elementary edge of an arrangement: it lies on another primitive's
 *               surface, so labels may change across it.
 *   region      the pieces of one primitive joined across every edge that is not a
 *               separator: its labels are constant (the paper's intra-primitive group).
 *   label       where something lies with respect to a primitive: IN, OUT, or on its
 *               surface with the same (SAME) or opposite (OPPO) orientation.
 *   wall        the border of a face dropped whole: a region's labels come only from
 *               its own side of it.
 *   dropped whole   a touched face that the result drops entirely, known from its
 *               labels with respect to the primitives it does not meet: it is neither
 *               split nor tessellated.
 *   copy, stand-in  a primitive whose mesh is the same arrays as an earlier one's: the
 *               earlier one (its stand-in) is evaluated for both.
 */
#include "base/parallel.h"
#include "csg/classify.h"
#include "csg/flat_vertices.h"
#include "csg/frames.h"
#include "csg/leaf_check.h"
#include "csg/manifold_split.h"
#include "csg/output_check.h"
#include "csg/reevaluate.h"
#include "csg/rounding_repair.h"
#include "csg/separate_copies.h"
#include "csg/void_shells.h"
#include "csg/whole_faces.h"
#include "mesh/tree.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct eval_state {
    mci_ctx ctx;
    const mcsg_tree *source; /* the tree evaluated */
    mci_ptree tree;
    uint32_t *alias; /* per primitive: the earlier one it is a copy of, or itself; NULL if
                        no primitive is a copy */
    mci_scene scene;
    mci_classifier cl;
    mci_kept kept;
    mci_trimmed_list *trimmed; /* per primitive, from the whole-face decision */
    mcsg_eval_stats stats;
    bool no_whole_faces; /* split and classify every touched face (the fallback in run) */
    uint32_t *face_group; /* per global face (see mci_octree_params), NULL when no
                             primitive has several shells */
    uint32_t *face_shell; /* the same, NULL unless a shell crosses itself */
    double *touching;     /* where the exact result touches itself (output_check.h) */
    size_t touching_count;
} eval_state;

static void count_faces(const mci_ptree *t, mcsg_eval_stats *st)
{
    st->primitives = t->leaf_count;
    for (size_t l = 0; l < t->leaf_count; l++) {
        size_t n = t->leaf_mesh[l]->triangle_count;
        st->faces += n;
        st->faces_min = l == 0 || n < st->faces_min ? n : st->faces_min;
        st->faces_max = n > st->faces_max ? n : st->faces_max;
    }
}

static mcsg_status triangulate_one(void *user, size_t k, mcsg_error *err)
{
    eval_state *e = user;
    if (e->scene.arr_dropped && e->scene.arr_dropped[k])
        return MCSG_OK; /* dropped whole: no pieces */
    return mci_arr_triangulate(&e->ctx, &e->scene.arrs[k], NULL, err);
}

static uint32_t triangulate_cost(const void *user, size_t k)
{
    const mci_face_arr *arr = &((const eval_state *)user)->scene.arrs[k];
    return (uint32_t)(arr->point_count + arr->edge_count);
}

static mcsg_status triangulate_all(eval_state *e, mcsg_error *err)
{
    double t0 = mci_seconds_now();
    mcsg_status st = mci_parallel_for_heaviest_first(&e->ctx, e->scene.arr_count,
                                                     triangulate_cost, triangulate_one, e, err);
    e->stats.seconds_triangulate = mci_seconds_now() - t0;
    return st;
}

/* Each primitive is classified on its own (it re-tessellates only its own faces), into
 * its own buffer; the buffers are joined in primitive order, as a sequential run would. */
typedef struct leaf_jobs {
    eval_state *e;
    mci_kept *kept;
    mci_classify_stats *stats;
} leaf_jobs;

static mcsg_status classify_one(void *user, size_t leaf, mcsg_error *err)
{
    leaf_jobs *j = user;
    return mci_classify_leaf(&j->e->ctx, &j->e->cl, (uint32_t)leaf, j->kept, &j->stats[leaf],
                             err);
}

/* A leaf's faces, as a rough measure of its classification's work. */
static uint32_t classify_cost(const void *user, size_t leaf)
{
    const leaf_jobs *j = user;
    return (uint32_t)j->e->tree.leaf_mesh[leaf]->triangle_count;
}

static bool join_kept(eval_state *e, const leaf_jobs *j)
{
    size_t total = 0;
    for (size_t l = 0; l < e->tree.leaf_count; l++)
        total += j->kept[l].count;
    e->kept.tris = mci_malloc_array(&e->ctx, 3 * total + 1, sizeof *e->kept.tris);
    e->kept.faces = mci_malloc_array(&e->ctx, total + 1, sizeof *e->kept.faces);
    if (!e->kept.tris || !e->kept.faces)
        return false;
    for (size_t l = 0; l < e->tree.leaf_count; l++) {
        const mci_kept *k = &j->kept[l];
        if (k->count == 0)
            continue; /* its arrays may be NULL */
        memcpy(e->kept.tris + 3 * e->kept.count, k->tris, 3 * k->count * sizeof *k->tris);
        memcpy(e->kept.faces + e->kept.count, k->faces, k->count * sizeof *k->faces);
        e->kept.count += k->count;
    }
    e->kept.capacity = total;
    return true;
}

static void add_classify_stats(mcsg_eval_stats *to, const mci_classify_stats *s)
{
    to->pieces += s->pieces;
    to->regions += s->regions;
    to->rays += s->rays;
    to->local_tests += s->local_tests;
    to->rejected_primitives += s->rejected_leaves;
}

/* The lists the whole-face decision handed on: the classification took what it used. */
static void free_trimmed(eval_state *e)
{
    mci_trimmed_lists_clear(&e->ctx, e->trimmed, e->tree.leaf_count);
    mci_free(&e->ctx, e->trimmed);
    e->trimmed = e->cl.trimmed = NULL;
}

static mcsg_status classify_all(eval_state *e, mcsg_error *err)
{
    double t0 = mci_seconds_now();
    size_t n = e->tree.leaf_count;
    leaf_jobs j = {e, mci_calloc_array(&e->ctx, n + 1, sizeof *j.kept),
                   mci_calloc_array(&e->ctx, n + 1, sizeof *j.stats)};
    mcsg_status st = j.kept && j.stats ? mci_classifier_init(&e->ctx, &e->scene, &e->tree,
                                                             &e->cl, err)
                                       : mci_fail_nomem(err, "classifying faces");
    e->cl.trimmed = e->trimmed;
    if (st == MCSG_OK)
        st = mci_parallel_for_heaviest_first(&e->ctx, n, classify_cost, classify_one, &j, err);
    free_trimmed(e);
    if (st == MCSG_OK && !join_kept(e, &j))
        st = mci_fail_nomem(err, "classifying faces");
    for (size_t l = 0; j.kept && j.stats && l < n; l++) {
        add_classify_stats(&e->stats, &j.stats[l]);
        mci_kept_free(&e->ctx, &j.kept[l]);
    }
    mci_free(&e->ctx, j.kept);
    mci_free(&e->ctx, j.stats);
    e->stats.seconds_classify = mci_seconds_now() - t0;
    return st;
}

/* Coordinates of output vertex id (see mci_classifier), rounded to double. rep[g] names
 * an arrangement point with global number g: (arrangement << 32 | point). */
static void vertex_coordinates(const eval_state *e, const uint64_t *rep, uint32_t id,
                               double *out)
{
    const mci_scene *s = &e->scene;
    if (id >= s->point_count) {
        memcpy(out, e->cl.new_vertex[id - s->point_count], 3 * sizeof *out);
        return;
    }
    mci_point_round(s->arrs[rep[id] >> 32].points[(uint32_t)rep[id]], out);
}

static uint64_t *point_representatives(const eval_state *e)
{
    const mci_scene *s = &e->scene;
    uint64_t *rep = mci_malloc_array(&e->ctx, s->point_count + 1, sizeof *rep);
    if (!rep)
        return NULL;
    for (size_t g = 0; g < s->point_count; g++)
        rep[g] = UINT64_MAX;
    /* The first copy, or the first explicit one: every copy rounds to the same doubles
     * but for the sign of a zero, which only an input vertex's copy knows. */
    for (size_t k = 0; k < s->arr_count; k++)
        for (size_t p = 0, slot = s->gid_start[k]; p < s->arrs[k].point_count; p++, slot++) {
            uint32_t g = s->gid[slot];
            if (rep[g] == UINT64_MAX ||
                (s->explicit_slot[slot] &&
                 !s->explicit_slot[s->gid_start[rep[g] >> 32] + (uint32_t)rep[g]]))
                rep[g] = (uint64_t)k << 32 | p;
        }
    return rep;
}

/* Vertices whose exact positions differ but round to the same doubles (points closer
 * than the rounding error, e.g. where curves cross at a vertex up to the inputs'
 * rounding) are joined, and the triangles this flattens are dropped. */
/* The rounded coordinates of every used vertex, numbered densely in order of use. */
typedef struct rounded {
    uint32_t *dense; /* output vertex id -> dense index */
    double *xyz;
    uint32_t *canon; /* dense index -> first dense index with the same coordinates */
    size_t count;
} rounded;

/* Rounding an exact point costs about a thousand instructions: the used vertices are
 * rounded in chunks of ids on the context's threads (each id writes its own slot). */
enum { ROUND_CHUNK = 8192 };

typedef struct round_job {
    const eval_state *e;
    const uint64_t *rep;
    rounded *r;
} round_job;

static mcsg_status round_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const round_job *j = user;
    (void)err;
    for (size_t id = begin; id < end; id++)
        if (j->r->dense[id] != MCI_NONE)
            vertex_coordinates(j->e, j->rep, (uint32_t)id, j->r->xyz + 3 * (size_t)j->r->dense[id]);
    return MCSG_OK;
}

static mcsg_status round_vertices(const eval_state *e, rounded *r, mcsg_error *err)
{
    size_t ids = e->scene.point_count + e->cl.new_vertex_count;
    uint64_t *rep = point_representatives(e);
    bool ok;
    r->dense = mci_malloc_array(&e->ctx, ids + 1, sizeof *r->dense);
    ok = rep && r->dense;
    for (size_t i = 0; ok && i < ids; i++)
        r->dense[i] = MCI_NONE;
    for (size_t i = 0; ok && i < 3 * e->kept.count; i++)
        if (r->dense[e->kept.tris[i]] == MCI_NONE)
            r->dense[e->kept.tris[i]] = (uint32_t)r->count++;
    r->xyz = ok ? mci_malloc_array(&e->ctx, r->count + 1, 3 * sizeof *r->xyz) : NULL;
    r->canon = ok ? mci_malloc_array(&e->ctx, r->count + 1, sizeof *r->canon) : NULL;
    ok = ok && r->xyz && r->canon;
    if (ok) {
        round_job job = {e, rep, r};
        mcsg_status st =
            mci_parallel_for_ranges(&e->ctx, ids, ROUND_CHUNK, round_chunk, &job, err);
        if (st != MCSG_OK) {
            mci_free(&e->ctx, rep);
            return st;
        }
    }
    ok = ok && mci_first_equal_coordinates(&e->ctx, r->xyz, r->count, r->canon);
    mci_free(&e->ctx, rep);
    return ok ? MCSG_OK : mci_fail_nomem(err, "assembling the result");
}

static void free_rounded(const mci_ctx *ctx, rounded *r)
{
    mci_free(ctx, r->dense);
    mci_free(ctx, r->xyz);
    mci_free(ctx, r->canon);
}

/* How many distinct exact vertices rounding joined into another. */
static size_t joined_count(const rounded *r)
{
    size_t joined = 0;
    for (size_t v = 0; v < r->count; v++)
        joined += r->canon[v] != v;
    return joined;
}

/* Drop the vertices no triangle uses any more (after cancelled triangles), keeping the
 * others in order: new ids never exceed old ones, so the move can be done in place. */
static void drop_unused_vertices(mcsg_mesh *m, uint32_t *map)
{
    size_t nv = 0;
    for (size_t v = 0; v < m->vertex_count; v++)
        map[v] = MCI_NONE;
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        map[m->triangles[i]] = 0;
    for (size_t v = 0; v < m->vertex_count; v++)
        if (map[v] != MCI_NONE) {
            memmove(m->vertices + 3 * nv, m->vertices + 3 * v, 3 * sizeof(double));
            map[v] = (uint32_t)nv++;
        }
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        m->triangles[i] = map[m->triangles[i]];
    m->vertex_count = nv;
}

/* How the exact result's kept triangle `tag` turns (mci_turn_fn): it lies in its face's
 * plane and faces as the face does, or the other way where the face's leaf is
 * complemented. */
static int kept_turn(const void *user, uint32_t tag, int *axis)
{
    const eval_state *e = user;
    const mci_octree *o = &e->scene.octree;
    uint32_t f = e->kept.faces[tag], leaf = o->face_leaf[f];
    int sign = mci_triangle_turn(mci_octree_face_vertex(o, f, 0), mci_octree_face_vertex(o, f, 1),
                                 mci_octree_face_vertex(o, f, 2), axis);
    return e->tree.nodes[e->tree.leaf_node[leaf]].complement ? -sign : sign;
}

/* See rounding_repair.h. Opposite twins only appear where rounding joined vertices
 * (`joined`) or a flat triangle was split; splitting can fold a sliver next to it and
 * cancelling twins can expose flat triangles, so repeat while either changes something.
 * `map` has room for every vertex of out. */
static mcsg_status repair_rounding(eval_state *e, mcsg_mesh *out, uint32_t *which,
                                   uint32_t *map, bool joined, mcsg_error *err)
{
    mci_flat_repair repair = {0, 0, 0, false};
    mci_expected_turns turns = {kept_turn, e};
    size_t split = 0, turned = 0, total_cancelled = 0;
    for (int round = 0; round < 8; round++) {
        size_t cancelled = 0;
        if ((joined && !mci_cancel_opposite_triangles(&e->ctx, out->triangles, which,
                                                      &out->triangle_count, &cancelled)) ||
            !mci_split_flat_triangles(&e->ctx, out->vertices, out->triangles, which,
                                      out->triangle_count, &turns, &repair))
            return mci_fail_nomem(err, "assembling the result");
        total_cancelled += cancelled;
        split += repair.split;
        turned += repair.turned;
        if (cancelled == 0 && repair.split == 0 && repair.turned == 0)
            break;
        /* Twins need joined vertices, a flat triangle split or a fold closing up (in
         * rounds of evaluating again, where folds abound): only then is the sort of every
         * triangle worth it. */
        joined = joined || cancelled > 0 || repair.split > 0 || repair.twins ||
                 e->ctx.reevaluation_round;
    }
    if (total_cancelled > 0)
        drop_unused_vertices(out, map);
    e->stats.rounding_dropped_triangles += total_cancelled;
    e->stats.rounding_split_triangles = split;
    e->stats.rounding_turned_triangles = turned;
    e->stats.rounding_flat_triangles = repair.remaining;
    return MCSG_OK;
}

/* Triangles with three distinct rounded vertices, renumbered by first use, repaired
 * where rounding folded or flattened them; *kept_tri lists the output triangles'
 * indices in e->kept. */
static mcsg_status build_output(eval_state *e, const rounded *r, mcsg_mesh *out,
                                uint32_t **kept_tri, mcsg_error *err)
{
    uint32_t *final = mci_malloc_array(&e->ctx, r->count + 1, sizeof *final);
    uint32_t *tris = mci_malloc_array(&e->ctx, 3 * e->kept.count + 1, sizeof *tris);
    uint32_t *which = mci_malloc_array(&e->ctx, e->kept.count + 1, sizeof *which);
    size_t nt = 0, nv = 0;
    mcsg_status st = final && tris && which ? MCSG_OK : mci_fail_nomem(err, "assembling the result");
    for (size_t v = 0; st == MCSG_OK && v < r->count; v++)
        final[v] = MCI_NONE;
    for (size_t t = 0; st == MCSG_OK && t < e->kept.count; t++) {
        uint32_t c[3];
        for (int i = 0; i < 3; i++)
            c[i] = r->canon[r->dense[e->kept.tris[3 * t + i]]];
        if (c[0] == c[1] || c[1] == c[2] || c[2] == c[0])
            continue;
        for (int i = 0; i < 3; i++) {
            if (final[c[i]] == MCI_NONE)
                final[c[i]] = (uint32_t)nv++;
            tris[3 * nt + i] = final[c[i]];
        }
        which[nt++] = (uint32_t)t;
    }
    if (st == MCSG_OK)
        st = mci_mesh_alloc(&e->ctx, out, nv, nt, err);
    for (size_t v = 0; st == MCSG_OK && v < r->count; v++)
        if (final[v] != MCI_NONE && r->canon[v] == v)
            memcpy(out->vertices + 3 * (size_t)final[v], r->xyz + 3 * v, 3 * sizeof(double));
    if (st == MCSG_OK && nt > 0)
        memcpy(out->triangles, tris, 3 * nt * sizeof *tris);
    e->stats.rounding_dropped_triangles = e->kept.count - nt;
    e->stats.rounding_joined_vertices = joined_count(r);
    if (st == MCSG_OK)
        st = repair_rounding(e, out, which, final, e->stats.rounding_joined_vertices > 0, err);
    mci_free(&e->ctx, final);
    mci_free(&e->ctx, tris);
    if (st == MCSG_OK)
        *kept_tri = which;
    else
        mci_free(&e->ctx, which);
    return st;
}

/* Parts of the result that touch along an edge or at a point get separate vertices. */
static mcsg_status split_touching(eval_state *e, mcsg_mesh *out, mcsg_error *err)
{
    mci_touching_split split;
    if (!mci_split_touching(&e->ctx, out, &split))
        return mci_fail_nomem(err, "assembling the result");
    e->stats.touching_vertices_split = split.new_vertices;
    if (split.unpaired_edges > 0) /* only after rounding moved vertices: leave them */
        mci_log(&e->ctx, MCSG_LOG_WARNING, "%zu edges of the result with more than two "
                "triangles could not be separated after rounding", split.unpaired_edges);
    if (split.reordered_edges > 0)
        mci_log(&e->ctx, MCSG_LOG_INFO, "%zu edges of the result with more than two "
                "triangles were reordered by rounding and paired by their order",
                split.reordered_edges);
    if (split.separated_edges > 0)
        mci_log(&e->ctx, MCSG_LOG_INFO, "%zu edges where parts of the result touch were "
                "paired so that vertex copies separate the parts", split.separated_edges);
    return MCSG_OK;
}

/* Shells that rounding left flat or inside out (see void_shells.c) go, with their tags
 * in kept_tri. */
static mcsg_status drop_void_shells(eval_state *e, mcsg_mesh *out, uint32_t *kept_tri,
                                    mcsg_error *err)
{
    mci_void_shells removed;
    if (!mci_drop_void_shells(&e->ctx, out, kept_tri, &removed))
        return mci_fail_nomem(err, "assembling the result");
    e->stats.rounding_dropped_shells = removed.shells;
    if (removed.shells > removed.folded)
        mci_log(&e->ctx, MCSG_LOG_WARNING, "%zu shells of the result were flat or inside out "
                "after rounding to doubles and were removed", removed.shells - removed.folded);
    if (removed.folded > 0)
        mci_log(&e->ctx, MCSG_LOG_WARNING, "%zu slivers of the result were folded onto "
                "another part by rounding to doubles and were removed", removed.folded);
    if (removed.shells > 0)
        mci_log(&e->ctx, MCSG_LOG_INFO, "the removed shells had %zu triangles",
                removed.triangles);
    return MCSG_OK;
}

/* Where the exact result touches itself (e->touching: edges allowed more than two
 * triangles once welded). */
static mcsg_status list_touching(eval_state *e, const rounded *r, mcsg_error *err)
{
    mci_exact_result exact = {e->kept.tris, e->kept.count, r->dense, r->xyz, NULL, 0};
    if (!mci_list_touching_edges(&e->ctx, &exact, &e->touching, &e->touching_count))
        return mci_fail_nomem(err, "checking the result");
    return MCSG_OK;
}

static mci_exact_result touching_of(const eval_state *e)
{
    if (e->ctx.reevaluation_round)
        return (mci_exact_result){NULL, 0, NULL, NULL, e->ctx.allowed_touching,
                                  e->ctx.allowed_touching_count};
    return (mci_exact_result){NULL, 0, NULL, NULL, e->touching, e->touching_count};
}

/* Parts that rounding made touch along an edge are moved apart (separate_copies.c). */
static mcsg_status separate_copies(eval_state *e, mcsg_mesh *out, mcsg_error *err)
{
    mci_exact_result exact = touching_of(e);
    mci_copy_separation sep;
    if (e->stats.touching_vertices_split == 0) /* no two vertices share coordinates */
        return MCSG_OK;
    if (!mci_separate_welded_copies(&e->ctx, out, &exact, &sep))
        return mci_fail_nomem(err, "assembling the result");
    e->stats.rounding_separated_vertices = sep.moved;
    if (sep.moved > 0)
        mci_log(&e->ctx, MCSG_LOG_INFO, "%zu vertices moved by one unit in the last place to "
                "separate parts that rounding made touch along %zu edges", sep.moved,
                sep.edges);
    return MCSG_OK;
}

/* The result against its guarantees, as the next program sees it (output_check.h). */
static mcsg_status check_output(eval_state *e, const mcsg_mesh *out, mcsg_error *err)
{
    mci_exact_result exact = touching_of(e);
    return mci_check_output(&e->ctx, out, &exact, &e->stats.output_check, err);
}

static mcsg_status fill_provenance(eval_state *e, const uint32_t *kept_tri, size_t n,
                                   mcsg_provenance **provenance, mcsg_error *err)
{
    const mci_octree *o = &e->scene.octree;
    mcsg_provenance *p = mci_malloc_array(&e->ctx, n + 1, sizeof *p);
    if (!p)
        return mci_fail_nomem(err, "assembling the result");
    for (size_t t = 0; t < n; t++) {
        uint32_t f = e->kept.faces[kept_tri[t]], leaf = o->face_leaf[f];
        const uint32_t *face_of = e->tree.leaf_face_of[leaf]; /* zero-area ones removed */
        p[t].leaf = e->tree.leaf_source[leaf];
        p[t].face = face_of ? face_of[f - o->face_base[leaf]] : f - o->face_base[leaf];
    }
    *provenance = p;
    return MCSG_OK;
}

/* What the removal of flat vertices reads: exact points by output vertex id (the
 * arrangements' for the scene's numbers, explicit ones for the leaf vertices
 * classification added), faces' corners and leaves. */
typedef struct flat_points {
    const eval_state *e;
    const uint64_t *rep;
    uint32_t *slot;     /* per leaf vertex added by classification: its point's, or NONE */
    mci_point *added;   /* made on first use: the removal reads few of them */
    size_t added_count;
} flat_points;

static const mci_point *flat_point(void *user, uint32_t id)
{
    flat_points *p = user;
    const mci_scene *s = &p->e->scene;
    uint32_t k = id - (uint32_t)s->point_count;
    if (id < s->point_count)
        return s->arrs[p->rep[id] >> 32].points[(uint32_t)p->rep[id]];
    if (p->slot[k] == MCI_NONE) { /* a slot each: pointers handed out stay valid */
        mci_point_explicit(&p->added[p->added_count], p->e->cl.new_vertex[k]);
        p->slot[k] = (uint32_t)p->added_count++;
    }
    return &p->added[p->slot[k]];
}

static const double *flat_corner(const void *user, uint32_t f, int k)
{
    return mci_octree_face_vertex(&((const flat_points *)user)->e->scene.octree, f, k);
}

static bool flat_complemented(const void *user, uint32_t f)
{
    const eval_state *e = ((const flat_points *)user)->e;
    uint32_t leaf = e->scene.octree.face_leaf[f];
    return e->tree.nodes[e->tree.leaf_node[leaf]].complement;
}

static bool flat_touched(const void *user, uint32_t f)
{
    return ((const flat_points *)user)->e->scene.arr_of[f] != MCI_NONE;
}

static bool flat_own_plane(const void *user, uint32_t f)
{
    const flat_points *p = user;
    uint32_t leaf = p->e->scene.octree.face_leaf[f];
    return !mci_tree_is_made(p->e->source, p->e->tree.leaf_source[leaf]);
}

/* Vertices that carry no shape leave the exact result (flat_vertices.h) unless the
 * options keep them. */
static mcsg_status remove_flat_vertices(eval_state *e, mcsg_error *err)
{
    const mci_scene *s = &e->scene;
    size_t added = e->cl.new_vertex_count;
    flat_points p = {e, NULL, NULL, NULL, 0};
    mci_flat_source src = {flat_point,   flat_corner,    flat_complemented,
                           flat_touched, flat_own_plane, &p,
                           s->point_count + added};
    mci_flat_stats fs;
    mcsg_status st;
    /* a round of evaluating a rounded result again is judged against the first
     * result's touching edges, which its own vertices keep */
    if (e->ctx.keep_all_vertices || e->ctx.reevaluation_round || e->kept.count == 0)
        return MCSG_OK;
    p.rep = point_representatives(e);
    p.slot = mci_malloc_array(&e->ctx, added + 1, sizeof *p.slot);
    p.added = mci_malloc_array(&e->ctx, added + 1, sizeof *p.added); /* untouched: no pages */
    if (!p.rep || !p.slot || !p.added)
        st = mci_fail_nomem(err, "removing flat vertices");
    else {
        memset(p.slot, 0xff, added * sizeof *p.slot);
        st = mci_remove_flat_vertices(&e->ctx, &e->kept, &src, &fs, err);
    }
    if (st == MCSG_OK)
        e->stats.flat_vertices_removed = fs.removed;
    if (st == MCSG_OK && fs.gave_up)
        mci_log(&e->ctx, MCSG_LOG_INFO, "%zu flat vertices kept: removing them would give an "
                "edge more than two triangles where parts of the result touch",
                fs.removable);
    mci_free(&e->ctx, (void *)p.rep);
    mci_free(&e->ctx, p.slot);
    mci_free(&e->ctx, p.added);
    return st;
}

/* The output's smallest angle and its triangles with an angle under 1 degree. A
 * triangle's smallest angle faces its shortest side, and is at most 60 degrees: the
 * square of its sine, the squared cross product of the two other sides over the product
 * of their squared lengths, orders the triangles. */
static void measure_angles(const mcsg_mesh *m, mcsg_eval_stats *stats)
{
    const double sin2_one_degree = 0.017452406437283512 * 0.017452406437283512;
    double smallest = 1;
    size_t needles = 0;
    for (size_t t = 0; t < m->triangle_count; t++) {
        const double *p[3];
        double d[3][3], len[3], cross[3], sine2;
        int shortest = 0;
        for (int i = 0; i < 3; i++)
            p[i] = m->vertices + 3 * (size_t)m->triangles[3 * t + i];
        for (int i = 0; i < 3; i++) {
            for (int k = 0; k < 3; k++)
                d[i][k] = p[(i + 1) % 3][k] - p[i][k];
            len[i] = d[i][0] * d[i][0] + d[i][1] * d[i][1] + d[i][2] * d[i][2];
            shortest = len[i] < len[shortest] ? i : shortest;
        }
        for (int k = 0; k < 3; k++)
            cross[k] = d[0][(k + 1) % 3] * d[1][(k + 2) % 3] -
                       d[0][(k + 2) % 3] * d[1][(k + 1) % 3];
        sine2 = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]) /
                (len[(shortest + 1) % 3] * len[(shortest + 2) % 3]);
        sine2 = sine2 == sine2 ? sine2 : 0; /* 0 / 0: a triangle with coincident corners */
        smallest = sine2 < smallest ? sine2 : smallest;
        needles += sine2 < sin2_one_degree;
    }
    stats->output_smallest_angle =
        m->triangle_count ? asin(sqrt(smallest)) * (180 / 3.14159265358979323846) : 0;
    stats->output_needles = needles;
}

static mcsg_status assemble(eval_state *e, mcsg_mesh *out, mcsg_provenance **provenance,
                            mcsg_error *err)
{
    double t0 = mci_seconds_now();
    rounded r = {NULL, NULL, NULL, 0};
    uint32_t *kept_tri = NULL;
    mcsg_status st = remove_flat_vertices(e, err);
    if (st == MCSG_OK)
        st = round_vertices(e, &r, err);
    /* Once the vertices are rounded, only the kept triangles and the face indexing are
     * read: the arrangements and the octree's cells go before the output is built (the
     * assembly was the peak of the two-model scenes). */
    mci_classifier_free(&e->ctx, &e->cl);
    mci_scene_free_geometry(&e->ctx, &e->scene);
    if (st == MCSG_OK)
        st = build_output(e, &r, out, &kept_tri, err);
    if (st == MCSG_OK)
        st = split_touching(e, out, err);
    if (st == MCSG_OK)
        st = drop_void_shells(e, out, kept_tri, err);
    if (st == MCSG_OK)
        st = list_touching(e, &r, err);
    if (st == MCSG_OK)
        st = separate_copies(e, out, err);
    if (st == MCSG_OK)
        st = check_output(e, out, err);
    if (st == MCSG_OK && provenance)
        st = fill_provenance(e, kept_tri, out->triangle_count, provenance, err);
    if (st == MCSG_OK)
        measure_angles(out, &e->stats);
    if (st != MCSG_OK)
        mci_mesh_free(&e->ctx, out);
    free_rounded(&e->ctx, &r);
    mci_free(&e->ctx, kept_tri);
    e->stats.output_vertices = out->vertex_count;
    e->stats.output_triangles = out->triangle_count;
    e->stats.seconds_assemble = mci_seconds_now() - t0;
    return st;
}

typedef mcsg_status (*step_fn)(eval_state *e, mcsg_error *err);

/* A step between the progress reports that may cancel it (docs of mcsg_progress_fn). */
static mcsg_status step(eval_state *e, const char *name, step_fn fn, mcsg_error *err)
{
    mcsg_status st = mci_progress(&e->ctx, name, 0, err);
    if (st == MCSG_OK)
        st = fn(e, err);
    if (st == MCSG_OK)
        st = mci_progress(&e->ctx, name, 1, err);
    return st;
}

/* Whether two meshes are the same arrays (the same file imported twice in the same
 * place, say): then the earlier one stands for the later in the whole evaluation. */
static bool same_mesh(const mcsg_mesh *a, const mcsg_mesh *b)
{
    /* Empty arrays may be NULL, which memcmp must not see even for 0 bytes. */
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           (a->vertex_count == 0 ||
            memcmp(a->vertices, b->vertices, 3 * a->vertex_count * sizeof *a->vertices) == 0) &&
           (a->triangle_count == 0 ||
            memcmp(a->triangles, b->triangles, 3 * a->triangle_count * sizeof *a->triangles) == 0);
}

typedef struct leaf_ref {
    const mcsg_mesh *mesh;
    uint32_t leaf;
} leaf_ref;

/* By size and first vertex (copies compare equal), then by leaf. */
static int compare_leaf_refs(const void *x, const void *y)
{
    const leaf_ref *p = x, *q = y;
    const mcsg_mesh *a = p->mesh, *b = q->mesh;
    int c;
    if (a->vertex_count != b->vertex_count)
        return a->vertex_count < b->vertex_count ? -1 : 1;
    if (a->triangle_count != b->triangle_count)
        return a->triangle_count < b->triangle_count ? -1 : 1;
    c = a->vertex_count ? memcmp(a->vertices, b->vertices, 3 * sizeof *a->vertices) : 0;
    return c ? c : (p->leaf > q->leaf) - (p->leaf < q->leaf);
}

static bool same_key(const leaf_ref *p, const leaf_ref *q)
{
    leaf_ref a = *p, b = *q;
    a.leaf = b.leaf = 0;
    return compare_leaf_refs(&a, &b) == 0;
}

/* e->alias: each copy points to the first leaf with the same mesh; only meshes of the
 * same size and first vertex are compared in full. Stays NULL when there is no copy. */
static mcsg_status find_copies(eval_state *e, mcsg_error *err)
{
    size_t n = e->tree.leaf_count, copies = 0;
    leaf_ref *order = mci_malloc_array(&e->ctx, n + 1, sizeof *order);
    uint32_t *alias = mci_malloc_array(&e->ctx, n + 1, sizeof *alias);
    if (!order || !alias) {
        mci_free(&e->ctx, order);
        mci_free(&e->ctx, alias);
        return mci_fail_nomem(err, "comparing the leaves");
    }
    for (uint32_t l = 0; l < n; l++) {
        order[l] = (leaf_ref){e->tree.leaf_mesh[l], l};
        alias[l] = l;
    }
    qsort(order, n, sizeof *order, compare_leaf_refs);
    for (size_t i = 1, run = 0; i < n; i++) {
        if (!same_key(&order[i], &order[i - 1]))
            run = i;
        /* Copies share their stand-in's labels, which assume one outward shell. */
        for (size_t j = run; j < i && !e->tree.leaf_winding[order[i].leaf]; j++)
            if (same_mesh(order[i].mesh, order[j].mesh)) {
                alias[order[i].leaf] = alias[order[j].leaf];
                copies++;
                break;
            }
    }
    mci_free(&e->ctx, order);
    if (copies == 0)
        mci_free(&e->ctx, alias);
    else
        e->alias = alias;
    e->stats.copied_primitives = copies;
    return MCSG_OK;
}

/* Whether a primitive with copies has a face in another primitive's surface (a coplanar
 * face). The classification of copies does not combine their labels correctly with such a
 * third coincident surface (differential fuzzing found an extra piece of the shared plane,
 * an edge with four triangles, where evaluating every primitive on its own is right), so
 * those trees are evaluated without copies. */
static mcsg_status copies_meet_coplanar_faces(eval_state *e, bool *meet, mcsg_error *err)
{
    const mci_scene *s = &e->scene;
    size_t n = e->tree.leaf_count;
    uint8_t *has_copies = mci_calloc_array(&e->ctx, n + 1, 1);
    *meet = false;
    if (!has_copies)
        return mci_fail_nomem(err, "comparing the leaves");
    for (size_t l = 0; l < n; l++)
        has_copies[e->alias[l]] |= e->alias[l] != l;
    for (uint32_t f = 0; f < s->face_count && !*meet; f++)
        *meet = s->arr_of[f] != MCI_NONE && (s->arr_contact[s->arr_of[f]] & MCI_CONTACT_COPLANAR) &&
                has_copies[s->octree.face_leaf[f]];
    mci_free(&e->ctx, has_copies);
    return MCSG_OK;
}

/* Face groups when a primitive has several shells: each shell its own group, so that
 * shells of one leaf that cross are intersected like different leaves; in a primitive
 * with a shell that crosses itself, each face its own group, and face_shell says which
 * shell it is on. Faces dropped whole are then not looked for: that decision takes a
 * face's leaf to be clean. */
static mcsg_status group_shells(eval_state *e, mcsg_error *err)
{
    const mci_ptree *t = &e->tree;
    size_t faces = 0, next = t->leaf_count, shells = t->leaf_count;
    bool any = false, crossing = false;
    for (size_t l = 0; l < t->leaf_count; l++) {
        faces += t->leaf_mesh[l]->triangle_count;
        any |= t->leaf_shell[l] != NULL || t->leaf_crossing[l];
        crossing |= t->leaf_crossing[l] != 0;
    }
    if (!any)
        return MCSG_OK;
    if (faces + 2 * t->leaf_count >= UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "too many faces to group (%zu)", faces);
    e->face_group = mci_malloc_array(&e->ctx, faces + 1, sizeof *e->face_group);
    e->face_shell = crossing ? mci_malloc_array(&e->ctx, faces + 1, sizeof *e->face_shell) : NULL;
    if (!e->face_group || (crossing && !e->face_shell))
        return mci_fail_nomem(err, "grouping shells");
    for (size_t l = 0, f = 0; l < t->leaf_count; l++) {
        const uint32_t *shell = t->leaf_shell[l];
        for (size_t k = 0; k < t->leaf_mesh[l]->triangle_count; k++, f++) {
            uint32_t own = shell ? (uint32_t)(shells + shell[k]) : (uint32_t)l;
            e->face_group[f] = t->leaf_crossing[l] ? (uint32_t)(next + k)
                               : shell              ? (uint32_t)(next + shell[k])
                                                    : (uint32_t)l;
            if (crossing)
                e->face_shell[f] = own;
        }
        next += t->leaf_crossing[l] ? t->leaf_mesh[l]->triangle_count
                                    : shell ? t->leaf_shells[l] : 0;
        shells += shell ? t->leaf_shells[l] : 0;
    }
    e->no_whole_faces = true;
    return MCSG_OK;
}

/* The scene of the pair tests and arrangements, through copies where they are safe. */
static mcsg_status build_scene(eval_state *e, mcsg_error *err)
{
    const mcsg_mesh *const *leaves = (const mcsg_mesh *const *)e->tree.leaf_mesh;
    bool coplanar = false;
    mcsg_status st = find_copies(e, err);
    if (st == MCSG_OK && !e->face_group)
        st = group_shells(e, err);
    if (st == MCSG_OK)
        st = mci_scene_build_touched(&e->ctx, leaves, e->tree.leaf_count, e->alias,
                                     e->face_group, e->face_shell, e->tree.leaf_mates,
                                     &e->scene, err);
    if (st == MCSG_OK && e->alias)
        st = copies_meet_coplanar_faces(e, &coplanar, err);
    if (st != MCSG_OK || !coplanar)
        return st;
    mci_scene_free(&e->ctx, &e->scene);
    mci_free(&e->ctx, e->alias);
    e->alias = NULL;
    e->stats.copied_primitives = 0;
    return mci_scene_build_touched(&e->ctx, leaves, e->tree.leaf_count, NULL, e->face_group,
                                   e->face_shell, e->tree.leaf_mates, &e->scene, err);
}

/* Faces that the result drops whole are found from the pair tests, before anything is
 * built for them: their arrangements keep their corners only, and are not split. */
static mcsg_status intersect_step(eval_state *e, mcsg_error *err)
{
    mcsg_status st = build_scene(e, err);
    double t0 = mci_seconds_now();
    if (st == MCSG_OK && !e->no_whole_faces &&
        !(e->trimmed = mci_calloc_array(&e->ctx, e->tree.leaf_count + 1, sizeof *e->trimmed)))
        st = mci_fail_nomem(err, "deciding whole faces");
    if (st == MCSG_OK && !e->no_whole_faces)
        st = mci_decide_whole_faces(&e->ctx, &e->scene, &e->tree, &e->stats.faces_dropped_whole,
                                    e->trimmed, err);
    e->stats.seconds_whole_faces = mci_seconds_now() - t0;
    if (st == MCSG_OK)
        st = mci_scene_arrange(&e->ctx, &e->scene, err);
    if (st == MCSG_OK)
        st = mci_scene_split(&e->ctx, &e->scene, e->scene.arr_dropped, err);
    if (st == MCSG_OK)
        st = mci_scene_number_points(&e->ctx, &e->scene, err);
    e->stats.intersect = e->scene.stats;
    return st;
}

/* Intersection, triangulation and classification. */
static mcsg_status evaluate_faces(eval_state *e, mcsg_error *err)
{
    mcsg_status st = step(e, "intersect", intersect_step, err);
    if (st == MCSG_OK)
        st = step(e, "triangulate", triangulate_all, err);
    if (st == MCSG_OK)
        st = step(e, "classify", classify_all, err);
    return st;
}

/* Faces dropped whole leave walls in their neighbours' regions, and a region's labels
 * come only from its own side of them. Where a degenerate arrangement has a region that
 * then cannot be labelled (no case is known: whole_faces.c keeps the pieces of faces
 * that other surfaces meet along their border or lie in), the faces are evaluated again
 * without that step, as every face was before it existed: slower, never wrong. */
static mcsg_status evaluate_faces_safely(eval_state *e, mcsg_error *err)
{
    mcsg_eval_stats before = e->stats;
    mcsg_status st = evaluate_faces(e, err);
    if (st != MCSG_ERR_INTERNAL || e->stats.faces_dropped_whole == 0)
        return st;
    mci_log(&e->ctx, MCSG_LOG_INFO, "faces dropped whole left a region undecided (%s): "
            "evaluating again with every touched face split", err ? err->message : "");
    mci_classifier_free(&e->ctx, &e->cl);
    mci_kept_free(&e->ctx, &e->kept);
    free_trimmed(e);
    mci_scene_free(&e->ctx, &e->scene);
    mci_free(&e->ctx, e->alias);
    e->alias = NULL;
    e->stats = before;
    e->no_whole_faces = true;
    return evaluate_faces(e, err);
}

/* Everything the faces' evaluation built, freed for another. */
static void free_faces(eval_state *e)
{
    mci_classifier_free(&e->ctx, &e->cl);
    mci_kept_free(&e->ctx, &e->kept);
    free_trimmed(e);
    mci_scene_free(&e->ctx, &e->scene);
    mci_free(&e->ctx, e->alias);
    mci_free(&e->ctx, e->face_group);
    mci_free(&e->ctx, e->face_shell);
    e->alias = NULL;
    e->face_group = e->face_shell = NULL;
}

/* Shells are not tested for crossing themselves up front unless the options ask (it
 * costs about an evaluation). When an internal check trips, they are tested then, and
 * if one crosses itself the faces are evaluated again with that primitive's faces
 * intersected with each other. */
static mcsg_status evaluate_faces_checked(eval_state *e, const mcsg_tree *tree, mcsg_error *err)
{
    mcsg_eval_stats before = e->stats;
    mcsg_status st = evaluate_faces_safely(e, err);
    size_t marked = 0;
    mcsg_error probe;
    if (st != MCSG_ERR_INTERNAL || e->ctx.check_self_intersections)
        return st;
    if (mci_mark_crossing_leaves(&e->ctx, tree, &e->tree, &marked, &probe) != MCSG_OK ||
        marked == 0)
        return st;
    mci_log(&e->ctx, MCSG_LOG_INFO, "%zu primitives cross themselves: evaluating again with "
            "their faces intersected with each other", marked);
    free_faces(e);
    e->stats = before;
    return evaluate_faces_safely(e, err);
}

/* The faces evaluated and the result assembled (with the output check). */
static mcsg_status evaluate_and_assemble(eval_state *e, const mcsg_tree *tree, mcsg_mesh *out,
                                         mcsg_provenance **provenance, mcsg_error *err)
{
    mcsg_status st = evaluate_faces_checked(e, tree, err);
    if (st == MCSG_OK)
        st = mci_progress(&e->ctx, "assemble", 0, err);
    if (st == MCSG_OK)
        st = assemble(e, out, provenance, err);
    if (st == MCSG_OK)
        st = mci_progress(&e->ctx, "assemble", 1, err);
    return st;
}

/* What in the result may come from a shell crossing itself that was not tested (one
 * shell enclosing a positive volume, like every clean leaf): edges open or misoriented,
 * which rounding never makes (it joins vertices and drops what collapses) and clean
 * leaves never give; crossing triangles, when they were counted (rounding can make
 * those too, but testing the leaves then costs less than the count did). NULL: none. */
static const char *flaw_of_untested_leaf(const mcsg_output_check *c)
{
    if (c->open_edges > 0 || c->misoriented_edges > 0)
        return "open";
    return c->crossing_pairs > 0 ? "with crossing triangles" : NULL;
}

/* When the result has such a flaw, the leaves not yet tested are, and if one crosses
 * itself the whole evaluation is done again with its faces intersected with each other:
 * nothing is paid for clean input. `before`: the stats before the faces were evaluated. */
static mcsg_status evaluate_flawed_result_again(eval_state *e, const mcsg_tree *tree,
                                                const mcsg_eval_stats *before, mcsg_mesh *out,
                                                mcsg_provenance **provenance, mcsg_error *err)
{
    const char *flaw = flaw_of_untested_leaf(&e->stats.output_check);
    size_t marked = 0;
    mcsg_status st;
    if (!flaw || e->ctx.check_self_intersections)
        return MCSG_OK;
    st = mci_mark_untested_crossing_leaves(&e->ctx, tree, &e->tree, &marked, err);
    if (st != MCSG_OK || marked == 0)
        return st;
    /* A warning: the first evaluation's warnings, above it, no longer apply. */
    mci_log(&e->ctx, MCSG_LOG_WARNING, "the result came out %s because %zu primitives cross "
            "themselves (--check-inputs finds them first): evaluating again with their faces "
            "intersected with each other; warnings above this line were about the first result",
            flaw, marked);
    mci_mesh_free(&e->ctx, out);
    if (provenance) {
        mci_free(&e->ctx, *provenance);
        *provenance = NULL;
    }
    mci_free(&e->ctx, e->touching);
    e->touching = NULL;
    e->touching_count = 0;
    free_faces(e);
    e->stats = *before;
    return evaluate_and_assemble(e, tree, out, provenance, err);
}

static mcsg_status run(eval_state *e, const mcsg_tree *tree, mcsg_mesh *out,
                       mcsg_provenance **provenance, mcsg_error *err)
{
    double t0 = mci_seconds_now();
    mcsg_eval_stats before;
    mcsg_status st = mci_ptree_build(&e->ctx, tree, &e->tree, err);
    e->source = tree;
    e->stats.seconds_tree = mci_seconds_now() - t0;
    if (st != MCSG_OK)
        return st;
    count_faces(&e->tree, &e->stats);
    if (e->tree.leaf_count == 0)
        return mci_mesh_alloc(&e->ctx, out, 0, 0, err);
    t0 = mci_seconds_now();
    st = mci_progress(&e->ctx, "check", 0, err);
    if (st == MCSG_OK)
        st = mci_check_leaves(&e->ctx, tree, &e->tree, err);
    if (st == MCSG_OK)
        st = mci_progress(&e->ctx, "check", 1, err);
    e->stats.seconds_check = mci_seconds_now() - t0;
    if (st != MCSG_OK)
        return st;
    before = e->stats;
    st = evaluate_and_assemble(e, tree, out, provenance, err);
    if (st == MCSG_OK)
        st = evaluate_flawed_result_again(e, tree, &before, out, provenance, err);
    if (st != MCSG_OK)
        mci_mesh_free(&e->ctx, out);
    /* A round of evaluating a rounded result again only logs why it failed: the
     * explanation, another self-intersection test of the whole mesh, is not worth it. */
    if (st == MCSG_ERR_INTERNAL && !e->ctx.reevaluation_round)
        st = mci_explain_internal_error(&e->ctx, tree, &e->tree, err);
    return st;
}

/* run, then everything it built freed (e->stats stays). */
static mcsg_status evaluate(eval_state *e, const mcsg_tree *tree, mcsg_mesh *out,
                            mcsg_provenance **provenance, mcsg_error *err)
{
    mcsg_status st = run(e, tree, out, provenance, err);
    mci_classifier_free(&e->ctx, &e->cl);
    mci_kept_free(&e->ctx, &e->kept);
    free_trimmed(e);
    mci_scene_free(&e->ctx, &e->scene);
    mci_ptree_free(&e->ctx, &e->tree);
    mci_free(&e->ctx, e->alias);
    mci_free(&e->ctx, e->face_group);
    mci_free(&e->ctx, e->face_shell);
    return st;
}

mcsg_status mci_eval_in_context(const mcsg_tree *tree, const mci_ctx *ctx, mcsg_mesh *out,
                                mcsg_provenance **provenance, mcsg_eval_stats *stats,
                                mcsg_error *err)
{
    eval_state e;
    double t0 = mci_seconds_now();
    mcsg_status st;
    memset(&e, 0, sizeof e);
    e.ctx = *ctx;
    if (provenance)
        *provenance = NULL;
    st = evaluate(&e, tree, out, provenance, err);
    mci_free(&e.ctx, e.touching);
    e.stats.seconds_total = mci_seconds_now() - t0;
    if (stats)
        *stats = e.stats;
    return st;
}

/* The rounded result against its guarantees: where it breaks one, triangles made to
 * cross are moved apart, and (when `rounds`) the rounded result is evaluated again
 * (mci_reevaluate_rounded). The check is logged when it passes or `rounds` was allowed. */
static mcsg_status settle_rounding(eval_state *e, mcsg_mesh *out, mcsg_provenance **provenance,
                                   bool rounds, mcsg_error *err)
{
    double t0 = mci_seconds_now();
    mcsg_status st = MCSG_OK;
    if (!mcsg_output_check_failed(&e->stats.output_check))
        return MCSG_OK;
    st = mci_progress(&e->ctx, "evaluate rounded result again", 0, err);
    if (st == MCSG_OK)
        st = mci_reevaluate_rounded(&e->ctx, e->touching, e->touching_count, rounds, out,
                                    provenance, &e->stats, err);
    if (st == MCSG_OK)
        st = mci_progress(&e->ctx, "evaluate rounded result again", 1, err);
    if (st == MCSG_OK && e->stats.rounding_reevaluation_kept &&
        e->stats.rounding_reevaluations == 0 && e->stats.rounding_snap_grid == 0)
        mci_log(&e->ctx, MCSG_LOG_INFO, "rounding to doubles made triangles cross; corners of "
                "theirs moved by one unit in the last place keep the result's guarantees");
    else if (st == MCSG_OK && e->stats.rounding_reevaluation_kept)
        mci_log(&e->ctx, MCSG_LOG_INFO, "rounding to doubles broke the result's guarantees; "
                "the rounded result, snapped to a grid of spacing %g (0: not snapped) and "
                "evaluated again by its winding number %zu times, keeps them",
                e->stats.rounding_snap_grid, e->stats.rounding_reevaluations);
    if (st == MCSG_OK && (rounds || !mcsg_output_check_failed(&e->stats.output_check)))
        mci_log_output_check(&e->ctx, &e->stats.output_check);
    e->stats.seconds_assemble += mci_seconds_now() - t0;
    return st;
}

/* The evaluation with its rounding settled. A result whose flat vertices were removed
 * and whose rounding still breaks a guarantee once crossing corners are moved apart (its
 * longer edges leave slivers that rounding folds otherwise) is made again with every
 * vertex, and the rounds of evaluating a rounded result again, if it needs them, start
 * from that one, as they were made for. */
static mcsg_status evaluate_settled(eval_state *e, const mcsg_tree *tree, mcsg_mesh *out,
                                    mcsg_provenance **provenance, mcsg_error *err)
{
    mci_ctx ctx = e->ctx;
    mcsg_status st = evaluate(e, tree, out, provenance, err);
    bool lean = e->stats.flat_vertices_removed > 0;
    if (st == MCSG_OK)
        st = settle_rounding(e, out, provenance, !lean, err);
    if (st != MCSG_OK || !lean || !mcsg_output_check_failed(&e->stats.output_check))
        return st;
    mci_log(&e->ctx, MCSG_LOG_INFO, "rounding to doubles broke a guarantee of the result "
            "without its %zu flat vertices: evaluating again with every vertex",
            e->stats.flat_vertices_removed);
    mci_mesh_free(&e->ctx, out);
    if (provenance) {
        mci_free(&e->ctx, *provenance);
        *provenance = NULL;
    }
    mci_free(&e->ctx, e->touching);
    memset(e, 0, sizeof *e);
    e->ctx = ctx;
    e->ctx.keep_all_vertices = 1;
    st = evaluate(e, tree, out, provenance, err);
    if (st == MCSG_OK)
        st = settle_rounding(e, out, provenance, true, err);
    return st;
}

mcsg_status mcsg_eval(const mcsg_tree *tree, const mcsg_options *opts, mcsg_mesh *out,
                      mcsg_provenance **provenance, mcsg_eval_stats *stats, mcsg_error *err)
{
    if (tree && out && mci_tree_frame_count(tree) > 0) {
        memset(out, 0, sizeof *out);
        if (provenance)
            *provenance = NULL;
        return mci_eval_frames(tree, opts, out, provenance, stats, err);
    }
    return mci_eval_flattened(tree, opts, out, provenance, stats, err);
}

mcsg_status mci_eval_flattened(const mcsg_tree *tree, const mcsg_options *opts, mcsg_mesh *out,
                               mcsg_provenance **provenance, mcsg_eval_stats *stats,
                               mcsg_error *err)
{
    eval_state e;
    double t0 = mci_seconds_now();
    mcsg_status st;
    mci_scratch_scope scratch;
    bool scratch_entered;
    memset(&e, 0, sizeof e);
    mci_ctx_init(&e.ctx, opts);
    if (out)
        memset(out, 0, sizeof *out);
    if (provenance)
        *provenance = NULL;
    if (!tree || !out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_eval: NULL %s", tree ? "out" : "tree");
    mci_pool_start(&e.ctx);
    /* One scratch scope for all the loops this thread runs: the exact cache
     * (exact/exact_cache.c) is allocated once per evaluation, not per loop, and the
     * points a step leaves in it may serve the next */
    scratch_entered = mci_scratch_enter(&scratch, &e.ctx.alloc);
    st = evaluate_settled(&e, tree, out, provenance, err);
    if (st != MCSG_OK) {
        mci_mesh_free(&e.ctx, out);
        if (provenance) {
            mci_free(&e.ctx, *provenance);
            *provenance = NULL;
        }
    }
    mci_free(&e.ctx, e.touching);
    mci_scratch_leave(&scratch, scratch_entered);
    mci_pool_stop(&e.ctx);
    e.stats.seconds_total = mci_seconds_now() - t0;
    if (stats)
        *stats = e.stats;
    return st;
}
