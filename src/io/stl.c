/*
 * STL reader and writer, ASCII and binary, following the 3D Systems StereoLithography
 * Interface Specification (1988) and common practice:
 *
 *  - Binary: an 80-byte header (ignored), a uint32 little-endian triangle count, then
 *    per triangle 12 float32 little-endian values (normal, three vertices) and a
 *    2-byte attribute (ignored). A file is binary when its size is exactly
 *    84 + 50 * count, even if the header starts with "solid" (many exporters do that).
 *  - ASCII: "solid name" / "facet normal nx ny nz" / "outer loop" / "vertex x y z" x3 /
 *    "endloop" / "endfacet" / "endsolid name", keywords case-insensitive, several solids
 *    per file, normals ignored.
 *
 * STL stores every triangle with its own corners, so vertices with identical
 * coordinates (-0 == +0) are welded through an open-addressing hash table; the vertex
 * order is the order of first appearance. NaN coordinates are never welded.
 * The binary writer rounds to float32 and logs how many coordinates changed.
 */
#include "io/mesh_io.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#if FLT_MANT_DIG != 24 || FLT_MAX_EXP != 128
#error "binary STL needs float to be IEEE binary32"
#endif

#define BINARY_HEADER_SIZE 84
#define BINARY_RECORD_SIZE 50

/* Slots hold the high 32 bits of the point's hash, which rule out almost every
 * mismatch without a look at the vertex array, and the vertex index + 1 in the low 32
 * bits (0: empty). The capacity is a power of two, at most half full. */
typedef struct weld_table {
    uint64_t *slots;
    size_t capacity;
    size_t used;
    uint64_t warm; /* see warm_slots */
} weld_table;

#define TAG_MASK 0xffffffff00000000ull
/* Triangles whose slots are looked up together (see warm_slots). */
#define BLOCK_TRIANGLES 8

typedef struct stl_reader {
    const mci_io_source *src;
    mci_io_builder mesh;
    weld_table table;
} stl_reader;

static uint32_t read_u32_le(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static double read_f32_le(const unsigned char *p)
{
    uint32_t bits = read_u32_le(p);
    float value;
    memcpy(&value, &bits, sizeof value);
    return value; /* exact: every float is a double */
}

/* ---------------------------------------------------------------------------------- */
/* Welding                                                                             */

static uint64_t coordinate_key(double x)
{
    uint64_t bits;
    x += 0.0; /* -0 + +0 is +0: both zeros hash alike */
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

static uint64_t hash_point(const double p[3])
{
    uint64_t h = coordinate_key(p[0]);
    h = (h ^ (h >> 29)) * 0xbf58476d1ce4e5b9ull + coordinate_key(p[1]);
    h = (h ^ (h >> 29)) * 0x94d049bb133111ebull + coordinate_key(p[2]);
    h = (h ^ (h >> 32)) * 0xff51afd7ed558ccdull;
    return h ^ (h >> 29);
}

/* A free slot for a point with this hash (a point known not to be in the table). */
static size_t free_slot(const weld_table *table, uint64_t hash)
{
    size_t mask = table->capacity - 1, i = (size_t)hash & mask;
    while (table->slots[i])
        i = (i + 1) & mask;
    return i;
}

/* Resize to `capacity` slots and re-insert every non-NaN vertex. */
static mcsg_status rehash(stl_reader *r, size_t capacity)
{
    weld_table grown = {NULL, capacity, r->table.used, r->table.warm};
    grown.slots = mci_calloc_array(r->src->ctx, capacity, sizeof(uint64_t));
    if (!grown.slots)
        return MCSG_ERR_NOMEM;
    for (size_t v = 0; v < r->mesh.vertex_count; v++) {
        const double *p = r->mesh.vertices + 3 * v;
        if (!isnan(p[0]) && !isnan(p[1]) && !isnan(p[2])) {
            uint64_t hash = hash_point(p);
            grown.slots[free_slot(&grown, hash)] = (hash & TAG_MASK) | (v + 1);
        }
    }
    mci_free(r->src->ctx, r->table.slots);
    r->table = grown;
    return MCSG_OK;
}

static mcsg_status add_vertex(stl_reader *r, const double p[3], uint32_t *index)
{
    mcsg_status status = mci_io_add_vertex(&r->mesh, p[0], p[1], p[2]);
    *index = (uint32_t)(r->mesh.vertex_count - 1);
    return status;
}

/* The index of the vertex at p (whose hash_point is `hash`), created if no earlier
 * vertex has these coordinates. */
static mcsg_status weld_vertex(stl_reader *r, const double p[3], uint64_t hash,
                               uint32_t *index)
{
    mcsg_status status;
    size_t mask, i;
    uint64_t tag = hash & TAG_MASK;
    if (isnan(p[0]) || isnan(p[1]) || isnan(p[2]))
        return add_vertex(r, p, index);
    if (2 * (r->table.used + 1) > r->table.capacity) {
        status = rehash(r, 2 * r->table.capacity);
        if (status != MCSG_OK)
            return status;
    }
    mask = r->table.capacity - 1;
    for (i = (size_t)hash & mask; r->table.slots[i]; i = (i + 1) & mask) {
        uint64_t slot = r->table.slots[i];
        const double *v = r->mesh.vertices + 3 * (size_t)((uint32_t)slot - 1);
        if ((slot & TAG_MASK) == tag && v[0] == p[0] && v[1] == p[1] && v[2] == p[2]) {
            *index = (uint32_t)slot - 1;
            return MCSG_OK;
        }
    }
    status = add_vertex(r, p, index);
    if (status != MCSG_OK)
        return status;
    r->table.slots[i] = tag | ((uint64_t)*index + 1);
    r->table.used++;
    return MCSG_OK;
}

/* Load the first slot of each point of a block before welding any of them: the cache
 * misses of independent loads overlap (memory-level parallelism), where welding one
 * point after the other would wait for each in turn. The loaded values are folded into
 * table.warm only so that the compiler keeps the loads. */
static void warm_slots(weld_table *table, const uint64_t *hashes, size_t count)
{
    size_t mask = table->capacity - 1;
    uint64_t fold = 0;
    for (size_t k = 0; k < count; k++)
        fold ^= table->slots[(size_t)hashes[k] & mask];
    table->warm ^= fold;
}

/* Start with room for about `expected` distinct vertices. */
static mcsg_status init_table(stl_reader *r, size_t expected)
{
    size_t capacity = 1024;
    while (capacity < 2 * expected && capacity < ((size_t)1 << 40))
        capacity *= 2;
    r->table.capacity = capacity / 2; /* rehash doubles it */
    r->table.used = 0;
    return rehash(r, capacity);
}

/* ---------------------------------------------------------------------------------- */
/* Binary                                                                              */

bool mci_stl_binary_size_matches(const unsigned char *bytes, size_t size)
{
    if (size < BINARY_HEADER_SIZE)
        return false;
    return (uint64_t)size - BINARY_HEADER_SIZE ==
           (uint64_t)BINARY_RECORD_SIZE * read_u32_le(bytes + 80);
}

static mcsg_status binary_size_error(const mci_io_source *src)
{
    uint64_t count, needed;
    if (src->size < BINARY_HEADER_SIZE)
        return mci_io_fail_byte(src, MCSG_ERR_PARSE, 0, "too small for a binary STL (%zu "
                                "bytes, at least 84 needed)", src->size);
    count = read_u32_le(src->bytes + 80);
    needed = BINARY_HEADER_SIZE + BINARY_RECORD_SIZE * count;
    return mci_io_fail_byte(src, MCSG_ERR_PARSE, 80, "binary STL header says %llu triangles "
                            "(needs %llu bytes) but the file has %zu bytes",
                            (unsigned long long)count, (unsigned long long)needed, src->size);
}

/* Decode a block of `count` triangles starting at triangle `first`. */
static void decode_block(const unsigned char *bytes, size_t first, size_t count,
                         double points[][3], uint64_t *hashes)
{
    for (size_t t = 0; t < count; t++) {
        /* Skip the header, the earlier records and this record's normal. */
        const unsigned char *corner =
            bytes + BINARY_HEADER_SIZE + BINARY_RECORD_SIZE * (first + t) + 12;
        for (size_t k = 3 * t; k < 3 * t + 3; k++, corner += 12) {
            points[k][0] = read_f32_le(corner);
            points[k][1] = read_f32_le(corner + 4);
            points[k][2] = read_f32_le(corner + 8);
            hashes[k] = hash_point(points[k]);
        }
    }
}

static mcsg_status read_binary(stl_reader *r)
{
    size_t count = read_u32_le(r->src->bytes + 80);
    mcsg_status status = mci_io_reserve(&r->mesh, count / 2 + 4, count);
    if (status == MCSG_OK)
        status = init_table(r, count / 2 + 4); /* a closed mesh has ~count/2 vertices */
    if (status != MCSG_OK)
        return mci_io_fail_build(r->src, status, true, 80);
    for (size_t first = 0; first < count; first += BLOCK_TRIANGLES) {
        double points[3 * BLOCK_TRIANGLES][3];
        uint64_t hashes[3 * BLOCK_TRIANGLES];
        uint32_t index[3 * BLOCK_TRIANGLES];
        size_t n = count - first < BLOCK_TRIANGLES ? count - first : BLOCK_TRIANGLES;
        decode_block(r->src->bytes, first, n, points, hashes);
        warm_slots(&r->table, hashes, 3 * n);
        for (size_t k = 0; k < 3 * n && status == MCSG_OK; k++) {
            status = weld_vertex(r, points[k], hashes[k], &index[k]);
            if (status == MCSG_OK && k % 3 == 2)
                status = mci_io_add_triangle(&r->mesh, index[k - 2], index[k - 1], index[k]);
            if (status != MCSG_OK)
                return mci_io_fail_build(r->src, status, true, BINARY_HEADER_SIZE +
                                         BINARY_RECORD_SIZE * (first + k / 3));
        }
    }
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */
/* ASCII                                                                               */

typedef struct stl_text {
    stl_reader *r;
    mci_io_tokens tokens;
    const char *token, *token_end; /* the token last read */
} stl_text;

static bool next_token(stl_text *s)
{
    return mci_io_next_token(&s->tokens, &s->token, &s->token_end);
}

static bool token_is(const stl_text *s, const char *word)
{
    return mci_io_token_is(s->token, s->token_end, word);
}

static mcsg_status fail_expected(const stl_text *s, const char *expected, bool at_end)
{
    char excerpt[48];
    if (at_end)
        return mci_io_fail_line(s->r->src, MCSG_ERR_PARSE, s->tokens.line, "unexpected end "
                                "of file, expected %s", expected);
    mci_io_excerpt(excerpt, s->token, s->token_end);
    return mci_io_fail_line(s->r->src, MCSG_ERR_PARSE, s->tokens.line, "expected %s, found "
                            "'%s'", expected, excerpt);
}

static mcsg_status expect(stl_text *s, const char *word)
{
    char quoted[32];
    bool found = next_token(s);
    if (found && token_is(s, word))
        return MCSG_OK;
    snprintf(quoted, sizeof quoted, "'%s'", word);
    return fail_expected(s, quoted, !found);
}

static mcsg_status read_point(stl_text *s, double p[3])
{
    for (int k = 0; k < 3; k++) {
        const char *next;
        bool found = next_token(s);
        if (!found || !mci_io_number(s->token, s->token_end, &p[k], &next))
            return fail_expected(s, "a number", !found);
    }
    return MCSG_OK;
}

/* After "facet": normal, loop of exactly three vertices, "endfacet". */
static mcsg_status read_facet(stl_text *s)
{
    size_t line = s->tokens.line;
    double p[3];
    uint32_t index[3];
    int corners = 0;
    mcsg_status status = expect(s, "normal");
    if (status == MCSG_OK)
        status = read_point(s, p);
    if (status == MCSG_OK)
        status = expect(s, "outer");
    if (status == MCSG_OK)
        status = expect(s, "loop");
    while (status == MCSG_OK) {
        bool found = next_token(s);
        if (found && token_is(s, "endloop"))
            break;
        if (!found || !token_is(s, "vertex"))
            return fail_expected(s, "'vertex' or 'endloop'", !found);
        if (corners == 3)
            return mci_io_fail_line(s->r->src, MCSG_ERR_PARSE, line, "facet with more than "
                                    "3 vertices");
        status = read_point(s, p);
        if (status == MCSG_OK &&
            (status = weld_vertex(s->r, p, hash_point(p), &index[corners++])) != MCSG_OK)
            return mci_io_fail_build(s->r->src, status, false, s->tokens.line);
    }
    if (status == MCSG_OK && corners != 3)
        return mci_io_fail_line(s->r->src, MCSG_ERR_PARSE, line, "facet with %d vertices "
                                "(expected 3)", corners);
    if (status == MCSG_OK)
        status = expect(s, "endfacet");
    if (status == MCSG_OK &&
        (status = mci_io_add_triangle(&s->r->mesh, index[0], index[1], index[2])) != MCSG_OK)
        return mci_io_fail_build(s->r->src, status, false, line);
    return status;
}

/* After "solid name": facets up to "endsolid". */
static mcsg_status read_solid(stl_text *s)
{
    mcsg_status status = MCSG_OK;
    while (status == MCSG_OK) {
        bool found = next_token(s);
        if (found && token_is(s, "endsolid")) {
            mci_io_skip_line(&s->tokens); /* its optional name */
            return MCSG_OK;
        }
        if (!found || !token_is(s, "facet"))
            return fail_expected(s, "'facet' or 'endsolid'", !found);
        status = read_facet(s);
    }
    return status;
}

static mcsg_status read_ascii(stl_reader *r)
{
    stl_text s;
    mcsg_status status = init_table(r, 0);
    s.r = r;
    mci_io_tokens_init(&s.tokens, r->src->text, r->src->text + r->src->size, 1);
    if (status != MCSG_OK)
        return mci_io_fail_build(r->src, status, false, 1);
    if (!next_token(&s))
        return fail_expected(&s, "'solid'", true);
    do {
        if (!token_is(&s, "solid"))
            return fail_expected(&s, "'solid'", false);
        mci_io_skip_line(&s.tokens); /* the solid's name */
        status = read_solid(&s);
    } while (status == MCSG_OK && next_token(&s));
    return status;
}

/* ---------------------------------------------------------------------------------- */

static bool starts_with_solid(const mci_io_source *src)
{
    mci_io_tokens t;
    const char *begin, *stop;
    mci_io_tokens_init(&t, src->text, src->text + src->size, 1);
    return mci_io_next_token(&t, &begin, &stop) && mci_io_token_is(begin, stop, "solid");
}

static mcsg_status read_detected(stl_reader *r, mcsg_format format)
{
    const mci_io_source *src = r->src;
    bool binary_size = mci_stl_binary_size_matches(src->bytes, src->size);
    if (format == MCSG_FORMAT_STL_BINARY)
        return binary_size ? read_binary(r) : binary_size_error(src);
    if (format == MCSG_FORMAT_STL_ASCII)
        return read_ascii(r);
    if (binary_size)
        return read_binary(r);
    if (starts_with_solid(src))
        return read_ascii(r);
    if (src->size >= BINARY_HEADER_SIZE)
        return binary_size_error(src);
    return mci_fail(src->err, MCSG_ERR_FORMAT, "%s: not an STL file: no 'solid' keyword "
                    "and too small for a binary STL (%zu bytes)", src->name, src->size);
}

mcsg_status mci_stl_read(const mci_io_source *src, mcsg_format format, mcsg_mesh *out)
{
    stl_reader r;
    mcsg_status status;
    memset(&r, 0, sizeof r);
    r.src = src;
    mci_io_builder_init(&r.mesh, src->ctx);
    status = read_detected(&r, format);
    mci_free(src->ctx, r.table.slots);
    if (status != MCSG_OK) {
        mci_io_builder_free(&r.mesh);
        return status;
    }
    mci_io_builder_finish(&r.mesh, out);
    return MCSG_OK;
}

/* ---------------------------------------------------------------------------------- */
/* Writing                                                                             */

/* The unit normal of a triangle, computed in double; zero when degenerate. */
static void triangle_normal(const mcsg_mesh *mesh, const uint32_t *t, double n[3])
{
    const double *a = mesh->vertices + 3 * (size_t)t[0];
    const double *b = mesh->vertices + 3 * (size_t)t[1];
    const double *c = mesh->vertices + 3 * (size_t)t[2];
    double u[3], v[3], scale = 0, length;
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        scale = fmax(scale, fmax(fabs(u[k]), fabs(v[k])));
    }
    n[0] = n[1] = n[2] = 0;
    if (!(scale > 0) || !isfinite(scale))
        return;
    for (int k = 0; k < 3; k++) { /* scaled so that huge coordinates cannot overflow */
        u[k] /= scale;
        v[k] /= scale;
    }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int k = 0; k < 3; k++)
        n[k] = length > 0 ? n[k] / length : 0;
}

static char *put_point(char *p, const char *keyword, const double v[3])
{
    p = mci_io_put_text(p, keyword);
    for (int k = 0; k < 3; k++) {
        *p++ = ' ';
        p = mci_io_put_double(p, v[k]);
    }
    *p++ = '\n';
    return p;
}

mcsg_status mci_stl_write_ascii(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out)
{
    char *p = mci_io_reserve_text(ctx, out, 32);
    if (!p)
        return MCSG_ERR_NOMEM;
    mci_io_commit_text(out, mci_io_put_text(p, "solid meshcsg\n"));
    for (size_t i = 0; i < mesh->triangle_count; i++) {
        const uint32_t *t = mesh->triangles + 3 * i;
        double normal[3];
        if (!(p = mci_io_reserve_text(ctx, out, 4 * (3 * MCI_DOUBLE_TEXT_MAX + 32) + 64)))
            return MCSG_ERR_NOMEM;
        triangle_normal(mesh, t, normal);
        p = put_point(p, "facet normal", normal);
        p = mci_io_put_text(p, "  outer loop\n");
        for (int k = 0; k < 3; k++)
            p = put_point(p, "    vertex", mesh->vertices + 3 * (size_t)t[k]);
        mci_io_commit_text(out, mci_io_put_text(p, "  endloop\nendfacet\n"));
    }
    if (!(p = mci_io_reserve_text(ctx, out, 32)))
        return MCSG_ERR_NOMEM;
    mci_io_commit_text(out, mci_io_put_text(p, "endsolid meshcsg\n"));
    return MCSG_OK;
}

static unsigned char *put_f32_le(unsigned char *p, double d)
{
    float f = mci_io_to_float32(d);
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits);
    for (int k = 0; k < 4; k++)
        *p++ = (unsigned char)(bits >> (8 * k));
    return p;
}

static size_t count_rounded_coordinates(const mcsg_mesh *mesh)
{
    size_t rounded = 0;
    for (size_t i = 0; i < 3 * mesh->vertex_count; i++) {
        double d = mesh->vertices[i];
        if (!isnan(d) && (double)mci_io_to_float32(d) != d)
            rounded++;
    }
    return rounded;
}

mcsg_status mci_stl_write_binary(const mci_ctx *ctx, const mcsg_mesh *mesh, mci_buf *out)
{
    static const char header[80] = "meshcsg binary STL";
    size_t rounded = count_rounded_coordinates(mesh);
    unsigned char *p;
    if (mesh->triangle_count > (SIZE_MAX - BINARY_HEADER_SIZE) / BINARY_RECORD_SIZE ||
        !mci_buf_reserve(ctx, out, BINARY_HEADER_SIZE +
                                       BINARY_RECORD_SIZE * mesh->triangle_count))
        return MCSG_ERR_NOMEM;
    p = out->data + out->len;
    memcpy(p, header, sizeof header);
    p += sizeof header;
    for (int k = 0; k < 4; k++)
        *p++ = (unsigned char)(mesh->triangle_count >> (8 * k));
    for (size_t i = 0; i < mesh->triangle_count; i++) {
        const uint32_t *t = mesh->triangles + 3 * i;
        double normal[3];
        triangle_normal(mesh, t, normal);
        for (int k = 0; k < 3; k++)
            p = put_f32_le(p, normal[k]);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++)
                p = put_f32_le(p, mesh->vertices[3 * (size_t)t[c] + (size_t)k]);
        *p++ = 0; /* attribute byte count */
        *p++ = 0;
    }
    out->len = (size_t)(p - out->data);
    if (rounded)
        mci_log(ctx, MCSG_LOG_WARNING, "%zu coordinates rounded to float32 for binary STL",
                rounded);
    return MCSG_OK;
}
