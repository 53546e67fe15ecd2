/* test_threads.c — built structures are immutable and may be queried from
 * many threads at once.  For every registered structure, 8 threads trace
 * the same rays (half of them with a per-thread counting hook, whose state
 * lives in the hook's user pointer) and must return bit-identical hits to a
 * single-threaded run. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "common/testkit.h"

#define NTHREADS 8
#define NRAYS 1500 /* at the small sizes (valgrind, the sanitizers): nrays() of them */

static int nrays(void) { return tk_fast_tests() ? 300 : NRAYS; }

typedef struct {
    const sidx_accel *a;
    const sidx_ray *rays;
    sidx_hit hits[NRAYS];
    int occluded[NRAYS];
    int traced;
    sidx_counters counts;
} job;

static void *run(void *arg)
{
    job *j = arg;
    sidx_counters_init(&j->counts);
    sidx_hook hook = sidx_counters_hook(&j->counts);
    sidx_query q = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, j->traced ? &hook : NULL, 0};
    for (int i = 0; i < nrays(); ++i) {
        sidx_accel_intersect(j->a, &j->rays[i], &q, &j->hits[i]);
        sidx_accel_occluded(j->a, &j->rays[i], &q, &j->occluded[i]);
    }
    return NULL;
}

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static float frand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (float)(rng >> 40) / (float)(1u << 24);
}

static void every_structure_is_thread_safe(void **state)
{
    (void)state;
    sidx_mesh m;
    assert_int_equal(sidx_scene_make("teapot", 0, &m, NULL), SIDX_OK);
    const sidx_aabb box = sidx_mesh_bounds(&m);
    const sidx_vec3 c = sidx_aabb_centroid(box), e = sidx_aabb_extent(box);
    sidx_ray *rays = malloc(sizeof *rays * NRAYS);
    assert_non_null(rays);
    for (int i = 0; i < nrays(); ++i) {
        /* one draw per statement, y first: the order gcc evaluated the
         * arguments in (C leaves it open; clang goes the other way) */
        const float oy = frand(), ox = frand();
        sidx_vec3 o = sidx_v3(c.x + (ox - 0.5f) * 3 * e.x, c.y + (oy - 0.5f) * 3 * e.y, c.z + 2 * e.z);
        const float ty = frand(), tx = frand();
        sidx_vec3 t = sidx_v3(c.x + (tx - 0.5f) * e.x, c.y + (ty - 0.5f) * e.y, c.z);
        assert_int_equal(sidx_ray_init(&rays[i], o, sidx_v3_sub(t, o), 0.0f, INFINITY), SIDX_OK);
    }
    job *jobs = calloc(NTHREADS + 1, sizeof *jobs);
    assert_non_null(jobs);
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s) {
        const char *name = sidx_accel_registered_name(s);
        sidx_accel *a = NULL;
        assert_int_equal(sidx_accel_build(name, &m, NULL, &a, NULL), SIDX_OK);
        for (int k = 0; k <= NTHREADS; ++k) {
            jobs[k].a = a;
            jobs[k].rays = rays;
            jobs[k].traced = k & 1;
        }
        run(&jobs[NTHREADS]); /* the single-threaded reference */
        pthread_t th[NTHREADS];
        for (int k = 0; k < NTHREADS; ++k) assert_int_equal(pthread_create(&th[k], NULL, run, &jobs[k]), 0);
        for (int k = 0; k < NTHREADS; ++k) pthread_join(th[k], NULL);
        int hits = 0;
        for (int k = 0; k < NTHREADS; ++k) {
            if (memcmp(jobs[k].hits, jobs[NTHREADS].hits, sizeof jobs[k].hits) != 0 ||
                memcmp(jobs[k].occluded, jobs[NTHREADS].occluded, sizeof jobs[k].occluded) != 0)
                fail_msg("%s: thread %d differs from the single-threaded run", name, k);
            if (jobs[k].traced)
                /* each traced thread saw exactly its own rays: 2 queries per ray */
                assert_int_equal(jobs[k].counts.n[SIDX_EV_RAY_BEGIN], 2 * nrays());
        }
        for (int i = 0; i < nrays(); ++i) hits += jobs[NTHREADS].hits[i].prim != SIDX_NO_HIT;
        assert_true(hits > nrays() / 10); /* the rays do reach the teapot */
        sidx_accel_destroy(a);
    }
    free(jobs);
    free(rays);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_structure_is_thread_safe),
    };
    return cmocka_run_group_tests_name("threads", tests, NULL, NULL);
}
