/*
 * Parts of the exact result that come closer than the spacing of doubles can round onto
 * each other: an edge of one part and an edge of another round to the same two points.
 * mci_split_touching gives each part its own vertex copies, so the output is manifold by
 * index, but once vertices are welded by coordinates (STL has no indices) that edge has
 * four triangles. Where the exact result itself does not touch there, the copies are
 * moved apart. Of the index edges on such a welded edge one stays in place (the first in
 * the order of vertex ids, or in a second round for the edges still left, the last);
 * each end of another that is not that one's vertex moves to one of the 26 doubles next
 * to it (one unit in the last place along some of the axes), the first direction that
 *   - lands on no other vertex (welding then leaves its edges as they are by index),
 *   - leaves each of its triangles with nonzero area and not turned over (its turn along
 *     the axis its normal was largest on keeps its sign),
 *   - makes none of its triangles cross a triangle near it (the exact test of
 *     mcsg_mesh_self_intersections, against every triangle whose bounding box meets
 *     theirs, padded by more than any move).
 * Directions are tried from the most inward (against the sum of its triangles' normals,
 * a preference in doubles only: every move is checked exactly). A copy where no
 * direction passes stays, and the output check reports the edge. So a vertex of the
 * output lies within one unit in the last place, per coordinate, of the double nearest
 * its exact position.
 */
#include "csg/separate_copies.h"
#include "base/sort.h"
#include "csg/rounding_repair.h"
#include "csg/self_intersect.h"
#include "exact/predicates.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

/* An undirected index edge lying on a welded edge: key of the welded edge, then the
 * vertex at its smaller welded end and the one at the other. */
typedef struct edge_use {
    uint64_t key;
    uint32_t lo, hi;
} edge_use;

typedef struct separator {
    const mci_ctx *ctx;
    mcsg_mesh *m;
    uint32_t *canon;      /* per vertex: welded id */
    uint64_t *bad;        /* welded edges to separate (keys), sorted */
    size_t nbad;
    uint32_t *candidate;  /* vertices to move, in order */
    size_t ncandidates;
    uint32_t *slot;       /* per vertex: its index in candidate[], or NONE */
    double (*box)[6];     /* per candidate: the padded box of its triangles */
    mci_keyed *incident, *near; /* (candidate index, triangle), sorted */
    size_t nincident, nnear;
    mci_keyed *by_hash;   /* (coordinate hash, vertex) of every vertex, sorted */
    double (*moved)[3];   /* where moved vertices went */
    size_t nmoved;
} separator;

static const double *at(const mcsg_mesh *m, uint32_t v)
{
    return m->vertices + 3 * (size_t)v;
}

static int compare_uses(const void *x, const void *y)
{
    const edge_use *a = x, *b = y;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    return (a->hi > b->hi) - (a->hi < b->hi);
}

static bool is_bad(const separator *s, uint64_t key)
{
    size_t lo = 0, hi = s->nbad;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (s->bad[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < s->nbad && s->bad[lo] == key;
}

/* The index edges on bad welded edges, sorted, each once. NULL when out of memory. */
static edge_use *bad_edge_uses(const separator *s, size_t *n)
{
    const mcsg_mesh *m = s->m;
    size_t count = 0, room = 16, kept = 0;
    edge_use *uses = mci_malloc_array(s->ctx, room, sizeof *uses);
    for (size_t t = 0; uses && t < m->triangle_count; t++)
        for (int i = 0; uses && i < 3; i++) {
            uint32_t a = m->triangles[3 * t + i], b = m->triangles[3 * t + (i + 1) % 3];
            uint32_t ca = s->canon[a], cb = s->canon[b];
            uint64_t key = ca < cb ? (uint64_t)ca << 32 | cb : (uint64_t)cb << 32 | ca;
            if (ca == cb || !is_bad(s, key))
                continue;
            if (count == room &&
                !mci_grow_array(s->ctx, (void **)&uses, &room, count + 1, sizeof *uses, 16)) {
                mci_free(s->ctx, uses);
                return NULL;
            }
            uses[count++] = ca < cb ? (edge_use){key, a, b} : (edge_use){key, b, a};
        }
    if (!uses)
        return NULL;
    qsort(uses, count, sizeof *uses, compare_uses);
    for (size_t i = 0; i < count; i++)
        if (kept == 0 || compare_uses(&uses[i], &uses[kept - 1]) != 0)
            uses[kept++] = uses[i];
    *n = kept;
    return uses;
}

static void add_candidate(separator *s, uint32_t v)
{
    if (s->slot[v] == NONE) {
        s->slot[v] = (uint32_t)s->ncandidates;
        s->candidate[s->ncandidates++] = v;
    }
}

/* The ends of the index edges on a bad welded edge that differ from those of the
 * edge kept in place: its first (round 0) or its last (round 1). A vertex both use would
 * separate nothing by moving. */
static bool choose_candidates(separator *s, int round)
{
    size_t n = 0;
    edge_use *uses = bad_edge_uses(s, &n);
    if (!uses)
        return false;
    s->candidate = mci_malloc_array(s->ctx, 2 * n + 1, sizeof *s->candidate);
    s->slot = mci_malloc_array(s->ctx, s->m->vertex_count + 1, sizeof *s->slot);
    if (s->candidate && s->slot) {
        for (size_t v = 0; v < s->m->vertex_count; v++)
            s->slot[v] = NONE;
        for (size_t first = 0, end; first < n; first = end) {
            size_t kept;
            for (end = first; end < n && uses[end].key == uses[first].key; end++)
                ;
            kept = round == 0 ? first : end - 1;
            for (size_t i = first; i < end; i++) {
                if (uses[i].lo != uses[kept].lo)
                    add_candidate(s, uses[i].lo);
                if (uses[i].hi != uses[kept].hi)
                    add_candidate(s, uses[i].hi);
            }
        }
    }
    mci_free(s->ctx, uses);
    return s->candidate && s->slot;
}

static void triangle_box(const mcsg_mesh *m, size_t t, double box[6])
{
    for (int k = 0; k < 3; k++)
        box[k] = box[3 + k] = at(m, m->triangles[3 * t])[k];
    for (int i = 1; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            double x = at(m, m->triangles[3 * t + i])[k];
            box[k] = fmin(box[k], x);
            box[3 + k] = fmax(box[3 + k], x);
        }
}

static bool boxes_meet(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] > b[3 + k] || b[k] > a[3 + k])
            return false;
    return true;
}

static bool push(const mci_ctx *ctx, mci_keyed **list, size_t *n, size_t *room, uint32_t c,
                 size_t t)
{
    if (*n == *room && !mci_grow_array(ctx, (void **)list, room, *n + 1, sizeof **list, 64))
        return false;
    (*list)[(*n)++] = (mci_keyed){c, (uint32_t)t};
    return true;
}

/* Each candidate's triangles, and the box they span padded by four units in the last
 * place of its largest coordinate (more than any move of this or another vertex). */
static bool find_incident(separator *s)
{
    const mcsg_mesh *m = s->m;
    size_t room = 0;
    s->box = mci_malloc_array(s->ctx, s->ncandidates + 1, sizeof *s->box);
    if (!s->box)
        return false;
    for (size_t c = 0; c < s->ncandidates; c++)
        for (int k = 0; k < 3; k++)
            s->box[c][k] = s->box[c][3 + k] = at(m, s->candidate[c])[k];
    for (size_t t = 0; t < m->triangle_count; t++)
        for (int i = 0; i < 3; i++) {
            uint32_t c = s->slot[m->triangles[3 * t + i]];
            double box[6];
            if (c == NONE)
                continue;
            if (!push(s->ctx, &s->incident, &s->nincident, &room, c, t))
                return false;
            triangle_box(m, t, box);
            for (int k = 0; k < 3; k++) {
                s->box[c][k] = fmin(s->box[c][k], box[k]);
                s->box[c][3 + k] = fmax(s->box[c][3 + k], box[3 + k]);
            }
        }
    for (size_t c = 0; c < s->ncandidates; c++) {
        double size = 0;
        for (int k = 0; k < 6; k++)
            size = fmax(size, fabs(s->box[c][k]));
        for (int k = 0; k < 3; k++) {
            s->box[c][k] -= 0x1p-50 * size;
            s->box[c][3 + k] += 0x1p-50 * size;
        }
    }
    mci_sort_keyed(s->incident, s->nincident);
    return true;
}

/* The triangles whose boxes meet each candidate's box. */
static bool find_near(separator *s)
{
    const mcsg_mesh *m = s->m;
    double all[6];
    size_t room = 0;
    memcpy(all, s->box[0], sizeof all);
    for (size_t c = 1; c < s->ncandidates; c++)
        for (int k = 0; k < 3; k++) {
            all[k] = fmin(all[k], s->box[c][k]);
            all[3 + k] = fmax(all[3 + k], s->box[c][3 + k]);
        }
    for (size_t t = 0; t < m->triangle_count; t++) {
        double box[6];
        triangle_box(m, t, box);
        if (!boxes_meet(box, all))
            continue;
        for (size_t c = 0; c < s->ncandidates; c++)
            if (boxes_meet(box, s->box[c]) &&
                !push(s->ctx, &s->near, &s->nnear, &room, (uint32_t)c, t))
                return false;
    }
    mci_sort_keyed(s->near, s->nnear);
    return true;
}

static bool index_coordinates(separator *s)
{
    const mcsg_mesh *m = s->m;
    s->by_hash = mci_malloc_array(s->ctx, m->vertex_count + 1, sizeof *s->by_hash);
    s->moved = mci_malloc_array(s->ctx, s->ncandidates + 1, sizeof *s->moved);
    if (!s->by_hash || !s->moved)
        return false;
    for (size_t v = 0; v < m->vertex_count; v++)
        s->by_hash[v] = (mci_keyed){mci_coordinate_hash(at(m, (uint32_t)v)), (uint32_t)v};
    mci_sort_keyed(s->by_hash, m->vertex_count);
    return true;
}

static bool same_point(const double *p, const double *q)
{
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

/* Whether some vertex has coordinates p (the moved ones where they went). */
static bool occupied(const separator *s, const double *p)
{
    uint64_t h = mci_coordinate_hash(p);
    size_t n = s->m->vertex_count;
    for (size_t i = mci_find_key(s->by_hash, n, h); i < n && s->by_hash[i].key == h; i++)
        if (same_point(at(s->m, s->by_hash[i].ref), p))
            return true;
    for (size_t i = 0; i < s->nmoved; i++)
        if (same_point(s->moved[i], p))
            return true;
    return false;
}

/* The 26 steps, most inward first (against `normal`), ties in a fixed order. */
static void order_steps(const double normal[3], int steps[26][3])
{
    double score[26];
    int n = 0;
    for (int x = -1; x <= 1; x++)
        for (int y = -1; y <= 1; y++)
            for (int z = -1; z <= 1; z++) {
                if (!x && !y && !z)
                    continue;
                steps[n][0] = x, steps[n][1] = y, steps[n][2] = z;
                score[n++] = (x * normal[0] + y * normal[1] + z * normal[2]) /
                             sqrt((double)(x * x + y * y + z * z));
            }
    for (int i = 1; i < 26; i++) /* insertion sort: stable */
        for (int j = i; j > 0 && score[j] < score[j - 1]; j--) {
            double ds = score[j];
            int d[3];
            memcpy(d, steps[j], sizeof d);
            score[j] = score[j - 1], score[j - 1] = ds;
            memcpy(steps[j], steps[j - 1], sizeof d);
            memcpy(steps[j - 1], d, sizeof d);
        }
}

/* Triangle t's turn along the axis its normal is largest on (mci_triangle_turn), as
 * turn[0], and that axis, as turn[1]. */
static void turns(const mcsg_mesh *m, uint32_t t, int out[2])
{
    const uint32_t *v = m->triangles + 3 * (size_t)t;
    out[0] = mci_triangle_turn(at(m, v[0]), at(m, v[1]), at(m, v[2]), &out[1]);
}

/* Triangle t's turn along `axis` now. */
static int turn_along(const mcsg_mesh *m, uint32_t t, int axis)
{
    const uint32_t *v = m->triangles + 3 * (size_t)t;
    const double *a = at(m, v[0]), *b = at(m, v[1]), *c = at(m, v[2]);
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    return mci_orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

/* Whether the candidate's triangles (incident[first .. end)) are as valid where the
 * vertex now is: nonzero area, no projected turn reversed (before[]), no crossing with
 * a near triangle. */
static bool move_is_valid(const separator *s, size_t first, size_t end, const int (*before)[2],
                          uint32_t c)
{
    size_t near_first = mci_find_key(s->near, s->nnear, c);
    for (size_t i = first; i < end; i++) {
        uint32_t t = s->incident[i].ref;
        const uint32_t *v = s->m->triangles + 3 * (size_t)t;
        if (mci_triangle_is_degenerate(at(s->m, v[0]), at(s->m, v[1]), at(s->m, v[2])))
            return false;
        if (turn_along(s->m, t, before[i - first][1]) != before[i - first][0])
            return false;
    }
    for (size_t i = first; i < end; i++) {
        uint32_t t = s->incident[i].ref;
        double box[6], other[6];
        triangle_box(s->m, t, box);
        for (size_t j = near_first; j < s->nnear && s->near[j].key == c; j++) {
            uint32_t u = s->near[j].ref;
            if (u == t)
                continue;
            triangle_box(s->m, u, other); /* closed triangles meet only if their boxes do */
            if (boxes_meet(box, other) && mci_triangles_cross(s->m, t, u))
                return false;
        }
    }
    return true;
}

static void normal_sum(const separator *s, size_t first, size_t end, double n[3])
{
    n[0] = n[1] = n[2] = 0;
    for (size_t i = first; i < end; i++) {
        const uint32_t *v = s->m->triangles + 3 * (size_t)s->incident[i].ref;
        const double *a = at(s->m, v[0]), *b = at(s->m, v[1]), *c = at(s->m, v[2]);
        for (int k = 0; k < 3; k++) {
            int i1 = (k + 1) % 3, i2 = (k + 2) % 3;
            n[k] += (b[i1] - a[i1]) * (c[i2] - a[i2]) - (b[i2] - a[i2]) * (c[i1] - a[i1]);
        }
    }
}

/* Whether candidate c's triangles cross a triangle near them where it is now. */
static bool crosses_here(separator *s, uint32_t c, int (*before)[2])
{
    size_t first = mci_find_key(s->incident, s->nincident, c), end = first;
    while (end < s->nincident && s->incident[end].key == c)
        end++;
    for (size_t i = first; i < end; i++)
        turns(s->m, s->incident[i].ref, before[i - first]);
    return !move_is_valid(s, first, end, (const int(*)[2])before, c);
}

/* Move candidate c to the first valid neighbouring double; false if none is. */
static bool try_move(separator *s, uint32_t c, int (*before)[2])
{
    double *p = s->m->vertices + 3 * (size_t)s->candidate[c], orig[3], normal[3];
    size_t first = mci_find_key(s->incident, s->nincident, c), end = first;
    int steps[26][3];
    while (end < s->nincident && s->incident[end].key == c)
        end++;
    for (size_t i = first; i < end; i++)
        turns(s->m, s->incident[i].ref, before[i - first]);
    normal_sum(s, first, end, normal);
    order_steps(normal, steps);
    memcpy(orig, p, sizeof orig);
    for (int d = 0; d < 26; d++) {
        double q[3];
        for (int k = 0; k < 3; k++)
            q[k] = steps[d][k] ? nextafter(orig[k], steps[d][k] * INFINITY) : orig[k];
        if (!isfinite(q[0] + q[1] + q[2]) || occupied(s, q))
            continue;
        memcpy(p, q, sizeof q);
        if (move_is_valid(s, first, end, (const int(*)[2])before, c)) {
            memcpy(s->moved[s->nmoved++], q, sizeof q);
            return true;
        }
        memcpy(p, orig, sizeof orig);
    }
    return false;
}

static size_t most_incident(const separator *s)
{
    size_t most = 0;
    for (size_t i = 0, j; i < s->nincident; i = j) {
        for (j = i; j < s->nincident && s->incident[j].key == s->incident[i].key; j++)
            ;
        most = j - i > most ? j - i : most;
    }
    return most;
}

static void free_separator(separator *s)
{
    const mci_ctx *ctx = s->ctx;
    mci_free(ctx, s->canon);
    mci_free(ctx, s->bad);
    mci_free(ctx, s->candidate);
    mci_free(ctx, s->slot);
    mci_free(ctx, s->box);
    mci_free(ctx, s->incident);
    mci_free(ctx, s->near);
    mci_free(ctx, s->by_hash);
    mci_free(ctx, s->moved);
}

static void start_separator(separator *s, const mci_ctx *ctx, mcsg_mesh *m)
{
    memset(s, 0, sizeof *s);
    s->ctx = ctx;
    s->m = m;
}

/* The candidates' triangles and what lies near them, then their moves (with
 * only_crossing, of those whose triangles cross something where they are); *moved
 * counts the moves. */
static bool move_candidates(separator *s, bool only_crossing, size_t *moved)
{
    int (*before)[2] = NULL;
    bool ok = find_incident(s) && find_near(s) && index_coordinates(s) &&
              (before = mci_malloc_array(s->ctx, most_incident(s) + 1, sizeof *before));
    for (size_t c = 0; ok && c < s->ncandidates; c++)
        if (!only_crossing || crosses_here(s, (uint32_t)c, before))
            *moved += try_move(s, (uint32_t)c, before);
    mci_free(s->ctx, before);
    return ok;
}

/* One round: the bad edges now, the candidates, and their moves. */
static bool separate_round(const mci_ctx *ctx, mcsg_mesh *m, const mci_exact_result *exact,
                           int round, mci_copy_separation *result)
{
    separator s;
    bool ok;
    start_separator(&s, ctx, m);
    s.canon = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *s.canon);
    ok = s.canon && mci_welded_overfull_edges(ctx, m, exact, s.canon, &s.bad, &s.nbad);
    if (round == 0)
        result->edges = s.nbad;
    if (ok && s.nbad > 0 && (ok = choose_candidates(&s, round)) && s.ncandidates > 0)
        ok = move_candidates(&s, false, &result->moved);
    free_separator(&s);
    return ok;
}

/* The corners of the crossing triangles, each once. */
static bool crossing_candidates(separator *s, const uint64_t *pairs, size_t n)
{
    const mcsg_mesh *m = s->m;
    s->candidate = mci_malloc_array(s->ctx, 6 * n + 1, sizeof *s->candidate);
    s->slot = mci_malloc_array(s->ctx, m->vertex_count + 1, sizeof *s->slot);
    if (!s->candidate || !s->slot)
        return false;
    for (size_t v = 0; v < m->vertex_count; v++)
        s->slot[v] = NONE;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            add_candidate(s, m->triangles[3 * (size_t)(pairs[i] >> 32) + k]);
            add_candidate(s, m->triangles[3 * (size_t)(uint32_t)pairs[i] + k]);
        }
    return true;
}

bool mci_separate_crossing_corners(const mci_ctx *ctx, mcsg_mesh *m, const uint64_t *pairs,
                                   size_t n, size_t *moved)
{
    separator s;
    bool ok;
    *moved = 0;
    if (n == 0)
        return true;
    start_separator(&s, ctx, m);
    ok = crossing_candidates(&s, pairs, n) && move_candidates(&s, true, moved);
    free_separator(&s);
    return ok;
}

bool mci_separate_welded_copies(const mci_ctx *ctx, mcsg_mesh *m, const mci_exact_result *exact,
                                mci_copy_separation *result)
{
    bool ok = true;
    memset(result, 0, sizeof *result);
    for (int round = 0; ok && round < 2 && (round == 0 || result->edges > 0); round++)
        ok = separate_round(ctx, m, exact, round, result);
    return ok;
}
