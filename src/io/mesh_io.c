/*
 * Mesh files: the public read/write entry points, format names and detection, and the
 * helpers every format shares (error messages, the growable mesh, text scanning and
 * text output). The formats themselves live in off.c, obj.c, stl.c, ply.c, threemf.c and
 * amf.c.
 *
 * Detection for MCSG_FORMAT_AUTO, in order: a "ply" magic line; AMF by the .amf extension
 * or XML whose first element is <amf> (AMF has no format code: it is only read, and only
 * so); 3MF by the .3mf extension or a zip archive; an OFF keyword as the first token
 * (Geomview's [ST][C][N][4][n]OFF); the file name's extension; an STL
 * "solid" keyword or a size matching a binary STL header; an OBJ keyword as the first
 * token. Messages are "NAME:LINE: ..." for text and "NAME: byte OFFSET: ..." for binary.
 */
#include "io/mesh_io.h"

#include "base/parallel.h"
#include "io/amf.h"
#include "io/threemf.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---------------------------------------------------------------------------------- */
/* Errors                                                                              */

mcsg_status mci_io_vfail(const mci_io_source *src, mcsg_status status, bool binary,
                         size_t where, const char *fmt, va_list ap)
{
    char prefix[MCSG_ERROR_MESSAGE_SIZE];
    if (binary)
        snprintf(prefix, sizeof prefix, "%s: byte %zu", src->name, where);
    else
        snprintf(prefix, sizeof prefix, "%s:%zu", src->name, where);
    return mci_vfail(src->err, status, prefix, fmt, ap);
}

mcsg_status mci_io_fail_line(const mci_io_source *src, mcsg_status status, size_t line,
                             const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mci_io_vfail(src, status, false, line, fmt, ap);
    va_end(ap);
    return status;
}

mcsg_status mci_io_fail_byte(const mci_io_source *src, mcsg_status status, size_t offset,
                             const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mci_io_vfail(src, status, true, offset, fmt, ap);
    va_end(ap);
    return status;
}

mcsg_status mci_io_fail_build(const mci_io_source *src, mcsg_status status, bool binary,
                              size_t where)
{
    const char *what = status == MCSG_ERR_NOMEM
                           ? "out of memory"
                           : "mesh too large (at most 4294967295 vertices and triangles)";
    if (binary)
        return mci_io_fail_byte(src, status, where, "%s", what);
    return mci_io_fail_line(src, status, where, "%s", what);
}

/* ---------------------------------------------------------------------------------- */
/* The growable mesh                                                                   */

void mci_io_builder_init(mci_io_builder *b, const mci_ctx *ctx)
{
    memset(b, 0, sizeof *b);
    b->ctx = ctx;
}

static mcsg_status resize_vertices(mci_io_builder *b, size_t cap)
{
    double *grown = mci_realloc_array(b->ctx, b->vertices, cap, 3 * sizeof(double));
    if (!grown)
        return MCSG_ERR_NOMEM;
    b->vertices = grown;
    b->vertex_cap = cap;
    return MCSG_OK;
}

static mcsg_status resize_triangles(mci_io_builder *b, size_t cap)
{
    uint32_t *grown = mci_realloc_array(b->ctx, b->triangles, cap, 3 * sizeof(uint32_t));
    if (!grown)
        return MCSG_ERR_NOMEM;
    b->triangles = grown;
    b->triangle_cap = cap;
    return MCSG_OK;
}

/* Doubling capacity, at least 64, at most UINT32_MAX. */
static size_t next_capacity(size_t cap)
{
    size_t grown = cap < 64 ? 64 : cap * 2;
    return grown > UINT32_MAX ? UINT32_MAX : grown;
}

mcsg_status mci_io_reserve(mci_io_builder *b, size_t vertices, size_t triangles)
{
    if (vertices > UINT32_MAX)
        vertices = UINT32_MAX;
    if (triangles > UINT32_MAX)
        triangles = UINT32_MAX;
    if (vertices > b->vertex_cap && resize_vertices(b, vertices) != MCSG_OK)
        return MCSG_ERR_NOMEM;
    if (triangles > b->triangle_cap && resize_triangles(b, triangles) != MCSG_OK)
        return MCSG_ERR_NOMEM;
    return MCSG_OK;
}

mcsg_status mci_io_grow_vertices(mci_io_builder *b)
{
    if (b->vertex_count >= UINT32_MAX)
        return MCSG_ERR_LIMIT;
    return resize_vertices(b, next_capacity(b->vertex_cap));
}

mcsg_status mci_io_grow_triangles(mci_io_builder *b)
{
    if (b->triangle_count >= UINT32_MAX)
        return MCSG_ERR_LIMIT;
    return resize_triangles(b, next_capacity(b->triangle_cap));
}

void mci_io_builder_finish(mci_io_builder *b, mcsg_mesh *out)
{
    /* Trimming is optional: if the smaller allocation fails, the larger one is kept. */
    if (b->vertex_count && b->vertex_count < b->vertex_cap)
        (void)resize_vertices(b, b->vertex_count);
    if (b->triangle_count && b->triangle_count < b->triangle_cap)
        (void)resize_triangles(b, b->triangle_count);
    if (!b->vertex_count) {
        mci_free(b->ctx, b->vertices);
        b->vertices = NULL;
    }
    if (!b->triangle_count) {
        mci_free(b->ctx, b->triangles);
        b->triangles = NULL;
    }
    out->vertices = b->vertices;
    out->vertex_count = b->vertex_count;
    out->triangles = b->triangles;
    out->triangle_count = b->triangle_count;
    mci_io_builder_init(b, b->ctx);
}

void mci_io_builder_free(mci_io_builder *b)
{
    mci_free(b->ctx, b->vertices);
    mci_free(b->ctx, b->triangles);
    mci_io_builder_init(b, b->ctx);
}

/* ---------------------------------------------------------------------------------- */
/* Text scanning                                                                       */

void mci_io_lines_init(mci_io_lines *it, const char *begin, const char *end)
{
    it->next = begin;
    it->end = end;
    it->number = 0;
}

bool mci_io_next_line(mci_io_lines *it, const char **begin, const char **stop)
{
    const char *newline;
    if (it->next >= it->end)
        return false;
    newline = memchr(it->next, '\n', (size_t)(it->end - it->next));
    *begin = it->next;
    *stop = newline ? newline : it->end;
    it->next = newline ? newline + 1 : it->end;
    if (*stop > *begin && (*stop)[-1] == '\r')
        (*stop)--;
    it->number++;
    return true;
}

void mci_io_tokens_init(mci_io_tokens *t, const char *begin, const char *end, size_t line)
{
    t->p = begin;
    t->end = end;
    t->line = line;
}

bool mci_io_next_token(mci_io_tokens *t, const char **begin, const char **stop)
{
    const char *p = t->p;
    for (; p < t->end; p++) {
        if (*p == '\n') {
            if (p + 1 < t->end) /* a final newline ends the last line, starts none */
                t->line++;
        } else if (!mci_io_is_blank(*p)) {
            break;
        }
    }
    if (p >= t->end) {
        t->p = p;
        return false;
    }
    *begin = p;
    while (p < t->end && *p != '\n' && !mci_io_is_blank(*p))
        p++;
    *stop = t->p = p;
    return true;
}

void mci_io_skip_line(mci_io_tokens *t)
{
    const char *newline = memchr(t->p, '\n', (size_t)(t->end - t->p));
    if (newline) {
        t->p = newline + 1;
        if (t->p < t->end)
            t->line++;
    } else {
        t->p = t->end;
    }
}

const char *mci_io_skip_blanks(const char *p, const char *end)
{
    while (p < end && mci_io_is_blank(*p))
        p++;
    return p;
}

const char *mci_io_token_end(const char *p, const char *end)
{
    while (p < end && *p != '\n' && !mci_io_is_blank(*p))
        p++;
    return p;
}

bool mci_io_token_is(const char *begin, const char *stop, const char *word)
{
    size_t n = strlen(word);
    if ((size_t)(stop - begin) != n)
        return false;
    for (size_t i = 0; i < n; i++) {
        char c = begin[i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != word[i])
            return false;
    }
    return true;
}

void mci_io_excerpt_span(char out[48], const char *begin, const char *stop)
{
    size_t n = 0;
    for (; begin < stop && n < 40; begin++)
        out[n++] = (*begin >= 0x20 && *begin < 0x7f) ? *begin : '?';
    if (begin < stop) {
        memcpy(out + n, "...", 3);
        n += 3;
    }
    out[n] = '\0';
}

void mci_io_excerpt(char out[48], const char *p, const char *end)
{
    mci_io_excerpt_span(out, p, mci_io_token_end(p, end));
}

bool mci_io_number(const char *p, const char *end, double *out, const char **next)
{
    const char *after;
    if (!mci_parse_double(p, end, out, &after))
        return false;
    if (after < end && *after != '\n' && !mci_io_is_blank(*after))
        return false;
    *next = after;
    return true;
}

bool mci_io_integer(const char *p, const char *end, int64_t *out, const char **next)
{
    const int64_t cap = (int64_t)1 << 62;
    bool negative = false;
    int64_t value = 0;
    const char *digits;
    if (p < end && (*p == '+' || *p == '-'))
        negative = *p++ == '-';
    digits = p;
    for (; p < end && *p >= '0' && *p <= '9'; p++)
        value = value > cap / 10 ? cap : value * 10 + (*p - '0');
    if (p == digits)
        return false;
    if (value > cap)
        value = cap;
    *out = negative ? -value : value;
    *next = p;
    return true;
}

/* ISO C leaves out-of-range conversions undefined, so they are rounded here as IEEE
 * does: from FLT_MAX + half an ulp (0x1.ffffffp127) on to infinity, below to FLT_MAX. */
float mci_io_to_float32(double d)
{
    if (d > FLT_MAX)
        return d >= 0x1.ffffffp127 ? INFINITY : FLT_MAX;
    if (d < -FLT_MAX)
        return d <= -0x1.ffffffp127 ? -INFINITY : -FLT_MAX;
    return (float)d;
}

/* ---------------------------------------------------------------------------------- */
/* Text output                                                                         */

char *mci_io_put_uint(char *p, uint64_t value)
{
    char digits[20], *end = digits + sizeof digits, *first = end;
    uint32_t small;
    for (; value > UINT32_MAX; value /= 100) /* two digits per division */
        memcpy(first -= 2, mci_digit_pairs + 2 * (value % 100), 2);
    for (small = (uint32_t)value; small >= 100; small /= 100) /* 32-bit: cheaper */
        memcpy(first -= 2, mci_digit_pairs + 2 * (small % 100), 2);
    if (small >= 10)
        memcpy(first -= 2, mci_digit_pairs + 2 * small, 2);
    else
        *--first = (char)('0' + small);
    while (first < end)
        *p++ = *first++;
    return p;
}

char *mci_io_put_double(char *p, double value)
{
    return p + mci_format_double(p, value);
}

char *mci_io_put_text(char *p, const char *text)
{
    size_t n = strlen(text);
    memcpy(p, text, n);
    return p + n;
}

char *mci_io_reserve_text(const mci_ctx *ctx, mci_buf *out, size_t bytes)
{
    if (!mci_buf_reserve(ctx, out, bytes))
        return NULL;
    return (char *)out->data + out->len;
}

void mci_io_commit_text(mci_buf *out, const char *stop)
{
    out->len = (size_t)(stop - (const char *)out->data);
}

/* Text records are formatted in blocks, several blocks at once on the context's threads,
 * each into its own buffer, and copied into place in block order (also on the threads):
 * the text does not depend on the thread count. Blocks go in waves so that only a wave's
 * text is held twice. */
enum { RECORD_BLOCK = 4096, RECORD_WAVE = 32 };

typedef struct record_job {
    const mci_ctx *ctx;
    const mcsg_mesh *mesh;
    const char *vertex_prefix, *triangle_prefix;
    uint32_t index_base;
    size_t vertex_blocks; /* blocks 0 .. vertex_blocks-1 hold vertices, the rest triangles */
    size_t first_block;   /* of the current wave */
    mci_buf *text;        /* per block of the wave */
    unsigned char *dest;  /* where the wave's text goes */
    size_t *offset;       /* per block of the wave: its place after dest */
} record_job;

static char *put_vertex(char *p, const char *prefix, const double *xyz)
{
    p = mci_io_put_text(p, prefix);
    for (int k = 0; k < 3; k++) {
        p = mci_io_put_double(p, xyz[k]);
        *p++ = k < 2 ? ' ' : '\n';
    }
    return p;
}

static char *put_triangle(char *p, const char *prefix, const uint32_t *abc, uint32_t base)
{
    p = mci_io_put_text(p, prefix);
    for (int k = 0; k < 3; k++) {
        p = mci_io_put_uint(p, (uint64_t)abc[k] + base);
        *p++ = k < 2 ? ' ' : '\n';
    }
    return p;
}

static mcsg_status format_record_block(void *user, size_t i, mcsg_error *err)
{
    const record_job *j = user;
    const mcsg_mesh *m = j->mesh;
    size_t block = j->first_block + i;
    bool vertices = block < j->vertex_blocks;
    size_t first = (vertices ? block : block - j->vertex_blocks) * RECORD_BLOCK;
    size_t total = vertices ? m->vertex_count : m->triangle_count;
    size_t end = total - first < RECORD_BLOCK ? total : first + RECORD_BLOCK;
    size_t room = vertices ? strlen(j->vertex_prefix) + 3 * MCI_DOUBLE_TEXT_MAX + 3
                           : strlen(j->triangle_prefix) + 3 * 21 + 3;
    char *p;
    (void)err;
    if (end - first > SIZE_MAX / room || !(p = mci_io_reserve_text(j->ctx, &j->text[i],
                                                                   (end - first) * room)))
        return MCSG_ERR_NOMEM;
    for (size_t r = first; r < end; r++)
        p = vertices ? put_vertex(p, j->vertex_prefix, m->vertices + 3 * r)
                     : put_triangle(p, j->triangle_prefix, m->triangles + 3 * r, j->index_base);
    mci_io_commit_text(&j->text[i], p);
    return MCSG_OK;
}

static mcsg_status copy_record_block(void *user, size_t i, mcsg_error *err)
{
    const record_job *j = user;
    (void)err;
    if (j->text[i].len)
        memcpy(j->dest + j->offset[i], j->text[i].data, j->text[i].len);
    return MCSG_OK;
}

mcsg_status mci_io_write_text_records(const mci_ctx *ctx, const mcsg_mesh *mesh,
                                      const char *vertex_prefix, const char *triangle_prefix,
                                      uint32_t index_base, mci_buf *out)
{
    mci_buf text[RECORD_WAVE];
    size_t offset[RECORD_WAVE];
    record_job j = {ctx, mesh, vertex_prefix, triangle_prefix, index_base,
                    (mesh->vertex_count + RECORD_BLOCK - 1) / RECORD_BLOCK, 0, text, NULL, offset};
    size_t blocks = j.vertex_blocks + (mesh->triangle_count + RECORD_BLOCK - 1) / RECORD_BLOCK;
    /* Two blocks per thread in flight: a block's text is held twice until copied. */
    size_t per_wave = 2 * (size_t)mci_thread_count(ctx) < RECORD_WAVE
                          ? 2 * (size_t)mci_thread_count(ctx) : RECORD_WAVE;
    mcsg_status st = MCSG_OK;
    mcsg_error err;
    mci_ctx pooled = *ctx; /* workers kept across the waves' loops */
    memset(text, 0, sizeof text);
    pooled.owns_pool = false; /* a pool ctx has stays ctx's */
    if (blocks > per_wave)
        mci_pool_start(&pooled);
    for (; st == MCSG_OK && j.first_block < blocks; j.first_block += per_wave) {
        size_t wave = blocks - j.first_block < per_wave ? blocks - j.first_block : per_wave;
        size_t len = 0;
        st = mci_parallel_for(&pooled, wave, format_record_block, &j, &err);
        for (size_t i = 0; st == MCSG_OK && i < wave; i++) {
            offset[i] = len;
            len += text[i].len;
        }
        if (st == MCSG_OK && !mci_buf_reserve(ctx, out, len + 1))
            st = MCSG_ERR_NOMEM;
        if (st == MCSG_OK) {
            j.dest = out->data + out->len;
            st = mci_parallel_for(&pooled, wave, copy_record_block, &j, &err);
            out->len += len;
        }
        for (size_t i = 0; i < wave; i++)
            mci_buf_free(ctx, &text[i]);
    }
    mci_pool_stop(&pooled);
    /* An empty mesh still yields a buffer. */
    if (st == MCSG_OK && !mci_io_reserve_text(ctx, out, 1))
        st = MCSG_ERR_NOMEM;
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* Format names and detection                                                          */

const char *mcsg_format_name(mcsg_format format)
{
    switch (format) {
    case MCSG_FORMAT_AUTO: return "automatic";
    case MCSG_FORMAT_OFF: return "OFF";
    case MCSG_FORMAT_OBJ: return "OBJ";
    case MCSG_FORMAT_STL_ASCII: return "ASCII STL";
    case MCSG_FORMAT_STL_BINARY: return "binary STL";
    case MCSG_FORMAT_PLY_ASCII: return "ASCII PLY";
    case MCSG_FORMAT_PLY_BINARY_LE: return "binary little-endian PLY";
    case MCSG_FORMAT_PLY_BINARY_BE: return "binary big-endian PLY";
    case MCSG_FORMAT_3MF: return "3MF";
    }
    return "unknown format";
}

static bool has_extension(const char *path, const char *ext)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/') || strchr(dot, '\\'))
        return false;
    return mci_io_token_is(dot, dot + strlen(dot), ext);
}

mcsg_format mcsg_format_from_path(const char *path)
{
    if (!path)
        return MCSG_FORMAT_AUTO;
    if (has_extension(path, ".off"))
        return MCSG_FORMAT_OFF;
    if (has_extension(path, ".obj"))
        return MCSG_FORMAT_OBJ;
    if (has_extension(path, ".stl"))
        return MCSG_FORMAT_STL_BINARY;
    if (has_extension(path, ".ply"))
        return MCSG_FORMAT_PLY_BINARY_LE;
    if (has_extension(path, ".3mf"))
        return MCSG_FORMAT_3MF;
    return MCSG_FORMAT_AUTO;
}

/* The first token that is not inside a '#' comment line, or false if there is none. */
static bool first_token(const mci_io_source *src, const char **begin, const char **stop)
{
    mci_io_tokens t;
    mci_io_tokens_init(&t, src->text, src->text + src->size, 1);
    while (mci_io_next_token(&t, begin, stop)) {
        if (**begin != '#')
            return true;
        mci_io_skip_line(&t);
    }
    return false;
}

static bool is_ply_magic(const mci_io_source *src)
{
    return src->size >= 3 && memcmp(src->text, "ply", 3) == 0 &&
           (src->size == 3 || src->text[3] == '\n' || mci_io_is_blank(src->text[3]));
}

static bool looks_like_obj(const char *begin, const char *stop)
{
    static const char *const keywords[] = {"v", "vn", "vt", "f", "o", "g", "mtllib",
                                           "usemtl", "s"};
    for (size_t i = 0; i < sizeof keywords / sizeof keywords[0]; i++)
        if ((size_t)(stop - begin) == strlen(keywords[i]) &&
            memcmp(begin, keywords[i], (size_t)(stop - begin)) == 0)
            return true;
    return false;
}

/* Detect the format of src (see the file comment) and read it. */
static mcsg_status read_detected(const mci_io_source *src, mcsg_mesh *out)
{
    const char *begin = NULL, *stop = NULL;
    bool has_token = first_token(src, &begin, &stop);
    mcsg_format by_name = mcsg_format_from_path(src->name);
    if (is_ply_magic(src))
        return mci_ply_read(src, out);
    if (mci_amf_is_name(src->name) ||
        (mci_amf_looks_like(src->text, src->size) &&
         !mci_stl_binary_size_matches(src->bytes, src->size)))
        return mci_amf_read_merged(src, out); /* plain or zipped XML */
    if (by_name == MCSG_FORMAT_3MF || (src->size >= 4 && memcmp(src->text, "PK\3\4", 4) == 0))
        return mci_3mf_read_merged(src, out); /* a zip archive */
    if (has_token && mci_off_is_keyword(begin, stop))
        return mci_off_read(src, out);
    if (by_name == MCSG_FORMAT_OFF)
        return mci_off_read(src, out);
    if (by_name == MCSG_FORMAT_OBJ)
        return mci_obj_read(src, out);
    if (by_name == MCSG_FORMAT_PLY_BINARY_LE)
        return mci_ply_read(src, out);
    if (by_name == MCSG_FORMAT_STL_BINARY ||
        (has_token && mci_io_token_is(begin, stop, "solid")) ||
        mci_stl_binary_size_matches(src->bytes, src->size))
        return mci_stl_read(src, MCSG_FORMAT_AUTO, out);
    if (has_token && looks_like_obj(begin, stop))
        return mci_obj_read(src, out);
    return mci_fail(src->err, MCSG_ERR_FORMAT,
                    "%s: unknown mesh format (not OFF, OBJ, STL, PLY, 3MF or AMF by content or "
                    "name)",
                    src->name);
}

static mcsg_status read_source(const mci_io_source *src, mcsg_format format,
                               mcsg_mesh *out)
{
    switch (format) {
    case MCSG_FORMAT_AUTO: return read_detected(src, out);
    case MCSG_FORMAT_OFF: return mci_off_read(src, out);
    case MCSG_FORMAT_OBJ: return mci_obj_read(src, out);
    case MCSG_FORMAT_STL_ASCII:
    case MCSG_FORMAT_STL_BINARY: return mci_stl_read(src, format, out);
    case MCSG_FORMAT_PLY_ASCII:
    case MCSG_FORMAT_PLY_BINARY_LE:
    case MCSG_FORMAT_PLY_BINARY_BE: return mci_ply_read(src, out);
    case MCSG_FORMAT_3MF: return mci_3mf_read_merged(src, out);
    }
    return mci_fail(src->err, MCSG_ERR_INVALID_ARG, "%s: invalid format code %d", src->name,
                    (int)format);
}

/* ---------------------------------------------------------------------------------- */
/* Public entry points                                                                 */

static void init_source(mci_io_source *src, const mci_ctx *ctx, const void *data,
                        size_t size, const char *name, mcsg_error *err)
{
    src->ctx = ctx;
    src->name = name ? name : "<memory>";
    src->text = size ? (const char *)data : ""; /* never offset a NULL pointer */
    src->bytes = (const unsigned char *)src->text;
    src->size = size;
    src->err = err;
}

mcsg_status mcsg_mesh_read_memory(const void *data, size_t size, mcsg_format format,
                                  const char *name, const mcsg_options *opts,
                                  mcsg_mesh *out, mcsg_error *err)
{
    mci_ctx ctx;
    mci_io_source src;
    mci_ctx_init(&ctx, opts);
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_read_memory: NULL output");
    memset(out, 0, sizeof *out);
    if (!data && size)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_read_memory: NULL data");
    init_source(&src, &ctx, data, size, name, err);
    return read_source(&src, format, out);
}

mcsg_status mcsg_mesh_read(const char *path, mcsg_format format, const mcsg_options *opts,
                           mcsg_mesh *out, mcsg_error *err)
{
    mci_ctx ctx;
    unsigned char *data;
    size_t size;
    mcsg_status status;
    mci_ctx_init(&ctx, opts);
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_read: NULL output");
    memset(out, 0, sizeof *out);
    if (!path)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_read: NULL path");
    status = mci_read_file(&ctx, path, &data, &size, err);
    if (status != MCSG_OK)
        return status;
    status = mcsg_mesh_read_memory(data, size, format, path, opts, out, err);
    mci_free(&ctx, data);
    return status;
}

/* Writers trust their input: check counts, arrays and indices here, once. */
static mcsg_status check_writable(const mcsg_mesh *mesh, const char *name, mcsg_error *err)
{
    if (!mesh)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "%s: NULL mesh", name);
    if (mesh->vertex_count > UINT32_MAX || mesh->triangle_count > UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "%s: mesh too large to write (%zu vertices, "
                        "%zu triangles)", name, mesh->vertex_count, mesh->triangle_count);
    if ((mesh->vertex_count && !mesh->vertices) || (mesh->triangle_count && !mesh->triangles))
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "%s: mesh arrays are NULL", name);
    for (size_t i = 0; i < 3 * mesh->triangle_count; i++)
        if (mesh->triangles[i] >= mesh->vertex_count)
            return mci_fail(err, MCSG_ERR_INVALID_MESH, "%s: triangle %zu uses vertex %u "
                            "but the mesh has %zu vertices", name, i / 3,
                            (unsigned)mesh->triangles[i], mesh->vertex_count);
    return MCSG_OK;
}

static mcsg_status write_format(const mci_ctx *ctx, mcsg_format format,
                                const mcsg_mesh *mesh, mci_buf *out)
{
    switch (format) {
    case MCSG_FORMAT_OFF: return mci_off_write(ctx, mesh, out);
    case MCSG_FORMAT_OBJ: return mci_obj_write(ctx, mesh, out);
    case MCSG_FORMAT_STL_ASCII: return mci_stl_write_ascii(ctx, mesh, out);
    case MCSG_FORMAT_STL_BINARY: return mci_stl_write_binary(ctx, mesh, out);
    case MCSG_FORMAT_PLY_ASCII:
    case MCSG_FORMAT_PLY_BINARY_LE:
    case MCSG_FORMAT_PLY_BINARY_BE: return mci_ply_write(ctx, mesh, format, out);
    case MCSG_FORMAT_3MF: return mci_3mf_write(ctx, mesh, 1, out);
    case MCSG_FORMAT_AUTO: break;
    }
    return MCSG_ERR_INVALID_ARG;
}

/* Serialise into a new buffer; `name` is used in messages. */
static mcsg_status write_to_buffer(const mci_ctx *ctx, mcsg_format format,
                                   const mcsg_mesh *mesh, const char *name, mci_buf *out,
                                   mcsg_error *err)
{
    mcsg_status status;
    memset(out, 0, sizeof *out);
    if ((int)format <= (int)MCSG_FORMAT_AUTO || (int)format > (int)MCSG_FORMAT_3MF)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "%s: invalid output format code %d", name,
                        (int)format);
    status = check_writable(mesh, name, err);
    if (status != MCSG_OK)
        return status;
    status = write_format(ctx, format, mesh, out);
    if (status != MCSG_OK) {
        mci_buf_free(ctx, out);
        return mci_fail(err, status, "%s: out of memory while writing %s", name,
                        mcsg_format_name(format));
    }
    return MCSG_OK;
}

mcsg_status mcsg_mesh_write_memory(mcsg_format format, const mcsg_mesh *mesh,
                                   const mcsg_options *opts, void **data, size_t *size,
                                   mcsg_error *err)
{
    mci_ctx ctx;
    mci_buf buf;
    mcsg_status status;
    mci_ctx_init(&ctx, opts);
    if (!data || !size)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_write_memory: NULL output");
    *data = NULL;
    *size = 0;
    status = write_to_buffer(&ctx, format, mesh, "<memory>", &buf, err);
    if (status != MCSG_OK)
        return status;
    *data = buf.data;
    *size = buf.len;
    return MCSG_OK;
}

mcsg_status mcsg_mesh_write(const char *path, mcsg_format format, const mcsg_mesh *mesh,
                            const mcsg_options *opts, mcsg_error *err)
{
    mci_ctx ctx;
    mci_buf buf;
    mcsg_status status;
    mci_ctx_init(&ctx, opts);
    if (!path)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_write: NULL path");
    if (format == MCSG_FORMAT_AUTO)
        format = mcsg_format_from_path(path);
    if (format == MCSG_FORMAT_AUTO)
        return mci_fail(err, MCSG_ERR_FORMAT, "%s: cannot tell the mesh format from the "
                        "file name (use .off, .obj, .stl, .ply or .3mf)", path);
    status = write_to_buffer(&ctx, format, mesh, path, &buf, err);
    if (status != MCSG_OK)
        return status;
    status = mci_write_file_atomic(path, buf.data, buf.len, err);
    mci_buf_free(&ctx, &buf);
    return status;
}

/* ---------------------------------------------------------------------------------- */
/* 3MF, one mesh per build item                                                         */

mcsg_status mcsg_3mf_read_memory(const void *data, size_t size, const char *name,
                                 const mcsg_options *opts, mcsg_mesh **meshes,
                                 char ***names, size_t *count, mcsg_error *err)
{
    mci_ctx ctx;
    mci_io_source src;
    mci_3mf_items items;
    mcsg_status status;
    mci_ctx_init(&ctx, opts);
    if (!meshes || !count)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_3mf_read: NULL output");
    *meshes = NULL, *count = 0;
    if (names)
        *names = NULL;
    if (!data && size)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_3mf_read: NULL data");
    init_source(&src, &ctx, data, size, name, err);
    status = mci_3mf_read(&src, &items);
    if (status != MCSG_OK)
        return status;
    *meshes = items.meshes, *count = items.count;
    if (names)
        *names = items.names;
    else {
        for (size_t k = 0; k < items.count; k++)
            mci_free(&ctx, items.names[k]);
        mci_free(&ctx, items.names);
    }
    return MCSG_OK;
}

mcsg_status mcsg_3mf_read(const char *path, const mcsg_options *opts, mcsg_mesh **meshes,
                          char ***names, size_t *count, mcsg_error *err)
{
    mci_ctx ctx;
    unsigned char *data;
    size_t size;
    mcsg_status status;
    mci_ctx_init(&ctx, opts);
    if (!path)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_3mf_read: NULL path");
    status = mci_read_file(&ctx, path, &data, &size, err);
    if (status != MCSG_OK)
        return status;
    status = mcsg_3mf_read_memory(data, size, path, opts, meshes, names, count, err);
    mci_free(&ctx, data);
    return status;
}

void mcsg_3mf_free(mcsg_mesh *meshes, char **names, size_t count, const mcsg_options *opts)
{
    mci_ctx ctx;
    mci_3mf_items items = {meshes, names, count};
    mci_ctx_init(&ctx, opts);
    mci_3mf_items_free(&ctx, &items);
}

mcsg_status mcsg_3mf_write(const char *path, const mcsg_mesh *meshes, size_t count,
                           const mcsg_options *opts, mcsg_error *err)
{
    mci_ctx ctx;
    mci_buf buf = {0};
    mcsg_status status;
    mci_ctx_init(&ctx, opts);
    if (!path || !meshes || count == 0)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_3mf_write: %s",
                        !path ? "NULL path" : "no meshes");
    for (size_t k = 0; k < count; k++) {
        status = check_writable(&meshes[k], path, err);
        if (status != MCSG_OK)
            return status;
    }
    if (mci_3mf_write(&ctx, meshes, count, &buf) != MCSG_OK) {
        mci_buf_free(&ctx, &buf);
        return mci_fail(err, MCSG_ERR_NOMEM, "%s: out of memory while writing 3MF", path);
    }
    status = mci_write_file_atomic(path, buf.data, buf.len, err);
    mci_buf_free(&ctx, &buf);
    return status;
}
