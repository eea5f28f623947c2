/*
 * Zero-area triangles removed from a leaf without changing its solid (zero_area.c).
 */
#ifndef MESHCSG_MESH_ZERO_AREA_H
#define MESHCSG_MESH_ZERO_AREA_H

#include "base/core.h"

#include <stdbool.h>
#include <stdint.h>

typedef struct mci_zero_area {
    size_t removed; /* zero-area triangles removed */
    size_t split;   /* triangles added by splitting others at corners of removed ones */
} mci_zero_area;

/* A copy of m (vertices unchanged) without its zero-area triangles, and (*face_of)[t]:
 * the triangle of m that triangle t of the copy is, or is part of. m must have finite
 * coordinates, valid indices, and be closed as a chain; the copy then is too, and has
 * the same winding number as m at every point off m. False only when out of memory
 * (nothing allocated). */
bool mci_remove_zero_area(const mci_ctx *ctx, const mcsg_mesh *m, mcsg_mesh *out,
                          uint32_t **face_of, mci_zero_area *res);

#endif
