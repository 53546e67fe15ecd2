/* Not borrowed but forged: defines a function of the library (here the
 * exercise's event call) to replace the library's own.
 * expect: defines sidx_ex_prim_test, a name of the library
 */
#include "sidx/sidx.h"
#include "sidx/exercise.h"

void sidx_ex_prim_test(const sidx_ex *ex, uint32_t prim, int result, float t)
{
    (void)ex, (void)prim, (void)result, (void)t;
}

sidx_status spawn_origin(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 dir, sidx_vec3 *out)
{
    (void)p_err, (void)ng, (void)dir;
    *out = p;
    return SIDX_OK;
}

sidx_status spawn_to(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 target, sidx_ray *out)
{
    (void)p_err, (void)ng;
    return sidx_ray_init(out, p, sidx_v3_sub(target, p), 0.0f, 1.0f);
}
