/*
 * One number per distinct point of all arrangements (mci_scene_number_points): exact
 * identity over the whole scene, not welding by distance.
 */
#include "base/parallel.h"
#include "base/sort.h"
#include "base/sort_template.h"
#include "csg/intersect_internal.h"

#include <stdlib.h>
#include <string.h>

static uint64_t definition_hash(const mci_point *p)
{
    return mci_hash_vertices(0x9e3779b97f4a7c15u ^ (uint64_t)p->kind, p->v,
                         mci_point_vertex_count(p));
}

/* Numbering in three steps, each deterministic:
 *   1. copies with the same definition (kind and defining vertices) are one point:
 *      found by hashing, no arithmetic (most shared points are defined identically by
 *      the faces that share them: canonical edge order, canonical TPI plane order);
 *   2. distinct definitions of one point (e.g. a crossing exactly at a vertex) are
 *      found among points whose certified boxes overlap (groups split along the axes
 *      until no axis splits them) and joined after exact comparisons;
 *   3. numbers follow the first occurrence in (face, local index) order. */
typedef struct numbering {
    const mci_ctx *ctx;
    const mci_point **table; /* by slot */
    uint8_t *explicit_slot;  /* by slot, filled with the hashes */
    uint32_t *parent;        /* union-find over slots */
    size_t total;
} numbering;

/* Join with the smaller slot as root, so that roots are first occurrences. */
static void join(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = mci_find_root(parent, a);
    b = mci_find_root(parent, b);
    if (a < b)
        parent[b] = a;
    else if (b < a)
        parent[a] = b;
}

/* Copies with one definition are found with one hash table per part of the hash space
 * (parts by the top bits, filled in parallel): a class of copies lies in one part, each
 * part takes its slots in increasing order, so every copy is joined to the first slot of
 * its class as a single table would do. */
enum { HASH_PARTS = 64, HASH_CHUNK = 16384 };

typedef struct same_job {
    numbering *nb;
    uint64_t *hash;                   /* by slot */
    uint32_t *by_part;                /* slots grouped by part, increasing within a part */
    size_t part_start[HASH_PARTS + 1];
} same_job;

static mcsg_status hash_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const same_job *j = user;
    (void)err;
    for (size_t slot = begin; slot < end; slot++) {
        j->hash[slot] = definition_hash(j->nb->table[slot]);
        j->nb->explicit_slot[slot] = j->nb->table[slot]->kind == MCI_POINT_EXPLICIT;
    }
    return MCSG_OK;
}

static mcsg_status join_part(void *user, size_t part, mcsg_error *err)
{
    const same_job *j = user;
    const numbering *nb = j->nb;
    size_t first = j->part_start[part], n = j->part_start[part + 1] - first, size = 16;
    uint32_t *bucket;
    while (size < 2 * n)
        size *= 2;
    if (!(bucket = mci_malloc_array(nb->ctx, size, sizeof *bucket)))
        return mci_fail_nomem(err, "numbering points");
    for (size_t i = 0; i < size; i++)
        bucket[i] = MCI_NONE;
    for (size_t i = 0; i < n; i++) {
        uint32_t slot = j->by_part[first + i];
        size_t at = j->hash[slot] & (size - 1);
        while (bucket[at] != MCI_NONE &&
               (j->hash[bucket[at]] != j->hash[slot] ||
                !mci_points_same_definition(nb->table[bucket[at]], nb->table[slot])))
            at = (at + 1) & (size - 1);
        if (bucket[at] == MCI_NONE)
            bucket[at] = slot;
        else
            nb->parent[slot] = bucket[at]; /* both are roots: the first of the class wins */
    }
    mci_free(nb->ctx, bucket);
    return MCSG_OK;
}

static mcsg_status join_same_definitions(const mci_ctx *ctx, numbering *nb, mcsg_error *err)
{
    same_job j = {nb, mci_malloc_array(ctx, nb->total + 1, sizeof *j.hash),
                  mci_malloc_array(ctx, nb->total + 1, sizeof *j.by_part), {0}};
    mcsg_status st = j.hash && j.by_part ? MCSG_OK : mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK)
        st = mci_parallel_for_ranges(ctx, nb->total, HASH_CHUNK, hash_chunk, &j, err);
    if (st == MCSG_OK) { /* a stable counting sort of the slots by part */
        size_t at[HASH_PARTS] = {0};
        for (size_t slot = 0; slot < nb->total; slot++)
            j.part_start[(j.hash[slot] >> 58) + 1]++;
        for (size_t q = 0; q < HASH_PARTS; q++)
            j.part_start[q + 1] += j.part_start[q];
        for (size_t q = 0; q < HASH_PARTS; q++)
            at[q] = j.part_start[q];
        for (size_t slot = 0; slot < nb->total; slot++)
            j.by_part[at[j.hash[slot] >> 58]++] = (uint32_t)slot;
        st = mci_parallel_for(ctx, HASH_PARTS, join_part, &j, err);
    }
    mci_free(ctx, j.hash);
    mci_free(ctx, j.by_part);
    return st;
}

/* The certified box rounded outward to floats: the table of these is the peak of the
 * dense scenes' runs, and a larger box only adds pairs to test. */
typedef struct boxed_slot {
    float lo[3], hi[3];
    uint32_t slot;
} boxed_slot;

/* A key whose unsigned order is the numeric order of x (not NaN; -0 counts as +0). */
static uint32_t orderable_float(float x)
{
    uint32_t bits;
    x += 0.0f; /* -0 -> +0 */
    memcpy(&bits, &x, sizeof bits);
    return bits >> 31 ? ~bits : bits | (UINT32_C(1) << 31);
}

typedef struct bounds_job {
    const numbering *nb;
    boxed_slot *items;
    uint64_t *order; /* per item: its low x (orderable_float) << 32 | its index */
    size_t n;
} bounds_job;

/* The certified boxes (the cost of this step: LPI and TPI bounds), in parallel. */
static mcsg_status bound_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const bounds_job *j = user;
    (void)err;
    for (size_t i = begin; i < end; i++) {
        boxed_slot *item = &j->items[i];
        double lo[3], hi[3];
        mci_point_bounds(j->nb->table[item->slot], lo, hi);
        for (int k = 0; k < 3; k++) { /* a NaN bound (overflow) bounds nothing */
            item->lo[k] = isnan(lo[k]) ? -INFINITY : mci_float_below(lo[k]);
            item->hi[k] = isnan(hi[k]) ? INFINITY : mci_float_above(hi[k]);
        }
        j->order[i] = (uint64_t)orderable_float(item->lo[0]) << 32 | i;
    }
    return MCSG_OK;
}

static bool boxes_meet(const boxed_slot *a, const boxed_slot *b)
{
    for (int k = 0; k < 3; k++)
        if (a->lo[k] > b->hi[k] || b->lo[k] > a->hi[k])
            return false;
    return true;
}

typedef struct lex_item {
    const mci_point *p;
    uint32_t slot;
} lex_item;

#define LEX_LESS(a, b) (mci_compare_lex((a)->p, (b)->p) < 0)
MCI_DEFINE_SORT(sort_lex_items, lex_item, LEX_LESS)

/* Groups up to this size test their overlapping pairs; larger ones sort exactly. */
enum { PAIRWISE_MAX = 32 };

/* A group that no axis splits (keys: item indices in the low halves): its points are
 * nearly coincident. A few are compared pair by pair where their boxes overlap; more are
 * sorted in exact lexicographic order and neighbours compared, since testing every pair
 * was quadratic where thousands of distinct points nearly coincide (a spindle torus,
 * whose meridians all cross the axis near one point). */
static void join_group(numbering *nb, const boxed_slot *items, const uint64_t *keys, size_t k,
                       lex_item *buffer)
{
    if (k <= PAIRWISE_MAX) {
        for (size_t i = 0; i < k; i++)
            for (size_t m = i + 1; m < k; m++) {
                const boxed_slot *a = &items[(uint32_t)keys[i]], *b = &items[(uint32_t)keys[m]];
                if (boxes_meet(a, b) && mci_points_equal(nb->table[a->slot], nb->table[b->slot]))
                    join(nb->parent, a->slot, b->slot);
            }
        return;
    }
    for (size_t i = 0; i < k; i++) {
        buffer[i].slot = items[(uint32_t)keys[i]].slot;
        buffer[i].p = nb->table[buffer[i].slot];
    }
    sort_lex_items(buffer, k);
    for (size_t i = 1; i < k; i++)
        if (mci_points_equal(buffer[i - 1].p, buffer[i].p))
            join(nb->parent, buffer[i - 1].slot, buffer[i].slot);
}

/* keys[0 .. n) by the low end of the boxes along axis (ties by item). */
static bool sort_by_low(const mci_ctx *ctx, const boxed_slot *items, uint64_t *keys, size_t n,
                        int axis)
{
    for (size_t i = 0; i < n; i++)
        keys[i] = (uint64_t)orderable_float(items[(uint32_t)keys[i]].lo[axis]) << 32 |
                  (uint32_t)keys[i];
    if (n > 4096)
        return mci_radix_sort_u64(ctx, keys, n);
    mci_sort_u64(keys, n);
    return true;
}

/* A run of keys whose boxes chain along the axes tried `unsplit` times in a row. */
typedef struct group_range {
    uint32_t begin, end;
    uint8_t axis, unsplit;
} group_range;

/* Splits a range sorted along r.axis where the chain of overlapping intervals breaks;
 * pushes the parts of two or more items (single points equal nothing else). */
static void split_range(const boxed_slot *items, const uint64_t *keys, group_range r,
                        group_range *stack, size_t *top)
{
    uint8_t next = (uint8_t)((r.axis + 1) % 3);
    uint32_t start = r.begin;
    float hi = items[(uint32_t)keys[r.begin]].hi[r.axis];
    for (uint32_t i = r.begin + 1; i <= r.end; i++) {
        const boxed_slot *b = i < r.end ? &items[(uint32_t)keys[i]] : NULL;
        if (b && !(b->lo[r.axis] > hi)) {
            hi = b->hi[r.axis] > hi ? b->hi[r.axis] : hi;
            continue;
        }
        if (start == r.begin && i == r.end) /* no break: one more axis tried in vain */
            stack[(*top)++] = (group_range){r.begin, r.end, next, (uint8_t)(r.unsplit + 1)};
        else if (i - start >= 2)
            stack[(*top)++] = (group_range){start, i, next, 1};
        if (b)
            start = i, hi = b->hi[r.axis];
    }
}

/* Distinct definitions of one point: equal points have overlapping certified boxes, so
 * the items are split recursively where the boxes' intervals along an axis stop
 * overlapping, until no axis splits a group; each group is then joined. A sweep that
 * tested every overlapping pair was quadratic in dense groups. The joins depend only on
 * which points are equal, not on the order. */
static mcsg_status join_by_splitting(const mci_ctx *ctx, numbering *nb, const boxed_slot *items,
                                     uint64_t *keys, size_t n, mcsg_error *err)
{
    group_range *stack = mci_malloc_array(ctx, n / 2 + 2, sizeof *stack);
    lex_item *buffer = NULL; /* for the largest group sorted so far */
    size_t top = 0, capacity = 0;
    mcsg_status st = stack ? MCSG_OK : mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK && n >= 2)
        stack[top++] = (group_range){0, (uint32_t)n, 0, 0};
    while (st == MCSG_OK && top > 0) {
        group_range r = stack[--top];
        size_t k = r.end - r.begin;
        if (r.unsplit == 3 && k > PAIRWISE_MAX && k > capacity) {
            mci_free(ctx, buffer);
            if (!(buffer = mci_malloc_array(ctx, capacity = k, sizeof *buffer)))
                st = mci_fail_nomem(err, "numbering points");
        }
        if (st != MCSG_OK)
            break;
        if (r.unsplit == 3)
            join_group(nb, items, keys + r.begin, k, buffer);
        else if (!sort_by_low(ctx, items, keys + r.begin, k, r.axis))
            st = mci_fail_nomem(err, "numbering points");
        else
            split_range(items, keys, r, stack, &top);
    }
    mci_free(ctx, stack);
    mci_free(ctx, buffer);
    return st;
}

static mcsg_status join_equal_points(const mci_ctx *ctx, numbering *nb, mcsg_error *err)
{
    size_t roots = 0;
    bounds_job j = {nb, NULL, NULL, 0};
    mcsg_status st;
    /* Sized for the roots only: most slots are copies. */
    for (uint32_t slot = 0; slot < nb->total; slot++)
        roots += nb->parent[slot] == slot;
    j.items = mci_malloc_array(ctx, roots + 1, sizeof *j.items);
    j.order = mci_malloc_array(ctx, roots + 1, sizeof *j.order);
    st = j.items && j.order ? MCSG_OK : mci_fail_nomem(err, "numbering points");
    for (uint32_t slot = 0; st == MCSG_OK && slot < nb->total; slot++)
        if (nb->parent[slot] == slot) /* not a copy of an earlier definition */
            j.items[j.n++].slot = slot;
    if (st == MCSG_OK)
        st = mci_parallel_for_ranges(ctx, j.n, HASH_CHUNK, bound_chunk, &j, err);
    if (st == MCSG_OK)
        st = join_by_splitting(ctx, nb, j.items, j.order, j.n, err);
    mci_free(ctx, j.items);
    mci_free(ctx, j.order);
    return st;
}

/* The table and the identity parents, on the threads in chunks of arrangements
 * (gid_start set); then, after the joins, the numbers: roots (first occurrences) are
 * numbered in slot order through per-chunk counts, so the numbering does not depend on
 * the threads. Both loops once ran on one thread: a serial pass over every slot. */
enum { SLOT_ARR_CHUNK = 4096 };

typedef struct slots_job {
    mci_scene *s;
    numbering *nb;
    uint32_t *first_id; /* per chunk of slots: the number of its first root */
} slots_job;

static mcsg_status fill_slot_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const slots_job *j = user;
    const mci_scene *s = j->s;
    (void)err;
    for (size_t k = begin; k < end; k++)
        for (uint32_t p = 0, slot = s->gid_start[k]; p < s->arrs[k].point_count; p++, slot++) {
            j->nb->table[slot] = s->arrs[k].points[p];
            j->nb->parent[slot] = slot;
        }
    return MCSG_OK;
}

static mcsg_status fill_slots(const mci_ctx *ctx, mci_scene *s, numbering *nb, mcsg_error *err)
{
    slots_job j = {s, nb, NULL};
    return mci_parallel_for_ranges(ctx, s->arr_count, SLOT_ARR_CHUNK, fill_slot_chunk, &j, err);
}

/* Pass 1: gid[slot] = its root (parent is only read: no path compression on the threads),
 * and the chunk's count of roots in first_id. */
static mcsg_status root_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const slots_job *j = user;
    const uint32_t *parent = j->nb->parent;
    uint32_t roots = 0;
    (void)err;
    for (size_t slot = begin; slot < end; slot++) {
        uint32_t x = (uint32_t)slot;
        while (parent[x] != x)
            x = parent[x];
        j->s->gid[slot] = x;
        roots += x == slot;
    }
    j->first_id[begin / HASH_CHUNK] = roots;
    return MCSG_OK;
}

/* Pass 2: each root's number into parent (no longer needed as such). */
static mcsg_status number_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const slots_job *j = user;
    uint32_t id = j->first_id[begin / HASH_CHUNK];
    (void)err;
    for (size_t slot = begin; slot < end; slot++)
        if (j->s->gid[slot] == slot)
            j->nb->parent[slot] = id++;
    return MCSG_OK;
}

/* Pass 3: every slot takes its root's number. */
static mcsg_status renumber_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const slots_job *j = user;
    (void)err;
    for (size_t slot = begin; slot < end; slot++)
        j->s->gid[slot] = j->nb->parent[j->s->gid[slot]];
    return MCSG_OK;
}

static mcsg_status number_roots(const mci_ctx *ctx, mci_scene *s, numbering *nb, uint32_t *count,
                                mcsg_error *err)
{
    size_t chunks = (nb->total + HASH_CHUNK - 1) / HASH_CHUNK;
    slots_job j = {s, nb, mci_malloc_array(ctx, chunks + 1, sizeof *j.first_id)};
    mcsg_status st = j.first_id
                         ? mci_parallel_for_ranges(ctx, nb->total, HASH_CHUNK, root_chunk, &j, err)
                         : mci_fail_nomem(err, "numbering points");
    *count = 0;
    for (size_t c = 0; st == MCSG_OK && c < chunks; c++) { /* counts -> first numbers */
        uint32_t roots = j.first_id[c];
        j.first_id[c] = *count;
        *count += roots;
    }
    if (st == MCSG_OK)
        st = mci_parallel_for_ranges(ctx, nb->total, HASH_CHUNK, number_chunk, &j, err);
    if (st == MCSG_OK)
        st = mci_parallel_for_ranges(ctx, nb->total, HASH_CHUNK, renumber_chunk, &j, err);
    mci_free(ctx, j.first_id);
    return st;
}

mcsg_status mci_scene_number_points(const mci_ctx *ctx, mci_scene *s, mcsg_error *err)
{
    numbering nb = {ctx, NULL, NULL, NULL, 0};
    uint32_t id = 0;
    bool ok;
    mcsg_status st;
    double t0 = mci_seconds_now();
    for (size_t k = 0; k < s->arr_count; k++)
        nb.total += s->arrs[k].point_count;
    if (nb.total >= UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "too many intersection points (%zu)", nb.total);
    s->gid_start = mci_malloc_array(ctx, s->arr_count + 1, sizeof *s->gid_start);
    s->explicit_slot = nb.explicit_slot = mci_malloc_array(ctx, nb.total + 1, 1);
    nb.table = mci_malloc_array(ctx, nb.total + 1, sizeof *nb.table);
    nb.parent = mci_malloc_array(ctx, nb.total + 1, sizeof *nb.parent);
    ok = s->gid_start && s->explicit_slot && nb.table && nb.parent;
    for (size_t k = 0, slot = 0; ok && k < s->arr_count; k++) {
        s->gid_start[k] = (uint32_t)slot;
        slot += s->arrs[k].point_count;
    }
    if (ok)
        s->gid_start[s->arr_count] = (uint32_t)nb.total;
    st = ok ? fill_slots(ctx, s, &nb, err) : mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK)
        st = join_same_definitions(ctx, &nb, err);
    if (st == MCSG_OK)
        st = join_equal_points(ctx, &nb, err);
    /* Allocated last: the joins' tables were this step's peak. */
    if (st == MCSG_OK && !(s->gid = mci_malloc_array(ctx, nb.total + 1, sizeof *s->gid)))
        st = mci_fail_nomem(err, "numbering points");
    if (st == MCSG_OK)
        st = number_roots(ctx, s, &nb, &id, err);
    s->point_count = st == MCSG_OK ? id : 0;
    mci_free(ctx, nb.table);
    mci_free(ctx, nb.parent);
    if (st == MCSG_OK)
        st = mci_point_values_init(ctx, &s->values, s->point_count, err);
    for (size_t k = 0; st == MCSG_OK && k < s->arr_count; k++) {
        s->arrs[k].gid = s->gid + s->gid_start[k];
        s->arrs[k].values = &s->values;
    }
    s->stats.seconds_merge = mci_seconds_now() - t0;
    return st;
}

