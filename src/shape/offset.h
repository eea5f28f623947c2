/*
 * The pieces of OpenSCAD's offset() (shape/offset.c). OpenSCAD offsets with Clipper: each
 * outline is moved along its edges' normals by delta, corners joined by an arc (round),
 * a miter point or a chamfer, and the result filled by its winding. The same region is
 * the union (delta > 0) of the input with one piece per edge (the edge swept by delta
 * along its normal) and one per corner the join fills (a wedge between the two moved
 * edges), or (delta < 0) the input minus those pieces on its inner side. The pieces are
 * simple convex polygons, so the union is exact with the 2D engine; their corners are
 * Clipper's, so that arcs have the same points.
 */
#ifndef MESHCSG_SHAPE_OFFSET_H
#define MESHCSG_SHAPE_OFFSET_H

#include "base/core.h"
#include "shape/region.h"

typedef enum mci_join { MCI_JOIN_ROUND, MCI_JOIN_MITER, MCI_JOIN_SQUARE } mci_join;

/* The pieces for outlines `o` (the region on their left, as mci_region_outlines gives
 * them), each piece one loop of *pieces. `steps` is the number of arc steps of a full
 * turn for round joins (Clipper's, from OpenSCAD's arc tolerance: the caller's). */
mcsg_status mci_offset_pieces(const mci_ctx *ctx, const mci_outlines *o, double delta,
                              mci_join join, double steps, mci_outlines *pieces,
                              mcsg_error *err);

#endif
