/* 04_bvh_sah.c — checker driver: the SAH cost of one split, then the
 * split choice of the deck's three "Building Partitions" loops (deck 001,
 * "Surface Area Heuristic" and "Building Partitions"): the full sweep over
 * sorted centroids, the sweep at every B-th position, and binning.
 * References: the cost as the "bvh" builds compute it
 * (sidx_ex_reference_sah_cost, C_trav + C_tri·(A_L·N_L + A_R·N_R)/A), and for the splits the library's own builds ("bvh-sweep",
 * "bvh-everyb", "bvh"), whose BUILD_CANDIDATE and BUILD_SPLIT events of
 * one node are the student's candidates and choice for that node's
 * triangles, one for one. */
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

static const char *const hint_cost =
    "C = C_trav + S_A/S_C·N_A·C_tri + S_B/S_C·N_B·C_tri: each child's probability is its SURFACE AREA "
    "(2·(xy + yz + zx), \"not the volume\") relative to the parent's, times its primitive count";
static const char *const hint_sweep =
    "\"sort(primitives, axis) — sort primitives by centroid\" (ties by triangle index), then for i = 1 .. n-1: "
    "a = bbox(primitives[0,i]), b = bbox(primitives[i,n]), report the candidate at pos = the midpoint of "
    "centroids i-1 and i; all three axes, x first, skipping an axis where every centroid is equal";
static const char *const hint_everyb =
    "\"check every B primitives\": only the positions i that are multiples of B (B = 8), never coarser than "
    "half the node (B = n/2 when 8 > n/2)";
static const char *const hint_bins =
    "\"find bin that triangle lies in\": bin = (int)((c - cmin)·nb/extent) over the CENTROID bounds, clamped "
    "to [0, nb-1]; plane j (1 .. nb-1) at cmin + extent·j/nb puts bins 0 .. j-1 left; a plane with an empty "
    "side is no candidate";
static const char *const hint_best =
    "\"if (cost < best_cost)\": keep the first cheapest candidate over all axes (strictly cheaper replaces "
    "it) and report it with sidx_ex_split";

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
        return;
    }
    if (i >= COST_CASES + num_split_cases()) {
        const int binned = i + 1 == num_cases();
        snprintf(out->name, sizeof out->name, "%s, four coincident triangles (every centroid equal)",
                 binned ? builder_what[2] : builder_what[0]);
        snprintf(out->what, sizeof out->what, "4 triangles, each with the box [0 0 0]-[1 1 0]: no plane separates them");
        out->hint = binned ? hint_bins : hint_sweep;
        return;
    }
    int b = 0, s = 0;
    const node_case *c = split_case(i, &b, &s);
    snprintf(out->name, sizeof out->name, "%s, scene %s, node %u (%u triangles)", builder_what[b], scene_names[s],
             c->node, c->count);
    snprintf(out->what, sizeof out->what, "%u triangles of %s; C_trav = %g, C_tri = %g", c->count, scene_names[s],
             (double)C_TRAV, (double)C_TRI);
    out->hint = b == 0 ? hint_sweep : b == 1 ? hint_everyb : hint_bins;
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

static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if (i < COST_CASES) return NULL;
    if ((ref && ref->type == SIDX_EV_BUILD_SPLIT) || (stu && stu->type == SIDX_EV_BUILD_SPLIT)) return hint_best;
    if (ref && stu && ref->axis == stu->axis && ref->pos == stu->pos && ref->count == stu->count &&
        ref->aux == stu->aux)
        return hint_cost; /* the right plane, the wrong cost */
    return NULL;
}

const ex_driver ex_driver_this = {
    "04_bvh_sah",
    "the SAH cost of one split, then the split choice: full sweep, every-B sweep, bins",
    "deck 001, \"Surface Area Heuristic\" and \"Building Partitions\" (the three loops)",
    setup, num_cases, describe, reference, student, hint, teardown, NULL, NULL, 0,
};
