/* 09_kdtree_build.c — building kd-trees: intuitive vs SAH.
 *
 * Slides (deck 000, "Spatial Index Structures"): "'Intuitive' kD-Tree
 * Building" ("Split axis: round-robin; largest extent — Split location:
 * middle of extent; median of geometry — Termination: target # of
 * primitives, limited tree depth — All of these techniques are NOT very
 * clever"), "Building good kD-trees" (Cost(cell) = C_trav + SA(L)/SA(c) ·
 * TriCount(L) + SA(R)/SA(c) · TriCount(R); "One can show that SAH cannot
 * have minima unless #triangles changes"; "Characteristics of the tree you
 * are looking for: deep and thin, typical depth of 50-100, about 2
 * triangles per leaf, big empty cells"), "Splitting with Cost in Mind"
 * (middle / median / cost-optimized), "Termination Criteria".
 *
 * What it shows, on one scene (default teapot):
 *   1. the SAH cost of every candidate plane the build looked at in the
 *      root cell (one BUILD_CANDIDATE event each), drawn as a curve over
 *      the position on the chosen axis, with the chosen split and the cost
 *      of not splitting at all (the termination test);
 *   2. the three builders side by side — middle of the extent, median of
 *      the geometry, SAH — with depth, leaf sizes, empty leaves, why leaves
 *      were made (the termination criteria that fired), duplicated
 *      references, SAH cost, and what rays pay;
 *   3. the SAH tree's leaves by depth: "deep and thin".
 *
 * Read:  lib/kdtree_build.c, sweep_axis
 * Run:   build/lessons/09_kdtree_build [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
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
    fprintf(f, "usage: 09_kdtree_build [--help] [build knobs] [SCENE]\n"
               "\n"
               "kd-tree builds: the SAH cost curve over candidate planes at the root, then the middle,\n"
               "median and SAH builders compared: depth, leaf sizes, termination, cost per ray.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "The knobs below change the middle, median and default-SAH trees (other costs, leaf\n"
               "size, depth cap); the \"deep and thin\" SAH tree keeps C_trav = C_tri = 1 and its\n"
               "depth cap.  The checks hold for the defaults.\n");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define MAXD 65
#define DEEP 100u /* the SAH row's depth cap asked for: the top of the slide's 50-100 */
typedef struct {
    const char *name, *what;
    sidx_accel_stats st;
    double build_ms, visits, tris, us, mean_depth;
    uint32_t reasons[SIDX_LEAF_REASON_COUNT];
    uint32_t by_depth[MAXD];
    uint32_t size_hist[6]; /* 0, 1, 2, 3-4, 5-8, 9+ */
    float t[2000];
} kd_row;

static void leaf_stats(const sidx_recorder *rec, kd_row *r)
{
    for (size_t i = 0; i < rec->count; ++i) {
        const sidx_event *e = &rec->events[i];
        if (e->type != SIDX_EV_BUILD_LEAF) continue;
        if (e->reason >= 0 && e->reason < SIDX_LEAF_REASON_COUNT) r->reasons[e->reason]++;
        r->by_depth[e->depth < MAXD ? e->depth : MAXD - 1]++;
        const uint32_t n = e->count;
        r->size_hist[n == 0 ? 0 : n == 1 ? 1 : n == 2 ? 2 : n <= 4 ? 3 : n <= 8 ? 4 : 5]++;
    }
}

/* The root's candidates on one axis as a curve. */
static void plot_curve(const sidx_recorder *rec, uint32_t root, int axis, float split_pos, float split_cost,
                       float leaf_cost, sidx_aabb cell)
{
    enum { COLS = 64, ROWS = 12 };
    float lo = sidx_v3_get(cell.min, axis), hi = sidx_v3_get(cell.max, axis);
    float colmin[COLS];
    for (int c = 0; c < COLS; ++c) colmin[c] = INFINITY;
    float cmin = INFINITY, cmax = -INFINITY;
    size_t n = 0;
    for (size_t i = 0; i < rec->count; ++i) {
        const sidx_event *e = &rec->events[i];
        if (e->type != SIDX_EV_BUILD_CANDIDATE || e->node != root || e->axis != axis) continue;
        int c = (int)((e->pos - lo) / (hi - lo) * COLS);
        if (c < 0) c = 0;
        if (c >= COLS) c = COLS - 1;
        if (e->cost < colmin[c]) colmin[c] = e->cost;
        if (e->cost < cmin) cmin = e->cost;
        if (e->cost > cmax) cmax = e->cost;
        ++n;
    }
    if (leaf_cost > cmax) cmax = leaf_cost;
    const float top = cmax, bottom = cmin;
    int split_col = (int)((split_pos - lo) / (hi - lo) * COLS);
    if (split_col >= COLS) split_col = COLS - 1;
    if (split_col < 0) split_col = 0;
    printf("  %zu candidates on axis %c, cost from %.4g to %.4g; 'o' = cheapest candidate in that column,\n"
           "  '|' = the chosen split (%.4g at %.4g), '~' = the cost of a leaf (%.4g)\n",
           n, "xyz"[axis], cmin, cmax, split_cost, split_pos, leaf_cost);
    for (int row = 0; row < ROWS; ++row) {
        const float hi_c = top - (top - bottom) * (float)row / ROWS, lo_c = top - (top - bottom) * (float)(row + 1) / ROWS;
        printf("  %9.4g |", hi_c);
        for (int c = 0; c < COLS; ++c) {
            char ch = ' ';
            if (leaf_cost <= hi_c && leaf_cost > lo_c) ch = '~';
            if (c == split_col) ch = '|';
            if (colmin[c] <= hi_c && (colmin[c] > lo_c || (row == ROWS - 1 && colmin[c] >= lo_c))) ch = 'o';
            putchar(ch);
        }
        putchar('\n');
    }
    printf("  %9s +%.*s\n", "", COLS, "----------------------------------------------------------------");
    printf("  %9s  %-10.4g%*s%10.4g   (%c)\n", "", lo, COLS - 20, "", hi, "xyz"[axis]);
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_C_TRAV(knobs),    LESSON_C_TRI(knobs),       LESSON_LEAF_SIZE(knobs),
                                     LESSON_MAX_DEPTH(knobs), LESSON_EMPTY_BONUS(knobs), {0}};
    lesson_args args = {.name = "09_kdtree_build", .usage = usage, .scene = "teapot", .options = options};
    lesson_parse(&args, argc, argv);
    static kd_row rows[4] = {
        {"kdtree-middle", "middle of extent", {0}, 0, 0, 0, 0, 0, {0}, {0}, {0}, {0}},
        {"kdtree-median", "median of geometry", {0}, 0, 0, 0, 0, 0, {0}, {0}, {0}, {0}},
        {"kdtree", "SAH, default C", {0}, 0, 0, 0, 0, 0, {0}, {0}, {0}, {0}},
        {"kdtree", "SAH, C_trav = 1", {0}, 0, 0, 0, 0, 0, {0}, {0}, {0}, {0}},
    };
    for (int i = 0; i < 3; ++i) lesson_need(&args, rows[i].name);
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const float R = sidx_v3_length(ext);
    enum { NR = 2000 };
    static sidx_ray rays[NR];
    uint32_t seed = 31337u;
    for (int i = 0; i < NR; ++i) {
        float f[5];
        for (int j = 0; j < 5; ++j) { seed = seed * 1664525u + 1013904223u; f[j] = (float)(seed >> 8) / 16777216.0f; }
        const float z = 2 * f[0] - 1, ang = 6.2831853f * f[1], s = sqrtf(1 - z * z);
        const sidx_vec3 o = sidx_v3_add(ctr, sidx_v3(R * s * cosf(ang), R * s * sinf(ang), R * z));
        const sidx_vec3 t = sidx_v3(box.min.x + f[2] * ext.x, box.min.y + f[3] * ext.y, box.min.z + f[4] * ext.z);
        sidx_ray_init(&rays[i], o, sidx_v3_sub(t, o), 0.0f, INFINITY);
    }

    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook rh = sidx_recorder_hook(&rec);
    int curve_ok = 0, same = 1;
    printf("== '%s': %u triangles\n", args.scene, mesh.num_triangles);
    for (int b = 0; b < 4; ++b) {
        kd_row *r = &rows[b];
        sidx_recorder_clear(&rec);
        sidx_build_options opt = knobs;
        opt.hook = &rh;
        if (b == 3) {
            /* the termination knob turned down, and the depth cap lifted to the slide's "typical
             * depth of 50-100": the library clamps it to 64, the depth its traversal stack holds */
            opt.c_trav = 1.0f;
            opt.c_tri = 1.0f;
            opt.max_depth = DEEP;
        }
        sidx_accel *a = NULL;
        const double t0 = now_s();
        if (sidx_accel_build(r->name, &mesh, &opt, &a, &err) != SIDX_OK) {
            fprintf(stderr, "09_kdtree_build: %s\n", err.message);
            sidx_recorder_free(&rec);
            sidx_mesh_free(&mesh);
            return 1;
        }
        r->build_ms = 1e3 * (now_s() - t0); /* includes recording the events */
        sidx_accel_stats_get(a, &r->st);
        leaf_stats(&rec, r);

        if (b == 2) {
            /* the root: node event, chosen split, candidates */
            printf("\n== 1. The SAH at the root: C_trav + SA(L)/SA(c) N_L C_tri + SA(R)/SA(c) N_R C_tri\n");
            sidx_printer pr;
            sidx_printer_init(&pr, stdout);
            const sidx_hook ph = sidx_printer_hook(&pr);
            const sidx_event *root = NULL, *split = NULL;
            float min_cost = INFINITY, min_pos = NAN;
            int shown = 0;
            for (size_t i = 0; i < rec.count; ++i) {
                const sidx_event *e = &rec.events[i];
                if (e->type == SIDX_EV_BUILD_NODE && e->parent == UINT32_MAX) { root = e; sidx_hook_emit(&ph, e); }
                if (!root || e->node != root->node) continue;
                if (e->type == SIDX_EV_BUILD_CANDIDATE) {
                    if (shown < 4) { sidx_hook_emit(&ph, e); ++shown; }
                    else if (shown == 4) { printf("      ... (the other candidates are in the curve below)\n"); ++shown; }
                    if (e->cost < min_cost) { min_cost = e->cost; min_pos = e->pos; }
                }
                if (e->type == SIDX_EV_BUILD_SPLIT && !split) { split = e; sidx_hook_emit(&ph, e); }
            }
            if (root && split) {
                /* C_tri of the kd-tree: the leaf event of a 1-triangle leaf tells it, but the
                 * root's "leaf" alternative is simply N * C_tri with the default C_tri */
                float c_tri = 1.5f;
                for (size_t i = 0; i < rec.count; ++i)
                    if (rec.events[i].type == SIDX_EV_BUILD_LEAF && rec.events[i].count > 0) {
                        c_tri = rec.events[i].cost / (float)rec.events[i].count;
                        break;
                    }
                const float leaf_cost = c_tri * (float)root->count;
                printf("\n");
                plot_curve(&rec, root->node, split->axis, split->pos, split->cost, leaf_cost, root->bounds);
                printf("  The curve only changes where a triangle starts or ends, so those are the only\n"
                       "  candidates needed; the chosen split is the lowest point of all three axes' curves,\n"
                       "  and the build keeps splitting only while a split is cheaper than the leaf (C_tri = %g).\n",
                       c_tri);
                curve_ok = min_cost == split->cost && min_pos == split->pos;
            }
        }

        sidx_counters c;
        sidx_counters_init(&c);
        const sidx_hook ch = sidx_counters_hook(&c);
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ch, 0};
        for (int i = 0; i < NR; ++i) {
            sidx_hit h;
            sidx_accel_intersect(a, &rays[i], &q, &h);
            r->t[i] = h.t;
            if (b > 0 && !(h.t == rows[0].t[i])) same = 0;
        }
        r->visits = (double)c.n[SIDX_EV_NODE_ENTER] / NR;
        r->tris = (double)c.n[SIDX_EV_PRIM_TEST] / NR;
        double best = INFINITY;
        for (int pass = 0; pass < 5; ++pass) {
            const double t1 = now_s();
            for (int i = 0; i < NR; ++i) {
                sidx_hit h;
                sidx_accel_intersect(a, &rays[i], NULL, &h);
            }
            if (now_s() - t1 < best) best = now_s() - t1;
        }
        r->us = 1e6 * best / NR;
        sidx_accel_destroy(a);
    }
    sidx_recorder_free(&rec);

    printf("\n== 2. Three builders, the SAH one twice: with sidx's default constants and with a cheaper\n"
           "   traversal step C_trav = 1 (the termination knob: splitting pays off sooner) (%d random rays)\n", NR);
    printf("  %-28s %19s %19s %19s %19s\n", "", rows[0].name, rows[1].name, rows[2].name, rows[3].name);
#define ROW(label, fmt, expr)                                                                                          \
    do {                                                                                                               \
        printf("  %-28s", label);                                                                                      \
        for (int b = 0; b < 4; ++b) { const kd_row *r = &rows[b]; printf(" %19" fmt, expr); }                         \
        printf("\n");                                                                                                  \
    } while (0)
    ROW("split rule", "s", r->what);
    ROW("nodes", "u", r->st.nodes);
    ROW("max depth", "u", r->st.max_depth);
    ROW("leaves", "u", r->st.leaves);
    for (int b = 0; b < 4; ++b) {
        double sum = 0, cnt = 0;
        for (int d = 0; d < MAXD; ++d) { sum += (double)d * rows[b].by_depth[d]; cnt += rows[b].by_depth[d]; }
        rows[b].mean_depth = cnt > 0 ? sum / cnt : 0.0;
    }
    ROW("mean leaf depth", ".2f", r->mean_depth);
    ROW("empty leaves", "u", r->st.empty_leaves);
    ROW("mean prims / non-empty leaf", ".2f", r->st.mean_leaf_prims);
    ROW("prim references", "llu", (unsigned long long)r->st.prim_refs);
    ROW("  = x triangles", ".2f", (double)r->st.prim_refs / mesh.num_triangles);
    ROW("leaves: few_prims", "u", r->reasons[SIDX_LEAF_FEW_PRIMS]);
    ROW("leaves: no_gain (SAH)", "u", r->reasons[SIDX_LEAF_NO_GAIN]);
    ROW("leaves: max_depth", "u", r->reasons[SIDX_LEAF_MAX_DEPTH]);
    ROW("leaves: empty", "u", r->reasons[SIDX_LEAF_EMPTY]);
    printf("  %-28s", "leaf size 0 / 1 / 2");
    for (int b = 0; b < 4; ++b) {
        char s[32];
        snprintf(s, sizeof s, "%u/%u/%u", rows[b].size_hist[0], rows[b].size_hist[1], rows[b].size_hist[2]);
        printf(" %19s", s);
    }
    printf("\n  %-28s", "leaf size 3-4 / 5-8 / 9+");
    for (int b = 0; b < 4; ++b) {
        char s[32];
        snprintf(s, sizeof s, "%u/%u/%u", rows[b].size_hist[3], rows[b].size_hist[4], rows[b].size_hist[5]);
        printf(" %19s", s);
    }
    printf("\n");
    ROW("SAH cost (own constants)", ".2f", r->st.sah_cost);
    ROW("build ms (recording)", ".1f", r->build_ms);
    ROW("nodes visited per ray", ".2f", r->visits);
    ROW("triangles tested per ray", ".2f", r->tris);
    ROW("us per ray", ".2f", r->us);

    printf("\n== 3. Where the leaves of the SAH tree with C_trav = 1 are (depth: count); the other rows\n"
           "   stop at the library's default depth cap 8 + 1.3 log2(N) = %u, this one was given %u\n",
           (unsigned)lrint(8.0 + 1.3 * log2((double)mesh.num_triangles)), DEEP);
    uint32_t maxc = 1;
    for (int d = 0; d < MAXD; ++d)
        if (rows[3].by_depth[d] > maxc) maxc = rows[3].by_depth[d];
    for (int d = 0; d < MAXD; ++d) {
        if (!rows[3].by_depth[d]) continue;
        const int bar = (int)(40.0 * rows[3].by_depth[d] / maxc + 0.5);
        printf("  %3d %6u %.*s\n", d, rows[3].by_depth[d], bar, "########################################");
    }
    printf("  Deepest leaf: %u.  %s\n", rows[3].st.max_depth,
           rows[3].reasons[SIDX_LEAF_MAX_DEPTH]
               ? "Leaves made at the cap say the library's ceiling (64, the depth its traversal\n"
                 "  stack holds) cut the tree; the slide's 100 is beyond it."
               : "No leaf was made by the depth cap: the SAH found no split worth its cost\n"
                 "  below this depth, so a higher cap would not make the tree deeper.  The slide's\n"
                 "  50-100 levels belong to scenes of millions of triangles; depth grows with log N.");
    printf("  Deep and thin: with a cheap traversal step most leaves hold one or two triangles or\n"
           "  none, big empty cells cut away the space around the surface.  sidx's default constants\n"
           "  stops earlier: fatter leaves, a smaller tree; which is faster per ray is measured above.\n");
    printf("  Same closest hits from all four: %s\n", same ? "yes" : "NO");
    sidx_mesh_free(&mesh);
    const int cost_lower = rows[2].st.sah_cost < rows[0].st.sah_cost && rows[2].st.sah_cost < rows[1].st.sah_cost;
    /* the knob: a cheaper traversal step gives thinner leaves, deeper */
    const int thin = rows[3].st.mean_leaf_prims < rows[2].st.mean_leaf_prims && rows[3].mean_depth > rows[2].mean_depth &&
                     rows[3].st.mean_leaf_prims < rows[0].st.mean_leaf_prims &&
                     rows[3].st.mean_leaf_prims < rows[1].st.mean_leaf_prims;
    lesson_check("same_hits", same);
    lesson_check("sah_cost_lower", cost_lower);
    lesson_check("sah_thin_leaves", thin);
    lesson_check("cost_curve_min_is_split", curve_ok);
    return 0;
}
