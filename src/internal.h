/*
 * Internal helpers shared by every module: the allocation context, error and log
 * formatting, and a growable byte buffer. Nothing here is part of the public API.
 * Internal cross-module symbols use the prefix mci_ ("meshcsg internal").
 */
#ifndef MESHCSG_INTERNAL_H
#define MESHCSG_INTERNAL_H

#include "meshcsg.h"

#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#if defined(__GNUC__) || defined(__clang__)
#define MCI_PRINTF(fmt, args) __attribute__((format(printf, fmt, args)))
#else
#define MCI_PRINTF(fmt, args)
#endif

typedef struct mcsg_pool mci_pool; /* the public pool type, opaque outside parallel.c */

/* Resolved options: the allocator is always complete, the logger may be NULL. */
typedef struct mci_ctx {
    mcsg_allocator alloc;
    mcsg_log_fn log;
    void *log_user;
    int threads;
    mcsg_progress_fn progress;
    void *progress_user;
    int check_self_intersections;
    mci_pool *pool; /* worker threads: the options' (borrowed) or the call's own */
    bool owns_pool; /* started by mci_pool_start, stopped by mci_pool_stop */
} mci_ctx;

/* Report the start (done = 0) or end (done = 1) of a step, if asked to. MCSG_OK to go
 * on; MCSG_ERR_CANCELLED (with the message in *err) when the callback asks to stop. */
mcsg_status mci_progress(const mci_ctx *ctx, const char *step, int done, mcsg_error *err);

/* Fill *ctx from opts (NULL or zero fields mean defaults). */
void mci_ctx_init(mci_ctx *ctx, const mcsg_options *opts);

/* Allocation through the context. All return NULL on failure (or on size overflow for
 * the _array variants) and never print. mci_free(ctx, NULL) is a no-op. */
void *mci_malloc(const mci_ctx *ctx, size_t size);
void *mci_realloc(const mci_ctx *ctx, void *ptr, size_t size);
void mci_free(const mci_ctx *ctx, void *ptr);
void *mci_malloc_array(const mci_ctx *ctx, size_t count, size_t elem_size);
void *mci_calloc_array(const mci_ctx *ctx, size_t count, size_t elem_size);
void *mci_realloc_array(const mci_ctx *ctx, void *ptr, size_t count, size_t elem_size);
char *mci_strdup(const mci_ctx *ctx, const char *s);
/* Make room for `need` elements of `elem_size` bytes in the growable array *array of
 * *capacity elements (doubling, at least `min_capacity`). False on allocation failure or
 * overflow, leaving the array as it was. */
bool mci_grow_array(const mci_ctx *ctx, void **array, size_t *capacity, size_t need,
                    size_t elem_size, size_t min_capacity);

/* Worker threads kept waiting for the parallel loops of one public call (or of many,
 * through mcsg_options.pool): starting a thread per loop cost 0.05-5 ms per loop on the
 * two-core test machine (the new thread waited for a sleeping processor), which the
 * short loops could not repay. Workers spin briefly between loops, then sleep.
 * mci_pool_start does nothing when ctx has a pool already (the options'), with one
 * thread, or when threads or memory are short (loops then start their own threads);
 * mci_pool_stop joins and frees the workers it started. A loop started while the pool
 * runs another (from inside a task, or from another call sharing it) runs in the calling
 * thread. */
void mci_pool_start(mci_ctx *ctx);
void mci_pool_stop(mci_ctx *ctx);

/* Run fn(user, i, err) for i in 0 .. count-1 on up to mci_thread_count(ctx) threads
 * (the calling thread included). Tasks must be independent. Returns MCSG_OK, or the
 * status and message of the failing task with the smallest index (once a failure is
 * known, no task after it starts; every task before it runs). */
typedef mcsg_status (*mci_task_fn)(void *user, size_t index, mcsg_error *err);
mcsg_status mci_parallel_for(const mci_ctx *ctx, size_t count, mci_task_fn fn, void *user,
                             mcsg_error *err);
/* The same, running task order[i] at position i: with mci_heaviest_first's order the
 * longest tasks start first and the threads finish together. A failure is reported for
 * the smallest failing position. */
mcsg_status mci_parallel_for_order(const mci_ctx *ctx, size_t count, const uint32_t *order,
                                   mci_task_fn fn, void *user, mcsg_error *err);
/* Indices 0 .. n-1 with the heaviest tasks (each over 1/256 of the total cost) first by
 * decreasing cost, then the others in index order (NULL when out of memory). */
uint32_t *mci_heaviest_first(const mci_ctx *ctx, const uint32_t *cost, size_t n);
/* mci_parallel_for with that order for the costs cost(user, i) (a task's work, roughly):
 * one big task coming last would otherwise run alone. */
typedef uint32_t (*mci_cost_fn)(const void *user, size_t index);
mcsg_status mci_parallel_for_heaviest_first(const mci_ctx *ctx, size_t count, mci_cost_fn cost,
                                            mci_task_fn fn, void *user, mcsg_error *err);
/* The end of chunk `chunk` of `size` items among n items (the last chunk may be short):
 * parallel steps split their items into fixed chunks, independent of the thread count. */
static inline size_t mci_chunk_end(size_t n, size_t chunk, size_t size)
{
    return n - chunk * size < size ? n : (chunk + 1) * size;
}
/* ctx->threads, or the number of online processors when it is 0 (at most 64). */
int mci_thread_count(const mci_ctx *ctx);

/* Six times a signed volume in double, summed a triangle at a time (det(a, b, c) each),
 * with what its error bound needs. */
typedef struct mci_volume_sum {
    double sum, magnitude, amplified_underflow;
    size_t triangles;
} mci_volume_sum;
void mci_volume_sum_add(mci_volume_sum *v, const double *a, const double *b, const double *c);
/* +1 or -1 when the error bound proves the sum's sign, 0 when it cannot. */
int mci_volume_sum_sign(const mci_volume_sum *v);

/* Exact sign of the signed volume enclosed by the triangles tris[3 * which[k] ..] for
 * k < n (tris[3 k ..] when which is NULL) over the vertices xyz (finite); the volume in
 * double in *volume (optional). A floating-point sum decides when its error bound allows,
 * big integers otherwise. */
int mci_triangles_volume_sign(const double *xyz, const uint32_t *tris, const uint32_t *which,
                              size_t n, double *volume);

/* mcsg_mesh_check with the context's allocator; the mesh's counts must fit uint32_t. */
mcsg_status mci_mesh_check(const mci_ctx *ctx, const mcsg_mesh *mesh,
                           mcsg_check_report *report, mcsg_error *err);

/* Wall-clock seconds since some fixed point (for step timings). */
double mci_seconds_now(void);

/* A hash of a point's three coordinates in which -0 and +0 are equal. */
uint64_t mci_coordinate_hash(const double *x);
/* canon[i] = the first j with point j's coordinates equal to point i's, for the n points
 * xyz[3i..3i+2] (hash table; -0 == +0). False on allocation failure. */
bool mci_first_equal_coordinates(const mci_ctx *ctx, const double *xyz, size_t n,
                                 uint32_t *canon);

/* A 64-bit key with a reference, for sorting and looking up edges and the like. */
typedef struct mci_keyed {
    uint64_t key;
    uint32_t ref;
} mci_keyed;

/* The key of the undirected edge u-v (smaller id in the high half). */
uint64_t mci_edge_key(uint32_t u, uint32_t v);
/* Sort by key, then ref. */
void mci_sort_keyed(mci_keyed *items, size_t n);
/* Sort 64-bit integers ascending (an introsort without qsort's callback). */
void mci_sort_u64(uint64_t *items, size_t n);
/* The same for long arrays: a least-significant-digit radix sort through tmp (n keys),
 * 11-bit digits (the counts stay in the first-level cache), passes only over the digits
 * where some keys differ (ids rarely use all their bits); n < 2^32. */
void mci_radix_sort_u64_buffered(uint64_t *keys, uint64_t *tmp, size_t n);
/* ... with the buffer allocated; false when it cannot be (keys unchanged). */
bool mci_radix_sort_u64(const mci_ctx *ctx, uint64_t *keys, size_t n);
/* Drops repeats from sorted keys[0 .. n) in place; returns how many are left. */
size_t mci_unique_u64(uint64_t *keys, size_t n);
/* Index of the first item with this key in sorted items[0 .. n), or n. */
size_t mci_find_key(const mci_keyed *items, size_t n, uint64_t key);

/* Record an error (if err is non-NULL) and return `status`, so that callers can write
 * `return mci_fail(err, MCSG_ERR_PARSE, "%s:%zu: ...", name, line);`. */
mcsg_status mci_fail(mcsg_error *err, mcsg_status status, const char *fmt, ...)
    MCI_PRINTF(3, 4);

/* The standard out-of-memory failure, with a short context such as "reading x.obj". */
mcsg_status mci_fail_nomem(mcsg_error *err, const char *what);

/* Send one formatted line to the log callback, if any. */
void mci_log(const mci_ctx *ctx, mcsg_log_level level, const char *fmt, ...) MCI_PRINTF(3, 4);

/* A growable array of bytes (or of fixed-size elements, managed by the caller). */
typedef struct mci_buf {
    unsigned char *data;
    size_t len; /* bytes used */
    size_t cap; /* bytes allocated */
} mci_buf;

/* Make room for `extra` more bytes. Returns false on allocation failure or overflow. */
bool mci_buf_reserve(const mci_ctx *ctx, mci_buf *buf, size_t extra);
/* Append bytes (reserving as needed). Returns false on allocation failure. */
bool mci_buf_append(const mci_ctx *ctx, mci_buf *buf, const void *bytes, size_t n);
/* Append printf-formatted text (no terminating NUL is kept in len). */
bool mci_buf_printf(const mci_ctx *ctx, mci_buf *buf, const char *fmt, ...) MCI_PRINTF(3, 4);
void mci_buf_free(const mci_ctx *ctx, mci_buf *buf);

/* Release everything a mesh owns and zero it (the internal form of mcsg_mesh_free). */
void mci_mesh_free(const mci_ctx *ctx, mcsg_mesh *mesh);
/* Allocate arrays for a mesh of the given size (contents uninitialised). */
mcsg_status mci_mesh_alloc(const mci_ctx *ctx, mcsg_mesh *mesh, size_t vertex_count,
                           size_t triangle_count, mcsg_error *err);

/* Read a whole file into memory (NUL-terminated for the text parsers; the NUL is not
 * counted in *size). */
mcsg_status mci_read_file(const mci_ctx *ctx, const char *path, unsigned char **data,
                          size_t *size, mcsg_error *err);

/* Write `size` bytes to `path` through a temporary file in the same directory that is
 * renamed over `path` only once everything was written and flushed. */
mcsg_status mci_write_file_atomic(const char *path, const void *data, size_t size,
                                  mcsg_error *err);

#endif /* MESHCSG_INTERNAL_H */
