/* bvh_obb.c — the deck's oriented-box BVH ("Axis-Aligned BVH ... How do we
 * make a non-axis-aligned BVH?").
 *
 * Topology comes from the binned SAH builder; afterwards every node gets
 * an oriented box fitted to the vertices below it: axes from the principal
 * components of the points (sidx_obb_fit, PCA), extents from projecting
 * them.  Traversal then tests these boxes instead of the AABBs.  The deck's
 * trade-off, measured in the report: a tighter box lowers the hit
 * probability A_child/A_parent, but each test costs more (C_trav rises)
 * and each node needs 60 more bytes.
 *
 * PCA is not the optimal box: for axis-aligned content (Cornell box walls)
 * its axes can come out rotated and the box larger than the AABB.  A node
 * therefore keeps whichever of the two has the smaller surface area — the
 * AABB expressed as an oriented box with identity axes. */
#include "bvh_internal.h"

/* The leftmost leaf's first primitive and the rightmost leaf's end give a
 * node's primitive range: leaves are contiguous in pre-order, so every
 * subtree owns one contiguous run of tris[].  O(depth) per node and no
 * extra memory, which lets refit reuse this without allocating. */
static void subtree_range(const bvh *b, uint32_t i, uint32_t *first, uint32_t *count)
{
    uint32_t l = i, r = i;
    while (!bvh_is_leaf(&b->nodes[l])) l = l + 1;
    while (!bvh_is_leaf(&b->nodes[r])) r = b->nodes[r].left_or_first;
    *first = b->nodes[l].left_or_first;
    *count = b->nodes[r].left_or_first + bvh_count(&b->nodes[r]) - *first;
}

/* Projections of the points on each axis, padded.  The traversal computes
 * axis·o + t·axis·d in float; its error grows with the size of the scene
 * (and the distance of the origin), not with the node, so the padding is
 * an absolute one tied to the scene's extent (b->obb_pad) — a small node
 * near a large coordinate would otherwise leak rays through its edges. */
static void project(const sidx_vec3 *p, uint32_t n, bvh_obb *o, float pad)
{
    for (int k = 0; k < 3; ++k) {
        float lo = INFINITY, hi = -INFINITY;
        for (uint32_t i = 0; i < n; ++i) {
            const float d = sidx_v3_dot(o->axis[k], p[i]);
            lo = d < lo ? d : lo;
            hi = d > hi ? d : hi;
        }
        o->lo[k] = lo - pad;
        o->hi[k] = hi + pad;
    }
}

static float slab_area(const bvh_obb *o)
{
    const float x = o->hi[0] - o->lo[0], y = o->hi[1] - o->lo[1], z = o->hi[2] - o->lo[2];
    return 2.0f * (x * y + y * z + z * x);
}

sidx_status sidx__bvh_fit_obbs(const sidx_accel *a, bvh *b)
{
    if (b->num_nodes == 0) return SIDX_OK;
    if (!b->obbs) {
        b->obbs = sidx__alloc(a, b->num_nodes, sizeof *b->obbs);
        if (!b->obbs) return SIDX_ERR_NOMEM;
    }
    /* 2⁻¹⁴ of the scene's largest coordinate: ~500 ulps, far above the
     * few ulps of rounding in the traversal's dot products, far below any
     * visible loosening of the boxes. */
    const sidx_aabb root = bvh_node_box(&b->nodes[0]);
    float mag = 0.0f;
    for (int k = 0; k < 3; ++k) {
        const float lo = fabsf(sidx_v3_get(root.min, k)), hi = fabsf(sidx_v3_get(root.max, k));
        mag = lo > mag ? lo : mag;
        mag = hi > mag ? hi : mag;
    }
    b->obb_pad = mag * (1.0f / 16384.0f) + FLT_MIN;
    for (uint32_t i = 0; i < b->num_nodes; ++i) {
        uint32_t first, count;
        subtree_range(b, i, &first, &count);
        const sidx_vec3 *p = b->tris[first].v; /* 3·count packed vertices */
        const uint32_t np = 3u * count;
        bvh_obb aligned = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0, 0, 0}, {0, 0, 0}};
        project(p, np, &aligned, b->obb_pad);
        sidx_obb fit;
        bvh_obb pca = aligned;
        if (sidx_obb_fit(p, np, &fit) == SIDX_OK) {
            for (int k = 0; k < 3; ++k) pca.axis[k] = fit.axis[k];
            project(p, np, &pca, b->obb_pad);
        }
        b->obbs[i] = slab_area(&pca) < slab_area(&aligned) ? pca : aligned;
    }
    return SIDX_OK;
}
