/* 10_kdtree_traversal.c — the kd-tree's stack traversal, step by step.
 *
 * Slides (deck 000, "Spatial Index Structures"): "kD-Tree Traversal"
 * ("Front-to-back traversal ... Termination criterion: traversal can be
 * terminated as soon as surface intersection is found in the current
 * node ... Maintain stack of sub-trees still to traverse"), "kD-Tree
 * Traversal (1)-(11)" (the figures' "Current: ... Stack: ..." per step and
 * "CANNOT terminate !!!"), "kD-Tree Traversal Operation" (the three cases
 * t_split > t_far, t_near < t_split < t_far, t_split < t_near) and
 * "kD-Tree Traversal: Inner Loop".  Deck 001: "K-D Trees" ("Requirement:
 * intersection point must lie within zone").
 *
 * What it shows: the built-in 2D scene ("flat2d": 16 triangles on the
 * board, each tilted so that a ray in the board's plane meets it along its
 * longest median) in a kd-tree, and one ray running across the board in
 * its plane, chosen so that it meets a triangle that straddles cells: the
 * hit is found in a cell the hit point does not lie in.  The traversal's
 * events are printed by the printer sink (an inner node's line gives its
 * plane, t_split and which of the three cases the walk takes), and after every step the lesson
 * prints the slide's two lines — Current: the node being visited, Stack:
 * the deferred far children (with their t intervals) — and marks the
 * step where a hit is found but the walk CANNOT terminate.
 *
 * Read:  lib/kdtree_traverse.c, kd_walk_slide
 * Run:   build/lessons/10_kdtree_traversal [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default flat2d); rays
 *        then run through the middle of its box
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include "sidx/sidx.h"
#include "lesson.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 10_kdtree_traversal [--help] [build knobs] [SCENE]\n"
               "\n"
               "The kd-tree stack traversal for one ray, with the slides' Current / Stack lines per\n"
               "step, including a hit outside the current cell that cannot end the walk.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: flat2d)\n"
               "The knobs below change the kd-tree walked (a smaller tree, other cuts); the checks\n"
               "hold for the defaults.\n");
}

/* Is there a hit beyond the cell it was found in, followed by more steps? */
static int cannot_terminate_case(const sidx_recorder *rec, size_t *at)
{
    float cell_far = INFINITY;
    for (size_t i = 0; i < rec->count; ++i) {
        const sidx_event *e = &rec->events[i];
        if (e->type == SIDX_EV_NODE_ENTER) cell_far = e->t_far;
        if (e->type == SIDX_EV_HIT_UPDATE && e->t > cell_far * 1.0001f) {
            for (size_t j = i + 1; j < rec->count; ++j)
                if (rec->events[j].type == SIDX_EV_STACK_POP || rec->events[j].type == SIDX_EV_NODE_ENTER) {
                    *at = i;
                    return 1;
                }
            return 0;
        }
    }
    return 0;
}

static size_t count_type(const sidx_recorder *rec, sidx_event_type t)
{
    size_t n = 0;
    for (size_t i = 0; i < rec->count; ++i) n += rec->events[i].type == t;
    return n;
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_C_TRAV(knobs),    LESSON_C_TRI(knobs),       LESSON_LEAF_SIZE(knobs),
                                     LESSON_MAX_DEPTH(knobs), LESSON_EMPTY_BONUS(knobs), LESSON_NO_MAILBOX(knobs),
                                     {0}};
    lesson_args args = {.name = "10_kdtree_traversal", .usage = usage, .scene = "flat2d", .options = options};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "kdtree");
    lesson_need(&args, "brute");
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    sidx_accel *kd = NULL, *ref = NULL;
    sidx_accel_stats st;
    if (sidx_accel_build("kdtree", &mesh, &knobs, &kd, &err) != SIDX_OK ||
        sidx_accel_build("brute", &mesh, NULL, &ref, &err) != SIDX_OK) {
        fprintf(stderr, "10_kdtree_traversal: %s\n", err.message);
        sidx_accel_destroy(kd);
        sidx_mesh_free(&mesh);
        return 1;
    }
    sidx_accel_stats_get(kd, &st);
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    printf("== '%s': %u triangles; kd-tree of %u nodes, %u leaves, depth %u\n", args.scene, mesh.num_triangles,
           st.nodes, st.leaves, st.max_depth);

    /* Rays across the box in the plane z = centre (for flat2d: the board),
     * from the left edge to the right: the shortest walk that shows the
     * "cannot terminate" case, else the shortest that hits. */
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook rh = sidx_recorder_hook(&rec);
    sidx_ray best_ray;
    int found = 0, have_any = 0;
    size_t best_len = SIZE_MAX, found_len = SIZE_MAX, at = 0;
    uint32_t seed = 5u;
    for (int k = 0; k < 4000; ++k) {
        float f[2];
        for (int j = 0; j < 2; ++j) { seed = seed * 1664525u + 1013904223u; f[j] = (float)(seed >> 8) / 16777216.0f; }
        const sidx_vec3 o = sidx_v3(box.min.x - 0.05f * ext.x, box.min.y + f[0] * ext.y, ctr.z);
        const sidx_vec3 t = sidx_v3(box.max.x, box.min.y + f[1] * ext.y, ctr.z);
        sidx_ray r;
        if (sidx_ray_init(&r, o, sidx_v3_sub(t, o), 0.0f, INFINITY) != SIDX_OK) continue;
        sidx_recorder_clear(&rec);
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &rh, 0};
        sidx_hit h;
        sidx_accel_intersect(kd, &r, &q, &h);
        if (h.prim == SIDX_NO_HIT) continue;
        const size_t len = count_type(&rec, SIDX_EV_NODE_ENTER);
        if (cannot_terminate_case(&rec, &at)) {
            if (len < found_len) { best_ray = r; found_len = len; found = 1; }
        } else if (!found && (!have_any || len < best_len)) {
            best_ray = r;
            best_len = len;
        }
        have_any = 1;
    }
    if (!have_any && !found) {
        fprintf(stderr, "10_kdtree_traversal: no ray across the scene hit anything\n");
        sidx_recorder_free(&rec);
        sidx_accel_destroy(kd);
        sidx_accel_destroy(ref);
        sidx_mesh_free(&mesh);
        return 1;
    }
    const sidx_ray ray = best_ray;
    printf("   ray o = (%g, %g, %g), d = (%g, %g, %g)%s\n", ray.org.x, ray.org.y, ray.org.z, ray.dir.x, ray.dir.y,
           ray.dir.z, found ? "  (it meets a triangle that straddles cells)" : "");

    /* the trace, with Current / Stack after every step */
    sidx_recorder_clear(&rec);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &rh, 0};
    sidx_hit h;
    sidx_accel_intersect(kd, &ray, &q, &h);
    sidx_printer pr;
    sidx_printer_init(&pr, stdout);
    const sidx_hook ph = sidx_printer_hook(&pr);
    typedef struct { uint32_t node; float t0, t1; } entry;
    entry stack[128];
    int sp = 0, consistent = 1, step = 0, cannot = 0, inner = 0, cases_ok = 1;
    uint32_t current = UINT32_MAX;
    float cur_far = INFINITY;
    printf("\n");
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        sidx_hook_emit(&ph, e);
        int show = 0;
        switch (e->type) {
        case SIDX_EV_NODE_ENTER:
            current = e->node;
            cur_far = e->t_far;
            show = 1;
            if (e->axis >= 0) { /* an inner node: t_split and the case it takes, as the slide has them */
                const float tol = 1e-5f * fmaxf(fabsf(e->t_near), fabsf(e->t_far));
                const int both_next = i + 1 < rec.count && rec.events[i + 1].type == SIDX_EV_STACK_PUSH;
                ++inner;
                if (e->result == SIDX_SPLIT_FAR_ONLY) cases_ok &= e->t < e->t_near && !both_next;
                else if (e->result == SIDX_SPLIT_NEAR_ONLY) cases_ok &= e->t > e->t_far && !both_next;
                else cases_ok &= e->result == SIDX_SPLIT_BOTH && both_next &&
                                 (e->t != e->t || (e->t >= e->t_near - tol && e->t <= e->t_far + tol));
            }
            break;
        case SIDX_EV_STACK_PUSH:
            if (sp < 128) stack[sp++] = (entry){e->node, e->t_near, e->t_far};
            if ((int)e->depth != sp) consistent = 0;
            break;
        case SIDX_EV_STACK_POP:
            if (sp == 0 || stack[sp - 1].node != e->node || (int)e->depth != sp) consistent = 0;
            if (sp > 0) --sp;
            current = UINT32_MAX;
            show = 1;
            break;
        case SIDX_EV_HIT_UPDATE:
            if (e->t > cur_far * 1.0001f) {
                printf("      ^ the hit (t=%g) lies beyond this cell (t_far=%g): CANNOT terminate !!!\n", e->t, cur_far);
                cannot = 1;
            }
            break;
        default: break;
        }
        if (show) {
            ++step;
            printf("      [step %d]  Current: ", step);
            if (current == UINT32_MAX) printf("(popped, next step enters it)");
            else printf("node %u", current);
            printf("   Stack:");
            if (sp == 0) printf(" (empty)");
            for (int k = sp - 1; k >= 0; --k) printf(" %u[%g,%g]", stack[k].node, stack[k].t0, stack[k].t1);
            printf("\n");
        }
    }
    sidx_hit hb;
    sidx_accel_intersect(ref, &ray, NULL, &hb);
    printf("\n  kd-tree: prim %u t=%g; brute force: prim %u t=%g\n", h.prim, h.t, hb.prim, hb.t);
    printf("  The stack holds only (node, t_near, t_far) of the far children still to visit, nearest on\n"
           "  top.  A hit ends the walk only if it lies inside the current cell (t <= t_far): a\n"
           "  triangle reaching into a later cell may hide a closer one still unvisited.\n");
    lesson_check("same_hit", h.t == hb.t);
    lesson_check("stack_trace_consistent", consistent);
    lesson_check("cannot_terminate_seen", cannot && found);
    lesson_check("split_cases_shown", inner > 0 && cases_ok);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(kd);
    sidx_accel_destroy(ref);
    sidx_mesh_free(&mesh);
    return 0;
}
