/* Reference solution of 16_kd_termination (deck 000, "Termination
 * Criteria": "threshold of cost improvement — but stretch decision over
 * multiple levels"; pbrt's badRefines). */
#include "sidx/sidx.h"

int kd_terminate(uint32_t n, uint32_t depth, float best_cost, float c_tri, uint32_t leaf_size, uint32_t max_depth,
                 uint32_t *bad)
{
    if (n == 0) return SIDX_LEAF_EMPTY;
    if (n <= leaf_size) return SIDX_LEAF_FEW_PRIMS;
    if (depth >= max_depth) return SIDX_LEAF_MAX_DEPTH;
    if (best_cost == INFINITY) return SIDX_LEAF_NO_SPLIT;
    const float leaf_cost = c_tri * (float)n;
    if (best_cost >= leaf_cost) {
        ++*bad;
        if (*bad >= 3 || (best_cost > 4.0f * leaf_cost && n < 16)) return SIDX_LEAF_NO_GAIN;
    }
    return SIDX_LEAF_NONE;
}
