/* test_lightbuffer.c — the light buffer gives exactly the shadow answers of
 * any-hit queries on brute force (and on "bvh") for random surface points,
 * lazily and eagerly, with and without the last-occluder cache, from many
 * threads at once; plus events, arguments, allocation failure, and the
 * measurement the issue asks for (speed and cache hit-rate against the
 * BVH's any-hit, printed). */
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
#include "sidx/lightbuffer.h"
#include "common/testkit.h"

#define TMIN 1e-4f
#define TMAX (1.0f - 1e-4f)

static void make_scene(const char *name, uint32_t detail, sidx_mesh *m)
{
    sidx_error err;
    assert_int_equal(sidx_scene_make(name, detail, m, &err), SIDX_OK);
}

static sidx_vec3 surface_point(tk_rng *g, const sidx_mesh *m)
{
    const uint32_t tri = tk_rng_below(g, m->num_triangles);
    double u = tk_rng_unit(g), v = tk_rng_unit(g);
    if (u + v > 1.0) { u = 1.0 - u; v = 1.0 - v; }
    const sidx_vec3 a = sidx_mesh_vertex(m, tri, 0), b = sidx_mesh_vertex(m, tri, 1), c = sidx_mesh_vertex(m, tri, 2);
    return sidx_v3_add(a, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(b, a), (float)u), sidx_v3_scale(sidx_v3_sub(c, a), (float)v)));
}

/* light given relative to the scene box: centre + rel·extent */
static sidx_vec3 light_at(const sidx_mesh *m, sidx_vec3 rel)
{
    const sidx_aabb b = sidx_mesh_bounds(m);
    return sidx_v3_add(sidx_aabb_centroid(b), sidx_v3_mul(rel, sidx_aabb_extent(b)));
}

static void check_against(const sidx_mesh *m, sidx_vec3 light, uint32_t res, size_t npoints, uint64_t seed)
{
    sidx_accel *brute = NULL, *bvh = NULL;
    assert_int_equal(sidx_accel_build("brute", m, NULL, &brute, NULL), SIDX_OK);
    if (sidx_accel_is_registered("bvh")) assert_int_equal(sidx_accel_build("bvh", m, NULL, &bvh, NULL), SIDX_OK);
    sidx_lightbuffer *lazy = NULL, *eager = NULL;
    sidx_error err;
    assert_int_equal(sidx_lightbuffer_build(m, light, res, 0, NULL, &lazy, &err), SIDX_OK);
    assert_int_equal(sidx_lightbuffer_build(m, light, res, 1, NULL, &eager, &err), SIDX_OK);
    sidx_lightbuffer_cache c_lazy, c_eager;
    assert_int_equal(sidx_lightbuffer_cache_init(lazy, &c_lazy), SIDX_OK);
    assert_int_equal(sidx_lightbuffer_cache_init(eager, &c_eager), SIDX_OK);
    tk_rng g;
    tk_rng_seed(&g, seed);
    size_t shadowed = 0, n = 0;
    for (size_t i = 0; i < npoints; ++i) {
        const sidx_vec3 p = surface_point(&g, m);
        sidx_ray r;
        if (sidx_lightbuffer_shadow_ray(lazy, p, TMIN, TMAX, &r) != SIDX_OK) continue;
        int ref, got;
        sidx_accel_occluded(brute, &r, NULL, &ref);
        assert_int_equal(sidx_lightbuffer_occluded(lazy, p, TMIN, TMAX, &c_lazy, NULL, &got), SIDX_OK);
        if (got != ref) fprintf(stderr, "point %zu (%g %g %g): brute %d, lazy light buffer %d\n", i, p.x, p.y, p.z, ref, got);
        assert_int_equal(got, ref);
        assert_int_equal(sidx_lightbuffer_occluded(eager, p, TMIN, TMAX, &c_eager, NULL, &got), SIDX_OK);
        assert_int_equal(got, ref);
        assert_int_equal(sidx_lightbuffer_occluded(eager, p, TMIN, TMAX, NULL, NULL, &got), SIDX_OK);
        assert_int_equal(got, ref);
        if (bvh) {
            int b;
            sidx_accel_occluded(bvh, &r, NULL, &b);
            assert_int_equal(b, ref);
        }
        shadowed += (size_t)ref;
        ++n;
    }
    assert_true(n > npoints * 9 / 10);
    /* lazy and eager hold the same lists for the cells the lazy one filled */
    sidx_lightbuffer_stats sl, se;
    sidx_lightbuffer_stats_get(lazy, &sl);
    sidx_lightbuffer_stats_get(eager, &se);
    assert_int_equal(se.cells_filled, se.cells);
    assert_true(sl.cells_filled <= sl.cells);
    assert_true(sl.refs <= se.refs);
    assert_int_equal(c_lazy.cache_hits, c_eager.cache_hits); /* same lists, same order, same cache history */
    printf("  lightbuffer res %u: %zu points, %.0f%% in shadow; lazy filled %u/%u cells (%llu refs vs %llu eager); "
           "cache hit %.0f%% of shadowed; %.1f tri tests/query\n",
           res, n, 100.0 * shadowed / n, sl.cells_filled, sl.cells, (unsigned long long)sl.refs,
           (unsigned long long)se.refs, shadowed ? 100.0 * c_lazy.cache_hits / shadowed : 0.0,
           (double)c_lazy.tri_tests / (double)(c_lazy.queries ? c_lazy.queries : 1));
    sidx_lightbuffer_cache_free(&c_lazy);
    sidx_lightbuffer_cache_free(&c_eager);
    sidx_lightbuffer_destroy(lazy);
    sidx_lightbuffer_destroy(eager);
    sidx_accel_destroy(bvh);
    sidx_accel_destroy(brute);
}

static void cornell_light_inside(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("cornell", 0, &m);
    check_against(&m, light_at(&m, sidx_v3(0.0f, 0.45f, 0.0f)), 16, 3000, 1);
    sidx_mesh_free(&m);
}

static void teapot_light_outside(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", 0, &m);
    check_against(&m, light_at(&m, sidx_v3(1.5f, 2.0f, 0.7f)), 32, 3000, 2);
    sidx_mesh_free(&m);
}

static void soup_light_in_the_middle(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("soup", 800, &m);
    check_against(&m, light_at(&m, sidx_v3(0.01f, -0.02f, 0.03f)), 8, 2000, 3);
    sidx_mesh_free(&m);
}

/* Light on a cube diagonal and in the plane of the menger sponge's faces:
 * directions on face borders and triangles seen edge-on. */
static void menger_awkward_lights(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("menger", 1, &m);
    const sidx_aabb b = sidx_mesh_bounds(&m);
    check_against(&m, sidx_v3_add(b.max, sidx_v3(1, 1, 1)), 4, 1500, 4);
    check_against(&m, sidx_v3(b.max.x + 1.0f, b.max.y, 0.5f * (b.min.z + b.max.z)), 5, 1500, 5);
    check_against(&m, sidx_aabb_centroid(b), 7, 1500, 6); /* inside the sponge's central hole */
    sidx_mesh_free(&m);
}

/* ---- threads: lazy filling from several threads -------------------------- */

#define NT 4
#define NPT 1500
typedef struct tjob { const sidx_lightbuffer *lb; const sidx_vec3 *pts; int out[NPT]; } tjob;

static void *tjob_run(void *arg)
{
    tjob *j = arg;
    sidx_lightbuffer_cache c;
    if (sidx_lightbuffer_cache_init(j->lb, &c) != SIDX_OK) return NULL;
    for (int i = 0; i < NPT; ++i) sidx_lightbuffer_occluded(j->lb, j->pts[i], TMIN, TMAX, &c, NULL, &j->out[i]);
    sidx_lightbuffer_cache_free(&c);
    return NULL;
}

static void lazy_fill_from_threads(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", 0, &m);
    sidx_vec3 *pts = malloc(NPT * sizeof *pts);
    assert_non_null(pts);
    tk_rng g;
    tk_rng_seed(&g, 99);
    for (int i = 0; i < NPT; ++i) pts[i] = surface_point(&g, &m);
    const sidx_vec3 light = light_at(&m, sidx_v3(-1.0f, 1.5f, 0.3f));
    sidx_lightbuffer *single = NULL, *shared = NULL;
    assert_int_equal(sidx_lightbuffer_build(&m, light, 24, 0, NULL, &single, NULL), SIDX_OK);
    assert_int_equal(sidx_lightbuffer_build(&m, light, 24, 0, NULL, &shared, NULL), SIDX_OK);
    tjob *ref = calloc(1, sizeof *ref), *jobs = calloc(NT, sizeof *jobs);
    assert_true(ref && jobs);
    ref->lb = single;
    ref->pts = pts;
    tjob_run(ref);
    pthread_t th[NT];
    for (int t = 0; t < NT; ++t) {
        jobs[t].lb = shared;
        jobs[t].pts = pts;
        assert_int_equal(pthread_create(&th[t], NULL, tjob_run, &jobs[t]), 0);
    }
    for (int t = 0; t < NT; ++t) pthread_join(th[t], NULL);
    for (int t = 0; t < NT; ++t) assert_memory_equal(jobs[t].out, ref->out, sizeof ref->out);
    sidx_lightbuffer_stats a, b;
    sidx_lightbuffer_stats_get(single, &a);
    sidx_lightbuffer_stats_get(shared, &b);
    assert_int_equal(a.cells_filled, b.cells_filled); /* each cell filled once */
    assert_true(a.refs == b.refs);
    free(ref);
    free(jobs);
    free(pts);
    sidx_lightbuffer_destroy(single);
    sidx_lightbuffer_destroy(shared);
    sidx_mesh_free(&m);
}

/* ---- events and arguments ------------------------------------------------------ */

static void events_and_arguments(void **state)
{
    (void)state;
    /* one big triangle between the light and the floor point */
    const float xyz[] = {-1, 1, -1, 1, 1, -1, 0, 1, 1};
    const uint32_t idx[] = {0, 1, 2};
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 3, idx, 1, NULL), SIDX_OK);
    sidx_lightbuffer *lb = NULL;
    assert_int_equal(sidx_lightbuffer_build(&m, sidx_v3(0, 5, 0), 8, 0, NULL, &lb, NULL), SIDX_OK);
    sidx_lightbuffer_cache c;
    assert_int_equal(sidx_lightbuffer_cache_init(lb, &c), SIDX_OK);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook hook = sidx_recorder_hook(&rec);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 3};
    int occ = -1;
    assert_int_equal(sidx_lightbuffer_occluded(lb, sidx_v3(0, 0, 0), TMIN, TMAX, &c, &q, &occ), SIDX_OK);
    assert_int_equal(occ, 1);
    /* RAY_BEGIN, NOTE (lazy fill), NODE_ENTER, PRIM_TEST, TERMINATE, RAY_END */
    assert_int_equal(rec.count, 6);
    assert_int_equal(rec.events[0].type, SIDX_EV_RAY_BEGIN);
    assert_int_equal(rec.events[1].type, SIDX_EV_NOTE);
    assert_int_equal(rec.events[2].type, SIDX_EV_NODE_ENTER);
    assert_int_equal(rec.events[2].cell[0], 3); /* face -y: the point is below the light */
    assert_int_equal(rec.events[3].type, SIDX_EV_PRIM_TEST);
    assert_int_equal(rec.events[3].prim, 0);
    assert_int_equal(rec.events[4].type, SIDX_EV_TERMINATE);
    assert_int_equal(rec.events[4].reason, SIDX_TERM_ANY_HIT);
    assert_int_equal(rec.events[5].type, SIDX_EV_RAY_END);
    for (size_t i = 0; i < rec.count; ++i) assert_int_equal(rec.events[i].ray_id, 3);
    /* second query: no fill, and the cached occluder answers */
    sidx_recorder_clear(&rec);
    assert_int_equal(sidx_lightbuffer_occluded(lb, sidx_v3(0.01f, 0, 0.01f), TMIN, TMAX, &c, &q, &occ), SIDX_OK);
    assert_int_equal(occ, 1);
    assert_int_equal(rec.count, 5);
    assert_int_equal(rec.events[2].type, SIDX_EV_PRIM_TEST);
    assert_int_equal(rec.events[2].aux, 1); /* the cached one */
    assert_int_equal(c.cache_hits, 1);
    /* a point between the triangle and the light is lit */
    assert_int_equal(sidx_lightbuffer_occluded(lb, sidx_v3(0, 2, 0), TMIN, TMAX, &c, NULL, &occ), SIDX_OK);
    assert_int_equal(occ, 0);
    /* the cell view names the cell the query enters, its list, and the reach */
    sidx_ray sr;
    assert_int_equal(sidx_lightbuffer_shadow_ray(lb, sidx_v3(0, 0, 0), TMIN, TMAX, &sr), SIDX_OK);
    sidx_lightbuffer_cell_view cv;
    assert_int_equal(sidx_lightbuffer_cell_get(lb, &sr, &cv), SIDX_OK);
    assert_int_equal(cv.id, rec.events[1].node);
    assert_int_equal(cv.face, 3);
    assert_int_equal(cv.count, 1);
    assert_int_equal(cv.tris[0], 0);
    assert_true(cv.dist[0] > 3.9f && cv.dist[0] < 4.1f); /* the triangle lies in y = 1, the light at y = 5 */
    assert_true(cv.reach > 4.99f * (1.0f - TMIN) && cv.reach < 5.01f);
    assert_int_equal(sidx_lightbuffer_cell_get(NULL, &sr, &cv), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_lightbuffer_cell_get(lb, NULL, &cv), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_lightbuffer_cell_get(lb, &sr, NULL), SIDX_ERR_INVALID_ARG);
    /* arguments */
    assert_int_equal(sidx_lightbuffer_occluded(lb, sidx_v3(0, 5, 0), TMIN, TMAX, &c, NULL, &occ), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_lightbuffer_occluded(lb, sidx_v3(NAN, 0, 0), TMIN, TMAX, &c, NULL, &occ), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_lightbuffer_occluded(NULL, sidx_v3(0, 0, 0), TMIN, TMAX, &c, NULL, &occ), SIDX_ERR_INVALID_ARG);
    sidx_lightbuffer *bad = NULL;
    assert_int_equal(sidx_lightbuffer_build(&m, sidx_v3(INFINITY, 0, 0), 8, 0, NULL, &bad, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_lightbuffer_build(&m, sidx_v3(0, 0, 0), 5000, 0, NULL, &bad, NULL), SIDX_ERR_INVALID_ARG);
    assert_null(bad);
    sidx_recorder_free(&rec);
    sidx_lightbuffer_cache_free(&c);
    sidx_lightbuffer_destroy(lb);
    sidx_lightbuffer_destroy(NULL);
    sidx_mesh_free(&m);
}


static void nomem(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("cornell", 0, &m);
    for (int eager = 0; eager < 2; ++eager)
        for (long k = 0; k < 12; ++k) {
            tk_failing f = {k, 0};
            sidx_allocator al = tk_failing_allocator(&f);
            sidx_build_options opt;
            memset(&opt, 0, sizeof opt);
            opt.alloc = &al;
            sidx_lightbuffer *lb = NULL;
            const sidx_status s = sidx_lightbuffer_build(&m, sidx_v3(0, 0.5f, 0), 8, eager, &opt, &lb, NULL);
            if (s == SIDX_OK) {
                /* lazy fills that fail fall back to scanning the face list */
                int occ;
                assert_int_equal(sidx_lightbuffer_occluded(lb, sidx_v3(0.1f, -0.9f, 0.2f), TMIN, TMAX, NULL, NULL, &occ),
                                 SIDX_OK);
                sidx_lightbuffer_destroy(lb);
            } else {
                assert_int_equal(s, SIDX_ERR_NOMEM);
                assert_null(lb);
            }
            assert_int_equal(f.live, 0);
        }
    sidx_mesh_free(&m);
}

/* ---- measurement: shadow rays of a camera image, scanline order ------------------ */

static void measure(void **state)
{
    (void)state;
    if (!sidx_accel_is_registered("bvh")) { printf("  (no bvh registered: measurement skipped)\n"); return; }
    sidx_mesh m;
    make_scene("stadium", 0, &m);
    sidx_accel *bvh = NULL;
    assert_int_equal(sidx_accel_build("bvh", &m, NULL, &bvh, NULL), SIDX_OK);
    const size_t W = tk_fast_tests() ? 64 : 192;
    tk_rayrec *rays = malloc(W * W * sizeof *rays);
    sidx_vec3 *pts = malloc(W * W * sizeof *pts);
    assert_true(rays && pts);
    tk_make_rays(&m, TK_RAYS_PRIMARY, W * W, 7, rays);
    size_t n = 0;
    for (size_t i = 0; i < W * W; ++i) {
        sidx_ray r;
        sidx_hit h;
        if (tk_ray_from(&rays[i], &r) != SIDX_OK) continue;
        sidx_accel_intersect(bvh, &r, NULL, &h);
        if (h.prim != SIDX_NO_HIT) pts[n++] = sidx_ray_at(&r, h.t);
    }
    const sidx_vec3 light = light_at(&m, sidx_v3(0.2f, 1.2f, -0.1f));
    sidx_lightbuffer *lb = NULL;
    double t0 = tk_now_ms();
    assert_int_equal(sidx_lightbuffer_build(&m, light, 32, 1, NULL, &lb, NULL), SIDX_OK);
    const double build_ms = tk_now_ms() - t0;
    sidx_lightbuffer_cache c;
    sidx_lightbuffer_cache_init(lb, &c);
    int *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
    assert_true(a && b);
    const int reps = tk_fast_tests() ? 1 : 3;
    t0 = tk_now_ms();
    for (int rep = 0; rep < reps; ++rep)
        for (size_t i = 0; i < n; ++i) sidx_lightbuffer_occluded(lb, pts[i], TMIN, TMAX, &c, NULL, &a[i]);
    const double lb_ms = tk_now_ms() - t0;
    t0 = tk_now_ms();
    for (int rep = 0; rep < reps; ++rep)
        for (size_t i = 0; i < n; ++i) {
            sidx_ray r;
            sidx_lightbuffer_shadow_ray(lb, pts[i], TMIN, TMAX, &r);
            sidx_accel_occluded(bvh, &r, NULL, &b[i]);
        }
    const double bvh_ms = tk_now_ms() - t0;
    size_t shadowed = 0;
    for (size_t i = 0; i < n; ++i) {
        assert_int_equal(a[i], b[i]);
        shadowed += (size_t)a[i];
    }
    /* and the same points in random order: the cache relies on coherence */
    sidx_lightbuffer_cache c2;
    sidx_lightbuffer_cache_init(lb, &c2);
    tk_rng g;
    tk_rng_seed(&g, 5);
    for (size_t i = 0; i < n; ++i) {
        int o;
        sidx_lightbuffer_occluded(lb, pts[tk_rng_below(&g, (uint32_t)n)], TMIN, TMAX, &c2, NULL, &o);
    }
    sidx_lightbuffer_stats st;
    sidx_lightbuffer_stats_get(lb, &st);
    sidx_accel_stats bs;
    sidx_accel_stats_get(bvh, &bs);
    printf("  measure (stadium, %u tris, %zu shadow rays x %d, eager res 32, build %.1f ms, %zu KiB vs bvh %zu KiB):\n"
           "    light buffer %.3f us/ray, bvh any-hit %.3f us/ray (%.2fx); %.0f%% shadowed;\n"
           "    cached occluder answered %.0f%% of shadowed queries in scanline order, %.0f%% in random order;"
           " %.1f triangle tests/query\n",
           m.num_triangles, n, reps, build_ms, st.bytes / 1024, bs.bytes / 1024, 1000.0 * lb_ms / (double)(n * reps),
           1000.0 * bvh_ms / (double)(n * reps), bvh_ms / (lb_ms > 0 ? lb_ms : 1e-9), 100.0 * shadowed / (double)n,
           100.0 * c.cache_hits / (double)(c.occluded ? c.occluded : 1),
           100.0 * c2.cache_hits / (double)(c2.occluded ? c2.occluded : 1), (double)c.tri_tests / (double)c.queries);
    free(a);
    free(b);
    free(rays);
    free(pts);
    sidx_lightbuffer_cache_free(&c);
    sidx_lightbuffer_cache_free(&c2);
    sidx_lightbuffer_destroy(lb);
    sidx_accel_destroy(bvh);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(events_and_arguments),
        cmocka_unit_test(cornell_light_inside),
        cmocka_unit_test(teapot_light_outside),
        cmocka_unit_test(soup_light_in_the_middle),
        cmocka_unit_test(menger_awkward_lights),
        cmocka_unit_test(lazy_fill_from_threads),
        cmocka_unit_test(nomem),
        cmocka_unit_test(measure),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
