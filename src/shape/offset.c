/*
 * The pieces of offset() (shape/offset.h), with Clipper 6's corner rules as OpenSCAD
 * 2021.01 calls them (ClipperOffset: MiterLimit 1e6, coordinates scaled by 2^16, which
 * sets the threshold under which a corner is too flat to join): for the corner at
 * vertex v between the previous edge's unit normal nk and the next one's nj, with
 * sinA = nk x nj,
 *  - |sinA delta 2^16| < 1 with nk . nj > 0: flat, nothing to fill;
 *  - sinA delta < 0: the moved edges cross there (a concave corner for this direction);
 *    the edge pieces cover it;
 *  - round: Clipper's arc from nk toward nj in steps of a turn / steps, as many as
 *    round(steps |angle| / 2 pi) (at least one), then nj;
 *  - miter: the point v + (nk + nj) delta / (1 + nk . nj), unless 1 + nk . nj is below
 *    2 / MiterLimit^2, then square;
 *  - square (chamfer): the corner cut at distance delta from v, across the bisector.
 * The normals are (dy, -dx) / length of each edge: outward for outlines with the region
 * on their left. These are choices of points, as Clipper makes them, not decisions about
 * existing geometry; the union of the pieces is exact.
 */
#include "shape/offset.h"

#include <math.h>
#include <string.h>

#define CLIPPER_SCALE 65536.0
#define MITER_LIMIT 1e6
#define TWO_PI 6.283185307179586476925

typedef struct piece_set {
    const mci_ctx *ctx;
    mci_outlines *o;
    size_t point_cap, loop_cap;
    double *join;     /* the current corner's points (x, y pairs) */
    size_t join_count, join_cap;
} piece_set;

static bool add_point(piece_set *s, double x, double y)
{
    mci_outlines *o = s->o;
    if (!mci_grow_array(s->ctx, (void **)&o->xy, &s->point_cap, 2 * (o->point_count + 1),
                        sizeof *o->xy, 256))
        return false;
    o->xy[2 * o->point_count] = x;
    o->xy[2 * o->point_count++ + 1] = y;
    return true;
}

static bool close_piece(piece_set *s)
{
    mci_outlines *o = s->o;
    if (!mci_grow_array(s->ctx, (void **)&o->loop_start, &s->loop_cap, o->loop_count + 2,
                        sizeof *o->loop_start, 64))
        return false;
    o->loop_start[++o->loop_count] = (uint32_t)o->point_count;
    return true;
}

static bool join_point(piece_set *s, const double *v, double dx, double dy)
{
    if (!mci_grow_array(s->ctx, (void **)&s->join, &s->join_cap, 2 * (s->join_count + 1),
                        sizeof *s->join, 64))
        return false;
    s->join[2 * s->join_count] = v[0] + dx;
    s->join[2 * s->join_count++ + 1] = v[1] + dy;
    return true;
}

static bool round_join(piece_set *s, const double *v, const double *nk, const double *nj,
                       double sin_a, double delta, double steps)
{
    double a = atan2(sin_a, nk[0] * nj[0] + nk[1] * nj[1]);
    double sr = sin(TWO_PI / steps) * (delta < 0 ? -1 : 1), cr = cos(TWO_PI / steps);
    double x = nk[0], y = nk[1];
    long count = lround(steps / TWO_PI * fabs(a));
    bool ok = true;
    for (long i = 0; ok && i < (count > 1 ? count : 1); i++) {
        double x2 = x;
        ok = join_point(s, v, x * delta, y * delta);
        x = x * cr - sr * y;
        y = x2 * sr + y * cr;
    }
    return ok && join_point(s, v, nj[0] * delta, nj[1] * delta);
}

static bool square_join(piece_set *s, const double *v, const double *nk, const double *nj,
                        double sin_a, double delta)
{
    double t = tan(atan2(sin_a, nk[0] * nj[0] + nk[1] * nj[1]) / 4);
    return join_point(s, v, nk[0] * delta, nk[1] * delta) &&
           join_point(s, v, delta * (nk[0] - nk[1] * t), delta * (nk[1] + nk[0] * t)) &&
           join_point(s, v, delta * (nj[0] + nj[1] * t), delta * (nj[1] - nj[0] * t)) &&
           join_point(s, v, nj[0] * delta, nj[1] * delta);
}

static bool miter_join(piece_set *s, const double *v, const double *nk, const double *nj,
                       double sin_a, double delta)
{
    double r = 1 + (nj[0] * nk[0] + nj[1] * nk[1]), q;
    if (r < 2 / (MITER_LIMIT * MITER_LIMIT))
        return square_join(s, v, nk, nj, sin_a, delta);
    q = delta / r;
    return join_point(s, v, nk[0] * delta, nk[1] * delta) &&
           join_point(s, v, (nk[0] + nj[0]) * q, (nk[1] + nj[1]) * q) &&
           join_point(s, v, nj[0] * delta, nj[1] * delta);
}

/* The join's points at v, from v + delta nk to v + delta nj (none where nothing is
 * filled). */
static bool corner_points(piece_set *s, const double *v, const double *nk, const double *nj,
                          double delta, mci_join join, double steps)
{
    double sin_a = nk[0] * nj[1] - nj[0] * nk[1];
    s->join_count = 0;
    if (fabs(sin_a * delta * CLIPPER_SCALE) < 1.0 && nk[0] * nj[0] + nk[1] * nj[1] > 0)
        return true;
    sin_a = fmax(-1.0, fmin(1.0, sin_a));
    if (sin_a * delta < 0)
        return true;
    switch (join) {
    case MCI_JOIN_ROUND: return round_join(s, v, nk, nj, sin_a, delta, steps);
    case MCI_JOIN_MITER: return miter_join(s, v, nk, nj, sin_a, delta);
    default: return square_join(s, v, nk, nj, sin_a, delta);
    }
}

static void unit_normal(const double *a, const double *b, double *n)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], f = 1 / sqrt(dx * dx + dy * dy);
    n[0] = dy * f;
    n[1] = -dx * f;
}

/* One piece per edge prev -> v: the edge swept by delta along its normal nk, with the
 * join at v attached (its points from v + delta nj back to v + delta nk): a rectangle
 * with a fan at one end, simple, and half as many pieces to unite as apart. */
static bool loop_pieces(piece_set *s, const mci_outlines *o, size_t loop, double delta,
                        mci_join join, double steps)
{
    const double *p = o->xy + 2 * (size_t)o->loop_start[loop];
    size_t n = o->loop_start[loop + 1] - o->loop_start[loop];
    for (size_t j = 0; j < n; j++) {
        const double *prev = p + 2 * ((j + n - 1) % n), *v = p + 2 * j, *next = p + 2 * ((j + 1) % n);
        double nk[2], nj[2];
        bool ok;
        unit_normal(prev, v, nk);
        unit_normal(v, next, nj);
        ok = corner_points(s, v, nk, nj, delta, join, steps) && add_point(s, prev[0], prev[1]) &&
             add_point(s, v[0], v[1]);
        for (size_t i = s->join_count; ok && i-- > 0;)
            ok = add_point(s, s->join[2 * i], s->join[2 * i + 1]);
        if (!ok || (s->join_count == 0 && !add_point(s, v[0] + nk[0] * delta, v[1] + nk[1] * delta)) ||
            !add_point(s, prev[0] + nk[0] * delta, prev[1] + nk[1] * delta) || !close_piece(s))
            return false;
    }
    return true;
}

mcsg_status mci_offset_pieces(const mci_ctx *ctx, const mci_outlines *o, double delta,
                              mci_join join, double steps, mci_outlines *pieces,
                              mcsg_error *err)
{
    piece_set s = {ctx, pieces, 0, 0, NULL, 0, 0};
    mcsg_status st = MCSG_OK;
    memset(pieces, 0, sizeof *pieces);
    pieces->loop_start = mci_calloc_array(ctx, 2, sizeof *pieces->loop_start);
    s.loop_cap = pieces->loop_start ? 2 : 0;
    if (!pieces->loop_start)
        st = mci_fail_nomem(err, "offsetting a 2D shape");
    for (size_t k = 0; st == MCSG_OK && k < o->loop_count; k++) {
        if (o->loop_start[k + 1] - o->loop_start[k] >= 3 &&
            !loop_pieces(&s, o, k, delta, join, steps))
            st = mci_fail_nomem(err, "offsetting a 2D shape");
    }
    mci_free(ctx, s.join);
    if (st != MCSG_OK)
        mci_outlines_free(ctx, pieces);
    return st;
}
