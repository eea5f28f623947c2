/*
 * End-to-end evaluation (mcsg_eval) against known answers: exact volumes of box scenes
 * (union, intersection, difference, nested), the identities A u A = A, A n A = A,
 * A - A = empty, solids touching on a face, edge or vertex, coplanar half-overlaps,
 * curved solids whose volumes add up, provenance, and allocation failures. Every
 * non-empty output must be closed, consistently oriented and edge-manifold.
 */
#include "testlib.h"

#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

typedef struct result {
    mcsg_mesh mesh;
    mcsg_check_report report;
    mcsg_eval_stats stats;
} result;

static mcsg_tree *parse(const char *text)
{
    mcsg_tree *tree = NULL;
    mcsg_error err;
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "test.scad", ".", NULL, &tree, &err),
             &err);
    return tree;
}

/* Evaluate and check the output's topology (closed, oriented, edge-manifold). */
static bool eval_text(const char *text, result *r)
{
    mcsg_error err;
    mcsg_status st;
    memset(r, 0, sizeof *r);
    st = test_eval_scad(text, NULL, &r->mesh, &r->stats, &err);
    CHECK_MSG(st == MCSG_OK, "%s: %s", text, err.message);
    if (st != MCSG_OK)
        return false;
    CHECK_OK(mcsg_mesh_check(&r->mesh, NULL, &r->report, &err), &err);
    return true;
}

static void expect_solid(const char *text, double volume, size_t components)
{
    result r;
    if (!eval_text(text, &r))
        return;
    CHECK_MSG(mcsg_check_report_is_valid(&r.report) && !r.report.inverted,
              "%s: not closed/oriented/manifold (%zu boundary, %zu non-manifold, %zu "
              "inconsistent edges)", text, r.report.boundary_edges,
              r.report.nonmanifold_edges, r.report.inconsistent_edges);
    CHECK_MSG(test_index_manifold_defects(&r.mesh) == 0, "%s: not manifold by index", text);
    CHECK_MSG(r.report.components == components, "%s: %zu components, expected %zu", text,
              r.report.components, components);
    CHECK_MSG(fabs(r.report.volume - volume) <= 1e-12 * fabs(volume) + 1e-15,
              "%s: volume %.17g, expected %.17g", text, r.report.volume, volume);
    CHECK(fabs(test_signed_volume(&r.mesh) - r.report.volume) <= 1e-12 * fabs(volume) + 1e-15);
    mcsg_mesh_free(&r.mesh, NULL);
}

/* A result whose parts touch along edges: closed and oriented, its only geometric
 * defect the shared edges, manifold by vertex index (parts have their own vertices). */
static void expect_touching(const char *text, double volume, size_t new_vertices)
{
    result r;
    if (!eval_text(text, &r))
        return;
    CHECK_MSG(r.report.boundary_edges == 0 && r.report.inconsistent_edges == 0 &&
              r.report.nonmanifold_edges > 0 && r.report.degenerate_triangles == 0,
              "%s: %zu boundary, %zu inconsistent, %zu non-manifold edges", text,
              r.report.boundary_edges, r.report.inconsistent_edges,
              r.report.nonmanifold_edges);
    CHECK_MSG(test_index_manifold_defects(&r.mesh) == 0, "%s: not manifold by index", text);
    CHECK_MSG(r.stats.touching_vertices_split == new_vertices, "%s: %zu vertices split", text,
              r.stats.touching_vertices_split);
    CHECK_MSG(fabs(test_signed_volume(&r.mesh) - volume) <= 1e-12 * volume, "%s: volume %.17g",
              text, test_signed_volume(&r.mesh));
    mcsg_mesh_free(&r.mesh, NULL);
}

static void expect_empty(const char *text)
{
    result r;
    if (!eval_text(text, &r))
        return;
    CHECK_MSG(r.mesh.triangle_count == 0, "%s: %zu triangles, expected none", text,
              r.mesh.triangle_count);
    mcsg_mesh_free(&r.mesh, NULL);
}

TEST(box_scenes_have_exact_volumes)
{
    expect_solid("union() { cube(2); translate([1,1,1]) cube(2); }", 15, 1);
    expect_solid("intersection() { cube(2); translate([1,1,1]) cube(2); }", 1, 1);
    expect_solid("difference() { cube(2); translate([1,1,1]) cube(2); }", 7, 1);
    expect_solid("difference() { cube(4, center=true); cube(2, center=true); }", 56, 2);
    expect_solid("difference() { cube([4,4,1]); translate([1,1,-1]) cube([2,2,3]); }", 12, 1);
    /* Nested: (A u B) - (C n D), with C n D = [1,2]^3 cutting into both. */
    expect_solid("difference() { union() { cube(2); translate([1,0,0]) cube(2); }"
                 " intersection() { translate([1,1,1]) cube(2); cube(2); } }",
                 12 - 1, 1);
    expect_solid("intersection() { union() { cube([3,1,1]); cube([1,3,1]); }"
                 " difference() { cube(3); translate([0.5,0.5,-1]) cube([0.25,0.25,3]); } }",
                 5 - 0.0625, 1);
    /* Three overlapping boxes in one union. */
    expect_solid("union() { cube(2); translate([1,0,0]) cube(2); translate([2,0,0]) cube(2); }",
                 16, 1);
}

/* A plate minus an n x n grid of square holes, with n bars on top touching it (the
 * bench's box_grid_n): volume 7 n^2 / 8 exactly. Its top and bottom faces carry every
 * hole's outline, hundreds of points each, on lines shared by whole rows of holes: the
 * triangulation's flipped insertion, the exact zeros of axis-aligned LPIs, and columns
 * of points with one x in the point numbering. */
static char *plate_with_holes(int n)
{
    size_t cap = 128 + (size_t)n * (size_t)(n + 1) * 96, len = 0;
    char *text = malloc(cap);
    len += (size_t)snprintf(text + len, cap - len,
                            "union() { difference() { cube([%d, %d, 1]);", n, n);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            len += (size_t)snprintf(text + len, cap - len,
                                    " translate([%d.25, %d.25, -1]) cube([0.5, 0.5, 3]);", i, j);
    len += (size_t)snprintf(text + len, cap - len, " }");
    for (int i = 0; i < n; i++)
        len += (size_t)snprintf(text + len, cap - len,
                                " translate([%d, 0, 1]) cube([0.25, %d, 0.5]);", i, n);
    snprintf(text + len, cap - len, " }");
    return text;
}

TEST(plates_with_grids_of_holes)
{
    for (int n = 4; n <= 16; n += 12) {
        char *text = plate_with_holes(n);
        expect_solid(text, 0.875 * n * n, 1);
        free(text);
    }
}

TEST(identical_operands)
{
    result r;
    expect_solid("union() { cube(2); cube(2); }", 8, 1);
    expect_solid("intersection() { cube(2); cube(2); }", 8, 1);
    expect_empty("difference() { cube(2); cube(2); }");
    expect_solid("union() { cube(2); cube(2); cube(2); }", 8, 1);
    expect_empty("difference() { sphere(1, $fn=12); sphere(1, $fn=12); }");
    /* A u A keeps exactly one copy of A's faces. */
    if (eval_text("union() { sphere(1, $fn=16); sphere(1, $fn=16); }", &r)) {
        mcsg_mesh a;
        mcsg_resolution res = {16, 0, 0};
        mcsg_error err;
        CHECK_OK(mcsg_make_sphere(1, res, NULL, &a, &err), &err);
        CHECK_EQ_SIZE(r.mesh.triangle_count, a.triangle_count);
        CHECK_EQ_SIZE(r.mesh.vertex_count, a.vertex_count);
        CHECK(fabs(r.report.volume - test_signed_volume(&a)) < 1e-12);
        CHECK(mcsg_check_report_is_valid(&r.report));
        mcsg_mesh_free(&a, NULL);
        mcsg_mesh_free(&r.mesh, NULL);
    }
}

/* expect_solid, and the evaluation's statistics (zeros if it failed). */
static mcsg_eval_stats solid_stats(const char *text, double volume, size_t components)
{
    result r;
    mcsg_eval_stats stats;
    memset(&stats, 0, sizeof stats);
    expect_solid(text, volume, components);
    if (!eval_text(text, &r))
        return stats;
    stats = r.stats;
    mcsg_mesh_free(&r.mesh, NULL);
    return stats;
}

static size_t solid_dropping(const char *text, double volume, size_t components)
{
    return solid_stats(text, volume, components).faces_dropped_whole;
}

/* Faces crossed by other leaves but buried in (or outside) a leaf they do not meet are
 * dropped whole before they are split (whole_faces.c); the rest of the classification
 * must not need them. The volumes are exact, so a wrongly dropped or kept face shows. */
TEST(buried_faces_are_dropped_whole)
{
    const char *two = "translate([2,2,2]) cube(3); translate([3,3,3]) cube(3);";
    char text[512];
    snprintf(text, sizeof text, "union() { cube(10); %s }", two);
    CHECK(solid_dropping(text, 1000, 1) > 0);
    snprintf(text, sizeof text, "union() { %s cube(10); }", two);
    CHECK(solid_dropping(text, 1000, 1) > 0);
    /* Carved: the crossing cubes make a cavity, and their faces are all needed. */
    snprintf(text, sizeof text, "difference() { cube(10); %s }", two);
    CHECK(solid_dropping(text, 1000 - (27 + 27 - 8), 2) == 0);
    /* Outside a leaf that an intersection keeps: the far cubes' crossing faces go. */
    CHECK(solid_dropping("intersection() { cube(10); union() { translate([2,2,2]) cube(3);"
                         " translate([3,3,3]) cube(3); translate([9,9,9]) cube(3);"
                         " translate([9.5,9.5,9.5]) cube(3); } }",
                         27 + 27 - 8 + 1, 2) > 0);
    /* A cube buried in one leaf and crossing another: only the buried part's faces. */
    CHECK(solid_dropping("union() { cube(10); translate([8,8,8]) cube(4);"
                         " translate([7,7,7]) cube(2); }",
                         1000 + 64 - 8, 1) > 0);
    /* The pyramid's top lies in the big cube's bottom plane and the small box crosses
     * it; its sides, outside the box, are dropped whole only if the big cube does not
     * meet them along the top's edges: those edges are the top's only separators with
     * the cube (a face meeting a surface along its border is never dropped whole). */
    {
        const char *down = "polyhedron(points=[[1,1,0],[9,1,0],[5,9,0],[5,4,-3]], "
                           "faces=[[0,2,1],[0,1,3],[1,2,3],[2,0,3]]);";
        const char *up = "polyhedron(points=[[1,1,0],[9,1,0],[5,9,0],[5,4,3]], "
                         "faces=[[0,1,2],[0,3,1],[1,3,2],[2,3,0]]);";
        const char *box = "translate([4,3,-0.5]) cube([2,2,1]);";
        snprintf(text, sizeof text, "intersection() { %s union() { cube(10); %s } }", box,
                 down);
        expect_solid(text, 4, 1);
        snprintf(text, sizeof text, "intersection() { %s union() { cube(10); %s } }", box, up);
        expect_solid(text, 2, 1);
        snprintf(text, sizeof text,
                 "intersection() { %s difference() { %s translate([0,0,-10]) cube(10); } }",
                 box, down);
        expect_empty(text);
        /* The same with the pyramid's top cut into a middle triangle, which the box
         * crosses, and a ring of triangles around it: the ring lies in the cube's bottom
         * face (and is not dropped whole) so the middle triangle's regions reach the
         * cube's separators along the top's outer edges through it. */
        expect_solid("intersection() { translate([4.8,3.4,-0.5]) cube([0.4,0.4,1]);"
                     " union() { cube(10); polyhedron(points=[[1,1,0],[9,1,0],[5,9,0],"
                     "[5,4,-3],[4,3,0],[6,3,0],[5,5,0]], faces=[[4,6,5],[0,5,1],[0,4,5],"
                     "[1,6,2],[1,5,6],[2,4,0],[2,6,4],[0,1,3],[1,2,3],[2,0,3]]); } }",
                     0.16, 1);
    }
}

static size_t solid_copies(const char *text, double volume, size_t components)
{
    return solid_stats(text, volume, components).copied_primitives;
}

/* A primitive that is the same mesh as an earlier one is evaluated through it (eval.c):
 * its faces are the earlier one's, with its own CSGlist, orientation and provenance. The
 * cases put both copies' faces in the result, in parts of one face, complemented. */
TEST(copies_are_evaluated_once)
{
    const char *a = "cube(4);", *c = "translate([2,0.5,0.5]) cube([4,3,3]);";
    char text[256];
    /* (A n C) u (A' - C'): the faces of A are kept partly by A, partly by A'. */
    snprintf(text, sizeof text, "union() { intersection() { %s %s } difference() { %s %s } }",
             a, c, a, c);
    CHECK_EQ_SIZE(solid_copies(text, 64, 1), 2);
    snprintf(text, sizeof text, "difference() { %s intersection() { %s %s } }", a, a, c);
    CHECK_EQ_SIZE(solid_copies(text, 46, 1), 1);
    snprintf(text, sizeof text, "difference() { union() { %s %s } %s }", a, c, a);
    CHECK_EQ_SIZE(solid_copies(text, 18, 1), 1);
    snprintf(text, sizeof text, "union() { difference() { %s %s } %s %s }", c, a, a, a);
    CHECK_EQ_SIZE(solid_copies(text, 82, 1), 2);
    /* A copy of a leaf that another leaf crosses, and a copy of that one. */
    CHECK_EQ_SIZE(solid_copies("intersection() { union() { cube(4); sphere(1, $fn=8); }"
                               " union() { cube(4); translate([5,0,0]) cube(1); } }", 64, 1),
                  1);
    /* A copied leaf with faces in another leaf's faces (C's sides in A's planes): the
     * copies' classification does not handle the third coincident surface, so the tree
     * is evaluated without copies (tests/data/csg-regressions/copies-coplanar-*). */
    snprintf(text, sizeof text, "union() { intersection() { %s %s } difference() { %s %s } }",
             a, "translate([2,0,0]) cube(4);", a, "translate([2,0,0]) cube(4);");
    CHECK_EQ_SIZE(solid_copies(text, 64, 1), 0);
}

TEST(touching_solids)
{
    /* An octahedron in a cube, its corners at the centres of the cube's faces: its faces
     * meet the cube only at their corners, so every vertex lies on the cube's surface and
     * no side of a piece does; the label comes from a point inside a face. */
    {
        const char *oct = "translate([2,2,2]) polyhedron(points=[[1,0,0],[-1,0,0],[0,1,0],"
                          "[0,-1,0],[0,0,1],[0,0,-1]], faces=[[0,4,2],[0,2,5],[0,3,4],"
                          "[0,5,3],[1,2,4],[1,5,2],[1,4,3],[1,3,5]]);";
        const char *box = "translate([1,1,1]) cube(2);";
        char text[512];
        snprintf(text, sizeof text, "union() { %s %s }", oct, box);
        expect_solid(text, 8, 1);
        snprintf(text, sizeof text, "intersection() { %s %s }", oct, box);
        expect_solid(text, 4.0 / 3, 1);
        snprintf(text, sizeof text, "difference() { %s %s }", oct, box);
        expect_empty(text);
        snprintf(text, sizeof text, "difference() { %s %s }", box, oct);
        expect_solid(text, 8 - 4.0 / 3, 2);
    }
    /* B touches A on a face: A - B = A, A u B fuses into one box. */
    expect_solid("difference() { cube(2); translate([2,0,0]) cube(2); }", 8, 1);
    expect_solid("difference() { cube(2); translate([2,0.5,0.5]) cube(1); }", 8, 1);
    expect_solid("union() { cube(2); translate([2,0,0]) cube(2); }", 16, 1);
    expect_solid("union() { cube(2); translate([2,0.5,0.5]) cube(1); }", 9, 1);
    expect_empty("intersection() { cube(2); translate([2,0,0]) cube(2); }");
    /* Touching at a vertex: two shells sharing one point. */
    expect_solid("union() { cube(2); translate([2,2,2]) cube(2); }", 16, 2);
    /* Touching along an edge: geometrically non-manifold, but each box keeps its own
     * copies of the edge's vertices, so the mesh is manifold by index. */
    expect_touching("union() { cube(1); translate([1,1,0]) cube(1); }", 2, 2);
    expect_touching("difference() { cube(2); translate([1,1,0]) cube([1,1,2]);"
                    " translate([0,0,0]) cube([1,1,2]); }", 4, 2);
    /* An L-shaped solid touching a cube along two edges that meet at a corner: around
     * that corner the cube's triangles stay one umbrella only when the four triangles at
     * each touching edge are paired by angle (an unpaired edge leaves the cube's corner
     * in two groups and gives five vertex copies instead of three). */
    expect_touching("union() { cube(1); translate([1,1,0]) cube(1); translate([0,1,1]) cube(1);"
                    " translate([1,1,1]) cube(1); }", 4, 3);
    /* Two notches touching along an edge whose ends lie inside the solid's surface:
     * around each end the surface is one umbrella when the four triangles at the edge are
     * paired by angle (solid wedge with solid wedge), so they are paired by notch. */
    expect_touching("difference() { cube([2,2,3]); translate([0,0,1]) cube([1,1,1]);"
                    " translate([1,1,1]) cube([1,1,1]); }", 10, 2);
    /* A box carved from the inside of a face: a pocket. */
    expect_solid("difference() { cube(2); translate([0.5,0.5,1]) cube([1,1,1]); }", 7, 1);
}

TEST(coplanar_overlaps)
{
    expect_solid("union() { cube(2); translate([1,0,0]) cube(2); }", 12, 1);
    expect_solid("difference() { cube(2); translate([1,0,0]) cube(2); }", 4, 1);
    expect_solid("intersection() { cube(2); translate([1,0,0]) cube(2); }", 4, 1);
    expect_solid("union() { cube(2); translate([1,1,0]) cube(2); }", 14, 1);
    expect_solid("difference() { cube(2); translate([1,1,0]) cube(2); }", 6, 1);
    /* Offset by half a face in two directions and stacked. */
    expect_solid("union() { cube(2); translate([1,1,2]) cube(2); }", 16, 1);
}

/* A CAD-like plate: length 900, width 10, height 1, its far end an arc of n segments,
 * its flat faces fan-triangulated from the middle of its near edge (on x = 0), as CAD
 * exporters triangulate a polygon: slivers 900 long and a few hundredths wide. */
#define HALF_PI 1.5707963267948966

static char *fan_plate(int n)
{
    size_t cap = (size_t)(n + 4) * 200 + 256, len = 0;
    char *text = malloc(cap);
    int m = n + 4; /* corners (0, -5), apex (0, 0), (0, 5), then the arc */
    if (!text)
        return NULL;
    len += (size_t)snprintf(text + len, cap - len, "polyhedron(points=[");
    for (int z = 0; z < 2; z++) {
        len += (size_t)snprintf(text + len, cap - len, "[0,-5,%d],[0,0,%d],[0,5,%d],", z, z, z);
        for (int i = 0; i <= n; i++) {
            double t = HALF_PI - 2 * HALF_PI * i / n;
            len += (size_t)snprintf(text + len, cap - len, "[%.17g,%.17g,%d],",
                                    -(900 + 2.5 * cos(t)), 5 * sin(t), z);
        }
    }
    len += (size_t)snprintf(text + len, cap - len, "], faces=[");
    /* polygon order 0 (0,-5), 1 apex, 2 (0,5), 3.. the arc from (-900,5) to (-900,-5):
     * clockwise seen from +z, so the bottom fan is (1, k, k+1) and the top reversed */
    for (int k = 2; k < m - 1; k++)
        len += (size_t)snprintf(text + len, cap - len, "[1,%d,%d],[%d,%d,%d],", k, k + 1,
                                1 + m, k + 1 + m, k + m);
    len += (size_t)snprintf(text + len, cap - len, "[1,%d,0],[%d,%d,%d],", m - 1, 1 + m, m,
                            2 * m - 1);
    for (int i = 0; i < m; i++) {
        int j = (i + 1) % m;
        len += (size_t)snprintf(text + len, cap - len, "[%d,%d,%d],[%d,%d,%d],", i, i + m,
                                j + m, i, j + m, j);
    }
    snprintf(text + len, cap - len, "]);");
    return text;
}

/* Two such plates crossing at right angles, then stacked. Crossing: inside the other
 * plate, a face's part is cut by the other's walls alone, so every vertex of that region
 * lies on the other's surface and no ray from a vertex decides its label; a local test
 * at a wall does. Rays from every vertex (thousands, each through the whole octree)
 * took 19 s at n = 3,900. */
TEST(cad_fan_plates)
{
    char *plate = fan_plate(150), *text;
    result one;
    if (!plate || !(text = malloc(2 * strlen(plate) + 200))) {
        CHECK(!"out of memory");
        free(plate);
        return;
    }
    if (eval_text(plate, &one)) {
        result r;
        double a = one.report.volume;
        CHECK(a > 9000 && a < 9020);
        sprintf(text, "union() { %s translate([-450, 450, 0.5]) rotate([0, 0, 90]) %s }", plate,
                plate);
        expect_solid(text, 2 * a - 50, 1);
        if (eval_text(text, &r)) {
            CHECK_MSG(r.stats.rays <= 40, "%zu rays", r.stats.rays);
            mcsg_mesh_free(&r.mesh, NULL);
        }
        /* Stacked, the top fan of one on the bottom fan of the other: every pair of their
         * coplanar slivers touches at the common apex only, a contact no arrangement
         * needs (intersect_pairs.c drops it); the shared faces still cancel. */
        sprintf(text, "union() { %s translate([0, 0, 1]) mirror([0, 1, 0]) %s }", plate, plate);
        expect_solid(text, 2 * a, 1);
        sprintf(text, "difference() { translate([0, 0, 1]) mirror([0, 1, 0]) %s %s }", plate,
                plate);
        expect_solid(text, a, 1);
        mcsg_mesh_free(&one.mesh, NULL);
    }
    free(text);
    free(plate);
}

/* Exact volumes of curved solids are unknown, but they must add up: vol(A u B) +
 * vol(A n B) = vol(A) + vol(B) and vol(A - B) = vol(A) - vol(A n B), to rounding. */
/* A polyhedron of axis-aligned boxes, one shell each: box k spans lo[k] .. hi[k] and
 * faces inward when inward[k] (NULL: none does). OpenSCAD lists faces clockwise seen
 * from outside. */
static char *boxes_polyhedron(double (*lo)[3], double (*hi)[3], const bool *inward, int n)
{
    static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    size_t cap = 512 + (size_t)n * 512, len = 0;
    char *text = malloc(cap);
    len += (size_t)snprintf(text + len, cap - len, "polyhedron(points=[");
    for (int k = 0; k < n; k++)
        for (int c = 0; c < 8; c++)
            len += (size_t)snprintf(text + len, cap - len, "%s[%g,%g,%g]", k + c ? "," : "",
                                    c & 4 ? hi[k][0] : lo[k][0], c & 2 ? hi[k][1] : lo[k][1],
                                    c & 1 ? hi[k][2] : lo[k][2]);
    len += (size_t)snprintf(text + len, cap - len, "], faces=[");
    for (int k = 0; k < n; k++)
        for (int f = 0; f < 6; f++) {
            int c[4];
            bool flip = inward && inward[k];
            for (int i = 0; i < 4; i++)
                c[i] = 8 * k + quads[f][flip ? 3 - i : i];
            len += (size_t)snprintf(text + len, cap - len, "%s[%d,%d,%d,%d]", k + f ? "," : "",
                                    c[0], c[1], c[2], c[3]);
        }
    snprintf(text + len, cap - len, "]);");
    return text;
}

/* The same for cubes: box k spans lo[k] .. hi[k] on every axis. */
static char *box_shells(const double *lo, const double *hi, const bool *inward, int n)
{
    double l[3][3], h[3][3];
    for (int k = 0; k < n && k < 3; k++)
        for (int i = 0; i < 3; i++)
            l[k][i] = lo[k], h[k][i] = hi[k];
    return boxes_polyhedron(l, h, inward, n < 3 ? n : 3);
}

/* "op() { A B }" in a buffer of its own. */
static char *tree_of(const char *op, const char *a, const char *b)
{
    size_t n = strlen(op) + strlen(a) + strlen(b) + 16;
    char *text = malloc(n);
    snprintf(text, n, "%s() { %s %s }", op, a, b);
    return text;
}

static void expect_tree_volume(const char *op, const char *a, const char *b, double volume,
                               size_t components)
{
    char *text = tree_of(op, a, b);
    if (volume == 0)
        expect_empty(text);
    else
        expect_solid(text, volume, components);
    free(text);
}

/* A slab crossing the shells of the boxes below. */
static const char *const shell_slab = "translate([5,-1,-1]) cube([20,5,20]);";

/* A leaf is where its winding number is positive: a box inside a box adds nothing, an
 * inward box inside one is a cavity, an inward box alone is empty; other leaves crossing
 * the shells, or lying on them, are classified by the numbers on each side. */
TEST(leaves_with_several_shells)
{
    const double lo[] = {0, 2, 4}, hi[] = {10, 8, 6};
    const bool out_out[] = {false, false}, out_in[] = {false, true}, in_out[] = {true, false};
    const bool out_in_out[] = {false, true, false}, in[] = {true};
    const char *slab = shell_slab;
    char *nested = box_shells(lo, hi, out_out, 2), *cavity = box_shells(lo, hi, out_in, 2);
    char *hollow = box_shells(lo, hi, in_out, 2), *triple = box_shells(lo, hi, out_in_out, 3);
    char *inverted = box_shells(lo, hi, in, 1);
    expect_tree_volume("union", nested, "", 1000, 1);
    expect_tree_volume("union", inverted, "", 0, 0);
    expect_tree_volume("union", hollow, "", 0, 0);
    expect_tree_volume("difference", nested, slab, 800, 1);
    expect_tree_volume("intersection", nested, slab, 200, 1);
    expect_tree_volume("union", nested, slab, 2800, 1);
    expect_tree_volume("difference", slab, nested, 1800, 1);
    expect_tree_volume("difference", cavity, slab, 620, 1); /* the slab opens the cavity */
    expect_tree_volume("intersection", cavity, slab, 164, 1);
    expect_tree_volume("union", cavity, slab, 2620, 2);
    expect_tree_volume("difference", slab, cavity, 1836, 2);
    expect_tree_volume("union", inverted, slab, 2000, 1);
    expect_tree_volume("difference", slab, hollow, 2000, 1);
    expect_tree_volume("difference", triple, slab, 628, 2);
    expect_tree_volume("intersection", triple, slab, 164, 1);
    /* Coincident shells of two such leaves. */
    expect_tree_volume("union", nested, cavity, 1000, 1);
    expect_tree_volume("intersection", nested, cavity, 784, 2);
    expect_tree_volume("difference", nested, cavity, 216, 1);
    expect_tree_volume("difference", cavity, nested, 0, 0);
    expect_tree_volume("union", triple, cavity, 792, 3);
    expect_tree_volume("union", inverted, cavity, 784, 2);
    free(nested);
    free(cavity);
    free(hollow);
    free(triple);
    free(inverted);
}

/* Shells of one leaf crossing each other: [0,10], [5,15] and [2,12] cubes. Overlapping
 * outward shells are their union; an inward one cuts the others. */
TEST(leaves_with_crossing_shells)
{
    const double lo[] = {0, 5, 2}, hi[] = {10, 15, 12};
    const bool in_second[] = {false, true, false}, outward[] = {false, false, false};
    char *two = box_shells(lo, hi, outward, 2), *three = box_shells(lo, hi, outward, 3);
    char *minus = box_shells(lo, hi, in_second, 2);
    expect_tree_volume("union", two, "", 1875, 1);
    expect_tree_volume("union", three, "", 3000 - 980 + 125, 1);
    expect_tree_volume("union", minus, "", 875, 1);
    expect_tree_volume("difference", two, shell_slab, 1675, 1);
    expect_tree_volume("difference", "cube(12);", two, 1728 - 1218, 1);
    expect_tree_volume("intersection", two, three, 1875, 1);
    expect_tree_volume("difference", three, two, 2145 - 1875, 1);
    free(two);
    free(three);
    free(minus);
}

/* Leaves closed as chains but not manifold, each shell kept apart where edges are shared
 * by four triangles: boxes sharing an edge or a face, a box listed twice (winding number
 * 2), faces lying in each other facing either way. */
TEST(leaves_closed_as_chains)
{
    static double edge_lo[2][3] = {{0, 0, 0}, {10, 10, 0}};
    static double edge_hi[2][3] = {{10, 10, 10}, {20, 20, 10}};
    static double face_lo[2][3] = {{0, 0, 0}, {10, 0, 0}};
    static double face_hi[2][3] = {{10, 10, 10}, {20, 10, 10}};
    static double part_lo[2][3] = {{0, 0, 0}, {10, 2, 2}};
    static double part_hi[2][3] = {{10, 10, 10}, {20, 8, 8}};
    static double inner_lo[2][3] = {{0, 0, 0}, {5, 2, 2}};
    static double inner_hi[2][3] = {{10, 10, 10}, {10, 8, 8}};
    static double twice_lo[2][3] = {{0, 0, 0}, {0, 0, 0}};
    static double twice_hi[2][3] = {{10, 10, 10}, {10, 10, 10}};
    static const bool second_inward[2] = {false, true};
    char *edge = boxes_polyhedron(edge_lo, edge_hi, NULL, 2);
    char *face = boxes_polyhedron(face_lo, face_hi, NULL, 2);
    char *part = boxes_polyhedron(part_lo, part_hi, NULL, 2);
    char *inner = boxes_polyhedron(inner_lo, inner_hi, NULL, 2);
    char *twice = boxes_polyhedron(twice_lo, twice_hi, NULL, 2);
    char *cancel = boxes_polyhedron(twice_lo, twice_hi, second_inward, 2);
    char *cut = boxes_polyhedron(inner_lo, inner_hi, second_inward, 2);
    const char *slab = "translate([5,-1,-1]) cube([20,3,20]);";
    const char *block = "translate([3,3,3]) cube([12,12,4]);";
    char *text;
    expect_touching(text = tree_of("union", edge, ""), 2000, 2);
    free(text);
    expect_touching(text = tree_of("difference", edge, slab), 1900, 2);
    free(text);
    expect_tree_volume("union", face, "", 2000, 1);
    expect_tree_volume("difference", face, slab, 1700, 1);
    expect_tree_volume("intersection", face, block, 336, 1);
    expect_tree_volume("union", part, "", 1360, 1);
    expect_tree_volume("difference", part, slab, 1260, 1);
    expect_tree_volume("intersection", part, block, 296, 1);
    expect_tree_volume("union", inner, "", 1000, 1);
    expect_tree_volume("difference", inner, slab, 900, 1);
    expect_tree_volume("union", twice, "", 1000, 1);
    expect_tree_volume("difference", twice, slab, 900, 1);
    expect_tree_volume("intersection", twice, block, 196, 1);
    expect_tree_volume("union", cancel, "", 0, 0);
    expect_tree_volume("union", cancel, block, 576, 1);
    expect_tree_volume("union", cut, "", 820, 1);
    expect_tree_volume("difference", cut, slab, 720, 1);
    free(edge);
    free(face);
    free(part);
    free(inner);
    free(twice);
    free(cancel);
    free(cut);
}

/* The surface of unit cells (scaled by 10) as a polyhedron: each face between a cell and
 * an empty one is a quad with corners of its own (they are identified by coordinates). */
static char *cells_polyhedron(const int (*cell)[3], int n)
{
    static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    static const int step[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0},
                                   {0, 1, 0},  {0, 0, -1}, {0, 0, 1}};
    size_t cap = 64 + (size_t)n * 6 * 160, len = 0, quads_out = 0;
    char *points = malloc(cap), *faces = malloc(cap), *text = malloc(2 * cap);
    for (int k = 0; k < n; k++)
        for (int f = 0; f < 6; f++) {
            bool covered = false;
            for (int j = 0; j < n; j++)
                covered |= cell[j][0] == cell[k][0] + step[f][0] &&
                           cell[j][1] == cell[k][1] + step[f][1] &&
                           cell[j][2] == cell[k][2] + step[f][2];
            for (int i = 0; !covered && i < 4; i++) {
                int c = quads[f][i];
                len += (size_t)snprintf(points + len, cap - len, "%s[%d,%d,%d]",
                                        quads_out + (size_t)i ? "," : "",
                                        10 * (cell[k][0] + (c >> 2 & 1)),
                                        10 * (cell[k][1] + (c >> 1 & 1)),
                                        10 * (cell[k][2] + (c & 1)));
            }
            quads_out += !covered;
        }
    faces[0] = '\0';
    for (size_t q = 0, flen = 0; q < quads_out; q++)
        flen += (size_t)snprintf(faces + flen, cap - flen, "%s[%zu,%zu,%zu,%zu]", q ? "," : "",
                                 4 * q, 4 * q + 1, 4 * q + 2, 4 * q + 3);
    snprintf(text, 2 * cap, "polyhedron(points=[%s], faces=[%s]);", points, faces);
    free(points);
    free(faces);
    return text;
}

/* One connected surface that meets itself along an edge of four triangles: cells (0,0,0)
 * and (1,1,0) touch along x = y = 10 and are joined through the layer above. Its
 * triangles there are paired by angle (each with the one it bounds a wedge of solid
 * with), so the two cells stay apart at the edge; its upper end is not split, since the
 * layer above joins the cells around it. */
TEST(leaf_touching_itself_along_an_edge)
{
    static const int cells[5][3] = {{0, 0, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}};
    char *bent = cells_polyhedron(cells, 5), *text;
    expect_touching(text = tree_of("union", bent, ""), 5000, 1); /* the lower end only */
    free(text);
    expect_touching(text = tree_of("difference", bent, "translate([-1,-1,15]) cube(30);"),
                    3500, 1);
    free(text);
    expect_touching(text = tree_of("difference", bent, "translate([-1,-1,3]) cube([30,30,2]);"),
                    4600, 3);
    free(text);
    expect_touching(text = tree_of("intersection", bent, "translate([5,5,2]) cube([10,10,4]);"),
                    200, 2);
    free(text);
    expect_tree_volume("difference", bent, "translate([5,5,-1]) cube([10,10,30]);", 3750, 1);
    free(bent);
}

/* Surfaces of one shell crossing at an edge: the cube [0,10]^3 and a prism inside it
 * on the edge x = y = 10, one shell since the cube's second triangle on that edge is
 * listed last. No angle pairs the four triangles there (the prism's wedge lies inside
 * the cube's): refused with the edge named. */
/* One shell meeting itself at an edge where directions do not alternate around it: a
 * surface of the shell enters another's wedge there. The pieces are paired as
 * neighbours about the edge (validate.c pair_neighbours), the leaf is classified by
 * winding numbers, and tested for crossings (its parts often overlap in their faces). */
/* A leaf alone (volume `alone`), its intersection with `box` (`common`) and the box
 * minus it (`box_minus_leaf`), each one component. */
static void expect_leaf_and_box(const char *leaf, const char *box, double alone,
                                double common, double box_minus_leaf)
{
    char text[2048];
    snprintf(text, sizeof text, "union() { %s }", leaf);
    expect_solid(text, alone, 1);
    snprintf(text, sizeof text, "intersection() { %s %s }", leaf, box);
    expect_solid(text, common, 1);
    snprintf(text, sizeof text, "difference() { %s %s }", box, leaf);
    expect_solid(text, box_minus_leaf, 1);
}

TEST(leaves_entering_themselves_at_an_edge)
{
    /* A box with a prism inside sharing its edge x = y = 10, joined into one shell
     * there, the prism's ends lying in the box's top and bottom: winding number 2 in the
     * prism, 1 in the rest of the box (a generalized winding number estimate over
     * 20,000 points: 1 and 2 only, 2 in 22%; the prism is 225). */
    static const char *const nested =
        "polyhedron(points=[[0,0,0],[0,0,10],[0,10,0],[0,10,10],[10,0,0],[10,0,10],[10,10,0],"
        "[10,10,10],[10,10,0],[1,4,0],[4,1,0],[10,10,10],[1,4,10],[4,1,10]], faces=[[0,2,3],["
        "0,3,1],[4,5,7],[4,7,6],[0,1,5],[0,5,4],[2,7,3],[0,4,6],[0,6,2],[1,3,7],[1,7,5],[9,10"
        ",8],[13,12,11],[12,9,8],[11,12,8],[13,10,9],[12,13,9],[11,8,10],[13,11,10],[2,6,7]])"
        ";";
    /* A prism over a bowtie whose two lobes cross at the vertex (1, 1): the lobe
     * (0, 0), (1, 1), (0, 2) runs counterclockwise (winding number 1, area 1), the lobe
     * (1, 1), (2, 1.5), (2, 0) clockwise (-1): the solid is the first. */
    static const char *const bowtie =
        "polyhedron(points=[[0,0,0],[1,1,0],[2,1.5,0],[2,0,0],[0,2,0],[0,0,1],[1,1,1],[2,1.5,1"
        "],[2,0,1],[0,2,1]], faces=[[6,1,0],[5,6,0],[7,2,1],[6,7,1],[8,3,2],[7,8,2],[6,1,3],[8"
        ",6,3],[9,4,1],[6,9,1],[5,0,4],[9,5,4],[1,4,0],[2,3,1],[9,6,5],[8,7,6]]);";
    /* Three lobes nested about the edge x = y = 0 of a prism (the triangles (0,0),
     * (10,0), (0,10); (0,0), (6,1), (1,6); (0,0), (3,1), (1,3), all counterclockwise,
     * one shell by the order of its faces): directions about the edge run out, out,
     * out, in, in, in, so neither pairing of neighbours works; the pairs are nested
     * instead. Winding numbers 1, 2 and 3: the solid is the outer lobe's prism, 500. */
    static const char *const nested3 =
        "polyhedron(points=[[0,0,0],[10,0,0],[10,0,10],[0,0,10],[0,10,0],[0,10,10],[6,1,0],[6"
        ",1,10],[1,6,0],[1,6,10],[3,1,0],[3,1,10],[1,3,0],[1,3,10]], faces=[[3,0,4],[3,7,0],["
        "3,0,8],[3,11,0],[3,0,12],[3,2,0],[2,1,0],[5,4,1],[2,5,1],[5,3,4],[7,6,0],[9,8,6],[7,"
        "9,6],[9,3,8],[11,10,0],[13,12,10],[11,13,10],[13,3,12],[1,4,0],[5,2,3],[6,8,0],[9,7,"
        "3],[10,12,0],[13,11,3]]);";
    char text[2048];
    snprintf(text, sizeof text, "union() { %s }", nested);
    expect_solid(text, 1000, 1);
    snprintf(text, sizeof text, "difference() { %s translate([-1,-1,4]) cube([12,12,2]); }",
             nested);
    expect_solid(text, 800, 2);
    /* The plane y = 1 through the crossing edge: half of the first lobe on each side. */
    expect_leaf_and_box(bowtie, "translate([-1,1,-1]) cube([4,2,3]);", 1, 0.5, 23.5);
    snprintf(text, sizeof text, "union() { %s translate([-1,1,-1]) cube([4,2,3]); }", bowtie);
    expect_solid(text, 24.5, 1);
    /* Cut across all three lobes: x <= 2 holds 18 of the outer lobe's area. */
    expect_leaf_and_box(nested3, "translate([-1,-1,-1]) cube([3,12,12]);", 500, 180, 252);
}

/* A single shell enclosing no volume is valid input: folded flat (a tetrahedron with
 * all four corners in z = 0) its winding number is 0 everywhere; a bowtie prism whose
 * lobes (area 1 each) run counterclockwise and clockwise has numbers 1 and -1, and the
 * first lobe is the solid. */
TEST(shells_enclosing_no_volume)
{
    static const char *const flat =
        "polyhedron(points=[[0,0,0],[4,0,0],[0,4,0],[1,1,0]], faces=[[0,2,1],[0,1,3],[0,3,2],"
        "[1,2,3]]);";
    static const char *const bowtie =
        "polyhedron(points=[[0,0,0],[1,1,0],[2,2,0],[2,0,0],[0,2,0],[0,0,1],[1,1,1],[2,2,1],"
        "[2,0,1],[0,2,1]], faces=[[6,1,0],[5,6,0],[7,2,1],[6,7,1],[8,3,2],[7,8,2],[6,1,3],[8"
        ",6,3],[9,4,1],[6,9,1],[5,0,4],[9,5,4],[1,4,0],[2,3,1],[9,6,5],[8,7,6]]);";
    char text[1024];
    snprintf(text, sizeof text, "union() { translate([-1,-1,-1]) cube(3); %s }", flat);
    expect_solid(text, 27, 1);
    snprintf(text, sizeof text, "difference() { translate([-1,-1,-1]) cube(3); %s }", flat);
    expect_solid(text, 27, 1);
    expect_leaf_and_box(bowtie, "translate([-1,1,-1]) cube([4,2,3]);", 1, 0.5, 23.5);
}

TEST(curved_volumes_add_up)
{
    static const char *a = "sphere(1, $fn=24);";
    static const char *b = "translate([0.5,0.2,0.1]) rotate([10,20,30]) cylinder(h=3, r=0.4, "
                           "center=true, $fn=10);";
    char text[512];
    double v[5];
    const char *ops[] = {"union", "intersection", "difference"};
    result r;
    for (int i = 0; i < 3; i++) {
        snprintf(text, sizeof text, "%s() { %s %s }", ops[i], a, b);
        if (!eval_text(text, &r))
            return;
        CHECK_MSG(mcsg_check_report_is_valid(&r.report), "%s: invalid output", text);
        CHECK(r.report.components == 1);
        v[i] = r.report.volume;
        mcsg_mesh_free(&r.mesh, NULL);
    }
    for (int i = 0; i < 2; i++) {
        snprintf(text, sizeof text, "union() { %s }", i == 0 ? a : b);
        if (!eval_text(text, &r))
            return;
        v[3 + i] = r.report.volume;
        mcsg_mesh_free(&r.mesh, NULL);
    }
    CHECK(v[1] > 0.1 && v[2] > 1);
    CHECK_MSG(fabs(v[0] + v[1] - v[3] - v[4]) < 1e-12, "union + intersection %.17g vs %.17g",
              v[0] + v[1], v[3] + v[4]);
    CHECK_MSG(fabs(v[2] - (v[3] - v[1])) < 1e-12, "difference %.17g vs %.17g", v[2],
              v[3] - v[1]);
}

/* A cylinder through a sphere along its axis, both with edges in the same vertical
 * planes: crossings exactly on the sphere's edges, and intersection points closer than
 * the rounding, which the output joins. */
TEST(aligned_edges_and_close_points)
{
    result r[4];
    const char *ops[] = {"union", "intersection", "difference"};
    char text[256];
    for (int i = 0; i < 3; i++) {
        snprintf(text, sizeof text,
                 "%s() { sphere(1, $fn=30); cylinder(h=3, r=0.3, center=true, $fn=12); }",
                 ops[i]);
        if (!eval_text(text, &r[i]))
            return;
        CHECK_MSG(mcsg_check_report_is_valid(&r[i].report), "%s: invalid output", text);
    }
    if (!eval_text("sphere(1, $fn=30);", &r[3]))
        return;
    CHECK(fabs(r[1].report.volume + r[2].report.volume - r[3].report.volume) < 1e-12);
    CHECK(r[0].report.volume > r[3].report.volume);
    for (int i = 0; i < 4; i++)
        mcsg_mesh_free(&r[i].mesh, NULL);
}

TEST(provenance_names_leaf_faces)
{
    mcsg_tree *tree = parse("difference() { cube(2); translate([1,1,1]) cube(2); }");
    mcsg_mesh out;
    mcsg_provenance *prov = NULL;
    mcsg_error err;
    size_t from_second = 0;
    if (!tree)
        return;
    CHECK_OK(mcsg_eval(tree, NULL, &out, &prov, NULL, &err), &err);
    CHECK(prov != NULL);
    for (size_t t = 0; prov && t < out.triangle_count; t++) {
        const mcsg_mesh *leaf = mcsg_tree_leaf_mesh(tree, prov[t].leaf);
        const uint32_t *tri = out.triangles + 3 * t;
        CHECK(mcsg_tree_node_kind(tree, prov[t].leaf) == MCSG_NODE_LEAF && leaf);
        if (!leaf || prov[t].face >= leaf->triangle_count) {
            CHECK(false);
            continue;
        }
        /* The triangle lies in its face's plane (box faces: one coordinate constant). */
        for (int k = 0; k < 3; k++) {
            const uint32_t *f = leaf->triangles + 3 * (size_t)prov[t].face;
            const double *a = leaf->vertices + 3 * (size_t)f[0], *b = leaf->vertices + 3 * (size_t)f[1],
                         *c = leaf->vertices + 3 * (size_t)f[2];
            if (a[k] == b[k] && b[k] == c[k])
                for (int i = 0; i < 3; i++)
                    CHECK(out.vertices[3 * (size_t)tri[i] + k] == a[k]);
        }
        from_second += prov[t].leaf != prov[0].leaf;
    }
    CHECK(from_second > 0); /* the carved corner comes from the second cube, reversed */
    mcsg_free(prov, NULL);
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
}

TEST(empty_and_trivial_trees)
{
    expect_empty("union() { }");
    expect_empty("difference() { }");
    expect_empty("intersection() { cube(1); translate([5,0,0]) cube(1); }");
    expect_solid("cube(3);", 27, 1);
    expect_solid("difference() { cube(3); translate([5,0,0]) cube(1); }", 27, 1);
    expect_solid("union() { cube(1); translate([5,0,0]) cube(1); }", 2, 2);
}

/* An allocator that hands out blocks from the top of an arena downwards, so that the
 * leaves' meshes sit in memory in the reverse of the usual order. Single-threaded. */
typedef struct downward_arena {
    unsigned char *base;
    size_t top;
} downward_arena;

static void *arena_malloc(void *user, size_t size)
{
    downward_arena *a = user;
    size_t need = (size + 2 * sizeof(max_align_t) - 1) / sizeof(max_align_t) * sizeof(max_align_t);
    if (need > a->top)
        return NULL;
    a->top -= need;
    memcpy(a->base + a->top, &size, sizeof size);
    return a->base + a->top + sizeof(max_align_t);
}

static void *arena_realloc(void *user, void *ptr, size_t size)
{
    size_t old;
    void *fresh = arena_malloc(user, size);
    if (ptr && fresh) {
        memcpy(&old, (unsigned char *)ptr - sizeof(max_align_t), sizeof old);
        memcpy(fresh, ptr, old < size ? old : size);
    }
    return fresh;
}

static void arena_free(void *user, void *ptr)
{
    (void)user;
    (void)ptr;
}

static bool eval_with(const char *text, const mcsg_options *opts, mcsg_mesh *out)
{
    mcsg_error err;
    mcsg_status st = test_eval_scad(text, opts, out, NULL, &err);
    CHECK_OK(st, &err);
    return st == MCSG_OK;
}

/* The output must not depend on the thread count or on where the leaves sit in memory:
 * canonical point definitions once followed memory addresses, and their floating-point
 * approximations (hence the rounded output) changed from run to run. */
TEST(output_is_independent_of_memory_layout_and_threads)
{
    const char *scene =
        "union() { rotate([10,20,30]) sphere(r=2,$fn=24); translate([1.3,0.2,0.1])"
        " rotate([40,5,70]) sphere(r=1.7,$fn=20); translate([0.4,1.1,-0.3]) rotate([3,60,9])"
        " cylinder(h=4,r=1,center=true,$fn=18); translate([-0.7,0.3,0.9]) rotate([33,-12,7])"
        " cube([2,1.5,1.2],center=true); }";
    size_t arena_size = (size_t)256 << 20;
    downward_arena arena = {malloc(arena_size), arena_size};
    mcsg_options normal = {0}, reversed = {0};
    mcsg_mesh a, b;
    reversed.allocator = (mcsg_allocator){arena_malloc, arena_realloc, arena_free, &arena};
    reversed.threads = 1;
    normal.threads = 2;
    if (!arena.base || !eval_with(scene, &normal, &a))
        return;
    if (eval_with(scene, &reversed, &b)) {
        CHECK(a.vertex_count == b.vertex_count && a.triangle_count == b.triangle_count);
        if (a.vertex_count == b.vertex_count && a.triangle_count == b.triangle_count) {
            CHECK(memcmp(a.vertices, b.vertices, 3 * a.vertex_count * sizeof(double)) == 0);
            CHECK(memcmp(a.triangles, b.triangles, 3 * a.triangle_count * sizeof(uint32_t)) == 0);
        }
    }
    CHECK(a.triangle_count > 500);
    mcsg_mesh_free(&a, &normal);
    free(arena.base);
}

static bool same_mesh(const mcsg_mesh *a, const mcsg_mesh *b)
{
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           memcmp(a->vertices, b->vertices, 3 * a->vertex_count * sizeof(double)) == 0 &&
           memcmp(a->triangles, b->triangles, 3 * a->triangle_count * sizeof(uint32_t)) == 0;
}

static const char *const pool_scene =
    "difference() { union() { rotate([10,20,30]) sphere(r=2,$fn=24);"
    " translate([1.3,0.2,0.1]) rotate([40,5,70]) sphere(r=1.7,$fn=20); }"
    " translate([0.4,1.1,-0.3]) rotate([3,60,9]) cylinder(h=4,r=1,center=true,$fn=18); }";

typedef struct pool_user {
    const mcsg_options *opts;
    mcsg_mesh out;
    int runs, same;
    const mcsg_mesh *expected;
} pool_user;

static void *evaluate_repeatedly(void *arg)
{
    pool_user *u = arg;
    for (int r = 0; r < u->runs; r++) {
        mcsg_mesh m;
        if (test_eval_scad(pool_scene, u->opts, &m, NULL, NULL) != MCSG_OK)
            continue;
        u->same += same_mesh(&m, u->expected);
        mcsg_mesh_free(&m, u->opts);
    }
    return NULL;
}

/* Workers shared through mcsg_options.pool: the same output as without, call after call,
 * and with two threads evaluating at once (one of them finds the pool busy and runs its
 * loops alone). One thread needs no pool. */
TEST(shared_worker_pool)
{
    mcsg_options own = {0}, shared = {0}, single = {0};
    mcsg_pool *pool = NULL, *none = (mcsg_pool *)&none;
    mcsg_mesh reference;
    mcsg_error err;
    pthread_t other;
    pool_user users[2];
    single.threads = 1;
    CHECK(mcsg_pool_create(&single, &none, &err) == MCSG_OK && none == NULL);
    own.threads = 3;
    if (!eval_with(pool_scene, &own, &reference))
        return;
    CHECK_OK(mcsg_pool_create(&own, &pool, &err), &err);
    CHECK(pool != NULL);
    shared.threads = 3;
    shared.pool = pool;
    for (int k = 0; k < 2; k++)
        users[k] = (pool_user){&shared, {0}, 6, 0, &reference};
    evaluate_repeatedly(&users[0]);
    CHECK_MSG(users[0].same == 6, "%d of 6 runs gave the same mesh", users[0].same);
    users[0].same = 0;
    CHECK(pthread_create(&other, NULL, evaluate_repeatedly, &users[1]) == 0);
    evaluate_repeatedly(&users[0]);
    pthread_join(other, NULL);
    CHECK_MSG(users[0].same == 6 && users[1].same == 6, "concurrent runs: %d and %d of 6 the "
              "same", users[0].same, users[1].same);
    mcsg_pool_free(pool);
    mcsg_pool_free(NULL);
    mcsg_mesh_free(&reference, &own);
}

static mcsg_status create_pool_under(const void *ctx, const mcsg_options *opts,
                                     mcsg_error *err)
{
    mcsg_options three = *opts;
    mcsg_pool *pool = NULL;
    mcsg_status st;
    (void)ctx;
    three.threads = 3;
    st = mcsg_pool_create(&three, &pool, err);
    CHECK((st == MCSG_OK) == (pool != NULL));
    mcsg_pool_free(pool);
    return st;
}

TEST(pool_creation_reports_allocation_failure)
{
    CHECK(test_allocation_failures("mcsg_pool_create", create_pool_under, NULL, false) >= 1);
}

/* Touching parts at both ends of a big output: vertex copies are made in chunks of 4,096
 * vertices on the threads and numbered in vertex order, so the mesh is the same for any
 * thread count, with copies from the first chunk and from a later one. */
TEST(touching_parts_in_a_big_output)
{
    const char *sphere = "translate([5, 0, 0]) sphere(1, $fn = 160);";
    char text[256];
    mcsg_options one = {0}, three = {0};
    mcsg_mesh a, b, alone;
    mcsg_eval_stats stats;
    mcsg_error err;
    one.threads = 1;
    three.threads = 3;
    snprintf(text, sizeof text, "union() { cube(1); translate([1, 1, 0]) cube(1); %s "
             "translate([10, 0, 0]) cube(1); translate([11, 1, 0]) cube(1); }", sphere);
    if (!eval_with(sphere, &one, &alone))
        return;
    CHECK_OK(test_eval_scad(text, &three, &a, &stats, &err), &err);
    CHECK_EQ_SIZE(stats.touching_vertices_split, 4);
    CHECK(a.vertex_count > 3 * 4096);
    CHECK(test_index_manifold_defects(&a) == 0);
    CHECK(fabs(test_signed_volume(&a) - test_signed_volume(&alone) - 4) < 1e-9);
    if (eval_with(text, &one, &b)) {
        CHECK(a.vertex_count == b.vertex_count && a.triangle_count == b.triangle_count);
        if (a.vertex_count == b.vertex_count && a.triangle_count == b.triangle_count) {
            CHECK(memcmp(a.vertices, b.vertices, 3 * a.vertex_count * sizeof(double)) == 0);
            CHECK(memcmp(a.triangles, b.triangles, 3 * a.triangle_count * sizeof(uint32_t)) == 0);
        }
        mcsg_mesh_free(&b, NULL);
    }
    /* One pair of cubes is numbered before the sphere, one after it. */
    CHECK(a.vertex_count > 4096 && a.vertices[0] < 3 && a.vertices[3 * (a.vertex_count - 5)] > 9);
    mcsg_mesh_free(&a, NULL);
    mcsg_mesh_free(&alone, NULL);
}

static mcsg_status eval_under(const void *ctx, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_mesh out;
    mcsg_provenance *prov;
    mcsg_status st = mcsg_eval(ctx, opts, &out, &prov, NULL, err);
    if (st == MCSG_OK) {
        CHECK(out.triangle_count > 0);
        mcsg_free(prov, opts);
        mcsg_mesh_free(&out, opts);
    }
    return st;
}

TEST(allocation_failures_leak_nothing)
{
    /* Small (the sweep is quadratic in the allocation count) but with crossings,
     * coplanar faces, several regions and a complemented leaf. */
    mcsg_tree *tree = parse("difference() { union() { cube(2); translate([1,1,0]) cube(2); }"
                            " translate([0.5,0.5,0.5]) cube(1); }");
    long calls;
    if (!tree)
        return;
    calls = test_allocation_failures("mcsg_eval", eval_under, tree, false);
    CHECK(calls > 100);
    printf("mcsg_eval: %ld allocations, each failed once\n", calls);
    mcsg_tree_free(tree);
}

/* mcsg_mesh_repair: the solid of one mesh, with its shells counted. */
static mcsg_mesh box_shells_mesh(const double *lo, const double *hi, const bool *inward, int n)
{
    char *text = box_shells(lo, hi, inward, n);
    mcsg_tree *tree = parse(text);
    mcsg_mesh m = {0};
    mcsg_error err;
    if (tree)
        CHECK_OK(mcsg_mesh_copy(mcsg_tree_leaf_mesh(tree, mcsg_tree_root(tree)), NULL, &m, &err),
                 &err);
    mcsg_tree_free(tree);
    free(text);
    return m;
}

static mcsg_status repair_under(const void *ctx, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_mesh out;
    mcsg_status st = mcsg_mesh_repair(ctx, opts, &out, NULL, err);
    if (st == MCSG_OK)
        mcsg_mesh_free(&out, opts);
    return st;
}

TEST(repair_joins_overlapping_shells)
{
    const double lo[] = {0, 5, 2}, hi[] = {10, 15, 8};
    const bool out_out[] = {false, false, false}, out_in[] = {false, false, true};
    mcsg_mesh two = box_shells_mesh(lo, hi, out_out, 2), hollow = box_shells_mesh(lo, hi, out_in, 3);
    mcsg_mesh out;
    mcsg_repair_stats st;
    mcsg_check_report r;
    mcsg_error err;
    CHECK_OK(mcsg_mesh_repair(&two, NULL, &out, &st, &err), &err);
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    CHECK(st.shells_in == 2 && st.shells_out == 1 && st.cavities == 0 && st.crossing_pairs > 0);
    CHECK(mcsg_check_report_is_valid(&r) && fabs(r.volume - 1875) < 1e-9);
    mcsg_mesh_free(&out, NULL);
    /* [0,10] and [5,15] overlapping, with an inward [2,8]: where it is inside both cubes
     * the winding number stays 1, so the cavity is [2,8]^3 less [5,8]^3. */
    CHECK_OK(mcsg_mesh_repair(&hollow, NULL, &out, &st, &err), &err);
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    CHECK(st.shells_in == 3 && st.shells_out == 2 && st.cavities == 1);
    CHECK(mcsg_check_report_is_valid(&r) && fabs(r.volume - (1875 - (216 - 27))) < 1e-9);
    mcsg_mesh_free(&out, NULL);
    CHECK(mcsg_mesh_repair(NULL, NULL, &out, &st, &err) == MCSG_ERR_INVALID_ARG);
    /* A failure may be absorbed: classification can need the optional per-thread table
     * of exact points (src/exact/exact_cache.c), whose failed allocation only costs
     * speed. */
    CHECK(test_allocation_failures("mcsg_mesh_repair", repair_under, &two, true) > 50);
    mcsg_mesh_free(&two, NULL);
    mcsg_mesh_free(&hollow, NULL);
}

/* Progress: the steps mcsg_progress_fn documents, in order, each started and ended; a
 * callback returning non-zero stops the evaluation there, cleanly. */
typedef struct progress_log {
    char steps[16][16];
    int done[16];
    int count;
    int stop_at; /* the report (0-based) that returns non-zero; -1: never */
} progress_log;

static int log_progress(void *user, const char *step, int done)
{
    progress_log *p = user;
    if (p->count < 16) {
        snprintf(p->steps[p->count], sizeof p->steps[0], "%s", step);
        p->done[p->count] = done;
    }
    return p->count++ == p->stop_at;
}

static mcsg_status eval_reporting(const mcsg_tree *tree, progress_log *p, test_allocator *a,
                                  mcsg_mesh *out, mcsg_error *err)
{
    mcsg_options opts = test_allocator_options(a);
    opts.progress = log_progress;
    opts.progress_user = p;
    return mcsg_eval(tree, &opts, out, NULL, NULL, err);
}

TEST(progress_reports_steps_and_can_cancel)
{
    static const char *const order[] = {"check", "intersect", "triangulate", "classify",
                                        "assemble"};
    mcsg_tree *tree = parse("difference() { cube(2); translate([1,1,1]) sphere(1, $fn=12); }");
    progress_log p = {.stop_at = -1};
    test_allocator a = {0};
    mcsg_mesh out;
    mcsg_error err;
    if (!tree)
        return;
    CHECK_OK(eval_reporting(tree, &p, &a, &out, &err), &err);
    CHECK(out.triangle_count > 0);
    mcsg_mesh_free(&out, &(mcsg_options){.allocator = test_allocator_options(&a).allocator});
    CHECK_EQ_SIZE(p.count, 10);
    for (int i = 0; i < 10 && i < p.count; i++)
        CHECK_MSG(strcmp(p.steps[i], order[i / 2]) == 0 && p.done[i] == i % 2,
                  "report %d: %s %d", i, p.steps[i], p.done[i]);
    /* Stopped at every report: MCSG_ERR_CANCELLED naming the step, no mesh, no leak. */
    for (int stop = 0; stop < 10; stop++) {
        progress_log q = {.stop_at = stop};
        test_allocator b = {0};
        mcsg_status st = eval_reporting(tree, &q, &b, &out, &err);
        CHECK_MSG(st == MCSG_ERR_CANCELLED, "stopping at report %d: status %s", stop,
                  mcsg_status_string(st));
        CHECK_EQ_SIZE(q.count, stop + 1);
        CHECK_CONTAINS(err.message, order[stop / 2]);
        CHECK(out.triangle_count == 0 && out.vertices == NULL && out.triangles == NULL);
        CHECK_EQ_SIZE(b.live, 0);
    }
    CHECK(strcmp(mcsg_status_string(MCSG_ERR_CANCELLED), "cancelled") == 0);
    mcsg_tree_free(tree);
}

TEST(intersect_reports_progress_and_can_cancel)
{
    mcsg_tree *tree = parse("union() { cube(2); translate([1,1,1]) cube(2); }");
    progress_log p = {.stop_at = -1}, q = {.stop_at = 1};
    mcsg_options opts = {0};
    mcsg_curves c;
    mcsg_error err;
    if (!tree)
        return;
    opts.progress = log_progress;
    opts.progress_user = &p;
    CHECK_OK(mcsg_intersect(tree, &opts, &c, NULL, &err), &err);
    CHECK(c.segment_count > 0);
    mcsg_curves_free(&c, NULL);
    CHECK(p.count == 2 && strcmp(p.steps[0], "intersect") == 0 && p.done[1] == 1);
    opts.progress_user = &q;
    CHECK(mcsg_intersect(tree, &opts, &c, NULL, &err) == MCSG_ERR_CANCELLED);
    CHECK(c.points == NULL && c.segments == NULL);
    mcsg_tree_free(tree);
}

/* The result's check (stats.output_check) agrees with independent checks of the output:
 * mcsg_mesh_check (vertices welded by coordinates), the index-manifold test of testlib,
 * and mcsg_mesh_self_intersections. Cases: results that rounding to doubles broke
 * (tests/data/rounding: an edge of four triangles even by index; crossing triangles;
 * OpenSCAD's example018 moved off the origin), cubes touching along an edge (allowed:
 * the exact result touches itself there), and a clean result. Whatever the rounding
 * does to these cases, the report must tell it: never a silent success. */
static void check_output_report(const char *path, const char *text, int expect)
{
    mcsg_options opts = {0};
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_eval_stats st;
    mcsg_check_report r;
    mcsg_error err;
    size_t pairs = 0;
    const mcsg_output_check *c = &st.output_check;
    opts.check_output_crossings = 1;
    CHECK_OK(path ? mcsg_scad_read(test_data(path), NULL, &tree, &err)
                  : mcsg_scad_read_memory(text, strlen(text), "case", NULL, NULL, &tree, &err),
             &err);
    if (!tree)
        return;
    CHECK_OK(mcsg_eval(tree, &opts, &out, NULL, &st, &err), &err);
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    CHECK_OK(mcsg_mesh_self_intersections(&out, NULL, &pairs, NULL, &err), &err);
    CHECK_MSG(r.nonmanifold_edges == c->welded_nonmanifold_edges + c->touching_edges &&
                  r.boundary_edges == c->open_edges &&
                  r.inconsistent_edges == c->misoriented_edges &&
                  r.degenerate_triangles == c->degenerate_triangles,
              "%s: check %zu/%zu/%zu/%zu, report %zu+%zu/%zu/%zu/%zu", path ? path : text,
              r.nonmanifold_edges, r.boundary_edges, r.inconsistent_edges,
              r.degenerate_triangles, c->welded_nonmanifold_edges, c->touching_edges,
              c->open_edges, c->misoriented_edges, c->degenerate_triangles);
    CHECK(c->crossings_checked && c->crossing_pairs == pairs);
    /* testlib's count includes vertices whose triangles are not one umbrella */
    CHECK(c->index_nonmanifold_edges == 0 || test_index_manifold_defects(&out) > 0);
    CHECK(!(r.nonmanifold_edges > c->touching_edges || pairs > 0) ||
          mcsg_output_check_failed(c));
    CHECK_MSG(expect < 0 || mcsg_output_check_failed(c) == expect, "%s: failed %d",
              path ? path : text, mcsg_output_check_failed(c));
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
}

TEST(output_check_tells_what_rounding_broke)
{
    check_output_report("rounding/nonmanifold-by-index-5-boxes/tree.scad", NULL, -1);
    check_output_report("rounding/crossing-after-rounding-3-cubes/tree.scad", NULL, -1);
    check_output_report("rounding/example018-moved.scad", NULL, -1);
    check_output_report(NULL, "union() { cube(1); translate([1, 1, 0]) cube(1); }", 0);
    check_output_report(NULL, "difference() { cube(2); translate([1, 1, 1]) sphere(1); }", 0);
    {
        mcsg_tree *tree = parse("union() { cube(1); translate([1, 1, 0]) cube(1); }");
        mcsg_mesh out;
        mcsg_eval_stats st;
        mcsg_error err;
        if (tree && mcsg_eval(tree, NULL, &out, NULL, &st, &err) == MCSG_OK) {
            CHECK(st.output_check.touching_edges == 1 && !st.output_check.crossings_checked);
            mcsg_mesh_free(&out, NULL);
        }
        mcsg_tree_free(tree);
    }
}

/* example018 moved off the origin: rounding makes parts touch along four edges (four
 * triangles on each once welded). Moving four vertex copies apart by one unit in the
 * last place keeps every guarantee checked by default, with no round of evaluating
 * again; the triangles still name faces of the tree's leaves. With crossings checked as
 * well, a sliver that rounding turned over is split away, and three rounds of evaluating
 * the rounded result again by its winding number settle the rest (the last round's
 * regions of a few units in the last place wide are decided by rays from points found
 * by bisection). */
TEST(rounding_broken_result_is_evaluated_again)
{
    mcsg_options opts = {0};
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_provenance *prov = NULL;
    mcsg_eval_stats st;
    mcsg_check_report r;
    mcsg_error err;
    CHECK_OK(mcsg_scad_read(test_data("rounding/example018-moved.scad"), NULL, &tree, &err),
             &err);
    if (!tree)
        return;
    /* with its flat vertices removed, the result has no sliver for rounding to turn over
     * and comes out clean even with crossings checked */
    opts.check_output_crossings = 1;
    CHECK_OK(mcsg_eval(tree, &opts, &out, NULL, &st, &err), &err);
    CHECK(st.flat_vertices_removed > 0 && st.rounding_turned_triangles == 0);
    CHECK(!mcsg_output_check_failed(&st.output_check) && st.output_check.crossings_checked);
    mcsg_mesh_free(&out, NULL);
    /* the exact result's every vertex, as the case was found */
    opts.check_output_crossings = 0;
    opts.keep_all_vertices = 1;
    CHECK_OK(mcsg_eval(tree, &opts, &out, &prov, &st, &err), &err);
    CHECK_EQ_SIZE(st.rounding_separated_vertices, 4);
    CHECK(st.rounding_reevaluations == 0);
    CHECK(!mcsg_output_check_failed(&st.output_check));
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    CHECK(mcsg_check_report_is_valid(&r) && r.components == 1);
    CHECK_MSG(fabs(r.volume - 175969.18382477) < 1e-6, "volume %.17g", r.volume);
    for (size_t t = 0; prov && t < out.triangle_count; t++) {
        const mcsg_mesh *leaf = mcsg_tree_leaf_mesh(tree, prov[t].leaf);
        CHECK_MSG(leaf && prov[t].face < leaf->triangle_count, "triangle %zu: leaf %u face %u",
                  t, prov[t].leaf, prov[t].face);
        if (!leaf)
            break;
    }
    mcsg_free(prov, NULL);
    mcsg_mesh_free(&out, NULL);
    opts.check_output_crossings = 1;
    CHECK_OK(mcsg_eval(tree, &opts, &out, NULL, &st, &err), &err);
    CHECK(st.rounding_turned_triangles == 1 && st.rounding_reevaluation_kept == 1);
    CHECK(!mcsg_output_check_failed(&st.output_check) && st.output_check.crossings_checked);
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    CHECK(mcsg_check_report_is_valid(&r) && r.components == 1);
    CHECK_MSG(fabs(r.volume - 175969.18382477) < 1e-6, "volume %.17g", r.volume);
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
}

/* A cube with one change: a triangle dropped, flipped, repeated, or a vertex moved. */
static const double contract_cube_v[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                                         0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
static const uint32_t contract_cube_t[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                           1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};

static const double identity_matrix[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

/* The tree op(a, b) through the API, each leaf under its matrix and with its label. */
static mcsg_tree *tree_of_two(const mcsg_mesh *a, const double *ma, const char *la,
                              const mcsg_mesh *b, const double *mb, const char *lb,
                              mcsg_node_kind op, mcsg_error *err)
{
    mcsg_tree *tree = NULL;
    mcsg_node_id ids[2], root;
    CHECK_OK(mcsg_tree_create(NULL, &tree, err), err);
    CHECK_OK(mcsg_tree_add_leaf(tree, a, ma, la, &ids[0], err), err);
    CHECK_OK(mcsg_tree_add_leaf(tree, b, mb, lb, &ids[1], err), err);
    CHECK_OK(mcsg_tree_add_op(tree, op, ids, 2, NULL, &root, err), err);
    CHECK_OK(mcsg_tree_set_root(tree, root, err), err);
    return tree;
}

/* Evaluates union(cube(2), leaf) through the API; the status and message. */
static mcsg_status eval_with_leaf_opts(const mcsg_mesh *leaf, const mcsg_options *opts,
                                       mcsg_error *err)
{
    double size[3] = {2, 2, 2};
    mcsg_tree *tree;
    mcsg_mesh cube, out;
    mcsg_status st;
    CHECK_OK(mcsg_make_cube(size, 1, NULL, &cube, err), err);
    tree = tree_of_two(&cube, identity_matrix, "big cube", leaf, identity_matrix, "the leaf",
                       MCSG_NODE_UNION, err);
    st = mcsg_eval(tree, opts, &out, NULL, NULL, err);
    CHECK(st != MCSG_OK || out.triangle_count > 0);
    mcsg_mesh_free(&out, NULL);
    mcsg_mesh_free(&cube, NULL);
    mcsg_tree_free(tree);
    return st;
}

static mcsg_status eval_with_leaf(const mcsg_mesh *leaf, mcsg_error *err)
{
    return eval_with_leaf_opts(leaf, NULL, err);
}

static void expect_contract_error(const mcsg_mesh *leaf, const char *problem)
{
    mcsg_error err;
    CHECK(eval_with_leaf(leaf, &err) == MCSG_ERR_INVALID_MESH);
    CHECK_CONTAINS(err.message, "leaf 1, the leaf: ");
    CHECK_CONTAINS(err.message, problem);
}

/* mcsg_eval checks every leaf against its input contract before any geometry and names
 * the first that breaks it. */
TEST(input_contract_is_checked)
{
    double v[24];
    uint32_t t[39];
    mcsg_mesh m = {v, t, 8, 12};
    mcsg_error err;
    memcpy(v, contract_cube_v, sizeof contract_cube_v);
    memcpy(t, contract_cube_t, sizeof contract_cube_t);
    CHECK_OK(eval_with_leaf(&m, &err), &err);
    m.triangle_count = 11;
    expect_contract_error(&m, "the surface is open: 3 boundary edges, e.g. from (");
    m.triangle_count = 13;
    memcpy(t + 36, t, 3 * sizeof *t);
    expect_contract_error(&m, "the surface does not close up: 3 edges of more than two "
                              "triangles are used more often one way than the other, e.g. ");
    m.triangle_count = 12;
    t[0] = 0, t[1] = 1, t[2] = 2; /* one triangle flipped */
    expect_contract_error(&m, "not consistently oriented");
    for (int i = 0; i < 12; i++) { /* all flipped */
        t[3 * i] = contract_cube_t[3 * i];
        t[3 * i + 1] = contract_cube_t[3 * i + 2];
        t[3 * i + 2] = contract_cube_t[3 * i + 1];
    }
    /* Inside out is valid: the leaf's solid is empty, the union the big cube alone. */
    CHECK_OK(eval_with_leaf(&m, &err), &err);
    memcpy(t, contract_cube_t, sizeof contract_cube_t);
    v[3 * 6] = NAN;
    expect_contract_error(&m, "NaN or infinite coordinates, e.g. vertex 6");
    v[3 * 6] = 1;
    {
        /* Zero-area triangles back to back are valid too: edge 0-1 of a tetrahedron has
         * vertex 4 on one side and 5 on the other, and the two zero-area triangles
         * (0, 4, 1) and (0, 1, 5) close the gaps; they go together, their neighbours
         * split at both (test_zero_area checks the copy). */
        static const double tv[] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2, 1, 0, 0, 0.5, 0, 0};
        static const uint32_t tt[] = {0, 2, 4, 4, 2, 1, 0, 4, 1, 0, 5, 3,
                                      5, 1, 3, 0, 1, 5, 0, 3, 2, 1, 2, 3};
        mcsg_mesh sliver = {(double *)tv, (uint32_t *)tt, 6, 8};
        CHECK_OK(eval_with_leaf(&sliver, &err), &err);
    }
}

/* op(cube, slab) through the API, the slab [-0.5,1.5]^2 x [1,1.5] lying on the cube's
 * top face and reaching past its edges; the output's volume and triangle count. */
static bool cube_and_slab(const mcsg_mesh *cube, mcsg_node_kind op, double *volume,
                          size_t *triangles)
{
    static const double on_top[12] = {1, 0, 0, 0.5, 0, 1, 0, 0.5, 0, 0, 1, 1.25};
    double size[3] = {2, 2, 0.5};
    mcsg_tree *tree;
    mcsg_mesh slab, out;
    mcsg_error err;
    mcsg_status st;
    CHECK_OK(mcsg_make_cube(size, 1, NULL, &slab, &err), &err);
    tree = tree_of_two(cube, identity_matrix, "cube", &slab, on_top, "slab", op, &err);
    st = mcsg_eval(tree, NULL, &out, NULL, NULL, &err);
    CHECK_MSG(st == MCSG_OK, "%s", err.message);
    if (st == MCSG_OK) {
        *volume = test_signed_volume(&out);
        *triangles = out.triangle_count;
        mcsg_mesh_free(&out, NULL);
    }
    mcsg_mesh_free(&slab, NULL);
    mcsg_tree_free(tree);
    return st == MCSG_OK;
}

/* A leaf whose triangles each have their own three vertices (a triangle soup, as STL
 * files and meshes read without welding give) is the same solid as the welded one: its
 * faces are neighbours by coordinates, and its cube's edges are still where the surface
 * bends. Taken as flat once, the slab's bottom face had no constraint along the cube's
 * edges and its triangulation failed. */
TEST(triangle_soup_leaf_is_its_welded_solid)
{
    double v[3 * 36];
    uint32_t t[36];
    mcsg_mesh welded = {(double *)contract_cube_v, (uint32_t *)contract_cube_t, 8, 12};
    mcsg_mesh soup = {v, t, 36, 12};
    static const mcsg_node_kind ops[] = {MCSG_NODE_UNION, MCSG_NODE_DIFFERENCE,
                                         MCSG_NODE_INTERSECTION};
    static const double volumes[] = {3, 1, 0};
    for (int i = 0; i < 36; i++) {
        memcpy(v + 3 * i, contract_cube_v + 3 * contract_cube_t[i], 3 * sizeof *v);
        t[i] = (uint32_t)i;
    }
    for (int k = 0; k < 3; k++) {
        double vs = -1, vw = -1;
        size_t ts = 0, tw = 0;
        if (!cube_and_slab(&soup, ops[k], &vs, &ts) || !cube_and_slab(&welded, ops[k], &vw, &tw))
            continue;
        CHECK_MSG(vs == volumes[k] && vw == volumes[k] && ts == tw,
                  "op %d: soup %.17g (%zu triangles), welded %.17g (%zu)", k, vs, ts, vw, tw);
    }
}

typedef struct warning_log {
    int warnings;
    char last[400];
} warning_log;

static void keep_warnings(void *user, mcsg_log_level level, const char *message)
{
    warning_log *w = user;
    if (level != MCSG_LOG_WARNING)
        return;
    w->warnings++;
    snprintf(w->last, sizeof w->last, "%s", message);
}

/* A leaf of one shell enclosing a positive volume, like every clean leaf, is not tested
 * for crossing itself unless the options ask; fuzz seed 0x6472ad9c07c636ec (shrunk to 3
 * leaves) has one that does (8 points, 12 faces), and the exact result came out open (23
 * open edges, status 3). An open or misoriented result is what such a leaf makes and
 * clean leaves never do, so the untested leaves are then tested and the evaluation done
 * again: the same mesh as with the leaves tested up front, and a warning says why. */
TEST(open_result_tests_the_leaves_left_untested)
{
    mcsg_tree *tree = NULL;
    mcsg_mesh out, tested;
    mcsg_options opts;
    mcsg_eval_stats st;
    mcsg_check_report r;
    mcsg_error err;
    warning_log log = {0, ""};
    CHECK_OK(mcsg_scad_read(test_data("csg-regressions/seed-6472ad9c07c636ec.scad"), NULL,
                            &tree, &err), &err);
    if (!tree)
        return;
    memset(&opts, 0, sizeof opts);
    opts.log = keep_warnings;
    opts.log_user = &log;
    CHECK_OK(mcsg_eval(tree, &opts, &out, NULL, &st, &err), &err);
    CHECK(!mcsg_output_check_failed(&st.output_check));
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    CHECK(mcsg_check_report_is_valid(&r) && r.volume > 0);
    CHECK_MSG(strstr(log.last, "came out open because 1 primitives cross themselves"), "%s",
              log.last);
    memset(&opts, 0, sizeof opts);
    opts.check_self_intersections = 1;
    CHECK_OK(mcsg_eval(tree, &opts, &tested, NULL, &st, &err), &err);
    CHECK(same_mesh(&out, &tested));
    mcsg_mesh_free(&tested, NULL);
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
}

typedef struct thread_log {
    pthread_t caller;
    int calls, foreign;
    unsigned last_leaf;
    bool in_order;
} thread_log;

static void note_thread(void *user, mcsg_log_level level, const char *message)
{
    thread_log *l = user;
    unsigned leaf;
    (void)level;
    l->calls++;
    l->foreign += !pthread_equal(pthread_self(), l->caller);
    if (sscanf(message, "leaf %u:", &leaf) == 1) {
        l->in_order = l->in_order && leaf >= l->last_leaf;
        l->last_leaf = leaf;
    }
}

/* The log callback is called from the caller's thread only (meshcsg.h), also for what
 * the leaves' checks find while they run in parallel, and in leaf order: 24 spheres,
 * each tested for crossing itself (a line each), on four threads. */
TEST(leaf_messages_come_from_the_callers_thread)
{
    char text[4096];
    size_t len = (size_t)snprintf(text, sizeof text, "union() {");
    mcsg_options opts;
    mcsg_mesh out;
    mcsg_error err;
    thread_log log = {pthread_self(), 0, 0, 0, true};
    mcsg_tree *tree;
    for (int i = 0; i < 24; i++)
        len += (size_t)snprintf(text + len, sizeof text - len,
                                " translate([%d, %d, 0]) sphere(1, $fn = 12);", i % 6 * 3, i / 6 * 3);
    snprintf(text + len, sizeof text - len, " }");
    tree = parse(text);
    memset(&opts, 0, sizeof opts);
    opts.threads = 4;
    opts.check_self_intersections = 1;
    opts.log = note_thread;
    opts.log_user = &log;
    CHECK_OK(mcsg_eval(tree, &opts, &out, NULL, NULL, &err), &err);
    CHECK_MSG(log.calls >= 24 && log.foreign == 0 && log.in_order,
              "%d calls, %d from other threads, in leaf order %d", log.calls, log.foreign,
              log.in_order);
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
}

/* With crossings counted, a result with crossing triangles also has the untested leaves
 * tested: a sphere with its top vertex pushed through its bottom (one shell, positive
 * volume) came back as given, crossing itself, and only the rounds of evaluating the
 * rounded result again, snapped to a grid, mended it. Now it is the exact result of the
 * leaf tested up front, rounded once. */
TEST(crossing_result_tests_the_leaves_left_untested)
{
    mcsg_resolution res = {32, 0, 0};
    double size[3] = {1, 1, 1}, far[12] = {1, 0, 0, 10, 0, 1, 0, 0, 0, 0, 1, 0};
    mcsg_mesh sphere, cube, out, tested;
    mcsg_options opts;
    mcsg_eval_stats st;
    mcsg_check_report r;
    mcsg_error err;
    warning_log log = {0, ""};
    mcsg_tree *tree;
    size_t top = 0;
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &sphere, &err), &err);
    for (size_t v = 0; v < sphere.vertex_count; v++)
        if (sphere.vertices[3 * v + 2] > sphere.vertices[3 * top + 2])
            top = v;
    sphere.vertices[3 * top + 2] = -1.5;
    CHECK_OK(mcsg_mesh_check(&sphere, NULL, &r, &err), &err);
    CHECK(r.components == 1 && r.volume > 0);
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    tree = tree_of_two(&sphere, identity_matrix, "pushed sphere", &cube, far, "cube",
                       MCSG_NODE_UNION, &err);
    memset(&opts, 0, sizeof opts);
    opts.check_output_crossings = 1;
    opts.log = keep_warnings;
    opts.log_user = &log;
    CHECK_OK(mcsg_eval(tree, &opts, &out, NULL, &st, &err), &err);
    CHECK(!mcsg_output_check_failed(&st.output_check) && st.rounding_reevaluations == 0);
    CHECK_MSG(strstr(log.last, "with crossing triangles because 1 primitives cross"), "%s",
              log.last);
    opts.log = NULL;
    opts.check_self_intersections = 1;
    CHECK_OK(mcsg_eval(tree, &opts, &tested, NULL, &st, &err), &err);
    CHECK(same_mesh(&out, &tested));
    mcsg_mesh_free(&tested, NULL);
    mcsg_mesh_free(&out, NULL);
    mcsg_mesh_free(&sphere, NULL);
    mcsg_mesh_free(&cube, NULL);
    mcsg_tree_free(tree);
}

/* Zero-area triangles bound nothing (no solid angle from any point off them) and are
 * removed before evaluation; one with three distinct corners takes a split of its
 * neighbour across its long edge with it, so the leaf stays closed. Provenance names
 * the leaf's own triangles. */
TEST(zero_area_triangles_are_removed)
{
    /* A tetrahedron whose bottom edge 0-1 has its midpoint 4 as a vertex, the gap
     * closed by the zero-area triangle (0, 4, 1); the triangle (0, 1, 3) across that
     * edge is split at 4. And a repeated corner: triangle (2, 2, 3) goes alone. */
    static const double tv[] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2, 1, 0, 0};
    static const uint32_t tt[] = {0, 2, 4, 4, 2, 1, 0, 4, 1, 0, 1, 3,
                                  0, 3, 2, 1, 2, 3, 2, 2, 3};
    static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    double size[3] = {2, 2, 2};
    mcsg_mesh sliver = {(double *)tv, (uint32_t *)tt, 5, 7}, cube, out;
    mcsg_tree *tree;
    mcsg_node_id ids[2], root;
    mcsg_provenance *prov = NULL;
    mcsg_check_report r;
    mcsg_error err;
    mcsg_options keep_all = {0};
    bool named[7] = {false};
    keep_all.keep_all_vertices = 1;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_make_cube(size, 1, NULL, &cube, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &cube, identity, "cube", &ids[0], &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &sliver, identity, "sliver", &ids[1], &err), &err);
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_UNION, ids, 2, NULL, &root, &err), &err);
    CHECK_OK(mcsg_tree_set_root(tree, root, &err), &err);
    /* every vertex kept: the two halves of the split side then name their faces */
    CHECK_OK(mcsg_eval(tree, &keep_all, &out, &prov, NULL, &err), &err);
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    /* [-1,1]^3 and the tetrahedron x, y, z >= 0, x + y + z <= 2 (4/3) meet in 5/6. */
    CHECK(mcsg_check_report_is_valid(&r));
    CHECK_MSG(fabs(r.volume - 8.5) < 1e-12, "volume %.17g", r.volume);
    for (size_t t = 0; prov && t < out.triangle_count; t++)
        if (prov[t].leaf == ids[1] && prov[t].face < 7)
            named[prov[t].face] = true;
    /* Every face has a part outside the cube (the side (0, 1, 3) as its two halves);
     * no output triangle comes from a removed one. */
    CHECK(named[0] && named[1] && named[3] && named[4] && named[5] && !named[2] && !named[6]);
    CHECK(test_allocation_failures("mcsg_eval, zero-area triangles", eval_under, tree, false) >
          50);
    mcsg_free(prov, NULL);
    mcsg_mesh_free(&out, NULL);
    mcsg_mesh_free(&cube, NULL);
    mcsg_tree_free(tree);
}

/* A leaf whose one shell crosses itself: the unit cube with its corner (1, 1, 1) pushed
 * through the bottom face to (0.5, 0.5, -0.2). When the options ask, shells are tested
 * first, and this one is evaluated with its faces intersected with each other: its
 * solid, where its winding number is positive, has volume 10/27 (a generalized winding
 * number estimate over 216,000 points gives 0.3705), 16 triangles once cut. */
TEST(leaves_crossing_themselves)
{
    static const char *const pushed =
        "polyhedron(points=[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[0.5,0.5,-0.2],"
        "[0,1,1]], faces=[[0,1,2],[0,2,3],[4,6,5],[4,7,6],[0,5,1],[0,4,5],[1,6,2],[1,5,6],"
        "[2,7,3],[2,6,7],[3,4,0],[3,7,4]]);";
    mcsg_options opts;
    mcsg_mesh out;
    mcsg_eval_stats stats;
    mcsg_check_report r;
    mcsg_error err;
    char *text = tree_of("union", pushed, "translate([3,0,0]) cube(1);");
    memset(&opts, 0, sizeof opts);
    opts.check_self_intersections = 1;
    CHECK_OK(test_eval_scad(text, &opts, &out, &stats, &err), &err);
    CHECK_OK(mcsg_mesh_check(&out, NULL, &r, &err), &err);
    CHECK(mcsg_check_report_is_valid(&r) && r.components == 2);
    CHECK_MSG(fabs(r.volume - (1 + 10.0 / 27)) < 1e-12, "volume %.17g", r.volume);
    CHECK_EQ_SIZE(out.triangle_count, 16 + 12);
    mcsg_mesh_free(&out, NULL);
    /* Without the test up front the leaf is taken as it is: nothing trips, and the
     * union gives the input back (docs/robustness.md). */
    opts.check_self_intersections = 0;
    CHECK_OK(test_eval_scad(text, &opts, &out, &stats, &err), &err);
    CHECK_EQ_SIZE(out.triangle_count, 12 + 12);
    mcsg_mesh_free(&out, NULL);
    free(text);
}

int main(void)
{
    RUN(box_scenes_have_exact_volumes);
    RUN(plates_with_grids_of_holes);
    RUN(identical_operands);
    RUN(buried_faces_are_dropped_whole);
    RUN(copies_are_evaluated_once);
    RUN(touching_solids);
    RUN(touching_parts_in_a_big_output);
    RUN(shared_worker_pool);
    RUN(pool_creation_reports_allocation_failure);
    RUN(coplanar_overlaps);
    RUN(cad_fan_plates);
    RUN(curved_volumes_add_up);
    RUN(aligned_edges_and_close_points);
    RUN(provenance_names_leaf_faces);
    RUN(empty_and_trivial_trees);
    RUN(output_is_independent_of_memory_layout_and_threads);
    RUN(allocation_failures_leak_nothing);
    RUN(progress_reports_steps_and_can_cancel);
    RUN(intersect_reports_progress_and_can_cancel);
    RUN(output_check_tells_what_rounding_broke);
    RUN(input_contract_is_checked);
    RUN(triangle_soup_leaf_is_its_welded_solid);
    RUN(zero_area_triangles_are_removed);
    RUN(leaves_with_several_shells);
    RUN(leaves_with_crossing_shells);
    RUN(leaves_closed_as_chains);
    RUN(leaf_touching_itself_along_an_edge);
    RUN(leaves_entering_themselves_at_an_edge);
    RUN(shells_enclosing_no_volume);
    RUN(rounding_broken_result_is_evaluated_again);
    RUN(leaves_crossing_themselves);
    RUN(open_result_tests_the_leaves_left_untested);
    RUN(crossing_result_tests_the_leaves_left_untested);
    RUN(leaf_messages_come_from_the_callers_thread);
    RUN(repair_joins_overlapping_shells);
    return test_summary();
}
