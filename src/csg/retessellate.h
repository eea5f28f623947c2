/*
 * Output tessellation of a classified face (csg/retessellate.c, paper §5.4).
 */
#ifndef MESHCSG_CSG_RETESSELLATE_H
#define MESHCSG_CSG_RETESSELLATE_H

#include "csg/arrange.h"

/* After classification: piece_keep[t] says whether triangle t of the current
 * tessellation (all constraints) belongs to the result. Re-tessellates with only the
 * constraints between kept and dropped triangles (when that drops any) and writes to
 * tri_keep the flags of the triangles now in arr->tris: there are never more of them
 * than before, so tri_keep needs room for arr->tri_count flags as on entry. */
mcsg_status mci_arr_retessellate(const mci_ctx *ctx, mci_face_arr *arr,
                                 const uint8_t *piece_keep, uint8_t *tri_keep,
                                 mcsg_error *err);

#endif
