/*
 * Random CSG trees against an independent membership oracle (see csg_fuzz.h).
 *
 * Each case is a random tree of 5..100 leaves and depth at most 12 drawn from one 64-bit
 * seed, of one of three families:
 *  - free: cubes, spheres, cylinders and cones of low resolution under random rotations
 *    and translations in a region of a few units, sometimes one shared model; some
 *    leaves are exact copies of an earlier leaf, and some take an earlier leaf's exact
 *    placement with another shape (shared vertices, near-coplanar faces);
 *  - grid: axis-aligned boxes with small-integer corners under signed axis permutations
 *    (mirrors included), a few axis-aligned cylinders and spheres on the grid, and exact
 *    copies: coplanar faces, shared edges and vertices everywhere;
 *  - tilted: grid leaves, each under one of a few integer similarity transforms (an
 *    integer quaternion's rotation scaled by its squared norm, 9 or 3): all vertices are
 *    integers, so faces of different leaves in general directions are exactly coplanar.
 * Inner nodes are unions, intersections and differences of 2..4 children.
 *
 * The oracle never looks at the library's geometry code. At a few hundred sample points
 * (uniform in the scene's box, uniform in the result's box, and just off random leaf
 * faces) it computes the generalized winding number of every leaf and of the output mesh
 * (solid angles by van Oosterom and Strackee, in double). A leaf contains the point when
 * its winding number exceeds 1/2; the tree's booleans then say whether the result must
 * contain it, and the output's winding number must be exactly that 0 or 1. Points where
 * any winding number is not within 1e-3 of an integer are too close to a surface for
 * double precision and are skipped, as are points within 2^-40 of the scene's scale of
 * the output's surface (rounding moved it by about a unit in the last place there); at
 * least half of all points must be checked.
 *
 * Besides: mcsg_eval returns MCSG_OK; the output is a valid closed, oriented,
 * edge-manifold mesh (mcsg_mesh_check) or empty, manifold by vertex index too; its
 * volume is not negative and roughly matches the Monte Carlo estimate; its vertices lie
 * in the scene's box; the provenance of every output triangle names a leaf and a face of
 * it whose plane holds the triangle, with the face's orientation reversed exactly when
 * the leaf is subtracted an odd number of times. A result may be edge-non-manifold only
 * where two parts of it can touch exactly along an edge: in grid and tilted trees, and in
 * trees with two copies of a leaf ((A | B) - (A & B) touches itself along the curve where
 * the surfaces of A and B cross), or, in any tree, where rounding joined distinct exact
 * vertices (rounding_joined_vertices; or dropped triangles, after cancelling twins), which
 * can bring two parts together along an edge; there the output must still be manifold by
 * vertex index. Then every edge must still be used as often in each direction (closed
 * and oriented).
 *
 * A failing case is shrunk (a subtree as the whole tree, a child removed, an operation
 * replaced by one of its children) while it still fails, and printed as a CSG file.
 */
#define _POSIX_C_SOURCE 200809L /* open_memstream */
#include "csg_fuzz.h"
#include "testlib.h"

#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define POINTS_PER_TREE 300
#define NEAR_INTEGER 1e-3

static const double PI = 3.14159265358979323846;

/* ---------------------------------------------------------------------------------- */
/* Random numbers                                                                      */

static double uniform(uint64_t *rng) { return (double)(test_xorshift(rng) >> 11) * 0x1p-53; }

static double uniform_in(uint64_t *rng, double lo, double hi)
{
    return lo + (hi - lo) * uniform(rng);
}

/* splitmix64: well-spread, nonzero xorshift states from consecutive case numbers. */
uint64_t csg_mix_seed(uint64_t x)
{
    x += 0x9e3779b97f4a7c15u;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9u;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebu;
    x ^= x >> 31;
    return x ? x : 1;
}

double csg_now(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---------------------------------------------------------------------------------- */
/* Models                                                                              */

typedef struct model {
    const char *name;
    mcsg_mesh mesh;
    double center[3], radius; /* of its bounding box */
} model;

static model models[] = {{"cube.obj", {0}, {0}, 0},
                         {"sphere.obj", {0}, {0}, 0},
                         {"spot.obj", {0}, {0}, 0}};
#define MODEL_COUNT ((int)(sizeof models / sizeof models[0]))
static bool models_loaded;

static bool load_model(model *md)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    mcsg_error err;
    if (mcsg_mesh_read(test_model(md->name), MCSG_FORMAT_AUTO, NULL, &md->mesh,
                       &err) != MCSG_OK)
        return false;
    if (md->mesh.vertex_count == 0) {
        mcsg_mesh_free(&md->mesh, NULL);
        return false;
    }
    for (size_t v = 0; v < md->mesh.vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            double x = md->mesh.vertices[3 * v + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    md->radius = 0;
    for (int k = 0; k < 3; k++) {
        md->center[k] = (lo[k] + hi[k]) / 2;
        md->radius += (hi[k] - lo[k]) * (hi[k] - lo[k]) / 4;
    }
    md->radius = sqrt(md->radius);
    return true;
}

bool csg_load_models(void)
{
    models_loaded = true;
    for (int i = 0; i < MODEL_COUNT; i++)
        models_loaded &= load_model(&models[i]);
    return models_loaded;
}

void csg_free_models(void)
{
    for (int i = 0; i < MODEL_COUNT; i++)
        mcsg_mesh_free(&models[i].mesh, NULL);
    models_loaded = false;
}

const char *csg_model_name(int index) { return models[index].name; }

/* ---------------------------------------------------------------------------------- */
/* Random trees                                                                        */

/* A uniformly random rotation (from a random unit quaternion) into m's 3x3 part. */
static void random_rotation(uint64_t *rng, double m[12])
{
    double u1 = uniform(rng), u2 = 2 * PI * uniform(rng), u3 = 2 * PI * uniform(rng);
    double x = sqrt(1 - u1) * sin(u2), y = sqrt(1 - u1) * cos(u2);
    double z = sqrt(u1) * sin(u3), w = sqrt(u1) * cos(u3);
    m[0] = 1 - 2 * (y * y + z * z), m[1] = 2 * (x * y - z * w), m[2] = 2 * (x * z + y * w);
    m[4] = 2 * (x * y + z * w), m[5] = 1 - 2 * (x * x + z * z), m[6] = 2 * (y * z - x * w);
    m[8] = 2 * (x * z - y * w), m[9] = 2 * (y * z + x * w), m[10] = 1 - 2 * (x * x + y * y);
}

/* A random signed permutation matrix (rotations and mirrors of the axes). */
static void random_axis_map(uint64_t *rng, double m[12])
{
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                    {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    const int *p = perms[test_random_int(rng, 0, 5)];
    memset(m, 0, 12 * sizeof *m);
    for (int row = 0; row < 3; row++)
        m[4 * row + p[row]] = test_random_int(rng, 0, 1) ? 1 : -1;
}

static void place_model(uint64_t *rng, csg_leaf_spec *l)
{
    const model *md = &models[test_random_int(rng, 0, MODEL_COUNT - 1)];
    double s = uniform_in(rng, 1.0, 2.0) / md->radius, c[3];
    l->shape = CSG_MODEL;
    l->model = (int)(md - models);
    for (int row = 0; row < 3; row++) {
        for (int k = 0; k < 3; k++)
            l->m[4 * row + k] *= s;
        c[row] = 0;
    }
    for (int row = 0; row < 3; row++)
        for (int k = 0; k < 3; k++)
            c[row] += l->m[4 * row + k] * md->center[k];
    for (int row = 0; row < 3; row++)
        l->m[4 * row + 3] -= c[row];
}

static void free_shape(uint64_t *rng, csg_leaf_spec *l)
{
    int pick = test_random_int(rng, 0, 99);
    if (pick < 35) {
        l->shape = CSG_CUBE;
        for (int k = 0; k < 3; k++)
            l->size[k] = uniform_in(rng, 0.5, 3.0);
        l->center = test_random_int(rng, 0, 1);
    } else if (pick < 65) {
        l->shape = CSG_SPHERE;
        l->r1 = uniform_in(rng, 0.5, 2.0);
        l->fn = test_random_int(rng, 6, 12);
    } else {
        int cone = test_random_int(rng, 0, 9);
        l->shape = CSG_CYLINDER;
        l->h = uniform_in(rng, 0.5, 3.0);
        l->r1 = uniform_in(rng, 0.3, 1.5);
        l->r2 = cone < 2 ? 0 : cone < 4 ? l->r1 : uniform_in(rng, 0.3, 1.5);
        if (cone == 9) /* upside-down cone */
            l->r2 = l->r1, l->r1 = 0;
        l->center = test_random_int(rng, 0, 1);
        l->fn = test_random_int(rng, 3, 12);
    }
}

void csg_free_leaf(uint64_t *rng, csg_leaf_spec *l)
{
    memset(l, 0, sizeof *l);
    random_rotation(rng, l->m);
    for (int k = 0; k < 3; k++)
        l->m[4 * k + 3] = uniform_in(rng, -1.5, 1.5);
    free_shape(rng, l);
}

/* Axis-aligned leaves with integer (or half-integer) coordinates in [0, 6]^3. */
static void grid_leaf(uint64_t *rng, csg_leaf_spec *l)
{
    int pick = test_random_int(rng, 0, 99);
    double lo[3] = {INFINITY, INFINITY, INFINITY};
    int corner[3];
    memset(l, 0, sizeof *l);
    random_axis_map(rng, l->m);
    for (int k = 0; k < 3; k++)
        corner[k] = test_random_int(rng, 0, 3);
    if (pick < 75) {
        l->shape = CSG_CUBE;
        for (int k = 0; k < 3; k++)
            l->size[k] = test_random_int(rng, 1, 3);
        /* Move the mapped box's lowest corner to `corner`. */
        for (int row = 0; row < 3; row++) {
            lo[row] = 0;
            for (int k = 0; k < 3; k++)
                if (l->m[4 * row + k] < 0)
                    lo[row] -= l->size[k];
            l->m[4 * row + 3] = corner[row] - lo[row];
        }
        return;
    }
    if (pick < 90) {
        static const int fns[] = {3, 4, 4, 6, 8, 12};
        l->shape = CSG_CYLINDER;
        l->h = test_random_int(rng, 1, 3);
        l->r1 = 0.5 * test_random_int(rng, 1, 4);
        l->r2 = test_random_int(rng, 0, 3) == 0 ? 0 : l->r1;
        l->center = test_random_int(rng, 0, 1);
        l->fn = fns[test_random_int(rng, 0, 5)];
    } else {
        l->shape = CSG_SPHERE;
        l->r1 = 0.5 * test_random_int(rng, 2, 4);
        l->fn = 4 + 2 * test_random_int(rng, 0, 2);
    }
    for (int row = 0; row < 3; row++)
        l->m[4 * row + 3] = corner[row] + 1;
}

/* The rotation of the integer quaternion (w, x, y, z) scaled by w^2 + x^2 + y^2 + z^2:
 * an integer matrix, exact in doubles. */
static void integer_rotation(const int q[4], double r[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = w * w + x * x - y * y - z * z, r[1] = 2 * (x * y - w * z), r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z), r[4] = w * w - x * x + y * y - z * z, r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y), r[7] = 2 * (y * z + w * x), r[8] = w * w - x * x - y * y + z * z;
}

/* A grid leaf mapped by an integer similarity (norm 9: (1,2,2,0) and its relatives, or
 * norm 3: (1,1,1,0)). Grid coordinates are multiples of 1/2 and the matrix entries are
 * integers, so every vertex is exact and shared planes stay shared. */
static void tilted_leaf(uint64_t *rng, csg_leaf_spec *l, int family_choice)
{
    static const int quats[2][3][4] = {{{1, 2, 2, 0}, {2, 1, 0, 2}, {0, 2, 1, 2}},
                                       {{1, 1, 1, 0}, {1, 0, 1, 1}, {0, 1, 1, 1}}};
    double r[9], m[12];
    grid_leaf(rng, l);
    integer_rotation(quats[family_choice][test_random_int(rng, 0, 2)], r);
    memcpy(m, l->m, sizeof m);
    for (int row = 0; row < 3; row++)
        for (int col = 0; col < 4; col++)
            l->m[4 * row + col] = r[3 * row] * m[col] + r[3 * row + 1] * m[4 + col] +
                                  r[3 * row + 2] * m[8 + col];
}

/* x with six significant digits, as OpenSCAD's .csg export writes it. */
static double six_digits(double x)
{
    char text[32];
    snprintf(text, sizeof text, "%.6g", x);
    return strtod(text, NULL);
}

/* The placement shared by an export tree's leaves: a turn about the z axis and then the x
 * axis by multiples of 15 degrees (45 often), and an offset far from the origin. */
typedef struct export_frame {
    double r[9], offset[3];
    int style; /* 0: Menger-like boxes, 1: turned cubes, 2: a drilled plate */
} export_frame;

static void export_frame_init(uint64_t *rng, export_frame *f)
{
    static const double far[][3] = {{0, 0, 0}, {150, 150, 0}, {1000, -2000, 500}};
    double a = PI / 12 * test_random_int(rng, 0, 23), b = PI / 4 * test_random_int(rng, 0, 3);
    double ca = cos(a), sa = sin(a), cb = cos(b), sb = sin(b);
    double rz[9] = {ca, -sa, 0, sa, ca, 0, 0, 0, 1};
    for (int i = 0; i < 3; i++) { /* rx(b) * rz(a) */
        f->r[i] = rz[i];
        f->r[3 + i] = cb * rz[3 + i] - sb * rz[6 + i];
        f->r[6 + i] = sb * rz[3 + i] + cb * rz[6 + i];
    }
    memcpy(f->offset, far[test_random_int(rng, 0, 2)], sizeof f->offset);
    f->style = test_random_int(rng, 0, 2);
}

/* A local placement (rotation `turn`, translation t) composed with the frame (unless the
 * frame is written around the tree), every entry written with six digits. */
static void export_place(const export_frame *f, bool framed, const double turn[9],
                         const double t[3], double m[12])
{
    static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double *r = framed ? identity : f->r;
    for (int row = 0; row < 3; row++) {
        double moved = framed ? 0 : f->offset[row];
        for (int col = 0; col < 3; col++) {
            double e = 0;
            for (int k = 0; k < 3; k++)
                e += r[3 * row + k] * turn[3 * k + col];
            m[4 * row + col] = six_digits(e);
            moved += r[3 * row + col] * t[col];
        }
        m[4 * row + 3] = six_digits(moved);
    }
}

/* Leaves come in groups of EXPORT_GROUP around one centre, the groups side by side on a
 * grid, overlapping their neighbours: a group is one feature of a part (a sponge, a star
 * of turned cubes, a drilled plate). One group of 65 concentric turned cubes makes an
 * arrangement of 2 million pieces; parts are not built like that. */
#define EXPORT_GROUP 6

static void export_group_centre(const export_frame *f, int leaf, double t[3])
{
    static const double spacing[] = {110, 40, 100};
    int group = leaf / EXPORT_GROUP;
    t[0] = spacing[f->style] * (group % 4);
    t[1] = spacing[f->style] * (group / 4);
    t[2] = 0;
}

static void export_leaf(uint64_t *rng, const export_frame *f, bool framed, int index,
                        csg_leaf_spec *l)
{
    static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double turn[9], t[3] = {0, 0, 0}, centre[3], side = 100.0 / 3;
    memcpy(turn, identity, sizeof turn);
    memset(l, 0, sizeof *l);
    l->shape = CSG_CUBE;
    l->center = 1;
    if (f->style == 0) { /* a beam of a Menger sponge's level 1 to 3, along some axis */
        int level = test_random_int(rng, 1, 3), axis = test_random_int(rng, 0, 2);
        double l3 = 100.0;
        for (int k = 0; k < level; k++)
            l3 /= 3;
        for (int k = 0; k < 3; k++)
            l->size[k] = six_digits(k == axis ? 110.0 : l3);
        for (int k = 0; k < 3; k++)
            if (k != axis)
                t[k] = six_digits(l3 * 3 * test_random_int(rng, -1, 1) +
                                  (level > 1 ? side * test_random_int(rng, -1, 1) : 0));
        if (test_random_int(rng, 0, 5) == 0) /* the sponge's cube itself */
            l->size[0] = l->size[1] = l->size[2] = 100, t[0] = t[1] = t[2] = 0;
    } else if (f->style == 1) { /* cubes turned about one axis by 15k degrees */
        double a = PI / 12 * test_random_int(rng, 0, 11), c = cos(a), s = sin(a);
        int axis = test_random_int(rng, 0, 2), i = (axis + 1) % 3, j = (axis + 2) % 3;
        turn[3 * i + i] = c, turn[3 * i + j] = -s, turn[3 * j + i] = s, turn[3 * j + j] = c;
        for (int k = 0; k < 3; k++)
            l->size[k] = six_digits(test_random_int(rng, 0, 1) ? 50.0 : 45.0);
    } else { /* a plate, or a cylinder drilled through it */
        if (test_random_int(rng, 0, 4) == 0) {
            l->size[0] = l->size[1] = 100, l->size[2] = 10;
        } else {
            l->shape = CSG_CYLINDER;
            l->h = 30;
            l->r1 = l->r2 = six_digits(side / test_random_int(rng, 3, 9));
            l->fn = test_random_int(rng, 6, 24);
            t[0] = six_digits(side * test_random_int(rng, -1, 1) / test_random_int(rng, 1, 3));
            t[1] = six_digits(side * test_random_int(rng, -1, 1) / test_random_int(rng, 1, 3));
        }
    }
    export_group_centre(f, index, centre);
    for (int k = 0; k < 3; k++)
        t[k] += centre[k];
    export_place(f, framed, turn, t, l->m);
}

/* The frame as one six-digit matrix, for the multmatrix written around the tree. */
static void export_frame_matrix(const export_frame *f, double m[12])
{
    for (int row = 0; row < 3; row++) {
        for (int col = 0; col < 3; col++)
            m[4 * row + col] = six_digits(f->r[3 * row + col]);
        m[4 * row + 3] = six_digits(f->offset[row]);
    }
}

static void random_leaves(csg_tree_spec *t, uint64_t *rng)
{
    int model_leaf = -1, tilt = test_random_int(rng, 0, 1);
    export_frame frame;
    if (t->family == CSG_EXPORT) {
        export_frame_init(rng, &frame);
        /* a bit of the seed, not a draw: the other half's trees stay as they were */
        t->framed = (t->seed >> 7) & 1;
        if (t->framed)
            export_frame_matrix(&frame, t->frame);
    }
    if (t->family == CSG_FREE && models_loaded && test_random_int(rng, 0, 2) == 0)
        model_leaf = test_random_int(rng, 0, t->leaf_count - 1);
    for (int i = 0; i < t->leaf_count; i++) {
        csg_leaf_spec *l = &t->leaves[i];
        int copy = i > 0 ? test_random_int(rng, 0, 9) : 9;
        if (i != model_leaf && copy == 0) {
            *l = t->leaves[test_random_int(rng, 0, i - 1)]; /* an exact copy */
        } else if (t->family == CSG_GRID) {
            grid_leaf(rng, l);
        } else if (t->family == CSG_TILTED) {
            tilted_leaf(rng, l, tilt);
        } else if (t->family == CSG_EXPORT) {
            export_leaf(rng, &frame, t->framed, i, l);
        } else if (i == model_leaf) {
            csg_free_leaf(rng, l);
            place_model(rng, l);
        } else if (copy == 1 && t->leaves[i - 1].shape != CSG_MODEL) {
            /* Another shape at the previous leaf's exact placement. */
            *l = t->leaves[i - 1];
            free_shape(rng, l);
        } else {
            csg_free_leaf(rng, l);
        }
        t->nodes[i].kind = MCSG_NODE_LEAF;
        t->nodes[i].leaf = i;
    }
}

/* Joins the pending nodes into operations until one is left. Left-deep chains (take
 * the first pending nodes) or random groups; a group that would exceed the depth limit
 * is taken from the shallowest pending nodes instead. The limit is a target, not a
 * guarantee: when only deep nodes are left to join, the tree can be a level deeper. */
static void random_operations(csg_tree_spec *t, uint64_t *rng)
{
    int pending[CSG_MAX_LEAVES], depth[CSG_MAX_NODES] = {0}, count = t->leaf_count;
    bool chain = test_random_int(rng, 0, 3) == 0;
    for (int i = 0; i < count; i++)
        pending[i] = i;
    t->node_count = t->leaf_count;
    while (count > 1) {
        int take = test_random_int(rng, 2, count < CSG_MAX_CHILDREN ? count : CSG_MAX_CHILDREN);
        int op = test_random_int(rng, 0, 99), at, deepest = 0;
        csg_node_spec *n = &t->nodes[t->node_count];
        n->kind = op < 50   ? MCSG_NODE_UNION
                  : op < 75 ? MCSG_NODE_DIFFERENCE
                            : MCSG_NODE_INTERSECTION;
        /* Mostly two operands for the shrinking operations, or little would be left. */
        if (n->kind != MCSG_NODE_UNION && test_random_int(rng, 0, 3) != 0)
            take = 2;
        /* Chains stop growing a few levels below the limit, so that the last joins of
         * deep pending nodes still fit under it. */
        if (chain && depth[pending[0]] >= CSG_MAX_DEPTH - 3)
            chain = false;
        at = chain ? 0 : test_random_int(rng, 0, count - take);
        for (int c = 0; c < take; c++)
            deepest = depth[pending[at + c]] > deepest ? depth[pending[at + c]] : deepest;
        if (deepest + 1 > CSG_MAX_DEPTH) {
            /* The window of `take` pending nodes with the smallest maximal depth. */
            int best = INT32_MAX;
            for (int a = 0; a + take <= count; a++) {
                int d = 0;
                for (int c = 0; c < take; c++)
                    d = depth[pending[a + c]] > d ? depth[pending[a + c]] : d;
                if (d < best)
                    best = d, at = a;
            }
            deepest = best;
        }
        n->child_count = take;
        memcpy(n->children, pending + at, (size_t)take * sizeof *pending);
        depth[t->node_count] = deepest + 1;
        pending[at] = t->node_count++;
        memmove(pending + at + 1, pending + at + take,
                (size_t)(count - at - take) * sizeof *pending);
        count -= take - 1;
    }
    t->root = pending[0];
}

/* Inner shells for the primitives of a free tree (not its models), drawn from a stream of
 * their own so that the tree is otherwise the free tree of the same seed. */
static void add_shells(csg_tree_spec *t)
{
    uint64_t rng = csg_mix_seed(t->seed ^ 0x5be11);
    for (int i = 0; i < t->leaf_count; i++) {
        csg_leaf_spec *l = &t->leaves[i];
        if (l->shape == CSG_MODEL || test_random_int(&rng, 0, 2) == 0)
            continue;
        l->inner = test_random_int(&rng, 0, 2);
        l->inner_scale[0] = uniform_in(&rng, 0.3, 0.8);
        l->inner_scale[1] = l->inner_scale[0] * uniform_in(&rng, 0.3, 0.8);
        for (int k = 0; k < 3; k++)
            l->inward[k] = test_random_int(&rng, 0, 2) == 0;
        for (int k = 0; k < 2; k++)
            if (test_random_int(&rng, 0, 1)) /* crossing the primitive, or the other copy */
                for (int axis = 0; axis < 3; axis++)
                    l->inner_shift[k][axis] = uniform_in(&rng, -0.6, 0.6);
    }
}

/* Exact copies (the same shell, or glued along a face, an edge or a corner) and pushed
 * corners for the primitives of a free tree, from a stream of their own. */
static void add_folds(csg_tree_spec *t)
{
    uint64_t rng = csg_mix_seed(t->seed ^ 0xf01d5);
    for (int i = 0; i < t->leaf_count; i++) {
        csg_leaf_spec *l = &t->leaves[i];
        if (l->shape == CSG_MODEL || test_random_int(&rng, 0, 1) == 0)
            continue;
        l->inner = test_random_int(&rng, 0, 2);
        l->pushed = test_random_int(&rng, 0, 2) == 0;
        for (int k = 0; k < 3; k++)
            l->inward[k] = test_random_int(&rng, 0, 3) == 0;
        for (int k = 0; k < l->inner; k++) {
            int axes = test_random_int(&rng, 0, 3); /* 0: the same shell again */
            l->exact_copy[k] = true;
            l->inner_scale[k] = 1;
            for (int a = 0; a < axes; a++) { /* the sign first, as gcc drew them */
                double sign = test_random_int(&rng, 0, 1) ? 1 : -1;
                l->inner_shift[k][test_random_int(&rng, 0, 2)] = sign;
            }
        }
    }
}

void csg_random_tree(csg_tree_spec *t, uint64_t seed)
{
    uint64_t rng = seed;
    int family = test_random_int(&rng, 0, 7);
    memset(t, 0, sizeof *t);
    t->seed = seed;
    t->family = family < 3   ? CSG_FREE
                : family < 5 ? CSG_GRID
                : family < 6 ? CSG_TILTED
                             : CSG_EXPORT;
    /* 5..100 leaves, small trees more often than large ones (cost grows with size). */
    t->leaf_count = 5 + (int)((CSG_MAX_LEAVES - 5 + 1) * pow(uniform(&rng), 3.0));
    random_leaves(t, &rng);
    random_operations(t, &rng);
    if (t->family == CSG_FREE && csg_mix_seed(seed) % 6 < 2) {
        t->family = csg_mix_seed(seed) % 6 == 0 ? CSG_SHELLS : CSG_FOLDS;
        if (t->family == CSG_SHELLS)
            add_shells(t);
        else
            add_folds(t);
    }
}

/* reach[i]: node i is in the tree. */
static void reachable(const csg_tree_spec *t, bool reach[CSG_MAX_NODES])
{
    memset(reach, 0, CSG_MAX_NODES * sizeof *reach);
    reach[t->root] = true;
    for (int i = t->root; i >= 0; i--)
        if (reach[i])
            for (int c = 0; c < t->nodes[i].child_count; c++)
                reach[t->nodes[i].children[c]] = true;
}

int csg_reachable_leaves(const csg_tree_spec *t)
{
    bool reach[CSG_MAX_NODES];
    int n = 0;
    reachable(t, reach);
    for (int i = 0; i < t->node_count; i++)
        n += reach[i] && t->nodes[i].kind == MCSG_NODE_LEAF;
    return n;
}

/* Whether two leaves of the tree are exact copies. Then the result may touch itself
 * along edges even in general position: (A | B) - (A & B) is non-manifold along the
 * curve where the surfaces of A and B cross. */
/* Two leaves with the same primitive at the same place (in the shells family their inner
 * shells and orientations may differ: the outer surfaces still coincide). */
static bool same_primitive(const csg_leaf_spec *a, const csg_leaf_spec *b)
{
    csg_leaf_spec x = *a, y = *b;
    x.inner = y.inner = 0;
    memset(x.inner_scale, 0, sizeof x.inner_scale);
    memset(y.inner_scale, 0, sizeof y.inner_scale);
    memset(x.inner_shift, 0, sizeof x.inner_shift);
    memset(y.inner_shift, 0, sizeof y.inner_shift);
    memset(x.inward, 0, sizeof x.inward);
    memset(y.inward, 0, sizeof y.inward);
    memset(x.exact_copy, 0, sizeof x.exact_copy);
    memset(y.exact_copy, 0, sizeof y.exact_copy);
    return memcmp(&x, &y, sizeof x) == 0;
}

static bool has_copies(const csg_tree_spec *t)
{
    bool reach[CSG_MAX_NODES];
    reachable(t, reach);
    for (int i = 0; i < t->node_count; i++)
        for (int j = 0; j < i; j++)
            if (reach[i] && reach[j] && t->nodes[i].kind == MCSG_NODE_LEAF &&
                t->nodes[j].kind == MCSG_NODE_LEAF &&
                same_primitive(&t->leaves[t->nodes[i].leaf], &t->leaves[t->nodes[j].leaf]))
                return true;
    return false;
}

/* Solids of the tree may touch: exact copies, or placements on a grid. */
static bool touching_allowed(const csg_tree_spec *t)
{
    return (t->family != CSG_FREE && t->family != CSG_SHELLS) || has_copies(t);
}

/* The folds family's leaves may cross themselves: their shells are tested first. */
static bool check_inputs(const csg_tree_spec *t)
{
    return t->family == CSG_FOLDS;
}

static mcsg_status make_primitive_mesh(const csg_leaf_spec *l, mcsg_mesh *out, mcsg_error *err)
{
    mcsg_resolution res = {l->fn, 0, 0};
    switch (l->shape) {
    case CSG_CUBE:
        return mcsg_make_cube(l->size, l->center, NULL, out, err);
    case CSG_SPHERE:
        return mcsg_make_sphere(l->r1, res, NULL, out, err);
    case CSG_CYLINDER:
        return mcsg_make_cylinder(l->h, l->r1, l->r2, l->center, res, NULL, out, err);
    case CSG_MODEL:
        break;
    }
    return mcsg_mesh_copy(&models[l->model].mesh, NULL, out, err);
}

/* Shell k of the leaf (0: the primitive, else its copy k - 1 scaled about the box
 * centre c and moved by its shift times the box size) written at vertex `base` and
 * triangle `tri` of out. */
static void write_shell(const csg_leaf_spec *l, const mcsg_mesh *m, const double c[3],
                        const double size[3], int k, mcsg_mesh *out)
{
    double s = k == 0 ? 1 : l->inner_scale[k - 1];
    const double *shift = k == 0 ? NULL : l->inner_shift[k - 1];
    bool exact = k > 0 && l->exact_copy[k - 1];
    size_t base = (size_t)k * m->vertex_count, tri = (size_t)k * m->triangle_count;
    for (size_t v = 0; v < 3 * m->vertex_count; v++)
        out->vertices[3 * base + v] =
            k == 0  ? m->vertices[v]
            : exact ? m->vertices[v] + shift[v % 3] * size[v % 3]
                    : c[v % 3] + s * (m->vertices[v] - c[v % 3]) + shift[v % 3] * size[v % 3];
    for (size_t t = 0; t < m->triangle_count; t++)
        for (int i = 0; i < 3; i++)
            out->triangles[3 * (tri + t) + (size_t)i] =
                (uint32_t)base + m->triangles[3 * t + (size_t)(l->inward[k] ? (3 - i) % 3 : i)];
}

/* The primitive and its inner copies in one mesh. */
static mcsg_status make_leaf_mesh(const csg_leaf_spec *l, mcsg_mesh *out, mcsg_error *err)
{
    mcsg_mesh m;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double c[3], size[3];
    mcsg_status st = make_primitive_mesh(l, &m, err);
    int shells = 1 + l->inner;
    if (st != MCSG_OK || (l->inner == 0 && !l->inward[0] && !l->pushed)) {
        *out = m;
        return st;
    }
    for (size_t v = 0; v < 3 * m.vertex_count; v++) {
        lo[v % 3] = fmin(lo[v % 3], m.vertices[v]);
        hi[v % 3] = fmax(hi[v % 3], m.vertices[v]);
    }
    for (int k = 0; k < 3; k++) {
        c[k] = (lo[k] + hi[k]) / 2;
        size[k] = hi[k] - lo[k];
    }
    for (int k = 0; l->pushed && k < 3; k++) /* through the centre, past the far side */
        m.vertices[k] = c[k] - 1.25 * (m.vertices[k] - c[k]);
    out->vertex_count = (size_t)shells * m.vertex_count;
    out->triangle_count = (size_t)shells * m.triangle_count;
    out->vertices = malloc(3 * out->vertex_count * sizeof *out->vertices);
    out->triangles = malloc(3 * out->triangle_count * sizeof *out->triangles);
    if (!out->vertices || !out->triangles) { /* mcsg_mesh_free frees with free() */
        mcsg_mesh_free(out, NULL);
        mcsg_mesh_free(&m, NULL);
        if (err) {
            err->status = MCSG_ERR_NOMEM;
            snprintf(err->message, sizeof err->message, "out of memory");
        }
        return MCSG_ERR_NOMEM;
    }
    for (int k = 0; k < shells; k++)
        write_shell(l, &m, c, size, k, out);
    mcsg_mesh_free(&m, NULL);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Printing a case as a CSG file                                                       */

static void print_indent(FILE *f, int depth)
{
    for (int i = 0; i < depth; i++)
        fputs("  ", f);
}

/* A leaf with shells as a polyhedron (OpenSCAD lists faces clockwise from outside). */
static void print_polyhedron(FILE *f, const csg_leaf_spec *l)
{
    mcsg_mesh m;
    mcsg_error err;
    if (make_leaf_mesh(l, &m, &err) != MCSG_OK) {
        fprintf(f, "// %s\n", err.message);
        return;
    }
    fputs("polyhedron(points = [", f);
    for (size_t v = 0; v < m.vertex_count; v++)
        fprintf(f, "%s[%.17g, %.17g, %.17g]", v ? ", " : "", m.vertices[3 * v],
                m.vertices[3 * v + 1], m.vertices[3 * v + 2]);
    fputs("], faces = [", f);
    for (size_t t = 0; t < m.triangle_count; t++)
        fprintf(f, "%s[%u, %u, %u]", t ? ", " : "", m.triangles[3 * t], m.triangles[3 * t + 2],
                m.triangles[3 * t + 1]);
    fputs("]);\n", f);
    mcsg_mesh_free(&m, NULL);
}

static void print_leaf(FILE *f, const csg_leaf_spec *l)
{
    const double *m = l->m;
    fprintf(f, "multmatrix([[%.17g, %.17g, %.17g, %.17g], [%.17g, %.17g, %.17g, %.17g], "
               "[%.17g, %.17g, %.17g, %.17g], [0, 0, 0, 1]]) ",
            m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11]);
    if (l->inner > 0 || l->inward[0] || l->pushed) {
        print_polyhedron(f, l);
        return;
    }
    switch (l->shape) {
    case CSG_CUBE:
        fprintf(f, "cube([%.17g, %.17g, %.17g], center = %s);\n", l->size[0], l->size[1],
                l->size[2], l->center ? "true" : "false");
        break;
    case CSG_SPHERE:
        fprintf(f, "sphere(r = %.17g, $fn = %d);\n", l->r1, l->fn);
        break;
    case CSG_CYLINDER:
        fprintf(f, "cylinder(h = %.17g, r1 = %.17g, r2 = %.17g, center = %s, $fn = %d);\n",
                l->h, l->r1, l->r2, l->center ? "true" : "false", l->fn);
        break;
    case CSG_MODEL:
        fprintf(f, "import(\"%s\");\n", models[l->model].name);
        break;
    }
}

static void print_node(FILE *f, const csg_tree_spec *t, int node, int depth)
{
    const csg_node_spec *n = &t->nodes[node];
    print_indent(f, depth);
    if (n->kind == MCSG_NODE_LEAF) {
        print_leaf(f, &t->leaves[n->leaf]);
        return;
    }
    fprintf(f, "%s() {\n", n->kind == MCSG_NODE_UNION          ? "union"
                           : n->kind == MCSG_NODE_INTERSECTION ? "intersection"
                                                               : "difference");
    for (int c = 0; c < n->child_count; c++)
        print_node(f, t, n->children[c], depth + 1);
    print_indent(f, depth);
    fputs("}\n", f);
}

/* The tree, inside its frame's multmatrix when it has one. */
static void print_tree(FILE *f, const csg_tree_spec *t)
{
    if (t->framed) {
        const double *m = t->frame;
        fprintf(f, "multmatrix([[%.17g, %.17g, %.17g, %.17g], [%.17g, %.17g, %.17g, %.17g], "
                   "[%.17g, %.17g, %.17g, %.17g], [0, 0, 0, 1]]) {\n",
                m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10], m[11]);
    }
    print_node(f, t, t->root, t->framed ? 1 : 0);
    if (t->framed)
        fputs("}\n", f);
}

const char *const csg_family_names[CSG_FAMILIES] = {"free",   "grid",   "tilted",
                                                    "export", "shells", "folds"};

void csg_print_case(FILE *f, const csg_tree_spec *t, bool with_provenance)
{
    fprintf(f, "// fuzz-csg: seed 0x%016" PRIx64 " family %s touching %s provenance %s; "
            "%d leaves\n", t->seed, csg_family_names[t->family],
            touching_allowed(t) ? "yes" : "no", with_provenance ? "yes" : "no",
            csg_reachable_leaves(t));
    print_tree(f, t);
}

bool csg_read_header(const char *text, uint64_t *seed, bool *touching, bool *with_provenance,
                     bool *check_inputs)
{
    char family[16], touch[8], prov[8];
    if (sscanf(text, "// fuzz-csg: seed %" SCNx64 " family %15s touching %7s provenance %7[a-z]",
               seed, family, touch, prov) != 4)
        return false;
    *touching = strcmp(touch, "yes") == 0;
    *with_provenance = strcmp(prov, "yes") == 0;
    *check_inputs = strcmp(family, csg_family_names[CSG_FOLDS]) == 0;
    return true;
}

/* ---------------------------------------------------------------------------------- */
/* Geometry for the oracle                                                             */

typedef struct box {
    double lo[3], hi[3];
} box;

static box empty_box(void)
{
    box b = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    return b;
}

static void box_add_mesh(box *b, const mcsg_mesh *m)
{
    for (size_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            double x = m->vertices[3 * v + k];
            b->lo[k] = x < b->lo[k] ? x : b->lo[k];
            b->hi[k] = x > b->hi[k] ? x : b->hi[k];
        }
}

static bool box_contains(const box *b, const double p[3])
{
    return p[0] >= b->lo[0] && p[0] <= b->hi[0] && p[1] >= b->lo[1] && p[1] <= b->hi[1] &&
           p[2] >= b->lo[2] && p[2] <= b->hi[2];
}

static void box_sample(uint64_t *rng, const box *b, double p[3])
{
    for (int k = 0; k < 3; k++)
        p[k] = uniform_in(rng, b->lo[k], b->hi[k]);
}

static double box_volume(const box *b)
{
    return (b->hi[0] - b->lo[0]) * (b->hi[1] - b->lo[1]) * (b->hi[2] - b->lo[2]);
}

/* Solid angle of triangle abc seen from p (van Oosterom and Strackee 1983). */
static double solid_angle(const double *a, const double *b, const double *c, const double *p)
{
    double ax = a[0] - p[0], ay = a[1] - p[1], az = a[2] - p[2];
    double bx = b[0] - p[0], by = b[1] - p[1], bz = b[2] - p[2];
    double cx = c[0] - p[0], cy = c[1] - p[1], cz = c[2] - p[2];
    double la = sqrt(ax * ax + ay * ay + az * az), lb = sqrt(bx * bx + by * by + bz * bz);
    double lc = sqrt(cx * cx + cy * cy + cz * cz);
    double det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
    double den = la * lb * lc + (ax * bx + ay * by + az * bz) * lc +
                 (ax * cx + ay * cy + az * cz) * lb + (bx * cx + by * cy + bz * cz) * la;
    return 2 * atan2(det, den);
}

/* Generalized winding number of a mesh at p; exactly 0 outside its bounding box. */
static double winding(const mcsg_mesh *m, const box *b, const double p[3])
{
    double sum = 0;
    if (!box_contains(b, p))
        return 0;
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        sum += solid_angle(m->vertices + 3 * tri[0], m->vertices + 3 * tri[1],
                           m->vertices + 3 * tri[2], p);
    }
    return sum / (4 * PI);
}

static bool near_integer(double w) { return fabs(w - nearbyint(w)) < NEAR_INTEGER; }

static double distance_to_plane(const double *a, const double *b, const double *c,
                                const double p[3]);

/* Whether p lies within `reach` of a triangle of m (its plane, inside the triangle's box
 * grown by reach): rounding to doubles moves the output's vertices by about a unit in the
 * last place, so which side such a point is on says nothing about the evaluation. */
static bool near_surface(const mcsg_mesh *m, const double p[3], double reach)
{
    for (size_t t = 0; t < m->triangle_count; t++) {
        const double *v[3];
        bool in_box = true;
        for (int c = 0; c < 3; c++)
            v[c] = m->vertices + 3 * (size_t)m->triangles[3 * t + (size_t)c];
        for (int k = 0; k < 3 && in_box; k++)
            in_box = p[k] >= fmin(v[0][k], fmin(v[1][k], v[2][k])) - reach &&
                     p[k] <= fmax(v[0][k], fmax(v[1][k], v[2][k])) + reach;
        if (in_box && distance_to_plane(v[0], v[1], v[2], p) <= reach)
            return true;
    }
    return false;
}

static void cross(const double u[3], const double v[3], double out[3])
{
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
}

static double dot(const double u[3], const double v[3])
{
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

static double norm(const double u[3]) { return sqrt(dot(u, u)); }

/* Distance from p to the plane of abc (infinite when abc has no area in double). */
static double distance_to_plane(const double *a, const double *b, const double *c,
                                const double p[3])
{
    double u[3], v[3], n[3], w[3], len;
    for (int k = 0; k < 3; k++)
        u[k] = b[k] - a[k], v[k] = c[k] - a[k], w[k] = p[k] - a[k];
    cross(u, v, n);
    len = norm(n);
    return len > 0 ? fabs(dot(n, w)) / len : INFINITY;
}

static void sub(const double *u, const double *v, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = u[k] - v[k];
}

/* Area normal (twice the area, outward for a counter-clockwise triangle). */
static void triangle_normal(const mcsg_mesh *m, size_t t, double n[3])
{
    const uint32_t *tri = m->triangles + 3 * t;
    double u[3], v[3];
    sub(m->vertices + 3 * tri[1], m->vertices + 3 * tri[0], u);
    sub(m->vertices + 3 * tri[2], m->vertices + 3 * tri[0], v);
    cross(u, v, n);
}

/* ---------------------------------------------------------------------------------- */
/* Edge balance: closed and oriented, allowing edges shared by four or more faces       */

static const double *sort_coords;

static int compare_vertices(const void *a, const void *b)
{
    const double *p = sort_coords + 3 * *(const uint32_t *)a;
    const double *q = sort_coords + 3 * *(const uint32_t *)b;
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

typedef struct edge_key {
    uint32_t lo, hi;
    int dir;
} edge_key;

static int compare_edges(const void *a, const void *b)
{
    const edge_key *e = a, *f = b;
    if (e->lo != f->lo)
        return e->lo < f->lo ? -1 : 1;
    if (e->hi != f->hi)
        return e->hi < f->hi ? -1 : 1;
    return 0;
}

/* Number of edges (vertices identified by coordinates) not used equally often in both
 * directions; *shared receives the number used by more than two triangles. */
static size_t unbalanced_edges(const mcsg_mesh *m, size_t *shared)
{
    size_t nv = m->vertex_count, ne = 3 * m->triangle_count, bad = 0;
    uint32_t *order = malloc((nv + 1) * sizeof *order), *canon = malloc((nv + 1) * sizeof *canon);
    edge_key *edges = malloc((ne + 1) * sizeof *edges);
    *shared = 0;
    for (uint32_t v = 0; v < nv; v++)
        order[v] = v;
    sort_coords = m->vertices;
    qsort(order, nv, sizeof *order, compare_vertices);
    for (size_t i = 0; i < nv; i++)
        canon[order[i]] = i > 0 && compare_vertices(&order[i - 1], &order[i]) == 0
                              ? canon[order[i - 1]]
                              : order[i];
    for (size_t t = 0; t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t a = canon[m->triangles[3 * t + k]];
            uint32_t b = canon[m->triangles[3 * t + (k + 1) % 3]];
            edge_key *e = &edges[3 * t + (size_t)k];
            e->lo = a < b ? a : b;
            e->hi = a < b ? b : a;
            e->dir = a < b ? 1 : -1;
        }
    qsort(edges, ne, sizeof *edges, compare_edges);
    for (size_t i = 0, j; i < ne; i = j) {
        int sum = 0;
        for (j = i; j < ne && compare_edges(&edges[i], &edges[j]) == 0; j++)
            sum += edges[j].dir;
        bad += sum != 0;
        *shared += j - i > 2;
    }
    free(order);
    free(canon);
    free(edges);
    return bad;
}

/* ---------------------------------------------------------------------------------- */
/* One case                                                                            */

static bool fail(csg_result *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->why, sizeof r->why, fmt, ap);
    va_end(ap);
    return false;
}

/* What the oracle knows of a tree: per node, the bounding box of a leaf and whether the
 * node is subtracted an odd number of times on the way from the root. */
typedef struct tree_facts {
    const mcsg_tree *tree;
    size_t node_count;
    box *leaf_box;
    int *polarity;
    bool *reach;
} tree_facts;

static void free_facts(tree_facts *f)
{
    free(f->leaf_box);
    free(f->polarity);
    free(f->reach);
}

static bool gather_facts(const mcsg_tree *tree, tree_facts *f)
{
    size_t n = mcsg_tree_node_count(tree);
    f->tree = tree;
    f->node_count = n;
    f->leaf_box = calloc(n + 1, sizeof *f->leaf_box);
    f->polarity = calloc(n + 1, sizeof *f->polarity);
    f->reach = calloc(n + 1, sizeof *f->reach);
    if (!f->leaf_box || !f->polarity || !f->reach)
        return false;
    f->reach[mcsg_tree_root(tree)] = true;
    f->polarity[mcsg_tree_root(tree)] = 1;
    /* Children are created before their parents: one pass from the root down. */
    for (size_t i = n; i-- > 0;) {
        mcsg_node_kind kind = mcsg_tree_node_kind(tree, (mcsg_node_id)i);
        if (!f->reach[i])
            continue;
        if (kind == MCSG_NODE_LEAF) {
            f->leaf_box[i] = empty_box();
            box_add_mesh(&f->leaf_box[i], mcsg_tree_leaf_mesh(tree, (mcsg_node_id)i));
        }
        for (size_t c = 0; c < mcsg_tree_child_count(tree, (mcsg_node_id)i); c++) {
            mcsg_node_id k = mcsg_tree_child(tree, (mcsg_node_id)i, c);
            f->reach[k] = true;
            f->polarity[k] =
                kind == MCSG_NODE_DIFFERENCE && c > 0 ? -f->polarity[i] : f->polarity[i];
        }
    }
    return true;
}

/* Membership in the solid of a node at one point. Leaves are evaluated only when their
 * membership matters (operations short-circuit), so that points near the surface of a
 * leaf that does not matter there are not skipped. */
typedef struct point_query {
    const tree_facts *f;
    const double *p;
    bool clear; /* every winding number used was within NEAR_INTEGER of an integer */
} point_query;

static bool member(point_query *q, mcsg_node_id node)
{
    const mcsg_tree *t = q->f->tree;
    size_t n = mcsg_tree_child_count(t, node);
    switch (mcsg_tree_node_kind(t, node)) {
    case MCSG_NODE_LEAF: {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(t, node);
        double w = m ? winding(m, &q->f->leaf_box[node], q->p) : 0;
        q->clear = q->clear && near_integer(w);
        return w > 0.5;
    }
    case MCSG_NODE_UNION:
        for (size_t c = 0; c < n; c++)
            if (member(q, mcsg_tree_child(t, node, c)))
                return true;
        return false;
    case MCSG_NODE_INTERSECTION:
        for (size_t c = 0; c < n; c++)
            if (!member(q, mcsg_tree_child(t, node, c)))
                return false;
        return n > 0;
    case MCSG_NODE_DIFFERENCE:
        if (n == 0 || !member(q, mcsg_tree_child(t, node, 0)))
            return false;
        for (size_t c = 1; c < n; c++)
            if (member(q, mcsg_tree_child(t, node, c)))
                return false;
        return true;
    }
    return false;
}

/* Provenance: a leaf of the tree, a face of it, the triangle in the face's plane, facing
 * the face's way (reversed for subtracted leaves). */
static bool check_provenance(const tree_facts *f, const mcsg_mesh *out,
                             const mcsg_provenance *prov, double scale, csg_result *r)
{
    for (size_t k = 0; k < out->triangle_count; k++) {
        const mcsg_provenance *p = &prov[k];
        const mcsg_mesh *leaf;
        const uint32_t *tri, *face;
        double fn[3], on[3], longest = 0, fnorm, onorm;
        if (p->leaf >= f->node_count ||
            mcsg_tree_node_kind(f->tree, p->leaf) != MCSG_NODE_LEAF)
            return fail(r, "triangle %zu: provenance leaf %" PRIu32 " is not a leaf", k,
                        p->leaf);
        leaf = mcsg_tree_leaf_mesh(f->tree, p->leaf);
        if (!leaf || p->face >= leaf->triangle_count)
            return fail(r, "triangle %zu: provenance face %" PRIu32 " of leaf %" PRIu32
                        " out of range", k, p->face, p->leaf);
        tri = out->triangles + 3 * k;
        face = leaf->triangles + 3 * p->face;
        triangle_normal(leaf, p->face, fn);
        fnorm = norm(fn);
        for (int c = 0; c < 3; c++) {
            double d[3], e[3];
            const double *v = out->vertices + 3 * tri[c];
            sub(v, leaf->vertices + 3 * face[0], d);
            if (fabs(dot(d, fn)) / fnorm > 1e-9 * scale)
                return fail(r, "triangle %zu (%.17g %.17g %.17g ...) is %g off the plane of its "
                            "provenance, face %" PRIu32 " of leaf %" PRIu32, k, v[0], v[1],
                            v[2], fabs(dot(d, fn)) / fnorm, p->face, p->leaf);
            sub(out->vertices + 3 * tri[(c + 1) % 3], v, e);
            longest = norm(e) > longest ? norm(e) : longest;
        }
        /* Orientation, where rounding cannot have turned the triangle. */
        triangle_normal(out, k, on);
        onorm = norm(on);
        if (onorm > 1e-9 * scale * longest &&
            dot(on, fn) * f->polarity[p->leaf] <= 0.5 * onorm * fnorm)
            return fail(r, "triangle %zu faces %s its provenance, face %" PRIu32
                        " of leaf %" PRIu32 " (subtracted: %s)", k,
                        dot(on, fn) > 0 ? "like" : "against", p->face, p->leaf,
                        f->polarity[p->leaf] < 0 ? "yes" : "no");
    }
    return true;
}

/* The output mesh on its own: valid (closed, oriented, manifold by index where it is
 * manifold by coordinates), touching only where allowed, not inverted, inside the box. */
/* The result's own check (stats->output_check) against the independent ones: it must
 * tell what mcsg_mesh_check (welded), the index test and the crossing test find. */
static bool output_check_agrees(const mcsg_mesh *out, const mcsg_eval_stats *stats,
                                const mcsg_check_report *report, size_t defects,
                                csg_result *r)
{
    const mcsg_output_check *c = &stats->output_check;
    if (report->nonmanifold_edges != c->welded_nonmanifold_edges + c->touching_edges ||
        report->boundary_edges != c->open_edges ||
        report->inconsistent_edges != c->misoriented_edges ||
        report->degenerate_triangles != c->degenerate_triangles ||
        (c->index_nonmanifold_edges > 0 && defects == 0))
        return fail(r, "the result's check disagrees with mcsg_mesh_check: %zu+%zu "
                    "non-manifold, %zu open, %zu misoriented edges, %zu degenerate "
                    "triangles, %zu index edges reported; found %zu non-manifold, %zu "
                    "boundary, %zu inconsistent, %zu degenerate, %zu index defects",
                    c->welded_nonmanifold_edges, c->touching_edges, c->open_edges,
                    c->misoriented_edges, c->degenerate_triangles, c->index_nonmanifold_edges,
                    report->nonmanifold_edges, report->boundary_edges,
                    report->inconsistent_edges, report->degenerate_triangles, defects);
    if (csg_self_check && out->triangle_count > 0) {
        size_t pairs = 0;
        mcsg_error err;
        if (mcsg_mesh_self_intersections(out, NULL, &pairs, NULL, &err) != MCSG_OK)
            return fail(r, "mcsg_mesh_self_intersections: %s", err.message);
        r->self_intersecting = pairs > 0;
        if (!c->crossings_checked || c->crossing_pairs != pairs)
            return fail(r, "the result's check reports %zu crossing pairs, the test finds %zu",
                        c->crossing_pairs, pairs);
    }
    return true;
}

/* Whether rounding to doubles changed the result's combinatorics (vertices joined,
 * triangles dropped or split): only then can it break a guarantee, and a broken
 * guarantee that the result's check reports is accepted (snap rounding is to remove
 * those); without rounding's doing, it is a bug. */
static bool rounding_acted(const mcsg_eval_stats *stats)
{
    return stats->rounding_joined_vertices > 0 || stats->rounding_dropped_triangles > 0 ||
           stats->rounding_split_triangles > 0 || stats->rounding_flat_triangles > 0 ||
           stats->rounding_turned_triangles > 0;
}

static bool check_mesh(const mcsg_mesh *out, const mcsg_eval_stats *stats,
                       bool allow_touching, const box *scene, double scale, csg_result *r)
{
    mcsg_check_report report;
    mcsg_error err;
    box outbox = empty_box();
    size_t defects;
    if (out->triangle_count == 0)
        return true;
    if (mcsg_mesh_check(out, NULL, &report, &err) != MCSG_OK)
        return fail(r, "mcsg_mesh_check: %s", err.message);
    defects = test_index_manifold_defects(out);
    if (!output_check_agrees(out, stats, &report, defects, r))
        return false;
    if (mcsg_output_check_failed(&stats->output_check) &&
        stats->output_check.crossing_pairs == 0 && !rounding_acted(stats))
        return fail(r, "the result breaks a guarantee although rounding changed nothing");
    if (mcsg_output_check_failed(&stats->output_check) && !report.inverted) {
        r->rounding_reported = true;
        return true;
    }
    /* Parts touching at a point or along an edge get their own vertex copies, so the
     * output must be manifold by index too. */
    if (defects > 0)
        return fail(r, "output is not manifold by vertex index: %zu defects (edges not "
                    "used once each way, vertices with several umbrellas)", defects);
    if (!mcsg_check_report_is_valid(&report)) {
        size_t shared, unbalanced = unbalanced_edges(out, &shared);
        bool only_shared_edges =
            report.nonmanifold_edges > 0 && report.boundary_edges == 0 &&
            report.inconsistent_edges == 0 && report.degenerate_triangles == 0 &&
            report.duplicate_triangles == 0 && report.out_of_range_indices == 0 &&
            report.nonfinite_vertices == 0;
        /* Rounding to doubles can flatten a thin exact triangle (zero area). The
         * evaluator splits such triangles away and counts the few it cannot (both sides
         * of an edge flat); only those are tolerated, if still closed and oriented. */
        bool rounding_only = report.degenerate_triangles > 0 &&
                             report.degenerate_triangles <= stats->rounding_flat_triangles &&
                             report.boundary_edges == 0 && report.inconsistent_edges == 0 &&
                             unbalanced == 0;
        /* Rounding that joins distinct exact vertices can bring two parts of any result
         * together along an edge, whether or not it collapses triangles (seed
         * 0xdf20a53a6838d150: a sliver's edge joined to a sphere's diagonal); the output
         * must then still be manifold by index. */
        bool touching_by_rounding =
            (stats->rounding_joined_vertices > 0 || stats->rounding_dropped_triangles > 0) &&
            defects == 0;
        if (rounding_only)
            r->rounding_artifacts = true;
        else if (!(allow_touching || touching_by_rounding) || !only_shared_edges ||
                 unbalanced > 0)
            return fail(r, "invalid output (%zu triangles): %zu boundary, %zu non-manifold, "
                        "%zu inconsistent, %zu unbalanced edges; %zu degenerate, %zu "
                        "duplicate triangles; %zu non-finite vertices", out->triangle_count,
                        report.boundary_edges, report.nonmanifold_edges,
                        report.inconsistent_edges, unbalanced, report.degenerate_triangles,
                        report.duplicate_triangles, report.nonfinite_vertices);
        else
            r->touching = true;
    }
    if (report.inverted)
        return fail(r, "output is inverted (volume %g)", report.volume);
    box_add_mesh(&outbox, out);
    for (int k = 0; k < 3; k++)
        if (outbox.lo[k] < scene->lo[k] - 1e-9 * scale ||
            outbox.hi[k] > scene->hi[k] + 1e-9 * scale)
            return fail(r, "output reaches out of the leaves' box along axis %d: [%.17g, "
                        "%.17g] vs [%.17g, %.17g]", k, outbox.lo[k], outbox.hi[k],
                        scene->lo[k], scene->hi[k]);
    return true;
}

/* A point for the oracle: uniform in the scene's box, in the result's box, or just off a
 * random face of a random leaf, on either side. */
static void sample_point(uint64_t *rng, int i, const tree_facts *f, const mcsg_node_id *leaves,
                         int leaf_n, const box *scene, const box *outbox, bool empty_out,
                         double scale, double p[3])
{
    int mode = i % 4;
    if (mode <= 1 || (mode == 2 && empty_out)) {
        box_sample(rng, scene, p);
    } else if (mode == 2) {
        box_sample(rng, outbox, p);
    } else {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(f->tree, leaves[test_random_int(rng, 0, leaf_n - 1)]);
        size_t t = (size_t)(test_xorshift(rng) % m->triangle_count);
        const uint32_t *tri = m->triangles + 3 * t;
        double u = sqrt(uniform(rng)), v = uniform(rng), n[3];
        double off = scale * pow(10, uniform_in(rng, -4, -2)) *
                     (test_random_int(rng, 0, 1) ? 1 : -1);
        triangle_normal(m, t, n);
        for (int k = 0; k < 3; k++)
            p[k] = (1 - u) * m->vertices[3 * tri[0] + k] +
                   u * (1 - v) * m->vertices[3 * tri[1] + k] +
                   u * v * m->vertices[3 * tri[2] + k] + off * n[k] / norm(n);
    }
}

/* The oracle point by point, then the volume against its Monte Carlo estimate. */
static bool check_points(const tree_facts *f, const tree_facts *claim, uint64_t seed,
                         const mcsg_mesh *out, box scene, double scale, csg_result *r)
{
    uint64_t rng = csg_mix_seed(seed ^ 0x706f696e7473u);
    mcsg_node_id *leaves = malloc((f->node_count + 1) * sizeof *leaves);
    int leaf_n = 0;
    size_t uniform_points = 0, uniform_inside = 0;
    box outbox = empty_box();
    double volume = test_signed_volume(out);
    point_query q = {claim, NULL, true};
    bool ok = true;
    if (!leaves)
        return fail(r, "out of memory in the oracle");
    for (size_t i = 0; i < f->node_count; i++)
        if (f->reach[i] && mcsg_tree_node_kind(f->tree, (mcsg_node_id)i) == MCSG_NODE_LEAF &&
            mcsg_tree_leaf_mesh(f->tree, (mcsg_node_id)i)->triangle_count > 0)
            leaves[leaf_n++] = (mcsg_node_id)i;
    box_add_mesh(&outbox, out);
    /* Sampling boxes slightly larger than the scene. */
    for (int k = 0; k < 3; k++) {
        double pad = 0.02 * (scene.hi[k] - scene.lo[k]);
        scene.lo[k] -= pad, scene.hi[k] += pad;
    }
    for (int i = 0; i < POINTS_PER_TREE && ok && leaf_n > 0; i++) {
        double p[3], w_out;
        bool expect;
        sample_point(&rng, i, f, leaves, leaf_n, &scene, &outbox, out->triangle_count == 0,
                     scale, p);
        r->points++;
        q.p = p;
        q.clear = true;
        expect = member(&q, mcsg_tree_root(claim->tree));
        if (!q.clear)
            continue;
        w_out = winding(out, &outbox, p);
        if (!near_integer(w_out) || near_surface(out, p, 0x1p-40 * scale))
            continue;
        r->checked++;
        r->inside += expect;
        if (i % 4 <= 1) {
            uniform_points++;
            uniform_inside += expect;
        }
        if (nearbyint(w_out) != (expect ? 1 : 0))
            ok = fail(r, "at (%.17g, %.17g, %.17g) the result's winding number is %.6f but "
                      "the point is %s the tree's solid", p[0], p[1], p[2], w_out,
                      expect ? "inside" : "outside");
    }
    free(leaves);
    if (ok && 2 * r->checked < r->points)
        ok = fail(r, "only %zu of %zu points were far enough from surfaces to check",
                  r->checked, r->points);
    /* Loose: five standard deviations plus 5% of the box. The deviation is estimated
     * from (inside + 1) / (points + 2), not from the plain fraction: a result of 5% of the
     * box has no point inside 150 uniform ones once in 4,000 trees, and a deviation
     * estimated as zero then failed it. */
    if (ok && uniform_points > 0) {
        double frac = (double)uniform_inside / (double)uniform_points, vbox = box_volume(&scene);
        double smooth = (double)(uniform_inside + 1) / (double)(uniform_points + 2);
        double sigma = vbox * sqrt(smooth * (1 - smooth) / (double)uniform_points);
        if (fabs(volume - vbox * frac) > 5 * sigma + 0.05 * vbox)
            ok = fail(r, "output volume %g, Monte Carlo estimate %g (box %g, %zu of %zu "
                      "points inside)", volume, vbox * frac, vbox, uniform_inside,
                      uniform_points);
    }
    return ok;
}

bool csg_self_check;

/* Keeps the reason a round of evaluating the rounded result again failed. */
static void keep_reevaluation_failure(void *user, mcsg_log_level level, const char *message)
{
    static const char prefix[] = "evaluating the rounded result again failed: ";
    csg_result *r = user;
    (void)level;
    if (strncmp(message, prefix, sizeof prefix - 1) == 0)
        snprintf(r->reevaluation, sizeof r->reevaluation, "%s", message + sizeof prefix - 1);
}

bool csg_check_tree(const mcsg_tree *tree, const mcsg_tree *claim, uint64_t seed,
                    bool with_provenance, bool allow_touching, bool check_inputs,
                    csg_result *r)
{
    tree_facts f = {0}, cf = {0};
    mcsg_mesh out = {0};
    mcsg_provenance *prov = NULL;
    mcsg_eval_stats stats;
    mcsg_error err;
    mcsg_status st;
    box scene = empty_box();
    double scale = 1, t0;
    bool ok;

    memset(r, 0, sizeof *r);
    if (!gather_facts(tree, &f) || (claim && !gather_facts(claim, &cf))) {
        free_facts(&f);
        free_facts(&cf);
        return fail(r, "out of memory in the oracle");
    }
    for (size_t i = 0; i < f.node_count; i++)
        if (f.reach[i] && mcsg_tree_node_kind(tree, (mcsg_node_id)i) == MCSG_NODE_LEAF)
            for (int k = 0; k < 3; k++) {
                scene.lo[k] = fmin(scene.lo[k], f.leaf_box[i].lo[k]);
                scene.hi[k] = fmax(scene.hi[k], f.leaf_box[i].hi[k]);
            }
    for (int k = 0; k < 3; k++)
        if (scene.lo[k] <= scene.hi[k])
            scale = fmax(scale, fmax(fabs(scene.lo[k]), fabs(scene.hi[k])));

    {
        mcsg_options opts = {0};
        opts.check_output_crossings = csg_self_check;
        opts.check_self_intersections = check_inputs;
        opts.log = keep_reevaluation_failure;
        opts.log_user = r;
        st = mcsg_eval(tree, &opts, &out, with_provenance ? &prov : NULL, &stats, &err);
    }
    if (st != MCSG_OK) {
        ok = fail(r, "mcsg_eval: %s: %s", mcsg_status_string(st), err.message);
    } else {
        r->triangles = out.triangle_count;
        r->dropped = stats.rounding_dropped_triangles;
        r->eval_seconds = stats.seconds_total;
        r->check = stats.output_check;
        ok = check_mesh(&out, &stats, allow_touching, &scene, scale, r);
        if (ok && test_signed_volume(&out) < -1e-9 * scale * scale * scale)
            ok = fail(r, "negative output volume %g", test_signed_volume(&out));
        if (ok && prov)
            ok = check_provenance(&f, &out, prov, scale, r);
        t0 = csg_now();
        if (ok)
            ok = check_points(&f, claim ? &cf : &f, seed, &out, scene, scale, r);
        r->oracle_seconds = csg_now() - t0;
    }
    mcsg_free(prov, NULL);
    mcsg_mesh_free(&out, NULL);
    free_facts(&f);
    free_facts(&cf);
    return ok;
}

/* A framed tree as the CSG reader makes it from the tree's text. */
static mcsg_status read_framed_tree(const csg_tree_spec *t, mcsg_tree **out, csg_result *r)
{
    char *text = NULL;
    size_t size = 0;
    mcsg_error err;
    mcsg_status st = MCSG_ERR_NOMEM;
    FILE *f = open_memstream(&text, &size);
    if (f) {
        print_tree(f, t);
        fclose(f);
        st = mcsg_scad_read_memory(text, size, "framed tree", NULL, NULL, out, &err);
    }
    free(text);
    if (st != MCSG_OK)
        fail(r, "reading the framed tree: %s", f ? err.message : "out of memory");
    return st;
}

static mcsg_status build_tree(const csg_tree_spec *t, mcsg_tree **out, csg_result *r)
{
    mcsg_node_id id[CSG_MAX_NODES];
    bool reach[CSG_MAX_NODES];
    mcsg_error err;
    mcsg_status st;
    if (t->framed)
        return read_framed_tree(t, out, r);
    st = mcsg_tree_create(NULL, out, &err);
    reachable(t, reach);
    for (int i = 0; i < t->node_count && st == MCSG_OK; i++) {
        const csg_node_spec *n = &t->nodes[i];
        if (!reach[i])
            continue;
        if (n->kind == MCSG_NODE_LEAF) {
            mcsg_mesh mesh;
            st = make_leaf_mesh(&t->leaves[n->leaf], &mesh, &err);
            if (st == MCSG_OK)
                st = mcsg_tree_add_leaf(*out, &mesh, t->leaves[n->leaf].m, NULL, &id[i], &err);
            mcsg_mesh_free(&mesh, NULL);
        } else {
            mcsg_node_id kids[CSG_MAX_CHILDREN];
            for (int c = 0; c < n->child_count; c++)
                kids[c] = id[n->children[c]];
            st = mcsg_tree_add_op(*out, n->kind, kids, (size_t)n->child_count, NULL, &id[i],
                                  &err);
        }
    }
    if (st == MCSG_OK)
        st = mcsg_tree_set_root(*out, id[t->root], &err);
    if (st != MCSG_OK)
        fail(r, "building the tree: %s", err.message);
    return st;
}

bool csg_run_case(const csg_tree_spec *t, const csg_tree_spec *claim, bool with_provenance,
                  csg_result *r)
{
    mcsg_tree *tree = NULL, *claim_tree = NULL;
    bool ok = false;
    memset(r, 0, sizeof *r);
    if (build_tree(t, &tree, r) == MCSG_OK && (!claim || build_tree(claim, &claim_tree, r) == MCSG_OK))
        ok = csg_check_tree(tree, claim_tree, t->seed, with_provenance,
                            touching_allowed(t), check_inputs(t), r);
    mcsg_tree_free(tree);
    mcsg_tree_free(claim_tree);
    return ok;
}

/* ---------------------------------------------------------------------------------- */
/* Shrinking a failing case                                                            */

/* Candidate reductions of t, numbered from 0; false when `which` is past the last. */
static bool reduction(const csg_tree_spec *t, int which, csg_tree_spec *out)
{
    bool reach[CSG_MAX_NODES];
    reachable(t, reach);
    *out = *t;
    /* A proper subtree as the whole tree. */
    for (int i = 0; i < t->root; i++)
        if (reach[i] && which-- == 0) {
            out->root = i;
            return true;
        }
    /* One child fewer. */
    for (int i = 0; i <= t->root; i++) {
        const csg_node_spec *n = &t->nodes[i];
        if (!reach[i] || n->child_count < 2)
            continue;
        for (int c = 0; c < n->child_count; c++)
            if (which-- == 0) {
                csg_node_spec *m = &out->nodes[i];
                memmove(m->children + c, m->children + c + 1,
                        (size_t)(m->child_count - c - 1) * sizeof *m->children);
                m->child_count--;
                return true;
            }
    }
    /* An operation child replaced by one of its own children. */
    for (int i = 0; i <= t->root; i++) {
        const csg_node_spec *n = &t->nodes[i];
        if (!reach[i] || n->kind == MCSG_NODE_LEAF)
            continue;
        for (int c = 0; c < n->child_count; c++) {
            const csg_node_spec *k = &t->nodes[n->children[c]];
            for (int g = 0; g < k->child_count; g++)
                if (which-- == 0) {
                    out->nodes[i].children[c] = k->children[g];
                    return true;
                }
        }
    }
    return false;
}

/* Failures of the same kind start with the same words (up to the first number or
 * parenthesis): a reduction must keep the failure it is shrinking, not find another. */
static bool same_kind_of_failure(const char *a, const char *b)
{
    size_t n = strcspn(b, "0123456789(");
    return strncmp(a, b, n) == 0;
}

void csg_shrink(csg_tree_spec *t, bool with_provenance, double budget)
{
    double end = csg_now() + budget;
    bool progress = true;
    static csg_tree_spec smaller;
    csg_result first;
    if (csg_run_case(t, NULL, with_provenance, &first))
        return; /* nothing to shrink */
    while (progress && csg_now() < end) {
        csg_result r;
        progress = false;
        for (int which = 0; reduction(t, which, &smaller) && csg_now() < end; which++) {
            if (!csg_run_case(&smaller, NULL, with_provenance, &r) &&
                same_kind_of_failure(r.why, first.why)) {
                *t = smaller;
                progress = true;
                break;
            }
        }
    }
}
