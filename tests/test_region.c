/*
 * Regions of the plane (src/shape/region.c): the even-odd fill of outlines by a
 * constrained triangulation, prisms over regions, and regions read back from evaluated
 * prisms. Areas are checked exactly where the answer is a sum of exact doubles.
 */
#include "testlib.h"

#include "base/core.h"
#include "shape/region.h"

#include <math.h>
#include <string.h>

static mci_ctx ctx;

/* Outlines from a flat list of loops: sizes[k] points each. */
static mci_outlines outlines(const double *xy, const uint32_t *sizes, size_t loops)
{
    mci_outlines o = {0};
    size_t n = 0;
    for (size_t k = 0; k < loops; k++)
        n += sizes[k];
    o.xy = mci_malloc_array(&ctx, n + 1, 2 * sizeof *o.xy);
    o.loop_start = mci_malloc_array(&ctx, loops + 1, sizeof *o.loop_start);
    memcpy(o.xy, xy, 2 * n * sizeof *xy);
    o.loop_start[0] = 0;
    for (size_t k = 0; k < loops; k++)
        o.loop_start[k + 1] = o.loop_start[k] + sizes[k];
    o.point_count = n;
    o.loop_count = loops;
    return o;
}

static double region_area(const mci_region *r)
{
    double sum = 0;
    for (size_t t = 0; t < r->tri_count; t++) {
        const double *a = r->xy + 2 * r->tris[3 * t], *b = r->xy + 2 * r->tris[3 * t + 1],
                     *c = r->xy + 2 * r->tris[3 * t + 2];
        double twice = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        CHECK_MSG(twice > 0, "triangle %zu is not counter-clockwise (%g)", t, twice);
        sum += twice / 2;
    }
    return sum;
}

/* The boundary's signed area (shoelace over its directed edges) equals the region's. */
static double boundary_area(const mci_region *r)
{
    double sum = 0;
    for (size_t e = 0; e < r->edge_count; e++) {
        const double *a = r->xy + 2 * r->edges[2 * e], *b = r->xy + 2 * r->edges[2 * e + 1];
        sum += (a[0] * b[1] - a[1] * b[0]) / 2;
    }
    return sum;
}

static void check_fill(const double *xy, const uint32_t *sizes, size_t loops, double area,
                       size_t edges)
{
    mci_outlines o = outlines(xy, sizes, loops);
    mci_region r;
    mcsg_error err;
    CHECK_OK(mci_region_from_outlines(&ctx, &o, &r, &err), &err);
    CHECK_EQ_DOUBLE(region_area(&r), area);
    CHECK_EQ_DOUBLE(boundary_area(&r), area);
    CHECK_EQ_SIZE(r.edge_count, edges);
    mci_region_free(&ctx, &r);
    mci_outlines_free(&ctx, &o);
}

TEST(square_and_orientation)
{
    static const double ccw[] = {0, 0, 4, 0, 4, 2, 0, 2}, cw[] = {0, 0, 0, 2, 4, 2, 4, 0};
    check_fill(ccw, (uint32_t[]){4}, 1, 8, 4);
    check_fill(cw, (uint32_t[]){4}, 1, 8, 4); /* even-odd: orientation does not matter */
}

TEST(holes_by_even_odd)
{
    /* A 10 x 10 square with a 4 x 4 hole given either way round, and an island in it. */
    static const double xy[] = {0, 0, 10, 0, 10, 10, 0, 10, 3, 3, 7, 3, 7, 7, 3, 7,
                                4, 4, 6, 4, 6, 6, 4, 6};
    check_fill(xy, (uint32_t[]){4, 4}, 2, 84, 8);
    check_fill(xy, (uint32_t[]){4, 4, 4}, 3, 88, 12);
}

TEST(shared_edges_cancel)
{
    /* Two squares sharing an edge: the edge cancels and the union is one rectangle. A
     * third square lying along half of an edge splits it (a point inside an edge). */
    static const double two[] = {0, 0, 1, 0, 1, 1, 0, 1, 1, 0, 2, 0, 2, 1, 1, 1};
    static const double half[] = {0, 0, 2, 0, 2, 2, 0, 2, 2, 0, 3, 0, 3, 1, 2, 1};
    check_fill(two, (uint32_t[]){4, 4}, 2, 2, 6);
    check_fill(half, (uint32_t[]){4, 4}, 2, 5, 7);
}

TEST(repeated_and_collinear_points)
{
    /* Repeated points, a point in the middle of an edge, and a loop of two points. */
    static const double xy[] = {0, 0, 0, 0, 2, 0, 4, 0, 4, 4, 0, 4, 9, 9, 8, 8};
    check_fill(xy, (uint32_t[]){6, 2}, 2, 16, 5);
}

TEST(touching_at_a_corner)
{
    static const double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 1, 1, 2, 1, 2, 2, 1, 2};
    mci_outlines o = outlines(xy, (uint32_t[]){4, 4}, 2), loops;
    mci_region r;
    mcsg_error err;
    CHECK_OK(mci_region_from_outlines(&ctx, &o, &r, &err), &err);
    CHECK_EQ_DOUBLE(region_area(&r), 2);
    CHECK_OK(mci_region_outlines(&ctx, &r, &loops, &err), &err);
    CHECK_EQ_SIZE(loops.point_count, 8);
    for (size_t k = 0; k < loops.loop_count; k++)
        CHECK(mci_outline_area2(&loops, k) > 0);
    mci_outlines_free(&ctx, &loops);
    mci_region_free(&ctx, &r);
    mci_outlines_free(&ctx, &o);
}

TEST(crossing_outlines_are_refused)
{
    static const double bowtie[] = {0, 0, 2, 2, 2, 0, 0, 2};
    static const double crossing[] = {0, 0, 4, 0, 4, 4, 0, 4, 2, 2, 6, 2, 6, 6, 2, 6};
    static const double infinite[] = {0, 0, 1, 0, INFINITY, 1};
    mci_outlines o = outlines(bowtie, (uint32_t[]){4}, 1);
    mci_region r;
    mcsg_error err;
    CHECK(mci_region_from_outlines(&ctx, &o, &r, &err) == MCSG_ERR_UNSUPPORTED);
    CHECK_CONTAINS(err.message, "crosses itself");
    mci_outlines_free(&ctx, &o);
    o = outlines(crossing, (uint32_t[]){4, 4}, 2);
    CHECK(mci_region_from_outlines(&ctx, &o, &r, &err) == MCSG_ERR_UNSUPPORTED);
    mci_outlines_free(&ctx, &o);
    o = outlines(infinite, (uint32_t[]){3}, 1);
    CHECK(mci_region_from_outlines(&ctx, &o, &r, &err) == MCSG_ERR_INVALID_ARG);
    CHECK_CONTAINS(err.message, "not finite");
    mci_outlines_free(&ctx, &o);
}

TEST(empty_outlines)
{
    static const double line[] = {0, 0, 1, 1, 2, 2};
    mci_outlines o = outlines(line, (uint32_t[]){3}, 1);
    mci_region r;
    mcsg_error err;
    CHECK_OK(mci_region_from_outlines(&ctx, &o, &r, &err), &err);
    CHECK_EQ_SIZE(r.tri_count, 0);
    mci_region_free(&ctx, &r);
    mci_outlines_free(&ctx, &o);
}

/* A prism is closed and outward with the region's area as volume; evaluating two
 * prisms and reading back their bottom gives the 2D result. */
TEST(prisms_and_back)
{
    static const double a[] = {0, 0, 3, 0, 3, 3, 0, 3}, b[] = {1, 1, 5, 1, 5, 2, 1, 2};
    mci_outlines oa = outlines(a, (uint32_t[]){4}, 1), ob = outlines(b, (uint32_t[]){4}, 1);
    mci_region ra, rb, back;
    mcsg_mesh pa, pb, out;
    mcsg_tree *tree;
    mcsg_node_id ids[2], root;
    mcsg_error err;
    CHECK_OK(mci_region_from_outlines(&ctx, &oa, &ra, &err), &err);
    CHECK_OK(mci_region_from_outlines(&ctx, &ob, &rb, &err), &err);
    CHECK_OK(mci_region_prism(&ctx, &ra, &pa, &err), &err);
    CHECK_OK(mci_region_prism(&ctx, &rb, &pb, &err), &err);
    CHECK_EQ_DOUBLE(test_signed_volume(&pa), 9);
    CHECK_EQ_SIZE(test_index_manifold_defects(&pa), 0);
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &pa, NULL, "a", &ids[0], &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(tree, &pb, NULL, "b", &ids[1], &err), &err);
    CHECK_OK(mcsg_tree_add_op(tree, MCSG_NODE_DIFFERENCE, ids, 2, "a - b", &root, &err), &err);
    CHECK_OK(mcsg_eval(tree, NULL, &out, NULL, NULL, &err), &err);
    CHECK_OK(mci_region_from_prisms(&ctx, &out, &back, &err), &err);
    CHECK_EQ_DOUBLE(region_area(&back), 7); /* 9 minus the 2 x 1 overlap */
    CHECK_EQ_DOUBLE(boundary_area(&back), 7);
    CHECK_EQ_SIZE(back.edge_count, 8);
    mci_region_free(&ctx, &back);
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
    mci_mesh_free(&ctx, &pa);
    mci_mesh_free(&ctx, &pb);
    mci_region_free(&ctx, &ra);
    mci_region_free(&ctx, &rb);
    mci_outlines_free(&ctx, &oa);
    mci_outlines_free(&ctx, &ob);
}

/* Many random points on a grid as one outline of a star: the triangulation holds
 * whatever their order around the centre. */
TEST(star_polygons)
{
    uint64_t seed = 0x5eed2d;
    for (int pass = 0; pass < 50; pass++) {
        int n = test_random_int(&seed, 3, 60);
        double xy[2 * 60], expected = 0;
        mci_outlines o;
        mci_region r;
        mcsg_error err;
        for (int i = 0; i < n; i++) {
            double angle = 6.283185307179586 * i / n;
            double radius = test_random_int(&seed, 1, 8);
            xy[2 * i] = round(radius * cos(angle) * 16) / 16;
            xy[2 * i + 1] = round(radius * sin(angle) * 16) / 16;
        }
        for (int i = 0; i < n; i++) {
            const double *p = xy + 2 * i, *q = xy + 2 * ((i + 1) % n);
            expected += (p[0] * q[1] - p[1] * q[0]) / 2;
        }
        o = outlines(xy, (uint32_t[]){(uint32_t)n}, 1);
        if (mci_region_from_outlines(&ctx, &o, &r, &err) == MCSG_OK) {
            CHECK_MSG(fabs(region_area(&r) - fabs(expected)) <= 1e-9 * fabs(expected) ||
                          r.tri_count == 0, "pass %d: area %.17g, shoelace %.17g", pass,
                      region_area(&r), expected);
            mci_region_free(&ctx, &r);
        } else {
            /* Rounded onto the grid, a star may fold over itself. */
            CHECK_CONTAINS(err.message, "crosses itself");
        }
        mci_outlines_free(&ctx, &o);
    }
}

/* The positive fill of counter-clockwise triangles is their union: shared edges cancel,
 * nested and overlapping ones count once, and clockwise ones take away. */
static void check_positive(const double *xy, const uint32_t *sizes, size_t loops, double area,
                           size_t edges)
{
    mci_outlines o = outlines(xy, sizes, loops);
    mci_region r;
    mcsg_error err;
    CHECK_OK(mci_region_fill(&ctx, &o, MCI_FILL_POSITIVE, &r, &err), &err);
    CHECK_EQ_DOUBLE(region_area(&r), area);
    CHECK_EQ_DOUBLE(boundary_area(&r), area);
    CHECK_EQ_SIZE(r.edge_count, edges);
    mci_region_free(&ctx, &r);
    mci_outlines_free(&ctx, &o);
}

TEST(positive_fill_is_a_union)
{
    /* Two triangles of a square (the diagonal cancels), and the square again inside a
     * bigger one: wound twice there, still inside once. */
    static const double halves[] = {0, 0, 2, 0, 2, 2, 0, 0, 2, 2, 0, 2};
    static const double nested[] = {0, 0, 2, 0, 2, 2, 0, 2, -1, -1, 3, -1, 3, 3, -1, 3};
    /* A square wound twice along a shared stretch: the edge counts twice and stays. */
    static const double twice[] = {0, 0, 2, 0, 2, 2, 0, 2, 0, 0, 1, 0, 1, 1, 0, 1};
    /* A clockwise square inside a counter-clockwise one is a hole; given twice, the
     * winding there is -1: still outside. */
    static const double hole[] = {0, 0, 4, 0, 4, 4, 0, 4, 1, 1, 1, 3, 3, 3, 3, 1,
                                  1, 1, 1, 3, 3, 3, 3, 1};
    check_positive(halves, (uint32_t[]){3, 3}, 2, 4, 4);
    check_positive(nested, (uint32_t[]){4, 4}, 2, 16, 4);
    check_positive(twice, (uint32_t[]){4, 4}, 2, 4, 6);
    check_positive(hole, (uint32_t[]){4, 4}, 2, 12, 8);
    check_positive(hole, (uint32_t[]){4, 4, 4}, 3, 12, 8);
}

TEST(positive_fill_refuses_crossings)
{
    static const double crossing[] = {0, 0, 4, 0, 4, 4, 0, 4, 2, 2, 6, 2, 6, 6, 2, 6};
    mci_outlines o = outlines(crossing, (uint32_t[]){4, 4}, 2);
    mci_region r;
    mcsg_error err;
    CHECK(mci_region_fill(&ctx, &o, MCI_FILL_POSITIVE, &r, &err) == MCSG_ERR_UNSUPPORTED);
    CHECK_CONTAINS(err.message, "crosses itself");
    mci_outlines_free(&ctx, &o);
}

TEST(straight_points_and_appending)
{
    /* Points on the square's sides (a run of two on the bottom) go; the triangle keeps
     * its three; a spike (going back along the same line) stays. */
    static const double xy[] = {0, 0, 1, 0, 2, 0, 4, 0, 4, 4, 0, 4, 0, 2,
                                5, 5, 6, 5, 5, 6, 7, 0, 9, 0, 8, 0, 8, 3};
    mci_outlines o = outlines(xy, (uint32_t[]){7, 3, 4}, 3), sum = {0};
    mci_outlines_drop_straight(&o);
    CHECK_EQ_SIZE(o.point_count, 11);
    CHECK_EQ_SIZE(o.loop_start[1], 4);
    CHECK_EQ_SIZE(o.loop_start[2], 7);
    CHECK_EQ_DOUBLE(mci_outline_area2(&o, 0), 32);
    CHECK_EQ_DOUBLE(o.xy[2 * 7], 7);
    CHECK_EQ_DOUBLE(o.xy[2 * 9], 8);
    CHECK(mci_outlines_append(&ctx, &sum, &o));
    CHECK(mci_outlines_append(&ctx, &sum, &o));
    CHECK_EQ_SIZE(sum.point_count, 22);
    CHECK_EQ_SIZE(sum.loop_count, 6);
    CHECK_EQ_SIZE(sum.loop_start[3], 11);
    CHECK_EQ_SIZE(sum.loop_start[6], 22);
    CHECK_EQ_DOUBLE(mci_outline_area2(&sum, 3), 32);
    mci_outlines_free(&ctx, &sum);
    mci_outlines_free(&ctx, &o);
}

int main(void)
{
    mci_ctx_init(&ctx, NULL);
    RUN(square_and_orientation);
    RUN(holes_by_even_odd);
    RUN(shared_edges_cancel);
    RUN(repeated_and_collinear_points);
    RUN(touching_at_a_corner);
    RUN(crossing_outlines_are_refused);
    RUN(empty_outlines);
    RUN(prisms_and_back);
    RUN(star_polygons);
    RUN(positive_fill_is_a_union);
    RUN(positive_fill_refuses_crossings);
    RUN(straight_points_and_appending);
    return test_summary();
}
