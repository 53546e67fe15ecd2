/* test_lazy_instance.c — lazy instances (sidx_aggregate_build_meshes with
 * opt.lazy) and the city that shows them (sidx_city_make):
 *  - a small city from its street-level camera: the lazy aggregate's hits
 *    equal the eager one's bit for bit (t, prim, instance, u, v, normal,
 *    shadow answers), ray by ray, in packets, in image tiles and on
 *    threads, each from a fresh lazy aggregate; the first frame builds
 *    some of the buildings, not all; instances sharing a mesh share one
 *    structure;
 *  - threads racing into one unbuilt instance (run under ThreadSanitizer
 *    by make test-tsan) build it once and all get the eager hits;
 *  - out of memory during an expansion: the query returns SIDX_ERR_NOMEM,
 *    nothing of the structure is kept, a later query builds it;
 *  - the expansion's events on the query's hook;
 *  - the city is the same city on every call, its buildings distinct,
 *    at least 10k triangles each at the default detail;
 *  - argument errors. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "sidx/sidx.h"
#include "sidx/instance.h"
#include "common/testkit.h"

static int same_hit(const sidx_hit *a, const sidx_hit *b)
{
    return a->prim == b->prim && a->instance == b->instance && !memcmp(&a->t, &b->t, sizeof a->t) &&
           !memcmp(&a->u, &b->u, sizeof a->u) && !memcmp(&a->v, &b->v, sizeof a->v) &&
           !memcmp(&a->ng, &b->ng, sizeof a->ng);
}

static sidx_vec3 unit(sidx_vec3 v) { return sidx_v3_scale(v, 1.0f / sidx_v3_length(v)); }

static sidx_accel *city_agg(const sidx_city *c, uint32_t n, int lazy, const sidx_allocator *al)
{
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.lazy = (uint32_t)lazy;
    o.alloc = al;
    sidx_accel *a = NULL;
    sidx_error err;
    if (sidx_aggregate_build_meshes(c->instances, n, &o, &a, &err) != SIDX_OK) fail_msg("%s", err.message);
    return a;
}

/* px x px primary rays from the city's camera */
static sidx_ray *camera_rays(const sidx_city *c, uint32_t px)
{
    sidx_ray *r = malloc((size_t)px * px * sizeof *r);
    assert_non_null(r);
    const sidx_vec3 f = unit(sidx_v3_sub(c->at, c->eye));
    const sidx_vec3 right = unit(sidx_v3_cross(f, sidx_v3(0, 1, 0))), up = sidx_v3_cross(right, f);
    for (uint32_t y = 0; y < px; ++y)
        for (uint32_t x = 0; x < px; ++x) {
            const float sx = (2.0f * ((float)x + 0.5f) / (float)px - 1.0f) * 0.6f;
            const float sy = (1.0f - 2.0f * ((float)y + 0.5f) / (float)px) * 0.6f;
            const sidx_vec3 d = sidx_v3_add(f, sidx_v3_add(sidx_v3_scale(right, sx), sidx_v3_scale(up, sy)));
            assert_int_equal(sidx_ray_init(&r[y * px + x], c->eye, d, 0.0f, INFINITY), SIDX_OK);
        }
    return r;
}

/* An instanced hit carries no point (sidx/spawn.h): the shadow ray starts
 * at o + t·d moved off the surface along the normal, towards the light. */
static sidx_ray shadow_ray(const sidx_ray *r, const sidx_hit *h, sidx_vec3 light)
{
    const sidx_vec3 p = sidx_v3_add(r->org, sidx_v3_scale(r->dir, h->t));
    sidx_vec3 n = unit(h->ng);
    if (sidx_v3_dot(n, r->dir) > 0.0f) n = sidx_v3_scale(n, -1.0f);
    const sidx_vec3 o = sidx_v3_add(p, sidx_v3_scale(n, 1e-3f));
    sidx_ray s;
    assert_int_equal(sidx_ray_init(&s, o, sidx_v3_sub(light, o), 0.0f, 1.0f), SIDX_OK);
    return s;
}

static uint32_t built(const sidx_accel *a)
{
    sidx_aggregate_info in;
    assert_int_equal(sidx_aggregate_info_get(a, &in), SIDX_OK);
    return in.built_structures;
}

#define FLAGS (SIDX_QUERY_POINT | SIDX_QUERY_NORMAL | SIDX_QUERY_UV)

static void lazy_hits_equal_eager(void **state)
{
    (void)state;
    const uint32_t n = 36, px = tk_tiny_tests() ? 16 : 40, N = px * px;
    sidx_city c;
    assert_int_equal(sidx_city_make(n, 3, &c, NULL), SIDX_OK);
    /* four more instances placing building 0 again: one structure for five instances */
    sidx_mesh_instance *inst = realloc(c.instances, (n + 4) * sizeof *inst);
    assert_non_null(inst);
    c.instances = inst;
    for (uint32_t k = 0; k < 4; ++k) {
        inst[n + k] = inst[0];
        inst[n + k].xform[3] -= 6.0f * (float)(k + 1);
        inst[n + k].xform[11] -= 30.0f;
    }
    const uint32_t ni = n + 4;
    sidx_ray *rays = camera_rays(&c, px);
    sidx_hit *want = malloc(N * sizeof *want), *got = malloc(N * sizeof *got);
    uint8_t *want_occ = malloc(N), *got_occ = malloc(N);
    sidx_ray *shadow = malloc(N * sizeof *shadow);
    assert_true(want && got && want_occ && got_occ && shadow);
    const sidx_query q = {FLAGS, SIDX_TRAVERSE_DEFAULT, NULL, 0};

    sidx_accel *eager = city_agg(&c, ni, 0, NULL);
    sidx_aggregate_info info;
    assert_int_equal(sidx_aggregate_info_get(eager, &info), SIDX_OK);
    assert_int_equal(info.mesh_structures, n);
    assert_int_equal(info.built_instances, ni);
    size_t hits = 0;
    for (uint32_t i = 0; i < N; ++i) {
        assert_int_equal(sidx_accel_intersect(eager, &rays[i], &q, &want[i]), SIDX_OK);
        int occ = 0;
        shadow[i] = rays[i]; /* a miss: its shadow ray is the primary ray again */
        if (want[i].prim != SIDX_NO_HIT) {
            ++hits;
            shadow[i] = shadow_ray(&rays[i], &want[i], c.light);
        }
        assert_int_equal(sidx_accel_occluded(eager, &shadow[i], NULL, &occ), SIDX_OK);
        want_occ[i] = (uint8_t)occ;
    }
    if (!(hits > N / 4 && hits < N)) fail_msg("%zu hits of %u", hits, N); /* buildings and sky */

    /* one ray at a time: the first frame builds some buildings, not all */
    sidx_accel *lazy = city_agg(&c, ni, 1, NULL);
    sidx_accel_stats st;
    sidx_accel_stats_get(lazy, &st);
    assert_int_equal(st.unbuilt, n);
    assert_int_equal(st.unbuilt_prims, ni);
    assert_int_equal(built(lazy), 0);
    for (uint32_t i = 0; i < N; ++i) {
        assert_int_equal(sidx_accel_intersect(lazy, &rays[i], &q, &got[i]), SIDX_OK);
        if (!same_hit(&want[i], &got[i]))
            fail_msg("ray %u: lazy prim %u inst %u t %a, eager prim %u inst %u t %a", i, got[i].prim,
                     got[i].instance, (double)got[i].t, want[i].prim, want[i].instance, (double)want[i].t);
        int occ = -1;
        assert_int_equal(sidx_accel_occluded(lazy, &shadow[i], NULL, &occ), SIDX_OK);
        assert_int_equal(occ, want_occ[i]);
    }
    const uint32_t first = built(lazy);
    assert_true(first > 0 && first < n);
    sidx_accel_stats_get(lazy, &st);
    assert_int_equal(st.unbuilt, n - first);
    sidx_accel_destroy(lazy);

    /* packets (they reach an aggregate ray by ray), tiles, threads: a fresh lazy aggregate each */
    const sidx_packet_options po = {SIDX_PACKET_PLAIN, 0, SIDX_QUERY_UV | SIDX_QUERY_NORMAL};
    sidx_hit *pk = malloc(N * sizeof *pk);
    assert_non_null(pk);
    lazy = city_agg(&c, ni, 1, NULL);
    for (uint32_t i = 0; i < N; i += 64) {
        const uint32_t m = N - i < 64 ? N - i : 64;
        assert_int_equal(sidx_packet_intersect(lazy, rays + i, m, 0, &po, pk + i, NULL), SIDX_OK);
        assert_int_equal(sidx_packet_occluded(lazy, shadow + i, m, 0, &po, got_occ + i, NULL), SIDX_OK);
    }
    sidx_accel_destroy(lazy);
    sidx_hit *ek = malloc(N * sizeof *ek);
    assert_non_null(ek);
    for (uint32_t i = 0; i < N; i += 64) {
        const uint32_t m = N - i < 64 ? N - i : 64;
        assert_int_equal(sidx_packet_intersect(eager, rays + i, m, 0, &po, ek + i, NULL), SIDX_OK);
    }
    for (uint32_t i = 0; i < N; ++i) {
        if (!same_hit(&ek[i], &pk[i])) fail_msg("packet ray %u differs", i);
        assert_int_equal(got_occ[i], want_occ[i]);
    }
    lazy = city_agg(&c, ni, 1, NULL);
    assert_int_equal(sidx_trace_tiles(lazy, rays, px, px, 8, &po, pk, NULL), SIDX_OK);
    assert_int_equal(sidx_trace_tiles(eager, rays, px, px, 8, &po, ek, NULL), SIDX_OK);
    for (uint32_t i = 0; i < N; ++i)
        if (!same_hit(&ek[i], &pk[i])) fail_msg("tile ray %u differs", i);
    sidx_accel_destroy(lazy);
    lazy = city_agg(&c, ni, 1, NULL);
    assert_int_equal(sidx_trace_parallel(lazy, rays, N, &q, got, 4), SIDX_OK);
    assert_int_equal(sidx_occluded_parallel(lazy, shadow, N, NULL, got_occ, 4), SIDX_OK);
    for (uint32_t i = 0; i < N; ++i) {
        if (!same_hit(&want[i], &got[i])) fail_msg("threaded ray %u differs", i);
        assert_int_equal(got_occ[i], want_occ[i]);
    }
    assert_int_equal(built(lazy), first); /* the same rays reach the same buildings */
    /* every hit's leaf is a built structure over its building's mesh */
    for (uint32_t i = 0; i < N; ++i) {
        if (got[i].prim == SIDX_NO_HIT) continue;
        const sidx_accel *leaf = NULL;
        float m[12];
        assert_int_equal(sidx_aggregate_leaf(lazy, got[i].instance, &leaf, m), SIDX_OK);
        assert_non_null(leaf);
        assert_ptr_equal(sidx_accel_mesh(leaf), c.instances[got[i].instance].mesh);
    }
    sidx_accel_destroy(lazy);
    sidx_accel_destroy(eager);
    free(pk);
    free(ek);
    free(rays);
    free(shadow);
    free(want);
    free(got);
    free(want_occ);
    free(got_occ);
    sidx_city_free(&c);
}

/* ---- threads racing into one unbuilt instance ---------------------------------- */

#define RACERS 4

static void threads_race_into_one_instance(void **state)
{
    (void)state;
    sidx_city c;
    assert_int_equal(sidx_city_make(1, 6, &c, NULL), SIDX_OK);
    /* rays at the one building from in front of it */
    const uint32_t px = 12, N = px * px;
    sidx_city look = c;
    look.eye = sidx_v3(0.0f, 6.0f, -16.0f);
    look.at = sidx_v3(0.0f, 6.0f, 0.0f);
    sidx_ray *rays = camera_rays(&look, px);
    sidx_hit *want = malloc(N * sizeof *want), *got = malloc(RACERS * N * sizeof *got);
    assert_true(want && got);
    sidx_accel *eager = city_agg(&c, 1, 0, NULL);
    assert_int_equal(sidx_accel_intersect_n(eager, rays, N, NULL, want), SIDX_OK);
    uint32_t on = 0;
    for (uint32_t i = N / 2; i < N; ++i) on += want[i].prim != SIDX_NO_HIT;
    assert_true(on > N / 8);
    const int rounds = tk_fast_tests() ? 4 : 16;
    for (int round = 0; round < rounds; ++round) {
        sidx_accel *lazy = city_agg(&c, 1, 1, NULL);
        /* every thread starts on the ray through the middle: all into the unbuilt building at once */
        assert_int_equal(tk_race_intersect(lazy, rays + N / 2, N / 2, RACERS, got), SIDX_OK);
        for (int t = 0; t < RACERS; ++t) {
            for (uint32_t i = 0; i < N / 2; ++i)
                if (!same_hit(&want[N / 2 + i], &got[(size_t)t * (N / 2) + i]))
                    fail_msg("round %d thread %d ray %u differs", round, t, i);
        }
        sidx_aggregate_info in;
        assert_int_equal(sidx_aggregate_info_get(lazy, &in), SIDX_OK);
        assert_int_equal(in.built_structures, 1);
        assert_int_equal(in.built_instances, 1);
        sidx_accel_destroy(lazy);
    }
    sidx_accel_destroy(eager);
    free(rays);
    free(want);
    free(got);
    sidx_city_free(&c);
}

/* ---- out of memory during an expansion ------------------------------------------- */

static void out_of_memory_is_the_query_s_error(void **state)
{
    (void)state;
    sidx_city c;
    assert_int_equal(sidx_city_make(1, 4, &c, NULL), SIDX_OK);
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.0f, 5.0f, -40.0f), sidx_v3(0.01f, 0.02f, 1.0f), 0.0f, INFINITY),
                     SIDX_OK);
    sidx_accel *eager = city_agg(&c, 1, 0, NULL);
    sidx_hit want;
    assert_int_equal(sidx_accel_intersect(eager, &r, NULL, &want), SIDX_OK);
    assert_int_not_equal(want.prim, SIDX_NO_HIT);
    int failed = 0;
    long k = 0;
    for (;; ++k) {
        tk_failing f = {1000000, 0};
        sidx_allocator al = tk_failing_allocator(&f);
        sidx_accel *lazy = city_agg(&c, 1, 1, &al);
        const long live = f.live;
        f.left = k; /* the expansion's k-th allocation fails */
        sidx_hit h;
        int occ = -1;
        const sidx_status s1 = sidx_accel_intersect(lazy, &r, NULL, &h);
        const sidx_status s2 = sidx_accel_occluded(lazy, &r, NULL, &occ);
        if (s1 == SIDX_OK) {
            /* k allocations were enough: the hit is the eager one's */
            assert_true(same_hit(&h, &want));
            assert_int_equal(s2, SIDX_OK);
            assert_int_equal(occ, 1);
            assert_int_equal(built(lazy), 1);
            sidx_accel_destroy(lazy);
            assert_int_equal(f.live, 0);
            break;
        }
        ++failed;
        assert_int_equal(s1, SIDX_ERR_NOMEM);
        /* nothing half built: the allocations the failed build made are given back */
        assert_int_equal(s2, SIDX_ERR_NOMEM);
        assert_int_equal(f.live, live);
        assert_int_equal(built(lazy), 0);
        sidx_accel_stats st;
        sidx_accel_stats_get(lazy, &st);
        assert_int_equal(st.unbuilt, 1);
        /* with memory again, a later query builds it */
        f.left = 1000000;
        assert_int_equal(sidx_accel_intersect(lazy, &r, NULL, &h), SIDX_OK);
        assert_true(same_hit(&h, &want));
        assert_int_equal(built(lazy), 1);
        sidx_accel_destroy(lazy);
        assert_int_equal(f.live, 0);
        assert_true(k < 1000);
    }
    assert_true(failed >= 3); /* the structure's build allocates several times */
    sidx_accel_destroy(eager);
    sidx_city_free(&c);
}

/* The eager and the lazy build of an aggregate without memory: the k-th
 * allocation fails, for every k until the build succeeds; nothing leaks. */
static void build_out_of_memory_leaks_nothing(void **state)
{
    (void)state;
    sidx_city c;
    assert_int_equal(sidx_city_make(3, 2, &c, NULL), SIDX_OK);
    for (int lazy = 0; lazy < 2; ++lazy) {
        long k = 0;
        for (;; ++k) {
            tk_failing f = {k, 0};
            sidx_allocator al = tk_failing_allocator(&f);
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.lazy = (uint32_t)lazy;
            o.alloc = &al;
            sidx_accel *a = NULL;
            const sidx_status s = sidx_aggregate_build_meshes(c.instances, 3, &o, &a, NULL);
            if (s == SIDX_OK) {
                sidx_accel_destroy(a);
                assert_int_equal(f.live, 0);
                break;
            }
            assert_int_equal(s, SIDX_ERR_NOMEM);
            assert_null(a);
            if (f.live != 0) fail_msg("lazy %d, allocation %ld failing: %ld not given back", lazy, k, f.live);
            assert_true(k < 10000);
        }
        assert_true(k > (lazy ? 5 : 10)); /* eager: the three buildings' builds fail too */
    }
    sidx_city_free(&c);
}

/* ---- events ------------------------------------------------------------------------ */

typedef struct evlog { int expand, builds, begin_after_expand; uint32_t node, count; } evlog;

static void on_event(const sidx_event *e, void *user)
{
    evlog *l = user;
    if (e->type == SIDX_EV_BUILD_LAZY_EXPAND) {
        l->expand++;
        l->node = e->node;
        l->count = e->count;
    } else if (e->type == SIDX_EV_BUILD_BEGIN && l->expand) {
        l->begin_after_expand++;
    } else if (e->type == SIDX_EV_BUILD_LEAF || e->type == SIDX_EV_BUILD_NODE) {
        l->builds++;
    }
}

static void expansion_events(void **state)
{
    (void)state;
    sidx_city c;
    assert_int_equal(sidx_city_make(4, 2, &c, NULL), SIDX_OK);
    sidx_accel *lazy = city_agg(&c, 4, 1, NULL);
    evlog log;
    memset(&log, 0, sizeof log);
    const sidx_hook hook = {on_event, &log, SIDX_EVMASK_BUILD};
    const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
    /* straight down onto building 0 */
    float m[12];
    memcpy(m, c.instances[0].xform, sizeof m);
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(m[3], 500.0f, m[11]), sidx_v3(0, -1, 0), 0.0f, INFINITY), SIDX_OK);
    sidx_hit h;
    assert_int_equal(sidx_accel_intersect(lazy, &r, &q, &h), SIDX_OK);
    assert_int_equal(h.instance, 0);
    assert_int_equal(log.expand, 1);
    assert_int_equal(log.node, 0);
    assert_int_equal(log.count, c.meshes[0].num_triangles);
    assert_int_equal(log.begin_after_expand, 1); /* the building's own build, on the query's hook */
    assert_true(log.builds > 0);
    memset(&log, 0, sizeof log);
    assert_int_equal(sidx_accel_intersect(lazy, &r, &q, &h), SIDX_OK);
    assert_int_equal(log.expand, 0); /* built once */
    sidx_accel_destroy(lazy);
    sidx_city_free(&c);
}

/* ---- the city ---------------------------------------------------------------------- */

static void city_is_deterministic(void **state)
{
    (void)state;
    sidx_city a, b;
    assert_int_equal(sidx_city_make(9, 3, &a, NULL), SIDX_OK);
    assert_int_equal(sidx_city_make(9, 3, &b, NULL), SIDX_OK);
    for (uint32_t i = 0; i < 9; ++i) {
        const sidx_mesh *x = &a.meshes[i], *y = &b.meshes[i];
        assert_int_equal(x->num_vertices, y->num_vertices);
        assert_int_equal(x->num_triangles, y->num_triangles);
        assert_memory_equal(x->positions, y->positions, x->num_vertices * sizeof *x->positions);
        assert_memory_equal(x->indices, y->indices, 3u * x->num_triangles * sizeof *x->indices);
        assert_memory_equal(a.instances[i].xform, b.instances[i].xform, sizeof a.instances[i].xform);
        assert_ptr_equal(a.instances[i].mesh, x);
        assert_null(a.instances[i].accel);
        /* distinct buildings: no two alike */
        for (uint32_t j = 0; j < i; ++j)
            assert_true(a.meshes[j].num_vertices != x->num_vertices ||
                        memcmp(a.meshes[j].positions, x->positions, x->num_vertices * sizeof *x->positions));
    }
    sidx_city_free(&a);
    sidx_city_free(&b);
    /* full size: at least 10k triangles a building */
    assert_int_equal(sidx_city_make(3, 0, &a, NULL), SIDX_OK);
    for (uint32_t i = 0; i < 3; ++i) assert_true(a.meshes[i].num_triangles >= 10000);
    sidx_city_free(&a);
    /* the flattened city of sidx_scene_make */
    sidx_mesh m;
    assert_int_equal(sidx_scene_open("city:4", &m, NULL), SIDX_OK);
    assert_int_equal(sidx_city_make(4, 8, &a, NULL), SIDX_OK);
    uint32_t t = 0;
    for (uint32_t i = 0; i < 4; ++i) t += a.meshes[i].num_triangles;
    assert_int_equal(m.num_triangles, t);
    sidx_city_free(&a);
    sidx_mesh_free(&m);
    sidx_city_free(NULL);
    assert_int_equal(sidx_city_make(0, 3, &a, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_city_make(70000, 3, &a, NULL), SIDX_ERR_LIMIT);
    assert_int_equal(sidx_city_make(1, 300, &a, NULL), SIDX_ERR_LIMIT);
}

static void argument_errors(void **state)
{
    (void)state;
    sidx_city c;
    assert_int_equal(sidx_city_make(2, 2, &c, NULL), SIDX_OK);
    sidx_accel *a = (sidx_accel *)1;
    assert_int_equal(sidx_aggregate_build_meshes(c.instances, 2, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_aggregate_build_meshes(NULL, 2, NULL, &a, NULL), SIDX_ERR_INVALID_ARG);
    assert_null(a);
    sidx_mesh_instance bad = c.instances[0];
    bad.mesh = NULL;
    assert_int_equal(sidx_aggregate_build_meshes(&bad, 1, NULL, &a, NULL), SIDX_ERR_INVALID_ARG);
    bad = c.instances[0];
    bad.accel = "no-such-structure";
    assert_int_equal(sidx_aggregate_build_meshes(&bad, 1, NULL, &a, NULL), SIDX_ERR_UNKNOWN_ACCEL);
    bad = c.instances[0];
    bad.xform[0] = bad.xform[2] = 0.0f; /* singular */
    bad.xform[8] = bad.xform[10] = 0.0f;
    assert_int_equal(sidx_aggregate_build_meshes(&bad, 1, NULL, &a, NULL), SIDX_ERR_INVALID_ARG);
    /* options the structure rejects: found at build time, lazy or not */
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.empty_bonus = 2.0f;
    bad = c.instances[0];
    bad.accel = "kdtree";
    bad.opt = &bo;
    sidx_build_options lz;
    memset(&lz, 0, sizeof lz);
    lz.lazy = 1;
    assert_int_not_equal(sidx_aggregate_build_meshes(&bad, 1, &lz, &a, NULL), SIDX_OK);
    assert_null(a);
    /* an empty aggregate */
    assert_int_equal(sidx_aggregate_build_meshes(NULL, 0, &lz, &a, NULL), SIDX_OK);
    sidx_ray r;
    sidx_hit h;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 1, -5), sidx_v3(0, 0, 1), 0.0f, INFINITY), SIDX_OK);
    assert_int_equal(sidx_accel_intersect(a, &r, NULL, &h), SIDX_OK);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    sidx_accel_destroy(a);
    sidx_city_free(&c);
}

int main(void)
{
    alarm(600); /* a wait on a part never published would hang: fail instead */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lazy_hits_equal_eager),      cmocka_unit_test(threads_race_into_one_instance),
        cmocka_unit_test(out_of_memory_is_the_query_s_error), cmocka_unit_test(build_out_of_memory_leaks_nothing),
        cmocka_unit_test(expansion_events),
        cmocka_unit_test(city_is_deterministic),      cmocka_unit_test(argument_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
