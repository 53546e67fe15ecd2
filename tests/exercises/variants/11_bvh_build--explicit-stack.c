/* A correct variant of 11_bvh_build with no recursion: a stack of
 * (parent, first, count) ranges, the left range popped first so that
 * nodes still take their slots in pre-order; a right child, when it
 * takes its slot, writes its index into its parent.  It must pass. */
#include "sidx/sidx.h"
#include "sidx/bvh.h"

typedef struct range {
    uint32_t parent, first, count; /* parent: UINT32_MAX for the subtree's root or a left child */
} range;

uint32_t bvh_build(sidx_bvh_node *nodes, uint32_t *num_nodes, uint32_t *prims, uint32_t first, uint32_t count,
                   const sidx_aabb *boxes, const sidx_vec3 *cents, uint32_t leaf_size, uint32_t max_leaf)
{
    range stack[256];
    int top = 0;
    const uint32_t root = *num_nodes;
    stack[top++] = (range){UINT32_MAX, first, count};
    while (top > 0) {
        const range r = stack[--top];
        const uint32_t ni = (*num_nodes)++;
        if (r.parent != UINT32_MAX) nodes[r.parent].left_or_first = ni;
        sidx_aabb bb = sidx_aabb_empty(), cb = sidx_aabb_empty();
        for (uint32_t i = 0; i < r.count; ++i) {
            bb = sidx_aabb_union(bb, boxes[prims[r.first + i]]);
            cb = sidx_aabb_grow(cb, cents[prims[r.first + i]]);
        }
        sidx_bvh_node *n = &nodes[ni];
        n->bmin[0] = bb.min.x, n->bmin[1] = bb.min.y, n->bmin[2] = bb.min.z;
        n->bmax[0] = bb.max.x, n->bmax[1] = bb.max.y, n->bmax[2] = bb.max.z;
        const sidx_vec3 e = sidx_aabb_extent(cb);
        uint32_t nl = 0;
        int axis = 0;
        if (r.count > leaf_size && e.x <= 0.0f && e.y <= 0.0f && e.z <= 0.0f) {
            if (r.count > max_leaf) nl = r.count / 2;
        } else if (r.count > leaf_size) {
            axis = sidx_aabb_max_axis(cb);
            const float pos = 0.5f * (sidx_v3_get(cb.min, axis) + sidx_v3_get(cb.max, axis));
            uint32_t i = r.first, j = r.first + r.count;
            while (i < j) {
                const uint32_t id = prims[i];
                if (sidx_v3_get(cents[id], axis) < pos) {
                    ++i;
                } else {
                    prims[i] = prims[--j];
                    prims[j] = id;
                }
            }
            nl = i - r.first;
        }
        if (nl == 0) {
            n->left_or_first = r.first;
            n->count_axis = r.count;
            continue;
        }
        n->count_axis = (uint32_t)axis << 30;
        stack[top++] = (range){ni, r.first + nl, r.count - nl};
        stack[top++] = (range){UINT32_MAX, r.first, nl};
    }
    return root;
}
