/* 26_bvh_optimise.c — a built BVH made better: reinsertion.
 *
 * Slides (deck 001, "Spatial Data Structures"): "Surface Area Heuristic"
 * and "BVH Review".  A top-down build picks each split once, greedily;
 * reinsertion (Bittner, Hapala & Havran 2013, "Fast insertion-based
 * optimization of bounding volume hierarchies") takes subtrees out of the
 * finished tree and puts each back where the SAH says it costs least
 * (lib/bvh_optimize.c, opt.optimize_ms).
 *
 * What it shows:
 *   1. the pass at work, from its own build_reinsert events: the first
 *      moves, then per pass the moves made and the SAH cost they removed;
 *   2. the tree before and after: SAH cost (stats), and what rays pay —
 *      nodes visited and triangles tested per ray, counted, same hits.
 *
 * Read:  lib/bvh_optimize.c, sidx__bvh_optimize
 * Run:   build/lessons/26_bvh_optimise [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "lesson.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 26_bvh_optimise [--help] [build knobs] [SCENE]\n"
               "\n"
               "Reinsertion over a built binary BVH: the moves it makes (its build_reinsert\n"
               "events), the SAH cost before and after, and the work per ray it saves.\n"
               "\n"
               "  SCENE   built-in name or .obj/.ply (default: teapot)\n"
               "The knobs below change the tree that is optimised (--optimize MS: the pass's time\n"
               "budget, default here 10000 ms, which it never needs).  The checks hold for the defaults.\n");
}

static sidx_build_options knobs;

#define NRAYS 20000
#define MAX_PASSES 16
static sidx_ray rays[NRAYS];
static sidx_hit hits[2][NRAYS];

typedef struct {
    uint32_t moves[MAX_PASSES + 1];
    double gain[MAX_PASSES + 1];
    uint32_t shown, total;
} pass_log;

static void on_reinsert(const sidx_event *e, void *user)
{
    pass_log *L = user;
    const uint32_t p = e->count <= MAX_PASSES ? e->count : MAX_PASSES;
    L->moves[p]++;
    L->gain[p] += e->cost;
    L->total++;
    if (L->shown++ < 5) {
        char line[256];
        sidx_event_format(e, line, sizeof line);
        printf("  %s\n", line);
    }
}

int main(int argc, char **argv)
{
    const lesson_option options[] = {LESSON_BVH_KNOBS(knobs), {"--optimize", .build = &knobs}, {0}};
    lesson_args args = {.name = "26_bvh_optimise", .usage = usage, .scene = "teapot", .options = options,
                        .refused = LESSON_BVH_ONLY};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");
    sidx_mesh m = lesson_open_scene(&args);
    sidx_error err = {0};

    sidx_accel *a[2] = {NULL, NULL};
    sidx_build_options bo = knobs;
    bo.optimize_ms = 0.0f;
    double t0 = lesson_seconds();
    if (sidx_accel_build("bvh", &m, &bo, &a[0], &err) != SIDX_OK) lesson_fail(&args, err.message);
    const double ms_plain = 1e3 * (lesson_seconds() - t0);

    printf("== 1. Reinsertion on %s (%u triangles): the first moves, as the build reports them\n", args.scene,
           m.num_triangles);
    pass_log L;
    memset(&L, 0, sizeof L);
    const sidx_hook h = {on_reinsert, &L, SIDX_EVMASK(SIDX_EV_BUILD_REINSERT)};
    bo.optimize_ms = knobs.optimize_ms > 0.0f ? knobs.optimize_ms : 10000.0f;
    bo.hook = &h;
    t0 = lesson_seconds();
    if (sidx_accel_build("bvh", &m, &bo, &a[1], &err) != SIDX_OK) lesson_fail(&args, err.message);
    const double ms_opt = 1e3 * (lesson_seconds() - t0);

    sidx_accel_stats s[2];
    sidx_accel_stats_get(a[0], &s[0]);
    sidx_accel_stats_get(a[1], &s[1]);
    printf("  (node ids of the tree as built; parent = the inner node taken out and re-made over the\n"
           "  subtree and its new neighbour; SAH -x = the expected cost the move removes)\n\n");
    printf("  %-6s %8s %14s\n", "pass", "moves", "SAH removed");
    double sum = 0.0;
    for (int p = 1; p <= MAX_PASSES; ++p) {
        if (!L.moves[p]) continue;
        printf("  %-6d %8u %14.4f\n", p, L.moves[p], L.gain[p]);
        sum += L.gain[p];
    }
    printf("  Each pass tries every node once, largest box first; the pass stops when one gains less\n"
           "  than 0.1%% of the inner nodes' area.  Leaves keep their triangles: only the tree above\n"
           "  them changes, so the SAH's leaf terms stay and only the inner nodes' areas fall.\n");

    printf("\n== 2. The tree before and after (%d random rays into the scene's box)\n", NRAYS);
    lesson_rays_into_box(sidx_mesh_bounds(&m), rays, NRAYS, 26u);
    printf("  %-10s %10s %10s %12s %12s %10s\n", "", "SAH cost", "depth", "nodes/ray", "tris/ray", "build ms");
    double nodes[2], tris[2];
    for (int k = 0; k < 2; ++k) {
        sidx_counters c;
        lesson_count_rays(a[k], rays, NRAYS, &c, hits[k]);
        nodes[k] = (double)c.n[SIDX_EV_NODE_ENTER] / NRAYS;
        tris[k] = (double)c.n[SIDX_EV_PRIM_TEST] / NRAYS;
        printf("  %-10s %10.3f %10u %12.2f %12.2f %10.1f\n", k ? "optimised" : "as built", s[k].sah_cost,
               s[k].max_depth, nodes[k], tris[k], k ? ms_opt : ms_plain);
    }
    int same = 1;
    for (int i = 0; i < NRAYS; ++i)
        same &= hits[0][i].prim == hits[1][i].prim || hits[0][i].t == hits[1][i].t;
    printf("  The SAH predicts the work of rays spread over the scene's box; the counts are those\n"
           "  rays' real work.  %u moves removed %.2f%% of the expected cost.\n",
           L.total, 100.0 * (s[0].sah_cost - s[1].sah_cost) / s[0].sah_cost);

    lesson_check("sah_lower", s[1].sah_cost < s[0].sah_cost);
    lesson_check("events_sum_to_gain", fabs(sum - (s[0].sah_cost - s[1].sah_cost)) <= 1e-3 * s[0].sah_cost);
    lesson_check("same_hits", same);
    sidx_accel_destroy(a[0]);
    sidx_accel_destroy(a[1]);
    sidx_mesh_free(&m);
    return 0;
}
