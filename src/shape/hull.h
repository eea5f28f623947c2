/*
 * Exact convex hulls of points with double coordinates (shape/hull.c), for OpenSCAD's
 * hull() and minkowski(). Every decision is an exact orientation predicate; the hull's
 * vertices are input points.
 */
#ifndef MESHCSG_SHAPE_HULL_H
#define MESHCSG_SHAPE_HULL_H

#include "base/core.h"
#include "shape/region.h"

/* The convex hull of n points (xyz, 3 per point) as a closed triangle mesh, outward and
 * counter-clockwise seen from outside. Points inside the hull or on its edges are not
 * vertices; coplanar points on a face may be (its triangles then lie in one plane). All
 * points on one plane (or fewer than four) give an empty mesh: the hull has no volume. */
mcsg_status mci_hull3d(const mci_ctx *ctx, const double *xyz, size_t n, mcsg_mesh *out,
                       mcsg_error *err);

/* The convex hull of n points (xy, 2 per point) as one counter-clockwise outline without
 * collinear points; empty when the points are all on one line. */
mcsg_status mci_hull2d(const mci_ctx *ctx, const double *xy, size_t n, mci_outlines *out,
                       mcsg_error *err);

#endif
