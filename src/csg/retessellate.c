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
#include "csg/retessellate.h"
#include "base/sort.h"
#include "csg/triangulate.h"

#include <string.h>

typedef mci_keyed side; /* key: local point ids of an edge; ref: see old_sides */

static uint64_t side_key(const uint32_t *tris, size_t r)
{
    return mci_edge_key(tris[r], tris[r - r % 3 + (r % 3 + 1) % 3]);
}

/* What the old tessellation (all constraints) tells the new one, from its adjacency:
 * its sides on the face's boundary (ref: their triangle), and each interior constraint
 * once (ref: 1 when valid, i.e. it separates a kept from a dropped piece). Both sorted by
 * key. Only constraints can be valid: pieces joined across other edges are in one
 * region, hence kept or dropped together. */
typedef struct old_sides {
    side *boundary, *constraint;
    size_t boundary_count, constraint_count;
} old_sides;

/* Scratch on the stack for faces of up to STACK_PIECES triangles (nearly all): the old
 * sides, the chosen edges and the spreading queue need no allocation there. */
enum { STACK_PIECES = 64 };

typedef struct scratch {
    side sides[3 * STACK_PIECES];
    bool use[3 * STACK_PIECES];
    uint32_t queue[STACK_PIECES];
} scratch;

/* Room for n items of `size` bytes: the stack's when they fit, else the heap's. */
static void *room(const mci_ctx *ctx, void *stack, size_t stack_bytes, size_t n, size_t size)
{
    return n <= stack_bytes / size ? stack : mci_malloc_array(ctx, n, size);
}

static void free_room(const mci_ctx *ctx, void *p, const void *stack)
{
    if (p != stack)
        mci_free(ctx, p);
}

static bool collect_old_sides(const mci_ctx *ctx, const mci_face_arr *arr,
                              const uint8_t *piece_keep, scratch *sc, old_sides *o)
{
    size_t n = 3 * arr->tri_count, nb = 0, nc = 0;
    for (size_t r = 0; r < n; r++) {
        uint32_t across = arr->adj[r];
        nb += across == UINT32_MAX;
        nc += across != UINT32_MAX && (across & MCI_CDT_CONSTRAINT) &&
              r < (across & ~MCI_CDT_CONSTRAINT);
    }
    /* One block for both lists (freed through o->boundary). */
    o->boundary = room(ctx, sc->sides, sizeof sc->sides, nb + nc + 1, sizeof *o->boundary);
    o->constraint = o->boundary ? o->boundary + nb : NULL;
    o->boundary_count = o->constraint_count = 0;
    if (!o->boundary)
        return false;
    for (size_t r = 0; r < n; r++) {
        uint32_t across = arr->adj[r], other = across & ~MCI_CDT_CONSTRAINT;
        if (across == UINT32_MAX)
            o->boundary[o->boundary_count++] = (side){side_key(arr->tris, r), (uint32_t)(r / 3)};
        else if ((across & MCI_CDT_CONSTRAINT) && r < other)
            o->constraint[o->constraint_count++] =
                (side){side_key(arr->tris, r), piece_keep[r / 3] != piece_keep[other / 3]};
    }
    mci_sort_keyed(o->boundary, o->boundary_count);
    mci_sort_keyed(o->constraint, o->constraint_count);
    return true;
}

static void free_old_sides(const mci_ctx *ctx, old_sides *o, const scratch *sc)
{
    free_room(ctx, o->boundary, sc->sides); /* and the constraints, in the same block */
}

/* Whether `key` is an interior constraint of the old tessellation, and a valid one. */
static bool is_interior(const old_sides *o, uint64_t key, bool *valid)
{
    size_t i = mci_find_key(o->constraint, o->constraint_count, key);
    *valid = i < o->constraint_count && o->constraint[i].ref;
    return i < o->constraint_count;
}

/* Status of the new triangles: from the old pieces along the face's boundary, then
 * across edges (the new adjacency), flipping across valid constraints. Fails if some
 * triangle is unreached. */
static mcsg_status spread_status(const mci_ctx *ctx, const old_sides *old,
                                 const uint8_t *piece_keep, const mci_face_arr *arr,
                                 scratch *sc, uint8_t *keep, mcsg_error *err)
{
    const uint32_t *tris = arr->tris;
    size_t n = arr->tri_count, tail = 0;
    uint32_t *queue = room(ctx, sc->queue, sizeof sc->queue, n + 1, sizeof *queue);
    mcsg_status st;
    for (size_t t = 0; queue && t < n; t++)
        keep[t] = 2;
    for (size_t r = 0; queue && r < 3 * n; r++) {
        uint32_t t = (uint32_t)(r / 3);
        size_t j;
        if (arr->adj[r] != UINT32_MAX || keep[t] != 2)
            continue;
        j = mci_find_key(old->boundary, old->boundary_count, side_key(tris, r));
        if (j < old->boundary_count) {
            keep[t] = piece_keep[old->boundary[j].ref];
            queue[tail++] = t;
        }
    }
    for (size_t head = 0; queue && head < tail; head++) {
        uint32_t t = queue[head];
        for (uint32_t r = 3 * t; r < 3 * t + 3; r++) {
            uint32_t u = arr->adj[r] == UINT32_MAX
                             ? UINT32_MAX
                             : (arr->adj[r] & ~MCI_CDT_CONSTRAINT) / 3;
            bool valid;
            if (u == UINT32_MAX || keep[u] != 2)
                continue;
            keep[u] = is_interior(old, side_key(tris, r), &valid) && valid ? !keep[t] : keep[t];
            queue[tail++] = u;
        }
    }
    st = !queue ? mci_fail_nomem(err, "tessellating the result")
         : tail < n ? mci_fail(err, MCSG_ERR_INTERNAL,
                               "face %u: a part of its tessellation is unclassified", arr->face)
                    : MCSG_OK;
    if (queue)
        free_room(ctx, queue, sc->queue);
    return st;
}

/* Choose the valid constraints; *droppable says whether any interior constraint is not. */
static void choose_valid(const mci_face_arr *arr, const old_sides *old, bool *use,
                         bool *droppable)
{
    *droppable = false;
    for (size_t e = 0; e < arr->edge_count; e++) {
        bool valid, interior = is_interior(old, mci_edge_key(arr->edges[e].a, arr->edges[e].b),
                                           &valid);
        use[e] = interior && valid;
        *droppable = *droppable || (interior && !use[e]);
    }
}

mcsg_status mci_arr_retessellate(const mci_ctx *ctx, mci_face_arr *arr,
                                 const uint8_t *piece_keep, uint8_t *tri_keep, mcsg_error *err)
{
    size_t n = arr->tri_count;
    scratch sc;
    old_sides old = {NULL, NULL, 0, 0};
    bool *use = room(ctx, sc.use, sizeof sc.use, arr->edge_count + 1, sizeof *use);
    bool droppable = false, any_kept = false;
    mcsg_status st = use && collect_old_sides(ctx, arr, piece_keep, &sc, &old)
                         ? MCSG_OK
                         : mci_fail_nomem(err, "tessellating the result");
    for (size_t t = 0; t < n; t++)
        any_kept = any_kept || piece_keep[t];
    if (st == MCSG_OK && any_kept)
        choose_valid(arr, &old, use, &droppable);
    if (st == MCSG_OK && droppable)
        st = mci_arr_triangulate(ctx, arr, use, err);
    /* Same boundary points and no more inside: never more triangles than before. */
    if (st == MCSG_OK && arr->tri_count > n)
        st = mci_fail(err, MCSG_ERR_INTERNAL, "face %u: more triangles after re-tessellating",
                      arr->face);
    if (st == MCSG_OK && !droppable)
        memcpy(tri_keep, piece_keep, n);
    else if (st == MCSG_OK)
        st = spread_status(ctx, &old, piece_keep, arr, &sc, tri_keep, err);
    if (old.boundary)
        free_old_sides(ctx, &old, &sc);
    if (use)
        free_room(ctx, use, sc.use);
    /* Nothing reads the adjacency after this; the face's triangles stay until assembly. */
    mci_free(ctx, arr->adj);
    arr->adj = NULL;
    return st;
}
