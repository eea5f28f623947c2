/*
 * Classification by winding numbers (docs/classification.md): a primitive with several
 * shells, or facing inward, is the set of points where its winding number is positive.
 * For one outward shell that is its inside, and labels are decided as the paper does;
 * for the others two things change:
 *   - its own faces are on its solid's boundary only where its winding number is 0 in
 *     front of them (1 behind): a shell inside another positive shell, or an inward
 *     shell on its own, bounds nothing. Shells neither cross nor touch (the input
 *     contract), so that number is one per shell, found by one ray from a point inside
 *     one of its faces (mci_leaf_shell_fronts, mci_ray_windings_on_plane);
 *   - another leaf's region takes its label from that primitive's winding number on each
 *     of its sides. A ray gives it directly; across a separator on the primitive's surface
 *     the local test only tells on which side of that surface each of the two regions
 *     lies, so the number is carried over from the region before (mci_wind_across). A
 *     region lying in that primitive's surface takes both numbers from a ray from a point
 *     inside one of its pieces (mci_ray_windings_on_plane).
 */
#include "csg/classify_leaf.h"
#include "csg/rays.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A point strictly inside the triangle with corners c[0..2] in plane `plane` (input
 * vertices; the corners may be implicit points): where a line through the corners'
 * approximate centroid, along the plane's approximate normal, pierces the plane (an LPI
 * of input vertices; `ends` holds the line's two ends, which the point refers to). False
 * when the doubles do not give a line crossing the plane or a point strictly inside
 * (slivers). */
static bool point_inside(const mci_point c[3], const mci_plane *plane, double ends[2][3],
                         mci_point *out)
{
    const double *a = plane->a, *b = plane->b, *d = plane->c;
    double x[3][3], n[3], size = 0, norm = 0;
    int axis, sign, turns[3];
    for (int i = 0; i < 3; i++)
        mci_point_approx(&c[i], x[i]);
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        n[k] = (b[i] - a[i]) * (d[j] - a[j]) - (b[j] - a[j]) * (d[i] - a[i]);
        norm = fmax(norm, fabs(n[k]));
        for (int v = 0; v < 3; v++)
            size = fmax(size, fabs(x[v][k] - x[(v + 1) % 3][k]));
    }
    if (!(norm > 0) || !(size > 0) || !isfinite(norm) || !isfinite(size))
        return false;
    for (int k = 0; k < 3; k++) {
        double centre = (x[0][k] + x[1][k] + x[2][k]) / 3, step = n[k] / norm * size;
        ends[0][k] = centre + step;
        ends[1][k] = centre - step;
    }
    if (mci_orient3d_vertex(ends[0], plane) * mci_orient3d_vertex(ends[1], plane) >= 0 ||
        !mci_point_lpi(out, ends[0], ends[1], plane) ||
        (axis = mci_plane_projection_axis(plane, &sign)) < 0)
        return false;
    for (int i = 0; i < 3; i++)
        turns[i] = mci_orient2d_projected(&c[i], &c[(i + 1) % 3], out, axis);
    return turns[0] != 0 && turns[0] == turns[1] && turns[1] == turns[2];
}

bool mci_point_inside_triangle(const double *a, const double *b, const double *c,
                               double ends[2][3], mci_point *out)
{
    mci_plane plane;
    mci_point corner[3];
    mci_plane_init(&plane, a, b, c);
    mci_point_explicit(&corner[0], a);
    mci_point_explicit(&corner[1], b);
    mci_point_explicit(&corner[2], c);
    return point_inside(corner, &plane, ends, out);
}

bool mci_leaf_piece_inside(const mci_leaf_work *w, size_t p, double ends[2][3], mci_point *out,
                           mci_plane *plane)
{
    mci_point c[3];
    for (int i = 0; i < 3; i++)
        mci_leaf_piece_point(w, p, i, &c[i]);
    mci_scene_face_plane(w->s, w->pface[p], plane);
    return point_inside(c, plane, ends, out);
}

/* Shells: the leaf's faces joined across shared edges (vertices by output id, i.e. by
 * coordinates). shell[f] is a face id of the shell (a union-find root). */
static mcsg_status find_shells(mci_leaf_work *w, uint32_t *shell)
{
    const mcsg_mesh *m = w->s->octree.leaves[w->leaf];
    const uint32_t *vid = w->cl->vertex_id + w->cl->vertex_first[w->leaf];
    size_t n = w->face_count;
    mci_keyed *edges = mci_malloc_array(w->ctx, 3 * n + 1, sizeof *edges);
    if (!edges)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t f = 0; f < n; f++) {
        const uint32_t *t = m->triangles + 3 * (size_t)f;
        shell[f] = f;
        for (int i = 0; i < 3; i++)
            edges[3 * (size_t)f + i] = (mci_keyed){mci_edge_key(vid[t[i]], vid[t[(i + 1) % 3]]), f};
    }
    mci_sort_keyed(edges, 3 * n);
    for (size_t i = 1; i < 3 * n; i++)
        if (edges[i].key == edges[i - 1].key) {
            uint32_t a = mci_find_root(shell, edges[i].ref), b = mci_find_root(shell, edges[i - 1].ref);
            shell[a > b ? a : b] = a < b ? a : b;
        }
    for (uint32_t f = 0; f < n; f++)
        shell[f] = mci_find_root(shell, f);
    mci_free(w->ctx, edges);
    return MCSG_OK;
}

/* The winding number of the leaf in front of the shell holding face f (local id), by a
 * ray from inside one of its faces that no other face of the leaf holds; false in
 * *found when every face of the shell fails (a shell folded onto itself). */
static mcsg_status shell_front(mci_leaf_work *w, const uint32_t *shell, uint32_t root,
                               int32_t *front, bool *found)
{
    const mcsg_mesh *m = w->s->octree.leaves[w->leaf];
    *found = false;
    for (uint32_t f = root; f < w->face_count; f++) {
        const uint32_t *t = m->triangles + 3 * (size_t)f;
        double ends[2][3];
        mci_point q;
        mci_plane plane;
        int behind, in_front;
        bool decided;
        if (shell[f] != root ||
            !mci_point_inside_triangle(m->vertices + 3 * (size_t)t[0], m->vertices + 3 * (size_t)t[1],
                                       m->vertices + 3 * (size_t)t[2], ends, &q))
            continue;
        w->stats->rays++;
        mci_scene_face_plane(w->s, w->face_base + f, &plane);
        if (!mci_ray_windings_on_plane(w->ctx, &q, &w->s->octree, w->leaf, &plane, &w->ray,
                                       &behind, &in_front, &decided))
            return mci_fail_nomem(w->err, "classifying faces");
        if (decided && behind == in_front + 1) { /* else the face has a twin */
            *front = in_front;
            *found = true;
            return MCSG_OK;
        }
    }
    return MCSG_OK;
}

mcsg_status mci_leaf_shell_fronts(mci_leaf_work *w)
{
    uint32_t *shell;
    mcsg_status st;
    if (!w->cl->tree->leaf_winding[w->leaf])
        return MCSG_OK;
    shell = mci_malloc_array(w->ctx, w->face_count + 1, sizeof *shell);
    w->face_front = mci_malloc_array(w->ctx, w->face_count + 1, sizeof *w->face_front);
    if (!shell || !w->face_front) {
        mci_free(w->ctx, shell);
        return mci_fail_nomem(w->err, "classifying faces");
    }
    st = find_shells(w, shell);
    for (uint32_t f = 0; f < w->face_count && st == MCSG_OK; f++) {
        bool found;
        if (shell[f] != f)
            continue; /* not a root: its front comes with the root's */
        st = shell_front(w, shell, f, &w->face_front[f], &found);
        if (st == MCSG_OK && !found)
            st = mci_fail(w->err, MCSG_ERR_INTERNAL, "leaf %u: no ray decides the winding "
                          "number of the shell of its face %u (a shell folded onto itself or "
                          "onto another)", w->leaf, f);
    }
    for (uint32_t f = 0; f < w->face_count && st == MCSG_OK; f++)
        w->face_front[f] = w->face_front[shell[f]];
    mci_free(w->ctx, shell);
    return st;
}

/* How far the winding number of the leaf whose surface holds a separator is above its
 * value in front of that surface, behind and in front of a piece with this local label:
 * inside that leaf (behind its surface) is one more. */
static int offset_behind(mci_label l)
{
    return l == MCI_LABEL_IN || l == MCI_LABEL_SAME;
}

static int offset_in_front(mci_label l)
{
    return l == MCI_LABEL_IN || l == MCI_LABEL_OPPO;
}

mci_label mci_label_of_windings(int32_t behind, int32_t in_front)
{
    if (behind > 0)
        return in_front > 0 ? MCI_LABEL_IN : MCI_LABEL_SAME;
    return in_front > 0 ? MCI_LABEL_OPPO : MCI_LABEL_OUT;
}

mci_label mci_wind_across(int32_t from_front, mci_label from_local, mci_label to_local,
                          int32_t *to_front)
{
    int32_t surface_front;
    if (from_front == MCI_WIND_UNKNOWN || from_local == MCI_LABEL_UNKNOWN ||
        to_local == MCI_LABEL_UNKNOWN) {
        *to_front = MCI_WIND_UNKNOWN;
        return MCI_LABEL_UNKNOWN;
    }
    surface_front = from_front - offset_in_front(from_local);
    *to_front = surface_front + offset_in_front(to_local);
    return mci_label_of_windings(surface_front + offset_behind(to_local), *to_front);
}
