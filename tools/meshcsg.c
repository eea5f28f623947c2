/*
 * meshcsg command-line tool: a thin client of the public API (include/meshcsg.h). The
 * commands and their options are the tables at the end of this file (`commands`), which
 * `meshcsg --help` and `meshcsg CMD --help` print; tools/cli_options.c parses them.
 *
 * Exit status: 0 on success (check: every mesh valid), 1 when a check finds a problem
 * or an operation fails, 2 on a usage error, 3 when eval wrote a result that rounding to
 * doubles made break a guarantee.
 */
#define _POSIX_C_SOURCE 200809L

#include "cli_options.h"
#include "meshcsg.h"
#include "picture.h"
#include "scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <pthread.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#define EXIT_PROBLEM CLI_EXIT_PROBLEM
#define EXIT_USAGE CLI_EXIT_USAGE
#define EXIT_BROKEN_GUARANTEE CLI_EXIT_BROKEN_GUARANTEE
#define DEMO_SPHERES 200

/* user: the lowest level printed, or NULL for warnings only. */
static void log_to_stderr(void *user, mcsg_log_level level, const char *message)
{
    const mcsg_log_level *lowest = user;
    if (level >= MCSG_LOG_WARNING)
        fprintf(stderr, "meshcsg: warning: %s\n", message);
    else if (lowest && level >= *lowest)
        fprintf(stderr, "meshcsg: %s\n", message);
}

static mcsg_options cli_options(void)
{
    mcsg_options opts;
    memset(&opts, 0, sizeof opts);
    opts.log = log_to_stderr;
    return opts;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n >= e && strcasecmp(path + n - e, ext) == 0;
}

static int is_csg_file(const char *path)
{
    return has_extension(path, ".scad") || has_extension(path, ".csg");
}

static void fail_line(const mcsg_error *err)
{
    fprintf(stderr, "meshcsg: %s\n", err->message);
}

/* ---------------------------------------------------------------------------------- */
/* pictures (picture, eval --picture)                                                  */

typedef struct picture_request {
    picture_view view;
    int width, height;
} picture_request;

/* --view and --size of command `cmd`; false after a usage error. */
static int picture_options(const char *cmd, const cli_values *v, picture_request *r)
{
    r->view = VIEW_ISO, r->width = 800, r->height = 600;
    if (v->view && !picture_view_parse(v->view, &r->view)) {
        fprintf(stderr, "meshcsg %s: --view takes iso, top, front or side: %s (see meshcsg "
                "%s --help)\n", cmd, v->view, cmd);
        return 0;
    }
    if (v->size && !picture_size_parse(v->size, &r->width, &r->height)) {
        fprintf(stderr, "meshcsg %s: --size takes WxH, each from 16 to 8192: %s (see "
                "meshcsg %s --help)\n", cmd, v->size, cmd);
        return 0;
    }
    return 1;
}

/* Draws the mesh (faces coloured by group, NULL: one colour) into a PNG at path. */
static int write_picture(const mcsg_mesh *mesh, const uint32_t *group,
                         const picture_request *r, int edges, const char *path)
{
    picture pic;
    char why[256];
    if (!picture_draw(mesh, group, r->view, r->width, r->height, edges, &pic)) {
        fprintf(stderr, "meshcsg: out of memory drawing %s\n", path);
        return 0;
    }
    int ok = picture_write_png(&pic, path, why, sizeof why);
    picture_free(&pic);
    if (!ok)
        fprintf(stderr, "meshcsg: %s: %s\n", path, why);
    return ok;
}

/* The leaf of every triangle, from provenance (NULL when out of memory). */
static uint32_t *leaf_groups(const mcsg_provenance *prov, size_t count)
{
    uint32_t *group = malloc((count ? count : 1) * sizeof *group);
    for (size_t t = 0; group && t < count; t++)
        group[t] = prov[t].leaf;
    return group;
}

static int cmd_picture(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    picture_request r;
    mcsg_mesh mesh;
    mcsg_error err;
    int ok;
    (void)argc;
    if (!picture_options("picture", v, &r))
        return EXIT_USAGE;
    if (mcsg_mesh_read(argv[0], MCSG_FORMAT_AUTO, &opts, &mesh, &err) != MCSG_OK) {
        fail_line(&err);
        return EXIT_PROBLEM;
    }
    ok = write_picture(&mesh, NULL, &r, v->edges, argv[1]);
    mcsg_mesh_free(&mesh, &opts);
    return ok ? 0 : EXIT_PROBLEM;
}

/* ---------------------------------------------------------------------------------- */
/* check                                                                               */

static void print_vertex(const mcsg_mesh *m, uint32_t v)
{
    const double *p = m->vertices + 3 * (size_t)v;
    printf("vertex %u (%.17g %.17g %.17g)", v, p[0], p[1], p[2]);
}

static void print_edge_problem(const char *name, const mcsg_mesh *m, size_t count,
                               const uint32_t edge[2], const char *what)
{
    if (!count)
        return;
    printf("%s: error: %zu %s, e.g. between ", name, count, what);
    print_vertex(m, edge[0]);
    printf(" and ");
    print_vertex(m, edge[1]);
    printf("\n");
}

static void print_triangle_problem(const char *name, size_t count, uint32_t example,
                                   const char *what)
{
    if (count)
        printf("%s: error: %zu %s, e.g. triangle %u\n", name, count, what, example);
}

static void print_problems(const char *name, const mcsg_mesh *m, const mcsg_check_report *r)
{
    if (r->triangle_count == 0)
        printf("%s: error: the mesh has no triangles\n", name);
    print_triangle_problem(name, r->out_of_range_indices, r->example_out_of_range_triangle,
                           "triangle corners reference no vertex (index out of range)");
    if (r->nonfinite_vertices)
        printf("%s: error: %zu vertices have NaN or infinite coordinates, e.g. vertex %u\n",
               name, r->nonfinite_vertices, r->example_nonfinite_vertex);
    print_triangle_problem(name, r->degenerate_triangles, r->example_degenerate_triangle,
                           "degenerate triangles (zero area)");
    print_triangle_problem(name, r->duplicate_triangles, r->example_duplicate_triangle,
                           "duplicate triangles (same three vertices as another)");
    print_edge_problem(name, m, r->boundary_edges, r->example_boundary_edge,
                       "boundary edges (the surface is open)");
    print_edge_problem(name, m, r->nonmanifold_edges, r->example_nonmanifold_edge,
                       "non-manifold edges (shared by more than two triangles)");
    print_edge_problem(name, m, r->inconsistent_edges, r->example_inconsistent_edge,
                       "inconsistently oriented edges (neighbours face opposite ways)");
    if (r->nonmanifold_edges && !r->unbalanced_edges && !r->boundary_edges &&
        !r->inconsistent_edges && !r->self_touching_edges)
        printf("%s: note: closed as a chain (each edge used as often one way as the other): "
               "eval and repair take it as %zu shells\n", name, r->components);
}

/* Check one mesh; flips it in place when it is consistently inverted. Returns 1 when
 * the mesh is valid. */
/* With --self-intersections: 1 when no two triangles intersect (exactly). */
static int check_self_intersections(const char *name, const mcsg_mesh *m,
                                    const mcsg_options *opts)
{
    size_t pairs;
    uint32_t example[2];
    mcsg_error err;
    if (mcsg_mesh_self_intersections(m, opts, &pairs, example, &err) != MCSG_OK) {
        fail_line(&err);
        return 0;
    }
    if (pairs == 0) {
        printf("%s: ok: no self-intersections\n", name);
        return 1;
    }
    printf("%s: error: %zu pairs of triangles intersect each other, e.g. triangles %u and %u\n",
           name, pairs, example[0], example[1]);
    return 0;
}

static int check_mesh(const char *name, mcsg_mesh *m, const mcsg_options *opts, int self)
{
    mcsg_check_report r;
    mcsg_error err;
    if (mcsg_mesh_check(m, opts, &r, &err) != MCSG_OK) {
        fail_line(&err);
        return 0;
    }
    if (!mcsg_check_report_is_valid(&r)) {
        print_problems(name, m, &r);
        /* The exact test needs only valid indices and finite coordinates. */
        if (self && r.out_of_range_indices == 0 && r.nonfinite_vertices == 0)
            check_self_intersections(name, m, opts);
        return 0;
    }
    if (r.volume_sign == 0) {
        printf("%s: error: the mesh encloses no volume (its triangles fold onto each other)\n",
               name);
        return 0;
    }
    if (r.inverted) {
        mcsg_mesh_flip(m);
        printf("%s: warning: the mesh is inside out (volume %.17g): every triangle faces "
               "inward; flipped\n", name, r.volume);
        r.volume = -r.volume;
    }
    printf("%s: ok: %zu vertices, %zu triangles, %zu component%s, volume %.17g\n", name,
           r.vertex_count, r.triangle_count, r.components, r.components == 1 ? "" : "s",
           r.volume);
    if (r.duplicate_vertices)
        printf("%s: note: %zu vertices repeat the coordinates of another vertex\n", name,
               r.duplicate_vertices);
    if (r.unused_vertices)
        printf("%s: note: %zu vertices are used by no triangle\n", name, r.unused_vertices);
    return !self || check_self_intersections(name, m, opts);
}

static int check_csg_file(const char *path, const mcsg_options *opts, int self)
{
    mcsg_tree *tree;
    mcsg_error err;
    int valid = 1;
    if (mcsg_scad_read(path, opts, &tree, &err) != MCSG_OK) {
        fail_line(&err);
        return 0;
    }
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++) {
        const mcsg_mesh *leaf = mcsg_tree_leaf_mesh(tree, id);
        mcsg_mesh copy;
        char name[1024];
        if (!leaf || leaf->triangle_count == 0)
            continue; /* empty leaves (e.g. sphere(r=0)) are the empty set, not errors */
        snprintf(name, sizeof name, "%s: leaf %s", path, mcsg_tree_node_label(tree, id));
        if (mcsg_mesh_copy(leaf, opts, &copy, &err) != MCSG_OK) {
            fail_line(&err);
            valid = 0;
            break;
        }
        valid &= check_mesh(name, &copy, opts, self);
        mcsg_mesh_free(&copy, opts);
    }
    mcsg_tree_free(tree);
    return valid;
}

static int check_mesh_file(const char *path, const char *fixed_out, const mcsg_options *opts,
                           int self)
{
    mcsg_mesh mesh;
    mcsg_error err;
    int valid;
    if (mcsg_mesh_read(path, MCSG_FORMAT_AUTO, opts, &mesh, &err) != MCSG_OK) {
        fail_line(&err);
        return 0;
    }
    valid = check_mesh(path, &mesh, opts, self);
    if (valid && fixed_out &&
        mcsg_mesh_write(fixed_out, MCSG_FORMAT_AUTO, &mesh, opts, &err) != MCSG_OK) {
        fail_line(&err);
        valid = 0;
    }
    mcsg_mesh_free(&mesh, opts);
    return valid;
}

static int cmd_check(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    int all_valid = 1;
    if (v->output && argc != 1) {
        fprintf(stderr, "meshcsg check: -o writes one fixed mesh: give exactly one FILE "
                "(see meshcsg check --help)\n");
        return EXIT_USAGE;
    }
    for (int i = 0; i < argc; i++)
        all_valid &= is_csg_file(argv[i])
                         ? check_csg_file(argv[i], &opts, v->self_intersections)
                         : check_mesh_file(argv[i], v->output, &opts, v->self_intersections);
    return all_valid ? 0 : EXIT_PROBLEM;
}

/* ---------------------------------------------------------------------------------- */
/* tree                                                                                */

typedef struct tree_stats {
    size_t leaves, faces, min_faces, max_faces, max_depth;
} tree_stats;

/* Indentation is capped so that a 10,000-deep tree prints lines of bounded width. */
#define MAX_INDENT 32

static void print_node(const mcsg_tree *tree, mcsg_node_id id, size_t depth,
                       tree_stats *stats)
{
    size_t indent = depth < MAX_INDENT ? depth : MAX_INDENT;
    mcsg_node_kind kind = mcsg_tree_node_kind(tree, id);
    printf("%*s", (int)(2 * indent), "");
    if (depth > MAX_INDENT)
        printf("[depth %zu] ", depth);
    if (kind == MCSG_NODE_LEAF) {
        size_t faces = mcsg_tree_leaf_mesh(tree, id)->triangle_count;
        printf("leaf %u: %s, %zu triangles\n", id, mcsg_tree_node_label(tree, id), faces);
        stats->leaves++;
        stats->faces += faces;
        stats->min_faces = faces < stats->min_faces ? faces : stats->min_faces;
        stats->max_faces = faces > stats->max_faces ? faces : stats->max_faces;
    } else {
        printf("%s (%zu children)  %s\n", mcsg_node_kind_name(kind),
               mcsg_tree_child_count(tree, id), mcsg_tree_node_label(tree, id));
    }
    if (depth > stats->max_depth)
        stats->max_depth = depth;
}

typedef struct stack_entry {
    mcsg_node_id node;
    size_t depth;
} stack_entry;

/* Depth-first, children in order, with an explicit stack: trees may be very deep. */
static int print_tree(const mcsg_tree *tree, tree_stats *stats)
{
    size_t n = mcsg_tree_node_count(tree), top = 0;
    stack_entry *stack = malloc((n + 1) * sizeof *stack);
    if (!stack)
        return 0;
    if (mcsg_tree_root(tree) != MCSG_NO_NODE)
        stack[top++] = (stack_entry){mcsg_tree_root(tree), 0};
    while (top > 0) {
        stack_entry e = stack[--top];
        size_t children = mcsg_tree_child_count(tree, e.node);
        print_node(tree, e.node, e.depth, stats);
        for (size_t i = children; i-- > 0;)
            stack[top++] = (stack_entry){mcsg_tree_child(tree, e.node, i), e.depth + 1};
    }
    free(stack);
    return 1;
}

static int cmd_tree(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    tree_stats stats = {0, 0, SIZE_MAX, 0, 0};
    mcsg_tree *tree;
    mcsg_error err;
    (void)v, (void)argc;
    if (mcsg_scad_read(argv[0], &opts, &tree, &err) != MCSG_OK) {
        fail_line(&err);
        return EXIT_PROBLEM;
    }
    if (!print_tree(tree, &stats)) {
        fprintf(stderr, "meshcsg: out of memory printing the tree\n");
        mcsg_tree_free(tree);
        return EXIT_PROBLEM;
    }
    printf("%zu nodes, %zu leaves, %zu triangles (per leaf: min %zu, max %zu), depth %zu\n",
           mcsg_tree_node_count(tree), stats.leaves, stats.faces,
           stats.leaves ? stats.min_faces : 0, stats.max_faces, stats.max_depth);
    mcsg_tree_free(tree);
    return 0;
}

/* ---------------------------------------------------------------------------------- */
/* convert                                                                             */

static const struct {
    const char *name;
    mcsg_format format;
} format_names[] = {
    {"off", MCSG_FORMAT_OFF},
    {"obj", MCSG_FORMAT_OBJ},
    {"stl", MCSG_FORMAT_STL_BINARY},
    {"stl-binary", MCSG_FORMAT_STL_BINARY},
    {"stl-ascii", MCSG_FORMAT_STL_ASCII},
    {"ply", MCSG_FORMAT_PLY_BINARY_LE},
    {"ply-binary", MCSG_FORMAT_PLY_BINARY_LE},
    {"ply-binary-be", MCSG_FORMAT_PLY_BINARY_BE},
    {"ply-ascii", MCSG_FORMAT_PLY_ASCII},
    {"3mf", MCSG_FORMAT_3MF},
};

static int parse_format(const char *name, mcsg_format *out)
{
    for (size_t i = 0; i < sizeof format_names / sizeof format_names[0]; i++) {
        if (strcasecmp(name, format_names[i].name) == 0) {
            *out = format_names[i].format;
            return 1;
        }
    }
    return 0;
}

static int cmd_convert(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    mcsg_format format = MCSG_FORMAT_AUTO;
    const char *paths[2] = {argv[0], argv[1]};
    mcsg_mesh mesh;
    mcsg_error err;
    (void)argc;
    if (v->format && !parse_format(v->format, &format)) {
        fprintf(stderr, "meshcsg convert: unknown format '%s' (off, obj, stl, stl-ascii, "
                "stl-binary, ply, ply-ascii, ply-binary, ply-binary-be, 3mf)\n", v->format);
        return EXIT_USAGE;
    }
    if (format == MCSG_FORMAT_AUTO && mcsg_format_from_path(paths[1]) == MCSG_FORMAT_AUTO) {
        fprintf(stderr, "meshcsg: %s: cannot tell the output format from the extension; "
                "use .off .obj .stl .ply .3mf or --format\n", paths[1]);
        return EXIT_USAGE;
    }
    if (mcsg_mesh_read(paths[0], MCSG_FORMAT_AUTO, &opts, &mesh, &err) != MCSG_OK) {
        fail_line(&err);
        return EXIT_PROBLEM;
    }
    if (mcsg_mesh_write(paths[1], format, &mesh, &opts, &err) != MCSG_OK) {
        fail_line(&err);
        mcsg_mesh_free(&mesh, &opts);
        return EXIT_PROBLEM;
    }
    printf("%s -> %s: %zu vertices, %zu triangles\n", paths[0], paths[1], mesh.vertex_count,
           mesh.triangle_count);
    mcsg_mesh_free(&mesh, &opts);
    return 0;
}

/* ---------------------------------------------------------------------------------- */
/* intersect                                                                           */

/* Curves as OBJ: one `v` per distinct point, one `l` per segment. */
static int write_curves_obj(const char *path, const mcsg_curves *c)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "meshcsg: %s: cannot create\n", path);
        return 0;
    }
    fprintf(f, "# meshcsg intersection curves: %zu points, %zu segments\n", c->point_count,
            c->segment_count);
    for (size_t i = 0; i < c->point_count; i++)
        fprintf(f, "v %.17g %.17g %.17g\n", c->points[3 * i], c->points[3 * i + 1],
                c->points[3 * i + 2]);
    for (size_t i = 0; i < c->segment_count; i++)
        fprintf(f, "l %u %u\n", c->segments[2 * i] + 1, c->segments[2 * i + 1] + 1);
    return fclose(f) == 0;
}

/* Points where an odd number of segments meet: zero when every curve is closed. */
static size_t odd_degree_points(const mcsg_curves *c)
{
    size_t odd = 0;
    unsigned char *parity = calloc(c->point_count + 1, 1);
    if (!parity)
        return SIZE_MAX;
    for (size_t i = 0; i < 2 * c->segment_count; i++)
        parity[c->segments[i]] ^= 1;
    for (size_t i = 0; i < c->point_count; i++)
        odd += parity[i];
    free(parity);
    return odd;
}

static void print_intersect_stats(const mcsg_intersect_stats *s, const mcsg_curves *c)
{
    printf("faces %zu, octree cells %zu (critical leaf cells %zu)\n", s->faces, s->cells,
           s->critical_cells);
    printf("candidate pairs %zu, intersecting pairs %zu, single-point contacts %zu, "
           "coplanar overlapping pairs %zu\n", s->candidate_pairs, s->intersecting_pairs,
           s->point_contacts, s->coplanar_pairs);
    printf("arranged faces %zu, segments %zu, distinct points %zu, points of odd degree %zu\n",
           s->arranged_faces, c->segment_count, c->point_count, odd_degree_points(c));
    printf("time: octree %.3f s, pairs %.3f s, intersect %.3f s, arrange %.3f s, "
           "merge %.3f s\n", s->seconds_octree, s->seconds_pairs, s->seconds_intersect,
           s->seconds_arrange, s->seconds_merge);
}

static int cmd_intersect(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    const char *in = argv[0], *out = v->output;
    mcsg_tree *tree;
    mcsg_curves curves;
    mcsg_intersect_stats stats;
    mcsg_error err;
    int ok;
    (void)argc;
    if (mcsg_scad_read(in, &opts, &tree, &err) != MCSG_OK) {
        fail_line(&err);
        return EXIT_PROBLEM;
    }
    if (mcsg_intersect(tree, &opts, &curves, &stats, &err) != MCSG_OK) {
        fail_line(&err);
        mcsg_tree_free(tree);
        return EXIT_PROBLEM;
    }
    print_intersect_stats(&stats, &curves);
    ok = !out || write_curves_obj(out, &curves);
    mcsg_curves_free(&curves, &opts);
    mcsg_tree_free(tree);
    return ok ? 0 : EXIT_PROBLEM;
}

/* ---------------------------------------------------------------------------------- */
/* demo                                                                                */

/* ---------------------------------------------------------------------------------- */
/* Progress: when stderr is a terminal and the work has run for more than a second, a
 * line names the step under way, how far along the steps it is and the time so far (a
 * ticker thread redraws it from the step the library last reported). */

typedef struct progress_state {
    pthread_mutex_t lock;
    pthread_t thread;
    const char *step;
    int step_number; /* 1.. among EVAL_STEPS, 0 for a step not in the list */
    double started;
    int shown, quit, running;
} progress_state;

static progress_state progress;

/* mcsg_eval's steps in order (mcsg_progress_fn); a rounding round comes after them. */
static const char *const EVAL_STEPS[] = {"check", "intersect", "triangulate", "classify",
                                         "assemble"};
#define EVAL_STEP_COUNT ((int)(sizeof EVAL_STEPS / sizeof *EVAL_STEPS))

static int eval_step_number(const char *step)
{
    for (int k = 0; k < EVAL_STEP_COUNT; k++)
        if (strcmp(step, EVAL_STEPS[k]) == 0)
            return k + 1;
    return 0;
}

static void clear_progress_line(void)
{
    if (progress.shown)
        fprintf(stderr, "\r%72s\r", "");
    progress.shown = 0;
}

static int on_progress(void *user, const char *step, int done)
{
    (void)user;
    pthread_mutex_lock(&progress.lock);
    clear_progress_line();
    progress.step = done ? NULL : step;
    if (!done)
        progress.step_number = eval_step_number(step);
    pthread_mutex_unlock(&progress.lock);
    return 0;
}

static void draw_progress(void)
{
    double seconds = now_seconds() - progress.started;
    if (progress.step_number > 0)
        fprintf(stderr, "\rmeshcsg: step %d of %d (%s), %.0f s ", progress.step_number,
                EVAL_STEP_COUNT, progress.step, seconds);
    else
        fprintf(stderr, "\rmeshcsg: %s, %.0f s ", progress.step, seconds);
    progress.shown = 1;
}

static void *progress_ticker(void *arg)
{
    struct timespec tick = {0, 250000000};
    (void)arg;
    for (;;) {
        nanosleep(&tick, NULL);
        pthread_mutex_lock(&progress.lock);
        if (progress.quit) {
            pthread_mutex_unlock(&progress.lock);
            return NULL;
        }
        if (progress.step && now_seconds() - progress.started > 1.0)
            draw_progress();
        pthread_mutex_unlock(&progress.lock);
    }
}

/* quiet: no progress line (--quiet). */
static void start_progress(mcsg_options *opts, int quiet)
{
    if (quiet || !isatty(2) || pthread_mutex_init(&progress.lock, NULL) != 0)
        return;
    progress.started = now_seconds();
    progress.step = NULL;
    progress.quit = 0;
    if (pthread_create(&progress.thread, NULL, progress_ticker, NULL) != 0) {
        pthread_mutex_destroy(&progress.lock);
        return;
    }
    progress.running = 1;
    opts->progress = on_progress;
}

static void stop_progress(void)
{
    if (!progress.running)
        return;
    pthread_mutex_lock(&progress.lock);
    progress.quit = 1;
    clear_progress_line();
    pthread_mutex_unlock(&progress.lock);
    pthread_join(progress.thread, NULL);
    pthread_mutex_destroy(&progress.lock);
    progress.running = 0;
}

/* ---------------------------------------------------------------------------------- */

/* Peak resident memory of this program: VmHWM from /proc/self/status where there is
 * one (getrusage's ru_maxrss also counts the memory of the process that ran us before
 * exec, e.g. a benchmark driver), else ru_maxrss. */
static double peak_memory_mib(void)
{
    char line[256];
    double kib = -1;
    struct rusage ru;
    FILE *f = fopen("/proc/self/status", "r");
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "VmHWM: %lf kB", &kib) == 1)
            break;
    if (f)
        fclose(f);
    if (kib >= 0)
        return kib / 1024.0;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0;
    return (double)ru.ru_maxrss / 1024.0; /* Linux reports KiB */
}

/* The paper's Table 1 columns: faces, primitives, time per step and in total. */
static void print_eval_stats(const mcsg_eval_stats *s, double read_seconds)
{
    const mcsg_intersect_stats *x = &s->intersect;
    printf("primitives %zu, faces %zu (min %zu, max %zu per primitive)\n", s->primitives,
           s->faces, s->faces_min, s->faces_max);
    if (read_seconds >= 0)
        printf("  read input       %8.3f s\n", read_seconds);
    if (s->frames_evaluated && !s->frames_flattened)
        printf("  frames           %8.3f s  (%zu groups under a turning transform evaluated "
               "in their own coordinates first; the lines below are the last evaluation's, "
               "with their results as leaves)\n", s->seconds_frames, s->frames_evaluated);
    else if (s->frames_evaluated)
        printf("  frames           %8.3f s  (%zu groups under a turning transform evaluated "
               "in their own coordinates first, which failed or broke more guarantees; the lines "
               "below are the evaluation of the tree with each leaf turned on its own)\n",
               s->seconds_frames, s->frames_evaluated);
    printf("  positive tree    %8.3f s\n", s->seconds_tree);
    printf("  input check      %8.3f s\n", s->seconds_check);
    printf("  octree           %8.3f s  (%zu cells)\n", x->seconds_octree, x->cells);
    printf("  candidate pairs  %8.3f s  (%zu)\n", x->seconds_pairs, x->candidate_pairs);
    printf("  intersect        %8.3f s  (%zu crossing, %zu coplanar pairs)\n",
           x->seconds_intersect, x->intersecting_pairs, x->coplanar_pairs);
    printf("  arrange faces    %8.3f s  (%zu faces)\n", x->seconds_arrange, x->arranged_faces);
    printf("  whole faces      %8.3f s  (%zu touched faces dropped whole)\n",
           s->seconds_whole_faces, s->faces_dropped_whole);
    printf("  number points    %8.3f s\n", x->seconds_merge);
    printf("  triangulate      %8.3f s  (%zu pieces)\n", s->seconds_triangulate, s->pieces);
    printf("  classify         %8.3f s  (%zu regions, %zu rays, %zu local tests, "
           "%zu primitives dropped whole)\n", s->seconds_classify, s->regions, s->rays,
           s->local_tests, s->rejected_primitives);
    printf("  assemble         %8.3f s  (%zu vertices, %zu triangles; %zu flat vertices "
           "removed)\n", s->seconds_assemble, s->output_vertices, s->output_triangles,
           s->flat_vertices_removed);
    printf("  output triangles %zu, smallest angle %.3g degrees, %zu with an angle under 1 "
           "degree\n", s->output_triangles, s->output_smallest_angle, s->output_needles);
    if (s->rounding_joined_vertices + s->rounding_dropped_triangles +
        s->rounding_split_triangles + s->rounding_flat_triangles + s->rounding_turned_triangles)
        printf("  rounding to doubles: %zu vertices joined, %zu triangles collapsed or folded "
               "and dropped, %zu flat ones split away, %zu flat left, %zu turned over and "
               "split away\n", s->rounding_joined_vertices, s->rounding_dropped_triangles,
               s->rounding_split_triangles, s->rounding_flat_triangles,
               s->rounding_turned_triangles);
    if (s->rounding_dropped_shells)
        printf("  rounding to doubles: %zu flat or inside-out shells removed\n",
               s->rounding_dropped_shells);
    if (s->touching_vertices_split)
        printf("  touching parts: %zu vertices given separate copies\n",
               s->touching_vertices_split);
    if (s->rounding_separated_vertices)
        printf("  touching or crossing made by rounding: %zu vertices moved by one unit in "
               "the last place\n", s->rounding_separated_vertices);
    if (s->rounding_reevaluations)
        printf("  rounding broke a guarantee: the rounded result evaluated again %zu times, "
               "%s\n", s->rounding_reevaluations,
               s->rounding_reevaluation_kept ? "a round's mesh kept" : "none kept");
    if (s->rounding_snap_grid > 0)
        printf("  rounding broke a guarantee: vertices snapped to a grid of spacing %g\n",
               s->rounding_snap_grid);
    printf("  total            %8.3f s\n", s->seconds_total);
}

/* Read, evaluate and write one CSG file with the given options and eval's command-line
 * values (--quiet: print nothing but errors and the requested stats). */
static int eval_file(mcsg_options *opts, const char *in, const cli_values *v,
                     const picture_request *draw)
{
    const char *out = v->output;
    int ok;
    mcsg_provenance *prov = NULL;
    double read_seconds, write_seconds;
    mcsg_status st;
    mcsg_tree *tree;
    mcsg_mesh result;
    mcsg_eval_stats stats;
    mcsg_error err;
    read_seconds = now_seconds();
    if (mcsg_scad_read(in, opts, &tree, &err) != MCSG_OK) {
        fail_line(&err);
        return EXIT_PROBLEM;
    }
    read_seconds = now_seconds() - read_seconds;
    start_progress(opts, v->quiet);
    st = mcsg_eval(tree, opts, &result, v->picture ? &prov : NULL, &stats, &err);
    stop_progress();
    if (st != MCSG_OK) {
        fail_line(&err);
        mcsg_tree_free(tree);
        return EXIT_PROBLEM;
    }
    write_seconds = now_seconds();
    ok = !out || mcsg_mesh_write(out, MCSG_FORMAT_AUTO, &result, opts, &err) == MCSG_OK;
    write_seconds = now_seconds() - write_seconds;
    if (!ok)
        fail_line(&err);
    if (v->picture) { /* faces coloured by the leaf they lie on */
        uint32_t *group = leaf_groups(prov, result.triangle_count);
        if (!group)
            fprintf(stderr, "meshcsg: out of memory drawing %s\n", v->picture);
        ok = group && write_picture(&result, group, draw, v->edges, v->picture) && ok;
        free(group);
        mcsg_free(prov, opts);
    }
    if (v->stats) {
        print_eval_stats(&stats, read_seconds);
        printf("  write output     %8.3f s\n", write_seconds);
        printf("  peak memory      %8.1f MiB\n", peak_memory_mib());
    }
    else if (!v->quiet)
        printf("%zu vertices, %zu triangles\n", result.vertex_count, result.triangle_count);
    mcsg_mesh_free(&result, opts);
    mcsg_tree_free(tree);
    if (!ok)
        return EXIT_PROBLEM;
    /* The library logged what is broken; the mesh was written all the same. */
    return mcsg_output_check_failed(&stats.output_check) ? EXIT_BROKEN_GUARANTEE : 0;
}

static int cmd_eval(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    picture_request draw;
    int code;
    mcsg_pool *pool = NULL;
    (void)argc;
    opts.threads = (int)v->threads;
    opts.check_self_intersections = v->check_inputs;
    opts.check_output_crossings = v->check_crossings;
    opts.keep_all_vertices = v->keep_all_vertices;
    if (v->quiet && v->verbose) {
        fprintf(stderr, "meshcsg eval: --quiet and --verbose contradict each other (see "
                        "meshcsg eval --help)\n");
        return EXIT_USAGE;
    }
    if (v->quiet)
        opts.log = NULL;
    if (v->verbose) {
        static const mcsg_log_level info = MCSG_LOG_INFO;
        opts.log_user = (void *)&info;
    }
    /* One set of workers for reading, evaluating and writing: each call would start its
     * own, and a new thread took up to milliseconds to get going. Without the pool (no
     * threads to spare) every call runs as before. */
    if (mcsg_pool_create(&opts, &pool, NULL) == MCSG_OK)
        opts.pool = pool;
    if (!v->picture && (v->view || v->size || v->edges)) {
        fprintf(stderr, "meshcsg eval: --view, --size and --edges go with --picture (see "
                        "meshcsg eval --help)\n");
        return EXIT_USAGE;
    }
    if (!picture_options("eval", v, &draw))
        return EXIT_USAGE;
    code = eval_file(&opts, argv[0], v, &draw);
    mcsg_pool_free(pool);
    return code;
}

/* ---------------------------------------------------------------------------------- */
/* repair                                                                              */

static int cmd_repair(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    mcsg_mesh in, result;
    mcsg_repair_stats st;
    mcsg_error err;
    int code = 0;
    (void)argc;
    opts.threads = (int)v->threads;
    opts.keep_all_vertices = v->keep_all_vertices;
    if (v->quiet)
        opts.log = NULL;
    if (mcsg_mesh_read(argv[0], MCSG_FORMAT_AUTO, &opts, &in, &err) != MCSG_OK) {
        fail_line(&err);
        return EXIT_PROBLEM;
    }
    start_progress(&opts, v->quiet);
    if (mcsg_mesh_repair(&in, &opts, &result, &st, &err) != MCSG_OK) {
        stop_progress();
        fail_line(&err);
        mcsg_mesh_free(&in, &opts);
        return EXIT_PROBLEM;
    }
    stop_progress();
    if (v->output && mcsg_mesh_write(v->output, MCSG_FORMAT_AUTO, &result, &opts, &err) != MCSG_OK) {
        fail_line(&err);
        code = EXIT_PROBLEM;
    }
    if (v->stats)
        print_eval_stats(&st.eval, -1);
    if (!v->quiet)
        printf("%zu shells in, %zu pairs of triangles meeting (shells crossing); %zu shells out "
           "(%zu cavities), %zu vertices, %zu triangles\n", st.shells_in, st.crossing_pairs,
           st.shells_out, st.cavities, result.vertex_count, result.triangle_count);
    mcsg_mesh_free(&result, &opts);
    mcsg_mesh_free(&in, &opts);
    if (code == 0 && mcsg_output_check_failed(&st.eval.output_check))
        code = EXIT_BROKEN_GUARANTEE;
    return code;
}

static int demo_check_leaves(const mcsg_tree *tree, const mcsg_options *opts,
                             size_t *faces)
{
    int valid = 1;
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++) {
        const mcsg_mesh *leaf = mcsg_tree_leaf_mesh(tree, id);
        mcsg_check_report r;
        mcsg_error err;
        if (!leaf)
            continue;
        *faces += leaf->triangle_count;
        if (mcsg_mesh_check(leaf, opts, &r, &err) != MCSG_OK) {
            fail_line(&err);
            return 0;
        }
        if (!mcsg_check_report_is_valid(&r) || r.inverted) {
            printf("demo: leaf %s is not a valid outward closed mesh\n",
                   mcsg_tree_node_label(tree, id));
            valid = 0;
        }
    }
    return valid;
}

static int demo_evaluate(const mcsg_tree *tree, const mcsg_options *opts, const char *out,
                         int spheres)
{
    mcsg_mesh result;
    mcsg_eval_stats st;
    mcsg_check_report rep;
    mcsg_error err;
    double ref = scene_ring_spheres_reference_volume(spheres);
    int ok;
    mcsg_options with_progress = *opts;
    mcsg_status status;
    start_progress(&with_progress, 0);
    status = mcsg_eval(tree, &with_progress, &result, NULL, &st, &err);
    stop_progress();
    if (status != MCSG_OK) {
        fail_line(&err);
        return 0;
    }
    print_eval_stats(&st, -1);
    printf("  peak memory      %8.1f MiB\n", peak_memory_mib());
    ok = mcsg_mesh_check(&result, opts, &rep, &err) == MCSG_OK &&
         mcsg_check_report_is_valid(&rep);
    printf("result: %zu vertices, %zu triangles, %zu shells, volume %.15g (%s)\n",
           result.vertex_count, result.triangle_count, rep.components, rep.volume,
           ok ? "closed, oriented, manifold" : "INVALID");
    if (ref > 0)
        printf("reference volume %.15g (the scene generator's exact reference): %s\n", ref,
               fabs(rep.volume - ref) <= 1e-10 * ref ? "matches" : "DIFFERS");
    if (out && mcsg_mesh_write(out, MCSG_FORMAT_AUTO, &result, opts, &err) != MCSG_OK) {
        fail_line(&err);
        ok = 0;
    } else if (out) {
        printf("wrote %s\n", out);
    }
    mcsg_mesh_free(&result, opts);
    return ok;
}

static int cmd_demo(const cli_values *v, int argc, char **argv)
{
    mcsg_options opts = cli_options();
    int spheres = v->spheres ? (int)v->spheres : DEMO_SPHERES, valid;
    size_t faces = 0;
    const char *out = v->output;
    mcsg_tree *tree;
    mcsg_pool *pool = NULL;
    mcsg_error err;
    double t0, t1, t2;
    (void)argc, (void)argv;
    opts.threads = (int)v->threads;
    if (mcsg_pool_create(&opts, &pool, NULL) == MCSG_OK) /* shared by the calls below */
        opts.pool = pool;
    t0 = now_seconds();
    if (scene_ring_spheres(spheres, 1, &opts, &tree, &err) != MCSG_OK) {
        fail_line(&err);
        mcsg_pool_free(pool);
        return EXIT_PROBLEM;
    }
    t1 = now_seconds();
    valid = demo_check_leaves(tree, &opts, &faces);
    t2 = now_seconds();
    printf("demo scene: the paper's ring (Fig. 15a) with %d spheres alternately added and "
           "carved: %zu leaves, %zu triangles, tree depth %d\n",
           spheres, mcsg_tree_leaf_count(tree), faces, spheres);
    printf("  build scene      %8.3f s\n", t1 - t0);
    printf("  validate leaves  %8.3f s  (%s)\n", t2 - t1,
           valid ? "every leaf closed, oriented, manifold" : "INVALID LEAVES");
    if (valid)
        valid = demo_evaluate(tree, &opts, out, spheres);
    mcsg_tree_free(tree);
    mcsg_pool_free(pool);
    return valid ? 0 : EXIT_PROBLEM;
}

/* ---------------------------------------------------------------------------------- */

/* A run allocates and frees arrays of tens to hundreds of megabytes, step after step.
 * glibc hands blocks over 32 MiB straight back to the kernel and trims the heap's top:
 * the next step then faults the same amount in again, zeroed by the kernel (a fifth of
 * bunny400k's run was system time). A short-lived batch process keeps its freed memory
 * for reuse instead; peaks grow by 1-7%. The library leaves the allocator alone: this
 * is the application's choice (docs/architecture.md). */
static void keep_freed_memory(void)
{
#if defined(__GLIBC__)
    mallopt(M_MMAP_MAX, 0);
    mallopt(M_TRIM_THRESHOLD, 0x7fffffff);
#endif
}

/* ---------------------------------------------------------------------------------- */
/* Commands and options: the one source of the usage text                             */

#define VALUE(field) offsetof(cli_values, field)
#define OUTPUT(help) {"output", 'o', CLI_STRING, "FILE", 0, 0, VALUE(output), help}
#define THREADS                                                                           \
    {"threads", 't', CLI_NUMBER, "N", 1, 1024, VALUE(threads),                           \
     "worker threads, 1 to 1024; the output is the same for any number (default: one "   \
     "per processor)"}
#define QUIET                                                                             \
    {"quiet", 'q', CLI_FLAG, NULL, 0, 0, VALUE(quiet),                                    \
     "print nothing but errors: no counts, warnings or progress line (the exit status "  \
     "still tells a broken guarantee; --stats still prints its table)"}
#define PICTURE_OPTIONS                                                                   \
    {"view", 0, CLI_STRING, "V", 0, 0, VALUE(view),                                       \
     "the picture's view: iso (from the front, right and above), top, front or side "    \
     "(from the right); the mesh fills it (default: iso)"},                              \
    {"size", 0, CLI_STRING, "WxH", 0, 0, VALUE(size),                                      \
     "the picture's size in pixels, each 16 to 8192 (default: 800x600)"},                \
    {"edges", 0, CLI_FLAG, NULL, 0, 0, VALUE(edges), "draw the triangles' edges"}
#define END_OF_OPTIONS {NULL, 0, CLI_FLAG, NULL, 0, 0, 0, NULL}

static const cli_option check_options[] = {
    {"self-intersections", 0, CLI_FLAG, NULL, 0, 0, VALUE(self_intersections),
     "also test exactly whether triangles cross each other (off by default)"},
    OUTPUT("write the mesh, flipped if it was inside out, to FILE (one input only; "
           "default: none)"),
    END_OF_OPTIONS};
static const cli_option no_options[] = {END_OF_OPTIONS};
static const cli_option convert_options[] = {
    {"format", 'f', CLI_STRING, "F", 0, 0, VALUE(format),
     "output format: off, obj, stl (binary), stl-ascii, stl-binary, ply (binary, little "
     "endian), ply-ascii, ply-binary, ply-binary-be, 3mf (default: from OUT's extension)"},
    END_OF_OPTIONS};
static const cli_option intersect_options[] = {
    OUTPUT("write the curves as OBJ points and lines to FILE (default: none)"),
    END_OF_OPTIONS};
static const cli_option eval_options[] = {
    OUTPUT("write the result to FILE, format from its extension: .off .obj .stl .ply .3mf "
           "(default: none, only counts are printed)"),
    {"stats", 0, CLI_FLAG, NULL, 0, 0, VALUE(stats),
     "print the paper's Table 1 columns: faces, primitives, time per step, peak memory"},
    THREADS,
    {"check-crossings", 0, CLI_FLAG, NULL, 0, 0, VALUE(check_crossings),
     "also test the result for crossing triangles, exactly (about the cost of an "
     "evaluation; off by default; the other guarantees are always checked)"},
    {"check-inputs", 0, CLI_FLAG, NULL, 0, 0, VALUE(check_inputs),
     "first test every shell of every leaf for self-intersections, exactly, and evaluate "
     "one that crosses itself by its winding number (about a third of an evaluation's "
     "cost on scanned models; by default only leaves with several shells, a negative "
     "or zero volume or an edge of more than two triangles are tested, and the others "
     "when the result would come out open, or with --check-crossings crossing)"},
    {"keep-all-vertices", 0, CLI_FLAG, NULL, 0, 0, VALUE(keep_all_vertices),
     "keep every vertex of the exact result (by default the vertices inside a flat "
     "region or a straight edge, where curves of the evaluation crossed, are removed "
     "and the flat regions triangulated again; the shape is the same)"},
    {"verbose", 'v', CLI_FLAG, NULL, 0, 0, VALUE(verbose),
     "also print the library's informational messages (what rounding did, why a step "
     "was retried)"},
    QUIET,
    {"picture", 0, CLI_STRING, "FILE", 0, 0, VALUE(picture),
     "also draw the result into a PNG picture, each face coloured by the leaf it comes "
     "from (default: none)"},
    PICTURE_OPTIONS,
    END_OF_OPTIONS};
static const cli_option picture_options_table[] = {PICTURE_OPTIONS, END_OF_OPTIONS};
static const cli_option repair_options[] = {
    OUTPUT("write the repaired mesh to FILE, format from its extension (default: none, "
           "only counts are printed)"),
    {"stats", 0, CLI_FLAG, NULL, 0, 0, VALUE(stats),
     "print the evaluation's steps and times, as eval --stats does"},
    THREADS,
    {"keep-all-vertices", 0, CLI_FLAG, NULL, 0, 0, VALUE(keep_all_vertices),
     "keep every vertex of the solid's exact boundary (as eval --keep-all-vertices)"},
    QUIET,
    END_OF_OPTIONS};
static const cli_option demo_options[] = {
    {"spheres", 'n', CLI_NUMBER, "N", 1, 10000, VALUE(spheres),
     "spheres on the ring, 1 to 10000 (default: 200)"},
    OUTPUT("write the result to FILE (default: none)"),
    THREADS,
    END_OF_OPTIONS};

static const cli_command commands[] = {
    {"check", "FILE...", "validate meshes (.off .obj .stl .ply .3mf .amf) or every leaf of a "
     "CSG file (.scad .csg)",
     "Prints one line per file when the mesh is a closed, consistently oriented,\n"
     "edge-manifold mesh, and one line per kind of problem otherwise.",
     check_options, 1, -1, cmd_check},
    {"tree", "FILE", "print the parsed CSG tree: operations, leaves, face counts", NULL,
     no_options, 1, 1, cmd_tree},
    {"convert", "IN OUT", "convert a mesh between formats", NULL, convert_options, 2, 2,
     cmd_convert},
    {"intersect", "FILE", "intersection curves between the leaves of a CSG file: counts, "
     "per-step times", NULL, intersect_options, 1, 1, cmd_intersect},
    {"eval", "FILE", "evaluate a CSG file (.scad .csg) exactly and write the result",
     "Every leaf must be closed: each edge used as often one way as the other (checked,\n"
     "with a message naming the leaf). A leaf is where its winding number is positive:\n"
     "several shells, overlapping or nested, are fine; zero-area triangles are removed\n"
     "with a warning. The result is checked too: when rounding to doubles broke a guarantee\n"
     "(closed, oriented, manifold once vertices are welded by coordinates, no zero-area\n"
     "triangles; no crossing triangles with --check-crossings), a warning says what,\n"
     "the mesh is written all the same, and the exit status is 3.",
     eval_options, 1, 1, cmd_eval},
    {"repair", "IN", "the solid of one mesh: overlapping shells joined into one, inner "
     "shells dropped, cavities kept",
     "The mesh's solid is where its winding number is positive. IN must be closed:\n"
     "each edge used as often one way as the other. Shells crossing each other or\n"
     "themselves (tested exactly), nested, sharing edges or faces, are what it\n"
     "resolves; zero-area triangles are removed with a warning. The exit status is 3\n"
     "when rounding to doubles broke a guarantee, as for eval.",
     repair_options, 1, 1, cmd_repair},
    {"picture", "MESH OUT", "draw a mesh (.off .obj .stl .ply .3mf .amf) into a PNG picture",
     "A software rasterizer: shaded faces, hidden ones removed; no display needed.",
     picture_options_table, 2, 2, cmd_picture},
    {"demo", "", "evaluate the built-in scene (the paper's ring with spheres), print the "
     "step timings and compare with the reference volume", NULL, demo_options, 0, 0,
     cmd_demo},
};
#define COMMAND_COUNT (sizeof commands / sizeof commands[0])

static void print_version(void)
{
    printf("meshcsg %d.%d.%d\n", MCSG_VERSION_MAJOR, MCSG_VERSION_MINOR, MCSG_VERSION_PATCH);
}

static const char *version_text(void)
{
    static char text[32];
    snprintf(text, sizeof text, "%d.%d.%d", MCSG_VERSION_MAJOR, MCSG_VERSION_MINOR,
             MCSG_VERSION_PATCH);
    return text;
}

int main(int argc, char **argv)
{
    cli_values values;
    keep_freed_memory();
    if (argc < 2) {
        cli_print_help(stderr, version_text(), commands, COMMAND_COUNT);
        return EXIT_USAGE;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0) {
        cli_print_help(stdout, version_text(), commands, COMMAND_COUNT);
        return 0;
    }
    if (strcmp(argv[1], "--version") == 0) {
        print_version();
        return 0;
    }
    for (size_t i = 0; i < COMMAND_COUNT; i++) {
        int operands;
        if (strcmp(argv[1], commands[i].name) != 0)
            continue;
        operands = cli_parse(&commands[i], argc - 2, argv + 2, &values);
        if (operands < 0)
            return operands == -2 ? 0 : EXIT_USAGE;
        return commands[i].run(&values, operands, argv + 2);
    }
    fprintf(stderr, "meshcsg: unknown command '%s' (see meshcsg --help)\n", argv[1]);
    return EXIT_USAGE;
}
