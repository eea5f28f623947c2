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

/* The search for a point inside a sliver (point_inside_sliver). */
typedef struct sliver_search {
    const mci_point *a, *b, *c; /* corners: a-b the long edge */
    const mci_plane *plane;
    int axis, turn;             /* projection, and the triangle's turn in it */
    double (*ends)[3];          /* the line's ends: ends[0] fixed, ends[1] moved */
    double far[3], across[3];   /* ends[1] = far + mu * across */
    mci_point *out;
} sliver_search;

/* Where the line's point for mu lies: -1 beyond the long edge, 0 strictly inside the
 * triangle, +1 beyond one of the other edges (or no point). */
static int sliver_side(sliver_search *q, double mu)
{
    for (int k = 0; k < 3; k++)
        q->ends[1][k] = q->far[k] + mu * q->across[k];
    if (mci_orient3d_vertex(q->ends[1], q->plane) * mci_orient3d_vertex(q->ends[0], q->plane) >=
            0 ||
        !mci_point_lpi(q->out, q->ends[0], q->ends[1], q->plane))
        return 1;
    if (mci_orient2d_projected(q->a, q->b, q->out, q->axis) != q->turn)
        return -1;
    return mci_orient2d_projected(q->b, q->c, q->out, q->axis) == q->turn &&
                   mci_orient2d_projected(q->c, q->a, q->out, q->axis) == q->turn
               ? 0
               : 1;
}

/* Bisection on mu between a point beyond the long edge and one beyond the others. */
static bool sliver_bisect(sliver_search *q, double lo, double hi)
{
    int at_lo = sliver_side(q, lo), at_hi = sliver_side(q, hi);
    if (at_lo == 0 || at_hi == 0)
        return sliver_side(q, at_lo == 0 ? lo : hi) == 0;
    if (at_lo == at_hi)
        return false;
    if (at_lo > 0) {
        double t = lo;
        lo = hi, hi = t;
    }
    for (int step = 0; step < 200; step++) {
        double mid = 0.5 * (lo + hi);
        int side;
        if (mid == lo || mid == hi)
            return false;
        side = sliver_side(q, mid);
        if (side == 0)
            return true;
        if (side < 0)
            lo = mid;
        else
            hi = mid;
    }
    return false;
}

/* The squared length of edge i (from corner i to the next) of doubles x, roughly. */
static double edge_length2(double x[3][3], int i)
{
    double sum = 0;
    for (int k = 0; k < 3; k++)
        sum += (x[(i + 1) % 3][k] - x[i][k]) * (x[(i + 1) % 3][k] - x[i][k]);
    return sum;
}

/* The normal of the plane's triangle from its doubles, and its largest component's
 * magnitude (0 for a degenerate plane). A triangle so thin that the product rounds to
 * nothing gets the unit vector along its projection axis, on the normal's side (decided
 * exactly): a line along it still crosses the plane near the triangle. */
static double approx_normal(const mci_plane *plane, double n[3])
{
    const double *a = plane->a, *b = plane->b, *d = plane->c;
    double norm = 0;
    int axis, sign;
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        n[k] = (b[i] - a[i]) * (d[j] - a[j]) - (b[j] - a[j]) * (d[i] - a[i]);
        norm = fmax(norm, fabs(n[k]));
    }
    if (norm > 0 && isfinite(norm))
        return norm;
    if ((axis = mci_plane_projection_axis(plane, &sign)) < 0)
        return 0;
    n[0] = n[1] = n[2] = 0;
    n[axis] = sign;
    return 1;
}

/* A point strictly inside a triangle narrower than the spacing of doubles, where no
 * line through doubles near its centroid pierces it: the line runs from ends[0], a
 * double next to the plane at the long edge's middle, to ends[1], far on the other
 * side, so that moving ends[1] by a whole unit moves the point by a tiny fraction of
 * one across the triangle; bisection over that offset, every step decided exactly,
 * finds the strip between the long edge and the others. x: the corners' doubles. */
static bool point_inside_sliver(const mci_point c[3], double x[3][3],
                                const mci_plane *plane, double ends[2][3], mci_point *out)
{
    sliver_search q = {NULL, NULL, NULL, plane, 0, 0, ends, {0}, {0}, out};
    double n[3], u[3], across[3], len = 0, nlen = 0, big = 0, mid[3], d0, d1, t0;
    int sign, longest = 0, s0;
    for (int i = 1; i < 3; i++)
        if (edge_length2(x, i) > edge_length2(x, longest))
            longest = i;
    q.a = &c[longest], q.b = &c[(longest + 1) % 3], q.c = &c[(longest + 2) % 3];
    q.axis = mci_plane_projection_axis(plane, &sign);
    q.turn = q.axis < 0 ? 0 : mci_orient2d_projected(q.a, q.b, q.c, q.axis);
    if (q.turn == 0)
        return false;
    approx_normal(plane, n);
    for (int k = 0; k < 3; k++) {
        u[k] = x[(longest + 1) % 3][k] - x[longest][k];
        mid[k] = 0.5 * (x[longest][k] + x[(longest + 1) % 3][k]);
        big = fmax(big, fabs(mid[k]));
    }
    for (int k = 0; k < 3; k++) {
        across[k] = n[(k + 1) % 3] * u[(k + 2) % 3] - n[(k + 2) % 3] * u[(k + 1) % 3];
        nlen = fmax(nlen, fabs(n[k]));
        len = fmax(len, fabs(across[k]));
    }
    if (!(len > 0) || !(nlen > 0) || !isfinite(len) || !isfinite(big) || big == 0)
        return false;
    /* ends[0]: the long edge's middle, moved off the plane along the projection axis by
     * the fewest units of the largest coordinate that leave it (a unit of that
     * coordinate itself is a denormal on a plane through 0, and the line would then
     * meet the plane at ends[0] whatever ends[1]). */
    memcpy(ends[0], mid, sizeof mid);
    for (int step = 0; (s0 = mci_orient3d_vertex(ends[0], plane)) == 0; step++) {
        if (step == 64)
            return false;
        ends[0][q.axis] += ldexp(1.0, ilogb(big) - 52);
    }
    /* far: as far again as the point is from the origin, on the other side. */
    memcpy(q.far, ends[0], sizeof q.far);
    q.far[q.axis] -= s0 * (n[q.axis] > 0 ? 1 : -1) * 4 * (big + 1);
    d0 = fabs(ends[0][q.axis] - mid[q.axis]) + 4 * big * 0x1p-52;
    d1 = fabs(q.far[q.axis] - ends[0][q.axis]);
    t0 = d0 / (d0 + d1); /* roughly how far along the line the plane is */
    for (int k = 0; k < 3; k++)
        q.across[k] = across[k] / len / t0;
    /* The triangle lies within some units of the doubles of its corners. */
    return sliver_bisect(&q, -64 * big * 0x1p-52, 64 * big * 0x1p-52);
}

/* a + b as a double and the rounding error of that sum. */
static double sum_error(double a, double b, double *error)
{
    double s = a + b, bb = s - a;
    *error = (a - (s - bb)) + (b - bb);
    return s;
}

/* The centroid of c's corners to about twice the precision of doubles: hi + lo per
 * coordinate (mci_point_dd_values). False when those values are not at hand. */
static bool centroid_dd(const mci_point c[3], double hi[3], double lo[3])
{
    double v[3][3][3];
    for (int i = 0; i < 3; i++)
        if (!mci_point_dd_values(&c[i], v[i]))
            return false;
    for (int k = 0; k < 3; k++) {
        double e1, e2, s = sum_error(v[0][k][0], v[1][k][0], &e1);
        double r, low = e1 + v[0][k][1] + v[1][k][1] + v[2][k][1];
        s = sum_error(s, v[2][k][0], &e2);
        low += e2;
        hi[k] = s / 3;
        r = fma(-3, hi[k], s); /* exact: s - 3 hi */
        lo[k] = (r + low) / 3;
    }
    return true;
}

/* A point strictly inside a triangle whose corners are all within a few units in the
 * last place of each other (no line through doubles near them is known to pierce it):
 * the line from ends[0], the double nearest its centroid moved just off the plane,
 * through the centroid (known to about twice the precision of doubles), to ends[1],
 * a power of two times as far on the other side. Rounding ends[1] then moves the
 * point where the line meets the plane by about 2^-52 of the distance from ends[0] to
 * the centroid, a tiny fraction of a unit. */
static bool point_inside_tiny(const mci_point c[3], const mci_plane *plane, double ends[2][3],
                              mci_point *out)
{
    double hi[3], lo[3], d[3], big = 0, reach = 0, scale;
    int sign, axis = mci_plane_projection_axis(plane, &sign), s0, turn;
    if (axis < 0 || !centroid_dd(c, hi, lo))
        return false;
    for (int k = 0; k < 3; k++)
        big = fmax(big, fabs(hi[k]));
    if (!isfinite(big) || big == 0)
        return false;
    memcpy(ends[0], hi, sizeof hi);
    for (int step = 0; (s0 = mci_orient3d_vertex(ends[0], plane)) == 0; step++) {
        if (step == 64)
            return false;
        ends[0][axis] += ldexp(1.0, ilogb(big) - 52);
    }
    for (int k = 0; k < 3; k++) {
        d[k] = (hi[k] - ends[0][k]) + lo[k];
        reach = fmax(reach, fabs(d[k]));
    }
    if (!(reach > 0))
        return false;
    scale = ldexp(1.0, ilogb(4 * (big + 1)) - ilogb(reach));
    for (int k = 0; k < 3; k++)
        ends[1][k] = ends[0][k] + scale * d[k];
    if (mci_orient3d_vertex(ends[1], plane) != -s0 ||
        !mci_point_lpi(out, ends[0], ends[1], plane))
        return false;
    turn = mci_orient2d_projected(&c[0], &c[1], out, axis);
    return turn != 0 && mci_orient2d_projected(&c[1], &c[2], out, axis) == turn &&
           mci_orient2d_projected(&c[2], &c[0], out, axis) == turn;
}

/* The corners' angles from their doubles x, largest first: order[0..2]. */
static void corners_by_angle(double x[3][3], int order[3])
{
    double angle[3];
    for (int i = 0; i < 3; i++) {
        double u[3], v[3], dot = 0, cross = 0;
        for (int k = 0; k < 3; k++) {
            u[k] = x[(i + 1) % 3][k] - x[i][k];
            v[k] = x[(i + 2) % 3][k] - x[i][k];
            dot += u[k] * v[k];
        }
        for (int k = 0; k < 3; k++) {
            double c = u[(k + 1) % 3] * v[(k + 2) % 3] - u[(k + 2) % 3] * v[(k + 1) % 3];
            cross += c * c;
        }
        angle[i] = atan2(sqrt(cross), dot);
        order[i] = i;
    }
    for (int i = 1; i < 3; i++)
        for (int j = i; j > 0 && angle[order[j]] > angle[order[j - 1]]; j--) {
            int t = order[j];
            order[j] = order[j - 1], order[j - 1] = t;
        }
}

/* A point strictly inside a triangle too thin for a line near its middle to be found
 * piercing it (its width below what doubles near its coordinates resolve: a corner a
 * unit from another, nearly on the line through the other two), next to a corner that
 * is an input vertex: the line from that corner moved a unit off the plane to a far
 * end on the other side, moved a unit within the plane in one of 16 directions (about
 * 22.5 degrees apart in the projection). It meets the plane next to the corner, inside
 * the triangle when that direction lies strictly within the corner's angle and the
 * triangle is wider than the distance there. `pick` chooses the corner (pick % 3, by
 * angle, largest first), the direction (pick / 3 % 16) and how far the far end is: 2^60
 * times the coordinates (the point about 2^-112 of a unit from the corner) for the
 * first 48, 2^600 times (2^-652 of a unit: slower exact arithmetic) for the next 48. */
static bool point_inside_at_corner(const mci_point c[3], double x[3][3],
                                   const mci_plane *plane, int pick, double ends[2][3],
                                   mci_point *out)
{
    static const int step[16][2] = {{1, 0},   {2, 1},   {1, 1},   {1, 2},
                                    {0, 1},   {-1, 2},  {-1, 1},  {-2, 1},
                                    {-1, 0},  {-2, -1}, {-1, -1}, {-1, -2},
                                    {0, -1},  {1, -2},  {1, -1},  {2, -1}};
    const mci_point *corner;
    double big = 0, unit;
    int order[3], sign, axis = mci_plane_projection_axis(plane, &sign), s0, turn;
    corners_by_angle(x, order);
    corner = &c[order[pick % 3]];
    if (axis < 0 || corner->kind != MCI_POINT_EXPLICIT)
        return false;
    for (int k = 0; k < 3; k++)
        big = fmax(big, fabs(corner->v[0][k]));
    unit = ldexp(1.0, (big > 0 ? ilogb(big) : -1022) - 52);
    memcpy(ends[0], corner->v[0], sizeof ends[0]);
    for (int n = 0; (s0 = mci_orient3d_vertex(ends[0], plane)) == 0; n++) {
        if (n == 64)
            return false;
        ends[0][axis] += unit;
    }
    memcpy(ends[1], corner->v[0], sizeof ends[1]);
    ends[1][(axis + 1) % 3] += step[pick / 3 % 16][0] * unit;
    ends[1][(axis + 2) % 3] += step[pick / 3 % 16][1] * unit;
    ends[1][axis] -= (ends[0][axis] > corner->v[0][axis] ? 1 : -1) *
                     ldexp(big + 1, pick < 48 ? 60 : 600);
    for (int k = 0; k < 3; k++)
        if (!isfinite(ends[0][k]) || !isfinite(ends[1][k])) /* coordinates near the limit */
            return false;
    if (mci_orient3d_vertex(ends[1], plane) != -s0 || !mci_point_lpi(out, ends[0], ends[1], plane))
        return false;
    turn = mci_orient2d_projected(&c[0], &c[1], out, axis);
    return turn != 0 && mci_orient2d_projected(&c[1], &c[2], out, axis) == turn &&
           mci_orient2d_projected(&c[2], &c[0], out, axis) == turn;
}

/* See classify_leaf.h. */
bool mci_point_inside_triangle(const mci_point c[3], const mci_plane *plane, int attempt,
                                double ends[2][3], mci_point *out)
{
    /* Barycentric weights, the centroid first: a point on the border of a face of another
     * surface lying in this one decides nothing, and another point rarely is too. */
    static const double weight[MCI_INSIDE_WEIGHTED][3] = {
        {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.3, 0.2}, {0.2, 0.5, 0.3}, {0.3, 0.2, 0.5}};
    const double *wt = weight[attempt < MCI_INSIDE_WEIGHTED ? attempt : 0];
    double x[3][3], n[3], size = 0, norm = approx_normal(plane, n);
    int axis, sign, turns[3];
    for (int i = 0; i < 3; i++)
        mci_point_near(&c[i], x[i]);
    if (attempt >= MCI_INSIDE_WEIGHTED)
        return point_inside_at_corner(c, x, plane, attempt - MCI_INSIDE_WEIGHTED, ends, out);
    for (int k = 0; k < 3; k++) {
        for (int v = 0; v < 3; v++)
            size = fmax(size, fabs(x[v][k] - x[(v + 1) % 3][k]));
    }
    if (!(size > 0) && attempt == MCI_INSIDE_WEIGHTED - 1) /* corners on one double */
        return point_inside_tiny(c, plane, ends, out);
    if (!(norm > 0) || !(size > 0) || !isfinite(norm) || !isfinite(size))
        return false;
    for (int k = 0; k < 3; k++) {
        double centre = wt[0] * x[0][k] + wt[1] * x[1][k] + wt[2] * x[2][k];
        double step = n[k] / norm * size;
        ends[0][k] = centre + step;
        ends[1][k] = centre - step;
    }
    /* The line may miss: a triangle much smaller than its coordinates' unit (ends
     * rounded onto the plane). The last attempt then searches as for a sliver. */
    if (mci_orient3d_vertex(ends[0], plane) * mci_orient3d_vertex(ends[1], plane) < 0 &&
        mci_point_lpi(out, ends[0], ends[1], plane) &&
        (axis = mci_plane_projection_axis(plane, &sign)) >= 0) {
        for (int i = 0; i < 3; i++)
            turns[i] = mci_orient2d_projected(&c[i], &c[(i + 1) % 3], out, axis);
        if (turns[0] != 0 && turns[0] == turns[1] && turns[1] == turns[2])
            return true;
    }
    if (attempt != MCI_INSIDE_WEIGHTED - 1)
        return false;
    return point_inside_sliver(c, x, plane, ends, out) || point_inside_tiny(c, plane, ends, out);
}

bool mci_leaf_piece_inside(const mci_leaf_work *w, size_t p, int attempt, double ends[2][3],
                           mci_point *out, mci_plane *plane)
{
    mci_point c[3];
    for (int i = 0; i < 3; i++)
        mci_leaf_piece_point(w, p, i, &c[i]);
    mci_scene_face_plane(w->s, w->pface[p], plane);
    return mci_point_inside_triangle(c, plane, attempt, ends, out);
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
                              mci_octree_face_group(&w->s->octree, w->pface[w->reg_pieces[k]]);
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
