/*
 * libFuzzer target for the SVG reader (src/io/svg.c, with the strokes of
 * src/shape/stroke.c). The first byte chooses the options (bit 0: center; bits 1-2: dpi
 * 72, 96, 25.4 or 0.5), the rest is the file. abort()s on a violation:
 *  - the status is one the reader documents (success, malformed input, a limit, out of
 *    memory), and a failure's message names the input and a line ("fuzz.svg:L: ...")
 *    unless it is an allocation failure; nothing is left in the output after a failure;
 *  - the drawing is well formed: shapes in order, each with a loop, every loop of at
 *    least 3 points, every point a finite multiple of 2^-16 below 2^46;
 *  - nothing leaks (the capped allocator of fuzz_alloc.h counts live bytes).
 * Small shapes are also filled (mci_region_from_outlines), which must not crash.
 * Replayed over fuzz/corpus/svg/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_alloc.h"

#include "base/core.h"
#include "io/svg.h"
#include "shape/region.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_drawing(const mci_svg *s)
{
    const mci_outlines *o = &s->outlines;
    if (s->shape_count > 0 && (!s->shape_start || s->shape_start[0] != 0 ||
                               s->shape_start[s->shape_count] != o->loop_count))
        abort();
    for (size_t k = 0; k < s->shape_count; k++)
        if (s->shape_start[k + 1] <= s->shape_start[k])
            abort();
    if (o->loop_count > 0 && (o->loop_start[0] != 0 ||
                              o->loop_start[o->loop_count] != o->point_count))
        abort();
    for (size_t k = 0; k < o->loop_count; k++)
        if (o->loop_start[k + 1] < o->loop_start[k] + 3)
            abort();
    for (size_t i = 0; i < 2 * o->point_count; i++) {
        double x = o->xy[i] * 65536;
        if (!(fabs(o->xy[i]) < 70368744177664.0) || x != floor(x))
            abort();
    }
}

static void fill_small_shapes(const mci_ctx *ctx, const mci_svg *s)
{
    for (size_t k = 0; k < s->shape_count; k++) {
        mci_outlines one = {s->outlines.xy, NULL, s->outlines.point_count,
                            s->outlines.loop_start + s->shape_start[k],
                            s->shape_start[k + 1] - s->shape_start[k]};
        mci_region r;
        mcsg_error err;
        if (s->outlines.loop_start[s->shape_start[k + 1]] -
                s->outlines.loop_start[s->shape_start[k]] > 2000)
            continue;
        if (mci_region_from_outlines(ctx, &one, &r, &err) == MCSG_OK)
            mci_region_free(ctx, &r);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const double dpis[] = {72, 96, 25.4, 0.5};
    fuzz_budget b = {0};
    mcsg_options opts;
    mci_ctx ctx;
    mci_svg s;
    mcsg_error err;
    mcsg_status st;
    unsigned opt;
    if (size == 0)
        return 0;
    opt = data[0];
    opts = capped_options(&b);
    mci_ctx_init(&ctx, &opts);
    st = mci_svg_read_memory(&ctx, (const char *)data + 1, size - 1, "fuzz.svg",
                             dpis[(opt >> 1) & 3], opt & 1, &s, &err);
    if (st == MCSG_OK) {
        check_drawing(&s);
        fill_small_shapes(&ctx, &s);
        mci_svg_free(&ctx, &s);
    } else if (st != MCSG_ERR_PARSE && st != MCSG_ERR_LIMIT && st != MCSG_ERR_NOMEM) {
        abort();
    } else if (s.outlines.xy || s.outlines.loop_start || s.shape_start || s.shape_count) {
        abort();
    } else if (st != MCSG_ERR_NOMEM && strncmp(err.message, "fuzz.svg:", 9) != 0) {
        abort();
    }
    if (b.live != 0)
        abort(); /* a leak */
    return 0;
}
