/*
 * The whole intersection stage on the benchmark scenes: octree, candidate
 * pairs, exact triangle-triangle intersection, per-face arrangements, numbering of all
 * points, and the triangulation of every touched face with all its constraints. Scenes
 * as in bench_octree (the ring built in memory exactly as ../shared/scenes does; a
 * model against a rotated, shifted copy). One core, median of 5 per step.
 */
#define _POSIX_C_SOURCE 200809L

#include "csg/intersect.h"
#include "benchlib.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 5
#define STEPS 7

static const char *step_names[STEPS] = {"octree", "pairs", "tri-tri", "arrange", "number",
                                        "triangulate", "total"};

/* One run; fills the step times and, on the last run, the counts. */
static void run_once(const mcsg_mesh *const *leaves, size_t n, double t[STEPS],
                     mci_scene *keep)
{
    mci_ctx ctx;
    mci_scene s;
    mcsg_error err;
    double t0 = bench_seconds(), t1, t2;
    mci_ctx_init(&ctx, NULL);
    if (mci_scene_build(&ctx, leaves, n, &s, &err) != MCSG_OK)
        bench_fail(&err);
    t1 = bench_seconds();
    if (mci_scene_number_points(&ctx, &s, &err) != MCSG_OK)
        bench_fail(&err);
    t2 = bench_seconds();
    for (size_t k = 0; k < s.arr_count; k++)
        if (mci_arr_triangulate(&ctx, &s.arrs[k], NULL, &err) != MCSG_OK)
            bench_fail(&err);
    t[0] = s.stats.seconds_octree;
    t[1] = s.stats.seconds_pairs;
    t[2] = s.stats.seconds_intersect;
    t[3] = s.stats.seconds_arrange;
    t[4] = t2 - t1;
    t[5] = bench_seconds() - t2;
    t[6] = bench_seconds() - t0;
    if (keep)
        *keep = s;
    else
        mci_scene_free(&ctx, &s);
}

static void run(const char *name, const mcsg_mesh *const *leaves, size_t n)
{
    double times[STEPS][RUNS];
    mci_scene s;
    mci_ctx ctx;
    size_t tris = 0;
    mci_ctx_init(&ctx, NULL);
    for (int r = 0; r < RUNS; r++) {
        double t[STEPS];
        run_once(leaves, n, t, r == RUNS - 1 ? &s : NULL);
        for (int k = 0; k < STEPS; k++)
            times[k][r] = t[k];
    }
    for (size_t k = 0; k < s.arr_count; k++)
        tris += s.arrs[k].tri_count;
    printf("%s: %zu faces, %zu candidate pairs, %zu crossing pairs, %zu coplanar, "
           "%zu arranged faces, %zu points, %zu sub-triangles\n ", name, s.face_count,
           s.stats.candidate_pairs, s.stats.intersecting_pairs, s.stats.coplanar_pairs,
           s.arr_count, s.point_count, tris);
    for (int k = 0; k < STEPS; k++)
        printf(" %s %.3f s", step_names[k], bench_median(times[k], RUNS));
    printf("\n");
    mci_scene_free(&ctx, &s);
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

static void model_vs_shifted(const char *shared, const char *model)
{
    char name[256];
    mcsg_mesh a, b;
    bench_model_and_shifted(shared, model, &a, &b);
    const mcsg_mesh *leaves[2] = {&a, &b}, *same[2] = {&a, &a};
    snprintf(name, sizeof name, "%s vs shifted copy", model);
    run(name, leaves, 2);
    snprintf(name, sizeof name, "%s vs itself", model);
    run(name, same, 2);
    mcsg_mesh_free(&a, NULL);
    mcsg_mesh_free(&b, NULL);
}

int main(void)
{
    const char *shared = getenv("MCSG_SHARED_DIR");
    ring(100);
    ring(800);
    if (!shared) {
        fprintf(stderr, "MCSG_SHARED_DIR not set: skipping the model scenes\n");
        return 0;
    }
    model_vs_shifted(shared, "cow100K.obj");
    model_vs_shifted(shared, "bunny100k.obj");
    return 0;
}
