/*
 * libFuzzer target for the STL readers (with ASCII/binary detection) and writers:
 * LLVMFuzzerTestOneInput reads the input with MCSG_FORMAT_AUTO and the name "x.stl", so
 * that detection is fuzzed too. Whenever that succeeds and detection chose STL at all
 * (content magic can pick PLY or OFF first), the mesh is written back in the STL flavour
 * the size rule selects (binary when the size is 84 + 50 * count, else ASCII), read
 * again and must come back identical (bit for bit; NaN equals NaN), else abort().
 * Replayed over fuzz/corpus/stl/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_mesh_common.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The binary STL size rule: 84 + 50 * (uint32 LE count at byte 80). */
static int binary_sized(const uint8_t *data, size_t size)
{
    uint64_t count;
    if (size < 84)
        return 0;
    count = (uint64_t)data[80] | (uint64_t)data[81] << 8 | (uint64_t)data[82] << 16 |
            (uint64_t)data[83] << 24;
    return (uint64_t)size - 84 == 50 * count;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    mcsg_format flavour = binary_sized(data, size) ? MCSG_FORMAT_STL_BINARY
                                                   : MCSG_FORMAT_STL_ASCII;
    mcsg_mesh mesh, as_stl;
    int was_stl;
    if (mcsg_mesh_read_memory(data, size, MCSG_FORMAT_AUTO, "x.stl", NULL, &mesh, NULL) !=
        MCSG_OK)
        return 0;
    /* Did detection pick STL? Then an explicit STL read gives the same mesh. */
    was_stl = mcsg_mesh_read_memory(data, size, flavour, "x.stl", NULL, &as_stl, NULL) ==
                  MCSG_OK && meshes_identical(&mesh, &as_stl);
    if (was_stl)
        check_round_trip(&mesh, flavour, "again.stl");
    mcsg_mesh_free(&as_stl, NULL);
    mcsg_mesh_free(&mesh, NULL);
    return 0;
}
