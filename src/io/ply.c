/*
 * PLY reader and writer, following Greg Turk's "The PLY Polygon File Format" (1994):
 *
 *   ply
 *   format ascii|binary_little_endian|binary_big_endian 1.0
 *   comment ... / obj_info ...
 *   element NAME COUNT
 *   property TYPE NAME | property list COUNT_TYPE ITEM_TYPE NAME
 *   end_header
 *
 * with the types char uchar short ushort int uint float double and their sized names
 * int8 uint8 int16 uint16 int32 uint32 float32 float64. The "vertex" element needs
 * scalar x, y, z properties (any type: every PLY type converts to double exactly); the
 * "face" element needs an integer list named vertex_indices or vertex_index; faces are
 * fan-triangulated. Every other element and property, lists included, is skipped in
 * all three encodings. ASCII bodies are read as whitespace-separated tokens; binary
 * reads are bounded by the remaining bytes before anything is allocated or skipped.
 */
#include "io/mesh_io.h"

#include <stdio.h>
#include <string.h>

typedef enum ply_type {
    PLY_INT8, PLY_UINT8, PLY_INT16, PLY_UINT16, PLY_INT32, PLY_UINT32, PLY_FLOAT32,
    PLY_FLOAT64
} ply_type;

static const struct {
    const char *name;
    ply_type type;
} type_names[] = {
    {"char", PLY_INT8},     {"uchar", PLY_UINT8},    {"short", PLY_INT16},
    {"ushort", PLY_UINT16}, {"int", PLY_INT32},      {"uint", PLY_UINT32},
    {"float", PLY_FLOAT32}, {"double", PLY_FLOAT64}, {"int8", PLY_INT8},
    {"uint8", PLY_UINT8},   {"int16", PLY_INT16},    {"uint16", PLY_UINT16},
    {"int32", PLY_INT32},   {"uint32", PLY_UINT32},  {"float32", PLY_FLOAT32},
    {"float64", PLY_FLOAT64},
};

typedef enum ply_role { ROLE_SKIP, ROLE_X, ROLE_Y, ROLE_Z, ROLE_INDICES } ply_role;
typedef enum ply_kind { ELEMENT_OTHER, ELEMENT_VERTEX, ELEMENT_FACE } ply_kind;
typedef enum ply_encoding { ENCODING_ASCII, ENCODING_LE, ENCODING_BE } ply_encoding;

typedef struct ply_property {
    bool is_list;
    ply_type count_type; /* lists only */
    ply_type type;       /* the value type, or the item type of a list */
    ply_role role;
} ply_property;

typedef struct ply_element {
    ply_kind kind;
    uint64_t count;
    size_t line; /* of its declaration */
    size_t first_property, property_count;
    char name[48];
} ply_element;

typedef struct ply_reader {
    const mci_io_source *src;
    mci_io_builder mesh;
    ply_encoding encoding;
    bool has_format;
    ply_element *elements;
    size_t element_count, element_cap;
    ply_property *properties;
    size_t property_count, property_cap;
    size_t body;         /* offset of the first byte after end_header */
    size_t header_lines; /* line number of end_header */
    size_t vertex_count; /* declared by the vertex element */
    /* Body cursor: a byte offset (binary) or a token scanner (ASCII). */
    size_t pos;
    mci_io_tokens tokens;
} ply_reader;

static size_t type_size(ply_type type)
{
    static const size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
    return sizes[type];
}

static bool type_is_integer(ply_type type) { return type < PLY_FLOAT32; }

static bool is_binary(const ply_reader *r) { return r->encoding != ENCODING_ASCII; }

/* ---------------------------------------------------------------------------------- */
/* Header                                                                              */

#define MAX_HEADER_TOKENS 6

/* Split a header line into tokens; returns how many (at most MAX_HEADER_TOKENS + 1,
 * which means "too many"). */
static int split_line(const char *p, const char *stop, const char *begin[],
                      const char *end[])
{
    int n = 0;
    for (;;) {
        p = mci_io_skip_blanks(p, stop);
        if (p == stop || n > MAX_HEADER_TOKENS)
            return n;
        begin[n] = p;
        p = end[n] = mci_io_token_end(p, stop);
        n++;
    }
}

static bool token_equals(const char *begin, const char *stop, const char *word)
{
    size_t n = strlen(word);
    return (size_t)(stop - begin) == n && memcmp(begin, word, n) == 0;
}

static bool lookup_type(const char *begin, const char *stop, ply_type *type)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++) {
        if (token_equals(begin, stop, type_names[i].name)) {
            *type = type_names[i].type;
            return true;
        }
    }
    return false;
}

static mcsg_status fail_token(const ply_reader *r, size_t line, const char *what,
                               const char *token, const char *stop)
{
    char excerpt[48];
    mci_io_excerpt(excerpt, token, stop);
    return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "%s '%s'", what, excerpt);
}

static mcsg_status parse_format(ply_reader *r, size_t line, int n, const char *begin[],
                                const char *end[])
{
    if (n != 3)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "expected 'format ENCODING "
                                "1.0'");
    if (r->has_format)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "second format line");
    if (token_equals(begin[1], end[1], "ascii"))
        r->encoding = ENCODING_ASCII;
    else if (token_equals(begin[1], end[1], "binary_little_endian"))
        r->encoding = ENCODING_LE;
    else if (token_equals(begin[1], end[1], "binary_big_endian"))
        r->encoding = ENCODING_BE;
    else
        return fail_token(r, line, "unknown PLY encoding", begin[1], end[1]);
    if (!token_equals(begin[2], end[2], "1.0") && !token_equals(begin[2], end[2], "1"))
        return mci_io_fail_line(r->src, MCSG_ERR_UNSUPPORTED, line, "PLY version %.*s is not "
                                "supported (only 1.0)", (int)(end[2] - begin[2] > 20 ? 20 :
                                end[2] - begin[2]), begin[2]);
    r->has_format = true;
    return MCSG_OK;
}

static mcsg_status parse_element(ply_reader *r, size_t line, int n, const char *begin[],
                                 const char *end[])
{
    ply_element *element;
    const char *next;
    int64_t count;
    if (n != 3)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "expected 'element NAME "
                                "COUNT'");
    if (!mci_io_integer(begin[2], end[2], &count, &next) || next != end[2] || count < 0)
        return fail_token(r, line, "invalid element count", begin[2], end[2]);
    if (r->element_count == r->element_cap) {
        size_t cap = r->element_cap ? 2 * r->element_cap : 4;
        ply_element *grown = mci_realloc_array(r->src->ctx, r->elements, cap, sizeof *grown);
        if (!grown)
            return mci_io_fail_build(r->src, MCSG_ERR_NOMEM, false, line);
        r->elements = grown;
        r->element_cap = cap;
    }
    element = &r->elements[r->element_count++];
    memset(element, 0, sizeof *element);
    element->count = (uint64_t)count;
    element->line = line;
    element->first_property = r->property_count;
    mci_io_excerpt(element->name, begin[1], end[1]);
    if (token_equals(begin[1], end[1], "vertex"))
        element->kind = ELEMENT_VERTEX;
    else if (token_equals(begin[1], end[1], "face"))
        element->kind = ELEMENT_FACE;
    for (size_t i = 0; i + 1 < r->element_count && element->kind != ELEMENT_OTHER; i++)
        if (r->elements[i].kind == element->kind)
            return fail_token(r, line, "second element", begin[1], end[1]);
    if (element->kind != ELEMENT_OTHER && element->count > UINT32_MAX) {
        char excerpt[48];
        mci_io_excerpt_span(excerpt, begin[2], end[2]);
        return mci_io_fail_line(r->src, MCSG_ERR_LIMIT, line, "%s %s elements exceed the "
                                "limit of 4294967295", excerpt, element->name);
    }
    return MCSG_OK;
}

/* The role of a property in its element, or an error for a misdeclared x/y/z/indices. */
static mcsg_status assign_role(ply_reader *r, size_t line, ply_property *property,
                               const char *name, const char *name_end)
{
    const ply_element *element = &r->elements[r->element_count - 1];
    static const char *const axes[] = {"x", "y", "z"};
    for (int axis = 0; axis < 3 && element->kind == ELEMENT_VERTEX; axis++) {
        if (!token_equals(name, name_end, axes[axis]))
            continue;
        if (property->is_list)
            return fail_token(r, line, "vertex coordinate must be a scalar, not a list:",
                               name, name_end);
        property->role = (ply_role)(ROLE_X + axis);
    }
    if (element->kind == ELEMENT_FACE && (token_equals(name, name_end, "vertex_indices") ||
                                          token_equals(name, name_end, "vertex_index"))) {
        if (!property->is_list)
            return fail_token(r, line, "face indices must be a list:", name, name_end);
        if (!type_is_integer(property->type))
            return fail_token(r, line, "face indices must have an integer type:", name,
                               name_end);
        property->role = ROLE_INDICES;
    }
    for (size_t i = element->first_property; i < r->property_count; i++)
        if (property->role != ROLE_SKIP && r->properties[i].role == property->role)
            return fail_token(r, line, "second property", name, name_end);
    return MCSG_OK;
}

static mcsg_status parse_property(ply_reader *r, size_t line, int n, const char *begin[],
                                  const char *end[])
{
    ply_property property = {false, PLY_UINT8, PLY_UINT8, ROLE_SKIP};
    bool is_list = n >= 2 && token_equals(begin[1], end[1], "list");
    int name = is_list ? 4 : 2;
    mcsg_status status;
    if (r->element_count == 0)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "property before any element");
    if (n != name + 1)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "expected 'property TYPE NAME' "
                                "or 'property list COUNT_TYPE ITEM_TYPE NAME'");
    property.is_list = is_list;
    if (is_list && !lookup_type(begin[2], end[2], &property.count_type))
        return fail_token(r, line, "unknown PLY type", begin[2], end[2]);
    if (is_list && !type_is_integer(property.count_type))
        return fail_token(r, line, "list count type must be an integer type, not", begin[2],
                           end[2]);
    if (!lookup_type(begin[name - 1], end[name - 1], &property.type))
        return fail_token(r, line, "unknown PLY type", begin[name - 1], end[name - 1]);
    status = assign_role(r, line, &property, begin[name], end[name]);
    if (status != MCSG_OK)
        return status;
    if (r->property_count == r->property_cap) {
        size_t cap = r->property_cap ? 2 * r->property_cap : 8;
        ply_property *grown = mci_realloc_array(r->src->ctx, r->properties, cap,
                                                sizeof *grown);
        if (!grown)
            return mci_io_fail_build(r->src, MCSG_ERR_NOMEM, false, line);
        r->properties = grown;
        r->property_cap = cap;
    }
    r->properties[r->property_count++] = property;
    r->elements[r->element_count - 1].property_count++;
    return MCSG_OK;
}

static const ply_element *find_element(const ply_reader *r, ply_kind kind)
{
    for (size_t i = 0; i < r->element_count; i++)
        if (r->elements[i].kind == kind)
            return &r->elements[i];
    return NULL;
}

static bool has_role(const ply_reader *r, const ply_element *element, ply_role role)
{
    for (size_t i = 0; i < element->property_count; i++)
        if (r->properties[element->first_property + i].role == role)
            return true;
    return false;
}

/* After end_header: what a mesh needs must have been declared. */
static mcsg_status check_header(ply_reader *r)
{
    static const char *const axes[] = {"x", "y", "z"};
    const ply_element *vertex = find_element(r, ELEMENT_VERTEX);
    const ply_element *face = find_element(r, ELEMENT_FACE);
    size_t line = r->header_lines;
    if (!r->has_format)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "missing format line");
    if (!vertex)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "no vertex element");
    for (int axis = 0; axis < 3; axis++)
        if (!has_role(r, vertex, (ply_role)(ROLE_X + axis)))
            return mci_io_fail_line(r->src, MCSG_ERR_PARSE, vertex->line, "vertex element "
                                    "has no property %s", axes[axis]);
    if (!face)
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, line, "no face element (a point "
                                "cloud is not a mesh)");
    if (!has_role(r, face, ROLE_INDICES))
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, face->line, "face element has no "
                                "vertex_indices list");
    r->vertex_count = (size_t)vertex->count;
    return MCSG_OK;
}

/* One header line after the magic; *done is set by end_header. */
static mcsg_status parse_header_line(ply_reader *r, const mci_io_lines *lines,
                                     const char *p, const char *stop, bool *done)
{
    const char *begin[MAX_HEADER_TOKENS + 1], *end[MAX_HEADER_TOKENS + 1];
    size_t line = lines->number;
    int n = split_line(p, stop, begin, end);
    if (n == 0)
        return MCSG_OK; /* blank line: tolerated */
    if (token_equals(begin[0], end[0], "comment") ||
        token_equals(begin[0], end[0], "obj_info"))
        return MCSG_OK;
    if (token_equals(begin[0], end[0], "format"))
        return parse_format(r, line, n, begin, end);
    if (token_equals(begin[0], end[0], "element"))
        return parse_element(r, line, n, begin, end);
    if (token_equals(begin[0], end[0], "property"))
        return parse_property(r, line, n, begin, end);
    if (token_equals(begin[0], end[0], "end_header") && n == 1) {
        *done = true;
        r->header_lines = line;
        r->body = (size_t)(lines->next - r->src->text);
        return check_header(r);
    }
    return fail_token(r, line, "unexpected PLY header line starting with", begin[0],
                       end[0]);
}

static mcsg_status parse_header(ply_reader *r)
{
    mci_io_lines lines;
    const char *p, *stop;
    bool done = false;
    mcsg_status status = MCSG_OK;
    mci_io_lines_init(&lines, r->src->text, r->src->text + r->src->size);
    if (!mci_io_next_line(&lines, &p, &stop) || !token_equals(p, mci_io_token_end(p, stop),
                                                              "ply"))
        return mci_io_fail_line(r->src, MCSG_ERR_PARSE, 1, "missing 'ply' magic line");
    while (status == MCSG_OK && !done) {
        if (!mci_io_next_line(&lines, &p, &stop))
            return mci_io_fail_line(r->src, MCSG_ERR_PARSE, lines.number, "missing "
                                    "end_header (the header never ends)");
        status = parse_header_line(r, &lines, p, stop, &done);
    }
    return status;
}

/* ---------------------------------------------------------------------------------- */
/* Reading values (both encodings)                                                     */

static uint64_t load_bytes(const unsigned char *p, size_t size, bool big_endian)
{
    uint64_t value = 0;
    for (size_t i = 0; i < size; i++)
        value = value << 8 | p[big_endian ? i : size - 1 - i];
    return value;
}

/* Decode an integer type, sign-extending explicitly (no implementation-defined casts). */
static int64_t decode_integer(const unsigned char *p, ply_type type, bool big_endian)
{
    size_t size = type_size(type);
    uint64_t bits = load_bytes(p, size, big_endian);
    bool is_signed = type == PLY_INT8 || type == PLY_INT16 || type == PLY_INT32;
    uint64_t sign = (uint64_t)1 << (8 * size - 1);
    if (is_signed && (bits & sign))
        return -(int64_t)((sign << 1) - bits);
    return (int64_t)bits;
}

static double decode_number(const unsigned char *p, ply_type type, bool big_endian)
{
    if (type == PLY_FLOAT32) {
        uint32_t bits = (uint32_t)load_bytes(p, 4, big_endian);
        float value;
        memcpy(&value, &bits, sizeof value);
        return value;
    }
    if (type == PLY_FLOAT64) {
        uint64_t bits = load_bytes(p, 8, big_endian);
        double value;
        memcpy(&value, &bits, sizeof value);
        return value;
    }
    return (double)decode_integer(p, type, big_endian);
}

static mcsg_status fail_truncated(ply_reader *r, const ply_element *element)
{
    if (is_binary(r))
        return mci_io_fail_byte(r->src, MCSG_ERR_PARSE, r->pos, "unexpected end of file in "
                                "element '%s'", element->name);
    return mci_io_fail_line(r->src, MCSG_ERR_PARSE, r->tokens.line, "unexpected end of file "
                            "in element '%s'", element->name);
}

/* The next ASCII token, or an end-of-file error. */
static mcsg_status next_token(ply_reader *r, const ply_element *element, const char **begin,
                              const char **stop)
{
    if (!mci_io_next_token(&r->tokens, begin, stop))
        return fail_truncated(r, element);
    return MCSG_OK;
}

/* Whether `size` more bytes are available; if not, the error is recorded. */
static mcsg_status need_bytes(ply_reader *r, const ply_element *element, uint64_t size)
{
    if (size > r->src->size - r->pos)
        return fail_truncated(r, element);
    return MCSG_OK;
}

static bool integer_fits(ply_type type, int64_t value)
{
    static const int64_t low[] = {-128, 0, -32768, 0, -2147483648LL, 0};
    static const int64_t high[] = {127, 255, 32767, 65535, 2147483647LL, 4294967295LL};
    return value >= low[type] && value <= high[type];
}

/* An ASCII value of the declared type: integers must be integer tokens in range, and
 * float values are rounded to float32 as a binary file would store them. (The decimal
 * is rounded to double first, which can change the float32 result only for decimals
 * within 2^-30 float32 ulp of a midpoint between two floats.) */
static mcsg_status parse_ascii_value(ply_reader *r, ply_type type, const char *begin,
                                     const char *stop, double *out)
{
    static const char *const names[] = {"char",  "uchar", "short", "ushort",
                                        "int",   "uint",  "float", "double"};
    const char *next;
    int64_t value;
    char what[48];
    if (!type_is_integer(type)) {
        if (!mci_io_number(begin, stop, out, &next))
            return fail_token(r, r->tokens.line, "invalid number", begin, stop);
        if (type == PLY_FLOAT32)
            *out = mci_io_to_float32(*out);
        return MCSG_OK;
    }
    if (!mci_io_integer(begin, stop, &value, &next) || next != stop ||
        !integer_fits(type, value)) {
        snprintf(what, sizeof what, "invalid %s value", names[type]);
        return fail_token(r, r->tokens.line, what, begin, stop);
    }
    *out = (double)value;
    return MCSG_OK;
}

static mcsg_status read_number(ply_reader *r, const ply_element *element, ply_type type,
                               double *out)
{
    const char *begin, *stop;
    mcsg_status status;
    if (is_binary(r)) {
        if ((status = need_bytes(r, element, type_size(type))) != MCSG_OK)
            return status;
        *out = decode_number(r->src->bytes + r->pos, type, r->encoding == ENCODING_BE);
        r->pos += type_size(type);
        return MCSG_OK;
    }
    if ((status = next_token(r, element, &begin, &stop)) != MCSG_OK)
        return status;
    return parse_ascii_value(r, type, begin, stop, out);
}

/* An integer-typed value (the header guarantees the type); exact in a double. */
static mcsg_status read_integer(ply_reader *r, const ply_element *element, ply_type type,
                                int64_t *out)
{
    double value = 0;
    mcsg_status status = read_number(r, element, type, &value);
    *out = (int64_t)value;
    return status;
}

static mcsg_status skip_values(ply_reader *r, const ply_element *element, ply_type type,
                               uint64_t count)
{
    double ignored;
    mcsg_status status = MCSG_OK;
    if (is_binary(r)) {
        if (count > (r->src->size - r->pos) / type_size(type))
            return fail_truncated(r, element);
        r->pos += (size_t)count * type_size(type);
        return MCSG_OK;
    }
    for (uint64_t i = 0; i < count && status == MCSG_OK; i++)
        status = read_number(r, element, type, &ignored);
    return status;
}

/* ---------------------------------------------------------------------------------- */
/* Elements                                                                            */

/* An error in the body at `where`: a byte offset (binary) or a line (ASCII). */
static mcsg_status fail_body(const ply_reader *r, size_t where, const char *fmt, ...)
    MCI_PRINTF(3, 4);

static mcsg_status fail_body(const ply_reader *r, size_t where, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    mci_io_vfail(r->src, MCSG_ERR_PARSE, is_binary(r), where, fmt, ap);
    va_end(ap);
    return MCSG_ERR_PARSE;
}

/* Where a value read from byte `start` was: that offset (binary), or the line of the
 * token just read (ASCII). */
static size_t value_position(const ply_reader *r, size_t start)
{
    return is_binary(r) ? start : r->tokens.line;
}

/* A face's index list of `corners` items, fan-triangulated. */
static mcsg_status read_polygon(ply_reader *r, const ply_element *element, ply_type type,
                                int64_t corners, size_t where)
{
    uint32_t first = 0, previous = 0;
    if (corners < 3)
        return fail_body(r, where, "face with %lld corners (at least 3 needed)",
                         (long long)corners);
    for (int64_t k = 0; k < corners; k++) {
        int64_t index;
        size_t start = r->pos;
        mcsg_status status = read_integer(r, element, type, &index);
        if (status != MCSG_OK)
            return status;
        where = value_position(r, start);
        if (index < 0 || (uint64_t)index >= r->vertex_count)
            return fail_body(r, where, "vertex index %lld out of range (%zu vertices)",
                             (long long)index, r->vertex_count);
        if (k >= 2 && (status = mci_io_add_triangle(&r->mesh, first, previous,
                                                     (uint32_t)index)) != MCSG_OK)
            return mci_io_fail_build(r->src, status, is_binary(r), where);
        if (k == 0)
            first = (uint32_t)index;
        previous = (uint32_t)index;
    }
    return MCSG_OK;
}

static mcsg_status read_property(ply_reader *r, const ply_element *element,
                                 const ply_property *property, double xyz[3])
{
    int64_t count;
    size_t start = r->pos, where;
    mcsg_status status;
    if (!property->is_list) {
        if (property->role == ROLE_SKIP)
            return skip_values(r, element, property->type, 1);
        return read_number(r, element, property->type, &xyz[property->role - ROLE_X]);
    }
    if ((status = read_integer(r, element, property->count_type, &count)) != MCSG_OK)
        return status;
    where = value_position(r, start);
    if (count < 0)
        return fail_body(r, where, "negative list length %lld", (long long)count);
    if (property->role == ROLE_INDICES)
        return read_polygon(r, element, property->type, count, where);
    return skip_values(r, element, property->type, (uint64_t)count);
}

/* Bytes per record when every property is a scalar, else 0. */
static size_t fixed_record_size(const ply_reader *r, const ply_element *element)
{
    size_t size = 0;
    for (size_t i = 0; i < element->property_count; i++) {
        const ply_property *property = &r->properties[element->first_property + i];
        if (property->is_list)
            return 0;
        size += type_size(property->type);
    }
    return size;
}

static mcsg_status read_element(ply_reader *r, const ply_element *element)
{
    size_t record = is_binary(r) ? fixed_record_size(r, element) : 0;
    if (element->property_count == 0)
        return MCSG_OK; /* records without properties occupy no bytes or tokens */
    if (record && element->count > (r->src->size - r->pos) / record)
        return mci_io_fail_byte(r->src, MCSG_ERR_PARSE, r->pos, "element '%s' needs %llu "
                                "records of %zu bytes but the file has only %zu bytes left",
                                element->name, (unsigned long long)element->count, record,
                                r->src->size - r->pos);
    if (record && element->kind == ELEMENT_OTHER) {
        r->pos += (size_t)element->count * record;
        return MCSG_OK;
    }
    for (uint64_t i = 0; i < element->count; i++) {
        double xyz[3] = {0, 0, 0};
        size_t start = r->pos;
        for (size_t k = 0; k < element->property_count; k++) {
            mcsg_status status =
                read_property(r, element, &r->properties[element->first_property + k], xyz);
            if (status != MCSG_OK)
                return status;
        }
        if (element->kind == ELEMENT_VERTEX) {
            mcsg_status status = mci_io_add_vertex(&r->mesh, xyz[0], xyz[1], xyz[2]);
            if (status != MCSG_OK)
                return mci_io_fail_build(r->src, status, is_binary(r),
                                         value_position(r, start));
        }
    }
    return MCSG_OK;
}

/* Reserve what the counts announce, bounded by what the remaining bytes can hold (a
 * vertex or face takes at least one byte per property, two in ASCII). */
static mcsg_status reserve_mesh(ply_reader *r)
{
    const ply_element *vertex = find_element(r, ELEMENT_VERTEX);
    const ply_element *face = find_element(r, ELEMENT_FACE);
    size_t per_byte = is_binary(r) ? 1 : 2;
    size_t remaining = r->src->size - r->body;
    size_t vertices = remaining / (per_byte * vertex->property_count);
    size_t faces = remaining / (per_byte * face->property_count);
    if (vertices > vertex->count)
        vertices = (size_t)vertex->count;
    if (faces > face->count)
        faces = (size_t)face->count;
    if (mci_io_reserve(&r->mesh, vertices, faces) != MCSG_OK)
        return mci_io_fail_build(r->src, MCSG_ERR_NOMEM, false, r->header_lines);
    return MCSG_OK;
}

static mcsg_status read_body(ply_reader *r)
{
    const char *begin, *stop;
    mcsg_status status = reserve_mesh(r);
    r->pos = r->body;
    mci_io_tokens_init(&r->tokens, r->src->text + r->body, r->src->text + r->src->size,
                       r->header_lines + 1);
    for (size_t i = 0; i < r->element_count && status == MCSG_OK; i++)
        status = read_element(r, &r->elements[i]);
    if (status != MCSG_OK)
        return status;
    if (is_binary(r) && r->pos != r->src->size)
        return mci_io_fail_byte(r->src, MCSG_ERR_PARSE, r->pos, "%zu bytes of unexpected "
                                "data after the last element", r->src->size - r->pos);
    if (!is_binary(r) && mci_io_next_token(&r->tokens, &begin, &stop))
        return fail_token(r, r->tokens.line, "unexpected data after the last element:",
                           begin, stop);
    return MCSG_OK;
}

mcsg_status mci_ply_read(const mci_io_source *src, mcsg_mesh *out)
{
    ply_reader r;
    mcsg_status status;
    memset(&r, 0, sizeof r);
    r.src = src;
    mci_io_builder_init(&r.mesh, src->ctx);
    status = parse_header(&r);
    if (status == MCSG_OK)
        status = read_body(&r);
    mci_free(src->ctx, r.elements);
    mci_free(src->ctx, r.properties);
    if (status != MCSG_OK) {
        mci_io_builder_free(&r.mesh);
        return status;
    }
    mci_io_builder_finish(&r.mesh, out);
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */
/* Writing                                                                             */

static bool write_header(const mci_ctx *ctx, const mcsg_mesh *mesh, mcsg_format format,
                         mci_buf *out)
{
    const char *encoding = format == MCSG_FORMAT_PLY_ASCII       ? "ascii"
                           : format == MCSG_FORMAT_PLY_BINARY_BE ? "binary_big_endian"
                                                                 : "binary_little_endian";
    return mci_buf_printf(ctx, out,
                          "ply\nformat %s 1.0\ncomment written by meshcsg\n"
                          "element vertex %zu\nproperty double x\nproperty double y\n"
                          "property double z\nelement face %zu\n"
                          "property list uchar uint vertex_indices\nend_header\n",
                          encoding, mesh->vertex_count, mesh->triangle_count);
}

static unsigned char *put_bytes(unsigned char *p, uint64_t value, size_t size,
                                bool big_endian)
{
    for (size_t i = 0; i < size; i++)
        p[big_endian ? size - 1 - i : i] = (unsigned char)(value >> (8 * i));
    return p + size;
}

static mcsg_status write_binary_body(const mci_ctx *ctx, const mcsg_mesh *mesh,
                                     bool big_endian, mci_buf *out)
{
    unsigned char *p;
    if (mesh->vertex_count > SIZE_MAX / 32 || mesh->triangle_count > SIZE_MAX / 32 ||
        !mci_buf_reserve(ctx, out, 24 * mesh->vertex_count + 13 * mesh->triangle_count))
        return MCSG_ERR_NOMEM;
    p = out->data + out->len;
    for (size_t i = 0; i < 3 * mesh->vertex_count; i++) {
        uint64_t bits;
        memcpy(&bits, &mesh->vertices[i], sizeof bits);
        p = put_bytes(p, bits, 8, big_endian);
    }
    for (size_t i = 0; i < mesh->triangle_count; i++) {
        *p++ = 3;
        for (int k = 0; k < 3; k++)
            p = put_bytes(p, mesh->triangles[3 * i + (size_t)k], 4, big_endian);
    }
    out->len = (size_t)(p - out->data);
    return MCSG_OK;
}

mcsg_status mci_ply_write(const mci_ctx *ctx, const mcsg_mesh *mesh, mcsg_format format,
                          mci_buf *out)
{
    if (!write_header(ctx, mesh, format, out))
        return MCSG_ERR_NOMEM;
    if (format == MCSG_FORMAT_PLY_ASCII)
        return mci_io_write_text_records(ctx, mesh, "", "3 ", 0, out);
    return write_binary_body(ctx, mesh, format == MCSG_FORMAT_PLY_BINARY_BE, out);
}
