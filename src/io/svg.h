/*
 * SVG drawings as OpenSCAD 2021.01's import() reads them (io/svg.c): the outlines of
 * each shape (rect, circle, ellipse, line, polyline, polygon, path), strokes of lines
 * and open paths included, placed on the page in millimetres and truncated to
 * Clipper's grid of 2^-16 as OpenSCAD's import does. Not part of the public API.
 */
#ifndef MESHCSG_IO_SVG_H
#define MESHCSG_IO_SVG_H

#include "base/core.h"
#include "shape/region.h" /* mci_outlines */

/* A drawing: every shape's loops, shape after shape. OpenSCAD fills each shape by the
 * even-odd rule and unites the shapes. */
typedef struct mci_svg {
    mci_outlines outlines;
    uint32_t *shape_start; /* shape_count + 1 entries: shape k's loops are shape_start[k]
                              .. shape_start[k + 1] - 1 */
    uint32_t *shape_line;  /* the line of each shape's element, for messages */
    size_t shape_count;    /* shapes with at least one loop */
} mci_svg;

void mci_svg_free(const mci_ctx *ctx, mci_svg *svg);

/* The shapes of an SVG file as OpenSCAD 2021.01's import(file, dpi, center) reads them
 * (dpi: its `dpi` parameter, 72 by default, for lengths without units; center: the
 * drawing's box centred on the origin). Loops of fewer than 3 distinct points are left
 * out, consecutive repeated points dropped. Elements OpenSCAD ignores (text, use, image,
 * anything inside defs) are ignored; strokes that cannot be reproduced and points
 * beyond Clipper's range are left out with a warning through mci_log. Malformed XML
 * or a geometry attribute that is not a number (where OpenSCAD would read 0) fails with
 * MCSG_ERR_PARSE naming "file:line:"; more than 2^22 points in all, elements nested
 * more than 1024 deep or more than 4096 transforms in force fail with MCSG_ERR_LIMIT.
 * *out is zeroed first and owned by the caller on success (mci_svg_free); on failure
 * nothing is left allocated. */
mcsg_status mci_svg_read(const mci_ctx *ctx, const char *path, double dpi, bool center,
                         mci_svg *out, mcsg_error *err);

/* The same from memory (`size` bytes, no terminating NUL needed); `name` for messages. */
mcsg_status mci_svg_read_memory(const mci_ctx *ctx, const char *data, size_t size,
                                const char *name, double dpi, bool center, mci_svg *out,
                                mcsg_error *err);

#endif
