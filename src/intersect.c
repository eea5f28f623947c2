/*
 * The intersection stage over a whole scene (paper §3.2, §4): octree, candidate pairs,
 * exact triangle-triangle intersection of each pair once, and exact merging of
 * coincident points (sorting by the exact lexicographic order, so that one geometric
 * point becomes one vertex whatever faces and definitions produced it).
 */
#include "intersect.h"
#include "octree.h"

#include <string.h>
#include <time.h>

typedef struct scene_curves {
    const mci_ctx *ctx;
    mci_point *points; /* segment ends before merging: 2 per segment */
    size_t point_count, point_capacity;
    mcsg_intersect_stats stats;
} scene_curves;

static double seconds_now(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static bool push_segment(scene_curves *c, const mci_point *a, const mci_point *b)
{
    if (c->point_count + 2 > c->point_capacity) {
        size_t cap = c->point_capacity ? 2 * c->point_capacity : 1024;
        mci_point *grown = mci_realloc_array(c->ctx, c->points, cap, sizeof *grown);
        if (!grown)
            return false;
        c->points = grown;
        c->point_capacity = cap;
    }
    c->points[c->point_count++] = *a;
    c->points[c->point_count++] = *b;
    return true;
}

static void face_plane(const mci_octree *t, uint32_t f, mci_plane *plane)
{
    mci_plane_init(plane, mci_octree_face_vertex(t, f, 0), mci_octree_face_vertex(t, f, 1),
                   mci_octree_face_vertex(t, f, 2));
}

static bool intersect_pairs(scene_curves *c, const mci_octree *t, const uint64_t *pairs,
                            size_t count)
{
    for (size_t i = 0; i < count; i++) {
        mci_plane p1, p2;
        mci_tt_result r;
        face_plane(t, (uint32_t)(pairs[i] >> 32), &p1);
        face_plane(t, (uint32_t)pairs[i], &p2);
        mci_triangle_intersection(&p1, &p2, &r);
        if (r.kind == MCI_TT_SEGMENT) {
            c->stats.intersecting_pairs++;
            if (!push_segment(c, &r.end[0], &r.end[1]))
                return false;
        }
        c->stats.point_contacts += r.kind == MCI_TT_POINT;
        c->stats.coplanar_pairs += r.kind == MCI_TT_COPLANAR && r.overlap;
    }
    return true;
}

/* Merge sort of point indices by the exact lexicographic order (C11 has no qsort with
 * a context argument). */
static void sort_by_position(const mci_point *points, uint32_t *idx, uint32_t *tmp, size_t n)
{
    for (size_t width = 1; width < n; width *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * width) {
            size_t mid = lo + width < n ? lo + width : n;
            size_t hi = lo + 2 * width < n ? lo + 2 * width : n;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi)
                tmp[k++] = mci_compare_lex(&points[idx[j]], &points[idx[i]]) < 0 ? idx[j++]
                                                                                : idx[i++];
            while (i < mid)
                tmp[k++] = idx[i++];
            while (j < hi)
                tmp[k++] = idx[j++];
        }
        memcpy(idx, tmp, n * sizeof *idx);
    }
}

/* Number the distinct points; out->segments refer to them. */
static bool merge_points(scene_curves *c, mcsg_curves *out)
{
    size_t n = c->point_count, unique = 0;
    uint32_t *idx = mci_malloc_array(c->ctx, n, sizeof *idx);
    uint32_t *tmp = mci_malloc_array(c->ctx, n, sizeof *tmp);
    uint32_t *id = mci_malloc_array(c->ctx, n, sizeof *id);
    bool ok = idx && tmp && id;
    for (size_t i = 0; ok && i < n; i++)
        idx[i] = (uint32_t)i;
    if (ok)
        sort_by_position(c->points, idx, tmp, n);
    for (size_t i = 0; ok && i < n; i++) {
        if (i > 0 && !mci_points_equal(&c->points[idx[i]], &c->points[idx[i - 1]]))
            unique++;
        id[idx[i]] = (uint32_t)unique;
    }
    unique += n > 0;
    out->points = ok ? mci_malloc_array(c->ctx, unique, 3 * sizeof(double)) : NULL;
    out->segments = ok ? mci_malloc_array(c->ctx, n, sizeof(uint32_t)) : NULL;
    ok = ok && out->points && out->segments;
    for (size_t i = 0; ok && i < n; i++) {
        out->segments[i] = id[i];
        mci_point_approx(&c->points[i], out->points + 3 * (size_t)id[i]);
    }
    if (!ok) {
        mci_free(c->ctx, out->points);
        mci_free(c->ctx, out->segments);
        out->points = NULL;
        out->segments = NULL;
    }
    out->point_count = ok ? unique : 0;
    out->segment_count = ok ? n / 2 : 0;
    mci_free(c->ctx, idx);
    mci_free(c->ctx, tmp);
    mci_free(c->ctx, id);
    return ok;
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

static mcsg_status run_stages(scene_curves *c, const mci_octree *t, mcsg_curves *out,
                              mcsg_error *err)
{
    uint64_t *pairs = NULL;
    size_t count = 0;
    double t0 = seconds_now(), t1, t2;
    mcsg_status st = mci_octree_candidate_pairs(c->ctx, t, &pairs, &count, err);
    if (st != MCSG_OK)
        return st;
    t1 = seconds_now();
    c->stats.candidate_pairs = count;
    if (!intersect_pairs(c, t, pairs, count) || (t2 = seconds_now(), !merge_points(c, out))) {
        mci_free(c->ctx, pairs);
        return mci_fail_nomem(err, "intersecting faces");
    }
    c->stats.seconds_pairs = t1 - t0;
    c->stats.seconds_intersect = t2 - t1;
    c->stats.seconds_merge = seconds_now() - t2;
    mci_free(c->ctx, pairs);
    return MCSG_OK;
}

mcsg_status mcsg_intersect(const mcsg_tree *tree, const mcsg_options *opts, mcsg_curves *out,
                           mcsg_intersect_stats *stats, mcsg_error *err)
{
    mci_ctx ctx;
    scene_curves c;
    mci_octree octree;
    const mcsg_mesh **leaves;
    mcsg_status st;
    double t0;
    mci_ctx_init(&ctx, opts);
    memset(out, 0, sizeof *out);
    memset(&c, 0, sizeof c);
    c.ctx = &ctx;
    if (!tree)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_intersect: NULL tree");
    leaves = mci_malloc_array(&ctx, mcsg_tree_node_count(tree) + 1, sizeof *leaves);
    if (!leaves)
        return mci_fail_nomem(err, "intersecting faces");
    t0 = seconds_now();
    st = mci_octree_build(&ctx, leaves, collect_leaves(tree, leaves), NULL, &octree, err);
    if (st == MCSG_OK) {
        c.stats.seconds_octree = seconds_now() - t0;
        c.stats.faces = octree.face_base[octree.leaf_count];
        c.stats.cells = octree.cell_count;
        c.stats.critical_cells = octree.critical_leaf_cells;
        st = run_stages(&c, &octree, out, err);
        mci_octree_free(&ctx, &octree);
    }
    mci_free(&ctx, c.points);
    mci_free(&ctx, leaves);
    if (stats)
        *stats = c.stats;
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
