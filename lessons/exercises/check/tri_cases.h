/* tri_cases.h — the ray–triangle battery shared by the two-step test
 * (01_ray_triangle) and Möller–Trumbore (02_moller_trumbore).  Integer and
 * half-integer coordinates on the awkward cases, so every product is exact
 * and an edge or a vertex hit does not depend on the order in which a
 * student's code does its arithmetic. */
#ifndef SIDX_EX_TRI_CASES_H
#define SIDX_EX_TRI_CASES_H

#include <math.h>
#include <string.h>
#include "check.h"

typedef struct tri_case {
    const char *name;
    const char *hint;
    const char *rules; /* the ids of the rules the case tests (check.h) */
    sidx_vec3 p0, p1, p2;
    sidx_ray ray;
    float tmax;
} tri_case;

#define TRI_RANDOM 40
#define TRI_FIXED 20
static tri_case tri_cases[TRI_FIXED + TRI_RANDOM];

/* The hints of the rules both drivers share (string literals, so that a
 * driver's rule table can hold them too). */
#define TRI_HINT_INSIDE                                                                                    \
    "a unique solution (t, u, v) with t >= 0, u >= 0, v >= 0, u + v <= 1 is an intersection; "             \
    "all four bounds are inclusive"
#define TRI_HINT_OUTSIDE                                                                                   \
    "a point outside the triangle is a miss: p is inside when u >= 0, v >= 0 and u + v <= 1, all three; a " \
    "hit of the triangle's plane alone is no intersection"
#define TRI_HINT_BEHIND                                                                                    \
    "What if t is negative? The intersection happens in the negative direction, behind the origin: a miss " \
    "(t must lie in [tmin, tmax))"
#define TRI_HINT_TMIN                                                                                      \
    "the lower bound is the ray's r->tmin, not 0: a hit with 0 <= t < tmin is a miss (a ray that starts "   \
    "beyond a surface, e.g. a secondary ray, must not hit it again)"
#define TRI_HINT_TMIN_INCL                                                                                 \
    "[tmin, tmax) includes tmin: a hit exactly at t = tmin (t >= tmin, not t > tmin) counts, e.g. a ray "  \
    "starting on the surface at t = 0"
#define TRI_HINT_TMAX                                                                                      \
    "hits count only in [tmin, tmax): a hit at or beyond tmax is a miss (tmax is the best hit so far)"
#define TRI_HINT_UNTOUCHED                                                                                 \
    "write the outputs only when you return 1: on a miss *t (and *u, *v) keep what the caller had there, " \
    "e.g. the best hit so far; check everything first, then write"
static const char *const hint_inside = TRI_HINT_INSIDE;
static const char *const hint_outside = TRI_HINT_OUTSIDE;
static const char *const hint_parallel =
    "What if D = 0? What does it mean? The ray is parallel to the triangle's plane (or the triangle is "
    "degenerate): there is no unique solution, report a miss";
static const char *const hint_behind = TRI_HINT_BEHIND;
static const char *const hint_tmin = TRI_HINT_TMIN;
static const char *const hint_tmin_incl = TRI_HINT_TMIN_INCL;
static const char *const hint_tmax = TRI_HINT_TMAX;
static const char *const hint_untouched = TRI_HINT_UNTOUCHED;
static const char *const hint_backface =
    "the ray may meet the triangle from either side: D < 0 is a hit as well (only D = 0 is special)";

static void tri_fill(void)
{
    const sidx_vec3 A = {0, 0, 0}, B = {4, 0, 0}, C = {0, 4, 0};
    int k = 0;
#define TC(nm, h, a, b, c, ray_, tmax_)                                                                     \
    tri_cases[k].name = nm;                                                                                \
    tri_cases[k].hint = h;                                                                                 \
    tri_cases[k].rules = NULL;                                                                             \
    tri_cases[k].p0 = a;                                                                                   \
    tri_cases[k].p1 = b;                                                                                   \
    tri_cases[k].p2 = c;                                                                                   \
    tri_cases[k].ray = ray_;                                                                               \
    tri_cases[k].tmax = tmax_;                                                                             \
    ++k
    TC("straight through the middle", hint_inside, A, B, C, ex_ray(1, 1, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("oblique ray through the middle", hint_inside, A, B, C, ex_ray(-1, 0.5f, 2, 1, 0.5f, -1, 0, INFINITY),
       INFINITY);
    TC("outside edge p0-p1 (v < 0)", hint_outside, A, B, C, ex_ray(1, -1, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("outside edge p0-p2 (u < 0)", hint_outside, A, B, C, ex_ray(-1, 1, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("outside edge p1-p2 (u + v > 1)", hint_outside, A, B, C, ex_ray(3, 3, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("exactly on edge p0-p1 (v = 0)", hint_inside, A, B, C, ex_ray(2, 0, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("exactly on edge p0-p2 (u = 0)", hint_inside, A, B, C, ex_ray(0, 2, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("exactly on edge p1-p2 (u + v = 1)", hint_inside, A, B, C, ex_ray(2, 2, 5, 0, 0, -1, 0, INFINITY),
       INFINITY);
    TC("exactly on vertex p0", hint_inside, A, B, C, ex_ray(0, 0, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("exactly on vertex p2", hint_inside, A, B, C, ex_ray(0, 4, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("from behind the triangle (D < 0)", hint_backface, A, B, C, ex_ray(1, 1, -5, 0, 0, 1, 0, INFINITY),
       INFINITY);
    TC("triangle behind the origin (t < 0)", hint_behind, A, B, C, ex_ray(1, 1, 5, 0, 0, 1, 0, INFINITY),
       INFINITY);
    TC("parallel ray above the plane (D = 0)", hint_parallel, A, B, C, ex_ray(-1, 1, 1, 1, 0, 0, 0, INFINITY),
       INFINITY);
    TC("ray lying in the triangle's plane (D = 0)", hint_parallel, A, B, C,
       ex_ray(-1, 1, 0, 1, 0, 0, 0, INFINITY), INFINITY);
    TC("degenerate triangle: three points on a line (D = 0)", hint_parallel, A, B, sidx_v3(2, 0, 0),
       ex_ray(1, 0, 5, 0, 0, -1, 0, INFINITY), INFINITY);
    TC("hit beyond tmax", hint_tmax, A, B, C, ex_ray(1, 1, 5, 0, 0, -1, 0, INFINITY), 4.0f);
    TC("hit exactly at tmax", hint_tmax, A, B, C, ex_ray(1, 1, 5, 0, 0, -1, 0, INFINITY), 5.0f);
    TC("origin on the triangle (t = 0)", hint_tmin_incl, A, B, C, ex_ray(1, 1, 0, 0, 0, -1, 0, INFINITY),
       INFINITY);
    /* tmin > 0: the bound is the ray's, not 0 (t = 5 here) */
    TC("tmin > 0: the hit lies before tmin (0 < t < tmin)", hint_tmin, A, B, C,
       ex_ray(1, 1, 5, 0, 0, -1, 6.0f, INFINITY), INFINITY);
    TC("tmin > 0: the hit exactly at tmin", hint_tmin_incl, A, B, C, ex_ray(1, 1, 5, 0, 0, -1, 5.0f, INFINITY),
       INFINITY);
    uint32_t s = 12345u;
    for (int i = 0; i < TRI_RANDOM; ++i) {
        sidx_vec3 p[3];
        for (int j = 0; j < 3; ++j)
            p[j] = sidx_v3(ex_rand(&s) * 4 - 2, ex_rand(&s) * 4 - 2, ex_rand(&s) * 4 - 2);
        const sidx_vec3 o = sidx_v3(ex_rand(&s) * 10 - 5, ex_rand(&s) * 10 - 5, ex_rand(&s) * 10 - 5);
        const sidx_vec3 aim = sidx_v3(ex_rand(&s) * 3 - 1.5f, ex_rand(&s) * 3 - 1.5f, ex_rand(&s) * 3 - 1.5f);
        const sidx_vec3 d = sidx_v3_sub(aim, o);
        TC("random triangle and ray", hint_inside, p[0], p[1], p[2], ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0, INFINITY),
           INFINITY);
    }
#undef TC
    static const struct {
        const char *name, *rules;
    } tagged[] = {
        {"straight through the middle", "t-formula"},
        {"oblique ray through the middle", "t-formula"},
        {"outside edge p0-p1 (v < 0)", "outside-miss untouched-on-miss"},
        {"outside edge p0-p2 (u < 0)", "outside-miss untouched-on-miss"},
        {"outside edge p1-p2 (u + v > 1)", "outside-miss untouched-on-miss"},
        {"exactly on edge p0-p1 (v = 0)", "edges-count"},
        {"exactly on edge p0-p2 (u = 0)", "edges-count"},
        {"exactly on edge p1-p2 (u + v = 1)", "edges-count"},
        {"exactly on vertex p0", "edges-count"},
        {"exactly on vertex p2", "edges-count"},
        {"from behind the triangle (D < 0)", "both-sides"},
        {"triangle behind the origin (t < 0)", "behind-miss untouched-on-miss"},
        {"parallel ray above the plane (D = 0)", "parallel-miss"},
        {"ray lying in the triangle's plane (D = 0)", "parallel-miss"},
        {"degenerate triangle: three points on a line (D = 0)", "parallel-miss"},
        {"hit beyond tmax", "tmax-exclusive untouched-on-miss"},
        {"hit exactly at tmax", "tmax-exclusive"},
        {"origin on the triangle (t = 0)", "tmin-inclusive"},
        {"tmin > 0: the hit lies before tmin (0 < t < tmin)", "tmin untouched-on-miss"},
        {"tmin > 0: the hit exactly at tmin", "tmin tmin-inclusive"},
    };
    for (int i = 0; i < k; ++i)
        for (size_t j = 0; j < sizeof tagged / sizeof tagged[0]; ++j)
            if (!strcmp(tri_cases[i].name, tagged[j].name)) tri_cases[i].rules = tagged[j].rules;
}

static void tri_describe(const tri_case *c, ex_case_info *out)
{
    char ray[160];
    ex_format_ray(ray, sizeof ray, &c->ray);
    snprintf(out->name, sizeof out->name, "%s", c->name);
    snprintf(out->what, sizeof out->what, "%s, tmax %g; triangle (%g, %g, %g) (%g, %g, %g) (%g, %g, %g)", ray,
             (double)c->tmax, (double)c->p0.x, (double)c->p0.y, (double)c->p0.z, (double)c->p1.x, (double)c->p1.y,
             (double)c->p1.z, (double)c->p2.x, (double)c->p2.y, (double)c->p2.z);
    out->hint = c->hint;
    out->rules = c->rules;
}

/* The harness's one event per case: PRIM_TEST with the case number as prim. */
static void tri_emit(const sidx_hook *h, size_t i, int hit, float t)
{
    sidx_ex ex;
    memset(&ex, 0, sizeof ex);
    ex.hook = h;
    ex.structure = "triangle";
    sidx_ex_prim_test(&ex, (uint32_t)i, hit, t);
}

/* An output written on a miss ("write ... when there is a hit"): a NOTE
 * with cell[0] = TRI_WRITTEN and the value written in t_near.  The
 * reference writes nothing on a miss, so its trace has no such step. */
#define TRI_WRITTEN 7
static void tri_emit_written(const sidx_hook *h, float value)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "triangle";
    e.cell[0] = TRI_WRITTEN;
    e.t_near = value;
    sidx_hook_emit(h, &e);
}

/* The same float bits: an output that still holds the caller's value. */
static int tri_same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

/* The hint for a hit where the reference misses, by the t written: a NaN
 * or an infinite t comes from N·d = 0 (D = 0), a t below 0 lies behind the
 * origin, one in [0, tmin) before the ray's start, one at or beyond tmax
 * beyond the best hit; NULL for a t inside [tmin, tmax) (the point lies
 * outside the triangle). */
static const char *tri_range_hint(float t, float tmin, float tmax, const char *parallel)
{
    if (isnan(t) || isinf(t)) return parallel;
    if (t < 0.0f && t < tmin) return hint_behind;
    if (t < tmin) return hint_tmin;
    if (!(t < tmax)) return hint_tmax;
    return NULL;
}

#endif
