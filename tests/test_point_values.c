/*
 * Unit tests of csg/point_values: the scene's table of points' double-word values gives
 * exactly what mci_point_dd_values computes, keeps it, says when a point has none, and
 * still answers when its blocks cannot be allocated.
 */
#include "testlib.h"
#include "csg/point_values.h"

#include <string.h>

/* Crossings of nearly coplanar planes (ill-conditioned TPIs and LPIs), as in a Menger
 * sponge export, and one explicit point. */
typedef struct sample {
    double v[9][3];
    mci_plane planes[3];
    mci_point points[3];
} sample;

static void make_sample(sample *s)
{
    static const double v[9][3] = {
        {0, 0, 0}, {1, 0, 0}, {0, 1, 1e-13},              /* nearly z = 0 */
        {0.3, 0, 0}, {0.3, 1, 0}, {0.3 + 1e-14, 0, 1},     /* nearly x = 0.3 */
        {0, 0.7, 0}, {0, 0.7, 1}, {1, 0.7 + 1e-15, 0},     /* nearly y = 0.7 */
    };
    memcpy(s->v, v, sizeof v);
    for (int k = 0; k < 3; k++)
        mci_plane_init(&s->planes[k], s->v[3 * k], s->v[3 * k + 1], s->v[3 * k + 2]);
    CHECK(mci_point_tpi(&s->points[0], &s->planes[0], &s->planes[1], &s->planes[2]));
    CHECK(mci_point_lpi(&s->points[1], s->v[6], s->v[8], &s->planes[1]));
    mci_point_explicit(&s->points[2], s->v[5]);
}

static bool same_values(const double *got, const mci_point *p)
{
    double want[3][3];
    return got && mci_point_dd_values(p, want) && memcmp(got, want, sizeof want) == 0;
}

TEST(values_are_computed_once_and_kept)
{
    static sample s;
    mci_ctx ctx;
    mci_point_values t;
    mcsg_error err;
    double scratch[3][3];
    make_sample(&s);
    mci_ctx_init(&ctx, NULL);
    /* Ids spread over several blocks of 512. */
    CHECK(mci_point_values_init(&ctx, &t, 2000, &err) == MCSG_OK);
    for (int k = 0; k < 3; k++) {
        uint32_t id = (uint32_t)(700 * k + 5);
        const double *v;
        CHECK(mci_point_values_known(&t, id) == NULL);
        v = mci_point_values_get(&t, id, &s.points[k], scratch);
        CHECK(same_values(v, &s.points[k]));
        CHECK(v != &scratch[0][0]); /* kept in the table */
        CHECK(mci_point_values_known(&t, id) == v);
        CHECK(mci_point_values_get(&t, id, &s.points[k], scratch) == v);
    }
    mci_point_values_free(&t);
    mci_point_values_free(&t); /* freeing twice is harmless: the table was emptied */
}

TEST(point_without_values)
{
    /* Coordinates near the top of the double range leave no normal double-word value. */
    static const double huge[3] = {1e300, -1e300, 1e300};
    mci_point p;
    mci_ctx ctx;
    mci_point_values t;
    mcsg_error err;
    double scratch[3][3], direct[3][3];
    mci_point_explicit(&p, huge);
    mci_ctx_init(&ctx, NULL);
    CHECK(!mci_point_dd_values(&p, direct));
    CHECK(mci_point_values_init(&ctx, &t, 1, &err) == MCSG_OK);
    CHECK(mci_point_values_get(&t, 0, &p, scratch) == NULL);
    CHECK(mci_point_values_known(&t, 0) == NULL);
    CHECK(mci_point_values_get(&t, 0, &p, scratch) == NULL);
    mci_point_values_free(&t);
}

/* Without its blocks the table still answers, from the caller's scratch; failing the
 * table itself is MCSG_ERR_NOMEM with nothing left allocated. */
static mcsg_status use_table(const void *user, const mcsg_options *opts, mcsg_error *err)
{
    const sample *s = user;
    mci_ctx ctx;
    mci_point_values t;
    double scratch[3][3];
    mcsg_status st;
    mci_ctx_init(&ctx, opts);
    st = mci_point_values_init(&ctx, &t, 1100, err);
    if (st != MCSG_OK)
        return st;
    for (int k = 0; k < 3; k++) {
        const double *v = mci_point_values_get(&t, (uint32_t)(520 * k), &s->points[k], scratch);
        CHECK(same_values(v, &s->points[k]));
    }
    mci_point_values_free(&t);
    return MCSG_OK;
}

TEST(allocation_failures)
{
    static sample s;
    make_sample(&s);
    CHECK(test_allocation_failures("point values", use_table, &s, true) > 0);
}

int main(void)
{
    RUN(values_are_computed_once_and_kept);
    RUN(point_without_values);
    RUN(allocation_failures);
    return test_summary();
}
