/*
 * meshcsg — exact constructive solid geometry on closed triangle meshes.
 *
 * One public header. Conventions that hold for every function below:
 *
 *  - Status: every fallible function returns an mcsg_status; MCSG_OK (0) is success.
 *    When an mcsg_error pointer is given (it may always be NULL), it receives the status
 *    and a one-line message naming the file and line (or byte offset) where that applies.
 *  - Options: every function that allocates takes `const mcsg_options *` (NULL, or a
 *    zero-initialised struct, means defaults: malloc/realloc/free, no logging).
 *  - Ownership: memory the library returns (mesh arrays, trees, buffers) is allocated
 *    with the options' allocator and must be released with the matching mcsg_*_free
 *    function, passing options with the same allocator. Input meshes passed by pointer
 *    are only read, never kept: the library copies what it needs.
 *  - The library never exits, never prints and keeps no global mutable state; it
 *    reports through return values and the optional logging callback only. Distinct
 *    objects may be used from different threads at the same time (a worker pool may
 *    be shared: see mcsg_options.pool).
 *  - On error, output arguments are left empty (zeroed mesh, NULL pointers) and nothing
 *    is leaked, including when an allocation fails half-way.
 */
#ifndef MESHCSG_H
#define MESHCSG_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The version, kept here only: CMake reads it from these lines. */
#define MCSG_VERSION_MAJOR 0
#define MCSG_VERSION_MINOR 1
#define MCSG_VERSION_PATCH 0

/* The version of the library linked at run time, "MAJOR.MINOR.PATCH" (compare with the
 * MCSG_VERSION_* of the header compiled against). Never NULL. */
const char *mcsg_version(void);

/* ------------------------------------------------------------------------------------ */
/* Status and errors                                                                     */

typedef enum mcsg_status {
    MCSG_OK = 0,
    MCSG_ERR_NOMEM,        /* an allocation failed */
    MCSG_ERR_IO,           /* a file could not be opened, read or written */
    MCSG_ERR_PARSE,        /* malformed input (mesh file or CSG text) */
    MCSG_ERR_FORMAT,       /* unknown file format, or a variant meshcsg does not read */
    MCSG_ERR_UNSUPPORTED,  /* well-formed input that uses a feature outside meshcsg */
    MCSG_ERR_INVALID_ARG,  /* the caller passed an invalid argument */
    MCSG_ERR_INVALID_MESH, /* a mesh is not usable (e.g. indices out of range) */
    MCSG_ERR_LIMIT,        /* the input exceeds a hard limit (e.g. 2^32-1 vertices) */
    MCSG_ERR_INTERNAL,     /* an internal consistency check failed: a bug, please report */
    MCSG_ERR_CANCELLED     /* the progress callback asked to stop (mcsg_progress_fn) */
} mcsg_status;

/* A short English description of a status code ("out of memory", ...). Never NULL. */
const char *mcsg_status_string(mcsg_status status);

#define MCSG_ERROR_MESSAGE_SIZE 512

/* Filled by a failing call when the caller passes a non-NULL pointer. The message is a
 * single line without a trailing newline, e.g. "box.off:12: expected 3 vertex indices". */
typedef struct mcsg_error {
    mcsg_status status;
    char message[MCSG_ERROR_MESSAGE_SIZE];
} mcsg_error;

/* ------------------------------------------------------------------------------------ */
/* Options: allocator hook and logging                                                   */

/* Custom allocator. Either all three functions are set, or none (then the C library's
 * malloc/realloc/free are used). realloc_fn(user, NULL, n) must behave like malloc_fn.
 * The library never calls free_fn with NULL. The libraries behind 3MF, AMF and SVG
 * import (libzip, expat) take no allocator: their own working memory comes from malloc. */
typedef struct mcsg_allocator {
    void *(*malloc_fn)(void *user, size_t size);
    void *(*realloc_fn)(void *user, void *ptr, size_t size);
    void (*free_fn)(void *user, void *ptr);
    void *user;
} mcsg_allocator;

typedef enum mcsg_log_level {
    MCSG_LOG_DEBUG = 0,
    MCSG_LOG_INFO = 1,
    MCSG_LOG_WARNING = 2
} mcsg_log_level;

/* Logging callback: `message` is one line without trailing newline, valid only during
 * the call. Called from the thread that called the library function. */
typedef void (*mcsg_log_fn)(void *user, mcsg_log_level level, const char *message);

/* Progress callback: called with done = 0 when a step of a long operation starts and
 * done = 1 when it ends, from the thread that called the library. Return 0 to go on;
 * any other value stops the operation at that point: it frees what it built and
 * returns MCSG_ERR_CANCELLED (a step under way finishes first, so stopping takes at most
 * one step). The steps, in order:
 *   mcsg_eval:      "check" (the input contract), "intersect" (octree, pair tests,
 *                   per-face arrangements, point numbering), "triangulate", "classify",
 *                   "assemble" (rounding and the output mesh), and only when rounding
 *                   broke a guarantee "evaluate rounded result again" (mcsg_eval)
 *   mcsg_intersect: "intersect"
 * `step` is a static string. */
typedef int (*mcsg_progress_fn)(void *user, const char *step, int done);

/* Worker threads that several calls share (mcsg_pool_create). */
typedef struct mcsg_pool mcsg_pool;

/* Zero means default for every field. */
typedef struct mcsg_options {
    mcsg_allocator allocator; /* zero: malloc/realloc/free */
    mcsg_log_fn log;          /* NULL: messages are dropped */
    void *log_user;           /* passed to log */
    int threads;              /* worker threads for evaluation, for reading the files
                                 of a CSG text's import() calls and for writing text
                                 meshes; 0: all cores. With more than one, the allocator
                                 is called from several threads at once and must be
                                 thread-safe (malloc is). Results do not depend on it.
                                 The workers live for one call; between its parallel
                                 steps they spin (yielding) up to 2 ms, then sleep */
    mcsg_progress_fn progress; /* NULL: no progress reports */
    void *progress_user;       /* passed to progress */
    int check_self_intersections; /* mcsg_eval: nonzero tests every shell of every leaf
                                     for self-intersections before evaluating (exact,
                                     costs about a third of an evaluation on scanned
                                     models, more on long slivers), and evaluates
                                     a leaf with a shell that crosses itself exactly, by
                                     its winding number, its faces intersected with each
                                     other. Zero tests only the leaves with several
                                     shells, a negative or zero volume or an edge of
                                     more than two triangles */
    int check_output_crossings; /* mcsg_eval: nonzero also tests the result for pairs of
                                   triangles that cross each other (exact, costs about as
                                   much as an evaluation; see mcsg_output_check) */
    int keep_all_vertices;    /* mcsg_eval, mcsg_mesh_repair: nonzero keeps every
                                 vertex of the exact result. Zero (the default) removes
                                 the vertices of faces that another surface met which
                                 carry no shape: inside a flat region, or inside a
                                 straight edge between two flat regions (where curves
                                 of the arrangement crossed); the shape is unchanged */
    mcsg_pool *pool;          /* NULL: each call starts its own workers. Else the calls
                                 made with these options use this pool's workers (all
                                 of them, whenever threads is not 1; worth it for many
                                 short calls: starting a thread costs from 0.05 to a
                                 few milliseconds); calls running at the same time
                                 take turns with it, a call that finds it busy runs its
                                 parallel steps on its own thread */
} mcsg_options;

/* Start worker threads for calls to share: opts->threads of them in all counting the
 * caller's (0: all cores), with the allocator of opts. *out is NULL (and the status
 * MCSG_OK) when that is one thread: calls then need no workers. The pool must outlive
 * every call that uses it. */
mcsg_status mcsg_pool_create(const mcsg_options *opts, mcsg_pool **out, mcsg_error *err);

/* Stop and release the workers (NULL is a no-op). No call may be using the pool. */
void mcsg_pool_free(mcsg_pool *pool);

/* Release a buffer returned by the library (e.g. from mcsg_mesh_write_memory).
 * free(NULL) is a no-op. */
void mcsg_free(void *ptr, const mcsg_options *opts);

/* ------------------------------------------------------------------------------------ */
/* Meshes                                                                                */

/* A triangle mesh. Vertex i is (vertices[3i], vertices[3i+1], vertices[3i+2]); triangle t
 * is (triangles[3t], triangles[3t+1], triangles[3t+2]), counter-clockwise seen from
 * outside for a correctly oriented closed mesh. Counts never exceed UINT32_MAX.
 * A mesh returned by the library owns its arrays: release it with mcsg_mesh_free. */
typedef struct mcsg_mesh {
    double *vertices;
    uint32_t *triangles;
    size_t vertex_count;
    size_t triangle_count;
} mcsg_mesh;

/* Free the arrays of a library-allocated mesh and zero the struct. NULL is a no-op. */
void mcsg_mesh_free(mcsg_mesh *mesh, const mcsg_options *opts);

/* Deep copy `src` into `*dst` (which is overwritten, not freed). */
mcsg_status mcsg_mesh_copy(const mcsg_mesh *src, const mcsg_options *opts, mcsg_mesh *dst,
                           mcsg_error *err);

/* Reverse the orientation of every triangle in place (swaps two indices per triangle). */
void mcsg_mesh_flip(mcsg_mesh *mesh);

/* Apply an affine map in place: p' = M[0..2][0..2] * p + M[.][3], with `matrix` a
 * row-major 3x4 matrix. If the 3x3 part has a negative determinant (a mirror), triangle
 * orientation is reversed so that the mesh keeps facing outward. Coordinates are
 * rounded to double (this is how transformed CSG leaves are defined). */
void mcsg_mesh_transform(mcsg_mesh *mesh, const double matrix[12]);

/* ------------------------------------------------------------------------------------ */
/* Mesh files                                                                            */

typedef enum mcsg_format {
    MCSG_FORMAT_AUTO = 0,   /* reading: detect from content and name; writing: from name */
    MCSG_FORMAT_OFF,        /* OFF, COFF, NOFF, CNOFF, STOFF... (ASCII) */
    MCSG_FORMAT_OBJ,        /* Wavefront OBJ: v and f records */
    MCSG_FORMAT_STL_ASCII,  /* "solid ... endsolid" */
    MCSG_FORMAT_STL_BINARY, /* 80-byte header, float32 little-endian */
    MCSG_FORMAT_PLY_ASCII,
    MCSG_FORMAT_PLY_BINARY_LE,
    MCSG_FORMAT_PLY_BINARY_BE,
    MCSG_FORMAT_3MF         /* 3MF (zip + XML): as one mesh, every build item's shells
                               side by side; mcsg_3mf_read keeps them apart */
} mcsg_format;

/* Human-readable name of a format ("OFF", "binary STL", ...). Never NULL. */
const char *mcsg_format_name(mcsg_format format);

/* Format implied by a file name's extension (case-insensitive): .off .obj .stl .ply .3mf.
 * For .stl this is MCSG_FORMAT_STL_BINARY and for .ply MCSG_FORMAT_PLY_BINARY_LE (the
 * compact choices for writing; reading detects the variant from the content).
 * MCSG_FORMAT_AUTO if the extension is not recognised. */
mcsg_format mcsg_format_from_path(const char *path);

/* Read a mesh file. With MCSG_FORMAT_AUTO the format is detected from the content (PLY
 * and OFF headers, STL ASCII vs binary by size and keywords) and the extension. AMF is
 * read only so (it has no format code: it is never written): a file named .amf or XML
 * whose root element is <amf>, plain or zipped, read as OpenSCAD 2021.01's import()
 * reads it, every object's triangles side by side in one mesh; units are ignored, as
 * OpenSCAD ignores them. Polygons
 * are fan-triangulated. For STL, vertices with bit-identical coordinates (with -0 == +0)
 * are welded into one. Numbers are parsed exactly (correctly rounded, independent of the
 * C locale). Errors name `path` and the line (text formats) or byte offset (binary).
 * On success `*out` owns new arrays; release with mcsg_mesh_free. */
mcsg_status mcsg_mesh_read(const char *path, mcsg_format format, const mcsg_options *opts,
                           mcsg_mesh *out, mcsg_error *err);

/* Same as mcsg_mesh_read, from a memory buffer. `name` (may be NULL) is used in error
 * messages and for extension-based detection. */
mcsg_status mcsg_mesh_read_memory(const void *data, size_t size, mcsg_format format,
                                  const char *name, const mcsg_options *opts,
                                  mcsg_mesh *out, mcsg_error *err);

/* Write a mesh file. MCSG_FORMAT_AUTO picks the format from the extension. Text formats
 * write the shortest decimal that reads back to the identical double. Binary STL stores
 * float32: coordinates that are not exactly representable are rounded, and a warning
 * with their count goes to the log. The file is written under a temporary name and
 * renamed, so a failed write never leaves a partial file at `path`. */
mcsg_status mcsg_mesh_write(const char *path, mcsg_format format, const mcsg_mesh *mesh,
                            const mcsg_options *opts, mcsg_error *err);

/* Serialise a mesh to a new buffer (`format` must not be AUTO). Release *data with
 * mcsg_free. */
mcsg_status mcsg_mesh_write_memory(mcsg_format format, const mcsg_mesh *mesh,
                                   const mcsg_options *opts, void **data, size_t *size,
                                   mcsg_error *err);

/* A 3MF file (core specification: a zip container, XML model) as one mesh per build
 * item: objects made of components are put together, the components' and items'
 * transforms applied (each rounding coordinates, as mcsg_mesh_transform does), and
 * coordinates converted to millimetres from the model's unit. Materials, colours and
 * extensions are ignored. On success *meshes holds *count meshes (at least one) and,
 * when `names` is not NULL, *names the name of the object each item places ("" for
 * none); release both with mcsg_3mf_free. Errors name the file, the model part and the
 * XML line. */
mcsg_status mcsg_3mf_read(const char *path, const mcsg_options *opts, mcsg_mesh **meshes,
                          char ***names, size_t *count, mcsg_error *err);

/* The same from memory; `name` (may be NULL) is used in messages. */
mcsg_status mcsg_3mf_read_memory(const void *data, size_t size, const char *name,
                                 const mcsg_options *opts, mcsg_mesh **meshes,
                                 char ***names, size_t *count, mcsg_error *err);

/* Release what mcsg_3mf_read returned (names may be NULL). */
void mcsg_3mf_free(mcsg_mesh *meshes, char **names, size_t count, const mcsg_options *opts);

/* Write `count` meshes (at least one) as a 3MF file, in millimetres: one object
 * ("object 1", ...) and one build item each. Written under a temporary name and
 * renamed, as mcsg_mesh_write does. */
mcsg_status mcsg_3mf_write(const char *path, const mcsg_mesh *meshes, size_t count,
                           const mcsg_options *opts, mcsg_error *err);

/* ------------------------------------------------------------------------------------ */
/* Validation                                                                            */

#define MCSG_NO_INDEX UINT32_MAX

/* What mcsg_mesh_check found. Edges are counted as undirected vertex pairs after
 * identifying vertices with identical coordinates. Each example_* field holds the first
 * offender found (vertex indices for edges, a triangle index, a vertex index), or
 * MCSG_NO_INDEX when there is none. */
typedef struct mcsg_check_report {
    size_t vertex_count;
    size_t triangle_count;
    size_t out_of_range_indices;  /* triangle corners referencing no vertex */
    size_t nonfinite_vertices;    /* a NaN or infinite coordinate */
    size_t degenerate_triangles;  /* exactly zero area (repeated or collinear corners) */
    size_t duplicate_triangles;   /* same three vertices as an earlier triangle */
    size_t boundary_edges;        /* used by one triangle */
    size_t nonmanifold_edges;     /* used by more than two triangles */
    size_t inconsistent_edges;    /* used twice in the same direction */
    size_t duplicate_vertices;    /* coordinates identical to an earlier vertex (info) */
    size_t unused_vertices;       /* referenced by no triangle (info) */
    size_t components;            /* shells: see self_touching_edges below */
    double volume;                /* signed volume, rounded (meaningful when closed) */
    int inverted;                 /* 1: closed, consistent, and the exact volume sign is
                                     negative: every triangle faces inward */
    int volume_sign;              /* exact sign of the volume (+1, -1, or 0) when closed
                                     and consistent; 0 otherwise. A closed mesh with
                                     volume 0 folds onto itself or crosses itself into
                                     lobes whose winding numbers cancel */
    uint32_t example_out_of_range_triangle;
    uint32_t example_nonfinite_vertex;
    uint32_t example_degenerate_triangle;
    uint32_t example_duplicate_triangle;
    uint32_t example_boundary_edge[2];
    uint32_t example_nonmanifold_edge[2];
    uint32_t example_inconsistent_edge[2];
    /* Closed as a chain (what mcsg_eval requires of a primitive): every edge is used
     * equally often in each direction. Non-manifold edges that are not are counted here;
     * boundary and inconsistent edges above never are. */
    size_t unbalanced_edges;      /* more than two triangles, unequal directions */
    uint32_t example_unbalanced_edge[2];
    /* Shells (what `components` counts): triangles joined across edges, where at an edge
     * of more than two triangles the k-th use in one direction is joined with the k-th
     * in the other (in triangle order). Where one shell then has more than two
     * triangles at an edge (it meets itself there), they are paired by angle about the
     * edge, each with the one it bounds a wedge of solid with (triangles in one
     * half-plane, such as a sliver folded flat, taken in an order that makes directions
     * alternate), or, where directions do not alternate (surfaces entering each other's
     * wedges), without crossing pairs: taken in turn about the edge, each with the last
     * one not yet paired running the other way (triangles in one half-plane then in a
     * fixed order, as if turned apart by an infinitesimal angle). An edge where one
     * shell has more than 64 triangles is counted here: mcsg_eval does not take such a
     * primitive. */
    size_t self_touching_edges;
    uint32_t example_self_touching_edge[2];
} mcsg_check_report;

/* Examine a mesh. Returns MCSG_OK when the examination ran (whatever it found); the
 * findings are in *report. Fails only on allocation failure or invalid arguments. */
mcsg_status mcsg_mesh_check(const mcsg_mesh *mesh, const mcsg_options *opts,
                            mcsg_check_report *report, mcsg_error *err);

/* 1 if the report describes a closed, consistently oriented, edge-manifold mesh with
 * finite coordinates, valid indices and no degenerate or duplicate triangles (it may be
 * inverted: flipping fixes that), 0 otherwise. */
int mcsg_check_report_is_valid(const mcsg_check_report *report);

/* Exact self-intersection test: *pairs receives the number of pairs of triangles whose
 * closed sets meet other than in the vertices and the edge they share (vertices are
 * identified by coordinates; touching at a point, crossing, overlapping in one plane,
 * folding onto a neighbour and repeated triangles all count), and example[2], if not
 * NULL, the first such pair found (or MCSG_NO_INDEX). Zero-area triangles are skipped
 * (mcsg_mesh_check reports them). Exact predicates on the doubles as given: this is the
 * test for outputs after rounding (`meshcsg eval --check-inputs` tests leaves with the
 * same rules, only for whether a shell crosses itself, faster).
 * Fails on NaN or infinite coordinates, indices out of range, or allocation failure.
 * Cost: an octree over the mesh and an exact test per pair of nearby triangles. */
mcsg_status mcsg_mesh_self_intersections(const mcsg_mesh *mesh, const mcsg_options *opts,
                                         size_t *pairs, uint32_t example[2], mcsg_error *err);

/* ------------------------------------------------------------------------------------ */
/* Primitives, tessellated exactly as OpenSCAD does                                      */

/* Number of fragments OpenSCAD uses for a circle of radius r: 3 for r < 2^-20 or an
 * infinite or NaN fn; with fn > 0, max(fn, 3) truncated to an integer; otherwise
 * ceil(max(min(360/fa, 2*pi*r/fs), 5)). OpenSCAD's defaults are fn = 0, fa = 12, fs = 2.
 * fa and fs are used as given here (results beyond INT_MAX saturate). */
int mcsg_fragments(double r, double fn, double fa, double fs);

/* Tessellation controls, as OpenSCAD's $fn, $fa, $fs. For mcsg_make_sphere and
 * mcsg_make_cylinder a zero fa or fs means OpenSCAD's default (12, 2), so a zeroed struct
 * gives OpenSCAD's default tessellation; other values below 0.01 are clamped to 0.01, as
 * OpenSCAD clamps $fa and $fs. */
typedef struct mcsg_resolution {
    double fn, fa, fs;
} mcsg_resolution;

/* The primitives below produce OpenSCAD's vertices bit for bit. OpenSCAD's polygons are
 * split into triangles counter-clockwise seen from outside: convex caps as a fan from
 * their first vertex, quads (a, b, c, d) as (a, b, c) + (a, c, d). An empty result is a
 * mesh with no vertices and no triangles (and MCSG_OK). Huge fragment counts fail with
 * MCSG_ERR_LIMIT beyond 2^32-1 vertices or triangles. */

/* OpenSCAD's cube: a box from the origin to size (or centred). A size <= 0 or non-finite
 * in any axis gives an empty mesh. 8 vertices (corner i has x from bit 0, y from bit 1,
 * z from bit 2), 12 triangles. */
mcsg_status mcsg_make_cube(const double size[3], int center, const mcsg_options *opts,
                           mcsg_mesh *out, mcsg_error *err);

/* OpenSCAD's sphere: n = mcsg_fragments(r) points per ring, (n+1)/2 rings at polar
 * angles 180*(i+0.5)/rings degrees, the first and last ring closed by a polygon cap.
 * r <= 0 or non-finite gives an empty mesh. Vertices n*rings; triangles
 * 2n(rings-1) + 2(n-2). */
mcsg_status mcsg_make_sphere(double r, mcsg_resolution res, const mcsg_options *opts,
                             mcsg_mesh *out, mcsg_error *err);

/* OpenSCAD's cylinder from z=0 to z=h (or centred): a circle of radius r1 at the bottom,
 * r2 at the top, fragments from max(r1, r2). A zero radius gives a single apex vertex (a
 * cone: n+1 vertices, n + (n-2) triangles); otherwise 2n vertices, 2n + 2(n-2) triangles.
 * h <= 0, a negative radius, r1 = r2 = 0 or a non-finite value gives an empty mesh. */
mcsg_status mcsg_make_cylinder(double h, double r1, double r2, int center,
                               mcsg_resolution res, const mcsg_options *opts,
                               mcsg_mesh *out, mcsg_error *err);

/* ------------------------------------------------------------------------------------ */
/* CSG trees                                                                             */

/* A CSG tree: leaves hold meshes (already transformed), inner nodes are operations.
 * Nodes are numbered 0..node_count-1 in creation order; a child is always created
 * before its parent, so trees of any depth are handled without recursion. */
typedef struct mcsg_tree mcsg_tree;

typedef uint32_t mcsg_node_id;
#define MCSG_NO_NODE UINT32_MAX

typedef enum mcsg_node_kind {
    MCSG_NODE_LEAF = 0,
    MCSG_NODE_UNION,        /* no children: the empty set */
    MCSG_NODE_INTERSECTION, /* no children: the empty set (OpenSCAD's rule) */
    MCSG_NODE_DIFFERENCE    /* first child minus all the others */
} mcsg_node_kind;

/* Name of a node kind: "leaf", "union", "intersection", "difference". */
const char *mcsg_node_kind_name(mcsg_node_kind kind);

/* Create an empty tree. It keeps a copy of *opts (allocator and logger). */
mcsg_status mcsg_tree_create(const mcsg_options *opts, mcsg_tree **out, mcsg_error *err);

/* Free a tree and every mesh it holds. NULL is a no-op. */
void mcsg_tree_free(mcsg_tree *tree);

/* Add a leaf holding a copy of `mesh`, transformed by `matrix` (row-major 3x4, NULL for
 * identity; see mcsg_mesh_transform). `label` (may be NULL) describes the leaf for
 * humans, e.g. "sphere(r=5) at a.scad:3:1"; it is copied. */
mcsg_status mcsg_tree_add_leaf(mcsg_tree *tree, const mcsg_mesh *mesh, const double matrix[12],
                               const char *label, mcsg_node_id *out, mcsg_error *err);

/* The same without a copy: the tree takes *mesh's arrays, which must come from the
 * tree's allocator (a mesh returned by mcsg_mesh_read, mcsg_make_cube, mcsg_eval, ...
 * called with the options the tree was created with), and transforms them in place.
 * On success and on failure alike the arrays are the tree's (freed on failure) and *mesh
 * is zeroed; only with a NULL tree or mesh (MCSG_ERR_INVALID_ARG) is nothing taken. */
mcsg_status mcsg_tree_add_leaf_take(mcsg_tree *tree, mcsg_mesh *mesh, const double matrix[12],
                                    const char *label, mcsg_node_id *out, mcsg_error *err);

/* Add an operation over existing nodes. Each node can be the child of one parent only
 * (MCSG_ERR_INVALID_ARG otherwise, also for an id listed twice). `label` may be NULL.
 * The new node's id (MCSG_NO_NODE on failure) is stored in *out (which may be NULL, or
 * point into `children`) once everything else is done. */
mcsg_status mcsg_tree_add_op(mcsg_tree *tree, mcsg_node_kind op, const mcsg_node_id *children,
                             size_t child_count, const char *label, mcsg_node_id *out,
                             mcsg_error *err);

/* Choose the root. Without a call, the root is the last node added. */
mcsg_status mcsg_tree_set_root(mcsg_tree *tree, mcsg_node_id node, mcsg_error *err);

/* Queries. An out-of-range node id returns MCSG_NO_NODE / 0 / NULL. */
mcsg_node_id mcsg_tree_root(const mcsg_tree *tree);
size_t mcsg_tree_node_count(const mcsg_tree *tree);
size_t mcsg_tree_leaf_count(const mcsg_tree *tree);
mcsg_node_kind mcsg_tree_node_kind(const mcsg_tree *tree, mcsg_node_id node);
size_t mcsg_tree_child_count(const mcsg_tree *tree, mcsg_node_id node);
mcsg_node_id mcsg_tree_child(const mcsg_tree *tree, mcsg_node_id node, size_t index);
const char *mcsg_tree_node_label(const mcsg_tree *tree, mcsg_node_id node); /* never NULL */
/* The mesh of a leaf (NULL for an operation). The tree owns it. The returned pointer is
 * valid until the next node is added to the tree (the node array may move) or the tree
 * is freed; the vertex and triangle arrays it points to stay valid, unchanged, until
 * mcsg_tree_free. The label pointer above follows the same rule as the mesh arrays. */
const mcsg_mesh *mcsg_tree_leaf_mesh(const mcsg_tree *tree, mcsg_node_id node);

/* ------------------------------------------------------------------------------------ */
/* CSG language (OpenSCAD subset; see docs/csg-language.md)                              */

/* Parse a CSG file into a new tree. import() paths resolve relative to the file's
 * directory. Errors name the file, line and column ("part.scad:3:5: ..."):
 * MCSG_ERR_PARSE for malformed text, MCSG_ERR_UNSUPPORTED for OpenSCAD features outside
 * the subset, MCSG_ERR_LIMIT for hard limits (expressions nested deeper than 256), and
 * import errors with the mesh reader's status. Warnings (e.g. unknown arguments, which
 * OpenSCAD ignores) go to the log. The empty set (an empty group, cube(0), ...) is a
 * union node without children. Leaves and operations carry labels such as
 * "sphere(r=5, $fn=32) at part.scad:3:5". Every leaf's mesh is transformed by all the
 * transforms above it; a transform that turns space (a row of its matrix with two
 * non-zero entries) over two or more leaves also marks its group as a frame, which
 * mcsg_eval evaluates in the group's own coordinates (docs/csg-language.md). */
mcsg_status mcsg_scad_read(const char *path, const mcsg_options *opts, mcsg_tree **out,
                           mcsg_error *err);

/* Parse CSG text from memory. `name` (may be NULL) appears in messages; import() paths
 * resolve relative to `base_dir` (NULL: the current directory). */
mcsg_status mcsg_scad_read_memory(const char *text, size_t size, const char *name,
                                  const char *base_dir, const mcsg_options *opts,
                                  mcsg_tree **out, mcsg_error *err);

/* ------------------------------------------------------------------------------------ */
/* Intersection curves (the first stage of evaluation, exposed for inspection)           */

/* Polylines as points and segments: segment i joins points segments[2i] and
 * segments[2i+1]. The segments are the pieces of the curves where faces of different
 * leaves cross, and the edges of coplanar faces of other leaves clipped to each face, all
 * split at every point where they meet (triple points included). Each exact point
 * appears once, however many faces produced it; its coordinates are the exact point's
 * coordinates rounded to the nearest doubles. */
typedef struct mcsg_curves {
    double *points;
    uint32_t *segments;
    size_t point_count;
    size_t segment_count;
} mcsg_curves;

typedef struct mcsg_intersect_stats {
    size_t faces;              /* faces of all leaves */
    size_t cells;              /* octree cells */
    size_t critical_cells;     /* leaf cells holding faces of two or more leaves */
    size_t candidate_pairs;    /* face pairs tested (each once) */
    size_t intersecting_pairs; /* pairs that cross along a segment */
    size_t point_contacts;     /* pairs touching at a single point */
    size_t coplanar_pairs;     /* coplanar pairs with overlapping interiors */
    size_t arranged_faces;     /* faces cut by curves or holding points on their edges */
    double seconds_octree, seconds_pairs, seconds_intersect, seconds_arrange, seconds_merge;
} mcsg_intersect_stats;

/* Intersect the faces of different leaves of `tree` (the operations are ignored): octree
 * over all leaves, candidate pairs, exact triangle-triangle intersection, exact merging
 * of coincident points. *out receives the curves (release with mcsg_curves_free); stats
 * may be NULL. */
mcsg_status mcsg_intersect(const mcsg_tree *tree, const mcsg_options *opts, mcsg_curves *out,
                           mcsg_intersect_stats *stats, mcsg_error *err);

void mcsg_curves_free(mcsg_curves *curves, const mcsg_options *opts);

/* ------------------------------------------------------------------------------------ */
/* Evaluation                                                                            */

/* Where an output triangle comes from: it lies in triangle `face` of the mesh of tree
 * leaf `leaf` (with that leaf's orientation, or reversed when the leaf is subtracted). */
typedef struct mcsg_provenance {
    mcsg_node_id leaf;
    uint32_t face;
} mcsg_provenance;

/* What mcsg_eval found when it checked its result against the guarantees of
 * docs/robustness.md. Every count is 0 when the result keeps them; the touching edges
 * are allowed (the exact result itself touches there). */
typedef struct mcsg_output_check {
    size_t open_edges;           /* edges of one triangle (welded by coordinates) */
    size_t misoriented_edges;    /* edges of two triangles facing opposite ways */
    size_t degenerate_triangles; /* triangles of zero area */
    size_t index_nonmanifold_edges; /* vertex-index edges not used exactly once in each
                                       direction (parts that touch have vertex copies) */
    size_t welded_nonmanifold_edges; /* once vertices are welded by coordinates (as STL
                                        readers, slicers and mesh libraries do), edges of
                                        more than two triangles where the exact result
                                        does not touch itself (rounding made them), or
                                        used more often one way than the other */
    size_t touching_edges;       /* the same where the exact result touches itself (two
                                    parts sharing an edge): allowed, not a failure */
    size_t crossing_pairs;       /* pairs of triangles that cross each other, when
                                    mcsg_options.check_output_crossings asked; else 0 */
    int crossings_checked;       /* whether crossing_pairs was computed */
} mcsg_output_check;

/* Nonzero when the check found a broken guarantee (anything but touching edges). */
int mcsg_output_check_failed(const mcsg_output_check *check);

typedef struct mcsg_eval_stats {
    size_t primitives;        /* leaves with at least one triangle that the root reaches */
    size_t faces;             /* their triangles in total ... */
    size_t faces_min, faces_max; /* ... and in the smallest and largest primitive */
    size_t pieces;            /* triangles after the touched faces were split */
    size_t regions;           /* groups of pieces that share all labels (paper §5.2) */
    size_t rays;              /* exact ray tests for first seeds (paper §5.5) */
    size_t local_tests;       /* exact label changes across intersection curves */
    size_t rejected_primitives; /* dropped whole by their first trimmed CSGlist (§5.3) */
    size_t faces_dropped_whole; /* touched faces dropped whole by their labels with respect
                                   to the leaves they do not meet, before being split */
    size_t copied_primitives;   /* primitives that are the same mesh as an earlier one
                                   (same arrays): the earlier one is evaluated for both */
    size_t output_vertices, output_triangles;
    double output_smallest_angle; /* the smallest angle of an output triangle, degrees */
    size_t output_needles;        /* output triangles with an angle under 1 degree */
    size_t flat_vertices_removed; /* vertices of the exact result inside a flat region or
                                     a straight edge, removed (see keep_all_vertices) */
    size_t rounding_joined_vertices;   /* exact vertices joined into another one that
                                          rounds to the same doubles (the one kept is
                                          not counted) */
    size_t rounding_dropped_triangles; /* collapsed (two corners joined) or folded onto an
                                          opposite twin when distinct exact vertices that
                                          round to the same doubles were joined */
    size_t rounding_split_triangles; /* rounded to three collinear corners and removed by
                                        splitting the neighbour at the middle corner (two
                                        back to back: their sides zipped) */
    size_t rounding_flat_triangles;  /* rounded flat and left (a neighbour flat as well,
                                        not back to back along one segment) */
    size_t rounding_turned_triangles; /* thin triangles that rounding turned over (a
                                         corner moved across the opposite edge), removed
                                         by splitting the neighbour at that corner */
    size_t rounding_dropped_shells;  /* closed parts of the result thinner than the
                                        spacing of doubles, which rounding made flat
                                        (volume 0) or inside out where no outer part's
                                        bounding box holds them: removed */
    size_t touching_vertices_split;  /* vertex copies added where parts of the result
                                        touch along an edge or at a point, so that the
                                        output is edge- and vertex-manifold */
    size_t rounding_separated_vertices; /* vertices moved by one unit in the last place
                                           where rounding made parts touch along an edge
                                           that the exact result keeps apart, or (when a
                                           round's candidate is kept) made triangles
                                           cross or touch */
    mcsg_output_check output_check; /* the result against its guarantees; a failure is
                                       also logged as a warning */
    size_t rounding_reevaluations;  /* evaluations of the rounded result (snapped or not)
                                       again, alone by its winding number, because
                                       rounding broke a guarantee (docs/robustness.md);
                                       at most 6 */
    int rounding_reevaluation_kept; /* 1 when the result is a round's candidate (snapped
                                       or evaluated again) whose check passed
                                       (output_check is then that candidate's) */
    double rounding_snap_grid;      /* when a round's result is kept: the spacing of the
                                       grid its vertices were snapped to (a power of two
                                       2^-48 to 2^-28 times the result's size); else 0 */
    mcsg_intersect_stats intersect; /* the intersection stage (mcsg_intersect) */
    double seconds_tree;        /* positive tree and CSG lists */
    double seconds_check;       /* checking the leaves against the input contract */
    double seconds_whole_faces; /* deciding faces dropped whole (in intersect's span) */
    double seconds_triangulate; /* tessellating the split faces */
    double seconds_classify;    /* regions, labels and selection */
    double seconds_assemble;    /* welding and rounding the output */
    size_t frames_evaluated;    /* groups under a transform that turns space, evaluated in
                                   their own coordinates before the rest (.scad input;
                                   docs/robustness.md) */
    double seconds_frames;      /* those evaluations (in seconds_total; the other fields
                                   describe the last evaluation, the root's) */
    int frames_flattened;       /* 1 when the tree evaluated with each leaf turned on
                                   its own was returned instead: the frames' evaluation
                                   failed, or its result broke more guarantees (the
                                   fields above are the returned evaluation's) */
    double seconds_total;
} mcsg_eval_stats;

/* Evaluate the CSG tree exactly: the boundary of the regularized result as a closed,
 * consistently oriented, edge-manifold triangle mesh whose vertices are the exact result
 * vertices rounded to double (only at the end). An empty result gives a mesh with no
 * triangles. Unless opts->keep_all_vertices, a vertex of a face that another surface met
 * is left out where it carries no shape (inside a flat region, or inside a straight edge
 * between two flat regions), decided exactly: its hole is triangulated again, each new
 * triangle naming in provenance the face of one it replaced there (same plane, same
 * facing; where a flat region spans coplanar faces of several leaves, either may be
 * named). Where rounding then breaks a guarantee that moving crossing corners does not
 * mend, the result is made again with every vertex (see below).
 * Input contract: every non-empty leaf the root reaches must be closed as a chain (with
 * vertices identified by coordinates, every edge used as often one way as the other;
 * mcsg_check_report: no boundary, inconsistent or unbalanced edges), with finite
 * coordinates, no shell with more than 64 triangles at one edge (self_touching_edges). Zero-area triangles bound nothing
 * and are removed first, with a warning (one with three collinear corners splits a
 * neighbour at its middle corner, several back to back split every edge through their
 * corners; provenance names the leaf's own triangles).
 * A leaf is the set where its winding number is positive: it may have several shells,
 * facing out or in, nested, overlapping, sharing edges or faces, and repeated triangles
 * (overlapping outward shells are their union, an inward shell inside an outward one is
 * a cavity, one on its own is empty, a triangle listed twice counts twice; see
 * docs/robustness.md). This is checked first; the first leaf that fails it gives
 * MCSG_ERR_INVALID_MESH with a message naming the leaf (its label: file or primitive, and
 * position in the CSG text) and an example of the problem. A shell that crosses itself
 * is evaluated exactly when its leaf is tested up front: always where the leaf has
 * several shells, a negative or zero volume or an edge of more than two triangles, and
 * in every leaf when opts->check_self_intersections asks (it costs about a third of an
 * evaluation on scanned models); or when an internal consistency check trips on it, or
 * the result comes out open or misoriented, or with crossing triangles when
 * opts->check_output_crossings counts them (the leaves not yet tested are tested then,
 * and the faces evaluated again, with a warning). Otherwise (one shell of
 * positive volume, not tested) its faces are not compared with each other and the
 * result is unspecified (a mesh that may not be the intended set; see
 * docs/robustness.md).
 * The result is checked before it is returned (stats->output_check): rounding to doubles
 * can break a guarantee where the exact result has features below the spacing of
 * doubles. Then, where triangles cross, their corners are moved by one unit in the last
 * place where that mends the crossings; otherwise the rounded mesh is snapped to a
 * coarser grid and evaluated again, alone, by its winding number (up to six rounds,
 * docs/robustness.md; the first candidate whose check passes replaces the result, its
 * provenance mapped back to the tree's leaves; stats->rounding_separated_vertices,
 * rounding_reevaluations, rounding_snap_grid). When none does, the first
 * result is still returned with MCSG_OK, the failure is logged as a warning, and
 * mcsg_output_check_failed tells it.
 * A tree read from CSG text can hold frames: a group under a transform that turns space
 * is evaluated first in its own coordinates and its result turned as one mesh (see
 * mcsg_scad_read and docs/robustness.md; stats->frames_evaluated).
 * *out receives the mesh (release with mcsg_mesh_free); if `provenance` is non-NULL it
 * receives one entry per output triangle (release with mcsg_free); stats may be NULL. */
mcsg_status mcsg_eval(const mcsg_tree *tree, const mcsg_options *opts, mcsg_mesh *out,
                      mcsg_provenance **provenance, mcsg_eval_stats *stats, mcsg_error *err);

/* What mcsg_mesh_repair found and made. */
typedef struct mcsg_repair_stats {
    size_t shells_in;      /* the input's shells (components over shared edges) */
    size_t crossing_pairs; /* pairs of triangles that meet: of different shells, or of a
                              shell crossing itself (not sharing an edge) */
    size_t shells_out;     /* the result's shells */
    size_t cavities;       /* ... of which face inward (holes inside the solid) */
    mcsg_eval_stats eval;  /* the evaluation that made it */
} mcsg_repair_stats;

/* The solid of one mesh as a clean closed mesh: the set where the mesh's winding number
 * is positive (mcsg_eval of the mesh alone), the everyday "make it printable" operation.
 * Overlapping shells become one, a shell inside another disappears, an inward shell
 * inside an outward one stays as a cavity, an inward shell on its own disappears, and a
 * shell crossing itself becomes the set where its winding number is positive (every
 * shell is tested exactly first). The input must meet mcsg_eval's contract for a leaf
 * (closed as a chain, finite; MCSG_ERR_INVALID_MESH with one line naming the problem).
 * The result carries mcsg_eval's guarantees and output check (stats->eval.output_check). *out receives the mesh (release with mcsg_mesh_free);
 * stats may be NULL. */
mcsg_status mcsg_mesh_repair(const mcsg_mesh *mesh, const mcsg_options *opts, mcsg_mesh *out,
                             mcsg_repair_stats *stats, mcsg_error *err);

#ifdef __cplusplus
}
#endif

#endif /* MESHCSG_H */
