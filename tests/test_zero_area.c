/*
 * Zero-area triangles removed from a leaf (mesh/zero_area.c) on hand-built meshes: a
 * repeated corner goes alone; three collinear corners take a split of the neighbour
 * across the long edge, also when that neighbour is itself a half of an earlier split;
 * two back to back go together after their neighbours are split at both middle corners;
 * the copy is closed as a chain, and face_of names the input triangle of every output
 * one.
 */
#include "testlib.h"
#include "base/core.h"
#include "mesh/zero_area.h"

#include <string.h>

/* The tetrahedron (0, 0, 0), (2, 0, 0), (0, 2, 0), (0, 0, 2) with points on its edge
 * 0-1: 4 = (1, 0, 0), 5 = (0.5, 0, 0). */
static const double points[] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 0, 0, 2, 1, 0, 0, 0.5, 0, 0};

static mci_ctx ctx; /* the default allocator */

static void free_copy(mcsg_mesh *out, uint32_t *face_of)
{
    mci_mesh_free(&ctx, out);
    mci_free(&ctx, face_of);
}

/* Runs the removal and checks the copy: closed as a chain, no zero-area triangle, the
 * solid's volume positive. */
static mci_zero_area remove_from(const uint32_t *tris, size_t n, mcsg_mesh *out,
                                 uint32_t **face_of)
{
    mcsg_mesh m = {(double *)points, (uint32_t *)tris, 6, n};
    mci_zero_area res;
    mcsg_check_report r;
    mcsg_error err;
    CHECK(mci_remove_zero_area(&ctx, &m, out, face_of, &res));
    CHECK_EQ_SIZE(out->triangle_count, n - res.removed + res.split);
    CHECK_OK(mcsg_mesh_check(out, NULL, &r, &err), &err);
    CHECK_EQ_SIZE(r.degenerate_triangles, 0);
    CHECK(r.boundary_edges == 0 && r.unbalanced_edges == 0 && r.inconsistent_edges == 0);
    CHECK(r.volume_sign > 0);
    return res;
}

/* How many of the copy's triangles come from input face f. */
static size_t from_face(const uint32_t *face_of, size_t n, uint32_t f)
{
    size_t count = 0;
    for (size_t t = 0; t < n; t++)
        count += face_of[t] == f;
    return count;
}

TEST(repeated_corner_goes_alone)
{
    static const uint32_t tris[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 2, 2, 3, 1, 3, 1};
    mcsg_mesh out;
    uint32_t *face_of;
    mci_zero_area res = remove_from(tris, 6, &out, &face_of);
    CHECK(res.removed == 2 && res.split == 0);
    for (uint32_t t = 0; t < 4 && face_of; t++)
        CHECK(face_of[t] == t && memcmp(out.triangles + 3 * t, tris + 3 * t, 12) == 0);
    free_copy(&out, face_of);
}

TEST(collinear_corners_split_the_neighbour)
{
    /* Bottom (0, 2, 4) and (4, 2, 1) use 4; (0, 4, 1) closes the gap; (0, 1, 3) holds
     * the long edge the other way and is split into (0, 4, 3) and (4, 1, 3). */
    static const uint32_t tris[] = {0, 2, 4, 4, 2, 1, 0, 4, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    mcsg_mesh out;
    uint32_t *face_of;
    mci_zero_area res = remove_from(tris, 6, &out, &face_of);
    CHECK(res.removed == 1 && res.split == 1);
    if (face_of) {
        CHECK_EQ_SIZE(from_face(face_of, out.triangle_count, 2), 0);
        CHECK_EQ_SIZE(from_face(face_of, out.triangle_count, 3), 2);
    }
    free_copy(&out, face_of);
}

/* Edge 0-1 with 5 and 4 on the bottom side: (0, 5, 4) needs 0 -> 4, which only the
 * first half of (0, 1, 3) split at 4 has; listed first, it waits for that split. */
static const uint32_t cascade[] = {0, 5, 4, 0, 2, 5, 5, 2, 4, 4, 2, 1,
                                   0, 4, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

TEST(splits_cascade_along_one_edge)
{
    mcsg_mesh out;
    uint32_t *face_of;
    mci_zero_area res = remove_from(cascade, 8, &out, &face_of);
    CHECK(res.removed == 2 && res.split == 2);
    if (face_of)
        CHECK_EQ_SIZE(from_face(face_of, out.triangle_count, 5), 3);
    free_copy(&out, face_of);
}

TEST(back_to_back_go_together)
{
    /* 4 on one side of edge 0-1 and 5 on the other, each gap closed by a zero-area
     * triangle: each one's long edge is held the other way only by the other. Both go,
     * after (0, 2, 4) is split at 5 and (5, 1, 3) at 4. */
    static const uint32_t tris[] = {0, 2, 4, 4, 2, 1, 0, 4, 1, 0, 5, 3,
                                    5, 1, 3, 0, 1, 5, 0, 3, 2, 1, 2, 3};
    mcsg_mesh out;
    uint32_t *face_of;
    mci_zero_area res = remove_from(tris, 8, &out, &face_of);
    CHECK(res.removed == 2 && res.split == 2);
    if (face_of) {
        CHECK_EQ_SIZE(from_face(face_of, out.triangle_count, 0), 2);
        CHECK_EQ_SIZE(from_face(face_of, out.triangle_count, 4), 2);
        CHECK_EQ_SIZE(from_face(face_of, out.triangle_count, 2), 0);
        CHECK_EQ_SIZE(from_face(face_of, out.triangle_count, 5), 0);
    }
    free_copy(&out, face_of);
}

static mcsg_status remove_under(const void *unused, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_mesh m = {(double *)points, (uint32_t *)cascade, 6, 8}, out;
    uint32_t *face_of;
    mci_zero_area res;
    mci_ctx failing;
    (void)unused;
    mci_ctx_init(&failing, opts);
    if (!mci_remove_zero_area(&failing, &m, &out, &face_of, &res))
        return mci_fail_nomem(err, "removing zero-area triangles");
    CHECK_EQ_SIZE(out.triangle_count, 8);
    mci_mesh_free(&failing, &out);
    mci_free(&failing, face_of);
    return MCSG_OK;
}

TEST(failing_allocations_leak_nothing)
{
    CHECK(test_allocation_failures("removing zero-area triangles", remove_under, NULL, false) >=
          5);
}

int main(void)
{
    mci_ctx_init(&ctx, NULL);
    RUN(repeated_corner_goes_alone);
    RUN(collinear_corners_split_the_neighbour);
    RUN(splits_cascade_along_one_edge);
    RUN(back_to_back_go_together);
    RUN(failing_allocations_leak_nothing);
    return test_summary();
}
