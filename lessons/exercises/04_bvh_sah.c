/* Exercise 04 — the surface area heuristic: the cost of one split, then
 * the split choice of the deck's three "Building Partitions" loops.
 *
 * Slides: deck 001, "Surface Area Heuristic" (C = C_trav + S_A/S_C·N_A·
 * C_tri + S_B/S_C·N_B·C_tri) and "Building Partitions" (the full sweep,
 * "check every B primitives", binning: "add bins to partitions instead of
 * triangles"); deck 000, "Building good kD-trees" ("proportional to
 * surface area ... not the volume").
 *
 * 1. sah_cost — C = C_trav + (A_L·N_L + A_R·N_R)·C_tri / A_parent, with A
 *    the surface area sidx_aabb_area (2·(xy + yz + zx)).
 * 2. split_sweep — one node's triangles prims[0 .. count) (indices into
 *    boxes[] and cents[], the triangles' bounding boxes and their
 *    centres).  For each axis x, y, z (skip an axis on which every
 *    centroid is equal): sort the triangles by centroid (ties by triangle
 *    index), then for each position i = 1 .. count-1 that is a multiple of
 *    step: left = the boxes of sorted[0 .. i), right = sorted[i .. count),
 *    cost = C over the node's box (the union of its triangles' boxes),
 *    reported with sidx_ex_candidate(ex, node, axis, pos, cost, i,
 *    count - i), pos = the midpoint of centroids i-1 and i.  step = 1 is
 *    the full sweep; step = B the every-B loop, never coarser than half
 *    the node (step = count / 2 when B is larger).  Finally report the
 *    cheapest candidate ("if (cost < best_cost)": the first of equal ones)
 *    with sidx_ex_split(ex, node, axis, pos, cost, n_left, n_right).
 * 3. split_binned — the same with `bins` bins per axis over the centroid
 *    bounds [cmin, cmin + extent]: a triangle's bin is (int)((c - cmin)·
 *    (bins / extent)) in float, clamped to [0, bins - 1]; plane j = 1 ..
 *    bins-1 lies at cmin + extent·j/bins and puts bins 0 .. j-1 left; a
 *    plane with no triangle on one side is no candidate.
 *
 * Check with:   make exercise EX=04_bvh_sah
 * Only the three function bodies are yours to write (helpers of your own
 * are fine). */
#include <stdlib.h>
#include "sidx/sidx.h"
#include "sidx/exercise.h"

float sah_cost(sidx_aabb parent, sidx_aabb left, uint32_t n_left, sidx_aabb right, uint32_t n_right, float c_trav,
               float c_tri)
{
    (void)parent;
    (void)left;
    (void)n_left;
    (void)right;
    (void)n_right;
    (void)c_trav;
    (void)c_tri;
    return 0.0f;
}

void split_sweep(const sidx_ex *ex, uint32_t node, const uint32_t *prims, uint32_t count, const sidx_aabb *boxes,
                 const sidx_vec3 *cents, uint32_t step, float c_trav, float c_tri)
{
    (void)ex;
    (void)node;
    (void)prims;
    (void)count;
    (void)boxes;
    (void)cents;
    (void)step;
    (void)c_trav;
    (void)c_tri;
}

void split_binned(const sidx_ex *ex, uint32_t node, const uint32_t *prims, uint32_t count, const sidx_aabb *boxes,
                  const sidx_vec3 *cents, uint32_t bins, float c_trav, float c_tri)
{
    (void)ex;
    (void)node;
    (void)prims;
    (void)count;
    (void)boxes;
    (void)cents;
    (void)bins;
    (void)c_trav;
    (void)c_tri;
}
