/*
 * Faces dropped whole, decided from the pair tests before they are arranged (paper
 * §5.2-5.3: the second trimmed tree of a group of faces decides it without sub-face work).
 *
 * A touched face meets the surfaces of a few leaves only (mci_scene's touch lists: the
 * pair tests report every contact). With respect to any other leaf M the face lies wholly
 * inside or wholly outside, and so does every face of its leaf connected to it through
 * faces that do not meet M either (their union is connected and misses M's surface).
 * Those labels alone often decide the face: buried in a leaf that a union adds, or
 * outside one that an intersection keeps, it is dropped whatever the leaves crossing it
 * say. Such a face needs no arrangement, no tessellation with its constraints, and no
 * classification of its pieces: in dense scenes, a large share of the touched faces.
 *
 * For a leaf P and each leaf M that P's trimmed CSGlist reads (mci_blist), the faces of
 * P that do not meet M are joined by their shared vertices (union-find on vertex
 * indices); a group is OUT when one of its vertices lies outside M's bounding box, and
 * otherwise takes the label of an exact ray from one of its vertices (none lies on M's
 * surface). A face is dropped when no value of its unknown labels (those of the leaves
 * it meets) would keep it (a forward sweep of the Blist). Everything is exact; a face that is not
 * decided here goes through the whole classification as before.
 */
#include "csg/whole_faces.h"
#include "base/parallel.h"
#include "csg/leaf_boxes.h"
#include "csg/rays.h"

#include <string.h>

typedef struct decide_job {
    const mci_ctx *ctx;
    mci_scene *s;
    const mci_ptree *t;
    const double (*box)[6]; /* per leaf */
    const uint32_t *overlap_start, *overlap; /* per leaf: the leaves whose boxes meet it */
    const mci_trim_base *trim_base;
    size_t *dropped;        /* per leaf: faces flagged */
    uint8_t *copied;        /* per leaf: another leaf is a copy of it (NULL: none is) */
    mci_trimmed_list *keep; /* per leaf: where its trimmed list goes (NULL: nowhere) */
} decide_job;

/* One leaf's decision. Vertex arrays are indexed by the leaf mesh's vertex index. */
typedef struct leaf_decision {
    const decide_job *j;
    uint32_t leaf, face_base;
    const mcsg_mesh *m;
    uint32_t *faces;         /* the leaf's touched faces (global ids) ... */
    size_t nfaces;
    mci_csg_entry *list;
    size_t nlist;
    mci_label *leaf_labels;
    mci_blist blist;         /* each step reads one leaf, no two the same leaf */
    uint32_t *reached, sweep; /* per step: the last sweep (face) that reached it */
    double (*face_box)[6];   /* per touched face */
    uint32_t *vf_start, *vf_face; /* faces around each vertex (CSR) */
    uint32_t *seen;          /* per face: the last search that reached it */
    uint8_t *memo;           /* per step and touched face: 1 + the label found by a search,
                                or 0 */
    bool no_search;          /* the memo would be too large: searched labels stay unknown */
    uint32_t *queue, search;
    mci_ray_scratch ray;
} leaf_decision;

static bool boxes_meet(const double a[6], const double b[6])
{
    for (int k = 0; k < 3; k++)
        if (a[3 + k] < b[k] || b[3 + k] < a[k])
            return false;
    return true;
}

static void triangle_box(const mcsg_mesh *m, const uint32_t *tri, double box[6])
{
    for (int k = 0; k < 3; k++) {
        double a = m->vertices[3 * (size_t)tri[0] + k], b = m->vertices[3 * (size_t)tri[1] + k],
               c = m->vertices[3 * (size_t)tri[2] + k];
        box[k] = a < b ? (a < c ? a : c) : (b < c ? b : c);
        box[3 + k] = a > b ? (a > c ? a : c) : (b > c ? b : c);
    }
}

/* Strictly outside the closed box: outside the leaf it bounds. */
static bool outside_box(const double *x, const double box[6])
{
    for (int k = 0; k < 3; k++)
        if (x[k] < box[k] || x[k] > box[3 + k])
            return true;
    return false;
}

static void free_decision(leaf_decision *d)
{
    const mci_ctx *ctx = d->j->ctx;
    void *all[] = {d->faces, d->list, d->leaf_labels, d->reached, d->face_box,
                   d->vf_start, d->vf_face, d->seen, d->memo, d->queue};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++)
        mci_free(ctx, all[i]);
    mci_blist_free(ctx, &d->blist);
    mci_ray_scratch_free(ctx, &d->ray);
}

/* The trimmed CSGlist of the leaf (every leaf whose box misses the leaf's is OUT), its
 * blist and the leaves it reads. False when out of memory. */
static bool trim_list(leaf_decision *d, bool *rejected)
{
    const mci_ptree *t = d->j->t;
    const decide_job *j = d->j;
    d->list = mci_malloc_array(j->ctx, t->node_count + 1, sizeof *d->list);
    d->leaf_labels = mci_malloc_array(j->ctx, t->leaf_count + 1, sizeof *d->leaf_labels);
    if (!d->list || !d->leaf_labels)
        return false;
    for (uint32_t l = 0; l < t->leaf_count; l++)
        d->leaf_labels[l] = MCI_LABEL_OUT;
    for (uint32_t i = j->overlap_start[d->leaf]; i < j->overlap_start[d->leaf + 1]; i++)
        d->leaf_labels[j->overlap[i]] = MCI_LABEL_UNKNOWN;
    if (!mci_csglist_trim_sparse(j->ctx, t, j->trim_base, d->leaf,
                                 j->overlap + j->overlap_start[d->leaf],
                                 j->overlap_start[d->leaf + 1] - j->overlap_start[d->leaf],
                                 d->list, &d->nlist, rejected))
        return false;
    if (*rejected)
        return true;
    if (!mci_blist_build(j->ctx, t, d->list, d->nlist, d->leaf_labels, &d->blist))
        return false;
    d->reached = mci_calloc_array(j->ctx, d->blist.count + 1, sizeof *d->reached);
    return d->reached != NULL;
}

/* Faces around each vertex of the leaf mesh (CSR), for the searches below. */
static bool index_vertex_faces(leaf_decision *d)
{
    const mcsg_mesh *m = d->m;
    size_t nt = m->triangle_count;
    d->vf_start = mci_calloc_array(d->j->ctx, m->vertex_count + 2, sizeof *d->vf_start);
    d->vf_face = mci_malloc_array(d->j->ctx, 3 * nt + 1, sizeof *d->vf_face);
    if (!d->vf_start || !d->vf_face)
        return false;
    for (size_t i = 0; i < 3 * nt; i++)
        d->vf_start[m->triangles[i] + 2]++;
    for (size_t v = 2; v < m->vertex_count + 2; v++)
        d->vf_start[v] += d->vf_start[v - 1];
    for (size_t i = 0; i < 3 * nt; i++)
        d->vf_face[d->vf_start[m->triangles[i] + 1]++] = (uint32_t)(i / 3);
    return true;
}

/* Whether face f (local) has a vertex outside leaf m's box: then f, and every face
 * joined to it through faces that do not meet m, is outside m. */
static bool reaches_outside(const leaf_decision *d, uint32_t f, const double mbox[6])
{
    const uint32_t *tri = d->m->triangles + 3 * (size_t)f;
    for (int i = 0; i < 3; i++)
        if (outside_box(d->m->vertices + 3 * (size_t)tri[i], mbox))
            return true;
    return false;
}

/* The label of local face f (which does not meet leaf m) with respect to m: a search
 * over the faces joined to it by shared vertices, through faces that do not meet m,
 * stops at the first one reaching outside m's box (OUT); a group wholly inside the box
 * takes the label of a ray from one of its vertices (none lies on m's surface). Every
 * face the search reaches gets the same label, so later faces of the group are free. */
/* Bytes the memo of one leaf may take (beyond, its faces are left to the classification
 * rather than failing or taking memory out of proportion: a big model read against
 * hundreds of leaves). */
#define MEMO_LIMIT ((size_t)1 << 26)

/* The search's arrays, made at the first search (most leaves need none: their touched
 * faces meet the leaves their CSGlist reads, as in a difference of two models). */
static bool prepare_search(leaf_decision *d)
{
    size_t nt = d->m->triangle_count + 1;
    if (d->queue || d->no_search)
        return true;
    if (d->blist.count > MEMO_LIMIT / d->nfaces) {
        d->no_search = true;
        return true;
    }
    d->seen = mci_calloc_array(d->j->ctx, nt, sizeof *d->seen);
    d->memo = mci_calloc_array(d->j->ctx, d->blist.count * d->nfaces, 1);
    d->queue = mci_malloc_array(d->j->ctx, nt, sizeof *d->queue);
    return d->seen && d->memo && d->queue && index_vertex_faces(d);
}

/* The memo slot of local face f, or NULL when f is not touched. The touched faces of a
 * leaf have consecutive arrangement numbers, in face order, as d->faces lists them. */
static uint8_t *memo_slot(const leaf_decision *d, uint8_t *row, uint32_t f)
{
    const mci_scene *s = d->j->s;
    uint32_t a = s->arr_of[d->face_base + f];
    return a == MCI_NONE ? NULL : row + (a - s->arr_of[d->faces[0]]);
}

static bool group_label(leaf_decision *d, uint32_t f, size_t r, uint8_t *label)
{
    uint32_t m = mci_scene_leaf_stand_in(d->j->s, d->blist.steps[r].leaf);
    const double *mbox = d->j->box[m];
    size_t head = 0, tail = 0;
    uint8_t result = MCI_LABEL_UNKNOWN;
    uint8_t *memo, *slot;
    if (!prepare_search(d))
        return false;
    if (d->no_search) {
        *label = MCI_LABEL_UNKNOWN;
        return true;
    }
    memo = d->memo + r * d->nfaces;
    slot = memo_slot(d, memo, f);
    if (*slot) {
        *label = (uint8_t)(*slot - 1);
        return true;
    }
    d->search++; /* a fresh search: its marks are new */
    d->seen[f] = d->search;
    d->queue[tail++] = f;
    while (head < tail && result == MCI_LABEL_UNKNOWN) {
        uint32_t g = d->queue[head++];
        const uint32_t *tri = d->m->triangles + 3 * (size_t)g;
        if (reaches_outside(d, g, mbox)) {
            result = MCI_LABEL_OUT;
            break;
        }
        for (int i = 0; i < 3; i++)
            for (uint32_t k = d->vf_start[tri[i]]; k < d->vf_start[tri[i] + 1]; k++) {
                uint32_t h = d->vf_face[k];
                if (d->seen[h] == d->search ||
                    mci_scene_face_touches(d->j->s, d->face_base + h, m))
                    continue;
                d->seen[h] = d->search;
                d->queue[tail++] = h;
            }
    }
    if (result == MCI_LABEL_UNKNOWN) {
        mci_point p;
        mci_label l;
        mci_point_explicit(&p, d->m->vertices + 3 * (size_t)d->m->triangles[3 * (size_t)f]);
        if (!mci_ray_label_octree(d->j->ctx, &p, &d->j->s->octree, m, &d->ray, &l))
            return false;
        result = (uint8_t)l; /* UNKNOWN only on m's surface, which f does not meet */
    }
    for (size_t i = 0; i < tail; i++)
        if ((slot = memo_slot(d, memo, d->queue[i])) != NULL)
            *slot = (uint8_t)(result + 1);
    *label = result;
    return true;
}

/* The label of touched face i with respect to the leaf step k reads, if the face does
 * not meet it: OUT when its box misses that leaf's, else its group's. A copy of another
 * leaf is that leaf (it has no faces in the scene); a copy of this one is SAME, left
 * UNKNOWN here. */
static bool step_label(leaf_decision *d, size_t i, size_t k, mci_label *label)
{
    uint32_t m = mci_scene_leaf_stand_in(d->j->s, d->blist.steps[k].leaf);
    uint8_t l = MCI_LABEL_UNKNOWN;
    *label = MCI_LABEL_UNKNOWN;
    if (m == d->leaf)
        return true;
    if (!boxes_meet(d->face_box[i], d->j->box[m]))
        l = MCI_LABEL_OUT; /* it is outside the box that holds m */
    else if (!mci_scene_face_touches(d->j->s, d->faces[i], m) &&
             !group_label(d, d->faces[i] - d->face_base, k, &l))
        return false;
    *label = (mci_label)l;
    return true;
}

/* Whether some value of touched face i's unknown labels would keep it: the steps jump
 * only forward, so a sweep in step order from the start marks the steps some way
 * reaches, reading each step's label only when reached, and stops at the first way to
 * acceptance (a kept face is found as soon as its way is). */
static bool may_accept(leaf_decision *d, size_t i, bool *accepts)
{
    const mci_blist *b = &d->blist;
    *accepts = b->start == MCI_BLIST_ACCEPT;
    if (b->start < 0)
        return true;
    d->sweep++;
    d->reached[b->start] = d->sweep;
    for (size_t k = (size_t)b->start; k < b->count && !*accepts; k++) {
        const mci_blist_step *step = &b->steps[k];
        int32_t to[2] = {step->on_in, step->on_out};
        mci_label l;
        if (d->reached[k] != d->sweep)
            continue;
        if (!step_label(d, i, k, &l))
            return false;
        for (int t = 0; t < 2; t++) {
            if ((t == 0 && l == MCI_LABEL_OUT) || (t == 1 && l == MCI_LABEL_IN))
                continue;
            if (to[t] == MCI_BLIST_ACCEPT || (to[t] >= 0 && to[t] <= (int32_t)k))
                *accepts = true; /* a backward jump would be a bug: keep the face */
            else if (to[t] >= 0)
                d->reached[to[t]] = d->sweep;
        }
    }
    return true;
}

/* Whether the face's pieces may carry what a neighbour's classification needs, so that
 * it must not be dropped whole (its neighbours' sides along it become walls, which no
 * region crosses), from its contacts (mci_scene.arr_contact):
 * - another surface meets it along part of its border (a crossing with both ends on
 *   one edge): once split, it has elementary edges there, and the neighbour across
 *   reads them as separators (its own arrangement may have none there, when it is
 *   coplanar with that surface);
 * - it lies in another leaf's surface (a coplanar face): a neighbour in the same plane
 *   has no side of that leaf to test along their common edge, and its regions take
 *   their label from across it, from where the flat part of the surface ends. */
static bool must_keep_pieces(const mci_scene *s, uint32_t f)
{
    return s->arr_contact[s->arr_of[f]] != 0;
}

/* Flag the touched faces that no value of their unknown labels would keep. */
static bool flag_dropped(leaf_decision *d, size_t *n)
{
    const mci_scene *s = d->j->s;
    *n = 0;
    for (size_t i = 0; i < d->nfaces; i++) {
        bool accepts;
        if (must_keep_pieces(s, d->faces[i]))
            continue;
        if (!may_accept(d, i, &accepts))
            return false;
        if (!accepts) {
            d->j->s->arr_dropped[d->j->s->arr_of[d->faces[i]]] = 1;
            ++*n;
        }
    }
    return true;
}

static bool collect_faces(leaf_decision *d)
{
    const mci_scene *s = d->j->s;
    d->faces = mci_malloc_array(d->j->ctx, d->m->triangle_count + 1, sizeof *d->faces);
    if (!d->faces)
        return false;
    for (uint32_t f = 0; f < d->m->triangle_count; f++)
        if (s->arr_of[d->face_base + f] != MCI_NONE)
            d->faces[d->nfaces++] = d->face_base + f;
    return true;
}

/* Hands the leaf's trimmed list and Blist on to the classification (which would make
 * the same again), cut to their size (they have room for every node and every leaf).
 * False when out of memory. */
static bool keep_trimmed_list(leaf_decision *d, bool rejected)
{
    mci_trimmed_list *k = d->j->keep ? &d->j->keep[d->leaf] : NULL;
    mci_csg_entry *list;
    mci_blist_step *steps = NULL;
    if (!k)
        return true;
    list = mci_realloc_array(d->j->ctx, d->list, d->nlist + 1, sizeof *list);
    if (list)
        d->list = list;
    if (list && !rejected &&
        (steps = mci_realloc_array(d->j->ctx, d->blist.steps, d->blist.count + 1,
                                   sizeof *steps)) != NULL)
        d->blist.steps = steps;
    if (!list || (!rejected && !steps))
        return false;
    *k = (mci_trimmed_list){d->list, d->nlist, true, rejected, d->blist};
    d->list = NULL;
    memset(&d->blist, 0, sizeof d->blist);
    return true;
}

static mcsg_status decide_leaf(void *user, size_t leaf, mcsg_error *err)
{
    const decide_job *j = user;
    leaf_decision d;
    bool rejected = false, ok;
    /* A leaf with copies: its faces' fate also depends on the copies' CSGlists, which
     * this pass does not read; they are left to the classification. */
    if (j->copied && j->copied[leaf])
        return MCSG_OK;
    memset(&d, 0, sizeof d);
    d.j = j;
    d.leaf = (uint32_t)leaf;
    d.face_base = j->s->octree.face_base[leaf];
    d.m = j->s->octree.leaves[leaf];
    ok = collect_faces(&d) && (d.nfaces == 0 || trim_list(&d, &rejected));
    if (ok && rejected) {
        for (size_t i = 0; i < d.nfaces; i++)
            j->s->arr_dropped[j->s->arr_of[d.faces[i]]] = 1;
        j->dropped[leaf] = d.nfaces;
    } else if (ok && d.nfaces > 0) {
        d.face_box = mci_malloc_array(j->ctx, d.nfaces, sizeof *d.face_box);
        ok = d.face_box != NULL;
        for (size_t i = 0; ok && i < d.nfaces; i++)
            triangle_box(d.m, d.m->triangles + 3 * (size_t)(d.faces[i] - d.face_base),
                         d.face_box[i]);
        ok = ok && flag_dropped(&d, &j->dropped[leaf]);
    }
    if (ok && d.list)
        ok = keep_trimmed_list(&d, rejected);
    free_decision(&d);
    return ok ? MCSG_OK : mci_fail_nomem(err, "deciding whole faces");
}

mcsg_status mci_decide_whole_faces(const mci_ctx *ctx, mci_scene *s, const mci_ptree *t,
                                   size_t *count, mci_trimmed_list *keep, mcsg_error *err)
{
    size_t n = s->octree.leaf_count;
    double (*box)[6] = mci_malloc_array(ctx, n + 1, sizeof *box);
    size_t *dropped = mci_calloc_array(ctx, n + 1, sizeof *dropped);
    decide_job job = {ctx, s, t, (const double (*)[6])box, NULL, NULL, NULL, dropped, NULL, keep};
    uint32_t *overlap_start = NULL, *overlap = NULL;
    mci_trim_base trim_base = {NULL, NULL, NULL};
    mcsg_status st = MCSG_OK;
    *count = 0;
    s->arr_dropped = mci_calloc_array(ctx, s->arr_count + 1, 1);
    if (s->alias && (job.copied = mci_calloc_array(ctx, n + 1, 1)) != NULL)
        for (size_t l = 0; l < n; l++)
            job.copied[s->alias[l]] |= s->alias[l] != l;
    if (!box || !dropped || !s->arr_dropped || (s->alias && !job.copied))
        st = mci_fail_nomem(err, "deciding whole faces");
    for (size_t l = 0; st == MCSG_OK && l < n; l++)
        mci_leaf_box(s->octree.leaves[l], box[l]);
    if (st == MCSG_OK && (!mci_box_overlaps(ctx, job.box, n, &overlap_start, &overlap) ||
                          !mci_trim_base_init(ctx, t, &trim_base)))
        st = mci_fail_nomem(err, "deciding whole faces");
    job.overlap_start = overlap_start;
    job.overlap = overlap;
    job.trim_base = &trim_base;
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, n, decide_leaf, &job, err);
    for (size_t l = 0; st == MCSG_OK && l < n; l++)
        *count += dropped[l];
    mci_free(ctx, box);
    mci_free(ctx, overlap_start);
    mci_free(ctx, overlap);
    mci_trim_base_free(ctx, &trim_base);
    mci_free(ctx, dropped);
    mci_free(ctx, job.copied);
    return st;
}
