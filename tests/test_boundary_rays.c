/* test_boundary_rays.c — rays lying on the scene box's boundary planes,
 * through every registered structure, against brute force.
 *
 * The family: rays along each of the box's 12 edges and in each of its 6
 * face planes (axis-parallel and diagonal in the face), starting outside,
 * on a corner, inside and at tiny coordinates, leaning in or out by 0,
 * 2^-100, FLT_MIN or 2^-24 of their length, with direction lengths 2^-20,
 * 1 and 2^28; over the fuzz cube [-1, 1]^3 (exact coordinates) and a box
 * at [0.1, 0.7]^3 (coordinates that are not exact in binary).
 *
 *  - every such ray whose direction keeps all its components in the
 *    triangle test's shear must get brute force's answer: a structure's box
 *    tests take a ray on a box plane as in the box (a ±0 component's
 *    0 · inf = NaN slab is ignored, not propagated), and a grid's walk
 *    starts and ends in the cells that plane bounds;
 *  - a ray with a component below FLT_MIN of the largest (the shear
 *    underflows: docs/errors.md) gets the fuzz oracles' one-way check
 *    (tests/fuzz/fuzz_oracle.h); the ray of
 *    tests/fuzz/regress/rays/edge-lean-shear-underflow.bin is one.  So
 *    does a ray with a denormal component, which the oracles trace but do
 *    not compare. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include "sidx/sidx.h"
#include "common/testkit.h"
#include "fuzz/fuzz_oracle.h"

#define MAX_ACCELS 64

typedef struct family {
    sidx_accel *acc[MAX_ACCELS]; /* acc[0] is brute force */
    size_t n;
    long compared, one_way, failed;
    unsigned stride, k; /* trace every stride-th ray of the family (SIDX_FAST_TESTS: valgrind) */
} family;

/* A closed cube [lo, hi]^3 of 12 triangles and one triangle inside it (the
 * scene of tests/fuzz/fuzz_rays.c for lo = -1, hi = 1). */
static void box_scene(sidx_mesh *m, float lo, float hi)
{
    const float mid = 0.5f * (lo + hi), q = 0.25f * (hi - lo);
    const float xyz[] = {lo, lo, lo, hi, lo, lo, hi, hi, lo, lo, hi, lo, lo, lo, hi, hi, lo, hi, hi, hi, hi, lo, hi, hi,
                         mid - q, mid - q, mid, mid + q, mid - q, mid, mid, mid + q, mid};
    static const uint32_t idx[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                   3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5, 8, 9, 10};
    assert_int_equal(sidx_mesh_from_arrays(m, xyz, 11, idx, 13, NULL), SIDX_OK);
}

static void family_build(family *f, const sidx_mesh *m)
{
    f->n = sidx_accel_registered_count();
    assert_true(f->n <= MAX_ACCELS);
    assert_string_equal(sidx_accel_registered_name(0), "brute");
    for (size_t i = 0; i < f->n; ++i)
        assert_int_equal(sidx_accel_build(sidx_accel_registered_name(i), m, NULL, &f->acc[i], NULL), SIDX_OK);
    f->compared = f->one_way = f->failed = 0;
    f->stride = tk_fast_tests() ? 16u : 1u;
    f->k = 0;
}

static void family_free(family *f)
{
    for (size_t i = 0; i < f->n; ++i) sidx_accel_destroy(f->acc[i]);
}

static int same_hit(const sidx_hit *a, const sidx_hit *b)
{
    if ((a->prim == SIDX_NO_HIT) != (b->prim == SIDX_NO_HIT)) return 0;
    if (a->prim == SIDX_NO_HIT || a->prim == b->prim) return a->t == b->t || a->prim == SIDX_NO_HIT;
    return fabsf(a->t - b->t) <= 1e-5f * fmaxf(1.0f, fabsf(a->t));
}

/* Traces one ray through every structure and checks it as the header
 * says; prints the first failures. */
static void trace_one(family *f, const float o[3], const float d[3], float tmax)
{
    if (f->k++ % f->stride) return;
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(o[0], o[1], o[2]), sidx_v3(d[0], d[1], d[2]), 0.0f, tmax), SIDX_OK);
    /* denormal components are not compared by the oracles either
     * (docs/errors.md): 1/d overflows, the products underflow */
    int denormal = 0;
    for (int k = 0; k < 3; ++k)
        if ((o[k] != 0.0f && fabsf(o[k]) < FLT_MIN) || (d[k] != 0.0f && fabsf(d[k]) < FLT_MIN)) denormal = 1;
    const int one_way = denormal || fo_shear_underflows(r.dir);
    sidx_hit ref;
    int occ_ref = -1;
    assert_int_equal(sidx_accel_intersect(f->acc[0], &r, NULL, &ref), SIDX_OK);
    assert_int_equal(sidx_accel_occluded(f->acc[0], &r, NULL, &occ_ref), SIDX_OK);
    for (size_t i = 1; i < f->n; ++i) {
        sidx_hit h;
        int occ = -1;
        assert_int_equal(sidx_accel_intersect(f->acc[i], &r, NULL, &h), SIDX_OK);
        assert_int_equal(sidx_accel_occluded(f->acc[i], &r, NULL, &occ), SIDX_OK);
        const int ok = one_way ? fo_no_nearer(&h, &ref, occ, occ_ref) : same_hit(&h, &ref) && occ == occ_ref;
        if (one_way) ++f->one_way;
        else ++f->compared;
        if (!ok && f->failed++ < 8)
            print_error("%s: o = (%a, %a, %a), d = (%a, %a, %a): prim %d t %a occ %d, brute prim %d t %a occ %d%s\n",
                        sidx_accel_registered_name(i), o[0], o[1], o[2], d[0], d[1], d[2], (int)h.prim, h.t, occ,
                        (int)ref.prim, ref.t, occ_ref, one_way ? " (one-way)" : "");
    }
}

/* The family over the box [lo, hi]^3. */
static void trace_family(family *f, float lo, float hi)
{
    const float mid = 0.5f * (lo + hi), span = hi - lo;
    /* where a ray starts on its travel axis and on the face's free axis */
    const float along[] = {lo - 2.0f * span, lo, mid, 0x1.8p-124f, hi};
    const float across[] = {lo, hi, mid, lo + 0.3f * span};
    const float lens[] = {0x1p-20f, 1.0f, 0x1p28f};
    const float leans[] = {0.0f, 0x1p-100f, FLT_MIN, 0x1p-24f};
    const float nl = sizeof leans / sizeof leans[0];
    for (int ax = 0; ax < 3; ++ax)
        for (int rot = 0; rot < 2; ++rot) {
            const int a1 = (ax + 1 + rot) % 3, a2 = 3 - ax - a1; /* a1: the face's fixed axis */
            for (int s1 = 0; s1 < 2; ++s1)
                for (size_t p2 = 0; p2 < sizeof across / sizeof across[0]; ++p2)
                    for (size_t p0 = 0; p0 < sizeof along / sizeof along[0]; ++p0)
                        for (int back = 0; back < 2; ++back)
                            for (size_t li = 0; li < sizeof lens / sizeof lens[0]; ++li)
                                for (int l1 = 0; l1 < 2 * (int)nl; ++l1)
                                    for (int l2 = 0; l2 < 2 * (int)nl; ++l2) {
                                        float o[3], d[3];
                                        o[a1] = s1 ? hi : lo;
                                        o[a2] = across[p2];
                                        o[ax] = along[p0];
                                        d[ax] = back ? -lens[li] : lens[li];
                                        /* leans as fractions of the length (lens[] are powers of two: exact) */
                                        d[a1] = (l1 & 1 ? -1.0f : 1.0f) * leans[l1 / 2] * (lens[li] < 1.0f ? lens[li] : 1.0f);
                                        d[a2] = (l2 & 1 ? -1.0f : 1.0f) * leans[l2 / 2] * (lens[li] < 1.0f ? lens[li] : 1.0f);
                                        trace_one(f, o, d, INFINITY);
                                        /* diagonal in the face a1 = lo or hi */
                                        d[a2] = (l2 & 1 ? -0.75f : 0.75f) * lens[li];
                                        trace_one(f, o, d, INFINITY);
                                    }
        }
}

static void edge_and_face_rays(float lo, float hi)
{
    sidx_mesh m;
    box_scene(&m, lo, hi);
    family f;
    family_build(&f, &m);
    trace_family(&f, lo, hi);
    print_message("box [%g, %g]^3: %ld compared, %ld one-way, %ld failed\n", (double)lo, (double)hi, f.compared,
                  f.one_way, f.failed);
    /* both kinds occur, or the family tests less than it says */
    assert_true(f.compared * (long)f.stride > 1000000);
    assert_true(f.one_way * (long)f.stride > 100000);
    assert_int_equal(f.failed, 0);
    family_free(&f);
    sidx_mesh_free(&m);
}

static void unit_cube(void **state)
{
    (void)state;
    edge_and_face_rays(-1.0f, 1.0f);
}

static void inexact_box(void **state)
{
    (void)state;
    edge_and_face_rays(0.1f, 0.7f);
}

/* What the oracle's class holds: components below FLT_MIN of the largest,
 * not small components as such. */
static void shear_underflow_class(void **state)
{
    (void)state;
    assert_true(fo_shear_underflows(sidx_v3(0.0f, 0x1.1ap-123f, 0x1p28f)));
    assert_true(fo_shear_underflows(sidx_v3(0.0f, FLT_MIN, 2.0f)));
    assert_true(fo_shear_underflows(sidx_v3(-0x1p-30f, 0x1p100f, 0.0f)));
    assert_false(fo_shear_underflows(sidx_v3(0.0f, FLT_MIN, 1.0f)));
    assert_false(fo_shear_underflows(sidx_v3(0.0f, 0x1p-100f, 1.0f)));
    assert_false(fo_shear_underflows(sidx_v3(0.0f, -0.0f, 0x1p28f)));
    assert_false(fo_shear_underflows(sidx_v3(1e-40f, 0.0f, 1e-40f))); /* denormal, but not relative to the largest */
}

/* The ray of regress/rays/edge-lean-shear-underflow.bin: along the edge
 * x = 1, y = 1 of the fuzz cube, leaning out in y by 2^-151 of its length.
 * In exact arithmetic it leaves the cube at t = 0 and passes the top corner
 * 4e-46 outside; brute force's triangle test drops the lean (d.y/d.z = 0)
 * and touches the corner, the grid misses it: the one-way check holds.
 * The same edge ray without the lean, or leaning 2^-100, is compared
 * exactly. */
static void edge_ray_of_the_fuzzer(void **state)
{
    (void)state;
    sidx_mesh m;
    box_scene(&m, -1.0f, 1.0f);
    family f;
    family_build(&f, &m);
    f.stride = 1;
    const float o[3] = {1.0f, 1.0f, 0x1.8p-124f}, d[3] = {0.0f, 0x1.1ap-123f, 0x1p28f};
    assert_true(fo_shear_underflows(sidx_v3(d[0], d[1], d[2])));
    trace_one(&f, o, d, 0x1.f4p127f);
    const float lean[][3] = {{0.0f, 0.0f, 0x1p28f}, {0.0f, 0x1p-100f, 1.0f}, {0.0f, -0x1p-100f, 1.0f}};
    for (size_t k = 0; k < sizeof lean / sizeof lean[0]; ++k) trace_one(&f, o, lean[k], 0x1.f4p127f);
    assert_int_equal(f.failed, 0);
    assert_int_equal(f.one_way, (long)f.n - 1);
    family_free(&f);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(shear_underflow_class),
        cmocka_unit_test(edge_ray_of_the_fuzzer),
        cmocka_unit_test(unit_cube),
        cmocka_unit_test(inexact_box),
    };
    return cmocka_run_group_tests_name("rays on the scene box's boundary planes", tests, NULL, NULL);
}
