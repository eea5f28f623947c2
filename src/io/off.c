/*
 * OFF reader and writer (ASCII only), following Geomview's OFF description:
 *
 *   [ST][C][N][4][n]OFF        header keyword; "OFF BINARY" is refused as unsupported
 *   [Ndim]                     with the n prefix only (must be 3 here)
 *   NVertices NFaces [NEdges]  may follow the keyword on the same line
 *   x y z [w] [extra...]       one vertex per line; w (4 prefix) must be 1; the
 *                              normals, colours and texture coordinates that follow are
 *                              ignored
 *   n i0 ... i(n-1) [colour]   one face per line, fan-triangulated (i0, ik, ik+1)
 *
 * '#' starts a comment anywhere; blank lines and CRLF are accepted. Only whitespace and
 * comments may follow the last face. Counts are capped by what the remaining bytes can
 * hold before anything is pre-allocated.
 */
#include "io/mesh_io.h"

#include <string.h>

typedef struct off_reader {
    const mci_io_source *src;
    mci_io_lines lines;
    const char *p, *stop; /* the unread part of the current line, comment removed */
    mci_io_builder mesh;
    bool homogeneous;   /* 4 prefix: a w coordinate follows x y z */
    bool has_dimension; /* n prefix: a dimension precedes the counts */
} off_reader;

/* Shortest lines that can hold a vertex ("0 0 0") and a face ("3 0 0 0"). */
#define MIN_VERTEX_LINE 6
#define MIN_FACE_LINE 8

static bool parse_keyword(const char *p, const char *stop, bool *homogeneous,
                          bool *has_dimension)
{
    if (stop - p >= 2 && p[0] == 'S' && p[1] == 'T')
        p += 2;
    if (p < stop && *p == 'C')
        p++;
    if (p < stop && *p == 'N')
        p++;
    *homogeneous = p < stop && *p == '4';
    if (*homogeneous)
        p++;
    *has_dimension = p < stop && *p == 'n';
    if (*has_dimension)
        p++;
    return stop - p == 3 && memcmp(p, "OFF", 3) == 0;
}

bool mci_off_is_keyword(const char *begin, const char *stop)
{
    bool homogeneous, has_dimension;
    return parse_keyword(begin, stop, &homogeneous, &has_dimension);
}

static size_t line_number(const off_reader *r)
{
    return r->lines.number ? r->lines.number : 1;
}

/* Advance to the next line with content (comments removed). False at end of input. */
static bool next_content_line(off_reader *r)
{
    const char *begin, *stop;
    while (mci_io_next_line(&r->lines, &begin, &stop)) {
        /* stop >= begin always; the test tells the compiler (across files, with LTO, it
         * otherwise warns of a negative length) */
        const char *hash = stop > begin ? memchr(begin, '#', (size_t)(stop - begin)) : NULL;
        if (hash)
            stop = hash;
        begin = mci_io_skip_blanks(begin, stop);
        if (begin < stop) {
            r->p = begin;
            r->stop = stop;
            return true;
        }
    }
    r->p = r->stop = NULL;
    return false;
}

/* The next integer on the line, read where it starts (no separate token scan: face lines
 * are most of a mesh file). *begin is where it starts, for messages; false when the line
 * has no more tokens (*begin == r->stop) or the token is not an integer. */
static bool next_integer_on_line(off_reader *r, const char **begin, int64_t *value)
{
    const char *p = mci_io_skip_blanks(r->p, r->stop), *next;
    *begin = p;
    if (p == r->stop || !mci_io_integer(p, r->stop, value, &next) ||
        (next < r->stop && !mci_io_is_blank(*next)))
        return false;
    r->p = next;
    return true;
}

static bool next_token_on_line(off_reader *r, const char **begin, const char **stop)
{
    const char *p = mci_io_skip_blanks(r->p, r->stop);
    if (p == r->stop)
        return false;
    *begin = p;
    *stop = r->p = mci_io_token_end(p, r->stop);
    return true;
}

/* The first token of a line just returned by next_content_line (which has one). */
static void take_first_token(off_reader *r, const char **begin, const char **stop)
{
    *begin = r->p;
    *stop = r->p = mci_io_token_end(r->p, r->stop);
}

static mcsg_status fail_token(const off_reader *r, const char *what, const char *token)
{
    char excerpt[48];
    mci_io_excerpt(excerpt, token, r->stop);
    return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r), "invalid %s '%s'", what,
                            excerpt);
}

/* A non-negative integer token that makes up the whole token. */
static bool parse_count(const char *begin, const char *stop, int64_t *value)
{
    const char *next;
    return mci_io_integer(begin, stop, value, &next) && next == stop && *value >= 0;
}

/* One header count, possibly on a following line. */
static mcsg_status read_count(off_reader *r, const char *what, uint32_t *out)
{
    const char *begin, *stop;
    int64_t value;
    while (!r->p || !next_token_on_line(r, &begin, &stop)) {
        if (!next_content_line(r))
            return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r),
                                    "unexpected end of file in the OFF header, expected "
                                    "the %s", what);
    }
    if (!parse_count(begin, stop, &value))
        return fail_token(r, what, begin);
    if (value > UINT32_MAX)
        return mci_io_fail_line(r->src, MCSG_ERR_LIMIT, line_number(r),
                                "%s %lld exceeds the limit of 4294967295", what,
                                (long long)value);
    *out = (uint32_t)value;
    return MCSG_OK;
}

static mcsg_status read_keyword(off_reader *r)
{
    const char *begin, *stop;
    if (!next_content_line(r))
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, 1, "empty file, expected an OFF "
                                "header");
    take_first_token(r, &begin, &stop);
    if (!parse_keyword(begin, stop, &r->homogeneous, &r->has_dimension))
        return fail_token(r, "OFF header keyword (expected OFF, COFF, NOFF, STOFF, 4OFF, "
                          "nOFF...)", begin);
    if (next_token_on_line(r, &begin, &stop)) {
        if (mci_io_token_is(begin, stop, "binary"))
            return mci_io_fail_line(r->src, MCSG_ERR_UNSUPPORTED, line_number(r),
                                    "binary OFF is not supported (convert it to ASCII OFF)");
        r->p = begin; /* a count on the keyword line: read it again below */
    }
    return MCSG_OK;
}

static mcsg_status read_header(off_reader *r, uint32_t *vertices, uint32_t *faces)
{
    const char *begin, *stop;
    uint32_t dimension;
    mcsg_status status = read_keyword(r);
    if (status == MCSG_OK && r->has_dimension) {
        status = read_count(r, "dimension", &dimension);
        if (status == MCSG_OK && dimension != 3)
            return mci_io_fail_line(r->src, MCSG_ERR_UNSUPPORTED, line_number(r),
                                    "nOFF with dimension %u is not supported (only 3)",
                                    (unsigned)dimension);
    }
    if (status == MCSG_OK)
        status = read_count(r, "vertex count", vertices);
    if (status == MCSG_OK)
        status = read_count(r, "face count", faces);
    if (status != MCSG_OK)
        return status;
    /* The edge count is optional, and only on the line of the face count. */
    if (next_token_on_line(r, &begin, &stop)) {
        int64_t value;
        if (!parse_count(begin, stop, &value))
            return fail_token(r, "edge count", begin);
        if (next_token_on_line(r, &begin, &stop))
            return fail_token(r, "data after the counts", begin);
    }
    return MCSG_OK;
}

static mcsg_status read_vertex(off_reader *r)
{
    double c[4] = {0, 0, 0, 1};
    int needed = r->homogeneous ? 4 : 3;
    mcsg_status status;
    for (int i = 0; i < needed; i++) {
        const char *p = mci_io_skip_blanks(r->p, r->stop);
        if (p == r->stop)
            return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r),
                                    "expected %d vertex coordinates, found %d", needed, i);
        if (!mci_io_number(p, r->stop, &c[i], &r->p))
            return fail_token(r, "number", p);
    }
    if (c[3] != 1.0)
        return mci_io_fail_line(r->src, MCSG_ERR_UNSUPPORTED, line_number(r),
                                "homogeneous coordinate w = %.17g is not supported (only "
                                "w = 1)", c[3]);
    status = mci_io_add_vertex(&r->mesh, c[0], c[1], c[2]);
    if (status != MCSG_OK)
        return mci_io_fail_build(r->src, status, false, line_number(r));
    return MCSG_OK;
}

/* "n i0 ... i(n-1)" followed by ignored colour values; fan-triangulated. */
static mcsg_status read_face(off_reader *r, uint32_t vertex_count)
{
    const char *begin;
    int64_t corners, index;
    uint32_t first = 0, previous = 0;
    if (!next_integer_on_line(r, &begin, &corners) || corners < 0)
        return fail_token(r, "corner count", begin);
    if (corners < 3)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r), "polygon with %lld "
                                "corners (at least 3 needed)", (long long)corners);
    for (int64_t k = 0; k < corners; k++) {
        if (!next_integer_on_line(r, &begin, &index)) {
            if (begin == r->stop)
                return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r), "expected "
                                        "%lld vertex indices, found %lld", (long long)corners,
                                        (long long)k);
            return fail_token(r, "vertex index", begin);
        }
        if (index < 0 || index >= vertex_count) {
            char excerpt[48];
            mci_io_excerpt_span(excerpt, begin, r->p);
            return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r), "vertex index "
                                    "%s out of range (%u vertices)", excerpt,
                                    (unsigned)vertex_count);
        }
        if (k >= 2) {
            mcsg_status status =
                mci_io_add_triangle(&r->mesh, first, previous, (uint32_t)index);
            if (status != MCSG_OK)
                return mci_io_fail_build(r->src, status, false, line_number(r));
        }
        if (k == 0)
            first = (uint32_t)index;
        previous = (uint32_t)index;
    }
    return MCSG_OK;
}

static size_t at_most(size_t a, size_t b) { return a < b ? a : b; }

static mcsg_status read_body(off_reader *r, uint32_t vertices, uint32_t faces)
{
    /* Reserve what the header announces, but no more than the rest can hold. */
    size_t remaining = (size_t)(r->lines.end - r->lines.next);
    mcsg_status status =
        mci_io_reserve(&r->mesh, at_most(vertices, remaining / MIN_VERTEX_LINE),
                       at_most(faces, remaining / MIN_FACE_LINE));
    if (status != MCSG_OK)
        return mci_io_fail_build(r->src, status, false, line_number(r));
    for (uint32_t i = 0; i < vertices && status == MCSG_OK; i++) {
        if (!next_content_line(r))
            return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r),
                                    "unexpected end of file, expected %u vertices, found %u",
                                    (unsigned)vertices, (unsigned)i);
        status = read_vertex(r);
    }
    for (uint32_t i = 0; i < faces && status == MCSG_OK; i++) {
        if (!next_content_line(r))
            return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line_number(r),
                                    "unexpected end of file, expected %u faces, found %u",
                                    (unsigned)faces, (unsigned)i);
        status = read_face(r, vertices);
    }
    if (status == MCSG_OK && next_content_line(r))
        return fail_token(r, "data after the last face", r->p);
    return status;
}

mcsg_status mci_off_read(const mci_io_source *src, mcsg_mesh *out)
{
    off_reader r;
    uint32_t vertices = 0, faces = 0;
    mcsg_status status;
    memset(&r, 0, sizeof r);
    r.src = src;
    mci_io_lines_init(&r.lines, src->text, src->text + src->size);
    mci_io_builder_init(&r.mesh, src->ctx);
    status = read_header(&r, &vertices, &faces);
    if (status == MCSG_OK)
        status = read_body(&r, vertices, faces);
    if (status != MCSG_OK) {
        mci_io_builder_free(&r.mesh);
        return status;
    }
    mci_io_builder_finish(&r.mesh, out);
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */

mcsg_status mci_off_write(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out)
{
    char *p = mci_io_reserve_text(ctx, out, 64);
    if (!p)
        return MCSG_ERR_NOMEM;
    p = mci_io_put_text(p, "OFF\n");
    p = mci_io_put_uint(p, mesh->vertex_count);
    p = mci_io_put_text(p, " ");
    p = mci_io_put_uint(p, mesh->triangle_count);
    mci_io_commit_text(out, mci_io_put_text(p, " 0\n"));
    return mci_io_write_text_records(ctx, mesh, "", "3 ", 0, out);
}
