/*
 * libFuzzer target for the OFF reader and writer: LLVMFuzzerTestOneInput reads the input
 * with MCSG_FORMAT_OFF; whenever that succeeds, the mesh is written back as OFF, read
 * again and must come back identical (bit for bit; NaN equals NaN), else abort().
 * Replayed over fuzz/corpus/off/ by CTest (fuzz/replay_main.c).
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
    if (mcsg_mesh_read_memory(data, size, MCSG_FORMAT_OFF, "fuzz.off", NULL, &mesh, NULL) !=
        MCSG_OK)
        return 0;
    check_round_trip(&mesh, MCSG_FORMAT_OFF, "again.off");
    mcsg_mesh_free(&mesh, NULL);
    return 0;
}
