/* 02_moller_trumbore.c — checker driver: Möller–Trumbore in the slide's
 * Cramer form (deck 001, "Moller-Trumbore Algorithm").  Reference: the
 * library's sidx_ex_reference_moller_cramer (sidx/exercise.h), that form
 * term by term as on the slide (sidx_intersect_triangle's Möller–Trumbore
 * is the paper's arrangement, which rounds differently). */
#include "tri_cases.h"

int moller_trumbore(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t, float *u,
                    float *v);

/* A hit's barycentrics, the outputs *u and *v: a NOTE with u in t_near
 * and v in t_far (compared within the tolerance of t). */
static void emit_uv(const sidx_hook *h, float u, float v)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "triangle";
    e.t_near = u;
    e.t_far = v;
    sidx_hook_emit(h, &e);
}

#define HINT_T                                                                                             \
    "the same triangle hit at another t: each unknown is a determinant divided by D (Cramer's rule), "       \
    "t = -(s x e2)·e1 / D with s = o - p0, e1 = p1 - p0, e2 = p2 - p0, D = (e1 x d)·e2: check the formula for " \
    "t and the division by D"
#define HINT_UV                                                                                            \
    "the right hit, other barycentrics: u = -(s x e2)·d / D goes with e1 = p1 - p0 and v = (e1 x d)·s / D "  \
    "with e2 = p2 - p0 (the hit point is p0 + u·e1 + v·e2); write them to *u and *v"
#define HINT_PARALLEL                                                                                      \
    "What if D = 0? What does it mean? The ray is parallel to the triangle's plane (or the triangle is "    \
    "degenerate): there is no unique solution, report a miss; test D == 0 before you divide: u, v, t are "  \
    "then ±inf or NaN, and a NaN fails every comparison, so `u < 0 || ...` lets it through"
#define HINT_BACKFACE "the ray may meet the triangle from either side: D < 0 is a hit as well (only D = 0 is special)"

/* The hand-out's promises (lessons/exercises/02_moller_trumbore.c). */
static const ex_rule rules[] = {
    {"t-formula", "t = -((s x e2)·e1) / D by Cramer's rule, with D = (e1 x d)·e2", HINT_T},
    {"barycentrics", "u = -((s x e2)·d) / D and v = ((e1 x d)·s) / D are written to the outputs u and v on a hit",
     HINT_UV},
    {"parallel-miss", "D = 0 (a parallel ray, a degenerate triangle: no unique solution) is a miss",
     HINT_PARALLEL},
    {"both-sides", "D < 0 (the ray meets the triangle's back) is a hit too", HINT_BACKFACE},
    {"behind-miss", "a negative t is a miss (\"What if t is negative?\")", TRI_HINT_BEHIND},
    {"tmin", "the lower bound is r->tmin, which may be > 0: t < tmin is a miss", TRI_HINT_TMIN},
    {"tmin-inclusive", "t = tmin is a hit: the range [r->tmin, tmax) includes tmin", TRI_HINT_TMIN_INCL},
    {"tmax-exclusive", "t >= tmax (the argument) is a miss: the range excludes tmax", TRI_HINT_TMAX},
    {"edges-count", "u >= 0, v >= 0, u + v <= 1: edges and vertices count", TRI_HINT_INSIDE},
    {"outside-miss", "u < 0, v < 0 or u + v > 1 is a miss", TRI_HINT_OUTSIDE},
    {"untouched-on-miss",
     "the outputs t, u, v are written only on a hit; a miss returns 0 and leaves them as they were",
     TRI_HINT_UNTOUCHED},
};
enum { R_T, R_UV, R_PARALLEL, R_BOTH, R_BEHIND, R_TMIN, R_TMIN_INCL, R_TMAX, R_EDGES, R_OUTSIDE, R_UNTOUCHED };

static int setup(void)
{
    tri_fill();
    return 0;
}

static size_t num_cases(void) { return TRI_FIXED + TRI_RANDOM; }
static void describe(size_t i, ex_case_info *out)
{
    tri_describe(&tri_cases[i], out);
    /* a hit's barycentrics are outputs too */
    if (out->rules && !strcmp(out->rules, "t-formula")) out->rules = "t-formula barycentrics";
    if (out->rules && !strcmp(out->rules, "edges-count")) out->rules = "edges-count barycentrics";
}

static void reference(size_t i, const sidx_hook *h)
{
    const tri_case *c = &tri_cases[i];
    float t = INFINITY, u = NAN, v = NAN;
    const int hit = sidx_ex_reference_moller_cramer(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t, &u, &v);
    tri_emit(h, i, hit, t);
    if (hit) emit_uv(h, u, v);
}

/* The caller's values of *t, *u, *v: a miss must leave them (the reference does). */
#define T_BEFORE 1234.5f
#define UV_BEFORE -7.25f

static void student(size_t i, const sidx_hook *h)
{
    const tri_case *c = &tri_cases[i];
    float t = T_BEFORE, u = UV_BEFORE, v = UV_BEFORE;
    const int hit = moller_trumbore(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t, &u, &v);
    tri_emit(h, i, hit, t);
    if (hit) emit_uv(h, u, v);
    if (!hit && !(tri_same_bits(t, T_BEFORE) && tri_same_bits(u, UV_BEFORE) && tri_same_bits(v, UV_BEFORE)))
        tri_emit_written(h, !tri_same_bits(t, T_BEFORE) ? t : !tri_same_bits(u, UV_BEFORE) ? u : v);
}

/* What differs decides: another t is the formula for t, other
 * barycentrics are u and v, an output written on a miss the untouched
 * rule; a hit where the reference misses is named by its t (NaN or inf:
 * D = 0; below 0: behind the origin; in [0, tmin): tmin; at or beyond
 * tmax: tmax) or, with t in range, by the inside test; a miss where the
 * reference hits by the reference's t (at tmin: the inclusive bound), the
 * sign of D (D < 0 is a hit) or the boundary of the triangle. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const tri_case *c = &tri_cases[i];
    if (stu && stu->type == SIDX_EV_NOTE && stu->cell[0] == TRI_WRITTEN) return rules[R_UNTOUCHED].hint;
    if (ref && stu && ref->type == SIDX_EV_NOTE && stu->type == SIDX_EV_NOTE) return rules[R_UV].hint;
    if (!ref || !stu || ref->type != SIDX_EV_PRIM_TEST || stu->type != SIDX_EV_PRIM_TEST) return NULL;
    if (ref->result == 1 && stu->result == 1) return rules[R_T].hint;
    if (ref->result == 0 && stu->result == 1) {
        const char *h = tri_range_hint(stu->t, c->ray.tmin, c->tmax, rules[R_PARALLEL].hint);
        return h ? h : rules[R_OUTSIDE].hint;
    }
    if (ref->result == 1 && stu->result == 0) {
        if (ref->t == c->ray.tmin) return rules[R_TMIN_INCL].hint;
        const sidx_vec3 e1 = sidx_v3_sub(c->p1, c->p0), e2 = sidx_v3_sub(c->p2, c->p0);
        if (sidx_v3_dot(sidx_v3_cross(e1, c->ray.dir), e2) < 0.0f) return rules[R_BOTH].hint;
        return rules[R_EDGES].hint;
    }
    return NULL;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    if (e->cell[0] == TRI_WRITTEN)
        snprintf(buf, size, "returned 0 (a miss) but wrote an output: %g", (double)e->t_near);
    else
        snprintf(buf, size, "barycentrics u=%g v=%g", (double)e->t_near, (double)e->t_far);
    return 1;
}

const ex_driver ex_driver_this = {
    "02_moller_trumbore",
    "Moller-Trumbore by Cramer's rule: D = 0, t < 0, edges and vertices",
    "deck 001, \"Moller-Trumbore Algorithm\" and \"Moller-Trumbore Visualized\"",
    setup, num_cases, describe, reference, student, hint, NULL, format, rules, sizeof rules / sizeof rules[0],
};
