/* Reference solution of 02_moller_trumbore (deck 001, "Moller-Trumbore
 * Algorithm"): s = u·e1 + v·e2 − t·d solved by Cramer's rule. */
#include "sidx/sidx.h"

int moller_trumbore(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t, float *u,
                    float *v)
{
    const sidx_vec3 e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0), s = sidx_v3_sub(r->org, p0);
    const sidx_vec3 e1xd = sidx_v3_cross(e1, r->dir), sxe2 = sidx_v3_cross(s, e2);
    const float D = sidx_v3_dot(e1xd, e2);
    if (D == 0.0f) return 0; /* parallel ray or degenerate triangle: no unique solution */
    const float uu = -sidx_v3_dot(sxe2, r->dir) / D;
    const float vv = sidx_v3_dot(e1xd, s) / D;
    const float tt = -sidx_v3_dot(sxe2, e1) / D;
    if (!(uu >= 0.0f && vv >= 0.0f && uu + vv <= 1.0f)) return 0;
    if (!(tt >= r->tmin && tt < tmax)) return 0; /* behind the origin, or not closer than tmax */
    *t = tt;
    *u = uu;
    *v = vv;
    return 1;
}
