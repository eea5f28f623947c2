/*
 * Faces dropped whole, decided before they are split (see whole_faces.c).
 */
#ifndef MESHCSG_CSG_WHOLE_FACES_H
#define MESHCSG_CSG_WHOLE_FACES_H

#include "csg/csgtree.h"
#include "csg/intersect.h"

/* Marks in scene->arr_dropped (allocated here, one flag per arrangement) the touched
 * faces that the result drops entirely: their labels with respect to the leaves whose
 * surfaces they do not meet already reject them, whatever the other labels are. Works on
 * a scene whose faces are not arranged yet (mci_scene_build_touched); the flagged faces
 * then need no arrangement (mci_scene_arrange gives them their corners only), no
 * tessellation and no classification of their pieces. *count receives the number
 * flagged. keep (NULL: not wanted) has a zeroed entry per leaf, where the leaves' trimmed
 * lists are handed on (mci_classifier.trimmed) when made; the caller frees them
 * (mci_trimmed_lists_clear). */
mcsg_status mci_decide_whole_faces(const mci_ctx *ctx, mci_scene *scene, const mci_ptree *tree,
                                   size_t *count, mci_trimmed_list *keep, mcsg_error *err);

#endif
