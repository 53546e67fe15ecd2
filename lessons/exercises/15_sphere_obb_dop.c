/* Exercise 15 — the other bounding volumes: sphere, OBB and 14-DOP.
 *
 * Slide: deck 000, "Bounding Volumes": the sphere ("very fast
 * intersection computation"), the non-axis-aligned box ("a.k.a. oriented
 * bounding box (OBB)", "fairly complex computation") and the slabs
 * ("pairs of half spaces (in addition to 3 for AABB)", "fixed number of
 * orientations/axes: e.g. x+y, x-y, etc.").
 *
 * Write three ray tests.  Each returns 1 and writes *t_near, *t_far (the
 * part of the ray inside the volume, clipped to [tmin, tmax]) when that
 * part is not empty (t_near <= t_far, the bound included), else 0 and
 * writes neither.
 *
 *   ray_sphere  |o + t·d − c|² = r², a quadratic in t (d need not be unit
 *               length): no real root is a miss, one root (a tangent ray)
 *               a hit of one point.  Form the discriminant from the
 *               centre's distance to the ray's line (l = f − (f·d/d·d)·d,
 *               f = o − c; disc = d·d·(r² − l·l)): the textbook b² − a·c
 *               loses the digits of a far sphere.
 *   ray_obb     three slabs along the box's own axes a_i (unit length):
 *               a_i·x between a_i·center − half_i and a_i·center + half_i.
 *   ray_kdop    seven slabs lo[i] <= n_i·x <= hi[i] along the axes
 *               sidx_kdop_axis(i): x, y, z and the four diagonals (not
 *               unit length: use them as they are).
 *
 * A slab along n is crossed between (lo − n·o)/(n·d) and (hi − n·o)/(n·d),
 * the smaller one the entry.  A ray parallel to a slab (n·d = 0) is inside
 * it for every t or never: test n·o against [lo, hi], both bounds inside.
 *
 * Awkward cases the checker tries: tangent rays, origins inside, volumes
 * behind the origin or beyond tmax, ±0 direction components, rays lying in
 * a face plane, flat boxes and slabs (lo == hi), a finite tmax.
 *
 * Check with:   make exercise EX=15_sphere_obb_dop
 * Only the function bodies are yours to write. */
#include "sidx/sidx.h"

int ray_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far)
{
    (void)r;
    (void)s;
    (void)tmin;
    (void)tmax;
    (void)t_near;
    (void)t_far;
    return 0;
}

int ray_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far)
{
    (void)r;
    (void)b;
    (void)tmin;
    (void)tmax;
    (void)t_near;
    (void)t_far;
    return 0;
}

int ray_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far)
{
    (void)r;
    (void)k;
    (void)tmin;
    (void)tmax;
    (void)t_near;
    (void)t_far;
    return 0;
}
