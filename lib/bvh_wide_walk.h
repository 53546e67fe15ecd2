/* bvh_wide_walk.h — one ray through a wide BVH: the traversal template.
 *
 * Not a normal header: bvh_wide.c includes it once per (width, instruction
 * set) with WALK_W (4 or 8), WALK_ISA (0 scalar, 1 SSE4.1, 2 AVX2, 3 AVX2
 * code compiled for AVX-512F/VL), WALK_ISA_NAME (scalar, sse41, avx2,
 * avx512) and WALK_TARGET (the matching __attribute__((target(...))) or
 * nothing) defined.  Every function here carries WALK_TARGET, so the SIMD
 * copies are compiled for their instruction set while the library as a
 * whole is built for baseline x86-64, and picked at run time (bvh_wide.c).
 *
 * This file is the walk, the same for every instruction set; what differs
 * (the ray's constants, the W-box test, the ranking of hit children, the
 * 4-triangle block test) is in one kernel header per instruction set,
 * included below: simd_wide_scalar.h (the portable reference, and the list
 * of what each kernel header defines), simd_wide_sse.h, simd_wide_avx2.h,
 * simd_wide_avx512.h.  The scalar copy returns bit-identical hits (see
 * "identical results" below).  Each function's name gets the width and
 * the instruction set pasted on by WFN: walk_ becomes walk_8_avx512, and
 * so on; lib/README.md, "Generated functions", lists them all.
 *
 * The walk (closest hit) per node:
 *   1. slab-test all W child boxes at once against [tmin, best]
 *      (Kay & Kajiya 1986), t_far widened by 1 + 2γ₃ (Ize 2013) exactly as
 *      sidx__box_test does, and min/max written in the order that lets a
 *      NaN slab value (0·∞: origin on the plane of an axis the ray is
 *      parallel to) never narrow the interval: MAXPS/MINPS return their
 *      SECOND operand when either is NaN, so the slab value goes first and
 *      the running interval second — the SIMD twin of `x > y ? x : y`.
 *      The far planes use 1/d pre-multiplied by the Ize factor (as
 *      Embree's robust mode does with its rdir_far): fl(fl(b − o)·fl(fl(1/d)·S))
 *      carries four roundings, like fl(fl(fl(b − o)·fl(1/d))·S) in
 *      sidx__box_test, so the same 1 + 2γ₃ bound keeps it conservative,
 *      and a node costs three multiplies fewer (with the plain test S = 1
 *      and the product is exact);
 *   2. one hit child: descend, no stack traffic (the common case deep in
 *      the tree); two: one compare; more: each goes straight to its stack
 *      slot by its rank in entry distance (rank_; the traced copy sorts
 *      by insertion, same order) — then descend into the nearest,
 *      deferring the others nearest-on-top, as Wald et al. 2008 and
 *      Embree do; every hit child is prefetched as it is handled;
 *   3. a leaf: its triangle blocks, 4 triangles per SSE pass with the
 *      watertight test (Woop, Benthin, Wald 2013) written lane-parallel;
 *   4. pop the next deferred child whose entry is still before the best hit.
 *
 * Identical results, SIMD or scalar: the slab and triangle arithmetic is
 * the same sequence of IEEE single-precision operations in every copy
 * (no FMA contraction: ISO C mode compiles with -ffp-contract=off, and the
 * intrinsics spell out mul then sub), min/max resolve NaNs the same way,
 * and a block's hits are reduced to the smallest t, ties to the lowest
 * lane — exactly what testing the 4 triangles one after another with a
 * shrinking bound accepts.  A lane whose edge function is exactly 0 sends
 * the whole block to the scalar test, which redoes it in double as the
 * paper prescribes.
 *
 * Events: the traced copy (traced = 1) emits NODE_ENTER, BOX_TEST per used
 * slot, STACK_PUSH / STACK_POP, PRIM_TEST and HIT_UPDATE per triangle (it
 * tests leaves one triangle at a time so the events say what was tested)
 * and TERMINATE; in the untraced copies every SIDX_EMIT is dead code. */

#if !defined(WALK_W) || !defined(WALK_ISA) || !defined(WALK_ISA_NAME)
#error "bvh_wide_walk.h is included by bvh_wide.c with WALK_W, WALK_ISA and WALK_ISA_NAME defined"
#endif
#if (WALK_ISA >= 2 && WALK_W != 8) || (WALK_ISA == 1 && WALK_W != 4)
#error "AVX2 and AVX-512 kernels are 8 wide, SSE4.1 kernels 4 wide"
#endif

#define WJOIN_(a, b, c) a##b##_##c
#define WJOIN(a, b, c) WJOIN_(a, b, c)
#define WFN(name) WJOIN(name, WALK_W, WALK_ISA_NAME)
#ifndef WIDE_PREFETCH
#define WIDE_PREFETCH 1
#endif
#include "hit.h"

#define WINL static inline __attribute__((always_inline)) WALK_TARGET

/* ---- the kernels of this instruction set ---------------------------------- */

#if WALK_ISA == 0
#include "simd_wide_scalar.h"
#elif WALK_ISA == 1
#include "simd_wide_sse.h"
#elif WALK_ISA == 2
#include "simd_wide_avx2.h"
#else
#include "simd_wide_avx512.h"
#endif

/* ---- prefetch, leaf, hit attributes ------------------------------------------ */

/* Start fetching a child that was hit: its node or first leaf block.
 * The walk is bound by the latency of these loads (perf: most samples sit
 * on the first load of a node or block), so every hit child is fetched
 * as soon as it is known, the nearest for now and the others for when
 * they are popped, inside the code that handles it anyway (a separate
 * loop over the hit mask and a branch-free leaf/node choice are slower:
 * docs/performance.md, "Wide BVHs").  A node is 2 (bvh4) or
 * 4 (bvh8) cache lines, a leaf block 2.5; prefetching a leaf's 4th line
 * is harmless. */
WINL void WFN(prefetch_)(const wide_bvh *w, const float *nodes, const wide_bvh *part, uint32_t ref, const int kind)
{
    const wide_tri4 *blocks = w->blocks;
    if (kind & WIDE_WALK_LAZY) { /* a lazy tree: an unbuilt child has nothing yet, a part's its own arrays */
        if ((ref & (WIDE_LEAF_BIT | WIDE_LAZY_BIT)) == WIDE_LAZY_BIT) return;
        if (ref & WIDE_PART_BIT) nodes = part->nodes, blocks = part->blocks, ref &= ~WIDE_PART_BIT;
    }
    const uintptr_t leaf = (uintptr_t)blocks + (uintptr_t)(ref & ~WIDE_LEAF_BIT) * sizeof(wide_tri4);
    const uintptr_t node = (uintptr_t)nodes + (uintptr_t)ref * (8u * WALK_W * sizeof(float));
    const char *line = (const char *)((ref & WIDE_LEAF_BIT) ? leaf : node);
    __builtin_prefetch(line);
    __builtin_prefetch(line + 64);
    __builtin_prefetch(line + 128);
    if (WALK_W == 8) __builtin_prefetch(line + 192);
}

/* One leaf: its blocks in order.  Returns 1 when an any-hit query may stop.
 *
 * Register pressure: the AVX2 walk holds the box constants (10 ymm) and
 * the triangle constants (6 xmm) across the node loop, so GCC stores 7 of
 * the ymm at every leaf entry and reloads them at the exit.  A leaf out
 * of line does not help (every xmm/ymm register is caller-saved in the
 * SysV ABI); more registers do: the AVX-512 copy keeps all the constants
 * in registers.  Figures, and the compiler tricks rejected:
 * docs/performance.md, "Wide BVHs". */
WINL int WFN(leaf_)(const sidx_accel *a, const wide_tri4 *block, const sidx_ray *r,
                    const WFN(ray_consts_) * consts, const sidx_query *q, uint32_t node_id, float *best, uint32_t *prim,
                    const wide_tri4 **hit_block, unsigned *hit_lane, float *hit_vw_det, const int anyhit,
                    const int traced, const int simd_tri)
{
    (void)consts;
    (void)node_id;
    const float *row_x, *row_y, *row_z; /* the block's rows on the ray's permuted axes, for tri4_ */
    WFN(block_rows_)(consts, block, &row_x, &row_y, &row_z);
    for (;; ++block) {
        int scalar = 1;
        if (!traced && simd_tri) {
            float t;
            unsigned lane;
            const int hit = WFN(tri4_)(row_x, row_y, row_z, consts, *best, &t, &lane, hit_vw_det);
            if (hit >= 0) {
                scalar = 0;
                if (hit) {
                    *prim = block->prim[lane] & WIDE_PRIM_MASK;
                    if (anyhit) return 1;
                    *best = t;
                    *hit_block = block;
                    *hit_lane = lane;
                }
            }
        }
        if (scalar) {
            for (int lane = 0; lane < 4; ++lane) {
                const uint32_t id = block->prim[lane] & WIDE_PRIM_MASK;
                if (id == WIDE_PAD_PRIM) continue;
                float t;
                const int found = wide_lane_test(a, r, block, (unsigned)lane, *best, &t, NULL, NULL);
                SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.node = node_id;
                          e_.prim = id; e_.result = found; e_.t = found ? t : INFINITY);
                if (found) {
                    *prim = id;
                    if (anyhit) return 1;
                    *best = t;
                    *hit_block = block;
                    *hit_lane = (unsigned)lane;
                    if (hit_vw_det) hit_vw_det[8 + lane] = NAN; /* no kernel values: uv_ computes u, v itself */
                    SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = id; e_.t = t);
                }
            }
        }
        if (block->prim[0] & WIDE_LAST_BLOCK) return 0;
        row_x += sizeof(wide_tri4) / sizeof(float);
        row_y += sizeof(wide_tri4) / sizeof(float);
        row_z += sizeof(wide_tri4) / sizeof(float);
    }
}

/* u, v and ng of the final hit, from the leaf block's copy of the
 * triangle (so no index and vertex look-ups in the mesh, which a diffuse
 * ray mostly misses in cache): the same test and normal the core would
 * compute (hit.c, sidx__hit_finish), on the same floats, so the same bits.
 * In the walk that keeps u, v (keep_uv, for queries asking for them) the
 * SIMD kernel left the accepted lane's V, W, det in vw_det, and u, v are the
 * scalar test's last step on them (sidx__tri_watertight_uv).  A hit the
 * scalar test found has det = NaN there (a kernel's det never is); then,
 * and in the other walks, u, v come from the lane's edge functions
 * (wide_lane_hit_uv: no T, no t), or, when the lane has an exactly-0 edge
 * function or the test is not the watertight one, from the whole test
 * again, whose bound only has to exceed t, which was accepted below the
 * old best, so +inf does. */
WINL void WFN(uv_)(const sidx_accel *a, const sidx_ray *r, uint32_t flags, const wide_tri4 *block, unsigned lane,
                   const float *vw_det, sidx_hit *hit)
{
    /* The corners are read where they are used (the normal last), not
     * held in registers across the u, v step, which spilled them.  The
     * walks without vw_det read them first: there the late reads made GCC
     * allocate the whole walk worse (docs/performance.md, "Wide BVHs"). */
    const int early = !vw_det;
    sidx_vec3 p0 = {0.0f, 0.0f, 0.0f}, p1 = p0, p2 = p0;
    if (early) {
        p0 = wide_lane_vertex(block, 0, lane);
        p1 = wide_lane_vertex(block, 1, lane);
        p2 = wide_lane_vertex(block, 2, lane);
    }
    if (flags & SIDX_QUERY_UV) {
        float u = 0.0f, v = 0.0f;
        if (vw_det && !isnan(vw_det[8 + lane])) {
            sidx__tri_watertight_uv(vw_det[lane], vw_det[4 + lane], vw_det[8 + lane], &u, &v);
            hit->u = u;
            hit->v = v;
        } else if (wide_lane_hit_uv(a, r, block, lane, &u, &v)) {
            hit->u = u;
            hit->v = v;
        }
    }
    if (flags & SIDX_QUERY_NORMAL) hit->ng = early ? sidx__tri_normal(p0, p1, p2) : wide_lane_normal(block, lane);
}

/* ---- the node fetch ------------------------------------------------------------ */

/* The node child `ref` names.  An eager tree: nodes[ref].  A lazy tree
 * (WIDE_WALK_LAZY; bvh_wide_internal.h, wide_lazy) also has unbuilt
 * children, whose place the root of their part takes — built now if no
 * ray reached it before (lazy.c), the void node (every slot empty) if its
 * memory could not be had — and the children of a part, marked
 * WIDE_PART_BIT, read from *part: the part entered last, for a part is
 * done before anything deferred before it is popped, so every marked
 * child on the stack is its own.  That is all a lazy walk does otherwise
 * than the eager one. */
WINL const float *WFN(fetch_node_)(const wide_bvh *w, const float *nodes, const wide_bvh **part, uint32_t ref,
                                   const sidx_query *q, const int kind)
{
    if (kind & WIDE_WALK_LAZY) {
        if (ref & WIDE_LAZY_BIT) { /* first: a part's number may have bit 29 set */
            const wide_bvh *p = sidx__lazy_get(&w->lazy->life, ref & ~WIDE_LAZY_BIT,
                                               (kind & WIDE_WALK_TRACED) ? q->hook : NULL);
            if (!p) return sidx__wide_void_node[WALK_W == 8]; /* the query reports it (lazy.c) */
            *part = p;
            return p->nodes;
        }
        if (ref & WIDE_PART_BIT) return (*part)->nodes + (size_t)(ref & ~WIDE_PART_BIT) * (8u * WALK_W);
    }
    return nodes + (size_t)ref * (8u * WALK_W);
}

/* The first triangle block of leaf child `ref`, the same way. */
WINL const wide_tri4 *WFN(fetch_leaf_)(const wide_bvh *w, const wide_bvh *part, uint32_t ref, const int kind)
{
    if ((kind & WIDE_WALK_LAZY) && (ref & WIDE_PART_BIT)) return part->blocks + (ref & ~(WIDE_LEAF_BIT | WIDE_PART_BIT));
    return w->blocks + (ref & ~WIDE_LEAF_BIT);
}

/* Insertion sort of stack[base, len), farthest at the bottom; stable, so
 * equal entries keep slot order and the lower slot is visited first (the
 * order the untraced closest-hit copies get from rank_).  The traced copy
 * moves each entry's exit t, depth and event id with it. */
WINL void WFN(sort_)(uint32_t *stack, float *stack_t_near, float *stack_t_far, uint32_t *stack_depth,
                     uint32_t *stack_id, uint32_t base, uint32_t len, const int traced)
{
    for (uint32_t i = base + 1; i < len; ++i) {
        const uint32_t moved = stack[i];
        const float moved_t_near = stack_t_near[i];
        float moved_t_far = 0.0f;
        uint32_t moved_depth = 0, moved_id = 0;
        if (traced) {
            moved_t_far = stack_t_far[i];
            moved_depth = stack_depth[i];
            moved_id = stack_id[i];
        }
        uint32_t j = i;
        while (j > base && stack_t_near[j - 1] <= moved_t_near) {
            stack[j] = stack[j - 1];
            stack_t_near[j] = stack_t_near[j - 1];
            if (traced) {
                stack_t_far[j] = stack_t_far[j - 1];
                stack_depth[j] = stack_depth[j - 1];
                stack_id[j] = stack_id[j - 1];
            }
            --j;
        }
        stack[j] = moved;
        stack_t_near[j] = moved_t_near;
        if (traced) {
            stack_t_far[j] = moved_t_far;
            stack_depth[j] = moved_depth;
            stack_id[j] = moved_id;
        }
    }
}

/* The traced copy's BOX_TEST event per used slot of a node. */
WINL void WFN(emit_boxes_)(const sidx_accel *a, const sidx_query *q, const float *node, unsigned hits,
                           const float *t_near, const float *t_far, uint32_t depth)
{
    const uint32_t *child = wide_child(node, WALK_W), *ids = wide_id(node, WALK_W);
    for (uint32_t slot = 0; slot < WALK_W; ++slot) {
        if (child[slot] == WIDE_EMPTY) continue;
        const int res = (int)((hits >> slot) & 1u);
        SIDX_EMIT(1, q->hook, SIDX_EV_BOX_TEST, e_.ray_id = q->ray_id; e_.node = ids[slot]; e_.depth = depth + 1;
                  e_.bounds = wide_slot_box(node, WALK_W, slot); e_.result = res;
                  e_.t_near = res ? t_near[slot] : NAN; e_.t_far = res ? t_far[slot] : NAN);
    }
}

/* ---- the walk ------------------------------------------------------------------ */

/* The deck's "traverse one ray, but intersect with many BVs (needs wide
 * BVH!)" (000, parallel and SIMD tracing) on the loop of the binary stack
 * walk (bvh_traverse.c, the ordered hit() of "Better BVH Traversal", 001),
 * as Wald, Benthin, Boulos 2008 and Embree run it; steps 1–4 are the ones
 * listed at the top of this file.  kind: what this copy is
 * (WIDE_WALK_*, a constant in each copy below, so every test of it is
 * resolved at compile time and no copy carries another's code). */
WINL int WFN(walk_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit, const int kind)
{
    const int anyhit = (kind & WIDE_WALK_ANYHIT) != 0, traced = (kind & WIDE_WALK_TRACED) != 0;
    const int simd_tri = (kind & WIDE_WALK_SIMD_TRI) != 0, keep_uv = (kind & WIDE_WALK_KEEP_UV) != 0;
    const wide_bvh *w = a->impl;
    const float *nodes = w->nodes;
    const wide_bvh *part = NULL; /* lazy trees: the part entered last (fetch_node_) */
    float best = anyhit ? r->tmax : hit->t;
    uint32_t prim = SIDX_NO_HIT, visited = 0;
    const wide_tri4 *hit_block = NULL;
    unsigned hit_lane = 0;
    /* keep_uv: V, W, det of hit_block's lanes, which the SIMD kernel
     * stores when it accepts a hit (uv_ turns them into u, v).  A separate
     * instantiation, so the walk without u, v carries none of it. */
    float vw_det_buf[12];
    float *const hit_vw_det = keep_uv ? vw_det_buf : NULL;
    if (w->num_inner == 0) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }
    WFN(ray_consts_) consts;
    /* Ize's factor also widens the best hit the boxes are clipped to (and
     * the pop test): a rounded entry an ulp beyond a hit must not drop a
     * box holding a triangle an ulp nearer (bvh_slab says more). */
    const float scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    WFN(ray_consts_init_)(&consts, r, scale);
    int tri_ready = 0;
    float best_s = best * scale; /* the widened bound boxes are clipped to (see bvh_slab) */

    /* Deferred children and their entry distances; exit distance, depth
     * and event id only for the events (dead in the untraced copies). */
    uint32_t stack[WIDE_STACK];
    float stack_t_near[WIDE_STACK];
    float stack_t_far[WIDE_STACK];
    uint32_t stack_depth[WIDE_STACK], stack_id[WIDE_STACK];
    _Alignas(32) float t_near[8];
    _Alignas(32) float t_far[8];
    uint32_t stack_len = 0, cur = 0, cur_id = 0, depth = 0;
    float cur_t_near = r->tmin, cur_t_far = best;
    int root_hit = 0;
    for (;;) {
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = cur_id; e_.depth = depth;
                  e_.t_near = cur_t_near; e_.t_far = cur_t_far);
        if (!(cur & WIDE_LEAF_BIT)) {
            /* 1. an inner node: slab-test its W children's boxes at once */
            const float *node = WFN(fetch_node_)(w, nodes, &part, cur, q, kind);
            const uint32_t *child = wide_child(node, WALK_W);
            unsigned hits = WFN(boxes_)(node, &consts, best_s, t_near, t_far, traced);
            if (traced) WFN(emit_boxes_)(a, q, node, hits, t_near, t_far, depth);
            if (visited == 1) root_hit = hits != 0;
            /* 2. descend into the nearest hit child, the others wait, nearest on top */
            if (hits) {
                const unsigned slot0 = (unsigned)__builtin_ctz(hits);
                hits &= hits - 1;
                if (!hits) { /* one child: descend, no stack */
                    cur = child[slot0];
                    if (!traced && WIDE_PREFETCH) WFN(prefetch_)(w, nodes, part, cur, kind);
                    if (traced) {
                        cur_t_near = t_near[slot0];
                        cur_t_far = t_far[slot0];
                        cur_id = wide_id(node, WALK_W)[slot0];
                    }
                    ++depth;
                    continue;
                }
                if (!traced && !(hits & (hits - 1))) {
                    /* Two (the most common case of several): one compare,
                     * the farther waits; ties go to the lower slot. */
                    const unsigned slot1 = (unsigned)__builtin_ctz(hits);
                    const float enter0 = t_near[slot0], enter1 = t_near[slot1];
                    if (WIDE_PREFETCH) {
                        WFN(prefetch_)(w, nodes, part, child[slot0], kind);
                        WFN(prefetch_)(w, nodes, part, child[slot1], kind);
                    }
                    const int first0 = anyhit || enter0 <= enter1;
                    stack[stack_len] = first0 ? child[slot1] : child[slot0];
                    stack_t_near[stack_len] = first0 ? enter1 : enter0;
                    ++stack_len;
                    cur = first0 ? child[slot0] : child[slot1];
                    ++depth;
                    continue;
                }
                if (!traced && !anyhit) {
                    /* Several, closest hit: each goes straight to its
                     * place, nearest on top.  rank_ gives it: how many hit
                     * children are visited before it — nearer, or as near
                     * and in a lower slot, the order the insertion sort
                     * below produces (stable, so equal entries keep slot
                     * order) — computed for each child independently, two
                     * compares of all W entries, no data-dependent branches
                     * where the sort's inner loop mispredicts
                     * (docs/performance.md, "Wide BVHs").  Entry distances
                     * are never NaN (the max with tmin). */
                    const unsigned hit_mask = hits | (1u << slot0);
                    const uint32_t top = stack_len + WFN(popc_)(hit_mask) - 1u;
                    unsigned pending = hit_mask;
                    do {
                        const unsigned slot = (unsigned)__builtin_ctz(pending);
                        pending &= pending - 1;
                        const uint32_t at = top - WFN(rank_)(t_near, slot, hit_mask);
                        stack[at] = child[slot];
                        stack_t_near[at] = t_near[slot];
                        if (WIDE_PREFETCH) WFN(prefetch_)(w, nodes, part, child[slot], kind);
                    } while (pending);
                    stack_len = top; /* the nearest is visited now, the rest wait */
                    cur = stack[top];
                    ++depth;
                    continue;
                }
                /* Several: append them, then order nearest-on-top. */
                const uint32_t base = stack_len;
                unsigned slot = slot0;
                for (;;) {
                    stack[stack_len] = child[slot];
                    if (!traced && WIDE_PREFETCH) WFN(prefetch_)(w, nodes, part, child[slot], kind);
                    stack_t_near[stack_len] = t_near[slot];
                    if (traced) {
                        stack_t_far[stack_len] = t_far[slot];
                        stack_depth[stack_len] = depth + 1;
                        stack_id[stack_len] = wide_id(node, WALK_W)[slot];
                    }
                    ++stack_len;
                    if (!hits) break;
                    slot = (unsigned)__builtin_ctz(hits);
                    hits &= hits - 1;
                }
                if (!anyhit) WFN(sort_)(stack, stack_t_near, stack_t_far, stack_depth, stack_id, base, stack_len, traced);
                --stack_len; /* the nearest is visited now, the rest wait */
                for (uint32_t i = base; traced && i < stack_len; ++i)
                    SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id; e_.node = stack_id[i];
                              e_.depth = i + 1; e_.t_near = stack_t_near[i]; e_.t_far = stack_t_far[i]);
                cur = stack[stack_len];
                if (traced) {
                    cur_t_near = stack_t_near[stack_len];
                    cur_t_far = stack_t_far[stack_len];
                    cur_id = stack_id[stack_len];
                }
                ++depth;
                continue;
            }
        } else {
            /* 3. a leaf: its blocks of four triangles */
            if (!tri_ready) { /* the triangle constants, at the first leaf: a ray that reaches none needs none */
                WFN(tri_consts_init_)(&consts, r);
                tri_ready = 1;
            }
            if (WFN(leaf_)(a, WFN(fetch_leaf_)(w, part, cur, kind), r, &consts, q, cur_id, &best, &prim, &hit_block, &hit_lane,
                           hit_vw_det, anyhit, traced, simd_tri)) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                          e_.count = visited);
                return 1;
            }
            best_s = best * scale; /* best only changes in a leaf */
        }
        /* 4. pop the next deferred child whose entry is still before the best hit */
        for (;;) {
            if (stack_len == 0) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                          e_.reason = root_hit ? SIDX_TERM_STACK_EMPTY : SIDX_TERM_MISS_ROOT; e_.t = best;
                          e_.count = visited);
                if (!anyhit && prim != SIDX_NO_HIT) {
                    hit->t = best;
                    hit->prim = prim;
                    if (q && (q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)))
                        WFN(uv_)(a, r, q->flags, hit_block, hit_lane, hit_vw_det, hit);
                }
                return 0;
            }
            --stack_len;
            SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_POP, e_.ray_id = q->ray_id; e_.node = stack_id[stack_len];
                      e_.depth = stack_len + 1; e_.t_near = stack_t_near[stack_len]; e_.t_far = stack_t_far[stack_len]);
            if (stack_t_near[stack_len] < best_s) {
                cur = stack[stack_len];
                if (traced) {
                    cur_t_near = stack_t_near[stack_len];
                    cur_t_far = stack_t_far[stack_len];
                    cur_id = stack_id[stack_len];
                    depth = stack_depth[stack_len];
                }
                break;
            }
        }
    }
}

/* Each instantiation is its own (not inlined) function, so the untraced
 * walks get the same code, registers and stack frame whether or not the
 * library is built with hooks: the hooks then cost one test per ray here
 * (the traced copy is much larger and would otherwise share a frame).
 * The copies for lazy trees are the same walks with WIDE_WALK_LAZY. */
#define WNOINL static __attribute__((noinline)) WALK_TARGET
#define WALK_ISECT(name_, kind_)                                                                                   \
    WNOINL void WFN(name_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)           \
    {                                                                                                             \
        WFN(walk_)(a, r, q, hit, kind_);                                                                          \
    }
#define WALK_OCCL(name_, kind_)                                                                                    \
    WNOINL int WFN(name_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)                           \
    {                                                                                                             \
        return WFN(walk_)(a, r, q, NULL, WIDE_WALK_ANYHIT | (kind_));                                             \
    }
WALK_ISECT(isect_traced_, WIDE_WALK_TRACED)
WALK_ISECT(isect_simd_, WIDE_WALK_SIMD_TRI)
#if WALK_TRI4
WALK_ISECT(isect_simd_uv_, WIDE_WALK_SIMD_TRI | WIDE_WALK_KEEP_UV)
#else
#define isect_simd_uv_ isect_simd_ /* no SIMD kernel, nothing to keep: the plain walk does */
#endif
WALK_ISECT(isect_other_, 0)
WALK_OCCL(occl_traced_, WIDE_WALK_TRACED)
WALK_OCCL(occl_simd_, WIDE_WALK_SIMD_TRI)
WALK_OCCL(occl_other_, 0)

WALK_ISECT(lazy_isect_traced_, WIDE_WALK_LAZY | WIDE_WALK_TRACED)
WALK_ISECT(lazy_isect_simd_, WIDE_WALK_LAZY | WIDE_WALK_SIMD_TRI)
#if WALK_TRI4
WALK_ISECT(lazy_isect_simd_uv_, WIDE_WALK_LAZY | WIDE_WALK_SIMD_TRI | WIDE_WALK_KEEP_UV)
#else
#define lazy_isect_simd_uv_ lazy_isect_simd_
#endif
WALK_ISECT(lazy_isect_other_, WIDE_WALK_LAZY)
WALK_OCCL(lazy_occl_traced_, WIDE_WALK_LAZY | WIDE_WALK_TRACED)
WALK_OCCL(lazy_occl_simd_, WIDE_WALK_LAZY | WIDE_WALK_SIMD_TRI)
WALK_OCCL(lazy_occl_other_, WIDE_WALK_LAZY)
#undef WALK_ISECT
#undef WALK_OCCL
#undef WNOINL

/* bvh_wide.c picks the untraced pair for the structure's triangle test
 * once, at build, and calls the traced one when a query has a hook. */
const wide_kernels WFN(sidx__wide_kernels_) = {
    WFN(isect_traced_),      WFN(isect_simd_),      WFN(isect_simd_uv_),      WFN(isect_other_),
    WFN(occl_traced_),       WFN(occl_simd_),       WFN(occl_other_),         WFN(lazy_isect_traced_),
    WFN(lazy_isect_simd_),   WFN(lazy_isect_simd_uv_), WFN(lazy_isect_other_), WFN(lazy_occl_traced_),
    WFN(lazy_occl_simd_),    WFN(lazy_occl_other_)};
#undef isect_simd_uv_
#undef lazy_isect_simd_uv_

/* ---- the stream walks (bvh_stream.c) -------------------------------------------
 * A buffer of rays, one after another, each through the untraced eager
 * walk: no entry checks and no choice of walk per ray, the hit set up and
 * finished beside the walk.  The walk stays a function of its own (one_*)
 * called from the loop, its registers allocated for it alone as in the
 * single-ray copies: inlined into the loop it measured no faster
 * (docs/performance.md, "The stream entry"). */
#define WSTREAM_KIND(simd_tri_, keep_uv_) (((simd_tri_) ? WIDE_WALK_SIMD_TRI : 0) | ((keep_uv_) ? WIDE_WALK_KEEP_UV : 0))
#define WSTREAM(name_, anyhit_, simd_tri_, keep_uv_)                                                           \
    static __attribute__((noinline)) WALK_TARGET int WFN(one_##name_)(const sidx_accel *a, const sidx_ray *r,  \
                                                                      const sidx_query *q, sidx_hit *hit)      \
    {                                                                                                           \
        if (anyhit_) return WFN(walk_)(a, r, q, NULL, WIDE_WALK_ANYHIT | WSTREAM_KIND(simd_tri_, 0));        \
        *hit = sidx_hit_none(); /* as sidx_accel_intersect hands it to the walk, and finishes it */             \
        hit->t = r->tmax;                                                                                       \
        (void)WFN(walk_)(a, r, q, hit, WSTREAM_KIND(simd_tri_, keep_uv_));                                     \
        sidx__finish_hit(a, r, q, hit);                                                                         \
        return 0;                                                                                               \
    }                                                                                                           \
    static __attribute__((noinline)) WALK_TARGET void WFN(name_)(const sidx_accel *a, const sidx_query *q,    \
                                                                 const bvh_stream_rays *c)                  \
    {                                                                                                           \
        const sidx_ray *rays = c->rays;                                                                         \
        const uint32_t *idx = c->idx;                                                                           \
        sidx_hit unused; /* an any-hit walk writes no hit */                                                    \
        for (uint32_t i = 0, n = c->count; i < n; ++i) {                                                        \
            const uint32_t j = idx ? idx[i] : i;                                                                \
            if (anyhit_) c->occluded[j] = WFN(one_##name_)(a, &rays[j], q, &unused);                            \
            else (void)WFN(one_##name_)(a, &rays[j], q, &c->hits[j]);                                           \
        }                                                                                                       \
    }
WSTREAM(stream_isect_simd_, 0, 1, 0)
WSTREAM(stream_isect_simd_uv_, 0, 1, WALK_TRI4)
WSTREAM(stream_isect_other_, 0, 0, 0)
WSTREAM(stream_occl_simd_, 1, 1, 0)
WSTREAM(stream_occl_other_, 1, 0, 0)
#undef WSTREAM
#undef WSTREAM_KIND

/* ---- the stream walks with several rays in flight ------------------------------
 * Where the tree is out of cache, a ray's walk is a chain of dependent
 * loads: each node is known only when its parent has arrived, and the
 * walk waits for it.  These walks keep WALK_FLIGHT rays in slots, each
 * slot holding all walk_ keeps in registers and on its stack (the ray's
 * constants, its stack of children and entry distances, its bound and
 * best hit), and advance them round-robin one step at a time: one node,
 * or one leaf and the pops after it.  While one ray waits for its node
 * the others work — software pipelining of independent pointer chases
 * (Kocberber, Falsafi, Grot 2015; Psaropoulos et al. 2017).  A step is
 * walk_'s untraced eager closest-hit code, in the same order on the same
 * values (children, ties, bounds), and what runs between two steps of a
 * ray touches nothing of its slot: so every hit is walk_'s bit for bit.
 * Where the tree fits in the cache the bookkeeping (each step loads
 * and stores its slot) makes it slower, so the build picks it by tree
 * size (bvh_wide.c, want_inflight; docs/performance.md, "Several rays in
 * flight").
 *
 * The slots live on this function's frame, no allocation: each holds a
 * full WIDE_STACK (the bound of walk_'s own stack), 8 slots about 37 KB,
 * well inside any thread's stack. */
#define WALK_FLIGHT 8 /* K: 16 gains little more out of cache (docs/performance.md) */

/* One ray between two steps. */
typedef struct WFN(flight_) {
    WFN(ray_consts_) consts;
    const sidx_ray *r;
    sidx_hit *out;                /* where its answer goes */
    const wide_tri4 *hit_block;   /* the best hit's block and lane (for u, v, ng) */
    float best, best_s;           /* walk_'s best and best_s */
    uint32_t prim, cur, stack_len;
    unsigned hit_lane;
    int tri_ready;
    float vw_det[12];             /* keep_uv: the kernel's V, W, det (walk_'s vw_det_buf) */
    uint32_t stack[WIDE_STACK];
    float stack_t_near[WIDE_STACK];
} WFN(flight_);

/* A ray into slot s: walk_'s set-up, and the root asked for. */
WINL void WFN(flight_start_)(const sidx_accel *a, WFN(flight_) * s, const sidx_ray *r, sidx_hit *out, float scale)
{
    s->r = r;
    s->out = out;
    WFN(ray_consts_init_)(&s->consts, r, scale);
    s->best = r->tmax;
    s->best_s = s->best * scale;
    s->prim = SIDX_NO_HIT;
    s->cur = 0;
    s->stack_len = 0;
    s->tri_ready = 0;
    s->hit_block = NULL;
    s->hit_lane = 0;
    if (WIDE_PREFETCH) WFN(prefetch_)(a->impl, ((const wide_bvh *)a->impl)->nodes, NULL, 0, 0);
}

/* One step of walk_ for the ray in s (steps 1–4 at the top of this
 * file, untraced, eager, closest hit); the node or block it reads next
 * is asked for.  1 when the ray has finished (its stack empty). */
WINL int WFN(flight_step_)(const sidx_accel *a, const sidx_query *q, WFN(flight_) * s, float scale, const int kind)
{
    const int simd_tri = (kind & WIDE_WALK_SIMD_TRI) != 0, keep_uv = (kind & WIDE_WALK_KEEP_UV) != 0;
    const wide_bvh *w = a->impl;
    const float *nodes = w->nodes;
    uint32_t cur = s->cur, stack_len = s->stack_len;
    if (!(cur & WIDE_LEAF_BIT)) {
        /* 1. an inner node: its W boxes */
        _Alignas(32) float t_near[8];
        _Alignas(32) float t_far[8];
        const float *node = nodes + (size_t)cur * (8u * WALK_W);
        const uint32_t *child = wide_child(node, WALK_W);
        unsigned hits = WFN(boxes_)(node, &s->consts, s->best_s, t_near, t_far, 0);
        /* 2. the nearest hit child next, the others deferred, as walk_ */
        if (hits) {
            const unsigned slot0 = (unsigned)__builtin_ctz(hits);
            hits &= hits - 1;
            if (!hits) { /* one child */
                s->cur = child[slot0];
                if (WIDE_PREFETCH) WFN(prefetch_)(w, nodes, NULL, s->cur, 0);
                return 0;
            }
            if (!(hits & (hits - 1))) { /* two: ties to the lower slot */
                const unsigned slot1 = (unsigned)__builtin_ctz(hits);
                const float enter0 = t_near[slot0], enter1 = t_near[slot1];
                if (WIDE_PREFETCH) {
                    WFN(prefetch_)(w, nodes, NULL, child[slot0], 0);
                    WFN(prefetch_)(w, nodes, NULL, child[slot1], 0);
                }
                const int first0 = enter0 <= enter1;
                s->stack[stack_len] = first0 ? child[slot1] : child[slot0];
                s->stack_t_near[stack_len] = first0 ? enter1 : enter0;
                s->stack_len = stack_len + 1;
                s->cur = first0 ? child[slot0] : child[slot1];
                return 0;
            }
            /* several: each straight to its place by rank_, nearest on top */
            const unsigned hit_mask = hits | (1u << slot0);
            const uint32_t top = stack_len + WFN(popc_)(hit_mask) - 1u;
            unsigned pending = hit_mask;
            do {
                const unsigned slot = (unsigned)__builtin_ctz(pending);
                pending &= pending - 1;
                const uint32_t at = top - WFN(rank_)(t_near, slot, hit_mask);
                s->stack[at] = child[slot];
                s->stack_t_near[at] = t_near[slot];
                if (WIDE_PREFETCH) WFN(prefetch_)(w, nodes, NULL, child[slot], 0);
            } while (pending);
            s->stack_len = top;
            s->cur = s->stack[top];
            return 0;
        }
    } else {
        /* 3. a leaf: its blocks, the bound shrinking with each hit */
        if (!s->tri_ready) {
            WFN(tri_consts_init_)(&s->consts, s->r);
            s->tri_ready = 1;
        }
        (void)WFN(leaf_)(a, WFN(fetch_leaf_)(w, NULL, cur, 0), s->r, &s->consts, q, 0, &s->best, &s->prim,
                         &s->hit_block, &s->hit_lane, keep_uv ? s->vw_det : NULL, 0, 0, simd_tri);
        s->best_s = s->best * scale;
    }
    /* 4. pop the next deferred child still before the best hit */
    const float best_s = s->best_s;
    for (;;) {
        if (stack_len == 0) return 1;
        --stack_len;
        if (s->stack_t_near[stack_len] < best_s) {
            cur = s->stack[stack_len];
            break;
        }
    }
    s->cur = cur;
    s->stack_len = stack_len;
    if (WIDE_PREFETCH) WFN(prefetch_)(w, nodes, NULL, cur, 0); /* pushed, maybe long ago: ask again */
    return 0;
}

/* The answer of a finished slot, as one_* and sidx_accel_intersect give it. */
WINL void WFN(flight_finish_)(const sidx_accel *a, const sidx_query *q, WFN(flight_) * s, const int keep_uv)
{
    sidx_hit *hit = s->out;
    *hit = sidx_hit_none();
    hit->t = s->r->tmax;
    if (s->prim != SIDX_NO_HIT) {
        hit->t = s->best;
        hit->prim = s->prim;
        if (q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL))
            WFN(uv_)(a, s->r, q->flags, s->hit_block, s->hit_lane, keep_uv ? s->vw_det : NULL, hit);
    }
    sidx__finish_hit(a, s->r, q, hit);
}

#define WFLIGHT(name_, plain_, keep_uv_)                                                                      \
    static __attribute__((noinline)) WALK_TARGET void WFN(name_)(const sidx_accel *a, const sidx_query *q,    \
                                                                 const bvh_stream_rays *c)                  \
    {                                                                                                           \
        const int kind = WIDE_WALK_SIMD_TRI | ((keep_uv_) ? WIDE_WALK_KEEP_UV : 0);                             \
        const wide_bvh *w = a->impl;                                                                            \
        if (w->num_inner == 0) { /* nothing to walk: the ray-by-ray walk answers */                             \
            WFN(plain_)(a, q, c);                                                                               \
            return;                                                                                             \
        }                                                                                                       \
        const float scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;                     \
        const uint32_t *idx = c->idx, n = c->count;                                                             \
        WFN(flight_) s[WALK_FLIGHT];                                                                            \
        /* fill the slots with the first rays */                                                                \
        uint32_t next = 0;                                                                                      \
        unsigned live = 0;                                                                                      \
        for (unsigned k = 0; k < WALK_FLIGHT && next < n; ++k, ++next) {                                        \
            const uint32_t j = idx ? idx[next] : next;                                                          \
            WFN(flight_start_)(a, &s[k], &c->rays[j], &c->hits[j], scale);                                      \
            live |= 1u << k;                                                                                    \
        }                                                                                                       \
        /* round-robin, one step per live slot; a finished slot answers and takes the next ray */               \
        for (unsigned k = 0; live; k = k + 1 == WALK_FLIGHT ? 0 : k + 1) {                                      \
            if (!(live >> k & 1u) || !WFN(flight_step_)(a, q, &s[k], scale, kind)) continue;                  \
            WFN(flight_finish_)(a, q, &s[k], keep_uv_);                                                         \
            if (next < n) {                                                                                     \
                const uint32_t j = idx ? idx[next] : next;                                                      \
                WFN(flight_start_)(a, &s[k], &c->rays[j], &c->hits[j], scale);                                  \
                ++next;                                                                                         \
            } else {                                                                                            \
                live &= ~(1u << k);                                                                             \
            }                                                                                                   \
        }                                                                                                       \
    }
WFLIGHT(flight_isect_simd_, stream_isect_simd_, 0)
WFLIGHT(flight_isect_simd_uv_, stream_isect_simd_uv_, WALK_TRI4)
#undef WFLIGHT
#undef WALK_FLIGHT

const wide_stream_kernels WFN(sidx__wide_stream_) = {WFN(stream_isect_simd_), WFN(stream_isect_simd_uv_),
                                                     WFN(stream_isect_other_), WFN(stream_occl_simd_),
                                                     WFN(stream_occl_other_), WFN(flight_isect_simd_),
                                                     WFN(flight_isect_simd_uv_)};

#undef WJOIN_
#undef WJOIN
#undef WFN
#undef WINL
#undef WALK_TRI4
