/* 01_ray_triangle.c — checker driver: ray–plane, then the two-step
 * ray–triangle test (deck 001, "Ray-Plane Intersection" and
 * "Ray-Triangle Intersection").  Reference: the library's
 * sidx_intersect_plane and sidx_intersect_triangle_two_step. */
#include "tri_cases.h"

int ray_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t);
int ray_triangle_two_step(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t);

typedef struct plane_case {
    const char *name, *hint;
    sidx_vec3 n;
    float c;
    sidx_ray ray;
} plane_case;

#define PLANE_RANDOM 20
#define PLANE_FIXED 9
static plane_case planes[PLANE_FIXED + PLANE_RANDOM];

static const char *const hint_plane = "t = (c - N·o) / (N·d): plug the ray o + t·d into N·x = c and solve for t";
static const char *const hint_plane_parallel =
    "N·d = 0: the ray is parallel to the plane (or lies in it), there is no unique t: a miss";
static const char *const hint_plane_range = "a hit counts only for t in [tmin, tmax): What if t is negative? "
                                            "The intersection is behind the origin";

static int setup(void)
{
    int k = 0;
#define PC(nm, h, nx, ny, nz, c_, ray_)                                                                     \
    planes[k].name = nm;                                                                                   \
    planes[k].hint = h;                                                                                    \
    planes[k].n = sidx_v3(nx, ny, nz);                                                                     \
    planes[k].c = c_;                                                                                      \
    planes[k].ray = ray_;                                                                                  \
    ++k
    PC("plane: head-on", hint_plane, 0, 0, 1, 0, ex_ray(0, 0, 5, 0, 0, -1, 0, INFINITY));
    PC("plane: oblique ray, tilted plane", hint_plane, 1, 1, 1, 1, ex_ray(1, 2, 3, 0.5f, -1, -2, 0, INFINITY));
    PC("plane: normal not of unit length", hint_plane, 0, 0, 2, 4, ex_ray(0, 0, 6, 0, 0, -2, 0, INFINITY));
    PC("plane: from the back side (N·d > 0)", hint_plane, 0, 0, 1, 0, ex_ray(0, 0, -3, 0, 0, 1, 0, INFINITY));
    PC("plane: parallel above it (N·d = 0)", hint_plane_parallel, 0, 0, 1, 0, ex_ray(0, 0, 1, 1, 0, 0, 0, INFINITY));
    PC("plane: ray lying in it (N·d = 0)", hint_plane_parallel, 0, 0, 1, 0, ex_ray(0, 0, 0, 1, 1, 0, 0, INFINITY));
    PC("plane: behind the origin (t < 0)", hint_plane_range, 0, 0, 1, 0, ex_ray(0, 0, 5, 0, 0, 1, 0, INFINITY));
    PC("plane: beyond tmax", hint_plane_range, 0, 0, 1, 0, ex_ray(0, 0, 5, 0, 0, -1, 0, 5.0f));
    PC("plane: ray starting on it (t = 0)", hint_plane_range, 0, 0, 1, 2, ex_ray(3, 1, 2, 0, 1, -1, 0, INFINITY));
    uint32_t s = 777u;
    for (int i = 0; i < PLANE_RANDOM; ++i) {
        const float nx = ex_rand(&s) * 2 - 1, ny = ex_rand(&s) * 2 - 1, nz = ex_rand(&s) * 2 - 1;
        PC("plane: random", hint_plane, nx, ny, nz, ex_rand(&s) * 4 - 2,
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
        return;
    }
    const plane_case *p = &planes[i];
    char ray[160];
    ex_format_ray(ray, sizeof ray, &p->ray);
    snprintf(out->name, sizeof out->name, "%s", p->name);
    snprintf(out->what, sizeof out->what, "%s; plane N=(%g, %g, %g) c=%g", ray, (double)p->n.x, (double)p->n.y,
             (double)p->n.z, (double)p->c);
    out->hint = p->hint;
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

static void student(size_t i, const sidx_hook *h)
{
    float t = INFINITY;
    int hit;
    if (i < NP) {
        hit = ray_plane(&planes[i].ray, planes[i].n, planes[i].c, &t);
    } else {
        const tri_case *c = &tri_cases[i - NP];
        hit = ray_triangle_two_step(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t);
    }
    tri_emit(h, i, hit, t);
}

static const char *const hint_plane_t =
    "the same plane hit at another t: plug the ray o + t·d into N·x = c, N·o + t·(N·d) = c, so t = (c - N·o) / "
    "(N·d) with the ray's own d (not normalised) and N as given (not normalised either)";
static const char *const hint_tri_t =
    "the same triangle hit at another t: step i) is the ray-plane test, the plane through the triangle is "
    "N = e1 x e2, c = N·p0, and t = (c - N·o) / (N·d) with the ray's own d; t is the plane's, step ii) only "
    "decides hit or miss";

/* What differs decides: another t is the formula for t; a hit whose t
 * lies outside [tmin, tmax) is the range rule (t < tmin: behind the
 * origin, t >= tmax: beyond the best hit); any other hit for a miss, or
 * miss for a hit, is the case's own rule. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if (!ref || !stu || ref->type != SIDX_EV_PRIM_TEST || stu->type != SIDX_EV_PRIM_TEST) return NULL;
    const int plane = i < NP;
    if (ref->result == 1 && stu->result == 1) return plane ? hint_plane_t : hint_tri_t;
    if (ref->result == 0 && stu->result == 1) {
        const sidx_ray *r = plane ? &planes[i].ray : &tri_cases[i - NP].ray;
        const float tmax = plane ? r->tmax : tri_cases[i - NP].tmax;
        if (!(stu->t >= r->tmin)) return plane ? hint_plane_range : hint_behind;
        if (!(stu->t < tmax)) return plane ? hint_plane_range : hint_tmax;
    }
    return NULL;
}

const ex_driver ex_driver_this = {
    "01_ray_triangle",
    "ray-plane intersection, then the two-step ray-triangle test",
    "deck 001, \"Ray-Plane Intersection\" and \"Ray-Triangle Intersection\"",
    setup, num_cases, describe, reference, student, hint, NULL, NULL, NULL, 0,
};
