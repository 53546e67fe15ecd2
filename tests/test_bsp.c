/* test_bsp.c — the BSP tree ("bsp"): ray queries against the
 * double-precision reference on every built-in scene and ray kind, the
 * split bookkeeping, the painter's order in 3D and in 2D (Doom-style,
 * eye in the plane of the flat2d scene), events, and allocation failure. */
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
#include "sidx/bsp.h"
#include "common/testkit.h"

static sidx_accel *build_bsp(const sidx_mesh *m, const sidx_build_options *opt)
{
    sidx_accel *a = NULL;
    sidx_error err;
    const sidx_status s = sidx_accel_build("bsp", m, opt, &a, &err);
    if (s != SIDX_OK) fprintf(stderr, "bsp build: %s\n", err.message);
    assert_int_equal(s, SIDX_OK);
    return a;
}

static void make_scene(const char *name, uint32_t detail, sidx_mesh *m)
{
    sidx_error err;
    assert_int_equal(sidx_scene_make(name, detail, m, &err), SIDX_OK);
}

/* ---- ray queries ------------------------------------------------------- */

static void check_scene(const char *name, uint32_t detail, size_t rays_per_kind)
{
    sidx_mesh m;
    make_scene(name, detail, &m);
    sidx_accel *bsp = build_bsp(&m, NULL);
    sidx_accel *brute = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    tk_rayrec *rays = malloc(rays_per_kind * sizeof *rays);
    assert_non_null(rays);
    tk_errstats es;
    memset(&es, 0, sizeof es);
    for (int kind = 0; kind < TK_RAYS_KIND_COUNT; ++kind) {
        tk_make_rays(&m, (tk_ray_kind)kind, rays_per_kind, 1234u + (uint64_t)kind, rays);
        for (size_t i = 0; i < rays_per_kind; ++i) {
            sidx_ray r;
            if (tk_ray_from(&rays[i], &r) != SIDX_OK) continue;
            /* against brute force with the same float triangle test: the
             * structure must find exactly what testing every triangle finds
             * (grazing rays make the double-precision reference differ from
             * any float test; test_accel_suite measures that error) */
            sidx_hit ref, got;
            sidx_accel_intersect(brute, &r, NULL, &ref);
            sidx_accel_intersect(bsp, &r, NULL, &got);
            if (!tk_hits_agree(&ref, &got))
                fprintf(stderr, "%s kind %d ray %zu: brute prim %u t %.9g, bsp prim %u t %.9g\n", name, kind, i,
                        ref.prim, ref.t, got.prim, got.t);
            tk_errstats_add(&es, &ref, &got);
            int occ_bsp, occ_brute;
            sidx_accel_occluded(bsp, &r, NULL, &occ_bsp);
            sidx_accel_occluded(brute, &r, NULL, &occ_brute);
            assert_int_equal(occ_bsp, occ_brute);
        }
    }
    assert_int_equal(tk_errstats_errors(&es), 0);
    sidx_bsp_info info;
    assert_int_equal(sidx_bsp_info_get(bsp, &info), SIDX_OK);
    /* every cut replaces one piece by two */
    assert_int_equal(info.pieces, info.input_tris + info.splits);
    sidx_accel_stats st;
    sidx_accel_stats_get(bsp, &st);
    printf("  bsp %-9s tris %6u  cuts %5u (%.1f%%)  nodes %6u  depth %2u  planes: %u polygon, %u free  "
           "coplanar pieces %u  ray refs %.2f/tri  %zu KiB  unordered leaves %u\n",
           name, info.input_tris, info.splits, 100.0 * info.splits / (info.input_tris ? info.input_tris : 1),
           info.nodes, info.max_depth, info.polygon_planes, info.free_planes, info.coplanar_pieces,
           (double)info.ray_refs / (info.input_tris ? info.input_tris : 1), st.bytes / 1024, info.unordered_leaves);
    free(rays);
    sidx_accel_destroy(brute);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

static void rays_icosphere(void **state) { (void)state; check_scene("icosphere", 0, 300); }
static void rays_teapot(void **state) { (void)state; check_scene("teapot", 0, 300); }
static void rays_stadium(void **state) { (void)state; check_scene("stadium", 0, 200); }
static void rays_soup(void **state) { (void)state; check_scene("soup", 600, 200); }
static void rays_menger(void **state) { (void)state; check_scene("menger", 0, 300); }
static void rays_flat2d(void **state) { (void)state; check_scene("flat2d", 0, 300); }
static void rays_cornell(void **state) { (void)state; check_scene("cornell", 0, 300); }
static void rays_grid(void **state) { (void)state; check_scene("grid", 32, 300); }

/* A closed sphere has no face plane with anything in front of it: pure
 * autopartition would be a 1280-deep list.  The free planes keep it shallow. */
static void convex_stays_shallow(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("icosphere", 0, &m);
    sidx_accel *bsp = build_bsp(&m, NULL);
    sidx_bsp_info info;
    sidx_bsp_info_get(bsp, &info);
    assert_true(info.max_depth < 40);
    assert_true(info.free_planes > 0);
    assert_int_equal(info.unordered_leaves, 0);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

/* Two crossing triangles: whichever plane is chosen first cuts the other. */
static void crossing_triangles_are_cut(void **state)
{
    (void)state;
    const float xyz[] = {-1, 0, -1, 1, 0, -1, 0, 0, 1, /* in y = 0 */
                         0, -1, -1, 0, 1, -1, 0, 0.5f, 1}; /* in x = 0, crosses the first */
    const uint32_t idx[] = {0, 1, 2, 3, 4, 5};
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 6, idx, 2, NULL), SIDX_OK);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook hook = sidx_recorder_hook(&rec);
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.hook = &hook;
    sidx_accel *bsp = build_bsp(&m, &opt);
    sidx_bsp_info info;
    sidx_bsp_info_get(bsp, &info);
    assert_int_equal(info.splits, 1);
    assert_int_equal(info.pieces, 3);
    int saw_note = 0, saw_split = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        assert_string_equal(e->structure, "bsp");
        if (e->type == SIDX_EV_NOTE && e->count == 1) saw_note = 1;
        if (e->type == SIDX_EV_BUILD_SPLIT) {
            saw_split = 1;
            assert_int_equal(e->axis, -1);
            assert_float_equal(sidx_v3_length(e->bounds.min), 1.0f, 1e-5f); /* unit normal in bounds.min */
        }
    }
    assert_true(saw_note && saw_split);
    /* a ray through each half of the cut triangle still finds it */
    sidx_ray r;
    sidx_hit h;
    sidx_ray_init(&r, sidx_v3(-5, 0.2f, 0.0f), sidx_v3(1, 0, 0), 0, INFINITY);
    sidx_accel_intersect(bsp, &r, NULL, &h);
    assert_int_equal(h.prim, 1);
    sidx_ray_init(&r, sidx_v3(-5, -0.2f, -0.5f), sidx_v3(1, 0, 0), 0, INFINITY);
    sidx_accel_intersect(bsp, &r, NULL, &h);
    assert_int_equal(h.prim, 1);

    /* traversal events, in order: NODE_ENTER ... PRIM_TEST ... TERMINATE */
    sidx_recorder_clear(&rec);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 7};
    sidx_ray_init(&r, sidx_v3(0.3f, -5, 0.0f), sidx_v3(0, 1, 0), 0, INFINITY);
    sidx_accel_intersect(bsp, &r, &q, &h);
    assert_int_equal(h.prim, 0);
    assert_true(rec.count >= 4);
    assert_int_equal(rec.events[0].type, SIDX_EV_RAY_BEGIN);
    assert_int_equal(rec.events[1].type, SIDX_EV_NODE_ENTER);
    assert_int_equal(rec.events[rec.count - 2].type, SIDX_EV_TERMINATE);
    assert_int_equal(rec.events[rec.count - 1].type, SIDX_EV_RAY_END);
    int saw_update = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        assert_int_equal(rec.events[i].ray_id, 7);
        if (rec.events[i].type == SIDX_EV_HIT_UPDATE) saw_update = 1;
    }
    assert_true(saw_update);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

/* ---- painter's order ------------------------------------------------------ */

typedef struct painted { sidx_vec3 *v; uint32_t *first, *num, *tri; size_t n, cap; size_t nv, capv; } painted;

static int collect(const sidx_bsp_piece *p, void *user)
{
    painted *pp = user;
    if (pp->n == pp->cap) {
        pp->cap = pp->cap ? 2 * pp->cap : 256;
        pp->first = realloc(pp->first, pp->cap * sizeof *pp->first);
        pp->num = realloc(pp->num, pp->cap * sizeof *pp->num);
        pp->tri = realloc(pp->tri, pp->cap * sizeof *pp->tri);
        assert_true(pp->first && pp->num && pp->tri);
    }
    while (pp->nv + p->num_verts > pp->capv) {
        pp->capv = pp->capv ? 2 * pp->capv : 1024;
        pp->v = realloc(pp->v, pp->capv * sizeof *pp->v);
        assert_non_null(pp->v);
    }
    assert_true(p->num_verts >= 3);
    memcpy(pp->v + pp->nv, p->verts, p->num_verts * sizeof *p->verts);
    pp->first[pp->n] = (uint32_t)pp->nv;
    pp->num[pp->n] = p->num_verts;
    pp->tri[pp->n] = p->tri;
    pp->nv += p->num_verts;
    pp->n++;
    return 0;
}

static void painted_free(painted *p)
{
    free(p->v); free(p->first); free(p->num); free(p->tri);
    memset(p, 0, sizeof *p);
}

static int ray_hits_piece(const sidx_ray *r, const painted *p, size_t i, float *t)
{
    const sidx_vec3 *v = p->v + p->first[i];
    for (uint32_t k = 1; k + 1 < p->num[i]; ++k)
        if (sidx_intersect_triangle(SIDX_TRI_WATERTIGHT, r, v[0], v[k], v[k + 1], r->tmax, t, NULL, NULL)) return 1;
    return 0;
}

/* What a painter sees along a ray: drawing back to front, the last piece
 * the ray passes through is the visible one; front to back, the first.
 * It must be the closest hit (same triangle, or a coincident surface). */
static void check_painter(const sidx_mesh *m, const sidx_accel *bsp, sidx_vec3 eye, int planar, size_t nrays,
                          uint64_t seed)
{
    painted b2f, f2b;
    memset(&b2f, 0, sizeof b2f);
    memset(&f2b, 0, sizeof f2b);
    assert_int_equal(sidx_bsp_paint(bsp, eye, SIDX_BSP_BACK_TO_FRONT, collect, &b2f, NULL), SIDX_OK);
    assert_int_equal(sidx_bsp_paint(bsp, eye, SIDX_BSP_FRONT_TO_BACK, collect, &f2b, NULL), SIDX_OK);
    sidx_bsp_info info;
    sidx_bsp_info_get(bsp, &info);
    assert_int_equal(b2f.n, info.pieces);
    assert_int_equal(f2b.n, info.pieces);
    for (size_t i = 0; i < b2f.n; ++i) assert_int_equal(b2f.tri[i], f2b.tri[f2b.n - 1 - i]); /* mirror images */

    tk_rng g;
    tk_rng_seed(&g, seed);
    size_t checked = 0;
    for (size_t k = 0; k < nrays; ++k) {
        /* aim at a random point of a random triangle so most rays hit */
        const uint32_t tri = tk_rng_below(&g, m->num_triangles);
        double u = tk_rng_unit(&g), v = tk_rng_unit(&g);
        if (u + v > 1.0) { u = 1.0 - u; v = 1.0 - v; }
        const sidx_vec3 a = sidx_mesh_vertex(m, tri, 0), b = sidx_mesh_vertex(m, tri, 1), c = sidx_mesh_vertex(m, tri, 2);
        sidx_vec3 target = sidx_v3_add(a, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(b, a), (float)u),
                                                      sidx_v3_scale(sidx_v3_sub(c, a), (float)v)));
        if (planar) target.z = eye.z; /* 2D: rays stay in the plane of the eye */
        const sidx_vec3 d = sidx_v3_sub(target, eye);
        tk_rayrec rec = tk_rayrec_make(eye, d, 0.0f, INFINITY);
        sidx_ray r;
        if (tk_ray_from(&rec, &r) != SIDX_OK) continue;
        sidx_hit ref;
        tk_ref_intersect(m, &rec, &ref);
        sidx_hit last = sidx_hit_none(), first = sidx_hit_none();
        for (size_t i = 0; i < b2f.n; ++i) {
            float t;
            if (ray_hits_piece(&r, &b2f, i, &t)) { last.t = t; last.prim = b2f.tri[i]; }
        }
        for (size_t i = 0; i < f2b.n; ++i) {
            float t;
            if (ray_hits_piece(&r, &f2b, i, &t)) { first.t = t; first.prim = f2b.tri[i]; break; }
        }
        if (!tk_hits_agree(&ref, &last) || !tk_hits_agree(&ref, &first))
            fprintf(stderr, "painter ray %zu: ref %u t %.9g, back-to-front last %u t %.9g, front-to-back first %u t %.9g\n",
                    k, ref.prim, ref.t, last.prim, last.t, first.prim, first.t);
        assert_true(tk_hits_agree(&ref, &last));
        assert_true(tk_hits_agree(&ref, &first));
        ++checked;
    }
    assert_true(checked > nrays / 2);
    painted_free(&b2f);
    painted_free(&f2b);
}

static void painter_3d(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", 0, &m);
    sidx_accel *bsp = build_bsp(&m, NULL);
    const sidx_aabb box = sidx_mesh_bounds(&m);
    const sidx_vec3 c = sidx_aabb_centroid(box), e = sidx_aabb_extent(box);
    const sidx_vec3 eyes[3] = {sidx_v3_add(c, sidx_v3(2.0f * e.x, 0.7f * e.y, 1.5f * e.z)),
                               sidx_v3_add(c, sidx_v3(-0.3f * e.x, -2.0f * e.y, 0.2f * e.z)),
                               sidx_v3_add(c, sidx_v3(0.05f * e.x, 0.1f * e.y, -3.0f * e.z))};
    for (int i = 0; i < 3; ++i) check_painter(&m, bsp, eyes[i], 0, tk_fast_tests() ? 40 : 120, 77u + (uint64_t)i);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

/* Soup: lots of cuts, so pieces (not triangles) are what gets ordered. */
static void painter_3d_soup(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("soup", 300, &m);
    sidx_accel *bsp = build_bsp(&m, NULL);
    sidx_bsp_info info;
    sidx_bsp_info_get(bsp, &info);
    assert_true(info.splits > 0);
    assert_int_equal(info.unordered_leaves, 0);
    check_painter(&m, bsp, sidx_v3(0.5f, 0.5f, 0.5f), 0, tk_fast_tests() ? 40 : 150, 5); /* eye inside the soup */
    check_painter(&m, bsp, sidx_v3(-2.0f, 0.3f, 3.0f), 0, tk_fast_tests() ? 40 : 150, 6);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

/* Doom-style 2D: the flat2d scene's triangles cross the plane z = 0 in
 * segments (their spines), the walls; the eye stands in that plane and
 * looks along it. */
static void painter_2d(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("flat2d", 0, &m);
    sidx_accel *bsp = build_bsp(&m, NULL);
    const sidx_aabb box = sidx_mesh_bounds(&m);
    const sidx_vec3 c = sidx_aabb_centroid(box), e = sidx_aabb_extent(box);
    check_painter(&m, bsp, sidx_v3(c.x - 0.9f * e.x, c.y + 0.1f * e.y, 0.0f), 1, tk_fast_tests() ? 40 : 150, 11);
    check_painter(&m, bsp, sidx_v3(c.x + 0.13f * e.x, c.y - 0.21f * e.y, 0.0f), 1, tk_fast_tests() ? 40 : 150, 12);
    /* and seen from +z, as the lecture draws it */
    check_painter(&m, bsp, sidx_v3(c.x + 0.2f * e.x, c.y, 10.0f * (e.x + e.y)), 0, tk_fast_tests() ? 40 : 120, 13);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

static int stop_after_3(const sidx_bsp_piece *p, void *user)
{
    (void)p;
    return ++*(int *)user == 3;
}

static void paint_arguments(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("cornell", 0, &m);
    sidx_accel *bsp = build_bsp(&m, NULL), *brute = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    int n = 0;
    assert_int_equal(sidx_bsp_paint(bsp, sidx_v3(0, 0, 0), SIDX_BSP_BACK_TO_FRONT, stop_after_3, &n, NULL), SIDX_OK);
    assert_int_equal(n, 3);
    assert_int_equal(sidx_bsp_paint(brute, sidx_v3(0, 0, 0), SIDX_BSP_BACK_TO_FRONT, stop_after_3, &n, NULL),
                     SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_paint(bsp, sidx_v3(NAN, 0, 0), SIDX_BSP_BACK_TO_FRONT, stop_after_3, &n, NULL),
                     SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_paint(bsp, sidx_v3(0, 0, 0), SIDX_BSP_BACK_TO_FRONT, NULL, &n, NULL),
                     SIDX_ERR_INVALID_ARG);
    sidx_bsp_info info;
    assert_int_equal(sidx_bsp_info_get(brute, &info), SIDX_ERR_INVALID_ARG);
    sidx_accel_destroy(brute);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

/* ---- the read-only node view ------------------------------------------------- */

typedef struct view_walk {
    const sidx_accel *bsp;
    uint32_t *next; /* per node: the index of its next piece */
    uint32_t pieces, mismatches;
} view_walk;

static int check_piece(const sidx_bsp_piece *p, void *user)
{
    view_walk *w = user;
    sidx_bsp_piece q;
    ++w->pieces;
    if (sidx_bsp_node_piece(w->bsp, p->node, w->next[p->node]++, &q) != SIDX_OK || q.tri != p->tri ||
        q.num_verts != p->num_verts || q.verts != p->verts || q.node != p->node)
        ++w->mismatches;
    return 0;
}

/* sidx_bsp_node_get / _piece describe the tree sidx_bsp_paint walks: the
 * painter draws each node's pieces in the view's order, every node's
 * pieces once; out-of-range ids and other structures are refused. */
static void node_view(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("cornell", 0, &m);
    sidx_accel *bsp = build_bsp(&m, NULL), *brute = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    sidx_bsp_info info;
    assert_int_equal(sidx_bsp_info_get(bsp, &info), SIDX_OK);
    uint32_t leaves = 0, total = 0;
    for (uint32_t i = 0; i < info.nodes; ++i) {
        sidx_bsp_node_view v;
        assert_int_equal(sidx_bsp_node_get(bsp, i, &v), SIDX_OK);
        if (v.child[0] == UINT32_MAX) {
            ++leaves;
            assert_int_equal(v.child[1], UINT32_MAX);
        } else {
            assert_true(v.child[0] < info.nodes && v.child[1] < info.nodes);
            assert_true(fabs(v.n[0] * v.n[0] + v.n[1] * v.n[1] + v.n[2] * v.n[2] - 1.0) < 1e-9);
        }
        total += v.piece_count;
    }
    assert_int_equal(leaves, info.leaves);
    view_walk w = {bsp, calloc(info.nodes, sizeof(uint32_t)), 0, 0};
    assert_non_null(w.next);
    assert_int_equal(sidx_bsp_paint(bsp, sidx_v3(2.5f, 2.5f, -3.0f), SIDX_BSP_BACK_TO_FRONT, check_piece, &w, NULL),
                     SIDX_OK);
    assert_int_equal(w.mismatches, 0);
    assert_int_equal(w.pieces, total);
    for (uint32_t i = 0; i < info.nodes; ++i) {
        sidx_bsp_node_view v;
        assert_int_equal(sidx_bsp_node_get(bsp, i, &v), SIDX_OK);
        assert_int_equal(w.next[i], v.piece_count);
    }
    free(w.next);
    sidx_bsp_node_view v;
    sidx_bsp_piece q;
    assert_int_equal(sidx_bsp_node_get(bsp, info.nodes, &v), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_node_get(brute, 0, &v), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_node_get(bsp, 0, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_node_get(NULL, 0, &v), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_node_get(bsp, 0, &v), SIDX_OK);
    assert_int_equal(sidx_bsp_node_piece(bsp, 0, v.piece_count, &q), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_node_piece(bsp, info.nodes, 0, &q), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_node_piece(brute, 0, 0, &q), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_bsp_node_piece(bsp, 0, 0, NULL), SIDX_ERR_INVALID_ARG);
    sidx_accel_destroy(brute);
    sidx_accel_destroy(bsp);
    sidx_mesh_free(&m);
}

/* ---- allocation failure ------------------------------------------------------ */


static void nomem_leaks_nothing(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("soup", 100, &m);
    int ok = 0;
    for (long k = 0; k < 400 && !ok; k += (k < 40 ? 1 : 7)) {
        tk_failing f = {k, 0};
        sidx_allocator al = tk_failing_allocator(&f);
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.alloc = &al;
        sidx_accel *a = NULL;
        const sidx_status s = sidx_accel_build("bsp", &m, &opt, &a, NULL);
        if (s == SIDX_OK) {
            ok = 1;
            sidx_accel_destroy(a);
        } else {
            assert_int_equal(s, SIDX_ERR_NOMEM);
            assert_null(a);
        }
        assert_int_equal(f.live, 0);
    }
    assert_true(ok);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(crossing_triangles_are_cut),
        cmocka_unit_test(convex_stays_shallow),
        cmocka_unit_test(rays_icosphere),
        cmocka_unit_test(rays_teapot),
        cmocka_unit_test(rays_stadium),
        cmocka_unit_test(rays_soup),
        cmocka_unit_test(rays_menger),
        cmocka_unit_test(rays_flat2d),
        cmocka_unit_test(rays_cornell),
        cmocka_unit_test(rays_grid),
        cmocka_unit_test(painter_3d),
        cmocka_unit_test(painter_3d_soup),
        cmocka_unit_test(painter_2d),
        cmocka_unit_test(paint_arguments),
        cmocka_unit_test(node_view),
        cmocka_unit_test(nomem_leaks_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
