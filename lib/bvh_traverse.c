/* bvh_traverse.c — walking the BVH, three ways (q->traversal):
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
 *            entry is no longer closer than the best hit.  The stack is a
 *            fixed array of BVH_DEPTH_LIMIT entries: the build never makes
 *            a deeper tree and a descent defers at most one sibling per
 *            level, so it cannot overflow and nothing is allocated.
 *
 * Each is written once with a `const int traced` parameter and
 * instantiated twice (docs/adding-a-structure.md §3): in the traced = 0
 * copies every SIDX_EMIT is dead code.  The stack walk is additionally
 * instantiated per box kind (AABB / oriented) and per query kind (closest
 * / any hit) so the fast path has no per-node branch on either. */
#include "bvh_internal.h"

#define SIDX_STRUCTURE_NAME (a->name)

static SIDX_INLINE int node_box(const bvh *b, const bvh_ray *br, const sidx_ray *r, uint32_t i, float tf_scale,
                                float tmin, float tmax, float *tn, float *tf, const int obb)
{
    if (obb) return bvh_obb_test(r, &b->obbs[i], tmin, tmax, tn, tf);
    return bvh_slab(br, &b->nodes[i], tf_scale, tmin, tmax, tn, tf);
}

/* Test a leaf's triangles (contiguous copies, original ids in prim_id).
 * The same sidx__tri_test on the same vertices as brute force, so a hit
 * has bit-identical t.  Every accepted hit writes *id: the original id,
 * or with by_copy (queries asking for u, v or the normal) the copy's
 * index, from which set_attrs finishes the final hit once — the loop
 * keeps one index and no u, v (the tests run without u_out).  Returns 1
 * when an any-hit query may stop. */
static SIDX_INLINE int leaf_test(const sidx_accel *a, const bvh *b, const bvh_node *n, const sidx_ray *r,
                                 const sidx_query *q, float *best, uint32_t *id, const int by_copy,
                                 const int anyhit, const int traced)
{
    const sidx_tri_method m = a->opt.tri;
    const uint32_t first = n->left_or_first, end = first + bvh_count(n);
    for (uint32_t i = first; i < end; ++i) {
        const bvh_tri *tr = &b->tris[i];
        float t;
        const int h = sidx__tri_test(m, r, tr->v[0], tr->v[1], tr->v[2], *best, &t, NULL, NULL);
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.node = (uint32_t)(n - b->nodes);
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
 * hit, which cost the loop ~150 instructions per diffuse ray on the
 * bunny); the normal from the copy. */
static SIDX_INLINE void set_hit(const sidx_accel *a, const bvh *b, const sidx_ray *r, const sidx_query *q,
                                float t, uint32_t tri, sidx_hit *hit)
{
    const bvh_tri *T = &b->tris[tri];
    hit->t = t;
    hit->prim = b->prim_id[tri];
    if (q->flags & SIDX_QUERY_UV)
        (void)sidx__tri_hit_uv_at(a->opt.tri, r, &T->v[0].x, &T->v[1].x, &T->v[2].x, 1, &hit->u, &hit->v);
    if (q->flags & SIDX_QUERY_NORMAL) hit->ng = sidx__tri_normal(T->v[0], T->v[1], T->v[2]);
}

#define EMIT_BOX(node_, res_, tn_, tf_)                                                                     \
    SIDX_EMIT(traced, q->hook, SIDX_EV_BOX_TEST, e_.ray_id = q->ray_id; e_.node = (node_);                 \
              e_.bounds = bvh_node_box(&b->nodes[(node_)]); e_.result = (res_);                            \
              e_.t_near = (res_) ? (tn_) : NAN; e_.t_far = (res_) ? (tf_) : NAN)

/* ---- stack (the fast path) -------------------------------------------- */

/* What bounds this loop (session 5, Sponza diffuse rays, 20k rays; gcc
 * 12 -O2; callgrind for instructions, interleaved runs of the fair driver
 * for time): about 3,100 instructions, 28 node steps and 12.5 L1 misses
 * per ray, and a near/both/none decision per inner node that a diffuse
 * ray makes at random.  The walk runs at the speed of its mispredicts:
 * each waits for the chain load -> (plane − o)·(1/d) -> min/max -> compare
 * of the boxes just loaded.  Measured and rejected, so nobody redoes them:
 *  - both boxes in one SSE2 pass (xor/and blend of the near planes, one
 *    shared horizontal min/max, one compare for both hit bits): −4%
 *    instructions and a third fewer mispredicts in callgrind's model, yet
 *    25% slower: the blend and the lane reductions add ~15 cycles to the
 *    chain every mispredict waits for;
 *  - branch-free choice of the next node (cmov, sp += both; SSE or scalar):
 *    the next node's address then waits for that same chain at every
 *    step instead of only at mispredicts: 0 to −25%;
 *  - one copy of the walk per direction octant (plane offsets as
 *    constants, six general registers freed): −2% instructions, −6% time
 *    on diffuse rays (the copies split the branch predictor's history);
 *  - prefetching the children's right children, carrying the right
 *    child's index in a register, a tree-shaped min/max, the triangles'
 *    method switch hoisted out of the leaf loop, a 4-wide leaf test on
 *    copies transposed at the leaf, the leaf out of line, a descent loop
 *    of its own ("while-while"): each makes gcc spill the ray's constants
 *    of the box test (+2% to +21% instructions) and none measured faster;
 *  - (session 6) the far planes pre-multiplied by Ize's factor, as the
 *    wide walk does, so the chain loses its last multiply: +2.3%
 *    instructions (the widened best is one more value kept across the
 *    loop), −1.3% mispredicts, +1% time — within the noise; and the
 *    whole library compiled for this machine (-march=native, AVX-512):
 *    no change.  The binary walk's time is its mispredicts, not its
 *    arithmetic;
 *  - (session 7) the leaves' triangles also stored as SSE blocks of four
 *    made at build (tris[i] in block i / 4, a leaf testing the blocks its
 *    range touches, as the kd-tree does) and tested by the wide BVHs'
 *    watertight kernel: bunny diffuse with u, v, Ng 1808 instead of 1661
 *    instructions per ray, mispredicts only −1.4 %, 4-10 % slower; Sponza
 *    diffuse −3 % to +10 %.  Leaves hold about 3 triangles, so a leaf
 *    costs 1-2 block passes, while the scalar tests mostly stop at their
 *    first edge sign;
 *  - (session 8) siblings side by side (tinybvh's layout: an inner node
 *    stores its first child, the second is the next node, each pair in
 *    one 64-byte line, pairs in depth-first order), so a step loads one
 *    line for both children's boxes: same hits, but Sponza diffuse 1.7
 *    instead of 2.1 Mrays/s in three interleaved runs.  Not explained
 *    (no hardware counters here); in this layout the left child (index
 *    + 1) shares its parent's line or sits in the adjacent one, so only
 *    the right child is a line from elsewhere; and the
 *    slab planes computed as p·(1/d) − o·(1/d) with FMA (-mfma on this
 *    file): within the noise, and Ize's bound would no longer cover it;
 *  - (session 9) the nearer child picked by the ray's sign on the node's
 *    split axis (pbrt-v3's order, count_axis already holds the axis), so
 *    the choice no longer waits for the two box tests: Sponza diffuse
 *    1.89-2.09 against 2.07-2.16 Mrays/s in three alternating runs — the
 *    branch resolves sooner but the order is worse;
 *  - and, to see how much the tree could still give, this walk over the
 *    binary tree of the spatial-split build (bvh_spatial.c, which the
 *    issue's "every primitive in exactly one leaf" rules out for "bvh"):
 *    Sponza diffuse 0.48 of Embree on the targets' fair timing instead of
 *    0.41 (prepared rays 0.56), the bunny's 0.47 down to 0.41.  Even
 *    duplicated references leave this walk short of 0.5 there.
 */


/* attrs: the query asks for u, v and/or the normal (closest hit only).  A
 * copy of its own, so the walk for plain queries carries no u, v and no
 * triangle index ("no u/v or normals unless asked"). */
static SIDX_INLINE int stack_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                  const int traced, const int anyhit, const int obb, const int attrs)
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
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }
    float tn, tf;
    const int hroot = node_box(b, &br, r, 0, scale, tmin, best, &tn, &tf, obb);
    EMIT_BOX(0u, hroot, tn, tf);
    if (!hroot) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }
    /* Deferred far children and their entry distances; depth and exit
     * distance only for the events (dead stores in the untraced copy). */
    uint32_t stk[BVH_DEPTH_LIMIT], stk_depth[BVH_DEPTH_LIMIT];
    float stk_tn[BVH_DEPTH_LIMIT], stk_tf[BVH_DEPTH_LIMIT];
    uint32_t sp = 0, node = 0, depth = 0;
    for (;;) {
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
                  e_.t_near = tn; e_.t_far = tf);
        const bvh_node *n = &nodes[node];
        if (bvh_is_leaf(n)) {
            if (leaf_test(a, b, n, r, q, &best, &prim, attrs, anyhit, traced)) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                          e_.reason = SIDX_TERM_ANY_HIT; e_.count = visited);
                return 1;
            }
        } else {
            const uint32_t l = node + 1, rc = n->left_or_first;
            float ln, lf, rn, rf;
            const int hl = node_box(b, &br, r, l, scale, tmin, best, &ln, &lf, obb);
            const int hr = node_box(b, &br, r, rc, scale, tmin, best, &rn, &rf, obb);
            EMIT_BOX(l, hl, ln, lf);
            EMIT_BOX(rc, hr, rn, rf);
            if (hl && hr) {
                /* Both: nearer entry first (ties: left), the other waits.
                 * (A branch-free version of this choice measured no
                 * faster with gcc -O2; this one reads like the slide.) */
                uint32_t near = l, far = rc;
                float fn = rn, ff = rf;
                tn = ln;
                tf = lf;
                if (rn < ln) {
                    near = rc;
                    far = l;
                    fn = ln;
                    ff = lf;
                    tn = rn;
                    tf = rf;
                }
                stk[sp] = far;
                stk_tn[sp] = fn;
                if (traced) {
                    stk_depth[sp] = depth + 1;
                    stk_tf[sp] = ff;
                }
                ++sp;
                SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id; e_.node = far; e_.depth = sp;
                          e_.t_near = fn; e_.t_far = ff);
                node = near;
                ++depth;
                continue;
            }
            if (hl | hr) {
                node = hl ? l : rc;
                tn = hl ? ln : rn;
                tf = hl ? lf : rf;
                ++depth;
                continue;
            }
        }
        /* Pop the next deferred node that can still hold a closer hit. */
        for (;;) {
            if (sp == 0) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                          e_.reason = SIDX_TERM_STACK_EMPTY; e_.t = best; e_.count = visited);
                if (!anyhit && prim != SIDX_NO_HIT) {
                    if (attrs) {
                        set_hit(a, b, r, q, best, prim, hit);
                    } else {
                        hit->t = best;
                        hit->prim = prim;
                    }
                }
                return 0;
            }
            --sp;
            SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_POP, e_.ray_id = q->ray_id; e_.node = stk[sp];
                      e_.depth = sp + 1; e_.t_near = stk_tn[sp]; e_.t_far = stk_tf[sp]);
            if (stk_tn[sp] < best * scale) { /* best widened as in bvh_slab */
                node = stk[sp];
                tn = stk_tn[sp];
                if (traced) {
                    tf = stk_tf[sp];
                    depth = stk_depth[sp];
                }
                break;
            }
        }
    }
}

/* ---- recursive: naive and ordered --------------------------------------- */

typedef struct walk {
    const sidx_accel *a;
    const bvh *b;
    const sidx_ray *r;
    const sidx_query *q;
    bvh_ray br;
    float scale, best;
    uint32_t tri, visited; /* the best hit so far: its leaf copy's index */
    int anyhit, obb;
} walk;

static int naive_rec0(walk *w, uint32_t node, uint32_t depth);
static int naive_rec1(walk *w, uint32_t node, uint32_t depth);
static int ordered_rec0(walk *w, uint32_t node, uint32_t depth, float tn, float tf);
static int ordered_rec1(walk *w, uint32_t node, uint32_t depth, float tn, float tf);

static SIDX_INLINE int walk_box(walk *w, uint32_t i, float *tn, float *tf)
{
    return w->obb ? node_box(w->b, &w->br, w->r, i, w->scale, w->r->tmin, w->best, tn, tf, 1)
                  : node_box(w->b, &w->br, w->r, i, w->scale, w->r->tmin, w->best, tn, tf, 0);
}

static SIDX_INLINE int walk_leaf(walk *w, const bvh_node *n, const int traced)
{
    return w->anyhit ? leaf_test(w->a, w->b, n, w->r, w->q, &w->best, &w->tri, 1, 1, traced)
                     : leaf_test(w->a, w->b, n, w->r, w->q, &w->best, &w->tri, 1, 0, traced);
}

/* The deck's hit(ray, node, best): "test if ray hits node's bbox ... if
 * (hit.prim == NULL || hit.t > best.t) return" — the box is clipped to
 * [tmin, best], so a box behind the best hit is a miss — then leaves test
 * their primitives and inner nodes "traverse BOTH children". */
static SIDX_INLINE int naive_body(walk *w, uint32_t node, uint32_t depth, const int traced)
{
    const sidx_accel *a = w->a;
    const bvh *b = w->b;
    const sidx_query *q = w->q;
    float tn, tf;
    const int h = walk_box(w, node, &tn, &tf);
    EMIT_BOX(node, h, tn, tf);
    if (!h) return 0;
    ++w->visited;
    SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
              e_.t_near = tn; e_.t_far = tf);
    const bvh_node *n = &b->nodes[node];
    if (bvh_is_leaf(n)) return walk_leaf(w, n, traced);
    const uint32_t right = n->left_or_first;
    if (traced ? naive_rec1(w, node + 1, depth + 1) : naive_rec0(w, node + 1, depth + 1)) return 1;
    return traced ? naive_rec1(w, right, depth + 1) : naive_rec0(w, right, depth + 1);
}
static int naive_rec0(walk *w, uint32_t node, uint32_t depth) { return naive_body(w, node, depth, 0); }
static int naive_rec1(walk *w, uint32_t node, uint32_t depth) { return naive_body(w, node, depth, 1); }

/* The deck's better hit(): the node's own box was tested by its parent
 * (or by the caller for the root), so test both children, visit the one
 * with the smaller entry t first, the other only if it can still win. */
static SIDX_INLINE int ordered_body(walk *w, uint32_t node, uint32_t depth, float tn, float tf, const int traced)
{
    const sidx_accel *a = w->a;
    const bvh *b = w->b;
    const sidx_query *q = w->q;
    ++w->visited;
    SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
              e_.t_near = tn; e_.t_far = tf);
    const bvh_node *n = &b->nodes[node];
    if (bvh_is_leaf(n)) return walk_leaf(w, n, traced);
    uint32_t c1 = node + 1, c2 = n->left_or_first;
    float n1, f1, n2, f2;
    int h1 = walk_box(w, c1, &n1, &f1);
    int h2 = walk_box(w, c2, &n2, &f2);
    EMIT_BOX(c1, h1, n1, f1);
    EMIT_BOX(c2, h2, n2, f2);
    if (h2 && (!h1 || n2 < n1)) { /* the right child is the nearer one */
        uint32_t tc = c1; c1 = c2; c2 = tc;
        int th = h1; h1 = h2; h2 = th;
        float t = n1; n1 = n2; n2 = t;
        t = f1; f1 = f2; f2 = t;
    }
    if (h1 && (traced ? ordered_rec1(w, c1, depth + 1, n1, f1) : ordered_rec0(w, c1, depth + 1, n1, f1)))
        return 1;
    if (h2 && n2 < w->best * w->scale) /* best widened as in bvh_slab */
        return traced ? ordered_rec1(w, c2, depth + 1, n2, f2) : ordered_rec0(w, c2, depth + 1, n2, f2);
    return 0;
}
static int ordered_rec0(walk *w, uint32_t node, uint32_t depth, float tn, float tf)
{
    return ordered_body(w, node, depth, tn, tf, 0);
}
static int ordered_rec1(walk *w, uint32_t node, uint32_t depth, float tn, float tf)
{
    return ordered_body(w, node, depth, tn, tf, 1);
}

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
    int found = 0, missed_root = b->num_nodes == 0;
    if (!missed_root) {
        if (ordered) {
            float tn, tf;
            const int h = walk_box(&w, 0, &tn, &tf);
            EMIT_BOX(0u, h, tn, tf);
            if (h) found = traced ? ordered_rec1(&w, 0, 0, tn, tf) : ordered_rec0(&w, 0, 0, tn, tf);
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

/* ---- entry points ---------------------------------------------------------- */

/* The copies for queries asking for u, v or the normal are functions of
 * their own: inlined into the entry point beside the plain copies they
 * cost the plain walk 2-3% more instructions (callgrind: one register
 * allocation for all of them). */
#define STACK_WALK_FN(name_, traced_, anyhit_, obb_, attrs_)                                                  \
    static SIDX_NOINLINE int name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit) \
    {                                                                                                           \
        return stack_walk(a, r, q, hit, traced_, anyhit_, obb_, attrs_);                                        \
    }
STACK_WALK_FN(sw_plain, 0, 0, 0, 0)
STACK_WALK_FN(sw_attrs, 0, 0, 0, 1)
STACK_WALK_FN(sw_attrs_obb, 0, 0, 1, 1)
STACK_WALK_FN(sw_traced_attrs, 1, 0, 0, 1)
STACK_WALK_FN(sw_traced_attrs_obb, 1, 0, 1, 1)
#undef STACK_WALK_FN

/* The recursive walks (teaching paths) out of line too, for the same
 * reason: the entry point's register allocation is the stack walk's. */
static SIDX_NOINLINE int rec_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                  int anyhit, int ordered, int traced)
{
    if (traced) return ordered ? recursive_walk(a, r, q, hit, anyhit, 1, 1) : recursive_walk(a, r, q, hit, anyhit, 0, 1);
    return ordered ? recursive_walk(a, r, q, hit, anyhit, 1, 0) : recursive_walk(a, r, q, hit, anyhit, 0, 0);
}

static SIDX_INLINE int dispatch(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                const int anyhit, const int traced)
{
    const int obb = ((const bvh *)a->impl)->obbs != NULL;
    const int attrs = !anyhit && (q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL));
    switch (q->traversal) {
    case SIDX_TRAVERSE_NAIVE: return rec_walk(a, r, q, hit, anyhit, 0, traced);
    case SIDX_TRAVERSE_ORDERED: return rec_walk(a, r, q, hit, anyhit, 1, traced);
    default:
        if (attrs && traced) return obb ? sw_traced_attrs_obb(a, r, q, hit) : sw_traced_attrs(a, r, q, hit);
        if (attrs) return obb ? sw_attrs_obb(a, r, q, hit) : sw_attrs(a, r, q, hit);
        return obb ? stack_walk(a, r, q, hit, traced, anyhit, 1, 0) : stack_walk(a, r, q, hit, traced, anyhit, 0, 0);
    }
}

/* Every query but the hot one: u, v or normal, traced, oriented boxes,
 * the recursive walks. */
static SIDX_NOINLINE void intersect_other(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    if (SIDX_QUERY_TRACED(q)) dispatch(a, r, q, hit, 0, 1);
    else dispatch(a, r, q, hit, 0, 0);
}

/* The entry point only sorts queries, before any set-up, so that each
 * walk runs in a function of its own with registers allocated for it
 * alone.  Measured (callgrind, bvh, diffuse rays, 20k): u, v or normal
 * queries — the "fair" path, as rtcIntersect1 fills them — were tested
 * inside the function holding all the walks, behind their prologue (six
 * saved registers, a 1.4 KB frame, the ray's constants): ~45 instructions
 * per ray; the plain walk on its own (sw_plain) takes 0.4% (bunny) to 1%
 * (Sponza) fewer instructions than inlined here beside the others. */
void sidx__bvh_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    if (q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)) {
        if (q->traversal != SIDX_TRAVERSE_NAIVE && q->traversal != SIDX_TRAVERSE_ORDERED && !SIDX_QUERY_TRACED(q)) {
            if (((const bvh *)a->impl)->obbs != NULL) sw_attrs_obb(a, r, q, hit);
            else sw_attrs(a, r, q, hit);
            return;
        }
        intersect_other(a, r, q, hit);
        return;
    }
    if (q->traversal == SIDX_TRAVERSE_NAIVE || q->traversal == SIDX_TRAVERSE_ORDERED || SIDX_QUERY_TRACED(q) ||
        ((const bvh *)a->impl)->obbs != NULL) {
        intersect_other(a, r, q, hit);
        return;
    }
    sw_plain(a, r, q, hit);
}

int sidx__bvh_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return SIDX_QUERY_TRACED(q) ? dispatch(a, r, q, NULL, 1, 1) : dispatch(a, r, q, NULL, 1, 0);
}
