/*
 * The intersection stage through the public API (mcsg_intersect): known curves of two
 * boxes, closed curves (every point of even degree) for generic scenes, coplanar
 * identical operands, touching boxes, random spheres.
 */
#include "testlib.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static mcsg_tree *scene(const mcsg_mesh *const *meshes, const double (*moves)[12], size_t n)
{
    mcsg_tree *tree;
    mcsg_error err;
    mcsg_node_id id;
    CHECK_OK(mcsg_tree_create(NULL, &tree, &err), &err);
    for (size_t i = 0; i < n; i++)
        CHECK_OK(mcsg_tree_add_leaf(tree, meshes[i], moves ? moves[i] : NULL, NULL, &id, &err),
                 &err);
    return tree;
}

static size_t odd_points(const mcsg_curves *c)
{
    size_t odd = 0;
    unsigned char *parity = calloc(c->point_count + 1, 1);
    for (size_t i = 0; i < 2 * c->segment_count; i++)
        parity[c->segments[i]] ^= 1;
    for (size_t i = 0; i < c->point_count; i++)
        odd += parity[i];
    free(parity);
    return odd;
}

static double total_length(const mcsg_curves *c)
{
    double sum = 0;
    for (size_t i = 0; i < c->segment_count; i++) {
        const double *a = c->points + 3 * c->segments[2 * i];
        const double *b = c->points + 3 * c->segments[2 * i + 1];
        sum += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                    (a[2] - b[2]) * (a[2] - b[2]));
    }
    return sum;
}

static void run(mcsg_tree *tree, mcsg_curves *c, mcsg_intersect_stats *s)
{
    mcsg_error err;
    CHECK_OK(mcsg_intersect(tree, NULL, c, s, &err), &err);
}

static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

static void translation(double m[12], double x, double y, double z)
{
    memcpy(m, identity, sizeof identity);
    m[3] = x, m[7] = y, m[11] = z;
}

TEST(two_boxes_give_the_hexagon)
{
    /* [0,1]^3 and [0.5,1.5]^3: the surfaces meet along six half-unit edges forming one
     * closed loop (split where they cross the faces' diagonals). */
    double size[3] = {1, 1, 1}, moves[2][12];
    mcsg_mesh cube;
    mcsg_curves c;
    mcsg_intersect_stats s;
    mcsg_error err;
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    translation(moves[0], 0, 0, 0);
    translation(moves[1], 0.5, 0.5, 0.5);
    const mcsg_mesh *m[2] = {&cube, &cube};
    mcsg_tree *tree = scene(m, (const double(*)[12])moves, 2);
    run(tree, &c, &s);
    CHECK(c.segment_count >= 6);
    CHECK_EQ_SIZE(odd_points(&c), 0);
    CHECK_EQ_DOUBLE(total_length(&c), 3.0);
    CHECK_EQ_SIZE(s.coplanar_pairs, 0);
    mcsg_curves_free(&c, NULL);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&cube, NULL);
}

TEST(box_and_rotated_box_give_closed_curves)
{
    double size[3] = {2, 2, 2};
    double c30 = 0.8660254037844386, s30 = 0.5;
    double moves[2][12] = {{1, 0, 0, -1, 0, 1, 0, -1, 0, 0, 1, -1},
                           {c30, -s30, 0, 0.3, s30, c30, 0, 0.2, 0, 0, 1, 0.1}};
    mcsg_mesh cube;
    mcsg_curves c;
    mcsg_intersect_stats s;
    mcsg_error err;
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    const mcsg_mesh *m[2] = {&cube, &cube};
    mcsg_tree *tree = scene(m, (const double(*)[12])moves, 2);
    run(tree, &c, &s);
    CHECK(c.segment_count >= 8);
    CHECK_EQ_SIZE(odd_points(&c), 0);
    mcsg_curves_free(&c, NULL);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&cube, NULL);
}

TEST(identical_spheres_are_coplanar_everywhere)
{
    mcsg_mesh a, b;
    mcsg_curves c;
    mcsg_intersect_stats s;
    mcsg_error err;
    CHECK_OK(mcsg_mesh_read(test_model("sphere.obj"), MCSG_FORMAT_AUTO, NULL, &a, &err),
             &err);
    CHECK_OK(mcsg_mesh_read(test_model("sphere.obj"), MCSG_FORMAT_AUTO, NULL, &b, &err),
             &err);
    const mcsg_mesh *m[2] = {&a, &b};
    mcsg_tree *tree = scene(m, NULL, 2);
    run(tree, &c, &s);
    /* Each face overlaps exactly its twin; neighbours touch along edges only. The
     * surfaces coincide, so the curves are exactly the mesh's edges, each once (where an
     * odd number of edges meet, a point has odd degree: parity means nothing here). */
    CHECK_EQ_SIZE(s.coplanar_pairs, a.triangle_count);
    CHECK_EQ_SIZE(c.segment_count, 3 * a.triangle_count / 2);
    CHECK_EQ_SIZE(c.point_count, a.triangle_count / 2 + 2);
    mcsg_curves_free(&c, NULL);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&a, NULL);
    mcsg_mesh_free(&b, NULL);
}

TEST(boxes_touching_at_a_vertex_only_touch)
{
    double size[3] = {1, 1, 1}, moves[2][12];
    mcsg_mesh cube;
    mcsg_curves c;
    mcsg_intersect_stats s;
    mcsg_error err;
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    translation(moves[0], 0, 0, 0);
    translation(moves[1], 1, 1, 1);
    const mcsg_mesh *m[2] = {&cube, &cube};
    mcsg_tree *tree = scene(m, (const double(*)[12])moves, 2);
    run(tree, &c, &s);
    CHECK_EQ_SIZE(c.segment_count, 0);
    CHECK(s.point_contacts > 0);
    mcsg_curves_free(&c, NULL);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&cube, NULL);
}

TEST(random_spheres_give_closed_curves)
{
    mcsg_mesh sphere;
    mcsg_resolution res = {14, 0, 0};
    mcsg_error err;
    double moves[30][12];
    const mcsg_mesh *m[30];
    uint64_t state = 12345;
    mcsg_curves c;
    mcsg_intersect_stats s;
    CHECK_OK(mcsg_make_sphere(1.0, res, NULL, &sphere, &err), &err);
    for (int i = 0; i < 30; i++) {
        double p[3];
        for (int k = 0; k < 3; k++) {
            state = state * 6364136223846793005ULL + 1442695040888963407ULL;
            p[k] = (double)(state >> 11) / 9007199254740992.0 * 4;
        }
        translation(moves[i], p[0], p[1], p[2]);
        m[i] = &sphere;
    }
    mcsg_tree *tree = scene(m, (const double(*)[12])moves, 30);
    run(tree, &c, &s);
    CHECK(c.segment_count > 1000);
    CHECK_EQ_SIZE(odd_points(&c), 0);
    printf("30 spheres: %zu candidate pairs, %zu segments, %zu points\n", s.candidate_pairs,
           c.segment_count, c.point_count);
    mcsg_curves_free(&c, NULL);
    mcsg_tree_free(tree);
    mcsg_mesh_free(&sphere, NULL);
}

int main(void)
{
    RUN(two_boxes_give_the_hexagon);
    RUN(box_and_rotated_box_give_closed_curves);
    RUN(identical_spheres_are_coplanar_everywhere);
    RUN(boxes_touching_at_a_vertex_only_touch);
    RUN(random_spheres_give_closed_curves);
    return test_summary();
}
