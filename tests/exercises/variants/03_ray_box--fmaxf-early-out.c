/* A correct 03_ray_box organised differently: the slab bounds folded in
 * with fmaxf / fminf (which return the other operand when one is NaN, so
 * a NaN slab, 0·inf for an origin on a plane the ray runs along, changes
 * nothing) and an early out as soon as the interval is empty (t0 only
 * grows and t1 only shrinks, so an empty interval stays empty). */
#include <math.h>
#include "sidx/sidx.h"

int ray_box(const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far)
{
    const float lo[3] = {box->min.x, box->min.y, box->min.z}, hi[3] = {box->max.x, box->max.y, box->max.z};
    const float o[3] = {r->org.x, r->org.y, r->org.z}, inv[3] = {r->inv_dir.x, r->inv_dir.y, r->inv_dir.z};
    float t0 = tmin, t1 = tmax;
    for (int k = 0; k < 3; ++k) {
        const float near_plane = r->sign[k] ? hi[k] : lo[k], far_plane = r->sign[k] ? lo[k] : hi[k];
        t0 = fmaxf(t0, (near_plane - o[k]) * inv[k]);
        t1 = fminf(t1, (far_plane - o[k]) * inv[k]);
        if (t0 > t1) return 0;
    }
    *t_near = t0;
    *t_far = t1;
    return 1;
}
