/*
 * Mesh validation (mesh/validate.c): mcsg_mesh_check with the internal context, and the
 * exact sign of a signed volume that it, the evaluator's input contract and the removal
 * of void shells share.
 */
#ifndef MESHCSG_MESH_VALIDATE_H
#define MESHCSG_MESH_VALIDATE_H

#include "base/core.h"

/* Six times a signed volume in double, summed a triangle at a time (det(a, b, c) each),
 * with what its error bound needs. */
typedef struct mci_volume_sum {
    double sum, magnitude, amplified_underflow;
    size_t triangles;
} mci_volume_sum;
void mci_volume_sum_add(mci_volume_sum *v, const double *a, const double *b, const double *c);
/* +1 or -1 when the error bound proves the sum's sign, 0 when it cannot. */
int mci_volume_sum_sign(const mci_volume_sum *v);

/* Exact sign of the signed volume enclosed by the triangles tris[3 * which[k] ..] for
 * k < n (tris[3 k ..] when which is NULL) over the vertices xyz (finite); the volume in
 * double in *volume (optional). A floating-point sum decides when its error bound allows,
 * big integers otherwise. */
int mci_triangles_volume_sign(const double *xyz, const uint32_t *tris, const uint32_t *which,
                              size_t n, double *volume);

/* mcsg_mesh_check with the context's allocator; the mesh's counts must fit uint32_t. */
mcsg_status mci_mesh_check(const mci_ctx *ctx, const mcsg_mesh *mesh,
                           mcsg_check_report *report, mcsg_error *err);
/* Where one shell meets itself at an edge of more than two triangles (two boxes of one
 * connected surface touching along an edge), the triangles there are paired by angle
 * about the edge, each with the one it bounds a solid wedge with: both orders of each
 * pair (t << 32 | u, triangle indices), sorted. */
typedef struct mci_edge_mates {
    uint64_t *pairs;
    size_t count;
    size_t entering_edges; /* edges where directions do not alternate: a surface of the
                              shell enters another's wedge there, so the shell may
                              overlap itself nearby (worth testing for crossings) */
} mci_edge_mates;

void mci_edge_mates_free(const mci_ctx *ctx, mci_edge_mates *mates);

/* Whether triangles t and u are paired at such an edge (mates may be NULL: no). */
bool mci_edge_mates_has(const mci_edge_mates *mates, uint32_t t, uint32_t u);

/* The same, and when `shell` is not NULL (room for a value per triangle) and the mesh has
 * several components, each triangle's component over shared edges, numbered
 * 0 .. report->components - 1 in the order of their first triangles (valid triangles
 * only; others get UINT32_MAX). With one component `shell` is left as it is. At edges
 * of more than two triangles the shells are joined by the k-th use each way. `mates`
 * (optional) receives the angle pairs where a shell meets itself (allocated with ctx:
 * free with mci_edge_mates_free; empty on error). `twin` (optional, 3 per triangle)
 * receives each half-edge's other use, half-edge 3 t + k running from triangle t's
 * corner k to the next: for an edge of exactly two triangles running opposite ways
 * (vertices identified by coordinates), MCI_NONE for every other. */
mcsg_status mci_mesh_check_shells(const mci_ctx *ctx, const mcsg_mesh *mesh,
                                  mcsg_check_report *report, uint32_t *shell,
                                  uint32_t *twin, mci_edge_mates *mates, mcsg_error *err);

#endif
