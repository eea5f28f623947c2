/*
 * Parallel loops (base/parallel.c): worker pools, loops over independent tasks with a
 * deterministic first error, and the fixed chunking that keeps results independent of
 * the thread count.
 */
#ifndef MESHCSG_BASE_PARALLEL_H
#define MESHCSG_BASE_PARALLEL_H

#include "base/core.h"

/* Worker threads kept waiting for the parallel loops of one public call (or of many,
 * through mcsg_options.pool): starting a thread per loop cost up to milliseconds per
 * loop (the new thread waited for a sleeping processor), which the short loops could
 * not repay. Workers spin briefly between loops, then sleep.
 * mci_pool_start does nothing when ctx has a pool already (the options'), with one
 * thread, or when threads or memory are short (loops then start their own threads);
 * mci_pool_stop joins and frees the workers it started. A loop started while the pool
 * runs another (from inside a task, or from another call sharing it) runs in the calling
 * thread. */
void mci_pool_start(mci_ctx *ctx);
void mci_pool_stop(mci_ctx *ctx);

/* Run fn(user, i, err) for i in 0 .. count-1 on up to mci_thread_count(ctx) threads
 * (the calling thread included). Tasks must be independent. Returns MCSG_OK, or the
 * status and message of the failing task with the smallest index (once a failure is
 * known, no task after it starts; every task before it runs). */
typedef mcsg_status (*mci_task_fn)(void *user, size_t index, mcsg_error *err);
mcsg_status mci_parallel_for(const mci_ctx *ctx, size_t count, mci_task_fn fn, void *user,
                             mcsg_error *err);
/* The same, running task order[i] at position i: with mci_heaviest_first's order the
 * longest tasks start first and the threads finish together. A failure is reported for
 * the smallest failing position. */
mcsg_status mci_parallel_for_order(const mci_ctx *ctx, size_t count, const uint32_t *order,
                                   mci_task_fn fn, void *user, mcsg_error *err);
/* Indices 0 .. n-1 with the heaviest tasks (each over 1/256 of the total cost) first by
 * decreasing cost, then the others in index order (NULL when out of memory). */
uint32_t *mci_heaviest_first(const mci_ctx *ctx, const uint32_t *cost, size_t n);
/* mci_parallel_for with that order for the costs cost(user, i) (a task's work, roughly):
 * one big task coming last would otherwise run alone. */
typedef uint32_t (*mci_cost_fn)(const void *user, size_t index);
mcsg_status mci_parallel_for_heaviest_first(const mci_ctx *ctx, size_t count, mci_cost_fn cost,
                                            mci_task_fn fn, void *user, mcsg_error *err);
/* A loop over items [0, n) in fixed chunks of `chunk` items (the last may be short),
 * chunks in parallel: fn(user, begin, end, err) for each chunk's items [begin, end).
 * The chunks do not depend on the thread count, so neither do the results; the error
 * reported is the first failing chunk's, as mci_parallel_for. Parallel steps over many
 * small items use this instead of a task per item. */
typedef mcsg_status (*mci_range_fn)(void *user, size_t begin, size_t end, mcsg_error *err);
mcsg_status mci_parallel_for_ranges(const mci_ctx *ctx, size_t n, size_t chunk,
                                    mci_range_fn fn, void *user, mcsg_error *err);
/* Memory that the calling thread keeps while it runs one loop's tasks (serial loops
 * included), or longer within a scope (below): `size` uninitialised bytes from the
 * scope's allocator, allocated at the thread's first call in it (*fresh is then true)
 * and freed when the thread leaves it. NULL outside loops and scopes, when the
 * allocation fails, or when size differs from the first call's. For caches that only
 * save work (exact points: exact/exact_cache.c), which must therefore stay valid
 * however long the scope lasts. */
void *mci_thread_scratch(size_t size, bool *fresh);

/* A scope of the calling thread's scratch over several loops (a whole evaluation): the
 * loops it runs then share it, and a pool's workers keep theirs while the pool lives.
 * mci_scratch_enter returns false, and the scope is not used, when the thread is in a
 * scope already; pass its result to mci_scratch_leave. */
typedef struct mci_scratch_scope {
    const mcsg_allocator *alloc;
    void *memory;
    size_t size;
} mci_scratch_scope;
bool mci_scratch_enter(mci_scratch_scope *s, const mcsg_allocator *alloc);
void mci_scratch_leave(mci_scratch_scope *s, bool entered);

/* ctx->threads, or the number of online processors when it is 0 (at most 64). */
int mci_thread_count(const mci_ctx *ctx);

#endif
