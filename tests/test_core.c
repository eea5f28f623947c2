/*
 * Core helpers: the keyed sort (introsort, and an in-place radix sort for long arrays)
 * and the 64-bit integer sort (sort_template.h, its heap sort too) against a qsort
 * reference on random, sorted, reversed, constant, organ-pipe, edge-key and equal-rank
 * inputs of many sizes, and the key lookup on the sorted result; the
 * parallel loop (every task once, the first failing position reported whatever the
 * thread count, with threads per loop or a pool), the pool's short and nested loops and
 * the heaviest-first order; mcsg_version against the header.
 */
#include "testlib.h"
#include "base/parallel.h"
#include "base/sort.h"
#include "base/core.h"
#include "base/sort_template.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int compare_reference(const void *x, const void *y)
{
    const mci_keyed *a = x, *b = y;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return (a->ref > b->ref) - (a->ref < b->ref);
}

static uint64_t next_random(uint64_t *state)
{
    *state = *state * 6364136223846793005u + 1442695040888963407u;
    return *state >> 11;
}

/* Fill items with pattern p: 0 random with many equal keys, 1 sorted, 2 reversed,
 * 3 one key, 4 organ pipe, 5 random 64-bit keys (refs distinct and unordered); 6 edge
 * keys with small refs, 7 a few keys and refs (equal ranks). */
static void fill(mci_keyed *items, size_t n, int pattern, uint64_t *rng)
{
    for (size_t i = 0; i < n; i++) {
        uint64_t k;
        switch (pattern) {
        case 0: k = next_random(rng) % (n / 4 + 1); break;
        case 1: k = i; break;
        case 2: k = n - i; break;
        case 3: k = 42; break;
        case 4: k = i < n / 2 ? i : n - i; break;
        default: k = next_random(rng) << 11 ^ next_random(rng); break;
        }
        items[i].key = k;
        items[i].ref = (uint32_t)i * 2654435761u; /* odd multiplier: distinct, unordered */
        if (pattern == 6) {
            items[i].key = mci_edge_key((uint32_t)(next_random(rng) % 70000),
                                        (uint32_t)(next_random(rng) % 70000));
            items[i].ref = (uint32_t)(next_random(rng) % (n + 1));
        } else if (pattern == 7) {
            items[i].key = next_random(rng) % 3;
            items[i].ref = (uint32_t)(next_random(rng) % 5);
        }
    }
}

/* Field by field: struct padding is not copied reliably. */
static bool same_order(const mci_keyed *a, const mci_keyed *b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (a[i].key != b[i].key || a[i].ref != b[i].ref)
            return false;
    return true;
}

/* Arrays over 1,024 items take the in-place radix sort (digits skipped or not, deep
 * buckets handed back to the introsort), shorter ones the introsort: both must give
 * qsort's order. */
TEST(keyed_sort_matches_qsort)
{
    static const size_t sizes[] = {0, 1, 2, 3, 15, 16, 17, 100, 1000, 4096, 4097, 50000,
                                   200000};
    uint64_t rng = 12345;
    for (size_t s = 0; s < sizeof sizes / sizeof *sizes; s++) {
        size_t n = sizes[s];
        mci_keyed *a = malloc((n + 1) * sizeof *a), *b = malloc((n + 1) * sizeof *b);
        CHECK(a && b);
        for (int pattern = 0; a && b && pattern < 8; pattern++) {
            fill(a, n, pattern, &rng);
            memcpy(b, a, n * sizeof *a);
            mci_sort_keyed(a, n);
            if (n)
                qsort(b, n, sizeof *b, compare_reference);
            CHECK_MSG(same_order(a, b, n), "size %zu pattern %d: order differs from qsort", n,
                      pattern);
            for (size_t i = 0; n && i < n; i += 1 + n / 7)
                CHECK(a[mci_find_key(a, n, a[i].key)].key == a[i].key &&
                      mci_find_key(a, n, a[i].key) <= i);
        }
        free(a);
        free(b);
    }
}

static int compare_u64_reference(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

static inline bool u64_before(const uint64_t *a, const uint64_t *b)
{
    return *a < *b;
}

/* The template instantiated here too, so that its heap sort (taken when the recursion
 * budget runs out, which median-of-three pivots make rare) is tested directly. */
MCI_DEFINE_SORT(test_sort_u64, uint64_t, u64_before)

/* mci_sort_u64 (sort_template.h's introsort), the template's heap sort and introsort
 * with a small recursion budget, and mci_radix_sort_u64, against qsort on the same
 * patterns; mci_unique_u64 on the sorted result. */
TEST(u64_sorts_match_qsort)
{
    static const size_t sizes[] = {0, 1, 2, 3, 15, 16, 17, 18, 100, 1000, 50000};
    uint64_t rng = 777;
    mci_ctx ctx;
    mcsg_options opts = {0};
    mci_ctx_init(&ctx, &opts);
    for (size_t s = 0; s < sizeof sizes / sizeof *sizes; s++) {
        size_t n = sizes[s];
        mci_keyed *items = malloc((n + 1) * sizeof *items);
        uint64_t *ref = malloc((n + 1) * sizeof *ref), *got = malloc((n + 1) * sizeof *got);
        CHECK(items && ref && got);
        for (int pattern = 0; items && ref && got && pattern < 8; pattern++) {
            fill(items, n, pattern, &rng);
            for (size_t i = 0; i < n; i++)
                ref[i] = items[i].key;
            if (n)
                qsort(ref, n, sizeof *ref, compare_u64_reference);
            for (int variant = 0; variant < 5; variant++) {
                for (size_t i = 0; i < n; i++)
                    got[i] = items[i].key;
                if (variant == 0)
                    mci_sort_u64(got, n);
                else if (variant == 1)
                    test_sort_u64(got, n);
                else if (variant == 2)
                    test_sort_u64_heap(got, n);
                else if (variant == 3)
                    test_sort_u64_intro(got, n, 2);
                else
                    CHECK(mci_radix_sort_u64(&ctx, got, n));
                CHECK_MSG(n == 0 || memcmp(got, ref, n * sizeof *got) == 0,
                          "size %zu pattern %d variant %d: order differs from qsort", n,
                          pattern, variant);
                if (variant == 0) { /* mci_unique_u64 against a plain count of changes */
                    size_t expected = 0, kept = mci_unique_u64(got, n);
                    for (size_t i = 0; i < n; i++)
                        expected += i == 0 || ref[i] != ref[i - 1];
                    CHECK_EQ_SIZE(kept, expected);
                    for (size_t i = 1; i < kept; i++)
                        CHECK(got[i - 1] < got[i]);
                }
            }
        }
        free(items);
        free(ref);
        free(got);
    }
}

TEST(find_key_reports_missing_keys)
{
    mci_keyed items[4] = {{2, 0}, {4, 1}, {4, 2}, {9, 3}};
    CHECK_EQ_SIZE(mci_find_key(items, 4, 4), 1);
    CHECK_EQ_SIZE(mci_find_key(items, 4, 3), 4);
    CHECK_EQ_SIZE(mci_find_key(items, 4, 10), 4);
    CHECK_EQ_SIZE(mci_find_key(items, 0, 2), 0);
}

enum { TASKS = 1000 };

typedef struct task_log {
    atomic_int runs[TASKS];
    const int *fail; /* tasks that fail, ended by -1 */
} task_log;

static mcsg_status logged_task(void *user, size_t i, mcsg_error *err)
{
    task_log *log = user;
    atomic_fetch_add(&log->runs[i], 1);
    for (const int *f = log->fail; *f >= 0; f++)
        if ((size_t)*f == i) {
            err->status = MCSG_ERR_INTERNAL;
            snprintf(err->message, sizeof err->message, "task %zu failed", i);
            return MCSG_ERR_INTERNAL;
        }
    return MCSG_OK;
}

static void run_tasks(const mci_ctx *ctx, const uint32_t *order, const int *fail,
                      task_log *log, mcsg_status *st, mcsg_error *err)
{
    for (int i = 0; i < TASKS; i++)
        atomic_init(&log->runs[i], 0);
    log->fail = fail;
    *st = mci_parallel_for_order(ctx, TASKS, order, logged_task, log, err);
}

static int ran_once(const task_log *log)
{
    int once = 0;
    for (int i = 0; i < TASKS; i++)
        once += atomic_load(&log->runs[i]) == 1;
    return once;
}

static mci_ctx ctx_with_threads(int threads, bool pooled)
{
    mci_ctx ctx;
    mcsg_options opts = {0};
    opts.threads = threads;
    mci_ctx_init(&ctx, &opts);
    if (pooled)
        mci_pool_start(&ctx);
    return ctx;
}

/* With threads started per loop and with a pool: the pool's workers must pick up every
 * loop posted after the first and never run a task twice. */
TEST(parallel_loop_runs_every_task_once_and_reports_the_first_failure)
{
    /* late: positions past the first 256, which are claimed in batches */
    static const int none[] = {-1}, two[] = {800, 37, -1}, late[] = {700, 650, -1};
    static task_log log;
    uint32_t reversed[TASKS];
    mcsg_error err;
    mcsg_status st;
    for (int i = 0; i < TASKS; i++)
        reversed[i] = (uint32_t)(TASKS - 1 - i);
    for (int threads = 1; threads <= 4; threads++) {
        for (int pooled = 0; pooled < 2; pooled++) {
            mci_ctx ctx = ctx_with_threads(threads, pooled);
            CHECK_MSG((ctx.pool != NULL) == (pooled && threads > 1), "%d threads: pool %p",
                      threads, (void *)ctx.pool);
            run_tasks(&ctx, NULL, none, &log, &st, &err);
            CHECK(st == MCSG_OK);
            CHECK_MSG(ran_once(&log) == TASKS, "%d threads, pool %d: %d of %d tasks ran once",
                      threads, pooled, ran_once(&log), TASKS);
            run_tasks(&ctx, reversed, none, &log, &st, &err);
            CHECK_MSG(ran_once(&log) == TASKS, "%d threads, pool %d, reversed: %d tasks ran once",
                      threads, pooled, ran_once(&log));
            /* In index order task 37 comes first; in reversed order task 800 does. */
            run_tasks(&ctx, NULL, two, &log, &st, &err);
            CHECK(st == MCSG_ERR_INTERNAL && strcmp(err.message, "task 37 failed") == 0);
            run_tasks(&ctx, reversed, two, &log, &st, &err);
            CHECK(st == MCSG_ERR_INTERNAL && strcmp(err.message, "task 800 failed") == 0);
            run_tasks(&ctx, NULL, late, &log, &st, &err);
            CHECK(st == MCSG_ERR_INTERNAL && strcmp(err.message, "task 650 failed") == 0);
            run_tasks(&ctx, reversed, late, &log, &st, &err);
            CHECK(st == MCSG_ERR_INTERNAL && strcmp(err.message, "task 700 failed") == 0);
            mci_pool_stop(&ctx);
            CHECK(ctx.pool == NULL);
        }
    }
}

/* Many short loops in a row on one pool (workers arrive late, or after the caller has
 * withdrawn the loop), and loops started from inside a task (they run in that thread). */
enum { OUTER = 6, SHORT_LOOPS = 400 };

typedef struct nest_job {
    const mci_ctx *ctx;
    task_log inner[OUTER];
    mcsg_status inner_status[OUTER];
} nest_job;

static mcsg_status nested_task(void *user, size_t i, mcsg_error *err)
{
    static const int none[] = {-1};
    nest_job *j = user;
    run_tasks(j->ctx, NULL, none, &j->inner[i], &j->inner_status[i], err);
    return j->inner_status[i];
}

static mcsg_status count_task(void *user, size_t i, mcsg_error *err)
{
    (void)err;
    atomic_fetch_add(&((atomic_int *)user)[i], 1);
    return MCSG_OK;
}

TEST(pool_runs_short_and_nested_loops)
{
    static nest_job nest;
    for (int threads = 2; threads <= 4; threads++) {
        mci_ctx ctx = ctx_with_threads(threads, true);
        atomic_int counts[3];
        mcsg_error err;
        int wrong = 0;
        for (int k = 0; k < 3; k++)
            atomic_init(&counts[k], 0);
        for (int loop = 0; loop < SHORT_LOOPS; loop++)
            CHECK(mci_parallel_for(&ctx, 3, count_task, counts, &err) == MCSG_OK);
        for (int k = 0; k < 3; k++)
            CHECK_MSG(atomic_load(&counts[k]) == SHORT_LOOPS, "%d threads: task %d ran %d times",
                      threads, k, atomic_load(&counts[k]));
        nest.ctx = &ctx;
        CHECK(mci_parallel_for(&ctx, OUTER, nested_task, &nest, &err) == MCSG_OK);
        for (int k = 0; k < OUTER; k++)
            wrong += nest.inner_status[k] != MCSG_OK || ran_once(&nest.inner[k]) != TASKS;
        CHECK_MSG(wrong == 0, "%d threads: %d nested loops wrong", threads, wrong);
        mci_pool_stop(&ctx);
    }
}

TEST(heaviest_first_moves_only_heavy_tasks)
{
    mci_ctx ctx;
    uint32_t cost[300], *order;
    mci_ctx_init(&ctx, NULL);
    for (int i = 0; i < 300; i++)
        cost[i] = 1;
    cost[7] = 500;  /* over 1/256 of the total: ahead */
    cost[250] = 900;
    cost[100] = 2;  /* not: keeps its place */
    order = mci_heaviest_first(&ctx, cost, 300);
    CHECK(order != NULL);
    if (!order)
        return;
    CHECK(order[0] == 250 && order[1] == 7);
    for (uint32_t i = 2, expect = 0; i < 300; i++, expect++) {
        expect += expect == 7;
        expect += expect == 250;
        CHECK_MSG(order[i] == expect, "position %u: %u, want %u", i, order[i], expect);
    }
    mci_free(&ctx, order);
}

TEST(version_matches_the_header)
{
    char expected[32];
    snprintf(expected, sizeof expected, "%d.%d.%d", MCSG_VERSION_MAJOR, MCSG_VERSION_MINOR,
             MCSG_VERSION_PATCH);
    CHECK_MSG(strcmp(mcsg_version(), expected) == 0, "mcsg_version() %s, header %s",
              mcsg_version(), expected);
}

int main(void)
{
    RUN(keyed_sort_matches_qsort);
    RUN(u64_sorts_match_qsort);
    RUN(find_key_reports_missing_keys);
    RUN(parallel_loop_runs_every_task_once_and_reports_the_first_failure);
    RUN(pool_runs_short_and_nested_loops);
    RUN(heaviest_first_moves_only_heavy_tasks);
    RUN(version_matches_the_header);
    return test_summary();
}
