/* A correct 13_octree_traversal organised differently: recursion instead
 * of a stack, and the crossings taken by repeated selection of the
 * smallest remaining t (the lowest axis on a tie) instead of a sort.
 * It takes the same steps, so it passes. */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/octree.h"
#include "sidx/exercise.h"

typedef struct walk {
    const sidx_ex *ex;
    const sidx_oct_node *nodes;
    const uint32_t *refs;
    int axes;
    sidx_hit *best;
} walk;

/* 1: stop the whole walk (returned to the caller as is), 0: go on. */
static int visit(const walk *w, uint32_t node, uint32_t depth, sidx_aabb box, float tn, float tf, int *stop)
{
    const sidx_ray *r = w->ex->ray;
    sidx_ex_node_enter(w->ex, node, depth, tn, tf);
    const sidx_oct_node *n = &w->nodes[node];
    if (n->n != SIDX_OCT_INNER) {
        for (uint32_t i = 0; i < n->n; ++i) {
            const uint32_t prim = w->refs[n->a + i];
            float t;
            if (!sidx_ex_test_triangle(w->ex, prim, w->best->t, &t)) continue;
            w->best->t = t;
            w->best->prim = prim;
            sidx_ex_hit_update(w->ex, prim, t);
        }
        if (!(w->best->t > tf)) {
            *stop = 1;
            return w->best->prim != SIDX_NO_HIT;
        }
        return 0;
    }
    const float *o = sidx_v3_array(&r->org), *d = sidx_v3_array(&r->dir), *id = sidx_v3_array(&r->inv_dir);
    const float *blo = sidx_v3_array(&box.min), *bhi = sidx_v3_array(&box.max);
    float centre[3], tc[3] = {0.0f, 0.0f, 0.0f};
    int pending[3] = {0, 0, 0};
    uint32_t c = 0;
    for (int k = 0; k < w->axes; ++k) {
        centre[k] = 0.5f * (blo[k] + bhi[k]);
        if (d[k] == 0.0f) {
            c |= (uint32_t)(o[k] >= centre[k]) << k;
            continue;
        }
        tc[k] = (centre[k] - o[k]) * id[k];
        const int past = !(tc[k] > tn); /* on or past the plane at the entry */
        c |= (uint32_t)(d[k] > 0.0f ? past : !past) << k;
        pending[k] = tc[k] > tn && tc[k] < tf;
    }
    float from = tn;
    for (;;) {
        int next = -1;
        for (int k = 0; k < w->axes; ++k)
            if (pending[k] && (next < 0 || tc[k] < tc[next])) next = k;
        const float to = next < 0 ? tf : tc[next];
        sidx_aabb cb = box;
        float *clo = sidx_v3_array_rw(&cb.min), *chi = sidx_v3_array_rw(&cb.max);
        for (int k = 0; k < w->axes; ++k) {
            if ((c >> k) & 1u) clo[k] = centre[k];
            else chi[k] = centre[k];
        }
        const int got = visit(w, n->a + c, depth + 1, cb, from, to, stop);
        if (*stop) return got;
        if (next < 0) return 0;
        pending[next] = 0;
        c ^= 1u << next;
        from = to;
    }
}

int oct_walk(const sidx_ex *ex, const sidx_oct_node *nodes, const uint32_t *refs, sidx_aabb root, int axes,
             float t_near, float t_far, sidx_hit *best)
{
    const walk w = {ex, nodes, refs, axes, best};
    int stop = 0;
    return visit(&w, 0, 0, root, t_near, t_far, &stop);
}
