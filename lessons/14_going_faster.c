/* 14_going_faster.c — "Can it go faster?": tracing rays on several cores.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Can it go faster?"
 * ("Parallelize it! Trace rays on multiple cores in parallel — ray tracing
 * is 'embarrassingly parallel' — Use SIMD instructions: traverse many rays
 * (packets), test with one BV; traverse one ray, but intersect with many
 * BVs (needs wide BVH!)"), "Packet Tracing", "Frustum Tracing".
 *
 * What it shows: one built BVH (default over the teapot) shared by 1, 2, 4
 * and 8 POSIX threads, each tracing its own slice of the same camera rays
 * with sidx_accel_intersect_n — a built structure is immutable, so they
 * need no lock.  Rays per second and the speed-up over one thread,
 * measured, and a check that every thread count gives the same hits.
 * Packets, frustum tracing and a wide (4/8-ary) BVH are the other items on
 * the slide; they are not in sidx yet (issue 8), so this lesson measures
 * only threads.  One ray's trace is printed from inside a worker thread,
 * to show that hooks work there too: the events arrive on the querying
 * thread with that query's user pointer.
 *
 * Run:   build/lessons/14_going_faster [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include "sidx/sidx.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 14_going_faster [--help] [SCENE]\n"
               "\n"
               "Threads sharing one BVH: rays per second with 1, 2, 4 and 8 threads.\n"
               "(Packets, frustum tracing and wide BVHs are not in sidx yet.)\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define W 400
#define H 300
#define NRAYS (W * H)
#define REPEAT 3
static sidx_ray rays[NRAYS];
static sidx_hit hits[NRAYS];
static float ref_t[NRAYS];

typedef struct {
    const sidx_accel *a;
    size_t first, count;
    int trace_one; /* print the first ray's events from this thread */
} job;

static void *worker(void *arg)
{
    const job *j = arg;
    if (j->trace_one) {
        sidx_printer pr;
        sidx_printer_init(&pr, stdout);
        pr.mask = SIDX_EVMASK(SIDX_EV_RAY_BEGIN) | SIDX_EVMASK(SIDX_EV_HIT_UPDATE) | SIDX_EVMASK(SIDX_EV_TERMINATE) |
                  SIDX_EVMASK(SIDX_EV_RAY_END);
        const sidx_hook ph = sidx_printer_hook(&pr);
        const size_t k = j->first + (j->count > W / 2 ? W / 2 : 0); /* the middle of its first row */
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ph, (uint32_t)k};
        sidx_accel_intersect(j->a, &rays[k], &q, &hits[k]);
    }
    for (int rep = 0; rep < REPEAT; ++rep) /* enough work per run to time it */
        sidx_accel_intersect_n(j->a, rays + j->first, j->count, NULL, hits + j->first);
    return NULL;
}

/* Traces all rays with n threads; returns seconds, or -1 on failure. */
static double run(const sidx_accel *a, int n, int trace_one)
{
    pthread_t th[8];
    job jobs[8];
    const double t0 = now_s();
    size_t first = 0;
    for (int i = 0; i < n; ++i) {
        const size_t count = NRAYS / (size_t)n + ((size_t)i < NRAYS % (size_t)n ? 1 : 0);
        jobs[i] = (job){a, first, count, trace_one && i == n - 1};
        first += count;
        if (pthread_create(&th[i], NULL, worker, &jobs[i]) != 0) {
            for (int k = 0; k < i; ++k) pthread_join(th[k], NULL);
            return -1.0;
        }
    }
    for (int i = 0; i < n; ++i) pthread_join(th[i], NULL);
    return now_s() - t0;
}

int main(int argc, char **argv)
{
    const char *scene = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) { usage(stdout); return 0; }
        if (argv[i][0] == '-' || scene) {
            fprintf(stderr, "14_going_faster: unexpected argument '%s'\n", argv[i]);
            usage(stderr);
            return 2;
        }
        scene = argv[i];
    }
    if (!sidx_accel_is_registered("bvh")) {
        fprintf(stderr, "14_going_faster: structure 'bvh' is not registered in this build\n");
        return 1;
    }
    const char *spec = scene ? scene : "teapot";
    sidx_mesh mesh;
    sidx_error err = {0};
    if (sidx_scene_open(spec, &mesh, &err) != SIDX_OK) {
        fprintf(stderr, "14_going_faster: %s\n", err.message);
        return 1;
    }
    sidx_accel *a = NULL;
    if (mesh.num_triangles == 0 || sidx_accel_build("bvh", &mesh, NULL, &a, &err) != SIDX_OK) {
        fprintf(stderr, "14_going_faster: %s\n", mesh.num_triangles ? err.message : "empty scene");
        sidx_mesh_free(&mesh);
        return 1;
    }
    /* a pinhole camera in front of the scene */
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const float R = sidx_v3_length(ext);
    const sidx_vec3 eye = sidx_v3(ctr.x + 0.3f * R, ctr.y + 0.4f * R, ctr.z + 1.3f * R);
    const sidx_vec3 fwd = sidx_v3_scale(sidx_v3_sub(ctr, eye), 1.0f / sidx_v3_length(sidx_v3_sub(ctr, eye)));
    sidx_vec3 right = sidx_v3_cross(fwd, sidx_v3(0, 1, 0));
    right = sidx_v3_scale(right, 1.0f / sidx_v3_length(right));
    const sidx_vec3 up = sidx_v3_cross(right, fwd);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const float u = (2.0f * ((float)x + 0.5f) / W - 1.0f) * 0.45f, v = (1.0f - 2.0f * ((float)y + 0.5f) / H) * 0.34f;
            sidx_ray_init(&rays[y * W + x], eye, sidx_v3_add(fwd, sidx_v3_add(sidx_v3_scale(right, u), sidx_v3_scale(up, v))),
                          0.0f, INFINITY);
        }
    const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    printf("== '%s' (%u triangles) in a BVH; %d x %d camera rays; %ld processors online\n", spec, mesh.num_triangles,
           W, H, cpus);
    printf("\n  One ray traced from inside the last worker thread (its own printer, its own ray id):\n");
    if (run(a, 2, 1) < 0) { fprintf(stderr, "14_going_faster: cannot start threads\n"); return 1; }
    for (int i = 0; i < NRAYS; ++i) ref_t[i] = hits[i].t;

    static const int counts[4] = {1, 2, 4, 8};
    double secs[4];
    int same = 1;
    printf("\n  each run traces every ray %d times; best of 3 runs\n", REPEAT);
    printf("  %8s %12s %14s %10s\n", "threads", "ms", "Mrays/s", "speed-up");
    for (int k = 0; k < 4; ++k) {
        double best = INFINITY;
        for (int rep = 0; rep < 3; ++rep) {
            const double s = run(a, counts[k], 0);
            if (s < 0) { fprintf(stderr, "14_going_faster: cannot start threads\n"); return 1; }
            if (s < best) best = s;
            for (int i = 0; i < NRAYS; ++i) same &= hits[i].t == ref_t[i];
        }
        secs[k] = best;
        printf("  %8d %12.2f %14.2f %9.2fx\n", counts[k], 1e3 * best, REPEAT * NRAYS / best / 1e6, secs[0] / best);
    }
    printf("\n  Every ray is independent and the structure is read-only: the speed-up follows the\n"
           "  number of cores until there are more threads than cores (%ld here).  Same hits with\n"
           "  every thread count: %s.\n", cpus, same ? "yes" : "NO");
    printf("  Packets (one box test for many rays, SIMD), frustum tracing and wide BVHs (one ray, 4-8\n"
           "  boxes per SIMD test) are not implemented in sidx yet (issue 8).\n");
    sidx_accel_destroy(a);
    sidx_mesh_free(&mesh);
    printf("CHECK same_hits=%d\n", same);
    if (cpus < 2) printf("  (one processor: no speed-up is possible, the check below only asks for no slow-down)\n");
    printf("CHECK threads_faster=%d\n", cpus < 2 ? secs[1] < 1.2 * secs[0] : secs[1] < 0.9 * secs[0]);
    return 0;
}
