/*
 * libFuzzer target for the evaluator: the input bytes describe up to 8 small leaves and
 * a tree over them, which mcsg_eval evaluates on one thread with an allocator capped at
 * 256 MiB that counts live blocks. Checked, abort()ing on a violation:
 *  - the status is success, an invalid mesh (a leaf breaking the input contract), an
 *    invalid argument (a transform the tree refuses) or out of memory; never an
 *    internal error;
 *  - when every leaf is valid by construction (primitives and non-flat tetrahedra under
 *    finite transforms), the evaluation succeeds;
 *  - with such valid leaves, a result has no boundary edge and no edge used twice in
 *    the same direction (vertices identified by coordinates; edges where parts touch
 *    may have four triangles), finite vertices, no repeated triangles, only the
 *    zero-area triangles the evaluator reports as left by rounding, and it is not
 *    inverted (the oracle test checks edge balance and membership in depth);
 *  - nothing is left allocated.
 *
 * Byte layout (missing bytes read as 0, so every input is meaningful):
 *   leaf count (1..8), then per leaf: kind, shape bytes, transform bytes; then per
 *   operation: kind and how many pending nodes it takes. Coordinates come from small
 *   grids (quarter units), so that coincident vertices, shared planes and touching
 *   solids are common; a few transforms take raw doubles from the input (huge, tiny,
 *   NaN). Replayed over fuzz/corpus/eval/ by CTest (fuzz/replay_main.c).
 *
 * To reproduce a finding outside the fuzzer: MCSG_FUZZ_DUMP=DIR replay_binary FILE writes
 * DIR/leafN.off (each leaf as the tree holds it, transformed) and DIR/tree.scad importing
 * them, which `meshcsg eval DIR/tree.scad` evaluates; a failed check prints what it saw.
 */
#include "fuzz_alloc.h"
#include "meshcsg.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define MAX_LEAVES 8

typedef struct reader {
    const uint8_t *data;
    size_t size, at;
} reader;

static unsigned next(reader *r) { return r->at < r->size ? r->data[r->at++] : 0; }

/* A value on the quarter grid in [-2, 2]. */
static double grid(reader *r) { return ((int)(next(r) % 17) - 8) / 4.0; }

static double raw_double(reader *r)
{
    uint64_t bits = 0;
    double x;
    for (int i = 0; i < 8; i++)
        bits = bits << 8 | next(r);
    memcpy(&x, &bits, sizeof x);
    return x;
}

/* A tetrahedron on grid points, oriented outward; *valid = 0 when it is flat. */
static mcsg_status make_tetrahedron(reader *r, const mcsg_options *opts, mcsg_mesh *out,
                                    int *valid)
{
    static const uint32_t faces[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    double p[12], u[3], v[3], w[3], det;
    mcsg_status st;
    for (int i = 0; i < 12; i++)
        p[i] = grid(r);
    for (int k = 0; k < 3; k++)
        u[k] = p[3 + k] - p[k], v[k] = p[6 + k] - p[k], w[k] = p[9 + k] - p[k];
    /* Exact: quarter-grid coordinates, products of small numbers. */
    det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
          u[2] * (v[0] * w[1] - v[1] * w[0]);
    *valid = det != 0;
    memset(out, 0, sizeof *out);
    {
        mcsg_mesh tmp = {p, (uint32_t *)faces, 4, 4};
        st = mcsg_mesh_copy(&tmp, opts, out, NULL);
    }
    if (st == MCSG_OK && det < 0)
        mcsg_mesh_flip(out);
    return st;
}

/* A mesh of 4..9 grid vertices and 4..15 arbitrary triangles: mostly open or
 * non-manifold, sometimes closed by accident. */
static mcsg_status make_soup(reader *r, const mcsg_options *opts, mcsg_mesh *out)
{
    double p[27];
    uint32_t t[45];
    size_t nv = 4 + next(r) % 6, nt = 4 + next(r) % 12;
    for (size_t i = 0; i < 3 * nv; i++)
        p[i] = grid(r);
    for (size_t i = 0; i < 3 * nt; i++)
        t[i] = next(r) % nv;
    mcsg_mesh tmp = {p, t, nv, nt};
    return mcsg_mesh_copy(&tmp, opts, out, NULL);
}

static mcsg_status make_shape(reader *r, const mcsg_options *opts, mcsg_mesh *out, int *valid)
{
    unsigned kind = next(r) % 6;
    double a = (1 + next(r) % 8) / 4.0, b = (1 + next(r) % 8) / 4.0, c = (next(r) % 9) / 4.0;
    int center = (int)(next(r) & 1);
    mcsg_resolution res = {3 + next(r) % 8, 12, 2};
    *valid = 1;
    switch (kind) {
    case 0:
    case 1: {
        double s[3] = {a, b, kind ? a : c + 0.25};
        return mcsg_make_cube(s, center, opts, out, NULL);
    }
    case 2:
        return mcsg_make_sphere(a, res, opts, out, NULL);
    case 3:
        return mcsg_make_cylinder(a, b, c, center, res, opts, out, NULL);
    case 4:
        return make_tetrahedron(r, opts, out, valid);
    default:
        *valid = 0;
        return make_soup(r, opts, out);
    }
}

/* Row-major 3x4. Signed axis permutations, scaled integer rotations (exact), rotations
 * by byte angles, and rarely raw doubles. */
static void make_transform(reader *r, double m[12], int *finite)
{
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                    {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    unsigned kind = next(r) % 8;
    memset(m, 0, 12 * sizeof *m);
    if (kind < 4) {
        const int *p = perms[next(r) % 6];
        unsigned signs = next(r);
        for (int row = 0; row < 3; row++)
            m[4 * row + p[row]] = signs >> row & 1 ? -1 : 1;
    } else if (kind < 6) {
        /* From the integer quaternion (w, x, y, z): |q|^2 times a rotation. */
        double w = next(r) % 3, x = next(r) % 3, y = next(r) % 3, z = next(r) % 3;
        if (w + x + y + z == 0)
            w = 1;
        m[0] = w * w + x * x - y * y - z * z, m[1] = 2 * (x * y - w * z);
        m[2] = 2 * (x * z + w * y), m[4] = 2 * (x * y + w * z);
        m[5] = w * w - x * x + y * y - z * z, m[6] = 2 * (y * z - w * x);
        m[8] = 2 * (x * z - w * y), m[9] = 2 * (y * z + w * x);
        m[10] = w * w - x * x - y * y + z * z;
    } else if (kind == 6) {
        double ang = next(r) * (6.283185307179586 / 256), c = cos(ang), s = sin(ang);
        unsigned axis = next(r) % 3, i = (axis + 1) % 3, j = (axis + 2) % 3;
        m[4 * axis + axis] = 1;
        m[4 * i + i] = c, m[4 * i + j] = -s, m[4 * j + i] = s, m[4 * j + j] = c;
    } else {
        m[0] = m[5] = m[10] = 1;
        unsigned row = next(r) % 3, col = next(r) % 4; /* in this order */
        m[4 * row + col] = raw_double(r);
    }
    for (int row = 0; row < 3; row++)
        m[4 * row + 3] += grid(r);
    *finite = kind != 7; /* a raw entry can be NaN, huge, or flatten the leaf */
}

static void check_result(const mcsg_mesh *out, const mcsg_eval_stats *stats)
{
    mcsg_check_report rep;
    if (out->triangle_count == 0)
        return;
    if (mcsg_mesh_check(out, NULL, &rep, NULL) != MCSG_OK)
        abort();
    if (rep.boundary_edges || rep.inconsistent_edges || rep.out_of_range_indices ||
        rep.nonfinite_vertices || rep.duplicate_triangles || rep.inverted ||
        rep.degenerate_triangles > stats->rounding_flat_triangles) {
        fprintf(stderr, "fuzz_eval: invalid result: %zu triangles, %zu boundary, %zu "
                "inconsistent edges, %zu duplicate, %zu degenerate triangles (%zu reported "
                "flat by rounding), inverted %d\n", out->triangle_count, rep.boundary_edges,
                rep.inconsistent_edges, rep.duplicate_triangles, rep.degenerate_triangles,
                stats->rounding_flat_triangles, rep.inverted);
        abort();
    }
}

/* MCSG_FUZZ_DUMP: the tree as OFF leaves and a CSG file, for the command-line tool. */
static void print_node(FILE *f, const mcsg_tree *tree, mcsg_node_id id, int depth)
{
    static const char *names[] = {"leaf", "union", "intersection", "difference"};
    mcsg_node_kind kind = mcsg_tree_node_kind(tree, id);
    fprintf(f, "%*s", 2 * depth, "");
    if (kind == MCSG_NODE_LEAF) {
        fprintf(f, "import(\"leaf%u.off\");\n", id);
        return;
    }
    fprintf(f, "%s() {\n", names[kind]);
    for (size_t c = 0; c < mcsg_tree_child_count(tree, id); c++)
        print_node(f, tree, mcsg_tree_child(tree, id, c), depth + 1);
    fprintf(f, "%*s}\n", 2 * depth, "");
}

static void dump_tree(const mcsg_tree *tree)
{
    const char *dir = getenv("MCSG_FUZZ_DUMP");
    char path[4096];
    FILE *f;
    if (!dir)
        return;
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++) {
        if (mcsg_tree_node_kind(tree, id) != MCSG_NODE_LEAF)
            continue;
        snprintf(path, sizeof path, "%s/leaf%u.off", dir, id);
        mcsg_mesh_write(path, MCSG_FORMAT_OFF, mcsg_tree_leaf_mesh(tree, id), NULL, NULL);
    }
    snprintf(path, sizeof path, "%s/tree.scad", dir);
    f = fopen(path, "w");
    if (f) {
        print_node(f, tree, mcsg_tree_root(tree), 0);
        fclose(f);
    }
}

static mcsg_status build(reader *r, const mcsg_options *opts, mcsg_tree *tree, int *valid)
{
    mcsg_node_id pending[MAX_LEAVES];
    size_t count = 1 + next(r) % MAX_LEAVES;
    mcsg_status st = MCSG_OK;
    for (size_t i = 0; i < count && st == MCSG_OK; i++) {
        mcsg_mesh mesh;
        double m[12];
        int shape_ok, finite;
        st = make_shape(r, opts, &mesh, &shape_ok);
        if (st != MCSG_OK)
            return st;
        make_transform(r, m, &finite);
        *valid &= shape_ok && finite;
        st = mcsg_tree_add_leaf(tree, &mesh, m, NULL, &pending[i], NULL);
        mcsg_mesh_free(&mesh, opts);
    }
    while (st == MCSG_OK && count > 1) {
        static const mcsg_node_kind ops[3] = {MCSG_NODE_UNION, MCSG_NODE_INTERSECTION,
                                              MCSG_NODE_DIFFERENCE};
        mcsg_node_kind op = ops[next(r) % 3];
        size_t take = 2 + next(r) % 3, at;
        take = take > count ? count : take;
        at = next(r) % (count - take + 1);
        st = mcsg_tree_add_op(tree, op, pending + at, take, NULL, &pending[at], NULL);
        memmove(pending + at + 1, pending + at + take, (count - at - take) * sizeof *pending);
        count -= take - 1;
    }
    if (st == MCSG_OK)
        st = mcsg_tree_set_root(tree, pending[0], NULL);
    return st;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_budget b = {0};
    reader r = {data, size, 0};
    mcsg_options opts;
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_eval_stats stats;
    mcsg_error err;
    mcsg_status st;
    int valid = 1;
    opts = capped_options(&b);
    opts.threads = 1;
    st = mcsg_tree_create(&opts, &tree, NULL);
    if (st == MCSG_OK)
        st = build(&r, &opts, tree, &valid);
    if (st == MCSG_OK) {
        dump_tree(tree);
        st = mcsg_eval(tree, &opts, &out, NULL, &stats, &err);
        if (st == MCSG_OK) {
            /* A leaf from raw bytes may intersect itself (not checked by mcsg_eval):
             * then only a clean return is required. */
            if (valid)
                check_result(&out, &stats);
            mcsg_mesh_free(&out, &opts);
        } else if (st == MCSG_ERR_INTERNAL || (valid && st != MCSG_ERR_NOMEM) ||
                   (st != MCSG_ERR_INVALID_MESH && st != MCSG_ERR_NOMEM &&
                    st != MCSG_ERR_LIMIT)) {
            fprintf(stderr, "fuzz_eval: mcsg_eval: %s: %s (leaves valid: %d)\n",
                    mcsg_status_string(st), err.message, valid);
            abort();
        }
    } else if (st != MCSG_ERR_NOMEM && st != MCSG_ERR_INVALID_ARG && st != MCSG_ERR_LIMIT &&
               st != MCSG_ERR_INVALID_MESH) {
        abort();
    }
    mcsg_tree_free(tree);
    if (b.live != 0)
        abort(); /* a leak */
    return 0;
}
