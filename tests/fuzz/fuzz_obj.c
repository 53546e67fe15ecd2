/* fuzz_obj.c — libFuzzer target: the OBJ parser on arbitrary bytes.
 * Must never crash, leak or read out of bounds; on success the mesh must
 * validate (every index in range, every coordinate finite). */
#include <stdint.h>
#include <stdlib.h>
#include "sidx/sidx.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sidx_mesh m;
    sidx_error err;
    if (sidx_mesh_parse_obj((const char *)data, size, "fuzz.obj", &m, &err) == SIDX_OK) {
        if (sidx_mesh_validate(&m, NULL) != SIDX_OK) abort();
        sidx_mesh_free(&m);
    }
    return 0;
}
