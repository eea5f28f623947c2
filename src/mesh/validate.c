/*
 * Mesh validation: the checks behind `meshcsg check` and mcsg_mesh_check.
 *
 * Vertices with identical coordinates are identified first (so an unwelded but
 * geometrically closed mesh is judged by its geometry), then every triangle contributes
 * three directed edges that are sorted by their undirected key (grouped by the smaller
 * vertex, then ordered by the larger): an edge used once is a boundary, more than twice
 * non-manifold, twice in the same direction inconsistent.
 * Degeneracy and the sign of the volume are decided with exact predicates (exact/predicates.h).
 */
#include "mesh/validate.h"
#include "mesh/edge_fan.h"
#include "base/sort.h"
#include "exact/kernel.h"
#include "exact/predicates.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <string.h>

typedef struct edge_use {
    uint64_t key;  /* (min vertex << 32) | max vertex, canonical ids */
    uint32_t tri;  /* triangle using the edge */
    unsigned forward : 1; /* 1 if the triangle runs from min to max */
    unsigned corner : 2;  /* the edge runs from the triangle's corner `corner` to the next */
} edge_use;

typedef struct check_state {
    const mci_ctx *ctx;
    const mcsg_mesh *mesh;
    mcsg_check_report *report;
    uint32_t *canon;    /* canonical vertex id per vertex */
    uint8_t *tri_ok;    /* triangle has valid indices */
    uint32_t *parent;   /* union-find over triangles */
    mci_edge_mates *mates; /* optional output: pairs by angle where a shell meets itself */
    size_t mates_room;
    uint32_t *twin;     /* optional output: per half-edge, the other use of a manifold edge */
} check_state;

static uint64_t hash_mix(uint64_t h)
{
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    return h ^ (h >> 33);
}

static uint64_t coordinate_bits(double x)
{
    uint64_t bits;
    if (x == 0)
        x = 0; /* -0.0 and +0.0 are the same point */
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

static uint64_t hash_point(const double *p)
{
    uint64_t h = hash_mix(coordinate_bits(p[0]));
    h = hash_mix(h ^ coordinate_bits(p[1]));
    return hash_mix(h ^ coordinate_bits(p[2]));
}

static bool same_point(const double *p, const double *q)
{
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

static bool point_is_finite(const double *p)
{
    return isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
}

static size_t table_size_for(size_t n)
{
    size_t size = 16;
    while (size < 2 * n)
        size *= 2;
    return size;
}

/* canon[v] = first vertex with the same coordinates; non-finite vertices stay alone. */
static bool identify_vertices(check_state *s)
{
    const mcsg_mesh *m = s->mesh;
    size_t size = table_size_for(m->vertex_count);
    uint32_t *table = mci_malloc_array(s->ctx, size, sizeof *table);
    if (!table)
        return false;
    memset(table, 0xff, size * sizeof *table);
    for (size_t v = 0; v < m->vertex_count; v++) {
        const double *p = m->vertices + 3 * v;
        size_t slot;
        s->canon[v] = (uint32_t)v;
        if (!point_is_finite(p)) {
            s->report->nonfinite_vertices++;
            if (s->report->example_nonfinite_vertex == MCSG_NO_INDEX)
                s->report->example_nonfinite_vertex = (uint32_t)v;
            continue;
        }
        for (slot = hash_point(p) & (size - 1); table[slot] != UINT32_MAX;
             slot = (slot + 1) & (size - 1)) {
            if (same_point(m->vertices + 3 * (size_t)table[slot], p))
                break;
        }
        if (table[slot] == UINT32_MAX) {
            table[slot] = (uint32_t)v;
        } else {
            s->canon[v] = table[slot];
            s->report->duplicate_vertices++;
        }
    }
    mci_free(s->ctx, table);
    return true;
}

static void check_indices(check_state *s)
{
    const mcsg_mesh *m = s->mesh;
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        size_t bad = (tri[0] >= m->vertex_count) + (tri[1] >= m->vertex_count) +
                     (tri[2] >= m->vertex_count);
        s->tri_ok[t] = bad == 0;
        s->report->out_of_range_indices += bad;
        if (bad && s->report->example_out_of_range_triangle == MCSG_NO_INDEX)
            s->report->example_out_of_range_triangle = (uint32_t)t;
    }
}

static const double *corner(const check_state *s, size_t t, int k)
{
    return s->mesh->vertices + 3 * (size_t)s->mesh->triangles[3 * t + (size_t)k];
}

static void check_degenerate(check_state *s)
{
    for (size_t t = 0; t < s->mesh->triangle_count; t++) {
        const double *a, *b, *c;
        if (!s->tri_ok[t])
            continue;
        a = corner(s, t, 0);
        b = corner(s, t, 1);
        c = corner(s, t, 2);
        if (!point_is_finite(a) || !point_is_finite(b) || !point_is_finite(c))
            continue;
        if (mci_triangle_is_degenerate(a, b, c)) {
            s->report->degenerate_triangles++;
            if (s->report->example_degenerate_triangle == MCSG_NO_INDEX)
                s->report->example_degenerate_triangle = (uint32_t)t;
        }
    }
}

static void sorted_triple(const check_state *s, size_t t, uint32_t out[3])
{
    uint32_t a = s->canon[s->mesh->triangles[3 * t]];
    uint32_t b = s->canon[s->mesh->triangles[3 * t + 1]];
    uint32_t c = s->canon[s->mesh->triangles[3 * t + 2]], swap;
    if (a > b) { swap = a; a = b; b = swap; }
    if (b > c) { swap = b; b = c; c = swap; }
    if (a > b) { swap = a; a = b; b = swap; }
    out[0] = a;
    out[1] = b;
    out[2] = c;
}

/* A triangle duplicates an earlier one when both use the same three (canonical)
 * vertices, in either orientation. */
static bool check_duplicates(check_state *s)
{
    size_t n = s->mesh->triangle_count, size = table_size_for(n);
    uint32_t *table = mci_malloc_array(s->ctx, size, sizeof *table);
    if (!table)
        return false;
    memset(table, 0xff, size * sizeof *table);
    for (size_t t = 0; t < n; t++) {
        uint32_t key[3], other[3];
        size_t slot;
        if (!s->tri_ok[t])
            continue;
        sorted_triple(s, t, key);
        slot = hash_mix(((uint64_t)key[0] << 32 | key[1]) ^ hash_mix(key[2])) & (size - 1);
        for (; table[slot] != UINT32_MAX; slot = (slot + 1) & (size - 1)) {
            sorted_triple(s, table[slot], other);
            if (memcmp(key, other, sizeof key) == 0)
                break;
        }
        if (table[slot] == UINT32_MAX) {
            table[slot] = (uint32_t)t;
        } else {
            s->report->duplicate_triangles++;
            if (s->report->example_duplicate_triangle == MCSG_NO_INDEX)
                s->report->example_duplicate_triangle = (uint32_t)t;
        }
    }
    mci_free(s->ctx, table);
    return true;
}

/* One vertex's edge uses (equal smaller vertex) stably by key: insertion sort for the
 * usual handful, the keyed sort with the position as tie-break for a fan's centre. */
static bool sort_vertex_run(const mci_ctx *ctx, edge_use *run, size_t n)
{
    mci_keyed *order;
    edge_use *copy;
    if (n <= 32) {
        for (size_t i = 1; i < n; i++) {
            edge_use x = run[i];
            size_t j = i;
            for (; j > 0 && run[j - 1].key > x.key; j--)
                run[j] = run[j - 1];
            run[j] = x;
        }
        return true;
    }
    order = mci_malloc_array(ctx, n, sizeof *order);
    copy = mci_malloc_array(ctx, n, sizeof *copy);
    if (order && copy) {
        for (size_t i = 0; i < n; i++) {
            order[i].key = run[i].key;
            order[i].ref = (uint32_t)i;
        }
        mci_sort_keyed(order, n);
        for (size_t i = 0; i < n; i++)
            copy[i] = run[order[i].ref];
        memcpy(run, copy, n * sizeof *run);
    }
    mci_free(ctx, order);
    mci_free(ctx, copy);
    return order && copy;
}

/* Edge uses stably by key into `out`: a counting sort by the smaller vertex (canonical
 * ids are below vertex_count), then each vertex's few uses by the larger one. A 16-bit
 * radix sort took four passes over the uses plus a copy back after each (much of the
 * check of a large model). */
static bool sort_edges(const check_state *s, const edge_use *in, size_t n, edge_use *out)
{
    size_t nv = s->mesh->vertex_count;
    uint32_t *start = mci_calloc_array(s->ctx, nv + 2, sizeof *start);
    bool ok = start != NULL;
    for (size_t i = 0; ok && i < n; i++)
        start[(in[i].key >> 32) + 2]++;
    for (size_t v = 2; ok && v < nv + 2; v++)
        start[v] += start[v - 1];
    for (size_t i = 0; ok && i < n; i++)
        out[start[(in[i].key >> 32) + 1]++] = in[i];
    for (size_t v = 0; ok && v < nv; v++)
        ok = sort_vertex_run(s->ctx, out + start[v], start[v + 1] - start[v]);
    mci_free(s->ctx, start);
    return ok;
}

static void unite(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = mci_find_root(parent, a);
    b = mci_find_root(parent, b);
    if (a != b)
        parent[a < b ? b : a] = a < b ? a : b;
}

static size_t collect_edges(const check_state *s, edge_use *edges)
{
    size_t n = 0;
    for (size_t t = 0; t < s->mesh->triangle_count; t++) {
        if (!s->tri_ok[t])
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = s->canon[s->mesh->triangles[3 * t + (size_t)k]];
            uint32_t b = s->canon[s->mesh->triangles[3 * t + (size_t)(k + 1) % 3]];
            if (a == b)
                continue; /* a collapsed edge of a degenerate triangle */
            edges[n].key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
            edges[n].tri = (uint32_t)t;
            edges[n].forward = a < b;
            edges[n].corner = (unsigned)k;
            n++;
        }
    }
    return n;
}

static void note_edge(uint32_t example[2], size_t *counter, uint64_t key)
{
    (*counter)++;
    if (example[0] == MCSG_NO_INDEX) {
        example[0] = (uint32_t)(key >> 32);
        example[1] = (uint32_t)key;
    }
}

/* The k-th use of the edge in direction `forward`, or n. */
static size_t kth_use(const edge_use *group, size_t n, uint32_t forward, size_t k)
{
    for (size_t i = 0; i < n; i++)
        if (group[i].forward == forward && k-- == 0)
            return i;
    return n;
}

/* The corner of use e's triangle off the edge (canonical coordinates), or NULL for a
 * triangle with a repeated corner. */
static const double *third_corner(const check_state *s, const edge_use *e)
{
    for (size_t k = 0; k < 3; k++) {
        uint32_t v = s->canon[s->mesh->triangles[3 * (size_t)e->tri + k]];
        if (v != (uint32_t)(e->key >> 32) && v != (uint32_t)e->key)
            return s->mesh->vertices + 3 * (size_t)v;
    }
    return NULL;
}

/* Pairs the uses of a balanced edge of more than two triangles by angle about the edge,
 * from its smaller to its larger vertex (mci_pair_fan_by_angle, as csg/manifold_split.c
 * pairs the output's): mate[i] is i's partner (positions in group). 0 when they cannot
 * be paired (or a triangle has no third corner); 2 when directions do not alternate
 * around the edge, else 1. */
static int pair_by_angle(const check_state *s, const edge_use *group, size_t n,
                         uint8_t *mate)
{
    const double *third[MCI_FAN_MAX];
    uint8_t forward[MCI_FAN_MAX];
    mci_edge_fan fan = {s->mesh->vertices + 3 * (size_t)(group[0].key >> 32),
                        s->mesh->vertices + 3 * (size_t)(uint32_t)group[0].key, third,
                        forward, n};
    if (n > MCI_FAN_MAX)
        return 0;
    for (size_t i = 0; i < n; i++) {
        forward[i] = group[i].forward;
        if (!(third[i] = third_corner(s, &group[i])))
            return 0;
    }
    return mci_pair_fan_by_angle(&fan, mate);
}

/* Joins the triangles of one edge into shells: both of a manifold edge; at a balanced
 * edge of more than two, the k-th use each way (any pairing closes every shell up as a
 * chain; this one keeps a file's parts, listed one after another, apart); all of an
 * unbalanced one. */
static void join_shells(check_state *s, const edge_use *group, size_t n, size_t forward)
{
    if (n == 2) { /* nearly every edge */
        unite(s->parent, group[0].tri, group[1].tri);
        if (s->twin && forward == 1) {
            s->twin[3 * (size_t)group[0].tri + group[0].corner] =
                3 * group[1].tri + group[1].corner;
            s->twin[3 * (size_t)group[1].tri + group[1].corner] =
                3 * group[0].tri + group[0].corner;
        }
        return;
    }
    for (size_t i = 1; i < n && 2 * forward != n; i++)
        unite(s->parent, group[0].tri, group[i].tri);
    for (size_t k = 0; 2 * forward == n && k < forward; k++)
        unite(s->parent, group[kth_use(group, n, 1, k)].tri, group[kth_use(group, n, 0, k)].tri);
}

static void classify_edge_group(check_state *s, const edge_use *group, size_t n)
{
    mcsg_check_report *r = s->report;
    size_t forward = 0;
    for (size_t i = 0; i < n; i++)
        forward += group[i].forward;
    join_shells(s, group, n, forward);
    if (n == 1)
        note_edge(r->example_boundary_edge, &r->boundary_edges, group[0].key);
    else if (n > 2)
        note_edge(r->example_nonmanifold_edge, &r->nonmanifold_edges, group[0].key);
    else if (forward != 1)
        note_edge(r->example_inconsistent_edge, &r->inconsistent_edges, group[0].key);
    if (n > 2 && 2 * forward != n)
        note_edge(r->example_unbalanced_edge, &r->unbalanced_edges, group[0].key);
}

/* Lists the pairs of one edge's uses, both ways (t << 32 | u), in s->mates. */
static bool add_mates(check_state *s, const edge_use *group, size_t n, const uint8_t *mate)
{
    mci_edge_mates *m = s->mates;
    if (m->count + n > s->mates_room) {
        size_t room = 2 * s->mates_room + n + 16;
        uint64_t *grown = mci_realloc_array(s->ctx, m->pairs, room, sizeof *grown);
        if (!grown)
            return false;
        m->pairs = grown;
        s->mates_room = room;
    }
    for (size_t i = 0; i < n; i++)
        m->pairs[m->count++] = (uint64_t)group[i].tri << 32 | group[mate[i]].tri;
    return true;
}

/* The uses of the edge in the shell of group[i] (more than two: it meets itself). */
static size_t uses_in_shell(const check_state *s, const edge_use *group, size_t n, size_t i,
                            edge_use *out)
{
    uint32_t root = mci_find_root(s->parent, group[i].tri);
    size_t m = 0;
    for (size_t j = 0; j < n && m < MCI_FAN_MAX; j++)
        if (mci_find_root(s->parent, group[j].tri) == root)
            out[m++] = group[j];
    return m;
}

/* After the shells are joined: a balanced edge of more than two triangles where a shell
 * has more than two uses. That shell's uses are paired by angle (pair_by_angle, the
 * other shells' left out) and listed in s->mates; where they cannot be (more than
 * MCI_FAN_MAX of them), the edge is counted as not supported. */
static bool check_self_touching(check_state *s, const edge_use *group, size_t n)
{
    edge_use mine[MCI_FAN_MAX];
    uint8_t mate[MCI_FAN_MAX];
    bool done[MCI_FAN_MAX] = {false};
    int paired;
    if (n <= 2)
        return true;
    for (size_t i = 0; i < n; i++) {
        size_t m;
        if (i < MCI_FAN_MAX && done[i])
            continue;
        m = uses_in_shell(s, group, n, i, mine);
        for (size_t j = i; j < n && j < MCI_FAN_MAX; j++)
            done[j] |= mci_find_root(s->parent, group[j].tri) ==
                       mci_find_root(s->parent, group[i].tri);
        if (m <= 2)
            continue;
        paired = n > MCI_FAN_MAX ? 0 : pair_by_angle(s, mine, m, mate);
        if (!paired) {
            note_edge(s->report->example_self_touching_edge, &s->report->self_touching_edges,
                      group[0].key);
            return true;
        }
        if (s->mates && !add_mates(s, mine, m, mate))
            return false;
        if (s->mates && paired == 2)
            s->mates->entering_edges++;
    }
    return true;
}

static bool check_edges(check_state *s)
{
    size_t n, start = 0;
    edge_use *edges = mci_malloc_array(s->ctx, s->mesh->triangle_count, 3 * sizeof *edges);
    edge_use *sorted = mci_malloc_array(s->ctx, s->mesh->triangle_count, 3 * sizeof *sorted);
    bool ok = edges && sorted;
    n = ok ? collect_edges(s, edges) : 0;
    ok = ok && sort_edges(s, edges, n, sorted);
    mci_free(s->ctx, edges);
    for (size_t i = 1; ok && i <= n; i++) {
        if (i == n || sorted[i].key != sorted[start].key) {
            classify_edge_group(s, sorted + start, i - start);
            start = i;
        }
    }
    start = 0;
    for (size_t i = 1; ok && s->report->nonmanifold_edges && i <= n; i++) {
        if (i == n || sorted[i].key != sorted[start].key) {
            ok = check_self_touching(s, sorted + start, i - start);
            start = i;
        }
    }
    mci_free(s->ctx, sorted);
    return ok;
}

static bool count_components_and_unused(check_state *s)
{
    const mcsg_mesh *m = s->mesh;
    uint8_t *used = mci_calloc_array(s->ctx, m->vertex_count, 1);
    if (!used && m->vertex_count)
        return false;
    for (size_t t = 0; t < m->triangle_count; t++) {
        if (!s->tri_ok[t])
            continue;
        if (mci_find_root(s->parent, (uint32_t)t) == t)
            s->report->components++;
        for (int k = 0; k < 3; k++)
            used[m->triangles[3 * t + (size_t)k]] = 1;
    }
    for (size_t v = 0; v < m->vertex_count; v++)
        s->report->unused_vertices += !used[v];
    mci_free(s->ctx, used);
    return true;
}

/* Triangle `which[k]` (k itself when which is NULL) of the list. */
static const uint32_t *listed_triangle(const uint32_t *tris, const uint32_t *which, size_t k)
{
    return tris + 3 * (size_t)(which ? which[k] : k);
}

/* Exact sign of the sum of det(a, b, c) over the triangles: every coordinate becomes an
 * integer at the triangles' smallest lsb exponent, and the sum is kept exactly. */
static int exact_volume_sign(const double *xyz, const uint32_t *tris, const uint32_t *which,
                             size_t n)
{
    int e0 = INT_MAX;
    mci_big sum = {0}, det;
    for (size_t k = 0; k < n; k++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                int e = mci_lsb_exponent(xyz[3 * (size_t)listed_triangle(tris, which, k)[i] + j]);
                e0 = e < e0 ? e : e0;
            }
    if (e0 == INT_MAX)
        return 0;
    for (size_t k = 0; k < n; k++) {
        const uint32_t *t = listed_triangle(tris, which, k);
        mci_det3_big(&det, xyz + 3 * (size_t)t[0], xyz + 3 * (size_t)t[1],
                     xyz + 3 * (size_t)t[2], e0);
        mci_big_add(&sum, &sum, &det);
    }
    return mci_big_sign(&sum);
}

void mci_volume_sum_add(mci_volume_sum *v, const double *a, const double *b, const double *c)
{
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, l = (i + 2) % 3;
        double p = b[j] * c[l], q = b[l] * c[j];
        v->sum += a[i] * (p - q);
        v->magnitude += fabs(a[i]) * (fabs(p) + fabs(q));
        v->amplified_underflow += fabs(a[i]);
    }
    v->triangles++;
}

/* The bound: each determinant has relative error <= 5 eps of its magnitude sum, and
 * summing n terms adds at most (n-1) eps of the running magnitude; as in mci_det3_sign,
 * plus the underflow of the products amplified by |a_i|. */
int mci_volume_sum_sign(const mci_volume_sum *v)
{
    double bound = (double)(v->triangles * 3 + 16) * (DBL_EPSILON / 2) * v->magnitude * 1.01 +
                   v->amplified_underflow * 0x1p-1072;
    if (isfinite(bound) && v->magnitude >= 0x1p-960 && fabs(v->sum) > bound)
        return v->sum > 0 ? 1 : -1;
    return 0;
}

int mci_triangles_volume_sign(const double *xyz, const uint32_t *tris, const uint32_t *which,
                              size_t n, double *volume)
{
    mci_volume_sum v = {0, 0, 0, 0};
    int sign;
    for (size_t k = 0; k < n; k++) {
        const uint32_t *t = listed_triangle(tris, which, k);
        mci_volume_sum_add(&v, xyz + 3 * (size_t)t[0], xyz + 3 * (size_t)t[1],
                           xyz + 3 * (size_t)t[2]);
    }
    if (volume)
        *volume = v.sum / 6;
    sign = mci_volume_sum_sign(&v);
    return sign != 0 ? sign : exact_volume_sign(xyz, tris, which, n);
}

static void compute_volume(check_state *s)
{
    const mcsg_mesh *m = s->mesh;
    int sign = mci_triangles_volume_sign(m->vertices, m->triangles, NULL, m->triangle_count,
                                         &s->report->volume);
    s->report->inverted = sign < 0;
    s->report->volume_sign = sign;
}

static void report_init(mcsg_check_report *r, const mcsg_mesh *m)
{
    memset(r, 0, sizeof *r);
    r->vertex_count = m->vertex_count;
    r->triangle_count = m->triangle_count;
    r->example_out_of_range_triangle = MCSG_NO_INDEX;
    r->example_nonfinite_vertex = MCSG_NO_INDEX;
    r->example_degenerate_triangle = MCSG_NO_INDEX;
    r->example_duplicate_triangle = MCSG_NO_INDEX;
    r->example_boundary_edge[0] = r->example_boundary_edge[1] = MCSG_NO_INDEX;
    r->example_nonmanifold_edge[0] = r->example_nonmanifold_edge[1] = MCSG_NO_INDEX;
    r->example_inconsistent_edge[0] = r->example_inconsistent_edge[1] = MCSG_NO_INDEX;
    r->example_unbalanced_edge[0] = r->example_unbalanced_edge[1] = MCSG_NO_INDEX;
    r->example_self_touching_edge[0] = r->example_self_touching_edge[1] = MCSG_NO_INDEX;
}

static bool run_checks(check_state *s)
{
    mcsg_check_report *r = s->report;
    check_indices(s);
    if (!identify_vertices(s))
        return false;
    check_degenerate(s);
    if (!check_duplicates(s) || !check_edges(s) || !count_components_and_unused(s))
        return false;
    /* The volume (and so the orientation) means something only for meshes closed as a
     * chain with finite coordinates. */
    if (!r->out_of_range_indices && !r->nonfinite_vertices && !r->boundary_edges &&
        !r->unbalanced_edges && !r->inconsistent_edges)
        compute_volume(s);
    return true;
}

mcsg_status mcsg_mesh_check(const mcsg_mesh *mesh, const mcsg_options *opts,
                            mcsg_check_report *report, mcsg_error *err)
{
    mci_ctx ctx;
    if (!mesh || !report || (mesh->vertex_count && !mesh->vertices) ||
        (mesh->triangle_count && !mesh->triangles))
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_check: NULL argument");
    if (mesh->vertex_count > UINT32_MAX || mesh->triangle_count > UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "mesh too large to check");
    mci_ctx_init(&ctx, opts);
    return mci_mesh_check(&ctx, mesh, report, err);
}

mcsg_status mci_mesh_check(const mci_ctx *ctx, const mcsg_mesh *mesh,
                           mcsg_check_report *report, mcsg_error *err)
{
    return mci_mesh_check_shells(ctx, mesh, report, NULL, NULL, NULL, err);
}

/* shell[t] from the union-find roots: dense numbers in order of first triangles. */
static void number_shells(const check_state *s, uint32_t *shell)
{
    uint32_t next = 0;
    for (size_t t = 0; t < s->mesh->triangle_count; t++)
        shell[t] = UINT32_MAX;
    for (size_t t = 0; t < s->mesh->triangle_count; t++) {
        uint32_t root;
        if (!s->tri_ok[t])
            continue;
        root = mci_find_root(s->parent, (uint32_t)t);
        if (shell[root] == UINT32_MAX)
            shell[root] = next++;
        shell[t] = shell[root];
    }
}

mcsg_status mci_mesh_check_shells(const mci_ctx *ctx_in, const mcsg_mesh *mesh,
                                  mcsg_check_report *report, uint32_t *shell,
                                  uint32_t *twin, mci_edge_mates *mates, mcsg_error *err)
{
    const mci_ctx ctx = *ctx_in;
    check_state s;
    bool ok;
    report_init(report, mesh);
    memset(&s, 0, sizeof s);
    s.ctx = &ctx;
    s.mesh = mesh;
    s.report = report;
    s.mates = mates;
    s.twin = twin;
    for (size_t h = 0; twin && h < 3 * mesh->triangle_count; h++)
        twin[h] = MCI_NONE;
    if (mates)
        memset(mates, 0, sizeof *mates);
    s.canon = mci_malloc_array(&ctx, mesh->vertex_count, sizeof *s.canon);
    s.tri_ok = mci_malloc_array(&ctx, mesh->triangle_count, 1);
    s.parent = mci_malloc_array(&ctx, mesh->triangle_count, sizeof *s.parent);
    ok = s.canon && s.tri_ok && s.parent;
    for (size_t t = 0; ok && t < mesh->triangle_count; t++)
        s.parent[t] = (uint32_t)t;
    ok = ok && run_checks(&s);
    if (ok && shell && report->components > 1)
        number_shells(&s, shell);
    if (ok && mates)
        mci_sort_u64(mates->pairs, mates->count);
    mci_free(&ctx, s.canon);
    mci_free(&ctx, s.tri_ok);
    mci_free(&ctx, s.parent);
    if (!ok) {
        if (mates)
            mci_edge_mates_free(&ctx, mates);
        report_init(report, mesh);
        return mci_fail_nomem(err, "checking a mesh");
    }
    return MCSG_OK;
}

void mci_edge_mates_free(const mci_ctx *ctx, mci_edge_mates *mates)
{
    mci_free(ctx, mates->pairs);
    mates->pairs = NULL;
    mates->count = 0;
    mates->entering_edges = 0;
}

bool mci_edge_mates_has(const mci_edge_mates *mates, uint32_t t, uint32_t u)
{
    uint64_t key = (uint64_t)t << 32 | u;
    size_t lo = 0, hi = mates ? mates->count : 0;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (mates->pairs[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < (mates ? mates->count : 0) && mates->pairs[lo] == key;
}

int mcsg_check_report_is_valid(const mcsg_check_report *r)
{
    return r->out_of_range_indices == 0 && r->nonfinite_vertices == 0 &&
           r->degenerate_triangles == 0 && r->duplicate_triangles == 0 &&
           r->boundary_edges == 0 && r->nonmanifold_edges == 0 &&
           r->inconsistent_edges == 0 && r->triangle_count > 0;
}
