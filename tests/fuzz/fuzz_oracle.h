/* fuzz_oracle.h — the rule the fuzz oracles (fuzz_build.c, fuzz_rays.c)
 * and tests/test_boundary_rays.c apply to a ray whose direction is an axis
 * or a plane to within float resolution (docs/errors.md, Limits).
 *
 * sidx_ray_init sets up the watertight triangle test (Woop et al. 2013)
 * with the shear constants d[kx]/d[kz] and d[ky]/d[kz].  When a component
 * is non-zero but below FLT_MIN times the largest one, its quotient is
 * denormal or 0: the triangle test traces the ray without (most of) that
 * component, while every box test (1/d[k]) keeps it.  The two rays differ
 * by less than 2^-126 · t, which no coordinate resolves, except for a ray
 * lying in a plane of the scene: along the fuzz cube's edge x = 1, y = 1,
 * leaning out by d.y = 0x1.1ap-123 against d.z = 2^28
 * (regress/rays/edge-lean-shear-underflow.bin), every box test sees the
 * ray leave the scene at t = 0 (exact: it passes the top corner 4e-46
 * outside), while brute force's triangle test, with d.y/d.z = 0, touches
 * that corner at distance 1.
 *
 * Such rays are held to a one-way check.  A structure tests a subset of
 * brute force's triangles with the same triangle test, so it may miss
 * what that rounding lets brute force touch, but it never reports a hit
 * brute force does not see, nor a nearer one, nor occlusion brute force
 * does not find. */
#ifndef SIDX_FUZZ_ORACLE_H
#define SIDX_FUZZ_ORACLE_H

#include <float.h>
#include <math.h>
#include "sidx/sidx.h"

/* 1 when a component of d is non-zero and |d[k]| / max|d| < FLT_MIN: the
 * quotient sidx_ray_init computes for the triangle test underflows. */
static inline int fo_shear_underflows(sidx_vec3 d)
{
    const float c[3] = {d.x, d.y, d.z};
    const float dmax = fmaxf(fabsf(c[0]), fmaxf(fabsf(c[1]), fabsf(c[2])));
    for (int k = 0; k < 3; ++k)
        if (c[k] != 0.0f && fabsf(c[k] / dmax) < FLT_MIN) return 1;
    return 0;
}

/* The one-way check: h and occ (a structure) against ref and occ_ref
 * (brute force).  1 when the structure's hit is none, the same triangle, or
 * no nearer than brute force's (to the oracles' tolerance), and it reports
 * occlusion only where brute force does. */
static inline int fo_no_nearer(const sidx_hit *h, const sidx_hit *ref, int occ, int occ_ref)
{
    if (occ && !occ_ref) return 0;
    if (h->prim == SIDX_NO_HIT) return 1;
    if (ref->prim == SIDX_NO_HIT) return 0;
    return h->prim == ref->prim || ref->t <= h->t + 1e-5f * fmaxf(1.0f, fabsf(h->t));
}

#endif
