/*
 * libFuzzer target for the AMF reader (src/io/amf.c). The first byte chooses what the
 * rest is: even, a whole file (plain XML, or a zip archive when it starts with "PK");
 * odd, the XML, zipped here as the entry "fuzz.amf" (zip's checksums would stop most
 * mutations of a whole archive before they reach the XML). abort()s on a violation:
 *  - the status is one the reader documents (success, malformed input, a limit, out of
 *    memory), and a failure's message names the input unless it is an allocation
 *    failure; the output is empty after a failure;
 *  - every triangle indexes its object's vertices, every object has a name;
 *  - mcsg_mesh_read gives the objects side by side, the same doubles and indices;
 *  - nothing leaks (the capped allocator of fuzz_alloc.h counts live bytes).
 * Replayed over fuzz/corpus/amf/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_alloc.h"

#include "base/core.h"
#include "io/amf.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zip.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* `xml` as the only entry of a zip archive (malloc'ed); NULL when libzip fails. */
static void *zip_xml(const uint8_t *xml, size_t size, size_t *zip_size)
{
    zip_error_t ze;
    zip_source_t *zs, *entry;
    zip_t *zip;
    void *bytes = NULL;
    zip_error_init(&ze);
    zs = zip_source_buffer_create(NULL, 0, 0, &ze);
    if (zs)
        zip_source_keep(zs);
    zip = zs ? zip_open_from_source(zs, ZIP_TRUNCATE, &ze) : NULL;
    entry = zip ? zip_source_buffer(zip, size ? xml : (const uint8_t *)"", size, 0) : NULL;
    if (!zip || !entry || zip_file_add(zip, "fuzz.amf", entry, 0) < 0 || zip_close(zip) != 0)
        abort(); /* libzip on memory does not fail but for want of memory */
    if (zip_source_open(zs) == 0 && zip_source_seek(zs, 0, SEEK_END) == 0) {
        zip_int64_t n = zip_source_tell(zs);
        bytes = n > 0 ? malloc((size_t)n) : NULL;
        if (bytes && (zip_source_seek(zs, 0, SEEK_SET) != 0 ||
                      zip_source_read(zs, bytes, (zip_uint64_t)n) != n))
            abort();
        *zip_size = (size_t)n;
        zip_source_close(zs);
    }
    zip_source_free(zs);
    zip_error_fini(&ze);
    return bytes;
}

static int same_double(double a, double b)
{
    return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

static void check_objects(const mci_amf_objects *o)
{
    for (size_t k = 0; k < o->count; k++) {
        const mcsg_mesh *m = &o->meshes[k];
        if (!o->names[k])
            abort();
        for (size_t t = 0; t < 3 * m->triangle_count; t++)
            if (m->triangles[t] >= m->vertex_count)
                abort();
    }
}

/* mcsg_mesh_read's one mesh is the objects side by side. */
static void check_merged(const mci_amf_objects *o, const mcsg_mesh *merged)
{
    size_t v = 0, t = 0;
    for (size_t k = 0; k < o->count; k++) {
        const mcsg_mesh *m = &o->meshes[k];
        if (v + m->vertex_count > merged->vertex_count ||
            t + m->triangle_count > merged->triangle_count)
            abort();
        for (size_t i = 0; i < 3 * m->vertex_count; i++)
            if (!same_double(m->vertices[i], merged->vertices[3 * v + i]))
                abort();
        for (size_t i = 0; i < 3 * m->triangle_count; i++)
            if (merged->triangles[3 * t + i] != m->triangles[i] + v)
                abort();
        v += m->vertex_count, t += m->triangle_count;
    }
    if (v != merged->vertex_count || t != merged->triangle_count)
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_budget b = {0};
    mcsg_options opts;
    mci_ctx ctx;
    mci_amf_objects o;
    mcsg_mesh merged;
    mcsg_error err;
    mcsg_status st;
    const uint8_t *file = data + 1;
    size_t file_size = size ? size - 1 : 0;
    void *zipped = NULL;
    if (size == 0)
        return 0;
    if (data[0] & 1) {
        if (!(zipped = zip_xml(file, file_size, &file_size)))
            return 0;
        file = zipped;
    }
    opts = capped_options(&b);
    mci_ctx_init(&ctx, &opts);
    mci_io_source src = {&ctx, "fuzz.amf", (const char *)file, file, file_size, &err};
    st = mci_amf_read(&src, &o);
    if (st != MCSG_OK && st != MCSG_ERR_PARSE && st != MCSG_ERR_LIMIT && st != MCSG_ERR_NOMEM)
        abort();
    if (st != MCSG_OK && ((st != MCSG_ERR_NOMEM && !strstr(err.message, "fuzz.amf")) ||
                          o.count || o.meshes || o.names))
        abort();
    if (st == MCSG_OK) {
        check_objects(&o);
        if (mcsg_mesh_read_memory(file, file_size, MCSG_FORMAT_AUTO, "fuzz.amf", &opts,
                                  &merged, &err) == MCSG_OK) {
            check_merged(&o, &merged);
            mcsg_mesh_free(&merged, &opts);
        }
        mci_amf_objects_free(&ctx, &o);
    }
    free(zipped);
    if (b.live != 0)
        abort();
    return 0;
}
