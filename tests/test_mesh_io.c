/*
 * Tests of the mesh file readers and writers (src/io/): bit-exact round trips of
 * every format, the format-specific features (OFF variants, OBJ corner syntax and
 * continuation lines, STL detection and welding, PLY encodings, types and skipped
 * data), the models of tests/data/models, one test per class of malformed input (status, file name
 * and line or byte offset in the message), hostile counts, and allocation failure at
 * every allocation (NOMEM, nothing leaked).
 *
 * Every in-memory read goes through an exactly-sized heap copy of the input, so that
 * ASan reports any read past the end (the library must not rely on a terminator).
 */
#define _POSIX_C_SOURCE 200809L

#include "testlib.h"

#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------- */
/* Helpers                                                                             */

static mcsg_status read_bytes(const void *data, size_t size, mcsg_format format,
                              const char *name, const mcsg_options *opts, mcsg_mesh *out,
                              mcsg_error *err)
{
    void *copy = malloc(size ? size : 1);
    mcsg_status status;
    memcpy(copy, data, size);
    status = mcsg_mesh_read_memory(copy, size, format, name, opts, out, err);
    free(copy);
    return status;
}

static mcsg_status read_text(const char *text, mcsg_format format, const char *name,
                             mcsg_mesh *out, mcsg_error *err)
{
    return read_bytes(text, strlen(text), format, name, NULL, out, err);
}

/* Read `text` expecting failure with `status` and a message containing `where` (e.g.
 * "bad.off:7:") and `what`. */
#define CHECK_READ_FAILS(text, format, name, status, where, what)                         \
    do {                                                                                  \
        mcsg_mesh m_;                                                                     \
        mcsg_error e_ = {MCSG_OK, ""};                                                    \
        mcsg_status s_ = read_text((text), (format), (name), &m_, &e_);                   \
        CHECK_MSG(s_ == (status), "status %d (%s), expected %d", (int)s_, e_.message,     \
                  (int)(status));                                                         \
        CHECK_CONTAINS(e_.message, (where));                                              \
        CHECK_CONTAINS(e_.message, (what));                                               \
        CHECK(m_.vertices == NULL && m_.triangles == NULL && m_.vertex_count == 0);       \
        if (s_ == MCSG_OK)                                                                \
            mcsg_mesh_free(&m_, NULL);                                                    \
    } while (0)

#define CHECK_BYTES_FAIL(data, size, format, name, status, where, what)                   \
    do {                                                                                  \
        mcsg_mesh m_;                                                                     \
        mcsg_error e_ = {MCSG_OK, ""};                                                    \
        mcsg_status s_ = read_bytes((data), (size), (format), (name), NULL, &m_, &e_);    \
        CHECK_MSG(s_ == (status), "status %d (%s), expected %d", (int)s_, e_.message,     \
                  (int)(status));                                                         \
        CHECK_CONTAINS(e_.message, (where));                                              \
        CHECK_CONTAINS(e_.message, (what));                                               \
        if (s_ == MCSG_OK)                                                                \
            mcsg_mesh_free(&m_, NULL);                                                    \
    } while (0)

/* Collects log lines. */
typedef struct log_capture {
    int count;
    char last[1024];
    char all[4096];
} log_capture;

static void capture_log(void *user, mcsg_log_level level, const char *message)
{
    log_capture *log = user;
    (void)level;
    log->count++;
    snprintf(log->last, sizeof log->last, "%s", message);
    if (strlen(log->all) + strlen(message) + 2 < sizeof log->all) {
        strcat(log->all, message);
        strcat(log->all, "\n");
    }
}

/* A growable byte string for building binary test files byte by byte. */
typedef struct bytes {
    unsigned char data[4096];
    size_t size;
} bytes;

static void put_text(bytes *b, const char *text)
{
    size_t n = strlen(text);
    memcpy(b->data + b->size, text, n);
    b->size += n;
}

static void put_uint(bytes *b, uint64_t value, int size, bool big_endian)
{
    for (int i = 0; i < size; i++)
        b->data[b->size + (size_t)(big_endian ? size - 1 - i : i)] =
            (unsigned char)(value >> (8 * i));
    b->size += (size_t)size;
}

static void put_f32(bytes *b, float value, bool big_endian)
{
    uint32_t bits;
    memcpy(&bits, &value, sizeof bits);
    put_uint(b, bits, 4, big_endian);
}

static void put_f64(bytes *b, double value, bool big_endian)
{
    uint64_t bits;
    memcpy(&bits, &value, sizeof bits);
    put_uint(b, bits, 8, big_endian);
}

/* The unit cube of tests/data/io (cube.off, cube.obj, cube.ply, cube_ascii.stl). */
static const double cube_vertices[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                           {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
static const uint32_t cube_quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                          {2, 3, 7, 6}, {0, 4, 7, 3}, {1, 2, 6, 5}};

/* The cube as 12 fan triangles, in the vertex order above. */
static void check_is_cube(const mcsg_mesh *m)
{
    CHECK_EQ_SIZE(m->vertex_count, 8);
    CHECK_EQ_SIZE(m->triangle_count, 12);
    if (m->vertex_count != 8 || m->triangle_count != 12)
        return;
    for (size_t i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            CHECK_EQ_DOUBLE(m->vertices[3 * i + (size_t)k], cube_vertices[i][k]);
    for (size_t q = 0; q < 6; q++) {
        const uint32_t *t = m->triangles + 6 * q;
        const uint32_t *quad = cube_quads[q];
        CHECK(t[0] == quad[0] && t[1] == quad[1] && t[2] == quad[2]);
        CHECK(t[3] == quad[0] && t[4] == quad[2] && t[5] == quad[3]);
    }
}

/* Same geometry, whatever the vertex numbering (for welded STL): compare coordinates
 * corner by corner. */
static void check_same_triangles_by_coordinates(const mcsg_mesh *m)
{
    CHECK_EQ_SIZE(m->triangle_count, 12);
    if (m->triangle_count != 12)
        return;
    for (size_t q = 0; q < 6; q++) {
        static const int fan[6] = {0, 1, 2, 0, 2, 3};
        for (int c = 0; c < 6; c++) {
            const double *got = m->vertices + 3 * (size_t)m->triangles[6 * q + (size_t)c];
            const double *want = cube_vertices[cube_quads[q][fan[c]]];
            CHECK(got[0] == want[0] && got[1] == want[1] && got[2] == want[2]);
        }
    }
}

/* A small mesh with awkward coordinates: every kind of double a text format must keep. */
static const double awkward[] = {0.1,      1e-300,  3.4e38, 4.9406564584124654e-324,
                                 -0.0,     DBL_MAX, -DBL_MAX, 1.0 / 3,
                                 2.2250738585072009e-308, 123456789012345680.0, -1e-5, 0.0,
                                 5e-324 * 3, 1e22, 1e23, 0.30000000000000004};

static void make_awkward_mesh(mcsg_mesh *m, double *vertices, uint32_t *triangles)
{
    size_t n = sizeof awkward / sizeof awkward[0];
    for (size_t i = 0; i < 3 * 8; i++)
        vertices[i] = awkward[(i * 7) % n];
    for (uint32_t t = 0; t < 6; t++) {
        triangles[3 * t] = t;
        triangles[3 * t + 1] = (t + 1) % 8;
        triangles[3 * t + 2] = (t + 5) % 8;
    }
    m->vertices = vertices;
    m->triangles = triangles;
    m->vertex_count = 8;
    m->triangle_count = 6;
}

static const mcsg_format exact_formats[] = {MCSG_FORMAT_OFF, MCSG_FORMAT_OBJ,
                                            MCSG_FORMAT_PLY_ASCII, MCSG_FORMAT_PLY_BINARY_LE,
                                            MCSG_FORMAT_PLY_BINARY_BE};

/* ---------------------------------------------------------------------------------- */
/* Round trips                                                                         */

TEST(round_trip_exact_formats)
{
    double vertices[24];
    uint32_t triangles[18];
    mcsg_mesh mesh, back;
    mcsg_error err;
    make_awkward_mesh(&mesh, vertices, triangles);
    for (size_t f = 0; f < sizeof exact_formats / sizeof exact_formats[0]; f++) {
        void *data = NULL;
        size_t size = 0;
        CHECK_OK(mcsg_mesh_write_memory(exact_formats[f], &mesh, NULL, &data, &size, &err),
                 &err);
        for (int detect = 0; detect < 2; detect++) {
            CHECK_OK(read_bytes(data, size, detect ? MCSG_FORMAT_AUTO : exact_formats[f],
                                NULL, NULL, &back, &err),
                     &err);
            CHECK_MSG(test_same_mesh(&mesh, &back), "%s round trip (detect=%d) differs",
                      mcsg_format_name(exact_formats[f]), detect);
            mcsg_mesh_free(&back, NULL);
        }
        mcsg_free(data, NULL);
    }
}

/* Text records are formatted in blocks on several threads: a mesh spanning several waves
 * of blocks (with a short last block) must read back exactly and give the same bytes for
 * any thread count. */
TEST(text_output_same_for_any_thread_count)
{
    static const mcsg_format text_formats[] = {MCSG_FORMAT_OFF, MCSG_FORMAT_OBJ,
                                               MCSG_FORMAT_PLY_ASCII};
    enum { NV = 150001, NT = 270007 };
    static const int thread_counts[] = {1, 2, 3};
    mcsg_mesh mesh = {malloc(3 * NV * sizeof(double)), malloc(3 * NT * sizeof(uint32_t)), NV,
                      NT};
    uint64_t state = 0x9e3779b97f4a7c15u;
    mcsg_error err;
    CHECK(mesh.vertices && mesh.triangles);
    for (size_t i = 0; mesh.vertices && i < 3 * (size_t)NV; i++) {
        state = state * 6364136223846793005u + 1442695040888963407u;
        mesh.vertices[i] = ldexp((double)(state >> 11) - 0x1p52, (int)(state % 41) - 60);
    }
    for (size_t i = 0; mesh.triangles && i < 3 * (size_t)NT; i++)
        mesh.triangles[i] = (uint32_t)((i * 2654435761u) % NV);
    for (size_t f = 0; mesh.vertices && mesh.triangles && f < 3; f++) {
        void *first = NULL;
        size_t first_size = 0;
        for (size_t t = 0; t < sizeof thread_counts / sizeof thread_counts[0]; t++) {
            mcsg_options opts = {0};
            mcsg_mesh back;
            void *data = NULL;
            size_t size = 0;
            opts.threads = thread_counts[t];
            CHECK_OK(mcsg_mesh_write_memory(text_formats[f], &mesh, &opts, &data, &size, &err),
                     &err);
            if (t == 0) {
                CHECK_OK(mcsg_mesh_read_memory(data, size, text_formats[f], "big", NULL, &back,
                                               &err),
                         &err);
                CHECK_MSG(test_same_mesh(&mesh, &back), "%s: the big mesh does not read back",
                          mcsg_format_name(text_formats[f]));
                mcsg_mesh_free(&back, NULL);
                first = data;
                first_size = size;
                continue;
            }
            CHECK_MSG(size == first_size && memcmp(data, first, size) == 0,
                      "%s: %d threads write other bytes than one", mcsg_format_name(text_formats[f]),
                      thread_counts[t]);
            mcsg_free(data, NULL);
        }
        mcsg_free(first, NULL);
    }
    free(mesh.vertices);
    free(mesh.triangles);
}

TEST(round_trip_through_files)
{
    static const char *const names[] = {"rt.off", "rt.obj", "rt.ply", "RT.PLY"};
    double vertices[24];
    uint32_t triangles[18];
    mcsg_mesh mesh, back;
    mcsg_error err;
    make_awkward_mesh(&mesh, vertices, triangles);
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        const char *path = test_tmp(names[i]);
        CHECK_OK(mcsg_mesh_write(path, MCSG_FORMAT_AUTO, &mesh, NULL, &err), &err);
        CHECK_OK(mcsg_mesh_read(path, MCSG_FORMAT_AUTO, NULL, &back, &err), &err);
        CHECK_MSG(test_same_mesh(&mesh, &back), "%s differs", names[i]);
        mcsg_mesh_free(&back, NULL);
    }
}

TEST(round_trip_empty_mesh)
{
    static const mcsg_format formats[] = {
        MCSG_FORMAT_OFF,       MCSG_FORMAT_OBJ,           MCSG_FORMAT_STL_ASCII,
        MCSG_FORMAT_STL_BINARY, MCSG_FORMAT_PLY_ASCII,    MCSG_FORMAT_PLY_BINARY_LE,
        MCSG_FORMAT_PLY_BINARY_BE};
    mcsg_mesh empty = {NULL, NULL, 0, 0}, back;
    mcsg_error err;
    for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
        void *data = NULL;
        size_t size = 0;
        CHECK_OK(mcsg_mesh_write_memory(formats[f], &empty, NULL, &data, &size, &err), &err);
        CHECK(data != NULL);
        CHECK_OK(read_bytes(data, size, formats[f], "empty", NULL, &back, &err), &err);
        CHECK(back.vertex_count == 0 && back.triangle_count == 0);
        mcsg_mesh_free(&back, NULL);
        mcsg_free(data, NULL);
    }
}

/* A tetrahedron whose vertices are listed in order of first use (as STL welding
 * rebuilds them) with float-representable coordinates. */
static void make_float_tetrahedron(mcsg_mesh *m, double *v, uint32_t *t)
{
    static const double coords[12] = {0, 0, 0, 1.5, 0, 0, 0, -0.25, 0, 0, 0, 3e-8f};
    static const uint32_t tris[12] = {0, 1, 2, 0, 3, 1, 1, 3, 2, 2, 3, 0};
    memcpy(v, coords, sizeof coords);
    memcpy(t, tris, sizeof tris);
    m->vertices = v;
    m->triangles = t;
    m->vertex_count = 4;
    m->triangle_count = 4;
}

TEST(round_trip_stl)
{
    static const mcsg_format formats[] = {MCSG_FORMAT_STL_ASCII, MCSG_FORMAT_STL_BINARY};
    double v[12];
    uint32_t t[12];
    mcsg_mesh mesh, back;
    mcsg_error err;
    log_capture log = {0, "", ""};
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    opts.log = capture_log;
    opts.log_user = &log;
    make_float_tetrahedron(&mesh, v, t);
    for (size_t f = 0; f < 2; f++) {
        void *data = NULL;
        size_t size = 0;
        CHECK_OK(mcsg_mesh_write_memory(formats[f], &mesh, &opts, &data, &size, &err), &err);
        CHECK_OK(read_bytes(data, size, MCSG_FORMAT_AUTO, "t.stl", NULL, &back, &err), &err);
        CHECK_MSG(test_same_mesh(&mesh, &back), "%s round trip differs",
                  mcsg_format_name(formats[f]));
        mcsg_mesh_free(&back, NULL);
        if (f == 1)
            CHECK_EQ_SIZE(size, 84 + 50 * 4);
        mcsg_free(data, NULL);
    }
    CHECK_MSG(log.count == 0, "unexpected warning: %s", log.last);
}

/* A triangle soup of 2001 triangles (6003 distinct vertices, some with NaN, in order of
 * first use) round-trips through both STL flavours: this grows the weld table several
 * times and covers a partial last block of the binary reader. */
TEST(stl_round_trip_soup)
{
    static const mcsg_format formats[] = {MCSG_FORMAT_STL_ASCII, MCSG_FORMAT_STL_BINARY};
    size_t triangles = 2001, vertices = 3 * triangles;
    mcsg_mesh soup = {malloc(3 * vertices * sizeof(double)),
                      malloc(3 * triangles * sizeof(uint32_t)), vertices, triangles};
    mcsg_error err;
    for (size_t i = 0; i < 3 * vertices; i++)
        soup.vertices[i] = i % 997 == 5 ? NAN : (double)(float)(0.001 * (double)i - 3.0);
    for (size_t i = 0; i < 3 * triangles; i++)
        soup.triangles[i] = (uint32_t)i;
    for (size_t f = 0; f < 2; f++) {
        void *data = NULL;
        size_t size = 0;
        mcsg_mesh back;
        CHECK_OK(mcsg_mesh_write_memory(formats[f], &soup, NULL, &data, &size, &err), &err);
        CHECK_OK(read_bytes(data, size, formats[f], NULL, NULL, &back, &err), &err);
        CHECK_MSG(test_same_mesh(&soup, &back), "%s soup differs",
                  mcsg_format_name(formats[f]));
        mcsg_mesh_free(&back, NULL);
        mcsg_free(data, NULL);
    }
    free(soup.vertices);
    free(soup.triangles);
}

TEST(stl_binary_rounding_warning)
{
    double v[12];
    uint32_t t[12];
    mcsg_mesh mesh, back;
    mcsg_error err;
    void *data = NULL;
    size_t size = 0;
    log_capture log = {0, "", ""};
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    opts.log = capture_log;
    opts.log_user = &log;
    make_float_tetrahedron(&mesh, v, t);
    v[3] = 0.1;   /* not a float */
    v[11] = 1e300; /* beyond float: rounds to infinity */
    CHECK_OK(mcsg_mesh_write_memory(MCSG_FORMAT_STL_BINARY, &mesh, &opts, &data, &size, &err),
             &err);
    CHECK_EQ_SIZE(log.count, 1);
    CHECK_CONTAINS(log.last, "2 coordinates rounded to float32 for binary STL");
    CHECK_OK(read_bytes(data, size, MCSG_FORMAT_STL_BINARY, NULL, NULL, &back, &err), &err);
    CHECK_EQ_SIZE(back.vertex_count, 4);
    if (back.vertex_count == 4) {
        CHECK_EQ_DOUBLE(back.vertices[3], (double)0.1f);
        CHECK(isinf(back.vertices[11]));
    }
    mcsg_mesh_free(&back, NULL);
    mcsg_free(data, NULL);
}

/* ---------------------------------------------------------------------------------- */
/* Format features                                                                     */

TEST(read_data_files)
{
    static const char *const names[] = {"io/cube.off", "io/cube.obj", "io/cube.ply"};
    mcsg_mesh m;
    mcsg_error err;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        CHECK_OK(mcsg_mesh_read(test_data(names[i]), MCSG_FORMAT_AUTO, NULL, &m, &err), &err);
        check_is_cube(&m);
        mcsg_mesh_free(&m, NULL);
    }
    CHECK_OK(mcsg_mesh_read(test_data("io/cube_ascii.stl"), MCSG_FORMAT_AUTO, NULL, &m, &err),
             &err);
    CHECK_EQ_SIZE(m.vertex_count, 8); /* 36 corners welded into 8 vertices */
    check_same_triangles_by_coordinates(&m);
    mcsg_mesh_free(&m, NULL);
}

TEST(off_variants)
{
    static const char *const texts[] = {
        "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
        "OFF 4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
        "OFF 4 2\r\n0 0 0\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n3 0 1 2\r\n3 0 2 3\r\n",
        "# c\n\nOFF\n# counts\n4 1 5 # edges\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n",
        "NOFF\n4 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3 1 0 0\n",
        ("STCNOFF\n4 1 0\n0 0 0 0 0 1 1 1 1 1 0 0\n1 0 0 0 0 1 1 1 1 1 1 0\n"
         "1 1 0 0 0 1 1 1 1 1 1 1\n0 1 0 0 0 1 1 1 1 1 0 1\n4 0 1 2 3\n"),
        "4OFF\n4 1 0\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1.0\n4 0 1 2 3\n",
        "nOFF\n3\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n",
        "nOFF 3 4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n# trailing comment\n\n",
        "4nOFF 3\n4 1\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n4 0 1 2 3\n",
    };
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        mcsg_mesh m;
        mcsg_error err;
        CHECK_OK(read_text(texts[i], MCSG_FORMAT_AUTO, NULL, &m, &err), &err);
        CHECK_MSG(m.vertex_count == 4 && m.triangle_count == 2, "text %zu: %zu/%zu", i,
                  m.vertex_count, m.triangle_count);
        if (m.triangle_count == 2) {
            static const uint32_t want[6] = {0, 1, 2, 0, 2, 3};
            CHECK_MSG(memcmp(m.triangles, want, sizeof want) == 0, "text %zu: triangles", i);
            CHECK_EQ_DOUBLE(m.vertices[7], 1.0);
        }
        mcsg_mesh_free(&m, NULL);
    }
}

TEST(off_repeated_indices_and_nonfinite_accepted)
{
    mcsg_mesh m;
    mcsg_error err;
    CHECK_OK(read_text("OFF\n3 1 0\nnan 0 0\ninf -inf 0\n0 1e999 0\n3 0 0 1\n",
                       MCSG_FORMAT_OFF, "x.off", &m, &err),
             &err);
    CHECK(m.vertex_count == 3 && m.triangle_count == 1);
    if (m.vertex_count == 3) {
        CHECK(isnan(m.vertices[0]) && isinf(m.vertices[3]) && m.vertices[4] < 0);
        CHECK(isinf(m.vertices[7]));
    }
    mcsg_mesh_free(&m, NULL);
}

TEST(obj_features)
{
    mcsg_mesh m;
    mcsg_error err;
    CHECK_OK(read_text("# comment\r\nmtllib a.mtl\r\no thing\r\ng a b\r\ns 1\r\n"
                       "usemtl red\r\nv 0 0 0\r\nv 1 0 0 1\r\nv 1 1 0 0.5 0.5 0.5\r\n"
                       "v 0 1 0 # fourth\r\nvt 0 0\r\nvn 0 0 1\r\nvp 0.5\r\n"
                       "f 1/1 2/1 3/1 4/1\r\n"    /* quad with texture indices */
                       "f 1//1 3//1 4//1\r\n"     /* normals only */
                       "f 1/1/1 2/1/1 3/1/1\r\n"  /* both */
                       "f -4 -3 -2 \\\r\n -1\r\n" /* negative, continued */
                       "fo 1 2 3\r\n"             /* obsolete spelling */
                       "v 5 5 5\r\n"
                       "f -1 1 2 3 4\r\n", /* pentagon: 3 triangles */
                       MCSG_FORMAT_AUTO, "features.obj", &m, &err),
             &err);
    CHECK_EQ_SIZE(m.vertex_count, 5);
    CHECK_EQ_SIZE(m.triangle_count, 2 + 1 + 1 + 2 + 1 + 3);
    if (m.triangle_count == 10) {
        static const uint32_t want[30] = {0, 1, 2, 0, 2, 3, 0, 2, 3, 0, 1, 2, 0, 1, 2,
                                          0, 2, 3, 0, 1, 2, 4, 0, 1, 4, 1, 2, 4, 2, 3};
        CHECK(memcmp(m.triangles, want, sizeof want) == 0);
    }
    if (m.vertex_count == 5)
        CHECK_EQ_DOUBLE(m.vertices[12], 5.0);
    mcsg_mesh_free(&m, NULL);
}

TEST(obj_warnings)
{
    log_capture log = {0, "", ""};
    mcsg_options opts;
    mcsg_mesh m;
    mcsg_error err;
    const char *text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\np 1\nl 2 3\nfoo 1\nbar\nfoo 2\n"
                       "f 1 2 3\n";
    memset(&opts, 0, sizeof opts);
    opts.log = capture_log;
    opts.log_user = &log;
    CHECK_OK(read_bytes(text, strlen(text), MCSG_FORMAT_OBJ, "w.obj", &opts, &m, &err), &err);
    CHECK_EQ_SIZE(m.triangle_count, 1);
    CHECK_EQ_SIZE(log.count, 3); /* l/p once, foo once, bar once */
    CHECK_CONTAINS(log.all, "w.obj:4: ignoring OBJ line and point elements");
    CHECK_CONTAINS(log.all, "w.obj:7: ignoring unknown OBJ keyword 'foo'");
    CHECK_CONTAINS(log.all, "w.obj:8: ignoring unknown OBJ keyword 'bar'");
    mcsg_mesh_free(&m, NULL);
}

TEST(stl_detection_and_welding)
{
    bytes b = {{0}, 0};
    mcsg_mesh m;
    mcsg_error err;
    /* A binary STL whose header starts with "solid", two triangles sharing an edge, one
     * corner given as -0.0 to weld with +0.0. */
    static const float tri[2][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1, 0}};
    put_text(&b, "solid this is binary, really");
    b.size = 80;
    put_uint(&b, 2, 4, false);
    for (int t = 0; t < 2; t++) {
        for (int k = 0; k < 3; k++)
            put_f32(&b, 0.0f, false);
        for (int k = 0; k < 9; k++)
            put_f32(&b, (t == 1 && k == 8) ? -0.0f : tri[t][k], false);
        put_uint(&b, 0, 2, false);
    }
    CHECK_OK(read_bytes(b.data, b.size, MCSG_FORMAT_AUTO, NULL, NULL, &m, &err), &err);
    CHECK_EQ_SIZE(m.vertex_count, 4);
    CHECK_EQ_SIZE(m.triangle_count, 2);
    if (m.triangle_count == 2) {
        static const uint32_t want[6] = {0, 1, 2, 1, 3, 2};
        CHECK(memcmp(m.triangles, want, sizeof want) == 0);
    }
    mcsg_mesh_free(&m, NULL);
    /* Explicitly ASCII: the same bytes are then malformed text. */
    CHECK_BYTES_FAIL(b.data, b.size, MCSG_FORMAT_STL_ASCII, "b.stl", MCSG_ERR_PARSE, "b.stl:",
                     "expected 'facet' or 'endsolid'");
}

TEST(stl_ascii_features)
{
    mcsg_mesh m;
    mcsg_error err;
    /* Two solids, mixed case, CRLF, a NaN vertex that must not be welded. */
    CHECK_OK(read_text("  SOLID first part\r\n FACET NORMAL 0 0 1\r\n OUTER LOOP\r\n"
                       "VERTEX 0 0 0\r\n VERTEX 1 0 0\r\n Vertex nan 1 0\r\n ENDLOOP\r\n"
                       " ENDFACET\r\nENDSOLID first part\r\nsolid\nfacet normal nan nan nan\n"
                       "outer loop vertex 0 0 0 vertex nan 1 0 vertex 1 0 0 endloop endfacet\n"
                       "endsolid\n",
                       MCSG_FORMAT_AUTO, NULL, &m, &err),
             &err);
    CHECK_EQ_SIZE(m.triangle_count, 2);
    CHECK_EQ_SIZE(m.vertex_count, 4); /* 0 0 0 and 1 0 0 welded, two NaN vertices */
    if (m.triangle_count == 2) {
        static const uint32_t want[6] = {0, 1, 2, 0, 3, 1};
        CHECK(memcmp(m.triangles, want, sizeof want) == 0);
    }
    mcsg_mesh_free(&m, NULL);
}

/* A PLY body built byte by byte: 4 vertices (float or double x y z, plus an extra uchar
 * and a skipped list), a face element with a quad and a triangle (count type and index
 * type as given, plus a skipped int), and an extra element with a list. */
static void build_binary_ply(bytes *b, bool big_endian, bool doubles, const char *count_type,
                             const char *index_type, int count_size, int index_size)
{
    static const double v[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0.1}, {0, 1, -2.5}};
    char header[1024];
    snprintf(header, sizeof header,
             "ply\r\nformat %s 1.0\r\ncomment built byte by byte\r\nelement vertex 4\r\n"
             "property %s x\r\nproperty uchar red\r\nproperty %s y\r\nproperty %s z\r\n"
             "property list uint8 float32 extra\r\n"
             "element face 2\r\nproperty int flags\r\nproperty list %s %s vertex_indices\r\n"
             "element material 2\r\nproperty list ushort double values\r\nproperty char c\r\n"
             "end_header\r\n",
             big_endian ? "binary_big_endian" : "binary_little_endian",
             doubles ? "double" : "float", doubles ? "float64" : "float32",
             doubles ? "double" : "float", count_type, index_type);
    b->size = 0;
    put_text(b, header);
    for (int i = 0; i < 4; i++) {
        for (int k = 0; k < 3; k++) {
            if (doubles)
                put_f64(b, v[i][k], big_endian);
            else
                put_f32(b, (float)v[i][k], big_endian);
            if (k == 0)
                put_uint(b, 200, 1, big_endian);
        }
        put_uint(b, 2, 1, big_endian); /* the extra list: 2 floats */
        put_f32(b, 1.0f, big_endian);
        put_f32(b, 2.0f, big_endian);
    }
    put_uint(b, 0xdeadbeef, 4, big_endian);
    put_uint(b, 4, count_size, big_endian);
    for (int i = 0; i < 4; i++)
        put_uint(b, (uint64_t)i, index_size, big_endian);
    put_uint(b, 7, 4, big_endian);
    put_uint(b, 3, count_size, big_endian);
    put_uint(b, 3, index_size, big_endian);
    put_uint(b, 2, index_size, big_endian);
    put_uint(b, 1, index_size, big_endian);
    for (int i = 0; i < 2; i++) {
        put_uint(b, 1, 2, big_endian);
        put_f64(b, 0.5, big_endian);
        put_uint(b, 0x80, 1, big_endian);
    }
}

static void check_ply_quad_mesh(const mcsg_mesh *m, bool doubles)
{
    static const uint32_t want[9] = {0, 1, 2, 0, 2, 3, 3, 2, 1};
    CHECK_EQ_SIZE(m->vertex_count, 4);
    CHECK_EQ_SIZE(m->triangle_count, 3);
    if (m->vertex_count != 4 || m->triangle_count != 3)
        return;
    CHECK(memcmp(m->triangles, want, sizeof want) == 0);
    CHECK_EQ_DOUBLE(m->vertices[8], doubles ? 0.1 : (double)0.1f);
    CHECK_EQ_DOUBLE(m->vertices[11], -2.5);
    CHECK_EQ_DOUBLE(m->vertices[6], 1.0);
}

TEST(ply_binary_encodings_and_types)
{
    static const struct {
        const char *count_type, *index_type;
        int count_size, index_size;
    } lists[] = {{"uchar", "int", 1, 4},   {"uint8", "uint32", 1, 4},
                 {"ushort", "ushort", 2, 2}, {"int", "uchar", 4, 1},
                 {"short", "int16", 2, 2}};
    bytes b;
    for (int be = 0; be < 2; be++) {
        for (int doubles = 0; doubles < 2; doubles++) {
            for (size_t l = 0; l < sizeof lists / sizeof lists[0]; l++) {
                mcsg_mesh m;
                mcsg_error err;
                build_binary_ply(&b, be, doubles, lists[l].count_type, lists[l].index_type,
                                 lists[l].count_size, lists[l].index_size);
                CHECK_OK(read_bytes(b.data, b.size, MCSG_FORMAT_AUTO, NULL, NULL, &m, &err),
                         &err);
                check_ply_quad_mesh(&m, doubles);
                mcsg_mesh_free(&m, NULL);
            }
        }
    }
}

TEST(ply_ascii_types)
{
    mcsg_mesh m;
    mcsg_error err;
    CHECK_OK(read_text("ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
                       "property double y\nproperty list int short skipped\nproperty float z\n"
                       "element face 2\nproperty list ushort uint vertex_index\n"
                       "property float quality\nelement edge 1\nproperty int a\n"
                       "property int b\nend_header\n"
                       "0 0 2 7 7 0\n1 0 0 0\n1 1 1 5 0.1\n0 1 0 -2.5\n"
                       "4 0 1 2 3 0.5\n3 3 2 1 1e3\n0 1\n",
                       MCSG_FORMAT_PLY_ASCII, NULL, &m, &err),
             &err);
    check_ply_quad_mesh(&m, false);
    mcsg_mesh_free(&m, NULL);
}

/* The models of tests/data/models, with their counts (tests/data/README.md). */
TEST(project_models)
{
    static const struct {
        const char *name;
        size_t vertices, triangles;
    } models[] = {
        {"spot.obj", 2930, 5856}, {"sphere.obj", 1442, 2880}, {"cube.obj", 8, 12},
    };
    size_t count = sizeof models / sizeof models[0];
    DIR *dir = opendir(test_model(""));
    struct dirent *entry;
    CHECK(dir != NULL);
    /* Every OBJ in the folder must be listed above, so that none goes untested. */
    while (dir && (entry = readdir(dir)) != NULL) {
        size_t len = strlen(entry->d_name), i = 0;
        if (len < 4 || strcmp(entry->d_name + len - 4, ".obj") != 0)
            continue;
        while (i < count && strcmp(models[i].name, entry->d_name) != 0)
            i++;
        CHECK_MSG(i < count, "%s is not in the table of expected counts", entry->d_name);
    }
    if (dir)
        closedir(dir);
    for (size_t i = 0; i < count; i++) {
        mcsg_mesh m;
        mcsg_error err;
        CHECK_OK(mcsg_mesh_read(test_model(models[i].name), MCSG_FORMAT_AUTO, NULL, &m, &err),
                 &err);
        CHECK_MSG(m.vertex_count == models[i].vertices && m.triangle_count ==
                                                               models[i].triangles,
                  "%s: %zu vertices, %zu triangles", models[i].name, m.vertex_count,
                  m.triangle_count);
        mcsg_mesh_free(&m, NULL);
    }
}

TEST(format_names_and_detection)
{
    static const struct {
        const char *text;
        const char *name;
        size_t triangles;
    } cases[] = {
        {"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", NULL, 1},
        {"# a comment first\nCOFF\n3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n"
         "3 0 1 2\n", "noext", 1},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", NULL, 1},
        {"# exported\n\ng part\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "data.bin", 1},
        {"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 1 0\nendloop\nendfacet\nendsolid x\n", NULL, 1},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
         "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "x.stl", 1},
        {"", "empty.obj", 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        mcsg_mesh m;
        mcsg_error err;
        CHECK_OK(read_text(cases[i].text, MCSG_FORMAT_AUTO, cases[i].name, &m, &err), &err);
        CHECK_MSG(m.triangle_count == cases[i].triangles, "case %zu", i);
        mcsg_mesh_free(&m, NULL);
    }
    CHECK_READ_FAILS("hello world\n", MCSG_FORMAT_AUTO, "readme.txt", MCSG_ERR_FORMAT,
                     "readme.txt", "unknown mesh format");
    CHECK_READ_FAILS("", MCSG_FORMAT_AUTO, NULL, MCSG_ERR_FORMAT, "<memory>", "unknown");
    CHECK(mcsg_format_from_path("a/b.OFF") == MCSG_FORMAT_OFF);
    CHECK(mcsg_format_from_path("b.Obj") == MCSG_FORMAT_OBJ);
    CHECK(mcsg_format_from_path("b.stl") == MCSG_FORMAT_STL_BINARY);
    CHECK(mcsg_format_from_path("b.ply") == MCSG_FORMAT_PLY_BINARY_LE);
    CHECK(mcsg_format_from_path("b.txt") == MCSG_FORMAT_AUTO);
    CHECK(mcsg_format_from_path("dir.stl/b") == MCSG_FORMAT_AUTO);
    CHECK(mcsg_format_from_path(NULL) == MCSG_FORMAT_AUTO);
    CHECK(strcmp(mcsg_format_name(MCSG_FORMAT_STL_BINARY), "binary STL") == 0);
    CHECK(strcmp(mcsg_format_name((mcsg_format)99), "unknown format") == 0);
}

/* ---------------------------------------------------------------------------------- */
/* Malformed input: one check per class                                                */

TEST(off_errors)
{
    const mcsg_format f = MCSG_FORMAT_OFF;
    CHECK_READ_FAILS("", f, "e.off", MCSG_ERR_PARSE, "e.off:1:", "empty file");
    CHECK_READ_FAILS("OFX\n", f, "k.off", MCSG_ERR_PARSE, "k.off:1:", "'OFX'");
    CHECK_READ_FAILS("OFF BINARY\n4 4 0\n", f, "b.off", MCSG_ERR_UNSUPPORTED, "b.off:1:",
                     "binary OFF");
    CHECK_READ_FAILS("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n", f, "t.off", MCSG_ERR_PARSE,
                     "t.off:5:",
                     "unexpected end of file, expected 4 vertices, found 3");
    CHECK_READ_FAILS("OFF\n3 12 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n", f, "t.off",
                     MCSG_ERR_PARSE, "t.off:6:", "expected 12 faces, found 1");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0x 0\n1 1 0\n3 0 1 2\n", f, "n.off",
                     MCSG_ERR_PARSE, "n.off:4:", "invalid number '0x'");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0\n1 1 0\n3 0 1 2\n", f, "n.off", MCSG_ERR_PARSE,
                     "n.off:4:", "expected 3 vertex coordinates, found 2");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 9\n", f, "r.off", MCSG_ERR_PARSE,
                     "r.off:6:", "vertex index 9 out of range (3 vertices)");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 99999999999999999999999\n", f,
                     "r.off", MCSG_ERR_PARSE, "r.off:6:",
                     "vertex index 99999999999999999999999 out of range");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 -1 2\n", f, "r.off",
                     MCSG_ERR_PARSE, "r.off:6:", "vertex index -1 out of range");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n2 0 1\n", f, "c.off", MCSG_ERR_PARSE,
                     "c.off:6:", "polygon with 2 corners");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n4 0 1 2\n", f, "c.off", MCSG_ERR_PARSE,
                     "c.off:6:", "expected 4 vertex indices, found 3");
    CHECK_READ_FAILS("OFF\n3 1 0\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n3 0 1 2\n", f, "x.off",
                     MCSG_ERR_PARSE, "x.off:7:", "data after the last face");
    CHECK_READ_FAILS("OFF\n3 1 0 7\n", f, "h.off", MCSG_ERR_PARSE, "h.off:2:", "after the "
                     "counts");
    CHECK_READ_FAILS("OFF\n-3 1 0\n", f, "h.off", MCSG_ERR_PARSE, "h.off:2:", "invalid "
                     "vertex count '-3'");
    CHECK_READ_FAILS("OFF\n3\n", f, "h.off", MCSG_ERR_PARSE, "h.off:2:", "expected the face "
                     "count");
    CHECK_READ_FAILS("OFF\n5000000000 1 0\n", f, "l.off", MCSG_ERR_LIMIT, "l.off:2:",
                     "exceeds the limit");
    CHECK_READ_FAILS("4OFF\n3 1 0\n0 0 0 1\n1 0 0 2\n", f, "w.off", MCSG_ERR_UNSUPPORTED,
                     "w.off:4:", "w = 2");
    CHECK_READ_FAILS("nOFF\n4\n3 1 0\n", f, "d.off", MCSG_ERR_UNSUPPORTED, "d.off:2:",
                     "dimension 4");
}

TEST(obj_errors)
{
    const mcsg_format f = MCSG_FORMAT_OBJ;
    const char *tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    char text[256];
    snprintf(text, sizeof text, "%sf 1 2 0\n", tri);
    CHECK_READ_FAILS(text, f, "z.obj", MCSG_ERR_PARSE, "z.obj:4:",
                     "vertex index 0 is invalid");
    snprintf(text, sizeof text, "%sf 1 2 4\n", tri);
    CHECK_READ_FAILS(text, f, "r.obj", MCSG_ERR_PARSE, "r.obj:4:",
                     "vertex index 4 out of range (3 vertices)");
    snprintf(text, sizeof text, "%sf -1 -2 -4\n", tri);
    CHECK_READ_FAILS(text, f, "r.obj", MCSG_ERR_PARSE, "r.obj:4:",
                     "vertex index -4 out of range (3 vertices)");
    snprintf(text, sizeof text, "%sf 1 2 -99999999999999999999/1/1\n", tri);
    CHECK_READ_FAILS(text, f, "r.obj", MCSG_ERR_PARSE, "r.obj:4:",
                     "vertex index -99999999999999999999 out of range (3 vertices)");
    snprintf(text, sizeof text, "%sf 1 2\n", tri);
    CHECK_READ_FAILS(text, f, "c.obj", MCSG_ERR_PARSE, "c.obj:4:", "face with 2 corners");
    snprintf(text, sizeof text, "%sf 1 2 3/x\n", tri);
    CHECK_READ_FAILS(text, f, "s.obj", MCSG_ERR_PARSE, "s.obj:4:", "invalid vertex "
                     "reference '3/x'");
    snprintf(text, sizeof text, "%sf 1 2 3.5\n", tri);
    CHECK_READ_FAILS(text, f, "s.obj", MCSG_ERR_PARSE, "s.obj:4:", "'3.5'");
    CHECK_READ_FAILS("v 0 0 0\nv 1 0,5 0\n", f, "n.obj", MCSG_ERR_PARSE, "n.obj:2:",
                     "invalid number '0,5'");
    CHECK_READ_FAILS("v 0 0\n", f, "n.obj", MCSG_ERR_PARSE, "n.obj:1:",
                     "vertex with 2 values");
    CHECK_READ_FAILS("\n\nv 0 0 0 2\n", f, "w.obj", MCSG_ERR_UNSUPPORTED, "w.obj:3:", "w = 2");
    CHECK_READ_FAILS("v 0 0 0\ncstype bezier\n", f, "ff.obj", MCSG_ERR_UNSUPPORTED,
                     "ff.obj:2:",
                     "free-form geometry ('cstype')");
    /* A continued record reports its first line. */
    snprintf(text, sizeof text, "%sf 1 \\\n 2 \\\n 9\nf 1 2 3\n", tri);
    CHECK_READ_FAILS(text, f, "j.obj", MCSG_ERR_PARSE, "j.obj:4:", "vertex index 9");
    snprintf(text, sizeof text, "%sf 1 2 3\r\nf 3 2 1 0\r\n", tri);
    CHECK_READ_FAILS(text, f, "crlf.obj", MCSG_ERR_PARSE, "crlf.obj:5:", "index 0");
}

TEST(stl_errors)
{
    static unsigned char data[300];
    const char *solid = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
    char text[512];
    memset(data, 0, sizeof data);
    data[80] = 5; /* 5 triangles need 334 bytes */
    CHECK_BYTES_FAIL(data, 200, MCSG_FORMAT_AUTO, "m.stl", MCSG_ERR_PARSE, "m.stl: byte 80:",
                     "binary STL header says 5 triangles (needs 334 bytes) but the file has "
                     "200 bytes");
    CHECK_BYTES_FAIL(data, 200, MCSG_FORMAT_STL_BINARY, NULL, MCSG_ERR_PARSE, "<memory>: byte "
                     "80:", "needs 334 bytes");
    CHECK_BYTES_FAIL(data, 50, MCSG_FORMAT_STL_BINARY, "s.stl", MCSG_ERR_PARSE,
                     "s.stl: byte 0",
                     "too small for a binary STL (50 bytes");
    CHECK_BYTES_FAIL("abc", 3, MCSG_FORMAT_AUTO, "a.stl", MCSG_ERR_FORMAT, "a.stl",
                     "no 'solid'");
    snprintf(text, sizeof text, "%svertex 1 0 0\nvertex 0 1 0\nvertex 1 1 1\nendloop\n",
             solid);
    CHECK_READ_FAILS(text, MCSG_FORMAT_AUTO, "four.stl", MCSG_ERR_PARSE, "four.stl:2:",
                     "facet with more than 3 vertices");
    snprintf(text, sizeof text, "%svertex 1 0 0\nendloop\nendfacet\nendsolid\n", solid);
    CHECK_READ_FAILS(text, MCSG_FORMAT_AUTO, "two.stl", MCSG_ERR_PARSE, "two.stl:2:",
                     "facet with 2 vertices (expected 3)");
    snprintf(text, sizeof text, "%svertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n", solid);
    CHECK_READ_FAILS(text, MCSG_FORMAT_AUTO, "trunc.stl", MCSG_ERR_PARSE, "trunc.stl:8:",
                     "unexpected end of file, expected 'facet' or 'endsolid'");
    snprintf(text, sizeof text, "%svertex 1 0 0\n", solid);
    CHECK_READ_FAILS(text, MCSG_FORMAT_AUTO, "mid.stl", MCSG_ERR_PARSE, "mid.stl:5:",
                     "unexpected end of file, expected 'vertex' or 'endloop'");
    snprintf(text, sizeof text, "%svertex 1 0 zero\n", solid);
    CHECK_READ_FAILS(text, MCSG_FORMAT_AUTO, "num.stl", MCSG_ERR_PARSE, "num.stl:5:",
                     "expected a number, found 'zero'");
    CHECK_READ_FAILS("solid s\nfacet normal 0 0 1\nouter hoop\n", MCSG_FORMAT_STL_ASCII,
                     "kw.stl", MCSG_ERR_PARSE, "kw.stl:3:", "expected 'loop', found 'hoop'");
    CHECK_READ_FAILS("solid a\nendsolid a\nsolid b\nendsolid b\nsolidx\n", MCSG_FORMAT_AUTO,
                     "multi.stl", MCSG_ERR_PARSE, "multi.stl:5:", "expected 'solid'");
}

TEST(ply_errors)
{
    const mcsg_format f = MCSG_FORMAT_AUTO;
    const char *head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\n";
    const char *face = "element face 1\nproperty list uchar int vertex_indices\n";
    char text[1024];
    CHECK_READ_FAILS("plyx\n", MCSG_FORMAT_PLY_ASCII, "m.ply", MCSG_ERR_PARSE, "m.ply:1:",
                     "missing 'ply' magic");
    snprintf(text, sizeof text, "%sproperty quad w\n%send_header\n", head, face);
    CHECK_READ_FAILS(text, f, "t.ply", MCSG_ERR_PARSE, "t.ply:7:", "unknown PLY type 'quad'");
    snprintf(text, sizeof text, "%s%s", head, face);
    CHECK_READ_FAILS(text, f, "h.ply", MCSG_ERR_PARSE, "h.ply:8:", "missing end_header");
    snprintf(text, sizeof text, "%s%s0 0 0\n", head, face);
    CHECK_READ_FAILS(text, f, "h.ply", MCSG_ERR_PARSE, "h.ply:9:", "unexpected PLY header "
                     "line starting with '0'");
    snprintf(text, sizeof text, "ply\nformat ascii 2.0\n");
    CHECK_READ_FAILS(text, f, "v.ply", MCSG_ERR_UNSUPPORTED, "v.ply:2:", "version 2.0");
    snprintf(text, sizeof text, "ply\nformat binary_middle_endian 1.0\n");
    CHECK_READ_FAILS(text, f, "v.ply", MCSG_ERR_PARSE, "v.ply:2:", "unknown PLY encoding");
    snprintf(text, sizeof text, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
             "property float y\n%send_header\n", face);
    CHECK_READ_FAILS(text, f, "xyz.ply", MCSG_ERR_PARSE, "xyz.ply:3:", "no property z");
    snprintf(text, sizeof text, "%selement face 1\nproperty list uchar int other\n"
             "end_header\n", head);
    CHECK_READ_FAILS(text, f, "fl.ply", MCSG_ERR_PARSE, "fl.ply:7:", "no vertex_indices list");
    snprintf(text, sizeof text, "%send_header\n0 0 0\n1 0 0\n0 1 0\n", head);
    CHECK_READ_FAILS(text, f, "pc.ply", MCSG_ERR_PARSE, "pc.ply:7:", "no face element");
    snprintf(text, sizeof text, "%selement face 1\nproperty list float int vertex_indices\n"
             "end_header\n", head);
    CHECK_READ_FAILS(text, f, "lc.ply", MCSG_ERR_PARSE, "lc.ply:8:", "list count type");
    snprintf(text, sizeof text, "%s%send_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n", head, face);
    CHECK_READ_FAILS(text, f, "neg.ply", MCSG_ERR_PARSE, "neg.ply:13:", "vertex index -2");
    snprintf(text, sizeof text, "%s%send_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", head, face);
    CHECK_READ_FAILS(text, f, "r.ply", MCSG_ERR_PARSE, "r.ply:13:",
                     "vertex index 3 out of range (3 vertices)");
    snprintf(text, sizeof text, "%s%send_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", head, face);
    CHECK_READ_FAILS(text, f, "c.ply", MCSG_ERR_PARSE, "c.ply:13:", "face with 2 corners");
    snprintf(text, sizeof text, "%s%send_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n9\n", head,
             face);
    CHECK_READ_FAILS(text, f, "x.ply", MCSG_ERR_PARSE, "x.ply:14:", "unexpected data after "
                     "the last element");
    snprintf(text, sizeof text, "%s%send_header\n0 0 0\n1 0 0\n0 1 0\n", head, face);
    CHECK_READ_FAILS(text, f, "e.ply", MCSG_ERR_PARSE, "e.ply:12:",
                     "unexpected end of file in "
                     "element 'face'");
    snprintf(text, sizeof text, "%s%send_header\n0 0 0\n1 0 zero\n", head, face);
    CHECK_READ_FAILS(text, f, "n.ply", MCSG_ERR_PARSE, "n.ply:11:", "invalid number 'zero'");
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 99999999999999999999\n");
    CHECK_READ_FAILS(text, f, "l.ply", MCSG_ERR_LIMIT, "l.ply:3:", "exceed the limit");
    snprintf(text, sizeof text, "ply\nformat ascii 1.0\nproperty float x\n");
    CHECK_READ_FAILS(text, f, "p.ply", MCSG_ERR_PARSE, "p.ply:3:", "property before any "
                     "element");
    snprintf(text, sizeof text, "ply\nformat ascii 1.0\nvertex 3\n");
    CHECK_READ_FAILS(text, f, "u.ply", MCSG_ERR_PARSE, "u.ply:3:",
                     "unexpected PLY header line");
}

TEST(ply_binary_errors)
{
    bytes b;
    size_t full;
    build_binary_ply(&b, false, false, "uchar", "int", 1, 4);
    full = b.size;
    CHECK_BYTES_FAIL(b.data, full - 3, MCSG_FORMAT_AUTO, "cut.ply", MCSG_ERR_PARSE,
                     "cut.ply: byte", "unexpected end of file in element 'material'");
    b.data[full] = 0;
    CHECK_BYTES_FAIL(b.data, full + 1, MCSG_FORMAT_AUTO, "long.ply", MCSG_ERR_PARSE,
                     "long.ply: byte", "1 bytes of unexpected data after the last element");
    /* A face index beyond the vertex count, at its exact offset. */
    {
        const char *body = strstr((char *)b.data, "end_header\r\n") + 12;
        size_t header = (size_t)(body - (char *)b.data);
        size_t index_offset = header + 4 * (4 + 1 + 8 + 1 + 8) + 4 + 1 + 2 * 4;
        char where[64];
        b.data[index_offset] = 9;
        snprintf(where, sizeof where, "idx.ply: byte %zu:", index_offset);
        CHECK_BYTES_FAIL(b.data, full, MCSG_FORMAT_AUTO, "idx.ply", MCSG_ERR_PARSE, where,
                         "vertex index 9 out of range (4 vertices)");
    }
    /* A skipped element claiming 2^60 fixed-size records fails at once. */
    b.size = 0;
    put_text(&b, "ply\nformat binary_little_endian 1.0\nelement junk 1152921504606846976\n"
                 "property double a\nelement vertex 0\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 0\nproperty list uchar int vertex_indices\n"
                 "end_header\n");
    put_f64(&b, 1.0, false);
    CHECK_BYTES_FAIL(b.data, b.size, MCSG_FORMAT_AUTO, "huge.ply", MCSG_ERR_PARSE,
                     "huge.ply: byte", "element 'junk' needs 1152921504606846976 records");
}

/* ---------------------------------------------------------------------------------- */
/* Hostile counts and allocation failures                                              */

TEST(hostile_counts_allocate_little)
{
    static const char *const texts[] = {
        "OFF\n4000000000 4000000000 0\n0 0 0\n",
        "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
        "property float y\nproperty float z\nelement face 4000000000\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0\n",
        "ply\nformat binary_big_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
        "property float y\nproperty float z\nelement face 4000000000\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0\n",
    };
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        test_allocator a = {0, 0, false, 0, 0};
        mcsg_options opts = test_allocator_options(&a);
        mcsg_mesh m;
        mcsg_error err;
        mcsg_status st = read_bytes(texts[i], strlen(texts[i]), MCSG_FORMAT_AUTO, "h", &opts,
                                    &m, &err);
        CHECK_MSG(st == MCSG_ERR_PARSE, "case %zu: %s", i, err.message);
        CHECK_MSG(a.largest < 4096, "case %zu: allocated %zu bytes", i, a.largest);
        CHECK_EQ_SIZE(a.live, 0);
    }
}

/* What an allocation-failure run reads (path) or writes (mesh), and in which format. */
typedef struct io_case {
    const char *path;
    const mcsg_mesh *mesh;
    mcsg_format format;
} io_case;

/* Read the file and free the mesh: no mesh is returned on failure. */
static mcsg_status read_file(const void *ctx, const mcsg_options *opts, mcsg_error *err)
{
    const io_case *c = ctx;
    mcsg_mesh m;
    mcsg_status st = mcsg_mesh_read(c->path, c->format, opts, &m, err);
    if (st == MCSG_OK)
        mcsg_mesh_free(&m, opts);
    else
        CHECK(m.vertices == NULL && m.triangles == NULL);
    return st;
}

/* Write the mesh to memory and free the data: no data is returned on failure. */
static mcsg_status write_memory(const void *ctx, const mcsg_options *opts, mcsg_error *err)
{
    const io_case *c = ctx;
    void *data = NULL;
    size_t size = 0;
    mcsg_status st = mcsg_mesh_write_memory(c->format, c->mesh, opts, &data, &size, err);
    if (st == MCSG_OK)
        mcsg_free(data, opts);
    else
        CHECK(data == NULL);
    return st;
}

/* Read `path` failing the 1st, 2nd, ... allocation until the read succeeds: each run
 * must fail cleanly with NOMEM and free everything. */
static void check_allocation_failures_read(const char *path, mcsg_format format)
{
    io_case c = {path, NULL, format};
    test_allocation_failures(path, read_file, &c, true);
}

/* The same for writing `mesh` to memory. */
static void check_allocation_failures_write(const mcsg_mesh *mesh, mcsg_format format)
{
    io_case c = {NULL, mesh, format};
    test_allocation_failures(mcsg_format_name(format), write_memory, &c, true);
}

TEST(allocation_failures)
{
    static const char *const names[] = {"io/cube.off", "io/cube.obj", "io/cube_ascii.stl",
                                        "io/cube.ply"};
    static const mcsg_format formats[] = {
        MCSG_FORMAT_OFF,        MCSG_FORMAT_OBJ,       MCSG_FORMAT_STL_ASCII,
        MCSG_FORMAT_STL_BINARY, MCSG_FORMAT_PLY_ASCII, MCSG_FORMAT_PLY_BINARY_LE,
        MCSG_FORMAT_PLY_BINARY_BE};
    static const char *const written[] = {"af.off", "af.obj", "af_a.stl", "af_b.stl",
                                          "af_a.ply", "af_le.ply", "af_be.ply"};
    mcsg_mesh cube;
    mcsg_error err;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        check_allocation_failures_read(test_data(names[i]), MCSG_FORMAT_AUTO);
    CHECK_OK(mcsg_mesh_read(test_data("io/cube.off"), MCSG_FORMAT_AUTO, NULL, &cube, &err),
             &err);
    for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
        const char *path = test_tmp(written[f]);
        check_allocation_failures_write(&cube, formats[f]);
        CHECK_OK(mcsg_mesh_write(path, formats[f], &cube, NULL, &err), &err);
        check_allocation_failures_read(path, MCSG_FORMAT_AUTO);
    }
    mcsg_mesh_free(&cube, NULL);
    /* OBJ continuation lines allocate a join buffer. */
    {
        const char *path = test_tmp("af_join.obj");
        mcsg_mesh m = {NULL, NULL, 0, 0};
        FILE *file = fopen(path, "wb");
        CHECK(file != NULL);
        if (file) {
            fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 \\\n 2 \\\n 3\n", file);
            fclose(file);
            check_allocation_failures_read(path, MCSG_FORMAT_OBJ);
        }
        mcsg_mesh_free(&m, NULL);
    }
}

/* ---------------------------------------------------------------------------------- */
/* Writer argument checks                                                              */

TEST(write_errors)
{
    double v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t t[3] = {0, 1, 3};
    mcsg_mesh bad = {v, t, 3, 1};
    mcsg_mesh good = {v, t, 3, 0};
    void *data = (void *)1;
    size_t size = 7;
    mcsg_error err;
    CHECK(mcsg_mesh_write_memory(MCSG_FORMAT_OFF, &bad, NULL, &data, &size, &err) ==
          MCSG_ERR_INVALID_MESH);
    CHECK(data == NULL && size == 0);
    CHECK_CONTAINS(err.message, "triangle 0 uses vertex 3 but the mesh has 3 vertices");
    CHECK(mcsg_mesh_write_memory(MCSG_FORMAT_AUTO, &good, NULL, &data, &size, &err) ==
          MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_mesh_write(test_tmp("x.unknown"), MCSG_FORMAT_AUTO, &good, NULL, &err) ==
          MCSG_ERR_FORMAT);
    CHECK_CONTAINS(err.message, "x.unknown");
    CHECK(mcsg_mesh_write("/nonexistent-dir/x.off", MCSG_FORMAT_AUTO, &good, NULL, &err) ==
          MCSG_ERR_IO);
    CHECK(mcsg_mesh_read("/nonexistent-dir/x.off", MCSG_FORMAT_AUTO, NULL, &good, &err) ==
          MCSG_ERR_IO);
    CHECK(good.vertices == NULL && good.vertex_count == 0);
    CHECK(mcsg_mesh_read_memory(NULL, 3, MCSG_FORMAT_OFF, NULL, NULL, &good, &err) ==
          MCSG_ERR_INVALID_ARG);
    CHECK(mcsg_mesh_read_memory("OFF", 3, (mcsg_format)42, NULL, NULL, &good, &err) ==
          MCSG_ERR_INVALID_ARG);
}

int main(void)
{
    RUN(round_trip_exact_formats);
    RUN(text_output_same_for_any_thread_count);
    RUN(round_trip_through_files);
    RUN(round_trip_empty_mesh);
    RUN(round_trip_stl);
    RUN(stl_round_trip_soup);
    RUN(stl_binary_rounding_warning);
    RUN(read_data_files);
    RUN(off_variants);
    RUN(off_repeated_indices_and_nonfinite_accepted);
    RUN(obj_features);
    RUN(obj_warnings);
    RUN(stl_detection_and_welding);
    RUN(stl_ascii_features);
    RUN(ply_binary_encodings_and_types);
    RUN(ply_ascii_types);
    RUN(project_models);
    RUN(format_names_and_detection);
    RUN(off_errors);
    RUN(obj_errors);
    RUN(stl_errors);
    RUN(ply_errors);
    RUN(ply_binary_errors);
    RUN(hostile_counts_allocate_little);
    RUN(allocation_failures);
    RUN(write_errors);
    return test_summary();
}
