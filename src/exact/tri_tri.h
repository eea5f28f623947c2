/*
 * Exact plane-based triangle-triangle intersection (paper §4.1, after Moeller): no
 * coordinate is ever constructed; the end points of an intersection segment are implicit
 * points (an input vertex, or an edge line of one triangle meeting the other's plane).
 */
#ifndef MESHCSG_EXACT_TRI_TRI_H
#define MESHCSG_EXACT_TRI_TRI_H

#include "exact/kernel.h"

typedef enum mci_tt_kind {
    MCI_TT_DISJOINT = 0,
    MCI_TT_POINT,    /* a single common point: end[0] (paper §4.2: recorded, no segment) */
    MCI_TT_SEGMENT,  /* the segment end[0] -> end[1], ordered along n1 x n2, distinct */
    MCI_TT_COPLANAR  /* same plane; `overlap` says whether the interiors overlap */
} mci_tt_kind;

typedef struct mci_tt_result {
    mci_tt_kind kind;
    bool overlap;
    /* SEGMENT: whether it lies along an edge of t1 (two of t1's corners are on t2's
     * plane), and of t2. */
    bool along_edge[2];
    /* SEGMENT with every corner of both triangles strictly off the other's plane: each
     * end is where an edge of one triangle crosses the other's plane, strictly inside
     * that edge; bit k says that end k is also strictly inside the other triangle. */
    uint8_t strict_ends;
    /* Set by mci_triangle_intersection_defined when end[] holds definitions only. */
    bool defined_only;
    mci_point end[2];
} mci_tt_result;

/* Intersect the closed triangles t1 = (t1->a, t1->b, t1->c) and t2 (their planes, as
 * built by mci_plane_init; both non-degenerate). Edge lines are defined by their two
 * vertices in a canonical order (by address), so that the point where an edge crosses a
 * plane has the same definition from both faces sharing that edge. */
void mci_triangle_intersection(const mci_plane *t1, const mci_plane *t2, mci_tt_result *out);

/* The same, for a caller that stores the ends' definitions and builds the points later
 * (or never): where every corner of each triangle is strictly off the other's plane (the
 * common case), each LPI end gets its kind and defining vertices v[0..4] only, and
 * `defined_only` is set; in every other case the ends are built as above. The results
 * are otherwise the same. */
void mci_triangle_intersection_defined(const mci_plane *t1, const mci_plane *t2,
                                       mci_tt_result *out);

/* For coplanar triangles a and b (the caller knows they are): whether they meet at one
 * common corner only, exactly. Exactly one corner v has the same coordinates in both, and,
 * in the projection along `axis` (any axis the plane's normal has a nonzero component
 * on), both of b's edges at v lie strictly beyond the line of one of a's edges at v. A
 * contact along a segment (an edge of b along an edge of a) fails the strict tests, as
 * do degenerate projections. Such a contact adds nothing to either face's arrangement,
 * and two CAD fans meeting at one apex have millions of them. */
bool mci_coplanar_touch_at_corner_only(const double *const a[3], const double *const b[3],
                                       int axis);

#endif
