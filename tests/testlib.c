#define _POSIX_C_SOURCE 200809L /* stat */

#include "testlib.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int test_failures;
int test_checks;
int test_cases;
int test_cases_failed;

void test_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    test_failures++;
    fprintf(stderr, "%s:%d: ", file, line);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

static bool skipped;

void test_skip(const char *why)
{
    printf("skipped: %s\n", why);
    skipped = true;
}

int test_summary(void)
{
    if (skipped && test_failures == 0) {
        printf("%d checks; skipped\n", test_checks);
        return TEST_SKIPPED;
    }
    if (test_checks == 0) {
        fprintf(stderr, "no check ran: a test that checks nothing fails\n");
        return 1;
    }
    printf("%d checks; test cases: %d passed, %d failed\n", test_checks,
           test_cases - test_cases_failed, test_cases_failed);
    return test_failures ? 1 : 0;
}

static const char *env_path(const char *var, const char *name)
{
    static char path[4][4096];
    static int slot;
    const char *dir = getenv(var);
    char *out = path[slot++ & 3];
    if (!dir) {
        test_fail(__FILE__, __LINE__, "environment variable %s is not set (run under ctest)",
                  var);
        dir = ".";
    }
    snprintf(out, sizeof path[0], "%s/%s", dir, name);
    return out;
}

const char *test_model(const char *name)
{
    char rel[512];
    snprintf(rel, sizeof rel, "models/%s", name);
    return env_path("MCSG_TEST_DATA", rel);
}

const char *test_shared_models_dir(void)
{
    static char path[4096];
    const char *dir = getenv("MCSG_SHARED_DIR");
    struct stat st;
    if (!dir || !*dir)
        return NULL;
    snprintf(path, sizeof path, "%s/models", dir);
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode) ? path : NULL;
}

const char *test_data(const char *name) { return env_path("MCSG_TEST_DATA", name); }

const char *test_tmp(const char *name) { return env_path("MCSG_TMP", name); }

bool test_read_string(const char *text, mcsg_format format, mcsg_mesh *out, mcsg_error *err)
{
    mcsg_status st = mcsg_mesh_read_memory(text, strlen(text), format, "string", NULL, out, err);
    return st == MCSG_OK;
}

double test_signed_volume(const mcsg_mesh *m)
{
    /* Relative to the first vertex, so that a mesh far from the origin does not lose its
     * volume to cancellation. */
    double v = 0, o[3] = {0, 0, 0};
    if (m && m->vertex_count > 0)
        memcpy(o, m->vertices, sizeof o);
    for (size_t t = 0; m && t < m->triangle_count; t++) {
        double p[3][3];
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                p[i][k] = m->vertices[3 * (size_t)m->triangles[3 * t + i] + k] - o[k];
        v += p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
             p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
             p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
    }
    return v / 6;
}

mcsg_status test_eval_scad(const char *text, const mcsg_options *opts, mcsg_mesh *out,
                           mcsg_eval_stats *stats, mcsg_error *err)
{
    mcsg_tree *tree = NULL;
    mcsg_status st = mcsg_scad_read_memory(text, strlen(text), "test.scad", ".", opts, &tree,
                                           err);
    if (st == MCSG_OK)
        st = mcsg_eval(tree, opts, out, NULL, stats, err);
    mcsg_tree_free(tree);
    return st;
}

typedef struct directed_edge {
    uint32_t from, to, tri;
} directed_edge;

static int compare_directed(const void *x, const void *y)
{
    const directed_edge *a = x, *b = y;
    if (a->from != b->from)
        return a->from < b->from ? -1 : 1;
    return (a->to > b->to) - (a->to < b->to);
}

static const directed_edge *find_directed(const directed_edge *e, size_t n, uint32_t from,
                                          uint32_t to)
{
    directed_edge key = {from, to, 0};
    return bsearch(&key, e, n, sizeof *e, compare_directed);
}

static double orient_of(const double *a, const double *b, const double *c, const double *d)
{
    double ab[3], ac[3], ad[3];
    for (int k = 0; k < 3; k++)
        ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ad[k] = d[k] - a[k];
    return ab[0] * (ac[1] * ad[2] - ac[2] * ad[1]) - ab[1] * (ac[0] * ad[2] - ac[2] * ad[0]) +
           ab[2] * (ac[0] * ad[1] - ac[1] * ad[0]);
}

void test_put_tetrahedron(const double *xyz, const uint32_t q[4], uint32_t *tris)
{
    static const int faces[4][4] = {{0, 1, 2, 3}, {0, 3, 1, 2}, {0, 2, 3, 1}, {1, 3, 2, 0}};
    for (int f = 0; f < 4; f++) {
        uint32_t a = q[faces[f][0]], b = q[faces[f][1]], c = q[faces[f][2]];
        uint32_t d = q[faces[f][3]];
        bool flip = orient_of(xyz + 3 * a, xyz + 3 * b, xyz + 3 * c, xyz + 3 * d) > 0;
        tris[3 * f] = a;
        tris[3 * f + 1] = flip ? c : b;
        tris[3 * f + 2] = flip ? b : c;
    }
}

size_t test_index_manifold_defects(const mcsg_mesh *m)
{
    size_t n = 3 * m->triangle_count, defects = 0, *seen_at;
    directed_edge *e = malloc((n + 1) * sizeof *e);
    size_t *umbrella = calloc(m->vertex_count + 1, sizeof *umbrella);
    for (size_t t = 0; t < m->triangle_count; t++)
        for (int k = 0; k < 3; k++)
            e[3 * t + k] = (directed_edge){m->triangles[3 * t + k],
                                           m->triangles[3 * t + (k + 1) % 3], (uint32_t)t};
    qsort(e, n, sizeof *e, compare_directed);
    for (size_t i = 0; i < n; i++) {
        bool repeated = (i > 0 && compare_directed(&e[i - 1], &e[i]) == 0) ||
                        (i + 1 < n && compare_directed(&e[i], &e[i + 1]) == 0);
        defects += repeated || !find_directed(e, n, e[i].to, e[i].from);
    }
    /* Umbrellas: walk around each vertex from one of its out-edges; the walk must come
     * back having visited every out-edge of the vertex. */
    seen_at = calloc(m->vertex_count + 1, sizeof *seen_at);
    for (size_t i = 0; i < n; i++)
        umbrella[e[i].from]++;
    for (size_t i = 0; i < n && defects == 0; i++) {
        uint32_t v = e[i].from, steps = 0;
        const directed_edge *at = &e[i];
        if (seen_at[v]++)
            continue;
        do { /* next out-edge around v: the one after the edge into v of this triangle */
            const uint32_t *t = m->triangles + 3 * (size_t)at->tri;
            uint32_t prev = t[0] == v ? t[2] : t[1] == v ? t[0] : t[1];
            at = find_directed(e, n, v, prev);
            steps++;
        } while (at && at != &e[i] && steps <= umbrella[v]);
        defects += !at || steps != umbrella[v];
    }
    free(seen_at);
    free(umbrella);
    free(e);
    return defects;
}

bool test_same_double(double a, double b)
{
    return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

bool test_same_mesh(const mcsg_mesh *a, const mcsg_mesh *b)
{
    if (!a || !b || a->vertex_count != b->vertex_count ||
        a->triangle_count != b->triangle_count)
        return false;
    for (size_t i = 0; i < 3 * a->vertex_count; i++)
        if (!test_same_double(a->vertices[i], b->vertices[i]))
            return false;
    for (size_t i = 0; i < 3 * a->triangle_count; i++)
        if (a->triangles[i] != b->triangles[i])
            return false;
    return true;
}

/* Counts one malloc or realloc call; false when this call is to fail. */
static bool allocation_allowed(test_allocator *a, size_t size)
{
    a->calls++;
    if (a->fail_at > 0 && (a->calls == a->fail_at || (a->sticky && a->calls > a->fail_at)))
        return false;
    if (size > a->largest)
        a->largest = size;
    return true;
}

/* The allocator functions behind test_allocator_options. */
static void *test_malloc(void *user, size_t size)
{
    test_allocator *a = user;
    void *p = allocation_allowed(a, size) ? malloc(size) : NULL;
    a->live += p != NULL;
    return p;
}

static void *test_realloc(void *user, void *ptr, size_t size)
{
    if (!ptr)
        return test_malloc(user, size);
    return allocation_allowed(user, size) ? realloc(ptr, size) : NULL;
}

static void test_free(void *user, void *ptr)
{
    ((test_allocator *)user)->live--;
    free(ptr);
}

mcsg_options test_allocator_options(test_allocator *a)
{
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    opts.allocator = (mcsg_allocator){test_malloc, test_realloc, test_free, a};
    opts.threads = 1; /* the counting allocator is not thread-safe */
    return opts;
}

/* One run with allocation `fail_at` failing; false if a check failed. Sets *clean_calls
 * to the allocation count when no allocation failed. */
static bool allocation_failure_run(const char *what, test_alloc_run run,
                                   const void *ctx, long fail_at, bool sticky,
                                   bool may_absorb, long *clean_calls)
{
    test_allocator a = {0, fail_at, sticky, 0, 0};
    mcsg_options opts = test_allocator_options(&a);
    mcsg_error err = {MCSG_OK, ""};
    int before = test_failures;
    mcsg_status st = run(ctx, &opts, &err);
    const char *mode = sticky ? " and later" : "";
    CHECK_MSG(a.live == 0, "%s: allocation %ld%s failed: %ld blocks leaked", what, fail_at,
              mode, a.live);
    if (a.calls < fail_at)
        *clean_calls = a.calls;
    else if (st == MCSG_OK)
        CHECK_MSG(may_absorb, "%s: succeeded although allocation %ld%s failed", what, fail_at,
                  mode);
    if (st != MCSG_OK) {
        CHECK_MSG(st == MCSG_ERR_NOMEM && a.calls >= fail_at,
                  "%s: allocation %ld%s failed: status %s (%ld calls): %s", what, fail_at,
                  mode, mcsg_status_string(st), a.calls, err.message);
        CHECK_CONTAINS(err.message, "out of memory");
    }
    return test_failures == before;
}

long test_allocation_failures(const char *what, test_alloc_run run, const void *ctx,
                              bool may_absorb)
{
    const long most = 100000;
    for (long n = 1; n <= most; n++) {
        long calls = -1;
        if (!allocation_failure_run(what, run, ctx, n, false, may_absorb, &calls))
            return -1;
        if (calls >= 0)
            return calls;
        if (!allocation_failure_run(what, run, ctx, n, true, may_absorb, &calls))
            return -1;
    }
    test_fail(__FILE__, __LINE__, "%s: still failing after %ld allocations", what, most);
    return -1;
}

uint64_t test_xorshift(uint64_t *state)
{
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return *state;
}

int test_random_int(uint64_t *state, int lo, int hi)
{
    return lo + (int)(test_xorshift(state) % (uint64_t)(hi - lo + 1));
}
