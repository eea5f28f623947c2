/*
 * Repair of triangles that rounding flattened, turned over or folded. The exact result
 * has no zero-area triangle, but a thin one (a vertex within an ulp of the opposite edge)
 * can round to three collinear points. Its middle vertex m then lies, exactly in doubles,
 * on the segment p-q of its long edge; the triangle on the other side of that edge,
 * (p, q, X), is split at m into (p, m, X) and (m, q, X), which replace the flat triangle
 * and that neighbour. The mesh stays closed and consistently oriented, the triangle count
 * does not change, and both new triangles lie in the neighbour's plane with the
 * neighbour's orientation, so they are not flat unless the neighbour was. Where the
 * neighbour is flat as well, with its middle corner X also on p-q (a sliver of zero
 * width), both go and the two sides are zipped: the triangle next to each across the
 * segment that holds the other's middle corner is split there, the halves taking the
 * two flat triangles' slots. Other flat triangles are left as they are and counted.
 *
 * The same split mends a thin triangle whose corner m rounding moved across the opposite
 * edge p-q: the triangle then turns the other way than its exact original (seen along
 * its face's normal; "turned"), or lies in its neighbour's plane on the neighbour's side
 * of the edge, covering part of it twice ("folded", found without the exact result).
 * This is what snap rounding does to an edge that passes within the rounding distance
 * of a vertex: the edge p-q is routed through m, the thin triangle collapses, and the
 * neighbour is split at m. The split is made only where m lies strictly inside the
 * neighbour (both halves turn as it does), so the halves cover exactly the neighbour
 * less the thin triangle's part of it. Every test is an exact predicate on the rounded
 * doubles; only the choice of which triangles to test (thin ones: a corner within 64
 * units of the opposite edge, where rounding moves each by half a unit) is a
 * floating-point bound.
 */
#include "csg/rounding_repair.h"
#include "base/sort.h"
#include "exact/kernel.h"
#include "exact/predicates.h"

#include <math.h>

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

/* A triangle's mark: FOLDED + i for a fold at corner i (folded_at). */
enum { GOOD = 0, FLAT = 1, TURNED = 2, FOLDED = 3 };

static uint64_t directed_key(uint32_t u, uint32_t v)
{
    return (uint64_t)u << 32 | v;
}

/* Where the neighbours of the suspect triangles are: every triangle holding a directed
 * edge opposite to one of theirs, as (edge key, triangle), sorted by key. The wanted
 * keys are few, so each edge of the mesh is tested against a bitmap of them first: no
 * sort of the whole mesh's edges. */
typedef struct edge_index {
    mci_keyed *edges;
    size_t count, room;
} edge_index;

/* The wanted keys, sorted, and a bitmap of their hashes with about 16 bits per key, so
 * that few of the mesh's other edges reach the binary search however many are wanted. */
typedef struct wanted_keys {
    mci_keyed *keys;
    size_t count;
    uint64_t *bits;
    int log_bits;
} wanted_keys;

/* From 512 bytes to 8 MiB: beyond that, more keys only mean more false hits. */
enum { MIN_WANTED_LOG_BITS = 12, MAX_WANTED_LOG_BITS = 26 };

static uint32_t wanted_bit(const wanted_keys *w, uint64_t key)
{
    return (uint32_t)((key * 0x9E3779B97F4A7C15u) >> (64 - w->log_bits));
}

static void want(wanted_keys *w, uint64_t key)
{
    uint32_t b = wanted_bit(w, key);
    w->keys[w->count++] = (mci_keyed){key, 0};
    w->bits[b / 64] |= (uint64_t)1 << (b % 64);
}

static bool is_wanted(const wanted_keys *w, uint64_t key)
{
    uint32_t b = wanted_bit(w, key);
    size_t i;
    if (!(w->bits[b / 64] >> (b % 64) & 1))
        return false;
    i = mci_find_key(w->keys, w->count, key);
    return i < w->count && w->keys[i].key == key;
}

static bool wanted_init(const mci_ctx *ctx, size_t room, wanted_keys *w)
{
    w->count = 0;
    w->log_bits = MIN_WANTED_LOG_BITS;
    while (w->log_bits < MAX_WANTED_LOG_BITS && ((size_t)1 << w->log_bits) < 16 * room)
        w->log_bits++;
    w->keys = mci_malloc_array(ctx, room + 1, sizeof *w->keys);
    w->bits = mci_calloc_array(ctx, ((size_t)1 << w->log_bits) / 64, sizeof *w->bits);
    return w->keys && w->bits;
}

static bool push_edge(const mci_ctx *ctx, edge_index *x, uint64_t key, uint32_t t)
{
    if (x->count == x->room) {
        size_t room = 2 * x->room + 16;
        mci_keyed *grown = mci_realloc_array(ctx, x->edges, room, sizeof *grown);
        if (!grown)
            return false;
        x->edges = grown;
        x->room = room;
    }
    x->edges[x->count++] = (mci_keyed){key, t};
    return true;
}

static bool index_neighbour_edges(const mci_ctx *ctx, const uint32_t *tris, size_t nt,
                                  const uint32_t *suspect, size_t ns, edge_index *out)
{
    wanted_keys w;
    bool ok = wanted_init(ctx, 3 * ns, &w);
    memset(out, 0, sizeof *out);
    for (size_t k = 0; ok && k < ns; k++)
        for (int i = 0; i < 3; i++) {
            const uint32_t *T = tris + 3 * (size_t)suspect[k];
            want(&w, directed_key(T[(i + 1) % 3], T[i]));
        }
    if (ok)
        mci_sort_keyed(w.keys, w.count);
    for (size_t t = 0; ok && t < nt; t++)
        for (int i = 0; ok && i < 3; i++) {
            uint64_t key = directed_key(tris[3 * t + i], tris[3 * t + (i + 1) % 3]);
            if (is_wanted(&w, key))
                ok = push_edge(ctx, out, key, (uint32_t)t);
        }
    if (ok)
        mci_sort_keyed(out->edges, out->count);
    mci_free(ctx, w.keys);
    mci_free(ctx, w.bits);
    return ok;
}

/* The untouched triangle holding directed edge u->v, not flat, or MCI_NONE. (A turned
 * one may take a flat neighbour's middle corner: it may not be mended itself.) */
static uint32_t neighbour_with_edge(const mci_keyed *edges, size_t n, uint32_t u, uint32_t v,
                                    const unsigned char *touched, const unsigned char *mark)
{
    uint64_t key = directed_key(u, v);
    for (size_t i = mci_find_key(edges, n, key); i < n && edges[i].key == key; i++)
        if (!touched[edges[i].ref] && mark[edges[i].ref] != FLAT)
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

/* The rounded triangle's turn projected along axis (+1 counter-clockwise). */
static int projected_turn(const double *xyz, const uint32_t *t, int axis)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    const double *a = at(xyz, t[0]), *b = at(xyz, t[1]), *c = at(xyz, t[2]);
    return mci_orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

/* Whether the triangle turns the other way than its exact original. */
static bool is_turned(const double *xyz, const uint32_t *t, uint32_t tag,
                      const mci_expected_turns *turns)
{
    int axis, sign = turns->turn(turns->user, tag, &axis);
    return sign != 0 && projected_turn(xyz, t, axis) == -sign;
}

/* Sign of (p - m) . (q - m) in the projection along axis, exactly: with R the quarter
 * turn (x, y) -> (-y, x), it is the cross product (q - m) x (R p - R m). */
static int projected_dot_sign(const double *m, const double *p, const double *q, int axis)
{
    int i = (axis + 1) % 3, j = (axis + 2) % 3;
    double m2[2] = {m[i], m[j]}, q2[2] = {q[i], q[j]};
    double rm[2] = {-m[j], m[i]}, rp[2] = {-p[j], p[i]};
    return mci_cross2_diff_sign(m2, q2, rm, rp);
}

/* The corner of a turned-over triangle whose angle is obtuse (the corner that rounding
 * moved across the opposite edge), or -1 when none is (not a thin triangle). */
static int obtuse_corner(const double *xyz, const uint32_t *t, int axis)
{
    for (int i = 0; i < 3; i++)
        if (projected_dot_sign(at(xyz, t[i]), at(xyz, t[(i + 2) % 3]), at(xyz, t[(i + 1) % 3]),
                               axis) < 0)
            return i;
    return -1;
}

/* Whether some corner of the triangle lies within 64 units in the last place (of its
 * largest coordinate, bounded above by the corners' length) of the line through the
 * other two: only such a triangle can be flat, or turned over or folded by rounding,
 * which moves each coordinate by half a unit at most. A generous floating-point bound
 * that only selects which triangles the exact tests look at. */
static bool is_thin(const double *xyz, const uint32_t *t)
{
    const double *a = at(xyz, t[0]), *b = at(xyz, t[1]), *c = at(xyz, t[2]);
    double u[3], v[3], cross2 = 0, lu = 0, lv = 0, lw = 0, size2 = 0;
    for (int k = 0; k < 3; k++) {
        double w = c[k] - b[k];
        u[k] = b[k] - a[k], v[k] = c[k] - a[k];
        lu += u[k] * u[k], lv += v[k] * v[k], lw += w * w;
        size2 += a[k] * a[k] + b[k] * b[k] + c[k] * c[k];
    }
    for (int k = 0; k < 3; k++) {
        double n = u[(k + 1) % 3] * v[(k + 2) % 3] - u[(k + 2) % 3] * v[(k + 1) % 3];
        cross2 += n * n;
    }
    /* The lowest corner is the one across the longest edge: height |u x v| / length;
     * (64 units)^2 = 2^-92 size^2. */
    return cross2 <= 0x1p-92 * size2 * fmax(lu, fmax(lv, lw));
}

int mci_triangle_turn(const double *a, const double *b, const double *c, int *axis)
{
    double n[3];
    int i, j;
    for (int k = 0; k < 3; k++) {
        i = (k + 1) % 3, j = (k + 2) % 3;
        n[k] = fabs((b[i] - a[i]) * (c[j] - a[j]) - (b[j] - a[j]) * (c[i] - a[i]));
    }
    *axis = n[0] >= n[1] && n[0] >= n[2] ? 0 : n[1] >= n[2] ? 1 : 2;
    i = (*axis + 1) % 3, j = (*axis + 2) % 3;
    return mci_orient2d(a[i], a[j], b[i], b[j], c[i], c[j]);
}

/* Triangle t's rounded turn along the axis its normal is largest on. */
static int own_turn(const double *xyz, const uint32_t *t, int *axis)
{
    return mci_triangle_turn(at(xyz, t[0]), at(xyz, t[1]), at(xyz, t[2]), axis);
}

/* The first triangle holding directed edge u->v, or MCI_NONE. */
static uint32_t triangle_with_edge(const mci_keyed *edges, size_t n, uint32_t u, uint32_t v)
{
    uint64_t key = directed_key(u, v);
    size_t i = mci_find_key(edges, n, key);
    return i < n && edges[i].key == key ? edges[i].ref : MCI_NONE;
}

/* Whether corner i of triangle T and the neighbour N across the edge opposite it are
 * folded onto each other: the same plane, and N's third corner on the same side of the
 * shared edge as T's corner i (so that the two turn opposite ways). */
static bool folded_at(const double *xyz, const uint32_t *tris, const edge_index *x,
                      const uint32_t *T, int i)
{
    uint32_t m = T[i], q = T[(i + 1) % 3], p = T[(i + 2) % 3];
    uint32_t n = triangle_with_edge(x->edges, x->count, p, q);
    const uint32_t *N;
    mci_plane plane;
    int turn, axis;
    if (n == MCI_NONE)
        return false;
    N = tris + 3 * (size_t)n;
    mci_plane_init(&plane, at(xyz, N[0]), at(xyz, N[1]), at(xyz, N[2]));
    if (mci_orient3d_vertex(at(xyz, m), &plane) != 0)
        return false;
    turn = own_turn(xyz, N, &axis);
    return turn != 0 && projected_turn(xyz, T, axis) == -turn;
}

/* What is wrong with suspect triangle t (flat or thin), if anything: GOOD, FLAT, TURNED
 * or FOLDED + corner. */
static unsigned char triangle_mark(const double *xyz, const uint32_t *tris,
                                   const uint32_t *source, const edge_index *x, size_t t,
                                   const mci_expected_turns *turns)
{
    const uint32_t *T = tris + 3 * t;
    if (is_flat(xyz, T))
        return FLAT;
    if (turns && is_turned(xyz, T, source[t], turns))
        return TURNED;
    for (int i = 0; i < 3; i++)
        if (folded_at(xyz, tris, x, T, i))
            return (unsigned char)(FOLDED + i);
    return GOOD;
}

/* The corner to split the neighbour at, for a marked triangle; -1 for none. */
static int split_corner(const double *xyz, const uint32_t *t, unsigned char mark, uint32_t tag,
                        const mci_expected_turns *turns)
{
    int axis;
    if (mark == FLAT)
        return middle_corner(xyz, t);
    if (mark >= FOLDED)
        return mark - FOLDED;
    return turns->turn(turns->user, tag, &axis) != 0 ? obtuse_corner(xyz, t, axis) : -1;
}

/* Whether both halves a and b of neighbour N, split for a turned or folded triangle,
 * turn as N should: as in the exact result (turned), or as N itself does (folded). Then
 * the moved corner lies inside N. */
static bool halves_turn_right(const double *xyz, const uint32_t *a, const uint32_t *b,
                              const uint32_t *N, uint32_t tag, unsigned char mark,
                              const mci_expected_turns *turns)
{
    int axis;
    int sign = mark == TURNED ? turns->turn(turns->user, tag, &axis) : own_turn(xyz, N, &axis);
    return sign != 0 && projected_turn(xyz, a, axis) == sign &&
           projected_turn(xyz, b, axis) == sign;
}

/* Whether a triangle holds directed edge u->v and has `third` as its third corner: the
 * opposite twin of a new half with edge v->u (a fold can close up that way). */
static bool has_twin(const uint32_t *tris, const edge_index *x, uint32_t u, uint32_t v,
                     uint32_t third)
{
    uint64_t key = directed_key(u, v);
    for (size_t i = mci_find_key(x->edges, x->count, key); i < x->count && x->edges[i].key == key;
         i++)
        if (third_corner(tris + 3 * (size_t)x->edges[i].ref, u, v) == third)
            return true;
    return false;
}

/* What a pass reads and writes. */
typedef struct pass_state {
    const double *xyz;
    uint32_t *tris, *source;
    const edge_index *x;
    unsigned char *touched;
    const unsigned char *mark;
    const mci_expected_turns *turns;
    uint32_t *changed; /* the triangles changed, nchanged of them */
    size_t nchanged, turned;
    bool twins;
} pass_state;

static void note_changed(pass_state *ps, uint32_t t)
{
    ps->touched[t] = 1;
    ps->changed[ps->nchanged++] = t;
}

/* The untouched, not flat triangle holding directed edge u->v, with its third corner
 * strictly off the line (it splits into two triangles of nonzero area), or MCI_NONE. */
static uint32_t splittable_with_edge(const pass_state *ps, uint32_t u, uint32_t v)
{
    return neighbour_with_edge(ps->x->edges, ps->x->count, u, v, ps->touched, ps->mark);
}

/* Split triangle n, which holds directed edge u->w, at z (strictly inside segment u-w)
 * into (u, z, Y) in place and (z, w, Y) in slot `into`. */
static void split_at(pass_state *ps, uint32_t n, uint32_t u, uint32_t w, uint32_t z, uint32_t into)
{
    uint32_t *N = ps->tris + 3 * (size_t)n, Y = third_corner(N, u, w);
    const uint32_t a[3] = {u, z, Y}, b[3] = {z, w, Y};
    ps->twins = ps->twins || has_twin(ps->tris, ps->x, z, u, Y) ||
                has_twin(ps->tris, ps->x, w, z, Y);
    memcpy(N, a, sizeof a);
    memcpy(ps->tris + 3 * (size_t)into, b, sizeof b);
    if (ps->source)
        ps->source[into] = ps->source[n];
}

/* Flat triangle t, with middle corner m between p and q, whose neighbour n across
 * its long edge (holding p->q) is flat too, with middle corner X: the two are a sliver
 * of zero width along p-q. Both go, and the two sides are zipped: where m and X lie in
 * the order p, m, X, q, t's neighbour across m->q is split at X and n's across X->p at
 * m (p, X, m, q: t's across p->m at X, n's across q->X at m), the new halves taking t's
 * and n's slots. Returns 2 when done, 0 when a triangle to split is flat or taken. */
static size_t zip_flat_pair(pass_state *ps, uint32_t t, uint32_t p, uint32_t q, uint32_t m)
{
    const double *P = at(ps->xyz, p), *Q = at(ps->xyz, q);
    uint32_t n = MCI_NONE, X, s1, s2;
    bool m_first;
    for (size_t i = mci_find_key(ps->x->edges, ps->x->count, directed_key(p, q));
         n == MCI_NONE && i < ps->x->count && ps->x->edges[i].key == directed_key(p, q); i++)
        if (!ps->touched[ps->x->edges[i].ref] && ps->mark[ps->x->edges[i].ref] == FLAT)
            n = ps->x->edges[i].ref;
    if (n == MCI_NONE)
        return 0;
    X = third_corner(ps->tris + 3 * (size_t)n, p, q);
    if (X == m || ps->tris[3 * (size_t)n + middle_corner(ps->xyz, ps->tris + 3 * (size_t)n)] != X)
        return 0;
    m_first = lex_less(at(ps->xyz, m), at(ps->xyz, X)) == lex_less(P, Q);
    s1 = m_first ? splittable_with_edge(ps, q, m) : splittable_with_edge(ps, m, p);
    s2 = m_first ? splittable_with_edge(ps, p, X) : splittable_with_edge(ps, X, q);
    if (s1 == MCI_NONE || s2 == MCI_NONE || s1 == s2)
        return 0;
    if (m_first) {
        split_at(ps, s1, q, m, X, t);
        split_at(ps, s2, p, X, m, n);
    } else {
        split_at(ps, s1, m, p, X, t);
        split_at(ps, s2, X, q, m, n);
    }
    note_changed(ps, t);
    note_changed(ps, n);
    note_changed(ps, s1);
    note_changed(ps, s2);
    return 2;
}

/* Mend suspect t if it is marked: split its neighbour at the moved corner (or zip it with
 * a flat neighbour). Returns how many triangles went. */
static size_t mend_one(pass_state *ps, uint32_t t)
{
    uint32_t *T = ps->tris + 3 * (size_t)t, *N, p, q, m, n, third, a[3], b[3];
    unsigned char mark = ps->mark[t];
    int i;
    if (mark == GOOD || ps->touched[t])
        return 0;
    i = split_corner(ps->xyz, T, mark, ps->source ? ps->source[t] : 0, ps->turns);
    if (i < 0)
        return 0;
    m = T[i];
    q = T[(i + 1) % 3];
    p = T[(i + 2) % 3];
    n = splittable_with_edge(ps, p, q);
    if (n == MCI_NONE)
        return mark == FLAT ? zip_flat_pair(ps, t, p, q, m) : 0;
    N = ps->tris + 3 * (size_t)n;
    third = third_corner(N, p, q);
    a[0] = p, a[1] = m, a[2] = third;
    b[0] = m, b[1] = q, b[2] = third;
    if (mark != FLAT && !halves_turn_right(ps->xyz, a, b, N, ps->source ? ps->source[n] : 0,
                                           mark, ps->turns))
        return 0;
    ps->twins = ps->twins || has_twin(ps->tris, ps->x, m, p, third) ||
                has_twin(ps->tris, ps->x, q, m, third);
    memcpy(T, a, sizeof a);
    memcpy(N, b, sizeof b);
    if (ps->source)
        ps->source[t] = ps->source[n];
    note_changed(ps, t);
    note_changed(ps, n);
    ps->turned += mark != FLAT;
    return 1;
}

/* The triangles under watch: every thin one, and among those the suspects, which the
 * next pass marks. A mark depends only on the triangle and the triangles holding its
 * edges, so it can change only where a triangle changed: the suspects are the thin
 * triangles that share a corner with a changed one, or whose mark was not GOOD but
 * could not be mended. Marking only those keeps the passes' cost with the changes, not
 * with the number of thin triangles, which is large on meshes full of slivers. */
typedef struct watch {
    uint32_t *thin, *suspect, *changed;
    size_t nthin, nsuspect, nchanged;
    unsigned char *dirty; /* per vertex: a corner of a changed triangle */
} watch;

static void set_corners(const uint32_t *tris, const uint32_t *list, size_t n,
                        unsigned char *flags, unsigned char value)
{
    for (size_t k = 0; k < n; k++)
        for (int i = 0; i < 3; i++)
            flags[tris[3 * (size_t)list[k] + i]] = value;
}

static bool near_change(const uint32_t *t, const unsigned char *dirty)
{
    return dirty[t[0]] || dirty[t[1]] || dirty[t[2]];
}

/* After a pass that changed w->changed: the triangles still thin, the changed ones that
 * became thin, and the next suspects: those near a change, and those to retry (marked
 * but not mended). listed[] and retry[] are zero on return. */
static void next_suspects(const double *xyz, const uint32_t *tris, watch *w,
                          unsigned char *retry, unsigned char *listed)
{
    size_t kept = 0;
    for (size_t k = 0; k < w->nthin; k++)
        if (is_thin(xyz, tris + 3 * (size_t)w->thin[k])) {
            listed[w->thin[k]] = 1;
            w->thin[kept++] = w->thin[k];
        }
    w->nthin = kept;
    for (size_t k = 0; k < w->nchanged; k++)
        if (!listed[w->changed[k]] && is_thin(xyz, tris + 3 * (size_t)w->changed[k])) {
            listed[w->changed[k]] = 1;
            w->thin[w->nthin++] = w->changed[k];
        }
    set_corners(tris, w->changed, w->nchanged, w->dirty, 1);
    w->nsuspect = 0;
    for (size_t k = 0; k < w->nthin; k++) {
        uint32_t t = w->thin[k];
        if (retry[t] || near_change(tris + 3 * (size_t)t, w->dirty))
            w->suspect[w->nsuspect++] = t;
        listed[t] = retry[t] = 0;
    }
    set_corners(tris, w->changed, w->nchanged, w->dirty, 0);
}

/* One pass: the suspects' neighbour edges, marks, splits; then the next suspects.
 * *fixed: how many triangles were removed. marks: three zeroed arrays of nt flags. */
static bool one_pass(const mci_ctx *ctx, const double *xyz, uint32_t *tris, uint32_t *source,
                     size_t nt, const mci_expected_turns *turns, unsigned char *marks,
                     watch *w, mci_flat_repair *result, size_t *fixed)
{
    unsigned char *mark = marks, *touched = marks + nt, *retry = marks + 2 * nt;
    edge_index x = {NULL, 0, 0};
    bool ok = index_neighbour_edges(ctx, tris, nt, w->suspect, w->nsuspect, &x);
    pass_state ps = {xyz, tris, source, &x, touched, mark, turns, w->changed, 0, 0, false};
    *fixed = 0;
    if (ok) {
        for (size_t k = 0; k < w->nsuspect; k++)
            mark[w->suspect[k]] = triangle_mark(xyz, tris, source, &x, w->suspect[k], turns);
        for (size_t k = 0; k < w->nsuspect; k++)
            *fixed += mend_one(&ps, w->suspect[k]);
        w->nchanged = ps.nchanged;
        result->turned += ps.turned;
        result->twins = result->twins || ps.twins;
        result->split += *fixed;
        for (size_t k = 0; k < w->nsuspect; k++) {
            uint32_t t = w->suspect[k];
            retry[t] = mark[t] != GOOD && !touched[t];
            mark[t] = GOOD;
        }
        for (size_t k = 0; k < w->nchanged; k++)
            touched[w->changed[k]] = 0;
        next_suspects(xyz, tris, w, retry, touched);
    }
    mci_free(ctx, x.edges);
    return ok;
}

static uint32_t vertex_count(const uint32_t *tris, size_t nt)
{
    uint32_t n = 0;
    for (size_t k = 0; k < 3 * nt; k++)
        n = tris[k] >= n ? tris[k] + 1 : n;
    return n;
}

static void free_watch(const mci_ctx *ctx, watch *w)
{
    mci_free(ctx, w->thin);
    mci_free(ctx, w->suspect);
    mci_free(ctx, w->changed);
    mci_free(ctx, w->dirty);
}

bool mci_split_flat_triangles(const mci_ctx *ctx, const double *xyz, uint32_t *tris,
                              uint32_t *source, size_t nt, const mci_expected_turns *turns,
                              mci_flat_repair *result)
{
    unsigned char *marks = mci_calloc_array(ctx, 3 * nt + 1, 1);
    watch w = {mci_malloc_array(ctx, nt + 1, sizeof(uint32_t)),
               mci_malloc_array(ctx, nt + 1, sizeof(uint32_t)),
               mci_malloc_array(ctx, nt + 1, sizeof(uint32_t)),
               0, 0, 0,
               mci_calloc_array(ctx, (size_t)vertex_count(tris, nt) + 1, 1)};
    bool ok = marks && w.thin && w.suspect && w.changed && w.dirty;
    size_t fixed = 1;
    memset(result, 0, sizeof *result);
    if (!source)
        turns = NULL;
    for (size_t t = 0; ok && t < nt; t++)
        if (is_thin(xyz, tris + 3 * t))
            w.thin[w.nthin++] = w.suspect[w.nsuspect++] = (uint32_t)t;
    /* Each pass fixes every marked triangle whose neighbour is free; chains of flat
     * triangles along one line need a few passes. */
    for (int pass = 0; ok && w.nsuspect > 0 && fixed > 0 && pass < 16; pass++)
        ok = one_pass(ctx, xyz, tris, source, nt, turns, marks, &w, result, &fixed);
    for (size_t k = 0; ok && k < w.nthin; k++)
        result->remaining += is_flat(xyz, tris + 3 * (size_t)w.thin[k]);
    result->split -= result->turned;
    mci_free(ctx, marks);
    free_watch(ctx, &w);
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
