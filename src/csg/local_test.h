/*
 * The exact local test at a separator (csg/local_test.c).
 */
#ifndef MESHCSG_CSG_LOCAL_TEST_H
#define MESHCSG_CSG_LOCAL_TEST_H

#include "csg/csgtree.h"
#include "csg/intersect.h"

/* Label of a piece of face arrangement fa with respect to the leaf of face h, where the
 * piece's edge x-y lies in the closed face h and w is the piece's third vertex. The
 * piece's interior does not meet that leaf's surface (or lies in it), so the side of w
 * near the edge decides. *partner (if not NULL): the face across the edge of h that the
 * test took as the other half of the wedge (where x-y lies along an edge of h), or
 * MCI_NONE. */
mci_label mci_local_label(const mci_scene *s, const mci_face_arr *fa, const mci_point *x,
                          const mci_point *y, const mci_point *w, uint32_t h, uint32_t *partner);

#endif
