/*
 * 3MF (3D Manufacturing Format, core specification 1.x): a zip container (libzip) whose
 * root relationship names the model part, XML (expat) with objects made of a mesh or of
 * components, and build items placing objects. Each build item is one mesh here, with
 * its components' and its own transforms applied (rounded once per transform, as
 * mcsg_mesh_transform does) and coordinates converted to millimetres. Materials,
 * colours and the extensions' elements are skipped: they do not change the geometry.
 * Writing makes one object and one build item per mesh.
 */
#include "io/threemf.h"

#include "base/numparse.h"

#include <expat.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zip.h>

#define MODEL_TYPE "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"
#define MAX_NESTING 32 /* components within components */

/* ---- reading the container ------------------------------------------------------ */

/* The bytes of entry `name` (a NUL is appended); NULL when there is none or it cannot
 * be read. The buffer grows with what actually comes out: the size an entry's header
 * claims is not trusted with an allocation. */
static char *read_entry(const mci_ctx *ctx, zip_t *zip, const char *name, size_t *size)
{
    zip_file_t *f = zip_fopen(zip, name, 0);
    char *data = NULL;
    size_t len = 0, cap = 0;
    zip_int64_t got = 1;
    while (f && got > 0) {
        if (cap - len < 4096) {
            size_t grown = cap ? 2 * cap : 65536;
            char *bigger = grown > cap && grown < SIZE_MAX / 2 ? mci_realloc(ctx, data, grown)
                                                               : NULL;
            if (!bigger)
                break;
            data = bigger, cap = grown;
        }
        got = zip_fread(f, data + len, cap - len - 1);
        len += got > 0 ? (size_t)got : 0;
    }
    if (f)
        zip_fclose(f);
    if (got != 0) { /* a read error (a checksum, a broken stream) or out of memory */
        mci_free(ctx, data);
        return NULL;
    }
    data[len] = '\0';
    *size = len;
    return data;
}

/* Element names come as "namespace local" (XML_ParserCreateNS with ' '). */
static const char *local_name(const char *name)
{
    const char *space = strrchr(name, ' ');
    return space ? space + 1 : name;
}

static const char *attribute(const char **atts, const char *name)
{
    for (int i = 0; atts[i]; i += 2)
        if (strcmp(local_name(atts[i]), name) == 0)
            return atts[i + 1];
    return NULL;
}

/* The model part: the root relationship of the 3D model type (default /3D/3dmodel.model). */
typedef struct rels_state {
    char target[512];
} rels_state;

static void rels_start(void *user, const char *name, const char **atts)
{
    rels_state *r = user;
    const char *type = attribute(atts, "Type"), *target = attribute(atts, "Target");
    if (strcmp(local_name(name), "Relationship") == 0 && type && target &&
        strcmp(type, MODEL_TYPE) == 0 && !r->target[0])
        snprintf(r->target, sizeof r->target, "%s", target[0] == '/' ? target + 1 : target);
}

static void model_part(const mci_ctx *ctx, zip_t *zip, char *part, size_t size)
{
    size_t n;
    char *rels = read_entry(ctx, zip, "_rels/.rels", &n);
    rels_state r = {{0}};
    snprintf(part, size, "3D/3dmodel.model");
    if (!rels)
        return;
    XML_Parser p = XML_ParserCreateNS(NULL, ' ');
    if (p) {
        XML_SetUserData(p, &r);
        XML_SetStartElementHandler(p, rels_start);
        if (XML_Parse(p, rels, (int)n, 1) == XML_STATUS_OK && r.target[0])
            snprintf(part, size, "%s", r.target);
        XML_ParserFree(p);
    }
    mci_free(ctx, rels);
}

/* ---- the model -------------------------------------------------------------------- */

/* An object placed by a transform: a component of another object, or a build item. */
typedef struct placement {
    uint32_t object; /* index in objects */
    double m[12];
} placement;

typedef struct object {
    uint32_t id;
    char *name;
    size_t first_vertex, vertex_count, first_triangle, triangle_count; /* in the pools */
    placement *parts;
    size_t part_count, part_cap;
} object;

typedef struct model_state {
    const mci_io_source *src;
    const char *part;
    XML_Parser parser;
    mcsg_status status;
    double unit;
    object *objects;
    size_t object_count, object_cap;
    placement *items;
    size_t item_count, item_cap;
    mci_io_builder pool; /* every object's vertices and triangles, one after another */
    object *current;
    int in_build, in_mesh;
} model_state;

static void stop(model_state *s, mcsg_status status, const char *fmt, ...) MCI_PRINTF(3, 4);

static void stop(model_state *s, mcsg_status status, const char *fmt, ...)
{
    char message[256];
    va_list ap;
    if (s->status != MCSG_OK)
        return;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    s->status = mci_fail(s->src->err, status, "%s: %s:%lu: %s", s->src->name, s->part,
                         (unsigned long)XML_GetCurrentLineNumber(s->parser), message);
    XML_StopParser(s->parser, XML_FALSE);
}

static bool number(model_state *s, const char **atts, const char *name, double *out)
{
    const char *text = attribute(atts, name), *next;
    if (!text || !mci_io_number(text, text + strlen(text), out, &next) || *next) {
        stop(s, MCSG_ERR_PARSE, "%s=\"%s\" is not a number", name, text ? text : "");
        return false;
    }
    return true;
}

static bool index_of(model_state *s, const char **atts, const char *name, uint64_t limit,
                     uint32_t *out)
{
    const char *text = attribute(atts, name), *next;
    int64_t v;
    if (!text || !mci_io_integer(text, text + strlen(text), &v, &next) || *next || v < 0 ||
        (uint64_t)v >= limit) {
        stop(s, MCSG_ERR_PARSE, "%s=\"%s\" is not an index below %llu", name,
             text ? text : "", (unsigned long long)limit);
        return false;
    }
    *out = (uint32_t)v;
    return true;
}

/* A 3MF transform "m00 m01 m02 m10 ... m32" (points are rows: p' = p M) as meshcsg's
 * row-major 3x4 matrix; identity when absent. */
static bool transform(model_state *s, const char **atts, double m[12])
{
    static const double identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    const char *text = attribute(atts, "transform"), *p, *end;
    double v[12];
    memcpy(m, identity, sizeof identity);
    if (!text)
        return true;
    p = text, end = text + strlen(text);
    for (int k = 0; k < 12; k++) {
        p = mci_io_skip_blanks(p, end);
        if (!mci_io_number(p, end, &v[k], &p)) {
            stop(s, MCSG_ERR_PARSE, "transform=\"%.40s\" is not 12 numbers", text);
            return false;
        }
    }
    if (*mci_io_skip_blanks(p, end)) {
        stop(s, MCSG_ERR_PARSE, "transform=\"%.40s\" is not 12 numbers", text);
        return false;
    }
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++)
            m[4 * r + c] = v[3 * c + r];
        m[4 * r + 3] = v[9 + r];
    }
    return true;
}

static object *find_object(model_state *s, const char **atts)
{
    uint32_t id;
    if (!index_of(s, atts, "objectid", UINT32_MAX, &id))
        return NULL;
    for (size_t k = 0; k < s->object_count; k++)
        if (s->objects[k].id == id)
            return &s->objects[k];
    stop(s, MCSG_ERR_PARSE, "objectid %u names no object defined before", (unsigned)id);
    return NULL;
}

static void start_object(model_state *s, const char **atts)
{
    uint32_t id;
    const char *name = attribute(atts, "name");
    if (!index_of(s, atts, "id", UINT32_MAX, &id))
        return;
    if (!mci_grow_array(s->src->ctx, (void **)&s->objects, &s->object_cap, s->object_count + 1,
                        sizeof *s->objects, 8)) {
        stop(s, MCSG_ERR_NOMEM, "out of memory");
        return;
    }
    s->current = &s->objects[s->object_count++];
    memset(s->current, 0, sizeof *s->current);
    s->current->id = id;
    s->current->name = mci_strdup(s->src->ctx, name ? name : "");
    s->current->first_vertex = s->pool.vertex_count;
    s->current->first_triangle = s->pool.triangle_count;
    if (!s->current->name)
        stop(s, MCSG_ERR_NOMEM, "out of memory");
}

static void add_vertex(model_state *s, const char **atts)
{
    double x, y, z;
    mcsg_status st;
    if (!number(s, atts, "x", &x) || !number(s, atts, "y", &y) || !number(s, atts, "z", &z))
        return;
    st = mci_io_add_vertex(&s->pool, x, y, z);
    if (st != MCSG_OK)
        stop(s, st, st == MCSG_ERR_NOMEM ? "out of memory" : "more than 2^32-1 vertices");
    else
        s->current->vertex_count++;
}

static void add_triangle(model_state *s, const char **atts)
{
    uint32_t v[3];
    uint64_t n = s->current->vertex_count; /* indices are the object's own */
    if (!index_of(s, atts, "v1", n, &v[0]) || !index_of(s, atts, "v2", n, &v[1]) ||
        !index_of(s, atts, "v3", n, &v[2]))
        return;
    mcsg_status st = mci_io_add_triangle(&s->pool, v[0], v[1], v[2]);
    if (st != MCSG_OK)
        stop(s, st, st == MCSG_ERR_NOMEM ? "out of memory" : "more than 2^32-1 triangles");
    else
        s->current->triangle_count++;
}

/* A placement (objectid, transform) appended to *list. */
static void add_placement(model_state *s, const char **atts, placement **list, size_t *count,
                          size_t *cap)
{
    object *o = find_object(s, atts);
    placement p;
    if (!o || !transform(s, atts, p.m))
        return;
    p.object = (uint32_t)(o - s->objects);
    if (!mci_grow_array(s->src->ctx, (void **)list, cap, *count + 1, sizeof **list, 8)) {
        stop(s, MCSG_ERR_NOMEM, "out of memory");
        return;
    }
    (*list)[(*count)++] = p;
}

static double unit_millimetres(const char *unit)
{
    static const struct { const char *name; double mm; } units[] = {
        {"micron", 0.001}, {"millimeter", 1}, {"centimeter", 10}, {"inch", 25.4},
        {"foot", 304.8},   {"meter", 1000}};
    for (size_t k = 0; k < sizeof units / sizeof *units; k++)
        if (strcmp(unit, units[k].name) == 0)
            return units[k].mm;
    return 0;
}

static void model_start(void *user, const char *full, const char **atts)
{
    model_state *s = user;
    const char *name = local_name(full);
    if (s->status != MCSG_OK)
        return;
    if (strcmp(name, "model") == 0) {
        const char *unit = attribute(atts, "unit");
        s->unit = unit ? unit_millimetres(unit) : 1;
        if (s->unit == 0)
            stop(s, MCSG_ERR_UNSUPPORTED, "unit \"%s\" is not one of 3MF's", unit);
    } else if (strcmp(name, "object") == 0)
        start_object(s, atts);
    else if (strcmp(name, "mesh") == 0)
        s->in_mesh = s->current != NULL;
    else if (strcmp(name, "vertex") == 0 && s->in_mesh)
        add_vertex(s, atts);
    else if (strcmp(name, "triangle") == 0 && s->in_mesh)
        add_triangle(s, atts);
    else if (strcmp(name, "component") == 0 && s->current)
        add_placement(s, atts, &s->current->parts, &s->current->part_count,
                      &s->current->part_cap);
    else if (strcmp(name, "build") == 0)
        s->in_build = 1;
    else if (strcmp(name, "item") == 0 && s->in_build)
        add_placement(s, atts, &s->items, &s->item_count, &s->item_cap);
}

static void model_end(void *user, const char *full)
{
    model_state *s = user;
    const char *name = local_name(full);
    if (strcmp(name, "object") == 0)
        s->current = NULL;
    else if (strcmp(name, "mesh") == 0)
        s->in_mesh = 0;
    else if (strcmp(name, "build") == 0)
        s->in_build = 0;
}

/* ---- build items as meshes ------------------------------------------------------- */

/* Appends vertices and triangles (indices into those vertices) to b. */
static mcsg_status append(mci_io_builder *b, const double *vertices, size_t vertex_count,
                          const uint32_t *triangles, size_t triangle_count)
{
    uint32_t base = (uint32_t)b->vertex_count;
    mcsg_status st = MCSG_OK;
    for (size_t v = 0; st == MCSG_OK && v < vertex_count; v++)
        st = mci_io_add_vertex(b, vertices[3 * v], vertices[3 * v + 1], vertices[3 * v + 2]);
    for (size_t t = 0; st == MCSG_OK && t < triangle_count; t++)
        st = mci_io_add_triangle(b, base + triangles[3 * t], base + triangles[3 * t + 1],
                                 base + triangles[3 * t + 2]);
    return st;
}

/* Object o with its components, each mapped by its transform, into *out. */
static mcsg_status flatten(model_state *s, uint32_t o, int depth, mcsg_mesh *out)
{
    const object *ob = &s->objects[o];
    mci_io_builder b;
    mcsg_status st = MCSG_OK;
    if (depth > MAX_NESTING)
        return mci_fail(s->src->err, MCSG_ERR_LIMIT, "%s: %s: components nested deeper than "
                        "%d (or an object made of itself)", s->src->name, s->part, MAX_NESTING);
    mci_io_builder_init(&b, s->src->ctx);
    st = mci_io_reserve(&b, ob->vertex_count, ob->triangle_count);
    if (st == MCSG_OK)
        st = append(&b, s->pool.vertices + 3 * ob->first_vertex, ob->vertex_count,
                    s->pool.triangles + 3 * ob->first_triangle, ob->triangle_count);
    for (size_t k = 0; st == MCSG_OK && k < ob->part_count; k++) {
        mcsg_mesh part;
        st = flatten(s, ob->parts[k].object, depth + 1, &part);
        if (st != MCSG_OK) { /* reported there */
            mci_io_builder_free(&b);
            return st;
        }
        mcsg_mesh_transform(&part, ob->parts[k].m);
        st = append(&b, part.vertices, part.vertex_count, part.triangles, part.triangle_count);
        mci_free(s->src->ctx, part.vertices);
        mci_free(s->src->ctx, part.triangles);
    }
    if (st != MCSG_OK) { /* the builder's: out of memory or too large */
        mci_io_builder_free(&b);
        return mci_fail(s->src->err, st, "%s: %s: %s", s->src->name, s->part,
                        st == MCSG_ERR_NOMEM ? "out of memory"
                                             : "more than 2^32-1 vertices or triangles");
    }
    mci_io_builder_finish(&b, out);
    return MCSG_OK;
}

#define EXPANSION_CAP ((uint64_t)1 << 40)
#define VISITING UINT64_MAX
/* Each placement of a component counts as this many elements: empty objects placed
 * billions of times would cost the time without the memory. */
#define INSTANCE_WEIGHT 256

/* The vertices and triangles object o expands to with its components (and placements),
 * saturating at EXPANSION_CAP, each object counted once (memo: 0 unknown, else the count
 * + 1); an object within its own components, or nesting deeper than MAX_NESTING, gives
 * the cap. */
static uint64_t expanded_size(const model_state *s, uint32_t o, int depth, uint64_t *memo)
{
    const object *ob = &s->objects[o];
    uint64_t n = ob->vertex_count + ob->triangle_count;
    if (memo[o] == VISITING || depth > MAX_NESTING)
        return EXPANSION_CAP;
    if (memo[o])
        return memo[o] - 1;
    memo[o] = VISITING;
    for (size_t k = 0; k < ob->part_count && n < EXPANSION_CAP; k++) /* a placement */
        n += INSTANCE_WEIGHT + expanded_size(s, ob->parts[k].object, depth + 1, memo);
    n = n < EXPANSION_CAP ? n : EXPANSION_CAP;
    memo[o] = n + 1;
    return n;
}

/* A few bytes of components can place a part a billion times: what all the items
 * expand to is counted before anything is built. */
static mcsg_status check_expansion(model_state *s)
{
    uint64_t *memo = mci_calloc_array(s->src->ctx, s->object_count + 1, sizeof *memo);
    uint64_t total = 0;
    if (!memo)
        return mci_fail(s->src->err, MCSG_ERR_NOMEM, "%s: out of memory", s->src->name);
    for (size_t k = 0; k < s->item_count && total <= UINT32_MAX; k++)
        total += INSTANCE_WEIGHT + expanded_size(s, s->items[k].object, 0, memo);
    mci_free(s->src->ctx, memo);
    if (total > UINT32_MAX)
        return mci_fail(s->src->err, MCSG_ERR_LIMIT, "%s: %s: the build items expand to more "
                        "than 2^32-1 vertices and triangles, or components are nested deeper "
                        "than %d or within themselves", s->src->name, s->part, MAX_NESTING);
    return MCSG_OK;
}

static mcsg_status item_mesh(model_state *s, const placement *it, mcsg_mesh *out)
{
    mcsg_status st = flatten(s, it->object, 0, out);
    if (st != MCSG_OK)
        return st;
    mcsg_mesh_transform(out, it->m);
    if (s->unit != 1) {
        const double scale[12] = {s->unit, 0, 0, 0, 0, s->unit, 0, 0, 0, 0, s->unit, 0};
        mcsg_mesh_transform(out, scale);
    }
    return MCSG_OK;
}

static void free_model(model_state *s)
{
    for (size_t k = 0; k < s->object_count; k++) {
        mci_free(s->src->ctx, s->objects[k].name);
        mci_free(s->src->ctx, s->objects[k].parts);
    }
    mci_free(s->src->ctx, s->objects);
    mci_free(s->src->ctx, s->items);
    mci_io_builder_free(&s->pool);
}

static mcsg_status parse_model(model_state *s, const char *xml, size_t size)
{
    s->parser = XML_ParserCreateNS(NULL, ' ');
    if (!s->parser)
        return mci_fail(s->src->err, MCSG_ERR_NOMEM, "%s: out of memory", s->src->name);
    XML_SetUserData(s->parser, s);
    XML_SetElementHandler(s->parser, model_start, model_end);
    if (size > INT32_MAX)
        stop(s, MCSG_ERR_LIMIT, "model part over 2 GiB");
    else if (XML_Parse(s->parser, xml, (int)size, 1) != XML_STATUS_OK && s->status == MCSG_OK)
        stop(s, MCSG_ERR_PARSE, "malformed XML: %s",
             XML_ErrorString(XML_GetErrorCode(s->parser)));
    XML_ParserFree(s->parser);
    return s->status;
}

mcsg_status mci_3mf_read(const mci_io_source *src, mci_3mf_items *out)
{
    zip_error_t ze;
    zip_source_t *zs;
    zip_t *zip = NULL;
    model_state s;
    char part[512];
    char *xml = NULL;
    size_t size = 0;
    memset(out, 0, sizeof *out);
    memset(&s, 0, sizeof s);
    s.src = src, s.part = part, s.unit = 1;
    mci_io_builder_init(&s.pool, src->ctx);
    zip_error_init(&ze);
    zs = zip_source_buffer_create(src->size ? src->bytes : (const void *)"", src->size, 0, &ze);
    if (zs && !(zip = zip_open_from_source(zs, ZIP_RDONLY, &ze)))
        zip_source_free(zs);
    if (!zip) {
        mcsg_status st = mci_fail(src->err, MCSG_ERR_PARSE, "%s: not a 3MF file (its zip "
                                  "container: %s)", src->name, zip_error_strerror(&ze));
        zip_error_fini(&ze);
        return st;
    }
    zip_error_fini(&ze);
    model_part(src->ctx, zip, part, sizeof part);
    xml = read_entry(src->ctx, zip, part, &size);
    zip_discard(zip);
    if (!xml)
        return mci_fail(src->err, MCSG_ERR_PARSE, "%s: not a 3MF file (no model part %s)",
                        src->name, part);
    s.status = parse_model(&s, xml, size);
    mci_free(src->ctx, xml);
    if (s.status == MCSG_OK && s.item_count == 0)
        s.status = mci_fail(src->err, MCSG_ERR_PARSE, "%s: %s: no build item", src->name, part);
    if (s.status == MCSG_OK)
        s.status = check_expansion(&s);
    if (s.status == MCSG_OK && (!(out->meshes = mci_calloc_array(src->ctx, s.item_count,
                                                                  sizeof *out->meshes)) ||
                                !(out->names = mci_calloc_array(src->ctx, s.item_count,
                                                                 sizeof *out->names))))
        s.status = mci_fail(src->err, MCSG_ERR_NOMEM, "%s: out of memory", src->name);
    for (size_t k = 0; s.status == MCSG_OK && k < s.item_count; k++) {
        s.status = item_mesh(&s, &s.items[k], &out->meshes[k]);
        out->count = k + (s.status == MCSG_OK);
        if (s.status == MCSG_OK &&
            !(out->names[k] = mci_strdup(src->ctx, s.objects[s.items[k].object].name)))
            s.status = mci_fail(src->err, MCSG_ERR_NOMEM, "%s: out of memory", src->name);
    }
    free_model(&s);
    if (s.status != MCSG_OK)
        mci_3mf_items_free(src->ctx, out);
    return s.status;
}

void mci_3mf_items_free(const mci_ctx *ctx, mci_3mf_items *items)
{
    for (size_t k = 0; k < items->count; k++) {
        mci_free(ctx, items->meshes[k].vertices);
        mci_free(ctx, items->meshes[k].triangles);
        if (items->names)
            mci_free(ctx, items->names[k]);
    }
    mci_free(ctx, items->meshes);
    mci_free(ctx, items->names);
    memset(items, 0, sizeof *items);
}

mcsg_status mci_3mf_read_merged(const mci_io_source *src, mcsg_mesh *out)
{
    mci_3mf_items items;
    mci_io_builder b;
    mcsg_status st = mci_3mf_read(src, &items);
    if (st != MCSG_OK)
        return st;
    mci_io_builder_init(&b, src->ctx);
    for (size_t k = 0; st == MCSG_OK && k < items.count; k++) {
        const mcsg_mesh *m = &items.meshes[k];
        st = append(&b, m->vertices, m->vertex_count, m->triangles, m->triangle_count);
    }
    mci_3mf_items_free(src->ctx, &items);
    if (st != MCSG_OK) {
        mci_io_builder_free(&b);
        return mci_io_fail_build(src, st, true, 0);
    }
    mci_io_builder_finish(&b, out);
    return MCSG_OK;
}

/* ---- writing ------------------------------------------------------------------------ */

static const char CONTENT_TYPES[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">"
    "<Default Extension=\"rels\" "
    "ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>"
    "<Default Extension=\"model\" "
    "ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/></Types>\n";
static const char RELS[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">"
    "<Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" Type=\"" MODEL_TYPE "\"/>"
    "</Relationships>\n";

static bool write_object(const mci_ctx *ctx, const mcsg_mesh *m, size_t id, mci_buf *x)
{
    if (!mci_buf_printf(ctx, x, "  <object id=\"%zu\" name=\"object %zu\" type=\"model\">\n"
                        "   <mesh>\n    <vertices>\n", id, id))
        return false;
    for (size_t v = 0; v < m->vertex_count; v++) {
        char *p = mci_io_reserve_text(ctx, x, 3 * MCI_DOUBLE_TEXT_MAX + 64);
        if (!p)
            return false;
        p = mci_io_put_text(p, "     <vertex x=\"");
        p = mci_io_put_double(mci_io_put_text(mci_io_put_double(p, m->vertices[3 * v]),
                                              "\" y=\""), m->vertices[3 * v + 1]);
        p = mci_io_put_double(mci_io_put_text(p, "\" z=\""), m->vertices[3 * v + 2]);
        mci_io_commit_text(x, mci_io_put_text(p, "\"/>\n"));
    }
    if (!mci_buf_printf(ctx, x, "    </vertices>\n    <triangles>\n"))
        return false;
    for (size_t t = 0; t < m->triangle_count; t++)
        if (!mci_buf_printf(ctx, x, "     <triangle v1=\"%u\" v2=\"%u\" v3=\"%u\"/>\n",
                            (unsigned)m->triangles[3 * t], (unsigned)m->triangles[3 * t + 1],
                            (unsigned)m->triangles[3 * t + 2]))
            return false;
    return mci_buf_printf(ctx, x, "    </triangles>\n   </mesh>\n  </object>\n");
}

static bool model_text(const mci_ctx *ctx, const mcsg_mesh *meshes, size_t count, mci_buf *x)
{
    if (!mci_buf_printf(ctx, x, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model "
                        "unit=\"millimeter\" xml:lang=\"en-US\" xmlns=\"http://schemas."
                        "microsoft.com/3dmanufacturing/core/2015/02\">\n <resources>\n"))
        return false;
    for (size_t k = 0; k < count; k++)
        if (!write_object(ctx, &meshes[k], k + 1, x))
            return false;
    if (!mci_buf_printf(ctx, x, " </resources>\n <build>\n"))
        return false;
    for (size_t k = 0; k < count; k++)
        if (!mci_buf_printf(ctx, x, "  <item objectid=\"%zu\"/>\n", k + 1))
            return false;
    return mci_buf_printf(ctx, x, " </build>\n</model>\n");
}

/* Entries carry a fixed time (1980-01-01, zip's first), so that the same meshes always
 * give the same bytes. */
static bool add_entry(zip_t *zip, const char *name, const void *data, size_t size)
{
    zip_source_t *s = zip_source_buffer(zip, data, size, 0);
    zip_int64_t index;
    if (!s)
        return false;
    index = zip_file_add(zip, name, s, ZIP_FL_ENC_UTF_8 | ZIP_FL_OVERWRITE);
    if (index < 0) {
        zip_source_free(s);
        return false;
    }
    return zip_file_set_dostime(zip, (zip_uint64_t)index, 0, (1 << 5) | 1, 0) == 0;
}

/* The zip built in memory is copied out of libzip's buffer into `out`. */
static bool zip_to_buffer(const mci_ctx *ctx, zip_source_t *zs, mci_buf *out)
{
    zip_int64_t size;
    bool ok;
    if (zip_source_open(zs) != 0)
        return false;
    ok = zip_source_seek(zs, 0, SEEK_END) == 0 && (size = zip_source_tell(zs)) >= 0 &&
         zip_source_seek(zs, 0, SEEK_SET) == 0 && mci_buf_reserve(ctx, out, (size_t)size) &&
         zip_source_read(zs, out->data, (zip_uint64_t)size) == size;
    if (ok)
        out->len = (size_t)size;
    zip_source_close(zs);
    return ok;
}

mcsg_status mci_3mf_write(const mci_ctx *ctx, const mcsg_mesh *meshes, size_t count,
                          mci_buf *out)
{
    mci_buf model = {0};
    zip_error_t ze;
    zip_source_t *zs;
    zip_t *zip = NULL;
    bool ok = model_text(ctx, meshes, count, &model);
    zip_error_init(&ze);
    zs = ok ? zip_source_buffer_create(NULL, 0, 0, &ze) : NULL;
    if (zs) {
        zip_source_keep(zs);
        zip = zip_open_from_source(zs, ZIP_TRUNCATE, &ze);
    }
    ok = zip && add_entry(zip, "[Content_Types].xml", CONTENT_TYPES, sizeof CONTENT_TYPES - 1) &&
         add_entry(zip, "_rels/.rels", RELS, sizeof RELS - 1) &&
         add_entry(zip, "3D/3dmodel.model", model.data, model.len);
    if (zip && (!ok || zip_close(zip) != 0)) {
        zip_discard(zip);
        ok = false;
    }
    ok = ok && zip_to_buffer(ctx, zs, out);
    if (zs)
        zip_source_free(zs);
    zip_error_fini(&ze);
    mci_buf_free(ctx, &model);
    return ok ? MCSG_OK : MCSG_ERR_NOMEM;
}
