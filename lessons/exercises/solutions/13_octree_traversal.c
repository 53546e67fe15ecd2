/* Reference solution of 13_octree_traversal (deck 000, "Octrees and
 * Quadtrees"; the child order of Revelles et al. 2000): a stack of the
 * cells still to visit, each with its box, interval and depth. */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/octree.h"
#include "sidx/exercise.h"

/* Deep enough for every octree of the library (at most 24 levels, at
 * most 3 children waiting per level, plus the one in hand). */
#define OCT_STACK 80

typedef struct oct_cell {
    sidx_aabb box;
    float t_near, t_far;
    uint32_t node, depth;
} oct_cell;

int oct_walk(const sidx_ex *ex, const sidx_oct_node *nodes, const uint32_t *refs, sidx_aabb root, int axes,
             float t_near, float t_far, sidx_hit *best)
{
    const sidx_ray *ray = ex->ray;
    const float org[3] = {ray->org.x, ray->org.y, ray->org.z};
    const float dir[3] = {ray->dir.x, ray->dir.y, ray->dir.z};
    const float inv_dir[3] = {ray->inv_dir.x, ray->inv_dir.y, ray->inv_dir.z};
    oct_cell stack[OCT_STACK];
    uint32_t size = 0;
    stack[size++] = (oct_cell){root, t_near, t_far, 0, 0};
    while (size > 0) {
        const oct_cell c = stack[--size];
        const sidx_oct_node *n = &nodes[c.node];
        sidx_ex_node_enter(ex, c.node, c.depth, c.t_near, c.t_far);
        if (n->n != SIDX_OCT_INNER) {
            for (uint32_t k = 0; k < n->n; ++k) {
                float t;
                if (sidx_ex_test_triangle(ex, refs[n->a + k], best->t, &t)) {
                    best->prim = refs[n->a + k];
                    best->t = t;
                    sidx_ex_hit_update(ex, best->prim, t);
                }
            }
            /* the next cell starts at t_far: nothing there lies in front */
            if (best->t <= c.t_far) return best->prim != SIDX_NO_HIT;
            continue;
        }
        const float lo[3] = {c.box.min.x, c.box.min.y, c.box.min.z};
        const float hi[3] = {c.box.max.x, c.box.max.y, c.box.max.z};
        float mid[3] = {0.0f, 0.0f, 0.0f}, t_mid[3] = {INFINITY, INFINITY, INFINITY};
        uint32_t child = 0;
        int order[3], m = 0;
        for (int k = 0; k < axes; ++k) {
            mid[k] = 0.5f * (lo[k] + hi[k]);
            if (dir[k] == 0.0f) { /* never crosses: the origin's side */
                if (org[k] >= mid[k]) child |= 1u << k;
                continue;
            }
            t_mid[k] = (mid[k] - org[k]) * inv_dir[k];
            if ((t_mid[k] <= c.t_near) == (dir[k] > 0.0f)) child |= 1u << k; /* the entry point's side */
            if (t_mid[k] > c.t_near && t_mid[k] < c.t_far) order[m++] = k;
        }
        for (int i = 1; i < m; ++i) /* crossings by t; equal t keep x, y, z */
            for (int j = i; j > 0 && t_mid[order[j]] < t_mid[order[j - 1]]; --j) {
                const int tmp = order[j];
                order[j] = order[j - 1];
                order[j - 1] = tmp;
            }
        /* the children in ray order, pushed last first */
        uint32_t ids[4];
        float bounds[5];
        ids[0] = child;
        bounds[0] = c.t_near;
        for (int i = 0; i < m; ++i) {
            bounds[i + 1] = t_mid[order[i]];
            ids[i + 1] = ids[i] ^ (1u << order[i]);
        }
        bounds[m + 1] = c.t_far;
        for (int i = m; i >= 0; --i) {
            oct_cell next = {c.box, bounds[i], bounds[i + 1], n->a + ids[i], c.depth + 1};
            float *nlo = sidx_v3_array_rw(&next.box.min), *nhi = sidx_v3_array_rw(&next.box.max);
            for (int k = 0; k < axes; ++k) {
                if (ids[i] & (1u << k)) nlo[k] = mid[k];
                else nhi[k] = mid[k];
            }
            stack[size++] = next;
        }
    }
    return 0;
}
