/*
 * Sorting and lookup of integer keys (sort.h): introsorts instantiated from
 * sort_template.h (qsort's comparison callback dominated short sorts), an in-place
 * most-significant-digit radix sort for long arrays of keyed items, and a
 * least-significant-digit radix sort through a buffer for 64-bit keys.
 */
#include "base/sort.h"
#include "base/sort_template.h"

#include <string.h>

uint64_t mci_edge_key(uint32_t u, uint32_t v)
{
    return u < v ? (uint64_t)u << 32 | v : (uint64_t)v << 32 | u;
}

/* The sort's total order: by key, then ref. Two comparisons instead of one on a
 * 128-bit rank: the keyed sorts of dense scenes take markedly fewer instructions. */
static inline bool keyed_less(const mci_keyed *a, const mci_keyed *b)
{
    return a->key != b->key ? a->key < b->key : a->ref < b->ref;
}

/* keyed_sort_intro: the introsort of sort_template.h, for short arrays and the radix
 * sort's small buckets. A specialised sort instead of qsort: the classification sorts
 * millions of edge keys, and qsort's callback and merge buffer cost several times as
 * much. (key, ref) is a total order, so the result is unique. */
MCI_DEFINE_SORT(keyed_sort, mci_keyed, keyed_less)

static inline bool u64_less(const uint64_t *a, const uint64_t *b)
{
    return *a < *b;
}

MCI_DEFINE_SORT(u64_sort, uint64_t, u64_less)

static inline bool u32_less(const uint32_t *a, const uint32_t *b)
{
    return *a < *b;
}

MCI_DEFINE_SORT(u32_sort, uint32_t, u32_less)

void mci_sort_u32(uint32_t *items, size_t n)
{
    u32_sort(items, n);
}

void mci_sort_u64(uint64_t *items, size_t n)
{
    u64_sort(items, n);
}

/* Byte `shift` / 8 of the 96-bit rank. Shifts are multiples of 8, so a digit lies
 * wholly in the key (shift >= 32) or in the ref: no 128-bit shift. */
static size_t keyed_digit(const mci_keyed *item, int shift)
{
    uint64_t word = shift >= 32 ? item->key >> (shift - 32) : (uint64_t)item->ref >> shift;
    return (size_t)(word & 255);
}

/* In-place most-significant-digit radix sort (American flag sort) on the 96-bit rank,
 * 8-bit digits from bit `shift` down; digits equal in every item of a bucket cost one
 * counting pass and no moves. Short buckets go to the introsort. No buffer: the
 * classification sorts arrays of millions of edge keys, and a copy would be the peak. */
static void radix_sort_keyed(mci_keyed *items, size_t n, int shift, int depth)
{
    size_t count[256], next[256], end[256];
    for (; shift >= 0; shift -= 8) {
        if (n <= 64) {
            keyed_sort_intro(items, n, depth);
            return;
        }
        memset(count, 0, sizeof count);
        for (size_t i = 0; i < n; i++)
            count[keyed_digit(&items[i], shift)]++;
        if (count[keyed_digit(&items[0], shift)] < n)
            break; /* this digit varies: distribute by it */
    }
    if (shift < 0)
        return; /* all ranks equal */
    for (size_t d = 0, sum = 0; d < 256; d++) {
        next[d] = sum;
        sum += count[d];
        end[d] = sum;
    }
    for (size_t d = 0; d < 256; d++)
        while (next[d] < end[d]) { /* cycle the item at next[d] to its bucket */
            mci_keyed item = items[next[d]];
            size_t home = keyed_digit(&item, shift);
            while (home != d) {
                mci_keyed displaced = items[next[home]];
                items[next[home]++] = item;
                item = displaced;
                home = keyed_digit(&item, shift);
            }
            items[next[d]++] = item;
        }
    for (size_t d = 0, first = 0; d < 256 && shift > 0; first += count[d], d++)
        if (count[d] > 1)
            radix_sort_keyed(items + first, count[d], shift - 8, depth);
}

void mci_sort_keyed(mci_keyed *items, size_t n)
{
    if (n > 1024)
        radix_sort_keyed(items, n, 88, mci_sort_depth(n));
    else
        keyed_sort(items, n);
}

void mci_radix_sort_u64_buffered(uint64_t *keys, uint64_t *tmp, size_t n)
{
    uint32_t count[2048];
    uint64_t *src = keys, *dst = tmp, all = ~UINT64_C(0), any = 0, varying;
    if (n <= 64) { /* clearing the counts alone would cost more */
        mci_sort_u64(keys, n);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        all &= keys[i];
        any |= keys[i];
    }
    varying = all ^ any;
    for (int shift = 0; shift < 64 && varying >> shift; shift += 11) {
        uint32_t sum = 0;
        if (!((varying >> shift) & 2047))
            continue; /* one digit value: the pass would not move anything */
        memset(count, 0, sizeof count);
        for (size_t i = 0; i < n; i++)
            count[(src[i] >> shift) & 2047]++;
        for (size_t d = 0; d < 2048; d++) {
            uint32_t c = count[d];
            count[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            dst[count[(src[i] >> shift) & 2047]++] = src[i];
        src = dst;
        dst = src == keys ? tmp : keys;
    }
    if (src != keys)
        memcpy(keys, src, n * sizeof *keys);
}

size_t mci_unique_u64(uint64_t *keys, size_t n)
{
    size_t out = 0;
    for (size_t i = 0; i < n; i++)
        if (out == 0 || keys[i] != keys[out - 1])
            keys[out++] = keys[i];
    return out;
}

bool mci_radix_sort_u64(const mci_ctx *ctx, uint64_t *keys, size_t n)
{
    uint64_t *tmp;
    if (n < 2)
        return true;
    if (!(tmp = mci_malloc_array(ctx, n, sizeof *tmp)))
        return false;
    mci_radix_sort_u64_buffered(keys, tmp, n);
    mci_free(ctx, tmp);
    return true;
}

size_t mci_find_key(const mci_keyed *items, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (items[mid].key < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && items[lo].key == key ? lo : n;
}
