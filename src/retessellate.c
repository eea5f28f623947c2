/*
 * Output tessellation of a classified face (paper §5.4): of all the constraint edges of
 * the arrangement, only those between a kept and a dropped piece bound the result (the
 * paper's valid-IPs); the others (pseudo-IPs: curves of parts that were carved away or
 * lie inside) are left out, and the face is triangulated again with the valid ones.
 *
 * Which new triangles are kept follows without geometry: the face's boundary is split at
 * the same points in both tessellations, so each boundary piece of a new triangle lies
 * on exactly one old piece, whose status it takes; the status then spreads across the
 * new triangulation's edges, flipping exactly across the valid constraints.
 */
#include "arrange.h"

#include <string.h>

typedef mci_keyed side; /* key: local point ids of an edge; ref: 3 * triangle + edge */

/* The 3 * n edge sides of triangles tris[0 .. 3n), sorted by key. */
static side *sorted_sides(const mci_ctx *ctx, const uint32_t *tris, size_t n)
{
    side *s = mci_malloc_array(ctx, 3 * n + 1, sizeof *s);
    if (!s)
        return NULL;
    for (size_t r = 0; r < 3 * n; r++) {
        s[r].key = mci_edge_key(tris[r], tris[r - r % 3 + (r % 3 + 1) % 3]);
        s[r].ref = (uint32_t)r;
    }
    mci_sort_keyed(s, 3 * n);
    return s;
}

/* Whether the interior edge `key` of the old tessellation separates kept from dropped. */
static bool is_valid_edge(const side *old, size_t n, const uint8_t *keep, uint64_t key)
{
    size_t i = mci_find_key(old, n, key);
    return i + 1 < n && old[i + 1].key == key && keep[old[i].ref / 3] != keep[old[i + 1].ref / 3];
}

static void mate_sides(const side *s, size_t n, uint32_t *mate);

/* Status of the new triangles: from the old pieces along the face's boundary, then
 * across edges, flipping across valid constraints. Fails if some triangle is unreached. */
static mcsg_status spread_status(const mci_ctx *ctx, const side *old, size_t old_n,
                                 const uint8_t *piece_keep, const mci_face_arr *arr,
                                 uint8_t *keep, mcsg_error *err)
{
    const uint32_t *tris = arr->tris;
    size_t n = arr->tri_count;
    mcsg_status st;
    side *fresh = sorted_sides(ctx, tris, n);
    uint32_t *mate = mci_malloc_array(ctx, 3 * n + 1, sizeof *mate);
    uint32_t *queue = mci_malloc_array(ctx, n + 1, sizeof *queue);
    size_t tail = 0;
    bool ok = fresh && mate && queue;
    for (size_t t = 0; ok && t < n; t++)
        keep[t] = 2;
    if (ok)
        mate_sides(fresh, 3 * n, mate);
    for (size_t r = 0; ok && r < 3 * n; r++) {
        uint32_t t = (uint32_t)(r / 3);
        size_t j;
        if (mate[r] != UINT32_MAX || keep[t] != 2)
            continue;
        j = mci_find_key(old, old_n, mci_edge_key(tris[r], tris[r - r % 3 + (r % 3 + 1) % 3]));
        if (j < old_n) {
            keep[t] = piece_keep[old[j].ref / 3];
            queue[tail++] = t;
        }
    }
    for (size_t head = 0; ok && head < tail; head++) {
        uint32_t t = queue[head];
        for (uint32_t r = 3 * t; r < 3 * t + 3; r++) {
            uint32_t u = mate[r] == UINT32_MAX ? UINT32_MAX : mate[r] / 3;
            if (u == UINT32_MAX || keep[u] != 2)
                continue;
            keep[u] = is_valid_edge(old, old_n, piece_keep,
                                    mci_edge_key(tris[r], tris[r - r % 3 + (r % 3 + 1) % 3]))
                          ? !keep[t]
                          : keep[t];
            queue[tail++] = u;
        }
    }
    st = !ok ? mci_fail_nomem(err, "tessellating the result")
         : tail < n ? mci_fail(err, MCSG_ERR_INTERNAL,
                               "face %u: a part of its tessellation is unclassified", arr->face)
                    : MCSG_OK;
    mci_free(ctx, fresh);
    mci_free(ctx, mate);
    mci_free(ctx, queue);
    return st;
}

/* Choose the valid constraints; *droppable says whether any interior constraint is not. */
static void choose_valid(const mci_face_arr *arr, const side *old, size_t old_n,
                         const uint8_t *piece_keep, bool *use, bool *droppable)
{
    *droppable = false;
    for (size_t e = 0; e < arr->edge_count; e++) {
        uint64_t key = mci_edge_key(arr->edges[e].a, arr->edges[e].b);
        size_t i = mci_find_key(old, old_n, key);
        bool interior = i + 1 < old_n && old[i + 1].key == key;
        use[e] = is_valid_edge(old, old_n, piece_keep, key);
        *droppable = *droppable || (interior && !use[e]);
    }
}

mcsg_status mci_arr_retessellate(const mci_ctx *ctx, mci_face_arr *arr,
                                 const uint8_t *piece_keep, uint8_t **tri_keep,
                                 mcsg_error *err)
{
    size_t n = arr->tri_count;
    side *old = sorted_sides(ctx, arr->tris, n);
    bool *use = mci_malloc_array(ctx, arr->edge_count + 1, sizeof *use);
    uint8_t *keep = NULL;
    bool droppable = false, any_kept = false;
    mcsg_status st = old && use ? MCSG_OK : mci_fail_nomem(err, "tessellating the result");
    *tri_keep = NULL;
    for (size_t t = 0; t < n; t++)
        any_kept = any_kept || piece_keep[t];
    if (st == MCSG_OK && any_kept)
        choose_valid(arr, old, 3 * n, piece_keep, use, &droppable);
    if (st == MCSG_OK && droppable)
        st = mci_arr_triangulate(ctx, arr, use, err);
    if (st == MCSG_OK) {
        keep = mci_malloc_array(ctx, arr->tri_count + 1, 1);
        if (!keep)
            st = mci_fail_nomem(err, "tessellating the result");
        else if (!droppable)
            memcpy(keep, piece_keep, n);
        else
            st = spread_status(ctx, old, 3 * n, piece_keep, arr, keep, err);
    }
    if (st == MCSG_OK)
        *tri_keep = keep;
    else
        mci_free(ctx, keep);
    mci_free(ctx, old);
    mci_free(ctx, use);
    return st;
}

/* mate[r]: the side of another triangle sharing side r, or UINT32_MAX on the boundary. */
static void mate_sides(const side *s, size_t n, uint32_t *mate)
{
    for (size_t i = 0; i < n; i++)
        mate[s[i].ref] = UINT32_MAX;
    for (size_t i = 0; i + 1 < n; i++)
        if (s[i].key == s[i + 1].key) {
            mate[s[i].ref] = s[i + 1].ref;
            mate[s[i + 1].ref] = s[i].ref;
        }
}
