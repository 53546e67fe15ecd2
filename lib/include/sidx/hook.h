/* sidx/hook.h — the trace hooks, the heart of sidx.
 *
 * Every structure reports each build decision and each traversal step as a
 * typed sidx_event to an optional hook: a callback, a user pointer and a
 * mask of the event types it wants.  With no hook attached a structure runs
 * a copy of its hot loop in which every emit is compiled out (the loop is a
 * static inline template instantiated twice), so tracing costs nothing when
 * unused.  docs/events.md describes each field per event type.
 *
 * Strings in events (structure, text) point to static storage and stay valid
 * for the life of the program.  The one other pointer, `prims` (a leaf's
 * primitive ids on BUILD_LEAF), points into the structure's build arrays and
 * is valid only during the callback: a sink that keeps events must copy the
 * list (the recorder does).  Everything else is copied by value. */
#ifndef SIDX_HOOK_H
#define SIDX_HOOK_H

#include <stdint.h>
#include "math.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sidx_event_type {
    /* build */
    SIDX_EV_BUILD_BEGIN = 0, /* count = primitives, bounds = scene box */
    SIDX_EV_BUILD_NODE,      /* node created: node, parent, depth, bounds, count */
    SIDX_EV_BUILD_CANDIDATE, /* split candidate: node, axis, pos, cost, count = N_left, aux = N_right */
    SIDX_EV_BUILD_SPLIT,     /* chosen split: node, axis, pos, cost, count = N_left, aux = N_right */
    SIDX_EV_BUILD_LEAF,      /* leaf made: node, depth, count, cost, reason (sidx_leaf_reason),
                                prims = its count primitive ids */
    SIDX_EV_BUILD_END,       /* node = node count, count = primitive references, depth = max depth */
    /* traversal */
    SIDX_EV_RAY_BEGIN,       /* ray_id, t_near/t_far = [tmin, tmax] */
    SIDX_EV_NODE_ENTER,      /* node (or cell id), depth, t_near, t_far; cell[] for grids */
    SIDX_EV_BOX_TEST,        /* node, bounds, result, t_near, t_far */
    SIDX_EV_STACK_PUSH,      /* node, depth = stack size after, t_near, t_far */
    SIDX_EV_STACK_POP,       /* node, depth = stack size before, t_near, t_far */
    SIDX_EV_PRIM_TEST,       /* prim (original index), result, t (if hit) */
    SIDX_EV_HIT_UPDATE,      /* prim, t: the closest hit so far changed */
    SIDX_EV_MAILBOX_HIT,     /* prim: already tested for this ray, skipped */
    SIDX_EV_TERMINATE,       /* reason (sidx_term_reason), t = best hit, count = nodes/cells visited */
    SIDX_EV_RAY_END,         /* prim, t of the final hit (SIDX_NO_HIT / inf on a miss); result = 1 if
                                hit / occluded (occlusion queries fill only result) */
    SIDX_EV_NOTE,            /* free text: a decision that is not one of the above (text) */
    /* build, irregular grid (after NOTE so the older types keep their numbers) */
    SIDX_EV_BUILD_MERGE,     /* two neighbouring cells with the same triangles became one: node = the
                                final cell, axis, aux = the face they met at, count, cell[]/extent[] =
                                the merged box, bounds */
    SIDX_EV_BUILD_EXPAND,    /* a cell's expanded box grew by one step (result 1) or stopped (result 0;
                                reason 1 = too many cells to check): node, axis, aux = 1 towards
                                +axis / 0 towards -axis, count = cells grown, cell[]/extent[] = the
                                expanded box, bounds */
    /* build, tree optimisation (opt.optimize_ms; after the build's BUILD_END) */
    SIDX_EV_BUILD_REINSERT,  /* a subtree moved where it costs less (Bittner 2013): node = the subtree,
                                parent = its old parent (re-created over it and aux), aux = the node it
                                now sits beside, depth = its new depth, count = the pass (from 1),
                                cost = the SAH gain, bounds = its box.  Ids are those of the tree as
                                built (its BUILD_NODE ids), before the pass renumbers the nodes */
    /* build, lazy trees (opt.lazy): emitted during a query, on its hook */
    SIDX_EV_BUILD_LAZY_EXPAND, /* a ray entered an unbuilt node and its subtree is built now: node,
                                  parent, depth, count = the subtree's primitives, bounds; the subtree's
                                  BUILD_SPLIT / BUILD_NODE / BUILD_LEAF events follow (the node's own
                                  BUILD_NODE came with the build) */
    SIDX_EV_COUNT
} sidx_event_type;

#define SIDX_EVMASK(type) (1u << (type))
#define SIDX_EVMASK_BUILD                                                                           \
    (SIDX_EVMASK(SIDX_EV_BUILD_BEGIN) | SIDX_EVMASK(SIDX_EV_BUILD_NODE) |                          \
     SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE) | SIDX_EVMASK(SIDX_EV_BUILD_SPLIT) |                     \
     SIDX_EVMASK(SIDX_EV_BUILD_LEAF) | SIDX_EVMASK(SIDX_EV_BUILD_END) |                           \
     SIDX_EVMASK(SIDX_EV_BUILD_MERGE) | SIDX_EVMASK(SIDX_EV_BUILD_EXPAND) |                     \
     SIDX_EVMASK(SIDX_EV_BUILD_REINSERT) | SIDX_EVMASK(SIDX_EV_BUILD_LAZY_EXPAND))
#define SIDX_EVMASK_ALL ((1u << SIDX_EV_COUNT) - 1u)
#define SIDX_EVMASK_TRAVERSAL (SIDX_EVMASK_ALL & ~SIDX_EVMASK_BUILD)

typedef enum sidx_leaf_reason {
    SIDX_LEAF_NONE = 0,
    SIDX_LEAF_FEW_PRIMS,       /* count <= leaf size */
    SIDX_LEAF_NO_GAIN,         /* no split cheaper than the leaf (SAH termination) */
    SIDX_LEAF_MAX_DEPTH,       /* depth limit reached */
    SIDX_LEAF_NO_SPLIT,        /* all centroids equal / no valid plane */
    SIDX_LEAF_EMPTY,           /* empty cell (space partitioning) */
    SIDX_LEAF_GIVEN,           /* the caller's tree says leaf (sidx_kdtree_build_from_splits) */
    SIDX_LEAF_REASON_COUNT
} sidx_leaf_reason;

typedef enum sidx_term_reason {
    SIDX_TERM_NONE = 0,
    SIDX_TERM_MISS_ROOT,       /* the ray missed the root / grid box */
    SIDX_TERM_STACK_EMPTY,     /* nothing left to visit */
    SIDX_TERM_HIT_IN_CELL,     /* space partitioning: hit inside the current cell ends the walk */
    SIDX_TERM_ANY_HIT,         /* occlusion query: first hit is enough */
    SIDX_TERM_LEFT_GRID,       /* DDA walked out of the grid */
    SIDX_TERM_REASON_COUNT
} sidx_term_reason;

/* `result` of STACK_POP (and of a kd-tree's STACK_PUSH) where the walk
 * reports it; other walks leave it blank (-1).  docs/events.md. */
typedef enum sidx_stack_result {
    SIDX_STACK_DROPPED = 0,  /* pop: t_near lies beyond the best hit, the node is not entered */
    SIDX_STACK_ENTERED = 1,  /* pop: the node is entered */
    SIDX_STACK_IN_PLANE = 2  /* kd-tree: the ray lies in the split plane, both children are near (the push,
                                and the pop, which enters the node) */
} sidx_stack_result;

/* `result` of a kd-tree's NODE_ENTER at an inner node, with axis, pos =
 * the split plane and t = t_split: the case of "kD-Tree Traversal
 * Operation" the walk takes there.  docs/events.md. */
typedef enum sidx_split_case {
    SIDX_SPLIT_FAR_ONLY = 0,  /* t_split < t_near: the plane lies before the cell, far child only */
    SIDX_SPLIT_NEAR_ONLY = 1, /* t_split > t_far: the plane lies beyond the cell, near child only */
    SIDX_SPLIT_BOTH = 2       /* t_near <= t_split <= t_far: both, near then far (the far one on the stack) */
} sidx_split_case;

typedef struct sidx_event {
    sidx_event_type type;
    const char *structure; /* "bvh", "kdtree", ... (static) */
    uint32_t ray_id;       /* per-query id given in sidx_query; 0 for builds */
    uint32_t node;         /* node or cell id; UINT32_MAX when not applicable.  The same id in
                              build and traversal events (the index in the final node array) */
    uint32_t parent;       /* BUILD_NODE: parent node id; UINT32_MAX for the root */
    uint32_t depth;        /* tree depth, or stack size for push/pop; structures also fill it on
                              BOX_TEST, CANDIDATE, SPLIT, PRIM_TEST where known (printer indent) */
    uint32_t prim;         /* original primitive index; UINT32_MAX when not applicable */
    uint32_t count;        /* primitive count / N_left / nodes visited, by type */
    uint32_t aux;          /* N_right for candidates and splits */
    int32_t axis;          /* split axis 0..2, -1 when none; BSP: -1 and plane in bounds.min/pos */
    int32_t result;        /* 1 = hit / accepted, 0 = miss / rejected */
    int32_t reason;        /* sidx_leaf_reason or sidx_term_reason */
    int32_t cell[3];       /* grid cell coordinates (irregular grid: its finest level) */
    uint32_t extent[3];    /* irregular grid: finest-level cells the box at cell[] spans per axis;
                              0, 0, 0 when the event is about one cell of a regular grid or none */
    float pos;             /* split position */
    float cost;            /* SAH cost of a candidate / split / leaf */
    float t_near, t_far;   /* parametric interval */
    float t;               /* hit distance */
    sidx_aabb bounds;      /* node / cell bounds */
    const char *text;      /* NOTE events: static text; NULL otherwise */
    const uint32_t *prims; /* BUILD_LEAF: the leaf's `count` primitive ids (original triangle indices;
                              an aggregate's instance indices), in the leaf's order.  Valid only
                              during the callback: copy it to keep it.  NULL on other events, and
                              when count is 0 or the structure does not list them */
} sidx_event;

typedef void (*sidx_hook_fn)(const sidx_event *ev, void *user);

typedef struct sidx_hook {
    sidx_hook_fn fn;  /* NULL = no hook */
    void *user;       /* handed back to fn; per-ray state lives here */
    uint32_t mask;    /* SIDX_EVMASK(...) bits of the events fn wants; 0 means all */
} sidx_hook;

/* A blank event: all ids UINT32_MAX, axis -1, t = inf. */
sidx_event sidx_event_blank(sidx_event_type type);

const char *sidx_event_type_name(sidx_event_type t);   /* "node_enter", ... */
const char *sidx_leaf_reason_name(int reason);         /* "few_prims", ... */
const char *sidx_term_reason_name(int reason);         /* "stack_empty", ... */

/* Deliver ev to hook if attached and the mask wants it (for code that
 * emits events outside a structure, e.g. lessons and the traced tests). */
void sidx_hook_emit(const sidx_hook *hook, const sidx_event *ev);

/* Traced versions of the elementary tests: run the test, then emit a
 * PRIM_TEST / BOX_TEST event.  hook may be NULL. */
#include "intersect.h"
int sidx_trace_triangle(const sidx_hook *hook, sidx_tri_method m, uint32_t prim, const sidx_ray *r,
                        sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float tmax, float *t, float *u, float *v);
int sidx_trace_aabb(const sidx_hook *hook, sidx_box_method m, uint32_t node, const sidx_ray *r,
                    const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far);

#ifdef __cplusplus
}
#endif
#endif
