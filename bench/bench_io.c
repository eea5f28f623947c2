/*
 * Mesh file reading benchmark. Builds a closed torus of 1,000,000 triangles in memory
 * (deterministic; the radii are jittered so that text coordinates need ~17 significant
 * digits), writes it as binary STL and as OBJ through the library's writers into a
 * directory (argument, default /tmp), then times mcsg_mesh_read on each file 5 times
 * and prints the median and minimum time and the triangle rate.
 *
 * Targets (Release build, 2 cores): binary STL <= 0.2 s, OBJ <= 0.8 s.
 *
 *   bench_io [directory] [--keep]     (--keep leaves the two files in place)
 */
#define _POSIX_C_SOURCE 200809L

#include "meshcsg.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RING_SEGMENTS 1000 /* around the torus axis */
#define TUBE_SEGMENTS 500  /* around the tube: 2 * 1000 * 500 = 1,000,000 triangles */
#define RUNS 5

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A small deterministic generator (splitmix64) giving doubles in [0, 1). */
static double next_unit(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static uint32_t grid_index(int i, int j)
{
    return (uint32_t)((i % RING_SEGMENTS) * TUBE_SEGMENTS + (j % TUBE_SEGMENTS));
}

/* The torus: vertex (i, j) at ring angle i and tube angle j, quads split in two,
 * oriented outward. Returns 0 on allocation failure. */
static int make_torus(mcsg_mesh *mesh)
{
    const double pi = 3.14159265358979323846;
    uint64_t state = 12345;
    size_t nv = (size_t)RING_SEGMENTS * TUBE_SEGMENTS, t = 0;
    mesh->vertices = malloc(3 * nv * sizeof(double));
    mesh->triangles = malloc(6 * nv * sizeof(uint32_t));
    if (!mesh->vertices || !mesh->triangles)
        return 0;
    mesh->vertex_count = nv;
    mesh->triangle_count = 2 * nv;
    for (int i = 0; i < RING_SEGMENTS; i++) {
        double theta = 2 * pi * i / RING_SEGMENTS;
        for (int j = 0; j < TUBE_SEGMENTS; j++) {
            double phi = 2 * pi * j / TUBE_SEGMENTS;
            double r = 3.0 * (1 + 0.01 * next_unit(&state));
            double ring = 10.0 + r * cos(phi);
            double *v = mesh->vertices + 3 * (size_t)grid_index(i, j);
            v[0] = ring * cos(theta);
            v[1] = ring * sin(theta);
            v[2] = r * sin(phi);
        }
    }
    for (int i = 0; i < RING_SEGMENTS; i++) {
        for (int j = 0; j < TUBE_SEGMENTS; j++, t += 2) {
            uint32_t a = grid_index(i, j), b = grid_index(i + 1, j);
            uint32_t c = grid_index(i + 1, j + 1), d = grid_index(i, j + 1);
            const uint32_t corners[6] = {a, b, c, a, c, d};
            memcpy(mesh->triangles + 3 * t, corners, sizeof corners);
        }
    }
    return 1;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Time RUNS reads of `path`; prints one result line. Returns 0 on a read error. */
static int time_reads(const char *label, const char *path, double target)
{
    double seconds[RUNS];
    size_t vertices = 0, triangles = 0;
    for (int run = 0; run < RUNS; run++) {
        mcsg_mesh mesh;
        mcsg_error err;
        double start = now_seconds();
        if (mcsg_mesh_read(path, MCSG_FORMAT_AUTO, NULL, &mesh, &err) != MCSG_OK) {
            fprintf(stderr, "bench_io: %s\n", err.message);
            return 0;
        }
        seconds[run] = now_seconds() - start;
        vertices = mesh.vertex_count;
        triangles = mesh.triangle_count;
        mcsg_mesh_free(&mesh, NULL);
    }
    qsort(seconds, RUNS, sizeof seconds[0], compare_doubles);
    printf("%-11s %zu triangles, %zu vertices: median %.3f s, min %.3f s, %.2f M "
           "triangles/s (target <= %.1f s: %s)\n",
           label, triangles, vertices, seconds[RUNS / 2], seconds[0],
           (double)triangles / seconds[RUNS / 2] / 1e6, target,
           seconds[RUNS / 2] <= target ? "met" : "MISSED");
    return 1;
}

static int write_file(const char *path, mcsg_format format, const mcsg_mesh *mesh)
{
    mcsg_error err;
    double start = now_seconds();
    if (mcsg_mesh_write(path, format, mesh, NULL, &err) != MCSG_OK) {
        fprintf(stderr, "bench_io: %s\n", err.message);
        return 0;
    }
    printf("wrote %s (%s) in %.2f s\n", path, mcsg_format_name(format), now_seconds() - start);
    return 1;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 && strcmp(argv[1], "--keep") != 0 ? argv[1] : "/tmp";
    int keep = strcmp(argv[argc - 1], "--keep") == 0;
    char stl_path[4096], obj_path[4096];
    mcsg_mesh torus = {NULL, NULL, 0, 0};
    int ok;
    snprintf(stl_path, sizeof stl_path, "%s/bench_io_torus.stl", dir);
    snprintf(obj_path, sizeof obj_path, "%s/bench_io_torus.obj", dir);
    if (!make_torus(&torus)) {
        fprintf(stderr, "bench_io: out of memory\n");
        return 1;
    }
    ok = write_file(stl_path, MCSG_FORMAT_STL_BINARY, &torus) &&
         write_file(obj_path, MCSG_FORMAT_OBJ, &torus);
    free(torus.vertices);
    free(torus.triangles);
    ok = ok && time_reads("binary STL", stl_path, 0.2) && time_reads("OBJ", obj_path, 0.8);
    if (!keep) {
        remove(stl_path);
        remove(obj_path);
    }
    return ok ? 0 : 1;
}
