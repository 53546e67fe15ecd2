/* Reference solution of 03_ray_box (deck 000, "Bounding Volumes": the
 * AABB's "min-max" test, i.e. the slab test of Kay & Kajiya 1986). */
#include "sidx/sidx.h"

int ray_box(const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far)
{
    float lo[3], hi[3], o[3], inv[3];
    sidx_v3_to_array(box->min, lo);
    sidx_v3_to_array(box->max, hi);
    sidx_v3_to_array(r->org, o);
    sidx_v3_to_array(r->inv_dir, inv);
    float t0 = tmin, t1 = tmax;
    for (int k = 0; k < 3; ++k) {
        /* near and far plane by the sign of the direction (-0 counts as negative) */
        const float np = r->sign[k] ? hi[k] : lo[k], fp = r->sign[k] ? lo[k] : hi[k];
        const float tn = (np - o[k]) * inv[k], tf = (fp - o[k]) * inv[k];
        /* written so that a NaN (0·inf: origin on a plane the ray runs along) changes nothing */
        if (tn > t0) t0 = tn;
        if (tf < t1) t1 = tf;
    }
    if (t0 > t1) return 0;
    *t_near = t0;
    *t_far = t1;
    return 1;
}
