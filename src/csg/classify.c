/*
 * Classification (paper §5) on the split, triangulated scene.
 *
 * Pieces: each leaf's surface is cut into pieces, the sub-triangles of its arranged
 * faces and its untouched faces whole. Their vertices carry output ids (global point
 * numbers), so pieces of one leaf meet along identical edges.
 *
 * Regions (the paper's intra-primitive groups, §5.2): pieces joined across every edge
 * that is not a separator. A separator is an elementary edge of an arrangement, i.e.
 * it lies on the surface of another leaf. A region's interior meets no other leaf's
 * surface, except coplanar regions lying wholly on it, so its label with respect to
 * every other leaf is constant.
 *
 * Labels: a first region (per connected part of a leaf) gets its labels by exact ray
 * shooting (the first seeds, §5.5); the others inherit them across separators, which
 * changes only the labels with respect to the leaves whose surface holds that separator
 * (Prop. 2). Those are decided by an exact local test at the separator: the side of the
 * piece's far vertex with respect to the face(s) of the other leaf containing the edge
 * (a wedge test when the edge lies along an edge of that leaf), and SAME / OPPO by the
 * orientations of coplanar faces.
 *
 * Only leaves whose bounding box meets this leaf's can have another label than OUT.
 *
 * This file holds what is built once for the whole scene (output vertex ids, the leaves'
 * boxes and copies) and runs each leaf's classification (classify_leaf.h lists its
 * steps and their files); rays.c and local_test.c decide the labels exactly.
 */
#include "csg/classify.h"
#include "csg/classify_leaf.h"
#include "csg/leaf_boxes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct coord_table {
    const double **key;
    uint32_t *value;
    size_t size;
} coord_table;

/* The id stored for coordinates x, or `fresh` after storing it. */
static uint32_t coord_lookup(coord_table *t, const double *x, uint32_t fresh)
{
    size_t at = mci_coordinate_hash(x) & (t->size - 1);
    while (t->key[at]) {
        const double *k = t->key[at];
        if (k[0] == x[0] && k[1] == x[1] && k[2] == x[2])
            return t->value[at];
        at = (at + 1) & (t->size - 1);
    }
    t->key[at] = x;
    t->value[at] = fresh;
    return fresh;
}

static bool assign_vertex_ids(const mci_ctx *ctx, mci_classifier *cl)
{
    const mci_scene *s = cl->scene;
    const mci_octree *o = &s->octree;
    size_t total = 0, size = 16;
    coord_table t;
    uint8_t *seen;
    bool ok;
    for (size_t l = 0; l < o->leaf_count; l++)
        total += o->leaves[l]->vertex_count;
    while (size < 2 * (total + s->point_count)) /* keys: numbers once, then leaf vertices */
        size *= 2;
    t.size = size;
    t.key = mci_calloc_array(ctx, size, sizeof *t.key);
    t.value = mci_malloc_array(ctx, size, sizeof *t.value);
    cl->vertex_first = mci_malloc_array(ctx, o->leaf_count + 1, sizeof *cl->vertex_first);
    cl->vertex_id = mci_malloc_array(ctx, total + 1, sizeof *cl->vertex_id);
    cl->new_vertex = mci_malloc_array(ctx, total + 1, sizeof *cl->new_vertex);
    seen = mci_calloc_array(ctx, s->point_count / 8 + 1, 1);
    ok = t.key && t.value && cl->vertex_first && cl->vertex_id && cl->new_vertex && seen &&
         s->point_count + total < UINT32_MAX;
    /* Equal coordinates have one number (point numbering joined them): each number is
     * stored once, found through the numbering's bytes, not by reading every point. */
    for (size_t k = 0; ok && k < s->arr_count; k++)
        for (size_t p = 0, slot = s->gid_start[k]; p < s->arrs[k].point_count; p++, slot++) {
            uint32_t g = s->gid[slot];
            if (!s->explicit_slot[slot] || (seen[g / 8] >> (g % 8)) & 1)
                continue;
            seen[g / 8] |= (uint8_t)(1u << (g % 8));
            coord_lookup(&t, s->arrs[k].points[p]->v[0], g);
        }
    mci_free(ctx, seen);
    for (size_t l = 0, at = 0; ok && l < o->leaf_count; l++) {
        const mcsg_mesh *m = o->leaves[l];
        cl->vertex_first[l] = at;
        for (size_t v = 0; v < m->vertex_count; v++, at++) {
            uint32_t fresh = (uint32_t)(s->point_count + cl->new_vertex_count);
            uint32_t id = coord_lookup(&t, m->vertices + 3 * v, fresh);
            if (id == fresh)
                cl->new_vertex[cl->new_vertex_count++] = m->vertices + 3 * v;
            cl->vertex_id[at] = id;
        }
    }
    mci_free(ctx, t.key);
    mci_free(ctx, t.value);
    return ok;
}

/* copy_start / copy_of from scene->alias (a counting sort). */
static bool index_copies(const mci_ctx *ctx, mci_classifier *cl)
{
    const mci_scene *s = cl->scene;
    size_t n = s->octree.leaf_count;
    if (!s->alias)
        return true;
    cl->copy_start = mci_calloc_array(ctx, n + 2, sizeof *cl->copy_start);
    cl->copy_of = mci_malloc_array(ctx, n + 1, sizeof *cl->copy_of);
    if (!cl->copy_start || !cl->copy_of)
        return false;
    for (size_t l = 0; l < n; l++)
        cl->copy_start[s->alias[l] + 2] += s->alias[l] != l;
    for (size_t l = 2; l < n + 2; l++)
        cl->copy_start[l] += cl->copy_start[l - 1];
    for (uint32_t l = 0; l < n; l++)
        if (s->alias[l] != l)
            cl->copy_of[cl->copy_start[s->alias[l] + 1]++] = l;
    return true;
}

mcsg_status mci_classifier_init(const mci_ctx *ctx, mci_scene *scene,
                                const mci_ptree *tree, mci_classifier *cl, mcsg_error *err)
{
    memset(cl, 0, sizeof *cl);
    cl->scene = scene;
    cl->tree = tree;
    cl->box = mci_malloc_array(ctx, scene->octree.leaf_count + 1, sizeof *cl->box);
    if (!cl->box || !assign_vertex_ids(ctx, cl) || !index_copies(ctx, cl)) {
        mci_classifier_free(ctx, cl);
        return mci_fail_nomem(err, "classifying faces");
    }
    for (size_t l = 0; l < scene->octree.leaf_count; l++)
        mci_leaf_box(scene->octree.leaves[l], cl->box[l]);
    if (!mci_box_overlaps(ctx, (const double (*)[6])cl->box, scene->octree.leaf_count,
                          &cl->overlap_start, &cl->overlap) ||
        !mci_trim_base_init(ctx, tree, &cl->trim_base)) {
        mci_classifier_free(ctx, cl);
        return mci_fail_nomem(err, "classifying faces");
    }
    return MCSG_OK;
}

void mci_classifier_free(const mci_ctx *ctx, mci_classifier *cl)
{
    mci_free(ctx, cl->vertex_first);
    mci_free(ctx, cl->vertex_id);
    mci_free(ctx, cl->new_vertex);
    mci_free(ctx, cl->box);
    mci_free(ctx, cl->overlap_start);
    mci_free(ctx, cl->overlap);
    mci_trim_base_free(ctx, &cl->trim_base);
    mci_free(ctx, cl->copy_start);
    mci_free(ctx, cl->copy_of);
    memset(cl, 0, sizeof *cl);
}

void mci_kept_free(const mci_ctx *ctx, mci_kept *kept)
{
    mci_free(ctx, kept->tris);
    mci_free(ctx, kept->faces);
    memset(kept, 0, sizeof *kept);
}

/* ---------------------------------------------------------------------------------- */
/* One leaf                                                                            */

static void free_work(mci_leaf_work *w)
{
    void *all[] = {w->pv, w->pface, w->plocal, w->mate, w->is_sep, w->sep, w->walls, w->region,
                   w->reg_start, w->reg_pieces, w->sep_start, w->sep_slots, w->cand,
                   w->slot_of_leaf, w->labels, w->needed, w->list, w->scratch,
                   w->leaf_labels, w->blist_slot, w->cand_winding, w->wind, w->coin, w->own_front,
                   w->own_coin, w->own_first, w->stacked, w->stacked_facing,
                   w->sheet_key};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        mci_free(w->ctx, all[i]);
    for (size_t k = 0; w->copy_list && k < w->ncopies; k++)
        mci_free(w->ctx, w->copy_list[k]);
    mci_free(w->ctx, w->copy_list);
    mci_free(w->ctx, w->copy_nlist);
    mci_free(w->ctx, w->borrowed);
    mci_blist_free(w->ctx, &w->blist);
    mci_ray_scratch_free(w->ctx, &w->ray);
}

mcsg_status mci_classify_leaf(const mci_ctx *ctx, const mci_classifier *cl, uint32_t leaf,
                              mci_kept *kept, mci_classify_stats *stats, mcsg_error *err)
{
    mci_leaf_work w;
    mcsg_status st;
    if (mci_scene_leaf_stand_in(cl->scene, leaf) != leaf)
        return MCSG_OK; /* a copy: the leaf it copies outputs its pieces too */
    memset(&w, 0, sizeof w);
    w.kept_all = kept;
    w.ctx = ctx;
    w.cl = cl;
    w.s = cl->scene;
    w.leaf = leaf;
    w.face_base = w.s->octree.face_base[leaf];
    w.face_count = w.s->octree.face_base[leaf + 1] - w.face_base;
    w.stats = stats;
    w.err = err;
    st = mci_leaf_regions(&w);
    if (st == MCSG_OK)
        st = mci_leaf_trim(&w);
    if (st == MCSG_OK && (!w.rejected || w.ncopies > 0)) {
        st = mci_leaf_label(&w);
        if (st == MCSG_OK)
            st = mci_leaf_select(&w);
    }
    stats->rejected_leaves += w.rejected;
    stats->pieces += w.np;
    stats->regions += w.nreg;
    free_work(&w);
    return st;
}
