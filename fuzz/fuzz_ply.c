/*
 * libFuzzer target for the PLY reader and writers: LLVMFuzzerTestOneInput reads the
 * input as PLY (the header picks the encoding); whenever that succeeds, the mesh is
 * written back in each of the three PLY encodings, read again and must come back
 * identical (bit for bit; NaN equals NaN), else abort(). Replayed over fuzz/corpus/ply/
 * by CTest (fuzz/replay_main.c).
 */
#include "fuzz_mesh_common.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const mcsg_format encodings[] = {MCSG_FORMAT_PLY_ASCII, MCSG_FORMAT_PLY_BINARY_LE,
                                            MCSG_FORMAT_PLY_BINARY_BE};
    mcsg_mesh mesh;
    if (mcsg_mesh_read_memory(data, size, MCSG_FORMAT_PLY_ASCII, "fuzz.ply", NULL, &mesh,
                              NULL) != MCSG_OK)
        return 0;
    for (size_t i = 0; i < sizeof encodings / sizeof encodings[0]; i++)
        check_round_trip(&mesh, encodings[i], "again.ply");
    mcsg_mesh_free(&mesh, NULL);
    return 0;
}
