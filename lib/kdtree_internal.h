/* kdtree_internal.h — the kd-tree's memory layout, shared by the builder
 * (kdtree_build.c), the traversal (kdtree_traverse.c) and its test suite.
 *
 * Layout, point by point from the deck ("Compact (8-byte) Nodes", "No
 * Bounding Box!", "Memory Layout", "Other Data"):
 *
 *   - a node is 8 bytes: a 32-bit float split position and one 32-bit word
 *     holding the child index with the leaf flag / split axis "swept under
 *     the rug" into its lowest 2 bits: 0, 1, 2 = inner node splitting x, y,
 *     z; 3 = leaf.  (The deck stores a byte pointer whose low bits are free
 *     because nodes are 8-byte aligned; we store index << 2 instead, which
 *     is the same trick and addresses 2^30 nodes.)
 *   - the two children of a node sit side by side, left at `child`, right
 *     at `child + 1`, so one index suffices;
 *   - a leaf keeps (primitive count, offset into a separate primitive-index
 *     array) in the same 8 bytes: the count in the first word (where an
 *     inner node has its split), the offset in the upper 30 bits of the
 *     second;
 *   - no node stores a box: traversal carries the cell implicitly as the
 *     ray interval [t_near, t_far];
 *   - nodes are written depth first as the build recurses, sibling pairs
 *     allocated together, so a subtree is one contiguous run of memory;
 *   - the leaves' triangles are copied, one copy per *reference*, into
 *     blocks of four in structure-of-arrays form (`blocks`, tri4_block,
 *     tri4.h, the wide BVH's leaf blocks too): reference i of the leaf array sits
 *     in block i / 4, lane i % 4.  The leaf's node already holds its
 *     reference offset, so a leaf reads its blocks directly: no index to
 *     chase ("Memory should be separated by rate of access": traversal
 *     steps touch only the 8-byte nodes, leaves only their blocks).  One
 *     SSE pass then runs the watertight test on four references at once
 *     (tri4_test, bit-identical to the scalar test but for the sign
 *     of a zero t).  The blocks are cut from the reference array, not per
 *     leaf, so a leaf's first and last block may hold neighbouring leaves'
 *     triangles: the traversal masks those lanes off (tri4_test_lanes),
 *     so a leaf tests its own triangles only, as the slides' leaf does,
 *     and a trace never shows a hit on a triangle the leaf does not list.
 *     This costs 40 bytes per reference, which the SIMD test pays for
 *     (docs/performance.md, kd-tree); `prims` keeps the original triangle
 *     ids per reference for the public view (sidx_kdtree_refs).
 *
 * Node ids in BUILD_* and traversal events are indices in `nodes`. */
#ifndef SIDX_KDTREE_INTERNAL_H
#define SIDX_KDTREE_INTERNAL_H

#include "sidx_internal.h"
#include "sidx/kdtree.h"
#include "tri4.h" /* tri4_block, tri4_test */
#include "lazy.h"

/* Low 2 bits of kd_node.bits: the split axis, or 3 for a leaf. */
#define KD_LEAF_FLAG 3u
/* The encoding addresses child indices and leaf offsets below 2^30;
 * larger scenes are refused with SIDX_ERR_LIMIT. */
#define KD_INDEX_LIMIT (1u << 30)
/* Hard ceiling on tree depth: it sizes the traversal stack (each level
 * pushes at most one far child), so opt.max_depth is clamped to it. */
#define KD_MAX_DEPTH 64u

/* The node is the public sidx_kd_node (sidx/kdtree.h), so that
 * sidx_kdtree_nodes can hand out the tree's own array:
 *   u.split  inner: split plane position on `axis`
 *   u.count  leaf: number of primitive references
 *   bits     inner: child << 2 | axis;  leaf: offset << 2 | 3 */
typedef sidx_kd_node kd_node;
_Static_assert(KD_LEAF_FLAG == SIDX_KD_LEAF, "one leaf flag");

_Static_assert(sizeof(kd_node) == 8, "the deck's compact kd-tree node is 8 bytes");

static inline int kd_is_leaf(const kd_node *n) { return (n->bits & 3u) == KD_LEAF_FLAG; }
static inline uint32_t kd_axis(const kd_node *n) { return n->bits & 3u; }
static inline uint32_t kd_child(const kd_node *n) { return n->bits >> 2; }    /* left; right = +1 */
static inline uint32_t kd_offset(const kd_node *n) { return n->bits >> 2; }   /* into kd_tree.prims */
static inline uint32_t kd_count(const kd_node *n) { return n->u.count; }
/* An empty leaf is always written with offset 0 (kd_make_leaf), so all
 * 8 bytes of it are one fixed pattern: the traversal, which peeks at both
 * children at every step, tests it with a single 64-bit compare. */
static inline uint64_t kd_word(const kd_node *n)
{
    uint64_t w;
    memcpy(&w, n, sizeof w);
    return w;
}
static inline uint64_t kd_word_empty(void)
{
    const kd_node empty = {{.count = 0u}, KD_LEAF_FLAG};
    return kd_word(&empty);
}
static inline int kd_is_empty(const kd_node *n) { return kd_word(n) == kd_word_empty(); }

static inline kd_node kd_make_inner(uint32_t axis, float split, uint32_t child)
{
    kd_node n;
    n.u.split = split;
    n.bits = (child << 2) | axis;
    return n;
}
static inline kd_node kd_make_leaf(uint32_t count, uint32_t offset)
{
    kd_node n;
    n.u.count = count;
    n.bits = ((count ? offset : 0u) << 2) | KD_LEAF_FLAG; /* empty: offset 0, see kd_is_empty */
    return n;
}

/* One triangle for the builder (clipping): its vertices and its original id. */
typedef struct kd_tri {
    sidx_vec3 v0, v1, v2;
    uint32_t prim;
} kd_tri;

struct kd_lazy;

typedef struct kd_tree {
    kd_node *nodes;         /* inside nodes_mem, node 1 on a cache-line start (kdtree_build.c) */
    void *nodes_mem;
    uint32_t num_nodes;
    uint32_t *prims;        /* leaf primitive references (original triangle ids), for the public view */
    uint32_t num_refs;
    tri4_block *blocks;      /* reference i in blocks[i / 4], lane i % 4; 64-byte aligned in blocks_mem */
    void *blocks_mem;
    uint32_t num_blocks;    /* (num_refs + 3) / 4; padding lanes have NaN vertices, TRI4_PAD_PRIM */
    sidx_aabb bounds;       /* the root cell: the scene box */
    /* statistics, filled by the build */
    uint32_t leaves, empty_leaves, max_depth;
    double sah_cost;
    float c_trav, c_tri, empty_bonus;   /* the constants actually used */
    /* Event ids of the nodes (kd_id): node 0 is root_id, node i > 0 is
     * id_base + i − 1.  The whole tree: 0 and 1, so an id is the index.
     * A lazy tree's expanded subtree: its root keeps the id of the unbuilt
     * node it replaces, the others get ids after those in use (kd_lazy). */
    uint32_t root_id, id_base;
    struct kd_lazy *lazy;   /* lazy trees only (opt.lazy); NULL when every node is built at once */
} kd_tree;

static inline uint32_t kd_id(const kd_tree *t, uint32_t node) { return node ? t->id_base + node - 1u : t->root_id; }

/* Lazy trees (opt.lazy).  The build stops at every node of at most
 * opt.lazy references that would not be a leaf anyway and writes it as an
 * unbuilt node: a leaf word whose count is KD_LAZY_COUNT (no leaf holds
 * that many) and whose offset is the index r of its record below.  The
 * record keeps what the build would have recursed with: the cell, depth,
 * parent, the look-ahead count and the node's input (its three sorted
 * event lists for the SAH builder, its clipped reference boxes for the
 * others).
 *
 * Each record is one part of lazy.c (lazy.h), which owns its life: claim,
 * wait, publish, failure and the counters.  The part's expand function
 * (kdtree_build.c) builds the subtree with the same recursion and
 * parameters on the record's input, into arrays of its own (a kd_tree
 * whose node 0 is the unbuilt node's subtree root): the eager tree's
 * subtree, node for node, split for split, leaf for leaf, with the leaf
 * references in the same order.  A kd-tree's subtree size is known only
 * once it is built (straddling triangles are duplicated), so it cannot be
 * given slots in the top tree's arrays beforehand.  Neither the top tree's
 * nodes nor a published subtree are ever written again.
 *
 * The walk: an unbuilt node is a leaf to the eager walk's tests; the lazy
 * copies of the walks read their nodes through a fetch that, meeting the
 * mark, takes the subtree from sidx__lazy_get and goes on at its node 0
 * (kdtree_traverse.c, kd_fetch).  Out of memory: nothing is published, the
 * walk passes the node over as an empty leaf and the query returns
 * SIDX_ERR_NOMEM (lazy.c); a later ray tries again.
 *
 * Event ids: an untraced expansion needs none, and takes its range
 * (id_base) from lazy->next_id once the subtree's size is known.  A query
 * with a build hook then runs the same build a second time with those
 * ids, for its events alone (kdtree_build.c, expand_build), so the ids of
 * a fully expanded tree are 0 .. the eager tree's node count − 1. */
#define KD_LAZY_COUNT 0xFFFFFFFFu

typedef struct kd_lazy_rec {
    uint32_t node, parent, depth;   /* the unbuilt node's id, its parent's and its depth */
    uint32_t count, bad;            /* its references; the look-ahead count on its path */
    sidx_aabb cell;
    void *input;                    /* SAH: 3 sorted event lists, cnt[k] long; else count kd_refs */
    size_t cnt[3];
} kd_lazy_rec;

typedef struct kd_lazy {
    sidx__lazy life;                /* part r: the subtree of recs[r] (lazy.h) */
    sidx__lazy_part *parts;         /* num_recs, for life */
    kd_lazy_rec *recs;
    uint32_t num_recs;
    kd_tri *tris;                   /* the build's triangle copies, kept for the expansions' clipping */
    uint32_t leaf_size, max_depth, bins; /* the build's resolved parameters */
    uint32_t next_id;               /* the next free event id; atomic */
} kd_lazy;

static inline kd_node kd_make_unbuilt(uint32_t rec)
{
    kd_node n;
    n.u.count = KD_LAZY_COUNT;
    n.bits = (rec << 2) | KD_LEAF_FLAG;
    return n;
}
static inline int kd_is_unbuilt(const kd_node *n) { return kd_is_leaf(n) && n->u.count == KD_LAZY_COUNT; }

/* Registry variants (a->variant). */
enum {
    KD_VARIANT_SAH = 0,     /* "kdtree": exact SAH, Wald & Havran 2006 event sweep */
    KD_VARIANT_BINNED = 1,  /* "kdtree-binned": binned SAH */
    KD_VARIANT_MEDIAN = 2,  /* "kdtree-median": largest extent, median of geometry */
    KD_VARIANT_MIDDLE = 3,  /* "kdtree-middle": largest extent, middle of the cell */
    KD_VARIANT_GIVEN = 4    /* sidx_kdtree_build_from_splits: the caller's splits (named "kdtree") */
};

/* Defaults.  The SAH's C_trav : C_tri is the cost of a kd step against a
 * triangle test: a step is one dependent load-subtract-multiply-compare
 * chain that mostly waits on memory ("Latency can harm you!"), and a leaf
 * reference costs about a quarter of a scalar test since leaves are tested
 * four references per SSE pass, so steps are dear and larger leaves pay:
 * 16 : 1, against the deck's 1 : 1.5.  The empty bonus is Wald &
 * Havran's λ = 0.8 (bonus 0.2, applied to the whole cost); 0.5 spends the
 * depth limit on thin empty slabs.  Leaf size 1 (pbrt) lets the SAH alone decide; the intuitive
 * builders, which have no cost to stop them, stop at 4.  Measurements and
 * the values rejected: docs/performance.md, kd-tree. */
#define KD_DEFAULT_C_TRAV 16.0f
#define KD_DEFAULT_C_TRI 1.0f
#define KD_DEFAULT_EMPTY_BONUS 0.2f
#define KD_DEFAULT_LEAF_SAH 1u
#define KD_DEFAULT_LEAF_INTUITIVE 4u

sidx_status sidx__kd_build(sidx_accel *a, sidx_error *err);
/* (Re)make kd->blocks from kd->prims and the mesh (also used by the tests'
 * hand-made trees).  SIDX_ERR_NOMEM leaves kd->blocks NULL. */
sidx_status sidx__kd_make_blocks(const sidx_accel *a, kd_tree *kd, const sidx_mesh *m);
void sidx__kd_destroy(sidx_accel *a);
/* The build's "perfect split" clipping: the bounds of triangle t ∩ cell
 * (exercise 09's checker hands a child cell's clipped boxes to the student). */
sidx_aabb sidx__kd_clip_bounds(const kd_tri *t, sidx_aabb cell);
void sidx__kd_stats(const sidx_accel *a, sidx_accel_stats *s);

#endif
