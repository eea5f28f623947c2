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

int main(int argc, char **argv)
{
    double seconds = argc > 1 ? atof(argv[1]) : 60, start = csg_now();
    const char *dir = argc > 2 ? argv[2] : MCSG_REGRESSION_DIR;
    uint64_t first = argc > 3 ? strtoull(argv[3], NULL, 0) : (uint64_t)(start * 1e6);
    static csg_tree_spec t;
    if (argc == 3 && strcmp(argv[1], "print") == 0) {
        csg_load_models();
        csg_random_tree(&t, strtoull(argv[2], NULL, 0));
        csg_print_case(stdout, &t, false);
        csg_free_models();
        return 0;
    }
    long trees = 0, failures = 0, leaves = 0, reported = 0;
    long self_intersecting[CSG_FAMILIES] = {0}, families[CSG_FAMILIES] = {0};
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
        leaves += t.leaf_count;
        if (csg_run_case(&t, NULL, with_provenance, &r)) {
            self_intersecting[t.family] += r.self_intersecting;
            reported += r.rounding_reported;
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
    csg_free_models();
    return failures ? 1 : 0;
}
