/* 19_instancing.c — aggregate objects and instancing.
 *
 * Slides (deck 000, "Spatial Index Structures"): "Aggregate Objects"
 * ("Object that holds groups of objects — conceptually stores bounding
 * volume (e.g. box) & a list of children — useful for instancing (placing
 * collection of objects repeatedly) & for Bounding Volume Hierarchies") and
 * "Bounding Volume Hierarchies (BVHs)" ("All nodes are aggregate objects —
 * usually every object appears once in the tree — except in case of
 * instancing").
 *
 * A field of K x K copies of one object (default: the teapot), each turned
 * and scaled its own way, built two ways: as instances of ONE BVH over the
 * object (sidx/instance.h: sidx_aggregate_build over K*K transforms), and
 * flattened — every copy's triangles written out into one big mesh under
 * one big BVH.  What it shows:
 *   1. one ray through the aggregate: its top-level BVH over the copies'
 *      boxes, the ray carried into an instance's space by the inverse
 *      transform, the object's own BVH walked there;
 *   2. memory and build time, instanced against flattened;
 *   3. per ray: node visits, box and triangle tests, time — and the hits,
 *      compared: same copy, same triangle, same t (to float rounding: the
 *      instanced ray is transformed, the flattened triangles are);
 *   4. nesting: K rows, each an aggregate of K copies, placed by a top
 *      aggregate — an aggregate is itself an object to place; same hits.
 *
 * Read:  lib/instance.c, agg_walk
 * Run:   build/lessons/19_instancing [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "lesson.h"
#include "sidx/instance.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 19_instancing [--help] [build knobs] [SCENE]\n"
               "\n"
               "Aggregates and instancing: a field of copies of SCENE as instances of one BVH against\n"
               "the same field flattened into one mesh — memory, build time, work and hits per ray —\n"
               "and an aggregate of aggregates.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "The knobs below change the instanced object's BVH and the flattened field's BVH\n"
               "alike; the aggregates over the instances keep one instance per leaf.  The checks\n"
               "hold for the defaults.\n");
}

#define K 10 /* K x K copies */
#define NRAYS 20000
static sidx_ray rays[NRAYS];
static sidx_hit h_inst[NRAYS], h_flat[NRAYS], h_nest[NRAYS];

/* Copy (row, col): turned about y, scaled, set on a grid of spacing `step`;
 * row-major 3x4, world = M[:, 0..2] p + M[:, 3]. */
static void placement(int row, int col, float step, sidx_vec3 c, int local, float m[12])
{
    uint32_t seed = (uint32_t)(row * K + col) * 2654435761u + 7u;
    const float ang = 6.2831853f * lesson_random(&seed), s = 0.6f + 0.6f * lesson_random(&seed);
    const float ca = cosf(ang) * s, sa = sinf(ang) * s;
    /* turn and scale about the object's centre c, then move to the grid point */
    const float x = step * (float)col, z = local ? 0.0f : step * (float)row;
    const float r[9] = {ca, 0, sa, 0, s, 0, -sa, 0, ca};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) m[4 * i + j] = r[3 * i + j];
        m[4 * i + 3] = -(r[3 * i] * c.x + r[3 * i + 1] * c.y + r[3 * i + 2] * c.z);
    }
    m[3] += x;
    m[11] += z;
}

static sidx_vec3 apply(const float m[12], sidx_vec3 p)
{
    return sidx_v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                   m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

/* Two hits agree: both miss, or the same copy and triangle at t equal to
 * within 1e-4 relative; *other counts a different triangle at that t (an
 * edge two triangles share). */
static int agree(const sidx_hit *a, const sidx_hit *b, int *other)
{
    if (a->prim == SIDX_NO_HIT || b->prim == SIDX_NO_HIT) return a->prim == b->prim;
    if (fabsf(a->t - b->t) > 1e-4f * fabsf(a->t)) return 0;
    if (a->prim != b->prim || a->instance != b->instance) ++*other;
    return 1;
}

/* Trace of one ray: the aggregate's own steps, and a summary of each
 * walk inside an instance (the object's BVH, in the copy's space). */
typedef struct {
    int inside;
    uint32_t copy;
    uint64_t nodes, tris;
    uint32_t prim;
    float t;
} ray_trace;

static void flush_inside(ray_trace *t)
{
    if (!t->inside) return;
    printf("      inside copy %u: %llu nodes, %llu triangle tests", t->copy, (unsigned long long)t->nodes,
           (unsigned long long)t->tris);
    if (t->prim != SIDX_NO_HIT) printf(", closest hit so far: triangle %u at t = %g", t->prim, t->t);
    if (t->nodes == 0) printf("\n      (the object's root box missed: a turned copy's world box is looser)");
    printf("\n");
    t->inside = 0;
}

static void trace_fn(const sidx_event *ev, void *user)
{
    ray_trace *t = user;
    const int agg = ev->structure && !strcmp(ev->structure, "aggregate");
    if (!agg) { /* the object's BVH, inside a copy */
        t->nodes += ev->type == SIDX_EV_NODE_ENTER;
        t->tris += ev->type == SIDX_EV_PRIM_TEST;
        if (ev->type == SIDX_EV_HIT_UPDATE) t->prim = ev->prim, t->t = ev->t;
        return;
    }
    if (ev->type == SIDX_EV_NODE_ENTER) {
        flush_inside(t);
        printf("  aggregate node %u enter, t_near = %g\n", ev->node, ev->t_near);
    } else if (ev->type == SIDX_EV_NOTE) {
        flush_inside(t);
        printf("  aggregate leaf: the ray, carried by the inverse transform, enters copy %u\n", ev->count);
        *t = (ray_trace){1, ev->count, 0, 0, SIDX_NO_HIT, INFINITY};
    } else if (ev->type == SIDX_EV_RAY_END) {
        flush_inside(t);
        printf("  aggregate end: %s\n", ev->prim != SIDX_NO_HIT ? "hit" : "miss");
    }
}

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_BVH_KNOBS(knobs), {0}};
    lesson_args args = {.name = "19_instancing",
                        .usage = usage,
                        .scene = "teapot",
                        .options = options,
                        .refused = LESSON_BVH_ONLY};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "bvh");
    sidx_mesh obj = lesson_open_scene(&args);
    sidx_error err = {0};
    const sidx_aabb ob = sidx_mesh_bounds(&obj);
    const sidx_vec3 c = sidx_aabb_centroid(ob);
    const float step = 1.3f * sidx_v3_length(sidx_aabb_extent(ob));

    /* ---- the instanced field ---- */
    double t0 = lesson_seconds();
    sidx_accel *child = NULL, *field = NULL;
    if (sidx_accel_build("bvh", &obj, &knobs, &child, &err) != SIDX_OK) lesson_fail(&args, err.message);
    sidx_instance *inst = malloc(K * K * sizeof *inst);
    if (!inst) lesson_fail(&args, "out of memory");
    for (int r = 0; r < K; ++r)
        for (int q = 0; q < K; ++q) {
            inst[r * K + q].accel = child;
            placement(r, q, step, c, 0, inst[r * K + q].xform);
        }
    if (sidx_aggregate_build(inst, K * K, NULL, &field, &err) != SIDX_OK) lesson_fail(&args, err.message);
    const double build_inst = lesson_seconds() - t0;

    /* ---- the flattened field ---- */
    t0 = lesson_seconds();
    const uint32_t nv = obj.num_vertices, nt = obj.num_triangles;
    float *xyz = malloc((size_t)K * K * nv * 3 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)K * K * nt * 3 * sizeof *idx);
    if (!xyz || !idx) lesson_fail(&args, "out of memory");
    for (uint32_t i = 0; i < K * K; ++i) {
        for (uint32_t v = 0; v < nv; ++v) {
            const sidx_vec3 p = apply(inst[i].xform, obj.positions[v]);
            float *o = &xyz[3 * ((size_t)i * nv + v)];
            o[0] = p.x, o[1] = p.y, o[2] = p.z;
        }
        for (uint32_t k = 0; k < 3 * nt; ++k) idx[(size_t)i * 3 * nt + k] = obj.indices[k] + i * nv;
    }
    sidx_mesh flat;
    memset(&flat, 0, sizeof flat);
    if (sidx_mesh_from_arrays(&flat, xyz, K * K * nv, idx, K * K * nt, &err) != SIDX_OK) lesson_fail(&args, err.message);
    free(xyz);
    free(idx);
    sidx_accel *big = NULL;
    if (sidx_accel_build("bvh", &flat, &knobs, &big, &err) != SIDX_OK) lesson_fail(&args, err.message);
    const double build_flat = lesson_seconds() - t0;

    printf("== A field of %d x %d copies of '%s' (%u triangles each): %llu triangles in the world\n", K, K, args.scene, nt,
           (unsigned long long)K * K * nt);

    /* rays from all around into the field's box (most pass over the flat field) */
    const sidx_aabb world = sidx_mesh_bounds(&flat);
    lesson_rays_into_box(world, rays, NRAYS, 19u);

    /* ---- 1 ---- */
    int pick = 0;
    for (int i = 0; i < NRAYS; ++i) {
        sidx_hit h;
        sidx_accel_intersect(field, &rays[i], NULL, &h);
        sidx_counters cc;
        lesson_count_rays(field, &rays[i], 1, &cc, NULL);
        if (h.prim != SIDX_NO_HIT && cc.n[SIDX_EV_NOTE] >= 2 && cc.n[SIDX_EV_NOTE] <= 3) { pick = i; break; }
    }
    printf("\n== 1. One ray through the aggregate: its own steps, and the object's BVH inside each copy\n");
    ray_trace rt = {0, 0, 0, 0, SIDX_NO_HIT, INFINITY};
    const sidx_hook th = {trace_fn, &rt, 0};
    const sidx_query q1 = {0, SIDX_TRAVERSE_DEFAULT, &th, 0};
    sidx_hit h1;
    sidx_accel_intersect(field, &rays[pick], &q1, &h1);
    printf("  the hit: copy %u, triangle %u of the object, t = %g\n", h1.instance, h1.prim, h1.t);

    /* ---- 2 ---- */
    sidx_aggregate_info ai;
    sidx_aggregate_info_get(field, &ai);
    sidx_accel_stats sf;
    sidx_accel_stats_get(big, &sf);
    const size_t obj_mesh = (size_t)nv * sizeof(sidx_vec3) + (size_t)nt * 3 * sizeof(uint32_t);
    const size_t flat_mesh = (size_t)flat.num_vertices * sizeof(sidx_vec3) + (size_t)flat.num_triangles * 3 * sizeof(uint32_t);
    const double mem_inst = (double)(ai.own_bytes + ai.shared_bytes + obj_mesh), mem_flat = (double)(sf.bytes + flat_mesh);
    printf("\n== 2. Memory and build time\n");
    printf("  %-12s %12s %12s %12s %10s\n", "", "structure", "mesh", "total KiB", "build ms");
    printf("  %-12s %12.1f %12.1f %12.1f %10.2f\n", "instanced", (ai.own_bytes + ai.shared_bytes) / 1024.0,
           obj_mesh / 1024.0, mem_inst / 1024.0, 1e3 * build_inst);
    printf("  %-12s %12.1f %12.1f %12.1f %10.2f\n", "flattened", sf.bytes / 1024.0, flat_mesh / 1024.0,
           mem_flat / 1024.0, 1e3 * build_flat);
    printf("  instanced = one object BVH (%.1f KiB, shared by all %u copies) + %.1f KiB of the aggregate's\n"
           "  own: %u transforms and their inverses, and a BVH over %u boxes.  %.0fx less memory.\n",
           ai.shared_bytes / 1024.0, ai.instances, ai.own_bytes / 1024.0, ai.instances, ai.instances,
           mem_flat / mem_inst);

    /* ---- 3 ---- */
    printf("\n== 3. Per ray (%d random rays into the field)\n", NRAYS);
    sidx_counters ci, cf;
    lesson_count_rays(field, rays, NRAYS, &ci, h_inst);
    lesson_count_rays(big, rays, NRAYS, &cf, h_flat);
    const double us_i = lesson_us_per_ray(field, rays, NRAYS, 3), us_f = lesson_us_per_ray(big, rays, NRAYS, 3);
    printf("  %-12s %10s %10s %10s %12s %10s\n", "", "nodes", "box tests", "tri tests", "instances", "us/ray");
    printf("  %-12s %10.2f %10.2f %10.2f %12.2f %10.3f\n", "instanced", (double)ci.n[SIDX_EV_NODE_ENTER] / NRAYS,
           (double)ci.n[SIDX_EV_BOX_TEST] / NRAYS, (double)ci.n[SIDX_EV_PRIM_TEST] / NRAYS,
           (double)ci.n[SIDX_EV_NOTE] / NRAYS, us_i);
    printf("  %-12s %10.2f %10.2f %10.2f %12s %10.3f\n", "flattened", (double)cf.n[SIDX_EV_NODE_ENTER] / NRAYS,
           (double)cf.n[SIDX_EV_BOX_TEST] / NRAYS, (double)cf.n[SIDX_EV_PRIM_TEST] / NRAYS, "-", us_f);
    int bad = 0, other = 0;
    long hit_rays = 0;
    for (int i = 0; i < NRAYS; ++i) {
        sidx_hit f = h_flat[i];
        if (f.prim != SIDX_NO_HIT) {
            f.instance = f.prim / nt;
            f.prim %= nt;
            ++hit_rays;
        }
        bad += !agree(&h_inst[i], &f, &other);
    }
    printf("  instances = copies a ray entered (its box hit by the ray): the top-level BVH's boxes around\n"
           "  turned copies are looser than the flattened tree's boxes around triangles, so a ray\n"
           "  enters several copies and does more work — the price of sharing one object BVH.\n");
    printf("  Hits: %ld of %d rays hit; %d disagree (copy, triangle, t to 1e-4), %d name another\n"
           "  triangle at the same t (a shared edge).\n",
           hit_rays, NRAYS, bad, other);

    /* ---- 4 ---- */
    printf("\n== 4. An aggregate of aggregates: %d rows of %d copies, each row an aggregate\n", K, K);
    sidx_accel *rows[K];
    sidx_instance row_inst[K];
    for (int r = 0; r < K; ++r) {
        sidx_instance local[K];
        for (int q2 = 0; q2 < K; ++q2) {
            local[q2].accel = child;
            placement(r, q2, step, c, 1, local[q2].xform);
        }
        if (sidx_aggregate_build(local, K, NULL, &rows[r], &err) != SIDX_OK) lesson_fail(&args, err.message);
        const float m[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, step * (float)r};
        row_inst[r].accel = rows[r];
        memcpy(row_inst[r].xform, m, sizeof m);
    }
    sidx_accel *nested = NULL;
    if (sidx_aggregate_build(row_inst, K, NULL, &nested, &err) != SIDX_OK) lesson_fail(&args, err.message);
    sidx_aggregate_info ni;
    sidx_aggregate_info_get(nested, &ni);
    sidx_counters cn;
    lesson_count_rays(nested, rays, NRAYS, &cn, h_nest);
    int bad_nest = 0, other_nest = 0;
    for (int i = 0; i < NRAYS; ++i) bad_nest += !agree(&h_nest[i], &h_inst[i], &other_nest);
    printf("  top: %u instances (the rows), %u leaf instances numbered depth first (row r, copy q -> %d r + q)\n"
           "  %.2f nodes and %.2f triangle tests per ray (flat aggregate: %.2f, %.2f).  Hits against the flat\n"
           "  aggregate: %d disagree, %d on a shared edge.\n",
           ni.instances, ni.leaf_instances, K, (double)cn.n[SIDX_EV_NODE_ENTER] / NRAYS,
           (double)cn.n[SIDX_EV_PRIM_TEST] / NRAYS, (double)ci.n[SIDX_EV_NODE_ENTER] / NRAYS,
           (double)ci.n[SIDX_EV_PRIM_TEST] / NRAYS, bad_nest, other_nest);

    sidx_accel_destroy(nested);
    for (int r = 0; r < K; ++r) sidx_accel_destroy(rows[r]);
    sidx_accel_destroy(big);
    sidx_mesh_free(&flat);
    sidx_accel_destroy(field);
    sidx_accel_destroy(child);
    free(inst);
    sidx_mesh_free(&obj);
    lesson_check("hits_agree", bad == 0 && hit_rays > 0);
    lesson_check("nested_hits_agree", bad_nest == 0 && ni.leaf_instances == K * K);
    lesson_check("one_shared_child", ai.distinct_children == 1 && ai.world_triangles == (uint64_t)K * K * nt);
    lesson_check("instancing_saves_memory", mem_inst < mem_flat);
    return 0;
}
