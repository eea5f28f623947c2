/*
 * One leaf's labels (paper §5.2, §5.3, §5.5): the candidates (leaves whose boxes meet
 * this one's), the trimmed CSGlist, the first seed of each connected part by exact rays,
 * and every other region's labels inherited across a separator, re-deciding only the
 * leaves whose surface holds it by the exact local test. Copies of this leaf share its
 * regions; a candidate that is a copy of another leaf borrows that leaf's labels.
 */
#include "csg/classify_leaf.h"
#include "csg/local_test.h"

#include <stdint.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

/* Which candidates are winding leaves, and room for their numbers if any is. */
static mcsg_status winding_candidates(mci_leaf_work *w)
{
    const uint8_t *winding = w->cl->tree->leaf_winding;
    bool any = false;
    if (!(w->cand_winding = mci_malloc_array(w->ctx, w->ncand + 1, 1)))
        return mci_fail_nomem(w->err, "classifying faces");
    for (size_t c = 0; c < w->ncand; c++)
        any |= (w->cand_winding[c] = winding[w->cand[c]]) != 0;
    if (winding[w->leaf]) {
        w->own_front = mci_malloc_array(w->ctx, w->nreg + 1, sizeof *w->own_front);
        w->own_coin = mci_malloc_array(w->ctx, w->nreg + 1, sizeof *w->own_coin);
        w->own_first = mci_malloc_array(w->ctx, w->nreg + 1, 1);
        if (!w->own_front || !w->own_coin || !w->own_first)
            return mci_fail_nomem(w->err, "classifying faces");
        for (size_t r = 0; r < w->nreg; r++)
            w->own_front[r] = MCI_WIND_UNKNOWN;
    }
    if (!any)
        return MCSG_OK;
    w->wind = mci_malloc_array(w->ctx, w->nreg * w->ncand + 1, sizeof *w->wind);
    w->coin = mci_calloc_array(w->ctx, w->nreg * w->ncand + 1, sizeof *w->coin);
    if (!w->wind || !w->coin)
        return mci_fail_nomem(w->err, "classifying faces");
    for (size_t i = 0; i < w->nreg * w->ncand; i++)
        w->wind[i] = MCI_WIND_UNKNOWN;
    return MCSG_OK;
}

/* Region r's label and winding numbers with respect to winding candidate c. */
static void set_windings(mci_leaf_work *w, uint32_t r, size_t c, int32_t behind, int32_t in_front)
{
    w->wind[(size_t)r * w->ncand + c] = in_front;
    w->coin[(size_t)r * w->ncand + c] = behind - in_front;
    w->labels[(size_t)r * w->ncand + c] = (uint8_t)mci_label_of_windings(behind, in_front);
}

/* The same from the ray-given number at a point of the region off that leaf's surface. */
static void set_winding(mci_leaf_work *w, uint32_t r, size_t c, int32_t number)
{
    set_windings(w, r, c, number, number);
}

bool mci_leaf_label_by_ray(mci_leaf_work *w, uint32_t r, size_t c, const mci_point *v)
{
    uint32_t m = w->cand[c];
    w->stats->rays++;
    if (w->cand_winding[c]) {
        int number;
        bool decided;
        if (!mci_ray_winding_octree(w->ctx, v, &w->s->octree, m, &w->ray, &number, &decided))
            return false;
        if (decided)
            set_winding(w, r, c, number);
        return true;
    }
    {
        mci_label label;
        if (!mci_ray_label_octree(w->ctx, v, &w->s->octree, m, &w->ray, &label))
            return false;
        w->labels[(size_t)r * w->ncand + c] = (uint8_t)label;
    }
    return true;
}

/* The candidates: the other leaves whose boxes meet this leaf's, in increasing index. */
static mcsg_status find_candidates(mci_leaf_work *w)
{
    size_t n = w->s->octree.leaf_count;
    const uint32_t *first = w->cl->overlap + w->cl->overlap_start[w->leaf];
    size_t count = w->cl->overlap_start[w->leaf + 1] - w->cl->overlap_start[w->leaf];
    w->cand = mci_malloc_array(w->ctx, count + 1, sizeof *w->cand);
    w->slot_of_leaf = mci_malloc_array(w->ctx, n + 1, sizeof *w->slot_of_leaf);
    if (!w->cand || !w->slot_of_leaf)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t l = 0; l < n; l++)
        w->slot_of_leaf[l] = MCI_NONE;
    for (size_t c = 0; c < count; c++) {
        w->slot_of_leaf[first[c]] = (uint32_t)w->ncand;
        w->cand[w->ncand++] = first[c];
    }
    if (w->nreg > 0 && w->ncand > SIZE_MAX / w->nreg)
        return mci_fail(w->err, MCSG_ERR_LIMIT, "too many labels in one leaf");
    w->labels = mci_malloc_array(w->ctx, w->nreg * w->ncand + 1, 1);
    if (!w->labels)
        return mci_fail_nomem(w->err, "classifying faces");
    memset(w->labels, MCI_LABEL_UNKNOWN, w->nreg * w->ncand);
    return winding_candidates(w);
}

static bool point_outside_box(const mci_point *p, const double box[6])
{
    double lo[3], hi[3];
    mci_point_bounds(p, lo, hi);
    for (int k = 0; k < 3; k++)
        if (hi[k] < box[k] || lo[k] > box[3 + k])
            return true;
    return false;
}

static void local_labels_at(mci_leaf_work *w, uint32_t r, size_t k, bool only_unknown,
                            uint32_t from);

/* Labels a seed region's rays left open (every vertex tried lies on that leaf's
 * surface): decided at a separator of the region on that leaf, if any. */
static void seed_by_local_tests(mci_leaf_work *w, uint32_t r)
{
    for (uint32_t i = w->sep_start[r]; i < w->sep_start[r + 1]; i++)
        local_labels_at(w, r, w->sep_slots[i], true, MCI_NONE);
}

/* Whether every label region r needs is known. */
static bool region_labelled(const mci_leaf_work *w, uint32_t r)
{
    const uint8_t *lab = w->labels + (size_t)r * w->ncand;
    for (size_t c = 0; c < w->ncand; c++)
        if (w->needed[c] && lab[c] == MCI_LABEL_UNKNOWN)
            return false;
    return true;
}

/* Rays from region vertices for the labels still unknown, vertices in a fixed order
 * (untouched faces' vertices first: they lie on no other surface), from the first'th
 * to before the end'th; true once every label needed is known. A ray from a vertex on
 * the other leaf's surface decides nothing; the next vertex is tried. */
static bool labels_from_vertices(mci_leaf_work *w, uint32_t r, size_t first, size_t end)
{
    uint8_t *lab = w->labels + (size_t)r * w->ncand;
    size_t at = 0;
    for (int pass = 0; pass < 2; pass++)
        for (uint32_t k = w->reg_start[r]; k < w->reg_start[r + 1]; k++) {
            uint32_t p = w->reg_pieces[k];
            bool untouched = mci_scene_arr_of_face(w->s, w->pface[p]) == NULL;
            if (untouched != (pass == 0))
                continue;
            for (int i = 0; i < 3; i++, at++) {
                mci_point v;
                if (at < first)
                    continue;
                if (at >= end || w->out_of_memory)
                    return false;
                mci_leaf_piece_point(w, p, i, &v);
                for (size_t c = 0; c < w->ncand; c++) {
                    if (lab[c] != MCI_LABEL_UNKNOWN || !w->needed[c])
                        continue;
                    if (point_outside_box(&v, w->cl->box[w->cand[c]])) {
                        if (w->cand_winding[c])
                            set_winding(w, r, c, 0);
                        lab[c] = MCI_LABEL_OUT;
                        continue;
                    }
                    if (!mci_leaf_label_by_ray(w, r, c, &v)) {
                        w->out_of_memory = true;
                        return false;
                    }
                }
                if (region_labelled(w, r))
                    return true;
            }
        }
    return false;
}

/* Region r's labels with respect to candidate c from a ray from q, a point strictly
 * inside one of its pieces, in the plane `at` of the piece's face: for a winding leaf, its
 * numbers on both sides when the piece lies in its surface too. False when out of
 * memory. */
static bool label_from_inside(mci_leaf_work *w, uint32_t r, size_t c, const mci_point *q,
                              const mci_plane *at)
{
    mci_plane_windings got;
    if (!w->cand_winding[c])
        return mci_leaf_label_by_ray(w, r, c, q);
    w->stats->rays++;
    if (!mci_ray_windings_on_plane(w->ctx, q, &w->s->octree, w->cand[c], at, &w->ray, &got))
        return false;
    if (got.decided)
        set_windings(w, r, c, got.behind, got.in_front);
    return true;
}

/* Whether some label region r needs, of those looked for, is unknown. */
static bool some_unknown(const mci_leaf_work *w, uint32_t r, bool winding_only)
{
    const uint8_t *lab = w->labels + (size_t)r * w->ncand;
    for (size_t c = 0; c < w->ncand; c++)
        if (lab[c] == MCI_LABEL_UNKNOWN && w->needed[c] && (!winding_only || w->cand_winding[c]))
            return true;
    return false;
}

bool mci_leaf_labels_from_inside(mci_leaf_work *w, uint32_t r, bool winding_only)
{
    uint8_t *lab = w->labels + (size_t)r * w->ncand;
    bool learnt = false;
    for (uint32_t k = w->reg_start[r]; k < w->reg_start[r + 1] && some_unknown(w, r, winding_only);
         k++)
        for (int attempt = 0; attempt < MCI_INSIDE_ATTEMPTS && some_unknown(w, r, winding_only);
             attempt++) {
            mci_point probe;
            mci_plane at;
            double ends[2][3];
            if (!mci_leaf_piece_inside(w, w->reg_pieces[k], attempt, ends, &probe, &at))
                continue;
            for (size_t c = 0; c < w->ncand; c++) {
                if (lab[c] != MCI_LABEL_UNKNOWN || !w->needed[c] ||
                    (winding_only && !w->cand_winding[c]))
                    continue;
                if (!label_from_inside(w, r, c, &probe, &at)) {
                    w->out_of_memory = true;
                    return false;
                }
                learnt = learnt || lab[c] != MCI_LABEL_UNKNOWN;
            }
        }
    return learnt;
}

/* Vertices tried by rays before the local tests at the region's separators: a region
 * whose vertices all lie on another leaf's surface (a face's part inside a wall-bounded
 * solid, cut by its walls) would otherwise cast a fruitless ray from every vertex, each
 * crossing the whole octree, where one local test at a separator decides. */
#define SEED_RAY_VERTICES 12

/* First seed: the region's labels by rays from a few vertices, then by local tests at
 * its separators, then by rays from the rest of its vertices. */
static void seed_region(mci_leaf_work *w, uint32_t r)
{
    if (labels_from_vertices(w, r, 0, SEED_RAY_VERTICES) || w->out_of_memory)
        return;
    seed_by_local_tests(w, r);
    if (!region_labelled(w, r))
        labels_from_vertices(w, r, SEED_RAY_VERTICES, SIZE_MAX);
    /* A winding leaf is not decided by a local test alone (it tells a side, not the
     * number), and every vertex lies on its surface where the region does. */
    if (w->wind && !region_labelled(w, r) && !w->out_of_memory)
        mci_leaf_labels_from_inside(w, r, true);
}

/* The three points of slot k's piece: the slot's ends x, y and the far vertex. */
static void slot_points(const mci_leaf_work *w, size_t k, mci_point *x, mci_point *y,
                        mci_point *far)
{
    size_t p = k / 3;
    mci_leaf_piece_point(w, p, (int)(k % 3), x);
    mci_leaf_piece_point(w, p, (int)(k % 3 + 1) % 3, y);
    mci_leaf_piece_point(w, p, (int)(k % 3 + 2) % 3, far);
}

static bool face_seen(const uint32_t *seen, size_t nseen, uint32_t h)
{
    for (size_t i = 0; i < nseen; i++)
        if (seen[i] == h)
            return true;
    return false;
}

/* The winding numbers across separator slot k of region r from region `from` (across
 * the slot's mate), for the leaf whose faces hold it in sep[begin .. end): one step per
 * sheet. A separator along an edge of the leaf is held by the faces on both sides, one
 * sheet: the local test takes them as one wedge, and the face it took as the other
 * half is not stepped again. Where one shell meets itself at the edge, each of its
 * wedges is a step of its own (the faces across are mates, see mci_scene.neighbour). */
static mci_wind_sum wind_steps(mci_leaf_work *w, size_t k, size_t begin, size_t end)
{
    const mci_scene *s = w->s;
    mci_wind_sum sum = {0, 0, false, false};
    uint32_t seen[16];
    size_t nseen = 0, k1 = w->mate[k];
    mci_point x, y, far, x1, y1, far1;
    slot_points(w, k, &x, &y, &far);
    slot_points(w, k1, &x1, &y1, &far1);
    for (size_t e = begin; e < end; e++) {
        uint32_t h = w->sep[e].ref, partner;
        mci_label to, from;
        if (face_seen(seen, nseen, h))
            continue;
        if (nseen + 2 > sizeof seen / sizeof seen[0]) {
            sum.unknown = true; /* more sheets through one curve than looked at */
            break;
        }
        seen[nseen++] = h;
        w->stats->local_tests += 2;
        to = mci_local_label(s, mci_scene_arr_of_face(s, w->pface[k / 3]), &x, &y, &far, h,
                             &partner);
        from = mci_local_label(s, mci_scene_arr_of_face(s, w->pface[k1 / 3]), &x1, &y1, &far1, h,
                               NULL);
        if (partner != MCI_NONE)
            seen[nseen++] = partner;
        mci_wind_sheet(&sum, from, to);
    }
    return sum;
}

/* Region r's number and label for winding candidate c from region `from`'s. */
static void winding_across(mci_leaf_work *w, uint32_t from, uint32_t r, size_t c, mci_wind_sum sum)
{
    size_t at = (size_t)from * w->ncand + c;
    int32_t before = w->wind[at];
    if (before == MCI_WIND_UNKNOWN || sum.unknown) {
        w->wind[(size_t)r * w->ncand + c] = MCI_WIND_UNKNOWN;
        w->labels[(size_t)r * w->ncand + c] = MCI_LABEL_UNKNOWN;
        return;
    }
    set_windings(w, r, c, before + sum.front + w->coin[at] + sum.coincident, before + sum.front);
}

/* Region r has this leaf's own numbers of region `from` (none of its faces lies between). */
static void own_copy(mci_leaf_work *w, uint32_t from, uint32_t r)
{
    w->own_front[r] = w->own_front[from];
    w->own_coin[r] = w->own_coin[from];
    w->own_first[r] = w->own_first[from];
}

/* This leaf's own numbers of region r from region `from`'s, across shells of it that
 * cross the region's face. Where another of its faces lies in either region, which
 * shells lie in r is not carried over: a ray decides (mci_leaf_own_seed). */
static void own_across(mci_leaf_work *w, uint32_t from, uint32_t r, mci_wind_sum sum)
{
    own_copy(w, from, r);
    if (w->own_front[r] == MCI_WIND_UNKNOWN || sum.unknown || sum.coplanar)
        w->own_front[r] = MCI_WIND_UNKNOWN;
    else
        w->own_front[r] += sum.front;
}

/* The end of the run of separator entries from e on with e's key and leaf (entries of
 * one leaf are consecutive: sorted by face). */
static size_t leaf_run_end(const mci_leaf_work *w, size_t e)
{
    uint32_t leaf = w->s->octree.face_leaf[w->sep[e].ref];
    size_t end = e + 1;
    while (end < w->nsep && w->sep[end].key == w->sep[e].key &&
           w->s->octree.face_leaf[w->sep[end].ref] == leaf)
        end++;
    return end;
}

/* Labels of region r, whose piece has edge slot k, with respect to the leaves holding
 * that slot, by local tests (only those still unknown if only_unknown). A winding leaf's
 * number (and this leaf's own, where another of its shells holds the slot) is carried
 * over from region `from` across the slot (mate of k), and left alone when from is
 * MCI_NONE. Entries of one leaf are consecutive (sorted by face). */
static void local_labels_at(mci_leaf_work *w, uint32_t r, size_t k, bool only_unknown,
                            uint32_t from)
{
    const mci_scene *s = w->s;
    uint8_t *to = w->labels + (size_t)r * w->ncand;
    uint64_t key = mci_edge_key(mci_leaf_slot_from(w, k), mci_leaf_slot_to(w, k));
    mci_point x, y, far;
    size_t e = mci_leaf_find_separator(w, key), end;
    slot_points(w, k, &x, &y, &far);
    for (; e < w->nsep && w->sep[e].key == key; e = end) {
        uint32_t leaf = s->octree.face_leaf[w->sep[e].ref], c = w->slot_of_leaf[leaf];
        end = leaf_run_end(w, e);
        if (leaf == w->leaf) {
            if (w->own_front && from != MCI_NONE && (!only_unknown ||
                                                     w->own_front[r] == MCI_WIND_UNKNOWN))
                own_across(w, from, r, wind_steps(w, k, e, end));
            continue;
        }
        if (c == MCI_NONE || !w->needed[c] || (only_unknown && to[c] != MCI_LABEL_UNKNOWN))
            continue;
        if (w->cand_winding[c]) {
            if (from != MCI_NONE)
                winding_across(w, from, r, c, wind_steps(w, k, e, end));
            continue;
        }
        for (size_t i = e; i < end && !(only_unknown && to[c] != MCI_LABEL_UNKNOWN); i++) {
            w->stats->local_tests++;
            to[c] = (uint8_t)mci_local_label(s, mci_scene_arr_of_face(s, w->pface[k / 3]), &x,
                                             &y, &far, w->sep[i].ref, NULL);
        }
    }
}

/* Labels of region r2 from those of r1 across separator slot k (a slot of r2): equal
 * but for the leaves whose surface holds the separator (paper Prop. 2). */
static void inherit_labels(mci_leaf_work *w, uint32_t r1, uint32_t r2, size_t k)
{
    memcpy(w->labels + (size_t)r2 * w->ncand, w->labels + (size_t)r1 * w->ncand, w->ncand);
    if (w->wind) {
        memcpy(w->wind + (size_t)r2 * w->ncand, w->wind + (size_t)r1 * w->ncand,
               w->ncand * sizeof *w->wind);
        memcpy(w->coin + (size_t)r2 * w->ncand, w->coin + (size_t)r1 * w->ncand,
               w->ncand * sizeof *w->coin);
    }
    if (w->own_front)
        own_copy(w, r1, r2);
    local_labels_at(w, r2, k, false, r1);
    if (w->own_front && w->own_front[r2] == MCI_WIND_UNKNOWN && !w->out_of_memory)
        mci_leaf_own_seed(w, r2);
}

/* Whether separator slot k lies on the surface of leaf m. */
static bool separator_on_leaf(const mci_leaf_work *w, size_t k, uint32_t m)
{
    uint64_t key = mci_edge_key(mci_leaf_slot_from(w, k), mci_leaf_slot_to(w, k));
    for (size_t e = mci_leaf_find_separator(w, key); e < w->nsep && w->sep[e].key == key; e++)
        if (w->s->octree.face_leaf[w->sep[e].ref] == m)
            return true;
    return false;
}

/* This leaf's own numbers of region r (separator slot k, on this leaf) carried over from
 * region `from` across k, sheets lying in either region included (own_across leaves
 * those out: which shell comes first there, own_first, is not carried). False when not
 * known. */
static bool own_carried(mci_leaf_work *w, size_t k, uint32_t from, int32_t *front,
                        int32_t *coin)
{
    uint64_t key = mci_edge_key(mci_leaf_slot_from(w, k), mci_leaf_slot_to(w, k));
    size_t e = mci_leaf_find_separator(w, key), end;
    mci_wind_sum sum = {0, 0, true, false};
    for (; e < w->nsep && w->sep[e].key == key; e = end) {
        end = leaf_run_end(w, e);
        if (w->s->octree.face_leaf[w->sep[e].ref] == w->leaf)
            sum = wind_steps(w, k, e, end);
    }
    if (sum.unknown || w->own_front[from] == MCI_WIND_UNKNOWN)
        return false;
    *front = w->own_front[from] + sum.front;
    *coin = w->own_coin[from] + sum.coincident;
    return true;
}

/* Whether face h's triangle (an input triangle in the plane of the piece) holds the
 * piece with these corners, projected along axis: whether it holds the point
 * corner[0] + e (corner[1] - corner[0]) + e^2 (corner[2] - corner[0]) for every small
 * enough e > 0, a point strictly inside the piece next to its first corner. An
 * orientation is linear in its last point, so each side of h is the sign for the first
 * corner off that side's line, in that order (not all three lie on one line): the point
 * never lies on h's border (a piece's corners often do), and no point need be built,
 * however thin the piece (no line through doubles may pierce a piece far narrower than
 * their spacing). A coplanar face's borders are constraints of the piece's face, so h
 * holds all of the piece or none, except across a border with a face lying flat in the
 * same plane (no constraint: intersect_arrange.c, edge_is_crease): each of the two
 * holds part of the piece then, and one of them this point. */
static bool face_holds_piece(const mci_leaf_work *w, uint32_t h, const mci_point corner[3],
                             int axis)
{
    const mcsg_mesh *m = w->s->octree.leaves[w->leaf];
    const uint32_t *t = m->triangles + 3 * (size_t)(h - w->face_base);
    mci_point c[3];
    int turn;
    for (int i = 0; i < 3; i++)
        mci_point_explicit(&c[i], m->vertices + 3 * (size_t)t[i]);
    turn = mci_orient2d_projected(&c[0], &c[1], &c[2], axis);
    for (int i = 0; i < 3; i++) {
        int side = 0;
        for (int k = 0; k < 3 && side == 0; k++)
            side = mci_orient2d_projected(&c[i], &c[(i + 1) % 3], &corner[k], axis);
        if (side != turn)
            return false;
    }
    return true;
}

/* The projection axis of piece p's face, and the piece's corners; -1 when the plane has
 * none (never for a face with pieces). */
static int piece_corners(const mci_leaf_work *w, size_t p, mci_point corner[3])
{
    mci_plane plane;
    int sign;
    mci_scene_face_plane(w->s, w->pface[p], &plane);
    for (int i = 0; i < 3; i++)
        mci_leaf_piece_point(w, p, i, &corner[i]);
    return mci_plane_projection_axis(&plane, &sign);
}

/* own_first of region r without a ray: whether no face of the leaf in a lower group lies
 * in the region facing its way (a face holds the region where it holds a piece of it). */
static bool own_first_by_cover(const mci_leaf_work *w, uint32_t r)
{
    uint32_t p = w->reg_pieces[w->reg_start[r]], f = w->pface[p];
    uint32_t group = mci_octree_face_group(&w->s->octree, f);
    mci_point corner[3];
    int axis = piece_corners(w, p, corner);
    for (uint32_t h = w->face_base; axis >= 0 && h < w->face_base + w->face_count; h++)
        if (h != f && mci_octree_face_group(&w->s->octree, h) < group &&
            mci_leaf_plane_relation(w, f, h) == 1 && face_holds_piece(w, h, corner, axis))
            return false;
    return true;
}

/* Whether the boxes of faces f and h of this leaf meet (closed boxes of their corners). */
static bool face_boxes_meet(const mci_leaf_work *w, uint32_t f, uint32_t h)
{
    const mcsg_mesh *m = w->s->octree.leaves[w->leaf];
    const uint32_t *a = m->triangles + 3 * (size_t)(f - w->face_base);
    const uint32_t *b = m->triangles + 3 * (size_t)(h - w->face_base);
    for (int k = 0; k < 3; k++) {
        double alo = INFINITY, ahi = -INFINITY, blo = INFINITY, bhi = -INFINITY;
        for (int i = 0; i < 3; i++) {
            double x = m->vertices[3 * (size_t)a[i] + k], y = m->vertices[3 * (size_t)b[i] + k];
            alo = fmin(alo, x), ahi = fmax(ahi, x), blo = fmin(blo, y), bhi = fmax(bhi, y);
        }
        if (ahi < blo || bhi < alo)
            return false;
    }
    return true;
}

size_t mci_leaf_coincident_faces(const mci_leaf_work *w, uint32_t f, uint32_t *faces,
                                 int8_t *facing)
{
    size_t n = 0;
    for (size_t i = 0; i < w->nstacked; i++) {
        uint32_t h = w->stacked[i];
        int relation = h != f && face_boxes_meet(w, f, h) ? mci_leaf_plane_relation(w, f, h) : 0;
        if (relation != 0) {
            faces[n] = h;
            facing[n++] = (int8_t)relation;
        }
    }
    return n;
}

/* One more face h holding a piece of face f: *coin and *first as mci_leaf_piece_stack
 * counts them. A face of f's own sheet holds f's piece only where the sheet overlaps
 * itself (turning more than once about a vertex in its plane): the lower face first. */
static void add_sheet(const mci_leaf_work *w, uint32_t f, uint32_t h, int8_t facing,
                      int32_t *coin, bool *first)
{
    uint64_t kh = w->sheet_key[h - w->face_base], kf = w->sheet_key[f - w->face_base];
    *coin += facing;
    if (facing > 0 && (kh < kf || (kh == kf && h < f)))
        *first = false;
}

void mci_leaf_piece_stack(const mci_leaf_work *w, size_t p, const uint32_t *faces,
                          const int8_t *facing, size_t n, int32_t *coin, bool *first)
{
    mci_point corner[3];
    int axis = n > 0 ? piece_corners(w, p, corner) : -1;
    *coin = 1;
    *first = true;
    for (size_t i = 0; axis >= 0 && i < n; i++)
        if (face_holds_piece(w, faces[i], corner, axis))
            add_sheet(w, w->pface[p], faces[i], facing[i], coin, first);
}

/* A region still unknown where every step into it crosses a sheet lying in one of the
 * two regions (a needle narrower than double-double numbers resolve, between crossing
 * sheets, casts no ray): its numbers carried across each decided neighbour's separator
 * on this leaf, when they all agree, and own_first by the faces covering it. True when
 * it was decided. */
static bool own_from_neighbours(mci_leaf_work *w, uint32_t r)
{
    int32_t front = 0, coin = 0, f, c;
    size_t agreeing = 0;
    for (uint32_t i = w->sep_start[r]; i < w->sep_start[r + 1]; i++) {
        uint32_t k = w->sep_slots[i], from;
        if (w->mate[k] == MCI_NONE || !separator_on_leaf(w, k, w->leaf))
            continue;
        from = w->region[w->mate[k] / 3];
        if (!own_carried(w, k, from, &f, &c))
            continue;
        if (agreeing > 0 && (f != front || c != coin))
            return false;
        front = f, coin = c, agreeing++;
    }
    if (agreeing == 0)
        return false;
    w->own_front[r] = front;
    w->own_coin[r] = coin;
    /* read only where the region bounds the solid */
    w->own_first[r] = front <= 0 && front + coin > 0 && own_first_by_cover(w, r);
    return true;
}

/* This leaf's own numbers still unknown (a region whose pieces give no point to cast a
 * ray from, and the regions reached from it): taken from a neighbour across a
 * separator, changed by the shells of this leaf holding it, until nothing changes; then
 * by own_from_neighbours, and again. */
static void fill_unknown_own(mci_leaf_work *w)
{
    bool changed = true;
    while (changed) {
        changed = false;
        for (uint32_t r = 0; r < w->nreg; r++)
            for (uint32_t i = w->sep_start[r];
                 w->own_front[r] == MCI_WIND_UNKNOWN && i < w->sep_start[r + 1]; i++) {
                uint32_t k = w->sep_slots[i], r2;
                if (w->mate[k] == MCI_NONE)
                    continue; /* a wall */
                r2 = w->region[w->mate[k] / 3];
                if (w->own_front[r2] == MCI_WIND_UNKNOWN)
                    continue;
                if (separator_on_leaf(w, k, w->leaf))
                    local_labels_at(w, r, k, true, r2);
                else
                    own_copy(w, r2, r);
                changed |= w->own_front[r] != MCI_WIND_UNKNOWN;
            }
        for (uint32_t r = 0; !changed && r < w->nreg; r++)
            changed = w->own_front[r] == MCI_WIND_UNKNOWN && own_from_neighbours(w, r);
    }
}

/* memchr first: a leaf that hundreds of others cross (the ring of a ring of spheres) has
 * as many candidates, all needed and labelled. */
static bool has_unknown_label(const mci_leaf_work *w, uint32_t r)
{
    const uint8_t *lab = w->labels + (size_t)r * w->ncand, *end = lab + w->ncand, *at = lab;
    while ((at = memchr(at, MCI_LABEL_UNKNOWN, (size_t)(end - at))) != NULL) {
        if (w->needed[at - lab])
            return true;
        at++;
    }
    return false;
}

/* Labels still unknown after the sweep: a seed's vertices all lie on a leaf (e.g. a
 * face coplanar with that leaf's face), and regions reached from it across curves of
 * other leaves inherited the unknown. They are decided by local tests at the region's
 * own separators on that leaf, if any, and otherwise copied from neighbours across
 * separators not on that leaf, until nothing changes. */
static void fill_unknown_labels(mci_leaf_work *w)
{
    bool changed = true, any = false;
    for (uint32_t r = 0; r < w->nreg; r++)
        if (has_unknown_label(w, r)) {
            seed_by_local_tests(w, r);
            any = any || has_unknown_label(w, r);
        }
    while (changed && any) { /* nearly always none left: no pass over every label */
        changed = false;
        for (uint32_t r = 0; r < w->nreg; r++) {
            uint8_t *lab = w->labels + (size_t)r * w->ncand;
            for (size_t c = 0; c < w->ncand; c++) {
                for (uint32_t i = w->sep_start[r];
                     w->needed[c] && lab[c] == MCI_LABEL_UNKNOWN && i < w->sep_start[r + 1]; i++) {
                    uint32_t k = w->sep_slots[i], r2;
                    uint8_t there;
                    if (w->mate[k] == MCI_NONE)
                        continue; /* a wall */
                    r2 = w->region[w->mate[k] / 3];
                    there = w->labels[(size_t)r2 * w->ncand + c];
                    if (there == MCI_LABEL_UNKNOWN)
                        continue;
                    if (!separator_on_leaf(w, k, w->cand[c])) {
                        lab[c] = there;
                        if (w->cand_winding[c]) {
                            w->wind[(size_t)r * w->ncand + c] = w->wind[(size_t)r2 * w->ncand + c];
                            w->coin[(size_t)r * w->ncand + c] = w->coin[(size_t)r2 * w->ncand + c];
                        }
                    } else if (w->cand_winding[c]) {
                        local_labels_at(w, r, k, true, r2);
                    }
                    changed |= lab[c] != MCI_LABEL_UNKNOWN;
                }
            }
        }
    }
}

/* Winding numbers still unknown after the sweep: its seed's pieces gave no point whose
 * ray decides (every probe on a border of another surface's face), and the regions
 * reached from it inherited the unknown. Any region of the part whose inside decides
 * will do: it is asked, and the sweep's fill carries its numbers to the others. */
static void retry_windings(mci_leaf_work *w)
{
    bool learnt = true;
    while (learnt && !w->out_of_memory) {
        learnt = false;
        for (uint32_t r = 0; r < w->nreg && !learnt && !w->out_of_memory; r++)
            learnt = some_unknown(w, r, true) && mci_leaf_labels_from_inside(w, r, true);
        if (learnt)
            fill_unknown_labels(w);
    }
}

/* Breadth-first over regions across separators, seeding each unreached part. */
static mcsg_status label_regions(mci_leaf_work *w)
{
    uint32_t *queue = mci_malloc_array(w->ctx, w->nreg + 1, sizeof *queue);
    uint8_t *seen = mci_calloc_array(w->ctx, w->nreg + 1, 1);
    size_t head = 0, tail = 0;
    if (!queue || !seen) {
        mci_free(w->ctx, queue);
        mci_free(w->ctx, seen);
        return mci_fail_nomem(w->err, "classifying faces");
    }
    for (uint32_t start = 0; start < w->nreg && !w->out_of_memory; start++) {
        if (seen[start])
            continue;
        seed_region(w, start);
        if (w->own_front && !w->out_of_memory)
            mci_leaf_own_seed(w, start);
        seen[start] = 1;
        queue[tail++] = start;
        while (head < tail) {
            uint32_t r1 = queue[head++];
            for (uint32_t i = w->sep_start[r1]; i < w->sep_start[r1 + 1]; i++) {
                uint32_t k = w->mate[w->sep_slots[i]], r2;
                if (k == MCI_NONE || seen[r2 = w->region[k / 3]])
                    continue; /* a wall, or seen */
                inherit_labels(w, r1, r2, k);
                seen[r2] = 1;
                queue[tail++] = r2;
            }
        }
    }
    mci_free(w->ctx, queue);
    mci_free(w->ctx, seen);
    if (w->out_of_memory)
        return mci_fail_nomem(w->err, "classifying faces");
    fill_unknown_labels(w);
    if (w->wind)
        retry_windings(w);
    if (w->own_front)
        fill_unknown_own(w);
    return MCSG_OK;
}

/* Adds +1 over the node range of each entry's subtree to the difference array cover. */
static void cover_entries(const mci_ptree *t, const mci_csg_entry *list, size_t n,
                          int32_t *cover)
{
    for (size_t i = 0; i < n; i++) {
        uint32_t node = list[i].node;
        cover[node + 1 - t->nodes[node].size]++;
        cover[node + 1]--;
    }
}

/* Copies: leaves that are the same mesh as this one. */

/* A copy B of this leaf P has P's pieces and regions; its labels are P's, with P's
 * own label SAME (the faces coincide, with the same orientation). P's classification
 * therefore also decides B's output, with B's CSGlist. And in P's labels, a candidate
 * that is a copy of another leaf R borrows R's labels (it has no faces in the scene). */
static uint32_t stand_in(const mci_leaf_work *w, uint32_t m)
{
    return mci_scene_leaf_stand_in(w->s, m);
}

/* The copies of this leaf and their trimmed CSGlists (candidates: this leaf's, less the
 * copy, plus this leaf), marked in cover as well. */
static mcsg_status trim_copy_lists(mci_leaf_work *w, int32_t *cover)
{
    const mci_ptree *t = w->cl->tree;
    if (!w->cl->copy_start)
        return MCSG_OK;
    w->copies = w->cl->copy_of + w->cl->copy_start[w->leaf];
    w->ncopies = w->cl->copy_start[w->leaf + 1] - w->cl->copy_start[w->leaf];
    if (w->ncopies == 0)
        return MCSG_OK;
    w->copy_list = mci_calloc_array(w->ctx, w->ncopies, sizeof *w->copy_list);
    w->copy_nlist = mci_calloc_array(w->ctx, w->ncopies, sizeof *w->copy_nlist);
    if (!w->copy_list || !w->copy_nlist)
        return MCSG_ERR_NOMEM;
    for (size_t k = 0; k < w->ncopies; k++) {
        uint32_t b = w->copies[k];
        bool rejected;
        if (!(w->copy_list[k] = mci_malloc_array(w->ctx, t->node_count + 1, sizeof **w->copy_list)))
            return MCSG_ERR_NOMEM;
        w->leaf_labels[b] = MCI_LABEL_OUT;
        w->leaf_labels[w->leaf] = MCI_LABEL_UNKNOWN;
        w->copy_nlist[k] = mci_csglist_trim(t, b, w->leaf_labels, w->scratch, w->copy_list[k],
                                            &rejected);
        w->leaf_labels[b] = MCI_LABEL_UNKNOWN;
        w->leaf_labels[w->leaf] = MCI_LABEL_OUT;
        if (rejected)
            w->copy_nlist[k] = SIZE_MAX; /* none of its faces is kept */
        else
            cover_entries(t, w->copy_list[k], w->copy_nlist[k], cover);
    }
    return MCSG_OK;
}

/* Before labelling: copies of this leaf are SAME everywhere; a copy of another leaf is
 * not labelled itself (it has no faces for rays or separators), that leaf is instead. */
static mcsg_status prepare_copy_labels(mci_leaf_work *w)
{
    if (!w->s->alias)
        return MCSG_OK;
    w->borrowed = mci_calloc_array(w->ctx, w->ncand + 1, 1);
    if (!w->borrowed)
        return mci_fail_nomem(w->err, "classifying faces");
    for (size_t c = 0; c < w->ncand; c++) {
        uint32_t r = stand_in(w, w->cand[c]), rc;
        if (r == w->cand[c])
            continue;
        if (r == w->leaf) {
            for (size_t g = 0; g < w->nreg; g++)
                w->labels[g * w->ncand + c] = MCI_LABEL_SAME;
            continue;
        }
        rc = w->slot_of_leaf[r]; /* a candidate: its box is the copy's */
        if (rc == MCI_NONE)
            return mci_fail(w->err, MCSG_ERR_INTERNAL, "leaf %u: a copy's leaf is no "
                            "candidate", w->leaf);
        w->borrowed[c] = 1 + w->needed[c];
        w->needed[rc] |= w->needed[c];
        w->needed[c] = 0;
    }
    return MCSG_OK;
}

/* After labelling: a copy of another leaf takes that leaf's labels. */
static void finish_copy_labels(mci_leaf_work *w)
{
    for (size_t c = 0; w->borrowed && c < w->ncand; c++) {
        size_t rc;
        if (!w->borrowed[c])
            continue;
        rc = w->slot_of_leaf[stand_in(w, w->cand[c])];
        for (size_t g = 0; g < w->nreg; g++)
            w->labels[g * w->ncand + c] = w->labels[g * w->ncand + rc];
        w->needed[c] = w->borrowed[c] - 1;
    }
}

/* The first trimmed tree (paper §5.2, §5.3): every leaf whose box misses this leaf's is
 * OUT for all its faces. CSGlist entries that this decides are dropped when desired and
 * reject the whole leaf when not; the candidates outside the remaining entries need no
 * labels at all (the paper's pseudo-IPs). */
#ifndef NDEBUG
/* Debug builds check a list made by the whole-face decision against the trimming here. */
static mcsg_status check_trimmed_list(mci_leaf_work *w, const mci_trimmed_list *made)
{
    mci_csg_entry *list = mci_malloc_array(w->ctx, w->cl->tree->node_count + 1, sizeof *list);
    bool rejected, same;
    size_t n;
    if (!list)
        return mci_fail_nomem(w->err, "classifying faces");
    n = mci_csglist_trim(w->cl->tree, w->leaf, w->leaf_labels, w->scratch, list, &rejected);
    same = rejected == made->rejected && (rejected || n == made->count);
    for (size_t i = 0; same && !rejected && i < n; i++)
        same = list[i].node == made->list[i].node && list[i].desired == made->list[i].desired;
    mci_free(w->ctx, list);
    return same ? MCSG_OK
                : mci_fail(w->err, MCSG_ERR_INTERNAL, "primitive %u: the trimmed CSGlist "
                           "handed on differs from its own", w->leaf);
}
#endif

static mcsg_status trim_csglist(mci_leaf_work *w)
{
    const mci_ptree *t = w->cl->tree;
    mci_trimmed_list *made = w->cl->trimmed ? &w->cl->trimmed[w->leaf] : NULL;
    int32_t *cover = mci_calloc_array(w->ctx, t->node_count + 2, sizeof *cover);
    w->list = mci_malloc_array(w->ctx, t->node_count + 1, sizeof *w->list);
    w->scratch = mci_malloc_array(w->ctx, t->node_count + 1, sizeof *w->scratch);
    w->leaf_labels = mci_malloc_array(w->ctx, t->leaf_count + 1, sizeof *w->leaf_labels);
    w->needed = mci_calloc_array(w->ctx, w->ncand + 1, 1);
    if (!cover || !w->list || !w->scratch || !w->leaf_labels || !w->needed) {
        mci_free(w->ctx, cover);
        return mci_fail_nomem(w->err, "classifying faces");
    }
    for (size_t l = 0; l < t->leaf_count; l++)
        w->leaf_labels[l] = MCI_LABEL_OUT;
    for (size_t c = 0; c < w->ncand; c++)
        w->leaf_labels[w->cand[c]] = MCI_LABEL_UNKNOWN;
    if (made && made->valid) { /* the same labels made it: every other leaf is a candidate */
#ifndef NDEBUG
        mcsg_status checked = check_trimmed_list(w, made);
        if (checked != MCSG_OK) {
            mci_free(w->ctx, cover);
            return checked;
        }
#endif
        memcpy(w->list, made->list, made->count * sizeof *w->list);
        w->nlist = made->count;
        w->rejected = made->rejected;
    } else if (!mci_csglist_trim_sparse(w->ctx, t, &w->cl->trim_base, w->leaf, w->cand,
                                        w->ncand, w->list, &w->nlist, &w->rejected)) {
        mci_free(w->ctx, cover);
        return mci_fail_nomem(w->err, "classifying faces");
    }
    if (!w->rejected)
        cover_entries(t, w->list, w->nlist, cover);
    if (trim_copy_lists(w, cover) != MCSG_OK) {
        mci_free(w->ctx, cover);
        return mci_fail_nomem(w->err, "classifying faces");
    }
    for (size_t n = 1; n <= t->node_count; n++)
        cover[n] += cover[n - 1];
    for (size_t c = 0; c < w->ncand; c++)
        w->needed[c] = cover[t->leaf_node[w->cand[c]]] > 0;
    mci_free(w->ctx, cover);
    if (made && made->valid && !w->rejected) { /* taken over: freed with the leaf's work */
        w->blist = made->blist;
        memset(&made->blist, 0, sizeof made->blist);
    } else if (!w->rejected &&
               !mci_blist_build(w->ctx, t, w->list, w->nlist, w->leaf_labels, &w->blist)) {
        return mci_fail_nomem(w->err, "classifying faces");
    }
    /* Every leaf a step reads is UNKNOWN in the trimming labels: a candidate. */
    if (!(w->blist_slot = mci_malloc_array(w->ctx, w->blist.count + 1, sizeof *w->blist_slot)))
        return mci_fail_nomem(w->err, "classifying faces");
    for (size_t i = 0; i < w->blist.count; i++)
        w->blist_slot[i] = w->slot_of_leaf[w->blist.steps[i].leaf];
    return MCSG_OK;
}

mcsg_status mci_leaf_trim(mci_leaf_work *w)
{
    mcsg_status st = find_candidates(w);
    if (st == MCSG_OK)
        st = trim_csglist(w);
    return st;
}

mcsg_status mci_leaf_label(mci_leaf_work *w)
{
    mcsg_status st = prepare_copy_labels(w);
    if (st == MCSG_OK)
        st = label_regions(w);
    finish_copy_labels(w);
    return st;
}
