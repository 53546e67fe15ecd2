/* Reference solution of 17_spawn_secondary (deck 001, "Ray-Triangle
 * Intersection": "be careful about the numerical rounding errors"; PBR
 * §3.9.5, "Robust spawned ray origins"). */
#include <math.h>
#include "sidx/sidx.h"

static int finite3(sidx_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* x rounded to float away from the surface, then one float further. */
static float away(double x, double off)
{
    float f = (float)x;
    if (off > 0.0) {
        if ((double)f < x) f = nextafterf(f, INFINITY);
        f = nextafterf(f, INFINITY);
    } else if (off < 0.0) {
        if ((double)f > x) f = nextafterf(f, -INFINITY);
        f = nextafterf(f, -INFINITY);
    }
    return f;
}

sidx_status spawn_origin(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 dir, sidx_vec3 *out)
{
    if (!finite3(p) || !finite3(p_err) || !finite3(ng) || !finite3(dir)) return SIDX_ERR_INVALID_ARG;
    if (dir.x == 0.0f && dir.y == 0.0f && dir.z == 0.0f) return SIDX_ERR_INVALID_ARG;
    const double len = sqrt((double)ng.x * ng.x + (double)ng.y * ng.y + (double)ng.z * ng.z);
    if (!(len > 0.0)) return SIDX_ERR_INVALID_ARG;
    const double n[3] = {ng.x / len, ng.y / len, ng.z / len};
    double d = fabs(n[0]) * p_err.x + fabs(n[1]) * p_err.y + fabs(n[2]) * p_err.z;
    if (n[0] * dir.x + n[1] * dir.y + n[2] * dir.z < 0.0) d = -d;
    const float pp[3] = {p.x, p.y, p.z};
    float o[3];
    for (int k = 0; k < 3; ++k) {
        const double off = d * n[k];
        o[k] = away((double)pp[k] + off, off);
    }
    const sidx_vec3 res = sidx_v3(o[0], o[1], o[2]);
    if (!finite3(res)) return SIDX_ERR_INVALID_ARG;
    *out = res;
    return SIDX_OK;
}

sidx_status spawn_to(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 target, sidx_ray *out)
{
    sidx_vec3 o;
    const sidx_status s = spawn_origin(p, p_err, ng, sidx_v3_sub(target, p), &o);
    if (s != SIDX_OK) return s;
    return sidx_ray_init(out, o, sidx_v3_sub(target, o), 0.0f, 1.0f);
}
