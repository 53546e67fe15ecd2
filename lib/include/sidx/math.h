/* sidx/math.h — vectors, boxes and rays.
 *
 * Everything is single precision, as in the renderers sidx is measured
 * against.  A ray carries what every traversal needs precomputed once:
 * the reciprocal direction and its signs (slab tests, near/far child order)
 * and the shear constants of the watertight triangle test (Woop, Benthin,
 * Wald 2013). */
#ifndef SIDX_MATH_H
#define SIDX_MATH_H

#include <math.h>
#include <stdint.h>
#include "status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_vec3 { float x, y, z; } sidx_vec3;

typedef struct sidx_aabb { sidx_vec3 min, max; } sidx_aabb;

static inline sidx_vec3 sidx_v3(float x, float y, float z) { sidx_vec3 v = {x, y, z}; return v; }
static inline sidx_vec3 sidx_v3_add(sidx_vec3 a, sidx_vec3 b) { return sidx_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline sidx_vec3 sidx_v3_sub(sidx_vec3 a, sidx_vec3 b) { return sidx_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline sidx_vec3 sidx_v3_mul(sidx_vec3 a, sidx_vec3 b) { return sidx_v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline sidx_vec3 sidx_v3_scale(sidx_vec3 a, float s) { return sidx_v3(a.x * s, a.y * s, a.z * s); }
static inline float sidx_v3_dot(sidx_vec3 a, sidx_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline sidx_vec3 sidx_v3_cross(sidx_vec3 a, sidx_vec3 b)
{
    return sidx_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float sidx_v3_length(sidx_vec3 a) { return sqrtf(sidx_v3_dot(a, a)); }
static inline sidx_vec3 sidx_v3_min(sidx_vec3 a, sidx_vec3 b)
{
    return sidx_v3(a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z);
}
static inline sidx_vec3 sidx_v3_max(sidx_vec3 a, sidx_vec3 b)
{
    return sidx_v3(a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z);
}
/* Component by axis index 0, 1, 2 (x, y, z). */
static inline float sidx_v3_get(sidx_vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }
/* Set one component by axis index. */
static inline void sidx_v3_set(sidx_vec3 *a, int axis, float value)
{
    if (axis == 0) a->x = value;
    else if (axis == 1) a->y = value;
    else a->z = value;
}
/* The three components copied to an array, for loops over the axes (a hot
 * loop indexes the copy, which the compiler keeps in registers), and back. */
static inline void sidx_v3_to_array(sidx_vec3 a, float out[3])
{
    out[0] = a.x;
    out[1] = a.y;
    out[2] = a.z;
}
static inline sidx_vec3 sidx_v3_from_array(const float in[3]) { return sidx_v3(in[0], in[1], in[2]); }
/* The components in place as float[3], for code that picks an axis by a
 * number it computed (a split axis; the watertight test's kx, ky, kz) and
 * cannot afford a copy or a three-way choice in its inner loop:
 * sidx_v3_array(&v)[axis] to read, sidx_v3_array_rw(&v)[axis] to write.
 * A pointer to a struct is a pointer to its first member, and a sidx_vec3
 * is three floats with no padding (checked below), so this is the memory
 * of v.x, v.y, v.z in order.  Use it instead of &v.x, which names one
 * float, not three.  (Macros, not functions: the compiler's inlining
 * budget for the hot loops that use them stays what it was.) */
#define sidx_v3_array(v) ((const float *)(const void *)(v))
#define sidx_v3_array_rw(v) ((float *)(void *)(v))
#ifndef __cplusplus
_Static_assert(sizeof(sidx_vec3) == 3 * sizeof(float), "sidx_vec3 must be three packed floats");
#endif

static inline int sidx_v3_isfinite(sidx_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

/* The empty box: min = +inf, max = -inf, so that any union fixes it. */
static inline sidx_aabb sidx_aabb_empty(void)
{
    sidx_aabb b = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    return b;
}
static inline int sidx_aabb_is_empty(sidx_aabb b) { return b.min.x > b.max.x || b.min.y > b.max.y || b.min.z > b.max.z; }
static inline sidx_aabb sidx_aabb_union(sidx_aabb a, sidx_aabb b)
{
    sidx_aabb r = {sidx_v3_min(a.min, b.min), sidx_v3_max(a.max, b.max)};
    return r;
}
static inline sidx_aabb sidx_aabb_grow(sidx_aabb a, sidx_vec3 p)
{
    sidx_aabb r = {sidx_v3_min(a.min, p), sidx_v3_max(a.max, p)};
    return r;
}
static inline sidx_vec3 sidx_aabb_extent(sidx_aabb b) { return sidx_v3_sub(b.max, b.min); }
static inline sidx_vec3 sidx_aabb_centroid(sidx_aabb b) { return sidx_v3_scale(sidx_v3_add(b.min, b.max), 0.5f); }
/* Surface area; 0 for an empty box (the SAH must not see negative areas). */
static inline float sidx_aabb_area(sidx_aabb b)
{
    if (sidx_aabb_is_empty(b)) return 0.0f;
    sidx_vec3 e = sidx_aabb_extent(b);
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
}
/* Axis (0,1,2) of the largest extent; ties go to the lowest axis. */
static inline int sidx_aabb_max_axis(sidx_aabb b)
{
    sidx_vec3 e = sidx_aabb_extent(b);
    return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
}
static inline int sidx_aabb_contains(sidx_aabb outer, sidx_aabb inner)
{
    return inner.min.x >= outer.min.x && inner.min.y >= outer.min.y && inner.min.z >= outer.min.z &&
           inner.max.x <= outer.max.x && inner.max.y <= outer.max.y && inner.max.z <= outer.max.z;
}

/* A ray o + t·d for t in [tmin, tmax].  Build it with sidx_ray_init, which
 * fills the precomputed fields; never edit org/dir afterwards without
 * calling sidx_ray_init again.  tmax may be INFINITY. */
typedef struct sidx_ray {
    sidx_vec3 org, dir;
    float tmin, tmax;
    sidx_vec3 inv_dir;  /* 1/d per component: ±inf for a ±0 component (the sign is kept) */
    uint8_t sign[3];    /* 1 where the direction component is negative, -0.0 included */
    uint8_t kx, ky, kz; /* watertight test: kz = axis of largest |d|, kx,ky the others (winding kept) */
    float sx, sy, sz;   /* watertight test: shear constants -dx/dz, -dy/dz, 1/dz after permutation */
} sidx_ray;

/* Fills *r.  Fails with SIDX_ERR_INVALID_ARG (and leaves *r untouched) if
 * any component of org or dir is NaN/Inf, if dir is the zero vector, if
 * tmin or tmax is NaN, if tmin < 0, or if tmin > tmax.  A ray starts at
 * its origin: a negative tmin would ask the conservative box tests to
 * widen intervals that lie behind the origin (Ize's 1 + 2γ factor on
 * t_far only widens positive distances), so it is refused here instead
 * of being answered differently by different structures (fuzz_rays).  The direction is not normalized:
 * t is measured in units of |dir|. */
sidx_status sidx_ray_init(sidx_ray *r, sidx_vec3 org, sidx_vec3 dir, float tmin, float tmax);

/* Point at parameter t. */
static inline sidx_vec3 sidx_ray_at(const sidx_ray *r, float t) { return sidx_v3_add(r->org, sidx_v3_scale(r->dir, t)); }

/* A closest-hit record.  prim is the triangle's index in the input mesh
 * (file order after fan triangulation) whatever a structure reorders;
 * SIDX_NO_HIT when the ray missed, and then t = +inf, u = v = 0.
 * u and v are the barycentric coordinates of the 2nd and 3rd vertex and ng
 * the (unnormalized) geometric normal e1 × e2: filled only when the query
 * asks for them (SIDX_QUERY_UV, SIDX_QUERY_NORMAL), zero otherwise. */
#define SIDX_NO_HIT UINT32_MAX
typedef struct sidx_hit {
    float t;
    uint32_t prim;
    float u, v;
    sidx_vec3 ng;
    uint32_t instance; /* instanced scenes: which instance; SIDX_NO_HIT otherwise */
    /* SIDX_QUERY_POINT (sidx/spawn.h): the hit point p, rebuilt from u, v
     * as (1-u-v)·p0 + u·p1 + v·p2, and p_err, a conservative bound on
     * |p - exact point| per component (zero when not asked). */
    sidx_vec3 p, p_err;
} sidx_hit;

static inline sidx_hit sidx_hit_none(void)
{
    sidx_hit h = {INFINITY, SIDX_NO_HIT, 0.0f, 0.0f, {0.0f, 0.0f, 0.0f}, SIDX_NO_HIT, {0.0f, 0.0f, 0.0f},
                  {0.0f, 0.0f, 0.0f}};
    return h;
}

#ifdef __cplusplus
}
#endif
#endif
