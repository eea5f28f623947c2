/*
 * OpenSCAD's surface() (io/surface.c): a height map, from a .dat table of numbers or a PNG
 * image, as the closed mesh OpenSCAD 2021.01 builds. Not part of the public API.
 */
#ifndef MESHCSG_IO_SURFACE_H
#define MESHCSG_IO_SURFACE_H

#include "base/core.h"

/* OpenSCAD 2021.01's surface(file, center, invert): a .dat height table (text) or a PNG
 * height map (luminance), as the closed mesh OpenSCAD builds (grid, fan of four triangles
 * per cell around its centre, walls and bottom at min(0, min value - 1)), outward
 * counter-clockwise. The file is PNG when it starts with PNG's signature, else a .dat
 * table: lines of numbers separated by spaces and tabs, blank lines and lines starting
 * with '#' skipped, row k of the table at y = k, column j at x = j, short rows filled
 * with 0. A PNG pixel (x, y) is at column x, row height - 1 - y, its height
 * (100/255) (0.2126 R + 0.7152 G + 0.0722 B), with invert (100/255) (1 - that sum)
 * (OpenSCAD's formula; its alpha is ignored); invert does nothing to a .dat file. center
 * puts the grid's middle at x = y = 0. The bottom is triangulated without zero-area
 * triangles; a height equal to the bottom's (a short row's 0 when no number is below 1)
 * shares the bottom's vertex there, the wall triangles it flattens left out.
 *
 * The mesh is welded: (2 rows columns - rows - columns + 1) + 2 (rows + columns) - 4
 * vertices and 4 (rows - 1)(columns - 1) + 6 (rows + columns - 2) - 2 triangles (fewer
 * where a height equals the bottom's). Fewer than 2 rows or columns give an empty mesh
 * (OpenSCAD's walls there enclose nothing), with a warning through mci_log.
 *
 * Errors: MCSG_ERR_IO for a file that cannot be read, MCSG_ERR_PARSE for a .dat token that
 * is not a finite number ("file:line:column: ..."; OpenSCAD stops there with a warning)
 * or a PNG that libpng cannot decode, MCSG_ERR_LIMIT for more than 2^24 grid points or
 * a height beyond 1e300 in magnitude. *out is zeroed first; nothing stays allocated on
 * failure. */
mcsg_status mci_surface_read(const mci_ctx *ctx, const char *path, bool center, bool invert,
                             mcsg_mesh *out, mcsg_error *err);

/* The same from memory (`size` bytes); `name` for messages. */
mcsg_status mci_surface_read_memory(const mci_ctx *ctx, const void *data, size_t size,
                                    const char *name, bool center, bool invert,
                                    mcsg_mesh *out, mcsg_error *err);

#endif
