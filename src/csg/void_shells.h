/*
 * Output shells that rounding to doubles left without volume. See void_shells.c.
 */
#ifndef MESHCSG_CSG_VOID_SHELLS_H
#define MESHCSG_CSG_VOID_SHELLS_H

#include "base/core.h"

typedef struct mci_void_shells {
    size_t shells;    /* shells removed */
    size_t triangles; /* their triangles */
    size_t folded;    /* of the shells, those removed for a fold (see void_shells.c) */
} mci_void_shells;

/* m: closed, consistently oriented triangle mesh allocated with ctx, its shells made
 * apart by vertex (mci_split_touching). Removes every shell whose exact volume is zero,
 * and every shell of negative volume that no shell of positive volume encloses within its
 * bounding box; then the smaller of two shells folded onto each other (a triangle of each
 * with the same corners in the same order), and a shell folded onto itself when another
 * shell is larger; then the vertices no triangle uses. tag (optional) holds one value per
 * triangle and is compacted with the triangles. Returns false only when out of memory
 * (m is then unchanged). */
bool mci_drop_void_shells(const mci_ctx *ctx, mcsg_mesh *m, uint32_t *tag,
                          mci_void_shells *result);

#endif
