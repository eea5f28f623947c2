/*
 * Leaf bounding boxes, and the pairs of them that meet, by one sweep over all boxes
 * sorted by low x (a flat tree of thousands of operands would make a test of every box
 * per leaf quadratic).
 */
#include "csg/leaf_boxes.h"
#include "base/sort.h"
#include "base/sort_template.h"

#include <stdlib.h>
#include <string.h>

void mci_leaf_box(const mcsg_mesh *m, double box[6])
{
    for (int k = 0; k < 3; k++) {
        box[k] = m->vertex_count ? m->vertices[k] : 0;
        box[3 + k] = box[k];
    }
    for (size_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            double x = m->vertices[3 * v + k];
            box[k] = x < box[k] ? x : box[k];
            box[3 + k] = x > box[3 + k] ? x : box[3 + k];
        }
}

typedef struct box_end {
    double lo;      /* the box's low x */
    uint32_t index;
} box_end;

static inline bool box_end_less(const box_end *a, const box_end *b)
{
    return a->lo != b->lo ? a->lo < b->lo : a->index < b->index;
}

MCI_DEFINE_SORT(sort_box_ends, box_end, box_end_less)

static bool yz_meet(const double a[6], const double b[6])
{
    return !(a[4] < b[1] || b[4] < a[1] || a[5] < b[2] || b[5] < a[2]);
}

/* A sweep along x over the boxes sorted by low x, each pair within the x range tested
 * on y and z: `fill` false counts each box's overlaps into start[i + 1], true writes
 * them where start[] (advanced) says. */
static void sweep_box_pairs(const double (*box)[6], const box_end *order, size_t n,
                            uint32_t *start, uint32_t *list, bool fill)
{
    for (size_t i = 0; i < n; i++) {
        uint32_t a = order[i].index;
        for (size_t k = i + 1; k < n && order[k].lo <= box[a][3]; k++) {
            uint32_t b = order[k].index;
            if (!yz_meet(box[a], box[b]))
                continue;
            if (fill) {
                list[start[a]++] = b;
                list[start[b]++] = a;
            } else {
                start[a + 1]++;
                start[b + 1]++;
            }
        }
    }
}

/* Once per evaluation instead of every box against every other per leaf: a plate minus
 * thousands of holes tested millions of pairs of boxes in each of two passes. */
bool mci_box_overlaps(const mci_ctx *ctx, const double (*box)[6], size_t n, uint32_t **start,
                      uint32_t **list)
{
    box_end *order = mci_malloc_array(ctx, n + 1, sizeof *order);
    uint32_t *at = mci_calloc_array(ctx, n + 1, sizeof *at);
    bool ok = order && at;
    *start = mci_calloc_array(ctx, n + 1, sizeof **start);
    *list = NULL;
    ok = ok && *start;
    for (size_t i = 0; ok && i < n; i++)
        order[i] = (box_end){box[i][0], (uint32_t)i};
    if (ok) {
        sort_box_ends(order, n);
        sweep_box_pairs(box, order, n, *start, NULL, false);
        for (size_t i = 0; i < n; i++)
            (*start)[i + 1] += (*start)[i];
        ok = (*list = mci_malloc_array(ctx, (size_t)(*start)[n] + 1, sizeof **list)) != NULL;
    }
    if (ok) {
        memcpy(at, *start, n * sizeof *at);
        sweep_box_pairs(box, order, n, at, *list, true);
        for (size_t i = 0; i < n; i++)
            mci_sort_u32(*list + (*start)[i], (*start)[i + 1] - (*start)[i]);
    }
    mci_free(ctx, order);
    mci_free(ctx, at);
    if (!ok) {
        mci_free(ctx, *start);
        mci_free(ctx, *list);
        *start = *list = NULL;
    }
    return ok;
}
