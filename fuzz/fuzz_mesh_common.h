/*
 * Shared by the mesh-format fuzz targets: bit-exact mesh comparison (NaN equals NaN)
 * and the write -> read -> compare round trip that every successful read must pass.
 */
#ifndef MESHCSG_FUZZ_MESH_COMMON_H
#define MESHCSG_FUZZ_MESH_COMMON_H

#include "meshcsg.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static int same_double(double a, double b)
{
    return (isnan(a) && isnan(b)) || memcmp(&a, &b, sizeof a) == 0;
}

static int meshes_identical(const mcsg_mesh *a, const mcsg_mesh *b)
{
    if (a->vertex_count != b->vertex_count || a->triangle_count != b->triangle_count)
        return 0;
    for (size_t i = 0; i < 3 * a->vertex_count; i++)
        if (!same_double(a->vertices[i], b->vertices[i]))
            return 0;
    return a->triangle_count == 0 ||
           memcmp(a->triangles, b->triangles, 3 * a->triangle_count * sizeof(uint32_t)) == 0;
}

/* Write `mesh` in `format`, read it back and abort unless it is identical. */
static void check_round_trip(const mcsg_mesh *mesh, mcsg_format format, const char *name)
{
    void *text = NULL;
    size_t text_size = 0;
    mcsg_mesh again;
    if (mcsg_mesh_write_memory(format, mesh, NULL, &text, &text_size, NULL) != MCSG_OK)
        abort();
    if (mcsg_mesh_read_memory(text, text_size, MCSG_FORMAT_AUTO, name, NULL, &again, NULL) !=
        MCSG_OK)
        abort();
    if (!meshes_identical(mesh, &again))
        abort();
    mcsg_mesh_free(&again, NULL);
    mcsg_free(text, NULL);
}

#endif
