/*
 * Shells that rounding left flat or inside out (void_shells.c), on hand-built meshes:
 * an inside-out tetrahedron apart from a cube goes, the same inside the cube's box stays
 * (it could be a cavity), a flat two-triangle shell goes; a thin tetrahedron folded onto a
 * cube's face (a triangle of each with the same corners in the same order) goes, two
 * cubes touching face to face (the same corners in opposite orders) stay; what stays
 * keeps its order, and the per-triangle tags follow the triangles.
 */
#include "testlib.h"
#include "base/core.h"
#include "csg/void_shells.h"

#include <string.h>

/* The unit cube at `at` (scaled by size), outward unless inverted: 8 vertices, 12
 * triangles, appended at vertex v0 and triangle t0. */
static void put_cube(mcsg_mesh *m, size_t v0, size_t t0, const double at[3], double size,
                     bool inverted)
{
    static const uint32_t faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                          {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                          {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (int c = 0; c < 8; c++)
        for (int k = 0; k < 3; k++)
            m->vertices[3 * (v0 + (size_t)c) + (size_t)k] = at[k] + size * ((c >> k) & 1);
    for (int f = 0; f < 12; f++) {
        uint32_t *t = m->triangles + 3 * (t0 + (size_t)f);
        t[0] = (uint32_t)v0 + faces[f][0];
        t[1] = (uint32_t)v0 + faces[f][inverted ? 2 : 1];
        t[2] = (uint32_t)v0 + faces[f][inverted ? 1 : 2];
    }
}

static bool alloc_mesh(const mci_ctx *ctx, mcsg_mesh *m, size_t nv, size_t nt)
{
    mcsg_error err;
    if (mci_mesh_alloc(ctx, m, nv, nt, &err) == MCSG_OK)
        return true;
    CHECK_MSG(false, "allocating the mesh: %s", err.message);
    return false;
}

TEST(inside_out_shell_apart_from_the_others_goes)
{
    static const double origin[3] = {0, 0, 0}, far[3] = {5, 0, 0}, inside[3] = {0.25, 0.25, 0.25};
    mci_ctx ctx;
    mcsg_mesh m;
    mci_void_shells removed;
    uint32_t tag[36];
    mci_ctx_init(&ctx, NULL);
    if (!alloc_mesh(&ctx, &m, 24, 36))
        return;
    put_cube(&m, 0, 0, origin, 1, false);
    put_cube(&m, 8, 12, far, 0.5, true);    /* no outer shell's box holds it */
    put_cube(&m, 16, 24, inside, 0.5, true); /* a cavity of the first cube */
    for (uint32_t t = 0; t < 36; t++)
        tag[t] = 100 + t;
    CHECK(mci_drop_void_shells(&ctx, &m, tag, &removed));
    CHECK_EQ_SIZE(removed.shells, 1);
    CHECK_EQ_SIZE(removed.triangles, 12);
    CHECK_EQ_SIZE(m.vertex_count, 16);
    CHECK_EQ_SIZE(m.triangle_count, 24);
    for (uint32_t t = 0; t < 24; t++)
        CHECK_EQ_SIZE(tag[t], t < 12 ? 100 + t : 112 + t);
    CHECK_EQ_SIZE(m.triangles[3 * 12], 8); /* the cavity's vertices moved down */
    CHECK_EQ_DOUBLE(m.vertices[3 * 8], 0.25);
    CHECK_EQ_DOUBLE(test_signed_volume(&m), 1 - 0.125);
    CHECK_EQ_SIZE(test_index_manifold_defects(&m), 0);
    mci_mesh_free(&ctx, &m);
}

TEST(flat_shell_goes_and_outward_shells_stay_as_they_are)
{
    static const double origin[3] = {0, 0, 0};
    mci_ctx ctx;
    mcsg_mesh m;
    mci_void_shells removed;
    mci_ctx_init(&ctx, NULL);
    if (!alloc_mesh(&ctx, &m, 11, 14))
        return;
    put_cube(&m, 0, 0, origin, 1, false);
    for (int k = 0; k < 3; k++) { /* a triangle and its reverse, inside the cube's box */
        m.vertices[3 * 8 + k] = 0.5;
        m.vertices[3 * 9 + k] = k == 0 ? 0.75 : 0.5;
        m.vertices[3 * 10 + k] = k == 1 ? 0.75 : 0.5;
    }
    memcpy(m.triangles + 36, (const uint32_t[]){8, 9, 10, 8, 10, 9}, 6 * sizeof(uint32_t));
    CHECK(mci_drop_void_shells(&ctx, &m, NULL, &removed));
    CHECK_EQ_SIZE(removed.shells, 1);
    CHECK_EQ_SIZE(m.vertex_count, 8);
    CHECK_EQ_SIZE(m.triangle_count, 12);
    CHECK(mci_drop_void_shells(&ctx, &m, NULL, &removed)); /* nothing more to remove */
    CHECK_EQ_SIZE(removed.shells, 0);
    CHECK_EQ_SIZE(m.triangle_count, 12);
    CHECK_EQ_DOUBLE(test_signed_volume(&m), 1);
    mci_mesh_free(&ctx, &m);
}

TEST(sliver_folded_onto_a_larger_shell_goes)
{
    static const double origin[3] = {0, 0, 0};
    static const uint32_t tetrahedron[12] = {8, 9, 10, 9, 8, 11, 10, 9, 11, 8, 10, 11};
    mci_ctx ctx;
    mcsg_mesh m;
    mci_void_shells removed;
    uint32_t tag[16];
    mci_ctx_init(&ctx, NULL);
    if (!alloc_mesh(&ctx, &m, 12, 16))
        return;
    put_cube(&m, 0, 0, origin, 1, false);
    /* The cube's triangle {0, 2, 1} (on z = 0, facing down) with its own vertices, and an
     * apex just inside the cube: the sliver lies behind the same face as the cube. */
    memcpy(m.vertices + 24, (const double[]){0, 0, 0, 0, 1, 0, 1, 0, 0, 0.25, 0.25, 1e-20},
           12 * sizeof(double));
    memcpy(m.triangles + 36, tetrahedron, sizeof tetrahedron);
    for (uint32_t t = 0; t < 16; t++)
        tag[t] = t;
    CHECK(mci_drop_void_shells(&ctx, &m, tag, &removed));
    CHECK_EQ_SIZE(removed.shells, 1);
    CHECK_EQ_SIZE(removed.folded, 1);
    CHECK_EQ_SIZE(removed.triangles, 4);
    CHECK_EQ_SIZE(m.vertex_count, 8);
    CHECK_EQ_SIZE(m.triangle_count, 12);
    CHECK_EQ_SIZE(tag[11], 11);
    CHECK_EQ_DOUBLE(test_signed_volume(&m), 1);
    mci_mesh_free(&ctx, &m);
}

TEST(shells_touching_face_to_face_stay)
{
    static const double origin[3] = {0, 0, 0}, next[3] = {1, 0, 0};
    mci_ctx ctx;
    mcsg_mesh m;
    mci_void_shells removed;
    mci_ctx_init(&ctx, NULL);
    if (!alloc_mesh(&ctx, &m, 16, 24))
        return;
    put_cube(&m, 0, 0, origin, 1, false);
    put_cube(&m, 8, 12, next, 1, false); /* its x = 0 face is the first's x = 1 face, reversed */
    CHECK(mci_drop_void_shells(&ctx, &m, NULL, &removed));
    CHECK_EQ_SIZE(removed.shells, 0);
    CHECK_EQ_SIZE(m.triangle_count, 24);
    CHECK_EQ_DOUBLE(test_signed_volume(&m), 2);
    mci_mesh_free(&ctx, &m);
}

int main(void)
{
    RUN(inside_out_shell_apart_from_the_others_goes);
    RUN(flat_shell_goes_and_outward_shells_stay_as_they_are);
    RUN(sliver_folded_onto_a_larger_shell_goes);
    RUN(shells_touching_face_to_face_stay);
    return test_summary();
}
