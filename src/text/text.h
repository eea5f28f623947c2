/*
 * OpenSCAD's text(): the outlines of a text as OpenSCAD 2021.01 draws them (text/text.c),
 * through fontconfig (the font), HarfBuzz (shaping) and FreeType (the glyph outlines).
 */
#ifndef MESHCSG_TEXT_TEXT_H
#define MESHCSG_TEXT_TEXT_H

#include "base/core.h"
#include "shape/region.h" /* mci_outlines */

/* text()'s arguments; NULL strings and the defaults noted are OpenSCAD's. */
typedef struct mci_text_params {
    const char *text;   /* UTF-8; NULL is "" */
    double size;        /* OpenSCAD's default 10 (the caller fills it in) */
    const char *font;   /* fontconfig pattern, e.g. "Liberation Sans:style=Bold"; NULL or
                           blank: OpenSCAD's default "Liberation Sans:style=Regular" */
    const char *halign; /* "left" (NULL), "center", "right" */
    const char *valign; /* "baseline" (NULL), "top", "center", "bottom" */
    double spacing;     /* OpenSCAD's default 1 (the caller fills it in) */
    const char *direction, *language, *script; /* NULL: detected, "en", detected */
    double fn, fa, fs; /* $fn, $fa, $fs in scope, as they are (text() clamps nothing) */
} mci_text_params;

/* The glyph outlines of the text, placed and flattened exactly as OpenSCAD 2021.01 does
 * (FreeType outline decomposition, curves split into segments by OpenSCAD's rule,
 * HarfBuzz shaping, alignment, spacing, size scaling): the points OpenSCAD gives its
 * Clipper union. Loops keep the font's orientation (TrueType: outer loops clockwise,
 * holes counter-clockwise). OpenSCAD fills them by the non-zero rule, uniting the glyphs:
 * the even-odd rule gives the same only where loops do not overlap, and they do overlap
 * in composite glyphs (in Liberation Sans, 20 characters below U+2200: Å Ç ç Ą ą ę Ş ş
 * ţ Ų Ǫ ǫ Ǭ ǭ ǻ ȩ Ḉ ḉ ḝ Å) and between glyphs set closer than their width. Repeated
 * consecutive points (the closing point of each contour) are dropped, and loops left
 * with fewer than three points. An empty text gives no loops. Unknown halign/valign
 * values and a font that fontconfig had to replace are logged as warnings; invalid UTF-8
 * fails with MCSG_ERR_INVALID_ARG, a non-finite size or spacing and a font pattern that
 * fontconfig cannot parse too, more than 2^26 points with MCSG_ERR_LIMIT, a font that
 * cannot be found or read with MCSG_ERR_IO. */
mcsg_status mci_text_outlines(const mci_ctx *ctx, const mci_text_params *p, mci_outlines *out,
                              mcsg_error *err);

#endif
