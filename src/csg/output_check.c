/*
 * The result's check (output_check.h). Every edge of the mesh is looked at twice: by
 * vertex index, where each must be used exactly once in each direction (parts that touch
 * have vertex copies), and with the vertices welded by coordinates, where an edge of one
 * triangle is open, two triangles facing the same way are misoriented, and more than two
 * triangles are allowed only where the exact result itself touches (its edge of the same
 * rounded ends has more than two triangles by exact identity). Degenerate triangles are
 * found with the exact predicate; crossing triangles, on request, with the exact
 * self-intersection test.
 */
#include "csg/output_check.h"
#include "base/sort.h"
#include "exact/predicates.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct edge_counts {
    size_t open, misoriented, unbalanced, overfull;
} edge_counts;

/* Ids below 2^31: an undirected edge and its direction fit one 64-bit key. */
#define MAX_PACKED_ID (UINT32_C(1) << 31)

/* The directed edges of triangles as keys ((smaller id * ids + larger id) * 2, plus 1
 * when the edge runs from the larger id), radix-sorted, so that each undirected edge's
 * uses are one run: one sort of keys as short as the ids allow (a sort of keyed pairs,
 * or lists per vertex, cost several times as much). Vertex ids (below `ids`) are mapped
 * through id[] (NULL: as they are); an edge whose ends map to one id is left out (its
 * triangle is degenerate). NULL when out of memory. */
static uint64_t *sorted_edges(const mci_ctx *ctx, const uint32_t *tris, size_t count,
                              const uint32_t *id, uint64_t ids, size_t *n)
{
    uint64_t *keys = mci_malloc_array(ctx, 3 * count + 1, sizeof *keys);
    *n = 0;
    for (size_t t = 0; keys && t < count; t++)
        for (int i = 0; i < 3; i++) {
            uint64_t u = tris[3 * t + i], v = tris[3 * t + (i + 1) % 3];
            if (id)
                u = id[u], v = id[v];
            if (u != v)
                keys[(*n)++] = u < v ? (u * ids + v) << 1 : (v * ids + u) << 1 | 1;
        }
    if (keys && !mci_radix_sort_u64(ctx, keys, *n)) {
        mci_free(ctx, keys);
        return NULL;
    }
    return keys;
}

/* Counts the undirected edges (runs of equal keys but for the direction bit) that are
 * open (one use), misoriented (two uses the same way), unbalanced (more than two uses,
 * more one way: non-manifold, as mcsg_mesh_check counts it, and never an allowed touch)
 * and overfull (more than two uses, balanced); the overfull ones are moved to the front
 * of keys as edge keys (smaller id << 32 | larger id). */
static void count_edges(uint64_t *keys, size_t n, uint64_t ids, edge_counts *c)
{
    memset(c, 0, sizeof *c);
    for (size_t i = 0, j; i < n; i = j) {
        size_t backward = 0;
        for (j = i; j < n && keys[j] >> 1 == keys[i] >> 1; j++)
            backward += keys[j] & 1;
        if (j - i == 2 && backward == 1)
            continue;
        if (j - i == 1)
            c->open++;
        else if (2 * backward != j - i && j - i == 2)
            c->misoriented++;
        else if (2 * backward != j - i)
            c->unbalanced++;
        else
            keys[c->overfull++] = (keys[i] >> 1) / ids << 32 | (keys[i] >> 1) % ids;
    }
}

/* An edge as its two ends' coordinates, the lexicographically smaller end first. */
typedef struct edge_ends {
    double p[6];
} edge_ends;

static int compare_points(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k]) /* -0 == +0, as welding has it */
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

static int compare_ends(const void *x, const void *y)
{
    const edge_ends *a = x, *b = y;
    int c = compare_points(a->p, b->p);
    return c ? c : compare_points(a->p + 3, b->p + 3);
}

static edge_ends ends_of(const double *a, const double *b)
{
    edge_ends e;
    bool swap = compare_points(a, b) > 0;
    memcpy(e.p, swap ? b : a, 3 * sizeof *a);
    memcpy(e.p + 3, swap ? a : b, 3 * sizeof *a);
    return e;
}

/* The edges where the exact result touches itself (more than two triangles by exact
 * identity), as rounded ends, sorted. NULL when out of memory (*n unset). */
static edge_ends *exact_touching_edges(const mci_ctx *ctx, const mci_exact_result *x,
                                       size_t *n)
{
    size_t count;
    edge_counts c;
    edge_ends *out;
    uint64_t *keys;
    uint64_t ids = 0;
    if (!x->tris) { /* listed before */
        out = mci_malloc_array(ctx, x->touching_count + 1, sizeof *out);
        if (out && x->touching_count > 0)
            memcpy(out, x->touching, x->touching_count * sizeof *out);
        *n = x->touching_count;
        return out;
    }
    for (size_t i = 0; i < 3 * x->count; i++)
        ids = x->tris[i] >= ids ? (uint64_t)x->tris[i] + 1 : ids;
    if (ids > MAX_PACKED_ID) { /* none known: every overfull edge fails */
        *n = 0;
        return mci_malloc(ctx, sizeof *out);
    }
    if (!(keys = sorted_edges(ctx, x->tris, x->count, NULL, ids, &count)))
        return NULL;
    count_edges(keys, count, ids, &c);
    out = mci_malloc_array(ctx, c.overfull + 1, sizeof *out);
    for (size_t i = 0; out && i < c.overfull; i++) {
        uint32_t u = (uint32_t)(keys[i] >> 32), v = (uint32_t)keys[i];
        out[i] = ends_of(x->xyz + 3 * (size_t)x->dense[u], x->xyz + 3 * (size_t)x->dense[v]);
    }
    if (out) {
        qsort(out, c.overfull, sizeof *out, compare_ends);
        *n = c.overfull;
    }
    mci_free(ctx, keys);
    return out;
}

bool mci_list_touching_edges(const mci_ctx *ctx, const mci_exact_result *exact, double **ends,
                             size_t *n)
{
    edge_ends *list = exact_touching_edges(ctx, exact, n);
    *ends = list ? list->p : NULL;
    return list != NULL;
}

/* Of the welded overfull edges (keys of welded ids), those where the exact result does
 * not touch itself are moved to the front of over[], in order; *apart says how many.
 * False when out of memory. */
static bool split_overfull(const mci_ctx *ctx, const mcsg_mesh *m, uint64_t *over,
                           size_t overfull, const mci_exact_result *x, size_t *apart)
{
    size_t touching_count = 0;
    edge_ends *touching = exact_touching_edges(ctx, x, &touching_count);
    *apart = 0;
    if (!touching)
        return false;
    for (size_t i = 0; i < overfull; i++) {
        uint32_t u = (uint32_t)(over[i] >> 32), v = (uint32_t)over[i];
        edge_ends key = ends_of(m->vertices + 3 * (size_t)u, m->vertices + 3 * (size_t)v);
        if (!bsearch(&key, touching, touching_count, sizeof key, compare_ends))
            over[(*apart)++] = over[i];
    }
    mci_free(ctx, touching);
    return true;
}

/* The welded view: canon[] (welded id per vertex), the edge counts, and the overfull
 * edges where the exact result does not touch at the front of *keys (*apart of them;
 * c->overfull in all). False when out of memory or with 2^31 vertices or more. */
static bool welded_edges(const mci_ctx *ctx, const mcsg_mesh *m, const mci_exact_result *x,
                         uint32_t *canon, uint64_t **keys, edge_counts *c, size_t *apart)
{
    size_t n = 0;
    bool ok = m->vertex_count < MAX_PACKED_ID &&
              mci_first_equal_coordinates(ctx, m->vertices, m->vertex_count, canon) &&
              (*keys = sorted_edges(ctx, m->triangles, m->triangle_count, canon,
                                    m->vertex_count, &n)) != NULL;
    memset(c, 0, sizeof *c);
    *apart = 0;
    if (ok)
        count_edges(*keys, n, m->vertex_count, c);
    return ok && (c->overfull == 0 || split_overfull(ctx, m, *keys, c->overfull, x, apart));
}

/* The welded view: open, misoriented and overfull edges. *copies says whether some
 * vertices share coordinates (only then can the indexed view differ). */
static bool check_welded(const mci_ctx *ctx, const mcsg_mesh *m, const mci_exact_result *x,
                         mcsg_output_check *check, bool *copies)
{
    uint32_t *canon = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *canon);
    uint64_t *keys = NULL;
    size_t apart = 0;
    edge_counts c;
    bool ok = canon && welded_edges(ctx, m, x, canon, &keys, &c, &apart);
    *copies = false;
    for (size_t v = 0; ok && v < m->vertex_count; v++)
        *copies |= canon[v] != v;
    check->open_edges = c.open;
    check->misoriented_edges = c.misoriented;
    check->welded_nonmanifold_edges = apart + c.unbalanced;
    check->touching_edges = c.overfull - apart;
    mci_free(ctx, canon);
    mci_free(ctx, keys);
    return ok;
}

bool mci_welded_overfull_edges(const mci_ctx *ctx, const mcsg_mesh *m,
                               const mci_exact_result *x, uint32_t *canon, uint64_t **edges,
                               size_t *n)
{
    edge_counts c;
    uint64_t *keys = NULL;
    bool ok = welded_edges(ctx, m, x, canon, &keys, &c, n);
    if (!ok) {
        mci_free(ctx, keys);
        keys = NULL;
        *n = 0;
    }
    *edges = keys;
    return ok;
}

/* The indexed view: every edge used once in each direction. */
static bool check_indexed(const mci_ctx *ctx, const mcsg_mesh *m, mcsg_output_check *check)
{
    size_t n;
    edge_counts c;
    uint64_t *keys = sorted_edges(ctx, m->triangles, m->triangle_count, NULL,
                                  m->vertex_count, &n);
    if (!keys)
        return false;
    count_edges(keys, n, m->vertex_count, &c);
    check->index_nonmanifold_edges = c.open + c.misoriented + c.unbalanced + c.overfull;
    mci_free(ctx, keys);
    return true;
}

/* Whether the triangle's area is certainly not zero: the xy, yz or zx component of
 * (b - a) x (c - a) beyond its rounding error (Shewchuk's orient2d bound, rounded up),
 * with finite values clear of underflow; else the exact test decides. Most triangles
 * are settled by the first component, at a tenth of the exact test's cost. */
static bool clearly_not_degenerate(const double *a, const double *b, const double *c)
{
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3;
        double l = (b[i] - a[i]) * (c[j] - a[j]), r = (b[j] - a[j]) * (c[i] - a[i]);
        double sum = fabs(l) + fabs(r);
        if (fabs(l - r) > 0x1p-50 * sum && sum > 0x1p-960 && sum < 0x1p+1000)
            return true;
    }
    return false;
}

static size_t degenerate_triangles(const mcsg_mesh *m)
{
    size_t count = 0;
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *v = m->triangles + 3 * t;
        const double *a = m->vertices + 3 * (size_t)v[0], *b = m->vertices + 3 * (size_t)v[1],
                     *c = m->vertices + 3 * (size_t)v[2];
        count += !clearly_not_degenerate(a, b, c) && mci_triangle_is_degenerate(a, b, c);
    }
    return count;
}

mcsg_status mci_count_crossings(const mci_ctx *ctx, const mcsg_mesh *m, size_t *pairs,
                                mcsg_error *err)
{
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    opts.allocator = ctx->alloc;
    opts.threads = ctx->threads;
    opts.pool = ctx->pool;
    return mcsg_mesh_self_intersections(m, &opts, pairs, NULL, err);
}

static mcsg_status check_crossings(const mci_ctx *ctx, const mcsg_mesh *m,
                                   mcsg_output_check *check, mcsg_error *err)
{
    check->crossings_checked = 1;
    return mci_count_crossings(ctx, m, &check->crossing_pairs, err);
}

mcsg_status mci_check_output(const mci_ctx *ctx, const mcsg_mesh *m,
                             const mci_exact_result *exact, mcsg_output_check *check,
                             mcsg_error *err)
{
    memset(check, 0, sizeof *check);
    if (m->triangle_count == 0)
        return MCSG_OK;
    bool copies;
    if (m->vertex_count >= MAX_PACKED_ID)
        return mci_fail(err, MCSG_ERR_LIMIT, "checking the result: more than 2^31 vertices");
    if (!check_welded(ctx, m, exact, check, &copies))
        return mci_fail_nomem(err, "checking the result");
    if (copies && !check_indexed(ctx, m, check))
        return mci_fail_nomem(err, "checking the result");
    /* Without vertex copies the indexed view is the welded one. */
    if (!copies)
        check->index_nonmanifold_edges = check->open_edges + check->misoriented_edges +
                                         check->welded_nonmanifold_edges +
                                         check->touching_edges;
    check->degenerate_triangles = degenerate_triangles(m);
    return ctx->check_output_crossings ? check_crossings(ctx, m, check, err) : MCSG_OK;
}

int mcsg_output_check_failed(const mcsg_output_check *c)
{
    return c && (c->open_edges || c->misoriented_edges || c->degenerate_triangles ||
                 c->index_nonmanifold_edges || c->welded_nonmanifold_edges ||
                 c->crossing_pairs);
}

/* "N what" after a separator, for the nonzero counts only. */
static size_t add_count(char *out, size_t at, size_t size, size_t n, const char *one,
                        const char *many)
{
    int w;
    if (n == 0 || at >= size)
        return at;
    w = snprintf(out + at, size - at, "%s%zu %s", at ? ", " : "", n, n == 1 ? one : many);
    return w > 0 ? at + (size_t)w : at;
}

void mci_describe_output_check(const mcsg_output_check *c, char *what, size_t size)
{
    size_t at = 0;
    if (size == 0)
        return;
    what[0] = 0;
    at = add_count(what, at, size, c->welded_nonmanifold_edges,
                   "edge of more than two triangles once vertices are welded by coordinates",
                   "edges of more than two triangles once vertices are welded by coordinates");
    at = add_count(what, at, size, c->index_nonmanifold_edges,
                   "edge not manifold by vertex index", "edges not manifold by vertex index");
    at = add_count(what, at, size, c->open_edges, "open edge", "open edges");
    at = add_count(what, at, size, c->misoriented_edges, "misoriented edge",
                   "misoriented edges");
    at = add_count(what, at, size, c->degenerate_triangles, "zero-area triangle",
                   "zero-area triangles");
    add_count(what, at, size, c->crossing_pairs, "pair of crossing triangles",
              "pairs of crossing triangles");
}

void mci_log_output_check(const mci_ctx *ctx, const mcsg_output_check *c)
{
    char what[512];
    if (!mcsg_output_check_failed(c))
        return;
    mci_describe_output_check(c, what, sizeof what);
    mci_log(ctx, MCSG_LOG_WARNING, "the result breaks its guarantees after rounding to "
            "doubles: %s", what);
}

size_t mci_output_check_defects(const mcsg_output_check *c)
{
    return c->open_edges + c->misoriented_edges + c->index_nonmanifold_edges +
           c->welded_nonmanifold_edges + c->degenerate_triangles + c->crossing_pairs;
}
