/*
 * Open-ended differential CSG fuzzing (`make fuzz-csg SECONDS=N`): random trees from
 * csg_fuzz.c, each evaluated and checked against the winding-number oracle, until N
 * seconds have passed. Every failing case is shrunk (up to 60 s) and saved as
 * DIR/seed-<seed>.scad (DIR: the second argument, by default the source tree's
 * tests/data/csg-regressions), where test_eval_oracle runs it on every test run: a
 * finding is a regression test as soon as it is written. Seeds start from the clock
 * (or from the third argument) and are printed, so a run can be repeated.
 *
 * usage: fuzz_csg SECONDS [DIR [FIRST_SEED]]; exit status 1 if anything failed.
 *        With MCSG_FUZZ_LIST_BROKEN set, every tree whose output is reported broken by
 *        rounding is printed (seed, family, the guarantee broken): the cases to study.
 *        fuzz_csg print SEED   prints the tree of one seed as a CSG file (imports relative
 *                              to tests/data/models).
 * The models are found through MCSG_TEST_DATA (tests/data), as under CTest.
 */
#include "csg_fuzz.h"
#include "testlib.h"

#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#ifndef MCSG_REGRESSION_DIR
#define MCSG_REGRESSION_DIR "tests/data/csg-regressions"
#endif

static void save_case(const char *dir, csg_tree_spec *t, bool with_provenance)
{
    char path[4096];
    csg_result r;
    FILE *f;
    csg_shrink(t, with_provenance, 60);
    csg_run_case(t, NULL, with_provenance, &r);
    snprintf(path, sizeof path, "%s/seed-%016" PRIx64 ".scad", dir, t->seed);
    f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "fuzz_csg: cannot write %s\n", path);
        return;
    }
    csg_print_case(f, t, with_provenance);
    fprintf(f, "// Shrunk to %d leaves; it failed with: %s\n", csg_reachable_leaves(t), r.why);
    fclose(f);
    printf("  saved %s (%d leaves): %s\n", path, csg_reachable_leaves(t), r.why);
}

/* What the outputs reported broken by rounding break, and why evaluating them again did
 * not mend them: the counts that tell where snap rounding stands. */
typedef struct broken_tally {
    long welded, crossing, degenerate, open, index_nonmanifold;
    char reason[12][48];
    long reason_count[12];
    int reasons;
} broken_tally;

/* A reason without its numbers and example coordinates: its kind. */
static void reason_kind(const char *why, char *kind, size_t size)
{
    const char *p = strstr(why, "rounded result: ");
    size_t n = 0;
    p = p ? p + strlen("rounded result: ") : why;
    for (; *p && *p != '(' && *p != ',' && n + 1 < size; p++)
        if (*p < '0' || *p > '9')
            kind[n++] = *p;
    kind[n] = '\0';
}

static void tally_broken(broken_tally *b, const csg_result *r)
{
    char kind[48];
    int k;
    b->welded += r->check.welded_nonmanifold_edges > 0;
    b->crossing += r->check.crossing_pairs > 0;
    b->degenerate += r->check.degenerate_triangles > 0;
    b->open += r->check.open_edges + r->check.misoriented_edges > 0;
    b->index_nonmanifold += r->check.index_nonmanifold_edges > 0;
    reason_kind(r->reevaluation[0] ? r->reevaluation : "every round failed its check", kind,
                sizeof kind);
    for (k = 0; k < b->reasons && strcmp(b->reason[k], kind) != 0; k++)
        ;
    if (k == b->reasons && b->reasons == 12)
        k = 11;
    else if (k == b->reasons)
        snprintf(b->reason[b->reasons++], sizeof b->reason[0], "%s", kind);
    b->reason_count[k]++;
}

static void print_broken(const broken_tally *b)
{
    printf("broken by rounding: %ld non-manifold once welded, %ld crossing, %ld zero-area, "
           "%ld open or misoriented, %ld not manifold by index; evaluating again failed by:\n",
           b->welded, b->crossing, b->degenerate, b->open, b->index_nonmanifold);
    for (int k = 0; k < b->reasons; k++)
        printf("  %6ld %s\n", b->reason_count[k], b->reason[k]);
}

static void print_broken_case(const csg_tree_spec *t, bool with_provenance,
                              const csg_result *r)
{
    const mcsg_output_check *c = &r->check;
    printf("broken seed 0x%016" PRIx64 " family %s provenance %s: %zu welded, %zu crossing, "
           "%zu zero-area, %zu open; %s\n", t->seed, csg_family_names[t->family],
           with_provenance ? "yes" : "no", c->welded_nonmanifold_edges, c->crossing_pairs,
           c->degenerate_triangles, c->open_edges,
           r->reevaluation[0] ? r->reevaluation : "every round failed its check");
    fflush(stdout);
}

int main(int argc, char **argv)
{
    double seconds = argc > 1 ? atof(argv[1]) : 60, start = csg_now();
    const char *dir = argc > 2 ? argv[2] : MCSG_REGRESSION_DIR;
    uint64_t first = argc > 3 ? strtoull(argv[3], NULL, 0) : (uint64_t)(start * 1e6);
    static csg_tree_spec t;
    static broken_tally broken;
    if (argc == 3 && strcmp(argv[1], "print") == 0) {
        csg_load_models();
        csg_random_tree(&t, strtoull(argv[2], NULL, 0));
        csg_print_case(stdout, &t, false);
        csg_free_models();
        return 0;
    }
    long trees = 0, failures = 0, leaves = 0, reported = 0;
    bool list_broken = getenv("MCSG_FUZZ_LIST_BROKEN") != NULL;
    long self_intersecting[CSG_FAMILIES] = {0}, families[CSG_FAMILIES] = {0};
    long framed[2] = {0, 0}, framed_broken[2] = {0, 0}; /* export trees not framed, framed */
    if (!csg_load_models())
        fprintf(stderr, "fuzz_csg: models of tests/data/models missing (set MCSG_TEST_DATA to tests/data): "
                "free trees use primitives only\n");
    csg_self_check = true;
    printf("fuzz_csg: %.0f s from seed number %" PRIu64 ", failures saved in %s\n", seconds,
           first, dir);
    fflush(stdout);
    for (uint64_t i = first; csg_now() - start < seconds; i++) {
        uint64_t seed = csg_mix_seed(i);
        bool with_provenance = i % 2 == 0;
        csg_result r;
        csg_random_tree(&t, seed);
        trees++;
        families[t.family]++;
        framed[t.framed] += t.family == CSG_EXPORT;
        leaves += t.leaf_count;
        if (csg_run_case(&t, NULL, with_provenance, &r)) {
            self_intersecting[t.family] += r.self_intersecting;
            reported += r.rounding_reported;
            framed_broken[t.framed] += t.family == CSG_EXPORT && r.rounding_reported;
            if (r.rounding_reported)
                tally_broken(&broken, &r);
            if (r.rounding_reported && list_broken)
                print_broken_case(&t, with_provenance, &r);
            continue;
        }
        failures++;
        printf("seed 0x%016" PRIx64 " (%d leaves): %s\n", seed, t.leaf_count, r.why);
        save_case(dir, &t, with_provenance);
        fflush(stdout);
    }
    printf("fuzz_csg: %ld trees (", trees);
    for (int k = 0; k < CSG_FAMILIES; k++)
        printf("%s%ld %s", k ? ", " : "", families[k], csg_family_names[k]);
    printf("; %ld leaves) in %.0f s, %ld failed; outputs that intersect themselves: ", leaves,
           csg_now() - start, failures);
    for (int k = 0; k < CSG_FAMILIES; k++)
        printf("%s%ld %s", k ? ", " : "", self_intersecting[k], csg_family_names[k]);
    printf("; %ld reported broken by rounding\n", reported);
    printf("export trees: %ld with their turn written around the tree (a frame), %ld reported "
           "broken; %ld with it in every leaf, %ld broken\n", framed[1], framed_broken[1],
           framed[0], framed_broken[0]);
    print_broken(&broken);
    csg_free_models();
    return failures ? 1 : 0;
}
