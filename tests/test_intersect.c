/* test_intersect.c — every elementary test against hand-computed cases from
 * the decks, plus the edge cases the header documents: edges, vertices,
 * degenerate triangles, parallel rays, rays starting on the surface,
 * negative t, ±0 direction components. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <string.h>
#include "sidx/sidx.h"

static sidx_ray mkray(float ox, float oy, float oz, float dx, float dy, float dz)
{
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(ox, oy, oz), sidx_v3(dx, dy, dz), 0.0f, INFINITY), SIDX_OK);
    return r;
}

static const sidx_tri_method all_methods[] = {SIDX_TRI_WATERTIGHT, SIDX_TRI_MOLLER_TRUMBORE, SIDX_TRI_TWO_STEP};
#define NMETHODS 3

/* ---- rays -------------------------------------------------------------- */

static void ray_init_rejects_bad_input(void **state)
{
    (void)state;
    sidx_ray r;
    memset(&r, 0x5a, sizeof r);
    sidx_ray before = r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, 0), sidx_v3(0, 0, 0), 0, INFINITY), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, 0), sidx_v3(-0.0f, 0, -0.0f), 0, INFINITY), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_ray_init(&r, sidx_v3(NAN, 0, 0), sidx_v3(1, 0, 0), 0, INFINITY), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, 0), sidx_v3(INFINITY, 0, 0), 0, INFINITY), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, 0), sidx_v3(1, 0, 0), NAN, INFINITY), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, 0), sidx_v3(1, 0, 0), 2.0f, 1.0f), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_ray_init(NULL, sidx_v3(0, 0, 0), sidx_v3(1, 0, 0), 0, 1), SIDX_ERR_INVALID_ARG);
    assert_memory_equal(&r, &before, sizeof r); /* untouched on failure */
}

static void ray_init_precomputes_signs_and_inverse(void **state)
{
    (void)state;
    sidx_ray r = mkray(0, 0, 0, 2.0f, -0.0f, 0.0f);
    assert_float_equal(r.inv_dir.x, 0.5f, 0.0f);
    assert_true(isinf(r.inv_dir.y) && r.inv_dir.y < 0); /* 1/-0 = -inf, sign kept */
    assert_true(isinf(r.inv_dir.z) && r.inv_dir.z > 0);
    assert_int_equal(r.sign[0], 0);
    assert_int_equal(r.sign[1], 1); /* -0.0 counts as negative */
    assert_int_equal(r.sign[2], 0);
    assert_int_equal(r.kz, 0);      /* largest |d| component */
    assert_int_equal(sidx_status_str(SIDX_ERR_NOMEM)[0] != '\0', 1);
    assert_string_equal(sidx_status_str(SIDX_OK), "ok");
    assert_non_null(sidx_status_str((sidx_status)999));
}

/* ---- ray–plane (slide: t = (c − N·o)/(N·d)) ---------------------------- */

static void plane_slide_formula(void **state)
{
    (void)state;
    float t = -1;
    sidx_ray r = mkray(1, 1, 0, 0, 0, 1);
    assert_true(sidx_intersect_plane(&r, sidx_v3(0, 0, 1), 2.0f, &t));
    assert_float_equal(t, 2.0f, 0.0f);
    r = mkray(1, 1, 0, 0, 0, 2); /* unnormalized d: t in units of |d| */
    assert_true(sidx_intersect_plane(&r, sidx_v3(0, 0, 1), 2.0f, &t));
    assert_float_equal(t, 1.0f, 0.0f);
    /* N not unit: plane 2z = 4 is the same plane */
    assert_true(sidx_intersect_plane(&r, sidx_v3(0, 0, 2), 4.0f, &t));
    assert_float_equal(t, 1.0f, 0.0f);
    r = mkray(0, 0, 0, 1, 0, 0); /* parallel: N·d = 0 */
    assert_false(sidx_intersect_plane(&r, sidx_v3(0, 0, 1), 2.0f, &t));
    assert_false(sidx_intersect_plane(&r, sidx_v3(0, 0, 1), 0.0f, &t)); /* even inside the plane */
    r = mkray(0, 0, 5, 0, 0, 1); /* plane behind: t = -3 */
    assert_false(sidx_intersect_plane(&r, sidx_v3(0, 0, 1), 2.0f, &t));
}

/* ---- ray–triangle ------------------------------------------------------ */

static const sidx_vec3 A = {0, 0, 0}, B = {1, 0, 0}, C = {0, 1, 0}, D = {1, 1, 0};

static void triangle_worked_example(void **state)
{
    (void)state;
    /* o = (0.25, 0.5, 2), d = (0, 0, -1) against (0,0,0) (1,0,0) (0,1,0):
     * o + t d = (1−u−v)a + u b + v c  →  t = 2, u = 0.25, v = 0.5 */
    sidx_ray r = mkray(0.25f, 0.5f, 2.0f, 0, 0, -1);
    for (int m = 0; m < NMETHODS; ++m) {
        float t = 0, u = 0, v = 0;
        assert_true(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, &u, &v));
        assert_float_equal(t, 2.0f, 1e-6f);
        assert_float_equal(u, 0.25f, 1e-6f);
        assert_float_equal(v, 0.5f, 1e-6f);
    }
    /* an oblique, unnormalized direction */
    r = mkray(-1.0f, -1.0f, 1.0f, 1.2f, 1.4f, -1.0f); /* hits z=0 at t=1: (0.2, 0.4, 0) */
    for (int m = 0; m < NMETHODS; ++m) {
        float t = 0, u = 0, v = 0;
        assert_true(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, &u, &v));
        assert_float_equal(t, 1.0f, 1e-6f);
        assert_float_equal(u, 0.2f, 1e-6f);
        assert_float_equal(v, 0.4f, 1e-6f);
    }
}

static void triangle_miss_outside_and_behind(void **state)
{
    (void)state;
    float t;
    for (int m = 0; m < NMETHODS; ++m) {
        sidx_ray r = mkray(0.8f, 0.8f, 1.0f, 0, 0, -1); /* u + v > 1 */
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, NULL, NULL));
        r = mkray(0.25f, 0.25f, -1.0f, 0, 0, -1); /* "What if t is negative?" — behind the origin: miss */
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, NULL, NULL));
        r = mkray(0.25f, 0.25f, 2.0f, 0, 0, -1); /* beyond tmax */
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, B, C, 1.5f, &t, NULL, NULL));
        /* tmax is exclusive: a hit at exactly tmax does not replace an equal best */
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, B, C, 2.0f, &t, NULL, NULL));
        assert_true(sidx_intersect_triangle(all_methods[m], &r, A, B, C, nextafterf(2.0f, 3.0f), &t, NULL, NULL));
    }
}

static void triangle_degenerate_and_parallel(void **state)
{
    (void)state;
    float t;
    const sidx_vec3 p = {0.5f, 0.5f, 0};
    for (int m = 0; m < NMETHODS; ++m) {
        sidx_ray r = mkray(0.5f, 0.5f, 1.0f, 0, 0, -1);
        /* collinear vertices: zero area ("What if D = 0?") */
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, D, sidx_v3(2, 2, 0), INFINITY, &t, NULL, NULL));
        /* all three vertices equal */
        assert_false(sidx_intersect_triangle(all_methods[m], &r, p, p, p, INFINITY, &t, NULL, NULL));
        /* ray parallel to the plane, lying inside it */
        r = mkray(-1.0f, 0.25f, 0.0f, 1, 0, 0);
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, NULL, NULL));
        /* parallel, above the plane */
        r = mkray(-1.0f, 0.25f, 0.5f, 1, 0, 0);
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, NULL, NULL));
    }
}

static void watertight_edges_and_vertices_inclusive(void **state)
{
    (void)state;
    float t, u, v;
    /* The shared edge b–c of (a,b,c) and (b,d,c): a ray through its midpoint
     * hits both triangles (edges are inclusive), so it cannot leak. */
    sidx_ray r = mkray(0.5f, 0.5f, 1.0f, 0, 0, -1);
    assert_true(sidx_intersect_triangle_watertight(&r, A, B, C, INFINITY, &t, &u, &v));
    assert_float_equal(u + v, 1.0f, 1e-6f);
    assert_true(sidx_intersect_triangle_watertight(&r, B, D, C, INFINITY, &t, &u, &v));
    /* a vertex: u = v = 0 */
    r = mkray(0.0f, 0.0f, 1.0f, 0, 0, -1);
    assert_true(sidx_intersect_triangle_watertight(&r, A, B, C, INFINITY, &t, &u, &v));
    assert_float_equal(u, 0.0f, 0.0f);
    assert_float_equal(v, 0.0f, 0.0f);
    /* just outside an edge */
    r = mkray(nextafterf(0.5f, 1.0f), 0.5f, 1.0f, 0, 0, -1);
    assert_false(sidx_intersect_triangle_watertight(&r, A, B, C, INFINITY, &t, &u, &v));
}

static void watertight_never_leaks_through_a_fan(void **state)
{
    (void)state;
    /* A closed fan of 12 triangles around a vertex at an irrational-ish
     * position; rays aimed exactly at shared edges and at the centre vertex
     * from random-ish origins.  Watertight: every ray hits at least one. */
    sidx_vec3 center = {0.3141592f, -0.2718281f, 0.1234567f};
    sidx_vec3 ring[12];
    for (int i = 0; i < 12; ++i) {
        const float ang = (float)i * 6.2831853f / 12.0f;
        ring[i] = sidx_v3(center.x + 1.37f * cosf(ang), center.y + 0.91f * sinf(ang), center.z + 0.17f * cosf(3 * ang));
    }
    int leaks_w = 0, leaks_m = 0, rays = 0;
    for (int k = 0; k < 200; ++k) {
        const float s = (float)k / 200.0f;
        for (int e = 0; e < 12; ++e) {
            /* a point on edge center–ring[e] */
            sidx_vec3 target = sidx_v3_add(center, sidx_v3_scale(sidx_v3_sub(ring[e], center), s));
            sidx_vec3 org = sidx_v3(0.11f * (float)(k % 7) - 0.3f, 0.07f * (float)(k % 5) - 0.2f, 3.0f + 0.01f * (float)k);
            sidx_ray r;
            assert_int_equal(sidx_ray_init(&r, org, sidx_v3_sub(target, org), 0.0f, INFINITY), SIDX_OK);
            int hw = 0, hm = 0;
            for (int i = 0; i < 12; ++i) {
                float t;
                hw |= sidx_intersect_triangle_watertight(&r, center, ring[i], ring[(i + 1) % 12], INFINITY, &t, NULL, NULL);
                hm |= sidx_intersect_triangle_moller(&r, center, ring[i], ring[(i + 1) % 12], INFINITY, &t, NULL, NULL);
            }
            leaks_w += !hw;
            leaks_m += !hm;
            ++rays;
        }
    }
    print_message("fan: %d rays, watertight leaks %d, Moller-Trumbore leaks %d\n", rays, leaks_w, leaks_m);
    assert_int_equal(leaks_w, 0);
}

static void triangle_ray_starting_on_surface(void **state)
{
    (void)state;
    float t = -1;
    sidx_ray r;
    /* origin on the triangle, tmin = 0: hit at t = 0 (documented: to leave a
     * surface, start with tmin > 0) */
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, 0), sidx_v3(0, 0, -1), 0.0f, INFINITY), SIDX_OK);
    assert_true(sidx_intersect_triangle_watertight(&r, A, B, C, INFINITY, &t, NULL, NULL));
    assert_float_equal(t, 0.0f, 0.0f);
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, 0), sidx_v3(0, 0, -1), 1e-4f, INFINITY), SIDX_OK);
    for (int m = 0; m < NMETHODS; ++m)
        assert_false(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, NULL, NULL));
}

static void triangle_axis_rays_with_signed_zeros(void **state)
{
    (void)state;
    const float zs[2] = {0.0f, -0.0f};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            for (int m = 0; m < NMETHODS; ++m) {
                float t = 0, u = 0, v = 0;
                sidx_ray r = mkray(0.25f, 0.25f, 1.0f, zs[i], zs[j], -1.0f);
                assert_true(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, &u, &v));
                assert_float_equal(t, 1.0f, 0.0f);
                /* from below, +z */
                r = mkray(0.25f, 0.25f, -1.0f, zs[i], zs[j], 1.0f);
                assert_true(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t, &u, &v));
                /* along x with ±0 in y, z: a triangle in the x = 1 plane */
                r = mkray(-1.0f, 0.25f, 0.25f, 1.0f, zs[i], zs[j]);
                assert_true(sidx_intersect_triangle(all_methods[m], &r, sidx_v3(1, 0, 0), sidx_v3(1, 1, 0),
                                                    sidx_v3(1, 0, 1), INFINITY, &t, &u, &v));
                assert_float_equal(t, 2.0f, 1e-6f);
            }
}

static void triangle_both_windings(void **state)
{
    (void)state;
    /* No back-face culling: the reversed triangle is hit at the same t. */
    for (int m = 0; m < NMETHODS; ++m) {
        float t1 = 0, t2 = 0, u, v;
        sidx_ray r = mkray(0.2f, 0.3f, 1.0f, 0, 0, -1);
        assert_true(sidx_intersect_triangle(all_methods[m], &r, A, B, C, INFINITY, &t1, &u, &v));
        assert_true(sidx_intersect_triangle(all_methods[m], &r, A, C, B, INFINITY, &t2, &u, &v));
        assert_float_equal(t1, t2, 0.0f);
        assert_float_equal(u, 0.3f, 1e-6f); /* now c is the 2nd vertex */
    }
}

/* ---- boxes and other bounding volumes ----------------------------------- */

static const sidx_aabb unit_box = {{0, 0, 0}, {1, 1, 1}};

static void aabb_slab_test(void **state)
{
    (void)state;
    for (int m = 0; m < SIDX_BOX_METHOD_COUNT; ++m) {
        float tn = -1, tf = -1;
        sidx_ray r = mkray(-1, 0.5f, 0.5f, 1, 0, 0);
        assert_true(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, INFINITY, &tn, &tf));
        assert_float_equal(tn, 1.0f, 0.0f);
        assert_float_equal(tf, 2.0f, 1e-6f);
        if (m == SIDX_BOX_ROBUST) assert_true(tf > 2.0f); /* widened by 1 + 2γ₃ */
        else assert_float_equal(tf, 2.0f, 0.0f);
        /* ±0 components: no NaN, correct interval */
        r = mkray(-1, 0.5f, 0.5f, 1, -0.0f, 0.0f);
        assert_true(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, INFINITY, &tn, &tf));
        assert_float_equal(tn, 1.0f, 0.0f);
        r = mkray(-1, 2.0f, 0.5f, 1, -0.0f, 0.0f); /* outside the y slab, parallel to it */
        assert_false(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, INFINITY, &tn, &tf));
        /* origin exactly on the slab plane y = 1 (0·inf = NaN): counts as inside */
        r = mkray(-1, 1.0f, 0.5f, 1, 0.0f, 0.0f);
        assert_true(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, INFINITY, &tn, &tf));
        assert_false(isnan(tn) || isnan(tf));
        r = mkray(-1, 1.0f, 0.5f, 1, -0.0f, 0.0f);
        assert_true(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, INFINITY, &tn, &tf));
        /* starting inside: t_near clipped to tmin */
        r = mkray(0.5f, 0.5f, 0.5f, 0, 0, 1);
        assert_true(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, INFINITY, &tn, &tf));
        assert_float_equal(tn, 0.0f, 0.0f);
        assert_float_equal(tf, 0.5f, 1e-6f);
        /* box behind, and box beyond tmax */
        r = mkray(0.5f, 0.5f, 2.0f, 0, 0, 1);
        assert_false(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, INFINITY, &tn, &tf));
        r = mkray(-1, 0.5f, 0.5f, 1, 0, 0);
        assert_false(sidx_intersect_aabb((sidx_box_method)m, &r, &unit_box, 0, 0.5f, &tn, &tf));
        /* flat box (zero thickness in z) is still hit by a ray crossing it */
        const sidx_aabb flat = {{0, 0, 0}, {1, 1, 0}};
        r = mkray(0.5f, 0.5f, 1, 0, 0, -1);
        assert_true(sidx_intersect_aabb((sidx_box_method)m, &r, &flat, 0, INFINITY, &tn, &tf));
        assert_float_equal(tn, 1.0f, 0.0f);
    }
}

static void aabb_robust_keeps_grazing_hits(void **state)
{
    (void)state;
    /* Far from the origin, the plain test can compute t_near > t_far for a
     * ray grazing a box corner that it does touch in exact arithmetic; the
     * robust test must never lose a hit the plain test finds. */
    int plain = 0, robust = 0;
    for (int i = 0; i < 2000; ++i) {
        const float f = 1000.0f + (float)i * 0.37f;
        const sidx_aabb box = {{f, f, f}, {f + 1.0f, f + 1.0f, f + 1.0f}};
        sidx_ray r = mkray(0, 0, 0, f + 1.0f, f + 1.0f, f * (1.0f + 1e-7f * (float)(i % 13)));
        float tn, tf;
        plain += sidx_intersect_aabb(SIDX_BOX_PLAIN, &r, &box, 0, INFINITY, &tn, &tf);
        int rob = sidx_intersect_aabb(SIDX_BOX_ROBUST, &r, &box, 0, INFINITY, &tn, &tf);
        robust += rob;
        if (sidx_intersect_aabb(SIDX_BOX_PLAIN, &r, &box, 0, INFINITY, &tn, &tf)) assert_true(rob);
    }
    print_message("grazing boxes: plain %d hits, robust %d hits of 2000\n", plain, robust);
    assert_true(robust >= plain);
}

static void sphere_obb_kdop(void **state)
{
    (void)state;
    float tn, tf;
    const sidx_sphere s = {{0, 0, 0}, 1.0f};
    sidx_ray r = mkray(-3, 0, 0, 1, 0, 0);
    assert_true(sidx_intersect_sphere(&r, &s, 0, INFINITY, &tn, &tf));
    assert_float_equal(tn, 2.0f, 1e-6f);
    assert_float_equal(tf, 4.0f, 1e-6f);
    r = mkray(-3, 1.5f, 0, 1, 0, 0);
    assert_false(sidx_intersect_sphere(&r, &s, 0, INFINITY, &tn, &tf));
    r = mkray(0, 0, 0, 0, 0, 2); /* inside, unnormalized: exit at t = 0.5 */
    assert_true(sidx_intersect_sphere(&r, &s, 0, INFINITY, &tn, &tf));
    assert_float_equal(tn, 0.0f, 0.0f);
    assert_float_equal(tf, 0.5f, 1e-6f);

    /* OBB: unit half extents rotated 45° about z; the ray along x meets the
     * rotated square's corner at x = −√2. */
    const float h = 0.70710678f;
    const sidx_obb o = {{0, 0, 0}, {{h, h, 0}, {-h, h, 0}, {0, 0, 1}}, {1, 1, 1}};
    r = mkray(-3, 0, 0, 1, 0, 0);
    assert_true(sidx_intersect_obb(&r, &o, 0, INFINITY, &tn, &tf));
    assert_float_equal(tn, 3.0f - 1.41421356f, 1e-5f);
    assert_float_equal(tf, 3.0f + 1.41421356f, 1e-5f);
    r = mkray(-3, 1.5f, 0, 1, 0, 0); /* inside the AABB of the OBB (|y| ≤ √2) but outside the OBB */
    assert_false(sidx_intersect_obb(&r, &o, 0, INFINITY, &tn, &tf));

    /* 14-DOP around a tetrahedron is tighter than its AABB */
    const sidx_vec3 tet[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    sidx_kdop k;
    sidx_aabb box;
    assert_int_equal(sidx_kdop_fit(tet, 4, &k), SIDX_OK);
    assert_int_equal(sidx_aabb_fit(tet, 4, &box), SIDX_OK);
    r = mkray(0.9f, 0.9f, -1.0f, 0, 0, 1);
    assert_true(sidx_intersect_aabb(SIDX_BOX_ROBUST, &r, &box, 0, INFINITY, &tn, &tf));
    assert_false(sidx_intersect_kdop(&r, &k, 0, INFINITY, &tn, &tf));
    r = mkray(0.1f, 0.1f, -1.0f, 0, 0, 1);
    assert_true(sidx_intersect_kdop(&r, &k, 0, INFINITY, &tn, &tf));
    assert_float_equal(tn, 1.0f, 1e-5f);
    assert_float_equal(tf, 1.8f, 1e-5f); /* exits through x + y + z = 1 at z = 0.8 */
}

static void fits_contain_their_points(void **state)
{
    (void)state;
    /* a thin rod along (1,1,1): the OBB is much tighter than the AABB */
    sidx_vec3 p[200];
    for (int i = 0; i < 200; ++i) {
        const float s = (float)i / 199.0f * 10.0f;
        const float w = 0.05f * (float)((i * 7) % 5 - 2);
        p[i] = sidx_v3(s + w, s - w, s + 0.5f * w);
    }
    sidx_aabb box;
    sidx_sphere sph;
    sidx_obb obb;
    sidx_kdop k;
    assert_int_equal(sidx_aabb_fit(p, 200, &box), SIDX_OK);
    assert_int_equal(sidx_sphere_fit(p, 200, &sph), SIDX_OK);
    assert_int_equal(sidx_obb_fit(p, 200, &obb), SIDX_OK);
    assert_int_equal(sidx_kdop_fit(p, 200, &k), SIDX_OK);
    for (int i = 0; i < 200; ++i) {
        assert_true(sidx_v3_length(sidx_v3_sub(p[i], sph.center)) <= sph.radius);
        for (int a = 0; a < 3; ++a) {
            const float d = sidx_v3_dot(sidx_v3_sub(p[i], obb.center), obb.axis[a]);
            assert_true(fabsf(d) <= sidx_v3_get(obb.half, a) * 1.0001f + 1e-5f);
        }
        for (int a = 0; a < SIDX_KDOP_AXES; ++a) {
            const float d = sidx_v3_dot(sidx_kdop_axis(a), p[i]);
            assert_true(d >= k.lo[a] && d <= k.hi[a]);
        }
    }
    assert_true(sidx_obb_area(&obb) < 0.25f * sidx_aabb_area(box));
    assert_int_equal(sidx_obb_fit(NULL, 3, &obb), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_sphere_fit(p, 0, &sph), SIDX_ERR_INVALID_ARG);
}

static void method_names_round_trip(void **state)
{
    (void)state;
    for (int m = 0; m < SIDX_TRI_METHOD_COUNT; ++m) {
        sidx_tri_method back;
        assert_int_equal(sidx_tri_method_parse(sidx_tri_method_name((sidx_tri_method)m), &back), SIDX_OK);
        assert_int_equal(back, m);
    }
    for (int m = 0; m < SIDX_BOX_METHOD_COUNT; ++m) {
        sidx_box_method back;
        assert_int_equal(sidx_box_method_parse(sidx_box_method_name((sidx_box_method)m), &back), SIDX_OK);
        assert_int_equal(back, m);
    }
    sidx_tri_method tm;
    assert_int_equal(sidx_tri_method_parse("fast", &tm), SIDX_ERR_INVALID_ARG);
    assert_null(sidx_tri_method_name((sidx_tri_method)7));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ray_init_rejects_bad_input),
        cmocka_unit_test(ray_init_precomputes_signs_and_inverse),
        cmocka_unit_test(plane_slide_formula),
        cmocka_unit_test(triangle_worked_example),
        cmocka_unit_test(triangle_miss_outside_and_behind),
        cmocka_unit_test(triangle_degenerate_and_parallel),
        cmocka_unit_test(watertight_edges_and_vertices_inclusive),
        cmocka_unit_test(watertight_never_leaks_through_a_fan),
        cmocka_unit_test(triangle_ray_starting_on_surface),
        cmocka_unit_test(triangle_axis_rays_with_signed_zeros),
        cmocka_unit_test(triangle_both_windings),
        cmocka_unit_test(aabb_slab_test),
        cmocka_unit_test(aabb_robust_keeps_grazing_hits),
        cmocka_unit_test(sphere_obb_kdop),
        cmocka_unit_test(fits_contain_their_points),
        cmocka_unit_test(method_names_round_trip),
    };
    return cmocka_run_group_tests_name("intersect", tests, NULL, NULL);
}
