/*
 * SVG drawings as OpenSCAD 2021.01 reads them for import() (its import_svg.cc and
 * libsvg), done again in C from what they do. XML comes from expat, element names as
 * written (a prefixed "svg:rect" is no rect, as with OpenSCAD's libxml2 reader).
 *
 * Elements, in document order:
 *  - defs: nothing inside is read (its own end tag ends that; nested defs end it early,
 *    as OpenSCAD's flag does).
 *  - svg, g, text, tspan are containers: the next shapes are their children. The end of
 *    g, text or tspan removes the innermost container, whatever it is; an svg is never
 *    removed. A shape's `transform` and those of its containers apply to its points, but
 *    not the outermost element's (it has no parent) and none at all for the outermost
 *    element itself. Transforms: the words matrix, translate, scale, rotate, skewX, skewY
 *    (replaced in the text by one letter each, as OpenSCAD does, so "translateX(" reads
 *    as a translate), arguments split at spaces, commas and parentheses; a wrong number
 *    of arguments drops that transform with a warning. Matrices are applied to each point
 *    one after another, innermost first, each as a*x + c*y + e (left to right, in
 *    doubles); rotate and skew use OpenSCAD's degree trigonometry.
 *  - rect: x, y, width, height; with rx or ry (|r| >= 1e-8; one given sets the other;
 *    each at most half the side) the path "M x+rx,y H ... A ... z" printed with six
 *    significant digits (OpenSCAD formats it so) and read as a path; else the four
 *    corners and the first again. circle and ellipse: 40 points at 9 i degrees,
 *    (cx + rx sin, cy + ry cos). polygon: its points and the first again. line and
 *    polyline: stroked, never filled (even when closed).
 *  - path: OpenSCAD's tokens (separators space and comma; the command letters
 *    zmlcqahvst, either case, and '-' are tokens of their own; a token with two dots or
 *    more cut into numbers each ending before a dot ("1.2.3" -> "1.2", ".3"); a token
 *    ending in 'e' held as the start of an exponent). Commands as OpenSCAD implements them: Béziers in 20 steps
 *    (t = i / 20, Bernstein form), arcs in |sweep| * 10 / 180 + 4 steps by the SVG
 *    implementation notes, S and T reflecting the previous control point only after a C
 *    or S (resp. Q or T). M starts a new subpath; the previous one, when its ends are
 *    more than 0.1 apart, is stroked instead of filled. z closes the subpath (and marks
 *    the path closed, so that its last subpath is never stroked).
 *  - Strokes (shape/stroke.h): width = the stroke-width attribute, else the style's
 *    "stroke-width:" entry (names matched exactly), 1 when below 0.01 or unreadable;
 *    caps: butt, round, else square; joins: bevel (Clipper's square), round, else miter.
 *    They are made before the shape's transform, which then moves their outline.
 *  - The page: the svg element's width and height with their unit (none: 25.4 / dpi
 *    mm each, px 25.4 / 96, pt 25.4 / 72, pc 25.4 / 6, in, cm, mm; %, em, ex: the
 *    viewBox size; missing or unreadable: the viewBox size at dpi, or 0). With a valid
 *    viewBox, a user unit is width / viewBox width millimetres (height likewise), the
 *    same for both unless preserveAspectRatio is "none" (the smaller for meet, the
 *    larger for slice, aligned by xMin/xMid/xMax, yMin/...). A later svg element
 *    replaces the page for everything (its viewBox, scale and alignment), as in
 *    OpenSCAD.
 *  - Placement: x = sx (x - vx) - cx, y = sy (-vy - y) + cy, where (cx, cy) is the
 *    centre of the box of all points times the scale in force when each was read (with
 *    center), else (-align x, height - align y). Each coordinate is then truncated to a
 *    multiple of 2^-16, Clipper's grid; a loop with a point at or beyond 2^46 there is
 *    dropped with the rest of its shape ("Range check failed", OpenSCAD's warning).
 * Numbers: geometry attributes must be numbers throughout (OpenSCAD reads 0 where one
 * is not; here that is a parse error naming the line), stroke-width falls back to 1 as
 * OpenSCAD's does. Non-finite points are left out of the centring box.
 */
#include "io/svg.h"

#include "base/numparse.h"
#include "base/degree_trig.h"
#include "shape/stroke.h"

#include <expat.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define MAX_POINTS ((size_t)1 << 22)
#define MAX_DEPTH 1024
#define MAX_MATRICES 4096
#define CLIPPER_SCALE 65536.0
#define CLIPPER_RANGE 4611686018427387904.0 /* 2^62: Clipper's hiRange, in grid units */
#define INCH_TO_MM 25.4
#define ELLIPSE_STEPS 40
#define BEZIER_STEPS 20

/* A shape's paths while it is read: path k is points start[k] .. start[k + 1] - 1 (the
 * last one up to n). */
typedef struct paths {
    double *xy;
    size_t n, cap;
    uint32_t *start;
    size_t count, start_cap;
} paths;

typedef enum align_kind { ALIGN_NONE, ALIGN_MIN, ALIGN_MID, ALIGN_MAX } align_kind;

typedef struct container {
    size_t mat_begin, mat_end; /* its own matrices in r->mats, innermost first */
} container;

typedef struct svg_reader {
    const mci_ctx *ctx;
    const char *name;
    mcsg_error *err;
    mcsg_status status;
    XML_Parser parser;
    double dpi;
    bool center, in_defs;
    container *stack;
    size_t depth, stack_cap;
    double *mats; /* 6 per matrix: m00 m01 m02 m10 m11 m12 */
    size_t mat_count, mat_cap;
    paths cur;
    /* the drawing so far: points as the transforms leave them, shape by shape */
    paths all;
    uint32_t *shape_start, *shape_line;
    size_t shape_count, shape_cap, line_cap;
    /* the page in force, and the centring box */
    double scale[2], align[2], viewbox[2], height_mm;
    double box_min[2], box_max[2];
    bool box_empty;
} svg_reader;

/* ---------------------------------------------------------------------------------- */
/* Messages */

static void fail(svg_reader *r, mcsg_status status, const char *fmt, ...) MCI_PRINTF(3, 4);

static void fail(svg_reader *r, mcsg_status status, const char *fmt, ...)
{
    char prefix[512];
    va_list ap;
    if (r->status != MCSG_OK)
        return;
    snprintf(prefix, sizeof prefix, "%s:%lu", r->name,
             (unsigned long)XML_GetCurrentLineNumber(r->parser));
    va_start(ap, fmt);
    r->status = mci_vfail(r->err, status, prefix, fmt, ap);
    va_end(ap);
    XML_StopParser(r->parser, XML_FALSE);
}

static void nomem(svg_reader *r)
{
    char what[512];
    if (r->status != MCSG_OK)
        return;
    snprintf(what, sizeof what, "reading %s", r->name);
    r->status = mci_fail_nomem(r->err, what);
    XML_StopParser(r->parser, XML_FALSE);
}

static void warn(svg_reader *r, const char *fmt, ...) MCI_PRINTF(2, 3);

static void warn(svg_reader *r, const char *fmt, ...)
{
    char prefix[512];
    va_list ap;
    snprintf(prefix, sizeof prefix, "%s:%lu", r->name,
             (unsigned long)XML_GetCurrentLineNumber(r->parser));
    va_start(ap, fmt);
    mci_vlog(r->ctx, MCSG_LOG_WARNING, prefix, fmt, ap);
    va_end(ap);
}

/* ---------------------------------------------------------------------------------- */
/* Paths being built */

static bool paths_room(svg_reader *r, paths *p, size_t more)
{
    if (r->cur.n + r->all.n + more > MAX_POINTS) {
        fail(r, MCSG_ERR_LIMIT, "more than %zu points", MAX_POINTS);
        return false;
    }
    if (!mci_grow_array(r->ctx, (void **)&p->xy, &p->cap, 2 * (p->n + more), sizeof *p->xy,
                        256)) {
        nomem(r);
        return false;
    }
    return true;
}

static void new_path(svg_reader *r, paths *p)
{
    if (r->status != MCSG_OK)
        return;
    if (!mci_grow_array(r->ctx, (void **)&p->start, &p->start_cap, p->count + 2,
                        sizeof *p->start, 16)) {
        nomem(r);
        return;
    }
    p->start[p->count++] = (uint32_t)p->n;
    p->start[p->count] = (uint32_t)p->n;
}

static void add_point(svg_reader *r, double x, double y)
{
    paths *p = &r->cur;
    if (r->status != MCSG_OK || !paths_room(r, p, 1))
        return;
    if (p->count == 0)
        new_path(r, p);
    if (r->status != MCSG_OK)
        return;
    p->xy[2 * p->n] = x;
    p->xy[2 * p->n + 1] = y;
    p->start[p->count] = (uint32_t)++p->n;
}

static size_t last_path_size(const paths *p)
{
    return p->count ? p->n - p->start[p->count - 1] : 0;
}

/* ---------------------------------------------------------------------------------- */
/* Numbers and attributes as OpenSCAD's libsvg reads them */

static bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

/* A number filling the whole text (Boost.Spirit's double_, which mci_parse_double's
 * grammar matches). */
static bool whole_number(const char *s, size_t n, double *v)
{
    const char *next;
    return n > 0 && mci_parse_double(s, s + n, v, &next) && next == s + n;
}

static const char *attribute(const char **atts, const char *name)
{
    for (size_t i = 0; atts[i]; i += 2)
        if (strcmp(atts[i], name) == 0)
            return atts[i + 1];
    return NULL;
}

/* A geometry attribute: 0 when missing or empty, else a number. */
static double number_attr(svg_reader *r, const char **atts, const char *element,
                          const char *name)
{
    const char *text = attribute(atts, name);
    double v = 0;
    if (r->status == MCSG_OK && text && *text && !whole_number(text, strlen(text), &v))
        fail(r, MCSG_ERR_PARSE, "<%s> %s=\"%.40s\" is not a number", element, name, text);
    return v;
}

/* OpenSCAD's parse_double: the number, or 0 when the text is not one. */
static double lenient_number(const char *s, size_t n)
{
    double v = 0;
    return whole_number(s, n, &v) ? v : 0;
}

/* The value of `name` in a style attribute ("a:b;c:d", names compared exactly, an entry
 * with other than one ':' skipped), as OpenSCAD's get_style. */
static bool style_value(const char *style, const char *name, const char **value, size_t *len)
{
    size_t name_len = strlen(name);
    while (style) {
        const char *end = strchr(style, ';'), *colon;
        size_t n = end ? (size_t)(end - style) : strlen(style);
        colon = memchr(style, ':', n);
        if (colon && !memchr(colon + 1, ':', n - (size_t)(colon + 1 - style)) &&
            (size_t)(colon - style) == name_len && memcmp(style, name, name_len) == 0) {
            *value = colon + 1;
            *len = n - (size_t)(colon + 1 - style);
            return true;
        }
        style = end ? end + 1 : NULL;
    }
    return false;
}

/* An attribute, else the style entry of that name (OpenSCAD's stroke settings). */
static bool stroke_setting(const char **atts, const char *name, const char **value, size_t *len)
{
    const char *v = attribute(atts, name), *style = attribute(atts, "style");
    if (v && *v) {
        *value = v;
        *len = strlen(v);
        return true;
    }
    return style && style_value(style, name, value, len);
}

static bool text_is(const char *s, size_t n, const char *word)
{
    return strlen(word) == n && memcmp(s, word, n) == 0;
}

typedef struct stroke_style {
    double width;
    mci_stroke_cap cap;
    mci_stroke_join join;
} stroke_style;

static stroke_style stroke_of(const char **atts)
{
    stroke_style s = {0, MCI_CAP_SQUARE, MCI_STROKE_MITER};
    const char *v;
    size_t n;
    if (stroke_setting(atts, "stroke-width", &v, &n))
        s.width = lenient_number(v, n);
    if (s.width < 0.01)
        s.width = 1;
    if (stroke_setting(atts, "stroke-linecap", &v, &n))
        s.cap = text_is(v, n, "butt") ? MCI_CAP_BUTT : text_is(v, n, "round") ? MCI_CAP_ROUND
                                                                               : MCI_CAP_SQUARE;
    if (stroke_setting(atts, "stroke-linejoin", &v, &n))
        s.join = text_is(v, n, "bevel")   ? MCI_STROKE_SQUARE
                 : text_is(v, n, "round") ? MCI_STROKE_ROUND
                                          : MCI_STROKE_MITER;
    return s;
}

/* ---------------------------------------------------------------------------------- */
/* Strokes */

/* The stroke of points [first, cur.n) of the current paths replaces them: its outline's
 * loops become paths of the shape. */
static void stroke_last(svg_reader *r, size_t first, const stroke_style *s)
{
    mci_outlines o = {0};
    mcsg_error err = {MCSG_OK, ""};
    size_t n = r->cur.n - first;
    mcsg_status st;
    if (r->status != MCSG_OK)
        return;
    st = mci_stroke_outline(r->ctx, r->cur.xy + 2 * first, n, s->width, s->cap, s->join,
                            MAX_POINTS - r->all.n - first, &o, &err);
    r->cur.n = first;
    r->cur.start[r->cur.count] = (uint32_t)first;
    if (st == MCSG_ERR_UNSUPPORTED)
        warn(r, "a stroke left out: %s", err.message);
    else if (st != MCSG_OK)
        fail(r, st, "%s", err.message);
    for (size_t k = 0; r->status == MCSG_OK && k < o.loop_count; k++) {
        new_path(r, &r->cur);
        for (uint32_t i = o.loop_start[k]; i < o.loop_start[k + 1]; i++)
            add_point(r, o.xy[2 * i], o.xy[2 * i + 1]);
        /* OpenSCAD closes each loop with its first point again */
        add_point(r, o.xy[2 * o.loop_start[k]], o.xy[2 * o.loop_start[k] + 1]);
    }
    mci_outlines_free(r->ctx, &o);
}

/* The last path, popped and stroked (its outline's loops take its place). */
static void stroke_last_path(svg_reader *r, const stroke_style *s)
{
    size_t first = r->cur.start[r->cur.count - 1];
    r->cur.count--; /* the path's own entry goes; its points are the stroke's input */
    r->cur.start[r->cur.count] = (uint32_t)r->cur.n;
    stroke_last(r, first, s);
}

/* ---------------------------------------------------------------------------------- */
/* Path data */

typedef struct path_state {
    svg_reader *r;
    const char **atts;
    double x, y, xx, yy, rx, ry, cx1, cy1, cx2, cy2, angle;
    bool large, sweep, last_cubic, last_quad, negate, closed;
    char cmd;
    int point;
    const char *exp; /* a held token ending in 'e' (with its sign), or NULL */
    size_t exp_len;
    bool exp_negative;
} path_state;

static const char PATH_COMMANDS[] = "-zmlcqahvstZMLCQAHVST";

static bool is_command(char c)
{
    return c != '\0' && strchr(PATH_COMMANDS, c) != NULL;
}

static double bernstein(double t, int exponent)
{
    return pow(1.0 - t, exponent);
}

static void quadratic_to(path_state *p, double x2, double y2)
{
    double x = p->x, y = p->y, cx1 = p->cx1, cy1 = p->cy1;
    for (unsigned long idx = 1; idx <= BEZIER_STEPS; ++idx) {
        double a = (double)idx * (1.0 / (double)BEZIER_STEPS);
        add_point(p->r, x * bernstein(a, 2) + cx1 * 2 * bernstein(a, 1) * a + x2 * a * a,
                  y * bernstein(a, 2) + cy1 * 2 * bernstein(a, 1) * a + y2 * a * a);
    }
}

static void cubic_to(path_state *p, double x2, double y2)
{
    double x = p->x, y = p->y, cx1 = p->cx1, cy1 = p->cy1, cx2 = p->cx2, cy2 = p->cy2;
    for (unsigned long idx = 1; idx <= BEZIER_STEPS; ++idx) {
        double a = (double)idx * (1.0 / (double)BEZIER_STEPS);
        add_point(p->r,
                  x * bernstein(a, 3) + cx1 * 3 * bernstein(a, 2) * a +
                      cx2 * 3 * bernstein(a, 1) * a * a + x2 * a * a * a,
                  y * bernstein(a, 3) + cy1 * 3 * bernstein(a, 2) * a +
                      cy2 * 3 * bernstein(a, 1) * a * a + y2 * a * a * a);
    }
}

static double vector_angle(double ux, double uy, double vx, double vy)
{
    double angle = mci_atan2_degrees(vy, vx) - mci_atan2_degrees(uy, ux);
    return angle < 0 ? angle + 360 : angle;
}

/* A double converted to int as x86-64 does (out of range and NaN: INT_MIN). */
static int to_int(double v)
{
    return v > -2147483649.0 && v < 2147483648.0 ? (int)v : -2147483647 - 1;
}

/* The SVG implementation notes' centre parametrisation (F.6.5), in OpenSCAD's steps. */
static void arc_to(path_state *p, double x2, double y2)
{
    double x1 = p->x, y1 = p->y, rx = p->rx, ry = p->ry;
    double cos_rad = mci_cos_degrees(p->angle), sin_rad = mci_sin_degrees(p->angle);
    double dx = (x1 - x2) / 2, dy = (y1 - y2) / 2;
    double x1_ = cos_rad * dx + sin_rad * dy, y1_ = -sin_rad * dx + cos_rad * dy;
    double d = (x1_ * x1_) / (rx * rx) + (y1_ * y1_) / (ry * ry), t1, t2, t3, cx_, cy_, cx, cy;
    double ux, uy, vx, vy, theta, delta;
    int steps;
    if (d > 1) {
        rx = fabs(sqrt(d) * rx);
        ry = fabs(sqrt(d) * ry);
    }
    t1 = rx * rx * ry * ry - rx * rx * y1_ * y1_ - ry * ry * x1_ * x1_;
    t2 = rx * rx * y1_ * y1_ + ry * ry * x1_ * x1_;
    if (t1 < 0)
        t1 = 0;
    t3 = sqrt(t1 / t2);
    if (p->large == p->sweep)
        t3 = -t3;
    cx_ = t3 * rx * y1_ / ry;
    cy_ = t3 * -ry * x1_ / rx;
    cx = cos_rad * cx_ - sin_rad * cy_ + (x1 + x2) / 2.0;
    cy = sin_rad * cx_ + cos_rad * cy_ + (y1 + y2) / 2.0;
    ux = (x1_ - cx_) / rx;
    uy = (y1_ - cy_) / ry;
    vx = (-x1_ - cx_) / rx;
    vy = (-y1_ - cy_) / ry;
    theta = vector_angle(1, 0, ux, uy);
    delta = vector_angle(ux, uy, vx, vy);
    if (!p->sweep)
        delta -= 360;
    steps = to_int(fabs(delta) * 10.0 / 180 + 4);
    for (int a = 0; a <= steps; ++a) {
        double phi = theta + delta * a / steps;
        double xx = cos_rad * mci_cos_degrees(phi) * rx - sin_rad * mci_sin_degrees(phi) * ry;
        double yy = sin_rad * mci_cos_degrees(phi) * rx + cos_rad * mci_sin_degrees(phi) * ry;
        add_point(p->r, xx + cx, yy + cy);
    }
}

/* OpenSCAD's is_open_path: the ends more than 0.1 apart. */
static bool last_path_open(const paths *c)
{
    const double *a = c->xy + 2 * (size_t)c->start[c->count - 1], *b = c->xy + 2 * (c->n - 1);
    return pow(pow(a[0] - b[0], 2) + pow(a[1] - b[1], 2) + pow(0.0 - 0.0, 2), 0.5) > 0.1;
}

static void move_to(path_state *p)
{
    svg_reader *r = p->r;
    if (last_path_size(&r->cur) > 0) {
        if (last_path_open(&r->cur)) {
            stroke_style s = stroke_of(p->atts);
            stroke_last_path(r, &s);
        }
        new_path(r, &r->cur);
    } else if (r->cur.count == 0) {
        new_path(r, &r->cur);
    }
    add_point(r, p->xx, p->yy);
    p->x = p->xx;
    p->y = p->yy;
}

static void close_path(path_state *p)
{
    paths *c = &p->r->cur;
    if (last_path_size(c) > 0) {
        size_t first = c->start[c->count - 1];
        double x = c->xy[2 * first], y = c->xy[2 * first + 1];
        add_point(p->r, x, y);
        p->x = x;
        p->y = y;
    }
    new_path(p->r, c);
    p->closed = true;
}

/* The end of a command's point: the current point moves, the Bézier memory is set. */
static void finish(path_state *p, bool cubic, bool quad)
{
    p->x = p->xx;
    p->y = p->yy;
    p->point = -1;
    p->last_cubic = cubic;
    p->last_quad = quad;
}

/* One number of the current command, by its position in the command's arguments. */
static void path_number(path_state *p, double v)
{
    bool rel = p->cmd >= 'a' && p->cmd <= 'z';
    switch (p->cmd | 32) {
    case 'a':
        switch (p->point) {
        case 0: p->rx = fabs(v); break;
        case 1: p->ry = fabs(v); break;
        case 2: p->angle = v; break;
        case 3: p->large = v > 0.5; break;
        case 4: p->sweep = v > 0.5; break;
        case 5: p->xx = rel ? p->x + v : v; break;
        case 6:
            p->yy = rel ? p->y + v : v;
            arc_to(p, p->xx, p->yy);
            finish(p, false, false);
            break;
        }
        break;
    case 'l':
        if (p->point == 0) {
            p->xx = rel ? p->x + v : v;
        } else if (p->point == 1) {
            p->yy = rel ? p->y + v : v;
            add_point(p->r, p->xx, p->yy);
            finish(p, false, false);
        }
        break;
    case 'c':
        switch (p->point) {
        case 0: p->cx1 = v; break;
        case 1: p->cy1 = v; break;
        case 2: p->cx2 = v; break;
        case 3: p->cy2 = v; break;
        case 4: p->xx = rel ? p->x + v : v; break;
        case 5:
            p->yy = rel ? p->y + v : v;
            if (rel) {
                p->cx1 += p->x, p->cy1 += p->y, p->cx2 += p->x, p->cy2 += p->y;
            }
            cubic_to(p, p->xx, p->yy);
            finish(p, true, false);
            break;
        }
        break;
    case 's':
        switch (p->point) {
        case 0:
            if (p->last_cubic) {
                p->cx1 = p->x + (p->x - p->cx2);
                p->cy1 = p->y + (p->y - p->cy2);
            } else {
                p->cx1 = p->x;
                p->cy1 = p->y;
            }
            p->cx2 = v;
            break;
        case 1: p->cy2 = v; break;
        case 2: p->xx = rel ? p->x + v : v; break;
        case 3:
            p->yy = rel ? p->y + v : v;
            if (rel) {
                p->cx2 += p->x, p->cy2 += p->y;
            }
            cubic_to(p, p->xx, p->yy);
            finish(p, true, false);
            break;
        }
        break;
    case 'q':
        switch (p->point) {
        case 0: p->cx1 = v; break;
        case 1: p->cy1 = v; break;
        case 2: p->xx = rel ? p->x + v : v; break;
        case 3:
            p->yy = rel ? p->y + v : v;
            if (rel) {
                p->cx1 += p->x, p->cy1 += p->y;
            }
            quadratic_to(p, p->xx, p->yy);
            finish(p, false, true);
            break;
        }
        break;
    case 't':
        if (p->point == 0) {
            if (p->last_quad) {
                p->cx1 = p->x + (p->x - p->cx1);
                p->cy1 = p->y + (p->y - p->cy1);
            } else {
                p->cx1 = p->x;
                p->cy1 = p->y;
            }
            p->xx = rel ? p->x + v : v;
        } else if (p->point == 1) {
            p->yy = rel ? p->y + v : v;
            quadratic_to(p, p->xx, p->yy);
            finish(p, false, true);
        }
        break;
    case 'm':
        if (p->point == 0) {
            p->xx = rel ? p->x + v : v;
        } else if (p->point == 1) {
            p->yy = rel ? p->y + v : v;
            p->cmd = rel ? 'l' : 'L';
            move_to(p);
            finish(p, false, false);
        }
        break;
    case 'v':
        if (p->point == 0) {
            p->y = rel ? p->y + v : v;
            add_point(p->r, p->x, p->y);
            p->point = -1;
            p->last_cubic = p->last_quad = false;
        }
        break;
    case 'h':
        if (p->point == 0) {
            p->x = rel ? p->x + v : v;
            add_point(p->r, p->x, p->y);
            p->point = -1;
            p->last_cubic = p->last_quad = false;
        }
        break;
    case 'z':
        close_path(p);
        p->last_cubic = p->last_quad = false;
        break;
    }
}

/* One token after OpenSCAD's splitting: a command, a sign, a held exponent start or a
 * number. */
static void path_token(path_state *p, const char *tok, size_t len)
{
    char buf[256];
    size_t used = 0;
    double v;
    if (len == 1 && is_command(tok[0])) {
        if (tok[0] == '-') {
            p->negate = true;
            return;
        }
        p->point = -1;
        p->cmd = tok[0];
        if ((p->cmd | 32) == 'z')
            path_number(p, 0);
        p->point++;
        return;
    }
    if (tok[len - 1] == 'e') {
        p->exp = tok;
        p->exp_len = len;
        p->exp_negative = p->negate;
        p->negate = false;
        return;
    }
    if (p->exp) {
        if (p->exp_len + len + 2 > sizeof buf) {
            fail(p->r, MCSG_ERR_PARSE, "<path> d: a number of more than %zu characters",
                 sizeof buf - 2);
            return;
        }
        if (p->exp_negative)
            buf[used++] = '-';
        memcpy(buf + used, p->exp, p->exp_len);
        used += p->exp_len;
        if (p->negate)
            buf[used++] = '-';
        memcpy(buf + used, tok, len);
        used += len;
        p->exp = NULL;
        if (!whole_number(buf, used, &v))
            fail(p->r, MCSG_ERR_PARSE, "<path> d: \"%.*s\" is not a number", (int)used, buf);
    } else {
        if (!whole_number(tok, len, &v))
            fail(p->r, MCSG_ERR_PARSE, "<path> d: \"%.*s\" is not a number",
                 (int)(len < 40 ? len : 40), tok);
        v = p->negate ? -v : v;
    }
    p->negate = false;
    if (p->r->status != MCSG_OK)
        return;
    path_number(p, v);
    p->point++;
}

/* A raw token split after every dot-separated part that follows a dot (OpenSCAD's
 * split_dots, for ",1-23.16.88"); text after the last such part is dropped as there. */
static void split_dots(path_state *p, const char *tok, size_t len)
{
    size_t dots = 0, text = 0, i = 0;
    bool dot_seen = false;
    for (size_t k = 0; k < len; k++)
        dots += tok[k] == '.';
    if (dots < 2) {
        path_token(p, tok, len);
        return;
    }
    while (i < len && p->r->status == MCSG_OK) {
        size_t j = i;
        if (tok[i] == '.') {
            dot_seen = true;
            i++;
            continue;
        }
        while (j < len && tok[j] != '.')
            j++;
        if (dot_seen) {
            path_token(p, tok + text, j - text);
            text = j;
        }
        i = j;
    }
}

static void read_path_data(svg_reader *r, const char **atts, const char *d)
{
    path_state p;
    memset(&p, 0, sizeof p);
    p.r = r;
    p.atts = atts;
    p.cmd = ' ';
    new_path(r, &r->cur);
    for (const char *s = d ? d : ""; *s && r->status == MCSG_OK;) {
        const char *t = s;
        if (*s == ' ' || *s == ',') {
            s++;
            continue;
        }
        if (is_command(*s)) {
            split_dots(&p, s++, 1);
            continue;
        }
        while (*t && *t != ' ' && *t != ',' && !is_command(*t))
            t++;
        split_dots(&p, s, (size_t)(t - s));
        s = t;
    }
    while (r->cur.count > 0 && last_path_size(&r->cur) == 0)
        r->cur.count--;
    if (r->status == MCSG_OK && !p.closed && r->cur.count > 0 && last_path_open(&r->cur)) {
        stroke_style s = stroke_of(atts);
        stroke_last_path(r, &s);
    }
}

/* ---------------------------------------------------------------------------------- */
/* Shapes */

/* "%g" with six significant digits, as OpenSCAD's boost::format prints the rounded
 * rectangle's path, whatever the C locale's decimal point. */
static size_t format_g6(char *out, double v)
{
    char buf[64], digits[8];
    int exponent, nd = 0;
    size_t n = 0;
    const char *e;
    if (isnan(v))
        return (size_t)sprintf(out, "%snan", signbit(v) ? "-" : "");
    if (isinf(v))
        return (size_t)sprintf(out, "%sinf", v < 0 ? "-" : "");
    snprintf(buf, sizeof buf, "%.5e", v);
    for (const char *c = buf; *c && *c != 'e' && nd < 6; c++)
        if (*c >= '0' && *c <= '9')
            digits[nd++] = *c;
    e = strchr(buf, 'e');
    exponent = e ? (int)strtol(e + 1, NULL, 10) : 0;
    while (nd > 1 && digits[nd - 1] == '0')
        nd--;
    if (buf[0] == '-')
        out[n++] = '-';
    if (exponent < -4 || exponent >= 6) {
        out[n++] = digits[0];
        if (nd > 1)
            out[n++] = '.';
        for (int i = 1; i < nd; i++)
            out[n++] = digits[i];
        n += (size_t)sprintf(out + n, "e%c%02d", exponent < 0 ? '-' : '+', abs(exponent));
    } else if (exponent < 0) {
        out[n++] = '0';
        out[n++] = '.';
        for (int i = -1; i > exponent; i--)
            out[n++] = '0';
        for (int i = 0; i < nd; i++)
            out[n++] = digits[i];
    } else {
        for (int i = 0; i <= exponent; i++)
            out[n++] = i < nd ? digits[i] : '0';
        if (nd > exponent + 1)
            out[n++] = '.';
        for (int i = exponent + 1; i < nd; i++)
            out[n++] = digits[i];
    }
    out[n] = '\0';
    return n;
}

static void rounded_rect(svg_reader *r, const char **atts, double x, double y, double w,
                         double h, double rx, double ry)
{
    const double v[] = {x + rx, y, x + w - rx, rx, ry, x + w, y + ry, y + h - ry, rx, ry,
                        x + w - rx, y + h, x + rx, rx, ry, x, y + h - ry, y + ry, rx, ry,
                        x + rx, y};
    static const char *const fmt[] = {"M ", ",", " H ", " A ", ",", " 0 0,1 ", ",", " V ",
                                      " A ", ",", " 0 0,1 ", ",", " H ", " A ", ",",
                                      " 0 0,1 ", ",", " V ", " A ", ",", " 0 0,1 ", ","};
    char d[22 * 40 + 8];
    size_t n = 0;
    for (size_t i = 0; i < sizeof v / sizeof *v; i++) {
        n += (size_t)sprintf(d + n, "%s", fmt[i]);
        n += format_g6(d + n, v[i]);
    }
    strcpy(d + n, " z");
    read_path_data(r, atts, d);
}

static void rect_shape(svg_reader *r, const char **atts)
{
    double x = number_attr(r, atts, "rect", "x"), y = number_attr(r, atts, "rect", "y");
    double w = number_attr(r, atts, "rect", "width"), h = number_attr(r, atts, "rect", "height");
    double rx = number_attr(r, atts, "rect", "rx"), ry = number_attr(r, atts, "rect", "ry");
    bool has_rx = !(fabs(rx) < 1e-8), has_ry = !(fabs(ry) < 1e-8);
    if (r->status != MCSG_OK)
        return;
    if (has_rx || has_ry) {
        if (!has_rx)
            rx = ry;
        else if (!has_ry)
            ry = rx;
        if (rx > w / 2)
            rx = w / 2;
        if (ry > h / 2)
            ry = h / 2;
        rounded_rect(r, atts, x, y, w, h, rx, ry);
        return;
    }
    new_path(r, &r->cur);
    add_point(r, x, y);
    add_point(r, x + w, y);
    add_point(r, x + w, y + h);
    add_point(r, x, y + h);
    add_point(r, x, y);
}

static void ellipse_shape(svg_reader *r, const char **atts, const char *element)
{
    double cx = number_attr(r, atts, element, "cx"), cy = number_attr(r, atts, element, "cy");
    double rx, ry;
    if (element[0] == 'c') {
        rx = ry = number_attr(r, atts, element, "r");
    } else {
        rx = number_attr(r, atts, element, "rx");
        ry = number_attr(r, atts, element, "ry");
    }
    new_path(r, &r->cur);
    for (unsigned long idx = 1; idx <= ELLIPSE_STEPS && r->status == MCSG_OK; ++idx) {
        double a = (double)idx * 360.0 / (double)ELLIPSE_STEPS;
        add_point(r, rx * mci_sin_degrees(a) + cx, ry * mci_cos_degrees(a) + cy);
    }
}

/* polygon and polyline: numbers split at spaces and commas, taken in pairs. */
static void point_list(svg_reader *r, const char **atts, const char *element)
{
    const char *s = attribute(atts, "points");
    double x = 0;
    bool first = true;
    new_path(r, &r->cur);
    while (s && *s && r->status == MCSG_OK) {
        const char *t = s;
        double v;
        if (*s == ' ' || *s == ',') {
            s++;
            continue;
        }
        while (*t && *t != ' ' && *t != ',')
            t++;
        if (!whole_number(s, (size_t)(t - s), &v))
            fail(r, MCSG_ERR_PARSE, "<%s> points: \"%.*s\" is not a number", element,
                 (int)(t - s < 40 ? t - s : 40), s);
        else if (first)
            x = v;
        else
            add_point(r, x, v);
        first = !first;
        s = t;
    }
}

static void line_shape(svg_reader *r, const char **atts)
{
    double x1 = number_attr(r, atts, "line", "x1"), y1 = number_attr(r, atts, "line", "y1");
    double x2 = number_attr(r, atts, "line", "x2"), y2 = number_attr(r, atts, "line", "y2");
    stroke_style s = stroke_of(atts);
    new_path(r, &r->cur);
    add_point(r, x1, y1);
    add_point(r, x2, y2);
    if (r->status == MCSG_OK)
        stroke_last_path(r, &s);
}

/* The current shape's paths from its element (OpenSCAD's set_attrs). */
static void shape_paths(svg_reader *r, const char *name, const char **atts)
{
    if (strcmp(name, "rect") == 0) {
        rect_shape(r, atts);
    } else if (strcmp(name, "circle") == 0 || strcmp(name, "ellipse") == 0) {
        ellipse_shape(r, atts, name);
    } else if (strcmp(name, "line") == 0) {
        line_shape(r, atts);
    } else if (strcmp(name, "polygon") == 0) {
        point_list(r, atts, name);
        if (r->status == MCSG_OK && last_path_size(&r->cur) > 0)
            add_point(r, r->cur.xy[0], r->cur.xy[1]);
    } else if (strcmp(name, "polyline") == 0) {
        stroke_style s = stroke_of(atts);
        point_list(r, atts, name);
        if (r->status == MCSG_OK && last_path_size(&r->cur) > 0)
            stroke_last_path(r, &s);
    } else if (strcmp(name, "path") == 0) {
        read_path_data(r, atts, attribute(atts, "d"));
    }
}

/* ---------------------------------------------------------------------------------- */
/* Transforms */

static void add_matrix(svg_reader *r, const double m[6])
{
    if (r->mat_count >= MAX_MATRICES) {
        fail(r, MCSG_ERR_LIMIT, "more than %d transforms in force", MAX_MATRICES);
        return;
    }
    if (!mci_grow_array(r->ctx, (void **)&r->mats, &r->mat_cap, 6 * (r->mat_count + 1),
                        sizeof *r->mats, 96)) {
        nomem(r);
        return;
    }
    memcpy(r->mats + 6 * r->mat_count++, m, 6 * sizeof *m);
}

/* One transform's matrices, in the order they apply (OpenSCAD's get_matrices). */
static void transform_matrices(svg_reader *r, char op, const double *a, size_t n)
{
    static const char *const names[] = {"matrix", "translate", "scale", "rotate", "skew_x",
                                        "skew_y"};
    const char *ops = "mtsrxy";
    int kind = (int)(strchr(ops, op) - ops);
    bool ok = kind == 0 ? n == 6 : kind == 1 || kind == 2 ? n == 1 || n == 2
                                : kind == 3 ? n == 1 || n == 3 : n == 1;
    if (!ok) {
        warn(r, "invalid arguments for %s", names[kind]);
        return;
    }
    switch (kind) {
    case 0: add_matrix(r, (double[6]){a[0], a[2], a[4], a[1], a[3], a[5]}); break;
    case 1: add_matrix(r, (double[6]){1, 0, a[0], 0, 1, n > 1 ? a[1] : 0}); break;
    case 2: add_matrix(r, (double[6]){a[0], 0, 0, 0, n > 1 ? a[1] : a[0], 0}); break;
    case 3: {
        double s = mci_sin_degrees(a[0]), c = mci_cos_degrees(a[0]);
        if (n == 3)
            add_matrix(r, (double[6]){1, 0, -a[1], 0, 1, -a[2]});
        add_matrix(r, (double[6]){c, -s, 0, s, c, 0});
        if (n == 3)
            add_matrix(r, (double[6]){1, 0, a[1], 0, 1, a[2]});
        break;
    }
    case 4: add_matrix(r, (double[6]){1, mci_tan_degrees(a[0]), 0, 0, 1, 0}); break;
    default: add_matrix(r, (double[6]){1, 0, 0, mci_tan_degrees(a[0]), 1, 0}); break;
    }
}

/* The transform text with OpenSCAD's word replacements, in place. */
static void replace_words(char *s)
{
    static const char *const words[][2] = {{"matrix", "m"}, {"translate", "t"},
                                           {"scale", "s"},  {"rotate", "r"},
                                           {"skewX", "x"},  {"skewY", "y"}};
    for (size_t w = 0; w < 6; w++) {
        size_t len = strlen(words[w][0]);
        char *in = s, *out = s;
        while (*in) {
            if (strncmp(in, words[w][0], len) == 0) {
                *out++ = words[w][1][0];
                in += len;
            } else {
                *out++ = *in++;
            }
        }
        *out = '\0';
    }
}

typedef struct transform_op {
    char op;
    double args[8];
    size_t n;
} transform_op;

/* The element's transforms as matrices in r->mats, the last transform's first. */
static void read_transform(svg_reader *r, const char *text)
{
    char *s;
    transform_op *ops = NULL;
    size_t count = 0, cap = 0, len = text ? strlen(text) : 0;
    if (!len)
        return;
    if (!(s = mci_malloc(r->ctx, len + 1))) {
        nomem(r);
        return;
    }
    memcpy(s, text, len + 1);
    replace_words(s);
    for (char *c = s; *c && r->status == MCSG_OK;) {
        char *t = c;
        if (strchr(" ,()", *c)) {
            c++;
            continue;
        }
        if (strchr("mtsrxy", *c)) {
            if (!mci_grow_array(r->ctx, (void **)&ops, &cap, count + 1, sizeof *ops, 4))
                nomem(r);
            else
                ops[count++] = (transform_op){*c++, {0}, 0};
            continue;
        }
        while (*t && !strchr(" ,()mtsrxy", *t))
            t++;
        if (count > 0) {
            double v;
            transform_op *op = &ops[count - 1];
            if (!whole_number(c, (size_t)(t - c), &v))
                fail(r, MCSG_ERR_PARSE, "transform: \"%.*s\" is not a number",
                     (int)(t - c < 40 ? t - c : 40), c);
            else if (op->n < 8)
                op->args[op->n] = v;
            op->n++;
        }
        c = t;
    }
    for (size_t k = count; k-- > 0 && r->status == MCSG_OK;)
        transform_matrices(r, ops[k].op, ops[k].args, ops[k].n);
    mci_free(r->ctx, ops);
    mci_free(r->ctx, s);
}

static void apply(const double *m, double *x, double *y)
{
    double px = *x, py = *y;
    *x = m[0] * px + m[1] * py + m[2] * 1.0;
    *y = m[3] * px + m[4] * py + m[5] * 1.0;
}

/* The shape's points through its own matrices [own, mat_count), then its containers'
 * (innermost first), but not the outermost container's; none without a container. */
static void transform_shape(svg_reader *r, size_t own)
{
    if (r->depth == 0)
        return;
    for (size_t i = 0; i < r->cur.n; i++) {
        double *x = &r->cur.xy[2 * i], *y = &r->cur.xy[2 * i + 1];
        for (size_t m = own; m < r->mat_count; m++)
            apply(r->mats + 6 * m, x, y);
        for (size_t c = r->depth; c-- > 1;)
            for (size_t m = r->stack[c].mat_begin; m < r->stack[c].mat_end; m++)
                apply(r->mats + 6 * m, x, y);
    }
}

/* ---------------------------------------------------------------------------------- */
/* The page */

typedef enum unit_kind {
    UNIT_UNDEFINED, UNIT_NONE, UNIT_PERCENT, UNIT_EM, UNIT_EX, UNIT_PX, UNIT_IN, UNIT_CM,
    UNIT_MM, UNIT_PT, UNIT_PC
} unit_kind;

static const char *skip_space(const char *s)
{
    while (*s && is_space(*s))
        s++;
    return s;
}

/* A number at s (OpenSCAD's qi::double_), its end in *next. */
static bool lead_number(const char *s, double *v, const char **next)
{
    return mci_parse_double(s, s + strlen(s), v, next);
}

/* OpenSCAD's parse_length: a number and an optional unit, spaces around. */
static unit_kind parse_length(const char *text, double *number)
{
    static const char *const units[] = {"em", "ex", "px", "in", "cm", "mm", "pt", "pc", "%"};
    static const unit_kind kinds[] = {UNIT_EM, UNIT_EX, UNIT_PX, UNIT_IN, UNIT_CM,
                                      UNIT_MM, UNIT_PT, UNIT_PC, UNIT_PERCENT};
    const char *s = skip_space(text ? text : ""), *next;
    unit_kind unit = UNIT_NONE;
    *number = 0;
    if (!lead_number(s, number, &next)) {
        *number = 0;
        return UNIT_UNDEFINED;
    }
    s = skip_space(next);
    for (size_t i = 0; i < 9; i++)
        if (strncmp(s, units[i], strlen(units[i])) == 0) {
            unit = kinds[i];
            s = skip_space(s + strlen(units[i]));
            break;
        }
    if (*s) {
        *number = 0;
        return UNIT_UNDEFINED;
    }
    return unit;
}

/* OpenSCAD's parse_viewbox: four numbers, each pair perhaps separated by one comma;
 * valid when the width and height are not negative. */
static bool parse_viewbox(const char *text, double vb[4])
{
    const char *s = skip_space(text ? text : ""), *next;
    for (int i = 0; i < 4; i++) {
        if (i > 0 && *s == ',')
            s = skip_space(s + 1);
        if (!lead_number(s, &vb[i], &next))
            return false;
        s = skip_space(next);
    }
    return *s == '\0' && vb[2] >= 0.0 && vb[3] >= 0.0;
}

/* OpenSCAD's parse_alignment: [defer] align [meet | slice]; MID and meet otherwise. */
static void parse_alignment(const char *text, align_kind al[2], bool *meet)
{
    static const char *const names[] = {"none",     "xMinYMin", "xMidYMin", "xMaxYMin",
                                        "xMinYMid", "xMidYMid", "xMaxYMid", "xMinYMax",
                                        "xMidYMax", "xMaxYMax"};
    const char *s = skip_space(text ? text : "");
    int found = -1;
    al[0] = al[1] = ALIGN_MID;
    *meet = true;
    if (strncmp(s, "defer", 5) == 0)
        s = skip_space(s + 5);
    for (int i = 0; i < 10 && found < 0; i++)
        if (strncmp(s, names[i], strlen(names[i])) == 0) {
            found = i;
            s = skip_space(s + strlen(names[i]));
        }
    if (found < 0)
        return;
    {
        bool m = true;
        if (strncmp(s, "meet", 4) == 0) {
            s = skip_space(s + 4);
        } else if (strncmp(s, "slice", 5) == 0) {
            m = false;
            s = skip_space(s + 5);
        }
        if (*s)
            return;
        *meet = m;
    }
    if (found == 0) {
        al[0] = al[1] = ALIGN_NONE;
    } else {
        al[0] = (align_kind)(ALIGN_MIN + (found - 1) % 3);
        al[1] = (align_kind)(ALIGN_MIN + (found - 1) / 3);
    }
}

static double to_mm(unit_kind unit, double number, double viewbox, bool viewbox_valid,
                    double dpi)
{
    switch (unit) {
    case UNIT_NONE: return INCH_TO_MM * number / dpi;
    case UNIT_PX: return INCH_TO_MM * number / 96.0;
    case UNIT_PT: return INCH_TO_MM * number / 72.0;
    case UNIT_PC: return INCH_TO_MM * number / 6.0;
    case UNIT_IN: return INCH_TO_MM * number;
    case UNIT_CM: return 10 * number;
    case UNIT_MM: return number;
    case UNIT_UNDEFINED: return viewbox_valid ? INCH_TO_MM * viewbox / dpi : 0.0;
    default: return viewbox_valid ? viewbox : 0.0;
    }
}

static double alignment_offset(align_kind a, double page_mm, double scale, double viewbox)
{
    return a == ALIGN_MID ? page_mm / 2.0 - scale * viewbox / 2.0
           : a == ALIGN_MAX ? page_mm - scale * viewbox
                            : 0.0;
}

/* An svg element: the page for everything (import_svg's loop over the pages). */
static void read_page(svg_reader *r, const char **atts)
{
    double w, h, vb[4] = {0, 0, 0, 0}, width_mm;
    unit_kind wu = parse_length(attribute(atts, "width"), &w);
    unit_kind hu = parse_length(attribute(atts, "height"), &h);
    bool valid = parse_viewbox(attribute(atts, "viewBox"), vb), meet;
    align_kind al[2];
    parse_alignment(attribute(atts, "preserveAspectRatio"), al, &meet);
    if (!valid)
        vb[2] = vb[3] = 0;
    width_mm = to_mm(wu, w, vb[2], valid, r->dpi);
    r->height_mm = to_mm(hu, h, vb[3], valid, r->dpi);
    if (!valid)
        return;
    r->viewbox[0] = vb[0];
    r->viewbox[1] = vb[1];
    r->scale[0] = width_mm / vb[2];
    r->scale[1] = r->height_mm / vb[3];
    if (al[0] != ALIGN_NONE) {
        double s = meet ? (r->scale[0] < r->scale[1] ? r->scale[0] : r->scale[1])
                        : (r->scale[0] > r->scale[1] ? r->scale[0] : r->scale[1]);
        r->scale[0] = r->scale[1] = s;
        r->align[0] = alignment_offset(al[0], width_mm, s, vb[2]);
        r->align[1] = alignment_offset(al[1], r->height_mm, s, vb[3]);
    }
}

/* ---------------------------------------------------------------------------------- */
/* Elements */

/* The current shape's points join the drawing: the centring box grows by them (at the
 * scale in force now), and its paths become the next shape. */
static void finish_shape(svg_reader *r)
{
    paths *c = &r->cur, *a = &r->all;
    uint32_t line = (uint32_t)XML_GetCurrentLineNumber(r->parser);
    for (size_t i = 0; i < c->n; i++) {
        double x = r->scale[0] * c->xy[2 * i], y = r->scale[1] * c->xy[2 * i + 1];
        if (!isfinite(x) || !isfinite(y))
            continue;
        r->box_min[0] = r->box_empty || x < r->box_min[0] ? x : r->box_min[0];
        r->box_max[0] = r->box_empty || x > r->box_max[0] ? x : r->box_max[0];
        r->box_min[1] = r->box_empty || y < r->box_min[1] ? y : r->box_min[1];
        r->box_max[1] = r->box_empty || y > r->box_max[1] ? y : r->box_max[1];
        r->box_empty = false;
    }
    if (c->n == 0)
        return;
    if (!mci_grow_array(r->ctx, (void **)&r->shape_start, &r->shape_cap, r->shape_count + 2,
                        sizeof *r->shape_start, 16) ||
        !mci_grow_array(r->ctx, (void **)&r->shape_line, &r->line_cap, r->shape_count + 1,
                        sizeof *r->shape_line, 16)) {
        nomem(r);
        return;
    }
    r->shape_start[r->shape_count] = (uint32_t)a->count;
    r->shape_line[r->shape_count++] = line;
    for (size_t k = 0; k < c->count && r->status == MCSG_OK; k++) {
        size_t first = c->start[k], end = k + 1 < c->count ? c->start[k + 1] : c->n;
        if (end == first)
            continue;
        new_path(r, a);
        if (r->status == MCSG_OK && paths_room(r, a, end - first)) {
            memcpy(a->xy + 2 * a->n, c->xy + 2 * first, 2 * (end - first) * sizeof *a->xy);
            a->n += end - first;
            a->start[a->count] = (uint32_t)a->n;
        }
    }
    r->shape_start[r->shape_count] = (uint32_t)a->count;
}

static bool is_container(const char *name)
{
    return strcmp(name, "svg") == 0 || strcmp(name, "g") == 0 || strcmp(name, "text") == 0 ||
           strcmp(name, "tspan") == 0;
}

static bool is_shape(const char *name)
{
    static const char *const names[] = {"circle", "ellipse", "line", "polygon", "polyline",
                                        "rect",   "path",    "data"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++)
        if (strcmp(name, names[i]) == 0)
            return true;
    return is_container(name);
}

static void XMLCALL element_start(void *user, const XML_Char *name, const XML_Char **atts)
{
    svg_reader *r = user;
    size_t own = r->mat_count;
    bool page = strcmp(name, "svg") == 0;
    if (r->status != MCSG_OK)
        return;
    if (strcmp(name, "defs") == 0)
        r->in_defs = true;
    if (r->in_defs || !is_shape(name))
        return;
    r->cur.n = r->cur.count = 0;
    if (page)
        read_page(r, atts);
    else
        read_transform(r, attribute(atts, "transform"));
    if (!page && !is_container(name))
        shape_paths(r, name, atts);
    transform_shape(r, own);
    if (r->status == MCSG_OK)
        finish_shape(r);
    if (r->status != MCSG_OK || !is_container(name)) {
        r->mat_count = own;
        return;
    }
    if (r->depth >= MAX_DEPTH) {
        fail(r, MCSG_ERR_LIMIT, "containers nested more than %d deep", MAX_DEPTH);
        return;
    }
    if (!mci_grow_array(r->ctx, (void **)&r->stack, &r->stack_cap, r->depth + 1,
                        sizeof *r->stack, 16)) {
        nomem(r);
        return;
    }
    r->stack[r->depth++] = (container){own, r->mat_count};
}

static void XMLCALL element_end(void *user, const XML_Char *name)
{
    svg_reader *r = user;
    if (r->status != MCSG_OK)
        return;
    if (strcmp(name, "defs") == 0)
        r->in_defs = false;
    if (r->in_defs)
        return;
    if ((strcmp(name, "g") == 0 || strcmp(name, "text") == 0 || strcmp(name, "tspan") == 0) &&
        r->depth > 0)
        r->mat_count = r->stack[--r->depth].mat_begin;
}

/* ---------------------------------------------------------------------------------- */
/* Placement on Clipper's grid, and the entry points */

typedef struct placed {
    size_t n;       /* the loop's points on the grid, repeats dropped */
    bool out_of_range;
} placed;

/* Clipper's DistanceFromLineSqrd: the squared distance of p from the line a b. */
static double line_distance2(const int64_t *p, const int64_t *a, const int64_t *b)
{
    double A = (double)(a[1] - b[1]), B = (double)(b[0] - a[0]);
    double C = A * (double)a[0] + B * (double)a[1];
    C = A * (double)p[0] + B * (double)p[1] - C;
    return (C * C) / (A * A + B * B);
}

/* Clipper's SlopesNearCollinear, measured from the point that lies between the others. */
static bool near_collinear(const int64_t *p1, const int64_t *p2, const int64_t *p3, double d2)
{
    int k = llabs(p1[0] - p2[0]) > llabs(p1[1] - p2[1]) ? 0 : 1;
    if ((p1[k] > p2[k]) == (p1[k] < p3[k]))
        return line_distance2(p1, p2, p3) < d2;
    if ((p2[k] > p1[k]) == (p2[k] < p3[k]))
        return line_distance2(p2, p1, p3) < d2;
    return line_distance2(p3, p1, p2) < d2;
}

static bool points_close(const int64_t *a, const int64_t *b, double d2)
{
    double dx = (double)a[0] - (double)b[0], dy = (double)a[1] - (double)b[1];
    return dx * dx + dy * dy <= d2;
}

/* Clipper's CleanPolygon (distance 1.415, as OpenSCAD's toPolygon2d calls it) on the n
 * grid points g: points closer than that to their neighbour or to the line through
 * their neighbours go; the rest, from where the cleaning stopped, into out (in
 * millimetres). `link` has room for 3 n entries. Returns the count left (0 when fewer
 * than 3). */
static size_t clean_polygon(const int64_t *g, size_t n, size_t *link, double *out)
{
    size_t *next = link, *prev = link + n, *done = link + 2 * n, op = 0, size = n;
    const double d2 = 1.415 * 1.415;
    for (size_t i = 0; i < n; i++) {
        next[i] = (i + 1) % n;
        prev[(i + 1) % n] = i;
        done[i] = 0;
    }
    while (!done[op] && next[op] != prev[op]) {
        size_t pr = prev[op], nx = next[op];
        if (points_close(g + 2 * op, g + 2 * pr, d2)) {
            next[pr] = nx, prev[nx] = pr, done[pr] = 0, op = pr, size--;
        } else if (points_close(g + 2 * pr, g + 2 * nx, d2)) {
            size_t nn = next[nx];
            next[op] = nn, prev[nn] = op, done[op] = 0;
            next[pr] = nn, prev[nn] = pr, done[pr] = 0, op = pr, size -= 2;
        } else if (near_collinear(g + 2 * pr, g + 2 * op, g + 2 * nx, d2)) {
            next[pr] = nx, prev[nx] = pr, done[pr] = 0, op = pr, size--;
        } else {
            done[op] = 1;
            op = nx;
        }
    }
    if (size < 3)
        return 0;
    for (size_t i = 0; i < size; i++, op = next[op]) {
        out[2 * i] = (double)g[2 * op] / CLIPPER_SCALE;
        out[2 * i + 1] = (double)g[2 * op + 1] / CLIPPER_SCALE;
    }
    return size;
}

/* Loop k of the drawing placed on the page, truncated to 2^-16 (Clipper's grid units
 * into g, room for the loop's points), repeats dropped. */
static void place_loop(const svg_reader *r, size_t k, double cx, double cy, int64_t *g,
                       placed *p)
{
    const paths *a = &r->all;
    size_t first = a->start[k], end = a->start[k + 1];
    p->n = 0;
    p->out_of_range = false;
    for (size_t i = first; i < end; i++) {
        double x = r->scale[0] * (-r->viewbox[0] + a->xy[2 * i]) - cx;
        double y = r->scale[1] * (-r->viewbox[1] - a->xy[2 * i + 1]) + cy;
        double gx = x * CLIPPER_SCALE, gy = y * CLIPPER_SCALE;
        if (!(fabs(gx) < CLIPPER_RANGE && fabs(gy) < CLIPPER_RANGE)) {
            p->out_of_range = end - first >= 3;
            p->n = 0;
            return;
        }
        if (p->n > 0 && g[2 * p->n - 2] == (int64_t)gx && g[2 * p->n - 1] == (int64_t)gy)
            continue;
        g[2 * p->n] = (int64_t)gx;
        g[2 * p->n++ + 1] = (int64_t)gy;
    }
    while (p->n > 1 && g[2 * p->n - 2] == g[0] && g[2 * p->n - 1] == g[1])
        p->n--;
}

static mcsg_status place(const svg_reader *r, mci_svg *out, mcsg_error *err)
{
    const paths *a = &r->all;
    double cx = r->center ? (r->box_min[0] + r->box_max[0]) / 2 : -r->align[0];
    double cy = r->center ? (r->box_min[1] + r->box_max[1]) / 2 : r->height_mm - r->align[1];
    mci_outlines *o = &out->outlines;
    placed p = {0};
    size_t longest = 0, *link;
    int64_t *g;
    for (size_t k = 0; k < a->count; k++)
        longest = a->start[k + 1] - a->start[k] > longest ? a->start[k + 1] - a->start[k] : longest;
    g = mci_malloc_array(r->ctx, 2 * longest + 2, sizeof *g);
    link = mci_malloc_array(r->ctx, 3 * longest + 3, sizeof *link);
    if (r->center && r->box_empty)
        cx = cy = 0;
    o->xy = mci_malloc_array(r->ctx, a->n + 1, 2 * sizeof *o->xy);
    o->loop_start = mci_calloc_array(r->ctx, a->count + 1, sizeof *o->loop_start);
    out->shape_start = mci_calloc_array(r->ctx, r->shape_count + 1, sizeof *out->shape_start);
    out->shape_line = mci_calloc_array(r->ctx, r->shape_count + 1, sizeof *out->shape_line);
    if (!o->xy || !o->loop_start || !out->shape_start || !out->shape_line || !g || !link) {
        mci_svg_free(r->ctx, out);
        mci_free(r->ctx, g);
        mci_free(r->ctx, link);
        return mci_fail_nomem(err, "reading an SVG file");
    }
    for (size_t s = 0; s < r->shape_count; s++) {
        size_t before = o->loop_count;
        for (size_t k = r->shape_start[s]; k < r->shape_start[s + 1]; k++) {
            place_loop(r, k, cx, cy, g, &p);
            if (p.out_of_range) {
                mci_log(r->ctx, MCSG_LOG_WARNING, "%s:%u: Range check failed for polygon. "
                        "skipping", r->name, (unsigned)r->shape_line[s]);
                break;
            }
            if (p.n < 3 || (p.n = clean_polygon(g, p.n, link, o->xy + 2 * o->point_count)) < 3)
                continue;
            o->point_count += p.n;
            o->loop_start[++o->loop_count] = (uint32_t)o->point_count;
        }
        if (o->loop_count > before) {
            out->shape_line[out->shape_count] = r->shape_line[s];
            out->shape_start[++out->shape_count] = (uint32_t)o->loop_count;
        }
    }
    mci_free(r->ctx, g);
    mci_free(r->ctx, link);
    return MCSG_OK;
}

static void free_paths(const mci_ctx *ctx, paths *p)
{
    mci_free(ctx, p->xy);
    mci_free(ctx, p->start);
    memset(p, 0, sizeof *p);
}

void mci_svg_free(const mci_ctx *ctx, mci_svg *svg)
{
    if (!svg)
        return;
    mci_outlines_free(ctx, &svg->outlines);
    mci_free(ctx, svg->shape_start);
    mci_free(ctx, svg->shape_line);
    memset(svg, 0, sizeof *svg);
}

static void free_reader(svg_reader *r)
{
    free_paths(r->ctx, &r->cur);
    free_paths(r->ctx, &r->all);
    mci_free(r->ctx, r->stack);
    mci_free(r->ctx, r->mats);
    mci_free(r->ctx, r->shape_start);
    mci_free(r->ctx, r->shape_line);
}

mcsg_status mci_svg_read_memory(const mci_ctx *ctx, const char *data, size_t size,
                                const char *name, double dpi, bool center, mci_svg *out,
                                mcsg_error *err)
{
    svg_reader r;
    mcsg_status st;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_svg_read_memory: NULL output");
    memset(out, 0, sizeof *out);
    if (!data && size > 0)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_svg_read_memory: NULL data");
    memset(&r, 0, sizeof r);
    r.ctx = ctx;
    r.name = name ? name : "<memory>";
    r.err = err;
    r.dpi = dpi;
    r.center = center;
    r.scale[0] = r.scale[1] = 1;
    r.box_empty = true;
    if (size > INT32_MAX)
        return mci_fail(err, MCSG_ERR_LIMIT, "%s: larger than 2 GiB", r.name);
    r.parser = XML_ParserCreate(NULL);
    if (!r.parser)
        return mci_fail_nomem(err, "reading an SVG file");
    XML_SetUserData(r.parser, &r);
    XML_SetElementHandler(r.parser, element_start, element_end);
    if (XML_Parse(r.parser, data ? data : "", (int)size, 1) != XML_STATUS_OK &&
        r.status == MCSG_OK)
        fail(&r, MCSG_ERR_PARSE, "malformed XML: %s",
             XML_ErrorString(XML_GetErrorCode(r.parser)));
    st = r.status;
    if (st == MCSG_OK)
        st = place(&r, out, err);
    XML_ParserFree(r.parser);
    free_reader(&r);
    return st;
}

mcsg_status mci_svg_read(const mci_ctx *ctx, const char *path, double dpi, bool center,
                         mci_svg *out, mcsg_error *err)
{
    unsigned char *data;
    size_t size;
    mcsg_status st;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_svg_read: NULL output");
    memset(out, 0, sizeof *out);
    if (!path)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_svg_read: NULL path");
    st = mci_read_file(ctx, path, &data, &size, err);
    if (st != MCSG_OK)
        return st;
    st = mci_svg_read_memory(ctx, (const char *)data, size, path, dpi, center, out, err);
    mci_free(ctx, data);
    return st;
}
