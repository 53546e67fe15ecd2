/* Exercise 17 — spawning a secondary ray with error bounds.
 *
 * Slide: deck 001, "Ray-Triangle Intersection": "(be careful about the
 * numerical rounding errors)".  A shadow or bounce ray starts at the hit
 * point p, which is itself rounded: started at p (or at p + 1e-3·n) it
 * hits the surface it leaves, or skips an occluder right next to it.
 * The answer of Pharr, Jakob, Humphreys, "Physically Based Rendering",
 * §3.9.5 "Robust spawned ray origins": the hit point comes with a bound
 * p_err on its error per component (the library computes both,
 * sidx_triangle_point in sidx/spawn.h); move the origin off the surface
 * by just enough that no point of the error box around p lies beyond it.
 *
 * Write spawn_origin: the origin of a ray leaving the surface with normal
 * ng (any length) at p (error bound p_err) in direction dir.
 *   1. Refuse (return SIDX_ERR_INVALID_ARG, *out untouched) a NaN or
 *      infinite component in p, p_err, ng or dir, a zero dir, a zero ng.
 *   2. In double: n = ng / |ng| (the unit normal), and the offset
 *      d = |n.x|·err.x + |n.y|·err.y + |n.z|·err.z (the farthest a point of
 *      the error box lies from the plane through p).
 *   3. To the side dir leaves through: d = −d when n·dir < 0 (a tangent
 *      dir, n·dir = 0, goes to the side of +ng).
 *   4. Per component k: off = d·n_k, o_k = p_k + off in double, rounded
 *      to float *away* from the surface (if the rounding went back
 *      towards it, take the next float away), then one more float away
 *      (nextafterf towards +inf when off > 0, −inf when off < 0; off = 0
 *      leaves the component as it is).
 *   5. A result that is not finite: SIDX_ERR_INVALID_ARG.  Else *out, SIDX_OK.
 * Then spawn_to: the shadow ray from the hit (p, p_err, ng) to a light at
 * target: origin = spawn_origin(p, p_err, ng, target − p), direction
 * target − origin, t in [0, 1) (sidx_ray_init); the status of either step.
 *
 * The checker compares the origin bit for bit (the offset is a few ulps:
 * any tolerance would pass an origin left on the surface).
 * Awkward cases it tries: a tangent dir, an axis-aligned normal (±0
 * components: no nudge there), a normal that is not unit length, a point
 * a million units out, a zero error bound, NaN and infinite inputs, an
 * origin that overflows.
 *
 * Check with:   make exercise EX=17_spawn_secondary
 * Only the function bodies are yours to write. */
#include "sidx/sidx.h"

sidx_status spawn_origin(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 dir, sidx_vec3 *out)
{
    (void)p;
    (void)p_err;
    (void)ng;
    (void)dir;
    (void)out;
    return SIDX_OK;
}

sidx_status spawn_to(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 target, sidx_ray *out)
{
    (void)p;
    (void)p_err;
    (void)ng;
    (void)target;
    (void)out;
    return SIDX_OK;
}
