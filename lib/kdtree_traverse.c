/* kdtree_traverse.c — front-to-back kd-tree traversal with a stack of
 * (node, t_near, t_far), deck 000 "kD-Tree Traversal", "kD-Tree Traversal
 * (1)-(11)", "kD-Tree Traversal Operation" and "kD-Tree Traversal: Inner
 * Loop".
 *
 * The ray is clipped to the scene box once; after that the current cell
 * is only implicit, as the ray's interval [t_near, t_far] inside it.  At
 * an inner node t_split = (split − o[axis]) · inv_dir[axis] is compared
 * with that interval: only the far child, only the near child, or both
 * (the far one pushed with [t_split, t_far], the near one entered with
 * [t_near, t_split]).  After a leaf the walk stops if the closest hit lies
 * inside the leaf's cell; a hit beyond it ("CANNOT terminate !!!") is kept
 * as the best so far and the walk goes on.
 *
 * Two walks take the same decision at every node and run the same
 * triangle tests in the same order, so they return the same hits, bit for
 * bit (tests/test_kdtree.c):
 *
 *   kd_walk_slide  the slide's loop as it is written: three cases, named
 *                  near and far children, a push for "both".  Used for
 *                  traced queries (a hook attached: the lessons, sidx-step,
 *                  sidx-view), whose events retell that loop, and for the
 *                  naive traversal.
 *   kd_walk_fast   the same decisions without branches, never entering an
 *                  empty leaf, leaves tested up to four references per SSE
 *                  pass.
 *                  Used for every other query: it is what the measurements
 *                  chose; it reads less like the slide.
 *
 * Each is written once and compiled twice: for a built tree and for a
 * lazy one, the copies differing only in how they read a node (kd_fetch,
 * below), so the walks carry no trace of lazy building.
 *
 * The rules for rounding, ±0 directions, rays inside a split plane and
 * empty leaves are written once, above kd_walk_slide; the fast walk keeps
 * every one of them.  Leaves, events and entry points come last.
 *
 * Rejected alternatives: docs/performance.md, kd-tree. */
#include "kdtree_internal.h"

#define SIDX_STRUCTURE_NAME "kdtree"

/* The SSE kernel for whole leaf blocks (tri4.h) where SSE2 is there. */
#define KD_SIMD SIDX_TRI4_SSE

/* 2γ₃ (Ize 2013): the relative error bound of t_split against t_near /
 * t_far, all three computed as (plane − o)·inv_dir. */
#define KD_TS_EPS (SIDX_ROBUST_TFAR_SCALE - 1.0f)

/* The slide's stack entry: a far child still to visit and the ray's
 * interval in it ("Store only necessary info on the stack"); depth only
 * for the events. */
typedef struct kd_stack_entry {
    uint32_t node, depth;
    float t_near, t_far;
} kd_stack_entry;

/* The slide walk's entry also remembers whether the ray lies in the split
 * plane that deferred it, so that its push and pop events can say so. */
typedef struct kd_slide_entry {
    uint32_t node, depth;
    float t_near, t_far;
    int in_plane;
} kd_slide_entry;

/* What both walks share: the state of the leaf tests, whose code
 * (kd_test_leaf and the rest) follows the two walks. */
#define KD_MAILBOX 16u /* entries of the per-ray mailbox (kd_test_leaf) */

/* What a walk carries from leaf to leaf. */
typedef struct kd_leaves {
    float best_t;                /* the closest hit so far; bounds every later test */
    int found;
    const tri4_block *best_block; /* the best hit's triangle copy (u, v, normal at the end) */
    unsigned best_lane;
    int simd, mailbox;
#if KD_SIMD
    tri4_ray simd_ray;
#endif
} kd_leaves;

static SIDX_INLINE int kd_enter_root(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, float best_t,
                                     float *t_near, float *t_far, const int traced, const int fetch);
static SIDX_INLINE void kd_leaves_init(kd_leaves *L, const sidx_accel *a, const sidx_ray *r, uint32_t *mbox,
                                       float best_t, const int traced);
static SIDX_INLINE int kd_test_leaf(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, kd_leaves *L,
                                    uint32_t *mbox, const tri4_block *blocks, const kd_node *leaf, uint32_t node,
                                    uint32_t visited, const int traced, const int any);
static SIDX_INLINE void kd_finish(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, const kd_leaves *L,
                                  sidx_hit *hit);

/* ==== reading nodes: the one difference of the lazy copies =================== */

/* How a walk reads its nodes, a compile-time constant of each copy (the
 * entry points at the end): KD_FETCH_TREE reads the tree's array;
 * KD_FETCH_LAZY, for a lazy tree (kd_lazy, kdtree_internal.h), may meet an
 * unbuilt node and then goes on in that node's subtree, which has arrays of
 * its own.  Everything a lazy copy does besides is in the helpers below,
 * so the walks are written once and their eager copies compile to the
 * code they had before lazy trees. */
enum { KD_FETCH_TREE = 0, KD_FETCH_LAZY = 1 };

/* Where a walk reads: the tree its node indices address (the whole tree,
 * or the subtree a lazy walk has entered), its nodes, and for a lazy walk
 * the parts of lazy.c and the hook its expansions report to. */
typedef struct kd_at {
    const kd_tree *tree;
    const kd_node *nodes;  /* tree->nodes */
    sidx__lazy *life;      /* KD_FETCH_LAZY: the unbuilt nodes' subtrees */
    const sidx_hook *hook; /* KD_FETCH_LAZY: build events of an expansion (traced queries) */
} kd_at;

static SIDX_INLINE kd_at kd_at_root(const sidx_accel *a, const sidx_hook *hook)
{
    const kd_tree *kd = a->impl;
    const kd_at at = {kd, kd->nodes, kd->lazy ? &kd->lazy->life : NULL, hook};
    return at;
}

/* Stands in for an unbuilt node whose subtree could not be built for want
 * of memory: the walk passes it over as an empty leaf, and the query
 * returns SIDX_ERR_NOMEM (lazy.c). */
static const kd_node kd_unbuildable = {{.count = 0u}, KD_LEAF_FLAG};

/* Node *node of the tree the walk is in.  A lazy walk that meets an
 * unbuilt node takes its subtree from lazy.c (sidx__lazy_get: one acquire
 * load when built; else built now, or waited for) and reads the subtree's
 * node 0, its root, in its stead. */
static SIDX_INLINE const kd_node *kd_fetch(kd_at *at, uint32_t *node, const int fetch)
{
    const kd_node *n = &at->nodes[*node];
    if (fetch == KD_FETCH_LAZY && SIDX_UNLIKELY(kd_is_unbuilt(n))) {
        const kd_tree *sub = sidx__lazy_get(at->life, kd_offset(n), at->hook);
        if (!sub) return &kd_unbuildable;
        at->tree = sub;
        at->nodes = sub->nodes;
        *node = 0;
        return sub->nodes;
    }
    return n;
}

/* A node's id in the events: its index, or in a lazy tree kd_id's. */
static SIDX_INLINE uint32_t kd_event_id(const kd_at *at, uint32_t node, const int fetch)
{
    return fetch == KD_FETCH_LAZY ? kd_id(at->tree, node) : node;
}

/* The naive walk's order: the left child first whatever the ray's direction. */
static SIDX_INLINE void kd_slide_swap(kd_slide_entry *x, kd_slide_entry *y)
{
    const kd_slide_entry t = *x;
    *x = *y;
    *y = t;
}

/* The walks' stacks.  Beside each entry a lazy walk keeps the tree its
 * node is in, restored when the entry is taken; an eager walk never
 * touches those. */
typedef struct kd_slide_stack {
    kd_slide_entry entry[KD_MAX_DEPTH + 2];
    const kd_tree *tree[KD_MAX_DEPTH + 2];
} kd_slide_stack;

typedef struct kd_fast_stack {
    kd_stack_entry entry[KD_MAX_DEPTH + 2];
    const kd_tree *tree[KD_MAX_DEPTH + 2];
} kd_fast_stack;

/* "push (far child, t_split, t_max) onto stack", and pop it again. */
static SIDX_INLINE void kd_slide_push(kd_slide_stack *s, unsigned *size, const kd_slide_entry *e, const kd_at *at,
                                      const int fetch)
{
    if (fetch == KD_FETCH_LAZY) s->tree[*size] = at->tree;
    s->entry[(*size)++] = *e;
}

static SIDX_INLINE kd_slide_entry kd_slide_pop(const kd_slide_stack *s, unsigned *size, kd_at *at, const int fetch)
{
    --*size;
    if (fetch == KD_FETCH_LAZY) {
        at->tree = s->tree[*size];
        at->nodes = at->tree->nodes;
    }
    return s->entry[*size];
}

/* The fast walk writes its top entry at every step and keeps it only in
 * the "both" case; it goes back to an entry's tree once it enters it. */
static SIDX_INLINE void kd_fast_put(kd_fast_stack *s, unsigned top, uint32_t node, float t_near, float t_far,
                                    const kd_at *at, const int fetch)
{
    s->entry[top].node = node;
    s->entry[top].t_near = t_near;
    s->entry[top].t_far = t_far;
    if (fetch == KD_FETCH_LAZY) s->tree[top] = at->tree;
}

static SIDX_INLINE void kd_fast_enter(const kd_fast_stack *s, unsigned top, kd_at *at, const int fetch)
{
    if (fetch == KD_FETCH_LAZY) {
        at->tree = s->tree[top];
        at->nodes = at->tree->nodes;
    }
}

/* ==== the slide walk ========================================================= */

/* Edge cases, decided here once (the fast walk takes the same decisions):
 *
 *   - rounding: t_split, t_near and t_far each carry a relative error of a
 *     few ulps, so a ray aimed exactly at a vertex on a split plane
 *     (t_split ≈ t_near) could be sent to the wrong side and miss the one
 *     triangle that touches the plane there.  A child is ruled out only
 *     when t_split lies outside [t_near, t_far] widened by 2γ₃ on both
 *     ends (Ize 2013, the bound of the robust box test); inside that
 *     window both children are visited, the slide's `<=`/`>=` ties
 *     included, and t_split is clamped into [t_near, t_far];
 *   - a ±0 direction component gives inv_dir = ±inf, so t_split = ±inf
 *     and the ray stays on its origin's side, which the sign rule picks
 *     (+0: near = left; origin above the plane → t_split = −inf → far =
 *     right).  If the origin lies exactly ON the plane, 0·inf = NaN: the
 *     ray runs inside the plane, which belongs to both closed cells, so
 *     both children are visited over the whole interval; the two
 *     intervals then overlap, so early termination is off for the rest of
 *     the ray (a hit in the first child need not be the closest);
 *   - a split exactly at a non-parallel ray's origin gives t_split = ±0 =
 *     t_near: both children, the near one with an empty interval;
 *   - a hit within 2γ₃ (Ize 2013) of the cell's far end does not end the
 *     walk, and a popped cell starting within 2γ₃ beyond the best hit is
 *     still entered: where the ray meets an edge or vertex on a split
 *     plane, the triangle across the plane may give a t an ulp smaller,
 *     and the walk returns the smallest t of all the triangles it crosses,
 *     as the brute force does.  A cell starting further on is skipped: it
 *     cannot hold a closer hit;
 *   - an empty leaf holds nothing to test; the fast walk never enters one,
 *     the slide walk enters it and goes straight on to the next cell (no
 *     stop test there, as the fast walk makes none), so both stop alike. */

/* The deck's loop ("kD-Tree Traversal: Inner Loop"), one node per
 * iteration; pbrt-v4's KdTreeAggregate::Intersect is the same loop.
 * Returns 1 when something was hit; for closest-hit queries `hit` then
 * carries the best hit.  A leaf's triangles are tested by one call,
 * kd_test_leaf (SIMD blocks, mailbox), as tinybvh keeps its leaf test.
 * naive: SIDX_TRAVERSE_NAIVE, the deck's naive variant — the left child
 * first whatever the ray's direction, every overlapped cell visited, no
 * early termination.  fetch: how nodes are read (kd_fetch; a lazy tree's
 * walk builds the subtrees it enters). */
static SIDX_INLINE int kd_walk_slide(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                     const int traced, const int any, const int naive, const int fetch)
{
    const float origin[3] = {r->org.x, r->org.y, r->org.z};
    const float inv_dir[3] = {r->inv_dir.x, r->inv_dir.y, r->inv_dir.z};
    const float best_t = any ? r->tmax : hit->t; /* the closest hit so far bounds every test */
    kd_at at = kd_at_root(a, traced ? q->hook : NULL);
    float t_near, t_far;
    if (!kd_enter_root(a, r, q, best_t, &t_near, &t_far, traced, fetch)) return 0;
    kd_leaves leaves;
    uint32_t mbox[KD_MAILBOX];
    kd_leaves_init(&leaves, a, r, mbox, best_t, traced);
    kd_slide_stack stack;
    unsigned stack_size = 0;
    uint32_t node = 0, depth = 0, visited = 0;
    int may_stop = !naive; /* early termination allowed (off once the ray runs inside a plane) */

    for (;;) { /* "Given (node, t_near, t_far)" */
        const kd_node *n = kd_fetch(&at, &node, fetch);
        ++visited;
        if (!kd_is_leaf(n)) {
            const uint32_t axis = kd_axis(n);
            const float t_split = (n->u.split - origin[axis]) * inv_dir[axis];
            /* "Near and far depend on direction of ray!" */
            const uint32_t left = kd_child(n), negative = r->sign[axis];
            const uint32_t near_child = left + negative, far_child = left + 1u - negative;
            /* "Three cases" ("kD-Tree Traversal Operation"), bounds widened by 2γ₃ (edge cases above) */
            const int split_case = t_split < t_near - fabsf(t_near) * KD_TS_EPS  ? SIDX_SPLIT_FAR_ONLY
                                   : t_split > t_far + fabsf(t_far) * KD_TS_EPS ? SIDX_SPLIT_NEAR_ONLY
                                                                                : SIDX_SPLIT_BOTH;
            /* the node's plane, t_split and the case taken (docs/events.md) */
            SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id;
                      e_.node = kd_event_id(&at, node, fetch); e_.depth = depth; e_.t_near = t_near; e_.t_far = t_far;
                      e_.axis = (int32_t)axis; e_.pos = n->u.split; e_.t = t_split; e_.result = split_case);
            ++depth;
            if (split_case == SIDX_SPLIT_FAR_ONLY) {
                node = far_child; /* the plane lies before the cell: far child only */
            } else if (split_case == SIDX_SPLIT_NEAR_ONLY) {
                node = near_child; /* the plane lies beyond the cell: near child only */
            } else {
                /* both: push (far_child, t_split, t_far), go on with (near_child, t_near, t_split);
                 * t_split clamped into the interval (NaN keeps the whole interval on both sides) */
                const int in_plane = t_split != t_split; /* both children are near */
                if (in_plane) may_stop = 0;
                kd_slide_entry far_entry = {far_child, depth, t_split > t_near ? t_split : t_near, t_far, in_plane};
                kd_slide_entry near_entry = {near_child, depth, t_near, t_split < t_far ? t_split : t_far, in_plane};
                if (naive && negative) kd_slide_swap(&far_entry, &near_entry); /* naive: the left child first */
                kd_slide_push(&stack, &stack_size, &far_entry, &at, fetch);
                /* result SIDX_STACK_IN_PLANE: the ray lies in the split plane (docs/events.md) */
                SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id;
                          e_.node = kd_event_id(&at, far_entry.node, fetch); e_.depth = stack_size;
                          e_.t_near = far_entry.t_near; e_.t_far = far_entry.t_far;
                          e_.result = in_plane ? SIDX_STACK_IN_PLANE : -1);
                node = near_entry.node, t_near = near_entry.t_near, t_far = near_entry.t_far;
            }
            continue;
        }

        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = kd_event_id(&at, node, fetch);
                  e_.depth = depth; e_.t_near = t_near; e_.t_far = t_far);
        /* A leaf: test its triangles (kd_test_leaf).  "Traversal can be terminated as soon as
         * surface intersection is found in the current node": stop if the best hit lies in this
         * cell; a hit beyond it is kept but the walk goes on ("CANNOT terminate !!!", Traversal
         * (10)).  An empty leaf: nothing to test, on to the next cell (edge cases above). */
        if (kd_count(n) != 0) {
            const uint32_t id = kd_event_id(&at, node, fetch);
            if (kd_test_leaf(a, r, q, &leaves, mbox, at.tree->blocks, n, id, visited, traced, any)) return 1;
            if (leaves.found && may_stop && leaves.best_t < t_far - fabsf(t_far) * KD_TS_EPS) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                          e_.reason = SIDX_TERM_HIT_IN_CELL; e_.t = leaves.best_t; e_.count = visited;
                          e_.node = id; e_.t_near = t_near; e_.t_far = t_far);
                kd_finish(a, r, q, &leaves, hit);
                return 1;
            }
        }

        /* pop the next cell; one starting beyond the best hit cannot hold a closer one */
        for (;;) {
            if (stack_size == 0) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                          e_.reason = SIDX_TERM_STACK_EMPTY; e_.t = leaves.found ? leaves.best_t : INFINITY;
                          e_.count = visited);
                if (leaves.found && !any) kd_finish(a, r, q, &leaves, hit);
                return leaves.found;
            }
            const kd_slide_entry next = kd_slide_pop(&stack, &stack_size, &at, fetch);
            const int enter = naive || next.t_near <= leaves.best_t + fabsf(leaves.best_t) * KD_TS_EPS;
            /* result: dropped, entered, or entered with the ray in its parent's split plane */
            SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_POP, e_.ray_id = q->ray_id;
                      e_.node = kd_event_id(&at, next.node, fetch); e_.depth = stack_size + 1u;
                      e_.t_near = next.t_near; e_.t_far = next.t_far;
                      e_.result = !enter ? SIDX_STACK_DROPPED
                                  : next.in_plane ? SIDX_STACK_IN_PLANE : SIDX_STACK_ENTERED);
            if (enter) {
                node = next.node, depth = next.depth, t_near = next.t_near, t_far = next.t_far;
                break;
            }
        }
    }
}

/* ==== the fast walk ========================================================== */

/* The slide walk's decisions, computed without branches: a kd step is a
 * dependent chain (load, subtract, multiply, compare, load) and a
 * mispredicted three-way branch per level costs more than the step itself
 * (deck 000, "Latency can harm you!").  The far entry is always written to
 * the stack and the stack pointer advances only in the "both" case.  Both
 * children of a node share 16 bytes, usually one cache line, and one of
 * them is the next load anyway: peeking at both lets the walk skip empty
 * leaves (the SAH's "big empty cells") instead of entering each and
 * popping right back.  Untraced: no events.  fetch: as in kd_walk_slide
 * (an unbuilt node is never empty, so the walk enters it). */
static SIDX_INLINE int kd_walk_fast(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                    const int any, const int fetch)
{
    const float origin[3] = {r->org.x, r->org.y, r->org.z};
    const float inv_dir[3] = {r->inv_dir.x, r->inv_dir.y, r->inv_dir.z};
    const uint32_t negative[3] = {r->sign[0], r->sign[1], r->sign[2]};
    const float best_t = any ? r->tmax : hit->t; /* the closest hit so far bounds every test */
    kd_at at = kd_at_root(a, NULL);
    float t_near, t_far;
    if (!kd_enter_root(a, r, q, best_t, &t_near, &t_far, 0, fetch)) return 0;
    kd_leaves leaves;
    uint32_t mbox[KD_MAILBOX];
    kd_leaves_init(&leaves, a, r, mbox, best_t, 0);

    kd_fast_stack stack;
    unsigned stack_size = 0;
    int may_stop = 1;
    uint32_t node = 0;
    const uint64_t empty = kd_word_empty();

    for (;;) {
        const kd_node *n = kd_fetch(&at, &node, fetch);
        while (!kd_is_leaf(n)) {
            const uint32_t axis = kd_axis(n);
            const float t_split = (n->u.split - origin[axis]) * inv_dir[axis];
            const uint32_t left = kd_child(n);
            const uint32_t near_child = left + negative[axis], far_child = left + 1u - negative[axis];
            const int far_only = t_split < t_near - fabsf(t_near) * KD_TS_EPS;
            const int near_only = t_split > t_far + fabsf(t_far) * KD_TS_EPS;
            /* NaN compares false both ways: "both", whole interval on each side */
            const float far_t_near = t_split > t_near ? t_split : t_near;
            const float near_t_far = t_split < t_far ? t_split : t_far;
            const uint64_t near_word = kd_word(&at.nodes[near_child]), far_word = kd_word(&at.nodes[far_child]);
            const int enter_near = !far_only & (near_word != empty);
            const int enter_far = !near_only & (far_word != empty);
            kd_fast_put(&stack, stack_size, far_child, far_t_near, t_far, &at, fetch);
            stack_size += (unsigned)(enter_near & enter_far);
            if (SIDX_UNLIKELY(t_split != t_split)) may_stop = 0; /* ray inside the plane: intervals overlap */
            if (SIDX_UNLIKELY(!(enter_near | enter_far))) goto pop;
            node = enter_near ? near_child : far_child;
            t_near = enter_near ? t_near : far_t_near;
            t_far = enter_near ? near_t_far : t_far;
            n = kd_fetch(&at, &node, fetch);
        }

        if (kd_test_leaf(a, r, q, &leaves, mbox, at.tree->blocks, n, node, 0, 0, any)) return 1;
        if (leaves.found && may_stop && leaves.best_t < t_far - fabsf(t_far) * KD_TS_EPS) {
            kd_finish(a, r, q, &leaves, hit);
            return 1;
        }
    pop: /* the next cell; those starting beyond the best hit are skipped */
        for (;;) {
            if (stack_size == 0) {
                if (leaves.found && !any) kd_finish(a, r, q, &leaves, hit);
                return leaves.found;
            }
            --stack_size;
            node = stack.entry[stack_size].node;
            t_near = stack.entry[stack_size].t_near;
            t_far = stack.entry[stack_size].t_far;
            if (t_near <= leaves.best_t + fabsf(leaves.best_t) * KD_TS_EPS) {
                kd_fast_enter(&stack, stack_size, &at, fetch);
                break;
            }
        }
    }
}

/* ==== leaves and events, shared by both walks ============================== */

/* Untraced walks with the default (watertight) test run the SSE kernel on
 * the leaf's lanes of its blocks; traced walks test lane by lane, so that
 * each test of the leaf's references and each mailbox hit is reported
 * (kd_test_leaf). */
static SIDX_INLINE void kd_leaves_init(kd_leaves *L, const sidx_accel *a, const sidx_ray *r, uint32_t *mbox,
                                       float best_t, const int traced)
{
    L->best_t = best_t;
    L->found = 0;
    L->best_block = NULL;
    L->best_lane = 0;
#if KD_SIMD
    L->simd = !traced && a->opt.tri == SIDX_TRI_WATERTIGHT;
    tri4_ray_init(&L->simd_ray, r);
#else
    (void)r;
    (void)traced;
    L->simd = 0;
#endif
    L->mailbox = !a->opt.no_mailbox && !L->simd;
    if (L->mailbox) memset(mbox, 0xff, KD_MAILBOX * sizeof *mbox);
}

/* u, v and the normal of the closest hit, when the query asks: from the
 * block's copy of the triangle, which is in cache, instead of the mesh
 * look-ups a diffuse ray mostly misses.  Run once, when the walk returns.
 * u, v by tri4_lane_hit_uv (the accepting test's float edge functions and
 * its own last step, so its bits, or the whole test again when that does
 * not apply). */
static SIDX_NOINLINE void kd_hit_attrs(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,
                                       const tri4_block *block, unsigned lane, sidx_hit *hit)
{
    float u = 0.0f, v = 0.0f;
    if ((q->flags & SIDX_QUERY_UV) && tri4_lane_hit_uv(a, r, block, lane, &u, &v)) {
        hit->u = u;
        hit->v = v;
    }
    if (q->flags & SIDX_QUERY_NORMAL) hit->ng = tri4_lane_normal(block, lane);
}

/* The closest hit, written once when the walk ends. */
static SIDX_INLINE void kd_finish(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, const kd_leaves *L,
                                  sidx_hit *hit)
{
    hit->t = L->best_t;
    hit->prim = L->best_block->prim[L->best_lane];
    if (SIDX_UNLIKELY(q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)))
        kd_hit_attrs(a, r, q, L->best_block, L->best_lane, hit);
}

#if KD_SIMD
/* A block the SIMD kernel declined (some kept lane's edge function is
 * exactly 0): the scalar test, which redoes those in double, on the kept
 * lanes (bits of `lanes`) one by one; the smallest t wins, the lowest lane
 * on ties, as in the kernel. */
static SIDX_NOINLINE int kd_block_scalar(const sidx_accel *a, const sidx_ray *r, const tri4_block *block,
                                         unsigned lanes, float best, float *t_out, unsigned *lane_out)
{
    int found = 0;
    for (unsigned l = 0; l < 4; ++l) {
        if (!(lanes >> l & 1u)) continue;
        float t;
        if (tri4_lane_test(a, r, block, l, best, &t, NULL, NULL)) {
            best = t;
            *t_out = t;
            *lane_out = l;
            found = 1;
        }
    }
    return found;
}
#endif

/* Test a leaf's triangles, and only those, against the best hit so far
 * (which bounds every test).  Returns 1 when an any-hit query is answered.
 *
 * The blocks are cut from the reference array, not per leaf
 * (kdtree_internal.h), so a leaf's first and last block may hold a
 * neighbouring leaf's references.  With the default (watertight) test
 * where SSE2 is there, the untraced walks run the SSE kernel on each of
 * the leaf's blocks with those lanes masked off (tri4_test_lanes): one
 * pass for four references, and a hit is only ever on one of the leaf's
 * own triangles.  The traced walks test the same references one by one
 * with the scalar test, in the same order, whose t is the kernel's bit for
 * bit; a strictly smaller t replaces the best, so the lowest reference
 * wins a tie in both, and both walks return the same hit.  Each test a
 * traced walk reports (PRIM_TEST, MAILBOX_HIT) is of a triangle the leaf
 * lists, and a HIT_UPDATE always follows the PRIM_TEST that found it.
 *
 * Mailboxing (deck 000, uniform grids: "Per-ray cache of object IDs —
 * data local to a ray (better!)"), in the scalar loop: a triangle
 * referenced by several leaves is tested once per ray.  A KD_MAILBOX-entry
 * direct-mapped table on the stack, keyed by the triangle's id; a
 * collision only evicts (a re-test is correct, just slower), so concurrent
 * queries share nothing.  The SIMD block loop has none: re-testing a lane
 * inside a block costs nothing, and gives the same answer (the same t,
 * not below the best it set). */
static SIDX_INLINE int kd_test_leaf(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, kd_leaves *L,
                                    uint32_t *mbox, const tri4_block *blocks, const kd_node *leaf, uint32_t node,
                                    uint32_t visited, const int traced, const int any)
{
    const uint32_t count = kd_count(leaf), offset = kd_offset(leaf);
    (void)visited;
#if KD_SIMD
    if (L->simd) {
        const tri4_block *block = blocks + (offset >> 2), *const end = blocks + ((offset + count + 3u) >> 2);
        /* the leaf's own lanes only (tri4_own_lanes) */
        tri4_own_lanes own = tri4_own_lanes_init(offset, count);
        for (; block < end; ++block) {
            float t;
            unsigned lane, kept;
            int h = tri4_test_own_lanes(block, &L->simd_ray, &own, L->best_t, &t, &lane, &kept);
            if (SIDX_UNLIKELY(h < 0)) h = kd_block_scalar(a, r, block, kept, L->best_t, &t, &lane);
            if (h) {
                if (any) return 1;
                L->found = 1;
                L->best_t = t;
                L->best_block = block;
                L->best_lane = lane;
            }
        }
        return 0;
    }
#endif
    for (uint32_t ref = offset; ref < offset + count; ++ref) {
        const tri4_block *block = &blocks[ref >> 2];
        const unsigned lane = ref & 3u;
        const uint32_t prim = block->prim[lane];
        if (L->mailbox) {
            uint32_t *const slot = &mbox[prim & (KD_MAILBOX - 1u)];
            if (*slot == prim) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_MAILBOX_HIT, e_.ray_id = q->ray_id; e_.prim = prim; e_.node = node);
                continue;
            }
            *slot = prim;
        }
        float t;
        const int h = tri4_lane_test(a, r, block, lane, L->best_t, &t, NULL, NULL);
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.prim = prim; e_.node = node;
                  e_.result = h; e_.t = h ? t : INFINITY);
        if (h) {
            if (any) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                          e_.t = t; e_.count = visited);
                return 1;
            }
            L->found = 1;
            L->best_t = t;
            L->best_block = block;
            L->best_lane = lane;
            SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = prim; e_.t = t;
                      e_.node = node);
        }
    }
    return 0;
}

/* The ray's interval in the root cell (the scene box), or 0 if it misses. */
static SIDX_INLINE int kd_enter_root(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, float best_t,
                                     float *t_near, float *t_far, const int traced, const int fetch)
{
    const kd_tree *kd = a->impl;
    if ((fetch == KD_FETCH_TREE && kd->num_refs == 0) || /* a lazy tree holds triangles (kdtree_build.c) */
        !sidx__box_test(a->opt.box == SIDX_BOX_ROBUST, r, &kd->bounds, r->tmin, best_t, t_near, t_far)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }
    return 1;
}

/* ==== entry points =========================================================== */

/* The walks by traversal and hook.  The untraced default is the fast
 * walk; a traced query, or one asking for the naive walk (which re-enters
 * from the root, as the deck's first version does), takes the slide's.
 * Each comes as an eager copy and as a copy for lazy trees (kd_lazy). */
#define KD_ENTRY_POINTS(sfx, fetch)                                                                              \
    static void kd_isect_fast##sfx(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit) \
    {                                                                                                          \
        (void)kd_walk_fast(a, r, q, hit, 0, fetch);                                                             \
    }                                                                                                          \
    static void kd_isect_slide_traced##sfx(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,        \
                                           sidx_hit *hit)                                                      \
    {                                                                                                          \
        (void)kd_walk_slide(a, r, q, hit, 1, 0, 0, fetch);                                                      \
    }                                                                                                          \
    static void kd_isect_naive##sfx(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)\
    {                                                                                                          \
        (void)kd_walk_slide(a, r, q, hit, 0, 0, 1, fetch);                                                      \
    }                                                                                                          \
    static void kd_isect_naive_traced##sfx(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,        \
                                           sidx_hit *hit)                                                      \
    {                                                                                                          \
        (void)kd_walk_slide(a, r, q, hit, 1, 0, 1, fetch);                                                      \
    }                                                                                                          \
    static int kd_occl_fast##sfx(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)                  \
    {                                                                                                          \
        sidx_hit dummy = sidx_hit_none();                                                                      \
        return kd_walk_fast(a, r, q, &dummy, 1, fetch);                                                         \
    }                                                                                                          \
    static int kd_occl_slide_traced##sfx(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)          \
    {                                                                                                          \
        sidx_hit dummy = sidx_hit_none();                                                                      \
        return kd_walk_slide(a, r, q, &dummy, 1, 1, 0, fetch);                                                  \
    }
KD_ENTRY_POINTS(, KD_FETCH_TREE)
KD_ENTRY_POINTS(_lazy, KD_FETCH_LAZY)

/* The walk tables (sidx_internal.h): [0] every traversal but the naive
 * one, [1] the naive one, [2] and [3] the same for lazy trees; any-hit
 * queries always take [0] or [2]. */
static const sidx__walk_table kd_walks[4] = {
    {kd_isect_fast, kd_isect_slide_traced, kd_occl_fast, kd_occl_slide_traced},
    {kd_isect_naive, kd_isect_naive_traced, kd_occl_fast, kd_occl_slide_traced},
    {kd_isect_fast_lazy, kd_isect_slide_traced_lazy, kd_occl_fast_lazy, kd_occl_slide_traced_lazy},
    {kd_isect_naive_lazy, kd_isect_naive_traced_lazy, kd_occl_fast_lazy, kd_occl_slide_traced_lazy},
};

static void kd_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    sidx__walk_intersect(&kd_walks[2u * a->lazy + (q->traversal == SIDX_TRAVERSE_NAIVE)], a, r, q, hit);
}

static int kd_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return sidx__walk_occluded(&kd_walks[2u * a->lazy], a, r, q);
}

/* One vtable serves all four builders (a->variant); the tree they produce
 * has the same layout, so traversal is shared.  No refit: moving vertices
 * changes which cells a triangle overlaps, so a kd-tree must be rebuilt. */
const sidx_accel_vtable sidx__kdtree_vtable = {sidx__kd_build, kd_intersect, kd_occluded, sidx__kd_stats,
                                               sidx__kd_destroy, NULL};
