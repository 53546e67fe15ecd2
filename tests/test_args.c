/* test_args.c — every public function of lib/include/sidx/ called with
 * NULL pointers and invalid values (bad enum values, zero counts, NaN,
 * out-of-range indices): each must give the result docs/errors.md states —
 * an error status (with a message where the function takes a sidx_error),
 * a documented no-op, or a documented return value — and never crash.
 *
 * The list of functions was taken from the headers (gcc -aux-info over
 * every header; see docs/errors.md); each test below is named after its
 * header.  Not called: the static inline helpers of math.h (sidx_v3_*,
 * sidx_aabb_*, sidx_ray_at, sidx_hit_none) and mesh.h's sidx_mesh_vertex.
 * They take values, not pointers (sidx_ray_at and sidx_mesh_vertex take a
 * pointer that is dereferenced unchecked, like an array index: they are the
 * hot-loop accessors, and a check would cost every traversal step), and on
 * NaN they return NaN by IEEE arithmetic — nothing to guard. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "sidx/sidx.h"
#include "sidx/beam.h"
#include "sidx/bsp.h"
#include "sidx/instance.h"
#include "sidx/kdtree.h"
#include "sidx/octree.h"
#include "sidx/lightbuffer.h"
#include "sidx/packet.h"
#include "sidx/parallel.h"
#include "sidx/rayclass.h"
#include "sidx/viz.h"

#define BAD_ENUM 1000

/* Checks that report and count instead of stopping the test, so one run
 * lists every function that breaks its contract; each test's teardown
 * fails the test if any check failed. */
static int failures;
#define CHECK(c)                                                                  \
    do {                                                                          \
        if (!(c)) {                                                               \
            ++failures;                                                           \
            print_error("%s:%d: check failed: %s\n", __FILE__, __LINE__, #c);     \
        }                                                                         \
    } while (0)
#define CHECK_EQ(a, b)                                                                                \
    do {                                                                                              \
        const long long a_ = (long long)(a), b_ = (long long)(b);                                     \
        if (a_ != b_) {                                                                               \
            ++failures;                                                                               \
            print_error("%s:%d: check failed: %s == %s (%lld != %lld)\n", __FILE__, __LINE__, #a, #b, a_, b_); \
        }                                                                                             \
    } while (0)
#define CHECK_NULL(p) CHECK((p) == NULL)
#define CHECK_MEM(a, b, n) CHECK(memcmp((a), (b), (n)) == 0)
static int teardown(void **state)
{
    (void)state;
    const int f = failures;
    failures = 0;
    return f ? -1 : 0;
}

/* An error status with a message naming the problem. */
#define ASSERT_FAILS(call, expected, errp)                          \
    do {                                                           \
        (errp)->status = SIDX_OK;                                  \
        (errp)->message[0] = '\0';                                 \
        const sidx_status s_ = (call);                             \
        CHECK_EQ(s_, (expected));                                  \
        CHECK_EQ((errp)->status, (expected));                      \
        CHECK((errp)->message[0] != '\0');                         \
    } while (0)

static sidx_mesh tiny_mesh(void)
{
    static const float xyz[] = {-1, -1, 0, 1, -1, 0, 0, 1, 0, -1, -1, 1, 1, -1, 1, 0, 1, 1};
    static const uint32_t idx[] = {0, 1, 2, 3, 4, 5};
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 6, idx, 2, NULL), SIDX_OK);
    return m;
}

static sidx_ray good_ray(void)
{
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.1f, 0.1f, -5), sidx_v3(0, 0, 1), 0.0f, INFINITY), SIDX_OK);
    return r;
}

/* ---- status.h, sidx.h, math.h ------------------------------------------ */

static void test_status_version_ray(void **state)
{
    (void)state;
    assert_non_null(sidx_status_str(SIDX_STATUS_COUNT));
    assert_non_null(sidx_status_str((sidx_status)-1));
    assert_non_null(sidx_status_str((sidx_status)BAD_ENUM));
    assert_non_null(sidx_version());

    sidx_ray r, before;
    memset(&r, 0x5a, sizeof r); /* every byte set (padding included) so memcmp is meaningful */
    before = r;
    const sidx_vec3 o = sidx_v3(0, 0, 0), d = sidx_v3(0, 0, 1);
    CHECK_EQ(sidx_ray_init(NULL, o, d, 0, 1), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_ray_init(&r, sidx_v3(NAN, 0, 0), d, 0, 1), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_ray_init(&r, o, sidx_v3(0, INFINITY, 0), 0, 1), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_ray_init(&r, o, sidx_v3(0, -0.0f, 0), 0, 1), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_ray_init(&r, o, d, NAN, 1), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_ray_init(&r, o, d, 0, NAN), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_ray_init(&r, o, d, 2, 1), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_ray_init(&r, o, d, -1.0f, 1), SIDX_ERR_INVALID_ARG); /* rays start at their origin */
    CHECK_MEM(&r, &before, sizeof r); /* untouched on failure */
    CHECK_EQ(sidx_ray_init(&r, o, d, -0.0f, 1), SIDX_OK); /* -0 is not negative */
}

/* ---- accel.h ------------------------------------------------------------ */

static void test_accel_registry_and_names(void **state)
{
    (void)state;
    sidx_traversal t = SIDX_TRAVERSE_STACK;
    CHECK_NULL(sidx_traversal_name(SIDX_TRAVERSE_COUNT));
    CHECK_NULL(sidx_traversal_name((sidx_traversal)BAD_ENUM));
    CHECK_EQ(sidx_traversal_parse(NULL, &t), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_traversal_parse("sideways", &t), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_traversal_parse("stack", NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(t, SIDX_TRAVERSE_STACK);
    const size_t n = sidx_accel_registered_count();
    CHECK(n > 0);
    CHECK_NULL(sidx_accel_registered_name(n));
    CHECK_NULL(sidx_accel_registered_name((size_t)-1));
    CHECK_NULL(sidx_accel_registered_description(n));
    CHECK_EQ(sidx_accel_is_registered(NULL), 0);
    CHECK_EQ(sidx_accel_is_registered(""), 0);
    CHECK_NULL(sidx_accel_name(NULL));
    CHECK_NULL(sidx_accel_mesh(NULL));
    CHECK_NULL(sidx_accel_options(NULL));
    sidx_accel_destroy(NULL); /* documented no-op */
}

static void test_accel_build_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    sidx_error err;
    sidx_accel *a = (sidx_accel *)&m; /* must be set to NULL on failure */
    CHECK_EQ(sidx_accel_build("bvh", &m, NULL, NULL, &err), SIDX_ERR_INVALID_ARG);
    ASSERT_FAILS(sidx_accel_build(NULL, &m, NULL, &a, &err), SIDX_ERR_INVALID_ARG, &err);
    CHECK_NULL(a);
    ASSERT_FAILS(sidx_accel_build("bvh", NULL, NULL, &a, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_accel_build("no-such-tree", &m, NULL, &a, &err), SIDX_ERR_UNKNOWN_ACCEL, &err);
    ASSERT_FAILS(sidx_accel_auto(NULL, NULL, &a, &err), SIDX_ERR_INVALID_ARG, &err);
    CHECK_EQ(sidx_accel_auto(&m, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);

    /* every out-of-range option, for every structure */
    sidx_build_options bad[10];
    memset(bad, 0, sizeof bad);
    bad[0].tri = (sidx_tri_method)BAD_ENUM;
    bad[1].box = (sidx_box_method)BAD_ENUM;
    bad[2].c_trav = -1.0f;
    bad[3].c_tri = NAN;
    bad[4].c_trav = INFINITY;
    bad[5].empty_bonus = 1.0f;
    bad[6].empty_bonus = NAN;
    bad[7].grid_density = -2.0f;
    bad[8].grid_density = NAN;
    const sidx_allocator half = {NULL, NULL, NULL};
    bad[9].alloc = &half;
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s)
        for (size_t k = 0; k < sizeof bad / sizeof bad[0]; ++k) {
            a = (sidx_accel *)&m;
            const int before = failures;
            ASSERT_FAILS(sidx_accel_build(sidx_accel_registered_name(s), &m, &bad[k], &a, &err),
                         SIDX_ERR_INVALID_ARG, &err);
            CHECK_NULL(a);
            if (failures != before) print_error("  (%s, bad option %zu)\n", sidx_accel_registered_name(s), k);
            if (a != NULL && a != (sidx_accel *)&m) sidx_accel_destroy(a);
        }

    /* invalid meshes */
    sidx_mesh broken = m;
    broken.positions = NULL;
    ASSERT_FAILS(sidx_accel_build("bvh", &broken, NULL, &a, &err), SIDX_ERR_INVALID_ARG, &err);
    broken = m;
    broken.indices = NULL;
    ASSERT_FAILS(sidx_accel_build("bvh", &broken, NULL, &a, &err), SIDX_ERR_INVALID_ARG, &err);
    broken = m;
    broken.num_vertices = 2; /* indices now out of range */
    ASSERT_FAILS(sidx_accel_build("kdtree", &broken, NULL, &a, &err), SIDX_ERR_BAD_GEOMETRY, &err);
    const float saved = m.positions[1].y;
    m.positions[1].y = NAN;
    ASSERT_FAILS(sidx_accel_build("grid", &m, NULL, &a, &err), SIDX_ERR_BAD_GEOMETRY, &err);
    ASSERT_FAILS(sidx_accel_auto(&m, NULL, &a, &err), SIDX_ERR_BAD_GEOMETRY, &err);
    m.positions[1].y = saved;
    sidx_mesh_free(&m);
}

static void test_accel_queries_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    const sidx_ray r = good_ray();
    sidx_hit h;
    int occ = 7;
    sidx_error err;
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s) {
        const char *name = sidx_accel_registered_name(s);
        sidx_accel *a = NULL;
        CHECK_EQ(sidx_accel_build(name, &m, NULL, &a, NULL), SIDX_OK);
        CHECK_EQ(sidx_accel_intersect(NULL, &r, NULL, &h), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_intersect(a, NULL, NULL, &h), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_intersect(a, &r, NULL, NULL), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_occluded(NULL, &r, NULL, &occ), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_occluded(a, NULL, NULL, &occ), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_occluded(a, &r, NULL, NULL), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_intersect_n(NULL, &r, 1, NULL, &h), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_intersect_n(a, NULL, 1, NULL, &h), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_intersect_n(a, &r, 1, NULL, NULL), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_intersect_n(a, NULL, 0, NULL, NULL), SIDX_OK); /* zero rays: nothing to do */
        CHECK_EQ(sidx_accel_stats_get(NULL, &(sidx_accel_stats){0}), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_accel_stats_get(a, NULL), SIDX_ERR_INVALID_ARG);
        /* a traversal variant that does not exist: the structure's default */
        sidx_hit ref, got;
        CHECK_EQ(sidx_accel_intersect(a, &r, NULL, &ref), SIDX_OK);
        const sidx_query q = {0, (sidx_traversal)BAD_ENUM, NULL, 0};
        CHECK_EQ(sidx_accel_intersect(a, &r, &q, &got), SIDX_OK);
        CHECK_EQ(got.prim, ref.prim);
        CHECK_EQ(sidx_accel_occluded(a, &r, &q, &occ), SIDX_OK);
        CHECK_EQ(occ, ref.prim != SIDX_NO_HIT);
        /* refit: OK or UNSUPPORTED with a message */
        err.message[0] = '\0';
        const sidx_status rs = sidx_accel_refit(a, &err);
        CHECK(rs == SIDX_OK || (rs == SIDX_ERR_UNSUPPORTED && err.message[0]));
        sidx_accel_destroy(a);
    }
    CHECK_EQ(sidx_accel_refit(NULL, &err), SIDX_ERR_INVALID_ARG);
    sidx_mesh_free(&m);
}

/* Zero counts: a mesh without triangles builds everywhere and every query
 * misses. */
static void test_accel_empty_mesh(void **state)
{
    (void)state;
    sidx_mesh m;
    CHECK_EQ(sidx_mesh_from_arrays(&m, NULL, 0, NULL, 0, NULL), SIDX_OK);
    CHECK_EQ(m.num_triangles, 0);
    const sidx_ray r = good_ray();
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s) {
        sidx_accel *a = NULL;
        sidx_error err;
        const sidx_status st = sidx_accel_build(sidx_accel_registered_name(s), &m, NULL, &a, &err);
        CHECK_EQ(st, SIDX_OK);
        sidx_hit h;
        int occ = 1;
        CHECK_EQ(sidx_accel_intersect(a, &r, NULL, &h), SIDX_OK);
        CHECK_EQ(h.prim, SIDX_NO_HIT);
        CHECK_EQ(sidx_accel_occluded(a, &r, NULL, &occ), SIDX_OK);
        CHECK_EQ(occ, 0);
        sidx_accel_stats stats;
        CHECK_EQ(sidx_accel_stats_get(a, &stats), SIDX_OK);
        sidx_accel_destroy(a);
    }
    sidx_accel *a = NULL;
    CHECK_EQ(sidx_accel_auto(&m, NULL, &a, NULL), SIDX_OK);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* ---- mesh.h --------------------------------------------------------------- */

static void test_mesh_bad_arguments(void **state)
{
    (void)state;
    sidx_error err;
    sidx_mesh m, untouched;
    memset(&untouched, 0xab, sizeof untouched);
    const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t idx[3] = {0, 1, 2}, bad_idx[3] = {0, 1, 3};
    sidx_mesh_free(NULL); /* documented no-op */
    memset(&m, 0, sizeof m);
    sidx_mesh_free(&m); /* zeroed mesh: no-op */

    ASSERT_FAILS(sidx_mesh_from_arrays(NULL, xyz, 3, idx, 1, &err), SIDX_ERR_INVALID_ARG, &err);
    m = untouched;
    ASSERT_FAILS(sidx_mesh_from_arrays(&m, NULL, 3, idx, 1, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_from_arrays(&m, xyz, 3, NULL, 1, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_from_arrays(&m, xyz, 3, bad_idx, 1, &err), SIDX_ERR_BAD_GEOMETRY, &err);
    const float nan_xyz[9] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    ASSERT_FAILS(sidx_mesh_from_arrays(&m, nan_xyz, 3, idx, 1, &err), SIDX_ERR_BAD_GEOMETRY, &err);
    CHECK_MEM(&m, &untouched, sizeof m); /* outputs untouched on failure */

    ASSERT_FAILS(sidx_mesh_validate(NULL, &err), SIDX_ERR_INVALID_ARG, &err);

    ASSERT_FAILS(sidx_mesh_load_obj(NULL, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_load_obj("x.obj", NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_load_obj("/nonexistent/sidx.obj", &m, &err), SIDX_ERR_IO, &err);
    ASSERT_FAILS(sidx_mesh_load_ply(NULL, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_load_ply("x.ply", NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_load_ply("/nonexistent/sidx.ply", &m, &err), SIDX_ERR_IO, &err);
    ASSERT_FAILS(sidx_mesh_load(NULL, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_load("x.obj", NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_load("/nonexistent/sidx.obj", &m, &err), SIDX_ERR_IO, &err);
    ASSERT_FAILS(sidx_mesh_parse_obj(NULL, 4, NULL, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_parse_obj("v 0 0 0", 7, NULL, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_parse_ply(NULL, 4, NULL, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_parse_ply("ply\n", 4, NULL, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    CHECK_MEM(&m, &untouched, sizeof m);
    /* zero bytes: an empty mesh (OBJ); PLY needs its header */
    CHECK_EQ(sidx_mesh_parse_obj(NULL, 0, NULL, &m, NULL), SIDX_OK);
    CHECK_EQ(m.num_triangles, 0);
    sidx_mesh_free(&m);
    m = untouched;
    ASSERT_FAILS(sidx_mesh_parse_ply(NULL, 0, NULL, &m, &err), SIDX_ERR_PARSE, &err);

    sidx_mesh good = tiny_mesh();
    ASSERT_FAILS(sidx_mesh_save_obj(NULL, "/tmp/x.obj", &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_save_obj(&good, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_mesh_save_obj(&good, "/nonexistent/dir/x.obj", &err), SIDX_ERR_IO, &err);

    CHECK(sidx_aabb_is_empty(sidx_mesh_bounds(NULL)));
    CHECK(sidx_aabb_is_empty(sidx_mesh_triangle_bounds(NULL, 0)));
    CHECK(sidx_aabb_is_empty(sidx_mesh_triangle_bounds(&good, 2)));
    CHECK(sidx_aabb_is_empty(sidx_mesh_triangle_bounds(&good, UINT32_MAX)));
    sidx_mesh_free(&good);

    m = untouched;
    ASSERT_FAILS(sidx_scene_make(NULL, 0, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_scene_make("nosuchscene", 0, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_scene_make("icosphere", 0, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_scene_make("icosphere", 11, &m, &err), SIDX_ERR_LIMIT, &err);
    ASSERT_FAILS(sidx_scene_make("grid", UINT32_MAX, &m, &err), SIDX_ERR_LIMIT, &err);
    ASSERT_FAILS(sidx_scene_open(NULL, &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_scene_open("icosphere:2", NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_scene_open("nosuchscene", &m, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_scene_open("icosphere:abc", &m, &err), SIDX_ERR_INVALID_ARG, &err);
    CHECK_MEM(&m, &untouched, sizeof m);
    assert_non_null(sidx_scene_names());
}

/* ---- intersect.h ----------------------------------------------------------- */

static void test_intersect_bad_arguments(void **state)
{
    (void)state;
    sidx_tri_method tm = SIDX_TRI_MOLLER_TRUMBORE;
    sidx_box_method bm = SIDX_BOX_PLAIN;
    CHECK_NULL(sidx_tri_method_name(SIDX_TRI_METHOD_COUNT));
    CHECK_NULL(sidx_tri_method_name((sidx_tri_method)BAD_ENUM));
    CHECK_NULL(sidx_box_method_name(SIDX_BOX_METHOD_COUNT));
    CHECK_EQ(sidx_tri_method_parse(NULL, &tm), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_tri_method_parse("bogus", &tm), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_tri_method_parse("watertight", NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_box_method_parse(NULL, &bm), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_box_method_parse("bogus", &bm), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_box_method_parse("robust", NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(tm, SIDX_TRI_MOLLER_TRUMBORE);
    CHECK_EQ(bm, SIDX_BOX_PLAIN);

    const sidx_ray r = good_ray();
    const sidx_vec3 a = sidx_v3(-1, -1, 0), b = sidx_v3(1, -1, 0), c = sidx_v3(0, 1, 0);
    float t = 42, u = 42, v = 42, tn = 42, tf = 42;
    /* the elementary tests: a NULL ray or output is a miss (0), outputs untouched */
    CHECK_EQ(sidx_intersect_plane(NULL, sidx_v3(0, 0, 1), 0, &t), 0);
    CHECK_EQ(sidx_intersect_triangle((sidx_tri_method)BAD_ENUM, &r, a, b, c, INFINITY, &t, &u, &v), 0);
    CHECK_EQ(sidx_intersect_triangle(SIDX_TRI_WATERTIGHT, NULL, a, b, c, INFINITY, &t, &u, &v), 0);
    CHECK_EQ(sidx_intersect_triangle_watertight(NULL, a, b, c, INFINITY, &t, &u, &v), 0);
    CHECK_EQ(sidx_intersect_triangle_moller(NULL, a, b, c, INFINITY, &t, &u, &v), 0);
    CHECK_EQ(sidx_intersect_triangle_two_step(NULL, a, b, c, INFINITY, &t, &u, &v), 0);
    /* NaN vertices and bound: miss */
    CHECK_EQ(sidx_intersect_triangle_watertight(&r, sidx_v3(NAN, 0, 0), b, c, INFINITY, &t, &u, &v), 0);
    CHECK_EQ(sidx_intersect_triangle_watertight(&r, a, b, c, NAN, &t, &u, &v), 0);
    CHECK(t == 42 && u == 42 && v == 42);
    /* NULL outputs are optional: not written, the answer is still given */
    CHECK_EQ(sidx_intersect_triangle(SIDX_TRI_WATERTIGHT, &r, a, b, c, INFINITY, NULL, NULL, NULL), 1);
    CHECK_EQ(sidx_intersect_triangle_watertight(&r, a, b, c, INFINITY, NULL, NULL, NULL), 1);
    CHECK_EQ(sidx_intersect_triangle_moller(&r, a, b, c, INFINITY, NULL, NULL, NULL), 1);
    CHECK_EQ(sidx_intersect_triangle_two_step(&r, a, b, c, INFINITY, NULL, NULL, NULL), 1);
    CHECK_EQ(sidx_intersect_plane(&r, sidx_v3(0, 0, 1), 0, NULL), 1);

    const sidx_aabb box = {{-1, -1, -1}, {1, 1, 1}};
    CHECK_EQ(sidx_intersect_aabb((sidx_box_method)BAD_ENUM, &r, &box, 0, INFINITY, &tn, &tf), 0);
    CHECK_EQ(sidx_intersect_aabb(SIDX_BOX_ROBUST, NULL, &box, 0, INFINITY, &tn, &tf), 0);
    CHECK_EQ(sidx_intersect_aabb(SIDX_BOX_ROBUST, &r, NULL, 0, INFINITY, &tn, &tf), 0);
    const sidx_sphere sph = {{0, 0, 0}, 1};
    CHECK_EQ(sidx_intersect_sphere(NULL, &sph, 0, INFINITY, &tn, &tf), 0);
    CHECK_EQ(sidx_intersect_sphere(&r, NULL, 0, INFINITY, &tn, &tf), 0);
    const sidx_obb obb = {{0, 0, 0}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {1, 1, 1}};
    CHECK_EQ(sidx_intersect_obb(NULL, &obb, 0, INFINITY, &tn, &tf), 0);
    CHECK_EQ(sidx_intersect_obb(&r, NULL, 0, INFINITY, &tn, &tf), 0);
    sidx_kdop kd;
    const sidx_vec3 pts[3] = {a, b, c};
    CHECK_EQ(sidx_kdop_fit(pts, 3, &kd), SIDX_OK);
    CHECK_EQ(sidx_intersect_kdop(NULL, &kd, 0, INFINITY, &tn, &tf), 0);
    CHECK_EQ(sidx_intersect_kdop(&r, NULL, 0, INFINITY, &tn, &tf), 0);
    CHECK(tn == 42 && tf == 42);
    CHECK_EQ(sidx_intersect_aabb(SIDX_BOX_ROBUST, &r, &box, 0, INFINITY, NULL, NULL), 1);
    CHECK_EQ(sidx_intersect_sphere(&r, &sph, 0, INFINITY, NULL, NULL), 1);
    CHECK_EQ(sidx_intersect_obb(&r, &obb, 0, INFINITY, NULL, NULL), 1);
    CHECK_EQ(sidx_intersect_kdop(&r, &kd, 0, INFINITY, NULL, NULL), 1);
    /* NaN bounds are not checked (sidx_ray_init never makes them): an answer, no crash */
    const int nan_box = sidx_intersect_aabb(SIDX_BOX_ROBUST, &r, &box, NAN, INFINITY, &tn, &tf);
    CHECK(nan_box == 0 || nan_box == 1);
    /* out-of-range slab index: the zero vector */
    const sidx_vec3 z = sidx_kdop_axis(SIDX_KDOP_AXES), z2 = sidx_kdop_axis(-1);
    CHECK(z.x == 0 && z.y == 0 && z.z == 0 && z2.x == 0 && z2.y == 0 && z2.z == 0);

    sidx_aabb ab;
    sidx_sphere sp;
    sidx_obb ob;
    CHECK_EQ(sidx_aabb_fit(NULL, 3, &ab), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aabb_fit(pts, 0, &ab), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aabb_fit(pts, 3, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_sphere_fit(NULL, 3, &sp), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_sphere_fit(pts, 0, &sp), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_sphere_fit(pts, 3, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_obb_fit(NULL, 3, &ob), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_obb_fit(pts, 0, &ob), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_obb_fit(pts, 3, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_kdop_fit(NULL, 3, &kd), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_kdop_fit(pts, 0, &kd), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_kdop_fit(pts, 3, NULL), SIDX_ERR_INVALID_ARG);
    /* NaN points: a documented precondition (finite points), not checked:
     * the fit succeeds with NaN in the result, no crash */
    const sidx_vec3 nanpts[2] = {sidx_v3(0, 0, 0), sidx_v3(NAN, 1, 1)};
    CHECK_EQ(sidx_aabb_fit(nanpts, 2, &ab), SIDX_OK);
    CHECK_EQ(sidx_sphere_fit(nanpts, 2, &sp), SIDX_OK);
    CHECK_EQ(sidx_obb_fit(nanpts, 2, &ob), SIDX_OK);
    CHECK_EQ(sidx_kdop_fit(nanpts, 2, &kd), SIDX_OK);
    CHECK(sidx_sphere_area(NULL) == 0.0f);
    CHECK(sidx_obb_area(NULL) == 0.0f);
}

/* ---- hook.h, sinks.h --------------------------------------------------- */

static void test_hooks_and_sinks_bad_arguments(void **state)
{
    (void)state;
    const sidx_event bad = sidx_event_blank((sidx_event_type)BAD_ENUM);
    CHECK_EQ(bad.type, (sidx_event_type)BAD_ENUM);
    CHECK(strcmp(sidx_event_type_name(SIDX_EV_COUNT), "unknown") == 0);
    CHECK(strcmp(sidx_event_type_name((sidx_event_type)BAD_ENUM), "unknown") == 0);
    CHECK(strcmp(sidx_leaf_reason_name(-1), "unknown") == 0);
    CHECK(strcmp(sidx_leaf_reason_name(BAD_ENUM), "unknown") == 0);
    CHECK(strcmp(sidx_term_reason_name(-1), "unknown") == 0);
    CHECK(strcmp(sidx_term_reason_name(BAD_ENUM), "unknown") == 0);
    const sidx_event ev = sidx_event_blank(SIDX_EV_NOTE);
    sidx_hook_emit(NULL, &ev);                       /* no hook: no-op */
    const sidx_hook nofn = {NULL, NULL, 0};
    sidx_hook_emit(&nofn, &ev);                      /* no callback: no-op */
    sidx_counters cnt;
    sidx_counters_init(&cnt);
    const sidx_hook ch = sidx_counters_hook(&cnt);
    sidx_hook_emit(&ch, NULL);                       /* no event: no-op */
    sidx_hook_emit(&ch, &bad);                       /* unknown type: not counted, no crash */
    uint64_t total = 0;
    for (int i = 0; i < SIDX_EV_COUNT; ++i) total += cnt.n[i];
    CHECK_EQ(total, 0);

    const sidx_ray r = good_ray();
    const sidx_vec3 a = sidx_v3(-1, -1, 0), b = sidx_v3(1, -1, 0), c = sidx_v3(0, 1, 0);
    float t = 42, u, v, tn = 42, tf;
    CHECK_EQ(sidx_trace_triangle(&ch, SIDX_TRI_WATERTIGHT, 0, NULL, a, b, c, INFINITY, &t, &u, &v), 0);
    const sidx_aabb box = {{-1, -1, -1}, {1, 1, 1}};
    CHECK_EQ(sidx_trace_aabb(&ch, SIDX_BOX_ROBUST, 0, NULL, &box, 0, INFINITY, &tn, &tf), 0);
    CHECK_EQ(sidx_trace_aabb(&ch, SIDX_BOX_ROBUST, 0, &r, NULL, 0, INFINITY, &tn, &tf), 0);
    CHECK(t == 42 && tn == 42);
    CHECK_EQ(sidx_trace_triangle(NULL, SIDX_TRI_WATERTIGHT, 0, &r, a, b, c, INFINITY, &t, &u, &v), 1);
    /* an unknown method runs the watertight test (the structures' default) */
    CHECK_EQ(sidx_trace_triangle(NULL, (sidx_tri_method)BAD_ENUM, 0, &r, a, b, c, INFINITY, NULL, NULL, NULL), 1);

    /* sinks: a hook made from a NULL sink does nothing when emitted to */
    sidx_printer_init(NULL, stdout);
    sidx_jsonl_init(NULL, stdout);
    sidx_recorder_init(NULL);
    sidx_recorder_clear(NULL);
    sidx_recorder_free(NULL);
    sidx_counters_init(NULL);
    sidx_counters_print(NULL, stdout);
    sidx_counters_print(&cnt, NULL);
    const sidx_hook hs[5] = {sidx_printer_hook(NULL), sidx_jsonl_hook(NULL), sidx_recorder_hook(NULL),
                             sidx_counters_hook(NULL), sidx_tee_hook(NULL)};
    for (int i = 0; i < 5; ++i) sidx_hook_emit(&hs[i], &ev);
    /* a printer / jsonl writer with no FILE: prints nothing */
    sidx_printer p;
    sidx_printer_init(&p, NULL);
    sidx_hook ph = sidx_printer_hook(&p);
    sidx_hook_emit(&ph, &ev);
    CHECK_EQ(p.lines, 0);
    sidx_jsonl j;
    sidx_jsonl_init(&j, NULL);
    sidx_hook jh = sidx_jsonl_hook(&j);
    sidx_hook_emit(&jh, &ev);
    CHECK_EQ(j.lines, 0);
    /* formatting: NULL event -> -1; NULL buffer with size 0 -> the length, as snprintf */
    char buf[256];
    CHECK_EQ(sidx_event_format(NULL, buf, sizeof buf), -1);
    CHECK_EQ(sidx_event_to_json(NULL, buf, sizeof buf), -1);
    CHECK(sidx_event_format(&ev, NULL, 0) > 0);
    CHECK(sidx_event_to_json(&ev, NULL, 0) > 0);
    CHECK(sidx_event_format(&bad, buf, sizeof buf) > 0);
    CHECK(sidx_event_to_json(&bad, buf, sizeof buf) > 0);
    /* BUILD_LEAF with a count but no prims list (a structure that does not
     * list them): the sinks print and record the count only */
    sidx_event leaf = sidx_event_blank(SIDX_EV_BUILD_LEAF);
    leaf.count = 5;
    leaf.prims = NULL;
    CHECK(sidx_event_format(&leaf, buf, sizeof buf) > 0);
    CHECK(sidx_event_to_json(&leaf, buf, sizeof buf) > 0);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook rh = sidx_recorder_hook(&rec);
    sidx_hook_emit(&rh, &leaf);
    CHECK_EQ(rec.count, 1);
    CHECK_NULL(rec.events[0].prims);
    sidx_recorder_clear(&rec);
    CHECK_EQ(rec.count, 0);
    sidx_recorder_free(&rec);
    sidx_recorder_free(&rec); /* zeroed by the first free: no-op */
    /* a tee claiming more than its 4 hooks forwards to the 4 only */
    sidx_tee tee;
    memset(&tee, 0, sizeof tee);
    tee.n = 1000;
    tee.hooks[0] = ch;
    sidx_hook th = sidx_tee_hook(&tee);
    sidx_hook_emit(&th, &ev);
    CHECK_EQ(cnt.n[SIDX_EV_NOTE], 1);
    tee.n = -3;
    sidx_hook_emit(&th, &ev);
    CHECK_EQ(cnt.n[SIDX_EV_NOTE], 1);
}

/* ---- beam.h ---------------------------------------------------------------- */

static void test_beam_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    sidx_error err;
    sidx_bundle_tree *t = NULL;
    ASSERT_FAILS(sidx_bundle_tree_build(NULL, NULL, &t, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_bundle_tree_build(&m, NULL, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    sidx_mesh broken = m;
    broken.num_vertices = 1;
    ASSERT_FAILS(sidx_bundle_tree_build(&broken, NULL, &t, &err), SIDX_ERR_BAD_GEOMETRY, &err);
    CHECK_EQ(sidx_bundle_tree_build(&m, NULL, &t, NULL), SIDX_OK);
    sidx_bundle_tree_destroy(NULL);
    sidx_bundle_result_free(NULL);

    sidx_bundle_result res;
    memset(&res, 0, sizeof res);
    const sidx_cone good_cone = {{0, 0, -5}, {0, 0, 1}, 0.3f};
    sidx_cone bad_cones[5] = {good_cone, good_cone, good_cone, good_cone, good_cone};
    bad_cones[0].axis = sidx_v3(0, 0, 0);
    bad_cones[1].half_angle = 0.0f;
    bad_cones[2].half_angle = 2.0f;
    bad_cones[3].half_angle = NAN;
    bad_cones[4].apex.x = INFINITY;
    CHECK_EQ(sidx_cone_trace(NULL, &good_cone, 0, 0, NULL, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_cone_trace(t, NULL, 0, 0, NULL, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_cone_trace(t, &good_cone, 0, 0, NULL, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_cone_candidates_brute(NULL, &good_cone, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_cone_candidates_brute(&m, NULL, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_cone_candidates_brute(&m, &good_cone, NULL), SIDX_ERR_INVALID_ARG);
    for (int i = 0; i < 5; ++i) {
        CHECK_EQ(sidx_cone_trace(t, &bad_cones[i], 0, 0, NULL, &res), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_cone_candidates_brute(&m, &bad_cones[i], &res), SIDX_ERR_INVALID_ARG);
    }
    const sidx_beam good_beam = {{0, 0, -5}, {{-0.1f, -0.1f, 1}, {0.1f, -0.1f, 1}, {0.1f, 0.1f, 1}, {-0.1f, 0.1f, 1}}};
    sidx_beam bad_beams[3] = {good_beam, good_beam, good_beam};
    bad_beams[0].dir[2] = bad_beams[0].dir[1]; /* two equal corners */
    bad_beams[1].dir[0] = sidx_v3(0, 0, 0);
    bad_beams[2].dir[3].y = NAN;
    CHECK_EQ(sidx_beam_trace(NULL, &good_beam, 0, 0, NULL, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_beam_trace(t, NULL, 0, 0, NULL, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_beam_trace(t, &good_beam, 0, 0, NULL, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_beam_candidates_brute(NULL, &good_beam, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_beam_candidates_brute(&m, NULL, &res), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_beam_candidates_brute(&m, &good_beam, NULL), SIDX_ERR_INVALID_ARG);
    for (int i = 0; i < 3; ++i) {
        CHECK_EQ(sidx_beam_trace(t, &bad_beams[i], 0, 0, NULL, &res), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_beam_candidates_brute(&m, &bad_beams[i], &res), SIDX_ERR_INVALID_ARG);
    }
    CHECK_NULL(res.cands);
    /* split: NULL input or output is a no-op */
    sidx_cone cs[4];
    sidx_beam bs[4];
    sidx_cone_split(NULL, cs);
    sidx_cone_split(&good_cone, NULL);
    sidx_beam_split(NULL, bs);
    sidx_beam_split(&good_beam, NULL);
    sidx_bundle_tree_destroy(t);
    sidx_mesh_free(&m);
}

/* ---- bsp.h, rayclass.h, instance.h --------------------------------------- */

static int count_piece(const sidx_bsp_piece *p, void *user)
{
    (void)p;
    ++*(int *)user;
    return 0;
}

static void test_structure_extras_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    sidx_accel *bvh = NULL, *bsp = NULL, *rc = NULL;
    CHECK_EQ(sidx_accel_build("bvh", &m, NULL, &bvh, NULL), SIDX_OK);
    sidx_bsp_info bi;
    CHECK_EQ(sidx_bsp_info_get(NULL, &bi), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_bsp_info_get(bvh, &bi), SIDX_ERR_INVALID_ARG);
    int n = 0;
    const sidx_vec3 eye = sidx_v3(0, 0, -5);
    CHECK_EQ(sidx_bsp_paint(NULL, eye, SIDX_BSP_BACK_TO_FRONT, count_piece, &n, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_bsp_paint(bvh, eye, SIDX_BSP_BACK_TO_FRONT, count_piece, &n, NULL), SIDX_ERR_INVALID_ARG);
    if (sidx_accel_is_registered("bsp")) {
        CHECK_EQ(sidx_accel_build("bsp", &m, NULL, &bsp, NULL), SIDX_OK);
        CHECK_EQ(sidx_bsp_info_get(bsp, NULL), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_bsp_paint(bsp, eye, SIDX_BSP_BACK_TO_FRONT, NULL, &n, NULL), SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_bsp_paint(bsp, sidx_v3(NAN, 0, 0), SIDX_BSP_BACK_TO_FRONT, count_piece, &n, NULL),
                         SIDX_ERR_INVALID_ARG);
        CHECK_EQ(sidx_bsp_paint(bsp, eye, (sidx_bsp_order)BAD_ENUM, count_piece, &n, NULL),
                         SIDX_ERR_INVALID_ARG);
        CHECK_EQ(n, 0);
        sidx_accel_destroy(bsp);
    }
    sidx_rayclass_info ri;
    CHECK_EQ(sidx_rayclass_info_get(NULL, &ri), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_rayclass_info_get(bvh, &ri), SIDX_ERR_INVALID_ARG);
    if (sidx_accel_is_registered("rayclass")) {
        CHECK_EQ(sidx_accel_build("rayclass", &m, NULL, &rc, NULL), SIDX_OK);
        CHECK_EQ(sidx_rayclass_info_get(rc, NULL), SIDX_ERR_INVALID_ARG);
        sidx_accel_destroy(rc);
    }

    /* aggregates */
    sidx_error err;
    sidx_accel *agg = (sidx_accel *)&m;
    sidx_instance inst[1] = {{bvh, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}}};
    ASSERT_FAILS(sidx_aggregate_build(NULL, 1, NULL, &agg, &err), SIDX_ERR_INVALID_ARG, &err);
    CHECK_NULL(agg);
    CHECK_EQ(sidx_aggregate_build(inst, 1, NULL, NULL, &err), SIDX_ERR_INVALID_ARG);
    sidx_instance bad = inst[0];
    bad.accel = NULL;
    ASSERT_FAILS(sidx_aggregate_build(&bad, 1, NULL, &agg, &err), SIDX_ERR_INVALID_ARG, &err);
    bad = inst[0];
    bad.xform[5] = NAN;
    ASSERT_FAILS(sidx_aggregate_build(&bad, 1, NULL, &agg, &err), SIDX_ERR_INVALID_ARG, &err);
    bad = inst[0];
    bad.xform[5] = 0.0f; /* singular: y squashed */
    ASSERT_FAILS(sidx_aggregate_build(&bad, 1, NULL, &agg, &err), SIDX_ERR_INVALID_ARG, &err);
    /* n = 0 is allowed (an empty scene), even with NULL instances */
    CHECK_EQ(sidx_aggregate_build(NULL, 0, NULL, &agg, &err), SIDX_OK);
    const sidx_ray r = good_ray();
    sidx_hit h;
    CHECK_EQ(sidx_accel_intersect(agg, &r, NULL, &h), SIDX_OK);
    CHECK_EQ(h.prim, SIDX_NO_HIT);
    sidx_accel_destroy(agg);
    CHECK_EQ(sidx_aggregate_build(inst, 1, NULL, &agg, &err), SIDX_OK);

    CHECK_EQ(sidx_accel_is_aggregate(NULL), 0);
    CHECK_EQ(sidx_accel_is_aggregate(bvh), 0);
    CHECK_EQ(sidx_aggregate_leaf_count(NULL), 0);
    CHECK_EQ(sidx_aggregate_leaf_count(bvh), 1);
    const sidx_accel *leaf = NULL;
    float xf[12];
    CHECK_EQ(sidx_aggregate_leaf(NULL, 0, &leaf, xf), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aggregate_leaf(bvh, 0, &leaf, xf), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aggregate_leaf(agg, 1, &leaf, xf), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aggregate_leaf(agg, UINT32_MAX, &leaf, xf), SIDX_ERR_INVALID_ARG);
    CHECK_NULL(leaf);
    /* both outputs are required */
    CHECK_EQ(sidx_aggregate_leaf(agg, 0, NULL, xf), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aggregate_leaf(agg, 0, &leaf, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aggregate_leaf(agg, 0, &leaf, xf), SIDX_OK);
    CHECK(leaf == bvh);
    sidx_aggregate_info ai;
    CHECK_EQ(sidx_aggregate_info_get(NULL, &ai), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aggregate_info_get(bvh, &ai), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_aggregate_info_get(agg, NULL), SIDX_ERR_INVALID_ARG);
    sidx_accel_destroy(agg);
    sidx_accel_destroy(bvh);
    sidx_mesh_free(&m);
}

/* ---- kdtree.h ------------------------------------------------------------------ */

static void test_kdtree_view_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    sidx_accel *kd = NULL, *bvh = NULL;
    CHECK_EQ(sidx_accel_build("kdtree", &m, NULL, &kd, NULL), SIDX_OK);
    CHECK_EQ(sidx_accel_build("bvh", &m, NULL, &bvh, NULL), SIDX_OK);
    const sidx_kd_node *nodes = (const sidx_kd_node *)&m;
    const uint32_t *refs = (const uint32_t *)&m;
    uint32_t count = 77;
    sidx_error err;
    ASSERT_FAILS(sidx_kdtree_nodes(NULL, &nodes, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_kdtree_nodes(bvh, &nodes, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_kdtree_nodes(kd, NULL, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_kdtree_nodes(kd, &nodes, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_kdtree_refs(NULL, &refs, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_kdtree_refs(bvh, &refs, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_kdtree_refs(kd, NULL, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_kdtree_refs(kd, &refs, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    /* outputs untouched on failure */
    CHECK(nodes == (const sidx_kd_node *)&m && refs == (const uint32_t *)&m && count == 77);
    CHECK_EQ(sidx_kdtree_nodes(kd, &nodes, &count, NULL), SIDX_OK);
    CHECK(count > 0);
    sidx_accel_destroy(kd);
    sidx_accel_destroy(bvh);
    sidx_mesh_free(&m);
}

/* ---- octree.h ------------------------------------------------------------------ */

static void test_octree_view_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    sidx_accel *oct = NULL, *bvh = NULL;
    CHECK_EQ(sidx_accel_build("octree", &m, NULL, &oct, NULL), SIDX_OK);
    CHECK_EQ(sidx_accel_build("bvh", &m, NULL, &bvh, NULL), SIDX_OK);
    const sidx_oct_node *nodes = (const sidx_oct_node *)&m;
    const uint32_t *refs = (const uint32_t *)&m;
    uint32_t count = 77;
    sidx_aabb box = {{1, 2, 3}, {4, 5, 6}};
    int axes = 77;
    sidx_error err;
    ASSERT_FAILS(sidx_octree_nodes(NULL, &nodes, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_nodes(bvh, &nodes, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_nodes(oct, NULL, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_nodes(oct, &nodes, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_refs(NULL, &refs, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_refs(bvh, &refs, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_refs(oct, NULL, &count, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_refs(oct, &refs, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_info(NULL, &box, &axes, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_info(bvh, &box, &axes, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_info(oct, NULL, &axes, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_octree_info(oct, &box, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    /* outputs untouched on failure */
    CHECK(nodes == (const sidx_oct_node *)&m && refs == (const uint32_t *)&m && count == 77 && axes == 77 &&
          box.min.x == 1.0f && box.max.z == 6.0f);
    CHECK_EQ(sidx_octree_nodes(oct, &nodes, &count, NULL), SIDX_OK);
    CHECK(count > 0);
    CHECK_EQ(sidx_octree_info(oct, &box, &axes, NULL), SIDX_OK);
    CHECK(axes == 3);
    sidx_accel_destroy(oct);
    sidx_accel_destroy(bvh);
    sidx_mesh_free(&m);
}

/* ---- lightbuffer.h ---------------------------------------------------------- */

static void test_lightbuffer_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    sidx_error err;
    sidx_lightbuffer *lb = NULL;
    const sidx_vec3 light = sidx_v3(0, 5, -5);
    ASSERT_FAILS(sidx_lightbuffer_build(NULL, light, 8, 0, NULL, &lb, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_lightbuffer_build(&m, light, 8, 0, NULL, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_lightbuffer_build(&m, sidx_v3(NAN, 0, 0), 8, 0, NULL, &lb, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_lightbuffer_build(&m, light, 1025, 0, NULL, &lb, &err), SIDX_ERR_INVALID_ARG, &err);
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.tri = (sidx_tri_method)BAD_ENUM;
    ASSERT_FAILS(sidx_lightbuffer_build(&m, light, 8, 0, &bo, &lb, &err), SIDX_ERR_INVALID_ARG, &err);
    sidx_mesh broken = m;
    broken.num_vertices = 1;
    ASSERT_FAILS(sidx_lightbuffer_build(&broken, light, 8, 0, NULL, &lb, &err), SIDX_ERR_BAD_GEOMETRY, &err);
    sidx_lightbuffer_destroy(NULL);
    CHECK_EQ(sidx_lightbuffer_build(&m, light, 8, 0, NULL, &lb, &err), SIDX_OK);

    sidx_lightbuffer_cache c;
    CHECK_EQ(sidx_lightbuffer_cache_init(NULL, &c), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_cache_init(lb, NULL), SIDX_ERR_INVALID_ARG);
    sidx_lightbuffer_cache_free(NULL);
    sidx_ray sr;
    CHECK_EQ(sidx_lightbuffer_shadow_ray(NULL, sidx_v3(0, 0, 0), 0, 1, &sr), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_shadow_ray(lb, sidx_v3(0, 0, 0), 0, 1, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_shadow_ray(lb, light, 0, 1, &sr), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_shadow_ray(lb, sidx_v3(0, NAN, 0), 0, 1, &sr), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_shadow_ray(lb, sidx_v3(0, 0, 0), NAN, 1, &sr), SIDX_ERR_INVALID_ARG);
    int occ = 7;
    CHECK_EQ(sidx_lightbuffer_occluded(NULL, sidx_v3(0, 0, 0), 0, 1, NULL, NULL, &occ), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_occluded(lb, sidx_v3(0, 0, 0), 0, 1, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_occluded(lb, light, 0, 1, NULL, NULL, &occ), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_occluded(lb, sidx_v3(INFINITY, 0, 0), 0, 1, NULL, NULL, &occ),
                     SIDX_ERR_INVALID_ARG);
    /* a cache made for another (smaller) light buffer is refused, not overrun */
    sidx_lightbuffer *small = NULL;
    CHECK_EQ(sidx_lightbuffer_build(&m, light, 2, 0, NULL, &small, &err), SIDX_OK);
    CHECK_EQ(sidx_lightbuffer_cache_init(small, &c), SIDX_OK);
    CHECK_EQ(sidx_lightbuffer_occluded(lb, sidx_v3(0, 0, 0), 0, 1, &c, NULL, &occ), SIDX_ERR_INVALID_ARG);
    sidx_lightbuffer_cache_free(&c);
    sidx_lightbuffer_destroy(small);
    sidx_lightbuffer_stats st;
    CHECK_EQ(sidx_lightbuffer_stats_get(NULL, &st), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_lightbuffer_stats_get(lb, NULL), SIDX_ERR_INVALID_ARG);
    sidx_lightbuffer_destroy(lb);
    sidx_mesh_free(&m);
}

/* ---- packet.h, parallel.h -------------------------------------------------- */

static void test_packets_and_parallel_bad_arguments(void **state)
{
    (void)state;
    sidx_mesh m = tiny_mesh();
    sidx_accel *a = NULL;
    CHECK_EQ(sidx_accel_build("bvh", &m, NULL, &a, NULL), SIDX_OK);
    sidx_ray rays[SIDX_PACKET_MAX + 1];
    for (unsigned i = 0; i <= SIDX_PACKET_MAX; ++i) rays[i] = good_ray();
    sidx_hit hits[SIDX_PACKET_MAX + 1];
    uint8_t occ[SIDX_PACKET_MAX + 1];
    CHECK_EQ(sidx_packet_intersect(NULL, rays, 4, 2, NULL, hits, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_packet_intersect(a, NULL, 4, 2, NULL, hits, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_packet_intersect(a, rays, 4, 2, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_packet_intersect(a, rays, SIDX_PACKET_MAX + 1, 0, NULL, hits, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_packet_occluded(NULL, rays, 4, 2, NULL, occ, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_packet_occluded(a, NULL, 4, 2, NULL, occ, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_packet_occluded(a, rays, 4, 2, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_packet_occluded(a, rays, SIDX_PACKET_MAX + 1, 0, NULL, occ, NULL), SIDX_ERR_INVALID_ARG);
    /* an unknown mode is PLAIN */
    sidx_packet_options po = {(sidx_packet_mode)BAD_ENUM, 0, 0};
    CHECK_EQ(sidx_packet_intersect(a, rays, 4, 2, &po, hits, NULL), SIDX_OK);
    CHECK_EQ(hits[3].prim, 0);
    CHECK_EQ(sidx_packet_occluded(a, rays, 4, 2, &po, occ, NULL), SIDX_OK);
    CHECK_EQ(occ[3], 1);
    /* FRUSTUM with a w that does not tile n: plain packets, same answers */
    po.mode = SIDX_PACKET_FRUSTUM;
    CHECK_EQ(sidx_packet_intersect(a, rays, 6, 4, &po, hits, NULL), SIDX_OK);
    CHECK_EQ(hits[0].prim, 0);
    CHECK_EQ(sidx_packet_intersect(a, rays, 0, 0, NULL, hits, NULL), SIDX_OK);
    CHECK_EQ(sidx_trace_tiles(NULL, rays, 2, 2, 4, NULL, hits, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_trace_tiles(a, NULL, 2, 2, 4, NULL, hits, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_trace_tiles(a, rays, 2, 2, 4, NULL, NULL, NULL), SIDX_ERR_INVALID_ARG);
    /* tile: 1..8 (a tile is one packet of at most 64 rays) */
    CHECK_EQ(sidx_trace_tiles(a, rays, 2, 2, 3, NULL, hits, NULL), SIDX_OK);
    CHECK_EQ(sidx_trace_tiles(a, rays, 2, 2, 0, NULL, hits, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_trace_tiles(a, rays, 2, 2, 9, NULL, hits, NULL), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_trace_tiles(a, rays, 2, 2, 65536, NULL, hits, NULL), SIDX_ERR_INVALID_ARG); /* 65536^2 wraps to 0 */
    CHECK_EQ(sidx_trace_tiles(a, rays, 0, 0, 4, NULL, hits, NULL), SIDX_OK);

    CHECK(sidx_hardware_threads() >= 1);
    CHECK_EQ(sidx_trace_parallel(NULL, rays, 4, NULL, hits, 2), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_trace_parallel(a, NULL, 4, NULL, hits, 2), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_trace_parallel(a, rays, 4, NULL, NULL, 2), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_trace_parallel(a, NULL, 0, NULL, NULL, 2), SIDX_OK);
    CHECK_EQ(sidx_occluded_parallel(NULL, rays, 4, NULL, occ, 2), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_occluded_parallel(a, NULL, 4, NULL, occ, 2), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_occluded_parallel(a, rays, 4, NULL, NULL, 2), SIDX_ERR_INVALID_ARG);
    CHECK_EQ(sidx_occluded_parallel(a, NULL, 0, NULL, NULL, 2), SIDX_OK);
    /* absurd thread counts are clamped, not obeyed */
    CHECK_EQ(sidx_trace_parallel(a, rays, 4, NULL, hits, UINT32_MAX), SIDX_OK);
    CHECK_EQ(hits[3].prim, 0);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* ---- viz.h ------------------------------------------------------------------- */

static void test_viz_bad_arguments(void **state)
{
    (void)state;
    sidx_error err;
    sidx_viz_tree t;
    memset(&t, 0, sizeof t);
    ASSERT_FAILS(sidx_viz_tree_from_events(NULL, 3, &t, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_viz_tree_from_events(NULL, 0, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_viz_tree_from_events(NULL, 0, &t, &err), SIDX_ERR_UNSUPPORTED, &err);
    sidx_viz_tree_free(NULL);
    CHECK_EQ(sidx_viz_tree_find(NULL, 0), SIDX_VIZ_NONE);
    sidx_viz_tree_apply_ray(NULL, NULL, 0);
    uint32_t nodes = 7;
    uint64_t prims = 7;
    sidx_viz_tree_subtree(NULL, 0, &nodes, &prims);
    CHECK_EQ(nodes, 0);
    CHECK_EQ(prims, 0);

    /* a real tree: out-of-range node index, NULL outputs */
    sidx_mesh m = tiny_mesh();
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook hk = sidx_recorder_hook(&rec);
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.hook = &hk;
    bo.leaf_size = 1;
    sidx_accel *a = NULL;
    CHECK_EQ(sidx_accel_build("bvh", &m, &bo, &a, NULL), SIDX_OK);
    CHECK_EQ(sidx_viz_tree_from_events(rec.events, rec.count, &t, &err), SIDX_OK);
    sidx_viz_tree_subtree(&t, (uint32_t)t.count, &nodes, &prims);
    CHECK_EQ(nodes, 0);
    sidx_viz_tree_subtree(&t, 0, NULL, NULL);
    sidx_viz_tree_apply_ray(&t, NULL, 5);
    CHECK_EQ(sidx_viz_tree_find(&t, UINT32_MAX - 5), SIDX_VIZ_NONE);
    sidx_viz_tree_free(&t);
    sidx_viz_tree_free(&t); /* zeroed by the first free: no-op */

    ASSERT_FAILS(sidx_dot_write(NULL, "bvh", NULL, "-", &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_dot_write(&m, NULL, NULL, "-", &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_dot_write(&m, "bvh", NULL, NULL, &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_dot_write(&m, "no-such-tree", NULL, "-", &err), SIDX_ERR_UNKNOWN_ACCEL, &err);
    ASSERT_FAILS(sidx_dot_write(&m, "bvh", NULL, "/tmp/x.unknownext", &err), SIDX_ERR_INVALID_ARG, &err);
    sidx_dot_options dopt;
    memset(&dopt, 0, sizeof dopt);
    dopt.has_ray = 1;
    dopt.ray_org = sidx_v3(0, 0, -5);
    dopt.ray_dir = sidx_v3(0, 0, 0); /* zero direction */
    ASSERT_FAILS(sidx_dot_write(&m, "bvh", &dopt, "-", &err), SIDX_ERR_INVALID_ARG, &err);
    ASSERT_FAILS(sidx_dot_write_events(NULL, 3, NULL, 0, NULL, "-", &err), SIDX_ERR_INVALID_ARG, &err);
    /* trav NULL: no ray, whatever ntrav says */
    char dotpath[] = "/tmp/sidx-args-XXXXXX";
    const int fd = mkstemp(dotpath);
    CHECK(fd >= 0);
    close(fd);
    char dotfile[64];
    snprintf(dotfile, sizeof dotfile, "%s.dot", dotpath);
#if SIDX_HAVE_GRAPHVIZ
    CHECK_EQ(sidx_dot_write_events(rec.events, rec.count, NULL, 2, NULL, dotfile, &err), SIDX_OK);
#else
    /* built without Graphviz: the documented answer, with a message naming the package */
    CHECK_EQ(sidx_dot_write_events(rec.events, rec.count, NULL, 2, NULL, dotfile, &err), SIDX_ERR_UNSUPPORTED);
    CHECK(strstr(err.message, "Graphviz") != NULL);
#endif
    unlink(dotfile);
    unlink(dotpath);
    ASSERT_FAILS(sidx_dot_write_events(rec.events, rec.count, NULL, 0, NULL, NULL, &err), SIDX_ERR_INVALID_ARG,
                 &err);

    sidx_vec3 o, d;
    CHECK(sidx_viz_parse_ray(NULL, &o, &d) != 0);
    CHECK(sidx_viz_parse_ray("1,2,3,4,5,6", NULL, &d) != 0);
    CHECK(sidx_viz_parse_ray("1,2,3,4,5,6", &o, NULL) != 0);
    CHECK(sidx_viz_parse_ray("1,2,3", &o, &d) != 0);
    CHECK(sidx_viz_parse_ray("1,2,3,nan,5,6", &o, &d) != 0);
    CHECK(sidx_viz_parse_ray("1,2,3,0,0,0", &o, &d) != 0);
    CHECK(sidx_viz_parse_ray("1,2,3,4,5,6,7", &o, &d) != 0);
    CHECK_EQ(sidx_viz_parse_ray("1,2,3,4,5,6", &o, &d), 0);

    sidx_build_options knobs = {0};
    char kmsg[128];
    CHECK_EQ(sidx_viz_build_knob(NULL, "4", &knobs, kmsg, sizeof kmsg), -1);
    CHECK_EQ(sidx_viz_build_knob("--bins", "4", NULL, kmsg, sizeof kmsg), -1);
    CHECK_EQ(sidx_viz_build_knob("--bins", NULL, &knobs, NULL, 0), -1);
    CHECK_EQ(sidx_viz_build_knob("--bins", "4", &knobs, NULL, 0), 2);
    CHECK_EQ(sidx_viz_build_knob("--no-such-knob", "4", &knobs, kmsg, sizeof kmsg), 0);
    CHECK(sidx_viz_build_knobs_help() != NULL);

    sidx_recorder_free(&rec);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_status_version_ray, teardown),
        cmocka_unit_test_teardown(test_accel_registry_and_names, teardown),
        cmocka_unit_test_teardown(test_accel_build_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_accel_queries_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_accel_empty_mesh, teardown),
        cmocka_unit_test_teardown(test_mesh_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_intersect_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_hooks_and_sinks_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_beam_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_structure_extras_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_kdtree_view_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_octree_view_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_lightbuffer_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_packets_and_parallel_bad_arguments, teardown),
        cmocka_unit_test_teardown(test_viz_bad_arguments, teardown),
    };
    return cmocka_run_group_tests_name("NULL and invalid arguments", tests, NULL, NULL);
}
