/* A correct variant of 11_bvh_build organised differently: the boxes
 * grown by hand with fminf / fmaxf, equal centroids found by a zero
 * extent, the largest axis by its own comparisons, the partition in a
 * helper on pointers, and the right child's index read from *num_nodes
 * before it is built.  It must pass. */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/bvh.h"

static uint32_t *split_middle(uint32_t *lo, uint32_t *hi, const sidx_vec3 *cents, int axis, float pos)
{
    while (lo != hi) {
        const float c = axis == 0 ? cents[*lo].x : axis == 1 ? cents[*lo].y : cents[*lo].z;
        if (c < pos) {
            ++lo;
        } else {
            const uint32_t t = *lo;
            *lo = *--hi;
            *hi = t;
        }
    }
    return lo;
}

uint32_t bvh_build(sidx_bvh_node *nodes, uint32_t *num_nodes, uint32_t *prims, uint32_t first, uint32_t count,
                   const sidx_aabb *boxes, const sidx_vec3 *cents, uint32_t leaf_size, uint32_t max_leaf)
{
    const uint32_t me = *num_nodes;
    *num_nodes = me + 1;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t k = 0; k < count; ++k) {
        const sidx_aabb b = boxes[prims[first + k]];
        const sidx_vec3 c = cents[prims[first + k]];
        const float bl[3] = {b.min.x, b.min.y, b.min.z}, bh[3] = {b.max.x, b.max.y, b.max.z}, cc[3] = {c.x, c.y, c.z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = fminf(lo[a], bl[a]);
            hi[a] = fmaxf(hi[a], bh[a]);
            clo[a] = fminf(clo[a], cc[a]);
            chi[a] = fmaxf(chi[a], cc[a]);
        }
    }
    for (int a = 0; a < 3; ++a) {
        nodes[me].bmin[a] = lo[a];
        nodes[me].bmax[a] = hi[a];
    }
    const float ex = chi[0] - clo[0], ey = chi[1] - clo[1], ez = chi[2] - clo[2];
    uint32_t nl = 0;
    int axis = 0;
    if (count > leaf_size) {
        if (ex == 0.0f && ey == 0.0f && ez == 0.0f) {
            nl = count > max_leaf ? count / 2 : 0;
        } else {
            axis = ex >= ey && ex >= ez ? 0 : ey >= ez ? 1 : 2;
            const float pos = 0.5f * (clo[axis] + chi[axis]);
            nl = (uint32_t)(split_middle(prims + first, prims + first + count, cents, axis, pos) - (prims + first));
        }
    }
    if (nl == 0) {
        nodes[me].left_or_first = first;
        nodes[me].count_axis = count;
    } else {
        bvh_build(nodes, num_nodes, prims, first, nl, boxes, cents, leaf_size, max_leaf);
        nodes[me].left_or_first = *num_nodes;
        bvh_build(nodes, num_nodes, prims, first + nl, count - nl, boxes, cents, leaf_size, max_leaf);
        nodes[me].count_axis = (uint32_t)axis << 30;
    }
    return me;
}
