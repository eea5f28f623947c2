/*
 * Evaluation of a CSG tree that has frames (mesh/tree.h): groups under a transform that
 * turns space are evaluated in their own coordinates first (csg/frames.c).
 */
#ifndef MESHCSG_CSG_FRAMES_H
#define MESHCSG_CSG_FRAMES_H

#include "base/core.h"

/* mcsg_eval for a tree with at least one frame: the same contract and outputs;
 * stats->frames_evaluated and seconds_frames tell the frames' part. When that result
 * breaks a guarantee, the tree is evaluated flattened too, and the result with fewer
 * defects is returned (stats->frames_flattened); so is the flattened one when the frames'
 * path fails other than for memory or a cancel. */
mcsg_status mci_eval_frames(const mcsg_tree *tree, const mcsg_options *opts, mcsg_mesh *out,
                            mcsg_provenance **provenance, mcsg_eval_stats *stats,
                            mcsg_error *err);

/* How far apart (along any axis) two points of `own` may be and still coincide once
 * mapped by m with mcsg_mesh_transform (every coordinate rounded): a proven bound from
 * the rounding error of the map and the norm of its inverse, or -1 when none is proven
 * (a map close to singular). The margin for mci_crossing_boxes (csg/shell_crossing.h). */
double mci_turn_margin(const double m[12], const mcsg_mesh *own);

/* mcsg_eval ignoring frames: every leaf as turned on its own (its flattened mesh). */
mcsg_status mci_eval_flattened(const mcsg_tree *tree, const mcsg_options *opts, mcsg_mesh *out,
                               mcsg_provenance **provenance, mcsg_eval_stats *stats,
                               mcsg_error *err);

#endif
