/*
 * Shells that rounding to doubles left without volume. A part of the exact result that is
 * thinner than the spacing of doubles (a sliver where two solids barely overlap) can round
 * to a closed shell that is flat (volume exactly zero) or inside out (negative volume).
 * A closed shell of volume zero bounds nothing. A shell of negative volume is a cavity
 * only inside an outer shell, whose bounding box then holds its own: one that no shell of
 * positive volume holds so cannot be a cavity. Both kinds are removed. The volume signs
 * are exact (a filtered sum, then big integers), and box containment compares doubles,
 * so nothing here depends on a tolerance. Flat or inverted slivers that do lie within an
 * outer shell's box stay (telling them from cavities needs an enclosure test).
 *
 * Shells are the vertex-connected parts: after mci_split_touching, parts that touch at a
 * point or along an edge have their own vertices.
 */
#include "void_shells.h"

#include <math.h>
#include <string.h>

#define NO_SHELL UINT32_MAX /* a vertex no triangle uses */

typedef struct shell {
    double lo[3], hi[3];
    mci_volume_sum volume;
    int sign;
    size_t first, count; /* if settled exactly, its triangles: by_shell[first ..) */
} shell;

static uint32_t find_root(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
    return x;
}

/* shell_of[v] for every vertex used (dense ids, in the order of the shells' first
 * triangles; NO_SHELL for unused vertices); returns the number of shells. parent has room
 * for the vertices. */
static size_t number_shells(const mcsg_mesh *m, uint32_t *parent, uint32_t *shell_of)
{
    size_t count = 0;
    for (size_t v = 0; v < m->vertex_count; v++)
        parent[v] = (uint32_t)v, shell_of[v] = NO_SHELL;
    for (size_t t = 0; t < m->triangle_count; t++)
        for (int i = 1; i < 3; i++) {
            uint32_t a = find_root(parent, m->triangles[3 * t]);
            uint32_t b = find_root(parent, m->triangles[3 * t + (size_t)i]);
            if (a != b)
                parent[a > b ? a : b] = a > b ? b : a;
        }
    for (size_t t = 0; t < m->triangle_count; t++) {
        uint32_t root = find_root(parent, m->triangles[3 * t]);
        if (shell_of[root] == NO_SHELL)
            shell_of[root] = (uint32_t)count++;
    }
    for (size_t v = 0; v < m->vertex_count; v++)
        shell_of[v] = shell_of[find_root(parent, (uint32_t)v)];
    return count;
}

/* Each shell's box and its volume in double, with the sign where that decides it. */
static void measure_shells(const mcsg_mesh *m, const uint32_t *shell_of, shell *shells,
                           size_t n)
{
    for (size_t s = 0; s < n; s++) {
        memset(&shells[s], 0, sizeof shells[s]);
        for (int k = 0; k < 3; k++)
            shells[s].lo[k] = INFINITY, shells[s].hi[k] = -INFINITY;
    }
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        mci_volume_sum_add(&shells[shell_of[tri[0]]].volume, m->vertices + 3 * (size_t)tri[0],
                           m->vertices + 3 * (size_t)tri[1], m->vertices + 3 * (size_t)tri[2]);
    }
    for (size_t v = 0; v < m->vertex_count; v++) {
        shell *sh;
        if (shell_of[v] == NO_SHELL)
            continue;
        sh = &shells[shell_of[v]];
        for (int k = 0; k < 3; k++) { /* finite coordinates: plain comparisons */
            double x = m->vertices[3 * v + (size_t)k];
            sh->lo[k] = x < sh->lo[k] ? x : sh->lo[k];
            sh->hi[k] = x > sh->hi[k] ? x : sh->hi[k];
        }
    }
    for (size_t s = 0; s < n; s++)
        shells[s].sign = mci_volume_sum_sign(&shells[s].volume);
}

/* The exact sign of the shells the double sum left undecided (thin ones), their
 * triangles grouped first (a counting sort into by_shell, allocated only then). False
 * when out of memory. */
static bool settle_signs(const mci_ctx *ctx, const mcsg_mesh *m, const uint32_t *shell_of,
                         shell *shells, size_t n)
{
    size_t undecided = 0;
    uint32_t *by_shell;
    for (size_t s = 0; s < n; s++)
        undecided += shells[s].sign == 0;
    if (undecided == 0)
        return true;
    if (!(by_shell = mci_malloc_array(ctx, m->triangle_count + 1, sizeof *by_shell)))
        return false;
    for (size_t s = 1; s < n; s++)
        shells[s].first = shells[s - 1].first + shells[s - 1].volume.triangles;
    for (size_t t = 0; t < m->triangle_count; t++) {
        shell *sh = &shells[shell_of[m->triangles[3 * t]]];
        by_shell[sh->first + sh->count++] = (uint32_t)t;
    }
    for (size_t s = 0; s < n; s++)
        if (shells[s].sign == 0)
            shells[s].sign = mci_triangles_volume_sign(m->vertices, m->triangles,
                                                       by_shell + shells[s].first,
                                                       shells[s].count, NULL);
    mci_free(ctx, by_shell);
    return true;
}

static bool box_holds(const shell *outer, const shell *inner)
{
    for (int k = 0; k < 3; k++)
        if (outer->lo[k] > inner->lo[k] || outer->hi[k] < inner->hi[k])
            return false;
    return true;
}

/* Whether shell s is to be removed (the shells' signs known). */
static bool is_void(const shell *shells, size_t n, size_t s)
{
    if (shells[s].sign > 0)
        return false;
    if (shells[s].sign == 0)
        return true;
    for (size_t p = 0; p < n; p++)
        if (shells[p].sign > 0 && box_holds(&shells[p], &shells[s]))
            return false;
    return true;
}

/* Keep the triangles of shells not removed (and their tags) and the vertices they use,
 * in order. new_id has room for the vertices (NO_SHELL there: a vertex that goes). */
static void compact(mcsg_mesh *m, uint32_t *tag, const uint32_t *shell_of,
                    const bool *removed, uint32_t *new_id)
{
    size_t nt = 0, nv = 0;
    for (size_t v = 0; v < m->vertex_count; v++)
        new_id[v] = shell_of[v] == NO_SHELL || removed[shell_of[v]] ? NO_SHELL : (uint32_t)nv++;
    for (size_t v = 0; v < m->vertex_count; v++)
        if (new_id[v] != NO_SHELL)
            memmove(m->vertices + 3 * (size_t)new_id[v], m->vertices + 3 * v, 3 * sizeof(double));
    for (size_t t = 0; t < m->triangle_count; t++) {
        if (new_id[m->triangles[3 * t]] == NO_SHELL)
            continue;
        for (int i = 0; i < 3; i++)
            m->triangles[3 * nt + (size_t)i] = new_id[m->triangles[3 * t + (size_t)i]];
        if (tag)
            tag[nt] = tag[t];
        nt++;
    }
    m->vertex_count = nv;
    m->triangle_count = nt;
}

bool mci_drop_void_shells(const mci_ctx *ctx, mcsg_mesh *m, uint32_t *tag,
                          mci_void_shells *result)
{
    uint32_t *parent, *shell_of;
    shell *shells = NULL;
    bool *removed = NULL, ok;
    size_t n = 0;
    memset(result, 0, sizeof *result);
    if (m->triangle_count == 0)
        return true;
    parent = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *parent);
    shell_of = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *shell_of);
    ok = parent && shell_of;
    if (ok) {
        n = number_shells(m, parent, shell_of);
        shells = mci_malloc_array(ctx, n + 1, sizeof *shells);
        removed = mci_calloc_array(ctx, n + 1, sizeof *removed);
        ok = shells && removed;
    }
    if (ok) {
        measure_shells(m, shell_of, shells, n);
        ok = settle_signs(ctx, m, shell_of, shells, n);
    }
    if (ok) {
        for (size_t s = 0; s < n; s++)
            if ((removed[s] = is_void(shells, n, s))) {
                result->shells++;
                result->triangles += shells[s].volume.triangles;
            }
        if (result->shells > 0)
            compact(m, tag, shell_of, removed, parent); /* parent: reused as the new ids */
    }
    mci_free(ctx, parent);
    mci_free(ctx, shell_of);
    mci_free(ctx, shells);
    mci_free(ctx, removed);
    return ok;
}
