/*
 * Exact kernel micro-benchmark. For each predicate, on a fixed pre-generated set of
 * 200,000 cases (50,000 for the sets where every call goes exact), reports the calls per
 * second of the combined predicate (median of 5 timed passes), the fraction of cases that
 * the floating-point filter decides alone, the calls per second of the exact stage alone
 * (median of 5 passes over the first 20,000 cases), and the fraction of results that are
 * 0 (which shows that the inputs are what they claim to be).
 *
 * Three input sets, each built from 8192 small scenes:
 *   random      vertices uniform in [-1, 1]^3; points and planes in general position.
 *   degenerate  vertices on the lattice 2^-10 Z^3 inside [-1, 1]^3, so that constructions
 *               are exact. Every point lies on a line L through two vertices; orient3d
 *               tests it against a plane through L that is not one of its own (result 0);
 *               compared and ordered points are one point defined twice, as an LPI of L
 *               and a TPI of two planes through L (result 0); orient2d's points are three
 *               points of L (collinear: 0).
 *   near        the degenerate scenes with a few vertex coordinates moved by one ulp:
 *               results are nonzero, but only just.
 * The constructors are timed on random input, on degenerate input (the line parallel to
 * the plane, three planes through one line: W = 0 must be proved exactly) and on the
 * near versions of those.
 *
 *   bench_kernel [directory]     (the argument is ignored: nothing is written)
 */
#define _POSIX_C_SOURCE 200809L

#include "exact/kernel.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define SCENES      8192
#define CASES       200000 /* random set */
#define SLOW_CASES  50000  /* degenerate and near sets, where every call is exact */
#define EXACT_CASES 20000
#define RUNS        5
/* Constructors write their outputs round-robin into this many slots. */
#define RING 1024

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t rng_state = 0xbe4c4u;

static uint64_t rng_next(void) /* splitmix64 */
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double rng_unit(void) { return (double)(rng_next() >> 11) * 0x1p-53; }

static int rng_int(int lo, int hi)
{
    return lo + (int)(rng_next() % (uint64_t)(hi - lo + 1));
}

/* ---------------------------------------------------------------- scenes */

/* Planes of a scene: P1, P2 (and in degenerate scenes P3) contain the line L = e0 e1. */
enum { P1, P2, P3, Q0, Q1, Q2, Q0N, NPLANES };
enum { NVERTS = 21 };

typedef struct scene {
    double v[NVERTS][3];
    mci_plane pl[NPLANES];
    mci_point ex, lpi[3], tpi[3], on[2];
    /* The plane each point is tested against by orient3d. */
    const mci_plane *t_ex, *t_lpi[3], *t_tpi[3];
    int par0, par1; /* degenerate scenes: a line parallel to P1 */
} scene;

static void plane(scene *s, int p, int a, int b, int c)
{
    mci_plane_init(&s->pl[p], s->v[a], s->v[b], s->v[c]);
}

static void lpi(mci_point *out, scene *s, int l0, int l1, int p)
{
    if (!mci_point_lpi(out, s->v[l0], s->v[l1], &s->pl[p]))
        mci_point_explicit(out, s->v[l0]); /* (probability ~0 on random input) */
}

static void tpi(mci_point *out, scene *s, int p, int q, int r)
{
    if (!mci_point_tpi(out, &s->pl[p], &s->pl[q], &s->pl[r]))
        mci_point_explicit(out, s->pl[p].a);
}

/* Random scene: vertices 0, 1 span L (P1, P2 contain it: on[] can be ordered along it);
 * the other points are in general position. */
static void scene_random(scene *s)
{
    for (int i = 0; i < NVERTS; i++)
        for (int k = 0; k < 3; k++)
            s->v[i][k] = 2 * rng_unit() - 1;
    plane(s, P1, 0, 1, 2);
    plane(s, P2, 1, 0, 3);
    plane(s, P3, 4, 5, 6);
    plane(s, Q0, 7, 8, 9);
    plane(s, Q1, 10, 11, 12);
    plane(s, Q2, 13, 14, 15);
    mci_point_explicit(&s->ex, s->v[16]);
    s->t_ex = &s->pl[Q0];
    lpi(&s->lpi[0], s, 2, 12, Q0);
    lpi(&s->lpi[1], s, 3, 15, Q1);
    lpi(&s->lpi[2], s, 4, 17, Q2);
    tpi(&s->tpi[0], s, Q0, Q1, P3);
    tpi(&s->tpi[1], s, Q1, Q2, P1);
    tpi(&s->tpi[2], s, Q2, P3, Q0);
    for (int k = 0; k < 3; k++) {
        s->t_lpi[k] = &s->pl[Q0 + (k + 1) % 3];
        s->t_tpi[k] = &s->pl[Q0 + (k + 2) % 3];
    }
    lpi(&s->on[0], s, 0, 1, Q0);
    tpi(&s->on[1], s, P1, P2, Q1);
}

/* Lattice point (i, j, k) * 2^-10. */
static void lattice_vertex(scene *s, int v, const int i[3])
{
    for (int k = 0; k < 3; k++)
        s->v[v][k] = i[k] * 0x1p-10;
}

static void lattice_random(scene *s, int v, int range)
{
    int i[3] = {rng_int(-range, range), rng_int(-range, range), rng_int(-range, range)};
    lattice_vertex(s, v, i);
}

/* e0 + t (e1 - e0), exactly (all lattice coordinates stay below 2^10 in magnitude). */
static void lattice_on_line(scene *s, int v, int e0, int e1, int t)
{
    int i[3];
    for (int k = 0; k < 3; k++) {
        double a = s->v[e0][k] * 0x1p10, b = s->v[e1][k] * 0x1p10;
        i[k] = (int)a + t * ((int)b - (int)a);
    }
    lattice_vertex(s, v, i);
}

/* Each coordinate of vertex v moved by one ulp, up or down. */
static void nudge(scene *s, int v)
{
    for (int k = 0; k < 3; k++)
        s->v[v][k] = nextafter(s->v[v][k], rng_int(0, 1) ? 2.0 : -2.0);
}

/* Degenerate scene: L = e0 e1 with lattice points f = e0 + 2(e1 - e0) and
 * g = e0 - (e1 - e0) on it; P1, P2, P3 contain L; Q0..Q2 are random. lpi[k] (an LPI of
 * L) and tpi[k] (a TPI of two P planes and the same Q) are the same point.
 * With `near`, a few vertices are copies moved by one ulp, so that the same predicates
 * are nearly but not exactly degenerate (all three coordinates of each copy are moved,
 * so that no projection hides the difference): g is off L, P2 and P3 do not quite contain L
 * (P2 through a moved e1, P3 through a moved f, which also defines lpi[1]), and the
 * ordered points are two TPIs of P1 and P2 with Q0 and a moved copy of Q0. */
static void scene_lattice(scene *s, bool near)
{
    enum { E0, E1, F, G, PAR0 = 13, PAR1 = 14, E1N = 18, FN, V7N };
    lattice_random(s, E0, 256);
    lattice_random(s, E1, 256);
    lattice_on_line(s, F, E0, E1, 2);
    lattice_on_line(s, G, E0, E1, -1);
    for (int i = 4; i < E1N; i++)
        lattice_random(s, i, 256);
    for (int k = 0; k < 3; k++) /* PAR1 = PAR0 + (e1 - e0): parallel to L, so to P1 */
        s->v[PAR1][k] = s->v[PAR0][k] + (s->v[E1][k] - s->v[E0][k]);
    s->par0 = PAR0, s->par1 = PAR1;
    memcpy(s->v[E1N], s->v[E1], sizeof s->v[0]);
    memcpy(s->v[FN], s->v[F], sizeof s->v[0]);
    memcpy(s->v[V7N], s->v[7], sizeof s->v[0]);
    if (near) {
        nudge(s, G);
        nudge(s, E1N);
        nudge(s, FN);
        nudge(s, V7N);
        nudge(s, PAR1);
    }
    plane(s, P1, E0, E1, 4);
    plane(s, P2, E1N, E0, 5);
    plane(s, P3, FN, 6, E0);
    plane(s, Q0, 7, 8, 9);
    plane(s, Q1, 10, 11, 12);
    plane(s, Q2, 15, 16, 17);
    plane(s, Q0N, V7N, 8, 9);
    mci_point_explicit(&s->ex, s->v[G]);
    s->t_ex = &s->pl[P1];
    lpi(&s->lpi[0], s, E0, E1, Q0);
    lpi(&s->lpi[1], s, FN, E0, Q1);
    lpi(&s->lpi[2], s, E1, F, Q2);
    tpi(&s->tpi[0], s, P1, P2, Q0);
    tpi(&s->tpi[1], s, P2, P3, Q1);
    tpi(&s->tpi[2], s, P3, P1, Q2);
    for (int k = 0; k < 3; k++) {
        s->t_lpi[k] = &s->pl[(k + 2) % 3]; /* a P plane: through L, not the LPI's own */
        s->t_tpi[k] = &s->pl[(k + 2) % 3]; /* the P plane the TPI does not use */
    }
    s->on[0] = s->tpi[0];
    if (near)
        tpi(&s->on[1], s, P2, P1, Q0N);
    else
        s->on[1] = s->lpi[0];
}

/* ---------------------------------------------------------------- cases */

enum { OP_O3D_EX, OP_O3D_LPI, OP_O3D_TPI, OP_CMP, OP_O2D_LPI, OP_O2D_TPI, OP_ORDER, NOPS };
enum { PRED_O3D, PRED_CMP, PRED_O2D, PRED_ORDER };
static const char *const op_names[NOPS] = {
    "orient3d explicit", "orient3d LPI",   "orient3d TPI",       "compare_coord LPI-TPI",
    "orient2d 3 LPI",    "orient2d 3 TPI", "order_on_plane_line"};
static const int op_pred[NOPS] = {PRED_O3D, PRED_O3D, PRED_O3D,  PRED_CMP,
                                  PRED_O2D, PRED_O2D, PRED_ORDER};

typedef struct bcase {
    const mci_point *a, *b, *c;
    const mci_plane *p1, *p2;
    int axis;
} bcase;

static bcase make_case(const scene *s, int op, int k, int axis)
{
    bcase c = {NULL, NULL, NULL, NULL, NULL, axis};
    switch (op) {
    case OP_O3D_EX:
        c.a = &s->ex, c.p1 = s->t_ex;
        break;
    case OP_O3D_LPI:
        c.a = &s->lpi[k], c.p1 = s->t_lpi[k];
        break;
    case OP_O3D_TPI:
        c.a = &s->tpi[k], c.p1 = s->t_tpi[k];
        break;
    case OP_CMP:
        c.a = &s->lpi[k], c.b = &s->tpi[k];
        break;
    case OP_O2D_LPI:
        c.a = &s->lpi[k], c.b = &s->lpi[(k + 1) % 3], c.c = &s->lpi[(k + 2) % 3];
        break;
    case OP_O2D_TPI:
        c.a = &s->tpi[k], c.b = &s->tpi[(k + 1) % 3], c.c = &s->tpi[(k + 2) % 3];
        break;
    default:
        c.a = &s->on[k & 1], c.b = &s->on[!(k & 1)], c.p1 = &s->pl[P1], c.p2 = &s->pl[P2];
        break;
    }
    return c;
}

static void make_cases(bcase *out, size_t n, const scene *scenes, int op)
{
    for (size_t i = 0; i < n; i++)
        out[i] =
            make_case(&scenes[rng_int(0, SCENES - 1)], op, rng_int(0, 2), rng_int(0, 2));
}

/* ---------------------------------------------------------------- timing */

enum { STAGE_COMBINED, STAGE_FILTERED, STAGE_EXACT };

/* One pass of a predicate's stage over n cases. Returns how many results are 0 (combined
 * and exact stages) or decided (filtered stage): the count keeps the calls from being
 * optimized away and gives the statistics without another pass. The switch is outside
 * the loops so that they measure the kernel, not the dispatch. */
static long run_pass(int pred, int stage, const bcase *c, size_t n)
{
    long count = 0;
    size_t i;
    switch (pred * 3 + stage) {
    case PRED_O3D * 3 + STAGE_COMBINED:
        for (i = 0; i < n; i++)
            count += mci_orient3d(c[i].a, c[i].p1) == 0;
        break;
    case PRED_O3D * 3 + STAGE_FILTERED:
        for (i = 0; i < n; i++)
            count += mci_orient3d_filtered(c[i].a, c[i].p1) != MCI_UNCERTAIN;
        break;
    case PRED_O3D * 3 + STAGE_EXACT:
        for (i = 0; i < n; i++)
            count += mci_orient3d_exact(c[i].a, c[i].p1) == 0;
        break;
    case PRED_CMP * 3 + STAGE_COMBINED:
        for (i = 0; i < n; i++)
            count += mci_compare_coord(c[i].a, c[i].b, c[i].axis) == 0;
        break;
    case PRED_CMP * 3 + STAGE_FILTERED:
        for (i = 0; i < n; i++)
            count += mci_compare_coord_filtered(c[i].a, c[i].b, c[i].axis) != MCI_UNCERTAIN;
        break;
    case PRED_CMP * 3 + STAGE_EXACT:
        for (i = 0; i < n; i++)
            count += mci_compare_coord_exact(c[i].a, c[i].b, c[i].axis) == 0;
        break;
    case PRED_O2D * 3 + STAGE_COMBINED:
        for (i = 0; i < n; i++)
            count += mci_orient2d_projected(c[i].a, c[i].b, c[i].c, c[i].axis) == 0;
        break;
    case PRED_O2D * 3 + STAGE_FILTERED:
        for (i = 0; i < n; i++)
            count += mci_orient2d_projected_filtered(c[i].a, c[i].b, c[i].c, c[i].axis) !=
                     MCI_UNCERTAIN;
        break;
    case PRED_O2D * 3 + STAGE_EXACT:
        for (i = 0; i < n; i++)
            count += mci_orient2d_projected_exact(c[i].a, c[i].b, c[i].c, c[i].axis) == 0;
        break;
    case PRED_ORDER * 3 + STAGE_COMBINED:
        for (i = 0; i < n; i++)
            count += mci_order_on_plane_line(c[i].a, c[i].b, c[i].p1, c[i].p2) == 0;
        break;
    default:
        break; /* order_on_plane_line has no separate stages */
    }
    return count;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Calls per second, median of RUNS passes; *count gets run_pass's count. */
static double time_stage(int pred, int stage, const bcase *c, size_t n, long *count)
{
    double t[RUNS];
    for (int r = 0; r < RUNS; r++) {
        double start = now_seconds();
        *count = run_pass(pred, stage, c, n);
        t[r] = now_seconds() - start;
    }
    qsort(t, RUNS, sizeof t[0], compare_doubles);
    return (double)n / t[RUNS / 2];
}

static void print_rate(double calls_per_second)
{
    if (calls_per_second < 0)
        printf(" %12s", "-");
    else if (calls_per_second >= 1e6)
        printf(" %10.2f M", calls_per_second / 1e6);
    else
        printf(" %10.1f k", calls_per_second / 1e3);
}

static void bench_predicate(const char *inputs, const scene *scenes, size_t n, int op,
                            bcase *cases)
{
    int pred = op_pred[op];
    long zeros, decided, unused;
    double combined, exact = -1;
    make_cases(cases, n, scenes, op);
    combined = time_stage(pred, STAGE_COMBINED, cases, n, &zeros);
    if (pred != PRED_ORDER)
        exact = time_stage(pred, STAGE_EXACT, cases, EXACT_CASES, &unused);
    decided = run_pass(pred, STAGE_FILTERED, cases, n);
    printf("%-22s %-10s", op_names[op], inputs);
    print_rate(combined);
    if (pred == PRED_ORDER)
        printf(" %9s", "-");
    else
        printf(" %8.1f%%", 100.0 * (double)decided / (double)n);
    print_rate(exact);
    printf(" %7.1f%%\n", 100.0 * (double)zeros / (double)n);
    fflush(stdout);
}

/* ---------------------------------------------------------------- constructors */

enum { CON_PLANE, CON_LPI, CON_TPI };
static const char *const con_names[] = {"mci_plane_init", "mci_point_lpi", "mci_point_tpi"};

/* One pass of a constructor over CASES inputs taken round-robin from the scenes; returns
 * how many succeeded (planes always do). */
static long construct_pass(int con, scene *scenes, bool degenerate)
{
    static mci_plane planes[RING];
    static mci_point points[RING];
    long ok = 0;
    for (size_t i = 0; i < CASES; i++) {
        scene *s = &scenes[i % SCENES];
        const mci_plane *pl = s->pl;
        if (con == CON_PLANE) {
            mci_plane_init(&planes[i % RING], s->v[i % 7], s->v[7 + i % 5],
                           s->v[12 + i % 6]);
            ok++;
        } else if (con == CON_LPI) {
            ok += degenerate ? mci_point_lpi(&points[i % RING], s->v[s->par0],
                                             s->v[s->par1], &pl[P1])
                             : mci_point_lpi(&points[i % RING], s->v[2], s->v[12], &pl[Q0]);
        } else {
            ok += degenerate ? mci_point_tpi(&points[i % RING], &pl[P1], &pl[P2], &pl[P3])
                             : mci_point_tpi(&points[i % RING], &pl[Q0], &pl[Q1], &pl[P3]);
        }
    }
    return ok;
}

static void bench_constructor(int con, const char *inputs, scene *scenes, bool degenerate)
{
    double t[RUNS];
    long ok = 0;
    for (int r = 0; r < RUNS; r++) {
        double start = now_seconds();
        ok = construct_pass(con, scenes, degenerate);
        t[r] = now_seconds() - start;
    }
    qsort(t, RUNS, sizeof t[0], compare_doubles);
    printf("%-22s %-10s", con_names[con], inputs);
    print_rate(CASES / t[RUNS / 2]);
    printf("   (%.1f%% of the points exist)\n", 100.0 * (double)ok / CASES);
}

int main(void)
{
    scene *random = malloc(SCENES * sizeof *random);
    scene *degenerate = malloc(SCENES * sizeof *degenerate);
    scene *near = malloc(SCENES * sizeof *near);
    bcase *cases = malloc(CASES * sizeof *cases);
    if (!random || !degenerate || !near || !cases) {
        fprintf(stderr, "bench_kernel: out of memory\n");
        return 1;
    }
    for (int i = 0; i < SCENES; i++) {
        scene_random(&random[i]);
        scene_lattice(&degenerate[i], false);
        scene_lattice(&near[i], true);
    }
    printf("cases per row: %d random, %d degenerate or near (exact stage alone: the first "
           "%d); median of %d passes\n\n",
           CASES, SLOW_CASES, EXACT_CASES, RUNS);
    printf("%-22s %-10s %12s %9s %12s %8s\n", "predicate", "inputs", "calls/s", "filtered",
           "exact/s", "result 0");
    for (int op = 0; op < NOPS; op++) {
        bench_predicate("random", random, CASES, op, cases);
        bench_predicate("degenerate", degenerate, SLOW_CASES, op, cases);
        bench_predicate("near", near, SLOW_CASES, op, cases);
    }
    printf("\n%-22s %-10s %12s\n", "constructor", "inputs", "calls/s");
    for (int con = CON_PLANE; con <= CON_TPI; con++) {
        bench_constructor(con, "random", random, false);
        if (con != CON_PLANE) {
            bench_constructor(con, "degenerate", degenerate, true);
            bench_constructor(con, "near", near, true);
        }
    }
    free(random);
    free(degenerate);
    free(near);
    free(cases);
    return 0;
}
