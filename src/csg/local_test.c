/*
 * The exact local test at a separator (paper Prop. 2 with an exact test instead of a BSP
 * per face): the label of a piece with respect to the leaf whose surface holds one of
 * its edges, from the side of the piece's far vertex against the face(s) of that leaf
 * containing the edge, a wedge test where the edge lies along an edge of that leaf, and
 * SAME / OPPO by orientation where the piece lies in that leaf's face.
 */
#include "csg/local_test.h"

/* The edges of a triangle a point lies on, as a bit set. */
static int edges_through(mci_containment c, int which)
{
    if (c == MCI_ON_EDGE)
        return 1 << which;
    if (c == MCI_ON_VERTEX)
        return 1 << which | 1 << ((which + 2) % 3);
    return 0;
}

/* SAME or OPPO for a piece of face arrangement fa lying on the coplanar face h. */
static mci_label coplanar_label(const mci_face_arr *fa, const mci_plane *h)
{
    mci_point a, b, c;
    mci_point_explicit(&a, h->a);
    mci_point_explicit(&b, h->b);
    mci_point_explicit(&c, h->c);
    return mci_orient2d_projected(&a, &b, &c, fa->axis) == fa->sign ? MCI_LABEL_SAME
                                                                    : MCI_LABEL_OPPO;
}

static mci_label one_face_label(int side, const mci_face_arr *fa, const mci_plane *h)
{
    return side > 0 ? MCI_LABEL_OUT : side < 0 ? MCI_LABEL_IN : coplanar_label(fa, h);
}

/* Side of the third corner of face h2 (the one off the plane, if any) w.r.t. h. */
static int bend(const mci_scene *s, uint32_t h2, const mci_plane *h)
{
    for (int k = 0; k < 3; k++) {
        mci_point q;
        int side;
        mci_point_explicit(&q, mci_scene_corner(s, h2, k));
        if ((side = mci_orient3d(&q, h)) != 0)
            return side;
    }
    return 0;
}

/* Two faces h1, h2 of a leaf meet at the edge; the leaf's interior is below both
 * (convex edge) or below either (reflex edge). s1, s2: sides of the piece's far vertex. */
static mci_label wedge_label(int convex, int s1, int s2, const mci_face_arr *fa,
                             const mci_plane *h1, const mci_plane *h2)
{
    if (convex) {
        if (s1 == 0)
            return s2 < 0 ? coplanar_label(fa, h1) : MCI_LABEL_OUT;
        if (s2 == 0)
            return s1 < 0 ? coplanar_label(fa, h2) : MCI_LABEL_OUT;
        return s1 < 0 && s2 < 0 ? MCI_LABEL_IN : MCI_LABEL_OUT;
    }
    if (s1 == 0)
        return s2 > 0 ? coplanar_label(fa, h1) : MCI_LABEL_IN;
    if (s2 == 0)
        return s1 > 0 ? coplanar_label(fa, h2) : MCI_LABEL_IN;
    return s1 > 0 && s2 > 0 ? MCI_LABEL_OUT : MCI_LABEL_IN;
}

/* Label of a piece of face arrangement fa with respect to the leaf of face h, where the
 * piece's edge x-y lies in the closed face h and w is the piece's third vertex. The
 * piece's interior does not meet that leaf's surface (or lies in it), so the side of w
 * near the edge decides. *partner (if not NULL): the face across the edge of h that the
 * test took as the other half of the wedge, or MCI_NONE. */
mci_label mci_local_label(const mci_scene *s, const mci_face_arr *fa, const mci_point *x,
                          const mci_point *y, const mci_point *w, uint32_t h, uint32_t *partner)
{
    mci_plane p1, p2;
    int wx, wy, common, side1, c;
    uint32_t h2 = MCI_NONE;
    mci_containment cx, cy;
    mci_scene_face_plane(s, h, &p1);
    cx = mci_point_in_triangle(x, &p1, &wx);
    cy = mci_point_in_triangle(y, &p1, &wy);
    if (partner)
        *partner = MCI_NONE;
    if (cx == MCI_OUTSIDE || cy == MCI_OUTSIDE)
        return MCI_LABEL_UNKNOWN;
    common = edges_through(cx, wx) & edges_through(cy, wy);
    if (common)
        h2 = s->neighbour[3 * (size_t)h + (common & 1 ? 0 : common & 2 ? 1 : 2)];
    if (partner)
        *partner = h2;
    side1 = mci_orient3d(w, &p1);
    if (h2 == MCI_NONE || (c = bend(s, h2, &p1)) == 0)
        return one_face_label(side1, fa, &p1);
    mci_scene_face_plane(s, h2, &p2);
    return wedge_label(c < 0, side1, mci_orient3d(w, &p2), fa, &p1, &p2);
}
