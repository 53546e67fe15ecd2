/* 21_mailboxes.c — mailboxing: per-object cache of ray ids against per-ray
 * cache of object ids.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Uniform Grid Traversal"
 * ("Mailboxing — single primitive can be referenced in many cells — avoid
 * multiple intersections — keep track of intersection tests — per-object
 * cache of ray IDs: problem with concurrent access — per-ray cache of
 * object IDs: data local to a ray (better!)").
 *
 * The library's grids keep the per-ray kind only: 32 slots on the stack
 * of each ray, indexed by triangle id mod 32 (lib/grid_internal.h).  The
 * per-object kind — every triangle stores the id of the last ray that
 * tested it (Amanatides & Woo 1987) — is shown here as a demonstration
 * inside the lesson: the grid is walked WITHOUT a mailbox ("grid-nomailbox")
 * and its PRIM_TEST events, the triangle tests in walk order, are replayed
 * through each kind of mailbox, which then says which tests it would have
 * skipped.  What it shows, on the camera rays of one image (default scene:
 * the teapot, grid density λ = 4):
 *   1. one ray's walk, cell by cell, the repeated triangles marked;
 *   2. the replays: no mailbox; per-ray tables of 1 to 256 slots (the
 *      32-slot replay must match the library's "grid" test for test);
 *      per-object, one thread; per-object shared by 2 and 4 threads taking
 *      neighbouring rays in turn, one test each per step — the "concurrent
 *      access": skips lost when another ray overwrote the id, and the
 *      writes to a cache line another thread wrote last (each a transfer of
 *      that line between cores on a real machine).
 * The replay counts the events of a real walk; the threads are simulated
 * (one test each in turn), so the lost skips are deterministic.
 *
 * Read:  lib/grid_internal.h, sidx__mailbox_seen
 * Run:   build/lessons/21_mailboxes [SCENE]
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
    fprintf(f, "usage: 21_mailboxes [--help] [build knobs] [SCENE]\n"
               "\n"
               "Mailboxing in a uniform grid: the triangle tests of a walk without a mailbox replayed\n"
               "through per-ray tables of 1 to 256 slots and through a per-object mailbox shared by 1,\n"
               "2 and 4 simulated threads — tests saved, memory, skips lost, cache lines moved.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "--lambda changes both grids' cells per triangle (default here 4: finer cells, more\n"
               "triangles in several cells, more for a mailbox to save).  The checks hold for the\n"
               "default.\n");
}

#define W 160
#define H 120
#define NRAYS (W * H)
#define LAMBDA 4.0f
#define LINE_PRIMS 16 /* 4-byte ray ids per 64-byte cache line */
static sidx_ray rays[NRAYS];

/* The triangle tests of every ray, in walk order: seq[start[r] .. start[r+1]). */
typedef struct {
    uint32_t *seq;
    size_t n, cap;
    size_t start[NRAYS + 1];
    int cur;
} tests_log;

static void log_fn(const sidx_event *ev, void *user)
{
    tests_log *l = user;
    if (ev->type != SIDX_EV_PRIM_TEST) return;
    if (l->n == l->cap) {
        const size_t cap = l->cap ? 2 * l->cap : 1 << 16;
        uint32_t *p = realloc(l->seq, cap * sizeof *p);
        if (!p) return; /* counted as fewer tests: the replays then disagree with the library */
        l->seq = p;
        l->cap = cap;
    }
    l->seq[l->n++] = ev->prim;
}

/* Per-ray table of `slots` ids, indexed by prim mod slots: the library's
 * kind at slots = 32.  Returns the tests performed. */
static uint64_t replay_per_ray(const tests_log *l, uint32_t slots)
{
    uint32_t *tab = malloc(slots * sizeof *tab);
    uint64_t tests = 0;
    if (!tab) return 0;
    for (int r = 0; r < NRAYS; ++r) {
        memset(tab, 0xff, slots * sizeof *tab);
        for (size_t k = l->start[r]; k < l->start[r + 1]; ++k) {
            uint32_t *slot = &tab[l->seq[k] % slots];
            if (*slot == l->seq[k]) continue;
            *slot = l->seq[k];
            ++tests;
        }
    }
    free(tab);
    return tests;
}

/* Per-object mailbox (one ray id per triangle) shared by `threads`
 * threads: thread j traces rays j, j + threads, ...; in each step every
 * thread makes its next triangle test.  *moves: writes to a cache line of
 * the mailbox another thread wrote last. */
static uint64_t replay_per_object(const tests_log *l, uint32_t ntris, int threads, uint64_t *moves)
{
    uint32_t *last = malloc(ntris * sizeof *last);
    int8_t *owner = malloc(((size_t)ntris / LINE_PRIMS + 1) * sizeof *owner);
    uint64_t tests = 0;
    *moves = 0;
    if (!last || !owner) {
        free(last);
        free(owner);
        return 0;
    }
    memset(last, 0xff, ntris * sizeof *last);
    memset(owner, 0xff, ((size_t)ntris / LINE_PRIMS + 1) * sizeof *owner);
    int ray[4];
    size_t pos[4];
    for (int j = 0; j < threads; ++j) {
        ray[j] = j;
        pos[j] = l->start[j];
    }
    for (int busy = threads; busy > 0;) {
        busy = 0;
        for (int j = 0; j < threads; ++j) {
            while (ray[j] < NRAYS && pos[j] == l->start[ray[j] + 1]) { /* next ray of this thread */
                ray[j] += threads;
                if (ray[j] < NRAYS) pos[j] = l->start[ray[j]];
            }
            if (ray[j] >= NRAYS) continue;
            ++busy;
            const uint32_t p = l->seq[pos[j]++];
            if (last[p] == (uint32_t)ray[j]) continue; /* skipped: this ray tested p already */
            last[p] = (uint32_t)ray[j];
            ++tests;
            if (owner[p / LINE_PRIMS] != (int8_t)j) {
                if (owner[p / LINE_PRIMS] >= 0) ++*moves;
                owner[p / LINE_PRIMS] = (int8_t)j;
            }
        }
    }
    free(owner);
    free(last);
    return tests;
}

/* One ray's walk: the cells with triangles and the triangles tested in
 * them, repeats starred; empty cells only counted. */
typedef struct {
    uint32_t seen[256];
    int n, cells, printed, cell_open;
    int32_t cell[3];
} walk_print;

static void walk_fn(const sidx_event *ev, void *user)
{
    walk_print *w = user;
    if (ev->type == SIDX_EV_NODE_ENTER) {
        w->cells++;
        w->cell_open = 0;
        memcpy(w->cell, ev->cell, sizeof w->cell);
    } else if (ev->type == SIDX_EV_PRIM_TEST) {
        if (!w->cell_open) {
            w->cell_open = 1;
            printf("%s  cell %d (%d,%d,%d):", w->printed++ ? "\n" : "", w->cells, w->cell[0], w->cell[1], w->cell[2]);
        }
        int rep = 0;
        for (int i = 0; i < w->n && !rep; ++i) rep = w->seen[i] == ev->prim;
        if (!rep && w->n < 256) w->seen[w->n++] = ev->prim;
        printf(" %u%s", ev->prim, rep ? "*" : "");
    }
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_LAMBDA(knobs), {0}};
    lesson_args args = {.name = "21_mailboxes",
                        .usage = usage,
                        .scene = "teapot",
                        .options = options,
                        .refused = "the grid has no other knob, and the lesson sets its mailbox modes itself"};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "grid");
    lesson_need(&args, "grid-nomailbox");
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    sidx_build_options opt = {0};
    opt.grid_density = knobs.grid_density > 0.0f ? knobs.grid_density : LAMBDA;
    sidx_accel *plain = NULL, *mb = NULL;
    if (sidx_accel_build("grid-nomailbox", &mesh, &opt, &plain, &err) != SIDX_OK ||
        sidx_accel_build("grid", &mesh, &opt, &mb, &err) != SIDX_OK)
        lesson_fail(&args, err.message);
    sidx_accel_stats st;
    sidx_accel_stats_get(mb, &st);

    /* a pinhole camera in front of the scene */
    const lesson_camera cam = lesson_camera_at(sidx_mesh_bounds(&mesh), 0.4f, 0.35f, 1.1f);
    lesson_camera_rays(&cam, W, H, 0.3f, 0.22f, rays);
    printf("== '%s' (%u triangles), grid %u x %u x %u (lambda = %g): %llu references, %.2f cells per triangle;\n"
           "   %d x %d camera rays\n",
           args.scene, mesh.num_triangles, st.res[0], st.res[1], st.res[2], (double)opt.grid_density, (unsigned long long)st.prim_refs,
           (double)st.prim_refs / mesh.num_triangles, W, H);

    /* ---- the walks without a mailbox, logged; the library's mailbox counted ---- */
    tests_log *lg = calloc(1, sizeof *lg);
    if (!lg) lesson_fail(&args, "out of memory");
    const sidx_hook lh = {log_fn, lg, SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    int same_hits = 1;
    uint64_t hit_rays = 0;
    for (int r = 0; r < NRAYS; ++r) {
        lg->start[r] = lg->n;
        const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &lh, (uint32_t)r};
        sidx_hit a, b;
        sidx_accel_intersect(plain, &rays[r], &q, &a);
        sidx_accel_intersect(mb, &rays[r], NULL, &b);
        same_hits &= a.prim == b.prim && (a.t == b.t || a.prim == SIDX_NO_HIT);
        hit_rays += a.prim != SIDX_NO_HIT;
    }
    lg->start[NRAYS] = lg->n;
    sidx_counters lib;
    lesson_count_rays(mb, rays, NRAYS, &lib, NULL);

    /* ---- 1 ---- */
    int pick = 0;
    size_t most = 0;
    for (int r = 0; r < NRAYS; ++r) {
        const size_t len = lg->start[r + 1] - lg->start[r];
        if (len > most && len <= 24) { most = len; pick = r; }
    }
    printf("\n== 1. One ray without a mailbox, cell by cell (* = tested before in an earlier cell)\n");
    walk_print wp;
    memset(&wp, 0, sizeof wp);
    const sidx_hook wh = {walk_fn, &wp, SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    const sidx_query wq = {0, SIDX_TRAVERSE_DEFAULT, &wh, 0};
    sidx_hit wh_hit;
    sidx_accel_intersect(plain, &rays[pick], &wq, &wh_hit);
    printf("\n  %d cells walked, %d of them empty; %zu tests of %d distinct triangles: a mailbox would\n"
           "  skip %zu\n", wp.cells, wp.cells - wp.printed, most, wp.n, most - (size_t)wp.n);

    /* ---- 2 ---- */
    printf("\n== 2. The %zu triangle tests of the walks, replayed through each mailbox\n", lg->n);
    printf("  %-34s %16s %10s %10s %14s\n", "mailbox", "memory", "tests/ray", "saved", "line moves/ray");
    const double none = (double)lg->n;
    printf("  %-34s %16s %10.2f %9.1f%% %14s\n", "none", "-", none / NRAYS, 0.0, "-");
    static const uint32_t slots[] = {1, 4, 32, 256};
    uint64_t per_ray[4];
    for (int k = 0; k < 4; ++k) {
        per_ray[k] = replay_per_ray(lg, slots[k]);
        char label[48], mem[32];
        snprintf(label, sizeof label, "per ray, %u slot%s%s", slots[k], slots[k] > 1 ? "s" : "",
                 slots[k] == 32 ? " (the library's)" : "");
        snprintf(mem, sizeof mem, "%u B per ray", 4 * slots[k]);
        printf("  %-34s %16s %10.2f %9.1f%% %14s\n", label, mem, (double)per_ray[k] / NRAYS,
               100.0 * (1.0 - (double)per_ray[k] / none), "-");
    }
    uint64_t per_obj[3], moves[3];
    static const int threads[3] = {1, 2, 4};
    for (int k = 0; k < 3; ++k) {
        per_obj[k] = replay_per_object(lg, mesh.num_triangles, threads[k], &moves[k]);
        char label[48], mem[32];
        snprintf(label, sizeof label, "per object, %d thread%s", threads[k], threads[k] > 1 ? "s" : "");
        snprintf(mem, sizeof mem, "%.1f KiB shared", 4.0 * mesh.num_triangles / 1024.0);
        printf("  %-34s %16s %10.2f %9.1f%% %14.3f\n", label, mem, (double)per_obj[k] / NRAYS,
               100.0 * (1.0 - (double)per_obj[k] / none), (double)moves[k] / NRAYS);
    }
    const uint64_t lib_tests = lib.n[SIDX_EV_PRIM_TEST];
    printf("  The library's \"grid\" itself: %.2f tests per ray, %.2f mailbox skips — the 32-slot replay\n"
           "  %s it test for test.  Same hits with and without its mailbox: %s (%llu of %d rays hit).\n",
           (double)lib_tests / NRAYS, (double)lib.n[SIDX_EV_MAILBOX_HIT] / NRAYS,
           lib_tests == per_ray[2] ? "matches" : "does NOT match", same_hits ? "yes" : "NO",
           (unsigned long long)hit_rays, NRAYS);
    printf("  One thread: the per-object mailbox saves every repeat (%.1f%%); the per-ray table saves\n"
           "  all but the collisions of its slots (32 slots: %.1f%%) in 128 bytes that never leave the\n"
           "  ray.  Shared by threads tracing neighbouring rays, the per-object ids overwrite each\n"
           "  other: %llu skips lost with 2 threads, %llu with 4, and every test writes to the structure\n"
           "  — %.2f and %.2f writes per ray to a cache line another core wrote last.  Per ray is better.\n",
           100.0 * (1.0 - (double)per_obj[0] / none), 100.0 * (1.0 - (double)per_ray[2] / none),
           (unsigned long long)(per_obj[1] - per_obj[0]), (unsigned long long)(per_obj[2] - per_obj[0]),
           (double)moves[1] / NRAYS, (double)moves[2] / NRAYS);

    const size_t total = lg->n;
    free(lg->seq);
    free(lg);
    sidx_accel_destroy(mb);
    sidx_accel_destroy(plain);
    sidx_mesh_free(&mesh);
    lesson_check("same_hits", same_hits);
    lesson_check("replay_matches_library", lib_tests == per_ray[2]);
    lesson_check("mailbox_saves_tests", per_ray[2] < total);
    lesson_check("per_object_saves_most", per_obj[0] <= per_ray[3] && per_ray[3] <= per_ray[2] && per_ray[2] <= per_ray[0]);
    lesson_check("sharing_loses_skips", per_obj[1] > per_obj[0] && per_obj[2] > per_obj[1]);
    lesson_check("sharing_moves_lines", moves[1] > 0 && moves[0] == 0);
    return 0;
}
