/*
 * Exact self-intersection test of a triangle mesh (mcsg_mesh_self_intersections): every
 * pair of triangles whose closed sets meet anywhere other than in the vertices and edge
 * they share is reported. Candidate pairs come from the octree of the intersection
 * stage, built over the mesh given twice (its pairs across the two copies are exactly
 * the pairs of the mesh, both ways round and each triangle with itself; the smaller
 * index first is kept); each candidate is decided by the exact triangle-triangle
 * intersection (exact/tri_tri.c). Vertices are identified by coordinates, as in
 * mcsg_mesh_check:
 *   no common vertex    any contact is an intersection (touching at a point included);
 *   one common vertex   they may meet only there: a segment, or overlapping interiors
 *                       in one plane, is an intersection;
 *   a common edge       in one plane with overlapping interiors (folded onto each other)
 *                       is an intersection; otherwise they meet exactly in the edge;
 *   three               a repeated triangle: an intersection.
 * Zero-area triangles have no plane and are skipped (mcsg_mesh_check reports them).
 * Not detected: coplanar triangles with one common vertex whose edges overlap along a
 * segment while their interiors stay apart.
 */
#include "csg/self_intersect.h"
#include "csg/octree.h"
#include "exact/predicates.h"
#include "exact/tri_tri.h"

#include <string.h>

static bool same_point(const double *p, const double *q)
{
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

static const double *vertex(const mcsg_mesh *m, uint32_t t, int k)
{
    return m->vertices + 3 * (size_t)m->triangles[3 * (size_t)t + k];
}

static int common_vertices(const mcsg_mesh *m, uint32_t s, uint32_t t)
{
    int n = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            n += same_point(vertex(m, s, i), vertex(m, t, j));
    return n;
}

/* x between a and b (inclusive) along axis k, for explicit points. */
static bool between(const double *a, const double *b, const double *x, int k)
{
    return (a[k] <= x[k] && x[k] <= b[k]) || (b[k] <= x[k] && x[k] <= a[k]);
}

/* Whether the closed segments pq and rs meet, all four points in one plane, seen along
 * `axis` (the plane's projection axis: the projection is one to one). */
static bool segments_meet(const double *p, const double *q, const double *r, const double *s,
                          int axis)
{
    mci_point P, Q, R, S;
    int i = (axis + 1) % 3, j = (axis + 2) % 3, o1, o2, o3, o4;
    mci_point_explicit(&P, p);
    mci_point_explicit(&Q, q);
    mci_point_explicit(&R, r);
    mci_point_explicit(&S, s);
    o1 = mci_orient2d_projected(&P, &Q, &R, axis);
    o2 = mci_orient2d_projected(&P, &Q, &S, axis);
    o3 = mci_orient2d_projected(&R, &S, &P, axis);
    o4 = mci_orient2d_projected(&R, &S, &Q, axis);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return true;
    return (o1 == 0 && between(p, q, r, i) && between(p, q, r, j)) ||
           (o2 == 0 && between(p, q, s, i) && between(p, q, s, j)) ||
           (o3 == 0 && between(r, s, p, i) && between(r, s, p, j)) ||
           (o4 == 0 && between(r, s, q, i) && between(r, s, q, j));
}

/* Coplanar triangles with disjoint interiors touch when two of their edges meet. */
static bool coplanar_boundaries_meet(const double *const a[3], const double *const b[3],
                                     const mci_plane *plane)
{
    int sign, axis = mci_plane_projection_axis(plane, &sign);
    for (int e = 0; e < 3; e++)
        for (int f = 0; f < 3; f++)
            if (segments_meet(a[e], a[(e + 1) % 3], b[f], b[(f + 1) % 3], axis))
                return true;
    return false;
}

/* Whether the corners of b that a lacks lie strictly on one side of a's plane: then b
 * meets that plane, and a, at most in their common corners, which is no crossing. Most
 * candidate pairs of a mesh are neighbours, and this decides them without the
 * triangle-triangle test. */
static bool off_plane_apart(const double *const b[3], const double *const a[3],
                            const mci_plane *plane)
{
    int side = 0;
    for (int i = 0; i < 3; i++) {
        int o;
        if (same_point(b[i], a[0]) || same_point(b[i], a[1]) || same_point(b[i], a[2]))
            continue;
        o = mci_orient3d_vertex(b[i], plane);
        if (o == 0 || (side != 0 && o != side))
            return false;
        side = o;
    }
    return side != 0;
}

bool mci_triangles_cross(const mcsg_mesh *m, uint32_t s, uint32_t t)
{
    const double *a[3] = {vertex(m, s, 0), vertex(m, s, 1), vertex(m, s, 2)};
    const double *b[3] = {vertex(m, t, 0), vertex(m, t, 1), vertex(m, t, 2)};
    int shared;
    mci_plane ps, pt;
    mci_tt_result r;
    if (mci_triangle_is_degenerate(a[0], a[1], a[2]) ||
        mci_triangle_is_degenerate(b[0], b[1], b[2]))
        return false;
    shared = common_vertices(m, s, t);
    if (shared >= 3)
        return true;
    mci_plane_init(&ps, a[0], a[1], a[2]);
    mci_plane_init(&pt, b[0], b[1], b[2]);
    if (off_plane_apart(b, a, &ps) || off_plane_apart(a, b, &pt))
        return false;
    mci_triangle_intersection(&ps, &pt, &r);
    switch (r.kind) {
    case MCI_TT_DISJOINT:
        return false;
    case MCI_TT_POINT:
        return shared == 0;
    case MCI_TT_SEGMENT:
        return shared < 2;
    case MCI_TT_COPLANAR:
        return r.overlap || (shared == 0 && coplanar_boundaries_meet(a, b, &ps));
    }
    return false;
}

/* The checks of mcsg_mesh_self_intersections on its arguments. */
static mcsg_status check_arguments(const mcsg_mesh *mesh, mcsg_error *err)
{
    if (mesh->triangle_count > UINT32_MAX / 2)
        return mci_fail(err, MCSG_ERR_LIMIT, "mesh too large to test for self-intersections");
    for (size_t i = 0; i < 3 * mesh->triangle_count; i++)
        if (mesh->triangles[i] >= mesh->vertex_count)
            return mci_fail(err, MCSG_ERR_INVALID_MESH, "triangle %zu uses vertex %u of %zu",
                            i / 3, mesh->triangles[i], mesh->vertex_count);
    for (size_t i = 0; i < 3 * mesh->vertex_count; i++)
        if (!(mesh->vertices[i] - mesh->vertices[i] == 0))
            return mci_fail(err, MCSG_ERR_INVALID_MESH, "vertex %zu has a NaN or infinite "
                            "coordinate", i / 3);
    return MCSG_OK;
}

/* The crossing pairs, counted (*count) and, when list is not NULL, listed (s << 32 | t,
 * s < t, in the octree's order; *list allocated with ctx). */
static mcsg_status find_crossings(const mci_ctx *ctx, const mcsg_mesh *mesh, size_t *count,
                                  uint64_t **list, mcsg_error *err)
{
    mci_octree tree;
    const mcsg_mesh *twice[2] = {mesh, mesh};
    uint64_t *candidates = NULL;
    size_t n = 0;
    mcsg_status st = mci_octree_build(ctx, twice, 2, NULL, &tree, err);
    *count = 0;
    if (st != MCSG_OK)
        return st;
    st = mci_octree_candidate_pairs(ctx, &tree, &candidates, &n, err);
    for (size_t i = 0; st == MCSG_OK && i < n; i++) {
        uint32_t s = (uint32_t)(candidates[i] >> 32);
        uint32_t t = (uint32_t)candidates[i] - (uint32_t)mesh->triangle_count;
        if (s < t && mci_triangles_cross(mesh, s, t))
            candidates[(*count)++] = (uint64_t)s << 32 | t; /* i >= *count: read already */
    }
    if (st == MCSG_OK && list)
        *list = candidates;
    else
        mci_free(ctx, candidates);
    mci_octree_free(ctx, &tree);
    return st;
}

mcsg_status mci_crossing_pairs(const mci_ctx *ctx, const mcsg_mesh *mesh, uint64_t **pairs,
                               size_t *n, mcsg_error *err)
{
    mcsg_status st = check_arguments(mesh, err);
    *pairs = NULL;
    *n = 0;
    if (st != MCSG_OK || mesh->triangle_count == 0)
        return st;
    return find_crossings(ctx, mesh, n, pairs, err);
}

mcsg_status mcsg_mesh_self_intersections(const mcsg_mesh *mesh, const mcsg_options *opts,
                                         size_t *pairs, uint32_t example[2], mcsg_error *err)
{
    mci_ctx ctx;
    uint64_t *list = NULL;
    mcsg_status st;
    if (!mesh || !pairs || (mesh->vertex_count && !mesh->vertices) ||
        (mesh->triangle_count && !mesh->triangles))
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_self_intersections: NULL argument");
    *pairs = 0;
    if (example)
        example[0] = example[1] = MCSG_NO_INDEX;
    st = check_arguments(mesh, err);
    if (st != MCSG_OK || mesh->triangle_count == 0)
        return st;
    mci_ctx_init(&ctx, opts);
    st = find_crossings(&ctx, mesh, pairs, example ? &list : NULL, err);
    if (st == MCSG_OK && example && *pairs > 0)
        example[0] = (uint32_t)(list[0] >> 32), example[1] = (uint32_t)list[0];
    mci_free(&ctx, list);
    return st;
}
