/* Exercise 16 — the kd-tree build's termination rule.
 *
 * Slides: deck 000, "Termination Criteria": "When should we stop
 * splitting? — when splitting does not help any more.  Use the cost
 * estimates in your termination criteria.  Threshold of cost improvement
 * — but stretch decision over multiple levels, to avoid local minima.
 * Threshold of cell size."  And "Building good kD-trees".
 *
 * The library's SAH kd-tree build ("kdtree") finds, for every node, its
 * cheapest split plane (best_cost, the SAH cost C_trav + ... of
 * exercise 09; +inf when the cell has no plane strictly inside it).  You
 * decide, node by node, whether it becomes a leaf and why.  Return one of
 * sidx_leaf_reason (sidx/hook.h), checked in this order:
 *
 *   SIDX_LEAF_EMPTY       n == 0 (an empty cell);
 *   SIDX_LEAF_FEW_PRIMS   n <= leaf_size;
 *   SIDX_LEAF_MAX_DEPTH   depth >= max_depth (the root has depth 0);
 *   SIDX_LEAF_NO_SPLIT    best_cost is +inf (no plane to split at);
 *   SIDX_LEAF_NO_GAIN     the split does not pay (below);
 *   SIDX_LEAF_NONE        split.
 *
 * "Split only if it pays", stretched over several levels: the leaf costs
 * c_tri·n.  A split with best_cost >= c_tri·n does not pay; *bad counts
 * such splits on the path from the root (on entry: the parent's count,
 * 0 at the root; add one for this node when its split does not pay — the
 * children start from the new count).  Such a split is still taken
 * (maybe the next level pays) unless it is the 3rd on the path
 * (*bad >= 3), or it is much worse than the leaf on few triangles
 * (best_cost > 4·c_tri·n and n < 16): then SIDX_LEAF_NO_GAIN.  This is
 * pbrt's badRefines (Pharr, Jakob, Humphreys, PBR 4.4.2).
 *
 * The checker builds kd-trees over several scenes and knob settings,
 * calls your function on every node your decisions reach, depth first,
 * and compares each decision with the library's BUILD_LEAF / BUILD_SPLIT.
 *
 * Check with:   make exercise EX=16_kd_termination
 * Only the function body is yours to write. */
#include "sidx/sidx.h"

int kd_terminate(uint32_t n, uint32_t depth, float best_cost, float c_tri, uint32_t leaf_size, uint32_t max_depth,
                 uint32_t *bad)
{
    (void)n;
    (void)depth;
    (void)best_cost;
    (void)c_tri;
    (void)leaf_size;
    (void)max_depth;
    (void)bad;
    return SIDX_LEAF_NO_GAIN;
}
