/*
 * A rounded result snapped onto a coarser grid (snap_round.h).
 *
 * Rounding to the nearest doubles keeps distinct exact points distinct however close
 * they are, and where thousands nearly coincide (a spindle torus's meridians at its
 * axis) or a sliver is thinner than the spacing of doubles, the rounded triangles fold
 * and cross there. Snapping every coordinate to a multiple of one power of two makes such
 * points one: a feature below the grid collapses. What a collapse leaves is removed
 * without changing any winding number off the mesh: triangles with two corners at one
 * grid point (their other two edges are one edge used both ways), pairs of the same
 * corners in opposite orders (they cancel: csg/rounding_repair.c), and collinear
 * triangles (mesh/zero_area.c).
 * The mesh stays closed as a chain: every directed edge maps to a directed edge. Where
 * parts of the result touch, welding joined their vertex copies, which are made again
 * (csg/manifold_split.c) as for any result.
 */
#include "csg/snap_round.h"
#include "csg/manifold_split.h"
#include "csg/rounding_repair.h"
#include "mesh/zero_area.h"

#include <math.h>
#include <string.h>

int mci_snap_exponent(const mcsg_mesh *m, int bits)
{
    double largest = 0;
    int e;
    for (size_t i = 0; i < 3 * m->vertex_count; i++)
        largest = fabs(m->vertices[i]) > largest ? fabs(m->vertices[i]) : largest;
    (void)frexp(largest, &e); /* largest < 2^e */
    return e - bits;
}

double mci_snap_coordinate(double x, int e)
{
    return ldexp(nearbyint(ldexp(x, -e)), e) + 0.0;
}

/* The snapped vertices, one per grid point in order of first use, and id[v] for every
 * input vertex (canon: room for the input's vertices). */
static bool weld_snapped(const mci_ctx *ctx, const mcsg_mesh *in, int e, mcsg_mesh *out,
                         uint32_t *id, uint32_t *canon)
{
    size_t n = in->vertex_count, count = 0;
    if (!(out->vertices = mci_malloc_array(ctx, 3 * n + 1, sizeof *out->vertices)))
        return false;
    for (size_t i = 0; i < 3 * n; i++)
        out->vertices[i] = mci_snap_coordinate(in->vertices[i], e);
    if (!mci_first_equal_coordinates(ctx, out->vertices, n, canon))
        return false;
    for (size_t v = 0; v < n; v++) {
        if (canon[v] != v) {
            id[v] = id[canon[v]];
            continue;
        }
        memmove(out->vertices + 3 * count, out->vertices + 3 * v, 3 * sizeof *out->vertices);
        id[v] = (uint32_t)count++;
    }
    out->vertex_count = count;
    return true;
}

/* The welded triangles without repeated corners and cancelled pairs
 * (csg/rounding_repair.c); face_of[t]: the input triangle of output triangle t. */
static bool snapped_triangles(const mci_ctx *ctx, const mcsg_mesh *in, const uint32_t *id,
                              mcsg_mesh *out, uint32_t *face_of)
{
    size_t count = 0, cancelled;
    out->triangles = mci_malloc_array(ctx, 3 * in->triangle_count + 1, sizeof *out->triangles);
    if (!out->triangles)
        return false;
    for (size_t t = 0; t < in->triangle_count; t++) {
        const uint32_t *c = in->triangles + 3 * t;
        uint32_t *to = out->triangles + 3 * count;
        to[0] = id[c[0]], to[1] = id[c[1]], to[2] = id[c[2]];
        if (to[0] != to[1] && to[1] != to[2] && to[0] != to[2])
            face_of[count++] = (uint32_t)t;
    }
    out->triangle_count = count;
    return mci_cancel_opposite_triangles(ctx, out->triangles, face_of, &out->triangle_count,
                                         &cancelled);
}

/* Collinear triangles removed (mesh/zero_area.c); face_of composed. */
static bool remove_collinear(const mci_ctx *ctx, mcsg_mesh *m, uint32_t **face_of)
{
    mcsg_mesh clean = {0};
    uint32_t *clean_of = NULL;
    mci_zero_area res;
    if (!mci_remove_zero_area(ctx, m, &clean, &clean_of, &res))
        return false;
    if (res.removed == 0) {
        mci_mesh_free(ctx, &clean);
        mci_free(ctx, clean_of);
        return true;
    }
    for (size_t t = 0; t < clean.triangle_count; t++)
        clean_of[t] = (*face_of)[clean_of[t]];
    mci_mesh_free(ctx, m);
    mci_free(ctx, *face_of);
    *m = clean;
    *face_of = clean_of;
    return true;
}

/* Vertices no triangle uses any more (of removed triangles) dropped, in order. */
static bool drop_unused_vertices(const mci_ctx *ctx, mcsg_mesh *m)
{
    uint32_t *renumber = mci_malloc_array(ctx, m->vertex_count + 1, sizeof *renumber);
    uint32_t count = 0;
    if (!renumber)
        return false;
    for (size_t v = 0; v < m->vertex_count; v++)
        renumber[v] = MCI_NONE;
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        renumber[m->triangles[i]] = 0;
    for (size_t v = 0; v < m->vertex_count; v++)
        if (renumber[v] == 0) {
            memmove(m->vertices + 3 * count, m->vertices + 3 * v, 3 * sizeof *m->vertices);
            renumber[v] = count++;
        }
    for (size_t i = 0; i < 3 * m->triangle_count; i++)
        m->triangles[i] = renumber[m->triangles[i]];
    m->vertex_count = count;
    mci_free(ctx, renumber);
    return true;
}

mcsg_status mci_snap_to_grid(const mci_ctx *ctx, const mcsg_mesh *in, int e, mcsg_mesh *out,
                             uint32_t **face_of, mcsg_error *err)
{
    uint32_t *id = mci_malloc_array(ctx, in->vertex_count + 1, sizeof *id);
    uint32_t *canon = mci_malloc_array(ctx, in->vertex_count + 1, sizeof *canon);
    mci_touching_split split;
    bool ok;
    memset(out, 0, sizeof *out);
    *face_of = mci_malloc_array(ctx, in->triangle_count + 1, sizeof **face_of);
    /* Welding joined the vertex copies of touching parts: they are made again last. */
    ok = id && canon && *face_of && weld_snapped(ctx, in, e, out, id, canon) &&
         snapped_triangles(ctx, in, id, out, *face_of) && remove_collinear(ctx, out, face_of) &&
         drop_unused_vertices(ctx, out) && mci_split_touching(ctx, out, &split);
    mci_free(ctx, id);
    mci_free(ctx, canon);
    if (ok)
        return MCSG_OK;
    mci_mesh_free(ctx, out);
    mci_free(ctx, *face_of);
    *face_of = NULL;
    return mci_fail_nomem(err, "snapping the rounded result to a grid");
}
