/*
 * The whole intersection stage (issue 4) on the benchmark scenes: octree, candidate
 * pairs, exact triangle-triangle intersection, per-face arrangements, numbering of all
 * points, and the triangulation of every touched face with all its constraints. Scenes
 * as in bench_octree (the ring built in memory exactly as ../shared/scenes does; a
 * model against a rotated, shifted copy). One core, median of 5 per step.
 */
#define _POSIX_C_SOURCE 200809L

#include "scene.h"
#include "scenes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RUNS 5
#define STEPS 7

static const char *step_names[STEPS] = {"octree", "pairs", "tri-tri", "arrange", "number",
                                        "triangulate", "total"};

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

static void fail(const mcsg_error *err)
{
    fprintf(stderr, "%s\n", err->message);
    exit(1);
}

/* One run; fills the step times and, on the last run, the counts. */
static void run_once(const mcsg_mesh *const *leaves, size_t n, double t[STEPS],
                     mci_scene *keep)
{
    mci_ctx ctx;
    mci_scene s;
    mcsg_error err;
    double t0 = now(), t1, t2;
    mci_ctx_init(&ctx, NULL);
    if (mci_scene_build(&ctx, leaves, n, &s, &err) != MCSG_OK)
        fail(&err);
    t1 = now();
    if (mci_scene_number_points(&ctx, &s, &err) != MCSG_OK)
        fail(&err);
    t2 = now();
    for (size_t k = 0; k < s.arr_count; k++)
        if (mci_arr_triangulate(&ctx, &s.arrs[k], NULL, &err) != MCSG_OK)
            fail(&err);
    t[0] = s.stats.seconds_octree;
    t[1] = s.stats.seconds_pairs;
    t[2] = s.stats.seconds_intersect;
    t[3] = s.stats.seconds_arrange;
    t[4] = t2 - t1;
    t[5] = now() - t2;
    t[6] = now() - t0;
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
    for (int k = 0; k < STEPS; k++) {
        qsort(times[k], RUNS, sizeof times[k][0], compare_double);
        printf(" %s %.3f s", step_names[k], times[k][RUNS / 2]);
    }
    printf("\n");
    mci_scene_free(&ctx, &s);
}

static void ring(int spheres)
{
    mcsg_tree *tree;
    mcsg_error err;
    const mcsg_mesh **leaves;
    size_t n = 0;
    char name[64];
    if (scene_ring_spheres(spheres, 1, NULL, &tree, &err) != MCSG_OK)
        fail(&err);
    leaves = malloc(mcsg_tree_node_count(tree) * sizeof *leaves);
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++)
        if (mcsg_tree_leaf_mesh(tree, id))
            leaves[n++] = mcsg_tree_leaf_mesh(tree, id);
    snprintf(name, sizeof name, "ring + %d spheres", spheres);
    run(name, leaves, n);
    free(leaves);
    mcsg_tree_free(tree);
}

static void model_vs_shifted(const char *shared, const char *model)
{
    char path[4096];
    mcsg_mesh a, b;
    mcsg_error err;
    const double c = 0.99875026039496628, s = 0.049979169270678331;
    double m[12] = {c, -s, 0, 0.07, s, c, 0, 0.04, 0, 0, 1, 0.03};
    snprintf(path, sizeof path, "%s/models/%s", shared, model);
    if (mcsg_mesh_read(path, MCSG_FORMAT_AUTO, NULL, &a, &err) != MCSG_OK ||
        mcsg_mesh_copy(&a, NULL, &b, &err) != MCSG_OK)
        fail(&err);
    mcsg_mesh_transform(&b, m);
    const mcsg_mesh *leaves[2] = {&a, &b};
    snprintf(path, sizeof path, "%s vs shifted copy", model);
    run(path, leaves, 2);
    const mcsg_mesh *same[2] = {&a, &a};
    snprintf(path, sizeof path, "%s vs itself", model);
    run(path, same, 2);
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
