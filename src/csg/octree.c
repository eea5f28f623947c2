/*
 * Adaptive octree over all leaves' faces (paper §3.1) and candidate pairs (§3.2).
 *
 * Cells are closed boxes; children split their parent at the rounded midpoint, and
 * siblings share the split coordinate exactly, so the leaf cells tile the root box.
 * A face is listed in every cell its triangle touches, and possibly in a few more: a
 * separating-axis test in doubles drops a face only when an axis separates it from the
 * cell by more than a bound on the rounding error (the exact test,
 * mci_triangle_touches_box, is kept for the tests). So any point common to two faces lies
 * in a leaf cell listing both: candidate pairs from leaf cells are complete, and an extra
 * listing only costs a pair that the exact pair test rejects.
 */
#include "csg/octree.h"
#include "base/parallel.h"
#include "base/sort.h"
#include "exact/kernel.h"
#include "exact/predicates.h"
#include "exact/tri_tri.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* 48 rather than 24: fewer cells to build for a few more candidate pairs, now that a
 * pair apart is rejected cheaply (same pairs that intersect, same outputs). */
#define DEFAULT_MAX_CELL_FACES 48
#define DEFAULT_MAX_DEPTH 14
#define NO_CHILD UINT32_MAX

/* ---------------------------------------------------------------------------------- */
/* Exact triangle-box overlap (separating axis theorem)                                */

static bool bounding_boxes_separate(const double *a, const double *b, const double *c,
                                    const double lo[3], const double hi[3])
{
    for (int k = 0; k < 3; k++) {
        double min = a[k] < b[k] ? a[k] : b[k], max = a[k] > b[k] ? a[k] : b[k];
        min = c[k] < min ? c[k] : min;
        max = c[k] > max ? c[k] : max;
        if (max < lo[k] || min > hi[k])
            return true;
    }
    return false;
}

static void box_corner(const double lo[3], const double hi[3], int index, double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = (index >> k) & 1 ? hi[k] : lo[k];
}

/* The triangle's plane separates when all eight corners are strictly on one side. */
static bool plane_separates(const double *a, const double *b, const double *c,
                            const double lo[3], const double hi[3])
{
    mci_plane plane;
    int first = 0;
    mci_plane_init(&plane, a, b, c);
    for (int i = 0; i < 8; i++) {
        double corner[3];
        mci_point p;
        int side;
        box_corner(lo, hi, i, corner);
        mci_point_explicit(&p, corner);
        side = mci_orient3d(&p, &plane);
        if (side == 0 || (i > 0 && side != first))
            return false;
        first = side;
    }
    return true;
}

/* Axis (q - p) x e_k: in the projection along k, the triangle covers the interval
 * between the line through p, q and the parallel line through r; the box projects to a
 * rectangle. Separated when all four rectangle corners lie strictly beyond one end. */
static bool edge_axis_separates(const double *p, const double *q, const double *r,
                                const double lo[3], const double hi[3], int k)
{
    int i = (k + 1) % 3, j = (k + 2) % 3;
    double P[2] = {p[i], p[j]}, Q[2] = {q[i], q[j]}, R[2] = {r[i], r[j]};
    int r_side, below = 0, above = 0;
    if (P[0] == Q[0] && P[1] == Q[1])
        return false; /* the edge is parallel to axis k: no such axis */
    r_side = mci_orient2d(P[0], P[1], Q[0], Q[1], R[0], R[1]);
    for (int corner = 0; corner < 4; corner++) {
        double C[2] = {corner & 1 ? hi[i] : lo[i], corner & 2 ? hi[j] : lo[j]};
        int at_edge = mci_orient2d(P[0], P[1], Q[0], Q[1], C[0], C[1]);
        int at_r = mci_cross2_diff_sign(P, Q, R, C);
        /* Below the interval [min(0, f(r)), max(0, f(r))] of f = (q - p) x (x - p). */
        below += r_side >= 0 ? at_edge < 0 : at_r < 0;
        above += r_side >= 0 ? (r_side > 0 ? at_r > 0 : at_edge > 0) : at_edge > 0;
    }
    return below == 4 || above == 4;
}

bool mci_triangle_touches_box(const double *a, const double *b, const double *c,
                              const double lo[3], const double hi[3])
{
    const double *corner[3] = {a, b, c};
    if (bounding_boxes_separate(a, b, c, lo, hi))
        return false;
    for (int e = 0; e < 3; e++) {
        for (int k = 0; k < 3; k++) {
            if (edge_axis_separates(corner[e], corner[(e + 1) % 3], corner[(e + 2) % 3], lo,
                                    hi, k))
                return false;
        }
    }
    return !plane_separates(a, b, c, lo, hi);
}

/* ---------------------------------------------------------------------------------- */
/* Building                                                                            */

typedef struct builder {
    const mci_ctx *ctx;
    mci_octree *tree;
    mci_octree_params params;
    size_t cell_capacity, id_capacity;
    float *face_box; /* per face: min x, y, z, max x, y, z (see face_boxes) */
} builder;

static size_t total_faces(const mcsg_mesh *const *leaves, size_t leaf_count)
{
    size_t total = 0;
    for (size_t i = 0; i < leaf_count; i++)
        total += leaves[i]->triangle_count;
    return total;
}

static bool index_faces(const mci_ctx *ctx, mci_octree *t, const uint8_t *skip_leaf)
{
    size_t total = total_faces(t->leaves, t->leaf_count);
    t->face_base = mci_malloc_array(ctx, t->leaf_count + 1, sizeof *t->face_base);
    t->face_leaf = mci_malloc_array(ctx, total, sizeof *t->face_leaf);
    t->face_ids = mci_malloc_array(ctx, total, sizeof *t->face_ids);
    if (!t->face_base || !t->face_leaf || !t->face_ids)
        return false;
    t->face_base[0] = 0;
    for (size_t i = 0; i < t->leaf_count; i++) {
        uint32_t end = t->face_base[i] + (uint32_t)t->leaves[i]->triangle_count;
        t->face_base[i + 1] = end;
        for (uint32_t f = t->face_base[i]; f < end; f++)
            t->face_leaf[f] = (uint32_t)i;
    }
    t->face_id_count = 0;
    for (size_t f = 0; f < total; f++)
        if (!skip_leaf || !skip_leaf[t->face_leaf[f]])
            t->face_ids[t->face_id_count++] = (uint32_t)f;
    return true;
}

/* The root is a cube (its box grown along the shorter axes), so that cells stay cubes at
 * every depth. Splitting a flat scene's box in all three axes made flat cells that faces
 * cross many at a time: on a long ring of spheres, more cells, and an octree step that
 * grew much faster than the faces. A side that overflows keeps the box as it is. */
static void make_cube(mci_cell *root)
{
    double side = 0;
    for (int k = 0; k < 3; k++)
        side = mci_max(side, root->hi[k] - root->lo[k]);
    for (int k = 0; side < INFINITY && k < 3; k++)
        root->hi[k] = mci_max(root->hi[k], root->lo[k] + side);
}

static void root_bounds(const mci_octree *t, mci_cell *root)
{
    for (int k = 0; k < 3; k++) {
        root->lo[k] = 0;
        root->hi[k] = 0;
    }
    for (uint32_t i = 0; i < t->face_id_count; i++) {
        for (int v = 0; v < 3; v++) {
            const double *p = mci_octree_face_vertex(t, t->face_ids[i], v);
            for (int k = 0; k < 3; k++) {
                if ((i == 0 && v == 0) || p[k] < root->lo[k])
                    root->lo[k] = p[k];
                if ((i == 0 && v == 0) || p[k] > root->hi[k])
                    root->hi[k] = p[k];
            }
        }
    }
    make_cube(root);
}

/* The group of face f (mci_octree_params.face_group). */
static uint32_t face_group(const mci_octree *t, uint32_t f)
{
    return t->face_group ? t->face_group[f] : t->face_leaf[f];
}

/* Whether face f's leaf has several groups (shells that may cross each other). */
static bool in_grouped_leaf(const mci_octree *t, uint32_t f)
{
    return t->face_group && t->face_group[f] >= t->leaf_count;
}

static bool cell_is_critical(const mci_octree *t, const mci_cell *cell)
{
    for (uint32_t i = 1; i < cell->count; i++) {
        if (face_group(t, t->face_ids[cell->first + i]) !=
            face_group(t, t->face_ids[cell->first]))
            return true;
    }
    return false;
}

/* The rounded midpoint must fall strictly inside, or the cell cannot be split. */
static bool split_points(const mci_cell *cell, double mid[3])
{
    for (int k = 0; k < 3; k++) {
        mid[k] = cell->lo[k] + (cell->hi[k] - cell->lo[k]) / 2;
        if (!(cell->lo[k] < mid[k] && mid[k] < cell->hi[k]))
            return false;
    }
    return true;
}

/* mci_max and mci_min differ from fmax and fmin only on NaN, which overflow on extreme
 * coordinates can produce; a NaN bound or value makes a "misses" test below false, which
 * keeps the face: still conservative.
 *
 * Whether the triangle's plane provably misses the box: the box corners extreme along
 * the normal, evaluated in doubles, are both strictly on one side by more than a bound
 * on the rounding error (differences, the cross product and the dot product each add at
 * most a few units of 2^-53 relative to the sums of absolute terms; 1e-14 covers them
 * tenfold, 1e-300 covers underflow). When it cannot prove it, the face is kept. */
static bool plane_misses_box(const double *a, const double *b, const double *c,
                             const double lo[3], const double hi[3])
{
    double d1[3], d2[3], lowest = 0, highest = 0, bound = 0;
    for (int k = 0; k < 3; k++) {
        d1[k] = b[k] - a[k];
        d2[k] = c[k] - a[k];
    }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        double n = d1[i] * d2[j] - d1[j] * d2[i];
        double n_abs = fabs(d1[i] * d2[j]) + fabs(d1[j] * d2[i]);
        double to_lo = lo[k] - a[k], to_hi = hi[k] - a[k];
        lowest += n * (n > 0 ? to_lo : to_hi);
        highest += n * (n > 0 ? to_hi : to_lo);
        bound += n_abs * mci_max(fabs(to_lo), fabs(to_hi));
    }
    bound = bound * 1e-14 + 1e-300;
    return lowest > bound || highest < -bound;
}

/* The same for the axis (q - p) x e_k: in the projection along k, f(x) = (q - p) x
 * (x - p) spans [min(0, f(r)), max(0, f(r))] over the triangle; the box's range of f
 * comes from its extreme corners. */
static bool edge_axis_misses_box(const double *p, const double *q, const double *r,
                                 const double lo[3], const double hi[3], int k)
{
    int i = (k + 1) % 3, j = (k + 2) % 3;
    double ei = q[i] - p[i], ej = q[j] - p[j];
    double fr = ei * (r[j] - p[j]) - ej * (r[i] - p[i]);
    double lo_j = lo[j] - p[j], hi_j = hi[j] - p[j], lo_i = lo[i] - p[i], hi_i = hi[i] - p[i];
    double f_lo = ei * (ei > 0 ? lo_j : hi_j) - ej * (ej > 0 ? hi_i : lo_i);
    double f_hi = ei * (ei > 0 ? hi_j : lo_j) - ej * (ej > 0 ? lo_i : hi_i);
    double bound = fabs(ei) * (mci_max(fabs(lo_j), fabs(hi_j)) + fabs(r[j] - p[j])) +
                   fabs(ej) * (mci_max(fabs(lo_i), fabs(hi_i)) + fabs(r[i] - p[i]));
    bound = bound * 1e-14 + 1e-300;
    return f_lo > mci_max(0, fr) + bound || f_hi < mci_min(0, fr) - bound;
}

static bool triangle_misses_box(const double *const v[3], const double lo[3],
                                const double hi[3])
{
    if (plane_misses_box(v[0], v[1], v[2], lo, hi))
        return true;
    for (int e = 0; e < 3; e++)
        for (int k = 0; k < 3; k++)
            if (edge_axis_misses_box(v[e], v[(e + 1) % 3], v[(e + 2) % 3], lo, hi, k))
                return true;
    return false;
}

/* Faces listed in a cell are a superset of those touching it: a face is dropped only
 * when its bounding box misses the cell or its plane or an edge axis provably does (the
 * separating axis theorem in doubles with error bounds). Completeness is
 * what matters (any point two faces share lies in a leaf cell listing both); an extra
 * face only costs a candidate pair that the exact triangle test then rejects. */
static bool face_touches_cell(const double *const v[3], const double box[6],
                              const mci_cell *cell)
{
    int inside_axes = 0;
    for (int k = 0; k < 3; k++) {
        if (box[3 + k] < cell->lo[k] || box[k] > cell->hi[k])
            return false;
        inside_axes += cell->lo[k] <= box[k] && box[3 + k] <= cell->hi[k];
    }
    /* Box inside the cell on two axes and overlapping on the third: the triangle is
     * convex, so it has a point within the cell's range on the third axis, and that
     * point is within range on the other two. Long thin faces (a cylinder's sides) take
     * this exact shortcut instead of the separating-axis tests. */
    return inside_axes >= 2 || !triangle_misses_box(v, cell->lo, cell->hi);
}

/* Face boxes in parallel chunks of faces (each face writes its own six numbers), in
 * floats rounded outward: they only choose which children to test and which pairs to
 * reject, for which a box holding the face will do, and half the bytes halve the time
 * of the passes that read one per face and level. */
enum { FACE_CHUNK = 16384 };

typedef struct box_job {
    const mci_octree *t;
    float *box;
} box_job;

/* The face's box in doubles, from its corners. */
static void exact_box(const double *const v[3], double box[6])
{
    for (int k = 0; k < 3; k++) {
        box[k] = mci_min(mci_min(v[0][k], v[1][k]), v[2][k]);
        box[3 + k] = mci_max(mci_max(v[0][k], v[1][k]), v[2][k]);
    }
}

static mcsg_status box_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const box_job *j = user;
    (void)err;
    for (uint32_t f = (uint32_t)begin; f < end; f++) {
        const double *v[3] = {mci_octree_face_vertex(j->t, f, 0),
                              mci_octree_face_vertex(j->t, f, 1),
                              mci_octree_face_vertex(j->t, f, 2)};
        double box[6];
        float *out = j->box + 6 * (size_t)f;
        exact_box(v, box);
        for (int k = 0; k < 3; k++) {
            out[k] = mci_float_below(box[k]);
            out[3 + k] = mci_float_above(box[3 + k]);
        }
    }
    return MCSG_OK;
}

static float *face_boxes(const mci_ctx *ctx, const mci_octree *t)
{
    uint32_t faces = t->face_base[t->leaf_count];
    box_job job = {t, mci_malloc_array(ctx, (size_t)faces + 1, 6 * sizeof *job.box)};
    if (job.box)
        mci_parallel_for_ranges(ctx, faces, FACE_CHUNK, box_chunk, &job, NULL);
    return job.box;
}

/* The octree is built level by level: the cells of one level are split in parallel,
 * each into its own list of children's faces, and the lists are appended in cell order,
 * so the tree (cells, numbering, face lists) does not depend on the thread count. */
typedef struct cell_split {
    bool critical, split;
    double mid[3]; /* the split point */
    uint32_t counts[8];
    uint32_t *ids; /* the children's faces, child after child */
    size_t id_count;
} cell_split;

typedef struct level_job {
    builder *b;
    const uint32_t *cells;
    cell_split *out;
} level_job;

static void child_box(const mci_cell *parent, int index, const double mid[3], mci_cell *c)
{
    for (int k = 0; k < 3; k++) {
        c->lo[k] = (index >> k) & 1 ? mid[k] : parent->lo[k];
        c->hi[k] = (index >> k) & 1 ? parent->hi[k] : mid[k];
    }
}

/* The index of the lowest set bit of a child mask (lowest_bit[0] is never used). */
static const uint8_t lowest_bit[256] = {
    0, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 4, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0,
    2, 0, 1, 0, 5, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 4, 0, 1, 0, 2, 0, 1, 0,
    3, 0, 1, 0, 2, 0, 1, 0, 6, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 4, 0, 1, 0,
    2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 5, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0,
    4, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 7, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0,
    2, 0, 1, 0, 4, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 5, 0, 1, 0, 2, 0, 1, 0,
    3, 0, 1, 0, 2, 0, 1, 0, 4, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 6, 0, 1, 0,
    2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 4, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0,
    5, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0, 4, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0,
    2, 0, 1, 0};

/* Children on one side of the split along axis k (bit k of a child's index: upper
 * half): side_children[k][s] for s = 1 lower, 2 upper, 3 both. */
static const uint8_t side_children[3][4] = {
    {0, 0x55, 0xAA, 0xFF}, {0, 0x33, 0xCC, 0xFF}, {0, 0x0F, 0xF0, 0xFF}};

/* The children that hold a corner of face f (closed boxes: a corner on a split plane is
 * in the children on both sides). A triangle touches every such child, so these need
 * no separating-axis test; a face straddling a cell's edge has its corners in up to
 * three of the four children it may touch. */
static uint8_t children_holding_corners(const double *const corner[3], const mci_cell *cell,
                                        const double mid[3])
{
    uint8_t held = 0;
    for (int v = 0; v < 3; v++) {
        const double *p = corner[v];
        uint8_t in = 0xFF;
        for (int k = 0; k < 3; k++) {
            if (p[k] < cell->lo[k] || p[k] > cell->hi[k])
                in = 0;
            in &= side_children[k][(p[k] <= mid[k]) | (p[k] >= mid[k]) << 1];
        }
        held |= in;
    }
    return held;
}

/* Bit c set for each child c the face touches. The face's (float) box picks the
 * candidate children (one side of the split or both, per axis); face_touches_cell
 * decides those (at once when the exact box is inside the child). */
static uint8_t children_touched(const builder *b, const mci_cell *cell,
                                const mci_cell child[8], const double mid[3], uint32_t f)
{
    const float *box = b->face_box + 6 * (size_t)f;
    const double *v[3];
    double exact[6];
    uint8_t candidates = 0xFF, mask;
    for (int k = 0; k < 3; k++)
        candidates &= side_children[k][(box[k] <= mid[k]) | (box[3 + k] >= mid[k]) << 1];
    /* One child (most faces, deep down): the face's box meets the parent only within
     * that child, so whatever part of the face the parent holds, the child holds. The
     * face touches the parent (or is kept there because that could not be ruled out),
     * so it stays listed: the lists remain supersets of the touching faces. */
    if (!(candidates & (candidates - 1)))
        return candidates;
    for (int k = 0; k < 3; k++)
        v[k] = mci_octree_face_vertex(b->tree, f, k);
    exact_box(v, exact);
    mask = candidates & children_holding_corners(v, cell, mid);
    for (candidates &= (uint8_t)~mask; candidates; candidates &= (uint8_t)(candidates - 1)) {
        int c = lowest_bit[candidates];
        if (face_touches_cell(v, exact, &child[c]))
            mask |= (uint8_t)(1u << c);
    }
    return mask;
}

/* The children each face of a cell touches, for a range of its faces. */
typedef struct mask_job {
    const builder *b;
    const mci_cell *cell, *child;
    const double *mid;
    const uint32_t *faces;
    uint8_t *mask;
} mask_job;

static mcsg_status masks(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const mask_job *j = user;
    (void)err;
    for (size_t k = begin; k < end; k++)
        j->mask[k] = children_touched(j->b, j->cell, j->child, j->mid, j->faces[k]);
    return MCSG_OK;
}

/* The faces of the parent that touch each child. When some child would keep all of the
 * parent's faces (many faces through one point, e.g. the centre of a cylinder's cap
 * fan), splitting cannot help: the cell stays a leaf. One pass computes each face's children
 * (on the threads when the level has a cell or two: the root holds every face), a
 * second lists the faces child after child, in the parent's order. */
static mcsg_status split_cell(level_job *j, size_t i, bool parallel, mcsg_error *err)
{
    const mci_octree *t = j->b->tree;
    const mci_cell *cell = &t->cells[j->cells[i]];
    cell_split *out = &j->out[i];
    uint32_t largest = 0, offset[8];
    mci_cell child[8];
    mask_job m = {j->b, cell, child, out->mid, NULL, NULL};
    mcsg_status st = MCSG_OK;
    out->critical = cell_is_critical(t, cell);
    if (!out->critical || cell->count <= j->b->params.max_cell_faces ||
        cell->depth >= j->b->params.max_depth || !split_points(cell, out->mid))
        return MCSG_OK;
    m.faces = t->face_ids + cell->first;
    if (!(m.mask = mci_malloc_array(j->b->ctx, cell->count, sizeof *m.mask)))
        return mci_fail_nomem(err, "building the octree");
    for (int c = 0; c < 8; c++)
        child_box(cell, c, out->mid, &child[c]);
    if (parallel)
        st = mci_parallel_for_ranges(j->b->ctx, cell->count, FACE_CHUNK, masks, &m, err);
    else
        masks(&m, 0, cell->count, NULL);
    for (uint32_t k = 0; st == MCSG_OK && k < cell->count; k++)
        for (unsigned bits = m.mask[k]; bits; bits &= bits - 1)
            out->counts[lowest_bit[bits]]++;
    for (int c = 0; c < 8; c++) {
        offset[c] = c == 0 ? 0 : offset[c - 1] + out->counts[c - 1];
        largest = out->counts[c] > largest ? out->counts[c] : largest;
    }
    out->id_count = offset[7] + out->counts[7];
    out->ids = st == MCSG_OK ? mci_malloc_array(j->b->ctx, out->id_count + 1, sizeof *out->ids)
                             : NULL;
    for (uint32_t k = 0; out->ids && k < cell->count; k++)
        for (unsigned bits = m.mask[k]; bits; bits &= bits - 1)
            out->ids[offset[lowest_bit[bits]]++] = m.faces[k];
    mci_free(j->b->ctx, m.mask);
    if (st != MCSG_OK)
        return st;
    if (!out->ids)
        return mci_fail_nomem(err, "building the octree");
    out->split = largest < cell->count;
    return MCSG_OK;
}

static mcsg_status split_task(void *user, size_t i, mcsg_error *err)
{
    return split_cell(user, i, false, err);
}

/* Appends the children of a split cell (its faces in out->ids) to the tree. */
static bool add_children(builder *b, uint32_t parent, const cell_split *out, uint32_t *next,
                         size_t *next_count)
{
    mci_octree *t = b->tree;
    uint32_t first_child = (uint32_t)t->cell_count;
    if (!mci_grow_array(b->ctx, (void **)&t->cells, &b->cell_capacity, t->cell_count + 8,
                        sizeof *t->cells, 64) ||
        !mci_grow_array(b->ctx, (void **)&t->face_ids, &b->id_capacity,
                        t->face_id_count + out->id_count, sizeof *t->face_ids, 64) ||
        t->face_id_count + out->id_count >= UINT32_MAX)
        return false;
    memcpy(t->face_ids + t->face_id_count, out->ids, out->id_count * sizeof *out->ids);
    for (int i = 0; i < 8; i++) {
        mci_cell *c = &t->cells[first_child + (uint32_t)i];
        child_box(&t->cells[parent], i, out->mid, c);
        c->depth = (uint16_t)(t->cells[parent].depth + 1);
        c->child = NO_CHILD;
        c->critical = 0;
        c->first = (uint32_t)t->face_id_count;
        c->count = out->counts[i];
        t->face_id_count += out->counts[i];
        next[(*next_count)++] = first_child + (uint32_t)i;
    }
    t->cells[parent].child = first_child;
    t->cell_count += 8;
    return true;
}

/* Splits every cell of one level; *level becomes the next level's cells. */
static mcsg_status build_level(builder *b, uint32_t **level, size_t *count, mcsg_error *err)
{
    mci_octree *t = b->tree;
    cell_split *out = mci_calloc_array(b->ctx, *count + 1, sizeof *out);
    level_job job = {b, *level, out};
    uint32_t *next = NULL;
    size_t splits = 0, next_count = 0;
    mcsg_status st = out ? MCSG_OK : mci_fail_nomem(err, "building the octree");
    if (st == MCSG_OK && *count < 2) /* the root: split its faces across the threads */
        st = split_cell(&job, 0, true, err);
    else if (st == MCSG_OK)
        st = mci_parallel_for(b->ctx, *count, split_task, &job, err);
    for (size_t i = 0; st == MCSG_OK && i < *count; i++)
        splits += out[i].split;
    if (st == MCSG_OK && !(next = mci_malloc_array(b->ctx, 8 * splits + 1, sizeof *next)))
        st = mci_fail_nomem(err, "building the octree");
    for (size_t i = 0; st == MCSG_OK && i < *count; i++) {
        mci_cell *cell = &t->cells[(*level)[i]];
        cell->critical = out[i].critical;
        if (cell->depth > t->max_depth)
            t->max_depth = cell->depth;
        if (out[i].split && !add_children(b, (*level)[i], &out[i], next, &next_count))
            st = mci_fail_nomem(err, "building the octree");
        else if (!out[i].split && t->cells[(*level)[i]].critical)
            t->critical_leaf_cells++;
    }
    for (size_t i = 0; out && i < *count; i++)
        mci_free(b->ctx, out[i].ids);
    mci_free(b->ctx, out);
    mci_free(b->ctx, *level);
    *level = next;
    *count = st == MCSG_OK ? next_count : 0;
    return st;
}

/* Once the tree is built only the leaf cells' lists are read (candidate pairs, rays);
 * the split cells' lists repeat every face once per level (most of the entries) and are
 * dropped. The lists lie in cell order, so the leaves' lists move down in place. The
 * cells, grown by doubling, are trimmed too. */
static bool keep_leaf_lists(const mci_ctx *ctx, mci_octree *t)
{
    size_t kept = 0;
    uint32_t *fit;
    mci_cell *cells = mci_realloc_array(ctx, t->cells, t->cell_count, sizeof *cells);
    if (!cells)
        return false;
    t->cells = cells;
    for (size_t c = 0; c < t->cell_count; c++) {
        mci_cell *cell = &t->cells[c];
        if (cell->child != NO_CHILD) {
            cell->first = cell->count = 0;
            continue;
        }
        memmove(t->face_ids + kept, t->face_ids + cell->first, cell->count * sizeof *t->face_ids);
        cell->first = (uint32_t)kept;
        kept += cell->count;
    }
    t->face_id_count = kept;
    fit = mci_realloc_array(ctx, t->face_ids, kept + 1, sizeof *fit);
    if (fit)
        t->face_ids = fit;
    return fit != NULL;
}

static mcsg_status build_cells(builder *b, mcsg_error *err)
{
    mci_octree *t = b->tree;
    uint32_t *level;
    size_t count = 1;
    mcsg_status st = MCSG_OK;
    t->cells = mci_malloc_array(b->ctx, 64, sizeof *t->cells);
    level = mci_malloc_array(b->ctx, 1, sizeof *level);
    if (!t->cells || !level) {
        mci_free(b->ctx, level);
        return mci_fail_nomem(err, "building the octree");
    }
    b->cell_capacity = 64;
    b->id_capacity = t->face_id_count;
    memset(&t->cells[0], 0, sizeof t->cells[0]);
    root_bounds(t, &t->cells[0]);
    t->cells[0].count = (uint32_t)t->face_id_count;
    t->cells[0].child = NO_CHILD;
    t->cell_count = 1;
    level[0] = 0;
    while (st == MCSG_OK && count > 0)
        st = build_level(b, &level, &count, err);
    mci_free(b->ctx, level);
    if (st == MCSG_OK && !keep_leaf_lists(b->ctx, t))
        st = mci_fail_nomem(err, "building the octree");
    return st;
}

mcsg_status mci_octree_build(const mci_ctx *ctx, const mcsg_mesh *const *leaves,
                             size_t leaf_count, const mci_octree_params *params,
                             mci_octree *out, mcsg_error *err)
{
    builder b;
    mcsg_status st;
    memset(out, 0, sizeof *out);
    /* Face ids and cell face lists are 32-bit; the lists repeat faces, so leave room. */
    if (total_faces(leaves, leaf_count) >= UINT32_MAX / 4)
        return mci_fail(err, MCSG_ERR_LIMIT, "too many faces in the scene (%zu; at most %u)",
                        total_faces(leaves, leaf_count), UINT32_MAX / 4 - 1);
    memset(&b, 0, sizeof b);
    out->leaves = leaves;
    out->leaf_count = leaf_count;
    b.ctx = ctx;
    b.tree = out;
    b.params.max_cell_faces = params && params->max_cell_faces ? params->max_cell_faces
                                                               : DEFAULT_MAX_CELL_FACES;
    b.params.max_depth = params && params->max_depth ? params->max_depth : DEFAULT_MAX_DEPTH;
    out->face_group = params ? params->face_group : NULL;
    out->face_shell = params ? params->face_shell : NULL;
    st = index_faces(ctx, out, params ? params->skip_leaf : NULL) &&
                 (b.face_box = face_boxes(ctx, out)) != NULL
             ? build_cells(&b, err)
             : mci_fail_nomem(err, "building the octree");
    out->face_box = b.face_box;
    if (st != MCSG_OK)
        mci_octree_free(ctx, out);
    return st;
}

void mci_octree_free_boxes(const mci_ctx *ctx, mci_octree *tree)
{
    mci_free(ctx, tree->face_box);
    tree->face_box = NULL;
}

void mci_octree_free_cells(const mci_ctx *ctx, mci_octree *tree)
{
    mci_octree_free_boxes(ctx, tree);
    mci_free(ctx, tree->cells);
    mci_free(ctx, tree->face_ids);
    tree->cells = NULL;
    tree->face_ids = NULL;
    tree->cell_count = tree->face_id_count = 0;
}

void mci_octree_free(const mci_ctx *ctx, mci_octree *tree)
{
    mci_octree_free_cells(ctx, tree);
    mci_free(ctx, tree->face_base);
    mci_free(ctx, tree->face_leaf);
    memset(tree, 0, sizeof *tree);
}

/* ---------------------------------------------------------------------------------- */
/* Candidate pairs                                                                     */

/* A cell's face with what the pair loop reads, copied once per cell (the loop reads each
 * face's box and leaf once per other face of the cell). */
typedef struct cell_face {
    float box[6];
    uint32_t face, run_end; /* run_end: the first later face of another leaf */
    uint32_t cells;         /* where the face's critical leaves start in face_cells.cell */
} cell_face;

/* Each face's critical leaf cells (their positions among the critical leaves, in
 * increasing order): a pair of faces that share several cells is collected in the first
 * of them only. Collected once per shared cell, many pairs came more than once, and the
 * sort that joined the copies ran on all of them. */
typedef struct face_cells {
    uint32_t *start; /* per face: its range [start[f], start[f + 1]) of cell */
    uint32_t *cell;
} face_cells;

/* Pairs are collected in parallel, in chunks of critical leaf cells fixed in advance
 * (not by the thread count); the chunks' lists are joined and then sorted, so the
 * result does not depend on the threads. */
#define PAIR_CELLS_PER_CHUNK 256

/* A face's plane in doubles for the separation filter of crowded cells: normal n of
 * (b - a) x (c - a) as computed, np the sums of its products' magnitudes (per
 * component), a the first corner. */
typedef struct face_plane {
    double n[3], np[3], a[3];
} face_plane;

typedef struct pair_chunk_list {
    uint64_t *pairs;
    size_t count, capacity;
    cell_face *faces; /* scratch: the current cell's faces */
    size_t face_capacity;
    face_plane *planes; /* scratch: their planes, in crowded cells */
    size_t plane_capacity;
} pair_chunk_list;

/* ---------------------------------------------------------------------------------- */
/* Separation by a face's plane, in crowded cells                                      */

/* Cells with more faces than this test each pair against both faces' planes before
 * listing it. Such cells are the ones the octree could not split: faces converging on
 * one point (the apex of a CAD fan, in every child around it), where two fans on
 * parallel planes 1e-7 apart gave 15 million pairs, none meeting. Below it the pair
 * test does the same work once, later. */
#define CROWDED_CELL_FACES 96

#define DBL_EPS 0x1p-53

static void face_plane_of(const mci_octree *t, uint32_t f, face_plane *p)
{
    const double *a = mci_octree_face_vertex(t, f, 0), *b = mci_octree_face_vertex(t, f, 1),
                 *c = mci_octree_face_vertex(t, f, 2);
    double d1[3], d2[3];
    for (int k = 0; k < 3; k++) {
        d1[k] = b[k] - a[k];
        d2[k] = c[k] - a[k];
        p->a[k] = a[k];
    }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        double u = d1[i] * d2[j], w = d1[j] * d2[i];
        p->n[k] = u - w;
        p->np[k] = fabs(u) + fabs(w);
    }
}

/* The side of vertex v against plane p: +1 or -1 when certain, 0 otherwise. With
 * d = b - a and e = c - a rounded (relative error u = 2^-53 each), each normal component
 * is within 4.2u of its sum of product magnitudes np (two rounded products, one
 * subtraction, rounded factors); v - a rounded adds u |N_k| |v - a|_k, the three
 * products u and the two additions 2u of their magnitudes: at most 8.3u sum_k np_k
 * |v - a|_k plus second-order terms, charged 10u; 2^-1000 covers underflow. A value
 * that is not finite decides nothing. */
static int side_of_plane(const face_plane *p, const double *v)
{
    double s = 0, bound = 0;
    for (int k = 0; k < 3; k++) {
        double e = v[k] - p->a[k];
        s += p->n[k] * e;
        bound += p->np[k] * fabs(e);
    }
    bound = bound * (10 * DBL_EPS) * (1 + 0x1p-40) + 0x1p-1000;
    if (!isfinite(s) || !isfinite(bound))
        return 0;
    return s > bound ? 1 : s < -bound ? -1 : 0;
}

/* Whether vertex x lies on the plane p of corners a[], exactly: the filter first for
 * those off it, a coordinate shared by all four (CAD parts cut along axis planes), else
 * the exact orientation. */
static bool on_face_plane(const face_plane *p, const double *const a[3], const double *x)
{
    if (side_of_plane(p, x) != 0)
        return false;
    for (int k = 0; k < 3; k++)
        if (a[0][k] == x[k] && a[1][k] == x[k] && a[2][k] == x[k])
            return true;
    return mci_orient3d_vertices(a[0], a[1], a[2], x) == 0;
}

/* Whether faces f (plane p) and g are coplanar, exactly, and touch at one common corner
 * only (mci_coplanar_touch_at_corner_only, in a projection along the normal's largest
 * component). Two fans meeting at one apex on a shared plane, as two parts unioned along
 * a cut, have millions of such pairs; intersect_pairs.c would drop their contacts after
 * the pair test anyway. */
static bool coplanar_touch_at_corner_only(const mci_octree *t, const face_plane *p, uint32_t f,
                                          uint32_t g)
{
    const double *a[3], *b[3], *off[3];
    int axis = 0, n_off = 0;
    for (int k = 0; k < 3; k++) {
        a[k] = mci_octree_face_vertex(t, f, k);
        b[k] = mci_octree_face_vertex(t, g, k);
    }
    for (int k = 0; k < 3; k++) { /* g's corners that are not f's */
        bool shared = false;
        for (int i = 0; i < 3; i++)
            shared |= b[k][0] == a[i][0] && b[k][1] == a[i][1] && b[k][2] == a[i][2];
        if (!shared)
            off[n_off++] = b[k];
    }
    if (n_off != 2 || !on_face_plane(p, a, off[0]) || !on_face_plane(p, a, off[1]))
        return false;
    for (int k = 1; k < 3; k++)
        if (fabs(p->n[k]) > fabs(p->n[axis]))
            axis = k;
    return mci_coplanar_touch_at_corner_only(a, b, axis);
}

/* Whether face g lies strictly on one side of face f's plane p. */
static bool face_plane_separates(const mci_octree *t, const face_plane *p, uint32_t g)
{
    int first = side_of_plane(p, mci_octree_face_vertex(t, g, 0));
    return first != 0 && side_of_plane(p, mci_octree_face_vertex(t, g, 1)) == first &&
           side_of_plane(p, mci_octree_face_vertex(t, g, 2)) == first;
}

static bool cell_faces_overlap(const cell_face *a, const cell_face *b)
{
    for (int k = 0; k < 3; k++)
        if (a->box[3 + k] < b->box[k] || b->box[3 + k] < a->box[k])
            return false;
    return true;
}

/* Whether critical leaf `cell`, which lists both faces, may be the first that does: a
 * and b are the faces' cell lists (increasing), a merge walk up to `cell`. The walk
 * gives up (true: the sort drops the copy) after a few steps, so that two long faces
 * sharing m cells (a cylinder's sides) cost a bounded walk in each, not O(m). */
enum { SHARED_CELL_STEPS = 8 };

static bool first_shared_cell(const uint32_t *a, const uint32_t *b, uint32_t cell)
{
    for (int step = 0; *a < cell && *b < cell; step++) {
        if (*a == *b)
            return false;
        if (step == SHARED_CELL_STEPS)
            return true;
        if (*a < *b)
            a++;
        else
            b++;
    }
    return true;
}

/* Faces of one shell that crosses itself (a group each) sharing an edge: they meet only
 * along it, unless folded onto each other (their third corners in one half-plane about
 * the edge, as where rounding flattened a sliver): then they overlap and are tested. */
static bool shell_neighbours(const mci_octree *t, uint32_t f, uint32_t g)
{
    const double *shared[3] = {NULL, NULL, NULL}, *third_f = NULL, *third_g = NULL;
    int common = 0;
    if (!t->face_shell || t->face_shell[f] != t->face_shell[g] ||
        t->face_leaf[f] != t->face_leaf[g])
        return false;
    for (int i = 0; i < 3; i++) {
        const double *p = mci_octree_face_vertex(t, f, i);
        bool found = false;
        for (int j = 0; j < 3 && !found; j++) {
            const double *q = mci_octree_face_vertex(t, g, j);
            found = p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
        }
        if (found)
            shared[common++] = p;
        else
            third_f = p;
    }
    if (common != 2)
        return false;
    for (int j = 0; j < 3 && !third_g; j++) {
        const double *q = mci_octree_face_vertex(t, g, j);
        if (!(q[0] == shared[0][0] && q[1] == shared[0][1] && q[2] == shared[0][2]) &&
            !(q[0] == shared[1][0] && q[1] == shared[1][1] && q[2] == shared[1][2]))
            third_g = q;
    }
    return third_f && third_g &&
           mci_half_plane_class(shared[0], shared[1], third_f, third_g) != 0;
}

/* A cell lists its faces in increasing id order, so each leaf's faces form one run: a
 * face is paired with the faces after its run only. `k`: the cell's position among the
 * critical leaves. */
static bool collect_cell_pairs(const mci_ctx *ctx, const mci_octree *t, const float *box,
                               const face_cells *fc, const mci_cell *cell, uint32_t k,
                               pair_chunk_list *out)
{
    const uint32_t *ids = t->face_ids + cell->first;
    uint32_t n = cell->count;
    bool crowded = n > CROWDED_CELL_FACES;
    if (!mci_grow_array(ctx, (void **)&out->faces, &out->face_capacity, n, sizeof *out->faces,
                        64))
        return false;
    for (uint32_t i = n; i-- > 0;) {
        cell_face *c = &out->faces[i];
        c->face = ids[i];
        c->cells = fc->start[ids[i]];
        memcpy(c->box, box + 6 * (size_t)ids[i], sizeof c->box);
        /* A grouped leaf's shells are not runs of ids: its faces meet every later face,
         * those of their own group left out below. */
        c->run_end = i + 1 < n && t->face_leaf[ids[i + 1]] == t->face_leaf[ids[i]] &&
                             !in_grouped_leaf(t, ids[i])
                         ? out->faces[i + 1].run_end
                         : i + 1;
    }
    if (crowded && !mci_grow_array(ctx, (void **)&out->planes, &out->plane_capacity, n,
                                   sizeof *out->planes, 64))
        return false;
    for (uint32_t i = 0; crowded && i < n; i++)
        face_plane_of(t, ids[i], &out->planes[i]);
    for (uint32_t i = 0; i < n; i++) {
        const cell_face *a = &out->faces[i];
        if (!mci_grow_array(ctx, (void **)&out->pairs, &out->capacity,
                            out->count + (n - a->run_end), sizeof *out->pairs, 64))
            return false;
        for (uint32_t j = a->run_end; j < n; j++)
            if (cell_faces_overlap(a, &out->faces[j]) &&
                (!t->face_group || face_group(t, a->face) != face_group(t, out->faces[j].face)) &&
                first_shared_cell(fc->cell + a->cells, fc->cell + out->faces[j].cells, k) &&
                !(crowded && (face_plane_separates(t, &out->planes[i], out->faces[j].face) ||
                              face_plane_separates(t, &out->planes[j], a->face) ||
                              coplanar_touch_at_corner_only(t, &out->planes[i], a->face,
                                                            out->faces[j].face))) &&
                !shell_neighbours(t, a->face, out->faces[j].face))
                out->pairs[out->count++] = (uint64_t)a->face << 32 | out->faces[j].face;
    }
    return true;
}

typedef struct pair_job {
    const mci_ctx *ctx;
    const mci_octree *tree;
    float *box;
    uint32_t *cells; /* the critical leaf cells */
    size_t cell_count;
    face_cells fc;
    pair_chunk_list *chunks;
} pair_job;

static mcsg_status collect_chunk(void *user, size_t begin, size_t end, mcsg_error *err)
{
    const pair_job *j = user;
    pair_chunk_list *out = &j->chunks[begin / PAIR_CELLS_PER_CHUNK];
    bool ok = true;
    for (size_t k = begin; ok && k < end; k++)
        ok = collect_cell_pairs(j->ctx, j->tree, j->box, &j->fc, &j->tree->cells[j->cells[k]],
                                (uint32_t)k, out);
    mci_free(j->ctx, out->faces);
    mci_free(j->ctx, out->planes);
    out->faces = NULL;
    out->planes = NULL;
    return ok ? MCSG_OK : mci_fail_nomem(err, "collecting candidate pairs");
}

/* The critical leaf cells, in cell order. */
static uint32_t *critical_leaves(const mci_ctx *ctx, const mci_octree *tree, size_t *count)
{
    uint32_t *cells = mci_malloc_array(ctx, tree->cell_count + 1, sizeof *cells);
    *count = 0;
    for (size_t c = 0; cells && c < tree->cell_count; c++)
        if (tree->cells[c].child == NO_CHILD && tree->cells[c].critical)
            cells[(*count)++] = (uint32_t)c;
    return cells;
}

/* face_cells of the critical leaves (cells[0..count)), in counting-sort order. */
static bool list_face_cells(const mci_ctx *ctx, const mci_octree *tree, const uint32_t *cells,
                            size_t count, face_cells *fc)
{
    uint32_t faces = tree->face_base[tree->leaf_count];
    size_t total = 0;
    fc->start = mci_calloc_array(ctx, (size_t)faces + 2, sizeof *fc->start);
    for (size_t k = 0; k < count; k++)
        total += tree->cells[cells[k]].count;
    fc->cell = fc->start ? mci_malloc_array(ctx, total + 1, sizeof *fc->cell) : NULL;
    if (!fc->cell)
        return false;
    /* Counts at f + 2, so that the fill leaves each range at [start[f], start[f + 1]). */
    for (size_t k = 0; k < count; k++) {
        const mci_cell *c = &tree->cells[cells[k]];
        for (uint32_t i = 0; i < c->count; i++)
            fc->start[tree->face_ids[c->first + i] + 2]++;
    }
    for (uint32_t f = 0; f < faces; f++)
        fc->start[f + 2] += fc->start[f + 1];
    for (size_t k = 0; k < count; k++) {
        const mci_cell *c = &tree->cells[cells[k]];
        for (uint32_t i = 0; i < c->count; i++)
            fc->cell[fc->start[tree->face_ids[c->first + i] + 1]++] = (uint32_t)k;
    }
    return true;
}

/* The chunks' pairs sorted and unique, without one sort over all of them: a pass puts
 * each pair in the bucket of its first face's range (contiguous ranges, so bucket order
 * is key order), then each bucket is sorted on its own, on the threads, and its repeats
 * (pairs whose first shared cell was not decided: see first_shared_cell) dropped. One
 * radix sort over all pairs ran on one thread: a large serial part of the step. */
enum { PAIRS_PER_BUCKET = 2048 };

typedef struct bucket_job {
    uint64_t *keys, *scratch; /* bucket b: [start[b], start[b + 1]) of each */
    const size_t *start;
    size_t *unique;           /* per bucket: its pairs once each, at its start in keys */
} bucket_job;

static mcsg_status bucket_task(void *user, size_t b, mcsg_error *err)
{
    const bucket_job *j = user;
    uint64_t *keys = j->keys + j->start[b];
    size_t n = j->start[b + 1] - j->start[b];
    (void)err;
    mci_radix_sort_u64_buffered(keys, j->scratch + j->start[b], n);
    j->unique[b] = mci_unique_u64(keys, n);
    return MCSG_OK;
}

/* The bucket of a pair: its first face's id >> shift. */
static int bucket_shift(uint32_t faces, size_t pairs)
{
    size_t wanted = pairs / PAIRS_PER_BUCKET + 1;
    int shift = 0;
    while (((size_t)faces >> shift) > wanted)
        shift++;
    return shift;
}

/* Moving the chunks' pairs into their buckets, on the threads: the chunks are taken in
 * FILL_GROUPS groups of consecutive chunks; each group counts its pairs per bucket, the
 * counts give each group its place in each bucket (groups in order within a bucket: the
 * order of one pass over the chunks), then each group moves its pairs and frees its
 * chunks' lists. One pass on one thread was a serial stretch of the step. */
enum { FILL_GROUPS = 16 };

typedef struct fill_job {
    const mci_ctx *ctx;
    pair_chunk_list *chunks;
    size_t chunk_count, buckets;
    int shift;
    size_t *at; /* group g, bucket b: at[g * buckets + b] */
    uint64_t *keys;
} fill_job;

static size_t group_first_chunk(const fill_job *j, size_t g)
{
    return g * j->chunk_count / FILL_GROUPS;
}

static mcsg_status count_group(void *user, size_t g, mcsg_error *err)
{
    const fill_job *j = user;
    size_t *at = j->at + g * j->buckets;
    (void)err;
    for (size_t c = group_first_chunk(j, g); c < group_first_chunk(j, g + 1); c++)
        for (size_t i = 0; i < j->chunks[c].count; i++)
            at[j->chunks[c].pairs[i] >> 32 >> j->shift]++;
    return MCSG_OK;
}

static mcsg_status move_group(void *user, size_t g, mcsg_error *err)
{
    const fill_job *j = user;
    size_t *at = j->at + g * j->buckets;
    (void)err;
    for (size_t c = group_first_chunk(j, g); c < group_first_chunk(j, g + 1); c++) {
        for (size_t i = 0; i < j->chunks[c].count; i++)
            j->keys[at[j->chunks[c].pairs[i] >> 32 >> j->shift]++] = j->chunks[c].pairs[i];
        mci_free(j->ctx, j->chunks[c].pairs);
        j->chunks[c].pairs = NULL;
    }
    return MCSG_OK;
}

/* Moves the chunks' pairs into their buckets (each chunk's list freed once moved; bucket
 * b gets [start[b], start[b + 1]) of keys); false when out of memory (the lists not moved
 * stay with the chunks). */
static bool fill_buckets(const mci_ctx *ctx, pair_chunk_list *chunks, size_t n, int shift,
                         uint64_t *keys, size_t *start, size_t buckets)
{
    fill_job j = {ctx, chunks, n, buckets, shift,
                  mci_calloc_array(ctx, FILL_GROUPS * buckets + 1, sizeof *j.at), keys};
    if (!j.at)
        return false;
    (void)mci_parallel_for(ctx, FILL_GROUPS, count_group, &j, NULL);
    start[0] = 0;
    for (size_t b = 0; b < buckets; b++) {
        size_t place = start[b];
        for (size_t g = 0; g < FILL_GROUPS; g++) {
            size_t count = j.at[g * buckets + b];
            j.at[g * buckets + b] = place;
            place += count;
        }
        start[b + 1] = place;
    }
    (void)mci_parallel_for(ctx, FILL_GROUPS, move_group, &j, NULL);
    mci_free(ctx, j.at);
    return true;
}

static mcsg_status sorted_unique_pairs(const mci_ctx *ctx, const mci_octree *tree,
                                       pair_chunk_list *chunks, size_t n, uint64_t **pairs,
                                       size_t *count, mcsg_error *err)
{
    size_t total = 0, buckets;
    uint32_t faces = tree->face_base[tree->leaf_count];
    int shift;
    bucket_job j = {NULL, NULL, NULL, NULL};
    size_t *start = NULL;
    mcsg_status st = MCSG_OK;
    for (size_t c = 0; c < n; c++)
        total += chunks[c].count;
    shift = bucket_shift(faces, total);
    buckets = ((size_t)faces >> shift) + 1;
    j.keys = mci_malloc_array(ctx, total + 1, sizeof *j.keys);
    j.start = start = mci_calloc_array(ctx, buckets + 1, sizeof *start);
    j.unique = mci_malloc_array(ctx, buckets + 1, sizeof *j.unique);
    if (!j.keys || !start || !j.unique ||
        !fill_buckets(ctx, chunks, n, shift, j.keys, start, buckets) ||
        !(j.scratch = mci_malloc_array(ctx, total + 1, sizeof *j.scratch)))
        st = mci_fail_nomem(err, "collecting candidate pairs");
    if (st == MCSG_OK)
        st = mci_parallel_for(ctx, buckets, bucket_task, &j, err);
    for (size_t b = 0; st == MCSG_OK && b < buckets; b++) { /* the buckets' runs joined */
        memmove(j.keys + *count, j.keys + start[b], j.unique[b] * sizeof *j.keys);
        *count += j.unique[b];
    }
    mci_free(ctx, j.scratch);
    mci_free(ctx, start);
    mci_free(ctx, j.unique);
    if (st == MCSG_OK)
        *pairs = j.keys;
    else
        mci_free(ctx, j.keys);
    return st;
}

mcsg_status mci_octree_candidate_pairs(const mci_ctx *ctx, const mci_octree *tree,
                                       uint64_t **pairs, size_t *count, mcsg_error *err)
{
    size_t chunk_count = 0;
    /* Contiguous boxes: a pair's test reads 48 bytes instead of 12 vertices. The build's
     * when the tree still has them, else computed again (a pass over the faces). */
    pair_job job = {ctx, tree, tree->face_box ? tree->face_box : face_boxes(ctx, tree), NULL,
                    0, {NULL, NULL}, NULL};
    mcsg_status st = MCSG_OK;
    *pairs = NULL;
    *count = 0;
    if (job.box)
        job.cells = critical_leaves(ctx, tree, &job.cell_count);
    chunk_count = (job.cell_count + PAIR_CELLS_PER_CHUNK - 1) / PAIR_CELLS_PER_CHUNK;
    if (job.cells && list_face_cells(ctx, tree, job.cells, job.cell_count, &job.fc))
        job.chunks = mci_calloc_array(ctx, chunk_count + 1, sizeof *job.chunks);
    if (!job.box || !job.cells || !job.chunks)
        st = mci_fail_nomem(err, "collecting candidate pairs");
    if (st == MCSG_OK)
        st = mci_parallel_for_ranges(ctx, job.cell_count, PAIR_CELLS_PER_CHUNK, collect_chunk,
                                     &job, err);
    mci_free(ctx, job.cells);
    mci_free(ctx, job.fc.start);
    mci_free(ctx, job.fc.cell);
    if (job.box != tree->face_box)
        mci_free(ctx, job.box);
    /* A pair sharing several cells may have been collected in more than one: keep one. */
    if (st == MCSG_OK)
        st = sorted_unique_pairs(ctx, tree, job.chunks, chunk_count, pairs, count, err);
    for (size_t c = 0; job.chunks && c < chunk_count; c++)
        mci_free(ctx, job.chunks[c].pairs);
    mci_free(ctx, job.chunks);
    return st;
}
