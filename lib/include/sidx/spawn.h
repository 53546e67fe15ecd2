/* sidx/spawn.h — secondary rays that neither hit the surface they leave
 * nor skip what lies just beyond it, with no scene-size epsilon.
 *
 * Deck 000 / 001 on shadow and bounce rays: "be careful about the
 * numerical rounding errors".  The usual answer, starting the new ray at
 * tmin = 1e-3, fails both ways: on a millimetre model 1e-3 skips whole
 * occluders, and a million units from the origin the stored hit point is
 * itself off by more than 1e-3, so the ray hits the surface it left
 * (lesson 24 counts both).  The answer of Pharr, Jakob, Humphreys,
 * "Physically Based Rendering" 3rd ed. §3.9 (pbrt-v3/v4) is used here:
 *
 * 1. The hit point with a bound on its rounding error (SIDX_QUERY_POINT,
 *    sidx_triangle_point).  With u, v the accepting test's barycentrics,
 *    the exact point P = (1-u-v)·p0 + u·p1 + v·p2 lies exactly in the
 *    triangle's plane (the weights sum to 1 in real arithmetic).  The
 *    float point is b0 = fl(fl(1-u) - v), p = fl(fl(b0·p0 + u·p1) + v·p2)
 *    per component.  Writing fl(x∘y) = (x∘y)(1+δ), |δ| <= ε = 2^-24, and
 *    γn = nε/(1-nε) (PBR §3.9.1):
 *      - two roundings in b0: b0 = β0 + η with β0 = 1-u-v and
 *        |η| <= ε|β0| + ε(1+ε)|1-u|  (the second term is the rounding
 *        of 1-u, which is not relative to a small β0);
 *      - three products and two sums: |p - (b0 p0 + u p1 + v p2)|
 *        <= γ3 (|b0 p0| + |u p1| + |v p2|)  (PBR §3.9.2, sums of products);
 *      - together, with |β0| <= |b0|(1+γ1) + ...:
 *        |p - P| <= γ4 |b0 p0| + γ3 (|u p1| + |v p2|) + γ2 |1-u| |p0|.
 *    sidx stores p_err = γ7 (|b0 p0| + |u p1| + |v p2|) + γ3 |1-u| |p0|,
 *    pbrt's γ7 bound plus the term for b0 = 1-u-v (pbrt divides three
 *    edge functions instead); the spare γ's cover the rounding of
 *    evaluating the bound itself in float.
 *    p_err is then widened by 2κ(err_x + err_y + err_z), where κ bounds
 *    the rounding of the unit normal's direction computed from the float
 *    ng = (p1-p0)×(p2-p0) (κ = 2γ6 |A| / |ng|, A_x = |e1y e2z| + |e1z e2y|,
 *    ...): a few 1e-7 of err for a well-shaped triangle, large for a
 *    sliver whose float normal points nowhere in particular — the offset
 *    below is taken along that float normal, so its error must be paid.
 *    Last, p_err is widened by the triangle test's own resolution,
 *    γ32·R·max(1, R²/|ng|) with R the distance from p to the farthest
 *    vertex.  The watertight test shears the vertices relative to the ray
 *    origin and rounds them by ε·(their distance from it), not by the
 *    point's error: an origin closer to the plane than that can still see
 *    its own triangle at a tiny t >= 0 (PBR §3.9.6 bounds the same δt by
 *    terms in ε·R²/area and rejects t <= δt inside the test; sidx keeps
 *    its test and moves the origin instead).  The form is PBR's, the
 *    constant is measured: tests/test_spawn.c finds 85 self-intersections
 *    on the Cornell box without this term and none from γ1 up; γ32 keeps
 *    a factor 32 of margin.
 *
 * 2. The ray origin offset off the surface (sidx_ray_spawn_origin): along
 *    the unit geometric normal n by d = |n_x| err_x + |n_y| err_y +
 *    |n_z| err_z, the largest distance from the plane that any point of
 *    the error box around p can have, to the side the direction leaves
 *    through (sign of n·dir), computed in double and rounded to float
 *    away from the surface, then moved one more ulp away per component
 *    (nextafterf) so the rounding can only add distance (PBR §3.9.5,
 *    "Robust spawned ray origins").  The exact plane through P then lies
 *    strictly behind the origin: the spawned ray cannot hit its own
 *    triangle, nor a coplanar neighbour, at any t >= 0.
 *
 * Guarantees and limits:
 *  - Every spawned ray starts at tmin = 0; no distance is skipped except
 *    the offset itself, which is at most |n|·err beyond the surface —
 *    an occluder closer to the surface than the hit point's own error
 *    bound may be missed (it is inside the point's uncertainty).
 *  - A non-coplanar neighbour (a concave corner) can be hit, correctly.
 *  - Triangles far from planar in float (slivers, κ >= 1/8) and zero-area
 *    triangles are refused with SIDX_ERR_BAD_GEOMETRY: their float normal
 *    does not say which side is which.
 *  - Points, bounds and offsets overflowing float (|p| near FLT_MAX)
 *    are refused with SIDX_ERR_BAD_GEOMETRY.
 *  - Instanced hits (hit.instance != SIDX_NO_HIT) and packet queries do
 *    not fill the point; sidx_ray_spawn refuses a hit without it
 *    (SIDX_ERR_INVALID_ARG).
 *  - Shadow rays towards another hit end short of it (PBR's
 *    1 - ShadowEpsilon, SIDX_SPAWN_SHADOW_EPS below): both ends are
 *    offset off their surfaces, and the last 1e-4 of the segment is left
 *    out so that the rounding of the target triangle's own t cannot
 *    report it as its own occluder.  An occluder in that last 1e-4 of the
 *    way is missed — relative to the segment, not an absolute distance.
 *
 * Usage:
 *     sidx_query q = {SIDX_QUERY_POINT, SIDX_TRAVERSE_DEFAULT, NULL, 0};
 *     sidx_hit h; sidx_accel_intersect(a, &camera_ray, &q, &h);
 *     sidx_ray shadow;
 *     if (h.prim != SIDX_NO_HIT && sidx_ray_spawn_to(&h, light, &shadow) == SIDX_OK)
 *         sidx_accel_occluded(a, &shadow, NULL, &blocked);
 */
#ifndef SIDX_SPAWN_H
#define SIDX_SPAWN_H

#include "math.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The fraction of a shadow segment between two hits left out at its far
 * end (pbrt's ShadowEpsilon): the ray's tmax is 1 - SIDX_SPAWN_SHADOW_EPS. */
#define SIDX_SPAWN_SHADOW_EPS 1e-4f

/* The point (1-u-v)·p0 + u·p1 + v·p2 and its error bound (the derivation
 * above), widened for the direction error of the float normal
 * (p1-p0)×(p2-p0).  SIDX_ERR_INVALID_ARG on NULL outputs or non-finite
 * input, SIDX_ERR_BAD_GEOMETRY for a zero-area or sliver triangle or an
 * overflowing result (outputs untouched then). */
sidx_status sidx_triangle_point(sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float u, float v, sidx_vec3 *p,
                                sidx_vec3 *p_err);

/* The origin of a ray leaving the surface with normal ng (any length, not
 * zero) at p (error bound p_err) in direction dir: offset to the side dir
 * points to.  A dir tangent to the surface (n·dir = 0) goes to the side of
 * +ng.  SIDX_ERR_INVALID_ARG for NULL out, NaN/Inf input, a zero ng or
 * a zero dir. */
sidx_status sidx_ray_spawn_origin(sidx_vec3 p, sidx_vec3 p_err, sidx_vec3 ng, sidx_vec3 dir, sidx_vec3 *out);

/* A ray leaving hit (queried with SIDX_QUERY_POINT) in direction dir,
 * tmin 0, tmax +inf.  Errors (SIDX_ERR_INVALID_ARG, *out untouched): NULL
 * arguments, a miss, a hit without its point, a NaN/Inf or zero dir. */
sidx_status sidx_ray_spawn(const sidx_hit *hit, sidx_vec3 dir, sidx_ray *out);

/* A shadow ray from hit to the point target (a light): direction
 * target - origin, tmin 0, tmax 1 (half-open: the target itself is not
 * tested).  For a target lying on a surface use sidx_ray_spawn_to_hit.
 * Errors as sidx_ray_spawn; SIDX_ERR_INVALID_ARG also when target is
 * the origin itself. */
sidx_status sidx_ray_spawn_to(const sidx_hit *hit, sidx_vec3 target, sidx_ray *out);

/* A shadow ray between two hits (both queried with SIDX_QUERY_POINT):
 * from `from` offset towards `to`, to `to` offset back towards `from`,
 * tmax 1 - SIDX_SPAWN_SHADOW_EPS.  Errors as sidx_ray_spawn_to. */
sidx_status sidx_ray_spawn_to_hit(const sidx_hit *from, const sidx_hit *to, sidx_ray *out);

#ifdef __cplusplus
}
#endif
#endif
