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
 */
#include "csg/classify.h"
#include "csg/retessellate.h"
#include "base/sort.h"
#include "base/sort_template.h"
#include "csg/triangulate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------- */
/* Exact ray shooting                                                                  */

/* Orientation of a, b and p + (eps, eps^2) in the (y, z) projection, for an infinitely
 * small eps: never 0 when a and b differ in the projection. The eps terms of
 * (b - a) x (p' - a) are eps (a_z - b_z) and eps^2 (b_y - a_y). */
static int perturbed_orient_yz(const mci_point *a, const mci_point *b, const mci_point *p)
{
    const double *u = a->v[0], *w = b->v[0];
    int o = mci_orient2d_projected(a, b, p, 0);
    if (o != 0)
        return o;
    if (u[2] != w[2])
        return u[2] > w[2] ? 1 : -1;
    return (w[1] > u[1]) - (w[1] < u[1]);
}

/* Whether the triangle's box misses the box lo..hi extended to +infinity in x (no
 * ray from a point of lo..hi can meet it) and whether it misses lo..hi itself. */
static void box_tests(const double *a, const double *b, const double *c,
                      const double lo[3], const double hi[3], bool *misses_ray,
                      bool *misses_point)
{
    *misses_ray = *misses_point = false;
    for (int k = 0; k < 3; k++) {
        double mn = a[k] < b[k] ? a[k] : b[k], mx = a[k] > b[k] ? a[k] : b[k];
        mn = c[k] < mn ? c[k] : mn;
        mx = c[k] > mx ? c[k] : mx;
        if (mx < lo[k] || (k > 0 && mn > hi[k]))
            *misses_ray = true;
        if (mx < lo[k] || mn > hi[k])
            *misses_point = true;
    }
}

static bool point_on_triangle(const mci_point *p, const mci_plane *plane)
{
    int which;
    return mci_orient3d(p, plane) == 0 && mci_point_in_triangle(p, plane, &which) != MCI_OUTSIDE;
}

/* One triangle's part in the ray test from p (bounds lo..hi): adds its crossing ahead
 * of p to *winding; false when p lies on the triangle (no ray decides then). */
static bool ray_crossing(const mci_point *p, const double lo[3], const double hi[3],
                         const double *a, const double *b, const double *c, int *winding)
{
    mci_point pa, pb, pc;
    mci_plane plane;
    int nx, side;
    bool misses_ray, misses_point;
    box_tests(a, b, c, lo, hi, &misses_ray, &misses_point);
    if (misses_ray)
        return true;
    mci_plane_init(&plane, a, b, c);
    if (!misses_point && point_on_triangle(p, &plane))
        return false;
    mci_point_explicit(&pa, a);
    mci_point_explicit(&pb, b);
    mci_point_explicit(&pc, c);
    nx = mci_orient2d_projected(&pa, &pb, &pc, 0); /* sign of the normal's x */
    if (nx == 0 || perturbed_orient_yz(&pa, &pb, p) != nx ||
        perturbed_orient_yz(&pb, &pc, p) != nx || perturbed_orient_yz(&pc, &pa, p) != nx)
        return true;
    side = mci_orient3d(p, &plane);
    if (side == 0)
        return false; /* unreachable: p would be on the triangle */
    if (side == -nx)
        *winding += nx; /* crossed ahead of p; leaving the solid when nx > 0 */
    return true;
}

mci_label mci_ray_label(const mci_point *p, const mcsg_mesh *m)
{
    double lo[3], hi[3];
    int winding = 0;
    mci_point_bounds(p, lo, hi);
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *tri = m->triangles + 3 * t;
        if (!ray_crossing(p, lo, hi, m->vertices + 3 * (size_t)tri[0],
                          m->vertices + 3 * (size_t)tri[1], m->vertices + 3 * (size_t)tri[2],
                          &winding))
            return MCI_LABEL_UNKNOWN;
    }
    return winding > 0 ? MCI_LABEL_IN : MCI_LABEL_OUT;
}

void mci_ray_scratch_free(const mci_ctx *ctx, mci_ray_scratch *s)
{
    mci_free(ctx, s->faces);
    mci_free(ctx, s->stack);
    memset(s, 0, sizeof *s);
}

/* Whether closed cell c meets the ray from the box lo..hi along +x. */
static bool cell_meets_ray(const mci_cell *c, const double lo[3], const double hi[3])
{
    return c->hi[0] >= lo[0] && c->lo[1] <= hi[1] && c->hi[1] >= lo[1] && c->lo[2] <= hi[2] &&
           c->hi[2] >= lo[2];
}

static inline bool u32_less(const uint32_t *a, const uint32_t *b)
{
    return *a < *b;
}

MCI_DEFINE_SORT(sort_u32, uint32_t, u32_less)

/* The first index in [lo, hi) of the increasing ids[] whose id is >= x (hi if none). */
static uint32_t first_at_least(const uint32_t *ids, uint32_t lo, uint32_t hi, uint32_t x)
{
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (ids[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* Faces of leaf m in the leaf cells the ray meets, sorted and unique in s->faces. Every
 * face the (perturbed) ray crosses, or that holds p, touches the closed ray, so it is
 * in a leaf cell that meets it. */
static bool collect_ray_faces(const mci_ctx *ctx, const mci_octree *o, uint32_t m,
                              const double lo[3], const double hi[3], mci_ray_scratch *s)
{
    uint32_t first = o->face_base[m], end = o->face_base[m + 1];
    size_t depth = 0, n = 0;
    if (!mci_grow_array(ctx, (void **)&s->stack, &s->stack_capacity, 1, sizeof *s->stack, 64))
        return false;
    s->stack[depth++] = 0;
    while (depth > 0) {
        const mci_cell *c = &o->cells[s->stack[--depth]];
        if (!cell_meets_ray(c, lo, hi))
            continue;
        if (c->child != UINT32_MAX) {
            if (!mci_grow_array(ctx, (void **)&s->stack, &s->stack_capacity, depth + 8,
                                sizeof *s->stack, 64))
                return false;
            for (uint32_t k = 0; k < 8; k++)
                s->stack[depth++] = c->child + k;
            continue;
        }
        /* The leaf's run in the cell's increasing list (cells hold faces of many
         * leaves: ring-800's rays scanned 30M face ids for the few of one leaf). */
        for (uint32_t i = first_at_least(o->face_ids, c->first, c->first + c->count, first);
             i < c->first + c->count && o->face_ids[i] < end; i++) {
            if (!mci_grow_array(ctx, (void **)&s->faces, &s->face_capacity, n + 1,
                                sizeof *s->faces, 64))
                return false;
            s->faces[n++] = o->face_ids[i];
        }
    }
    sort_u32(s->faces, n);
    s->face_count = 0;
    for (size_t i = 0; i < n; i++)
        if (i == 0 || s->faces[i] != s->faces[i - 1])
            s->faces[s->face_count++] = s->faces[i];
    return true;
}

bool mci_ray_label_octree(const mci_ctx *ctx, const mci_point *p, const mci_octree *o,
                          uint32_t m, mci_ray_scratch *s, mci_label *label)
{
    double lo[3], hi[3];
    int winding = 0;
    mci_point_bounds(p, lo, hi);
    if (!collect_ray_faces(ctx, o, m, lo, hi, s))
        return false;
    *label = MCI_LABEL_UNKNOWN;
    for (size_t i = 0; i < s->face_count; i++) {
        uint32_t f = s->faces[i];
        if (!ray_crossing(p, lo, hi, mci_octree_face_vertex(o, f, 0),
                          mci_octree_face_vertex(o, f, 1), mci_octree_face_vertex(o, f, 2),
                          &winding))
            return true;
    }
    *label = winding > 0 ? MCI_LABEL_IN : MCI_LABEL_OUT;
    return true;
}

/* ---------------------------------------------------------------------------------- */
/* Exact local test at a separator                                                     */

static void face_plane(const mci_scene *s, uint32_t f, mci_plane *plane)
{
    mci_plane_init(plane, mci_scene_corner(s, f, 0), mci_scene_corner(s, f, 1),
                   mci_scene_corner(s, f, 2));
}

/* The edges of a triangle a point lies on, as a bit set. */
static int edges_through(mci_containment c, int which)
{
    if (c == MCI_ON_EDGE)
        return 1 << which;
    if (c == MCI_ON_VERTEX)
        return 1 << which | 1 << ((which + 2) % 3);
    return 0;
}

/* SAME or OPPO for a piece of face arrangement fa lying on the coplanar face h. */
static mci_label coplanar_label(const mci_face_arr *fa, const mci_plane *h)
{
    mci_point a, b, c;
    mci_point_explicit(&a, h->a);
    mci_point_explicit(&b, h->b);
    mci_point_explicit(&c, h->c);
    return mci_orient2d_projected(&a, &b, &c, fa->axis) == fa->sign ? MCI_LABEL_SAME
                                                                    : MCI_LABEL_OPPO;
}

static mci_label one_face_label(int side, const mci_face_arr *fa, const mci_plane *h)
{
    return side > 0 ? MCI_LABEL_OUT : side < 0 ? MCI_LABEL_IN : coplanar_label(fa, h);
}

/* Side of the third corner of face h2 (the one off the plane, if any) w.r.t. h. */
static int bend(const mci_scene *s, uint32_t h2, const mci_plane *h)
{
    for (int k = 0; k < 3; k++) {
        mci_point q;
        int side;
        mci_point_explicit(&q, mci_scene_corner(s, h2, k));
        if ((side = mci_orient3d(&q, h)) != 0)
            return side;
    }
    return 0;
}

/* Two faces h1, h2 of a leaf meet at the edge; the leaf's interior is below both
 * (convex edge) or below either (reflex edge). s1, s2: sides of the piece's far vertex. */
static mci_label wedge_label(int convex, int s1, int s2, const mci_face_arr *fa,
                             const mci_plane *h1, const mci_plane *h2)
{
    if (convex) {
        if (s1 == 0)
            return s2 < 0 ? coplanar_label(fa, h1) : MCI_LABEL_OUT;
        if (s2 == 0)
            return s1 < 0 ? coplanar_label(fa, h2) : MCI_LABEL_OUT;
        return s1 < 0 && s2 < 0 ? MCI_LABEL_IN : MCI_LABEL_OUT;
    }
    if (s1 == 0)
        return s2 > 0 ? coplanar_label(fa, h1) : MCI_LABEL_IN;
    if (s2 == 0)
        return s1 > 0 ? coplanar_label(fa, h2) : MCI_LABEL_IN;
    return s1 > 0 && s2 > 0 ? MCI_LABEL_OUT : MCI_LABEL_IN;
}

/* Label of a piece of face arrangement fa with respect to the leaf of face h, where the
 * piece's edge x-y lies in the closed face h and w is the piece's third vertex. The
 * piece's interior does not meet that leaf's surface (or lies in it), so the side of w
 * near the edge decides. */
static mci_label local_label(const mci_scene *s, const mci_face_arr *fa, const mci_point *x,
                             const mci_point *y, const mci_point *w, uint32_t h)
{
    mci_plane p1, p2;
    int wx, wy, common, side1, c;
    uint32_t h2 = MCI_NONE;
    mci_containment cx, cy;
    face_plane(s, h, &p1);
    cx = mci_point_in_triangle(x, &p1, &wx);
    cy = mci_point_in_triangle(y, &p1, &wy);
    if (cx == MCI_OUTSIDE || cy == MCI_OUTSIDE)
        return MCI_LABEL_UNKNOWN;
    common = edges_through(cx, wx) & edges_through(cy, wy);
    if (common)
        h2 = s->neighbour[3 * (size_t)h + (common & 1 ? 0 : common & 2 ? 1 : 2)];
    side1 = mci_orient3d(w, &p1);
    if (h2 == MCI_NONE || (c = bend(s, h2, &p1)) == 0)
        return one_face_label(side1, fa, &p1);
    face_plane(s, h2, &p2);
    return wedge_label(c < 0, side1, mci_orient3d(w, &p2), fa, &p1, &p2);
}

/* ---------------------------------------------------------------------------------- */
/* The classifier: output vertex ids and leaf boxes                                    */

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

void mci_leaf_box(const mcsg_mesh *m, double box[6])
{
    for (int k = 0; k < 3; k++) {
        box[k] = m->vertex_count ? m->vertices[k] : 0;
        box[3 + k] = box[k];
    }
    for (size_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            double x = m->vertices[3 * v + k];
            box[k] = x < box[k] ? x : box[k];
            box[3 + k] = x > box[3 + k] ? x : box[3 + k];
        }
}

typedef struct box_end {
    double lo;      /* the box's low x */
    uint32_t index;
} box_end;

static inline bool box_end_less(const box_end *a, const box_end *b)
{
    return a->lo != b->lo ? a->lo < b->lo : a->index < b->index;
}

MCI_DEFINE_SORT(sort_box_ends, box_end, box_end_less)

static bool yz_meet(const double a[6], const double b[6])
{
    return !(a[4] < b[1] || b[4] < a[1] || a[5] < b[2] || b[5] < a[2]);
}

/* A sweep along x over the boxes sorted by low x, each pair within the x range tested
 * on y and z: `fill` false counts each box's overlaps into start[i + 1], true writes
 * them where start[] (advanced) says. */
static void sweep_box_pairs(const double (*box)[6], const box_end *order, size_t n,
                            uint32_t *start, uint32_t *list, bool fill)
{
    for (size_t i = 0; i < n; i++) {
        uint32_t a = order[i].index;
        for (size_t k = i + 1; k < n && order[k].lo <= box[a][3]; k++) {
            uint32_t b = order[k].index;
            if (!yz_meet(box[a], box[b]))
                continue;
            if (fill) {
                list[start[a]++] = b;
                list[start[b]++] = a;
            } else {
                start[a + 1]++;
                start[b + 1]++;
            }
        }
    }
}

/* Once per evaluation instead of every box against every other per leaf: a plate minus
 * 4,096 holes tested 16.8M pairs of boxes in each of two passes. */
bool mci_box_overlaps(const mci_ctx *ctx, const double (*box)[6], size_t n, uint32_t **start,
                      uint32_t **list)
{
    box_end *order = mci_malloc_array(ctx, n + 1, sizeof *order);
    uint32_t *at = mci_calloc_array(ctx, n + 1, sizeof *at);
    bool ok = order && at;
    *start = mci_calloc_array(ctx, n + 1, sizeof **start);
    *list = NULL;
    ok = ok && *start;
    for (size_t i = 0; ok && i < n; i++)
        order[i] = (box_end){box[i][0], (uint32_t)i};
    if (ok) {
        sort_box_ends(order, n);
        sweep_box_pairs(box, order, n, *start, NULL, false);
        for (size_t i = 0; i < n; i++)
            (*start)[i + 1] += (*start)[i];
        ok = (*list = mci_malloc_array(ctx, (size_t)(*start)[n] + 1, sizeof **list)) != NULL;
    }
    if (ok) {
        memcpy(at, *start, n * sizeof *at);
        sweep_box_pairs(box, order, n, at, *list, true);
        for (size_t i = 0; i < n; i++)
            sort_u32(*list + (*start)[i], (*start)[i + 1] - (*start)[i]);
    }
    mci_free(ctx, order);
    mci_free(ctx, at);
    if (!ok) {
        mci_free(ctx, *start);
        mci_free(ctx, *list);
        *start = *list = NULL;
    }
    return ok;
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
/* One leaf: pieces, regions, labels, selection                                        */

typedef struct leaf_work {
    const mci_ctx *ctx;
    const mci_classifier *cl;
    const mci_scene *s;
    uint32_t leaf, face_base, face_count;
    size_t np;        /* pieces */
    uint32_t *pv;     /* 3 per piece: output vertex ids */
    uint32_t *pface;  /* per piece: global face id */
    uint32_t *plocal; /* 3 per piece: arrangement point id (arranged faces) */
    uint32_t *mate;   /* per edge slot 3p + i (pv[i] -> pv[i + 1]): the slot across */
    uint8_t *is_sep;  /* per edge slot */
    mci_keyed *sep;       /* separators: (edge key, face of another leaf holding it), sorted */
    size_t nsep;
    mci_keyed *walls;     /* border sides of the leaf's faces dropped whole, sorted */
    size_t nwalls;
    uint32_t *region; /* per piece */
    size_t nreg;
    uint32_t *reg_start, *reg_pieces; /* pieces by region (CSR) */
    uint32_t *sep_start, *sep_slots;  /* separator slots by region (CSR) */
    uint32_t *cand;   /* leaves whose box meets this leaf's */
    size_t ncand;
    uint32_t *slot_of_leaf; /* leaf -> index in cand, or MCI_NONE */
    uint8_t *labels;  /* nreg x ncand */
    uint8_t *needed;  /* per candidate: in a subtree of the trimmed CSGlist */
    mci_csg_entry *list; /* the CSGlist, trimmed by the labels known for the whole leaf */
    size_t nlist;
    bool rejected;    /* the trimmed CSGlist drops every face of the leaf */
    mci_blist blist;  /* the trimmed CSGlist compiled for IN/OUT labels (paper §5.4) */
    uint32_t *blist_slot; /* per blist step: the candidate slot of the leaf it reads */
    mci_ray_scratch ray;
    bool out_of_memory; /* set by a ray test that could not allocate */
    mci_label *scratch, *leaf_labels;
    const uint32_t *copies; /* leaves that are copies of this one (see eval.c) ... */
    size_t ncopies;
    mci_csg_entry **copy_list; /* ... their trimmed CSGlists */
    size_t *copy_nlist;
    uint8_t *borrowed;    /* per candidate: a copy of another leaf, labelled as that one */
    mci_kept *kept_all;   /* per leaf: the kept triangles (copies' too) */
    mci_classify_stats *stats;
    mcsg_error *err;
} leaf_work;

static void free_work(leaf_work *w)
{
    void *all[] = {w->pv, w->pface, w->plocal, w->mate, w->is_sep, w->sep, w->walls, w->region,
                   w->reg_start, w->reg_pieces, w->sep_start, w->sep_slots, w->cand,
                   w->slot_of_leaf, w->labels, w->needed, w->list, w->scratch,
                   w->leaf_labels, w->blist_slot};
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

static const mci_face_arr *arr_of_face(const mci_scene *s, uint32_t f)
{
    return s->arr_of[f] == MCI_NONE ? NULL : &s->arrs[s->arr_of[f]];
}

static mcsg_status make_pieces(leaf_work *w)
{
    const mci_scene *s = w->s;
    const mcsg_mesh *m = s->octree.leaves[w->leaf];
    const uint32_t *vid = w->cl->vertex_id + w->cl->vertex_first[w->leaf];
    size_t np = 0, at = 0;
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++)
        np += arr_of_face(s, f) ? arr_of_face(s, f)->tri_count : 1;
    if (np >= UINT32_MAX / 3)
        return mci_fail(w->err, MCSG_ERR_LIMIT, "too many pieces in one leaf (%zu)", np);
    w->np = np;
    w->pv = mci_malloc_array(w->ctx, 3 * np + 1, sizeof *w->pv);
    w->plocal = mci_malloc_array(w->ctx, 3 * np + 1, sizeof *w->plocal);
    w->pface = mci_malloc_array(w->ctx, np + 1, sizeof *w->pface);
    if (!w->pv || !w->plocal || !w->pface)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++) {
        const mci_face_arr *arr = arr_of_face(s, f);
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

/* The point of vertex i of piece p. */
static void piece_point(const leaf_work *w, size_t p, int i, mci_point *out)
{
    const mci_face_arr *arr = arr_of_face(w->s, w->pface[p]);
    if (arr) {
        *out = *arr->points[w->plocal[3 * p + i]];
    } else {
        const mcsg_mesh *m = w->s->octree.leaves[w->leaf];
        mci_point_explicit(out, m->vertices + 3 * (size_t)w->plocal[3 * p + i]);
    }
}

static uint32_t slot_from(const leaf_work *w, size_t slot)
{
    return w->pv[slot];
}

static uint32_t slot_to(const leaf_work *w, size_t slot)
{
    return w->pv[slot - slot % 3 + (slot % 3 + 1) % 3];
}

/* Sides inside an arranged face are paired by its triangulation (adj: the side across
 * and whether it is a constraint, i.e. an elementary edge, i.e. a separator); returns
 * the number of sides left to pair by sorting (those on face boundaries), with mate
 * MCI_NONE. Most sides of a cut face are inside it, so the sort shrinks to the faces'
 * borders. */
static size_t pair_inside_faces(leaf_work *w)
{
    size_t left = 0, p = 0;
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++) {
        const mci_face_arr *arr = arr_of_face(w->s, f);
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
    const mci_face_arr *arr = arr_of_face(s, f), *across;
    const uint32_t *gid = arr_gids(s, arr);
    uint32_t nb = s->neighbour[3 * (size_t)f + (size_t)e];
    uint64_t key = mci_edge_key(gid[e], gid[(e + 1) % 3]);
    *edge = e;
    if (nb == MCI_NONE || !(across = arr_of_face(s, nb)) || dropped_whole(s, nb))
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
static mcsg_status collect_walls(leaf_work *w)
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
static bool is_wall(leaf_work *w, size_t slot, uint64_t key)
{
    if (mci_find_key(w->walls, w->nwalls, key) == w->nwalls)
        return false;
    w->is_sep[slot] = 1;
    return true;
}

/* Pairing by vertex, when the leaf's vertex ids are dense (a model's own vertices,
 * numbered together; sorting 1.2 million edge keys took most of bunny400k's
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
static bool list_sides_by_vertex(leaf_work *w, size_t n, vertex_sides *vs, bool *nomem)
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
            vs->start[slot_from(w, k) - vs->first + 2]++;
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

/* Border slots of vertex `from` going to vertex `to`: how many, and the first. */
static size_t sides_between(const vertex_sides *vs, uint32_t from, uint32_t to,
                            uint32_t *first)
{
    size_t count = 0;
    if (from < vs->first || from > vs->last)
        return 0;
    for (uint32_t i = vs->start[from - vs->first]; i < vs->start[from - vs->first + 1]; i++)
        if (vs->sides[i].to == to && count++ == 0)
            *first = vs->sides[i].slot;
    return count;
}

static bool is_separator(const leaf_work *w, uint64_t key)
{
    return mci_find_key(w->sep, w->nsep, key) != w->nsep;
}

/* True when every border slot is paired (or a wall); false with *nomem set when memory
 * ran out, else when the sort must decide. */
static bool pair_by_vertex(leaf_work *w, size_t n, bool *nomem)
{
    vertex_sides vs = {UINT32_MAX, 0, NULL, NULL};
    bool ok;
    for (size_t k = 0; k < 3 * w->np; k++) {
        if (w->mate[k] != MCI_NONE)
            continue;
        vs.first = slot_from(w, k) < vs.first ? slot_from(w, k) : vs.first;
        vs.last = slot_from(w, k) > vs.last ? slot_from(w, k) : vs.last;
    }
    ok = n > 0 && (vs.last - vs.first) / 8 < n && list_sides_by_vertex(w, n, &vs, nomem);
    for (size_t s = 0; ok && s < n; s++) {
        uint32_t k = vs.sides[s].slot, u = slot_from(w, k), v = vs.sides[s].to;
        uint32_t back = MCI_NONE, ignored;
        uint64_t key = mci_edge_key(u, v);
        size_t ahead, behind;
        if (w->mate[k] != MCI_NONE)
            continue;
        ahead = sides_between(&vs, u, v, &ignored);
        behind = sides_between(&vs, v, u, &back);
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

/* Pair every directed piece edge with its opposite; a closed, consistently oriented
 * edge-manifold surface has exactly one. Sides on face borders are sorted by edge key
 * and walked along the sorted separators (collect_separators), which marks the
 * separator slots (is_sep); leaves with dense vertex ids are paired by vertex first
 * (pair_by_vertex). */
static mcsg_status pair_edges(leaf_work *w)
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
        e[m].key = mci_edge_key(slot_from(w, k), slot_to(w, k));
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
        if (j - i != 2 || slot_from(w, e[i].ref) != slot_to(w, e[i + 1].ref))
            st = mci_fail(w->err, MCSG_ERR_INTERNAL,
                          "leaf %u does not close up after splitting: an edge is shared by "
                          "%zu pieces%s (inputs must be closed and edge-manifold)",
                          w->leaf, j - i, j - i == 2 ? " with equal orientations" : "");
        else {
            w->mate[e[i].ref] = e[i + 1].ref;
            w->mate[e[i + 1].ref] = e[i].ref;
            while (sep < w->nsep && w->sep[sep].key < e[i].key)
                sep++;
            w->is_sep[e[i].ref] = w->is_sep[e[i + 1].ref] =
                sep < w->nsep && w->sep[sep].key == e[i].key;
        }
        i = j;
    }
    mci_free(w->ctx, e);
    return st;
}

/* Every elementary edge of the leaf's arrangements, with the other leaf's face. */
static mcsg_status collect_separators(leaf_work *w)
{
    const mci_scene *s = w->s;
    size_t n = 0;
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++)
        n += arr_of_face(s, f) ? arr_of_face(s, f)->edge_count : 0;
    w->sep = mci_malloc_array(w->ctx, n + 1, sizeof *w->sep);
    w->is_sep = mci_calloc_array(w->ctx, 3 * w->np + 1, sizeof *w->is_sep);
    if (!w->sep || !w->is_sep)
        return mci_fail_nomem(w->err, "classifying faces");
    for (uint32_t f = w->face_base; f < w->face_base + w->face_count; f++) {
        const mci_face_arr *arr = arr_of_face(s, f);
        const uint32_t *gid = arr ? s->gid + s->gid_start[s->arr_of[f]] : NULL;
        for (size_t e = 0; arr && e < arr->edge_count; e++) {
            w->sep[w->nsep].key = mci_edge_key(gid[arr->edges[e].a], gid[arr->edges[e].b]);
            w->sep[w->nsep++].ref = arr->edges[e].other;
        }
    }
    mci_sort_keyed(w->sep, w->nsep);
    return MCSG_OK;
}

/* Index of the first separator entry with this key, or nsep. */
static size_t find_separator(const leaf_work *w, uint64_t key)
{
    return mci_find_key(w->sep, w->nsep, key);
}

static uint32_t find_root(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

/* Regions: pieces joined across non-separator edges; numbered by first piece. */
static mcsg_status build_regions(leaf_work *w)
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
        if (!w->is_sep[k]) {
            uint32_t a = find_root(parent, (uint32_t)(k / 3));
            uint32_t b = find_root(parent, w->mate[k] / 3);
            parent[a > b ? a : b] = a > b ? b : a;
        }
    }
    for (uint32_t p = 0; p < w->np; p++) {
        uint32_t r = find_root(parent, p);
        w->region[p] = r == p ? (uint32_t)w->nreg++ : w->region[r];
    }
    mci_free(w->ctx, parent);
    return MCSG_OK;
}

/* CSR lists: pieces of each region, and separator slots of each region. */
static mcsg_status index_regions(leaf_work *w)
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

/* The candidates: the other leaves whose boxes meet this leaf's, in increasing index. */
static mcsg_status find_candidates(leaf_work *w)
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
    return MCSG_OK;
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

static void local_labels_at(leaf_work *w, uint8_t *to, size_t k, bool only_unknown);

/* Labels a seed region's rays left open (every vertex tried lies on that leaf's
 * surface): decided at a separator of the region on that leaf, if any. */
static void seed_by_local_tests(leaf_work *w, uint32_t r)
{
    uint8_t *lab = w->labels + (size_t)r * w->ncand;
    for (uint32_t i = w->sep_start[r]; i < w->sep_start[r + 1]; i++)
        local_labels_at(w, lab, w->sep_slots[i], true);
}

/* First seed: the region's labels by rays from its vertices (untouched faces' vertices
 * first: they lie on no other surface). A ray from a vertex on the other leaf's surface
 * decides nothing; the next vertex is tried. */
static void seed_region(leaf_work *w, uint32_t r)
{
    uint8_t *lab = w->labels + (size_t)r * w->ncand;
    for (int pass = 0; pass < 2; pass++)
        for (uint32_t k = w->reg_start[r]; k < w->reg_start[r + 1]; k++) {
            uint32_t p = w->reg_pieces[k];
            bool untouched = arr_of_face(w->s, w->pface[p]) == NULL;
            if (untouched != (pass == 0))
                continue;
            for (int i = 0; i < 3; i++) {
                mci_point v;
                mci_label label;
                bool all = true;
                piece_point(w, p, i, &v);
                for (size_t c = 0; c < w->ncand; c++) {
                    uint32_t m = w->cand[c];
                    if (lab[c] != MCI_LABEL_UNKNOWN || !w->needed[c])
                        continue;
                    if (point_outside_box(&v, w->cl->box[m])) {
                        lab[c] = MCI_LABEL_OUT;
                        continue;
                    }
                    w->stats->rays++;
                    if (!mci_ray_label_octree(w->ctx, &v, &w->s->octree, m, &w->ray, &label)) {
                        w->out_of_memory = true;
                        return;
                    }
                    lab[c] = (uint8_t)label;
                    all = all && label != MCI_LABEL_UNKNOWN;
                }
                if (all)
                    return;
            }
        }
    seed_by_local_tests(w, r);
}

/* Labels of the region of piece k / 3 with respect to the leaves holding its edge slot
 * k, by local tests (only those still unknown if only_unknown). */
static void local_labels_at(leaf_work *w, uint8_t *to, size_t k, bool only_unknown)
{
    const mci_scene *s = w->s;
    size_t p = k / 3;
    uint64_t key = mci_edge_key(slot_from(w, k), slot_to(w, k));
    mci_point x, y, far;
    piece_point(w, p, (int)(k % 3), &x);
    piece_point(w, p, (int)(k % 3 + 1) % 3, &y);
    piece_point(w, p, (int)(k % 3 + 2) % 3, &far);
    for (size_t e = find_separator(w, key); e < w->nsep && w->sep[e].key == key; e++) {
        uint32_t h = w->sep[e].ref, c = w->slot_of_leaf[s->octree.face_leaf[h]];
        if (c == MCI_NONE || !w->needed[c] || (only_unknown && to[c] != MCI_LABEL_UNKNOWN))
            continue;
        w->stats->local_tests++;
        to[c] = (uint8_t)local_label(s, arr_of_face(s, w->pface[p]), &x, &y, &far, h);
    }
}

/* Labels of region r2 from those of r1 across separator slot k (a slot of r2): equal
 * but for the leaves whose surface holds the separator (paper Prop. 2). */
static void inherit_labels(leaf_work *w, uint32_t r1, uint32_t r2, size_t k)
{
    uint8_t *to = w->labels + (size_t)r2 * w->ncand;
    memcpy(to, w->labels + (size_t)r1 * w->ncand, w->ncand);
    local_labels_at(w, to, k, false);
}

/* Whether separator slot k lies on the surface of leaf m. */
static bool separator_on_leaf(const leaf_work *w, size_t k, uint32_t m)
{
    uint64_t key = mci_edge_key(slot_from(w, k), slot_to(w, k));
    for (size_t e = find_separator(w, key); e < w->nsep && w->sep[e].key == key; e++)
        if (w->s->octree.face_leaf[w->sep[e].ref] == m)
            return true;
    return false;
}

/* memchr first: the ring of ring-800 has ~800 candidates, all needed and labelled. */
static bool has_unknown_label(const leaf_work *w, uint32_t r)
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
static void fill_unknown_labels(leaf_work *w)
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
                    if (there != MCI_LABEL_UNKNOWN && !separator_on_leaf(w, k, w->cand[c])) {
                        lab[c] = there;
                        changed = true;
                    }
                }
            }
        }
    }
}

/* Breadth-first over regions across separators, seeding each unreached part. */
static mcsg_status label_regions(leaf_work *w)
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
    return MCSG_OK;
}

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
} owner;

/* The kept triangles of arranged face f, whose pieces start at piece `first`, after
 * re-tessellating it with its valid constraints only. */
static mcsg_status emit_arranged_face(leaf_work *w, uint32_t f, size_t first, const owner *o)
{
    mci_face_arr *arr = &w->cl->scene->arrs[w->s->arr_of[f]];
    const uint32_t *gid = w->s->gid + w->s->gid_start[w->s->arr_of[f]];
    uint8_t stack_keep[2 * 256]; /* piece and triangle flags: most faces allocate none */
    uint8_t *piece_keep = arr->tri_count <= 256 ? stack_keep
                                                : mci_malloc_array(w->ctx, 2 * arr->tri_count, 1);
    uint8_t *tri_keep = piece_keep ? piece_keep + arr->tri_count : NULL;
    mcsg_status st = piece_keep ? MCSG_OK : mci_fail_nomem(w->err, "classifying faces");
    for (size_t i = 0; st == MCSG_OK && i < arr->tri_count; i++)
        piece_keep[i] = o->keep[w->region[first + i]];
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
static mcsg_status emit_shared_face(leaf_work *w, uint32_t f, size_t first,
                                    const owner *owners, size_t n)
{
    const mci_face_arr *arr = arr_of_face(w->s, f);
    for (size_t k = 0; k < n; k++)
        for (size_t p = first; p < first + arr->tri_count; p++)
            if (owners[k].keep[w->region[p]] &&
                !push_triangle(w->ctx, owners[k].kept, w->pv + 3 * p, owners[k].reversed,
                               f + owners[k].face_offset))
                return mci_fail_nomem(w->err, "classifying faces");
    return MCSG_OK;
}

/* The owner keeping pieces of the face [first, first + count), the number of such owners
 * in *n. */
static const owner *face_owner(const leaf_work *w, size_t first, size_t count,
                               const owner *owners, size_t n_owners, size_t *n)
{
    const owner *found = NULL;
    *n = 0;
    for (size_t k = 0; k < n_owners; k++)
        for (size_t p = first; p < first + count; p++)
            if (owners[k].keep[w->region[p]]) {
                found = &owners[k];
                ++*n;
                break;
            }
    return found;
}

static mcsg_status emit_kept(leaf_work *w, const owner *owners, size_t n_owners)
{
    mcsg_status st = MCSG_OK;
    size_t p = 0;
    while (p < w->np && st == MCSG_OK) {
        uint32_t f = w->pface[p];
        const mci_face_arr *arr = arr_of_face(w->s, f);
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
            if (owners[k].keep[w->region[p]] &&
                !push_triangle(w->ctx, owners[k].kept, w->pv + 3 * p, owners[k].reversed,
                               f + owners[k].face_offset))
                st = mci_fail_nomem(w->err, "classifying faces");
        p++;
    }
    return st;
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

/* ---------------------------------------------------------------------------------- */
/* Copies: leaves that are the same mesh as this one                                   */

/* A copy B of this leaf P has P's pieces and regions; its labels are P's, with P's
 * own label SAME (the faces coincide, with the same orientation). P's classification
 * therefore also decides B's output, with B's CSGlist. And in P's labels, a candidate
 * that is a copy of another leaf R borrows R's labels (it has no faces in the scene). */
static uint32_t stand_in(const leaf_work *w, uint32_t m)
{
    return mci_scene_leaf_stand_in(w->s, m);
}

/* The copies of this leaf and their trimmed CSGlists (candidates: this leaf's, less the
 * copy, plus this leaf), marked in cover as well. */
static mcsg_status trim_copy_lists(leaf_work *w, int32_t *cover)
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
static mcsg_status prepare_copy_labels(leaf_work *w)
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
static void finish_copy_labels(leaf_work *w)
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
static mcsg_status check_trimmed_list(leaf_work *w, const mci_trimmed_list *made)
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

static mcsg_status trim_csglist(leaf_work *w)
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

/* Labels of region r for the CSGlist of leaf `as` (this leaf or a copy of it): this
 * leaf is SAME for a copy; reversed for a complemented leaf. */
static void region_labels(leaf_work *w, size_t r, uint32_t as)
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

/* A point strictly inside the triangle a, b, c (input vertices): where a line through its
 * approximate centroid, along its approximate normal, pierces its plane (an LPI of input
 * vertices; `ends` holds the line's two ends, which the point refers to). False when the
 * doubles do not give a line crossing the plane or a point strictly inside (slivers). */
static bool point_inside_triangle(const double *a, const double *b, const double *c,
                                  double ends[2][3], mci_point *out)
{
    double e1[3], e2[3], n[3], size = 0, norm = 0;
    mci_plane plane;
    mci_point corner[3];
    int axis, sign, turns[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = b[k] - a[k];
        e2[k] = c[k] - a[k];
        size = fmax(size, fmax(fabs(e1[k]), fabs(e2[k])));
    }
    for (int k = 0; k < 3; k++) {
        n[k] = e1[(k + 1) % 3] * e2[(k + 2) % 3] - e1[(k + 2) % 3] * e2[(k + 1) % 3];
        norm = fmax(norm, fabs(n[k]));
    }
    if (!(norm > 0) || !(size > 0) || !isfinite(norm))
        return false;
    for (int k = 0; k < 3; k++) {
        double centre = (a[k] + b[k] + c[k]) / 3, step = n[k] / norm * size;
        ends[0][k] = centre + step;
        ends[1][k] = centre - step;
    }
    mci_plane_init(&plane, a, b, c);
    if (mci_orient3d_vertices(a, b, c, ends[0]) * mci_orient3d_vertices(a, b, c, ends[1]) >= 0 ||
        !mci_point_lpi(out, ends[0], ends[1], &plane) ||
        (axis = mci_plane_projection_axis(&plane, &sign)) < 0)
        return false;
    mci_point_explicit(&corner[0], a);
    mci_point_explicit(&corner[1], b);
    mci_point_explicit(&corner[2], c);
    for (int i = 0; i < 3; i++)
        turns[i] = mci_orient2d_projected(&corner[i], &corner[(i + 1) % 3], out, axis);
    return turns[0] != 0 && turns[0] == turns[1] && turns[1] == turns[2];
}

/* The region's labels still unknown when its labels do not decide it: rays from a point
 * strictly inside one of its pieces with input corners. The seeds cast rays from region
 * vertices only; when every vertex lies on a leaf's surface and no side of the region is
 * on it (faces touching that leaf only at their corners), the inside of a piece still
 * tells. False when nothing was learnt. */
static bool labels_from_inside(leaf_work *w, uint32_t r)
{
    uint8_t *lab = w->labels + (size_t)r * w->ncand;
    bool learnt = false;
    for (uint32_t k = w->reg_start[r]; k < w->reg_start[r + 1] && !learnt; k++) {
        mci_point v[3], probe;
        double ends[2][3];
        uint32_t p = w->reg_pieces[k];
        for (int i = 0; i < 3; i++)
            piece_point(w, p, i, &v[i]);
        if (v[0].kind != MCI_POINT_EXPLICIT || v[1].kind != MCI_POINT_EXPLICIT ||
            v[2].kind != MCI_POINT_EXPLICIT ||
            !point_inside_triangle(v[0].v[0], v[1].v[0], v[2].v[0], ends, &probe))
            continue;
        for (size_t c = 0; c < w->ncand; c++) {
            mci_label label;
            if (lab[c] != MCI_LABEL_UNKNOWN || !w->needed[c])
                continue;
            w->stats->rays++;
            if (!mci_ray_label_octree(w->ctx, &probe, &w->s->octree, w->cand[c], &w->ray,
                                      &label)) {
                w->out_of_memory = true;
                return false;
            }
            lab[c] = (uint8_t)label;
            learnt = learnt || label != MCI_LABEL_UNKNOWN;
        }
    }
    return learnt;
}

/* Whether region r is kept, for this leaf or its copy k (-1: its labels do not tell). */
/* The blist on region r's own labels (mci_blist_accepts without spreading them over the
 * leaves first: the ring of ring-800 has ~800 candidates, and a walk reads a few). */
static int region_blist_accepts(const leaf_work *w, uint32_t r)
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

static int region_accepts(leaf_work *w, uint32_t r, size_t k)
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

/* keep[r] for every region, for this leaf (k = ncopies) or its copy k. */
static mcsg_status decide_regions(leaf_work *w, size_t k, uint8_t *keep)
{
    bool self = k == w->ncopies, rejected = self ? w->rejected : w->copy_nlist[k] == SIZE_MAX;
    for (uint32_t r = 0; r < w->nreg; r++) {
        int accepts = 0;
        if (!rejected) {
            accepts = region_accepts(w, r, k);
            if (accepts < 0 && labels_from_inside(w, r))
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

/* Evaluate each region's CSGlist (this leaf's and its copies') and output the pieces of
 * the kept ones. */
static mcsg_status select_pieces(leaf_work *w)
{
    const mci_ptree *t = w->cl->tree;
    size_t n = w->ncopies + 1;
    owner *owners = mci_malloc_array(w->ctx, n, sizeof *owners);
    uint8_t *keep = mci_malloc_array(w->ctx, n * (w->nreg + 1), 1);
    mcsg_status st = owners && keep ? MCSG_OK : mci_fail_nomem(w->err, "classifying faces");
    for (size_t k = 0; k < n && st == MCSG_OK; k++) {
        uint32_t as = k == 0 ? w->leaf : w->copies[k - 1];
        owners[k] = (owner){keep + k * (w->nreg + 1), t->nodes[t->leaf_node[as]].complement,
                            &w->kept_all[as],
                            w->s->octree.face_base[as] - w->s->octree.face_base[w->leaf]};
        st = decide_regions(w, k == 0 ? w->ncopies : k - 1, keep + k * (w->nreg + 1));
    }
    st = st == MCSG_OK ? emit_kept(w, owners, n) : st;
    mci_free(w->ctx, owners);
    mci_free(w->ctx, keep);
    return st;
}

mcsg_status mci_classify_leaf(const mci_ctx *ctx, const mci_classifier *cl, uint32_t leaf,
                              mci_kept *kept, mci_classify_stats *stats, mcsg_error *err)
{
    leaf_work w;
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
    st = make_pieces(&w);
    if (st == MCSG_OK)
        st = collect_separators(&w);
    if (st == MCSG_OK)
        st = collect_walls(&w);
    if (st == MCSG_OK)
        st = pair_edges(&w);
    if (st == MCSG_OK)
        st = build_regions(&w);
    if (st == MCSG_OK)
        st = index_regions(&w);
    if (st == MCSG_OK)
        st = find_candidates(&w);
    if (st == MCSG_OK)
        st = trim_csglist(&w);
    if (st == MCSG_OK && (!w.rejected || w.ncopies > 0)) {
        st = prepare_copy_labels(&w);
        if (st == MCSG_OK)
            st = label_regions(&w);
        finish_copy_labels(&w);
        if (st == MCSG_OK)
            st = select_pieces(&w);
    }
    stats->rejected_leaves += w.rejected;
    stats->pieces += w.np;
    stats->regions += w.nreg;
    free_work(&w);
    return st;
}
