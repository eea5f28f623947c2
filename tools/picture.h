/*
 * Pictures of meshes without a display: an orthographic software rasterizer (z-buffer,
 * Lambert shading, faces coloured by group, optional edges) and a PNG writer on libpng.
 * Used by `meshcsg picture` and `meshcsg eval --picture`.
 */
#ifndef MCSG_PICTURE_H
#define MCSG_PICTURE_H

#include <stddef.h>
#include <stdint.h>

#include "meshcsg.h"

typedef enum picture_view {
    VIEW_ISO,   /* from (1, -1, 1): the front, right and top faces */
    VIEW_TOP,   /* from +z: x to the right, y up */
    VIEW_FRONT, /* from -y: x to the right, z up */
    VIEW_SIDE   /* from +x: y to the right, z up */
} picture_view;

typedef struct picture {
    int width, height;
    uint8_t *rgb;  /* width * height * 3 bytes, rows from the top */
    float *depth;  /* per pixel: towards the viewer is larger; -inf where empty */
} picture;

/* Parses "iso", "top", "front" or "side"; false otherwise. */
int picture_view_parse(const char *name, picture_view *view);

/* Parses "WxH" (16 to 8192 each); false otherwise. */
int picture_size_parse(const char *text, int *width, int *height);

/* Draws the mesh, fitted to the picture with a margin of 5% on a white background.
 * `group` (NULL: one colour) gives each triangle's colour index, e.g. its leaf from
 * provenance; `edges` darkens the triangles' edges. Returns false on allocation
 * failure. Release with picture_free. */
int picture_draw(const mcsg_mesh *mesh, const uint32_t *group, picture_view view, int width,
                 int height, int edges, picture *out);

void picture_free(picture *p);

/* The colour of group g with full light (the shading scales it). */
void picture_group_colour(uint32_t g, uint8_t rgb[3]);

/* Writes the picture as an 8-bit RGB PNG; false with a message in `why` (one line) when
 * the file cannot be written. */
int picture_write_png(const picture *p, const char *path, char *why, size_t why_size);

#endif
