/* Reference solution of 09_kdtree_sah (deck 000, "Building good
 * kD-trees", "Cost-Optimized Split"). */
#include <stdlib.h>
#include "sidx/sidx.h"
#include "sidx/exercise.h"

enum { END = 0, PLANAR = 1, START = 2 }; /* the order of events at one position */

typedef struct ev {
    float pos;
    int type;
} ev;

static int ev_cmp(const void *pa, const void *pb)
{
    const ev *x = pa, *y = pb;
    if (x->pos != y->pos) return x->pos < y->pos ? -1 : 1;
    return x->type - y->type;
}

/* The SAH of the plane at pos on axis k, with the empty-space bonus.  A
 * child cell's area is 2·(ea·eb + (its length on k)·(ea + eb)). */
static float cost(sidx_aabb cell, int k, float pos, uint32_t nl, uint32_t nr, float c_trav, float c_tri,
                  float bonus)
{
    const sidx_vec3 e = sidx_aabb_extent(cell);
    const float ea = k == 0 ? e.y : e.x, eb = k == 2 ? e.y : e.z;
    const float lo = sidx_v3_get(cell.min, k), hi = sidx_v3_get(cell.max, k);
    const float inv = 1.0f / sidx_aabb_area(cell);
    const float pl = 2.0f * (ea * eb + (pos - lo) * (ea + eb)) * inv;
    const float pr = 2.0f * (ea * eb + (hi - pos) * (ea + eb)) * inv;
    float c = c_trav + c_tri * (pl * (float)nl + pr * (float)nr);
    if (nl == 0 || nr == 0) c *= 1.0f - bonus;
    return c;
}

void kd_split(const sidx_ex *ex, uint32_t node, sidx_aabb cell, const sidx_aabb *boxes, uint32_t n, float c_trav,
              float c_tri, float empty_bonus)
{
    ev *E = malloc((2 * (size_t)n + 1) * sizeof *E);
    float best = INFINITY, best_pos = 0;
    int best_axis = -1;
    uint32_t best_nl = 0, best_nr = 0;
    for (int k = 0; k < 3 && E; ++k) {
        size_t m = 0;
        for (uint32_t i = 0; i < n; ++i) {
            const float lo = sidx_v3_get(boxes[i].min, k), hi = sidx_v3_get(boxes[i].max, k);
            if (lo == hi) {
                E[m++] = (ev){lo, PLANAR};
            } else {
                E[m++] = (ev){lo, START};
                E[m++] = (ev){hi, END};
            }
        }
        qsort(E, m, sizeof *E, ev_cmp);
        const float clo = sidx_v3_get(cell.min, k), chi = sidx_v3_get(cell.max, k);
        uint32_t nl = 0, nr = n;
        for (size_t i = 0; i < m;) {
            const float p = E[i].pos;
            uint32_t pe = 0, pp = 0, ps = 0;
            while (i < m && E[i].pos == p && E[i].type == END) ++pe, ++i;
            while (i < m && E[i].pos == p && E[i].type == PLANAR) ++pp, ++i;
            while (i < m && E[i].pos == p && E[i].type == START) ++ps, ++i;
            nr -= pe + pp;
            if (p > clo && p < chi) {
                const float cl = cost(cell, k, p, nl + pp, nr, c_trav, c_tri, empty_bonus);
                const float cr = pp ? cost(cell, k, p, nl, nr + pp, c_trav, c_tri, empty_bonus) : cl;
                const int left = cl <= cr;
                const float c = left ? cl : cr;
                const uint32_t cnl = left ? nl + pp : nl, cnr = left ? nr : nr + pp;
                sidx_ex_candidate(ex, node, k, p, c, cnl, cnr);
                if (c < best) {
                    best = c;
                    best_pos = p;
                    best_axis = k;
                    best_nl = cnl;
                    best_nr = cnr;
                }
            }
            nl += ps + pp;
        }
    }
    if (best_axis >= 0) sidx_ex_split(ex, node, best_axis, best_pos, best, best_nl, best_nr);
    free(E);
}
