/* test_parallel.c — sidx_trace_parallel / sidx_occluded_parallel and the
 * parallel binned-SAH build.
 *
 *  - tracing on 1, 2, 3 and 8 threads gives exactly the hits of
 *    sidx_accel_intersect_n (every ray traced once, none skipped, none
 *    twice, whatever the batch boundaries), and the same any-hit answers;
 *  - a traced query runs on one thread and delivers every event;
 *  - the untraced build (parallel.c, on any number of threads) produces
 *    the SAME tree as the traced recursive build, node for node and primitive for primitive, on
 *    several scenes and option sets, and bvh4/bvh8 built on 2 threads
 *    answer exactly like their one-thread builds;
 *  - the persistent worker pool: several application threads calling
 *    sidx_trace_parallel and parallel builds at the same time (one gets
 *    the pool, the others threads of their own) all get exact answers,
 *    and a forked child (which inherits none of the pool's threads) can
 *    still trace in parallel;
 *  - allocation failures during a parallel build leak nothing;
 *  - NULL arguments are rejected. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sidx/sidx.h"
#include "sidx/parallel.h"
#include "bvh_wide_internal.h"
#include "common/testkit.h"

static sidx_mesh scene(const char *name, uint32_t detail)
{
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make(name, detail, &m, &err) != SIDX_OK) fail_msg("scene %s: %s", name, err.message);
    return m;
}

static sidx_accel *build(const char *name, const sidx_mesh *m, uint32_t threads)
{
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.threads = threads;
    sidx_accel *a = NULL;
    sidx_error err;
    if (sidx_accel_build(name, m, &o, &a, &err) != SIDX_OK) fail_msg("build %s: %s", name, err.message);
    return a;
}

static sidx_ray *rays_for(const sidx_mesh *m, size_t n, tk_ray_kind kind)
{
    tk_rayrec *rec = malloc(n * sizeof *rec);
    sidx_ray *r = malloc(n * sizeof *r);
    assert_non_null(rec);
    assert_non_null(r);
    tk_make_rays(m, kind, n, 3, rec);
    for (size_t i = 0; i < n; ++i) assert_int_equal(tk_ray_from(&rec[i], &r[i]), SIDX_OK);
    free(rec);
    return r;
}

static void test_trace_matches_serial(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot", 0);
    const size_t n = tk_fast_tests() ? 1000 : 5003; /* not a multiple of the batch */
    sidx_ray *rays = rays_for(&m, n, TK_RAYS_DIFFUSE);
    sidx_hit *ref = malloc(n * sizeof *ref), *got = malloc(n * sizeof *got);
    uint8_t *occ = malloc(n);
    assert_non_null(ref);
    assert_non_null(got);
    assert_non_null(occ);
    const char *names[] = {"bvh", "bvh8", "kdtree"};
    for (size_t k = 0; k < 3; ++k) {
        sidx_accel *a = build(names[k], &m, 1);
        const sidx_query q = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, NULL, 0};
        assert_int_equal(sidx_accel_intersect_n(a, rays, n, &q, ref), SIDX_OK);
        const unsigned threads[] = {1, 2, 3, 8, 0};
        for (size_t t = 0; t < 5; ++t) {
            memset(got, 0xAB, n * sizeof *got);
            assert_int_equal(sidx_trace_parallel(a, rays, n, &q, got, threads[t]), SIDX_OK);
            assert_memory_equal(got, ref, n * sizeof *ref);
            memset(occ, 7, n);
            assert_int_equal(sidx_occluded_parallel(a, rays, n, NULL, occ, threads[t]), SIDX_OK);
            for (size_t i = 0; i < n; ++i) assert_int_equal(occ[i], ref[i].prim != SIDX_NO_HIT);
        }
        sidx_accel_destroy(a);
    }
    free(ref);
    free(got);
    free(occ);
    free(rays);
    sidx_mesh_free(&m);
}

typedef struct evcount { uint64_t begins, ends; } evcount;
static void ev_fn(const sidx_event *ev, void *user)
{
    evcount *c = user;
    if (ev->type == SIDX_EV_RAY_BEGIN) c->begins++;
    if (ev->type == SIDX_EV_RAY_END) c->ends++;
}

static void test_traced_query_serial(void **state)
{
    (void)state;
    sidx_mesh m = scene("icosphere", 0);
    const size_t n = 700;
    sidx_ray *rays = rays_for(&m, n, TK_RAYS_PRIMARY);
    sidx_hit *h = malloc(n * sizeof *h);
    assert_non_null(h);
    sidx_accel *a = build("bvh8", &m, 1);
    evcount c = {0, 0};
    const sidx_hook hook = {ev_fn, &c, 0};
    const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
    /* ev_fn is not thread-safe: this must run on one thread to count right */
    assert_int_equal(sidx_trace_parallel(a, rays, n, &q, h, 4), SIDX_OK);
    assert_int_equal(c.begins, n);
    assert_int_equal(c.ends, n);
    sidx_accel_destroy(a);
    free(h);
    free(rays);
    sidx_mesh_free(&m);
}

static void ignore_event(const sidx_event *e, void *user)
{
    (void)e;
    (void)user;
}

/* The reference is the recursive builder of bvh_build.c, which a build
 * hook selects (it emits the events); every untraced build, on one thread
 * or several, goes through parallel.c and must give the same tree. */
static void check_same_tree(const sidx_mesh *m, const sidx_build_options *base)
{
    const unsigned threads[] = {1, 2, 3, 4};
    sidx_accel *ref = NULL;
    sidx_build_options o = *base;
    const sidx_hook quiet = {ignore_event, NULL, 0};
    o.threads = 1;
    o.hook = &quiet;
    assert_int_equal(sidx_accel_build("bvh", m, &o, &ref, NULL), SIDX_OK);
    o.hook = NULL;
    const bvh *r = ref->impl;
    for (size_t t = 0; t < 4; ++t) {
        o.threads = threads[t];
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build("bvh", m, &o, &a, NULL), SIDX_OK);
        const bvh *b = a->impl;
        assert_int_equal(b->num_nodes, r->num_nodes);
        assert_int_equal(b->num_leaves, r->num_leaves);
        assert_int_equal(b->max_depth, r->max_depth);
        assert_memory_equal(b->nodes, r->nodes, (size_t)r->num_nodes * sizeof *r->nodes);
        assert_memory_equal(b->prim_id, r->prim_id, (size_t)r->num_prims * sizeof *r->prim_id);
        assert_memory_equal(b->tris, r->tris, (size_t)r->num_prims * sizeof *r->tris);
        assert_true(b->sah_cost == r->sah_cost);
        sidx_accel_destroy(a);
    }
    sidx_accel_destroy(ref);
}

static void test_parallel_build_identical(void **state)
{
    (void)state;
    struct { const char *name; uint32_t detail; } sc[] = {
        {"soup", tk_fast_tests() ? 20000 : 60000}, {"teapot", 0}, {"stadium", 0}, {"menger", 3}, {"cornell", 0}};
    for (size_t i = 0; i < sizeof sc / sizeof sc[0]; ++i) {
        sidx_mesh m = scene(sc[i].name, sc[i].detail);
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        check_same_tree(&m, &o);
        /* at the small sizes the option sets below run on every scene but
         * the 96,000-triangle sponge (the soup takes the parallel passes) */
        if (tk_fast_tests() && m.num_triangles > 50000) {
            sidx_mesh_free(&m);
            continue;
        }
        o.leaf_size = 1;
        o.bins = 8;
        check_same_tree(&m, &o);
        o.leaf_size = 6;
        o.bins = 64;
        o.max_depth = 12;
        o.c_trav = 2.0f;
        check_same_tree(&m, &o);
        o.leaf_size = 2; /* a bin count that is not a multiple of 4: the tail of the vector scan of used bins */
        o.bins = 7;
        o.max_depth = 0;
        o.c_trav = 0.0f;
        check_same_tree(&m, &o);
        sidx_mesh_free(&m);
    }
    /* a real scan (the bunny) when $SIDX_SCENES holds it */
    const char *dir = getenv("SIDX_SCENES");
    if (dir && *dir) {
        char path[1024];
        snprintf(path, sizeof path, "%s/bunny.obj", dir);
        sidx_mesh bunny;
        if (sidx_mesh_load_obj(path, &bunny, NULL) == SIDX_OK) {
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            check_same_tree(&bunny, &o);
            sidx_mesh_free(&bunny);
        } else {
            printf("  SKIPPED bunny: %s not readable\n", path);
        }
    }
    /* all centroids equal: the halving path */
    sidx_mesh one = scene("icosphere", 0), dup;
    for (uint32_t i = 0; i < one.num_triangles; ++i) {
        one.indices[3 * i + 0] = 0;
        one.indices[3 * i + 1] = 1;
        one.indices[3 * i + 2] = 2;
    }
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    check_same_tree(&one, &o);
    (void)dup;
    sidx_mesh_free(&one);
}

/* Signed zeros: -0.0 == +0.0, so which of the two a min or max keeps
 * depends on the order the boxes are combined in (sidx_v3_min keeps its
 * second operand on a tie).  The parallel build combines them in chunks
 * and gathers the children's bounds while partitioning, in a different
 * order than the one-thread builder's loop; its boxes must still be the
 * same bits.  Here half of the x and y coordinates are zeros of both signs
 * (by vertex parity), so most nodes have a zero min or max whose sign a
 * wrong order would flip — and the comparison is bitwise. */
static void test_parallel_build_signed_zero(void **state)
{
    (void)state;
    const uint32_t details[] = {20000, 300}; /* with and without the parallel passes of the top phase */
    for (size_t d = 0; d < 2; ++d) {
        sidx_mesh m = scene("soup", details[d]);
        sidx_aabb b = sidx_mesh_bounds(&m);
        const float mx = 0.5f * (b.min.x + b.max.x), my = 0.5f * (b.min.y + b.max.y);
        for (uint32_t v = 0; v < m.num_vertices; ++v) {
            sidx_vec3 *p = &m.positions[v];
            if (p->x < mx) p->x = (v & 1) ? -0.0f : 0.0f;
            if (p->y > my) p->y = (v & 2) ? -0.0f : 0.0f;
        }
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        check_same_tree(&m, &o);
        o.leaf_size = 1;
        check_same_tree(&m, &o);
        sidx_mesh_free(&m);
    }
}

static void test_wide_parallel_same_answers(void **state)
{
    (void)state;
    sidx_mesh m = scene("soup", 30000);
    const size_t n = 2000;
    sidx_ray *rays = rays_for(&m, n, TK_RAYS_DIFFUSE);
    const char *names[] = {"bvh4", "bvh8"};
    for (int k = 0; k < 2; ++k) {
        sidx_accel *a1 = build(names[k], &m, 1), *a2 = build(names[k], &m, 2);
        sidx_accel_stats s1, s2;
        sidx_accel_stats_get(a1, &s1);
        sidx_accel_stats_get(a2, &s2);
        assert_int_equal(s1.nodes, s2.nodes);
        assert_true(s1.sah_cost == s2.sah_cost);
        /* the spatial-split build on two threads (its subtrees as tasks,
         * stitched back): the same tree, node for node and block for block */
        const wide_bvh *w1 = a1->impl, *w2 = a2->impl;
        assert_true(s1.prim_refs > m.num_triangles); /* the soup does get split references */
        assert_int_equal(w1->num_inner, w2->num_inner);
        assert_int_equal(w1->num_blocks, w2->num_blocks);
        assert_memory_equal(w1->nodes, w2->nodes, (size_t)w1->num_inner * 8u * w1->width * sizeof(float));
        assert_memory_equal(w1->blocks, w2->blocks, (size_t)w1->num_blocks * sizeof *w1->blocks);
        for (size_t i = 0; i < n; ++i) {
            sidx_hit h1, h2;
            sidx_accel_intersect(a1, &rays[i], NULL, &h1);
            sidx_accel_intersect(a2, &rays[i], NULL, &h2);
            assert_int_equal(h1.prim, h2.prim);
            assert_memory_equal(&h1.t, &h2.t, sizeof h1.t);
        }
        sidx_accel_destroy(a1);
        sidx_accel_destroy(a2);
    }
    free(rays);
    sidx_mesh_free(&m);
}

typedef struct failing { int countdown, live; } failing;
static void *f_alloc(size_t size, void *user)
{
    failing *f = user;
    if (f->countdown-- == 0) return NULL;
    f->live++;
    return malloc(size);
}
static void f_free(void *p, void *user)
{
    failing *f = user;
    if (p) f->live--;
    free(p);
}

static void test_parallel_build_alloc_failures(void **state)
{
    (void)state;
    sidx_mesh m = scene("soup", 20000);
    const char *names[] = {"bvh", "bvh8"};
    for (int k = 0; k < 2; ++k)
        for (int c = 0;; ++c) {
            failing f = {c, 0};
            const sidx_allocator al = {f_alloc, f_free, &f};
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.alloc = &al;
            o.threads = 2;
            sidx_accel *a = NULL;
            const sidx_status s = sidx_accel_build(names[k], &m, &o, &a, NULL);
            if (s == SIDX_OK) {
                sidx_accel_destroy(a);
                assert_int_equal(f.live, 0);
                break;
            }
            assert_int_equal(s, SIDX_ERR_NOMEM);
            assert_null(a);
            assert_int_equal(f.live, 0);
            assert_true(c < 200);
        }
    sidx_mesh_free(&m);
}

/* ---- the worker pool: concurrent callers and fork ---------------------------- */

typedef struct caller {
    const sidx_accel *a;
    const sidx_mesh *m;
    const sidx_ray *rays;
    const sidx_hit *ref;
    const bvh *ref_tree;
    size_t n;
    int rounds, bad;
} caller;

static void *caller_main(void *p)
{
    caller *c = p;
    sidx_hit *got = malloc(c->n * sizeof *got);
    if (!got) {
        c->bad++;
        return NULL;
    }
    for (int r = 0; r < c->rounds; ++r) {
        memset(got, 0xAB, c->n * sizeof *got);
        if (sidx_trace_parallel(c->a, c->rays, c->n, NULL, got, 2) != SIDX_OK ||
            memcmp(got, c->ref, c->n * sizeof *got) != 0)
            c->bad++;
        /* and a parallel build, whose passes also want the pool */
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        o.threads = 2;
        sidx_accel *b = NULL;
        if (sidx_accel_build("bvh", c->m, &o, &b, NULL) != SIDX_OK) {
            c->bad++;
            continue;
        }
        const bvh *t = b->impl;
        if (t->num_nodes != c->ref_tree->num_nodes ||
            memcmp(t->nodes, c->ref_tree->nodes, (size_t)t->num_nodes * sizeof *t->nodes) != 0)
            c->bad++;
        sidx_accel_destroy(b);
    }
    free(got);
    return NULL;
}

static void test_pool_concurrent_callers(void **state)
{
    (void)state;
    sidx_mesh m = scene("soup", 20000); /* above the size where build passes go parallel */
    const size_t n = 3001;
    sidx_ray *rays = rays_for(&m, n, TK_RAYS_DIFFUSE);
    sidx_hit *ref = malloc(n * sizeof *ref);
    assert_non_null(ref);
    sidx_accel *a = build("bvh", &m, 1);
    assert_int_equal(sidx_accel_intersect_n(a, rays, n, NULL, ref), SIDX_OK);
    enum { NCALLERS = 4 };
    caller c[NCALLERS];
    pthread_t th[NCALLERS];
    for (int i = 0; i < NCALLERS; ++i) {
        c[i] = (caller){a, &m, rays, ref, a->impl, n, tk_fast_tests() ? 3 : 10, 0};
        assert_int_equal(pthread_create(&th[i], NULL, caller_main, &c[i]), 0);
    }
    for (int i = 0; i < NCALLERS; ++i) {
        pthread_join(th[i], NULL);
        assert_int_equal(c[i].bad, 0);
    }
    sidx_accel_destroy(a);
    free(ref);
    free(rays);
    sidx_mesh_free(&m);
}

static void test_pool_after_fork(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot", 0);
    const size_t n = 2000;
    sidx_ray *rays = rays_for(&m, n, TK_RAYS_DIFFUSE);
    sidx_hit *ref = malloc(n * sizeof *ref), *got = malloc(n * sizeof *got);
    assert_non_null(ref);
    assert_non_null(got);
    sidx_accel *a = build("bvh", &m, 1);
    assert_int_equal(sidx_accel_intersect_n(a, rays, n, NULL, ref), SIDX_OK);
    /* the parent's pool is running before the fork */
    assert_int_equal(sidx_trace_parallel(a, rays, n, NULL, got, 2), SIDX_OK);
    assert_memory_equal(got, ref, n * sizeof *ref);
    fflush(NULL);
    const pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        /* the child: a pool that waited for the parent's workers would hang; the alarm turns that into a failure */
        alarm(30);
        int ok = 1;
        for (int r = 0; r < 3 && ok; ++r) {
            memset(got, 0xAB, n * sizeof *got);
            ok = sidx_trace_parallel(a, rays, n, NULL, got, 2) == SIDX_OK && memcmp(got, ref, n * sizeof *got) == 0;
        }
        /* the child's copies of the test's memory are the child's to free:
         * under `make valgrind` they would be leaks of the child */
        sidx_accel_destroy(a);
        free(ref);
        free(got);
        free(rays);
        sidx_mesh_free(&m);
        _exit(ok ? 0 : 1);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
    /* and the parent's pool still works */
    memset(got, 0xAB, n * sizeof *got);
    assert_int_equal(sidx_trace_parallel(a, rays, n, NULL, got, 2), SIDX_OK);
    assert_memory_equal(got, ref, n * sizeof *ref);
    sidx_accel_destroy(a);
    free(ref);
    free(got);
    free(rays);
    sidx_mesh_free(&m);
}

static void test_invalid_arguments(void **state)
{
    (void)state;
    sidx_mesh m = scene("cornell", 0);
    sidx_accel *a = build("bvh", &m, 1);
    sidx_ray r;
    sidx_hit h;
    uint8_t o;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, 0), sidx_v3(0, 0, 1), 0, INFINITY), SIDX_OK);
    assert_int_equal(sidx_trace_parallel(NULL, &r, 1, NULL, &h, 2), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_trace_parallel(a, NULL, 1, NULL, &h, 2), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_trace_parallel(a, &r, 1, NULL, NULL, 2), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_occluded_parallel(a, &r, 1, NULL, NULL, 2), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_trace_parallel(a, NULL, 0, NULL, NULL, 2), SIDX_OK);
    assert_int_equal(sidx_occluded_parallel(a, &r, 1, NULL, &o, 2), SIDX_OK);
    assert_true(sidx_hardware_threads() >= 1);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trace_matches_serial),       cmocka_unit_test(test_traced_query_serial),
        cmocka_unit_test(test_parallel_build_identical),   cmocka_unit_test(test_wide_parallel_same_answers),
        cmocka_unit_test(test_parallel_build_alloc_failures), cmocka_unit_test(test_invalid_arguments),
        cmocka_unit_test(test_parallel_build_signed_zero),
        cmocka_unit_test(test_pool_concurrent_callers),     cmocka_unit_test(test_pool_after_fork),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
