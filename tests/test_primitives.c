/*
 * Primitives: fragment counts (OpenSCAD's get_fragments_from_r), vertex and triangle
 * counts for many r/$fn/$fa/$fs combinations, exact coordinates against OpenSCAD's
 * formulas, closedness (every directed edge has exactly one twin), positive volume,
 * the empty cases, the size limit and allocation failures.
 */
#include "testlib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846
#define DEG2RAD 0.017453292519943295769
#define SQRT3_4 0.86602540378443859659
#define SQRT1_2 0.70710678118654752440

/* The formula, written out independently of the library. */
static int expected_fragments(double r, double fn, double fa, double fs)
{
    if (r < 0.00000095367431640625 || isinf(fn) || isnan(fn))
        return 3;
    if (fn > 0)
        return fn >= 3 ? (int)fn : 3;
    return (int)ceil(fmax(fmin(360.0 / fa, r * 2 * PI_D / fs), 5));
}

static int compare_edges(const void *pa, const void *pb)
{
    const uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return (a > b) - (a < b);
}

/* Every directed edge appears once and its reverse appears once. */
static bool is_closed(const mcsg_mesh *m)
{
    size_t n = 3 * m->triangle_count;
    uint64_t *edges = malloc((n ? n : 1) * sizeof *edges);
    bool ok = true;
    for (size_t t = 0; t < m->triangle_count; t++) {
        for (int k = 0; k < 3; k++) {
            uint64_t a = m->triangles[3 * t + k], b = m->triangles[3 * t + (k + 1) % 3];
            edges[3 * t + k] = a << 32 | b;
        }
    }
    qsort(edges, n, sizeof *edges, compare_edges);
    for (size_t i = 0; i < n && ok; i++) {
        uint64_t twin = (edges[i] & 0xFFFFFFFFu) << 32 | edges[i] >> 32;
        ok = (i + 1 >= n || edges[i + 1] != edges[i]) &&
             bsearch(&twin, edges, n, sizeof *edges, compare_edges) != NULL;
    }
    free(edges);
    return ok;
}

/* Closed, outward (positive volume), and valid for the library's own checker. */
static void check_solid(const mcsg_mesh *m, const char *what)
{
    mcsg_check_report report;
    mcsg_error err;
    CHECK_MSG(is_closed(m), "%s is not closed", what);
    CHECK_MSG(test_signed_volume(m) > 0, "%s has volume %g", what, test_signed_volume(m));
    CHECK_OK(mcsg_mesh_check(m, NULL, &report, &err), &err);
    CHECK_MSG(mcsg_check_report_is_valid(&report) && !report.inverted,
              "%s fails mcsg_mesh_check", what);
}

TEST(fragments_follow_openscad)
{
    static const double radii[] = {0.0000009, 0.00000095367431640625, 0.001, 0.5, 1, 3.3,
                                   10, 57.3, 1000};
    static const double fns[] = {0, -4, 1, 2.5, 3, 3.9, 7, 64, INFINITY, NAN};
    static const double fas[] = {12, 1, 5, 30, 0.5};
    static const double fss[] = {2, 0.1, 0.5, 7};
    for (size_t i = 0; i < sizeof radii / sizeof radii[0]; i++)
        for (size_t j = 0; j < sizeof fns / sizeof fns[0]; j++)
            for (size_t k = 0; k < sizeof fas / sizeof fas[0]; k++)
                for (size_t l = 0; l < sizeof fss / sizeof fss[0]; l++) {
                    int got = mcsg_fragments(radii[i], fns[j], fas[k], fss[l]);
                    int want = expected_fragments(radii[i], fns[j], fas[k], fss[l]);
                    CHECK_MSG(got == want, "fragments(%g, %g, %g, %g) = %d, want %d", radii[i],
                              fns[j], fas[k], fss[l], got, want);
                }
    CHECK_EQ_SIZE(mcsg_fragments(1, 0, 12, 2), 5);      /* defaults, small r: 5 */
    CHECK_EQ_SIZE(mcsg_fragments(10, 0, 12, 2), 30);    /* 360/12 */
    CHECK_EQ_SIZE(mcsg_fragments(5, 0, 12, 2), 16);     /* ceil(5*pi) */
    CHECK_EQ_SIZE(mcsg_fragments(1e-7, 100, 12, 2), 3); /* tiny radius */
    CHECK_EQ_SIZE(mcsg_fragments(1, 1, 12, 2), 3);      /* $fn = 1 */
    CHECK_EQ_SIZE(mcsg_fragments(1, 1e30, 12, 2), 2147483647); /* saturates, no UB */
    CHECK_EQ_SIZE(mcsg_fragments(1, 0, 0, 0), 2147483647);
}

static size_t sphere_triangles(size_t n) { return 2 * n * ((n + 1) / 2 - 1) + 2 * (n - 2); }

TEST(sphere_counts)
{
    static const double radii[] = {0.0000001, 0.3, 1, 2.5, 10, 40};
    static const double fns[] = {0, 1, 3, 4, 5, 6, 7, 8, 33, 64};
    static const mcsg_resolution resolutions[] = {{0, 12, 2}, {0, 3, 0.25}, {0, 45, 10}};
    for (size_t i = 0; i < sizeof radii / sizeof radii[0]; i++) {
        for (size_t j = 0; j < sizeof fns / sizeof fns[0]; j++) {
            for (size_t k = 0; k < 3; k++) {
                mcsg_resolution res = resolutions[k];
                mcsg_mesh m;
                mcsg_error err;
                size_t n;
                res.fn = fns[j];
                n = (size_t)mcsg_fragments(radii[i], res.fn, res.fa, res.fs);
                CHECK_OK(mcsg_make_sphere(radii[i], res, NULL, &m, &err), &err);
                CHECK_EQ_SIZE(m.vertex_count, n * ((n + 1) / 2));
                CHECK_EQ_SIZE(m.triangle_count, sphere_triangles(n));
                check_solid(&m, "sphere");
                mcsg_mesh_free(&m, NULL);
            }
        }
    }
}

TEST(cylinder_and_cone_counts)
{
    static const double radii[][2] = {{1, 1}, {2, 1}, {0.5, 3}, {1, 0}, {0, 4}, {10, 10},
                                      {1e-7, 1e-7}};
    static const double fns[] = {0, 1, 3, 5, 12, 31};
    for (size_t i = 0; i < sizeof radii / sizeof radii[0]; i++) {
        for (size_t j = 0; j < sizeof fns / sizeof fns[0]; j++) {
            for (int center = 0; center < 2; center++) {
                mcsg_resolution res = {fns[j], 12, 2};
                double r1 = radii[i][0], r2 = radii[i][1];
                size_t n = (size_t)mcsg_fragments(fmax(r1, r2), fns[j], 12, 2);
                bool cone = r1 == 0 || r2 == 0;
                mcsg_mesh m;
                mcsg_error err;
                CHECK_OK(mcsg_make_cylinder(3, r1, r2, center, res, NULL, &m, &err), &err);
                CHECK_EQ_SIZE(m.vertex_count, cone ? n + 1 : 2 * n);
                CHECK_EQ_SIZE(m.triangle_count, cone ? n + (n - 2) : 2 * n + 2 * (n - 2));
                check_solid(&m, cone ? "cone" : "cylinder");
                mcsg_mesh_free(&m, NULL);
            }
        }
    }
}

TEST(cube_counts_and_coordinates)
{
    const double size[3] = {1, 2, 3};
    mcsg_mesh m;
    mcsg_error err;
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &m, &err), &err);
    CHECK_EQ_SIZE(m.vertex_count, 8);
    CHECK_EQ_SIZE(m.triangle_count, 12);
    check_solid(&m, "cube");
    CHECK_EQ_DOUBLE(test_signed_volume(&m), 6);
    /* OpenSCAD's corner order: bit 0 is x, bit 1 is y, bit 2 is z. */
    CHECK_EQ_DOUBLE(m.vertices[3 * 7 + 0], 1);
    CHECK_EQ_DOUBLE(m.vertices[3 * 7 + 1], 2);
    CHECK_EQ_DOUBLE(m.vertices[3 * 7 + 2], 3);
    CHECK_EQ_DOUBLE(m.vertices[3 * 2 + 0], 0);
    CHECK_EQ_DOUBLE(m.vertices[3 * 2 + 1], 2);
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(mcsg_make_cube(size, 1, NULL, &m, &err), &err);
    CHECK_EQ_DOUBLE(m.vertices[0], -0.5);
    CHECK_EQ_DOUBLE(m.vertices[1], -1);
    CHECK_EQ_DOUBLE(m.vertices[2], -1.5);
    CHECK_EQ_DOUBLE(m.vertices[3 * 7 + 2], 1.5);
    check_solid(&m, "centred cube");
    mcsg_mesh_free(&m, NULL);
}

static void check_vertex(const mcsg_mesh *m, size_t i, double x, double y, double z)
{
    CHECK_MSG(i < m->vertex_count && m->vertices[3 * i] == x && m->vertices[3 * i + 1] == y &&
                  m->vertices[3 * i + 2] == z,
              "vertex %zu is (%.17g, %.17g, %.17g), want (%.17g, %.17g, %.17g)", i,
              m->vertices[3 * i], m->vertices[3 * i + 1], m->vertices[3 * i + 2], x, y, z);
}

/* Values from OpenSCAD's formulas: multiples of 30 and 45 degrees are exact. */
TEST(exact_sphere_coordinates)
{
    mcsg_resolution res = {4, 12, 2};
    mcsg_mesh m;
    mcsg_error err;
    /* $fn = 4: 2 rings at 45 and 135 degrees, radius and height sqrt(1/2). */
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &m, &err), &err);
    check_vertex(&m, 0, SQRT1_2, 0, SQRT1_2);
    check_vertex(&m, 1, 0, SQRT1_2, SQRT1_2);
    check_vertex(&m, 2, -SQRT1_2, 0, SQRT1_2);
    check_vertex(&m, 3, 0, -SQRT1_2, SQRT1_2);
    check_vertex(&m, 4, SQRT1_2, 0, -SQRT1_2);
    mcsg_mesh_free(&m, NULL);
    /* $fn = 6, r = 2: rings at 30, 90, 150 degrees; points every 60 degrees. */
    res.fn = 6;
    CHECK_OK(mcsg_make_sphere(2, res, NULL, &m, &err), &err);
    check_vertex(&m, 0, 1, 0, 2 * SQRT3_4);
    check_vertex(&m, 1, 1 * 0.5, 1 * SQRT3_4, 2 * SQRT3_4);
    check_vertex(&m, 6, 2, 0, 0);
    check_vertex(&m, 7, 2 * 0.5, 2 * SQRT3_4, 0);
    check_vertex(&m, 9, -2, 0, 0);
    check_vertex(&m, 12, 1, 0, -2 * SQRT3_4);
    mcsg_mesh_free(&m, NULL);
    /* $fn = 7: point 1 at 360/7 > 45 degrees, computed as sin((90 - phi) deg). */
    res.fn = 7;
    CHECK_OK(mcsg_make_sphere(3, res, NULL, &m, &err), &err);
    {
        double ring_phi = 180.0 * 0.5 / 4, phi = 360.0 / 7;
        double ring_r = 3 * sin(ring_phi * DEG2RAD), z = 3 * cos(ring_phi * DEG2RAD);
        check_vertex(&m, 1, ring_r * sin((90.0 - phi) * DEG2RAD), ring_r * cos((90.0 - phi) * DEG2RAD),
                     z);
    }
    mcsg_mesh_free(&m, NULL);
}

TEST(exact_cylinder_coordinates)
{
    mcsg_resolution res = {6, 12, 2};
    mcsg_mesh m;
    mcsg_error err;
    CHECK_OK(mcsg_make_cylinder(3, 2, 2, 0, res, NULL, &m, &err), &err);
    check_vertex(&m, 0, 2, 0, 0);
    check_vertex(&m, 1, 1, 2 * SQRT3_4, 0);
    check_vertex(&m, 3, -2, 0, 0);
    check_vertex(&m, 4, -1, -2 * SQRT3_4, 0);
    check_vertex(&m, 6, 2, 0, 3);
    mcsg_mesh_free(&m, NULL);
    /* A centred cone: apex at +h/2 is the last vertex. */
    CHECK_OK(mcsg_make_cylinder(4, 1, 0, 1, res, NULL, &m, &err), &err);
    check_vertex(&m, 0, 1, 0, -2);
    check_vertex(&m, 6, 0, 0, 2);
    mcsg_mesh_free(&m, NULL);
    /* An inverted cone: apex at z1 is vertex 0. */
    CHECK_OK(mcsg_make_cylinder(4, 0, 1, 0, res, NULL, &m, &err), &err);
    check_vertex(&m, 0, 0, 0, 0);
    check_vertex(&m, 1, 1, 0, 4);
    mcsg_mesh_free(&m, NULL);
}

TEST(empty_primitives)
{
    static const double sizes[][3] = {{0, 1, 1}, {1, -1, 1}, {1, 1, NAN}, {INFINITY, 1, 1}};
    static const double cylinders[][3] = {{0, 1, 1}, {-1, 1, 1}, {1, 0, 0}, {1, -1, 2},
                                          {1, 2, -0.5}, {INFINITY, 1, 1}, {1, NAN, 1}};
    static const double spheres[] = {0, -1, NAN, INFINITY};
    mcsg_resolution res = {0, 12, 2};
    mcsg_mesh m;
    mcsg_error err;
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        CHECK_OK(mcsg_make_cube(sizes[i], 0, NULL, &m, &err), &err);
        CHECK(m.vertex_count == 0 && m.triangle_count == 0 && !m.vertices && !m.triangles);
    }
    for (size_t i = 0; i < sizeof cylinders / sizeof cylinders[0]; i++) {
        CHECK_OK(mcsg_make_cylinder(cylinders[i][0], cylinders[i][1], cylinders[i][2], 0, res,
                                    NULL, &m, &err), &err);
        CHECK(m.vertex_count == 0 && m.triangle_count == 0);
    }
    for (size_t i = 0; i < sizeof spheres / sizeof spheres[0]; i++) {
        CHECK_OK(mcsg_make_sphere(spheres[i], res, NULL, &m, &err), &err);
        CHECK(m.vertex_count == 0 && m.triangle_count == 0);
    }
}

TEST(resolution_defaults_and_clamping)
{
    mcsg_resolution zero = {0, 0, 0}, tiny = {0, 0.001, 0.001};
    mcsg_mesh m;
    mcsg_error err;
    /* A zero fa or fs means OpenSCAD's default: r = 10 gives 360/12 = 30 fragments. */
    CHECK_OK(mcsg_make_sphere(10, zero, NULL, &m, &err), &err);
    CHECK_EQ_SIZE(m.vertex_count, 30 * 15);
    mcsg_mesh_free(&m, NULL);
    /* Below 0.01 both are clamped to 0.01: r = 1 gives ceil(2*pi/0.01) = 629. */
    CHECK_OK(mcsg_make_cylinder(1, 1, 1, 0, tiny, NULL, &m, &err), &err);
    CHECK_EQ_SIZE(m.vertex_count, 2 * 629);
    mcsg_mesh_free(&m, NULL);
}

TEST(too_many_fragments_is_a_limit)
{
    mcsg_resolution res = {1e6, 12, 2};
    mcsg_mesh m;
    mcsg_error err;
    CHECK(mcsg_make_sphere(1, res, NULL, &m, &err) == MCSG_ERR_LIMIT);
    CHECK_CONTAINS(err.message, "sphere");
    CHECK(m.vertices == NULL && m.vertex_count == 0);
    res.fn = 3e9;
    CHECK(mcsg_make_cylinder(1, 1, 1, 0, res, NULL, &m, &err) == MCSG_ERR_LIMIT);
}

/* Make the primitive named by `kind` ("sphere", "cylinder" or "cube") and free it. */
static mcsg_status make_primitive(const void *kind, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_resolution res = {8, 12, 2};
    const double size[3] = {1, 1, 1};
    mcsg_mesh m;
    mcsg_status st;
    if (strcmp(kind, "sphere") == 0)
        st = mcsg_make_sphere(1, res, opts, &m, err);
    else if (strcmp(kind, "cylinder") == 0)
        st = mcsg_make_cylinder(1, 1, 1, 0, res, opts, &m, err);
    else
        st = mcsg_make_cube(size, 0, opts, &m, err);
    if (st == MCSG_OK)
        mcsg_mesh_free(&m, opts);
    return st;
}

TEST(allocation_failures)
{
    /* A mesh needs two allocations: failing either gives NOMEM. */
    CHECK_EQ_SIZE(test_allocation_failures("sphere", make_primitive, "sphere", false), 2);
    CHECK_EQ_SIZE(test_allocation_failures("cylinder", make_primitive, "cylinder", false), 2);
    CHECK_EQ_SIZE(test_allocation_failures("cube", make_primitive, "cube", false), 2);
}

TEST(null_arguments)
{
    mcsg_resolution res = {0, 12, 2};
    mcsg_mesh m;
    mcsg_error err;
    CHECK(mcsg_make_cube(NULL, 0, NULL, &m, &err) == MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_make_sphere(1, res, NULL, NULL, &err) == MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_make_cylinder(1, 1, 1, 0, res, NULL, NULL, NULL) == MCSG_ERR_INVALID_ARG);
}

int main(void)
{
    RUN(fragments_follow_openscad);
    RUN(sphere_counts);
    RUN(cylinder_and_cone_counts);
    RUN(cube_counts_and_coordinates);
    RUN(exact_sphere_coordinates);
    RUN(exact_cylinder_coordinates);
    RUN(empty_primitives);
    RUN(resolution_defaults_and_clamping);
    RUN(too_many_fragments_is_a_limit);
    RUN(allocation_failures);
    RUN(null_arguments);
    return test_summary();
}
