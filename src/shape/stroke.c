/*
 * Strokes of open paths (shape/stroke.h), as OpenSCAD 2021.01's libsvg makes them with
 * Clipper 6.2.1. Two steps:
 *  - the offset outline, by ClipperOffset's rules for an open path (MiterLimit 2, so any
 *    corner whose normals' dot product is at least -0.5 gets its miter point, else a
 *    chamfer; ArcTolerance 0.25 units, steps per turn pi / acos(1 - 0.25 / delta) capped
 *    at delta pi): the path's points truncated to integers (times 10000) with repeats
 *    dropped, unit normals (dy, -dx) / length; along the path, each inner corner
 *    (sinA delta < 0) as the moved end, the corner itself and the moved start, each
 *    outer corner as the join asks (round: arc points stepped by the turn's sine and
 *    cosine), a corner whose |sinA delta| is below 1 with the normals' dot product
 *    positive as one moved point; the end cap; the way back along the other side; the
 *    start cap. Butt caps are two points, square caps a chamfer across the end (sinA
 *    0), round caps half a turn of arc. A single point is a square of side 2 delta, or
 *    a full circle of arc steps for round joins. Every point is rounded half away from
 *    zero, as Clipper's Round.
 *  - the union of that outline by the positive fill rule. Crossings are found on the
 *    integers with exact orientation tests; each is rounded as Clipper's IntersectPoint
 *    rounds it (from the edges' slopes dx/dy in doubles; horizontal edges at their y),
 *    kept inside both edges' boxes, and inserted in both edges, as are points that lie
 *    on another edge; repeated until nothing crosses (16 rounds at most). The closed walk
 *    is then cut into simple loops at its repeated points, each loop's winding depth
 *    summed from the loops around it (exact point-in-polygon tests), and the loops that
 *    separate positive winding from the rest kept: their even-odd fill is Clipper's
 *    union.
 */
#include "shape/stroke.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define STROKE_SCALE 10000.0
#define MAX_UNITS 1125899906842624.0 /* 2^50: sums and differences stay exact */
#define CLIPPER_PI 3.141592653589793238
#define MAX_ROUNDS 16

__extension__ typedef __int128 wide;

typedef struct ipt {
    int64_t x, y;
} ipt;

typedef struct ipath {
    ipt *p;
    size_t n, cap;
} ipath;

typedef struct offsetter {
    const mci_ctx *ctx;
    const ipt *src;
    double (*normals)[2];
    double delta, sin_a, sin_step, cos_step, steps_per_rad, steps;
    mci_stroke_join join;
    ipath *dest;
    size_t max_points;
    mcsg_status status;
} offsetter;

static int64_t clipper_round(double v)
{
    return v < 0 ? (int64_t)(v - 0.5) : (int64_t)(v + 0.5);
}

static bool push_point(const mci_ctx *ctx, ipath *path, int64_t x, int64_t y)
{
    if (!mci_grow_array(ctx, (void **)&path->p, &path->cap, path->n + 1, sizeof *path->p, 64))
        return false;
    path->p[path->n++] = (ipt){x, y};
    return true;
}

static void emit(offsetter *o, double x, double y)
{
    if (o->status != MCSG_OK)
        return;
    if (o->dest->n >= o->max_points)
        o->status = MCSG_ERR_LIMIT;
    else if (!push_point(o->ctx, o->dest, clipper_round(x), clipper_round(y)))
        o->status = MCSG_ERR_NOMEM;
}

/* The source point j moved by normal n times delta. */
static void emit_moved(offsetter *o, size_t j, const double n[2])
{
    emit(o, (double)o->src[j].x + n[0] * o->delta, (double)o->src[j].y + n[1] * o->delta);
}

static void do_square(offsetter *o, size_t j, size_t k)
{
    const double *nk = o->normals[k], *nj = o->normals[j];
    double sx = (double)o->src[j].x, sy = (double)o->src[j].y;
    double dx = tan(atan2(o->sin_a, nk[0] * nj[0] + nk[1] * nj[1]) / 4);
    emit(o, sx + o->delta * (nk[0] - nk[1] * dx), sy + o->delta * (nk[1] + nk[0] * dx));
    emit(o, sx + o->delta * (nj[0] + nj[1] * dx), sy + o->delta * (nj[1] - nj[0] * dx));
}

static void do_miter(offsetter *o, size_t j, size_t k, double r)
{
    const double *nk = o->normals[k], *nj = o->normals[j];
    double q = o->delta / r;
    emit(o, (double)o->src[j].x + (nk[0] + nj[0]) * q, (double)o->src[j].y + (nk[1] + nj[1]) * q);
}

static void do_round(offsetter *o, size_t j, size_t k)
{
    const double *nk = o->normals[k], *nj = o->normals[j];
    double a = atan2(o->sin_a, nk[0] * nj[0] + nk[1] * nj[1]);
    int64_t steps = clipper_round(o->steps_per_rad * fabs(a));
    double x = nk[0], y = nk[1];
    for (int64_t i = 0; i < (steps > 1 ? steps : 1) && o->status == MCSG_OK; i++) {
        double x2 = x;
        emit_moved(o, j, (double[2]){x, y});
        x = x * o->cos_step - o->sin_step * y;
        y = x2 * o->sin_step + y * o->cos_step;
    }
    emit_moved(o, j, nj);
}

/* Clipper's OffsetPoint: the join at source point j after the edge with normal k; k
 * becomes j unless the corner is flat. */
static void offset_point(offsetter *o, size_t j, size_t *k)
{
    const double *nk = o->normals[*k], *nj = o->normals[j];
    o->sin_a = nk[0] * nj[1] - nj[0] * nk[1];
    if (fabs(o->sin_a * o->delta) < 1.0) {
        if (nk[0] * nj[0] + nj[1] * nk[1] > 0) {
            emit_moved(o, j, nk);
            return;
        }
    } else if (o->sin_a > 1.0) {
        o->sin_a = 1.0;
    } else if (o->sin_a < -1.0) {
        o->sin_a = -1.0;
    }
    if (o->sin_a * o->delta < 0) {
        emit_moved(o, j, nk);
        emit(o, (double)o->src[j].x, (double)o->src[j].y);
        emit_moved(o, j, nj);
    } else if (o->join == MCI_STROKE_MITER) {
        double r = 1 + (nj[0] * nk[0] + nj[1] * nk[1]);
        if (r >= 0.5)
            do_miter(o, j, *k, r);
        else
            do_square(o, j, *k);
    } else if (o->join == MCI_STROKE_SQUARE) {
        do_square(o, j, *k);
    } else {
        do_round(o, j, *k);
    }
    *k = j;
}

static void unit_normal(ipt a, ipt b, double n[2])
{
    double dx = (double)(b.x - a.x), dy = (double)(b.y - a.y), f;
    if (a.x == b.x && a.y == b.y) {
        n[0] = n[1] = 0;
        return;
    }
    f = 1.0 / sqrt(dx * dx + dy * dy);
    dx *= f;
    dy *= f;
    n[0] = dy;
    n[1] = -dx;
}

static void cap(offsetter *o, mci_stroke_cap cap_type, size_t j, size_t k, double sign)
{
    if (cap_type == MCI_CAP_BUTT) {
        const double *n = o->normals[j];
        emit_moved(o, j, (double[2]){sign * n[0], sign * n[1]});
        emit_moved(o, j, (double[2]){-sign * n[0], -sign * n[1]});
        return;
    }
    o->sin_a = 0;
    if (cap_type == MCI_CAP_SQUARE)
        do_square(o, j, k);
    else
        do_round(o, j, k);
}

/* A lone point: Clipper's square, or its circle for round joins. */
static void offset_single(offsetter *o)
{
    if (o->join == MCI_STROKE_ROUND) {
        double x = 1.0, y = 0.0;
        for (int64_t j = 1; (double)j <= o->steps && o->status == MCSG_OK; j++) {
            double x2 = x;
            emit_moved(o, 0, (double[2]){x, y});
            x = x * o->cos_step - o->sin_step * y;
            y = x2 * o->sin_step + y * o->cos_step;
        }
        return;
    }
    emit_moved(o, 0, (double[2]){-1, -1});
    emit_moved(o, 0, (double[2]){1, -1});
    emit_moved(o, 0, (double[2]){1, 1});
    emit_moved(o, 0, (double[2]){-1, 1});
}

/* Clipper's DoOffset for one open path of len >= 2 distinct consecutive points. */
static void offset_open(offsetter *o, size_t len, mci_stroke_cap cap_type)
{
    double (*n)[2] = o->normals;
    size_t k = 0;
    for (size_t j = 0; j + 1 < len; j++)
        unit_normal(o->src[j], o->src[j + 1], n[j]);
    n[len - 1][0] = n[len - 2][0];
    n[len - 1][1] = n[len - 2][1];
    for (size_t j = 1; j + 1 < len; j++)
        offset_point(o, j, &k);
    if (cap_type != MCI_CAP_BUTT) {
        n[len - 1][0] = -n[len - 1][0];
        n[len - 1][1] = -n[len - 1][1];
    }
    cap(o, cap_type, len - 1, len - 2, 1);
    for (size_t j = len - 1; j > 0; j--) {
        n[j][0] = -n[j - 1][0];
        n[j][1] = -n[j - 1][1];
    }
    n[0][0] = -n[1][0];
    n[0][1] = -n[1][1];
    k = len - 1;
    for (size_t j = len - 2; j > 0; j--)
        offset_point(o, j, &k);
    cap(o, cap_type, 0, 1, -1);
}

/* ---------------------------------------------------------------------------------- */
/* The union of the outline (positive fill) */

static wide orient(ipt a, ipt b, ipt c)
{
    return (wide)(b.x - a.x) * (c.y - a.y) - (wide)(b.y - a.y) * (c.x - a.x);
}

static int sign_of(wide v)
{
    return (v > 0) - (v < 0);
}

static bool same_point(ipt a, ipt b)
{
    return a.x == b.x && a.y == b.y;
}

/* Whether c, on the line through a and b, lies strictly between them. */
static bool strictly_between(ipt a, ipt b, ipt c)
{
    return (wide)(c.x - a.x) * (b.x - a.x) + (wide)(c.y - a.y) * (b.y - a.y) > 0 &&
           (wide)(c.x - b.x) * (a.x - b.x) + (wide)(c.y - b.y) * (a.y - b.y) > 0;
}

/* An edge as Clipper holds it: bottom (larger y) and top, and dx/dy. */
typedef struct cedge {
    ipt bot, top;
    double dx;
    bool horizontal, vertical;
} cedge;

static cedge clipper_edge(ipt a, ipt b)
{
    cedge e;
    e.bot = a.y >= b.y ? a : b;
    e.top = a.y >= b.y ? b : a;
    e.horizontal = e.bot.y == e.top.y;
    e.vertical = e.bot.x == e.top.x;
    e.dx = e.horizontal ? -1e40 : (double)(e.top.x - e.bot.x) / (double)(e.top.y - e.bot.y);
    return e;
}

static int64_t top_x(const cedge *e, int64_t y)
{
    return y == e->top.y ? e->top.x : e->bot.x + clipper_round(e->dx * (double)(y - e->bot.y));
}

static int64_t clamp64(int64_t v, int64_t lo, int64_t hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* Clipper's IntersectPoint for two edges that cross, then kept inside both boxes. */
static ipt crossing_point(ipt a, ipt b, ipt c, ipt d)
{
    cedge e1 = clipper_edge(a, b), e2 = clipper_edge(c, d);
    ipt ip;
    if (e1.horizontal || e2.horizontal) {
        const cedge *h = e1.horizontal ? &e1 : &e2, *other = e1.horizontal ? &e2 : &e1;
        ip.y = h->bot.y;
        ip.x = other->horizontal ? h->bot.x : top_x(other, ip.y);
    } else if (e1.vertical || e2.vertical) {
        const cedge *v = e1.vertical ? &e1 : &e2, *other = e1.vertical ? &e2 : &e1;
        double b2 = (double)other->bot.y - ((double)other->bot.x / other->dx);
        ip.x = v->bot.x;
        ip.y = other->vertical ? v->bot.y : clipper_round((double)ip.x / other->dx + b2);
    } else {
        double b1 = (double)e1.bot.x - (double)e1.bot.y * e1.dx;
        double b2 = (double)e2.bot.x - (double)e2.bot.y * e2.dx;
        double q = (b2 - b1) / (e1.dx - e2.dx);
        ip.y = clipper_round(q);
        ip.x = fabs(e1.dx) < fabs(e2.dx) ? clipper_round(e1.dx * q + b1)
                                         : clipper_round(e2.dx * q + b2);
    }
    if (ip.y < e1.top.y || ip.y < e2.top.y) {
        ip.y = e1.top.y > e2.top.y ? e1.top.y : e2.top.y;
        ip.x = fabs(e1.dx) < fabs(e2.dx) ? top_x(&e1, ip.y) : top_x(&e2, ip.y);
    }
    {
        int64_t lox = a.x < b.x ? a.x : b.x, hix = a.x < b.x ? b.x : a.x;
        int64_t loy = a.y < b.y ? a.y : b.y, hiy = a.y < b.y ? b.y : a.y;
        lox = lox > (c.x < d.x ? c.x : d.x) ? lox : (c.x < d.x ? c.x : d.x);
        hix = hix < (c.x < d.x ? d.x : c.x) ? hix : (c.x < d.x ? d.x : c.x);
        loy = loy > (c.y < d.y ? c.y : d.y) ? loy : (c.y < d.y ? c.y : d.y);
        hiy = hiy < (c.y < d.y ? d.y : c.y) ? hiy : (c.y < d.y ? d.y : c.y);
        ip.x = clamp64(ip.x, lox, hix);
        ip.y = clamp64(ip.y, loy, hiy);
    }
    return ip;
}

/* A point to insert into an edge. */
typedef struct insertion {
    size_t edge;
    ipt p;
    wide along; /* (p - edge start) . edge direction */
} insertion;

typedef struct splitter {
    const mci_ctx *ctx;
    ipath *poly;
    insertion *ins;
    size_t ins_count, ins_cap, max_points;
    mcsg_status status;
} splitter;

static void insert(splitter *s, size_t edge, ipt p)
{
    const ipt *v = s->poly->p;
    ipt a = v[edge], b = v[(edge + 1) % s->poly->n];
    if (s->status != MCSG_OK || same_point(p, a) || same_point(p, b))
        return;
    if (s->ins_count >= s->max_points) {
        s->status = MCSG_ERR_LIMIT;
        return;
    }
    if (!mci_grow_array(s->ctx, (void **)&s->ins, &s->ins_cap, s->ins_count + 1, sizeof *s->ins,
                        64)) {
        s->status = MCSG_ERR_NOMEM;
        return;
    }
    s->ins[s->ins_count++] =
        (insertion){edge, p, (wide)(p.x - a.x) * (b.x - a.x) + (wide)(p.y - a.y) * (b.y - a.y)};
}

static void test_pair(splitter *s, size_t i, size_t j)
{
    size_t n = s->poly->n;
    const ipt *v = s->poly->p;
    ipt a = v[i], b = v[(i + 1) % n], c = v[j], d = v[(j + 1) % n];
    int o1 = sign_of(orient(a, b, c)), o2 = sign_of(orient(a, b, d));
    int o3 = sign_of(orient(c, d, a)), o4 = sign_of(orient(c, d, b));
    if (o1 * o2 < 0 && o3 * o4 < 0) {
        ipt ip = crossing_point(a, b, c, d);
        insert(s, i, ip);
        insert(s, j, ip);
        return;
    }
    if (o1 == 0 && strictly_between(a, b, c))
        insert(s, i, c);
    if (o2 == 0 && strictly_between(a, b, d))
        insert(s, i, d);
    if (o3 == 0 && strictly_between(c, d, a))
        insert(s, j, a);
    if (o4 == 0 && strictly_between(c, d, b))
        insert(s, j, b);
}

typedef struct edge_box {
    int64_t xmin, xmax, ymin, ymax;
    size_t edge;
} edge_box;

static int compare_boxes(const void *pa, const void *pb)
{
    const edge_box *a = pa, *b = pb;
    return (a->xmin > b->xmin) - (a->xmin < b->xmin);
}

static int compare_insertions(const void *pa, const void *pb)
{
    const insertion *a = pa, *b = pb;
    if (a->edge != b->edge)
        return (a->edge > b->edge) - (a->edge < b->edge);
    return (a->along > b->along) - (a->along < b->along);
}

/* Consecutive repeats (and the last point equal to the first) dropped, in place. */
static void drop_repeats(ipath *p)
{
    size_t m = 0;
    for (size_t i = 0; i < p->n; i++)
        if (m == 0 || !same_point(p->p[m - 1], p->p[i]))
            p->p[m++] = p->p[i];
    while (m > 1 && same_point(p->p[m - 1], p->p[0]))
        m--;
    p->n = m;
}

/* Every insertion found in one sweep over the edges' boxes. */
static void find_insertions(splitter *s, edge_box *boxes)
{
    size_t n = s->poly->n;
    for (size_t i = 0; i < n; i++) {
        ipt a = s->poly->p[i], b = s->poly->p[(i + 1) % n];
        boxes[i] = (edge_box){a.x < b.x ? a.x : b.x, a.x < b.x ? b.x : a.x,
                              a.y < b.y ? a.y : b.y, a.y < b.y ? b.y : a.y, i};
    }
    qsort(boxes, n, sizeof *boxes, compare_boxes);
    for (size_t i = 0; i < n && s->status == MCSG_OK; i++)
        for (size_t j = i + 1; j < n && boxes[j].xmin <= boxes[i].xmax; j++)
            if (boxes[j].ymin <= boxes[i].ymax && boxes[i].ymin <= boxes[j].ymax)
                test_pair(s, boxes[i].edge, boxes[j].edge);
}

/* The polygon with the insertions in place, along each edge in order. */
static mcsg_status apply_insertions(splitter *s)
{
    ipath out = {0};
    size_t next = 0;
    qsort(s->ins, s->ins_count, sizeof *s->ins, compare_insertions);
    for (size_t i = 0; i < s->poly->n; i++) {
        if (!push_point(s->ctx, &out, s->poly->p[i].x, s->poly->p[i].y))
            goto nomem;
        for (; next < s->ins_count && s->ins[next].edge == i; next++)
            if (!push_point(s->ctx, &out, s->ins[next].p.x, s->ins[next].p.y))
                goto nomem;
    }
    mci_free(s->ctx, s->poly->p);
    *s->poly = out;
    drop_repeats(s->poly);
    return s->poly->n > s->max_points ? MCSG_ERR_LIMIT : MCSG_OK;
nomem:
    mci_free(s->ctx, out.p);
    return MCSG_ERR_NOMEM;
}

/* Insert crossings and touching points until no two edges cross. */
static mcsg_status split_crossings(const mci_ctx *ctx, ipath *poly, size_t max_points,
                                   mcsg_error *err)
{
    splitter s = {ctx, poly, NULL, 0, 0, max_points, MCSG_OK};
    edge_box *boxes = NULL;
    for (int round = 0; s.status == MCSG_OK; round++) {
        if (round == MAX_ROUNDS) {
            s.status = mci_fail(err, MCSG_ERR_UNSUPPORTED, "the stroke's outline crosses "
                                "itself where rounding its crossings does not settle");
            break;
        }
        mci_free(ctx, boxes);
        boxes = mci_malloc_array(ctx, poly->n + 1, sizeof *boxes);
        if (!boxes) {
            s.status = MCSG_ERR_NOMEM;
            break;
        }
        s.ins_count = 0;
        find_insertions(&s, boxes);
        if (s.status != MCSG_OK || s.ins_count == 0)
            break;
        s.status = apply_insertions(&s);
    }
    mci_free(ctx, boxes);
    mci_free(ctx, s.ins);
    if (s.status == MCSG_ERR_NOMEM)
        return mci_fail_nomem(err, "stroking an SVG path");
    if (s.status == MCSG_ERR_LIMIT)
        return mci_fail(err, MCSG_ERR_LIMIT, "a stroke's outline has more than %zu points",
                        max_points);
    return s.status;
}

/* Loops of a closed walk cut at its repeated points (a hash of point -> stack slot). */
typedef struct loops {
    ipath pts;      /* the loops' points, loop after loop */
    size_t *start;  /* count + 1 */
    size_t count, cap;
} loops;

static size_t hash_point(ipt p, size_t mask)
{
    uint64_t h = (uint64_t)p.x * 0x9e3779b97f4a7c15u ^ ((uint64_t)p.y + 0x632be59bd9b4e019u) *
                                                          0xbf58476d1ce4e5b9u;
    return (size_t)(h ^ (h >> 29)) & mask;
}

static bool add_loop(const mci_ctx *ctx, loops *l, const ipt *p, size_t n)
{
    if (!mci_grow_array(ctx, (void **)&l->start, &l->cap, l->count + 2, sizeof *l->start, 16))
        return false;
    if (l->count == 0)
        l->start[0] = 0;
    for (size_t i = 0; i < n; i++)
        if (!push_point(ctx, &l->pts, p[i].x, p[i].y))
            return false;
    l->start[++l->count] = l->pts.n;
    return true;
}

static bool cut_loops(const mci_ctx *ctx, const ipath *poly, loops *out)
{
    size_t cap = 16, top = 0;
    size_t *table;
    ipt *stack;
    bool ok = true;
    while (cap < 2 * poly->n + 2)
        cap *= 2;
    table = mci_malloc_array(ctx, cap, sizeof *table);
    stack = mci_malloc_array(ctx, poly->n + 1, sizeof *stack);
    if (!table || !stack) {
        mci_free(ctx, table);
        mci_free(ctx, stack);
        return false;
    }
    /* Entries name stack slots; one is current while its slot, below the top, still
     * holds the point looked for (points on the stack are distinct). */
    memset(table, 0xff, cap * sizeof *table);
    for (size_t i = 0; i < poly->n && ok; i++) {
        ipt p = poly->p[i];
        size_t h = hash_point(p, cap - 1), found = SIZE_MAX;
        for (; table[h] != SIZE_MAX; h = (h + 1) & (cap - 1))
            if (table[h] < top && same_point(stack[table[h]], p)) {
                found = table[h];
                break;
            }
        if (found == SIZE_MAX) {
            for (; table[h] != SIZE_MAX; h = (h + 1) & (cap - 1))
                ;
            table[h] = top;
            stack[top++] = p;
            continue;
        }
        ok = top - found < 3 || add_loop(ctx, out, stack + found, top - found);
        top = found + 1;
    }
    if (ok && top >= 3)
        ok = add_loop(ctx, out, stack, top);
    mci_free(ctx, table);
    mci_free(ctx, stack);
    return ok;
}

static wide loop_area2(const ipt *p, size_t n)
{
    wide sum = 0;
    for (size_t i = 0; i < n; i++) {
        ipt a = p[i], b = p[(i + 1) % n];
        sum += (wide)a.x * b.y - (wide)b.x * a.y;
    }
    return sum;
}

/* Where q (coordinates times `den`, 1 or 2) is against the loop: 1 inside, 0 outside,
 * -1 on its boundary. */
static int point_in_loop(const ipt *p, size_t n, ipt q, int64_t den)
{
    bool inside = false;
    for (size_t i = 0; i < n; i++) {
        ipt a = {p[i].x * den, p[i].y * den}, b = {p[(i + 1) % n].x * den, p[(i + 1) % n].y * den};
        wide side = orient(a, b, q);
        if (side == 0 && (q.x >= (a.x < b.x ? a.x : b.x)) && q.x <= (a.x < b.x ? b.x : a.x) &&
            q.y >= (a.y < b.y ? a.y : b.y) && q.y <= (a.y < b.y ? b.y : a.y))
            return -1;
        if ((a.y > q.y) != (b.y > q.y) && (side > 0) == (b.y > a.y))
            inside = !inside;
    }
    return inside;
}

/* Whether loop l lies inside loop m (they do not cross): a vertex, or else an edge's
 * midpoint, of l off m's boundary decides. */
static bool loop_inside(const ipt *l, size_t ln, const ipt *m, size_t mn)
{
    for (size_t i = 0; i < ln; i++) {
        int where = point_in_loop(m, mn, l[i], 1);
        if (where >= 0)
            return where == 1;
    }
    for (size_t i = 0; i < ln; i++) {
        ipt mid = {l[i].x + l[(i + 1) % ln].x, l[i].y + l[(i + 1) % ln].y};
        int where = point_in_loop(m, mn, mid, 2);
        if (where >= 0)
            return where == 1;
    }
    return false;
}

typedef struct loop_info {
    int64_t xmin, xmax, ymin, ymax;
    int sign;
} loop_info;

static void loop_box(const ipt *p, size_t n, loop_info *b)
{
    b->xmin = b->xmax = p[0].x;
    b->ymin = b->ymax = p[0].y;
    for (size_t i = 1; i < n; i++) {
        b->xmin = p[i].x < b->xmin ? p[i].x : b->xmin;
        b->xmax = p[i].x > b->xmax ? p[i].x : b->xmax;
        b->ymin = p[i].y < b->ymin ? p[i].y : b->ymin;
        b->ymax = p[i].y > b->ymax ? p[i].y : b->ymax;
    }
}

/* The loops that bound the positive winding, as outlines in user units. */
static mcsg_status keep_boundaries(const mci_ctx *ctx, const loops *l, mci_outlines *out,
                                   mcsg_error *err)
{
    loop_info *info = mci_calloc_array(ctx, l->count + 1, sizeof *info);
    size_t points = 0, kept = 0;
    bool *keep = mci_calloc_array(ctx, l->count + 1, sizeof *keep);
    if (!info || !keep)
        goto nomem;
    for (size_t k = 0; k < l->count; k++) {
        const ipt *p = l->pts.p + l->start[k];
        size_t n = l->start[k + 1] - l->start[k];
        loop_box(p, n, &info[k]);
        info[k].sign = sign_of(loop_area2(p, n));
    }
    for (size_t k = 0; k < l->count; k++) {
        int depth = 0;
        if (info[k].sign == 0)
            continue;
        for (size_t m = 0; m < l->count; m++) {
            if (m == k || info[m].sign == 0 || info[m].xmin > info[k].xmin ||
                info[m].xmax < info[k].xmax || info[m].ymin > info[k].ymin ||
                info[m].ymax < info[k].ymax)
                continue;
            if (loop_inside(l->pts.p + l->start[k], l->start[k + 1] - l->start[k],
                            l->pts.p + l->start[m], l->start[m + 1] - l->start[m]))
                depth += info[m].sign;
        }
        keep[k] = (depth + info[k].sign > 0) != (depth > 0);
        if (keep[k]) {
            points += l->start[k + 1] - l->start[k];
            kept++;
        }
    }
    out->xy = mci_malloc_array(ctx, points + 1, 2 * sizeof *out->xy);
    out->loop_start = mci_calloc_array(ctx, kept + 1, sizeof *out->loop_start);
    if (!out->xy || !out->loop_start)
        goto nomem;
    for (size_t k = 0; k < l->count; k++) {
        if (!keep[k])
            continue;
        for (size_t i = l->start[k]; i < l->start[k + 1]; i++) {
            out->xy[2 * out->point_count] = (double)l->pts.p[i].x / STROKE_SCALE;
            out->xy[2 * out->point_count++ + 1] = (double)l->pts.p[i].y / STROKE_SCALE;
        }
        out->loop_start[++out->loop_count] = (uint32_t)out->point_count;
    }
    mci_free(ctx, info);
    mci_free(ctx, keep);
    return MCSG_OK;
nomem:
    mci_free(ctx, info);
    mci_free(ctx, keep);
    mci_outlines_free(ctx, out);
    return mci_fail_nomem(err, "stroking an SVG path");
}

static mcsg_status unite(const mci_ctx *ctx, ipath *poly, size_t max_points, mci_outlines *out,
                         mcsg_error *err)
{
    loops l = {0};
    mcsg_status st;
    drop_repeats(poly);
    if (poly->n < 3)
        return MCSG_OK;
    st = split_crossings(ctx, poly, max_points, err);
    if (st == MCSG_OK && !cut_loops(ctx, poly, &l))
        st = mci_fail_nomem(err, "stroking an SVG path");
    if (st == MCSG_OK)
        st = keep_boundaries(ctx, &l, out, err);
    mci_free(ctx, l.pts.p);
    mci_free(ctx, l.start);
    return st;
}

/* The path's points in Clipper's units (truncated), repeats dropped. */
static mcsg_status to_units(const mci_ctx *ctx, const double *xy, size_t n, ipath *src,
                            mcsg_error *err)
{
    for (size_t i = 0; i < n; i++) {
        double x = xy[2 * i] * STROKE_SCALE, y = xy[2 * i + 1] * STROKE_SCALE;
        if (!(fabs(x) <= MAX_UNITS && fabs(y) <= MAX_UNITS))
            return mci_fail(err, MCSG_ERR_UNSUPPORTED, "a stroked point (%g, %g) is beyond "
                            "2^50 / 10000 or not finite", xy[2 * i], xy[2 * i + 1]);
        if (src->n > 0 && src->p[src->n - 1].x == (int64_t)x && src->p[src->n - 1].y == (int64_t)y)
            continue;
        if (!push_point(ctx, src, (int64_t)x, (int64_t)y))
            return mci_fail_nomem(err, "stroking an SVG path");
    }
    return MCSG_OK;
}

/* ClipperOffset's arc steps for delta (its DoOffset preamble). */
static void arc_steps(offsetter *o)
{
    double y = 0.25 > fabs(o->delta) * 0.25 ? fabs(o->delta) * 0.25 : 0.25;
    double steps = CLIPPER_PI / acos(1 - y / fabs(o->delta));
    if (steps > fabs(o->delta) * CLIPPER_PI)
        steps = fabs(o->delta) * CLIPPER_PI;
    o->steps = steps;
    o->sin_step = sin(CLIPPER_PI * 2 / steps);
    o->cos_step = cos(CLIPPER_PI * 2 / steps);
    o->steps_per_rad = steps / (CLIPPER_PI * 2);
}

mcsg_status mci_stroke_outline(const mci_ctx *ctx, const double *xy, size_t n, double width,
                               mci_stroke_cap cap_type, mci_stroke_join join,
                               size_t max_points, mci_outlines *out, mcsg_error *err)
{
    ipath src = {0}, raw = {0};
    offsetter o = {0};
    mcsg_status st;
    memset(out, 0, sizeof *out);
    o.delta = width * 5000.0;
    if (!(o.delta >= 1e-20 && o.delta <= MAX_UNITS))
        return mci_fail(err, MCSG_ERR_UNSUPPORTED, "a stroke width of %g is not supported",
                        width);
    st = to_units(ctx, xy, n, &src, err);
    if (st == MCSG_OK && src.n > 0) {
        o.ctx = ctx;
        o.src = src.p;
        o.join = join;
        o.dest = &raw;
        o.max_points = max_points;
        o.normals = mci_malloc_array(ctx, src.n + 1, sizeof *o.normals);
        arc_steps(&o);
        if (!o.normals)
            o.status = MCSG_ERR_NOMEM;
        else if (src.n == 1)
            offset_single(&o);
        else
            offset_open(&o, src.n, cap_type);
        st = o.status == MCSG_ERR_NOMEM ? mci_fail_nomem(err, "stroking an SVG path")
             : o.status == MCSG_ERR_LIMIT
                 ? mci_fail(err, MCSG_ERR_LIMIT, "a stroke's outline has more than %zu points",
                            max_points)
                 : MCSG_OK;
        mci_free(ctx, o.normals);
    }
    if (st == MCSG_OK && raw.n > 0)
        st = unite(ctx, &raw, max_points, out, err);
    mci_free(ctx, src.p);
    mci_free(ctx, raw.p);
    return st;
}
