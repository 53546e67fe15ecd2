/* fuzz_ply.c — libFuzzer target: the PLY parser (ascii and binary) on
 * arbitrary bytes.  Same contract as fuzz_obj.c. */
#include <stdint.h>
#include <stdlib.h>
#include "sidx/sidx.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sidx_mesh m;
    sidx_error err;
    if (sidx_mesh_parse_ply(data, size, "fuzz.ply", &m, &err) == SIDX_OK) {
        if (sidx_mesh_validate(&m, NULL) != SIDX_OK) abort();
        sidx_mesh_free(&m);
    }
    return 0;
}
