/* Borrowed: the library's three bounding-volume tests.
 * expect: uses sidx_intersect_kdop, which this exercise asks you to write
 */
#include "sidx/sidx.h"

int ray_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far)
{
    return sidx_intersect_sphere(r, s, tmin, tmax, t_near, t_far);
}

int ray_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far)
{
    return sidx_intersect_obb(r, b, tmin, tmax, t_near, t_far);
}

int ray_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far)
{
    return sidx_intersect_kdop(r, k, tmin, tmax, t_near, t_far);
}
