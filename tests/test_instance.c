/* test_instance.c — aggregates and instancing: 10,000 instances of one
 * icosphere BVH trace like the flattened scene (every instance's triangles
 * transformed and copied into one mesh) for random rays, with one copy of
 * the sphere's structure in memory; nested aggregates; u, v and world
 * normals; events; argument errors. */
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
#include "sidx/instance.h"
#include "common/testkit.h"

static const char *child_structure(void) { return sidx_accel_is_registered("bvh") ? "bvh" : "brute"; }

/* random rotation (unit quaternion), non-uniform scale in [0.5, 1.5], translation in [-L, L]^3 */
static void random_xform(tk_rng *g, float L, float m[12])
{
    double q[4], n = 0.0;
    for (int i = 0; i < 4; ++i) { q[i] = tk_rng_range(g, -1, 1); n += q[i] * q[i]; }
    n = sqrt(n);
    for (int i = 0; i < 4; ++i) q[i] /= n;
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                         2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
    const double s[3] = {tk_rng_range(g, 0.5, 1.5), tk_rng_range(g, 0.5, 1.5), tk_rng_range(g, 0.5, 1.5)};
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m[4 * r + c] = (float)(R[3 * r + c] * s[c]); /* R·S */
        m[4 * r + 3] = (float)tk_rng_range(g, -L, L);
    }
}

static sidx_vec3 apply(const float m[12], sidx_vec3 p)
{
    return sidx_v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                   m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

/* The flattened scene: leaf instance i's triangles at i·T .. i·T + T − 1. */
static void flatten(const sidx_accel *agg, const sidx_mesh *obj, sidx_mesh *out)
{
    const uint32_t n = sidx_aggregate_leaf_count(agg), V = obj->num_vertices, T = obj->num_triangles;
    float *xyz = malloc((size_t)n * V * 3 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * T * 3 * sizeof *idx);
    assert_true(xyz && idx);
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_accel *leaf;
        float m[12];
        assert_int_equal(sidx_aggregate_leaf(agg, i, &leaf, m), SIDX_OK);
        assert_ptr_equal(sidx_accel_mesh(leaf), obj);
        for (uint32_t v = 0; v < V; ++v) {
            const sidx_vec3 p = apply(m, obj->positions[v]);
            xyz[3 * ((size_t)i * V + v) + 0] = p.x;
            xyz[3 * ((size_t)i * V + v) + 1] = p.y;
            xyz[3 * ((size_t)i * V + v) + 2] = p.z;
        }
        for (uint32_t k = 0; k < 3 * T; ++k) idx[(size_t)i * 3 * T + k] = obj->indices[k] + i * V;
    }
    assert_int_equal(sidx_mesh_from_arrays(out, xyz, n * V, idx, n * T, NULL), SIDX_OK);
    free(xyz);
    free(idx);
}

/* rays: half aimed at random leaf instances' centres, half random */
static void make_rays(tk_rng *g, const sidx_aabb world, const sidx_accel *agg, size_t n, sidx_ray *rays)
{
    const sidx_vec3 c = sidx_aabb_centroid(world), e = sidx_aabb_extent(world);
    const uint32_t leaves = sidx_aggregate_leaf_count(agg);
    for (size_t i = 0; i < n; ++i) {
        sidx_vec3 o = sidx_v3_add(c, sidx_v3((float)tk_rng_range(g, -0.8, 0.8) * e.x, (float)tk_rng_range(g, -0.8, 0.8) * e.y,
                                             (float)tk_rng_range(g, -0.8, 0.8) * e.z));
        if (i % 4 == 0) o = sidx_v3_add(c, sidx_v3_scale(tk_rng_sphere(g), 1.5f * sidx_v3_length(e))); /* from outside */
        sidx_vec3 d;
        if (i % 2 == 0) {
            const sidx_accel *leaf;
            float m[12];
            sidx_aggregate_leaf(agg, tk_rng_below(g, leaves), &leaf, m);
            d = sidx_v3_sub(sidx_v3(m[3], m[7], m[11]), o);
        } else {
            d = tk_rng_sphere(g);
        }
        d = sidx_v3_scale(d, (float)tk_rng_range(g, 0.3, 3.0)); /* any length: t must not care */
        assert_int_equal(sidx_ray_init(&rays[i], o, d, 0.0f, INFINITY), SIDX_OK);
    }
}

static void compare(const sidx_accel *agg, const sidx_accel *flat, const sidx_ray *rays, size_t n, uint32_t T,
                    size_t *hits_out)
{
    size_t hits = 0;
    for (size_t i = 0; i < n; ++i) {
        sidx_hit ref, got;
        sidx_accel_intersect(flat, &rays[i], NULL, &ref);
        sidx_accel_intersect(agg, &rays[i], NULL, &got);
        sidx_hit g2 = got;
        if (got.prim != SIDX_NO_HIT) g2.prim = got.instance * T + got.prim;
        else assert_int_equal(got.instance, SIDX_NO_HIT);
        if (!tk_hits_agree(&ref, &g2))
            fprintf(stderr, "ray %zu: flattened prim %u t %.9g; instanced instance %u prim %u t %.9g\n", i, ref.prim,
                    ref.t, got.instance, got.prim, got.t);
        assert_true(tk_hits_agree(&ref, &g2));
        int o1, o2;
        sidx_accel_occluded(flat, &rays[i], NULL, &o1);
        sidx_accel_occluded(agg, &rays[i], NULL, &o2);
        assert_int_equal(o1, o2);
        hits += ref.prim != SIDX_NO_HIT;
    }
    if (hits_out) *hits_out = hits;
}

static void ten_thousand_instances(void **state)
{
    (void)state;
    const uint32_t N = 10000;
    sidx_mesh sphere;
    assert_int_equal(sidx_scene_make("icosphere", 1, &sphere, NULL), SIDX_OK); /* 80 triangles */
    sidx_accel *child = NULL;
    assert_int_equal(sidx_accel_build(child_structure(), &sphere, NULL, &child, NULL), SIDX_OK);
    sidx_instance *inst = malloc(N * sizeof *inst);
    assert_non_null(inst);
    tk_rng g;
    tk_rng_seed(&g, 2024);
    for (uint32_t i = 0; i < N; ++i) {
        inst[i].accel = child;
        random_xform(&g, 40.0f, inst[i].xform);
    }
    sidx_accel *agg = NULL;
    sidx_error err;
    double t0 = tk_now_ms();
    assert_int_equal(sidx_aggregate_build(inst, N, NULL, &agg, &err), SIDX_OK);
    const double agg_ms = tk_now_ms() - t0;
    assert_int_equal(sidx_aggregate_leaf_count(agg), N);
    sidx_mesh flat_mesh;
    flatten(agg, &sphere, &flat_mesh);
    sidx_accel *flat = NULL, *flat_brute = NULL;
    t0 = tk_now_ms();
    /* the reference over 800k triangles: the middle-split BVH builds
     * fastest (this suite must stay quick under the sanitizers) */
    const char *flat_name = sidx_accel_is_registered("bvh-middle") ? "bvh-middle" : child_structure();
    assert_int_equal(sidx_accel_build(flat_name, &flat_mesh, NULL, &flat, NULL), SIDX_OK);
    const double flat_ms = tk_now_ms() - t0;
    assert_int_equal(sidx_accel_build("brute", &flat_mesh, NULL, &flat_brute, NULL), SIDX_OK);

    const size_t nrays = tk_fast_tests() ? 300 : 2000;
    sidx_ray *rays = malloc(nrays * sizeof *rays);
    assert_non_null(rays);
    make_rays(&g, sidx_mesh_bounds(&flat_mesh), agg, nrays, rays);
    size_t hits;
    compare(agg, flat, rays, nrays, sphere.num_triangles, &hits);
    assert_true(hits > nrays / 4);
    compare(agg, flat_brute, rays, 12, sphere.num_triangles, NULL); /* the real reference, on a few */

    /* memory: one copy of the sphere's structure */
    sidx_aggregate_info info;
    assert_int_equal(sidx_aggregate_info_get(agg, &info), SIDX_OK);
    sidx_accel_stats cs, fs;
    sidx_accel_stats_get(child, &cs);
    sidx_accel_stats_get(flat, &fs);
    assert_int_equal(info.instances, N);
    assert_int_equal(info.distinct_children, 1);
    assert_int_equal(info.shared_bytes, cs.bytes);
    assert_int_equal(info.world_triangles, (uint64_t)N * sphere.num_triangles);
    const size_t inst_total = info.own_bytes + info.shared_bytes + (size_t)sphere.num_vertices * 12 + sphere.num_triangles * 12;
    const size_t flat_total = fs.bytes + (size_t)flat_mesh.num_vertices * 12 + (size_t)flat_mesh.num_triangles * 12;
    assert_true(inst_total < flat_total / 4);
    printf("  %u instances of a %u-triangle sphere (%s): instanced %zu KiB (top level %zu KiB + one %zu KiB %s + mesh)"
           " vs flattened %zu KiB (%s %zu KiB + %u-triangle mesh); build %.1f ms vs %.1f ms\n",
           N, sphere.num_triangles, child_structure(), inst_total / 1024, info.own_bytes / 1024, cs.bytes / 1024,
           child_structure(), flat_total / 1024, flat_name, fs.bytes / 1024, flat_mesh.num_triangles, agg_ms,
           flat_ms);
    /* speed, for the record */
    sidx_hit h;
    t0 = tk_now_ms();
    for (size_t i = 0; i < nrays; ++i) sidx_accel_intersect(agg, &rays[i], NULL, &h);
    const double ti = tk_now_ms() - t0;
    t0 = tk_now_ms();
    for (size_t i = 0; i < nrays; ++i) sidx_accel_intersect(flat, &rays[i], NULL, &h);
    const double tf = tk_now_ms() - t0;
    printf("  per ray: instanced %.2f us, flattened %.2f us\n", 1000.0 * ti / nrays, 1000.0 * tf / nrays);

    free(rays);
    sidx_accel_destroy(flat_brute);
    sidx_accel_destroy(flat);
    sidx_mesh_free(&flat_mesh);
    sidx_accel_destroy(agg);
    free(inst);
    sidx_accel_destroy(child);
    sidx_mesh_free(&sphere);
}

/* An aggregate of aggregates: 4 groups of 25 spheres, placed 40 times. */
static void nested_aggregates(void **state)
{
    (void)state;
    sidx_mesh sphere;
    assert_int_equal(sidx_scene_make("icosphere", 1, &sphere, NULL), SIDX_OK);
    sidx_accel *child = NULL;
    assert_int_equal(sidx_accel_build(child_structure(), &sphere, NULL, &child, NULL), SIDX_OK);
    tk_rng g;
    tk_rng_seed(&g, 7);
    sidx_accel *groups[4];
    sidx_instance gi[25];
    for (int k = 0; k < 4; ++k) {
        for (int i = 0; i < 25; ++i) {
            gi[i].accel = child;
            random_xform(&g, 6.0f, gi[i].xform);
        }
        assert_int_equal(sidx_aggregate_build(gi, 25, NULL, &groups[k], NULL), SIDX_OK);
    }
    sidx_instance top[40];
    for (int i = 0; i < 40; ++i) {
        top[i].accel = groups[i % 4];
        random_xform(&g, 30.0f, top[i].xform);
    }
    sidx_accel *agg = NULL;
    assert_int_equal(sidx_aggregate_build(top, 40, NULL, &agg, NULL), SIDX_OK);
    assert_int_equal(sidx_aggregate_leaf_count(agg), 1000);
    sidx_aggregate_info info;
    sidx_aggregate_info_get(agg, &info);
    assert_int_equal(info.distinct_children, 4);
    assert_int_equal(info.world_triangles, 1000u * sphere.num_triangles);
    sidx_mesh flat_mesh;
    flatten(agg, &sphere, &flat_mesh);
    sidx_accel *flat = NULL;
    assert_int_equal(sidx_accel_build("brute", &flat_mesh, NULL, &flat, NULL), SIDX_OK);
    sidx_ray rays[150];
    make_rays(&g, sidx_mesh_bounds(&flat_mesh), agg, 150, rays);
    size_t hits;
    compare(agg, flat, rays, 150, sphere.num_triangles, &hits);
    assert_true(hits > 30);

    /* u, v and the world normal agree with the flattened triangle's */
    const sidx_query q = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    int checked = 0;
    for (int i = 0; i < 150; ++i) {
        sidx_hit a, b;
        sidx_accel_intersect(agg, &rays[i], &q, &a);
        sidx_accel_intersect(flat, &rays[i], &q, &b);
        if (a.prim == SIDX_NO_HIT || a.instance * sphere.num_triangles + a.prim != b.prim) continue;
        assert_float_equal(a.u, b.u, 2e-3f);
        assert_float_equal(a.v, b.v, 2e-3f);
        const float cosang = sidx_v3_dot(a.ng, b.ng) / (sidx_v3_length(a.ng) * sidx_v3_length(b.ng));
        assert_true(cosang > 0.9999f);
        ++checked;
    }
    assert_true(checked > 20);
    sidx_accel_destroy(flat);
    sidx_mesh_free(&flat_mesh);
    sidx_accel_destroy(agg);
    for (int k = 0; k < 4; ++k) sidx_accel_destroy(groups[k]);
    sidx_accel_destroy(child);
    sidx_mesh_free(&sphere);
}

static void events_and_errors(void **state)
{
    (void)state;
    sidx_mesh sphere;
    assert_int_equal(sidx_scene_make("icosphere", 1, &sphere, NULL), SIDX_OK);
    sidx_accel *child = NULL;
    assert_int_equal(sidx_accel_build("brute", &sphere, NULL, &child, NULL), SIDX_OK);
    sidx_instance in[2] = {{child, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}}, {child, {2, 0, 0, 5, 0, 2, 0, 0, 0, 0, 2, 0}}};
    sidx_accel *agg = NULL;
    assert_int_equal(sidx_aggregate_build(in, 2, NULL, &agg, NULL), SIDX_OK);
    assert_true(sidx_accel_is_aggregate(agg));
    assert_false(sidx_accel_is_aggregate(child));
    /* a ray along +x through both: the first sphere (radius 1 at 0) is hit at x = -1 */
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook hook = sidx_recorder_hook(&rec);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 5};
    sidx_ray r;
    sidx_ray_init(&r, sidx_v3(-10, 0.01f, 0.02f), sidx_v3(2, 0, 0), 0, INFINITY);
    sidx_hit h;
    sidx_accel_intersect(agg, &r, &q, &h);
    assert_int_equal(h.instance, 0);
    assert_float_equal(h.t, 4.5f, 0.02f);
    int notes = 0, child_events = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        if (rec.events[i].type == SIDX_EV_NOTE && !strcmp(rec.events[i].structure, "aggregate")) ++notes;
        if (!strcmp(rec.events[i].structure, "brute")) ++child_events;
    }
    assert_true(notes >= 1);
    assert_true(child_events > 0);
    /* from the far side it is the big one (instance 1) */
    sidx_ray_init(&r, sidx_v3(20, 0.01f, 0.02f), sidx_v3(-1, 0, 0), 0, INFINITY);
    sidx_accel_intersect(agg, &r, NULL, &h);
    assert_int_equal(h.instance, 1);
    assert_float_equal(h.t, 13.0f, 0.1f);
    /* errors */
    sidx_accel *bad = NULL;
    sidx_instance sing = {child, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0}};
    assert_int_equal(sidx_aggregate_build(&sing, 1, NULL, &bad, NULL), SIDX_ERR_INVALID_ARG);
    sidx_instance none = {NULL, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}};
    assert_int_equal(sidx_aggregate_build(&none, 1, NULL, &bad, NULL), SIDX_ERR_INVALID_ARG);
    assert_null(bad);
    const sidx_accel *leaf;
    float m[12];
    assert_int_equal(sidx_aggregate_leaf(agg, 2, &leaf, m), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_aggregate_leaf(child, 0, &leaf, m), SIDX_ERR_INVALID_ARG);
    /* an empty aggregate misses everything */
    sidx_accel *empty = NULL;
    assert_int_equal(sidx_aggregate_build(NULL, 0, NULL, &empty, NULL), SIDX_OK);
    sidx_accel_intersect(empty, &r, NULL, &h);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    sidx_accel_destroy(empty);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(agg);
    sidx_accel_destroy(child);
    sidx_mesh_free(&sphere);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(events_and_errors),
        cmocka_unit_test(nested_aggregates),
        cmocka_unit_test(ten_thousand_instances),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
