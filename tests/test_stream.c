/* test_stream.c — sidx_accel_intersect_n and sidx_accel_occluded_n, the
 * stream entry of bvh, bvh4 and bvh8 (lib/bvh_stream.c).
 *
 * Its answers are those of single queries, bit for bit: for every ray of
 * a buffer, hits[i] (every byte of the sidx_hit) equals what
 * sidx_accel_intersect gives for that ray alone, and occluded[i] what
 * sidx_accel_occluded gives —
 *  - on bvh, bvh4 and bvh8, the wide trees with the best kernels this CPU
 *    has and with the portable scalar ones (SIDX_SIMD=scalar), with the
 *    watertight test (the SIMD triangle kernels) and with Möller–Trumbore
 *    (the other walks), with the robust and the plain box test;
 *  - with no attributes, with u, v and the normal, with the precise t and
 *    the point; with and without SIDX_QUERY_REORDER;
 *  - on buffers of 0, 1, 7, 8, 9 and 1000 rays (around the sort keys'
 *    groups of 8; reordering from 64 rays on), on primary, diffuse,
 *    shadow, grazing and axis-parallel rays, with invalid records mixed in
 *    (NaN origin or direction, zero direction, an infinite direction, NaN
 *    tmin, tmin > tmax: fields set by hand past sidx_ray_init) that the
 *    single query answers too;
 *  - a traced buffer emits, event for event, the events of the single
 *    queries one after another with ray ids q->ray_id + i;
 *  - the same with several rays in flight (SIDX_STREAM_INFLIGHT=on at
 *    build), bvh8 and bvh4, best and scalar kernels;
 *  - two threads streaming through one structure at once (reordered and
 *    not, rays in flight or not) get the same answers (make test-tsan
 *    runs this suite too);
 *  - NULL arguments are refused, n = 0 takes NULL arrays. */
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

#include "sidx/sidx.h"
#include "common/testkit.h"

#define NRAYS 1000u

static sidx_mesh scene(const char *name)
{
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make(name, 0, &m, &err) != SIDX_OK) fail_msg("scene %s: %s", name, err.message);
    return m;
}

static sidx_accel *build_with(const char *name, const sidx_mesh *m, const sidx_build_options *opt, const char *simd,
                              int inflight)
{
    if (simd) setenv("SIDX_SIMD", simd, 1);
    if (inflight) setenv("SIDX_STREAM_INFLIGHT", "on", 1);
    sidx_accel *a = NULL;
    sidx_error err;
    const sidx_status s = sidx_accel_build(name, m, opt, &a, &err);
    unsetenv("SIDX_SIMD");
    unsetenv("SIDX_STREAM_INFLIGHT");
    if (s != SIDX_OK) fail_msg("build %s: %s", name, err.message);
    return a;
}

static sidx_accel *build(const char *name, const sidx_mesh *m, const sidx_build_options *opt, const char *simd)
{
    return build_with(name, m, opt, simd, 0);
}

/* NRAYS rays of every kind in turn, with invalid records every 37th
 * place: the single query takes them as they are, so must the stream. */
static sidx_ray *make_rays(const sidx_mesh *m)
{
    tk_rayrec *rec = malloc(NRAYS * sizeof *rec);
    sidx_ray *r = calloc(NRAYS, sizeof *r);
    assert_non_null(rec);
    assert_non_null(r);
    const uint32_t per = NRAYS / 5u;
    for (uint32_t k = 0; k < 5; ++k) tk_make_rays(m, (tk_ray_kind)k, per, 7u + k, rec + k * per);
    /* interleave the kinds in blocks of 3 so that every chunk mixes them */
    for (uint32_t i = 0; i < NRAYS; ++i) {
        const uint32_t kind = (i / 3u) % 5u, at = kind * per + (i / 15u) * 3u + i % 3u;
        if (tk_ray_from(&rec[at < NRAYS ? at : i], &r[i]) != SIDX_OK)
            sidx_ray_init(&r[i], sidx_v3(0, 0, 0), sidx_v3(1, 0, 0), 0.0f, INFINITY);
    }
    free(rec);
    for (uint32_t i = 5; i < NRAYS; i += 37) {
        sidx_ray *x = &r[i];
        switch ((i / 37u) % 6u) {
        case 0: x->org.y = NAN; break;
        case 1: /* zero direction, as the fields would be set by hand */
            x->dir = sidx_v3(0, 0, 0);
            x->inv_dir = sidx_v3(INFINITY, INFINITY, INFINITY);
            x->sign[0] = x->sign[1] = x->sign[2] = 0;
            break;
        case 2: x->dir.z = NAN; x->inv_dir.z = NAN; break;
        case 3: x->tmin = NAN; break;
        case 4: x->tmin = 2.0f; x->tmax = 1.0f; break;
        default: x->dir.x = INFINITY; x->inv_dir.x = 0.0f; break;
        }
    }
    return r;
}

static const size_t sizes[] = {0, 1, 7, 8, 9, NRAYS};
#define NSIZES (sizeof sizes / sizeof sizes[0])

/* Every buffer size from a few starts, every query variant: the stream
 * against single queries. */
static void check_accel(const sidx_accel *a, const sidx_ray *rays, const char *what)
{
    static const uint32_t flag_sets[] = {0u, SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_QUERY_PRECISE_T | SIDX_QUERY_POINT};
    sidx_hit *one = malloc(NRAYS * sizeof *one), *many = malloc(NRAYS * sizeof *many);
    int *occ1 = malloc(NRAYS * sizeof *occ1), *occn = malloc(NRAYS * sizeof *occn);
    assert_non_null(one);
    assert_non_null(many);
    assert_non_null(occ1);
    assert_non_null(occn);
    for (size_t f = 0; f < sizeof flag_sets / sizeof flag_sets[0]; ++f)
        for (int reorder = 0; reorder < 2; ++reorder) {
            sidx_query q = {flag_sets[f] | (reorder ? SIDX_QUERY_REORDER : 0u), SIDX_TRAVERSE_DEFAULT, NULL, 0};
            for (size_t s = 0; s < NSIZES; ++s) {
                const size_t n = sizes[s], start = n == NRAYS ? 0 : 3 * s;
                for (size_t i = 0; i < n; ++i) {
                    assert_int_equal(sidx_accel_intersect(a, &rays[start + i], &q, &one[i]), SIDX_OK);
                    assert_int_equal(sidx_accel_occluded(a, &rays[start + i], &q, &occ1[i]), SIDX_OK);
                }
                memset(many, 0xA5, NRAYS * sizeof *many);
                memset(occn, 0xA5, NRAYS * sizeof *occn);
                assert_int_equal(sidx_accel_intersect_n(a, rays + start, n, &q, many), SIDX_OK);
                assert_int_equal(sidx_accel_occluded_n(a, rays + start, n, &q, occn), SIDX_OK);
                for (size_t i = 0; i < n; ++i) {
                    if (memcmp(&one[i], &many[i], sizeof one[i]) != 0)
                        fail_msg("%s flags %u reorder %d n %zu: ray %zu: single t %a prim %u, stream t %a prim %u", what,
                                 flag_sets[f], reorder, n, start + i, (double)one[i].t, one[i].prim,
                                 (double)many[i].t, many[i].prim);
                    if (occ1[i] != occn[i])
                        fail_msg("%s reorder %d n %zu: ray %zu: occluded single %d stream %d", what, reorder, n,
                                 start + i, occ1[i], occn[i]);
                }
                /* nothing written past the buffer */
                if (n < NRAYS) assert_int_equal(occn[n], (int)0xA5A5A5A5);
            }
        }
    free(one);
    free(many);
    free(occ1);
    free(occn);
}

static void test_bit_identical(void **state)
{
    (void)state;
    static const char *const names[] = {"bvh", "bvh4", "bvh8"};
    static const char *const scenes[] = {"teapot", "soup"};
    /* fast sizes (sanitizers): one scene; smallest (ThreadSanitizer,
     * valgrind): also only the default triangle and box tests */
    const size_t nscenes = tk_fast_tests() ? 1 : 2;
    const int variants = !tk_tiny_tests();
    for (size_t sc = 0; sc < nscenes; ++sc) {
        sidx_mesh m = scene(scenes[sc]);
        sidx_ray *rays = make_rays(&m);
        for (size_t k = 0; k < 3; ++k)
            for (int simd = 0; simd < (k ? 2 : 1); ++simd)
                for (int tri = 0; tri < 2; ++tri)
                    for (int box = 0; box < 2; ++box) {
                        /* the plain box test only with the watertight one: what the other walks add is the
                         * triangle test */
                        if ((box && tri) || ((box || tri) && !variants)) continue;
                        sidx_build_options opt;
                        memset(&opt, 0, sizeof opt);
                        opt.tri = tri ? SIDX_TRI_MOLLER_TRUMBORE : SIDX_TRI_WATERTIGHT;
                        opt.box = box ? SIDX_BOX_PLAIN : SIDX_BOX_ROBUST;
                        sidx_accel *a = build(names[k], &m, &opt, simd ? "scalar" : NULL);
                        char what[96];
                        snprintf(what, sizeof what, "%s on %s (%s kernels, %s, %s boxes)", names[k], scenes[sc],
                                 simd ? "scalar" : "best", tri ? "moller" : "watertight", box ? "plain" : "robust");
                        check_accel(a, rays, what);
                        sidx_accel_destroy(a);
                    }
        free(rays);
        sidx_mesh_free(&m);
    }
}

/* Several rays in flight (SIDX_STREAM_INFLIGHT=on; by default only for
 * trees too large for a test): bvh8 and bvh4, best and scalar kernels,
 * robust and plain boxes, every size, flag set and order of
 * check_accel.  Only the watertight test has these walks; the others and
 * any hit are the ray-by-ray walks test_bit_identical checks. */
static void test_inflight(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    sidx_ray *rays = make_rays(&m);
    static const struct {
        const char *name, *simd;
        int box;
    } cases[] = {{"bvh8", NULL, 0}, {"bvh8", "scalar", 0}, {"bvh8", NULL, 1}, {"bvh4", NULL, 0}, {"bvh4", "scalar", 0}};
    const size_t ncases = tk_tiny_tests() ? 1 : sizeof cases / sizeof cases[0];
    for (size_t c = 0; c < ncases; ++c) {
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.tri = SIDX_TRI_WATERTIGHT;
        opt.box = cases[c].box ? SIDX_BOX_PLAIN : SIDX_BOX_ROBUST;
        sidx_accel *a = build_with(cases[c].name, &m, &opt, cases[c].simd, 1);
        char what[96];
        snprintf(what, sizeof what, "%s in flight (%s kernels, %s boxes)", cases[c].name,
                 cases[c].simd ? "scalar" : "best", cases[c].box ? "plain" : "robust");
        check_accel(a, rays, what);
        sidx_accel_destroy(a);
    }
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- events --------------------------------------------------------------------- */

/* The fields of an event a traversal fills, copied (no padding bytes, no
 * pointer valid only during the callback). */
typedef struct ev_rec {
    int32_t type, axis, result, reason;
    uint32_t ray_id, node, depth, prim, count;
    float t_near, t_far, t;
    float bounds[6];
    const char *structure;
} ev_rec;

typedef struct ev_log {
    ev_rec *e;
    size_t n, cap;
} ev_log;

static void record(const sidx_event *ev, void *user)
{
    ev_log *l = user;
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 1024;
        l->e = realloc(l->e, l->cap * sizeof *l->e);
        assert_non_null(l->e);
    }
    ev_rec *r = &l->e[l->n++];
    memset(r, 0, sizeof *r);
    r->type = (int32_t)ev->type;
    r->axis = ev->axis;
    r->result = ev->result;
    r->reason = ev->reason;
    r->ray_id = ev->ray_id;
    r->node = ev->node;
    r->depth = ev->depth;
    r->prim = ev->prim;
    r->count = ev->count;
    r->t_near = ev->t_near;
    r->t_far = ev->t_far;
    r->t = ev->t;
    memcpy(r->bounds, &ev->bounds, sizeof r->bounds);
    r->structure = ev->structure;
}

static void test_traced_events(void **state)
{
    (void)state;
    static const char *const names[] = {"bvh", "bvh4", "bvh8"};
    sidx_mesh m = scene("teapot");
    sidx_ray *rays = make_rays(&m);
    const size_t n = 200; /* every kind and some invalid records */
    sidx_hit *one = malloc(n * sizeof *one), *many = malloc(n * sizeof *many);
    int *occ1 = malloc(n * sizeof *occ1), *occn = malloc(n * sizeof *occn);
    for (size_t k = 0; k < 3; ++k) {
        sidx_accel *a = build(names[k], &m, NULL, NULL);
        for (int reorder = 0; reorder < 2; ++reorder) {
            ev_log single = {0}, stream = {0};
            sidx_hook h1 = {record, &single, 0}, hn = {record, &stream, 0};
            const uint32_t base = 1000;
            sidx_query q = {reorder ? SIDX_QUERY_REORDER : 0u, SIDX_TRAVERSE_DEFAULT, &h1, 0};
            for (size_t i = 0; i < n; ++i) {
                q.ray_id = base + (uint32_t)i;
                assert_int_equal(sidx_accel_intersect(a, &rays[i], &q, &one[i]), SIDX_OK);
            }
            for (size_t i = 0; i < n; ++i) {
                q.ray_id = base + (uint32_t)i;
                assert_int_equal(sidx_accel_occluded(a, &rays[i], &q, &occ1[i]), SIDX_OK);
            }
            q.hook = &hn;
            q.ray_id = base;
            assert_int_equal(sidx_accel_intersect_n(a, rays, n, &q, many), SIDX_OK);
            assert_int_equal(sidx_accel_occluded_n(a, rays, n, &q, occn), SIDX_OK);
            assert_true(single.n > 10 * n);
            assert_int_equal(single.n, stream.n);
            for (size_t i = 0; i < single.n; ++i)
                if (memcmp(&single.e[i], &stream.e[i], sizeof single.e[i]) != 0)
                    fail_msg("%s reorder %d: event %zu of %zu differs (type %d/%d, ray %u/%u)", names[k], reorder, i,
                             single.n, single.e[i].type, stream.e[i].type, single.e[i].ray_id, stream.e[i].ray_id);
            assert_memory_equal(one, many, n * sizeof *one);
            assert_memory_equal(occ1, occn, n * sizeof *occ1);
            free(single.e);
            free(stream.e);
        }
        sidx_accel_destroy(a);
    }
    free(one);
    free(many);
    free(occ1);
    free(occn);
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- threads sharing a structure ---------------------------------------------- */

typedef struct job {
    const sidx_accel *a;
    const sidx_ray *rays;
    sidx_hit hits[NRAYS];
    int occ[NRAYS];
    sidx_status s1, s2;
} job;

static void *run_job(void *arg)
{
    job *j = arg;
    for (int reorder = 0; reorder < 2; ++reorder) {
        const sidx_query q = {reorder ? SIDX_QUERY_REORDER : 0u, SIDX_TRAVERSE_DEFAULT, NULL, 0};
        j->s1 = sidx_accel_intersect_n(j->a, j->rays, NRAYS, &q, j->hits);
        j->s2 = sidx_accel_occluded_n(j->a, j->rays, NRAYS, &q, j->occ);
        if (j->s1 != SIDX_OK || j->s2 != SIDX_OK) break;
    }
    return NULL;
}

static void test_threads(void **state)
{
    (void)state;
    static const char *const names[] = {"bvh", "bvh8", "bvh8"}; /* the last with rays in flight */
    sidx_mesh m = scene("teapot");
    sidx_ray *rays = make_rays(&m);
    job *jobs = calloc(2, sizeof *jobs);
    sidx_hit *one = malloc(NRAYS * sizeof *one);
    int *occ = malloc(NRAYS * sizeof *occ);
    assert_non_null(jobs);
    assert_non_null(one);
    assert_non_null(occ);
    for (size_t k = 0; k < 3; ++k) {
        sidx_accel *a = build_with(names[k], &m, NULL, NULL, k == 2);
        for (size_t i = 0; i < NRAYS; ++i) {
            assert_int_equal(sidx_accel_intersect(a, &rays[i], NULL, &one[i]), SIDX_OK);
            assert_int_equal(sidx_accel_occluded(a, &rays[i], NULL, &occ[i]), SIDX_OK);
        }
        pthread_t th[2];
        for (int t = 0; t < 2; ++t) {
            jobs[t].a = a;
            jobs[t].rays = rays;
            assert_int_equal(pthread_create(&th[t], NULL, run_job, &jobs[t]), 0);
        }
        for (int t = 0; t < 2; ++t) {
            pthread_join(th[t], NULL);
            assert_int_equal(jobs[t].s1, SIDX_OK);
            assert_int_equal(jobs[t].s2, SIDX_OK);
            assert_memory_equal(jobs[t].hits, one, NRAYS * sizeof *one);
            assert_memory_equal(jobs[t].occ, occ, NRAYS * sizeof *occ);
        }
        sidx_accel_destroy(a);
    }
    free(jobs);
    free(one);
    free(occ);
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- arguments ------------------------------------------------------------------ */

static void test_arguments(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    sidx_accel *a = build("bvh8", &m, NULL, NULL);
    sidx_ray r;
    sidx_ray_init(&r, sidx_v3(0, 0, 10), sidx_v3(0, 0, -1), 0.0f, INFINITY);
    sidx_hit h = sidx_hit_none();
    int o = 7;
    assert_int_equal(sidx_accel_intersect_n(NULL, &r, 1, NULL, &h), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_intersect_n(a, NULL, 1, NULL, &h), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_intersect_n(a, &r, 1, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_occluded_n(NULL, &r, 1, NULL, &o), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_occluded_n(a, NULL, 1, NULL, &o), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_occluded_n(a, &r, 1, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(o, 7); /* nothing written on a refused call */
    assert_int_equal(sidx_accel_intersect_n(a, NULL, 0, NULL, NULL), SIDX_OK);
    assert_int_equal(sidx_accel_occluded_n(a, NULL, 0, NULL, NULL), SIDX_OK);
    /* NULL query: the default one */
    assert_int_equal(sidx_accel_occluded_n(a, &r, 1, NULL, &o), SIDX_OK);
    int o1 = 0;
    assert_int_equal(sidx_accel_occluded(a, &r, NULL, &o1), SIDX_OK);
    assert_int_equal(o, o1);
    assert_int_equal(o, 1); /* the teapot is at the origin */
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bit_identical),
        cmocka_unit_test(test_inflight),
        cmocka_unit_test(test_traced_events),
        cmocka_unit_test(test_threads),
        cmocka_unit_test(test_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
