/* Exercise 02 — Möller–Trumbore, solved by Cramer's rule.
 *
 * Slides: deck 001, "Moller-Trumbore Algorithm" and "Moller-Trumbore
 * Visualized".
 *
 * With s = o − p0, e1 = p1 − p0, e2 = p2 − p0 the ray meets the triangle
 * where s = u·e1 + v·e2 − t·d.  By Cramer's rule, with
 * D = (e1 × d)·e2:
 *     u = −((s × e2)·d) / D,   v = ((e1 × d)·s) / D,   t = −((s × e2)·e1) / D
 * Return 1 and write *t, *u, *v when there is a unique solution with
 * u >= 0, v >= 0, u + v <= 1 (edges and vertices count) and t in
 * [r->tmin, tmax); return 0 otherwise, with *t, *u, *v left as they were.
 * "What if D = 0? What does it mean?"  "What if t is negative?"
 *
 * Helpers: sidx/math.h.  Check with:   make exercise EX=02_moller_trumbore
 * Only the function body is yours to write. */
#include "sidx/sidx.h"

int moller_trumbore(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t, float *u,
                    float *v)
{
    (void)r;
    (void)p0;
    (void)p1;
    (void)p2;
    (void)tmax;
    (void)t;
    (void)u;
    (void)v;
    return 0;
}
