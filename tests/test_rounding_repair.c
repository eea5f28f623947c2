/*
 * What rounding to doubles breaks, mended on hand-built meshes:
 *   - a flat triangle (three collinear corners) and a thin one folded onto its
 *     neighbour (rounding_repair.c: the neighbour is split at the middle corner), and two
 *     flat triangles back to back (zipped);
 *   - two parts touching along an edge that the exact result keeps apart
 *     (separate_copies.c: vertex copies moved apart by one unit in the last place);
 *   - a sliver thinner than a grid's spacing, collapsed by snapping (snap_round.c).
 */
#include "testlib.h"
#include "base/core.h"
#include "csg/manifold_split.h"
#include "csg/output_check.h"
#include "csg/rounding_repair.h"
#include "csg/separate_copies.h"
#include "csg/snap_round.h"
#include "exact/predicates.h"

#include <math.h>
#include <string.h>

/* A tetrahedron a b c d (faces outward) whose face (a, b, c) is split at m into
 * (a, m, c) and (m, b, c), closed by the triangle (m, a, b) against face (b, a, d). With
 * m on the segment a-b that triangle is flat; with m just off it, inside face (b, a, d),
 * it is folded onto that face. */
enum { A, B, C, D, M, CORNERS };
static const uint32_t dented_tetrahedron[] = {A, M, C, M, B, C, B, D, C,
                                              A, C, D, B, A, D, M, A, B};
enum { DENTED_TRIANGLES = 6 };

static void put_dented_tetrahedron(double *xyz, double m_y)
{
    const double corners[CORNERS][3] = {{1, 0, 0}, {3, 0, 0}, {2, 1, 2}, {2, 2, 0}, {2, 0, 0}};
    memcpy(xyz, corners, sizeof corners);
    xyz[3 * M + 1] = m_y;
}

static size_t degenerate_triangles(const double *xyz, const uint32_t *tris, size_t n)
{
    size_t count = 0;
    for (size_t t = 0; t < n; t++)
        count += mci_triangle_is_degenerate(xyz + 3 * tris[3 * t], xyz + 3 * tris[3 * t + 1],
                                            xyz + 3 * tris[3 * t + 2]);
    return count;
}

/* Repairs the dented tetrahedron with m at height m_y; the result must be closed, with
 * no flat triangle, and hold the tetrahedron's volume (the dent is 2^-50 deep). */
static void repair_dent(double m_y, size_t split, size_t turned)
{
    mci_ctx ctx;
    double xyz[3 * CORNERS];
    uint32_t tris[3 * DENTED_TRIANGLES];
    mcsg_mesh m = {.vertices = xyz, .vertex_count = CORNERS, .triangles = tris,
                   .triangle_count = DENTED_TRIANGLES};
    mci_flat_repair r;
    mci_ctx_init(&ctx, NULL);
    put_dented_tetrahedron(xyz, m_y);
    memcpy(tris, dented_tetrahedron, sizeof tris);
    CHECK_EQ_SIZE(degenerate_triangles(xyz, tris, DENTED_TRIANGLES), m_y == 0);
    CHECK(mci_split_flat_triangles(&ctx, xyz, tris, NULL, DENTED_TRIANGLES, NULL, &r));
    CHECK_EQ_SIZE(r.split, split);
    CHECK_EQ_SIZE(r.turned, turned);
    CHECK_EQ_SIZE(r.remaining, 0);
    CHECK_EQ_SIZE(degenerate_triangles(xyz, tris, DENTED_TRIANGLES), 0);
    CHECK_EQ_SIZE(test_index_manifold_defects(&m), 0);
    CHECK_MSG(fabs(test_signed_volume(&m) - 4.0 / 3) < 1e-12, "volume %.17g",
              test_signed_volume(&m));
    /* The neighbour (b, a, d) was split at m: both halves are there. */
    for (int half = 0; half < 2; half++) {
        const uint32_t want[2][3] = {{B, M, D}, {M, A, D}};
        bool found = false;
        for (int t = 0; t < DENTED_TRIANGLES; t++)
            for (int k = 0; k < 3; k++)
                found |= tris[3 * t] == want[half][k] &&
                         tris[3 * t + 1] == want[half][(k + 1) % 3] &&
                         tris[3 * t + 2] == want[half][(k + 2) % 3];
        CHECK_MSG(found, "half %d of the split neighbour", half);
    }
}

TEST(flat_triangle_is_removed_by_splitting_its_neighbour)
{
    repair_dent(0, 1, 0);
}

TEST(folded_triangle_is_removed_by_splitting_its_neighbour)
{
    repair_dent(0x1p-50, 0, 1);
}

/* The tetrahedron's edge a-b opened into a sliver of zero width: face (a, b, c) split at
 * m, face (b, a, d) at x, both on segment a-b, closed by the flat triangles (b, m, a) and
 * (a, x, b) back to back. Neither flat triangle's neighbour across a-b can be split (it
 * is the other); the pair goes, and the sides are zipped by splitting (a, m, c) at x and
 * (b, x, d) at m. */
TEST(back_to_back_flat_triangles_are_zipped)
{
    enum { ZA, ZB, ZC, ZD, ZM, ZX, ZIP_POINTS };
    const double corners[ZIP_POINTS][3] = {{1, 0, 0}, {3, 0, 0}, {2, 1, 2},
                                           {2, 2, 0}, {2, 0, 0}, {1.5, 0, 0}};
    uint32_t tris[] = {ZA, ZM, ZC, ZM, ZB, ZC, ZB, ZX, ZD, ZX, ZA, ZD,
                       ZB, ZD, ZC, ZA, ZC, ZD, ZB, ZM, ZA, ZA, ZX, ZB};
    double xyz[3 * ZIP_POINTS];
    mcsg_mesh m = {.vertices = xyz, .vertex_count = ZIP_POINTS, .triangles = tris,
                   .triangle_count = 8};
    mci_ctx ctx;
    mci_flat_repair r;
    mci_ctx_init(&ctx, NULL);
    memcpy(xyz, corners, sizeof corners);
    CHECK_EQ_SIZE(test_index_manifold_defects(&m), 0);
    CHECK_EQ_SIZE(degenerate_triangles(xyz, tris, 8), 2);
    CHECK(mci_split_flat_triangles(&ctx, xyz, tris, NULL, 8, NULL, &r));
    CHECK_EQ_SIZE(r.split, 2);
    CHECK_EQ_SIZE(r.remaining, 0);
    CHECK_EQ_SIZE(degenerate_triangles(xyz, tris, 8), 0);
    CHECK_EQ_SIZE(test_index_manifold_defects(&m), 0);
    CHECK_MSG(fabs(test_signed_volume(&m) - 4.0 / 3) < 1e-12, "volume %.17g",
              test_signed_volume(&m));
}

TEST(opposite_twins_cancel)
{
    mci_ctx ctx;
    uint32_t tris[] = {0, 1, 2, 3, 4, 5, 2, 1, 0, 1, 0, 2, 0, 2, 1};
    uint32_t source[] = {10, 11, 12, 13, 14};
    size_t n = 5, cancelled = 0;
    mci_ctx_init(&ctx, NULL);
    CHECK(mci_cancel_opposite_triangles(&ctx, tris, source, &n, &cancelled));
    /* (0 1 2) cancels with one of its three reversals; the other two and (3 4 5) stay. */
    CHECK_EQ_SIZE(cancelled, 2);
    CHECK_EQ_SIZE(n, 3);
    CHECK(tris[0] == 3 && tris[1] == 4 && tris[2] == 5 && source[0] == 11);
}

/* Two tetrahedra sharing the edge u-v, wedges apart around it (as in
 * test_manifold_split.c, away from the origin so that a step of one unit in the last
 * place is a normal double). */
enum { U, V, R0, R1, R2, R3, TWO_TETRA_POINTS };

static bool within_one_unit(const double *moved, const double *was)
{
    for (int k = 0; k < 3; k++)
        if (moved[k] != was[k] && moved[k] != nextafter(was[k], INFINITY) &&
            moved[k] != nextafter(was[k], -INFINITY))
            return false;
    return true;
}

/* The split two tetrahedra, separated with the exact result touching along u-v
 * (`touching`) or not. */
static void separate_two_tetrahedra(bool touching)
{
    static const double points[TWO_TETRA_POINTS][3] = {
        {1, 1, 1}, {1, 1, 3}, {2, 1, 2}, {1, 2, 2}, {0, 2, 2}, {0, 0, 2}};
    const uint32_t first[4] = {U, V, R0, R1}, second[4] = {U, V, R2, R3};
    const double touching_edge[6] = {1, 1, 1, 1, 1, 3};
    mci_exact_result exact = {NULL, 0, NULL, NULL, touching_edge, touching ? 1 : 0};
    mci_ctx ctx;
    mcsg_mesh m;
    mcsg_error err;
    mci_touching_split split;
    mci_copy_separation sep;
    uint64_t *edges = NULL;
    uint32_t canon[TWO_TETRA_POINTS + 2];
    size_t left = 99, crossings = 99;
    mci_ctx_init(&ctx, NULL);
    if (mci_mesh_alloc(&ctx, &m, TWO_TETRA_POINTS, 8, &err) != MCSG_OK) {
        CHECK_MSG(false, "allocating the mesh: %s", err.message);
        return;
    }
    memcpy(m.vertices, points, sizeof points);
    test_put_tetrahedron(m.vertices, first, m.triangles);
    test_put_tetrahedron(m.vertices, second, m.triangles + 12);
    CHECK(mci_split_touching(&ctx, &m, &split));
    CHECK_EQ_SIZE(m.vertex_count, TWO_TETRA_POINTS + 2);
    CHECK(mci_separate_welded_copies(&ctx, &m, &exact, &sep));
    CHECK_EQ_SIZE(sep.edges, touching ? 0 : 1);
    CHECK_EQ_SIZE(sep.moved, touching ? 0 : 2); /* the second tetrahedron's u and v */
    CHECK(mci_welded_overfull_edges(&ctx, &m, &exact, canon, &edges, &left));
    CHECK_EQ_SIZE(left, 0);
    CHECK_OK(mci_count_crossings(&ctx, &m, &crossings, &err), &err);
    CHECK_EQ_SIZE(crossings, 0);
    CHECK_EQ_SIZE(test_index_manifold_defects(&m), 0);
    for (size_t v = 0; v < m.vertex_count; v++)
        CHECK_MSG(within_one_unit(m.vertices + 3 * v, points[v < TWO_TETRA_POINTS ? v : v - 6]),
                  "vertex %zu moved too far", v);
    CHECK_MSG(fabs(test_signed_volume(&m) - 1.0) < 1e-14, "volume %.17g",
              test_signed_volume(&m));
    mci_free(&ctx, edges);
    mci_mesh_free(&ctx, &m);
}

TEST(copies_that_rounding_made_touch_are_moved_apart)
{
    separate_two_tetrahedra(false);
}

TEST(copies_where_the_exact_result_touches_stay)
{
    separate_two_tetrahedra(true);
}

/* The separation under failing allocations: nothing leaks, and a failure is reported. */
static mcsg_status separate_under(const void *unused, const mcsg_options *opts, mcsg_error *err)
{
    static const double points[TWO_TETRA_POINTS][3] = {
        {1, 1, 1}, {1, 1, 3}, {2, 1, 2}, {1, 2, 2}, {0, 2, 2}, {0, 0, 2}};
    const uint32_t first[4] = {U, V, R0, R1}, second[4] = {U, V, R2, R3};
    mci_exact_result exact = {NULL, 0, NULL, NULL, NULL, 0};
    mci_ctx ctx;
    mcsg_mesh m;
    mci_touching_split split;
    mci_copy_separation sep;
    mcsg_status st;
    (void)unused;
    mci_ctx_init(&ctx, opts);
    st = mci_mesh_alloc(&ctx, &m, TWO_TETRA_POINTS, 8, err);
    if (st != MCSG_OK)
        return st;
    memcpy(m.vertices, points, sizeof points);
    test_put_tetrahedron(m.vertices, first, m.triangles);
    test_put_tetrahedron(m.vertices, second, m.triangles + 12);
    if (!mci_split_touching(&ctx, &m, &split) || !mci_separate_welded_copies(&ctx, &m, &exact, &sep))
        st = mci_fail_nomem(err, "separating copies");
    else
        CHECK_EQ_SIZE(sep.moved, 2);
    mci_mesh_free(&ctx, &m);
    return st;
}

/* The result's check counts as mcsg_mesh_check does: an edge of more than two triangles
 * used more often one way is non-manifold (never an allowed touch), and only an edge of
 * two triangles facing the same way is misoriented. Here a tetrahedron with one face
 * listed again: its three edges have three uses, two one way. */
TEST(output_check_counts_like_the_mesh_check)
{
    static const double points[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const uint32_t corners[4] = {0, 1, 2, 3};
    mci_exact_result exact = {NULL, 0, NULL, NULL, NULL, 0};
    mcsg_output_check check;
    mcsg_check_report report;
    mcsg_mesh m;
    mcsg_error err;
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mci_mesh_alloc(&ctx, &m, 4, 5, &err), &err);
    memcpy(m.vertices, points, sizeof points);
    test_put_tetrahedron(m.vertices, corners, m.triangles);
    memcpy(m.triangles + 12, m.triangles, 3 * sizeof *m.triangles);
    CHECK_OK(mci_check_output(&ctx, &m, &exact, &check, &err), &err);
    CHECK_OK(mcsg_mesh_check(&m, NULL, &report, &err), &err);
    CHECK_EQ_SIZE(check.welded_nonmanifold_edges + check.touching_edges, report.nonmanifold_edges);
    CHECK_EQ_SIZE(check.misoriented_edges, report.inconsistent_edges);
    CHECK(check.welded_nonmanifold_edges == 3 && check.touching_edges == 0 &&
          check.index_nonmanifold_edges == 3 && mcsg_output_check_failed(&check));
    mci_mesh_free(&ctx, &m);
}

TEST(separation_under_failing_allocations_leaks_nothing)
{
    CHECK(test_allocation_failures("separating copies", separate_under, NULL, false) > 10);
}

/* A unit cube and, beside it, a tetrahedron whose fourth corner lies a few units in the
 * last place off its base's corner c: snapped to a grid of 2^-40, the corner joins c, two
 * faces get a repeated corner and the other two are the base both ways round. Only the
 * cube is left, its triangles named by face_of. */
TEST(sliver_below_the_grid_collapses)
{
    double xyz[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1,
                    3, 0, 0, 4, 0, 0, 3, 1, 0, 3, 1, 0};
    uint32_t tris[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                       1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7,
                       8, 10, 9, 8, 9, 11, 9, 10, 11, 10, 8, 11};
    mcsg_mesh in = {xyz, tris, 12, 16}, out = {0};
    uint32_t *face_of = NULL;
    mcsg_error err;
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    xyz[3 * 11 + 2] = ldexp(1, -50); /* d = c + (0, 0, 2^-50) */
    CHECK(mci_snap_exponent(&in, 40) == 3 - 40);
    CHECK(mci_snap_to_grid(&ctx, &in, -37, &out, &face_of, &err) == MCSG_OK);
    CHECK(out.triangle_count == 12 && out.vertex_count == 8);
    for (size_t t = 0; t < out.triangle_count; t++)
        CHECK(face_of[t] == t);
    CHECK(fabs(test_signed_volume(&out) - 1) < 1e-12);
    mci_mesh_free(&ctx, &out);
    mci_free(&ctx, face_of);
    /* On a grid finer than the sliver, nothing changes. */
    CHECK(mci_snap_to_grid(&ctx, &in, -60, &out, &face_of, &err) == MCSG_OK);
    CHECK(out.triangle_count == 16 && out.vertex_count == 12);
    mci_mesh_free(&ctx, &out);
    mci_free(&ctx, face_of);
}

int main(void)
{
    RUN(flat_triangle_is_removed_by_splitting_its_neighbour);
    RUN(folded_triangle_is_removed_by_splitting_its_neighbour);
    RUN(back_to_back_flat_triangles_are_zipped);
    RUN(opposite_twins_cancel);
    RUN(copies_that_rounding_made_touch_are_moved_apart);
    RUN(copies_where_the_exact_result_touches_stay);
    RUN(output_check_counts_like_the_mesh_check);
    RUN(sliver_below_the_grid_collapses);
    RUN(separation_under_failing_allocations_leaks_nothing);
    return test_summary();
}
