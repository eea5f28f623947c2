/*
 * Random CSG trees checked against an independent membership oracle: the generator,
 * oracle and shrinker shared by test_eval_oracle (a fixed-seed slice in CTest, plus the
 * saved regressions) and fuzz_csg (open-ended differential fuzzing, `make fuzz-csg`).
 * See csg_fuzz.c for what is generated and what is checked.
 */
#ifndef MCSG_CSG_FUZZ_H
#define MCSG_CSG_FUZZ_H

#include "meshcsg.h"

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#define CSG_MAX_LEAVES 100
#define CSG_MAX_NODES (2 * CSG_MAX_LEAVES)
#define CSG_MAX_CHILDREN 4
#define CSG_MAX_DEPTH 12

typedef enum csg_shape { CSG_CUBE, CSG_SPHERE, CSG_CYLINDER, CSG_MODEL } csg_shape;

/* free: random primitives and models under random rigid motions, some leaves sharing
 * another's placement; grid: axis-aligned boxes, cylinders and spheres with small
 * integer coordinates (coplanar faces, shared edges and vertices everywhere); tilted:
 * grid leaves under exact integer similarity transforms, so that planes in general
 * directions are shared exactly; export: trees as OpenSCAD's .csg export writes them,
 * every size and matrix entry with six significant digits (Menger-like grids of boxes,
 * cubes turned by multiples of 15 and 45 degrees, plates drilled by cylinders), turned
 * and moved far from the origin: faces meant to be coplanar are 1e-5 apart or tilted by
 * 1e-16, features below the spacing of doubles; shells: free trees whose primitives
 * carry smaller copies of themselves (one or two, inside or crossing them, each facing
 * out or in), and may face inward themselves: leaves whose solid is where their winding
 * number is positive, with nested and overlapping shells, cavities, and shells that are
 * empty on their own; folds: free trees whose primitives carry exact copies of themselves
 * (the same shell again, or moved by the box's size along one, two or three axes so that
 * they share a face, an edge or a corner with it, each facing out or in), and may have a
 * corner pushed through the opposite side so that they cross themselves: leaves closed
 * only as chains, evaluated with their shells tested first
 * (mcsg_options.check_self_intersections). */
typedef enum csg_family {
    CSG_FREE,
    CSG_GRID,
    CSG_TILTED,
    CSG_EXPORT,
    CSG_SHELLS,
    CSG_FOLDS
} csg_family;
#define CSG_FAMILIES 6
/* The families' names, as the case files' first line and the reports write them. */
extern const char *const csg_family_names[CSG_FAMILIES];

typedef struct csg_leaf_spec {
    csg_shape shape;
    double size[3];   /* cube */
    double r1, r2, h; /* sphere: r1; cylinder: h, r1 at the bottom, r2 at the top */
    int center;       /* cube, cylinder */
    int fn;           /* sphere, cylinder */
    int model;        /* index into the models */
    /* Shells family: copies of the primitive (0..2), each scaled by inner_scale[k] about
     * the centre of the primitive's box and moved by inner_shift[k] times the box's size
     * (0: nested inside; else crossing it); inward[0] turns the primitive itself inside
     * out, inward[1 + k] the copy k. */
    int inner;
    double inner_scale[2], inner_shift[2][3];
    bool inward[3];
    /* Folds family: copy k is exact (vertex + inner_shift[k] times the box's size, the
     * shift -1, 0 or 1 on each axis), and the primitive's first vertex is pushed through
     * to the far side of its box's centre. */
    bool exact_copy[2];
    bool pushed;
    double m[12];     /* row-major 3x4 placement */
} csg_leaf_spec;

typedef struct csg_node_spec {
    mcsg_node_kind kind;
    int leaf; /* index into leaves[] when kind == MCSG_NODE_LEAF */
    int child_count;
    int children[CSG_MAX_CHILDREN]; /* node indices, each smaller than this node's */
} csg_node_spec;

/* Nodes are listed children first; only those reachable from `root` are in the tree
 * (shrinking a failing case drops some). */
typedef struct csg_tree_spec {
    uint64_t seed;
    csg_family family;
    int leaf_count, node_count, root;
    csg_leaf_spec leaves[CSG_MAX_LEAVES];
    csg_node_spec nodes[CSG_MAX_NODES];
    /* Export family, half of the seeds: the shared turn and offset as one multmatrix
     * around the whole tree, as OpenSCAD's export nests it (the leaves' matrices are
     * their own placements); the tree is then built by reading its CSG text, so that
     * the turned group is evaluated in its own frame. */
    bool framed;
    double frame[12];
} csg_tree_spec;

typedef struct csg_result {
    char why[1024];             /* the first problem found */
    size_t points, checked, inside;
    size_t triangles, dropped;
    double eval_seconds, oracle_seconds;
    bool touching;              /* accepted edge-non-manifold output (shared edges) */
    bool rounding_artifacts;    /* closed and oriented, but flat triangles left by rounding */
    bool self_intersecting;     /* with csg_self_check: the rounded output intersects itself */
    bool rounding_reported;     /* the result's check reported a guarantee broken by
                                   rounding (accepted: what snap rounding will fix), and
                                   agreed with the independent checks */
    mcsg_output_check check;    /* the result's own check, as returned */
    char reevaluation[160];     /* why evaluating the rounded result again failed, from
                                   the log; empty when it did not fail */
} csg_result;

/* When set, every output is also tested for self-intersections (counted, not failed:
 * rounding to doubles may create them). */
extern bool csg_self_check;

/* Loads the models used by free trees (tests/data/models: cube.obj, sphere.obj,
 * spot.obj); false if one cannot be read (free trees then use primitives only). */
bool csg_load_models(void);
void csg_free_models(void);
const char *csg_model_name(int index);

uint64_t csg_mix_seed(uint64_t x);
double csg_now(void);

/* A random tree of 5..100 leaves and depth at most CSG_MAX_DEPTH from the seed. */
void csg_random_tree(csg_tree_spec *t, uint64_t seed);
/* Leaves reachable from the root. */
int csg_reachable_leaves(const csg_tree_spec *t);
/* A random leaf of the free family (for hand-made cases). */
void csg_free_leaf(uint64_t *rng, csg_leaf_spec *l);

/* Evaluates `tree` (its leaves' shells tested first if check_inputs) and checks it:
 * status, mesh validity (edge-non-manifold output only with allow_touching), provenance,
 * membership at a few hundred points against the oracle evaluating `claim` (NULL: the
 * same tree; same leaves, maybe other operations), volume. False with r->why on the
 * first problem. */
bool csg_check_tree(const mcsg_tree *tree, const mcsg_tree *claim, uint64_t seed,
                    bool with_provenance, bool allow_touching, bool check_inputs,
                    csg_result *r);
/* The same for a spec (claim may be NULL). */
bool csg_run_case(const csg_tree_spec *t, const csg_tree_spec *claim, bool with_provenance,
                  csg_result *r);
/* Greedy shrinking of a failing case for at most `budget` seconds. */
void csg_shrink(csg_tree_spec *t, bool with_provenance, double budget);

/* The case as a CSG file. The first line is a comment that csg_read_header parses:
 * "// fuzz-csg: seed 0x... family F touching T provenance P". Models are imported by
 * file name: parse with import paths relative to tests/data/models. */
void csg_print_case(FILE *f, const csg_tree_spec *t, bool with_provenance);
/* Parses that first line; false if it is not there. *check_inputs: the family is one
 * whose shells are tested first (csg_check_tree). */
bool csg_read_header(const char *text, uint64_t *seed, bool *touching, bool *with_provenance,
                     bool *check_inputs);

#endif
