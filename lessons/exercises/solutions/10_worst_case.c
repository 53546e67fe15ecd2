/* Reference solution of 10_worst_case (deck 000, "Spatial index
 * structures": the private exercise). */
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"

void worst_case_scene(const char *structure, uint32_t n, sidx_mesh *out)
{
    float *xyz = malloc((size_t)n * 9 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * 3 * sizeof *idx);
    if (!xyz || !idx) {
        free(xyz);
        free(idx);
        return;
    }
    const int stadium = strcmp(structure, "grid") == 0;
    for (uint32_t i = 0; i < n; ++i) {
        float *v = xyz + 9 * i;
        const float s = (float)i / (float)n;
        if (stadium && i + 1 < n) { /* the teapot: n - 1 small triangles inside one cell */
            const float x = 0.01f * s, y = 0.01f * (1.0f - s);
            const float tri[9] = {x, y, 0, x + 0.001f, y, 0.001f, x, y + 0.001f, 0.002f};
            memcpy(v, tri, sizeof tri);
        } else if (stadium) { /* the stadium: one triangle far away */
            const float tri[9] = {100, 100, 100, 99, 100, 100, 100, 99, 100};
            memcpy(v, tri, sizeof tri);
        } else { /* a haystack: slivers from corner to corner, every box the whole scene */
            const float tri[9] = {0, 0, s, 1, 1, 1 - s, 1, 1 - 0.001f, 1 - s};
            memcpy(v, tri, sizeof tri);
        }
        for (int k = 0; k < 3; ++k) idx[3 * i + (uint32_t)k] = 3 * i + (uint32_t)k;
    }
    sidx_mesh_from_arrays(out, xyz, 3 * n, idx, n, NULL);
    free(xyz);
    free(idx);
}
