/* 05_bvh_traversal.c — naive vs ordered BVH traversal, side by side.
 *
 * Slides (deck 001, "Spatial Data Structures"): "BVH Traversal" (the
 * naive hit(): "traverse BOTH children"; "We don't ALWAYS need to check
 * both children. Recall the first example where we terminated after
 * searching only the closer bbox."), "Better BVH Traversal" ("pick node
 * with better time" ... "Only check far bbox if closest primitive in the
 * near bbox is farther than the closest point intersected in the far
 * bbox") and "BVH Review" ("Traversing the BVH").  Deck 000: "BVH
 * traversal (1)-(3)" and "Bounding Volume Hierarchies (BVHs)" ("Cannot
 * terminate on first intersection found ... Can only terminate, once all
 * remaining BVs are completely behind the intersection").
 *
 * What it shows: a stack of six square tiles, one above the other, and a
 * ray falling through all of them from above.  The naive traversal visits
 * the children in stored order (left first), the ordered one nearer child
 * first; both traces are printed side by side from the printer's lines,
 * and the count of nodes each visited.  Then the same for many random
 * rays on a real scene (default teapot), also with the explicit-stack
 * traversal that sidx uses by default.
 *
 * Read:  lib/bvh_traverse.c, ordered_body
 * Run:   build/lessons/05_bvh_traversal [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply for the averages (default teapot)
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
    fprintf(f, "usage: 05_bvh_traversal [--help] [build knobs] [SCENE]\n"
               "\n"
               "Naive (both children, stored order) vs ordered (nearer child first) BVH traversal:\n"
               "two traces side by side, then node visits per ray on a scene.\n"
               "\n"
               "  SCENE   scene for the averages: built-in name or .obj/.ply (default: teapot)\n"
               "The knobs below change the BVH of the averages on SCENE (other leaves, other cuts);\n"
               "the six tiles keep one tile per leaf.  The checks hold for the defaults.\n");
}

/* Six 2 x 2 tiles at heights z = 0 .. 5, shifted a little so their boxes
 * are not all the same. */
static sidx_status make_tiles(sidx_mesh *out, sidx_error *err)
{
    float xyz[6 * 4 * 3];
    uint32_t idx[6 * 6];
    for (int i = 0; i < 6; ++i) {
        const float x0 = -1.0f + 0.15f * (float)(i % 3), y0 = -1.0f + 0.1f * (float)(i % 2), z = (float)i;
        const float c[4][2] = {{x0, y0}, {x0 + 2, y0}, {x0 + 2, y0 + 2}, {x0, y0 + 2}};
        for (int k = 0; k < 4; ++k) {
            xyz[12 * i + 3 * k] = c[k][0];
            xyz[12 * i + 3 * k + 1] = c[k][1];
            xyz[12 * i + 3 * k + 2] = z;
        }
        const uint32_t b = (uint32_t)(4 * i);
        const uint32_t q[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        memcpy(&idx[6 * i], q, sizeof q);
    }
    return sidx_mesh_from_arrays(out, xyz, 24, idx, 12, err);
}

typedef struct {
    uint64_t visits, boxes, prims;
} work;

static void print_side_by_side(const sidx_recorder *l, const sidx_recorder *r, int width)
{
    const size_t n = l->count > r->count ? l->count : r->count;
    char a[256], b[256];
    printf("  %-*s | %s\n", width, "naive (both children, left first)", "ordered (nearer child first)");
    printf("  %.*s-+-%.*s\n", width, "------------------------------------------------------------------------",
           width, "------------------------------------------------------------------------");
    for (size_t i = 0; i < n; ++i) {
        a[0] = b[0] = '\0';
        if (i < l->count) sidx_event_format(&l->events[i], a, sizeof a);
        if (i < r->count) sidx_event_format(&r->events[i], b, sizeof b);
        printf("  %-*.*s | %s\n", width, width, a, b);
    }
}

static work count_of(const sidx_recorder *rec)
{
    work w = {0, 0, 0};
    for (size_t i = 0; i < rec->count; ++i) {
        w.visits += rec->events[i].type == SIDX_EV_NODE_ENTER;
        w.boxes += rec->events[i].type == SIDX_EV_BOX_TEST;
        w.prims += rec->events[i].type == SIDX_EV_PRIM_TEST;
    }
    return w;
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_BINS(knobs),      LESSON_C_TRAV(knobs),    LESSON_C_TRI(knobs),
                                     LESSON_LEAF_SIZE(knobs), LESSON_MAX_DEPTH(knobs), {0}};
    lesson_args args = {.name = "05_bvh_traversal", .usage = usage, .scene = "teapot", .options = options};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");

    /* ---- one ray through the tiles ---- */
    sidx_mesh tiles;
    sidx_error err = {0};
    if (make_tiles(&tiles, &err) != SIDX_OK) { fprintf(stderr, "05_bvh_traversal: %s\n", err.message); return 1; }
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    pr.mask = SIDX_EVMASK_BUILD & ~SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE);
    const sidx_hook ph = sidx_printer_hook(&pr);
    sidx_build_options opt = {0};
    opt.hook = &ph;
    opt.leaf_size = 2; /* one tile (two triangles) per leaf */
    sidx_accel *a = NULL;
    printf("== Six tiles stacked at z = 0..5 (triangles 2i, 2i+1 make tile i), leaves of two triangles\n");
    if (sidx_accel_build("bvh", &tiles, &opt, &a, &err) != SIDX_OK) {
        fprintf(stderr, "05_bvh_traversal: %s\n", err.message);
        sidx_mesh_free(&tiles);
        return 1;
    }
    sidx_ray ray;
    sidx_ray_init(&ray, sidx_v3(0.3f, 0.2f, 10.0f), sidx_v3(0.01f, 0.02f, -1.0f), 0.0f, INFINITY);
    printf("\n== One ray from (0.3, 0.2, 10) straight down through every tile; the top tile (z = 5) is\n"
           "   the closest hit.  The printer's lines, one traversal per column:\n\n");
    sidx_recorder rn, ro;
    sidx_recorder_init(&rn);
    sidx_recorder_init(&ro);
    const sidx_hook hn = sidx_recorder_hook(&rn), ho = sidx_recorder_hook(&ro);
    sidx_query qn = {0, SIDX_TRAVERSE_NAIVE, &hn, 0}, qo = {0, SIDX_TRAVERSE_ORDERED, &ho, 0};
    sidx_hit h_naive, h_ordered;
    sidx_accel_intersect(a, &ray, &qn, &h_naive);
    sidx_accel_intersect(a, &ray, &qo, &h_ordered);
    print_side_by_side(&rn, &ro, 52);
    const work wn = count_of(&rn), wo = count_of(&ro);
    printf("\n  %-10s %8s %10s %10s   hit\n", "", "visits", "box tests", "tri tests");
    printf("  %-10s %8llu %10llu %10llu   prim %u t=%g\n", "naive", (unsigned long long)wn.visits,
           (unsigned long long)wn.boxes, (unsigned long long)wn.prims, h_naive.prim, h_naive.t);
    printf("  %-10s %8llu %10llu %10llu   prim %u t=%g\n", "ordered", (unsigned long long)wo.visits,
           (unsigned long long)wo.boxes, (unsigned long long)wo.prims, h_ordered.prim, h_ordered.t);
    printf("  The naive walk goes left first, finds the lower tiles first and has to keep improving its\n"
           "  hit; the ordered walk takes the nearer child, hits the top tile at once, and then every\n"
           "  farther box starts behind that hit and is skipped.  Neither can stop at the first hit:\n"
           "  BVH boxes may overlap, and only boxes entirely behind the hit can be dropped.\n");
    printf("  Erratum, deck 001 \"Better BVH Traversal\": the slide picks `second` by its own comparison\n"
           "  (hit2.t <= hit1.t ? child2 : child1), so when child 2 is nearer both `first` and `second`\n"
           "  are child 2 (on the second version of the slide, when child 1 is nearer, both are child 1),\n"
           "  and it then tests hit2.t (or an undefined closest.t) whichever child went first.  The walk\n"
           "  above takes `second` as the child that is not `first` and tests that child's own entry t\n"
           "  against the best hit so far.\n");
    const int same_one = h_naive.prim == h_ordered.prim && h_naive.t == h_ordered.t;
    const int fewer_one = wo.visits < wn.visits;
    sidx_recorder_free(&rn);
    sidx_recorder_free(&ro);
    sidx_accel_destroy(a);
    sidx_mesh_free(&tiles);

    /* ---- averages on a scene ---- */
    sidx_mesh mesh = lesson_open_scene(&args);
    if (sidx_accel_build("bvh", &mesh, &knobs, &a, &err) != SIDX_OK) {
        fprintf(stderr, "05_bvh_traversal: %s\n", err.message);
        sidx_mesh_free(&mesh);
        return 1;
    }
    const int nrays = 20000;
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const float R = sidx_v3_length(ext);
    const sidx_traversal kinds[3] = {SIDX_TRAVERSE_NAIVE, SIDX_TRAVERSE_ORDERED, SIDX_TRAVERSE_STACK};
    sidx_counters cnt[3];
    int same = 1;
    for (int k = 0; k < 3; ++k) sidx_counters_init(&cnt[k]);
    uint32_t seed = 4242u;
    for (int i = 0; i < nrays; ++i) {
        float f[5];
        for (int j = 0; j < 5; ++j) { seed = seed * 1664525u + 1013904223u; f[j] = (float)(seed >> 8) / 16777216.0f; }
        const float z = 2 * f[0] - 1, ang = 6.2831853f * f[1], s = sqrtf(1 - z * z);
        const sidx_vec3 o = sidx_v3_add(ctr, sidx_v3(R * s * cosf(ang), R * s * sinf(ang), R * z));
        const sidx_vec3 t = sidx_v3(box.min.x + f[2] * ext.x, box.min.y + f[3] * ext.y, box.min.z + f[4] * ext.z);
        sidx_ray r;
        if (sidx_ray_init(&r, o, sidx_v3_sub(t, o), 0.0f, INFINITY) != SIDX_OK) continue;
        float t0 = 0;
        for (int k = 0; k < 3; ++k) {
            const sidx_hook ch = sidx_counters_hook(&cnt[k]);
            sidx_query q = {0, kinds[k], &ch, (uint32_t)i};
            sidx_hit h;
            sidx_accel_intersect(a, &r, &q, &h);
            if (k == 0) t0 = h.t;
            else if (!(h.t == t0)) same = 0;
        }
    }
    sidx_accel_destroy(a);
    printf("\n== '%s' (%u triangles): %d random rays, per ray on average\n", args.scene, mesh.num_triangles, nrays);
    sidx_mesh_free(&mesh);
    printf("  %-10s %10s %10s %10s %8s\n", "traversal", "visits", "box tests", "tri tests", "pushes");
    double v[3];
    for (int k = 0; k < 3; ++k) {
        v[k] = (double)cnt[k].n[SIDX_EV_NODE_ENTER] / nrays;
        printf("  %-10s %10.2f %10.2f %10.2f %8.2f\n", sidx_traversal_name(kinds[k]), v[k],
               (double)cnt[k].n[SIDX_EV_BOX_TEST] / nrays, (double)cnt[k].n[SIDX_EV_PRIM_TEST] / nrays,
               (double)cnt[k].n[SIDX_EV_STACK_PUSH] / nrays);
    }
    printf("  All three find the same closest hits: %s.  Ordered visits %.0f%% of the nodes naive visits.\n",
           same ? "yes" : "NO", 100.0 * v[1] / v[0]);
    lesson_check("same_hit", same && same_one);
    lesson_check("ordered_visits_fewer", fewer_one);
    lesson_check("ordered_fewer_on_average", v[1] < v[0] && v[2] < v[0]);
    return 0;
}
