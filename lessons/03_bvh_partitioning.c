/* 03_bvh_partitioning.c — how to split 11 primitives in two.
 *
 * Slides (deck 001, "Spatial Data Structures"): "BVH Partitioning" ("What
 * is the best way to partition these primitives?" — "We can split them
 * into equal # of primitives... but bboxes take up large area" — "We can
 * split them into the smallest possible bboxes... but some bboxes will
 * have many more primitives"), "Surface Area Heuristic", "Building
 * Partitions" and "Building Partitions Example" with its
 * "Cost = 3 prims * (0.15) + 8 prims * (0.87)".  Deck 000: "Splitting with
 * Cost in Mind" — "Split in the middle", "Split at the Median",
 * "Cost-Optimized Split".
 *
 * What it shows: the slide's eleven primitives (lesson_partition11, in
 * lesson.h: triangles whose binned candidates have the slide's numbers),
 * split at the root four ways — in the middle of the centroid
 * extent (bvh-middle), into equal counts (bvh-median), by the SAH over 4
 * bins per axis as in the slide's example (bvh with bins = 4) and by the
 * SAH at every position (bvh-sweep).  For each candidate plane the build
 * reports (BUILD_CANDIDATE, printed by the printer sink) the lesson prints
 * the slide's line: how many primitives fall on each side and which share
 * of the parent's surface each child box has; for the binned build the
 * six lines next to the slide's, checked to 2 decimals.  Then the whole SAH build
 * traced, and per builder the SAH cost of the root split, of the whole
 * tree, and what random rays actually paid (boxes and triangles tested).
 *
 * Read:  lib/bvh_build.c, find_binned
 * Run:   build/lessons/03_bvh_partitioning [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply to split instead of the
 *        eleven triangles (only the first candidates are printed then).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include "sidx/sidx.h"
#include "lesson.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 03_bvh_partitioning [--help] [build knobs] [SCENE]\n"
               "\n"
               "The 11 primitives of deck 001 \"Building Partitions Example\", whose binned candidates\n"
               "have the slide's numbers: split in the middle, into equal counts, and by the surface\n"
               "area heuristic, with the cost of every candidate the build considers.\n"
               "\n"
               "  SCENE   split this scene instead: built-in name or .obj/.ply\n"
               "The knobs below change the trees: --bins the binned SAH build's bins (the slide's\n"
               "example has 4), --leaf-size and --max-depth all four builds.  The checks hold for\n"
               "the defaults.\n");
}

/* Deck 001 "Building Partitions Example": per axis, the three planes
 * between 4 bins, as (left count, right count, left share, right share). */
static const struct {
    char axis;
    unsigned nl, nr;
    float fl, fr;
} slide[6] = {{'x', 3, 8, 0.15f, 0.87f}, {'x', 6, 5, 0.38f, 0.43f}, {'x', 9, 2, 0.81f, 0.18f},
              {'y', 3, 8, 0.19f, 0.91f}, {'y', 6, 5, 0.32f, 0.36f}, {'y', 9, 2, 0.94f, 0.13f}};

typedef struct {
    const char *accel;
    const char *label;
    uint32_t bins;
    /* results */
    float root_cost;
    int root_axis;
    float root_pos;
    uint32_t nl, nr;
    sidx_accel_stats st;
    double boxes_per_ray, tris_per_ray;
} builder;

static char axis_name(int a) { return a == 0 ? 'x' : a == 1 ? 'y' : a == 2 ? 'z' : '-'; }

/* Reproduces a root candidate from the primitives: who lies left of the
 * plane, the two child boxes, their share of the parent's area (returned
 * in share[0], share[1]); says whether the event agrees. */
static int explain(const sidx_mesh *m, const sidx_event *ev, sidx_aabb parent, float c_trav, float share[2])
{
    sidx_aabb l = sidx_aabb_empty(), r = sidx_aabb_empty();
    uint32_t nl = 0, nr = 0;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        const sidx_aabb b = sidx_mesh_triangle_bounds(m, i);
        const float c = sidx_v3_get(sidx_aabb_centroid(b), ev->axis);
        if (c < ev->pos) { l = sidx_aabb_union(l, b); ++nl; }
        else { r = sidx_aabb_union(r, b); ++nr; }
    }
    const float a = sidx_aabb_area(parent), fl = sidx_aabb_area(l) / a, fr = sidx_aabb_area(r) / a;
    const float cost = c_trav + (float)nl * fl + (float)nr * fr;
    const int same = nl == ev->count && nr == ev->aux && fabsf(cost - ev->cost) <= 1e-4f * (1.0f + fabsf(cost));
    share[0] = fl;
    share[1] = fr;
    printf("        Cost = C_trav + %u prims * (%.2f) + %u prims * (%.2f) = %g + %.2f + %.2f = %.3f%s\n", nl, fl, nr,
               fr, c_trav, nl * fl, nr * fr, cost, same ? "" : "   (differs from the event!)");
    return same;
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_BINS(knobs), LESSON_LEAF_SIZE(knobs), LESSON_MAX_DEPTH(knobs), {0}};
    /* no default scene: the eleven triangles */
    lesson_args args = {.name = "03_bvh_partitioning", .usage = usage, .options = options};
    lesson_parse(&args, argc, argv);
    static const char *const needed[] = {"bvh-middle", "bvh-median", "bvh", "bvh-sweep"};
    for (int i = 0; i < 4; ++i) lesson_need(&args, needed[i]);

    sidx_mesh mesh;
    sidx_error err = {0};
    if (args.scene_given) mesh = lesson_open_scene(&args);
    else if (lesson_partition11(&mesh, &err) != SIDX_OK) lesson_fail(&args, err.message);
    if (mesh.num_triangles < 2) lesson_fail(&args, "need at least two triangles");
    const int small = mesh.num_triangles <= 16;
    const sidx_aabb box = sidx_mesh_bounds(&mesh);

    printf("== The primitives (%u triangles%s)\n", mesh.num_triangles, args.scene_given ? "" : ", z = 0, seen from +z");
    if (small)
        for (uint32_t i = 0; i < mesh.num_triangles; ++i) {
            const sidx_vec3 c = sidx_aabb_centroid(sidx_mesh_triangle_bounds(&mesh, i));
            printf("  prim %2u  centroid (%.2f, %.2f)\n", i, c.x, c.y);
        }

    char binned[64] = "SAH over 4 bins per axis (the slide's example)";
    if (knobs.bins) snprintf(binned, sizeof binned, "SAH over %u bins per axis", knobs.bins);
    builder bs[4] = {
        {"bvh-middle", "split in the middle (of the centroid extent)", 0, 0, 0, 0, 0, 0, {0}, 0, 0},
        {"bvh-median", "split at the median (equal counts)", 0, 0, 0, 0, 0, 0, {0}, 0, 0},
        {"bvh", binned, knobs.bins ? knobs.bins : 4, 0, 0, 0, 0, 0, {0}, 0, 0},
        {"bvh-sweep", "SAH at every centroid position", 0, 0, 0, 0, 0, 0, {0}, 0, 0},
    };
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    const sidx_hook ph = sidx_printer_hook(&pr);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook rh = sidx_recorder_hook(&rec);
    int explained = 1, failed = 0, slide_ok = 1;
    /* the binned build's root candidates, as the slide writes them */
    struct {
        char axis;
        unsigned nl, nr;
        float fl, fr;
    } got[6];
    int ngot = 0;
    const float c_trav = 1.0f; /* the library's default C_trav = C_tri = 1 */

    for (int b = 0; b < 4 && !failed; ++b) {
        printf("\n== %s: %s\n", bs[b].accel, bs[b].label);
        sidx_recorder_clear(&rec);
        sidx_build_options opt = knobs;
        opt.hook = &rh;
        opt.bins = bs[b].bins;
        sidx_accel *a = NULL;
        if (sidx_accel_build(bs[b].accel, &mesh, &opt, &a, &err) != SIDX_OK) {
            fprintf(stderr, "03_bvh_partitioning: %s\n", err.message);
            failed = 1;
            break;
        }
        sidx_accel_stats_get(a, &bs[b].st);
        /* the root: its node event, its candidates, its decision */
        sidx_aabb root_box = box;
        uint32_t root = UINT32_MAX;
        int shown = 0;
        for (size_t i = 0; i < rec.count; ++i) {
            const sidx_event *ev = &rec.events[i];
            if (ev->type == SIDX_EV_BUILD_NODE && ev->parent == UINT32_MAX) {
                root = ev->node;
                root_box = ev->bounds;
                sidx_hook_emit(&ph, ev);
            }
            if (ev->node != root || root == UINT32_MAX) continue;
            if (ev->type == SIDX_EV_BUILD_CANDIDATE) {
                if (small || shown < 12) {
                    float share[2];
                    sidx_hook_emit(&ph, ev);
                    explained &= explain(&mesh, ev, root_box, c_trav, share);
                    if (bs[b].bins == 4 && ngot < 6) {
                        got[ngot].axis = axis_name(ev->axis);
                        got[ngot].nl = ev->count;
                        got[ngot].nr = ev->aux;
                        got[ngot].fl = share[0];
                        got[ngot].fr = share[1];
                        ++ngot;
                    }
                } else if (shown == 12) {
                    printf("      ... (more candidates not shown)\n");
                }
                ++shown;
            } else if (ev->type == SIDX_EV_BUILD_SPLIT) {
                sidx_hook_emit(&ph, ev);
                bs[b].root_cost = ev->cost;
                bs[b].root_axis = ev->axis;
                bs[b].root_pos = ev->pos;
                bs[b].nl = ev->count;
                bs[b].nr = ev->aux;
            } else if (ev->type == SIDX_EV_BUILD_LEAF) {
                sidx_hook_emit(&ph, ev);
                bs[b].root_cost = ev->cost;
                bs[b].nl = ev->count;
                bs[b].root_axis = -1;
            }
        }
        printf("    %d candidate(s) at the root\n", shown);
        if (bs[b].bins == 4 && !args.scene_given) {
            /* The slide's six lines, computed from the candidates above,
             * next to the slide's figures rounded as it prints them. */
            printf("\n  The slide's lines (\"Building Partitions Example\"), from the build / on the slide:\n");
            for (int i = 0; i < ngot; ++i) {
                const int same = got[i].axis == slide[i].axis && got[i].nl == slide[i].nl && got[i].nr == slide[i].nr &&
                                 lroundf(100 * got[i].fl) == lroundf(100 * slide[i].fl) &&
                                 lroundf(100 * got[i].fr) == lroundf(100 * slide[i].fr);
                printf("    %c: Cost = %u prims * (%.2f) + %u prims * (%.2f)   slide: %u * (%.2f) + %u * (%.2f)%s\n",
                       got[i].axis, got[i].nl, got[i].fl, got[i].nr, got[i].fr, slide[i].nl, slide[i].fl, slide[i].nr,
                       slide[i].fr, same ? "" : "   DIFFERS");
                slide_ok &= same;
            }
            slide_ok &= ngot == 6;
            printf("  The slide's cost drops C_trav and C_tri (constants: they do not move the minimum) and\n"
                   "  weighs each side's count by its share of the parent's area.  Best partition: the lowest,\n"
                   "  %c %u|%u; the build splits there and recurses with each child (the whole build below).\n"
                   "  Erratum: the second \"Building Partitions\" loop has cost = a.area() + b.area() + (n - i);\n"
                   "  the SAH is a.area * i + b.area * (n - i), as in the first loop and as computed here.\n",
                   axis_name(bs[b].root_axis), bs[b].nl, bs[b].nr);
        }

        /* the whole build of the slide's example, traced */
        if (b == 2 && small) {
            printf("\n  The whole build, as the printer shows it (candidates left out):\n");
            pr.mask = SIDX_EVMASK_BUILD & ~SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE);
            for (size_t i = 0; i < rec.count; ++i) sidx_hook_emit(&ph, &rec.events[i]);
            pr.mask = 0;
        }

        /* what rays pay: random rays straight down onto the plane (or, for a
         * scene, from random points on its bounding sphere inwards) */
        sidx_counters cnt;
        sidx_counters_init(&cnt);
        const sidx_hook ch = sidx_counters_hook(&cnt);
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ch, 0};
        uint32_t seed = 12345u;
        const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
        const int nrays = 20000;
        for (int k = 0; k < nrays; ++k) {
            float f[4];
            for (int j = 0; j < 4; ++j) {
                seed = seed * 1664525u + 1013904223u;
                f[j] = (float)(seed >> 8) / 16777216.0f;
            }
            sidx_vec3 o, d;
            if (!args.scene_given) {
                o = sidx_v3(box.min.x + f[0] * ext.x, box.min.y + f[1] * ext.y, 5.0f);
                d = sidx_v3(0.2f * (f[2] - 0.5f), 0.2f * (f[3] - 0.5f), -1.0f);
            } else {
                const float z = 2 * f[0] - 1, ph2 = 6.2831853f * f[1], s = sqrtf(1 - z * z), R = sidx_v3_length(ext);
                o = sidx_v3_add(ctr, sidx_v3(R * s * cosf(ph2), R * s * sinf(ph2), R * z));
                const sidx_vec3 tgt = sidx_v3(box.min.x + f[2] * ext.x, box.min.y + f[3] * ext.y, ctr.z);
                d = sidx_v3_sub(tgt, o);
            }
            sidx_ray r;
            if (sidx_ray_init(&r, o, d, 0.0f, INFINITY) != SIDX_OK) continue;
            sidx_hit h;
            sidx_accel_intersect(a, &r, &q, &h);
        }
        bs[b].boxes_per_ray = (double)cnt.n[SIDX_EV_BOX_TEST] / nrays;
        bs[b].tris_per_ray = (double)cnt.n[SIDX_EV_PRIM_TEST] / nrays;
        sidx_accel_destroy(a);
    }
    sidx_recorder_free(&rec);
    sidx_mesh_free(&mesh);
    if (failed) return 1;

    printf("\n== Side by side (C_trav = C_tri = 1; SAH cost relative to the root box)\n");
    printf("  %-11s %-16s %11s %9s %7s %7s %14s %14s\n", "builder", "root split", "split cost", "tree SAH", "nodes",
           "leaves", "boxes per ray", "tris per ray");
    for (int b = 0; b < 4; ++b) {
        char split[40];
        if (bs[b].root_axis >= 0)
            snprintf(split, sizeof split, "%c=%.2f %u|%u", axis_name(bs[b].root_axis), bs[b].root_pos, bs[b].nl, bs[b].nr);
        else
            snprintf(split, sizeof split, "leaf");
        printf("  %-11s %-16s %11.3f %9.3f %7u %7u %14.2f %14.2f\n", bs[b].accel, split, bs[b].root_cost,
               bs[b].st.sah_cost, bs[b].st.nodes, bs[b].st.leaves, bs[b].boxes_per_ray, bs[b].tris_per_ray);
    }
    const int sah_root = bs[3].root_cost <= bs[0].root_cost + 1e-6f && bs[3].root_cost <= bs[1].root_cost + 1e-6f;
    const int sah_tree = bs[3].st.sah_cost <= bs[0].st.sah_cost + 1e-9 && bs[3].st.sah_cost <= bs[1].st.sah_cost + 1e-9;
    const double work_sah = bs[3].boxes_per_ray + bs[3].tris_per_ray;
    const double work_mid = bs[0].boxes_per_ray + bs[0].tris_per_ray, work_med = bs[1].boxes_per_ray + bs[1].tris_per_ray;
    printf("\n  The middle split makes the two probabilities equal and ignores the counts; the median makes\n"
           "  the counts equal and ignores the probabilities; the SAH weighs both, and its root split is\n"
           "  the cheapest (%.3f vs %.3f middle, %.3f median).  Rays confirm it: %.2f tests per ray\n"
           "  (boxes + triangles) vs %.2f and %.2f.\n",
           bs[3].root_cost, bs[0].root_cost, bs[1].root_cost, work_sah, work_mid, work_med);
    lesson_check("candidate_costs_reproduced", explained);
    if (!args.scene_given) lesson_check("slide_candidates_match", slide_ok);
    lesson_check("sah_cost_lower", sah_root);
    lesson_check("sah_tree_cost_lower", sah_tree);
    lesson_check("sah_fewer_tests_per_ray", work_sah <= work_mid && work_sah <= work_med);
    return 0;
}
