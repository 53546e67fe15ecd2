/* Exercise 12 — BVH refit: the vertices moved, the tree stays, the boxes
 * are recomputed bottom-up.
 *
 * Slides: deck 001, "Primitive vs. Spatial" ("Bounding Volume Hierarchy
 * ... [+] Easier to update (animation)") and "Bounding Volume Hierarchy
 * (BVH)" ("Root node encompasses all primitives").
 *
 * The tree is the library's own binary BVH, read through sidx/bvh.h, as
 * it was built BEFORE the mesh's vertices moved: nodes[0] is the root; an
 * inner node's children are i + 1 and nodes[i].left_or_first; a leaf
 * holds the triangles prims[first .. first + count) (first =
 * left_or_first, count = sidx_bvh_count); children come after their
 * parent in the array.  mesh holds the moved vertices
 * (sidx_mesh_vertex(mesh, prim, k), k = 0, 1, 2).
 *
 * Write bvh_refit: give every node its new box (bmin[], bmax[]) — keep
 * left_or_first and count_axis as they are:
 *   - a leaf's box is the bounding box of its triangles' vertices;
 *   - an inner node's box is the union of its two children's boxes, so
 *     both children must be refitted before it (bottom-up).
 * The checker compares every node's box with the library's
 * sidx_accel_refit on the same tree and the same moved vertices.
 * Awkward cases: a tree that is one leaf, no vertex moved, one vertex
 * moved far away, a triangle collapsed to a point.
 *
 * Check with:   make exercise EX=12_bvh_refit
 * Only the function body is yours to write (helpers of your own are
 * fine). */
#include "sidx/sidx.h"
#include "sidx/bvh.h"

void bvh_refit(sidx_bvh_node *nodes, uint32_t num_nodes, const uint32_t *prims, const sidx_mesh *mesh)
{
    (void)nodes;
    (void)num_nodes;
    (void)prims;
    (void)mesh;
}
