/* 01_ray_triangle.c — checker driver: ray–plane, then the two-step
 * ray–triangle test (deck 001, "Ray-Plane Intersection" and
 * "Ray-Triangle Intersection").  Reference: the library's
 * sidx_intersect_plane and sidx_intersect_triangle_two_step. */
#include "tri_cases.h"

int ray_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t);
int ray_triangle_two_step(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t);

typedef struct plane_case {
    const char *name, *hint, *rules;
    sidx_vec3 n;
    float c;
    sidx_ray ray;
} plane_case;

#define PLANE_RANDOM 20
#define PLANE_FIXED 12
static plane_case planes[PLANE_FIXED + PLANE_RANDOM];

#define HINT_PLANE_T                                                                                       \
    "the same plane hit at another t: plug the ray o + t·d into N·x = c, N·o + t·(N·d) = c, so t = (c - N·o) / " \
    "(N·d) with the ray's own d (not normalised) and N as given (not normalised either)"
#define HINT_TRI_T                                                                                         \
    "the same triangle hit at another t: step i) is the ray-plane test, the plane through the triangle is "  \
    "N = e1 x e2, c = N·p0, and t = (c - N·o) / (N·d) with the ray's own d; t is the plane's, step ii) only " \
    "decides hit or miss"
#define HINT_PARALLEL                                                                                      \
    "N·d = 0: the ray is parallel to the plane (or lies in it), there is no unique t: a miss; test N·d == 0 " \
    "before you divide (c - N·o)/0 is ±inf, or NaN when the ray lies in the plane, and a NaN fails every "   \
    "comparison, so `t < tmin || t >= tmax` lets it through"
#define HINT_BOTH_SIDES                                                                                    \
    "the ray may meet the plane or the triangle from either side: N·d > 0 (from the back) is a hit as well; " \
    "only N·d = 0 is special"

/* The hand-out's promises (lessons/exercises/01_ray_triangle.c). */
static const ex_rule rules[] = {
    {"t-formula", "t = (c - N·o) / (N·d), with the ray's own d and N as given", HINT_PLANE_T},
    {"tri-plane",
     "the triangle's t is that of its plane, N = (p1 - p0) x (p2 - p0), c = N·p0; step ii) only decides hit or "
     "miss",
     HINT_TRI_T},
    {"parallel-miss", "N·d = 0 (parallel to the plane, or lying in it) is a miss", HINT_PARALLEL},
    {"both-sides", "a ray meeting the plane or the triangle from its back (N·d > 0) hits it too",
     HINT_BOTH_SIDES},
    {"behind-miss", "a negative t (behind the origin) is a miss", TRI_HINT_BEHIND},
    {"tmin", "the lower bound is r->tmin, which may be > 0: t < tmin is a miss", TRI_HINT_TMIN},
    {"tmin-inclusive", "t = tmin is a hit: the range [tmin, tmax) includes tmin", TRI_HINT_TMIN_INCL},
    {"tmax-exclusive",
     "t >= tmax is a miss: the range [tmin, tmax) excludes tmax, which is r->tmax for the plane and the "
     "argument tmax for the triangle",
     TRI_HINT_TMAX},
    {"edges-count", "p on the triangle's boundary (an edge, a vertex) is inside", TRI_HINT_INSIDE},
    {"outside-miss", "p outside the triangle is a miss, even though the ray hits its plane", TRI_HINT_OUTSIDE},
    {"untouched-on-miss", "the output t is written only on a hit (return 1); a miss returns 0 and leaves it as it was",
     TRI_HINT_UNTOUCHED},
};
enum { R_T, R_TRI_PLANE, R_PARALLEL, R_BOTH, R_BEHIND, R_TMIN, R_TMIN_INCL, R_TMAX, R_EDGES, R_OUTSIDE, R_UNTOUCHED };

static const char *const hint_plane = "t = (c - N·o) / (N·d): plug the ray o + t·d into N·x = c and solve for t";
static const char *const hint_plane_parallel = HINT_PARALLEL;
static const char *const hint_plane_range = "a hit counts only for t in [tmin, tmax): What if t is negative? "
                                            "The intersection is behind the origin";

static int setup(void)
{
    int k = 0;
#define PC(nm, h, rl, nx, ny, nz, c_, ray_)                                                                 \
    planes[k].name = nm;                                                                                   \
    planes[k].hint = h;                                                                                    \
    planes[k].rules = rl;                                                                                  \
    planes[k].n = sidx_v3(nx, ny, nz);                                                                     \
    planes[k].c = c_;                                                                                      \
    planes[k].ray = ray_;                                                                                  \
    ++k
    PC("plane: head-on", hint_plane, "t-formula", 0, 0, 1, 0, ex_ray(0, 0, 5, 0, 0, -1, 0, INFINITY));
    PC("plane: oblique ray, tilted plane", hint_plane, "t-formula", 1, 1, 1, 1,
       ex_ray(1, 2, 3, 0.5f, -1, -2, 0, INFINITY));
    PC("plane: normal not of unit length", hint_plane, "t-formula", 0, 0, 2, 4, ex_ray(0, 0, 6, 0, 0, -2, 0, INFINITY));
    PC("plane: from the back side (N·d > 0)", rules[R_BOTH].hint, "both-sides", 0, 0, 1, 0,
       ex_ray(0, 0, -3, 0, 0, 1, 0, INFINITY));
    PC("plane: parallel above it (N·d = 0)", hint_plane_parallel, "parallel-miss", 0, 0, 1, 0,
       ex_ray(0, 0, 1, 1, 0, 0, 0, INFINITY));
    PC("plane: ray lying in it (N·d = 0)", hint_plane_parallel, "parallel-miss", 0, 0, 1, 0,
       ex_ray(0, 0, 0, 1, 1, 0, 0, INFINITY));
    PC("plane: behind the origin (t < 0)", hint_plane_range, "behind-miss untouched-on-miss", 0, 0, 1, 0,
       ex_ray(0, 0, 5, 0, 0, 1, 0, INFINITY));
    PC("plane: beyond tmax", hint_plane_range, "tmax-exclusive untouched-on-miss", 0, 0, 1, 0,
       ex_ray(0, 0, 5, 0, 0, -1, 0, 5.0f));
    PC("plane: ray starting on it (t = 0)", TRI_HINT_TMIN_INCL, "tmin-inclusive", 0, 0, 1, 2,
       ex_ray(3, 1, 2, 0, 1, -1, 0, INFINITY));
    /* tmin > 0 (a secondary ray, a segment): the bound is the ray's, not 0 */
    PC("plane: tmin > 0, the hit lies before tmin (0 < t < tmin)", TRI_HINT_TMIN, "tmin untouched-on-miss", 0, 0,
       1, 0, ex_ray(0, 0, 5, 0, 0, -1, 6.0f, INFINITY));
    PC("plane: tmin > 0, the hit exactly at tmin", TRI_HINT_TMIN_INCL, "tmin tmin-inclusive", 0, 0, 1, 0,
       ex_ray(0, 0, 5, 0, 0, -1, 5.0f, INFINITY));
    PC("plane: tmin > 0, the hit beyond it", hint_plane, "tmin t-formula", 0, 0, 1, 0,
       ex_ray(0, 0, 5, 0, 0, -1, 2.0f, 8.0f));
    uint32_t s = 777u;
    for (int i = 0; i < PLANE_RANDOM; ++i) {
        const float nx = ex_rand(&s) * 2 - 1, ny = ex_rand(&s) * 2 - 1, nz = ex_rand(&s) * 2 - 1;
        PC("plane: random", hint_plane, NULL, nx, ny, nz, ex_rand(&s) * 4 - 2,
           ex_ray(ex_rand(&s) * 10 - 5, ex_rand(&s) * 10 - 5, ex_rand(&s) * 10 - 5, ex_rand(&s) * 2 - 1,
                  ex_rand(&s) * 2 - 1, ex_rand(&s) * 2 - 1 + 0.01f, 0, ex_rand(&s) < 0.3f ? 3.0f : INFINITY));
    }
#undef PC
    tri_fill();
    return 0;
}

#define NP (PLANE_FIXED + PLANE_RANDOM)
static size_t num_cases(void) { return NP + TRI_FIXED + TRI_RANDOM; }

static void describe(size_t i, ex_case_info *out)
{
    if (i >= NP) {
        tri_describe(&tri_cases[i - NP], out);
        snprintf(out->name, sizeof out->name, "two-step triangle: %s", tri_cases[i - NP].name);
        /* the two-step test has no D: its parallel case is N·d = 0 */
        if (out->hint == hint_parallel) out->hint = hint_plane_parallel;
        if (out->hint == hint_backface) out->hint = rules[R_BOTH].hint;
        if (out->rules && !strcmp(out->rules, "t-formula")) out->rules = "tri-plane";
        return;
    }
    const plane_case *p = &planes[i];
    char ray[160];
    ex_format_ray(ray, sizeof ray, &p->ray);
    snprintf(out->name, sizeof out->name, "%s", p->name);
    snprintf(out->what, sizeof out->what, "%s; plane N=(%g, %g, %g) c=%g", ray, (double)p->n.x, (double)p->n.y,
             (double)p->n.z, (double)p->c);
    out->hint = p->hint;
    out->rules = p->rules;
}

static void reference(size_t i, const sidx_hook *h)
{
    float t = INFINITY;
    int hit;
    if (i < NP) {
        hit = sidx_intersect_plane(&planes[i].ray, planes[i].n, planes[i].c, &t);
    } else {
        const tri_case *c = &tri_cases[i - NP];
        hit = sidx_intersect_triangle_two_step(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t, NULL, NULL);
    }
    tri_emit(h, i, hit, t);
}

/* The caller's value of *t: a miss must leave it (the reference does). */
#define T_BEFORE 1234.5f

static void student(size_t i, const sidx_hook *h)
{
    float t = T_BEFORE;
    int hit;
    if (i < NP) {
        hit = ray_plane(&planes[i].ray, planes[i].n, planes[i].c, &t);
    } else {
        const tri_case *c = &tri_cases[i - NP];
        hit = ray_triangle_two_step(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t);
    }
    tri_emit(h, i, hit, t);
    if (!hit && !tri_same_bits(t, T_BEFORE)) tri_emit_written(h, t);
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE || e->cell[0] != TRI_WRITTEN) return 0;
    snprintf(buf, size, "returned 0 (a miss) but wrote *t = %g", (double)e->t_near);
    return 1;
}

static const char *const hint_plane_t = HINT_PLANE_T;

/* What differs decides: another t is the formula for t; an output
 * written on a miss is the untouched rule; a hit where the reference
 * misses is named by its t (NaN or inf: N·d = 0; below 0: behind the
 * origin; in [0, tmin): the ray's tmin; at or beyond tmax: tmax) or, with
 * t in range, by the test that should have refused it (N·d > 0 is no
 * refusal, the point outside the triangle is); a miss where the reference
 * hits, by where the reference's t lies (at tmin: the inclusive bound),
 * the case's side (N·d > 0) or the boundary of the triangle. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if (stu && stu->type == SIDX_EV_NOTE && stu->cell[0] == TRI_WRITTEN) return rules[R_UNTOUCHED].hint;
    if (!ref || !stu || ref->type != SIDX_EV_PRIM_TEST || stu->type != SIDX_EV_PRIM_TEST) return NULL;
    const int plane = i < NP;
    const sidx_ray *r = plane ? &planes[i].ray : &tri_cases[i - NP].ray;
    const float tmax = plane ? r->tmax : tri_cases[i - NP].tmax;
    if (ref->result == 1 && stu->result == 1) return plane ? hint_plane_t : rules[R_TRI_PLANE].hint;
    if (ref->result == 0 && stu->result == 1) {
        const char *h = tri_range_hint(stu->t, r->tmin, tmax, rules[R_PARALLEL].hint);
        if (h) return h;
        return plane ? NULL : rules[R_OUTSIDE].hint;
    }
    if (ref->result == 1 && stu->result == 0) {
        if (ref->t == r->tmin) return rules[R_TMIN_INCL].hint;
        const sidx_vec3 n = plane ? planes[i].n
                                  : sidx_v3_cross(sidx_v3_sub(tri_cases[i - NP].p1, tri_cases[i - NP].p0),
                                                  sidx_v3_sub(tri_cases[i - NP].p2, tri_cases[i - NP].p0));
        if (sidx_v3_dot(n, r->dir) > 0.0f) return rules[R_BOTH].hint;
        if (!plane) return rules[R_EDGES].hint;
    }
    return NULL;
}

const ex_driver ex_driver_this = {
    "01_ray_triangle",
    "ray-plane intersection, then the two-step ray-triangle test",
    "deck 001, \"Ray-Plane Intersection\" and \"Ray-Triangle Intersection\"",
    setup, num_cases, describe, reference, student, hint, NULL, format, rules, sizeof rules / sizeof rules[0],
};
