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

/* The volume of the exact result of scene_ring_spheres(n, 1) for n = 100, 200, 400 and
 * 800, from reference.tsv of the shared generator (exact rational constructions, and a
 * second, independent evaluator agreeing to 1e-9 relative); 0 for other n. */
double scene_ring_spheres_reference_volume(int n);

#endif
