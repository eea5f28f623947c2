/*
 * The intersection stage over a whole scene (see intersect.h): octree (paper §3.1),
 * candidate pairs (§3.2), exact triangle-triangle intersection of each pair once (§4.1,
 * intersect_pairs.c), per-face records turned into arrangements (§4.2,
 * intersect_arrange.c), and one number per distinct point over the whole scene
 * (intersect_numbering.c). This file runs the steps, frees the scene, and gives the
 * public mcsg_intersect its curves.
 */
#include "base/parallel.h"
#include "base/sort.h"
#include "csg/intersect_internal.h"

#include <stdlib.h>
#include <string.h>

static mcsg_status intersect_scene(const mci_ctx *ctx, mci_scene *s, mcsg_error *err)
{
    uint64_t *pairs = NULL;
    size_t count = 0;
    mci_hit_list hits = {NULL, 0, 0, NULL, 0, 0};
    mci_plane_cache planes = {NULL, NULL};
    double t0 = mci_seconds_now(), t1, t2;
    mcsg_status st = mci_octree_candidate_pairs(ctx, &s->octree, &pairs, &count, err);
    mci_octree_free_boxes(ctx, &s->octree);
    if (st != MCSG_OK)
        return st;
    t1 = mci_seconds_now();
    s->stats.candidate_pairs = count;
    st = mci_intersect_pairs(ctx, s, pairs, count, &planes, &hits, err);
    mci_free(ctx, pairs);
    t2 = mci_seconds_now();
    if (st == MCSG_OK)
        st = mci_scene_build_neighbours(ctx, s, &hits, err);
    if (st == MCSG_OK)
        st = mci_scene_prepare_arrangements(ctx, s, &hits, &planes, err);
    mci_hit_list_free(ctx, &hits);
    mci_plane_cache_free(ctx, &planes);
    s->stats.seconds_pairs = t1 - t0;
    s->stats.seconds_intersect = t2 - t1;
    s->stats.seconds_arrange = mci_seconds_now() - t2;
    s->stats.arranged_faces = s->arr_count;
    return st;
}

mcsg_status mci_scene_build(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                            size_t leaf_count, mci_scene *scene, mcsg_error *err)
{
    mcsg_status st = mci_scene_build_touched(ctx, leaves, leaf_count, NULL, NULL, NULL, NULL,
                                             scene, err);
    if (st != MCSG_OK)
        return st;
    st = mci_scene_arrange(ctx, scene, err);
    if (st == MCSG_OK)
        st = mci_scene_split(ctx, scene, NULL, err);
    if (st != MCSG_OK)
        mci_scene_free(ctx, scene);
    return st;
}

mcsg_status mci_scene_build_touched(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                                    size_t leaf_count, const uint32_t *alias,
                                    const uint32_t *face_group, const uint32_t *face_shell,
                                    const mci_edge_mates *leaf_mates, mci_scene *scene,
                                    mcsg_error *err)
{
    double t0 = mci_seconds_now();
    mci_octree_params params = {0, 0, NULL, face_group, face_shell};
    uint8_t *skip = NULL;
    mcsg_status st;
    memset(scene, 0, sizeof *scene);
    scene->alias = alias;
    scene->leaf_mates = leaf_mates;
    if (alias) {
        if (!(skip = mci_malloc_array(ctx, leaf_count + 1, 1)))
            return mci_fail_nomem(err, "building the octree");
        for (size_t l = 0; l < leaf_count; l++)
            skip[l] = alias[l] != l;
    }
    params.skip_leaf = skip;
    st = mci_octree_build(ctx, leaves, leaf_count, alias || face_group ? &params : NULL,
                          &scene->octree, err);
    mci_free(ctx, skip);
    if (st != MCSG_OK)
        return st;
    scene->stats.seconds_octree = mci_seconds_now() - t0;
    scene->face_count = scene->octree.face_base[scene->octree.leaf_count];
    scene->stats.faces = scene->face_count;
    scene->stats.cells = scene->octree.cell_count;
    scene->stats.critical_cells = scene->octree.critical_leaf_cells;
    st = intersect_scene(ctx, scene, err);
    if (st != MCSG_OK)
        mci_scene_free(ctx, scene);
    return st;
}

void mci_scene_free_geometry(const mci_ctx *ctx, mci_scene *scene)
{
    for (size_t k = 0; scene->arrs && k < scene->arr_count; k++)
        mci_arr_free(ctx, &scene->arrs[k]);
    mci_free(ctx, scene->arrs);
    mci_free(ctx, scene->arr_of);
    mci_free(ctx, scene->neighbour);
    mci_free(ctx, scene->gid_start);
    mci_free(ctx, scene->gid);
    mci_free(ctx, scene->explicit_slot);
    mci_point_values_free(&scene->values);
    mci_free(ctx, scene->touch_start);
    mci_free(ctx, scene->touch_leaf);
    mci_free(ctx, scene->arr_dropped);
    mci_free(ctx, scene->arr_contact);
    mci_scene_free_pending(ctx, scene);
    mci_free_point_blocks(ctx, scene->hit_blocks, scene->hit_block_count);
    mci_free(ctx, scene->vertex_points);
    scene->hit_blocks = NULL;
    scene->hit_block_count = 0;
    scene->vertex_points = NULL;
    scene->arrs = NULL;
    scene->arr_of = scene->neighbour = scene->gid_start = scene->gid = NULL;
    scene->explicit_slot = scene->arr_dropped = scene->arr_contact = NULL;
    scene->touch_start = scene->touch_leaf = NULL;
    scene->arr_count = scene->point_count = 0;
    mci_octree_free_cells(ctx, &scene->octree);
}

void mci_scene_free(const mci_ctx *ctx, mci_scene *scene)
{
    mci_scene_free_geometry(ctx, scene);
    mci_octree_free(ctx, &scene->octree);
    memset(scene, 0, sizeof *scene);
}

/* ---------------------------------------------------------------------------------- */
/* Public entry: the curves                                                            */

/* Every elementary edge of every arrangement, once (both faces along a curve have it). */
static uint64_t *curve_edges(const mci_ctx *ctx, const mci_scene *s, size_t *count)
{
    size_t n = 0;
    uint64_t *keys;
    for (size_t k = 0; k < s->arr_count; k++)
        n += s->arrs[k].edge_count;
    keys = mci_malloc_array(ctx, n + 1, sizeof *keys);
    if (!keys)
        return NULL;
    for (size_t k = 0, i = 0; k < s->arr_count; k++) {
        const uint32_t *gid = s->gid + s->gid_start[k];
        for (size_t e = 0; e < s->arrs[k].edge_count; e++) {
            uint64_t a = gid[s->arrs[k].edges[e].a], b = gid[s->arrs[k].edges[e].b];
            keys[i++] = a < b ? a << 32 | b : b << 32 | a;
        }
    }
    mci_sort_u64(keys, n);
    *count = mci_unique_u64(keys, n);
    return keys;
}

/* Renumber the points the curves use, densely (corners off the curves are left out). */
static size_t compact_points(const mci_scene *s, const uint64_t *keys, size_t count,
                             uint32_t *new_id)
{
    size_t used = 0;
    for (size_t i = 0; i < s->point_count; i++)
        new_id[i] = MCI_NONE;
    for (size_t i = 0; i < 2 * count; i++) {
        uint32_t g = (uint32_t)(i % 2 ? keys[i / 2] : keys[i / 2] >> 32);
        if (new_id[g] == MCI_NONE)
            new_id[g] = (uint32_t)used++;
    }
    return used;
}

static mcsg_status export_curves(const mci_ctx *ctx, const mci_scene *s, mcsg_curves *out,
                                 mcsg_error *err)
{
    size_t count = 0, used = 0;
    uint64_t *keys = curve_edges(ctx, s, &count);
    uint32_t *new_id = mci_malloc_array(ctx, s->point_count + 1, sizeof *new_id);
    if (keys && new_id)
        used = compact_points(s, keys, count, new_id);
    out->points = mci_malloc_array(ctx, used + 1, 3 * sizeof(double));
    out->segments = mci_malloc_array(ctx, 2 * count + 1, sizeof(uint32_t));
    if (!keys || !new_id || !out->points || !out->segments) {
        mci_free(ctx, keys);
        mci_free(ctx, new_id);
        mci_free(ctx, out->points);
        mci_free(ctx, out->segments);
        memset(out, 0, sizeof *out);
        return mci_fail_nomem(err, "collecting the curves");
    }
    for (size_t k = 0; k < s->arr_count; k++)
        for (size_t p = 0; p < s->arrs[k].point_count; p++) {
            uint32_t id = new_id[s->gid[s->gid_start[k] + p]];
            if (id != MCI_NONE)
                mci_point_round(s->arrs[k].points[p], out->points + 3 * (size_t)id);
        }
    for (size_t i = 0; i < count; i++) {
        out->segments[2 * i] = new_id[keys[i] >> 32];
        out->segments[2 * i + 1] = new_id[(uint32_t)keys[i]];
    }
    out->point_count = used;
    out->segment_count = count;
    mci_free(ctx, keys);
    mci_free(ctx, new_id);
    return MCSG_OK;
}

static size_t collect_leaves(const mcsg_tree *tree, const mcsg_mesh **leaves)
{
    size_t n = 0;
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++) {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(tree, id);
        if (m && m->triangle_count > 0)
            leaves[n++] = m;
    }
    return n;
}

mcsg_status mcsg_intersect(const mcsg_tree *tree, const mcsg_options *opts, mcsg_curves *out,
                           mcsg_intersect_stats *stats, mcsg_error *err)
{
    mci_ctx ctx;
    mci_scene scene;
    const mcsg_mesh **leaves;
    mcsg_status st;
    mci_ctx_init(&ctx, opts);
    memset(out, 0, sizeof *out);
    memset(&scene, 0, sizeof scene);
    if (!tree)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_intersect: NULL tree");
    leaves = mci_malloc_array(&ctx, mcsg_tree_node_count(tree) + 1, sizeof *leaves);
    if (!leaves)
        return mci_fail_nomem(err, "intersecting faces");
    mci_pool_start(&ctx);
    st = mci_progress(&ctx, "intersect", 0, err);
    if (st == MCSG_OK)
        st = mci_scene_build(&ctx, leaves, collect_leaves(tree, leaves), &scene, err);
    if (st == MCSG_OK)
        st = mci_scene_number_points(&ctx, &scene, err);
    if (st == MCSG_OK)
        st = mci_progress(&ctx, "intersect", 1, err);
    if (st == MCSG_OK)
        st = export_curves(&ctx, &scene, out, err);
    if (stats)
        *stats = scene.stats;
    mci_scene_free(&ctx, &scene);
    mci_free(&ctx, leaves);
    mci_pool_stop(&ctx);
    return st;
}

void mcsg_curves_free(mcsg_curves *curves, const mcsg_options *opts)
{
    mci_ctx ctx;
    if (!curves)
        return;
    mci_ctx_init(&ctx, opts);
    mci_free(&ctx, curves->points);
    mci_free(&ctx, curves->segments);
    memset(curves, 0, sizeof *curves);
}
