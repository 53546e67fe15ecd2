/* 02_moller_trumbore.c — checker driver: Möller–Trumbore in the slide's
 * Cramer form (deck 001, "Moller-Trumbore Algorithm").  Reference: that
 * form computed here, term by term as on the slide (the library's
 * sidx_intersect_triangle_moller is the same solution arranged as
 * Möller and Trumbore's paper does, which rounds differently). */
#include "tri_cases.h"

int moller_trumbore(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t, float *u,
                    float *v);

static int cramer(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t_out)
{
    const sidx_vec3 e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0), s = sidx_v3_sub(r->org, p0);
    const sidx_vec3 e1xd = sidx_v3_cross(e1, r->dir), sxe2 = sidx_v3_cross(s, e2);
    const float D = sidx_v3_dot(e1xd, e2);
    if (D == 0.0f) return 0;
    const float u = -sidx_v3_dot(sxe2, r->dir) / D;
    const float v = sidx_v3_dot(e1xd, s) / D;
    const float t = -sidx_v3_dot(sxe2, e1) / D;
    if (!(u >= 0.0f && v >= 0.0f && u + v <= 1.0f)) return 0;
    if (!(t >= r->tmin && t < tmax)) return 0;
    *t_out = t;
    return 1;
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
    float t = INFINITY;
    const int hit = cramer(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t);
    tri_emit(h, i, hit, t);
}

static void student(size_t i, const sidx_hook *h)
{
    const tri_case *c = &tri_cases[i];
    float t = INFINITY, u = 0, v = 0;
    const int hit = moller_trumbore(&c->ray, c->p0, c->p1, c->p2, c->tmax, &t, &u, &v);
    tri_emit(h, i, hit, t);
}

const ex_driver ex_driver_this = {
    "02_moller_trumbore",
    "Moller-Trumbore by Cramer's rule: D = 0, t < 0, edges and vertices",
    "deck 001, \"Moller-Trumbore Algorithm\" and \"Moller-Trumbore Visualized\"",
    setup, num_cases, describe, reference, student, NULL, NULL, NULL,
};
