/*
 * Octree build and candidate pairs on the issue-4 benchmark scenes: the paper's ring with
 * 800 spheres (145.6K faces, built in memory exactly as ../shared/scenes generates it)
 * and cow100K / bunny100k against a rotated, shifted copy of themselves. Median of 5.
 */
#define _POSIX_C_SOURCE 200809L

#include "octree.h"
#include "scenes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RUNS 5

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static mci_octree_params params = {24, 14};

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
        double t0 = now(), t1, t2;
        if (mci_octree_build(&ctx, leaves, n, &params, &tree, &err) != MCSG_OK) {
            fprintf(stderr, "%s\n", err.message);
            exit(1);
        }
        t1 = now();
        if (mci_octree_candidate_pairs(&ctx, &tree, &pairs, &pair_count, &err) != MCSG_OK) {
            fprintf(stderr, "%s\n", err.message);
            exit(1);
        }
        t2 = now();
        build[r] = t1 - t0;
        pairs_time[r] = t2 - t1;
        mci_free(&ctx, pairs);
        if (r < RUNS - 1)
            mci_octree_free(&ctx, &tree);
    }
    qsort(build, RUNS, sizeof build[0], compare_double);
    qsort(pairs_time, RUNS, sizeof pairs_time[0], compare_double);
    printf("%-28s %8zu faces  build %.3f s  pairs %.3f s  cells %zu  depth %u  "
           "critical leaves %zu  face refs %zu  candidate pairs %zu\n",
           name, faces, build[RUNS / 2], pairs_time[RUNS / 2], tree.cell_count,
           tree.max_depth, tree.critical_leaf_cells, tree.face_id_count, pair_count);
    mci_octree_free(&ctx, &tree);
}

static void ring(int spheres)
{
    mcsg_tree *tree;
    mcsg_error err;
    const mcsg_mesh **leaves;
    size_t n = 0;
    char name[64];
    if (scene_ring_spheres(spheres, 1, NULL, &tree, &err) != MCSG_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    leaves = malloc(mcsg_tree_node_count(tree) * sizeof *leaves);
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++)
        if (mcsg_tree_leaf_mesh(tree, id))
            leaves[n++] = mcsg_tree_leaf_mesh(tree, id);
    snprintf(name, sizeof name, "ring + %d spheres", spheres);
    run(name, leaves, n);
    free(leaves);
    mcsg_tree_free(tree);
}

static void model_minus_shifted(const char *shared, const char *model)
{
    char path[4096];
    mcsg_mesh a, b;
    mcsg_error err;
    /* A small rotation about z and a shift of a few percent of the model's size. */
    const double c = 0.99875026039496628, s = 0.049979169270678331;
    double m[12] = {c, -s, 0, 0.07, s, c, 0, 0.04, 0, 0, 1, 0.03};
    snprintf(path, sizeof path, "%s/models/%s", shared, model);
    if (mcsg_mesh_read(path, MCSG_FORMAT_AUTO, NULL, &a, &err) != MCSG_OK ||
        mcsg_mesh_copy(&a, NULL, &b, &err) != MCSG_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    mcsg_mesh_transform(&b, m);
    const mcsg_mesh *leaves[2] = {&a, &b};
    snprintf(path, sizeof path, "%s vs shifted copy", model);
    run(path, leaves, 2);
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
