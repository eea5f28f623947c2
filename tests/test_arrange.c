/*
 * Per-face arrangements over whole scenes (src/csg/arrange.c, src/csg/intersect.c). For each
 * scene every touched face is triangulated with all its constraints, and then checked
 * exactly:
 *   - tiling: every sub-triangle is positive in its face's orientation, and the count
 *     is that of a triangulation of the face with its points (2 inside + on edges + 1);
 *   - constraints: every elementary edge is an edge of its face's triangulation;
 *   - no T-junctions: each leaf, re-assembled from its faces (sub-triangles numbered by
 *     the scene's global point identity), is closed: every directed edge meets its
 *     reverse exactly once;
 *   - curves on both surfaces: a piece of the curve where faces f and g cross appears,
 *     with the same two points, in both arrangements.
 * Scenes: two boxes, a box and a rotated box, boxes sharing faces (coplanar), boxes
 * touching at an edge and at a vertex, identical spheres, random spheres (triple
 * points), the coplanar plate-and-bars grid.
 */
#include "testlib.h"
#include "csg/intersect.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct scene_case {
    mcsg_tree *tree;
    mcsg_node_id ids[128];
    const mcsg_mesh *leaves[128]; /* resolved once all are added (the tree may move them) */
    size_t leaf_count;
} scene_case;

static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

static void add_leaf(scene_case *c, const mcsg_mesh *mesh, const double *move)
{
    mcsg_error err;
    mcsg_node_id id;
    if (!c->tree)
        CHECK_OK(mcsg_tree_create(NULL, &c->tree, &err), &err);
    CHECK_OK(mcsg_tree_add_leaf(c->tree, mesh, move ? move : identity, NULL, &id, &err), &err);
    c->ids[c->leaf_count++] = id;
}

static void add_box(scene_case *c, double x0, double y0, double z0, double x1, double y1,
                    double z1)
{
    double size[3] = {x1 - x0, y1 - y0, z1 - z0}, move[12];
    mcsg_mesh cube;
    mcsg_error err;
    memcpy(move, identity, sizeof move);
    move[3] = x0, move[7] = y0, move[11] = z0;
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    add_leaf(c, &cube, move);
    mcsg_mesh_free(&cube, NULL);
}

/* ---------------------------------------------------------------------------------- */
/* Checks                                                                              */

static int orient_in_face(const mci_face_arr *arr, uint32_t a, uint32_t b, uint32_t c)
{
    return arr->sign * mci_orient2d_projected(arr->points[a], arr->points[b],
                                              arr->points[c], arr->axis);
}

static bool tri_has_edge(const mci_face_arr *arr, uint32_t a, uint32_t b)
{
    for (size_t t = 0; t < arr->tri_count; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t u = arr->tris[3 * t + i], w = arr->tris[3 * t + (i + 1) % 3];
            if ((u == a && w == b) || (u == b && w == a))
                return true;
        }
    return false;
}

static void check_face_tiling(const mci_face_arr *arr)
{
    size_t inside = 0, on_edges = 0;
    for (size_t p = 3; p < arr->point_count; p++) {
        inside += arr->where[p] == MCI_AT_INSIDE;
        on_edges += arr->where[p] >= MCI_AT_EDGE && arr->where[p] < MCI_AT_INSIDE;
    }
    CHECK_EQ_SIZE(arr->tri_count, 2 * inside + on_edges + 1);
    for (size_t t = 0; t < arr->tri_count; t++) {
        const uint32_t *v = arr->tris + 3 * t;
        CHECK_MSG(orient_in_face(arr, v[0], v[1], v[2]) > 0, "face %u: sub-triangle %zu not "
                  "positive", arr->face, t);
    }
    for (size_t e = 0; e < arr->edge_count; e++)
        CHECK_MSG(tri_has_edge(arr, arr->edges[e].a, arr->edges[e].b),
                  "face %u: edge %zu missing from the triangulation", arr->face, e);
}

typedef struct directed {
    uint32_t u, w;
} directed;

static int compare_directed(const void *x, const void *y)
{
    const directed *a = x, *b = y;
    if (a->u != b->u)
        return (a->u > b->u) - (a->u < b->u);
    return (a->w > b->w) - (a->w < b->w);
}

/* Global number of corner k of face f: through an arrangement holding f's corner, or a
 * fresh number per leaf vertex (vertex_gid caches both). */
static uint32_t corner_gid(const mci_scene *s, uint32_t f, int k, uint32_t *vertex_gid,
                           uint32_t *next)
{
    const mcsg_mesh *m = s->octree.leaves[s->octree.face_leaf[f]];
    uint32_t local = f - s->octree.face_base[s->octree.face_leaf[f]];
    uint32_t v = m->triangles[3 * (size_t)local + (size_t)k];
    if (vertex_gid[v] == MCI_NONE)
        vertex_gid[v] = (*next)++;
    return vertex_gid[v];
}

/* Fill vertex_gid from the arrangements' corners first, checking they agree. */
static void corner_gids_from_arrangements(const mci_scene *s, size_t leaf, uint32_t *vertex_gid)
{
    const mcsg_mesh *m = s->octree.leaves[leaf];
    for (size_t k = 0; k < s->arr_count; k++) {
        const mci_face_arr *arr = &s->arrs[k];
        uint32_t local;
        if (s->octree.face_leaf[arr->face] != leaf)
            continue;
        local = arr->face - s->octree.face_base[leaf];
        for (int i = 0; i < 3; i++) {
            uint32_t v = m->triangles[3 * (size_t)local + (size_t)i];
            uint32_t g = s->gid[s->gid_start[k] + (uint32_t)i];
            CHECK_MSG(vertex_gid[v] == MCI_NONE || vertex_gid[v] == g,
                      "vertex %u has two identities", v);
            vertex_gid[v] = g;
        }
    }
}

static void check_leaf_closed(const mci_scene *s, size_t leaf)
{
    const mcsg_mesh *m = s->octree.leaves[leaf];
    uint32_t *vertex_gid = malloc((m->vertex_count + 1) * sizeof *vertex_gid);
    uint32_t next = (uint32_t)s->point_count, base = s->octree.face_base[leaf];
    directed *edges = NULL;
    size_t n = 0, cap = 0, unmatched = 0;
    for (size_t v = 0; v < m->vertex_count; v++)
        vertex_gid[v] = MCI_NONE;
    corner_gids_from_arrangements(s, leaf, vertex_gid);
    for (uint32_t f = base; f < base + m->triangle_count; f++) {
        uint32_t k = s->arr_of[f], tri[3];
        size_t count = k == MCI_NONE ? 1 : s->arrs[k].tri_count;
        for (size_t t = 0; t < count; t++) {
            for (int i = 0; i < 3; i++)
                tri[i] = k == MCI_NONE ? corner_gid(s, f, i, vertex_gid, &next)
                                       : s->gid[s->gid_start[k] + s->arrs[k].tris[3 * t + i]];
            if (n + 3 > cap) {
                cap = cap ? 2 * cap : 1024;
                edges = realloc(edges, cap * sizeof *edges);
            }
            for (int i = 0; i < 3; i++)
                edges[n++] = (directed){tri[i], tri[(i + 1) % 3]};
        }
    }
    qsort(edges, n, sizeof *edges, compare_directed);
    for (size_t e = 0; e < n; e++) {
        directed rev = {edges[e].w, edges[e].u};
        directed *hit = bsearch(&rev, edges, n, sizeof *edges, compare_directed);
        bool twice = (e > 0 && compare_directed(&edges[e], &edges[e - 1]) == 0);
        unmatched += !hit || twice;
    }
    CHECK_MSG(unmatched == 0, "leaf %zu: %zu directed edges without a unique reverse "
              "(T-junctions or overlaps)", leaf, unmatched);
    free(edges);
    free(vertex_gid);
}

/* Each crossing piece of f (with g) is a piece of g (with f), by global numbers. */
static void check_curves_on_both_surfaces(const mci_scene *s, size_t *pieces)
{
    for (size_t k = 0; k < s->arr_count; k++) {
        const mci_face_arr *arr = &s->arrs[k];
        for (size_t e = 0; e < arr->edge_count; e++) {
            const mci_arr_edge *edge = &arr->edges[e];
            uint32_t a = s->gid[s->gid_start[k] + edge->a], b = s->gid[s->gid_start[k] + edge->b];
            uint32_t j = s->arr_of[edge->other];
            bool found = false;
            if (edge->coplanar)
                continue;
            (*pieces)++;
            for (size_t x = 0; j != MCI_NONE && x < s->arrs[j].edge_count && !found; x++) {
                const mci_arr_edge *o = &s->arrs[j].edges[x];
                uint32_t oa = s->gid[s->gid_start[j] + o->a], ob = s->gid[s->gid_start[j] + o->b];
                found = o->other == arr->face && ((oa == a && ob == b) || (oa == b && ob == a));
            }
            CHECK_MSG(found, "piece %u-%u of face %u x %u missing from face %u", a, b,
                      arr->face, edge->other, edge->other);
        }
    }
}

/* Whether point location `where` is on the closed edge e (corner e to corner e + 1). */
static bool on_closed_edge(uint8_t where, int e)
{
    return where == MCI_AT_EDGE + e || where == MCI_AT_CORNER + e ||
           where == MCI_AT_CORNER + (e + 1) % 3;
}

/* The contacts the pair tests gave each face before it was arranged (arr_contact, read
 * by the whole-face decision) are what its merged arrangement shows: a coplanar face
 * added, and a crossing segment with both ends on one closed edge. count[i]: faces with
 * contact bit i. */
static void check_contacts(const mci_scene *s, size_t count[2])
{
    for (size_t k = 0; k < s->arr_count; k++) {
        const mci_face_arr *arr = &s->arrs[k];
        uint8_t shown = arr->coplanar ? MCI_CONTACT_COPLANAR : 0;
        for (size_t g = 0; g < arr->segment_count; g++)
            for (int e = 0; e < 3 && !arr->segments[g].phantom; e++)
                if (on_closed_edge(arr->where[arr->segments[g].a], e) &&
                    on_closed_edge(arr->where[arr->segments[g].b], e))
                    shown |= MCI_CONTACT_BORDER;
        CHECK_MSG(s->arr_contact[k] == shown, "face %u: contacts %u from the pair tests, %u "
                  "in its arrangement", arr->face, s->arr_contact[k], shown);
        for (int i = 0; i < 2; i++)
            count[i] += (shown >> i) & 1;
    }
}

static void check_scene(scene_case *c, const char *name, bool generic)
{
    mci_ctx ctx;
    mci_scene s;
    mcsg_error err;
    size_t pieces = 0, contacts[2] = {0, 0};
    mci_ctx_init(&ctx, NULL);
    for (size_t i = 0; i < c->leaf_count; i++)
        c->leaves[i] = mcsg_tree_leaf_mesh(c->tree, c->ids[i]);
    /* mci_scene_build's steps, to see the arrangements before splitting frees their
     * segments. */
    CHECK_OK(mci_scene_build_touched(&ctx, c->leaves, c->leaf_count, NULL, NULL, NULL, NULL, &s,
                                     &err),
             &err);
    CHECK_OK(mci_scene_arrange(&ctx, &s, &err), &err);
    check_contacts(&s, contacts);
    CHECK_OK(mci_scene_split(&ctx, &s, NULL, &err), &err);
    CHECK_OK(mci_scene_number_points(&ctx, &s, &err), &err);
    for (size_t k = 0; k < s.arr_count; k++) {
        CHECK_OK(mci_arr_triangulate(&ctx, &s.arrs[k], NULL, &err), &err);
        check_face_tiling(&s.arrs[k]);
    }
    for (size_t leaf = 0; leaf < c->leaf_count; leaf++)
        check_leaf_closed(&s, leaf);
    if (generic)
        check_curves_on_both_surfaces(&s, &pieces);
    printf("  %s: %zu faces, %zu arranged (%zu meet a coplanar face, %zu a surface along an "
           "edge), %zu points, %zu crossing pieces\n", name, s.face_count, s.arr_count,
           contacts[0], contacts[1], s.point_count, pieces);
    mci_scene_free(&ctx, &s);
    mcsg_tree_free(c->tree);
    memset(c, 0, sizeof *c);
}

/* ---------------------------------------------------------------------------------- */
/* Scenes                                                                              */

TEST(two_boxes)
{
    static scene_case c;
    add_box(&c, 0, 0, 0, 1, 1, 1);
    add_box(&c, 0.5, 0.5, 0.5, 1.5, 1.5, 1.5);
    check_scene(&c, "two boxes", true);
}

TEST(box_and_rotated_box)
{
    static scene_case c;
    double size[3] = {2, 2, 2}, c30 = 0.8660254037844386, s30 = 0.5;
    double move[12] = {c30, -s30, 0, 0.3, s30, c30, 0, 0.2, 0, 0, 1, 0.1};
    mcsg_mesh cube;
    mcsg_error err;
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    add_box(&c, -1, -1, -1, 1, 1, 1);
    add_leaf(&c, &cube, move);
    check_scene(&c, "box and rotated box", true);
    mcsg_mesh_free(&cube, NULL);
}

TEST(boxes_sharing_faces)
{
    static scene_case c;
    add_box(&c, 0, 0, 0, 2, 2, 2);
    add_box(&c, 1, 0, 0, 3, 2, 2);     /* overlaps, shares four face planes */
    add_box(&c, 2, 0, 0, 4, 1, 2);     /* touches the first on x = 2, shares planes */
    add_box(&c, 0.5, 0.5, 2, 1.5, 1.5, 3); /* stands on top: a face on a face */
    check_scene(&c, "boxes sharing faces", false);
}

TEST(boxes_touching_at_an_edge_and_a_vertex)
{
    static scene_case c;
    add_box(&c, 0, 0, 0, 1, 1, 1);
    add_box(&c, 1, 1, 0, 2, 2, 1); /* along the edge x = y = 1 */
    add_box(&c, 2, 2, 1, 3, 3, 2); /* at the vertex (2, 2, 1) */
    check_scene(&c, "boxes touching at an edge and a vertex", false);
}

TEST(identical_spheres)
{
    static scene_case c;
    mcsg_mesh sphere;
    mcsg_resolution res = {16, 0, 0};
    mcsg_error err;
    CHECK_OK(mcsg_make_sphere(1.0, res, NULL, &sphere, &err), &err);
    add_leaf(&c, &sphere, NULL);
    add_leaf(&c, &sphere, NULL);
    add_leaf(&c, &sphere, NULL);
    check_scene(&c, "three identical spheres", false);
    mcsg_mesh_free(&sphere, NULL);
}

TEST(random_spheres_with_triple_points)
{
    static scene_case c;
    mcsg_mesh sphere;
    mcsg_resolution res = {12, 0, 0};
    mcsg_error err;
    uint64_t state = 777;
    CHECK_OK(mcsg_make_sphere(1.0, res, NULL, &sphere, &err), &err);
    for (int i = 0; i < 24; i++) {
        double move[12];
        memcpy(move, identity, sizeof move);
        for (int k = 0; k < 3; k++)
            move[4 * k + 3] = (double)test_random_int(&state, 0, 1 << 20) / (1 << 20) * 3;
        add_leaf(&c, &sphere, move);
    }
    check_scene(&c, "24 random spheres", true);
    mcsg_mesh_free(&sphere, NULL);
}

TEST(plate_with_holes_and_bars)
{
    static scene_case c;
    int n = 4;
    add_box(&c, 0, 0, 0, n, n, 1);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            add_box(&c, i + 0.25, j + 0.25, -1, i + 0.75, j + 0.75, 2);
    for (int i = 0; i < n; i++)
        add_box(&c, i, 0, 1, i + 0.25, n, 1.5);
    check_scene(&c, "plate, holes and bars", false);
}

static mcsg_status intersect_run(const void *tree, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_curves curves;
    mcsg_status st = mcsg_intersect(tree, opts, &curves, NULL, err);
    if (st == MCSG_OK) {
        CHECK(curves.segment_count > 0);
        mcsg_curves_free(&curves, opts);
    }
    return st;
}

TEST(allocation_failures_leak_nothing)
{
    static scene_case c;
    add_box(&c, 0, 0, 0, 2, 2, 2);
    add_box(&c, 1, 0, 0, 3, 2, 2);
    add_box(&c, 0.5, 0.5, 0.5, 1.5, 1.5, 2.5);
    CHECK(test_allocation_failures("intersecting boxes", intersect_run, c.tree, false) > 0);
    mcsg_tree_free(c.tree);
    memset(&c, 0, sizeof c);
}

int main(void)
{
    RUN(two_boxes);
    RUN(box_and_rotated_box);
    RUN(boxes_sharing_faces);
    RUN(boxes_touching_at_an_edge_and_a_vertex);
    RUN(identical_spheres);
    RUN(random_spheres_with_triple_points);
    RUN(plate_with_holes_and_bars);
    RUN(allocation_failures_leak_nothing);
    return test_summary();
}
