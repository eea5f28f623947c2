/*
 * OpenSCAD 2021.01's surface() (its SurfaceNode): a table of heights read from a .dat text
 * file or a PNG image, made into a closed mesh the way OpenSCAD makes its PolySet:
 *
 *  - the top: grid point (row i, column j) at (ox + j, oy + i, height); each cell split
 *    into four triangles around its centre, whose height is the mean of the four corners
 *    ((h1 + h2 + h3 + h4) / 4, in that order);
 *  - the walls: a quad per boundary segment down to the bottom, split (a, b, c) and
 *    (a, c, d) in OpenSCAD's vertex order;
 *  - the bottom at min(0, min(height - 1)): OpenSCAD's single polygon through every
 *    boundary point, split here by a strip between the first and last rows (two fans at
 *    the first and last columns take in the side points), so no triangle has zero area.
 *
 * Vertices are shared (welded). A boundary height equal to the bottom's (a missing value,
 * read as 0, when every height is at least 1) is the bottom's vertex there; the wall
 * triangles that would have no area are left out, which keeps the mesh closed.
 *
 * PNG goes through libpng, converted as OpenSCAD's lodepng converts to 8-bit RGB: palettes
 * expanded, grey levels below 8 bits scaled, 16 bits cut to their high byte, grey copied to
 * red, green and blue, transparency and alpha ignored, no gamma. libpng's messages are kept
 * for the error, never printed.
 */
#include "io/surface.h"

#include "base/numparse.h"

#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <string.h>

#define MAX_POINTS ((size_t)1 << 24) /* grid points (rows x columns) */
#define MAX_HEIGHT 1e300             /* so that the sum of four heights stays finite */

/* The heights, row-major, rows x columns (missing values 0), and the bottom's height. */
typedef struct height_table {
    double *h;
    size_t rows, columns;
    double bottom;
} height_table;

/* ---- .dat ------------------------------------------------------------------------------ */

static bool is_space(char c)
{
    return c == ' ' || (c >= '\t' && c <= '\r');
}

static mcsg_status read_dat(const mci_ctx *ctx, const char *text, size_t size, const char *name,
                            height_table *t, mcsg_error *err)
{
    double *values = NULL;
    size_t *row_len = NULL, count = 0, cap = 0, rows = 0, row_cap = 0, columns = 0, line = 0;
    size_t pos = 0;
    double bottom = 0;
    mcsg_status st = MCSG_OK;
    while (st == MCSG_OK && pos < size) {
        const char *start = text + pos, *nl = memchr(start, '\n', size - pos);
        const char *end = nl ? nl : text + size, *s = start, *e = end;
        size_t in_row = 0;
        pos = nl ? (size_t)(nl - text) + 1 : size;
        line++;
        while (s < e && is_space(*s))
            s++;
        while (e > s && is_space(e[-1]))
            e--;
        if (s == e || *s == '#')
            continue;
        if (rows == MAX_POINTS) {
            st = mci_fail(err, MCSG_ERR_LIMIT, "%s:%zu: more than %zu rows of heights", name,
                          line, MAX_POINTS);
            break;
        }
        while (s < e) {
            const char *tok = s, *next;
            double v;
            while (s < e && *s != ' ' && *s != '\t')
                s++;
            if (!mci_parse_double(tok, s, &v, &next) || next != s || !isfinite(v)) {
                st = mci_fail(err, MCSG_ERR_PARSE, "%s:%zu:%zu: '%.*s' is not a number", name,
                              line, (size_t)(tok - start) + 1, (int)(s - tok < 64 ? s - tok : 64),
                              tok);
                break;
            }
            if (fabs(v) > MAX_HEIGHT) {
                st = mci_fail(err, MCSG_ERR_LIMIT, "%s:%zu:%zu: height %.17g beyond %g", name,
                              line, (size_t)(tok - start) + 1, v, MAX_HEIGHT);
                break;
            }
            if (in_row == MAX_POINTS) {
                st = mci_fail(err, MCSG_ERR_LIMIT, "%s:%zu: more than %zu heights in a row",
                              name, line, MAX_POINTS);
                break;
            }
            if (!mci_grow_array(ctx, (void **)&values, &cap, count + 1, sizeof *values, 256)) {
                st = mci_fail_nomem(err, "reading a surface");
                break;
            }
            values[count++] = v;
            in_row++;
            if (v - 1 < bottom)
                bottom = v - 1;
            while (s < e && (*s == ' ' || *s == '\t'))
                s++;
        }
        if (st != MCSG_OK)
            break;
        if (!mci_grow_array(ctx, (void **)&row_len, &row_cap, rows + 1, sizeof *row_len, 64)) {
            st = mci_fail_nomem(err, "reading a surface");
            break;
        }
        row_len[rows++] = in_row;
        if (in_row > columns)
            columns = in_row;
    }
    if (st == MCSG_OK && rows > 0 && columns > MAX_POINTS / rows)
        st = mci_fail(err, MCSG_ERR_LIMIT, "%s: %zu rows of up to %zu heights: more than %zu "
                      "grid points", name, rows, columns, MAX_POINTS);
    if (st == MCSG_OK && rows > 0) {
        t->h = mci_calloc_array(ctx, rows * columns, sizeof *t->h);
        if (!t->h)
            st = mci_fail_nomem(err, "reading a surface");
    }
    if (st == MCSG_OK) {
        for (size_t i = 0, k = 0; i < rows; k += row_len[i], i++)
            memcpy(t->h + i * columns, values + k, row_len[i] * sizeof *values);
        t->rows = rows;
        t->columns = rows ? columns : 0;
        t->bottom = bottom;
    }
    mci_free(ctx, values);
    mci_free(ctx, row_len);
    return st;
}

/* ---- PNG -------------------------------------------------------------------------------- */

typedef struct png_job {
    const mci_ctx *ctx;
    const unsigned char *data;
    size_t size, pos;
    char message[200]; /* libpng's error */
    png_structp png;
    png_infop info;
    unsigned char *pixels;
    png_bytep *rows;
    uint32_t width, height;
    bool too_large, no_memory;
} png_job;

static void png_read_bytes(png_structp png, png_bytep out, size_t n)
{
    png_job *job = png_get_io_ptr(png);
    if (n > job->size - job->pos)
        png_error(png, "the file ends early");
    memcpy(out, job->data + job->pos, n);
    job->pos += n;
}

static void png_on_error(png_structp png, png_const_charp message)
{
    png_job *job = png_get_error_ptr(png);
    snprintf(job->message, sizeof job->message, "%s", message);
    png_longjmp(png, 1);
}

static void png_on_warning(png_structp png, png_const_charp message)
{
    (void)png;
    (void)message;
}

/* Decode into job->pixels (8-bit RGB rows); false after a libpng error. Everything this
 * changes lives in *job, so nothing is lost to the long jump. */
static bool png_decode(png_job *job)
{
    png_structp png = job->png;
    png_infop info = job->info;
    int color, depth;
    size_t rowbytes;
    if (setjmp(png_jmpbuf(png)))
        return false;
    png_set_read_fn(png, job, png_read_bytes);
    png_set_user_limits(png, (png_uint_32)MAX_POINTS, (png_uint_32)MAX_POINTS);
    png_read_info(png, info);
    job->width = png_get_image_width(png, info);
    job->height = png_get_image_height(png, info);
    if ((size_t)job->width * job->height > MAX_POINTS) {
        job->too_large = true;
        return true;
    }
    color = png_get_color_type(png, info);
    depth = png_get_bit_depth(png, info);
    if (color == PNG_COLOR_TYPE_PALETTE)
        png_set_palette_to_rgb(png);
    if ((color & PNG_COLOR_MASK_COLOR) == 0 && depth < 8)
        png_set_expand_gray_1_2_4_to_8(png);
    if (depth == 16)
        png_set_strip_16(png);
    if ((color & PNG_COLOR_MASK_ALPHA) || png_get_valid(png, info, PNG_INFO_tRNS))
        png_set_strip_alpha(png); /* also the alpha a palette's tRNS would expand to */
    if ((color & PNG_COLOR_MASK_COLOR) == 0)
        png_set_gray_to_rgb(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    rowbytes = png_get_rowbytes(png, info);
    if (rowbytes != 3 * (size_t)job->width)
        png_error(png, "unexpected row size after conversion to RGB");
    job->pixels = mci_malloc_array(job->ctx, job->height, rowbytes);
    job->rows = mci_malloc_array(job->ctx, job->height, sizeof *job->rows);
    if (!job->pixels || !job->rows) {
        job->no_memory = true;
        return true;
    }
    for (uint32_t y = 0; y < job->height; y++)
        job->rows[y] = job->pixels + y * rowbytes;
    png_read_image(png, job->rows);
    return true;
}

static mcsg_status read_png(const mci_ctx *ctx, const unsigned char *data, size_t size,
                            const char *name, bool invert, height_table *t, mcsg_error *err)
{
    png_job job;
    mcsg_status st = MCSG_OK;
    /* The size the header claims, refused before libpng reads on: IHDR comes first. */
    if (size >= 24 && memcmp(data + 12, "IHDR", 4) == 0) {
        uint32_t w = (uint32_t)data[16] << 24 | (uint32_t)data[17] << 16 |
                     (uint32_t)data[18] << 8 | data[19];
        uint32_t h = (uint32_t)data[20] << 24 | (uint32_t)data[21] << 16 |
                     (uint32_t)data[22] << 8 | data[23];
        if ((uint64_t)w * h > MAX_POINTS)
            return mci_fail(err, MCSG_ERR_LIMIT, "%s: PNG image of %u x %u pixels: more than "
                            "%zu grid points", name, w, h, MAX_POINTS);
    }
    memset(&job, 0, sizeof job);
    job.ctx = ctx;
    job.data = data;
    job.size = size;
    job.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &job, png_on_error, png_on_warning);
    job.info = job.png ? png_create_info_struct(job.png) : NULL;
    if (!job.info)
        st = mci_fail_nomem(err, "reading a PNG image");
    else if (!png_decode(&job))
        st = mci_fail(err, MCSG_ERR_PARSE, "%s: cannot read the PNG image: %s", name,
                      job.message);
    else if (job.too_large)
        st = mci_fail(err, MCSG_ERR_LIMIT, "%s: PNG image of %u x %u pixels: more than %zu "
                      "grid points", name, job.width, job.height, MAX_POINTS);
    else if (job.no_memory)
        st = mci_fail_nomem(err, "reading a PNG image");
    if (st == MCSG_OK) {
        size_t w = job.width, hgt = job.height;
        t->h = mci_malloc_array(ctx, w * hgt, sizeof *t->h);
        if (!t->h)
            st = mci_fail_nomem(err, "reading a surface");
        for (size_t y = 0; st == MCSG_OK && y < hgt; y++)
            for (size_t x = 0; x < w; x++) {
                const unsigned char *p = job.rows[y] + 3 * x;
                double pixel = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
                double z = 100.0 / 255 * (invert ? 1 - pixel : pixel);
                t->h[(hgt - 1 - y) * w + x] = z;
                if (z - 1 < t->bottom)
                    t->bottom = z - 1;
            }
        t->rows = hgt;
        t->columns = w;
    }
    if (job.png)
        png_destroy_read_struct(&job.png, job.info ? &job.info : NULL, NULL);
    mci_free(ctx, job.pixels);
    mci_free(ctx, job.rows);
    return st;
}

/* ---- the mesh ------------------------------------------------------------------------------ */

typedef struct mesh_writer {
    const height_table *t;
    size_t rows, columns;
    uint32_t *top;          /* each grid point's vertex (the bottom's where they are one) */
    uint32_t centre_base;   /* the cells' centres, row-major */
    uint32_t bottom_base;   /* the boundary at the bottom, counter-clockwise from (0, 0) */
    uint32_t *tris;
    size_t tri_count;
} mesh_writer;

/* The bottom vertex under boundary point (row i, column j). */
static uint32_t bottom_at(const mesh_writer *w, size_t i, size_t j)
{
    size_t a = w->columns - 1, b = w->rows - 1, k;
    if (i == 0)
        k = j;
    else if (j == a)
        k = a + i;
    else if (i == b)
        k = a + b + (a - j);
    else
        k = 2 * a + b + (b - i);
    return w->bottom_base + (uint32_t)k;
}

static uint32_t top_at(const mesh_writer *w, size_t i, size_t j)
{
    return w->top[i * w->columns + j];
}

static void triangle(mesh_writer *w, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t *t;
    if (a == b || b == c || c == a)
        return; /* a wall triangle flattened by a height at the bottom */
    t = w->tris + 3 * w->tri_count++;
    t[0] = a, t[1] = b, t[2] = c;
}

static void quad(mesh_writer *w, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
    triangle(w, a, b, c);
    triangle(w, a, c, d);
}

/* A bottom triangle given counter-clockwise seen from above, turned to face down. */
static void bottom_triangle(mesh_writer *w, uint32_t a, uint32_t b, uint32_t c)
{
    triangle(w, a, c, b);
}

static mcsg_status build_mesh(const mci_ctx *ctx, const height_table *t, bool center,
                              const char *name, mcsg_mesh *out, mcsg_error *err)
{
    size_t rows = t->rows, columns = t->columns, a = columns - 1, b = rows - 1;
    size_t merged = 0, tops, vertices, triangles;
    double ox = center ? -(double)(columns - 1) / 2.0 : 0;
    double oy = center ? -(double)(rows - 1) / 2.0 : 0;
    mesh_writer w;
    mcsg_status st;
    uint32_t next = 0;
    if (rows < 2 || columns < 2) {
        mci_log(ctx, MCSG_LOG_WARNING, "%s: %zu row%s of %zu height%s: the surface is empty",
                name, rows, rows == 1 ? "" : "s", columns, columns == 1 ? "" : "s");
        return MCSG_OK;
    }
    memset(&w, 0, sizeof w);
    w.t = t;
    w.rows = rows;
    w.columns = columns;
    w.top = mci_malloc_array(ctx, rows * columns, sizeof *w.top);
    if (!w.top)
        return mci_fail_nomem(err, "making a surface");
    for (size_t i = 0; i < rows; i++)
        for (size_t j = 0; j < columns; j++)
            if ((i == 0 || i == b || j == 0 || j == a) && t->h[i * columns + j] == t->bottom)
                merged++;
    tops = rows * columns - merged;
    vertices = tops + a * b + 2 * (a + b);
    triangles = 4 * a * b + 6 * (a + b) - 2;
    st = mci_mesh_alloc(ctx, out, vertices, triangles, err);
    if (st != MCSG_OK) {
        mci_free(ctx, w.top);
        return st;
    }
    w.centre_base = (uint32_t)tops;
    w.bottom_base = (uint32_t)(tops + a * b);
    w.tris = out->triangles;
    /* Vertices: the grid, the centres, the bottom's boundary. */
    for (size_t i = 0; i < rows; i++)
        for (size_t j = 0; j < columns; j++) {
            double z = t->h[i * columns + j];
            if ((i == 0 || i == b || j == 0 || j == a) && z == t->bottom) {
                w.top[i * columns + j] = bottom_at(&w, i, j);
                continue;
            }
            out->vertices[3 * next] = ox + (double)j;
            out->vertices[3 * next + 1] = oy + (double)i;
            out->vertices[3 * next + 2] = z;
            w.top[i * columns + j] = next++;
        }
    for (size_t i = 1; i < rows; i++)
        for (size_t j = 1; j < columns; j++) {
            const double *h = t->h;
            double *v = out->vertices + 3 * (w.centre_base + (i - 1) * a + (j - 1));
            v[0] = ox + (double)j - 0.5;
            v[1] = oy + (double)i - 0.5;
            v[2] = (h[(i - 1) * columns + j - 1] + h[(i - 1) * columns + j] +
                    h[i * columns + j - 1] + h[i * columns + j]) / 4;
        }
    for (size_t i = 0; i < rows; i++)
        for (size_t j = 0; j < columns; j++)
            if (i == 0 || i == b || j == 0 || j == a) {
                double *v = out->vertices + 3 * (size_t)bottom_at(&w, i, j);
                v[0] = ox + (double)j;
                v[1] = oy + (double)i;
                v[2] = t->bottom;
            }
    /* The top: four triangles per cell around its centre. */
    for (size_t i = 1; i < rows; i++)
        for (size_t j = 1; j < columns; j++) {
            uint32_t v1 = top_at(&w, i - 1, j - 1), v2 = top_at(&w, i - 1, j);
            uint32_t v3 = top_at(&w, i, j - 1), v4 = top_at(&w, i, j);
            uint32_t c = w.centre_base + (uint32_t)((i - 1) * a + (j - 1));
            triangle(&w, v1, v2, c);
            triangle(&w, v2, v4, c);
            triangle(&w, v4, v3, c);
            triangle(&w, v3, v1, c);
        }
    /* The walls, in OpenSCAD's order and vertex order. */
    for (size_t i = 1; i < rows; i++) {
        quad(&w, bottom_at(&w, i - 1, 0), top_at(&w, i - 1, 0), top_at(&w, i, 0),
             bottom_at(&w, i, 0));
        quad(&w, bottom_at(&w, i, a), top_at(&w, i, a), top_at(&w, i - 1, a),
             bottom_at(&w, i - 1, a));
    }
    for (size_t j = 1; j < columns; j++) {
        quad(&w, bottom_at(&w, 0, j), top_at(&w, 0, j), top_at(&w, 0, j - 1),
             bottom_at(&w, 0, j - 1));
        quad(&w, bottom_at(&w, b, j - 1), top_at(&w, b, j - 1), top_at(&w, b, j),
             bottom_at(&w, b, j));
    }
    /* The bottom: the rectangle between rows 0 and b split along the diagonals from
     * (0, x) to (b, x + 1); the triangles against the first and last columns become fans
     * that take in those columns' points. */
    for (size_t x = 0; x < a; x++) {
        if (x + 1 == a)
            for (size_t y = 0; y < b; y++)
                bottom_triangle(&w, bottom_at(&w, 0, x), bottom_at(&w, y, a),
                                bottom_at(&w, y + 1, a));
        else
            bottom_triangle(&w, bottom_at(&w, 0, x), bottom_at(&w, 0, x + 1),
                            bottom_at(&w, b, x + 1));
        if (x == 0)
            for (size_t y = 0; y < b; y++)
                bottom_triangle(&w, bottom_at(&w, y, 0), bottom_at(&w, b, 1),
                                bottom_at(&w, y + 1, 0));
        else
            bottom_triangle(&w, bottom_at(&w, 0, x), bottom_at(&w, b, x + 1),
                            bottom_at(&w, b, x));
    }
    out->triangle_count = w.tri_count;
    mci_free(ctx, w.top);
    return MCSG_OK;
}

/* ---- entry points ------------------------------------------------------------------------ */

mcsg_status mci_surface_read_memory(const mci_ctx *ctx, const void *data, size_t size,
                                    const char *name, bool center, bool invert,
                                    mcsg_mesh *out, mcsg_error *err)
{
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    height_table t;
    mcsg_status st;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_surface_read_memory: NULL output");
    memset(out, 0, sizeof *out);
    if (!data && size > 0)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_surface_read_memory: NULL data");
    if (!name)
        name = "<memory>";
    memset(&t, 0, sizeof t);
    if (size >= 8 && memcmp(data, signature, 8) == 0)
        st = read_png(ctx, data, size, name, invert, &t, err);
    else
        st = read_dat(ctx, data ? data : "", size, name, &t, err);
    if (st == MCSG_OK)
        st = build_mesh(ctx, &t, center, name, out, err);
    mci_free(ctx, t.h);
    return st;
}

mcsg_status mci_surface_read(const mci_ctx *ctx, const char *path, bool center, bool invert,
                             mcsg_mesh *out, mcsg_error *err)
{
    unsigned char *data;
    size_t size;
    mcsg_status st;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_surface_read: NULL output");
    memset(out, 0, sizeof *out);
    if (!path)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_surface_read: NULL path");
    st = mci_read_file(ctx, path, &data, &size, err);
    if (st != MCSG_OK)
        return st;
    st = mci_surface_read_memory(ctx, data, size, path, center, invert, out, err);
    mci_free(ctx, data);
    return st;
}
