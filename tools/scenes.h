/*
 * Built-in benchmark scenes, generated in memory. ring_spheres reproduces
 * ../shared/scenes/make_scenes.py bit for bit (same Mersenne Twister stream as Python's
 * random.Random(seed), same formulas in the same evaluation order), so its results can
 * be compared with reference.tsv.
 */
#ifndef MESHCSG_SCENES_H
#define MESHCSG_SCENES_H

#include "meshcsg.h"

/* Paper Fig. 15(a) / Table 2: a 40x20 torus (R=10, r=2.5), then n UV spheres of 10x10
 * segments alternately unioned and subtracted, as a left-deep tree n levels deep. */
mcsg_status scene_ring_spheres(int n, unsigned seed, const mcsg_options *opts,
                               mcsg_tree **out, mcsg_error *err);

#endif
