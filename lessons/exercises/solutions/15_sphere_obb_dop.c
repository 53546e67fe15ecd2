/* Reference solution of 15_sphere_obb_dop (deck 000, "Bounding Volumes":
 * the sphere, the OBB and the slabs of a 14-DOP). */
#include "sidx/sidx.h"

int ray_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far)
{
    const sidx_vec3 f = sidx_v3_sub(r->org, s->center);
    const float a = sidx_v3_dot(r->dir, r->dir);
    const float b = -sidx_v3_dot(f, r->dir);
    /* l: from the centre to the closest point of the ray's line */
    const sidx_vec3 l = sidx_v3_add(f, sidx_v3_scale(r->dir, b / a));
    const float disc = a * (s->radius * s->radius - sidx_v3_dot(l, l));
    if (disc < 0.0f) return 0;
    const float sq = sqrtf(disc);
    float t0 = (b - sq) / a, t1 = (b + sq) / a;
    if (t0 < tmin) t0 = tmin;
    if (t1 > tmax) t1 = tmax;
    if (t0 > t1) return 0;
    *t_near = t0;
    *t_far = t1;
    return 1;
}

/* Clips [*t0, *t1] by the slab lo <= n·x <= hi; 0 when it becomes empty. */
static int slab(const sidx_ray *r, sidx_vec3 n, float lo, float hi, float *t0, float *t1)
{
    const float nd = sidx_v3_dot(n, r->dir), no = sidx_v3_dot(n, r->org);
    if (nd == 0.0f) return no >= lo && no <= hi;
    float a = (lo - no) / nd, b = (hi - no) / nd;
    if (a > b) {
        const float tmp = a;
        a = b;
        b = tmp;
    }
    if (a > *t0) *t0 = a;
    if (b < *t1) *t1 = b;
    return *t0 <= *t1;
}

int ray_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far)
{
    float t0 = tmin, t1 = tmax;
    const float h[3] = {b->half.x, b->half.y, b->half.z};
    for (int i = 0; i < 3; ++i) {
        const float c = sidx_v3_dot(b->axis[i], b->center);
        if (!slab(r, b->axis[i], c - h[i], c + h[i], &t0, &t1)) return 0;
    }
    *t_near = t0;
    *t_far = t1;
    return 1;
}

int ray_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far)
{
    float t0 = tmin, t1 = tmax;
    for (int i = 0; i < SIDX_KDOP_AXES; ++i)
        if (!slab(r, sidx_kdop_axis(i), k->lo[i], k->hi[i], &t0, &t1)) return 0;
    *t_near = t0;
    *t_far = t1;
    return 1;
}
