/*
 * Core helpers: the keyed sort (introsort, and an in-place radix sort for long arrays)
 * against a qsort reference on random, sorted, reversed, constant, organ-pipe, edge-key
 * and equal-rank inputs of many sizes, and the key lookup on the sorted result.
 */
#include "testlib.h"
#include "internal.h"

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

/* Arrays over 4,096 items take the in-place radix sort (digits skipped or not, deep
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

TEST(find_key_reports_missing_keys)
{
    mci_keyed items[4] = {{2, 0}, {4, 1}, {4, 2}, {9, 3}};
    CHECK_EQ_SIZE(mci_find_key(items, 4, 4), 1);
    CHECK_EQ_SIZE(mci_find_key(items, 4, 3), 4);
    CHECK_EQ_SIZE(mci_find_key(items, 4, 10), 4);
    CHECK_EQ_SIZE(mci_find_key(items, 0, 2), 0);
}

int main(void)
{
    RUN(keyed_sort_matches_qsort);
    RUN(find_key_reports_missing_keys);
    return test_summary();
}
