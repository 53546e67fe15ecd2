/* quantised.c — bvh8 with quantised child boxes (2 cache lines a node)
 * against its float nodes (4 lines) on the height field of `sidx-bench
 * scale --scene heightfield` (docs/performance.md, "Wide BVHs",
 * "Quantised child boxes at scale").  Not part of the build; compile and
 * run it by hand:
 *
 *   cc -std=gnu11 -O2 -ffp-contract=off -mavx2 -mfma -mpopcnt -Ilib/include -Ilib -Itests \
 *      tests/bench/probe/quantised.c tests/common/testkit.c build/lib/libsidx.a -lm -pthread -o quantised
 *   (add -mavx512f -mavx512vl for the AVX-512 build: 32 vector registers,
 *   as the library's AVX-512 copy, and a third walk, quantised-512, which
 *   decodes both planes of an axis in one 16-lane pass; valgrind runs
 *   only the AVX2 build)
 *   ./quantised D primary|diffuse time [ROUNDS]   hit check, then per round
 *       (3 by default) a warm-up pass of each walk and 5 passes of float,
 *       quantised, (quantised-512,) library in turn (thread CPU time of
 *       the 100000 rays): ratios of the best and of the median passes
 *   ./quantised D primary|diffuse lines            hit check, then per ray:
 *       distinct 64-byte lines, 4 KB and 2 MB pages of the nodes and
 *       blocks each probe walk reads (2000 rays, every 50th)
 *   valgrind --tool=callgrind --cache-sim=yes --LL=33554432,16,64 \
 *       --instr-atstart=no ./quantised D primary|diffuse cg
 *       the float walk, then the quantised one, each dumped as a part of
 *       its own (callgrind.out.PID.1, .2; callgrind_annotate gives the
 *       totals): 20000 other rays of the set warm the caches, then 2000
 *       rays (every 50th) are counted, as layout.c does
 *
 * D is the detail of the built-in scene heightfield (724: 1M, 1448: 4.2M, 2896: 16.8M
 * triangles); the rays are the scale command's 100000 (tk_make_rays, seed
 * 7).  Every mode but cg first checks the conversion and the hits: every
 * decoded plane must lie on or outside its float plane, and every ray's
 * (t bits, prim) from each probe walk must equal sidx_accel_intersect's,
 * else it says how many planes and which rays differ and exits 1.
 * -DPROBE_BREAK=1 or 2 breaks the conversion on purpose (the checks must
 * then fail): 1 moves every box's x hi plane one step in, 2 rounds each q
 * to nearest.  -DPROBE_PREFETCH=0: neither probe walk prefetches.
 * -ffp-contract=off: the triangle kernel's
 * multiplies and subtractions must not be fused, as in the library.
 *
 * The quantised node (Mahovsky 2005; Ylitie, Karras, Laine 2017 "Efficient
 * incoherent ray traversal on GPUs through compressed wide BVHs"): per
 * axis a float origin and a power-of-two step 2^e, per child and plane one
 * byte q, a plane decoded as fl(origin + q·2^e) — q·2^e is exact (8-bit q
 * times a power of two), so the decode rounds once, whether as a multiply
 * and an add or as one FMA.  The conversion computes each plane with that
 * same expression and steps q down (lo) or up (hi) until the decoded plane
 * lies outside the float box, so a decoded box contains the box the float
 * node holds.  The slab test (the library's AVX2 kernel, simd_wide_avx2.h:
 * fl(fl(b − o)·inv), far planes with 1/d times Ize's 1 + 2γ₃) is monotone
 * in b — every step is a rounded subtraction or a multiply by a constant,
 * and a NaN slab value (0·∞) never narrows the interval — so a wider box
 * gives an entry no later and an exit no earlier, and the walk reaches
 * every leaf the float walk reaches: every triangle that can give the hit
 * is tested, the same closest t.  The prim could differ only where two
 * triangles in different leaves give the same float t and the changed
 * order keeps the other one; the check would show it.  Empty slots are
 * cut by a mask byte.  The walks are one function (walk) with a
 * compile-time flag, the float copy reading the library's own nodes, so
 * quantised / float isolates the layout and the decode. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <time.h>
#include <immintrin.h>
#include <valgrind/callgrind.h>
#include "sidx/sidx.h"
#include "bvh_wide_internal.h"
#include "common/testkit.h"

#ifndef PROBE_BREAK
#define PROBE_BREAK 0
#endif
#ifndef PROBE_PREFETCH
#define PROBE_PREFETCH 1 /* 0: neither probe walk prefetches hit children */
#endif

/* ---- the quantised node: 128 bytes, 2 lines ---------------------------------- */

typedef struct qnode {
    float origin[3];   /* per axis: the node's lower corner */
    float step[3];     /* per axis: 2^e */
    uint8_t q[6][8];   /* lo_x, hi_x, lo_y, hi_y, lo_z, hi_z of the 8 children (the two planes
                        * of an axis side by side: one 16-byte load for the 512-bit decode) */
    uint32_t child[8]; /* as the float node's (WIDE_LEAF_BIT | block, node index, WIDE_EMPTY) */
    uint8_t valid;     /* bit s: slot s holds a child */
    uint8_t pad[23];
} qnode;
_Static_assert(sizeof(qnode) == 128, "a quantised node is 2 lines");

/* The decoded plane, the walk's expression: q·2^e is exact, one rounding. */
static float decode(float origin, float step, unsigned q)
{
    const volatile float prod = (float)q * step; /* exact; volatile: no fused multiply-add, same bits either way */
    return origin + prod;
}

/* One node's boxes to bytes, rounded outward; 0 if some box is not finite
 * or does not fit 255 steps. */
static int quantise_node(const float *n, qnode *out)
{
    memset(out, 0, sizeof *out);
    const uint32_t *child = wide_child(n, 8);
    for (int s = 0; s < 8; ++s) {
        out->child[s] = child[s];
        if (child[s] != WIDE_EMPTY) out->valid |= (uint8_t)(1u << s);
    }
    for (int k = 0; k < 3; ++k) {
        float lo = INFINITY, hi = -INFINITY;
        for (int s = 0; s < 8; ++s) {
            if (!(out->valid >> s & 1)) continue;
            if (!isfinite(n[k * 8 + s]) || !isfinite(n[(3 + k) * 8 + s])) return 0;
            lo = fminf(lo, n[k * 8 + s]);
            hi = fmaxf(hi, n[(3 + k) * 8 + s]);
        }
        if (out->valid == 0) lo = hi = 0.0f;
        /* smallest e with 255·2^e over the extent (in double, exact for floats); the
         * step-up below may still need a larger one, hence the loop */
        int e;
        (void)frexp(((double)hi - (double)lo) / 255.0, &e);
        if (e < -126) e = -126;
        for (;; ++e) {
            if (e > 127) return 0;
            const float step = ldexpf(1.0f, e);
            int ok = 1;
            for (int s = 0; s < 8 && ok; ++s) {
                uint8_t *ql = &out->q[2 * k][s], *qh = &out->q[2 * k + 1][s];
                if (!(out->valid >> s & 1)) {
                    *ql = 255, *qh = 0; /* masked anyway */
                    continue;
                }
                const float bl = n[k * 8 + s], bh = n[(3 + k) * 8 + s];
                long a = (long)floor(((double)bl - lo) / step), b = (long)ceil(((double)bh - lo) / step);
                if (a < 0) a = 0;
                if (b > 255) b = 255;
#if PROBE_BREAK == 2 /* deliberately wrong: nearest q, no outward steps */
                a = lround(((double)bl - lo) / step), b = lround(((double)bh - lo) / step);
                if (b > 255 || decode(lo, step, 255) < hi) ok = 0;
#else
                while (a > 0 && decode(lo, step, (unsigned)a) > bl) --a;   /* down until it contains lo */
                while (b < 255 && decode(lo, step, (unsigned)b) < bh) ++b; /* up until it contains hi */
                if (decode(lo, step, (unsigned)a) > bl || decode(lo, step, (unsigned)b) < bh) ok = 0;
                /* and back in while it still contains the plane: the tightest outward q */
                while (a < 255 && decode(lo, step, (unsigned)a + 1) <= bl) ++a;
                while (b > 0 && decode(lo, step, (unsigned)b - 1) >= bh) --b;
#endif
                *ql = (uint8_t)a, *qh = (uint8_t)b;
            }
            if (!ok) continue;
            out->origin[k] = lo;
            out->step[k] = step;
            break;
        }
    }
#if PROBE_BREAK == 1
    /* deliberately wrong: the x hi plane of every box one step inward */
    for (int s = 0; s < 8; ++s)
        if (out->q[1][s] > out->q[0][s]) --out->q[1][s];
#endif
    return 1;
}

/* ---- the walk, float or quantised --------------------------------------------- */

#define WINL static inline __attribute__((always_inline))

typedef struct consts {
    __m256 org_x, org_y, org_z, inv_x, inv_y, inv_z, far_x, far_y, far_z, tmin;
    tri4_ray tri;
    uint32_t near_off[3], far_off[3];   /* the planes of axis k: floats from b (float node) */
    uint32_t qnear_off[3], qfar_off[3]; /* and bytes from q (quantised node) */
#ifdef __AVX512F__
    __m512 org5[3], mul5[3]; /* walk 2: origin; 1/d in the lo half, 1/d·S in the hi (swapped for d < 0) */
    __m512i perm5[3];        /* walk 2: puts the entry plane's half low (identity, or the halves swapped) */
#endif
} consts_t;

/* A plane of a node on axis k: 8 floats read at off, or 8 bytes at qoff decoded. */
WINL __m256 plane(const void *node, uint32_t off, uint32_t qoff, int k, const int quant)
{
    if (!quant) return _mm256_load_ps((const float *)node + off);
    const qnode *n = node;
    const __m256 q = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(n->q[0] + qoff))));
    return _mm256_fmadd_ps(q, _mm256_broadcast_ss(&n->step[k]), _mm256_broadcast_ss(&n->origin[k]));
}

#ifdef __AVX512F__
/* Walk 2 (quantised, AVX-512 builds only): both planes of an axis decoded
 * in one 16-lane pass, entry planes in the low half, exit planes in the
 * high; the same operations per lane, in the same order, as boxes()
 * below: fl(fl(b − o)·inv) and fl(fl(b − o)·inv·S), max (slab value
 * first) into the entry half, min into the exit half.  So the same bits. */
WINL unsigned boxes512(const qnode *n, const consts_t *c, float best, float *t_near)
{
    __m512 acc = _mm512_mask_mov_ps(_mm512_set1_ps(best), 0x00FF, _mm512_castps256_ps512(c->tmin));
    for (int k = 0; k < 3; ++k) {
        const __m512 q = _mm512_cvtepi32_ps(_mm512_cvtepu8_epi32(_mm_loadu_si128((const __m128i *)(const void *)n->q[2 * k])));
        const __m512 b = _mm512_fmadd_ps(q, _mm512_set1_ps(n->step[k]), _mm512_set1_ps(n->origin[k]));
        const __m512 t = _mm512_permutexvar_ps(c->perm5[k], _mm512_mul_ps(_mm512_sub_ps(b, c->org5[k]), c->mul5[k]));
        acc = _mm512_mask_max_ps(acc, 0x00FF, t, acc);
        acc = _mm512_mask_min_ps(acc, 0xFF00, t, acc);
    }
    const __m256 t_enter = _mm512_castps512_ps256(acc);
    const __m256 t_exit = _mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(acc), 1));
    _mm256_store_ps(t_near, t_enter);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ)) & n->valid;
}
#endif

/* simd_wide_avx2.h's boxes_, the planes from plane(). */
WINL unsigned boxes(const void *node, const consts_t *c, float best, float *t_near, const int quant)
{
#ifdef __AVX512F__
    if (quant == 2) return boxes512(node, c, best, t_near);
#endif
    /* cppcheck-suppress ctuuninitvar ; walk() sets every field read here */
    const __m256 lo_x = plane(node, c->near_off[0], c->qnear_off[0], 0, quant), hi_x = plane(node, c->far_off[0], c->qfar_off[0], 0, quant);
    const __m256 lo_y = plane(node, c->near_off[1], c->qnear_off[1], 1, quant), hi_y = plane(node, c->far_off[1], c->qfar_off[1], 1, quant);
    const __m256 lo_z = plane(node, c->near_off[2], c->qnear_off[2], 2, quant), hi_z = plane(node, c->far_off[2], c->qfar_off[2], 2, quant);
    const __m256 near_x = _mm256_mul_ps(_mm256_sub_ps(lo_x, c->org_x), c->inv_x);
    const __m256 near_y = _mm256_mul_ps(_mm256_sub_ps(lo_y, c->org_y), c->inv_y);
    const __m256 near_z = _mm256_mul_ps(_mm256_sub_ps(lo_z, c->org_z), c->inv_z);
    const __m256 far_x = _mm256_mul_ps(_mm256_sub_ps(hi_x, c->org_x), c->far_x);
    const __m256 far_y = _mm256_mul_ps(_mm256_sub_ps(hi_y, c->org_y), c->far_y);
    const __m256 far_z = _mm256_mul_ps(_mm256_sub_ps(hi_z, c->org_z), c->far_z);
    __m256 t_enter = _mm256_max_ps(near_x, c->tmin);
    t_enter = _mm256_max_ps(near_y, t_enter);
    t_enter = _mm256_max_ps(near_z, t_enter);
    __m256 t_exit = _mm256_min_ps(far_x, _mm256_set1_ps(best));
    t_exit = _mm256_min_ps(far_y, t_exit);
    t_exit = _mm256_min_ps(far_z, t_exit);
    _mm256_store_ps(t_near, t_enter);
    const unsigned hits = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ));
    return quant ? hits & ((const qnode *)node)->valid : hits;
}

WINL uint32_t rank(const float *t_near, unsigned slot, unsigned hit_mask)
{
    const __m256 entries = _mm256_load_ps(t_near), own = _mm256_set1_ps(t_near[slot]);
    const unsigned nearer = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_LT_OQ));
    const unsigned as_near = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_EQ_OQ));
    return (uint32_t)__builtin_popcount(hit_mask & (nearer | (as_near & ((1u << slot) - 1u))));
}

/* What a walk touches (mode "lines"): distinct lines and pages, per ray. */
typedef struct touched {
    uintptr_t lines[1 << 14], pages[1 << 12], pages2[1 << 10];
    size_t nl, np, np2;
    size_t nodes, blocks; /* visits */
} touched;
static void add(uintptr_t *arr, size_t *n, size_t cap, uintptr_t v)
{
    for (size_t i = 0; i < *n; ++i)
        if (arr[i] == v) return;
    if (*n < cap) arr[(*n)++] = v;
}
static void touch(touched *tc, const void *p, size_t bytes)
{
    for (uintptr_t x = (uintptr_t)p & ~(uintptr_t)63; x < (uintptr_t)p + bytes; x += 64) {
        add(tc->lines, &tc->nl, 1 << 14, x);
        add(tc->pages, &tc->np, 1 << 12, x >> 12);
        add(tc->pages2, &tc->np2, 1 << 10, x >> 21);
    }
}

typedef struct tree {
    const sidx_accel *a;
    const wide_bvh *w;
    const qnode *qn;
} tree;

/* Start fetching a hit child, as the library's prefetch_: a float node's
 * 4 lines, a quantised node's 2 and one more (a leaf block is 2.5 lines,
 * whichever node array points to it). */
WINL void prefetch(const tree *tr, uint32_t ref, const int quant)
{
    if (!PROBE_PREFETCH) return;
    const uintptr_t leaf = (uintptr_t)tr->w->blocks + (uintptr_t)(ref & ~WIDE_LEAF_BIT) * sizeof(wide_tri4);
    const uintptr_t node = quant ? (uintptr_t)(tr->qn + ref) : (uintptr_t)tr->w->nodes + (uintptr_t)ref * 256u;
    const char *line = (const char *)((ref & WIDE_LEAF_BIT) ? leaf : node);
    __builtin_prefetch(line);
    __builtin_prefetch(line + 64);
    __builtin_prefetch(line + 128);
    if (!quant) __builtin_prefetch(line + 192);
}

/* bvh_wide_walk.h's untraced closest-hit walk with the SIMD triangle test
 * (walk_ with WIDE_WALK_SIMD_TRI), the same steps in the same order;
 * quant picks the node array and the plane fetch, count records what it
 * reads.  Returns the hit as sidx_accel_intersect would: t (INFINITY on a
 * miss) and prim. */
WINL void walk(const tree *tr, const sidx_ray *r, float *t_out, uint32_t *prim_out, touched *tc, const int quant,
               const int count)
{
    const wide_bvh *w = tr->w;
    float best = r->tmax;
    uint32_t prim = SIDX_NO_HIT;
    consts_t c;
    const float *o = sidx_v3_array(&r->org), *inv = sidx_v3_array(&r->inv_dir);
    const float scale = tr->a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    for (int k = 0; k < 3; ++k) {
        c.near_off[k] = (uint32_t)((r->sign[k] ? 3 + k : k) * 8);
        c.far_off[k] = (uint32_t)((r->sign[k] ? k : 3 + k) * 8);
        c.qnear_off[k] = (uint32_t)((r->sign[k] ? 2 * k + 1 : 2 * k) * 8);
        c.qfar_off[k] = (uint32_t)((r->sign[k] ? 2 * k : 2 * k + 1) * 8);
    }
#ifdef __AVX512F__
    if (quant == 2)
        for (int k = 0; k < 3; ++k) {
            const __m512 in = _mm512_set1_ps(inv[k]), fa = _mm512_set1_ps(inv[k] * scale);
            c.org5[k] = _mm512_set1_ps(o[k]);
            /* lanes 0-7 hold the lo planes, 8-15 the hi: d < 0 enters through hi */
            c.mul5[k] = r->sign[k] ? _mm512_mask_mov_ps(in, 0x00FF, fa) : _mm512_mask_mov_ps(in, 0xFF00, fa);
            c.perm5[k] = r->sign[k] ? _mm512_setr_epi32(8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7)
                                    : _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        }
#endif
    c.org_x = _mm256_set1_ps(o[0]), c.org_y = _mm256_set1_ps(o[1]), c.org_z = _mm256_set1_ps(o[2]);
    c.inv_x = _mm256_set1_ps(inv[0]), c.inv_y = _mm256_set1_ps(inv[1]), c.inv_z = _mm256_set1_ps(inv[2]);
    c.far_x = _mm256_set1_ps(inv[0] * scale), c.far_y = _mm256_set1_ps(inv[1] * scale);
    c.far_z = _mm256_set1_ps(inv[2] * scale);
    c.tmin = _mm256_set1_ps(r->tmin);
    int tri_ready = 0;
    float best_s = best * scale;
    uint32_t stack[WIDE_STACK];
    float stack_t_near[WIDE_STACK];
    _Alignas(32) float t_near[8];
    uint32_t stack_len = 0, cur = 0;
    for (;;) {
        if (!(cur & WIDE_LEAF_BIT)) {
            const void *node = quant ? (const void *)(tr->qn + cur) : (const void *)(w->nodes + (size_t)cur * 64u);
            const uint32_t *child = quant ? ((const qnode *)node)->child : wide_child(node, 8);
            if (count) touch(tc, node, quant ? 128 : 256), ++tc->nodes;
            unsigned hits = boxes(node, &c, best_s, t_near, quant);
            if (hits) {
                const unsigned slot0 = (unsigned)__builtin_ctz(hits);
                hits &= hits - 1;
                if (!hits) {
                    cur = child[slot0];
                    prefetch(tr, cur, quant);
                    continue;
                }
                if (!(hits & (hits - 1))) {
                    const unsigned slot1 = (unsigned)__builtin_ctz(hits);
                    const float enter0 = t_near[slot0], enter1 = t_near[slot1];
                    prefetch(tr, child[slot0], quant);
                    prefetch(tr, child[slot1], quant);
                    const int first0 = enter0 <= enter1;
                    stack[stack_len] = first0 ? child[slot1] : child[slot0];
                    stack_t_near[stack_len] = first0 ? enter1 : enter0;
                    ++stack_len;
                    cur = first0 ? child[slot0] : child[slot1];
                    continue;
                }
                const unsigned hit_mask = hits | (1u << slot0);
                const uint32_t top = stack_len + (uint32_t)__builtin_popcount(hit_mask) - 1u;
                unsigned pending = hit_mask;
                do {
                    const unsigned slot = (unsigned)__builtin_ctz(pending);
                    pending &= pending - 1;
                    const uint32_t at = top - rank(t_near, slot, hit_mask);
                    stack[at] = child[slot];
                    stack_t_near[at] = t_near[slot];
                    prefetch(tr, child[slot], quant);
                } while (pending);
                stack_len = top;
                cur = stack[top];
                continue;
            }
        } else {
            if (!tri_ready) {
                tri4_ray_init(&c.tri, r);
                tri_ready = 1;
            }
            /* bvh_wide_walk.h's leaf_ */
            const wide_tri4 *block = w->blocks + (cur & ~WIDE_LEAF_BIT);
            const float *row_x = &block->v[0][0][0] + c.tri.kx4, *row_y = &block->v[0][0][0] + c.tri.ky4,
                        *row_z = &block->v[0][0][0] + c.tri.kz4;
            for (;; ++block) {
                if (count) touch(tc, block, sizeof *block), ++tc->blocks;
                float t;
                unsigned lane;
                const int hit = tri4_test_axes(row_x, row_y, row_z, &c.tri, best, &t, &lane, NULL);
                if (hit > 0) {
                    prim = block->prim[lane] & WIDE_PRIM_MASK;
                    best = t;
                } else if (hit < 0) {
                    for (unsigned l = 0; l < 4; ++l) {
                        const uint32_t id = block->prim[l] & WIDE_PRIM_MASK;
                        if (id == WIDE_PAD_PRIM) continue;
                        if (tri4_lane_test(tr->a, r, block, l, best, &t, NULL, NULL)) prim = id, best = t;
                    }
                }
                if (block->prim[0] & WIDE_LAST_BLOCK) break;
                row_x += sizeof(wide_tri4) / sizeof(float);
                row_y += sizeof(wide_tri4) / sizeof(float);
                row_z += sizeof(wide_tri4) / sizeof(float);
            }
            best_s = best * scale;
        }
        for (;;) {
            if (stack_len == 0) {
                *t_out = prim == SIDX_NO_HIT ? INFINITY : best;
                *prim_out = prim;
                return;
            }
            --stack_len;
            if (stack_t_near[stack_len] < best_s) {
                cur = stack[stack_len];
                break;
            }
        }
    }
}

static __attribute__((noinline)) void walk_float(const tree *tr, const sidx_ray *r, float *t, uint32_t *prim)
{
    walk(tr, r, t, prim, NULL, 0, 0);
}
static __attribute__((noinline)) void walk_quant(const tree *tr, const sidx_ray *r, float *t, uint32_t *prim)
{
    walk(tr, r, t, prim, NULL, 1, 0);
}
#ifdef __AVX512F__
#define WALKS 3 /* float, quantised, quantised with the 512-bit decode */
static __attribute__((noinline)) void walk_quant512(const tree *tr, const sidx_ray *r, float *t, uint32_t *prim)
{
    walk(tr, r, t, prim, NULL, 2, 0);
}
#else
#define WALKS 2
#endif
static const char *const walk_name[3] = {"float", "quantised", "quantised-512"};
/* probe walk `which` (0 float, 1 quantised, 2 quantised with the 512-bit decode) */
static void walk_any(int which, const tree *tr, const sidx_ray *r, float *t, uint32_t *prim)
{
    if (which == 0) walk_float(tr, r, t, prim);
    else if (which == 1) walk_quant(tr, r, t, prim);
#ifdef __AVX512F__
    else walk_quant512(tr, r, t, prim);
#endif
}
static __attribute__((noinline)) void walk_float_count(const tree *tr, const sidx_ray *r, touched *tc)
{
    float t;
    uint32_t p;
    walk(tr, r, &t, &p, tc, 0, 1);
}
static __attribute__((noinline)) void walk_quant_count(const tree *tr, const sidx_ray *r, touched *tc)
{
    float t;
    uint32_t p;
    walk(tr, r, &t, &p, tc, 1, 1);
}

/* ---- measuring ----------------------------------------------------------------- */

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static volatile float sink;

/* One pass of walk `which` (walk_any's, WALKS: the library) over n rays: seconds. */
static double pass(const tree *tr, const sidx_ray *r, size_t n, int which)
{
    float s = 0.0f;
    const double t0 = cpu_now();
    for (size_t i = 0; i < n; ++i) {
        float t;
        uint32_t p;
        if (which < WALKS) walk_any(which, tr, &r[i], &t, &p);
        else {
            sidx_hit h;
            sidx_accel_intersect(tr->a, &r[i], NULL, &h);
            t = h.t;
        }
        s += t;
    }
    const double dt = cpu_now() - t0;
    sink = s;
    return dt;
}

static int cmp_d(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: %s D primary|diffuse time [ROUNDS] | lines | cg\n", argv[0]);
        return 2;
    }
    const uint32_t d = (uint32_t)atoi(argv[1]);
    const int diffuse = !strcmp(argv[2], "diffuse");
    const char *mode = argv[3];
    const int cg = !strcmp(mode, "cg");
    sidx_mesh m;
    sidx_error err;
    /* the scale command's height field: the built-in scene heightfield:D */
    if (sidx_scene_make("heightfield", d, &m, &err) != SIDX_OK) { fprintf(stderr, "%s\n", err.message); return 1; }
    sidx_accel *a = NULL;
    if (sidx_accel_build("bvh8", &m, NULL, &a, &err) != SIDX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    const wide_bvh *w = a->impl;
    if (w->width != 8 || a->opt.box != SIDX_BOX_ROBUST) {
        fprintf(stderr, "expected bvh8 with robust boxes\n");
        return 1;
    }
    qnode *qn = aligned_alloc(64, (size_t)w->num_inner * sizeof *qn);
    if (!qn) return 1;
    for (uint32_t i = 0; i < w->num_inner; ++i)
        if (!quantise_node(wide_node(w, i), &qn[i])) {
            fprintf(stderr, "node %u does not quantise\n", i);
            return 1;
        }
    /* containment, plane by plane: the decoded box against the float one */
    size_t inward = 0, planes = 0;
    for (uint32_t i = 0; i < w->num_inner; ++i) {
        const float *n = wide_node(w, i);
        for (int s = 0; s < 8; ++s) {
            if (!(qn[i].valid >> s & 1)) continue;
            for (int k = 0; k < 3; ++k) {
                planes += 2;
                inward += decode(qn[i].origin[k], qn[i].step[k], qn[i].q[2 * k][s]) > n[k * 8 + s];
                inward += decode(qn[i].origin[k], qn[i].step[k], qn[i].q[2 * k + 1][s]) < n[(3 + k) * 8 + s];
            }
        }
    }
    printf("%zu of %zu decoded planes inside the float box\n", inward, planes);
    const tree tr = {a, w, qn};
    const size_t N = 100000;
    tk_rayrec *all = malloc(N * sizeof *all);
    sidx_ray *r = malloc(N * sizeof *r);
    if (!all || !r) return 1;
    tk_make_rays(&m, diffuse ? TK_RAYS_DIFFUSE : TK_RAYS_PRIMARY, N, 7, all);
    for (size_t i = 0; i < N; ++i)
        sidx_ray_init(&r[i], sidx_v3(all[i].o[0], all[i].o[1], all[i].o[2]), sidx_v3(all[i].d[0], all[i].d[1], all[i].d[2]),
                      all[i].tmin, all[i].tmax);
    const size_t n_cg = 2000;
    if (cg) {
        /* per walk: 20000 other rays of the set warm the caches (every 5th,
         * offset 2: never a counted one), then n_cg rays are counted and
         * dumped as their own part */
        float s = 0.0f, t;
        uint32_t p;
        for (int quant = 0; quant < 2; ++quant) {
            CALLGRIND_START_INSTRUMENTATION;
            for (size_t i = 0; i < 20000; ++i) {
                if (quant) walk_quant(&tr, &r[5 * i + 2], &t, &p);
                else walk_float(&tr, &r[5 * i + 2], &t, &p);
                s += t;
            }
            CALLGRIND_ZERO_STATS;
            for (size_t i = 0; i < n_cg; ++i) {
                if (quant) walk_quant(&tr, &r[i * (N / n_cg)], &t, &p);
                else walk_float(&tr, &r[i * (N / n_cg)], &t, &p);
                s += t;
            }
            CALLGRIND_DUMP_STATS_AT(quant ? "quantised" : "float");
            CALLGRIND_STOP_INSTRUMENTATION;
        }
        printf("%u %s: %g\n", d, argv[2], (double)s);
        return 0;
    }
    /* the hit check: every ray, both probe walks against the library */
    size_t bad = 0;
    for (size_t i = 0; i < N; ++i) {
        sidx_hit h;
        sidx_accel_intersect(a, &r[i], NULL, &h);
        for (int which = 0; which < WALKS; ++which) {
            float t;
            uint32_t p;
            walk_any(which, &tr, &r[i], &t, &p);
            uint32_t tb, hb;
            memcpy(&tb, &t, 4);
            memcpy(&hb, &h.t, 4);
            if (tb != hb || p != h.prim) {
                if (bad < 10)
                    printf("MISMATCH ray %zu %s walk: t %a prim %u, library t %a prim %u\n", i, walk_name[which],
                           (double)t, p, (double)h.t, h.prim);
                ++bad;
            }
        }
    }
    printf("D %u (%u tris), %s: %u nodes, float %.1f MB, quantised %.1f MB; hit check over %zu rays: %zu mismatches\n", d,
           m.num_triangles, argv[2], w->num_inner, w->num_inner * 256.0 / 1048576, w->num_inner * 128.0 / 1048576, N, bad);
    if (bad || inward) return 1;
    if (!strcmp(mode, "lines")) {
        static touched tc;
        for (int quant = 0; quant < 2; ++quant) {
            double ln = 0, pg = 0, pg2 = 0;
            tc.nodes = tc.blocks = 0;
            for (size_t i = 0; i < n_cg; ++i) {
                tc.nl = tc.np = tc.np2 = 0;
                if (quant) walk_quant_count(&tr, &r[i * (N / n_cg)], &tc);
                else walk_float_count(&tr, &r[i * (N / n_cg)], &tc);
                ln += tc.nl, pg += tc.np, pg2 += tc.np2;
            }
            printf("%s: per ray %.1f lines, %.2f 4K pages, %.2f 2M pages; %.2f nodes and %.2f blocks visited\n",
                   quant ? "quantised" : "float", ln / n_cg, pg / n_cg, pg2 / n_cg, (double)tc.nodes / n_cg,
                   (double)tc.blocks / n_cg);
        }
        return 0;
    }
    /* time: rounds; in each a warm-up pass of every walk, then 5 passes
     * of float, quantised, library in turn (interleaved pass by pass, so
     * a change in the machine's load falls on all three alike) */
    const int rounds = argc > 4 ? atoi(argv[4]) : 3;
    if (rounds < 1 || rounds > 64) return 2;
    double ratio_best[2][64], ratio_med[2][64];
    for (int rd = 0; rd < rounds; ++rd) {
        double p[WALKS + 1][5], best[WALKS + 1], med[WALKS + 1];
        for (int which = 0; which <= WALKS; ++which) (void)pass(&tr, r, N, which);
        for (int k = 0; k < 5; ++k)
            for (int which = 0; which <= WALKS; ++which) p[which][k] = pass(&tr, r, N, which);
        for (int which = 0; which <= WALKS; ++which) {
            qsort(p[which], 5, sizeof(double), cmp_d);
            best[which] = p[which][0], med[which] = p[which][2];
        }
        printf("round %d: Mrays/s best", rd + 1);
        for (int which = 0; which <= WALKS; ++which)
            printf(" %s %.2f", which < WALKS ? walk_name[which] : "library", N / best[which] * 1e-6);
        for (int which = 1; which < WALKS; ++which) {
            ratio_best[which - 1][rd] = best[which] / best[0], ratio_med[which - 1][rd] = med[which] / med[0];
            printf("; %s/float time best %.3f median %.3f", walk_name[which], ratio_best[which - 1][rd],
                   ratio_med[which - 1][rd]);
        }
        printf("; float/library %.3f\n", best[0] / best[WALKS]);
        fflush(stdout);
    }
    for (int which = 1; which < WALKS; ++which) {
        double *rb = ratio_best[which - 1], *rm = ratio_med[which - 1];
        qsort(rb, (size_t)rounds, sizeof(double), cmp_d);
        qsort(rm, (size_t)rounds, sizeof(double), cmp_d);
        printf("%s/float over %d rounds, median [min..max]: best passes %.3f [%.3f..%.3f], median passes %.3f "
               "[%.3f..%.3f]\n",
               walk_name[which], rounds, rb[rounds / 2], rb[0], rb[rounds - 1], rm[rounds / 2], rm[0], rm[rounds - 1]);
    }
    return 0;
}
