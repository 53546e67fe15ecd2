/* A correct 19_bvh_reindex organised differently: a first pass gives
 * every leaf its new first from a running sum (the old firsts kept
 * aside), a second pass copies the blocks backwards from the last
 * leaf.  The result is the same layout, so it passes. */
#include <stdlib.h>
#include "sidx/sidx.h"
#include "sidx/bvh.h"

uint32_t bvh_reindex(sidx_bvh_node *nodes, uint32_t num_nodes, const uint32_t *lists, uint32_t *prims)
{
    uint32_t *old = malloc((num_nodes ? num_nodes : 1) * sizeof *old);
    if (!old) return 0;
    uint32_t total = 0;
    for (uint32_t i = 0; i < num_nodes; ++i) {
        old[i] = nodes[i].left_or_first;
        if (sidx_bvh_is_leaf(&nodes[i])) {
            nodes[i].left_or_first = total;
            total += sidx_bvh_count(&nodes[i]);
        }
    }
    for (uint32_t i = num_nodes; i-- > 0;) {
        if (!sidx_bvh_is_leaf(&nodes[i])) continue;
        for (uint32_t k = sidx_bvh_count(&nodes[i]); k-- > 0;)
            prims[nodes[i].left_or_first + k] = lists[old[i] + k];
    }
    free(old);
    return total;
}
