/*
 * The table of mci_point_values: a state byte per point, claimed by one thread with a
 * compare-and-swap, and values in blocks allocated the first time a point of the block
 * needs them, so that scenes whose boxes decide every predicate allocate nothing more
 * than the state bytes.
 */
#include "csg/point_values.h"

#include <string.h>

enum { BLOCK_BITS = 9, BLOCK = 1 << BLOCK_BITS };

enum { UNKNOWN, BUSY, KNOWN, NONE };

mcsg_status mci_point_values_init(const mci_ctx *ctx, mci_point_values *t, size_t count,
                                  mcsg_error *err)
{
    size_t blocks = (count + BLOCK - 1) >> BLOCK_BITS;
    memset(t, 0, sizeof *t);
    t->ctx = ctx;
    t->state = mci_malloc_array(ctx, count ? count : 1, sizeof *t->state);
    t->blocks = mci_malloc_array(ctx, blocks ? blocks : 1, sizeof *t->blocks);
    if (!t->state || !t->blocks) {
        mci_point_values_free(t);
        return mci_fail_nomem(err, "keeping point values");
    }
    t->count = count;
    for (size_t i = 0; i < count; i++)
        atomic_init(&t->state[i], UNKNOWN);
    for (size_t b = 0; b < blocks; b++)
        atomic_init(&t->blocks[b], NULL);
    return MCSG_OK;
}

void mci_point_values_free(mci_point_values *t)
{
    size_t blocks = (t->count + BLOCK - 1) >> BLOCK_BITS;
    for (size_t b = 0; t->blocks && b < blocks; b++)
        mci_free(t->ctx, atomic_load(&t->blocks[b]));
    mci_free(t->ctx, (void *)t->state);
    mci_free(t->ctx, (void *)t->blocks);
    memset(t, 0, sizeof *t);
}

/* The block holding point id, allocated by whichever thread needs it first; NULL when
 * the allocation fails. */
static double (*block_of(mci_point_values *t, uint32_t id))[3][3]
{
    _Atomic(void *) *slot = &t->blocks[id >> BLOCK_BITS];
    void *b = atomic_load_explicit(slot, memory_order_acquire), *fresh;
    if (b)
        return b;
    fresh = mci_malloc_array(t->ctx, BLOCK, sizeof(double[3][3]));
    if (!fresh)
        return NULL;
    if (!atomic_compare_exchange_strong_explicit(slot, &b, fresh, memory_order_acq_rel,
                                                 memory_order_acquire)) {
        mci_free(t->ctx, fresh); /* another thread's block came first: b is it */
        return b;
    }
    return fresh;
}

const double *mci_point_values_known(mci_point_values *t, uint32_t id)
{
    double (*b)[3][3];
    if (atomic_load_explicit(&t->state[id], memory_order_acquire) != KNOWN)
        return NULL;
    /* The block was stored before the state, which we acquired. */
    b = atomic_load_explicit(&t->blocks[id >> BLOCK_BITS], memory_order_relaxed);
    return &b[id & (BLOCK - 1)][0][0];
}

const double *mci_point_values_get(mci_point_values *t, uint32_t id, const mci_point *p,
                                   double scratch[3][3])
{
    unsigned char expected = UNKNOWN;
    const double *known = mci_point_values_known(t, id);
    double (*b)[3][3] = NULL;
    if (known)
        return known;
    if (atomic_load_explicit(&t->state[id], memory_order_relaxed) == NONE)
        return NULL;
    /* Claimed by one thread; the others (and all when no block) compute for themselves. */
    if (atomic_compare_exchange_strong_explicit(&t->state[id], &expected, BUSY,
                                                memory_order_acq_rel, memory_order_acquire)) {
        b = block_of(t, id);
        if (b && mci_point_dd_values(p, b[id & (BLOCK - 1)])) {
            atomic_store_explicit(&t->state[id], KNOWN, memory_order_release);
            return &b[id & (BLOCK - 1)][0][0];
        }
        atomic_store_explicit(&t->state[id], b ? NONE : UNKNOWN, memory_order_release);
        if (b)
            return NULL;
    }
    return mci_point_dd_values(p, scratch) ? &scratch[0][0] : NULL;
}
