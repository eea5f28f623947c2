/*
 * Polygon faces triangulated as OpenSCAD 2021.01 does (shape/tess.h).
 *
 * OpenSCAD (src/polyset-utils.cc, src/GeometryUtils.cc) rounds every vertex to float,
 * merges vertices with equal floats, drops repeated consecutive corners and "null ears"
 * (a, b, a), passes three-corner faces through, and gives the rest to libtess2 (its copy
 * in src/ext/libtess2: SGI Free Software License B 2.0) with the odd winding rule,
 * TESS_CONSTRAINED_DELAUNAY_TRIANGLES and no normal. libtess2 then
 *  - estimates a normal (two vertices extreme along the widest axis and the vertex making
 *    the largest triangle with them), projects onto the plane of the two other axes
 *    (s = the next axis, t = the one after, negated when the normal's component is
 *    negative) and flips t when the contour's signed area is negative;
 *  - sweeps the projected contour left to right (s, then t) with a dictionary of the
 *    edges crossing the sweep line, splitting the inside into monotone regions: a vertex
 *    with both edges to its right inside the polygon is joined to the rightmost processed
 *    vertex of the chains above and below it; a vertex with both edges to its left gets a
 *    temporary edge to the nearer unprocessed end of those chains, replaced once the
 *    next vertex of the merged region is met;
 *  - triangulates each monotone region from its rightmost vertex with two chains;
 *  - flips interior edges from a stack (filled face by face, each face's edges from its
 *    first edge) while the two angles opposite an edge sum to more than pi + 0.01, pushing
 *    three of the four edges around a flipped one.
 * This file repeats those steps on the same half-edge structure (the same face list and
 * edge orders, which decide the order of the flips), written anew: each geometric
 * question is an exact predicate on the float-rounded coordinates where libtess2
 * computes in float. The angle test is decided exactly as well: flip when
 * alpha + beta > c, c being the double nearest pi + 0.01, as sin and cos of the sum
 * compared with cos(c - pi), whose square is bracketed by two doubles.
 *
 * Not reproduced: libtess2 cuts edges where they cross (new vertices, which OpenSCAD
 * drops and patches) and merges corners that project to one point; such faces (found
 * exactly, as the sweep meets them) are fanned from their first corner instead.
 */
#include "shape/tess.h"

#include "base/sort_template.h"
#include "exact/big.h"
#include "exact/predicates.h"

#include <limits.h>
#include <math.h>
#include <string.h>

typedef struct tvert tvert;
typedef struct tface tface;
typedef struct thalf thalf;
typedef struct treg treg;
typedef struct tnode tnode;

struct tvert {
    tvert *next, *prev;
    thalf *an_edge;
    double s, t;
    uint32_t idx; /* position in the cleaned face */
};

struct tface {
    tface *next, *prev;
    thalf *an_edge;
    bool inside;
};

struct thalf {
    thalf *sym, *onext, *lnext;
    tvert *org;
    tface *lface;
    treg *active;
    int winding;
    bool mark;
};

struct treg {
    thalf *e_up;
    tnode *node_up;
    int winding_number;
    bool inside, sentinel, dirty, fix_upper_edge;
};

struct tnode {
    treg *key;
    tnode *next, *prev;
};

#define DST(e) ((e)->sym->org)
#define RFACE(e) ((e)->sym->lface)
#define OPREV(e) ((e)->sym->lnext)
#define LPREV(e) ((e)->onext->sym)
#define RPREV(e) ((e)->sym->onext)
#define DNEXT(e) (RPREV(e)->sym)
#define REGION_BELOW(r) ((r)->node_up->prev->key)
#define REGION_ABOVE(r) ((r)->node_up->next->key)

/* The number of exact scratch integers the predicates use at most. */
#define TESS_BIGS 24

struct mci_tess {
    /* pools with free lists, sized for the face being triangulated */
    tvert *verts;
    tface *faces;
    thalf *halves; /* pairs: 2k and 2k + 1 */
    treg *regs;
    tnode *nodes;
    size_t cap; /* the cleaned face size the pools were sized for */
    tvert *free_vert;
    tface *free_face;
    thalf *free_half;
    treg *free_reg;
    tnode *free_node;
    /* the mesh and the sweep */
    tvert vhead;
    tface fhead;
    tnode dict;
    tvert *event;
    tvert **order; /* vertices in sweep order */
    /* the cleaned face: corner positions, ids, float coordinates */
    uint32_t *pos, *ids;
    double *fxyz;
    size_t face_cap;
    mci_big *big; /* TESS_BIGS scratch integers */
    bool unsupported;
};

/* ---------------------------------------------------------------------------------- */
/* Exact predicates on the projected (float-rounded) coordinates */

static int sign_of(int x)
{
    return (x > 0) - (x < 0);
}

static int vert_leq(const tvert *u, const tvert *v)
{
    return u->s < v->s || (u->s == v->s && u->t <= v->t);
}

static bool vert_eq(const tvert *u, const tvert *v)
{
    return u->s == v->s && u->t == v->t;
}

/* libtess2's EdgeSign: the side of v relative to the edge u -> w (u left of w); 0 when
 * w is not strictly right of u. */
static int edge_sign(const tvert *u, const tvert *v, const tvert *w)
{
    if (!(w->s > u->s))
        return 0;
    return mci_orient2d(u->s, u->t, w->s, w->t, v->s, v->t);
}

static int lsb_min(int e0, double x)
{
    int e = mci_lsb_exponent(x);
    return e < e0 ? e : e0;
}

/* r = (a - b) scaled by 2^-e0. */
static void big_diff(mci_tess *ts, mci_big *r, double a, double b, int e0)
{
    mci_big *tmp = &ts->big[TESS_BIGS - 1];
    mci_big_from_double(r, a, e0);
    mci_big_from_double(tmp, b, e0);
    mci_big_sub(r, r, tmp);
}

/* EdgeEval(u1, v, w1) >= EdgeEval(u2, v, w2): edge 2 lies at or above edge 1 where the
 * sweep line through v crosses them (a vertical edge counts as passing through v). */
static bool edge_eval_geq(mci_tess *ts, const tvert *u1, const tvert *w1, const tvert *u2,
                          const tvert *w2, const tvert *v)
{
    bool flat1 = !(w1->s > u1->s), flat2 = !(w2->s > u2->s);
    if (flat1 || flat2) {
        if (flat1 && flat2)
            return true;
        return flat1 ? mci_orient2d(u2->s, u2->t, w2->s, w2->t, v->s, v->t) <= 0
                     : mci_orient2d(u1->s, u1->t, w1->s, w1->t, v->s, v->t) >= 0;
    }
    /* O_k = (u_k - v) x (w_k - v), D_k = w_k.s - u_k.s > 0: sign of O1 D2 - O2 D1 */
    const double c[10] = {u1->s, u1->t, w1->s, w1->t, u2->s, u2->t, w2->s, w2->t, v->s, v->t};
    int e0 = INT_MAX;
    for (int k = 0; k < 10; k++)
        e0 = lsb_min(e0, c[k]);
    if (e0 == INT_MAX)
        return true;
    mci_big *b = ts->big;
    big_diff(ts, &b[0], u1->s, v->s, e0);
    big_diff(ts, &b[1], u1->t, v->t, e0);
    big_diff(ts, &b[2], w1->s, v->s, e0);
    big_diff(ts, &b[3], w1->t, v->t, e0);
    mci_big_mul(&b[4], &b[0], &b[3]);
    mci_big_mul(&b[5], &b[1], &b[2]);
    mci_big_sub(&b[4], &b[4], &b[5]); /* O1 */
    big_diff(ts, &b[0], u2->s, v->s, e0);
    big_diff(ts, &b[1], u2->t, v->t, e0);
    big_diff(ts, &b[2], w2->s, v->s, e0);
    big_diff(ts, &b[3], w2->t, v->t, e0);
    mci_big_mul(&b[6], &b[0], &b[3]);
    mci_big_mul(&b[5], &b[1], &b[2]);
    mci_big_sub(&b[6], &b[6], &b[5]); /* O2 */
    big_diff(ts, &b[0], w2->s, u2->s, e0);
    big_diff(ts, &b[1], w1->s, u1->s, e0);
    mci_big_mul(&b[7], &b[4], &b[0]);
    mci_big_mul(&b[8], &b[6], &b[1]);
    mci_big_sub(&b[7], &b[7], &b[8]);
    return mci_big_sign(&b[7]) >= 0;
}

/* The square of cos(c - pi), c the double nearest pi + 0.01, lies strictly between
 * these two adjacent doubles (computed with 300-bit arithmetic). */
#define COS2_LO 0x1.fff2e4ab2c6cbp-1
#define COS2_HI 0x1.fff2e4ab2c6ccp-1

/* Whether libtess2 flips the edge A-B between triangles A B C and B A D: the angles at C
 * and D sum to more than c (see the file comment). Exact; a sum within the bracket of
 * cos^2 (never met by rational input, cos being transcendental there) keeps the edge. */
static bool should_flip(mci_tess *ts, const tvert *a, const tvert *bv, const tvert *cv,
                        const tvert *dv)
{
    const double c[8] = {a->s, a->t, bv->s, bv->t, cv->s, cv->t, dv->s, dv->t};
    int e0 = INT_MAX;
    for (int k = 0; k < 8; k++)
        e0 = lsb_min(e0, c[k]);
    if (e0 == INT_MAX)
        return false;
    mci_big *b = ts->big;
    /* angle at C between A - C and B - C; at D between B - D and A - D */
    big_diff(ts, &b[0], a->s, cv->s, e0);
    big_diff(ts, &b[1], a->t, cv->t, e0);
    big_diff(ts, &b[2], bv->s, cv->s, e0);
    big_diff(ts, &b[3], bv->t, cv->t, e0);
    big_diff(ts, &b[4], bv->s, dv->s, e0);
    big_diff(ts, &b[5], bv->t, dv->t, e0);
    big_diff(ts, &b[6], a->s, dv->s, e0);
    big_diff(ts, &b[7], a->t, dv->t, e0);
    mci_big *d1 = &b[8], *c1 = &b[9], *d2 = &b[10], *c2 = &b[11], *x = &b[12], *y = &b[13];
    mci_big *n = &b[14], *m = &b[15];
    for (int k = 0; k < 2; k++) {
        mci_big *p = &b[4 * k], *dd = k ? d2 : d1, *cc = k ? c2 : c1;
        mci_big_mul(x, &p[0], &p[2]);
        mci_big_mul(y, &p[1], &p[3]);
        mci_big_add(dd, x, y);
        mci_big_mul(x, &p[0], &p[3]);
        mci_big_mul(y, &p[1], &p[2]);
        mci_big_sub(cc, x, y);
        if (mci_big_sign(cc) < 0)
            mci_big_neg(cc, cc);
    }
    /* sin(alpha + beta) >= 0 keeps the edge unless it is exactly 0 with cos < 0 */
    mci_big_mul(x, c1, d2);
    mci_big_mul(y, d1, c2);
    mci_big_add(x, x, y);
    if (mci_big_sign(x) > 0)
        return false;
    /* X = c1 c2 - d1 d2 = -cos(alpha + beta) |a||b||a'||b'|; flip when X < K N */
    mci_big_mul(x, c1, c2);
    mci_big_mul(y, d1, d2);
    mci_big_sub(x, x, y);
    if (mci_big_sign(x) < 0)
        return true;
    mci_big_mul(x, x, x);
    /* N^2 = |a|^2 |b|^2 |a'|^2 |b'|^2 */
    mci_big_set_int(n, 1);
    for (int k = 0; k < 8; k += 2) {
        mci_big_mul(y, &b[k], &b[k]);
        mci_big_mul(m, &b[k + 1], &b[k + 1]);
        mci_big_add(y, y, m);
        mci_big_mul(n, n, y);
    }
    /* X^2 < COS2_LO N^2: flip; X^2 >= COS2_HI N^2: keep; between: keep */
    mci_big_shift_left(x, x, 53);
    mci_big_from_double(y, COS2_LO, -53);
    mci_big_mul(m, y, n);
    mci_big_sub(m, x, m);
    return mci_big_sign(m) < 0;
}

/* ---------------------------------------------------------------------------------- */
/* Pools and the half-edge mesh (libtess2's mesh.c operations, same list orders) */

static void *pool_take(void **free_list, size_t next_offset)
{
    void *p = *free_list;
    if (p)
        *free_list = *(void **)((char *)p + next_offset);
    return p;
}

static tvert *alloc_vert(mci_tess *ts)
{
    tvert *v = pool_take((void **)&ts->free_vert, offsetof(tvert, next));
    if (!v)
        ts->unsupported = true;
    return v;
}

static tface *alloc_face(mci_tess *ts)
{
    tface *f = pool_take((void **)&ts->free_face, offsetof(tface, next));
    if (!f)
        ts->unsupported = true;
    return f;
}

static void free_vert(mci_tess *ts, tvert *v)
{
    v->next = ts->free_vert;
    ts->free_vert = v;
}

static void free_face(mci_tess *ts, tface *f)
{
    f->next = ts->free_face;
    ts->free_face = f;
}

static thalf *make_edge_pair(mci_tess *ts)
{
    thalf *e = ts->free_half;
    if (!e) {
        ts->unsupported = true;
        return NULL;
    }
    ts->free_half = e->onext;
    thalf *s = e + 1;
    memset(e, 0, 2 * sizeof *e);
    e->sym = s;
    e->onext = e;
    e->lnext = s;
    s->sym = e;
    s->onext = s;
    s->lnext = e;
    return e;
}

static void kill_edge(mci_tess *ts, thalf *e)
{
    if ((size_t)(e - ts->halves) & 1)
        e = e->sym;
    e->onext = ts->free_half;
    ts->free_half = e;
}

static void splice_raw(thalf *a, thalf *b)
{
    thalf *a_onext = a->onext, *b_onext = b->onext;
    a_onext->sym->lnext = b;
    b_onext->sym->lnext = a;
    a->onext = b_onext;
    b->onext = a_onext;
}

static void make_vertex(tvert *v, thalf *e_orig, tvert *v_next)
{
    tvert *v_prev = v_next->prev;
    v->prev = v_prev;
    v_prev->next = v;
    v->next = v_next;
    v_next->prev = v;
    v->an_edge = e_orig;
    thalf *e = e_orig;
    do {
        e->org = v;
        e = e->onext;
    } while (e != e_orig);
}

static void make_face(tface *f, thalf *e_orig, tface *f_next)
{
    tface *f_prev = f_next->prev;
    f->prev = f_prev;
    f_prev->next = f;
    f->next = f_next;
    f_next->prev = f;
    f->an_edge = e_orig;
    f->inside = f_next->inside;
    thalf *e = e_orig;
    do {
        e->lface = f;
        e = e->lnext;
    } while (e != e_orig);
}

static void kill_vertex(mci_tess *ts, tvert *v, tvert *new_org)
{
    thalf *e = v->an_edge, *start = e;
    do {
        e->org = new_org;
        e = e->onext;
    } while (e != start);
    v->next->prev = v->prev;
    v->prev->next = v->next;
    free_vert(ts, v);
}

static void kill_face(mci_tess *ts, tface *f, tface *new_lface)
{
    thalf *e = f->an_edge, *start = e;
    do {
        e->lface = new_lface;
        e = e->lnext;
    } while (e != start);
    f->next->prev = f->prev;
    f->prev->next = f->next;
    free_face(ts, f);
}

/* One edge, two vertices and a loop (tessMeshMakeEdge). */
static thalf *mesh_make_edge(mci_tess *ts)
{
    tvert *v1 = alloc_vert(ts), *v2 = alloc_vert(ts);
    tface *f = alloc_face(ts);
    thalf *e = make_edge_pair(ts);
    if (!v1 || !v2 || !f || !e)
        return NULL;
    make_vertex(v1, e, &ts->vhead);
    make_vertex(v2, e->sym, &ts->vhead);
    make_face(f, e, &ts->fhead);
    return e;
}

/* tessMeshSplice: exchanges e_org->onext and e_dst->onext, merging or splitting the
 * vertices and loops involved (e_dst's are the ones made or destroyed). */
static bool mesh_splice(mci_tess *ts, thalf *e_org, thalf *e_dst)
{
    bool joining_loops = false, joining_vertices = false;
    if (e_org == e_dst)
        return true;
    if (e_dst->org != e_org->org) {
        joining_vertices = true;
        kill_vertex(ts, e_dst->org, e_org->org);
    }
    if (e_dst->lface != e_org->lface) {
        joining_loops = true;
        kill_face(ts, e_dst->lface, e_org->lface);
    }
    splice_raw(e_dst, e_org);
    if (!joining_vertices) {
        tvert *v = alloc_vert(ts);
        if (!v)
            return false;
        make_vertex(v, e_dst, e_org->org);
        e_org->org->an_edge = e_org;
    }
    if (!joining_loops) {
        tface *f = alloc_face(ts);
        if (!f)
            return false;
        make_face(f, e_dst, e_org->lface);
        e_org->lface->an_edge = e_org;
    }
    return true;
}

/* tessMeshDelete: removes an edge, joining its two loops or splitting one. */
static bool mesh_delete(mci_tess *ts, thalf *e_del)
{
    thalf *e_del_sym = e_del->sym;
    bool joining_loops = false;
    if (e_del->lface != RFACE(e_del)) {
        joining_loops = true;
        kill_face(ts, e_del->lface, RFACE(e_del));
    }
    if (e_del->onext == e_del) {
        kill_vertex(ts, e_del->org, NULL);
    } else {
        RFACE(e_del)->an_edge = OPREV(e_del);
        e_del->org->an_edge = e_del->onext;
        splice_raw(e_del, OPREV(e_del));
        if (!joining_loops) {
            tface *f = alloc_face(ts);
            if (!f)
                return false;
            make_face(f, e_del, e_del->lface);
        }
    }
    if (e_del_sym->onext == e_del_sym) {
        kill_vertex(ts, e_del_sym->org, NULL);
        kill_face(ts, e_del_sym->lface, NULL);
    } else {
        e_del->lface->an_edge = OPREV(e_del_sym);
        e_del_sym->org->an_edge = e_del_sym->onext;
        splice_raw(e_del_sym, OPREV(e_del_sym));
    }
    kill_edge(ts, e_del);
    return true;
}

/* tessMeshAddEdgeVertex: a new edge after e_org in its loop, to a new vertex. */
static thalf *mesh_add_edge_vertex(mci_tess *ts, thalf *e_org)
{
    thalf *e_new = make_edge_pair(ts);
    tvert *v = alloc_vert(ts);
    if (!e_new || !v)
        return NULL;
    thalf *e_new_sym = e_new->sym;
    splice_raw(e_new, e_org->lnext);
    e_new->org = DST(e_org);
    make_vertex(v, e_new_sym, e_new->org);
    e_new->lface = e_new_sym->lface = e_org->lface;
    return e_new;
}

/* tessMeshSplitEdge: e_org split at a new vertex, the second half e_org->lnext. */
static thalf *mesh_split_edge(mci_tess *ts, thalf *e_org)
{
    thalf *temp = mesh_add_edge_vertex(ts, e_org);
    if (!temp)
        return NULL;
    thalf *e_new = temp->sym;
    splice_raw(e_org->sym, OPREV(e_org->sym));
    splice_raw(e_org->sym, e_new);
    DST(e_org) = e_new->org;
    DST(e_new)->an_edge = e_new->sym;
    RFACE(e_new) = RFACE(e_org);
    e_new->winding = e_org->winding;
    e_new->sym->winding = e_org->sym->winding;
    return e_new;
}

/* tessMeshConnect: a new edge from DST(e_org) to e_dst->org; a split loop's new part is
 * the new edge's left face. */
static thalf *mesh_connect(mci_tess *ts, thalf *e_org, thalf *e_dst)
{
    bool joining_loops = false;
    thalf *e_new = make_edge_pair(ts);
    if (!e_new)
        return NULL;
    thalf *e_new_sym = e_new->sym;
    if (e_dst->lface != e_org->lface) {
        joining_loops = true;
        kill_face(ts, e_dst->lface, e_org->lface);
    }
    splice_raw(e_new, e_org->lnext);
    splice_raw(e_new_sym, e_dst);
    e_new->org = DST(e_org);
    e_new_sym->org = e_dst->org;
    e_new->lface = e_new_sym->lface = e_org->lface;
    e_org->lface->an_edge = e_new_sym;
    if (!joining_loops) {
        tface *f = alloc_face(ts);
        if (!f)
            return NULL;
        make_face(f, e_new, e_org->lface);
    }
    return e_new;
}

/* tessMeshFlipEdge: the diagonal of the two triangles beside `edge` exchanged. */
static void mesh_flip_edge(thalf *edge)
{
    thalf *a0 = edge, *a1 = a0->lnext, *a2 = a1->lnext;
    thalf *b0 = edge->sym, *b1 = b0->lnext, *b2 = b1->lnext;
    tvert *a_org = a0->org, *a_opp = a2->org, *b_org = b0->org, *b_opp = b2->org;
    tface *fa = a0->lface, *fb = b0->lface;
    a0->org = b_opp;
    a0->onext = b1->sym;
    b0->org = a_opp;
    b0->onext = a1->sym;
    a2->onext = b0;
    b2->onext = a0;
    b1->onext = a2->sym;
    a1->onext = b2->sym;
    a0->lnext = a2;
    a2->lnext = b1;
    b1->lnext = a0;
    b0->lnext = b2;
    b2->lnext = a1;
    a1->lnext = b0;
    a1->lface = fb;
    b1->lface = fa;
    fa->an_edge = a0;
    fb->an_edge = b0;
    if (a_org->an_edge == a0)
        a_org->an_edge = b1;
    if (b_org->an_edge == b0)
        b_org->an_edge = a1;
}

/* ---------------------------------------------------------------------------------- */
/* The sweep (libtess2's sweep.c; the paths that cut crossing edges or merge touching
 * features mark the face unsupported instead) */

static bool sweep_event(mci_tess *ts, tvert *v_event);
static bool walk_dirty_regions(mci_tess *ts, treg *reg_up);

/* The edge dictionary's order: reg1's upper edge at or below reg2's (EdgeLeq). */
static bool edge_leq(mci_tess *ts, const treg *reg1, const treg *reg2)
{
    tvert *event = ts->event;
    thalf *e1 = reg1->e_up, *e2 = reg2->e_up;
    if (DST(e1) == event) {
        if (DST(e2) == event) {
            if (vert_leq(e1->org, e2->org))
                return edge_sign(DST(e2), e1->org, e2->org) <= 0;
            return edge_sign(DST(e1), e2->org, e1->org) >= 0;
        }
        return edge_sign(DST(e2), event, e2->org) <= 0;
    }
    if (DST(e2) == event)
        return edge_sign(DST(e1), event, e1->org) >= 0;
    return edge_eval_geq(ts, DST(e1), e1->org, DST(e2), e2->org, event);
}

static tnode *dict_insert_before(mci_tess *ts, tnode *node, treg *key)
{
    do {
        node = node->prev;
    } while (node->key && !edge_leq(ts, node->key, key));
    tnode *n = ts->free_node;
    if (!n) {
        ts->unsupported = true;
        return NULL;
    }
    ts->free_node = n->next;
    n->key = key;
    n->next = node->next;
    node->next->prev = n;
    n->prev = node;
    node->next = n;
    return n;
}

static void dict_delete(mci_tess *ts, tnode *n)
{
    n->next->prev = n->prev;
    n->prev->next = n->next;
    n->next = ts->free_node;
    ts->free_node = n;
}

static treg *alloc_reg(mci_tess *ts)
{
    treg *r = ts->free_reg;
    if (!r) {
        ts->unsupported = true;
        return NULL;
    }
    ts->free_reg = (treg *)r->e_up;
    memset(r, 0, sizeof *r);
    return r;
}

static void delete_region(mci_tess *ts, treg *reg)
{
    reg->e_up->active = NULL;
    dict_delete(ts, reg->node_up);
    reg->e_up = (thalf *)ts->free_reg;
    ts->free_reg = reg;
}

static bool fix_upper_edge(mci_tess *ts, treg *reg, thalf *new_edge)
{
    if (!mesh_delete(ts, reg->e_up))
        return false;
    reg->fix_upper_edge = false;
    reg->e_up = new_edge;
    new_edge->active = reg;
    return true;
}

static treg *top_left_region(mci_tess *ts, treg *reg)
{
    tvert *org = reg->e_up->org;
    do {
        reg = REGION_ABOVE(reg);
    } while (reg->e_up->org == org);
    if (reg->fix_upper_edge) {
        thalf *e = mesh_connect(ts, REGION_BELOW(reg)->e_up->sym, reg->e_up->lnext);
        if (!e || !fix_upper_edge(ts, reg, e))
            return NULL;
        reg = REGION_ABOVE(reg);
    }
    return reg;
}

static treg *add_region_below(mci_tess *ts, treg *reg_above, thalf *e_new_up)
{
    treg *r = alloc_reg(ts);
    if (!r)
        return NULL;
    r->e_up = e_new_up;
    r->node_up = dict_insert_before(ts, reg_above->node_up, r);
    if (!r->node_up)
        return NULL;
    e_new_up->active = r;
    return r;
}

static void compute_winding(treg *reg)
{
    reg->winding_number = REGION_ABOVE(reg)->winding_number + reg->e_up->winding;
    reg->inside = reg->winding_number & 1;
}

static void finish_region(mci_tess *ts, treg *reg)
{
    thalf *e = reg->e_up;
    tface *f = e->lface;
    f->inside = reg->inside;
    f->an_edge = e;
    delete_region(ts, reg);
}

/* FinishLeftRegions: closes the regions between the left-going edges of a vertex;
 * returns the lowest such edge, NULL when unsupported. */
static thalf *finish_left_regions(mci_tess *ts, treg *reg_first, treg *reg_last)
{
    treg *reg_prev = reg_first;
    thalf *e_prev = reg_first->e_up;
    while (reg_prev != reg_last) {
        reg_prev->fix_upper_edge = false;
        treg *reg = REGION_BELOW(reg_prev);
        thalf *e = reg->e_up;
        if (e->org != e_prev->org) {
            if (!reg->fix_upper_edge) {
                finish_region(ts, reg_prev);
                break;
            }
            e = mesh_connect(ts, LPREV(e_prev), e->sym);
            if (!e || !fix_upper_edge(ts, reg, e))
                return NULL;
        }
        if (e_prev->onext != e) {
            if (!mesh_splice(ts, OPREV(e), e) || !mesh_splice(ts, e_prev, e))
                return NULL;
        }
        finish_region(ts, reg_prev);
        e_prev = reg->e_up;
        reg_prev = reg;
    }
    return e_prev;
}

/* CheckForRightSplice, where it finds nothing to splice; splicing is unsupported. */
static bool check_for_right_splice(mci_tess *ts, treg *reg_up, bool *spliced)
{
    treg *reg_lo = REGION_BELOW(reg_up);
    thalf *e_up = reg_up->e_up, *e_lo = reg_lo->e_up;
    *spliced = false;
    if (vert_leq(e_up->org, e_lo->org)) {
        if (edge_sign(DST(e_lo), e_up->org, e_lo->org) > 0)
            return true;
    } else {
        if (edge_sign(DST(e_up), e_lo->org, e_up->org) < 0)
            return true;
    }
    *spliced = true;
    ts->unsupported = true;
    return false;
}

static bool check_for_left_splice(mci_tess *ts, treg *reg_up)
{
    treg *reg_lo = REGION_BELOW(reg_up);
    thalf *e_up = reg_up->e_up, *e_lo = reg_lo->e_up;
    if (vert_leq(DST(e_up), DST(e_lo))) {
        if (edge_sign(DST(e_up), DST(e_lo), e_up->org) < 0)
            return true;
    } else {
        if (edge_sign(DST(e_lo), DST(e_up), e_lo->org) > 0)
            return true;
    }
    ts->unsupported = true;
    return false;
}

/* CheckForIntersect, where the edges do not meet; meeting edges are unsupported. */
static bool check_for_intersect(mci_tess *ts, treg *reg_up)
{
    treg *reg_lo = REGION_BELOW(reg_up);
    thalf *e_up = reg_up->e_up, *e_lo = reg_lo->e_up;
    tvert *org_up = e_up->org, *org_lo = e_lo->org, *dst_up = DST(e_up), *dst_lo = DST(e_lo);
    if (org_up == org_lo)
        return true;
    double t_min_up = fmin(org_up->t, dst_up->t), t_max_lo = fmax(org_lo->t, dst_lo->t);
    if (t_min_up > t_max_lo)
        return true;
    if (vert_leq(org_up, org_lo)) {
        if (edge_sign(dst_lo, org_up, org_lo) > 0)
            return true;
    } else {
        if (edge_sign(dst_up, org_lo, org_up) < 0)
            return true;
    }
    ts->unsupported = true;
    return false;
}

static bool add_right_edges(mci_tess *ts, treg *reg_up, thalf *e_first, thalf *e_last,
                            thalf *e_top_left, bool clean_up)
{
    treg *reg, *reg_prev;
    thalf *e, *e_prev;
    bool first_time = true;
    e = e_first;
    do {
        if (!add_region_below(ts, reg_up, e->sym))
            return false;
        e = e->onext;
    } while (e != e_last);
    if (!e_top_left)
        e_top_left = RPREV(REGION_BELOW(reg_up)->e_up);
    reg_prev = reg_up;
    e_prev = e_top_left;
    for (;;) {
        reg = REGION_BELOW(reg_prev);
        e = reg->e_up->sym;
        if (e->org != e_prev->org)
            break;
        if (e->onext != e_prev) {
            if (!mesh_splice(ts, OPREV(e), e) || !mesh_splice(ts, OPREV(e_prev), e))
                return false;
        }
        reg->winding_number = reg_prev->winding_number - e->winding;
        reg->inside = reg->winding_number & 1;
        reg_prev->dirty = true;
        if (!first_time) {
            bool spliced;
            if (!check_for_right_splice(ts, reg_prev, &spliced))
                return false;
        }
        first_time = false;
        reg_prev = reg;
        e_prev = e;
    }
    reg_prev->dirty = true;
    return !clean_up || walk_dirty_regions(ts, reg_prev);
}

static bool walk_dirty_regions(mci_tess *ts, treg *reg_up)
{
    treg *reg_lo = REGION_BELOW(reg_up);
    for (;;) {
        while (reg_lo->dirty) {
            reg_up = reg_lo;
            reg_lo = REGION_BELOW(reg_lo);
        }
        if (!reg_up->dirty) {
            reg_lo = reg_up;
            reg_up = REGION_ABOVE(reg_up);
            if (!reg_up || !reg_up->dirty)
                return true;
        }
        reg_up->dirty = false;
        thalf *e_up = reg_up->e_up, *e_lo = reg_lo->e_up;
        if (DST(e_up) != DST(e_lo) && !check_for_left_splice(ts, reg_up))
            return false;
        if (e_up->org != e_lo->org) {
            if (DST(e_up) != DST(e_lo) && !reg_up->fix_upper_edge && !reg_lo->fix_upper_edge &&
                (DST(e_up) == ts->event || DST(e_lo) == ts->event)) {
                if (!check_for_intersect(ts, reg_up))
                    return false;
            } else {
                bool spliced;
                if (!check_for_right_splice(ts, reg_up, &spliced))
                    return false;
            }
        }
        if (e_up->org == e_lo->org && DST(e_up) == DST(e_lo)) {
            e_lo->winding += e_up->winding;
            e_lo->sym->winding += e_up->sym->winding;
            delete_region(ts, reg_up);
            if (!mesh_delete(ts, e_up))
                return false;
            reg_up = REGION_ABOVE(reg_lo);
        }
    }
}

/* ConnectRightVertex: a vertex whose edges all go left gets a temporary edge to the
 * nearer right end of the edges above and below it. */
static bool connect_right_vertex(mci_tess *ts, treg *reg_up, thalf *e_bottom_left)
{
    treg *reg_lo = REGION_BELOW(reg_up);
    thalf *e_up = reg_up->e_up, *e_lo = reg_lo->e_up, *e_new;
    if (DST(e_up) != DST(e_lo) && !check_for_intersect(ts, reg_up))
        return false;
    if (vert_eq(e_up->org, ts->event) || vert_eq(e_lo->org, ts->event)) {
        ts->unsupported = true;
        return false;
    }
    e_new = vert_leq(e_lo->org, e_up->org) ? OPREV(e_lo) : e_up;
    e_new = mesh_connect(ts, LPREV(e_bottom_left), e_new);
    if (!e_new || !add_right_edges(ts, reg_up, e_new, e_new->onext, e_new->onext, false))
        return false;
    e_new->sym->active->fix_upper_edge = true;
    return walk_dirty_regions(ts, reg_up);
}

/* The region containing v_event (dictSearch with v_event's edge as the key). */
static treg *region_containing(mci_tess *ts, tvert *v_event)
{
    treg tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.e_up = v_event->an_edge->sym;
    tnode *node = &ts->dict;
    do {
        node = node->next;
    } while (node->key && !edge_leq(ts, &tmp, node->key));
    return node->key;
}

/* ConnectLeftVertex: a vertex whose edges all go right, inside the polygon, is joined to
 * the rightmost processed vertex of the chains above and below it. */
static bool connect_left_vertex(mci_tess *ts, tvert *v_event)
{
    treg *reg_up = region_containing(ts, v_event);
    treg *reg_lo = reg_up ? REGION_BELOW(reg_up) : NULL;
    if (!reg_lo)
        return true;
    thalf *e_up = reg_up->e_up, *e_lo = reg_lo->e_up, *e_new;
    if (edge_sign(DST(e_up), v_event, e_up->org) == 0) {
        ts->unsupported = true; /* ConnectLeftDegenerate */
        return false;
    }
    treg *reg = vert_leq(DST(e_lo), DST(e_up)) ? reg_up : reg_lo;
    if (reg_up->inside || reg->fix_upper_edge) {
        if (reg == reg_up) {
            e_new = mesh_connect(ts, v_event->an_edge->sym, e_up->lnext);
        } else {
            thalf *temp = mesh_connect(ts, DNEXT(e_lo), v_event->an_edge);
            e_new = temp ? temp->sym : NULL;
        }
        if (!e_new)
            return false;
        if (reg->fix_upper_edge) {
            if (!fix_upper_edge(ts, reg, e_new))
                return false;
        } else {
            treg *r = add_region_below(ts, reg_up, e_new);
            if (!r)
                return false;
            compute_winding(r);
        }
        return sweep_event(ts, v_event);
    }
    return add_right_edges(ts, reg_up, v_event->an_edge, v_event->an_edge, NULL, true);
}

static bool sweep_event(mci_tess *ts, tvert *v_event)
{
    ts->event = v_event;
    thalf *e = v_event->an_edge;
    while (!e->active) {
        e = e->onext;
        if (e == v_event->an_edge)
            return connect_left_vertex(ts, v_event);
    }
    treg *reg_up = top_left_region(ts, e->active);
    if (!reg_up)
        return false;
    treg *reg = REGION_BELOW(reg_up);
    thalf *e_top_left = reg->e_up;
    thalf *e_bottom_left = finish_left_regions(ts, reg, NULL);
    if (!e_bottom_left)
        return false;
    if (e_bottom_left->onext == e_top_left)
        return connect_right_vertex(ts, reg_up, e_bottom_left);
    return add_right_edges(ts, reg_up, e_bottom_left->onext, e_top_left, e_top_left, true);
}

static bool add_sentinel(mci_tess *ts, double smin, double smax, double t)
{
    treg *reg = alloc_reg(ts);
    thalf *e = mesh_make_edge(ts);
    if (!reg || !e)
        return false;
    e->org->s = smax;
    e->org->t = t;
    DST(e)->s = smin;
    DST(e)->t = t;
    ts->event = DST(e);
    reg->e_up = e;
    reg->sentinel = true;
    reg->node_up = dict_insert_before(ts, &ts->dict, reg);
    return reg->node_up != NULL;
}

/* Removes faces of two edges (RemoveDegenerateFaces). */
static bool remove_degenerate_faces(mci_tess *ts)
{
    tface *f, *f_next;
    for (f = ts->fhead.next; f != &ts->fhead; f = f_next) {
        f_next = f->next;
        thalf *e = f->an_edge;
        if (e->lnext->lnext == e) {
            e->onext->winding += e->winding;
            e->onext->sym->winding += e->sym->winding;
            if (!mesh_delete(ts, e))
                return false;
        }
    }
    return true;
}

/* tessComputeInterior for vertices already sorted into ts->order (distinct points). */
static bool compute_interior(mci_tess *ts, size_t n, double smin, double smax, double tmin,
                             double tmax)
{
    ts->dict.key = NULL;
    ts->dict.next = ts->dict.prev = &ts->dict;
    if (!add_sentinel(ts, smin, smax, tmin) || !add_sentinel(ts, smin, smax, tmax))
        return false;
    for (size_t k = 0; k < n; k++)
        if (!sweep_event(ts, ts->order[k]))
            return false;
    while (ts->dict.next != &ts->dict)
        delete_region(ts, ts->dict.next->key);
    return remove_degenerate_faces(ts);
}

/* tessMeshTessellateMonoRegion. */
static bool tessellate_mono_region(mci_tess *ts, tface *face)
{
    thalf *up = face->an_edge, *lo;
    for (; vert_leq(DST(up), up->org); up = LPREV(up))
        ;
    for (; vert_leq(up->org, DST(up)); up = up->lnext)
        ;
    lo = LPREV(up);
    while (up->lnext != lo) {
        if (vert_leq(DST(up), lo->org)) {
            while (lo->lnext != up && (vert_leq(DST(lo->lnext), lo->lnext->org) ||
                                       edge_sign(lo->org, DST(lo), DST(lo->lnext)) <= 0)) {
                thalf *temp = mesh_connect(ts, lo->lnext, lo);
                if (!temp)
                    return false;
                lo = temp->sym;
            }
            lo = LPREV(lo);
        } else {
            while (lo->lnext != up && (vert_leq(LPREV(up)->org, DST(LPREV(up))) ||
                                       edge_sign(DST(up), up->org, LPREV(up)->org) >= 0)) {
                thalf *temp = mesh_connect(ts, up, LPREV(up));
                if (!temp)
                    return false;
                up = temp->sym;
            }
            up = up->lnext;
        }
    }
    while (lo->lnext->lnext != up) {
        thalf *temp = mesh_connect(ts, lo->lnext, lo);
        if (!temp)
            return false;
        lo = temp->sym;
    }
    return true;
}

static bool edge_is_internal(const thalf *e)
{
    return RFACE(e) && RFACE(e)->inside;
}

/* tessMeshRefineDelaunay, with its stack (a linked list through unused pool slots is
 * not needed: at most one entry per edge, kept in ts->order's storage after the sweep). */
static void refine_delaunay(mci_tess *ts, thalf **stack)
{
    size_t top = 0;
    for (tface *f = ts->fhead.next; f != &ts->fhead; f = f->next) {
        if (!f->inside)
            continue;
        thalf *e = f->an_edge;
        do {
            e->mark = edge_is_internal(e);
            if (e->mark && !e->sym->mark)
                stack[top++] = e;
            e = e->lnext;
        } while (e != f->an_edge);
    }
    while (top > 0) {
        thalf *e = stack[--top];
        e->mark = e->sym->mark = false;
        if (!should_flip(ts, e->org, DST(e), e->lnext->lnext->org, e->sym->lnext->lnext->org))
            continue;
        mesh_flip_edge(e);
        thalf *around[3] = {e->lnext, LPREV(e), e->sym->lnext};
        for (int i = 0; i < 3; i++) {
            if (!around[i]->mark && edge_is_internal(around[i])) {
                around[i]->mark = around[i]->sym->mark = true;
                stack[top++] = around[i];
            }
        }
    }
}

/* ---------------------------------------------------------------------------------- */
/* Face cleaning, normal and projection (OpenSCAD's and libtess2's front ends) */

/* Drops repeated consecutive corners, "null ears" and corners with non-finite float
 * coordinates as GeometryUtils::tessellatePolygonWithHoles does; *m is the size kept. */
static void clean_face(mci_tess *ts, size_t *m)
{
    uint32_t *id = ts->ids, *pos = ts->pos;
    size_t size = *m, i = 0;
    while (size >= 3 && i < size) {
        size_t next = (i + 1) % size, prev = (i + size - 1) % size;
        size_t from = SIZE_MAX, cut = 0;
        if (id[i] == id[next]) {
            from = i, cut = 1;
        } else if (id[prev] == id[next]) {
            from = i == 0 ? 0 : i - 1, cut = 2;
        } else {
            const double *p = ts->fxyz + 3 * (size_t)pos[i];
            if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
                from = i, cut = 1;
        }
        if (from == SIZE_MAX) {
            i++;
            continue;
        }
        memmove(id + from, id + from + cut, (size - from - cut) * sizeof *id);
        memmove(pos + from, pos + from + cut, (size - from - cut) * sizeof *pos);
        size -= cut;
        if (cut == 2) {
            if (i == 0)
                break; /* OpenSCAD's unsigned index wraps and ends the loop here */
            i--;
        }
    }
    *m = size;
}

static const double *vxyz(const mci_tess *ts, const tvert *v)
{
    return ts->fxyz + 3 * (size_t)ts->pos[v->idx];
}

/* Sign of (a - b) - (c - d), exactly. */
static int diff_cmp(mci_tess *ts, double a, double b, double c, double d)
{
    int e0 = lsb_min(lsb_min(lsb_min(lsb_min(INT_MAX, a), b), c), d);
    if (e0 == INT_MAX)
        return 0;
    big_diff(ts, &ts->big[0], a, b, e0);
    big_diff(ts, &ts->big[1], c, d, e0);
    mci_big_sub(&ts->big[0], &ts->big[0], &ts->big[1]);
    return mci_big_sign(&ts->big[0]);
}

/* cross (p - o) x (q - o) into big[out .. out + 2] and its squared length into
 * big[out + 3], all scaled by a common 2^-e0. */
static void big_cross(mci_tess *ts, const double *p, const double *q, const double *o, int e0,
                      int out)
{
    mci_big *b = ts->big, *r = ts->big + out;
    for (int k = 0; k < 3; k++) {
        big_diff(ts, &b[k], p[k], o[k], e0);
        big_diff(ts, &b[3 + k], q[k], o[k], e0);
    }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mci_big_mul(&b[6], &b[i], &b[3 + j]);
        mci_big_mul(&b[7], &b[j], &b[3 + i]);
        mci_big_sub(&r[k], &b[6], &b[7]);
    }
    mci_big_set_int(&r[3], 0);
    for (int k = 0; k < 3; k++) {
        mci_big_mul(&b[6], &r[k], &r[k]);
        mci_big_add(&r[3], &r[3], &b[6]);
    }
}

static int big_abs_cmp(const mci_big *a, const mci_big *b)
{
    int sa = a->size < 0 ? -a->size : a->size, sb = b->size < 0 ? -b->size : b->size;
    if (sa != sb)
        return sa < sb ? -1 : 1;
    return sa == 0 ? 0 : sign_of(mpn_cmp(a->limb, b->limb, (mp_size_t)sa));
}

/* libtess2's ComputeNormal followed by LongAxis: the axis the projection drops and the
 * sign of the normal's component along it, decided exactly on the vertex list. */
static void projection_axis(mci_tess *ts, int *axis, int *sign)
{
    tvert *head = &ts->vhead, *min_v[3], *max_v[3];
    int e0 = INT_MAX;
    for (int k = 0; k < 3; k++)
        min_v[k] = max_v[k] = head->next;
    for (tvert *v = head->next; v != head; v = v->next) {
        const double *c = vxyz(ts, v);
        for (int k = 0; k < 3; k++) {
            e0 = lsb_min(e0, c[k]);
            if (c[k] < vxyz(ts, min_v[k])[k])
                min_v[k] = v;
            if (c[k] > vxyz(ts, max_v[k])[k])
                max_v[k] = v;
        }
    }
    int i = 0;
#define EXTENT(k) vxyz(ts, max_v[k])[k], vxyz(ts, min_v[k])[k]
    if (diff_cmp(ts, EXTENT(1), EXTENT(0)) > 0)
        i = 1;
    if (diff_cmp(ts, EXTENT(2), EXTENT(i)) > 0)
        i = 2;
#undef EXTENT
    *axis = 2;
    *sign = 1;
    if (!(vxyz(ts, min_v[i])[i] < vxyz(ts, max_v[i])[i]) || e0 == INT_MAX)
        return; /* all vertices equal: libtess2 takes (0, 0, 1) */
    /* the normal: the largest (p1 - p2) x (v - p2), the first of equal ones */
    const double *p1 = vxyz(ts, min_v[i]), *p2 = vxyz(ts, max_v[i]);
    mci_big *best = ts->big + 12; /* 12..15: the best cross and its length */
    mci_big_set_int(&best[3], 0);
    for (tvert *v = head->next; v != head; v = v->next) {
        big_cross(ts, p1, vxyz(ts, v), p2, e0, 8);
        if (mci_big_sign(&ts->big[11]) > 0 && big_abs_cmp(&ts->big[11], &best[3]) > 0)
            for (int k = 0; k < 4; k++)
                mci_big_copy(&best[k], &ts->big[8 + k]);
    }
    if (mci_big_sign(&best[3]) == 0) {
        /* collinear: the axis where p1 - p2 is shortest (ShortAxis) */
        mci_big *d = ts->big + 16;
        for (int k = 0; k < 3; k++) {
            big_diff(ts, &d[k], p1[k], p2[k], e0);
        }
        int s = 0;
        if (big_abs_cmp(&d[1], &d[0]) < 0)
            s = 1;
        if (big_abs_cmp(&d[2], &d[s]) < 0)
            s = 2;
        *axis = s;
        return;
    }
    int a = 0;
    if (big_abs_cmp(&best[1], &best[0]) > 0)
        a = 1;
    if (big_abs_cmp(&best[2], &best[a]) > 0)
        a = 2;
    *axis = a;
    *sign = mci_big_sign(&best[a]) > 0 ? 1 : -1;
}

/* Sign of the contour's signed area in (s, t), exactly (libtess2's CheckOrientation). */
static int contour_area_sign(mci_tess *ts, size_t m, tvert **by_idx)
{
    int e0 = INT_MAX;
    for (size_t k = 0; k < m; k++)
        e0 = lsb_min(lsb_min(e0, by_idx[k]->s), by_idx[k]->t);
    if (e0 == INT_MAX)
        return 0;
    mci_big *b = ts->big;
    mci_big_set_int(&b[0], 0);
    for (size_t k = 0; k < m; k++) {
        const tvert *p = by_idx[k], *q = by_idx[(k + 1) % m];
        mci_big_from_double(&b[1], p->s, e0);
        mci_big_from_double(&b[2], q->t, e0);
        mci_big_mul(&b[3], &b[1], &b[2]);
        mci_big_from_double(&b[1], q->s, e0);
        mci_big_from_double(&b[2], p->t, e0);
        mci_big_mul(&b[4], &b[1], &b[2]);
        mci_big_sub(&b[3], &b[3], &b[4]);
        mci_big_add(&b[0], &b[0], &b[3]);
    }
    return mci_big_sign(&b[0]);
}

typedef tvert *tvert_ref;
#define VERT_LESS(a, b) (!vert_leq(*(b), *(a)))
MCI_DEFINE_SORT(sort_verts, tvert_ref, VERT_LESS)

/* ---------------------------------------------------------------------------------- */
/* Scratch and the entry point */

void mci_tess_free(const mci_ctx *ctx, mci_tess **t)
{
    mci_tess *ts = *t;
    if (!ts)
        return;
    mci_free(ctx, ts->verts);
    mci_free(ctx, ts->faces);
    mci_free(ctx, ts->halves);
    mci_free(ctx, ts->regs);
    mci_free(ctx, ts->nodes);
    mci_free(ctx, ts->order);
    mci_free(ctx, ts->pos);
    mci_free(ctx, ts->ids);
    mci_free(ctx, ts->fxyz);
    mci_free(ctx, ts->big);
    mci_free(ctx, ts);
    *t = NULL;
}

/* Pool sizes for a cleaned face of m corners: the mesh stays planar (at most 3V edges
 * and 2V faces for V = m + 4 vertices), with a few transient elements. */
static bool reserve(const mci_ctx *ctx, mci_tess *ts, size_t n)
{
    if (n <= ts->cap)
        return true;
    size_t cap = n < 16 ? 16 : n;
    mci_free(ctx, ts->verts);
    mci_free(ctx, ts->faces);
    mci_free(ctx, ts->halves);
    mci_free(ctx, ts->regs);
    mci_free(ctx, ts->nodes);
    mci_free(ctx, ts->order);
    mci_free(ctx, ts->pos);
    mci_free(ctx, ts->ids);
    mci_free(ctx, ts->fxyz);
    ts->cap = 0;
    ts->verts = mci_malloc_array(ctx, cap + 16, sizeof *ts->verts);
    ts->faces = mci_malloc_array(ctx, 2 * cap + 32, sizeof *ts->faces);
    ts->halves = mci_malloc_array(ctx, 2 * (4 * cap + 32), sizeof *ts->halves);
    ts->regs = mci_malloc_array(ctx, 2 * cap + 32, sizeof *ts->regs);
    ts->nodes = mci_malloc_array(ctx, 2 * cap + 32, sizeof *ts->nodes);
    ts->order = mci_malloc_array(ctx, 4 * cap + 32, sizeof *ts->order);
    ts->pos = mci_malloc_array(ctx, cap, sizeof *ts->pos);
    ts->ids = mci_malloc_array(ctx, cap, sizeof *ts->ids);
    ts->fxyz = mci_malloc_array(ctx, 3 * cap, sizeof *ts->fxyz);
    if (!ts->verts || !ts->faces || !ts->halves || !ts->regs || !ts->nodes || !ts->order ||
        !ts->pos || !ts->ids || !ts->fxyz)
        return false;
    ts->cap = cap;
    return true;
}

static void reset_pools(mci_tess *ts)
{
    size_t cap = ts->cap;
    ts->free_vert = NULL;
    for (size_t k = cap + 16; k-- > 0;)
        free_vert(ts, &ts->verts[k]);
    ts->free_face = NULL;
    for (size_t k = 2 * cap + 32; k-- > 0;)
        free_face(ts, &ts->faces[k]);
    ts->free_half = NULL;
    for (size_t k = 4 * cap + 32; k-- > 0;) {
        ts->halves[2 * k].onext = ts->free_half;
        ts->free_half = &ts->halves[2 * k];
    }
    ts->free_reg = NULL;
    for (size_t k = 2 * cap + 32; k-- > 0;) {
        ts->regs[k].e_up = (thalf *)ts->free_reg;
        ts->free_reg = &ts->regs[k];
    }
    ts->free_node = NULL;
    for (size_t k = 2 * cap + 32; k-- > 0;) {
        ts->nodes[k].next = ts->free_node;
        ts->free_node = &ts->nodes[k];
    }
    memset(&ts->vhead, 0, sizeof ts->vhead);
    ts->vhead.next = ts->vhead.prev = &ts->vhead;
    memset(&ts->fhead, 0, sizeof ts->fhead);
    ts->fhead.next = ts->fhead.prev = &ts->fhead;
    ts->unsupported = false;
}

/* The contour as tessAddContour builds it: the same vertex list and face list orders. */
static bool add_contour(mci_tess *ts, size_t m)
{
    thalf *e = NULL;
    for (size_t k = 0; k < m; k++) {
        if (!e) {
            e = mesh_make_edge(ts);
            if (!e || !mesh_splice(ts, e, e->sym))
                return false;
        } else {
            if (!mesh_split_edge(ts, e))
                return false;
            e = e->lnext;
        }
        e->org->idx = (uint32_t)k;
        e->winding = 1;
        e->sym->winding = -1;
    }
    return true;
}

/* Project, sort and sweep; false when the face is not reproduced (ts->unsupported). */
static bool libtess2_triangles(mci_tess *ts, size_t m, uint32_t *tris, uint32_t *count)
{
    int axis, sign;
    reset_pools(ts);
    if (!add_contour(ts, m))
        return false;
    projection_axis(ts, &axis, &sign);
    tvert **by_idx = ts->order + m;
    size_t k = 0;
    for (tvert *v = ts->vhead.next; v != &ts->vhead; v = v->next, k++) {
        const double *c = vxyz(ts, v);
        v->s = c[(axis + 1) % 3];
        v->t = sign > 0 ? c[(axis + 2) % 3] : -c[(axis + 2) % 3];
        ts->order[k] = v;
        by_idx[v->idx] = v;
    }
    int area = contour_area_sign(ts, m, by_idx);
    if (area == 0) {
        ts->unsupported = true; /* a degenerate projection: no orientation to keep */
        return false;
    }
    for (k = 0; k < m && area < 0; k++)
        ts->order[k]->t = -ts->order[k]->t;
    double smin = by_idx[0]->s, smax = smin, tmin = by_idx[0]->t, tmax = tmin;
    for (k = 0; k < m; k++) {
        tvert *v = ts->order[k];
        smin = fmin(smin, v->s), smax = fmax(smax, v->s);
        tmin = fmin(tmin, v->t), tmax = fmax(tmax, v->t);
    }
    sort_verts(ts->order, m);
    for (k = 1; k < m; k++)
        if (vert_eq(ts->order[k - 1], ts->order[k])) {
            ts->unsupported = true; /* corners that libtess2 would merge */
            return false;
        }
    /* sentinels strictly outside: any such place gives the same exact answers */
    double ws = smax - smin + 1, wt = tmax - tmin + 1;
    if (!compute_interior(ts, m, smin - (fabs(smin) + ws), smax + (fabs(smax) + ws),
                          tmin - (fabs(tmin) + wt), tmax + (fabs(tmax) + wt)))
        return false;
    for (tface *f = ts->fhead.next; f != &ts->fhead; f = f->next)
        if (f->inside && !tessellate_mono_region(ts, f))
            return false;
    refine_delaunay(ts, (thalf **)ts->order);
    uint32_t c = 0;
    for (tface *f = ts->fhead.next; f != &ts->fhead; f = f->next) {
        if (!f->inside)
            continue;
        thalf *e = f->an_edge;
        if (c + 1 > m - 2 || e->lnext->lnext->lnext != e) {
            ts->unsupported = true;
            return false;
        }
        for (int j = 0; j < 3; j++, e = e->lnext)
            tris[3 * c + j] = ts->pos[e->org->idx];
        c++;
    }
    *count = c;
    return true;
}

static void fan(const mci_tess *ts, size_t m, uint32_t *tris, uint32_t *count)
{
    uint32_t c = 0;
    for (size_t k = 1; k + 1 < m; k++, c++) {
        tris[3 * c] = ts->pos[0];
        tris[3 * c + 1] = ts->pos[k];
        tris[3 * c + 2] = ts->pos[k + 1];
    }
    *count = c;
}

mcsg_status mci_tess_face(const mci_ctx *ctx, mci_tess **t, const double *xyz,
                          const uint32_t *ids, uint32_t n, uint32_t *tris, uint32_t *count,
                          mci_tess_how *how, mcsg_error *err)
{
    mci_tess *ts = *t;
    *count = 0;
    *how = MCI_TESS_EMPTY;
    if (!ts) {
        ts = *t = mci_malloc(ctx, sizeof *ts);
        if (!ts)
            return mci_fail_nomem(err, "triangulating a polyhedron face");
        memset(ts, 0, sizeof *ts);
        ts->big = mci_malloc_array(ctx, TESS_BIGS, sizeof *ts->big);
        if (!ts->big)
            return mci_fail_nomem(err, "triangulating a polyhedron face");
    }
    if (!reserve(ctx, ts, n))
        return mci_fail_nomem(err, "triangulating a polyhedron face");
    /* PolysetUtils::tessellate_faces: repeated consecutive vertices, then a last equal
     * to the first */
    size_t m = 0;
    for (uint32_t k = 0; k < n; k++) {
        if (m > 0 && ids[k] == ts->ids[m - 1])
            continue;
        ts->ids[m] = ids[k];
        ts->pos[m++] = k;
        for (int j = 0; j < 3; j++)
            ts->fxyz[3 * (size_t)k + j] = (double)(float)xyz[3 * (size_t)k + j];
    }
    if (m > 1 && ts->ids[0] == ts->ids[m - 1])
        m--;
    if (m < 3)
        return MCSG_OK;
    if (m > 3)
        clean_face(ts, &m);
    if (m < 3)
        return MCSG_OK;
    if (m == 3) {
        for (int j = 0; j < 3; j++)
            tris[j] = ts->pos[j];
        *count = 1;
        *how = MCI_TESS_TRIANGLE;
        return MCSG_OK;
    }
    if (libtess2_triangles(ts, m, tris, count)) {
        *how = MCI_TESS_LIBTESS2;
        return MCSG_OK;
    }
    fan(ts, m, tris, count);
    *how = MCI_TESS_FAN;
    return MCSG_OK;
}
