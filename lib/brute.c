/* brute.c — the baseline: test every triangle, O(n) per ray.
 *
 * The slides' "naïve approach (brute force) still needs to check every
 * triangle".  Every other structure is checked against this one, so it is
 * kept as simple as possible: no build, no reordering. */
#include "sidx_internal.h"

#define SIDX_STRUCTURE_NAME "brute"

static sidx_status brute_build(sidx_accel *a, sidx_error *err)
{
    (void)err;
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_BEGIN, e_.count = a->mesh->num_triangles;
              e_.bounds = sidx_mesh_bounds(a->mesh));
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_END, e_.node = 0; e_.count = a->mesh->num_triangles; e_.depth = 0);
    a->impl = NULL;
    return SIDX_OK;
}

static SIDX_INLINE void brute_intersect_impl(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,
                                             sidx_hit *hit, const int traced)
{
    const sidx_mesh *m = a->mesh;
    const sidx_tri_method method = a->opt.tri;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        float t;
        const int h = sidx__mesh_tri_test(m, method, i, r, hit->t, &t);
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.prim = i; e_.result = h;
                  e_.t = h ? t : INFINITY);
        if (h) {
            hit->t = t;
            hit->prim = i;
            SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = i; e_.t = t);
        }
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_STACK_EMPTY;
              e_.t = hit->t; e_.count = m->num_triangles);
}

static void brute_intersect_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    brute_intersect_impl(a, r, q, hit, 0);
}
static void brute_intersect_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    brute_intersect_impl(a, r, q, hit, 1);
}

static SIDX_INLINE int brute_occluded_impl(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,
                                           const int traced)
{
    const sidx_mesh *m = a->mesh;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        float t;
        const int h = sidx__mesh_tri_test(m, a->opt.tri, i, r, r->tmax, &t);
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.prim = i; e_.result = h;
                  e_.t = h ? t : INFINITY);
        if (h) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.t = t; e_.count = i + 1);
            return 1;
        }
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_STACK_EMPTY;
              e_.count = m->num_triangles);
    return 0;
}

static int brute_occluded_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return brute_occluded_impl(a, r, q, 0);
}
static int brute_occluded_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return brute_occluded_impl(a, r, q, 1);
}

/* The walk table (sidx_internal.h): the same for every build. */
static const sidx__walk_table brute_walks = {brute_intersect_plain, brute_intersect_traced, brute_occluded_plain,
                                             brute_occluded_traced};

static void brute_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    sidx__walk_intersect(&brute_walks, a, r, q, hit);
}

static int brute_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return sidx__walk_occluded(&brute_walks, a, r, q);
}

static void brute_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    s->nodes = 1;
    s->leaves = 1;
    s->prim_refs = a->mesh->num_triangles;
    s->mean_leaf_prims = a->mesh->num_triangles;
    s->sah_cost = a->mesh->num_triangles; /* C_tri · n with C_tri = 1 */
}

static void brute_destroy(sidx_accel *a) { (void)a; }

static sidx_status brute_refit(sidx_accel *a, sidx_error *err)
{
    (void)a;
    (void)err;
    return SIDX_OK; /* nothing cached: moving vertices needs no update */
}

const sidx_accel_vtable sidx__brute_vtable = {brute_build, brute_intersect, brute_occluded, brute_stats,
                                              brute_destroy, brute_refit};
