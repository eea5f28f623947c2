/*
 * Which regions of one leaf belong to the result (the CSGlist evaluated on each region's
 * labels, for the leaf and each copy of it), and their pieces emitted as kept triangles:
 * an arranged face is re-tessellated with its valid constraints only (paper §5.4)
 * before its kept triangles are output.
 */
#include "csg/classify_leaf.h"
#include "csg/retessellate.h"

#include <stdlib.h>
#include <string.h>

static bool grow_kept(const mci_ctx *ctx, mci_kept *kept, size_t need)
{
    size_t cap = kept->capacity;
    if (!mci_grow_array(ctx, (void **)&kept->tris, &cap, need, 3 * sizeof *kept->tris, 1024))
        return false;
    cap = kept->capacity;
    if (!mci_grow_array(ctx, (void **)&kept->faces, &cap, need, sizeof *kept->faces, 1024))
        return false;
    kept->capacity = cap;
    return true;
}

static bool push_triangle(const mci_ctx *ctx, mci_kept *kept, const uint32_t *v,
                          bool reversed, uint32_t face)
{
    uint32_t *tri;
    if (!grow_kept(ctx, kept, kept->count + 1))
        return false;
    tri = kept->tris + 3 * kept->count;
    tri[0] = v[0];
    tri[1] = v[reversed ? 2 : 1];
    tri[2] = v[reversed ? 1 : 2];
    kept->faces[kept->count++] = face;
    return true;
}

/* Who takes kept pieces of this leaf's regions: the leaf itself, and each copy of it
 * (with its own decisions, orientation, output list, and face ids offset by its place). */
typedef struct owner {
    const uint8_t *keep; /* per region */
    bool reversed;
    mci_kept *kept;
    uint32_t face_offset;
    size_t k;            /* w->ncopies for the leaf itself, else the copy's index */
    const uint8_t *piece_keep; /* per piece, where pieces are decided one by one (a
                                  winding leaf with stacks, decide_pieces); else NULL */
} owner;

/* Whether owner o keeps piece p. */
static bool owner_keeps(const mci_leaf_work *w, const owner *o, size_t p)
{
    return o->piece_keep ? o->piece_keep[p] : o->keep[w->region[p]];
}

static int region_accepts(mci_leaf_work *w, uint32_t r, size_t k);
static bool off_own_boundary(const mci_leaf_work *w, uint32_t r);

/* Faces lying where face f does, in a winding leaf (mci_leaf_coincident_faces): a view
 * of w's arrays, n = 0 for a face in no stack (a face that another overlaps in its plane
 * took it into its arrangement: only such faces are listed in w->stacked). */
typedef struct coincident {
    const uint32_t *faces;
    const int8_t *facing;
    size_t n;
} coincident;

static coincident coincident_faces(const mci_leaf_work *w, uint32_t f)
{
    const mci_face_arr *arr = mci_scene_arr_of_face(w->s, f);
    coincident c = {NULL, NULL, 0};
    if (w->stacked && arr && arr->coplanar) {
        uint32_t *faces = w->stacked + w->nstacked;
        c.n = mci_leaf_coincident_faces(w, f, faces, w->stacked_facing);
        c.faces = faces;
        c.facing = w->stacked_facing;
    }
    return c;
}

/* Whether owner o keeps piece p: its region's decision, with the stack the piece lies
 * in (own: whether the piece bounds the leaf's solid by its own stack, as
 * mci_leaf_piece_stack counts it) in place of the region's; where that turns the piece
 * into a border of the leaf's solid, the region's CSGlist decides. */
static bool piece_kept(mci_leaf_work *w, const owner *o, size_t p, bool own)
{
    uint32_t r = w->region[p];
    int accepts;
    if (own == !off_own_boundary(w, r))
        return o->keep[r];
    if (!own || (o->k == w->ncopies ? w->rejected : w->copy_nlist[o->k] == SIZE_MAX))
        return false;
    accepts = region_accepts(w, r, o->k);
    if (o->k != w->ncopies)
        w->leaf_labels[w->leaf] = MCI_LABEL_OUT; /* as trimming left it */
    return accepts == 1;
}

/* The kept triangles of arranged face f, whose pieces start at piece `first`, after
 * re-tessellating it with its valid constraints only. */
static mcsg_status emit_arranged_face(mci_leaf_work *w, uint32_t f, size_t first, const owner *o)
{
    mci_face_arr *arr = &w->cl->scene->arrs[w->s->arr_of[f]];
    const uint32_t *gid = w->s->gid + w->s->gid_start[w->s->arr_of[f]];
    uint8_t stack_keep[2 * 256]; /* piece and triangle flags: most faces allocate none */
    uint8_t *piece_keep = arr->tri_count <= 256 ? stack_keep
                                                : mci_malloc_array(w->ctx, 2 * arr->tri_count, 1);
    uint8_t *tri_keep = piece_keep ? piece_keep + arr->tri_count : NULL;
    mcsg_status st = piece_keep ? MCSG_OK : mci_fail_nomem(w->err, "classifying faces");
    for (size_t i = 0; st == MCSG_OK && i < arr->tri_count; i++)
        piece_keep[i] = owner_keeps(w, o, first + i);
    if (st == MCSG_OK)
        st = mci_arr_retessellate(w->ctx, arr, piece_keep, tri_keep, w->err);
    for (size_t t = 0; st == MCSG_OK && t < arr->tri_count; t++) {
        uint32_t v[3];
        if (!tri_keep[t])
            continue;
        for (int i = 0; i < 3; i++)
            v[i] = gid[arr->tris[3 * t + i]];
        if (!push_triangle(w->ctx, o->kept, v, o->reversed, f + o->face_offset))
            st = mci_fail_nomem(w->err, "classifying faces");
    }
    if (piece_keep != stack_keep)
        mci_free(w->ctx, piece_keep);
    return st;
}

/* A face whose pieces go to several owners (a leaf and a copy of it, each keeping a
 * part): each takes its pieces as tessellated with all constraints (re-tessellating for
 * one would change the pieces of the other). */
static mcsg_status emit_shared_face(mci_leaf_work *w, uint32_t f, size_t first,
                                    const owner *owners, size_t n)
{
    const mci_face_arr *arr = mci_scene_arr_of_face(w->s, f);
    for (size_t k = 0; k < n; k++)
        for (size_t p = first; p < first + arr->tri_count; p++)
            if (owner_keeps(w, &owners[k], p) &&
                !push_triangle(w->ctx, owners[k].kept, w->pv + 3 * p, owners[k].reversed,
                               f + owners[k].face_offset))
                return mci_fail_nomem(w->err, "classifying faces");
    return MCSG_OK;
}

/* The owner keeping pieces of the face [first, first + count), the number of such owners
 * in *n. */
static const owner *face_owner(const mci_leaf_work *w, size_t first, size_t count,
                               const owner *owners, size_t n_owners, size_t *n)
{
    const owner *found = NULL;
    *n = 0;
    for (size_t k = 0; k < n_owners; k++)
        for (size_t p = first; p < first + count; p++)
            if (owner_keeps(w, &owners[k], p)) {
                found = &owners[k];
                ++*n;
                break;
            }
    return found;
}

static mcsg_status emit_kept(mci_leaf_work *w, const owner *owners, size_t n_owners)
{
    mcsg_status st = MCSG_OK;
    size_t p = 0;
    while (p < w->np && st == MCSG_OK) {
        uint32_t f = w->pface[p];
        const mci_face_arr *arr = mci_scene_arr_of_face(w->s, f);
        if (arr) {
            size_t n = arr->tri_count, takers;
            const owner *o = face_owner(w, p, n, owners, n_owners, &takers);
            if (takers == 1)
                st = emit_arranged_face(w, f, p, o);
            else if (takers > 1)
                st = emit_shared_face(w, f, p, owners, n_owners);
            p += n;
            continue;
        }
        for (size_t k = 0; k < n_owners && st == MCSG_OK; k++)
            if (owner_keeps(w, &owners[k], p) &&
                !push_triangle(w->ctx, owners[k].kept, w->pv + 3 * p, owners[k].reversed,
                               f + owners[k].face_offset))
                st = mci_fail_nomem(w->err, "classifying faces");
        p++;
    }
    return st;
}

/* Labels of region r for the CSGlist of leaf `as` (this leaf or a copy of it): this
 * leaf is SAME for a copy; reversed for a complemented leaf. */
static void region_labels(mci_leaf_work *w, size_t r, uint32_t as)
{
    const mci_ptree *t = w->cl->tree;
    bool reversed = t->nodes[t->leaf_node[as]].complement;
    const uint8_t *lab = w->labels + r * w->ncand;
    for (size_t c = 0; c < w->ncand; c++)
        w->leaf_labels[w->cand[c]] = (mci_label)lab[c];
    if (as != w->leaf)
        w->leaf_labels[w->leaf] = MCI_LABEL_SAME;
    for (size_t c = 0; reversed && c < w->ncand; c++)
        w->leaf_labels[w->cand[c]] = mci_label_reverse(w->leaf_labels[w->cand[c]]);
    if (reversed && as != w->leaf)
        w->leaf_labels[w->leaf] = mci_label_reverse(w->leaf_labels[w->leaf]);
}

/* Whether region r is kept, for this leaf or its copy k (-1: its labels do not tell). */
/* The blist on region r's own labels (mci_blist_accepts without spreading them over the
 * leaves first: a leaf that hundreds of others cross has as many candidates, and a walk
 * reads a few). */
static int region_blist_accepts(const mci_leaf_work *w, uint32_t r)
{
    const uint8_t *lab = w->labels + (size_t)r * w->ncand;
    int32_t at = w->blist.start;
    while (at >= 0) {
        const mci_blist_step *step = &w->blist.steps[at];
        uint8_t l = lab[w->blist_slot[at]];
        if (l == MCI_LABEL_IN)
            at = step->on_in;
        else if (l == MCI_LABEL_OUT)
            at = step->on_out;
        else
            return -1;
    }
    return at == MCI_BLIST_ACCEPT;
}

static int region_accepts(mci_leaf_work *w, uint32_t r, size_t k)
{
    const mci_ptree *t = w->cl->tree;
    bool self = k == w->ncopies;
    /* IN and OUT do not depend on orientation: reversing the labels changes none of
     * those the blist reads. */
    int accepts = self ? region_blist_accepts(w, r) : -1;
    if (accepts >= 0)
        return accepts;
    /* Labels on a coplanar face (SAME / OPPO) need the combination rules. */
    region_labels(w, r, self ? w->leaf : w->copies[k]);
    return self ? mci_csglist_accepts(t, w->list, w->nlist, w->leaf_labels, w->scratch)
                : mci_csglist_accepts(t, w->copy_list[k], w->copy_nlist[k], w->leaf_labels,
                                      w->scratch);
}

/* Whether region r bounds nothing of this leaf's solid facing its way: the winding
 * number is positive on both sides or on neither, or positive only in front (another
 * face of the leaf lying in the region, facing the other way, bounds it), or another
 * shell facing this way lies in the region and comes first (mci_leaf_work.own_first). */
static bool off_own_boundary(const mci_leaf_work *w, uint32_t r)
{
    return w->own_front && !(w->own_front[r] <= 0 && w->own_front[r] + w->own_coin[r] > 0 &&
                             w->own_first[r]);
}

/* keep[r] for every region, for this leaf (k = ncopies) or its copy k. */
static mcsg_status decide_regions(mci_leaf_work *w, size_t k, uint8_t *keep)
{
    bool self = k == w->ncopies, rejected = self ? w->rejected : w->copy_nlist[k] == SIZE_MAX;
    for (uint32_t r = 0; r < w->nreg; r++) {
        int accepts = 0;
        if (w->own_front && w->own_front[r] == MCI_WIND_UNKNOWN)
            return mci_fail(w->err, MCSG_ERR_INTERNAL, "leaf %u: the winding number of a "
                            "region could not be decided", w->leaf);
        if (!rejected && !off_own_boundary(w, r)) {
            accepts = region_accepts(w, r, k);
            if (accepts < 0 && mci_leaf_labels_from_inside(w, r, false))
                accepts = region_accepts(w, r, k);
            if (w->out_of_memory)
                return mci_fail_nomem(w->err, "classifying faces");
            if (accepts < 0)
                return mci_fail(w->err, MCSG_ERR_INTERNAL,
                                "leaf %u: a region's label could not be decided", w->leaf);
        }
        keep[r] = accepts == 1;
    }
    if (!self)
        w->leaf_labels[w->leaf] = MCI_LABEL_OUT; /* as trimming left it */
    return MCSG_OK;
}

/* w->sheet_key (see classify_leaf.h): faces joined across edges to their neighbours in
 * the same plane facing the same way (mci_leaf_plane_relation 1; a face folded back
 * onto the same side faces the other way, and its edge bounds the sheet). */
static mcsg_status find_sheets(mci_leaf_work *w)
{
    uint32_t n = w->face_count, base = w->face_base;
    uint32_t *parent = mci_malloc_array(w->ctx, n + 1, sizeof *parent);
    w->sheet_key = mci_malloc_array(w->ctx, n + 1, sizeof *w->sheet_key);
    if (!parent || !w->sheet_key) {
        mci_free(w->ctx, parent);
        return mci_fail_nomem(w->err, "classifying faces");
    }
    for (uint32_t f = 0; f < n; f++) {
        parent[f] = f;
        w->sheet_key[f] = UINT64_MAX;
    }
    for (uint32_t f = 0; f < n; f++)
        for (int k = 0; k < 3; k++) {
            uint32_t nb = w->s->neighbour[3 * (size_t)(base + f) + k];
            if (nb != MCI_NONE && nb > base + f && nb < base + n &&
                mci_leaf_plane_relation(w, base + f, nb) == 1)
                parent[mci_find_root(parent, nb - base)] = mci_find_root(parent, f);
        }
    for (uint32_t f = 0; f < n; f++) {
        uint32_t root = mci_find_root(parent, f);
        uint64_t key = (uint64_t)mci_octree_face_group(&w->s->octree, base + f) << 32 | f;
        if (key < w->sheet_key[root])
            w->sheet_key[root] = key;
    }
    for (uint32_t f = 0; f < n; f++)
        w->sheet_key[f] = w->sheet_key[mci_find_root(parent, f)];
    mci_free(w->ctx, parent);
    return MCSG_OK;
}

/* w->stacked for a winding leaf: its faces whose arrangement took a coplanar face (and
 * room for as many, for mci_leaf_coincident_faces), and the sheets of its faces. */
static mcsg_status list_stacked_faces(mci_leaf_work *w)
{
    size_t n = 0;
    for (uint32_t h = w->face_base; h < w->face_base + w->face_count; h++) {
        const mci_face_arr *arr = mci_scene_arr_of_face(w->s, h);
        n += arr && arr->coplanar;
    }
    if (n == 0)
        return MCSG_OK;
    w->stacked = mci_malloc_array(w->ctx, 2 * n, sizeof *w->stacked);
    w->stacked_facing = mci_malloc_array(w->ctx, n, sizeof *w->stacked_facing);
    if (!w->stacked || !w->stacked_facing)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t h = w->face_base; h < w->face_base + w->face_count; h++) {
        const mci_face_arr *arr = mci_scene_arr_of_face(w->s, h);
        if (arr && arr->coplanar)
            w->stacked[w->nstacked++] = h;
    }
    return find_sheets(w);
}

/* In a winding leaf whose faces lie in stacks of coincident sheets, each piece decided
 * with the stack it lies in (piece_kept): a region's own_coin and own_first are those at
 * its seed, and a region can reach beyond the stack its seed lies in (a face in a stack
 * is joined to same-facing faces of its plane, and their pieces to pieces under fewer
 * sheets). Sets each owner's piece_keep (*out: the array, n x np). */
static mcsg_status decide_pieces(mci_leaf_work *w, owner *owners, size_t n, uint8_t **out)
{
    uint8_t *keep = mci_malloc_array(w->ctx, n * w->np + 1, 1);
    if (!(*out = keep))
        return mci_fail_nomem(w->err, "classifying faces");
    for (size_t p = 0, end; p < w->np; p = end) {
        uint32_t f = w->pface[p];
        coincident c = coincident_faces(w, f);
        for (end = p; end < w->np && w->pface[end] == f; end++) {
            int32_t coin, front = w->own_front[w->region[end]];
            bool first, own;
            mci_leaf_piece_stack(w, end, c.faces, c.facing, c.n, &coin, &first);
            own = front <= 0 && front + coin > 0 && first;
            for (size_t k = 0; k < n; k++)
                keep[k * w->np + end] = piece_kept(w, &owners[k], end, own);
        }
    }
    for (size_t k = 0; k < n; k++)
        owners[k].piece_keep = keep + k * w->np;
    return w->out_of_memory ? mci_fail_nomem(w->err, "classifying faces") : MCSG_OK;
}

/* Evaluate each region's CSGlist (this leaf's and its copies') and output the pieces of
 * the kept ones. */
mcsg_status mci_leaf_select(mci_leaf_work *w)
{
    const mci_ptree *t = w->cl->tree;
    size_t n = w->ncopies + 1;
    owner *owners = mci_malloc_array(w->ctx, n, sizeof *owners);
    uint8_t *keep = mci_malloc_array(w->ctx, n * (w->nreg + 1), 1);
    uint8_t *piece_keep = NULL;
    mcsg_status st = owners && keep ? MCSG_OK : mci_fail_nomem(w->err, "classifying faces");
    if (st == MCSG_OK && t->leaf_winding[w->leaf])
        st = list_stacked_faces(w);
    for (size_t k = 0; k < n && st == MCSG_OK; k++) {
        uint32_t as = k == 0 ? w->leaf : w->copies[k - 1];
        owners[k] = (owner){keep + k * (w->nreg + 1), t->nodes[t->leaf_node[as]].complement,
                            &w->kept_all[as],
                            w->s->octree.face_base[as] - w->s->octree.face_base[w->leaf],
                            k == 0 ? w->ncopies : k - 1, NULL};
        st = decide_regions(w, k == 0 ? w->ncopies : k - 1, keep + k * (w->nreg + 1));
    }
    if (st == MCSG_OK && w->stacked)
        st = decide_pieces(w, owners, n, &piece_keep);
    st = st == MCSG_OK ? emit_kept(w, owners, n) : st;
    mci_free(w->ctx, owners);
    mci_free(w->ctx, keep);
    mci_free(w->ctx, piece_keep);
    return st;
}
