/* Exercise 11 — the recursive BVH build: partition, leaf, equal centroids.
 *
 * Slides: deck 001, "BVH Partitioning" ("Split in the middle"), "Recurse
 * with each child node", "After re-indexing (sorting) based on leaf
 * nodes" ("Only need to store 2 integers per leaf node!") and "Edge
 * Cases" ("primitives with same centroid ... pick a random partition");
 * deck 000, "Bounding Volume Hierarchies (BVHs)".
 *
 * bvh_build builds the subtree over the triangles prims[first .. first +
 * count) (indices into boxes[] and cents[], the triangles' bounding boxes
 * and their centres) into the library's node layout (sidx/bvh.h) and
 * returns the index of its root:
 *   - the node takes the next free slot, nodes[*num_nodes], and counts it
 *     (++*num_nodes) before its children, so nodes lie in depth-first
 *     pre-order and an inner node's left child is the node after it;
 *   - its box (bmin[], bmax[]) is the union of its triangles' boxes;
 *   - it is a leaf (left_or_first = first, count_axis = count) when
 *     count <= leaf_size;
 *   - "primitives with same centroid": when every centroid is equal (the
 *     centroid bounds have no extent on any axis) no plane separates
 *     them: a leaf if count <= max_leaf, otherwise the range is split in
 *     half as it stands, prims[first .. first + count/2) to the left
 *     (axis 0);
 *   - otherwise "split in the middle": on the axis of largest extent of
 *     the centroid bounds (sidx_aabb_max_axis: a tie goes to x, then y),
 *     at the middle of the centroid bounds on that axis, pos = 0.5f *
 *     (min + max).  Partition prims[first .. first + count) in place,
 *     one walk from the front: with i = first and j = first + count,
 *     while i < j, a triangle whose centroid is < pos stays (++i), any
 *     other is swapped with prims[--j].  The left child gets prims[first
 *     .. i), the right child the rest;
 *   - build the left child, then the right one; the inner node stores the
 *     right child's index in left_or_first and the axis in count_axis
 *     (axis << 30, a count of 0 marks it inner).
 * The checker builds the library's "bvh-middle" over the same triangles
 * and compares, node by node in array order, every box, every leaf's
 * (first, count) and its triangles in order, every inner node's axis,
 * then every child link, the node count and the returned root.  The
 * battery's nodes never have a centroid extent one float wide (where the
 * middle could put every centroid on one side).
 *
 * Check with:   make exercise EX=11_bvh_build
 * Only the function body is yours to write (helpers of your own are
 * fine). */
#include "sidx/sidx.h"
#include "sidx/bvh.h"

uint32_t bvh_build(sidx_bvh_node *nodes, uint32_t *num_nodes, uint32_t *prims, uint32_t first, uint32_t count,
                   const sidx_aabb *boxes, const sidx_vec3 *cents, uint32_t leaf_size, uint32_t max_leaf)
{
    (void)nodes;
    (void)num_nodes;
    (void)prims;
    (void)first;
    (void)count;
    (void)boxes;
    (void)cents;
    (void)leaf_size;
    (void)max_leaf;
    return 0;
}
