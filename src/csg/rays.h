/*
 * Exact ray shooting (csg/rays.c): a point's label with respect to a closed mesh.
 */
#ifndef MESHCSG_CSG_RAYS_H
#define MESHCSG_CSG_RAYS_H

#include "csg/csgtree.h"
#include "csg/octree.h"
#include "exact/kernel.h"

/* Where point p is with respect to the closed mesh m, by an exact ray along +x,
 * symbolically perturbed so that rays through edges and vertices are decided
 * consistently: IN, OUT, or UNKNOWN when p lies on m's surface. */
mci_label mci_ray_label(const mci_point *p, const mcsg_mesh *m);

/* Reusable buffers for mci_ray_label_octree (zero-initialise; free when done). */
typedef struct mci_ray_scratch {
    uint32_t *faces, *stack;
    size_t face_count, face_capacity, stack_capacity;
} mci_ray_scratch;

void mci_ray_scratch_free(const mci_ctx *ctx, mci_ray_scratch *s);

/* The winding number of leaf m of octree o at p: the crossings of the perturbed ray
 * along +x, +1 where it leaves through a face (the face's normal has a positive x) and
 * -1 where it enters. *decided is false when p lies on a face of m (no ray decides then).
 * Returns false when out of memory. */
bool mci_ray_winding_octree(const mci_ctx *ctx, const mci_point *p, const mci_octree *o,
                            uint32_t m, mci_ray_scratch *s, int *winding, bool *decided);

/* What mci_ray_windings_on_plane tells. */
typedef struct mci_plane_windings {
    int behind, in_front;
    uint32_t first_same; /* the lowest group (mci_octree_face_group: a shell, or a face
                          * of a shell crossing itself) among the faces holding p that
                          * face like the plane; UINT32_MAX if none */
    bool decided;
} mci_plane_windings;

/* Leaf m's winding numbers just behind and just in front of the plane `at` (as its
 * normal points) at p, a point of that plane where no face of m crosses the plane: the
 * faces holding p all lie in it (coincident faces, counted with their orientation: one
 * facing like `at` adds one behind). out->decided is false when a face across the plane
 * holds p, or p lies on the border of a face in it (where it could count twice). Returns
 * false when out of memory. */
bool mci_ray_windings_on_plane(const mci_ctx *ctx, const mci_point *p, const mci_octree *o,
                               uint32_t m, const mci_plane *at, mci_ray_scratch *s,
                               mci_plane_windings *out);

/* mci_ray_label for the leaf m of octree o, testing only m's faces in the cells the ray
 * passes through (paper §5.2). Returns false when out of memory (*label unset). */
bool mci_ray_label_octree(const mci_ctx *ctx, const mci_point *p, const mci_octree *o,
                          uint32_t m, mci_ray_scratch *s, mci_label *label);

#endif
