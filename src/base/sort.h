/*
 * Sorting and lookup of integer keys (base/sort.c): keyed items, 64-bit integers, radix
 * sorts for long arrays. Introsorts are instantiated from base/sort_template.h.
 */
#ifndef MESHCSG_BASE_SORT_H
#define MESHCSG_BASE_SORT_H

#include "base/core.h"

/* A 64-bit key with a reference, for sorting and looking up edges and the like. */
typedef struct mci_keyed {
    uint64_t key;
    uint32_t ref;
} mci_keyed;

/* The key of the undirected edge u-v (smaller id in the high half). */
uint64_t mci_edge_key(uint32_t u, uint32_t v);
/* Sort by key, then ref. */
void mci_sort_keyed(mci_keyed *items, size_t n);
/* Sort 32-bit integers ascending (an introsort without qsort's callback). */
void mci_sort_u32(uint32_t *items, size_t n);
/* Sort 64-bit integers ascending (an introsort without qsort's callback). */
void mci_sort_u64(uint64_t *items, size_t n);
/* The same for long arrays: a least-significant-digit radix sort through tmp (n keys),
 * 11-bit digits (the counts stay in the first-level cache), passes only over the digits
 * where some keys differ (ids rarely use all their bits); n < 2^32. */
void mci_radix_sort_u64_buffered(uint64_t *keys, uint64_t *tmp, size_t n);
/* ... with the buffer allocated; false when it cannot be (keys unchanged). */
bool mci_radix_sort_u64(const mci_ctx *ctx, uint64_t *keys, size_t n);
/* Drops repeats from sorted keys[0 .. n) in place; returns how many are left. */
size_t mci_unique_u64(uint64_t *keys, size_t n);
/* Index of the first item with this key in sorted items[0 .. n), or n. */
size_t mci_find_key(const mci_keyed *items, size_t n, uint64_t key);

#endif
