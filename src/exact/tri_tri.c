/*
 * Exact triangle-triangle intersection (see tri_tri.h). Steps, as in the paper §4.1:
 * (1) signs of each triangle's vertices against the other's plane (early rejection);
 * (2) Seg1 = t1 ∩ plane(t2) and Seg2 = t2 ∩ plane(t1), each a point or a segment whose
 *     ends are vertices on the plane or edge-line/plane points (LPI);
 * (3) the intersection is the overlap of Seg1 and Seg2 along the common line, found by
 *     ordering their ends with the exact order predicate (paper Eq. 1).
 * Coplanar triangles are tested for overlapping interiors with the edges' bounding
 * planes (projected orientations): the interiors are disjoint exactly when some edge
 * line of either triangle has the whole other triangle on its closed outer side.
 */
#include "exact/tri_tri.h"
#include "exact/predicates.h"

#include <stdint.h>
#include <string.h>

static const double *corner(const mci_plane *t, int i)
{
    return i == 0 ? t->a : i == 1 ? t->b : t->c;
}

/* Side of each vertex of t against `plane`. */
static void vertex_sides(const mci_plane *t, const mci_plane *plane, int side[3])
{
    for (int i = 0; i < 3; i++)
        side[i] = mci_orient3d_vertex(corner(t, i), plane);
}

static bool all_strictly_one_side(const int side[3])
{
    return (side[0] > 0 && side[1] > 0 && side[2] > 0) ||
           (side[0] < 0 && side[1] < 0 && side[2] < 0);
}

static bool all_sides_strict(const int side[3])
{
    return side[0] != 0 && side[1] != 0 && side[2] != 0;
}

/* The index of the corner alone on its side (sides all strict, not all equal). */
static int lone_corner(const int side[3])
{
    return side[0] == side[1] ? 2 : side[0] == side[2] ? 1 : 0;
}

/* t's corners from the lone one on, in t's circular order (same orientation). */
static void corners_from(const mci_plane *t, int first, const double *out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = corner(t, (first + i) % 3);
}

static void swap_last_two(const double *v[3])
{
    const double *t = v[1];
    v[1] = v[2];
    v[2] = t;
}

/* Whether the sections of t1 and t2 on the common line are apart (a gap between them),
 * decided on the input vertices alone (Devillers & Guigue 2002), before any point is
 * constructed: most candidate pairs that cross each other's planes are rejected here.
 * Name the corners p, q, r with p alone on its side of the other plane, q and r swapped
 * where needed so that p1 is in front of plane (p2, q2, r2) and p2 in front of plane
 * (p1, q1, r1). Along d = n1 x n2 the line then crosses t1 from its p1-r1 edge to its
 * p1-q1 edge, and t2 from p2-q2 to p2-r2. The plane (p1, q1, p2) holds t1's last end
 * and has normal . d = -((q1 - p1) . n2) ((p2 - p1) . n1) > 0, so orient(p1, q1, p2, q2)
 * > 0 puts t2's first end strictly after t1's last; orient(p1, r1, p2, r2) < 0 likewise
 * puts t2's last end strictly before t1's first. Every corner must be strictly off the
 * other triangle's plane (so no three of these points are collinear). */
/* The corners named as above: v1 = p1, q1, r1 and v2 = p2, q2, r2. */
typedef struct strict_pair {
    const double *v1[3], *v2[3];
    bool reversed; /* the section runs against n1 x n2 (exactly one triangle renamed) */
} strict_pair;

static void name_corners(const mci_plane *t1, const int side1[3], const mci_plane *t2,
                         const int side2[3], strict_pair *c)
{
    int lone1 = lone_corner(side1), lone2 = lone_corner(side2);
    corners_from(t1, lone1, c->v1);
    corners_from(t2, lone2, c->v2);
    if (side1[lone1] < 0)
        swap_last_two(c->v2);
    if (side2[lone2] < 0)
        swap_last_two(c->v1);
    c->reversed = side1[lone1] * side2[lone2] < 0;
}

static bool sections_apart(const strict_pair *c)
{
    return mci_orient3d_vertices(c->v1[0], c->v1[1], c->v2[0], c->v2[1]) > 0 ||
           mci_orient3d_vertices(c->v1[0], c->v1[2], c->v2[0], c->v2[2]) < 0;
}

/* The corner of t1 that is t1's only contact with t2's plane (one side 0, the other two
 * strictly on one side) and is also a corner of t2 (same coordinates), or NULL. Then
 * the triangles meet in that point and nowhere else: t1 touches the plane there only,
 * and t2 holds it. The general path would find the same point through the sections,
 * and keep t1's copy of it (the overlap starts and ends at t1's section on ties). */
static const double *shared_lone_corner(const mci_plane *t1, const int side1[3],
                                        const mci_plane *t2)
{
    for (int i = 0; i < 3; i++) {
        const double *v = corner(t1, i);
        int a = side1[(i + 1) % 3], b = side1[(i + 2) % 3];
        if (side1[i] != 0 || a == 0 || a != b)
            continue;
        for (int k = 0; k < 3; k++) {
            const double *w = corner(t2, k);
            if (v[0] == w[0] && v[1] == w[1] && v[2] == w[2])
                return v;
        }
        return NULL;
    }
    return NULL;
}

/* The edge line through u and v, defined in a canonical vertex order, meeting the
 * plane: built, or (see mci_triangle_intersection_defined) its definition only. */
static void edge_crossing(mci_point *out, const double *u, const double *v,
                          const mci_plane *plane, bool build)
{
    bool swap = mci_vertex_before(v, u);
    const double *a = swap ? v : u, *b = swap ? u : v;
    if (build) /* the sides differ strictly: the line is not parallel to the plane */
        (void)mci_point_lpi(out, a, b, plane);
    else
        mci_point_lpi_define(out, a, b, plane);
}

/* The overlap of sections that are not apart (every corner strictly off the other
 * plane), with the names above: t1's section runs from I (on p1-r1) to J (on p1-q1), t2's
 * from K (on p2-q2) to L (on p2-r2). The plane (p1, r1, p2) holds I and p2, so for a
 * point X of the line, orient(p1, r1, p2, X) is > 0 after I, < 0 before it (as in
 * sections_apart), and for K, on the segment from p2 to q2, it has q2's sign; likewise
 * (p1, q1, p2) against J, with L taking r2's sign. So the overlap [max(I, K), min(J, L)]
 * is known before any point is built, and only its two ends are (on a tie between the
 * sections' ends, t1's copy, as overlap_on_line keeps). It is a single point only when
 * K = J or L = I. */
static void strict_overlap(const mci_plane *t1, const mci_plane *t2, const strict_pair *c,
                           mci_tt_result *out)
{
    bool build = !out->defined_only;
    const double *p1 = c->v1[0], *q1 = c->v1[1], *r1 = c->v1[2];
    const double *p2 = c->v2[0], *q2 = c->v2[1], *r2 = c->v2[2];
    int start_side = mci_orient3d_vertices(p1, r1, p2, q2);
    int end_side = mci_orient3d_vertices(p1, q1, p2, r2);
    bool start_k = start_side > 0, end_l = end_side < 0;
    bool single = start_k && !end_l ? mci_orient3d_vertices(p1, q1, p2, q2) == 0
                  : !start_k && end_l ? mci_orient3d_vertices(p1, r1, p2, r2) == 0
                                      : false;
    mci_point *start = &out->end[c->reversed], *end = &out->end[!c->reversed];
    out->kind = single ? MCI_TT_POINT : MCI_TT_SEGMENT;
    /* A single point is the copy overlap_on_line keeps: the later start along n1 x n2,
     * which is the section's end when the section runs against it. */
    if (single)
        start = end = &out->end[0];
    /* A segment's end lies strictly inside the other triangle unless the two sections
     * end there together (a tie: it is on an edge of each). */
    else
        out->strict_ends = (uint8_t)((start_side != 0) << c->reversed |
                                     (end_side != 0) << !c->reversed);
    if (!single || !c->reversed) {
        if (start_k)
            edge_crossing(start, p2, q2, t1, build);
        else
            edge_crossing(start, p1, r1, t2, build);
    }
    if (!single || c->reversed) {
        if (end_l)
            edge_crossing(end, p2, r2, t1, build);
        else
            edge_crossing(end, p1, q1, t2, build);
    }
}

/* t ∩ plane as 1 or 2 points (t not coplanar with the plane, not strictly on a side). */
static int plane_section(const mci_plane *t, const mci_plane *plane, const int side[3],
                         mci_point out[2])
{
    int n = 0;
    for (int i = 0; i < 3 && n < 2; i++) {
        int j = (i + 1) % 3;
        if (side[i] == 0)
            mci_point_explicit(&out[n++], corner(t, i));
        if (n < 2 && side[i] * side[j] < 0)
            edge_crossing(&out[n++], corner(t, i), corner(t, j), plane, true);
    }
    return n;
}

/* The common line of the two planes, as an axis and direction sign (computed once). */
typedef struct line_order {
    int axis, sign;
} line_order;

static int order_on_line(const mci_point *a, const mci_point *b, const line_order *l)
{
    return l->sign * mci_compare_coord(a, b, l->axis);
}

/* Sort a section's ends along the line; a single point is its own segment. */
static void order_section(mci_point s[2], int n, const line_order *l)
{
    if (n == 1) {
        s[1] = s[0];
    } else if (order_on_line(&s[0], &s[1], l) > 0) {
        mci_point t = s[0];
        s[0] = s[1];
        s[1] = t;
    }
}

static void overlap_on_line(const mci_point s1[2], const mci_point s2[2],
                            const line_order *l, mci_tt_result *out)
{
    const mci_point *start, *end;
    int order;
    start = order_on_line(&s1[0], &s2[0], l) >= 0 ? &s1[0] : &s2[0];
    end = order_on_line(&s1[1], &s2[1], l) <= 0 ? &s1[1] : &s2[1];
    order = order_on_line(start, end, l);
    if (order > 0) {
        out->kind = MCI_TT_DISJOINT;
        return;
    }
    out->end[0] = *start;
    if (order == 0) {
        out->kind = MCI_TT_POINT;
        return;
    }
    out->kind = MCI_TT_SEGMENT;
    out->end[1] = *end;
}

/* Whether some edge of `a` has all of `b` on its closed outer side, in the projection
 * along `axis` where a's orientation has sign `a_sign`. */
static bool edge_separates(const mci_plane *a, int a_sign, const mci_plane *b, int axis)
{
    mci_point ac[3], bc[3];
    for (int i = 0; i < 3; i++) {
        mci_point_explicit(&ac[i], corner(a, i));
        mci_point_explicit(&bc[i], corner(b, i));
    }
    for (int e = 0; e < 3; e++) {
        int outside = 0;
        for (int i = 0; i < 3; i++)
            outside += a_sign * mci_orient2d_projected(&ac[e], &ac[(e + 1) % 3], &bc[i], axis) <= 0;
        if (outside == 3)
            return true;
    }
    return false;
}

static bool coplanar_interiors_overlap(const mci_plane *t1, const mci_plane *t2)
{
    int sign1, sign2, axis = mci_plane_projection_axis(t1, &sign1);
    mci_point c[3];
    if (axis < 0)
        return false;
    for (int i = 0; i < 3; i++)
        mci_point_explicit(&c[i], corner(t2, i));
    sign2 = mci_orient2d_projected(&c[0], &c[1], &c[2], axis);
    if (sign2 == 0)
        return false;
    return !edge_separates(t1, sign1, t2, axis) && !edge_separates(t2, sign2, t1, axis);
}

/* With defined_only, strict overlaps leave their ends as definitions (and set the
 * flag); every other case builds them. */
static void intersect(const mci_plane *t1, const mci_plane *t2, mci_tt_result *out,
                      bool defined_only)
{
    int side1[3], side2[3], n1, n2;
    const double *lone;
    mci_point s1[2], s2[2];
    line_order line;
    memset(out, 0, sizeof *out);
    vertex_sides(t1, t2, side1);
    if (all_strictly_one_side(side1))
        return;
    vertex_sides(t2, t1, side2);
    if (all_strictly_one_side(side2))
        return;
    if (all_sides_strict(side1) && all_sides_strict(side2)) {
        strict_pair c;
        name_corners(t1, side1, t2, side2, &c);
        if (!sections_apart(&c)) {
            out->defined_only = defined_only;
            strict_overlap(t1, t2, &c, out);
        }
        return;
    }
    if (side1[0] == 0 && side1[1] == 0 && side1[2] == 0) {
        out->kind = MCI_TT_COPLANAR;
        out->overlap = coplanar_interiors_overlap(t1, t2);
        return;
    }
    out->along_edge[0] = (side1[0] == 0) + (side1[1] == 0) + (side1[2] == 0) == 2;
    out->along_edge[1] = (side2[0] == 0) + (side2[1] == 0) + (side2[2] == 0) == 2;
    if ((lone = shared_lone_corner(t1, side1, t2)) != NULL) {
        out->kind = MCI_TT_POINT;
        mci_point_explicit(&out->end[0], lone);
        return;
    }
    n1 = plane_section(t1, t2, side1, s1);
    n2 = plane_section(t2, t1, side2, s2);
    /* Not coplanar and both meet the other's plane: the planes are not parallel. */
    line.axis = mci_plane_line_axis(t1, t2, &line.sign);
    if (line.axis < 0)
        return; /* not reached: parallel planes put t1 strictly on one side */
    order_section(s1, n1, &line);
    order_section(s2, n2, &line);
    overlap_on_line(s1, s2, &line, out);
}

void mci_triangle_intersection(const mci_plane *t1, const mci_plane *t2, mci_tt_result *out)
{
    intersect(t1, t2, out, false);
}

void mci_triangle_intersection_defined(const mci_plane *t1, const mci_plane *t2,
                                       mci_tt_result *out)
{
    intersect(t1, t2, out, true);
}

/* orient2d of a, b, c projected along `axis`. */
static int orient_along(const double *a, const double *b, const double *c, int axis)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    return mci_orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

bool mci_coplanar_touch_at_corner_only(const double *const a[3], const double *const b[3],
                                       int axis)
{
    int shared = 0, i0 = 0, j0 = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (a[i][0] == b[j][0] && a[i][1] == b[j][1] && a[i][2] == b[j][2]) {
                shared++;
                i0 = i;
                j0 = j;
            }
    if (shared != 1)
        return false;
    {
        const double *v = a[i0], *a1 = a[(i0 + 1) % 3], *a2 = a[(i0 + 2) % 3];
        const double *b1 = b[(j0 + 1) % 3], *b2 = b[(j0 + 2) % 3], *swap;
        int turn_a = orient_along(v, a1, a2, axis), turn_b = orient_along(v, b1, b2, axis);
        if (turn_a == 0 || turn_b == 0)
            return false;
        if (turn_a < 0) {
            swap = a1;
            a1 = a2;
            a2 = swap;
        }
        if (turn_b < 0) {
            swap = b1;
            b1 = b2;
            b2 = swap;
        }
        /* a's sector lies left of v->a1 and right of v->a2 (it spans less than a half
         * turn): b's, strictly beyond one of those lines, meets it at v only */
        return (orient_along(v, a1, b1, axis) < 0 && orient_along(v, a1, b2, axis) < 0) ||
               (orient_along(v, a2, b1, axis) > 0 && orient_along(v, a2, b2, axis) > 0);
    }
}
