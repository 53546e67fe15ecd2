/* 03_ray_box.c — checker driver: the ray–AABB slab test (deck 000,
 * "Bounding Volumes": "Very simple intersection computation (min-max)";
 * deck 001, "Bounding Box").  Reference: the library's textbook slab test,
 * sidx_intersect_aabb(SIDX_BOX_PLAIN, ...). */
#include <string.h>
#include "check.h"

int ray_box(const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far);

typedef struct box_case {
    const char *name, *hint;
    sidx_aabb box;
    sidx_ray ray;
    float tmin, tmax;
} box_case;

#define BOX_RANDOM 40
#define BOX_FIXED 21
static box_case cases[BOX_FIXED + BOX_RANDOM];

static const char *const hint_slab =
    "per axis the slab gives t = (min - o)·(1/d) and (max - o)·(1/d); t_near is the largest entry, t_far the "
    "smallest exit, and the box is hit when t_near <= t_far";
static const char *const hint_zero =
    "a ±0 direction component: 1/d is ±inf, so (plane - o)·(1/d) is ±inf and the slab either holds the origin "
    "(no restriction) or not (miss); use the ray's inv_dir, keep -0 negative";
static const char *const hint_on_plane =
    "origin exactly on a slab plane with d = 0 on that axis: (plane - o)·(1/d) = 0·inf = NaN; the ray lies on "
    "the box's face and counts as inside, so a NaN must never replace t_near or t_far";
static const char *const hint_inside =
    "a ray starting inside the box enters it at tmin: clip [t_near, t_far] to [tmin, tmax]";
static const char *const hint_clip =
    "clip to [tmin, tmax]: a box behind the origin or beyond tmax is a miss, and an infinite tmax stays infinite "
    "only until a slab's exit cuts it";
static const char *const hint_touch =
    "the box is hit when t_near <= t_far, the bound included: a ray through a flat box, along an edge or leaving "
    "through a face at tmin has t_near == t_far, a hit of one point";
static const char *const hint_neg =
    "near and far planes swap for a negative direction component: with d < 0 the ray enters at max and leaves at min";

static sidx_aabb B(float x0, float y0, float z0, float x1, float y1, float z1)
{
    sidx_aabb b = {{x0, y0, z0}, {x1, y1, z1}};
    return b;
}

static int setup(void)
{
    int k = 0;
#define BC(nm, h, box_, ray_, tmin_, tmax_)                                                                 \
    cases[k].name = nm;                                                                                    \
    cases[k].hint = h;                                                                                     \
    cases[k].box = box_;                                                                                   \
    cases[k].ray = ray_;                                                                                   \
    cases[k].tmin = tmin_;                                                                                 \
    cases[k].tmax = tmax_;                                                                                 \
    ++k
    const sidx_aabb U = B(-1, -1, -1, 1, 1, 1);
    BC("head-on along +x", hint_slab, U, ex_ray(-5, 0.25f, 0.125f, 1, 0.0625f, 0.03125f, 0, INFINITY), 0, INFINITY);
    BC("oblique, all components non-zero", hint_slab, U, ex_ray(-3, -2, -4, 1, 0.75f, 1.25f, 0, INFINITY), 0,
       INFINITY);
    BC("negative direction on every axis", hint_neg, U, ex_ray(4, 3, 5, -1, -0.75f, -1.25f, 0, INFINITY), 0,
       INFINITY);
    BC("miss: passes beside the box", hint_slab, U, ex_ray(-5, 3, 0, 1, 0.125f, 0, 0, INFINITY), 0, INFINITY);
    BC("+0 direction component, origin inside that slab", hint_zero, U, ex_ray(-5, 0.5f, 0, 1, 0, 0, 0, INFINITY),
       0, INFINITY);
    BC("+0 direction component, origin outside that slab", hint_zero, U, ex_ray(-5, 2, 0, 1, 0, 0, 0, INFINITY),
       0, INFINITY);
    BC("-0 direction component, origin inside that slab", hint_zero, U,
       ex_ray(5, 0.5f, 0.25f, -1, -0.0f, 0.0f, 0, INFINITY), 0, INFINITY);
    BC("-0 direction component, origin outside that slab", hint_zero, U,
       ex_ray(5, -3, 0.25f, -1, -0.0f, -0.0f, 0, INFINITY), 0, INFINITY);
    BC("two zero components: a ray along the z axis", hint_zero, U, ex_ray(0.5f, -0.5f, 9, 0, 0, -1, 0, INFINITY),
       0, INFINITY);
    BC("ray on a face plane of the box (d = 0 on that axis)", hint_on_plane, U,
       ex_ray(-5, 1, 0.5f, 1, 0, 0, 0, INFINITY), 0, INFINITY);
    BC("ray on the min face plane, +0 on that axis (NaN at the near plane)", hint_on_plane, U,
       ex_ray(-5, -1, 0.5f, 1, 0, 0, 0, INFINITY), 0, INFINITY);
    BC("ray on the max face plane, -0 on that axis (NaN at the near plane)", hint_on_plane, U,
       ex_ray(-5, 1, 0.5f, 1, -0.0f, 0, 0, INFINITY), 0, INFINITY);
    BC("origin inside the box", hint_inside, U, ex_ray(0.25f, 0.5f, -0.5f, 1, -1, 0.5f, 0, INFINITY), 0, INFINITY);
    BC("origin inside, tmin > 0", hint_inside, U, ex_ray(0, 0, 0, 0.5f, 0.25f, 1, 0.5f, INFINITY), 0.5f, INFINITY);
    BC("box behind the origin", hint_clip, U, ex_ray(5, 0, 0, 1, 0, 0, 0, INFINITY), 0, INFINITY);
    BC("box beyond tmax", hint_clip, U, ex_ray(-5, 0, 0, 1, 0, 0, 0, 3.0f), 0, 3.0f);
    BC("tmax inside the box", hint_clip, U, ex_ray(-5, 0, 0, 1, 0, 0, 0, 5.0f), 0, 5.0f);
    BC("flat box (zero thickness in z)", hint_slab, B(-1, -1, 0, 1, 1, 0), ex_ray(0.5f, 0.5f, 3, 0, 0.25f, -1, 0,
       INFINITY), 0, INFINITY);
    BC("flat box crossed head-on (t_near == t_far)", hint_touch, B(-1, -1, 0, 1, 1, 0),
       ex_ray(0.5f, 0.5f, 3, 0, 0, -1, 0, INFINITY), 0, INFINITY);
    BC("touching an edge of the box (t_near == t_far)", hint_touch, U, ex_ray(-2, 0, 0.5f, 1, 1, 0, 0, INFINITY), 0,
       INFINITY);
    BC("origin on the exit face, leaving (t_near == t_far == tmin)", hint_touch, U,
       ex_ray(1, 0.25f, 0.5f, 1, 0.5f, 0.25f, 0, INFINITY), 0, INFINITY);
    uint32_t s = 4242u;
    for (int i = 0; i < BOX_RANDOM; ++i) {
        float lo[3], hi[3];
        for (int j = 0; j < 3; ++j) {
            const float a = ex_rand(&s) * 4 - 2, b = ex_rand(&s) * 4 - 2;
            lo[j] = a < b ? a : b;
            hi[j] = a < b ? b : a;
        }
        const float dx = ex_rand(&s) * 2 - 1, dy = ex_rand(&s) * 2 - 1, dz = ex_rand(&s) * 2 - 1;
        BC("random box and ray", hint_slab, B(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]),
           ex_ray(ex_rand(&s) * 8 - 4, ex_rand(&s) * 8 - 4, ex_rand(&s) * 8 - 4, dx, dy, dz + 0.01f, 0, INFINITY),
           0, (i % 4 == 3) ? 2.5f : INFINITY);
    }
#undef BC
    return 0;
}

static size_t num_cases(void) { return BOX_FIXED + BOX_RANDOM; }

static void describe(size_t i, ex_case_info *out)
{
    const box_case *c = &cases[i];
    char ray[160];
    ex_format_ray(ray, sizeof ray, &c->ray);
    snprintf(out->name, sizeof out->name, "%s", c->name);
    snprintf(out->what, sizeof out->what, "%s; box [(%g, %g, %g), (%g, %g, %g)], clipped to [%g, %g]", ray,
             (double)c->box.min.x, (double)c->box.min.y, (double)c->box.min.z, (double)c->box.max.x,
             (double)c->box.max.y, (double)c->box.max.z, (double)c->tmin, (double)c->tmax);
    out->hint = c->hint;
}

static void emit(const sidx_hook *h, size_t i, int hit, float tn, float tf)
{
    sidx_ex ex;
    memset(&ex, 0, sizeof ex);
    ex.hook = h;
    ex.structure = "box";
    sidx_ex_box_test(&ex, (uint32_t)i, &cases[i].box, hit, tn, tf);
}

static void reference(size_t i, const sidx_hook *h)
{
    const box_case *c = &cases[i];
    float tn = NAN, tf = NAN;
    const int hit = sidx_intersect_aabb(SIDX_BOX_PLAIN, &c->ray, &c->box, c->tmin, c->tmax, &tn, &tf);
    emit(h, i, hit, tn, tf);
}

static void student(size_t i, const sidx_hook *h)
{
    const box_case *c = &cases[i];
    float tn = NAN, tf = NAN;
    const int hit = ray_box(&c->ray, &c->box, c->tmin, c->tmax, &tn, &tf);
    emit(h, i, hit, tn, tf);
}

const ex_driver ex_driver_this = {
    "03_ray_box",
    "the ray-AABB slab test: ±0 direction components, rays starting inside, infinite t",
    "deck 000, \"Bounding Volumes\" (AABB: \"min-max\"); deck 001, \"Bounding Box\"",
    setup, num_cases, describe, reference, student, NULL, NULL, NULL, NULL, 0,
};
