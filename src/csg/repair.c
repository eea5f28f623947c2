/*
 * mcsg_mesh_repair: one mesh's solid by winding number, evaluated as the only leaf of a
 * tree (eval.c does the work: shells of the leaf are intersected with each other and
 * classified by winding numbers), then the result's shells counted with their
 * orientation.
 */
#include "base/core.h"
#include "csg/reevaluate.h"
#include "mesh/validate.h"

#include <string.h>

/* The result's shells, and how many of them face inward (negative exact volume). */
static mcsg_status count_shells(const mci_ctx *ctx, const mcsg_mesh *out, mcsg_repair_stats *st,
                                mcsg_error *err)
{
    mcsg_check_report report;
    uint32_t *shell = mci_malloc_array(ctx, out->triangle_count + 1, sizeof *shell);
    uint32_t *which = mci_malloc_array(ctx, out->triangle_count + 1, sizeof *which);
    mcsg_status s = shell && which ? mci_mesh_check_shells(ctx, out, &report, shell, NULL, NULL, err)
                                   : mci_fail_nomem(err, "counting the result's shells");
    st->shells_out = s == MCSG_OK ? report.components : 0;
    for (uint32_t k = 0; s == MCSG_OK && st->shells_out > 1 && k < st->shells_out; k++) {
        size_t n = 0;
        for (size_t t = 0; t < out->triangle_count; t++)
            if (shell[t] == k)
                which[n++] = (uint32_t)t;
        st->cavities += mci_triangles_volume_sign(out->vertices, out->triangles, which, n,
                                                  NULL) < 0;
    }
    mci_free(ctx, shell);
    mci_free(ctx, which);
    return s;
}

mcsg_status mcsg_mesh_repair(const mcsg_mesh *mesh, const mcsg_options *opts, mcsg_mesh *out,
                             mcsg_repair_stats *stats, mcsg_error *err)
{
    mci_ctx ctx;
    mcsg_options checked;
    mcsg_tree *tree = NULL;
    mcsg_check_report report;
    mcsg_repair_stats st;
    mcsg_status s;
    memset(&st, 0, sizeof st);
    if (out)
        memset(out, 0, sizeof *out);
    if (!mesh || !out)
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "mcsg_mesh_repair: NULL %s",
                        mesh ? "out" : "mesh");
    mci_ctx_init(&ctx, opts);
    if (opts)
        checked = *opts;
    else
        memset(&checked, 0, sizeof checked);
    checked.check_self_intersections = 1; /* a shell crossing itself is named, not guessed */
    s = mcsg_mesh_check(mesh, opts, &report, err);
    st.shells_in = s == MCSG_OK ? report.components : 0;
    if (s == MCSG_OK)
        s = mci_tree_of_one_mesh(opts, mesh, "the mesh", &tree, err);
    if (s == MCSG_OK)
        s = mcsg_eval(tree, &checked, out, NULL, &st.eval, err);
    st.crossing_pairs = st.eval.intersect.intersecting_pairs + st.eval.intersect.coplanar_pairs;
    if (s == MCSG_OK)
        s = count_shells(&ctx, out, &st, err);
    mcsg_tree_free(tree);
    if (s != MCSG_OK)
        mcsg_mesh_free(out, opts);
    if (stats)
        *stats = st;
    return s;
}
