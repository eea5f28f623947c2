/*
 * SVG import (src/io/svg.c, src/shape/stroke.c, the union in src/scad/shapes2d.c)
 * against OpenSCAD 2021.01. The known answers come from OpenSCAD itself
 * (tests/data/svg/measure.py): for each file, OpenSCAD's loops and points
 * (`openscad -o x.svg` of the import) and the exact area of its polygon (the rational
 * vertices of `openscad -o x.nef3` of the import extruded by 1). Files are OpenSCAD's own
 * SVG test data (tests/data/svg/README.md). Where shapes do not overlap, meshcsg's area
 * and points are OpenSCAD's exactly; where they overlap (a stroke across a circle),
 * OpenSCAD's Clipper rounds each crossing of the union to 2^-16 and cleans points near
 * it, meshcsg's union is exact: those differ by up to 3e-6 of the area.
 */
#include "testlib.h"

#include "base/core.h"
#include "io/svg.h"
#include "shape/region.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static mci_ctx ctx;

typedef struct known {
    const char *file;
    bool center;
    double dpi;
    size_t loops, points; /* OpenSCAD's */
    double area;          /* OpenSCAD's, exact */
    bool overlapping;     /* shapes overlap: the union's crossings are rounded there */
} known;

static const known KNOWN[] = {
    {"spec-paths-arcs01.svg", false, 72, 3, 154, 747.1412348767044, false},
    {"spec-paths-arcs02.svg", false, 72, 4, 120, 59.440566000994295, false},
    {"spec-paths-cubic01.svg", false, 72, 1, 368, 28.856165638426319, true},
    {"spec-paths-cubic02.svg", false, 72, 6, 1385, 119.47817513090558, true},
    {"spec-paths-quad01.svg", false, 72, 3, 276, 83.060801962739788, true},
    {"spec-paths-triangle01.svg", false, 72, 1, 3, 200, false},
    {"spec-shapes-circle01.svg", false, 72, 1, 40, 312.86903010169044, false},
    {"spec-shapes-ellipse01.svg", false, 72, 2, 80, 1564.3447300976841, false},
    {"spec-shapes-line01.svg", false, 72, 5, 20, 225.8822712689871, false},
    {"spec-shapes-polygon01.svg", false, 72, 2, 16, 585.60389558412135, false},
    {"spec-shapes-polyline01.svg", false, 72, 1, 44, 311, false},
    {"spec-shapes-rect01.svg", false, 72, 1, 4, 800, false},
    {"spec-shapes-rect02.svg", false, 72, 2, 80, 1556.2833722857758, false},
    {"box-w-holes.svg", true, 72, 5, 324, 2183.6836491797585, false},
    {"simple.svg", true, 72, 2, 164, 299.99938850384206, false},
    {"simple.svg", false, 96, 2, 164, 299.9996791643789, false},
    {"line-cap-line-join.svg", false, 72, 9, 3979, 7662.5221058800817, false},
    {"viewbox_300x400_meet_xMaxYMin.svg", false, 72, 10, 70, 11005.890600686427, false},
    {"viewbox_300x400_meet_xMidYMin.svg", false, 72, 10, 70, 11005.890600686427, false},
    {"viewbox_300x400_meet_xMinYMin.svg", false, 72, 10, 70, 11005.889837746043, false},
    {"viewbox_300x400_none.svg", false, 72, 10, 70, 22011.780720593291, false},
    {"viewbox_600x200_meet_xMinYMax.svg", false, 72, 10, 70, 11005.888693335932, false},
    {"viewbox_600x200_meet_xMinYMid.svg", false, 72, 10, 70, 11005.890219215769, false},
    {"viewbox_600x200_meet_xMinYMin.svg", false, 72, 10, 70, 11005.889837746043, false},
    {"viewbox_600x200_none.svg", false, 72, 10, 70, 22011.778837269638, false},
    {"viewbox_600x200_slice_xMaxYMin.svg", false, 72, 10, 70, 44023.558866926702, false},
    {"viewbox_600x200_slice_xMidYMin.svg", false, 72, 10, 70, 44023.56007927889, false},
    {"viewbox_600x200_slice_xMinYMin.svg", false, 72, 10, 70, 44023.559764740989, false},
    {"viewbox_600x600_slice_xMinYMax.svg", false, 72, 10, 70, 11005.889837746043, false},
    {"viewbox_600x600_slice_xMinYMid.svg", false, 72, 10, 70, 11005.889837746043, false},
    {"viewbox_600x600_slice_xMinYMin.svg", false, 72, 10, 70, 11005.889837746043, false},
};

static char logged[8192];

static void capture_log(void *user, mcsg_log_level level, const char *message)
{
    size_t n = strlen(logged);
    (void)user;
    snprintf(logged + n, sizeof logged - n, "%d %s\n", (int)level, message);
}

/* The import extruded by 1, evaluated: its volume is the area. */
static double extruded_area(const known *k, size_t *vertices)
{
    char text[512];
    mcsg_options opts;
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_error err;
    double volume = NAN;
    memset(&opts, 0, sizeof opts);
    snprintf(text, sizeof text, "linear_extrude(1) import(\"%s\", center=%s, dpi=%g);", k->file,
             k->center ? "true" : "false", k->dpi);
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "t.scad", test_data("svg"), &opts, &tree,
                                   &err),
             &err);
    if (tree && mcsg_eval(tree, &opts, &out, NULL, NULL, &err) == MCSG_OK) {
        volume = test_signed_volume(&out);
        *vertices = out.vertex_count;
        mcsg_mesh_free(&out, NULL);
    } else {
        CHECK_MSG(false, "%s: %s", k->file, err.message);
    }
    mcsg_tree_free(tree);
    return volume;
}

TEST(svg_known_answers_from_openscad)
{
    for (size_t i = 0; i < sizeof KNOWN / sizeof *KNOWN; i++) {
        const known *k = &KNOWN[i];
        char name[96];
        mci_svg s;
        mcsg_error err;
        size_t vertices = 0;
        double area;
        snprintf(name, sizeof name, "svg/%s", k->file);
        CHECK_OK(mci_svg_read(&ctx, test_data(name), k->dpi, k->center, &s, &err), &err);
        if (!k->overlapping)
            CHECK_MSG(s.outlines.loop_count == k->loops && s.outlines.point_count == k->points,
                      "%s: %zu loops, %zu points; OpenSCAD %zu, %zu", k->file,
                      s.outlines.loop_count, s.outlines.point_count, k->loops, k->points);
        mci_svg_free(&ctx, &s);
        area = extruded_area(k, &vertices);
        CHECK_MSG(fabs(area - k->area) <= (k->overlapping ? 3e-6 : 1e-9) * k->area,
                  "%s: area %.17g, OpenSCAD's %.17g", k->file, area, k->area);
        if (!k->overlapping)
            CHECK_MSG(vertices == 2 * k->points, "%s: %zu vertices, OpenSCAD %zu points",
                      k->file, vertices, k->points);
    }
}

/* OpenSCAD's extruded SVG tests (testdata/scad/svg/extruded, viewbox-test.scad with two
 * of the viewbox files), exported with `openscad -o x.csg`; the volumes are those of
 * `openscad -o x.stl`, whose float coordinates alone move them by up to 1e-6. */
TEST(svg_extruded_openscad_tests)
{
    static const struct {
        const char *csg;
        double volume;
    } cases[] = {
        {"ex-box-w-holes.csg", 4383.4638047439921},
        {"ex-simple-center.csg", 324.19338139333041},
        {"ex-viewbox_300x400_none.csg", 70097.016909065715},
        {"ex-viewbox_600x200_slice_xMidYMin.csg", 67972.385963250112},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char name[96];
        mcsg_tree *tree = NULL;
        mcsg_mesh out;
        mcsg_error err;
        mcsg_check_report report;
        snprintf(name, sizeof name, "svg/%s", cases[i].csg);
        CHECK_OK(mcsg_scad_read(test_data(name), NULL, &tree, &err), &err);
        CHECK_OK(mcsg_eval(tree, NULL, &out, NULL, NULL, &err), &err);
        CHECK_OK(mcsg_mesh_check(&out, NULL, &report, &err), &err);
        CHECK(mcsg_check_report_is_valid(&report));
        CHECK_MSG(fabs(test_signed_volume(&out) - cases[i].volume) <= 1e-6 * cases[i].volume,
                  "%s: volume %.17g, OpenSCAD's %.17g", cases[i].csg, test_signed_volume(&out),
                  cases[i].volume);
        mcsg_mesh_free(&out, NULL);
        mcsg_tree_free(tree);
    }
}

static mcsg_status read_text(const char *text, mci_svg *s, mcsg_error *err)
{
    return mci_svg_read_memory(&ctx, text, strlen(text), "t.svg", 72, false, s, err);
}

/* Area of shape k's even-odd fill. */
static double shape_area(const mci_svg *s, size_t k)
{
    mci_outlines one = {s->outlines.xy, NULL, s->outlines.point_count,
                        s->outlines.loop_start + s->shape_start[k],
                        s->shape_start[k + 1] - s->shape_start[k]};
    mci_region r;
    mcsg_error err;
    double sum = 0;
    CHECK_OK(mci_region_from_outlines(&ctx, &one, &r, &err), &err);
    for (size_t t = 0; t < r.tri_count; t++) {
        const double *a = r.xy + 2 * r.tris[3 * t], *b = r.xy + 2 * r.tris[3 * t + 1],
                     *c = r.xy + 2 * r.tris[3 * t + 2];
        sum += ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2;
    }
    mci_region_free(&ctx, &r);
    return sum;
}

/* OpenSCAD's quirks, each checked against its own import of the same text: no viewBox
 * (a user unit is a millimetre, y flipped about the page height), transforms of the
 * containers but never the outermost element's, mm units, a rotate about a centre. */
TEST(svg_placement_and_transforms)
{
    static const char *text =
        "<svg width=\"100mm\" height=\"50mm\">\n"
        "<g transform=\"translate(10 5) scale(2)\">\n"
        "  <rect x=\"1\" y=\"1\" width=\"3\" height=\"2\"/>\n"
        "  <rect transform=\"rotate(90 10 10)\" x=\"10\" y=\"10\" width=\"4\" height=\"1\"/>\n"
        "</g>\n"
        "<defs><rect width=\"100\" height=\"100\"/></defs>\n"
        "<path d=\"M0 0 H4 V4 H0 z m1 1 h2 v2 h-2 z\"/>\n"
        "</svg>\n";
    mci_svg s;
    mcsg_error err;
    CHECK_OK(read_text(text, &s, &err), &err);
    CHECK(s.shape_count == 3);
    if (s.shape_count == 3) {
        /* (1,1)-(4,3) scaled by 2 and moved: x 12..18, y 7..11, then y = 50 - y */
        CHECK(s.outlines.xy[0] == 12 && s.outlines.xy[1] == 43);
        CHECK(fabs(shape_area(&s, 0) - 24) == 0);
        CHECK(fabs(shape_area(&s, 1) - 16) == 0);
        CHECK(shape_area(&s, 2) == 12); /* even-odd: the inner square is a hole */
        CHECK(s.shape_line[2] == 7);
    }
    mci_svg_free(&ctx, &s);
}

TEST(svg_errors_name_the_line)
{
    static const struct {
        const char *text, *needle;
        mcsg_status status;
    } cases[] = {
        {"<svg>\n<rect width=\"1\"\n</svg>", "t.svg:3: malformed XML", MCSG_ERR_PARSE},
        {"<svg>\n\n<rect width=\"1px\" height=\"1\"/></svg>", "t.svg:3: <rect> width=\"1px\"",
         MCSG_ERR_PARSE},
        {"<svg>\n<path d=\"M 0 0 L 1 x\"/></svg>", "t.svg:2: <path> d: \"x\"", MCSG_ERR_PARSE},
        {"<svg><g transform=\"scale(q)\"/></svg>", "t.svg:1: transform: \"q\"", MCSG_ERR_PARSE},
        {"<svg><polygon points=\"1 2 3 ,y\"/></svg>", "points: \"y\"", MCSG_ERR_PARSE},
        {"", "malformed XML", MCSG_ERR_PARSE},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        mci_svg s;
        mcsg_error err = {MCSG_OK, ""};
        CHECK_MSG(read_text(cases[i].text, &s, &err) == cases[i].status, "case %zu: %s", i,
                  err.message);
        CHECK_CONTAINS(err.message, cases[i].needle);
        CHECK(s.outlines.xy == NULL && s.shape_count == 0);
    }
}

TEST(svg_limits)
{
    mci_buf b = {0};
    mci_svg s;
    mcsg_error err;
    CHECK(mci_buf_printf(&ctx, &b, "<svg>"));
    for (int i = 0; i < 1100; i++)
        CHECK(mci_buf_printf(&ctx, &b, "<g>"));
    CHECK(mci_buf_printf(&ctx, &b, "%s", ""));
    CHECK(mci_svg_read_memory(&ctx, (const char *)b.data, b.len, "deep.svg", 72, false, &s,
                              &err) == MCSG_ERR_LIMIT);
    CHECK_CONTAINS(err.message, "deep.svg:1: containers nested more than 1024 deep");
    b.len = 0;
    CHECK(mci_buf_printf(&ctx, &b, "<svg><polyline stroke-width=\"1e9\" "
                         "stroke-linecap=\"round\" points=\"0 0 1 0\"/></svg>"));
    CHECK(mci_svg_read_memory(&ctx, (const char *)b.data, b.len, "big.svg", 72, false, &s,
                              &err) == MCSG_ERR_LIMIT);
    CHECK_CONTAINS(err.message, "more than");
    mci_buf_free(&ctx, &b);
}

/* Strokes that cannot be reproduced are left out with a warning, and OpenSCAD's own
 * warnings (invalid transform arguments, points beyond Clipper's range) are given. */
TEST(svg_warnings)
{
    static const char *text =
        "<svg>\n<line x1=\"0\" y1=\"0\" x2=\"1e300\" y2=\"0\"/>\n"
        "<rect transform=\"translate(1 2 3)\" width=\"2\" height=\"2\"/>\n"
        "<rect x=\"1e300\" width=\"1e300\" height=\"2\"/>\n</svg>\n";
    mcsg_options opts;
    mci_ctx c;
    mci_svg s;
    mcsg_error err;
    memset(&opts, 0, sizeof opts);
    opts.log = capture_log;
    mci_ctx_init(&c, &opts);
    logged[0] = '\0';
    CHECK_OK(mci_svg_read_memory(&c, text, strlen(text), "w.svg", 72, false, &s, &err), &err);
    CHECK_CONTAINS(logged, "w.svg:2: a stroke left out");
    CHECK_CONTAINS(logged, "w.svg:3: invalid arguments for translate");
    CHECK_CONTAINS(logged, "w.svg:4: Range check failed for polygon. skipping");
    CHECK(s.shape_count == 1); /* the rect, untransformed */
    mci_svg_free(&c, &s);
}

static mcsg_status read_under(const void *p, const mcsg_options *opts, mcsg_error *err)
{
    const known *k = p;
    mci_ctx c;
    mci_svg s;
    char name[96];
    mcsg_status st;
    mci_ctx_init(&c, opts);
    snprintf(name, sizeof name, "svg/%s", k->file);
    st = mci_svg_read(&c, test_data(name), k->dpi, k->center, &s, err);
    if (st == MCSG_OK) {
        CHECK(s.outlines.loop_count == k->loops && s.outlines.point_count == k->points);
        mci_svg_free(&c, &s);
    }
    return st;
}

TEST(svg_allocation_failures)
{
    /* strokes of every join and cap, and a rounded rectangle */
    CHECK(test_allocation_failures("mci_svg_read spec-shapes-rect02.svg", read_under,
                                   &KNOWN[12], false) > 10);
    CHECK(test_allocation_failures("mci_svg_read spec-shapes-polyline01.svg", read_under,
                                   &KNOWN[10], false) > 10);
}

TEST(svg_unreadable_file)
{
    mci_svg s;
    mcsg_error err = {MCSG_OK, ""};
    CHECK(mci_svg_read(&ctx, test_data("svg/no-such-file.svg"), 72, false, &s, &err) ==
          MCSG_ERR_IO);
    CHECK_CONTAINS(err.message, "no-such-file.svg");
}

int main(void)
{
    mci_ctx_init(&ctx, NULL);
    RUN(svg_known_answers_from_openscad);
    RUN(svg_extruded_openscad_tests);
    RUN(svg_placement_and_transforms);
    RUN(svg_errors_name_the_line);
    RUN(svg_limits);
    RUN(svg_warnings);
    RUN(svg_allocation_failures);
    RUN(svg_unreadable_file);
    return test_summary();
}
