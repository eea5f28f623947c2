/*
 * Polyhedron faces triangulated as OpenSCAD 2021.01 does (shape/tess.c).
 *
 * The expected triangles come from libtess2 as OpenSCAD 2021.01 ships it
 * (src/ext/libtess2 at tag openscad-2021.01), built alone and called as
 * GeometryUtils::tessellatePolygonWithHoles calls it (float coordinates,
 * TESS_WINDING_ODD, TESS_CONSTRAINED_DELAUNAY_TRIANGLES, no normal); the volumes are
 * those of OpenSCAD's own export (`openscad -o x.stl`, then `meshcsg check x.stl`).
 */
#include "shape/tess.h"
#include "testlib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Triangles equal as sets of oriented triangles (any rotation of each). */
static bool same_triangles(const uint32_t *a, const uint32_t *b, uint32_t count)
{
    bool used[32] = {false};
    for (uint32_t i = 0; i < count; i++) {
        bool found = false;
        for (uint32_t j = 0; j < count && !found; j++)
            for (int r = 0; r < 3 && !found; r++)
                if (!used[j] && a[3 * i] == b[3 * j + r] &&
                    a[3 * i + 1] == b[3 * j + (r + 1) % 3] &&
                    a[3 * i + 2] == b[3 * j + (r + 2) % 3])
                    used[j] = found = true;
        if (!found)
            return false;
    }
    return true;
}

typedef struct tess_case {
    const char *what;
    uint32_t n;
    double xyz[3 * 12];
    uint32_t count;
    uint32_t tris[3 * 10];
} tess_case;

static const tess_case libtess2_cases[] = {
    {"an L (planar, not convex)", 6,
     {0, 0, 0, 4, 0, 0, 4, 1, 0, 1, 1, 0, 1, 3, 0, 0, 3, 0},
     4, {4, 5, 3, 3, 1, 2, 3, 0, 1, 0, 3, 5}},
    {"a star of eight corners (split and merge vertices)", 8,
     {0, 0, 0, 2, 1, 0, 4, 0, 0, 3, 2, 0, 4, 4, 0, 2, 3, 0, 0, 4, 0, 1, 2, 0},
     6, {4, 5, 3, 1, 3, 5, 3, 1, 2, 5, 7, 1, 7, 5, 6, 1, 7, 0}},
    {"a square lifted at two corners (angles sum to pi: no flip)", 4,
     {0, 0, 0, 10, 0, 1, 10, 10, 0, 0, 10, 1},
     2, {3, 1, 2, 1, 3, 0}},
    {"a trapezoid lifted at two corners (flipped by the Delaunay step)", 4,
     {0, 0, 0, 6, 0, 1, 7, 5, 0, -1, 5, 1},
     2, {2, 0, 1, 0, 2, 3}},
    {"a heptagon out of plane", 7,
     {0, 0, 0, 5, 0, 1, 9, 3, 0, 7, 8, 2, 2, 9, 0, -2, 6, 1, -3, 2, -1},
     5, {3, 1, 2, 4, 1, 3, 4, 0, 1, 5, 0, 4, 0, 5, 6}},
};

static void run_case(const mci_ctx *ctx, mci_tess **t, const tess_case *c, mci_tess_how *how,
                     uint32_t *tris, uint32_t *count)
{
    uint32_t ids[12];
    mcsg_error err;
    for (uint32_t k = 0; k < c->n; k++)
        ids[k] = k;
    CHECK_OK(mci_tess_face(ctx, t, c->xyz, ids, c->n, tris, count, how, &err), &err);
}

TEST(same_triangles_as_libtess2)
{
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    mci_tess *t = NULL;
    for (size_t i = 0; i < sizeof libtess2_cases / sizeof libtess2_cases[0]; i++) {
        const tess_case *c = &libtess2_cases[i];
        uint32_t tris[3 * 10], count = 0;
        mci_tess_how how;
        run_case(&ctx, &t, c, &how, tris, &count);
        CHECK_MSG(how == MCI_TESS_LIBTESS2, "%s: not reproduced", c->what);
        CHECK_MSG(count == c->count && same_triangles(tris, c->tris, count),
                  "%s: other triangles than libtess2's", c->what);
    }
    mci_tess_free(&ctx, &t);
    CHECK(t == NULL);
}

/* OpenSCAD's cleaning: repeated corners, a last corner equal to the first, null ears,
 * three corners passed through as given, fewer giving nothing. */
TEST(cleaning)
{
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    mci_tess *t = NULL;
    mcsg_error err;
    uint32_t tris[3 * 6], count;
    mci_tess_how how;
    /* vertices 0 1 1 2 0: repeated and closing corners leave the triangle of corners
     * 0 1 3, as given */
    const uint32_t rep[5] = {0, 1, 1, 2, 0};
    const double rep_xyz[3 * 5] = {0, 0, 0, 1, 0, 0, 1, 0, 0, 1, 1, 0, 0, 0, 0};
    CHECK_OK(mci_tess_face(&ctx, &t, rep_xyz, rep, 5, tris, &count, &how, &err), &err);
    CHECK(how == MCI_TESS_TRIANGLE && count == 1);
    CHECK(tris[0] == 0 && tris[1] == 1 && tris[2] == 3);
    /* vertices 0 1 4 1 2 3: the null ear 1 4 1 goes (corners 1 and 2), leaving the
     * square of corners 0 3 4 5 */
    const uint32_t ear[6] = {0, 1, 4, 1, 2, 3};
    const double ear_xyz[3 * 6] = {0, 0, 0, 1, 0, 0, 5, 5, 5, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    CHECK_OK(mci_tess_face(&ctx, &t, ear_xyz, ear, 6, tris, &count, &how, &err), &err);
    CHECK(how == MCI_TESS_LIBTESS2 && count == 2);
    for (uint32_t k = 0; k < 3 * count; k++)
        CHECK(tris[k] != 1 && tris[k] != 2);
    /* two distinct vertices: nothing */
    const uint32_t two[4] = {0, 1, 0, 1};
    CHECK_OK(mci_tess_face(&ctx, &t, rep_xyz, two, 4, tris, &count, &how, &err), &err);
    CHECK(how == MCI_TESS_EMPTY && count == 0);
    mci_tess_free(&ctx, &t);
}

/* A quadrilateral whose projection crosses itself (libtess2 would cut it at the
 * crossing): fanned from its first corner, still n - 2 triangles. */
TEST(crossing_projection_is_fanned)
{
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    mci_tess *t = NULL;
    const tess_case c = {"bow tie", 4, {0, 0, 0, 10, 0, -1, 10, 1, 0, 0, 1, -1}, 0, {0}};
    uint32_t tris[6], count = 0;
    mci_tess_how how;
    run_case(&ctx, &t, &c, &how, tris, &count);
    CHECK(how == MCI_TESS_FAN && count == 2);
    CHECK(tris[0] == 0 && tris[1] == 1 && tris[2] == 2 && tris[3] == 0 && tris[4] == 2 &&
          tris[5] == 3);
    mci_tess_free(&ctx, &t);
}

static mcsg_status alloc_run(const void *arg, const mcsg_options *opts, mcsg_error *err)
{
    (void)arg;
    mci_ctx ctx;
    mci_ctx_init(&ctx, opts);
    mci_tess *t = NULL;
    const tess_case *c = &libtess2_cases[1];
    uint32_t ids[12], tris[3 * 10], count = 0;
    mci_tess_how how;
    for (uint32_t k = 0; k < c->n; k++)
        ids[k] = k;
    mcsg_status st = mci_tess_face(&ctx, &t, c->xyz, ids, c->n, tris, &count, &how, err);
    if (st == MCSG_OK)
        CHECK(count == c->count && same_triangles(tris, c->tris, count));
    mci_tess_free(&ctx, &t);
    return st;
}

TEST(allocation_failures)
{
    CHECK(test_allocation_failures("mci_tess_face", alloc_run, NULL, false) > 0);
}

/* OpenSCAD's test files issue1867.scad and issue1061.scad (non-planar faces), evaluated
 * and compared with the volume of OpenSCAD's export. */
static double scad_volume(const char *file, mcsg_mesh *mesh)
{
    mcsg_tree *tree = NULL;
    mcsg_error err;
    double v = NAN;
    memset(mesh, 0, sizeof *mesh);
    CHECK_OK(mcsg_scad_read(test_data(file), NULL, &tree, &err), &err);
    if (tree) {
        CHECK_OK(mcsg_eval(tree, NULL, mesh, NULL, NULL, &err), &err);
        v = test_signed_volume(mesh);
    }
    mcsg_tree_free(tree);
    return v;
}

static double tetra_volume(const double *a, const double *b, const double *c, const double *d)
{
    double u[3], v[3], w[3];
    for (int k = 0; k < 3; k++)
        u[k] = b[k] - a[k], v[k] = c[k] - a[k], w[k] = d[k] - a[k];
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
            u[2] * (v[0] * w[1] - v[1] * w[0])) / 6;
}

TEST(openscad_issue_files)
{
    mcsg_mesh mesh;
    /* issue1867: a box whose bottom quadrilateral is not planar */
    double v = scad_volume("tess/issue1867.scad", &mesh);
    CHECK_MSG(fabs(v - 3010992.1642072834) <= 1e-6 * 3010992.1642072834, "issue1867: %.17g", v);
    mcsg_mesh_free(&mesh, NULL);
    /* issue1061: a twisted column of 24 non-planar quadrilaterals. One of them,
     * [10, 11, 15, 14], projects onto a bow tie; libtess2 cuts it at the crossing and
     * OpenSCAD patches it with the diagonal 10-15, where meshcsg fans it (14-11). So
     * OpenSCAD's volume is meshcsg's plus the tetrahedron between the two diagonals. */
    v = scad_volume("tess/issue1061.scad", &mesh);
    CHECK(mesh.vertex_count >= 16);
    if (mesh.vertex_count >= 16) {
        const double p10[3] = {5.42115, 9.96105, 6}, p11[3] = {9.96105, 1.05099, 6};
        const double p14[3] = {4.50554, 11, 9}, p15[3] = {11, 3.39596, 9};
        double tetra = fabs(tetra_volume(p10, p11, p14, p15));
        double openscad = 1876.7975858517846;
        CHECK_MSG(fabs(v + tetra - openscad) <= 1e-6 * openscad, "issue1061: %.17g + %.17g",
                  v, tetra);
        CHECK_MSG(fabs(v - openscad) > 1e-3, "issue1061: the bow tie now matches");
    }
    mcsg_mesh_free(&mesh, NULL);
}

int main(void)
{
    RUN(same_triangles_as_libtess2);
    RUN(cleaning);
    RUN(crossing_projection_is_fanned);
    RUN(allocation_failures);
    RUN(openscad_issue_files);
    return test_summary();
}
