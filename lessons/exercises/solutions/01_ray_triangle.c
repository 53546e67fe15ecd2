/* Reference solution of 01_ray_triangle (deck 001, "Ray-Plane
 * Intersection", "Ray-Triangle Intersection"). */
#include "sidx/sidx.h"

int ray_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t)
{
    const float nd = sidx_v3_dot(n, r->dir);
    if (nd == 0.0f) return 0; /* parallel, or lying in the plane: no unique t */
    const float tt = (c - sidx_v3_dot(n, r->org)) / nd;
    if (!(tt >= r->tmin && tt < r->tmax)) return 0;
    *t = tt;
    return 1;
}

int ray_triangle_two_step(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t)
{
    /* i) the plane through the triangle: N = e1 x e2, c = N·p0 */
    const sidx_vec3 e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0);
    const sidx_vec3 n = sidx_v3_cross(e1, e2);
    const float nd = sidx_v3_dot(n, r->dir);
    if (nd == 0.0f) return 0;
    const float tt = (sidx_v3_dot(n, p0) - sidx_v3_dot(n, r->org)) / nd;
    if (!(tt >= r->tmin && tt < tmax)) return 0;
    /* ii) p = o + t·d in barycentric coordinates: p - p0 = u·e1 + v·e2 */
    const sidx_vec3 w = sidx_v3_sub(sidx_ray_at(r, tt), p0);
    const float d00 = sidx_v3_dot(e1, e1), d01 = sidx_v3_dot(e1, e2), d11 = sidx_v3_dot(e2, e2);
    const float d20 = sidx_v3_dot(w, e1), d21 = sidx_v3_dot(w, e2);
    const float den = d00 * d11 - d01 * d01;
    if (den == 0.0f) return 0;
    const float u = (d11 * d20 - d01 * d21) / den;
    const float v = (d00 * d21 - d01 * d20) / den;
    if (!(u >= 0.0f && v >= 0.0f && u + v <= 1.0f)) return 0;
    *t = tt;
    return 1;
}
