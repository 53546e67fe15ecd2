/* Exercise 11 — the recursive BVH build (deck 001, "BVH Partitioning",
 * "Recurse with each child node", "Edge Cases"): reference solution.
 * Nodes are written in pre-order, each in the slot it takes before its
 * children are built, so the left child is always the next node. */
#include "sidx/sidx.h"
#include "sidx/bvh.h"

uint32_t bvh_build(sidx_bvh_node *nodes, uint32_t *num_nodes, uint32_t *prims, uint32_t first, uint32_t count,
                   const sidx_aabb *boxes, const sidx_vec3 *cents, uint32_t leaf_size, uint32_t max_leaf)
{
    const uint32_t ni = (*num_nodes)++;
    sidx_bvh_node *n = &nodes[ni];
    sidx_aabb bb = sidx_aabb_empty(), cb = sidx_aabb_empty();
    for (uint32_t i = first; i < first + count; ++i) {
        bb = sidx_aabb_union(bb, boxes[prims[i]]);
        cb = sidx_aabb_grow(cb, cents[prims[i]]);
    }
    n->bmin[0] = bb.min.x;
    n->bmin[1] = bb.min.y;
    n->bmin[2] = bb.min.z;
    n->bmax[0] = bb.max.x;
    n->bmax[1] = bb.max.y;
    n->bmax[2] = bb.max.z;
    int axis = 0;
    uint32_t nl = 0;
    if (count <= leaf_size) {
        /* few enough: a leaf */
    } else if (!(cb.max.x > cb.min.x) && !(cb.max.y > cb.min.y) && !(cb.max.z > cb.min.z)) {
        if (count > max_leaf) nl = count / 2; /* same centroids: halve the range as it stands */
    } else {
        axis = sidx_aabb_max_axis(cb);
        const float pos = 0.5f * (sidx_v3_get(cb.min, axis) + sidx_v3_get(cb.max, axis));
        uint32_t i = first, j = first + count;
        while (i < j) {
            const uint32_t id = prims[i];
            if (sidx_v3_get(cents[id], axis) < pos) {
                ++i;
            } else {
                prims[i] = prims[--j];
                prims[j] = id;
            }
        }
        nl = i - first;
    }
    if (nl == 0) {
        n->left_or_first = first;
        n->count_axis = count;
        return ni;
    }
    bvh_build(nodes, num_nodes, prims, first, nl, boxes, cents, leaf_size, max_leaf);
    const uint32_t right =
        bvh_build(nodes, num_nodes, prims, first + nl, count - nl, boxes, cents, leaf_size, max_leaf);
    n->left_or_first = right;
    n->count_axis = (uint32_t)axis << 30;
    return ni;
}
