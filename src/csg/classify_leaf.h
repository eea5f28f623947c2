/*
 * The classification of one leaf, shared by the files that do it (csg/classify*.c); the
 * rest of the pipeline sees csg/classify.h. mci_classify_leaf (classify.c) runs:
 *   mci_leaf_regions  (classify_regions.c) pieces, separators, walls, edge pairing,
 *                     regions
 *   mci_leaf_trim     (classify_labels.c)  the candidates and the trimmed CSGlist
 *   mci_leaf_label    (classify_labels.c)  labels of every region: seeds by rays,
 *                     inheritance across separators by the local test, copies
 *   mci_leaf_select   (classify_select.c)  the regions kept, their pieces re-tessellated
 *                     and emitted
 */
#ifndef MESHCSG_CSG_CLASSIFY_LEAF_H
#define MESHCSG_CSG_CLASSIFY_LEAF_H

#include "base/sort.h"
#include "csg/classify.h"

/* The state of one leaf's classification, from its pieces to its kept triangles. */
typedef struct mci_leaf_work {
    const mci_ctx *ctx;
    const mci_classifier *cl;
    const mci_scene *s;
    uint32_t leaf, face_base, face_count;
    size_t np;        /* pieces */
    uint32_t *pv;     /* 3 per piece: output vertex ids */
    uint32_t *pface;  /* per piece: global face id */
    uint32_t *plocal; /* 3 per piece: arrangement point id (arranged faces) */
    uint32_t *mate;   /* per edge slot 3p + i (pv[i] -> pv[i + 1]): the slot across */
    uint8_t *is_sep;  /* per edge slot */
    mci_keyed *sep;       /* separators: (edge key, face of another leaf holding it), sorted */
    size_t nsep;
    mci_keyed *walls;     /* border sides of the leaf's faces dropped whole, sorted */
    size_t nwalls;
    uint32_t *region; /* per piece */
    size_t nreg;
    uint32_t *reg_start, *reg_pieces; /* pieces by region (CSR) */
    uint32_t *sep_start, *sep_slots;  /* separator slots by region (CSR) */
    uint32_t *cand;   /* leaves whose box meets this leaf's */
    size_t ncand;
    uint32_t *slot_of_leaf; /* leaf -> index in cand, or MCI_NONE */
    uint8_t *labels;  /* nreg x ncand */
    /* Winding leaves (mci_ptree.leaf_winding, classify_winding.c). cand_winding: per
     * candidate, 1 for a winding leaf; wind (NULL when no candidate is one): nreg x
     * ncand, that leaf's winding number in front of the region, MCI_WIND_UNKNOWN if not
     * known yet, and coin (the same size) how much more it is behind the region (not 0
     * where the region lies in that leaf's surface); own_front (NULL unless this leaf is
     * one): per region, this leaf's winding number in front of it, or MCI_WIND_UNKNOWN;
     * own_coin: how much more it is behind (1 unless other faces of the leaf lie in the
     * region, as when a triangle is listed twice); own_first: the region's shell is the
     * lowest group among those whose faces lie in it facing the same way (of coincident
     * pieces that bound the solid, only that one is output). */
    uint8_t *cand_winding;
    int32_t *wind, *coin;
    int32_t *own_front, *own_coin;
    uint8_t *own_first;
    uint8_t *needed;  /* per candidate: in a subtree of the trimmed CSGlist */
    mci_csg_entry *list; /* the CSGlist, trimmed by the labels known for the whole leaf */
    size_t nlist;
    bool rejected;    /* the trimmed CSGlist drops every face of the leaf */
    mci_blist blist;  /* the trimmed CSGlist compiled for IN/OUT labels (paper §5.4) */
    uint32_t *blist_slot; /* per blist step: the candidate slot of the leaf it reads */
    mci_ray_scratch ray;
    bool out_of_memory; /* set by a ray test that could not allocate */
    mci_label *scratch, *leaf_labels;
    const uint32_t *copies; /* leaves that are copies of this one (see eval.c) ... */
    size_t ncopies;
    mci_csg_entry **copy_list; /* ... their trimmed CSGlists */
    size_t *copy_nlist;
    uint8_t *borrowed;    /* per candidate: a copy of another leaf, labelled as that one */
    mci_kept *kept_all;   /* per leaf: the kept triangles (copies' too) */
    uint32_t *stacked;    /* a winding leaf's faces whose arrangement took a coplanar
                             face, ascending, then room for as many (mci_leaf_select);
                             NULL otherwise */
    int8_t *stacked_facing; /* room for nstacked (mci_leaf_coincident_faces) */
    size_t nstacked;
    /* With stacked: per face of the leaf (from face_base), its sheet's key: faces joined
     * across edges to a neighbour in their plane facing their way (a flat region, whose
     * inner borders are no constraints) share the least (group << 32 | face) among
     * them. Which coincident sheet comes first is decided by these keys, constant over
     * a sheet (a shell crossing itself has a group per face). */
    uint64_t *sheet_key;
    mci_classify_stats *stats;
    mcsg_error *err;
} mci_leaf_work;

/* The point of vertex i of piece p. */
static inline void mci_leaf_piece_point(const mci_leaf_work *w, size_t p, int i, mci_point *out)
{
    const mci_face_arr *arr = mci_scene_arr_of_face(w->s, w->pface[p]);
    if (arr) {
        *out = *arr->points[w->plocal[3 * p + i]];
    } else {
        const mcsg_mesh *m = w->s->octree.leaves[w->leaf];
        mci_point_explicit(out, m->vertices + 3 * (size_t)w->plocal[3 * p + i]);
    }
}

static inline uint32_t mci_leaf_slot_from(const mci_leaf_work *w, size_t slot)
{
    return w->pv[slot];
}

static inline uint32_t mci_leaf_slot_to(const mci_leaf_work *w, size_t slot)
{
    return w->pv[slot - slot % 3 + (slot % 3 + 1) % 3];
}

/* Index of the first separator entry with this key, or nsep. */
static inline size_t mci_leaf_find_separator(const mci_leaf_work *w, uint64_t key)
{
    return mci_find_key(w->sep, w->nsep, key);
}

/* Region r's label with respect to candidate c by a ray from v (and its winding number
 * for a winding leaf); the label stays UNKNOWN when v lies on that leaf's surface. False
 * when out of memory. */
bool mci_leaf_label_by_ray(mci_leaf_work *w, uint32_t r, size_t c, const mci_point *v);

/* The region's labels still unknown (only those of winding leaves if winding_only), by
 * rays from a point strictly inside one of its pieces: where every vertex of a region lies
 * on a leaf's surface, the inside of a piece still tells (or, for a winding leaf, tells
 * the numbers on both sides of a piece lying in that surface). False when nothing was
 * learnt (w->out_of_memory set when out of memory). */
bool mci_leaf_labels_from_inside(mci_leaf_work *w, uint32_t r, bool winding_only);

/* The faces of this winding leaf that may lie where face f does: in w->stacked, in f's
 * plane, with boxes meeting f's; facing[i] 1 where faces[i] faces f's way, -1 where it
 * faces the other. Both have room for w->nstacked; returns how many. */
size_t mci_leaf_coincident_faces(const mci_leaf_work *w, uint32_t f, uint32_t *faces,
                                 int8_t *facing);
/* The stack piece p lies in, from those faces (faces[0 .. n) of its face f): *coin, how
 * much more the leaf's winding number is behind p than in front (1 for f, plus one for
 * each face holding p that faces its way, less one for each facing the other), and
 * *first, whether no face holding p faces its way in a lower sheet (sheet_key; of one
 * sheet overlapping itself, a lower face). A face holds p where
 * its triangle holds the points of p next to p's first corner (a symbolic point, never
 * on a face's border: a border between two faces of one flat region is no constraint,
 * and may cross p). */
void mci_leaf_piece_stack(const mci_leaf_work *w, size_t p, const uint32_t *faces,
                          const int8_t *facing, size_t n, int32_t *coin, bool *first);

/* Winding numbers (classify_winding.c). */
#define MCI_WIND_UNKNOWN INT32_MIN

/* own_front[r], own_coin[r] and own_first[r] by a ray from a point inside one of region
 * r's pieces; false when no piece gives a point whose ray decides (w->out_of_memory set
 * when out of memory). */
bool mci_leaf_own_seed(mci_leaf_work *w, uint32_t r);
/* The label of a region with the winding numbers behind and in front of it. */
mci_label mci_label_of_windings(int32_t behind, int32_t in_front);
/* A winding leaf's numbers across a separator on its surface, summed over the shells
 * that hold it: how much the number in front of the region grows from the region before
 * (`front`), and how much the excess behind it over in front does (`coincident`: a
 * region lying in a shell has one more, or one less, behind). */
typedef struct mci_wind_sum {
    int32_t front, coincident;
    bool unknown;
    bool coplanar; /* a region on either side lies in a face of that leaf */
} mci_wind_sum;
/* Adds one shell holding the separator, with the local labels of the region before and
 * of the region after with respect to it. */
void mci_wind_sheet(mci_wind_sum *sum, mci_label from_local, mci_label to_local);
/* A point strictly inside piece p: where a line through a point of its corners'
 * approximate triangle (the centroid for attempt 0, other weights for the others, up to
 * MCI_INSIDE_ATTEMPTS), along its face's approximate normal, pierces the face's plane
 * (an LPI of input vertices: `ends` holds the line's two ends, and *plane the face's
 * plane, which the point refers to). False when the doubles do not give a line crossing
 * the plane or a point strictly inside (slivers). */
#define MCI_INSIDE_WEIGHTED 4
#define MCI_INSIDE_ATTEMPTS (MCI_INSIDE_WEIGHTED + 96)
/* The same for the triangle with corners c[0..2] (input vertices or implicit points)
 * lying in `plane`: a point strictly inside it where the line through a point of the
 * corners' approximate triangle along the plane's approximate normal pierces the plane
 * (an LPI of input vertices; `ends` holds the line's two ends, which *out refers to).
 * The last of the first MCI_INSIDE_WEIGHTED attempts also searches a sliver narrower
 * than the spacing of doubles (a line from next to its long edge to a far end moved a
 * unit at a time). The 96 after them look next to a corner that is an input vertex (by
 * angle, largest first) in 16 directions at two distances, for a triangle thinner still
 * (a corner nearly on the line through the others, far below the spacing of doubles).
 * A plane whose normal rounds to zero in doubles is crossed along its projection axis.
 * False when no point strictly inside was found. */
bool mci_point_inside_triangle(const mci_point c[3], const mci_plane *plane, int attempt,
                               double ends[2][3], mci_point *out);
bool mci_leaf_piece_inside(const mci_leaf_work *w, size_t p, int attempt, double ends[2][3],
                           mci_point *out, mci_plane *plane);

/* How faces f and g lie: 0 in different planes, 1 in one plane facing the same way, -1
 * in one plane facing opposite ways (classify_regions.c). */
int mci_leaf_plane_relation(const mci_leaf_work *w, uint32_t f, uint32_t g);

mcsg_status mci_leaf_regions(mci_leaf_work *w);
mcsg_status mci_leaf_trim(mci_leaf_work *w);
mcsg_status mci_leaf_label(mci_leaf_work *w);
mcsg_status mci_leaf_select(mci_leaf_work *w);

#endif
