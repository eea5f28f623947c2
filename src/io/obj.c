/*
 * Wavefront OBJ reader and writer for polygonal geometry, following the OBJ
 * specification (Wavefront "Advanced Visualizer" manual, appendix B1):
 *
 *   v x y z [w]       w must be 1 (other values are rational geometry: unsupported);
 *                     "v x y z r g b" (the common vertex colour extension) is accepted
 *   f v v v ...       corners as v, v/vt, v//vn or v/vt/vn; indices are 1-based, and
 *                     negative ones count back from the last vertex read; polygons are
 *                     fan-triangulated. "fo" is the obsolete spelling of "f"
 *   vt vn vp g o s usemtl mtllib   ignored
 *   l p               ignored, with one warning per file
 *   cstype curv curv2 surf parm trim hole scrv sp end con deg bmat step
 *                     free-form geometry: MCSG_ERR_UNSUPPORTED
 *   anything else     ignored with one warning per keyword
 *
 * '#' starts a comment, a backslash at the end of a line continues the record on the
 * next line, and CRLF line endings are accepted.
 */
#include "io/mesh_io.h"

#include <string.h>

/* Distinct unknown keywords reported (then silence), and the length compared. */
#define MAX_REPORTED_KEYWORDS 32
#define KEYWORD_SIZE 16

typedef struct obj_reader {
    const mci_io_source *src;
    mci_io_lines lines;
    mci_io_builder mesh;
    mci_buf joined; /* a record continued over several lines */
    size_t line;    /* first line of the current record */
    bool warned_lines_points;
    size_t unknown_count;
    char unknown[MAX_REPORTED_KEYWORDS][KEYWORD_SIZE];
} obj_reader;

static const char *const ignored_keywords[] = {"vt", "vn", "vp", "g", "o", "s", "usemtl",
                                               "mtllib"};
static const char *const freeform_keywords[] = {"cstype", "curv", "curv2", "surf", "parm",
                                                "trim",   "hole", "scrv",  "sp",   "end",
                                                "con",    "deg",  "bmat",  "step"};

static bool token_equals(const char *begin, const char *stop, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(stop - begin) == n && memcmp(begin, word, n) == 0;
}

static bool token_in(const char *begin, const char *stop, const char *const *words,
                     size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (token_equals(begin, stop, words[i]))
            return true;
    return false;
}

static mcsg_status fail_token(const obj_reader *r, const char *what, const char *token,
                              const char *stop)
{
    char excerpt[48];
    mci_io_excerpt(excerpt, token, stop);
    return mci_io_fail_line(r->src, MCSG_ERR_PARSE, r->line, "invalid %s '%s'", what,
                            excerpt);
}

/* ---------------------------------------------------------------------------------- */
/* Records                                                                             */

/* The backslash ending a line (trailing blanks allowed after it), or NULL. */
static const char *continuation_mark(const char *begin, const char *stop)
{
    while (stop > begin && mci_io_is_blank(stop[-1]))
        stop--;
    return (stop > begin && stop[-1] == '\\') ? stop - 1 : NULL;
}

/* Join a record continued with backslashes into r->joined; begin and stop hold its first
 * line on entry and the joined text on return. */
static mcsg_status join_lines(obj_reader *r, const char **begin, const char **stop)
{
    r->joined.len = 0;
    for (;;) {
        const char *mark = continuation_mark(*begin, *stop);
        const char *keep = mark ? mark : *stop;
        if (!mci_buf_append(r->src->ctx, &r->joined, *begin, (size_t)(keep - *begin)) ||
            !mci_buf_append(r->src->ctx, &r->joined, " ", 1))
            return mci_io_fail_build(r->src, MCSG_ERR_NOMEM, false, r->line);
        if (!mark || !mci_io_next_line(&r->lines, begin, stop))
            break;
    }
    *begin = (const char *)r->joined.data;
    *stop = *begin + r->joined.len;
    return MCSG_OK;
}

/* The next record without its comment; *found is false at the end of the input. */
static mcsg_status next_record(obj_reader *r, const char **begin, const char **stop,
                               bool *found)
{
    const char *hash;
    mcsg_status status = MCSG_OK;
    *found = mci_io_next_line(&r->lines, begin, stop);
    if (!*found)
        return MCSG_OK;
    r->line = r->lines.number;
    if (continuation_mark(*begin, *stop))
        status = join_lines(r, begin, stop);
    /* *stop >= *begin always; the test tells the compiler (see off.c) */
    hash = status == MCSG_OK && *stop > *begin ? memchr(*begin, '#', (size_t)(*stop - *begin))
                                               : NULL;
    if (hash)
        *stop = hash;
    return status;
}

/* ---------------------------------------------------------------------------------- */
/* Vertices and faces                                                                  */

static mcsg_status read_vertex(obj_reader *r, const char *p, const char *stop)
{
    double c[4] = {0, 0, 0, 1};
    size_t count = 0;
    mcsg_status status;
    for (;;) {
        double value;
        p = mci_io_skip_blanks(p, stop);
        if (p == stop)
            break;
        if (!mci_io_number(p, stop, &value, &p))
            return fail_token(r, "number", p, stop);
        if (count < 4)
            c[count] = value;
        count++;
    }
    if (count < 3 || count == 5)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, r->line, "vertex with %zu values "
                                "(expected x y z, x y z w or x y z r g b)", count);
    if (count == 4 && c[3] != 1.0)
        return mci_io_fail_line(r->src, MCSG_ERR_UNSUPPORTED, r->line, "homogeneous "
                                "coordinate w = %.17g is not supported (only w = 1)", c[3]);
    status = mci_io_add_vertex(&r->mesh, c[0], c[1], c[2]);
    if (status != MCSG_OK)
        return mci_io_fail_build(r->src, status, false, r->line);
    return MCSG_OK;
}

/* One corner "v", "v/vt", "v//vn" or "v/vt/vn" at *p: the 0-based vertex index. */
static mcsg_status read_corner(obj_reader *r, const char **p, const char *stop,
                               uint32_t *out)
{
    const char *token = *p, *q = *p, *digits_end;
    int64_t index, other;
    int64_t count = (int64_t)r->mesh.vertex_count;
    char excerpt[48];
    if (!mci_io_integer(q, stop, &index, &q))
        return fail_token(r, "vertex reference", token, stop);
    digits_end = q;
    for (int slash = 0; slash < 2 && q < stop && *q == '/'; slash++) {
        q++;
        if (q < stop && *q != '/' && !mci_io_is_blank(*q) &&
            !mci_io_integer(q, stop, &other, &q))
            return fail_token(r, "vertex reference", token, stop);
    }
    if (q < stop && !mci_io_is_blank(*q))
        return fail_token(r, "vertex reference", token, stop);
    if (index == 0)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, r->line, "vertex index 0 is invalid "
                                "(OBJ indices start at 1)");
    if (index > count || -index > count) {
        mci_io_excerpt_span(excerpt, token, digits_end);
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, r->line, "vertex index %s out of "
                                "range (%lld vertices)", excerpt, (long long)count);
    }
    *out = (uint32_t)(index > 0 ? index - 1 : count + index);
    *p = q;
    return MCSG_OK;
}

static mcsg_status read_face(obj_reader *r, const char *p, const char *stop)
{
    uint32_t first = 0, previous = 0, index = 0;
    size_t corners = 0;
    for (;; corners++) {
        mcsg_status status;
        p = mci_io_skip_blanks(p, stop);
        if (p == stop)
            break;
        status = read_corner(r, &p, stop, &index);
        if (status == MCSG_OK && corners >= 2)
            status = mci_io_add_triangle(&r->mesh, first, previous, index);
        if (status == MCSG_ERR_NOMEM || status == MCSG_ERR_LIMIT)
            return mci_io_fail_build(r->src, status, false, r->line);
        if (status != MCSG_OK)
            return status;
        if (corners == 0)
            first = index;
        previous = index;
    }
    if (corners < 3)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, r->line, "face with %zu corners (at "
                                "least 3 needed)", corners);
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */
/* Ignored records                                                                     */

static void warn_lines_points(obj_reader *r)
{
    if (r->warned_lines_points)
        return;
    r->warned_lines_points = true;
    mci_log(r->src->ctx, MCSG_LOG_WARNING, "%s:%zu: ignoring OBJ line and point elements "
            "(l, p)", r->src->name, r->line);
}

static void warn_unknown(obj_reader *r, const char *begin, const char *stop)
{
    char excerpt[48];
    mci_io_excerpt(excerpt, begin, stop);
    excerpt[KEYWORD_SIZE - 1] = '\0';
    for (size_t i = 0; i < r->unknown_count && i < MAX_REPORTED_KEYWORDS; i++)
        if (strcmp(r->unknown[i], excerpt) == 0)
            return;
    if (r->unknown_count < MAX_REPORTED_KEYWORDS) {
        memcpy(r->unknown[r->unknown_count], excerpt, KEYWORD_SIZE);
        mci_log(r->src->ctx, MCSG_LOG_WARNING, "%s:%zu: ignoring unknown OBJ keyword '%s'",
                r->src->name, r->line, excerpt);
    } else if (r->unknown_count == MAX_REPORTED_KEYWORDS) {
        mci_log(r->src->ctx, MCSG_LOG_WARNING, "%s:%zu: more unknown OBJ keywords, ignored "
                "without further warnings", r->src->name, r->line);
    } else {
        return;
    }
    r->unknown_count++;
}

static mcsg_status read_record(obj_reader *r, const char *p, const char *stop)
{
    const char *keyword = mci_io_skip_blanks(p, stop), *end;
    if (keyword == stop)
        return MCSG_OK;
    end = mci_io_token_end(keyword, stop);
    if (token_equals(keyword, end, "v"))
        return read_vertex(r, end, stop);
    if (token_equals(keyword, end, "f") || token_equals(keyword, end, "fo"))
        return read_face(r, end, stop);
    if (token_in(keyword, end, ignored_keywords,
                 sizeof ignored_keywords / sizeof ignored_keywords[0]))
        return MCSG_OK;
    if (token_equals(keyword, end, "l") || token_equals(keyword, end, "p")) {
        warn_lines_points(r);
        return MCSG_OK;
    }
    if (token_in(keyword, end, freeform_keywords,
                 sizeof freeform_keywords / sizeof freeform_keywords[0])) {
        char excerpt[48];
        mci_io_excerpt(excerpt, keyword, end);
        return mci_io_fail_line(r->src, MCSG_ERR_UNSUPPORTED, r->line, "free-form geometry "
                                "('%s') is not supported", excerpt);
    }
    warn_unknown(r, keyword, end);
    return MCSG_OK;
}

mcsg_status mci_obj_read(const mci_io_source *src, mcsg_mesh *out)
{
    obj_reader r;
    const char *begin, *stop;
    bool found = true;
    mcsg_status status = MCSG_OK;
    memset(&r, 0, sizeof r);
    r.src = src;
    mci_io_lines_init(&r.lines, src->text, src->text + src->size);
    mci_io_builder_init(&r.mesh, src->ctx);
    while (status == MCSG_OK) {
        status = next_record(&r, &begin, &stop, &found);
        if (status != MCSG_OK || !found)
            break;
        status = read_record(&r, begin, stop);
    }
    mci_buf_free(src->ctx, &r.joined);
    if (status != MCSG_OK) {
        mci_io_builder_free(&r.mesh);
        return status;
    }
    mci_io_builder_finish(&r.mesh, out);
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */

mcsg_status mci_obj_write(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out)
{
    return mci_io_write_text_records(ctx, mesh, "v ", "f ", 1, out);
}
