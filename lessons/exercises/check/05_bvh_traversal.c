/* 05_bvh_traversal.c — checker driver: the naive BVH walk, then the
 * ordered one (deck 001, "BVH Traversal" and "Better BVH Traversal").
 * Reference: the library's own recursive walks (q.traversal NAIVE and
 * ORDERED) over a "bvh" built with the textbook slab test, whose events
 * are the slide's steps one for one. */
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "sidx/bvh.h"

void bvh_hit_naive(const sidx_ex *ex, const sidx_bvh_node *nodes, const uint32_t *prims, uint32_t node,
                   uint32_t depth, sidx_hit *best);
void bvh_hit_ordered(const sidx_ex *ex, const sidx_bvh_node *nodes, const uint32_t *prims, uint32_t node,
                     uint32_t depth, float t_near, float t_far, sidx_hit *best);

#define NSCENES 3
#define RAYS 40
static const char *const scene_names[NSCENES] = {"flat2d", "soup:200", "cornell"};
static sidx_mesh meshes[NSCENES];
static sidx_accel *accels[NSCENES];
static sidx_ray rays[NSCENES][RAYS];
static const char *ray_kind[NSCENES][RAYS];

static int setup(void)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.box = SIDX_BOX_PLAIN;
    for (int s = 0; s < NSCENES; ++s) {
        if (sidx_scene_open(scene_names[s], &meshes[s], NULL) != SIDX_OK) return -1;
        if (sidx_accel_build("bvh", &meshes[s], &bo, &accels[s], NULL) != SIDX_OK) return -1;
        const sidx_aabb b = sidx_mesh_bounds(&meshes[s]);
        const sidx_vec3 c = sidx_aabb_centroid(b), e = sidx_aabb_extent(b);
        uint32_t st = 99u + (uint32_t)s;
        for (int i = 0; i < RAYS; ++i) {
            const float u = ex_rand(&st), v = ex_rand(&st), w = ex_rand(&st);
            const sidx_vec3 p = sidx_v3(b.min.x + u * e.x, b.min.y + v * e.y, b.min.z + w * e.z);
            sidx_vec3 o, d;
            if (i < 12) { /* the slide's view: from the front, towards the scene */
                o = sidx_v3(p.x, p.y, b.max.z + e.z + 1.0f);
                d = sidx_v3((ex_rand(&st) - 0.5f) * 0.2f, (ex_rand(&st) - 0.5f) * 0.2f, -1.0f);
                ray_kind[s][i] = "from the front";
            } else if (i < 24) { /* across the scene, through many overlapping boxes */
                const float a = ex_rand(&st) * 6.2831853f;
                o = sidx_v3(c.x + cosf(a) * e.x, c.y + sinf(a) * e.y, p.z);
                d = sidx_v3_sub(p, o);
                ray_kind[s][i] = "across the scene";
            } else if (i < 32) { /* starting inside the scene box */
                o = p;
                d = sidx_v3(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f);
                ray_kind[s][i] = "starting inside";
            } else if (i < 36) { /* missing everything */
                o = sidx_v3(b.max.x + 1.0f, b.max.y + 1.0f, b.max.z + 1.0f);
                d = sidx_v3(ex_rand(&st) + 0.1f, ex_rand(&st), ex_rand(&st));
                ray_kind[s][i] = "missing the root box";
            } else { /* random, with tmax cutting the scene */
                o = sidx_v3(c.x - e.x, p.y, p.z);
                d = sidx_v3(1.0f, (ex_rand(&st) - 0.5f) * 0.3f, (ex_rand(&st) - 0.5f) * 0.3f);
                ray_kind[s][i] = "with a finite tmax";
            }
            if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) d.x = 1.0f;
            rays[s][i] = ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0, i >= 36 ? e.x : INFINITY);
        }
    }
    return 0;
}

static void teardown(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        sidx_accel_destroy(accels[s]);
        sidx_mesh_free(&meshes[s]);
    }
}

#define PER_PART (NSCENES * RAYS)
static size_t num_cases(void) { return 2 * PER_PART; }

static void split(size_t i, int *ordered, int *s, int *r)
{
    *ordered = i >= PER_PART;
    i %= PER_PART;
    *s = (int)(i / RAYS);
    *r = (int)(i % RAYS);
}

#define HINT_BOX_BEST                                                                                      \
    "\"if (hit.prim == NULL || hit.t > best.t) return\": test the box over [ray.tmin, best.t], so a box that " \
    "begins behind the best hit so far is a miss"
#define HINT_NAIVE_ORDER                                                                                   \
    "test the node's box first; a leaf then tests its primitives prims[first .. first + count), an inner "  \
    "node traverses BOTH children, child1 (node + 1) before child2 (left_or_first)"
#define HINT_NEARER                                                                                        \
    "\"pick node with better time\": test both children's boxes, then visit first the one the ray enters "  \
    "first (smaller t_near; on a tie child1)"
#define HINT_TIE                                                                                           \
    "the two children's boxes begin at the same t_near: on a tie child1 (node + 1) goes first; only a "     \
    "strictly smaller t_near puts child2 first"
#define HINT_FAR                                                                                           \
    "\"Only check far bbox if closest primitive in the near bbox is farther than the closest point "        \
    "intersected in the far bbox\": visit the second child only if its box was hit and its t_near < best.t"
#define HINT_UPDATE                                                                                        \
    "\"if (hit.prim != NULL && hit.t < best.t)\": a closer hit replaces best (prim and t) and is reported "  \
    "with sidx_ex_hit_update"
#define HINT_PRIMS                                                                                         \
    "test each primitive of the leaf against the best hit so far: sidx_ex_test_triangle(ex, prim, best->t, " \
    "&t), with best->t as its tmax"
#define HINT_LEAF_IDS                                                                                      \
    "a leaf holds the triangles prims[first .. first + count), first = left_or_first: the triangle ids are " \
    "prims[i], not the positions i themselves"
#define HINT_INTERVAL                                                                                      \
    "the same child entered with another interval: \"pick node with better time\" uses the times its box "  \
    "test gave, so enter each child over (t_near, t_far) of that test, hit(child, t_near, t_far)"

/* The hand-out's promises (lessons/exercises/05_bvh_traversal.c). */
static const ex_rule rules[] = {
    {"box-over-best", "the naive walk tests a node's box over [ray tmin, best->t] and returns on a miss",
     HINT_BOX_BEST},
    {"naive-both-children", "the naive walk enters the node, then traverses both children, child1 before child2",
     HINT_NAIVE_ORDER},
    {"leaf-prims", "a leaf tests the triangles prims[first .. first + count)", HINT_LEAF_IDS},
    {"leaf-bound", "each triangle is tested against the best hit so far (tmax = best->t)", HINT_PRIMS},
    {"hit-update", "a closer hit updates best->prim and best->t and is reported with sidx_ex_hit_update",
     HINT_UPDATE},
    {"nearer-first", "the ordered walk tests both children's boxes and visits first the one entered first",
     HINT_NEARER},
    {"tie-child1", "of two children entered at the same t_near, child1 goes first", HINT_TIE},
    {"far-cull", "the second child is visited only if its box was hit and its t_near < best->t", HINT_FAR},
    {"child-interval", "each child is entered over the [t_near, t_far] its own box test gave", HINT_INTERVAL},
};
enum { R_BOX_BEST, R_NAIVE, R_LEAF_IDS, R_PRIMS, R_UPDATE, R_NEARER, R_TIE, R_FAR, R_INTERVAL };

static const char *const hint_box_best = HINT_BOX_BEST;
static const char *const hint_naive_order = HINT_NAIVE_ORDER;
static const char *const hint_nearer = HINT_NEARER;
static const char *const hint_far = HINT_FAR;
static const char *const hint_update = HINT_UPDATE;
static const char *const hint_prims = HINT_PRIMS;
static const char *const hint_interval = HINT_INTERVAL;

static void reference(size_t i, const sidx_hook *h);

/* 1 if the reference's walk of case i meets two children whose boxes the
 * ray enters at the same t_near (the order's tie). */
static int has_tie(size_t i)
{
    ex_trace rec = {NULL, 0, 0};
    const sidx_hook h = {ex_trace_hook_fn, &rec, SIDX_EVMASK(SIDX_EV_BOX_TEST)};
    reference(i, &h);
    int tie = 0;
    /* after the root's, the ordered walk tests boxes in pairs: child1, then child2 */
    for (size_t k = 1; k + 1 < rec.n && !tie; k += 2)
        tie = rec.ev[k].result == 1 && rec.ev[k + 1].result == 1 && rec.ev[k].t_near == rec.ev[k + 1].t_near;
    free(rec.ev);
    return tie;
}

static void describe(size_t i, ex_case_info *out)
{
    int ordered, s, r;
    split(i, &ordered, &s, &r);
    snprintf(out->name, sizeof out->name, "%s walk, scene %s, ray %d (%s)", ordered ? "ordered" : "naive",
             scene_names[s], r + 1, ray_kind[s][r]);
    ex_describe_walk(out, &rays[s][r], "bvh", NULL, scene_names[s], &meshes[s]);
    out->rules = !ordered    ? "box-over-best naive-both-children leaf-prims leaf-bound hit-update"
                 : has_tie(i) ? "nearer-first tie-child1 far-cull child-interval leaf-prims leaf-bound hit-update"
                              : "nearer-first far-cull child-interval leaf-prims leaf-bound hit-update";
}

static void reference(size_t i, const sidx_hook *h)
{
    int ordered, s, r;
    split(i, &ordered, &s, &r);
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.traversal = ordered ? SIDX_TRAVERSE_ORDERED : SIDX_TRAVERSE_NAIVE;
    q.hook = h;
    sidx_hit hit;
    sidx_accel_intersect(accels[s], &rays[s][r], &q, &hit);
}

/* Counts the student's NODE_ENTER events (TERMINATE's count) on the way
 * to the runner's hook. */
typedef struct counting {
    const sidx_hook *inner;
    uint32_t entered;
} counting;

static void counting_fn(const sidx_event *ev, void *user)
{
    counting *c = user;
    if (ev->type == SIDX_EV_NODE_ENTER) ++c->entered;
    sidx_hook_emit(c->inner, ev);
}

/* 1 if the ray of case i enters the boxes of nodes a and b at the same
 * t_near (two siblings the walk orders). */
static int sibling_tie(size_t i, uint32_t a, uint32_t b)
{
    int ordered, s, r;
    split(i, &ordered, &s, &r);
    const sidx_bvh_node *nodes = NULL;
    uint32_t nn = 0;
    sidx_bvh_nodes(accels[s], &nodes, &nn, NULL);
    if (a >= nn || b >= nn) return 0;
    const sidx_aabb ba = sidx_bvh_box(&nodes[a]), bb = sidx_bvh_box(&nodes[b]);
    float na, fa, nb, fb;
    const sidx_ray *ray = &rays[s][r];
    return sidx_intersect_aabb(SIDX_BOX_PLAIN, ray, &ba, ray->tmin, INFINITY, &na, &fa) &&
           sidx_intersect_aabb(SIDX_BOX_PLAIN, ray, &bb, ray->tmin, INFINITY, &nb, &fb) && na == nb;
}

/* What differs decides: the same box tested over another interval is the
 * culling by best.t; a hit update, or another primitive step, is the
 * leaf (another triangle: the ids through prims[]); in the ordered walk
 * the same child entered with another interval is the box test's
 * interval, another child at the same depth is the near-first order (the
 * tie rule when both boxes begin at the same t_near), and a child entered or skipped is the far-child rule;
 * in the naive walk anything else is its order. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const int ordered = i >= PER_PART;
    if (ref && stu && ref->type == SIDX_EV_BOX_TEST && stu->type == SIDX_EV_BOX_TEST && ref->node == stu->node)
        return hint_box_best;
    if (ref && stu && ref->type == SIDX_EV_HIT_UPDATE) return hint_update;
    if (stu && stu->type == SIDX_EV_HIT_UPDATE) return hint_update;
    if (ref && stu && ref->type == SIDX_EV_PRIM_TEST && stu->type == SIDX_EV_PRIM_TEST)
        return ref->prim != stu->prim ? rules[R_LEAF_IDS].hint : hint_prims;
    if (ordered) {
        if (ref && stu && ref->type == SIDX_EV_NODE_ENTER && stu->type == SIDX_EV_NODE_ENTER &&
            ref->node == stu->node)
            return hint_interval;
        if (ref && stu && ref->type == SIDX_EV_NODE_ENTER && stu->type == SIDX_EV_NODE_ENTER &&
            ref->depth == stu->depth)
            return sibling_tie(i, ref->node, stu->node) ? rules[R_TIE].hint : hint_nearer;
        if ((stu && stu->type == SIDX_EV_NODE_ENTER) || (ref && ref->type == SIDX_EV_NODE_ENTER)) return hint_far;
        return hint_nearer;
    }
    return hint_naive_order;
}

/* What the library's query does around the walk: RAY_BEGIN, the walk
 * (the ordered one after the root's box test: the slide's better hit()
 * is called on a node whose box its caller tested), TERMINATE, RAY_END. */
static void student(size_t i, const sidx_hook *h)
{
    int ordered, s, r;
    split(i, &ordered, &s, &r);
    const sidx_ray *ray = &rays[s][r];
    const sidx_bvh_node *nodes = NULL;
    const uint32_t *prims = NULL;
    uint32_t nn = 0, np = 0;
    sidx_bvh_nodes(accels[s], &nodes, &nn, NULL);
    sidx_bvh_prims(accels[s], &prims, &np, NULL);
    counting c = {h, 0};
    const sidx_hook ch = {counting_fn, &c, 0};
    sidx_ex ex;
    sidx_hit best;
    ex_walk_begin(&ex, &ch, h, "bvh", ray, &meshes[s], SIDX_TRI_WATERTIGHT, SIDX_BOX_PLAIN, &best);
    int missed_root = 0;
    if (ordered) {
        const sidx_aabb root = sidx_bvh_box(&nodes[0]);
        float tn, tf;
        if (sidx_ex_test_box(&ex, 0, &root, ray->tmin, best.t, &tn, &tf))
            bvh_hit_ordered(&ex, nodes, prims, 0, 0, tn, tf, &best);
        else
            missed_root = 1;
    } else {
        bvh_hit_naive(&ex, nodes, prims, 0, 0, &best);
        missed_root = c.entered == 0;
    }
    sidx_event e = sidx_event_blank(SIDX_EV_TERMINATE);
    e.structure = "bvh";
    e.reason = missed_root ? SIDX_TERM_MISS_ROOT : SIDX_TERM_STACK_EMPTY;
    e.t = best.t;
    e.count = c.entered;
    sidx_hook_emit(h, &e);
    ex_walk_end(h, "bvh", &best);
}

const ex_driver ex_driver_this = {
    "05_bvh_traversal",
    "BVH traversal: the naive recursive walk, then the ordered one",
    "deck 001, \"BVH Traversal\" and \"Better BVH Traversal\"; deck 000, \"BVH traversal (1)-(3)\"",
    setup, num_cases, describe, reference, student, hint, teardown, NULL, rules, sizeof rules / sizeof rules[0],
};
