/* Exercise 06 — the uniform grid: its resolution, then the 3D-DDA walk.
 *
 * Slides: deck 000, "Uniform Grids" (Resolution: "Usually R_{x,y,z} =
 * d_{x,y,z}·∛(λn/V)") and "Uniform Grid Traversal" ("3D-DDA ... Step
 * through the structure cell by cell; intersect with primitives inside
 * non-empty cells").
 *
 * 1. grid_resolution — the number of cells per axis for a box of extent
 *    d (the diagonal, a vector), n objects and density λ:
 *    R_i = d_i·∛(λn/V), V = d_x·d_y·d_z, computed in double, rounded to
 *    the nearest integer, at least 1.  An axis of zero extent (a flat
 *    scene) gets one cell and the formula runs over the other k axes:
 *    V = their product, k-th root instead of the cube root.
 * 2. grid_walk — the cells a ray pierces, in order, through the library's
 *    own grid read with sidx/grid.h (box, res, cell, inv_cell; cell id
 *    c = x + res[0]·(y + res[1]·z) holds refs[offsets[c] .. offsets[c+1])).
 *    best starts as "no hit" with best->t = the ray's tmax.
 *    - clip the ray to g->box: sidx_intersect_aabb(SIDX_BOX_PLAIN, ray,
 *      &g->box, ray->tmin, best->t, &t0, &t1); a miss: return;
 *    - the first cell holds p = o + t0·d: per axis floor((p - box.min)
 *      ·inv_cell), clamped to [0, res - 1];
 *    - per axis: step = +1, -1, or 0 for a zero direction component;
 *      t_max = the t of the next cell boundary, computed (so your t agree
 *      with the library's to the last bit) as
 *          ((float)(c + up) * cell + (box.min - o)) * inv_dir,
 *      up = 1 when stepping up, 0 when down; +inf when step is 0;
 *    - each cell: report it with sidx_ex_cell_enter(ex, id, x, y, z, t_in,
 *      t_out), t_in = t0 for the first cell and the previous t_out after,
 *      t_out = the smallest t_max (the face the ray leaves through); test
 *      its triangles with sidx_ex_test_triangle(ex, prim, best->t, &t) and
 *      on a hit update best and call sidx_ex_hit_update(ex, prim, t);
 *    - stop when best->t <= t_out (a hit inside this cell is final: a hit
 *      beyond the exit may be beaten in a later cell), else step along
 *      the axis of the smallest t_max (on a tie the later axis: z before y
 *      before x); stop when the cell index leaves [0, res - 1].
 *
 * Check with:   make exercise EX=06_grid_dda
 * Only the two function bodies are yours to write (helpers of your own
 * are fine). */
#include <math.h>
#include "sidx/sidx.h"
#include "sidx/grid.h"
#include "sidx/exercise.h"

void grid_resolution(sidx_vec3 d, double n, double lambda, uint32_t res[3])
{
    (void)d;
    (void)n;
    (void)lambda;
    res[0] = res[1] = res[2] = 0;
}

void grid_walk(const sidx_ex *ex, const sidx_grid_cells *g, sidx_hit *best)
{
    (void)ex;
    (void)g;
    (void)best;
}
