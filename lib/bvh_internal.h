/* bvh_internal.h — the BVH's private data layout, shared by bvh_build.c,
 * bvh_traverse.c and bvh_obb.c.  Not part of the library's interface.
 *
 * Layout (the deck's "After re-indexing (sorting) based on leaf nodes ...
 * Only need to store 2 integers per leaf node!"):
 *
 *   nodes[]    flattened 32-byte nodes in depth-first (pre-)order.  An inner
 *              node's left child is the next node (index + 1), its right
 *              child index is stored; a leaf stores (first, count) into
 *   prim_id[]  the primitive index array reordered so each leaf's
 *              primitives are contiguous: prim_id[i] = ORIGINAL triangle
 *              index, which is what hits report;
 *   tris[]     a copy of the three vertices of prim_id[i], in the same
 *              order, so a leaf test reads one contiguous run of memory
 *              instead of chasing mesh->indices -> mesh->positions.
 *
 * Node ids in build and traversal events are indices into nodes[]. */
#ifndef SIDX_BVH_INTERNAL_H
#define SIDX_BVH_INTERNAL_H

#include "sidx_internal.h"
#include "lazy.h"

/* Deepest tree a build may produce; it also sizes the traversal's fixed
 * stack (an ordered descent keeps at most one deferred sibling per level),
 * so the traversal never allocates and never overflows.  opt.max_depth
 * above this is clamped to it. */
#define BVH_DEPTH_LIMIT 64u

/* The deck: "Recurse until few primitives (< 4) left in node".  A node of
 * at most BVH_DEFAULT_LEAF_SIZE primitives becomes a leaf (opt.leaf_size
 * overrides: leaf when count <= leaf_size). */
#define BVH_DEFAULT_LEAF_SIZE 3u

/* SAH termination ("split only while splitting helps") may leave a node
 * as a leaf only up to this many primitives (or leaf_size if larger);
 * above it the best split is taken even when the SAH says it does not pay,
 * so leaves stay small enough that no ray tests thousands of triangles
 * because of one pessimistic estimate (pbrt-v3 does the same with its
 * maxPrimsInNode). */
#define BVH_MAX_LEAF 16u

/* Node count field: low 30 bits = primitive count (0 for an inner node),
 * top 2 bits = split axis of an inner node (for sign-based ordering and
 * the viewers). */
#define BVH_COUNT_MASK 0x3FFFFFFFu
#define BVH_AXIS_SHIFT 30

typedef struct bvh_node {
    float bmin[3];
    uint32_t left_or_first; /* inner: right child index; leaf: first index into prim_id/tris */
    float bmax[3];
    uint32_t count_axis;    /* leaf: count (> 0); inner: axis << 30 */
} bvh_node;
_Static_assert(sizeof(bvh_node) == 32, "two BVH nodes per 64-byte cache line");

/* The three vertices of one triangle, packed: a run of tris[] is also a
 * run of 3·count sidx_vec3, which the OBB fit reads directly. */
typedef struct bvh_tri {
    sidx_vec3 v[3];
} bvh_tri;
_Static_assert(sizeof(bvh_tri) == 9 * sizeof(float), "bvh_tri must be three packed vec3");

/* An oriented box as three slabs: lo[k] <= axis[k]·x <= hi[k]. */
typedef struct bvh_obb {
    sidx_vec3 axis[3];
    float lo[3], hi[3];
} bvh_obb;

typedef enum bvh_builder {
    BVH_BINNED = 0, /* "bvh":        binned SAH (Wald 2007) */
    BVH_SWEEP,      /* "bvh-sweep":  full SAH sweep over sorted centroids */
    BVH_EVERYB,     /* "bvh-everyb": SAH sweep evaluated every B-th position */
    BVH_MEDIAN,     /* "bvh-median": equal counts on the largest centroid axis */
    BVH_MIDDLE,     /* "bvh-middle": middle of the centroid extent */
    BVH_OBB,        /* "bvh-obb":    binned SAH topology + PCA oriented boxes */
    BVH_SBVH,       /* "bvh-sbvh":   binned SAH with spatial splits (bvh_spatial.c) */
    BVH_BUILDER_COUNT
} bvh_builder;

/* The walk tables (sidx_internal.h §1): one per traversal, and for the
 * stack walk a second one for queries asking for u, v or the normal. */
typedef enum bvh_walk_kind {
    BVH_WALK_NAIVE,
    BVH_WALK_ORDERED,
    BVH_WALK_STACK,
    BVH_WALK_STACK_ATTRS,
    BVH_WALK_COUNT
} bvh_walk_kind;

/* Lazy trees (opt.lazy).  An unbuilt node keeps its box and holds
 * count_axis = BVH_LAZY_MARK | r for good, r the index of its part (axis 3
 * never occurs on an inner node, and a leaf's count stays below 2^30, so
 * the mark is unambiguous).  Its life — claim, wait, publish, failure, the
 * counters — is lazy.c's (lazy.h), one sidx__lazy_part per unbuilt node;
 * what bvh_build.c hands it is the expand function, which builds the
 * subtree with the same builder on the same, identically ordered,
 * primitives the eager build would have at that node (the tree is the
 * eager one, node for node, at other indices).
 *
 * The part: the subtree's root, a node of its own that the expansion
 * returns and lazy.c publishes.  Below it the subtree fills the 2·count − 2
 * slots the unbuilt node reserved after itself in nodes[] (a binary tree
 * over count primitives has at most 2·count − 1 nodes) and its primitives'
 * run prim_id[first, first + count) and tris[]: memory no walk reads before
 * it has the root, which it gets through lazy.c's acquire, so nothing the
 * rest of the tree is read through is written (lazy.h, "build").  The walk
 * reaches it through its node fetch (bvh_traverse.c): a walk over a lazy
 * tree is the eager walk with nodes[i] swapped for bvh_lazy_node.
 *
 * Out of memory: the expansion gives back what it took and writes nothing,
 * lazy.c puts the part back to unbuilt and marks the query (it returns
 * SIDX_ERR_NOMEM), and the walk stands on void_leaf instead: one
 * degenerate triangle at the origin (tris[num_prims]), which every
 * triangle test misses (zero edges, zero determinant). */
#define BVH_LAZY_MARK 0xC0000000u
#define BVH_LAZY_MAX_RECS 0x3FFFFFFEu

typedef struct bvh_lazy_rec {
    uint32_t node, parent, depth;   /* the unbuilt node, its parent and depth (for the events) */
    uint32_t first, count;          /* its primitives: prim_id[first, first + count) */
} bvh_lazy_rec;

typedef struct bvh_lazy {
    sidx__lazy life;                /* one part per record (lazy.c) */
    bvh_lazy_rec *recs;
    uint32_t num_recs;
    sidx_aabb *pbox;                /* the build's per-triangle boxes and centroids, kept for the expansions */
    sidx_vec3 *cent;
    uint32_t top_nodes, top_leaves; /* what the build made before any ray */
    uint32_t part_leaves;           /* leaves the expansions made (atomic: stats read it) */
    bvh_node void_leaf;             /* where a walk stands when an expansion failed */
} bvh_lazy;

typedef struct bvh {
    bvh_node *nodes;        /* 64-byte aligned inside nodes_mem */
    void *nodes_mem;
    uint32_t num_nodes;
    uint32_t num_leaves;
    uint32_t max_depth;     /* deepest node built */
    uint32_t num_prims;
    uint32_t *prim_id;      /* reordered original triangle indices */
    bvh_tri *tris;          /* vertices in prim_id order */
    bvh_obb *obbs;          /* bvh-obb only: one per node; NULL otherwise */
    double sah_cost;
    float obb_pad;          /* absolute padding of the oriented slabs (bvh-obb) */
    const sidx__walk_table *walks; /* [BVH_WALK_COUNT]: the copies for its box kind (sidx__bvh_pick_walks) */
    bvh_lazy *lazy;         /* lazy trees only; NULL when every node is built at once */
} bvh;

/* The node a walk over a lazy tree stands on when it reaches node n: n
 * itself, or for an unbuilt node its part's root, built now if no ray
 * reached it before (lazy.c: one acquire load once built), void_leaf when
 * that build could not get its memory. */
static SIDX_INLINE const bvh_node *bvh_lazy_node(const bvh *b, const bvh_node *n, const sidx_hook *hook)
{
    if (SIDX_LIKELY(n->count_axis < BVH_LAZY_MARK)) return n;
    const bvh_node *root = sidx__lazy_get(&b->lazy->life, n->count_axis & BVH_COUNT_MASK, hook);
    return root ? root : &b->lazy->void_leaf;
}

/* bvh_traverse.c: the vtable's entries, and the choice of walks the
 * build makes once its tree (and whether it has oriented boxes) is final. */
void sidx__bvh_pick_walks(bvh *b);
void sidx__bvh_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit);
int sidx__bvh_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q);

/* parallel.c: the binned-SAH build on opt.threads threads, producing the
 * same tree as bvh_build.c's recursive build (bvh_build.c calls it for
 * "bvh" whenever no build hook is attached, threads = 0 or 1 included).  The parameters are the
 * builder's resolved options. */
typedef struct bvh_par_params {
    uint32_t leaf_size, max_leaf, max_depth, bins;
    float c_trav, c_tri;
} bvh_par_params;
sidx_status sidx__bvh_build_parallel(sidx_accel *a, const bvh_par_params *p, sidx_error *err);

/* Those parameters from a->opt, defaults filled in and clamped: one
 * reading for bvh_build.c (and so parallel.c) and bvh_spatial.c. */
static inline bvh_par_params bvh_params(const sidx_accel *a)
{
    bvh_par_params p;
    p.leaf_size = a->opt.leaf_size ? a->opt.leaf_size : BVH_DEFAULT_LEAF_SIZE;
    p.max_leaf = p.leaf_size > BVH_MAX_LEAF ? p.leaf_size : BVH_MAX_LEAF;
    p.max_depth = (a->opt.max_depth && a->opt.max_depth < BVH_DEPTH_LIMIT) ? a->opt.max_depth : BVH_DEPTH_LIMIT;
    /* Bins: 2 is the fewest that gives a plane; above 1024 binning stops
     * being cheaper than the sweep it approximates. */
    p.bins = a->opt.bins ? a->opt.bins : 32u;
    if (p.bins < 2) p.bins = 2;
    if (p.bins > 1024) p.bins = 1024;
    p.c_trav = a->opt.c_trav > 0.0f ? a->opt.c_trav : 1.0f;
    p.c_tri = a->opt.c_tri > 0.0f ? a->opt.c_tri : 1.0f;
    return p;
}

/* bvh_spatial.c: the binary tree with spatial splits (SBVH) that bvh4 and
 * bvh8 collapse; prim_id[] holds references (a triangle may be in several
 * leaves), tris[] is NULL and the nodes are not aligned (only the collapse
 * reads the tree).  Reads a->opt like bvh_build.c; sets a->impl. */
typedef struct sidx__sbvh_lazy sidx__sbvh_lazy;
sidx_status sidx__bvh_build_spatial(sidx_accel *a, uint32_t lazy_max, uint32_t lazy_min, sidx__sbvh_lazy **lazy,
                                    sidx_error *err);

/* Lazy builds of that tree (lazy_max > 0 and lazy != NULL): every subtree
 * of more than lazy_min and at most lazy_max references is left as a
 * placeholder node, count_axis = BVH_LAZY_MARK | r and left_or_first = its
 * reference count, record r of *lazy keeping what its build needs.
 * sidx__sbvh_lazy_build builds record r's subtree as a tree of its own
 * (the eager build's subtree at that node, node for node), callable from
 * any thread, once per record at a time; sidx__sbvh_lazy_release frees
 * the record's copy of its references once its subtree is built for good. */
uint32_t sidx__sbvh_lazy_count(const sidx__sbvh_lazy *L);

/* bvh_spatial.c: "bvh-sbvh", that tree as a binary BVH the walks of
 * bvh_traverse.c read: SAH counts not rounded to blocks, nodes aligned,
 * tris[] filled (one copy per reference), sah_cost set, build events on
 * a->opt.hook.  prim_id[] holds references (num_prims >= triangles). */
sidx_status sidx__bvh_build_sbvh(sidx_accel *a, sidx_error *err);
sidx_status sidx__sbvh_lazy_build(const sidx_accel *a, sidx__sbvh_lazy *L, uint32_t r, bvh **out);
void sidx__sbvh_lazy_release(const sidx_accel *a, sidx__sbvh_lazy *L, uint32_t r);
void sidx__sbvh_lazy_free(const sidx_accel *a, sidx__sbvh_lazy *L);

/* bvh_sah.c: the tree's expected cost under the SAH (stats sah_cost). */
double sidx__bvh_tree_sah(const bvh *b, float c_trav, float c_tri);

/* bvh_optimize.c: reinsertion (Bittner et al. 2013) over a built binary
 * tree when a->opt.optimize_ms > 0; returns the moves made (each one a
 * BUILD_REINSERT event on a->opt.hook).  Leaves keep their primitives;
 * the nodes are renumbered, sah_cost recomputed, OBBs refitted.  Without
 * the memory for its scratch it leaves the tree as built. */
uint32_t sidx__bvh_optimize(const sidx_accel *a, bvh *b);

/* bvh_obb.c: fit one oriented box per node (after nodes/tris are final). */
sidx_status sidx__bvh_fit_obbs(const sidx_accel *a, bvh *b);

static SIDX_INLINE int bvh_is_leaf(const bvh_node *n) { return (n->count_axis & BVH_COUNT_MASK) != 0; }
static SIDX_INLINE uint32_t bvh_count(const bvh_node *n) { return n->count_axis & BVH_COUNT_MASK; }
static SIDX_INLINE int bvh_axis(const bvh_node *n) { return (int)(n->count_axis >> BVH_AXIS_SHIFT); }

static inline sidx_aabb bvh_node_box(const bvh_node *n)
{
    sidx_aabb b = {{n->bmin[0], n->bmin[1], n->bmin[2]}, {n->bmax[0], n->bmax[1], n->bmax[2]}};
    return b;
}

/* What the fast slab test needs from a ray, computed once per query. */
typedef struct bvh_ray {
    float org[3], inv[3];
    /* Byte offsets of the near / far plane of each axis inside a node:
     * bmin sits at offset 0 and bmax at offset 16, so a negative
     * direction simply reads the planes the other way round.  This is the
     * ray's sign[] turned into addresses: no branch and no swap per box. */
    uint32_t near_off[3], far_off[3];
} bvh_ray;

static SIDX_INLINE void bvh_ray_setup(bvh_ray *br, const sidx_ray *r)
{
    const float *o = sidx_v3_array(&r->org), *inv = sidx_v3_array(&r->inv_dir);
    for (int k = 0; k < 3; ++k) {
        br->org[k] = o[k];
        br->inv[k] = inv[k];
        br->near_off[k] = (uint32_t)(r->sign[k] ? 16 + 4 * k : 4 * k);
        br->far_off[k] = (uint32_t)(r->sign[k] ? 4 * k : 16 + 4 * k);
    }
}

/* Slab test of one node over [tmin, tmax] (Kay & Kajiya 1986), the same
 * arithmetic as sidx__box_test: t = (plane − o)·(1/d).  Written as
 * `x > y ? x : y` on purpose: that is exactly the x86 maxss/minss operand
 * order, so the compiler emits branch-free min/max, and a NaN slab value
 * (origin exactly on a plane of an axis the ray is parallel to: 0·inf)
 * never narrows the interval, as in the reference test.  tf_scale is
 * SIDX_ROBUST_TFAR_SCALE for the robust test (Ize 2013: t_far times
 * 1 + 2γ₃ so float rounding never loses a hit) and exactly 1 for the plain
 * one: a multiply by 1 is exact, so one copy of the loop serves both. */
static SIDX_INLINE int bvh_slab(const bvh_ray *br, const bvh_node *n, const float tf_scale, float tmin, float tmax,
                                float *t_near, float *t_far)
{
    const char *base = (const char *)n;
    float tn0, tn1, tn2, tf0, tf1, tf2;
    float p;
    memcpy(&p, base + br->near_off[0], sizeof p);
    tn0 = (p - br->org[0]) * br->inv[0];
    memcpy(&p, base + br->near_off[1], sizeof p);
    tn1 = (p - br->org[1]) * br->inv[1];
    memcpy(&p, base + br->near_off[2], sizeof p);
    tn2 = (p - br->org[2]) * br->inv[2];
    memcpy(&p, base + br->far_off[0], sizeof p);
    tf0 = (p - br->org[0]) * br->inv[0];
    memcpy(&p, base + br->far_off[1], sizeof p);
    tf1 = (p - br->org[1]) * br->inv[1];
    memcpy(&p, base + br->far_off[2], sizeof p);
    tf2 = (p - br->org[2]) * br->inv[2];
    float t0 = tmin, t1 = tmax;
    t0 = tn0 > t0 ? tn0 : t0;
    t0 = tn1 > t0 ? tn1 : t0;
    t0 = tn2 > t0 ? tn2 : t0;
    t1 = tf0 < t1 ? tf0 : t1;
    t1 = tf1 < t1 ? tf1 : t1;
    t1 = tf2 < t1 ? tf2 : t1;
    /* Scale after the min: rounding is monotonic, so S·min(a, b) is
     * exactly min(S·a, S·b) and one multiply does the work of three.  It
     * also widens tmax — the best hit so far — by the same factor: a
     * triangle an ulp nearer than the best hit may sit in a box whose
     * ROUNDED entry lands an ulp beyond it, and comparing the entry with
     * the unwidened best would drop that box and keep the farther hit.
     * The triangle test still bounds hits strictly by the best t. */
    t1 *= tf_scale;
    *t_near = t0;
    *t_far = t1;
    return t0 <= t1;
}

/* Ray against an oriented box: clip [tmin, tmax] by its three slabs.  A
 * ray parallel to a slab (axis·d = 0) is inside it or never.  The slabs
 * are padded when fitted (bvh_obb.c), which is what keeps this test from
 * losing hits to rounding; it costs two dot products and a division per
 * axis against the AABB's one subtraction and multiply — the deck's
 * "larger intersection cost for non-aligned bboxes". */
static SIDX_INLINE int bvh_obb_test(const sidx_ray *r, const bvh_obb *b, float tmin, float tmax, float *t_near,
                                    float *t_far)
{
    float t0 = tmin, t1 = tmax;
    for (int k = 0; k < 3; ++k) {
        const float nd = sidx_v3_dot(b->axis[k], r->dir), no = sidx_v3_dot(b->axis[k], r->org);
        if (nd == 0.0f) { /* outside a slab it runs parallel to: never inside the box */
            if (no < b->lo[k] || no > b->hi[k]) { t0 = INFINITY; t1 = -INFINITY; }
            continue;
        }
        const float inv = 1.0f / nd;
        float ta = (b->lo[k] - no) * inv, tb = (b->hi[k] - no) * inv;
        if (ta > tb) { const float tmp = ta; ta = tb; tb = tmp; }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
    }
    *t_near = t0;
    *t_far = t1;
    return t0 <= t1;
}

/* Bin of centroid coordinate c: the same expression when binning and when
 * partitioning, so both agree on every primitive. */
static inline uint32_t bin_of(float c, float cmin, float scale, uint32_t nb)
{
    const float f = (c - cmin) * scale;
    /* Clamp in float before converting: with a tiny centroid extent the
     * scale overflows to inf, and converting inf to an integer is
     * undefined (found by fuzz_build). NaN goes to bin 0. */
    if (!(f > 0.0f)) return 0u;
    if (f >= (float)nb) return nb - 1;
    return (uint32_t)f;
}

/* ---- the stream entry (bvh_stream.c) ---------------------------------------
 * sidx_accel_intersect_n / _occluded_n on a bvh-family tree, bvh4 or bvh8
 * (untraced, eager): bvh_stream.c picks the structure's stream walk once
 * per call, and one call of it runs the buffer's rays one after another,
 * each through the single-ray walk with no entry checks and no choice of
 * walk per ray.  Ray i of the walk is rays[idx[i]] (rays[i] when idx is
 * NULL); its answer goes to hits[] (closest hit: set up and finished as
 * sidx_accel_intersect does) or occluded[] (any hit) at the same place. */
typedef struct bvh_stream_rays {
    const sidx_ray *rays;
    const uint32_t *idx;
    uint32_t count;
    sidx_hit *hits;
    int *occluded;
} bvh_stream_rays;
typedef void (*bvh_stream_fn)(const sidx_accel *a, const sidx_query *q, const bvh_stream_rays *c);
/* bvh_traverse.c: the stack walk over a buffer (AABB, eager trees). */
void sidx__bvh_stream_isect(const sidx_accel *a, const sidx_query *q, const bvh_stream_rays *c);
void sidx__bvh_stream_isect_attrs(const sidx_accel *a, const sidx_query *q, const bvh_stream_rays *c);
void sidx__bvh_stream_occl(const sidx_accel *a, const sidx_query *q, const bvh_stream_rays *c);

#endif
