/* Borrowed: the checker's own reference of the exercise.
 * expect: uses sidx_ex_reference_moller_cramer, which this exercise asks you to write
 */
#include "sidx/sidx.h"
#include "sidx/exercise.h"

int moller_trumbore(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t, float *u,
                    float *v)
{
    return sidx_ex_reference_moller_cramer(r, p0, p1, p2, tmax, t, u, v);
}
