/* Borrowed: a query of the library on the tree, its events relayed.
 * expect: uses sidx_accel_intersect, which this exercise asks you to write
 */
#include "sidx/sidx.h"
#include "sidx/bsp.h"
#include "sidx/exercise.h"

void bsp_paint(const sidx_accel *bsp, sidx_vec3 eye, const sidx_ex *ex)
{
    sidx_ray r;
    sidx_hit h;
    if (sidx_ray_init(&r, eye, sidx_v3(0, 0, 1), 0, 1e30f) != SIDX_OK) return;
    if (sidx_accel_intersect(bsp, &r, NULL, &h) == SIDX_OK && h.prim != SIDX_NO_HIT)
        sidx_ex_prim_test(ex, h.prim, 1, h.t);
}
