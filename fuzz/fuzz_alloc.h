/*
 * Shared by the fuzz targets that run whole library calls: an allocator for mcsg_options
 * that caps live memory at 256 MiB (so that huge inputs end as MCSG_ERR_NOMEM instead of
 * exhausting the machine) and counts live bytes (so that a leak is an abort()).
 */
#ifndef MESHCSG_FUZZ_ALLOC_H
#define MESHCSG_FUZZ_ALLOC_H

#include "meshcsg.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#define FUZZ_BUDGET ((size_t)256 << 20)

typedef struct fuzz_budget {
    size_t live;
} fuzz_budget;

/* Each block starts with a header holding its size, padded for any alignment. */
typedef union fuzz_header {
    size_t size;
    max_align_t align;
} fuzz_header;

static void *capped_realloc(void *user, void *ptr, size_t size)
{
    fuzz_budget *b = user;
    fuzz_header *h = ptr ? (fuzz_header *)ptr - 1 : NULL;
    size_t old = h ? h->size : 0;
    if (size > FUZZ_BUDGET || b->live - old + size > FUZZ_BUDGET)
        return NULL;
    h = realloc(h, sizeof *h + size);
    if (!h)
        return NULL;
    b->live = b->live - old + size;
    h->size = size;
    return h + 1;
}

static void *capped_malloc(void *user, size_t size) { return capped_realloc(user, NULL, size); }

static void capped_free(void *user, void *ptr)
{
    fuzz_header *h = (fuzz_header *)ptr - 1;
    ((fuzz_budget *)user)->live -= h->size;
    free(h);
}

/* Default options with the capped allocator counting into *b. */
static mcsg_options capped_options(fuzz_budget *b)
{
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    opts.allocator.malloc_fn = capped_malloc;
    opts.allocator.realloc_fn = capped_realloc;
    opts.allocator.free_fn = capped_free;
    opts.allocator.user = b;
    return opts;
}

#endif
