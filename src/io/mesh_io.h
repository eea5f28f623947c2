/*
 * Internals shared by the mesh file readers and writers (mesh_io.c, off.c, obj.c, stl.c, ply.c): the input
 * description and error reporting, a growable mesh, text scanning helpers and the
 * per-format entry points. Not part of the public API.
 */
#ifndef MESHCSG_IO_MESH_IO_H
#define MESHCSG_IO_MESH_IO_H

#include "base/core.h"
#include "base/numparse.h"

/* ---------------------------------------------------------------------------------- */
/* Input and errors                                                                    */

/* One input buffer being read. `text` and `bytes` are the same memory, which is not
 * NUL-terminated: every access is bounded by `size`. */
typedef struct mci_io_source {
    const mci_ctx *ctx;
    const char *name; /* path, caller's name, or "<memory>": the prefix of every message */
    const char *text;
    const unsigned char *bytes;
    size_t size;
    mcsg_error *err;
} mci_io_source;

/* "NAME:LINE: message" (text formats). Returns `status`. */
mcsg_status mci_io_fail_line(const mci_io_source *src, mcsg_status status, size_t line,
                             const char *fmt, ...) MCI_PRINTF(4, 5);
/* "NAME: byte OFFSET: message" (binary formats). Returns `status`. */
mcsg_status mci_io_fail_byte(const mci_io_source *src, mcsg_status status, size_t offset,
                             const char *fmt, ...) MCI_PRINTF(4, 5);
/* Either of the two from a va_list: at byte `where` when binary, else at line `where`. */
mcsg_status mci_io_vfail(const mci_io_source *src, mcsg_status status, bool binary,
                         size_t where, const char *fmt, va_list ap);
/* Report a failure of the mesh builder (MCSG_ERR_NOMEM or MCSG_ERR_LIMIT) at a line
 * (binary == false) or byte offset (binary == true). Returns `status`. */
mcsg_status mci_io_fail_build(const mci_io_source *src, mcsg_status status, bool binary,
                              size_t where);

/* ---------------------------------------------------------------------------------- */
/* A mesh under construction                                                           */

typedef struct mci_io_builder {
    const mci_ctx *ctx;
    double *vertices;
    uint32_t *triangles;
    size_t vertex_count, vertex_cap;     /* in vertices (3 doubles each) */
    size_t triangle_count, triangle_cap; /* in triangles (3 indices each) */
} mci_io_builder;

void mci_io_builder_init(mci_io_builder *b, const mci_ctx *ctx);
/* Pre-allocate room. Callers bound the counts by what the remaining input could hold,
 * so that a header claiming 2^60 elements cannot trigger a huge allocation. */
mcsg_status mci_io_reserve(mci_io_builder *b, size_t vertices, size_t triangles);
/* Double the capacity; MCSG_ERR_LIMIT past UINT32_MAX elements, or MCSG_ERR_NOMEM. */
mcsg_status mci_io_grow_vertices(mci_io_builder *b);
mcsg_status mci_io_grow_triangles(mci_io_builder *b);
/* Move the arrays into *out (trimmed to size) and reset the builder. */
void mci_io_builder_finish(mci_io_builder *b, mcsg_mesh *out);
void mci_io_builder_free(mci_io_builder *b);

static inline mcsg_status mci_io_add_vertex(mci_io_builder *b, double x, double y, double z)
{
    double *v;
    if (b->vertex_count == b->vertex_cap) {
        mcsg_status status = mci_io_grow_vertices(b);
        if (status != MCSG_OK)
            return status;
    }
    v = b->vertices + 3 * b->vertex_count++;
    v[0] = x;
    v[1] = y;
    v[2] = z;
    return MCSG_OK;
}

static inline mcsg_status mci_io_add_triangle(mci_io_builder *b, uint32_t a, uint32_t c1,
                                              uint32_t c2)
{
    uint32_t *t;
    if (b->triangle_count == b->triangle_cap) {
        mcsg_status status = mci_io_grow_triangles(b);
        if (status != MCSG_OK)
            return status;
    }
    t = b->triangles + 3 * b->triangle_count++;
    t[0] = a;
    t[1] = c1;
    t[2] = c2;
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */
/* Text scanning                                                                       */

/* Blanks separate tokens within a line ('\r' included, for CRLF files). */
static inline bool mci_io_is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* Iterates over lines: `number` is the 1-based number of the line last returned. */
typedef struct mci_io_lines {
    const char *next, *end;
    size_t number;
} mci_io_lines;

void mci_io_lines_init(mci_io_lines *it, const char *begin, const char *end);
/* The next line, without its "\n" or "\r\n". False at the end of the input. */
bool mci_io_next_line(mci_io_lines *it, const char **begin, const char **stop);

/* Iterates over whitespace-separated tokens across lines, counting lines. */
typedef struct mci_io_tokens {
    const char *p, *end;
    size_t line; /* line of the token last returned (or of the current position) */
} mci_io_tokens;

void mci_io_tokens_init(mci_io_tokens *t, const char *begin, const char *end, size_t line);
bool mci_io_next_token(mci_io_tokens *t, const char **begin, const char **stop);
/* Skip the rest of the current line, including its newline. */
void mci_io_skip_line(mci_io_tokens *t);

const char *mci_io_skip_blanks(const char *p, const char *end);
const char *mci_io_token_end(const char *p, const char *end);
/* Case-insensitive comparison of the token [begin, stop) with a lower-case word. */
bool mci_io_token_is(const char *begin, const char *stop, const char *word);
/* Copy the token starting at p (at most 40 characters, non-printable bytes shown as
 * '?') for an error message. */
void mci_io_excerpt(char out[48], const char *p, const char *end);
/* The same for the exact span [begin, stop). */
void mci_io_excerpt_span(char out[48], const char *begin, const char *stop);

/* A number (see numparse.h) that must end at a blank or at `end`. On success stores it,
 * sets *next after it and returns true. */
bool mci_io_number(const char *p, const char *end, double *out, const char **next);
/* An optionally signed decimal integer (no terminator check). Values beyond +-2^62
 * saturate there, which every caller rejects as out of range. */
bool mci_io_integer(const char *p, const char *end, int64_t *out, const char **next);

/* float32 rounding of d (round to nearest even, overflow to infinity), without the
 * undefined behaviour of an out-of-range conversion in ISO C. */
float mci_io_to_float32(double d);

/* ---------------------------------------------------------------------------------- */
/* Writing                                                                             */

/* Append-only text output. Each writer reserves room for a record, then fills it. */
char *mci_io_put_uint(char *p, uint64_t value);
/* p needs MCI_DOUBLE_TEXT_MAX bytes of room; the text is shorter (see numparse.h). */
char *mci_io_put_double(char *p, double value);
char *mci_io_put_text(char *p, const char *text);
/* Room for one record of text: returns the write position or NULL (out of memory). */
char *mci_io_reserve_text(const mci_ctx *ctx, mci_buf *out, size_t bytes);
/* Mark the text written up to `stop` (inside the reserved room) as part of out. */
void mci_io_commit_text(mci_buf *out, const char *stop);
/* The vertex and triangle lines of OFF, OBJ and ASCII PLY: "<vertex_prefix>x y z" per
 * vertex, then "<triangle_prefix>a b c" per triangle with indices + index_base. */
mcsg_status mci_io_write_text_records(const mci_ctx *ctx, const mcsg_mesh *mesh,
                                      const char *vertex_prefix, const char *triangle_prefix,
                                      uint32_t index_base, mci_buf *out);

/* ---------------------------------------------------------------------------------- */
/* Formats. Readers fill *out on success (and leave it zeroed on error); writers append
 * to *out and return MCSG_OK or MCSG_ERR_NOMEM without a message (the caller adds it).
 * Writers get meshes already checked: counts <= UINT32_MAX, indices in range. */

bool mci_off_is_keyword(const char *begin, const char *stop);
mcsg_status mci_off_read(const mci_io_source *src, mcsg_mesh *out);
mcsg_status mci_off_write(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out);

mcsg_status mci_obj_read(const mci_io_source *src, mcsg_mesh *out);
mcsg_status mci_obj_write(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out);

/* True when the size matches the triangle count of a binary STL header. */
bool mci_stl_binary_size_matches(const unsigned char *bytes, size_t size);
/* `format`: MCSG_FORMAT_STL_ASCII, MCSG_FORMAT_STL_BINARY, or AUTO to detect. */
mcsg_status mci_stl_read(const mci_io_source *src, mcsg_format format, mcsg_mesh *out);
mcsg_status mci_stl_write_ascii(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out);
mcsg_status mci_stl_write_binary(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out);

/* The encoding comes from the header, whichever PLY format was asked for. */
mcsg_status mci_ply_read(const mci_io_source *src, mcsg_mesh *out);
/* `format`: one of the three MCSG_FORMAT_PLY_* values. */
mcsg_status mci_ply_write(const mci_ctx *ctx, const mcsg_mesh *mesh, mcsg_format format,
                          mci_buf *out);

#endif
