/* hit.h — finishing a closest hit (internal): what hit.c computes, and
 * the one step every single-ray path takes after its walk.  A header of
 * its own so that sidx_internal.h, which every file includes, calls no
 * function of a source file. */
#ifndef SIDX_HIT_H
#define SIDX_HIT_H

#include "sidx_internal.h"

/* hit.c: finishes a closest hit on triangle hit->prim of m, found by a
 * walk that set hit->t and hit->prim, as the query's flags ask:
 * SIDX__QUERY_REFINE_T refines t on the triangle's plane; SIDX_QUERY_UV
 * and SIDX_QUERY_NORMAL recompute u, v (by test method tri on ray r) and
 * the geometric normal from the mesh, except what `own` (the same bits)
 * says the walk set already; SIDX_QUERY_POINT sets hit->p and hit->p_err
 * (and u, v, ng unless `own` and the flags both name them).  The one
 * finish every query path calls once per hit ray: sidx_accel_intersect,
 * the packet walks, the aggregate (on its local ray).  Never called on a
 * miss. */
void sidx__hit_finish(const sidx_mesh *m, sidx_tri_method tri, const sidx_ray *r, uint32_t flags, uint32_t own,
                      sidx_hit *hit);

/* The final hit of a closest-hit query finished once, after the walk
 * (accel.c, and the stream entry, bvh_stream.c): t refined, u, v, the
 * geometric normal and the point, as the query asks (sidx__hit_finish,
 * hit.c).  The hot loop never pays for them ("no u/v or normals unless
 * asked").  A structure that keeps u, v or ng from its own traversal
 * (a->fills_uv, a->fills_ng) has set them already. */
static SIDX_INLINE void sidx__finish_hit(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    if (hit->prim == SIDX_NO_HIT) {
        /* The query set *hit = sidx_hit_none() with t = tmax, and a walk
         * writes only t and prim when it accepts a hit, and u, v, ng for its
         * final one: on a miss only t differs from sidx_hit_none(). */
        hit->t = INFINITY;
        return;
    }
    /* Aggregates (instance.c) set the instance and finish their hit in
     * world space themselves: their a->mesh is not where the hit lies, so
     * an instanced hit gets no point. */
    if (hit->instance != SIDX_NO_HIT) return;
    /* On request only: the mesh read misses the cache on incoherent rays
     * (docs/performance.md, "Precision of the closest hit's t"). */
    const uint32_t own = (a->fills_uv ? SIDX_QUERY_UV : 0u) | (a->fills_ng ? SIDX_QUERY_NORMAL : 0u);
    /* a call only when there is something to do: a query asking for u, v
     * from a structure that filled them (bvh, bvh8, kdtree) makes none */
    if (!(q->flags & (SIDX__QUERY_REFINE_T | SIDX_QUERY_POINT)) &&
        !(q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL) & ~own))
        return;
    sidx__hit_finish(a->mesh, a->opt.tri, r, q->flags, own, hit);
}

#endif
