/*
 * Exact ray shooting (paper §5.2 first seeds, §5.5): where a point is with respect to a
 * closed mesh, by the signed crossings of a ray along +x (the winding number; the paper
 * counts their parity, which is the same for one outward shell), symbolically perturbed
 * so that rays through edges and vertices are decided consistently (no re-shooting, no
 * nudge). Through the octree, only the leaf's faces in the cells the ray passes through
 * are tested.
 */
#include "csg/rays.h"
#include "base/sort.h"

#include <stdlib.h>
#include <string.h>

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
         * leaves: scanning whole lists, a dense scene's rays read tens of millions of
         * face ids for the few of one leaf). */
        for (uint32_t i = first_at_least(o->face_ids, c->first, c->first + c->count, first);
             i < c->first + c->count && o->face_ids[i] < end; i++) {
            if (!mci_grow_array(ctx, (void **)&s->faces, &s->face_capacity, n + 1,
                                sizeof *s->faces, 64))
                return false;
            s->faces[n++] = o->face_ids[i];
        }
    }
    mci_sort_u32(s->faces, n);
    s->face_count = 0;
    for (size_t i = 0; i < n; i++)
        if (i == 0 || s->faces[i] != s->faces[i - 1])
            s->faces[s->face_count++] = s->faces[i];
    return true;
}

bool mci_ray_winding_octree(const mci_ctx *ctx, const mci_point *p, const mci_octree *o,
                            uint32_t m, mci_ray_scratch *s, int *winding, bool *decided)
{
    double lo[3], hi[3];
    mci_point_bounds(p, lo, hi);
    *winding = 0;
    *decided = false;
    if (!collect_ray_faces(ctx, o, m, lo, hi, s))
        return false;
    for (size_t i = 0; i < s->face_count; i++) {
        uint32_t f = s->faces[i];
        if (!ray_crossing(p, lo, hi, mci_octree_face_vertex(o, f, 0),
                          mci_octree_face_vertex(o, f, 1), mci_octree_face_vertex(o, f, 2),
                          winding))
            return true;
    }
    *decided = true;
    return true;
}

/* The sign of the normal's component `axis` of the plane through a, b, c. */
static int normal_sign(const double *a, const double *b, const double *c, int axis)
{
    mci_point pa, pb, pc;
    mci_point_explicit(&pa, a);
    mci_point_explicit(&pb, b);
    mci_point_explicit(&pc, c);
    return mci_orient2d_projected(&pa, &pb, &pc, axis);
}

/* Face a, b, c holds p, which lies in plane `at`: +1 or -1 when the face lies in that
 * plane facing the same or the other way, 0 when it does not lie in it. */
static int coincident_orientation(const double *a, const double *b, const double *c,
                                  const mci_plane *at)
{
    int axis, sign;
    if (mci_orient3d_vertex(a, at) != 0 || mci_orient3d_vertex(b, at) != 0 ||
        mci_orient3d_vertex(c, at) != 0 || (axis = mci_plane_projection_axis(at, &sign)) < 0)
        return 0;
    return normal_sign(a, b, c, axis) * sign;
}

/* Whether p, a point of the plane of a, b, c, lies in the open triangle. */
static bool strictly_inside(const mci_point *p, const double *a, const double *b, const double *c)
{
    mci_plane plane;
    int which;
    mci_plane_init(&plane, a, b, c);
    return mci_point_in_triangle(p, &plane, &which) == MCI_INSIDE;
}

/* The two windings from the ray's: it starts at p + (0, e, e^2), on side sigma of `at`
 * (0 when the plane is across the ray, which then leaves it towards nx), and crosses the
 * faces holding p right away when it heads towards the plane (their net orientation
 * `coincident`, against at's normal). Behind those faces the number is `coincident`
 * more than in front. */
static void windings_beside(const mci_plane *at, int beyond, int coincident, int *behind,
                            int *in_front)
{
    int n[3], sigma, side, value;
    for (int k = 0; k < 3; k++)
        n[k] = normal_sign(at->a, at->b, at->c, k);
    sigma = n[1] != 0 ? n[1] : n[2];
    side = sigma != 0 ? sigma : n[0];
    value = beyond + (sigma * n[0] < 0 ? n[0] * coincident : 0);
    *in_front = side > 0 ? value : value - coincident;
    *behind = *in_front + coincident;
}

bool mci_ray_windings_on_plane(const mci_ctx *ctx, const mci_point *p, const mci_octree *o,
                               uint32_t m, const mci_plane *at, mci_ray_scratch *s,
                               mci_plane_windings *out)
{
    double lo[3], hi[3];
    int beyond = 0, coincident = 0;
    mci_point_bounds(p, lo, hi);
    out->decided = false;
    out->first_same = UINT32_MAX;
    if (!collect_ray_faces(ctx, o, m, lo, hi, s))
        return false;
    for (size_t i = 0; i < s->face_count; i++) {
        const double *a = mci_octree_face_vertex(o, s->faces[i], 0),
                     *b = mci_octree_face_vertex(o, s->faces[i], 1),
                     *c = mci_octree_face_vertex(o, s->faces[i], 2);
        if (!ray_crossing(p, lo, hi, a, b, c, &beyond)) { /* the face holds p */
            int orientation = coincident_orientation(a, b, c, at);
            /* Across the plane the face meets it at p; on the face's border, p is on the
             * neighbours in the plane too, and each sheet must count once. */
            if (orientation == 0 || !strictly_inside(p, a, b, c))
                return true;
            coincident += orientation;
            if (orientation > 0 && mci_octree_face_group(o, s->faces[i]) < out->first_same)
                out->first_same = mci_octree_face_group(o, s->faces[i]);
        }
    }
    windings_beside(at, beyond, coincident, &out->behind, &out->in_front);
    out->decided = true;
    return true;
}

bool mci_ray_label_octree(const mci_ctx *ctx, const mci_point *p, const mci_octree *o,
                          uint32_t m, mci_ray_scratch *s, mci_label *label)
{
    int winding;
    bool decided;
    if (!mci_ray_winding_octree(ctx, p, o, m, s, &winding, &decided))
        return false;
    *label = !decided ? MCI_LABEL_UNKNOWN : winding > 0 ? MCI_LABEL_IN : MCI_LABEL_OUT;
    return true;
}
