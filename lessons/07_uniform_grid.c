/* 07_uniform_grid.c — the uniform grid: resolution, 3D-DDA, mailboxing.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Uniform Grids" ("Want:
 * number of cells is O(n) ... Usually R_{x,y,z} = d_{x,y,z} ∛(λn/V)"),
 * "Uniform Grid Traversal" ("3D-DDA ... Step through the structure cell by
 * cell", "Mailboxing: single primitive can be referenced in many cells ...
 * Per-ray cache of object IDs").  Deck 001: "Uniform Grid" ("What is a
 * good number of voxels?") and its figure "Too few cells: requires
 * checking every primitive / Too many cells: walking through a lot of
 * empty space".
 *
 * What it shows, on one scene (default teapot):
 *   1. the resolution formula worked out for several densities λ, next to
 *      the resolution the grid actually chose;
 *   2. one ray walked through a coarse grid, cell by cell, as the printer
 *      shows the 3D-DDA's NODE_ENTER events, then the DDA's own state
 *      (step, tDelta, tMax per axis, the axis that steps) worked out from
 *      the grid's box and cell size, beside the library's cells;
 *   3. mailboxing on and off: triangle tests per ray, measured;
 *   4. too few vs too many cells: cells visited, triangle tests and time
 *      per ray across λ from 1/16 to 256.
 *
 * Read:  lib/grid.c, grid_walk
 * Run:   build/lessons/07_uniform_grid [SCENE]
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

static void usage(FILE *f)
{
    fprintf(f, "usage: 07_uniform_grid [--help] [build knobs] [SCENE]\n"
               "\n"
               "Uniform grid: the resolution formula for several lambda, a ray's 3D-DDA walk cell by\n"
               "cell, what mailboxing saves, and too few vs too many cells.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "The knob below sets the density of the grid the one ray walks (part 2, default\n"
               "lambda = 1/16: a coarse grid, few cells to print); the lambda sweep is the lesson's\n"
               "own.  The checks hold for the defaults.\n");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define NRAYS 4000
static sidx_ray rays[NRAYS];

static void make_rays(const sidx_mesh *m)
{
    const sidx_aabb box = sidx_mesh_bounds(m);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const float R = sidx_v3_length(ext);
    uint32_t seed = 2024u;
    for (int i = 0; i < NRAYS; ++i) {
        float f[5];
        for (int j = 0; j < 5; ++j) { seed = seed * 1664525u + 1013904223u; f[j] = (float)(seed >> 8) / 16777216.0f; }
        const float z = 2 * f[0] - 1, ang = 6.2831853f * f[1], s = sqrtf(1 - z * z);
        const sidx_vec3 o = sidx_v3_add(ctr, sidx_v3(R * s * cosf(ang), R * s * sinf(ang), R * z));
        const sidx_vec3 t = sidx_v3(box.min.x + f[2] * ext.x, box.min.y + f[3] * ext.y, box.min.z + f[4] * ext.z);
        sidx_ray_init(&rays[i], o, sidx_v3_sub(t, o), 0.0f, INFINITY);
    }
}

typedef struct {
    double cells, tris, mailbox, us_per_ray, build_ms;
    sidx_accel_stats st;
    float t[NRAYS];
} measured;

static int measure(const char *name, const sidx_mesh *m, float lambda, measured *out)
{
    sidx_build_options opt = {0};
    opt.grid_density = lambda;
    sidx_accel *a = NULL;
    sidx_error err = {0};
    const double t0 = now_s();
    if (sidx_accel_build(name, m, &opt, &a, &err) != SIDX_OK) {
        fprintf(stderr, "07_uniform_grid: %s\n", err.message);
        return 0;
    }
    out->build_ms = 1e3 * (now_s() - t0);
    sidx_accel_stats_get(a, &out->st);
    sidx_counters c;
    sidx_counters_init(&c);
    const sidx_hook ch = sidx_counters_hook(&c);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ch, 0};
    for (int i = 0; i < NRAYS; ++i) {
        sidx_hit h;
        sidx_accel_intersect(a, &rays[i], &q, &h);
        out->t[i] = h.t;
    }
    out->cells = (double)c.n[SIDX_EV_NODE_ENTER] / NRAYS;
    out->tris = (double)c.n[SIDX_EV_PRIM_TEST] / NRAYS;
    out->mailbox = (double)c.n[SIDX_EV_MAILBOX_HIT] / NRAYS;
    /* time: the fastest of five passes (the machine may be busy) */
    double best = INFINITY;
    for (int pass = 0; pass < 5; ++pass) {
        const double t1 = now_s();
        for (int i = 0; i < NRAYS; ++i) {
            sidx_hit h;
            sidx_accel_intersect(a, &rays[i], NULL, &h);
        }
        const double dt = now_s() - t1;
        if (dt < best) best = dt;
    }
    out->us_per_ray = 1e6 * best / NRAYS;
    sidx_accel_destroy(a);
    return 1;
}

/* Checks the DDA's NODE_ENTER events: each cell a face neighbour of the
 * one before, entered where the previous one was left. */
typedef struct {
    int n, ok;
    int32_t last[3];
    float last_far;
    int32_t cells[64][3]; /* the first 64 cells entered, for part 2's DDA table */
    float first_near;
} dda_check;

static void dda_fn(const sidx_event *ev, void *user)
{
    dda_check *d = user;
    if (ev->type != SIDX_EV_NODE_ENTER) return;
    if (d->n > 0) {
        int diff = 0;
        for (int k = 0; k < 3; ++k) diff += abs(ev->cell[k] - d->last[k]);
        if (diff != 1) d->ok = 0;
        if (ev->t_near != d->last_far) d->ok = 0;
        if (ev->t_far < ev->t_near) d->ok = 0;
    }
    memcpy(d->last, ev->cell, sizeof d->last);
    if (d->n < 64) memcpy(d->cells[d->n], ev->cell, sizeof d->cells[0]);
    if (d->n == 0) d->first_near = ev->t_near;
    d->last_far = ev->t_far;
    d->n++;
}

/* The 3D-DDA's own state (Amanatides & Woo 1987; deck 000 "Uniform Grid
 * Traversal"), worked out here in double from the grid's box and cell size
 * alone, beside the cells the library entered:
 *   step[k]   = the sign of d[k]: which neighbour comes next on axis k;
 *   tDelta[k] = cell[k] / |d[k]|: how much t one cell on axis k takes;
 *   tMax[k]   = the t at which the ray leaves the current cell on axis k.
 * Each step goes along the axis with the smallest tMax, then adds that
 * axis's tDelta to its tMax.  Returns 1 if every cell matches the library's. */
static int dda_table(const sidx_accel *a, const sidx_ray *ray, const dda_check *dc)
{
    sidx_grid_cells g;
    sidx_error err = {0};
    if (sidx_grid_cells_get(a, &g, &err) != SIDX_OK) {
        printf("  (no grid view: %s)\n", err.message);
        return 0;
    }
    const float *o = sidx_v3_array(&ray->org), *d = sidx_v3_array(&ray->dir);
    const float *lo = sidx_v3_array(&g.box.min);
    int cell[3], step[3];
    double t_delta[3], t_max[3];
    for (int k = 0; k < 3; ++k) {
        /* the entry cell: where the ray enters the grid box (t_near of the first cell) */
        const double p = (double)o[k] + (double)dc->first_near * d[k];
        int c = (int)floor((p - lo[k]) / g.cell[k]);
        cell[k] = c < 0 ? 0 : c >= (int)g.res[k] ? (int)g.res[k] - 1 : c;
        step[k] = d[k] > 0 ? 1 : d[k] < 0 ? -1 : 0;
        t_delta[k] = d[k] != 0 ? g.cell[k] / fabs((double)d[k]) : INFINITY;
        const double wall = lo[k] + (double)g.cell[k] * (cell[k] + (step[k] > 0 ? 1 : 0));
        t_max[k] = d[k] != 0 ? (wall - o[k]) / d[k] : INFINITY;
    }
    printf("\n  The 3D-DDA's own state, worked out from the grid's box and cell size:\n");
    printf("    step = (%+d, %+d, %+d)   tDelta = cell / |d| = (%.6g, %.6g, %.6g)\n", step[0], step[1], step[2],
           t_delta[0], t_delta[1], t_delta[2]);
    printf("    %-4s %-12s %10s %10s %10s   %-6s %s\n", "step", "cell", "tMax x", "tMax y", "tMax z", "next", "library");
    int agree = 1;
    const int n = dc->n < 64 ? dc->n : 64;
    for (int i = 0; i < n; ++i) {
        const int axis = t_max[0] <= t_max[1] ? (t_max[0] <= t_max[2] ? 0 : 2) : (t_max[1] <= t_max[2] ? 1 : 2);
        const int same = cell[0] == dc->cells[i][0] && cell[1] == dc->cells[i][1] && cell[2] == dc->cells[i][2];
        agree &= same;
        char here[24], lib[24];
        snprintf(here, sizeof here, "(%d,%d,%d)", cell[0], cell[1], cell[2]);
        snprintf(lib, sizeof lib, "(%d,%d,%d)", (int)dc->cells[i][0], (int)dc->cells[i][1], (int)dc->cells[i][2]);
        printf("    %-4d %-12s %10.6g %10.6g %10.6g   %c%-5s %s%s\n", i + 1, here, t_max[0], t_max[1], t_max[2],
               step[axis] > 0 ? '+' : '-', axis == 0 ? "x" : axis == 1 ? "y" : "z", lib, same ? "" : "  <- differs");
        cell[axis] += step[axis];
        t_max[axis] += t_delta[axis];
    }
    printf("    (the walk stops where the library stopped: the hit lies in the last cell)\n");
    sidx_grid_cells_free(&g);
    return agree;
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_LAMBDA(knobs), {0}};
    lesson_args args = {.name = "07_uniform_grid", .usage = usage, .scene = "teapot", .options = options};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "grid");
    lesson_need(&args, "grid-nomailbox");
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    make_rays(&mesh);
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 d = sidx_aabb_extent(box);
    const double n = mesh.num_triangles, V = (double)d.x * d.y * d.z;

    /* ---- 1 ---- */
    printf("== 1. Resolution: R = d * cbrt(lambda * n / V)   on '%s'\n", args.scene);
    printf("  n = %u triangles, d = (%g, %g, %g), V = %g\n", mesh.num_triangles, d.x, d.y, d.z, V);
    printf("  %8s %10s   %-22s %-18s %10s\n", "lambda", "cbrt(.)", "formula R (rounded)", "grid chose", "cells");
    static const float lambdas[] = {1.0f / 16, 0.25f, 1.0f, 4.0f, 16.0f, 64.0f, 256.0f};
    const int nl = (int)(sizeof lambdas / sizeof lambdas[0]);
    measured *ms = calloc((size_t)nl + 2, sizeof *ms);
    if (!ms) { sidx_mesh_free(&mesh); return 1; }
    int formula_ok = 1, failed = 0;
    for (int i = 0; i < nl && !failed; ++i) {
        if (!measure("grid", &mesh, lambdas[i], &ms[i])) { failed = 1; break; }
        const double s = cbrt(lambdas[i] * n / V);
        int r[3];
        for (int k = 0; k < 3; ++k) {
            r[k] = (int)floor(sidx_v3_get(d, k) * s + 0.5);
            if (r[k] < 1) r[k] = 1;
        }
        char f[40], g[40];
        snprintf(f, sizeof f, "%d x %d x %d", r[0], r[1], r[2]);
        snprintf(g, sizeof g, "%u x %u x %u", ms[i].st.res[0], ms[i].st.res[1], ms[i].st.res[2]);
        printf("  %8g %10.4g   %-22s %-18s %10llu\n", lambdas[i], s, f, g,
               (unsigned long long)ms[i].st.res[0] * ms[i].st.res[1] * ms[i].st.res[2]);
        for (int k = 0; k < 3; ++k)
            if (abs(r[k] - (int)ms[i].st.res[k]) > 1) formula_ok = 0;
    }
    if (failed) { free(ms); sidx_mesh_free(&mesh); return 1; }
    printf("  cells = R_x R_y R_z ~ lambda * n: O(n) cells, ~cbrt(n) per axis.\n");

    /* ---- 2 ---- */
    sidx_build_options opt = knobs;
    char lam[32] = "1/16";
    if (opt.grid_density > 0.0f) snprintf(lam, sizeof lam, "%g", opt.grid_density);
    else opt.grid_density = 1.0f / 16;
    printf("\n== 2. One ray through a %s grid (lambda = %s), cell by cell (3D-DDA)\n",
           knobs.grid_density > 0.0f ? "chosen" : "coarse", lam);
    sidx_accel *a = NULL;
    if (sidx_accel_build("grid", &mesh, &opt, &a, &err) != SIDX_OK) {
        fprintf(stderr, "07_uniform_grid: %s\n", err.message);
        free(ms);
        sidx_mesh_free(&mesh);
        return 1;
    }
    /* the random ray that hits after the longest walk of at most 14 cells */
    int pick = 0;
    uint64_t longest = 0;
    for (int i = 0; i < NRAYS; ++i) {
        sidx_counters c;
        sidx_counters_init(&c);
        const sidx_hook ch = sidx_counters_hook(&c);
        sidx_query cq = {0, SIDX_TRAVERSE_DEFAULT, &ch, 0};
        sidx_hit hh;
        sidx_accel_intersect(a, &rays[i], &cq, &hh);
        const uint64_t cells = c.n[SIDX_EV_NODE_ENTER];
        if (hh.prim != SIDX_NO_HIT && cells <= 14 && cells > longest) { longest = cells; pick = i; }
    }
    const sidx_ray ray = rays[pick];
    printf("  grid %u x %u x %u; ray o = (%g, %g, %g), d = (%g, %g, %g)\n", ms[0].st.res[0], ms[0].st.res[1],
           ms[0].st.res[2], ray.org.x, ray.org.y, ray.org.z, ray.dir.x, ray.dir.y, ray.dir.z);
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    pr.mask = SIDX_EVMASK_TRAVERSAL & ~SIDX_EVMASK(SIDX_EV_PRIM_TEST);
    dda_check dc = {.n = 0, .ok = 1};
    sidx_tee tee = {{sidx_printer_hook(&pr), {dda_fn, &dc, SIDX_EVMASK(SIDX_EV_NODE_ENTER)}}, 2};
    const sidx_hook th = sidx_tee_hook(&tee);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &th, 0};
    sidx_hit h;
    sidx_accel_intersect(a, &ray, &q, &h);
    printf("  (triangle tests left out; mailbox lines are triangles already tested in an earlier cell)\n");
    printf("  %d cells, each a face neighbour of the last, entered at the t the last one was left: %s\n", dc.n,
           dc.ok ? "yes" : "NO");
    const int dda_agrees = dda_table(a, &ray, &dc);
    sidx_accel_destroy(a);

    /* ---- 3 ---- */
    printf("\n== 3. Mailboxing, lambda = 4, %d random rays\n", NRAYS);
    measured *mb = &ms[nl], *nomb = &ms[nl + 1];
    if (!measure("grid", &mesh, 4.0f, mb) || !measure("grid-nomailbox", &mesh, 4.0f, nomb)) {
        free(ms);
        sidx_mesh_free(&mesh);
        return 1;
    }
    int same = 1;
    for (int i = 0; i < NRAYS; ++i) same &= mb->t[i] == nomb->t[i];
    printf("  %-16s %12s %14s %12s\n", "", "tri tests", "skipped (mb)", "us per ray");
    printf("  %-16s %12.2f %14.2f %12.2f\n", "with mailbox", mb->tris, mb->mailbox, mb->us_per_ray);
    printf("  %-16s %12.2f %14s %12.2f\n", "without", nomb->tris, "-", nomb->us_per_ray);
    printf("  %llu references for %u triangles: %.2f cells per triangle on average; the mailbox saves\n"
           "  %.0f%% of the triangle tests.  Same hits: %s\n",
           (unsigned long long)mb->st.prim_refs, mesh.num_triangles, (double)mb->st.prim_refs / mesh.num_triangles,
           100.0 * (1.0 - mb->tris / nomb->tris), same ? "yes" : "NO");

    /* ---- 4 ---- */
    printf("\n== 4. Too few vs too many cells (%d random rays)\n", NRAYS);
    printf("  %8s %10s %12s %12s %12s %11s %10s\n", "lambda", "cells", "visited/ray", "tri tests", "work/ray",
           "us per ray", "build ms");
    int best = 0;
    double best_work = INFINITY;
    for (int i = 0; i < nl; ++i) {
        const double work = ms[i].cells + ms[i].tris;
        if (work < best_work) { best_work = work; best = i; }
        printf("  %8g %10llu %12.2f %12.2f %12.2f %11.2f %10.2f\n", lambdas[i],
               (unsigned long long)ms[i].st.res[0] * ms[i].st.res[1] * ms[i].st.res[2], ms[i].cells, ms[i].tris, work,
               ms[i].us_per_ray, ms[i].build_ms);
    }
    printf("  work = cells visited + triangles tested.  Few big cells: every ray tests many triangles.\n"
           "  Many small cells: every ray walks through many empty cells.  The least work here: lambda = %g.\n",
           lambdas[best]);
    lesson_check("resolution_formula", formula_ok);
    lesson_check("dda_cells_in_order", dc.ok && dc.n > 1);
    lesson_check("dda_state_gives_library_cells", dda_agrees && dc.n > 1);
    lesson_check("mailbox_saves_tests", same && mb->tris < nomb->tris);
    lesson_check("middle_lambda_best", best > 0 && best < nl - 1);
    free(ms);
    sidx_mesh_free(&mesh);
    return 0;
}
