/*
 * First-seed rays (src/csg/rays.c): the ray test through the octree must give the same
 * label as the brute-force test over every face of the leaf, for points anywhere,
 * including points whose rays graze vertices and edges exactly (integer grids) and
 * points on the surface (UNKNOWN); and the labels must be right for boxes, where
 * membership is known. Also the leaves' box overlaps (the candidates of every leaf's
 * classification; src/csg/leaf_boxes.c) against every pair of boxes.
 */
#include "testlib.h"
#include "csg/leaf_boxes.h"
#include "csg/classify.h"
#include "csg/classify_leaf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static uint64_t rng = 0x7261797361u;

static double uniform(double lo, double hi)
{
    return lo + (hi - lo) * (double)test_random_int(&rng, 0, 1 << 30) / (double)(1 << 30);
}

typedef struct scene {
    mcsg_mesh meshes[4];
    const mcsg_mesh *leaves[4];
    size_t count;
    mci_octree tree;
} scene;

static void build_scene(scene *s, const mci_ctx *ctx)
{
    mcsg_error err;
    mcsg_resolution fine = {48, 0, 0}, coarse = {7, 0, 0};
    double box[3] = {2, 3, 2}, unit[3] = {1, 1, 1};
    double shift[12] = {1, 0, 0, 0.5, 0, 1, 0, 0.25, 0, 0, 1, -0.5};
    double grid[12] = {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 0};
    mci_octree_params params = {8, 10, NULL, NULL, NULL};
    CHECK_OK(mcsg_make_sphere(1.5, fine, NULL, &s->meshes[0], &err), &err);
    CHECK_OK(mcsg_make_cube(box, 1, NULL, &s->meshes[1], &err), &err);
    CHECK_OK(mcsg_make_cylinder(3, 1, 0.5, 1, coarse, NULL, &s->meshes[2], &err), &err);
    CHECK_OK(mcsg_make_cube(unit, 0, NULL, &s->meshes[3], &err), &err);
    mcsg_mesh_transform(&s->meshes[2], shift);
    mcsg_mesh_transform(&s->meshes[3], grid); /* [1,2] x [1,2] x [0,1] */
    s->count = 4;
    for (size_t i = 0; i < s->count; i++)
        s->leaves[i] = &s->meshes[i];
    CHECK_OK(mci_octree_build(ctx, s->leaves, s->count, &params, &s->tree, &err), &err);
}

static void free_scene(scene *s, const mci_ctx *ctx)
{
    mci_octree_free(ctx, &s->tree);
    for (size_t i = 0; i < s->count; i++)
        mcsg_mesh_free(&s->meshes[i], NULL);
}

/* Both tests on p for every leaf; returns the label for the last leaf. */
static mci_label compare_at(const scene *s, const mci_ctx *ctx, mci_ray_scratch *scratch,
                            const double x[3], int *unknown)
{
    mci_point p;
    mci_label fast = MCI_LABEL_UNKNOWN;
    mci_point_explicit(&p, x);
    for (uint32_t m = 0; m < s->count; m++) {
        mci_label slow = mci_ray_label(&p, s->leaves[m]);
        CHECK(mci_ray_label_octree(ctx, &p, &s->tree, m, scratch, &fast));
        CHECK_MSG(fast == slow, "leaf %u at (%.17g, %.17g, %.17g): octree %d, brute force %d",
                  m, x[0], x[1], x[2], fast, slow);
        *unknown += fast == MCI_LABEL_UNKNOWN;
    }
    return fast;
}

TEST(octree_rays_agree_with_brute_force)
{
    mci_ctx ctx;
    scene s;
    mci_ray_scratch scratch;
    int unknown = 0;
    memset(&scratch, 0, sizeof scratch);
    mci_ctx_init(&ctx, NULL);
    build_scene(&s, &ctx);
    for (int i = 0; i < 3000; i++) { /* anywhere */
        double x[3] = {uniform(-2, 2), uniform(-2, 2), uniform(-2, 2)};
        compare_at(&s, &ctx, &scratch, x, &unknown);
    }
    for (int i = 0; i < 3000; i++) { /* on a quarter-integer grid: rays along edges */
        double x[3] = {test_random_int(&rng, -8, 8) / 4.0, test_random_int(&rng, -8, 8) / 4.0,
                       test_random_int(&rng, -8, 8) / 4.0};
        compare_at(&s, &ctx, &scratch, x, &unknown);
    }
    for (uint32_t m = 0; m < s.count; m++) /* every vertex: on the surface */
        for (size_t v = 0; v < s.meshes[m].vertex_count; v++) {
            mci_point p;
            mci_label label;
            mci_point_explicit(&p, s.meshes[m].vertices + 3 * v);
            CHECK(mci_ray_label_octree(&ctx, &p, &s.tree, m, &scratch, &label));
            CHECK(label == MCI_LABEL_UNKNOWN);
            compare_at(&s, &ctx, &scratch, s.meshes[m].vertices + 3 * v, &unknown);
        }
    CHECK(unknown > 0);
    mci_ray_scratch_free(&ctx, &scratch);
    free_scene(&s, &ctx);
}

TEST(octree_rays_know_the_box)
{
    mci_ctx ctx;
    scene s;
    mci_ray_scratch scratch;
    memset(&scratch, 0, sizeof scratch);
    mci_ctx_init(&ctx, NULL);
    build_scene(&s, &ctx);
    for (int i = 0; i < 2000; i++) {
        /* Leaf 3 is [1,2] x [1,2] x [0,1]; grid points on its faces, edges and corners
         * are on the surface. */
        double x[3] = {test_random_int(&rng, 0, 12) / 4.0, test_random_int(&rng, 0, 12) / 4.0,
                       test_random_int(&rng, -4, 8) / 4.0};
        bool inside = x[0] > 1 && x[0] < 2 && x[1] > 1 && x[1] < 2 && x[2] > 0 && x[2] < 1;
        bool closed = x[0] >= 1 && x[0] <= 2 && x[1] >= 1 && x[1] <= 2 && x[2] >= 0 && x[2] <= 1;
        mci_point p;
        mci_label label;
        mci_point_explicit(&p, x);
        CHECK(mci_ray_label_octree(&ctx, &p, &s.tree, 3, &scratch, &label));
        CHECK(label == (inside ? MCI_LABEL_IN : closed ? MCI_LABEL_UNKNOWN : MCI_LABEL_OUT));
    }
    mci_ray_scratch_free(&ctx, &scratch);
    free_scene(&s, &ctx);
}

/* Boxes on a quarter-unit grid (shared and touching sides are frequent), some long in
 * x as a plate under its holes: mci_box_overlaps must list exactly the pairs of closed
 * boxes that meet, each row in increasing index. */
/* The winding numbers of leaf m just behind and in front of plane a, b, c at point x
 * (which lies in it); *decided as mci_ray_windings_on_plane gives it. */
static void windings_at(const mci_octree *o, uint32_t m, const double *a, const double *b,
                        const double *c, const double x[3], int *behind, int *front,
                        bool *decided)
{
    mci_ctx ctx;
    mci_ray_scratch scratch = {0};
    mci_plane at;
    mci_point p;
    mci_plane_windings got;
    mci_ctx_init(&ctx, NULL);
    mci_plane_init(&at, a, b, c);
    mci_point_explicit(&p, x);
    CHECK(mci_ray_windings_on_plane(&ctx, &p, o, m, &at, &scratch, &got));
    *behind = got.behind;
    *front = got.in_front;
    *decided = got.decided;
    mci_ray_scratch_free(&ctx, &scratch);
}

/* A unit cube given twice in one mesh (two coincident shells), and a tetrahedron: the
 * numbers on both sides of a face from a point in it, for faces across the ray (x = 0),
 * along it (z = 0) and slanted, either way round; a point on a face's border decides
 * nothing (it would count a sheet twice). */
TEST(windings_on_both_sides_of_a_face)
{
    static const double o0[3] = {0, 0, 0}, x1[3] = {1, 0, 0}, y1[3] = {0, 1, 0}, z1[3] = {0, 0, 1};
    mcsg_mesh cube, twice, tetra;
    const mcsg_mesh *leaves[2];
    double unit[3] = {1, 1, 1};
    const double on_x0[3] = {0, 0.3, 0.4}, on_z0[3] = {0.3, 0.4, 0}, on_slant[3] = {0.25, 0.25, 0.5};
    const double on_diagonal[3] = {0.5, 0.5, 0};
    static const double tv[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const uint32_t tt[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    mci_octree o;
    mci_ctx ctx;
    mcsg_error err;
    int behind, front;
    bool decided;
    mci_ctx_init(&ctx, NULL);
    CHECK_OK(mcsg_make_cube(unit, 0, NULL, &cube, &err), &err);
    twice.vertex_count = 2 * cube.vertex_count;
    twice.triangle_count = 2 * cube.triangle_count;
    twice.vertices = malloc(3 * twice.vertex_count * sizeof *twice.vertices);
    twice.triangles = malloc(3 * twice.triangle_count * sizeof *twice.triangles);
    for (size_t i = 0; i < 3 * cube.vertex_count; i++)
        twice.vertices[i] = twice.vertices[i + 3 * cube.vertex_count] = cube.vertices[i];
    for (size_t i = 0; i < 3 * cube.triangle_count; i++) {
        twice.triangles[i] = cube.triangles[i];
        twice.triangles[i + 3 * cube.triangle_count] = cube.triangles[i] + (uint32_t)cube.vertex_count;
    }
    tetra = (mcsg_mesh){(double *)tv, (uint32_t *)tt, 4, 4};
    leaves[0] = &twice;
    leaves[1] = &tetra;
    CHECK_OK(mci_octree_build(&ctx, leaves, 2, NULL, &o, &err), &err);
    /* x = 0, outward normal -x: inside (2) behind it; seen from +x, the other way. */
    windings_at(&o, 0, o0, z1, y1, on_x0, &behind, &front, &decided);
    CHECK(decided && behind == 2 && front == 0);
    windings_at(&o, 0, o0, y1, z1, on_x0, &behind, &front, &decided);
    CHECK(decided && behind == 0 && front == 2);
    windings_at(&o, 0, o0, y1, x1, on_z0, &behind, &front, &decided);
    CHECK(decided && behind == 2 && front == 0);
    windings_at(&o, 0, o0, x1, y1, on_z0, &behind, &front, &decided);
    CHECK(decided && behind == 0 && front == 2);
    windings_at(&o, 0, o0, y1, x1, on_diagonal, &behind, &front, &decided);
    CHECK(!decided);
    windings_at(&o, 1, x1, y1, z1, on_slant, &behind, &front, &decided);
    CHECK(decided && behind == 1 && front == 0);
    windings_at(&o, 1, x1, z1, y1, on_slant, &behind, &front, &decided);
    CHECK(decided && behind == 0 && front == 1);
    mci_octree_free(&ctx, &o);
    mcsg_mesh_free(&cube, NULL);
    free(twice.vertices);
    free(twice.triangles);
}

/* Whether some attempt finds a point strictly inside the triangle a, b, c (its own
 * plane), checked by its turns against the edges. */
static bool inside_point_found(const double *a, const double *b, const double *c)
{
    mci_plane plane;
    mci_point corner[3], out;
    double ends[2][3];
    int sign, axis;
    mci_plane_init(&plane, a, b, c);
    mci_point_explicit(&corner[0], a);
    mci_point_explicit(&corner[1], b);
    mci_point_explicit(&corner[2], c);
    axis = mci_plane_projection_axis(&plane, &sign);
    for (int attempt = 0; attempt < MCI_INSIDE_ATTEMPTS; attempt++) {
        int turns[3];
        if (!mci_point_inside_triangle(corner, &plane, attempt, ends, &out))
            continue;
        for (int i = 0; i < 3; i++)
            turns[i] = mci_orient2d_projected(&corner[i], &corner[(i + 1) % 3], &out, axis);
        CHECK_MSG(turns[0] == sign && turns[1] == sign && turns[2] == sign,
                  "attempt %d: the point is not strictly inside", attempt);
        return true;
    }
    return false;
}

/* Ray seeds in slivers narrower than the spacing of doubles: one in the plane y = 0
 * (7e-17 wide, from a rounded sponge evaluated again: the line's near end was moved off
 * the plane by a denormal, so the line met the plane at that end whatever its far end),
 * and one whose normal computed in doubles is 0 (exactly 2^-54: (1 + 2^-27)^2 rounds to
 * 1 + 2^-26). */
TEST(slivers_get_inside_points)
{
    static const double a[3] = {33.264638957550233, 0, 11.760821572499935},
                        b[3] = {27.216519079750014, 0, 16.037483962500119},
                        c[3] = {33.275569907228288, 0, 11.753092231428719};
    static const double o[3] = {0, 0, 0};
    double u[3] = {1 + 0x1p-27, 1, 0}, v[3] = {1 + 0x1p-26, 1 + 0x1p-27, 0};
    CHECK(inside_point_found(a, b, c));
    CHECK(inside_point_found(o, u, v));
    CHECK(inside_point_found(o, v, u));
    CHECK(inside_point_found(c, b, a));
}

/* A triangle in z = 0 whose corners (lines meeting the plane) all round to the same
 * double, (1, 1, 0): (1 + q, 1 + q), (1 + 3q, 1 + q), (1 + q, 1 + 3q), q = 2^-55, a
 * quarter of the spacing of doubles there. A region made only of such pieces
 * (re-evaluated rounded results, where many exact points nearly coincide) was left
 * undecided. */
TEST(tiny_triangles_get_inside_points)
{
    static const double top[3] = {1, 1, 1}, to0[3] = {1 + 0x1p-52, 1 + 0x1p-52, -7},
                        to1[3] = {1 + 3 * 0x1p-52, 1 + 0x1p-52, -7},
                        to2[3] = {1 + 0x1p-52, 1 + 3 * 0x1p-52, -7};
    static const double pa[3] = {0, 0, 0}, pb[3] = {1, 0, 0}, pc[3] = {0, 1, 0};
    const double *far[3] = {to0, to1, to2};
    mci_plane plane;
    mci_point corner[3], out;
    double ends[2][3];
    bool found = false;
    mci_plane_init(&plane, pa, pb, pc);
    for (int i = 0; i < 3; i++)
        CHECK(mci_point_lpi(&corner[i], top, far[i], &plane));
    for (int attempt = 0; attempt < MCI_INSIDE_ATTEMPTS && !found; attempt++) {
        int turns[3];
        if (!mci_point_inside_triangle(corner, &plane, attempt, ends, &out))
            continue;
        for (int i = 0; i < 3; i++)
            turns[i] = mci_orient2d_projected(&corner[i], &corner[(i + 1) % 3], &out, 2);
        CHECK_MSG(turns[0] != 0 && turns[0] == turns[1] && turns[1] == turns[2],
                  "attempt %d: the point is not strictly inside", attempt);
        found = true;
    }
    CHECK(found);
}

/* A triangle in z = -25 far smaller than the unit of its coordinates there (1.8e-15
 * across, 1.1e-16 wide in x, against units of 7.1e-15 in x and 3.6e-15 in z): two
 * corners are doubles one unit apart in y, the third a line meeting a plane next to the
 * first. The line through a point of its corners' doubles along the normal, as long as
 * the triangle, rounds back onto the plane at both ends; the search for a point inside
 * gave up there instead of trying a line from far away, and a region of such a piece
 * (a turned result evaluated as a leaf by its winding number) was left undecided. */
TEST(triangles_below_the_unit_get_inside_points)
{
    static const double a[3] = {-46.279362785375007, -13.481394198375, -25},
                        b[3] = {-46.279362785375007, -13.481394198375002, -25},
                        d[3] = {-46.974794344704073, -12.276871966039092, -25},
                        p[3] = {-47.141000000000005, 1.6506250000000016, -25},
                        q[3] = {-46.279362785375007, -13.481394198375002, -24};
    mci_plane line_plane, plane;
    mci_point corner[3], out;
    double ends[2][3];
    int sign, axis, found = -1;
    mci_plane_init(&line_plane, b, p, q);
    mci_plane_init(&plane, p, a, b);
    mci_point_explicit(&corner[0], a);
    mci_point_explicit(&corner[1], b);
    CHECK(mci_point_lpi(&corner[2], d, a, &line_plane));
    CHECK(mci_orient3d(&corner[2], &plane) == 0);
    axis = mci_plane_projection_axis(&plane, &sign);
    CHECK(mci_orient2d_projected(&corner[0], &corner[1], &corner[2], axis) == sign);
    for (int attempt = 0; attempt < MCI_INSIDE_ATTEMPTS && found < 0; attempt++) {
        if (!mci_point_inside_triangle(corner, &plane, attempt, ends, &out))
            continue;
        for (int i = 0; i < 3; i++)
            CHECK_MSG(mci_orient2d_projected(&corner[i], &corner[(i + 1) % 3], &out, axis) ==
                          sign, "attempt %d: the point is not strictly inside", attempt);
        found = attempt;
    }
    CHECK(found >= 0);
}

/* A needle in the plane x = 69.60141415711261 whose middle corner lies a unit (1.8e-15)
 * from the far corner, on the line through the other two within about 1e-31: far
 * thinner than any line near its middle resolves (the sliver search moves its line by
 * units of the offset along the long edge, about 1e-32 there). Next to the middle
 * corner, an input vertex, a line from far away meets the plane 2^-112 of a unit from
 * it, inside. The only piece of a region in the rounded result of fuzz seed
 * 0xe2096d867567563a evaluated again; with no point to cast a ray from, its winding
 * numbers were undecided. */
TEST(needles_below_double_double_get_inside_points)
{
    static const double a[3] = {69.60141415711261, 1.1187469739708047, 18.968332756382562},
                        b[3] = {69.60141415711261, 11.755378344372957, 8.33170138598041},
                        c[3] = {69.60141415711261, 11.755378344372959, 8.331701385980407};
    mci_plane plane;
    mci_point corner[3], out;
    double ends[2][3];
    bool near_middle = false;
    mci_plane_init(&plane, a, b, c);
    mci_point_explicit(&corner[0], a);
    mci_point_explicit(&corner[1], b);
    mci_point_explicit(&corner[2], c);
    for (int attempt = 0; attempt < MCI_INSIDE_WEIGHTED; attempt++)
        near_middle |= mci_point_inside_triangle(corner, &plane, attempt, ends, &out);
    CHECK(!near_middle); /* the case needs the corner's attempts */
    CHECK(inside_point_found(a, b, c));
    CHECK(inside_point_found(c, a, b));
    {
        /* Two corners 6e-64 apart in x at x = 5e-50 (a rounded result's vertices near
         * 0), the third 0.13 away: the point must lie within about 1e-64 of a corner,
         * 2^-160 of the unit of its other coordinates (fuzz seed 0x323af87d8f33eb18). */
        static const double p[3] = {5.0806567214241748e-50, -25.000000000000004,
                                    -28.867506729742217},
                            q[3] = {5.0806567214241169e-50, -25.000000000000004,
                                    -28.867506729742217},
                            r[3] = {0.11309941359603591, -25.000000000000004,
                                    -28.802208722412153};
        CHECK(inside_point_found(p, q, r));
        CHECK(inside_point_found(q, p, r));
    }
}

TEST(box_overlaps_match_every_pair)
{
    mci_ctx ctx;
    mci_ctx_init(&ctx, NULL);
    for (int round = 0; round < 30; round++) {
        size_t n = (size_t)test_random_int(&rng, 0, 120), listed = 0;
        double (*box)[6] = malloc((n + 1) * sizeof *box);
        uint32_t *start, *list;
        for (size_t i = 0; i < n; i++)
            for (int k = 0; k < 3; k++) {
                double lo = test_random_int(&rng, 0, 40) / 4.0;
                double len = test_random_int(&rng, 0, k == 0 && i % 7 == 0 ? 40 : 8) / 4.0;
                box[i][k] = lo;
                box[i][3 + k] = lo + len;
            }
        CHECK(mci_box_overlaps(&ctx, (const double (*)[6])box, n, &start, &list));
        for (size_t i = 0; i < n; i++) {
            uint32_t at = start[i];
            for (size_t j = 0; j < n; j++) {
                bool meet = j != i;
                for (int k = 0; k < 3; k++)
                    meet = meet && !(box[i][3 + k] < box[j][k] || box[j][3 + k] < box[i][k]);
                if (!meet)
                    continue;
                CHECK_MSG(at < start[i + 1] && list[at] == j, "round %d: box %zu misses %zu",
                          round, i, j);
                at += at < start[i + 1] && list[at] == j;
            }
            CHECK_MSG(at == start[i + 1], "round %d: box %zu lists extra boxes", round, i);
            listed += start[i + 1] - start[i];
        }
        CHECK(n == 0 || start[n] == listed);
        mci_free(&ctx, start);
        mci_free(&ctx, list);
        free(box);
    }
}

int main(void)
{
    RUN(octree_rays_agree_with_brute_force);
    RUN(octree_rays_know_the_box);
    RUN(box_overlaps_match_every_pair);
    RUN(windings_on_both_sides_of_a_face);
    RUN(slivers_get_inside_points);
    RUN(tiny_triangles_get_inside_points);
    RUN(triangles_below_the_unit_get_inside_points);
    RUN(needles_below_double_double_get_inside_points);
    return test_summary();
}
