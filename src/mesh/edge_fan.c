/*
 * Pairing by angle around one edge (see edge_fan.h). The half-plane predicates are exact
 * (exact/kernel.h), so the order, and the pairs, are too.
 */
#include "mesh/edge_fan.h"
#include "exact/kernel.h"

#include <stdbool.h>

/* Sorts order[0 .. n) by the angle of the uses' half-planes about the axis; tie[i] is set
 * when order[i] lies in the same half-plane as order[i - 1]. */
static void sort_by_angle(const mci_edge_fan *fan, uint8_t *order, bool *tie)
{
    const double *const *w = fan->third;
    for (size_t i = 0; i < fan->n; i++)
        order[i] = (uint8_t)i;
    for (size_t i = 1; i < fan->n; i++) /* insertion sort: n is small */
        for (size_t j = i; j > 0 && mci_half_plane_before(fan->u, fan->v, w[0], w[order[j]],
                                                         w[order[j - 1]]); j--) {
            uint8_t t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    tie[0] = false;
    for (size_t i = 1; i < fan->n; i++)
        tie[i] = mci_half_plane_class(fan->u, fan->v, w[order[i - 1]], w[order[i]]) == 0;
}

/* Reorders each run of ties in order[] so that directions alternate around the edge,
 * forward uses at positions of parity `phase`; false when a run holds the wrong number
 * of forward uses for that. */
static bool alternate_ties(const mci_edge_fan *fan, const bool *tie, int phase, uint8_t *order)
{
    for (size_t start = 0, end; start < fan->n; start = end) {
        uint8_t fwd[MCI_FAN_MAX], back[MCI_FAN_MAX];
        size_t nf = 0, nb = 0, wanted = 0;
        for (end = start + 1; end < fan->n && tie[end]; end++)
            ;
        for (size_t i = start; i < end; i++) {
            if (fan->forward[order[i]])
                fwd[nf++] = order[i];
            else
                back[nb++] = order[i];
            wanted += (i & 1) == (size_t)phase;
        }
        if (nf != wanted)
            return false;
        for (size_t i = start; i < end; i++)
            order[i] = (i & 1) == (size_t)phase ? fwd[--nf] : back[--nb];
    }
    return true;
}

/* Uses in turn order (ties in the order given) paired without crossing. Always succeeds
 * on a balanced fan. */
static void pair_neighbours(const mci_edge_fan *fan, const uint8_t *order, uint8_t *mate)
{
    uint8_t stack[MCI_FAN_MAX];
    size_t top = 0;
    for (size_t i = 0; i < fan->n; i++) {
        uint8_t here = order[i];
        if (top > 0 && fan->forward[stack[top - 1]] != fan->forward[here]) {
            uint8_t other = stack[--top];
            mate[here] = other, mate[other] = here;
        } else {
            stack[top++] = here;
        }
    }
}

int mci_pair_fan_by_angle(const mci_edge_fan *fan, uint8_t *mate)
{
    uint8_t order[MCI_FAN_MAX];
    bool tie[MCI_FAN_MAX];
    size_t forward = 0, n = fan->n;
    int phase = 0;
    for (size_t i = 0; i < n; i++)
        forward += fan->forward[i] != 0;
    if (n == 0 || n > MCI_FAN_MAX || 2 * forward != n)
        return 0;
    sort_by_angle(fan, order, tie);
    while (phase < 2 && !alternate_ties(fan, tie, phase, order))
        phase++;
    if (phase == 2) { /* ties, if any, in the sort's order: see edge_fan.h */
        pair_neighbours(fan, order, mate);
        return 2;
    }
    for (size_t i = 0; i < n; i++) {
        uint8_t here = order[i], before = order[(i + n - 1) % n];
        if (fan->forward[here])
            mate[here] = before, mate[before] = here;
    }
    return 1;
}
