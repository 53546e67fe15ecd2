/* test_bvh_optimize.c — the reinsertion pass (bvh_optimize.c).
 *
 *  - the optimised tree is well formed: pre-order layout (left = id + 1),
 *    every primitive in exactly one leaf, boxes containing their children
 *    and triangles, depth within the limit;
 *  - its SAH cost is at most the unoptimised one;
 *  - closest hits on random rays have exactly brute force's t, for bvh,
 *    bvh-obb, bvh4 and bvh8;
 *  - one BUILD_REINSERT event per move the pass reports;
 *  - a budget of 0 leaves the tree bit-identical; a large one gives the
 *    same tree every time;
 *  - out of memory at any step: a clean failure or a valid tree, no leak.
 * Includes the BVH's private header to walk the node array. */
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
#include "bvh_internal.h"
#include "common/testkit.h"

static const char *const scenes[] = {"teapot", "soup", "stadium", "cornell", "menger"};
#define NSCENES (sizeof scenes / sizeof scenes[0])
#define BIG_BUDGET 1e6f /* ms: the pass ends by itself long before */

/* The scene at its default detail, or at its small sizes (under valgrind
 * and the sanitizers) a coarser one: the pass runs to its end on every
 * scene either way, on fewer triangles. */
static sidx_mesh scene(const char *name)
{
    static const char *const small[][2] = {
        {"teapot", "teapot:12"}, {"soup", "soup:500"}, {"stadium", "stadium:24"}, {"menger", "menger:1"}};
    const char *spec = name;
    for (size_t i = 0; tk_fast_tests() && i < sizeof small / sizeof small[0]; ++i)
        if (!strcmp(small[i][0], name)) spec = small[i][1];
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_open(spec, &m, &err) != SIDX_OK) fail_msg("scene %s: %s", spec, err.message);
    return m;
}

static sidx_accel *build(const char *name, const sidx_mesh *m, float optimize_ms, const sidx_hook *hook)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.optimize_ms = optimize_ms;
    bo.hook = hook;
    sidx_accel *a = NULL;
    sidx_error err;
    if (sidx_accel_build(name, m, &bo, &a, &err) != SIDX_OK) fail_msg("build %s: %s", name, err.message);
    return a;
}

static int inside(sidx_aabb outer, sidx_aabb in)
{
    return in.min.x >= outer.min.x && in.min.y >= outer.min.y && in.min.z >= outer.min.z &&
           in.max.x <= outer.max.x && in.max.y <= outer.max.y && in.max.z <= outer.max.z;
}

/* Walks node i; returns the index after its subtree (pre-order). */
static uint32_t check_node(const bvh *b, uint32_t i, uint32_t depth, uint32_t *next_prim, uint8_t *seen,
                           uint32_t *leaves)
{
    assert_true(i < b->num_nodes);
    assert_true(depth <= BVH_DEPTH_LIMIT);
    const bvh_node *n = &b->nodes[i];
    const sidx_aabb box = bvh_node_box(n);
    if (bvh_is_leaf(n)) {
        ++*leaves;
        assert_int_equal(n->left_or_first, *next_prim); /* leaves in pre-order cover prim_id in order */
        for (uint32_t j = 0; j < bvh_count(n); ++j) {
            const uint32_t p = n->left_or_first + j;
            assert_false(seen[b->prim_id[p]]);
            seen[b->prim_id[p]] = 1;
            for (int k = 0; k < 3; ++k) {
                const sidx_vec3 v = b->tris[p].v[k];
                const sidx_aabb pt = {v, v};
                assert_true(inside(box, pt));
            }
        }
        *next_prim += bvh_count(n);
        return i + 1;
    }
    const uint32_t right = n->left_or_first;
    assert_true(inside(box, bvh_node_box(&b->nodes[i + 1])));
    assert_true(right > i + 1 && right < b->num_nodes);
    assert_true(inside(box, bvh_node_box(&b->nodes[right])));
    const uint32_t after_left = check_node(b, i + 1, depth + 1, next_prim, seen, leaves);
    assert_int_equal(after_left, right);
    return check_node(b, right, depth + 1, next_prim, seen, leaves);
}

static void check_tree(const sidx_accel *a, const sidx_mesh *m)
{
    const bvh *b = a->impl;
    uint8_t *seen = calloc(m->num_triangles, 1);
    assert_non_null(seen);
    uint32_t next = 0, leaves = 0;
    assert_int_equal(check_node(b, 0, 0, &next, seen, &leaves), b->num_nodes);
    assert_int_equal(next, b->num_prims);
    assert_int_equal(leaves, b->num_leaves);
    for (uint32_t t = 0; t < m->num_triangles; ++t) assert_true(seen[t]);
    free(seen);
}

/* Random rays from around the scene towards points inside it: closest t
 * must equal brute force's bit for bit (the primitive may differ only on
 * a tie: a shared edge hit at the same t). */
static void check_hits(const sidx_accel *a, const sidx_accel *ref, const sidx_mesh *m, uint64_t seed)
{
    const sidx_aabb sb = sidx_mesh_bounds(m);
    const sidx_vec3 c = sidx_v3_scale(sidx_v3_add(sb.min, sb.max), 0.5f);
    const sidx_vec3 ext = sidx_v3_sub(sb.max, sb.min);
    const sidx_aabb around = {sidx_v3_sub(c, sidx_v3_scale(ext, 1.5f)), sidx_v3_add(c, sidx_v3_scale(ext, 1.5f))};
    tk_rng rng;
    tk_rng_seed(&rng, seed);
    const int n = tk_fast_tests() ? 600 : 3000;
    int hits = 0;
    for (int i = 0; i < n; ++i) {
        const sidx_vec3 o = tk_rng_in_box(&rng, around), t = tk_rng_in_box(&rng, sb);
        sidx_ray r;
        if (sidx_ray_init(&r, o, sidx_v3_sub(t, o), 0.0f, INFINITY) != SIDX_OK) continue;
        sidx_hit h, hr;
        assert_int_equal(sidx_accel_intersect(a, &r, NULL, &h), SIDX_OK);
        assert_int_equal(sidx_accel_intersect(ref, &r, NULL, &hr), SIDX_OK);
        assert_int_equal(h.prim == SIDX_NO_HIT, hr.prim == SIDX_NO_HIT);
        if (hr.prim != SIDX_NO_HIT) {
            assert_memory_equal(&h.t, &hr.t, sizeof h.t);
            ++hits;
        }
        int occ = 0;
        assert_int_equal(sidx_accel_occluded(a, &r, NULL, &occ), SIDX_OK);
        assert_int_equal(occ, hr.prim != SIDX_NO_HIT);
    }
    assert_true(hits > n / 30);
}

static void test_valid_better_exact(void **state)
{
    (void)state;
    for (size_t s = 0; s < NSCENES; ++s) {
        sidx_mesh m = scene(scenes[s]);
        sidx_accel *ref = build("brute", &m, 0.0f, NULL);
        sidx_accel *plain = build("bvh", &m, 0.0f, NULL);
        sidx_accel *opt = build("bvh", &m, BIG_BUDGET, NULL);
        check_tree(opt, &m);
        sidx_accel_stats s0, s1;
        sidx_accel_stats_get(plain, &s0);
        sidx_accel_stats_get(opt, &s1);
        assert_true(s1.sah_cost <= s0.sah_cost);
        assert_int_equal(s1.nodes, s0.nodes);
        assert_int_equal(s1.leaves, s0.leaves);
        check_hits(opt, ref, &m, s + 1);
        const char *others[] = {"bvh-obb", "bvh-median", "bvh4", "bvh8"};
        for (size_t k = 0; k < sizeof others / sizeof others[0]; ++k) {
            sidx_accel *w = build(others[k], &m, BIG_BUDGET, NULL);
            check_hits(w, ref, &m, 100 + s);
            sidx_accel_destroy(w);
        }
        sidx_accel_destroy(opt);
        sidx_accel_destroy(plain);
        sidx_accel_destroy(ref);
        sidx_mesh_free(&m);
    }
}

static void count_reinsert(const sidx_event *ev, void *user)
{
    uint32_t *n = user;
    assert_int_equal(ev->type, SIDX_EV_BUILD_REINSERT);
    assert_true(ev->cost > 0.0f);
    assert_true(ev->node != ev->parent && ev->node != ev->aux && ev->parent != ev->aux);
    ++*n;
}

static void test_events_match_moves(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    sidx_accel *a = build("bvh", &m, 0.0f, NULL);
    const bvh *b = a->impl;
    const double before = b->sah_cost;
    uint32_t events = 0;
    sidx_hook h = {count_reinsert, &events, SIDX_EVMASK(SIDX_EV_BUILD_REINSERT)};
    a->opt.hook = &h;
    a->opt.optimize_ms = BIG_BUDGET;
    const uint32_t moves = sidx__bvh_optimize(a, a->impl);
    assert_true(moves > 0);
    assert_int_equal(events, moves);
    assert_true(((const bvh *)a->impl)->sah_cost < before);
    a->opt.hook = NULL;
    check_tree(a, &m);

    /* the same count through the build, with a hook taking every event */
    uint32_t all = 0;
    sidx_hook h2 = {count_reinsert, &all, SIDX_EVMASK(SIDX_EV_BUILD_REINSERT)};
    sidx_accel *c = build("bvh", &m, BIG_BUDGET, &h2);
    assert_int_equal(all, moves);
    sidx_accel_destroy(c);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

static void test_budget_zero_and_determinism(void **state)
{
    (void)state;
    sidx_mesh m = scene("stadium");
    sidx_accel *a = build("bvh", &m, 0.0f, NULL);
    sidx_accel *d = NULL;
    sidx_error err;
    assert_int_equal(sidx_accel_build("bvh", &m, NULL, &d, &err), SIDX_OK);
    const bvh *ba = a->impl, *bd = d->impl;
    assert_int_equal(ba->num_nodes, bd->num_nodes);
    assert_memory_equal(ba->nodes, bd->nodes, ba->num_nodes * sizeof *ba->nodes);
    assert_memory_equal(ba->prim_id, bd->prim_id, ba->num_prims * sizeof *ba->prim_id);
    assert_int_equal(sidx__bvh_optimize(a, a->impl), 0); /* budget 0: nothing */
    assert_memory_equal(ba->nodes, bd->nodes, ba->num_nodes * sizeof *ba->nodes);

    sidx_accel *o1 = build("bvh", &m, BIG_BUDGET, NULL), *o2 = build("bvh", &m, BIG_BUDGET, NULL);
    const bvh *b1 = o1->impl, *b2 = o2->impl;
    assert_int_equal(b1->num_nodes, b2->num_nodes);
    assert_memory_equal(b1->nodes, b2->nodes, b1->num_nodes * sizeof *b1->nodes);
    assert_memory_equal(b1->prim_id, b2->prim_id, b1->num_prims * sizeof *b1->prim_id);
    sidx_accel_destroy(o1);
    sidx_accel_destroy(o2);
    sidx_accel_destroy(a);
    sidx_accel_destroy(d);
    sidx_mesh_free(&m);
}

static void test_bad_budget_refused(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.optimize_ms = -1.0f;
    sidx_accel *a = NULL;
    sidx_error err;
    assert_int_equal(sidx_accel_build("bvh", &m, &bo, &a, &err), SIDX_ERR_INVALID_ARG);
    bo.optimize_ms = NAN;
    assert_int_equal(sidx_accel_build("bvh", &m, &bo, &a, &err), SIDX_ERR_INVALID_ARG);
    assert_null(a);
    sidx_mesh_free(&m);
}

/* An allocator failing from the k-th call on, counting what is live. */
typedef struct {
    long calls, fail_at, live;
} fail_alloc;
static void *fa_alloc(size_t size, void *user)
{
    fail_alloc *f = user;
    if (f->calls++ >= f->fail_at) return NULL;
    void *p = malloc(size);
    if (p) ++f->live;
    return p;
}
static void fa_free(void *p, void *user)
{
    fail_alloc *f = user;
    if (p) --f->live;
    free(p);
}

/* Out of memory at every step, the pass included: a clean failure or a
 * valid tree (the pass without its scratch leaves the tree as built),
 * nothing leaked. */
static void test_alloc_failures(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    const char *names[] = {"bvh", "bvh8"};
    for (size_t n = 0; n < 2; ++n) {
        for (long k = 0; k < 64; ++k) {
            fail_alloc f = {0, k, 0};
            sidx_allocator al = {fa_alloc, fa_free, &f};
            sidx_build_options bo;
            memset(&bo, 0, sizeof bo);
            bo.alloc = &al;
            bo.optimize_ms = BIG_BUDGET;
            sidx_accel *a = NULL;
            sidx_error err;
            const sidx_status s = sidx_accel_build(names[n], &m, &bo, &a, &err);
            if (s == SIDX_OK) {
                if (n == 0) check_tree(a, &m);
                sidx_accel_destroy(a);
            } else {
                assert_int_equal(s, SIDX_ERR_NOMEM);
                assert_null(a);
            }
            assert_int_equal(f.live, 0);
        }
    }
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valid_better_exact),
        cmocka_unit_test(test_events_match_moves),
        cmocka_unit_test(test_budget_zero_and_determinism),
        cmocka_unit_test(test_bad_budget_refused),
        cmocka_unit_test(test_alloc_failures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
