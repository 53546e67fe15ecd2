/* 03_ray_box.c — checker driver: the ray–AABB slab test (deck 000,
 * "Bounding Volumes": "Very simple intersection computation (min-max)";
 * deck 001, "Bounding Box").  Reference: the library's textbook slab test,
 * sidx_intersect_aabb(SIDX_BOX_PLAIN, ...). */
#include <string.h>
#include "check.h"

int ray_box(const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far);

typedef struct box_case {
    const char *name, *hint, *rules;
    sidx_aabb box;
    sidx_ray ray;
    float tmin, tmax;
} box_case;

#define BOX_RANDOM 40
#define BOX_FIXED 23
static box_case cases[BOX_FIXED + BOX_RANDOM];

#define HINT_SLAB                                                                                          \
    "per axis the slab gives t = (min - o)·(1/d) and (max - o)·(1/d); t_near is the largest entry, t_far the " \
    "smallest exit, and the box is hit when t_near <= t_far"
#define HINT_ZERO                                                                                          \
    "a ±0 direction component: 1/d is ±inf, so (plane - o)·(1/d) is ±inf and the slab either holds the "   \
    "origin (no restriction) or not (miss); use the ray's inv_dir, keep -0 negative"
#define HINT_ON_PLANE                                                                                      \
    "origin exactly on a slab plane with d = 0 on that axis: (plane - o)·(1/d) = 0·inf = NaN; the ray lies " \
    "on the box's face and counts as inside, so a NaN must never replace t_near or t_far"
#define HINT_INSIDE "a ray starting inside the box enters it at tmin: clip [t_near, t_far] to [tmin, tmax]"
#define HINT_CLIP_TMIN                                                                                     \
    "clip to [tmin, tmax] from below: start t_near at tmin, so a ray starting inside the box enters it at "  \
    "tmin and a box behind the origin (every exit < tmin) is a miss"
#define HINT_CLIP_TMAX                                                                                     \
    "clip to [tmin, tmax] from above: start t_far at tmax, so a box beyond tmax is a miss, a box reaching "  \
    "past tmax is left at tmax, and an infinite tmax stays infinite only until a slab's exit cuts it"
#define HINT_CLIP_ARGS                                                                                     \
    "clip to the tmin and tmax you are given (the arguments: the caller's interval, e.g. [tmin, best.t]), "  \
    "not to the ray's own r->tmin, r->tmax"
#define HINT_TOUCH                                                                                         \
    "the box is hit when t_near <= t_far, the bound included: a ray through a flat box, along an edge or "  \
    "leaving through a face at tmin has t_near == t_far, a hit of one point"
#define HINT_NEG                                                                                           \
    "near and far planes swap for a negative direction component: with d < 0 the ray enters at max and "   \
    "leaves at min"
#define HINT_UNTOUCHED                                                                                     \
    "write *t_near and *t_far only when you return 1: on a miss they keep what the caller had there; "      \
    "decide first, then write"

/* The hand-out's promises (lessons/exercises/03_ray_box.c). */
static const ex_rule rules[] = {
    {"slab", "t_near is the largest entry, t_far the smallest exit of the three slabs", HINT_SLAB},
    {"negative-dir", "a negative direction component enters a slab at max and leaves at min", HINT_NEG},
    {"zero-dir",
     "a ±0 direction component (inv_dir ±inf, r->sign 1 for -0) either keeps the slab (origin inside it) or "
     "misses",
     HINT_ZERO},
    {"on-face", "a ray lying exactly in a face plane of the box counts as inside", HINT_ON_PLANE},
    {"clip-tmin", "the interval is clipped to tmin: a ray starting inside enters at tmin, a box behind is a miss",
     HINT_CLIP_TMIN},
    {"clip-tmax", "the interval is clipped to tmax (an infinite tmax included): a box beyond tmax is a miss",
     HINT_CLIP_TMAX},
    {"clip-arguments", "the clip is to the arguments tmin and tmax, not to the ray's own interval",
     HINT_CLIP_ARGS},
    {"touch", "t_near <= t_far is a hit, equality included (a flat box, an edge, a face at tmin)", HINT_TOUCH},
    {"untouched-on-miss", "the outputs t_near and t_far are written only on a hit; a miss returns 0 and leaves them",
     HINT_UNTOUCHED},
};
enum { R_SLAB, R_NEG, R_ZERO, R_ON_FACE, R_TMIN, R_TMAX, R_ARGS, R_TOUCH, R_UNTOUCHED };

static const char *const hint_slab = HINT_SLAB;
static const char *const hint_zero = HINT_ZERO;
static const char *const hint_on_plane = HINT_ON_PLANE;
static const char *const hint_inside = HINT_INSIDE;
static const char *const hint_clip_tmin = HINT_CLIP_TMIN;
static const char *const hint_clip_tmax = HINT_CLIP_TMAX;
static const char *const hint_clip_args = HINT_CLIP_ARGS;
static const char *const hint_touch = HINT_TOUCH;
static const char *const hint_neg = HINT_NEG;

static sidx_aabb B(float x0, float y0, float z0, float x1, float y1, float z1)
{
    sidx_aabb b = {{x0, y0, z0}, {x1, y1, z1}};
    return b;
}

static int setup(void)
{
    int k = 0;
#define BC(nm, h, rl, box_, ray_, tmin_, tmax_)                                                             \
    cases[k].name = nm;                                                                                    \
    cases[k].hint = h;                                                                                     \
    cases[k].rules = rl;                                                                                   \
    cases[k].box = box_;                                                                                   \
    cases[k].ray = ray_;                                                                                   \
    cases[k].tmin = tmin_;                                                                                 \
    cases[k].tmax = tmax_;                                                                                 \
    ++k
    const sidx_aabb U = B(-1, -1, -1, 1, 1, 1);
    BC("head-on along +x", hint_slab, "slab",
       U, ex_ray(-5, 0.25f, 0.125f, 1, 0.0625f, 0.03125f, 0, INFINITY), 0, INFINITY);
    BC("oblique, all components non-zero", hint_slab, "slab", U, ex_ray(-3, -2, -4, 1, 0.75f, 1.25f, 0, INFINITY), 0,
       INFINITY);
    BC("negative direction on every axis", hint_neg, "negative-dir",
       U, ex_ray(4, 3, 5, -1, -0.75f, -1.25f, 0, INFINITY), 0,
       INFINITY);
    BC("miss: passes beside the box", hint_slab, "slab untouched-on-miss",
       U, ex_ray(-5, 3, 0, 1, 0.125f, 0, 0, INFINITY), 0, INFINITY);
    BC("+0 direction component, origin inside that slab", hint_zero, "zero-dir",
       U, ex_ray(-5, 0.5f, 0, 1, 0, 0, 0, INFINITY),
       0, INFINITY);
    BC("+0 direction component, origin outside that slab", hint_zero, "zero-dir untouched-on-miss",
       U, ex_ray(-5, 2, 0, 1, 0, 0, 0, INFINITY),
       0, INFINITY);
    BC("-0 direction component, origin inside that slab", hint_zero, "zero-dir negative-dir", U,
       ex_ray(5, 0.5f, 0.25f, -1, -0.0f, 0.0f, 0, INFINITY), 0, INFINITY);
    BC("-0 direction component, origin outside that slab", hint_zero, "zero-dir untouched-on-miss", U,
       ex_ray(5, -3, 0.25f, -1, -0.0f, -0.0f, 0, INFINITY), 0, INFINITY);
    BC("two zero components: a ray along the z axis", hint_zero, "zero-dir",
       U, ex_ray(0.5f, -0.5f, 9, 0, 0, -1, 0, INFINITY),
       0, INFINITY);
    BC("ray on a face plane of the box (d = 0 on that axis)", hint_on_plane, "on-face", U,
       ex_ray(-5, 1, 0.5f, 1, 0, 0, 0, INFINITY), 0, INFINITY);
    BC("ray on the min face plane, +0 on that axis (NaN at the near plane)", hint_on_plane, "on-face", U,
       ex_ray(-5, -1, 0.5f, 1, 0, 0, 0, INFINITY), 0, INFINITY);
    BC("ray on the max face plane, -0 on that axis (NaN at the near plane)", hint_on_plane, "on-face", U,
       ex_ray(-5, 1, 0.5f, 1, -0.0f, 0, 0, INFINITY), 0, INFINITY);
    BC("origin inside the box", hint_inside, "clip-tmin",
       U, ex_ray(0.25f, 0.5f, -0.5f, 1, -1, 0.5f, 0, INFINITY), 0, INFINITY);
    BC("origin inside, tmin > 0", hint_inside, "clip-tmin",
       U, ex_ray(0, 0, 0, 0.5f, 0.25f, 1, 0.5f, INFINITY), 0.5f, INFINITY);
    BC("box behind the origin", hint_clip_tmin, "clip-tmin untouched-on-miss",
       U, ex_ray(5, 0, 0, 1, 0, 0, 0, INFINITY), 0, INFINITY);
    BC("box beyond tmax", hint_clip_tmax, "clip-tmax untouched-on-miss",
       U, ex_ray(-5, 0, 0, 1, 0, 0, 0, 3.0f), 0, 3.0f);
    BC("tmax inside the box", hint_clip_tmax, "clip-tmax", U, ex_ray(-5, 0, 0, 1, 0, 0, 0, 5.0f), 0, 5.0f);
    BC("flat box (zero thickness in z)", hint_slab, "slab touch",
       B(-1, -1, 0, 1, 1, 0), ex_ray(0.5f, 0.5f, 3, 0, 0.25f, -1, 0,
       INFINITY), 0, INFINITY);
    BC("flat box crossed head-on (t_near == t_far)", hint_touch, "touch", B(-1, -1, 0, 1, 1, 0),
       ex_ray(0.5f, 0.5f, 3, 0, 0, -1, 0, INFINITY), 0, INFINITY);
    BC("touching an edge of the box (t_near == t_far)", hint_touch, "touch",
       U, ex_ray(-2, 0, 0.5f, 1, 1, 0, 0, INFINITY), 0,
       INFINITY);
    BC("origin on the exit face, leaving (t_near == t_far == tmin)", hint_touch, "touch clip-tmin", U,
       ex_ray(1, 0.25f, 0.5f, 1, 0.5f, 0.25f, 0, INFINITY), 0, INFINITY);
    /* the interval to clip to is the caller's, narrower than the ray's */
    BC("clipped to [4.5, 5.5], narrower than the ray's [0, inf)", hint_clip_args, "clip-arguments clip-tmin clip-tmax",
       U, ex_ray(-5, 0.25f, 0.5f, 1, 0, 0, 0, INFINITY), 4.5f, 5.5f);
    BC("box beyond the given tmax = 3, the ray's tmax infinite", hint_clip_args, "clip-arguments clip-tmax", U,
       ex_ray(-5, 0, 0, 1, 0, 0, 0, INFINITY), 0, 3.0f);
    uint32_t s = 4242u;
    for (int i = 0; i < BOX_RANDOM; ++i) {
        float lo[3], hi[3];
        for (int j = 0; j < 3; ++j) {
            const float a = ex_rand(&s) * 4 - 2, b = ex_rand(&s) * 4 - 2;
            lo[j] = a < b ? a : b;
            hi[j] = a < b ? b : a;
        }
        const float dx = ex_rand(&s) * 2 - 1, dy = ex_rand(&s) * 2 - 1, dz = ex_rand(&s) * 2 - 1;
        BC("random box and ray", hint_slab, NULL, B(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]),
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
    out->rules = c->rules;
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

/* The caller's values of *t_near, *t_far: a miss must leave them (the
 * reference does). */
#define T_BEFORE 1234.5f

/* An output written on a miss: a NOTE with cell[0] = 7 and the value in
 * t_near (the reference's trace has no such step). */
static void emit_written(const sidx_hook *h, float value)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "box";
    e.cell[0] = 7;
    e.t_near = value;
    sidx_hook_emit(h, &e);
}

static int same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

static void student(size_t i, const sidx_hook *h)
{
    const box_case *c = &cases[i];
    float tn = T_BEFORE, tf = T_BEFORE;
    const int hit = ray_box(&c->ray, &c->box, c->tmin, c->tmax, &tn, &tf);
    emit(h, i, hit, tn, tf);
    if (!hit && !(same_bits(tn, T_BEFORE) && same_bits(tf, T_BEFORE)))
        emit_written(h, same_bits(tn, T_BEFORE) ? tf : tn);
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE || e->cell[0] != 7) return 0;
    snprintf(buf, size, "returned 0 (a miss) but wrote an output: %g", (double)e->t_near);
    return 1;
}

/* What differs decides: an output written on a miss is the untouched
 * rule; on a ray lying in a face plane any other result is the NaN
 * rule; an interval that reaches below the tmin or above the tmax given
 * is the clip (the ray's own bound there: the arguments); a miss where
 * the reference hits one point (t_near == t_far) is the touch rule; the
 * rest is the case's own rule. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const box_case *c = &cases[i];
    if (stu && stu->type == SIDX_EV_NOTE && stu->cell[0] == 7) return rules[R_UNTOUCHED].hint;
    if (!ref || !stu || ref->type != SIDX_EV_BOX_TEST || stu->type != SIDX_EV_BOX_TEST) return NULL;
    /* a ray in a face plane: whatever went wrong, a NaN took a bound */
    if (c->rules && strstr(c->rules, "on-face")) return rules[R_ON_FACE].hint;
    if (stu->result == 1) {
        /* on a case whose interval differs from the ray's, a wrong clip is the arguments' */
        const int args = c->tmin != c->ray.tmin || c->tmax != c->ray.tmax;
        if (stu->t_near < c->tmin || stu->t_far < c->tmin ||
            (ref->result == 1 && ref->t_near == c->tmin && stu->t_near != c->tmin))
            return args ? rules[R_ARGS].hint : rules[R_TMIN].hint;
        if (stu->t_far > c->tmax || stu->t_near > c->tmax ||
            (ref->result == 1 && ref->t_far == c->tmax && stu->t_far != c->tmax))
            return args ? rules[R_ARGS].hint : rules[R_TMAX].hint;
    }
    if (ref->result == 1 && stu->result == 0 && ref->t_near == ref->t_far) return rules[R_TOUCH].hint;
    return NULL;
}

const ex_driver ex_driver_this = {
    "03_ray_box",
    "the ray-AABB slab test: ±0 direction components, rays starting inside, infinite t",
    "deck 000, \"Bounding Volumes\" (AABB: \"min-max\"); deck 001, \"Bounding Box\"",
    setup, num_cases, describe, reference, student, hint, NULL, format, rules, sizeof rules / sizeof rules[0],
};
