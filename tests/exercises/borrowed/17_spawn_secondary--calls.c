/* Borrowed: the library's own offset origin, and its shadow ray.
 * expect: uses sidx_ray_spawn_origin, which this exercise asks you to write
 */
#include "sidx/sidx.h"

sidx_status spawn_origin(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 dir, sidx_vec3 *out)
{
    return sidx_ray_spawn_origin(p, p_err, ng, dir, out);
}

sidx_status spawn_to(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 target, sidx_ray *out)
{
    sidx_vec3 o;
    const sidx_status s = sidx_ray_spawn_origin(p, p_err, ng, sidx_v3_sub(target, p), &o);
    if (s != SIDX_OK) return s;
    return sidx_ray_init(out, o, sidx_v3_sub(target, o), 0.0f, 1.0f);
}
