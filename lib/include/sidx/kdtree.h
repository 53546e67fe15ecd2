/* sidx/kdtree.h — a read-only view of a built kd-tree's memory.
 *
 * The kd-tree family ("kdtree", "kdtree-binned", "kdtree-median",
 * "kdtree-middle") stores the deck's compact node ("Compact (8-byte)
 * Nodes"): two 32-bit words and nothing else, no box ("No Bounding Box!").
 * These calls hand out the tree's own arrays, so a lesson or a tool can
 * print and check the bits the traversal really reads instead of a
 * re-encoding of them.
 *
 * Node encoding (word `bits`, low 2 bits first):
 *
 *   bits & 3 == 0, 1, 2   inner node splitting x, y, z:
 *                         u.split = plane position (IEEE float),
 *                         bits >> 2 = index of the left child; the right
 *                         child is always the next node (index + 1)
 *   bits & 3 == 3         leaf:
 *                         u.count = number of triangle references,
 *                         bits >> 2 = offset of the first one in the
 *                         reference array (0 for an empty leaf)
 *
 * Node 0 is the root; its cell is the scene box (sidx_mesh_bounds); every
 * other cell is implicit, cut from its parent's by the split plane.  A
 * leaf's references refs[offset .. offset + count) are triangle indices
 * in the input mesh; a triangle straddling several cells is referenced by
 * each of them.  The pointers stay valid until sidx_accel_destroy. */
#ifndef SIDX_KDTREE_H
#define SIDX_KDTREE_H

#include <stdint.h>
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_kd_node {
    union {
        float split;    /* inner node: split plane position */
        uint32_t count; /* leaf: number of triangle references */
    } u;
    uint32_t bits;      /* inner: left child << 2 | axis;  leaf: offset << 2 | 3 */
} sidx_kd_node;

#define SIDX_KD_LEAF 3u /* bits & 3 of a leaf */

/* The node array of a built kd-tree: *nodes points at *count nodes.
 * SIDX_ERR_INVALID_ARG (outputs untouched) if an argument is NULL or if
 * `a` is not one of the kd-tree structures. */
sidx_status sidx_kdtree_nodes(const sidx_accel *a, const sidx_kd_node **nodes, uint32_t *count, sidx_error *err);

/* The leaf reference array (triangle indices): *refs points at *count
 * entries, indexed by the leaves' offsets.  Same errors as above. */
sidx_status sidx_kdtree_refs(const sidx_accel *a, const uint32_t **refs, uint32_t *count, sidx_error *err);

/* ---- a kd-tree given split by split ----------------------------------- */

/* One node of a tree given by hand, in depth-first order (a node, then its
 * left subtree, then its right subtree): an inner node splitting `axis`
 * (0, 1, 2 = x, y, z) at `pos`, or a leaf (axis SIDX_KD_LEAF; pos unused).
 * label: the node's name (sidx_accel_set_node_label), or NULL. */
typedef struct sidx_kd_split {
    uint32_t axis;
    float pos;
    const char *label;
} sidx_kd_split;

/* Builds the kd-tree made of exactly these splits, so that a slide's tree
 * ("kD-Tree Example") can be walked as drawn, whatever the SAH would
 * choose.  The root cell is the scene box; each leaf references the
 * triangles overlapping its cell, sifted as the other builders sift them
 * (perfect splits).  The result is an ordinary "kdtree" (same nodes, same
 * traversal, sidx_kdtree_nodes works); entry i's node id is that of the
 * i-th node written depth first, and entries with a label label it.
 * opt as for sidx_accel_build (its hook gets a NOTE, then the build
 * events, the leaves with reason "given"); leaf_size, max_depth, bins and
 * the empty bonus are not used, c_trav and c_tri only price the tree
 * (sidx_accel_stats.sah_cost).
 * Errors: SIDX_ERR_INVALID_ARG (NULL arguments, count 0, a list that ends
 * before the tree does or goes on after it, an axis above 3, a position
 * not strictly inside its node's cell, a label of SIDX_LABEL_MAX bytes or
 * more), SIDX_ERR_LIMIT (deeper than 64 levels: the traversal stack),
 * then sidx_accel_build's (mesh, options, memory).  *out is NULL on error. */
sidx_status sidx_kdtree_build_from_splits(const sidx_mesh *mesh, const sidx_kd_split *splits, uint32_t count,
                                          const sidx_build_options *opt, sidx_accel **out, sidx_error *err);

#ifdef __cplusplus
}
#endif

#endif
