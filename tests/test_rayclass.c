/* test_rayclass.c — ray classification ("rayclass"): identical closest
 * hits and any-hit answers to brute force on the built-in scenes for every
 * ray kind, the events of one query, allocation failure, and the
 * measurement the issue asks for — memory and preprocessing against
 * run-time gain (printed; the deck calls the trade-off poor). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "sidx/rayclass.h"
#include "common/testkit.h"

static void make_scene(const char *name, uint32_t detail, sidx_mesh *m)
{
    sidx_error err;
    assert_int_equal(sidx_scene_make(name, detail, m, &err), SIDX_OK);
}

static void check_scene(const char *name, uint32_t detail, size_t per_kind, uint32_t depth)
{
    sidx_mesh m;
    make_scene(name, detail, &m);
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.max_depth = depth;
    sidx_accel *rc = NULL, *brute = NULL;
    assert_int_equal(sidx_accel_build("rayclass", &m, &opt, &rc, NULL), SIDX_OK);
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    tk_rayrec *rays = malloc(per_kind * sizeof *rays);
    assert_non_null(rays);
    tk_errstats es;
    memset(&es, 0, sizeof es);
    for (int kind = 0; kind < TK_RAYS_KIND_COUNT; ++kind) {
        tk_make_rays(&m, (tk_ray_kind)kind, per_kind, 4321u + (uint64_t)kind, rays);
        for (size_t i = 0; i < per_kind; ++i) {
            sidx_ray r;
            if (tk_ray_from(&rays[i], &r) != SIDX_OK) continue;
            sidx_hit ref, got;
            sidx_accel_intersect(brute, &r, NULL, &ref);
            sidx_accel_intersect(rc, &r, NULL, &got);
            if (!tk_hits_agree(&ref, &got))
                fprintf(stderr, "%s kind %d ray %zu: brute %u t %.9g, rayclass %u t %.9g\n", name, kind, i, ref.prim,
                        ref.t, got.prim, got.t);
            tk_errstats_add(&es, &ref, &got);
            int o1, o2;
            sidx_accel_occluded(brute, &r, NULL, &o1);
            sidx_accel_occluded(rc, &r, NULL, &o2);
            assert_int_equal(o1, o2);
        }
    }
    assert_int_equal(tk_errstats_errors(&es), 0);
    free(rays);
    sidx_accel_destroy(brute);
    sidx_accel_destroy(rc);
    sidx_mesh_free(&m);
}

static void rays_icosphere(void **state) { (void)state; check_scene("icosphere", 0, 300, 8); }
static void rays_teapot(void **state) { (void)state; check_scene("teapot", 0, 200, 6); }
static void rays_stadium(void **state) { (void)state; check_scene("stadium", 0, 150, 6); }
static void rays_soup(void **state) { (void)state; check_scene("soup", 800, 200, 8); }
static void rays_menger(void **state) { (void)state; check_scene("menger", 1, 200, 8); }
static void rays_flat2d(void **state) { (void)state; check_scene("flat2d", 0, 300, 8); }
static void rays_cornell(void **state) { (void)state; check_scene("cornell", 0, 300, 8); }
static void rays_grid(void **state) { (void)state; check_scene("grid", 16, 300, 8); }
static void rays_deep(void **state) { (void)state; check_scene("cornell", 0, 150, 16); }
static void rays_shallow(void **state) { (void)state; check_scene("cornell", 0, 150, 1); }

static void events(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("cornell", 0, &m);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook hook = sidx_recorder_hook(&rec);
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.hook = &hook;
    sidx_accel *rc = NULL;
    assert_int_equal(sidx_accel_build("rayclass", &m, &opt, &rc, NULL), SIDX_OK);
    size_t nodes = 0, leaves = 0, dir_splits = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        if (rec.events[i].type == SIDX_EV_BUILD_NODE) ++nodes;
        if (rec.events[i].type == SIDX_EV_BUILD_LEAF) ++leaves;
        if (rec.events[i].type == SIDX_EV_BUILD_SPLIT && rec.events[i].axis == -1) {
            assert_non_null(rec.events[i].text);
            ++dir_splits;
        }
    }
    sidx_rayclass_info info;
    assert_int_equal(sidx_rayclass_info_get(rc, &info), SIDX_OK);
    assert_int_equal(nodes, info.nodes);
    assert_int_equal(leaves, info.leaves);
    assert_true(dir_splits > 0);
    sidx_recorder_clear(&rec);
    const sidx_aabb b = sidx_mesh_bounds(&m);
    sidx_ray r;
    sidx_ray_init(&r, sidx_aabb_centroid(b), sidx_v3(0.1f, -1.0f, 0.2f), 0, INFINITY);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 9};
    sidx_hit h;
    sidx_accel_intersect(rc, &r, &q, &h);
    assert_true(h.prim != SIDX_NO_HIT);
    assert_int_equal(rec.events[0].type, SIDX_EV_RAY_BEGIN);
    assert_int_equal(rec.events[1].type, SIDX_EV_NODE_ENTER);
    int saw_test = 0, saw_update = 0, saw_term = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        saw_test |= rec.events[i].type == SIDX_EV_PRIM_TEST;
        saw_update |= rec.events[i].type == SIDX_EV_HIT_UPDATE;
        saw_term |= rec.events[i].type == SIDX_EV_TERMINATE;
    }
    assert_true(saw_test && saw_update && saw_term);
    sidx_accel *brute = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    assert_int_equal(sidx_rayclass_info_get(brute, &info), SIDX_ERR_INVALID_ARG);
    sidx_accel_destroy(brute);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(rc);
    sidx_mesh_free(&m);
}


static void nomem(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("cornell", 0, &m);
    int ok = 0;
    for (long k = 0; k < 2000 && !ok; k += (k < 50 ? 1 : 37)) {
        tk_failing f = {k, 0};
        sidx_allocator al = tk_failing_allocator(&f);
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.alloc = &al;
        opt.max_depth = 6;
        sidx_accel *a = NULL;
        const sidx_status s = sidx_accel_build("rayclass", &m, &opt, &a, NULL);
        if (s == SIDX_OK) { ok = 1; sidx_accel_destroy(a); }
        else { assert_int_equal(s, SIDX_ERR_NOMEM); assert_null(a); }
        assert_int_equal(f.live, 0);
    }
    assert_true(ok);
    sidx_mesh_free(&m);
}

/* A few big triangles at the deepest allowed tree: the 5D tree doubles
 * per level, so without a budget this asked for gigabytes (fuzz_build).
 * It must stop with SIDX_ERR_LIMIT, a message naming the option to lower,
 * nothing leaked; and the same scene at the default depth still builds. */
static void budget(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("soup", 24, &m);
    tk_failing f = {LONG_MAX, 0}; /* never fails: only counts live blocks */
    sidx_allocator al = tk_failing_allocator(&f);
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.alloc = &al;
    opt.max_depth = 24;
    opt.leaf_size = 1;
    sidx_accel *a = NULL;
    sidx_error err;
    memset(&err, 0, sizeof err);
    assert_int_equal(sidx_accel_build("rayclass", &m, &opt, &a, &err), SIDX_ERR_LIMIT);
    assert_null(a);
    assert_non_null(strstr(err.message, "max_depth"));
    assert_int_equal(f.live, 0);
    opt.max_depth = 0;
    assert_int_equal(sidx_accel_build("rayclass", &m, &opt, &a, &err), SIDX_OK);
    sidx_accel_destroy(a);
    assert_int_equal(f.live, 0);
    sidx_mesh_free(&m);
}

/* ---- the trade-off, in numbers ---------------------------------------------------- */

static double time_rays(const sidx_accel *a, const sidx_ray *rays, size_t n, sidx_hit *hits)
{
    const double t0 = tk_now_ms();
    for (size_t i = 0; i < n; ++i) sidx_accel_intersect(a, &rays[i], NULL, &hits[i]);
    return tk_now_ms() - t0;
}

static void measure(void **state)
{
    (void)state;
    /* the full table (depths to 12, 5000 rays) takes minutes under the
     * sanitizers: SIDX_RAYCLASS_TABLE=1 asks for it */
    const int fast = tk_fast_tests() || !getenv("SIDX_RAYCLASS_TABLE");
    if (tk_tiny_tests()) { /* valgrind: times under memcheck say nothing; rays_deep builds as deep */
        print_message("skipped at the smallest sizes: a table of times\n");
        return;
    }
    sidx_mesh m;
    make_scene("teapot", 0, &m);
    const size_t n = tk_tiny_tests() ? 250 : fast ? 2000 : 5000;
    tk_rayrec *recs = malloc(n * sizeof *recs);
    sidx_ray *rays = malloc(n * sizeof *rays);
    sidx_hit *h0 = malloc(n * sizeof *h0), *h1 = malloc(n * sizeof *h1);
    assert_true(recs && rays && h0 && h1);
    printf("  rayclass trade-off on teapot (%u tris), %zu rays of each kind:\n", m.num_triangles, n);
    printf("    %-22s %9s %10s %9s %9s %11s %11s\n", "structure", "build ms", "memory KiB", "leaves", "cand/leaf",
           "primary us", "diffuse us");
    const char *names[] = {"brute", "bvh", "rayclass", "rayclass", "rayclass", "rayclass"};
    const uint32_t depths[] = {0, 0, 6, 8, 10, 12};
    const int count = fast ? 4 : 6;
    for (int s = 0; s < count; ++s) {
        if (!sidx_accel_is_registered(names[s])) continue;
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.max_depth = depths[s];
        sidx_accel *a = NULL;
        const double t0 = tk_now_ms();
        assert_int_equal(sidx_accel_build(names[s], &m, &opt, &a, NULL), SIDX_OK);
        const double build = tk_now_ms() - t0;
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        double us[2];
        for (int kind = 0; kind < 2; ++kind) {
            tk_make_rays(&m, kind == 0 ? TK_RAYS_PRIMARY : TK_RAYS_DIFFUSE, n, 10 + (uint64_t)kind, recs);
            size_t nr = 0;
            for (size_t i = 0; i < n; ++i)
                if (tk_ray_from(&recs[i], &rays[nr]) == SIDX_OK) ++nr;
            us[kind] = 1000.0 * time_rays(a, rays, nr, h1) / (double)nr;
        }
        char label[32];
        if (depths[s]) snprintf(label, sizeof label, "%s depth %u", names[s], depths[s]);
        else snprintf(label, sizeof label, "%s", names[s]);
        printf("    %-22s %9.1f %10zu %9u %9.1f %11.3f %11.3f\n", label, build, st.bytes / 1024, st.leaves,
               st.mean_leaf_prims, us[0], us[1]);
        sidx_accel_destroy(a);
    }
    (void)h0;
    free(recs);
    free(rays);
    free(h0);
    free(h1);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(events),
        cmocka_unit_test(rays_icosphere),
        cmocka_unit_test(rays_teapot),
        cmocka_unit_test(rays_stadium),
        cmocka_unit_test(rays_soup),
        cmocka_unit_test(rays_menger),
        cmocka_unit_test(rays_flat2d),
        cmocka_unit_test(rays_cornell),
        cmocka_unit_test(rays_grid),
        cmocka_unit_test(rays_deep),
        cmocka_unit_test(rays_shallow),
        cmocka_unit_test(nomem),
        cmocka_unit_test(budget),
        cmocka_unit_test(measure),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
