/* Reference solution of 05_bvh_traversal (deck 001, "BVH Traversal",
 * "Better BVH Traversal"). */
#include "sidx/sidx.h"
#include "sidx/bvh.h"
#include "sidx/exercise.h"

static void leaf(const sidx_ex *ex, const sidx_bvh_node *n, const uint32_t *prims, sidx_hit *best)
{
    for (uint32_t i = n->left_or_first; i < n->left_or_first + sidx_bvh_count(n); ++i) {
        float t;
        if (sidx_ex_test_triangle(ex, prims[i], best->t, &t) && t < best->t) {
            best->t = t;
            best->prim = prims[i];
            sidx_ex_hit_update(ex, prims[i], t);
        }
    }
}

void bvh_hit_naive(const sidx_ex *ex, const sidx_bvh_node *nodes, const uint32_t *prims, uint32_t node,
                   uint32_t depth, sidx_hit *best)
{
    const sidx_bvh_node *n = &nodes[node];
    const sidx_aabb box = sidx_bvh_box(n);
    float tn, tf;
    if (!sidx_ex_test_box(ex, node, &box, ex->ray->tmin, best->t, &tn, &tf)) return;
    sidx_ex_node_enter(ex, node, depth, tn, tf);
    if (sidx_bvh_is_leaf(n)) {
        leaf(ex, n, prims, best);
        return;
    }
    bvh_hit_naive(ex, nodes, prims, node + 1, depth + 1, best);
    bvh_hit_naive(ex, nodes, prims, n->left_or_first, depth + 1, best);
}

void bvh_hit_ordered(const sidx_ex *ex, const sidx_bvh_node *nodes, const uint32_t *prims, uint32_t node,
                     uint32_t depth, float t_near, float t_far, sidx_hit *best)
{
    const sidx_bvh_node *n = &nodes[node];
    sidx_ex_node_enter(ex, node, depth, t_near, t_far);
    if (sidx_bvh_is_leaf(n)) {
        leaf(ex, n, prims, best);
        return;
    }
    uint32_t c1 = node + 1, c2 = n->left_or_first;
    const sidx_aabb b1 = sidx_bvh_box(&nodes[c1]), b2 = sidx_bvh_box(&nodes[c2]);
    float n1 = INFINITY, f1 = INFINITY, n2 = INFINITY, f2 = INFINITY;
    int h1 = sidx_ex_test_box(ex, c1, &b1, ex->ray->tmin, best->t, &n1, &f1);
    int h2 = sidx_ex_test_box(ex, c2, &b2, ex->ray->tmin, best->t, &n2, &f2);
    if (h2 && (!h1 || n2 < n1)) { /* child2 is the nearer: visit it first */
        uint32_t c = c1; c1 = c2; c2 = c;
        int h = h1; h1 = h2; h2 = h;
        float x = n1; n1 = n2; n2 = x;
        x = f1; f1 = f2; f2 = x;
    }
    if (h1) bvh_hit_ordered(ex, nodes, prims, c1, depth + 1, n1, f1, best);
    if (h2 && n2 < best->t) bvh_hit_ordered(ex, nodes, prims, c2, depth + 1, n2, f2, best);
}
