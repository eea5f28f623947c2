/*
 * A type-specialised introsort, instantiated per element type. qsort calls its
 * comparison through a pointer and merges through a buffer; the arrangements and
 * triangulations sort hundreds of thousands of short arrays (10-50 items), where that
 * overhead was most of the cost.
 *
 * MCI_DEFINE_SORT(name, type, less) defines
 *     static inline void name(type *items, size_t n);
 * sorting ascending by `less`, a function or macro taking two `const type *` and true
 * when the first goes strictly before the second. The sort is not stable: orders with
 * ties between distinct items must not use it where the result's order matters.
 *
 * Introsort: quicksort on the median of three with Hoare's partition, insertion sort
 * for ranges of 16 items or fewer, heap sort when the recursion passes twice the
 * logarithm (so the worst case stays n log n). Recursion goes into the smaller part.
 */
#ifndef MESHCSG_BASE_SORT_TEMPLATE_H
#define MESHCSG_BASE_SORT_TEMPLATE_H

#include <stddef.h>

/* The recursion budget of the introsort for n items: twice floor(log2 n). */
static inline int mci_sort_depth(size_t n)
{
    int depth = 0;
    for (size_t m = n; m > 1; m >>= 1)
        depth += 2;
    return depth;
}

#define MCI_DEFINE_SORT(name, type, less)                                                 \
    static inline void name##_insertion(type *items, size_t n)                            \
    {                                                                                     \
        for (size_t i = 1; i < n; i++) {                                                  \
            type x = items[i];                                                            \
            size_t j = i;                                                                 \
            for (; j > 0 && less(&x, &items[j - 1]); j--)                                 \
                items[j] = items[j - 1];                                                  \
            items[j] = x;                                                                 \
        }                                                                                 \
    }                                                                                     \
                                                                                          \
    static inline void name##_sift_down(type *items, size_t root, size_t n)               \
    {                                                                                     \
        for (;;) {                                                                        \
            size_t child = 2 * root + 1;                                                  \
            type t;                                                                       \
            if (child >= n)                                                               \
                return;                                                                   \
            if (child + 1 < n && less(&items[child], &items[child + 1]))                  \
                child++;                                                                  \
            if (!less(&items[root], &items[child]))                                       \
                return;                                                                   \
            t = items[root];                                                              \
            items[root] = items[child];                                                   \
            items[child] = t;                                                             \
            root = child;                                                                 \
        }                                                                                 \
    }                                                                                     \
                                                                                          \
    static inline void name##_heap(type *items, size_t n)                                 \
    {                                                                                     \
        for (size_t i = n / 2; i-- > 0;)                                                  \
            name##_sift_down(items, i, n);                                                \
        for (size_t end = n; end-- > 1;) {                                                \
            type t = items[0];                                                            \
            items[0] = items[end];                                                        \
            items[end] = t;                                                               \
            name##_sift_down(items, 0, end);                                              \
        }                                                                                 \
    }                                                                                     \
                                                                                          \
    /* The median of the first, middle and last items (a copy: the partition moves        \
     * items). */                                                                         \
    static inline type name##_pivot(const type *items, size_t n)                          \
    {                                                                                     \
        const type *a = &items[0], *b = &items[n / 2], *c = &items[n - 1];                \
        if (less(a, b))                                                                   \
            return less(b, c) ? *b : less(a, c) ? *c : *a;                                \
        return less(a, c) ? *a : less(b, c) ? *c : *b;                                    \
    }                                                                                     \
                                                                                          \
    static inline void name##_intro(type *items, size_t n, int depth)                     \
    {                                                                                     \
        while (n > 16) {                                                                  \
            size_t i = 0, j = n - 1;                                                      \
            type pivot = name##_pivot(items, n);                                          \
            if (depth-- == 0) {                                                           \
                name##_heap(items, n);                                                    \
                return;                                                                   \
            }                                                                             \
            for (;;) { /* Hoare partition: the pivot's value stops both scans */          \
                type t;                                                                   \
                while (less(&items[i], &pivot))                                           \
                    i++;                                                                  \
                while (less(&pivot, &items[j]))                                           \
                    j--;                                                                  \
                if (i >= j)                                                               \
                    break;                                                                \
                t = items[i];                                                             \
                items[i++] = items[j];                                                    \
                items[j--] = t;                                                           \
            }                                                                             \
            /* [0, j] <= pivot <= [j + 1, n): recurse into the smaller part */            \
            if (j + 1 < n - (j + 1)) {                                                    \
                name##_intro(items, j + 1, depth);                                        \
                items += j + 1;                                                           \
                n -= j + 1;                                                               \
            } else {                                                                      \
                name##_intro(items + j + 1, n - (j + 1), depth);                          \
                n = j + 1;                                                                \
            }                                                                             \
        }                                                                                 \
        name##_insertion(items, n);                                                       \
    }                                                                                     \
                                                                                          \
    static inline void name(type *items, size_t n)                                        \
    {                                                                                     \
        if (n > 1)                                                                        \
            name##_intro(items, n, mci_sort_depth(n));                                    \
    }

#endif
