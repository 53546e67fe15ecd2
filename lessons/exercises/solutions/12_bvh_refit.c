/* Exercise 12 — BVH refit (deck 001, "Primitive vs. Spatial": "Easier to
 * update (animation)"): reference solution.  Children follow their
 * parent in the array, so one backward pass refits both children of a
 * node before the node itself. */
#include "sidx/sidx.h"
#include "sidx/bvh.h"

void bvh_refit(sidx_bvh_node *nodes, uint32_t num_nodes, const uint32_t *prims, const sidx_mesh *mesh)
{
    for (uint32_t i = num_nodes; i-- > 0;) {
        sidx_bvh_node *n = &nodes[i];
        sidx_aabb bb = sidx_aabb_empty();
        if (sidx_bvh_is_leaf(n)) {
            for (uint32_t j = 0; j < sidx_bvh_count(n); ++j)
                for (int k = 0; k < 3; ++k) bb = sidx_aabb_grow(bb, sidx_mesh_vertex(mesh, prims[n->left_or_first + j], k));
        } else {
            bb = sidx_aabb_union(sidx_bvh_box(&nodes[i + 1]), sidx_bvh_box(&nodes[n->left_or_first]));
        }
        n->bmin[0] = bb.min.x;
        n->bmin[1] = bb.min.y;
        n->bmin[2] = bb.min.z;
        n->bmax[0] = bb.max.x;
        n->bmax[1] = bb.max.y;
        n->bmax[2] = bb.max.z;
    }
}
