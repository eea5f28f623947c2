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
        st = l->fn(l->user, i, &err);
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
    pthread_t threads[MAX_THREADS];
    int wanted = mci_thread_count(ctx), started = 0;
    loop l;
    if (wanted <= 1 || count <= 1) {
        for (size_t i = 0; i < count; i++) {
            mcsg_status st = fn(user, i, err);
            if (st != MCSG_OK)
                return st;
        }
        return MCSG_OK;
    }
    memset(&l, 0, sizeof l);
    l.fn = fn;
    l.user = user;
    l.count = count;
    atomic_init(&l.next, 0);
    atomic_init(&l.stop, false);
    l.fail_index = SIZE_MAX;
    if (pthread_mutex_init(&l.lock, NULL) != 0) {
        mci_ctx one = *ctx;
        one.threads = 1;
        return mci_parallel_for(&one, count, fn, user, err);
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
