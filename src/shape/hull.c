/*
 * Exact convex hulls (shape/hull.h).
 *
 * 3D: Quickhull's incremental scheme with conflict lists. Each point outside the current
 * hull waits on one face it sees; a face's point is added by removing every face it sees
 * (a connected set found by a walk over neighbours) and joining the horizon to it. The
 * points waiting on removed faces move to a new face they see, or are inside: the new
 * faces cover every outside point that saw a removed face. "Sees" is a strict exact
 * orientation test, so a point in a face's plane never removes it: no new triangle is
 * flat, and the result's faces are the hull's, split into triangles.
 *
 * 2D: Andrew's monotone chain with exact orientation, dropping collinear points.
 */
#include "shape/hull.h"

#include "base/sort_template.h"
#include "exact/kernel.h"
#include "exact/predicates.h"

#include <string.h>

typedef struct xyz_point {
    double x, y, z;
} xyz_point;

#define XYZ_LESS(a, b)                                                                    \
    ((a)->x < (b)->x || ((a)->x == (b)->x && ((a)->y < (b)->y ||                          \
                                             ((a)->y == (b)->y && (a)->z < (b)->z))))
MCI_DEFINE_SORT(sort_xyz_points, xyz_point, XYZ_LESS)

typedef struct hull_face {
    uint32_t v[3];
    uint32_t nb[3];   /* the face across edge v[i] -> v[i + 1] */
    uint32_t conflict; /* first waiting point, or UINT32_MAX */
    uint32_t seen;    /* stamp of the last walk that visited it */
    bool alive, visible;
} hull_face;

typedef struct hull3 {
    const mci_ctx *ctx;
    const double *p;  /* 3 per unique point */
    size_t n;
    uint32_t *next;   /* conflict lists */
    hull_face *faces;
    size_t face_count, face_cap;
    uint32_t *stack, *visible, *start_of, *end_of;
    size_t stack_cap, visible_cap;
    uint32_t stamp;
} hull3;

#define P(h, i) ((h)->p + 3 * (size_t)(i))

static int sees(const hull3 *h, const hull_face *f, uint32_t q)
{
    return mci_orient3d_vertices(P(h, f->v[0]), P(h, f->v[1]), P(h, f->v[2]), P(h, q)) > 0;
}

/* Unique points in lexicographic order (flat xyz). */
static double *unique_points(const mci_ctx *ctx, const double *xyz, size_t n, size_t *count)
{
    xyz_point *s = mci_malloc_array(ctx, n + 1, sizeof *s);
    size_t k = 0;
    if (!s)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        s[i].x = xyz[3 * i] == 0 ? 0.0 : xyz[3 * i];
        s[i].y = xyz[3 * i + 1] == 0 ? 0.0 : xyz[3 * i + 1];
        s[i].z = xyz[3 * i + 2] == 0 ? 0.0 : xyz[3 * i + 2];
    }
    sort_xyz_points(s, n);
    for (size_t i = 0; i < n; i++) {
        if (k == 0 || XYZ_LESS(&s[k - 1], &s[i]))
            s[k++] = s[i];
    }
    *count = k;
    return (double *)(void *)s; /* three doubles per point, no padding */
}

static bool collinear3(const double *a, const double *b, const double *c)
{
    return mci_orient2d(a[0], a[1], b[0], b[1], c[0], c[1]) == 0 &&
           mci_orient2d(a[1], a[2], b[1], b[2], c[1], c[2]) == 0 &&
           mci_orient2d(a[2], a[0], b[2], b[0], c[2], c[0]) == 0;
}

static uint32_t new_face(hull3 *h, uint32_t a, uint32_t b, uint32_t c)
{
    hull_face *f;
    if (!mci_grow_array(h->ctx, (void **)&h->faces, &h->face_cap, h->face_count + 1,
                        sizeof *h->faces, 64))
        return UINT32_MAX;
    f = &h->faces[h->face_count];
    memset(f, 0, sizeof *f);
    memcpy(f->v, (uint32_t[3]){a, b, c}, sizeof f->v);
    f->nb[0] = f->nb[1] = f->nb[2] = UINT32_MAX;
    f->conflict = UINT32_MAX;
    f->alive = true;
    return (uint32_t)h->face_count++;
}

/* Put point q on the first face of faces[first ..] that it sees; false if none. */
static bool assign(hull3 *h, uint32_t q, size_t first)
{
    for (size_t f = first; f < h->face_count; f++) {
        if (h->faces[f].alive && sees(h, &h->faces[f], q)) {
            h->next[q] = h->faces[f].conflict;
            h->faces[f].conflict = q;
            return true;
        }
    }
    return false;
}

static int edge_index(const hull_face *f, uint32_t a, uint32_t b)
{
    for (int i = 0; i < 3; i++) {
        if (f->v[i] == a && f->v[(i + 1) % 3] == b)
            return i;
    }
    return -1;
}

/* The first tetrahedron, outward; false when every point lies on one plane. */
static bool start(hull3 *h, bool *ok)
{
    static const int faces[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
    uint32_t q[4] = {0, 1, 0, 0};
    size_t j = 2;
    while (j < h->n && collinear3(P(h, 0), P(h, 1), P(h, j)))
        j++;
    if (j >= h->n)
        return false;
    q[2] = (uint32_t)j;
    for (j = 0; j < h->n; j++) {
        if (mci_orient3d_vertices(P(h, 0), P(h, 1), P(h, q[2]), P(h, j)) != 0)
            break;
    }
    if (j >= h->n)
        return false;
    q[3] = (uint32_t)j;
    for (int k = 0; k < 4; k++) {
        uint32_t a = q[faces[k][0]], b = q[faces[k][1]], c = q[faces[k][2]];
        bool behind = mci_orient3d_vertices(P(h, a), P(h, b), P(h, c), P(h, q[faces[k][3]])) < 0;
        if (new_face(h, a, behind ? b : c, behind ? c : b) == UINT32_MAX)
            return *ok = false;
    }
    for (int k = 0; k < 4; k++) {
        for (int i = 0; i < 3; i++) {
            hull_face *f = &h->faces[k];
            for (int m = 0; m < 4; m++) {
                if (m != k && edge_index(&h->faces[m], f->v[(i + 1) % 3], f->v[i]) >= 0)
                    f->nb[i] = (uint32_t)m;
            }
        }
    }
    for (uint32_t i = 0; i < h->n; i++) {
        if (i != q[0] && i != q[1] && i != q[2] && i != q[3])
            assign(h, i, 0);
    }
    return true;
}

static bool push(hull3 *h, uint32_t **array, size_t *cap, size_t len, uint32_t value)
{
    if (!mci_grow_array(h->ctx, (void **)array, cap, len + 1, sizeof **array, 64))
        return false;
    (*array)[len] = value;
    return true;
}

/* The faces point p sees, from face f0 on (they are connected). */
static bool find_visible(hull3 *h, uint32_t f0, uint32_t p, size_t *count)
{
    size_t top = 0, len = 0;
    h->stamp++;
    h->faces[f0].seen = h->stamp;
    h->faces[f0].visible = true;
    if (!push(h, &h->stack, &h->stack_cap, top++, f0))
        return false;
    while (top > 0) {
        uint32_t f = h->stack[--top];
        if (!push(h, &h->visible, &h->visible_cap, len++, f))
            return false;
        for (int i = 0; i < 3; i++) {
            uint32_t g = h->faces[f].nb[i];
            if (h->faces[g].seen == h->stamp)
                continue;
            h->faces[g].seen = h->stamp;
            h->faces[g].visible = sees(h, &h->faces[g], p);
            if (h->faces[g].visible && !push(h, &h->stack, &h->stack_cap, top++, g))
                return false;
        }
    }
    *count = len;
    return true;
}

/* Join the horizon of the visible faces to p, and link the new faces. */
static bool add_cone(hull3 *h, uint32_t p, size_t visible, size_t *first_new)
{
    *first_new = h->face_count;
    for (size_t k = 0; k < visible; k++) {
        for (int i = 0; i < 3; i++) {
            hull_face *f = &h->faces[h->visible[k]];
            uint32_t g = f->nb[i], a = f->v[i], b = f->v[(i + 1) % 3], nf;
            int back;
            if (h->faces[g].visible && h->faces[g].seen == h->stamp)
                continue;
            nf = new_face(h, a, b, p);
            if (nf == UINT32_MAX)
                return false;
            h->faces[nf].nb[0] = g;
            back = edge_index(&h->faces[g], b, a);
            h->faces[g].nb[back] = nf;
            h->start_of[a] = nf;
            h->end_of[b] = nf;
        }
    }
    for (size_t f = *first_new; f < h->face_count; f++) {
        hull_face *nf = &h->faces[f];
        nf->nb[1] = h->start_of[nf->v[1]]; /* b -> p pairs with p -> b of (b, c, p) */
        nf->nb[2] = h->end_of[nf->v[0]];   /* p -> a pairs with a -> p of (z, a, p) */
    }
    return true;
}

static bool add_point(hull3 *h, uint32_t f0)
{
    uint32_t p = h->faces[f0].conflict;
    size_t visible, first_new;
    h->faces[f0].conflict = h->next[p];
    if (!find_visible(h, f0, p, &visible) || !add_cone(h, p, visible, &first_new))
        return false;
    for (size_t k = 0; k < visible; k++) {
        hull_face *f = &h->faces[h->visible[k]];
        uint32_t q = f->conflict;
        f->alive = false;
        f->visible = false;
        f->conflict = UINT32_MAX;
        while (q != UINT32_MAX) {
            uint32_t after = h->next[q];
            assign(h, q, first_new);
            q = after;
        }
    }
    return true;
}

static mcsg_status hull_mesh(hull3 *h, mcsg_mesh *out, mcsg_error *err)
{
    size_t tris = 0, verts = 0;
    uint32_t *map = mci_malloc_array(h->ctx, h->n + 1, sizeof *map);
    mcsg_status st;
    if (!map)
        return mci_fail_nomem(err, "making a convex hull");
    for (size_t i = 0; i < h->n; i++)
        map[i] = UINT32_MAX;
    for (size_t f = 0; f < h->face_count; f++) {
        for (int i = 0; h->faces[f].alive && i < 3; i++) {
            if (map[h->faces[f].v[i]] == UINT32_MAX)
                map[h->faces[f].v[i]] = (uint32_t)verts++;
        }
        tris += h->faces[f].alive;
    }
    st = mci_mesh_alloc(h->ctx, out, verts, tris, err);
    for (size_t i = 0; st == MCSG_OK && i < h->n; i++) {
        if (map[i] != UINT32_MAX)
            memcpy(out->vertices + 3 * (size_t)map[i], P(h, i), 3 * sizeof(double));
    }
    for (size_t f = 0, t = 0; st == MCSG_OK && f < h->face_count; f++) {
        for (int i = 0; h->faces[f].alive && i < 3; i++)
            out->triangles[3 * t + (size_t)i] = map[h->faces[f].v[i]];
        t += h->faces[f].alive;
    }
    mci_free(h->ctx, map);
    return st;
}

mcsg_status mci_hull3d(const mci_ctx *ctx, const double *xyz, size_t n, mcsg_mesh *out,
                       mcsg_error *err)
{
    hull3 h;
    bool ok = true;
    mcsg_status st = MCSG_OK;
    memset(&h, 0, sizeof h);
    memset(out, 0, sizeof *out);
    h.ctx = ctx;
    if (n >= UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "convex hull of 2^32 points or more");
    h.p = unique_points(ctx, xyz, n, &h.n);
    h.next = mci_malloc_array(ctx, n + 1, sizeof *h.next);
    h.start_of = mci_malloc_array(ctx, n + 1, sizeof *h.start_of);
    h.end_of = mci_malloc_array(ctx, n + 1, sizeof *h.end_of);
    if (!h.p || !h.next || !h.start_of || !h.end_of)
        ok = false;
    else if (h.n >= 4 && start(&h, &ok)) {
        for (size_t f = 0; ok && f < h.face_count; f++) {
            while (ok && h.faces[f].alive && h.faces[f].conflict != UINT32_MAX)
                ok = add_point(&h, (uint32_t)f);
        }
        if (ok)
            st = hull_mesh(&h, out, err);
    }
    if (!ok)
        st = mci_fail_nomem(err, "making a convex hull");
    mci_free(ctx, (void *)h.p);
    mci_free(ctx, h.next);
    mci_free(ctx, h.start_of);
    mci_free(ctx, h.end_of);
    mci_free(ctx, h.faces);
    mci_free(ctx, h.stack);
    mci_free(ctx, h.visible);
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* 2D */

typedef struct xy_pt {
    double x, y;
} xy_pt;

#define XY_LESS(a, b) ((a)->x < (b)->x || ((a)->x == (b)->x && (a)->y < (b)->y))
MCI_DEFINE_SORT(sort_xy_pts, xy_pt, XY_LESS)

static bool turns_left(const xy_pt *a, const xy_pt *b, const xy_pt *c)
{
    return mci_orient2d(a->x, a->y, b->x, b->y, c->x, c->y) > 0;
}

mcsg_status mci_hull2d(const mci_ctx *ctx, const double *xy, size_t n, mci_outlines *out,
                       mcsg_error *err)
{
    xy_pt *s = mci_malloc_array(ctx, n + 1, sizeof *s);
    xy_pt *h = mci_malloc_array(ctx, 2 * n + 2, sizeof *h);
    size_t k = 0, lower;
    memset(out, 0, sizeof *out);
    out->loop_start = mci_calloc_array(ctx, 2, sizeof *out->loop_start);
    if (!s || !h || !out->loop_start) {
        mci_free(ctx, s);
        mci_free(ctx, h);
        mci_outlines_free(ctx, out);
        return mci_fail_nomem(err, "making a convex hull");
    }
    for (size_t i = 0; i < n; i++)
        s[i] = (xy_pt){xy[2 * i] == 0 ? 0.0 : xy[2 * i], xy[2 * i + 1] == 0 ? 0.0 : xy[2 * i + 1]};
    sort_xy_pts(s, n);
    for (size_t i = 0; i < n; i++) { /* lower chain */
        while (k >= 2 && !turns_left(&h[k - 2], &h[k - 1], &s[i]))
            k--;
        h[k++] = s[i];
    }
    lower = k + 1;
    for (size_t i = n; i-- > 1;) { /* upper chain, back to the first point */
        while (k >= lower && !turns_left(&h[k - 2], &h[k - 1], &s[i - 1]))
            k--;
        h[k++] = s[i - 1];
    }
    k = k > 0 ? k - 1 : 0; /* the first point came round again */
    if (k >= 3) {
        out->xy = (double *)(void *)h;
        out->point_count = k;
        out->loop_count = 1;
        out->loop_start[1] = (uint32_t)k;
        h = NULL;
    }
    mci_free(ctx, s);
    mci_free(ctx, h);
    return MCSG_OK;
}
