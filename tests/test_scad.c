/*
 * The CSG language: every supported statement and argument form, OpenSCAD's scoping of
 * $fn/$fa/$fs, transform composition and orientation, imports relative to the file,
 * modifiers, empty operands, exported .csg files, deep nesting (10,000 and 100,000
 * levels), every class of error with its line and column, warnings through the log, and
 * allocation failures at every step.
 */
#include "testlib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SQRT3_4 0.86602540378443859659

typedef struct log_capture {
    char text[16384];
    int warnings, infos;
} log_capture;

static void capture(void *user, mcsg_log_level level, const char *message)
{
    log_capture *log = user;
    size_t len = strlen(log->text);
    log->warnings += level == MCSG_LOG_WARNING;
    log->infos += level == MCSG_LOG_INFO;
    snprintf(log->text + len, sizeof log->text - len, "%s\n", message);
}

static mcsg_options logging(log_capture *log)
{
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    memset(log, 0, sizeof *log);
    opts.log = capture;
    opts.log_user = log;
    return opts;
}

static const char *data_dir(void)
{
    static char dir[4096];
    snprintf(dir, sizeof dir, "%s", test_data("scad"));
    return dir;
}

/* Parse text named "t.scad" with imports from tests/data/scad; NULL on failure. */
static mcsg_tree *parse_logged(const char *text, log_capture *log)
{
    mcsg_options opts = logging(log);
    mcsg_tree *tree = NULL;
    mcsg_error err;
    mcsg_status st = mcsg_scad_read_memory(text, strlen(text), "t.scad", data_dir(), &opts,
                                           &tree, &err);
    CHECK_MSG(st == MCSG_OK, "parsing \"%s\" failed: %s", text, err.message);
    return st == MCSG_OK ? tree : NULL;
}

static mcsg_tree *parse(const char *text)
{
    log_capture log;
    return parse_logged(text, &log);
}

/* The text must fail with `status` and a message containing both needles. */
static void expect_error(const char *text, mcsg_status status, const char *where,
                         const char *what)
{
    mcsg_tree *tree = (mcsg_tree *)1;
    mcsg_error err;
    mcsg_status st = mcsg_scad_read_memory(text, strlen(text), "t.scad", data_dir(), NULL,
                                           &tree, &err);
    CHECK_MSG(st == status, "\"%s\": status %s, want %s (%s)", text, mcsg_status_string(st),
              mcsg_status_string(status), st == MCSG_OK ? "" : err.message);
    CHECK(tree == NULL);
    if (st != MCSG_OK && err.status == st) {
        CHECK_CONTAINS(err.message, where);
        CHECK_CONTAINS(err.message, what);
    }
    if (st == MCSG_OK)
        mcsg_tree_free(tree);
}

static mcsg_node_id root(const mcsg_tree *tree) { return mcsg_tree_root(tree); }

/* The only leaf of a tree (the root must be that leaf). */
static const mcsg_mesh *only_leaf(const mcsg_tree *tree)
{
    CHECK(tree && mcsg_tree_leaf_count(tree) == 1);
    CHECK(tree && mcsg_tree_node_kind(tree, root(tree)) == MCSG_NODE_LEAF);
    return tree ? mcsg_tree_leaf_mesh(tree, root(tree)) : NULL;
}

/* The one leaf of a tree, wherever it is. */
static const mcsg_mesh *any_leaf(const mcsg_tree *tree)
{
    CHECK(tree && mcsg_tree_leaf_count(tree) == 1);
    for (mcsg_node_id id = 0; tree && id < mcsg_tree_node_count(tree); id++) {
        if (mcsg_tree_node_kind(tree, id) == MCSG_NODE_LEAF)
            return mcsg_tree_leaf_mesh(tree, id);
    }
    return NULL;
}

/* Axis-aligned bounds: lo[3], hi[3]. */
static void bounds(const mcsg_mesh *m, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (size_t i = 0; m && i < m->vertex_count; i++) {
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->vertices[3 * i + k]);
            hi[k] = fmax(hi[k], m->vertices[3 * i + k]);
        }
    }
}

static void check_bounds(const mcsg_tree *tree, double x0, double y0, double z0, double x1,
                         double y1, double z1)
{
    double lo[3], hi[3];
    bounds(only_leaf(tree), lo, hi);
    CHECK_MSG(lo[0] == x0 && lo[1] == y0 && lo[2] == z0 && hi[0] == x1 && hi[1] == y1 &&
                  hi[2] == z1,
              "bounds [%.17g %.17g %.17g] - [%.17g %.17g %.17g], want [%g %g %g] - [%g %g %g]",
              lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], x0, y0, z0, x1, y1, z1);
}

static const char *root_label(const mcsg_tree *tree)
{
    return tree ? mcsg_tree_node_label(tree, root(tree)) : "";
}

/* The leaf of `text` must equal the mesh built directly. */
static void check_same_as(const char *text, const mcsg_mesh *want)
{
    mcsg_tree *tree = parse(text);
    CHECK_MSG(test_same_mesh(only_leaf(tree), want), "\"%s\" differs from the direct mesh",
              text);
    mcsg_tree_free(tree);
}

TEST(cube_forms)
{
    const double unit[3] = {1, 1, 1}, five[3] = {5, 5, 5}, box[3] = {1, 2, 3};
    mcsg_mesh m;
    mcsg_error err;
    CHECK_OK(mcsg_make_cube(unit, 0, NULL, &m, &err), &err);
    check_same_as("cube();", &m);
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(mcsg_make_cube(five, 0, NULL, &m, &err), &err);
    check_same_as("cube(5);", &m);
    check_same_as("cube(size=5, center=false);", &m);
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(mcsg_make_cube(box, 1, NULL, &m, &err), &err);
    check_same_as("cube([1, 2, 3], true);", &m);
    check_same_as("cube(center=true, size=[1,2,3]);", &m);
    check_same_as("cube(center=true, [1,2,3]);", &m); /* positional fills `size` */
    mcsg_mesh_free(&m, NULL);
}

TEST(sphere_forms)
{
    mcsg_resolution res = {0, 12, 2};
    mcsg_mesh m;
    mcsg_error err;
    mcsg_tree *tree;
    CHECK_OK(mcsg_make_sphere(5, res, NULL, &m, &err), &err);
    check_same_as("sphere(5);", &m);
    check_same_as("sphere(r=5);", &m);
    check_same_as("sphere(d=10);", &m);
    check_same_as("sphere(r=1, d=10);", &m); /* the diameter wins, as in OpenSCAD */
    mcsg_mesh_free(&m, NULL);
    res.fn = 12;
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &m, &err), &err);
    check_same_as("sphere($fn=12);", &m);
    check_same_as("sphere(1, $fn=12);", &m);
    mcsg_mesh_free(&m, NULL);
    tree = parse("sphere(r=5, $fn=32);");
    CHECK(strcmp(root_label(tree), "sphere(r=5, $fn=32) at t.scad:1:1") == 0);
    CHECK_EQ_SIZE(only_leaf(tree)->vertex_count, 32 * 16);
    mcsg_tree_free(tree);
    tree = parse("\n  sphere(2);");
    CHECK(strcmp(root_label(tree), "sphere(r=2, $fa=12, $fs=2) at t.scad:2:3") == 0);
    mcsg_tree_free(tree);
}

TEST(cylinder_forms)
{
    struct {
        const char *text;
        double h, r1, r2;
        int center;
    } cases[] = {
        {"cylinder();", 1, 1, 1, 0},
        {"cylinder(h=10, r=2);", 10, 2, 2, 0},
        {"cylinder(10, 2, 1);", 10, 2, 1, 0},
        {"cylinder(10, 2);", 10, 2, 1, 0}, /* r2 keeps its default 1, as in OpenSCAD */
        {"cylinder(h=5, d=4, center=true);", 5, 2, 2, 1},
        {"cylinder(h=5, d1=4, d2=2);", 5, 2, 1, 0},
        {"cylinder(h=5, r=3, r1=1);", 5, 1, 3, 0},
        {"cylinder(h=5, r1=0, r2=2);", 5, 0, 2, 0},
        {"cylinder(h=5, r1=2, r2=0);", 5, 2, 0, 0},
        {"cylinder(h=1, r=1, d=4);", 1, 2, 2, 0},
        {"cylinder(h=2, r1=1, d1=6, r2=5);", 2, 3, 5, 0},
        {"cylinder(3, 1, 1, true);", 3, 1, 1, 1},
    };
    mcsg_resolution res = {0, 12, 2};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        mcsg_mesh m;
        mcsg_error err;
        CHECK_OK(mcsg_make_cylinder(cases[i].h, cases[i].r1, cases[i].r2, cases[i].center, res,
                                    NULL, &m, &err), &err);
        check_same_as(cases[i].text, &m);
        mcsg_mesh_free(&m, NULL);
    }
}

TEST(resolution_scoping)
{
    struct {
        const char *text;
        size_t fragments; /* of the only sphere, r = 10 unless said otherwise */
    } cases[] = {
        {"sphere(10);", 30},
        {"$fn = 12; sphere(10);", 12},
        {"sphere(10); $fn = 12;", 12}, /* assignments apply to the whole scope */
        {"$fn = 6; sphere(10); $fn = 8;", 8}, /* the last value wins */
        {"sphere(10, $fn=7);", 7},
        {"$fn = 5; sphere(r=10, $fn=$fn*2);", 10}, /* evaluated in the caller's scope */
        {"translate([0,0,0], $fn=9) sphere(10);", 9},
        {"translate([0,0,0]) { $fn = 5; sphere(10); }", 5},
        {"$fn = 4; union() { $fn = 7; } sphere(10);", 4},
        {"union() { $fn = 7; { sphere(10); } }", 7}, /* bare braces share the scope */
        {"$fa = 6; $fs = 0.5; sphere(10);", 60},
        {"$fa = 6; $fs = 0.5; sphere(1);", 13},
        {"$fn = 4 * 2 + 1; sphere(10);", 9},
        {"$fn = 3.7; sphere(10);", 3},
        {"$fn = 1; sphere(10);", 3},
        {"$fn = -1; sphere(10);", 30},
        {"$fa = 0; $fs = 1000; sphere(10);", 5}, /* $fa clamped to 0.01, $fs wins */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        mcsg_tree *tree = parse(cases[i].text);
        size_t n = cases[i].fragments, rings = (n + 1) / 2;
        const mcsg_mesh *m = any_leaf(tree);
        CHECK_MSG(m && m->vertex_count == n * rings, "\"%s\": %zu vertices, want %zu",
                  cases[i].text, m ? m->vertex_count : 0, n * rings);
        mcsg_tree_free(tree);
    }
}

TEST(resolution_warnings)
{
    log_capture log;
    mcsg_tree *tree = parse_logged("$fs = 0; $fn = 6; sphere(1); $fn = 7;", &log);
    CHECK_CONTAINS(log.text, "$fs too small");
    CHECK_CONTAINS(log.text, "t.scad:1:30: $fn was assigned on line 1");
    CHECK_EQ_SIZE(only_leaf(tree)->vertex_count, 7 * 4);
    mcsg_tree_free(tree);
}

TEST(transforms)
{
    mcsg_tree *tree;
    tree = parse("translate([1, 2, 3]) cube(1);");
    check_bounds(tree, 1, 2, 3, 2, 3, 4);
    mcsg_tree_free(tree);
    tree = parse("translate([1, 2]) cube(1);"); /* z defaults to 0 */
    check_bounds(tree, 1, 2, 0, 2, 3, 1);
    mcsg_tree_free(tree);
    tree = parse("rotate(90) cube([2, 1, 1]);"); /* about z, exact at 90 degrees */
    check_bounds(tree, -1, 0, 0, 0, 2, 1);
    mcsg_tree_free(tree);
    tree = parse("rotate([90, 0, 0]) cube([1, 2, 3]);");
    check_bounds(tree, 0, -3, 0, 1, 0, 2);
    mcsg_tree_free(tree);
    tree = parse("rotate(a=90, v=[1, 0, 0]) cube([1, 2, 3]);");
    check_bounds(tree, 0, -3, 0, 1, 0, 2);
    mcsg_tree_free(tree);
    tree = parse("rotate([0, 0, 180]) cube(1);");
    check_bounds(tree, -1, -1, 0, 0, 0, 1);
    mcsg_tree_free(tree);
    tree = parse("scale([2, 3, 4]) cube(1);");
    check_bounds(tree, 0, 0, 0, 2, 3, 4);
    mcsg_tree_free(tree);
    tree = parse("scale(2) cube(1);");
    check_bounds(tree, 0, 0, 0, 2, 2, 2);
    mcsg_tree_free(tree);
    tree = parse("scale([2, 3]) cube(1);"); /* z defaults to 1 */
    check_bounds(tree, 0, 0, 0, 2, 3, 1);
    mcsg_tree_free(tree);
    tree = parse("multmatrix([[1, 0, 0, 5], [0, 1, 0, 6], [0, 0, 1, 7]]) cube(1);");
    check_bounds(tree, 5, 6, 7, 6, 7, 8);
    mcsg_tree_free(tree);
    tree = parse("multmatrix([[2, 0, 0, 2], [0, 2, 0, 0], [0, 0, 2, 0], [0, 0, 0, 2]]) cube(1);");
    check_bounds(tree, 1, 0, 0, 2, 1, 1); /* divided by m[3][3] */
    mcsg_tree_free(tree);
    tree = parse("multmatrix([[3]]) cube(1);"); /* padded with the identity */
    check_bounds(tree, 0, 0, 0, 3, 1, 1);
    mcsg_tree_free(tree);
}

TEST(transform_order_follows_openscad)
{
    /* The outer transform applies last: translate(rotate(x)) vs rotate(translate(x)). */
    mcsg_tree *tree = parse("translate([10, 0, 0]) rotate(90) cube(1);");
    check_bounds(tree, 9, 0, 0, 10, 1, 1);
    mcsg_tree_free(tree);
    tree = parse("rotate(90) translate([10, 0, 0]) cube(1);");
    check_bounds(tree, -1, 10, 0, 0, 11, 1);
    mcsg_tree_free(tree);
    tree = parse("translate([1, 0, 0]) scale(2) { cube(1); }");
    check_bounds(tree, 1, 0, 0, 3, 2, 2);
    mcsg_tree_free(tree);
    /* Euler angles: x first, then y, then z (Rz*Ry*Rx). */
    tree = parse("rotate([90, 90, 0]) cube([1, 2, 3]);");
    check_bounds(tree, 0, -3, -1, 2, 0, 0);
    mcsg_tree_free(tree);
}

TEST(mirrors_keep_meshes_outward)
{
    static const char *const texts[] = {
        "mirror([1, 0, 0]) cube(1);", "mirror([1, 1, 0]) cube(1);",
        "mirror([0, 0, 1]) sphere(2);", "mirror([1, 0, 0]) mirror([0, 1, 0]) cylinder(2, 1, 0);",
        "scale([-1, 1, 1]) cube(1);", "multmatrix([[1, 0, 0], [0, -1, 0], [0, 0, 1]]) cube(1);",
        "mirror() cube(1);",
    };
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        log_capture log;
        mcsg_tree *tree = parse_logged(texts[i], &log);
        CHECK_MSG(test_signed_volume(only_leaf(tree)) > 0, "\"%s\" is inverted", texts[i]);
        mcsg_tree_free(tree);
    }
    {
        mcsg_tree *tree = parse("mirror([1, 0, 0]) cube(1);");
        check_bounds(tree, -1, 0, 0, 0, 1, 1);
        mcsg_tree_free(tree);
    }
}

TEST(flattening_transforms_give_empty_sets)
{
    log_capture log;
    mcsg_tree *tree = parse_logged("union() { scale([1, 0, 1]) { cube(1); sphere(1); } cube(2); }",
                                   &log);
    mcsg_node_id u = root(tree), flat = mcsg_tree_child(tree, u, 0);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, u), 2);
    CHECK(mcsg_tree_node_kind(tree, flat) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, flat), 2);
    CHECK(mcsg_tree_node_kind(tree, mcsg_tree_child(tree, flat, 0)) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, mcsg_tree_child(tree, flat, 0)), 0);
    CHECK_CONTAINS(mcsg_tree_node_label(tree, mcsg_tree_child(tree, flat, 0)),
                   "cube(size=[1, 1, 1], center=false) at t.scad:1:30 (empty: flattened");
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 1);
    CHECK_CONTAINS(log.text, "t.scad:1:11: scale() flattens its children");
    CHECK_EQ_SIZE(log.warnings, 1);
    mcsg_tree_free(tree);
    tree = parse("multmatrix([[1, 0, 0], [0, 1, 0], [0, 0, 0]]) cube(1);");
    CHECK(mcsg_tree_node_kind(tree, root(tree)) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 0);
    mcsg_tree_free(tree);
}

TEST(operations_and_groups)
{
    mcsg_tree *tree = parse("difference() { cube(10); sphere(1); cylinder(); }\n"
                            "intersection() { cube(1); sphere(1); }\n"
                            "union() { cube(1); }\n"
                            "group() { cube(1); }\n"
                            "render(convexity = 4) { cube(1); cube(2); }\n"
                            "color(\"red\", 0.5) cube(1);\n"
                            "color([1, 0, 0]) translate([1, 0, 0]) { }\n");
    mcsg_node_id top = root(tree), c;
    CHECK(mcsg_tree_node_kind(tree, top) == MCSG_NODE_UNION);
    CHECK(strcmp(root_label(tree), "top level of t.scad") == 0);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, top), 7);
    c = mcsg_tree_child(tree, top, 0);
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_DIFFERENCE);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, c), 3);
    CHECK(strcmp(mcsg_tree_node_label(tree, c), "difference() at t.scad:1:1") == 0);
    c = mcsg_tree_child(tree, top, 1);
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_INTERSECTION);
    CHECK(strcmp(mcsg_tree_node_label(tree, c), "intersection() at t.scad:2:1") == 0);
    c = mcsg_tree_child(tree, top, 2); /* union() keeps its node, even for one child */
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, c), 1);
    c = mcsg_tree_child(tree, top, 3); /* group() of one child is that child */
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_LEAF);
    CHECK_CONTAINS(mcsg_tree_node_label(tree, c), "at t.scad:4:11");
    c = mcsg_tree_child(tree, top, 4); /* render() of two: an implicit union */
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_UNION);
    CHECK(strcmp(mcsg_tree_node_label(tree, c), "render() at t.scad:5:1") == 0);
    c = mcsg_tree_child(tree, top, 5);
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_LEAF);
    c = mcsg_tree_child(tree, top, 6); /* no children: the empty set */
    CHECK(mcsg_tree_node_kind(tree, c) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, c), 0);
    CHECK(strcmp(mcsg_tree_node_label(tree, c), "translate() at t.scad:7:18") == 0);
    mcsg_tree_free(tree);
}

TEST(empty_operands)
{
    log_capture log;
    mcsg_tree *tree = parse_logged("difference() { cube(0); sphere(1); }", &log);
    mcsg_node_id d = root(tree), first = mcsg_tree_child(tree, d, 0);
    CHECK(mcsg_tree_node_kind(tree, d) == MCSG_NODE_DIFFERENCE);
    CHECK(mcsg_tree_node_kind(tree, first) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, first), 0);
    CHECK_CONTAINS(mcsg_tree_node_label(tree, first), "(empty)");
    CHECK_CONTAINS(log.text, "t.scad:1:16: cube() is empty");
    mcsg_tree_free(tree);
    tree = parse("intersection() { }");
    CHECK(mcsg_tree_node_kind(tree, root(tree)) == MCSG_NODE_INTERSECTION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, root(tree)), 0);
    mcsg_tree_free(tree);
    tree = parse("");
    CHECK_EQ_SIZE(mcsg_tree_node_count(tree), 1);
    CHECK(mcsg_tree_node_kind(tree, root(tree)) == MCSG_NODE_UNION);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, root(tree)), 0);
    mcsg_tree_free(tree);
    tree = parse("sphere(0); cylinder(h=0); cylinder(r1=0, r2=0); polyhedron([[0,0,0]], []);");
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 0);
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, root(tree)), 4);
    mcsg_tree_free(tree);
}

TEST(modifiers)
{
    log_capture log;
    mcsg_tree *tree = parse_logged("*cube(1); %sphere(1); #cylinder();", &log);
    CHECK_CONTAINS(only_leaf(tree) ? root_label(tree) : "", "cylinder(");
    CHECK_CONTAINS(log.text, "t.scad:1:1: disabled (*) cube() is left out");
    CHECK_CONTAINS(log.text, "t.scad:1:11: background (%) sphere() is left out");
    mcsg_tree_free(tree);
    /* A background first child is not the difference's first operand (OpenSCAD). */
    tree = parse("difference() { %cube(5); sphere(1); *cube(\"not evaluated\"); cube(1); }");
    CHECK_EQ_SIZE(mcsg_tree_child_count(tree, root(tree)), 2);
    CHECK_CONTAINS(mcsg_tree_node_label(tree, mcsg_tree_child(tree, root(tree), 0)), "sphere");
    mcsg_tree_free(tree);
    tree = parse("#%*# cube(1); cube(2);");
    CHECK_CONTAINS(root_label(tree), "cube(size=[2, 2, 2]");
    mcsg_tree_free(tree);
    expect_error("cube(1);\n  !sphere(1);", MCSG_ERR_UNSUPPORTED, "t.scad:2:3:", "`!`");
    expect_error("*foo();", MCSG_ERR_PARSE, "t.scad:1:2:", "unknown module `foo`");
}

#define TETRA_POINTS "[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]"
#define TETRA_FACES "[[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]"

TEST(polyhedron_forms)
{
    static const char *const texts[] = {
        "polyhedron(points=" TETRA_POINTS ", faces=" TETRA_FACES ");",
        "polyhedron(" TETRA_POINTS ", " TETRA_FACES ", 10);",
        "polyhedron(faces=" TETRA_FACES ", points=" TETRA_POINTS ", convexity=2);",
        "polyhedron(points=" TETRA_POINTS ", triangles=" TETRA_FACES ");",
    };
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        log_capture log;
        mcsg_tree *tree = parse_logged(texts[i], &log);
        const mcsg_mesh *m = only_leaf(tree);
        CHECK(m && m->vertex_count == 4 && m->triangle_count == 4);
        /* OpenSCAD's faces are clockwise from outside: reversed, the tetrahedron is
         * outward. */
        CHECK_EQ_DOUBLE(test_signed_volume(m), 1.0 / 6);
        CHECK(m && m->triangles[0] == 2 && m->triangles[1] == 1 && m->triangles[2] == 0);
        if (i == 3)
            CHECK_CONTAINS(log.text, "`triangles` is deprecated");
        mcsg_tree_free(tree);
    }
}

TEST(polyhedron_polygons_and_2d_points)
{
    /* A unit cube with quad faces (clockwise from outside), two points given in 2D. */
    log_capture log;
    mcsg_tree *tree = parse_logged(
        "polyhedron([[0,0],[1,0,0],[1,1,0],[0,1],[0,0,1],[1,0,1],[1,1,1],[0,1,1]],"
        "[[0,1,2,3],[4,7,6,5],[0,4,5,1],[1,5,6,2],[2,6,7,3],[3,7,4,0],[0,1]]);", &log);
    const mcsg_mesh *m = only_leaf(tree);
    CHECK(m && m->vertex_count == 8 && m->triangle_count == 12);
    CHECK_EQ_DOUBLE(test_signed_volume(m), 1);
    CHECK_CONTAINS(log.text, "ignoring faces[6]");
    CHECK(strcmp(root_label(tree), "polyhedron(8 points, 7 faces) at t.scad:1:1") == 0);
    mcsg_tree_free(tree);
}

TEST(polyhedron_errors)
{
    expect_error("polyhedron(points=" TETRA_POINTS ",\n  faces=[[0, 1, 2], [0, 4, 1]]);",
                 MCSG_ERR_PARSE, "t.scad:2:3:", "faces[1][1] = 4 is not a point index (the "
                 "polyhedron has 4 points)");
    expect_error("polyhedron(" TETRA_POINTS ", [[0, 1, 2.5]]);", MCSG_ERR_PARSE, "t.scad:1:58:",
                 "faces[0][2] = 2.5");
    expect_error("polyhedron(" TETRA_POINTS ", [[0, 1, -1]]);", MCSG_ERR_PARSE, "t.scad:1:",
                 "faces[0][2] = -1");
    expect_error("polyhedron([[0, 0, 0], [1]], []);", MCSG_ERR_PARSE, "t.scad:1:12:",
                 "points[1]");
    expect_error("polyhedron([[0, 0, 0], [1, 0, \"z\"]], []);", MCSG_ERR_PARSE, "t.scad:1:12:",
                 "points[1] is not a vector of 2 or 3 finite numbers");
    expect_error("polyhedron([[0, 0, 1/0]], []);", MCSG_ERR_PARSE, "t.scad:1:12:", "points[0]");
    expect_error("polyhedron(faces=[]);", MCSG_ERR_PARSE, "t.scad:1:1:",
                 "`points` must be a vector of points, not undef");
    expect_error("polyhedron(" TETRA_POINTS ", 3);", MCSG_ERR_PARSE, "t.scad:1:",
                 "`faces` must be a vector of faces, not a number");
    expect_error("polyhedron(" TETRA_POINTS ", [3]);", MCSG_ERR_PARSE, "t.scad:1:",
                 "faces[0] is a number");
}

TEST(imports)
{
    mcsg_tree *tree = parse("import(\"cube.off\");");
    const mcsg_mesh *m = only_leaf(tree);
    CHECK(m && m->vertex_count == 8 && m->triangle_count == 12);
    CHECK(strcmp(root_label(tree), "import(\"cube.off\") at t.scad:1:1") == 0);
    mcsg_tree_free(tree);
    tree = parse("translate([0, 0, 5]) import(file = \"parts/tetra.off\", convexity = 3);");
    check_bounds(tree, 0, 0, 5, 1, 1, 6);
    mcsg_tree_free(tree);
    tree = parse("import(\"cu\\x62e.off\");"); /* escapes in strings */
    CHECK(tree && mcsg_tree_leaf_count(tree) == 1);
    mcsg_tree_free(tree);
    tree = parse("import(filename = \"cube.off\");"); /* OpenSCAD's legacy name */
    CHECK(tree && mcsg_tree_leaf_count(tree) == 1);
    mcsg_tree_free(tree);
}

/* import() files are read ahead, several at once: a file named twice gives two leaves
 * (one a copy), each transformed on its own, and the messages its read logs come once
 * per call, in program order between the walk's own messages. */
TEST(imports_read_ahead)
{
    static const char text[] = "union() {\n"
                               "  import(\"warns.obj\");\n"
                               "  translate() cube(1);\n"
                               "  translate([5, 0, 0]) import(\"warns.obj\");\n"
                               "  import(\"cube.off\");\n"
                               "}\n";
    log_capture log;
    mcsg_options opts = logging(&log);
    mcsg_tree *tree = NULL;
    mcsg_error err;
    const char *first, *walk, *second;
    opts.threads = 2;
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "t.scad", data_dir(), &opts, &tree,
                                   &err),
             &err);
    CHECK(tree && mcsg_tree_leaf_count(tree) == 4);
    if (tree && mcsg_tree_leaf_count(tree) == 4) {
        const mcsg_mesh *a = mcsg_tree_leaf_mesh(tree, mcsg_tree_child(tree, root(tree), 0));
        const mcsg_mesh *b = mcsg_tree_leaf_mesh(tree, mcsg_tree_child(tree, root(tree), 2));
        const mcsg_mesh *c = mcsg_tree_leaf_mesh(tree, mcsg_tree_child(tree, root(tree), 3));
        CHECK(a && b && a->vertex_count == 4 && b->vertex_count == 4);
        for (size_t i = 0; a && b && i < 12; i++)
            CHECK(b->vertices[i] == a->vertices[i] + (i % 3 == 0 ? 5 : 0));
        CHECK(c && c->vertex_count == 8 && c->triangle_count == 12);
    }
    CHECK_EQ_SIZE(log.warnings, 3);
    first = strstr(log.text, "ignoring unknown OBJ keyword 'foo'");
    walk = strstr(log.text, "translate(): no vector given");
    second = first ? strstr(first + 1, "ignoring unknown OBJ keyword 'foo'") : NULL;
    CHECK_MSG(first && walk && second && first < walk && walk < second,
              "messages out of order:\n%s", log.text);
    mcsg_tree_free(tree);
}

TEST(import_relative_to_the_file)
{
    mcsg_tree *tree = NULL;
    mcsg_error err;
    const mcsg_mesh *tetra, *cube;
    CHECK_OK(mcsg_scad_read(test_data("scad/assembly.scad"), NULL, &tree, &err), &err);
    CHECK(tree && mcsg_tree_leaf_count(tree) == 2);
    tetra = mcsg_tree_leaf_mesh(tree, mcsg_tree_child(tree, root(tree), 0));
    cube = mcsg_tree_leaf_mesh(tree, mcsg_tree_child(tree, root(tree), 1));
    CHECK(tetra && tetra->vertex_count == 4 && test_signed_volume(tetra) > 0);
    CHECK(cube && cube->vertex_count == 8 && cube->vertices[3] == 3); /* moved by 2 */
    CHECK_CONTAINS(mcsg_tree_node_label(tree, root(tree)), "assembly.scad:2:1");
    mcsg_tree_free(tree);
}

TEST(import_errors)
{
    expect_error("cube(1);\n  import(\"missing.off\");", MCSG_ERR_IO,
                 "t.scad:2:3: import(\"missing.off\"): ", "missing.off");
    expect_error("import(\"bad.off\");", MCSG_ERR_PARSE, "t.scad:1:1: import(\"bad.off\"): ",
                 "bad.off");
    expect_error("import(3);", MCSG_ERR_PARSE, "t.scad:1:8:", "`file` must be a file name");
    expect_error("import();", MCSG_ERR_PARSE, "t.scad:1:1:", "not undef");
    expect_error("import(\"\");", MCSG_ERR_PARSE, "t.scad:1:8:", "invalid file name");
}

TEST(openscad_exported_csg)
{
    log_capture log;
    mcsg_options opts = logging(&log);
    mcsg_tree *tree = NULL;
    mcsg_error err;
    CHECK_OK(mcsg_scad_read(test_data("scad/exported.csg"), &opts, &tree, &err), &err);
    CHECK(tree && mcsg_tree_leaf_count(tree) == 5);
    CHECK_MSG(log.warnings == 0, "unexpected warnings:\n%s", log.text);
    for (mcsg_node_id id = 0; tree && id < mcsg_tree_node_count(tree); id++) {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(tree, id);
        CHECK_MSG(!m || test_signed_volume(m) > 0, "leaf %s is inverted",
                  mcsg_tree_node_label(tree, id));
    }
    mcsg_tree_free(tree);
}

/* The only leaf is cube(size=[x, y, z]) at the origin for the given size expression. */
static void check_cube_size(const char *size_expr, double x, double y, double z)
{
    char text[512];
    mcsg_tree *tree;
    snprintf(text, sizeof text, "cube(%s);", size_expr);
    tree = parse(text);
    check_bounds(tree, 0, 0, 0, x, y, z);
    mcsg_tree_free(tree);
}

TEST(expressions)
{
    check_cube_size("[1 + 2, 2 * 3, 10 / 4]", 3, 6, 2.5);
    check_cube_size("2 ^ 3", 8, 8, 8);
    check_cube_size("2 ^ 3 ^ 2 / 64", 8, 8, 8); /* ^ is right-associative */
    check_cube_size("7 % 4", 3, 3, 3);
    check_cube_size("-(-2)", 2, 2, 2);
    check_cube_size("- -2 + +1", 3, 3, 3);
    check_cube_size("1 + 2 * 3 - 4 / 2", 5, 5, 5);
    check_cube_size("(1 + 2) * 3", 9, 9, 9);
    check_cube_size("[1, 2, 3] * 2 + [1, 1, 1]", 3, 5, 7);
    check_cube_size("2 * [1, 2, 3] - [1, 1, 1] / 1", 1, 3, 5);
    check_cube_size("[3, 2, 1] / 2", 1.5, 1, 0.5);
    check_cube_size("-[1, 2, 3] * -1", 1, 2, 3);
    check_cube_size("[1, 2, 3] * [1, 1, 1]", 6, 6, 6); /* dot product */
    check_cube_size("[sin(30), cos(60), tan(45)]", 0.5, 0.5, 1);
    check_cube_size("[asin(0.5), acos(0.5), atan(1)]", 30, 60, 45);
    check_cube_size("[atan2(1, 1), sqrt(16), pow(2, 10)]", 45, 4, 1024);
    check_cube_size("[min(3, 1, 2), max([1, 5, 2]), abs(-3)]", 1, 5, 3);
    check_cube_size("[floor(2.7), ceil(2.1), round(2.5)]", 2, 3, 3);
    check_cube_size("[exp(0), ln(1) + 1, log(100)]", 1, 1, 2);
    check_cube_size("[log(2, 8), sign(-4) + 2, norm([3, 4])]", 3, 1, 5);
    check_cube_size("[len([1, 2, 3]), len(\"h\\u00e9\"), max(7)]", 3, 2, 7);
    check_cube_size("PI", 3.14159265358979323846, 3.14159265358979323846,
                    3.14159265358979323846);
    check_cube_size("[1e1, .5, 1.]", 10, 0.5, 1);
    check_cube_size("[0x10, 0.1, 2E-1]", 16, 0.1, 0.2); /* exact decimal parsing */
    check_cube_size("[1, /* comment */ 2, // another\n 3,]", 1, 2, 3);
    check_cube_size("$fn + $fa + $fs", 14, 14, 14); /* defaults 0, 12, 2 */
    check_cube_size("[$t + 1, 1, 1]", 1, 1, 1);
}

TEST(special_variables_hold_any_value)
{
    /* $v's elements must survive the expressions that compute with it. */
    mcsg_tree *tree = parse("$v = [1, 2, 3];\ncube($v * 2 + $v + $v * 0);\n"
                            "translate($v) cube($v);");
    mcsg_node_id top = root(tree);
    double lo[3], hi[3];
    bounds(mcsg_tree_leaf_mesh(tree, mcsg_tree_child(tree, top, 0)), lo, hi);
    CHECK(hi[0] == 3 && hi[1] == 6 && hi[2] == 9);
    bounds(mcsg_tree_leaf_mesh(tree, mcsg_tree_child(tree, top, 1)), lo, hi);
    CHECK(lo[0] == 1 && lo[1] == 2 && lo[2] == 3 && hi[0] == 2 && hi[1] == 4 && hi[2] == 6);
    mcsg_tree_free(tree);
    /* An unknown special variable is undef, with a warning. */
    {
        log_capture log;
        tree = parse_logged("cube($undefined);", &log);
        CHECK_CONTAINS(log.text, "t.scad:1:6: unknown variable $undefined");
        check_bounds(tree, 0, 0, 0, 1, 1, 1);
        mcsg_tree_free(tree);
    }
}

TEST(syntax_errors)
{
    expect_error("cube(1)", MCSG_ERR_PARSE, "t.scad:1:8:",
                 "unexpected end of file: expected a statement or `;` after `cube(...)`");
    expect_error("cube(1;", MCSG_ERR_PARSE, "t.scad:1:7:", "expected `,` or `)` after an "
                 "argument, found `;`");
    expect_error("union() {\n  cube(1);\n", MCSG_ERR_PARSE, "t.scad:3:1:",
                 "expected `}` to close the `{` at line 1, column 9");
    expect_error("cube(1);\n}", MCSG_ERR_PARSE, "t.scad:2:1:", "unmatched `}`");
    expect_error("union() { translate([1,0,0]) }", MCSG_ERR_PARSE, "t.scad:1:30:",
                 "expected a statement or `;`");
    expect_error("cube;", MCSG_ERR_PARSE, "t.scad:1:5:", "expected `(` after the module name");
    expect_error("cube(size=);", MCSG_ERR_PARSE, "t.scad:1:11:", "expected an expression");
    expect_error("cube([1, 2 3]);", MCSG_ERR_PARSE, "t.scad:1:12:", "expected `,` or `]`");
    expect_error("cube((1;", MCSG_ERR_PARSE, "t.scad:1:8:", "expected `)`, found `;`");
    expect_error("5;", MCSG_ERR_PARSE, "t.scad:1:1:", "expected a statement, found number `5`");
    expect_error("cube(3d);", MCSG_ERR_PARSE, "t.scad:1:6:", "invalid number `3d`");
    expect_error("cube(1e);", MCSG_ERR_PARSE, "t.scad:1:6:", "invalid number");
    expect_error("cube(1) @", MCSG_ERR_PARSE, "t.scad:1:9:", "unexpected character `@`");
    expect_error("cube(1);\n/* not closed\n", MCSG_ERR_PARSE, "t.scad:2:1:",
                 "unterminated comment");
    expect_error("import(\"abc.off);\ncube(1);", MCSG_ERR_PARSE, "t.scad:1:8:",
                 "unterminated string");
    expect_error("translate([0,0,0]) $fn = 3;", MCSG_ERR_PARSE, "t.scad:1:20:",
                 "assignment needs braces");
    expect_error("cube(1);\n\tcub(2);", MCSG_ERR_PARSE, "t.scad:2:2:", "unknown module `cub`");
    expect_error("cube(\x01);", MCSG_ERR_PARSE, "t.scad:1:6:", "unexpected byte 0x01");
}

TEST(unsupported_constructs)
{
    expect_error("for (i = [0:2]) cube(i);", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:",
                 "`for` is not supported by meshcsg (supported: union, difference");
    expect_error("\n  module part() { cube(1); }", MCSG_ERR_UNSUPPORTED, "t.scad:2:3:",
                 "`module` is not supported");
    expect_error("function f(x) = x;", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:", "`function`");
    expect_error("if (true) cube(1);", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:", "`if`");
    expect_error("use <lib.scad>", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:", "`use`");
    expect_error("include <lib.scad>", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:", "`include`");
    expect_error("roof() square(1);", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:",
                 "`roof` is not supported");
    expect_error("union() { fill() { square(1); } }", MCSG_ERR_UNSUPPORTED, "t.scad:1:11:",
                 "`fill`");
    expect_error("x = 5;", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:", "assignment to `x`");
    expect_error("cube(size);", MCSG_ERR_UNSUPPORTED, "t.scad:1:6:", "variable `size`");
    expect_error("cube(f(1));", MCSG_ERR_UNSUPPORTED, "t.scad:1:6:", "function `f`");
    expect_error("cube(1 < 2);", MCSG_ERR_UNSUPPORTED, "t.scad:1:8:", "operator `<`");
    expect_error("cube(true ? 1 : 2);", MCSG_ERR_UNSUPPORTED, "t.scad:1:11:", "operator `?`");
    expect_error("cube(!true);", MCSG_ERR_UNSUPPORTED, "t.scad:1:6:", "logical");
    expect_error("cube([1, 2, 3][0]);", MCSG_ERR_UNSUPPORTED, "t.scad:1:15:", "indexing");
    expect_error("cube([0:3]);", MCSG_ERR_UNSUPPORTED, "t.scad:1:8:", "ranges");
    expect_error("cube([for (i = [1, 2]) i]);", MCSG_ERR_UNSUPPORTED, "t.scad:1:7:",
                 "list comprehensions");
    expect_error("cube(let (a = 1) a);", MCSG_ERR_UNSUPPORTED, "t.scad:1:6:", "`let`");
    expect_error("cube(sin(x = 1));", MCSG_ERR_UNSUPPORTED, "t.scad:1:10:", "named arguments");
    expect_error("echo(1);", MCSG_ERR_UNSUPPORTED, "t.scad:1:1:", "`echo`");
}

TEST(bad_argument_types)
{
    expect_error("cube(\"a\");", MCSG_ERR_PARSE, "t.scad:1:6:",
                 "cube(): `size` must be a number or a vector of 3 numbers, not a string");
    expect_error("cube([1, 2]);", MCSG_ERR_PARSE, "t.scad:1:6:", "not a vector");
    expect_error("cube(1, center=1);", MCSG_ERR_PARSE, "t.scad:1:9:",
                 "`center` must be true or false, not a number");
    expect_error("sphere(r=\"x\");", MCSG_ERR_PARSE, "t.scad:1:8:", "`r` must be a number");
    expect_error("cylinder(h=[1]);", MCSG_ERR_PARSE, "t.scad:1:10:", "`h` must be a number");
    expect_error("translate(\"x\") cube(1);", MCSG_ERR_PARSE, "t.scad:1:11:",
                 "translate(): `v` must be a vector of 2 or 3 numbers, not a string");
    expect_error("translate([1, 0, 1/0]) cube(1);", MCSG_ERR_PARSE, "t.scad:1:11:",
                 "must be finite");
    expect_error("rotate([1, 2, 3, 4]) cube(1);", MCSG_ERR_PARSE, "t.scad:1:8:", "`a` must be");
    expect_error("rotate(a=90, v=true) cube(1);", MCSG_ERR_PARSE, "t.scad:1:14:", "`v` must be");
    expect_error("scale(\"2\") cube(1);", MCSG_ERR_PARSE, "t.scad:1:7:", "`v` must be");
    expect_error("multmatrix([[1, 0], 3]) cube(1);", MCSG_ERR_PARSE, "t.scad:1:12:",
                 "`m` must be a matrix");
    expect_error("multmatrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 0]]) cube(1);",
                 MCSG_ERR_PARSE, "t.scad:1:12:", "m[3][3] is 0");
    expect_error("scale(1e300) scale(1e300) cube(1);", MCSG_ERR_PARSE, "t.scad:1:27:",
                 "cube(size=[1, 1, 1], center=false): vertex 0 is not finite after the transforms");
    expect_error("translate([1e308, 0, 0]) translate([1e308, 0, 0]) cube(1);", MCSG_ERR_PARSE,
                 "t.scad:1:51:", "vertex 0 is not finite");
    expect_error("sphere(1, $fn=\"x\");", MCSG_ERR_PARSE, "t.scad:1:1:",
                 "sphere(): $fn must be a number, not a string");
    expect_error("cube([1, 2, 3] + [1, 2]);", MCSG_ERR_PARSE, "t.scad:1:16:",
                 "cannot apply `+` to a vector and a vector");
    expect_error("cube(\"a\" * 2);", MCSG_ERR_PARSE, "t.scad:1:10:", "cannot apply `*`");
    expect_error("cube(-\"a\");", MCSG_ERR_PARSE, "t.scad:1:6:", "cannot negate a string");
    expect_error("cube(sqrt(\"a\"));", MCSG_ERR_PARSE, "t.scad:1:6:", "sqrt(): invalid arguments");
    expect_error("cube(min());", MCSG_ERR_PARSE, "t.scad:1:6:", "min(): invalid arguments");
}

TEST(warnings_for_ignored_arguments)
{
    log_capture log;
    mcsg_tree *tree = parse_logged("cube(1, true, 3, 4);\ncube(1, foo=2);\n"
                                   "cube(size=1, size=2);\ncube(1, size=2);\n"
                                   "sphere(1) cube(1);\ncylinder(h=1, r=1, r1=2);", &log);
    CHECK_CONTAINS(log.text, "t.scad:1:15: cube(): ignoring surplus positional arguments");
    CHECK_CONTAINS(log.text, "t.scad:2:9: cube(): ignoring unknown argument `foo`");
    CHECK_CONTAINS(log.text, "t.scad:3:14: cube(): argument `size` supplied more than once");
    CHECK_CONTAINS(log.text, "t.scad:4:9: cube(): argument `size` overrides a positional");
    CHECK_CONTAINS(log.text, "t.scad:5:1: sphere() takes no children: ignoring them");
    CHECK_CONTAINS(log.text, "t.scad:6:1: cylinder(): parameters ambiguous");
    CHECK_EQ_SIZE(log.warnings, 6);
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 6);
    mcsg_tree_free(tree);
}

/* `levels` nested union() blocks around one cube, built as text. */
static char *nested_unions(size_t levels)
{
    const char *open = "union() {\n", *close = "}\n", *leaf = "cube(1);\n";
    size_t size = levels * (strlen(open) + strlen(close)) + strlen(leaf) + 1, pos = 0;
    char *text = malloc(size);
    for (size_t i = 0; i < levels; i++, pos += strlen(open))
        memcpy(text + pos, open, strlen(open));
    memcpy(text + pos, leaf, strlen(leaf));
    pos += strlen(leaf);
    for (size_t i = 0; i < levels; i++, pos += strlen(close))
        memcpy(text + pos, close, strlen(close));
    text[pos] = 0;
    return text;
}

static void check_deep_nesting(size_t levels)
{
    char *text = nested_unions(levels);
    mcsg_tree *tree = parse(text);
    mcsg_node_id id = tree ? root(tree) : MCSG_NO_NODE;
    size_t depth = 0;
    CHECK(tree && mcsg_tree_node_count(tree) == levels + 1);
    while (tree && mcsg_tree_child_count(tree, id) == 1) {
        id = mcsg_tree_child(tree, id, 0);
        depth++;
    }
    CHECK_EQ_SIZE(depth, levels);
    CHECK(tree && mcsg_tree_node_kind(tree, id) == MCSG_NODE_LEAF);
    mcsg_tree_free(tree);
    /* Unclosed at the deepest level: the error names the innermost open brace. */
    text[strlen(text) - 2] = 0;
    {
        char where[64];
        snprintf(where, sizeof where, "the `{` at line 1, column 9");
        expect_error(text, MCSG_ERR_PARSE, "unexpected end of file", where);
    }
    free(text);
}

TEST(deep_nesting_10000) { check_deep_nesting(10000); }

TEST(deep_nesting_100000) { check_deep_nesting(100000); }

TEST(deep_transform_chain)
{
    const size_t levels = 10000;
    const char *step = "translate([1, 0, 0])\n";
    size_t len = strlen(step);
    char *text = malloc(levels * len + 16);
    mcsg_tree *tree;
    for (size_t i = 0; i < levels; i++)
        memcpy(text + i * len, step, len);
    strcpy(text + levels * len, "cube(1);");
    tree = parse(text);
    check_bounds(tree, 10000, 0, 0, 10001, 1, 1);
    CHECK_CONTAINS(root_label(tree), "at t.scad:10001:1");
    mcsg_tree_free(tree);
    free(text);
}

/* `depth` copies of `open`, then "1", then `depth` copies of `close`. */
static void check_expression_depth(const char *open, const char *close, size_t depth, bool ok)
{
    size_t lo = strlen(open), lc = strlen(close), pos = 5;
    char *text = malloc(depth * (lo + lc) + 16);
    memcpy(text, "cube(", 5);
    for (size_t i = 0; i < depth; i++, pos += lo)
        memcpy(text + pos, open, lo);
    text[pos++] = '1';
    for (size_t i = 0; i < depth; i++, pos += lc)
        memcpy(text + pos, close, lc);
    strcpy(text + pos, ");");
    if (ok) {
        mcsg_tree_free(parse(text));
    } else {
        expect_error(text, MCSG_ERR_LIMIT, "t.scad:1:", "expression nested more than 256");
    }
    free(text);
}

TEST(expression_depth_limit)
{
    check_expression_depth("(", ")", 250, true);
    check_expression_depth("(", ")", 300, false);
    check_expression_depth("-", "", 250, true);
    check_expression_depth("-", "", 100000, false);
    check_expression_depth("[", "]", 100000, false);
    check_expression_depth("2^", "", 100000, false);
    check_expression_depth("sin(", ")", 1000, false);
}

TEST(api_arguments)
{
    mcsg_tree *tree = (mcsg_tree *)1;
    mcsg_error err;
    CHECK(mcsg_scad_read_memory("cube(1);", 8, NULL, NULL, NULL, NULL, &err) ==
          MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_scad_read_memory(NULL, 3, NULL, NULL, NULL, &tree, &err) == MCSG_ERR_INVALID_ARG);
    CHECK(tree == NULL);
    CHECK_OK(mcsg_scad_read_memory(NULL, 0, NULL, NULL, NULL, &tree, &err), &err);
    CHECK(tree && mcsg_tree_node_count(tree) == 1);
    mcsg_tree_free(tree);
    /* Without a name, messages say <memory>; the text need not be NUL-terminated. */
    CHECK(mcsg_scad_read_memory("cube(1);cub", 11, NULL, NULL, NULL, &tree, &err) ==
          MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "<memory>:1:9:");
    CHECK(mcsg_scad_read("/nonexistent/dir/x.scad", NULL, &tree, &err) == MCSG_ERR_IO);
    CHECK_CONTAINS(err.message, "/nonexistent/dir/x.scad");
    CHECK(tree == NULL);
    CHECK(mcsg_scad_read(NULL, NULL, &tree, &err) == MCSG_ERR_INVALID_ARG);
}

/* Read the CSG text `text` and free the tree: a tree exactly when the read succeeds. */
static mcsg_status read_scad(const void *text, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_tree *tree = NULL;
    mcsg_status st = mcsg_scad_read_memory(text, strlen(text), "t.scad", data_dir(), opts,
                                           &tree, err);
    CHECK(st == MCSG_OK ? tree != NULL : tree == NULL);
    mcsg_tree_free(tree);
    return st;
}

/* Fail allocation 1, 2, ... until the whole read succeeds: each failure must be a
 * clean MCSG_ERR_NOMEM with nothing leaked. */
static void check_allocation_failures(const char *text)
{
    CHECK(test_allocation_failures("CSG read", read_scad, text, false) > 10);
}

TEST(every_allocation_failure_is_clean)
{
    check_allocation_failures(
        "$fn = 8;\n"
        "difference() {\n"
        "  cube([10, 10, 10], center = true);\n"
        "  translate([0, 0, 2]) rotate([0, 90, 0]) cylinder(h = 20, r = 2, center = true);\n"
        "  mirror([1, 0, 0]) scale(0.5) sphere(d = 8, $fn = 12);\n"
        "  multmatrix([[1, 0, 0, 1], [0, 1, 0, 0], [0, 0, 1, 0]]) {\n"
        "    polyhedron(" TETRA_POINTS ", " TETRA_FACES ");\n"
        "    color(\"red\") cube(1); %cube(2); *cube(3);\n"
        "  }\n"
        "}\n"
        "intersection() { cube(1); sphere(min(1, 2) * [1, 1] * [0.5, 0.5]); }\n"
        "cube(undef, foo = 1); group();\n");
}

TEST(every_allocation_failure_with_imports_is_clean)
{
    check_allocation_failures("union() { import(\"cube.off\"); translate([3, 0, 0]) "
                              "import(\"parts/tetra.off\"); }");
}

int main(void)
{
    RUN(cube_forms);
    RUN(sphere_forms);
    RUN(cylinder_forms);
    RUN(resolution_scoping);
    RUN(resolution_warnings);
    RUN(transforms);
    RUN(transform_order_follows_openscad);
    RUN(mirrors_keep_meshes_outward);
    RUN(flattening_transforms_give_empty_sets);
    RUN(operations_and_groups);
    RUN(empty_operands);
    RUN(modifiers);
    RUN(polyhedron_forms);
    RUN(polyhedron_polygons_and_2d_points);
    RUN(polyhedron_errors);
    RUN(imports);
    RUN(imports_read_ahead);
    RUN(import_relative_to_the_file);
    RUN(import_errors);
    RUN(openscad_exported_csg);
    RUN(expressions);
    RUN(special_variables_hold_any_value);
    RUN(syntax_errors);
    RUN(unsupported_constructs);
    RUN(bad_argument_types);
    RUN(warnings_for_ignored_arguments);
    RUN(deep_nesting_10000);
    RUN(deep_nesting_100000);
    RUN(deep_transform_chain);
    RUN(expression_depth_limit);
    RUN(api_arguments);
    RUN(every_allocation_failure_is_clean);
    RUN(every_allocation_failure_with_imports_is_clean);
    return test_summary();
}
