/*
 * surface() as OpenSCAD 2021.01 builds it (src/io/surface.c): .dat tables and PNG height
 * maps of every colour type, the mesh's counts, volume and orientation, errors and limits.
 * The known answers come from OpenSCAD 2021.01 (`openscad -o x.stl` of
 * surface(file, center, invert)): its vertex and triangle counts, and the volume of its STL,
 * which prints each coordinate rounded to a float and then to 6 digits; the same rounding
 * of meshcsg's mesh gives OpenSCAD's volume (and the same vertices and top triangles).
 */
#include "testlib.h"

#include "base/core.h"
#include "io/surface.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static mci_ctx ctx;

typedef struct known {
    const char *file;
    bool center, invert;
    size_t vertices, triangles;
    double volume;          /* meshcsg's, exact up to the sum's rounding */
    double openscad_volume; /* of OpenSCAD's STL */
} known;

/* example010.dat (Old/example010.scad) and surface_image.png (Advanced/surface_image.scad)
 * are OpenSCAD's examples; the others this project's (tests/data/surface). short-row.dat
 * has a missing value (0) at the boundary, where every height is at least 1: that vertex is
 * the bottom's, and OpenSCAD's STL drops the same two flat wall triangles. */
static const known KNOWN[] = {
    {"example010.dat", false, false, 4321, 8638, 21785.556322572003, 21785.621664180002},
    {"example010.dat", true, true, 4321, 8638, 21785.556322572003, 21785.621664180017},
    {"surface_image.png", false, false, 5097, 10190, 87367.557235295317, 87367.55737600007},
    {"surface_image.png", true, true, 5097, 10190, 157534.44276470889, 157534.82072236895},
    {"small.dat", false, false, 28, 52, 29.5, 29.5},
    {"small.dat", true, true, 28, 52, 29.5, 29.5},
    {"short-row.dat", false, false, 20, 36, 11, 11},
    {"short-row.dat", true, true, 20, 36, 11, 11},
    {"grey8.png", false, false, 28, 52, 333.45098039215679, 333.45095666666663},
    {"grey8.png", true, true, 28, 52, 278.54901960784315, 278.54995616666668},
    {"grey2.png", false, false, 24, 44, 229, 228.99996666666661},
    {"grey2.png", true, true, 24, 44, 179, 179.00064516666666},
    {"rgb16.png", false, false, 14, 24, 101.47641176470587, 101.47640999999999},
    {"rgb16.png", true, true, 14, 24, 102.52358823529413, 102.52394283333334},
    {"palette.png", false, false, 21, 38, 169.91303921568627, 169.91303333333335},
    {"palette.png", true, true, 21, 38, 120.1669607843137, 120.16686666666664},
    {"rgba-interlaced.png", false, false, 177, 350, 3153.4029803921603, 3153.4030633333341},
    {"rgba-interlaced.png", true, true, 177, 350, 2971.4823529411751, 2971.4839461666666},
};

/* A coordinate as OpenSCAD's STL export writes it: a float, then 6 significant digits. */
static double as_exported(double x)
{
    char text[64];
    snprintf(text, sizeof text, "%g", (double)(float)x);
    return strtod(text, NULL);
}

static double volume(const mcsg_mesh *m, bool exported)
{
    double sum = 0;
    for (size_t t = 0; t < m->triangle_count; t++) {
        double p[3][3];
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++) {
                double x = m->vertices[3 * (size_t)m->triangles[3 * t + c] + k];
                p[c][k] = exported ? as_exported(x) : x;
            }
        sum += (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
                p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0])) / 6;
    }
    return sum;
}

static void check_closed(const char *what, const mcsg_mesh *m)
{
    mcsg_check_report r;
    mcsg_error err;
    CHECK_OK(mcsg_mesh_check(m, NULL, &r, &err), &err);
    CHECK_MSG(mcsg_check_report_is_valid(&r) && r.volume_sign == 1 && r.components == 1 &&
                  r.duplicate_vertices == 0 && r.unused_vertices == 0,
              "%s: not a closed outward mesh (valid %d, sign %d, %zu shells, %zu degenerate)",
              what, mcsg_check_report_is_valid(&r), r.volume_sign, r.components,
              r.degenerate_triangles);
}

static mcsg_status read_file(const char *file, bool center, bool invert, mcsg_mesh *m,
                             mcsg_error *err)
{
    char name[64];
    snprintf(name, sizeof name, "surface/%s", file);
    return mci_surface_read(&ctx, test_data(name), center, invert, m, err);
}

TEST(surface_known_answers_from_openscad)
{
    for (size_t i = 0; i < sizeof KNOWN / sizeof *KNOWN; i++) {
        const known *k = &KNOWN[i];
        mcsg_mesh m;
        mcsg_error err;
        double v, exported;
        CHECK_OK(read_file(k->file, k->center, k->invert, &m, &err), &err);
        CHECK_MSG(m.vertex_count == k->vertices && m.triangle_count == k->triangles,
                  "%s: %zu vertices, %zu triangles", k->file, m.vertex_count, m.triangle_count);
        v = volume(&m, false);
        exported = volume(&m, true);
        CHECK_MSG(fabs(v - k->volume) <= 1e-9 * k->volume, "%s: volume %.17g", k->file, v);
        CHECK_MSG(fabs(exported - k->openscad_volume) <= 1e-9 * k->volume,
                  "%s: volume %.17g as OpenSCAD exports it, not %.17g", k->file, exported,
                  k->openscad_volume);
        check_closed(k->file, &m);
        mcsg_mesh_free(&m, NULL);
    }
}

/* Whether the mesh has the vertex (x, y, z). */
static bool has_vertex(const mcsg_mesh *m, double x, double y, double z)
{
    for (size_t i = 0; i < m->vertex_count; i++)
        if (m->vertices[3 * i] == x && m->vertices[3 * i + 1] == y && m->vertices[3 * i + 2] == z)
            return true;
    return false;
}

static double luminance(double r, double g, double b, bool invert)
{
    double pixel = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    return 100.0 / 255 * (invert ? 1 - pixel : pixel);
}

/* Heights where OpenSCAD puts them: .dat row k at y = k; a pixel (x, y) at column x, row
 * height - 1 - y; the cell centres at the mean; the bottom at min(0, min - 1). */
TEST(surface_heights_in_place)
{
    mcsg_mesh m;
    mcsg_error err;
    CHECK_OK(read_file("small.dat", false, false, &m, &err), &err);
    CHECK(has_vertex(&m, 0, 0, 1) && has_vertex(&m, 3, 0, 4) && has_vertex(&m, 0, 1, -1.5));
    CHECK(has_vertex(&m, 2, 2, 7) && has_vertex(&m, 3, 2, 0)); /* the short row's 0 */
    CHECK(has_vertex(&m, 0.5, 0.5, (1 + 2 + -1.5 + 0.25) / 4.0));
    CHECK(has_vertex(&m, 0, 0, -2.5) && has_vertex(&m, 3, 2, -2.5)); /* the bottom */
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(read_file("small.dat", true, true, &m, &err), &err);
    CHECK(has_vertex(&m, -1.5, -1, 1) && has_vertex(&m, 1.5, 1, 0));
    CHECK(has_vertex(&m, -1, -0.5, (1 + 2 + -1.5 + 0.25) / 4.0));
    mcsg_mesh_free(&m, NULL);
    /* grey8.png, 4 x 3: its top row 0 50 100 150 at y = 2 */
    CHECK_OK(read_file("grey8.png", false, false, &m, &err), &err);
    CHECK(has_vertex(&m, 0, 2, luminance(0, 0, 0, false)));
    CHECK(has_vertex(&m, 3, 2, luminance(150, 150, 150, false)));
    CHECK(has_vertex(&m, 2, 1, luminance(255, 255, 255, false)));
    CHECK(has_vertex(&m, 0, 0, -1)); /* the bottom: black is 0 */
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(read_file("grey8.png", false, true, &m, &err), &err);
    CHECK(has_vertex(&m, 2, 1, luminance(255, 255, 255, true)));
    CHECK(has_vertex(&m, 0, 0, luminance(255, 255, 255, true) - 1));
    mcsg_mesh_free(&m, NULL);
    /* grey2.png, 2-bit levels 0 85 170 255: row 0 of the image is 0 1 2 3 1 */
    CHECK_OK(read_file("grey2.png", false, false, &m, &err), &err);
    CHECK(has_vertex(&m, 3, 1, luminance(255, 255, 255, false)) &&
          has_vertex(&m, 4, 1, luminance(85, 85, 85, false)));
    mcsg_mesh_free(&m, NULL);
    /* rgb16.png: the high bytes (0xff, 0, 0), (0, 0xff, 0), (0, 0, 0x80) */
    CHECK_OK(read_file("rgb16.png", false, false, &m, &err), &err);
    CHECK(has_vertex(&m, 0, 1, luminance(255, 0, 0, false)) &&
          has_vertex(&m, 1, 1, luminance(0, 255, 0, false)) &&
          has_vertex(&m, 2, 1, luminance(0, 0, 128, false)) &&
          has_vertex(&m, 0, 0, luminance(0x12, 0x56, 0x9a, false)));
    mcsg_mesh_free(&m, NULL);
    /* palette.png: indices 0 1 2 in the top row (red, green, blue), its tRNS ignored */
    CHECK_OK(read_file("palette.png", false, false, &m, &err), &err);
    CHECK(has_vertex(&m, 0, 2, luminance(255, 0, 0, false)) &&
          has_vertex(&m, 1, 2, luminance(0, 255, 0, false)) &&
          has_vertex(&m, 0, 1, luminance(128, 128, 128, false)));
    mcsg_mesh_free(&m, NULL);
    /* rgba-interlaced.png, 9 x 9: pixel (x, y) is (29 x, 31 y, 17 (x + y)) mod 256 */
    CHECK_OK(read_file("rgba-interlaced.png", false, false, &m, &err), &err);
    for (int y = 0; y < 9; y += 4)
        for (int x = 0; x < 9; x += 3)
            CHECK(has_vertex(&m, x, 8 - y,
                             luminance((x * 29) % 256, (y * 31) % 256, ((x + y) * 17) % 256,
                                       false)));
    mcsg_mesh_free(&m, NULL);
}

static mcsg_status read_text(const mci_ctx *c, const char *text, mcsg_mesh *m, mcsg_error *err)
{
    return mci_surface_read_memory(c, text, strlen(text), "t.dat", false, false, m, err);
}

static char logged[1024];

static void capture_log(void *user, mcsg_log_level level, const char *message)
{
    size_t n = strlen(logged);
    (void)user;
    snprintf(logged + n, sizeof logged - n, "%d %s\n", (int)level, message);
}

TEST(surface_fewer_than_two_rows_or_columns_is_empty)
{
    static const char *const texts[] = {"", "# nothing\n\n", "1 2 3 4\n", "1\n2\n3\n"};
    mcsg_options opts;
    mci_ctx logging;
    memset(&opts, 0, sizeof opts);
    opts.log = capture_log;
    mci_ctx_init(&logging, &opts);
    for (size_t i = 0; i < sizeof texts / sizeof *texts; i++) {
        mcsg_mesh m;
        mcsg_error err;
        logged[0] = 0;
        CHECK_OK(read_text(&logging, texts[i], &m, &err), &err);
        CHECK(m.vertex_count == 0 && m.triangle_count == 0 && !m.vertices && !m.triangles);
        CHECK_CONTAINS(logged, "2 t.dat: ");
        CHECK_CONTAINS(logged, "the surface is empty");
    }
    CHECK_CONTAINS(logged, "t.dat: 3 rows of 1 height: the surface is empty");
}

static void check_error(const char *text, size_t size, mcsg_status status, const char *message)
{
    mcsg_mesh m;
    mcsg_error err = {MCSG_OK, ""};
    mcsg_status st = mci_surface_read_memory(&ctx, text, size, "t.dat", false, false, &m, &err);
    CHECK_MSG(st == status, "status %d, not %d, for %s", (int)st, (int)status, message);
    CHECK_CONTAINS(err.message, message);
    CHECK(m.vertices == NULL && m.triangles == NULL && m.vertex_count == 0);
}

#define ERR(text, status, message) check_error(text, sizeof text - 1, status, message)

/* OpenSCAD warns and stops at the first token that is no number; meshcsg fails there. */
TEST(surface_errors_name_line_and_column)
{
    ERR("1 2\n# c\n3 x 4\n", MCSG_ERR_PARSE, "t.dat:3:3: 'x' is not a number");
    ERR("1 2\n  3\t4,5\n", MCSG_ERR_PARSE, "t.dat:2:5: '4,5' is not a number");
    ERR("1 2 # a comment after numbers\n3 4\n", MCSG_ERR_PARSE, "t.dat:1:5: '#' is not a number");
    ERR("1 nan\n3 4\n", MCSG_ERR_PARSE, "t.dat:1:3: 'nan' is not a number");
    ERR("1 2\n3 1e400\n", MCSG_ERR_PARSE, "t.dat:2:3: '1e400' is not a number");
    ERR("1 2\n3 -1e301\n", MCSG_ERR_LIMIT, "t.dat:2:3: height -1.0000000000000001e+301 beyond");
    ERR("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", MCSG_ERR_PARSE, "t.dat: cannot read the PNG image: ");
}

static uint32_t crc32_of(const unsigned char *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1)));
    }
    return c ^ 0xffffffffu;
}

static void put32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)(v >> 24), p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8), p[3] = (unsigned char)v;
}

/* Checked before anything the size asks for is allocated. */
TEST(surface_limits)
{
    /* A row of 5000 numbers and 4999 rows of one: a grid of 25 million points. */
    size_t n = 0;
    char *text = malloc(40000);
    unsigned char png[8 + 25 + 12];
    for (int i = 0; i < 5000; i++)
        n += (size_t)sprintf(text + n, "1 ");
    for (int i = 0; i < 4999; i++)
        n += (size_t)sprintf(text + n, "\n1");
    check_error(text, n, MCSG_ERR_LIMIT,
                "t.dat: 5000 rows of up to 5000 heights: more than 16777216 grid points");
    free(text);
    /* A PNG header claiming 5000 x 5000 pixels. */
    memcpy(png, "\x89PNG\r\n\x1a\n", 8);
    put32(png + 8, 13);
    memcpy(png + 12, "IHDR", 4);
    put32(png + 16, 5000);
    put32(png + 20, 5000);
    memcpy(png + 24, "\x08\x02\x00\x00\x00", 5);
    put32(png + 29, crc32_of(png + 12, 17));
    memcpy(png + 33, "\0\0\0\0IEND\xae\x42\x60\x82", 12);
    check_error((const char *)png, sizeof png, MCSG_ERR_LIMIT,
                "t.dat: PNG image of 5000 x 5000 pixels: more than 16777216 grid points");
}

static mcsg_status read_under(const void *what, const mcsg_options *opts, mcsg_error *err)
{
    const known *k = what;
    mci_ctx c;
    mcsg_mesh m;
    char name[64];
    mcsg_status st;
    mci_ctx_init(&c, opts);
    snprintf(name, sizeof name, "surface/%s", k->file);
    st = mci_surface_read(&c, test_data(name), k->center, k->invert, &m, err);
    if (st == MCSG_OK) {
        CHECK(m.vertex_count == k->vertices && m.triangle_count == k->triangles);
        mci_mesh_free(&c, &m);
    }
    return st;
}

TEST(surface_allocation_failures)
{
    CHECK(test_allocation_failures("mci_surface_read small.dat", read_under, &KNOWN[4], false) >
          3);
    CHECK(test_allocation_failures("mci_surface_read short-row.dat", read_under, &KNOWN[7],
                                   false) > 3);
    CHECK(test_allocation_failures("mci_surface_read palette.png", read_under, &KNOWN[14],
                                   false) > 3);
}

TEST(surface_unreadable_file)
{
    mcsg_mesh m;
    mcsg_error err = {MCSG_OK, ""};
    CHECK(read_file("no-such-file.png", false, false, &m, &err) == MCSG_ERR_IO);
    CHECK_CONTAINS(err.message, "no-such-file.png");
    CHECK(mci_surface_read(&ctx, NULL, false, false, &m, &err) == MCSG_ERR_INVALID_ARG);
}

int main(void)
{
    mci_ctx_init(&ctx, NULL);
    RUN(surface_known_answers_from_openscad);
    RUN(surface_heights_in_place);
    RUN(surface_fewer_than_two_rows_or_columns_is_empty);
    RUN(surface_errors_name_line_and_column);
    RUN(surface_limits);
    RUN(surface_allocation_failures);
    RUN(surface_unreadable_file);
    return test_summary();
}
