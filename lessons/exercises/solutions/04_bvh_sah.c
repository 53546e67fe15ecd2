/* Reference solution of 04_bvh_sah (deck 001, "Surface Area Heuristic",
 * "Building Partitions"). */
#include <stdlib.h>
#include "sidx/sidx.h"
#include "sidx/exercise.h"

/* C = C_trav + (A_L·N_L + A_R·N_R)·C_tri / A, from the areas. */
static float cost_of(float al, uint32_t nl, float ar, uint32_t nr, float area, float c_trav, float c_tri)
{
    return c_trav + c_tri * (al * (float)nl + ar * (float)nr) * (1.0f / area);
}

float sah_cost(sidx_aabb parent, sidx_aabb left, uint32_t n_left, sidx_aabb right, uint32_t n_right, float c_trav,
               float c_tri)
{
    return cost_of(sidx_aabb_area(left), n_left, sidx_aabb_area(right), n_right, sidx_aabb_area(parent), c_trav,
                   c_tri);
}

typedef struct key {
    float c;
    uint32_t id;
} key;

static int key_cmp(const void *pa, const void *pb)
{
    const key *x = pa, *y = pb;
    if (x->c != y->c) return x->c < y->c ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

/* The cheapest candidate so far ("if (cost < best_cost)"). */
typedef struct best_split {
    float cost, pos;
    int axis;
    uint32_t nl;
} best_split;

/* Reports a candidate and keeps it if strictly cheaper. */
static void candidate(const sidx_ex *ex, uint32_t node, best_split *b, int axis, float pos, float cost, uint32_t nl,
                      uint32_t count)
{
    sidx_ex_candidate(ex, node, axis, pos, cost, nl, count - nl);
    if (cost < b->cost) {
        b->cost = cost;
        b->axis = axis;
        b->pos = pos;
        b->nl = nl;
    }
}

static void node_bounds(const uint32_t *prims, uint32_t count, const sidx_aabb *boxes, const sidx_vec3 *cents,
                        sidx_aabb *bb, sidx_aabb *cb)
{
    *bb = sidx_aabb_empty();
    *cb = sidx_aabb_empty();
    for (uint32_t i = 0; i < count; ++i) {
        *bb = sidx_aabb_union(*bb, boxes[prims[i]]);
        *cb = sidx_aabb_grow(*cb, cents[prims[i]]);
    }
}

void split_sweep(const sidx_ex *ex, uint32_t node, const uint32_t *prims, uint32_t count, const sidx_aabb *boxes,
                 const sidx_vec3 *cents, uint32_t step, float c_trav, float c_tri)
{
    sidx_aabb bb, cb;
    node_bounds(prims, count, boxes, cents, &bb, &cb);
    if (step > count / 2) step = count / 2;
    if (step < 1) step = 1;
    key *k = malloc(count * sizeof *k);
    float *right = malloc(count * sizeof *right);
    best_split best = {INFINITY, 0, -1, 0};
    for (int axis = 0; axis < 3 && k && right; ++axis) {
        if (!(sidx_v3_get(cb.max, axis) > sidx_v3_get(cb.min, axis))) continue;
        for (uint32_t i = 0; i < count; ++i) {
            k[i].c = sidx_v3_get(cents[prims[i]], axis);
            k[i].id = prims[i];
        }
        qsort(k, count, sizeof *k, key_cmp);
        sidx_aabb acc = sidx_aabb_empty();
        for (uint32_t i = count - 1; i >= 1; --i) {
            acc = sidx_aabb_union(acc, boxes[k[i].id]);
            right[i] = sidx_aabb_area(acc);
        }
        acc = sidx_aabb_empty();
        for (uint32_t i = 1; i < count; ++i) {
            acc = sidx_aabb_union(acc, boxes[k[i - 1].id]);
            if (i % step) continue;
            const float cost = cost_of(sidx_aabb_area(acc), i, right[i], count - i, sidx_aabb_area(bb), c_trav, c_tri);
            const float pos = 0.5f * (k[i - 1].c + k[i].c);
            candidate(ex, node, &best, axis, pos, cost, i, count);
        }
    }
    if (best.axis >= 0) sidx_ex_split(ex, node, best.axis, best.pos, best.cost, best.nl, count - best.nl);
    free(k);
    free(right);
}

void split_binned(const sidx_ex *ex, uint32_t node, const uint32_t *prims, uint32_t count, const sidx_aabb *boxes,
                  const sidx_vec3 *cents, uint32_t bins, float c_trav, float c_tri)
{
    sidx_aabb bb, cb;
    node_bounds(prims, count, boxes, cents, &bb, &cb);
    sidx_aabb *bin = malloc(bins * sizeof *bin);
    uint32_t *n = malloc(bins * sizeof *n);
    best_split best = {INFINITY, 0, -1, 0};
    for (int axis = 0; axis < 3 && bin && n; ++axis) {
        const float cmin = sidx_v3_get(cb.min, axis), ext = sidx_v3_get(cb.max, axis) - cmin;
        if (!(ext > 0.0f)) continue;
        const float scale = (float)bins / ext;
        for (uint32_t j = 0; j < bins; ++j) {
            bin[j] = sidx_aabb_empty();
            n[j] = 0;
        }
        for (uint32_t i = 0; i < count; ++i) {
            const float f = (sidx_v3_get(cents[prims[i]], axis) - cmin) * scale;
            const uint32_t j = !(f > 0.0f) ? 0u : f >= (float)bins ? bins - 1 : (uint32_t)f;
            bin[j] = sidx_aabb_union(bin[j], boxes[prims[i]]);
            n[j]++;
        }
        for (uint32_t j = 1; j < bins; ++j) { /* plane j: bins 0 .. j-1 left */
            sidx_aabb a = sidx_aabb_empty(), b = sidx_aabb_empty();
            uint32_t nl = 0;
            for (uint32_t q = 0; q < j; ++q) {
                a = sidx_aabb_union(a, bin[q]);
                nl += n[q];
            }
            for (uint32_t q = j; q < bins; ++q) b = sidx_aabb_union(b, bin[q]);
            if (nl == 0 || nl == count) continue;
            const float cost = sah_cost(bb, a, nl, b, count - nl, c_trav, c_tri);
            const float pos = cmin + ext * (float)j / (float)bins;
            candidate(ex, node, &best, axis, pos, cost, nl, count);
        }
    }
    if (best.axis >= 0) sidx_ex_split(ex, node, best.axis, best.pos, best.cost, best.nl, count - best.nl);
    free(bin);
    free(n);
}
