/*
 * The arrangement of one face: everything the intersection stage found on it (crossing
 * segments, single contact points, coplanar faces of other leaves, points on its edges
 * shared by its neighbours), merged exactly, split into non-crossing elementary edges,
 * and triangulated for any chosen subset of them. See arrange.c.
 */
#ifndef MESHCSG_CSG_ARRANGE_H
#define MESHCSG_CSG_ARRANGE_H

#include "base/core.h"
#include "exact/kernel.h"

/* Where a point of a face lies. */
enum {
    MCI_AT_CORNER = 0, /* + corner index 0..2 */
    MCI_AT_EDGE = 3,   /* + edge index 0..2 (edge i from corner i to corner i + 1) */
    MCI_AT_INSIDE = 6,
    MCI_AT_UNKNOWN = 0xfe /* not located yet */
};

/* A piece of constraint between two points of the face, with its source: the segment
 * where face `other` (global id) crosses this face, or (coplanar) part of an edge of the
 * coplanar face `other`. Several edges may join the same two points (one per source). */
typedef struct mci_arr_edge {
    uint32_t a, b; /* point ids, a < b */
    uint32_t other;
    uint8_t coplanar;
} mci_arr_edge;

/* An input segment before splitting: its line is this face's plane ∩ the plane through
 * l[0], l[1], l[2] (the other face's plane; for a coplanar edge u-v: u, v and an
 * auxiliary vertex off the face's plane). */
typedef struct mci_arr_segment {
    uint32_t a, b;
    uint32_t other;
    uint8_t coplanar;
    const double *l[3];
    uint64_t line; /* segments with equal `line` lie on one line (see mci_arr_add_crossing) */
    uint32_t group;  /* the leaf of `other` */
    uint8_t on_edge; /* lies along an edge of `other` (always for coplanar edges) */
    uint8_t phantom; /* an edge inside a flat region of the coplanar `other`: no
                        constraint, but the points where segments of other leaves cross
                        it are added (the faces across it have them as segment ends) */
} mci_arr_segment;

/* Lines a point is known to lie on, by construction (at most 3 kept: the list only
 * saves predicate evaluations, so dropping one is harmless). Line ids have 40 bits (see
 * mci_arr_add_crossing), kept as 32 + 8: 16 bytes a point instead of 32 (every point
 * of every arrangement has one). */
typedef struct mci_point_lines {
    uint32_t low[3];
    uint8_t high[3];
    uint8_t count;
} mci_point_lines;

/* Points an arrangement made itself (corners, clipped coplanar edges, crossings), in
 * blocks that never move (see arrange.c). */
typedef struct mci_point_pool mci_point_pool;

typedef struct mci_face_arr {
    mci_plane plane;     /* the face's plane; corners plane.a, .b, .c */
    /* [0..2] are the corners. The points are referred to, not copied: those given by
     * the caller live in the caller's stores (see mci_arr_add_point), the others in
     * `own`. 8 bytes a point instead of a 176-byte copy in every face that has it. A
     * point may be given to another arrangement (a scene shares edge points with the
     * neighbour across), so arrangements that share points are freed together. */
    const mci_point **points;
    mci_point_pool *own;
    mci_point_lines *lines; /* per point */
    uint8_t *where;      /* MCI_AT_* per point, after mci_arr_merge; between merges,
                            appended points' known locations or MCI_AT_UNKNOWN */
    mci_arr_segment *segments;
    mci_arr_edge *edges; /* after mci_arr_split: sorted by (a, b, other) */
    double (*aux)[3];    /* auxiliary vertices (stable: points refer to them); NULL
                            when no coplanar face is expected (mci_arr_init) */
    uint32_t *tris;      /* after mci_arr_triangulate: 3 point ids per triangle */
    uint32_t *adj;       /* ... and the side across each side (mci_cdt_output.adj) */
    /* Once the scene's points are numbered: each point's number and the scene's table
     * of point values, which triangulation shares (NULL before, and outside scenes). */
    const uint32_t *gid;
    struct mci_point_values *values;
    uint32_t face;       /* global face id */
    int axis, sign;      /* projection (mci_plane_projection_axis) */
    /* Counts in 32 bits (point ids are 32-bit anyway): one header per touched face
     * (tens of thousands in dense scenes), each some 40 bytes smaller. */
    uint32_t where_count; /* points classified in where[] */
    uint32_t point_count, point_capacity;
    uint32_t segment_count, segment_capacity;
    uint32_t edge_count;
    uint32_t aux_count, aux_capacity;
    uint32_t tri_count;
    bool dirty;          /* points were added since the last merge */
    bool coplanar;       /* a coplanar face of another leaf was added */
    bool segments_freed; /* mci_arr_free_segments was called */
} mci_face_arr;

/* Start the arrangement of face `face` with corners a, b, c (non-degenerate).
 * `corners` gives explicit points at a, b, c that outlive the arrangement (NULL: the
 * arrangement makes its own). `max_coplanar` bounds the number of mci_arr_add_coplanar
 * calls (it sizes the auxiliary vertex store, whose addresses must not move); `points`
 * is the number of points expected in all, corners included (room is made for them;
 * more may come). */
mcsg_status mci_arr_init(const mci_ctx *ctx, mci_face_arr *arr, uint32_t face,
                         const double *a, const double *b, const double *c,
                         const mci_point *const corners[3], size_t max_coplanar,
                         size_t points, mcsg_error *err);
/* An arrangement of the corners alone, as merged (a face dropped whole: nothing is
 * added to it, and it is never tessellated). */
mcsg_status mci_arr_init_corners(const mci_ctx *ctx, mci_face_arr *arr, uint32_t face,
                                 const double *a, const double *b, const double *c,
                                 const mci_point *const corners[3], mcsg_error *err);
void mci_arr_free(const mci_ctx *ctx, mci_face_arr *arr);
/* Free the segments once they are no longer needed: after mci_arr_split (the edges
 * are built), or after the last merge of an arrangement that will not be split.
 * Adding segments or coplanar faces, or splitting, afterwards fails (mci_arr_split with
 * MCSG_ERR_INTERNAL). */
void mci_arr_free_segments(const mci_ctx *ctx, mci_face_arr *arr);

/* Room for `points` points and `segments` segments in all (when more than now), so that
 * adding a counted number of them does not grow the arrays step by step (doubling left
 * much of the arrangements' memory unused). False when out of memory. */
bool mci_arr_reserve(const mci_ctx *ctx, mci_face_arr *arr, size_t points, size_t segments);

/* p made stable, for a point built on the stack that is to be added: the stored corner
 * when p is an explicit point at that corner's vertex, else a copy kept by the
 * arrangement until mci_arr_free. NULL when out of memory. */
const mci_point *mci_arr_keep(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p);

/* Inputs. Points must lie on the face (closed triangle). The arrangement refers to the
 * points given (mci_arr_add_point, mci_arr_add_crossing): they must stay valid and
 * unchanged as long as the arrangement is used. */
bool mci_arr_add_point(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *p);
/* The segment a-b where face `other` crosses. `plane_id` names other's plane: faces of
 * one flat region of a leaf may share it (their segments then lie on one line, which
 * spares exact zero tests); distinct planes must have distinct ids below 2^32.
 * `group` is other's leaf and `on_edge` says whether the segment lies along an edge of
 * other: two segments of one leaf that do not lie along edges cannot cross or overlap
 * (a leaf does not intersect itself), so they are not compared at all. `where` (may be
 * NULL) gives the ends' locations MCI_AT_* when the caller knows them exactly (merging
 * then does not locate them again), or MCI_AT_UNKNOWN. */
bool mci_arr_add_crossing(const mci_ctx *ctx, mci_face_arr *arr, const mci_point *a,
                          const mci_point *b, uint32_t other, const mci_plane *other_plane,
                          uint32_t plane_id, uint32_t group, bool on_edge,
                          const uint8_t where[2]);
/* The coplanar face `other` (corners of other_plane): its edges are clipped to this
 * face. The part inside of a crease edge (crease[i] for the edge from corner i to
 * corner i + 1: the other surface bends there) becomes a coplanar segment; other edges
 * lie inside a flat region of the other surface, bound no region, and give only their
 * end points. */
bool mci_arr_add_coplanar(const mci_ctx *ctx, mci_face_arr *arr, uint32_t other,
                          const mci_plane *other_plane, const bool crease[3], uint32_t group);

/* Merge coincident points exactly (corners keep ids 0..2) and classify each point
 * (where[]). May be called again after more points were added. Fails with
 * MCSG_ERR_INTERNAL if a point is off the face. */
mcsg_status mci_arr_merge(const mci_ctx *ctx, mci_face_arr *arr, mcsg_error *err);

/* Split the segments at every point on them and at their crossings (new points are
 * triple points: three planes, or an edge line and two planes), giving `edges`. Merges
 * first if points were added since the last merge. */
mcsg_status mci_arr_split(const mci_ctx *ctx, mci_face_arr *arr, mcsg_error *err);

/* Triangulate the face with the edges e for which use[e] is true (all if use is NULL):
 * the points inserted are those on the face's boundary, the end points of the used
 * edges, and (when use is NULL) every other point too. */
mcsg_status mci_arr_triangulate(const mci_ctx *ctx, mci_face_arr *arr, const bool *use,
                                mcsg_error *err);

#endif
