/* boxtree.h — a small, private bounding-box tree over an array of boxes.
 *
 * Not the library's BVH (lib/bvh_*.c, registered as "bvh"): this one only
 * serves structures that need "some BVH over N boxes" as a building block
 * — the top level of an aggregate (instance.c: "the top level is a BVH over
 * instance world boxes") and the node walk of beam and cone tracing
 * (beam.c), which needs node boxes that the registered BVH keeps private.
 * It is an object-median split along the longest centroid axis, the
 * simplest builder that still gives O(log n) depth; the deck's SAH builders
 * live in the real BVH. */
#ifndef SIDX_BOXTREE_H
#define SIDX_BOXTREE_H

#include "sidx_internal.h"

typedef struct sidx__btnode {
    sidx_aabb box;
    uint32_t first; /* leaf: first item in sidx__boxtree.items; inner: index of the left child (right = +1) */
    uint32_t count; /* leaf: number of items (0 only for an empty tree); inner: SIDX_BT_INNER */
} sidx__btnode;
#define SIDX_BT_INNER UINT32_MAX

typedef struct sidx__boxtree {
    sidx__btnode *nodes;
    uint32_t *items;     /* item ids (indices into the caller's box array), leaf by leaf */
    uint32_t num_nodes, num_items, depth;
    sidx_allocator al;
} sidx__boxtree;

/* Builds over boxes[0..n); leaves hold at most leaf_size items (>= 1).
 * n may be 0 (then one empty leaf).  Returns SIDX_ERR_NOMEM on failure
 * with nothing leaked. */
sidx_status sidx__boxtree_build(sidx__boxtree *t, const sidx_aabb *boxes, uint32_t n, uint32_t leaf_size,
                                const sidx_allocator *al);
void sidx__boxtree_free(sidx__boxtree *t);
size_t sidx__boxtree_bytes(const sidx__boxtree *t);
/* A malloc/free allocator for code that has no sidx_accel to allocate through. */
sidx_allocator sidx__default_allocator(void);

/* Deepest possible stack for walking a tree built by sidx__boxtree_build:
 * median splits halve the item count, so depth <= 33 for 2^32 items. */
#define SIDX_BOXTREE_STACK 64

#endif
