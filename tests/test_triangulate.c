/*
 * Constrained triangulation of a face: random implicit points in tilted faces, lattice
 * points with many collinear triples, points on the boundary, random non-crossing
 * constraints. Every output is checked exactly: positive orientation of every triangle,
 * each interior edge shared by exactly two triangles in opposite directions, boundary
 * edges along the face's edges, the triangle count of a tiling (2 interior + boundary
 * points + 1), every inserted point used, every constraint an edge.
 */
#include "testlib.h"
#include "csg/triangulate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_POINTS 4096

typedef struct face_case {
    double corner[3][3];
    double (*aux)[3]; /* end points of the lines that define LPI points */
    mci_plane plane;
    mci_point points[MAX_POINTS];
    const mci_point *refs[MAX_POINTS]; /* the triangulation's input: points by id */
    size_t count;
    int axis, sign;
    uint32_t *edges;
    size_t edge_count;
} face_case;

static uint64_t rng = 0x1234567887654321u;

static double uniform(void)
{
    return (double)(test_xorshift(&rng) >> 11) * 0x1p-53;
}

static int orient_face(const face_case *f, uint32_t a, uint32_t b, uint32_t p)
{
    return f->sign *
           mci_orient2d_projected(&f->points[a], &f->points[b], &f->points[p], f->axis);
}

static bool is_new_point(const face_case *f, const mci_point *p)
{
    for (size_t i = 0; i < f->count; i++)
        if (mci_points_equal(&f->points[i], p))
            return false;
    return true;
}

static const mci_point *const *point_refs(face_case *f)
{
    for (size_t i = 0; i < f->count; i++)
        f->refs[i] = &f->points[i];
    return f->refs;
}

static void setup_face(face_case *f)
{
    mci_plane_init(&f->plane, f->corner[0], f->corner[1], f->corner[2]);
    f->axis = mci_plane_projection_axis(&f->plane, &f->sign);
    for (int i = 0; i < 3; i++)
        mci_point_explicit(&f->points[i], f->corner[i]);
    f->count = 3;
}

/* A tilted face with LPI points: lines between random points on both sides. */
static void random_lpi_face(face_case *f, size_t want)
{
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            f->corner[i][k] = uniform() * 10 - 5;
    setup_face(f);
    f->aux = malloc(2 * want * sizeof *f->aux);
    for (size_t i = 0; i < want; i++) {
        double *p = f->aux[2 * i], *q = f->aux[2 * i + 1], w[3];
        double s = uniform(), t = uniform() * (1 - s);
        mci_point lpi;
        int which;
        for (int k = 0; k < 3; k++) {
            w[k] = f->corner[0][k] + s * (f->corner[1][k] - f->corner[0][k]) +
                   t * (f->corner[2][k] - f->corner[0][k]);
            p[k] = w[k] + uniform() - 0.5;
            q[k] = 2 * w[k] - p[k];
        }
        if (mci_point_lpi(&lpi, p, q, &f->plane) &&
            mci_point_in_triangle(&lpi, &f->plane, &which) != MCI_OUTSIDE && is_new_point(f, &lpi))
            f->points[f->count++] = lpi;
    }
}

/* A face in z = 0 with integer corners and lattice points inside and on the edges. */
static void lattice_face(face_case *f, int size)
{
    static double lattice[MAX_POINTS][3];
    double c[3][3] = {{0, 0, 0}, {size, 0, 0}, {0, size, 0}};
    memcpy(f->corner, c, sizeof c);
    setup_face(f);
    f->aux = NULL;
    for (int x = 0; x <= size; x++)
        for (int y = 0; x + y <= size && f->count < MAX_POINTS; y++) {
            double *p = lattice[f->count];
            mci_point pt;
            if ((x == 0 && y == 0) || (x == size && y == 0) || (x == 0 && y == size))
                continue;
            p[0] = x, p[1] = y, p[2] = 0;
            mci_point_explicit(&pt, p);
            f->points[f->count++] = pt;
        }
}

static bool inside_segment(const face_case *f, uint32_t a, uint32_t b, uint32_t p)
{
    return p != a && p != b && orient_face(f, a, b, p) == 0 &&
           mci_compare_lex(&f->points[a], &f->points[p]) *
                   mci_compare_lex(&f->points[p], &f->points[b]) > 0;
}

static bool on_face_edge(const face_case *f, uint32_t a, uint32_t b)
{
    for (uint32_t e = 0; e < 3; e++)
        if (orient_face(f, e, (e + 1) % 3, a) == 0 && orient_face(f, e, (e + 1) % 3, b) == 0)
            return true;
    return false;
}

static bool acceptable_constraint(const face_case *f, uint32_t a, uint32_t b)
{
    if (a == b || on_face_edge(f, a, b))
        return false;
    for (uint32_t p = 0; p < f->count; p++)
        if (inside_segment(f, a, b, p))
            return false;
    for (size_t k = 0; k < f->edge_count; k++) {
        uint32_t x = f->edges[2 * k], y = f->edges[2 * k + 1];
        if ((x == a && y == b) || (x == b && y == a))
            return false;
        if (orient_face(f, a, b, x) * orient_face(f, a, b, y) < 0 &&
            orient_face(f, x, y, a) * orient_face(f, x, y, b) < 0)
            return false;
    }
    return true;
}

/* Random short constraints: each from a point to one of a few later points. */
static void random_constraints(face_case *f, size_t want)
{
    f->edges = malloc(2 * want * sizeof *f->edges);
    f->edge_count = 0;
    for (size_t tries = 0; tries < 4 * want && f->edge_count < want; tries++) {
        uint32_t a = (uint32_t)test_random_int(&rng, 0, (int)f->count - 1);
        uint32_t b = (uint32_t)test_random_int(&rng, 0, (int)f->count - 1);
        if (acceptable_constraint(f, a, b)) {
            f->edges[2 * f->edge_count] = a;
            f->edges[2 * f->edge_count++ + 1] = b;
        }
    }
}

static int edge_cmp(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0]) : (a[1] > b[1]) - (a[1] < b[1]);
}

static bool has_directed(const uint32_t *sorted, size_t n, uint32_t u, uint32_t w)
{
    uint32_t key[2] = {u, w};
    return bsearch(key, sorted, n, 2 * sizeof *sorted, edge_cmp) != NULL;
}

static size_t boundary_point_count(const face_case *f)
{
    size_t n = 0;
    for (uint32_t p = 3; p < f->count; p++)
        for (uint32_t e = 0; e < 3; e++)
            n += orient_face(f, e, (e + 1) % 3, p) == 0;
    return n;
}

/* Exact checks that the triangles tile the face and honour the constraints. */
static void check_tiling(const face_case *f, const mci_cdt_output *out)
{
    size_t n = out->tri_count, boundary_edges = 0, nb = boundary_point_count(f);
    uint32_t *directed = malloc(6 * n * sizeof *directed);
    bool *used = calloc(f->count, sizeof *used);
    for (size_t t = 0; t < n; t++) {
        const uint32_t *v = out->tris + 3 * t;
        CHECK_MSG(orient_face(f, v[0], v[1], v[2]) > 0, "triangle %zu not positive", t);
        for (int i = 0; i < 3; i++) {
            directed[6 * t + 2 * i] = v[i];
            directed[6 * t + 2 * i + 1] = v[(i + 1) % 3];
            used[v[i]] = true;
        }
    }
    qsort(directed, 3 * n, 2 * sizeof *directed, edge_cmp);
    for (size_t e = 0; e < 3 * n; e++) {
        uint32_t u = directed[2 * e], w = directed[2 * e + 1];
        CHECK(e == 0 || edge_cmp(directed + 2 * e, directed + 2 * e - 2) != 0);
        if (!has_directed(directed, 3 * n, w, u)) {
            boundary_edges++;
            CHECK_MSG(on_face_edge(f, u, w), "open edge %u-%u inside the face", u, w);
        }
    }
    CHECK_EQ_SIZE(boundary_edges, 3 + nb);
    CHECK_EQ_SIZE(n, 2 * (f->count - 3 - nb) + nb + 1);
    for (size_t p = 0; p < f->count; p++)
        CHECK_MSG(used[p], "point %zu unused", p);
    for (size_t k = 0; k < f->edge_count; k++) {
        uint32_t a = f->edges[2 * k], b = f->edges[2 * k + 1];
        CHECK_MSG(has_directed(directed, 3 * n, a, b) || has_directed(directed, 3 * n, b, a),
                  "constraint %u-%u missing", a, b);
    }
    free(directed);
    free(used);
}

/* Whether a-b (either direction) is one of the case's constraints. */
static bool is_constraint(const face_case *f, uint32_t a, uint32_t b)
{
    for (size_t k = 0; k < f->edge_count; k++) {
        uint32_t u = f->edges[2 * k], w = f->edges[2 * k + 1];
        if ((u == a && w == b) || (u == b && w == a))
            return true;
    }
    return false;
}

/* adj: every side inside the face names the side running the other way (which names it
 * back), the constraint bit says whether the edge is a constraint, and only sides on
 * the face's boundary have no neighbour. */
static void check_adjacency(const face_case *f, const mci_cdt_output *out)
{
    for (size_t s = 0; s < 3 * out->tri_count; s++) {
        uint32_t u = out->tris[s], w = out->tris[s - s % 3 + (s % 3 + 1) % 3], other, back;
        if (out->adj[s] == UINT32_MAX) {
            CHECK_MSG(on_face_edge(f, u, w), "side %u-%u has no neighbour inside the face",
                      u, w);
            continue;
        }
        other = out->adj[s] & ~MCI_CDT_CONSTRAINT;
        CHECK(other < 3 * out->tri_count && other / 3 != s / 3);
        if (other >= 3 * out->tri_count)
            continue;
        back = out->adj[other];
        CHECK_MSG(out->tris[other] == w &&
                      out->tris[other - other % 3 + (other % 3 + 1) % 3] == u,
                  "side %zu: neighbour side %u is not its reverse", s, other);
        CHECK(back != UINT32_MAX && (back & ~MCI_CDT_CONSTRAINT) == s);
        CHECK_MSG(((out->adj[s] & MCI_CDT_CONSTRAINT) != 0) == is_constraint(f, u, w),
                  "side %u-%u: constraint bit wrong", u, w);
    }
}

static void run_case(face_case *f)
{
    mci_ctx ctx;
    mcsg_error err;
    mci_cdt_output out;
    uint32_t *insert = malloc(f->count * sizeof *insert);
    mci_cdt_input in = {point_refs(f), f->count, f->axis, f->sign, insert, f->count - 3,
                        f->edges, f->edge_count, NULL, NULL, NULL, NULL};
    mci_ctx_init(&ctx, NULL);
    for (size_t i = 3; i < f->count; i++)
        insert[i - 3] = (uint32_t)i;
    CHECK_OK(mci_triangulate(&ctx, &in, &out, &err), &err);
    if (out.tris) {
        check_tiling(f, &out);
        check_adjacency(f, &out);
    }
    free(out.tris);
    free(out.adj);
    free(insert);
    free(f->edges);
    free(f->aux);
}

TEST(empty_face)
{
    static face_case f;
    lattice_face(&f, 1);
    f.edges = NULL;
    f.edge_count = 0;
    run_case(&f);
}

TEST(random_points_tilted_faces)
{
    static face_case f;
    for (int round = 0; round < 40; round++) {
        random_lpi_face(&f, (size_t)test_random_int(&rng, 1, 300));
        random_constraints(&f, f.count / 2);
        run_case(&f);
    }
}

TEST(lattice_points_with_collinear_constraints)
{
    static face_case f;
    for (int round = 0; round < 20; round++) {
        lattice_face(&f, test_random_int(&rng, 2, 24));
        random_constraints(&f, f.count);
        run_case(&f);
    }
}

/* A long constraint across a lattice forces many flips per constraint. */
TEST(long_constraints_across_lattice)
{
    static face_case f;
    lattice_face(&f, 40);
    f.edges = malloc(64 * sizeof *f.edges);
    f.edge_count = 0;
    /* point ids of (x, y): lattice order minus the skipped corners; find by search. */
    for (uint32_t p = 3; p < f.count && f.edge_count < 30; p++) {
        uint32_t q = (uint32_t)test_random_int(&rng, 3, (int)f.count - 1);
        if (acceptable_constraint(&f, p, q)) {
            f.edges[2 * f.edge_count] = p;
            f.edges[2 * f.edge_count++ + 1] = q;
        }
    }
    CHECK(f.edge_count > 10);
    run_case(&f);
}

TEST(contract_violations_are_reported)
{
    static face_case f;
    mci_ctx ctx;
    mcsg_error err;
    mci_cdt_output out;
    uint32_t insert[2] = {3, 3};
    mci_cdt_input in;
    lattice_face(&f, 3);
    mci_ctx_init(&ctx, NULL);
    in = (mci_cdt_input){point_refs(&f), f.count, f.axis, f.sign, insert, 2, NULL, 0, NULL, NULL, NULL, NULL};
    CHECK(mci_triangulate(&ctx, &in, &out, &err) == MCSG_ERR_INTERNAL);
    CHECK(out.tris == NULL && out.adj == NULL);
}

TEST(allocation_failures)
{
    static face_case f;
    random_lpi_face(&f, 60);
    random_constraints(&f, 30);
    {
        uint32_t insert[MAX_POINTS];
        mci_cdt_input in = {point_refs(&f), f.count, f.axis, f.sign, insert, f.count - 3,
                            f.edges, f.edge_count, NULL, NULL, NULL, NULL};
        for (size_t i = 3; i < f.count; i++)
            insert[i - 3] = (uint32_t)i;
        for (int fail_at = 1; fail_at < 64; fail_at++) {
            test_allocator a = {0};
            mcsg_options opts = test_allocator_options(&a);
            mci_ctx ctx;
            mcsg_error err;
            mci_cdt_output out;
            mcsg_status st;
            a.fail_at = fail_at;
            mci_ctx_init(&ctx, &opts);
            st = mci_triangulate(&ctx, &in, &out, &err);
            CHECK(st == MCSG_OK || st == MCSG_ERR_NOMEM);
            if (st == MCSG_OK) {
                mci_free(&ctx, out.tris);
                mci_free(&ctx, out.adj);
            }
            CHECK_EQ_SIZE(a.live, 0);
        }
    }
    free(f.edges);
    free(f.aux);
}

int main(void)
{
    RUN(empty_face);
    RUN(random_points_tilted_faces);
    RUN(lattice_points_with_collinear_constraints);
    RUN(long_constraints_across_lattice);
    RUN(contract_violations_are_reported);
    RUN(allocation_failures);
    return test_summary();
}
