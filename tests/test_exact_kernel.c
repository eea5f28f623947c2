/*
 * Tests of the exact plane-based kernel (src/exact/kernel.h) against the independent
 * exact reference of exact_reference.h (GMP, from the geometric definitions: an LPI by
 * solving for the line parameter, a TPI by rational Gaussian elimination, each predicate
 * as the sign of its defining expression on exact coordinates), on the scenarios of
 * exact_scenarios.h. This file holds the checks of each kernel answer against the
 * reference, the tables of counts, and a few direct tests (bit helpers, orient3d of
 * vertices, LPIs equal by projection).
 *
 * Every case checks three things: the combined predicate equals the reference; the exact
 * stage equals the reference (on every case, not only where the filter gives up); the
 * filtered stage returns MCI_UNCERTAIN or the reference sign. Constructors' return
 * values and the certified error bounds of the cached normals and offsets
 * (|v - exact| <= e) are checked as well, since every filter relies on them.
 *
 * Cases come in scenarios: a few input vertices, planes through them, explicit, LPI and
 * TPI points, and the predicates over all (or sampled) combinations of those, so every
 * kind of point appears in every predicate slot. Scenario classes:
 *   random/REGIME   vertices drawn from one coordinate regime (draw_coord)
 *   nearpar/REGIME  nearly parallel planes and lines (copies nudged by a few ulps)
 *   same, line, par adversarial scenarios on exact lattices: one point defined in many
 *                   ways; points on a common line; exactly parallel and singular
 *                   configurations. Each is followed by "+ulp" runs with an input
 *                   coordinate moved by one ulp.
 * MCSG_TEST_SCALE (default 1, 0.5 under the sanitizers) multiplies the number of
 * scenarios; MCSG_TEST_SEED sets the random seed. The tables at the end count the cases and the filter's decisions.
 */
#include "base/parallel.h"
#include "exact/big.h"
#include "exact/exact_cache.h"
#include "exact/kernel.h"
#include "exact_reference.h"
#include "exact_scenarios.h"
#include "testlib.h"

#include <float.h>
#include <gmp.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_PRINTED 12     /* mismatches printed in full; all are counted */
#define NONE        (-100) /* no such stage in a result triple; no reference result */

/* ---------------------------------------------------------------- classes and counts */

enum {
    PR_ORIENT3D,
    PR_CMP,
    PR_LEX,
    PR_EQ,
    PR_ORIENT2D,
    PR_LINEDIR,
    PR_ORDER_PL,
    PR_ORDER_EDGE,
    PR_LPI,
    PR_TPI,
    PR_BOUNDS,
    PR_COUNT
};
static const char *const pred_names[PR_COUNT] = {
    "orient3d",  "compare_coord", "compare_lex",    "points_equal",
    "orient2d",  "line_dir_sign", "order_plane_ln", "order_edge_ln",
    "point_lpi", "point_tpi",     "cached_bounds"};

typedef struct pstat {
    long calls, zero;   /* cases, and those whose reference result is 0 */
    long filt, decided; /* cases with a filtered stage, and those it decided */
    long decided_zero;  /* ... decided although the reference is 0 */
    long mismatches;
} pstat;

static pstat stats[MAX_CLASSES][PR_COUNT];
static long class_scenarios[MAX_CLASSES];
static double class_seconds[MAX_CLASSES];

/* ---------------------------------------------------------------- workspace */

/* Kernel objects and their references for the scenario being run. Kept for the whole
 * run so that the GMP numbers are allocated once. */
static struct {
    mci_plane kpl[MAXPL];
    mci_point kpt[MAXPT];
    bool ok[MAXPT]; /* both kernel and reference constructed the point */
    ref_plane rpl[MAXPL];
    ref_point rpt[MAXPT];
    ref_point rv[MAXV]; /* the input vertices */
    ref_vec rx[MAXPT];  /* rational coordinates */
    mpq_t rw[MAXPT];    /* W as the header defines it: n.u (LPI), det (TPI) */
    /* The scenario's lines (query.line): whether each exists, and which points lie on
     * it, decided once per point rather than once per pair the point is in. */
    ref_line rline[MAXLINES];
    bool line_ok[MAXLINES], on_line[MAXLINES][MAXPT];
} ws;

static void ws_init(void)
{
    for (int i = 0; i < MAXPL; i++)
        ref_plane_init(&ws.rpl[i]);
    for (int i = 0; i < MAXPT; i++) {
        ref_point_init(&ws.rpt[i]);
        ref_vec_init(&ws.rx[i]);
        mpq_init(ws.rw[i]);
    }
    for (int i = 0; i < MAXV; i++)
        ref_point_init(&ws.rv[i]);
    for (int i = 0; i < MAXLINES; i++)
        ref_line_init(&ws.rline[i]);
}

static void ws_clear(void)
{
    for (int i = 0; i < MAXPL; i++)
        ref_plane_clear(&ws.rpl[i]);
    for (int i = 0; i < MAXPT; i++) {
        ref_point_clear(&ws.rpt[i]);
        ref_vec_clear(&ws.rx[i]);
        mpq_clear(ws.rw[i]);
    }
    for (int i = 0; i < MAXV; i++)
        ref_point_clear(&ws.rv[i]);
    for (int i = 0; i < MAXLINES; i++)
        ref_line_clear(&ws.rline[i]);
}

/* ---------------------------------------------------------------- reporting */

typedef struct query {
    int pred;
    int pt[3], pl[2], lv[2], axis;
    int line; /* the line orders: line_planes[line], or line_edges[line - MAXLP] */
} query;

static const char *vstr(const double *x)
{
    static char buf[8][96];
    static int slot;
    char *out = buf[slot++ & 7];
    snprintf(out, sizeof buf[0], "{%a, %a, %a}", x[0], x[1], x[2]);
    return out;
}

static void print_plane(const scenario *s, const char *label, int p)
{
    fprintf(stderr, "    %s plane %s %s %s\n", label, vstr(s->v[s->plv[p][0]]),
            vstr(s->v[s->plv[p][1]]), vstr(s->v[s->plv[p][2]]));
}

static void print_point(const scenario *s, const char *label, int i)
{
    const point_def *d = &s->pt[i];
    static const char *const kinds[] = {"explicit", "LPI", "TPI"};
    fprintf(stderr, "  %s = %s", label, kinds[d->kind]);
    if (d->kind == MCI_POINT_EXPLICIT)
        fprintf(stderr, " %s\n", vstr(s->v[d->v[0]]));
    if (d->kind == MCI_POINT_LPI) {
        fprintf(stderr, " line %s %s\n", vstr(s->v[d->v[0]]), vstr(s->v[d->v[1]]));
        print_plane(s, "", d->pl[0]);
    }
    if (d->kind == MCI_POINT_TPI) {
        fputc('\n', stderr);
        for (int k = 0; k < 3; k++)
            print_plane(s, "", d->pl[k]);
    }
}

static int operand_points(int pred)
{
    static const int n[PR_COUNT] = {1, 2, 2, 2, 3, 0, 2, 2, 1, 1, 0};
    return n[pred];
}

static int operand_planes(int pred)
{
    return pred == PR_ORIENT3D ? 1 : pred == PR_LINEDIR || pred == PR_ORDER_PL ? 2 : 0;
}

static void print_query(const scenario *s, const query *q)
{
    static const char *const names[] = {"A", "B", "C"};
    for (int k = 0; k < operand_points(q->pred); k++)
        print_point(s, names[k], q->pt[k]);
    for (int k = 0; k < operand_planes(q->pred); k++)
        print_plane(s, k ? "P2 =" : "P1 =", q->pl[k]);
    if (q->pred == PR_ORDER_EDGE)
        fprintf(stderr, "  edge line %s %s\n", vstr(s->v[q->lv[0]]), vstr(s->v[q->lv[1]]));
}

static int printed_mismatches;

static void mismatch(const scenario *s, const query *q, const int got[3], int ref)
{
    char g[3][8];
    test_failures++;
    stats[s->cls][q->pred].mismatches++;
    if (printed_mismatches++ >= MAX_PRINTED)
        return;
    for (int k = 0; k < 3; k++) {
        if (got[k] == NONE)
            snprintf(g[k], sizeof g[k], "-");
        else
            snprintf(g[k], sizeof g[k], "%d", got[k]);
    }
    fprintf(stderr,
            "MISMATCH %s axis %d (%s): combined %s, exact %s, filtered %s, "
            "reference %d\n",
            pred_names[q->pred], q->axis, class_names[s->cls], g[0], g[1], g[2], ref);
    print_query(s, q);
}

/* Counts a case and checks its three stages against the reference. */
static void check_case(const scenario *s, const query *q, const int got[3], int ref)
{
    pstat *st = &stats[s->cls][q->pred];
    bool bad = (got[0] != NONE && got[0] != ref) || (got[1] != NONE && got[1] != ref) ||
               (got[2] != NONE && got[2] != MCI_UNCERTAIN && got[2] != ref);
    test_checks++;
    st->calls++;
    st->zero += ref == 0;
    if (got[2] != NONE) {
        st->filt++;
        if (got[2] != MCI_UNCERTAIN) {
            st->decided++;
            st->decided_zero += ref == 0;
        }
    }
    if (bad)
        mismatch(s, q, got, ref);
}

/* ---------------------------------------------------------------- cached bounds */

static long uninformative_bounds; /* cached values with bound +inf or NaN */

/* |f.v - x| <= f.e. A bound of +inf or NaN (after an overflow) says nothing and holds
 * trivially: every filter comparison |v| > e fails on it, so the exact stage decides. */
static bool fv_holds(mci_fv f, mpq_srcptr x)
{
    if (isnan(f.e) || (isinf(f.e) && f.e > 0)) {
        uninformative_bounds++;
        return true;
    }
    if (!isfinite(f.v) || !isfinite(f.e) || f.e < 0)
        return false;
    return ref_within(f.v, f.e, x);
}

static void print_bound(const char *what, int k, mci_fv f, mpq_srcptr x)
{
    fprintf(stderr, "  cached %s[%d] = %a +- %a, exact %a\n", what, k, f.v, f.e,
            mpq_get_d(x));
}

/* The cached normal's bounds hold; with `print`, shows those that do not. */
static bool plane_bounds_ok(int p, bool print)
{
    bool ok = true;
    for (int k = 0; k < 3; k++)
        if (!fv_holds(ws.kpl[p].n[k], ws.rpl[p].n.c[k])) {
            ok = false;
            if (print)
                print_bound("normal", k, ws.kpl[p].n[k], ws.rpl[p].n.c[k]);
        }
    return ok;
}

static void check_plane_bounds(const scenario *s, int p)
{
    query q = {PR_BOUNDS, {0, 0, 0}, {p, p}, {0, 0}, 0, 0};
    int got[3] = {plane_bounds_ok(p, false), NONE, NONE};
    check_case(s, &q, got, 1);
    if (!got[0] && printed_mismatches <= MAX_PRINTED) {
        print_plane(s, "of", p);
        plane_bounds_ok(p, true);
    }
}

/* The stored (y, w) approximate sign(W) * (Y, W) with Y = W (X - base) (that is the
 * header's Y: u n.(a - p) for an LPI, the Cramer numerators for a TPI), and w_sign = 1. */
static bool point_bounds_ok(int i, bool print)
{
    const mci_point *p = &ws.kpt[i];
    bool ok = p->w_sign == 1;
    mpq_t w, y, base;
    mpq_inits(w, y, base, NULL);
    mpq_abs(w, ws.rw[i]);
    if (print)
        fprintf(stderr, "  w_sign %d\n", p->w_sign);
    if (!fv_holds(p->w, w)) {
        ok = false;
        if (print)
            print_bound("w", 0, p->w, w);
    }
    for (int k = 0; k < 3; k++) {
        mpq_set_d(base, p->v[0][k]);
        mpq_sub(y, ws.rx[i].c[k], base);
        mpq_mul(y, y, w);
        if (!fv_holds(p->y[k], y)) {
            ok = false;
            if (print)
                print_bound("y", k, p->y[k], y);
        }
    }
    mpq_clears(w, y, base, NULL);
    return ok;
}

/* The double-word values the exact cache keeps (mci_point_dd_values) hold the exact
 * coordinates: |x - (hi + lo)| <= e. */
static long approx_points, approx_tight;

static void check_point_approx(const scenario *s, int i)
{
    double approx[3][3];
    mpq_t d, e;
    if (!mci_point_dd_values(&ws.kpt[i], approx))
        return;
    approx_points++;
    mpq_inits(d, e, NULL);
    for (int k = 0; k < 3; k++) {
        mpq_set_d(d, approx[k][0]);
        mpq_set_d(e, approx[k][1]);
        mpq_add(d, d, e);
        mpq_sub(d, ws.rx[i].c[k], d);
        mpq_abs(d, d);
        mpq_set_d(e, approx[k][2]);
        CHECK_MSG(mpq_cmp(d, e) <= 0, "%s: point %d coordinate %d: approximation %.17g + %.17g "
                  "off by more than %.3g", class_names[s->cls], i, k, approx[k][0], approx[k][1],
                  approx[k][2]);
        approx_tight += approx[k][2] <= fabs(approx[k][0]) * 0x1p-100;
    }
    mpq_clears(d, e, NULL);
}

static void check_point_bounds(const scenario *s, int i)
{
    query q = {PR_BOUNDS, {i, 0, 0}, {0, 0}, {0, 0}, 0, 0};
    int got[3] = {point_bounds_ok(i, false), NONE, NONE};
    check_case(s, &q, got, 1);
    if (!got[0] && printed_mismatches <= MAX_PRINTED) {
        print_point(s, "of", i);
        point_bounds_ok(i, true);
    }
}

/* ---------------------------------------------------------------- point boxes */

static long box_points, box_infinite, box_tight; /* mci_point_bounds of implicit points */
static int box_printed;

/* lo <= x (upper: x <= hi), exactly. An infinite bound on its own side always holds. */
static bool box_bound_holds(double b, mpq_srcptr x, bool upper)
{
    int c;
    if (isinf(b) && (b > 0) == upper)
        return true;
    if (!isfinite(b))
        return false;
    c = ref_cmp_d(b, x);
    return upper ? c >= 0 : c <= 0;
}

/* The box of mci_point_bounds contains the exact point; counts infinite and tight boxes
 * (tight: hi - lo <= 1e-10 (|lo| + |hi|) + 1e-300 on every axis). */
static void check_point_box(const scenario *s, int i)
{
    const mci_point *p = &ws.kpt[i];
    double lo[3], hi[3];
    bool infinite = false, tight = true;
    mci_point_bounds(p, lo, hi);
    for (int k = 0; k < 3; k++) {
        mpq_srcptr x = ws.rx[i].c[k];
        bool ok = box_bound_holds(lo[k], x, false) && box_bound_holds(hi[k], x, true);
        CHECK_MSG(ok, "mci_point_bounds (%s) axis %d: [%a, %a] misses exact %a",
                  class_names[s->cls], k, lo[k], hi[k], mpq_get_d(x));
        if (!ok && box_printed++ < MAX_PRINTED) {
            print_point(s, "of", i);
            fprintf(stderr, "  base %a, y = %a +- %a, w = %a +- %a; exact - lo = %a, "
                    "exact - hi = %a\n", p->v[0][k], p->y[k].v, p->y[k].e, p->w.v,
                    p->w.e, ref_gap(x, lo[k]), ref_gap(x, hi[k]));
        }
        infinite |= isinf(lo[k]) || isinf(hi[k]);
        tight &= hi[k] - lo[k] <= 1e-10 * (fabs(lo[k]) + fabs(hi[k])) + 1e-300;
    }
    if (p->kind != MCI_POINT_EXPLICIT) {
        box_points++;
        box_infinite += infinite;
        box_tight += tight && !infinite;
    }
}

/* ---------------------------------------------------------------- correct rounding */

static long rounded_coordinates;

/* mci_point_round gives the nearest double on every axis; mci_point_approx is finite. */
/* The double-double rounding stage on its own, from the approximation and from a guess
 * two steps off (it must walk to the nearest double or give up). */
static long dd_rounded, dd_round_tries;

static void check_point_round_dd(const scenario *s, int i, const double approx[3])
{
    for (int shift = 0; shift < 2; shift++) {
        double guess[3], r[3];
        unsigned left;
        for (int k = 0; k < 3; k++)
            guess[k] = shift ? nextafter(nextafter(approx[k], INFINITY), INFINITY) : approx[k];
        left = mci_point_round_dd(&ws.kpt[i], 7, guess, r);
        for (int k = 0; k < 3; k++) {
            if (fabs(mpq_get_d(ws.rx[i].c[k])) > 0x1p1020)
                continue;
            dd_round_tries++;
            if ((left >> k) & 1)
                continue;
            dd_rounded++;
            CHECK_MSG(ref_is_nearest_double(r[k], ws.rx[i].c[k]),
                      "mci_point_round_dd (%s) axis %d: %a, exact %a", class_names[s->cls],
                      k, r[k], mpq_get_d(ws.rx[i].c[k]));
        }
    }
}

static void check_point_round(const scenario *s, int i)
{
    double r[3], a[3];
    mci_point_round(&ws.kpt[i], r);
    mci_point_approx(&ws.kpt[i], a);
    for (int k = 0; k < 3; k++) {
        if (fabs(mpq_get_d(ws.rx[i].c[k])) > 0x1p1020)
            continue; /* near or beyond the double range: not a point of any mesh */
        CHECK_MSG(ref_is_nearest_double(r[k], ws.rx[i].c[k]),
                  "mci_point_round (%s) axis %d: %a, exact %a", class_names[s->cls], k, r[k],
                  mpq_get_d(ws.rx[i].c[k]));
        CHECK_MSG(isfinite(a[k]), "mci_point_approx (%s) axis %d: %a", class_names[s->cls],
                  k, a[k]);
        rounded_coordinates++;
    }
    check_point_round_dd(s, i, a);
}

/* ---------------------------------------------------------------- building a scenario */

static void build_point(const scenario *s, int i)
{
    const point_def *d = &s->pt[i];
    mci_point *kp = &ws.kpt[i];
    bool kok = true, rok = true;
    if (d->kind == MCI_POINT_EXPLICIT) {
        mci_point_explicit(kp, s->v[d->v[0]]);
        ref_vec_set_d(&ws.rx[i], s->v[d->v[0]]);
    } else if (d->kind == MCI_POINT_LPI) {
        kok = mci_point_lpi(kp, s->v[d->v[0]], s->v[d->v[1]], &ws.kpl[d->pl[0]]);
        rok = ref_lpi(&ws.rx[i], ws.rw[i], s->v[d->v[0]], s->v[d->v[1]], &ws.rpl[d->pl[0]]);
    } else {
        kok = mci_point_tpi(kp, &ws.kpl[d->pl[0]], &ws.kpl[d->pl[1]], &ws.kpl[d->pl[2]]);
        rok = ref_tpi(&ws.rx[i], ws.rw[i], &ws.rpl[d->pl[0]], &ws.rpl[d->pl[1]],
                      &ws.rpl[d->pl[2]]);
    }
    if (d->kind != MCI_POINT_EXPLICIT) {
        query q = {
            d->kind == MCI_POINT_LPI ? PR_LPI : PR_TPI, {i, 0, 0}, {0, 0}, {0, 0}, 0, 0};
        int got[3] = {kok, NONE, NONE};
        check_case(s, &q, got, rok);
    }
    ws.ok[i] = kok && rok;
    if (!ws.ok[i])
        return;
    ref_point_set_vec(&ws.rpt[i], &ws.rx[i]);
    if (d->kind != MCI_POINT_EXPLICIT)
        check_point_bounds(s, i);
    check_point_box(s, i);
    check_point_round(s, i);
    check_point_approx(s, i);
}

static void build(const scenario *s)
{
    for (int i = 0; i < s->nv; i++)
        ref_point_set_d(&ws.rv[i], s->v[i]);
    for (int p = 0; p < s->npl; p++) {
        const double *a = s->v[s->plv[p][0]], *b = s->v[s->plv[p][1]],
                     *c = s->v[s->plv[p][2]];
        mci_plane_init(&ws.kpl[p], a, b, c);
        ref_plane_set(&ws.rpl[p], a, b, c);
        check_plane_bounds(s, p);
    }
    for (int i = 0; i < s->npt; i++)
        build_point(s, i);
}

/* The scenario's lines in the reference, and which of the usable points lie on each:
 * decided here once per point, as queries_pairs orders every pair on every line. */
static void build_lines(const scenario *s, const int *idx, int n)
{
    for (int l = 0; l < s->nlp; l++) {
        const ref_plane *p1 = &ws.rpl[s->line_planes[l][0]];
        const ref_plane *p2 = &ws.rpl[s->line_planes[l][1]];
        ws.line_ok[l] = ref_line_set_planes(&ws.rline[l], p1, p2);
        for (int i = 0; i < n; i++)
            ws.on_line[l][idx[i]] = ref_on_planes(&ws.rpt[idx[i]], p1, p2);
    }
    for (int l = 0; l < s->nle; l++) {
        const ref_point *l0 = &ws.rv[s->line_edges[l][0]], *l1 = &ws.rv[s->line_edges[l][1]];
        ws.line_ok[MAXLP + l] = ref_line_set_points(&ws.rline[MAXLP + l], l0, l1);
        for (int i = 0; i < n; i++)
            ws.on_line[MAXLP + l][idx[i]] = ref_on_line(&ws.rpt[idx[i]], l0, l1);
    }
}

/* ---------------------------------------------------------------- running queries */

static void kernel_eval(const scenario *s, const query *q, int got[3])
{
    const mci_point *a = &ws.kpt[q->pt[0]], *b = &ws.kpt[q->pt[1]], *c = &ws.kpt[q->pt[2]];
    const mci_plane *p1 = &ws.kpl[q->pl[0]], *p2 = &ws.kpl[q->pl[1]];
    int ax = q->axis;
    got[0] = got[1] = got[2] = NONE;
    switch (q->pred) {
    case PR_ORIENT3D:
        got[0] = mci_orient3d(a, p1);
        got[1] = mci_orient3d_exact(a, p1);
        got[2] = mci_orient3d_filtered(a, p1);
        break;
    case PR_CMP:
        got[0] = mci_compare_coord(a, b, ax);
        got[1] = mci_compare_coord_exact(a, b, ax);
        got[2] = mci_compare_coord_filtered(a, b, ax);
        break;
    case PR_LEX:
        got[0] = mci_compare_lex(a, b);
        break;
    case PR_EQ:
        got[0] = mci_points_equal(a, b);
        break;
    case PR_ORIENT2D:
        got[0] = mci_orient2d_projected(a, b, c, ax);
        got[1] = mci_orient2d_projected_exact(a, b, c, ax);
        got[2] = mci_orient2d_projected_filtered(a, b, c, ax);
        break;
    case PR_LINEDIR:
        got[1] = mci_line_direction_sign_exact(p1, p2, ax);
        got[2] = mci_line_direction_sign_filtered(p1, p2, ax);
        break;
    case PR_ORDER_PL:
        got[0] = mci_order_on_plane_line(a, b, p1, p2);
        break;
    default: /* PR_ORDER_EDGE */
        got[0] = mci_order_on_edge_line(a, b, s->v[q->lv[0]], s->v[q->lv[1]]);
        break;
    }
}

/* The order of the query's points along its line, or NONE unless the line exists and
 * both points lie on it. */
static int ref_line_order(const query *q)
{
    int a = q->pt[0], b = q->pt[1], l = q->line;
    if (!ws.line_ok[l] || !ws.on_line[l][a] || !ws.on_line[l][b])
        return NONE;
    return ref_order_on_line(&ws.rpt[a], &ws.rpt[b], &ws.rline[l]);
}

/* The reference result, or NONE where the predicate's precondition does not hold. */
static int ref_eval(const query *q)
{
    const ref_point *a = &ws.rpt[q->pt[0]], *b = &ws.rpt[q->pt[1]], *c = &ws.rpt[q->pt[2]];
    const ref_plane *p1 = &ws.rpl[q->pl[0]], *p2 = &ws.rpl[q->pl[1]];
    switch (q->pred) {
    case PR_ORIENT3D:
        return ref_orient3d(a, p1);
    case PR_CMP:
        return ref_compare_coord(a, b, q->axis);
    case PR_LEX:
        return ref_compare_lex(a, b);
    case PR_EQ:
        return ref_compare_lex(a, b) == 0;
    case PR_ORIENT2D:
        return ref_orient2d(a, b, c, q->axis);
    case PR_LINEDIR:
        return ref_line_direction_sign(p1, p2, q->axis);
    default: /* PR_ORDER_PL, PR_ORDER_EDGE */
        return ref_line_order(q);
    }
}

/* The double-double stage of orient2d, checked on every case: a sign it gives must be
 * the reference's. Counted where the first filter gave up (where it is used). */
static long dd_after_filter, dd_decided;

static long box_filter_cases, box_filter_decided;

/* The box filter (mci_orient2d_projected_quick, inline) alone: a sign it gives must be
 * the reference's, and it never answers 0. */
static void check_orient2d_boxes(const scenario *s, const query *q, int ref)
{
    const mci_point *a = &ws.kpt[q->pt[0]], *b = &ws.kpt[q->pt[1]], *c = &ws.kpt[q->pt[2]];
    int got = mci_orient2d_projected_quick(a, b, c, q->axis);
    CHECK_MSG(got == MCI_UNCERTAIN || (got != 0 && got == ref),
              "mci_orient2d_projected_quick (%s): %d, reference %d", class_names[s->cls], got,
              ref);
    box_filter_cases++;
    box_filter_decided += got != MCI_UNCERTAIN;
}

/* The stages that compute no implicit point (mci_orient2d_projected_cheap): a sign
 * they give, 0 included, must be the reference's. */
static long cheap_cases, cheap_decided;

static void check_orient2d_cheap(const scenario *s, const query *q, int ref)
{
    const mci_point *a = &ws.kpt[q->pt[0]], *b = &ws.kpt[q->pt[1]], *c = &ws.kpt[q->pt[2]];
    int got = mci_orient2d_projected_cheap(a, b, c, q->axis);
    CHECK_MSG(got == MCI_UNCERTAIN || got == ref,
              "mci_orient2d_projected_cheap (%s): %d, reference %d", class_names[s->cls], got,
              ref);
    cheap_cases++;
    cheap_decided += got != MCI_UNCERTAIN;
}

static void check_orient2d_dd(const scenario *s, const query *q, int filtered, int ref)
{
    const mci_point *a = &ws.kpt[q->pt[0]], *b = &ws.kpt[q->pt[1]], *c = &ws.kpt[q->pt[2]];
    int got = mci_orient2d_projected_dd(a, b, c, q->axis);
    CHECK_MSG(got == MCI_UNCERTAIN || got == ref,
              "mci_orient2d_projected_dd (%s): %d, reference %d", class_names[s->cls], got,
              ref);
    if (filtered == MCI_UNCERTAIN) {
        dd_after_filter++;
        dd_decided += got != MCI_UNCERTAIN;
    }
}

/* The vertex forms of orient3d (an input vertex against a plane, and against the plane
 * of three input vertices): full predicate equal to the reference, filter never wrong. */
static long vertex_filter_cases, vertex_filter_decided, vertex_dd_cases, vertex_dd_decided;

/* The double-double stage between them: a sign it gives must be the reference's. */
static void check_orient3d_vertex_dd(const scenario *s, const mci_plane *p, const double *x,
                                     int filtered, int ref)
{
    int got = mci_orient3d_vertices_dd(p->a, p->b, p->c, x);
    CHECK_MSG(got == MCI_UNCERTAIN || got == ref, "mci_orient3d_vertices_dd (%s): %d, "
              "reference %d", class_names[s->cls], got, ref);
    if (filtered == MCI_UNCERTAIN) {
        vertex_dd_cases++;
        vertex_dd_decided += got != MCI_UNCERTAIN;
    }
}

static void check_orient3d_vertex(const scenario *s, const query *q, int ref)
{
    const mci_point *a = &ws.kpt[q->pt[0]];
    const mci_plane *p = &ws.kpl[q->pl[0]];
    const double *x = a->v[0];
    int f1, f2;
    if (a->kind != MCI_POINT_EXPLICIT)
        return;
    f1 = mci_orient3d_vertex_filtered(x, p);
    f2 = mci_orient3d_vertices_filtered(p->a, p->b, p->c, x);
    CHECK_MSG(mci_orient3d_vertex(x, p) == ref, "mci_orient3d_vertex (%s): reference %d",
              class_names[s->cls], ref);
    CHECK_MSG(mci_orient3d_vertices(p->a, p->b, p->c, x) == ref,
              "mci_orient3d_vertices (%s): reference %d", class_names[s->cls], ref);
    CHECK_MSG(f1 == MCI_UNCERTAIN || f1 == ref, "mci_orient3d_vertex_filtered (%s): %d, "
              "reference %d", class_names[s->cls], f1, ref);
    CHECK_MSG(f2 == MCI_UNCERTAIN || f2 == ref, "mci_orient3d_vertices_filtered (%s): %d, "
              "reference %d", class_names[s->cls], f2, ref);
    check_orient3d_vertex_dd(s, p, x, f2, ref);
    vertex_filter_cases += 2;
    vertex_filter_decided += (f1 != MCI_UNCERTAIN) + (f2 != MCI_UNCERTAIN);
}

static void run_query(const scenario *s, const query *q)
{
    int got[3], ref = ref_eval(q);
    if (ref == NONE)
        return; /* precondition fails: the kernel must not be asked */
    kernel_eval(s, q, got);
    check_case(s, q, got, ref);
    if (q->pred == PR_ORIENT2D) {
        check_orient2d_boxes(s, q, ref);
        check_orient2d_cheap(s, q, ref);
        check_orient2d_dd(s, q, got[2], ref);
    }
    if (q->pred == PR_ORIENT3D)
        check_orient3d_vertex(s, q, ref);
}

/* Indices of the points that exist; returns their count. */
static int usable_points(const scenario *s, int *idx)
{
    int n = 0;
    for (int i = 0; i < s->npt; i++)
        if (ws.ok[i])
            idx[n++] = i;
    return n;
}

static void queries_orient3d(const scenario *s, const int *idx, int n)
{
    for (int i = 0; i < n; i++)
        for (int p = 0; p < s->npl; p++) {
            query q = {PR_ORIENT3D, {idx[i], 0, 0}, {p, p}, {0, 0}, 0, 0};
            run_query(s, &q);
        }
}

/* compare_coord on every axis, lex, equality, and the line orders, for every pair
 * (including a point with itself), in a random order of the two operands. */
static void queries_pairs(const scenario *s, const int *idx, int n)
{
    for (int i = 0; i < n; i++)
        for (int j = i; j < n; j++) {
            bool swap = rng_chance(0.5);
            query q = {PR_CMP,
                       {swap ? idx[j] : idx[i], swap ? idx[i] : idx[j], 0},
                       {0, 0},
                       {0, 0},
                       0,
                       0};
            for (q.axis = 0; q.axis < 3; q.axis++)
                run_query(s, &q);
            q.axis = 0;
            q.pred = PR_LEX;
            run_query(s, &q);
            q.pred = PR_EQ;
            run_query(s, &q);
            q.pred = PR_ORDER_PL;
            for (int l = 0; l < s->nlp; l++) {
                q.pl[0] = s->line_planes[l][0];
                q.pl[1] = s->line_planes[l][1];
                q.line = l;
                run_query(s, &q);
            }
            q.pred = PR_ORDER_EDGE;
            for (int l = 0; l < s->nle; l++) {
                q.lv[0] = s->line_edges[l][0];
                q.lv[1] = s->line_edges[l][1];
                q.line = MAXLP + l;
                run_query(s, &q);
            }
        }
}

static void orient2d_all_axes(const scenario *s, int a, int b, int c)
{
    query q = {PR_ORIENT2D, {a, b, c}, {0, 0}, {0, 0}, 0, 0};
    for (q.axis = 0; q.axis < 3; q.axis++)
        run_query(s, &q);
}

/* Every triple when there are few points (in a random order of the three), otherwise a
 * sample drawn with replacement (so repeated points occur too). */
static void queries_orient2d(const scenario *s, const int *idx, int n)
{
    enum { SAMPLE = 90 };
    if (n > 10) {
        for (int t = 0; t < SAMPLE; t++)
            orient2d_all_axes(s, idx[rng_int(0, n - 1)], idx[rng_int(0, n - 1)],
                              idx[rng_int(0, n - 1)]);
        return;
    }
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            for (int k = j + 1; k < n; k++) {
                int t[3] = {idx[i], idx[j], idx[k]}, r = rng_int(0, 2);
                if (rng_chance(0.5))
                    orient2d_all_axes(s, t[r], t[(r + 1) % 3], t[(r + 2) % 3]);
                else
                    orient2d_all_axes(s, t[r], t[(r + 2) % 3], t[(r + 1) % 3]);
            }
}

static void queries_linedir(const scenario *s)
{
    for (int p = 0; p < s->npl; p++)
        for (int r = p + 1; r < s->npl; r++) {
            query q = {PR_LINEDIR, {0, 0, 0}, {p, r}, {0, 0}, 0, 0};
            for (q.axis = 0; q.axis < 3; q.axis++)
                run_query(s, &q);
        }
}

/* The generator's claims (group points on the onpl planes, and equal) hold exactly: a
 * failure here is a bug of this test, not of the kernel. */
static void check_claims(const scenario *s)
{
    for (int g = 0; g < s->ngroup; g++) {
        int i = s->group[g];
        if (!ws.ok[i])
            continue;
        for (int p = 0; p < s->nonpl; p++)
            CHECK_MSG(ref_orient3d(&ws.rpt[i], &ws.rpl[s->onpl[p]]) == 0,
                      "%s: generator: point %d not on plane %d", class_names[s->cls], i,
                      s->onpl[p]);
        if (s->group_equal && ws.ok[s->group[0]])
            CHECK_MSG(ref_compare_lex(&ws.rpt[i], &ws.rpt[s->group[0]]) == 0,
                      "%s: generator: point %d differs from %d", class_names[s->cls], i,
                      s->group[0]);
    }
}

static double seconds(void) { return (double)clock() / CLOCKS_PER_SEC; }

/* MCSG_TEST_ONLY=TEXT runs only the classes whose name contains TEXT. */
static bool class_selected(int cls)
{
    const char *only = getenv("MCSG_TEST_ONLY");
    return !only || strstr(class_names[cls], only);
}

static void run_queries(const scenario *s)
{
    int idx[MAXPT], n = usable_points(s, idx);
    build_lines(s, idx, n);
    queries_orient3d(s, idx, n);
    queries_pairs(s, idx, n);
    queries_orient2d(s, idx, n);
    queries_linedir(s);
}

/* Points kept by the threads' exact caches (exact/exact_cache.h) over the scenarios run
 * inside a loop: the cached path was taken, not only allowed. */
static long cached_points_seen;

static mcsg_status run_queries_task(void *user, size_t index, mcsg_error *err)
{
    (void)index;
    (void)err;
    run_queries(user);
    cached_points_seen += (long)mci_exact_cache_count();
    return MCSG_OK;
}

/* Every other scenario runs its queries inside a one-thread loop, where the exact stage
 * keeps points in the thread's cache and answers repeated queries from it: the same
 * checks against the reference then hold for the cached path. */
static void run_queries_in_loop(const scenario *s)
{
    mcsg_options opts = {0};
    mci_ctx ctx;
    mcsg_error err;
    opts.threads = 1;
    mci_ctx_init(&ctx, &opts);
    CHECK(mci_parallel_for(&ctx, 1, run_queries_task, (void *)s, &err) == MCSG_OK);
}

static void run_scenario(const scenario *s)
{
    static long runs;
    double t = seconds();
    if (!class_selected(s->cls))
        return;
    build(s);
    check_claims(s);
    if (runs++ % 2)
        run_queries_in_loop(s);
    else
        run_queries(s);
    class_scenarios[s->cls]++;
    class_seconds[s->cls] += seconds() - t;
}

/* The scenario, then `runs` copies with one input coordinate (sometimes two) moved by one
 * ulp: exact degeneracies become near-degeneracies the reference still decides. */
static void run_with_perturbations(const scenario *base, int runs, int ulp_cls)
{
    run_scenario(base);
    for (int r = 0; r < runs; r++) {
        scenario s = *base;
        int moves = rng_chance(0.25) ? 2 : 1;
        s.cls = ulp_cls;
        s.ngroup = s.nonpl = 0;
        for (int m = 0; m < moves; m++) {
            double *x = &s.v[rng_int(0, s.nv - 1)][rng_int(0, 2)];
            *x = nudge(*x, 1);
        }
        run_scenario(&s);
    }
}

/* ---------------------------------------------------------------- driver */

/* MCSG_TEST_SCALE, else 1; under the sanitizers (5-10x slower, and there to find memory
 * and undefined-behaviour errors, which half the scenarios reach as well) 0.5. */
static double test_scale(void)
{
    const char *env = getenv("MCSG_TEST_SCALE");
    double f = env ? atof(env) : getenv("MCSG_SANITIZED") ? 0.5 : 1.0;
    return f > 0 ? f : 1.0;
}

static long scaled(long n) { return (long)((double)n * test_scale() + 0.5); }

/* Scenarios per class at scale 1 (the normal build: about 30 s). The exp and mix regimes (and the adversarial lattices with mixed
 * scales) make the exact stage work on integers of ~2000 bits, some 0.2 ms per case, so
 * they get fewer scenarios than the well-scaled regimes. */
static const int random_counts[R_COUNT] = {220, 220, 25, 25, 220, 220, 220, 220};
static const int nearpar_counts[R_COUNT] = {50, 50, 10, 10, 50, 50, 50, 50};

TEST(kernel_random)
{
    scenario s;
    double t = seconds();
    for (int r = 0; r < R_COUNT; r++)
        for (long n = scaled(random_counts[r]); n > 0; n--) {
            scenario_random(&s, r);
            run_scenario(&s);
        }
    printf("  random scenarios: %.1f s\n", seconds() - t);
}

TEST(kernel_near_parallel)
{
    scenario s;
    double t = seconds();
    for (int r = 0; r < R_COUNT; r++)
        for (long n = scaled(nearpar_counts[r]); n > 0; n--) {
            scenario_near_parallel(&s, r);
            run_scenario(&s);
        }
    printf("  nearly parallel scenarios: %.1f s\n", seconds() - t);
}

TEST(kernel_adversarial)
{
    static void (*const builders[])(scenario *, const lattice *) = {
        scenario_same, scenario_line, scenario_parallel};
    static const char *const names[] = {"same+ulp", "line+ulp", "par+ulp"};
    scenario s;
    double t = seconds();
    for (int b = 0; b < 3; b++) {
        int ulp_cls = class_id(names[b], "");
        for (int l = 0; l < lattice_count; l++)
            for (long n = scaled(lattices[l].count); n > 0; n--) {
                builders[b](&s, &lattices[l]);
                run_with_perturbations(&s, b == 2 ? 6 : 3, ulp_cls);
            }
    }
    printf("  adversarial scenarios: %.1f s\n", seconds() - t);
}

TEST(kernel_axis_grid)
{
    scenario s;
    double t = seconds();
    int ulp_cls = class_id("axisgrid+ulp", "");
    for (long n = scaled(400); n > 0; n--) {
        scenario_axis_grid(&s);
        run_with_perturbations(&s, 2, ulp_cls);
    }
    printf("  axis-aligned grid scenarios: %.1f s\n", seconds() - t);
}

/* mpq_set_d must be exact on the whole range (the reference relies on it). */
TEST(reference_sanity)
{
    const double xs[] = {0x1p-1074, 3 * 0x1p-1074, 0x1.fffffffffffffp+1023,
                         1e-300,    3.4e38,        -0x1.123456789abcdp-1030};
    mpq_t q;
    mpq_init(q);
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        mpq_set_d(q, xs[i]);
        CHECK(mpq_get_d(q) == xs[i]);
    }
    mpq_clear(q);
}

static void print_class_table(void)
{
    printf("\n%-18s %5s %8s %8s %6s %6s  %6s %6s %6s %6s  %s\n", "class", "scen", "cases",
           "ref=0", "time", "filt%", "o3d%", "cmp%", "o2d%", "ldir%", "mismatch");
    for (int c = 0; c < nclasses; c++) {
        long calls = 0, zero = 0, filt = 0, dec = 0, bad = 0;
        for (int p = 0; p < PR_COUNT; p++) {
            calls += stats[c][p].calls, zero += stats[c][p].zero,
                bad += stats[c][p].mismatches;
            filt += stats[c][p].filt, dec += stats[c][p].decided;
        }
        const pstat *o = stats[c];
        printf(
            "%-18s %5ld %8ld %8ld %5.1fs %5.1f%%  %6.1f %6.1f %6.1f %6.1f  %ld\n",
            class_names[c], class_scenarios[c], calls, zero, class_seconds[c],
            filt ? 100.0 * dec / filt : 0.0,
            100.0 * o[PR_ORIENT3D].decided / (o[PR_ORIENT3D].filt + !o[PR_ORIENT3D].filt),
            100.0 * o[PR_CMP].decided / (o[PR_CMP].filt + !o[PR_CMP].filt),
            100.0 * o[PR_ORIENT2D].decided / (o[PR_ORIENT2D].filt + !o[PR_ORIENT2D].filt),
            100.0 * o[PR_LINEDIR].decided / (o[PR_LINEDIR].filt + !o[PR_LINEDIR].filt),
            bad);
    }
}

static void print_predicate_table(void)
{
    long total = 0;
    printf("\n%-15s %10s %9s %10s %8s %10s %13s %8s\n", "predicate", "cases", "ref=0",
           "filtered", "decided", "of ref!=0", "decided,ref=0", "mismatch");
    for (int p = 0; p < PR_COUNT; p++) {
        pstat t = {0, 0, 0, 0, 0, 0};
        for (int c = 0; c < nclasses; c++) {
            t.calls += stats[c][p].calls, t.zero += stats[c][p].zero;
            t.filt += stats[c][p].filt, t.decided += stats[c][p].decided;
            t.decided_zero += stats[c][p].decided_zero,
                t.mismatches += stats[c][p].mismatches;
        }
        total += t.calls;
        long nonzero = t.filt ? t.calls - t.zero : 0;
        printf("%-15s %10ld %9ld %10ld %7.1f%% %9.1f%% %13ld %8ld\n", pred_names[p],
               t.calls, t.zero, t.filt, t.filt ? 100.0 * t.decided / t.filt : 0.0,
               nonzero ? 100.0 * (t.decided - t.decided_zero) / nonzero : 0.0,
               t.decided_zero, t.mismatches);
    }
    printf("total cases: %ld; cached values with an uninformative bound (inf/NaN): %ld\n",
           total, uninformative_bounds);
    printf("coordinates rounded by mci_point_round (checked nearest): %ld\n", rounded_coordinates);
    printf("coordinates rounded by the double-double stage: %ld of %ld\n", dd_rounded,
           dd_round_tries);
    printf("orient2d box filter: %ld cases, %ld decided\n", box_filter_cases,
           box_filter_decided);
    printf("orient2d stages without implicit points: %ld cases, %ld decided\n", cheap_cases,
           cheap_decided);
    printf("orient2d cases the first filter left: %ld, double-double stage decided %ld\n",
           dd_after_filter, dd_decided);
    printf("orient3d of input vertices: %ld filter cases, %ld decided by the filter\n",
           vertex_filter_cases, vertex_filter_decided);
    printf("orient3d of input vertices the filter left: %ld, double-double stage decided %ld\n",
           vertex_dd_cases, vertex_dd_decided);
    printf("implicit point boxes: %ld, infinite %ld, tight (1e-10) %ld\n\n", box_points,
           box_infinite, box_tight);
}

static bool same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* The inline steps agree with nextafter on special values and random bit patterns. */
TEST(next_double)
{
    static const double special[] = {0.0, -0.0, 0x1p-1074, -0x1p-1074, 0x1p-1022, -0x1p-1022,
                                     1.0, -1.0, DBL_MAX, -DBL_MAX, INFINITY, -INFINITY};
    for (size_t i = 0; i < sizeof special / sizeof special[0]; i++) {
        double x = special[i];
        CHECK_MSG(same_bits(mci_next_up(x), nextafter(x, INFINITY)), "next_up(%a)", x);
        CHECK_MSG(same_bits(mci_next_down(x), nextafter(x, -INFINITY)), "next_down(%a)", x);
    }
    CHECK(isnan(mci_next_up(NAN)) && isnan(mci_next_down(NAN)));
    for (int i = 0; i < 200000; i++) {
        uint64_t bits = rng_next();
        double x;
        memcpy(&x, &bits, sizeof x);
        if (isnan(x))
            continue;
        CHECK_MSG(same_bits(mci_next_up(x), nextafter(x, INFINITY)), "next_up(%a)", x);
        CHECK_MSG(same_bits(mci_next_down(x), nextafter(x, -INFINITY)), "next_down(%a)", x);
    }
}

/* The bit range read from a double's fields agrees with ilogb and with the lowest set
 * bit of the significand, on special values and random bit patterns. */
static void check_bit_range(double x)
{
    int lsb, msb;
    double scaled;
    mci_bit_range(x, &lsb, &msb);
    CHECK_MSG(msb == ilogb(x), "msb of %a: %d, ilogb %d", x, msb, ilogb(x));
    scaled = ldexp(x, -lsb); /* exact: an odd integer */
    CHECK_MSG(scaled == trunc(scaled) && fmod(scaled, 2.0) != 0, "lsb of %a: %d", x, lsb);
}

TEST(bit_range)
{
    static const double special[] = {0x1p-1074, -0x1p-1074, 0x1.8p-1073, 0x1p-1022,
                                     0x1.fffffffffffffp-1023, 1.0, -1.0, 0.1, 3.0, DBL_MAX,
                                     -DBL_MAX, 0x1p1023};
    for (size_t i = 0; i < sizeof special / sizeof special[0]; i++)
        check_bit_range(special[i]);
    for (int i = 0; i < 200000; i++) {
        uint64_t bits = rng_next();
        double x;
        memcpy(&x, &bits, sizeof x);
        if (isfinite(x) && x != 0)
            check_bit_range(x);
    }
}

/* Four vertices in every cyclic order, against the reference, through both vertex forms.
 * The vertices are made exact integers once; each order's determinant is computed anew. */
static void check_four_vertices(const double *const q[4], long *zeros)
{
    ref_point x[4];
    for (int i = 0; i < 4; i++) {
        ref_point_init(&x[i]);
        ref_point_set_d(&x[i], q[i]);
    }
    for (int r = 0; r < 4; r++) {
        int i = (r + 1) % 4, j = (r + 2) % 4, k = (r + 3) % 4;
        const double *a = q[r], *b = q[i], *c = q[j], *d = q[k];
        int ref = ref_orient3d_points(&x[r], &x[i], &x[j], &x[k]);
        mci_plane plane;
        mci_plane_init(&plane, a, b, c);
        CHECK_MSG(mci_orient3d_vertices(a, b, c, d) == ref, "mci_orient3d_vertices: ref %d",
                  ref);
        CHECK_MSG(mci_orient3d_vertex(d, &plane) == ref, "mci_orient3d_vertex: ref %d", ref);
        *zeros += ref == 0;
    }
    for (int i = 0; i < 4; i++)
        ref_point_clear(&x[i]);
}

/* The shapes the coordinate rule and the double-word stage of orient3d of vertices are
 * for: a cylinder's side rectangle and cap (coplanar by their coordinates, which no
 * filter decides), a UV sphere's quad (nearly coplanar after rounding), and each with one
 * coordinate moved by an ulp (then the answer is not 0 for the rule's shapes). */
TEST(vertex_orient3d_shapes)
{
    long zeros = 0, cases = 0;
    for (int i = 0; i < 20000; i++) {
        double t1 = rng_unit() * 6.283185307179586, t2 = t1 + 0.01 + rng_unit() * 0.5;
        double p1 = rng_unit() * 3.14159, p2 = p1 + 0.01 + rng_unit() * 0.3;
        double rad = ldexp(0.5 + rng_unit(), rng_int(-30, 30)), z0 = rng_unit() * rad,
               z1 = z0 + rad * (0.1 + rng_unit());
        double side[4][3] = {{rad * cos(t1), rad * sin(t1), z0},
                             {rad * cos(t2), rad * sin(t2), z0},
                             {rad * cos(t2), rad * sin(t2), z1},
                             {rad * cos(t1), rad * sin(t1), z1}};
        double cap[4][3] = {{0, 0, z0}, {rad * cos(t1), rad * sin(t1), z0},
                            {rad * cos(t2), rad * sin(t2), z0}, {rad * cos(p2), rad * sin(p1), z0}};
        double quad[4][3];
        double (*shapes[3])[3] = {side, cap, quad};
        for (int k = 0; k < 4; k++) {
            double t = k == 0 || k == 3 ? t1 : t2, p = k < 2 ? p1 : p2;
            quad[k][0] = rad * cos(t) * sin(p);
            quad[k][1] = rad * sin(t) * sin(p);
            quad[k][2] = rad * cos(p);
        }
        for (int sh = 0; sh < 3; sh++) {
            const double *q[4] = {shapes[sh][0], shapes[sh][1], shapes[sh][2], shapes[sh][3]};
            int v = rng_int(0, 3), axis = rng_int(0, 2);
            check_four_vertices(q, &zeros);
            shapes[sh][v][axis] = mci_next_up(shapes[sh][v][axis]);
            check_four_vertices(q, &zeros);
            cases += 8;
        }
    }
    printf("vertex orient3d shapes: %ld cases, %ld coplanar\n", cases, zeros);
    CHECK(zeros > cases / 4); /* the rule's shapes were there */
}

/* The coordinates of x cyclically moved by `shift` axes (the shapes below along any axis). */
static void rotate_axes(double x[3], int shift)
{
    double t[3] = {x[0], x[1], x[2]};
    for (int k = 0; k < 3; k++)
        x[(k + shift) % 3] = t[k];
}

/* Two crossings of one plane that contains an axis direction (a side of a cylindrical
 * hole) with two lines whose ends project to the same points along that axis (a
 * cylinder's top and bottom cap edges): equal on the two other axes by definition
 * (mci_compare_coord's rule), and compared with the exact stage on every axis, also
 * after an end is moved by one ulp (the rule must then not apply). */
TEST(lpi_equal_by_projection)
{
    long cases = 0, equal = 0;
    for (int i = 0; i < 20000; i++) {
        double r = 0.2 + rng_unit(), big = 5 + 5 * rng_unit(), t1 = rng_unit() * 6.2831853;
        double t2 = t1 + 0.05 + rng_unit() * 0.5, u = rng_unit() * 6.2831853;
        double cx = (big - 2 * r) * cos(u + 0.01), cy = (big - 2 * r) * sin(u + 0.01);
        double z0 = -1 - rng_unit(), z1 = 1 + rng_unit();
        double v[7][3] = {{cx + r * cos(t1), cy + r * sin(t1), 2 * z0},
                          {cx + r * cos(t2), cy + r * sin(t2), 2 * z0},
                          {cx + r * cos(t1), cy + r * sin(t1), 2 * z1},
                          {0, 0, z1}, {big * cos(u), big * sin(u), z1},
                          {0, 0, z0}, {big * cos(u), big * sin(u), z0}};
        int shift = rng_int(0, 2), moved = rng_int(0, 1);
        mci_plane plane;
        mci_point a, b;
        for (int k = 0; k < 7; k++)
            rotate_axes(v[k], shift);
        if (moved) /* one end of the lower line moved across: no longer the same projection */
            v[6][(shift + rng_int(0, 1)) % 3] = mci_next_up(v[6][(shift + rng_int(0, 1)) % 3]);
        mci_plane_init(&plane, v[0], v[1], v[2]);
        if (!mci_point_lpi(&a, v[3], v[4], &plane) || !mci_point_lpi(&b, v[5], v[6], &plane))
            continue;
        for (int axis = 0; axis < 3; axis++) {
            int got = mci_compare_coord(&a, &b, axis), ref = mci_compare_coord_exact(&a, &b, axis);
            CHECK_MSG(got == ref, "case %d axis %d (shift %d, moved %d): %d, exact %d", i, axis,
                      shift, moved, got, ref);
            equal += ref == 0;
        }
        cases++;
    }
    printf("lpi equal by projection: %ld pairs, %ld equal coordinates\n", cases, equal);
    CHECK(cases > 10000 && equal > cases / 2); /* the rule's shapes were there */
}

/* A random vertex on a coarse grid (so that midpoints and sums are exact). */
static void grid_vertex(double v[3])
{
    for (int k = 0; k < 3; k++)
        v[k] = rng_int(-32, 32) / 4.0;
}

/* mci_compare_coord and mci_compare_lex of a and b against the exact stage; true when
 * the points are equal. */
static bool check_against_exact(const mci_point *a, const mci_point *b, int i)
{
    int lex = 0;
    for (int axis = 0; axis < 3; axis++) {
        int got = mci_compare_coord(a, b, axis), ref = mci_compare_coord_exact(a, b, axis);
        CHECK_MSG(got == ref, "case %d axis %d: %d, exact %d", i, axis, got, ref);
        if (lex == 0)
            lex = ref;
    }
    CHECK_MSG(mci_compare_lex(a, b) == lex, "case %d: lex %d, exact %d", i,
              mci_compare_lex(a, b), lex);
    return lex == 0;
}

/* Two triangles whose edges PQ and RS cross at their midpoint X: the LPI of PQ with RS's
 * plane and the LPI of RS with PQ's plane are both X (mci_compare_coord's rule of
 * crossing lines), and the LPIs of one line with two triangles of one plane (the
 * rule of the same line and plane). After one end is moved by one ulp (the lines no
 * longer meet, or the planes differ) the rules must not apply: every answer is checked
 * against the exact stage. */
TEST(lpi_equal_by_lines)
{
    long cases = 0, equal = 0;
    for (int i = 0; i < 20000; i++) {
        double x[3], d1[3], d2[3], p[3], q[3], r[3], s[3], ca[3], cb[3], cb2[3];
        int moved = rng_int(0, 2), same_line = rng_int(0, 1);
        mci_plane plane_a, plane_b, plane_b2;
        mci_point a, b;
        grid_vertex(x), grid_vertex(d1), grid_vertex(d2), grid_vertex(ca), grid_vertex(cb);
        for (int k = 0; k < 3; k++) {
            p[k] = x[k] - d1[k], q[k] = x[k] + d1[k];
            r[k] = x[k] - d2[k], s[k] = x[k] + d2[k];
            cb2[k] = r[k] + s[k] - cb[k]; /* R S CB CB2: a parallelogram, one plane */
        }
        if (moved == 1)
            q[rng_int(0, 2)] = mci_next_up(q[rng_int(0, 2)]);
        else if (moved == 2)
            cb2[rng_int(0, 2)] = mci_next_down(cb2[rng_int(0, 2)]);
        mci_plane_init(&plane_a, p, q, ca);
        mci_plane_init(&plane_b, r, s, cb);
        mci_plane_init(&plane_b2, s, cb2, r);
        if (!mci_point_lpi(&a, p, q, &plane_b))
            continue;
        if (same_line ? !mci_point_lpi(&b, q, p, &plane_b2) : !mci_point_lpi(&b, r, s, &plane_a))
            continue;
        equal += check_against_exact(&a, &b, i);
        cases++;
    }
    printf("lpi equal by lines: %ld pairs, %ld equal\n", cases, equal);
    CHECK(cases > 10000 && equal > cases / 3); /* the rules' shapes were there */
}

int main(void)
{
    const char *seed = getenv("MCSG_TEST_SEED");
    if (seed)
        rng_state = strtoull(seed, NULL, 0);
    printf("seed 0x%llx, scale %g\n", (unsigned long long)rng_state, test_scale());
    ws_init();
    RUN(next_double);
    RUN(bit_range);
    RUN(vertex_orient3d_shapes);
    RUN(lpi_equal_by_projection);
    RUN(lpi_equal_by_lines);
    RUN(reference_sanity);
    RUN(kernel_adversarial);
    RUN(kernel_near_parallel);
    RUN(kernel_random);
    RUN(kernel_axis_grid);
    print_class_table();
    print_predicate_table();
    /* The box filter's check was not vacuous: it decided some cases and left others. */
    CHECK(box_filter_decided > 0 && box_filter_decided < box_filter_cases);
    CHECK(cheap_decided > 0 && cheap_decided < cheap_cases);
    printf("points kept by the exact cache: %ld; approximations checked %ld, coordinates "
           "within 2^-100: %ld\n", cached_points_seen, approx_points, approx_tight);
    CHECK(approx_points > 0 && approx_tight > 0);
    CHECK(cached_points_seen > 0);
    ws_clear();
    return test_summary();
}
