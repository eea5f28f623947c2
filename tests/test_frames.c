/*
 * Frames (mesh/tree.h, csg/frames.c): the reader marks a group under a transform that
 * turns space, and evaluation takes such a group in its own coordinates first. Checked:
 * which nodes become frames and what their leaves' local meshes are; results against
 * volumes known by hand, clean (closed, manifold once welded, no crossing triangles);
 * provenance naming the tree's own leaves; the same set as the tree flattened (volume and
 * bounding box); failures
 * inside a frame; allocation failures.
 */
#include "testlib.h"

#include "csg/frames.h"
#include "mesh/tree.h"

#include <math.h>
#include <string.h>

static mcsg_tree *read_text(const char *text)
{
    mcsg_tree *tree = NULL;
    mcsg_error err;
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "frames.scad", NULL, NULL, &tree, &err),
             &err);
    return tree;
}

/* The nodes marked as frames, in id order, into ids (at most 8). */
static size_t frames_of(const mcsg_tree *tree, mcsg_node_id ids[8])
{
    size_t count = 0;
    for (mcsg_node_id n = 0; n < mcsg_tree_node_count(tree); n++) {
        if (mci_tree_frame(tree, n) && count < 8)
            ids[count++] = n;
    }
    CHECK_EQ_SIZE(count, mci_tree_frame_count(tree));
    return count;
}

static size_t frame_count_of(const char *text)
{
    mcsg_tree *tree = read_text(text);
    mcsg_node_id ids[8];
    size_t count = tree ? frames_of(tree, ids) : 0;
    mcsg_tree_free(tree);
    return count;
}

static bool same_vertices(const mcsg_mesh *a, const mcsg_mesh *b)
{
    return a && b && a->vertex_count == b->vertex_count &&
           memcmp(a->vertices, b->vertices, 3 * a->vertex_count * sizeof(double)) == 0;
}

TEST(frames_marked_by_the_reader)
{
    mcsg_tree *tree, *alone;
    mcsg_node_id ids[8];
    /* two leaves under a turn: a frame; one leaf, or scales and moves: none */
    CHECK_EQ_SIZE(frame_count_of("rotate(30) { cube(1); sphere(1); }"), 1);
    CHECK_EQ_SIZE(frame_count_of("rotate(30) cube(1);"), 0);
    CHECK_EQ_SIZE(frame_count_of("translate([1, 2, 3]) scale([2, 3, 4]) mirror([1, 0, 0]) "
                                 "{ cube(1); cube(2); }"), 0);
    CHECK_EQ_SIZE(frame_count_of("multmatrix([[0, 1, 0, 0], [-2, 0, 0, 0], [0, 0, 1, 5]]) "
                                 "{ cube(1); cube(2); }"), 0);
    CHECK_EQ_SIZE(frame_count_of("rotate(30) { cube(1); rotate(45) { cube(1); cube(2); } }"), 2);
    /* a turn directly inside another: one frame with the product */
    CHECK_EQ_SIZE(frame_count_of("rotate(30) rotate([10, 0, 0]) { cube(1); cube(2); }"), 1);
    /* a frame with an empty part and one leaf is no frame */
    CHECK_EQ_SIZE(frame_count_of("rotate(30) { cube(1); cube(0); }"), 0);

    /* a lone turned leaf inside a frame: its local mesh is turned into the frame */
    tree = read_text("rotate(30) union() { cube(1); rotate(45) cube(2); }");
    alone = read_text("rotate(45) cube(2);");
    if (tree && alone && frames_of(tree, ids) == 1) {
        /* leaves come first in call order: node 0 is cube(1), node 1 cube(2) */
        const mcsg_mesh *local = mci_tree_leaf_local(tree, 1);
        const mcsg_mesh *plain = mcsg_tree_leaf_mesh(alone, 0);
        CHECK(mcsg_tree_node_kind(tree, 1) == MCSG_NODE_LEAF && local != NULL);
        CHECK(mci_tree_leaf_local(tree, 0) != NULL);
        CHECK(same_vertices(local, plain));
        CHECK(mci_tree_leaf_local(alone, 0) == NULL); /* no frame: no copy kept */
        CHECK(mci_tree_frame(tree, ids[0])[1] != 0);
    }
    mcsg_tree_free(tree);
    mcsg_tree_free(alone);
}

/* The same tree without frames: every leaf as turned alone (node ids kept). */
static mcsg_tree *flattened_copy(const mcsg_tree *tree)
{
    mcsg_tree *flat = NULL;
    mcsg_error err;
    mcsg_node_id ids[64];
    CHECK_OK(mcsg_tree_create(NULL, &flat, &err), &err);
    for (mcsg_node_id n = 0; flat && n < mcsg_tree_node_count(tree); n++) {
        size_t children = mcsg_tree_child_count(tree, n);
        CHECK(children <= 64);
        for (size_t i = 0; i < children && i < 64; i++)
            ids[i] = mcsg_tree_child(tree, n, i);
        if (mcsg_tree_node_kind(tree, n) == MCSG_NODE_LEAF)
            CHECK_OK(mcsg_tree_add_leaf(flat, mcsg_tree_leaf_mesh(tree, n), NULL, NULL, NULL,
                                        &err), &err);
        else
            CHECK_OK(mcsg_tree_add_op(flat, mcsg_tree_node_kind(tree, n), ids, children, NULL,
                                      NULL, &err), &err);
    }
    if (flat)
        CHECK_OK(mcsg_tree_set_root(flat, mcsg_tree_root(tree), &err), &err);
    return flat;
}

/* The centroid of the solid a closed mesh bounds. */
static void centroid(const mcsg_mesh *m, double c[3])
{
    double moment[3] = {0, 0, 0}, volume = 0;
    for (size_t t = 0; t < m->triangle_count; t++) {
        const double *p = m->vertices + 3 * m->triangles[3 * t];
        const double *q = m->vertices + 3 * m->triangles[3 * t + 1];
        const double *r = m->vertices + 3 * m->triangles[3 * t + 2];
        double v = (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
                    p[2] * (q[0] * r[1] - q[1] * r[0])) / 6;
        volume += v;
        for (int a = 0; a < 3; a++)
            moment[a] += v * (p[a] + q[a] + r[a]) / 4;
    }
    for (int a = 0; a < 3; a++)
        c[a] = volume != 0 ? moment[a] / volume : 0;
}

/* The result is the set that the flattened tree gives, to within rounding: the same
 * volume and centroid. (Not the same bounding box: where the flattened tree turns faces
 * meant to coincide one by one, slivers ~1e-14 thick can stay.) */
static void same_as_flattened(const char *text, const mcsg_tree *tree, const mcsg_mesh *out)
{
    mcsg_tree *flat = flattened_copy(tree);
    mcsg_mesh plain;
    mcsg_error err;
    double c[3], plain_c[3], v, plain_v;
    if (!flat)
        return;
    CHECK_EQ_SIZE(mci_tree_frame_count(flat), 0);
    CHECK_OK(mcsg_eval(flat, NULL, &plain, NULL, NULL, &err), &err);
    centroid(out, c);
    centroid(&plain, plain_c);
    for (int a = 0; a < 3; a++)
        CHECK_MSG(fabs(c[a] - plain_c[a]) <= 1e-9 * (fabs(plain_c[a]) + 1), "%s: centroid "
                  "%.17g on axis %d, flattened %.17g", text, c[a], a, plain_c[a]);
    v = test_signed_volume(out);
    plain_v = test_signed_volume(&plain);
    CHECK_MSG(fabs(v - plain_v) <= 1e-12 * fabs(plain_v) + 1e-15, "%s: volume %.17g, flattened "
              "%.17g", text, v, plain_v);
    mcsg_mesh_free(&plain, NULL);
    mcsg_tree_free(flat);
}

typedef struct outcome {
    mcsg_mesh mesh;
    mcsg_provenance *provenance;
    mcsg_eval_stats stats;
    double volume;
} outcome;

/* Evaluate; the result must be clean: closed, oriented, manifold once welded, without
 * zero-area or crossing triangles, its provenance naming leaves of the tree, the same set
 * as without frames. */
static bool clean_result(const char *text, outcome *o)
{
    mcsg_tree *tree = read_text(text);
    mcsg_check_report r;
    mcsg_error err;
    size_t pairs = 0;
    bool ok = tree != NULL;
    memset(o, 0, sizeof *o);
    if (ok) {
        mcsg_status st = mcsg_eval(tree, NULL, &o->mesh, &o->provenance, &o->stats, &err);
        CHECK_MSG(st == MCSG_OK, "%s: %s", text, err.message);
        ok = st == MCSG_OK;
    }
    if (ok) {
        CHECK_OK(mcsg_mesh_check(&o->mesh, NULL, &r, &err), &err);
        CHECK_MSG(mcsg_check_report_is_valid(&r) && r.degenerate_triangles == 0,
                  "%s: %zu open, %zu non-manifold edges, %zu zero-area triangles", text,
                  r.boundary_edges, r.nonmanifold_edges, r.degenerate_triangles);
        CHECK_OK(mcsg_mesh_self_intersections(&o->mesh, NULL, &pairs, NULL, &err), &err);
        CHECK_MSG(pairs == 0, "%s: %zu crossing pairs", text, pairs);
        CHECK(!mcsg_output_check_failed(&o->stats.output_check));
        for (size_t t = 0; t < o->mesh.triangle_count; t++) {
            const mcsg_mesh *leaf = mcsg_tree_leaf_mesh(tree, o->provenance[t].leaf);
            CHECK_MSG(leaf && o->provenance[t].face < leaf->triangle_count,
                      "%s: triangle %zu comes from node %u face %u", text, t,
                      o->provenance[t].leaf, o->provenance[t].face);
            if (!leaf)
                break;
        }
        o->volume = test_signed_volume(&o->mesh);
        same_as_flattened(text, tree, &o->mesh);
    }
    mcsg_tree_free(tree);
    return ok;
}

static void free_outcome(outcome *o)
{
    mcsg_mesh_free(&o->mesh, NULL);
    mcsg_free(o->provenance, NULL);
}

static void check_volume(const char *text, double expected, size_t frames)
{
    outcome o;
    if (clean_result(text, &o)) {
        CHECK_MSG(fabs(o.volume - expected) <= 1e-12 * fabs(expected) + 1e-15,
                  "%s: volume %.17g, expected %.17g", text, o.volume, expected);
        CHECK_EQ_SIZE(o.stats.frames_evaluated, frames);
    }
    free_outcome(&o);
}

TEST(frames_evaluate_turned_groups)
{
    /* two cubes sharing a face, turned: one box 2 x 1 x 1, with only its corners */
    outcome o;
    if (clean_result("rotate([30, 40, 50]) { cube(1); translate([1, 0, 0]) cube(1); }",
                     &o)) {
        CHECK(fabs(o.volume - 2) <= 1e-12);
        CHECK_EQ_SIZE(o.mesh.vertex_count, 8);
        CHECK_EQ_SIZE(o.stats.frames_evaluated, 1);
    }
    free_outcome(&o);
    /* a frame as the subtrahend, at the root, nested, directly nested, empty */
    check_volume("difference() { cube(4, center = true); rotate([10, 20, 30]) { "
                 "cube(1, center = true); translate([0.5, 0, 0]) cube(1, center = true); } }",
                 64 - 1.5, 1);
    check_volume("rotate([0, 0, 30]) difference() { cube(2); cube(1); }", 7, 1);
    check_volume("rotate([0, 0, 30]) union() { cube(1); translate([5, 0, 0]) rotate([45, 0, 0]) "
                 "intersection() { cube(2, center = true); cube([1, 4, 4], center = true); } }",
                 1 + 4, 2);
    check_volume("rotate(30) rotate([0, 45, 0]) { cube(1); translate([0, 0, 1]) cube(1); }",
                 2, 1);
    check_volume("union() { cube(1); rotate(30) intersection() { cube(1); "
                 "translate([5, 0, 0]) cube(1); } }", 1, 1);
}

/* A turned group of coplanar parts (a cube with three bars through it and a corner cut
 * away, turned by a six-digit matrix far from the origin):
 * in its frame the faces meant to coincide do; the result is clean and the same set as
 * the tree with every leaf turned on its own, to within rounding. */
TEST(frames_keep_coplanar_faces_coplanar)
{
    static const char *const framed =
        "multmatrix([[0.816497, 0.408248, 0.408248, 150], [0, 0.707107, -0.707107, 150], "
        "[-0.57735, 0.57735, 0.57735, 0]]) difference() { cube(30, center = true); "
        "cube([40, 10, 10], center = true); cube([10, 40, 10], center = true); "
        "cube([10, 10, 40], center = true); translate([7, 7, 7]) cube(8); }";
    outcome o;
    /* the three bars take 3 x 3000 - 3 x 1000 + 1000 of the cube, the corner [7, 15]^3
     * (flush with three of its faces) 512 more; the six-digit matrix scales volumes by
     * its determinant, 1 - 5.2e-8 */
    double expected = (27000 - 7000 - 512) * 0.9999999482070105;
    if (clean_result(framed, &o)) {
        CHECK_MSG(fabs(o.volume - expected) <= 1e-9 * expected, "volume %.17g, expected %.17g",
                  o.volume, expected);
        CHECK_EQ_SIZE(o.stats.frames_evaluated, 1);
        /* the corner (15, 15, 15), at x = 174.49 once turned, is cut away whole: turned
         * one by one, its faces and the cut's leave a sliver there */
        for (size_t v = 0; v < o.mesh.vertex_count; v++)
            CHECK(o.mesh.vertices[3 * v] < 172);
        CHECK_EQ_SIZE(o.mesh.vertex_count, 46); /* 90 with the flat ones */
    }
    free_outcome(&o);
}

/* The margin of a turn: 2 (error bound of each rounded coordinate) times the norm of the
 * inverse; none for a map that flattens space. */
TEST(turn_margins)
{
    double unit[3] = {1, -1, 1};
    uint32_t tri[3] = {0, 0, 0};
    mcsg_mesh point = {unit, tri, 1, 1};
    const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    const double half[12] = {0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0};
    const double flat[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0};
    const double turn[12] = {0.866025, -0.5, 0, 100, 0.5, 0.866025, 0, 0, 0, 0, 1, 0};
    double m = mci_turn_margin(identity, &point);
    CHECK(m >= 2 * 0x1p-51 && m <= 2 * 0x1p-50 * 1.01);
    /* halving: errors of half the size, an inverse twice as large */
    CHECK(fabs(mci_turn_margin(half, &point) - m) <= 1e-3 * m);
    CHECK(mci_turn_margin(flat, &point) == -1);
    /* the move of 100 dominates the error of the first row (about 100 ulps of 1), and
     * the inverse's norm is cos 30 + sin 30 = 1.366 */
    m = mci_turn_margin(turn, &point);
    CHECK_MSG(m > 1.36 * 100 * 2 * 0x1p-51 && m < 1.37 * 102 * 2 * 0x1p-50, "margin %g", m);
}

/* A leaf that breaks the input contract inside a frame is named as anywhere else. */
TEST(frames_report_bad_leaves)
{
    static const char *const text =
        "rotate(30) { cube(1); polyhedron([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], "
        "[[0, 1, 2], [0, 3, 1], [0, 2, 3]]); }";
    mcsg_tree *tree = read_text(text);
    mcsg_mesh out;
    mcsg_error err;
    if (tree) {
        CHECK(mcsg_eval(tree, NULL, &out, NULL, NULL, &err) == MCSG_ERR_INVALID_MESH);
        CHECK_MSG(strstr(err.message, "polyhedron") && strstr(err.message, "frames.scad:1:"),
                  "%s", err.message);
    }
    mcsg_tree_free(tree);
}

static mcsg_status eval_framed(const void *ctx, const mcsg_options *opts, mcsg_error *err)
{
    const char *text = ctx;
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_provenance *provenance = NULL;
    mcsg_status st = mcsg_scad_read_memory(text, strlen(text), "frames.scad", NULL, opts, &tree,
                                           err);
    if (st == MCSG_OK)
        st = mcsg_eval(tree, opts, &out, &provenance, NULL, err);
    if (st == MCSG_OK) {
        CHECK(fabs(test_signed_volume(&out) - 8) <= 1e-12);
        mcsg_mesh_free(&out, opts);
        mcsg_free(provenance, opts);
    }
    mcsg_tree_free(tree);
    return st;
}

/* The exact predicates' cache (exact/exact_cache.c) only saves work: a failed allocation
 * there is absorbed, so runs may succeed; every other failure must come out as
 * MCSG_ERR_NOMEM with nothing leaked. */
TEST(frames_survive_allocation_failures)
{
    CHECK(test_allocation_failures("frames", eval_framed,
                                   "rotate(30) { difference() { cube(2); cube(1); } "
                                   "translate([5, 0, 0]) rotate([0, 20, 0]) { cube(1); "
                                   "cube(0.5); } }",
                                   true) > 0);
}

int main(void)
{
    RUN(frames_marked_by_the_reader);
    RUN(frames_evaluate_turned_groups);
    RUN(frames_keep_coplanar_faces_coplanar);
    RUN(turn_margins);
    RUN(frames_report_bad_leaves);
    RUN(frames_survive_allocation_failures);
    return test_summary();
}
