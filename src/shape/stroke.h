/*
 * Strokes of open paths as OpenSCAD 2021.01's SVG import draws them (shape/stroke.c):
 * its libsvg offsets an open line by half the stroke width with Clipper 6.2.1's
 * ClipperOffset (points scaled by 10000 and truncated to integers, MiterLimit 2,
 * ArcTolerance 0.25) and unites the outline Clipper makes (positive fill). The outline's
 * points are Clipper's integer points; its self-crossings (the loops Clipper's inner
 * corners make) are resolved here on the same integers, each crossing rounded as
 * Clipper's IntersectPoint rounds it. Not part of the public API.
 */
#ifndef MESHCSG_SHAPE_STROKE_H
#define MESHCSG_SHAPE_STROKE_H

#include "base/core.h"
#include "shape/region.h"

typedef enum mci_stroke_cap { MCI_CAP_BUTT, MCI_CAP_SQUARE, MCI_CAP_ROUND } mci_stroke_cap;
typedef enum mci_stroke_join {
    MCI_STROKE_MITER, /* Clipper's jtMiter (SVG "miter" and anything unknown) */
    MCI_STROKE_SQUARE, /* jtSquare: SVG "bevel" */
    MCI_STROKE_ROUND
} mci_stroke_join;

/* The outline of the stroke of width `width` along the open path of n points (x, y
 * pairs), as loops whose even-odd fill is the stroke (Clipper's union of its offset),
 * each point an integer divided by 10000. *out is zeroed first and owned by the caller
 * (mci_outlines_free); it may have no loops (an empty path). Fails with MCSG_ERR_LIMIT
 * when the outline would have more than max_points points, MCSG_ERR_UNSUPPORTED when a
 * coordinate times 10000 or the half width times 10000 exceeds 2^50 in magnitude or is
 * not finite, or when the outline's crossings could not be resolved (the message says
 * which; the caller decides what to do). */
mcsg_status mci_stroke_outline(const mci_ctx *ctx, const double *xy, size_t n, double width,
                               mci_stroke_cap cap, mci_stroke_join join, size_t max_points,
                               mci_outlines *out, mcsg_error *err);

#endif
