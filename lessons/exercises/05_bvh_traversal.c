/* Exercise 05 — BVH traversal: the naive walk, then the ordered one.
 *
 * Slides: deck 001, "BVH Traversal" and "Better BVH Traversal"; deck 000,
 * "BVH traversal (1)-(3)".
 *
 * The tree is the library's own binary BVH, read through sidx/bvh.h:
 * nodes[0] is the root; an inner node's children are node + 1 (child1)
 * and nodes[node].left_or_first (child2); a leaf holds the triangles
 * prims[first .. first + count) (first = left_or_first, count =
 * sidx_bvh_count).  best starts as "no hit" with best->t = the ray's
 * tmax; keep best->prim and best->t up to date.
 *
 * Report every step through sidx/exercise.h — the checker compares your
 * steps with the library's, one by one:
 *   sidx_ex_test_box(ex, node, &box, ex->ray->tmin, best->t, &tn, &tf)
 *                                      slab test + its BOX_TEST step
 *   sidx_ex_node_enter(ex, node, depth, tn, tf)   you visit a node
 *   sidx_ex_test_triangle(ex, prim, best->t, &t)  triangle test + its step
 *   sidx_ex_hit_update(ex, prim, t)               best changed
 *
 * 1. bvh_hit_naive — the first hit(): test the node's box (over
 *    [tmin, best->t]: "if (hit.prim == NULL || hit.t > best.t) return"),
 *    enter it; a leaf tests each of its primitives, an inner node
 *    traverses BOTH children, child1 then child2.  Called on the root.
 * 2. bvh_hit_ordered — "Better BVH Traversal": called on a node whose box
 *    was already tested (the checker tests the root's), with that box's
 *    [t_near, t_far].  Enter it; a leaf as above; an inner node tests both
 *    children's boxes, visits first the one the ray enters first (a tie:
 *    child1), and the other only if its box was hit and "can still beat
 *    the best hit" (its t_near < best->t).
 *
 * Check with:   make exercise EX=05_bvh_traversal
 * Only the two function bodies are yours to write (helpers of your own
 * are fine). */
#include "sidx/sidx.h"
#include "sidx/bvh.h"
#include "sidx/exercise.h"

void bvh_hit_naive(const sidx_ex *ex, const sidx_bvh_node *nodes, const uint32_t *prims, uint32_t node,
                   uint32_t depth, sidx_hit *best)
{
    (void)ex;
    (void)nodes;
    (void)prims;
    (void)node;
    (void)depth;
    (void)best;
}

void bvh_hit_ordered(const sidx_ex *ex, const sidx_bvh_node *nodes, const uint32_t *prims, uint32_t node,
                     uint32_t depth, float t_near, float t_far, sidx_hit *best)
{
    (void)ex;
    (void)nodes;
    (void)prims;
    (void)node;
    (void)depth;
    (void)t_near;
    (void)t_far;
    (void)best;
}
