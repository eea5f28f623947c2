/*
 * libFuzzer target for the 3MF reader and writer. The first byte chooses what the rest
 * is: even, a whole 3MF file (the zip container's reading); odd, the model part's XML,
 * put into a valid container here (zip's checksums would stop most mutations of a
 * whole file before they reach the XML). Whenever reading succeeds, each build item's
 * mesh is written back as 3MF, read again and must come back identical, else abort(). Replayed
 * over fuzz/corpus/3mf/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_mesh_common.h"

#include <stdint.h>
#include <stdlib.h>
#include <zip.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char RELS[] =
    "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">"
    "<Relationship Target=\"/3D/3dmodel.model\" Id=\"r\" Type=\"http://schemas.microsoft."
    "com/3dmanufacturing/2013/01/3dmodel\"/></Relationships>";

/* A zip holding the relationships and `xml` as the model part; NULL when libzip fails. */
static void *wrap_model(const uint8_t *xml, size_t size, size_t *zip_size)
{
    zip_error_t ze;
    zip_source_t *zs, *rels, *model;
    zip_t *zip;
    void *bytes = NULL;
    zip_error_init(&ze);
    zs = zip_source_buffer_create(NULL, 0, 0, &ze);
    zip_source_keep(zs);
    zip = zs ? zip_open_from_source(zs, ZIP_TRUNCATE, &ze) : NULL;
    rels = zip ? zip_source_buffer(zip, RELS, sizeof RELS - 1, 0) : NULL;
    model = zip ? zip_source_buffer(zip, size ? xml : (const uint8_t *)"", size, 0) : NULL;
    if (!zip || !rels || !model || zip_file_add(zip, "_rels/.rels", rels, 0) < 0 ||
        zip_file_add(zip, "3D/3dmodel.model", model, 0) < 0 || zip_close(zip) != 0)
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

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *file = data + 1;
    size_t file_size = size ? size - 1 : 0;
    void *wrapped = NULL;
    mcsg_mesh *meshes;
    size_t count;
    if (size == 0)
        return 0;
    if (data[0] & 1) {
        wrapped = wrap_model(file, file_size, &file_size);
        if (!wrapped)
            return 0;
        file = wrapped;
    }
    if (mcsg_3mf_read_memory(file, file_size, "fuzz.3mf", NULL, &meshes, NULL, &count,
                             NULL) == MCSG_OK) {
        for (size_t k = 0; k < count; k++)
            check_round_trip(&meshes[k], MCSG_FORMAT_3MF, "again.3mf");
        mcsg_3mf_free(meshes, NULL, count, NULL);
    }
    free(wrapped);
    return 0;
}
