/*
 * Validation and the basic exact predicates: every class of mesh problem is caught and
 * counted, valid meshes (including the models of tests/data/models) pass, and the exact predicates
 * agree with GMP rationals on random and constructed-degenerate inputs.
 */
#include "testlib.h"
#include "exact/predicates.h"
#include "exact/big.h"
#include "mesh/edge_fan.h"

#include <float.h>
#include <gmp.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double cube_vertices[8 * 3] = {
    0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1,
};
static const uint32_t cube_triangles[12 * 3] = {
    0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
    1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7,
};

/* A writable copy of the unit cube with room for extra triangles and vertices. */
typedef struct test_mesh {
    double v[64 * 3];
    uint32_t t[64 * 3];
    mcsg_mesh mesh;
} test_mesh;

static void make_cube(test_mesh *m)
{
    memcpy(m->v, cube_vertices, sizeof cube_vertices);
    memcpy(m->t, cube_triangles, sizeof cube_triangles);
    m->mesh.vertices = m->v;
    m->mesh.triangles = m->t;
    m->mesh.vertex_count = 8;
    m->mesh.triangle_count = 12;
}

static mcsg_check_report check(const mcsg_mesh *mesh)
{
    mcsg_check_report r;
    mcsg_error err;
    CHECK_OK(mcsg_mesh_check(mesh, NULL, &r, &err), &err);
    return r;
}

TEST(valid_cube)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    r = check(&m.mesh);
    CHECK(mcsg_check_report_is_valid(&r));
    CHECK_EQ_DOUBLE(r.volume, 1.0);
    CHECK(!r.inverted);
    CHECK_EQ_SIZE(r.components, 1);
    CHECK_EQ_SIZE(r.boundary_edges + r.nonmanifold_edges + r.inconsistent_edges, 0);
}

TEST(removed_triangle_gives_boundary)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    m.mesh.triangle_count = 11;
    r = check(&m.mesh);
    CHECK(!mcsg_check_report_is_valid(&r));
    CHECK_EQ_SIZE(r.boundary_edges, 3);
    CHECK(r.example_boundary_edge[0] != MCSG_NO_INDEX);
}

TEST(flipped_triangle_gives_inconsistent_edges)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    m.t[3 * 5 + 1] = cube_triangles[3 * 5 + 2];
    m.t[3 * 5 + 2] = cube_triangles[3 * 5 + 1];
    r = check(&m.mesh);
    CHECK(!mcsg_check_report_is_valid(&r));
    CHECK_EQ_SIZE(r.inconsistent_edges, 3);
    CHECK_EQ_SIZE(r.boundary_edges, 0);
}

TEST(inverted_cube_is_reported_and_flippable)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    mcsg_mesh_flip(&m.mesh);
    r = check(&m.mesh);
    CHECK(mcsg_check_report_is_valid(&r));
    CHECK(r.inverted);
    CHECK_EQ_DOUBLE(r.volume, -1.0);
    mcsg_mesh_flip(&m.mesh);
    r = check(&m.mesh);
    CHECK(!r.inverted);
}

TEST(duplicate_triangle_is_nonmanifold)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    memcpy(m.t + 36, cube_triangles, 3 * sizeof(uint32_t));
    m.mesh.triangle_count = 13;
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.duplicate_triangles, 1);
    CHECK_EQ_SIZE(r.example_duplicate_triangle, 12);
    CHECK_EQ_SIZE(r.nonmanifold_edges, 3);
    CHECK_EQ_SIZE(r.unbalanced_edges, 3); /* used twice one way, once the other */
    CHECK(!mcsg_check_report_is_valid(&r));
}

/* Closed as a chain though not manifold: every edge used equally often each way. The
 * shells are paired at the shared edges, so a cube listed twice is two shells, and two
 * cubes sharing an edge stay apart. */
/* Moves the second of the triangles that use both vertices a and b to the end. */
static void move_last_on_edge(test_mesh *m, uint32_t a, uint32_t b)
{
    size_t n = m->mesh.triangle_count, found = 0;
    for (size_t t = 0; t < n; t++) {
        uint32_t *c = m->t + 3 * t, moved[3];
        bool has_a = c[0] == a || c[1] == a || c[2] == a;
        bool has_b = c[0] == b || c[1] == b || c[2] == b;
        if (!(has_a && has_b) || ++found < 2)
            continue;
        memcpy(moved, c, sizeof moved);
        memmove(c, c + 3, 3 * (n - 1 - t) * sizeof *c);
        memcpy(m->t + 3 * (n - 1), moved, sizeof moved);
        return;
    }
}

TEST(balanced_edges_pair_shells)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    memcpy(m.t + 36, cube_triangles, sizeof cube_triangles);
    m.mesh.triangle_count = 24;
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.nonmanifold_edges, 18);
    CHECK_EQ_SIZE(r.unbalanced_edges + r.boundary_edges + r.inconsistent_edges, 0);
    CHECK_EQ_SIZE(r.self_touching_edges, 0);
    CHECK_EQ_SIZE(r.components, 2);
    CHECK_EQ_DOUBLE(r.volume, 2.0);
    /* A second cube at (1, 1, 0): it shares the edge from (1,1,0) to (1,1,1). */
    make_cube(&m);
    for (int i = 0; i < 24; i++)
        m.v[24 + i] = cube_vertices[i] + (i % 3 < 2 ? 1 : 0);
    for (int i = 0; i < 36; i++)
        m.t[36 + i] = cube_triangles[i] + 8;
    m.mesh.vertex_count = 16;
    m.mesh.triangle_count = 24;
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.nonmanifold_edges, 1);
    CHECK_EQ_SIZE(r.example_nonmanifold_edge[0], 2);
    CHECK_EQ_SIZE(r.unbalanced_edges + r.self_touching_edges, 0);
    CHECK_EQ_SIZE(r.components, 2);
    CHECK_EQ_DOUBLE(r.volume, 2.0);
    /* The same with the first cube's second triangle on that edge listed last: in
     * triangle order its uses pair with the other cube's, so the two are one shell that
     * meets itself at the edge, where its triangles are paired by angle. */
    move_last_on_edge(&m, 2, 6); /* (1,1,0) and (1,1,1) */
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.unbalanced_edges + r.self_touching_edges, 0);
    CHECK_EQ_SIZE(r.components, 1);
    CHECK_EQ_DOUBLE(r.volume, 2.0);
}

TEST(degenerate_triangles)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    /* A collinear triangle (0,0,0)-(1,1,1)-(0.5,0.5,0.5) and one with a repeated corner. */
    m.v[24] = 0.5, m.v[25] = 0.5, m.v[26] = 0.5;
    m.mesh.vertex_count = 9;
    m.t[36] = 0, m.t[37] = 6, m.t[38] = 8;
    m.t[39] = 1, m.t[40] = 1, m.t[41] = 2;
    m.mesh.triangle_count = 14;
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.degenerate_triangles, 2);
    CHECK_EQ_SIZE(r.example_degenerate_triangle, 12);
    /* Nearly collinear is not degenerate: move the middle point by one ulp. */
    m.v[26] = nextafter(0.5, 1.0);
    m.mesh.triangle_count = 13;
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.degenerate_triangles, 0);
}

TEST(out_of_range_and_nonfinite)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    m.t[4] = 99;
    m.v[7] = NAN;
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.out_of_range_indices, 1);
    CHECK_EQ_SIZE(r.example_out_of_range_triangle, 1);
    CHECK_EQ_SIZE(r.nonfinite_vertices, 1);
    CHECK_EQ_SIZE(r.example_nonfinite_vertex, 2);
    CHECK(!mcsg_check_report_is_valid(&r));
    m.v[7] = INFINITY;
    r = check(&m.mesh);
    CHECK_EQ_SIZE(r.nonfinite_vertices, 1);
}

TEST(unwelded_cube_is_judged_by_geometry)
{
    /* 36 separate corners: every vertex repeated, still a closed cube. */
    static double v[36 * 3];
    static uint32_t t[36];
    mcsg_mesh mesh = {v, t, 36, 12};
    mcsg_check_report r;
    for (int i = 0; i < 36; i++) {
        memcpy(v + 3 * i, cube_vertices + 3 * cube_triangles[i], 3 * sizeof(double));
        t[i] = (uint32_t)i;
    }
    r = check(&mesh);
    CHECK(mcsg_check_report_is_valid(&r));
    CHECK_EQ_SIZE(r.duplicate_vertices, 28);
    CHECK_EQ_DOUBLE(r.volume, 1.0);
}

TEST(two_components_and_unused_vertex)
{
    test_mesh m;
    mcsg_check_report r;
    make_cube(&m);
    for (int i = 0; i < 24; i++)
        m.v[24 + i] = cube_vertices[i] + (i % 3 == 0 ? 5 : 0);
    for (int i = 0; i < 36; i++)
        m.t[36 + i] = cube_triangles[i] + 8;
    m.v[48] = 9, m.v[49] = 9, m.v[50] = 9;
    m.mesh.vertex_count = 17;
    m.mesh.triangle_count = 24;
    r = check(&m.mesh);
    CHECK(mcsg_check_report_is_valid(&r));
    CHECK_EQ_SIZE(r.components, 2);
    CHECK_EQ_SIZE(r.unused_vertices, 1);
    CHECK_EQ_DOUBLE(r.volume, 2.0);
}

TEST(empty_mesh_is_invalid)
{
    mcsg_mesh mesh = {0};
    mcsg_check_report r = check(&mesh);
    CHECK(!mcsg_check_report_is_valid(&r));
}

TEST(tiny_and_huge_cubes_have_exact_orientation)
{
    /* Volumes far below the filter's range must still get their exact sign. */
    const double scales[] = {0x1p-1000, 1e-300, 0x1p-1074 * 4, 1e300, 0x1p1000};
    for (size_t s = 0; s < sizeof scales / sizeof scales[0]; s++) {
        test_mesh m;
        mcsg_check_report r;
        make_cube(&m);
        for (int i = 0; i < 24; i++)
            m.v[i] *= scales[s];
        mcsg_mesh_flip(&m.mesh);
        r = check(&m.mesh);
        CHECK_MSG(r.inverted, "scale %g: inverted cube not detected", scales[s]);
        CHECK_EQ_SIZE(r.degenerate_triangles, 0);
    }
}

/* ---- exact predicates against GMP rationals ---- */

static int ref_orient2d(const double p[6])
{
    mpq_t q[6], l, r;
    int sign;
    for (int i = 0; i < 6; i++) {
        mpq_init(q[i]);
        mpq_set_d(q[i], p[i]);
    }
    mpq_inits(l, r, NULL);
    mpq_sub(q[0], q[0], q[4]);
    mpq_sub(q[1], q[1], q[5]);
    mpq_sub(q[2], q[2], q[4]);
    mpq_sub(q[3], q[3], q[5]);
    mpq_mul(l, q[0], q[3]);
    mpq_mul(r, q[1], q[2]);
    mpq_sub(l, l, r);
    sign = mpq_sgn(l);
    for (int i = 0; i < 6; i++)
        mpq_clear(q[i]);
    mpq_clears(l, r, NULL);
    return sign;
}

static int ref_det3(const double p[9])
{
    mpq_t q[9], t, u, sum;
    int sign;
    for (int i = 0; i < 9; i++) {
        mpq_init(q[i]);
        mpq_set_d(q[i], p[i]);
    }
    mpq_inits(t, u, sum, NULL);
    /* a . (b x c) */
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        mpq_mul(t, q[3 + j], q[6 + k]);
        mpq_mul(u, q[3 + k], q[6 + j]);
        mpq_sub(t, t, u);
        mpq_mul(t, t, q[i]);
        mpq_add(sum, sum, t);
    }
    sign = mpq_sgn(sum);
    for (int i = 0; i < 9; i++)
        mpq_clear(q[i]);
    mpq_clears(t, u, sum, NULL);
    return sign;
}

static uint64_t rng_state = 0x9e3779b97f4a7c15ULL;
static uint64_t next_random(void)
{
    return test_xorshift(&rng_state);
}

/* A random double from a mix of regimes: small integers, unit-range values, values
 * with extreme exponents, and exact zeros. */
static double random_coordinate(void)
{
    uint64_t r = next_random();
    switch (r % 5) {
    case 0: return (double)((int64_t)(r >> 40) % 7);
    case 1: return ((double)(r >> 11) / 9007199254740992.0) * 2 - 1;
    case 2: return ldexp((double)(r >> 11) / 9007199254740992.0, (int)((r >> 3) % 2000) - 1000);
    case 3: return -ldexp((double)(r >> 11) / 9007199254740992.0, (int)((r >> 5) % 600) - 300);
    default: return 0.0;
    }
}

TEST(orient2d_random_matches_rationals)
{
    for (int n = 0; n < 200000; n++) {
        double p[6];
        for (int i = 0; i < 6; i++)
            p[i] = random_coordinate();
        CHECK_MSG(mci_orient2d(p[0], p[1], p[2], p[3], p[4], p[5]) == ref_orient2d(p),
                  "orient2d mismatch at case %d", n);
    }
}

TEST(orient2d_constructed_collinear)
{
    /* c = a + t (b - a) with dyadic t and coordinates keeps c exactly on the line; moving
     * c by one ulp in either direction must flip the sign consistently with rationals. */
    for (int n = 0; n < 100000; n++) {
        int scale = (int)(next_random() % 1200) - 600;
        double ax = ldexp((double)(next_random() % 1024), scale);
        double ay = ldexp((double)(next_random() % 1024), scale);
        double dx = ldexp((double)(next_random() % 1024), scale);
        double dy = ldexp((double)(next_random() % 1024), scale);
        double t = (double)(next_random() % 64) / 16.0;
        double p[6] = {ax, ay, ax + dx, ay + dy, ax + t * dx, ay + t * dy};
        CHECK(ref_orient2d(p) == 0);
        CHECK(mci_orient2d(p[0], p[1], p[2], p[3], p[4], p[5]) == 0);
        p[5] = nextafter(p[5], INFINITY);
        CHECK(mci_orient2d(p[0], p[1], p[2], p[3], p[4], p[5]) == ref_orient2d(p));
        p[5] = nextafter(nextafter(p[5], -INFINITY), -INFINITY);
        CHECK(mci_orient2d(p[0], p[1], p[2], p[3], p[4], p[5]) == ref_orient2d(p));
    }
}

TEST(det3_random_and_coplanar_match_rationals)
{
    for (int n = 0; n < 100000; n++) {
        double p[9];
        for (int i = 0; i < 9; i++)
            p[i] = random_coordinate();
        if (n % 2) {
            /* c = a + b exactly when no rounding happens: small integers. */
            for (int i = 0; i < 6; i++)
                p[i] = (double)((int64_t)(next_random() % 2001) - 1000);
            for (int i = 0; i < 3; i++)
                p[6 + i] = p[i] + p[3 + i];
        }
        CHECK_MSG(mci_det3_sign(p, p + 3, p + 6) == ref_det3(p), "det3 mismatch at case %d: %d vs %d %a %a %a %a %a %a %a %a %a", n, mci_det3_sign(p, p + 3, p + 6), ref_det3(p), p[0],p[1],p[2],p[3],p[4],p[5],p[6],p[7],p[8]);
    }
}

/* ---- the project's models ---- */

TEST(models_validate_clean)
{
    const char *models[] = {"cube.obj", "spot.obj", "sphere.obj"};
    for (size_t i = 0; i < sizeof models / sizeof models[0]; i++) {
        mcsg_mesh mesh;
        mcsg_error err;
        mcsg_check_report r;
        if (mcsg_mesh_read(test_model(models[i]), MCSG_FORMAT_AUTO, NULL, &mesh, &err) !=
            MCSG_OK) {
            CHECK_MSG(0, "%s", err.message);
            continue;
        }
        r = check(&mesh);
        CHECK_MSG(mcsg_check_report_is_valid(&r) && !r.inverted && r.volume > 0,
                  "%s is not clean", models[i]);
        CHECK_EQ_SIZE(r.components, 1);
        /* One removed triangle and one flipped triangle are caught. */
        mesh.triangle_count--;
        r = check(&mesh);
        CHECK_EQ_SIZE(r.boundary_edges, 3);
        mesh.triangle_count++;
        mcsg_mesh_flip(&(mcsg_mesh){mesh.vertices, mesh.triangles + 3, mesh.vertex_count, 1});
        r = check(&mesh);
        CHECK_EQ_SIZE(r.inconsistent_edges, 3);
        mcsg_mesh_free(&mesh, NULL);
    }
}

/* ---- allocation failure ---- */

/* One mesh check under the test allocator: a successful check finds the cube valid. */
static mcsg_status check_cube(const void *mesh, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_check_report r;
    mcsg_status st = mcsg_mesh_check(mesh, opts, &r, err);
    if (st == MCSG_OK)
        CHECK(mcsg_check_report_is_valid(&r));
    return st;
}

/* The winding numbers on the two sides of each use of a fan whose uses lie at the given
 * whole-degree angles (distinct), taken in turn: crossing a forward use in the positive
 * turn adds one, a backward use takes one away. lo[i] <= hi[i]. */
static void fan_sides(const int *degrees, const uint8_t *forward, size_t n, int *lo, int *hi)
{
    for (size_t i = 0; i < n; i++) {
        int before = 0; /* the sector just before use i, from the one before angle 0 */
        for (size_t j = 0; j < n; j++)
            if (degrees[j] < degrees[i])
                before += forward[j] ? 1 : -1;
        lo[i] = forward[i] ? before : before - 1;
        hi[i] = lo[i] + 1;
    }
}

/* Pairing by angle keeps a region's numbers: partners have the same numbers on each
 * side (the property classification relies on when it joins their pieces), on random
 * balanced fans of up to 16 uses about the x axis, in alternating and other orders. */
TEST(fan_pairs_keep_winding_numbers)
{
    uint64_t rng = 0xfa4;
    const double u[3] = {0, 0, 0}, v[3] = {1, 0, 0};
    size_t stacked = 0;
    for (int round = 0; round < 2000; round++) {
        size_t n = 2 * (size_t)test_random_int(&rng, 1, 8);
        double corner[16][3];
        const double *third[16];
        uint8_t forward[16], mate[16], used[360] = {0};
        int degrees[16], lo[16], hi[16], got;
        mci_edge_fan fan = {u, v, third, forward, n};
        for (size_t i = 0; i < n; i++) {
            do
                degrees[i] = test_random_int(&rng, 0, 359);
            while (used[degrees[i]]);
            used[degrees[i]] = 1;
            corner[i][0] = 0.5;
            corner[i][1] = cos(degrees[i] * 3.14159265358979323846 / 180);
            corner[i][2] = sin(degrees[i] * 3.14159265358979323846 / 180);
            third[i] = corner[i];
            forward[i] = i < n / 2;
        }
        for (size_t i = n; i-- > 1;) { /* shuffle the directions */
            size_t j = (size_t)test_random_int(&rng, 0, (int)i);
            uint8_t t = forward[i];
            forward[i] = forward[j], forward[j] = t;
        }
        got = mci_pair_fan_by_angle(&fan, mate);
        CHECK(got == 1 || got == 2);
        stacked += got == 2;
        fan_sides(degrees, forward, n, lo, hi);
        for (size_t i = 0; i < n; i++) {
            CHECK(mate[i] < n && mate[mate[i]] == i && forward[mate[i]] != forward[i]);
            CHECK_MSG(lo[mate[i]] == lo[i] && hi[mate[i]] == hi[i],
                      "round %d: uses %zu and %u have numbers %d/%d and %d/%d", round, i,
                      mate[i], lo[i], hi[i], lo[mate[i]], hi[mate[i]]);
        }
    }
    CHECK(stacked > 100 && stacked < 1900); /* both kinds of fan were met */
}

/* Two uses in one half-plane facing opposite ways (a sliver folded flat) and a pair across
 * them: the folded pair is split so that directions alternate. An unbalanced fan is
 * refused. Two uses each way, each way's in one half-plane (directions cannot
 * alternate): paired by the stack, partners running opposite ways. */
TEST(fan_ties_and_refusals)
{
    const double u[3] = {0, 0, 0}, v[3] = {1, 0, 0};
    const double up[3] = {0.5, 0, 1}, down[3] = {0.5, 0, -1}, side[3] = {0.5, 1, 0};
    const double *third[4] = {up, up, down, side};
    uint8_t forward[4] = {1, 0, 1, 0}, mate[4];
    mci_edge_fan fan = {u, v, third, forward, 4};
    CHECK(mci_pair_fan_by_angle(&fan, mate) == 1);
    CHECK(mate[0] != 1 && mate[mate[0]] == 0 && mate[mate[1]] == 1);
    forward[3] = 1;
    CHECK(mci_pair_fan_by_angle(&fan, mate) == 0);
    third[3] = down;
    forward[0] = 1, forward[1] = 1, forward[2] = 0, forward[3] = 0;
    CHECK(mci_pair_fan_by_angle(&fan, mate) == 2);
    for (size_t i = 0; i < 4; i++)
        CHECK(mate[i] < 4 && mate[mate[i]] == i && forward[mate[i]] != forward[i]);
}

TEST(check_survives_every_allocation_failure)
{
    test_mesh m;
    make_cube(&m);
    CHECK(test_allocation_failures("mcsg_mesh_check", check_cube, &m.mesh, false) > 0);
}

int main(void)
{
    RUN(valid_cube);
    RUN(removed_triangle_gives_boundary);
    RUN(flipped_triangle_gives_inconsistent_edges);
    RUN(inverted_cube_is_reported_and_flippable);
    RUN(duplicate_triangle_is_nonmanifold);
    RUN(balanced_edges_pair_shells);
    RUN(degenerate_triangles);
    RUN(out_of_range_and_nonfinite);
    RUN(unwelded_cube_is_judged_by_geometry);
    RUN(two_components_and_unused_vertex);
    RUN(empty_mesh_is_invalid);
    RUN(tiny_and_huge_cubes_have_exact_orientation);
    RUN(orient2d_random_matches_rationals);
    RUN(orient2d_constructed_collinear);
    RUN(det3_random_and_coplanar_match_rationals);
    RUN(models_validate_clean);
    RUN(fan_pairs_keep_winding_numbers);
    RUN(fan_ties_and_refusals);
    RUN(check_survives_every_allocation_failure);
    return test_summary();
}
