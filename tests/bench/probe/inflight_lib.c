/* inflight_lib.c — the library's stream entry (sidx_accel_intersect_n) on
 * bvh8 with several rays in flight and without (SIDX_STREAM_INFLIGHT=on
 * and off at build), on the height field of `sidx-bench scale --scene
 * heightfield` or a mesh file, and what the default (by tree size) picks
 * (docs/performance.md, "Several rays in flight").  Not part of the
 * build; compile and run it by hand:
 *
 *   cc -std=gnu11 -O2 -Ilib/include -Ilib -Itests tests/bench/probe/inflight_lib.c \
 *      tests/common/testkit.c build/lib/libsidx.a -lm -pthread -o inflight_lib
 *   ./inflight_lib D|FILE primary|diffuse [ROUNDS]
 *
 * D is the detail of the built-in scene heightfield (724: 1M, 2896: 16.8M
 * triangles); anything not a number is a mesh file.  The rays are the
 * scale command's 100000 (tk_make_rays, seed 7).  Three trees are built:
 * default, on, off.  Every ray's hit from each must equal the single
 * query's byte for byte (exit 1 otherwise).  Then per round (7 by
 * default) a warm-up call of each and 3 timed calls of on, off, default
 * in turn (thread CPU time, the best kept); printed: the tree's bytes,
 * what the default picked, Mrays/s of off, and on / off and default / off
 * time as median [min..max] over the rounds. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "sidx/sidx.h"
#include "bvh_wide_internal.h"
#include "common/testkit.h"

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_d(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

static sidx_accel *build(const sidx_mesh *m, const char *env)
{
    if (env) setenv("SIDX_STREAM_INFLIGHT", env, 1);
    else unsetenv("SIDX_STREAM_INFLIGHT");
    sidx_accel *a = NULL;
    sidx_error err;
    if (sidx_accel_build("bvh8", m, NULL, &a, &err) != SIDX_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    unsetenv("SIDX_STREAM_INFLIGHT");
    return a;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: %s D|FILE primary|diffuse [ROUNDS]\n", argv[0]);
        return 2;
    }
    char *end;
    const unsigned long d = strtoul(argv[1], &end, 10);
    const int diffuse = !strcmp(argv[2], "diffuse");
    const int rounds = argc > 3 ? atoi(argv[3]) : 7;
    if (rounds < 1 || rounds > 64) return 2;
    sidx_mesh m;
    sidx_error err;
    const sidx_status st = *end == '\0' && d > 0 ? sidx_scene_make("heightfield", (uint32_t)d, &m, &err)
                                                 : sidx_mesh_load(argv[1], &m, &err);
    if (st != SIDX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    sidx_accel *acc[3] = {build(&m, "on"), build(&m, "off"), build(&m, NULL)};
    static const char *const name[3] = {"on", "off", "default"};
    const wide_bvh *w = acc[2]->impl;
    const size_t bytes = (size_t)w->num_inner * 8u * w->width * sizeof(float) + (size_t)w->num_blocks * sizeof(wide_tri4);
    const size_t N = 100000;
    tk_rayrec *all = malloc(N * sizeof *all);
    sidx_ray *r = malloc(N * sizeof *r);
    sidx_hit *one = malloc(N * sizeof *one), *many = malloc(N * sizeof *many);
    if (!all || !r || !one || !many) return 1;
    tk_make_rays(&m, diffuse ? TK_RAYS_DIFFUSE : TK_RAYS_PRIMARY, N, 7, all);
    for (size_t i = 0; i < N; ++i)
        sidx_ray_init(&r[i], sidx_v3(all[i].o[0], all[i].o[1], all[i].o[2]),
                      sidx_v3(all[i].d[0], all[i].d[1], all[i].d[2]), all[i].tmin, all[i].tmax);
    /* the hit check */
    for (size_t i = 0; i < N; ++i) sidx_accel_intersect(acc[1], &r[i], NULL, &one[i]);
    for (int k = 0; k < 3; ++k) {
        memset(many, 0xA5, N * sizeof *many);
        sidx_accel_intersect_n(acc[k], r, N, NULL, many);
        size_t bad = 0;
        for (size_t i = 0; i < N; ++i) bad += memcmp(&one[i], &many[i], sizeof one[i]) != 0;
        if (bad) {
            fprintf(stderr, "%s: %zu hits differ from single queries\n", name[k], bad);
            return 1;
        }
    }
    double on_off[64] = {0}, def_off[64] = {0}, off_mrays[64] = {0};
    for (int round = 0; round < rounds; ++round) {
        double best[3] = {1e30, 1e30, 1e30};
        for (int k = 0; k < 3; ++k) sidx_accel_intersect_n(acc[k], r, N, NULL, many);
        for (int pass = 0; pass < 3; ++pass)
            for (int k = 0; k < 3; ++k) {
                const double t0 = cpu_now();
                sidx_accel_intersect_n(acc[k], r, N, NULL, many);
                const double dt = cpu_now() - t0;
                if (dt < best[k]) best[k] = dt;
            }
        on_off[round] = best[0] / best[1];
        def_off[round] = best[2] / best[1];
        off_mrays[round] = (double)N / best[1] * 1e-6;
        printf("round %d: on/off %.3f default/off %.3f off %.2f Mrays/s\n", round, on_off[round], def_off[round],
               off_mrays[round]);
    }
    qsort(on_off, (size_t)rounds, sizeof *on_off, cmp_d);
    qsort(def_off, (size_t)rounds, sizeof *def_off, cmp_d);
    qsort(off_mrays, (size_t)rounds, sizeof *off_mrays, cmp_d);
    printf("%s %s: tree %.1f MiB, default %s; off %.2f Mrays/s; on/off %.2f [%.2f..%.2f]; default/off %.2f "
           "[%.2f..%.2f]\n",
           argv[1], argv[2], (double)bytes / (1024.0 * 1024.0), w->inflight ? "on" : "off", off_mrays[rounds / 2],
           on_off[rounds / 2], on_off[0], on_off[rounds - 1], def_off[rounds / 2], def_off[0], def_off[rounds - 1]);
    for (int k = 0; k < 3; ++k) sidx_accel_destroy(acc[k]);
    free(all), free(r), free(one), free(many);
    sidx_mesh_free(&m);
    return 0;
}
