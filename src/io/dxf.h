/*
 * DXF drawings as OpenSCAD 2021.01's import() reads them (io/dxf.c): the outlines of a
 * file's LINE, LWPOLYLINE, CIRCLE, ARC, ELLIPSE and INSERT entities, snapped to
 * OpenSCAD's grid of 1/1024 and chained into paths as its DxfData does. Not part of the
 * public API.
 */
#ifndef MESHCSG_IO_DXF_H
#define MESHCSG_IO_DXF_H

#include "base/core.h"
#include "shape/region.h" /* mci_outlines */

/* The outlines of a DXF file's drawing as OpenSCAD 2021.01's import()/DxfData reads them:
 * LINE, LWPOLYLINE, CIRCLE, ARC, ELLIPSE, INSERT of BLOCKs; `layer` NULL or "" = all
 * layers; coordinates (value - origin) * scale (origin NULL = 0, 0); circles and arcs
 * split by get_fragments_from_r(r, fn, fs, fa); endpoints snapped to OpenSCAD's 1/1024
 * grid and chained into paths, open paths closed, each path's points in OpenSCAD's order.
 * The caller fills them by the even-odd rule. Unsupported entities: a warning through
 * mci_log as OpenSCAD's. Malformed input (a group code that is not an integer, a value
 * that is not a finite number, an entity without the points it needs) fails with
 * MCSG_ERR_PARSE naming "file:line:"; coordinates beyond 2^40 in magnitude, more than
 * 2^22 line segments (blocks and inserted copies included), or arc angles more than 1024
 * turns apart fail with MCSG_ERR_LIMIT. *out is zeroed first and owned by the caller on
 * success (mci_outlines_free); on failure nothing is left allocated. */
mcsg_status mci_dxf_read(const mci_ctx *ctx, const char *path, const char *layer,
                         const double origin[2], double scale, double fn, double fa, double fs,
                         mci_outlines *out, mcsg_error *err);

/* The same from memory (`size` bytes, no terminating NUL needed); `name` for messages. */
mcsg_status mci_dxf_read_memory(const mci_ctx *ctx, const char *data, size_t size,
                                const char *name, const char *layer, const double origin[2],
                                double scale, double fn, double fa, double fs,
                                mci_outlines *out, mcsg_error *err);

#endif
