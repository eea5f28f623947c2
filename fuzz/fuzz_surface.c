/*
 * libFuzzer target for surface() (src/io/surface.c): the first byte chooses center (bit 0)
 * and invert (bit 1), the rest is the file, a .dat table or a PNG. With bit 2 set, the
 * CRCs of a PNG's chunks are made right first (else libpng stops most mutations of a PNG
 * at its first checksum). abort()s on a violation:
 *  - the status is one the reader documents (success, malformed input, a limit, out of
 *    memory), a failure's message names the input ("fuzz.surface...") unless it is an
 *    allocation failure, and a failure leaves no mesh;
 *  - a mesh is empty or has OpenSCAD's counts (at most: a height at the bottom's level
 *    removes flat wall triangles) and, up to 200,000 triangles, is closed, outward,
 *    without zero-area triangles (mcsg_mesh_check);
 *  - nothing leaks (the capped allocator of fuzz_alloc.h counts live bytes; libpng's
 *    own allocations are not counted).
 * Replayed over fuzz/corpus/surface/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_alloc.h"

#include "base/core.h"
#include "io/surface.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint32_t crc32_of(const uint8_t *p, size_t n)
{
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1)));
    }
    return c ^ 0xffffffffu;
}

/* Rewrite the CRC of every whole chunk after the signature. */
static void fix_png_crcs(uint8_t *png, size_t size)
{
    size_t pos = 8;
    while (pos + 12 <= size) {
        uint32_t len = (uint32_t)png[pos] << 24 | (uint32_t)png[pos + 1] << 16 |
                       (uint32_t)png[pos + 2] << 8 | png[pos + 3];
        uint32_t crc;
        if (len > size - pos - 12)
            break;
        crc = crc32_of(png + pos + 4, (size_t)len + 4);
        pos += 8 + (size_t)len;
        png[pos] = (uint8_t)(crc >> 24), png[pos + 1] = (uint8_t)(crc >> 16);
        png[pos + 2] = (uint8_t)(crc >> 8), png[pos + 3] = (uint8_t)crc;
        pos += 4;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_budget b = {0};
    mcsg_options opts;
    mci_ctx ctx;
    mcsg_mesh m;
    mcsg_error err;
    mcsg_status st;
    uint8_t *copy = NULL;
    const uint8_t *file = data + 1;
    if (size == 0)
        return 0;
    if ((data[0] & 4) && size > 9 && memcmp(data + 1, "\x89PNG", 4) == 0) {
        copy = malloc(size - 1);
        if (!copy)
            return 0;
        memcpy(copy, data + 1, size - 1);
        fix_png_crcs(copy, size - 1);
        file = copy;
    }
    opts = capped_options(&b);
    mci_ctx_init(&ctx, &opts);
    st = mci_surface_read_memory(&ctx, file, size - 1, "fuzz.surface", data[0] & 1,
                                 (data[0] >> 1) & 1, &m, &err);
    free(copy);
    if (st == MCSG_OK) {
        if (m.triangle_count > 0 && m.triangle_count <= 200000) {
            mcsg_check_report r;
            if (mcsg_mesh_check(&m, &opts, &r, &err) != MCSG_OK) {
                if (err.status != MCSG_ERR_NOMEM)
                    abort();
            } else if (!mcsg_check_report_is_valid(&r) || r.volume_sign != 1 ||
                       r.components != 1 || r.unused_vertices != 0 ||
                       r.duplicate_vertices != 0) {
                abort();
            }
        }
        if ((m.triangle_count == 0) != (m.vertex_count == 0))
            abort();
        mci_mesh_free(&ctx, &m);
    } else if (st != MCSG_ERR_PARSE && st != MCSG_ERR_LIMIT && st != MCSG_ERR_NOMEM) {
        abort();
    } else if (m.vertices || m.triangles || m.vertex_count || m.triangle_count) {
        abort();
    } else if (st != MCSG_ERR_NOMEM && strncmp(err.message, "fuzz.surface", 12) != 0) {
        abort();
    }
    if (b.live != 0)
        abort(); /* a leak */
    return 0;
}
