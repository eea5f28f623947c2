/*
 * Leaf bounding boxes and which of them meet (csg/leaf_boxes.c): the candidates of the
 * trimmed CSGlists (paper §5.3: a leaf whose box misses another's is OUT of it, or IN
 * when complemented).
 */
#ifndef MESHCSG_CSG_LEAF_BOXES_H
#define MESHCSG_CSG_LEAF_BOXES_H

#include "base/core.h"

/* The bounding box of a mesh's vertices: lo[3], hi[3] (zeros for an empty mesh). */
void mci_leaf_box(const mcsg_mesh *m, double box[6]);

/* The boxes each of n closed boxes meets, itself excepted: those of box i are
 * list[start[i] .. start[i + 1]), in increasing index. Both arrays are allocated with
 * ctx (the caller frees them); false when out of memory (nothing allocated). */
bool mci_box_overlaps(const mci_ctx *ctx, const double (*box)[6], size_t n, uint32_t **start,
                      uint32_t **list);

#endif
