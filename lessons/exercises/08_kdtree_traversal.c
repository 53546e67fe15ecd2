/* Exercise 08 — kd-tree traversal: front to back, with a stack.
 *
 * Slides: deck 000, "kD-Tree Traversal", "kD-Tree Traversal (1)-(11)",
 * "kD-Tree Traversal Operation" and "kD-Tree Traversal: Inner Loop".
 *
 * The tree is the library's own kd-tree, read through sidx/kdtree.h:
 * nodes[0] is the root; an inner node splits axis bits & 3 at u.split, its
 * left child (the side below the plane) is bits >> 2 and its right child
 * the next node; a leaf ((bits & 3) == SIDX_KD_LEAF) holds the triangles
 * refs[first .. first + u.count) with first = bits >> 2.  The checker
 * clips the ray to the root's cell: "Given (node, t_near, t_far)", you get
 * the root's [t_near, t_far].  best starts as "no hit" with best->t = the
 * ray's tmax; keep best->prim and best->t up to date.
 *
 * Write kd_walk, the deck's loop, one node per iteration:
 *   - report each node you visit: sidx_ex_node_enter(ex, node, depth,
 *     t_near, t_far) (the root has depth 0, a child its parent's + 1);
 *   - inner node: t_split = (split - ray->org[axis]) * ray->inv_dir[axis].
 *     "Near and far depend on direction of ray!": the near child is the
 *     left one unless the direction is negative on the axis (ray->sign,
 *     which counts -0 as negative).  "Three cases": t_split before the
 *     interval: far child only, over the same [t_near, t_far]; beyond it:
 *     near child only; otherwise both: push (far child, t_split, t_far),
 *     reporting sidx_ex_push(ex, far, stack size after the push, t_split,
 *     t_far), and go on with (near child, t_near, t_split).  Rounding:
 *     rule a child out only when t_split lies outside [t_near, t_far]
 *     widened by |t|·KD_EPS at each end (below); a tie (t_split == t_near
 *     or t_far) goes to BOTH, and t_split is clamped into [t_near, t_far].
 *     A NaN t_split (the ray runs inside the plane) goes to both over the
 *     whole interval, and then no early exit for the rest of the ray;
 *   - leaf: test each triangle, sidx_ex_test_triangle(ex, prim, best->t,
 *     &t); a closer hit updates best and is reported with
 *     sidx_ex_hit_update.  "Traversal can be terminated as soon as surface
 *     intersection is found in the current node": return 1 if the best hit
 *     lies in this cell, inside it by more than a rounding error
 *     (best->t < t_far - |t_far|·KD_EPS: a triangle across the far plane
 *     may give a t an ulp smaller); a hit beyond it does not end the walk
 *     ("CANNOT terminate !!!").  An empty leaf is entered and left (no
 *     stop test);
 *   - then pop the next cell, sidx_ex_pop(ex, node, stack size before the
 *     pop, t_near, t_far), restoring its depth too; a popped cell whose
 *     t_near lies beyond best->t (by more than |best->t|·KD_EPS) cannot
 *     hold a closer hit: pop the next one.  Return 0 when the stack is
 *     empty.
 * The checker reports the end of the walk from your return value.
 *
 * Check with:   make exercise EX=08_kdtree_traversal
 * Only the body of kd_walk is yours to write (helpers of your own are
 * fine). */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/kdtree.h"
#include "sidx/exercise.h"

/* 2γ₃ (Ize 2013): how far rounding can move t_split against t_near, t_far. */
#define KD_EPS 3.576278687e-7f
/* Deep enough for every tree of the library (at most 64 levels). */
#define KD_STACK 66

int kd_walk(const sidx_ex *ex, const sidx_kd_node *nodes, const uint32_t *refs, float t_near, float t_far,
            sidx_hit *best)
{
    (void)ex;
    (void)nodes;
    (void)refs;
    (void)t_near;
    (void)t_far;
    (void)best;
    return 0;
}
