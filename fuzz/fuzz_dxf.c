/*
 * libFuzzer target for the DXF reader (src/io/dxf.c). The first byte chooses the options
 * (bits 0-1: layer none, "0", "A" or "body"; bits 2-3: $fn 0, 3, 7 or 30; bits 4-5:
 * origin and scale), the rest is the file. abort()s on a violation:
 *  - the status is one the reader documents (success, malformed input, a limit, out of
 *    memory), and a failure's message names the input and a line ("fuzz.dxf:L: ...")
 *    unless it is an allocation failure; nothing is left in the output after a failure;
 *  - outlines are well formed: loops in order, every point a finite multiple of 1/1024
 *    within 2^40;
 *  - nothing leaks (the capped allocator of fuzz_alloc.h counts live bytes).
 * Small results are also filled (mci_region_from_outlines), which must not crash. Replayed
 * over fuzz/corpus/dxf/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_alloc.h"

#include "base/core.h"
#include "io/dxf.h"
#include "shape/region.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_outlines(const mci_outlines *o)
{
    if (o->loop_count > 0 && (!o->loop_start || o->loop_start[0] != 0 ||
                              o->loop_start[o->loop_count] != o->point_count))
        abort();
    for (size_t k = 0; k < o->loop_count; k++)
        if (o->loop_start[k + 1] < o->loop_start[k] + 1)
            abort(); /* every path has a point at least */
    for (size_t i = 0; i < 2 * o->point_count; i++) {
        double x = o->xy[i] * 1024;
        if (!(fabs(o->xy[i]) <= 1099511627776.0) || x != floor(x))
            abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const layers[] = {NULL, "0", "A", "body"};
    static const double fns[] = {0, 3, 7, 30};
    static const double placement[4][3] = {{0, 0, 1}, {1, -2, 1}, {0, 0, 2.5}, {3, 4, 0.5}};
    fuzz_budget b = {0};
    mcsg_options opts;
    mci_ctx ctx;
    mci_outlines o;
    mcsg_error err;
    mcsg_status st;
    unsigned opt;
    if (size == 0)
        return 0;
    opt = data[0];
    opts = capped_options(&b);
    mci_ctx_init(&ctx, &opts);
    st = mci_dxf_read_memory(&ctx, (const char *)data + 1, size - 1, "fuzz.dxf", layers[opt & 3],
                             placement[(opt >> 4) & 3], placement[(opt >> 4) & 3][2],
                             fns[(opt >> 2) & 3], 12, 2, &o, &err);
    if (st == MCSG_OK) {
        check_outlines(&o);
        if (o.point_count <= 2000) {
            mci_region r;
            if (mci_region_from_outlines(&ctx, &o, &r, &err) == MCSG_OK)
                mci_region_free(&ctx, &r);
        }
        mci_outlines_free(&ctx, &o);
    } else if (st != MCSG_ERR_PARSE && st != MCSG_ERR_LIMIT && st != MCSG_ERR_NOMEM) {
        abort();
    } else if (o.xy || o.loop_start || o.point_count || o.loop_count) {
        abort();
    } else if (st != MCSG_ERR_NOMEM && strncmp(err.message, "fuzz.dxf:", 9) != 0) {
        abort();
    }
    if (b.live != 0)
        abort(); /* a leak */
    return 0;
}
