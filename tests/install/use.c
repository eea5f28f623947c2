/* A program built against an installed meshcsg (tests/install/run.sh): the public API
 * only, through the installed header. Evaluates a cube minus a sphere and checks the
 * result's volume against its exact value's neighbourhood (the sphere is a polyhedron
 * inscribed in r = 4, so its volume is below 4/3 pi r^3 and the result above
 * 1000 - 268.1). Exit status 0 when all is as expected. */
#include <meshcsg.h>
#include <stdio.h>
#include <string.h>

static const char scene[] =
    "difference() { cube(10, center = true); sphere(r = 4, $fn = 48); }";

int main(void)
{
    mcsg_tree *tree;
    mcsg_mesh result;
    mcsg_check_report report;
    mcsg_error err;
    char header[64];
    snprintf(header, sizeof header, "%d.%d.%d", MCSG_VERSION_MAJOR, MCSG_VERSION_MINOR,
             MCSG_VERSION_PATCH);
    if (strcmp(mcsg_version(), header) != 0) {
        fprintf(stderr, "library %s, header %s\n", mcsg_version(), header);
        return 1;
    }
    if (mcsg_scad_read_memory(scene, sizeof scene - 1, "scene", NULL, NULL, &tree, &err) !=
        MCSG_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    if (mcsg_eval(tree, NULL, &result, NULL, NULL, &err) != MCSG_OK) {
        fprintf(stderr, "%s\n", err.message);
        mcsg_tree_free(tree);
        return 1;
    }
    mcsg_tree_free(tree);
    if (mcsg_mesh_check(&result, NULL, &report, &err) != MCSG_OK) {
        fprintf(stderr, "%s\n", err.message);
        mcsg_mesh_free(&result, NULL);
        return 1;
    }
    mcsg_mesh_free(&result, NULL);
    printf("meshcsg %s: %zu triangles, volume %.6f, %zu boundary edges\n", mcsg_version(),
           report.triangle_count, report.volume, report.boundary_edges);
    return report.boundary_edges == 0 && report.components == 2 && report.volume > 731.9 &&
                   report.volume < 740.0
               ? 0
               : 1;
}
