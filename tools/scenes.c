/*
 * In-memory scene generators (see scenes.h). Python's random module is MT19937 seeded
 * by init_by_array with the seed's 32-bit words; random() takes 27 + 26 bits of two
 * draws; uniform(a, b) = a + (b - a) * random(). Reproducing it lets the demo scene
 * match the reference volumes computed by the shared generator.
 */
#include "scenes.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* math.pi; C11 has no M_PI. */
#define SCENE_PI 3.141592653589793

#define MT_N 624
#define MT_M 397

typedef struct python_random {
    uint32_t state[MT_N];
    int index;
} python_random;

static void mt_init_genrand(python_random *r, uint32_t s)
{
    r->state[0] = s;
    for (int i = 1; i < MT_N; i++)
        r->state[i] = 1812433253u * (r->state[i - 1] ^ (r->state[i - 1] >> 30)) + (uint32_t)i;
    r->index = MT_N;
}

/* Python's seed(int) for a non-negative seed below 2^32: init_by_array([seed]). */
static void mt_seed(python_random *r, uint32_t seed)
{
    int i = 1, j = 0;
    mt_init_genrand(r, 19650218u);
    for (int k = MT_N; k > 0; k--) {
        uint32_t prev = r->state[i - 1];
        r->state[i] = (r->state[i] ^ ((prev ^ (prev >> 30)) * 1664525u)) + seed + (uint32_t)j;
        i++;
        j = 0; /* the key has one word */
        if (i >= MT_N) {
            r->state[0] = r->state[MT_N - 1];
            i = 1;
        }
    }
    for (int k = MT_N - 1; k > 0; k--) {
        uint32_t prev = r->state[i - 1];
        r->state[i] = (r->state[i] ^ ((prev ^ (prev >> 30)) * 1566083941u)) - (uint32_t)i;
        i++;
        if (i >= MT_N) {
            r->state[0] = r->state[MT_N - 1];
            i = 1;
        }
    }
    r->state[0] = 0x80000000u;
}

static uint32_t mt_next(python_random *r)
{
    uint32_t y;
    if (r->index >= MT_N) {
        for (int k = 0; k < MT_N; k++) {
            y = (r->state[k] & 0x80000000u) | (r->state[(k + 1) % MT_N] & 0x7fffffffu);
            r->state[k] = r->state[(k + MT_M) % MT_N] ^ (y >> 1) ^ ((y & 1) ? 0x9908b0dfu : 0);
        }
        r->index = 0;
    }
    y = r->state[r->index++];
    y ^= y >> 11;
    y ^= (y << 7) & 0x9d2c5680u;
    y ^= (y << 15) & 0xefc60000u;
    return y ^ (y >> 18);
}

static double py_random(python_random *r)
{
    uint32_t a = mt_next(r) >> 5, b = mt_next(r) >> 6;
    return (a * 67108864.0 + b) * (1.0 / 9007199254740992.0);
}

static double py_uniform(python_random *r, double lo, double hi)
{
    return lo + (hi - lo) * py_random(r);
}

static void set_vertex(double *v, double x, double y, double z)
{
    v[0] = x;
    v[1] = y;
    v[2] = z;
}

static void set_triangle(uint32_t *t, uint32_t a, uint32_t b, uint32_t c)
{
    t[0] = a;
    t[1] = b;
    t[2] = c;
}

static mcsg_status alloc_mesh(mcsg_mesh *m, size_t nv, size_t nt, mcsg_error *err)
{
    memset(m, 0, sizeof *m);
    m->vertices = malloc(nv * 3 * sizeof(double));
    m->triangles = malloc(nt * 3 * sizeof(uint32_t));
    if (!m->vertices || !m->triangles) {
        free(m->vertices);
        free(m->triangles);
        if (err) {
            err->status = MCSG_ERR_NOMEM;
            snprintf(err->message, sizeof err->message, "out of memory building a scene");
        }
        return MCSG_ERR_NOMEM;
    }
    m->vertex_count = nv;
    m->triangle_count = nt;
    return MCSG_OK;
}

static void free_mesh(mcsg_mesh *m)
{
    free(m->vertices);
    free(m->triangles);
}

/* make_scenes.py torus(R, r, 40, 20). */
static mcsg_status make_torus(double R, double r, mcsg_mesh *m, mcsg_error *err)
{
    const int nu = 40, nv = 20;
    size_t f = 0;
    if (alloc_mesh(m, (size_t)nu * nv, (size_t)2 * nu * nv, err) != MCSG_OK)
        return MCSG_ERR_NOMEM;
    for (int i = 0; i < nu; i++) {
        double u = 2 * SCENE_PI * i / nu;
        for (int j = 0; j < nv; j++) {
            double w = 2 * SCENE_PI * j / nv;
            set_vertex(m->vertices + 3 * (size_t)(i * nv + j), (R + r * cos(w)) * cos(u),
                       (R + r * cos(w)) * sin(u), r * sin(w));
        }
    }
    for (int i = 0; i < nu; i++) {
        for (int j = 0; j < nv; j++) {
            uint32_t a = (uint32_t)(i * nv + j), b = (uint32_t)(((i + 1) % nu) * nv + j);
            uint32_t c = (uint32_t)(((i + 1) % nu) * nv + (j + 1) % nv);
            uint32_t d = (uint32_t)(i * nv + (j + 1) % nv);
            set_triangle(m->triangles + 3 * f++, a, b, c);
            set_triangle(m->triangles + 3 * f++, a, c, d);
        }
    }
    return MCSG_OK;
}

/* make_scenes.py sphere(c, r, 10, 10, rot): 82 vertices, 180 triangles. */
static mcsg_status make_uv_sphere(const double c[3], double r, double rot, mcsg_mesh *m,
                                  mcsg_error *err)
{
    const int slices = 10, stacks = 10;
    const uint32_t south = (uint32_t)((stacks - 1) * slices + 1);
    size_t f = 0;
    if (alloc_mesh(m, (size_t)south + 1, 180, err) != MCSG_OK)
        return MCSG_ERR_NOMEM;
    set_vertex(m->vertices, c[0], c[1], c[2] + r);
    for (int i = 1; i < stacks; i++) {
        double th = SCENE_PI * i / stacks;
        for (int j = 0; j < slices; j++) {
            double ph = 2 * SCENE_PI * j / slices + rot;
            set_vertex(m->vertices + 3 * (size_t)(1 + (i - 1) * slices + j),
                       c[0] + r * sin(th) * cos(ph), c[1] + r * sin(th) * sin(ph),
                       c[2] + r * cos(th));
        }
    }
    set_vertex(m->vertices + 3 * (size_t)south, c[0], c[1], c[2] - r);
#define RING(i, j) ((uint32_t)(1 + ((i) - 1) * slices + ((j) % slices)))
    for (int j = 0; j < slices; j++)
        set_triangle(m->triangles + 3 * f++, 0, RING(1, j), RING(1, j + 1));
    for (int i = 1; i < stacks - 1; i++) {
        for (int j = 0; j < slices; j++) {
            uint32_t a = RING(i, j), b = RING(i, j + 1), cc = RING(i + 1, j + 1), d = RING(i + 1, j);
            set_triangle(m->triangles + 3 * f++, a, d, cc);
            set_triangle(m->triangles + 3 * f++, a, cc, b);
        }
    }
    for (int j = 0; j < slices; j++)
        set_triangle(m->triangles + 3 * f++, south, RING(stacks - 1, j + 1), RING(stacks - 1, j));
#undef RING
    return MCSG_OK;
}

static mcsg_status add_leaf(mcsg_tree *tree, mcsg_mesh *mesh, const char *label,
                            mcsg_node_id *id, mcsg_error *err)
{
    mcsg_status st = mcsg_tree_add_leaf(tree, mesh, NULL, label, id, err);
    free_mesh(mesh);
    return st;
}

/* Sphere k of ring_spheres: draws from the stream in make_scenes.py's order. */
static mcsg_status ring_sphere(python_random *rnd, int k, int n, mcsg_mesh *m,
                               mcsg_error *err)
{
    const double R = 10.0, r = 2.5;
    double u = 2 * SCENE_PI * (k + py_random(rnd) * 0.5) / n;
    double w = py_uniform(rnd, 0, 2 * SCENE_PI);
    double rr = r * py_uniform(rnd, 0.85, 1.15);
    double c[3] = {(R + rr * cos(w)) * cos(u), (R + rr * cos(w)) * sin(u), rr * sin(w)};
    double radius = py_uniform(rnd, 0.6, 1.1);
    double rot = py_uniform(rnd, 0, 1);
    return make_uv_sphere(c, radius, rot, m, err);
}

mcsg_status scene_ring_spheres(int n, unsigned seed, const mcsg_options *opts,
                               mcsg_tree **out, mcsg_error *err)
{
    python_random rnd;
    mcsg_tree *tree = NULL;
    mcsg_mesh mesh;
    mcsg_node_id acc, leaf;
    char label[64];
    mcsg_status st = mcsg_tree_create(opts, &tree, err);
    *out = NULL;
    if (st == MCSG_OK)
        st = make_torus(10.0, 2.5, &mesh, err);
    if (st == MCSG_OK)
        st = add_leaf(tree, &mesh, "ring (torus 40x20)", &acc, err);
    mt_seed(&rnd, seed);
    for (int k = 1; st == MCSG_OK && k <= n; k++) {
        mcsg_node_id pair[2];
        snprintf(label, sizeof label, "sphere %d", k);
        st = ring_sphere(&rnd, k - 1, n, &mesh, err);
        if (st == MCSG_OK)
            st = add_leaf(tree, &mesh, label, &leaf, err);
        pair[0] = acc;
        pair[1] = leaf;
        if (st == MCSG_OK)
            st = mcsg_tree_add_op(tree, k % 2 ? MCSG_NODE_UNION : MCSG_NODE_DIFFERENCE, pair,
                                  2, NULL, &acc, err);
    }
    if (st != MCSG_OK) {
        mcsg_tree_free(tree);
        return st;
    }
    *out = tree;
    return MCSG_OK;
}

double scene_ring_spheres_reference_volume(int n)
{
    static const struct {
        int spheres;
        double volume;
    } known[] = {{100, 1218.25668328392}, {200, 1228.83061615465},
                 {400, 1268.90811032719}, {800, 1267.12846189024}};
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
        if (known[i].spheres == n)
            return known[i].volume;
    return 0;
}
