/*
 * Octree build and candidate pairs on the issue-4 benchmark scenes: the paper's ring with
 * 800 spheres (145.6K faces, built in memory exactly as ../shared/scenes generates it)
 * and cow100K / bunny100k against a rotated, shifted copy of themselves. Median of 5.
 */
#define _POSIX_C_SOURCE 200809L

#include "csg/octree.h"
#include "benchlib.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 5

/* The library defaults (src/csg/octree.c); MCSG_OCTREE_CELL_FACES overrides the cell size. */
static mci_octree_params params = {48, 14, NULL, NULL, NULL};

static void run(const char *name, const mcsg_mesh *const *leaves, size_t n)
{
    double build[RUNS], pairs_time[RUNS];
    size_t faces = 0, pair_count = 0;
    mci_octree tree;
    mci_ctx ctx;
    mcsg_error err;
    mci_ctx_init(&ctx, NULL);
    for (size_t i = 0; i < n; i++)
        faces += leaves[i]->triangle_count;
    for (int r = 0; r < RUNS; r++) {
        uint64_t *pairs;
        double t0 = bench_seconds(), t1, t2;
        if (mci_octree_build(&ctx, leaves, n, &params, &tree, &err) != MCSG_OK)
            bench_fail(&err);
        t1 = bench_seconds();
        if (mci_octree_candidate_pairs(&ctx, &tree, &pairs, &pair_count, &err) != MCSG_OK)
            bench_fail(&err);
        t2 = bench_seconds();
        build[r] = t1 - t0;
        pairs_time[r] = t2 - t1;
        mci_free(&ctx, pairs);
        if (r < RUNS - 1)
            mci_octree_free(&ctx, &tree);
    }
    printf("%-28s %8zu faces  build %.3f s  pairs %.3f s  cells %zu  depth %u  "
           "critical leaves %zu  face refs %zu  candidate pairs %zu\n",
           name, faces, bench_median(build, RUNS), bench_median(pairs_time, RUNS), tree.cell_count,
           tree.max_depth, tree.critical_leaf_cells, tree.face_id_count, pair_count);
    mci_octree_free(&ctx, &tree);
}

static void ring(int spheres)
{
    mcsg_tree *tree;
    size_t n;
    const mcsg_mesh **leaves = bench_ring_leaves(spheres, &tree, &n);
    char name[64];
    snprintf(name, sizeof name, "ring + %d spheres", spheres);
    run(name, leaves, n);
    free(leaves);
    mcsg_tree_free(tree);
}

static void model_minus_shifted(const char *shared, const char *model)
{
    char name[256];
    mcsg_mesh a, b;
    bench_model_and_shifted(shared, model, &a, &b);
    const mcsg_mesh *leaves[2] = {&a, &b};
    snprintf(name, sizeof name, "%s vs shifted copy", model);
    run(name, leaves, 2);
    mcsg_mesh_free(&a, NULL);
    mcsg_mesh_free(&b, NULL);
}

int main(void)
{
    const char *shared = getenv("MCSG_SHARED_DIR");
    if (getenv("MCSG_OCTREE_CELL_FACES"))
        params.max_cell_faces = (uint32_t)atoi(getenv("MCSG_OCTREE_CELL_FACES"));
    ring(100);
    ring(800);
    if (!shared) {
        fprintf(stderr, "MCSG_SHARED_DIR not set: skipping the model scenes\n");
        return 0;
    }
    model_minus_shifted(shared, "cow100K.obj");
    model_minus_shifted(shared, "bunny100k.obj");
    return 0;
}
