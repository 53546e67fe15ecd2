/* 17_oriented_bvh.c — the non-axis-aligned BVH: faster? "Yes, and no."
 *
 * Slides (deck 001, "Axis-Aligned BVH"): "How do we make a
 * non-axis-aligned BVH? ... [+] Nodes have less likelihood of having empty
 * space, [-] Larger intersection cost for non-aligned bboxes, [-] More
 * memory overhead" and "Are non-axis-aligned BVHs actually faster? Yes,
 * and no.  Surface area ratio S_A/S_C decreases with better-fitting bboxes;
 * bounding box intersection cost C_trav increases".  Deck 000, "Bounding
 * Volumes": the oriented box is "often better fit, fairly complex
 * computation".
 *
 * "bvh-obb" has the very same tree as "bvh" (binned SAH topology); only
 * the box of every node is replaced by an oriented one (PCA axes, or the
 * AABB where that is smaller).  So the two columns below differ by the box
 * alone.  What it shows, on the default scene and on the same scene turned
 * off the axes, then on a triangle soup:
 *   1. one ray's first steps in both trees, through the printer: the same
 *      nodes, but the oriented boxes reject some the AABBs let through;
 *   2. the cost of one box test alone: the slab test against an AABB
 *      (sidx_intersect_aabb) and against an oriented box
 *      (sidx_intersect_obb, three dot products more per axis), ns per test;
 *   3. per ray: box tests, triangle tests, time; per tree: memory — the
 *      SAH's two terms, one falling and one rising.
 * Times are printed, never checked: whether fewer, dearer tests win
 * depends on the machine and the scene — the slide's "yes, and no".
 *
 * Read:  lib/bvh_obb.c, sidx__bvh_fit_obbs
 * Run:   build/lessons/17_oriented_bvh [SCENE]
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
    fprintf(f, "usage: 17_oriented_bvh [--help] [build knobs] [SCENE]\n"
               "\n"
               "The oriented-box BVH (bvh-obb) against the axis-aligned one (bvh) on the same tree:\n"
               "box tests per ray, ns per box test, memory, time per ray; on SCENE, on SCENE\n"
               "rotated off the axes, and on a triangle soup.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "The knobs below change the binned-SAH tree both BVHs share (the oriented one keeps its\n"
               "topology), so the two still differ only in their boxes.  The checks hold for the\n"
               "defaults.\n");
}

/* The build knobs of the command line (all zero: the BVH's defaults). */
static sidx_build_options knobs;

#define NRAYS 10000
static sidx_ray rays[NRAYS];
static sidx_hit hit_aabb[NRAYS], hit_obb[NRAYS];

/* A copy of m turned by 35 degrees about z, then 50 about x: the same
 * shape, no longer lined up with the axes the AABBs are tied to. */
static sidx_mesh rotated(const lesson_args *args, const sidx_mesh *m)
{
    const float a = 0.6108652f, b = 0.8726646f;
    const float ca = cosf(a), sa = sinf(a), cb = cosf(b), sb = sinf(b);
    float *xyz = malloc(3u * (size_t)m->num_vertices * sizeof *xyz);
    if (!xyz) lesson_fail(args, "out of memory");
    for (uint32_t i = 0; i < m->num_vertices; ++i) {
        const sidx_vec3 p = m->positions[i];
        const float x = ca * p.x - sa * p.y, y = sa * p.x + ca * p.y, z = p.z;
        xyz[3 * i] = x;
        xyz[3 * i + 1] = cb * y - sb * z;
        xyz[3 * i + 2] = sb * y + cb * z;
    }
    sidx_mesh out;
    memset(&out, 0, sizeof out);
    const sidx_status s = sidx_mesh_from_arrays(&out, xyz, m->num_vertices, m->indices, m->num_triangles, NULL);
    free(xyz);
    if (s != SIDX_OK) lesson_fail(args, "cannot copy the mesh");
    return out;
}

typedef struct {
    double boxes, tris, nodes, us;
    size_t bytes;
    int same;
} row;

static int same_hit(const sidx_hit *a, const sidx_hit *b)
{
    return a->prim == b->prim && (a->t == b->t || (isinf(a->t) && isinf(b->t)));
}

/* Both trees over m, counted and timed on the same rays. */
static void compare(const lesson_args *args, const sidx_mesh *m, const char *label, row out[2])
{
    static const char *const names[2] = {"bvh", "bvh-obb"};
    sidx_hit *hits[2] = {hit_aabb, hit_obb};
    lesson_rays_into_box(sidx_mesh_bounds(m), rays, NRAYS, 17u);
    for (int s = 0; s < 2; ++s) {
        sidx_accel *a = NULL;
        sidx_error err = {0};
        if (sidx_accel_build(names[s], m, &knobs, &a, &err) != SIDX_OK) lesson_fail(args, err.message);
        sidx_counters c;
        lesson_count_rays(a, rays, NRAYS, &c, hits[s]);
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        out[s].boxes = (double)c.n[SIDX_EV_BOX_TEST] / NRAYS;
        out[s].tris = (double)c.n[SIDX_EV_PRIM_TEST] / NRAYS;
        out[s].nodes = (double)c.n[SIDX_EV_NODE_ENTER] / NRAYS;
        out[s].us = lesson_us_per_ray(a, rays, NRAYS, 5);
        out[s].bytes = st.bytes;
        sidx_accel_destroy(a);
    }
    out[0].same = out[1].same = 1;
    for (int i = 0; i < NRAYS; ++i) out[1].same &= same_hit(&hit_aabb[i], &hit_obb[i]);
    for (int s = 0; s < 2; ++s)
        printf("  %-26s %-8s %10.2f %10.2f %9.2f %10.3f %11.1f\n", s ? "" : label, names[s], out[s].boxes, out[s].tris,
               out[s].nodes, out[s].us, out[s].bytes / 1024.0);
}

/* ---- 2: one box test alone ---- */
#define NBOX 256
#define NTEST_RAYS 256

static double ns_per_test(const sidx_aabb *ab, const sidx_obb *ob, int oriented, long *hits)
{
    double best = INFINITY;
    long h = 0;
    for (int pass = 0; pass < 5; ++pass) {
        h = 0;
        const double t0 = lesson_seconds();
        for (int r = 0; r < NTEST_RAYS; ++r)
            for (int b = 0; b < NBOX; ++b) {
                float tn, tf;
                h += oriented ? sidx_intersect_obb(&rays[r], &ob[b], 0.0f, INFINITY, &tn, &tf)
                              : sidx_intersect_aabb(SIDX_BOX_ROBUST, &rays[r], &ab[b], 0.0f, INFINITY, &tn, &tf);
            }
        const double dt = lesson_seconds() - t0;
        if (dt < best) best = dt;
    }
    *hits = h;
    return 1e9 * best / ((double)NTEST_RAYS * NBOX);
}

/* Prints the box tests of one ray: node, result. */
static void box_line(const sidx_event *ev, void *user)
{
    int *n = user;
    if (ev->type != SIDX_EV_BOX_TEST || *n >= 10) return;
    printf("%s node %u %s", *n == 0 ? "" : *n % 5 ? "," : ",\n          ", ev->node, ev->result ? "hit" : "miss");
    ++*n;
}

int main(int argc, char **argv)
{
    const lesson_option options[] = {LESSON_BVH_KNOBS(knobs), {0}};
    lesson_args args = {.name = "17_oriented_bvh",
                        .usage = usage,
                        .scene = "teapot",
                        .options = options,
                        .refused = LESSON_BVH_ONLY};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");
    lesson_need(&args, "bvh-obb");
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_mesh turned = rotated(&args, &mesh);
    sidx_mesh soup = lesson_open(&args, "soup:4000");
    sidx_error err = {0};

    /* ---- 1 ---- */
    printf("== 1. One ray, the first box tests in each tree (same nodes, different boxes) on '%s' turned\n", args.scene);
    lesson_rays_into_box(sidx_mesh_bounds(&turned), rays, NRAYS, 17u);
    sidx_accel *t[2] = {NULL, NULL};
    if (sidx_accel_build("bvh", &turned, &knobs, &t[0], &err) != SIDX_OK ||
        sidx_accel_build("bvh-obb", &turned, &knobs, &t[1], &err) != SIDX_OK)
        lesson_fail(&args, err.message);
    int pick = 0, most = 0; /* the ray whose box tests differ most */
    for (int i = 0; i < 2000; ++i) {
        sidx_counters c[2];
        sidx_hit h;
        for (int s = 0; s < 2; ++s) lesson_count_rays(t[s], &rays[i], 1, &c[s], &h);
        const int d = (int)c[0].n[SIDX_EV_BOX_TEST] - (int)c[1].n[SIDX_EV_BOX_TEST];
        if (h.prim != SIDX_NO_HIT && d > most && c[0].n[SIDX_EV_BOX_TEST] <= 40) { most = d; pick = i; }
    }
    int trace_fewer = 0;
    for (int s = 0; s < 2; ++s) {
        int n = 0;
        sidx_counters c;
        lesson_count_rays(t[s], &rays[pick], 1, &c, NULL);
        const sidx_hook h = {box_line, &n, SIDX_EVMASK(SIDX_EV_BOX_TEST)};
        const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &h, 0};
        sidx_hit hit;
        printf("  %-8s", s ? "bvh-obb" : "bvh");
        sidx_accel_intersect(t[s], &rays[pick], &q, &hit);
        printf("%s\n           %llu box tests in all, hit triangle %u at t = %g\n", n >= 10 ? ", ..." : "",
               (unsigned long long)c.n[SIDX_EV_BOX_TEST], hit.prim, hit.t);
        trace_fewer = s ? trace_fewer - (int)c.n[SIDX_EV_BOX_TEST] : (int)c.n[SIDX_EV_BOX_TEST];
    }
    sidx_accel_destroy(t[0]);
    sidx_accel_destroy(t[1]);

    /* ---- 2 ---- */
    printf("\n== 2. One box test alone: %d rays x %d boxes, each around 16 neighbouring triangles of '%s' turned\n",
           NTEST_RAYS, NBOX, args.scene);
    sidx_aabb *ab = malloc(NBOX * sizeof *ab);
    sidx_obb *ob = malloc(NBOX * sizeof *ob);
    sidx_vec3 *pts = malloc(3u * 64u * sizeof *pts);
    if (!ab || !ob || !pts) lesson_fail(&args, "out of memory");
    for (uint32_t b = 0; b < NBOX; ++b) { /* runs of 16 triangles in mesh order: strips of the surface */
        uint32_t np = 0;
        const uint32_t first = (uint32_t)((uint64_t)b * turned.num_triangles / NBOX);
        for (uint32_t k = 0; k < 16; ++k)
            for (int v = 0; v < 3; ++v) pts[np++] = sidx_mesh_vertex(&turned, (first + k) % turned.num_triangles, v);
        if (sidx_aabb_fit(pts, np, &ab[b]) != SIDX_OK || sidx_obb_fit(pts, np, &ob[b]) != SIDX_OK)
            lesson_fail(&args, "cannot fit a box");
    }
    long hits_a = 0, hits_o = 0;
    const double ns_a = ns_per_test(ab, ob, 0, &hits_a), ns_o = ns_per_test(ab, ob, 1, &hits_o);
    printf("  %-14s %12s %10s %9s\n", "box", "ns per test", "hit rate", "bytes");
    printf("  %-14s %12.2f %9.1f%% %9zu\n", "AABB (robust)", ns_a, 100.0 * hits_a / (NTEST_RAYS * NBOX), sizeof(sidx_aabb));
    printf("  %-14s %12.2f %9.1f%% %9zu\n", "oriented box", ns_o, 100.0 * hits_o / (NTEST_RAYS * NBOX), sizeof(sidx_obb));
    printf("  The oriented test first projects the ray on the box's three axes (6 dot products): %.1fx\n"
           "  the time of the AABB's, and it lets through %.0f%% fewer rays around the same points.\n",
           ns_o / ns_a, 100.0 * (1.0 - (double)hits_o / (double)(hits_a ? hits_a : 1)));
    free(pts);
    free(ob);
    free(ab);

    /* ---- 3 ---- */
    printf("\n== 3. The same tree with either box: per ray (%d random rays), and memory\n", NRAYS);
    printf("  %-26s %-8s %10s %10s %9s %10s %11s\n", "scene", "boxes", "box tests", "tri tests", "nodes", "us/ray",
           "memory KiB");
    row r[3][2];
    char label[3][64];
    snprintf(label[0], sizeof label[0], "%s (%u tris)", args.scene, mesh.num_triangles);
    snprintf(label[1], sizeof label[1], "%s turned", args.scene);
    snprintf(label[2], sizeof label[2], "soup:4000");
    compare(&args, &mesh, label[0], r[0]);
    compare(&args, &turned, label[1], r[1]);
    compare(&args, &soup, label[2], r[2]);
    int same = 1, fewer = 1, bigger = 1;
    for (int k = 0; k < 3; ++k) {
        same &= r[k][1].same;
        fewer &= r[k][1].boxes < r[k][0].boxes;
        bigger &= r[k][1].bytes > r[k][0].bytes;
    }
    printf("  Same hits (prim and t) with either box on every ray: %s\n", same ? "yes" : "NO");
    printf("  Yes: with the oriented boxes a ray needs %.0f%%, %.0f%% and %.0f%% fewer box tests (the children\n"
           "  of a rejected node are never tested) and fewer triangle tests — S_A/S_C falls.\n"
           "  No: each test costs %.1fx as much and the nodes need %.1fx the memory; the time per ray\n"
           "  is %.2fx, %.2fx and %.2fx that of the axis-aligned tree:\n"
           "  C_trav rises; the time per ray says whether by more than the tests saved.\n",
           100.0 * (1 - r[0][1].boxes / r[0][0].boxes), 100.0 * (1 - r[1][1].boxes / r[1][0].boxes),
           100.0 * (1 - r[2][1].boxes / r[2][0].boxes), ns_o / ns_a, (double)r[0][1].bytes / (double)r[0][0].bytes,
           r[0][1].us / r[0][0].us, r[1][1].us / r[1][0].us, r[2][1].us / r[2][0].us);

    sidx_mesh_free(&soup);
    sidx_mesh_free(&turned);
    sidx_mesh_free(&mesh);
    lesson_check("same_hits", same);
    lesson_check("obb_fewer_box_tests", fewer && trace_fewer > 0);
    lesson_check("obb_fewer_box_hits", hits_o < hits_a);
    lesson_check("obb_more_memory", bigger);
    return 0;
}
