/*
 * Core services: allocator dispatch, error and log formatting, growable buffers,
 * whole-file reading and atomic file writing. Every other module builds on these.
 */
#define _POSIX_C_SOURCE 200809L

#include "base/core.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static void *default_malloc(void *user, size_t size)
{
    (void)user;
    return malloc(size);
}

static void *default_realloc(void *user, void *ptr, size_t size)
{
    (void)user;
    return realloc(ptr, size);
}

static void default_free(void *user, void *ptr)
{
    (void)user;
    free(ptr);
}

void mci_ctx_init(mci_ctx *ctx, const mcsg_options *opts)
{
    memset(ctx, 0, sizeof *ctx);
    if (opts && opts->allocator.malloc_fn && opts->allocator.realloc_fn &&
        opts->allocator.free_fn) {
        ctx->alloc = opts->allocator;
    } else {
        ctx->alloc.malloc_fn = default_malloc;
        ctx->alloc.realloc_fn = default_realloc;
        ctx->alloc.free_fn = default_free;
    }
    if (opts) {
        ctx->log = opts->log;
        ctx->log_user = opts->log_user;
        ctx->threads = opts->threads;
        ctx->progress = opts->progress;
        ctx->progress_user = opts->progress_user;
        ctx->check_self_intersections = opts->check_self_intersections;
        ctx->check_output_crossings = opts->check_output_crossings;
        ctx->keep_all_vertices = opts->keep_all_vertices;
        ctx->pool = opts->pool;
    }
}

void *mci_malloc(const mci_ctx *ctx, size_t size)
{
    return ctx->alloc.malloc_fn(ctx->alloc.user, size ? size : 1);
}

void *mci_realloc(const mci_ctx *ctx, void *ptr, size_t size)
{
    return ctx->alloc.realloc_fn(ctx->alloc.user, ptr, size ? size : 1);
}

void mci_free(const mci_ctx *ctx, void *ptr)
{
    if (ptr)
        ctx->alloc.free_fn(ctx->alloc.user, ptr);
}

void *mci_malloc_array(const mci_ctx *ctx, size_t count, size_t elem_size)
{
    if (elem_size && count > SIZE_MAX / elem_size)
        return NULL;
    return mci_malloc(ctx, count * elem_size);
}

void *mci_calloc_array(const mci_ctx *ctx, size_t count, size_t elem_size)
{
    void *p = mci_malloc_array(ctx, count, elem_size);
    if (p)
        memset(p, 0, count * elem_size);
    return p;
}

void *mci_realloc_array(const mci_ctx *ctx, void *ptr, size_t count, size_t elem_size)
{
    if (elem_size && count > SIZE_MAX / elem_size)
        return NULL;
    return mci_realloc(ctx, ptr, count * elem_size);
}

bool mci_grow_array(const mci_ctx *ctx, void **array, size_t *capacity, size_t need,
                    size_t elem_size, size_t min_capacity)
{
    size_t cap = *capacity > min_capacity ? *capacity : min_capacity;
    void *grown;
    if (need <= *capacity)
        return true;
    while (cap < need) {
        if (cap > SIZE_MAX / 2)
            return false;
        cap *= 2;
    }
    grown = mci_realloc_array(ctx, *array, cap, elem_size);
    if (!grown)
        return false;
    *array = grown;
    *capacity = cap;
    return true;
}

char *mci_strdup(const mci_ctx *ctx, const char *s)
{
    size_t n = strlen(s) + 1;
    char *copy = mci_malloc(ctx, n);
    if (copy)
        memcpy(copy, s, n);
    return copy;
}

/* "PREFIX: " (nothing without a prefix) and the formatted text, truncated to size. */
static void format_line(char *out, size_t size, const char *prefix, const char *fmt,
                        va_list ap)
{
    int n = prefix ? snprintf(out, size, "%s: ", prefix) : 0;
    if (n < 0)
        n = 0;
    if ((size_t)n < size)
        vsnprintf(out + n, size - (size_t)n, fmt, ap);
}

mcsg_status mci_vfail(mcsg_error *err, mcsg_status status, const char *prefix,
                      const char *fmt, va_list ap)
{
    if (err) {
        err->status = status;
        format_line(err->message, sizeof err->message, prefix, fmt, ap);
    }
    return status;
}

mcsg_status mci_fail(mcsg_error *err, mcsg_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mci_vfail(err, status, NULL, fmt, ap);
    va_end(ap);
    return status;
}

mcsg_status mci_fail_nomem(mcsg_error *err, const char *what)
{
    return mci_fail(err, MCSG_ERR_NOMEM, "out of memory while %s", what);
}

void mci_vlog(const mci_ctx *ctx, mcsg_log_level level, const char *prefix, const char *fmt,
              va_list ap)
{
    char line[1024];
    if (!ctx->log)
        return;
    format_line(line, sizeof line, prefix, fmt, ap);
    ctx->log(ctx->log_user, level, line);
}

void mci_log(const mci_ctx *ctx, mcsg_log_level level, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mci_vlog(ctx, level, NULL, fmt, ap);
    va_end(ap);
}

bool mci_buf_reserve(const mci_ctx *ctx, mci_buf *buf, size_t extra)
{
    size_t need, cap;
    unsigned char *grown;
    if (extra > SIZE_MAX - buf->len)
        return false;
    need = buf->len + extra;
    if (need <= buf->cap)
        return true;
    cap = buf->cap ? buf->cap : 256;
    while (cap < need)
        cap = cap > SIZE_MAX / 2 ? need : cap * 2;
    grown = mci_realloc(ctx, buf->data, cap);
    if (!grown)
        return false;
    buf->data = grown;
    buf->cap = cap;
    return true;
}

bool mci_buf_append(const mci_ctx *ctx, mci_buf *buf, const void *bytes, size_t n)
{
    if (!mci_buf_reserve(ctx, buf, n))
        return false;
    if (n)
        memcpy(buf->data + buf->len, bytes, n);
    buf->len += n;
    return true;
}

bool mci_buf_printf(const mci_ctx *ctx, mci_buf *buf, const char *fmt, ...)
{
    va_list ap;
    int n;
    va_start(ap, fmt);
    n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || !mci_buf_reserve(ctx, buf, (size_t)n + 1))
        return false;
    va_start(ap, fmt);
    vsnprintf((char *)buf->data + buf->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    buf->len += (size_t)n;
    return true;
}

void mci_buf_free(const mci_ctx *ctx, mci_buf *buf)
{
    mci_free(ctx, buf->data);
    memset(buf, 0, sizeof *buf);
}

mcsg_status mci_read_file(const mci_ctx *ctx, const char *path, unsigned char **data,
                          size_t *size, mcsg_error *err)
{
    FILE *f = fopen(path, "rb");
    mci_buf buf = {0};
    *data = NULL;
    *size = 0;
    if (!f)
        return mci_fail(err, MCSG_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    for (;;) {
        size_t got;
        /* Grow only when full (the buffer doubles), so a small file costs one small
         * allocation and a large one a logarithmic number of copies. */
        if (buf.cap - buf.len < 2 && !mci_buf_reserve(ctx, &buf, buf.cap ? buf.cap : 65536)) {
            fclose(f);
            mci_buf_free(ctx, &buf);
            return mci_fail_nomem(err, "reading a file");
        }
        got = fread(buf.data + buf.len, 1, buf.cap - buf.len - 1, f);
        buf.len += got;
        if (got == 0)
            break;
    }
    if (ferror(f)) {
        int e = errno;
        fclose(f);
        mci_buf_free(ctx, &buf);
        return mci_fail(err, MCSG_ERR_IO, "%s: read error: %s", path, strerror(e));
    }
    fclose(f);
    buf.data[buf.len] = 0;
    *data = buf.data;
    *size = buf.len;
    return MCSG_OK;
}

mcsg_status mci_write_file_atomic(const char *path, const void *data, size_t size,
                                  mcsg_error *err)
{
    char tmp[4096];
    FILE *f;
    int ok;
    if (snprintf(tmp, sizeof tmp, "%s.tmp%ld", path, (long)getpid()) >= (int)sizeof tmp)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "%s: path too long", path);
    f = fopen(tmp, "wb");
    if (!f)
        return mci_fail(err, MCSG_ERR_IO, "%s: cannot create: %s", path, strerror(errno));
    ok = fwrite(data, 1, size, f) == size;
    ok = (fflush(f) == 0) && ok;
    ok = (fclose(f) == 0) && ok;
    if (!ok || rename(tmp, path) != 0) {
        int e = errno;
        remove(tmp);
        return mci_fail(err, MCSG_ERR_IO, "%s: write failed: %s", path, strerror(e));
    }
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */

const char *mcsg_status_string(mcsg_status status)
{
    switch (status) {
    case MCSG_OK: return "success";
    case MCSG_ERR_NOMEM: return "out of memory";
    case MCSG_ERR_IO: return "input/output error";
    case MCSG_ERR_PARSE: return "malformed input";
    case MCSG_ERR_FORMAT: return "unknown or unsupported file format";
    case MCSG_ERR_UNSUPPORTED: return "unsupported feature";
    case MCSG_ERR_INVALID_ARG: return "invalid argument";
    case MCSG_ERR_INVALID_MESH: return "invalid mesh";
    case MCSG_ERR_LIMIT: return "size limit exceeded";
    case MCSG_ERR_INTERNAL: return "internal error";
    case MCSG_ERR_CANCELLED: return "cancelled";
    }
    return "unknown status";
}

void mcsg_free(void *ptr, const mcsg_options *opts)
{
    mci_ctx ctx;
    mci_ctx_init(&ctx, opts);
    mci_free(&ctx, ptr);
}

void mci_mesh_free(const mci_ctx *ctx, mcsg_mesh *mesh)
{
    if (!mesh)
        return;
    mci_free(ctx, mesh->vertices);
    mci_free(ctx, mesh->triangles);
    memset(mesh, 0, sizeof *mesh);
}

mcsg_status mci_mesh_alloc(const mci_ctx *ctx, mcsg_mesh *mesh, size_t vertex_count,
                           size_t triangle_count, mcsg_error *err)
{
    memset(mesh, 0, sizeof *mesh);
    if (vertex_count > UINT32_MAX || triangle_count > UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "mesh too large: %zu vertices, %zu triangles "
                        "(at most %u each)", vertex_count, triangle_count, UINT32_MAX);
    mesh->vertices = mci_malloc_array(ctx, vertex_count, 3 * sizeof(double));
    mesh->triangles = mci_malloc_array(ctx, triangle_count, 3 * sizeof(uint32_t));
    if (!mesh->vertices || !mesh->triangles) {
        mci_mesh_free(ctx, mesh);
        return mci_fail_nomem(err, "allocating a mesh");
    }
    mesh->vertex_count = vertex_count;
    mesh->triangle_count = triangle_count;
    return MCSG_OK;
}

void mcsg_mesh_free(mcsg_mesh *mesh, const mcsg_options *opts)
{
    mci_ctx ctx;
    mci_ctx_init(&ctx, opts);
    mci_mesh_free(&ctx, mesh);
}

mcsg_status mcsg_mesh_copy(const mcsg_mesh *src, const mcsg_options *opts, mcsg_mesh *dst,
                           mcsg_error *err)
{
    mci_ctx ctx;
    mcsg_status st;
    mci_ctx_init(&ctx, opts);
    if (!src || !dst)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_copy: NULL mesh");
    st = mci_mesh_alloc(&ctx, dst, src->vertex_count, src->triangle_count, err);
    if (st != MCSG_OK)
        return st;
    if (src->vertex_count)
        memcpy(dst->vertices, src->vertices, src->vertex_count * 3 * sizeof(double));
    if (src->triangle_count)
        memcpy(dst->triangles, src->triangles, src->triangle_count * 3 * sizeof(uint32_t));
    return MCSG_OK;
}

void mcsg_mesh_flip(mcsg_mesh *mesh)
{
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        uint32_t *tri = mesh->triangles + 3 * t;
        uint32_t swap = tri[1];
        tri[1] = tri[2];
        tri[2] = swap;
    }
}

void mcsg_mesh_transform(mcsg_mesh *mesh, const double m[12])
{
    double det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                 m[2] * (m[4] * m[9] - m[5] * m[8]);
    for (size_t i = 0; i < mesh->vertex_count; i++) {
        double *p = mesh->vertices + 3 * i;
        double x = p[0], y = p[1], z = p[2];
        p[0] = m[0] * x + m[1] * y + m[2] * z + m[3];
        p[1] = m[4] * x + m[5] * y + m[6] * z + m[7];
        p[2] = m[8] * x + m[9] * y + m[10] * z + m[11];
    }
    /* The sign only decides orientation; a mirror has det = -1 up to rounding, far from
     * zero, and a singular map (det ~ 0) collapses the mesh whatever we choose. */
    if (det < 0)
        mcsg_mesh_flip(mesh);
}

double mci_seconds_now(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

uint64_t mci_coordinate_hash(const double *x)
{
    uint64_t h = 0x9e3779b97f4a7c15u;
    for (int k = 0; k < 3; k++) {
        double v = x[k] == 0 ? 0.0 : x[k]; /* -0 and +0 are one coordinate */
        uint64_t bits;
        memcpy(&bits, &v, sizeof bits);
        h = (h ^ bits) * 0xff51afd7ed558ccdu;
        h ^= h >> 29;
    }
    return h;
}

mcsg_status mci_progress(const mci_ctx *ctx, const char *step, int done, mcsg_error *err)
{
    if (!ctx->progress || ctx->progress(ctx->progress_user, step, done) == 0)
        return MCSG_OK;
    return mci_fail(err, MCSG_ERR_CANCELLED, "cancelled by the progress callback at the %s of "
                    "step \"%s\"", done ? "end" : "start", step);
}

#define MCI_STRINGIFY(x) #x
#define MCI_VERSION_TEXT(a, b, c) MCI_STRINGIFY(a) "." MCI_STRINGIFY(b) "." MCI_STRINGIFY(c)

const char *mcsg_version(void)
{
    return MCI_VERSION_TEXT(MCSG_VERSION_MAJOR, MCSG_VERSION_MINOR, MCSG_VERSION_PATCH);
}

bool mci_first_equal_coordinates(const mci_ctx *ctx, const double *xyz, size_t n,
                                 uint32_t *canon)
{
    size_t size = 16;
    uint32_t *table;
    while (size < 2 * n)
        size *= 2;
    table = mci_malloc_array(ctx, size, sizeof *table);
    if (!table)
        return false;
    for (size_t i = 0; i < size; i++)
        table[i] = UINT32_MAX;
    for (uint32_t v = 0; v < n; v++) {
        const double *x = xyz + 3 * (size_t)v;
        size_t at = mci_coordinate_hash(x) & (size - 1);
        while (table[at] != UINT32_MAX) {
            const double *y = xyz + 3 * (size_t)table[at];
            if (x[0] == y[0] && x[1] == y[1] && x[2] == y[2])
                break;
            at = (at + 1) & (size - 1);
        }
        if (table[at] == UINT32_MAX)
            table[at] = v;
        canon[v] = table[at];
    }
    mci_free(ctx, table);
    return true;
}
