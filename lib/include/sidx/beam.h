/* sidx/beam.h — cone and beam tracing, at lesson scale.
 *
 * The deck: "trace continuous bundles of rays.  Cone tracing: approximate a
 * collection of rays with cone(s), subdivide into smaller cones if
 * necessary.  Beam tracing: exactly represent a ray bundle with a pyramid
 * ...  Problems: clipping of beams?  Good approximations?  How to compute
 * intersections?  Not really practical!!"
 *
 * Here a bundle is traced against a BVH over triangle boxes: nodes whose
 * boxes lie outside the bundle are culled, and what survives is the list
 * of CANDIDATE triangles — triangles the bundle may touch.  That is all a
 * bundle can honestly say: which of them each ray hits first still needs
 * the rays (or exact beam clipping, which the deck's "clipping of beams?"
 * questions).  When a bundle has more than max_candidates candidates it
 * is replaced by 4 smaller ones (up to max_levels times); the counts in
 * sidx_bundle_result show what that buys and costs.
 *
 * Tests used (both conservative):
 *   beam: a box or triangle is culled when it lies entirely outside one of
 *         the pyramid's 4 side planes or behind the apex;
 *   cone: nodes are culled against the cone's circumscribed square pyramid
 *         (planes are monotone: a box holding a surviving triangle always
 *         survives), triangles in addition by their bounding sphere against
 *         the cone itself. */
#ifndef SIDX_BEAM_H
#define SIDX_BEAM_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_cone {
    sidx_vec3 apex, axis;   /* axis need not be unit length */
    float half_angle;       /* radians, in (0, 1.5] (about 86 degrees) */
} sidx_cone;

typedef struct sidx_beam {
    sidx_vec3 apex;
    sidx_vec3 dir[4];       /* corner directions, in order around the pyramid (either orientation) */
} sidx_beam;

typedef struct sidx_bundle_tree sidx_bundle_tree;
/* A median-split BVH over the triangles' boxes (opt: alloc; leaf_size, 0 = 4). */
sidx_status sidx_bundle_tree_build(const sidx_mesh *m, const sidx_build_options *opt, sidx_bundle_tree **out,
                                   sidx_error *err);
void sidx_bundle_tree_destroy(sidx_bundle_tree *t);

typedef struct sidx_bundle_result {
    uint32_t *cands;          /* distinct candidate triangles, ascending (malloc'ed) */
    uint32_t num_cands;
    uint32_t bundles;         /* bundles traced to the end (leaves of the subdivision) */
    uint32_t subdivisions;    /* bundles replaced by 4 smaller ones */
    uint64_t nodes_visited;   /* BVH nodes tested, over all bundles (discarded ones included) */
    uint64_t nodes_culled;
    uint64_t tri_tests;
    uint64_t cand_refs;       /* candidates summed over the final bundles (shared ones counted each time) */
} sidx_bundle_result;
void sidx_bundle_result_free(sidx_bundle_result *r);

/* max_candidates = 0: never subdivide.  hook may be NULL; events:
 * NODE_ENTER / BOX_TEST per node (result 0 = culled), PRIM_TEST per
 * triangle (result 1 = candidate), NOTE on each subdivision.
 * SIDX_ERR_INVALID_ARG on bad geometry (zero axis, angle out of range,
 * degenerate corners), SIDX_ERR_NOMEM. */
sidx_status sidx_cone_trace(const sidx_bundle_tree *t, const sidx_cone *c, uint32_t max_candidates,
                            uint32_t max_levels, const sidx_hook *hook, sidx_bundle_result *out);
sidx_status sidx_beam_trace(const sidx_bundle_tree *t, const sidx_beam *b, uint32_t max_candidates,
                            uint32_t max_levels, const sidx_hook *hook, sidx_bundle_result *out);

/* The same tests without the tree (every triangle): the reference. */
sidx_status sidx_cone_candidates_brute(const sidx_mesh *m, const sidx_cone *c, sidx_bundle_result *out);
sidx_status sidx_beam_candidates_brute(const sidx_mesh *m, const sidx_beam *b, sidx_bundle_result *out);

/* The 4 sub-bundles of a subdivision (for drawing and testing). */
void sidx_cone_split(const sidx_cone *c, sidx_cone out[4]);
void sidx_beam_split(const sidx_beam *b, sidx_beam out[4]);

#ifdef __cplusplus
}
#endif
#endif
