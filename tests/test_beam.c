/* test_beam.c — cone and beam tracing: the BVH walk finds exactly the
 * candidates of testing every triangle, candidates are conservative (every
 * triangle a ray of the bundle hits first is one), subdivision covers the
 * parent, events; and the counts that show why the deck calls bundles "not
 * really practical" (printed). */
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
#include "sidx/beam.h"
#include "common/testkit.h"

static const float DEG = 0.017453292f;

static sidx_vec3 unitv(sidx_vec3 v) { return sidx_v3_scale(v, 1.0f / sidx_v3_length(v)); }

/* a uniformly random direction inside the cone */
static sidx_vec3 dir_in_cone(tk_rng *g, const sidx_cone *c)
{
    const sidx_vec3 a = unitv(c->axis);
    const sidx_vec3 h = fabsf(a.x) < 0.6f ? sidx_v3(1, 0, 0) : sidx_v3(0, 1, 0);
    const sidx_vec3 p = unitv(sidx_v3_cross(a, h)), q = sidx_v3_cross(a, p);
    const double cz = 1.0 - tk_rng_unit(g) * (1.0 - cos(c->half_angle)), phi = 6.283185307 * tk_rng_unit(g);
    const double sz = sqrt(1.0 - cz * cz);
    return sidx_v3_add(sidx_v3_scale(a, (float)cz),
                       sidx_v3_add(sidx_v3_scale(p, (float)(sz * cos(phi))), sidx_v3_scale(q, (float)(sz * sin(phi)))));
}

static sidx_vec3 dir_in_beam(tk_rng *g, const sidx_beam *b)
{
    const float s = (float)tk_rng_unit(g), t = (float)tk_rng_unit(g);
    sidx_vec3 d[4];
    for (int i = 0; i < 4; ++i) d[i] = unitv(b->dir[i]);
    const sidx_vec3 top = sidx_v3_add(sidx_v3_scale(d[0], 1 - s), sidx_v3_scale(d[1], s));
    const sidx_vec3 bot = sidx_v3_add(sidx_v3_scale(d[3], 1 - s), sidx_v3_scale(d[2], s));
    return sidx_v3_add(sidx_v3_scale(top, 1 - t), sidx_v3_scale(bot, t));
}

static int in_cone(const sidx_cone *c, sidx_vec3 d)
{
    return sidx_v3_dot(unitv(d), unitv(c->axis)) >= cosf(c->half_angle) - 1e-6f;
}

static int in_beam(const sidx_beam *b, sidx_vec3 d)
{
    sidx_vec3 n[4], mean = sidx_v3(0, 0, 0), u[4];
    for (int i = 0; i < 4; ++i) { u[i] = unitv(b->dir[i]); mean = sidx_v3_add(mean, u[i]); }
    for (int i = 0; i < 4; ++i) {
        n[i] = sidx_v3_cross(u[i], u[(i + 1) % 4]);
        if (sidx_v3_dot(n[i], mean) < 0) n[i] = sidx_v3_scale(n[i], -1);
        if (sidx_v3_dot(n[i], unitv(d)) < -1e-5f) return 0;
    }
    return 1;
}

static int contains(const sidx_bundle_result *r, uint32_t tri)
{
    uint32_t lo = 0, hi = r->num_cands;
    while (lo < hi) {
        const uint32_t mid = (lo + hi) / 2;
        if (r->cands[mid] < tri) lo = mid + 1;
        else hi = mid;
    }
    return lo < r->num_cands && r->cands[lo] == tri;
}

typedef struct scene { sidx_mesh m; sidx_bundle_tree *tree; sidx_accel *brute; sidx_vec3 eye, centre; float radius; } scene;

static void scene_open(scene *s, const char *name)
{
    assert_int_equal(sidx_scene_make(name, 0, &s->m, NULL), SIDX_OK);
    assert_int_equal(sidx_bundle_tree_build(&s->m, NULL, &s->tree, NULL), SIDX_OK);
    assert_int_equal(sidx_accel_build(sidx_accel_is_registered("bvh") ? "bvh" : "brute", &s->m, NULL, &s->brute, NULL),
                     SIDX_OK);
    const sidx_aabb b = sidx_mesh_bounds(&s->m);
    s->centre = sidx_aabb_centroid(b);
    s->radius = 0.5f * sidx_v3_length(sidx_aabb_extent(b));
    s->eye = sidx_v3_add(s->centre, sidx_v3(0.6f * s->radius, 0.5f * s->radius, 2.5f * s->radius));
}

static void scene_close(scene *s)
{
    sidx_accel_destroy(s->brute);
    sidx_bundle_tree_destroy(s->tree);
    sidx_mesh_free(&s->m);
}

/* every first hit of a ray in the bundle is a candidate */
static void check_conservative(const scene *s, const sidx_cone *c, const sidx_beam *b, const sidx_bundle_result *r,
                               int nrays, uint32_t *distinct_hit)
{
    tk_rng g;
    tk_rng_seed(&g, 31);
    assert_true(c != NULL || b != NULL); /* one of the two is traced */
    const sidx_vec3 apex = c ? c->apex : b ? b->apex : sidx_v3(0, 0, 0);
    uint8_t *seen = calloc(s->m.num_triangles, 1);
    assert_non_null(seen);
    uint32_t distinct = 0;
    for (int i = 0; i < nrays; ++i) {
        const sidx_vec3 d = c ? dir_in_cone(&g, c) : dir_in_beam(&g, b);
        sidx_ray ray;
        assert_int_equal(sidx_ray_init(&ray, apex, d, 0, INFINITY), SIDX_OK);
        sidx_hit h;
        sidx_accel_intersect(s->brute, &ray, NULL, &h);
        if (h.prim == SIDX_NO_HIT) continue;
        if (!contains(r, h.prim)) fprintf(stderr, "ray %d hits %u, not a candidate\n", i, h.prim);
        assert_true(contains(r, h.prim));
        if (!seen[h.prim]) { seen[h.prim] = 1; ++distinct; }
    }
    free(seen);
    if (distinct_hit) *distinct_hit = distinct;
}

static void tree_equals_brute(void **state)
{
    (void)state;
    scene s;
    scene_open(&s, "teapot");
    const float angles[] = {0.5f, 3.0f, 15.0f, 60.0f};
    for (int i = 0; i < 4; ++i) {
        sidx_cone c = {s.eye, sidx_v3_sub(s.centre, s.eye), angles[i] * DEG};
        sidx_bundle_result a, b;
        assert_int_equal(sidx_cone_trace(s.tree, &c, 0, 0, NULL, &a), SIDX_OK);
        assert_int_equal(sidx_cone_candidates_brute(&s.m, &c, &b), SIDX_OK);
        assert_int_equal(a.num_cands, b.num_cands);
        assert_memory_equal(a.cands, b.cands, a.num_cands * sizeof *a.cands);
        check_conservative(&s, &c, NULL, &a, 400, NULL);
        sidx_bundle_result_free(&a);
        sidx_bundle_result_free(&b);

        /* a square beam of the same opening */
        const sidx_vec3 ax = unitv(sidx_v3_sub(s.centre, s.eye));
        const sidx_vec3 p = unitv(sidx_v3_cross(ax, sidx_v3(0, 1, 0))), q = sidx_v3_cross(ax, p);
        const float tn = tanf(angles[i] * DEG);
        sidx_beam bm;
        bm.apex = s.eye;
        for (int k = 0; k < 4; ++k) {
            const float sp = (k == 0 || k == 3) ? -tn : tn, sq = (k < 2) ? tn : -tn;
            bm.dir[k] = sidx_v3_add(ax, sidx_v3_add(sidx_v3_scale(p, sp), sidx_v3_scale(q, sq)));
        }
        assert_int_equal(sidx_beam_trace(s.tree, &bm, 0, 0, NULL, &a), SIDX_OK);
        assert_int_equal(sidx_beam_candidates_brute(&s.m, &bm, &b), SIDX_OK);
        assert_int_equal(a.num_cands, b.num_cands);
        assert_memory_equal(a.cands, b.cands, a.num_cands * sizeof *a.cands);
        check_conservative(&s, NULL, &bm, &a, 400, NULL);
        sidx_bundle_result_free(&a);
        sidx_bundle_result_free(&b);
    }
    scene_close(&s);
}

static void splits_cover_the_parent(void **state)
{
    (void)state;
    tk_rng g;
    tk_rng_seed(&g, 3);
    const float angles[] = {1.0f, 10.0f, 40.0f, 80.0f};
    for (int i = 0; i < 4; ++i) {
        sidx_cone c = {sidx_v3(0, 0, 0), sidx_v3(0.3f, -1.0f, 0.2f), angles[i] * DEG}, sub[4];
        sidx_cone_split(&c, sub);
        for (int k = 0; k < 4; ++k) assert_true(sub[k].half_angle < c.half_angle);
        for (int n = 0; n < 4000; ++n) {
            const sidx_vec3 d = dir_in_cone(&g, &c);
            int any = 0;
            for (int k = 0; k < 4; ++k) any |= in_cone(&sub[k], d);
            assert_true(any);
        }
    }
    sidx_beam b = {sidx_v3(1, 2, 3), {sidx_v3(-1, -0.5f, 2), sidx_v3(1.2f, -0.4f, 2), sidx_v3(0.8f, 0.9f, 2), sidx_v3(-1, 0.7f, 2)}}, sub[4];
    sidx_beam_split(&b, sub);
    for (int n = 0; n < 4000; ++n) {
        const sidx_vec3 d = dir_in_beam(&g, &b);
        int any = 0;
        for (int k = 0; k < 4; ++k) any |= in_beam(&sub[k], d);
        assert_true(any);
    }
}

static void subdivision_and_events(void **state)
{
    (void)state;
    scene s;
    scene_open(&s, "teapot");
    sidx_cone c = {s.eye, sidx_v3_sub(s.centre, s.eye), 10.0f * DEG};
    sidx_counters cnt;
    sidx_counters_init(&cnt);
    sidx_hook hook = sidx_counters_hook(&cnt);
    sidx_bundle_result whole, split;
    assert_int_equal(sidx_cone_trace(s.tree, &c, 0, 0, NULL, &whole), SIDX_OK);
    assert_int_equal(sidx_cone_trace(s.tree, &c, 64, 3, &hook, &split), SIDX_OK);
    assert_true(split.subdivisions > 0);
    /* No subset relation: 4 cones of 0.78θ cover 2.4 times the parent's
     * solid angle, so splitting a cone can ADD candidates (see counts). */
    check_conservative(&s, &c, NULL, &split, 600, NULL);
    assert_int_equal(cnt.n[SIDX_EV_NOTE], split.subdivisions);
    assert_int_equal(cnt.n[SIDX_EV_BOX_TEST], split.nodes_visited);
    assert_int_equal(cnt.n[SIDX_EV_PRIM_TEST], split.tri_tests);
    sidx_bundle_result_free(&whole);
    sidx_bundle_result_free(&split);
    /* arguments */
    sidx_cone bad = {s.eye, sidx_v3(0, 0, 0), 0.1f};
    sidx_bundle_result r;
    assert_int_equal(sidx_cone_trace(s.tree, &bad, 0, 0, NULL, &r), SIDX_ERR_INVALID_ARG);
    bad.axis = sidx_v3(0, 0, 1);
    bad.half_angle = 2.0f;
    assert_int_equal(sidx_cone_trace(s.tree, &bad, 0, 0, NULL, &r), SIDX_ERR_INVALID_ARG);
    sidx_beam flat = {s.eye, {sidx_v3(1, 0, 0), sidx_v3(1, 0, 0), sidx_v3(1, 0, 0), sidx_v3(1, 0, 0)}};
    assert_int_equal(sidx_beam_trace(s.tree, &flat, 0, 0, NULL, &r), SIDX_ERR_INVALID_ARG);
    scene_close(&s);
}

/* The lesson: candidates against what the rays really see. */
static void counts(void **state)
{
    (void)state;
    scene s;
    scene_open(&s, "teapot");
    printf("  cone tracing the teapot (%u tris) from outside; split = at most 16 candidates, 5 levels;"
           " 'rays see' = distinct triangles 2000 sample rays hit first:\n", s.m.num_triangles);
    printf("    %6s | %9s %9s %8s | %13s %8s %9s %9s | %9s\n", "angle", "cands", "nodes", "tests", "split cands",
           "cones", "nodes", "tests", "rays see");
    const float angles[] = {0.25f, 1.0f, 4.0f, 12.0f};
    for (int i = 0; i < 4; ++i) {
        sidx_cone c = {s.eye, sidx_v3_sub(s.centre, s.eye), angles[i] * DEG};
        sidx_bundle_result a, b;
        assert_int_equal(sidx_cone_trace(s.tree, &c, 0, 0, NULL, &a), SIDX_OK);
        assert_int_equal(sidx_cone_trace(s.tree, &c, 16, 5, NULL, &b), SIDX_OK);
        uint32_t seen = 0;
        check_conservative(&s, &c, NULL, &b, 2000, &seen);
        printf("    %5.2f° | %9u %9llu %8llu | %13u %8u %9llu %9llu | %9u\n", angles[i], a.num_cands,
               (unsigned long long)a.nodes_visited, (unsigned long long)a.tri_tests, b.num_cands, b.bundles,
               (unsigned long long)b.nodes_visited, (unsigned long long)b.tri_tests, seen);
        sidx_bundle_result_free(&a);
        sidx_bundle_result_free(&b);
    }
    printf("  beams of the same openings (square pyramids; sub-beams tile the parent exactly):\n");
    for (int i = 0; i < 4; ++i) {
        const sidx_vec3 ax = unitv(sidx_v3_sub(s.centre, s.eye));
        const sidx_vec3 p = unitv(sidx_v3_cross(ax, sidx_v3(0, 1, 0))), q = sidx_v3_cross(ax, p);
        const float tn = tanf(angles[i] * DEG);
        sidx_beam bm;
        bm.apex = s.eye;
        for (int k = 0; k < 4; ++k) {
            const float sp = (k == 0 || k == 3) ? -tn : tn, sq = (k < 2) ? tn : -tn;
            bm.dir[k] = sidx_v3_add(ax, sidx_v3_add(sidx_v3_scale(p, sp), sidx_v3_scale(q, sq)));
        }
        sidx_bundle_result a, b;
        assert_int_equal(sidx_beam_trace(s.tree, &bm, 0, 0, NULL, &a), SIDX_OK);
        assert_int_equal(sidx_beam_trace(s.tree, &bm, 16, 5, NULL, &b), SIDX_OK);
        uint32_t seen = 0;
        check_conservative(&s, NULL, &bm, &b, 2000, &seen);
        printf("    %5.2f° | %9u %9llu %8llu | %13u %8u %9llu %9llu | %9u\n", angles[i], a.num_cands,
               (unsigned long long)a.nodes_visited, (unsigned long long)a.tri_tests, b.num_cands, b.bundles,
               (unsigned long long)b.nodes_visited, (unsigned long long)b.tri_tests, seen);
        sidx_bundle_result_free(&a);
        sidx_bundle_result_free(&b);
    }
    scene_close(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(splits_cover_the_parent),
        cmocka_unit_test(tree_equals_brute),
        cmocka_unit_test(subdivision_and_events),
        cmocka_unit_test(counts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
