/* 27_building_kdtrees_quickly.c — where a kd-tree build spends its time,
 * and a build that waits for the rays.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Building kD-trees
 * quickly" ("Remember, profile first! Where's the time going? — Split
 * personality — Memory traffic all at the top (NO cache misses at bottom)
 * — Sifting through bajillion triangles to pick one split (!) —
 * Hierarchical building? — Computation mostly at the bottom — Lots of
 * leaves, need more exact candidate info — Lazy building?").
 *
 * What it shows, on one scene (default stadium:2048, the teapot in a
 * stadium of ~15,700 triangles):
 *   1. profile first: the SAH build (Wald & Havran's event sweep) level by
 *      level, from its own build events: nodes, the triangle references a
 *      level sifts, the sorted event lists one node sweeps (its working
 *      set) against a 32 KB cache, and the build time spent at each level
 *      (the clock read at every event): the top levels sift every
 *      triangle through lists far larger than a cache, the bottom levels
 *      make nearly all of the nodes from lists that fit in one;
 *   2. lazy building (opt.lazy): the top of the tree now, every subtree of
 *      at most 1024 references when a ray first enters it.  One image from
 *      beside the teapot: what it builds, the build_lazy_expand event of
 *      one ray, and its hits against the eager tree's; then a tree whose
 *      root waits, which the first ray builds whole: the eager tree, node
 *      for node;
 *   3. lazy instances: the same idea one level up.  A city of 100
 *      distinct buildings (sidx_city_make), each an instance naming its
 *      mesh and a BVH to build (sidx_aggregate_build_meshes); with
 *      opt.lazy a building's BVH is built the first time a ray enters its
 *      box.  One image from the street with a shadow ray per hit: how
 *      many buildings it built, and its hits against the eager city's.
 *
 * Read:  lib/kdtree_build.c, kd_expand; lib/lazy.c, sidx__lazy_claim;
 *        lib/instance.c, sidx_aggregate_build_meshes
 * Run:   build/lessons/27_building_kdtrees_quickly [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default stadium:2048)
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
    fprintf(f, "usage: 27_building_kdtrees_quickly [--help] [build knobs] [SCENE]\n"
               "\n"
               "Where the SAH kd-tree build spends its time, level by level (nodes, references\n"
               "sifted, working set per node, time), then a lazy build: what one image from a\n"
               "camera that sees part of the scene builds, and its hits against the eager tree's.\n"
               "\n"
               "  SCENE   built-in name or .obj/.ply (default: stadium:2048; a stadium is seen from\n"
               "          beside its teapot, any other scene from outside its box)\n"
               "The knobs below change both kd-trees.  The checks hold for the defaults.\n");
}

static sidx_build_options knobs;

#define MAXD 65
#define L1_BYTES (32u * 1024u)   /* a typical L1 data cache */
#define EVENT_BYTES 48u          /* a reference's 6 sorted events, 8 bytes each (lib/kdtree_build.c) */
#define W 128
#define H 128

/* ---- 1. the profile ---------------------------------------------------------------- */

typedef struct level {
    uint32_t nodes, leaves, small; /* small: nodes whose event lists fit in L1_BYTES */
    uint64_t refs;
    double seconds;
} level;

typedef struct profile {
    level lv[MAXD];
    uint32_t max_depth;
    double last;            /* the clock at the previous event */
    int last_depth;         /* that event's level; -1 before the root, MAXD after the last leaf */
    double before_root, after_leaves;
    uint64_t root_refs;
} profile;

/* Every build event closes the interval since the previous one, which is
 * the previous event's node's work: BUILD_NODE → its split or leaf is the
 * sweep over its events, BUILD_SPLIT → the first child's BUILD_NODE is
 * sifting its lists into the children's. */
static void on_build(const sidx_event *e, void *user)
{
    profile *p = user;
    const double now = lesson_seconds();
    const double dt = now - p->last;
    p->last = now;
    if (p->last_depth < 0) p->before_root += dt;
    else if (p->last_depth >= MAXD) p->after_leaves += dt;
    else p->lv[p->last_depth].seconds += dt;
    const int d = e->depth < MAXD ? (int)e->depth : MAXD - 1;
    switch (e->type) {
    case SIDX_EV_BUILD_NODE:
        p->lv[d].nodes++;
        p->lv[d].refs += e->count;
        p->lv[d].small += (uint64_t)e->count * EVENT_BYTES <= L1_BYTES;
        if (e->depth == 0) p->root_refs = e->count;
        if (e->depth > p->max_depth) p->max_depth = e->depth;
        p->last_depth = d;
        break;
    case SIDX_EV_BUILD_LEAF: p->lv[d].leaves++; p->last_depth = d; break;
    case SIDX_EV_BUILD_SPLIT: p->last_depth = d; break;
    case SIDX_EV_BUILD_END: p->last_depth = MAXD; break;
    default: p->last_depth = -1; break; /* BUILD_BEGIN: triangle copies and the root's one full sort follow */
    }
}

/* ---- 2. lazy building ---------------------------------------------------------------- */

typedef struct expand_log {
    uint32_t expands, leaves_after, first_count, first_node;
    int first_shown;
} expand_log;

static void on_expand(const sidx_event *e, void *user)
{
    expand_log *l = user;
    if (e->type == SIDX_EV_BUILD_LAZY_EXPAND) {
        if (l->expands++ == 0) {
            l->first_count = e->count;
            l->first_node = e->node;
            char line[256];
            sidx_event_format(e, line, sizeof line);
            printf("  %s\n", line);
        }
    } else if (e->type == SIDX_EV_BUILD_LEAF && l->expands) {
        l->leaves_after++;
        if (l->first_shown++ < 3) {
            char line[256];
            sidx_event_format(e, line, sizeof line);
            printf("    then %s\n", line);
        }
    }
}

/* A lazy kd-tree's leaves test blocks of four references that reach into
 * neighbouring leaves (lib/kdtree_internal.h); a subtree built apart has
 * other neighbours, so where two triangles are hit at the same t, or an
 * ulp apart, it may keep the other one.  Such a hit: t within 1e-6·t and
 * the ray hits that triangle at exactly its t. */
static int close_hit(const sidx_mesh *m, const sidx_ray *r, const sidx_hit *e, const sidx_hit *l)
{
    if (e->prim == SIDX_NO_HIT || l->prim == SIDX_NO_HIT) return e->prim == l->prim;
    float t, u, v;
    return fabsf(e->t - l->t) <= 1e-6f * fabsf(e->t) &&
           sidx_intersect_triangle_watertight(r, sidx_mesh_vertex(m, l->prim, 0), sidx_mesh_vertex(m, l->prim, 1),
                                              sidx_mesh_vertex(m, l->prim, 2), INFINITY, &t, &u, &v) &&
           t == l->t;
}

static sidx_ray rays[W * H];
static sidx_hit hits[2][W * H];

int main(int argc, char **argv)
{
    const lesson_option options[] = {LESSON_C_TRAV(knobs),    LESSON_C_TRI(knobs),       LESSON_LEAF_SIZE(knobs),
                                     LESSON_MAX_DEPTH(knobs), LESSON_EMPTY_BONUS(knobs), {0}};
    lesson_args args = {.name = "27_building_kdtrees_quickly", .usage = usage, .scene = "stadium:2048",
                        .options = options, .refused = "only SAH kd-trees are built here"};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "kdtree");
    sidx_mesh m = lesson_open_scene(&args);
    sidx_error err = {0};
    const uint32_t n = m.num_triangles;

    /* ---- 1 ---- */
    printf("== 1. Profile first: the SAH build of %s (%u triangles), level by level\n", args.scene, n);
    profile *p = calloc(1, sizeof *p);
    if (!p) lesson_fail(&args, "out of memory");
    p->last_depth = -1;
    const sidx_hook ph = {on_build, p,
                          SIDX_EVMASK(SIDX_EV_BUILD_BEGIN) | SIDX_EVMASK(SIDX_EV_BUILD_NODE) |
                              SIDX_EVMASK(SIDX_EV_BUILD_SPLIT) | SIDX_EVMASK(SIDX_EV_BUILD_LEAF) |
                              SIDX_EVMASK(SIDX_EV_BUILD_END)};
    sidx_build_options bo = knobs;
    bo.hook = &ph;
    sidx_accel *profiled = NULL;
    p->last = lesson_seconds();
    if (sidx_accel_build("kdtree", &m, &bo, &profiled, &err) != SIDX_OK) lesson_fail(&args, err.message);
    sidx_accel_destroy(profiled);
    double total = p->before_root + p->after_leaves;
    uint32_t nodes = 0, small = 0;
    for (uint32_t d = 0; d <= p->max_depth && d < MAXD; ++d) {
        total += p->lv[d].seconds;
        nodes += p->lv[d].nodes;
        small += p->lv[d].small;
    }
    printf("  working set = the node's sorted event lists, %u bytes per reference; cache = %u KB\n\n",
           EVENT_BYTES, L1_BYTES / 1024u);
    printf("  %5s %7s %7s %10s %12s %14s %8s %8s\n", "depth", "nodes", "leaves", "refs", "refs/node",
           "working set", "> cache", "time %");
    for (uint32_t d = 0; d <= p->max_depth && d < MAXD; ++d) {
        const level *L = &p->lv[d];
        if (!L->nodes) continue;
        const double per = (double)L->refs / L->nodes;
        char ws[32];
        const double bytes = per * EVENT_BYTES;
        if (bytes >= 1024.0 * 1024.0) snprintf(ws, sizeof ws, "%.1f MB", bytes / (1024.0 * 1024.0));
        else snprintf(ws, sizeof ws, "%.1f KB", bytes / 1024.0);
        printf("  %5u %7u %7u %10llu %12.1f %14s %8u %7.1f%%\n", d, L->nodes, L->leaves, (unsigned long long)L->refs,
               per, ws, L->nodes - L->small, 100.0 * L->seconds / total);
    }
    uint32_t top = 0, top_nodes = 0; /* the levels whose nodes' lists do not fit in the cache on average */
    double top_time = 0.0, top_refs = 0.0, all_refs = 0.0;
    for (uint32_t d = 0; d <= p->max_depth && d < MAXD; ++d) {
        all_refs += (double)p->lv[d].refs;
        if (p->lv[d].nodes && (double)p->lv[d].refs * EVENT_BYTES > (double)p->lv[d].nodes * L1_BYTES) {
            top = d + 1;
            top_nodes += p->lv[d].nodes;
            top_time += p->lv[d].seconds;
            top_refs += (double)p->lv[d].refs;
        }
    }
    printf("\n  before the root: the triangle copies and the one full sort of the events (%.1f%% of the time);\n"
           "  after the last leaf: the leaves' triangle blocks (%.1f%%).  Total %.1f ms.\n",
           100.0 * p->before_root / total, 100.0 * p->after_leaves / total, 1e3 * total);
    printf("  Split personality: the top %u levels (%u nodes, %.2f%% of them) sift %.0f%% of all the references\n"
           "  through lists larger than the cache and take %.0f%% of the time: memory traffic.  Below them,\n"
           "  %.1f%% of the nodes sweep lists that fit in it: the computation of many small decisions.\n",
           top, top_nodes, 100.0 * top_nodes / nodes, 100.0 * top_refs / all_refs, 100.0 * top_time / total,
           100.0 * small / nodes);
    int top_all = p->root_refs == n;
    for (uint32_t d = 1; d < 3 && d <= p->max_depth; ++d) top_all &= p->lv[d].refs >= n;
    const uint64_t root_bytes = p->root_refs * EVENT_BYTES;
    free(p);

    /* ---- 2 ---- */
    printf("\n== 2. Lazy building: one %dx%d image from ", W, H);
    const sidx_aabb box = sidx_mesh_bounds(&m);
    lesson_camera cam;
    if (!strncmp(args.scene, "stadium", 7)) {
        printf("beside the teapot\n");
        /* the camera of sidx-bench lazy: the teapot, the floor, a slice of the stands */
        cam.eye = sidx_v3(0.9f, 0.35f, 0.9f);
        const sidx_vec3 at = sidx_v3(0.0f, 0.2f, 0.0f), d = sidx_v3_sub(at, cam.eye);
        cam.fwd = sidx_v3_scale(d, 1.0f / sidx_v3_length(d));
        cam.right = sidx_v3_cross(cam.fwd, sidx_v3(0, 1, 0));
        cam.right = sidx_v3_scale(cam.right, 1.0f / sidx_v3_length(cam.right));
        cam.up = sidx_v3_cross(cam.right, cam.fwd);
    } else {
        printf("outside the scene's box\n");
        cam = lesson_camera_at(box, 0.3f, 0.4f, 1.2f);
    }
    lesson_camera_rays(&cam, W, H, 0.37f, 0.37f, rays);
    sidx_accel *kd[2] = {NULL, NULL};
    double build_ms[2], image_ms[2];
    sidx_accel_stats before, after, eager;
    for (int k = 0; k < 2; ++k) {
        sidx_build_options o = knobs;
        o.lazy = (uint32_t)k; /* 1: the default size, SIDX_LAZY_DEFAULT */
        double t0 = lesson_seconds();
        if (sidx_accel_build("kdtree", &m, &o, &kd[k], &err) != SIDX_OK) lesson_fail(&args, err.message);
        build_ms[k] = 1e3 * (lesson_seconds() - t0);
        if (k) sidx_accel_stats_get(kd[k], &before);
        t0 = lesson_seconds();
        for (int i = 0; i < W * H; ++i)
            if (sidx_accel_intersect(kd[k], &rays[i], NULL, &hits[k][i]) != SIDX_OK) lesson_fail(&args, "out of memory");
        image_ms[k] = 1e3 * (lesson_seconds() - t0);
    }
    sidx_accel_stats_get(kd[0], &eager);
    sidx_accel_stats_get(kd[1], &after);
    printf("  %-26s %10s %10s %10s %12s %12s\n", "", "build ms", "image ms", "nodes", "references", "unbuilt");
    printf("  %-26s %10.1f %10.1f %10u %12llu %12s\n", "eager", build_ms[0], image_ms[0], eager.nodes,
           (unsigned long long)eager.prim_refs, "-");
    printf("  %-26s %10.1f %10s %10u %12llu %12u\n", "lazy, the top only", build_ms[1], "", before.nodes,
           (unsigned long long)before.prim_refs, before.unbuilt);
    printf("  %-26s %10s %10.1f %10u %12llu %12u\n", "lazy, after the image", "", image_ms[1], after.nodes,
           (unsigned long long)after.prim_refs, after.unbuilt);
    const double built = (double)after.prim_refs / (double)eager.prim_refs;
    printf("  The image built %.0f%% of the eager tree's nodes and %.0f%% of its references; %u subtrees\n"
           "  (%llu references) no ray entered are still unbuilt.  (Times: one run, not checked.)\n",
           100.0 * after.nodes / eager.nodes, 100.0 * built, after.unbuilt, (unsigned long long)after.unbuilt_prims);
    size_t same = 0, close = 0;
    for (int i = 0; i < W * H; ++i) {
        const sidx_hit *e = &hits[0][i], *l = &hits[1][i];
        if (e->prim == l->prim && memcmp(&e->t, &l->t, sizeof e->t) == 0) same++;
        else close += close_hit(&m, &rays[i], e, l);
    }
    printf("  Hits: %zu of %d the eager tree's bit for bit, %zu on a triangle the ray hits at the same t\n"
           "  up to rounding (a lazy subtree's leaf blocks of four have other neighbours).\n",
           same, W * H, close);

    printf("\n  The middle pixel's ray through a fresh lazy tree, with a hook:\n");
    sidx_accel *fresh = NULL;
    sidx_build_options o = knobs;
    o.lazy = 1;
    if (sidx_accel_build("kdtree", &m, &o, &fresh, &err) != SIDX_OK) lesson_fail(&args, err.message);
    expand_log log;
    memset(&log, 0, sizeof log);
    const sidx_hook eh = {on_expand, &log, SIDX_EVMASK(SIDX_EV_BUILD_LAZY_EXPAND) | SIDX_EVMASK(SIDX_EV_BUILD_LEAF)};
    const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &eh, 0};
    sidx_hit h;
    if (sidx_accel_intersect(fresh, &rays[(H / 2) * W + W / 2], &q, &h) != SIDX_OK) lesson_fail(&args, "out of memory");
    printf("  ... %u subtrees built for this ray, %u leaves in them.\n", log.expands, log.leaves_after);
    sidx_accel_destroy(fresh);

    printf("\n  A lazy tree whose root waits (opt.lazy = %u, the whole scene): the middle pixel's ray\n"
           "  builds it all.\n", n);
    o.lazy = n > 1 ? n : 2;
    if (sidx_accel_build("kdtree", &m, &o, &fresh, &err) != SIDX_OK) lesson_fail(&args, err.message);
    sidx_accel_stats whole0, whole;
    sidx_accel_stats_get(fresh, &whole0);
    if (sidx_accel_intersect(fresh, &rays[(H / 2) * W + W / 2], NULL, &h) != SIDX_OK)
        lesson_fail(&args, "out of memory");
    sidx_accel_stats_get(fresh, &whole);
    printf("  before: %u node, %u unbuilt; after: %u nodes, %u leaves, %llu references, depth %u\n"
           "  (eager: %u nodes, %u leaves, %llu references, depth %u)\n",
           whole0.nodes, whole0.unbuilt, whole.nodes, whole.leaves, (unsigned long long)whole.prim_refs,
           whole.max_depth, eager.nodes, eager.leaves, (unsigned long long)eager.prim_refs, eager.max_depth);
    sidx_accel_destroy(fresh);

    /* 3. lazy instances: a city seen from its street */
    printf("\n== 3. Lazy instances: a city of 100 distinct buildings, each an instance with its own\n"
           "BVH; one %dx%d image from the street and a shadow ray per hit to the sun\n", W, H);
    sidx_city city;
    if (sidx_city_make(100, 8, &city, &err) != SIDX_OK) lesson_fail(&args, err.message);
    lesson_camera street;
    street.eye = city.eye;
    street.fwd = sidx_v3_sub(city.at, city.eye);
    street.fwd = sidx_v3_scale(street.fwd, 1.0f / sidx_v3_length(street.fwd));
    street.right = sidx_v3_cross(street.fwd, sidx_v3(0, 1, 0));
    street.right = sidx_v3_scale(street.right, 1.0f / sidx_v3_length(street.right));
    street.up = sidx_v3_cross(street.right, street.fwd);
    lesson_camera_rays(&street, W, H, 0.5f, 0.5f, rays);
    sidx_aggregate_info cinfo[2];
    size_t city_same = 0, city_hits = 0;
    uint64_t city_tris = 0;
    for (uint32_t i = 0; i < city.n; ++i) city_tris += city.meshes[i].num_triangles;
    const sidx_query cq = {SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    for (int k = 0; k < 2; ++k) {
        sidx_build_options co;
        memset(&co, 0, sizeof co);
        co.lazy = (uint32_t)k;
        sidx_accel *agg = NULL;
        if (sidx_aggregate_build_meshes(city.instances, city.n, &co, &agg, &err) != SIDX_OK)
            lesson_fail(&args, err.message);
        for (int i = 0; i < W * H; ++i) {
            sidx_hit *ch = &hits[k][i];
            if (sidx_accel_intersect(agg, &rays[i], &cq, ch) != SIDX_OK) lesson_fail(&args, "out of memory");
            if (ch->prim == SIDX_NO_HIT) continue;
            /* an instanced hit has no point to spawn from: o + t d, a little off the surface */
            const sidx_ray *r = &rays[i];
            sidx_vec3 nn = sidx_v3_scale(ch->ng, 1.0f / sidx_v3_length(ch->ng));
            if (sidx_v3_dot(nn, r->dir) > 0.0f) nn = sidx_v3_scale(nn, -1.0f);
            const sidx_vec3 p = sidx_v3_add(sidx_v3_add(r->org, sidx_v3_scale(r->dir, ch->t)), sidx_v3_scale(nn, 1e-3f));
            sidx_ray sr;
            int occ = 0;
            if (sidx_ray_init(&sr, p, sidx_v3_sub(city.light, p), 0.0f, 1.0f) == SIDX_OK &&
                sidx_accel_occluded(agg, &sr, NULL, &occ) != SIDX_OK)
                lesson_fail(&args, "out of memory");
            ch->u = (float)occ; /* the shadow answer, compared below with the hit */
        }
        sidx_aggregate_info_get(agg, &cinfo[k]);
        sidx_accel_destroy(agg);
    }
    for (int i = 0; i < W * H; ++i) {
        const sidx_hit *e = &hits[0][i], *l = &hits[1][i];
        city_hits += e->prim != SIDX_NO_HIT;
        city_same += e->prim == l->prim && e->instance == l->instance && !memcmp(&e->t, &l->t, sizeof e->t) &&
                     !memcmp(&e->u, &l->u, sizeof e->u) && !memcmp(&e->ng, &l->ng, sizeof e->ng);
    }
    printf("  %llu triangles in %u buildings; the image hits %zu of %d pixels.\n"
           "  eager: %u buildings built before the first ray; lazy: %u built by the image (%u still waiting).\n"
           "  Hits and shadow answers: %zu of %d the eager city's bit for bit.\n",
           (unsigned long long)city_tris, city.n, city_hits, W * H, cinfo[0].built_structures,
           cinfo[1].built_structures, cinfo[1].mesh_structures - cinfo[1].built_structures, city_same, W * H);
    printf("  (sidx-bench lazy city:1000 measures it at full size: docs/performance.md.)\n");
    sidx_city_free(&city);

    lesson_check("top_sifts_everything", top_all);
    lesson_check("root_exceeds_cache", root_bytes > L1_BYTES);
    lesson_check("most_nodes_fit_cache", small >= 0.9 * nodes);
    lesson_check("image_builds_part", built < 0.75 && after.unbuilt > 0);
    lesson_check("hits_agree", same + close == (size_t)(W * H));
    lesson_check("expand_event_then_subtree", log.expands >= 1 && log.leaves_after >= 1 &&
                                                  log.first_count <= SIDX_LAZY_DEFAULT);
    lesson_check("whole_tree_is_eager", whole0.unbuilt == 1 && whole.unbuilt == 0 && whole.nodes == eager.nodes &&
                                            whole.leaves == eager.leaves && whole.prim_refs == eager.prim_refs &&
                                            whole.max_depth == eager.max_depth);
    lesson_check("city_builds_few", cinfo[0].built_structures == 100 && cinfo[1].built_structures > 0 &&
                                        cinfo[1].built_structures <= 50);
    lesson_check("city_hits_identical", city_same == (size_t)(W * H) && city_hits > 0);
    sidx_accel_destroy(kd[0]);
    sidx_accel_destroy(kd[1]);
    sidx_mesh_free(&m);
    return 0;
}
