/*
 * A minimal parallel loop on POSIX threads: workers take indices from a shared counter.
 * The first failure (the smallest failing index, whatever the thread timing) is reported,
 * and no new index is started after a failure, so results and errors are the same as a
 * sequential run's. A thread that cannot be created leaves its share to the others.
 */
#define _POSIX_C_SOURCE 200809L

#include "internal.h"

#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

#define MAX_THREADS 64

typedef struct loop {
    mci_task_fn fn;
    void *user;
    const uint32_t *order; /* NULL: tasks in index order */
    size_t count;
    atomic_size_t next;
    atomic_bool stop;
    pthread_mutex_t lock;
    size_t fail_index;
    mcsg_error fail;
} loop;

static void *worker(void *arg)
{
    loop *l = arg;
    mcsg_error err;
    for (;;) {
        size_t i;
        mcsg_status st;
        if (atomic_load(&l->stop))
            break;
        i = atomic_fetch_add(&l->next, 1);
        if (i >= l->count)
            break;
        st = l->fn(l->user, l->order ? l->order[i] : i, &err);
        if (st == MCSG_OK)
            continue;
        err.status = st;
        pthread_mutex_lock(&l->lock);
        if (i < l->fail_index) {
            l->fail_index = i;
            l->fail = err;
        }
        pthread_mutex_unlock(&l->lock);
        atomic_store(&l->stop, true);
    }
    return NULL;
}

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

mcsg_status mci_parallel_for_order(const mci_ctx *ctx, size_t count, const uint32_t *order,
                                   mci_task_fn fn, void *user, mcsg_error *err)
{
    pthread_t threads[MAX_THREADS];
    int wanted = mci_thread_count(ctx), started = 0;
    loop l;
    if (wanted <= 1 || count <= 1) {
        for (size_t i = 0; i < count; i++) {
            mcsg_status st = fn(user, order ? order[i] : i, err);
            if (st != MCSG_OK)
                return st;
        }
        return MCSG_OK;
    }
    memset(&l, 0, sizeof l);
    l.fn = fn;
    l.user = user;
    l.order = order;
    l.count = count;
    atomic_init(&l.next, 0);
    atomic_init(&l.stop, false);
    l.fail_index = SIZE_MAX;
    if (pthread_mutex_init(&l.lock, NULL) != 0) {
        mci_ctx one = *ctx;
        one.threads = 1;
        return mci_parallel_for_order(&one, count, order, fn, user, err);
    }
    for (int t = 1; t < wanted && (size_t)t < count; t++)
        if (pthread_create(&threads[started], NULL, worker, &l) == 0)
            started++;
    worker(&l);
    for (int t = 0; t < started; t++)
        pthread_join(threads[t], NULL);
    pthread_mutex_destroy(&l.lock);
    if (l.fail_index == SIZE_MAX)
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
