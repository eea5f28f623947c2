/*
 * OpenSCAD's 2D shapes and the modules that use their children's geometry (src/scad/
 * shapes2d.c, geometry.c). Known answers come from OpenSCAD 2021.01 itself: the volume,
 * vertex and triangle counts of `openscad -o x.stl x.scad` for each text below (its STL
 * holds floats, hence the tolerance of 1e-5 relative); where the answer is exact
 * (prisms of rectangles) it is checked exactly.
 */
#include "testlib.h"

#include <math.h>
#include <string.h>

typedef struct log_capture {
    char text[4096];
} log_capture;

static void capture(void *user, mcsg_log_level level, const char *message)
{
    log_capture *log = user;
    size_t len = strlen(log->text);
    (void)level;
    snprintf(log->text + len, sizeof log->text - len, "%s\n", message);
}

/* Evaluate, check closed and manifold once welded, return the volume (NAN on failure). */
static double eval_volume(const char *text, size_t *vertices, size_t *triangles,
                          log_capture *log)
{
    mcsg_options opts;
    mcsg_mesh out;
    mcsg_eval_stats stats;
    mcsg_check_report report;
    mcsg_error err;
    double volume;
    memset(&opts, 0, sizeof opts);
    opts.log = log ? capture : NULL;
    opts.log_user = log;
    if (test_eval_scad(text, &opts, &out, &stats, &err) != MCSG_OK) {
        CHECK_MSG(false, "%s: %s", text, err.message);
        return NAN;
    }
    CHECK_OK(mcsg_mesh_check(&out, NULL, &report, &err), &err);
    CHECK_MSG(mcsg_check_report_is_valid(&report) &&
                  !mcsg_output_check_failed(&stats.output_check),
              "%s: %zu open, %zu non-manifold edges", text, report.boundary_edges,
              report.nonmanifold_edges);
    volume = test_signed_volume(&out);
    if (vertices)
        *vertices = out.vertex_count;
    if (triangles)
        *triangles = out.triangle_count;
    mcsg_mesh_free(&out, NULL);
    return volume;
}

/* Volume within `tolerance` (relative) of OpenSCAD's, and OpenSCAD's vertex and
 * triangle counts. */
static void check_openscad_within(const char *text, double volume, size_t vertices,
                                  size_t triangles, double tolerance)
{
    size_t v = 0, t = 0;
    double got = eval_volume(text, &v, &t, NULL);
    CHECK_MSG(fabs(got - volume) <= tolerance * volume, "%s: volume %.17g, OpenSCAD's %.17g", text,
              got, volume);
    CHECK_MSG(v == vertices && t == triangles, "%s: %zu vertices, %zu triangles; OpenSCAD "
              "%zu, %zu", text, v, t, vertices, triangles);
}

static void check_openscad(const char *text, double volume, size_t vertices, size_t triangles)
{
    check_openscad_within(text, volume, vertices, triangles, 1e-5);
}

static void expect_error(const char *text, mcsg_status status, const char *needle)
{
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_error err;
    mcsg_status st = mcsg_scad_read_memory(text, strlen(text), "t.scad", NULL, NULL, &tree,
                                           &err);
    if (st == MCSG_OK) {
        mcsg_tree_free(tree);
        st = test_eval_scad(text, NULL, &out, NULL, &err);
        if (st == MCSG_OK)
            mcsg_mesh_free(&out, NULL);
    }
    CHECK_MSG(st == status, "%s: status %s, expected %s", text, mcsg_status_string(st),
              mcsg_status_string(status));
    if (st != MCSG_OK)
        CHECK_CONTAINS(err.message, needle);
}

TEST(prisms_of_squares_are_exact)
{
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(height = 10) square([20, 10], center = true);",
                                NULL, NULL, NULL), 2000);
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(3) square(2);", NULL, NULL, NULL), 12);
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(height = 2, center = true) translate([5, 5]) "
                                "square(1);", NULL, NULL, NULL), 2);
    /* 2D CSG before extruding: a 4 x 4 square minus two 1 x 1 corners, one overlapping. */
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) difference() { square(4); square(1); "
                                "translate([3, 3]) square(2); }", NULL, NULL, NULL), 14);
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) intersection() { square(4); "
                                "translate([1, 2]) square(4); }", NULL, NULL, NULL), 6);
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) union() { square(2); translate([1, 0]) "
                                "square(2); }", NULL, NULL, NULL), 6);
}

TEST(polygons_with_paths)
{
    /* Even-odd, as OpenSCAD fills polygon(): the hole's orientation does not matter. */
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) polygon([[0,0],[10,0],[10,10],[0,10],"
                                "[3,3],[7,3],[7,7],[3,7]], [[0,1,2,3],[4,5,6,7]]);",
                                NULL, NULL, NULL), 84);
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) polygon([[0,0],[10,0],[10,10],[0,10],"
                                "[3,3],[7,3],[7,7],[3,7]], [[0,1,2,3],[4,7,6,5]]);",
                                NULL, NULL, NULL), 84);
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(2) polygon(points = [[0,0],[4,0],[0,4]]);",
                                NULL, NULL, NULL), 16);
}

TEST(shapes_follow_2d_transforms)
{
    /* 2D objects take the x, y part of a transform: a half turn about x mirrors them, a
     * quarter turn flattens them away (with OpenSCAD's warning). */
    log_capture log = {""};
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) rotate([180, 0, 0]) square(2);", NULL, NULL,
                                NULL), 4);
    CHECK_EQ_DOUBLE(eval_volume("cube(1); linear_extrude(1) rotate([90, 0, 0]) square(2);",
                                NULL, NULL, &log), 1);
    CHECK_CONTAINS(log.text, "test.scad:1:47: square() is scaled to zero area: removing it");
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) scale([3, 1]) mirror([1, 0]) square(2);",
                                NULL, NULL, NULL), 12);
    check_openscad("linear_extrude(1) rotate(30) square([4, 2]);", 7.9999944050000016, 8, 12);
}

TEST(openscad_linear_extrude)
{
    check_openscad("linear_extrude(height=10, twist=90, slices=5) square([20,10], center=true);",
                   2224.8817226823326, 24, 44);
    check_openscad("linear_extrude(height=20, twist=-180, scale=0.3) translate([2,0]) "
                   "circle(r=5, $fn=12);", 703.10670359084543, 168, 332);
    check_openscad("linear_extrude(height=5, scale=[2, 0.5], $fn=7) difference() { "
                   "square(10, center=true); circle(3, $fn=16); }", 393.0601803502737, 160, 320);
}

TEST(scale_zero_makes_a_point)
{
    size_t v, t;
    /* The apex is shared by the outer cone and the hole's: the result touches itself
     * there, so the vertex is split (one more than OpenSCAD's 9). */
    double got = eval_volume("linear_extrude(height=4, scale=0) polygon(points=[[0,0],[10,0],"
                             "[10,10],[0,10],[3,3],[7,3],[7,7],[3,7]], paths=[[0,1,2,3],"
                             "[4,7,6,5]]);", &v, &t, NULL);
    CHECK_EQ_DOUBLE(got, 112);
    CHECK_EQ_SIZE(t, 16);
}

/* A top scaled to zero along one axis is a segment, which a notch on one side only
 * splits at its corners: the walls must meet there (OpenSCAD 2021.01's own result is
 * open, 4 boundary edges). The volume is the region's 3 times the height 3 times the
 * mean scale 1/2. */
TEST(scale_zero_makes_a_segment)
{
    static const char *const shape = "difference() { square(2, true); "
                                     "translate([-0.5, 0]) square(1, true); }";
    char text[256];
    snprintf(text, sizeof text, "linear_extrude(height=3, slices=20, scale=[0, 1]) %s", shape);
    CHECK(fabs(eval_volume(text, NULL, NULL, NULL) - 4.5) < 1e-12); /* slices' heights round */
    snprintf(text, sizeof text, "linear_extrude(height=3, slices=7, scale=[1, 0]) "
             "rotate(90) %s", shape);
    CHECK(fabs(eval_volume(text, NULL, NULL, NULL) - 4.5) < 1e-12);
    /* Twisted, the walls are ruled surfaces cut into triangles: closed, about 4.5. */
    snprintf(text, sizeof text, "linear_extrude(height=3, twist=90, scale=[0, 1]) %s", shape);
    CHECK(fabs(eval_volume(text, NULL, NULL, NULL) - 4.5) < 0.1);
}

TEST(openscad_rotate_extrude)
{
    check_openscad("rotate_extrude(angle=-120, $fn=30) polygon([[0,0],[6,-3],[8,4],[0,6]]);",
                   365.92456934849832, 24, 44);
    check_openscad("rotate_extrude($fa=5, $fs=0.5) mirror([1,0]) translate([4,0]) circle(r=2);",
                   312.36380234562017, 1872, 3744);
    check_openscad("rotate_extrude($fn=40) translate([10,0]) difference() { circle(r=5, $fn=30);"
                   " circle(r=2, $fn=20); }", 4105.2149576333622, 2000, 4000);
}

TEST(openscad_hull_offset_projection_resize)
{
    check_openscad("hull() { cube(5); translate([10,0,0]) sphere(2, $fn=12); }",
                   280.74002562850575, 46, 88);
    check_openscad("linear_extrude(2) hull() { circle(3, $fn=10); translate([8,0]) square(2); }",
                   106.95074030600001, 18, 32);
    check_openscad("linear_extrude(1) offset(r=2, $fn=16) square(10);", 192.24601298863999,
                   40, 76);
    check_openscad("linear_extrude(1) offset(r=-1, $fn=20) difference() { square(10); "
                   "translate([3,3]) square(4); }", 28.90998848000034, 56, 112);
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) offset(delta=1) difference() { square(10); "
                                "translate([3,3]) square(4); }", NULL, NULL, NULL), 140);
    CHECK(fabs(eval_volume("linear_extrude(1) offset(delta=1.5, chamfer=true) "
                           "polygon([[0,0],[10,0],[5,8]]);", NULL, NULL, NULL) -
               91.097885539999922) <= 1e-5 * 91.1);
    check_openscad("linear_extrude(1) projection() rotate([30,20,0]) cube(5, center=true);",
                   40.641936088000044, 12, 20);
    check_openscad("linear_extrude(1) projection(cut=true) rotate([30,20,0]) "
                   "cube(5, center=true);", 30.720166170229202, 16, 28);
    check_openscad("resize([10,0,0], auto=true) sphere(2, $fn=16);", 520.3372601706792, 128,
                   252);
}

TEST(openscad_minkowski)
{
    /* A sphere's mesh is convex but for rounding: it is summed as its hull, as OpenSCAD
     * does; the cube with a corner cut away is not convex and is summed face by face. */
    CHECK(fabs(eval_volume("minkowski() { cube([10,10,2]); cylinder(r=1, h=1, $fn=12); }",
                           NULL, NULL, NULL) - 429) <= 1e-12 * 429);
    /* OpenSCAD sums CGAL's convex parts of the L-shaped block and writes floats: 1.1e-5
     * apart, within the 1e-4 that the examples are held to. */
    check_openscad_within("minkowski() { difference() { cube(10); translate([2,2,2]) "
                          "cube(20); } sphere(1, $fn=8); }", 1121.9608611186877, 71, 138, 1e-4);
    check_openscad("linear_extrude(1) minkowski() { difference() { square(10); "
                   "translate([2,2]) square(20); } circle(1, $fn=8); }", 78.535500000000255,
                   32, 60);
    expect_error("minkowski() { difference() { cube(10); translate([2,2,2]) cube(20); } "
                 "difference() { cube(10); translate([2,2,2]) cube(20); } }",
                 MCSG_ERR_UNSUPPORTED, "minkowski(): neither operand is convex or star-shaped");
}

TEST(openscad_text_dxf_surface)
{
    /* Liberation Sans (Debian fonts-liberation2), as OpenSCAD 2021.01 draws it; "Åç" has
     * glyphs made of crossing pieces, filled by the non-zero rule. */
    check_openscad("linear_extrude(1) text(\"OpenSCAD\");", 219.53413366841087, 1090, 2168);
    check_openscad("linear_extrude(1) text(\"\u00c5\u00e7\");", 53.357887386343116, 360, 720);
    {
        char text[512];
        snprintf(text, sizeof text, "linear_extrude(2) import(\"%s\");",
                 test_data("dxf/example013.dxf"));
        check_openscad(text, 4000, 40, 76);
        /* The deprecated `file` reads the drawing in place of the children (warning),
         * with rotate_extrude's origin and scale. */
        snprintf(text, sizeof text, "linear_extrude(height = 2, file = \"%s\");",
                 test_data("dxf/example013.dxf"));
        check_openscad(text, 4000, 40, 76);
        {
            log_capture log = {{0}};
            char child[512];
            snprintf(text, sizeof text, "rotate_extrude(file = \"%s\", origin = [-30, 0], "
                     "scale = 0.5, $fn = 16);", test_data("dxf/example013.dxf"));
            snprintf(child, sizeof child, "rotate_extrude($fn = 16) scale(0.5) "
                     "translate([30, 0]) import(\"%s\", $fn = 16);",
                     test_data("dxf/example013.dxf"));
            CHECK_EQ_DOUBLE(eval_volume(text, NULL, NULL, &log), eval_volume(child, NULL, NULL,
                                                                             NULL));
            CHECK_CONTAINS(log.text, "rotate_extrude(): `file` is deprecated");
        }
        /* OpenSCAD's STL holds floats: its volume is 21785.62, the exact mesh's 21785.556. */
        snprintf(text, sizeof text, "surface(\"%s\", center=true);",
                 test_data("surface/example010.dat"));
        CHECK(fabs(eval_volume(text, NULL, NULL, NULL) - 21785.556322571869) <= 1e-9 * 21785.6);
    }
}

TEST(errors_and_warnings)
{
    log_capture log = {""};
    expect_error("square(1);", MCSG_ERR_UNSUPPORTED, "the top level is a 2D object");
    expect_error("rotate_extrude() translate([-1, 0]) square(2);", MCSG_ERR_PARSE,
                 "t.scad:1:1: rotate_extrude(): all points must have the same X coordinate "
                 "sign (range is -1.00 -> 1.00)");
    expect_error("linear_extrude(1) polygon([[0,0],[2,2],[2,0],[0,2]]);", MCSG_ERR_UNSUPPORTED,
                 "t.scad:1:19: polygon(): the outline crosses itself");
    expect_error("linear_extrude(1) polygon([[0,0],[1]]);", MCSG_ERR_PARSE,
                 "polygon(): points[1] is not a vector of 2 finite numbers");
    expect_error("linear_extrude(height = \"a\") square(1);", MCSG_ERR_PARSE,
                 "t.scad:1:16: linear_extrude(): `height` must be a number, not a string");
    expect_error("linear_extrude(file = \"a.dxf\");", MCSG_ERR_IO,
                 "t.scad:1:1: linear_extrude(\"a.dxf\"): a.dxf: cannot open");
    expect_error("linear_extrude(1) square(\"a\");", MCSG_ERR_PARSE,
                 "square(): `size` must be a number or a vector of 2 numbers, not a string");
    /* Mixing dimensions: the 2D square is left out of the union, with a warning. */
    CHECK_EQ_DOUBLE(eval_volume("union() { cube(2); square(5); }", NULL, NULL, &log), 8);
    CHECK_CONTAINS(log.text, "mixing 2D and 3D objects is not supported: the 2D ones are empty");
    /* ... where they stand, as OpenSCAD has it: an intersection with one is empty. */
    log.text[0] = 0;
    CHECK_EQ_DOUBLE(eval_volume("cube(1); intersection() { cube(5); square(2); }", NULL, NULL,
                                &log), 1);
    CHECK_CONTAINS(log.text, "the 2D ones are empty, and so is the intersection");
    CHECK_EQ_DOUBLE(eval_volume("difference() { cube(5); square(2); }", NULL, NULL, NULL), 125);
    log.text[0] = 0;
    CHECK_EQ_DOUBLE(eval_volume("linear_extrude(1) polygon([[0,0],[4,0],[0,4]], [[0,1,2,7]]);",
                                NULL, NULL, &log), 8);
    CHECK_CONTAINS(log.text, "point index 7 is out of bounds (from paths[0][3])");
    log.text[0] = 0;
    CHECK_EQ_DOUBLE(eval_volume("cube(1); linear_extrude(1) circle(0);", NULL, NULL, &log), 1);
    CHECK_CONTAINS(log.text, "circle() is empty");
}

/* Read and evaluate CSG text: a mesh exactly when both succeed. */
static mcsg_status read_and_eval(const void *text, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_mesh out;
    mcsg_status st = test_eval_scad(text, opts, &out, NULL, err);
    if (st == MCSG_OK)
        mcsg_mesh_free(&out, opts);
    return st;
}

/* Fail allocation 1, 2, ... until the whole read and evaluation succeed: a short text
 * through the region, the prisms, a nested evaluation, the offset's pieces, a sweep and
 * a hull of sums must fail cleanly (MCSG_ERR_NOMEM, nothing leaked: the sanitizer build
 * checks). Each run repeats all before its failing allocation, hence a short text. A
 * failure may be absorbed: the engine's per-thread table of exact points is optional
 * (src/exact/exact_cache.c), and nested evaluations are the first to ask for it. */
TEST(every_allocation_failure_is_clean)
{
    /* Two texts rather than one: each run repeats everything before its failure, so
     * the cost grows with the square of a text's allocations. */
    CHECK(test_allocation_failures("2D read and evaluation", read_and_eval,
                                   "linear_extrude(1, twist = 30) offset(r = 1, $fn = 4) "
                                   "difference() { square(4); circle(1, $fn = 4); }\n",
                                   true) > 10);
    CHECK(test_allocation_failures("minkowski", read_and_eval,
                                   "minkowski() { cube(1); cube(1); }\n", true) > 10);
}

/* The shadow's runs, groups and union fail as cleanly. */
TEST(projection_allocation_failures_are_clean)
{
    CHECK(test_allocation_failures("projection", read_and_eval,
                                   "linear_extrude(1) projection() "
                                   "rotate([0, 0, 30]) cube(1);\n", true) > 10);
}

int main(void)
{
    RUN(prisms_of_squares_are_exact);
    RUN(polygons_with_paths);
    RUN(shapes_follow_2d_transforms);
    RUN(openscad_linear_extrude);
    RUN(scale_zero_makes_a_point);
    RUN(scale_zero_makes_a_segment);
    RUN(openscad_rotate_extrude);
    RUN(openscad_hull_offset_projection_resize);
    RUN(openscad_minkowski);
    RUN(openscad_text_dxf_surface);
    RUN(errors_and_warnings);
    RUN(every_allocation_failure_is_clean);
    RUN(projection_allocation_failures_are_clean);
    return test_summary();
}
