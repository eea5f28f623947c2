/*
 * Regions of the plane for OpenSCAD's 2D geometry (shape/region.c). A region is a set of
 * counter-clockwise triangles over points with double coordinates, with its boundary as
 * directed edges (the region on their left). It is made from outlines (a polygon's
 * paths, a circle) by the even-odd rule with a constrained triangulation, decided by
 * exact predicates; 2D CSG is done by the 3D engine on prisms over regions (z from 0 to
 * 1), whose faces at z = 0 are read back as the resulting region.
 */
#ifndef MESHCSG_SHAPE_REGION_H
#define MESHCSG_SHAPE_REGION_H

#include "base/core.h"

/* Closed outlines: loop k is points loop_start[k] .. loop_start[k + 1] - 1 (x, y pairs
 * in xy), the last joined to the first. */
typedef struct mci_outlines {
    double *xy;
    uint32_t *ids;        /* NULL, or (from a region) each point's vertex in the region */
    size_t point_count;
    uint32_t *loop_start; /* loop_count + 1 entries */
    size_t loop_count;
} mci_outlines;

typedef struct mci_region {
    double *xy;          /* 2 per vertex */
    size_t vertex_count;
    uint32_t *tris;      /* 3 per triangle, counter-clockwise */
    size_t tri_count;
    uint32_t *edges;     /* 2 per boundary edge: from, to; the region on the left */
    size_t edge_count;
} mci_region;

void mci_outlines_free(const mci_ctx *ctx, mci_outlines *o);
void mci_region_free(const mci_ctx *ctx, mci_region *r);

/* The region the outlines enclose by the even-odd rule: repeated points are merged,
 * edges split where another outline's point lies on them, and edges given an even
 * number of times cancel. Outlines that cross each other (two edges meeting at a point
 * inside both) fail with MCSG_ERR_UNSUPPORTED, naming that place. Non-finite
 * coordinates fail with MCSG_ERR_INVALID_ARG. An empty result is a region without
 * triangles. */
mcsg_status mci_region_from_outlines(const mci_ctx *ctx, const mci_outlines *o,
                                     mci_region *out, mcsg_error *err);

typedef enum mci_fill_rule {
    MCI_FILL_EVEN_ODD, /* inside where a ray crosses the outlines an odd number of times */
    MCI_FILL_POSITIVE  /* inside where the outlines wind counter-clockwise around the point
                          more often than clockwise: the union of counter-clockwise loops */
} mci_fill_rule;

/* The same by either rule. By the positive rule, edges given both ways cancel in pairs
 * and the rest keep their direction and multiplicity, so the loops of counter-clockwise
 * triangles give their union. */
mcsg_status mci_region_fill(const mci_ctx *ctx, const mci_outlines *o, mci_fill_rule rule,
                            mci_region *out, mcsg_error *err);

/* The prism over the region from z = 0 to z = 1: closed and outward. */
mcsg_status mci_region_prism(const mci_ctx *ctx, const mci_region *r, mcsg_mesh *out,
                             mcsg_error *err);


/* The region read back from a mesh of prisms evaluated by the engine: its triangles
 * with every corner at z = 0 (facing down there), turned to face up. */
mcsg_status mci_region_from_prisms(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_region *out,
                                   mcsg_error *err);

/* The boundary chained into closed outlines (each counter-clockwise around the region
 * on its left: outer outlines counter-clockwise, holes clockwise). */
mcsg_status mci_region_outlines(const mci_ctx *ctx, const mci_region *r, mci_outlines *out,
                                mcsg_error *err);

/* Drop the points of loops of more than three points that lie straight between their
 * neighbours (inside the segment joining them): the same region with fewer points. */
void mci_outlines_drop_straight(mci_outlines *o);

/* Add src's loops after dst's (outlines without ids; dst may be all zero). False when
 * memory runs out (dst unchanged but still valid) or either has ids. */
bool mci_outlines_append(const mci_ctx *ctx, mci_outlines *dst, const mci_outlines *src);

/* Twice the signed area of loop k. */
double mci_outline_area2(const mci_outlines *o, size_t k);

#endif
