/* Exercise 13 — octree traversal: front to back, children in ray order.
 *
 * Slides: deck 000, "Octrees and Quadtrees" ("simplest hierarchical
 * grid": each inner node a 2×2×2 grid of equal children) with the
 * front-to-back walk of "kD-Tree Traversal" ("Traversal can be terminated
 * as soon as surface intersection is found in the current node"); the
 * child order from the ray's own mid-plane crossings is Revelles, Ureña
 * and Lastra 2000 ("An Efficient Parametric Algorithm for Octree
 * Traversal").
 *
 * The tree is the library's own octree, read through sidx/octree.h:
 * nodes[0] is the root, its cell is `root`; an inner node (n ==
 * SIDX_OCT_INNER) is cut at its centre, mid = 0.5f * (lo + hi) on each of
 * the first `axes` axes (3 for the octree, 2 for the quadtree, which
 * never cuts z), into children a + c: bit k of c set = the upper half on
 * axis k; a leaf holds the triangles refs[a .. a + n) (n = 0: an empty
 * leaf).  The checker clips the ray to the root's cell and gives you its
 * [t_near, t_far]; best starts as "no hit" with best->t = the ray's tmax.
 *
 * Write oct_walk, front to back:
 *   - report every cell you enter: sidx_ex_node_enter(ex, node, depth,
 *     t_near, t_far) (the root has depth 0, a child its parent's + 1);
 *   - inner node entered over [t_near, t_far]: the ray crosses mid-plane
 *     k at t_k = (mid_k - org[k]) * inv_dir[k].  It starts in the child
 *     that holds its entry point: upper on axis k when it is on or past
 *     the plane in the direction it moves (t_k <= t_near and d_k > 0, or
 *     t_k > t_near and d_k < 0); a direction component ±0 never crosses
 *     (t_k = +inf) and takes the side of the origin (upper when the
 *     origin lies on the plane).  Then each crossing strictly inside
 *     (t_near, t_far), in increasing t (equal t: x, then y, then z),
 *     flips bit k and starts the next child: children c0 over [t_near,
 *     t_1], c1 over [t_1, t_2], ..., the last over [t_m, t_far] — at most
 *     4, each entered even over a zero-length interval, before any later
 *     one (a stack of the children still to visit, or recursion);
 *   - leaf: test each triangle, sidx_ex_test_triangle(ex, prim, best->t,
 *     &t), and on a hit update best->prim and best->t and report it with
 *     sidx_ex_hit_update(ex, prim, t).  Then, empty leaf or not: if
 *     best->t <= t_far the hit lies before the next cell (which starts at
 *     t_far): stop, return 1 if there is a hit (0 if there is none: the
 *     ray's tmax ended it).  A hit beyond t_far does not stop the walk:
 *     a triangle in a later cell may lie in front of it.
 *   - return 0 when every cell along the ray has been visited.
 * The checker reports the end of the walk from your return value.
 *
 * Check with:   make exercise EX=13_octree_traversal
 * Only the body of oct_walk is yours to write (helpers of your own are
 * fine). */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/octree.h"
#include "sidx/exercise.h"

/* Deep enough for every octree of the library (at most 24 levels, at
 * most 3 children waiting per level, plus the one in hand). */
#define OCT_STACK 80

int oct_walk(const sidx_ex *ex, const sidx_oct_node *nodes, const uint32_t *refs, sidx_aabb root, int axes,
             float t_near, float t_far, sidx_hit *best)
{
    (void)ex;
    (void)nodes;
    (void)refs;
    (void)root;
    (void)axes;
    (void)t_near;
    (void)t_far;
    (void)best;
    return 0;
}
