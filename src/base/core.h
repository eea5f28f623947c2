/*
 * Internal helpers shared by every module (base/core.c): the allocation context, error,
 * log and progress reporting, a growable byte buffer, whole-file reads and atomic
 * writes, mesh allocation, timing and coordinate hashing. Nothing here is part of the
 * public API. Internal cross-module symbols use the prefix mci_ ("meshcsg internal").
 */
#ifndef MESHCSG_BASE_CORE_H
#define MESHCSG_BASE_CORE_H

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

/* "No index": an absent face, arrangement, point or vertex in the uint32_t index arrays. */
#define MCI_NONE UINT32_MAX

/* The root of x in a union-find forest (parent[r] == r at a root), halving the path on
 * the way. */
static inline uint32_t mci_find_root(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

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
    int check_output_crossings;
    int keep_all_vertices;
    /* An evaluation of a rounded result again (csg/reevaluate.c): its rounding repair
     * looks for opposite twins after every change, which folds there need. */
    bool reevaluation_round;
    /* In such a round: where the first evaluation's exact result touches itself (edge
     * ends as output_check.h lists them). Parts of the round's result touching anywhere
     * else are moved apart, though its own exact result touches there: rounding made that
     * contact, and the round is judged against the first result's. */
    const double *allowed_touching;
    size_t allowed_touching_count;
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

/* Wall-clock seconds since some fixed point (for step timings). */
double mci_seconds_now(void);

/* A hash of a point's three coordinates in which -0 and +0 are equal. */
uint64_t mci_coordinate_hash(const double *x);
/* canon[i] = the first j with point j's coordinates equal to point i's, for the n points
 * xyz[3i..3i+2] (hash table; -0 == +0). False on allocation failure. */
bool mci_first_equal_coordinates(const mci_ctx *ctx, const double *xyz, size_t n,
                                 uint32_t *canon);

/* Record an error (if err is non-NULL) and return `status`, so that callers can write
 * `return mci_fail(err, MCSG_ERR_PARSE, "%s:%zu: ...", name, line);`. */
mcsg_status mci_fail(mcsg_error *err, mcsg_status status, const char *fmt, ...)
    MCI_PRINTF(3, 4);

/* The standard out-of-memory failure, with a short context such as "reading x.obj". */
mcsg_status mci_fail_nomem(mcsg_error *err, const char *what);

/* Send one formatted line to the log callback, if any. */
void mci_log(const mci_ctx *ctx, mcsg_log_level level, const char *fmt, ...) MCI_PRINTF(3, 4);

/* mci_fail and mci_log from a va_list, the text preceded by "PREFIX: " when prefix is not
 * NULL: what the modules' own error and warning helpers (with file, line and column, or
 * byte offset) build on. */
mcsg_status mci_vfail(mcsg_error *err, mcsg_status status, const char *prefix,
                      const char *fmt, va_list ap);
void mci_vlog(const mci_ctx *ctx, mcsg_log_level level, const char *prefix, const char *fmt,
              va_list ap);

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

#endif /* MESHCSG_BASE_CORE_H */
