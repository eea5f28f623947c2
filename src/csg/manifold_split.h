/*
 * Making the output edge- and vertex-manifold where parts of the result touch along an
 * edge or at a point: each umbrella of triangles around a vertex gets its own copy of
 * the vertex. See manifold_split.c.
 */
#ifndef MESHCSG_CSG_MANIFOLD_SPLIT_H
#define MESHCSG_CSG_MANIFOLD_SPLIT_H

#include "base/core.h"

typedef struct mci_touching_split {
    size_t new_vertices;   /* vertex copies added */
    size_t unpaired_edges; /* edges whose triangles could not be paired (left as they are):
                              not as many in each direction, or over 64 */
    size_t reordered_edges; /* edges whose triangles did not alternate in direction around
                               them after rounding, paired by their order */
    size_t separated_edges; /* edges paired again so that vertex copies separate them */
} mci_touching_split;

/* m: closed, consistently oriented triangle mesh allocated with ctx (its vertex array
 * grows). Returns false only when out of memory (m is then partly rewritten: free it). */
bool mci_split_touching(const mci_ctx *ctx, mcsg_mesh *m, mci_touching_split *result);

#endif
