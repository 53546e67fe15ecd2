/* Exercise 19 — BVH leaf re-indexing (deck 001, "After re-indexing
 * (sorting) based on leaf nodes"): reference solution.  One pass over
 * the nodes in layout order; a running count of the references placed
 * so far is each leaf's new first. */
#include "sidx/sidx.h"
#include "sidx/bvh.h"

uint32_t bvh_reindex(sidx_bvh_node *nodes, uint32_t num_nodes, const uint32_t *lists, uint32_t *prims)
{
    uint32_t placed = 0;
    for (uint32_t i = 0; i < num_nodes; ++i) {
        sidx_bvh_node *n = &nodes[i];
        if (!sidx_bvh_is_leaf(n)) continue;
        const uint32_t from = n->left_or_first, count = sidx_bvh_count(n);
        for (uint32_t k = 0; k < count; ++k) prims[placed + k] = lists[from + k];
        n->left_or_first = placed;
        placed += count;
    }
    return placed;
}
