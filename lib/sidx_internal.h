/* sidx_internal.h — what every structure's source file shares, not public.
 *
 *  1. the accelerator vtable and the registry entry,
 *  2. SIDX_EMIT: the hook call that compiles away in untraced instances,
 *  3. the elementary tests as static inline functions for the hot loops,
 *  4. checked allocation through the build's allocator.
 *
 * How a structure keeps hooks free when unused: its traversal is a
 * `static SIDX_INLINE` function taking `const int traced`; the vtable entry
 * calls it with traced = 0 when q->hook is NULL and with traced = 1
 * otherwise.  Each call is a separate instantiation, so in the traced = 0
 * copy every SIDX_EMIT is dead code the compiler removes.  Building with
 * -DSIDX_NO_HOOKS removes them from both copies (the bench compares). */
#ifndef SIDX_INTERNAL_H
#define SIDX_INTERNAL_H

#include <stdlib.h>
#include <string.h>
#include <float.h>
#include "sidx/sidx.h"

#if defined(__GNUC__)
#define SIDX_INLINE inline __attribute__((always_inline))
#define SIDX_NOINLINE __attribute__((noinline))
#define SIDX_LIKELY(x) __builtin_expect(!!(x), 1)
#define SIDX_UNLIKELY(x) __builtin_expect(!!(x), 0)
#else
#define SIDX_INLINE inline
#define SIDX_NOINLINE
#define SIDX_LIKELY(x) (x)
#define SIDX_UNLIKELY(x) (x)
#endif

/* ---- 1. accelerator vtable ------------------------------------------- */

typedef struct sidx_accel_vtable {
    /* Build a->impl from a->mesh and a->opt.  On failure free everything
     * allocated and leave a->impl NULL. */
    sidx_status (*build)(sidx_accel *a, sidx_error *err);
    /* Closest hit: set hit->t and hit->prim (ORIGINAL triangle index) only.
     * hit arrives with prim = SIDX_NO_HIT and t = r->tmax: use hit->t as
     * the current upper bound and accept only t < hit->t.
     * The core fills u, v, ng afterwards when asked, and emits RAY_BEGIN /
     * RAY_END around this call. */
    void (*intersect)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit);
    /* Any hit: return 1 at the first hit found in [tmin, tmax). */
    int (*occluded)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q);
    void (*stats)(const sidx_accel *a, sidx_accel_stats *s);
    void (*destroy)(sidx_accel *a);        /* free a->impl (not a) */
    sidx_status (*refit)(sidx_accel *a, sidx_error *err);   /* may be NULL */
} sidx_accel_vtable;

/* The query pointer a vtable entry receives is never NULL:
 * sidx_accel_intersect and sidx_accel_occluded put a default query (no
 * flags, default traversal, no hook) in its place, and every internal
 * caller (instances, packets, threads) passes a real one.  No walk tests
 * q for NULL; a walk tests q->hook through SIDX_QUERY_TRACED. */

/* One dispatch pattern for every structure: its build picks, once, the
 * walk functions that fit this tree and its options (mailbox or not, box
 * kind, instruction set) and stores them in a walk table; the vtable's
 * intersect and occluded entries then only pick the traced or the plain
 * copy by the query (sidx__walk_intersect / sidx__walk_occluded below).
 * A structure with several traversals (the BVH's naive / ordered /
 * stack) keeps one table per traversal. */
typedef void (*sidx__intersect_fn)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit);
typedef int (*sidx__occluded_fn)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q);
typedef struct sidx__walk_table {
    sidx__intersect_fn intersect, intersect_traced; /* closest hit: plain copy, traced copy */
    sidx__occluded_fn occluded, occluded_traced;    /* any hit */
} sidx__walk_table;

struct sidx_accel {
    const sidx_accel_vtable *vt;
    const char *name;          /* registered name (static) */
    int variant;               /* registry entry's variant (builder choice etc.) */
    /* 1 when vt->intersect also sets hit->u, hit->v (when SIDX_QUERY_UV asks)
     * / hit->ng (when SIDX_QUERY_NORMAL asks) itself — u, v kept from its
     * own triangle test, ng from its own copy of the triangle — so the core
     * skips its re-test and the index and vertex look-ups in the mesh,
     * which a diffuse ray mostly misses in cache.  Either way the values
     * are bit-identical to sidx__hit_finish's (hit.c): same test, same floats.
     * Bytes beside `variant`, in what would be padding, so that the labels
     * below do not make the structure bigger. */
    unsigned char fills_uv, fills_ng;
    /* 1 for a lazy tree (opt.lazy in effect): the queries then say whether
     * an expansion failed (sidx__lazy_failed, lazy.h). */
    unsigned char lazy;
    const sidx_mesh *mesh;
    sidx_build_options opt;    /* copy; opt.hook is only valid during build */
    sidx_allocator alloc;      /* resolved allocator (never NULL fns) */
    void *impl;
    /* node labels (sidx_accel_set_node_label, labels.c); NULL until one
     * is set.  Display only: no walk reads them */
    struct sidx__labels *labels;
};

/* Builds an accelerator the registry does not name the usual way: the
 * options are checked and the structure allocated as for
 * sidx_accel_build, then build(a, arg, err) fills a->impl.  The kd-tree
 * built from given splits (kdtree_build.c) goes through here. */
typedef sidx_status (*sidx__build_fn)(sidx_accel *a, void *arg, sidx_error *err);
sidx_status sidx__accel_build_with(const char *name, const sidx_accel_vtable *vt, int variant, const sidx_mesh *mesh,
                                   const sidx_build_options *opt, sidx__build_fn build, void *arg, sidx_accel **out,
                                   sidx_error *err);

/* bvh_stream.c: n rays through a bvh-family tree, bvh4 or bvh8 with the
 * stream walk, closest hit into hits[] or, with hits NULL, any hit into
 * occluded[]; the same answers as n single queries.  Returns 0, having
 * done nothing, when the query goes ray by ray instead (other structures,
 * traced queries, lazy trees, bvh-obb, the naive and ordered walks). */
int sidx__bvh_stream(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q, sidx_hit *hits,
                     int *occluded);

/* Frees the labels (sidx_accel_destroy). */
void sidx__labels_free(sidx_accel *a);

/* Registry entries live in accel_registry.def as
 *   SIDX_ACCEL("name", vtable_symbol, variant, "one-line description")
 * Adding a structure = one line there + one source file defining
 * `const sidx_accel_vtable vtable_symbol`. */
#define SIDX_ACCEL(name, vt, variant, desc) extern const sidx_accel_vtable vt;
#include "accel_registry.def"
#undef SIDX_ACCEL

/* ---- 2. hook emission ------------------------------------------------- */

static SIDX_INLINE int sidx__hook_wants(const sidx_hook *h, sidx_event_type t)
{
    return h && h->fn && (h->mask == 0 || (h->mask & SIDX_EVMASK(t)));
}

/* SIDX_EMIT(traced, hook, TYPE, field assignments on e_ ...);
 * e.g. SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.node = i; e_.depth = d);
 * `structure` is filled from SIDX_STRUCTURE_NAME, which each source file
 * defines before using the macro. */
#ifdef SIDX_NO_HOOKS
/* The event is still type-checked, so the variables it reads count as
 * used and this variant compiles warning-free, but `if (0)` removes it. */
#define SIDX_EMIT(traced, hook, type, ...)                                  \
    do {                                                                    \
        (void)(traced);                                                     \
        (void)(hook);                                                       \
        if (0) {                                                            \
            sidx_event e_ = sidx_event_blank(type);                         \
            e_.structure = SIDX_STRUCTURE_NAME;                             \
            __VA_ARGS__;                                                    \
            (void)e_;                                                       \
        }                                                                   \
    } while (0)
#else
#define SIDX_EMIT(traced, hook, type, ...)                                  \
    do {                                                                    \
        if ((traced) && sidx__hook_wants((hook), (type))) {                 \
            sidx_event e_ = sidx_event_blank(type);                         \
            e_.structure = SIDX_STRUCTURE_NAME;                             \
            __VA_ARGS__;                                                    \
            (hook)->fn(&e_, (hook)->user);                                  \
        }                                                                   \
    } while (0)
#endif

/* Is this query traced?  (Always 0 when hooks are compiled out.)  q is
 * never NULL here: the public entry points put a blank query in place of
 * NULL before they ask. */
#ifdef SIDX_NO_HOOKS
#define SIDX_QUERY_TRACED(q) 0
#else
#define SIDX_QUERY_TRACED(q) ((q)->hook && (q)->hook->fn)
#endif

/* The walk-table dispatch (section 1): the traced copy when the query has
 * a hook, the plain copy otherwise. */
static SIDX_INLINE void sidx__walk_intersect(const sidx__walk_table *t, const sidx_accel *a, const sidx_ray *r,
                                             const sidx_query *q, sidx_hit *hit)
{
    (SIDX_QUERY_TRACED(q) ? t->intersect_traced : t->intersect)(a, r, q, hit);
}
static SIDX_INLINE int sidx__walk_occluded(const sidx__walk_table *t, const sidx_accel *a, const sidx_ray *r,
                                           const sidx_query *q)
{
    return (SIDX_QUERY_TRACED(q) ? t->occluded_traced : t->occluded)(a, r, q);
}

/* ---- 3. elementary tests, inline ------------------------------------- */

/* Woop, Benthin, Wald 2013, "Watertight Ray/Triangle Intersection".
 * Translate the vertices to the ray origin, shear so the ray runs along
 * +z, and evaluate the 2D edge functions U, V, W.  Edges shared by two
 * triangles get bit-identical edge functions of opposite sign, so a ray
 * cannot slip between them.  When an edge function is exactly 0 it is
 * recomputed in double, as the paper advises, so the sign is exact.
 *
 * The test is split in three so that every caller computes the same
 * floats with the same operations: the sheared vertices and the float
 * edge functions (sidx__tri_watertight_edges), the test itself
 * (sidx__tri_watertight_p), and u, v of a hit from V, W and det
 * (sidx__tri_watertight_uv) — which a structure's final hit forms
 * without redoing the rest (sidx__tri_hit_uv_at, below). */
typedef struct sidx__wt_edges {
    float Ax, Ay, Bx, By, Cx, Cy; /* vertices relative to the origin, sheared */
    float az, bz, cz;             /* their z relative to the origin (T scales them by 1/d[kz]) */
    float U, V, W;                /* edge functions, float */
} sidx__wt_edges;

/* pa, pb, pc point at the x of each vertex, whose y and z follow `stride`
 * floats apart: 1 for a sidx_vec3, 4 for a lane of a 4-triangle block. */
static SIDX_INLINE sidx__wt_edges sidx__tri_watertight_edges(const sidx_ray *r, const float *pa, const float *pb,
                                                             const float *pc, const int stride)
{
    const float *o = sidx_v3_array(&r->org);
    const int kx = r->kx, ky = r->ky, kz = r->kz;
    const float ax = pa[kx * stride] - o[kx], ay = pa[ky * stride] - o[ky], az = pa[kz * stride] - o[kz];
    const float bx = pb[kx * stride] - o[kx], by = pb[ky * stride] - o[ky], bz = pb[kz * stride] - o[kz];
    const float cx = pc[kx * stride] - o[kx], cy = pc[ky * stride] - o[ky], cz = pc[kz * stride] - o[kz];
    sidx__wt_edges e;
    e.Ax = ax - r->sx * az, e.Ay = ay - r->sy * az;
    e.Bx = bx - r->sx * bz, e.By = by - r->sy * bz;
    e.Cx = cx - r->sx * cz, e.Cy = cy - r->sy * cz;
    e.az = az, e.bz = bz, e.cz = cz;
    e.U = e.Cx * e.By - e.Cy * e.Bx;
    e.V = e.Ax * e.Cy - e.Ay * e.Cx;
    e.W = e.Bx * e.Ay - e.By * e.Ax;
    return e;
}

static SIDX_INLINE void sidx__tri_watertight_uv(float V, float W, float det, float *u_out, float *v_out)
{
    const float inv = 1.0f / det;
    *u_out = V * inv;
    *v_out = W * inv;
}

/* The test on vertices read in place (pa, pb, pc point at x, y, z).
 * The by-value form below copies its arguments to the stack first, since
 * they are indexed by the ray's kx, ky, kz; a caller whose triangles
 * already sit in memory (the kd-tree's leaf copies) saves that spill.
 * Same arithmetic on the same floats, so bit-identical results. */
static SIDX_INLINE int sidx__tri_watertight_p(const sidx_ray *r, const float *pa, const float *pb, const float *pc,
                                              float tmax, float *t_out, float *u_out, float *v_out)
{
    const sidx__wt_edges e = sidx__tri_watertight_edges(r, pa, pb, pc, 1);
    float U = e.U, V = e.V, W = e.W;
    if (SIDX_UNLIKELY(U == 0.0f || V == 0.0f || W == 0.0f)) {
        U = (float)((double)e.Cx * (double)e.By - (double)e.Cy * (double)e.Bx);
        V = (float)((double)e.Ax * (double)e.Cy - (double)e.Ay * (double)e.Cx);
        W = (float)((double)e.Bx * (double)e.Ay - (double)e.By * (double)e.Ax);
    }
    /* mixed signs: the ray passes outside an edge.  Evaluated without
     * short-circuits, so it is one branch (taken by most tests, which
     * miss) rather than up to six data-dependent ones. */
    const int neg = (U < 0.0f) | (V < 0.0f) | (W < 0.0f), pos = (U > 0.0f) | (V > 0.0f) | (W > 0.0f);
    if (neg & pos) return 0;
    const float det = U + V + W;
    if (det == 0.0f) return 0; /* degenerate triangle, or ray parallel to its plane */
    const float Az = r->sz * e.az, Bz = r->sz * e.bz, Cz = r->sz * e.cz;
    const float T = U * Az + V * Bz + W * Cz;
    /* t = T/det must lie in [tmin, tmax): compare without dividing first. */
    const float t = T / det;
    if (!(t >= r->tmin && t < tmax)) return 0;
    *t_out = t;
    if (u_out) sidx__tri_watertight_uv(V, W, det, u_out, v_out);
    return 1;
}
static SIDX_INLINE int sidx__tri_watertight(const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float tmax,
                                            float *t_out, float *u_out, float *v_out)
{
    return sidx__tri_watertight_p(r, sidx_v3_array(&a), sidx_v3_array(&b), sidx_v3_array(&c), tmax, t_out, u_out, v_out);
}

/* Möller & Trumbore 1997, as derived on the slides with Cramer's rule:
 * s = o − p0, e1 = p1 − p0, e2 = p2 − p0, D = (d × e2)·e1.
 * D = 0 ("What if D = 0?"): the ray is parallel to the plane, or the
 * triangle is degenerate — a miss.  No epsilon: an epsilon on D is
 * scale-dependent and would drop small but valid triangles. */
static SIDX_INLINE int sidx__tri_moller(const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float tmax,
                                        float *t_out, float *u_out, float *v_out)
{
    const sidx_vec3 e1 = sidx_v3_sub(b, a), e2 = sidx_v3_sub(c, a);
    const sidx_vec3 p = sidx_v3_cross(r->dir, e2);
    const float det = sidx_v3_dot(e1, p);
    if (det == 0.0f) return 0;
    const float inv = 1.0f / det;
    const sidx_vec3 s = sidx_v3_sub(r->org, a);
    const float u = sidx_v3_dot(s, p) * inv;
    if (u < 0.0f || u > 1.0f) return 0;
    const sidx_vec3 qv = sidx_v3_cross(s, e1);
    const float v = sidx_v3_dot(r->dir, qv) * inv;
    if (v < 0.0f || u + v > 1.0f) return 0;
    const float t = sidx_v3_dot(e2, qv) * inv;
    if (!(t >= r->tmin && t < tmax)) return 0;
    *t_out = t;
    if (u_out) { *u_out = u; *v_out = v; }
    return 1;
}

/* The deck's two-step method: (i) ray–plane with N = e1 × e2, c = N·p0,
 * t = (c − N·o)/(N·d); (ii) barycentric point-in-triangle test of
 * p = o + t·d by the dot-product formulation (Ericson 2005, 3.4). */
static SIDX_INLINE int sidx__tri_two_step(const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float tmax,
                                          float *t_out, float *u_out, float *v_out)
{
    const sidx_vec3 e1 = sidx_v3_sub(b, a), e2 = sidx_v3_sub(c, a);
    const sidx_vec3 n = sidx_v3_cross(e1, e2);
    const float nd = sidx_v3_dot(n, r->dir);
    if (nd == 0.0f) return 0;
    const float t = (sidx_v3_dot(n, a) - sidx_v3_dot(n, r->org)) / nd;
    if (!(t >= r->tmin && t < tmax)) return 0;
    const sidx_vec3 w = sidx_v3_sub(sidx_ray_at(r, t), a);
    const float d00 = sidx_v3_dot(e1, e1), d01 = sidx_v3_dot(e1, e2), d11 = sidx_v3_dot(e2, e2);
    const float d20 = sidx_v3_dot(w, e1), d21 = sidx_v3_dot(w, e2);
    const float den = d00 * d11 - d01 * d01;
    if (den == 0.0f) return 0;
    const float u = (d11 * d20 - d01 * d21) / den;
    const float v = (d00 * d21 - d01 * d20) / den;
    if (!(u >= 0.0f && v >= 0.0f && u + v <= 1.0f)) return 0;
    *t_out = t;
    if (u_out) { *u_out = u; *v_out = v; }
    return 1;
}

static SIDX_INLINE int sidx__tri_test(sidx_tri_method m, const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c,
                                      float tmax, float *t, float *u, float *v)
{
    switch (m) {
    case SIDX_TRI_MOLLER_TRUMBORE: return sidx__tri_moller(r, a, b, c, tmax, t, u, v);
    case SIDX_TRI_TWO_STEP: return sidx__tri_two_step(r, a, b, c, tmax, t, u, v);
    default: return sidx__tri_watertight(r, a, b, c, tmax, t, u, v);
    }
}

/* The vertex whose x is at p, with y and z `stride` floats apart (1 for a
 * sidx_vec3, 4 for a lane of a 4-triangle block): a copy of the same
 * floats, so a test on it gives the same bits as on the original. */
static SIDX_INLINE sidx_vec3 sidx__vec3_at(const float *p, const int stride)
{
    return (sidx_vec3){p[0], p[stride], p[2 * stride]};
}

/* u, v of a hit that sidx__tri_test(m, r, p0, p1, p2, ...) accepted, for
 * a structure that finishes only the final hit — the one definition that
 * the mesh finish (hit.c), the binary BVH's leaf copies and the wide
 * BVH's and kd-tree's 4-triangle blocks share.  p0, p1, p2 point at the x
 * of each vertex, y and z `stride` floats apart (sidx__vec3_at): read in
 * place, since the edge functions index them by the ray's kx, ky, kz and
 * vertices passed by value would first be copied to the stack.
 *
 * With the watertight test: the float edge functions again
 * (sidx__tri_watertight_edges: the same floats the accepting test
 * computed) and the test's own last step on them (sidx__tri_watertight_uv),
 * skipping T, t and the compares, which the hit already passed.  Same
 * arithmetic on the same floats, so the bits of forming u, v at every
 * accepted hit, which the walks do not pay for.  When an edge function
 * is exactly 0 the test redid them in double, and with another test there
 * is no such split: then the whole test again, whose bound only has to
 * exceed the hit's t, so +inf does.  Returns 0, leaving u, v alone, if
 * that test misses (a hit it did not accept). */
static SIDX_INLINE int sidx__tri_hit_uv_at(sidx_tri_method m, const sidx_ray *r, const float *p0, const float *p1,
                                          const float *p2, const int stride, float *u, float *v)
{
    if (m == SIDX_TRI_WATERTIGHT) {
        const sidx__wt_edges e = sidx__tri_watertight_edges(r, p0, p1, p2, stride);
        if (e.U != 0.0f && e.V != 0.0f && e.W != 0.0f) {
            sidx__tri_watertight_uv(e.V, e.W, e.U + e.V + e.W, u, v);
            return 1;
        }
    }
    float t;
    return sidx__tri_test(m, r, sidx__vec3_at(p0, stride), sidx__vec3_at(p1, stride), sidx__vec3_at(p2, stride),
                          INFINITY, &t, u, v);
}

/* The geometric normal hit.ng: (p1 − p0) × (p2 − p0), unnormalized.  One
 * definition, so a structure computing it from its own copy of the
 * vertices gets the same bits as sidx__hit_finish (hit.c) from the mesh. */
static SIDX_INLINE sidx_vec3 sidx__tri_normal(sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2)
{
    return sidx_v3_cross(sidx_v3_sub(p1, p0), sidx_v3_sub(p2, p0));
}

/* The query flag that asks for the closest hit's t refined on its
 * triangle's plane (the point of SIDX_QUERY_POINT is made from u, v, not
 * t, and does not need it). */
#define SIDX__QUERY_REFINE_T SIDX_QUERY_PRECISE_T

/* Triangle `tri` of mesh m, tested with method m (t only). */
static SIDX_INLINE int sidx__mesh_tri_test(const sidx_mesh *mesh, sidx_tri_method m, uint32_t tri,
                                           const sidx_ray *r, float tmax, float *t)
{
    const uint32_t *ix = mesh->indices + 3u * tri;
    return sidx__tri_test(m, r, mesh->positions[ix[0]], mesh->positions[ix[1]], mesh->positions[ix[2]], tmax, t,
                          NULL, NULL);
}

/* 1 + 2γ₃ with γ_n = nε/(1 − nε), ε = 2⁻²⁴ (Ize 2013; pbrt-v3 3.9.2):
 * widening t_far by this factor makes the float slab test conservative. */
#define SIDX_ROBUST_TFAR_SCALE 1.0000003576278687f

/* Slab test over [tmin, tmax].  A ±0 direction gives inv_dir = ±inf, and
 * (bound − o)·inv_dir is ±inf, or NaN when the origin lies exactly on the
 * slab plane; the comparisons below are written so a NaN never narrows
 * the interval (x > NaN is false), i.e. a ray on the plane counts as in. */
static SIDX_INLINE int sidx__box_test(int robust, const sidx_ray *r, const sidx_aabb *b, float tmin, float tmax,
                                      float *t_near, float *t_far)
{
    const float *bmin = sidx_v3_array(&b->min), *bmax = sidx_v3_array(&b->max), *o = sidx_v3_array(&r->org), *inv = sidx_v3_array(&r->inv_dir);
    const float *const corner[2] = {bmin, bmax};
    float t0 = tmin, t1 = tmax;
    for (int i = 0; i < 3; ++i) {
        /* near and far plane picked by the direction's sign (Williams et
         * al. 2005): a pointer choice, not a swap of the two results —
         * the same values without a branch that random directions make
         * a coin toss */
        const float *np = corner[r->sign[i] != 0], *fp = corner[r->sign[i] == 0];
        const float tn = (np[i] - o[i]) * inv[i];
        float tf = (fp[i] - o[i]) * inv[i];
        if (robust) tf *= SIDX_ROBUST_TFAR_SCALE;
        if (tn > t0) t0 = tn;
        if (tf < t1) t1 = tf;
    }
    if (t0 > t1) return 0;
    *t_near = t0;
    *t_far = t1;
    return 1;
}

/* ---- 4. allocation ----------------------------------------------------- */

/* size × count with overflow check; NULL on overflow or failure. */
static inline void *sidx__alloc(const sidx_accel *a, size_t count, size_t size)
{
    if (size != 0 && count > SIZE_MAX / size) return NULL;
    size_t bytes = count * size;
    return a->alloc.alloc(bytes ? bytes : 1, a->alloc.user);
}
static inline void *sidx__calloc(const sidx_accel *a, size_t count, size_t size)
{
    void *p = sidx__alloc(a, count, size);
    if (p && count && size) memset(p, 0, count * size);
    return p;
}
static inline void sidx__free(const sidx_accel *a, void *p)
{
    if (p) a->alloc.free(p, a->alloc.user);
}
/* Grow *buf (elements of `size`) to hold at least `need`; capacity doubles.
 * Returns 0 on failure, leaving *buf and *cap unchanged. */
int sidx__grow(const sidx_accel *a, void **buf, size_t *cap, size_t need, size_t size);

/* ---- 5. small shared helpers ------------------------------------------ */

/* Writes a formatted message into err (if non-NULL) and returns status. */
sidx_status sidx__fail(sidx_error *err, sidx_status s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Triangle bounds and centroids for all triangles (allocated with a's
 * allocator); returns SIDX_ERR_NOMEM on failure. */
sidx_status sidx__prim_boxes(const sidx_accel *a, sidx_aabb **boxes, sidx_vec3 **centroids);

#endif
