/*
 * Degenerate-case corpus, first part: scenes built to hit the special
 * cases of exact CSG, each with its expected volume (exact where the geometry allows,
 * otherwise an identity that must hold: |A u B| + |A n B| = |A| + |B|, independence of
 * operand order, scaling by s^3). Every output must be closed, consistently oriented,
 * free of zero-area triangles and manifold by vertex index.
 */
#include "testlib.h"

#include <float.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int outputs, self_intersecting_outputs; /* after rounding to doubles (reported) */

typedef struct outcome {
    mcsg_mesh mesh;
    mcsg_check_report report;
    mcsg_eval_stats stats;
    double volume;
} outcome;

/* Evaluate and check topology; `touching` allows edges shared by touching parts. */
static bool solid(const char *text, bool touching, outcome *o)
{
    mcsg_error err;
    mcsg_status st = test_eval_scad(text, NULL, &o->mesh, &o->stats, &err);
    CHECK_MSG(st == MCSG_OK, "%s: %s", text, err.message);
    if (st != MCSG_OK)
        return false;
    CHECK_OK(mcsg_mesh_check(&o->mesh, NULL, &o->report, &err), &err);
    o->volume = test_signed_volume(&o->mesh);
    CHECK_MSG(o->report.boundary_edges == 0 && o->report.inconsistent_edges == 0 &&
                  o->report.degenerate_triangles == 0 && o->report.duplicate_triangles == 0 &&
                  (touching || o->report.nonmanifold_edges == 0),
              "%s: %zu boundary, %zu inconsistent, %zu non-manifold edges, %zu degenerate, "
              "%zu duplicate triangles", text, o->report.boundary_edges,
              o->report.inconsistent_edges, o->report.nonmanifold_edges,
              o->report.degenerate_triangles, o->report.duplicate_triangles);
    CHECK_MSG(test_index_manifold_defects(&o->mesh) == 0 || o->report.nonmanifold_edges > 0,
              "%s: not manifold by index", text);
    if (o->mesh.triangle_count > 0) {
        size_t pairs;
        CHECK_OK(mcsg_mesh_self_intersections(&o->mesh, NULL, &pairs, NULL, &err), &err);
        outputs++;
        self_intersecting_outputs += pairs > 0;
    }
    return true;
}

static double volume_touching(const char *text, bool touching)
{
    outcome o;
    double v = NAN;
    if (solid(text, touching, &o)) {
        v = o.volume;
        mcsg_mesh_free(&o.mesh, NULL);
    }
    return v;
}

static double volume_of(const char *text) { return volume_touching(text, false); }

static void expect_volume(const char *text, double expected, double rel)
{
    double v = volume_of(text);
    CHECK_MSG(fabs(v - expected) <= rel * fabs(expected) + 1e-300, "%s: volume %.17g, expected "
              "%.17g", text, v, expected);
}

/* |A u B| + |A n B| = |A| + |B| for two operand texts. */
static void expect_identity(const char *a, const char *b, double rel)
{
    char u[4096], n[4096];
    double va = volume_of(a), vb = volume_of(b), vu, vn;
    snprintf(u, sizeof u, "union() { %s %s }", a, b);
    snprintf(n, sizeof n, "intersection() { %s %s }", a, b);
    vu = volume_of(u);
    vn = volume_of(n);
    CHECK_MSG(fabs(vu + vn - va - vb) <= rel * (va + vb), "%s | %s: %.17g + %.17g vs %.17g + "
              "%.17g", a, b, vu, vn, va, vb);
}

TEST(coplanar_faces_stacked_and_offset)
{
    expect_volume("union() { cube(1); translate([0,0,1]) cube(1); translate([0,0,2]) cube(1); }",
                  3, 1e-15);
    expect_volume("union() { cube(2); translate([1,0,0]) cube(2); }", 12, 1e-15);
    expect_volume("union() { cube(2); translate([1,1,0]) cube(2); translate([0.5,0.5,2])"
                  " cube(2); }", 22, 1e-15);
    expect_volume("difference() { cube(2); translate([1,0,0]) cube(2); }", 4, 1e-15);
    expect_volume("intersection() { cube(2); translate([1,1,0]) cube(2); }", 2, 1e-15);
    /* A face offset by half a face on the top of another. */
    expect_volume("union() { cube([2,2,1]); translate([1,1,1]) cube([2,2,1]); }", 8, 1e-15);
}

TEST(identical_operands_three_times)
{
    const char *s = "sphere(1, $fn=24);";
    double v = volume_of(s);
    char text[512];
    snprintf(text, sizeof text, "union() { %s %s %s }", s, s, s);
    expect_volume(text, v, 1e-15);
    snprintf(text, sizeof text, "intersection() { %s %s %s }", s, s, s);
    expect_volume(text, v, 1e-15);
    snprintf(text, sizeof text, "difference() { %s %s %s }", s, s, s);
    expect_volume(text, 0, 0);
    snprintf(text, sizeof text, "difference() { union() { %s %s } %s }", s, s, s);
    expect_volume(text, 0, 0);
}

TEST(copies_moved_by_an_ulp_or_rotated_by_1e_7)
{
    char text[512];
    double ulp = DBL_EPSILON; /* one ulp at 1: the box [eps, 1 + eps] */
    snprintf(text, sizeof text, "difference() { cube(1); translate([%.17g,0,0]) cube(1); }", ulp);
    expect_volume(text, ulp, 1e-9);
    snprintf(text, sizeof text, "union() { cube(1); translate([%.17g,0,0]) cube(1); }", ulp);
    expect_volume(text, 1 + ulp, 1e-15);
    /* Rotated by 1e-7 rad (5.73e-6 degrees) about a skew axis: thin wedges everywhere. */
    expect_identity("sphere(1, $fn=16);",
                    "rotate(a=5.729577951308232e-6, v=[1,2,3]) sphere(1, $fn=16);", 1e-12);
    expect_identity("cube(1, center=true);",
                    "rotate(a=5.729577951308232e-6, v=[0,0,1]) cube(1, center=true);", 1e-12);
}

TEST(needles_and_slivers)
{
    /* A needle cylinder (radius 1e-6) through a box, and a sliver box 1e-9 thick. */
    expect_identity("cube(2, center=true);", "cylinder(h=3, r=1e-6, center=true, $fn=5);", 1e-12);
    expect_identity("cube(2, center=true);",
                    "translate([0,0,1-1e-9]) cube([1,1,1], center=false);", 1e-12);
    expect_volume("difference() { cube(1); translate([-1,-1,1e-9]) cube(3); }", 1e-9, 1e-6);
}

TEST(fans_of_cylinders_through_one_axis)
{
    char text[4096];
    size_t n = 0;
    double forward, backward;
    n += (size_t)snprintf(text + n, sizeof text - n, "union() {");
    for (int i = 0; i < 12; i++)
        n += (size_t)snprintf(text + n, sizeof text - n,
                              " rotate([0,0,%d]) rotate([0,90,0]) cylinder(h=4, r=0.5,"
                              " center=true, $fn=12);", 15 * i);
    snprintf(text + n, sizeof text - n, " }");
    forward = volume_of(text);
    n = 0;
    n += (size_t)snprintf(text + n, sizeof text - n, "union() {");
    for (int i = 11; i >= 0; i--)
        n += (size_t)snprintf(text + n, sizeof text - n,
                              " rotate([0,0,%d]) rotate([0,90,0]) cylinder(h=4, r=0.5,"
                              " center=true, $fn=12);", 15 * i);
    snprintf(text + n, sizeof text - n, " }");
    backward = volume_of(text);
    CHECK_MSG(fabs(forward - backward) <= 1e-12 * forward, "%.17g vs %.17g", forward,
              backward);
    CHECK(forward > 0 && forward < 12 * 4 * 3.1416 * 0.25);
}

TEST(scales_and_far_from_the_origin)
{
    const char *pattern =
        "translate([%.17g,%.17g,%.17g]) scale(%.17g) difference() { union() { cube(2);"
        " translate([1,1,1]) sphere(1, $fn=12); } rotate([10,20,30]) cylinder(h=5,"
        " r=0.4, center=true, $fn=9); }";
    double scales[3] = {1e-4, 1, 1e5}, base = 0;
    char text[1024];
    for (int i = 0; i < 3; i++) {
        double v;
        snprintf(text, sizeof text, pattern, 0.0, 0.0, 0.0, scales[i]);
        v = volume_of(text) / (scales[i] * scales[i] * scales[i]);
        if (i == 0)
            base = v;
        CHECK_MSG(fabs(v - base) <= 1e-9 * base, "scale %g: %.17g vs %.17g", scales[i], v,
                  base);
    }
    snprintf(text, sizeof text, pattern, 1e6, 1e6, 1e6, 1.0);
    CHECK_MSG(fabs(volume_of(text) - base) <= 1e-6 * base, "centre at 1e6: %.17g vs %.17g",
              volume_of(text), base);
}

/* n spheres of radius 1 ($fn = 16: 252 faces each) on a helix, sphere k from `first`. */
static void sphere_helix(char *text, size_t size, int first, int n)
{
    size_t len = (size_t)snprintf(text, size, "union() {");
    for (int i = first; i < first + n; i++) /* each crosses several neighbours */
        len += (size_t)snprintf(text + len, size - len,
                                " translate([%.17g,%.17g,%.17g]) sphere(1, $fn=16);",
                                6 * cos(i * 0.15), 6 * sin(i * 0.15), i * 0.02);
    snprintf(text + len, size - len, " }");
}

/* 400 spheres (150 under the sanitizers): one solid, and |A u B| = |A| + |B| - |A n B| for
 * the unions A, B of the two halves. */
TEST(union_of_hundreds_of_overlapping_spheres)
{
    static char all[262144], a[131072], b[131072], both[270000];
    int n = getenv("MCSG_SANITIZED") ? 150 : 400;
    double va, vb, vn;
    outcome o;
    sphere_helix(all, sizeof all, 0, n);
    sphere_helix(a, sizeof a, 0, n / 2);
    sphere_helix(b, sizeof b, n / 2, n - n / 2);
    if (solid(all, false, &o)) {
        CHECK_EQ_SIZE(o.report.components, 1);
        CHECK(o.volume > 4.0 && o.volume < n * 4.2);
        va = volume_of(a);
        vb = volume_of(b);
        snprintf(both, sizeof both, "intersection() { %s %s }", a, b);
        vn = volume_of(both);
        CHECK_MSG(fabs(o.volume - (va + vb - vn)) <= 1e-12 * o.volume,
                  "%.17g vs %.17g + %.17g - %.17g", o.volume, va, vb, vn);
        printf("  %d spheres: %zu output triangles, volume %.6f\n", n,
               o.mesh.triangle_count, o.volume);
        mcsg_mesh_free(&o.mesh, NULL);
    }
}

/* A real model minus a copy rotated by 1e-7 rad or moved by about an ulp of its
 * coordinates: |A - B| + |A n B| = |A|, with thin slivers everywhere. */
TEST(models_minus_nearly_identical_copies)
{
    static const char *const moves[] = {
        "rotate(a=5.729577951308232e-6, v=[1,2,3])", "translate([1e-16, 2e-16, -1e-16])"};
    char model[4300], moved[4500], diff[9000], inter[9000];
    const char *names[] = {"spot.obj", "sphere.obj"};
    for (int m = 0; m < 2; m++) {
        double va, vd, vi;
        snprintf(model, sizeof model, "import(\"%s\");", test_model(names[m]));
        snprintf(moved, sizeof moved, "%s %s", moves[m], model);
        snprintf(diff, sizeof diff, "difference() { %s %s }", model, moved);
        snprintf(inter, sizeof inter, "intersection() { %s %s }", model, moved);
        /* Where the surface is parallel to the motion, the exact difference pinches to
         * nothing: its parts may touch along edges there. */
        va = volume_of(model);
        vd = volume_touching(diff, true);
        vi = volume_touching(inter, true);
        CHECK_MSG(fabs(vd + vi - va) <= 1e-12 * va, "%s: %.17g + %.17g vs %.17g", names[m], vd,
                  vi, va);
        CHECK(vd < 1e-4 * va);
    }
}

/* OpenSCAD's example024 (a Menger sponge of side 100, turned onto a corner, its lower half
 * cut away) as its .csg export writes it, with six significant digits: faces meant to be
 * coplanar are some 1e-5 apart, and the rotation's rounding makes them meet at angles
 * near 1e-16, so their crossing points are nearly parallel planes' (wide certified boxes,
 * which the kernel tightens exactly once). The exact volume of the text as written:
 * the sponge's boxes in rationals (coordinate compression), times |det| of the rounded
 * rotation, halved by central symmetry; OpenSCAD's own render is 1.8e-6 off it. */
typedef struct text_buf {
    char *s;
    size_t len, cap;
} text_buf;

static void append(text_buf *b, const char *fmt, ...)
{
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
    va_end(ap);
    if (n > 0 && (size_t)n < b->cap - b->len)
        b->len += (size_t)n;
    else
        b->len = b->cap; /* full: the test below then fails to parse */
}

static void menger_negative(text_buf *b, double size, int level)
{
    double l = size / 3;
    append(b, "cube(size = [%.6g, %.6g, %.6g], center = true);\n", 110.0, l, l);
    for (int i = -1; level > 1 && i <= 1; i++)
        for (int j = -1; j <= 1; j++) {
            if (!i && !j)
                continue;
            append(b, "multmatrix([[1, 0, 0, 0], [0, 1, 0, %.6g], [0, 0, 1, %.6g], "
                      "[0, 0, 0, 1]]) {\n", i * l, j * l);
            menger_negative(b, l, level - 1);
            append(b, "}\n");
        }
}

TEST(menger_sponge_with_six_digit_numbers)
{
    static const char *const turns[] = {
        "[[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]",
        "[[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]",
        "[[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]]"};
    text_buf b = {malloc(64 * 1024), 0, 64 * 1024};
    outcome o;
    double expected = 274348.7704270973;
    if (!b.s)
        return;
    append(&b, "difference() {\nmultmatrix([[0.816497, 0.408248, 0.408248, 0], [0, 0.707107, "
               "-0.707107, 0], [-0.57735, 0.57735, 0.57735, 0], [0, 0, 0, 1]]) difference() {"
               "\ncube(size = [100, 100, 100], center = true);\n");
    for (int t = 0; t < 3; t++) {
        append(&b, "multmatrix(%s) {\n", turns[t]);
        menger_negative(&b, 100, 2);
        append(&b, "}\n");
    }
    append(&b, "}\ntranslate([0, 0, -100]) cube(size = [200, 200, 200], center = true);\n}\n");
    CHECK(b.len < b.cap);
    /* Parts of the result touch along an edge once rounded (not yet separated). */
    if (solid(b.s, true, &o)) {
        CHECK_MSG(fabs(o.volume - expected) <= 1e-12 * expected, "volume %.17g, expected %.17g",
                  o.volume, expected);
        CHECK_EQ_SIZE(o.report.components, 1);
        mcsg_mesh_free(&o.mesh, NULL);
    }
    free(b.s);
}

int main(void)
{
    RUN(coplanar_faces_stacked_and_offset);
    RUN(identical_operands_three_times);
    RUN(copies_moved_by_an_ulp_or_rotated_by_1e_7);
    RUN(needles_and_slivers);
    RUN(fans_of_cylinders_through_one_axis);
    RUN(scales_and_far_from_the_origin);
    RUN(union_of_hundreds_of_overlapping_spheres);
    RUN(models_minus_nearly_identical_copies);
    RUN(menger_sponge_with_six_digit_numbers);
    printf("outputs self-intersecting after rounding to doubles: %d of %d\n",
           self_intersecting_outputs, outputs);
    return test_summary();
}
