/* 15_sphere_obb_dop.c — checker driver: the ray tests of the other bounding
 * volumes of deck 000, "Bounding Volumes": the sphere, the OBB and the
 * slabs of a 14-DOP.  Reference: the library's sidx_intersect_sphere,
 * sidx_intersect_obb and sidx_intersect_kdop (sidx/intersect.h), reported
 * as one BOX_TEST per case (result, t_near, t_far). */
#include <math.h>
#include <string.h>
#include "check.h"

int ray_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far);
int ray_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far);
int ray_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far);

enum { V_SPHERE, V_OBB, V_KDOP };

typedef struct bv_case {
    const char *name;
    int rule;             /* the rule the case is about: its hint */
    char rules[120];      /* the ids of the rules it tests (setup) */
    int kind;
    sidx_sphere s;
    sidx_obb b;
    sidx_kdop k;
    sidx_ray ray;
    float tmin, tmax;
} bv_case;

#define BV_MAX 160
static bv_case cases[BV_MAX];
static size_t n_cases;

/* The hand-out's rules, in its order. */
enum { R_QUAD, R_NO_ROOT, R_TANGENT, R_FAR, R_OBB, R_KDOP, R_SWAP, R_PARALLEL, R_PARALLEL_IN, R_CLIP, R_TOUCH,
       R_UNTOUCHED, NRULES };
static const ex_rule rules[NRULES] = {
    {"sphere-quadratic", "the sphere: a quadratic in t with a = d·d (d need not be unit length), t_near and t_far "
     "its two roots",
     "Sphere (\"very fast intersection computation\"): |o + t·d - c|^2 = r^2 is a quadratic in t; t_near and t_far "
     "are its two roots (-b -/+ sqrt(disc))/a with a = d·d, clipped to [tmin, tmax]: the direction need not be unit "
     "length, a = d·d stays in the roots and in the discriminant"},
    {"sphere-no-root", "no real root (discriminant < 0) is a miss",
     "Sphere: no real root (a discriminant < 0) is a miss: return 0 before taking its square root"},
    {"sphere-tangent", "one root (a tangent ray, discriminant 0) is a hit of one point",
     "Sphere: a tangent ray has discriminant 0, one double root: a hit of one point (t_near == t_far), not a miss"},
    {"sphere-far", "the discriminant from the centre's distance to the ray's line, disc = d·d·(r² - l·l), not b² - a·c",
     "Sphere: form the discriminant from the centre's distance to the ray's line, l = f - (f·d/d·d)·d with "
     "f = o - c, disc = d·d·(r² - l·l): the textbook b² - a·c subtracts two huge, nearly equal numbers for a far "
     "sphere and loses its digits"},
    {"obb-own-axes", "the OBB: three slabs along its own axes a_i, a_i·center ± half_i",
     "Non-axis-aligned box (\"oriented bounding box (OBB)\"): three slabs along the box's own axes a_i, "
     "a_i·center - half_i <= a_i·x <= a_i·center + half_i; t_near is the largest entry, t_far the smallest exit"},
    {"kdop-seven-axes", "the 14-DOP: seven slabs lo[i] <= n_i·x <= hi[i] along sidx_kdop_axis(i), used as they are "
     "(not unit length)",
     "Slabs (\"pairs of half spaces\", \"fixed number of orientations/axes: e.g. x+y, x-y, etc.\"): lo[i] <= n_i·x <= "
     "hi[i] along the seven axes sidx_kdop_axis(i), not unit length; t_near is the largest entry, t_far the smallest "
     "exit"},
    {"entry-smaller", "a slab's entry is the smaller of (lo - n·o)/(n·d) and (hi - n·o)/(n·d)",
     "entry and exit of a slab swap when n·d < 0: the entry is the smaller of (lo - n·o)/(n·d) and (hi - n·o)/(n·d)"},
    {"parallel-no-divide", "a ray parallel to a slab (n·d = 0, ±0) is inside it for every t or never: n·o against "
     "[lo, hi], no division",
     "a ray parallel to a slab (n·d = 0, ±0 included) is inside it for every t or never: test n·o against [lo, hi], "
     "both bounds inside (a ray in a face plane is inside); never divide by n·d = 0"},
    {"parallel-bounds-inside", "a parallel ray with n·o == lo or n·o == hi (in a face plane) is inside",
     "a parallel ray in a face plane (n·o == lo or n·o == hi) is inside the slab: both bounds inside, lo <= n·o <= hi"},
    {"clip-range", "the inside part is clipped to [tmin, tmax]: behind the origin or beyond tmax is a miss, an origin "
     "inside enters at tmin",
     "clip to [tmin, tmax]: a volume behind the origin or beyond tmax is a miss, an origin inside enters at tmin"},
    {"touch-inclusive", "a hit when t_near <= t_far, the bound included (one point is a hit)",
     "the volume is hit when t_near <= t_far, the bound included: a flat slab (lo == hi) crossed, or an edge touched, "
     "gives t_near == t_far"},
    {"miss-untouched", "on a miss (return 0) *t_near and *t_far are not written",
     "return 0 on a miss and leave *t_near and *t_far as they were: write them only for a hit"},
};

static sidx_vec3 V(float x, float y, float z) { return sidx_v3(x, y, z); }

static bv_case *add(const char *name, int rule, int kind, sidx_ray ray, float tmin, float tmax)
{
    bv_case *c = &cases[n_cases++];
    memset(c, 0, sizeof *c);
    c->name = name;
    c->rule = rule;
    c->kind = kind;
    c->ray = ray;
    c->tmin = tmin;
    c->tmax = tmax;
    return c;
}

static void sph(const char *name, int rule, sidx_vec3 c, float rad, sidx_ray ray, float tmin, float tmax)
{
    bv_case *k = add(name, rule, V_SPHERE, ray, tmin, tmax);
    k->s.center = c;
    k->s.radius = rad;
}

/* An OBB turned by angle ang (radians) about z, then its axes as given. */
static void obb(const char *name, int rule, sidx_vec3 c, float ang, sidx_vec3 half, sidx_ray ray, float tmin,
                float tmax)
{
    bv_case *k = add(name, rule, V_OBB, ray, tmin, tmax);
    k->b.center = c;
    const float cs = ang == 0.0f ? 1.0f : cosf(ang), sn = ang == 0.0f ? 0.0f : sinf(ang);
    k->b.axis[0] = V(cs, sn, 0);
    k->b.axis[1] = V(-sn, cs, 0);
    k->b.axis[2] = V(0, 0, 1);
    k->b.half = half;
}

/* A 14-DOP fitted to the points, then slab j optionally set to [lo, hi]. */
static void dop(const char *name, int rule, const sidx_vec3 *p, uint32_t n, int j, float lo, float hi,
                sidx_ray ray, float tmin, float tmax)
{
    bv_case *k = add(name, rule, V_KDOP, ray, tmin, tmax);
    (void)sidx_kdop_fit(p, n, &k->k);
    if (j >= 0) {
        k->k.lo[j] = lo;
        k->k.hi[j] = hi;
    }
}

static int reference_test(const bv_case *c, float *tn, float *tf)
{
    if (c->kind == V_SPHERE) return sidx_intersect_sphere(&c->ray, &c->s, c->tmin, c->tmax, tn, tf);
    if (c->kind == V_OBB) return sidx_intersect_obb(&c->ray, &c->b, c->tmin, c->tmax, tn, tf);
    return sidx_intersect_kdop(&c->ray, &c->k, c->tmin, c->tmax, tn, tf);
}

/* The slabs of an OBB or a 14-DOP: normal n_j, [lo_j, hi_j]; their number. */
static int slabs_of(const bv_case *c, sidx_vec3 *n, float *lo, float *hi)
{
    if (c->kind == V_OBB) {
        const float h[3] = {c->b.half.x, c->b.half.y, c->b.half.z};
        for (int j = 0; j < 3; ++j) {
            const float m = sidx_v3_dot(c->b.axis[j], c->b.center);
            n[j] = c->b.axis[j];
            lo[j] = m - h[j];
            hi[j] = m + h[j];
        }
        return 3;
    }
    for (int j = 0; j < SIDX_KDOP_AXES; ++j) {
        n[j] = sidx_kdop_axis(j);
        lo[j] = c->k.lo[j];
        hi[j] = c->k.hi[j];
    }
    return SIDX_KDOP_AXES;
}

/* The rules case c tests: its own, the volume's test, a slab crossed
 * with n·d < 0 (the entry is the hi side), a miss (outputs untouched). */
static void case_rules(bv_case *c)
{
    static const int general[3] = {R_QUAD, R_OBB, R_KDOP};
    int has[NRULES] = {0};
    has[c->rule] = has[general[c->kind]] = 1;
    if (c->kind != V_SPHERE) {
        sidx_vec3 n[SIDX_KDOP_AXES];
        float lo[SIDX_KDOP_AXES], hi[SIDX_KDOP_AXES];
        const int m = slabs_of(c, n, lo, hi);
        for (int j = 0; j < m; ++j) {
            has[R_SWAP] |= sidx_v3_dot(n[j], c->ray.dir) < 0.0f;
            has[R_PARALLEL] |= sidx_v3_dot(n[j], c->ray.dir) == 0.0f;
        }
    }
    float tn, tf;
    has[R_UNTOUCHED] = !reference_test(c, &tn, &tf);
    c->rules[0] = '\0';
    for (int r = 0; r < NRULES; ++r)
        if (has[r]) {
            const size_t len = strlen(c->rules);
            snprintf(c->rules + len, sizeof c->rules - len, "%s%s", len ? " " : "", rules[r].id);
        }
}

static int setup(void)
{
    const float inf = INFINITY;
    n_cases = 0;
    /* the sphere */
    sph("sphere: head-on", R_QUAD, V(0, 0, 0), 1, ex_ray(-5, 0.25f, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: oblique, off-centre", R_QUAD, V(1, 2, 3), 2, ex_ray(-3, -1, 0, 1, 0.75f, 0.5f, 0, inf), 0, inf);
    sph("sphere: miss beside it", R_NO_ROOT, V(0, 0, 0), 1, ex_ray(-5, 1.5f, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: tangent ray (discriminant 0)", R_TANGENT, V(0, 0, 0), 1, ex_ray(-5, 1, 0, 1, 0, 0, 0, inf), 0,
        inf);
    sph("sphere: tangent ray, direction of length 2", R_TANGENT, V(0, 0, 0), 2, ex_ray(3, -4, 2, 0, 2, 0, 0, inf),
        0, inf);
    sph("sphere: direction not unit length", R_QUAD, V(0, 0, 0), 1, ex_ray(-6, 0, 0, 4, 0, 0, 0, inf), 0, inf);
    sph("sphere: direction not unit length, oblique", R_QUAD, V(1, 1, 1), 1.5f,
        ex_ray(-4, -3, 1, 3, 2, 0.5f, 0, inf), 0, inf);
    sph("sphere: origin inside", R_CLIP, V(0, 0, 0), 2, ex_ray(0.5f, 0.25f, 0, 0, 1, 0, 0, inf), 0, inf);
    sph("sphere: origin inside, tmin > 0", R_CLIP, V(0, 0, 0), 2, ex_ray(0, 0, 0, 1, 0, 0, 0.5f, inf), 0.5f, inf);
    sph("sphere: behind the origin", R_CLIP, V(0, 0, 0), 1, ex_ray(5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: beyond tmax", R_CLIP, V(0, 0, 0), 1, ex_ray(-5, 0, 0, 1, 0, 0, 0, 3), 0, 3);
    sph("sphere: tmax inside it", R_CLIP, V(0, 0, 0), 1, ex_ray(-5, 0, 0, 1, 0, 0, 0, 4.5f), 0, 4.5f);
    sph("sphere: origin on the surface, leaving (t_near == t_far == tmin)", R_TOUCH, V(0, 0, 0), 1,
        ex_ray(1, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: origin on the surface, entering", R_QUAD, V(0, 0, 0), 1, ex_ray(-1, 0, 0, 1, 0, 0, 0, inf), 0,
        inf);
    sph("sphere: -0 direction components", R_QUAD, V(0, 0, 0), 1, ex_ray(0.5f, 0.25f, 5, -0.0f, -0.0f, -1, 0, inf),
        0, inf);
    sph("sphere: radius 0 (a point) on the ray", R_TANGENT, V(2, 0, 0), 0, ex_ray(0, 0, 0, 1, 0, 0, 0, inf), 0,
        inf);
    sph("sphere: far away (the centre 1e4 off)", R_FAR, V(1e4f, 0, 0), 1, ex_ray(0, 0.5f, 0, 1, 0, 0, 0, inf),
        0, inf);
    sph("sphere: far away, grazing", R_FAR, V(1e4f, 0, 0), 1, ex_ray(0, 0.999f, 0, 1, 0, 0, 0, inf), 0, inf);
    /* the OBB */
    obb("OBB: axis-aligned, head-on", R_OBB, V(0, 0, 0), 0, V(1, 1, 1), ex_ray(-5, 0.25f, 0.5f, 1, 0, 0, 0, inf),
        0, inf);
    obb("OBB: turned by 30 degrees, oblique", R_OBB, V(1, 2, 0), 0.5235988f, V(2, 1, 0.5f),
        ex_ray(-5, -2, 0.25f, 1, 0.75f, 0, 0, inf), 0, inf);
    obb("OBB: turned by 45 degrees, miss past its corner", R_OBB, V(0, 0, 0), 0.7853982f, V(1, 1, 1),
        ex_ray(-5, 1.5f, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: turned by 45 degrees, hit near its corner", R_OBB, V(0, 0, 0), 0.7853982f, V(1, 1, 1),
        ex_ray(-5, 1.25f, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: negative direction on every axis", R_SWAP, V(0, 0, 0), 0.3f, V(1, 2, 1),
        ex_ray(4, 3, 5, -1, -0.75f, -1.25f, 0, inf), 0, inf);
    obb("OBB: ray parallel to a slab, inside it", R_PARALLEL, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, 0.5f, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: ray parallel to a slab, outside it", R_PARALLEL, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, 2, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: ray parallel to a slab, -0 components", R_PARALLEL, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(5, 0.5f, -0.25f, -1, -0.0f, -0.0f, 0, inf), 0, inf);
    obb("OBB: ray in the max face plane (parallel)", R_PARALLEL_IN, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, 1, 0.5f, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: ray in the max face plane, -0 components (n·d = -0)", R_PARALLEL_IN, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(1, 0.5f, 5, -0.0f, -0.0f, -1, 0, inf), 0, inf);
    obb("OBB: ray in the min face plane (parallel)", R_PARALLEL_IN, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, -1, 0.5f, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: flat (half 0 in z), crossed head-on (t_near == t_far)", R_TOUCH, V(0, 0, 0), 0, V(1, 1, 0),
        ex_ray(0.5f, 0.5f, 3, 0, 0, -1, 0, inf), 0, inf);
    obb("OBB: an edge touched (t_near == t_far)", R_TOUCH, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-2, 0, 0.5f, 1, 1, 0, 0, inf), 0, inf);
    obb("OBB: origin inside", R_CLIP, V(0, 0, 0), 0.4f, V(1, 1, 1), ex_ray(0.25f, 0.5f, -0.5f, 1, -1, 0.5f, 0, inf),
        0, inf);
    obb("OBB: behind the origin", R_CLIP, V(0, 0, 0), 0.4f, V(1, 1, 1), ex_ray(5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: beyond tmax", R_CLIP, V(0, 0, 0), 0.4f, V(1, 1, 1), ex_ray(-5, 0, 0, 1, 0, 0, 0, 3), 0, 3);
    obb("OBB: tmax inside it", R_CLIP, V(0, 0, 0), 0, V(1, 1, 1), ex_ray(-5, 0, 0, 1, 0, 0, 0, 5), 0, 5);
    obb("OBB: origin on the exit face, leaving (t_near == t_far == tmin)", R_TOUCH, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(1, 0.25f, 0.5f, 1, 0.5f, 0.25f, 0, inf), 0, inf);
    obb("OBB: half extents differ per axis (which half goes with which axis)", R_OBB, V(0, 0, 0), 0, V(3, 1, 0.5f),
        ex_ray(-0.5f, -5, 0.25f, 0, 1, 0, 0, inf), 0, inf);
    obb("OBB: half extents differ per axis, along x", R_OBB, V(0, 0, 0), 0, V(3, 1, 0.5f),
        ex_ray(-5, 0.5f, 0.25f, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: half extents differ per axis, along z", R_OBB, V(0, 0, 0), 0, V(3, 1, 0.5f),
        ex_ray(0.5f, 0.5f, 5, 0, 0, -1, 0, inf), 0, inf);
    /* the 14-DOP */
    const sidx_vec3 cube[8] = {V(-1, -1, -1), V(1, -1, -1), V(-1, 1, -1), V(1, 1, -1),
                               V(-1, -1, 1),  V(1, -1, 1),  V(-1, 1, 1),  V(1, 1, 1)};
    const sidx_vec3 tet[4] = {V(0, 0, 0), V(2, 0, 0), V(0, 2, 0), V(0, 0, 2)};
    dop("14-DOP of a cube: head-on", R_KDOP, cube, 8, -1, 0, 0, ex_ray(-5, 0.25f, 0.5f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a cube: through the corner region a diagonal slab cuts", R_KDOP, cube, 8, 3, -2, 2,
        ex_ray(-5, 0.9f, 0.9f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a tetrahedron: a diagonal slab decides", R_KDOP, tet, 4, -1, 0, 0,
        ex_ray(-5, 1.5f, 1.5f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a tetrahedron: hit through its slanted face", R_KDOP, tet, 4, -1, 0, 0,
        ex_ray(5, 0.25f, 0.25f, -1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a tetrahedron: oblique", R_KDOP, tet, 4, -1, 0, 0, ex_ray(-3, -2, -1, 1, 0.75f, 0.5f, 0, inf),
        0, inf);
    dop("14-DOP of a tetrahedron: negative direction", R_SWAP, tet, 4, -1, 0, 0,
        ex_ray(4, 3, 5, -1, -0.75f, -1.25f, 0, inf), 0, inf);
    dop("14-DOP: ray parallel to the x-y+z slab, inside it", R_PARALLEL, cube, 8, 4, -1, 1,
        ex_ray(-5, -5, 0.25f, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: ray parallel to the x-y+z slab, outside it", R_PARALLEL, cube, 8, 4, -1, 1,
        ex_ray(-5, -3, 0.25f, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: ray in the plane x-y+z = hi (parallel)", R_PARALLEL_IN, cube, 8, 4, -1, 1,
        ex_ray(-5, -4, 0, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: ray in the plane x-y+z = lo (parallel)", R_PARALLEL_IN, cube, 8, 4, -1, 1,
        ex_ray(-5, -6, 0, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: -0 direction components", R_PARALLEL, cube, 8, -1, 0, 0,
        ex_ray(0.5f, 0.25f, 5, -0.0f, -0.0f, -1, 0, inf), 0, inf);
    dop("14-DOP: a flat diagonal slab (lo == hi) crossed (t_near == t_far)", R_TOUCH, cube, 8, 3, 0.5f, 0.5f,
        ex_ray(-5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP: origin inside", R_CLIP, tet, 4, -1, 0, 0, ex_ray(0.25f, 0.25f, 0.25f, 1, -1, 0.5f, 0, inf), 0,
        inf);
    dop("14-DOP: behind the origin", R_CLIP, cube, 8, -1, 0, 0, ex_ray(5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP: beyond tmax", R_CLIP, cube, 8, -1, 0, 0, ex_ray(-5, 0, 0, 1, 0, 0, 0, 3), 0, 3);
    dop("14-DOP: tmax inside it", R_CLIP, tet, 4, -1, 0, 0, ex_ray(-5, 0.5f, 0.5f, 1, 0, 0, 0, 5.5f), 0, 5.5f);
    dop("14-DOP of a cube: the last slab (x-y-z) decides", R_KDOP, cube, 8, 6, -1, 1,
        ex_ray(-5, -1.5f, -1.5f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a cube: the last slab (x-y-z) misses", R_KDOP, cube, 8, 6, -1, 1,
        ex_ray(-5, -0.9f, -0.9f, 1, 0, 0, 0, inf), 0, inf);
    /* random volumes and rays */
    uint32_t st = 1515u;
    for (int i = 0; i < 24; ++i) {
        const float ox = ex_rand(&st) * 8 - 4, oy = ex_rand(&st) * 8 - 4, oz = ex_rand(&st) * 8 - 4;
        const float dx = -ox + ex_rand(&st) * 2 - 1, dy = -oy + ex_rand(&st) * 2 - 1, dz = -oz + ex_rand(&st) * 2 - 1;
        const float tmax = (i % 4 == 3) ? 0.75f : inf;
        const sidx_ray ray = ex_ray(ox, oy, oz, dx, dy, dz + 0.01f, 0, tmax);
        if (i % 3 == 0) {
            sph("sphere: random", R_QUAD, V(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f),
                0.5f + ex_rand(&st) * 1.5f, ray, 0, tmax);
        } else if (i % 3 == 1) {
            obb("OBB: random", R_OBB, V(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, 0), ex_rand(&st) * 3.0f,
                V(0.5f + ex_rand(&st), 0.5f + ex_rand(&st), 0.5f + ex_rand(&st)), ray, 0, tmax);
        } else {
            sidx_vec3 p[5];
            for (int j = 0; j < 5; ++j) p[j] = V(ex_rand(&st) * 3 - 1.5f, ex_rand(&st) * 3 - 1.5f, ex_rand(&st) * 3 - 1.5f);
            dop("14-DOP: random", R_KDOP, p, 5, -1, 0, 0, ray, 0, tmax);
        }
    }
    for (size_t i = 0; i < n_cases; ++i) case_rules(&cases[i]);
    return 0;
}

static size_t num_cases(void) { return n_cases; }

static void describe(size_t i, ex_case_info *out)
{
    const bv_case *c = &cases[i];
    char ray[160], vol[340];
    ex_format_ray(ray, sizeof ray, &c->ray);
    if (c->kind == V_SPHERE)
        snprintf(vol, sizeof vol, "sphere c=(%g, %g, %g) r=%g", (double)c->s.center.x, (double)c->s.center.y,
                 (double)c->s.center.z, (double)c->s.radius);
    else if (c->kind == V_OBB)
        snprintf(vol, sizeof vol, "OBB c=(%g, %g, %g) a0=(%g, %g, %g) a1=(%g, %g, %g) a2=(0, 0, 1) half=(%g, %g, %g)",
                 (double)c->b.center.x, (double)c->b.center.y, (double)c->b.center.z, (double)c->b.axis[0].x,
                 (double)c->b.axis[0].y, (double)c->b.axis[0].z, (double)c->b.axis[1].x, (double)c->b.axis[1].y,
                 (double)c->b.axis[1].z, (double)c->b.half.x, (double)c->b.half.y, (double)c->b.half.z);
    else {
        int n = snprintf(vol, sizeof vol, "14-DOP");
        for (int j = 0; j < SIDX_KDOP_AXES && n > 0 && (size_t)n < sizeof vol; ++j)
            n += snprintf(vol + n, sizeof vol - (size_t)n, " [%g, %g]", (double)c->k.lo[j], (double)c->k.hi[j]);
    }
    snprintf(out->name, sizeof out->name, "%s", c->name);
    snprintf(out->what, sizeof out->what, "%.150s; %.300s, clipped to [%g, %g]", ray, vol, (double)c->tmin, (double)c->tmax);
    out->hint = rules[c->rule].hint;
    out->rules = c->rules;
}

static const char *const kind_name[] = {"sphere", "obb", "kdop"};

/* One BOX_TEST (result, t_near, t_far); after a miss a NOTE whose count
 * says whether *t_near or *t_far was written (they start as NaN). */
static void emit(const sidx_hook *h, size_t i, int hit, float tn, float tf)
{
    sidx_ex ex;
    memset(&ex, 0, sizeof ex);
    ex.hook = h;
    ex.structure = kind_name[cases[i].kind];
    sidx_aabb none = sidx_aabb_empty();
    sidx_ex_box_test(&ex, (uint32_t)i, &none, hit, tn, tf);
    if (hit) return;
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = ex.structure;
    e.count = !isnan(tn) || !isnan(tf);
    e.t_near = e.t_far = 0.0f;
    sidx_hook_emit(h, &e);
}

static void reference(size_t i, const sidx_hook *h)
{
    float tn = NAN, tf = NAN;
    const int hit = reference_test(&cases[i], &tn, &tf);
    emit(h, i, hit, tn, tf);
}

static void student(size_t i, const sidx_hook *h)
{
    const bv_case *c = &cases[i];
    float tn = NAN, tf = NAN;
    int hit;
    if (c->kind == V_SPHERE) hit = ray_sphere(&c->ray, &c->s, c->tmin, c->tmax, &tn, &tf);
    else if (c->kind == V_OBB) hit = ray_obb(&c->ray, &c->b, c->tmin, c->tmax, &tn, &tf);
    else hit = ray_kdop(&c->ray, &c->k, c->tmin, c->tmax, &tn, &tf);
    emit(h, i, hit, tn, tf);
}

/* Two known mistakes, played on the case for the hint: the textbook
 * discriminant b² - a·c, and slabs whose entry and exit are never
 * swapped.  Each returns the hit flag and writes the interval. */
static int textbook_sphere(const bv_case *c, float *tn, float *tf)
{
    const sidx_vec3 f = sidx_v3_sub(c->ray.org, c->s.center);
    const float a = sidx_v3_dot(c->ray.dir, c->ray.dir), b = -sidx_v3_dot(f, c->ray.dir);
    const float disc = b * b - a * (sidx_v3_dot(f, f) - c->s.radius * c->s.radius);
    if (disc < 0.0f) return 0;
    const float sq = sqrtf(disc);
    float t0 = (b - sq) / a, t1 = (b + sq) / a;
    if (t0 < c->tmin) t0 = c->tmin;
    if (t1 > c->tmax) t1 = c->tmax;
    *tn = t0;
    *tf = t1;
    return t0 <= t1;
}

/* divide: a parallel slab divided by n·d = 0 like any other (swap kept);
 * else entry and exit never swapped. */
static int slabs_played(const bv_case *c, int divide, float *tn, float *tf)
{
    sidx_vec3 n[SIDX_KDOP_AXES];
    float lo[SIDX_KDOP_AXES], hi[SIDX_KDOP_AXES], t0 = c->tmin, t1 = c->tmax;
    const int m = slabs_of(c, n, lo, hi);
    for (int j = 0; j < m; ++j) {
        const float nd = sidx_v3_dot(n[j], c->ray.dir), no = sidx_v3_dot(n[j], c->ray.org);
        if (nd == 0.0f && !divide) {
            if (!(no >= lo[j] && no <= hi[j])) return 0;
            continue;
        }
        float a = (lo[j] - no) / nd, b = (hi[j] - no) / nd;
        if (divide && a > b) {
            const float x = a;
            a = b;
            b = x;
        }
        if (a > t0) t0 = a;
        if (b < t1) t1 = b;
        if (!(t0 <= t1)) return 0;
    }
    *tn = t0;
    *tf = t1;
    return 1;
}

static int near_t(float a, float b) { return a == b || fabsf(a - b) <= 1e-4f * fmaxf(fabsf(a), fabsf(b)); }

/* The hint by what differs: outputs written on a miss; the student's
 * answer that a known mistake gives (the textbook discriminant, no swap);
 * the case's own rule; for a parallel case whose hit agrees, the
 * volume's test. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const bv_case *c = &cases[i];
    if (!ref || !stu) return NULL;
    if (ref->type == SIDX_EV_NOTE && stu->type == SIDX_EV_NOTE) return rules[R_UNTOUCHED].hint;
    if (ref->type != SIDX_EV_BOX_TEST || stu->type != SIDX_EV_BOX_TEST) return NULL;
    for (int k = c->kind == V_SPHERE ? 0 : 1; k >= 0; --k) { /* a slab divided by 0 first: both may miss */
        float tn = NAN, tf = NAN;
        const int sim = c->kind == V_SPHERE ? textbook_sphere(c, &tn, &tf) : slabs_played(c, k, &tn, &tf);
        if (sim == stu->result && (!sim || (near_t(tn, stu->t_near) && near_t(tf, stu->t_far))))
            return rules[c->kind == V_SPHERE ? R_FAR : k ? R_PARALLEL : R_SWAP].hint;
    }
    if (ref->result != stu->result) return rules[c->rule].hint;
    if (c->rule == R_PARALLEL || c->rule == R_PARALLEL_IN) return rules[c->kind == V_OBB ? R_OBB : R_KDOP].hint;
    return rules[c->rule].hint;
}

/* The NOTE after a miss: whether the outputs were written. */
static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    snprintf(buf, size, "after the miss: %s", e->count ? "*t_near or *t_far written" : "*t_near, *t_far left as they were");
    return 1;
}

const ex_driver ex_driver_this = {
    "15_sphere_obb_dop",
    "the sphere, OBB and 14-DOP ray tests: tangent rays, parallel slabs, flat volumes",
    "deck 000, \"Bounding Volumes\" (sphere, OBB, slabs)",
    setup, num_cases, describe, reference, student, hint, NULL, format, rules, NRULES,
};
