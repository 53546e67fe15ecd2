/* A correct 08_kdtree_traversal organised as pbrt does: the first child
 * is the one on the origin's side of the plane (a tie, the origin on the
 * plane, broken by the direction's sign, -0 counting as negative), a plane
 * behind the origin (t_split < 0) or beyond the cell keeps only the first
 * child, a plane before the cell only the second.  It visits the cells of
 * the slide's rule ("Near and far depend on direction of ray!") in the
 * same order: while the ray runs toward the plane, the origin's side is
 * the near side. */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/kdtree.h"
#include "sidx/exercise.h"

#define KD_EPS 3.576278687e-7f
#define KD_STACK 66

typedef struct todo {
    uint32_t node, depth;
    float t_near, t_far;
} todo;

int kd_walk(const sidx_ex *ex, const sidx_kd_node *nodes, const uint32_t *refs, float t_near, float t_far,
            sidx_hit *best)
{
    const sidx_ray *ray = ex->ray;
    const float org[3] = {ray->org.x, ray->org.y, ray->org.z};
    const float inv_dir[3] = {ray->inv_dir.x, ray->inv_dir.y, ray->inv_dir.z};
    todo stack[KD_STACK];
    uint32_t size = 0, node = 0, depth = 0;
    int may_stop = 1;
    for (;;) {
        const sidx_kd_node *n = &nodes[node];
        sidx_ex_node_enter(ex, node, depth, t_near, t_far);
        if ((n->bits & 3u) != SIDX_KD_LEAF) {
            const uint32_t axis = n->bits & 3u, below = n->bits >> 2, above = below + 1u;
            const float split = n->u.split;
            const float t_split = (split - org[axis]) * inv_dir[axis];
            const int below_first = org[axis] < split || (org[axis] == split && !ray->sign[axis]);
            const uint32_t first = below_first ? below : above, second = below_first ? above : below;
            ++depth;
            if (isnan(t_split)) { /* the ray runs inside the plane: both cells, whole interval */
                may_stop = 0;
                const todo t = {second, depth, t_near, t_far};
                stack[size++] = t;
                sidx_ex_push(ex, t.node, size, t.t_near, t.t_far);
                node = first;
            } else if (t_split < 0.0f || t_split > t_far + fabsf(t_far) * KD_EPS) {
                node = first;
            } else if (t_split < t_near - fabsf(t_near) * KD_EPS) {
                node = second;
            } else {
                const todo t = {second, depth, fmaxf(t_split, t_near), t_far};
                stack[size++] = t;
                sidx_ex_push(ex, t.node, size, t.t_near, t.t_far);
                node = first;
                t_far = fminf(t_split, t_far);
            }
            continue;
        }
        const uint32_t first = n->bits >> 2;
        for (uint32_t k = 0; k < n->u.count; ++k) {
            float t;
            if (sidx_ex_test_triangle(ex, refs[first + k], best->t, &t)) {
                best->prim = refs[first + k];
                best->t = t;
                sidx_ex_hit_update(ex, best->prim, t);
            }
        }
        if (n->u.count != 0 && best->prim != SIDX_NO_HIT && may_stop && best->t < t_far - fabsf(t_far) * KD_EPS)
            return 1;
        do {
            if (size == 0) return 0;
            const todo next = stack[--size];
            sidx_ex_pop(ex, next.node, size + 1u, next.t_near, next.t_far);
            node = next.node;
            depth = next.depth;
            t_near = next.t_near;
            t_far = next.t_far;
        } while (t_near > best->t + fabsf(best->t) * KD_EPS);
    }
}
