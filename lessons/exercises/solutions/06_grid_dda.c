/* Reference solution of 06_grid_dda (deck 000, "Uniform Grids",
 * "Uniform Grid Traversal"). */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/grid.h"
#include "sidx/exercise.h"

void grid_resolution(sidx_vec3 d, double n, double lambda, uint32_t res[3])
{
    const double e[3] = {d.x, d.y, d.z};
    double vol = 1.0;
    int dims = 0;
    for (int i = 0; i < 3; ++i)
        if (e[i] > 0.0) {
            vol *= e[i];
            ++dims;
        }
    const double s = dims ? pow(lambda * n / vol, 1.0 / dims) : 0.0;
    for (int i = 0; i < 3; ++i) {
        const double r = e[i] > 0.0 ? floor(e[i] * s + 0.5) : 1.0;
        res[i] = r >= 1.0 ? (uint32_t)r : 1u;
    }
}

void grid_walk(const sidx_ex *ex, const sidx_grid_cells *g, sidx_hit *best)
{
    const sidx_ray *r = ex->ray;
    float t0, t1;
    if (!sidx_intersect_aabb(SIDX_BOX_PLAIN, r, &g->box, r->tmin, best->t, &t0, &t1)) return;
    const float o[3] = {r->org.x, r->org.y, r->org.z}, d[3] = {r->dir.x, r->dir.y, r->dir.z};
    const float inv[3] = {r->inv_dir.x, r->inv_dir.y, r->inv_dir.z};
    const float lo[3] = {g->box.min.x, g->box.min.y, g->box.min.z};
    int c[3], step[3], up[3];
    float t_max[3];
    for (int i = 0; i < 3; ++i) {
        const float f = floorf((o[i] + t0 * d[i] - lo[i]) * g->inv_cell[i]);
        c[i] = !(f >= 0.0f) ? 0 : f >= (float)g->res[i] ? (int)g->res[i] - 1 : (int)f;
        step[i] = d[i] > 0.0f ? 1 : d[i] < 0.0f ? -1 : 0;
        up[i] = d[i] > 0.0f;
        t_max[i] = step[i] ? ((float)(c[i] + up[i]) * g->cell[i] + (lo[i] - o[i])) * inv[i] : INFINITY;
    }
    float t_in = t0;
    for (;;) {
        const int axis = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
        const float t_out = t_max[axis];
        const uint32_t id = (uint32_t)c[0] + g->res[0] * ((uint32_t)c[1] + g->res[1] * (uint32_t)c[2]);
        sidx_ex_cell_enter(ex, id, c[0], c[1], c[2], t_in, t_out);
        for (uint32_t k = g->offsets[id]; k < g->offsets[id + 1]; ++k) {
            float t;
            if (sidx_ex_test_triangle(ex, g->refs[k], best->t, &t)) {
                best->t = t;
                best->prim = g->refs[k];
                sidx_ex_hit_update(ex, g->refs[k], t);
            }
        }
        if (best->t <= t_out) return; /* a hit inside this cell is final */
        c[axis] += step[axis];
        if (c[axis] < 0 || c[axis] >= (int)g->res[axis]) return;
        t_max[axis] = ((float)(c[axis] + up[axis]) * g->cell[axis] + (lo[axis] - o[axis])) * inv[axis];
        t_in = t_out;
    }
}
