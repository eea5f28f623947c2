/*
 * Vertices that carry no shape leave the result (csg/flat_vertices.c): results whose
 * fewest vertices are known come out with exactly those (a closed mesh of genus 0 with V
 * vertices has 2V - 4 triangles), the volume stays, provenance still names a face whose
 * plane holds the triangle, and mcsg_options.keep_all_vertices gives back every vertex.
 * (A closed mesh of genus g with V vertices has 2 V + 4 g - 4 triangles.)
 */
#include "testlib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct outcome {
    mcsg_mesh mesh;
    mcsg_provenance *provenance;
    mcsg_eval_stats stats;
    mcsg_check_report report;
    mcsg_tree *tree;
} outcome;

static bool evaluate(const char *text, bool keep_all, outcome *o)
{
    mcsg_options opts;
    mcsg_error err;
    memset(o, 0, sizeof *o);
    memset(&opts, 0, sizeof opts);
    opts.threads = 1;
    opts.keep_all_vertices = keep_all;
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "test.scad", ".", NULL, &o->tree, &err),
             &err);
    if (!o->tree)
        return false;
    mcsg_status st = mcsg_eval(o->tree, &opts, &o->mesh, &o->provenance, &o->stats, &err);
    CHECK_MSG(st == MCSG_OK, "%s: %s", text, err.message);
    if (st != MCSG_OK)
        return false;
    CHECK_OK(mcsg_mesh_check(&o->mesh, NULL, &o->report, &err), &err);
    CHECK_MSG(mcsg_check_report_is_valid(&o->report) && !o->report.inverted,
              "%s: not closed, oriented and manifold once welded", text);
    CHECK_MSG(test_index_manifold_defects(&o->mesh) == 0, "%s: not manifold by index", text);
    CHECK(!mcsg_output_check_failed(&o->stats.output_check));
    return true;
}

static void release(outcome *o)
{
    mcsg_mesh_free(&o->mesh, NULL);
    free(o->provenance);
    mcsg_tree_free(o->tree);
}

/* The result (of genus `genus`) has exactly `vertices` vertices, hence 2 V + 4 g - 4
 * triangles, the volume of the result that keeps every vertex, and that one has
 * `all_vertices`. */
static void expect_fewest(const char *text, size_t genus, size_t vertices, size_t all_vertices)
{
    outcome lean, all;
    if (!evaluate(text, false, &lean) || !evaluate(text, true, &all))
        return;
    CHECK_MSG(lean.mesh.vertex_count == vertices, "%s: %zu vertices, expected %zu", text,
              lean.mesh.vertex_count, vertices);
    CHECK_EQ_SIZE(lean.mesh.triangle_count, 2 * vertices + 4 * genus - 4);
    CHECK_EQ_SIZE(lean.stats.output_triangles, lean.mesh.triangle_count);
    CHECK_EQ_SIZE(lean.stats.flat_vertices_removed, all.mesh.vertex_count - vertices);
    CHECK_MSG(all.mesh.vertex_count == all_vertices, "%s: %zu vertices kept, expected %zu",
              text, all.mesh.vertex_count, all_vertices);
    CHECK_EQ_SIZE(all.stats.flat_vertices_removed, 0);
    CHECK_MSG(fabs(lean.report.volume - all.report.volume) <= 1e-12 * fabs(all.report.volume),
              "%s: volume %.17g against %.17g", text, lean.report.volume, all.report.volume);
    release(&lean);
    release(&all);
}

TEST(cube_minus_cylinder_keeps_only_its_corners)
{
    /* 8 corners and 2 x 64 on the circles; the diagonals of the cylinder's side quads
     * met the cube's faces at 128 more points, on straight edges of the result */
    expect_fewest("difference() { cube(10, center = true); "
                  "cylinder(h = 20, r = 3, center = true, $fn = 64); }",
                  1, 136, 264);
}

TEST(boxes_side_by_side_are_one_box)
{
    expect_fewest("union() { cube([10, 10, 10]); translate([10, 0, 0]) cube([10, 10, 10]); }",
                  0, 8, 12);
    expect_fewest("union() { cube([10, 10, 10]); translate([5, 0, 0]) cube([10, 10, 10]); }",
                  0, 8, 24);
}

TEST(a_groove_and_a_step_keep_their_corners)
{
    expect_fewest("difference() { cube([10, 10, 10]); "
                  "translate([3, -1, 7]) cube([4, 12, 4]); }",
                  0, 16, 24);
    expect_fewest("union() { cube([10, 10, 10]); translate([2, 2, 10]) cube([6, 6, 6]); }", 0,
                  16, 16);
}

/* Twice the area of triangle t's projection along the axis where face f's normal is
 * largest, signed, over the face's (a cosine-like ratio: 1 when they face the same way
 * in one plane). */
static double facing_ratio(const mcsg_mesh *m, uint32_t t, const mcsg_mesh *leaf, uint32_t f)
{
    const double *a = leaf->vertices + 3 * (size_t)leaf->triangles[3 * f];
    const double *b = leaf->vertices + 3 * (size_t)leaf->triangles[3 * f + 1];
    const double *c = leaf->vertices + 3 * (size_t)leaf->triangles[3 * f + 2];
    const double *p = m->vertices + 3 * (size_t)m->triangles[3 * t];
    const double *q = m->vertices + 3 * (size_t)m->triangles[3 * t + 1];
    const double *r = m->vertices + 3 * (size_t)m->triangles[3 * t + 2];
    double n[3], u[3], len_n = 0, len_u = 0, dot = 0;
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        n[k] = (b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]);
        u[k] = (q[i] - p[i]) * (r[j] - p[j]) - (q[j] - p[j]) * (r[i] - p[i]);
    }
    for (int k = 0; k < 3; k++) {
        len_n += n[k] * n[k];
        len_u += u[k] * u[k];
        dot += n[k] * u[k];
    }
    return dot / sqrt(len_n * len_u);
}

/* Distance of point p from face f's plane, over the face's size. */
static double off_plane(const double *p, const mcsg_mesh *leaf, uint32_t f)
{
    const double *a = leaf->vertices + 3 * (size_t)leaf->triangles[3 * f];
    const double *b = leaf->vertices + 3 * (size_t)leaf->triangles[3 * f + 1];
    const double *c = leaf->vertices + 3 * (size_t)leaf->triangles[3 * f + 2];
    double n[3], len = 0, d = 0;
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        n[k] = (b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]);
    }
    for (int k = 0; k < 3; k++) {
        len += n[k] * n[k];
        d += n[k] * (p[k] - a[k]);
    }
    return fabs(d) / sqrt(len);
}

TEST(provenance_names_a_face_holding_the_triangle)
{
    const char *text = "difference() { union() { cube(10, center = true); "
                       "translate([5, 0, 0]) cube(10, center = true); } "
                       "cylinder(h = 20, r = 3, center = true, $fn = 48); }";
    outcome o;
    size_t subtracted = 0;
    if (!evaluate(text, false, &o))
        return;
    CHECK(o.stats.flat_vertices_removed > 0);
    for (uint32_t t = 0; t < o.mesh.triangle_count; t++) {
        const mcsg_mesh *leaf = mcsg_tree_leaf_mesh(o.tree, o.provenance[t].leaf);
        uint32_t f = o.provenance[t].face;
        /* the cylinder is subtracted: its faces face the other way in the result */
        bool cylinder = leaf->triangle_count != 12;
        double ratio = facing_ratio(&o.mesh, t, leaf, f);
        subtracted += cylinder;
        CHECK_MSG(fabs(ratio - (cylinder ? -1.0 : 1.0)) < 1e-9,
                  "triangle %u faces %.17g against its face %u", t, ratio, f);
        for (int k = 0; k < 3; k++) {
            const double *corner = o.mesh.vertices + 3 * (size_t)o.mesh.triangles[3 * t + k];
            CHECK(off_plane(corner, leaf, f) < 1e-12);
        }
    }
    CHECK(subtracted == 96); /* the cylinder's 48 side quads, two triangles each */
    release(&o);
}

/* The smallest angle of the output, in degrees, and the triangles under one degree. */
static double smallest_angle(const mcsg_mesh *m, size_t *needles)
{
    double smallest = 180;
    *needles = 0;
    for (size_t t = 0; t < m->triangle_count; t++) {
        double least = 180;
        for (int k = 0; k < 3; k++) {
            const double *a = m->vertices + 3 * (size_t)m->triangles[3 * t + k];
            const double *b = m->vertices + 3 * (size_t)m->triangles[3 * t + (k + 1) % 3];
            const double *c = m->vertices + 3 * (size_t)m->triangles[3 * t + (k + 2) % 3];
            double u[3], v[3], dot = 0, cross[3], len = 0;
            for (int i = 0; i < 3; i++)
                u[i] = b[i] - a[i], v[i] = c[i] - a[i];
            for (int i = 0; i < 3; i++) {
                cross[i] = u[(i + 1) % 3] * v[(i + 2) % 3] - u[(i + 2) % 3] * v[(i + 1) % 3];
                dot += u[i] * v[i];
                len += cross[i] * cross[i];
            }
            double angle = atan2(sqrt(len), dot) * 180 / 3.14159265358979323846;
            least = angle < least ? angle : least;
        }
        *needles += least < 1;
        smallest = least < smallest ? least : smallest;
    }
    return smallest;
}

TEST(stats_report_the_triangles_angles)
{
    outcome o;
    size_t needles;
    if (!evaluate("difference() { cube(10, center = true); "
                  "cylinder(h = 20, r = 3, center = true, $fn = 64); }",
                  false, &o))
        return;
    double smallest = smallest_angle(&o.mesh, &needles);
    CHECK_MSG(fabs(o.stats.output_smallest_angle - smallest) < 1e-9 * (1 + smallest),
              "smallest angle %.17g, measured %.17g", o.stats.output_smallest_angle, smallest);
    CHECK_EQ_SIZE(o.stats.output_needles, needles);
    CHECK(smallest > 0);
    release(&o);
}

int main(void)
{
    RUN(cube_minus_cylinder_keeps_only_its_corners);
    RUN(boxes_side_by_side_are_one_box);
    RUN(a_groove_and_a_step_keep_their_corners);
    RUN(provenance_names_a_face_holding_the_triangle);
    RUN(stats_report_the_triangles_angles);
    return test_summary();
}
