/* 16_time_vs_error.c — run time against error: what accuracy costs.
 *
 * Slides (deck 001, "Spatial Data Structures"): "Ray-Triangle
 * Intersection" ("be careful about the numerical rounding errors"),
 * "Moller-Trumbore Algorithm"; deck 000: "Acceleration Strategies"
 * ("Faster ray-primitive intersection algorithms — does not reduce
 * complexity, 'only' a constant factor (but relevant!)") and "Bounding
 * Volumes" ("AABB: very simple intersection computation (min-max)").
 *
 * What it shows, measured on the spot:
 *   1. the box test alone: rays aimed at points on the faces, edges and
 *      corners of boxes — every one of them touches its box — tested with
 *      the textbook slab test and with the robust one (Ize 2013: t_far
 *      widened by 1 + 2γ₃): how many each wrongly misses, and ns per test;
 *   2. whole traversals: a BVH over a closed mesh (default icosphere:4),
 *      rays from inside it aimed at its vertices and edges, with each of
 *      the four combinations watertight / Möller–Trumbore triangle test ×
 *      robust / plain box test: rays that escape (leaks) and time per ray.
 * One escaping ray is traced through the printer, to see where it got lost.
 *
 * Read:  lib/intersect.c, sidx_intersect_aabb;
 *        lib/intersect.c, sidx_intersect_triangle
 * Run:   build/lessons/16_time_vs_error [SCENE]
 *        SCENE = a closed mesh, built-in name or .obj/.ply (default
 *        icosphere:4); rays start at its box centre, which must be inside
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "sidx/sidx.h"
#include "lesson.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 16_time_vs_error [--help] [SCENE]\n"
               "\n"
               "Accuracy against speed: plain vs robust box test and Moller-Trumbore vs watertight\n"
               "triangle test, as missed boxes, leaking rays and time per test / per ray.\n"
               "\n"
               "  SCENE   closed mesh: built-in name or .obj/.ply (default: icosphere:4)\n");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint32_t rng = 0xC0FFEEu;
static float frand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return (float)(rng >> 8) / 16777216.0f;
}

/* (a·frand() + b, a·frand() + b, a·frand() + b), one draw per statement:
 * C leaves the order of a call's arguments open, so sidx_v3(frand(), ...)
 * gave gcc and clang different boxes.  z is drawn first, the order gcc
 * took when the figures in the docs were made. */
static sidx_vec3 frand_vec(float a, float b)
{
    const float z = a * frand() + b, y = a * frand() + b, x = a * frand() + b;
    return sidx_v3(x, y, z);
}

/* ---- 1. the box test alone ---------------------------------------------------- */

#define NB 200000
static sidx_ray brays[NB];
static sidx_aabb bboxes[NB];

static void box_part(long miss[SIDX_BOX_METHOD_COUNT], double ns[SIDX_BOX_METHOD_COUNT], long *example)
{
    for (long i = 0; i < NB; ++i) {
        /* a box with awkward coordinates, a point on its surface: on a face,
         * an edge or a corner, and a ray towards it from far away */
        const sidx_vec3 lo = frand_vec(100.0f, -50.0f);
        const sidx_vec3 hi = sidx_v3_add(lo, frand_vec(3.0f, 0.01f));
        bboxes[i].min = lo;
        bboxes[i].max = hi;
        const float px = lo.x + frand() * (hi.x - lo.x); /* x first, as the initializer list ran */
        const float py = lo.y + frand() * (hi.y - lo.y);
        const float pz = lo.z + frand() * (hi.z - lo.z);
        sidx_vec3 target = sidx_v3(px, py, pz);
        const int kind = (int)(i % 3); /* 0 face, 1 edge, 2 corner: pin 1, 2 or 3 coordinates */
        for (int k = 0; k <= kind; ++k) {
            const int ax = (int)((i / 3 + (long)k) % 3);
            sidx_v3_set(&target, ax, frand() < 0.5f ? sidx_v3_get(lo, ax) : sidx_v3_get(hi, ax));
        }
        const sidx_vec3 org = frand_vec(200.0f, -100.0f);
        sidx_ray_init(&brays[i], org, sidx_v3_sub(target, org), 0.0f, INFINITY);
    }
    *example = -1;
    for (int m = 0; m < SIDX_BOX_METHOD_COUNT; ++m) {
        miss[m] = 0;
        for (long i = 0; i < NB; ++i) {
            float tn, tf;
            if (!sidx_intersect_aabb((sidx_box_method)m, &brays[i], &bboxes[i], 0.0f, INFINITY, &tn, &tf)) {
                miss[m]++;
                if (m == SIDX_BOX_PLAIN && *example < 0) *example = i;
            }
        }
        double best = INFINITY;
        volatile int sink = 0;
        for (int pass = 0; pass < 5; ++pass) {
            const double t0 = now_s();
            for (long i = 0; i < NB; ++i) {
                float tn, tf;
                sink += sidx_intersect_aabb((sidx_box_method)m, &brays[i], &bboxes[i], 0.0f, INFINITY, &tn, &tf);
            }
            if (now_s() - t0 < best) best = now_s() - t0;
        }
        (void)sink;
        ns[m] = 1e9 * best / NB;
    }
}

/* ---- 2. whole traversals -------------------------------------------------------- */

#define NR 20000
static sidx_ray mrays[NR];

int main(int argc, char **argv)
{
    lesson_args args = {.name = "16_time_vs_error",
                        .usage = usage,
                        .scene = "icosphere:4",
                        .refused = "the lesson compares triangle and box tests; its BVH only carries them"};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");

    printf("== 1. The box test alone: %d rays, each aimed at a point ON its box (face, edge or corner)\n", NB);
    long bmiss[SIDX_BOX_METHOD_COUNT], example;
    double bns[SIDX_BOX_METHOD_COUNT];
    box_part(bmiss, bns, &example);
    printf("  %-8s %14s %12s\n", "test", "wrong misses", "ns per test");
    for (int m = 0; m < SIDX_BOX_METHOD_COUNT; ++m)
        printf("  %-8s %14ld %12.2f\n", sidx_box_method_name((sidx_box_method)m), bmiss[m], bns[m]);
    if (example >= 0) {
        printf("  One of the plain test's misses, traced (plain, then robust):\n");
        sidx_printer pr;
        sidx_printer_init(&pr, stdout);
        pr.show_bounds = 1;
        const sidx_hook ph = sidx_printer_hook(&pr);
        float tn, tf;
        printf("  ");
        fflush(stdout);
        sidx_trace_aabb(&ph, SIDX_BOX_PLAIN, 0, &brays[example], &bboxes[example], 0.0f, INFINITY, &tn, &tf);
        printf("  ");
        fflush(stdout);
        sidx_trace_aabb(&ph, SIDX_BOX_ROBUST, 0, &brays[example], &bboxes[example], 0.0f, INFINITY, &tn, &tf);
        printf("  The plain test computes t_near and t_far of the touching point each with its own rounding;\n"
               "  when the box is only touched, t_near can come out a hair above t_far.  The robust test\n"
               "  widens t_far by 1 + 2*gamma_3 so rounding can never separate them.\n");
    }

    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    const sidx_vec3 centre = sidx_aabb_centroid(sidx_mesh_bounds(&mesh));
    for (int k = 0; k < NR; ++k) {
        const uint32_t tri = (uint32_t)(frand() * (float)mesh.num_triangles) % mesh.num_triangles;
        const int e = (int)(frand() * 3.0f) % 3;
        const sidx_vec3 a = sidx_mesh_vertex(&mesh, tri, e), b = sidx_mesh_vertex(&mesh, tri, (e + 1) % 3);
        const float s = (k % 4 == 0) ? 0.0f : frand();
        const sidx_vec3 target = sidx_v3_add(a, sidx_v3_scale(sidx_v3_sub(b, a), s));
        sidx_ray_init(&mrays[k], centre, sidx_v3_sub(target, centre), 0.0f, INFINITY);
    }
    printf("\n== 2. A BVH over '%s' (%u triangles); %d rays from its centre at its vertices and edges\n", args.scene,
           mesh.num_triangles, NR);
    printf("  %-11s %-7s %8s %12s\n", "triangle", "box", "leaks", "us per ray");
    long leaks[SIDX_TRI_METHOD_COUNT][SIDX_BOX_METHOD_COUNT];
    double us[SIDX_TRI_METHOD_COUNT][SIDX_BOX_METHOD_COUNT];
    int leak_ray = -1;
    sidx_accel *leak_accel = NULL;
    for (int tm = 0; tm < 2; ++tm)
        for (int bm = 0; bm < SIDX_BOX_METHOD_COUNT; ++bm) {
            sidx_build_options opt = {0};
            opt.tri = (sidx_tri_method)tm;
            opt.box = (sidx_box_method)bm;
            sidx_accel *a = NULL;
            if (sidx_accel_build("bvh", &mesh, &opt, &a, &err) != SIDX_OK) {
                fprintf(stderr, "16_time_vs_error: %s\n", err.message);
                sidx_accel_destroy(leak_accel);
                sidx_mesh_free(&mesh);
                return 1;
            }
            leaks[tm][bm] = 0;
            int first = -1;
            for (int k = 0; k < NR; ++k) {
                sidx_hit h;
                sidx_accel_intersect(a, &mrays[k], NULL, &h);
                if (h.prim == SIDX_NO_HIT) {
                    leaks[tm][bm]++;
                    if (first < 0) first = k;
                }
            }
            double best = INFINITY;
            for (int pass = 0; pass < 3; ++pass) {
                const double t0 = now_s();
                for (int k = 0; k < NR; ++k) {
                    sidx_hit h;
                    sidx_accel_intersect(a, &mrays[k], NULL, &h);
                }
                if (now_s() - t0 < best) best = now_s() - t0;
            }
            us[tm][bm] = 1e6 * best / NR;
            printf("  %-11s %-7s %8ld %12.3f\n", sidx_tri_method_name((sidx_tri_method)tm),
                   sidx_box_method_name((sidx_box_method)bm), leaks[tm][bm], us[tm][bm]);
            if (tm == SIDX_TRI_MOLLER_TRUMBORE && bm == SIDX_BOX_ROBUST && first >= 0 && !leak_accel) {
                leak_accel = a;
                leak_ray = first;
            } else {
                sidx_accel_destroy(a);
            }
        }
    if (leak_accel) {
        printf("\n  One ray that escapes with Moller-Trumbore, its leaf and triangle tests (printer):\n");
        sidx_printer pr;
        sidx_printer_init(&pr, stdout);
        pr.mask = SIDX_EVMASK(SIDX_EV_RAY_BEGIN) | SIDX_EVMASK(SIDX_EV_PRIM_TEST) | SIDX_EVMASK(SIDX_EV_TERMINATE) |
                  SIDX_EVMASK(SIDX_EV_RAY_END);
        const sidx_hook ph = sidx_printer_hook(&pr);
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ph, 0};
        sidx_hit h;
        sidx_accel_intersect(leak_accel, &mrays[leak_ray], &q, &h);
        printf("  Every triangle it reaches says miss: the ray passes exactly between two of them.\n");
        sidx_accel_destroy(leak_accel);
    }
    sidx_mesh_free(&mesh);
    const double cost = 100.0 * (us[0][0] / us[1][1] - 1.0);
    printf("\n== Key figures\n");
    printf("  box test: plain misses %ld of %d touching rays, robust %ld; %.2f vs %.2f ns per test\n",
           bmiss[SIDX_BOX_PLAIN], NB, bmiss[SIDX_BOX_ROBUST], bns[SIDX_BOX_PLAIN], bns[SIDX_BOX_ROBUST]);
    printf("  traversal: watertight + robust leaks %ld, Moller + plain leaks %ld; the accurate pair costs\n"
           "  %+.0f%% time per ray here.\n",
           leaks[0][0], leaks[1][1], cost);
    lesson_check("watertight_leaks", leaks[0][0]);
    lesson_check("moller_leaks_more", leaks[1][0] > leaks[0][0]);
    lesson_check("robust_box_misses", bmiss[SIDX_BOX_ROBUST]);
    lesson_check("plain_box_misses_more", bmiss[SIDX_BOX_PLAIN] > bmiss[SIDX_BOX_ROBUST]);
    return 0;
}
