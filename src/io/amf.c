/*
 * AMF as OpenSCAD 2021.01 reads it (its src/import_amf.cc, read for the rules only):
 *  - it follows element paths, not the schema: /amf/object opens and closes an object;
 *    each /amf/object/mesh/vertices/vertex/coordinates adds a vertex when it closes, from
 *    the x, y, z read inside it; each /amf/object/mesh/volume/triangle adds a triangle when
 *    it closes, from v1, v2, v3, indexing the vertices of its object listed so far. Names
 *    are compared as written (no namespace processing), so a default xmlns changes nothing
 *    and a prefixed <a:amf> is not the root OpenSCAD looks for;
 *  - one object is one polygon set holding all its volumes' triangles; several objects are
 *    unioned (the caller does that: import() puts a leaf per object under a union);
 *  - a number is a text node parsed whole (boost::lexical_cast): "+1", "1.", "inf" and
 *    "nan" are numbers, " 1" and "1 " are not; an index is a decimal integer ("+0", "00");
 *    text split by a comment or a child element is several nodes, the last one counts;
 *    CDATA sections are not text nodes and are skipped;
 *  - units, constellations, materials, colours and metadata change nothing;
 *  - a zip archive (OpenSCAD built with libzip, as 2021.01's packages are) is read from
 *    its entry named like the file, else from its only entry.
 * Where OpenSCAD goes on with garbage this reader stops with an error: a value missing
 * from a vertex or triangle (OpenSCAD reuses the previous one), an index out of range (it
 * reads past its vector), malformed XML or a number that is none (it warns and keeps the
 * objects closed before, or none).
 */
#include "io/amf.h"

#include "base/numparse.h"

#include <expat.h>
#include <stdio.h>
#include <string.h>
#include <zip.h>

#define TEXT_MAX 1024 /* a value's text (names are cut there) */
#define PATH_DEPTH 7  /* amf object mesh vertices vertex coordinates x */
#define CHUNK 65536   /* bytes given to expat at a time */
/* Zipped XML is inflated as it is parsed; a few bytes of deflate can claim gigabytes. */
#define ZIP_XML_MAX ((uint64_t)1 << 30)

/* The elements on OpenSCAD's paths. */
enum kind {
    K_NONE,
    K_AMF,
    K_OBJECT,
    K_NAME, /* <metadata type="name"> of an object: its name in labels */
    K_MESH,
    K_VERTICES,
    K_VERTEX,
    K_COORDS,
    K_X,
    K_Y,
    K_Z,
    K_VOLUME,
    K_TRIANGLE,
    K_V1,
    K_V2,
    K_V3
};

static const struct {
    unsigned char parent, kind;
    const char *name;
} CHILDREN[] = {
    {K_NONE, K_AMF, "amf"},          {K_AMF, K_OBJECT, "object"},
    {K_OBJECT, K_NAME, "metadata"},  {K_OBJECT, K_MESH, "mesh"},
    {K_MESH, K_VERTICES, "vertices"}, {K_MESH, K_VOLUME, "volume"},
    {K_VERTICES, K_VERTEX, "vertex"}, {K_VERTEX, K_COORDS, "coordinates"},
    {K_COORDS, K_X, "x"},            {K_COORDS, K_Y, "y"},
    {K_COORDS, K_Z, "z"},            {K_VOLUME, K_TRIANGLE, "triangle"},
    {K_TRIANGLE, K_V1, "v1"},        {K_TRIANGLE, K_V2, "v2"},
    {K_TRIANGLE, K_V3, "v3"},
};

static const char *const VALUE_TAGS[] = {"x", "y", "z", "v1", "v2", "v3"};

typedef struct amf_state {
    const mci_io_source *src;
    char entry[128]; /* the zip entry being read ("" for plain XML): part of messages */
    XML_Parser parser;
    mcsg_status status;
    size_t depth;   /* elements open */
    size_t matched; /* how many of the open elements, from the root, are on a path */
    unsigned char kinds[PATH_DEPTH];
    bool in_cdata;
    char text[TEXT_MAX + 1]; /* the current text node of a value or name element */
    size_t text_len;
    double xyz[3];
    int64_t v[3];
    unsigned have; /* bits of the xyz or v values given in this vertex or triangle */
    mci_io_builder object;
    char name[TEXT_MAX + 1];
    mci_amf_objects *out;
    size_t mesh_cap, name_cap;
} amf_state;

static void stop(amf_state *s, mcsg_status status, const char *fmt, ...) MCI_PRINTF(3, 4);

/* The first failure is kept, with "NAME:LINE:" or "NAME: ENTRY:LINE:", and parsing stops. */
static void stop(amf_state *s, mcsg_status status, const char *fmt, ...)
{
    char message[256];
    unsigned long line = (unsigned long)XML_GetCurrentLineNumber(s->parser);
    va_list ap;
    if (s->status != MCSG_OK)
        return;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    if (s->entry[0])
        s->status = mci_fail(s->src->err, status, "%s: %s:%lu: %s", s->src->name, s->entry,
                             line, message);
    else
        s->status = mci_fail(s->src->err, status, "%s:%lu: %s", s->src->name, line, message);
    XML_StopParser(s->parser, XML_FALSE);
}

static void stop_build(amf_state *s, mcsg_status status, const char *what)
{
    if (status == MCSG_ERR_NOMEM)
        stop(s, status, "out of memory");
    else
        stop(s, status, "an object of more than 2^32-1 %s", what);
}

static bool is_text_kind(unsigned char k)
{
    return k == K_NAME || (k >= K_X && k <= K_Z) || (k >= K_V1 && k <= K_V3);
}

/* Whether the innermost open element is a value or name whose text is read. */
static bool in_text(const amf_state *s)
{
    return s->matched > 0 && s->matched == s->depth && is_text_kind(s->kinds[s->matched - 1]);
}

static bool is_name_metadata(const char **atts)
{
    for (int i = 0; atts[i]; i += 2)
        if (strcmp(atts[i], "type") == 0)
            return mci_io_token_is(atts[i + 1], atts[i + 1] + strlen(atts[i + 1]), "name");
    return false;
}

/* The kind of element `name` under an element of kind `parent`, K_NONE off the paths. */
static unsigned char child_kind(unsigned char parent, const char *name, const char **atts)
{
    for (size_t k = 0; k < sizeof CHILDREN / sizeof *CHILDREN; k++)
        if (CHILDREN[k].parent == parent && strcmp(CHILDREN[k].name, name) == 0)
            return CHILDREN[k].kind != K_NAME || is_name_metadata(atts) ? CHILDREN[k].kind
                                                                         : K_NONE;
    return K_NONE;
}

/* A text node ended (at the element's end, a child, a comment...): its value is read. */
static void take_text(amf_state *s)
{
    unsigned char k = s->kinds[s->matched - 1];
    const char *t = s->text, *end = s->text + s->text_len, *next = NULL;
    char shown[48];
    int64_t index;
    if (s->text_len == 0)
        return;
    s->text[s->text_len] = '\0';
    s->text_len = 0;
    if (k == K_NAME) {
        memcpy(s->name, s->text, (size_t)(end - t) + 1);
        return;
    }
    if (k <= K_Z ? mci_parse_double(t, end, &s->xyz[k - K_X], &next)
                 : mci_io_integer(t, end, &index, &next)) {
        if (next == end) {
            if (k >= K_V1)
                s->v[k - K_V1] = index;
            s->have |= 1u << (k <= K_Z ? k - K_X : k - K_V1);
            return;
        }
    }
    mci_io_excerpt_span(shown, t, end);
    stop(s, MCSG_ERR_PARSE, "<%s>%s</%s> is not %s", VALUE_TAGS[k <= K_Z ? k - K_X : k - K_V1 + 3],
         shown, VALUE_TAGS[k <= K_Z ? k - K_X : k - K_V1 + 3],
         k <= K_Z ? "a number" : "an integer");
}

static void open_element(amf_state *s, unsigned char kind)
{
    if (kind == K_OBJECT) {
        mci_io_builder_free(&s->object);
        s->name[0] = '\0';
    } else if (kind == K_COORDS || kind == K_TRIANGLE)
        s->have = 0;
}

static void close_vertex(amf_state *s)
{
    mcsg_status st;
    for (int k = 0; k < 3; k++)
        if (!(s->have & (1u << k))) {
            stop(s, MCSG_ERR_PARSE, "a vertex's <coordinates> without <%s>", VALUE_TAGS[k]);
            return;
        }
    st = mci_io_add_vertex(&s->object, s->xyz[0], s->xyz[1], s->xyz[2]);
    if (st != MCSG_OK)
        stop_build(s, st, "vertices");
}

static void close_triangle(amf_state *s)
{
    uint64_t n = s->object.vertex_count;
    mcsg_status st;
    for (int k = 0; k < 3; k++) {
        if (!(s->have & (1u << k))) {
            stop(s, MCSG_ERR_PARSE, "a <triangle> without <%s>", VALUE_TAGS[3 + k]);
            return;
        }
        if (s->v[k] < 0 || (uint64_t)s->v[k] >= n) {
            stop(s, MCSG_ERR_PARSE, "<%s>%lld</%s> is not the index of one of the %llu "
                 "vertices listed before it in its object", VALUE_TAGS[3 + k],
                 (long long)s->v[k], VALUE_TAGS[3 + k], (unsigned long long)n);
            return;
        }
    }
    st = mci_io_add_triangle(&s->object, (uint32_t)s->v[0], (uint32_t)s->v[1], (uint32_t)s->v[2]);
    if (st != MCSG_OK)
        stop_build(s, st, "triangles");
}

/* The object's mesh and name join the output. */
static void close_object(amf_state *s)
{
    const mci_ctx *ctx = s->src->ctx;
    mci_amf_objects *o = s->out;
    char *name;
    if (!mci_grow_array(ctx, (void **)&o->meshes, &s->mesh_cap, o->count + 1,
                        sizeof *o->meshes, 4) ||
        !mci_grow_array(ctx, (void **)&o->names, &s->name_cap, o->count + 1, sizeof *o->names,
                        4) ||
        !(name = mci_strdup(ctx, s->name))) {
        stop(s, MCSG_ERR_NOMEM, "out of memory");
        return;
    }
    o->names[o->count] = name;
    mci_io_builder_finish(&s->object, &o->meshes[o->count++]);
}

static void close_element(amf_state *s, unsigned char kind)
{
    if (kind == K_COORDS)
        close_vertex(s);
    else if (kind == K_TRIANGLE)
        close_triangle(s);
    else if (kind == K_OBJECT)
        close_object(s);
}

static void on_start(void *user, const char *name, const char **atts)
{
    amf_state *s = user;
    unsigned char kind = K_NONE;
    if (s->status != MCSG_OK)
        return;
    if (in_text(s))
        take_text(s);
    if (s->matched == s->depth && s->matched < PATH_DEPTH)
        kind = child_kind(s->matched ? s->kinds[s->matched - 1] : K_NONE, name, atts);
    s->depth++;
    if (s->depth == 1 && kind != K_AMF) {
        char shown[48];
        mci_io_excerpt_span(shown, name, name + strlen(name));
        stop(s, MCSG_ERR_PARSE, "the root element is <%s>, not <amf>", shown);
    } else if (kind != K_NONE) {
        s->kinds[s->matched++] = kind;
        open_element(s, kind);
    }
}

static void on_end(void *user, const char *name)
{
    amf_state *s = user;
    (void)name;
    if (s->status != MCSG_OK)
        return;
    if (s->matched == s->depth && s->matched > 0) {
        if (in_text(s))
            take_text(s);
        close_element(s, s->kinds[--s->matched]);
    }
    s->depth--;
}

static void on_text(void *user, const char *data, int len)
{
    amf_state *s = user;
    size_t n = (size_t)len;
    if (s->status != MCSG_OK || s->in_cdata || !in_text(s))
        return;
    if (n > TEXT_MAX - s->text_len) {
        if (s->kinds[s->matched - 1] != K_NAME) {
            stop(s, MCSG_ERR_PARSE, "a value of more than %d characters", TEXT_MAX);
            return;
        }
        n = TEXT_MAX - s->text_len;
    }
    memcpy(s->text + s->text_len, data, n);
    s->text_len += n;
}

/* Comments and processing instructions end a text node. */
static void on_comment(void *user, const char *data)
{
    amf_state *s = user;
    (void)data;
    if (s->status == MCSG_OK && in_text(s))
        take_text(s);
}

static void on_instruction(void *user, const char *target, const char *data)
{
    (void)target;
    on_comment(user, data);
}

static void on_cdata_start(void *user)
{
    amf_state *s = user;
    on_comment(user, NULL);
    s->in_cdata = true;
}

static void on_cdata_end(void *user)
{
    ((amf_state *)user)->in_cdata = false;
}

/* ---- feeding expat ------------------------------------------------------------------ */

static void xml_error(amf_state *s)
{
    enum XML_Error code = XML_GetErrorCode(s->parser);
    if (code == XML_ERROR_NO_MEMORY)
        stop(s, MCSG_ERR_NOMEM, "out of memory");
#if XML_MAJOR_VERSION > 2 || (XML_MAJOR_VERSION == 2 && XML_MINOR_VERSION >= 4)
    else if (code == XML_ERROR_AMPLIFICATION_LIMIT_BREACH)
        stop(s, MCSG_ERR_LIMIT, "entities expand beyond expat's amplification limit");
#endif
    else
        stop(s, MCSG_ERR_PARSE, "malformed XML: %s", XML_ErrorString(code));
}

/* Part of the document (`last`: its end). False once reading stopped. */
static bool feed(amf_state *s, const char *data, size_t size, bool last)
{
    do {
        int n = size > CHUNK ? CHUNK : (int)size;
        if (XML_Parse(s->parser, data, n, last && (size_t)n == size) != XML_STATUS_OK) {
            xml_error(s); /* does nothing when a handler stopped with its own message */
            return false;
        }
        data += n;
        size -= (size_t)n;
    } while (size > 0 && s->status == MCSG_OK);
    return s->status == MCSG_OK;
}

static XML_Parser new_parser(amf_state *s)
{
    XML_Parser p = XML_ParserCreate(NULL);
    if (!p)
        return NULL;
    XML_SetUserData(p, s);
    XML_SetElementHandler(p, on_start, on_end);
    XML_SetCharacterDataHandler(p, on_text);
    XML_SetCommentHandler(p, on_comment);
    XML_SetProcessingInstructionHandler(p, on_instruction);
    XML_SetCdataSectionHandler(p, on_cdata_start, on_cdata_end);
    return p;
}

/* ---- zip archives --------------------------------------------------------------------- */

static const char *last_component(const char *path)
{
    const char *slash = strrchr(path, '/'), *backslash = strrchr(path, '\\');
    if (backslash > slash)
        slash = backslash;
    return slash ? slash + 1 : path;
}

/* The entry OpenSCAD reads: named like the file (in any folder), else the only one. */
static zip_int64_t pick_entry(amf_state *s, zip_t *zip)
{
    const char *file = last_component(s->src->name);
    zip_int64_t index = zip_name_locate(zip, file, ZIP_FL_NODIR);
    zip_int64_t count = zip_get_num_entries(zip, 0);
    if (index < 0 && count == 1) {
        index = 0;
        mci_log(s->src->ctx, MCSG_LOG_WARNING, "%s: the zip archive has no entry %s; reading "
                "its only entry, %s", s->src->name, file, zip_get_name(zip, 0, 0));
    }
    if (index < 0)
        s->status = mci_fail(s->src->err, MCSG_ERR_PARSE, "%s: the zipped AMF has no entry "
                             "%s and %lld entries, not one", s->src->name, file,
                             (long long)count);
    else
        snprintf(s->entry, sizeof s->entry, "%s", zip_get_name(zip, (zip_uint64_t)index, 0));
    return index;
}

/* The entry inflated a chunk at a time into expat. */
static void parse_entry(amf_state *s, zip_t *zip, zip_int64_t index)
{
    zip_file_t *f = zip_fopen_index(zip, (zip_uint64_t)index, 0);
    char *chunk = f ? mci_malloc(s->src->ctx, CHUNK) : NULL;
    uint64_t total = 0;
    zip_int64_t got = 1;
    if (!f)
        s->status = mci_fail(s->src->err, MCSG_ERR_PARSE, "%s: %s: cannot be read (%s)",
                             s->src->name, s->entry, zip_strerror(zip));
    else if (!chunk)
        s->status = mci_fail(s->src->err, MCSG_ERR_NOMEM, "%s: out of memory", s->src->name);
    while (s->status == MCSG_OK && got > 0) {
        got = zip_fread(f, chunk, CHUNK);
        total += got > 0 ? (uint64_t)got : 0;
        if (got < 0)
            s->status = mci_fail(s->src->err, MCSG_ERR_PARSE, "%s: %s: a broken zip entry (%s)",
                                 s->src->name, s->entry, zip_file_strerror(f));
        else if (total > ZIP_XML_MAX)
            stop(s, MCSG_ERR_LIMIT, "the zipped XML inflates to more than 1 GiB");
        else
            feed(s, chunk, (size_t)got, got == 0);
    }
    mci_free(s->src->ctx, chunk);
    if (f)
        zip_fclose(f);
}

static void read_zip(amf_state *s)
{
    const mci_io_source *src = s->src;
    zip_error_t ze;
    zip_source_t *zs;
    zip_t *zip = NULL;
    zip_int64_t index;
    zip_error_init(&ze);
    zs = zip_source_buffer_create(src->bytes, src->size, 0, &ze);
    if (zs && !(zip = zip_open_from_source(zs, ZIP_RDONLY, &ze)))
        zip_source_free(zs);
    if (!zip)
        s->status = mci_fail(src->err, zip_error_code_zip(&ze) == ZIP_ER_MEMORY
                                           ? MCSG_ERR_NOMEM : MCSG_ERR_PARSE,
                             "%s: not a readable zip archive (%s)", src->name,
                             zip_error_strerror(&ze));
    zip_error_fini(&ze);
    if (!zip)
        return;
    index = pick_entry(s, zip);
    if (index >= 0)
        parse_entry(s, zip, index);
    zip_discard(zip);
}

/* ---- entry points ----------------------------------------------------------------------- */

mcsg_status mci_amf_read(const mci_io_source *src, mci_amf_objects *out)
{
    amf_state *s = mci_malloc(src->ctx, sizeof *s); /* 2 KB of text buffers */
    mcsg_status st;
    memset(out, 0, sizeof *out);
    if (!s)
        return mci_fail(src->err, MCSG_ERR_NOMEM, "%s: out of memory", src->name);
    memset(s, 0, sizeof *s);
    s->src = src, s->out = out;
    mci_io_builder_init(&s->object, src->ctx);
    if (!(s->parser = new_parser(s)))
        s->status = mci_fail(src->err, MCSG_ERR_NOMEM, "%s: out of memory", src->name);
    else if (src->size >= 2 && src->bytes[0] == 'P' && src->bytes[1] == 'K')
        read_zip(s);
    else
        feed(s, src->text, src->size, true);
    if (s->parser)
        XML_ParserFree(s->parser);
    mci_io_builder_free(&s->object);
    st = s->status;
    mci_free(src->ctx, s);
    if (st != MCSG_OK)
        mci_amf_objects_free(src->ctx, out);
    return st;
}

mcsg_status mci_amf_read_file(const mci_ctx *ctx, const char *path, mci_amf_objects *out,
                              mcsg_error *err)
{
    unsigned char *data = NULL;
    size_t size = 0;
    mci_io_source src;
    mcsg_status st;
    memset(out, 0, sizeof *out);
    st = mci_read_file(ctx, path, &data, &size, err);
    if (st != MCSG_OK)
        return st;
    src.ctx = ctx, src.name = path, src.err = err, src.size = size;
    src.text = size ? (const char *)data : "";
    src.bytes = (const unsigned char *)src.text;
    st = mci_amf_read(&src, out);
    mci_free(ctx, data);
    return st;
}

void mci_amf_objects_free(const mci_ctx *ctx, mci_amf_objects *objects)
{
    for (size_t k = 0; k < objects->count; k++) {
        mci_free(ctx, objects->meshes[k].vertices);
        mci_free(ctx, objects->meshes[k].triangles);
        mci_free(ctx, objects->names[k]);
    }
    mci_free(ctx, objects->meshes);
    mci_free(ctx, objects->names);
    memset(objects, 0, sizeof *objects);
}

/* Appends mesh m to b, its indices moved past b's vertices. */
static mcsg_status append(mci_io_builder *b, const mcsg_mesh *m)
{
    uint32_t base = (uint32_t)b->vertex_count;
    mcsg_status st = MCSG_OK;
    for (size_t v = 0; st == MCSG_OK && v < m->vertex_count; v++)
        st = mci_io_add_vertex(b, m->vertices[3 * v], m->vertices[3 * v + 1],
                               m->vertices[3 * v + 2]);
    for (size_t t = 0; st == MCSG_OK && t < m->triangle_count; t++)
        st = mci_io_add_triangle(b, base + m->triangles[3 * t], base + m->triangles[3 * t + 1],
                                 base + m->triangles[3 * t + 2]);
    return st;
}

mcsg_status mci_amf_read_merged(const mci_io_source *src, mcsg_mesh *out)
{
    mci_amf_objects objects;
    mci_io_builder b;
    mcsg_status st = mci_amf_read(src, &objects);
    memset(out, 0, sizeof *out);
    if (st != MCSG_OK)
        return st;
    mci_io_builder_init(&b, src->ctx);
    for (size_t k = 0; st == MCSG_OK && k < objects.count; k++)
        st = append(&b, &objects.meshes[k]);
    mci_amf_objects_free(src->ctx, &objects);
    if (st != MCSG_OK) {
        mci_io_builder_free(&b);
        return mci_io_fail_build(src, st, true, 0);
    }
    mci_io_builder_finish(&b, out);
    return MCSG_OK;
}

bool mci_amf_is_name(const char *name)
{
    size_t n = name ? strlen(name) : 0;
    return n >= 4 && mci_io_token_is(name + n - 4, name + n, ".amf");
}

static bool xml_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

/* The first occurrence of `word` in [p, end), or NULL. */
static const char *find(const char *p, const char *end, const char *word)
{
    size_t n = strlen(word);
    for (; (size_t)(end - p) >= n; p++)
        if (memcmp(p, word, n) == 0)
            return p;
    return NULL;
}

bool mci_amf_looks_like(const char *text, size_t size)
{
    const char *p = text, *end = text + size;
    if (size >= 3 && memcmp(p, "\xEF\xBB\xBF", 3) == 0)
        p += 3;
    for (;;) { /* the prolog: declaration, comments, instructions, document type */
        const char *close;
        while (p < end && xml_space(*p))
            p++;
        if (end - p < 5 || p[0] != '<')
            return false;
        close = p[1] == '?' ? "?>" : memcmp(p, "<!--", 4) == 0 ? "-->" : p[1] == '!' ? ">" : NULL;
        if (!close)
            break;
        if (!(p = find(p + 2, end, close)))
            return false;
        p += strlen(close);
    }
    return memcmp(p, "<amf", 4) == 0 && (xml_space(p[4]) || p[4] == '>' || p[4] == '/');
}
