/* 13_worst_case.c — the private exercise: a worst case for every structure.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Motivation" ("Can reduce
 * complexity to O(log n) on average — Worst case complexity is still O(n)
 * — Private exercise: Come up with a worst case example").
 *
 * What it shows: two answers to the exercise.  A "star": n large
 * triangles that all pass through one point, in random orientations — no
 * plane separates them near that point and no box around some of them is
 * smaller than the box around all, so a ray aimed at the point tests
 * almost every triangle in a BVH or a kd-tree.  A "speck": n tiny
 * triangles in one spot of a huge empty box — all in one cell of the
 * uniform grid.
 * For n = 128 ... 1024 the lesson measures the triangle tests per ray in a
 * BVH, a kd-tree and a uniform grid, and, for
 * contrast, the same counts on n random small triangles (a soup), where
 * the structures do their job.  The worst-case counts double when n
 * doubles: O(n).  The octree is measured too: on the star it keeps all n
 * triangles in one leaf — a cut there only copies triangles that span the
 * cell, which its duplication rule refuses — so its memory stays bounded
 * (lib/octree.c "Bounds": at most 64·n + 1 nodes whatever the scene) and
 * its queries pay instead: O(n) tests, like the trees.
 *
 * Read:  lib/bvh_traverse.c, stack_walk
 * Run:   build/lessons/13_worst_case [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply to use as the "good"
 *        contrast instead of the soup (its first n triangles are used)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include "sidx/sidx.h"
#include "lesson.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 13_worst_case [--help] [build knobs] [SCENE]\n"
               "\n"
               "A scene that makes the BVH, the kd-tree and the grid test O(n) triangles per ray: n big\n"
               "triangles through one point; triangle tests per ray as n doubles, against a soup.\n"
               "\n"
               "  SCENE   contrast scene (first n triangles): built-in name or .obj/.ply (default: soup)\n"
               "The knobs below change all four structures, each reading those it has: try whether a\n"
               "smaller leaf, a deeper tree or a finer grid gets the star below O(n).  The checks hold\n"
               "for the defaults.\n");
}

/* The build knobs of the command line (all zero: every structure's default). */
static sidx_build_options knobs;

static float lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

/* n equilateral triangles of circumradius 1 centred on the origin, each in
 * a random plane through it. */
static sidx_status make_star(uint32_t n, sidx_mesh *out, sidx_error *err)
{
    float *xyz = malloc((size_t)n * 9 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * 3 * sizeof *idx);
    if (!xyz || !idx) { free(xyz); free(idx); return SIDX_ERR_NOMEM; }
    uint32_t seed = 1234u;
    for (uint32_t i = 0; i < n; ++i) {
        const float z = 2 * lcg(&seed) - 1, ph = 6.2831853f * lcg(&seed), s = sqrtf(1 - z * z);
        const sidx_vec3 nrm = sidx_v3(s * cosf(ph), s * sinf(ph), z);
        sidx_vec3 a = sidx_v3_cross(nrm, fabsf(nrm.x) < 0.9f ? sidx_v3(1, 0, 0) : sidx_v3(0, 1, 0));
        a = sidx_v3_scale(a, 1.0f / sidx_v3_length(a));
        const sidx_vec3 b = sidx_v3_cross(nrm, a);
        const float rot = 6.2831853f * lcg(&seed);
        for (int k = 0; k < 3; ++k) {
            const float ang = rot + 2.0943951f * (float)k;
            const sidx_vec3 p = sidx_v3_add(sidx_v3_scale(a, cosf(ang)), sidx_v3_scale(b, sinf(ang)));
            xyz[9 * i + 3 * k] = p.x;
            xyz[9 * i + 3 * k + 1] = p.y;
            xyz[9 * i + 3 * k + 2] = p.z;
            idx[3 * i + (uint32_t)k] = 3 * i + (uint32_t)k;
        }
    }
    const sidx_status st = sidx_mesh_from_arrays(out, xyz, 3 * n, idx, n, err);
    free(xyz);
    free(idx);
    return st;
}

/* The uniform grid's worst case: n tiny triangles in a speck, and two more
 * at opposite corners of a huge box.  The resolution formula sees n
 * triangles in a huge volume: the speck falls into one cell. */
static sidx_status make_cluster(uint32_t n, sidx_mesh *out, sidx_error *err)
{
    const uint32_t total = n + 2;
    float *xyz = malloc((size_t)total * 9 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)total * 3 * sizeof *idx);
    if (!xyz || !idx) { free(xyz); free(idx); return SIDX_ERR_NOMEM; }
    uint32_t seed = 4321u;
    for (uint32_t i = 0; i < total; ++i) {
        sidx_vec3 c = sidx_v3(371.3f + 0.01f * lcg(&seed), 129.7f + 0.01f * lcg(&seed), -257.9f + 0.01f * lcg(&seed));
        if (i == n) c = sidx_v3(-1000, -1000, -1000);
        if (i == n + 1) c = sidx_v3(1000, 1000, 1000);
        for (int k = 0; k < 3; ++k) {
            xyz[9 * i + 3 * k] = c.x + 0.001f * lcg(&seed);
            xyz[9 * i + 3 * k + 1] = c.y + 0.001f * lcg(&seed);
            xyz[9 * i + 3 * k + 2] = c.z + 0.001f * lcg(&seed);
            idx[3 * i + (uint32_t)k] = 3 * i + (uint32_t)k;
        }
    }
    const sidx_status st = sidx_mesh_from_arrays(out, xyz, 3 * total, idx, total, err);
    free(xyz);
    free(idx);
    return st;
}

/* The first n triangles of a mesh (all its vertices, as x, y, z floats). */
static sidx_status first_n(const sidx_mesh *m, uint32_t n, sidx_mesh *out, sidx_error *err)
{
    if (n > m->num_triangles) n = m->num_triangles;
    float *xyz = malloc((size_t)m->num_vertices * 3 * sizeof *xyz);
    if (!xyz) return SIDX_ERR_NOMEM;
    for (uint32_t v = 0; v < m->num_vertices; ++v) sidx_v3_to_array(m->positions[v], &xyz[3 * v]);
    const sidx_status st = sidx_mesh_from_arrays(out, xyz, m->num_vertices, m->indices, n, err);
    free(xyz);
    return st;
}

/* Triangle tests per ray for rays from random directions aimed at `target`
 * (plus a small random offset of `jitter`). */
static double tests_per_ray(const char *name, const sidx_mesh *m, sidx_vec3 target, float jitter, float dist,
                            int *ok)
{
    sidx_accel *a = NULL;
    sidx_error err = {0};
    if (sidx_accel_build(name, m, &knobs, &a, &err) != SIDX_OK) {
        fprintf(stderr, "13_worst_case: %s: %s\n", name, err.message);
        *ok = 0;
        return 0.0;
    }
    sidx_counters c;
    sidx_counters_init(&c);
    const sidx_hook ch = sidx_counters_hook(&c);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ch, 0};
    uint32_t seed = 99u;
    const int nr = 200;
    for (int i = 0; i < nr; ++i) {
        const float z = 2 * lcg(&seed) - 1, ph = 6.2831853f * lcg(&seed), s = sqrtf(1 - z * z);
        const sidx_vec3 o = sidx_v3_add(target, sidx_v3(dist * s * cosf(ph), dist * s * sinf(ph), dist * z));
        const sidx_vec3 t = sidx_v3_add(target, sidx_v3(jitter * (lcg(&seed) - 0.5f), jitter * (lcg(&seed) - 0.5f),
                                                        jitter * (lcg(&seed) - 0.5f)));
        sidx_ray r;
        if (sidx_ray_init(&r, o, sidx_v3_sub(t, o), 0.0f, INFINITY) != SIDX_OK) continue;
        sidx_hit h;
        sidx_accel_intersect(a, &r, &q, &h);
    }
    sidx_accel_destroy(a);
    return (double)c.n[SIDX_EV_PRIM_TEST] / nr;
}

int main(int argc, char **argv)
{
    const lesson_option options[] = {LESSON_KNOBS(knobs), {0}};
    lesson_args args = {.name = "13_worst_case", .usage = usage, .scene = "soup:1024", .options = options};
    lesson_parse(&args, argc, argv);
    static const char *const names[4] = {"bvh", "kdtree", "grid", "octree"};
    for (int s = 0; s < 4; ++s) lesson_need(&args, names[s]);
    const int nstruct = 4;
    sidx_mesh good_src = lesson_open_scene(&args);
    sidx_error err = {0};
    static const uint32_t ns[4] = {128, 256, 512, 1024};
    double star[4][4], good[4][4], clus[4][4];
    int ok = 1;

    /* one traced ray in the smallest star, through the BVH, hits and totals only */
    {
        sidx_mesh m;
        if (make_star(ns[0], &m, &err) != SIDX_OK) { fprintf(stderr, "13_worst_case: cannot make the star\n"); return 1; }
        sidx_accel *a = NULL;
        if (sidx_accel_build("bvh", &m, &knobs, &a, &err) == SIDX_OK) {
            printf("== A star of %u triangles through the origin; one ray at it through the BVH\n", ns[0]);
            sidx_printer pr;
            sidx_printer_init(&pr, stdout);
            pr.mask = SIDX_EVMASK(SIDX_EV_RAY_BEGIN) | SIDX_EVMASK(SIDX_EV_HIT_UPDATE) |
                      SIDX_EVMASK(SIDX_EV_TERMINATE) | SIDX_EVMASK(SIDX_EV_RAY_END);
            sidx_counters c;
            sidx_counters_init(&c);
            sidx_tee tee = {{sidx_printer_hook(&pr), sidx_counters_hook(&c)}, 2};
            const sidx_hook th = sidx_tee_hook(&tee);
            sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &th, 0};
            sidx_ray r;
            sidx_ray_init(&r, sidx_v3(0.3f, 0.4f, 3.0f), sidx_v3(-0.3f, -0.4f, -3.0f), 0.0f, INFINITY);
            sidx_hit h;
            sidx_accel_intersect(a, &r, &q, &h);
            printf("  -> %llu of %u triangles tested, %llu boxes\n", (unsigned long long)c.n[SIDX_EV_PRIM_TEST], ns[0],
                   (unsigned long long)c.n[SIDX_EV_BOX_TEST]);
            sidx_accel_destroy(a);
        }
        sidx_mesh_free(&m);
    }

    for (int k = 0; k < 4 && ok; ++k) {
        sidx_mesh m, g, cl;
        if (make_star(ns[k], &m, &err) != SIDX_OK) { ok = 0; break; }
        if (make_cluster(ns[k], &cl, &err) != SIDX_OK) { sidx_mesh_free(&m); ok = 0; break; }
        if (first_n(&good_src, ns[k], &g, &err) != SIDX_OK) { sidx_mesh_free(&m); sidx_mesh_free(&cl); ok = 0; break; }
        const sidx_aabb gb = sidx_mesh_bounds(&g);
        const float gd = sidx_v3_length(sidx_aabb_extent(gb));
        for (int s = 0; s < nstruct && ok; ++s) {
            star[s][k] = tests_per_ray(names[s], &m, sidx_v3(0, 0, 0), 0.05f, 3.0f, &ok);
            good[s][k] = tests_per_ray(names[s], &g, sidx_aabb_centroid(gb), 0.5f * gd, 1.5f * gd, &ok);
            clus[s][k] = tests_per_ray(names[s], &cl, sidx_v3(371.305f, 129.705f, -257.895f), 0.008f, 3.0f, &ok);
        }
        sidx_mesh_free(&cl);
        sidx_mesh_free(&m);
        sidx_mesh_free(&g);
    }
    sidx_mesh_free(&good_src);
    if (!ok) return 1;

    printf("\n== Triangle tests per ray (200 rays each), as n doubles\n");
    printf("  %-8s %-10s", "", "scene");
    for (int k = 0; k < 4; ++k) printf(" %9u", ns[k]);
    printf("   %s\n", "1024 vs 128");
    int linear = 1;
    for (int s = 0; s < nstruct; ++s)
        for (int which = 0; which < 3; ++which) {
            const double *v = which == 0 ? star[s] : which == 1 ? clus[s] : good[s];
            const char *label = which == 0 ? "star" : which == 1 ? "speck" : args.scene_given ? "contrast" : "soup";
            printf("  %-8s %-10s", which ? "" : names[s], label);
            for (int k = 0; k < 4; ++k) printf(" %9.1f", v[k]);
            const double growth = v[0] > 0 ? v[3] / v[0] : 0.0;
            /* the worst case of each: the star for the trees and the octree, the speck for the grid */
            const int worst = (s != 2 && which == 0) || (s == 2 && which == 1);
            printf("   x%.1f%s\n", growth, worst ? "   <- its worst case: O(n)" : "");
            if (worst && growth < 4.0) linear = 0; /* 8x the triangles: at least half-linear growth */
        }
    printf("\n  n grew 8x.  star: n big triangles through one point — near it every box of the BVH\n"
           "  and every cell of the kd-tree holds nearly all of them, nothing can be eliminated.\n"
           "  speck: n tiny triangles in one spot of a huge, otherwise empty box — the grid's\n"
           "  resolution comes from the whole box, so they all share one cell (the trees adapt and\n"
           "  do not care).  The octree keeps the star in one leaf (cutting it only copies\n"
           "  triangles that span the cell; its node count is capped at 64 n + 1 anyway), and the\n"
           "  speck lies below its depth limit of 16 halvings of a 2000-unit box: O(n) on both.\n"
           "  Each structure has its O(n) scene; on the soup they barely notice n.\n");
    lesson_check("worst_cases_linear", linear);
    return 0;
}
