/* test_limits.c — what the structures do at their limits.
 *
 *  1. A pathological scene that drives every registered tree to its depth
 *     limit: triangles in a geometric sequence (sizes and positions 2^-i)
 *     nested into one corner, so every middle split, centre split or
 *     refinement peels off one triangle and the next level looks like the
 *     last.  Each structure must build (or refuse with SIDX_ERR_LIMIT and a
 *     message), stay within a bounded depth even when asked for an
 *     unbounded one (opt.max_depth = UINT32_MAX), and answer every
 *     traversal variant exactly like the double-precision reference — so
 *     the fixed traversal stacks, sized from the depth limit, hold (under
 *     SAN=1 an overflow of one is an ASan report; a recursion without bound
 *     a stack overflow).
 *  2. Counts past the 32-bit indices: a mesh claiming more triangles than
 *     3·tri + k can address is refused with SIDX_ERR_LIMIT before any array
 *     is read or allocated.
 *  3. Loaders given headers with huge counts and a tiny body fail at once
 *     (SIDX_ERR_PARSE or SIDX_ERR_LIMIT) without allocating what the header
 *     claims — checked in a child process under a 512 MB address-space
 *     limit (not under ASan or valgrind, which reserve far more). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include "common/testkit.h"

/* Every tree's depth cap (BVH_DEPTH_LIMIT, KD_MAX_DEPTH, BSP_MAX_DEPTH are
 * 64; octree 24, grid2 6, irregular grid 16, rayclass 24). */
#define DEPTH_CAP 64u
/* Triangle sizes down to 2^-56: the watertight test multiplies two
 * coordinates, and below ~2^-63 those products leave the normal floats —
 * every float test, brute force included, then misses what the double
 * reference hits.  That float limit, not a structure, bounds the cluster. */
#define NESTED 56
#define FAN 24

/* Two pathological parts:
 *  - the cluster: triangle i a right triangle of legs s = 2^-(i+1) at
 *    (s, s, s) in the plane z = s, and a unit one at (1, 1, 1): every
 *    middle split (BVH, kd-tree), centre split (octree) or refinement
 *    (nested grids) peels off one triangle, so the tree is as deep as the
 *    cluster is long.  Seen along z the triangles are disjoint.
 *  - the fan: FAN triangles sharing the vertex (-1, -1, -1): every cell
 *    holding that vertex holds all of them, no split separates them, so
 *    spatial subdivisions (kd-trees, octree, grids) split until their
 *    depth cap. */
static void nested_scene(sidx_mesh *m)
{
    float xyz[(NESTED + 1 + FAN) * 9];
    uint32_t idx[(NESTED + 1 + FAN) * 3];
    int t = 0;
    for (int i = 0; i <= NESTED; ++i, ++t) {
        const float s = i == NESTED ? 1.0f : ldexpf(1.0f, -i - 1);
        const float v[9] = {s, s, s, 1.5f * s, s, s, s, 1.5f * s, s};
        memcpy(&xyz[9 * t], v, sizeof v);
    }
    for (int k = 0; k < FAN; ++k, ++t) {
        const double a0 = 2.0 * M_PI * k / FAN, a1 = 2.0 * M_PI * (k + 1) / FAN;
        const float v[9] = {-1, -1, -1, (float)(-1 + 0.5 * cos(a0)), (float)(-1 + 0.5 * sin(a0)), -1.2f - 0.01f * k,
                            (float)(-1 + 0.5 * cos(a1)), (float)(-1 + 0.5 * sin(a1)), -1.2f - 0.01f * (k + 1)};
        memcpy(&xyz[9 * t], v, sizeof v);
    }
    for (int i = 0; i < 3 * t; ++i) idx[i] = (uint32_t)i;
    assert_int_equal(sidx_mesh_from_arrays(m, xyz, (uint32_t)(3 * t), idx, (uint32_t)t, NULL), SIDX_OK);
}

/* Rays at the scale of their target (origins a few triangle sizes away,
 * so float resolution is never the issue): along ±z through every cluster
 * centroid and diagonally into the corner, random rays into the cluster at
 * every scale, and rays at random points of the fan.
 *
 * A random ray at a large scale also passes the cluster's smallest
 * triangles, from 2^50 times their size or more.  There even the double
 * reference cannot see them: o − v loses the triangle's extent, the three
 * edge functions are rounding noise, and when the noise happens to agree
 * in sign the reference "hits" a triangle the ray misses by 0.2 (seen when
 * clang, which evaluates a call's arguments left to right, drew these rays
 * in another order: prim 54, of size 2^-55, "hit" at t 0.63 by a ray from
 * 0.46 away).  The draws are therefore one per statement, in a fixed
 * order, so every compiler tests the same rays, none of which falls in
 * that trap. */
static size_t nested_rays(const sidx_mesh *m, tk_rayrec *out, size_t max)
{
    size_t n = 0;
    for (uint32_t t = 0; t <= NESTED && n + 3 <= max; ++t) {
        const sidx_vec3 a = sidx_mesh_vertex(m, t, 0), b = sidx_mesh_vertex(m, t, 1), c = sidx_mesh_vertex(m, t, 2);
        const sidx_vec3 g = sidx_v3_scale(sidx_v3_add(a, sidx_v3_add(b, c)), 1.0f / 3.0f);
        const float s = a.x;
        out[n++] = tk_rayrec_make(sidx_v3(g.x, g.y, g.z - s), sidx_v3(0, 0, s), 0.0f, INFINITY);
        out[n++] = tk_rayrec_make(sidx_v3(g.x, g.y, g.z + 0.25f * s), sidx_v3(0, 0, -s), 0.0f, INFINITY);
        out[n++] = tk_rayrec_make(sidx_v3_sub(g, sidx_v3(s, s, s)), sidx_v3(s, s, s), 0.0f, INFINITY);
    }
    tk_rng rng;
    tk_rng_seed(&rng, 11);
    for (int k = 0; k < 200 && n < max; ++k) {
        const float s = ldexpf(1.0f, -1 - (int)tk_rng_below(&rng, NESTED));
        /* one draw per statement, z first: the order gcc evaluated the
         * arguments in (C leaves it open; clang drew x first and got
         * other rays) */
        const float tz = (float)tk_rng_range(&rng, 0.9, 1.1), ty = (float)tk_rng_range(&rng, 0.9, 1.6),
                    tx = (float)tk_rng_range(&rng, 0.9, 1.6);
        const sidx_vec3 target = sidx_v3(s * tx, s * ty, s * tz);
        const sidx_vec3 o = sidx_v3_add(target, sidx_v3_scale(tk_rng_sphere(&rng), 3.0f * s));
        out[n++] = tk_rayrec_make(o, sidx_v3_sub(target, o), 0.0f, INFINITY);
    }
    while (n < max) {
        const uint32_t t = NESTED + 1 + tk_rng_below(&rng, FAN);
        const double u = tk_rng_unit(&rng), v = tk_rng_unit(&rng) * (1.0 - u);
        const sidx_vec3 a = sidx_mesh_vertex(m, t, 0), b = sidx_mesh_vertex(m, t, 1), c = sidx_mesh_vertex(m, t, 2);
        const sidx_vec3 p = sidx_v3_add(a, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(b, a), (float)u),
                                                       sidx_v3_scale(sidx_v3_sub(c, a), (float)v)));
        const sidx_vec3 o = sidx_v3_add(p, tk_rng_sphere(&rng));
        out[n++] = tk_rayrec_make(o, sidx_v3_sub(p, o), 0.0f, INFINITY);
    }
    return n;
}

static void check_structure(const char *name, const sidx_mesh *m, const tk_rayrec *rays, const sidx_hit *ref,
                            size_t n, uint32_t max_depth)
{
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.leaf_size = 1;
    opt.max_depth = max_depth;
    sidx_accel *a = NULL;
    sidx_error err = {SIDX_OK, ""};
    const sidx_status s = sidx_accel_build(name, m, &opt, &a, &err);
    if (s != SIDX_OK) {
        print_message("%s: refused: %s\n", name, err.message);
        assert_int_equal(s, SIDX_ERR_LIMIT);
        assert_true(err.message[0] != '\0');
        assert_null(a);
        return;
    }
    sidx_accel_stats st;
    assert_int_equal(sidx_accel_stats_get(a, &st), SIDX_OK);
    if (st.max_depth > DEPTH_CAP) print_error("%s: depth %u above %u\n", name, st.max_depth, DEPTH_CAP);
    assert_true(st.max_depth <= DEPTH_CAP);
    uint64_t errors = 0;
    for (int v = 0; v < SIDX_TRAVERSE_COUNT; ++v) {
        const sidx_query q = {0, (sidx_traversal)v, NULL, 0};
        for (size_t i = 0; i < n; ++i) {
            sidx_ray r;
            assert_int_equal(tk_ray_from(&rays[i], &r), SIDX_OK);
            sidx_hit h;
            int occ = -1;
            sidx_accel_intersect(a, &r, &q, &h);
            sidx_accel_occluded(a, &r, &q, &occ);
            if (!tk_hits_agree(&ref[i], &h) || occ != (ref[i].prim != SIDX_NO_HIT)) {
                if (errors++ < 3)
                    print_error("%s (%s) ray %zu: prim %u t %g, reference prim %u t %g, occluded %d\n", name,
                                sidx_traversal_name((sidx_traversal)v), i, h.prim, (double)h.t, ref[i].prim,
                                (double)ref[i].t, occ);
            }
        }
    }
    print_message("%-15s max_depth %-10u depth %2u, nodes %6u, errors %llu\n", name, max_depth, st.max_depth,
                  st.nodes, (unsigned long long)errors);
    assert_int_equal(errors, 0);
    sidx_accel_destroy(a);
}

static void test_every_tree_at_its_depth_limit(void **state)
{
    (void)state;
    sidx_mesh m;
    nested_scene(&m);
    enum { NRAYS = 3 * (NESTED + 1) + 200 + 200 };
    static tk_rayrec rays[NRAYS];
    static sidx_hit ref[NRAYS];
    const size_t n = nested_rays(&m, rays, NRAYS);
    size_t hits = 0;
    for (size_t i = 0; i < n; ++i) {
        tk_ref_intersect(&m, &rays[i], &ref[i]);
        hits += ref[i].prim != SIDX_NO_HIT;
    }
    assert_true(hits >= 2 * (NESTED + 1) + 200); /* every centroid and fan ray hits */
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s) {
        const char *name = sidx_accel_registered_name(s);
        check_structure(name, &m, rays, ref, n, 0);
        /* "unbounded": clamped to the cap.  Not for rayclass: its cap (24
         * levels of 5D bisection) is honoured but makes ~17M nodes here,
         * a minute of build — too slow for a unit test. */
        if (strcmp(name, "rayclass") != 0) check_structure(name, &m, rays, ref, n, UINT32_MAX);
        check_structure(name, &m, rays, ref, n, 3);          /* shallow cap: forced big leaves */
    }
    /* the scene is pathological: the middle-split BVH goes deep (one level
     * per cluster triangle, until the float centroids run out), the
     * kd-trees asked for unbounded depth stop at exactly their cap */
    const char *deep[] = {"bvh-middle", "kdtree-middle", "kdtree-median"};
    const uint32_t ask[] = {0, UINT32_MAX, UINT32_MAX}, expect[] = {32, 64, 64};
    for (int i = 0; i < 3; ++i) {
        sidx_accel *a = NULL;
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.leaf_size = 1;
        opt.max_depth = ask[i];
        if (!sidx_accel_is_registered(deep[i])) continue;
        assert_int_equal(sidx_accel_build(deep[i], &m, &opt, &a, NULL), SIDX_OK);
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        print_message("%s: depth %u\n", deep[i], st.max_depth);
        assert_true(st.max_depth >= expect[i]);
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

/* ---- 32-bit indices ------------------------------------------------------------ */

static void test_counts_past_32bit_indices_are_refused(void **state)
{
    (void)state;
    /* arrays for one triangle; the struct claims 2^32/3 + 1: reading them
     * would be out of bounds (ASan), indexing 3·tri would wrap */
    sidx_vec3 pos[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    uint32_t idx[3] = {0, 1, 2};
    sidx_mesh m = {pos, idx, 3, UINT32_MAX / 3u + 1u};
    sidx_error err = {SIDX_OK, ""};
    assert_int_equal(sidx_mesh_validate(&m, &err), SIDX_ERR_LIMIT);
    assert_non_null(strstr(err.message, "triangles"));
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s) {
        sidx_accel *a = NULL;
        err.message[0] = '\0';
        assert_int_equal(sidx_accel_build(sidx_accel_registered_name(s), &m, NULL, &a, &err), SIDX_ERR_LIMIT);
        assert_null(a);
        assert_true(err.message[0] != '\0');
    }
    m.num_triangles = UINT32_MAX; /* also SIDX_NO_HIT: can never be a triangle count */
    assert_int_equal(sidx_mesh_validate(&m, NULL), SIDX_ERR_LIMIT);
    sidx_mesh out;
    memset(&out, 0, sizeof out);
    assert_int_equal(sidx_mesh_from_arrays(&out, sidx_v3_array(&pos[0]), 3, idx, UINT32_MAX / 3u + 1u, &err), SIDX_ERR_LIMIT);
    assert_null(out.positions);
    /* the true count passes */
    m.num_triangles = 1;
    assert_int_equal(sidx_mesh_validate(&m, NULL), SIDX_OK);
}

/* ---- loaders ---------------------------------------------------------------------- */

typedef struct {
    const char *what;
    const char *data;
    int ply;
} bad_file;

static const bad_file huge_headers[] = {
    {"ascii vertex count 2^32-1",
     "ply\nformat ascii 1.0\nelement vertex 4294967295\nproperty float x\nproperty float y\nproperty float z\n"
     "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
     1},
    {"ascii face count 2^32-1",
     "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
     "element face 4294967295\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
     1},
    {"ascii vertex count 2^40",
     "ply\nformat ascii 1.0\nelement vertex 1099511627776\nproperty float x\nproperty float y\nproperty float z\n"
     "end_header\n0 0 0\n",
     1},
    {"binary face count 2^31",
     "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
     "element face 2147483648\nproperty list uchar int vertex_indices\nend_header\n",
     1},
    {"binary vertex count 2^32-1",
     "ply\nformat binary_little_endian 1.0\nelement vertex 4294967295\nproperty double x\nproperty double y\n"
     "property double z\nend_header\n",
     1},
    {"binary list of 255 indices per face, 2^31 faces",
     "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
     "element face 2147483647\nproperty list uchar uint vertex_indices\nend_header\n",
     1},
    {"OBJ face with index 2^32", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967296\n", 0},
    {"OBJ face with index 2^64", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 18446744073709551616\n", 0},
};

static sidx_status parse_bad(const bad_file *f, sidx_error *err)
{
    sidx_mesh m;
    const size_t len = strlen(f->data);
    return f->ply ? sidx_mesh_parse_ply(f->data, len, f->what, &m, err)
                  : sidx_mesh_parse_obj(f->data, len, f->what, &m, err);
}

static void test_loaders_refuse_huge_counts_without_allocating(void **state)
{
    (void)state;
    const int limit_memory = !TK_UNDER_ASAN && !tk_fast_tests();
    for (size_t i = 0; i < sizeof huge_headers / sizeof huge_headers[0]; ++i) {
        const bad_file *f = &huge_headers[i];
        sidx_error err = {SIDX_OK, ""};
        const sidx_status s = parse_bad(f, &err);
        print_message("%-48s -> %s: %s\n", f->what, sidx_status_str(s), err.message);
        assert_true(s == SIDX_ERR_PARSE || s == SIDX_ERR_LIMIT || s == SIDX_ERR_BAD_GEOMETRY);
        assert_true(err.message[0] != '\0');
        if (!limit_memory) continue;
        /* again in a child that cannot map more than 512 MB: an attempt to
         * allocate what the header claims would give NOMEM there */
        fflush(NULL);
        const pid_t pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            const struct rlimit rl = {512u << 20, 512u << 20};
            if (setrlimit(RLIMIT_AS, &rl) != 0) _exit(100);
            _exit((int)parse_bad(f, NULL));
        }
        int status = 0;
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFEXITED(status));
        assert_int_equal(WEXITSTATUS(status), (int)s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_tree_at_its_depth_limit),
        cmocka_unit_test(test_counts_past_32bit_indices_are_refused),
        cmocka_unit_test(test_loaders_refuse_huge_counts_without_allocating),
    };
    return cmocka_run_group_tests_name("limits", tests, NULL, NULL);
}
