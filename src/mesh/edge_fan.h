/*
 * The triangles around one edge, paired by angle (edge_fan.c): the rule by which the mesh
 * check pairs the triangles of an edge where a shell meets itself (mesh/validate.c), and
 * by which classification pairs the pieces of a leaf along an edge that more than two of
 * them share (csg/classify_regions.c).
 */
#ifndef MESHCSG_MESH_EDGE_FAN_H
#define MESHCSG_MESH_EDGE_FAN_H

#include <stddef.h>
#include <stdint.h>

enum { MCI_FAN_MAX = 64 };

/* The uses of an edge on the axis u -> v (input vertices): use i lies in the half-plane
 * bounded by the axis holding input vertex third[i] (off the axis), and runs from u to v
 * if forward[i]. */
typedef struct mci_edge_fan {
    const double *u, *v;
    const double *const *third;
    const uint8_t *forward;
    size_t n;
} mci_edge_fan;

/* Pairs the uses so that the winding numbers beside partners are equal on the sides
 * facing each other and on their other sides (their pieces may be joined into one
 * region): each use running from u to v with the one just before it in the turn, which
 * must run the other way (they bound one solid wedge). Uses in one half-plane (a sliver
 * folded flat, a face listed twice) may be taken in any order that makes directions
 * alternate. Where directions cannot alternate, uses in turn order are paired without
 * crossing (a stack: one running the other way than the top pairs with it), so that
 * the uses between two partners, either way round, are whole pairs; uses in one
 * half-plane are then taken in the sort's order, as if turned apart by an infinitesimal
 * angle: the sectors between them have no width, and the numbers there, which that
 * order makes up, bound nothing (classification does not join the pieces of a face that
 * lies on other faces to a face in another plane, csg/classify_regions.c). mate[i]: i's
 * partner.
 * Returns 0 when the fan has more than MCI_FAN_MAX uses or is unbalanced; 2 when paired
 * by the stack; else 1. Deterministic: the order depends on the uses' order and
 * coordinates only. */
int mci_pair_fan_by_angle(const mci_edge_fan *fan, uint8_t *mate);

#endif
