/*
 * Core services: allocator dispatch, error and log formatting, growable buffers,
 * whole-file reading and atomic file writing. Every other module builds on these.
 */
#define _POSIX_C_SOURCE 200809L

#include "internal.h"
#include "sort_template.h"

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

mcsg_status mci_fail(mcsg_error *err, mcsg_status status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->status = status;
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return status;
}

mcsg_status mci_fail_nomem(mcsg_error *err, const char *what)
{
    return mci_fail(err, MCSG_ERR_NOMEM, "out of memory while %s", what);
}

void mci_log(const mci_ctx *ctx, mcsg_log_level level, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    if (!ctx->log)
        return;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    ctx->log(ctx->log_user, level, line);
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

uint64_t mci_edge_key(uint32_t u, uint32_t v)
{
    return u < v ? (uint64_t)u << 32 | v : (uint64_t)v << 32 | u;
}

/* The sort's total order: by key, then ref. Two comparisons instead of one on a
 * 128-bit rank: the keyed sorts of ring-800 took 225M instructions instead of 285M. */
static inline bool keyed_less(const mci_keyed *a, const mci_keyed *b)
{
    return a->key != b->key ? a->key < b->key : a->ref < b->ref;
}

/* keyed_sort_intro: the introsort of sort_template.h, for short arrays and the radix
 * sort's small buckets. A specialised sort instead of qsort: the classification sorts
 * millions of edge keys, and qsort's callback and merge buffer cost three times as
 * much. (key, ref) is a total order, so the result is unique. */
MCI_DEFINE_SORT(keyed_sort, mci_keyed, keyed_less)

static inline bool u64_less(const uint64_t *a, const uint64_t *b)
{
    return *a < *b;
}

MCI_DEFINE_SORT(u64_sort, uint64_t, u64_less)

void mci_sort_u64(uint64_t *items, size_t n)
{
    u64_sort(items, n);
}

/* Byte `shift` / 8 of the 96-bit rank. Shifts are multiples of 8, so a digit lies
 * wholly in the key (shift >= 32) or in the ref: no 128-bit shift. */
static size_t keyed_digit(const mci_keyed *item, int shift)
{
    uint64_t word = shift >= 32 ? item->key >> (shift - 32) : (uint64_t)item->ref >> shift;
    return (size_t)(word & 255);
}

/* In-place most-significant-digit radix sort (American flag sort) on the 96-bit rank,
 * 8-bit digits from bit `shift` down; digits equal in every item of a bucket cost one
 * counting pass and no moves. Short buckets go to the introsort. No buffer: the
 * classification sorts arrays of millions of edge keys, and a copy would be the peak. */
static void radix_sort_keyed(mci_keyed *items, size_t n, int shift, int depth)
{
    size_t count[256], next[256], end[256];
    for (; shift >= 0; shift -= 8) {
        if (n <= 64) {
            keyed_sort_intro(items, n, depth);
            return;
        }
        memset(count, 0, sizeof count);
        for (size_t i = 0; i < n; i++)
            count[keyed_digit(&items[i], shift)]++;
        if (count[keyed_digit(&items[0], shift)] < n)
            break; /* this digit varies: distribute by it */
    }
    if (shift < 0)
        return; /* all ranks equal */
    for (size_t d = 0, sum = 0; d < 256; d++) {
        next[d] = sum;
        sum += count[d];
        end[d] = sum;
    }
    for (size_t d = 0; d < 256; d++)
        while (next[d] < end[d]) { /* cycle the item at next[d] to its bucket */
            mci_keyed item = items[next[d]];
            size_t home = keyed_digit(&item, shift);
            while (home != d) {
                mci_keyed displaced = items[next[home]];
                items[next[home]++] = item;
                item = displaced;
                home = keyed_digit(&item, shift);
            }
            items[next[d]++] = item;
        }
    for (size_t d = 0, first = 0; d < 256 && shift > 0; first += count[d], d++)
        if (count[d] > 1)
            radix_sort_keyed(items + first, count[d], shift - 8, depth);
}

void mci_sort_keyed(mci_keyed *items, size_t n)
{
    if (n > 1024)
        radix_sort_keyed(items, n, 88, mci_sort_depth(n));
    else
        keyed_sort(items, n);
}

void mci_radix_sort_u64_buffered(uint64_t *keys, uint64_t *tmp, size_t n)
{
    uint32_t count[2048];
    uint64_t *src = keys, *dst = tmp, all = ~UINT64_C(0), any = 0, varying;
    if (n <= 64) { /* clearing the counts alone would cost more */
        mci_sort_u64(keys, n);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        all &= keys[i];
        any |= keys[i];
    }
    varying = all ^ any;
    for (int shift = 0; shift < 64 && varying >> shift; shift += 11) {
        uint32_t sum = 0;
        if (!((varying >> shift) & 2047))
            continue; /* one digit value: the pass would not move anything */
        memset(count, 0, sizeof count);
        for (size_t i = 0; i < n; i++)
            count[(src[i] >> shift) & 2047]++;
        for (size_t d = 0; d < 2048; d++) {
            uint32_t c = count[d];
            count[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            dst[count[(src[i] >> shift) & 2047]++] = src[i];
        src = dst;
        dst = src == keys ? tmp : keys;
    }
    if (src != keys)
        memcpy(keys, src, n * sizeof *keys);
}

size_t mci_unique_u64(uint64_t *keys, size_t n)
{
    size_t out = 0;
    for (size_t i = 0; i < n; i++)
        if (out == 0 || keys[i] != keys[out - 1])
            keys[out++] = keys[i];
    return out;
}

bool mci_radix_sort_u64(const mci_ctx *ctx, uint64_t *keys, size_t n)
{
    uint64_t *tmp;
    if (n < 2)
        return true;
    if (!(tmp = mci_malloc_array(ctx, n, sizeof *tmp)))
        return false;
    mci_radix_sort_u64_buffered(keys, tmp, n);
    mci_free(ctx, tmp);
    return true;
}

size_t mci_find_key(const mci_keyed *items, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (items[mid].key < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && items[lo].key == key ? lo : n;
}
