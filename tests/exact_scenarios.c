/*
 * The scenarios of test_exact_kernel (see exact_scenarios.h).
 */
#include "exact_scenarios.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- random numbers */

uint64_t rng_state = 0x5eed2024u;

uint64_t rng_next(void) /* splitmix64 */
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

double rng_unit(void) { return (double)(rng_next() >> 11) * 0x1p-53; }

int rng_int(int lo, int hi) /* inclusive */
{
    return lo + (int)(rng_next() % (uint64_t)(hi - lo + 1));
}

bool rng_chance(double p) { return rng_unit() < p; }

double rng_sign(void) { return (rng_next() & 1) ? -1.0 : 1.0; }

/* ---------------------------------------------------------------- coordinate regimes */

static const char *const regime_names[R_COUNT] = {
    "unit", "smallint", "exp", "mix", "far", "fargrid", "scales", "bits"};

/* The "bits" regime's integer width for the current scenario (set per scenario). */
static int bits_width = 1;

/* A b-bit integer times 2^-20, often at the extremes +-(2^b - 1) and +-2^(b-1): the
 * exact stage's 128-bit path is taken when a degree bound proves the polynomial fits,
 * and widths from 1 to 40 bits (half of them up to 8, where the degree-20 predicates
 * change paths) put every predicate on both sides of that bound, with the largest
 * intermediates it admits. */
static double draw_bits(void)
{
    int64_t top = ((int64_t)1 << bits_width) - 1, x;
    switch (rng_int(0, 3)) {
    case 0:
        x = top;
        break;
    case 1:
        x = (int64_t)1 << (bits_width - 1);
        break;
    default:
        x = (int64_t)(rng_unit() * (double)(top + 1));
        break;
    }
    return rng_sign() * ldexp((double)x, -20);
}

/* One coordinate. smallint and fargrid make exact coplanarity frequent; exp spans the
 * whole double range (subnormals included); mix puts 1e-300, 1e300, 3.4e38 and 1e-3 in
 * one case; far clusters points 1e6 from the origin; bits: see draw_bits. */
static double draw_coord(int regime)
{
    static const double mix[] = {0, 1e-300, 1e300, 3.4e38, 1e-3, 1};
    switch (regime) {
    case R_UNIT:
        return 2 * rng_unit() - 1;
    case R_INT:
        return rng_int(-6, 6);
    case R_EXP:
        return rng_chance(0.03) ? 0
                                : rng_sign() * ldexp(1 + rng_unit(), rng_int(-1074, 1023));
    case R_MIX:
        return rng_sign() * mix[rng_int(0, 5)] * (rng_chance(0.5) ? 1 : 1 + rng_unit());
    case R_FAR:
        return 1e6 + (2 * rng_unit() - 1) * 1e-3;
    case R_FARGRID:
        return 1e6 + rng_int(-4, 4) * 0x1p-30;
    default: /* R_BITS */
        return draw_bits();
    }
}

/* A vertex. "scales" mixes a 50-unit part with coordinates like 1e-17 that should have
 * been 0, per vertex. */
static void draw_vertex(int regime, double out[3])
{
    static const double scales[] = {50, 1e-17, 1};
    double s = scales[rng_int(0, 2)];
    for (int k = 0; k < 3; k++) {
        if (regime != R_SCALES)
            out[k] = draw_coord(regime);
        else
            out[k] = rng_chance(0.1) ? 0 : s * (2 * rng_unit() - 1);
    }
}

double nudge(double x, int n)
{
    double dir = rng_chance(0.5) ? INFINITY : -INFINITY;
    for (int i = 0; i < n; i++) {
        double y = nextafter(x, dir);
        if (!isfinite(y))
            break;
        x = y;
    }
    return x;
}

static int sc_vertex(scenario *s, const double x[3])
{
    if (s->nv >= MAXV)
        abort();
    memcpy(s->v[s->nv], x, sizeof s->v[0]);
    return s->nv++;
}

static int sc_plane(scenario *s, int a, int b, int c)
{
    if (s->npl >= MAXPL)
        abort();
    s->plv[s->npl][0] = a;
    s->plv[s->npl][1] = b;
    s->plv[s->npl][2] = c;
    return s->npl++;
}

/* A plane through a, b, c in a random one of its three rotations (same orientation). */
static int sc_plane_rotated(scenario *s, int a, int b, int c)
{
    int r = rng_int(0, 2), t[3] = {a, b, c};
    return sc_plane(s, t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
}

static int sc_point(scenario *s, mci_point_kind kind, int v0, int v1, int p0, int p1,
                    int p2)
{
    if (s->npt >= MAXPT)
        abort();
    s->pt[s->npt] = (point_def){kind, {v0, v1}, {p0, p1, p2}};
    return s->npt++;
}

static int sc_explicit(scenario *s, int v)
{
    return sc_point(s, MCI_POINT_EXPLICIT, v, v, 0, 0, 0);
}

static int sc_lpi(scenario *s, int l0, int l1, int pl)
{
    return sc_point(s, MCI_POINT_LPI, l0, l1, pl, pl, pl);
}

static int sc_tpi(scenario *s, int p0, int p1, int p2)
{
    return sc_point(s, MCI_POINT_TPI, 0, 0, p0, p1, p2);
}

static void sc_line_planes(scenario *s, int p0, int p1)
{
    if (s->nlp >= MAXLP)
        abort();
    s->line_planes[s->nlp][0] = p0;
    s->line_planes[s->nlp++][1] = p1;
}

static void sc_line_edge(scenario *s, int v0, int v1)
{
    if (s->nle >= MAXLE)
        abort();
    s->line_edges[s->nle][0] = v0;
    s->line_edges[s->nle++][1] = v1;
}

/* ---------------------------------------------------------------- classes */

char class_names[MAX_CLASSES][24];
int nclasses;

int class_id(const char *prefix, const char *name)
{
    char buf[24];
    snprintf(buf, sizeof buf, "%s%s", prefix, name);
    for (int i = 0; i < nclasses; i++)
        if (strcmp(class_names[i], buf) == 0)
            return i;
    if (nclasses >= MAX_CLASSES)
        abort();
    memcpy(class_names[nclasses], buf, sizeof buf);
    return nclasses++;
}

/* ---------------------------------------------------------------- random scenarios */

static int random_vertex(scenario *s, int regime)
{
    double x[3];
    draw_vertex(regime, x);
    return sc_vertex(s, x);
}

/* Random vertices; planes 0..2 share the line v0 v1 (in both orientations) so that
 * points on it can be ordered; LPIs and TPIs on that line and elsewhere. A few cases are
 * degenerate on purpose (repeated vertex in a plane, repeated plane in a TPI, p = q). */
void scenario_random(scenario *s, int regime)
{
    const int nv = 12;
    memset(s, 0, sizeof *s);
    s->cls = class_id("random/", regime_names[regime]);
    bits_width = rng_chance(0.5) ? rng_int(1, 8) : rng_int(9, 40);
    for (int i = 0; i < nv; i++)
        random_vertex(s, regime);
    sc_plane(s, 0, 1, 2);
    sc_plane(s, 1, 0, 3);
    sc_plane(s, 4, 0, 1);
    for (int p = 3; p < 8; p++) {
        int a = rng_int(2, nv - 1), b = rng_int(2, nv - 1), c = rng_int(2, nv - 1);
        if (!rng_chance(0.03))
            while (b == a || c == a || c == b)
                b = rng_int(2, nv - 1), c = rng_int(2, nv - 1);
        sc_plane(s, a, b, c);
    }
    sc_explicit(s, 0);
    sc_explicit(s, 1);
    sc_explicit(s, rng_int(2, nv - 1));
    sc_explicit(s, rng_int(2, nv - 1));
    sc_lpi(s, 0, 1, rng_int(3, 7));
    sc_lpi(s, 1, 0, rng_int(3, 7));
    for (int k = 0; k < 3; k++) {
        int a = rng_int(0, nv - 1), b = rng_chance(0.02) ? a : rng_int(0, nv - 1);
        sc_lpi(s, a, b, rng_int(0, 7));
    }
    sc_tpi(s, 0, 1, rng_int(3, 7));
    sc_tpi(s, 2, 0, rng_int(3, 7));
    for (int k = 0; k < 3; k++) {
        int a = rng_int(0, 7), b = rng_int(0, 7), c = rng_int(0, 7);
        if (!rng_chance(0.03))
            while (b == a || c == a || c == b)
                b = rng_int(0, 7), c = rng_int(0, 7);
        sc_tpi(s, a, b, c);
    }
    sc_line_planes(s, 0, 1);
    sc_line_planes(s, 2, 0);
    sc_line_edge(s, 0, 1);
    sc_line_edge(s, 1, 0);
}

/* ---------------------------------------------------------------- nearly parallel */

/* A copy of vertex v with n_coords of its coordinates nudged by 1..3 ulps. */
static int nudged_vertex(scenario *s, int v, int n_coords)
{
    double x[3];
    memcpy(x, s->v[v], sizeof x);
    for (int k = 0; k < n_coords; k++) {
        int a = rng_int(0, 2);
        x[a] = nudge(x[a], rng_int(1, 3));
    }
    return sc_vertex(s, x);
}

/* q = p + (b - a) rounded: a line nearly parallel to any plane through a and b (exactly
 * parallel when the sum is exact). Falls back to a nudged p if the sum overflows. */
static int parallel_end(scenario *s, int p, int a, int b)
{
    double x[3];
    for (int k = 0; k < 3; k++) {
        x[k] = s->v[p][k] + (s->v[b][k] - s->v[a][k]);
        if (!isfinite(x[k]))
            x[k] = nudge(s->v[p][k], 4);
    }
    return sc_vertex(s, x);
}

/* Planes that are copies of P0 = (v0, v1, v2) nudged by a few ulps: TPIs of nearly
 * parallel planes, LPIs of lines nearly parallel to planes. P0 and P2 share the line
 * v0 v1 exactly (P2's third vertex is a nudged v2), so points on it are ordered too. */
void scenario_near_parallel(scenario *s, int regime)
{
    memset(s, 0, sizeof *s);
    s->cls = class_id("nearpar/", regime_names[regime]);
    bits_width = rng_chance(0.5) ? rng_int(1, 8) : rng_int(9, 40);
    for (int i = 0; i < 8; i++)
        random_vertex(s, regime);
    int w0 = nudged_vertex(s, 0, 1), w1 = nudged_vertex(s, 1, 2),
        w2 = nudged_vertex(s, 2, 1);
    int w2b = nudged_vertex(s, 2, 1), q1 = parallel_end(s, 3, 0, 1);
    int q2 = parallel_end(s, 6, 0, 2), q3 = nudged_vertex(s, parallel_end(s, 5, 1, 2), 1);
    int p0 = sc_plane(s, 0, 1, 2), p1 = sc_plane_rotated(s, w0, w1, w2);
    int p2 = sc_plane(s, 0, 1, w2b), p3 = sc_plane(s, 3, 4, 5), p4 = sc_plane(s, 5, 6, 7);
    sc_tpi(s, p0, p1, p3);
    sc_tpi(s, p0, p2, p3);
    sc_tpi(s, p2, p0, p4);
    sc_tpi(s, p1, p2, p4);
    sc_tpi(s, p3, p0, p4);
    sc_lpi(s, 3, q1, p0);
    sc_lpi(s, 3, q1, p1);
    sc_lpi(s, 6, q2, p2);
    sc_lpi(s, 5, q3, p0);
    sc_lpi(s, 0, 1, p1);
    sc_lpi(s, 0, 1, p3);
    sc_lpi(s, 1, 0, p4);
    sc_explicit(s, 0);
    sc_explicit(s, 1);
    sc_explicit(s, 3);
    sc_line_planes(s, p0, p2);
    sc_line_edge(s, 0, 1);
}

/* ---------------------------------------------------------------- exact lattices */

/* Lattices whose coordinates span a wide range of exponents (and any scenario with an
 * outlier) cost the exact stage far more, hence the smaller counts. */
const lattice lattices[] = {
    {"int", {0, 0, 0}, {0, 0, 0}, 8},
    {"far", {-20, -20, -20}, {1000000ll << 20, 1000000ll << 20, -(1000000ll << 20)}, 8},
    {"farmix", {-10, -10, -3}, {-(3000000ll << 10), 500000ll << 10, 70000000ll << 3}, 8},
    {"subnormal", {-1074, -1074, -1074}, {0, 0, 0}, 8},
    {"subnormal-off", {-1074, -1074, -1074}, {1ll << 40, -(1ll << 41), 0}, 8},
    {"huge", {985, 985, 985}, {0, 0, 0}, 2},
    {"mixed-axes", {116, -22, 985}, {0, 0, 0}, 2},
    {"mixed-axes2", {-997, 0, -1074}, {0, 1ll << 45, 0}, 2},
    {"tiny-huge-far", {-1000, 900, -30}, {0, 0, 1000000ll << 30}, 2},
};
const int lattice_count = (int)(sizeof lattices / sizeof lattices[0]);

typedef struct ivec {
    int64_t c[3];
} ivec;

static ivec iv_rand(int64_t range)
{
    ivec r;
    for (int k = 0; k < 3; k++)
        r.c[k] = rng_int(-(int)range, (int)range);
    return r;
}

/* a + s b */
static ivec iv_axpy(ivec a, int64_t s, ivec b)
{
    for (int k = 0; k < 3; k++)
        a.c[k] += s * b.c[k];
    return a;
}

static ivec iv_sub(ivec a, ivec b) { return iv_axpy(a, -1, b); }

static int lat_vertex(scenario *s, const lattice *L, ivec i)
{
    double x[3];
    for (int k = 0; k < 3; k++)
        x[k] = ldexp((double)(L->off[k] + i.c[k]), L->k[k]);
    return sc_vertex(s, x);
}

/* A vertex far off the lattice (1e300, 3.4e38, 1e-300, ...), used only where it cannot
 * spoil exactness: as a plane's or line's other vertex next to the point of interest. */
static int outlier_vertex(scenario *s)
{
    double x[3];
    draw_vertex(R_MIX, x);
    return sc_vertex(s, x);
}

/* A plane through lattice point X (vertex x), exactly, in one of three ways: X as a
 * vertex (the other two sometimes outliers); c = X + i(X - a) + j(X - b) (X inside the
 * span of a, b, c); X the centroid of a, b, c. */
static int plane_through(scenario *s, const lattice *L, ivec X, int x, int64_t range,
                         int kind)
{
    ivec a = iv_axpy(X, 1, iv_rand(range)), b = iv_axpy(X, 1, iv_rand(range));
    if (kind == 0) {
        bool far = rng_chance(0.3);
        int vb = far ? outlier_vertex(s) : lat_vertex(s, L, a);
        int vc = far ? outlier_vertex(s) : lat_vertex(s, L, b);
        return sc_plane_rotated(s, x, vb, vc);
    }
    if (kind == 1) {
        int i = rng_int(-2, 2), j = rng_int(-2, 2);
        if (i == 0 && j == 0)
            i = 1;
        ivec c = iv_axpy(iv_axpy(X, i, iv_sub(X, a)), j, iv_sub(X, b));
        return sc_plane_rotated(s, lat_vertex(s, L, a), lat_vertex(s, L, b),
                                lat_vertex(s, L, c));
    }
    ivec u = iv_sub(a, X), v = iv_sub(b, X), c = iv_axpy(iv_sub(X, u), -1, v);
    return sc_plane_rotated(s, lat_vertex(s, L, a), lat_vertex(s, L, b),
                            lat_vertex(s, L, c));
}

/* A line through X: X the midpoint, outside the segment, an endpoint (either end), or
 * an endpoint with an outlier as the other. Returns the two vertices in l[]. */
static void line_through(scenario *s, const lattice *L, ivec X, int x, int64_t range,
                         int l[2])
{
    ivec d = iv_rand(range);
    switch (rng_int(0, 4)) {
    case 0:
        l[0] = lat_vertex(s, L, iv_axpy(X, -1, d)),
        l[1] = lat_vertex(s, L, iv_axpy(X, 1, d));
        break;
    case 1:
        l[0] = lat_vertex(s, L, iv_axpy(X, 1, d)),
        l[1] = lat_vertex(s, L, iv_axpy(X, 3, d));
        break;
    case 2:
        l[0] = x, l[1] = lat_vertex(s, L, iv_axpy(X, 1, d));
        break;
    case 3:
        l[0] = lat_vertex(s, L, iv_axpy(X, 1, d)), l[1] = x;
        break;
    default:
        l[0] = x, l[1] = outlier_vertex(s);
        break;
    }
}

/* A plane through three random lattice points (rarely through anything of interest). */
static int lat_random_plane(scenario *s, const lattice *L, int64_t range)
{
    int a = lat_vertex(s, L, iv_rand(range));
    int b = lat_vertex(s, L, iv_rand(range));
    int c = lat_vertex(s, L, iv_rand(range));
    return sc_plane(s, a, b, c);
}

static int64_t lattice_range(void) { return rng_chance(0.3) ? 8 : 1024; }

/* One point X defined many ways: explicit; LPIs of lines through X with planes through
 * X; TPIs of three planes through X. All must be equal and on all those planes. A few
 * unrelated points (one lattice step away, an LPI and a TPI with a plane missing X)
 * keep the comparisons honest. */
void scenario_same(scenario *s, const lattice *L)
{
    int64_t range = lattice_range();
    ivec X = iv_rand(range);
    int pl[6], lines[4][2], x;
    memset(s, 0, sizeof *s);
    s->cls = class_id("same", "");
    x = lat_vertex(s, L, X);
    for (int k = 0; k < 6; k++)
        s->onpl[s->nonpl++] = pl[k] = plane_through(s, L, X, x, range, k % 3);
    for (int k = 0; k < 4; k++)
        line_through(s, L, X, x, range, lines[k]);
    s->group[s->ngroup++] = sc_explicit(s, x);
    for (int k = 0; k < 4; k++)
        s->group[s->ngroup++] = sc_lpi(s, lines[k][0], lines[k][1], pl[rng_int(0, 5)]);
    for (int k = 0; k < 4; k++) {
        int a = rng_int(0, 5), b = (a + rng_int(1, 5)) % 6, c = rng_int(0, 5);
        while (c == a || c == b)
            c = rng_int(0, 5);
        s->group[s->ngroup++] = sc_tpi(s, pl[a], pl[b], pl[c]);
    }
    s->group_equal = true;
    ivec step = {{0, 0, 0}};
    step.c[rng_int(0, 2)] = rng_chance(0.5) ? 1 : -1;
    int other = lat_random_plane(s, L, range);
    sc_explicit(s, lat_vertex(s, L, iv_axpy(X, 1, step)));
    sc_lpi(s, lines[0][0], lines[0][1], other);
    sc_tpi(s, pl[0], other, pl[1]);
}

/* Points on one line L = e0 e1: lattice points, LPIs of L (given by two different vertex
 * pairs) with other planes, TPIs of two planes through L with a third. LPI(L, Q) and
 * TPI(P, P', Q) are the same point; order along L by planes and by edge. */
void scenario_line(scenario *s, const lattice *L)
{
    int64_t range = lattice_range();
    ivec e0 = iv_rand(range), d = iv_rand(range / 2 + 1);
    ivec f0 = iv_axpy(e0, rng_int(-3, 3), d), f1 = iv_axpy(e0, rng_int(2, 4), d);
    int ve0, ve1, vf0, vf1, p[4], q[4];
    memset(s, 0, sizeof *s);
    s->cls = class_id("line", "");
    ve0 = lat_vertex(s, L, e0), ve1 = lat_vertex(s, L, iv_axpy(e0, 1, d));
    vf0 = lat_vertex(s, L, f0), vf1 = lat_vertex(s, L, f1);
    p[0] = sc_plane(s, ve0, ve1, lat_vertex(s, L, iv_rand(range)));
    p[1] = sc_plane(s, ve1, ve0, lat_vertex(s, L, iv_rand(range)));
    p[2] = sc_plane(s, vf0, lat_vertex(s, L, iv_rand(range)), vf1);
    p[3] =
        sc_plane(s, rng_chance(0.3) ? outlier_vertex(s) : lat_vertex(s, L, iv_rand(range)),
                 vf1, ve0);
    for (int k = 0; k < 3; k++)
        q[k] = lat_random_plane(s, L, range);
    int far = outlier_vertex(s);
    q[3] = sc_plane_rotated(s, vf0, far, lat_vertex(s, L, iv_rand(range)));
    for (int k = 0; k < 4; k++)
        s->onpl[s->nonpl++] = p[k];
    /* Every point of the scenario is on L: all form the group. */
    sc_explicit(s, ve0);
    sc_explicit(s, ve1);
    sc_explicit(s, vf0);
    sc_explicit(s, vf1);
    sc_lpi(s, ve0, ve1, q[0]);
    sc_lpi(s, vf0, vf1, q[0]);
    sc_lpi(s, vf1, ve0, q[1]);
    sc_lpi(s, ve1, vf0, q[2]);
    sc_lpi(s, ve0, ve1, q[3]);
    sc_tpi(s, p[0], p[1], q[0]);
    sc_tpi(s, p[2], q[1], p[0]);
    sc_tpi(s, q[2], p[3], p[1]);
    sc_tpi(s, p[1], p[2], q[3]);
    for (int k = 0; k < s->npt; k++)
        s->group[s->ngroup++] = k;
    sc_line_planes(s, p[0], p[1]);
    sc_line_planes(s, p[2], p[0]);
    sc_line_planes(s, p[1], p[3]);
    sc_line_planes(s, p[3], p[2]);
    sc_line_edge(s, ve0, ve1);
    sc_line_edge(s, vf1, vf0);
}

/* Exactly degenerate configurations (constructors must say no) next to valid ones:
 * a line parallel to a plane and a line inside it (LPI), parallel planes and three planes
 * through one line (TPI). The +ulp runs turn them into near-degeneracies. */
void scenario_parallel(scenario *s, const lattice *L)
{
    int64_t range = lattice_range();
    ivec a = iv_rand(range), b = iv_rand(range), c = iv_rand(range), t = iv_rand(range);
    ivec p = iv_rand(range), e0 = iv_rand(range), e1 = iv_rand(range);
    int i = rng_int(-2, 2), j = rng_int(1, 2), va, vb, vc;
    memset(s, 0, sizeof *s);
    s->cls = class_id("par", "");
    va = lat_vertex(s, L, a), vb = lat_vertex(s, L, b), vc = lat_vertex(s, L, c);
    int P = sc_plane(s, va, vb, vc);
    int Pt =
        sc_plane(s, lat_vertex(s, L, iv_axpy(a, 1, t)), lat_vertex(s, L, iv_axpy(b, 1, t)),
                 lat_vertex(s, L, iv_axpy(c, 1, t)));
    int vp = lat_vertex(s, L, p);
    int vq = lat_vertex(s, L, iv_axpy(iv_axpy(p, i, iv_sub(b, a)), j, iv_sub(c, a)));
    int vin0 = lat_vertex(s, L, iv_axpy(a, j, iv_sub(c, b)));
    int vin1 = lat_vertex(s, L, iv_axpy(iv_axpy(b, i, iv_sub(c, a)), -j, iv_sub(b, a)));
    int ve0 = lat_vertex(s, L, e0), ve1 = lat_vertex(s, L, e1);
    int R1 = sc_plane(s, ve0, ve1, lat_vertex(s, L, iv_rand(range)));
    int R2 = sc_plane(s, lat_vertex(s, L, iv_rand(range)), ve1, ve0);
    int R3 = sc_plane(s, ve1, lat_vertex(s, L, iv_axpy(e0, 2, iv_sub(e1, e0))),
                      lat_vertex(s, L, iv_rand(range)));
    int Q = lat_random_plane(s, L, range);
    sc_lpi(s, vp, vq, P);
    sc_lpi(s, vq, vp, Pt);
    sc_lpi(s, vp, vq, Q);
    sc_lpi(s, vin0, vin1, P);
    sc_lpi(s, vin0, vin1, Q);
    sc_lpi(s, ve0, ve1, R3);
    sc_tpi(s, P, Pt, Q);
    sc_tpi(s, R1, R2, R3);
    sc_tpi(s, R1, R2, Q);
    sc_tpi(s, P, R1, Q);
    sc_tpi(s, Pt, R2, R3);
    sc_explicit(s, va);
    sc_explicit(s, vp);
    sc_line_planes(s, R1, R2);
    sc_line_planes(s, R3, R1);
    sc_line_edge(s, ve0, ve1);
}

/* ---------------------------------------------------------------- axis-aligned grids */

/* A grid coordinate: a multiple of 1/4 in [-64, 64] (a plate's holes and bars). */
static double grid_coord(void)
{
    return rng_int(-256, 256) / 4.0;
}

/* A vertex on the grid with coordinate k set to c. */
static int grid_vertex_at(scenario *s, int k, double c)
{
    double x[3] = {grid_coord(), grid_coord(), grid_coord()};
    x[k] = c;
    return sc_vertex(s, x);
}

/* What a plate with a grid of holes is made of: planes x_k = c (three vertices sharing
 * coordinate k; now and then collinear, so that the constructors must say no), lines
 * that are translates of one another along the plane (the holes' wall diagonals), and
 * their LPIs, which lie on one line of the plane: exact zeros in the orientations, on
 * inputs short enough for 128-bit integers once the plane's normal cancels (EVAL(lpi)).
 * A second aligned plane, a general one and TPIs through the aligned ones besides. */
void scenario_axis_grid(scenario *s)
{
    int k = rng_int(0, 2), i = (k + 1) % 3, j = (k + 2) % 3, pl[3], lines[4][2];
    double c = grid_coord(), d[3], t[3] = {0, 0, 0};
    memset(s, 0, sizeof *s);
    s->cls = class_id("axisgrid", "");
    int a = grid_vertex_at(s, k, c), b = grid_vertex_at(s, k, c);
    int e = rng_chance(0.05) ? a : grid_vertex_at(s, k, c);
    pl[0] = sc_plane_rotated(s, a, b, e);
    pl[1] = sc_plane_rotated(s, grid_vertex_at(s, i, c), grid_vertex_at(s, i, c),
                             grid_vertex_at(s, i, c));
    pl[2] = sc_plane(s, random_vertex(s, R_INT), random_vertex(s, R_INT),
                     grid_vertex_at(s, k, c));
    for (int m = 0; m < 3; m++)
        d[m] = rng_int(-8, 8) / 4.0;
    if (d[k] == 0)
        d[k] = 0.75;
    t[i] = rng_int(-8, 8) / 4.0;
    t[j] = rng_int(-8, 8) / 4.0;
    double base[3] = {grid_coord() / 2, grid_coord() / 2, grid_coord() / 2};
    for (int n = 0; n < 4; n++) {
        double p0[3], p1[3];
        for (int m = 0; m < 3; m++) {
            p0[m] = base[m] + n * t[m];
            p1[m] = p0[m] + d[m];
        }
        lines[n][0] = sc_vertex(s, p0);
        lines[n][1] = sc_vertex(s, p1);
    }
    s->onpl[s->nonpl++] = pl[0];
    for (int n = 0; n < 4; n++)
        s->group[s->ngroup++] = sc_lpi(s, lines[n][rng_int(0, 1)], lines[n][0] ^ lines[n][1] ^
                                       lines[n][rng_int(0, 1)], pl[0]);
    s->group[s->ngroup++] = sc_explicit(s, a);
    s->group[s->ngroup++] = sc_explicit(s, b);
    sc_lpi(s, lines[0][0], lines[0][1], pl[1]);
    sc_lpi(s, lines[1][0], lines[2][1], pl[2]);
    sc_tpi(s, pl[0], pl[1], pl[2]);
}
