/* test_tprec.c — the precision of the closest hit's t.
 *
 * Rays start close to large triangles (the cornell box, the teapot and a
 * sheet of long thin slivers, scaled by 1e3 and translated by 1e4), where the watertight test's t is
 * coarsest: each sheared vertex is rounded by ε times its distance from
 * the origin (Woop, Benthin & Wald 2013), which is large beside t.  After
 * the walk the query recomputes t on the hit triangle's plane in double
 * when the vertices' spread along the ray exceeds 4 t |d_kz| (accel.c,
 * refine_t).  Against the exact t on the same triangle — n·(p0 − o) / n·d
 * in long double from the float vertices and the float ray — the relative
 * error must be at most TPREC_BOUND, the bound docs/spawning.md
 * ("Precision of t") states for rays with |cos(d, n)| >= 0.05: a t the
 * check leaves to the test has its vertices within 4 t |d_kz| of the
 * origin along the ray, so the shear's rounding stays a few ε of t.
 *
 * The refinement is asked for with SIDX_QUERY_PRECISE_T (queries and
 * packets alike); a default query keeps the test's t (test below).
 *
 * Checked for every registered structure, the packet walks (whose t must
 * also be the single ray's, bit for bit) and aggregates with an identity
 * transform, one level and nested. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <cmocka.h>
#include "sidx/sidx.h"

static const sidx_query precise = {.flags = SIDX_QUERY_PRECISE_T};
static const sidx_packet_options precise_packets = {.mode = SIDX_PACKET_PLAIN, .flags = SIDX_QUERY_PRECISE_T};
#include "common/testkit.h"

/* 2^-17 (7.6e-6): the bound of docs/spawning.md, "Precision of t". */
#define TPREC_BOUND 7.62939453125e-6

/* The exact t of ray r on triangle prim's plane (long double). */
static long double exact_t(const sidx_mesh *m, uint32_t prim, const sidx_ray *r)
{
    const sidx_vec3 p0 = sidx_mesh_vertex(m, prim, 0), p1 = sidx_mesh_vertex(m, prim, 1),
                    p2 = sidx_mesh_vertex(m, prim, 2);
    const long double a[3] = {(long double)p1.x - p0.x, (long double)p1.y - p0.y, (long double)p1.z - p0.z};
    const long double b[3] = {(long double)p2.x - p0.x, (long double)p2.y - p0.y, (long double)p2.z - p0.z};
    const long double n[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    const long double w[3] = {(long double)p0.x - r->org.x, (long double)p0.y - r->org.y,
                              (long double)p0.z - r->org.z};
    return (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]) / (n[0] * r->dir.x + n[1] * r->dir.y + n[2] * r->dir.z);
}

/* Rays from close in front of random points of random triangles, at
 * 10^-1 .. 10^-5 of the triangle's size, with |cos(d, n)| >= 0.05. */
static size_t make_rays(const sidx_mesh *m, tk_rng *rng, sidx_ray *rays, size_t n)
{
    size_t k = 0;
    while (k < n) {
        const uint32_t tri = tk_rng_below(rng, m->num_triangles);
        const sidx_vec3 p0 = sidx_mesh_vertex(m, tri, 0), p1 = sidx_mesh_vertex(m, tri, 1),
                        p2 = sidx_mesh_vertex(m, tri, 2);
        const sidx_vec3 nn = sidx_v3_cross(sidx_v3_sub(p1, p0), sidx_v3_sub(p2, p0));
        const double len = sidx_v3_length(nn), size = sqrt(len);
        if (!(len > 0.0)) continue;
        double u = tk_rng_unit(rng), v = tk_rng_unit(rng);
        if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
        const sidx_vec3 d = tk_rng_sphere(rng);
        const double c = sidx_v3_dot(d, nn) / len;
        if (fabs(c) < 0.05) continue;
        const double s = size * pow(10.0, -tk_rng_range(rng, 1.0, 5.0));
        sidx_vec3 o;
        o.x = (float)((1.0 - u - v) * p0.x + u * p1.x + v * p2.x - s * d.x);
        o.y = (float)((1.0 - u - v) * p0.y + u * p1.y + v * p2.y - s * d.y);
        o.z = (float)((1.0 - u - v) * p0.z + u * p1.z + v * p2.z - s * d.z);
        if (sidx_ray_init(&rays[k], o, d, 0.0f, INFINITY) != SIDX_OK) continue;
        ++k;
    }
    return k;
}

/* Sponza's case: a corrugated sheet of long thin triangles (40 by 0.05,
 * the ridges 0.02 high), so a ray starting close to one reaches a point
 * far from two of its vertices. */
static void make_slivers(sidx_mesh *out)
{
    enum { ROWS = 41 };
    float xyz[2 * ROWS * 3];
    uint32_t idx[(ROWS - 1) * 6];
    for (int k = 0; k < ROWS; ++k)
        for (int e = 0; e < 2; ++e) {
            float *p = xyz + (2 * k + e) * 3;
            p[0] = e ? 40.0f : 0.0f;
            p[1] = (k & 1) ? 0.02f : 0.0f;
            p[2] = 0.05f * (float)k;
        }
    for (int k = 0; k + 1 < ROWS; ++k) {
        const uint32_t a = (uint32_t)(2 * k), b = a + 1, c = a + 2, d = a + 3;
        const uint32_t t[6] = {a, b, d, a, d, c};
        memcpy(idx + 6 * k, t, sizeof t);
    }
    assert_int_equal(sidx_mesh_from_arrays(out, xyz, 2 * ROWS, idx, (ROWS - 1) * 2, NULL), SIDX_OK);
}

typedef struct tally { size_t hits; double worst; } tally;

static void check(const char *what, const sidx_mesh *m, const sidx_ray *r, const sidx_hit *h, tally *tl)
{
    if (h->prim == SIDX_NO_HIT) return;
    long double ex = exact_t(m, h->prim, r);
    /* an origin on the plane, or behind it after rounding: t is clamped to tmin */
    if (ex < r->tmin) ex = r->tmin;
    const double rel = ex == 0 ? (h->t == 0.0f ? 0.0 : INFINITY) : (double)(fabsl((long double)h->t - ex) / fabsl(ex));
    ++tl->hits;
    if (rel > tl->worst) tl->worst = rel;
    if (!(rel <= TPREC_BOUND))
        fail_msg("%s: prim %u t %.9g exact %.12Lg relative error %.3g > %.3g", what, (unsigned)h->prim, (double)h->t,
                 ex, rel, TPREC_BOUND);
}

static void t_within_bound(void **state)
{
    (void)state;
    const size_t nrays = tk_tiny_tests() ? 64 : tk_fast_tests() ? 256 : 2048;
    static const char *const scenes[] = {"cornell", "teapot", "slivers"};
    static const struct { const char *tag; double scale; float offset; } variants[] = {
        {"x1e3", 1e3, 0.0f}, {"+1e4", 1.0, 1e4f}, {"x1e3+1e4", 1e3, 1e4f}};
    sidx_ray *rays = malloc(nrays * sizeof *rays);
    sidx_hit *single = malloc(nrays * sizeof *single), *pk = malloc(nrays * sizeof *pk);
    assert_non_null(rays);
    assert_non_null(single);
    assert_non_null(pk);
    tally all = {0, 0.0};
    size_t refined = 0; /* hits whose t the flag changed */
    for (size_t si = 0; si < sizeof scenes / sizeof scenes[0]; ++si) {
        sidx_mesh base;
        if (strcmp(scenes[si], "slivers") == 0)
            make_slivers(&base);
        else
            assert_int_equal(sidx_scene_make(scenes[si], 0, &base, NULL), SIDX_OK);
        for (size_t vi = 0; vi < sizeof variants / sizeof variants[0]; ++vi) {
            if (tk_tiny_tests() && vi != si % 3) continue; /* the smallest sizes: one variant per scene */
            const float off = variants[vi].offset;
            sidx_mesh m;
            assert_int_equal(tk_mesh_transform(&base, variants[vi].scale, sidx_v3(off, off, off), &m), SIDX_OK);
            tk_rng rng;
            tk_rng_seed(&rng, 0x7e5 + si * 3 + vi);
            const size_t n = make_rays(&m, &rng, rays, nrays);
            char what[128];
            for (size_t k = 0; k < sidx_accel_registered_count(); ++k) {
                const char *name = sidx_accel_registered_name(k);
                sidx_accel *a = NULL;
                assert_int_equal(sidx_accel_build(name, &m, NULL, &a, NULL), SIDX_OK);
                snprintf(what, sizeof what, "%s %s, %s", scenes[si], variants[vi].tag, name);
                for (size_t i = 0; i < n; ++i) {
                    assert_int_equal(sidx_accel_intersect(a, &rays[i], &precise, &single[i]), SIDX_OK);
                    check(what, &m, &rays[i], &single[i], &all);
                    /* a default query: the same triangle, the test's own t */
                    sidx_hit d;
                    assert_int_equal(sidx_accel_intersect(a, &rays[i], NULL, &d), SIDX_OK);
                    if (d.prim != single[i].prim)
                        fail_msg("%s, ray %zu: prim %u without the flag, %u with it", what, i, (unsigned)d.prim,
                                 (unsigned)single[i].prim);
                    refined += d.t != single[i].t;
                }
                /* packets: the single ray's answer, t included */
                for (size_t i = 0; i + 16 <= n; i += 16)
                    assert_int_equal(sidx_packet_intersect(a, &rays[i], 16, 16, &precise_packets, &pk[i], NULL), SIDX_OK);
                /* On a hit at the shared diagonal of a quad a packet walk may
                 * accept the other triangle than the single ray (so at main
                 * c7cae4c already); its t is then held to the bound alone. */
                for (size_t i = 0; i < n / 16 * 16; ++i) {
                    snprintf(what, sizeof what, "%s %s, %s packets", scenes[si], variants[vi].tag, name);
                    check(what, &m, &rays[i], &pk[i], &all);
                    if (pk[i].prim == single[i].prim && memcmp(&pk[i].t, &single[i].t, sizeof pk[i].t))
                        fail_msg("%s, packet ray %zu: prim %u t %.9g, single ray: prim %u t %.9g", what, i,
                                 (unsigned)pk[i].prim, (double)pk[i].t, (unsigned)single[i].prim, (double)single[i].t);
                }
                if (k == 0) {
                    /* aggregates, identity transform: the local ray is the ray */
                    const sidx_instance one = {a, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}};
                    sidx_accel *agg = NULL, *nest = NULL;
                    assert_int_equal(sidx_aggregate_build(&one, 1, NULL, &agg, NULL), SIDX_OK);
                    const sidx_instance outer = {agg, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}};
                    assert_int_equal(sidx_aggregate_build(&outer, 1, NULL, &nest, NULL), SIDX_OK);
                    for (size_t i = 0; i < n; ++i) {
                        sidx_hit h;
                        sidx_accel_intersect(agg, &rays[i], &precise, &h);
                        snprintf(what, sizeof what, "%s %s, aggregate", scenes[si], variants[vi].tag);
                        check(what, &m, &rays[i], &h, &all);
                        sidx_accel_intersect(nest, &rays[i], &precise, &h);
                        snprintf(what, sizeof what, "%s %s, nested aggregate", scenes[si], variants[vi].tag);
                        check(what, &m, &rays[i], &h, &all);
                    }
                    sidx_accel_destroy(nest);
                    sidx_accel_destroy(agg);
                }
                sidx_accel_destroy(a);
            }
            sidx_mesh_free(&m);
        }
        sidx_mesh_free(&base);
    }
    printf("t precision: %zu hits, worst relative error %.3g (bound %.3g); the flag refined %zu\n", all.hits,
           all.worst, TPREC_BOUND, refined);
    assert_true(all.hits > 0);
    assert_true(refined > 0); /* these scenes are where the test's t is coarse */
    free(rays);
    free(single);
    free(pk);
}

/* t stays in [tmin, tmax): a ray whose tmax is just past the hit keeps a
 * t below tmax, and the hit t is reproduced by every structure. */
static void t_inside_interval(void **state)
{
    (void)state;
    sidx_mesh m;
    assert_int_equal(sidx_scene_make("cornell", 0, &m, NULL), SIDX_OK);
    tk_rng rng;
    tk_rng_seed(&rng, 11);
    sidx_ray rays[256];
    const size_t n = make_rays(&m, &rng, rays, 256);
    for (size_t k = 0; k < sidx_accel_registered_count(); ++k) {
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build(sidx_accel_registered_name(k), &m, NULL, &a, NULL), SIDX_OK);
        for (size_t i = 0; i < n; ++i) {
            sidx_hit h;
            sidx_accel_intersect(a, &rays[i], &precise, &h);
            if (h.prim == SIDX_NO_HIT) continue;
            sidx_ray r = rays[i];
            r.tmax = nextafterf(h.t, INFINITY);
            sidx_hit h2;
            sidx_accel_intersect(a, &r, &precise, &h2);
            if (h2.prim == SIDX_NO_HIT) continue; /* the walk's float t was above the refined one */
            assert_true(h2.t >= r.tmin && h2.t < r.tmax);
        }
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(t_within_bound),
        cmocka_unit_test(t_inside_interval),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
