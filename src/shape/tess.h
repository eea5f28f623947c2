/*
 * Polygon faces triangulated as OpenSCAD 2021.01 triangulates a polyhedron's faces
 * (shape/tess.c): its face cleaning, then libtess2's sweep-line triangulation (odd
 * winding rule, constrained-Delaunay refinement) in the projection libtess2 chooses,
 * every decision taken by exact predicates on the corners rounded to float, as OpenSCAD
 * rounds them. A face that libtess2 would cut at crossings of its own edges (or where
 * two corners project to one point) is fanned instead, and reported as such.
 */
#ifndef MESHCSG_SHAPE_TESS_H
#define MESHCSG_SHAPE_TESS_H

#include "base/core.h"

/* Reusable scratch for mci_tess_face; zero-initialise, free with mci_tess_free. */
typedef struct mci_tess mci_tess;

/* How one face was triangulated. */
typedef enum mci_tess_how {
    MCI_TESS_EMPTY,    /* fewer than three distinct corners after cleaning: no triangles */
    MCI_TESS_TRIANGLE, /* three corners after cleaning: passed through as they are */
    MCI_TESS_LIBTESS2, /* libtess2's triangles, reproduced */
    MCI_TESS_FAN,      /* not reproduced (self-touching projection): a fan instead */
} mci_tess_how;

/* Frees the scratch (*t may be NULL; it is NULL afterwards). */
void mci_tess_free(const mci_ctx *ctx, mci_tess **t);

/* Triangulate one face of n corners in the order OpenSCAD's PolySet holds them (a
 * polyhedron face reversed). ids[k] names corner k's vertex: equal ids are one vertex
 * (callers give points with equal float coordinates one id, as OpenSCAD does); xyz holds
 * 3 doubles per corner. Up to n - 2 triangles, as corner positions (0 .. n-1), go to
 * tris (3 per triangle), oriented like the face; *count receives their number. */
mcsg_status mci_tess_face(const mci_ctx *ctx, mci_tess **t, const double *xyz,
                          const uint32_t *ids, uint32_t n, uint32_t *tris, uint32_t *count,
                          mci_tess_how *how, mcsg_error *err);

#endif
