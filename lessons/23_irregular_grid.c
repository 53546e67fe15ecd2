/* 23_irregular_grid.c — the irregular grid: base grid, merge, expand, and
 * the long steps its traversal takes.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Irregular Grids"
 * ("Irregular grids can accel traversal [Perard-Gayot'17] — Build
 * (hierarchical) base grid (power of 2, adapts to scene) — Base grid
 * defines minimum resolution for computation — Neighboring cells can be
 * merged (eagerly) as long as no change in set of primitives — Can also
 * expand cells (for exit operations) as long as neighbors contain only
 * subset of cells primitives — Allows for making larger steps — Approach
 * needs more memory"), "Construction (merge & expand)" and "Traversal
 * (simplified, finest level: 12 steps)".
 *
 * The deck's figures are lost; its one number is kept: a ray that takes
 * 12 steps through the finest level.  On a 2D scene of eleven triangles
 * laid over an 8 x 8 finest level, the lesson prints, from the build's
 * events (build_leaf, build_merge, build_expand, docs/events.md):
 *   1. the base grid: a 2 x 2 top grid whose cells are cut into quarters
 *      while they hold more than one small triangle, down to the finest
 *      level, drawn as a map (cell walls, triangles per cell);
 *   2. the merges: neighbours with the same triangles joined, one line per
 *      merge, and the map of the merged cells;
 *   3. the expansion: each cell's box grown over neighbours holding a
 *      subset of its triangles, one line per step (the refusals counted);
 *   4. the slide's traversal: one ray through a uniform grid at the finest
 *      level, 12 steps, and through the irregular grid, which jumps across
 *      each cell's expanded box;
 *   5. measured on a bigger scene (default stadium): cells visited and
 *      triangles tested per ray, memory and build time, irregular against
 *      uniform grid.
 * Cells print as coordinates at the finest level with their extent:
 * "cell (2,4,0) 2x2x1" spans x 2..4, y 4..6.
 *
 * Read:  lib/grid_irregular.c, merge_cells; lib/grid_irregular.c, expand_cell
 * Run:   build/lessons/23_irregular_grid [SCENE]
 *        SCENE = the scene of part 5 (default stadium); parts 1-4 always use
 *        the lesson's own 2D scene
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
    fprintf(f, "usage: 23_irregular_grid [--help] [build knobs] [SCENE]\n"
               "\n"
               "Irregular grid (deck 000 \"Irregular Grids\", \"Construction (merge & expand)\",\n"
               "\"Traversal (simplified, finest level: 12 steps)\"): its base grid, merges and expansions\n"
               "on a 2D scene of eleven triangles, one ray's 12 finest-level steps against the irregular\n"
               "grid's few, then cells visited and triangles tested per ray on a bigger scene.\n"
               "\n"
               "  SCENE   scene of the measured part (default: stadium)\n"
               "  The knobs change the irregular grid of the measured part (--lambda: its top grid;\n"
               "  --leaf-size: triangles a part may keep uncut; --max-depth: octant levels).\n");
}

#define FINE 8 /* finest-level cells per axis of the 2D scene */
#define NRAYS 4000

/* The 2D scene on [0, 8] x [0, 8], z = 0: a cluster of small triangles in
 * the upper left, a pair in the lower right, one long sliver and a few
 * loners, so that the base grid is fine in places and coarse in others. */
static const float scene2d[][6] = {
    {0.0f, 7.0f, 0.6f, 7.0f, 0.3f, 8.0f},   /* upper-left cluster */
    {1.2f, 6.9f, 1.8f, 6.9f, 1.5f, 7.6f},
    {0.3f, 5.3f, 0.9f, 5.3f, 0.6f, 5.9f},
    {1.3f, 5.2f, 1.9f, 5.2f, 1.6f, 5.8f},
    {2.4f, 6.2f, 3.0f, 6.2f, 2.7f, 6.8f},
    {6.2f, 0.0f, 6.8f, 0.0f, 6.5f, 0.6f},   /* lower-right pair */
    {7.2f, 1.3f, 7.8f, 1.3f, 7.5f, 1.9f},
    {4.3f, 7.3f, 7.7f, 7.3f, 6.0f, 7.6f},   /* a long sliver along the top */
    {7.4f, 4.3f, 8.0f, 4.3f, 7.7f, 4.9f},   /* loners */
    {0.4f, 0.4f, 1.0f, 0.4f, 0.7f, 1.0f},
    {5.3f, 2.3f, 5.7f, 2.3f, 5.5f, 2.6f},
};
#define N2D (sizeof scene2d / sizeof scene2d[0])

static sidx_mesh make_scene2d(const lesson_args *args)
{
    float xyz[N2D * 9];
    uint32_t idx[N2D * 3];
    for (size_t i = 0; i < N2D; ++i) {
        for (int k = 0; k < 3; ++k) {
            xyz[9 * i + 3 * k] = scene2d[i][2 * k];
            xyz[9 * i + 3 * k + 1] = scene2d[i][2 * k + 1];
            xyz[9 * i + 3 * k + 2] = 0.0f;
            idx[3 * i + k] = (uint32_t)(3 * i + k);
        }
    }
    sidx_mesh m;
    sidx_error err = {0};
    if (sidx_mesh_from_arrays(&m, xyz, (uint32_t)(3 * N2D), idx, (uint32_t)N2D, &err) != SIDX_OK)
        lesson_fail(args, err.message);
    return m;
}

/* ---- maps of the finest level ------------------------------------------ */

/* A map: which cell owns each finest cell (walls are drawn between
 * different owners) and three characters to print inside it. */
typedef struct map2d {
    long owner[FINE][FINE];
    char text[FINE][FINE][4];
} map2d;

/* Three characters of src (blank-padded) into a map cell.  By hand, not
 * with strcpy or snprintf: gcc 12 at -O2 drops calls to a helper that
 * writes a caller's local both directly and through a string function. */
static void text_set(char dst[4], const char *src)
{
    for (int i = 0; i < 3; ++i) dst[i] = src && *src ? *src++ : ' ';
    dst[3] = '\0';
}

static void map_clear(map2d *m)
{
    for (int y = 0; y < FINE; ++y)
        for (int x = 0; x < FINE; ++x) {
            m->owner[y][x] = -1;
            text_set(m->text[y][x], NULL);
        }
}

/* Paints the box cell[] + extent[] (finest level, z ignored). */
static void map_paint(map2d *m, const int32_t cell[3], const uint32_t ext[3], long owner, const char *text)
{
    for (int32_t y = cell[1]; y < cell[1] + (int32_t)ext[1] && y < FINE; ++y)
        for (int32_t x = cell[0]; x < cell[0] + (int32_t)ext[0] && x < FINE; ++x) {
            if (y < 0 || x < 0) continue;
            m->owner[y][x] = owner;
            if (text) text_set(m->text[y][x], text);
        }
}

static long own(const map2d *m, int x, int y)
{
    return x < 0 || y < 0 || x >= FINE || y >= FINE ? -2 : m->owner[y][x];
}

/* y up: the top row first.  A wall wherever two owners meet. */
static void map_print(const map2d *m)
{
    for (int y = FINE; y >= 0; --y) {
        /* the wall line above row y - 1 (below row y) */
        printf("    ");
        for (int x = 0; x <= FINE; ++x) {
            const int wall_l = own(m, x - 1, y) != own(m, x - 1, y - 1);
            const int wall_r = own(m, x, y) != own(m, x, y - 1);
            const int wall_u = own(m, x - 1, y) != own(m, x, y);
            const int wall_d = own(m, x - 1, y - 1) != own(m, x, y - 1);
            putchar(wall_l || wall_r || wall_u || wall_d ? '+' : ' ');
            if (x < FINE) printf("%s", wall_r ? "---" : "   ");
        }
        putchar('\n');
        if (y == 0) break;
        printf("  %d ", y - 1);
        for (int x = 0; x <= FINE; ++x) {
            putchar(own(m, x - 1, y - 1) != own(m, x, y - 1) ? '|' : ' ');
            if (x < FINE) printf("%s", m->text[y - 1][x]);
        }
        putchar('\n');
    }
    printf("     ");
    for (int x = 0; x < FINE; ++x) printf(" %d  ", x);
    putchar('\n');
}

/* ---- the recorded build ----------------------------------------------- */

static void print_event(const sidx_event *e)
{
    char line[256];
    sidx_event_format(e, line, sizeof line);
    const char *s = line;
    while (*s == ' ') ++s;
    printf("  %s\n", s);
}

static int overlaps(const int32_t a[3], const uint32_t ae[3], const int32_t b[3], const uint32_t be[3])
{
    for (int i = 0; i < 2; ++i)
        if (a[i] >= b[i] + (int32_t)be[i] || b[i] >= a[i] + (int32_t)ae[i]) return 0;
    return 1;
}

/* Is every id of the leaf event `sub` in the list of `of`? */
static int prims_subset(const sidx_event *sub, const sidx_event *of)
{
    for (uint32_t i = 0; i < sub->count; ++i) {
        int found = 0;
        for (uint32_t j = 0; j < of->count && !found; ++j) found = sub->prims[i] == of->prims[j];
        if (!found) return 0;
    }
    return 1;
}

static sidx_accel *build_or_fail(const lesson_args *args, const char *name, const sidx_mesh *m,
                                 const sidx_build_options *opt)
{
    sidx_accel *a = NULL;
    sidx_error err = {0};
    if (sidx_accel_build(name, m, opt, &a, &err) != SIDX_OK) lesson_fail(args, err.message);
    return a;
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_LAMBDA(knobs), LESSON_LEAF_SIZE(knobs), LESSON_MAX_DEPTH(knobs), {0}};
    lesson_args args = {.name = "23_irregular_grid", .usage = usage, .scene = "stadium", .options = options};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "grid-irregular");
    lesson_need(&args, "grid");

    /* ---- 1 ---- */
    sidx_mesh m2 = make_scene2d(&args);
    /* The top grid from the formula: lambda = 4/n gives R = 2 per axis on
     * the square; cut while a part holds more than one small triangle
     * (leaf size 1), at most 2 levels: the finest level is 8 x 8. */
    sidx_build_options o2 = {0};
    o2.grid_density = 4.0f / (float)N2D;
    o2.leaf_size = 1;
    o2.max_depth = 2;
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook rh = sidx_recorder_hook(&rec);
    rh.mask = SIDX_EVMASK_BUILD;
    o2.hook = &rh;
    sidx_accel *ig = build_or_fail(&args, "grid-irregular", &m2, &o2);
    if (rec.overflow) lesson_fail(&args, "out of memory recording the build");
    sidx_accel_stats st2;
    sidx_accel_stats_get(ig, &st2);

    printf("== 1. The base grid: a 2 x 2 top grid, cut into quarters where the triangles are\n");
    printf("  %u triangles in z = 0 on [0, 8] x [0, 8]; lambda = 4/n, leaf size 1, 2 levels\n", (unsigned)N2D);
    map2d base, merged;
    map_clear(&base);
    map_clear(&merged);
    int n_leaf = 0, n_merge = 0, n_grow = 0, n_stop = 0, fine_ok = 1;
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        if (e->type != SIDX_EV_BUILD_LEAF) continue;
        char t[16];
        if (e->count)
            snprintf(t, sizeof t, " %u ", e->count < 10u ? e->count : 9u);
        else
            snprintf(t, sizeof t, " . ");
        map_paint(&base, e->cell, e->extent, n_leaf, t);
        map_paint(&merged, e->cell, e->extent, (long)e->node, t);
        fine_ok &= e->extent[0] >= 1 && e->cell[0] + (int32_t)e->extent[0] <= FINE;
        ++n_leaf;
        print_event(e);
    }
    printf("  %d base cells (walls between them; inside: triangles in the cell, . = none):\n", n_leaf);
    map_print(&base);

    /* ---- 2 ---- */
    printf("\n== 2. Merge: neighbours with the same triangles become one box\n");
    for (size_t i = 0; i < rec.count; ++i)
        if (rec.events[i].type == SIDX_EV_BUILD_MERGE) {
            print_event(&rec.events[i]);
            ++n_merge;
        }
    /* A merged cell must stay a box: the finest cells it owns fill the
     * rectangle they span. */
    int boxes_ok = 1;
    for (uint32_t c = 0; c < st2.nodes; ++c) {
        int x0 = FINE, y0 = FINE, x1 = -1, y1 = -1, cnt = 0;
        for (int y = 0; y < FINE; ++y)
            for (int x = 0; x < FINE; ++x)
                if (merged.owner[y][x] == (long)c) {
                    if (x < x0) x0 = x;
                    if (y < y0) y0 = y;
                    if (x > x1) x1 = x;
                    if (y > y1) y1 = y;
                    ++cnt;
                }
        if (cnt == 0 || cnt != (x1 - x0 + 1) * (y1 - y0 + 1)) boxes_ok = 0;
    }
    printf("  %d merges: %d base cells became %u cells, each still a box: %s\n", n_merge, n_leaf, st2.nodes,
           boxes_ok ? "yes" : "NO");
    map_print(&merged);

    /* ---- 3 ---- */
    printf("\n== 3. Expand: each cell's box grows over neighbours holding a subset of its triangles\n");
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        if (e->type != SIDX_EV_BUILD_EXPAND) continue;
        if (e->result == 1) {
            print_event(e);
            ++n_grow;
        } else {
            ++n_stop;
        }
    }
    /* Check the rule on the result: every base cell an expanded box covers
     * holds a subset of the expanding cell's triangles (the base cells'
     * lists come with the build_leaf events; a cell's own list is that of
     * any base cell it was merged from). */
    int subset_ok = 1, expanded_cells = 0;
    for (uint32_t c = 0; c < st2.nodes; ++c) {
        const sidx_event *mine = NULL, *last = NULL;
        for (size_t i = 0; i < rec.count; ++i) {
            const sidx_event *e = &rec.events[i];
            if (e->type == SIDX_EV_BUILD_LEAF && e->node == c && !mine) mine = e;
            if (e->type == SIDX_EV_BUILD_EXPAND && e->node == c && e->result == 1) last = e;
        }
        if (!mine || !last) continue;
        ++expanded_cells;
        for (size_t i = 0; i < rec.count; ++i) {
            const sidx_event *e = &rec.events[i];
            if (e->type == SIDX_EV_BUILD_LEAF && overlaps(e->cell, e->extent, last->cell, last->extent) &&
                !prims_subset(e, mine))
                subset_ok = 0;
        }
    }
    printf("  %d steps grown; %d refused (a neighbour holds a triangle the cell does not: the\n"
           "  build_expand events with result 0, which sidx-step --build lists too).  %d cells are\n"
           "  larger after expansion.  Every base cell inside an expanded box holds a subset of that\n"
           "  cell's triangles: %s\n",
           n_grow, n_stop, expanded_cells, subset_ok ? "yes" : "NO");

    /* ---- 4 ---- */
    printf("\n== 4. Traversal (simplified, finest level: 12 steps)\n");
    /* y = 1.25 + x/2: it crosses 8 columns and 4 rows of the finest level
     * and no corner, so a walk cell by cell takes 8 + 4 = 12 steps. */
    sidx_ray ray;
    sidx_ray_init(&ray, sidx_v3(-1.0f, 0.75f, 0.0f), sidx_v3(1.0f, 0.5f, 0.0f), 0.0f, INFINITY);
    printf("  ray o = (-1, 0.75, 0), d = (1, 0.5, 0)\n");
    sidx_build_options og = {0};
    og.grid_density = (float)(FINE * FINE) / (float)N2D; /* R = sqrt(lambda n) = 8 per axis */
    sidx_accel *ug = build_or_fail(&args, "grid", &m2, &og);
    sidx_accel_stats stu;
    sidx_accel_stats_get(ug, &stu);
    /* the cells each walk enters */
    sidx_recorder wu, wi;
    sidx_recorder_init(&wu);
    sidx_recorder_init(&wi);
    sidx_hook hu = sidx_recorder_hook(&wu), hi = sidx_recorder_hook(&wi);
    hu.mask = hi.mask = SIDX_EVMASK(SIDX_EV_NODE_ENTER);
    sidx_query qu = {0, SIDX_TRAVERSE_DEFAULT, &hu, 0}, qi = {0, SIDX_TRAVERSE_DEFAULT, &hi, 0};
    sidx_hit hit_u, hit_i;
    sidx_accel_intersect(ug, &ray, &qu, &hit_u);
    sidx_accel_intersect(ig, &ray, &qi, &hit_i);
    const int steps_u = (int)wu.count, steps_i = (int)wi.count;
    printf("  uniform grid at the finest level (%u x %u), %d steps:\n   ", stu.res[0], stu.res[1], steps_u);
    for (int i = 0; i < steps_u; ++i) printf(" (%d,%d)", (int)wu.events[i].cell[0], (int)wu.events[i].cell[1]);
    printf("\n  irregular grid, %d steps, each across a cell's expanded box:\n", steps_i);
    for (int i = 0; i < steps_i; ++i) print_event(&wi.events[i]);
    /* The map: the merged cells' walls; inside, the uniform grid's step
     * number and the letter of the irregular grid's step covering it. */
    map2d path = merged;
    for (int y = 0; y < FINE; ++y)
        for (int x = 0; x < FINE; ++x) text_set(path.text[y][x], NULL);
    for (int i = 0; i < steps_u; ++i) {
        const sidx_event *u = &wu.events[i];
        const float tm = 0.5f * (u->t_near + u->t_far);
        char letter = '?';
        for (int j = 0; j < steps_i; ++j)
            if (tm >= wi.events[j].t_near && tm <= wi.events[j].t_far) letter = (char)('A' + j);
        char t[16];
        snprintf(t, sizeof t, "%2d%c", (i + 1) % 100, letter);
        if (u->cell[0] >= 0 && u->cell[0] < FINE && u->cell[1] >= 0 && u->cell[1] < FINE)
            text_set(path.text[u->cell[1]][u->cell[0]], t);
    }
    printf("  the finest cells the ray crosses: uniform step number, irregular step letter:\n");
    map_print(&path);
    const int same_hit = hit_u.prim == hit_i.prim && (hit_u.prim == SIDX_NO_HIT || hit_u.t == hit_i.t);
    if (hit_i.prim != SIDX_NO_HIT)
        printf("  both hit triangle %u at t = %g: %s\n", hit_i.prim, (double)hit_i.t, same_hit ? "yes" : "NO");
    else
        printf("  both miss: %s\n", same_hit ? "yes" : "NO");
    printf("  %d steps at the finest level, %d on the irregular grid.\n", steps_u, steps_i);
    sidx_recorder_free(&wu);
    sidx_recorder_free(&wi);
    sidx_accel_destroy(ug);
    sidx_accel_destroy(ig);
    sidx_recorder_free(&rec);
    sidx_mesh_free(&m2);

    /* ---- 5 ---- */
    sidx_mesh m = lesson_open_scene(&args);
    printf("\n== 5. Measured on '%s' (%u triangles), %d random rays into its box\n", args.scene, m.num_triangles,
           NRAYS);
    sidx_ray *rays = malloc(NRAYS * sizeof *rays);
    sidx_hit *hits_u = malloc(NRAYS * sizeof *hits_u), *hits_i = malloc(NRAYS * sizeof *hits_i);
    if (!rays || !hits_u || !hits_i) lesson_fail(&args, "out of memory");
    lesson_rays_into_box(sidx_mesh_bounds(&m), rays, NRAYS, 23u);
    const char *const names[2] = {"grid", "grid-irregular"};
    double cells[2], tests[2], us[2], ms[2];
    sidx_accel_stats st[2];
    for (int k = 0; k < 2; ++k) {
        const double t0 = lesson_seconds();
        sidx_accel *a = build_or_fail(&args, names[k], &m, k ? &knobs : NULL);
        ms[k] = 1e3 * (lesson_seconds() - t0);
        sidx_accel_stats_get(a, &st[k]);
        sidx_counters c;
        lesson_count_rays(a, rays, NRAYS, &c, k ? hits_i : hits_u);
        cells[k] = (double)c.n[SIDX_EV_NODE_ENTER] / NRAYS;
        tests[k] = (double)c.n[SIDX_EV_PRIM_TEST] / NRAYS;
        us[k] = lesson_us_per_ray(a, rays, NRAYS, 3);
        sidx_accel_destroy(a);
    }
    int same = 1;
    for (int i = 0; i < NRAYS; ++i) same &= hits_u[i].t == hits_i[i].t; /* both +inf on a miss */
    printf("  %-16s %10s %12s %12s %10s %10s %10s\n", "", "cells", "visited/ray", "tests/ray", "KiB", "build ms",
           "us/ray");
    for (int k = 0; k < 2; ++k)
        printf("  %-16s %10u %12.2f %12.2f %10.1f %10.2f %10.2f\n", names[k], st[k].nodes, cells[k], tests[k],
               (double)st[k].bytes / 1024.0, ms[k], us[k]);
    printf("  The irregular grid visits %.1fx fewer cells per ray and tests %.1fx fewer triangles; it\n"
           "  uses %.1fx the memory of the uniform grid.  Same closest hits: %s\n",
           cells[0] / cells[1], tests[0] / tests[1], (double)st[1].bytes / (double)st[0].bytes, same ? "yes" : "NO");
    const int mem_more = st[1].bytes > st[0].bytes; /* the slide: "Approach needs more memory" */
    free(rays);
    free(hits_u);
    free(hits_i);
    sidx_mesh_free(&m);

    lesson_check("base_within_finest_level", fine_ok && n_leaf > 4);
    lesson_check("merged_cells_are_boxes", boxes_ok && n_merge > 0);
    lesson_check("expanded_over_subsets", subset_ok && n_grow > 0);
    lesson_check("finest_level_12_steps", steps_u == 12 && stu.res[0] == FINE && stu.res[1] == FINE);
    lesson_check("irregular_fewer_steps", steps_i < steps_u);
    lesson_check("same_hit", same_hit);
    lesson_check("same_hits", same);
    lesson_check("fewer_cells_visited", cells[1] < cells[0]);
    lesson_check("needs_more_memory", mem_more);
    return 0;
}
