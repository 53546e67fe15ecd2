/* kdtree_traverse.c — front-to-back kd-tree traversal with an explicit stack.
 *
 * The deck's inner loop ("kD-Tree Traversal: Inner Loop"), point by point:
 *
 *   - the ray is clipped to the scene box once; after that the current
 *     cell is only implicit, as the interval [t_near, t_far] of the ray
 *     inside it ("Implicitly maintain the bounds of the current node");
 *   - at an inner node, one subtract and one multiply:
 *         t_split = (split − o[axis]) · inv_dir[axis]
 *     and three cases: t_split > t_far → near child only; t_split < t_near
 *     → far child only; otherwise push (far, t_split, t_far) and continue
 *     with (near, t_near, t_split).  Near/far follow the sign of the
 *     direction on the split axis;
 *   - the stack holds only (node, t_near, t_far) ("Store only necessary
 *     info on the stack");
 *   - "Traversal can be terminated as soon as surface intersection is found
 *     in the current node": after a leaf, stop if the closest hit lies in
 *     [t_near, t_far] of that leaf.  A triangle straddling several cells
 *     may report a hit *beyond* t_far, inside a later cell — the deck's
 *     "CANNOT terminate !!!" case: that hit is kept as the best so far (it
 *     also bounds every later triangle test) but the walk goes on, since a
 *     closer triangle may still wait in the next cell.
 *
 * Edge cases, decided here once:
 *
 *   - rounding: t_split, t_near and t_far each carry a relative error of a
 *     few ulps, so a ray aimed exactly at a vertex lying on a split plane
 *     (t_split ≈ t_near) could be sent to the wrong side and miss the one
 *     triangle that touches the plane there.  A child is therefore ruled
 *     out only when t_split lies outside [t_near, t_far] widened by 2γ₃ on
 *     both ends (the Ize 2013 bound the robust box test uses); inside that
 *     window both children are visited, the deck's `<=`/`>=` ties included;
 *   - a ±0 direction component gives inv_dir = ±inf, so t_split = ±inf and
 *     the ray stays on the side of its origin, which the sign rule picks
 *     (+0: near = left; origin above the plane → t_split = −inf → far =
 *     right).  If the origin lies exactly ON the plane, 0·inf = NaN: the ray
 *     runs inside the plane, which belongs to both closed cells, so both
 *     children are visited over the whole interval; since the two intervals
 *     then overlap, early termination is switched off for the rest of this
 *     ray (a hit in the first child need not be the closest);
 *   - a split exactly at a non-parallel ray's origin gives t_split = ±0 =
 *     t_near: both children, the near one with an empty interval;
 *   - the early-termination test widens t_far by 1 + 2γ₃ (Ize 2013, as the
 *     robust box test does) so a hit computed a rounding error past the
 *     cell boundary still ends the walk rather than costing another cell,
 *     and a popped cell starting beyond the best hit is skipped.
 *
 * Two departures from the deck's loop, both measured on the bunny: the
 * three-way decision is computed without branches, and a child that is an
 * empty leaf is never entered (its sibling pair is fetched together, so
 * the check costs no extra memory access).  SIDX_TRAVERSE_NAIVE runs the
 * deck's naive variant instead: left child first whatever the ray's
 * direction, every overlapped cell visited, no early termination.
 *
 * Measured and rejected (bunny, 20k primary + 20k diffuse rays, callgrind
 * and interleaved timings against "bvh"): the deck's branchy three-way
 * step executes ~30% fewer instructions but ran ~10% slower (the near/far
 * branch is a coin toss); a step that also selects the next node's word
 * and interval by bit masks, with no branch at all, halves the
 * mispredictions but adds enough instructions to run no faster.
 * Measured and rejected later (same rays, callgrind with a 2 MB L2 and
 * branch simulation, best of 7 interleaved CPU-time rounds against "bvh"):
 *   - the near/far choice (`vf`, mispredicted ~48% of steps) made
 *     branch-free, node and interval by integer masks and no-valid-child
 *     sent to an empty sentinel leaf: mispredictions -35%, instructions
 *     +21%, primary rays ~25% slower — a correctly predicted branch lets
 *     the CPU start the next node's load before the compare resolves,
 *     the masks put the whole compare chain on the load's path;
 *   - both children pushed by conditional stack-pointer increments and
 *     the next cell always popped: mispredictions -55%, ~15% slower (the
 *     node index goes through a store-to-load forward on every step);
 *   - only the no-valid-child case sent to a static empty cell instead of
 *     `goto pop`: gcc turns the pointer choice back into a branch, or
 *     with a mask adds ~6% instructions; no gain;
 *   - widening t_split once (|t_split|·2γ₃) instead of t_near and t_far:
 *     -2% instructions but diffuse rays ~4% slower — the widening then
 *     waits for t_split and lengthens the chain the near/far branch
 *     resolves on, while t_near/t_far are widened in parallel with the
 *     node load — and decisions no longer match the bound above;
 *   - prefetching a child leaf's triangles when it is peeked at: no gain;
 *   - building the larger-area child's subtree first so the common
 *     descent reads the adjacent pair: no measurable gain (the pair of a
 *     child whose sibling is a leaf is adjacent already).
 *
 * Leaves (kdtree_internal.h): the untraced walk with the default
 * watertight test runs the SSE kernel wide_tri4_test on each block of four
 * references the leaf covers.  Measured on the bunny (20k rays, callgrind,
 * best of 5 CPU-time runs interleaved with the scalar per-triangle
 * version and "bvh"): instructions -9% (primary) / -10% (diffuse);
 * rays/s +3-10% with the same tree, and the cheaper leaves make larger
 * leaves pay (KD_DEFAULT_C_TRAV, kdtree_internal.h): together +20%.
 *
 * Mailboxing (the deck's grid slide: "Per-ray cache of object IDs — data
 * local to a ray (better!)"), in the scalar leaf loop (traced walks, other
 * triangle tests, no SSE2): a triangle referenced by several leaves is
 * tested once per ray.  The block walk has none: re-testing a lane inside
 * a block costs nothing.  The cache is a 16-entry direct-mapped table on
 * the stack, keyed by the triangle's id, indexed by its low bits; a
 * collision only
 * evicts (re-testing is correct, just slower), so no allocation and no
 * per-object state is needed and concurrent queries never share anything.
 * Its cost on the hot path, measured (bunny, 20k diffuse rays, callgrind):
 * switched off (no_mailbox) the walk executes 0.8% more instructions
 * (re-tests) and 2% fewer mispredicted branches — a wash either way, so
 * it stays on by default. */
#include "kdtree_internal.h"

#define SIDX_STRUCTURE_NAME "kdtree"

#define KD_MAILBOX 16u
/* The SSE kernel for whole leaf blocks (bvh_wide_internal.h) where SSE2 is there. */
#if defined(SIDX_WIDE_X86) && defined(__SSE2__)
#define KD_SIMD 1
#else
#define KD_SIMD 0
#endif
/* 2γ₃ (Ize 2013): the relative error bound of t_split against t_near /
 * t_far, all three computed as (plane − o)·inv_dir. */
#define KD_TS_EPS (SIDX_ROBUST_TFAR_SCALE - 1.0f)

typedef struct kd_entry {
    uint32_t node, depth;
    float t0, t1;
} kd_entry;

/* u, v and the normal of the closest hit, when the query asks (a->fills_uv,
 * fills_ng): from the block's copy of the triangle, which is in cache,
 * instead of the mesh look-ups a diffuse ray mostly misses.  Run once,
 * when the walk returns.  u, v by wide_lane_hit_uv (the accepting test's
 * float edge functions and its own last step, so its bits, or the whole
 * test again when that does not apply). */
static SIDX_NOINLINE void kd_hit_attrs(const sidx_accel *a, const sidx_ray *r, const sidx_query *q,
                                       const wide_tri4 *B, unsigned lane, sidx_hit *hit)
{
    float u = 0.0f, v = 0.0f;
    if ((q->flags & SIDX_QUERY_UV) && wide_lane_hit_uv(a, r, B, lane, &u, &v)) {
        hit->u = u;
        hit->v = v;
    }
    if (q->flags & SIDX_QUERY_NORMAL) hit->ng = wide_lane_normal(B, lane);
}

#if KD_SIMD
/* A block the SIMD kernel declined (some lane's edge function is exactly
 * 0): the scalar test, which redoes those in double, lane by lane; the
 * smallest t wins, the lowest lane on ties, as in the kernel. */
static SIDX_NOINLINE int kd_block_scalar(const sidx_accel *a, const sidx_ray *r, const wide_tri4 *B, float best,
                                         float *t_out, unsigned *lane_out)
{
    int found = 0;
    for (unsigned l = 0; l < 4; ++l) {
        if (B->prim[l] == WIDE_PAD_PRIM) continue;
        float t;
        if (wide_lane_test(a, r, B, l, best, &t, NULL, NULL)) {
            best = t;
            *t_out = t;
            *lane_out = l;
            found = 1;
        }
    }
    return found;
}
#endif

/* The closest hit, written once when the walk ends. */
static SIDX_INLINE void kd_finish(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, const wide_tri4 *B,
                                  unsigned lane, float t, sidx_hit *hit)
{
    hit->t = t;
    hit->prim = B->prim[lane];
    if (SIDX_UNLIKELY(q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL))) kd_hit_attrs(a, r, q, B, lane, hit);
}

/* One template, instantiated per (traced, any-hit, naive).  Returns 1 when
 * something was hit.  For closest-hit queries `hit` carries the best hit. */
static SIDX_INLINE int kd_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                               const int traced, const int any, const int naive)
{
    const kd_tree *kd = a->impl;
    const kd_node *nodes = kd->nodes;
    const wide_tri4 *blocks = kd->blocks;
    const sidx_tri_method method = a->opt.tri;
    const int robust = a->opt.box == SIDX_BOX_ROBUST;
    const float org[3] = {r->org.x, r->org.y, r->org.z};
    const float inv[3] = {r->inv_dir.x, r->inv_dir.y, r->inv_dir.z};
    const uint32_t sign[3] = {r->sign[0], r->sign[1], r->sign[2]};
    float tmax = any ? r->tmax : hit->t; /* closest hit so far bounds every test */
    int found = 0;
    const wide_tri4 *hit_block = NULL; /* where the best hit's triangle copy is (u, v, normal) */
    unsigned hit_lane = 0;
    uint32_t visited = 0;
    (void)visited;

    float t0, t1;
    if (kd->num_refs == 0 || !sidx__box_test(robust, r, &kd->bounds, r->tmin, tmax, &t0, &t1)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }

#if KD_SIMD
    /* untraced walks with the default (watertight) test run the SSE
     * kernel on whole blocks; traced walks test reference by reference
     * so that every test and mailbox event is reported */
    const int simd = !traced && method == SIDX_TRI_WATERTIGHT;
    wide_tri_ray R;
    wide_tri_ray_init(&R, r);
#else
    const int simd = 0;
#endif
    const int mailbox = !a->opt.no_mailbox && !simd; /* the scalar leaf loop's */
    kd_entry stack[KD_MAX_DEPTH + 2];
    unsigned sp = 0;
    uint32_t mbox[KD_MAILBOX];
    if (mailbox) memset(mbox, 0xff, sizeof mbox);
    int may_stop = !naive; /* early termination allowed (see the NaN case) */
    uint32_t node = 0, depth = 0;
    const uint64_t empty = kd_word_empty();

    for (;;) {
        const kd_node *nd = &nodes[node];
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
                  e_.t_near = t0; e_.t_far = t1);
        while (!kd_is_leaf(nd)) {
            const uint32_t axis = kd_axis(nd);
            const float ts = (nd->u.split - org[axis]) * inv[axis];
            const uint32_t c = kd_child(nd);
            if (!naive) {
                /* The three cases, written without branches: a kd step is
                 * a dependent chain (load, subtract, multiply, compare,
                 * load) and a mispredicted three-way branch per level
                 * costs more than the step itself ("Latency can harm
                 * you!").  The far entry is always written to the stack
                 * and the stack pointer advances only in the "both" case.
                 * NaN compares false both ways, so it lands in "both" with
                 * the full interval on each side (ts > t0 ? ts : t0 keeps
                 * t0 for NaN, ts < t1 ? ts : t1 keeps t1). */
                const uint32_t sg = sign[axis];
                const uint32_t first = c + sg, second = c + 1u - sg;
                /* robust: only a plane clearly outside the widened
                 * interval rules a child out (see the header) */
                const int far_only = ts < t0 - fabsf(t0) * KD_TS_EPS;
                const int near_only = ts > t1 + fabsf(t1) * KD_TS_EPS;
                const float s0 = ts > t0 ? ts : t0, f1 = ts < t1 ? ts : t1;
                /* The siblings share 16 bytes, usually one cache line, and
                 * one of them is the next load anyway: peeking at both lets
                 * the walk skip empty leaves (the SAH's "big empty cells")
                 * instead of entering each and popping right back. */
                const uint64_t wf = kd_word(&nodes[first]), ws = kd_word(&nodes[second]);
                const int vf = !far_only & (wf != empty);
                const int vs = !near_only & (ws != empty);
                stack[sp].node = second;
                stack[sp].t0 = s0;
                stack[sp].t1 = t1;
                if (traced) stack[sp].depth = depth + 1u;
                sp += (unsigned)(vf & vs);
                if (traced && (vf & vs))
                    SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id; e_.node = second;
                              e_.depth = sp; e_.t_near = s0; e_.t_far = t1);
                if (SIDX_UNLIKELY(ts != ts)) may_stop = 0; /* ray inside the plane: intervals overlap */
                if (SIDX_UNLIKELY(!(vf | vs))) goto pop;
                node = vf ? first : second;
                t0 = vf ? t0 : s0;
                t1 = vf ? f1 : t1;
            } else {
                /* the deck's naive traversal: left child always first, no
                 * ordering along the ray, no early termination */
                const uint32_t sg = sign[axis];
                const int far_only = ts < t0 - fabsf(t0) * KD_TS_EPS;
                const int near_only = ts > t1 + fabsf(t1) * KD_TS_EPS;
                const float lo = ts > t0 ? ts : t0, hi = ts < t1 ? ts : t1;
                /* near child [t0, hi], far child [lo, t1]; left = near unless the ray runs -axis */
                const int vnear = !far_only, vfar = !near_only;
                const int vl = sg ? vfar : vnear, vr = sg ? vnear : vfar;
                const float l0 = sg ? lo : t0, l1 = sg ? t1 : hi, r0 = sg ? t0 : lo, r1 = sg ? hi : t1;
                const float f0 = vl ? l0 : r0, f1 = vl ? l1 : r1, s0 = r0, s1 = r1;
                if (vl && vr) {
                    stack[sp].node = c + 1u;
                    stack[sp].depth = depth + 1u;
                    stack[sp].t0 = s0;
                    stack[sp].t1 = s1;
                    ++sp;
                    SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id; e_.node = c + 1u;
                              e_.depth = sp; e_.t_near = s0; e_.t_far = s1);
                }
                node = vl ? c : c + 1u;
                t0 = f0;
                t1 = f1;
            }
            ++depth;
            nd = &nodes[node];
            ++visited;
            SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
                      e_.t_near = t0; e_.t_far = t1);
        }

        /* leaf: test its triangles */
        const uint32_t cnt = kd_count(nd), off = kd_offset(nd);
#if KD_SIMD
        if (simd) {
            /* every block holding one of the leaf's references, all four
             * lanes (a neighbour's triangle costs nothing extra here and
             * a hit on it is a true hit, kdtree_internal.h); no mailbox:
             * a re-test inside a block is free */
            const wide_tri4 *B = blocks + (off >> 2), *const E = blocks + ((off + cnt + 3u) >> 2);
            for (; B < E; ++B) {
                float t;
                unsigned lane;
                int h = wide_tri4_test(B, &R, tmax, &t, &lane, NULL);
                if (SIDX_UNLIKELY(h < 0)) h = kd_block_scalar(a, r, B, tmax, &t, &lane);
                if (h) {
                    if (any) return 1;
                    found = 1;
                    tmax = t;
                    hit_block = B;
                    hit_lane = lane;
                }
            }
        } else
#endif
        {
            for (uint32_t i = 0; i < cnt; ++i) {
                const wide_tri4 *B = &blocks[(off + i) >> 2];
                const unsigned l = (off + i) & 3u;
                const uint32_t p = B->prim[l];
                if (mailbox) {
                    uint32_t *slot = &mbox[p & (KD_MAILBOX - 1u)];
                    if (*slot == p) {
                        SIDX_EMIT(traced, q->hook, SIDX_EV_MAILBOX_HIT, e_.ray_id = q->ray_id; e_.prim = p;
                                  e_.node = node);
                        continue;
                    }
                    *slot = p;
                }
                float t;
                const int h = wide_lane_test(a, r, B, l, tmax, &t, NULL, NULL);
                SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.prim = p; e_.node = node;
                          e_.result = h; e_.t = h ? t : INFINITY);
                if (h) {
                    if (any) {
                        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                                  e_.reason = SIDX_TERM_ANY_HIT; e_.t = t; e_.count = visited);
                        return 1;
                    }
                    found = 1;
                    tmax = t;
                    hit_block = B;
                    hit_lane = l;
                    SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = p; e_.t = t;
                              e_.node = node);
                }
            }
        }
        /* the closest hit lies inside this cell: nothing behind can beat it */
        if (found && may_stop && tmax <= t1 + fabsf(t1) * (SIDX_ROBUST_TFAR_SCALE - 1.0f)) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_HIT_IN_CELL;
                      e_.t = tmax; e_.count = visited; e_.node = node; e_.t_near = t0; e_.t_far = t1);
            kd_finish(a, r, q, hit_block, hit_lane, tmax, hit);
            return 1;
        }
        /* pop the next cell; skip those starting behind the best hit */
    pop:
        for (;;) {
            if (sp == 0) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                          e_.reason = SIDX_TERM_STACK_EMPTY; e_.t = found ? tmax : INFINITY; e_.count = visited);
                if (found && !any) kd_finish(a, r, q, hit_block, hit_lane, tmax, hit);
                return found;
            }
            --sp;
            node = stack[sp].node;
            depth = traced ? stack[sp].depth : 0u;
            t0 = stack[sp].t0;
            t1 = stack[sp].t1;
            SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_POP, e_.ray_id = q->ray_id; e_.node = node; e_.depth = sp + 1u;
                      e_.t_near = t0; e_.t_far = t1);
            if (naive || t0 <= tmax) break;
        }
    }
}

static void kd_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    const int naive = q->traversal == SIDX_TRAVERSE_NAIVE;
    if (SIDX_QUERY_TRACED(q)) {
        if (naive) kd_walk(a, r, q, hit, 1, 0, 1);
        else kd_walk(a, r, q, hit, 1, 0, 0);
    } else {
        if (naive) kd_walk(a, r, q, hit, 0, 0, 1);
        else kd_walk(a, r, q, hit, 0, 0, 0);
    }
}

static int kd_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    sidx_hit dummy = sidx_hit_none();
    return SIDX_QUERY_TRACED(q) ? kd_walk(a, r, q, &dummy, 1, 1, 0) : kd_walk(a, r, q, &dummy, 0, 1, 0);
}

/* One vtable serves all four builders (a->variant); the tree they produce
 * has the same layout, so traversal is shared.  No refit: moving vertices
 * changes which cells a triangle overlaps, so a kd-tree must be rebuilt. */
const sidx_accel_vtable sidx__kdtree_vtable = {sidx__kd_build, kd_intersect, kd_occluded, sidx__kd_stats,
                                               sidx__kd_destroy, NULL};
