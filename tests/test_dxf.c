/*
 * DXF drawings as OpenSCAD 2021.01's import() reads them (src/io/dxf.c): outlines, their
 * fill, warnings, errors and limits. The known answers below come from OpenSCAD 2021.01
 * (`openscad -o x.nef3` of the import linear_extruded and unioned with a far cube: the
 * exact vertices of OpenSCAD's polygon; `openscad -o x.dxf` of the import: its area from
 * coordinates printed to 6 digits), see tests/data/README.md for the files.
 */
#include "testlib.h"

#include "base/core.h"
#include "io/dxf.h"
#include "shape/region.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static mci_ctx ctx;

static double region_area(const mci_region *r)
{
    double sum = 0;
    for (size_t t = 0; t < r->tri_count; t++) {
        const double *a = r->xy + 2 * r->tris[3 * t], *b = r->xy + 2 * r->tris[3 * t + 1],
                     *c = r->xy + 2 * r->tris[3 * t + 2];
        sum += ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2;
    }
    return sum;
}

typedef struct known {
    const char *file, *layer;
    double origin[2], scale, fn;
    size_t loops, points; /* the outlines as read */
    double area;          /* their even-odd fill, as meshcsg's region sums it */
    double openscad_area; /* OpenSCAD's, from its export to 6 digits */
    size_t vertices;      /* the region's */
    size_t openscad_vertices; /* OpenSCAD's (the exact vertices of its polygon) */
} known;

/* OpenSCAD 2021.01: example007, 008, 009 and 013 import these layers (example009's
 * fan_side with origin [0, -40], example015 its body with scale 2); the other files are
 * this project's, written to try snapping, layers, arcs, ellipses, blocks, branching and
 * open paths. fa = 12, fs = 2 throughout (OpenSCAD's defaults). Every vertex of
 * OpenSCAD's polygon is one of the region's; the region's others (the difference of the
 * last two columns) lie on straight boundaries, which OpenSCAD's polygon omits. */
static const known KNOWN[] = {
    {"example007.dxf", "cutout1", {0, 0}, 1, 0, 1, 4, 112, 112, 4, 4},
    {"example007.dxf", "cutout2", {0, 0}, 1, 0, 1, 8, 511, 511, 8, 8},
    {"example007.dxf", "dorn", {0, 0}, 1, 0, 1, 9, 187.5, 187.5, 9, 9},
    {"example008.dxf", "G", {0, 0}, 1, 0, 1, 16, 1650, 1650, 16, 16},
    {"example008.dxf", "E", {0, 0}, 1, 0, 1, 12, 1500, 1500, 12, 12},
    {"example008.dxf", "B", {0, 0}, 1, 0, 3, 17, 1850, 1850, 17, 17},
    {"example008.dxf", "X", {0, 0}, 1, 0, 1, 4, 400, 400, 4, 4},
    {"example009.dxf", "body", {0, 0}, 1, 0, 6, 138, 308.86538505554199, 308.8620199, 138, 138},
    {"example009.dxf", "plate", {0, 0}, 1, 0, 9, 102, 627.15943050384521, 627.1567887, 102, 102},
    {"example009.dxf", "fan_top", {0, 0}, 1, 0, 2, 37, 294.9394063949585, 294.9394664, 37, 37},
    {"example009.dxf", "fan_side", {0, -40}, 1, 0, 1, 31, 363.97951126098633, 363.9791459, 31,
     31},
    {"example009.dxf", "body", {0, 0}, 2, 0, 6, 214, 1230.8823146820068, 1230.880866, 214, 214},
    {"example013.dxf", NULL, {0, 0}, 1, 0, 1, 20, 2000, 2000, 20, 20},
    {"snap.dxf", NULL, {0, 0}, 1, 0, 2, 7, 85.0048828125, 85.005, 7, 7},
    {"layers.dxf", NULL, {0, 0}, 1, 0, 3, 25, 266.52702331542969, 266.5270048, 25, 25},
    {"layers.dxf", "A", {0, 0}, 1, 0, 1, 6, 150, 150, 6, 6},
    {"layers.dxf", "B", {0, 0}, 1, 0, 2, 19, 116.52702331542969, 116.5270048, 19, 19},
    {"layers.dxf", "B", {0, 0}, 1, 8, 2, 11, 110.703125, 110.704, 11, 11},
    {"curves.dxf", NULL, {0, 0}, 1, 0, 2, 34, 354.48970699310303, 354.4898998, 34, 34},
    {"curves.dxf", NULL, {0, 0}, 1, 10, 2, 18, 346.93409729003906, 346.9345718, 18, 18},
    {"curves.dxf", NULL, {1, 2}, 3, 0, 3, 50, 3870.0253295898438, 3870.023032, 48, 48},
    {"insert.dxf", NULL, {0, 0}, 1, 0, 3, 10, 13.500236511230469, 13.50025548, 10, 10},
    {"insert.dxf", NULL, {-1, 1}, 2, 0, 3, 10, 53.999255180358887, 53.99946357, 10, 10},
    {"theta.dxf", NULL, {0, 0}, 1, 0, 1, 7, 8, 8, 6, 4},
    {"open.dxf", NULL, {0, 0}, 1, 0, 2, 6, 40, 40, 4, 4},
};

static mcsg_status read_known(const known *k, mci_outlines *o, mcsg_error *err)
{
    char name[64];
    snprintf(name, sizeof name, "dxf/%s", k->file);
    return mci_dxf_read(&ctx, test_data(name), k->layer, k->origin, k->scale, k->fn, 12, 2, o,
                        err);
}

TEST(dxf_known_answers_from_openscad)
{
    for (size_t i = 0; i < sizeof KNOWN / sizeof *KNOWN; i++) {
        const known *k = &KNOWN[i];
        mci_outlines o;
        mci_region r;
        mcsg_error err;
        double area;
        CHECK_OK(read_known(k, &o, &err), &err);
        CHECK_MSG(o.loop_count == k->loops && o.point_count == k->points,
                  "%s %s: %zu loops, %zu points", k->file, k->layer ? k->layer : "",
                  o.loop_count, o.point_count);
        CHECK_OK(mci_region_from_outlines(&ctx, &o, &r, &err), &err);
        area = region_area(&r);
        CHECK_MSG(fabs(area - k->area) <= 1e-9 * k->area, "%s %s: area %.17g, not %.17g",
                  k->file, k->layer ? k->layer : "", area, k->area);
        CHECK_MSG(fabs(area - k->openscad_area) <= 2e-5 * k->area,
                  "%s %s: area %.17g, OpenSCAD's %.17g", k->file, k->layer ? k->layer : "",
                  area, k->openscad_area);
        CHECK_MSG(r.vertex_count == k->vertices, "%s %s: %zu vertices", k->file,
                  k->layer ? k->layer : "", r.vertex_count);
        mci_region_free(&ctx, &r);
        mci_outlines_free(&ctx, &o);
    }
}

static void check_loop(const mci_outlines *o, size_t k, const double *xy, size_t n)
{
    CHECK_MSG(k < o->loop_count && o->loop_start[k + 1] - o->loop_start[k] == n,
              "loop %zu: wrong size", k);
    if (k >= o->loop_count || o->loop_start[k + 1] - o->loop_start[k] != n)
        return;
    for (size_t i = 0; i < 2 * n; i++)
        CHECK_MSG(o->xy[2 * o->loop_start[k] + i] == xy[i], "loop %zu, coordinate %zu: %.17g",
                  k, i, o->xy[2 * o->loop_start[k] + i]);
}

/* Paths in OpenSCAD's order: open ones first (each backwards, closed from its last point
 * to its first), then closed ones (backwards, without the first point). */
TEST(dxf_paths_in_openscad_order)
{
    static const double zigzag[] = {5, 3, 10, 10, 10, 0, 0, 0}, lone[] = {30, 10, 20, 0};
    /* theta.dxf: the bar (2,0)-(2,2) first, then the rectangle; the closed path from the
     * bar ends at (2,2), not where it started, and loses the bar with its first point. */
    static const double theta[] = {2, 2, 0, 2, 0, 0, 2, 0, 4, 0, 4, 2, 2, 2};
    static const known open = {"open.dxf", NULL, {0, 0}, 1, 0, 0, 0, 0, 0, 0, 0};
    static const known th = {"theta.dxf", NULL, {0, 0}, 1, 0, 0, 0, 0, 0, 0, 0};
    mci_outlines o;
    mcsg_error err;
    CHECK_OK(read_known(&open, &o, &err), &err);
    check_loop(&o, 0, zigzag, 4);
    check_loop(&o, 1, lone, 2);
    mci_outlines_free(&ctx, &o);
    CHECK_OK(read_known(&th, &o, &err), &err);
    check_loop(&o, 0, theta, 7);
    mci_outlines_free(&ctx, &o);
}

static char logged[4096];

static void capture_log(void *user, mcsg_log_level level, const char *message)
{
    size_t n = strlen(logged);
    (void)user;
    snprintf(logged + n, sizeof logged - n, "%d %s\n", (int)level, message);
}

static mcsg_status read_text(const mci_ctx *c, const char *text, const char *layer,
                             mci_outlines *o, mcsg_error *err)
{
    return mci_dxf_read_memory(c, text, strlen(text), "t.dxf", layer, NULL, 1, 0, 12, 2, o,
                               err);
}

#define SEC "0\nSECTION\n2\nENTITIES\n"
#define END "0\nENDSEC\n0\nEOF\n"
#define LINE(x1, y1, x2, y2) "0\nLINE\n8\n0\n10\n" #x1 "\n20\n" #y1 "\n11\n" #x2 "\n21\n" #y2 "\n"

/* OpenSCAD's warning, once per kind of entity, with the count in hexadecimal. */
TEST(dxf_unsupported_entities_warn)
{
    mcsg_options opts;
    mci_ctx logging;
    mci_outlines o;
    mcsg_error err;
    char text[2048] = SEC;
    for (int i = 0; i < 17; i++)
        strcat(text, "0\nTEXT\n8\n0\n1\nx\n");
    strcat(text, "0\nSPLINE\n8\nother\n" LINE(0, 0, 1, 0) LINE(1, 0, 0, 1) LINE(0, 1, 0, 0) END);
    memset(&opts, 0, sizeof opts);
    opts.log = capture_log;
    mci_ctx_init(&logging, &opts);
    logged[0] = 0;
    CHECK_OK(read_text(&logging, text, NULL, &o, &err), &err);
    CHECK(o.loop_count == 1 && o.point_count == 3);
    CHECK_CONTAINS(logged, "2 Unsupported DXF Entity 'TEXT' (11) in \"t.dxf\".\n");
    CHECK_CONTAINS(logged, "2 Unsupported DXF Entity 'SPLINE' (1) in \"t.dxf\".\n");
    mci_outlines_free(&ctx, &o);
    logged[0] = 0;
    CHECK_OK(read_text(&logging, text, "0", &o, &err), &err);
    CHECK(o.loop_count == 1);
    CHECK_CONTAINS(logged, "Unsupported DXF Entity 'TEXT' (11) in layer '0' of t.dxf\n");
    CHECK(!strstr(logged, "SPLINE")); /* on another layer */
    mci_outlines_free(&ctx, &o);
}

/* OpenSCAD turns an entity into segments at the next group code 0: the last one before
 * the end of the file is dropped; entities outside ENTITIES and BLOCKS count for nothing. */
TEST(dxf_entities_end_at_the_next_group_code_0)
{
    mci_outlines o;
    mcsg_error err;
    CHECK_OK(read_text(&ctx, SEC LINE(0, 0, 4, 0) LINE(4, 0, 0, 3) LINE(0, 3, 0, 0), NULL, &o,
                       &err),
             &err);
    CHECK(o.loop_count == 1 && o.point_count == 3); /* an open path: the last LINE dropped */
    mci_outlines_free(&ctx, &o);
    CHECK_OK(read_text(&ctx, LINE(0, 0, 4, 0) LINE(4, 0, 0, 3) LINE(0, 3, 0, 0) END, NULL, &o,
                       &err),
             &err);
    CHECK(o.loop_count == 0 && o.point_count == 0);
    mci_outlines_free(&ctx, &o);
    /* White space around codes and values, CR LF line ends, a code line without a value
     * at the end of the file. */
    CHECK_OK(read_text(&ctx, "  0\r\nSECTION\r\n  2\r\nENTITIES\r\n0\r\nLWPOLYLINE\r\n70\r\n"
                             "   1\r\n10\r\n0\r\n20\r\n0\r\n10\r\n2\r\n20\r\n0\r\n10\r\n0\r\n"
                             "20\r\n2\r\n  0\r\nENDSEC\r\n999",
                       NULL, &o, &err),
             &err);
    CHECK(o.loop_count == 1 && o.point_count == 3);
    mci_outlines_free(&ctx, &o);
    CHECK_OK(read_text(&ctx, "", NULL, &o, &err), &err);
    CHECK(o.loop_count == 0);
    mci_outlines_free(&ctx, &o);
}

static void check_error(const char *text, mcsg_status status, const char *message)
{
    mci_outlines o;
    mcsg_error err = {MCSG_OK, ""};
    mcsg_status st = read_text(&ctx, text, NULL, &o, &err);
    CHECK_MSG(st == status, "status %d, not %d, for %s", (int)st, (int)status, message);
    CHECK_CONTAINS(err.message, message);
    CHECK(o.xy == NULL && o.loop_start == NULL && o.loop_count == 0);
}

TEST(dxf_errors_name_the_line)
{
    check_error(SEC "0\nLINE\nten\n0\n" END, MCSG_ERR_PARSE,
                "t.dxf:7: group code 'ten' is not an integer");
    check_error(SEC "0\nLINE\n10\n1,5\n" END, MCSG_ERR_PARSE,
                "t.dxf:8: group code 10: '1,5' is not a finite number");
    check_error(SEC "0\nCIRCLE\n40\ninf\n" END, MCSG_ERR_PARSE,
                "t.dxf:8: group code 40: 'inf' is not a finite number");
    check_error(SEC "0\nLINE\n70\n1.5\n" END, MCSG_ERR_PARSE,
                "t.dxf:8: group code 70: '1.5' is not an integer");
    check_error(SEC "0\nLINE\n10\n1\n20\n1\n" END, MCSG_ERR_PARSE,
                "t.dxf:6: LINE without its two points");
    check_error(SEC "0\nCIRCLE\n40\n1\n" END, MCSG_ERR_PARSE, "t.dxf:6: CIRCLE without its point");
    check_error(SEC "0\nLWPOLYLINE\n10\n1\n20\n1\n10\n2\n" END, MCSG_ERR_PARSE,
                "t.dxf:6: LWPOLYLINE with 2 x and 1 y coordinates");
    /* A bad code line at the very end is where OpenSCAD stops, silently. */
    {
        mci_outlines o;
        mcsg_error err;
        CHECK_OK(read_text(&ctx, SEC LINE(0, 0, 1, 0) "0\nEOF\nnot a code", NULL, &o, &err),
                 &err);
        CHECK(o.loop_count == 1);
        mci_outlines_free(&ctx, &o);
    }
}

TEST(dxf_limits)
{
    mci_outlines o;
    mcsg_error err = {MCSG_OK, ""};
    const char *circle = SEC "0\nCIRCLE\n10\n0\n20\n0\n40\n1\n" END;
    check_error(SEC LINE(0, 0, 1e13, 0) END, MCSG_ERR_LIMIT,
                "t.dxf:6: LINE: point (10000000000000, 0) is not finite or beyond 2^40");
    check_error(SEC "0\nARC\n10\n0\n20\n0\n40\n1\n50\n1e9\n51\n0\n" END, MCSG_ERR_LIMIT,
                "t.dxf:6: ARC: start and end angles more than 1024 turns apart");
    check_error(SEC "0\nARC\n10\n0\n20\n0\n40\n1\n50\n0\n51\n1e30\n" END, MCSG_ERR_LIMIT,
                "t.dxf:6: ARC: more than 4194304 line segments");
    /* $fn of a billion: refused before anything is made. */
    CHECK(mci_dxf_read_memory(&ctx, circle, strlen(circle), "t.dxf", NULL, NULL, 1, 1e9, 12, 2,
                              &o, &err) == MCSG_ERR_LIMIT);
    CHECK_CONTAINS(err.message, "t.dxf:6: CIRCLE: more than 4194304 line segments");
    /* Blocks inserted into blocks: each doubles, ten levels are 2^10 copies of a square. */
    {
        char text[8192] = "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n2\nB0\n" LINE(0, 0, 1, 0)
            LINE(1, 0, 1, 1) LINE(1, 1, 0, 1) LINE(0, 1, 0, 0) "0\nENDBLK\n";
        char *p = text + strlen(text);
        for (int k = 1; k <= 10; k++)
            p += sprintf(p, "0\nBLOCK\n2\nB%d\n0\nINSERT\n2\nB%d\n10\n0\n20\n0\n"
                            "0\nINSERT\n2\nB%d\n10\n%d\n20\n0\n0\nENDBLK\n",
                         k, k - 1, k - 1, 1 << k);
        sprintf(p, "0\nENDSEC\n0\nSECTION\n2\nENTITIES\n0\nINSERT\n2\nB10\n10\n0\n20\n0\n" END);
        CHECK_OK(read_text(&ctx, text, NULL, &o, &err), &err);
        CHECK(o.loop_count == 1024 && o.point_count == 4096);
        mci_outlines_free(&ctx, &o);
    }
}

static mcsg_status read_under(const void *what, const mcsg_options *opts, mcsg_error *err)
{
    const known *k = what;
    mci_ctx c;
    mci_outlines o;
    char name[64];
    mcsg_status st;
    mci_ctx_init(&c, opts);
    snprintf(name, sizeof name, "dxf/%s", k->file);
    st = mci_dxf_read(&c, test_data(name), k->layer, k->origin, k->scale, k->fn, 12, 2, &o, err);
    if (st == MCSG_OK) {
        CHECK(o.loop_count == k->loops && o.point_count == k->points);
        mci_outlines_free(&c, &o);
    }
    return st;
}

TEST(dxf_allocation_failures)
{
    CHECK(test_allocation_failures("mci_dxf_read insert.dxf", read_under, &KNOWN[21], false) >
          10);
    CHECK(test_allocation_failures("mci_dxf_read layers.dxf", read_under, &KNOWN[14], false) >
          10);
}

TEST(dxf_unreadable_file)
{
    mci_outlines o;
    mcsg_error err = {MCSG_OK, ""};
    CHECK(mci_dxf_read(&ctx, test_data("dxf/no-such-file.dxf"), NULL, NULL, 1, 0, 12, 2, &o,
                       &err) == MCSG_ERR_IO);
    CHECK_CONTAINS(err.message, "no-such-file.dxf");
    CHECK(mci_dxf_read(&ctx, NULL, NULL, NULL, 1, 0, 12, 2, &o, &err) == MCSG_ERR_INVALID_ARG);
}

int main(void)
{
    mci_ctx_init(&ctx, NULL);
    RUN(dxf_known_answers_from_openscad);
    RUN(dxf_paths_in_openscad_order);
    RUN(dxf_unsupported_entities_warn);
    RUN(dxf_entities_end_at_the_next_group_code_0);
    RUN(dxf_errors_name_the_line);
    RUN(dxf_limits);
    RUN(dxf_allocation_failures);
    RUN(dxf_unreadable_file);
    return test_summary();
}
