/*
 * Vertices of the exact result that carry no shape, removed before rounding
 * (csg/flat_vertices.c).
 */
#ifndef MESHCSG_CSG_FLAT_VERTICES_H
#define MESHCSG_CSG_FLAT_VERTICES_H

#include "csg/classify.h"
#include "exact/kernel.h"

/* What the removal reads of the exact result besides its triangles. */
typedef struct mci_flat_source {
    /* The exact point of output vertex id (every id a kept triangle uses); it stays
     * valid until the removal returns. */
    const mci_point *(*point)(void *user, uint32_t id);
    /* Corner k of global face f, as the leaf gives it. */
    const double *(*corner)(const void *user, uint32_t f, int k);
    /* Whether face f's leaf is complemented: its kept triangles face the other way. */
    bool (*complemented)(const void *user, uint32_t f);
    /* Whether face f met another surface (was split): only vertices of such faces are
     * looked at, the others being the leaves' own. */
    bool (*touched)(const void *user, uint32_t f);
    /* Whether face f's plane is that of the face provenance names for it: false for a
     * leaf that is another evaluation's rounded result (a frame's), whose thin triangles
     * lie in planes tilted from their sources'. Vertices with such faces are kept. */
    bool (*own_plane)(const void *user, uint32_t f);
    void *user;
    size_t id_count; /* every vertex id is below it */
} mci_flat_source;

typedef struct mci_flat_stats {
    size_t removable;  /* vertices found flat where they sit */
    size_t removed;    /* of those, removed */
    size_t rounds;
    bool gave_up; /* an edge of the new triangles would have more than two: every
                     vertex was kept */
} mci_flat_stats;

/* Removes from kept every vertex of a touched face whose surroundings are flat: all its
 * triangles lie in one plane facing one way, or in two such planes meeting along a
 * straight line through it (it lies inside a straight edge of the result). Each is
 * decided by exact predicates; its triangles are replaced by a triangulation of the hole
 * it leaves, each new triangle taking the face of one it replaces on its side (the same
 * plane, facing the same way). The result keeps its shape exactly and stays closed and
 * oriented. When a new edge would have more than two triangles (another part of the
 * result touching a flat region along a segment that was no edge), kept is left as it
 * was. kept's arrays are rewritten (never longer). */
mcsg_status mci_remove_flat_vertices(const mci_ctx *ctx, mci_kept *kept,
                                     const mci_flat_source *src, mci_flat_stats *stats,
                                     mcsg_error *err);

#endif
