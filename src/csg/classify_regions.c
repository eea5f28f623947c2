/*
 * One leaf's pieces and regions (paper §5.2, intra-primitive groups): the pieces are the
 * sub-triangles of its arranged faces and its untouched faces whole; each directed piece
 * edge is paired with the one across it; edges lying on another leaf's surface
 * (separators) and the borders of faces dropped whole (walls) stop the grouping, and
 * the regions are the pieces joined across all other edges.
 */
#include "csg/classify_leaf.h"
#include "csg/triangulate.h"
#include "mesh/edge_fan.h"

#include <stdlib.h>
#include <string.h>

static mcsg_status make_pieces(mci_leaf_work *w)
{
    const mci_scene *s = w->s;
    const mcsg_mesh *m = s->octree.leaves[w->leaf];
    const uint32_t *vid = w->cl->vertex_id + w->cl->vertex_first[w->leaf];
    size_t np = 0, at = 0;
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++)
        np += mci_scene_arr_of_face(s, f) ? mci_scene_arr_of_face(s, f)->tri_count : 1;
    if (np >= UINT32_MAX / 3)
        return mci_fail(w->err, MCSG_ERR_LIMIT, "too many pieces in one leaf (%zu)", np);
    w->np = np;
    w->pv = mci_malloc_array(w->ctx, 3 * np + 1, sizeof *w->pv);
    w->plocal = mci_malloc_array(w->ctx, 3 * np + 1, sizeof *w->plocal);
    w->pface = mci_malloc_array(w->ctx, np + 1, sizeof *w->pface);
    if (!w->pv || !w->plocal || !w->pface)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++) {
        const mci_face_arr *arr = mci_scene_arr_of_face(s, f);
        if (!arr) {
            const uint32_t *t = m->triangles + 3 * (size_t)(f - w->face_base);
            for (int i = 0; i < 3; i++) {
                w->pv[3 * at + i] = vid[t[i]];
                w->plocal[3 * at + i] = t[i];
            }
            w->pface[at++] = f;
            continue;
        }
        for (size_t k = 0; k < arr->tri_count; k++, at++) {
            const uint32_t *gid = s->gid + s->gid_start[s->arr_of[f]];
            for (int i = 0; i < 3; i++) {
                w->plocal[3 * at + i] = arr->tris[3 * k + i];
                w->pv[3 * at + i] = gid[arr->tris[3 * k + i]];
            }
            w->pface[at] = f;
        }
    }
    return MCSG_OK;
}

/* Sides inside an arranged face are paired by its triangulation (adj: the side across
 * and whether it is a constraint, i.e. an elementary edge, i.e. a separator); returns
 * the number of sides left to pair by sorting (those on face boundaries), with mate
 * MCI_NONE. Most sides of a cut face are inside it, so the sort shrinks to the faces'
 * borders. */
static size_t pair_inside_faces(mci_leaf_work *w)
{
    size_t left = 0, p = 0;
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++) {
        const mci_face_arr *arr = mci_scene_arr_of_face(w->s, f);
        if (!arr) {
            for (int i = 0; i < 3; i++)
                w->mate[3 * p + i] = MCI_NONE;
            left += 3;
            p++;
            continue;
        }
        for (size_t k = 0; k < 3 * arr->tri_count; k++) {
            uint32_t across = arr->adj[k];
            size_t slot = 3 * p + k;
            if (across == MCI_NONE) {
                w->mate[slot] = MCI_NONE;
                left++;
                continue;
            }
            w->mate[slot] = (uint32_t)(3 * p) + (across & ~MCI_CDT_CONSTRAINT);
            w->is_sep[slot] = (across & MCI_CDT_CONSTRAINT) != 0;
        }
        p += arr->tri_count;
    }
    return left;
}

/* Whether the arrangement of face f was dropped whole (no pieces). */
static bool dropped_whole(const mci_scene *s, uint32_t f)
{
    return s->arr_dropped && s->arr_of[f] != MCI_NONE && s->arr_dropped[s->arr_of[f]];
}

/* Appends the keys of the sides along edge e of arrangement arr (global ids gid): its
 * points on that edge in order from corner e to corner e + 1. After a merge the points
 * past the corners are in lexicographic order, which on a line is the order along it. */
static void add_edge_sides(const mci_face_arr *arr, const uint32_t *gid, int e, mci_keyed *out,
                           size_t *n)
{
    int a = e, b = (e + 1) % 3;
    bool ascending = mci_compare_lex(arr->points[a], arr->points[b]) < 0;
    uint32_t prev = (uint32_t)a;
    for (size_t k = 3; k < arr->point_count; k++) {
        size_t i = ascending ? k : arr->point_count + 2 - k;
        if (arr->where[i] != MCI_AT_EDGE + e)
            continue;
        out[(*n)++] = (mci_keyed){mci_edge_key(gid[prev], gid[i]), 0};
        prev = (uint32_t)i;
    }
    out[(*n)++] = (mci_keyed){mci_edge_key(gid[prev], gid[b]), 0};
}

/* The global point ids of arrangement arr. */
static const uint32_t *arr_gids(const mci_scene *s, const mci_face_arr *arr)
{
    return s->gid + s->gid_start[arr - s->arrs];
}

/* Where the sides along edge e of face f, dropped whole, are listed: the edge of the
 * arranged neighbour across that has pieces (its points on the edge are the ones its
 * pieces end at; the dropped face has its corners only), else f's own edge (one side:
 * the neighbour is untouched, a whole triangle, or dropped too). */
static const mci_face_arr *wall_edge(const mci_scene *s, uint32_t f, int e, int *edge)
{
    const mci_face_arr *arr = mci_scene_arr_of_face(s, f), *across;
    const uint32_t *gid = arr_gids(s, arr);
    uint32_t nb = s->neighbour[3 * (size_t)f + (size_t)e];
    uint64_t key = mci_edge_key(gid[e], gid[(e + 1) % 3]);
    *edge = e;
    if (nb == MCI_NONE || !(across = mci_scene_arr_of_face(s, nb)) || dropped_whole(s, nb))
        return arr;
    for (int i = 0; i < 3; i++) {
        const uint32_t *g = arr_gids(s, across);
        if (mci_edge_key(g[i], g[(i + 1) % 3]) == key) {
            *edge = i;
            return across;
        }
    }
    return arr;
}

/* Pieces next to a face dropped whole have no piece across their side there: those
 * sides are walls (no region crosses them), known by their keys. */
static mcsg_status collect_walls(mci_leaf_work *w)
{
    const mci_scene *s = w->s;
    size_t n = 0;
    int edge;
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++)
        for (int e = 0; dropped_whole(s, f) && e < 3; e++)
            n += wall_edge(s, f, e, &edge)->point_count + 1;
    if (n == 0)
        return MCSG_OK;
    w->walls = mci_malloc_array(w->ctx, n, sizeof *w->walls);
    if (!w->walls)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++)
        for (int e = 0; dropped_whole(s, f) && e < 3; e++) {
            const mci_face_arr *arr = wall_edge(s, f, e, &edge);
            add_edge_sides(arr, arr_gids(s, arr), edge, w->walls, &w->nwalls);
        }
    mci_sort_keyed(w->walls, w->nwalls);
    return MCSG_OK;
}

/* A side with no opposite piece: a wall (marked as a separator without a mate) when it
 * borders a face dropped whole, else the leaf does not close up. */
static bool is_wall(mci_leaf_work *w, size_t slot, uint64_t key)
{
    if (mci_find_key(w->walls, w->nwalls, key) == w->nwalls)
        return false;
    w->is_sep[slot] = 1;
    return true;
}

/* Pairing by vertex, when the leaf's vertex ids are dense (a model's own vertices,
 * numbered together; sorting millions of edge keys took most of a large model's
 * classification). The border slots are listed by their start vertex (a counting sort
 * over the ids from the smallest); each slot u -> v finds its opposite among v's. The
 * outcome is the sort's when every edge has exactly two sides, one each way, or one side
 * that is a wall; anything else (or sparse ids, or a vertex with more than
 * VERTEX_SIDES_MAX border sides, such as a fan's centre) returns false with the pairs
 * found left in place, and the sort decides (and reports) the rest. */
enum { VERTEX_SIDES_MAX = 64 };

typedef struct side {
    uint32_t slot, to;
} side;

typedef struct vertex_sides {
    uint32_t first, last; /* the range of start vertex ids */
    uint32_t *start;      /* per vertex id - first + 2 */
    side *sides;          /* border slots by start vertex, with their end vertex */
} vertex_sides;

/* Lists the sides; false when a vertex has too many of them (then *nomem stays false)
 * or memory ran out. */
static bool list_sides_by_vertex(mci_leaf_work *w, size_t n, vertex_sides *vs, bool *nomem)
{
    size_t range = (size_t)(vs->last - vs->first) + 1;
    vs->start = mci_calloc_array(w->ctx, range + 2, sizeof *vs->start);
    vs->sides = mci_malloc_array(w->ctx, n + 1, sizeof *vs->sides);
    if (!vs->start || !vs->sides) {
        *nomem = true;
        return false;
    }
    for (size_t k = 0; k < 3 * w->np; k++)
        if (w->mate[k] == MCI_NONE)
            vs->start[mci_leaf_slot_from(w, k) - vs->first + 2]++;
    for (size_t v = 2; v < range + 2; v++) {
        if (vs->start[v] > VERTEX_SIDES_MAX)
            return false;
        vs->start[v] += vs->start[v - 1];
    }
    for (size_t p = 0; p < w->np; p++)
        for (int i = 0; i < 3; i++)
            if (w->mate[3 * p + (size_t)i] == MCI_NONE)
                vs->sides[vs->start[w->pv[3 * p + (size_t)i] - vs->first + 1]++] =
                    (side){(uint32_t)(3 * p) + (uint32_t)i, w->pv[3 * p + (size_t)(i + 1) % 3]};
    return true;
}

/* The shell of the face holding edge slot k: shells of one leaf that may cross each
 * other (or lie in each other's faces) are paired each on its own. */
static uint32_t slot_shell(const mci_leaf_work *w, size_t k)
{
    return mci_octree_face_shell(&w->s->octree, w->pface[k / 3]);
}

/* Whether the leaf's faces are in several shells (mci_octree_face_shell tells them). */
static bool leaf_has_shells(const mci_leaf_work *w)
{
    return w->cl->tree->leaf_shell[w->leaf] != NULL || w->cl->tree->leaf_crossing[w->leaf];
}

/* Border slots of vertex `from` going to vertex `to` in faces of shell g (any shell if g
 * is MCI_NONE): how many, and the first. */
static size_t sides_between(const mci_leaf_work *w, const vertex_sides *vs, uint32_t from,
                            uint32_t to, uint32_t g, uint32_t *first)
{
    size_t count = 0;
    if (from < vs->first || from > vs->last)
        return 0;
    for (uint32_t i = vs->start[from - vs->first]; i < vs->start[from - vs->first + 1]; i++)
        if (vs->sides[i].to == to && (g == MCI_NONE || slot_shell(w, vs->sides[i].slot) == g) &&
            count++ == 0)
            *first = vs->sides[i].slot;
    return count;
}

static bool is_separator(const mci_leaf_work *w, uint64_t key)
{
    return mci_find_key(w->sep, w->nsep, key) != w->nsep;
}

/* True when every border slot is paired (or a wall); false with *nomem set when memory
 * ran out, else when the sort must decide. */
static bool pair_by_vertex(mci_leaf_work *w, size_t n, bool *nomem)
{
    vertex_sides vs = {UINT32_MAX, 0, NULL, NULL};
    bool ok, shells = leaf_has_shells(w);
    for (size_t k = 0; k < 3 * w->np; k++) {
        if (w->mate[k] != MCI_NONE)
            continue;
        vs.first = mci_leaf_slot_from(w, k) < vs.first ? mci_leaf_slot_from(w, k) : vs.first;
        vs.last = mci_leaf_slot_from(w, k) > vs.last ? mci_leaf_slot_from(w, k) : vs.last;
    }
    ok = n > 0 && (vs.last - vs.first) / 8 < n && list_sides_by_vertex(w, n, &vs, nomem);
    for (size_t s = 0; ok && s < n; s++) {
        uint32_t k = vs.sides[s].slot, u = mci_leaf_slot_from(w, k), v = vs.sides[s].to;
        uint32_t back = MCI_NONE, ignored, g;
        uint64_t key = mci_edge_key(u, v);
        size_t ahead, behind;
        if (w->mate[k] != MCI_NONE)
            continue;
        g = shells ? slot_shell(w, k) : MCI_NONE;
        ahead = sides_between(w, &vs, u, v, g, &ignored);
        behind = sides_between(w, &vs, v, u, g, &back);
        if (u != v && ahead == 1 && behind == 1) {
            w->mate[k] = back;
            w->mate[back] = (uint32_t)k;
            w->is_sep[k] = w->is_sep[back] = is_separator(w, key);
        } else if (u == v || !(ahead == 1 && behind == 0 && is_wall(w, k, key))) {
            ok = false;
        }
    }
    mci_free(w->ctx, vs.start);
    mci_free(w->ctx, vs.sides);
    return ok;
}

/* Which sides pair_sides may join, pass by pass, where more than two sides meet: first
 * the two sides of a cut through one face, then sides of faces the leaf check paired by
 * angle (where one shell meets itself, mci_ptree.leaf_mates), then any. */
typedef enum side_pass { SAME_FACE, ANGLE_MATES, ANY_FACE } side_pass;

static bool sides_match(const mci_leaf_work *w, uint32_t k, uint32_t j, bool shells,
                        side_pass pass)
{
    const mci_edge_mates *mates = &w->cl->tree->leaf_mates[w->leaf];
    uint32_t f = w->pface[k / 3], g = w->pface[j / 3];
    if (w->mate[j] != MCI_NONE || mci_leaf_slot_from(w, j) != mci_leaf_slot_to(w, k) ||
        (shells && slot_shell(w, j) != slot_shell(w, k)))
        return false;
    if (pass == SAME_FACE)
        return f == g;
    return pass == ANY_FACE ||
           mci_edge_mates_has(mates, f - w->face_base, g - w->face_base);
}

/* The edges of its face that a point with location `where` (MCI_AT_*) lies on, as bits:
 * a corner on the two edges it ends, an edge point on its edge. */
static unsigned edges_at(int where)
{
    if (where < MCI_AT_EDGE)
        return 1u << where | 1u << (where + 2) % 3;
    return where < MCI_AT_INSIDE ? 1u << (where - MCI_AT_EDGE) : 0;
}

/* The edge of piece slot k's face that the slot lies along (sides left to pair lie on
 * their faces' borders): the one edge both its ends lie on, or -1. */
static int slot_face_edge(const mci_leaf_work *w, size_t k)
{
    const mci_face_arr *arr = mci_scene_arr_of_face(w->s, w->pface[k / 3]);
    unsigned common;
    if (!arr)
        return (int)(k % 3); /* a whole face: its corners in order */
    common = edges_at(arr->where[w->plocal[k]]) &
             edges_at(arr->where[w->plocal[k - k % 3 + (k % 3 + 1) % 3]]);
    return common == 1 ? 0 : common == 2 ? 1 : common == 4 ? 2 : -1;
}

/* Input vertex `corner` of face f of the leaf. */
static const double *face_corner(const mci_leaf_work *w, uint32_t f, int corner)
{
    const mcsg_mesh *m = w->s->octree.leaves[w->leaf];
    return m->vertices + 3 * (size_t)m->triangles[3 * (size_t)(f - w->face_base) + (size_t)corner];
}

/* Pairs the unpaired sides of the run in the shell of side `first` by angle about their
 * common edge (mci_pair_fan_by_angle): each side lies along an edge of its face, the
 * face in the half-plane of that edge holding its third corner. Where more than two
 * sides meet (a shell touching itself along an edge, or input edges overlapping on one
 * line), pairs that bound one wedge keep a region's winding numbers; pairs found
 * otherwise (by face) need not. False when the sides cannot be paired so. */
static bool pair_sides_by_angle(mci_leaf_work *w, const mci_keyed *run, size_t n, size_t first,
                                bool shells, bool separator)
{
    const double *third[MCI_FAN_MAX];
    uint8_t forward[MCI_FAN_MAX], mate[MCI_FAN_MAX];
    uint32_t slot[MCI_FAN_MAX];
    mci_edge_fan fan = {NULL, NULL, third, forward, 0};
    uint32_t k0 = run[first].ref;
    for (size_t i = first; i < n; i++) {
        uint32_t k = run[i].ref, f = w->pface[k / 3];
        int e = slot_face_edge(w, k);
        if (w->mate[k] != MCI_NONE || (shells && slot_shell(w, k) != slot_shell(w, k0)))
            continue;
        if (e < 0 || fan.n == MCI_FAN_MAX)
            return false;
        forward[fan.n] = mci_leaf_slot_from(w, k) < mci_leaf_slot_to(w, k);
        third[fan.n] = face_corner(w, f, (e + 2) % 3);
        if (fan.n == 0) { /* the axis from the smaller output id to the larger */
            fan.u = face_corner(w, f, forward[0] ? e : (e + 1) % 3);
            fan.v = face_corner(w, f, forward[0] ? (e + 1) % 3 : e);
        }
        slot[fan.n++] = k;
    }
    if (mci_pair_fan_by_angle(&fan, mate) == 0)
        return false;
    for (size_t i = 0; i < fan.n; i++) {
        w->mate[slot[i]] = slot[mate[i]];
        w->is_sep[slot[i]] = separator;
    }
    return true;
}

/* Pairs the n sides of one edge (a run of equal keys), each with the opposite side of
 * its own shell: by angle where more than two meet, else (or where that fails) by face
 * (see side_pass); the pairs are separators if `separator`. */
static mcsg_status pair_sides(mci_leaf_work *w, const mci_keyed *run, size_t n, bool separator)
{
    bool shells = leaf_has_shells(w);
    bool mates = w->cl->tree->leaf_mates[w->leaf].count > 0;
    side_pass pass = n > 2 ? SAME_FACE : ANY_FACE;
    for (size_t a = 0; n > 2 && a < n; a++)
        if (w->mate[run[a].ref] == MCI_NONE)
            pair_sides_by_angle(w, run, n, a, shells, separator);
    for (; pass <= ANY_FACE; pass++)
        for (size_t a = 0; a < n && (pass != ANGLE_MATES || mates); a++) {
            uint32_t k = run[a].ref;
            size_t b = a + 1;
            if (w->mate[k] != MCI_NONE)
                continue;
            while (b < n && !sides_match(w, k, run[b].ref, shells, pass))
                b++;
            if (b == n && pass == ANY_FACE)
                return mci_fail(w->err, MCSG_ERR_INTERNAL,
                                "leaf %u does not close up after splitting: an edge is shared "
                                "by %zu pieces%s (inputs must be closed as chains)", w->leaf, n,
                                n == 2 ? " with equal orientations" : "");
            if (b == n)
                continue;
            w->mate[k] = run[b].ref;
            w->mate[run[b].ref] = k;
            w->is_sep[k] = w->is_sep[run[b].ref] = separator;
        }
    return MCSG_OK;
}

/* Pair every directed piece edge with its opposite; a surface closed as a chain has one
 * in each shell (where more than two pieces share an edge, pair_sides pairs them shell
 * by shell). Sides on face borders are sorted by edge key
 * and walked along the sorted separators (collect_separators), which marks the
 * separator slots (is_sep); leaves with dense vertex ids are paired by vertex first
 * (pair_by_vertex). */
static mcsg_status pair_edges(mci_leaf_work *w)
{
    size_t n, i = 0, sep = 0, m = 0;
    mci_keyed *e;
    mcsg_status st = MCSG_OK;
    bool nomem = false;
    w->mate = mci_malloc_array(w->ctx, 3 * w->np + 1, sizeof *w->mate);
    if (!w->mate)
        return mci_fail_nomem(w->err, "classifying faces");
    n = pair_inside_faces(w);
    if (pair_by_vertex(w, n, &nomem))
        return MCSG_OK;
    if (nomem)
        return mci_fail_nomem(w->err, "classifying faces");
    e = mci_malloc_array(w->ctx, n + 1, sizeof *e);
    if (!e)
        return mci_fail_nomem(w->err, "classifying faces");
    for (size_t k = 0; k < 3 * w->np; k++) {
        if (w->mate[k] != MCI_NONE)
            continue;
        e[m].key = mci_edge_key(mci_leaf_slot_from(w, k), mci_leaf_slot_to(w, k));
        e[m++].ref = (uint32_t)k;
    }
    n = m; /* fewer when pair_by_vertex paired some before giving up */
    mci_sort_keyed(e, n);
    while (i < n && st == MCSG_OK) {
        size_t j = i;
        while (j < n && e[j].key == e[i].key)
            j++;
        if (j - i == 1 && is_wall(w, e[i].ref, e[i].key)) {
            i = j;
            continue;
        }
        while (sep < w->nsep && w->sep[sep].key < e[i].key)
            sep++;
        st = pair_sides(w, e + i, j - i, sep < w->nsep && w->sep[sep].key == e[i].key);
        i = j;
    }
    mci_free(w->ctx, e);
    return st;
}

/* Every elementary edge of the leaf's arrangements, with the other leaf's face. */
static mcsg_status collect_separators(mci_leaf_work *w)
{
    const mci_scene *s = w->s;
    size_t n = 0;
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++)
        n += mci_scene_arr_of_face(s, f) ? mci_scene_arr_of_face(s, f)->edge_count : 0;
    w->sep = mci_malloc_array(w->ctx, n + 1, sizeof *w->sep);
    w->is_sep = mci_calloc_array(w->ctx, 3 * w->np + 1, sizeof *w->is_sep);
    if (!w->sep || !w->is_sep)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++) {
        const mci_face_arr *arr = mci_scene_arr_of_face(s, f);
        const uint32_t *gid = arr ? s->gid + s->gid_start[s->arr_of[f]] : NULL;
        for (size_t e = 0; arr && e < arr->edge_count; e++) {
            w->sep[w->nsep].key = mci_edge_key(gid[arr->edges[e].a], gid[arr->edges[e].b]);
            w->sep[w->nsep++].ref = arr->edges[e].other;
        }
    }
    mci_sort_keyed(w->sep, w->nsep);
    return MCSG_OK;
}

int mci_leaf_plane_relation(const mci_leaf_work *w, uint32_t f, uint32_t g)
{
    mci_plane pf, pg;
    int axis, sign;
    mci_scene_face_plane(w->s, f, &pf);
    mci_scene_face_plane(w->s, g, &pg);
    if (mci_orient3d_vertex(pg.a, &pf) != 0 || mci_orient3d_vertex(pg.b, &pf) != 0 ||
        mci_orient3d_vertex(pg.c, &pf) != 0)
        return 0;
    axis = mci_plane_projection_axis(&pf, &sign);
    return axis >= 0 && mci_plane_normal_sign(&pg, axis) == -sign ? -1 : 1;
}

/* Whether another face lies in face f's plane over part of it (its arrangement took a
 * coplanar face): f's pieces there lie in a stack of coincident sheets. */
static bool stacked(const mci_leaf_work *w, uint32_t f)
{
    const mci_face_arr *arr = mci_scene_arr_of_face(w->s, f);
    return arr && arr->coplanar;
}

/* Whether pieces are joined across slot k: not a separator, and, in a leaf classified
 * by winding numbers, not where the region's numbers stop meaning the same:
 *   - a fold flat onto the piece across (faces in one plane facing opposite ways, a
 *     sliver that rounding turned over): each one's front is the other's back there,
 *     and the numbers on the two sides of the plane differ by what the faces covering
 *     it add up to;
 *   - from a face lying in a stack of coincident sheets to a face in another plane: a
 *     ray from a piece in the stack tells the numbers beyond the whole stack, which are
 *     not those beside a single sheet (where two sheets facing opposite ways bound a
 *     crack of no width, the number in front of each is the crack's, and beyond the
 *     stack it is the solid's around it).
 * Faces in one plane facing the same way stay joined, stacked or not. (Not joining them
 * either, so that a stacked face's pieces are regions of their own, lost 0.75% of the
 * volume of tests/data/rounding/folded-cap-sliver.off, not understood.) */
static bool joins(const mci_leaf_work *w, size_t k)
{
    uint32_t f, g;
    int relation;
    if (w->is_sep[k])
        return false; /* walls too: they have no mate */
    if (!w->cl->tree->leaf_winding[w->leaf])
        return true;
    f = w->pface[k / 3], g = w->pface[w->mate[k] / 3];
    if (f == g)
        return true;
    relation = mci_leaf_plane_relation(w, f, g);
    return relation == 1 || (relation == 0 && !stacked(w, f) && !stacked(w, g));
}

/* Regions: pieces joined across non-separator edges; numbered by first piece. */
static mcsg_status build_regions(mci_leaf_work *w)
{
    uint32_t *parent = mci_malloc_array(w->ctx, w->np + 1, sizeof *parent);
    w->region = mci_malloc_array(w->ctx, w->np + 1, sizeof *w->region);
    if (!parent || !w->region) {
        mci_free(w->ctx, parent);
        return mci_fail_nomem(w->err, "classifying faces");
    }
    for (uint32_t p = 0; p < w->np; p++)
        parent[p] = p;
    for (size_t k = 0; k < 3 * w->np; k++) {
        if (joins(w, k)) {
            uint32_t a = mci_find_root(parent, (uint32_t)(k / 3));
            uint32_t b = mci_find_root(parent, w->mate[k] / 3);
            parent[a > b ? a : b] = a > b ? b : a;
        }
    }
    for (uint32_t p = 0; p < w->np; p++) {
        uint32_t r = mci_find_root(parent, p);
        w->region[p] = r == p ? (uint32_t)w->nreg++ : w->region[r];
    }
    mci_free(w->ctx, parent);
    return MCSG_OK;
}

/* CSR lists: pieces of each region, and separator slots of each region. */
static mcsg_status index_regions(mci_leaf_work *w)
{
    size_t nr = w->nreg;
    w->reg_start = mci_calloc_array(w->ctx, nr + 2, sizeof *w->reg_start);
    w->sep_start = mci_calloc_array(w->ctx, nr + 2, sizeof *w->sep_start);
    w->reg_pieces = mci_malloc_array(w->ctx, w->np + 1, sizeof *w->reg_pieces);
    w->sep_slots = mci_malloc_array(w->ctx, 3 * w->np + 1, sizeof *w->sep_slots);
    if (!w->reg_start || !w->sep_start || !w->reg_pieces || !w->sep_slots)
        return mci_fail_nomem(w->err, "classifying faces");
    for (size_t p = 0; p < w->np; p++) {
        w->reg_start[w->region[p] + 2]++;
        for (int i = 0; i < 3; i++)
            w->sep_start[w->region[p] + 2] += w->is_sep[3 * p + i];
    }
    for (size_t r = 2; r < nr + 2; r++) {
        w->reg_start[r] += w->reg_start[r - 1];
        w->sep_start[r] += w->sep_start[r - 1];
    }
    for (size_t p = 0; p < w->np; p++) {
        w->reg_pieces[w->reg_start[w->region[p] + 1]++] = (uint32_t)p;
        for (int i = 0; i < 3; i++)
            if (w->is_sep[3 * p + i])
                w->sep_slots[w->sep_start[w->region[p] + 1]++] = (uint32_t)(3 * p + i);
    }
    return MCSG_OK;
}

mcsg_status mci_leaf_regions(mci_leaf_work *w)
{
    mcsg_status st = make_pieces(w);
    if (st == MCSG_OK)
        st = collect_separators(w);
    if (st == MCSG_OK)
        st = collect_walls(w);
    if (st == MCSG_OK)
        st = pair_edges(w);
    if (st == MCSG_OK)
        st = build_regions(w);
    if (st == MCSG_OK)
        st = index_regions(w);
    return st;
}
