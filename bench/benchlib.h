/*
 * Helpers shared by the benchmarks: a monotonic clock, medians, and the benchmark
 * scenes (the paper's ring with N spheres built in memory, a shared model with a
 * rotated and shifted copy of itself).
 */
#ifndef MCSG_BENCHLIB_H
#define MCSG_BENCHLIB_H

#include "meshcsg.h"

#include <stddef.h>

double bench_seconds(void);

/* The median of v[0..n) (sorts v). */
double bench_median(double *v, size_t n);

/* Print the message and exit: benchmarks stop at the first failure. */
void bench_fail(const mcsg_error *err);

/* The ring with `spheres` spheres, exactly as ../shared/scenes generates it: the tree
 * and its leaf meshes (malloc'ed array; free it, then mcsg_tree_free). */
const mcsg_mesh **bench_ring_leaves(int spheres, mcsg_tree **tree, size_t *count);

/* ../shared/models/<model> in *a, and in *b a copy rotated by 0.05 rad about z and
 * shifted by (0.07, 0.04, 0.03). */
void bench_model_and_shifted(const char *shared, const char *model, mcsg_mesh *a,
                             mcsg_mesh *b);

#endif
