/*
 * The plane-based inside-triangle test (mci_point_in_triangle, mci_plane_projection_axis)
 * against independent references: for points built as a + s(b - a) + t(c - a) with exact
 * dyadic s, t the answer follows from s and t; for LPI points it comes from the signs of
 * the three sub-triangle areas ((b-p) x (c-p)) . n etc., computed in GMP rationals.
 */
#include "testlib.h"
#include "exact/kernel.h"

#include <gmp.h>
#include <math.h>
#include <string.h>

static uint64_t rng = 0x243f6a8885a308d3ULL;
static uint64_t next_random(void)
{
    return test_xorshift(&rng);
}

static int random_int(int lo, int hi)
{
    return test_random_int(&rng, lo, hi);
}

/* Containment from barycentric parameters (p = a + s(b-a) + t(c-a)). */
static mci_containment expected_from_st(double s, double t, int *which)
{
    double u = 1 - s - t;
    *which = -1;
    if (s < 0 || t < 0 || u < 0)
        return MCI_OUTSIDE;
    if ((s == 0) + (t == 0) + (u == 0) == 2) {
        *which = s == 1 ? 1 : t == 1 ? 2 : 0;
        return MCI_ON_VERTEX;
    }
    if (t == 0 || u == 0 || s == 0) {
        *which = t == 0 ? 0 : u == 0 ? 1 : 2;
        return MCI_ON_EDGE;
    }
    return MCI_INSIDE;
}

/* A non-degenerate triangle (decided exactly) with small-integer corners times 2^scale
 * plus an offset. */
static void random_triangle(double v[3][3], int scale, double offset)
{
    mci_plane plane;
    int sign;
    do {
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                v[i][k] = ldexp(random_int(-100, 100), scale) + offset;
        mci_plane_init(&plane, v[0], v[1], v[2]);
    } while (mci_plane_projection_axis(&plane, &sign) < 0);
}

static void check_case(const mci_point *p, const mci_plane *plane, mci_containment want,
                       int want_which, const char *what)
{
    int which;
    mci_containment got = mci_point_in_triangle(p, plane, &which);
    CHECK_MSG(got == want && which == want_which, "%s: got %d/%d, want %d/%d", what, got,
              which, want, want_which);
}

TEST(explicit_and_tpi_points_on_dyadic_grid)
{
    const int scales[] = {0, -20, 30, -1000, 900};
    for (int n = 0; n < 40000; n++) {
        int scale = scales[n % 5];
        double v[3][3], p[3], r[4][3], s = random_int(-4, 12) / 8.0, t = random_int(-4, 12) / 8.0;
        mci_plane plane, q1, q2;
        mci_point point, tpi;
        int which;
        mci_containment want;
        random_triangle(v, scale, scale == 0 && n % 7 == 0 ? 1e6 : 0);
        for (int k = 0; k < 3; k++) /* exact: small integers times powers of two */
            p[k] = v[0][k] + s * (v[1][k] - v[0][k]) + t * (v[2][k] - v[0][k]);
        mci_plane_init(&plane, v[0], v[1], v[2]);
        want = expected_from_st(s, t, &which);
        mci_point_explicit(&point, p);
        check_case(&point, &plane, want, which, "explicit");
        /* The same point as the intersection of the triangle's plane with two others. */
        for (int i = 0; i < 4; i++)
            for (int k = 0; k < 3; k++)
                r[i][k] = ldexp(random_int(-100, 100), scale);
        mci_plane_init(&q1, p, r[0], r[1]);
        mci_plane_init(&q2, p, r[2], r[3]);
        if (mci_point_tpi(&tpi, &plane, &q1, &q2))
            check_case(&tpi, &plane, want, which, "tpi");
    }
}

/* sign(((x - p) x (y - p)) . n) in rationals. */
static int area_sign(mpq_t p[3], mpq_t x[3], mpq_t y[3], mpq_t n[3])
{
    mpq_t dx[3], dy[3], c, t, sum;
    int sign;
    mpq_inits(c, t, sum, NULL);
    for (int k = 0; k < 3; k++) {
        mpq_inits(dx[k], dy[k], NULL);
        mpq_sub(dx[k], x[k], p[k]);
        mpq_sub(dy[k], y[k], p[k]);
    }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mpq_mul(c, dx[i], dy[j]);
        mpq_mul(t, dx[j], dy[i]);
        mpq_sub(c, c, t);
        mpq_mul(c, c, n[k]);
        mpq_add(sum, sum, c);
    }
    sign = mpq_sgn(sum);
    for (int k = 0; k < 3; k++)
        mpq_clears(dx[k], dy[k], NULL);
    mpq_clears(c, t, sum, NULL);
    return sign;
}

static void mpq_vec_set(mpq_t out[3], const double *v)
{
    for (int k = 0; k < 3; k++)
        mpq_set_d(out[k], v[k]);
}

/* The LPI of line l0 l1 with the plane of v, exactly; false if parallel. */
static bool reference_lpi(mpq_t out[3], double v[3][3], const double *l0, const double *l1,
                          mpq_t n[3])
{
    mpq_t a[3], b[3], c[3], p[3], q[3], e1[3], e2[3], num, den, t;
    bool ok;
    mpq_inits(num, den, t, NULL);
    for (int k = 0; k < 3; k++)
        mpq_inits(a[k], b[k], c[k], p[k], q[k], e1[k], e2[k], NULL);
    mpq_vec_set(a, v[0]), mpq_vec_set(b, v[1]), mpq_vec_set(c, v[2]);
    mpq_vec_set(p, l0), mpq_vec_set(q, l1);
    for (int k = 0; k < 3; k++) {
        mpq_sub(e1[k], b[k], a[k]);
        mpq_sub(e2[k], c[k], a[k]);
    }
    for (int k = 0; k < 3; k++) {
        int i = (k + 1) % 3, j = (k + 2) % 3;
        mpq_mul(n[k], e1[i], e2[j]);
        mpq_mul(t, e1[j], e2[i]);
        mpq_sub(n[k], n[k], t);
    }
    for (int k = 0; k < 3; k++) {
        mpq_sub(t, a[k], p[k]);
        mpq_mul(t, t, n[k]);
        mpq_add(num, num, t);
        mpq_sub(q[k], q[k], p[k]);
        mpq_mul(t, q[k], n[k]);
        mpq_add(den, den, t);
    }
    ok = mpq_sgn(den) != 0;
    if (ok) {
        mpq_div(t, num, den);
        for (int k = 0; k < 3; k++) {
            mpq_mul(out[k], q[k], t);
            mpq_add(out[k], out[k], p[k]);
        }
    }
    for (int k = 0; k < 3; k++)
        mpq_clears(a[k], b[k], c[k], p[k], q[k], e1[k], e2[k], NULL);
    mpq_clears(num, den, t, NULL);
    return ok;
}

/* Containment from the three sub-triangle areas: edge ab <-> (a, b, p), and so on. */
static mci_containment reference_containment(mpq_t p[3], double v[3][3], mpq_t n[3],
                                             int *which)
{
    mpq_t corner[3][3];
    int side[3], zeros = 0;
    mci_containment result = MCI_INSIDE;
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++)
            mpq_init(corner[i][k]);
        mpq_vec_set(corner[i], v[i]);
    }
    for (int e = 0; e < 3; e++) {
        side[e] = area_sign(p, corner[e], corner[(e + 1) % 3], n);
        zeros += side[e] == 0;
    }
    *which = -1;
    if (side[0] < 0 || side[1] < 0 || side[2] < 0) {
        result = MCI_OUTSIDE;
    } else if (zeros == 1) {
        result = MCI_ON_EDGE;
        *which = side[0] == 0 ? 0 : side[1] == 0 ? 1 : 2;
    } else if (zeros == 2) {
        result = MCI_ON_VERTEX;
        *which = side[1] != 0 ? 0 : side[2] != 0 ? 1 : 2;
    }
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            mpq_clear(corner[i][k]);
    return result;
}

static double random_unit(void)
{
    return (double)(next_random() >> 11) / 9007199254740992.0 * 2 - 1;
}

/* LPI points: random lines through random triangles, and lines through exact points of
 * the triangle's edges and vertices (dyadic grid), compared with the area reference. */
TEST(lpi_points_against_rational_areas)
{
    long counts[4] = {0};
    for (int n = 0; n < 30000; n++) {
        double v[3][3], l0[3], l1[3];
        mpq_t p[3], nrm[3];
        mci_plane plane;
        mci_point point;
        int which;
        bool grid = n % 2;
        if (grid) {
            double s = random_int(0, 8) / 8.0, d[3];
            random_triangle(v, -3, 0);
            int e = random_int(0, 2);
            for (int k = 0; k < 3; k++) {
                d[k] = random_int(-5, 5);
                l0[k] = v[e][k] + s * (v[(e + 1) % 3][k] - v[e][k]) + d[k];
                l1[k] = l0[k] - 2 * d[k];
            }
        } else {
            for (int i = 0; i < 3; i++)
                for (int k = 0; k < 3; k++)
                    v[i][k] = random_unit();
            for (int k = 0; k < 3; k++)
                l0[k] = random_unit(), l1[k] = random_unit();
        }
        for (int k = 0; k < 3; k++)
            mpq_inits(p[k], nrm[k], NULL);
        mci_plane_init(&plane, v[0], v[1], v[2]);
        if (reference_lpi(p, v, l0, l1, nrm) && mci_point_lpi(&point, l0, l1, &plane)) {
            mci_containment want = reference_containment(p, v, nrm, &which);
            counts[want]++;
            check_case(&point, &plane, want, which, grid ? "lpi grid" : "lpi random");
        }
        for (int k = 0; k < 3; k++)
            mpq_clears(p[k], nrm[k], NULL);
    }
    printf("lpi cases: outside %ld, inside %ld, on edge %ld, on vertex %ld\n", counts[0],
           counts[1], counts[2], counts[3]);
    CHECK(counts[2] > 100 && counts[3] > 100 && counts[1] > 100);
}

TEST(projection_axis)
{
    double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0}, d[3] = {1, 1, 0};
    mci_plane plane;
    int sign;
    mci_plane_init(&plane, a, b, c);
    CHECK(mci_plane_projection_axis(&plane, &sign) == 2 && sign == 1);
    mci_plane_init(&plane, a, c, b);
    CHECK(mci_plane_projection_axis(&plane, &sign) == 2 && sign == -1);
    mci_plane_init(&plane, a, b, d);
    CHECK(mci_plane_projection_axis(&plane, &sign) == 2 && sign == 1);
    d[1] = 0; /* collinear corners: no plane */
    mci_plane_init(&plane, a, b, d);
    CHECK(mci_plane_projection_axis(&plane, &sign) == -1 && sign == 0);
}

int main(void)
{
    RUN(explicit_and_tpi_points_on_dyadic_grid);
    RUN(lpi_points_against_rational_areas);
    RUN(projection_axis);
    return test_summary();
}
