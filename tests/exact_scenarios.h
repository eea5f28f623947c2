/*
 * The scenarios of test_exact_kernel (exact_scenarios.c): a few input vertices, planes
 * through them, and explicit, LPI and TPI points defined on those, drawn at random from
 * coordinate regimes or built adversarially (nearly parallel planes, exact lattices where
 * one point has many definitions or many points share a line, axis-aligned grids). Each
 * scenario has a class (its generator and regime) for the test's tables, and states what
 * it claims exactly (points on planes, equal points), which the test checks against the
 * reference before trusting the kernel with it.
 *
 * The random stream is one splitmix64 state: a seed reproduces every scenario.
 */
#ifndef MCSG_TESTS_EXACT_SCENARIOS_H
#define MCSG_TESTS_EXACT_SCENARIOS_H

#include "exact/kernel.h"

#include <stdbool.h>
#include <stdint.h>

#define MAXV        48
#define MAXPL       16
#define MAXPT       28
#define MAXLP       6 /* lines where two planes meet (order_on_plane_line) */
#define MAXLE       4 /* edge lines (order_on_edge_line) */
#define MAXLINES    (MAXLP + MAXLE)
#define MAX_CLASSES 40

/* The random stream (splitmix64). */
extern uint64_t rng_state;
uint64_t rng_next(void);
double rng_unit(void);           /* in [0, 1) */
int rng_int(int lo, int hi);     /* inclusive */
bool rng_chance(double p);
double rng_sign(void);           /* +1 or -1 */

/* Coordinate regimes (see draw_coord in exact_scenarios.c). */
enum { R_UNIT, R_INT, R_EXP, R_MIX, R_FAR, R_FARGRID, R_SCALES, R_BITS, R_COUNT };
/* x moved by n ulps in a random direction (stays finite). */
double nudge(double x, int n);

typedef struct point_def {
    mci_point_kind kind;
    int v[2];  /* explicit: v[0]; LPI: line v[0], v[1] */
    int pl[3]; /* LPI: plane pl[0]; TPI: pl[0..2] */
} point_def;

typedef struct scenario {
    int cls; /* class index (class_id) */
    int nv, npl, npt;
    double v[MAXV][3];
    int plv[MAXPL][3];
    point_def pt[MAXPT];
    /* Pairs of planes through a common line and pairs of vertices on that line: the
     * order_on_plane_line / order_on_edge_line queries (run where the reference confirms
     * that both points lie on the line). */
    int nlp, line_planes[MAXLP][2];
    int nle, line_edges[MAXLE][2];
    /* The generator's claim, checked against the reference before the kernel is trusted
     * with it: the points group[] lie on all planes onpl[] (and are all equal if
     * group_equal). Cleared in perturbed copies. */
    int ngroup, group[MAXPT];
    int nonpl, onpl[MAXPL];
    bool group_equal;
} scenario;

/* Scenario classes: "random/unit", "same", ... by index; class_id registers a name. */
extern char class_names[MAX_CLASSES][24];
extern int nclasses;
int class_id(const char *prefix, const char *name);

/* The generators: each fills *s (its class set). */
void scenario_random(scenario *s, int regime);
void scenario_near_parallel(scenario *s, int regime);
/* Points off[a] + i[a] * 2^k[a] per axis, i integer. Every integer combination of lattice
 * points computed in integers is an exact double while |off + i| < 2^53 (so the
 * adversarial constructions below are exact by design; check_claims verifies it).
 * Different scales per axis put 3.4e38, 1e-3 and 1e300 into one point. */
typedef struct lattice {
    const char *name;
    int k[3];
    int64_t off[3];
    int count; /* scenarios per adversarial builder at scale 1 */
} lattice;

/* The adversarial lattices. */
extern const lattice lattices[];
extern const int lattice_count;
void scenario_same(scenario *s, const lattice *L);
void scenario_line(scenario *s, const lattice *L);
void scenario_parallel(scenario *s, const lattice *L);
void scenario_axis_grid(scenario *s);

#endif
