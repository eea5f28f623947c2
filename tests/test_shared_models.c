/*
 * Optional checks on the larger models of ../shared/models (next to a checkout; found
 * through MCSG_SHARED_DIR), which are not part of the project: skipped, and reported as
 * skipped by CTest, when the folder is missing. The suite's own models are tested by the
 * other tests (tests/data/models).
 *
 * - every model reads with the counts of models/README.md, and no OBJ goes unlisted;
 * - every model is closed, outward, manifold, one component; removing or flipping one
 *   triangle is caught;
 * - the smaller scans have no self-intersections;
 * - the bunny minus a copy rotated by 1e-7 rad: |A - B| + |A n B| = |A|.
 */
#include "testlib.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

static const struct {
    const char *name;
    size_t vertices, triangles;
} models[] = {
    {"armadillo.obj", 49999, 99994}, {"bunny.obj", 14290, 28576},
    {"bunny25k.obj", 12500, 24996},  {"bunny50k.obj", 25000, 49996},
    {"bunny100k.obj", 50000, 99996}, {"cow.obj", 2930, 5856},
    {"cow25k.obj", 12500, 24996},    {"cow50k.obj", 25000, 49996},
    {"cow100K.obj", 50000, 99996},   {"sphere1.obj", 1442, 2880},
    {"sphere2.obj", 1442, 2880},     {"cube.obj", 8, 12},
};
#define MODEL_COUNT (sizeof models / sizeof models[0])

static const char *shared_model(const char *dir, const char *name)
{
    static char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return path;
}

static bool read_model(const char *dir, const char *name, mcsg_mesh *m)
{
    mcsg_error err;
    mcsg_status st = mcsg_mesh_read(shared_model(dir, name), MCSG_FORMAT_AUTO, NULL, m, &err);
    CHECK_MSG(st == MCSG_OK, "%s", err.message);
    return st == MCSG_OK;
}

static mcsg_check_report check(const mcsg_mesh *m)
{
    mcsg_check_report r;
    mcsg_error err;
    memset(&r, 0, sizeof r);
    CHECK_OK(mcsg_mesh_check(m, NULL, &r, &err), &err);
    return r;
}

static void every_model_is_listed(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *entry;
    CHECK(d != NULL);
    while (d && (entry = readdir(d)) != NULL) {
        size_t len = strlen(entry->d_name), i = 0;
        if (len < 4 || strcmp(entry->d_name + len - 4, ".obj") != 0)
            continue;
        while (i < MODEL_COUNT && strcmp(models[i].name, entry->d_name) != 0)
            i++;
        CHECK_MSG(i < MODEL_COUNT, "%s is not in the table of expected counts", entry->d_name);
    }
    if (d)
        closedir(d);
}

static void model_is_clean(const char *name, mcsg_mesh *m)
{
    mcsg_check_report r = check(m);
    CHECK_MSG(mcsg_check_report_is_valid(&r) && !r.inverted && r.volume > 0,
              "%s is not clean", name);
    CHECK_EQ_SIZE(r.components, 1);
    m->triangle_count--;
    r = check(m);
    CHECK_EQ_SIZE(r.boundary_edges, 3);
    m->triangle_count++;
    mcsg_mesh_flip(&(mcsg_mesh){m->vertices, m->triangles + 3, m->vertex_count, 1});
    r = check(m);
    CHECK_EQ_SIZE(r.inconsistent_edges, 3);
    mcsg_mesh_flip(&(mcsg_mesh){m->vertices, m->triangles + 3, m->vertex_count, 1});
}

TEST(models_read_with_their_counts_and_validate)
{
    const char *dir = test_shared_models_dir();
    every_model_is_listed(dir);
    for (size_t i = 0; i < MODEL_COUNT; i++) {
        mcsg_mesh m;
        if (!read_model(dir, models[i].name, &m))
            continue;
        CHECK_MSG(m.vertex_count == models[i].vertices &&
                      m.triangle_count == models[i].triangles,
                  "%s: %zu vertices, %zu triangles", models[i].name, m.vertex_count,
                  m.triangle_count);
        model_is_clean(models[i].name, &m);
        mcsg_mesh_free(&m, NULL);
    }
}

TEST(scans_do_not_intersect_themselves)
{
    static const char *names[] = {"sphere1.obj", "cow.obj", "bunny.obj"};
    const char *dir = test_shared_models_dir();
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        mcsg_mesh m;
        mcsg_error err;
        size_t pairs = 1;
        if (!read_model(dir, names[i], &m))
            continue;
        CHECK_OK(mcsg_mesh_self_intersections(&m, NULL, &pairs, NULL, &err), &err);
        CHECK_MSG(pairs == 0, "%s intersects itself", names[i]);
        mcsg_mesh_free(&m, NULL);
    }
}

/* Evaluates `text` and returns the volume of a closed, oriented result (NAN otherwise);
 * edges shared by touching parts are allowed (the difference pinches to nothing where
 * the surface is parallel to the motion). */
static double closed_volume(const char *text)
{
    mcsg_mesh out;
    mcsg_error err;
    mcsg_check_report r;
    double v = NAN;
    if (test_eval_scad(text, NULL, &out, NULL, &err) != MCSG_OK) {
        CHECK_MSG(false, "%s", err.message);
        return v;
    }
    r = check(&out);
    CHECK_MSG(r.boundary_edges == 0 && r.inconsistent_edges == 0 &&
                  r.degenerate_triangles == 0,
              "%zu boundary, %zu inconsistent edges, %zu degenerate triangles",
              r.boundary_edges, r.inconsistent_edges, r.degenerate_triangles);
    v = test_signed_volume(&out);
    mcsg_mesh_free(&out, NULL);
    return v;
}

TEST(bunny_minus_a_copy_rotated_by_1e_7)
{
    char model[4300], diff[9000], inter[9000];
    double va, vd, vi;
    snprintf(model, sizeof model, "import(\"%s\");",
             shared_model(test_shared_models_dir(), "bunny.obj"));
    snprintf(diff, sizeof diff, "difference() { %s rotate(a=5.729577951308232e-6, "
             "v=[1,2,3]) %s }", model, model);
    snprintf(inter, sizeof inter, "intersection() { %s rotate(a=5.729577951308232e-6, "
             "v=[1,2,3]) %s }", model, model);
    va = closed_volume(model);
    vd = closed_volume(diff);
    vi = closed_volume(inter);
    CHECK_MSG(fabs(vd + vi - va) <= 1e-12 * va, "%.17g + %.17g vs %.17g", vd, vi, va);
    CHECK(vd < 1e-4 * va);
}

int main(void)
{
    if (!test_shared_models_dir()) {
        test_skip("no shared models folder (MCSG_SHARED_DIR/models, ../shared/models "
                  "next to the checkout); the suite's own models are in tests/data/models");
        return test_summary();
    }
    RUN(models_read_with_their_counts_and_validate);
    RUN(scans_do_not_intersect_themselves);
    RUN(bunny_minus_a_copy_rotated_by_1e_7);
    return test_summary();
}
