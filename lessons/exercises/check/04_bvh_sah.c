/* 04_bvh_sah.c — checker driver: the SAH cost of one split, then the
 * split choice of the deck's three "Building Partitions" loops (deck 001,
 * "Surface Area Heuristic" and "Building Partitions"): the full sweep over
 * sorted centroids, the sweep at every B-th position, and binning.
 * References: the cost as the "bvh" builds compute it
 * (sidx_ex_reference_sah_cost, C_trav + C_tri·(A_L·N_L + A_R·N_R)/A), and for the splits the library's own builds ("bvh-sweep",
 * "bvh-everyb", "bvh"), whose BUILD_CANDIDATE and BUILD_SPLIT events of
 * one node are the student's candidates and choice for that node's
 * triangles, one for one. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "sidx/bvh.h"

float sah_cost(sidx_aabb parent, sidx_aabb left, uint32_t n_left, sidx_aabb right, uint32_t n_right, float c_trav,
               float c_tri);
void split_sweep(const sidx_ex *ex, uint32_t node, const uint32_t *prims, uint32_t count, const sidx_aabb *boxes,
                 const sidx_vec3 *cents, uint32_t step, float c_trav, float c_tri);
void split_binned(const sidx_ex *ex, uint32_t node, const uint32_t *prims, uint32_t count, const sidx_aabb *boxes,
                  const sidx_vec3 *cents, uint32_t bins, float c_trav, float c_tri);

#define C_TRAV 1.0f
#define C_TRI 1.0f
#define EVERY_B 8u
#define BINS 16u

/* ---- part 1: the cost of one split ------------------------------------------ */

typedef struct cost_case {
    const char *name;
    sidx_aabb parent, left, right;
    uint32_t nl, nr;
} cost_case;

#define COST_FIXED 5
#define COST_RANDOM 8
#define COST_CASES (COST_FIXED + COST_RANDOM)
static cost_case cost_cases[COST_CASES];

static sidx_aabb box6(float x0, float y0, float z0, float x1, float y1, float z1)
{
    sidx_aabb b = {{x0, y0, z0}, {x1, y1, z1}};
    return b;
}

static void cost_setup(void)
{
    int k = 0;
    cost_cases[k++] = (cost_case){"the unit cube split in half along x", box6(0, 0, 0, 1, 1, 1), box6(0, 0, 0, 0.5f, 1, 1),
                                  box6(0.5f, 0, 0, 1, 1, 1), 4, 4};
    cost_cases[k++] = (cost_case){"the deck's example: 3 prims left, 8 right, overlapping boxes",
                                  box6(0, 0, 0, 8, 4, 1), box6(0, 0, 0, 1.5f, 1, 1), box6(1, 0, 0, 8, 4, 1), 3, 8};
    cost_cases[k++] = (cost_case){"flat boxes (zero volume, non-zero area)", box6(0, 0, 0, 4, 2, 0),
                                  box6(0, 0, 0, 1, 2, 0), box6(1, 0, 0, 4, 1, 0), 2, 5};
    cost_cases[k++] = (cost_case){"children smaller than the gap between them", box6(0, 0, 0, 10, 1, 1),
                                  box6(0, 0, 0, 1, 1, 1), box6(9, 0, 0, 10, 1, 1), 10, 10};
    cost_cases[k++] = (cost_case){"one child as large as the parent", box6(-2, -2, -2, 2, 2, 2),
                                  box6(-2, -2, -2, 2, 2, 2), box6(0, 0, 0, 1, 1, 1), 7, 1};
    uint32_t st = 404u;
    while (k < COST_CASES) {
        cost_case *c = &cost_cases[k++];
        const float w = 1 + 4 * ex_rand(&st), h = 1 + 4 * ex_rand(&st), d = 1 + 4 * ex_rand(&st);
        const float s = w * ex_rand(&st);
        c->name = "a random split of a random box";
        c->parent = box6(0, 0, 0, w, h, d);
        c->left = box6(0, 0, 0, s + 0.25f * (w - s) * ex_rand(&st), h, d * (0.5f + 0.5f * ex_rand(&st)));
        c->right = box6(s, h * 0.5f * ex_rand(&st), 0, w, h, d);
        c->nl = 1u + (uint32_t)(20.0f * ex_rand(&st));
        c->nr = 1u + (uint32_t)(20.0f * ex_rand(&st));
    }
}

/* ---- part 2: the split choice -------------------------------------------- */

#define NSCENES 3
#define NBUILDERS 3
#define NODES_PER 6 /* inner nodes per build and scene, the first in depth-first order */
static const char *const scene_names[NSCENES] = {"soup:150", "flat2d:6", "cornell"};
static const char *const builder_names[NBUILDERS] = {"bvh-sweep", "bvh-everyb", "bvh"};
static const char *const builder_what[NBUILDERS] = {"full sweep", "every-B sweep (B = 8)", "binned (16 bins)"};
static sidx_mesh meshes[NSCENES];
static sidx_aabb *boxes[NSCENES];
static sidx_vec3 *cents[NSCENES];

typedef struct node_case {
    uint32_t node, count;
    uint32_t *prims;
    sidx_event *ev; /* the library's CANDIDATE and SPLIT events of the node */
    size_t nev;
    char rules[160]; /* the rules the case tests (node_rules) */
} node_case;
static node_case nodes[NBUILDERS][NSCENES][NODES_PER];
static uint32_t num_nodes[NBUILDERS][NSCENES];

/* The triangles under node (the leaves of its subtree). */
static uint32_t subtree_prims(const sidx_bvh_node *nd, const uint32_t *pr, uint32_t node, uint32_t *out, uint32_t n)
{
    const sidx_bvh_node *x = &nd[node];
    if (sidx_bvh_is_leaf(x)) {
        for (uint32_t i = 0; i < sidx_bvh_count(x); ++i) out[n++] = pr[x->left_or_first + i];
        return n;
    }
    n = subtree_prims(nd, pr, node + 1, out, n);
    return subtree_prims(nd, pr, x->left_or_first, out, n);
}

/* The rules a node case tests: by builder, and by what its triangles
 * hold (a flat axis, equal centroids, fewer than 2·B triangles). */
static void node_rules(const node_case *c, int b, int s, char *out, size_t size)
{
    static const char *const by_builder[NBUILDERS] = {"node-box sweep-midpoint first-cheapest",
                                                      "every-b sweep-midpoint",
                                                      "bin-index bin-plane node-box first-cheapest"};
    int flat = 0, ties = 0;
    for (int axis = 0; axis < 3; ++axis) {
        float lo = INFINITY, hi = -INFINITY;
        for (uint32_t k = 0; k < c->count; ++k) {
            const float v = sidx_v3_get(cents[s][c->prims[k]], axis);
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
            for (uint32_t q = 0; q < k && !ties; ++q) ties = v == sidx_v3_get(cents[s][c->prims[q]], axis);
        }
        flat |= !(hi > lo);
    }
    snprintf(out, size, "%s%s%s%s", by_builder[b], flat ? " skip-flat-axis" : "", ties && b == 0 ? " sort-ties" : "",
             b == 1 && c->count < 2 * EVERY_B ? " every-b-half" : "");
}

static int setup(void)
{
    cost_setup();
    for (int s = 0; s < NSCENES; ++s) {
        if (sidx_scene_open(scene_names[s], &meshes[s], NULL) != SIDX_OK) return -1;
        const uint32_t n = meshes[s].num_triangles;
        boxes[s] = malloc(n * sizeof *boxes[s]);
        cents[s] = malloc(n * sizeof *cents[s]);
        if (!boxes[s] || !cents[s]) return -1;
        for (uint32_t i = 0; i < n; ++i) {
            boxes[s][i] = sidx_mesh_triangle_bounds(&meshes[s], i);
            cents[s][i] = sidx_aabb_centroid(boxes[s][i]);
        }
        for (int b = 0; b < NBUILDERS; ++b) {
            ex_trace rec = {NULL, 0, 0};
            const sidx_hook h = {ex_trace_hook_fn, &rec,
                                 SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE) | SIDX_EVMASK(SIDX_EV_BUILD_SPLIT)};
            sidx_build_options bo;
            memset(&bo, 0, sizeof bo);
            bo.hook = &h;
            bo.c_trav = C_TRAV;
            bo.c_tri = C_TRI;
            bo.every_b = EVERY_B;
            bo.bins = BINS;
            bo.threads = 1;
            sidx_accel *a = NULL;
            if (sidx_accel_build(builder_names[b], &meshes[s], &bo, &a, NULL) != SIDX_OK) return -1;
            const sidx_bvh_node *nd = NULL;
            const uint32_t *pr = NULL;
            uint32_t nn = 0, np = 0;
            sidx_bvh_nodes(a, &nd, &nn, NULL);
            sidx_bvh_prims(a, &pr, &np, NULL);
            /* the nodes the library split on an axis, in event order */
            for (size_t k = 0; k < rec.n && num_nodes[b][s] < NODES_PER; ++k) {
                if (rec.ev[k].type != SIDX_EV_BUILD_SPLIT || rec.ev[k].axis < 0) continue;
                node_case *c = &nodes[b][s][num_nodes[b][s]++];
                c->node = rec.ev[k].node;
                size_t first = k;
                while (first > 0 && rec.ev[first - 1].type == SIDX_EV_BUILD_CANDIDATE &&
                       rec.ev[first - 1].node == c->node)
                    --first;
                c->nev = k + 1 - first;
                c->ev = malloc(c->nev * sizeof *c->ev);
                c->prims = malloc(np * sizeof *c->prims);
                if (!c->ev || !c->prims) return -1;
                memcpy(c->ev, rec.ev + first, c->nev * sizeof *c->ev);
                c->count = subtree_prims(nd, pr, c->node, c->prims, 0);
                node_rules(c, b, s, c->rules, sizeof c->rules);
            }
            free(rec.ev);
            sidx_accel_destroy(a);
        }
    }
    return 0;
}

static void teardown(void)
{
    for (int b = 0; b < NBUILDERS; ++b)
        for (int s = 0; s < NSCENES; ++s)
            for (uint32_t k = 0; k < num_nodes[b][s]; ++k) {
                free(nodes[b][s][k].ev);
                free(nodes[b][s][k].prims);
            }
    for (int s = 0; s < NSCENES; ++s) {
        free(boxes[s]);
        free(cents[s]);
        sidx_mesh_free(&meshes[s]);
    }
}

/* Part 3: four coincident triangles (every centroid equal): no plane
 * separates them, so no candidate and no split, for the sweep and the bins. */
#define COINCIDENT_CASES 2
static const uint32_t coincident_prims[4] = {0, 1, 2, 3};
static const sidx_aabb coincident_boxes[4] = {
    {{0, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}}, {{0, 0, 0}, {1, 1, 0}}};
static const sidx_vec3 coincident_cents[4] = {{0.5f, 0.5f, 0}, {0.5f, 0.5f, 0}, {0.5f, 0.5f, 0}, {0.5f, 0.5f, 0}};

static size_t num_split_cases(void)
{
    size_t n = 0;
    for (int b = 0; b < NBUILDERS; ++b)
        for (int s = 0; s < NSCENES; ++s) n += num_nodes[b][s];
    return n;
}

static size_t num_cases(void) { return COST_CASES + num_split_cases() + COINCIDENT_CASES; }

/* Case i of part 2: builder, scene and node. */
static const node_case *split_case(size_t i, int *b_out, int *s_out)
{
    i -= COST_CASES;
    *b_out = *s_out = 0;
    for (int b = 0; b < NBUILDERS; ++b)
        for (int s = 0; s < NSCENES; ++s) {
            if (i < num_nodes[b][s]) {
                *b_out = b;
                *s_out = s;
                return &nodes[b][s][i];
            }
            i -= num_nodes[b][s];
        }
    return NULL;
}

#define HINT_AREA                                                                                          \
    "C = C_trav + S_A/S_C·N_A·C_tri + S_B/S_C·N_B·C_tri: each child's probability is its SURFACE AREA "      \
    "(2·(xy + yz + zx), \"not the volume\") relative to the parent's, times its primitive count"
#define HINT_COUNTS                                                                                        \
    "each child's area is weighted by its own primitive count, times C_tri, over the parent's area: "       \
    "C = C_trav + (A_L·N_L + A_R·N_R)·C_tri / A_parent, each area times its primitive count (not added to it)"
#define HINT_SWEEP                                                                                         \
    "\"sort(primitives, axis) — sort primitives by centroid\" (ties by triangle index), then for i = 1 .. n-1: " \
    "a = bbox(primitives[0,i]), b = bbox(primitives[i,n]), report the candidate at pos = the midpoint of "   \
    "centroids i-1 and i; all three axes, x first, skipping an axis where every centroid is equal"
#define HINT_FLAT                                                                                          \
    "skip an axis on which every centroid is equal (the centroid bounds have no extent there): no plane "   \
    "separates the triangles, so that axis has no candidate at all"
#define HINT_TIES                                                                                          \
    "triangles of equal centroid are sorted by triangle index: at such a tie the boxes left and right of "  \
    "position i, and so the cost, depend on that order"
#define HINT_NODE_BOX                                                                                      \
    "the parent's area is that of the node's box, the union of its triangles' BOXES, not the bounds of "    \
    "their centroids"
#define HINT_EVERYB                                                                                        \
    "\"check every B primitives\": only the positions i that are multiples of B (B = 8), never coarser than " \
    "half the node (B = n/2 when 8 > n/2)"
#define HINT_BINS                                                                                          \
    "\"find bin that triangle lies in\": bin = (int)((c - cmin)·nb/extent) over the CENTROID bounds, clamped " \
    "to [0, nb-1]; plane j (1 .. nb-1) at cmin + extent·j/nb puts bins 0 .. j-1 left; a plane with an empty " \
    "side is no candidate"
#define HINT_BIN_INDEX                                                                                     \
    "a triangle's bin is (int)((c - cmin)·(nb/extent)) computed in float, truncated (not rounded), clamped " \
    "to [0, nb-1]: the counts left and right of a plane follow from the bins"
#define HINT_BIN_PLANE                                                                                     \
    "plane j (1 .. nb-1) lies at cmin + extent·j/nb over the CENTROID bounds [cmin, cmin + extent] (not the " \
    "node's box) and puts bins 0 .. j-1 left"
#define HINT_BEST                                                                                          \
    "\"if (cost < best_cost)\": keep the first cheapest candidate over all axes (strictly cheaper replaces " \
    "it) and report it with sidx_ex_split"

/* The hand-out's promises (lessons/exercises/04_bvh_sah.c). */
static const ex_rule rules[] = {
    {"sah-area", "the probabilities are surface areas, 2·(xy + yz + zx), relative to the parent's", HINT_AREA},
    {"sah-counts", "C = C_trav + (A_L·N_L + A_R·N_R)·C_tri / A_parent: each area times its own count",
     HINT_COUNTS},
    {"skip-flat-axis", "an axis on which every centroid is equal is skipped", HINT_FLAT},
    {"sort-ties", "the sweep sorts by centroid, ties by triangle index", HINT_TIES},
    {"node-box", "the cost is over the node's box, the union of its triangles' boxes", HINT_NODE_BOX},
    {"sweep-midpoint", "the sweep's candidate at position i lies at the midpoint of centroids i-1 and i",
     HINT_SWEEP},
    {"every-b", "step = B: only the positions i that are multiples of step", HINT_EVERYB},
    {"every-b-half", "step is never coarser than half the node: step = count / 2 when B is larger",
     HINT_EVERYB},
    {"bin-index", "a triangle's bin is (int)((c - cmin)·(bins / extent)) in float, clamped to [0, bins - 1]",
     HINT_BIN_INDEX},
    {"bin-plane", "plane j = 1 .. bins-1 lies at cmin + extent·j/bins over the centroid bounds, bins 0 .. j-1 left",
     HINT_BIN_PLANE},
    {"first-cheapest", "the split is the cheapest candidate, the first of equal ones (cost < best_cost)",
     HINT_BEST},
};
enum { R_AREA, R_COUNTS, R_FLAT, R_TIES, R_NODE_BOX, R_MID, R_EVERYB, R_HALF, R_BIN_INDEX, R_BIN_PLANE,
       R_BEST };

static const char *const hint_cost = HINT_AREA;
static const char *const hint_sweep = HINT_SWEEP;
static const char *const hint_everyb = HINT_EVERYB;
static const char *const hint_bins = HINT_BINS;


static void describe(size_t i, ex_case_info *out)
{
    if (i < COST_CASES) {
        const cost_case *c = &cost_cases[i];
        snprintf(out->name, sizeof out->name, "cost: %s", c->name);
        snprintf(out->what, sizeof out->what,
                 "parent [%g %g %g]-[%g %g %g]  left [%g %g %g]-[%g %g %g] N=%u  right [%g %g %g]-[%g %g %g] N=%u  "
                 "C_trav=%g C_tri=%g",
                 (double)c->parent.min.x, (double)c->parent.min.y, (double)c->parent.min.z, (double)c->parent.max.x,
                 (double)c->parent.max.y, (double)c->parent.max.z, (double)c->left.min.x, (double)c->left.min.y,
                 (double)c->left.min.z, (double)c->left.max.x, (double)c->left.max.y, (double)c->left.max.z, c->nl,
                 (double)c->right.min.x, (double)c->right.min.y, (double)c->right.min.z, (double)c->right.max.x,
                 (double)c->right.max.y, (double)c->right.max.z, c->nr, (double)C_TRAV, (double)C_TRI);
        out->hint = hint_cost;
        out->rules = "sah-area sah-counts";
        return;
    }
    if (i >= COST_CASES + num_split_cases()) {
        const int binned = i + 1 == num_cases();
        snprintf(out->name, sizeof out->name, "%s, four coincident triangles (every centroid equal)",
                 binned ? builder_what[2] : builder_what[0]);
        snprintf(out->what, sizeof out->what, "4 triangles, each with the box [0 0 0]-[1 1 0]: no plane separates them");
        out->hint = binned ? hint_bins : hint_sweep;
        out->rules = "skip-flat-axis";
        return;
    }
    int b = 0, s = 0;
    const node_case *c = split_case(i, &b, &s);
    snprintf(out->name, sizeof out->name, "%s, scene %s, node %u (%u triangles)", builder_what[b], scene_names[s],
             c->node, c->count);
    snprintf(out->what, sizeof out->what, "%u triangles of %s; C_trav = %g, C_tri = %g", c->count, scene_names[s],
             (double)C_TRAV, (double)C_TRI);
    out->hint = b == 0 ? hint_sweep : b == 1 ? hint_everyb : hint_bins;
    out->rules = c->rules;
}

static void reference(size_t i, const sidx_hook *h)
{
    if (i < COST_CASES) {
        const cost_case *c = &cost_cases[i];
        sidx_ex ex;
        memset(&ex, 0, sizeof ex);
        ex.hook = h;
        ex.structure = "bvh";
        sidx_ex_candidate(&ex, 0, 0, 0.0f,
                          sidx_ex_reference_sah_cost(c->parent, c->left, c->nl, c->right, c->nr, C_TRAV, C_TRI), c->nl,
                          c->nr);
        return;
    }
    if (i >= COST_CASES + num_split_cases()) return; /* no candidate, no split */
    int b = 0, s = 0;
    const node_case *c = split_case(i, &b, &s);
    for (size_t k = 0; k < c->nev; ++k) sidx_hook_emit(h, &c->ev[k]);
}

static void student(size_t i, const sidx_hook *h)
{
    sidx_ex ex;
    memset(&ex, 0, sizeof ex);
    ex.hook = h;
    ex.structure = "bvh";
    if (i < COST_CASES) {
        const cost_case *c = &cost_cases[i];
        sidx_ex_candidate(&ex, 0, 0, 0.0f, sah_cost(c->parent, c->left, c->nl, c->right, c->nr, C_TRAV, C_TRI),
                          c->nl, c->nr);
        return;
    }
    if (i >= COST_CASES + num_split_cases()) {
        if (i + 1 == num_cases())
            split_binned(&ex, 0, coincident_prims, 4, coincident_boxes, coincident_cents, BINS, C_TRAV, C_TRI);
        else
            split_sweep(&ex, 0, coincident_prims, 4, coincident_boxes, coincident_cents, 1u, C_TRAV, C_TRI);
        return;
    }
    int b = 0, s = 0;
    const node_case *c = split_case(i, &b, &s);
    ex.mesh = &meshes[s];
    if (b == 2)
        split_binned(&ex, c->node, c->prims, c->count, boxes[s], cents[s], BINS, C_TRAV, C_TRI);
    else
        split_sweep(&ex, c->node, c->prims, c->count, boxes[s], cents[s], b == 0 ? 1u : EVERY_B, C_TRAV, C_TRI);
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* 1 if the sorted centroids of node c on axis are equal at positions
 * nl - 1 and nl (a tie the sort breaks by triangle index). */
static int tie_at(const node_case *c, int s, int axis, uint32_t nl)
{
    if (nl == 0 || nl >= c->count) return 0;
    float *v = malloc(c->count * sizeof *v);
    if (!v) return 0;
    for (uint32_t k = 0; k < c->count; ++k) v[k] = sidx_v3_get(cents[s][c->prims[k]], axis);
    qsort(v, c->count, sizeof *v, cmp_float);
    const int tie = v[nl - 1] == v[nl];
    free(v);
    return tie;
}

/* 1 if b's cost is a's with the parent's area taken from the centroid
 * bounds instead of the node's box. */
static int cost_over_centroids(const node_case *c, int s, float ref_cost, float stu_cost)
{
    sidx_aabb bb = sidx_aabb_empty(), cb = sidx_aabb_empty();
    for (uint32_t k = 0; k < c->count; ++k) {
        bb = sidx_aabb_union(bb, boxes[s][c->prims[k]]);
        cb = sidx_aabb_grow(cb, cents[s][c->prims[k]]);
    }
    const float want = C_TRAV + (ref_cost - C_TRAV) * (sidx_aabb_area(bb) / sidx_aabb_area(cb));
    return fabsf(want - stu_cost) <= 1e-4f * fabsf(want);
}

/* 1 if node c's reference trace has a candidate on axis. */
static int ref_has_axis(const node_case *c, int axis)
{
    for (size_t k = 0; k < c->nev; ++k)
        if (c->ev[k].type == SIDX_EV_BUILD_CANDIDATE && c->ev[k].axis == axis) return 1;
    return 0;
}

/* What differs decides.  Cost cases: a cost that the volumes give names
 * the area, any other the counts.  Split cases: a candidate on an axis
 * the reference has none on is the flat axis; the split is the first-cheapest rule; the same
 * plane with another cost is the node's box (the cost over the centroid
 * bounds), a tie of centroids (the sort's order) or the formula; another
 * plane in the bins is the plane's position (another position) or the
 * bin index (other counts). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if (i < COST_CASES) {
        if (!ref || !stu) return NULL;
        const cost_case *c = &cost_cases[i];
        const sidx_vec3 el = sidx_aabb_extent(c->left), er = sidx_aabb_extent(c->right),
                        ep = sidx_aabb_extent(c->parent);
        const float vol = C_TRAV + C_TRI * (el.x * el.y * el.z * (float)c->nl + er.x * er.y * er.z * (float)c->nr) /
                                       (ep.x * ep.y * ep.z);
        return fabsf(vol - stu->cost) <= 1e-4f * fabsf(vol) ? rules[R_AREA].hint : rules[R_COUNTS].hint;
    }
    if (i >= COST_CASES + num_split_cases()) return stu ? rules[R_FLAT].hint : NULL;
    int b = 0, s = 0;
    const node_case *c = split_case(i, &b, &s);
    if (stu && stu->type == SIDX_EV_BUILD_CANDIDATE) {
        if (!ref_has_axis(c, stu->axis)) return rules[R_FLAT].hint;
    }
    if ((ref && ref->type == SIDX_EV_BUILD_SPLIT) || (stu && stu->type == SIDX_EV_BUILD_SPLIT))
        return rules[R_BEST].hint;
    if (!ref || !stu) return NULL;
    if (ref->axis == stu->axis && ref->pos == stu->pos && ref->count == stu->count && ref->aux == stu->aux) {
        /* the right plane, the wrong cost */
        if (cost_over_centroids(c, s, ref->cost, stu->cost)) return rules[R_NODE_BOX].hint;
        if (b != 2 && tie_at(c, s, ref->axis, ref->count)) return rules[R_TIES].hint;
        return rules[R_COUNTS].hint;
    }
    if (b == 2 && ref->axis == stu->axis)
        return ref->pos != stu->pos ? rules[R_BIN_PLANE].hint : rules[R_BIN_INDEX].hint;
    return NULL;
}

const ex_driver ex_driver_this = {
    "04_bvh_sah",
    "the SAH cost of one split, then the split choice: full sweep, every-B sweep, bins",
    "deck 001, \"Surface Area Heuristic\" and \"Building Partitions\" (the three loops)",
    setup, num_cases, describe, reference, student, hint, teardown, NULL, rules, sizeof rules / sizeof rules[0],
};
