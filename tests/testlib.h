/*
 * A minimal test harness: CHECK-style assertions that count and report failures and
 * keep going, plus helpers to find test data. Each test file defines test cases with
 * TEST(name) and lists them in main via RUN(name); main returns test_summary().
 */
#ifndef MCSG_TESTLIB_H
#define MCSG_TESTLIB_H

#include "meshcsg.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

extern int test_failures;
extern int test_checks;

void test_fail(const char *file, int line, const char *fmt, ...);

#define CHECK(cond)                                                                       \
    do {                                                                                  \
        test_checks++;                                                                    \
        if (!(cond))                                                                      \
            test_fail(__FILE__, __LINE__, "CHECK(%s)", #cond);                            \
    } while (0)

#define CHECK_MSG(cond, ...)                                                              \
    do {                                                                                  \
        test_checks++;                                                                    \
        if (!(cond))                                                                      \
            test_fail(__FILE__, __LINE__, __VA_ARGS__);                                   \
    } while (0)

#define CHECK_EQ_SIZE(a, b)                                                               \
    do {                                                                                  \
        size_t a_ = (size_t)(a), b_ = (size_t)(b);                                        \
        test_checks++;                                                                    \
        if (a_ != b_)                                                                     \
            test_fail(__FILE__, __LINE__, "%s == %s: %zu != %zu", #a, #b, a_, b_);       \
    } while (0)

#define CHECK_EQ_DOUBLE(a, b)                                                             \
    do {                                                                                  \
        double a_ = (a), b_ = (b);                                                        \
        test_checks++;                                                                    \
        if (!(a_ == b_))                                                                  \
            test_fail(__FILE__, __LINE__, "%s == %s: %.17g != %.17g", #a, #b, a_, b_);   \
    } while (0)

/* Status check: prints the error message when a call that should succeed fails. */
#define CHECK_OK(call, errp)                                                              \
    do {                                                                                  \
        mcsg_status st_ = (call);                                                         \
        test_checks++;                                                                    \
        if (st_ != MCSG_OK)                                                               \
            test_fail(__FILE__, __LINE__, "%s failed: %s", #call, (errp)->message);       \
    } while (0)

/* The message of a failing call must contain `needle`. */
#define CHECK_CONTAINS(haystack, needle)                                                  \
    do {                                                                                  \
        test_checks++;                                                                    \
        if (!strstr((haystack), (needle)))                                                \
            test_fail(__FILE__, __LINE__, "expected \"%s\" in \"%s\"", (needle),          \
                      (haystack));                                                        \
    } while (0)

#define TEST(name) static void name(void)
#define RUN(name)                                                                         \
    do {                                                                                  \
        int before_ = test_failures;                                                      \
        name();                                                                           \
        printf("%s %s\n", test_failures == before_ ? "ok  " : "FAIL", #name);             \
        test_cases++;                                                                     \
        if (test_failures != before_)                                                     \
            test_cases_failed++;                                                          \
    } while (0)

extern int test_cases;
extern int test_cases_failed;

/* Exit status of a test binary that skipped its checks (CTest's SKIP_RETURN_CODE). */
#define TEST_SKIPPED 77

/* Prints "N passed, M failed" and returns the process exit code. A test binary that ran
 * no check at all fails (a test that checks nothing must not pass), unless test_skip was
 * called: then it returns TEST_SKIPPED, which CTest reports as skipped, never as passed. */
int test_summary(void);

/* Marks the binary as skipped, printing why (e.g. optional data missing). Checks that
 * still fail make it fail. */
void test_skip(const char *why);

/* Path of a model under tests/data/models (part of the project). Static buffer. */
const char *test_model(const char *name);
/* The optional folder of larger models, $MCSG_SHARED_DIR/models (../shared/models next
 * to a checkout), or NULL when it does not exist. Static buffer. */
const char *test_shared_models_dir(void);
/* Path of a file under tests/data. Static buffer. */
const char *test_data(const char *name);
/* Path of a scratch file in the build tree. Static buffer. */
const char *test_tmp(const char *name);

/* xorshift64 step on a caller-owned state (each test file keeps its own seed, so that
 * its cases do not depend on what other code draws). */
uint64_t test_xorshift(uint64_t *state);
/* Uniform-ish integer in [lo, hi] from test_xorshift. */
int test_random_int(uint64_t *state, int lo, int hi);

/* Read a mesh from a string in the given format; aborts the test case on failure. */
bool test_read_string(const char *text, mcsg_format format, mcsg_mesh *out, mcsg_error *err);

/* ---- mesh helpers ---- */

/* Signed volume of a triangle mesh (positive when outward); 0 for NULL. */
double test_signed_volume(const mcsg_mesh *m);
/* Parse CSG text (mcsg_scad_read_memory, imports relative to ".") and evaluate it. */
mcsg_status test_eval_scad(const char *text, const mcsg_options *opts, mcsg_mesh *out,
                           mcsg_eval_stats *stats, mcsg_error *err);
/* Edges (undirected vertex-index pairs, vertices NOT identified by coordinates) that are
 * not used exactly once in each direction, plus vertices whose triangles do not form a
 * single umbrella: 0 for an index-manifold closed oriented mesh. */
size_t test_index_manifold_defects(const mcsg_mesh *m);
/* The four faces of tetrahedron q (vertex ids into xyz) as triangles tris[0 .. 12),
 * each turned so that the fourth corner is behind it (faces outward). */
void test_put_tetrahedron(const double *xyz, const uint32_t q[4], uint32_t *tris);
/* Equal bit for bit, except that any NaN equals any NaN. */
bool test_same_double(double a, double b);
/* Same counts, vertices (test_same_double) and triangles; false if either is NULL. */
bool test_same_mesh(const mcsg_mesh *a, const mcsg_mesh *b);

/* ---- allocation failures ---- */

/* A counting allocator for mcsg_options. Call number fail_at of malloc or realloc fails
 * (1: the first; 0: none), and with `sticky` every later call fails too. realloc(NULL)
 * counts as a malloc. `live` counts blocks not yet freed, `largest` the largest request. */
typedef struct test_allocator {
    long calls;
    long fail_at;
    bool sticky;
    long live;
    size_t largest;
} test_allocator;

/* Default options whose allocator is `a`. */
mcsg_options test_allocator_options(test_allocator *a);

/* One run of the code under test with `opts`: it checks its own results, frees all it
 * allocated before returning, and returns its status (the message in *err). */
typedef mcsg_status (*test_alloc_run)(const void *ctx, const mcsg_options *opts,
                                      mcsg_error *err);

/* Runs `run` failing allocation 1, 2, ... (each once alone and once with all later ones)
 * until a run makes no failing allocation. Every run must end with nothing allocated, and
 * each other run must fail with MCSG_ERR_NOMEM and an "out of memory" message, or, if
 * `may_absorb`, may succeed (the failed allocation was optional, e.g. a trim). Returns the
 * allocation count of the run without failure, or -1 after reporting the first problem.
 * `what` names the case in messages. */
long test_allocation_failures(const char *what, test_alloc_run run, const void *ctx,
                              bool may_absorb);

#endif
