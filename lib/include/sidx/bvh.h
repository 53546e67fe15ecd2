/* sidx/bvh.h — a read-only view of a built binary BVH's memory.
 *
 * The binary BVH family ("bvh", "bvh-sweep", "bvh-everyb", "bvh-median",
 * "bvh-middle", "bvh-obb") stores its nodes flattened in depth-first
 * order, 32 bytes each, and the deck's leaf re-indexing ("After
 * re-indexing (sorting) based on leaf nodes ... Only need to store 2
 * integers per leaf node!"): a leaf holds (first, count) into one array of
 * triangle indices.  These calls hand out the tree's own arrays, so an
 * exercise or a tool reads the very nodes the traversal reads.
 *
 *   node i is a leaf     when count_axis & SIDX_BVH_COUNT_MASK != 0:
 *                        its triangles are prims[first .. first + count),
 *                        first = left_or_first
 *   node i is inner      otherwise: left child = i + 1, right child =
 *                        left_or_first, split axis = count_axis >> 30
 *
 * Node 0 is the root.  prims[] holds triangle indices of the input mesh
 * (what hits report).  The pointers stay valid until sidx_accel_destroy. */
#ifndef SIDX_BVH_H
#define SIDX_BVH_H

#include <stdint.h>
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_bvh_node {
    float bmin[3];
    uint32_t left_or_first; /* inner: right child index; leaf: first index into prims */
    float bmax[3];
    uint32_t count_axis;    /* leaf: count (> 0); inner: axis << 30 */
} sidx_bvh_node;

#define SIDX_BVH_COUNT_MASK 0x3FFFFFFFu

static inline int sidx_bvh_is_leaf(const sidx_bvh_node *n) { return (n->count_axis & SIDX_BVH_COUNT_MASK) != 0; }
static inline uint32_t sidx_bvh_count(const sidx_bvh_node *n) { return n->count_axis & SIDX_BVH_COUNT_MASK; }
static inline sidx_aabb sidx_bvh_box(const sidx_bvh_node *n)
{
    sidx_aabb b = {{n->bmin[0], n->bmin[1], n->bmin[2]}, {n->bmax[0], n->bmax[1], n->bmax[2]}};
    return b;
}

/* The node array of a built binary BVH: *nodes points at *count nodes.
 * SIDX_ERR_INVALID_ARG (outputs untouched) if an argument is NULL or if
 * `a` is not one of the binary BVH structures. */
sidx_status sidx_bvh_nodes(const sidx_accel *a, const sidx_bvh_node **nodes, uint32_t *count, sidx_error *err);

/* The leaves' triangle indices, indexed by the leaves' first: *prims
 * points at *count entries.  Same errors as above.  In "bvh-sbvh" (spatial
 * splits) a triangle cut by a split plane is in several leaves, so *count
 * may exceed the mesh's triangles and an index may occur more than once;
 * every other binary BVH lists each triangle exactly once. */
sidx_status sidx_bvh_prims(const sidx_accel *a, const uint32_t **prims, uint32_t *count, sidx_error *err);

#ifdef __cplusplus
}
#endif

#endif
