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

static int setup(void)
{
    tri_fill();
    return 0;
}

static size_t num_cases(void) { return TRI_FIXED + TRI_RANDOM; }
static void describe(size_t i, ex_case_info *out) { tri_describe(&tri_cases[i], out); }

static void reference(size_t i, const sidx_hook *h)
{
    const tri_case *c = &tri_cases[i];
    float t = INFINITY, u = NAN, v = NAN;
    const int hit = sidx_ex_reference_moller_cramer(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t, &u, &v);
    tri_emit(h, i, hit, t);
    if (hit) emit_uv(h, u, v);
}

static void student(size_t i, const sidx_hook *h)
{
    const tri_case *c = &tri_cases[i];
    float t = INFINITY, u = NAN, v = NAN;
    const int hit = moller_trumbore(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t, &u, &v);
    tri_emit(h, i, hit, t);
    if (hit) emit_uv(h, u, v);
}

static const char *const hint_t =
    "the same triangle hit at another t: each unknown is a determinant divided by D (Cramer's rule), "
    "t = -(s x e2)·e1 / D with s = o - p0, e1 = p1 - p0, e2 = p2 - p0, D = (e1 x d)·e2: check the formula for t "
    "and the division by D";
static const char *const hint_uv =
    "the right hit, other barycentrics: u = -(s x e2)·d / D goes with e1 = p1 - p0 and v = (e1 x d)·s / D with "
    "e2 = p2 - p0 (the hit point is p0 + u·e1 + v·e2); write them to *u and *v";

/* What differs decides: another t is the formula for t, other
 * barycentrics are u and v, a hit for a miss (or the reverse) is the
 * case's own rule. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    (void)i;
    if (ref && stu && ref->type == SIDX_EV_PRIM_TEST && stu->type == SIDX_EV_PRIM_TEST && ref->result == 1 &&
        stu->result == 1)
        return hint_t;
    if (ref && stu && ref->type == SIDX_EV_NOTE && stu->type == SIDX_EV_NOTE) return hint_uv;
    return NULL;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    snprintf(buf, size, "barycentrics u=%g v=%g", (double)e->t_near, (double)e->t_far);
    return 1;
}

const ex_driver ex_driver_this = {
    "02_moller_trumbore",
    "Moller-Trumbore by Cramer's rule: D = 0, t < 0, edges and vertices",
    "deck 001, \"Moller-Trumbore Algorithm\" and \"Moller-Trumbore Visualized\"",
    setup, num_cases, describe, reference, student, hint, NULL, format, NULL, 0,
};
