/* test_grid.c — the space-partitioning family: uniform grid (grid,
 * grid-nomailbox, grid-boxonly), two-level grid (grid2), irregular grid
 * (grid-irregular), octree and quadtree.
 *
 *  - closest hits identical to brute force (same prim, or t within 1e-5
 *    relative) on every built-in scene, for primary rays, rays starting
 *    inside the scene, grazing rays, shadow segments and axis-parallel rays
 *    with exact ±0 components; any-hit agrees with closest-hit;
 *  - no leaks from inside a closed icosphere aimed at its vertices and
 *    edge midpoints;
 *  - the resolution formula R = d·∛(λn/V) on a known box;
 *  - the DDA visits exactly the hand-computed cells of a 4×4×4 grid;
 *  - mailboxing changes nothing but the number of tests;
 *  - grid2 visits fewer cells than grid in the teapot-in-a-stadium;
 *  - the irregular grid has fewer cells than its base grid. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "sidx/sidx.h"
#include "common/testkit.h"

static const char *const structures[] = {"grid",           "grid-nomailbox", "grid-boxonly", "grid2",
                                         "grid-irregular", "octree",         "quadtree"};
#define N_STRUCTURES (sizeof structures / sizeof structures[0])

static const char *const scenes[] = {"icosphere", "teapot", "soup", "menger", "stadium", "cornell", "flat2d"};
#define N_SCENES (sizeof scenes / sizeof scenes[0])

/* Every structure of the family must be registered. */
static int have(const char *name)
{
    assert_true(sidx_accel_is_registered(name));
    return 1;
}

static sidx_accel *build(const char *name, const sidx_mesh *m, const sidx_build_options *opt)
{
    sidx_accel *a = NULL;
    sidx_error err;
    const sidx_status s = sidx_accel_build(name, m, opt, &a, &err);
    if (s != SIDX_OK) fprintf(stderr, "build %s: %s\n", name, err.message);
    assert_int_equal(s, SIDX_OK);
    assert_non_null(a);
    return a;
}

static void make_scene(const char *name, sidx_mesh *m)
{
    sidx_error err;
    assert_int_equal(sidx_scene_make(name, 0, m, &err), SIDX_OK);
}

static sidx_ray ray_of(const tk_rayrec *rec)
{
    sidx_ray r;
    assert_int_equal(tk_ray_from(rec, &r), SIDX_OK);
    return r;
}

/* ---- against brute force ------------------------------------------------- */

/* Closest hits of brute force for rays[0..n). */
static sidx_hit *reference_hits(const sidx_accel *ref, const tk_rayrec *rays, size_t n)
{
    sidx_hit *h = malloc((n ? n : 1) * sizeof *h);
    assert_non_null(h);
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray r = ray_of(&rays[i]);
        assert_int_equal(sidx_accel_intersect(ref, &r, NULL, &h[i]), SIDX_OK);
    }
    return h;
}

static void check_hits(const sidx_hit *ref, const sidx_accel *a, const tk_rayrec *rays, size_t n, const char *scene,
                       const char *kind)
{
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray r = ray_of(&rays[i]);
        sidx_hit hg;
        assert_int_equal(sidx_accel_intersect(a, &r, NULL, &hg), SIDX_OK);
        if (!tk_hits_agree(&ref[i], &hg)) {
            fprintf(stderr, "%s on %s, %s ray %zu: o=(%.9g %.9g %.9g) d=(%.9g %.9g %.9g) brute prim %u t %.9g, got "
                    "prim %u t %.9g\n",
                    sidx_accel_name(a), scene, kind, i, (double)r.org.x, (double)r.org.y, (double)r.org.z,
                    (double)r.dir.x, (double)r.dir.y, (double)r.dir.z, ref[i].prim, (double)ref[i].t, hg.prim,
                    (double)hg.t);
            fail();
        }
        int occ = -1;
        assert_int_equal(sidx_accel_occluded(a, &r, NULL, &occ), SIDX_OK);
        if (occ != (ref[i].prim != SIDX_NO_HIT)) {
            fprintf(stderr, "%s on %s, %s ray %zu: occluded %d but closest hit prim %u\n", sidx_accel_name(a),
                    scene, kind, i, occ, ref[i].prim);
            fail();
        }
    }
}

static void check_rays(const sidx_accel *ref, const sidx_accel *a, const tk_rayrec *rays, size_t n,
                       const char *scene, const char *kind)
{
    sidx_hit *h = reference_hits(ref, rays, n);
    check_hits(h, a, rays, n, scene, kind);
    free(h);
}

static void test_against_brute(void **state)
{
    (void)state;
    const size_t per_kind = tk_tiny_tests() ? 20 : tk_fast_tests() ? 60 : 200;
    tk_rayrec *rays = malloc(TK_RAYS_KIND_COUNT * per_kind * sizeof *rays);
    assert_non_null(rays);
    for (size_t s = 0; s < N_SCENES; ++s) {
        sidx_mesh m;
        make_scene(scenes[s], &m);
        sidx_accel *ref = build("brute", &m, NULL);
        for (int kind = 0; kind < TK_RAYS_KIND_COUNT; ++kind)
            tk_make_rays(&m, (tk_ray_kind)kind, per_kind, 1234 + s, rays + (size_t)kind * per_kind);
        sidx_hit *hits = reference_hits(ref, rays, TK_RAYS_KIND_COUNT * per_kind);
        for (size_t k = 0; k < N_STRUCTURES; ++k) {
            if (!have(structures[k])) continue;
            sidx_accel *a = build(structures[k], &m, NULL);
            for (int kind = 0; kind < TK_RAYS_KIND_COUNT; ++kind)
                check_hits(hits + (size_t)kind * per_kind, a, rays + (size_t)kind * per_kind, per_kind, scenes[s],
                           tk_ray_kind_name((tk_ray_kind)kind));
            sidx_accel_destroy(a);
        }
        free(hits);
        sidx_accel_destroy(ref);
        sidx_mesh_free(&m);
    }
    free(rays);
}

/* Non-default densities and leaf sizes exercise other resolutions. */
static void test_against_brute_options(void **state)
{
    (void)state;
    const size_t n = 150;
    tk_rayrec *rays = malloc(2 * n * sizeof *rays);
    assert_non_null(rays);
    const float densities[] = {0.05f, 1.0f, 20.0f};
    const char *const sc[] = {"teapot", "flat2d"};
    for (size_t s = 0; s < 2; ++s) {
        sidx_mesh m;
        make_scene(sc[s], &m);
        sidx_accel *ref = build("brute", &m, NULL);
        tk_make_rays(&m, TK_RAYS_DIFFUSE, n, 99, rays);
        tk_make_rays(&m, TK_RAYS_AXIS, n, 7, rays + n);
        sidx_hit *hits = reference_hits(ref, rays, 2 * n);
        for (size_t k = 0; k < N_STRUCTURES; ++k)
            for (size_t d = 0; d < 3 && have(structures[k]); ++d) {
                sidx_build_options opt;
                memset(&opt, 0, sizeof opt);
                opt.grid_density = densities[d];
                opt.leaf_size = d == 0 ? 1 : d == 1 ? 4 : 32;
                opt.max_depth = d == 0 ? 3 : d == 1 ? 1 : 0;
                sidx_accel *a = build(structures[k], &m, &opt);
                check_hits(hits, a, rays, 2 * n, sc[s], "diffuse/axis");
                sidx_accel_destroy(a);
            }
        free(hits);
        sidx_accel_destroy(ref);
        sidx_mesh_free(&m);
    }
    free(rays);
}

/* ---- leaks ------------------------------------------------------------- */

static void test_no_leaks_icosphere(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("icosphere", &m);
    const size_t max = (size_t)m.num_triangles * 6u;
    tk_rayrec *rays = malloc(max * sizeof *rays);
    assert_non_null(rays);
    const sidx_vec3 inside[] = {{0.0f, 0.0f, 0.0f}, {0.1f, -0.2f, 0.3f}};
    for (size_t o = 0; o < 2; ++o) {
        const size_t n = tk_make_leak_rays(&m, inside[o], max, rays);
        assert_true(n > 1000);
        for (size_t k = 0; k < N_STRUCTURES; ++k) {
            if (!have(structures[k])) continue;
            sidx_accel *a = build(structures[k], &m, NULL);
            size_t leaks = 0;
            for (size_t i = 0; i < n; ++i) {
                const sidx_ray r = ray_of(&rays[i]);
                sidx_hit h;
                sidx_accel_intersect(a, &r, NULL, &h);
                int occ = 0;
                sidx_accel_occluded(a, &r, NULL, &occ);
                leaks += (h.prim == SIDX_NO_HIT) + (occ == 0);
            }
            if (leaks) fprintf(stderr, "%s: %zu leaks of %zu rays\n", structures[k], leaks, n);
            assert_int_equal(leaks, 0);
            sidx_accel_destroy(a);
        }
    }
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- resolution formula ------------------------------------------------- */

/* n = 8 triangles spanning exactly [0,4]×[0,2]×[0,1] (V = 8), or its flat
 * version z = 0 (an area of 8). */
static void box_mesh(sidx_mesh *m, int flat)
{
    float xyz[8 * 9];
    uint32_t idx[24];
    const float zt = flat ? 0.0f : 1.0f;
    const float big[9] = {0, 0, 0, 4, 0, 0, 4, 2, zt};
    memcpy(xyz, big, sizeof big);
    for (int t = 1; t < 8; ++t) {
        const float x = 0.5f * (float)t;
        const float v[9] = {x, 0.5f, 0, x + 0.1f, 0.5f, 0, x, 0.6f, 0};
        memcpy(xyz + 9 * t, v, sizeof v);
    }
    for (uint32_t i = 0; i < 24; ++i) idx[i] = i;
    assert_int_equal(sidx_mesh_from_arrays(m, xyz, 24, idx, 8, NULL), SIDX_OK);
}

static void check_res(const sidx_mesh *m, float lambda, uint32_t rx, uint32_t ry, uint32_t rz)
{
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.grid_density = lambda;
    sidx_accel *a = build("grid", m, &opt);
    sidx_accel_stats s;
    assert_int_equal(sidx_accel_stats_get(a, &s), SIDX_OK);
    if (s.res[0] != rx || s.res[1] != ry || s.res[2] != rz)
        fprintf(stderr, "lambda %g: res %u %u %u, expected %u %u %u\n", (double)lambda, s.res[0], s.res[1], s.res[2],
                rx, ry, rz);
    assert_int_equal(s.res[0], rx);
    assert_int_equal(s.res[1], ry);
    assert_int_equal(s.res[2], rz);
    assert_int_equal(s.nodes, rx * ry * rz);
    sidx_accel_destroy(a);
}

static void test_resolution_formula(void **state)
{
    (void)state;
    sidx_mesh m;
    box_mesh(&m, 0);
    /* R = d·∛(λ·8/8) = d·∛λ, d = (4, 2, 1). */
    check_res(&m, 1.0f, 4, 2, 1);
    check_res(&m, 8.0f, 8, 4, 2);
    check_res(&m, 27.0f, 12, 6, 3);
    /* λ = 4: ∛4 = 1.587 → (6.35, 3.17, 1.59) rounded = (6, 3, 2). */
    check_res(&m, 4.0f, 6, 3, 2);
    /* The default density is 4. */
    check_res(&m, 0.0f, 6, 3, 2);
    /* Tiny λ: every axis clamps to 1 cell. */
    check_res(&m, 1e-4f, 1, 1, 1);
    /* Huge λ: per-axis clamp to 512 and total bounded to 2^24 cells (a
     * 2^24-cell grid: left out under valgrind, where filling it takes a
     * minute; the sanitizer run builds it). */
    if (!tk_under_valgrind()) {
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.grid_density = 1e9f;
        sidx_accel *a = build("grid", &m, &opt);
        sidx_accel_stats s;
        sidx_accel_stats_get(a, &s);
        assert_true(s.res[0] <= 512 && s.res[1] <= 512 && s.res[2] <= 512);
        assert_true((uint64_t)s.res[0] * s.res[1] * s.res[2] <= (1u << 24));
        assert_true(s.res[0] >= 256);
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
    /* Flat scene (z extent 0): the 2D formula R = d·√(λn/A), z gets 1 cell. */
    box_mesh(&m, 1);
    check_res(&m, 1.0f, 4, 2, 1);
    check_res(&m, 4.0f, 8, 4, 1);
    sidx_mesh_free(&m);
}

/* ---- the DDA on a hand-computed ray ------------------------------------ */

/* Eight tiny triangles at the corners of [0,4]³ (n = 8, V = 64): with
 * λ = 8, R = 4·∛(8·8/64) = 4 per axis, cells of size 1. */
static void corner_mesh(sidx_mesh *m)
{
    float xyz[8 * 9];
    uint32_t idx[24];
    for (int c = 0; c < 8; ++c) {
        const float x = (c & 1) ? 4.0f : 0.0f, y = (c & 2) ? 4.0f : 0.0f, z = (c & 4) ? 4.0f : 0.0f;
        const float sx = (c & 1) ? -0.1f : 0.1f, sy = (c & 2) ? -0.1f : 0.1f;
        const float v[9] = {x, y, z, x + sx, y, z, x, y + sy, z};
        memcpy(xyz + 9 * c, v, sizeof v);
    }
    for (uint32_t i = 0; i < 24; ++i) idx[i] = i;
    assert_int_equal(sidx_mesh_from_arrays(m, xyz, 24, idx, 8, NULL), SIDX_OK);
}

static void expect_cells(const sidx_accel *a, sidx_vec3 o, sidx_vec3 d, const int (*cells)[3], size_t n)
{
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook hook = sidx_recorder_hook(&rec);
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &hook;
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, o, d, 0.0f, INFINITY), SIDX_OK);
    sidx_hit h;
    sidx_accel_intersect(a, &r, &q, &h);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    size_t k = 0;
    int terminated = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        if (e->type == SIDX_EV_TERMINATE) {
            assert_int_equal(e->reason, SIDX_TERM_LEFT_GRID);
            assert_int_equal(e->count, n);
            terminated = 1;
        }
        if (e->type != SIDX_EV_NODE_ENTER) continue;
        assert_true(k < n);
        assert_int_equal(e->cell[0], cells[k][0]);
        assert_int_equal(e->cell[1], cells[k][1]);
        assert_int_equal(e->cell[2], cells[k][2]);
        assert_int_equal(e->node, (uint32_t)(cells[k][0] + 4 * cells[k][1] + 16 * cells[k][2]));
        assert_true(e->t_near <= e->t_far);
        ++k;
    }
    assert_int_equal(k, n);
    assert_true(terminated);
    sidx_recorder_free(&rec);
}

static void test_dda_cells(void **state)
{
    (void)state;
    sidx_mesh m;
    corner_mesh(&m);
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.grid_density = 8.0f;
    sidx_accel *a = build("grid", &m, &opt);
    sidx_accel_stats s;
    sidx_accel_stats_get(a, &s);
    assert_int_equal(s.res[0], 4);
    assert_int_equal(s.res[1], 4);
    assert_int_equal(s.res[2], 4);
    /* o = (-1, 0.45, 1.5), d = (1, 0.3, +0): y = 0.45 + 0.3t, x = t - 1.
     * Enters x = 0 at t = 1 (y = 0.75): cell (0,0,1).  y = 1 at t = 1.833
     * (x = 0.83): (0,1,1).  x = 1, 2, 3 at t = 2, 3, 4 (y = 1.05, 1.35,
     * 1.65): (1,1,1), (2,1,1), (3,1,1).  x = 4 at t = 5 (y = 1.95): leaves.
     * z never steps: its component is exactly +0. */
    static const int fwd[5][3] = {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {2, 1, 1}, {3, 1, 1}};
    expect_cells(a, sidx_v3(-1.0f, 0.45f, 1.5f), sidx_v3(1.0f, 0.3f, 0.0f), fwd, 5);
    /* The same line backwards, with a -0 z component. */
    static const int back[5][3] = {{3, 1, 1}, {2, 1, 1}, {1, 1, 1}, {0, 1, 1}, {0, 0, 1}};
    expect_cells(a, sidx_v3(5.0f, 2.25f, 1.5f), sidx_v3(-1.0f, -0.3f, -0.0f), back, 5);
    /* Axis-parallel, starting inside: o = (2.5, 3.5, 0.5), d = (0, 0, -1)
     * from cell (2,3,0) straight out of the bottom: one cell; and d = +z:
     * (2,3,0) .. (2,3,3). */
    static const int down[1][3] = {{2, 3, 0}};
    expect_cells(a, sidx_v3(2.5f, 3.5f, 0.5f), sidx_v3(0.0f, -0.0f, -1.0f), down, 1);
    static const int up[4][3] = {{2, 3, 0}, {2, 3, 1}, {2, 3, 2}, {2, 3, 3}};
    expect_cells(a, sidx_v3(2.5f, 3.5f, 0.5f), sidx_v3(0.0f, 0.0f, 2.0f), up, 4);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* ---- mailboxing ------------------------------------------------------- */

static sidx_counters count_events(const sidx_accel *a, const tk_rayrec *rays, size_t n)
{
    sidx_counters c;
    sidx_counters_init(&c);
    const sidx_hook hook = sidx_counters_hook(&c);
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &hook;
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray r = ray_of(&rays[i]);
        sidx_hit h;
        sidx_accel_intersect(a, &r, &q, &h);
    }
    return c;
}

static void test_mailbox(void **state)
{
    (void)state;
    const size_t n = 400;
    tk_rayrec *rays = malloc(n * sizeof *rays);
    assert_non_null(rays);
    sidx_mesh m;
    make_scene("teapot", &m);
    /* A dense grid so that triangles span several cells. */
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.grid_density = 16.0f;
    sidx_accel *on = build("grid", &m, &opt);
    sidx_accel *off = build("grid-nomailbox", &m, &opt);
    opt.no_mailbox = 1;
    sidx_accel *off2 = build("grid", &m, &opt);
    tk_make_rays(&m, TK_RAYS_DIFFUSE, n, 5, rays);
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray r = ray_of(&rays[i]);
        sidx_hit h1, h2, h3;
        sidx_accel_intersect(on, &r, NULL, &h1);
        sidx_accel_intersect(off, &r, NULL, &h2);
        sidx_accel_intersect(off2, &r, NULL, &h3);
        assert_int_equal(h1.prim, h2.prim);
        assert_true(h1.t == h2.t || (isinf(h1.t) && isinf(h2.t)));
        assert_int_equal(h2.prim, h3.prim);
    }
    const sidx_counters c_on = count_events(on, rays, n), c_off = count_events(off, rays, n),
                        c_off2 = count_events(off2, rays, n);
    assert_true(c_on.n[SIDX_EV_MAILBOX_HIT] > 0);
    assert_int_equal(c_off.n[SIDX_EV_MAILBOX_HIT], 0);
    assert_int_equal(c_off2.n[SIDX_EV_MAILBOX_HIT], 0);
    /* Every skip is a test saved; nothing else changes. */
    assert_int_equal(c_on.n[SIDX_EV_PRIM_TEST] + c_on.n[SIDX_EV_MAILBOX_HIT], c_off.n[SIDX_EV_PRIM_TEST]);
    assert_int_equal(c_on.n[SIDX_EV_NODE_ENTER], c_off.n[SIDX_EV_NODE_ENTER]);
    sidx_accel_destroy(on);
    sidx_accel_destroy(off);
    sidx_accel_destroy(off2);
    sidx_mesh_free(&m);
    free(rays);
}

/* Exact SAT insertion stores fewer references than bounding-box insertion
 * and gives the same hits. */
static void test_exact_vs_boxonly(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", &m);
    sidx_accel *ex = build("grid", &m, NULL), *bo = build("grid-boxonly", &m, NULL);
    sidx_accel_stats se, sb;
    sidx_accel_stats_get(ex, &se);
    sidx_accel_stats_get(bo, &sb);
    assert_true(se.prim_refs < sb.prim_refs);
    assert_true(se.prim_refs >= m.num_triangles);
    assert_true(se.empty_leaves >= sb.empty_leaves);
    assert_int_equal(se.res[0], sb.res[0]);
    sidx_accel_destroy(ex);
    sidx_accel_destroy(bo);
    sidx_mesh_free(&m);
}

/* ---- grid2, irregular, octree ------------------------------------------- */

/* A camera inside the stadium looking at the teapot: the rays that hit it
 * are the ones a uniform grid answers with thousands of tests. */
static void teapot_view(size_t n, tk_rayrec *out)
{
    const size_t w = (size_t)sqrt((double)n);
    const sidx_vec3 eye = {2.0f, 1.2f, 3.0f}, at = {0.0f, 0.15f, 0.0f};
    sidx_vec3 f = sidx_v3_sub(at, eye);
    f = sidx_v3_scale(f, 1.0f / sidx_v3_length(f));
    sidx_vec3 r = sidx_v3_cross(f, sidx_v3(0, 1, 0));
    r = sidx_v3_scale(r, 1.0f / sidx_v3_length(r));
    const sidx_vec3 u = sidx_v3_cross(r, f);
    for (size_t i = 0; i < n; ++i) {
        const float x = (float)((((double)(i % w) + 0.5) / (double)w * 2.0 - 1.0) * 0.35);
        const float y = (float)((1.0 - ((double)(i / w) + 0.5) / (double)w * 2.0) * 0.35);
        const sidx_vec3 d = sidx_v3_add(f, sidx_v3_add(sidx_v3_scale(r, x), sidx_v3_scale(u, y)));
        out[i] = tk_rayrec_make(eye, d, 0.0f, INFINITY);
    }
}

static void test_grid2_stadium(void **state)
{
    (void)state;
    if (!have("grid2")) return;
    const size_t n = 400;
    tk_rayrec *rays = malloc(n * sizeof *rays);
    assert_non_null(rays);
    sidx_mesh m;
    make_scene("stadium", &m);
    sidx_accel *g = build("grid", &m, NULL), *g2 = build("grid2", &m, NULL), *ref = build("brute", &m, NULL);
    /* From outside: the walk through the stadium's empty space is shorter. */
    tk_make_rays(&m, TK_RAYS_PRIMARY, n, 3, rays);
    sidx_counters c1 = count_events(g, rays, n), c2 = count_events(g2, rays, n);
    fprintf(stderr, "stadium, primary: cells/ray grid %.2f grid2 %.2f; tests/ray grid %.2f grid2 %.2f\n",
            (double)c1.n[SIDX_EV_NODE_ENTER] / n, (double)c2.n[SIDX_EV_NODE_ENTER] / n,
            (double)c1.n[SIDX_EV_PRIM_TEST] / n, (double)c2.n[SIDX_EV_PRIM_TEST] / n);
    assert_true(c2.n[SIDX_EV_NODE_ENTER] < c1.n[SIDX_EV_NODE_ENTER]);
    /* At the teapot: the uniform grid has it in one cell with all its
     * triangles; the nested grid resolves it. */
    teapot_view(n, rays);
    check_rays(ref, g2, rays, n, "stadium", "teapot view");
    c1 = count_events(g, rays, n);
    c2 = count_events(g2, rays, n);
    fprintf(stderr, "stadium, teapot view: cells/ray grid %.2f grid2 %.2f; tests/ray grid %.2f grid2 %.2f\n",
            (double)c1.n[SIDX_EV_NODE_ENTER] / n, (double)c2.n[SIDX_EV_NODE_ENTER] / n,
            (double)c1.n[SIDX_EV_PRIM_TEST] / n, (double)c2.n[SIDX_EV_PRIM_TEST] / n);
    assert_true(c2.n[SIDX_EV_PRIM_TEST] * 20 < c1.n[SIDX_EV_PRIM_TEST]);
    sidx_accel_destroy(g);
    sidx_accel_destroy(g2);
    sidx_accel_destroy(ref);
    sidx_mesh_free(&m);
    free(rays);
}

/* Remembers the irregular grid's "base cells" NOTE (count = cells before
 * merging, depth = octant levels used). */
typedef struct base_note { uint32_t cells, depth; int seen; } base_note;
static void base_note_fn(const sidx_event *ev, void *user)
{
    base_note *b = user;
    if (ev->type == SIDX_EV_NOTE && ev->text && strstr(ev->text, "base cells")) {
        b->cells = ev->count;
        b->depth = ev->depth;
        b->seen = 1;
    }
}

static void test_irregular_merges(void **state)
{
    (void)state;
    if (!have("grid-irregular")) return;
    const char *const sc[] = {"teapot", "stadium", "cornell", "flat2d"};
    for (size_t s = 0; s < 4; ++s) {
        sidx_mesh m;
        make_scene(sc[s], &m);
        base_note bn = {0, 0, 0};
        const sidx_hook h = {base_note_fn, &bn, SIDX_EVMASK(SIDX_EV_NOTE)};
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        o.hook = &h;
        sidx_accel *a = build("grid-irregular", &m, &o);
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        assert_true(bn.seen);
        fprintf(stderr, "grid-irregular on %s: %u base cells (%u octant levels) -> %u merged cells\n", sc[s],
                bn.cells, bn.depth, st.nodes);
        /* Merging must join cells: fewer cells than the base had. */
        assert_true(st.nodes > 0 && st.nodes < bn.cells);
        /* The virtual grid is the top grid times a power of two: a
         * subdivided axis is a multiple of 2^depth. */
        for (int i = 0; i < 3; ++i) assert_true(st.res[i] == 1 || st.res[i] % (1u << bn.depth) == 0);
        if (s == 1) assert_true(bn.depth >= 4); /* the teapot forces deep octants */
        sidx_accel_destroy(a);
        sidx_mesh_free(&m);
    }
}

/* The irregular grid's construction events (deck 000 "Construction
 * (merge & expand)"): one build_leaf per base cell, one build_merge per
 * merge (so base cells - merges = final cells), boxes in finest-level
 * cells with the faces inside them; a traced build makes the same grid
 * as an untraced one; a walk names the expanded box it jumps across. */
static void test_irregular_construction_events(void **state)
{
    (void)state;
    if (!have("grid-irregular")) return;
    const char *const sc[] = {"flat2d", "cornell", "teapot"};
    for (size_t s = 0; s < 3; ++s) {
        sidx_mesh m;
        make_scene(sc[s], &m);
        sidx_recorder rec;
        sidx_recorder_init(&rec);
        sidx_hook h = sidx_recorder_hook(&rec);
        h.mask = SIDX_EVMASK_BUILD | SIDX_EVMASK(SIDX_EV_NOTE);
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        o.hook = &h;
        sidx_accel *a = build("grid-irregular", &m, &o), *plain = build("grid-irregular", &m, NULL);
        assert_false(rec.overflow);
        sidx_accel_stats st, sp;
        sidx_accel_stats_get(a, &st);
        sidx_accel_stats_get(plain, &sp);
        assert_int_equal(st.nodes, sp.nodes);
        assert_int_equal(st.prim_refs, sp.prim_refs);
        assert_int_equal(st.bytes, sp.bytes);
        uint32_t base = 0, leaves = 0, merges = 0, grown = 0;
        int32_t fine[3] = {0, 0, 0};
        for (size_t i = 0; i < rec.count; ++i) {
            const sidx_event *e = &rec.events[i];
            if (e->type == SIDX_EV_NOTE && e->text && strstr(e->text, "base cells")) {
                base = e->count;
                memcpy(fine, e->cell, sizeof fine);
            }
            if (e->type != SIDX_EV_BUILD_LEAF && e->type != SIDX_EV_BUILD_MERGE && e->type != SIDX_EV_BUILD_EXPAND)
                continue;
            assert_true(e->node < st.nodes);
            for (int k = 0; k < 3; ++k) {
                assert_true(e->extent[k] >= 1);
                assert_true(e->cell[k] >= 0 && e->cell[k] + (int32_t)e->extent[k] <= fine[k]);
            }
            assert_false(sidx_aabb_is_empty(e->bounds));
            if (e->type == SIDX_EV_BUILD_LEAF) ++leaves;
            if (e->type == SIDX_EV_BUILD_MERGE) {
                ++merges;
                assert_true(e->axis >= 0 && e->axis < 3);
                assert_true(e->aux > (uint32_t)e->cell[e->axis] &&
                            e->aux < (uint32_t)e->cell[e->axis] + e->extent[e->axis]);
            }
            if (e->type == SIDX_EV_BUILD_EXPAND && e->result == 1) {
                ++grown;
                assert_true(e->count >= 1);
            }
        }
        fprintf(stderr, "grid-irregular on %s: %u base cells, %u merges, %u cells, %u expansion steps\n", sc[s],
                leaves, merges, st.nodes, grown);
        assert_int_equal(leaves, base);
        assert_int_equal(leaves - merges, st.nodes);
        assert_true(merges > 0 && grown > 0);
        /* a traced walk: every cell entered comes with its expanded box */
        sidx_recorder tr;
        sidx_recorder_init(&tr);
        const sidx_hook th = sidx_recorder_hook(&tr);
        const sidx_aabb box = sidx_mesh_bounds(&m);
        sidx_ray r;
        sidx_ray_init(&r, sidx_v3_add(box.max, sidx_v3(1.0f, 1.0f, 1.0f)),
                      sidx_v3_sub(sidx_aabb_centroid(box), sidx_v3_add(box.max, sidx_v3(1.0f, 1.0f, 1.0f))), 0.0f,
                      INFINITY);
        sidx_query q;
        memset(&q, 0, sizeof q);
        q.hook = &th;
        sidx_hit hit;
        sidx_accel_intersect(a, &r, &q, &hit);
        size_t entered = 0;
        for (size_t i = 0; i < tr.count; ++i)
            if (tr.events[i].type == SIDX_EV_NODE_ENTER) {
                ++entered;
                assert_true(tr.events[i].extent[0] >= 1 && tr.events[i].cell[0] >= 0);
            }
        assert_true(entered > 0);
        sidx_recorder_free(&tr);
        sidx_recorder_free(&rec);
        sidx_accel_destroy(a);
        sidx_accel_destroy(plain);
        sidx_mesh_free(&m);
    }
}

/* The irregular grid fixes the teapot in a stadium as the nested grid does. */
static void test_irregular_stadium(void **state)
{
    (void)state;
    if (!have("grid-irregular")) return;
    const size_t n = 400;
    tk_rayrec *rays = malloc(n * sizeof *rays);
    assert_non_null(rays);
    sidx_mesh m;
    make_scene("stadium", &m);
    sidx_accel *g = build("grid", &m, NULL), *gi = build("grid-irregular", &m, NULL), *ref = build("brute", &m, NULL);
    teapot_view(n, rays);
    check_rays(ref, gi, rays, n, "stadium", "teapot view");
    const sidx_counters c1 = count_events(g, rays, n), c3 = count_events(gi, rays, n);
    fprintf(stderr, "stadium, teapot view: cells/ray grid %.2f grid-irregular %.2f; tests/ray grid %.2f "
                    "grid-irregular %.2f\n",
            (double)c1.n[SIDX_EV_NODE_ENTER] / n, (double)c3.n[SIDX_EV_NODE_ENTER] / n,
            (double)c1.n[SIDX_EV_PRIM_TEST] / n, (double)c3.n[SIDX_EV_PRIM_TEST] / n);
    assert_true(c3.n[SIDX_EV_PRIM_TEST] * 20 < c1.n[SIDX_EV_PRIM_TEST]);
    /* Expanded cells: fewer steps than the uniform grid even though the
     * cells around the teapot are far finer. */
    assert_true(c3.n[SIDX_EV_NODE_ENTER] < c1.n[SIDX_EV_NODE_ENTER] * 4);
    sidx_accel_destroy(g);
    sidx_accel_destroy(gi);
    sidx_accel_destroy(ref);
    sidx_mesh_free(&m);
    free(rays);
}

static void test_octree_quadtree(void **state)
{
    (void)state;
    if (!have("octree")) return;
    sidx_mesh m;
    make_scene("flat2d", &m);
    sidx_accel *o = build("octree", &m, NULL), *q = build("quadtree", &m, NULL);
    sidx_accel_stats so, sq;
    sidx_accel_stats_get(o, &so);
    sidx_accel_stats_get(q, &sq);
    /* A quadtree never splits z; a quadtree node has 4 children: nodes = 1 + 4·inner. */
    assert_int_equal(sq.res[2], 1);
    assert_int_equal((sq.nodes - 1) % 4, 0);
    assert_true(sq.leaves > 1);
    assert_true(sq.prim_refs >= m.num_triangles);
    /* Every flat2d triangle crosses z = 0, the octree's first z cut: all of
     * them would go to both halves, so the duplication rule keeps the
     * octree one leaf.  That is why 2D scenes take the quadtree. */
    assert_int_equal(so.nodes, 1);
    assert_int_equal(so.prim_refs, m.num_triangles);
    sidx_accel_destroy(o);
    sidx_accel_destroy(q);
    sidx_mesh_free(&m);
    /* an octree node has 8 children: nodes = 1 + 8·inner */
    make_scene("teapot", &m);
    o = build("octree", &m, NULL);
    sidx_accel_stats_get(o, &so);
    assert_int_equal((so.nodes - 1) % 8, 0);
    assert_true(so.leaves > 1);
    assert_true(so.prim_refs >= m.num_triangles);
    sidx_accel_destroy(o);
    sidx_mesh_free(&m);
}

/* Build events: node ids of traversal exist in the build; BUILD_END counts. */
static void test_build_events(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("icosphere", &m);
    for (size_t k = 0; k < N_STRUCTURES; ++k) {
        if (!have(structures[k])) continue;
        sidx_counters c;
        sidx_counters_init(&c);
        const sidx_hook hook = sidx_counters_hook(&c);
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.hook = &hook;
        sidx_accel *a = build(structures[k], &m, &opt);
        sidx_accel_stats s;
        sidx_accel_stats_get(a, &s);
        assert_int_equal(c.n[SIDX_EV_BUILD_BEGIN], 1);
        assert_int_equal(c.n[SIDX_EV_BUILD_END], 1);
        assert_true(c.n[SIDX_EV_BUILD_NODE] > 0);
        assert_true(s.bytes > 0);
        assert_true(s.prim_refs >= m.num_triangles);
        assert_true(s.mean_leaf_prims > 0.0);
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

/* Every structure on an empty mesh and a single triangle. */
static void test_tiny_meshes(void **state)
{
    (void)state;
    const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t idx[3] = {0, 1, 2};
    sidx_mesh one, none;
    assert_int_equal(sidx_mesh_from_arrays(&one, xyz, 3, idx, 1, NULL), SIDX_OK);
    memset(&none, 0, sizeof none);
    for (size_t k = 0; k < N_STRUCTURES; ++k) {
        if (!have(structures[k])) continue;
        sidx_accel *a = build(structures[k], &one, NULL);
        sidx_ray r;
        sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, 1.0f), sidx_v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
        sidx_hit h;
        sidx_accel_intersect(a, &r, NULL, &h);
        assert_int_equal(h.prim, 0);
        assert_true(fabsf(h.t - 1.0f) < 1e-6f);
        sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, 1.0f), sidx_v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
        sidx_accel_intersect(a, &r, NULL, &h);
        assert_int_equal(h.prim, SIDX_NO_HIT);
        sidx_accel_destroy(a);
        sidx_accel *e = NULL;
        if (sidx_accel_build(structures[k], &none, NULL, &e, NULL) == SIDX_OK) {
            sidx_accel_intersect(e, &r, NULL, &h);
            assert_int_equal(h.prim, SIDX_NO_HIT);
            sidx_accel_destroy(e);
        }
    }
    sidx_mesh_free(&one);
}

/* Allocation failures at every point of every build: clean failure, no leak. */
typedef struct fail_alloc { long countdown; long live; } fail_alloc;
static void *fa_alloc(size_t size, void *user)
{
    fail_alloc *f = user;
    if (f->countdown-- == 0) return NULL;
    void *p = malloc(size);
    if (p) f->live++;
    return p;
}
static void fa_free(void *p, void *user)
{
    fail_alloc *f = user;
    if (p) { f->live--; free(p); }
}

static void test_alloc_failures(void **state)
{
    (void)state;
    sidx_mesh m;
    sidx_error err;
    assert_int_equal(sidx_scene_make("icosphere", 2, &m, &err), SIDX_OK);
    for (size_t k = 0; k < N_STRUCTURES; ++k) {
        if (!have(structures[k])) continue;
        for (long fail_at = 0;; ++fail_at) {
            fail_alloc f = {fail_at, 0};
            const sidx_allocator al = {fa_alloc, fa_free, &f};
            sidx_build_options opt;
            memset(&opt, 0, sizeof opt);
            opt.alloc = &al;
            sidx_accel *a = NULL;
            const sidx_status s = sidx_accel_build(structures[k], &m, &opt, &a, NULL);
            if (s == SIDX_OK) {
                sidx_accel_destroy(a);
                assert_int_equal(f.live, 0);
                break;
            }
            assert_int_equal(s, SIDX_ERR_NOMEM);
            assert_null(a);
            assert_int_equal(f.live, 0);
            assert_true(fail_at < 100000);
        }
    }
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_resolution_formula),
        cmocka_unit_test(test_dda_cells),
        cmocka_unit_test(test_tiny_meshes),
        cmocka_unit_test(test_against_brute),
        cmocka_unit_test(test_against_brute_options),
        cmocka_unit_test(test_no_leaks_icosphere),
        cmocka_unit_test(test_mailbox),
        cmocka_unit_test(test_exact_vs_boxonly),
        cmocka_unit_test(test_grid2_stadium),
        cmocka_unit_test(test_irregular_merges),
        cmocka_unit_test(test_irregular_construction_events),
        cmocka_unit_test(test_irregular_stadium),
        cmocka_unit_test(test_octree_quadtree),
        cmocka_unit_test(test_build_events),
        cmocka_unit_test(test_alloc_failures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
