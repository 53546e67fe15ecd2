/* 12_octree_bsp.c — octrees and quadtrees; BSP trees and the painter's order.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Octrees and Quadtrees"
 * ("Hierarchical space partitioning ('simplest hierarchical grid') — each
 * inner node contains 8 equally sized voxels — Quadtree: 2D 'octree' —
 * Adaptive subdivision: adjust depth to local scene complexity"), "BSP
 * Trees" ("Recursively split space with planes — arbitrary split
 * positions, arbitrary orientations — Used for visibility computation,
 * e.g. in games (Doom!) — Enumerating objects in back to front order").
 * Deck 001: "Quad-Tree/Octree" ("Like uniform grid, easy to build — has
 * greater ability to adapt to location of scene geometry than uniform
 * grid — still not as good adaptability as K-D tree").
 *
 * What it shows:
 *   1. a quadtree over the 2D board ("flat2d", one triangle per shape),
 *      split down to 2 triangles per leaf: the top of the build as the
 *      printer shows it (four children per node), and how deep it went
 *      where — leaves per depth;
 *   2. an octree over a 3D scene (default teapot) against the uniform grid
 *      and the kd-tree: nodes, depth, and what rays pay.  The kd-tree is
 *      built twice: with deck 000's cost constants ("Building good
 *      kD-trees": Cost = C_trav + SA(L)/SA(c)·TriCount(L) + ..., a
 *      triangle test costs 1; C_trav = 1 puts a node step on that scale),
 *      and with sidx's default C_trav = 16, which prices a node step for
 *      its SIMD leaf tests and so stops early with fat leaves;
 *   3. a BSP tree over the board, its shapes stood up as walls on their
 *      segments (as Doom's map: planes perpendicular to the board, which
 *      cut it into convex regions), and the painter's algorithm: the pieces
 *      enumerated back to front from an eye on the board (first lines
 *      through the printer), then checked: along every one of many rays
 *      from the eye, a piece drawn later is never behind a piece drawn
 *      earlier.
 *
 * Read:  lib/octree.c, octree_walk; lib/bsp.c, sidx_bsp_paint
 * Run:   build/lessons/12_octree_bsp [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply for part 2 (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "lesson.h"
#include "sidx/bsp.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 12_octree_bsp [--help] [build knobs] [SCENE]\n"
               "\n"
               "Quadtree over the 2D board, octree vs grid vs kd-tree (deck and default SAH constants)\n"
               "on a scene, and a BSP tree's back-to-front painter's order checked along rays from the eye.\n"
               "\n"
               "  SCENE   scene for the octree comparison: built-in name or .obj/.ply (default: teapot)\n"
               "The knobs below change the quadtree and the octree (--leaf-size: split above N\n"
               "triangles, default 2 for the board's quadtree, 8 for the octree; --max-depth) and the\n"
               "uniform grid (--lambda); the kd-trees keep their two cost settings, the BSP tree its\n"
               "own.  The checks hold for the defaults.\n");
}

static float lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

/* ---- the painter's pieces ---- */
#define MAXV 16
typedef struct {
    uint32_t tri, n;
    sidx_vec3 v[MAXV];
} piece;
typedef struct {
    piece *p;
    size_t n, cap;
    int too_many_verts;
} pieces;

static int collect(const sidx_bsp_piece *pc, void *user)
{
    pieces *ps = user;
    if (ps->n == ps->cap) {
        size_t cap = ps->cap ? 2 * ps->cap : 256;
        piece *np = realloc(ps->p, cap * sizeof *np);
        if (!np) return 1;
        ps->p = np;
        ps->cap = cap;
    }
    piece *d = &ps->p[ps->n++];
    d->tri = pc->tri;
    d->n = pc->num_verts < MAXV ? pc->num_verts : MAXV;
    if (pc->num_verts > MAXV) ps->too_many_verts = 1;
    memcpy(d->v, pc->verts, d->n * sizeof *d->v);
    return 0;
}

/* Does the ray hit the convex polygon (fan of triangles)?  t of the hit. */
static int hit_piece(const sidx_ray *r, const piece *p, float *t)
{
    for (uint32_t k = 1; k + 1 < p->n; ++k) {
        float u, v;
        if (sidx_intersect_triangle(SIDX_TRI_WATERTIGHT, r, p->v[0], p->v[k], p->v[k + 1], INFINITY, t, &u, &v))
            return 1;
    }
    return 0;
}

/* The board as Doom's BSP sees it: each shape's segment in the plane
 * z = 0 (where its tilted triangle crosses it, the spine) stood up as a
 * wall, a quad of two triangles from z = -0.5 to 0.5.  The walls' planes
 * are perpendicular to the board, so a plane through one wall is the 2D
 * BSP's line through its segment and cuts the walls it crosses (deck 000
 * "BSP Trees": split space with the polygons' own planes).  The tilted
 * triangles themselves lie nearly in the board's plane: their planes would
 * cut almost nothing.  Returns 0 if out of memory. */
static int board_walls(const sidx_mesh *board, sidx_mesh *out, sidx_error *err)
{
    const uint32_t n = board->num_triangles;
    float *xyz = malloc((size_t)n * 4 * 3 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * 6 * sizeof *idx), nv = 0, nt = 0;
    if (!xyz || !idx) {
        free(xyz), free(idx);
        return 0;
    }
    for (uint32_t i = 0; i < n; ++i) {
        sidx_vec3 v[3], end[2] = {{0, 0, 0}, {0, 0, 0}};
        int ends = 0;
        for (int k = 0; k < 3; ++k) v[k] = board->positions[board->indices[3 * i + k]];
        for (int k = 0; k < 3 && ends < 2; ++k) { /* where the edges cross z = 0 */
            const sidx_vec3 a = v[k], b = v[(k + 1) % 3];
            if ((a.z <= 0.0f) == (b.z <= 0.0f) && a.z != 0.0f) continue;
            const float f = a.z == b.z ? 0.0f : a.z / (a.z - b.z);
            end[ends++] = sidx_v3(a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), 0.0f);
        }
        if (ends < 2 || (end[0].x == end[1].x && end[0].y == end[1].y)) continue;
        const float c[4][3] = {{end[0].x, end[0].y, -0.5f}, {end[1].x, end[1].y, -0.5f},
                               {end[1].x, end[1].y, 0.5f}, {end[0].x, end[0].y, 0.5f}};
        memcpy(xyz + 3 * nv, c, sizeof c);
        const uint32_t q[6] = {nv, nv + 1, nv + 2, nv, nv + 2, nv + 3};
        memcpy(idx + 3 * nt, q, sizeof q);
        nv += 4;
        nt += 2;
    }
    const int ok = sidx_mesh_from_arrays(out, xyz, nv, idx, nt, err) == SIDX_OK;
    free(xyz), free(idx);
    return ok;
}

static int same_hits(const sidx_accel *a, const sidx_accel *ref, const sidx_mesh *m, int flat, uint32_t seed)
{
    const sidx_aabb box = sidx_mesh_bounds(m);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const float R = sidx_v3_length(ext);
    for (int i = 0; i < 1000; ++i) {
        const float z = flat ? 0.9f : 2 * lcg(&seed) - 1, ang = 6.2831853f * lcg(&seed), s = sqrtf(1 - z * z);
        const sidx_vec3 o = sidx_v3_add(ctr, sidx_v3(R * s * cosf(ang), R * s * sinf(ang), R * z));
        const sidx_vec3 t = sidx_v3(box.min.x + lcg(&seed) * ext.x, box.min.y + lcg(&seed) * ext.y, ctr.z);
        sidx_ray r;
        if (sidx_ray_init(&r, o, sidx_v3_sub(t, o), 0.0f, INFINITY) != SIDX_OK) continue;
        sidx_hit h1, h2;
        sidx_accel_intersect(a, &r, NULL, &h1);
        sidx_accel_intersect(ref, &r, NULL, &h2);
        if (!(h1.t == h2.t)) return 0;
    }
    return 1;
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_LEAF_SIZE(knobs), LESSON_MAX_DEPTH(knobs), LESSON_LAMBDA(knobs), {0}};
    lesson_args args = {.name = "12_octree_bsp", .usage = usage, .scene = "teapot", .options = options};
    lesson_parse(&args, argc, argv);
    static const char *const need[] = {"octree", "quadtree", "bsp", "brute"};
    for (int i = 0; i < 4; ++i) lesson_need(&args, need[i]);
    sidx_mesh board = lesson_open(&args, "flat2d"), mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    int ok = 1, same = 1;

    /* ---- 1. quadtree ---- */
    printf("== 1. A quadtree over the 2D board ('flat2d', %u triangles, one per shape; leaves of at most %u):\n"
           "   the top two levels\n",
           board.num_triangles, knobs.leaf_size ? knobs.leaf_size : 2u);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook rh = sidx_recorder_hook(&rec);
    sidx_build_options opt = {0};
    opt.hook = &rh;
    sidx_build_options qo = knobs;
    qo.hook = &rh;
    /* 16 shapes and the default leaf size 8 would stop at depth 1: split
     * down to 2 shapes per leaf, so the board shows where the tree goes deep */
    if (!qo.leaf_size) qo.leaf_size = 2;
    sidx_accel *qt = NULL, *ref = NULL;
    if (sidx_accel_build("quadtree", &board, &qo, &qt, &err) != SIDX_OK ||
        sidx_accel_build("brute", &board, NULL, &ref, &err) != SIDX_OK) {
        fprintf(stderr, "12_octree_bsp: %s\n", err.message);
        return 1;
    }
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    pr.show_bounds = 1;
    const sidx_hook ph = sidx_printer_hook(&pr);
    uint32_t by_depth[32] = {0}, maxd = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        if ((e->type == SIDX_EV_BUILD_NODE && e->depth <= 1) || e->type == SIDX_EV_BUILD_BEGIN) sidx_hook_emit(&ph, e);
        if (e->type == SIDX_EV_BUILD_LEAF && e->depth < 32) {
            by_depth[e->depth]++;
            if (e->depth > maxd) maxd = e->depth;
        }
    }
    pr.show_bounds = 0;
    printf("  leaves per depth:");
    for (uint32_t d = 0; d <= maxd; ++d) printf(" %u:%u", d, by_depth[d]);
    printf("\n  Every cut halves x and y: four equal children.  Where the board is crowded the tree\n"
           "  goes deeper (adaptive subdivision); empty corners stay big.\n");
    same &= same_hits(qt, ref, &board, 1, 11u);
    sidx_accel_destroy(qt);

    /* ---- 2. octree vs grid vs kd-tree ---- */
    printf("\n== 2. '%s' (%u triangles): octree vs uniform grid vs kd-tree, 2000 random rays\n", args.scene,
           mesh.num_triangles);
    /* The kd-tree twice: deck 000's constants (C_trav = C_tri = 1) and sidx's default (C_trav = 16). */
    static const char *const cmp[4] = {"grid", "octree", "kdtree", "kdtree"};
    static const char *const label[4] = {"grid", "octree", "kd C=1", "kd C=16"};
    static const float ctrav[4] = {0.0f, 0.0f, 1.0f, 16.0f};
    double tris[4] = {0}, visits[4] = {0};
    uint32_t leaves[4] = {0};
    printf("  %-8s %8s %8s %7s %12s %12s %12s\n", "", "nodes", "leaves", "depth", "memory KiB", "visits/ray",
           "tris/ray");
    sidx_accel *mref = NULL;
    if (sidx_accel_build("brute", &mesh, NULL, &mref, &err) != SIDX_OK) ok = 0;
    for (int s = 0; s < 4 && ok; ++s) {
        if (!sidx_accel_is_registered(cmp[s])) continue;
        sidx_build_options ko = {0};
        if (s < 2) ko = knobs; /* grid, octree */
        ko.c_trav = ctrav[s];
        ko.c_tri = ctrav[s] > 0.0f ? 1.0f : 0.0f;
        sidx_accel *a = NULL;
        if (sidx_accel_build(cmp[s], &mesh, &ko, &a, &err) != SIDX_OK) { ok = 0; break; }
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        sidx_counters c;
        sidx_counters_init(&c);
        const sidx_hook ch = sidx_counters_hook(&c);
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &ch, 0};
        const sidx_aabb box = sidx_mesh_bounds(&mesh);
        const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
        const float R = sidx_v3_length(ext);
        uint32_t seed = 77u;
        for (int i = 0; i < 2000; ++i) {
            const float z = 2 * lcg(&seed) - 1, ang = 6.2831853f * lcg(&seed), sn = sqrtf(1 - z * z);
            const sidx_vec3 o = sidx_v3_add(ctr, sidx_v3(R * sn * cosf(ang), R * sn * sinf(ang), R * z));
            const sidx_vec3 t = sidx_v3(box.min.x + lcg(&seed) * ext.x, box.min.y + lcg(&seed) * ext.y,
                                        box.min.z + lcg(&seed) * ext.z);
            sidx_ray r;
            if (sidx_ray_init(&r, o, sidx_v3_sub(t, o), 0.0f, INFINITY) != SIDX_OK) continue;
            sidx_hit h;
            sidx_accel_intersect(a, &r, &q, &h);
        }
        visits[s] = c.n[SIDX_EV_NODE_ENTER] / 2000.0;
        tris[s] = c.n[SIDX_EV_PRIM_TEST] / 2000.0;
        leaves[s] = st.leaves;
        printf("  %-8s %8u %8u %7u %12.1f %12.2f %12.2f\n", label[s], st.nodes, st.leaves, st.max_depth,
               st.bytes / 1024.0, visits[s], tris[s]);
        same &= same_hits(a, mref, &mesh, 0, 21u);
        sidx_accel_destroy(a);
    }
    sidx_accel_destroy(mref);
    if (!ok) fprintf(stderr, "12_octree_bsp: %s\n", err.message);
    printf("  The octree cuts every cell at its centre, wherever the triangles are; the kd-tree puts\n"
           "  each plane where the SAH says and so adapts better: with the deck's constants (C=1) it\n"
           "  tests %.1fx fewer triangles per ray than the octree: its leaves hug the surface.  It pays\n"
           "  with %.1fx the leaves and %.1fx the node visits.  With sidx's default C_trav = 16 a node\n"
           "  step is priced like 16 triangle tests (the SIMD leaf test makes triangles cheap), so the\n"
           "  SAH stops early: few fat leaves, %.1fx the octree's triangle tests, which the faster leaf\n"
           "  test repays (lesson 09 times both).\n",
           tris[2] > 0 ? tris[1] / tris[2] : 0.0, leaves[1] ? (double)leaves[2] / leaves[1] : 0.0,
           visits[1] > 0 ? visits[2] / visits[1] : 0.0, tris[1] > 0 ? tris[3] / tris[1] : 0.0);
    /* what the text claims: the deck-constant kd-tree tests fewer triangles than the octree; the
     * default one (C_trav = 16) has fewer leaves and tests more triangles than the octree */
    const int kd_adapts = ok && tris[2] > 0 && tris[2] < tris[1];
    const int kd_default_fatter = ok && tris[3] > tris[1] && tris[3] > tris[2] && leaves[3] < leaves[2];

    /* ---- 3. BSP and the painter ---- */
    printf("\n== 3. A BSP tree over the board, and the painter's order from an eye on it\n");
    sidx_accel *bsp = NULL, *wall_ref = NULL;
    sidx_mesh walls = {0};
    sidx_recorder_clear(&rec);
    if (ok && !board_walls(&board, &walls, &err)) { ok = 0; fprintf(stderr, "12_octree_bsp: the board's walls: %s\n", err.message[0] ? err.message : "out of memory"); }
    if (ok && (sidx_accel_build("bsp", &walls, &opt, &bsp, &err) != SIDX_OK ||
               sidx_accel_build("brute", &walls, NULL, &wall_ref, &err) != SIDX_OK)) { ok = 0; fprintf(stderr, "12_octree_bsp: %s\n", err.message); }
    int painter_ok = 0, planes_cut = 0;
    if (ok) {
        printf("  The board's %u shapes as walls standing on their segments (two triangles each, planes\n"
               "  perpendicular to the board, as Doom's BSP cuts the map with the lines of its walls):\n",
               board.num_triangles);
        sidx_bsp_info bi;
        sidx_bsp_info_get(bsp, &bi);
        printf("  %u triangles -> %u pieces (%u cut by a plane); %u nodes, %u on a triangle's own plane,\n"
               "  %u leaves with more than one piece\n",
               bi.input_tris, bi.pieces, bi.splits, bi.nodes, bi.polygon_planes, bi.unordered_leaves);
        printf("  the first planes the build chose (arbitrary orientation: n, d):\n");
        int shown = 0;
        for (size_t i = 0; i < rec.count && shown < 3; ++i)
            if (rec.events[i].type == SIDX_EV_BUILD_SPLIT) { sidx_hook_emit(&ph, &rec.events[i]); ++shown; }
        same &= same_hits(bsp, wall_ref, &walls, 1, 31u);
        /* the planes cut the board: every splitting plane stands on it (normal in the board's
         * plane) and some walls are cut in pieces */
        int standing = 1;
        for (uint32_t k = 0; k < bi.nodes; ++k) {
            sidx_bsp_node_view nv;
            if (sidx_bsp_node_get(bsp, k, &nv) != SIDX_OK) { standing = 0; break; }
            if (nv.child[0] != UINT32_MAX && fabs(nv.n[2]) > 1e-6) standing = 0;
        }
        planes_cut = standing && bi.splits > 0 && bi.leaves >= board.num_triangles;
        printf("  every plane perpendicular to the board: %s; they cut it into %u convex regions (the\n"
               "  leaves) and cut %u walls where a plane crosses them\n",
               standing ? "yes" : "NO", bi.leaves, bi.splits);

        const sidx_vec3 eye = sidx_v3(5.3f, 5.1f, 0.0f);
        printf("\n  Back to front from the eye (%g, %g, 0): the order sidx_bsp_paint hands the pieces out\n", eye.x,
               eye.y);
        pieces ps = {NULL, 0, 0, 0};
        sidx_counters pc;
        sidx_counters_init(&pc);
        const sidx_hook pch = sidx_counters_hook(&pc);
        sidx_bsp_paint(bsp, eye, SIDX_BSP_BACK_TO_FRONT, collect, &ps, &pch);
        for (size_t i = 0; i < ps.n && i < 10; ++i) {
            sidx_vec3 c = sidx_v3(0, 0, 0);
            for (uint32_t k = 0; k < ps.p[i].n; ++k) c = sidx_v3_add(c, ps.p[i].v[k]);
            c = sidx_v3_scale(c, 1.0f / (float)ps.p[i].n);
            printf("    paint %2zu: wall %2u, triangle %3u (%u-gon) around (%.2f, %.2f), %.2f from the eye\n", i + 1,
                   ps.p[i].tri / 2, ps.p[i].tri, ps.p[i].n, c.x, c.y, sidx_v3_length(sidx_v3_sub(c, eye)));
        }
        printf("    ... %zu pieces painted, %llu nodes walked\n", ps.n, (unsigned long long)pc.n[SIDX_EV_NODE_ENTER]);
        /* the check: along rays from the eye, the painting order must fall as t grows */
        long rays_multi = 0, violations = 0;
        uint32_t seed = 3u;
        for (int k = 0; k < 2000; ++k) {
            const float ang = 6.2831853f * lcg(&seed);
            sidx_ray r;
            sidx_ray_init(&r, eye, sidx_v3(cosf(ang), sinf(ang), 0.0f), 0.0f, INFINITY);
            float last_t = -1.0f;
            size_t last_i = 0;
            int hits = 0;
            /* pieces in painting order: a later (nearer-drawn) piece must be hit at a smaller t */
            for (size_t i = 0; i < ps.n; ++i) {
                float t;
                if (!hit_piece(&r, &ps.p[i], &t)) continue;
                if (hits > 0 && t > last_t * (1.0f + 1e-5f) + 1e-6f) {
                    ++violations;
                    (void)last_i;
                }
                last_t = t;
                last_i = i;
                ++hits;
            }
            if (hits > 1) ++rays_multi;
        }
        printf("  %d rays from the eye across the board: %ld cross two pieces or more; pieces met in\n"
               "  an order that contradicts the painting order: %ld\n",
               2000, rays_multi, violations);
        printf("  Drawing in this order, each piece is painted over everything behind it: no sorting at\n"
               "  draw time, only a walk that visits the far side of every plane first.\n");
        painter_ok = rays_multi > 0 && violations == 0 && !ps.too_many_verts;
        free(ps.p);
    }
    sidx_accel_destroy(bsp);
    sidx_accel_destroy(wall_ref);
    sidx_mesh_free(&walls);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(ref);
    sidx_mesh_free(&board);
    sidx_mesh_free(&mesh);
    if (!ok) return 1;
    lesson_check("same_hits", same);
    lesson_check("kd_deck_constants_fewer_tris_than_octree", kd_adapts);
    lesson_check("kd_default_c_trav_fatter_leaves", kd_default_fatter);
    lesson_check("bsp_planes_cut_the_board", planes_cut);
    lesson_check("painter_order_back_to_front", painter_ok);
    return 0;
}
