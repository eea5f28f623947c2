/*
 * The rasterizer of picture.h. Each triangle is projected orthographically, its pixels
 * (centres inside it, by edge functions) kept where its depth beats the z-buffer's, and
 * shaded by the angle between its normal and a light above the viewer's left shoulder.
 * Doubles are only drawn here: nothing geometric is decided, so no exactness is needed.
 */
#include "picture.h"

#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MARGIN 0.05
#define AMBIENT 0.3

typedef struct camera {
    double right[3], up[3], toward[3]; /* toward: from the scene to the viewer */
    double light[3];                   /* unit, from above the viewer's left shoulder */
    double scale, offset_x, offset_y;  /* screen = scale * (p . right) + offset */
} camera;

int picture_view_parse(const char *name, picture_view *view)
{
    static const char *const names[] = {"iso", "top", "front", "side"};
    for (int k = 0; k < 4; k++)
        if (strcmp(name, names[k]) == 0) {
            *view = (picture_view)k;
            return 1;
        }
    return 0;
}

int picture_size_parse(const char *text, int *width, int *height)
{
    char *end;
    long w = strtol(text, &end, 10), h;
    if (end == text || (*end != 'x' && *end != 'X') || w < 16 || w > 8192)
        return 0;
    text = end + 1;
    h = strtol(text, &end, 10);
    if (end == text || *end != '\0' || h < 16 || h > 8192)
        return 0;
    *width = (int)w, *height = (int)h;
    return 1;
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void set3(double v[3], double x, double y, double z, double scale)
{
    v[0] = x * scale, v[1] = y * scale, v[2] = z * scale;
}

static void view_axes(picture_view view, camera *c)
{
    switch (view) {
    case VIEW_TOP:
        set3(c->right, 1, 0, 0, 1), set3(c->up, 0, 1, 0, 1), set3(c->toward, 0, 0, 1, 1);
        break;
    case VIEW_FRONT:
        set3(c->right, 1, 0, 0, 1), set3(c->up, 0, 0, 1, 1), set3(c->toward, 0, -1, 0, 1);
        break;
    case VIEW_SIDE:
        set3(c->right, 0, 1, 0, 1), set3(c->up, 0, 0, 1, 1), set3(c->toward, 1, 0, 0, 1);
        break;
    default: /* from (1, -1, 1): right = z x toward, up = toward x right */
        set3(c->toward, 1, -1, 1, 1 / sqrt(3.0));
        set3(c->right, 1, 1, 0, 1 / sqrt(2.0));
        set3(c->up, -1, 1, 2, 1 / sqrt(6.0));
    }
}

/* Fits the used vertices' projection into the picture, margins kept, centred. */
static void fit(const mcsg_mesh *mesh, int width, int height, camera *c)
{
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, span;
    for (size_t t = 0; t < 3 * mesh->triangle_count; t++) {
        const double *p = mesh->vertices + 3 * (size_t)mesh->triangles[t];
        double x = dot(p, c->right), y = dot(p, c->up);
        lo[0] = fmin(lo[0], x), hi[0] = fmax(hi[0], x);
        lo[1] = fmin(lo[1], y), hi[1] = fmax(hi[1], y);
    }
    if (!(lo[0] <= hi[0])) {
        c->scale = 1, c->offset_x = c->offset_y = 0;
        return;
    }
    span = fmax((hi[0] - lo[0]) / width, (hi[1] - lo[1]) / height);
    c->scale = span > 0 ? (1 - 2 * MARGIN) / span : 1;
    c->offset_x = width / 2.0 - c->scale * (lo[0] + hi[0]) / 2;
    c->offset_y = height / 2.0 - c->scale * (lo[1] + hi[1]) / 2;
}

void picture_group_colour(uint32_t g, uint8_t rgb[3])
{
    /* hues a golden angle apart, so neighbouring groups differ; a soft saturation */
    double h = fmod(0.58 + 0.618033988749895 * g, 1.0) * 6, s = 0.55, v = 0.95;
    int sector = (int)h;
    double f = h - sector, p = v * (1 - s), q = v * (1 - s * f), u = v * (1 - s * (1 - f));
    double r[6] = {v, q, p, p, u, v}, gr[6] = {u, v, v, q, p, p}, b[6] = {p, p, u, v, v, q};
    rgb[0] = (uint8_t)lround(255 * r[sector % 6]);
    rgb[1] = (uint8_t)lround(255 * gr[sector % 6]);
    rgb[2] = (uint8_t)lround(255 * b[sector % 6]);
}

typedef struct screen_triangle {
    double x[3], y[3], z[3];
    uint8_t rgb[3];
} screen_triangle;

static double edge_fn(const screen_triangle *s, int a, int b, double px, double py)
{
    return (s->x[b] - s->x[a]) * (py - s->y[a]) - (s->y[b] - s->y[a]) * (px - s->x[a]);
}

/* Distance in pixels from (px, py) to the nearest side, given the edge functions. */
static double side_distance(const screen_triangle *s, const double w[3])
{
    double d = INFINITY;
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        double len = hypot(s->x[b] - s->x[a], s->y[b] - s->y[a]);
        if (len > 0)
            d = fmin(d, fabs(w[k]) / len);
    }
    return d;
}

static void fill(picture *p, const screen_triangle *s, int edges)
{
    double area = edge_fn(s, 0, 1, s->x[2], s->y[2]);
    int x0 = (int)floor(fmin(s->x[0], fmin(s->x[1], s->x[2])));
    int x1 = (int)ceil(fmax(s->x[0], fmax(s->x[1], s->x[2])));
    int y0 = (int)floor(fmin(s->y[0], fmin(s->y[1], s->y[2])));
    int y1 = (int)ceil(fmax(s->y[0], fmax(s->y[1], s->y[2])));
    if (area == 0 || !isfinite(area))
        return; /* seen edge-on */
    x0 = x0 < 0 ? 0 : x0, y0 = y0 < 0 ? 0 : y0;
    x1 = x1 > p->width ? p->width : x1, y1 = y1 > p->height ? p->height : y1;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            double px = x + 0.5, py = y + 0.5;
            double w[3] = {edge_fn(s, 1, 2, px, py) / area, edge_fn(s, 2, 0, px, py) / area,
                           edge_fn(s, 0, 1, px, py) / area};
            if (w[0] < 0 || w[1] < 0 || w[2] < 0)
                continue;
            float z = (float)(w[0] * s->z[0] + w[1] * s->z[1] + w[2] * s->z[2]);
            /* rows go down the picture, y up the screen */
            size_t at = (size_t)(p->height - 1 - y) * (size_t)p->width + (size_t)x;
            if (!(z > p->depth[at]))
                continue;
            double wa[3] = {w[0] * fabs(area), w[1] * fabs(area), w[2] * fabs(area)};
            double dim = edges && side_distance(s, wa) < 0.6 ? 0.45 : 1.0;
            p->depth[at] = z;
            for (int k = 0; k < 3; k++)
                p->rgb[3 * at + k] = (uint8_t)lround(s->rgb[k] * dim);
        }
}

static void place_light(camera *c)
{
    static const double in_view[3] = {-0.35, 0.45, 0.82}; /* right, up, toward */
    double len = sqrt(dot(in_view, in_view));
    for (int k = 0; k < 3; k++)
        c->light[k] = (in_view[0] * c->right[k] + in_view[1] * c->up[k] +
                       in_view[2] * c->toward[k]) / len;
}

static void project(const mcsg_mesh *mesh, size_t t, const camera *c, const uint32_t *group,
                    screen_triangle *s)
{
    double n[3], e1[3], e2[3], len, lambert;
    const double *v[3];
    uint8_t base[3];
    for (int k = 0; k < 3; k++) {
        v[k] = mesh->vertices + 3 * (size_t)mesh->triangles[3 * t + k];
        s->x[k] = c->scale * dot(v[k], c->right) + c->offset_x;
        s->y[k] = c->scale * dot(v[k], c->up) + c->offset_y;
        s->z[k] = dot(v[k], c->toward);
    }
    for (int k = 0; k < 3; k++)
        e1[k] = v[1][k] - v[0][k], e2[k] = v[2][k] - v[0][k];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    len = sqrt(dot(n, n));
    lambert = len > 0 ? fabs(dot(n, c->light)) / len : 0;
    picture_group_colour(group ? group[t] : 0, base);
    for (int k = 0; k < 3; k++)
        s->rgb[k] = (uint8_t)lround(base[k] * (AMBIENT + (1 - AMBIENT) * lambert));
}

int picture_draw(const mcsg_mesh *mesh, const uint32_t *group, picture_view view, int width,
                 int height, int edges, picture *out)
{
    size_t pixels = (size_t)width * (size_t)height;
    camera c;
    out->width = width, out->height = height;
    out->rgb = malloc(3 * pixels);
    out->depth = malloc(pixels * sizeof *out->depth);
    if (!out->rgb || !out->depth) {
        picture_free(out);
        return 0;
    }
    memset(out->rgb, 255, 3 * pixels);
    for (size_t i = 0; i < pixels; i++)
        out->depth[i] = -INFINITY;
    view_axes(view, &c);
    place_light(&c);
    fit(mesh, width, height, &c);
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        screen_triangle s;
        project(mesh, t, &c, group, &s);
        fill(out, &s, edges);
    }
    return 1;
}

void picture_free(picture *p)
{
    free(p->rgb);
    free(p->depth);
    p->rgb = NULL, p->depth = NULL;
}

typedef struct png_failure {
    jmp_buf jump;
    char *why;
    size_t why_size;
} png_failure;

static void on_png_error(png_structp png, png_const_charp message)
{
    png_failure *f = png_get_error_ptr(png);
    snprintf(f->why, f->why_size, "%s", message);
    longjmp(f->jump, 1);
}

static void on_png_warning(png_structp png, png_const_charp message)
{
    (void)png, (void)message; /* nothing a user can act on */
}

/* libpng reports errors by longjmp: everything it touches after setjmp is volatile or
 * set before. */
static int write_rows(FILE *file, const picture *p, png_failure *f)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, f, on_png_error,
                                              on_png_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        snprintf(f->why, f->why_size, "out of memory");
        png_destroy_write_struct(&png, NULL);
        return 0;
    }
    if (setjmp(f->jump)) {
        png_destroy_write_struct(&png, &info);
        return 0;
    }
    png_init_io(png, file);
    png_set_IHDR(png, info, (png_uint_32)p->width, (png_uint_32)p->height, 8,
                 PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    for (int y = 0; y < p->height; y++)
        png_write_row(png, p->rgb + 3 * (size_t)y * (size_t)p->width);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return 1;
}

int picture_write_png(const picture *p, const char *path, char *why, size_t why_size)
{
    png_failure f;
    FILE *file = fopen(path, "wb");
    int ok;
    f.why = why, f.why_size = why_size;
    if (!file) {
        snprintf(why, why_size, "cannot create %s", path);
        return 0;
    }
    ok = write_rows(file, p, &f);
    if (fclose(file) != 0 && ok) {
        snprintf(why, why_size, "cannot write %s", path);
        ok = 0;
    }
    if (!ok)
        remove(path);
    return ok;
}
