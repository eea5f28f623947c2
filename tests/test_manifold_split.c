/*
 * Touching parts of an output (manifold_split.c) on hand-built meshes: two tetrahedra
 * that share the edge u-v, with their wedges about it apart (the triangles alternate in
 * direction around the edge) or overlapping (they do not, as after rounding reordered
 * nearly coplanar triangles). Either way each tetrahedron must end with its own copies
 * of u and v, so that the mesh is manifold by vertex index.
 */
#include "testlib.h"
#include "base/core.h"
#include "csg/manifold_split.h"

#include <string.h>

enum { U, V, FIRST_RIM };

/* u and v on the z axis; rim points at height 1 around it, at the given angles
 * (multiples of 45 degrees, so every coordinate is exact). */
static void put_points(double *xyz, const int *degrees, int rim_count)
{
    static const double unit[8][2] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1},
                                      {-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
    memset(xyz, 0, 3 * FIRST_RIM * sizeof *xyz);
    xyz[3 * V + 2] = 2;
    for (int i = 0; i < rim_count; i++) {
        double *p = xyz + 3 * (FIRST_RIM + i);
        p[0] = unit[degrees[i] / 45][0];
        p[1] = unit[degrees[i] / 45][1];
        p[2] = 1;
    }
}

/* Two tetrahedra u v r0 r1 and u v r2 r3 (rim angles in degrees), split. */
static void split_two_tetrahedra(const int degrees[4], size_t reordered)
{
    mci_ctx ctx;
    mcsg_mesh m;
    mcsg_error err;
    mci_touching_split split;
    const uint32_t first[4] = {U, V, FIRST_RIM, FIRST_RIM + 1};
    const uint32_t second[4] = {U, V, FIRST_RIM + 2, FIRST_RIM + 3};
    mci_ctx_init(&ctx, NULL);
    if (mci_mesh_alloc(&ctx, &m, FIRST_RIM + 4, 8, &err) != MCSG_OK) {
        CHECK_MSG(false, "allocating the mesh: %s", err.message);
        return;
    }
    put_points(m.vertices, degrees, 4);
    test_put_tetrahedron(m.vertices, first, m.triangles);
    test_put_tetrahedron(m.vertices, second, m.triangles + 12);
    CHECK(test_index_manifold_defects(&m) > 0);
    CHECK(mci_split_touching(&ctx, &m, &split));
    CHECK_EQ_SIZE(split.new_vertices, 2);
    CHECK_EQ_SIZE(split.unpaired_edges, 0);
    CHECK_EQ_SIZE(split.reordered_edges, reordered);
    CHECK_EQ_SIZE(m.vertex_count, FIRST_RIM + 6);
    CHECK_EQ_SIZE(test_index_manifold_defects(&m), 0);
    for (int i = 0; i < 12; i++) /* the first tetrahedron keeps u and v */
        CHECK(m.triangles[i] < FIRST_RIM + 4);
    for (int i = 12; i < 24; i++)
        CHECK(m.triangles[i] == FIRST_RIM + 2 || m.triangles[i] == FIRST_RIM + 3 ||
              m.triangles[i] >= FIRST_RIM + 4);
    CHECK_EQ_DOUBLE(test_signed_volume(&m), 1.0); /* 1/3 + 2/3 */
    mci_mesh_free(&ctx, &m);
}

TEST(wedges_touching_along_an_edge_get_their_own_vertices)
{
    const int apart[4] = {0, 90, 135, 225};
    split_two_tetrahedra(apart, 0);
}

/* Directions around u-v: 0 and 45 degrees run v -> u, 90 and 135 run u -> v. The angle
 * pairing fails; pairing by the turn about u keeps each tetrahedron whole. */
TEST(overlapping_wedges_are_paired_so_that_copies_separate_them)
{
    const int overlapping[4] = {0, 90, 45, 135};
    split_two_tetrahedra(overlapping, 1);
}

int main(void)
{
    RUN(wedges_touching_along_an_edge_get_their_own_vertices);
    RUN(overlapping_wedges_are_paired_so_that_copies_separate_them);
    return test_summary();
}
