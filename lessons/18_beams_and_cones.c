/* 18_beams_and_cones.c — tracing continuous bundles of rays: beams and cones.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Acceleration
 * Strategies" ("Tracing of continuous bundles of rays — exploits coherence
 * of neighboring rays, amortize cost among them — frustum tracing, cone
 * tracing, beam tracing") and "Beam and Cone Tracing" ("Cone tracing:
 * approximate collection of rays with cone(s), subdivide into smaller cones
 * if necessary.  Beam tracing: exactly represent a ray bundle with pyramid
 * ...  Problems: clipping of beams?  Good approximations?  How to compute
 * intersections?  Not really practical!!").
 *
 * A pinhole camera looks at the scene (default: the teapot); its image is
 * cut into 8x8-pixel tiles.  A tile's beam is the pyramid through the four
 * outer corners of its pixels; its cone is the narrowest cone around the
 * tile's centre ray that holds that pyramid.  sidx_beam_trace /
 * sidx_cone_trace (sidx/beam.h) walk a BVH with the bundle and return the
 * CANDIDATE triangles: those the bundle may touch.  What it shows:
 *   1. one tile's beam through the printer: nodes kept and culled, the
 *      candidates it ends with;
 *   2. amortizing: one beam per tile against one beam per pixel — nodes
 *      visited per pixel — and the candidates against the triangles the
 *      tile's rays really hit first ("good approximations?");
 *   3. subdividing: a beam or cone with more than 16 candidates is replaced
 *      by 4 smaller ones, up to 3 times — candidates a ray is left with,
 *      against the walks it costs; cones, whose 4 children overlap, pay
 *      more for the same answer;
 * and every ray's first hit (found by the "bvh" one ray at a time) is among
 * its tile's candidates: the bundle is conservative, but the rays are still
 * needed to say which candidate each of them hits.
 *
 * Read:  lib/beam.c, sidx_beam_trace
 * Run:   build/lessons/18_beams_and_cones [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "lesson.h"
#include "sidx/beam.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 18_beams_and_cones [--help] [build knobs] [SCENE]\n"
               "\n"
               "Beam and cone tracing of a camera image in 8x8-pixel tiles: the candidates a bundle\n"
               "finds, what one bundle per tile saves against one per pixel, and what subdividing\n"
               "beams and cones buys and costs; every ray's hit must be among its tile's candidates.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "--leaf-size changes the leaves of the box tree the beams and cones walk (default 4).\n"
               "The checks hold for the default.\n");
}

#define W 64
#define H 64
#define TILE 8
#define NTILES ((W / TILE) * (H / TILE))
#define SPLIT_CANDS 16 /* subdivide a bundle with more candidates than this */

static lesson_camera cam;
static sidx_ray rays[W * H];
static sidx_hit hits[W * H];

/* The direction through image point (x, y), in pixels (pixel i spans [i, i+1]). */
static sidx_vec3 dir_at(float x, float y)
{
    return lesson_camera_dir(&cam, (2.0f * x / W - 1.0f) * 0.3f, (1.0f - 2.0f * y / H) * 0.3f);
}

/* The beam through the outer corners of pixels [x0, x0+n) x [y0, y0+n). */
static sidx_beam beam_of(int x0, int y0, int n)
{
    const float a = (float)x0, b = (float)(x0 + n), c = (float)y0, d = (float)(y0 + n);
    sidx_beam bm = {cam.eye, {dir_at(a, c), dir_at(b, c), dir_at(b, d), dir_at(a, d)}};
    return bm;
}

static sidx_vec3 unit(sidx_vec3 v) { return sidx_v3_scale(v, 1.0f / sidx_v3_length(v)); }

/* The narrowest cone about the centre ray that holds the beam's corners. */
static sidx_cone cone_of(const sidx_beam *b, int x0, int y0, int n)
{
    const sidx_vec3 axis = unit(dir_at((float)x0 + 0.5f * (float)n, (float)y0 + 0.5f * (float)n));
    float cmin = 1.0f;
    for (int k = 0; k < 4; ++k) {
        const float c = sidx_v3_dot(axis, unit(b->dir[k]));
        cmin = c < cmin ? c : cmin;
    }
    sidx_cone cn = {cam.eye, axis, acosf(cmin) * 1.0001f};
    return cn;
}

static int has(const sidx_bundle_result *r, uint32_t prim)
{
    uint32_t lo = 0, hi = r->num_cands; /* cands are ascending */
    while (lo < hi) {
        const uint32_t mid = (lo + hi) / 2;
        if (r->cands[mid] < prim) lo = mid + 1;
        else hi = mid;
    }
    return lo < r->num_cands && r->cands[lo] == prim;
}

static int same_cands(const sidx_bundle_result *a, const sidx_bundle_result *b)
{
    return a->num_cands == b->num_cands && !memcmp(a->cands, b->cands, a->num_cands * sizeof *a->cands);
}

/* Every ray of the tile whose first hit is a triangle finds it among r's candidates. */
static int holds_tile_hits(const sidx_bundle_result *r, int x0, int y0)
{
    for (int y = y0; y < y0 + TILE; ++y)
        for (int x = x0; x < x0 + TILE; ++x)
            if (hits[y * W + x].prim != SIDX_NO_HIT && !has(r, hits[y * W + x].prim)) return 0;
    return 1;
}

/* One line per event of a bundle walk, for the first `left` events. */
typedef struct {
    int left, dropped;
} first_events;

static void first_fn(const sidx_event *ev, void *user)
{
    first_events *f = user;
    if (ev->type != SIDX_EV_BOX_TEST && ev->type != SIDX_EV_PRIM_TEST) return;
    if (f->left <= 0) {
        f->dropped++;
        return;
    }
    f->left--;
    if (ev->type == SIDX_EV_BOX_TEST)
        printf("  node %u: %s\n", ev->node,
               ev->result ? "box meets the beam, enter" : "box outside the beam, culled");
    else
        printf("    triangle %u: %s\n", ev->prim,
               ev->result ? "candidate" : "outside, dropped");
}

/* ---- subdividing by hand, to follow every ray into its final bundle ---- */

typedef struct {
    const sidx_bundle_tree *tree;
    uint32_t max_levels;
    uint64_t bundles, nodes, ray_cands; /* ray_cands: the candidates of each ray's final bundle, summed */
    int conservative;
} split_walk;

static int in_beam(const sidx_beam *b, sidx_vec3 d)
{
    const sidx_vec3 c = sidx_v3_add(sidx_v3_add(b->dir[0], b->dir[1]), sidx_v3_add(b->dir[2], b->dir[3]));
    for (int k = 0; k < 4; ++k) {
        const sidx_vec3 n = sidx_v3_cross(b->dir[k], b->dir[(k + 1) & 3]);
        if ((sidx_v3_dot(n, d) >= 0) != (sidx_v3_dot(n, c) >= 0)) return 0;
    }
    return 1;
}

static int in_cone(const sidx_cone *c, sidx_vec3 d)
{
    return sidx_v3_dot(unit(c->axis), unit(d)) >= cosf(c->half_angle);
}

/* The library's rule (sidx/beam.h): more than SPLIT_CANDS candidates and
 * fewer than max_levels splits above: replace the bundle by its 4 children.
 * Each of the rays idx[0..n) follows the first child that holds it. */
static void split_trace(split_walk *w, const sidx_beam *b, const sidx_cone *c, uint32_t level, const int *idx, int n)
{
    sidx_bundle_result r = {0};
    const sidx_status s = b ? sidx_beam_trace(w->tree, b, 0, 0, NULL, &r) : sidx_cone_trace(w->tree, c, 0, 0, NULL, &r);
    if (s != SIDX_OK) {
        w->conservative = 0;
        return;
    }
    w->nodes += r.nodes_visited;
    if (r.num_cands > SPLIT_CANDS && level < w->max_levels) {
        sidx_beam bs[4];
        sidx_cone cs[4];
        if (b) sidx_beam_split(b, bs);
        else sidx_cone_split(c, cs);
        int sub[4][TILE * TILE], ns[4] = {0, 0, 0, 0};
        for (int i = 0; i < n; ++i) {
            int k = 0;
            while (k < 3 && !(b ? in_beam(&bs[k], rays[idx[i]].dir) : in_cone(&cs[k], rays[idx[i]].dir))) ++k;
            sub[k][ns[k]++] = idx[i];
        }
        for (int k = 0; k < 4; ++k) split_trace(w, b ? &bs[k] : NULL, b ? NULL : &cs[k], level + 1, sub[k], ns[k]);
    } else {
        w->bundles++;
        w->ray_cands += (uint64_t)n * r.num_cands;
        for (int i = 0; i < n; ++i)
            if (hits[idx[i]].prim != SIDX_NO_HIT && !has(&r, hits[idx[i]].prim)) w->conservative = 0;
    }
    sidx_bundle_result_free(&r);
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_LEAF_SIZE(knobs), {0}};
    lesson_args args = {.name = "18_beams_and_cones",
                        .usage = usage,
                        .scene = "teapot",
                        .options = options,
                        .refused = "the bundle tree has no other knob; the BVH only gives each pixel's true hit"};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    sidx_bundle_tree *tree = NULL;
    sidx_accel *bvh = NULL;
    if (sidx_bundle_tree_build(&mesh, &knobs, &tree, &err) != SIDX_OK ||
        sidx_accel_build("bvh", &mesh, NULL, &bvh, &err) != SIDX_OK)
        lesson_fail(&args, err.message);

    cam = lesson_camera_at(sidx_mesh_bounds(&mesh), 0.35f, 0.3f, 1.2f);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            sidx_ray_init(&rays[y * W + x], cam.eye, dir_at((float)x + 0.5f, (float)y + 0.5f), 0.0f, INFINITY);
    sidx_accel_intersect_n(bvh, rays, (size_t)W * H, NULL, hits);
    printf("== '%s' (%u triangles); a %d x %d camera image in %d tiles of %d x %d pixels\n", args.scene,
           mesh.num_triangles, W, H, NTILES, TILE, TILE);

    /* ---- 1. one beam, traced ---- */
    int tx = 0, ty = 0; /* the tile with the fewest candidates among those with hits in it */
    uint32_t fewest = UINT32_MAX;
    for (int y0 = 0; y0 < H; y0 += TILE)
        for (int x0 = 0; x0 < W; x0 += TILE) {
            const sidx_beam b = beam_of(x0, y0, TILE);
            sidx_bundle_result r = {0};
            if (sidx_beam_trace(tree, &b, 0, 0, NULL, &r) != SIDX_OK) lesson_fail(&args, "beam trace failed");
            uint32_t hit_here = 0;
            for (uint32_t i = 0; i < r.num_cands; ++i)
                for (int k = 0; k < TILE * TILE; ++k)
                    if (hits[(y0 + k / TILE) * W + x0 + k % TILE].prim == r.cands[i]) { ++hit_here; break; }
            if (hit_here >= 2 && r.num_cands < fewest) { fewest = r.num_cands; tx = x0; ty = y0; }
            sidx_bundle_result_free(&r);
        }
    printf("\n== 1. The beam of the tile at pixel (%d, %d), through the BVH (its first 16 tests)\n", tx, ty);
    first_events fe = {16, 0};
    const sidx_hook fh = {first_fn, &fe, SIDX_EVMASK(SIDX_EV_BOX_TEST) | SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    const sidx_beam b1 = beam_of(tx, ty, TILE);
    sidx_bundle_result r1 = {0};
    if (sidx_beam_trace(tree, &b1, 0, 0, &fh, &r1) != SIDX_OK) lesson_fail(&args, "beam trace failed");
    printf("  ... %d tests more\n  %llu nodes visited, %llu culled, %llu triangle tests; %u candidates:\n   ", fe.dropped,
           (unsigned long long)r1.nodes_visited, (unsigned long long)r1.nodes_culled,
           (unsigned long long)r1.tri_tests, r1.num_cands);
    for (uint32_t i = 0; i < r1.num_cands && i < 8; ++i) printf(" %u", r1.cands[i]);
    printf("%s\n", r1.num_cands > 8 ? " ..." : "");
    uint32_t seen_hit[TILE * TILE], nseen = 0;
    for (int y = ty; y < ty + TILE; ++y)
        for (int x = tx; x < tx + TILE; ++x) {
            const uint32_t p = hits[y * W + x].prim;
            int dup = p == SIDX_NO_HIT;
            for (uint32_t k = 0; k < nseen && !dup; ++k) dup = seen_hit[k] == p;
            if (!dup) seen_hit[nseen++] = p;
        }
    printf("  the tile's %d rays, traced one by one, hit %u distinct triangles first; all among the\n"
           "  candidates: %s\n", TILE * TILE, nseen, holds_tile_hits(&r1, tx, ty) ? "yes" : "NO");
    sidx_bundle_result_free(&r1);

    /* ---- 2. one bundle per tile vs one per pixel ---- */
    printf("\n== 2. All %d tiles: one bundle per tile against one beam per pixel\n", NTILES);
    uint64_t tile_nodes[2] = {0, 0}, tile_cands[2] = {0, 0}, pixel_nodes = 0, pixel_cands = 0, hit_tris = 0;
    int conservative = 1, tree_exact = 1;
    for (int y0 = 0; y0 < H; y0 += TILE)
        for (int x0 = 0; x0 < W; x0 += TILE) {
            const sidx_beam b = beam_of(x0, y0, TILE);
            const sidx_cone c = cone_of(&b, x0, y0, TILE);
            sidx_bundle_result rb = {0}, rc = {0}, bb = {0}, bc = {0};
            if (sidx_beam_trace(tree, &b, 0, 0, NULL, &rb) != SIDX_OK ||
                sidx_cone_trace(tree, &c, 0, 0, NULL, &rc) != SIDX_OK ||
                sidx_beam_candidates_brute(&mesh, &b, &bb) != SIDX_OK ||
                sidx_cone_candidates_brute(&mesh, &c, &bc) != SIDX_OK)
                lesson_fail(&args, "bundle trace failed");
            tree_exact &= same_cands(&rb, &bb) && same_cands(&rc, &bc);
            conservative &= holds_tile_hits(&rb, x0, y0) && holds_tile_hits(&rc, x0, y0);
            tile_nodes[0] += rb.nodes_visited;
            tile_nodes[1] += rc.nodes_visited;
            tile_cands[0] += rb.num_cands;
            tile_cands[1] += rc.num_cands;
            /* the triangles the tile's rays really hit first, each once */
            for (uint32_t i = 0; i < rb.num_cands; ++i) {
                int hit = 0;
                for (int y = y0; y < y0 + TILE && !hit; ++y)
                    for (int x = x0; x < x0 + TILE && !hit; ++x) hit = hits[y * W + x].prim == rb.cands[i];
                hit_tris += (uint64_t)hit;
            }
            for (int y = y0; y < y0 + TILE; ++y)
                for (int x = x0; x < x0 + TILE; ++x) {
                    const sidx_beam pb = beam_of(x, y, 1);
                    sidx_bundle_result rp = {0};
                    if (sidx_beam_trace(tree, &pb, 0, 0, NULL, &rp) != SIDX_OK) lesson_fail(&args, "beam trace failed");
                    pixel_nodes += rp.nodes_visited;
                    pixel_cands += rp.num_cands;
                    sidx_bundle_result_free(&rp);
                }
            sidx_bundle_result_free(&rb);
            sidx_bundle_result_free(&rc);
            sidx_bundle_result_free(&bb);
            sidx_bundle_result_free(&bc);
        }
    const double px = (double)W * H;
    printf("  %-22s %14s %16s %18s\n", "", "nodes / pixel", "candidates/tile", "candidates / ray");
    printf("  %-22s %14.2f %16s %18.2f\n", "a beam per pixel", (double)pixel_nodes / px, "-", (double)pixel_cands / px);
    printf("  %-22s %14.2f %16.2f %18.2f\n", "a beam per tile", (double)tile_nodes[0] / px,
           (double)tile_cands[0] / NTILES, (double)tile_cands[0] / NTILES);
    printf("  %-22s %14.2f %16.2f %18.2f\n", "a cone per tile", (double)tile_nodes[1] / px,
           (double)tile_cands[1] / NTILES, (double)tile_cands[1] / NTILES);
    printf("  One beam walks the tree for %d rays: %.1fx fewer node visits per pixel than a beam each.\n"
           "  But its answer is a list: of its %.1f candidates per tile only %.1f are the first hit of\n"
           "  some ray of the tile — each ray still tests the list (or the beam must be clipped at every\n"
           "  triangle: \"clipping of beams?\").  The cone holds the square beam and a little more:\n"
           "  %.0f%% more candidates (\"good approximations?\").\n",
           TILE * TILE, (double)pixel_nodes / (double)tile_nodes[0], (double)tile_cands[0] / NTILES,
           (double)hit_tris / NTILES, 100.0 * ((double)tile_cands[1] / (double)tile_cands[0] - 1.0));
    printf("  The tree walk finds exactly the candidates of testing every triangle: %s;\n"
           "  every ray's first hit is among its tile's beam and cone candidates: %s\n",
           tree_exact ? "yes" : "NO", conservative ? "yes" : "NO");

    /* ---- 3. subdividing ---- */
    printf("\n== 3. Subdividing bundles with more than %d candidates into 4, up to L times (all tiles)\n", SPLIT_CANDS);
    printf("  %-6s %3s %10s %12s %14s %18s\n", "", "L", "bundles", "subdivided", "nodes / pixel", "candidates / ray");
    double per_ray[2][4];
    uint64_t nodes[2][4];
    int sub_conservative = 1, own_matches = 1;
    for (int kind = 0; kind < 2; ++kind)
        for (int L = 0; L <= 3; ++L) {
            split_walk w = {tree, (uint32_t)L, 0, 0, 0, 1};
            uint64_t subs = 0, lib_bundles = 0, lib_nodes = 0;
            for (int y0 = 0; y0 < H; y0 += TILE)
                for (int x0 = 0; x0 < W; x0 += TILE) {
                    const sidx_beam b = beam_of(x0, y0, TILE);
                    const sidx_cone c = cone_of(&b, x0, y0, TILE);
                    int idx[TILE * TILE];
                    for (int k = 0; k < TILE * TILE; ++k) idx[k] = (y0 + k / TILE) * W + x0 + k % TILE;
                    split_trace(&w, kind ? NULL : &b, kind ? &c : NULL, 0, idx, TILE * TILE);
                    sidx_bundle_result r = {0}; /* the library's own subdivision, for comparison */
                    const sidx_status s = kind ? sidx_cone_trace(tree, &c, SPLIT_CANDS, (uint32_t)L, NULL, &r)
                                               : sidx_beam_trace(tree, &b, SPLIT_CANDS, (uint32_t)L, NULL, &r);
                    if (s != SIDX_OK) lesson_fail(&args, "bundle trace failed");
                    sub_conservative &= holds_tile_hits(&r, x0, y0);
                    subs += r.subdivisions;
                    lib_bundles += r.bundles;
                    lib_nodes += r.nodes_visited;
                    sidx_bundle_result_free(&r);
                }
            own_matches &= w.bundles == lib_bundles && w.nodes == lib_nodes;
            sub_conservative &= w.conservative;
            nodes[kind][L] = w.nodes;
            per_ray[kind][L] = (double)w.ray_cands / px;
            printf("  %-6s %3d %10llu %12llu %14.2f %18.2f\n", kind ? "cones" : "beams", L, (unsigned long long)w.bundles,
                   (unsigned long long)subs, (double)w.nodes / px, per_ray[kind][L]);
        }
    printf("  candidates / ray: the candidates of the final bundle each ray ends in (the lesson repeats the\n"
           "  subdivision with sidx_beam_split / sidx_cone_split to follow the rays; same bundles and node\n"
           "  visits as the library's own: %s).  Smaller bundles leave each ray fewer candidates, for\n"
           "  more walks through the tree: at L = 3 about as many node visits as a beam per\n"
           "  pixel (%.1f).  The 4 children of a cone cover %.1fx its solid angle (circles cannot tile a\n"
           "  circle), so at L = 3 cones pay %.1fx the node visits of beams and leave each ray %.1fx the\n"
           "  candidates.\n",
           own_matches ? "yes" : "NO", (double)pixel_nodes / px, 4.0 * 0.78 * 0.78, (double)nodes[1][3] / (double)nodes[0][3],
           per_ray[1][3] / per_ray[0][3]);

    sidx_accel_destroy(bvh);
    sidx_bundle_tree_destroy(tree);
    sidx_mesh_free(&mesh);
    lesson_check("tree_matches_brute", tree_exact);
    lesson_check("conservative", conservative && sub_conservative);
    lesson_check("tile_beam_fewer_visits", tile_nodes[0] < pixel_nodes);
    lesson_check("candidates_exceed_hits", (uint64_t)tile_cands[0] > hit_tris);
    lesson_check("subdivision_narrows", per_ray[0][3] < per_ray[0][0] && per_ray[1][3] < per_ray[1][0]);
    lesson_check("own_subdivision_matches", own_matches);
    lesson_check("cones_cost_more", nodes[1][3] > nodes[0][3] && tile_cands[1] >= tile_cands[0]);
    return 0;
}
