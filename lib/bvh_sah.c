/* bvh_sah.c — the expected cost of a built binary BVH under the surface
 * area heuristic (deck 001 "Surface Area Heuristic"), the statistics'
 * sah_cost.  bvh_build.c fills it once a tree is built and again after a
 * refit, the reinsertion pass (bvh_optimize.c) after it has moved nodes;
 * a file of its own, so that the pass, which the build calls, does not
 * call back into the build for it. */
#include "bvh_internal.h"

/* Σ_inner C_trav·A(n)/A(root) + Σ_leaves C_tri·N·A(n)/A(root). */
double sidx__bvh_tree_sah(const bvh *b, float c_trav, float c_tri)
{
    if (b->num_nodes == 0) return 0.0;
    const double root = sidx_aabb_area(bvh_node_box(&b->nodes[0]));
    if (!(root > 0.0)) return (double)b->num_prims * c_tri;
    double s = 0.0;
    for (uint32_t i = 0; i < b->num_nodes; ++i) {
        const bvh_node *n = &b->nodes[i];
        const double ar = sidx_aabb_area(bvh_node_box(n)) / root;
        s += bvh_is_leaf(n) ? ar * c_tri * bvh_count(n) : ar * c_trav;
    }
    return s;
}
