/*
 * Where parts of a result touch along an edge or at a point (two boxes sharing only an
 * edge, a cone tip on a face), the exact result is not a manifold: an edge has four (or
 * more) triangles, or a vertex has two umbrellas. The output is made edge- and
 * vertex-manifold by giving each umbrella its own copy of the vertex (same coordinates),
 * which changes no geometry.
 *
 * At an edge with 2k triangles, the triangles are sorted by angle around the edge and
 * paired: a triangle's solid side is at decreasing angle about its own edge direction
 * (its normal points to increasing angle), so each triangle running u->v is paired with
 * the one just before it in the turn about u->v, which runs v->u. Then, at every vertex,
 * the triangles around it are grouped by crossing its edges (to the unique other triangle
 * at a manifold edge, to the paired one at a non-manifold edge); each group beyond the
 * first gets a new vertex. All angle comparisons are exact predicates on the rounded
 * coordinates.
 *
 * Two serial passes, only where edges have more than two triangles, pair by turns about
 * an end instead (pair_reordered, separate_shared_edges): where rounding reordered the
 * triangles about an edge so that directions do not alternate, and where the angle pairs
 * would share both ends' umbrellas, so that no copy could separate them.
 */
#include "csg/manifold_split.h"
#include "base/parallel.h"
#include "exact/kernel.h"
#include "exact/predicates.h"

#include <string.h>

/* Pairing and grouping run on the threads in fixed chunks of vertices (each chunk writes
 * only its own vertices' edge slots and corners); copies are numbered in vertex order
 * through per-chunk counts, so the result does not depend on the thread count. */
enum { VERTEX_CHUNK = 4096 };

typedef struct splitter {
    const mci_ctx *ctx;
    mcsg_mesh *m;
    uint32_t *mate; /* per edge slot 3t + i (corner i -> i + 1): the paired slot */
    uint32_t *start, *corner; /* corners (= outgoing edge slots) of vertex v:
                                 corner[start[v] .. start[v + 1]) */
    size_t chunks;
    size_t *bad_edges;        /* per chunk: edges left unpaired */
    size_t *reordered_edges;  /* per chunk: edges the angle pairing left (reordered) */
    size_t *shared_edges;     /* per chunk: edges with over two triangles, paired */
    size_t separated_edges;   /* paired again by separate_pairs */
    uint32_t *parent, *copy;  /* per corner: union-find, the copy of a root */
    size_t *extra;            /* per chunk: new vertices; then the first new id */
} splitter;

static const double *vertex(const mcsg_mesh *m, uint32_t v)
{
    return m->vertices + 3 * (size_t)v;
}

static uint32_t slot_from(const mcsg_mesh *m, uint32_t s)
{
    return m->triangles[s];
}

/* The next and the previous corner of slot s's triangle (no division: these run for
 * every corner of the output several times). */
static uint32_t next_in_triangle(uint32_t s)
{
    return s % 3 == 2 ? s - 2 : s + 1;
}

static uint32_t prev_in_triangle(uint32_t s)
{
    return s % 3 == 0 ? s + 2 : s - 1;
}

static uint32_t slot_to(const mcsg_mesh *m, uint32_t s)
{
    return m->triangles[next_in_triangle(s)];
}

static uint32_t slot_third(const mcsg_mesh *m, uint32_t s)
{
    return m->triangles[prev_in_triangle(s)];
}

static void pair_slots(splitter *sp, uint32_t a, uint32_t b)
{
    sp->mate[a] = b;
    sp->mate[b] = a;
}

/* The slot y -> x reached by turning about x from slot s (x -> y) across x's other
 * edges, through the slots already paired: consistent orientation makes the turn end at
 * an edge y -> x. MCI_NONE if an edge on the way is not paired yet. */
static uint32_t turn_about_from(const splitter *sp, uint32_t s)
{
    const mcsg_mesh *m = sp->m;
    uint32_t x = slot_from(m, s), y = slot_to(m, s);
    for (uint32_t steps = sp->start[x + 1] - sp->start[x]; steps > 0; steps--) {
        uint32_t in = prev_in_triangle(s); /* w -> x */
        if (slot_from(m, in) == y)
            return in;
        if ((s = sp->mate[in]) == MCI_NONE)
            return MCI_NONE;
    }
    return MCI_NONE;
}

/* The pairs that let copies of x separate them: each slot leaving x (from[k]) with the
 * slot where the turn about x from it ends (to[k]), which puts every pair in an umbrella
 * of its own at x. Returns the number of pairs, or 0 if a turn fails or two end at the
 * same slot. */
static size_t pairs_by_turns(const splitter *sp, const uint32_t *slots, size_t n, uint32_t x,
                             uint32_t *from, uint32_t *to)
{
    size_t pairs = 0;
    for (size_t i = 0; i < n; i++) {
        if (slot_from(sp->m, slots[i]) != x)
            continue;
        from[pairs] = slots[i];
        to[pairs] = turn_about_from(sp, slots[i]);
        if (to[pairs] == MCI_NONE)
            return 0;
        for (size_t k = 0; k < pairs; k++)
            if (to[k] == to[pairs])
                return 0;
        pairs++;
    }
    return pairs;
}

/* Pair the edge by turns about x (see pairs_by_turns); false, with nothing written, if
 * that fails. */
static bool pair_by_turns(splitter *sp, const uint32_t *slots, size_t n, uint32_t x)
{
    uint32_t from[32], to[32];
    size_t pairs = pairs_by_turns(sp, slots, n, x, from, to);
    for (size_t k = 0; k < pairs; k++)
        pair_slots(sp, from[k], to[k]);
    return pairs > 0;
}

/* Sort the slots of edge u-v (slots[0] runs u -> v) by angle about u -> v. */
static void sort_by_angle(const splitter *sp, uint32_t *slots, size_t n)
{
    const mcsg_mesh *m = sp->m;
    uint32_t u = slot_from(m, slots[0]), v = slot_to(m, slots[0]);
    const double *pu = vertex(m, u), *pv = vertex(m, v), *r = vertex(m, slot_third(m, slots[0]));
    for (size_t i = 1; i < n; i++) /* insertion sort: n is small */
        for (size_t j = i;
             j > 0 && mci_half_plane_before(pu, pv, r, vertex(m, slot_third(m, slots[j])),
                                            vertex(m, slot_third(m, slots[j - 1])));
             j--) {
            uint32_t t = slots[j];
            slots[j] = slots[j - 1];
            slots[j - 1] = t;
        }
}

/* The last resort: any pairing of opposite directions makes the edge manifold. This one
 * reads the turn about u -> v as a bracket sequence (v -> u opens, u -> v closes) and
 * pairs matching brackets, so that no two pairs interleave. Both directions occur n / 2
 * times. */
static void pair_by_brackets(splitter *sp, uint32_t *slots, size_t n)
{
    uint32_t open[32], u = slot_from(sp->m, slots[0]);
    size_t first = 0, depth = 0;
    long balance = 0, lowest = 0;
    sort_by_angle(sp, slots, n);
    for (size_t i = 0; i < n; i++) { /* start just after the lowest prefix balance */
        balance += slot_from(sp->m, slots[i]) == u ? -1 : 1;
        if (balance < lowest)
            lowest = balance, first = i + 1;
    }
    for (size_t k = 0; k < n; k++) {
        uint32_t s = slots[(first + k) % n];
        if (slot_from(sp->m, s) != u)
            open[depth++] = s;
        else
            pair_slots(sp, s, open[--depth]);
    }
}

/* Pair the 2k slots of one edge (slots[0 .. n)) by angle: each u -> v slot with the one
 * just before it in the turn, which runs v -> u wherever the directions alternate.
 * Returns false, with nothing paired, if they do not (see pair_reordered). */
static bool pair_by_angle(splitter *sp, uint32_t *slots, size_t n)
{
    const mcsg_mesh *m = sp->m;
    uint32_t u = slot_from(m, slots[0]), v = slot_to(m, slots[0]);
    sort_by_angle(sp, slots, n);
    for (size_t i = 0; i < n; i++)
        if (slot_from(m, slots[i]) == u && slot_from(m, slots[(i + n - 1) % n]) != v)
            return false;
    for (size_t i = 0; i < n; i++)
        if (slot_from(m, slots[i]) == u)
            pair_slots(sp, slots[i], slots[(i + n - 1) % n]);
    return true;
}

/* One stable counting sort of corners by their edge's target vertex (by_target) or by
 * their own vertex: in[] (NULL: all corners in order) into out[], with start[v] the first
 * position of key v. */
static void sort_corners_by(const mcsg_mesh *m, bool by_target, const uint32_t *in,
                            uint32_t *out, uint32_t *start)
{
    size_t n = 3 * m->triangle_count;
    memset(start, 0, (m->vertex_count + 2) * sizeof *start);
    for (size_t c = 0; c < n; c++)
        start[(by_target ? slot_to(m, (uint32_t)c) : slot_from(m, (uint32_t)c)) + 2]++;
    for (size_t v = 2; v < m->vertex_count + 2; v++)
        start[v] += start[v - 1];
    for (size_t k = 0; k < n; k++) {
        uint32_t c = in ? in[k] : (uint32_t)k;
        out[start[(by_target ? slot_to(m, c) : slot_from(m, c)) + 1]++] = c;
    }
}

/* Corners (3t + i) grouped by vertex in CSR form, each vertex's corners ordered by the
 * vertex their edge goes to. Corner 3t + i is also the edge slot leaving its vertex, so
 * this lists each vertex's outgoing edges, and the edges u -> v form one run: a fan
 * centre with a thousand edges costs a binary search, not a scan per edge. Two stable
 * counting sorts: by edge target, then by vertex. */
static bool corners_by_vertex(splitter *sp)
{
    const mcsg_mesh *m = sp->m;
    size_t n = 3 * m->triangle_count;
    uint32_t *start = mci_calloc_array(sp->ctx, m->vertex_count + 2, sizeof *start);
    uint32_t *corner = mci_malloc_array(sp->ctx, n + 1, sizeof *corner);
    uint32_t *by_target = mci_malloc_array(sp->ctx, n + 1, sizeof *by_target);
    sp->start = start;
    sp->corner = corner;
    if (start && corner && by_target) {
        sort_corners_by(m, true, NULL, by_target, start);
        sort_corners_by(m, false, by_target, corner, start);
    }
    mci_free(sp->ctx, by_target);
    return start && corner && by_target;
}

/* The run of vertex u's corners whose edge goes to v (u's corners are ordered by the
 * vertex their edge goes to: a binary search). Returns the run's start; *count is its
 * length. */
static uint32_t run_to(const splitter *sp, uint32_t u, uint32_t v, size_t *count)
{
    uint32_t lo = sp->start[u], hi = sp->start[u + 1], first;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (slot_to(sp->m, sp->corner[mid]) < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    first = lo;
    while (lo < sp->start[u + 1] && slot_to(sp->m, sp->corner[lo]) == v)
        lo++;
    *count = lo - first;
    return first;
}

/* Whether the pairs of an edge u-v (from[k]: u -> v, paired) get vertex copies that
 * separate them: each pair's umbrellas at u and at v differ from every other pair's. */
static bool pairs_separate(const splitter *sp, const uint32_t *from, size_t pairs)
{
    uint32_t at_u[32], at_v[32];
    for (size_t k = 0; k < pairs; k++) {
        at_u[k] = mci_find_root(sp->parent, from[k]);
        at_v[k] = mci_find_root(sp->parent, next_in_triangle(from[k]));
        for (size_t j = 0; j < k; j++)
            if (at_u[j] == at_u[k] && at_v[j] == at_v[k])
                return false;
    }
    return true;
}

static size_t position(const uint32_t *slots, uint32_t s)
{
    size_t i = 0;
    while (slots[i] != s)
        i++;
    return i;
}

/* Whether two of the pairs (from[k], to[k]) cross as chords of the angle order about the
 * edge (slots, sorted by sort_by_angle). */
static bool pairs_cross(const uint32_t *slots, const uint32_t *from, const uint32_t *to,
                        size_t pairs)
{
    size_t lo[32], hi[32];
    for (size_t k = 0; k < pairs; k++) {
        size_t a = position(slots, from[k]), b = position(slots, to[k]);
        lo[k] = a < b ? a : b;
        hi[k] = a < b ? b : a;
        for (size_t j = 0; j < k; j++)
            if ((lo[j] < lo[k] && lo[k] < hi[j] && hi[j] < hi[k]) ||
                (lo[k] < lo[j] && lo[j] < hi[k] && hi[k] < hi[j]))
                return true;
    }
    return false;
}

/* Parts touching along an edge whose ends each have a single umbrella are not separated
 * by vertex copies (and rounding can bring such an edge about). Where the turn pairing
 * about u or v differs from the pairs and, in the angle order, pairs neighbours as well
 * (no two of its pairs cross; with four triangles, it is the other pairing of adjacent
 * ones), it takes their place. Returns whether it did. The slots are those of edge u-v,
 * paired, with slots[0 .. pairs) running u -> v. */
static bool separate_pairs(splitter *sp, uint32_t *slots, size_t n, uint32_t u, uint32_t v)
{
    uint32_t from[32], to[32], ends[2] = {u, v};
    if (pairs_separate(sp, slots, n / 2))
        return false;
    for (int e = 0; e < 2; e++) {
        size_t pairs = pairs_by_turns(sp, slots, n, ends[e], from, to), same = 0;
        for (size_t k = 0; k < pairs; k++)
            same += sp->mate[from[k]] == to[k];
        if (pairs == 0 || same == pairs)
            continue;
        sort_by_angle(sp, slots, n);
        if (pairs_cross(slots, from, to, pairs))
            continue;
        for (size_t k = 0; k < pairs; k++)
            pair_slots(sp, from[k], to[k]);
        return true;
    }
    return false;
}

/* How the slots of a non-manifold edge are paired: by angle (the first pass, on the
 * threads), or, for the edges that pass left (reordered by rounding), by turns, or by
 * turns or else brackets; SEPARATING revisits the paired edges (separate_pairs). */
typedef enum pairing { BY_ANGLE, BY_TURNS, BY_TURNS_OR_BRACKETS, SEPARATING } pairing;

/* Pair the slots of the edges u-v with u < v: the two opposite ones of a manifold edge
 * directly, the 2k of a non-manifold edge as `how` says. u's corners come in runs u -> v;
 * the run v -> u is found by a binary search among v's. Returns the number of edges that
 * BY_ANGLE left or the others paired. */
static size_t pair_at_vertex(splitter *sp, size_t chunk, uint32_t u, pairing how)
{
    const mcsg_mesh *m = sp->m;
    uint32_t slots[64];
    size_t counted = 0;
    for (uint32_t k = sp->start[u]; k < sp->start[u + 1];) {
        uint32_t v = slot_to(m, sp->corner[k]), back_first;
        size_t ahead = 1, back;
        while (k + ahead < sp->start[u + 1] && slot_to(m, sp->corner[k + ahead]) == v)
            ahead++;
        k += (uint32_t)ahead;
        if (v < u)
            continue;
        back_first = run_to(sp, v, u, &back);
        if (ahead == 1 && back == 1) {
            if (how == BY_ANGLE)
                pair_slots(sp, sp->corner[k - 1], sp->corner[back_first]);
            continue;
        }
        if (ahead != back || ahead + back > sizeof slots / sizeof slots[0]) {
            sp->bad_edges[chunk] += how == BY_ANGLE;
            continue;
        }
        if ((how == BY_TURNS || how == BY_TURNS_OR_BRACKETS) &&
            sp->mate[sp->corner[k - 1]] != MCI_NONE)
            continue;
        memcpy(slots, sp->corner + k - ahead, ahead * sizeof *slots);
        memcpy(slots + ahead, sp->corner + back_first, back * sizeof *slots);
        if (how == SEPARATING)
            counted += separate_pairs(sp, slots, ahead + back, u, v);
        else if (how == BY_ANGLE) {
            counted += !pair_by_angle(sp, slots, ahead + back);
            sp->shared_edges[chunk]++;
        }
        else if (pair_by_turns(sp, slots, ahead + back, u) ||
                 pair_by_turns(sp, slots, ahead + back, v))
            counted++;
        else if (how == BY_TURNS_OR_BRACKETS) {
            pair_by_brackets(sp, slots, ahead + back);
            counted++;
        }
    }
    return counted;
}

static mcsg_status pair_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    splitter *sp = user;
    size_t chunk = begin / VERTEX_CHUNK;
    (void)err;
    for (uint32_t u = (uint32_t)begin; u < end; u++)
        sp->reordered_edges[chunk] += pair_at_vertex(sp, chunk, u, BY_ANGLE);
    return MCSG_OK;
}

/* Rounding can reorder nearly coplanar triangles around an edge, or, where it joined
 * vertices, bring in triangles of another edge, so that the directions no longer
 * alternate. Such an edge is paired so that copies of one of its ends can separate the
 * pairs (pair_by_turns), which needs the other edges on the turns paired first: passes
 * in vertex order (the same for any thread count) until one pairs nothing, then one that
 * pairs what is left by brackets. */
static void pair_reordered(splitter *sp)
{
    size_t left = 0;
    for (size_t c = 0; c < sp->chunks; c++)
        left += sp->reordered_edges[c];
    pairing how = BY_TURNS;
    while (left > 0) {
        size_t paired = 0;
        for (uint32_t u = 0; u < sp->m->vertex_count; u++)
            paired += pair_at_vertex(sp, 0, u, how);
        left -= paired;
        if (how == BY_TURNS_OR_BRACKETS)
            break;
        if (paired == 0)
            how = BY_TURNS_OR_BRACKETS;
    }
}

static bool pair_edges(splitter *sp)
{
    for (size_t s = 0; s < 3 * sp->m->triangle_count; s++)
        sp->mate[s] = MCI_NONE;
    if (mci_parallel_for_ranges(sp->ctx, sp->m->vertex_count, VERTEX_CHUNK, pair_chunk, sp,
                                NULL) != MCSG_OK)
        return false;
    pair_reordered(sp);
    return true;
}

/* The corner of the triangle holding slot s (paired with an edge at vertex x) at x. */
static uint32_t corner_at(const mcsg_mesh *m, uint32_t s, uint32_t x)
{
    uint32_t t = s - s % 3;
    for (uint32_t i = 0; i < 3; i++)
        if (m->triangles[t + i] == x)
            return t + i;
    return MCI_NONE;
}

/* Union the corners of one vertex across its edges; parent is indexed by corner. */
static void group_corners(const splitter *sp, const uint32_t *corners, size_t n,
                          uint32_t *parent)
{
    const mcsg_mesh *m = sp->m;
    for (size_t k = 0; k < n; k++) {
        uint32_t c = corners[k], x = m->triangles[c];
        uint32_t at_x[2] = {c, c - c % 3 + (c % 3 + 2) % 3}; /* x -> next, prev -> x */
        for (int e = 0; e < 2; e++) {
            uint32_t other = sp->mate[at_x[e]], d;
            if (other == MCI_NONE || (d = corner_at(m, other, x)) == MCI_NONE)
                continue;
            d = mci_find_root(parent, d);
            c = mci_find_root(parent, c);
            if (c != d)
                parent[c > d ? c : d] = c < d ? c : d;
        }
    }
}

/* Group the chunk's corners and count the umbrellas beyond each vertex's first (copy[]
 * marks the roots seen). */
/* Whether the n corners of vertex v (corners[0 .. n)) form one umbrella: turning about v
 * from the first corner (across each corner's incoming edge w -> v to its pair, the slot
 * v -> w, which is the corner at v of the triangle across) comes back to it after n steps.
 * Then all of them get the first as their root, without the union-find. */
static bool one_umbrella(const splitter *sp, const uint32_t *corners, size_t n)
{
    uint32_t c = corners[0];
    for (size_t steps = 1; steps <= n; steps++) {
        c = sp->mate[prev_in_triangle(c)];
        if (c == MCI_NONE)
            return false;
        if (c == corners[0]) {
            if (steps != n)
                return false;
            for (size_t k = 0; k < n; k++)
                sp->parent[corners[k]] = corners[0];
            return true;
        }
    }
    return false;
}

static mcsg_status group_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    splitter *sp = user;
    const uint32_t *start = sp->start, *corner = sp->corner;
    size_t chunk = begin / VERTEX_CHUNK, extra = 0;
    (void)err;
    for (size_t v = begin; v < end; v++) {
        uint32_t first_root;
        if (start[v] == start[v + 1] ||
            one_umbrella(sp, corner + start[v], start[v + 1] - start[v]))
            continue;
        group_corners(sp, corner + start[v], start[v + 1] - start[v], sp->parent);
        first_root = mci_find_root(sp->parent, corner[start[v]]);
        for (uint32_t k = start[v]; k < start[v + 1]; k++) {
            uint32_t root = mci_find_root(sp->parent, corner[k]);
            if (root != first_root && sp->copy[root] == MCI_NONE) {
                sp->copy[root] = 0;
                extra++;
            }
        }
    }
    sp->extra[chunk] = extra;
    return MCSG_OK;
}

/* Give the chunk's extra umbrellas their vertices, numbered from extra[chunk] on in vertex
 * and corner order, with the coordinates of the vertex they copy. */
static mcsg_status number_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    splitter *sp = user;
    mcsg_mesh *m = sp->m;
    const uint32_t *start = sp->start, *corner = sp->corner;
    size_t next = sp->extra[begin / VERTEX_CHUNK];
    (void)err;
    for (size_t v = begin; v < end; v++) {
        uint32_t first_root = start[v] < start[v + 1] ? mci_find_root(sp->parent, corner[start[v]]) : 0;
        for (uint32_t k = start[v]; k < start[v + 1]; k++) {
            uint32_t c = corner[k], root = mci_find_root(sp->parent, c);
            if (root == first_root)
                continue;
            if (sp->copy[root] == 0) {
                sp->copy[root] = (uint32_t)next++;
                memcpy(m->vertices + 3 * (size_t)sp->copy[root], m->vertices + 3 * v,
                       3 * sizeof(double));
            }
            m->triangles[c] = sp->copy[root];
        }
    }
    return MCSG_OK;
}

/* Umbrellas of every vertex (parent), and the number beyond the first per chunk (extra). */
static void group(splitter *sp)
{
    for (size_t c = 0; c < 3 * sp->m->triangle_count; c++)
        sp->parent[c] = (uint32_t)c, sp->copy[c] = MCI_NONE;
    mci_parallel_for_ranges(sp->ctx, sp->m->vertex_count, VERTEX_CHUNK, group_chunk, sp, NULL);
}

/* Once grouped: the edges with over two triangles that vertex copies would not separate
 * are paired again where that helps (separate_pairs), serially in vertex order; returns
 * whether any was (then the caller groups again). Every edge is judged on the first
 * grouping's umbrellas, and turns read the pairs as they are at that point. */
static bool separate_shared_edges(splitter *sp)
{
    size_t shared = 0;
    for (size_t c = 0; c < sp->chunks; c++)
        shared += sp->shared_edges[c];
    if (shared == 0)
        return false;
    for (uint32_t u = 0; u < sp->m->vertex_count; u++)
        sp->separated_edges += pair_at_vertex(sp, 0, u, SEPARATING);
    return sp->separated_edges > 0;
}

/* New vertices for every umbrella of a vertex but the one with its first corner. */
static bool split_vertices(splitter *sp, size_t *added)
{
    mcsg_mesh *m = sp->m;
    size_t n = 3 * m->triangle_count, nv = m->vertex_count, extra = 0;
    double *grown;
    sp->parent = mci_malloc_array(sp->ctx, n + 1, sizeof *sp->parent);
    sp->copy = mci_malloc_array(sp->ctx, n + 1, sizeof *sp->copy);
    sp->extra = mci_malloc_array(sp->ctx, sp->chunks + 1, sizeof *sp->extra);
    *added = 0;
    if (!sp->parent || !sp->copy || !sp->extra)
        return false;
    group(sp);
    if (separate_shared_edges(sp))
        group(sp);
    for (size_t c = 0; c < sp->chunks; c++) {
        size_t count = sp->extra[c];
        sp->extra[c] = nv + extra;
        extra += count;
    }
    if (extra == 0)
        return true;
    if (nv + extra >= UINT32_MAX ||
        !(grown = mci_realloc_array(sp->ctx, m->vertices, nv + extra, 3 * sizeof(double))))
        return false;
    m->vertices = grown;
    mci_parallel_for_ranges(sp->ctx, sp->m->vertex_count, VERTEX_CHUNK, number_chunk, sp, NULL);
    m->vertex_count = nv + extra;
    *added = extra;
    return true;
}

bool mci_split_touching(const mci_ctx *ctx, mcsg_mesh *m, mci_touching_split *result)
{
    splitter sp;
    bool ok;
    memset(&sp, 0, sizeof sp);
    memset(result, 0, sizeof *result);
    if (m->triangle_count == 0)
        return true;
    sp.ctx = ctx;
    sp.m = m;
    sp.chunks = (m->vertex_count + VERTEX_CHUNK - 1) / VERTEX_CHUNK;
    sp.mate = mci_malloc_array(ctx, 3 * m->triangle_count + 1, sizeof *sp.mate);
    sp.bad_edges = mci_calloc_array(ctx, sp.chunks + 1, sizeof *sp.bad_edges);
    sp.reordered_edges = mci_calloc_array(ctx, sp.chunks + 1, sizeof *sp.reordered_edges);
    sp.shared_edges = mci_calloc_array(ctx, sp.chunks + 1, sizeof *sp.shared_edges);
    ok = sp.mate && sp.bad_edges && sp.reordered_edges && sp.shared_edges &&
         corners_by_vertex(&sp) &&
         pair_edges(&sp) &&
         split_vertices(&sp, &result->new_vertices);
    for (size_t c = 0; sp.bad_edges && sp.reordered_edges && c < sp.chunks; c++) {
        result->unpaired_edges += sp.bad_edges[c];
        result->reordered_edges += sp.reordered_edges[c];
    }
    result->separated_edges = sp.separated_edges;
    mci_free(ctx, sp.mate);
    mci_free(ctx, sp.bad_edges);
    mci_free(ctx, sp.reordered_edges);
    mci_free(ctx, sp.shared_edges);
    mci_free(ctx, sp.start);
    mci_free(ctx, sp.corner);
    mci_free(ctx, sp.parent);
    mci_free(ctx, sp.copy);
    mci_free(ctx, sp.extra);
    return ok;
}
