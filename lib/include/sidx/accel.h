/* sidx/accel.h — the common interface of every acceleration structure.
 *
 * Every structure is built, queried, measured and destroyed the same way
 * and picked by name ("brute", "bvh", "kdtree", "grid", ...):
 *
 *     sidx_accel *a;
 *     if (sidx_accel_build("bvh", &mesh, NULL, &a, &err) != SIDX_OK) ...
 *     sidx_ray r; sidx_ray_init(&r, org, dir, 0.0f, INFINITY);
 *     sidx_hit h; sidx_accel_intersect(a, &r, NULL, &h);
 *     sidx_accel_destroy(a);
 *
 * Ownership: the structure keeps a pointer to the mesh, which must outlive
 * it.  A built structure is immutable (except sidx_accel_refit), so any
 * number of threads may query it at once; hooks receive their events on the
 * querying thread, with the sidx_hook.user of that query.
 *
 * Zero-initialized option structs mean "defaults" everywhere. */
#ifndef SIDX_ACCEL_H
#define SIDX_ACCEL_H

#include <stddef.h>
#include <stdint.h>
#include "hook.h"
#include "intersect.h"
#include "mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_accel sidx_accel;

/* Optional custom allocator (e.g. to inject failures in tests).  alloc
 * returns NULL on failure; free accepts NULL. */
typedef struct sidx_allocator {
    void *(*alloc)(size_t size, void *user);
    void (*free)(void *ptr, void *user);
    void *user;
} sidx_allocator;

typedef struct sidx_build_options {
    const sidx_hook *hook;        /* receives build events; NULL = none */
    const sidx_allocator *alloc;  /* NULL = malloc/free */
    sidx_tri_method tri;          /* triangle test used by queries (default: watertight) */
    sidx_box_method box;          /* box test used by queries (default: robust, Ize 2013) */
    float c_trav, c_tri;          /* SAH constants; 0 = the structure's default (BVH: 1, 1) */
    uint32_t leaf_size;           /* make a leaf at or below this many primitives; 0 = default */
    uint32_t max_depth;           /* 0 = the structure's default */
    uint32_t bins;                /* binned builders; 0 = 32 */
    uint32_t every_b;             /* every-B sweep; 0 = 32 */
    float grid_density;           /* λ of the grid resolution formula; 0 = default */
    float empty_bonus;            /* kd-tree empty-space bonus in [0,1); 0 = default */
    int no_mailbox;               /* 1 = switch mailboxing off (grids, kd-tree) */
    int no_spatial_splits;        /* 1 = bvh4/bvh8 collapse the plain binned-SAH BVH (every triangle in
                                     one leaf, faster build) instead of the one with spatial splits */
    uint32_t threads;             /* build threads (bvh, bvh4, bvh8; the same tree for any count); 0 = 1 */
    float optimize_ms;            /* bvh family, bvh4, bvh8: time budget in ms of the reinsertion pass
                                     that improves the binary tree after the build (bvh_optimize.c);
                                     0 = off.  A budget large enough gives the same tree every time;
                                     one that cuts the pass short depends on the machine's speed */
    uint32_t lazy;                /* bvh family but bvh-obb and bvh-sbvh, bvh4 and bvh8 (not with no_spatial_splits),
                                     and the kd-tree family but a tree of given splits: build the top of
                                     the tree now and leave each subtree of at most this many primitives
                                     (kd-tree: references; wide BVHs: more than 8) as an unbuilt node
                                     holding them, built the first time a ray enters it (a
                                     BUILD_LAZY_EXPAND event, then its build events, on that query's hook).
                                     bvh family: the tree below each node is the eager build's, node for
                                     node, and hits are bit-identical to the eager tree's.  bvh4, bvh8: the
                                     binary tree below each unbuilt node is the eager one, but the wide
                                     nodes above it group it otherwise, so where a ray hits two triangles
                                     at exactly the same t the other one may be reported (same t; a t of 0
                                     may come out as -0 where the eager tree gives +0); packets over them
                                     go ray by ray.  kd-tree: node for node the eager tree, but its leaves
                                     test blocks of four references that reach into neighbouring leaves,
                                     and a subtree built apart has other neighbours, so hits are the eager
                                     tree's up to rounding: the same misses, and each hit within 1e-6·t of
                                     the eager one, on a triangle the ray hits at exactly that t.  Neither
                                     depends on the order in which subtrees were built.  0 = eager;
                                     1 = the default size (SIDX_LAZY_DEFAULT).  Ignored by the other
                                     structures and with optimize_ms > 0 (the pass needs the whole tree).
                                     A query that cannot get the memory for an expansion returns
                                     SIDX_ERR_NOMEM, its hit not to be used; the subtree stays unbuilt and
                                     a later query tries again */
} sidx_build_options;

/* opt.lazy = 1: subtrees of at most this many primitives wait for a ray. */
#define SIDX_LAZY_DEFAULT 1024u

typedef enum sidx_traversal {
    SIDX_TRAVERSE_DEFAULT = 0,    /* the structure's fast path */
    SIDX_TRAVERSE_STACK,          /* iterative ordered traversal with an explicit stack */
    SIDX_TRAVERSE_ORDERED,        /* recursive, nearer child first (the deck's ordered traversal) */
    SIDX_TRAVERSE_NAIVE,          /* recursive, both children always (the deck's naive traversal) */
    SIDX_TRAVERSE_COUNT
} sidx_traversal;
const char *sidx_traversal_name(sidx_traversal t); /* "default", "stack", "ordered", "naive" */
sidx_status sidx_traversal_parse(const char *name, sidx_traversal *out);

#define SIDX_QUERY_UV     1u  /* fill hit.u, hit.v */
#define SIDX_QUERY_NORMAL 2u  /* fill hit.ng */
#define SIDX_QUERY_POINT  4u  /* fill hit.p, hit.p_err (and u, v, ng): for sidx_ray_spawn, sidx/spawn.h */
#define SIDX_QUERY_PRECISE_T 8u /* the closest hit's t refined on its triangle's plane where the watertight
                                 test's t is coarse: docs/spawning.md,
                                 "Precision of t"; it reads the hit triangle from the mesh once per ray */
#define SIDX_QUERY_REORDER 16u /* sidx_accel_intersect_n / _occluded_n on bvh, bvh4, bvh8: walk the buffer
                                sorted by direction octant, then by a Morton code of the origin, so that rays
                                that go the same way follow each other; answers still in input order, and the
                                same bits.  Buffers of 64 rays or more; it takes 16 bytes per ray from the
                                build's allocator for the call (without them: input order, the same answers).
                                It did not pay on any ray kind measured (docs/performance.md, "The stream
                                entry"): off unless asked.  Ignored by every other query and structure */

typedef struct sidx_query {
    uint32_t flags;               /* SIDX_QUERY_* */
    sidx_traversal traversal;     /* structures without the variant use their default */
    const sidx_hook *hook;        /* receives traversal events; NULL = none (fast path) */
    uint32_t ray_id;              /* copied into events */
} sidx_query;

typedef struct sidx_accel_stats {
    const char *name;             /* registered name */
    uint32_t nodes, leaves, max_depth;
    uint64_t prim_refs;           /* primitive references stored (> triangles when duplicated) */
    size_t bytes;                 /* memory held by the structure, mesh excluded */
    double sah_cost;              /* expected cost under the SAH, 0 if not applicable */
    double mean_leaf_prims;       /* over non-empty leaves / cells */
    uint32_t empty_leaves;
    uint32_t res[3];              /* grids: resolution; 0 otherwise */
    /* lazy builds (opt.lazy): the subtrees no ray has entered yet and the primitive references they
     * hold; nodes, leaves, max_depth and prim_refs count what is built so far, so that
     * prim_refs / (prim_refs + unbuilt_prims) is the fraction built.  0 for eager builds */
    uint32_t unbuilt;
    uint64_t unbuilt_prims;
} sidx_accel_stats;

/* Builds structure `name` over mesh.  opt may be NULL.  On failure *out is
 * NULL and nothing is leaked.  Errors: SIDX_ERR_INVALID_ARG (NULL args),
 * SIDX_ERR_UNKNOWN_ACCEL, SIDX_ERR_BAD_GEOMETRY (mesh fails
 * sidx_mesh_validate), SIDX_ERR_NOMEM, SIDX_ERR_LIMIT. */
sidx_status sidx_accel_build(const char *name, const sidx_mesh *mesh, const sidx_build_options *opt,
                             sidx_accel **out, sidx_error *err);

/* "auto": picks structure and builder from the mesh's statistics and says
 * why through a NOTE event on opt->hook; same contract as sidx_accel_build. */
sidx_status sidx_accel_auto(const sidx_mesh *mesh, const sidx_build_options *opt, sidx_accel **out, sidx_error *err);

/* Closest hit in [ray.tmin, ray.tmax).  q may be NULL.  The ray must come
 * from sidx_ray_init or sidx_ray_spawn(_to), which refuse bad rays and fill
 * the fields the walks read (1/d, signs, shear): its fields are the
 * library's, read-only to the caller.  A ray filled in by hand (an all-zero
 * struct, 1/d that is not the reciprocal of d) is not checked per query —
 * that would cost every ray — and its answer is undefined.  *hit is always
 * written (sidx_hit_none() on a miss).  Fails on NULL arguments, and on a
 * lazy build (opt.lazy) with SIDX_ERR_NOMEM when the subtree the ray
 * enters cannot be built for want of memory: the hit is then not to be
 * used (the ray skipped that subtree). */
sidx_status sidx_accel_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit);
/* Any hit in [tmin, tmax): *occluded = 1 if there is one; stops at the first.
 * Errors as sidx_accel_intersect. */
sidx_status sidx_accel_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, int *occluded);
/* n rays at once (same query for all); ray ids are q->ray_id + i.
 * hits[i] is what sidx_accel_intersect gives for rays[i], bit for bit,
 * and a traced query emits each ray's events in turn, exactly as n single
 * queries would.  bvh (and the bvh family but bvh-obb), bvh4 and bvh8 walk
 * an untraced buffer (of an eager tree) with a stream walk: the checks and
 * the choice of walk made once per call instead of once per ray
 * (docs/performance.md, "The stream entry"), optionally in another order
 * (SIDX_QUERY_REORDER).  On a bvh8 tree whose nodes and triangle blocks
 * take 8 MiB or more, closest-hit buffers with the watertight test
 * (the default) are walked 8 rays at a time, each advanced one node or
 * leaf in turn so that one ray's wait on memory overlaps the others'
 * work: the same hits, bit for bit, faster on trees out of cache, slower
 * on trees in cache (docs/performance.md, "Several rays in flight").  SIDX_STREAM_INFLIGHT=on or off in the environment when
 * the tree is built forces the choice (bvh4 and bvh8; tests and
 * measurements).  rays and hits may be NULL when
 * n is 0.  Errors: SIDX_ERR_INVALID_ARG (a NULL structure, or NULL arrays
 * with n > 0: nothing written); on a lazy tree SIDX_ERR_NOMEM when any
 * ray's query returned it (the other rays are answered, that ray's hit
 * is not to be used). */
sidx_status sidx_accel_intersect_n(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                   sidx_hit *hits);
/* n any-hit queries at once: occluded[i] is what sidx_accel_occluded
 * gives for rays[i] (1 or 0).  Same walk, events, options and errors as
 * sidx_accel_intersect_n. */
sidx_status sidx_accel_occluded_n(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                  int *occluded);

sidx_status sidx_accel_stats_get(const sidx_accel *a, sidx_accel_stats *s);
/* After moving vertices of the mesh in place: update bounds bottom-up.
 * SIDX_ERR_UNSUPPORTED for structures that must be rebuilt instead.
 * bvh-sbvh: each leaf is then bounded by its whole triangles (the part of
 * a cut triangle a reference stood for has no meaning once the triangle
 * moved), so hits stay exact but the spatial splits' gain is lost until
 * the tree is rebuilt. */
sidx_status sidx_accel_refit(sidx_accel *a, sidx_error *err);
void sidx_accel_destroy(sidx_accel *a);            /* NULL is fine */

/* ---- node labels -------------------------------------------------------
 * A built structure's nodes may carry short names, so that a lesson,
 * sidx-step, sidx-dot and sidx-view can call a node what a slide calls it
 * ("A", "L4": deck 000, "kD-Tree Example").  Labels are for display only:
 * no query reads them, traced or not.
 *
 * `node` is a node id as the events give it (BUILD_NODE, NODE_ENTER), below
 * sidx_accel_stats.nodes.  The structure keeps its own copy of `label`
 * (at most SIDX_LABEL_MAX - 1 bytes), allocated with the build's
 * allocator and freed by sidx_accel_destroy; NULL or "" removes the label.
 * Errors: SIDX_ERR_INVALID_ARG (a NULL structure, a node id out of range
 * or a structure without nodes, a label too long), SIDX_ERR_NOMEM; the
 * labels are unchanged then.  Set labels before the structure is shared
 * between threads: setting is not synchronised with reading them. */
#define SIDX_LABEL_MAX 32
sidx_status sidx_accel_set_node_label(sidx_accel *a, uint32_t node, const char *label, sidx_error *err);
/* The label of `node`, or NULL (no label, NULL structure).  Valid until
 * that label is set again or the structure is destroyed. */
const char *sidx_accel_node_label(const sidx_accel *a, uint32_t node);

/* sidx_accel_build for a mesh opened from `scene` (a built-in scene name,
 * "name:detail" or a file; NULL = none): built-in scenes that come with
 * their own tree get it, every other pairing is sidx_accel_build(name,
 * mesh, opt).  The one such scene today: "kd-slide" with "kdtree" gets the
 * tree of deck 000 "kD-Tree Example", split by split, its nodes labelled
 * A, B, C, D and L1..L5 as the slide labels them
 * (sidx_kdtree_build_from_splits).  Same errors as sidx_accel_build. */
sidx_status sidx_scene_accel_build(const char *scene, const char *name, const sidx_mesh *mesh,
                                   const sidx_build_options *opt, sidx_accel **out, sidx_error *err);

const char *sidx_accel_name(const sidx_accel *a);
const sidx_mesh *sidx_accel_mesh(const sidx_accel *a);
const sidx_build_options *sidx_accel_options(const sidx_accel *a);

/* The registry, in registration order. */
size_t sidx_accel_registered_count(void);
const char *sidx_accel_registered_name(size_t i);        /* NULL past the end */
const char *sidx_accel_registered_description(size_t i);
int sidx_accel_is_registered(const char *name);

#ifdef __cplusplus
}
#endif
#endif
