/*
 * Repair of triangles that rounding flattened. The exact result has no zero-area
 * triangle, but a thin one (a vertex within an ulp of the opposite edge) can round to
 * three collinear points. Its middle vertex m then lies, exactly in doubles, on the
 * segment p-q of its long edge; the triangle on the other side of that edge, (p, q, X),
 * is split at m into (p, m, X) and (m, q, X), which replace the flat triangle and that
 * neighbour. The mesh stays closed and consistently oriented, the triangle count does not
 * change, and both new triangles lie in the neighbour's plane with the neighbour's
 * orientation, so they are not flat unless the neighbour was (then the flat triangle is
 * left as it is and counted).
 */
#include "csg/rounding_repair.h"
#include "base/sort.h"
#include "exact/predicates.h"


#include <stdlib.h>
#include <string.h>

static const double *at(const double *xyz, uint32_t v)
{
    return xyz + 3 * (size_t)v;
}

static bool is_flat(const double *xyz, const uint32_t *t)
{
    return mci_triangle_is_degenerate(at(xyz, t[0]), at(xyz, t[1]), at(xyz, t[2]));
}

static bool lex_less(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k];
    return false;
}

/* Corner of a flat triangle between the other two: on a line, lexicographic order of
 * distinct points is their order along the line. */
static int middle_corner(const double *xyz, const uint32_t *t)
{
    for (int i = 0; i < 3; i++) {
        const double *m = at(xyz, t[i]), *u = at(xyz, t[(i + 1) % 3]),
                     *w = at(xyz, t[(i + 2) % 3]);
        if (lex_less(u, m) != lex_less(w, m))
            return i;
    }
    return 0; /* unreachable for three distinct collinear points */
}

static uint64_t directed_key(uint32_t u, uint32_t v)
{
    return (uint64_t)u << 32 | v;
}

static bool index_directed_edges(const mci_ctx *ctx, const uint32_t *tris, size_t nt,
                                 mci_keyed **out)
{
    mci_keyed *edges = mci_malloc_array(ctx, 3 * nt + 1, sizeof *edges);
    if (!edges)
        return false;
    for (size_t t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++) {
            edges[3 * t + i].key = directed_key(tris[3 * t + i], tris[3 * t + (i + 1) % 3]);
            edges[3 * t + i].ref = (uint32_t)t;
        }
    mci_sort_keyed(edges, 3 * nt);
    *out = edges;
    return true;
}

/* The untouched, non-flat triangle holding directed edge u->v, or MCI_NONE. */
static uint32_t neighbour_with_edge(const mci_keyed *edges, size_t n, uint32_t u, uint32_t v,
                                    const unsigned char *touched, const unsigned char *flat)
{
    uint64_t key = directed_key(u, v);
    for (size_t i = mci_find_key(edges, n, key); i < n && edges[i].key == key; i++)
        if (!touched[edges[i].ref] && !flat[edges[i].ref])
            return edges[i].ref;
    return MCI_NONE;
}

static uint32_t third_corner(const uint32_t *t, uint32_t u, uint32_t v)
{
    for (int i = 0; i < 3; i++)
        if (t[i] != u && t[i] != v)
            return t[i];
    return t[0];
}

/* One pass: split the neighbours of flat triangles whose neighbour is not flat and not
 * already changed in this pass. Returns how many flat triangles were removed. */
static size_t split_pass(const double *xyz, uint32_t *tris, uint32_t *source, size_t nt,
                         const mci_keyed *edges, unsigned char *touched,
                         const unsigned char *flat)
{
    size_t fixed = 0;
    for (size_t t = 0; t < nt; t++) {
        uint32_t *T = tris + 3 * t, p, q, m, n, x;
        int i;
        if (!flat[t] || touched[t])
            continue;
        i = middle_corner(xyz, T);
        m = T[i];
        q = T[(i + 1) % 3];
        p = T[(i + 2) % 3];
        n = neighbour_with_edge(edges, 3 * nt, p, q, touched, flat);
        if (n == MCI_NONE)
            continue;
        x = third_corner(tris + 3 * (size_t)n, p, q);
        T[0] = p, T[1] = m, T[2] = x;
        tris[3 * (size_t)n] = m, tris[3 * (size_t)n + 1] = q, tris[3 * (size_t)n + 2] = x;
        if (source)
            source[t] = source[n];
        touched[t] = touched[n] = 1;
        fixed++;
    }
    return fixed;
}

static size_t mark_flat(const double *xyz, const uint32_t *tris, size_t nt, unsigned char *flat)
{
    size_t count = 0;
    for (size_t t = 0; t < nt; t++) {
        flat[t] = is_flat(xyz, tris + 3 * t);
        count += flat[t];
    }
    return count;
}

bool mci_split_flat_triangles(const mci_ctx *ctx, const double *xyz, uint32_t *tris,
                              uint32_t *source, size_t nt, mci_flat_repair *result)
{
    unsigned char *marks = mci_malloc_array(ctx, 2 * nt + 1, 1), *flat, *touched;
    size_t count;
    bool ok = marks != NULL;
    memset(result, 0, sizeof *result);
    if (!ok)
        return false;
    flat = marks;
    touched = marks + nt;
    count = mark_flat(xyz, tris, nt, flat);
    /* Each pass fixes every flat triangle whose neighbour is free; chains of flat
     * triangles along one line need a few passes. */
    for (int pass = 0; ok && count > 0 && pass < 16; pass++) {
        mci_keyed *edges = NULL;
        size_t fixed;
        ok = index_directed_edges(ctx, tris, nt, &edges);
        if (!ok)
            break;
        memset(touched, 0, nt);
        fixed = split_pass(xyz, tris, source, nt, edges, touched, flat);
        mci_free(ctx, edges);
        result->split += fixed;
        count = mark_flat(xyz, tris, nt, flat);
        if (fixed == 0)
            break;
    }
    result->remaining = count;
    mci_free(ctx, marks);
    return ok;
}

/* ---------------------------------------------------------------------------------- */
/* Opposite duplicates                                                                 */

typedef struct sorted_triangle {
    uint32_t v[3]; /* corners in increasing order */
    uint32_t t;
    int8_t parity; /* +1 if the triangle's cyclic order is increasing, else -1 */
} sorted_triangle;

static void sort_corners(const uint32_t *t, sorted_triangle *s)
{
    uint32_t a = t[0], b = t[1], c = t[2], x;
    int swaps = 0;
    if (a > b)
        x = a, a = b, b = x, swaps++;
    if (b > c)
        x = b, b = c, c = x, swaps++;
    if (a > b)
        x = a, a = b, b = x, swaps++;
    s->v[0] = a, s->v[1] = b, s->v[2] = c;
    s->parity = swaps % 2 == 0 ? 1 : -1;
}

static int compare_sorted(const void *x, const void *y)
{
    const sorted_triangle *a = x, *b = y;
    for (int i = 0; i < 3; i++)
        if (a->v[i] != b->v[i])
            return a->v[i] < b->v[i] ? -1 : 1;
    if (a->parity != b->parity)
        return a->parity < b->parity ? -1 : 1;
    return (a->t > b->t) - (a->t < b->t);
}

static bool same_corners(const sorted_triangle *a, const sorted_triangle *b)
{
    return a->v[0] == b->v[0] && a->v[1] == b->v[1] && a->v[2] == b->v[2];
}

/* In a group of triangles on the same corners (sorted: parity -1 first), mark
 * min(#-1, #+1) of each orientation for removal. */
static size_t mark_cancelling(const sorted_triangle *g, size_t n, unsigned char *removed)
{
    size_t neg = 0, pairs;
    while (neg < n && g[neg].parity < 0)
        neg++;
    pairs = neg < n - neg ? neg : n - neg;
    for (size_t i = 0; i < pairs; i++)
        removed[g[i].t] = removed[g[neg + i].t] = 1;
    return 2 * pairs;
}

bool mci_cancel_opposite_triangles(const mci_ctx *ctx, uint32_t *tris, uint32_t *source,
                                   size_t *nt, size_t *cancelled)
{
    size_t n = *nt, out = 0;
    sorted_triangle *s = mci_malloc_array(ctx, n + 1, sizeof *s);
    unsigned char *removed = mci_malloc_array(ctx, n + 1, 1);
    *cancelled = 0;
    if (!s || !removed) {
        mci_free(ctx, s);
        mci_free(ctx, removed);
        return false;
    }
    for (size_t t = 0; t < n; t++) {
        sort_corners(tris + 3 * t, &s[t]);
        s[t].t = (uint32_t)t;
        removed[t] = 0;
    }
    qsort(s, n, sizeof *s, compare_sorted);
    for (size_t i = 0, j; i < n; i = j) {
        for (j = i + 1; j < n && same_corners(&s[i], &s[j]); j++)
            ;
        if (j - i > 1)
            *cancelled += mark_cancelling(s + i, j - i, removed);
    }
    for (size_t t = 0; *cancelled > 0 && t < n; t++)
        if (!removed[t]) {
            memmove(tris + 3 * out, tris + 3 * t, 3 * sizeof *tris);
            if (source)
                source[out] = source[t];
            out++;
        }
    if (*cancelled > 0)
        *nt = out;
    mci_free(ctx, s);
    mci_free(ctx, removed);
    return true;
}
