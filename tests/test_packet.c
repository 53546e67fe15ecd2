/* test_packet.c — packets of coherent rays and frustum culling.
 *
 *  - 4x4 and 8x8 tiles of primary rays, plain packets and frustum packets,
 *    AVX2 and scalar kernels: every ray's closest hit agrees with the
 *    single-ray BVH (same prim, or same t within 1e-5 relative — an exact
 *    tie of two triangles may resolve differently), on every built-in scene;
 *  - a camera inside the closed icosphere: every packet ray hits (no leaks);
 *  - shadow packets to a point light (any-hit) agree with single rays;
 *  - incoherent packets (random directions) fall back to single rays and
 *    still agree; other structures (bvh8, kdtree) work through the fallback;
 *  - frustum culling saves ray-box tests against plain packets;
 *  - NULL / oversized arguments are rejected.
 * Wide BVHs ("bvh4", "bvh8", packet_wide.c), AVX2 and scalar kernels:
 *  - tiles (4x4, 8x8, plain and frustum) give exactly the single-ray hit
 *    of the same structure (same prim, same t, same u, v) and agree with
 *    brute force, on every built-in scene and from inside the icosphere;
 *  - tiles straddling an axis are walked once per sign class, and rays
 *    with a zero direction component (no interval test) still agree;
 *  - shadow packets (any-hit) equal single-ray occlusion;
 *  - the interval test culls children for whole packets. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sidx/sidx.h"
#include "sidx/packet.h"
#include "common/testkit.h"

static const char *const scenes[] = {"icosphere", "teapot", "soup", "menger", "stadium", "cornell"};
#define NSCENES (sizeof scenes / sizeof scenes[0])

/* The dense soup: many triangles per pixel of the small images below (at
 * the small sizes, fewer triangles for fewer pixels). */
static uint32_t dense_soup(void) { return tk_fast_tests() ? 12000u : 40000u; }

static sidx_mesh scene(const char *name)
{
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make(name, 0, &m, &err) != SIDX_OK) fail_msg("scene %s: %s", name, err.message);
    return m;
}

/* A pinhole camera: W x H rays from eye towards look, row-major. */
static void camera(sidx_vec3 eye, sidx_vec3 look, float fov_tan, uint32_t W, uint32_t H, sidx_ray *out)
{
    const sidx_vec3 fwd = sidx_v3_sub(look, eye);
    const float fl = sidx_v3_length(fwd);
    const sidx_vec3 f = sidx_v3_scale(fwd, 1.0f / fl);
    sidx_vec3 right = sidx_v3_cross(f, sidx_v3(0, 1, 0));
    right = sidx_v3_scale(right, 1.0f / sidx_v3_length(right));
    const sidx_vec3 up = sidx_v3_cross(right, f);
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
            const float u = ((x + 0.5f) / W * 2.0f - 1.0f) * fov_tan, v = (1.0f - (y + 0.5f) / H * 2.0f) * fov_tan;
            const sidx_vec3 d = sidx_v3_add(f, sidx_v3_add(sidx_v3_scale(right, u), sidx_v3_scale(up, v)));
            assert_int_equal(sidx_ray_init(&out[y * W + x], eye, d, 0.0f, INFINITY), SIDX_OK);
        }
}

static void primary_rays(const sidx_mesh *m, uint32_t W, uint32_t H, sidx_ray *out)
{
    const sidx_aabb b = sidx_mesh_bounds(m);
    const sidx_vec3 c = sidx_aabb_centroid(b);
    const float r = 0.5f * sidx_v3_length(sidx_aabb_extent(b));
    camera(sidx_v3_add(c, sidx_v3(0.9f * r, 0.7f * r, 2.0f * r)), c, 0.45f, W, H, out);
}

static void check_tiles(const char *label, const sidx_accel *a, const sidx_accel *ref, const sidx_ray *rays,
                        uint32_t W, uint32_t H, int require_hit)
{
    const size_t n = (size_t)W * H;
    sidx_hit *h = malloc(n * sizeof *h), *r = malloc(n * sizeof *r);
    assert_non_null(h);
    assert_non_null(r);
    for (size_t i = 0; i < n; ++i) sidx_accel_intersect(ref, &rays[i], NULL, &r[i]);
    const uint32_t tiles[] = {4, 8};
    const sidx_packet_mode modes[] = {SIDX_PACKET_PLAIN, SIDX_PACKET_FRUSTUM, SIDX_PACKET_SINGLE};
    for (int simd = 0; simd < 2; ++simd) {
        if (!simd) setenv("SIDX_SIMD", "scalar", 1);
        for (int t = 0; t < 2; ++t)
            for (int md = 0; md < 3; ++md) {
                const sidx_packet_options o = {modes[md], 0, 0};
                sidx_packet_stats st;
                memset(&st, 0, sizeof st);
                memset(h, 0xCD, n * sizeof *h);
                assert_int_equal(sidx_trace_tiles(a, rays, W, H, tiles[t], &o, h, &st), SIDX_OK);
                for (size_t i = 0; i < n; ++i) {
                    if (!tk_hits_agree(&r[i], &h[i]))
                        fail_msg("%s simd %d tile %u mode %d ray %zu: prim %u t %.9g, single prim %u t %.9g", label,
                                 simd, tiles[t], md, i, h[i].prim, (double)h[i].t, r[i].prim, (double)r[i].t);
                    if (require_hit && h[i].prim == SIDX_NO_HIT) fail_msg("%s: leak at ray %zu", label, i);
                }
            }
        unsetenv("SIDX_SIMD");
    }
    free(h);
    free(r);
}

static void test_primary_tiles_match_single(void **state)
{
    (void)state;
    const uint32_t W = 48, H = 40; /* edge tiles are partial */
    sidx_ray *rays = malloc((size_t)W * H * sizeof *rays);
    assert_non_null(rays);
    for (size_t si = 0; si < NSCENES; ++si) {
        sidx_mesh m = scene(scenes[si]);
        primary_rays(&m, W, H, rays);
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build("bvh", &m, NULL, &a, NULL), SIDX_OK);
        check_tiles(scenes[si], a, a, rays, W, H, 0);
        sidx_accel_destroy(a);
        sidx_mesh_free(&m);
    }
    free(rays);
}

static void test_inside_icosphere_no_leaks(void **state)
{
    (void)state;
    sidx_mesh m = scene("icosphere");
    const uint32_t W = 32, H = 32;
    sidx_ray *rays = malloc((size_t)W * H * sizeof *rays);
    assert_non_null(rays);
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("bvh", &m, NULL, &a, NULL), SIDX_OK);
    const sidx_vec3 looks[] = {{1, 0.1f, 0.2f}, {-0.3f, 1, 0.05f}, {0.2f, -0.4f, -1}};
    for (int k = 0; k < 3; ++k) {
        camera(sidx_v3(0.013f, -0.007f, 0.003f), looks[k], 1.3f, W, H, rays);
        check_tiles("inside icosphere", a, a, rays, W, H, 1);
    }
    sidx_accel_destroy(a);
    free(rays);
    sidx_mesh_free(&m);
}

static void test_shadow_packets(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    const uint32_t W = 32, H = 32, n = W * H;
    sidx_ray *prim = malloc(n * sizeof *prim), *shadow = malloc(n * sizeof *shadow);
    uint8_t *occ = malloc(n);
    assert_non_null(prim);
    assert_non_null(shadow);
    assert_non_null(occ);
    primary_rays(&m, W, H, prim);
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("bvh", &m, NULL, &a, NULL), SIDX_OK);
    const sidx_aabb b = sidx_mesh_bounds(&m);
    const sidx_vec3 light = sidx_v3_add(b.max, sidx_aabb_extent(b));
    uint32_t ns = 0;
    for (uint32_t i = 0; i < n; ++i) {
        sidx_hit h;
        sidx_accel_intersect(a, &prim[i], NULL, &h);
        if (h.prim == SIDX_NO_HIT) continue;
        const sidx_vec3 p = sidx_ray_at(&prim[i], h.t);
        assert_int_equal(sidx_ray_init(&shadow[ns++], p, sidx_v3_sub(light, p), 1e-4f, 1.0f), SIDX_OK);
    }
    assert_true(ns > 64);
    sidx_packet_stats st;
    memset(&st, 0, sizeof st);
    for (int simd = 0; simd < 2; ++simd) {
        if (!simd) setenv("SIDX_SIMD", "scalar", 1);
        for (uint32_t base = 0; base < ns; base += 16) {
            const uint32_t cnt = ns - base < 16 ? ns - base : 16;
            const sidx_packet_options o = {SIDX_PACKET_PLAIN, 0, 0};
            assert_int_equal(sidx_packet_occluded(a, shadow + base, cnt, 0, &o, occ + base, &st), SIDX_OK);
            for (uint32_t i = 0; i < cnt; ++i) {
                int ref;
                sidx_accel_occluded(a, &shadow[base + i], NULL, &ref);
                assert_int_equal(occ[base + i], ref);
            }
        }
        unsetenv("SIDX_SIMD");
    }
    assert_true(st.packets > st.single_packets); /* shadow rays to one light share signs mostly */
    sidx_accel_destroy(a);
    free(prim);
    free(shadow);
    free(occ);
    sidx_mesh_free(&m);
}

static void test_incoherent_and_other_structures(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    const uint32_t n = 64;
    tk_rayrec rec[64];
    sidx_ray rays[64];
    sidx_hit h[64], r[64];
    tk_make_rays(&m, TK_RAYS_DIFFUSE, n, 9, rec);
    for (uint32_t i = 0; i < n; ++i) assert_int_equal(tk_ray_from(&rec[i], &rays[i]), SIDX_OK);
    const char *names[] = {"bvh", "bvh8", "kdtree"};
    for (int k = 0; k < 3; ++k) {
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build(names[k], &m, NULL, &a, NULL), SIDX_OK);
        sidx_packet_stats st;
        memset(&st, 0, sizeof st);
        assert_int_equal(sidx_packet_intersect(a, rays, n, 8, NULL, h, &st), SIDX_OK);
        /* the binary walk traces mixed signs ray by ray, the wide one once per sign class */
        assert_int_equal(st.single_packets, k == 1 ? 0 : 1);
        assert_int_equal(st.split_packets, k == 1 ? 1 : 0);
        for (uint32_t i = 0; i < n; ++i) {
            sidx_accel_intersect(a, &rays[i], NULL, &r[i]);
            assert_true(tk_hits_agree(&r[i], &h[i]));
        }
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

static void test_frustum_saves_box_tests(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    const uint32_t W = 64, H = 64;
    sidx_ray *rays = malloc((size_t)W * H * sizeof *rays);
    sidx_hit *h = malloc((size_t)W * H * sizeof *h);
    assert_non_null(rays);
    assert_non_null(h);
    primary_rays(&m, W, H, rays);
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("bvh", &m, NULL, &a, NULL), SIDX_OK);
    sidx_packet_stats plain, fr;
    memset(&plain, 0, sizeof plain);
    memset(&fr, 0, sizeof fr);
    const sidx_packet_options op = {SIDX_PACKET_PLAIN, 0, 0}, of = {SIDX_PACKET_FRUSTUM, 0, 0};
    assert_int_equal(sidx_trace_tiles(a, rays, W, H, 8, &op, h, &plain), SIDX_OK);
    assert_int_equal(sidx_trace_tiles(a, rays, W, H, 8, &of, h, &fr), SIDX_OK);
    assert_int_equal(plain.frustum_tests, 0);
    assert_true(fr.frustum_culls > 0);
    assert_true(fr.box_tests < plain.box_tests);
    print_message("teapot 64x64, 8x8 tiles: plain %llu ray-box tests, frustum %llu (+%llu frustum tests, %llu culls)\n",
                  (unsigned long long)plain.box_tests, (unsigned long long)fr.box_tests,
                  (unsigned long long)fr.frustum_tests, (unsigned long long)fr.frustum_culls);
    sidx_accel_destroy(a);
    free(rays);
    free(h);
    sidx_mesh_free(&m);
}

/* A dense mesh seen from afar (many triangles per pixel): rays part deep
 * in the tree, so rays finish subtrees alone (the adaptive switch, both
 * the last-group rule and the whole-packet rule below SWITCH_DEPTH), and
 * the hits must still be those of single rays, closest and any-hit.  Also:
 * 4x4 tiles never use the frustum (it could replace one group test at
 * most), 8x8 tiles do. */
static void test_dense_mesh_switch(void **state)
{
    (void)state;
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make("soup", dense_soup(), &m, &err) != SIDX_OK) fail_msg("soup: %s", err.message);
    const uint32_t W = tk_fast_tests() ? 24 : 40, H = W;
    sidx_ray *rays = malloc((size_t)W * H * sizeof *rays);
    assert_non_null(rays);
    primary_rays(&m, W, H, rays);
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("bvh", &m, NULL, &a, NULL), SIDX_OK);
    check_tiles("dense soup", a, a, rays, W, H, 0);
    sidx_hit *h = malloc((size_t)W * H * sizeof *h);
    assert_non_null(h);
    const sidx_packet_options of = {SIDX_PACKET_FRUSTUM, 0, 0};
    sidx_packet_stats s4, s8;
    memset(&s4, 0, sizeof s4);
    memset(&s8, 0, sizeof s8);
    assert_int_equal(sidx_trace_tiles(a, rays, W, H, 4, &of, h, &s4), SIDX_OK);
    assert_int_equal(sidx_trace_tiles(a, rays, W, H, 8, &of, h, &s8), SIDX_OK);
    assert_int_equal(s4.frustum_tests, 0);
    assert_true(s8.frustum_tests > 0);
    assert_true(s4.switched_rays > 0);
    assert_true(s8.switched_rays > 0);
    sidx_accel_destroy(a);
    free(h);
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- wide BVHs ---------------------------------------------------------------------- */

/* Same prim, same t (bit for bit), same u, v when asked. */
static int hits_identical(const sidx_hit *a, const sidx_hit *b, int uv)
{
    if (a->prim != b->prim) return 0;
    if (a->prim == SIDX_NO_HIT) return 1;
    if (memcmp(&a->t, &b->t, sizeof a->t)) return 0;
    return !uv || (!memcmp(&a->u, &b->u, sizeof a->u) && !memcmp(&a->v, &b->v, sizeof a->v));
}

/* Every tile size and mode, AVX2 and scalar kernels: against the single
 * ray of the same structure exactly, against brute force up to ties. */
static void check_wide_tiles(const char *label, const sidx_accel *a, const sidx_accel *brute, const sidx_ray *rays,
                             uint32_t W, uint32_t H, int require_hit, sidx_packet_stats *total)
{
    const size_t n = (size_t)W * H;
    sidx_hit *h = malloc(n * sizeof *h), *r = malloc(n * sizeof *r), *bf = malloc(n * sizeof *bf);
    assert_non_null(h);
    assert_non_null(r);
    assert_non_null(bf);
    const sidx_query quv = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    for (size_t i = 0; i < n; ++i) {
        sidx_accel_intersect(a, &rays[i], &quv, &r[i]);
        sidx_accel_intersect(brute, &rays[i], NULL, &bf[i]);
        if (!tk_hits_agree(&bf[i], &r[i])) fail_msg("%s ray %zu: single ray disagrees with brute force", label, i);
    }
    const uint32_t tiles[] = {4, 8};
    const sidx_packet_mode modes[] = {SIDX_PACKET_PLAIN, SIDX_PACKET_FRUSTUM};
    size_t near_ties = 0, compared = 0;
    for (int simd = 0; simd < 2; ++simd) {
        if (!simd) setenv("SIDX_SIMD", "scalar", 1);
        for (int t = 0; t < 2; ++t)
            for (int md = 0; md < 2; ++md)
                for (int uv = 0; uv < 2; ++uv) {
                    const sidx_packet_options o = {modes[md], 0, uv ? SIDX_QUERY_UV : 0};
                    sidx_packet_stats st;
                    memset(&st, 0, sizeof st);
                    memset(h, 0xCD, n * sizeof *h);
                    assert_int_equal(sidx_trace_tiles(a, rays, W, H, tiles[t], &o, h, &st), SIDX_OK);
                    assert_int_equal(st.single_packets, 0);
                    for (size_t i = 0; i < n; ++i) {
                        /* Counted, and reported below: a near tie (two
                         * triangles within a few ulps of t) resolved
                         * differently would mean one walk dropped the box of
                         * the nearer one (see test_single_rays_keep_nearest).  Then both must still agree
                         * with brute force up to the tie tolerance. */
                        if (!hits_identical(&r[i], &h[i], uv) &&
                            (++near_ties, !tk_hits_agree(&r[i], &h[i]) || !tk_hits_agree(&bf[i], &r[i])))
                            fail_msg("%s simd %d tile %u mode %d uv %d ray %zu: prim %u t %.9g, single prim %u t %.9g",
                                     label, simd, tiles[t], md, uv, i, h[i].prim, (double)h[i].t, r[i].prim,
                                     (double)r[i].t);
                        if (!tk_hits_agree(&bf[i], &h[i])) fail_msg("%s ray %zu: brute force disagrees", label, i);
                        if (require_hit && h[i].prim == SIDX_NO_HIT) fail_msg("%s: leak at ray %zu", label, i);
                    }
                    compared += n;
                    if (total) {
                        total->packets += st.packets;
                        total->split_packets += st.split_packets;
                        total->interval_tests += st.interval_tests;
                        total->interval_culls += st.interval_culls;
                    }
                }
        unsetenv("SIDX_SIMD");
    }
    /* Packets and single rays both widen the best t for their box tests
     * (Ize's factor), so neither drops the nearer triangle of a near tie:
     * none may differ at all (before the widening, 16 of 25,600 soup hits did). */
    if (near_ties) fail_msg("%s: %zu of %zu hits differ from single rays", label, near_ties, compared);
    free(h);
    free(r);
    free(bf);
}

static void test_wide_tiles_match_single(void **state)
{
    (void)state;
    const uint32_t W = tk_fast_tests() ? 22 : 48, H = tk_fast_tests() ? 18 : 40;
    sidx_ray *rays = malloc((size_t)W * H * sizeof *rays);
    assert_non_null(rays);
    const char *names[] = {"bvh4", "bvh8"};
    for (size_t si = 0; si < NSCENES; ++si) {
        sidx_mesh m = scene(scenes[si]);
        primary_rays(&m, W, H, rays);
        sidx_accel *brute = NULL;
        assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
        for (int k = 0; k < 2; ++k) {
            sidx_accel *a = NULL;
            assert_int_equal(sidx_accel_build(names[k], &m, NULL, &a, NULL), SIDX_OK);
            char label[64];
            snprintf(label, sizeof label, "%s %s", scenes[si], names[k]);
            sidx_packet_stats st;
            memset(&st, 0, sizeof st);
            check_wide_tiles(label, a, brute, rays, W, H, 0, &st);
            assert_true(st.interval_tests > 0);
            sidx_accel_destroy(a);
        }
        sidx_accel_destroy(brute);
        sidx_mesh_free(&m);
    }
    free(rays);
}

/* From inside the closed icosphere, looking along axes and between them:
 * every ray hits (no leaks), tiles straddle the axes (split by sign
 * class), and with an odd image width looking down -z the middle column
 * has d.x = 0 exactly (inverse direction inf: those packets skip the
 * interval test). */
static void test_wide_inside_and_axis_rays(void **state)
{
    (void)state;
    sidx_mesh m = scene("icosphere");
    const uint32_t W = 33, H = 31;
    sidx_ray *rays = malloc((size_t)W * H * sizeof *rays);
    assert_non_null(rays);
    sidx_accel *brute = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    const sidx_vec3 looks[] = {{1, 0.1f, 0.2f}, {-0.3f, 1, 0.05f}, {0.013f, -0.007f, -1}};
    const char *names[] = {"bvh4", "bvh8"};
    for (int k = 0; k < 2; ++k) {
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build(names[k], &m, NULL, &a, NULL), SIDX_OK);
        sidx_packet_stats st;
        memset(&st, 0, sizeof st);
        for (int l = 0; l < 3; ++l) {
            camera(sidx_v3(0.013f, -0.007f, 0.003f), looks[l], 1.3f, W, H, rays);
            check_wide_tiles("inside icosphere", a, brute, rays, W, H, 1, &st);
        }
        assert_true(st.split_packets > 0);
        int zero_dir = 0;
        for (size_t i = 0; i < (size_t)W * H; ++i) zero_dir |= rays[i].dir.x == 0.0f;
        assert_true(zero_dir); /* the last camera really has axis-parallel rays */
        sidx_accel_destroy(a);
    }
    sidx_accel_destroy(brute);
    free(rays);
    sidx_mesh_free(&m);
}

/* Shadow rays from the teapot's visible points to a point light, as
 * packets of 16 and 64, AVX2 and scalar: occlusion equals single rays. */
static void test_wide_shadow_packets(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    const uint32_t W = 32, H = 32, n = W * H;
    sidx_ray *prim = malloc(n * sizeof *prim), *shadow = malloc(n * sizeof *shadow);
    uint8_t *occ = malloc(n);
    assert_non_null(prim);
    assert_non_null(shadow);
    assert_non_null(occ);
    primary_rays(&m, W, H, prim);
    const sidx_aabb b = sidx_mesh_bounds(&m);
    const sidx_vec3 light = sidx_v3_add(b.max, sidx_aabb_extent(b));
    const char *names[] = {"bvh4", "bvh8"};
    for (int k = 0; k < 2; ++k) {
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build(names[k], &m, NULL, &a, NULL), SIDX_OK);
        uint32_t ns = 0, nocc = 0;
        for (uint32_t i = 0; i < n; ++i) {
            sidx_hit h;
            sidx_accel_intersect(a, &prim[i], NULL, &h);
            if (h.prim == SIDX_NO_HIT) continue;
            const sidx_vec3 p = sidx_ray_at(&prim[i], h.t);
            assert_int_equal(sidx_ray_init(&shadow[ns++], p, sidx_v3_sub(light, p), 1e-4f, 1.0f), SIDX_OK);
        }
        assert_true(ns > 64);
        for (int simd = 0; simd < 2; ++simd) {
            if (!simd) setenv("SIDX_SIMD", "scalar", 1);
            for (uint32_t size = 16; size <= 64; size *= 4)
                for (uint32_t base = 0; base < ns; base += size) {
                    const uint32_t cnt = ns - base < size ? ns - base : size;
                    const sidx_packet_options o = {SIDX_PACKET_PLAIN, 0, 0};
                    sidx_packet_stats st;
                    memset(&st, 0, sizeof st);
                    assert_int_equal(sidx_packet_occluded(a, shadow + base, cnt, 0, &o, occ + base, &st), SIDX_OK);
                    assert_int_equal(st.single_packets, 0);
                    for (uint32_t i = 0; i < cnt; ++i) {
                        int ref;
                        sidx_accel_occluded(a, &shadow[base + i], NULL, &ref);
                        assert_int_equal(occ[base + i], ref);
                        nocc += (uint32_t)ref;
                    }
                }
            unsetenv("SIDX_SIMD");
        }
        assert_true(nocc > 0); /* the spout and handle shadow the body */
        sidx_accel_destroy(a);
    }
    free(prim);
    free(shadow);
    free(occ);
    sidx_mesh_free(&m);
}

/* Near ties in single-ray walks (Ize 2013 applied to the best hit too): in
 * the dense soup two triangles can lie an ulp apart in t, and the nearer
 * one's box can have a ROUNDED entry an ulp beyond the farther hit already
 * found.  Clipping boxes to the unwidened best dropped that box (16 of
 * these rays kept the farther triangle); with best widened by 1 + 2γ₃ every
 * single-ray walk returns exactly brute force's t.  Brute force applies
 * the same triangle test to every triangle, so its t is the true minimum
 * of the per-triangle values, and the walks must reproduce it bit for bit
 * (the prim may differ only between triangles with equal t). */
static void test_single_rays_keep_nearest(void **state)
{
    (void)state;
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make("soup", dense_soup(), &m, &err) != SIDX_OK) fail_msg("soup: %s", err.message);
    const uint32_t W = tk_fast_tests() ? 32 : 160, H = W; /* brute force: W * H * dense_soup() triangle tests */
    const size_t n = (size_t)W * H;
    sidx_ray *rays = malloc(n * sizeof *rays);
    sidx_hit *ref = malloc(n * sizeof *ref);
    assert_non_null(rays);
    assert_non_null(ref);
    primary_rays(&m, W, H, rays);
    sidx_accel *brute = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    for (size_t i = 0; i < n; ++i) sidx_accel_intersect(brute, &rays[i], NULL, &ref[i]);
    static const char *const names[] = {"bvh", "bvh4", "bvh8"};
    for (int k = 0; k < 3; ++k) {
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build(names[k], &m, NULL, &a, NULL), SIDX_OK);
        size_t bad = 0;
        for (size_t i = 0; i < n; ++i) {
            sidx_hit h;
            sidx_accel_intersect(a, &rays[i], NULL, &h);
            const int same = (h.prim == SIDX_NO_HIT) == (ref[i].prim == SIDX_NO_HIT) &&
                             (h.prim == SIDX_NO_HIT || memcmp(&h.t, &ref[i].t, sizeof h.t) == 0);
            if (!same && bad++ < 3)
                print_message("%s ray %zu: prim %u t %.9g, brute force prim %u t %.9g\n", names[k], i, h.prim,
                              (double)h.t, ref[i].prim, (double)ref[i].t);
        }
        if (bad) fail_msg("%s: %zu of %zu rays differ from brute force's nearest t", names[k], bad, n);
        sidx_accel_destroy(a);
    }
    sidx_accel_destroy(brute);
    sidx_mesh_free(&m);
    free(rays);
    free(ref);
}

/* A dense mesh from afar (many triangles per pixel, rays part deep in the
 * tree): exact agreement with single rays, and the interval test culls
 * children for whole packets. */
static void test_wide_dense_mesh(void **state)
{
    (void)state;
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make("soup", dense_soup(), &m, &err) != SIDX_OK) fail_msg("soup: %s", err.message);
    const uint32_t W = tk_fast_tests() ? 24 : 40, H = W;
    sidx_ray *rays = malloc((size_t)W * H * sizeof *rays);
    assert_non_null(rays);
    primary_rays(&m, W, H, rays);
    sidx_accel *brute = NULL, *a = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    assert_int_equal(sidx_accel_build("bvh8", &m, NULL, &a, NULL), SIDX_OK);
    sidx_packet_stats st;
    memset(&st, 0, sizeof st);
    check_wide_tiles("dense soup bvh8", a, brute, rays, W, H, 0, &st);
    assert_true(st.interval_culls > 0);
    assert_true(st.interval_culls < st.interval_tests);
    print_message("soup %u, bvh8: interval test culled %llu of %llu child boxes\n", (unsigned)m.num_triangles,
                  (unsigned long long)st.interval_culls, (unsigned long long)st.interval_tests);
    sidx_accel_destroy(a);
    sidx_accel_destroy(brute);
    free(rays);
    sidx_mesh_free(&m);
}

/* Rays aimed exactly at vertices and edge points (grazing, incoherent:
 * packets of up to 8 sign classes), so edge functions of exactly 0 send
 * blocks to the scalar fallback: packets of 64 equal single rays. */
static void test_wide_grazing_packets(void **state)
{
    (void)state;
    const char *scn[] = {"teapot", "icosphere", "cornell"};
    const char *names[] = {"bvh4", "bvh8"};
    enum { NR = 1024 };
    static tk_rayrec rec[NR];
    static sidx_ray rays[NR];
    static sidx_hit h[NR], r[NR];
    for (int si = 0; si < 3; ++si) {
        sidx_mesh m = scene(scn[si]);
        tk_make_rays(&m, TK_RAYS_GRAZING, NR, 5, rec);
        uint32_t n = 0;
        for (uint32_t i = 0; i < NR; ++i)
            if (tk_ray_from(&rec[i], &rays[n]) == SIDX_OK) ++n;
        for (int k = 0; k < 2; ++k) {
            sidx_accel *a = NULL;
            assert_int_equal(sidx_accel_build(names[k], &m, NULL, &a, NULL), SIDX_OK);
            for (uint32_t i = 0; i < n; ++i) sidx_accel_intersect(a, &rays[i], NULL, &r[i]);
            for (int simd = 0; simd < 2; ++simd) {
                if (!simd) setenv("SIDX_SIMD", "scalar", 1);
                sidx_packet_stats st;
                memset(&st, 0, sizeof st);
                for (uint32_t base = 0; base < n; base += 64) {
                    const uint32_t cnt = n - base < 64 ? n - base : 64;
                    assert_int_equal(sidx_packet_intersect(a, rays + base, cnt, 0, NULL, h + base, &st), SIDX_OK);
                }
                for (uint32_t i = 0; i < n; ++i)
                    if (!hits_identical(&r[i], &h[i], 0) && !tk_hits_agree(&r[i], &h[i]))
                        fail_msg("%s %s simd %d grazing ray %u: prim %u t %.9g, single prim %u t %.9g", scn[si],
                                 names[k], simd, i, h[i].prim, (double)h[i].t, r[i].prim, (double)r[i].t);
                assert_true(st.split_packets > 0);
                unsetenv("SIDX_SIMD");
            }
            sidx_accel_destroy(a);
        }
        sidx_mesh_free(&m);
    }
}

static void test_invalid_arguments(void **state)
{
    (void)state;
    sidx_mesh m = scene("cornell");
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("bvh", &m, NULL, &a, NULL), SIDX_OK);
    sidx_ray r[65];
    sidx_hit h[65];
    uint8_t o[65];
    for (int i = 0; i < 65; ++i) assert_int_equal(sidx_ray_init(&r[i], sidx_v3(0, 0, 0), sidx_v3(0, 0, 1), 0, INFINITY), SIDX_OK);
    assert_int_equal(sidx_packet_intersect(NULL, r, 4, 2, NULL, h, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_packet_intersect(a, NULL, 4, 2, NULL, h, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_packet_intersect(a, r, 4, 2, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_packet_intersect(a, r, 65, 0, NULL, h, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_packet_occluded(a, r, 4, 0, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_packet_occluded(a, r, 4, 0, NULL, o, NULL), SIDX_OK);
    assert_int_equal(sidx_packet_intersect(a, r, 0, 0, NULL, h, NULL), SIDX_OK);
    assert_int_equal(sidx_trace_tiles(a, r, 8, 8, 9, NULL, h, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_trace_tiles(a, r, 8, 8, 0, NULL, h, NULL), SIDX_ERR_INVALID_ARG);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_primary_tiles_match_single), cmocka_unit_test(test_inside_icosphere_no_leaks),
        cmocka_unit_test(test_shadow_packets),             cmocka_unit_test(test_incoherent_and_other_structures),
        cmocka_unit_test(test_frustum_saves_box_tests),    cmocka_unit_test(test_invalid_arguments),
        cmocka_unit_test(test_dense_mesh_switch),          cmocka_unit_test(test_wide_tiles_match_single),
        cmocka_unit_test(test_wide_inside_and_axis_rays),  cmocka_unit_test(test_wide_shadow_packets),
        cmocka_unit_test(test_wide_dense_mesh), cmocka_unit_test(test_single_rays_keep_nearest),            cmocka_unit_test(test_wide_grazing_packets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
