/*
 * mcsg_mesh_self_intersections: exact self-intersection test of a mesh. Valid closed
 * meshes (primitives, shared models, a sphere evaluated against a cube) have none;
 * a pushed-in vertex, boxes in one mesh touching other than in common vertices and edges
 * or overlapping, a fold and a repeated triangle are found.
 */
#include "testlib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static size_t self_pairs(const mcsg_mesh *m, uint32_t example[2])
{
    size_t pairs = 0;
    mcsg_error err;
    CHECK_OK(mcsg_mesh_self_intersections(m, NULL, &pairs, example, &err), &err);
    return pairs;
}

static void make_box(double x, double y, double z, double s, mcsg_mesh *out)
{
    mcsg_error err;
    double size[3] = {s, s, s}, m[12] = {1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z};
    CHECK_OK(mcsg_make_cube(size, 0, NULL, out, &err), &err);
    mcsg_mesh_transform(out, m);
}

/* Two meshes as one (indices of b shifted). */
static void join(const mcsg_mesh *a, const mcsg_mesh *b, mcsg_mesh *out)
{
    mcsg_error err;
    mcsg_mesh both = {0};
    size_t nv = a->vertex_count + b->vertex_count, nt = a->triangle_count + b->triangle_count;
    double *v = malloc(3 * nv * sizeof *v);
    uint32_t *t = malloc(3 * nt * sizeof *t);
    memcpy(v, a->vertices, 3 * a->vertex_count * sizeof *v);
    memcpy(v + 3 * a->vertex_count, b->vertices, 3 * b->vertex_count * sizeof *v);
    memcpy(t, a->triangles, 3 * a->triangle_count * sizeof *t);
    for (size_t i = 0; i < 3 * b->triangle_count; i++)
        t[3 * a->triangle_count + i] = b->triangles[i] + (uint32_t)a->vertex_count;
    both.vertices = v, both.triangles = t, both.vertex_count = nv, both.triangle_count = nt;
    CHECK_OK(mcsg_mesh_copy(&both, NULL, out, &err), &err);
    free(v);
    free(t);
}

TEST(valid_meshes_have_none)
{
    static const char *models[] = {"cube.obj", "sphere.obj", "spot.obj"};
    mcsg_mesh m;
    mcsg_error err;
    mcsg_resolution res = {24, 0, 0};
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &m, &err), &err);
    CHECK_EQ_SIZE(self_pairs(&m, NULL), 0);
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(mcsg_make_cylinder(2, 1, 0, 1, res, NULL, &m, &err), &err);
    CHECK_EQ_SIZE(self_pairs(&m, NULL), 0);
    mcsg_mesh_free(&m, NULL);
    for (size_t i = 0; i < sizeof models / sizeof *models; i++) {
        CHECK_OK(mcsg_mesh_read(test_model(models[i]), MCSG_FORMAT_AUTO, NULL, &m, &err), &err);
        CHECK_MSG(self_pairs(&m, NULL) == 0, "%s intersects itself", models[i]);
        mcsg_mesh_free(&m, NULL);
    }
    CHECK_OK(test_eval_scad("difference() { sphere(1, $fn = 20); cube(1); }", NULL, &m, NULL,
                            &err), &err);
    CHECK(m.triangle_count > 0);
    CHECK_EQ_SIZE(self_pairs(&m, NULL), 0);
    mcsg_mesh_free(&m, NULL);
}

TEST(pushed_in_vertex_crosses)
{
    mcsg_mesh m;
    uint32_t ex[2];
    make_box(0, 0, 0, 1, &m);
    /* Find the corner (1, 1, 1) and push it through the opposite corner's faces. */
    for (size_t v = 0; v < m.vertex_count; v++)
        if (m.vertices[3 * v] == 1 && m.vertices[3 * v + 1] == 1 && m.vertices[3 * v + 2] == 1)
            m.vertices[3 * v] = m.vertices[3 * v + 1] = m.vertices[3 * v + 2] = -0.5;
    CHECK(self_pairs(&m, ex) > 0);
    CHECK(ex[0] < ex[1] && ex[1] < m.triangle_count);
    mcsg_mesh_free(&m, NULL);
}

static size_t pairs_with_box_at(const mcsg_mesh *a, double x, double y, double z)
{
    mcsg_mesh b, both;
    size_t n;
    make_box(x, y, z, 1, &b);
    join(a, &b, &both);
    n = self_pairs(&both, NULL);
    mcsg_mesh_free(&b, NULL);
    mcsg_mesh_free(&both, NULL);
    return n;
}

/* Contact in common vertices or edges (same coordinates) is not an intersection: that
 * is non-manifold contact, which mcsg_mesh_check reports. Contact anywhere else is. */
TEST(touching_and_overlapping_boxes)
{
    mcsg_mesh a;
    make_box(0, 0, 0, 1, &a);
    CHECK_EQ_SIZE(pairs_with_box_at(&a, 1, 1, 1), 0); /* a common corner */
    CHECK_EQ_SIZE(pairs_with_box_at(&a, 1, 1, 0), 0); /* a common edge */
    CHECK(pairs_with_box_at(&a, 1, 1, 0.5) > 0);      /* edges overlapping along a segment */
    CHECK(pairs_with_box_at(&a, 1, 0.5, 0.5) > 0);    /* faces overlapping */
    CHECK(pairs_with_box_at(&a, 0.5, 0.25, 0.125) > 0); /* solids overlapping */
    CHECK_EQ_SIZE(pairs_with_box_at(&a, 2, 0, 0), 0); /* apart */
    CHECK_EQ_SIZE(pairs_with_box_at(&a, 1.0000000000000002, 0, 0), 0); /* one ulp apart */
    mcsg_mesh_free(&a, NULL);
}

TEST(fold_and_repeated_triangle)
{
    /* A flat "tetrahedron": four coplanar points, its triangles overlap pairwise. */
    static const double flat_v[] = {0, 0, 0, 4, 0, 0, 0, 4, 0, 1, 1, 0};
    static const uint32_t flat_t[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    static const uint32_t twice_t[] = {0, 1, 2, 0, 1, 2};
    mcsg_mesh flat = {(double *)flat_v, (uint32_t *)flat_t, 4, 4};
    mcsg_mesh twice = {(double *)flat_v, (uint32_t *)twice_t, 4, 2};
    CHECK(self_pairs(&flat, NULL) > 0);
    CHECK_EQ_SIZE(self_pairs(&twice, NULL), 1);
}

TEST(bad_arguments)
{
    static const double v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static const uint32_t t[] = {0, 1, 3};
    double nan_v[9];
    mcsg_mesh out_of_range = {(double *)v, (uint32_t *)t, 3, 1};
    mcsg_mesh empty = {0};
    size_t pairs = 7;
    mcsg_error err;
    memcpy(nan_v, v, sizeof nan_v);
    nan_v[4] = NAN;
    mcsg_mesh with_nan = {nan_v, (uint32_t *)t, 3, 1};
    static const uint32_t ok_t[] = {0, 1, 2};
    with_nan.triangles = (uint32_t *)ok_t;
    CHECK(mcsg_mesh_self_intersections(&out_of_range, NULL, &pairs, NULL, &err) ==
          MCSG_ERR_INVALID_MESH);
    CHECK(mcsg_mesh_self_intersections(&with_nan, NULL, &pairs, NULL, &err) ==
          MCSG_ERR_INVALID_MESH);
    CHECK_CONTAINS(err.message, "NaN");
    CHECK(mcsg_mesh_self_intersections(NULL, NULL, &pairs, NULL, &err) == MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_mesh_self_intersections(&empty, NULL, &pairs, NULL, &err) == MCSG_OK);
    CHECK_EQ_SIZE(pairs, 0);
}

static mcsg_status self_check_run(const void *ctx, const mcsg_options *opts, mcsg_error *err)
{
    size_t pairs;
    mcsg_status st = mcsg_mesh_self_intersections(ctx, opts, &pairs, NULL, err);
    CHECK(st != MCSG_OK || pairs == 0);
    return st;
}

TEST(allocation_failures)
{
    mcsg_mesh m;
    mcsg_error err;
    mcsg_resolution res = {8, 0, 0};
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &m, &err), &err);
    CHECK(test_allocation_failures("self-intersections", self_check_run, &m, false) > 0);
    mcsg_mesh_free(&m, NULL);
}

int main(void)
{
    RUN(valid_meshes_have_none);
    RUN(pushed_in_vertex_crosses);
    RUN(touching_and_overlapping_boxes);
    RUN(fold_and_repeated_triangle);
    RUN(bad_arguments);
    RUN(allocation_failures);
    return test_summary();
}
