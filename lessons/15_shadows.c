/* 15_shadows.c — shadow rays: any-hit, the light buffer, ray classification.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Directional
 * Partitioning" ("Useful only for rays that start from a single point —
 * camera, point light sources ... Variation: Light buffer (for shadow
 * rays) — Lazy and conservative evaluation — Store last found occluder in
 * directional structure — Test entry first for next shadow test") and "Ray
 * Classification" ("Partitioning of space and direction [Arvo & Kirk'87]
 * ... Very costly preprocessing, cheap traversal — Improper trade-off
 * between preprocessing and run-time — Memory hungry, even with lazy
 * evaluation — Seldom used in practice").  Deck 000: "kD-Tree Traversal"
 * for the any-hit early exit ("traversal can be terminated as soon as
 * surface intersection is found").
 *
 * What it shows, on a scene with a point light (default: the Cornell box,
 * light under the ceiling), for shadow rays from points all over its
 * surfaces, visited triangle by triangle so that neighbouring queries look
 * in similar directions:
 *   1. one shadow query through the printer, in the BVH (any hit) and in
 *      the light buffer (the cell, the cached occluder tested first);
 *   2. per shadow query: closest hit vs any hit in a BVH, and the light
 *      buffer with and without its last-occluder cache — triangle and box
 *      tests, time, and whether all agree;
 *   3. ray classification against the BVH for closest hits: preprocessing
 *      time, memory, time per ray.
 *
 * Read:  lib/lightbuffer.c, sidx_lightbuffer_occluded;
 *        lib/rayclass.c, rc_query
 * Run:   build/lessons/15_shadows [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default cornell); the
 *        light is put at 90% of the box height above its centre
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "sidx/sidx.h"
#include "lesson.h"
#include "sidx/lightbuffer.h"
#include "sidx/rayclass.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 15_shadows [--help] [build knobs] [SCENE]\n"
               "\n"
               "Shadow rays: closest hit vs any hit, the light buffer with its last-occluder cache,\n"
               "and ray classification's preprocessing and memory against its speed.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: cornell)\n"
               "The knobs below change the BVHs of parts 1-3; --leaf-size and --max-depth also ray\n"
               "classification's cells.  The light buffer keeps its 32 x 32 faces.  The checks hold\n"
               "for the defaults.\n");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static float lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

#define NP 20000
static sidx_vec3 pts[NP];
static sidx_ray srays[NP];
static unsigned char answer[4][NP];

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_BVH_KNOBS(knobs), {0}};
    lesson_args args = {.name = "15_shadows",
                        .usage = usage,
                        .scene = "cornell",
                        .options = options,
                        .refused = "no grid or kd-tree is built here"};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");
    lesson_need(&args, "rayclass");
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const sidx_vec3 light = sidx_v3(ctr.x + 0.03f * ext.x, box.min.y + 0.9f * ext.y, ctr.z + 0.02f * ext.z);

    /* points on the surfaces, triangle after triangle */
    uint32_t seed = 9u;
    const uint32_t per = (NP + mesh.num_triangles - 1) / mesh.num_triangles;
    int np = 0;
    for (uint32_t t = 0; t < mesh.num_triangles && np < NP; ++t)
        for (uint32_t k = 0; k < per && np < NP; ++k) {
            float u = lcg(&seed), v = lcg(&seed);
            if (u + v > 1) { u = 1 - u; v = 1 - v; }
            const sidx_vec3 a = sidx_mesh_vertex(&mesh, t, 0), b = sidx_mesh_vertex(&mesh, t, 1),
                            c = sidx_mesh_vertex(&mesh, t, 2);
            pts[np++] = sidx_v3_add(a, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(b, a), u), sidx_v3_scale(sidx_v3_sub(c, a), v)));
        }
    /* The points lie on the surfaces, so the shadow rays skip the first
     * and last 1e-3 of the way: the epsilon hack, kept here because the
     * light buffer takes points, not hits.  Lesson 24 measures where the
     * constant fails (tiny and far-away scenes) and sidx_ray_spawn_to,
     * which replaces it for hits. */
    const float tmin = 1e-3f, tmax = 1.0f - 1e-3f;

    sidx_accel *bvh = NULL;
    sidx_lightbuffer *lb = NULL;
    if (sidx_accel_build("bvh", &mesh, &knobs, &bvh, &err) != SIDX_OK ||
        sidx_lightbuffer_build(&mesh, light, 32, 0, NULL, &lb, &err) != SIDX_OK) {
        fprintf(stderr, "15_shadows: %s\n", err.message);
        sidx_accel_destroy(bvh);
        sidx_mesh_free(&mesh);
        return 1;
    }
    for (int i = 0; i < np; ++i) sidx_lightbuffer_shadow_ray(lb, pts[i], tmin, tmax, &srays[i]);
    printf("== '%s': %u triangles; point light at (%g, %g, %g); %d shadow rays from its surfaces\n", args.scene,
           mesh.num_triangles, light.x, light.y, light.z, np);

    /* ---- 1. one query, traced ---- */
    int pick = 0;
    for (int i = 0; i < np; ++i) {
        int occ = 0;
        sidx_accel_occluded(bvh, &srays[i], NULL, &occ);
        if (occ) { pick = i; break; }
    }
    printf("\n== 1. The shadow ray of the point (%g, %g, %g), towards the light\n", pts[pick].x, pts[pick].y,
           pts[pick].z);
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    const sidx_hook ph = sidx_printer_hook(&pr);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ph, 0};
    int occ = 0;
    printf("  BVH, any hit:\n");
    sidx_accel_occluded(bvh, &srays[pick], &q, &occ);
    sidx_lightbuffer_cache cache;
    sidx_lightbuffer_cache_init(lb, &cache);
    printf("  light buffer (first query: the cell is filled lazily):\n");
    sidx_lightbuffer_occluded(lb, pts[pick], tmin, tmax, &cache, &q, &occ);
    printf("  light buffer, same point again (the cached occluder is tested first):\n");
    sidx_lightbuffer_occluded(lb, pts[pick], tmin, tmax, &cache, &q, &occ);
    sidx_lightbuffer_cache_free(&cache);

    /* ---- 2. all queries ---- */
    printf("\n== 2. %d shadow queries\n", np);
    const char *label[4] = {"BVH closest hit", "BVH any hit", "light buffer, no cache", "light buffer + cache"};
    double tests[4], boxes[4], us[4];
    uint64_t cache_hits = 0, cache_tests = 0;
    for (int m = 0; m < 4; ++m) {
        sidx_counters c;
        sidx_counters_init(&c);
        const sidx_hook ch = sidx_counters_hook(&c);
        sidx_query cq = {0, SIDX_TRAVERSE_DEFAULT, &ch, 0};
        double best = INFINITY;
        for (int pass = 0; pass < 4; ++pass) {
            sidx_lightbuffer_cache lc;
            sidx_lightbuffer_cache_init(lb, &lc);
            const sidx_query *qq = pass == 0 ? &cq : NULL;
            const double t0 = now_s();
            for (int i = 0; i < np; ++i) {
                int o = 0;
                if (m == 0) {
                    sidx_hit h;
                    sidx_accel_intersect(bvh, &srays[i], qq, &h);
                    o = h.prim != SIDX_NO_HIT;
                } else if (m == 1) {
                    sidx_accel_occluded(bvh, &srays[i], qq, &o);
                } else {
                    sidx_lightbuffer_occluded(lb, pts[i], tmin, tmax, m == 3 ? &lc : NULL, qq, &o);
                }
                if (pass == 0) answer[m][i] = (unsigned char)o;
            }
            const double dt = now_s() - t0;
            if (pass > 0 && dt < best) best = dt; /* pass 0 is traced (and fills the lazy cells) */
            if (pass == 0 && m == 3) { cache_hits = lc.cache_hits; cache_tests = lc.cache_tests; }
            sidx_lightbuffer_cache_free(&lc);
        }
        tests[m] = (double)c.n[SIDX_EV_PRIM_TEST] / np;
        boxes[m] = (double)(c.n[SIDX_EV_BOX_TEST] + c.n[SIDX_EV_NODE_ENTER]) / np;
        us[m] = 1e6 * best / np;
    }
    int same = 1;
    long shadowed = 0;
    for (int i = 0; i < np; ++i) {
        shadowed += answer[1][i];
        for (int m = 0; m < 4; ++m) same &= answer[m][i] == answer[1][i];
    }
    printf("  %-24s %12s %16s %11s\n", "", "tri tests", "boxes / cells", "us/query");
    for (int m = 0; m < 4; ++m) printf("  %-24s %12.2f %16.2f %11.3f\n", label[m], tests[m], boxes[m], us[m]);
    printf("  %ld of %d points are in shadow; all four agree on every point: %s\n", shadowed, np, same ? "yes" : "NO");
    printf("  the cache: %llu queries tried the last occluder first, %llu of them were answered by it\n",
           (unsigned long long)cache_tests, (unsigned long long)cache_hits);
    sidx_lightbuffer_stats ls;
    sidx_lightbuffer_stats_get(lb, &ls);
    printf("  light buffer: %u of %u cells filled lazily, %llu references, %.1f KiB\n", ls.cells_filled, ls.cells,
           (unsigned long long)ls.refs, ls.bytes / 1024.0);

    /* ---- 3. ray classification ---- */
    printf("\n== 3. Ray classification (5D: origin x direction) vs the BVH, closest hits of the same rays\n");
    sidx_accel *rc = NULL;
    double build[2];
    double t0 = now_s();
    sidx_accel *bvh2 = NULL;
    if (sidx_accel_build("bvh", &mesh, &knobs, &bvh2, &err) != SIDX_OK) { fprintf(stderr, "15_shadows: %s\n", err.message); return 1; }
    build[0] = now_s() - t0;
    t0 = now_s();
    if (sidx_accel_build("rayclass", &mesh, &knobs, &rc, &err) != SIDX_OK) {
        fprintf(stderr, "15_shadows: %s\n", err.message);
        return 1;
    }
    build[1] = now_s() - t0;
    sidx_accel *pair[2] = {bvh2, rc};
    double per_ray[2];
    int same_rc = 1;
    for (int s = 0; s < 2; ++s) {
        double best = INFINITY;
        for (int pass = 0; pass < 3; ++pass) {
            const double t1 = now_s();
            for (int i = 0; i < np; ++i) {
                sidx_hit h;
                sidx_accel_intersect(pair[s], &srays[i], NULL, &h);
                if (pass == 0 && (h.prim != SIDX_NO_HIT) != answer[0][i]) same_rc = 0;
            }
            if (now_s() - t1 < best) best = now_s() - t1;
        }
        per_ray[s] = 1e6 * best / np;
    }
    sidx_accel_stats sb, sr;
    sidx_accel_stats_get(bvh2, &sb);
    sidx_accel_stats_get(rc, &sr);
    sidx_rayclass_info ri;
    sidx_rayclass_info_get(rc, &ri);
    printf("  %-10s %12s %14s %12s\n", "", "build ms", "memory KiB", "us per ray");
    printf("  %-10s %12.2f %14.1f %12.3f\n", "bvh", 1e3 * build[0], sb.bytes / 1024.0, per_ray[0]);
    printf("  %-10s %12.2f %14.1f %12.3f\n", "rayclass", 1e3 * build[1], sr.bytes / 1024.0, per_ray[1]);
    printf("  rayclass: %u nodes, %u leaves, %llu candidate references (%.1f per leaf, up to %u), %llu beam-box\n"
           "  tests while building.  Same answers as the BVH: %s\n",
           ri.nodes, ri.leaves, (unsigned long long)ri.candidates, ri.mean_candidates, ri.max_candidates,
           (unsigned long long)ri.beam_tests, same_rc ? "yes" : "NO");
    printf("  The deck's verdict, measured: %.0fx the memory and %.0fx the build time of a BVH, for %.2fx its\n"
           "  speed per ray.\n",
           (double)sr.bytes / (double)sb.bytes, build[1] / build[0], per_ray[0] / per_ray[1]);
    sidx_accel_destroy(rc);
    sidx_accel_destroy(bvh2);
    sidx_accel_destroy(bvh);
    sidx_lightbuffer_destroy(lb);
    sidx_mesh_free(&mesh);
    lesson_check("same_answers", same && same_rc);
    lesson_check("any_hit_cheaper", tests[1] + boxes[1] < tests[0] + boxes[0]);
    lesson_check("light_buffer_saves", cache_hits > 0 && tests[3] < tests[2]);
    return 0;
}
