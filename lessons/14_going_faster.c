/* 14_going_faster.c — "Can it go faster?": wide BVHs, packets, frustums, threads.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Can it go faster?"
 * ("Parallelize it! Trace rays on multiple cores in parallel — ray tracing
 * is 'embarrassingly parallel' — Use SIMD instructions: traverse many rays
 * (packets), test with one BV (for BVHs) — traverse one ray, but intersect
 * with many BVs (needs wide BVH!) — hybrid mix of both with adaptive
 * switch"), "Packet Tracing" ("Combine many similar rays (e.g. primary or
 * shadow rays) ... all rays perform the same traversal operations ...
 * Overhead: rays will perform unnecessary operations — low for coherent
 * and small set of rays (e.g. up to 4x4 rays)") and "Frustum Tracing"
 * ("Compute with 4 corner 'rays' — avoid traversing many rays individually
 * — particularly beneficial in the upper levels of spatial index").
 *
 * What it shows, measured on the spot for one image of primary rays from a
 * pinhole camera in front of the scene (default: the teapot):
 *   1. one ray at a time: the binary BVH ("bvh") against 4- and 8-wide
 *      BVHs ("bvh4", "bvh8": one SIMD pass tests all the boxes of a node),
 *      collapsed from a binary tree that may also cut long triangles in two
 *      (spatial splits, lib/bvh_spatial.c) — rays per second, and node visits,
 *      box and triangle tests per ray counted with sidx_counters on every
 *      4th ray;
 *   2. packets: the image traced in 4x4 and 8x8 tiles (sidx_trace_tiles,
 *      sidx/packet.h) against single rays — one node fetch serves the whole
 *      tile, at the price of box tests for rays that do not need them;
 *   3. frustum culling: the same tiles with SIDX_PACKET_FRUSTUM.  The walk
 *      tests the corner-ray pyramid only where it can replace the box tests
 *      of 2 or more groups of 8 rays, so a 4x4 tile (2 groups) walks exactly
 *      as plain packets do, and an 8x8 tile culls nodes and skips box tests.
 *      The counts (frustum tests, culls, box tests saved) are the result;
 *      the time against plain packets is taken warm, interleaved, best of
 *      several passes, with the run's noise beside it — the 4x4 "speed-up"
 *      of the same walk twice shows how large that noise is;
 *   4. threads: sidx_trace_parallel (sidx/parallel.h) with 1 and 2 threads,
 *      wall-clock and CPU time side by side.
 * Every method must return the very same hits as the binary BVH, bit for
 * bit (prim and t; a different prim is accepted only on an exact tie, both
 * triangles hit at the same t).  Times are printed, never checked: on a
 * busy machine a second thread or a SIMD path may gain nothing.
 * SIDX_SIMD=scalar in the environment forces the portable kernels of the
 * wide BVHs and packets, to see what the SIMD instructions bring;
 * SIDX_SIMD=avx2 keeps bvh8 off AVX-512 (the same code with 32 registers
 * instead of 16), to see what the bigger register file brings.
 *
 * Read:  lib/packet.c, packet_walk_impl
 * Run:   build/lessons/14_going_faster [SCENE]
 *        SIDX_SIMD=scalar build/lessons/14_going_faster
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "sidx/sidx.h"
#include "lesson.h"
#include "sidx/packet.h"
#include "sidx/parallel.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 14_going_faster [--help] [build knobs] [SCENE]\n"
               "\n"
               "Going faster on one image of camera rays: a binary BVH vs 4- and 8-wide BVHs,\n"
               "4x4 and 8x8 packets vs single rays, frustum culling vs plain packets, and 1 vs 2\n"
               "threads; every method must give the same hits.  SIDX_SIMD=scalar forces the\n"
               "portable (non-SIMD) kernels, SIDX_SIMD=avx2 keeps bvh8 off AVX-512.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "The knobs below change the binary BVH and the SAH BVH the wide ones are collapsed\n"
               "from; the packets and threads walk the binary BVH.  The checks hold for the defaults.\n");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double cpu_s(void) /* CPU time of all the process's threads */
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define W 320 /* multiples of 8: every tile is a full 4x4 or 8x8 */
#define H 240
#define NRAYS (W * H)
#define BEST_OF 7   /* each time is the best of this many passes over the image */
#define SUBSET 4    /* sidx_counters on every 4th ray */
static sidx_ray rays[NRAYS];
static sidx_hit ref[NRAYS]; /* the binary BVH's hits, one ray at a time */
static sidx_hit got[NRAYS];

/* ---- same hits, bit for bit ----------------------------------------------------- */

static int same_bits(float a, float b)
{
    uint32_t x, y;
    memcpy(&x, &a, sizeof x);
    memcpy(&y, &b, sizeof y);
    return x == y;
}

/* Triangle p is hit by ray r at exactly t (the watertight test of the builds). */
static int hit_at(const sidx_mesh *m, const sidx_ray *r, uint32_t p, float t)
{
    if (p == SIDX_NO_HIT || p >= m->num_triangles) return 0;
    float tt, u, v;
    return sidx_intersect_triangle_watertight(r, sidx_mesh_vertex(m, p, 0), sidx_mesh_vertex(m, p, 1),
                                              sidx_mesh_vertex(m, p, 2), INFINITY, &tt, &u, &v) &&
           same_bits(tt, t);
}

typedef struct {
    size_t diff; /* rays whose hit differs from the reference */
    size_t ties; /* other prim, same t, both really hit there */
} agreement;

static agreement compare(const sidx_mesh *m, const sidx_hit *h)
{
    agreement g = {0, 0};
    for (size_t i = 0; i < NRAYS; ++i) {
        if (!same_bits(h[i].t, ref[i].t)) ++g.diff;
        else if (h[i].prim != ref[i].prim) {
            if (hit_at(m, &rays[i], ref[i].prim, ref[i].t) && hit_at(m, &rays[i], h[i].prim, h[i].t)) ++g.ties;
            else ++g.diff;
        }
    }
    return g;
}

static int all_same = 1;
static size_t all_ties = 0;

static void agree(const char *what, const sidx_mesh *m)
{
    const agreement g = compare(m, got);
    all_ties += g.ties;
    if (g.diff) {
        all_same = 0;
        printf("  !! %s: %zu of %d hits differ from the binary BVH's\n", what, g.diff, NRAYS);
    }
}

/* ---- the measurements --------------------------------------------------------------- */

/* Best wall time of BEST_OF single-ray passes (sidx_accel_intersect_n). */
static double time_single(const sidx_accel *a)
{
    double best = INFINITY;
    for (int k = 0; k < BEST_OF; ++k) {
        const double t0 = now_s();
        sidx_accel_intersect_n(a, rays, NRAYS, NULL, got);
        const double s = now_s() - t0;
        if (s < best) best = s;
    }
    return best;
}

/* Best wall time of BEST_OF passes in tiles; stats of one pass. */
static double time_tiles(const sidx_accel *a, uint32_t tile, sidx_packet_mode mode, sidx_packet_stats *st)
{
    const sidx_packet_options opt = {mode, 0, 0};
    double best = INFINITY;
    for (int k = 0; k < BEST_OF; ++k) {
        sidx_packet_stats s;
        memset(&s, 0, sizeof s);
        const double t0 = now_s();
        const sidx_status rc = sidx_trace_tiles(a, rays, W, H, tile, &opt, got, &s);
        const double sec = now_s() - t0;
        if (rc != SIDX_OK) return -1.0;
        if (sec < best) best = sec;
        *st = s;
    }
    return best;
}

static double thread_s(void) /* CPU time of the calling thread */
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Plain against frustum tiles, warm and interleaved: one untimed pass of
 * each, then BEST_OF rounds of one pass each (the order swapped every
 * round), so a slow spell of the machine hits both.  Best times, and the
 * noise: the larger relative gap between a side's best and median. */
typedef struct { double plain, frustum, noise; } versus;
static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
static versus time_versus(const sidx_accel *a, uint32_t tile)
{
    const sidx_packet_options opt[2] = {{SIDX_PACKET_PLAIN, 0, 0}, {SIDX_PACKET_FRUSTUM, 0, 0}};
    double t[2][BEST_OF];
    for (int m = 0; m < 2; ++m) sidx_trace_tiles(a, rays, W, H, tile, &opt[m], got, NULL);
    for (int k = 0; k < BEST_OF; ++k)
        for (int j = 0; j < 2; ++j) {
            const int m = (k + j) % 2;
            const double t0 = thread_s();
            sidx_trace_tiles(a, rays, W, H, tile, &opt[m], got, NULL);
            t[m][k] = thread_s() - t0;
        }
    versus v = {0, 0, 0};
    for (int m = 0; m < 2; ++m) {
        qsort(t[m], BEST_OF, sizeof t[m][0], cmp_double);
        const double spread = (t[m][BEST_OF / 2] - t[m][0]) / t[m][0];
        if (spread > v.noise) v.noise = spread;
    }
    v.plain = t[0][0];
    v.frustum = t[1][0];
    return v;
}

/* Node visits, box and triangle tests of single rays, on every SUBSET-th ray. */
typedef struct { double nodes, boxes, tris; } per_ray;
static per_ray count_single(const sidx_accel *a)
{
    sidx_counters c;
    sidx_counters_init(&c);
    const sidx_hook h = sidx_counters_hook(&c);
    sidx_hit hit;
    size_t n = 0;
    for (size_t i = 0; i < NRAYS; i += SUBSET, ++n) {
        const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &h, (uint32_t)i};
        sidx_accel_intersect(a, &rays[i], &q, &hit);
    }
    return (per_ray){(double)c.n[SIDX_EV_NODE_ENTER] / (double)n, (double)c.n[SIDX_EV_BOX_TEST] / (double)n,
                     (double)c.n[SIDX_EV_PRIM_TEST] / (double)n};
}

/* The wide builds say which kernels they picked in a NOTE event. */
static void note_hook(const sidx_event *ev, void *user)
{
    if (ev->type == SIDX_EV_NOTE && ev->text) *(const char **)user = ev->text;
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_BVH_KNOBS(knobs), {0}};
    lesson_args args = {.name = "14_going_faster",
                        .usage = usage,
                        .scene = "teapot",
                        .options = options,
                        .refused = LESSON_BVH_ONLY};
    lesson_parse(&args, argc, argv);
    static const char *const names[3] = {"bvh", "bvh4", "bvh8"};
    for (int s = 0; s < 3; ++s) lesson_need(&args, names[s]);
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    sidx_accel *acc[3] = {NULL, NULL, NULL};
    const char *kernel[3] = {"scalar, one box per test", NULL, NULL};
    for (int s = 0; s < 3; ++s) {
        const sidx_hook nh = {note_hook, (void *)&kernel[s], SIDX_EVMASK(SIDX_EV_NOTE)};
        sidx_build_options bo = knobs;
        bo.hook = s ? &nh : NULL;
        if (sidx_accel_build(names[s], &mesh, &bo, &acc[s], &err) != SIDX_OK) {
            fprintf(stderr, "14_going_faster: %s: %s\n", names[s], err.message);
            for (int k = 0; k < s; ++k) sidx_accel_destroy(acc[k]);
            sidx_mesh_free(&mesh);
            return 1;
        }
    }

    /* a pinhole camera in front of the scene: every ray starts at the eye,
     * so each tile's rays lie inside the pyramid of its 4 corner rays */
    const lesson_camera cam = lesson_camera_at(sidx_mesh_bounds(&mesh), 0.3f, 0.4f, 1.3f);
    lesson_camera_rays(&cam, W, H, 0.27f, 0.2f, rays);
    sidx_accel_intersect_n(acc[0], rays, NRAYS, NULL, ref);
    size_t hit_rays = 0;
    for (size_t i = 0; i < NRAYS; ++i) hit_rays += ref[i].prim != SIDX_NO_HIT;
    const char *simd_env = getenv("SIDX_SIMD");
    printf("== '%s' (%u triangles); %d x %d camera rays (%.0f%% hit); %u hardware threads; SIDX_SIMD=%s\n", args.scene,
           mesh.num_triangles, W, H, 100.0 * (double)hit_rays / NRAYS, sidx_hardware_threads(),
           simd_env ? simd_env : "(unset)");
    printf("   times: best of %d passes over the image; counts: exact (packets) or on every %dth ray (single rays)\n",
           BEST_OF, SUBSET);

    /* ---- 1. one ray, many boxes: wide BVHs -------------------------------------- */
    printf("\n== 1. One ray at a time (sidx_accel_intersect_n): binary BVH vs 4- and 8-wide nodes\n");
    printf("  %-6s %9s %8s %10s %10s %9s   %s\n", "", "Mrays/s", "vs bvh", "nodes/ray", "boxes/ray", "tris/ray",
           "kernels");
    double single_s[3];
    per_ray pr[3];
    for (int s = 0; s < 3; ++s) {
        single_s[s] = time_single(acc[s]);
        agree(names[s], &mesh);
        pr[s] = count_single(acc[s]);
        printf("  %-6s %9.2f %7.2fx %10.2f %10.2f %9.2f   %s\n", names[s], NRAYS / single_s[s] / 1e6,
               single_s[0] / single_s[s], pr[s].nodes, pr[s].boxes, pr[s].tris, kernel[s] ? kernel[s] : "?");
    }
    const int wide_fewer = pr[1].nodes < pr[0].nodes && pr[2].nodes < pr[0].nodes;
    sidx_accel_stats st8;
    sidx_accel_stats_get(acc[2], &st8);
    const uint64_t refs8 = st8.prim_refs;
    printf("  The wide trees regroup a binary tree's boxes: a ray visits %.1fx (bvh4) and %.1fx (bvh8)\n"
           "  fewer nodes, each a run of boxes tested in one SIMD pass — more box tests, fewer steps and\n"
           "  cache misses.  Their binary tree also has spatial splits: %llu references to %u triangles\n"
           "  (bvh8), a long triangle cut in two where that keeps sibling boxes from overlapping.\n"
           "  (SIDX_SIMD=scalar: the same counts without SIMD — compare the times.)\n",
           pr[0].nodes / pr[1].nodes, pr[0].nodes / pr[2].nodes, (unsigned long long)refs8, mesh.num_triangles);

    /* ---- 2. many rays, one box: packets ---------------------------------------- */
    printf("\n== 2. Packets over the binary BVH (sidx_trace_tiles): 4x4 and 8x8 tiles vs single rays\n");
    printf("  %-12s %9s %9s %12s %10s %9s %10s %10s\n", "", "Mrays/s", "vs single", "packet steps", "boxes/ray",
           "tris/ray", "ray by ray", "solo walks");
    printf("  %-12s %9.2f %8.2fx %12.2f %10.2f %9.2f %10s %9s\n", "single rays", NRAYS / single_s[0] / 1e6, 1.0,
           pr[0].nodes, pr[0].boxes, pr[0].tris, "", "");
    static const uint32_t tiles[2] = {4, 8};
    sidx_packet_stats plain[2];
    double plain_s[2];
    for (int k = 0; k < 2; ++k) {
        char label[32];
        snprintf(label, sizeof label, "%ux%u packets", tiles[k], tiles[k]);
        plain_s[k] = time_tiles(acc[0], tiles[k], SIDX_PACKET_PLAIN, &plain[k]);
        if (plain_s[k] < 0) { fprintf(stderr, "14_going_faster: sidx_trace_tiles failed\n"); return 1; }
        agree(label, &mesh);
        const sidx_packet_stats *p = &plain[k];
        printf("  %-12s %9.2f %8.2fx %12.2f %10.2f %9.2f %9.1f%% %10llu\n", label, NRAYS / plain_s[k] / 1e6,
               single_s[0] / plain_s[k], (double)p->node_visits / NRAYS, (double)p->box_tests / NRAYS,
               (double)p->prim_tests / NRAYS, 100.0 * (double)p->single_packets / (double)p->packets,
               (unsigned long long)p->switched_rays);
    }
    printf("  packet steps = nodes the packet walk processed, per ray: one node fetch and one loop step\n"
           "  serve up to 16 or 64 rays.  Box tests per ray even drop (first-hit early descent: once a\n"
           "  group of 8 rays hits an inner node, the packet enters it without testing the other groups),\n"
           "  but triangle tests per ray grow with the tile — rays \"perform unnecessary operations\" in\n"
           "  leaves only their neighbours reach.  Tiles straddling a change of direction signs are traced\n"
           "  ray by ray; solo walks = subtrees finished by 1 or 2 rays alone (the adaptive switch).\n");

    /* ---- 3. frustum culling -------------------------------------------------------- */
    printf("\n== 3. Frustum culling (SIDX_PACKET_FRUSTUM): the 4 corner rays of a tile bound all its rays\n");
    printf("  The walk tests a node against the frustum only where the first active group of 8 rays\n"
           "  missed it and 2 or more groups remain, whose box tests a cull then skips (lib/packet.c,\n"
           "  packet_walk_impl).  A 4x4 tile is 2 groups: it never uses the frustum, its walk is the\n"
           "  plain one.  An 8x8 tile is 8 groups: one cull skips up to 7 groups, 56 box tests.\n");
    printf("  %-6s %7s %12s %9s %13s %13s %7s %11s\n", "tile", "groups", "frust. tests", "culls", "plain boxes",
           "frustum boxes", "saved", "boxes/cull");
    sidx_packet_stats fru[2];
    for (int k = 0; k < 2; ++k) {
        char label[32];
        snprintf(label, sizeof label, "%ux%u frustum", tiles[k], tiles[k]);
        const sidx_packet_options fopt = {SIDX_PACKET_FRUSTUM, 0, 0};
        memset(&fru[k], 0, sizeof fru[k]);
        if (sidx_trace_tiles(acc[0], rays, W, H, tiles[k], &fopt, got, &fru[k]) != SIDX_OK) {
            fprintf(stderr, "14_going_faster: sidx_trace_tiles failed\n");
            return 1;
        }
        agree(label, &mesh);
        const double saved = (double)plain[k].box_tests - (double)fru[k].box_tests;
        char per_cull[16] = "-";
        if (fru[k].frustum_culls) snprintf(per_cull, sizeof per_cull, "%.1f", saved / (double)fru[k].frustum_culls);
        printf("  %ux%-4u %7u %12llu %9llu %13llu %13llu %6.1f%% %11s\n", tiles[k], tiles[k],
               tiles[k] * tiles[k] / 8, (unsigned long long)fru[k].frustum_tests,
               (unsigned long long)fru[k].frustum_culls, (unsigned long long)plain[k].box_tests,
               (unsigned long long)fru[k].box_tests, 100.0 * saved / (double)plain[k].box_tests, per_cull);
    }
    /* the counts are the result; the times only say whether the saving shows */
    const int frustum_4x4_same_walk = fru[0].frustum_tests == 0 && fru[0].box_tests == plain[0].box_tests &&
                                      fru[0].node_visits == plain[0].node_visits &&
                                      fru[0].prim_tests == plain[0].prim_tests;
    const int frustum_8x8_saves = fru[1].box_tests < plain[1].box_tests;
    /* every box test saved is one a cull skipped: at most 7 groups of 8 per cull */
    const int saved_by_culls = plain[1].box_tests - fru[1].box_tests <= 56 * fru[1].frustum_culls;
    const int frustum_le = fru[0].box_tests <= plain[0].box_tests && fru[1].box_tests <= plain[1].box_tests;
    printf("  8x8: %.0f%% of the frustum tests cull a node; the others cost a test and save nothing.\n",
           fru[1].frustum_tests ? 100.0 * (double)fru[1].frustum_culls / (double)fru[1].frustum_tests : 0.0);
    printf("  Time, frustum vs plain packets (thread CPU time, warm, best of %d passes each, interleaved):\n",
           BEST_OF);
    double noise = 0.0; /* the 4x4 gap of the same walk twice, or a side's best-to-median gap */
    for (int k = 0; k < 2; ++k) {
        const versus v = time_versus(acc[0], tiles[k]);
        const double ratio = v.plain / v.frustum;
        if (k == 0) noise = fabs(ratio - 1.0);
        if (v.noise > noise) noise = v.noise;
        printf("    %ux%u: %.2fx  ", tiles[k], tiles[k], ratio);
        if (k == 0) printf("(the same walk twice: this is the timing noise of this machine)\n");
        else if (fabs(ratio - 1.0) <= noise)
            printf("(within the noise, +-%.0f%%: %.0f%% fewer box tests do not show in time)\n", 100.0 * noise,
                   100.0 * (1.0 - (double)fru[1].box_tests / (double)plain[1].box_tests));
        else printf("(%s; noise +-%.0f%%)\n", ratio > 1.0 ? "the frustum is faster" : "the frustum is slower",
                    100.0 * noise);
    }
    printf("  Whether the saved box tests save time depends on what they cost: the packet tests a box\n"
           "  against 8 rays in one SIMD pass, while the frustum costs its set-up per tile (4 planes,\n"
           "  and a check that every ray lies inside them) plus every test that does not cull.\n");

    /* ---- 4. many cores: threads ------------------------------------------------------ */
    printf("\n== 4. Threads (sidx_trace_parallel over bvh8: a share of the rays per thread, in batches of %u, plus work stealing)\n",
           SIDX_PARALLEL_BATCH);
    printf("  %-8s %9s %9s %10s %9s\n", "threads", "wall ms", "CPU ms", "CPU/wall", "Mrays/s");
    double wall[2];
    for (unsigned t = 1; t <= 2; ++t) {
        double best = INFINITY, cpu = 0.0;
        for (int k = 0; k < BEST_OF; ++k) {
            const double w0 = now_s(), c0 = cpu_s();
            sidx_trace_parallel(acc[2], rays, NRAYS, NULL, got, t);
            const double c = cpu_s() - c0, w = now_s() - w0;
            if (w < best) { best = w; cpu = c; }
        }
        char label[32];
        snprintf(label, sizeof label, "%u threads", t);
        agree(label, &mesh);
        wall[t - 1] = best;
        printf("  %-8u %9.2f %9.2f %10.2f %9.2f\n", t, 1e3 * best, 1e3 * cpu, cpu / best, NRAYS / best / 1e6);
    }
    printf("  CPU/wall is how many cores were really working.  The rays are independent and the tree is\n"
           "  read-only, so with free cores 2 threads take about half the wall time for the same CPU\n"
           "  time (%.2fx here); on a loaded machine the second thread waits for a core and gains nothing.\n",
           wall[0] / wall[1]);

    printf("\n  Same hits (prim and t, bit for bit) as the binary BVH from every method above: %s\n"
           "  (%zu hits on an exact tie of two triangles at the same t, where either may be named).\n",
           all_same ? "yes" : "NO", all_ties);
    for (int s = 0; s < 3; ++s) sidx_accel_destroy(acc[s]);
    sidx_mesh_free(&mesh);
    lesson_check("same_hits", all_same);
    lesson_check("wide_fewer_node_visits", wide_fewer);
    lesson_check("frustum_box_tests_le_plain", frustum_le);
    lesson_check("frustum_4x4_same_walk", frustum_4x4_same_walk);
    lesson_check("frustum_8x8_saves_box_tests", frustum_8x8_saves);
    lesson_check("frustum_culls_nodes", fru[1].frustum_culls > 0);
    lesson_check("saved_box_tests_come_from_culls", frustum_8x8_saves && saved_by_culls);
    return 0;
}
