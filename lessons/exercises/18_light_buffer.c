/* Exercise 18 — the light buffer's cached occluder.
 *
 * Slide: deck 000, "Directional Partitioning": "Variation: Light buffer
 * (for shadow rays)" — "Lazy and conservative evaluation", "Store last
 * found occluder in directional structure", "Test entry first for next
 * shadow test".  A direction cube around a point light (sidx/lightbuffer.h):
 * each cell lists the triangles that could be seen from the light through
 * it, nearest to the light first.  A shadow ray from a surface point p to
 * the light looks up the cell of the direction light -> p; neighbouring
 * shadow rays tend to be blocked by the same triangle, so each cell keeps
 * the last occluder found in it.
 *
 * Write lb_shadow_test: is the shadow ray ex->ray (origin p, direction
 * light - p, so t = 1 is the light; t in [ray.tmin, ray.tmax)) blocked?
 * cell is the ray's cell (its list tris[0..count-1], their distances
 * dist[] from the light, and reach); *last is the cell's cached occluder
 * (SIDX_NO_HIT: none yet).
 *   1. If the cell has a cached occluder, test it first:
 *      sidx_ex_test_triangle(ex, *last, ex->ray->tmax, &t).  A hit: the
 *      point is in shadow, return 1 (the cache stays as it is).
 *   2. Else walk the list in its order.  Stop (return 0) at the first
 *      triangle with dist > reach: it lies beyond the shadow segment, and
 *      so does everything after it.  Skip the cached triangle (tested in
 *      1).  Test each other one with sidx_ex_test_triangle over
 *      [tmin, ray.tmax): a hit beyond the light does not shadow p.
 *   3. On a hit: remember the triangle in *last, return 1 (on a hit stop:
 *      any occluder will do, the nearest is not needed).
 *   4. The list ran out or reached reach: return 0 (*last unchanged).
 *
 * The checker runs several shadow rays in a row with one cache per case
 * and compares every triangle test, the verdict and the cell's cached
 * occluder after each ray with the library's sidx_lightbuffer_occluded.
 * Awkward cases it tries: a cell with no cached occluder, a cached
 * occluder that misses this ray, an occluder exactly at tmax, a ray
 * starting on a surface (tmin = 0 and tmin > 0), lazy and eager cells.
 *
 * Check with:   make exercise EX=18_light_buffer
 * Only the function body is yours to write. */
#include "sidx/sidx.h"
#include "sidx/exercise.h"

int lb_shadow_test(const sidx_lightbuffer_cell_view *cell, uint32_t *last, const sidx_ex *ex)
{
    (void)cell;
    (void)last;
    (void)ex;
    return 0;
}
