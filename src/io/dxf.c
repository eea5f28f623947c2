/*
 * DXF drawings as OpenSCAD 2021.01 reads them for import() (its DxfData constructor, on
 * its grid of 1/1024). The file is a list of pairs of lines, a group code and a value,
 * each trimmed of white space. An entity starts at group code 0 and is turned into line
 * segments when the next group code 0 arrives, so the last entity before the end of the
 * file is dropped, as OpenSCAD drops it. What OpenSCAD does, step by step:
 *
 *  - Group codes 10 and 11 append an x, 20 and 21 a y, as (value - origin) * scale (the
 *    values as they are inside the BLOCKS section); 40 is a radius (scaled outside
 *    BLOCKS), 41, 42, 50, 51 angles or scales, 70 flags, 2 a name, 8 the layer. Each
 *    number read is checked whatever the entity, as OpenSCAD parses it whatever the
 *    entity; codes 12 to 16 and 22 to 26 are parsed too.
 *  - LINE: its two points. LWPOLYLINE: consecutive points, closed when flag 1 is set
 *    (bulges ignored). CIRCLE: n = get_fragments_from_r(r, fn, fs, fa) segments from
 *    360 i / n degrees (OpenSCAD's degree trigonometry). ARC: the end angle increased by
 *    360 until not below the start, then ceil(n * sweep / 360) segments. ELLIPSE: the
 *    major axis (its x and y taken with the origin subtracted, as OpenSCAD does), the
 *    ratio (scaled, as OpenSCAD does), parameters in radians, ceil(n * sweep / 2 pi)
 *    segments by the C library's sin and cos. INSERT: each segment of the named block,
 *    its points' x and y multiplied by the scales 41 and 42, turned by 50 degrees,
 *    multiplied by `scale` and moved to the insertion point.
 *  - Segments count only inside the ENTITIES section (on the chosen layer) and inside
 *    BLOCKS (into the current block, every layer). Each end is snapped to the grid: to
 *    the nearest cell of 1/1024, or when that cell holds no point yet, to an occupied
 *    neighbour (edge neighbours first, then corners, in OpenSCAD's scan order). Each
 *    cell lists the segments ending there, by their number among the ENTITIES segments
 *    (a BLOCKS segment is listed under the number the next ENTITIES segment will take:
 *    OpenSCAD's quirk, kept; numbers no segment takes are ignored).
 *  - Paths: first open ones, each from the lowest-numbered segment with an end whose
 *    cell lists no other segment still unused (its first end if that is free), then
 *    closed ones, each from the lowest unused segment's first end; a path goes on
 *    through the first unused segment listed at its current end that ends in that cell.
 *    (OpenSCAD scans all segments again for each open path; here each cell counts the
 *    unused segments it lists, and a heap holds the segments that may have a free end:
 *    the same paths in the same order, without the quadratic time.)
 *  - When no path is open, each closed path is reversed if at its leftmost point (the
 *    first of them) atan2 of the neighbour before is below that of the neighbour after
 *    (OpenSCAD's atan2(dx, dy), compared exactly here).
 *  - Outlines: each path backwards, without its first point when closed.
 *
 * Unlike OpenSCAD, which warns and goes on, malformed input is an error: a group code
 * that is not an integer, a value that is not a finite number, an entity without the
 * points it uses. Everything is bounded before it is allocated: segments in all (2^22),
 * coordinates (2^40, so that grid cells and their differences are exact integers), the
 * turns an arc's end angle is raised by (1024).
 */
#include "io/dxf.h"

#include "base/numparse.h"
#include "base/sort.h"
#include "base/degree_trig.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define GRID 0.0009765625                 /* OpenSCAD's GRID_COARSE, 2^-10 */
#define MAX_SEGMENTS ((size_t)1 << 22)    /* line segments made, blocks included */
#define MAX_COORDINATE 1099511627776.0    /* 2^40: cells below 2^50, exact */
#define MAX_TURNS 1024                    /* an arc's end angle raised by 360 at most so often */
#define MAX_NAMED_WARNINGS 16             /* unsupported entity kinds named one by one */
#define PI 3.14159265358979323846         /* M_PI */

__extension__ typedef __int128 i128;

typedef struct span {
    const char *s;
    size_t n;
} span;

static bool span_is(span a, const char *lit)
{
    size_t n = strlen(lit);
    return a.n == n && memcmp(a.s, lit, n) == 0;
}

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= UINT64_C(0xbf58476d1ce4e5b9);
    x ^= x >> 27;
    x *= UINT64_C(0x94d049bb133111eb);
    return x ^ (x >> 31);
}

static uint64_t hash_bytes(const char *s, size_t n)
{
    uint64_t h = UINT64_C(0xcbf29ce484222325);
    for (size_t i = 0; i < n; i++)
        h = (h ^ (unsigned char)s[i]) * UINT64_C(0x100000001b3);
    return mix64(h);
}

/* ---- a table of names (blocks, unsupported entity kinds) --------------------------- */

typedef struct name_table {
    span *names; /* into the input, which outlives the table */
    size_t count, cap;
    uint32_t *slots; /* MCI_NONE or an index into names */
    size_t mask;     /* slots - 1, a power of two less one; 0 before the first name */
} name_table;

static uint32_t names_find(const name_table *t, span s)
{
    if (!t->slots)
        return MCI_NONE;
    for (size_t i = hash_bytes(s.s, s.n) & t->mask;; i = (i + 1) & t->mask) {
        uint32_t id = t->slots[i];
        if (id == MCI_NONE || (t->names[id].n == s.n && memcmp(t->names[id].s, s.s, s.n) == 0))
            return id;
    }
}

static bool names_rehash(const mci_ctx *ctx, name_table *t, size_t slots)
{
    uint32_t *fresh = mci_malloc_array(ctx, slots, sizeof *fresh);
    if (!fresh)
        return false;
    memset(fresh, 0xff, slots * sizeof *fresh);
    for (size_t id = 0; id < t->count; id++) {
        size_t i = hash_bytes(t->names[id].s, t->names[id].n) & (slots - 1);
        while (fresh[i] != MCI_NONE)
            i = (i + 1) & (slots - 1);
        fresh[i] = (uint32_t)id;
    }
    mci_free(ctx, t->slots);
    t->slots = fresh;
    t->mask = slots - 1;
    return true;
}

/* The name's index, added when new (*added set); MCI_NONE when out of memory. */
static uint32_t names_add(const mci_ctx *ctx, name_table *t, span s, bool *added)
{
    uint32_t id = names_find(t, s);
    *added = false;
    if (id != MCI_NONE)
        return id;
    if (2 * (t->count + 1) > (t->slots ? t->mask + 1 : 0) &&
        !names_rehash(ctx, t, t->slots ? 2 * (t->mask + 1) : 16))
        return MCI_NONE;
    if (!mci_grow_array(ctx, (void **)&t->names, &t->cap, t->count + 1, sizeof *t->names, 16))
        return MCI_NONE;
    id = (uint32_t)t->count++;
    t->names[id] = s;
    for (size_t i = hash_bytes(s.s, s.n) & t->mask;; i = (i + 1) & t->mask)
        if (t->slots[i] == MCI_NONE) {
            t->slots[i] = id;
            break;
        }
    *added = true;
    return id;
}

static void names_free(const mci_ctx *ctx, name_table *t)
{
    mci_free(ctx, t->names);
    mci_free(ctx, t->slots);
}

/* ---- the grid: cells of 1/1024 that hold points ------------------------------------- */

typedef struct cell_table {
    int64_t *xy; /* 2 per cell: its integer coordinates (the point is xy * GRID) */
    size_t count, cap;
    uint32_t *slots;
    size_t mask;
} cell_table;

static size_t cell_slot(int64_t x, int64_t y, size_t mask)
{
    return (size_t)(mix64((uint64_t)x * UINT64_C(0x9e3779b97f4a7c15) ^ (uint64_t)y) & mask);
}

static uint32_t cell_find(const cell_table *t, int64_t x, int64_t y)
{
    if (!t->slots)
        return MCI_NONE;
    for (size_t i = cell_slot(x, y, t->mask);; i = (i + 1) & t->mask) {
        uint32_t id = t->slots[i];
        if (id == MCI_NONE || (t->xy[2 * id] == x && t->xy[2 * id + 1] == y))
            return id;
    }
}

static bool cell_rehash(const mci_ctx *ctx, cell_table *t, size_t slots)
{
    uint32_t *fresh = mci_malloc_array(ctx, slots, sizeof *fresh);
    if (!fresh)
        return false;
    memset(fresh, 0xff, slots * sizeof *fresh);
    for (size_t id = 0; id < t->count; id++) {
        size_t i = cell_slot(t->xy[2 * id], t->xy[2 * id + 1], slots - 1);
        while (fresh[i] != MCI_NONE)
            i = (i + 1) & (slots - 1);
        fresh[i] = (uint32_t)id;
    }
    mci_free(ctx, t->slots);
    t->slots = fresh;
    t->mask = slots - 1;
    return true;
}

/* Add a cell known to be absent; MCI_NONE when out of memory. */
static uint32_t cell_add(const mci_ctx *ctx, cell_table *t, int64_t x, int64_t y)
{
    uint32_t id;
    if (2 * (t->count + 1) > (t->slots ? t->mask + 1 : 0) &&
        !cell_rehash(ctx, t, t->slots ? 2 * (t->mask + 1) : 64))
        return MCI_NONE;
    if (!mci_grow_array(ctx, (void **)&t->xy, &t->cap, t->count + 1, 2 * sizeof *t->xy, 64))
        return MCI_NONE;
    id = (uint32_t)t->count++;
    t->xy[2 * id] = x;
    t->xy[2 * id + 1] = y;
    for (size_t i = cell_slot(x, y, t->mask);; i = (i + 1) & t->mask)
        if (t->slots[i] == MCI_NONE) {
            t->slots[i] = id;
            break;
        }
    return id;
}

/* ---- the reader ------------------------------------------------------------------------ */

typedef struct dxf_segment {
    uint32_t cell[2];
} dxf_segment;

typedef struct dxf_block {
    dxf_segment *segs;
    size_t count, cap;
} dxf_block;

typedef struct dxf_reader {
    const mci_ctx *ctx;
    const char *name;
    mcsg_error *err;
    const char *layer_filter; /* NULL: every layer */
    double ox, oy, scale, fn, fa, fs;

    cell_table cells;
    dxf_segment *segs; /* the ENTITIES segments */
    size_t seg_count, seg_cap;
    uint32_t *entry_cell, *entry_value; /* the cells' lists, in the order they grew */
    size_t entry_count, entry_cap, entry_value_cap;
    size_t made; /* segments made, blocks included */

    name_table block_names;
    dxf_block *blocks;
    size_t block_cap;
    uint32_t current_block; /* MCI_NONE: none */

    name_table kinds; /* unsupported entity kinds */
    size_t *kind_counts;
    size_t kind_cap;

    bool in_entities, in_blocks;
    /* The entity being read. */
    span mode, layer, iddata;
    size_t mode_line;
    int flags;
    double *xv, *yv;
    size_t nx, ny, capx, capy;
    double radius, arc_start, arc_stop, ell_start, ell_stop;
} dxf_reader;

static mcsg_status fail_at(dxf_reader *r, mcsg_status status, size_t line, const char *fmt, ...)
    MCI_PRINTF(4, 5);

static mcsg_status fail_at(dxf_reader *r, mcsg_status status, size_t line, const char *fmt, ...)
{
    char prefix[512];
    va_list ap;
    mcsg_status st;
    snprintf(prefix, sizeof prefix, "%s:%zu", r->name, line);
    va_start(ap, fmt);
    st = mci_vfail(r->err, status, prefix, fmt, ap);
    va_end(ap);
    return st;
}

static mcsg_status nomem(dxf_reader *r)
{
    char what[512];
    snprintf(what, sizeof what, "reading %s", r->name);
    return mci_fail_nomem(r->err, what);
}

static bool layer_matches(const dxf_reader *r)
{
    return !r->layer_filter || span_is(r->layer, r->layer_filter);
}

/* Snap (x, y) to the grid as OpenSCAD's Grid2d::align does, creating its cell. */
static mcsg_status align(dxf_reader *r, double x, double y, uint32_t *cell)
{
    int64_t ix, iy;
    uint32_t id;
    if (!(fabs(x) <= MAX_COORDINATE) || !(fabs(y) <= MAX_COORDINATE))
        return fail_at(r, MCSG_ERR_LIMIT, r->mode_line,
                       "%.*s: point (%.17g, %.17g) is not finite or beyond 2^40 in magnitude",
                       (int)(r->mode.n < 64 ? r->mode.n : 64), r->mode.s, x, y);
    ix = (int64_t)round(x / GRID);
    iy = (int64_t)round(y / GRID);
    id = cell_find(&r->cells, ix, iy);
    if (id == MCI_NONE) {
        /* The nearest occupied neighbour by |dx| + |dy|, the first in OpenSCAD's scan
         * (x outer, y inner, both ascending) among equals. */
        int best = 10;
        for (int dx = -1; dx <= 1; dx++)
            for (int dy = -1; dy <= 1; dy++) {
                uint32_t n = cell_find(&r->cells, ix + dx, iy + dy);
                int d = (dx < 0 ? -dx : dx) + (dy < 0 ? -dy : dy);
                if (n != MCI_NONE && d < best) {
                    best = d;
                    id = n;
                }
            }
        if (id == MCI_NONE && (id = cell_add(r->ctx, &r->cells, ix, iy)) == MCI_NONE)
            return nomem(r);
    }
    *cell = id;
    return MCSG_OK;
}

static bool push_entry(dxf_reader *r, uint32_t cell, uint32_t value)
{
    if (!mci_grow_array(r->ctx, (void **)&r->entry_cell, &r->entry_cap, r->entry_count + 1,
                        sizeof *r->entry_cell, 64) ||
        !mci_grow_array(r->ctx, (void **)&r->entry_value, &r->entry_value_cap,
                        r->entry_count + 1, sizeof *r->entry_value, 64))
        return false;
    r->entry_cell[r->entry_count] = cell;
    r->entry_value[r->entry_count++] = value;
    return true;
}

static bool push_segment(const mci_ctx *ctx, dxf_segment **segs, size_t *count, size_t *cap,
                         uint32_t c1, uint32_t c2)
{
    if (!mci_grow_array(ctx, (void **)segs, cap, *count + 1, sizeof **segs, 16))
        return false;
    (*segs)[*count].cell[0] = c1;
    (*segs)[(*count)++].cell[1] = c2;
    return true;
}

/* Whether segments made now are kept (ADD_LINE's first two tests). */
static bool keeps_segments(const dxf_reader *r)
{
    return r->in_blocks || (r->in_entities && layer_matches(r));
}

/* Room for `more` segments within MAX_SEGMENTS. */
static mcsg_status budget(dxf_reader *r, double more)
{
    if (!(more <= (double)(MAX_SEGMENTS - r->made)))
        return fail_at(r, MCSG_ERR_LIMIT, r->mode_line,
                       "%.*s: more than %zu line segments in the drawing",
                       (int)(r->mode.n < 64 ? r->mode.n : 64), r->mode.s, MAX_SEGMENTS);
    return MCSG_OK;
}

/* OpenSCAD's ADD_LINE. */
static mcsg_status add_segment(dxf_reader *r, double x1, double y1, double x2, double y2)
{
    uint32_t c1, c2, number = (uint32_t)r->seg_count;
    mcsg_status st;
    if (!keeps_segments(r))
        return MCSG_OK;
    if ((st = budget(r, 1)) != MCSG_OK || (st = align(r, x1, y1, &c1)) != MCSG_OK ||
        (st = align(r, x2, y2, &c2)) != MCSG_OK)
        return st;
    r->made++;
    if (!push_entry(r, c1, number) || !push_entry(r, c2, number))
        return nomem(r);
    if (r->in_entities &&
        !push_segment(r->ctx, &r->segs, &r->seg_count, &r->seg_cap, c1, c2))
        return nomem(r);
    if (r->in_blocks && r->current_block != MCI_NONE) {
        dxf_block *b = &r->blocks[r->current_block];
        if (!push_segment(r->ctx, &b->segs, &b->count, &b->cap, c1, c2))
            return nomem(r);
    }
    return MCSG_OK;
}

static mcsg_status need_points(dxf_reader *r, size_t n)
{
    if (r->nx < n || r->ny < n)
        return fail_at(r, MCSG_ERR_PARSE, r->mode_line,
                       "%.*s without %s (group codes 10 and 20%s)", (int)r->mode.n, r->mode.s,
                       n == 1 ? "its point" : "its two points", n == 1 ? "" : ", 11 and 21");
    return MCSG_OK;
}

/* The number of turns (360 degrees, or 2 pi) that `stop` is raised by until it is not
 * below `start`, done as OpenSCAD does it, one addition at a time. */
static mcsg_status raise_angle(dxf_reader *r, double start, double *stop, double turn)
{
    for (int k = 0; start > *stop; k++) {
        if (k == MAX_TURNS)
            return fail_at(r, MCSG_ERR_LIMIT, r->mode_line,
                           "%.*s: start and end angles more than %d turns apart",
                           (int)r->mode.n, r->mode.s, MAX_TURNS);
        *stop += turn;
    }
    return MCSG_OK;
}

static mcsg_status flush_circle(dxf_reader *r)
{
    mcsg_status st = need_points(r, 1);
    double cx, cy, rad = r->radius;
    int n;
    if (st != MCSG_OK || !keeps_segments(r))
        return st;
    cx = r->xv[0], cy = r->yv[0];
    n = mcsg_fragments(rad, r->fn, r->fa, r->fs);
    if ((st = budget(r, n)) != MCSG_OK)
        return st;
    for (int i = 0; st == MCSG_OK && i < n; i++) {
        double a1 = (360.0 * i) / n, a2 = (360.0 * (i + 1)) / n;
        st = add_segment(r, mci_cos_degrees(a1) * rad + cx, mci_sin_degrees(a1) * rad + cy,
                         mci_cos_degrees(a2) * rad + cx, mci_sin_degrees(a2) * rad + cy);
    }
    return st;
}

static mcsg_status flush_arc(dxf_reader *r)
{
    mcsg_status st = need_points(r, 1);
    double cx, cy, rad = r->radius, sweep, count;
    int n;
    if (st != MCSG_OK || !keeps_segments(r) ||
        (st = raise_angle(r, r->arc_start, &r->arc_stop, 360.0)) != MCSG_OK)
        return st;
    cx = r->xv[0], cy = r->yv[0];
    n = mcsg_fragments(rad, r->fn, r->fa, r->fs);
    sweep = r->arc_stop - r->arc_start;
    count = ceil(n * sweep / 360);
    if ((st = budget(r, count)) != MCSG_OK)
        return st;
    n = (int)count;
    for (int i = 0; st == MCSG_OK && i < n; i++) {
        double a1 = r->arc_start + sweep * i / n, a2 = r->arc_start + sweep * (i + 1) / n;
        st = add_segment(r, mci_cos_degrees(a1) * rad + cx, mci_sin_degrees(a1) * rad + cy,
                         mci_cos_degrees(a2) * rad + cx, mci_sin_degrees(a2) * rad + cy);
    }
    return st;
}

static mcsg_status flush_ellipse(dxf_reader *r)
{
    mcsg_status st = need_points(r, 2);
    double cx, cy, ex, ey, major, minor, rot, cosval, sweep, count, px = 0, py = 0;
    int n;
    if (st != MCSG_OK || !keeps_segments(r) ||
        (st = raise_angle(r, r->ell_start, &r->ell_stop, 2 * PI)) != MCSG_OK)
        return st;
    cx = r->xv[0], cy = r->yv[0], ex = r->xv[1], ey = r->yv[1];
    major = sqrt(ex * ex + ey * ey);
    cosval = ex / major;
    if (cosval > 1.0)
        cosval = 1.0;
    if (cosval < -1.0)
        cosval = -1.0;
    rot = acos(cosval);
    if (ey < 0.0)
        rot = 2 * PI - rot;
    minor = major * r->radius; /* the ratio, read as a radius */
    sweep = r->ell_stop - r->ell_start;
    n = mcsg_fragments(major, r->fn, r->fa, r->fs);
    count = ceil(n * sweep / (2 * PI));
    if ((st = budget(r, count)) != MCSG_OK)
        return st;
    n = (int)count;
    for (int i = 0; st == MCSG_OK && n > 0 && i <= n; i++) {
        double a = r->ell_start + sweep * i / n;
        double qx = cos(a) * major, qy = sin(a) * minor;
        double x = cos(rot) * qx - sin(rot) * qy, y = sin(rot) * qx + cos(rot) * qy;
        x += cx;
        y += cy;
        if (i > 0)
            st = add_segment(r, px, py, x, y);
        px = x, py = y;
    }
    return st;
}

static mcsg_status flush_insert(dxf_reader *r)
{
    uint32_t id = names_find(&r->block_names, r->iddata);
    size_t n = id == MCI_NONE ? 0 : r->blocks[id].count;
    double a = r->arc_start, sx = r->ell_start, sy = r->ell_stop, c, s;
    mcsg_status st = MCSG_OK;
    if (n == 0)
        return MCSG_OK;
    if ((st = need_points(r, 1)) != MCSG_OK || !keeps_segments(r) ||
        (st = budget(r, (double)n)) != MCSG_OK)
        return st;
    c = mci_cos_degrees(a);
    s = mci_sin_degrees(a);
    for (size_t i = 0; st == MCSG_OK && i < n; i++) {
        dxf_segment seg = r->blocks[id].segs[i]; /* the block may grow (an INSERT of itself) */
        const int64_t *p = r->cells.xy + 2 * seg.cell[0], *q = r->cells.xy + 2 * seg.cell[1];
        double lx1 = (double)p[0] * GRID * sx, ly1 = (double)p[1] * GRID * sy;
        double lx2 = (double)q[0] * GRID * sx, ly2 = (double)q[1] * GRID * sy;
        st = add_segment(r, (c * lx1 - s * ly1) * r->scale + r->xv[0],
                         (s * lx1 + c * ly1) * r->scale + r->yv[0],
                         (c * lx2 - s * ly2) * r->scale + r->xv[0],
                         (s * lx2 + c * ly2) * r->scale + r->yv[0]);
    }
    return st;
}

static mcsg_status flush_lwpolyline(dxf_reader *r)
{
    size_t n = r->nx > r->ny ? r->nx : r->ny;
    bool closed = r->flags & 1;
    mcsg_status st = MCSG_OK;
    if ((r->nx != r->ny && (n >= 2 || closed)) || (n == 0 && closed))
        return fail_at(r, MCSG_ERR_PARSE, r->mode_line,
                       "LWPOLYLINE with %zu x and %zu y coordinates", r->nx, r->ny);
    for (size_t i = 1; st == MCSG_OK && i < n; i++)
        st = add_segment(r, r->xv[i - 1], r->yv[i - 1], r->xv[i % n], r->yv[i % n]);
    if (st == MCSG_OK && closed)
        st = add_segment(r, r->xv[n - 1], r->yv[n - 1], r->xv[0], r->yv[0]);
    return st;
}

/* The entity read so far, at the next group code 0. */
static mcsg_status flush(dxf_reader *r)
{
    mcsg_status st = MCSG_OK;
    if (span_is(r->mode, "SECTION")) {
        r->in_entities = span_is(r->iddata, "ENTITIES");
        r->in_blocks = span_is(r->iddata, "BLOCKS");
    } else if (span_is(r->mode, "LINE")) {
        if ((st = need_points(r, 2)) == MCSG_OK)
            st = add_segment(r, r->xv[0], r->yv[0], r->xv[1], r->yv[1]);
    } else if (span_is(r->mode, "LWPOLYLINE")) {
        st = flush_lwpolyline(r);
    } else if (span_is(r->mode, "CIRCLE")) {
        st = flush_circle(r);
    } else if (span_is(r->mode, "ARC")) {
        st = flush_arc(r);
    } else if (span_is(r->mode, "ELLIPSE")) {
        st = flush_ellipse(r);
    } else if (span_is(r->mode, "INSERT")) {
        st = flush_insert(r);
    } else if (span_is(r->mode, "DIMENSION") && layer_matches(r)) {
        /* dimensions are for dxf_dim(), not part of the drawing */
    } else if (span_is(r->mode, "BLOCK")) {
        bool added;
        r->current_block = MCI_NONE;
        if (r->iddata.n > 0) {
            uint32_t id;
            /* Room first: every name in the table has its block. */
            if (!mci_grow_array(r->ctx, (void **)&r->blocks, &r->block_cap,
                                r->block_names.count + 1, sizeof *r->blocks, 16) ||
                (id = names_add(r->ctx, &r->block_names, r->iddata, &added)) == MCI_NONE)
                return nomem(r);
            if (added)
                memset(&r->blocks[id], 0, sizeof r->blocks[id]);
            r->current_block = id;
        }
    } else if (span_is(r->mode, "ENDBLK")) {
        r->current_block = MCI_NONE;
    } else if (span_is(r->mode, "ENDSEC")) {
    } else if (r->in_blocks || (r->in_entities && layer_matches(r))) {
        bool added;
        uint32_t id;
        if (!mci_grow_array(r->ctx, (void **)&r->kind_counts, &r->kind_cap, r->kinds.count + 1,
                            sizeof *r->kind_counts, 16) ||
            (id = names_add(r->ctx, &r->kinds, r->mode, &added)) == MCI_NONE)
            return nomem(r);
        if (added)
            r->kind_counts[id] = 0;
        r->kind_counts[id]++;
    }
    return st;
}

/* One line: up to '\n', trimmed of the white space of C's isspace. *eof is set when the
 * line did not end with '\n' (std::getline's eofbit). */
static span next_line(const char *data, size_t size, size_t *pos, bool *eof)
{
    span s = {data + *pos, 0};
    const char *nl = *pos < size ? memchr(data + *pos, '\n', size - *pos) : NULL;
    size_t end = nl ? (size_t)(nl - data) : size;
    s.n = end - *pos;
    *pos = nl ? end + 1 : size;
    *eof = !nl;
    while (s.n > 0 && (*s.s == ' ' || (*s.s >= '\t' && *s.s <= '\r')))
        s.s++, s.n--;
    while (s.n > 0 && (s.s[s.n - 1] == ' ' || (s.s[s.n - 1] >= '\t' && s.s[s.n - 1] <= '\r')))
        s.n--;
    return s;
}

/* An int as boost::lexical_cast<int> reads one: a sign, then decimal digits. */
static bool parse_int(span s, int *out)
{
    size_t i = 0;
    bool negative = false;
    long long v = 0;
    if (s.n > 0 && (s.s[0] == '+' || s.s[0] == '-'))
        negative = s.s[i++] == '-';
    if (i == s.n)
        return false;
    for (; i < s.n; i++) {
        if (s.s[i] < '0' || s.s[i] > '9')
            return false;
        v = 10 * v + (s.s[i] - '0');
        if (v > (long long)INT32_MAX + 1)
            return false;
    }
    if (negative)
        v = -v;
    if (v > INT32_MAX || v < INT32_MIN)
        return false;
    *out = (int)v;
    return true;
}

static mcsg_status parse_number(dxf_reader *r, span s, int code, size_t line, double *out)
{
    const char *next;
    if (!mci_parse_double(s.s, s.s + s.n, out, &next) || next != s.s + s.n || !isfinite(*out))
        return fail_at(r, MCSG_ERR_PARSE, line, "group code %d: '%.*s' is not a finite number",
                       code, (int)(s.n < 64 ? s.n : 64), s.s);
    return MCSG_OK;
}

static bool push_double(const mci_ctx *ctx, double **v, size_t *n, size_t *cap, double x)
{
    if (!mci_grow_array(ctx, (void **)v, cap, *n + 1, sizeof **v, 16))
        return false;
    (*v)[(*n)++] = x;
    return true;
}

static mcsg_status parse(dxf_reader *r, const char *data, size_t size)
{
    size_t pos = 0, line = 0;
    bool eof = size == 0;
    mcsg_status st = MCSG_OK;
    while (st == MCSG_OK && !eof) {
        span id, value;
        int code;
        double v = 0;
        size_t code_line = ++line, value_line;
        id = next_line(data, size, &pos, &eof);
        value = eof ? (span){data + size, 0} : next_line(data, size, &pos, &eof);
        value_line = ++line;
        if (!parse_int(id, &code)) {
            if (eof)
                break; /* OpenSCAD stops there silently */
            return fail_at(r, MCSG_ERR_PARSE, code_line, "group code '%.*s' is not an integer",
                           (int)(id.n < 64 ? id.n : 64), id.s);
        }
        if ((code >= 10 && code <= 16) || (code >= 20 && code <= 26) || code == 40 ||
            code == 41 || code == 42 || code == 50 || code == 51) {
            if ((st = parse_number(r, value, code, value_line, &v)) != MCSG_OK)
                return st;
        }
        switch (code) {
        case 0:
            if ((st = flush(r)) != MCSG_OK)
                return st;
            r->mode = value;
            r->mode_line = value_line;
            r->layer = r->iddata = (span){"", 0};
            r->flags = 0;
            r->nx = r->ny = 0;
            r->radius = r->arc_start = r->arc_stop = 0;
            r->ell_start = r->ell_stop = span_is(r->mode, "INSERT") ? 1.0 : 0.0;
            break;
        case 2:
            r->iddata = value;
            break;
        case 8:
            r->layer = value;
            break;
        case 10:
        case 11:
            if (!push_double(r->ctx, &r->xv, &r->nx, &r->capx,
                             r->in_blocks ? v : (v - r->ox) * r->scale))
                return nomem(r);
            break;
        case 20:
        case 21:
            if (!push_double(r->ctx, &r->yv, &r->ny, &r->capy,
                             r->in_blocks ? v : (v - r->oy) * r->scale))
                return nomem(r);
            break;
        case 40:
            r->radius = r->in_blocks ? v : v * r->scale;
            break;
        case 41:
            r->ell_start = v;
            break;
        case 42:
            r->ell_stop = v;
            break;
        case 50:
            r->arc_start = v;
            break;
        case 51:
            r->arc_stop = v;
            break;
        case 70:
            if (!parse_int(value, &r->flags))
                return fail_at(r, MCSG_ERR_PARSE, value_line,
                               "group code 70: '%.*s' is not an integer",
                               (int)(value.n < 64 ? value.n : 64), value.s);
            break;
        default:
            break;
        }
    }
    return st;
}

static void warn_unsupported(const dxf_reader *r)
{
    size_t others = 0;
    for (size_t k = 0; k < r->kinds.count; k++) {
        span s = r->kinds.names[k];
        if (k >= MAX_NAMED_WARNINGS) {
            others += r->kind_counts[k];
            continue;
        }
        if (!r->layer_filter)
            mci_log(r->ctx, MCSG_LOG_WARNING, "Unsupported DXF Entity '%.*s' (%zx) in \"%s\".",
                    (int)(s.n < 64 ? s.n : 64), s.s, r->kind_counts[k], r->name);
        else
            mci_log(r->ctx, MCSG_LOG_WARNING,
                    "Unsupported DXF Entity '%.*s' (%zx) in layer '%s' of %s",
                    (int)(s.n < 64 ? s.n : 64), s.s, r->kind_counts[k], r->layer_filter,
                    r->name);
    }
    if (others)
        mci_log(r->ctx, MCSG_LOG_WARNING,
                "%zu more unsupported DXF entities of %zu other kinds in \"%s\"", others,
                r->kinds.count - MAX_NAMED_WARNINGS, r->name);
}

/* ---- paths ---------------------------------------------------------------------------- */

typedef struct path_builder {
    const mci_ctx *ctx;
    const dxf_segment *segs;
    size_t seg_count, cell_count;
    bool *used;
    /* Per cell: the distinct segment numbers its list holds, and how many of them are
     * still unused (an end is free when that is 1: the segment itself). */
    uint32_t *distinct_start, *distinct; /* CSR by cell */
    uint32_t *unused_count;
    uint32_t *value_start, *value_cells; /* CSR by segment number: the cells listing it */
    /* Per cell: its list in order, only segments that end in the cell; a cursor past
     * the used ones at its front. */
    uint32_t *chain_start, *chain, *cursor;
    uint32_t *heap; /* segments that may have a free end, lowest number on top */
    size_t heap_count;
    uint32_t *points; /* the paths' cells */
    size_t point_count, point_cap;
    uint32_t *path_start; /* path_count + 1 */
    size_t path_count, path_cap;
    size_t open_paths;
} path_builder;

static void heap_push(path_builder *p, uint32_t v)
{
    size_t i = p->heap_count++;
    while (i > 0 && p->heap[(i - 1) / 2] > v) {
        p->heap[i] = p->heap[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    p->heap[i] = v;
}

static uint32_t heap_pop(path_builder *p)
{
    uint32_t top = p->heap[0], last = p->heap[--p->heap_count];
    size_t i = 0, n = p->heap_count;
    for (;;) {
        size_t c = 2 * i + 1;
        if (c >= n)
            break;
        if (c + 1 < n && p->heap[c + 1] < p->heap[c])
            c++;
        if (p->heap[c] >= last)
            break;
        p->heap[i] = p->heap[c];
        i = c;
    }
    if (n > 0)
        p->heap[i] = last;
    return top;
}

static bool end_is_free(const path_builder *p, uint32_t cell)
{
    return p->unused_count[cell] == 1;
}

static void mark_used(path_builder *p, uint32_t seg, bool track)
{
    p->used[seg] = true;
    for (uint32_t k = p->value_start[seg]; k < p->value_start[seg + 1]; k++) {
        uint32_t c = p->value_cells[k];
        if (--p->unused_count[c] == 1 && track) {
            for (uint32_t j = p->distinct_start[c]; j < p->distinct_start[c + 1]; j++)
                if (!p->used[p->distinct[j]]) {
                    heap_push(p, p->distinct[j]);
                    break;
                }
        }
    }
}

static bool add_point(path_builder *p, uint32_t cell)
{
    if (!mci_grow_array(p->ctx, (void **)&p->points, &p->point_cap, p->point_count + 1,
                        sizeof *p->points, 64))
        return false;
    p->points[p->point_count++] = cell;
    return true;
}

/* One path from segment `seg`, entered at its end `end`. */
static bool chain(path_builder *p, uint32_t seg, int end, bool track)
{
    if (!mci_grow_array(p->ctx, (void **)&p->path_start, &p->path_cap, p->path_count + 2,
                        sizeof *p->path_start, 16) ||
        !add_point(p, p->segs[seg].cell[end]))
        return false;
    p->path_start[p->path_count] = (uint32_t)(p->point_count - 1);
    for (;;) {
        uint32_t c = p->segs[seg].cell[!end];
        if (!add_point(p, c))
            return false;
        mark_used(p, seg, track);
        while (p->cursor[c] < p->chain_start[c + 1] && p->used[p->chain[p->cursor[c]]])
            p->cursor[c]++;
        if (p->cursor[c] == p->chain_start[c + 1])
            break;
        seg = p->chain[p->cursor[c]];
        end = p->segs[seg].cell[0] == c ? 0 : 1;
    }
    p->path_count++;
    p->path_start[p->path_count] = (uint32_t)p->point_count;
    return true;
}

static void path_builder_free(path_builder *p)
{
    const mci_ctx *ctx = p->ctx;
    mci_free(ctx, p->used);
    mci_free(ctx, p->distinct_start);
    mci_free(ctx, p->distinct);
    mci_free(ctx, p->unused_count);
    mci_free(ctx, p->value_start);
    mci_free(ctx, p->value_cells);
    mci_free(ctx, p->chain_start);
    mci_free(ctx, p->chain);
    mci_free(ctx, p->cursor);
    mci_free(ctx, p->heap);
    mci_free(ctx, p->points);
    mci_free(ctx, p->path_start);
}

/* The cells' lists, indexed three ways (see path_builder). */
static bool index_lists(path_builder *p, const dxf_reader *r)
{
    const mci_ctx *ctx = p->ctx;
    size_t ns = p->seg_count, nc = p->cell_count, m = 0, pairs = 0;
    uint64_t *keys = mci_malloc_array(ctx, r->entry_count + 1, sizeof *keys);
    bool ok = keys != NULL;
    p->used = mci_calloc_array(ctx, ns + 1, sizeof *p->used);
    p->distinct_start = mci_calloc_array(ctx, nc + 1, sizeof *p->distinct_start);
    p->unused_count = mci_calloc_array(ctx, nc + 1, sizeof *p->unused_count);
    p->value_start = mci_calloc_array(ctx, ns + 2, sizeof *p->value_start);
    p->chain_start = mci_calloc_array(ctx, nc + 2, sizeof *p->chain_start);
    p->cursor = mci_malloc_array(ctx, nc + 1, sizeof *p->cursor);
    p->heap = mci_malloc_array(ctx, ns + nc + 1, sizeof *p->heap);
    ok = ok && p->used && p->distinct_start && p->unused_count && p->value_start &&
         p->chain_start && p->cursor && p->heap;
    for (size_t i = 0; ok && i < r->entry_count; i++)
        if (r->entry_value[i] < ns)
            keys[m++] = (uint64_t)r->entry_cell[i] << 32 | r->entry_value[i];
    if (ok) {
        mci_sort_u64(keys, m);
        pairs = mci_unique_u64(keys, m);
        p->distinct = mci_malloc_array(ctx, pairs + 1, sizeof *p->distinct);
        p->value_cells = mci_malloc_array(ctx, pairs + 1, sizeof *p->value_cells);
        ok = p->distinct && p->value_cells;
    }
    if (ok) {
        for (size_t k = 0; k < pairs; k++) {
            uint32_t c = (uint32_t)(keys[k] >> 32), v = (uint32_t)keys[k];
            p->distinct[k] = v;
            p->unused_count[c]++;
            p->distinct_start[c + 1]++;
            p->value_start[v + 2]++;
        }
        for (size_t c = 0; c < nc; c++)
            p->distinct_start[c + 1] += p->distinct_start[c];
        for (size_t v = 0; v < ns; v++)
            p->value_start[v + 2] += p->value_start[v + 1];
        for (size_t k = 0; k < pairs; k++)
            p->value_cells[p->value_start[(uint32_t)keys[k] + 1]++] = (uint32_t)(keys[k] >> 32);
        /* Chains: the entries whose segment ends in their cell, in order (counting sort). */
        m = 0;
        for (size_t i = 0; i < r->entry_count; i++) {
            uint32_t c = r->entry_cell[i], v = r->entry_value[i];
            if (v < ns && (p->segs[v].cell[0] == c || p->segs[v].cell[1] == c)) {
                p->chain_start[c + 2]++;
                m++;
            }
        }
        p->chain = mci_malloc_array(ctx, m + 1, sizeof *p->chain);
        ok = p->chain != NULL;
    }
    if (ok) {
        for (size_t c = 0; c < nc; c++)
            p->chain_start[c + 2] += p->chain_start[c + 1];
        for (size_t i = 0; i < r->entry_count; i++) {
            uint32_t c = r->entry_cell[i], v = r->entry_value[i];
            if (v < ns && (p->segs[v].cell[0] == c || p->segs[v].cell[1] == c))
                p->chain[p->chain_start[c + 1]++] = v;
        }
        for (size_t c = 0; c < nc; c++)
            p->cursor[c] = p->chain_start[c];
    }
    mci_free(ctx, keys);
    return ok;
}

/* Whether OpenSCAD's atan2(y1, x1) < atan2(y2, x2), exactly, on integer vectors. */
static bool angle_below(int64_t y1, int64_t x1, int64_t y2, int64_t x2)
{
    /* 0: (-pi, 0); 1: 0 (also atan2(0, 0)); 2: (0, pi); 3: pi */
    int h1 = y1 < 0 ? 0 : y1 > 0 ? 2 : x1 >= 0 ? 1 : 3;
    int h2 = y2 < 0 ? 0 : y2 > 0 ? 2 : x2 >= 0 ? 1 : 3;
    if (h1 != h2)
        return h1 < h2;
    if (h1 == 1 || h1 == 3)
        return false;
    return (i128)x1 * y2 - (i128)y1 * x2 > 0;
}

/* OpenSCAD's fixup_path_direction, for closed paths (when no path is open). */
static void fix_directions(path_builder *p, const cell_table *cells)
{
    if (p->open_paths > 0)
        return;
    for (size_t k = 0; k < p->path_count; k++) {
        uint32_t *pt = p->points + p->path_start[k];
        size_t n = p->path_start[k + 1] - p->path_start[k], b = 0, a, c;
        const int64_t *xy = cells->xy;
        for (size_t j = 1; j < n; j++)
            if (xy[2 * pt[j]] < xy[2 * pt[b]])
                b = j;
        a = b == 0 ? n - 2 : b - 1;
        c = b == n - 1 ? 1 : b + 1;
        if (angle_below(xy[2 * pt[a]] - xy[2 * pt[b]], xy[2 * pt[a] + 1] - xy[2 * pt[b] + 1],
                        xy[2 * pt[c]] - xy[2 * pt[b]], xy[2 * pt[c] + 1] - xy[2 * pt[b] + 1]))
            for (size_t i = 0, j = n - 1; i < j; i++, j--) {
                uint32_t t = pt[i];
                pt[i] = pt[j];
                pt[j] = t;
            }
    }
}

static mcsg_status make_paths(dxf_reader *r, mci_outlines *out)
{
    path_builder p;
    size_t ns = r->seg_count, total = 0;
    mcsg_status st = MCSG_OK;
    memset(&p, 0, sizeof p);
    p.ctx = r->ctx;
    p.segs = r->segs;
    p.seg_count = ns;
    p.cell_count = r->cells.count;
    if (!index_lists(&p, r)) {
        path_builder_free(&p);
        return nomem(r);
    }
    /* Open paths: from the lowest segment with a free end. */
    for (uint32_t s = 0; s < ns; s++)
        if (end_is_free(&p, r->segs[s].cell[0]) || end_is_free(&p, r->segs[s].cell[1]))
            heap_push(&p, s);
    while (st == MCSG_OK && p.heap_count > 0) {
        uint32_t s = heap_pop(&p);
        int end;
        if (p.used[s])
            continue;
        if (end_is_free(&p, r->segs[s].cell[0]))
            end = 0;
        else if (end_is_free(&p, r->segs[s].cell[1]))
            end = 1;
        else
            continue;
        if (!chain(&p, s, end, true))
            st = nomem(r);
        p.open_paths++;
    }
    /* Closed paths: from the lowest unused segment. */
    for (uint32_t s = 0; st == MCSG_OK && s < ns; s++)
        if (!p.used[s] && !chain(&p, s, 0, false))
            st = nomem(r);
    if (st == MCSG_OK) {
        fix_directions(&p, &r->cells);
        for (size_t k = 0; k < p.path_count; k++)
            total += p.path_start[k + 1] - p.path_start[k] - (k < p.open_paths ? 0 : 1);
        out->xy = mci_malloc_array(r->ctx, total + 1, 2 * sizeof *out->xy);
        out->loop_start = mci_malloc_array(r->ctx, p.path_count + 1, sizeof *out->loop_start);
        if (!out->xy || !out->loop_start) {
            mci_outlines_free(r->ctx, out);
            st = nomem(r);
        }
    }
    if (st == MCSG_OK) {
        size_t o = 0;
        out->loop_start[0] = 0;
        for (size_t k = 0; k < p.path_count; k++) {
            size_t first = p.path_start[k] + (k < p.open_paths ? 0 : 1);
            for (size_t j = p.path_start[k + 1]; j-- > first; o++) {
                const int64_t *c = r->cells.xy + 2 * (size_t)p.points[j];
                out->xy[2 * o] = (double)c[0] * GRID;
                out->xy[2 * o + 1] = (double)c[1] * GRID;
            }
            out->loop_start[k + 1] = (uint32_t)o;
        }
        out->point_count = o;
        out->loop_count = p.path_count;
    }
    path_builder_free(&p);
    return st;
}

static void reader_free(dxf_reader *r)
{
    const mci_ctx *ctx = r->ctx;
    mci_free(ctx, r->cells.xy);
    mci_free(ctx, r->cells.slots);
    mci_free(ctx, r->segs);
    mci_free(ctx, r->entry_cell);
    mci_free(ctx, r->entry_value);
    for (size_t k = 0; k < r->block_names.count; k++)
        mci_free(ctx, r->blocks[k].segs);
    mci_free(ctx, r->blocks);
    names_free(ctx, &r->block_names);
    names_free(ctx, &r->kinds);
    mci_free(ctx, r->kind_counts);
    mci_free(ctx, r->xv);
    mci_free(ctx, r->yv);
}

mcsg_status mci_dxf_read_memory(const mci_ctx *ctx, const char *data, size_t size,
                                const char *name, const char *layer, const double origin[2],
                                double scale, double fn, double fa, double fs,
                                mci_outlines *out, mcsg_error *err)
{
    dxf_reader r;
    mcsg_status st;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_dxf_read_memory: NULL output");
    memset(out, 0, sizeof *out);
    if (!data && size > 0)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_dxf_read_memory: NULL data");
    memset(&r, 0, sizeof r);
    r.ctx = ctx;
    r.name = name ? name : "<memory>";
    r.err = err;
    r.layer_filter = layer && layer[0] ? layer : NULL;
    r.ox = origin ? origin[0] : 0;
    r.oy = origin ? origin[1] : 0;
    r.scale = scale;
    r.fn = fn, r.fa = fa, r.fs = fs;
    r.current_block = MCI_NONE;
    r.mode = r.layer = r.iddata = (span){"", 0};
    st = parse(&r, data ? data : "", size);
    if (st == MCSG_OK) {
        warn_unsupported(&r);
        st = make_paths(&r, out);
    }
    reader_free(&r);
    return st;
}

mcsg_status mci_dxf_read(const mci_ctx *ctx, const char *path, const char *layer,
                         const double origin[2], double scale, double fn, double fa, double fs,
                         mci_outlines *out, mcsg_error *err)
{
    unsigned char *data;
    size_t size;
    mcsg_status st;
    if (!out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_dxf_read: NULL output");
    memset(out, 0, sizeof *out);
    if (!path)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mci_dxf_read: NULL path");
    st = mci_read_file(ctx, path, &data, &size, err);
    if (st != MCSG_OK)
        return st;
    st = mci_dxf_read_memory(ctx, (const char *)data, size, path, layer, origin, scale, fn, fa,
                             fs, out, err);
    mci_free(ctx, data);
    return st;
}
