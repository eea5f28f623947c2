/*
 * Classification by winding numbers (docs/classification.md): a primitive with several
 * shells, or facing inward, is the set of points where its winding number is positive.
 * For one outward shell that is its inside, and labels are decided as the paper does;
 * for the others two things change:
 *   - its own faces are on its solid's boundary only where its winding number is 0 in
 *     front of them (1 behind): a shell inside another positive shell, or an inward
 *     shell on its own, bounds nothing. Each connected part of its regions takes that
 *     number from one ray from a point inside one of its pieces (mci_leaf_own_seed,
 *     mci_ray_windings_on_plane); shells may cross each other (they are intersected as
 *     different leaves are, see mci_octree_params.face_group), and across a curve where
 *     another shell crosses, the number changes as for another leaf (below);
 *   - another leaf's region takes its label from that primitive's winding number on each
 *     of its sides. A ray gives it directly; across a separator on the primitive's surface
 *     the local test only tells on which side of that surface each of the two regions
 *     lies, so the number is carried over from the region before, one step per shell
 *     holding the separator (mci_wind_sheet). A region lying in that primitive's surface
 *     takes both numbers from a ray from a point inside one of its pieces
 *     (mci_ray_windings_on_plane).
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
static bool point_inside(const mci_point c[3], const mci_plane *plane, int attempt,
                         double ends[2][3], mci_point *out)
{
    /* Barycentric weights, the centroid first: a point on the border of a face of another
     * surface lying in this one decides nothing, and another point rarely is too. */
    static const double weight[MCI_INSIDE_ATTEMPTS][3] = {
        {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.3, 0.2}, {0.2, 0.5, 0.3}, {0.3, 0.2, 0.5}};
    const double *wt = weight[attempt];
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
        double centre = wt[0] * x[0][k] + wt[1] * x[1][k] + wt[2] * x[2][k];
        double step = n[k] / norm * size;
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

bool mci_leaf_piece_inside(const mci_leaf_work *w, size_t p, int attempt, double ends[2][3],
                           mci_point *out, mci_plane *plane)
{
    mci_point c[3];
    for (int i = 0; i < 3; i++)
        mci_leaf_piece_point(w, p, i, &c[i]);
    mci_scene_face_plane(w->s, w->pface[p], plane);
    return point_inside(c, plane, attempt, ends, out);
}

bool mci_leaf_own_seed(mci_leaf_work *w, uint32_t r)
{
    for (uint32_t k = w->reg_start[r], attempt = 0; k < w->reg_start[r + 1];
         attempt = (attempt + 1) % MCI_INSIDE_ATTEMPTS, k += attempt == 0) {
        double ends[2][3];
        mci_point q;
        mci_plane at;
        mci_plane_windings got;
        if (!mci_leaf_piece_inside(w, w->reg_pieces[k], (int)attempt, ends, &q, &at))
            continue;
        w->stats->rays++;
        if (!mci_ray_windings_on_plane(w->ctx, &q, &w->s->octree, w->leaf, &at, &w->ray,
                                       &got)) {
            w->out_of_memory = true;
            return false;
        }
        if (got.decided) {
            w->own_front[r] = got.in_front;
            w->own_coin[r] = got.behind - got.in_front;
            w->own_first[r] = got.first_same ==
                              mci_octree_face_shell(&w->s->octree, w->pface[w->reg_pieces[k]]);
            return true;
        }
    }
    return false;
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

void mci_wind_sheet(mci_wind_sum *sum, mci_label from_local, mci_label to_local)
{
    if (from_local == MCI_LABEL_UNKNOWN || to_local == MCI_LABEL_UNKNOWN) {
        sum->unknown = true;
        return;
    }
    /* The same label on both sides keeps whatever lies in the region (a coplanar
     * neighbour of the face across the separator's edge looks like one). */
    sum->coplanar |= from_local != to_local &&
                     (from_local == MCI_LABEL_SAME || from_local == MCI_LABEL_OPPO ||
                      to_local == MCI_LABEL_SAME || to_local == MCI_LABEL_OPPO);
    sum->front += offset_in_front(to_local) - offset_in_front(from_local);
    sum->coincident += offset_behind(to_local) - offset_in_front(to_local) -
                       (offset_behind(from_local) - offset_in_front(from_local));
}
