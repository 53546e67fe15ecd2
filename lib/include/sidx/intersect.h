/* sidx/intersect.h — the elementary tests every structure is made of.
 *
 * Each test is a plain function of its own so the lessons can call it and
 * print the numbers.  All return 1 for a hit and 0 for a miss and write
 * their outputs only on a hit.  A triangle hit requires tmin <= t < tmax
 * (half-open: a later triangle at exactly the best t found so far does not
 * replace it, so the first one found wins a tie).
 *
 * Edge cases, as tested in tests/test_intersect.c:
 *
 *   test               edge / vertex      degenerate tri   parallel ray (D = 0)
 *   -----------------  -----------------  ---------------  --------------------
 *   watertight         hit (inclusive),   miss (see below) miss, even when the
 *   (default)          never a leak:                       ray lies in the
 *                      a ray through a                     triangle's plane
 *                      shared edge hits
 *                      at least one side
 *   moller_trumbore    hit if the         miss (D = 0)     miss (D = 0)
 *                      rounding allows;
 *                      may leak
 *   two_step           as moller          miss (N = 0)     miss (N·d = 0)
 *
 * Degenerate triangles: all three tests miss when two vertices coincide or
 * for any ray that does not pass through the triangle's line.  For three
 * distinct collinear vertices the watertight test's edge functions are all
 * zero only in exact arithmetic; a ray aimed exactly at a point of that
 * segment can therefore register a hit — at the correct t, on the segment
 * (tests/test_accel_suite.c checks exactly that).  Everywhere else: miss.
 *
 * Watertightness needs the edge functions computed the same way for every
 * triangle: compile sidx with -ffp-contract=off (the Makefile does), or a
 * compiler may fuse some of them into FMAs and let rays slip through edges
 * (found by fuzzing clang's AVX2 kernels; tests/fuzz/regress/build/).
 *
 * Denormal coordinates (0 < |x| < FLT_MIN) underflow in the products: the
 * watertight test may then report t = 0 for an origin ~1e-40 off the plane
 * (docs/errors.md).  Scale such geometry up.
 *
 * A negative t ("What if t is negative?" on the slides) is an intersection
 * behind the origin: every test reports it as a miss when t < tmin.
 *
 * Box tests return the parametric interval [t_near, t_far] clipped to
 * [tmin, tmax].  A ±0 direction component is handled without NaN: the slab
 * of that axis then either contains the origin (no restriction) or not
 * (miss).  A ray lying exactly on a slab plane counts as inside. */
#ifndef SIDX_INTERSECT_H
#define SIDX_INTERSECT_H

#include "math.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sidx_tri_method {
    SIDX_TRI_WATERTIGHT = 0,     /* Woop, Benthin, Wald 2013 — the default */
    SIDX_TRI_MOLLER_TRUMBORE,    /* Möller & Trumbore 1997 (Cramer's rule, as on the slides) */
    SIDX_TRI_TWO_STEP,           /* the deck's first method: ray–plane, then barycentric test */
    SIDX_TRI_METHOD_COUNT
} sidx_tri_method;

typedef enum sidx_box_method {
    SIDX_BOX_ROBUST = 0,         /* Ize 2013: t_far scaled by 1 + 2γ₃ so no hit is lost — the default */
    SIDX_BOX_PLAIN,              /* the textbook slab test (Kay & Kajiya 1986) */
    SIDX_BOX_METHOD_COUNT
} sidx_box_method;

/* "watertight", "moller", "twostep" / "robust", "plain"; NULL for out-of-range values. */
const char *sidx_tri_method_name(sidx_tri_method m);
const char *sidx_box_method_name(sidx_box_method m);
/* Parse a name; returns SIDX_ERR_INVALID_ARG for an unknown one. */
sidx_status sidx_tri_method_parse(const char *name, sidx_tri_method *out);
sidx_status sidx_box_method_parse(const char *name, sidx_box_method *out);

/* Ray–plane N·x = c (slides: t = (c − N·o) / (N·d)).  Miss when N·d = 0
 * (parallel, including a ray inside the plane) or t outside [tmin, tmax). */
int sidx_intersect_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t);

/* Ray–triangle (a, b, c).  u, v: barycentric weights of b and c. */
int sidx_intersect_triangle(sidx_tri_method m, const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c,
                            float tmax, float *t, float *u, float *v);
int sidx_intersect_triangle_watertight(const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c,
                                       float tmax, float *t, float *u, float *v);
int sidx_intersect_triangle_moller(const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c,
                                   float tmax, float *t, float *u, float *v);
int sidx_intersect_triangle_two_step(const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c,
                                     float tmax, float *t, float *u, float *v);

/* Ray–AABB slab test over [tmin, tmax]. */
int sidx_intersect_aabb(sidx_box_method m, const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax,
                        float *t_near, float *t_far);

/* Bounding sphere. */
typedef struct sidx_sphere { sidx_vec3 center; float radius; } sidx_sphere;
int sidx_intersect_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far);

/* Oriented box: center, three orthonormal axes, half extents along them. */
typedef struct sidx_obb { sidx_vec3 center; sidx_vec3 axis[3]; sidx_vec3 half; } sidx_obb;
int sidx_intersect_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far);

/* Slabs (a k-DOP) along a fixed set of SIDX_KDOP_AXES directions: the
 * three coordinate axes and the four cube diagonals — a 14-DOP. */
#define SIDX_KDOP_AXES 7
typedef struct sidx_kdop { float lo[SIDX_KDOP_AXES], hi[SIDX_KDOP_AXES]; } sidx_kdop;
/* The (unnormalized) directions of the slabs, for drawing and fitting. */
sidx_vec3 sidx_kdop_axis(int i);
int sidx_intersect_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far);

/* Bounding volumes around a point set (n >= 1; points must be finite).
 * Sphere: Ritter 1990 (not minimal, within ~5–20%).  OBB: axes from the
 * covariance of the points (PCA), extents from projecting them.  Return
 * SIDX_ERR_INVALID_ARG on NULL or n == 0. */
sidx_status sidx_aabb_fit(const sidx_vec3 *p, uint32_t n, sidx_aabb *out);
sidx_status sidx_sphere_fit(const sidx_vec3 *p, uint32_t n, sidx_sphere *out);
sidx_status sidx_obb_fit(const sidx_vec3 *p, uint32_t n, sidx_obb *out);
sidx_status sidx_kdop_fit(const sidx_vec3 *p, uint32_t n, sidx_kdop *out);
float sidx_sphere_area(const sidx_sphere *s);
float sidx_obb_area(const sidx_obb *b);

#ifdef __cplusplus
}
#endif
#endif
