/*
 * libFuzzer target for the OBJ reader and writer: LLVMFuzzerTestOneInput reads the input
 * with MCSG_FORMAT_OBJ; whenever that succeeds, the mesh is written back as OBJ, read
 * again and must come back identical (bit for bit; NaN equals NaN), else abort().
 * Replayed over fuzz/corpus/obj/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_mesh_common.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    mcsg_mesh mesh;
    if (mcsg_mesh_read_memory(data, size, MCSG_FORMAT_OBJ, "fuzz.obj", NULL, &mesh, NULL) !=
        MCSG_OK)
        return 0;
    check_round_trip(&mesh, MCSG_FORMAT_OBJ, "again.obj");
    mcsg_mesh_free(&mesh, NULL);
    return 0;
}
