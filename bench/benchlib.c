/* Benchmark helpers (see benchlib.h). */
#define _POSIX_C_SOURCE 200809L

#include "benchlib.h"
#include "scenes.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

double bench_seconds(void)
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

double bench_median(double *v, size_t n)
{
    qsort(v, n, sizeof *v, compare_double);
    return v[n / 2];
}

void bench_fail(const mcsg_error *err)
{
    fprintf(stderr, "%s\n", err->message);
    exit(1);
}

const mcsg_mesh **bench_ring_leaves(int spheres, mcsg_tree **tree, size_t *count)
{
    mcsg_error err;
    const mcsg_mesh **leaves;
    if (scene_ring_spheres(spheres, 1, NULL, tree, &err) != MCSG_OK)
        bench_fail(&err);
    leaves = malloc(mcsg_tree_node_count(*tree) * sizeof *leaves);
    *count = 0;
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(*tree); id++)
        if (mcsg_tree_leaf_mesh(*tree, id))
            leaves[(*count)++] = mcsg_tree_leaf_mesh(*tree, id);
    return leaves;
}

void bench_model_and_shifted(const char *shared, const char *model, mcsg_mesh *a,
                             mcsg_mesh *b)
{
    char path[4096];
    mcsg_error err;
    const double c = 0.99875026039496628, s = 0.049979169270678331;
    double m[12] = {c, -s, 0, 0.07, s, c, 0, 0.04, 0, 0, 1, 0.03};
    snprintf(path, sizeof path, "%s/models/%s", shared, model);
    if (mcsg_mesh_read(path, MCSG_FORMAT_AUTO, NULL, a, &err) != MCSG_OK ||
        mcsg_mesh_copy(a, NULL, b, &err) != MCSG_OK)
        bench_fail(&err);
    mcsg_mesh_transform(b, m);
}
