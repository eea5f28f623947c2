/*
 * mci_find_shell_crossing (csg/shell_crossing.c), the fast exact test of whether a shell
 * crosses itself, against the plainest oracle: every pair of triangles of one shell
 * whose boxes meet, decided by mci_triangles_cross. Random meshes: spheres and cylinders
 * turned at random, with vertices pushed by random amounts (some crossing, some not),
 * some snapped to a coarse grid (coplanar triangles, collinear edges, pinched patches),
 * some with noise on every vertex (ragged patches, folds), two shells overlapping in one
 * mesh; the proofs must cover most triangles of the meshes that do not cross, so the
 * comparison tests them and not only the grid. (12,000 meshes of other seeds agreed.)
 */
#include "testlib.h"
#include "csg/frames.h"
#include "csg/self_intersect.h"
#include "csg/shell_crossing.h"
#include "exact/kernel.h"
#include "mesh/validate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct answer {
    bool crosses;
    mci_shell_crossing_stats stats;
} answer;

static answer fast_answer(const mcsg_mesh *m)
{
    mci_ctx ctx;
    mcsg_check_report report;
    mcsg_error err;
    answer a;
    uint32_t ex[2], *shell = malloc((m->triangle_count + 1) * sizeof *shell);
    uint32_t *twin = malloc((3 * m->triangle_count + 1) * sizeof *twin);
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mci_mesh_check_shells(&ctx, m, &report, shell, twin, NULL, &err), &err);
    CHECK_OK(mci_find_shell_crossing(&ctx, m, report.components > 1 ? shell : NULL, twin,
                                     &a.crosses, ex, &a.stats, &err), &err);
    if (a.crosses)
        CHECK(mci_triangles_cross(m, ex[0], ex[1]));
    free(shell);
    free(twin);
    return a;
}

static void box_of(const mcsg_mesh *m, size_t t, double box[6])
{
    for (int k = 0; k < 3; k++) {
        box[k] = INFINITY, box[k + 3] = -INFINITY;
        for (int c = 0; c < 3; c++) {
            double x = m->vertices[3 * (size_t)m->triangles[3 * t + (size_t)c] + (size_t)k];
            box[k] = fmin(box[k], x), box[k + 3] = fmax(box[k + 3], x);
        }
    }
}

/* Crossing pairs, every pair whose boxes meet tested one by one: of one shell only when
 * `one_shell` (shells by mci_mesh_check_shells), and only until the first when `first`. */
static size_t oracle_count(const mcsg_mesh *m, bool one_shell, bool first)
{
    mci_ctx ctx;
    mcsg_check_report report;
    mcsg_error err;
    size_t n = m->triangle_count, pairs = 0;
    uint32_t *shell = calloc(n + 1, sizeof *shell);
    double *box = malloc((6 * n + 1) * sizeof *box);
    mci_ctx_init(&ctx, NULL);
    if (one_shell)
        CHECK_OK(mci_mesh_check_shells(&ctx, m, &report, shell, NULL, NULL, &err), &err);
    for (size_t t = 0; t < n; t++)
        box_of(m, t, box + 6 * t);
    for (size_t t = 0; t < n && !(first && pairs); t++)
        for (size_t u = t + 1; u < n && !(first && pairs); u++) {
            bool meet = shell[t] == shell[u];
            for (int k = 0; k < 3 && meet; k++)
                meet = box[6 * t + k] <= box[6 * u + k + 3] && box[6 * u + k] <= box[6 * t + k + 3];
            pairs += meet && mci_triangles_cross(m, (uint32_t)t, (uint32_t)u);
        }
    free(shell);
    free(box);
    return pairs;
}

/* Whether two triangles of one shell cross. */
static bool oracle_crosses(const mcsg_mesh *m)
{
    return oracle_count(m, true, true) > 0;
}

static double uniform(uint64_t *rng)
{
    return (double)(test_xorshift(rng) >> 11) * 0x1p-53;
}

/* A random rotation (Gram-Schmidt of random vectors) and a shift, applied to m. */
static void turn_at_random(mcsg_mesh *m, uint64_t *rng)
{
    double a[3][3], mat[12];
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++)
            a[i][k] = uniform(rng) - 0.5;
        for (int j = 0; j < i; j++) {
            double d = a[i][0] * a[j][0] + a[i][1] * a[j][1] + a[i][2] * a[j][2];
            for (int k = 0; k < 3; k++)
                a[i][k] -= d * a[j][k];
        }
        double len = sqrt(a[i][0] * a[i][0] + a[i][1] * a[i][1] + a[i][2] * a[i][2]);
        for (int k = 0; k < 3; k++)
            a[i][k] /= len;
    }
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++)
            mat[4 * i + k] = a[i][k];
        mat[4 * i + 3] = uniform(rng);
    }
    mcsg_mesh_transform(m, mat);
}

static void push_vertices(mcsg_mesh *m, uint64_t *rng, int count, double reach)
{
    for (int i = 0; i < count; i++) {
        size_t v = (size_t)test_random_int(rng, 0, (int)m->vertex_count - 1);
        for (int k = 0; k < 3; k++)
            m->vertices[3 * v + (size_t)k] += reach * (2 * uniform(rng) - 1);
    }
}

/* Every vertex moved a little, as a scan's noise: normals turn every way, patches get
 * ragged borders and pinches, and here and there the surface folds over itself. */
static void add_noise(mcsg_mesh *m, uint64_t *rng, double reach)
{
    for (size_t i = 0; i < 3 * m->vertex_count; i++)
        m->vertices[i] += reach * (2 * uniform(rng) - 1);
}

static void snap(mcsg_mesh *m, double step)
{
    for (size_t i = 0; i < 3 * m->vertex_count; i++)
        m->vertices[i] = step * round(m->vertices[i] / step);
}

static void random_shape(uint64_t *rng, mcsg_mesh *out)
{
    mcsg_error err;
    mcsg_resolution res = {test_random_int(rng, 5, 40), 0, 0};
    if (test_random_int(rng, 0, 3) == 0)
        CHECK_OK(mcsg_make_cylinder(1 + uniform(rng), 1, uniform(rng), 0, res, NULL, out, &err),
                 &err);
    else
        CHECK_OK(mcsg_make_sphere(1, res, NULL, out, &err), &err);
    turn_at_random(out, rng);
}

/* Two meshes as one: a second shell (indices of b shifted). */
static void join(mcsg_mesh *a, const mcsg_mesh *b)
{
    size_t nv = a->vertex_count + b->vertex_count, nt = a->triangle_count + b->triangle_count;
    double *v = malloc(3 * nv * sizeof *v);
    uint32_t *t = malloc(3 * nt * sizeof *t);
    mcsg_mesh both = {v, t, nv, nt};
    mcsg_error err;
    memcpy(v, a->vertices, 3 * a->vertex_count * sizeof *v);
    memcpy(v + 3 * a->vertex_count, b->vertices, 3 * b->vertex_count * sizeof *v);
    memcpy(t, a->triangles, 3 * a->triangle_count * sizeof *t);
    for (size_t i = 0; i < 3 * b->triangle_count; i++)
        t[3 * a->triangle_count + i] = b->triangles[i] + (uint32_t)a->vertex_count;
    mcsg_mesh_free(a, NULL);
    CHECK_OK(mcsg_mesh_copy(&both, NULL, a, &err), &err);
    free(v);
    free(t);
}

/* The pairs mci_list_shell_crossings lists (every shell against every other too). */
static size_t listed_pairs(const mcsg_mesh *m)
{
    mci_ctx ctx;
    mcsg_check_report report;
    mcsg_error err;
    uint64_t *pairs = NULL;
    size_t count = 0;
    uint32_t *twin = malloc((3 * m->triangle_count + 1) * sizeof *twin);
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mci_mesh_check_shells(&ctx, m, &report, NULL, twin, NULL, &err), &err);
    CHECK_OK(mci_list_shell_crossings(&ctx, m, twin, NULL, &pairs, &count, &err), &err);
    for (size_t i = 0; i < count; i++)
        CHECK(mci_triangles_cross(m, (uint32_t)(pairs[i] >> 32), (uint32_t)pairs[i]));
    free(pairs);
    free(twin);
    return count;
}

TEST(agrees_with_every_pair_on_random_meshes)
{
    uint64_t rng = 0x5eed5ca1ab1e;
    size_t crossing = 0, apart = 0, proven = 0, triangles_apart = 0, shells = 0;
    size_t listed_crossing = 0, star_shaped = 0;
    for (int trial = 0; trial < 400; trial++) {
        mcsg_mesh m, other;
        answer a;
        bool truth;
        int kind = test_random_int(&rng, 0, 4);
        random_shape(&rng, &m);
        if (kind == 3) { /* a second shell overlapping the first */
            random_shape(&rng, &other);
            join(&m, &other);
            mcsg_mesh_free(&other, NULL);
            shells++;
        }
        push_vertices(&m, &rng, test_random_int(&rng, 0, 4),
                      kind == 0 ? 0.02 : 0.2 + uniform(&rng));
        if (kind == 2)
            snap(&m, 0.125);
        if (kind == 4)
            add_noise(&m, &rng, 0.2 * uniform(&rng) / sqrt((double)m.triangle_count));
        a = fast_answer(&m);
        truth = oracle_crosses(&m);
        if (mci_star_shaped(&m)) {
            CHECK_MSG(!truth, "trial %d (kind %d): proven star-shaped, but it crosses itself",
                      trial, kind);
            star_shaped++;
        }
        CHECK_MSG(a.crosses == truth, "trial %d (kind %d, %zu triangles): fast test says %d, "
                  "every pair says %d", trial, kind, m.triangle_count, a.crosses, truth);
        if (trial % 4 == 0) { /* the whole list, not only whether there is a pair */
            size_t listed = listed_pairs(&m), every = oracle_count(&m, false, false);
            CHECK_MSG(listed == every, "trial %d (kind %d): %zu pairs listed, %zu cross",
                      trial, kind, listed, every);
            listed_crossing += listed > 0;
        }
        crossing += truth;
        apart += !truth;
        if (!truth) {
            proven += a.stats.proven_triangles;
            triangles_apart += m.triangle_count;
        }
        mcsg_mesh_free(&m, NULL);
    }
    /* Both answers common, two shells tried, and the proofs doing most of the work. */
    CHECK(crossing >= 60 && apart >= 60);
    CHECK(shells >= 50);
    CHECK_MSG(listed_crossing >= 15, "only %zu lists compared had a pair", listed_crossing);
    CHECK_MSG(2 * proven > triangles_apart, "only %zu of %zu triangles proven", proven,
              triangles_apart);
    CHECK_MSG(star_shaped >= 40 && star_shaped < apart, "%zu of %zu meshes apart proven "
              "star-shaped", star_shaped, apart);
}

/* A bipyramid over a pentagram: its equator goes around the axis twice. Every triangle
 * faces away from the centre, yet the triangles cross: the ray from the centre meets
 * two, and the proof of star shape must say no. */
static void pentagram_bipyramid(mcsg_mesh *out)
{
    double v[21];
    uint32_t t[30];
    mcsg_mesh m = {v, t, 7, 10};
    mcsg_error err;
    for (int k = 0; k < 5; k++) {
        double angle = 2 * 3.14159265358979323846 * k / 5;
        v[3 * k] = cos(angle), v[3 * k + 1] = sin(angle), v[3 * k + 2] = 0;
    }
    v[15] = v[16] = 0, v[17] = 1;
    v[18] = v[19] = 0, v[20] = -1;
    for (uint32_t i = 0; i < 5; i++) {
        uint32_t a = 2 * i % 5, b = 2 * (i + 1) % 5;
        t[6 * i] = a, t[6 * i + 1] = b, t[6 * i + 2] = 5;
        t[6 * i + 3] = b, t[6 * i + 4] = a, t[6 * i + 5] = 6;
    }
    CHECK_OK(mcsg_mesh_copy(&m, NULL, out, &err), &err);
}

static bool faces_away_from(const mcsg_mesh *m, const double *o)
{
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *c = m->triangles + 3 * t;
        if (mci_orient3d_vertices(m->vertices + 3 * c[0], m->vertices + 3 * c[1],
                                  m->vertices + 3 * c[2], o) >= 0)
            return false;
    }
    return true;
}

/* Star shape on known meshes: convex ones pass (an octahedron whose corner lies on the
 * ray too), far from the origin as well, and a sphere
 * with every other vertex pushed out (star-shaped, not convex); a vertex pushed through
 * the other side, a mesh listed twice and a surface wound twice around its centre do
 * not. */
TEST(star_shaped_cases)
{
    mcsg_mesh m, twice;
    mcsg_error err;
    mcsg_resolution res = {24, 0, 0};
    double centre[3] = {0, 0, 0};
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &m, &err), &err);
    CHECK(mci_star_shaped(&m));
    for (size_t v = 0; v < m.vertex_count; v += 2)
        for (int k = 0; k < 3; k++)
            m.vertices[3 * v + k] *= 1.5;
    CHECK(mci_star_shaped(&m) && !oracle_crosses(&m));
    CHECK_OK(mcsg_mesh_copy(&m, NULL, &twice, &err), &err);
    join(&twice, &m);
    CHECK(!mci_star_shaped(&twice));
    mcsg_mesh_free(&twice, NULL);
    for (size_t v = 0; v < m.vertex_count; v++)
        m.vertices[3 * v] += 1e6;
    CHECK(mci_star_shaped(&m));
    m.vertices[2] = -m.vertices[2] * 3; /* the first vertex through the other side */
    CHECK(!mci_star_shaped(&m) && oracle_crosses(&m));
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(mcsg_make_cylinder(2, 1, 1, 0, res, NULL, &m, &err), &err);
    CHECK(mci_star_shaped(&m));
    mcsg_mesh_free(&m, NULL);
    {
        /* The ray from the centre of an octahedron runs through its corner (1, 0, 0),
         * and the edges from there: only its symbolic perturbation picks one triangle. */
        double v[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
        uint32_t t[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4,
                          2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
        mcsg_mesh octahedron = {v, t, 6, 8};
        CHECK(faces_away_from(&octahedron, centre) && mci_star_shaped(&octahedron));
    }
    pentagram_bipyramid(&m);
    CHECK(faces_away_from(&m, centre));
    CHECK(!mci_star_shaped(&m) && oracle_crosses(&m));
    mcsg_mesh_free(&m, NULL);
}

/* A turned mesh tested with the boxes of the mesh before the turn, grown by
 * mci_turn_margin, gives the answer of its own boxes. Meshes snapped to a coarse grid
 * (triangles coplanar and touching everywhere), turned by six-digit matrices: rounding
 * the turn makes some of them cross, by units in the last place. */
TEST(turned_meshes_tested_with_boxes_before_the_turn)
{
    uint64_t rng = 0x7e57ab1e;
    size_t crossing = 0, apart = 0;
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    for (int trial = 0; trial < 200; trial++) {
        mcsg_mesh own, turned;
        mcsg_check_report report;
        mcsg_error err;
        uint32_t ex[2], *twin;
        double a = uniform(&rng) * 6.283, b = uniform(&rng) * 6.283, margin;
        double m[12] = {cos(a), -sin(a), 0, 150, sin(a) * cos(b), cos(a) * cos(b), -sin(b),
                        -20, sin(a) * sin(b), cos(a) * sin(b), cos(b), 3};
        bool plain, boxed;
        mci_crossing_boxes boxes;
        for (int i = 0; i < 12; i++) /* six decimals, as an export might write them */
            m[i] = round(m[i] * 1e6) / 1e6;
        random_shape(&rng, &own);
        push_vertices(&own, &rng, test_random_int(&rng, 0, 2), 0.05);
        snap(&own, 0.125);
        CHECK_OK(mcsg_mesh_copy(&own, NULL, &turned, &err), &err);
        mcsg_mesh_transform(&turned, m);
        margin = mci_turn_margin(m, &own);
        CHECK(margin > 0 && margin < 1e-9);
        twin = malloc((3 * turned.triangle_count + 1) * sizeof *twin);
        CHECK_OK(mci_mesh_check_shells(&ctx, &turned, &report, NULL, twin, NULL, &err), &err);
        boxes.mesh = &own;
        boxes.margin = margin;
        CHECK_OK(mci_find_shell_crossing(&ctx, &turned, NULL, twin, &plain, ex, NULL, &err),
                 &err);
        CHECK_OK(mci_find_shell_crossing_boxed(&ctx, &turned, NULL, twin, &boxes, &boxed, ex,
                                               NULL, &err), &err);
        CHECK_MSG(plain == boxed, "trial %d: %d with the turned mesh's boxes, %d with the "
                  "boxes before the turn", trial, plain, boxed);
        crossing += plain;
        apart += !plain;
        free(twin);
        mcsg_mesh_free(&own, NULL);
        mcsg_mesh_free(&turned, NULL);
    }
    CHECK_MSG(crossing >= 20 && apart >= 20, "%zu crossing, %zu apart", crossing, apart);
}

/* Known cases: a clean sphere is proven patch by patch; a vertex pushed through its
 * opposite side, or a shell touching itself in a vertex it does not share, crosses. */
TEST(known_cases)
{
    mcsg_mesh m;
    mcsg_error err;
    mcsg_resolution res = {32, 0, 0};
    answer a;
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &m, &err), &err);
    a = fast_answer(&m);
    CHECK(!a.crosses);
    CHECK_EQ_SIZE(a.stats.proven_triangles, m.triangle_count);
    /* A vertex of the top ring through the bottom. */
    size_t top = 0;
    for (size_t v = 0; v < m.vertex_count; v++)
        if (m.vertices[3 * v + 2] > m.vertices[3 * top + 2])
            top = v;
    m.vertices[3 * top + 2] = -1.5;
    a = fast_answer(&m);
    CHECK(a.crosses);
    CHECK(oracle_crosses(&m));
    mcsg_mesh_free(&m, NULL);
}

/* The test allocates what it needs with the context's allocator: each allocation that
 * fails gives MCSG_ERR_NOMEM, and nothing is left allocated. A sphere whose patches are
 * proven, so that the proofs' room is allocated too. */
static mcsg_status crossing_run(const void *mesh, const mcsg_options *opts, mcsg_error *err)
{
    const mcsg_mesh *m = mesh;
    mci_ctx ctx;
    mcsg_check_report report;
    uint32_t ex[2], *twin = malloc(3 * m->triangle_count * sizeof *twin);
    bool crosses = true;
    mcsg_status st;
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mci_mesh_check_shells(&ctx, m, &report, NULL, twin, NULL, err), err);
    mci_ctx_init(&ctx, opts);
    st = mci_find_shell_crossing(&ctx, m, NULL, twin, &crosses, ex, NULL, err);
    CHECK(st != MCSG_OK || !crosses);
    free(twin);
    return st;
}

TEST(allocation_failures)
{
    mcsg_mesh m;
    mcsg_error err;
    mcsg_resolution res = {12, 0, 0};
    CHECK_OK(mcsg_make_sphere(1, res, NULL, &m, &err), &err);
    CHECK(test_allocation_failures("shell crossing", crossing_run, &m, false) > 0);
    mcsg_mesh_free(&m, NULL);
}

int main(void)
{
    RUN(agrees_with_every_pair_on_random_meshes);
    RUN(turned_meshes_tested_with_boxes_before_the_turn);
    RUN(star_shaped_cases);
    RUN(known_cases);
    RUN(allocation_failures);
    return test_summary();
}
