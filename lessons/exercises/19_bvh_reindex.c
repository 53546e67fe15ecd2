/* Exercise 19 — BVH leaf re-indexing: each leaf's triangles contiguous,
 * in the order the leaves are laid out.
 *
 * Slides: deck 001, "What About Ordering?" and "After re-indexing
 * (sorting) based on leaf nodes" ("Only need to store 2 integers per leaf
 * node!"): once the tree is built, the triangle index array is sorted so
 * that every leaf's triangles sit side by side, and a leaf keeps only
 * (first, count) into it.
 *
 * The tree is the library's own binary BVH (sidx/bvh.h), laid out depth
 * first: nodes[0] is the root, an inner node's children are i + 1 and
 * left_or_first; a leaf (sidx_bvh_is_leaf) holds sidx_bvh_count(n)
 * triangles.  Before re-indexing, a leaf's left_or_first points at its
 * triangle list in `lists`: lists[first .. first + count), one block per
 * leaf, but the blocks are stored in some other order than the leaves
 * (the order a builder happened to finish them in, with unused slots
 * between them in some cases).
 *
 * Write bvh_reindex:
 *   - walk the nodes in array order, 0, 1, 2, ...: the leaves' layout
 *     order, which is also the order a depth-first traversal meets them;
 *   - copy each leaf's triangles, in the leaf's own order, to the next
 *     free slots of prims (starting at prims[0]), and set the leaf's
 *     left_or_first to where its block now starts: first = the number of
 *     triangles of the leaves before it;
 *   - change nothing else: the count, the boxes, the inner nodes (their
 *     left_or_first is the right child's index);
 *   - return the number of entries written to prims (every triangle
 *     reference once: the sum of the leaves' counts).
 * The checker compares every node's fields and box, every slot of prims
 * (and that nothing is written past them) and your return value with the
 * library's own layout of the same tree (sidx_bvh_nodes, sidx_bvh_prims).
 * Awkward cases: a tree that is one leaf, lists already in leaf order,
 * lists in reverse order, unused slots in lists.
 *
 * Check with:   make exercise EX=19_bvh_reindex
 * Only the function body is yours to write (helpers of your own are
 * fine). */
#include "sidx/sidx.h"
#include "sidx/bvh.h"

uint32_t bvh_reindex(sidx_bvh_node *nodes, uint32_t num_nodes, const uint32_t *lists, uint32_t *prims)
{
    (void)nodes;
    (void)num_nodes;
    (void)lists;
    (void)prims;
    return 0;
}
