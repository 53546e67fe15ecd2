/* 06_object_vs_space.c — object partitioning (BVH) vs space partitioning (kd-tree).
 *
 * Slides (deck 000, "Spatial Index Structures"): "Object vs. Space
 * Partitioning" ("BVHs hierarchical partition objects into groups ...
 * Subgroups may be overlapping!" — "Space partitioning ... Subspaces are
 * non-overlapping and completely fill parent space"), "Bounding Volume
 * Hierarchies (BVHs)" ("BV can also overlap — Cannot terminate on first
 * intersection found"), "kD-Tree Traversal" ("Traversal can be terminated
 * as soon as surface intersection is found in the current node").  Deck
 * 001: "Primitive vs. Spatial" ("[-] Volumes can overlap, [-] Unable to
 * terminate on first hit" / "[+] No volume overlap, [+] Can terminate on
 * first hit, [-] May intersect primitive multiple times") and "K-D Trees"
 * ("Requirement: intersection point must lie within zone").
 *
 * What it shows: the same scene (default: a soup of 600 random triangles)
 * in a BVH and in a kd-tree.
 *   1. the top of both trees, boxes printed: the BVH's children overlap,
 *      the kd-tree's cells tile their parent; over the whole tree, how
 *      many sibling pairs overlap and by how much, and how many primitive
 *      references each stores (the kd-tree duplicates straddling ones);
 *   2. one ray traced in both, through the printer: the kd-tree stops in
 *      the cell where it found its hit ("terminate: hit_in_cell"), the BVH
 *      goes on until every remaining box lies behind the hit;
 *   3. over many rays: nodes visited after the closest hit was already
 *      found, and how often a kd-tree hit lay outside the current cell
 *      (the "must lie within zone" requirement, when it cannot stop).
 *   4. deck 001 "Spatial Data Structures Review" (spatial / primitive,
 *      build speed, search speed of BVH, kd-tree, uniform grid, octree),
 *      measured on one scene (default the teapot, or SCENE): references
 *      per triangle, build time, node visits and triangle tests per ray,
 *      time per ray, memory; each of the slide's ticks set beside what
 *      was measured.  Verdicts and checks come from counts (the same on
 *      every run); times are only printed.
 *
 * Read:  lib/kdtree_traverse.c, kd_walk_slide
 * Run:   build/lessons/06_object_vs_space [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default soup:600)
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
    fprintf(f, "usage: 06_object_vs_space [--help] [build knobs] [SCENE]\n"
               "\n"
               "The same scene in a BVH (object partitioning) and a kd-tree (space partitioning):\n"
               "overlapping boxes vs disjoint cells, and which can stop at the first hit.  Then\n"
               "deck 001's review table (BVH, kd-tree, uniform grid, octree) measured on one scene.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: soup:600; the review table:\n"
               "          teapot)\n"
               "The knobs below change every structure built (BVH and kd-tree in parts 1-3, all four\n"
               "in the review); the kd-tree's C_trav and C_tri stay 4 and 1 where --c-trav or --c-tri\n"
               "is not given.  The checks hold for the defaults.\n");
}

/* The build knobs of the command line (all zero: every structure's default). */
static sidx_build_options knobs;

/* The options for structure s of a part (kd = it is the kd-tree): the
 * knobs, and for the kd-tree the 4 : 1 costs where no cost knob is set. */
static sidx_build_options build_options(int kd)
{
    sidx_build_options opt = knobs;
    if (kd && !knobs.c_trav) opt.c_trav = 4.0f;
    if (kd && !knobs.c_tri) opt.c_tri = 1.0f;
    return opt;
}

static double volume(sidx_aabb b)
{
    if (sidx_aabb_is_empty(b)) return 0.0;
    const sidx_vec3 e = sidx_aabb_extent(b);
    return (double)e.x * e.y * e.z;
}

static sidx_aabb intersect_box(sidx_aabb a, sidx_aabb b)
{
    sidx_aabb r = {sidx_v3_max(a.min, b.min), sidx_v3_min(a.max, b.max)};
    return r;
}

typedef struct {
    uint32_t pairs, overlapping;
    double overlap_frac;    /* mean volume of the sibling overlap / volume of the parent */
    double cover_err;       /* max |vol(L) + vol(R) - vol(P)| / vol(P), space partitioning */
} tree_stats;

/* Sibling pairs from BUILD_NODE events (parent links). */
static tree_stats sibling_stats(const sidx_recorder *rec)
{
    tree_stats s = {0, 0, 0.0, 0.0};
    const sidx_event *ev = rec->events;
    for (size_t i = 0; i < rec->count; ++i) {
        if (ev[i].type != SIDX_EV_BUILD_NODE) continue;
        const sidx_event *kids[2];
        int n = 0;
        for (size_t j = i + 1; j < rec->count && n < 2; ++j)
            if (ev[j].type == SIDX_EV_BUILD_NODE && ev[j].parent == ev[i].node) kids[n++] = &ev[j];
        if (n != 2) continue;
        const double vp = volume(ev[i].bounds);
        if (!(vp > 0.0)) continue;
        s.pairs++;
        const double ov = volume(intersect_box(kids[0]->bounds, kids[1]->bounds));
        if (ov > 1e-9 * vp) s.overlapping++;
        s.overlap_frac += ov / vp;
        const double cover = fabs(volume(kids[0]->bounds) + volume(kids[1]->bounds) - vp) / vp;
        if (cover > s.cover_err) s.cover_err = cover;
    }
    if (s.pairs) s.overlap_frac /= s.pairs;
    return s;
}

/* Prints the root and its children with their boxes. */
static void print_top(const sidx_recorder *rec)
{
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    pr.show_bounds = 1;
    const sidx_hook ph = sidx_printer_hook(&pr);
    for (size_t i = 0; i < rec->count; ++i) {
        const sidx_event *e = &rec->events[i];
        if (e->type == SIDX_EV_BUILD_BEGIN || (e->type == SIDX_EV_BUILD_NODE && e->depth <= 1) ||
            (e->type == SIDX_EV_BUILD_SPLIT && e->depth == 0))
            sidx_hook_emit(&ph, e);
    }
}

typedef struct {
    double visits, after_hit;
    long out_of_cell, stopped_in_cell, rays;
} walk_stats;

/* Per ray: traversal steps (node visits, pops, box and triangle tests)
 * after the final closest-hit update; for a
 * kd-tree, also whether some hit was found beyond its cell's t_far. */
static void analyse_ray(const sidx_recorder *rec, walk_stats *w)
{
    size_t last_update = rec->count;
    float cell_far = INFINITY;
    int out = 0, visits = 0;
    for (size_t i = 0; i < rec->count; ++i) {
        const sidx_event *e = &rec->events[i];
        if (e->type == SIDX_EV_HIT_UPDATE) last_update = i;
        if (e->type == SIDX_EV_NODE_ENTER) { cell_far = e->t_far; ++visits; }
        if (e->type == SIDX_EV_PRIM_TEST && e->result == 1 && e->t > cell_far * 1.000001f) out = 1;
        if (e->type == SIDX_EV_TERMINATE && e->reason == SIDX_TERM_HIT_IN_CELL) w->stopped_in_cell++;
    }
    int after = 0;
    for (size_t i = last_update; i < rec->count; ++i) {
        const sidx_event_type t = rec->events[i].type;
        after += t == SIDX_EV_NODE_ENTER || t == SIDX_EV_STACK_POP || t == SIDX_EV_BOX_TEST ||
                 t == SIDX_EV_PRIM_TEST || t == SIDX_EV_MAILBOX_HIT;
    }
    w->visits += visits;
    w->after_hit += after;
    w->out_of_cell += out;
    w->rays++;
}

/* ---- 4. deck 001 "Spatial Data Structures Review", measured ----
 * The slide's table: [Spatial] [Primitive] [Build Speed] [Search Speed],
 * a tick or a cross per structure.  "Spatial" is measured by what a
 * space partition must do: reference a triangle from every cell it
 * touches (references per triangle > 1), where a primitive partition
 * stores each one once.  Search speed is counted (node or cell visits and
 * triangle tests per ray) and timed; build speed timed and counted
 * (count_build_work).  Every verdict printed comes from counts, so the
 * table reads the same on every run; the times are printed beside them. */
typedef struct {
    const char *accel, *row;
    int spatial, build_fast, search_fast; /* the slide's ticks */
} review_row;

static const review_row review_rows[4] = {
    {"bvh", "BVH", 0, 0, 1},
    {"kdtree", "K-D Tree", 1, 0, 1},
    {"grid", "Uniform Grid", 1, 1, 0},
    {"octree", "Quad/Octree", 1, 0, 1},
};

typedef struct {
    double build_ms, refs_per_tri, visits, tests, us;
    size_t bytes;
    uint64_t build_work;
} review_measure;

/* The build's work, counted from its events so that the "build" verdict
 * is the same on every run: each triangle placed in a node or cell (the
 * count of every BUILD_NODE and BUILD_LEAF) and each split cost evaluated
 * (BUILD_CANDIDATE).  A uniform grid places each triangle in the cells it
 * touches and evaluates nothing, which is the slide's "fast build". */
static void count_build_work(const sidx_event *e, void *user)
{
    uint64_t *w = user;
    *w += e->type == SIDX_EV_BUILD_CANDIDATE ? 1u : (uint64_t)e->count;
}

static const char *tick(int yes) { return yes ? "yes" : "no"; }

/* Returns 0 if a structure could not be built. */
static int review_table(const lesson_args *args, long checks[4])
{
    const char *spec = args->scene_given ? args->scene : "teapot";
    sidx_mesh mesh = lesson_open(args, spec);
    const size_t nrays = 5000;
    sidx_ray *rays = malloc(nrays * sizeof *rays);
    sidx_hit *ref = malloc(nrays * sizeof *ref), *hits = malloc(nrays * sizeof *hits);
    if (!rays || !ref || !hits) lesson_fail(args, "out of memory");
    lesson_rays_into_box(sidx_mesh_bounds(&mesh), rays, nrays, 2024u);

    review_measure m[4];
    size_t differ = 0;
    sidx_error err = {0};
    for (int s = 0; s < 4; ++s) {
        sidx_accel *acc = NULL;
        double best = INFINITY;
        /* the kd-tree with the 4 : 1 costs of parts 1-3 (leaves of a few
         * triangles), not its SIMD-tuned 16 : 1 default */
        sidx_build_options opt = build_options(s == 1);
        for (int pass = 0; pass < 3; ++pass) { /* best of 3: the build time on a busy machine */
            sidx_accel_destroy(acc);
            acc = NULL;
            const double t0 = lesson_seconds();
            if (sidx_accel_build(review_rows[s].accel, &mesh, &opt, &acc, &err) != SIDX_OK) {
                fprintf(stderr, "06_object_vs_space: %s\n", err.message);
                free(rays), free(ref), free(hits);
                sidx_mesh_free(&mesh);
                return 0;
            }
            const double dt = lesson_seconds() - t0;
            if (dt < best) best = dt;
        }
        /* once more with a hook, untimed, to count the build's work */
        sidx_accel_destroy(acc);
        acc = NULL;
        m[s].build_work = 0;
        const sidx_hook wh = {count_build_work, &m[s].build_work,
                              SIDX_EVMASK(SIDX_EV_BUILD_NODE) | SIDX_EVMASK(SIDX_EV_BUILD_LEAF) |
                                  SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE)};
        opt.hook = &wh;
        if (sidx_accel_build(review_rows[s].accel, &mesh, &opt, &acc, &err) != SIDX_OK) {
            fprintf(stderr, "06_object_vs_space: %s\n", err.message);
            free(rays), free(ref), free(hits);
            sidx_mesh_free(&mesh);
            return 0;
        }
        sidx_accel_stats st;
        sidx_accel_stats_get(acc, &st);
        sidx_counters c;
        lesson_count_rays(acc, rays, nrays, &c, s == 0 ? ref : hits);
        if (s > 0)
            for (size_t i = 0; i < nrays; ++i) differ += !(hits[i].t == ref[i].t);
        m[s].build_ms = 1e3 * best;
        m[s].refs_per_tri = (double)st.prim_refs / mesh.num_triangles;
        m[s].visits = (double)c.n[SIDX_EV_NODE_ENTER] / nrays;
        m[s].tests = (double)c.n[SIDX_EV_PRIM_TEST] / nrays;
        m[s].us = lesson_us_per_ray(acc, rays, nrays, 3);
        m[s].bytes = st.bytes;
        sidx_accel_destroy(acc);
    }

    printf("\n== 4. Deck 001 \"Spatial Data Structures Review\", measured on '%s' (%u triangles, %zu rays into its box)\n",
           spec, mesh.num_triangles, nrays);
    printf("  %-13s | %-7s %-9s %-6s %-6s | %8s %9s %10s %9s %7s %9s\n", "slide:", "spatial", "primitive",
           "build", "search", "refs/tri", "build ms", "visits/ray", "tests/ray", "us/ray", "memory KB");
    for (int s = 0; s < 4; ++s) {
        const review_row *r = &review_rows[s];
        printf("  %-13s | %-7s %-9s %-6s %-6s | %8.2f %9.2f %10.1f %9.1f %7.2f %9.1f\n", r->row, tick(r->spatial),
               tick(!r->spatial), tick(r->build_fast), tick(r->search_fast), m[s].refs_per_tri, m[s].build_ms,
               m[s].visits, m[s].tests, m[s].us, (double)m[s].bytes / 1024.0);
    }
    printf("  (visits = nodes entered, for the grid cells stepped through; tests = triangle tests; a grid\n"
           "   cell step costs less than a tree node, so compare the visits within a column, not across)\n");

    /* spatial / primitive: the references */
    int spatial_dup = 1;
    for (int s = 1; s < 4; ++s) spatial_dup &= m[s].refs_per_tri > 1.0;
    const int bvh_once = m[0].refs_per_tri == 1.0;
    printf("  spatial / primitive: the BVH stores each triangle once (%.2f), the three space partitions\n"
           "  reference a triangle from every cell it touches (%.2f to %.2f): %s the slide\n",
           m[0].refs_per_tri, fmin(m[1].refs_per_tri, fmin(m[2].refs_per_tri, m[3].refs_per_tri)),
           fmax(m[1].refs_per_tri, fmax(m[2].refs_per_tri, m[3].refs_per_tri)),
           bvh_once && spatial_dup ? "as on" : "NOT as on");

    /* build speed: timed, and judged by the counted work (the times vary from run to run) */
    const uint64_t tree_least = m[0].build_work < m[3].build_work
                                    ? (m[0].build_work < m[1].build_work ? m[0].build_work : m[1].build_work)
                                    : (m[3].build_work < m[1].build_work ? m[3].build_work : m[1].build_work);
    printf("  build speed: the grid built in %.2f ms, the binned BVH in %.2f, the octree in %.2f, the\n"
           "  exact-SAH kd-tree in %.2f (best of 3); build work (triangles placed in nodes or cells +\n"
           "  split costs evaluated): grid %llu, BVH %llu, octree %llu, kd-tree %llu:\n  %s\n",
           m[2].build_ms, m[0].build_ms, m[3].build_ms, m[1].build_ms, (unsigned long long)m[2].build_work,
           (unsigned long long)m[0].build_work, (unsigned long long)m[3].build_work,
           (unsigned long long)m[1].build_work,
           m[2].build_work < tree_least ? "the grid does the least work, as on the slide's build mark"
                                        : "the grid does NOT do the least work here, against the slide");
    /* search speed: counted (triangle tests per ray), and timed */
    const int grid_worse_than_trees = m[2].tests > m[0].tests && m[2].tests > m[1].tests;
    printf("  search speed: triangle tests per ray, grid %.1f against BVH %.1f and kd-tree %.1f:\n  %s\n",
           m[2].tests, m[0].tests, m[1].tests,
           grid_worse_than_trees ? "the grid's cross and the trees' ticks, as on the slide"
                                 : "NOT as on the slide");
    /* judged by the counted tests, not the time, so that the verdict is the same on every run */
    const int octree_beats_grid = m[3].tests < m[2].tests;
    printf("  the octree (a tick on the slide) tests %.1f per ray in %.2f us against the grid's %.1f in %.2f us:\n"
           "  %s\n",
           m[3].tests, m[3].us, m[2].tests, m[2].us,
           octree_beats_grid ? "it tests fewer triangles than the grid, as on the slide"
                             : "it does NOT test fewer triangles than the grid here: its splits at the cell centre\n"
                               "  adapt less than the trees' SAH planes (lesson 12 sets it beside the kd-tree)");
    printf("  Same closest hits in all four: %s\n", differ == 0 ? "yes" : "NO");
    checks[0] = differ == 0;
    checks[1] = bvh_once;
    checks[2] = spatial_dup;
    checks[3] = grid_worse_than_trees;
    free(rays), free(ref), free(hits);
    sidx_mesh_free(&mesh);
    return 1;
}

int main(int argc, char **argv)
{
    const lesson_option options[] = {LESSON_KNOBS(knobs), {0}};
    lesson_args args = {.name = "06_object_vs_space", .usage = usage, .scene = "soup:600", .options = options};
    lesson_parse(&args, argc, argv);
    static const char *const names[2] = {"bvh", "kdtree"};
    for (int s = 0; s < 4; ++s) lesson_need(&args, review_rows[s].accel);
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};

    sidx_accel *acc[2] = {NULL, NULL};
    sidx_accel_stats st[2];
    tree_stats ts[2];
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook rh = sidx_recorder_hook(&rec);
    printf("== '%s': %u triangles\n", args.scene, mesh.num_triangles);
    for (int s = 0; s < 2; ++s) {
        sidx_recorder_clear(&rec);
        sidx_build_options opt = build_options(s == 1);
        opt.hook = &rh;
        /* The kd-tree's default C_trav : C_tri = 16 : 1 makes leaves of
         * ~20 references, tested four at a time by SIMD; here leaves of a
         * few triangles like the BVH's (4 : 1), so that "steps after the
         * closest hit" compares the two walks, not two leaf sizes. */
        if (sidx_accel_build(names[s], &mesh, &opt, &acc[s], &err) != SIDX_OK) {
            fprintf(stderr, "06_object_vs_space: %s\n", err.message);
            sidx_accel_destroy(acc[0]);
            sidx_recorder_free(&rec);
            sidx_mesh_free(&mesh);
            return 1;
        }
        sidx_accel_stats_get(acc[s], &st[s]);
        printf("\n== 1%c. The top of the %s (%s partitioning): root and its two children\n", 'a' + s, names[s],
               s == 0 ? "object" : "space");
        print_top(&rec);
        ts[s] = sibling_stats(&rec);
    }
    printf("\n  over the whole tree                          %12s %12s\n", "bvh", "kdtree");
    printf("  sibling pairs                                %12u %12u\n", ts[0].pairs, ts[1].pairs);
    printf("  pairs whose boxes overlap                    %12u %12u\n", ts[0].overlapping, ts[1].overlapping);
    printf("  mean overlap volume / parent volume          %11.1f%% %11.1f%%\n", 100 * ts[0].overlap_frac,
           100 * ts[1].overlap_frac);
    printf("  worst |vol(L) + vol(R) - vol(parent)|        %11.1f%% %11.1f%%\n", 100 * ts[0].cover_err,
           100 * ts[1].cover_err);
    printf("  primitive references (%u triangles)        %12llu %12llu\n", mesh.num_triangles,
           (unsigned long long)st[0].prim_refs, (unsigned long long)st[1].prim_refs);
    printf("  The BVH's children overlap and need not fill their parent; the kd-tree's cells never\n"
           "  overlap and fill it exactly, at the price of referencing a triangle from every cell it\n"
           "  touches.\n");

    /* ---- one ray ---- */
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    /* aimed at the triangle nearest the centre of the scene, from above */
    uint32_t aim = 0;
    float best_d = INFINITY;
    for (uint32_t i = 0; i < mesh.num_triangles; ++i) {
        const float d = sidx_v3_length(sidx_v3_sub(sidx_aabb_centroid(sidx_mesh_triangle_bounds(&mesh, i)), ctr));
        if (d < best_d) { best_d = d; aim = i; }
    }
    const sidx_vec3 target = sidx_aabb_centroid(sidx_mesh_triangle_bounds(&mesh, aim));
    const sidx_vec3 org = sidx_v3(ctr.x + 0.13f * ext.x, ctr.y - 0.11f * ext.y, box.max.z + 2.0f * ext.z);
    sidx_ray ray;
    sidx_ray_init(&ray, org, sidx_v3_sub(target, org), 0.0f, INFINITY);
    printf("\n  The ray: from (%g, %g, %g) towards the centroid of triangle %u\n", org.x, org.y, org.z, aim);
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    const sidx_hook ph = sidx_printer_hook(&pr);
    sidx_hit h[2];
    for (int s = 0; s < 2; ++s) {
        printf("\n== 2%c. One ray through the %s, every event\n", 'a' + s, names[s]);
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ph, 0};
        sidx_accel_intersect(acc[s], &ray, &q, &h[s]);
    }

    /* ---- many rays ---- */
    walk_stats ws[2];
    memset(ws, 0, sizeof ws);
    int same = h[0].t == h[1].t;
    const float R = sidx_v3_length(ext);
    uint32_t seed = 99u;
    const int nrays = 5000;
    for (int i = 0; i < nrays; ++i) {
        float f[5];
        for (int j = 0; j < 5; ++j) { seed = seed * 1664525u + 1013904223u; f[j] = (float)(seed >> 8) / 16777216.0f; }
        const float z = 2 * f[0] - 1, ang = 6.2831853f * f[1], sn = sqrtf(1 - z * z);
        const sidx_vec3 o = sidx_v3_add(ctr, sidx_v3(R * sn * cosf(ang), R * sn * sinf(ang), R * z));
        const sidx_vec3 t = sidx_v3(box.min.x + f[2] * ext.x, box.min.y + f[3] * ext.y, box.min.z + f[4] * ext.z);
        sidx_ray r;
        if (sidx_ray_init(&r, o, sidx_v3_sub(t, o), 0.0f, INFINITY) != SIDX_OK) continue;
        float tt[2];
        for (int s = 0; s < 2; ++s) {
            sidx_recorder_clear(&rec);
            sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &rh, (uint32_t)i};
            sidx_hit hh;
            sidx_accel_intersect(acc[s], &r, &q, &hh);
            tt[s] = hh.t;
            if (hh.prim != SIDX_NO_HIT) analyse_ray(&rec, &ws[s]);
        }
        if (!(tt[0] == tt[1])) same = 0;
    }
    sidx_recorder_free(&rec);
    sidx_accel_destroy(acc[0]);
    sidx_accel_destroy(acc[1]);
    sidx_mesh_free(&mesh);

    printf("\n== 3. %d random rays; averages over the %ld that hit something\n", nrays, ws[0].rays);
    printf("  %-8s %14s %28s %18s\n", "", "nodes visited", "steps after closest hit", "stopped in cell");
    for (int s = 0; s < 2; ++s)
        printf("  %-8s %14.2f %28.2f %17.1f%%\n", names[s], ws[s].visits / (double)ws[s].rays,
               ws[s].after_hit / (double)ws[s].rays, 100.0 * ws[s].stopped_in_cell / (double)ws[s].rays);
    printf("  (steps = node visits, stack pops, box and triangle tests after the final closest-hit update)\n");
    printf("  kd-tree rays that found a hit beyond the current cell and so could NOT stop there: %ld\n",
           ws[1].out_of_cell);
    printf("  Same closest hits in both: %s\n", same ? "yes" : "NO");
    const double after_bvh = ws[0].after_hit / (double)ws[0].rays, after_kd = ws[1].after_hit / (double)ws[1].rays;

    long review[4];
    if (!review_table(&args, review)) return 1;
    lesson_check("same_hits", same);
    lesson_check("bvh_boxes_overlap", ts[0].overlapping > 0);
    lesson_check("kd_cells_disjoint", ts[1].pairs > 0 && ts[1].overlapping == 0 && ts[1].cover_err < 1e-4);
    lesson_check("kd_stops_at_first_hit", after_kd < after_bvh && ws[1].stopped_in_cell > 0);
    lesson_check("review_same_hits", review[0]);
    lesson_check("review_bvh_refs_once", review[1]);
    lesson_check("review_spatial_duplicates", review[2]);
    lesson_check("review_grid_tests_more_than_trees", review[3]);
    return 0;
}
