/* sidx/instance.h — aggregates and instancing.
 *
 * The deck's aggregate object "holds groups of objects, conceptually stores
 * a bounding volume & a list of children", and is "useful for instancing
 * (placing a collection of objects repeatedly)".  Here a child is any built
 * structure — a "bvh" over a mesh, a kd-tree, ... or another aggregate —
 * placed by an affine 3×4 transform.  The same child may be placed any
 * number of times: 10,000 bunnies cost one bunny BVH plus 10,000 transforms.
 *
 *     sidx_instance inst[2] = {{bunny_bvh, {1,0,0,0, 0,1,0,0, 0,0,1,0}},
 *                              {bunny_bvh, {1,0,0,5, 0,1,0,0, 0,0,1,0}}};
 *     sidx_accel *scene;
 *     sidx_aggregate_build(inst, 2, NULL, &scene, &err);
 *     sidx_accel_intersect(scene, &ray, NULL, &hit);   // hit.instance, hit.prim
 *     sidx_accel_destroy(scene);                        // not the children
 *
 * The aggregate is an ordinary sidx_accel for queries, stats and destroy
 * (not in the registry: it is built from instances, not from a mesh).  Its
 * top level is a BVH over the instances' world boxes.  A ray reaching an
 * instance is carried into the instance's space by the inverse transform;
 * the direction is NOT renormalized, so t means the same point in both
 * spaces and hits from different instances compare directly.
 *
 * Hits: prim is the triangle in the instanced structure's own mesh;
 * instance is a "leaf instance id": the instances of nested aggregates are
 * numbered depth first (an aggregate child with k leaf instances takes k
 * consecutive ids), so a plain scene of n instances uses ids 0..n-1.
 * sidx_aggregate_leaf() turns an id back into the structure and the
 * composite object-to-world transform.  u, v are the barycentrics in that
 * triangle; ng is the geometric normal transformed to world space (by the
 * inverse transpose), unnormalized.
 *
 * Ownership: the children must outlive the aggregate; the instance array
 * is copied. */
#ifndef SIDX_INSTANCE_H
#define SIDX_INSTANCE_H

#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_instance {
    const sidx_accel *accel; /* any built structure, or an aggregate */
    float xform[12];         /* object to world, row-major 3×4: world = M[:, 0..2]·p + M[:, 3] */
} sidx_instance;

/* Errors: SIDX_ERR_INVALID_ARG (NULL, a NULL child, a non-finite or
 * singular transform, n = 0 is allowed), SIDX_ERR_NOMEM, SIDX_ERR_LIMIT
 * (more than 2^32 − 2 leaf instances).  opt: hook (build events), alloc;
 * others ignored. */
sidx_status sidx_aggregate_build(const sidx_instance *instances, uint32_t n, const sidx_build_options *opt,
                                 sidx_accel **out, sidx_error *err);

int sidx_accel_is_aggregate(const sidx_accel *a);
/* Leaf instances below an aggregate (1 for any other structure). */
uint32_t sidx_aggregate_leaf_count(const sidx_accel *a);
/* The structure and composite object-to-world transform of a leaf
 * instance id (as found in sidx_hit.instance).  SIDX_ERR_INVALID_ARG if
 * a is not an aggregate or id is out of range. */
sidx_status sidx_aggregate_leaf(const sidx_accel *a, uint32_t leaf_id, const sidx_accel **leaf, float xform[12]);

typedef struct sidx_aggregate_info {
    uint32_t instances;        /* direct children */
    uint32_t leaf_instances;   /* after expanding nested aggregates */
    uint32_t distinct_children;/* distinct structures placed directly */
    uint64_t world_triangles;  /* triangles of the flattened scene */
    size_t own_bytes;          /* this aggregate: instances, inverse transforms, top-level BVH */
    size_t shared_bytes;       /* the distinct children, counted once each (their stats bytes) */
} sidx_aggregate_info;
sidx_status sidx_aggregate_info_get(const sidx_accel *a, sidx_aggregate_info *out);

#ifdef __cplusplus
}
#endif
#endif
