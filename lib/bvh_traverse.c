/* bvh_traverse.c — walking the BVH, three ways (q->traversal), in the
 * order the deck teaches them:
 *
 *   naive    the deck's first "BVH Traversal": test the node's box, give
 *            up if it is missed or lies behind the best hit so far, else
 *            recurse into BOTH children, left then right;
 *   ordered  the deck's "Better BVH Traversal": test both children's
 *            boxes, recurse into the nearer first and into the farther
 *            only if its entry distance is still below the best hit
 *            ("Only check far bbox if closest primitive in the near bbox
 *            is farther than the closest point intersected in the far
 *            bbox");
 *   stack    (the default) the same ordered descent without recursion:
 *            go to the nearer child, push the farther with its entry
 *            distance, pop when a leaf is done and drop popped nodes whose
 *            entry is not closer than the best hit.  The stack is a
 *            fixed array of BVH_DEPTH_LIMIT entries: the build never makes
 *            a deeper tree and a descent defers at most one sibling per
 *            level, so it cannot overflow and nothing is allocated.
 *
 * Each is written once with a `const int traced` parameter and
 * instantiated twice (docs/adding-a-structure.md §3): in the traced = 0
 * copies every SIDX_EMIT is dead code.  The stack walk is additionally
 * instantiated per box kind (AABB / oriented), per query kind (closest /
 * any hit) and for queries asking for u, v or the normal, so the fast path
 * has no per-node branch on any of them.  The build picks the copies that
 * fit its tree once, one walk table per traversal (sidx__bvh_pick_walks,
 * end of file); a query only picks the table.
 *
 * Lazy trees (opt.lazy) have walks of their own: the same templates with
 * their node fetch swapped (fetch_node: nodes[i], or bvh_lazy_node, which
 * builds an unbuilt subtree the first time a ray reaches it), so the walks
 * themselves hold no trace of laziness and the eager copies compile as if
 * it did not exist. */
#include "bvh_internal.h"
#include "hit.h"

#define SIDX_STRUCTURE_NAME (a->name)

/* The node fetch: node i as the walk stands on it.  BVH_FETCH_EAGER reads
 * nodes[i]; BVH_FETCH_LAZY (lazy trees) goes through bvh_lazy_node, which
 * puts an unbuilt subtree's root in place of node i, built now if no ray
 * reached it before (bvh_internal.h, bvh_lazy). */
enum { BVH_FETCH_EAGER = 0, BVH_FETCH_LAZY = 1 };
static SIDX_INLINE const bvh_node *fetch_node(const bvh *b, const bvh_node *nodes, uint32_t i, const sidx_query *q,
                                              const int fetch, const int traced)
{
    if (fetch == BVH_FETCH_EAGER) return &nodes[i];
    return bvh_lazy_node(b, &nodes[i], traced ? q->hook : NULL);
}

static SIDX_INLINE int node_box(const bvh *b, const bvh_ray *br, const sidx_ray *r, uint32_t i, float tf_scale,
                                float tmin, float tmax, float *t_near, float *t_far, const int obb)
{
    if (obb) return bvh_obb_test(r, &b->obbs[i], tmin, tmax, t_near, t_far);
    return bvh_slab(br, &b->nodes[i], tf_scale, tmin, tmax, t_near, t_far);
}

/* Test a leaf's triangles (contiguous copies, original ids in prim_id).
 * The same sidx__tri_test on the same vertices as brute force, so a hit
 * has bit-identical t.  Every accepted hit writes *id: the original id,
 * or with by_copy (queries asking for u, v or the normal) the copy's
 * index, from which set_hit finishes the final hit once — the loop
 * keeps one index and no u, v (the tests run without u_out).  Returns 1
 * when an any-hit query may stop. */
static SIDX_INLINE int leaf_test(const sidx_accel *a, const bvh *b, uint32_t node, const bvh_node *n,
                                 const sidx_ray *r, const sidx_query *q, float *best, uint32_t *id,
                                 const int by_copy, const int anyhit, const int traced)
{
    const sidx_tri_method m = a->opt.tri;
    const uint32_t first = n->left_or_first, end = first + bvh_count(n);
    for (uint32_t i = first; i < end; ++i) {
        const bvh_tri *tr = &b->tris[i];
        float t;
        const int h = sidx__tri_test(m, r, tr->v[0], tr->v[1], tr->v[2], *best, &t, NULL, NULL);
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.node = node;
                  e_.prim = b->prim_id[i]; e_.result = h; e_.t = h ? t : INFINITY);
        if (h) {
            *id = by_copy ? i : b->prim_id[i];
            if (anyhit) return 1;
            *best = t;
            SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = b->prim_id[i];
                      e_.t = t);
        }
    }
    return 0;
}

/* The final closest hit on the leaf copy `tri`, with what the query asked
 * for (a->fills_uv, fills_ng): its original id; u, v by the accepting
 * test's own last step on the same floats, the copy read in place
 * (sidx__tri_hit_uv_at: the same bits as forming them at every accepted
 * hit, once per ray instead; figures in docs/performance.md, Binary BVH);
 * the normal from the copy. */
static SIDX_INLINE void set_hit(const sidx_accel *a, const bvh *b, const sidx_ray *r, const sidx_query *q,
                                float t, uint32_t tri, sidx_hit *hit)
{
    const bvh_tri *T = &b->tris[tri];
    hit->t = t;
    hit->prim = b->prim_id[tri];
    if (q->flags & SIDX_QUERY_UV)
        (void)sidx__tri_hit_uv_at(a->opt.tri, r, sidx_v3_array(&T->v[0]), sidx_v3_array(&T->v[1]), sidx_v3_array(&T->v[2]), 1, &hit->u, &hit->v);
    if (q->flags & SIDX_QUERY_NORMAL) hit->ng = sidx__tri_normal(T->v[0], T->v[1], T->v[2]);
}

#define EMIT_BOX(node_, res_, tn_, tf_)                                                                     \
    SIDX_EMIT(traced, q->hook, SIDX_EV_BOX_TEST, e_.ray_id = q->ray_id; e_.node = (node_);                 \
              e_.bounds = bvh_node_box(&b->nodes[(node_)]); e_.result = (res_);                            \
              e_.t_near = (res_) ? (tn_) : NAN; e_.t_far = (res_) ? (tf_) : NAN)


/* ---- naive and ordered: the deck's recursive hit() ------------------------ */

/* What both recursions carry down: the ray, its slab set-up and the best
 * hit so far. */
typedef struct walk {
    const sidx_accel *a;
    const bvh *b;
    const sidx_ray *r;
    const sidx_query *q;
    bvh_ray br;
    float scale, best;
    uint32_t tri, visited; /* the best hit so far: its leaf copy's index */
    int anyhit, obb, lazy;
} walk;

static SIDX_INLINE const bvh_node *walk_node(walk *w, uint32_t i, const int traced)
{
    const bvh *b = w->b;
    return w->lazy ? fetch_node(b, b->nodes, i, w->q, BVH_FETCH_LAZY, traced)
                   : fetch_node(b, b->nodes, i, w->q, BVH_FETCH_EAGER, traced);
}

static SIDX_INLINE int walk_box(walk *w, uint32_t i, float *t_near, float *t_far)
{
    return w->obb ? node_box(w->b, &w->br, w->r, i, w->scale, w->r->tmin, w->best, t_near, t_far, 1)
                  : node_box(w->b, &w->br, w->r, i, w->scale, w->r->tmin, w->best, t_near, t_far, 0);
}

static SIDX_INLINE int walk_leaf(walk *w, uint32_t node, const bvh_node *n, const int traced)
{
    return w->anyhit ? leaf_test(w->a, w->b, node, n, w->r, w->q, &w->best, &w->tri, 1, 1, traced)
                     : leaf_test(w->a, w->b, node, n, w->r, w->q, &w->best, &w->tri, 1, 0, traced);
}

/* naive_rec0 / naive_rec1: the plain and the traced copy of naive_body
 * (and the same for ordered). */
static int naive_rec0(walk *w, uint32_t node, uint32_t depth);
static int naive_rec1(walk *w, uint32_t node, uint32_t depth);
static int ordered_rec0(walk *w, uint32_t node, uint32_t depth, float t_near, float t_far);
static int ordered_rec1(walk *w, uint32_t node, uint32_t depth, float t_near, float t_far);

/* The deck's hit(ray, node, best): "test if ray hits node's bbox ... if
 * (hit.prim == NULL || hit.t > best.t) return" — the box is clipped to
 * [tmin, best], so a box behind the best hit is a miss — then leaves test
 * their primitives and inner nodes "traverse BOTH children". */
static SIDX_INLINE int naive_body(walk *w, uint32_t node, uint32_t depth, const int traced)
{
    const sidx_accel *a = w->a;
    const bvh *b = w->b;
    const sidx_query *q = w->q;
    float t_near, t_far;
    const int h = walk_box(w, node, &t_near, &t_far);
    EMIT_BOX(node, h, t_near, t_far);
    if (!h) return 0;
    ++w->visited;
    SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
              e_.t_near = t_near; e_.t_far = t_far);
    const bvh_node *n = walk_node(w, node, traced);
    if (bvh_is_leaf(n)) return walk_leaf(w, node, n, traced);
    const uint32_t right = n->left_or_first;
    if (traced ? naive_rec1(w, node + 1, depth + 1) : naive_rec0(w, node + 1, depth + 1)) return 1;
    return traced ? naive_rec1(w, right, depth + 1) : naive_rec0(w, right, depth + 1);
}
static int naive_rec0(walk *w, uint32_t node, uint32_t depth) { return naive_body(w, node, depth, 0); }
static int naive_rec1(walk *w, uint32_t node, uint32_t depth) { return naive_body(w, node, depth, 1); }

/* The deck's better hit(): the node's own box was tested by its parent
 * (or by the caller for the root), so test both children, visit the one
 * with the smaller entry t first, the other only if it can still win. */
static SIDX_INLINE int ordered_body(walk *w, uint32_t node, uint32_t depth, float t_near, float t_far, const int traced)
{
    const sidx_accel *a = w->a;
    const bvh *b = w->b;
    const sidx_query *q = w->q;
    ++w->visited;
    SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
              e_.t_near = t_near; e_.t_far = t_far);
    const bvh_node *n = walk_node(w, node, traced);
    if (bvh_is_leaf(n)) return walk_leaf(w, node, n, traced);
    /* left and right child until sorted: then the nearer and the farther */
    uint32_t near_child = node + 1, far_child = n->left_or_first;
    float near_t_near, near_t_far, far_t_near, far_t_far;
    int near_hit = walk_box(w, near_child, &near_t_near, &near_t_far);
    int far_hit = walk_box(w, far_child, &far_t_near, &far_t_far);
    EMIT_BOX(near_child, near_hit, near_t_near, near_t_far);
    EMIT_BOX(far_child, far_hit, far_t_near, far_t_far);
    if (far_hit && (!near_hit || far_t_near < near_t_near)) { /* the right child is the nearer one */
        uint32_t tc = near_child; near_child = far_child; far_child = tc;
        int th = near_hit; near_hit = far_hit; far_hit = th;
        float t = near_t_near; near_t_near = far_t_near; far_t_near = t;
        t = near_t_far; near_t_far = far_t_far; far_t_far = t;
    }
    if (near_hit && (traced ? ordered_rec1(w, near_child, depth + 1, near_t_near, near_t_far)
                            : ordered_rec0(w, near_child, depth + 1, near_t_near, near_t_far)))
        return 1;
    if (far_hit && far_t_near < w->best * w->scale) /* best widened as in bvh_slab */
        return traced ? ordered_rec1(w, far_child, depth + 1, far_t_near, far_t_far)
                      : ordered_rec0(w, far_child, depth + 1, far_t_near, far_t_far);
    return 0;
}
static int ordered_rec0(walk *w, uint32_t node, uint32_t depth, float t_near, float t_far)
{
    return ordered_body(w, node, depth, t_near, t_far, 0);
}
static int ordered_rec1(walk *w, uint32_t node, uint32_t depth, float t_near, float t_far)
{
    return ordered_body(w, node, depth, t_near, t_far, 1);
}

/* Either recursion from the root, and the final hit. */
static SIDX_INLINE int recursive_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                      const int anyhit, const int ordered, const int traced)
{
    const bvh *b = a->impl;
    walk w;
    w.a = a;
    w.b = b;
    w.r = r;
    w.q = q;
    bvh_ray_setup(&w.br, r);
    w.scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    w.best = anyhit ? r->tmax : hit->t;
    w.tri = SIDX_NO_HIT;
    w.visited = 0;
    w.anyhit = anyhit;
    w.obb = b->obbs != NULL;
    w.lazy = b->lazy != NULL;
    int found = 0, missed_root = b->num_nodes == 0;
    if (!missed_root) {
        if (ordered) {
            float t_near, t_far;
            const int h = walk_box(&w, 0, &t_near, &t_far);
            EMIT_BOX(0u, h, t_near, t_far);
            if (h) found = traced ? ordered_rec1(&w, 0, 0, t_near, t_far) : ordered_rec0(&w, 0, 0, t_near, t_far);
            else missed_root = 1;
        } else {
            found = traced ? naive_rec1(&w, 0, 0) : naive_rec0(&w, 0, 0);
            missed_root = w.visited == 0;
        }
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
              e_.reason = found ? SIDX_TERM_ANY_HIT : missed_root ? SIDX_TERM_MISS_ROOT : SIDX_TERM_STACK_EMPTY;
              e_.t = anyhit ? INFINITY : w.best; e_.count = w.visited);
    if (!anyhit && w.tri != SIDX_NO_HIT) set_hit(a, b, r, q, w.best, w.tri, hit);
    return found;
}

/* ---- stack: the ordered descent without recursion (the fast path) -------- */

#define EMIT_TERMINATE(reason_, t_)                                                                           \
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = (reason_); e_.t = (t_);  \
              e_.count = visited)

/* The closest hit found, as the query asked for it (attrs: u, v, normal). */
static SIDX_INLINE void stack_hit(const sidx_accel *a, const bvh *b, const sidx_ray *r, const sidx_query *q,
                                  float best, uint32_t prim, const int attrs, sidx_hit *hit)
{
    if (attrs) {
        set_hit(a, b, r, q, best, prim, hit);
    } else {
        hit->t = best;
        hit->prim = prim;
    }
}

/* The walk runs at the speed of its branch mispredicts, not of its
 * arithmetic: a diffuse ray makes each inner node's near / both / none
 * choice at random, and every mispredict waits for the chain load ->
 * (plane − o)·(1/d) -> min/max -> compare of the boxes just loaded.  So the
 * loop stays this plain scalar one: none of two-box SIMD tests,
 * branch-free choices, per-octant copies, prefetches, SIMD leaves and
 * other node layouts is faster (measured, with the figures:
 * docs/performance.md, Binary BVH).
 *
 * attrs: the query asks for u, v and/or the normal (closest hit only).  A
 * copy of its own, so the walk for plain queries carries no u, v and no
 * triangle index ("no u/v or normals unless asked").
 *
 * The deck's "Better BVH Traversal" (001, the ordered hit()) with its
 * recursion turned into a stack, as tinybvh's BVH::Intersect and pbrt's
 * BVHAggregate::Intersect keep it: at an inner node test both children's
 * boxes, go to the nearer, push the farther with its entry distance; at a
 * leaf test its triangles; then pop the next deferred node whose entry is
 * still before the best hit.  fetch: the node fetch (fetch_node). */
static SIDX_INLINE int stack_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                  const int traced, const int anyhit, const int obb, const int attrs, const int fetch)
{
    const bvh *b = a->impl;
    const bvh_node *nodes = b->nodes;
    const float scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    const float tmin = r->tmin;
    float best = anyhit ? r->tmax : hit->t;
    /* the best hit so far: its original id, or with attrs its copy's index */
    uint32_t prim = SIDX_NO_HIT, visited = 0;
    bvh_ray br;
    bvh_ray_setup(&br, r);
    if (b->num_nodes == 0) {
        EMIT_TERMINATE(SIDX_TERM_MISS_ROOT, INFINITY);
        return 0;
    }
    float t_near, t_far;
    const int hit_root = node_box(b, &br, r, 0, scale, tmin, best, &t_near, &t_far, obb);
    EMIT_BOX(0u, hit_root, t_near, t_far);
    if (!hit_root) {
        EMIT_TERMINATE(SIDX_TERM_MISS_ROOT, INFINITY);
        return 0;
    }
    /* Deferred far children and their entry distances; depth and exit
     * distance only for the events (dead stores in the untraced copy). */
    uint32_t stack[BVH_DEPTH_LIMIT], stack_depth[BVH_DEPTH_LIMIT];
    float stack_t_near[BVH_DEPTH_LIMIT], stack_t_far[BVH_DEPTH_LIMIT];
    uint32_t stack_len = 0, node = 0, depth = 0;
    for (;;) {
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
                  e_.t_near = t_near; e_.t_far = t_far);
        const bvh_node *n = fetch_node(b, nodes, node, q, fetch, traced);
        if (bvh_is_leaf(n)) { /* a leaf: its triangles */
            if (leaf_test(a, b, node, n, r, q, &best, &prim, attrs, anyhit, traced)) {
                EMIT_TERMINATE(SIDX_TERM_ANY_HIT, INFINITY);
                return 1;
            }
        } else { /* an inner node: both children's boxes, entry and exit t */
            const uint32_t left = node + 1, right = n->left_or_first;
            float left_t_near, left_t_far, right_t_near, right_t_far;
            const int hit_left = node_box(b, &br, r, left, scale, tmin, best, &left_t_near, &left_t_far, obb);
            const int hit_right = node_box(b, &br, r, right, scale, tmin, best, &right_t_near, &right_t_far, obb);
            EMIT_BOX(left, hit_left, left_t_near, left_t_far);
            EMIT_BOX(right, hit_right, right_t_near, right_t_far);
            if (hit_left && hit_right) {
                /* Both: the nearer entry now (ties: left), the farther waits.
                 * (A branch-free version of this choice measured no faster
                 * with gcc -O2; this one reads like the slide.) */
                uint32_t near_child = left, far_child = right;
                float far_t_near = right_t_near, far_t_far = right_t_far;
                t_near = left_t_near;
                t_far = left_t_far;
                if (right_t_near < left_t_near) {
                    near_child = right, far_child = left;
                    far_t_near = left_t_near, far_t_far = left_t_far;
                    t_near = right_t_near, t_far = right_t_far;
                }
                stack[stack_len] = far_child;
                stack_t_near[stack_len] = far_t_near;
                if (traced) stack_depth[stack_len] = depth + 1, stack_t_far[stack_len] = far_t_far;
                ++stack_len;
                SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id; e_.node = far_child;
                          e_.depth = stack_len; e_.t_near = far_t_near; e_.t_far = far_t_far);
                node = near_child;
                ++depth;
                continue;
            }
            if (hit_left | hit_right) { /* one: go there */
                node = hit_left ? left : right;
                t_near = hit_left ? left_t_near : right_t_near;
                t_far = hit_left ? left_t_far : right_t_far;
                ++depth;
                continue;
            }
        }
        /* Pop the next deferred node that can still hold a closer hit. */
        for (;;) {
            if (stack_len == 0) {
                EMIT_TERMINATE(SIDX_TERM_STACK_EMPTY, best);
                if (!anyhit && prim != SIDX_NO_HIT) stack_hit(a, b, r, q, best, prim, attrs, hit);
                return 0;
            }
            --stack_len;
            /* result 0: dropped, its entry lies beyond the best hit (docs/events.md) */
            SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_POP, e_.ray_id = q->ray_id; e_.node = stack[stack_len];
                      e_.depth = stack_len + 1; e_.t_near = stack_t_near[stack_len]; e_.t_far = stack_t_far[stack_len];
                      e_.result = stack_t_near[stack_len] < best * scale);
            if (stack_t_near[stack_len] < best * scale) { /* best widened as in bvh_slab */
                node = stack[stack_len];
                t_near = stack_t_near[stack_len];
                if (traced) t_far = stack_t_far[stack_len], depth = stack_depth[stack_len];
                break;
            }
        }
    }
}
#undef EMIT_TERMINATE

/* ---- walk tables and entry points (sidx_internal.h §1) --------------------- */

/* Every copy a table names is a function of its own, so that each walk's
 * registers are allocated for it alone (the plain stack walk beside the
 * others costs it instructions: docs/performance.md, Binary BVH). */
#define RECURSIVE_INTERSECT(name_, ordered_, traced_)                                                          \
    static void name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)             \
    {                                                                                                           \
        (void)recursive_walk(a, r, q, hit, 0, ordered_, traced_);                                               \
    }
#define RECURSIVE_OCCLUDED(name_, ordered_, traced_)                                                           \
    static int name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)                              \
    {                                                                                                           \
        return recursive_walk(a, r, q, NULL, 1, ordered_, traced_);                                             \
    }
#define STACK_INTERSECT(name_, traced_, obb_, attrs_, fetch_)                                                  \
    static void name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)             \
    {                                                                                                           \
        (void)stack_walk(a, r, q, hit, traced_, 0, obb_, attrs_, fetch_);                                       \
    }
#define STACK_OCCLUDED(name_, traced_, obb_, fetch_)                                                           \
    static int name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)                              \
    {                                                                                                           \
        return stack_walk(a, r, q, NULL, traced_, 1, obb_, 0, fetch_);                                          \
    }

/* The recursive walks test the box kind per node (w.obb): teaching paths,
 * one copy serves both kinds. */
RECURSIVE_INTERSECT(naive_intersect, 0, 0)
RECURSIVE_INTERSECT(naive_intersect_traced, 0, 1)
RECURSIVE_OCCLUDED(naive_occluded, 0, 0)
RECURSIVE_OCCLUDED(naive_occluded_traced, 0, 1)
RECURSIVE_INTERSECT(ordered_intersect, 1, 0)
RECURSIVE_INTERSECT(ordered_intersect_traced, 1, 1)
RECURSIVE_OCCLUDED(ordered_occluded, 1, 0)
RECURSIVE_OCCLUDED(ordered_occluded_traced, 1, 1)

STACK_INTERSECT(stack_intersect, 0, 0, 0, BVH_FETCH_EAGER) /* the hot path: plain closest hit on AABBs */
STACK_INTERSECT(stack_intersect_traced, 1, 0, 0, BVH_FETCH_EAGER)
STACK_INTERSECT(stack_intersect_attrs, 0, 0, 1, BVH_FETCH_EAGER)
STACK_INTERSECT(stack_intersect_attrs_traced, 1, 0, 1, BVH_FETCH_EAGER)
STACK_OCCLUDED(stack_occluded, 0, 0, BVH_FETCH_EAGER)
STACK_OCCLUDED(stack_occluded_traced, 1, 0, BVH_FETCH_EAGER)

STACK_INTERSECT(obb_stack_intersect, 0, 1, 0, BVH_FETCH_EAGER)
STACK_INTERSECT(obb_stack_intersect_traced, 1, 1, 0, BVH_FETCH_EAGER)
STACK_INTERSECT(obb_stack_intersect_attrs, 0, 1, 1, BVH_FETCH_EAGER)
STACK_INTERSECT(obb_stack_intersect_attrs_traced, 1, 1, 1, BVH_FETCH_EAGER)
STACK_OCCLUDED(obb_stack_occluded, 0, 1, BVH_FETCH_EAGER)
STACK_OCCLUDED(obb_stack_occluded_traced, 1, 1, BVH_FETCH_EAGER)

/* lazy trees (AABBs only): the same walk, its node fetch swapped (fetch_node) */
STACK_INTERSECT(lazy_stack_intersect, 0, 0, 0, BVH_FETCH_LAZY)
STACK_INTERSECT(lazy_stack_intersect_traced, 1, 0, 0, BVH_FETCH_LAZY)
STACK_INTERSECT(lazy_stack_intersect_attrs, 0, 0, 1, BVH_FETCH_LAZY)
STACK_INTERSECT(lazy_stack_intersect_attrs_traced, 1, 0, 1, BVH_FETCH_LAZY)
STACK_OCCLUDED(lazy_stack_occluded, 0, 0, BVH_FETCH_LAZY)
STACK_OCCLUDED(lazy_stack_occluded_traced, 1, 0, BVH_FETCH_LAZY)

#undef RECURSIVE_INTERSECT
#undef RECURSIVE_OCCLUDED
#undef STACK_INTERSECT
#undef STACK_OCCLUDED

/* {closest hit, closest hit traced, any hit, any hit traced} per walk. */
static const sidx__walk_table aabb_walks[BVH_WALK_COUNT] = {
    [BVH_WALK_NAIVE] = {naive_intersect, naive_intersect_traced, naive_occluded, naive_occluded_traced},
    [BVH_WALK_ORDERED] = {ordered_intersect, ordered_intersect_traced, ordered_occluded, ordered_occluded_traced},
    [BVH_WALK_STACK] = {stack_intersect, stack_intersect_traced, stack_occluded, stack_occluded_traced},
    [BVH_WALK_STACK_ATTRS] = {stack_intersect_attrs, stack_intersect_attrs_traced, stack_occluded,
                              stack_occluded_traced},
};
static const sidx__walk_table obb_walks[BVH_WALK_COUNT] = {
    [BVH_WALK_NAIVE] = {naive_intersect, naive_intersect_traced, naive_occluded, naive_occluded_traced},
    [BVH_WALK_ORDERED] = {ordered_intersect, ordered_intersect_traced, ordered_occluded, ordered_occluded_traced},
    [BVH_WALK_STACK] = {obb_stack_intersect, obb_stack_intersect_traced, obb_stack_occluded,
                        obb_stack_occluded_traced},
    [BVH_WALK_STACK_ATTRS] = {obb_stack_intersect_attrs, obb_stack_intersect_attrs_traced, obb_stack_occluded,
                              obb_stack_occluded_traced},
};

static const sidx__walk_table lazy_walks[BVH_WALK_COUNT] = {
    [BVH_WALK_NAIVE] = {naive_intersect, naive_intersect_traced, naive_occluded, naive_occluded_traced},
    [BVH_WALK_ORDERED] = {ordered_intersect, ordered_intersect_traced, ordered_occluded, ordered_occluded_traced},
    [BVH_WALK_STACK] = {lazy_stack_intersect, lazy_stack_intersect_traced, lazy_stack_occluded,
                        lazy_stack_occluded_traced},
    [BVH_WALK_STACK_ATTRS] = {lazy_stack_intersect_attrs, lazy_stack_intersect_attrs_traced, lazy_stack_occluded,
                              lazy_stack_occluded_traced},
};

void sidx__bvh_pick_walks(bvh *b) { b->walks = b->obbs ? obb_walks : b->lazy ? lazy_walks : aabb_walks; }

/* The table for this query's traversal (anything but naive and ordered
 * is the stack walk) and, for the stack walk, for whether it asks for u,
 * v or the normal.  q is never NULL here (sidx_internal.h §1). */
static SIDX_INLINE const sidx__walk_table *walks_for(const sidx_accel *a, const sidx_query *q)
{
    const bvh *b = a->impl;
    if (q->traversal == SIDX_TRAVERSE_NAIVE) return &b->walks[BVH_WALK_NAIVE];
    if (q->traversal == SIDX_TRAVERSE_ORDERED) return &b->walks[BVH_WALK_ORDERED];
    return &b->walks[(q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)) ? BVH_WALK_STACK_ATTRS : BVH_WALK_STACK];
}

void sidx__bvh_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    sidx__walk_intersect(walks_for(a, q), a, r, q, hit);
}

int sidx__bvh_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return sidx__walk_occluded(walks_for(a, q), a, r, q);
}

/* ---- the stream walk (bvh_stream.c) ----------------------------------------
 * A buffer of rays, one after another, each through the plain stack walk:
 * no entry checks and no choice of walk per ray, the hit set up and
 * finished beside the walk.  The walk stays a function of its own (one_*),
 * its registers allocated for it alone as the single-ray copies' (see
 * above): inlined into the loop it measured no faster
 * (docs/performance.md, "The stream entry"). */
#define STREAM_WALK(name_, anyhit_, attrs_)                                                                    \
    static SIDX_NOINLINE int one_##name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,          \
                                         sidx_hit *hit)                                                        \
    {                                                                                                           \
        if (anyhit_) return stack_walk(a, r, q, NULL, 0, 1, 0, 0, 0);                                           \
        *hit = sidx_hit_none(); /* as sidx_accel_intersect hands it to the walk, and finishes it */             \
        hit->t = r->tmax;                                                                                       \
        (void)stack_walk(a, r, q, hit, 0, 0, 0, attrs_, 0);                                                     \
        sidx__finish_hit(a, r, q, hit);                                                                         \
        return 0;                                                                                               \
    }                                                                                                           \
    void name_(const sidx_accel *a, const sidx_query *q, const bvh_stream_rays *c)                            \
    {                                                                                                           \
        const sidx_ray *rays = c->rays;                                                                         \
        const uint32_t *idx = c->idx;                                                                           \
        sidx_hit unused; /* an any-hit walk writes no hit */                                                    \
        for (uint32_t i = 0, n = c->count; i < n; ++i) {                                                        \
            const uint32_t j = idx ? idx[i] : i;                                                                \
            if (anyhit_) c->occluded[j] = one_##name_(a, &rays[j], q, &unused);                                 \
            else (void)one_##name_(a, &rays[j], q, &c->hits[j]);                                                \
        }                                                                                                       \
    }
STREAM_WALK(sidx__bvh_stream_isect, 0, 0)
STREAM_WALK(sidx__bvh_stream_isect_attrs, 0, 1)
STREAM_WALK(sidx__bvh_stream_occl, 1, 0)
#undef STREAM_WALK
