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
#include "mesh.h"

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
 * a is not an aggregate or id is out of range.  A lazy instance whose
 * structure no ray has reached yet gives *leaf = NULL (not built here). */
sidx_status sidx_aggregate_leaf(const sidx_accel *a, uint32_t leaf_id, const sidx_accel **leaf, float xform[12]);

/* Lazy instances: an instance that names a mesh and the structure to build
 * over it, which the aggregate builds itself — up front, or, with
 * opt->lazy != 0, the first time a ray enters the instance's world box (a
 * city of 1,000 buildings seen from one street builds the few the rays
 * reach):
 *
 *     sidx_mesh_instance inst[2] = {{&house, "bvh", NULL, {1,0,0,0, 0,1,0,0, 0,0,1,0}},
 *                                   {&tower, "bvh", NULL, {1,0,0,9, 0,1,0,0, 0,0,1,0}}};
 *     sidx_build_options o = {0};
 *     o.lazy = 1;                                       // 0: every structure built now
 *     sidx_aggregate_build_meshes(inst, 2, &o, &city, &err);
 *     sidx_accel_intersect(city, &ray, NULL, &hit);     // builds what the ray enters
 *
 * Instances naming the same mesh, structure name and options pointer share
 * one structure (built once).  The aggregate owns the structures it builds
 * and frees them with itself; the meshes must outlive it.
 *
 * Hits: lazy and eager give the same hits, bit for bit, for single rays,
 * packets (which reach an aggregate ray by ray) and any number of threads;
 * the structure is the one sidx_accel_build(accel, mesh, opt) makes.  An
 * aggregate of mesh instances walks its top level one instance per leaf, so
 * that "the ray enters its box" is the top walk's own box test.
 *
 * Lazy: the instance's structure is built during the query that first
 * reaches it, on that query's thread; threads racing into one unbuilt
 * instance build it once (the others wait).  Its hook receives a
 * BUILD_LAZY_EXPAND event (node = instance, count = the mesh's triangles,
 * bounds = the world box) and then the structure's build events.  A query
 * that cannot get the memory returns SIDX_ERR_NOMEM, its hit not to be
 * used; nothing of that structure is kept and a later query tries again.
 * sidx_accel_stats of the aggregate: unbuilt = the structures not built
 * yet, unbuilt_prims = the instances waiting on them (prim_refs counts
 * instances); sidx_aggregate_info_get gives both in full. */
typedef struct sidx_mesh_instance {
    const sidx_mesh *mesh;          /* the instance's geometry, in its own space */
    const char *accel;              /* registry name (sidx_accel_build); NULL = "bvh" */
    const sidx_build_options *opt;  /* its build options, NULL = defaults; read at aggregate build and copied
                                       (its hook and alloc are not used: the aggregate's allocator, the
                                       aggregate's build hook or, lazily, the query's hook instead) */
    float xform[12];                /* object to world, as sidx_instance */
} sidx_mesh_instance;

/* Errors: those of sidx_aggregate_build, plus SIDX_ERR_INVALID_ARG for a
 * NULL mesh, sidx_mesh_validate's error for an invalid one,
 * SIDX_ERR_UNKNOWN_ACCEL for a name the registry lacks, the structure's
 * error for options it rejects (tried on one triangle, so that a lazy
 * build fails at a query only for want of memory); eager (opt->lazy = 0):
 * any error of building a structure.  opt: lazy (0 = build all now, else lazily; the structures'
 * own lazy builds are their opt's), hook (build events), alloc (the
 * aggregate and every structure it builds); others ignored. */
sidx_status sidx_aggregate_build_meshes(const sidx_mesh_instance *instances, uint32_t n, const sidx_build_options *opt,
                                        sidx_accel **out, sidx_error *err);

/* A city for lazy instances: n distinct buildings (each from its own seed:
 * 4 to 8 sides, height, taper, twist; 2·k·detail² + k·detail triangles,
 * at least 10,512 at the default detail 36, 72 at detail 3) on a square
 * grid of blocks 24 units apart, each turned about y, and a street-level
 * camera looking down the street between the two middle columns.  The
 * same n and detail give the same city, bit for bit, on every machine.
 * instances[i] places meshes[i]: accel NULL ("bvh") and opt NULL, for the
 * caller to set before sidx_aggregate_build_meshes.  Errors:
 * SIDX_ERR_INVALID_ARG (out NULL, n = 0), SIDX_ERR_LIMIT (n > 65536,
 * detail > 256), SIDX_ERR_NOMEM.  sidx_city_free frees it (a zeroed city
 * is fine). */
typedef struct sidx_city {
    uint32_t n;
    sidx_mesh *meshes;               /* n buildings, each in its own space */
    sidx_mesh_instance *instances;   /* building i on its block */
    sidx_vec3 eye, at;               /* the street-level camera */
    sidx_vec3 light;                 /* a sun, high to one side */
} sidx_city;
sidx_status sidx_city_make(uint32_t n, uint32_t detail, sidx_city *out, sidx_error *err);
void sidx_city_free(sidx_city *c);

typedef struct sidx_aggregate_info {
    uint32_t instances;        /* direct children */
    uint32_t leaf_instances;   /* after expanding nested aggregates */
    uint32_t distinct_children;/* distinct structures placed directly */
    uint64_t world_triangles;  /* triangles of the flattened scene */
    size_t own_bytes;          /* this aggregate: instances, inverse transforms, top-level BVH */
    size_t shared_bytes;       /* the distinct children, counted once each (their stats bytes);
                                  mesh instances: the structures built so far */
    uint32_t mesh_structures;  /* mesh instances: the distinct structures the aggregate builds */
    uint32_t built_structures; /* of those, built so far (all of them when eager) */
    uint32_t built_instances;  /* direct instances whose structure is built (all of them when eager) */
} sidx_aggregate_info;
sidx_status sidx_aggregate_info_get(const sidx_accel *a, sidx_aggregate_info *out);

#ifdef __cplusplus
}
#endif
#endif
