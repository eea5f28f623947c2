/*
 * A minimal parallel loop on POSIX threads: workers take indices from a shared counter.
 * The first failure (the smallest failing index, whatever the thread timing) is reported,
 * and no new index is started after a failure, so results and errors are the same as a
 * sequential run's. A thread that cannot be created leaves its share to the others.
 * A public call that runs many loops keeps its workers in a pool (mci_pool_start).
 */
#define _POSIX_C_SOURCE 200809L

#include "base/parallel.h"
#include "base/sort.h"

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

#define MAX_THREADS 64

/* Positions are claimed a batch at a time: with one atomic increment per task, the
 * counter's cache line went from processor to processor on every task, which cost as
 * much as the short tasks themselves (an arrangement's split, a face's triangulation).
 * The first positions go one at a time: a heaviest-first order puts its heavy tasks
 * there (at most 256 of them exceed 1/256 of the whole), and a batch of those would load
 * one thread. */
enum { CLAIM_BATCH = 16, SINGLE_CLAIMS = 256 };

typedef struct loop {
    mcsg_allocator alloc; /* for the threads' scratch (mci_thread_scratch) */
    mci_task_fn fn;
    void *user;
    const uint32_t *order; /* NULL: tasks in index order */
    size_t count;
    _Alignas(64) atomic_size_t next; /* apart from what the tasks read */
    _Alignas(64) atomic_size_t fail_index; /* SIZE_MAX: none failed yet */
    pthread_mutex_t lock;
    mcsg_error fail;
} loop;

/* Runs position i unless a task at an earlier position has failed: positions below the
 * first failure all run (so the smallest failing position is the one reported, whatever
 * the threads), those after it do not start once it is known. */
static void run_position(loop *l, size_t i)
{
    mcsg_error err;
    mcsg_status st;
    if (i > atomic_load(&l->fail_index))
        return;
    st = l->fn(l->user, l->order ? l->order[i] : i, &err);
    if (st == MCSG_OK)
        return;
    err.status = st;
    pthread_mutex_lock(&l->lock);
    if (i < atomic_load(&l->fail_index)) {
        atomic_store(&l->fail_index, i);
        l->fail = err;
    }
    pthread_mutex_unlock(&l->lock);
}

/* ---------------------------------------------------------------------------------- */
/* Thread scratch                                                                      */

/* The scope a thread's scratch belongs to: the outermost loop or scope it is in. */
static _Thread_local mci_scratch_scope *current_scope;

bool mci_scratch_enter(mci_scratch_scope *s, const mcsg_allocator *alloc)
{
    if (current_scope)
        return false;
    s->alloc = alloc;
    s->memory = NULL;
    s->size = 0;
    current_scope = s;
    return true;
}

void mci_scratch_leave(mci_scratch_scope *s, bool entered)
{
    if (!entered)
        return;
    if (s->memory)
        s->alloc->free_fn(s->alloc->user, s->memory);
    current_scope = NULL;
}

void *mci_thread_scratch(size_t size, bool *fresh)
{
    mci_scratch_scope *s = current_scope;
    *fresh = false;
    if (!s || size == 0)
        return NULL;
    if (!s->memory) {
        if (s->size != 0) /* an earlier allocation failed: do not retry on every call */
            return NULL;
        s->size = size;
        s->memory = s->alloc->malloc_fn(s->alloc->user, size);
        *fresh = s->memory != NULL;
    }
    return s->size == size ? s->memory : NULL;
}

static void *worker(void *arg)
{
    loop *l = arg;
    mci_scratch_scope scope;
    bool entered = mci_scratch_enter(&scope, &l->alloc);
    for (;;) {
        size_t batch = atomic_load(&l->next) < SINGLE_CLAIMS ? 1 : CLAIM_BATCH;
        size_t first, end;
        if (atomic_load(&l->fail_index) != SIZE_MAX)
            break;
        first = atomic_fetch_add(&l->next, batch);
        if (first >= l->count)
            break;
        end = l->count - first < batch ? l->count : first + batch;
        for (size_t i = first; i < end; i++)
            run_position(l, i);
    }
    mci_scratch_leave(&scope, entered);
    return NULL;
}

/* ---------------------------------------------------------------------------------- */
/* The pool                                                                            */

/* How long a worker spins for the next loop, and the caller for the workers' last
 * tasks, before sleeping. Most serial stretches between an evaluation's loops are
 * shorter; a sleeping worker took from 0.01 to several milliseconds to wake here. */
#define SPIN_SECONDS 0.002

struct mcsg_pool {
    mcsg_allocator alloc; /* the pool's own memory comes from and goes back to it */
    int workers;
    pthread_t threads[MAX_THREADS];
    pthread_mutex_t lock;
    pthread_cond_t posted;   /* generation moved */
    pthread_cond_t finished; /* active fell to 0 */
    atomic_uint generation;  /* bumped for each loop posted, and for shutdown */
    atomic_int active;       /* workers between taking a loop and leaving it */
    _Atomic(loop *) job;     /* the loop on offer, NULL once its caller is done */
    atomic_bool in_use;      /* a loop runs on the pool (a nested loop runs alone) */
    atomic_bool shutdown;
};

/* Spins (yielding) until done(p) or SPIN_SECONDS pass; false when the time ran out. */
static bool spin_until(mci_pool *p, bool (*done)(mci_pool *, unsigned), unsigned arg)
{
    double until = mci_seconds_now() + SPIN_SECONDS;
    for (unsigned i = 1; !done(p, arg); i++) {
        if (i % 64 == 0 && mci_seconds_now() > until)
            return false;
        sched_yield();
    }
    return true;
}

static bool generation_moved(mci_pool *p, unsigned seen)
{
    return atomic_load(&p->generation) != seen;
}

static bool workers_idle(mci_pool *p, unsigned unused)
{
    (void)unused;
    return atomic_load(&p->active) == 0;
}

/* Blocks until done(p), with cond signalled (under lock) whenever it may have become true. */
static void sleep_until(mci_pool *p, pthread_cond_t *cond, bool (*done)(mci_pool *, unsigned),
                        unsigned arg)
{
    if (spin_until(p, done, arg))
        return;
    pthread_mutex_lock(&p->lock);
    while (!done(p, arg))
        pthread_cond_wait(cond, &p->lock);
    pthread_mutex_unlock(&p->lock);
}

static void announce(mci_pool *p, pthread_cond_t *cond)
{
    pthread_mutex_lock(&p->lock);
    pthread_cond_broadcast(cond);
    pthread_mutex_unlock(&p->lock);
}

static void post(mci_pool *p, loop *l)
{
    atomic_store(&p->job, l);
    pthread_mutex_lock(&p->lock);
    atomic_fetch_add(&p->generation, 1);
    pthread_cond_broadcast(&p->posted);
    pthread_mutex_unlock(&p->lock);
}

/* A worker counts itself active before it looks at the job, and the caller withdraws the
 * job before it waits for active to reach 0 (both sequentially consistent): a worker
 * either is waited for or finds no job, so none touches a loop after its caller left. */
static void *pool_worker(void *arg)
{
    mci_pool *p = arg;
    unsigned seen = 0;
    mci_scratch_scope scope;
    bool entered = mci_scratch_enter(&scope, &p->alloc); /* the worker's whole life */
    for (;;) {
        loop *l;
        sleep_until(p, &p->posted, generation_moved, seen);
        seen = atomic_load(&p->generation);
        if (atomic_load(&p->shutdown)) {
            mci_scratch_leave(&scope, entered);
            return NULL;
        }
        atomic_fetch_add(&p->active, 1);
        if ((l = atomic_load(&p->job)) != NULL)
            worker(l);
        if (atomic_fetch_sub(&p->active, 1) == 1)
            announce(p, &p->finished);
    }
}

static void run_on_pool(mci_pool *p, loop *l)
{
    post(p, l);
    worker(l);
    atomic_store(&p->job, NULL);
    sleep_until(p, &p->finished, workers_idle, 0);
}

static void pool_free(mci_pool *p, int sync_objects)
{
    mcsg_allocator alloc = p->alloc;
    if (sync_objects > 2)
        pthread_cond_destroy(&p->finished);
    if (sync_objects > 1)
        pthread_cond_destroy(&p->posted);
    if (sync_objects > 0)
        pthread_mutex_destroy(&p->lock);
    alloc.free_fn(alloc.user, p);
}

/* A pool with `wanted` - 1 workers, or NULL (out of memory or no thread started). */
static mci_pool *pool_new(const mci_ctx *ctx, int wanted)
{
    mci_pool *p = mci_malloc(ctx, sizeof *p);
    if (!p)
        return NULL;
    memset(p, 0, sizeof *p);
    p->alloc = ctx->alloc;
    atomic_init(&p->generation, 0);
    atomic_init(&p->active, 0);
    atomic_init(&p->job, NULL);
    atomic_init(&p->in_use, false);
    atomic_init(&p->shutdown, false);
    if (pthread_mutex_init(&p->lock, NULL) != 0) {
        pool_free(p, 0);
    } else if (pthread_cond_init(&p->posted, NULL) != 0) {
        pool_free(p, 1);
    } else if (pthread_cond_init(&p->finished, NULL) != 0) {
        pool_free(p, 2);
    } else {
        for (int t = 1; t < wanted; t++)
            if (pthread_create(&p->threads[p->workers], NULL, pool_worker, p) == 0)
                p->workers++;
        if (p->workers > 0)
            return p;
        pool_free(p, 3);
    }
    return NULL;
}

static void pool_delete(mci_pool *p)
{
    atomic_store(&p->shutdown, true);
    post(p, NULL);
    for (int t = 0; t < p->workers; t++)
        pthread_join(p->threads[t], NULL);
    pool_free(p, 3);
}

void mci_pool_start(mci_ctx *ctx)
{
    int wanted = mci_thread_count(ctx);
    if (wanted > 1 && !ctx->pool && (ctx->pool = pool_new(ctx, wanted)) != NULL)
        ctx->owns_pool = true;
}

void mci_pool_stop(mci_ctx *ctx)
{
    if (ctx->pool && ctx->owns_pool)
        pool_delete(ctx->pool);
    if (ctx->owns_pool)
        ctx->pool = NULL;
    ctx->owns_pool = false;
}

mcsg_status mcsg_pool_create(const mcsg_options *opts, mcsg_pool **out, mcsg_error *err)
{
    mci_ctx ctx;
    int wanted;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_pool_create: NULL output");
    mci_ctx_init(&ctx, opts);
    wanted = mci_thread_count(&ctx);
    *out = NULL;
    if (wanted <= 1)
        return MCSG_OK;
    if (!(*out = pool_new(&ctx, wanted)))
        return mci_fail(err, MCSG_ERR_NOMEM, "starting %d worker threads: out of memory or "
                        "threads", wanted - 1);
    return MCSG_OK;
}

void mcsg_pool_free(mcsg_pool *pool)
{
    if (pool)
        pool_delete(pool);
}

/* ---------------------------------------------------------------------------------- */
/* Loops                                                                               */

int mci_thread_count(const mci_ctx *ctx)
{
    long n = ctx->threads > 0 ? ctx->threads : sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > MAX_THREADS ? MAX_THREADS : (int)n;
}

mcsg_status mci_parallel_for(const mci_ctx *ctx, size_t count, mci_task_fn fn, void *user,
                             mcsg_error *err)
{
    return mci_parallel_for_order(ctx, count, NULL, fn, user, err);
}

/* The end of chunk `chunk` of `size` items among n items (the last chunk may be short). */
static size_t mci_chunk_end(size_t n, size_t chunk, size_t size)
{
    return n - chunk * size < size ? n : (chunk + 1) * size;
}

typedef struct range_loop {
    mci_range_fn fn;
    void *user;
    size_t n, chunk;
} range_loop;

static mcsg_status range_task(void *user, size_t index, mcsg_error *err)
{
    const range_loop *r = user;
    return r->fn(r->user, index * r->chunk, mci_chunk_end(r->n, index, r->chunk), err);
}

mcsg_status mci_parallel_for_ranges(const mci_ctx *ctx, size_t n, size_t chunk,
                                    mci_range_fn fn, void *user, mcsg_error *err)
{
    range_loop r = {fn, user, n, chunk};
    return mci_parallel_for(ctx, (n + chunk - 1) / chunk, range_task, &r, err);
}

static mcsg_status run_serially(const mci_ctx *ctx, size_t count, const uint32_t *order,
                                mci_task_fn fn, void *user, mcsg_error *err)
{
    mci_scratch_scope scope;
    bool entered = mci_scratch_enter(&scope, &ctx->alloc);
    mcsg_status st = MCSG_OK;
    for (size_t i = 0; i < count && st == MCSG_OK; i++)
        st = fn(user, order ? order[i] : i, err);
    mci_scratch_leave(&scope, entered);
    return st;
}

mcsg_status mci_parallel_for_order(const mci_ctx *ctx, size_t count, const uint32_t *order,
                                   mci_task_fn fn, void *user, mcsg_error *err)
{
    pthread_t threads[MAX_THREADS];
    int wanted = mci_thread_count(ctx), started = 0;
    mci_pool *pool = ctx->pool;
    loop l;
    if (wanted <= 1 || count <= 1 || (pool && atomic_exchange(&pool->in_use, true)))
        return run_serially(ctx, count, order, fn, user, err);
    memset(&l, 0, sizeof l);
    l.alloc = ctx->alloc;
    l.fn = fn;
    l.user = user;
    l.order = order;
    l.count = count;
    atomic_init(&l.next, 0);
    atomic_init(&l.fail_index, SIZE_MAX);
    if (pthread_mutex_init(&l.lock, NULL) != 0) {
        mci_ctx one = *ctx;
        one.threads = 1;
        if (pool)
            atomic_store(&pool->in_use, false);
        return mci_parallel_for_order(&one, count, order, fn, user, err);
    }
    if (pool) {
        run_on_pool(pool, &l);
        atomic_store(&pool->in_use, false);
    } else {
        for (int t = 1; t < wanted && (size_t)t < count; t++)
            if (pthread_create(&threads[started], NULL, worker, &l) == 0)
                started++;
        worker(&l);
        for (int t = 0; t < started; t++)
            pthread_join(threads[t], NULL);
    }
    pthread_mutex_destroy(&l.lock);
    if (atomic_load(&l.fail_index) == SIZE_MAX)
        return MCSG_OK;
    if (err)
        *err = l.fail;
    return l.fail.status;
}

uint32_t *mci_heaviest_first(const mci_ctx *ctx, const uint32_t *cost, size_t n)
{
    mci_keyed *keyed = mci_malloc_array(ctx, n + 1, sizeof *keyed);
    uint32_t *order = mci_malloc_array(ctx, n + 1, sizeof *order);
    uint64_t total = 0;
    size_t heavy = 0, at;
    if (!keyed || !order) {
        mci_free(ctx, keyed);
        mci_free(ctx, order);
        return NULL;
    }
    for (size_t i = 0; i < n; i++)
        total += cost[i];
    /* Only tasks worth more than 1/256 of the whole move ahead (at most 256 of them): the
     * rest keep index order, which keeps their memory in order for the passes after. */
    for (size_t i = 0; i < n; i++)
        if ((uint64_t)cost[i] * 256 > total) {
            keyed[heavy].key = UINT32_MAX - cost[i];
            keyed[heavy++].ref = (uint32_t)i;
        }
    mci_sort_keyed(keyed, heavy);
    for (at = 0; at < heavy; at++)
        order[at] = keyed[at].ref;
    for (size_t i = 0; i < n; i++)
        if ((uint64_t)cost[i] * 256 <= total)
            order[at++] = (uint32_t)i;
    mci_free(ctx, keyed);
    return order;
}

mcsg_status mci_parallel_for_heaviest_first(const mci_ctx *ctx, size_t count, mci_cost_fn cost,
                                            mci_task_fn fn, void *user, mcsg_error *err)
{
    uint32_t *costs = mci_malloc_array(ctx, count + 1, sizeof *costs), *order = NULL;
    mcsg_status st;
    for (size_t i = 0; costs && i < count; i++)
        costs[i] = cost(user, i);
    if (costs)
        order = mci_heaviest_first(ctx, costs, count);
    mci_free(ctx, costs);
    if (!order)
        return mci_fail_nomem(err, "scheduling parallel work");
    st = mci_parallel_for_order(ctx, count, order, fn, user, err);
    mci_free(ctx, order);
    return st;
}
