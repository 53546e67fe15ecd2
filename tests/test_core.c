/* test_core.c — the accelerator interface, the hook contract and the
 * brute-force baseline: exact event streams, errors as values, allocation
 * failure, u/v and normals only on request. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"

/* Two triangles: T0 in z = 0, T1 in z = -1 (behind it for a ray going -z),
 * and T2 off to the side. */
static const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, -1, 1, 0, -1, 0, 1, -1, 5, 5, 0, 6, 5, 0, 5, 6, 0};
static const uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8};

static sidx_mesh make_mesh(void)
{
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 9, idx, 3, NULL), SIDX_OK);
    return m;
}

typedef struct { sidx_event ev[64]; int n; } log_t;
static void log_hook(const sidx_event *e, void *user)
{
    log_t *l = user;
    if (l->n < 64) l->ev[l->n++] = *e;
}

static void brute_event_stream_is_exact(void **state)
{
    (void)state;
    sidx_mesh m = make_mesh();
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &a, NULL), SIDX_OK);
    log_t log = {.n = 0};
    sidx_hook hook = {log_hook, &log, 0};
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 7};
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, 1), sidx_v3(0, 0, -1), 0, INFINITY), SIDX_OK);
    sidx_hit h;
    assert_int_equal(sidx_accel_intersect(a, &r, &q, &h), SIDX_OK);
    assert_int_equal(h.prim, 0);
    assert_float_equal(h.t, 1.0f, 0.0f);
    const sidx_event_type expect[] = {SIDX_EV_RAY_BEGIN, SIDX_EV_PRIM_TEST, SIDX_EV_HIT_UPDATE, SIDX_EV_PRIM_TEST,
                                      SIDX_EV_PRIM_TEST, SIDX_EV_TERMINATE, SIDX_EV_RAY_END};
    assert_int_equal(log.n, 7);
    for (int i = 0; i < 7; ++i) {
        assert_int_equal(log.ev[i].type, expect[i]);
        assert_int_equal(log.ev[i].ray_id, 7);
    }
    assert_int_equal(log.ev[1].prim, 0);
    assert_int_equal(log.ev[1].result, 1);
    assert_int_equal(log.ev[3].prim, 1);
    assert_int_equal(log.ev[3].result, 0); /* T1 at t = 2 is beyond the best hit t = 1 */
    assert_int_equal(log.ev[4].prim, 2);
    assert_int_equal(log.ev[4].result, 0);
    assert_int_equal(log.ev[5].reason, SIDX_TERM_STACK_EMPTY);
    assert_int_equal(log.ev[6].prim, 0);
    assert_float_equal(log.ev[6].t, 1.0f, 0.0f);

    /* the mask filters: only PRIM_TEST */
    log.n = 0;
    hook.mask = SIDX_EVMASK(SIDX_EV_PRIM_TEST);
    sidx_accel_intersect(a, &r, &q, &h);
    assert_int_equal(log.n, 3);
    /* traced and untraced give the same hit */
    sidx_hit h2;
    sidx_accel_intersect(a, &r, NULL, &h2);
    assert_int_equal(h2.prim, h.prim);
    assert_float_equal(h2.t, h.t, 0.0f);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

static void brute_closest_any_and_miss(void **state)
{
    (void)state;
    sidx_mesh m = make_mesh();
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &a, NULL), SIDX_OK);
    sidx_ray r;
    sidx_hit h;
    int occ = -1;
    /* from below: T1 (z = -1) is hit first */
    sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, -3), sidx_v3(0, 0, 1), 0, INFINITY);
    sidx_accel_intersect(a, &r, NULL, &h);
    assert_int_equal(h.prim, 1);
    assert_float_equal(h.t, 2.0f, 0.0f);
    assert_int_equal(h.u, 0.0f); /* not asked for: zero */
    assert_int_equal(sidx_accel_occluded(a, &r, NULL, &occ), SIDX_OK);
    assert_int_equal(occ, 1);
    /* segment that stops before T1 */
    sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, -3), sidx_v3(0, 0, 1), 0, 1.5f);
    sidx_accel_intersect(a, &r, NULL, &h);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    assert_true(isinf(h.t));
    assert_int_equal(sidx_accel_occluded(a, &r, NULL, &occ), SIDX_OK);
    assert_int_equal(occ, 0);
    /* miss everything */
    sidx_ray_init(&r, sidx_v3(3, 3, 3), sidx_v3(0, 0, 1), 0, INFINITY);
    sidx_accel_intersect(a, &r, NULL, &h);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    assert_int_equal(h.instance, SIDX_NO_HIT);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

static void uv_and_normal_only_on_request(void **state)
{
    (void)state;
    sidx_mesh m = make_mesh();
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &a, NULL), SIDX_OK);
    sidx_ray r;
    sidx_hit h;
    sidx_ray_init(&r, sidx_v3(0.25f, 0.5f, 1), sidx_v3(0, 0, -1), 0, INFINITY);
    sidx_query q = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    sidx_accel_intersect(a, &r, &q, &h);
    assert_float_equal(h.u, 0.25f, 1e-6f);
    assert_float_equal(h.v, 0.5f, 1e-6f);
    assert_float_equal(h.ng.z, 0.0f, 0.0f);
    q.flags = SIDX_QUERY_NORMAL;
    sidx_accel_intersect(a, &r, &q, &h);
    assert_float_equal(h.u, 0.0f, 0.0f);
    assert_float_equal(h.ng.z, 1.0f, 0.0f); /* e1 × e2 = (1,0,0) × (0,1,0) */
    /* batch query: ids increase */
    sidx_ray rays[2] = {r, r};
    sidx_hit hits[2];
    assert_int_equal(sidx_accel_intersect_n(a, rays, 2, NULL, hits), SIDX_OK);
    assert_int_equal(hits[1].prim, 0);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

static void errors_are_values(void **state)
{
    (void)state;
    sidx_mesh m = make_mesh();
    sidx_accel *a = (sidx_accel *)&m; /* must be reset to NULL on failure */
    sidx_error err;
    assert_int_equal(sidx_accel_build("no-such-thing", &m, NULL, &a, &err), SIDX_ERR_UNKNOWN_ACCEL);
    assert_null(a);
    assert_non_null(strstr(err.message, "no-such-thing"));
    assert_int_equal(sidx_accel_build(NULL, &m, NULL, &a, &err), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_build("brute", NULL, NULL, &a, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_build("brute", &m, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    sidx_build_options bad = {0};
    bad.tri = (sidx_tri_method)42;
    assert_int_equal(sidx_accel_build("brute", &m, &bad, &a, &err), SIDX_ERR_INVALID_ARG);
    memset(&bad, 0, sizeof bad);
    bad.empty_bonus = 1.5f;
    assert_int_equal(sidx_accel_build("brute", &m, &bad, &a, &err), SIDX_ERR_INVALID_ARG);
    /* NaN vertex: refused at build, never traced */
    m.positions[4].y = NAN;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &a, &err), SIDX_ERR_BAD_GEOMETRY);
    assert_null(a);
    m.positions[4].y = 0.0f;
    /* index out of range */
    m.indices[5] = 99;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &a, &err), SIDX_ERR_BAD_GEOMETRY);
    m.indices[5] = 5;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &a, NULL), SIDX_OK);
    sidx_ray r;
    sidx_ray_init(&r, sidx_v3(0, 0, 1), sidx_v3(0, 0, -1), 0, INFINITY);
    sidx_hit h;
    sidx_accel_stats st;
    assert_int_equal(sidx_accel_intersect(NULL, &r, NULL, &h), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_intersect(a, NULL, NULL, &h), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_intersect(a, &r, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_occluded(a, &r, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_stats_get(a, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_stats_get(a, &st), SIDX_OK);
    assert_string_equal(st.name, "brute");
    assert_int_equal(sidx_accel_refit(NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_intersect_n(a, NULL, 1, NULL, &h), SIDX_ERR_INVALID_ARG);
    assert_null(sidx_accel_name(NULL));
    assert_string_equal(sidx_accel_name(a), "brute");
    assert_ptr_equal(sidx_accel_mesh(a), &m);
    sidx_accel_destroy(a);
    sidx_accel_destroy(NULL);
    sidx_mesh_free(&m);
}

/* An allocator that fails the k-th call (and counts live blocks). */
typedef struct { int calls, fail_at, live; } failing_alloc;
static void *fa_alloc(size_t n, void *u)
{
    failing_alloc *f = u;
    if (++f->calls == f->fail_at) return NULL;
    void *p = malloc(n);
    if (p) f->live++;
    return p;
}
static void fa_free(void *p, void *u)
{
    failing_alloc *f = u;
    if (p) { f->live--; free(p); }
}

static void allocation_failure_every_k_for_every_structure(void **state)
{
    (void)state;
    /* For each registered structure: fail the 1st, 2nd, ... allocation of a
     * build until one succeeds; each failure must return SIDX_ERR_NOMEM and
     * leave nothing allocated. */
    /* 80 triangles: small enough to fail every one of a build's allocations
     * (a kd-tree allocates per node) in well under a second per structure. */
    sidx_mesh m;
    assert_int_equal(sidx_scene_make("icosphere", 1, &m, NULL), SIDX_OK);
    for (size_t i = 0; i < sidx_accel_registered_count(); ++i) {
        const char *name = sidx_accel_registered_name(i);
        /* Each run of the loop rebuilds up to allocation k, so failing
         * every one of n allocations costs n²/2: rayclass makes about 4,800
         * on these 80 triangles, most of them one per node of the same
         * kind.  Every k up to 512 (every allocation of the other
         * structures), then every 7th, a stride prime to the per-node
         * pattern so that each kind of allocation is still failed.  Under
         * valgrind and the sanitizers (SIDX_FAST_TESTS) every k up to 64,
         * then every ~8th: each run is 30x slower there. */
        const int fast = getenv("SIDX_FAST_TESTS") != NULL;
        int k;
        for (k = 1; k < 20000; k += (fast && k > 64) ? k / 8 : k > 512 ? 7 : 1) {
            failing_alloc f = {0, k, 0};
            sidx_allocator al = {fa_alloc, fa_free, &f};
            sidx_build_options o = {0};
            o.alloc = &al;
            sidx_accel *a = NULL;
            sidx_status s = sidx_accel_build(name, &m, &o, &a, NULL);
            if (s == SIDX_OK) {
                /* Either the failing call was never reached (we are done), or
                 * the structure recovered from it (a documented fallback):
                 * both must leave nothing behind once destroyed. */
                sidx_accel_destroy(a);
                assert_int_equal(f.live, 0);
                if (f.calls < k) break;
                continue;
            }
            if (s != SIDX_ERR_NOMEM) fail_msg("%s: failing allocation %d gave %s", name, k, sidx_status_str(s));
            assert_null(a);
            if (f.live != 0) fail_msg("%s: %d blocks leaked when allocation %d failed", name, f.live, k);
        }
        if (k >= 20000) fail_msg("%s: still allocating after 20000 injected failures", name);
        print_message("%-16s builds with about %d allocations; each failure handled\n", name, k - 1);
    }
    sidx_mesh_free(&m);
}

static void registry_and_auto(void **state)
{
    (void)state;
    assert_true(sidx_accel_registered_count() >= 1);
    assert_string_equal(sidx_accel_registered_name(0), "brute");
    assert_null(sidx_accel_registered_name(100000));
    assert_true(sidx_accel_is_registered("brute"));
    assert_true(sidx_accel_is_registered("auto"));
    assert_false(sidx_accel_is_registered("nope"));
    sidx_mesh m = make_mesh();
    log_t log = {.n = 0};
    sidx_hook hook = {log_hook, &log, SIDX_EVMASK(SIDX_EV_NOTE)};
    sidx_build_options o = {0};
    o.hook = &hook;
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("auto", &m, &o, &a, NULL), SIDX_OK);
    assert_string_equal(sidx_accel_name(a), "brute"); /* 3 triangles: brute force wins */
    assert_int_equal(log.n, 1);
    assert_non_null(strstr(log.ev[0].text, "tiny"));
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

static void traversal_names(void **state)
{
    (void)state;
    for (int t = 0; t < SIDX_TRAVERSE_COUNT; ++t) {
        sidx_traversal back;
        assert_int_equal(sidx_traversal_parse(sidx_traversal_name((sidx_traversal)t), &back), SIDX_OK);
        assert_int_equal(back, t);
    }
    sidx_traversal tr;
    assert_int_equal(sidx_traversal_parse("sideways", &tr), SIDX_ERR_INVALID_ARG);
    assert_string_equal(sidx_event_type_name(SIDX_EV_MAILBOX_HIT), "mailbox_hit");
    assert_string_equal(sidx_leaf_reason_name(SIDX_LEAF_NO_GAIN), "no_gain");
    assert_string_equal(sidx_term_reason_name(SIDX_TERM_HIT_IN_CELL), "hit_in_cell");
    assert_string_equal(sidx_event_type_name((sidx_event_type)99), "unknown");
}

static void traced_tests_emit(void **state)
{
    (void)state;
    log_t log = {.n = 0};
    sidx_hook hook = {log_hook, &log, 0};
    sidx_ray r;
    sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, 1), sidx_v3(0, 0, -1), 0, INFINITY);
    float t = 0;
    assert_true(sidx_trace_triangle(&hook, SIDX_TRI_WATERTIGHT, 5, &r, sidx_v3(0, 0, 0), sidx_v3(1, 0, 0),
                                    sidx_v3(0, 1, 0), INFINITY, &t, NULL, NULL));
    const sidx_aabb box = {{0, 0, -1}, {1, 1, 0}};
    float tn, tf;
    assert_true(sidx_trace_aabb(&hook, SIDX_BOX_ROBUST, 3, &r, &box, 0, INFINITY, &tn, &tf));
    assert_false(sidx_trace_aabb(NULL, SIDX_BOX_ROBUST, 3, &r, NULL, 0, INFINITY, &tn, &tf));
    assert_int_equal(log.n, 2);
    assert_int_equal(log.ev[0].type, SIDX_EV_PRIM_TEST);
    assert_int_equal(log.ev[0].prim, 5);
    assert_float_equal(log.ev[0].t, 1.0f, 0.0f);
    assert_int_equal(log.ev[1].type, SIDX_EV_BOX_TEST);
    assert_int_equal(log.ev[1].node, 3);
    assert_float_equal(log.ev[1].t_near, 1.0f, 0.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(brute_event_stream_is_exact),
        cmocka_unit_test(brute_closest_any_and_miss),
        cmocka_unit_test(uv_and_normal_only_on_request),
        cmocka_unit_test(errors_are_values),
        cmocka_unit_test(allocation_failure_every_k_for_every_structure),
        cmocka_unit_test(registry_and_auto),
        cmocka_unit_test(traversal_names),
        cmocka_unit_test(traced_tests_emit),
    };
    return cmocka_run_group_tests_name("core", tests, NULL, NULL);
}
