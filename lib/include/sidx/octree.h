/* sidx/octree.h — a read-only view of a built octree's memory.
 *
 * The octree family ("octree", and "quadtree", which never cuts z) stores
 * the deck's "simplest hierarchical grid" (deck 001, "Quad/Octree"; deck
 * 000, "Octrees and Quadtrees"): every inner node is cut at its centre
 * into 2×2×2 equal children (2×2 for the quadtree), stored contiguously,
 * so a node is two 32-bit words and no box.  These calls hand out the
 * tree's own arrays, so an exercise or a tool reads the very nodes the
 * traversal reads.
 *   node i is inner  when n == SIDX_OCT_INNER: its children are
 *                    a + c for c = 0 .. 7 (0 .. 3 for the quadtree), bit
 *                    k of c set = the upper half on axis k (x = bit 0,
 *                    y = bit 1, z = bit 2), halves cut at 0.5·(lo + hi)
 *   node i is a leaf otherwise: it references the triangles
 *                    refs[a .. a + n) (n = 0: an empty leaf)
 * Node 0 is the root; its cell is the tree's box (sidx_octree_info);
 * every other cell is implicit, cut from its parent's.  The pointers stay
 * valid until sidx_accel_destroy. */
#ifndef SIDX_OCTREE_H
#define SIDX_OCTREE_H

#include <stdint.h>
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_oct_node {
    uint32_t a; /* inner: index of the first child; leaf: first index into refs */
    uint32_t n; /* SIDX_OCT_INNER, or the leaf's reference count */
} sidx_oct_node;

#define SIDX_OCT_INNER 0xffffffffu

/* The node array: *nodes points at *count nodes.  SIDX_ERR_INVALID_ARG
 * (outputs untouched) if an argument is NULL or `a` is not an octree or
 * a quadtree. */
sidx_status sidx_octree_nodes(const sidx_accel *a, const sidx_oct_node **nodes, uint32_t *count, sidx_error *err);
/* The leaves' triangle indices, indexed by the leaves' a: *refs points at
 * *count entries (NULL and 0 for a tree without references).  Same
 * errors as above. */
sidx_status sidx_octree_refs(const sidx_accel *a, const uint32_t **refs, uint32_t *count, sidx_error *err);
/* The root's cell and the number of axes cut at each node (3 for the
 * octree, 2 for the quadtree: x and y).  Same errors as above. */
sidx_status sidx_octree_info(const sidx_accel *a, sidx_aabb *root_box, int *axes_cut, sidx_error *err);

#ifdef __cplusplus
}
#endif

#endif
