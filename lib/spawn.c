/* spawn.c — hit points with error bounds, and secondary rays spawned from
 * them (sidx/spawn.h has the derivation; Pharr, Jakob, Humphreys, PBR 3rd
 * ed. §3.9).  Nothing here runs inside a traversal: the point of a hit is
 * formed once, after the closest hit is known, and only when
 * SIDX_QUERY_POINT asks for it (sidx__hit_finish, hit.c, calls
 * sidx_triangle_point). */
#include "sidx_internal.h"

/* The multiple of ε in the test-resolution term of the bound (below). */
#ifndef SPAWN_TEST_GAMMA
#define SPAWN_TEST_GAMMA 32
#endif

/* γn = nε / (1 - nε), ε = 2^-24 the unit roundoff of float (PBR §3.9.1). */
static double gamma_n(int n)
{
    const double eps = 0x1p-24;
    return n * eps / (1.0 - n * eps);
}

/* A double bound as a float that is not smaller. */
static float round_up(double x)
{
    float f = (float)x;
    if ((double)f < x) f = nextafterf(f, INFINITY);
    return f;
}

sidx_status sidx_triangle_point(sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float u, float v, sidx_vec3 *p,
                                sidx_vec3 *p_err)
{
    if (!p || !p_err) return SIDX_ERR_INVALID_ARG;
    if (!sidx_v3_isfinite(p0) || !sidx_v3_isfinite(p1) || !sidx_v3_isfinite(p2) || !isfinite(u) || !isfinite(v))
        return SIDX_ERR_INVALID_ARG;
    /* The float reconstruction the bound is derived for (spawn.h, 1.):
     * b0 = (1-u)-v, then (b0·p0 + u·p1) + v·p2, left to right, no FMA
     * (the Makefile compiles with -ffp-contract=off). */
    const float b0 = (1.0f - u) - v;
    const sidx_vec3 pt = sidx_v3_add(sidx_v3_add(sidx_v3_scale(p0, b0), sidx_v3_scale(p1, u)), sidx_v3_scale(p2, v));
    const float *a0 = sidx_v3_array(&p0), *a1 = sidx_v3_array(&p1), *a2 = sidx_v3_array(&p2);
    double err[3];
    const double g7 = gamma_n(7), g3 = gamma_n(3), g6 = gamma_n(6);
    const double one_u = fabs(1.0 - (double)u);
    for (int k = 0; k < 3; ++k)
        err[k] = g7 * (fabs((double)b0 * a0[k]) + fabs((double)u * a1[k]) + fabs((double)v * a2[k])) +
                 g3 * one_u * fabs((double)a0[k]);
    /* The float normal hit.ng (same bits as sidx__tri_normal) and a bound
     * on its direction error: κ = 2γ6 |A| / |ng| with A_x = |e1y e2z| +
     * |e1z e2y| (cyclic), the magnitude of the products each component of
     * the cross product subtracts (PBR §3.9.2).  The offset is taken along
     * this float normal, so the error box is widened by 2κ·Σerr to pay for
     * its direction (spawn.h, 1.). */
    const sidx_vec3 e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0);
    const sidx_vec3 ng = sidx__tri_normal(p0, p1, p2);
    const double ax = fabs((double)e1.y * e2.z) + fabs((double)e1.z * e2.y),
                 ay = fabs((double)e1.z * e2.x) + fabs((double)e1.x * e2.z),
                 az = fabs((double)e1.x * e2.y) + fabs((double)e1.y * e2.x);
    const double nlen = sqrt((double)ng.x * ng.x + (double)ng.y * ng.y + (double)ng.z * ng.z);
    if (!(nlen > 0.0) || !isfinite(nlen)) return SIDX_ERR_BAD_GEOMETRY;
    const double kappa = 2.0 * g6 * sqrt(ax * ax + ay * ay + az * az) / nlen;
    if (kappa >= 0.125) return SIDX_ERR_BAD_GEOMETRY; /* a sliver: its float normal has no reliable side */
    /* The watertight test's own resolution (spawn.h, 2.): a spawned ray
     * starting closer to the plane than the test can resolve may still see
     * its own triangle at a tiny t >= 0, because the shear rounds the
     * vertices relative to the origin by ε·(their distance from it), not
     * by ε·(the point's error).  PBR §3.9.6 bounds that δt by terms in
     * ε·R²/|ng| with R the farthest vertex; the same form is added here
     * with a constant (SPAWN_TEST_GAMMA) measured on tests/test_spawn.c. */
    double R2 = 0.0;
    for (int i = 0; i < 3; ++i) {
        const float *vi = i == 0 ? a0 : i == 1 ? a1 : a2;
        const double dx = (double)vi[0] - pt.x, dy = (double)vi[1] - pt.y, dz = (double)vi[2] - pt.z;
        const double r2 = dx * dx + dy * dy + dz * dz;
        if (r2 > R2) R2 = r2;
    }
    const double R = sqrt(R2), shape = R2 / nlen > 1.0 ? R2 / nlen : 1.0;
    const double resolution = gamma_n(SPAWN_TEST_GAMMA) * R * shape;
    const double widen = 2.0 * kappa * (err[0] + err[1] + err[2]) + resolution;
    const sidx_vec3 e = sidx_v3(round_up(err[0] + widen), round_up(err[1] + widen), round_up(err[2] + widen));
    if (!sidx_v3_isfinite(pt) || !sidx_v3_isfinite(e)) return SIDX_ERR_BAD_GEOMETRY;
    *p = pt;
    *p_err = e;
    return SIDX_OK;
}

/* Away from the surface by one float: the offset's rounding to float can
 * then only add distance (PBR §3.9.5, "Robust spawned ray origins"). */
static float round_away(double x, double direction)
{
    float f = (float)x;
    if (direction > 0.0) {
        if ((double)f < x) f = nextafterf(f, INFINITY);
        f = nextafterf(f, INFINITY);
    } else if (direction < 0.0) {
        if ((double)f > x) f = nextafterf(f, -INFINITY);
        f = nextafterf(f, -INFINITY);
    }
    return f;
}

sidx_status sidx_ray_spawn_origin(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 dir, sidx_vec3 *out)
{
    if (!out || !sidx_v3_isfinite(p) || !sidx_v3_isfinite(p_err) || !sidx_v3_isfinite(ng) || !sidx_v3_isfinite(dir))
        return SIDX_ERR_INVALID_ARG;
    if (dir.x == 0.0f && dir.y == 0.0f && dir.z == 0.0f) return SIDX_ERR_INVALID_ARG;
    const double n[3] = {ng.x, ng.y, ng.z};
    const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0.0) || !isfinite(len)) return SIDX_ERR_INVALID_ARG;
    /* d: the farthest any point of the error box around p can lie from the
     * plane through p with unit normal n (the support of the box along n). */
    const double nu[3] = {n[0] / len, n[1] / len, n[2] / len};
    double d = fabs(nu[0]) * p_err.x + fabs(nu[1]) * p_err.y + fabs(nu[2]) * p_err.z;
    /* to the side the direction leaves through; a tangent one to +ng */
    if (nu[0] * dir.x + nu[1] * dir.y + nu[2] * dir.z < 0.0) d = -d;
    const float *pp = sidx_v3_array(&p);
    float o[3];
    for (int k = 0; k < 3; ++k) {
        const double off = d * nu[k];
        o[k] = round_away((double)pp[k] + off, off);
    }
    const sidx_vec3 res = sidx_v3_from_array(o);
    if (!sidx_v3_isfinite(res)) return SIDX_ERR_INVALID_ARG;
    *out = res;
    return SIDX_OK;
}

/* A hit that carries its point: a hit queried with SIDX_QUERY_POINT on a
 * triangle sidx_triangle_point accepted (p_err is then > 0 somewhere). */
static int has_point(const sidx_hit *h)
{
    return h->prim != SIDX_NO_HIT && (h->p_err.x > 0.0f || h->p_err.y > 0.0f || h->p_err.z > 0.0f);
}

sidx_status sidx_ray_spawn(const sidx_hit *hit, sidx_vec3 dir, sidx_ray *out)
{
    if (!hit || !out || !has_point(hit)) return SIDX_ERR_INVALID_ARG;
    sidx_vec3 o;
    const sidx_status s = sidx_ray_spawn_origin(hit->p, hit->p_err, hit->ng, dir, &o);
    if (s != SIDX_OK) return s;
    return sidx_ray_init(out, o, dir, 0.0f, INFINITY);
}

sidx_status sidx_ray_spawn_to(const sidx_hit *hit, sidx_vec3 target, sidx_ray *out)
{
    if (!hit || !out || !has_point(hit) || !sidx_v3_isfinite(target)) return SIDX_ERR_INVALID_ARG;
    sidx_vec3 o;
    const sidx_status s = sidx_ray_spawn_origin(hit->p, hit->p_err, hit->ng, sidx_v3_sub(target, hit->p), &o);
    if (s != SIDX_OK) return s;
    /* half-open [0, 1): the target point itself is not tested */
    return sidx_ray_init(out, o, sidx_v3_sub(target, o), 0.0f, 1.0f);
}

sidx_status sidx_ray_spawn_to_hit(const sidx_hit *from, const sidx_hit *to, sidx_ray *out)
{
    if (!from || !to || !out || !has_point(from) || !has_point(to)) return SIDX_ERR_INVALID_ARG;
    sidx_vec3 pf, pt;
    sidx_status s = sidx_ray_spawn_origin(from->p, from->p_err, from->ng, sidx_v3_sub(to->p, from->p), &pf);
    if (s != SIDX_OK) return s;
    /* the far end off its own surface, towards the near end (pbrt-v4's
     * SpawnRayTo between two interactions) */
    s = sidx_ray_spawn_origin(to->p, to->p_err, to->ng, sidx_v3_sub(pf, to->p), &pt);
    if (s != SIDX_OK) return s;
    return sidx_ray_init(out, pf, sidx_v3_sub(pt, pf), 0.0f, 1.0f - SIDX_SPAWN_SHADOW_EPS);
}
