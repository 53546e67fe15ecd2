/* 15_sphere_obb_dop.c — checker driver: the ray tests of the other bounding
 * volumes of deck 000, "Bounding Volumes": the sphere, the OBB and the
 * slabs of a 14-DOP.  Reference: the library's sidx_intersect_sphere,
 * sidx_intersect_obb and sidx_intersect_kdop (sidx/intersect.h), reported
 * as one BOX_TEST per case (result, t_near, t_far). */
#include <string.h>
#include "check.h"

int ray_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far);
int ray_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far);
int ray_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far);

enum { V_SPHERE, V_OBB, V_KDOP };

typedef struct bv_case {
    const char *name, *hint;
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

static const char *const hint_sphere =
    "Sphere (\"very fast intersection computation\"): |o + t·d - c|^2 = r^2 is a quadratic in t; no real root is a "
    "miss, t_near and t_far are the two roots (-b -/+ sqrt(disc))/a with a = d·d, clipped to [tmin, tmax]";
static const char *const hint_tangent =
    "Sphere: a tangent ray has discriminant 0, one double root: a hit of one point (t_near == t_far), not a miss";
static const char *const hint_sphere_a =
    "Sphere: the direction need not be unit length; a = d·d stays in the roots (-b -/+ sqrt(disc))/a and in the "
    "discriminant";
static const char *const hint_obb =
    "Non-axis-aligned box (\"oriented bounding box (OBB)\"): three slabs along the box's own axes a_i, "
    "a_i·center - half_i <= a_i·x <= a_i·center + half_i; t_near is the largest entry, t_far the smallest exit";
static const char *const hint_slabs =
    "Slabs (\"pairs of half spaces\", \"fixed number of orientations/axes: e.g. x+y, x-y, etc.\"): lo[i] <= n_i·x <= "
    "hi[i] along the seven axes sidx_kdop_axis(i), not unit length; t_near is the largest entry, t_far the smallest "
    "exit";
static const char *const hint_parallel =
    "a ray parallel to a slab (n·d = 0, ±0 included) is inside it for every t or never: test n·o against [lo, hi], "
    "both bounds inside (a ray in a face plane is inside); never divide by n·d = 0";
static const char *const hint_clip =
    "clip to [tmin, tmax]: a volume behind the origin or beyond tmax is a miss, an origin inside enters at tmin";
static const char *const hint_touch =
    "the volume is hit when t_near <= t_far, the bound included: a flat slab (lo == hi) crossed, or an edge touched, "
    "gives t_near == t_far";
static const char *const hint_swap =
    "entry and exit of a slab swap when n·d < 0: the entry is the smaller of (lo - n·o)/(n·d) and (hi - n·o)/(n·d)";

static sidx_vec3 V(float x, float y, float z) { return sidx_v3(x, y, z); }

static bv_case *add(const char *name, const char *hint, int kind, sidx_ray ray, float tmin, float tmax)
{
    bv_case *c = &cases[n_cases++];
    memset(c, 0, sizeof *c);
    c->name = name;
    c->hint = hint;
    c->kind = kind;
    c->ray = ray;
    c->tmin = tmin;
    c->tmax = tmax;
    return c;
}

static void sph(const char *name, const char *hint, sidx_vec3 c, float rad, sidx_ray ray, float tmin, float tmax)
{
    bv_case *k = add(name, hint, V_SPHERE, ray, tmin, tmax);
    k->s.center = c;
    k->s.radius = rad;
}

/* An OBB turned by angle ang (radians) about z, then its axes as given. */
static void obb(const char *name, const char *hint, sidx_vec3 c, float ang, sidx_vec3 half, sidx_ray ray, float tmin,
                float tmax)
{
    bv_case *k = add(name, hint, V_OBB, ray, tmin, tmax);
    k->b.center = c;
    const float cs = ang == 0.0f ? 1.0f : cosf(ang), sn = ang == 0.0f ? 0.0f : sinf(ang);
    k->b.axis[0] = V(cs, sn, 0);
    k->b.axis[1] = V(-sn, cs, 0);
    k->b.axis[2] = V(0, 0, 1);
    k->b.half = half;
}

/* A 14-DOP fitted to the points, then slab j optionally set to [lo, hi]. */
static void dop(const char *name, const char *hint, const sidx_vec3 *p, uint32_t n, int j, float lo, float hi,
                sidx_ray ray, float tmin, float tmax)
{
    bv_case *k = add(name, hint, V_KDOP, ray, tmin, tmax);
    (void)sidx_kdop_fit(p, n, &k->k);
    if (j >= 0) {
        k->k.lo[j] = lo;
        k->k.hi[j] = hi;
    }
}

static int setup(void)
{
    const float inf = INFINITY;
    n_cases = 0;
    /* the sphere */
    sph("sphere: head-on", hint_sphere, V(0, 0, 0), 1, ex_ray(-5, 0.25f, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: oblique, off-centre", hint_sphere, V(1, 2, 3), 2, ex_ray(-3, -1, 0, 1, 0.75f, 0.5f, 0, inf), 0, inf);
    sph("sphere: miss beside it", hint_sphere, V(0, 0, 0), 1, ex_ray(-5, 1.5f, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: tangent ray (discriminant 0)", hint_tangent, V(0, 0, 0), 1, ex_ray(-5, 1, 0, 1, 0, 0, 0, inf), 0,
        inf);
    sph("sphere: tangent ray, direction of length 2", hint_tangent, V(0, 0, 0), 2, ex_ray(3, -4, 2, 0, 2, 0, 0, inf),
        0, inf);
    sph("sphere: direction not unit length", hint_sphere_a, V(0, 0, 0), 1, ex_ray(-6, 0, 0, 4, 0, 0, 0, inf), 0, inf);
    sph("sphere: direction not unit length, oblique", hint_sphere_a, V(1, 1, 1), 1.5f,
        ex_ray(-4, -3, 1, 3, 2, 0.5f, 0, inf), 0, inf);
    sph("sphere: origin inside", hint_clip, V(0, 0, 0), 2, ex_ray(0.5f, 0.25f, 0, 0, 1, 0, 0, inf), 0, inf);
    sph("sphere: origin inside, tmin > 0", hint_clip, V(0, 0, 0), 2, ex_ray(0, 0, 0, 1, 0, 0, 0.5f, inf), 0.5f, inf);
    sph("sphere: behind the origin", hint_clip, V(0, 0, 0), 1, ex_ray(5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: beyond tmax", hint_clip, V(0, 0, 0), 1, ex_ray(-5, 0, 0, 1, 0, 0, 0, 3), 0, 3);
    sph("sphere: tmax inside it", hint_clip, V(0, 0, 0), 1, ex_ray(-5, 0, 0, 1, 0, 0, 0, 4.5f), 0, 4.5f);
    sph("sphere: origin on the surface, leaving (t_near == t_far == tmin)", hint_touch, V(0, 0, 0), 1,
        ex_ray(1, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    sph("sphere: origin on the surface, entering", hint_sphere, V(0, 0, 0), 1, ex_ray(-1, 0, 0, 1, 0, 0, 0, inf), 0,
        inf);
    sph("sphere: -0 direction components", hint_sphere, V(0, 0, 0), 1, ex_ray(0.5f, 0.25f, 5, -0.0f, -0.0f, -1, 0, inf),
        0, inf);
    sph("sphere: radius 0 (a point) on the ray", hint_tangent, V(2, 0, 0), 0, ex_ray(0, 0, 0, 1, 0, 0, 0, inf), 0,
        inf);
    sph("sphere: far away (the centre 1e4 off)", hint_sphere, V(1e4f, 0, 0), 1, ex_ray(0, 0.5f, 0, 1, 0, 0, 0, inf),
        0, inf);
    sph("sphere: far away, grazing", hint_tangent, V(1e4f, 0, 0), 1, ex_ray(0, 0.999f, 0, 1, 0, 0, 0, inf), 0, inf);
    /* the OBB */
    obb("OBB: axis-aligned, head-on", hint_obb, V(0, 0, 0), 0, V(1, 1, 1), ex_ray(-5, 0.25f, 0.5f, 1, 0, 0, 0, inf),
        0, inf);
    obb("OBB: turned by 30 degrees, oblique", hint_obb, V(1, 2, 0), 0.5235988f, V(2, 1, 0.5f),
        ex_ray(-5, -2, 0.25f, 1, 0.75f, 0, 0, inf), 0, inf);
    obb("OBB: turned by 45 degrees, miss past its corner", hint_obb, V(0, 0, 0), 0.7853982f, V(1, 1, 1),
        ex_ray(-5, 1.5f, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: turned by 45 degrees, hit near its corner", hint_obb, V(0, 0, 0), 0.7853982f, V(1, 1, 1),
        ex_ray(-5, 1.25f, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: negative direction on every axis", hint_swap, V(0, 0, 0), 0.3f, V(1, 2, 1),
        ex_ray(4, 3, 5, -1, -0.75f, -1.25f, 0, inf), 0, inf);
    obb("OBB: ray parallel to a slab, inside it", hint_parallel, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, 0.5f, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: ray parallel to a slab, outside it", hint_parallel, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, 2, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: ray parallel to a slab, -0 components", hint_parallel, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(5, 0.5f, -0.25f, -1, -0.0f, -0.0f, 0, inf), 0, inf);
    obb("OBB: ray in the max face plane (parallel)", hint_parallel, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, 1, 0.5f, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: ray in the max face plane, -0 components (n·d = -0)", hint_parallel, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(1, 0.5f, 5, -0.0f, -0.0f, -1, 0, inf), 0, inf);
    obb("OBB: ray in the min face plane (parallel)", hint_parallel, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-5, -1, 0.5f, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: flat (half 0 in z), crossed head-on (t_near == t_far)", hint_touch, V(0, 0, 0), 0, V(1, 1, 0),
        ex_ray(0.5f, 0.5f, 3, 0, 0, -1, 0, inf), 0, inf);
    obb("OBB: an edge touched (t_near == t_far)", hint_touch, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(-2, 0, 0.5f, 1, 1, 0, 0, inf), 0, inf);
    obb("OBB: origin inside", hint_clip, V(0, 0, 0), 0.4f, V(1, 1, 1), ex_ray(0.25f, 0.5f, -0.5f, 1, -1, 0.5f, 0, inf),
        0, inf);
    obb("OBB: behind the origin", hint_clip, V(0, 0, 0), 0.4f, V(1, 1, 1), ex_ray(5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: beyond tmax", hint_clip, V(0, 0, 0), 0.4f, V(1, 1, 1), ex_ray(-5, 0, 0, 1, 0, 0, 0, 3), 0, 3);
    obb("OBB: tmax inside it", hint_clip, V(0, 0, 0), 0, V(1, 1, 1), ex_ray(-5, 0, 0, 1, 0, 0, 0, 5), 0, 5);
    obb("OBB: origin on the exit face, leaving (t_near == t_far == tmin)", hint_touch, V(0, 0, 0), 0, V(1, 1, 1),
        ex_ray(1, 0.25f, 0.5f, 1, 0.5f, 0.25f, 0, inf), 0, inf);
    obb("OBB: half extents differ per axis (which half goes with which axis)", hint_obb, V(0, 0, 0), 0, V(3, 1, 0.5f),
        ex_ray(-0.5f, -5, 0.25f, 0, 1, 0, 0, inf), 0, inf);
    obb("OBB: half extents differ per axis, along x", hint_obb, V(0, 0, 0), 0, V(3, 1, 0.5f),
        ex_ray(-5, 0.5f, 0.25f, 1, 0, 0, 0, inf), 0, inf);
    obb("OBB: half extents differ per axis, along z", hint_obb, V(0, 0, 0), 0, V(3, 1, 0.5f),
        ex_ray(0.5f, 0.5f, 5, 0, 0, -1, 0, inf), 0, inf);
    /* the 14-DOP */
    const sidx_vec3 cube[8] = {V(-1, -1, -1), V(1, -1, -1), V(-1, 1, -1), V(1, 1, -1),
                               V(-1, -1, 1),  V(1, -1, 1),  V(-1, 1, 1),  V(1, 1, 1)};
    const sidx_vec3 tet[4] = {V(0, 0, 0), V(2, 0, 0), V(0, 2, 0), V(0, 0, 2)};
    dop("14-DOP of a cube: head-on", hint_slabs, cube, 8, -1, 0, 0, ex_ray(-5, 0.25f, 0.5f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a cube: through the corner region a diagonal slab cuts", hint_slabs, cube, 8, 3, -2, 2,
        ex_ray(-5, 0.9f, 0.9f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a tetrahedron: a diagonal slab decides", hint_slabs, tet, 4, -1, 0, 0,
        ex_ray(-5, 1.5f, 1.5f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a tetrahedron: hit through its slanted face", hint_slabs, tet, 4, -1, 0, 0,
        ex_ray(5, 0.25f, 0.25f, -1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a tetrahedron: oblique", hint_slabs, tet, 4, -1, 0, 0, ex_ray(-3, -2, -1, 1, 0.75f, 0.5f, 0, inf),
        0, inf);
    dop("14-DOP of a tetrahedron: negative direction", hint_swap, tet, 4, -1, 0, 0,
        ex_ray(4, 3, 5, -1, -0.75f, -1.25f, 0, inf), 0, inf);
    dop("14-DOP: ray parallel to the x-y+z slab, inside it", hint_parallel, cube, 8, 4, -1, 1,
        ex_ray(-5, -5, 0.25f, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: ray parallel to the x-y+z slab, outside it", hint_parallel, cube, 8, 4, -1, 1,
        ex_ray(-5, -3, 0.25f, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: ray in the plane x-y+z = hi (parallel)", hint_parallel, cube, 8, 4, -1, 1,
        ex_ray(-5, -4, 0, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: ray in the plane x-y+z = lo (parallel)", hint_parallel, cube, 8, 4, -1, 1,
        ex_ray(-5, -6, 0, 1, 1, 0, 0, inf), 0, inf);
    dop("14-DOP: -0 direction components", hint_parallel, cube, 8, -1, 0, 0,
        ex_ray(0.5f, 0.25f, 5, -0.0f, -0.0f, -1, 0, inf), 0, inf);
    dop("14-DOP: a flat diagonal slab (lo == hi) crossed (t_near == t_far)", hint_touch, cube, 8, 3, 0.5f, 0.5f,
        ex_ray(-5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP: origin inside", hint_clip, tet, 4, -1, 0, 0, ex_ray(0.25f, 0.25f, 0.25f, 1, -1, 0.5f, 0, inf), 0,
        inf);
    dop("14-DOP: behind the origin", hint_clip, cube, 8, -1, 0, 0, ex_ray(5, 0, 0, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP: beyond tmax", hint_clip, cube, 8, -1, 0, 0, ex_ray(-5, 0, 0, 1, 0, 0, 0, 3), 0, 3);
    dop("14-DOP: tmax inside it", hint_clip, tet, 4, -1, 0, 0, ex_ray(-5, 0.5f, 0.5f, 1, 0, 0, 0, 5.5f), 0, 5.5f);
    dop("14-DOP of a cube: the last slab (x-y-z) decides", hint_slabs, cube, 8, 6, -1, 1,
        ex_ray(-5, -1.5f, -1.5f, 1, 0, 0, 0, inf), 0, inf);
    dop("14-DOP of a cube: the last slab (x-y-z) misses", hint_slabs, cube, 8, 6, -1, 1,
        ex_ray(-5, -0.9f, -0.9f, 1, 0, 0, 0, inf), 0, inf);
    /* random volumes and rays */
    uint32_t st = 1515u;
    for (int i = 0; i < 24; ++i) {
        const float ox = ex_rand(&st) * 8 - 4, oy = ex_rand(&st) * 8 - 4, oz = ex_rand(&st) * 8 - 4;
        const float dx = -ox + ex_rand(&st) * 2 - 1, dy = -oy + ex_rand(&st) * 2 - 1, dz = -oz + ex_rand(&st) * 2 - 1;
        const float tmax = (i % 4 == 3) ? 0.75f : inf;
        const sidx_ray ray = ex_ray(ox, oy, oz, dx, dy, dz + 0.01f, 0, tmax);
        if (i % 3 == 0) {
            sph("sphere: random", hint_sphere, V(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f),
                0.5f + ex_rand(&st) * 1.5f, ray, 0, tmax);
        } else if (i % 3 == 1) {
            obb("OBB: random", hint_obb, V(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, 0), ex_rand(&st) * 3.0f,
                V(0.5f + ex_rand(&st), 0.5f + ex_rand(&st), 0.5f + ex_rand(&st)), ray, 0, tmax);
        } else {
            sidx_vec3 p[5];
            for (int j = 0; j < 5; ++j) p[j] = V(ex_rand(&st) * 3 - 1.5f, ex_rand(&st) * 3 - 1.5f, ex_rand(&st) * 3 - 1.5f);
            dop("14-DOP: random", hint_slabs, p, 5, -1, 0, 0, ray, 0, tmax);
        }
    }
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
    out->hint = c->hint;
}

static const char *const kind_name[] = {"sphere", "obb", "kdop"};

static void emit(const sidx_hook *h, size_t i, int hit, float tn, float tf)
{
    sidx_ex ex;
    memset(&ex, 0, sizeof ex);
    ex.hook = h;
    ex.structure = kind_name[cases[i].kind];
    sidx_aabb none = sidx_aabb_empty();
    sidx_ex_box_test(&ex, (uint32_t)i, &none, hit, tn, tf);
}

static void reference(size_t i, const sidx_hook *h)
{
    const bv_case *c = &cases[i];
    float tn = NAN, tf = NAN;
    int hit;
    if (c->kind == V_SPHERE) hit = sidx_intersect_sphere(&c->ray, &c->s, c->tmin, c->tmax, &tn, &tf);
    else if (c->kind == V_OBB) hit = sidx_intersect_obb(&c->ray, &c->b, c->tmin, c->tmax, &tn, &tf);
    else hit = sidx_intersect_kdop(&c->ray, &c->k, c->tmin, c->tmax, &tn, &tf);
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

/* The hint by what differs: the hit flag (the case's own hint: tangent,
 * parallel, clip, touch), or with both hitting the interval (t_near and
 * t_far are the entry and exit of the volume's own test). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const bv_case *c = &cases[i];
    if (!ref || !stu || ref->type != SIDX_EV_BOX_TEST || stu->type != SIDX_EV_BOX_TEST) return NULL;
    if (ref->result != stu->result) return NULL;
    if (c->hint == hint_clip || c->hint == hint_touch || c->hint == hint_tangent || c->hint == hint_sphere_a ||
        c->hint == hint_swap)
        return NULL;
    return c->kind == V_SPHERE ? hint_sphere : c->kind == V_OBB ? hint_obb : hint_slabs;
}

const ex_driver ex_driver_this = {
    "15_sphere_obb_dop",
    "the sphere, OBB and 14-DOP ray tests: tangent rays, parallel slabs, flat volumes",
    "deck 000, \"Bounding Volumes\" (sphere, OBB, slabs)",
    setup, num_cases, describe, reference, student, hint, NULL, NULL, NULL, 0,
};
