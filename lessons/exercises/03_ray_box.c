/* Exercise 03 — the ray–AABB slab test.
 *
 * Slides: deck 000, "Bounding Volumes" (the AABB: "very simple
 * intersection computation (min-max)"); deck 001, "Bounding Box".
 *
 * The box is the intersection of three slabs min.k <= x_k <= max.k.  Along
 * the ray, slab k is crossed between (min.k − o.k)/d.k and
 * (max.k − o.k)/d.k; the ray is inside the box over the largest entry to
 * the smallest exit.  Clip that interval to [tmin, tmax]: return 1 and
 * write *t_near, *t_far when it is not empty (t_near <= t_far), else
 * return 0 and leave them as they were.  tmin and tmax are the interval
 * you are given (the caller's), not necessarily the ray's own.
 *
 * Awkward cases the checker tries: a direction component of +0 or −0
 * (r->inv_dir holds ±inf there, r->sign[k] is 1 for a negative component,
 * −0 included), a ray starting inside the box, an infinite tmax, a ray
 * lying exactly in a face plane of the box (counts as inside).
 *
 * Check with:   make exercise EX=03_ray_box
 * Only the function body is yours to write. */
#include "sidx/sidx.h"

int ray_box(const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far)
{
    (void)r;
    (void)box;
    (void)tmin;
    (void)tmax;
    (void)t_near;
    (void)t_far;
    return 0;
}
