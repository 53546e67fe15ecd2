/* Exercise 01 — ray–plane intersection, then the two-step ray–triangle test.
 *
 * Slides: deck 001, "Ray-Plane Intersection" and "Ray-Triangle Intersection".
 *
 * 1. ray_plane: the plane N·x = c.  Plug the ray o + t·d into it and solve
 *    for t = (c − N·o) / (N·d).  Return 1 and write *t when the ray meets
 *    the plane at a t in [r->tmin, r->tmax); return 0 otherwise, with *t
 *    left as it was — think of N·d = 0 (what does it mean?), of a negative
 *    t, and of a ray whose tmin is not 0.
 * 2. ray_triangle_two_step: "i) compute ray-plane intersection to find
 *    point p on plane; ii) perform point-in-triangle test for point p" with
 *    barycentric coordinates.  The plane through p0, p1, p2 has
 *    N = (p1 − p0) × (p2 − p0) and c = N·p0.  A hit needs t in
 *    [r->tmin, tmax) and p inside the triangle or on its boundary; on a
 *    miss return 0 and leave *t as it was.
 *
 * Helpers: sidx/math.h (sidx_v3_dot, sidx_v3_cross, sidx_v3_sub,
 * sidx_ray_at, ...).  Check with:   make exercise EX=01_ray_triangle
 * Only the two function bodies are yours to write. */
#include "sidx/sidx.h"

int ray_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t)
{
    (void)r;
    (void)n;
    (void)c;
    (void)t;
    return 0;
}

int ray_triangle_two_step(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t)
{
    (void)r;
    (void)p0;
    (void)p1;
    (void)p2;
    (void)tmax;
    (void)t;
    return 0;
}
