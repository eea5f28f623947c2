/*
 * OpenSCAD's primitives: cube, sphere and cylinder, tessellated exactly as OpenSCAD
 * (2024+, src/core/primitives.cc and src/utils/calc.cc) does, so that a file run through
 * OpenSCAD and through meshcsg gets the same leaf vertices, bit for bit:
 *  - fragments: get_fragments_from_r (3 below r = 2^-20 or for an infinite/NaN $fn;
 *    max($fn, 3) for $fn > 0; else ceil(max(min(360/$fa, r*2*pi/$fs), 5)));
 *  - circle point i of n at phi = 360*i/n degrees: (r*cos_degrees(phi), r*sin_degrees(phi));
 *  - sphere: rings = (n+1)/2 circles at polar angle 180*(i+0.5)/rings, radius
 *    r*sin_degrees, height r*cos_degrees; a cap polygon on the first and on the last ring,
 *    quads between rings. Vertices n*rings;
 *  - cylinder: a circle of r1 at z1 and one of r2 at z2 (a single apex vertex when that
 *    radius is 0), quads (or triangles for a cone) around, one cap polygon per circle;
 *  - cube: 8 corners, 6 quads.
 * OpenSCAD keeps these polygons and lets its triangulator split them. meshcsg splits them
 * itself, with the same outward orientation (counter-clockwise seen from outside): each
 * convex cap polygon by a fan from its first vertex, each quad (a, b, c, d) into (a, b, c)
 * and (a, c, d). The polygons are planar up to the rounding of their vertices, so any
 * triangulation covers the same surface; only the diagonal may differ from OpenSCAD's.
 * Triangle counts: cube 12, sphere 2n(rings-1) + 2(n-2), cylinder 2n + 2(n-2),
 * cone n + (n-2).
 */
#include "base/core.h"
#include "base/degree_trig.h"

#include <limits.h>
#include <math.h>
#include <string.h>

/* OpenSCAD's GRID_FINE: below this radius a circle gets the minimum 3 fragments. */
#define GRID_FINE 0.00000095367431640625
/* OpenSCAD's F_MINIMUM: smaller $fa and $fs are clamped to it. */
#define F_MINIMUM 0.01
#define PI_DOUBLE 3.14159265358979323846

int mcsg_fragments(double r, double fn, double fa, double fs)
{
    double n;
    if (r < GRID_FINE || isinf(fn) || isnan(fn))
        return 3;
    if (fn > 0.0) {
        if (fn < 3)
            return 3;
        return fn >= (double)INT_MAX ? INT_MAX : (int)fn;
    }
    /* fmin/fmax ignore a NaN operand, as std::fmin/fmax do in OpenSCAD. */
    n = ceil(fmax(fmin(360.0 / fa, r * 2 * PI_DOUBLE / fs), 5));
    return n >= (double)INT_MAX ? INT_MAX : (int)n;
}

/* A zero fa or fs means OpenSCAD's default; other values below F_MINIMUM are clamped
 * to it (OpenSCAD's set_fragments). */
static int resolution_fragments(double r, mcsg_resolution res)
{
    double fa = res.fa == 0 ? 12.0 : res.fa, fs = res.fs == 0 ? 2.0 : res.fs;
    if (fa < F_MINIMUM)
        fa = F_MINIMUM;
    if (fs < F_MINIMUM)
        fs = F_MINIMUM;
    return mcsg_fragments(r, res.fn, fa, fs);
}

/* Allocate a mesh, first checking the counts against the 32-bit limit in 64 bits. */
static mcsg_status alloc_counted(const mci_ctx *ctx, uint64_t vertices, uint64_t triangles,
                                 const char *what, mcsg_mesh *out, mcsg_error *err)
{
    if (vertices > UINT32_MAX || triangles > UINT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "%s: %llu vertices and %llu triangles exceed "
                        "the limit of %u each", what, (unsigned long long)vertices,
                        (unsigned long long)triangles, UINT32_MAX);
    return mci_mesh_alloc(ctx, out, (size_t)vertices, (size_t)triangles, err);
}

/* Append n circle points of radius r at height z, starting at vertex index `first`. */
static void put_circle(double *vertices, size_t first, double r, double z, int n)
{
    for (int i = 0; i < n; i++) {
        double phi = (360.0 * i) / n;
        double *p = vertices + 3 * (first + (size_t)i);
        p[0] = r * mci_cos_degrees(phi);
        p[1] = r * mci_sin_degrees(phi);
        p[2] = z;
    }
}

static uint32_t *put_triangle(uint32_t *t, size_t a, size_t b, size_t c)
{
    t[0] = (uint32_t)a;
    t[1] = (uint32_t)b;
    t[2] = (uint32_t)c;
    return t + 3;
}

/* A convex polygon, counter-clockwise seen from outside, as a fan from corner 0. */
static uint32_t *put_fan(uint32_t *t, const size_t *corners, size_t n)
{
    for (size_t k = 1; k + 1 < n; k++)
        t = put_triangle(t, corners[0], corners[k], corners[k + 1]);
    return t;
}

/* The cap polygon of a circle of n points starting at `first`, in increasing order
 * (facing +z) or decreasing (facing -z), as a fan from its first corner. */
static uint32_t *put_cap(uint32_t *t, size_t first, size_t n, int facing_up)
{
    for (size_t k = 1; k + 1 < n; k++) {
        if (facing_up)
            t = put_triangle(t, first, first + k, first + k + 1);
        else
            t = put_triangle(t, first + n - 1, first + n - 1 - k, first + n - 2 - k);
    }
    return t;
}

mcsg_status mcsg_make_cube(const double size[3], int center, const mcsg_options *opts,
                           mcsg_mesh *out, mcsg_error *err)
{
    /* OpenSCAD's quads: top, bottom, front, right, back, left; corner i is
     * (i&1 ? x2 : x1, i&2 ? y2 : y1, i&4 ? z2 : z1). */
    static const size_t quads[6][4] = {{4, 5, 7, 6}, {2, 3, 1, 0}, {0, 1, 5, 4},
                                       {1, 3, 7, 5}, {3, 2, 6, 7}, {2, 0, 4, 6}};
    double lo[3], hi[3];
    mci_ctx ctx;
    mcsg_status st;
    uint32_t *t;
    mci_ctx_init(&ctx, opts);
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_make_cube: NULL output");
    memset(out, 0, sizeof *out);
    if (!size)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_make_cube: NULL size");
    for (int k = 0; k < 3; k++) {
        if (!(size[k] > 0) || isinf(size[k]))
            return MCSG_OK; /* OpenSCAD: an empty cube */
        lo[k] = center ? -size[k] / 2 : 0;
        hi[k] = center ? +size[k] / 2 : size[k];
    }
    st = mci_mesh_alloc(&ctx, out, 8, 12, err);
    if (st != MCSG_OK)
        return st;
    for (int i = 0; i < 8; i++) {
        out->vertices[3 * i + 0] = (i & 1) ? hi[0] : lo[0];
        out->vertices[3 * i + 1] = (i & 2) ? hi[1] : lo[1];
        out->vertices[3 * i + 2] = (i & 4) ? hi[2] : lo[2];
    }
    t = out->triangles;
    for (int q = 0; q < 6; q++)
        t = put_fan(t, quads[q], 4);
    return MCSG_OK;
}

mcsg_status mcsg_make_sphere(double r, mcsg_resolution res, const mcsg_options *opts,
                             mcsg_mesh *out, mcsg_error *err)
{
    mci_ctx ctx;
    mcsg_status st;
    size_t n, rings;
    uint32_t *t;
    mci_ctx_init(&ctx, opts);
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_make_sphere: NULL output");
    memset(out, 0, sizeof *out);
    if (!(r > 0) || isinf(r))
        return MCSG_OK; /* OpenSCAD: an empty sphere */
    n = (size_t)resolution_fragments(r, res);
    rings = (n + 1) / 2;
    st = alloc_counted(&ctx, (uint64_t)n * rings, 2 * (uint64_t)n * (rings - 1) + 2 * (n - 2),
                       "sphere", out, err);
    if (st != MCSG_OK)
        return st;
    for (size_t i = 0; i < rings; i++) {
        double phi = (180.0 * ((double)i + 0.5)) / (double)rings;
        put_circle(out->vertices, i * n, r * mci_sin_degrees(phi), r * mci_cos_degrees(phi),
                   (int)n);
    }
    t = put_cap(out->triangles, 0, n, 1);
    for (size_t i = 0; i + 1 < rings; i++) {
        for (size_t k = 0; k < n; k++) {
            /* OpenSCAD's quad between ring i (above) and ring i+1 (below). */
            size_t quad[4] = {i * n + (k + 1) % n, i * n + k, (i + 1) * n + k,
                              (i + 1) * n + (k + 1) % n};
            t = put_fan(t, quad, 4);
        }
    }
    put_cap(t, (rings - 1) * n, n, 0);
    return MCSG_OK;
}

/* Side faces of a cylinder or cone between the bottom (z1) and top (z2) vertices. */
static uint32_t *put_cylinder_sides(uint32_t *t, size_t n, int cone, int inverted_cone)
{
    for (size_t i = 0; i < n; i++) {
        size_t j = (i + 1) % n;
        if (cone) {
            t = put_triangle(t, i, j, n); /* apex is vertex n */
        } else if (inverted_cone) {
            t = put_triangle(t, 0, j + 1, i + 1); /* apex is vertex 0 */
        } else {
            size_t quad[4] = {i, j, j + n, i + n};
            t = put_fan(t, quad, 4);
        }
    }
    return t;
}

static int cylinder_is_empty(double h, double r1, double r2)
{
    /* OpenSCAD's exact rule: no height, a negative or infinite radius, or no radius. */
    return !(h > 0) || isinf(h) || !(r1 >= 0) || isinf(r1) || !(r2 >= 0) || isinf(r2) ||
           (r1 <= 0 && r2 <= 0);
}

mcsg_status mcsg_make_cylinder(double h, double r1, double r2, int center,
                               mcsg_resolution res, const mcsg_options *opts,
                               mcsg_mesh *out, mcsg_error *err)
{
    mci_ctx ctx;
    mcsg_status st;
    size_t n;
    int cone, inverted_cone;
    double z1, z2;
    uint32_t *t;
    mci_ctx_init(&ctx, opts);
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_make_cylinder: NULL output");
    memset(out, 0, sizeof *out);
    if (cylinder_is_empty(h, r1, r2))
        return MCSG_OK;
    n = (size_t)resolution_fragments(fmax(r1, r2), res);
    z1 = center ? -h / 2 : 0;
    z2 = center ? +h / 2 : h;
    cone = r2 == 0.0;
    inverted_cone = r1 == 0.0;
    st = alloc_counted(&ctx, (cone || inverted_cone) ? n + 1 : 2 * (uint64_t)n,
                       (cone || inverted_cone) ? n + (n - 2) : 2 * (uint64_t)n + 2 * (n - 2),
                       "cylinder", out, err);
    if (st != MCSG_OK)
        return st;
    if (inverted_cone) {
        double apex[3] = {0.0, 0.0, z1};
        memcpy(out->vertices, apex, sizeof apex);
    } else {
        put_circle(out->vertices, 0, r1, z1, (int)n);
    }
    if (cone) {
        double apex[3] = {0.0, 0.0, z2};
        memcpy(out->vertices + 3 * n, apex, sizeof apex);
    } else {
        put_circle(out->vertices, inverted_cone ? 1 : n, r2, z2, (int)n);
    }
    t = put_cylinder_sides(out->triangles, n, cone, inverted_cone);
    if (!inverted_cone)
        t = put_cap(t, 0, n, 0);
    if (!cone)
        put_cap(t, inverted_cone ? 1 : n, n, 1);
    return MCSG_OK;
}
