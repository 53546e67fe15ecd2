/* inflight.c — bvh8 walked K rays at a time ("rays in flight"): K walks,
 * each with its own stack, bound and best hit, advanced round-robin one
 * step at a time, against the single walk ray after ray, on the height
 * field of `sidx-bench scale --scene heightfield` and on the bunny
 * (docs/performance.md, "Wide BVHs", "Several rays in flight").  Not part
 * of the build; compile and run it by hand:
 *
 *   cc -std=gnu11 -O2 -ffp-contract=off -mavx2 -mfma -mpopcnt -Ilib/include -Ilib -Itests \
 *      tests/bench/probe/inflight.c tests/common/testkit.c build/lib/libsidx.a -lm -pthread -o inflight
 *   (add -mavx512f -mavx512vl for the AVX-512 build: 32 vector registers,
 *   as the library's AVX-512 copy; valgrind runs only the AVX2 build)
 *   ./inflight D|FILE primary|diffuse time [ROUNDS]   hit check, then per
 *       round (7 by default) a warm-up pass of each walk and 5 passes of
 *       single, K = 2, 4, 8, 16, library in turn (thread CPU time of the 100000
 *       rays): ratios K / single of the best passes, per round and
 *       median [min..max] over the rounds
 *   ./inflight D|FILE primary|diffuse check           the hit check alone
 *   valgrind --tool=callgrind --instr-atstart=no ./inflight D|FILE primary|diffuse cg
 *       the single walk, then K = 2, 4, 8, 16, each dumped as a part of its own
 *       (callgrind.out.PID.1 .. .5; callgrind_annotate gives the totals):
 *       20000 other rays of the set warm the caches, then 2000 rays (every
 *       50th) are counted, as quantised.c does
 *
 * D is the detail of the built-in scene heightfield (724: 1M, 1448: 4.2M,
 * 2896: 16.8M triangles); anything not a number is a mesh file
 * (sidx_mesh_load), e.g. /work/shared/scenes/bunny.obj.  The rays are the
 * scale command's 100000 (tk_make_rays, seed 7).  Modes time and check
 * first compare every ray's (t bits, prim) from each probe walk with
 * sidx_accel_intersect's, print the first mismatches and exit 1 on any.
 * -DPROBE_BREAK=1 or 2 breaks the interleaved walk on purpose (the check
 * must then fail): 1 drops the push of the farther child where a node has
 * two hit children, 2 stores each ray's answer in its neighbour's place
 * (rays 2i and 2i+1 swapped).  -DPROBE_PREFETCH=0: no walk prefetches.
 * -ffp-contract=off: the triangle kernel's multiplies and subtractions
 * must not be fused, as in the library.
 *
 * The single walk is quantised.c's float walk: bvh_wide_walk.h's untraced
 * closest-hit walk step by step over the library's own nodes and blocks.
 * The interleaved walk cuts the same walk into steps — a step is one node
 * (box test, the hit children pushed in the same order, the next node
 * picked) or one leaf (its blocks through the same kernel), then the pops
 * down to the next node — and keeps each ray's whole state (constants,
 * stack, bound, best hit) in a slot of its own.  After a step it prefetches
 * the node or block the ray reads next (hit children are prefetched as in
 * the library; a node taken from the stack is prefetched here too) and
 * turns to the next slot; a slot whose ray has finished takes the next ray
 * of the buffer.  A ray's steps run in the same order on the same values
 * whatever runs between them, so every ray's answer is the single walk's,
 * bit for bit; only the order in which memory is asked for changes: while
 * one ray waits for its node, K − 1 others work (software pipelining of
 * independent pointer chases, as interleaved hash-table probing:
 * Psaropoulos et al., "Interleaving with coroutines", VLDB 2017). */
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
#define PROBE_PREFETCH 1 /* 0: no walk prefetches */
#endif

#define WINL static inline __attribute__((always_inline))

/* ---- the walk's pieces (quantised.c's float walk) ------------------------------ */

typedef struct consts {
    __m256 org_x, org_y, org_z, inv_x, inv_y, inv_z, far_x, far_y, far_z, tmin;
    tri4_ray tri;
    uint32_t near_off[3], far_off[3]; /* the planes of axis k: floats from b */
} consts_t;

/* simd_wide_avx2.h's boxes_ */
WINL unsigned boxes(const float *node, const consts_t *c, float best, float *t_near)
{
    const __m256 lo_x = _mm256_load_ps(node + c->near_off[0]), hi_x = _mm256_load_ps(node + c->far_off[0]);
    const __m256 lo_y = _mm256_load_ps(node + c->near_off[1]), hi_y = _mm256_load_ps(node + c->far_off[1]);
    const __m256 lo_z = _mm256_load_ps(node + c->near_off[2]), hi_z = _mm256_load_ps(node + c->far_off[2]);
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
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ));
}

WINL uint32_t rank(const float *t_near, unsigned slot, unsigned hit_mask)
{
    const __m256 entries = _mm256_load_ps(t_near), own = _mm256_set1_ps(t_near[slot]);
    const unsigned nearer = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_LT_OQ));
    const unsigned as_near = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_EQ_OQ));
    return (uint32_t)__builtin_popcount(hit_mask & (nearer | (as_near & ((1u << slot) - 1u))));
}

typedef struct tree {
    const sidx_accel *a;
    const wide_bvh *w;
    float scale; /* Ize's far-plane factor of robust boxes */
} tree;

/* Start fetching a node's 4 lines or a leaf block's first 3, as the
 * library's prefetch_. */
WINL void prefetch(const tree *tr, uint32_t ref)
{
    if (!PROBE_PREFETCH) return;
    const uintptr_t leaf = (uintptr_t)tr->w->blocks + (uintptr_t)(ref & ~WIDE_LEAF_BIT) * sizeof(wide_tri4);
    const uintptr_t node = (uintptr_t)tr->w->nodes + (uintptr_t)ref * 256u;
    const char *line = (const char *)((ref & WIDE_LEAF_BIT) ? leaf : node);
    __builtin_prefetch(line);
    __builtin_prefetch(line + 64);
    __builtin_prefetch(line + 128);
    __builtin_prefetch(line + 192);
}

WINL void consts_init(consts_t *c, const sidx_ray *r, float scale)
{
    const float *o = sidx_v3_array(&r->org), *inv = sidx_v3_array(&r->inv_dir);
    for (int k = 0; k < 3; ++k) {
        c->near_off[k] = (uint32_t)((r->sign[k] ? 3 + k : k) * 8);
        c->far_off[k] = (uint32_t)((r->sign[k] ? k : 3 + k) * 8);
    }
    c->org_x = _mm256_set1_ps(o[0]), c->org_y = _mm256_set1_ps(o[1]), c->org_z = _mm256_set1_ps(o[2]);
    c->inv_x = _mm256_set1_ps(inv[0]), c->inv_y = _mm256_set1_ps(inv[1]), c->inv_z = _mm256_set1_ps(inv[2]);
    c->far_x = _mm256_set1_ps(inv[0] * scale), c->far_y = _mm256_set1_ps(inv[1] * scale);
    c->far_z = _mm256_set1_ps(inv[2] * scale);
    c->tmin = _mm256_set1_ps(r->tmin);
}

/* bvh_wide_walk.h's leaf_: the blocks of leaf ref, closest hit into *best, *prim. */
WINL void leaf(const tree *tr, const sidx_ray *r, const consts_t *c, uint32_t ref, float *best, uint32_t *prim)
{
    const wide_tri4 *block = tr->w->blocks + (ref & ~WIDE_LEAF_BIT);
    const float *row_x = &block->v[0][0][0] + c->tri.kx4, *row_y = &block->v[0][0][0] + c->tri.ky4,
                *row_z = &block->v[0][0][0] + c->tri.kz4;
    for (;; ++block) {
        float t;
        unsigned lane;
        const int hit = tri4_test_axes(row_x, row_y, row_z, &c->tri, *best, &t, &lane, NULL);
        if (hit > 0) {
            *prim = block->prim[lane] & WIDE_PRIM_MASK;
            *best = t;
        } else if (hit < 0) {
            for (unsigned l = 0; l < 4; ++l) {
                const uint32_t id = block->prim[l] & WIDE_PRIM_MASK;
                if (id == WIDE_PAD_PRIM) continue;
                if (tri4_lane_test(tr->a, r, block, l, *best, &t, NULL, NULL)) *prim = id, *best = t;
            }
        }
        if (block->prim[0] & WIDE_LAST_BLOCK) break;
        row_x += sizeof(wide_tri4) / sizeof(float);
        row_y += sizeof(wide_tri4) / sizeof(float);
        row_z += sizeof(wide_tri4) / sizeof(float);
    }
}

/* ---- walk 1: the single walk, ray after ray ------------------------------------- */

/* quantised.c's float walk (bvh_wide_walk.h's walk_ with
 * WIDE_WALK_SIMD_TRI, untraced, closest hit).  Returns the hit as
 * sidx_accel_intersect would: t (INFINITY on a miss) and prim. */
static __attribute__((noinline)) void walk1(const tree *tr, const sidx_ray *r, float *t_out, uint32_t *prim_out)
{
    const wide_bvh *w = tr->w;
    const float scale = tr->scale;
    float best = r->tmax;
    uint32_t prim = SIDX_NO_HIT;
    consts_t c;
    consts_init(&c, r, scale);
    int tri_ready = 0;
    float best_s = best * scale;
    uint32_t stack[WIDE_STACK];
    float stack_t_near[WIDE_STACK];
    _Alignas(32) float t_near[8];
    uint32_t stack_len = 0, cur = 0;
    for (;;) {
        if (!(cur & WIDE_LEAF_BIT)) {
            const float *node = w->nodes + (size_t)cur * 64u;
            const uint32_t *child = wide_child(node, 8);
            unsigned hits = boxes(node, &c, best_s, t_near);
            if (hits) {
                const unsigned slot0 = (unsigned)__builtin_ctz(hits);
                hits &= hits - 1;
                if (!hits) {
                    cur = child[slot0];
                    prefetch(tr, cur);
                    continue;
                }
                if (!(hits & (hits - 1))) {
                    const unsigned slot1 = (unsigned)__builtin_ctz(hits);
                    const float enter0 = t_near[slot0], enter1 = t_near[slot1];
                    prefetch(tr, child[slot0]);
                    prefetch(tr, child[slot1]);
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
                    prefetch(tr, child[slot]);
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
            leaf(tr, r, &c, cur, &best, &prim);
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

/* ---- walk 2: K rays in flight ---------------------------------------------------- */

/* One ray's walk between two steps: all walk1 keeps in registers and on
 * its stack. */
typedef struct slot {
    consts_t c;
    const sidx_ray *r;
    size_t idx; /* the ray's place in the buffer (where its answer goes) */
    float best, best_s;
    uint32_t prim, cur, stack_len;
    int tri_ready;
    uint32_t stack[WIDE_STACK];
    float stack_t_near[WIDE_STACK];
} slot;

WINL void slot_start(const tree *tr, slot *s, const sidx_ray *r, size_t idx)
{
    s->r = r, s->idx = idx;
    consts_init(&s->c, r, tr->scale);
    s->best = r->tmax, s->best_s = r->tmax * tr->scale;
    s->prim = SIDX_NO_HIT, s->cur = 0, s->stack_len = 0, s->tri_ready = 0;
    prefetch(tr, 0);
}

/* One step of walk1 for the ray in s: one node (or one leaf and the pops
 * after it); the next node or block is prefetched.  1 when the ray has
 * finished (stack empty; the answer in s->best, s->prim). */
WINL int step(const tree *tr, slot *s)
{
    uint32_t cur = s->cur, stack_len = s->stack_len;
    if (!(cur & WIDE_LEAF_BIT)) {
        _Alignas(32) float t_near[8];
        const float *node = tr->w->nodes + (size_t)cur * 64u;
        const uint32_t *child = wide_child(node, 8);
        unsigned hits = boxes(node, &s->c, s->best_s, t_near);
        if (hits) {
            const unsigned slot0 = (unsigned)__builtin_ctz(hits);
            hits &= hits - 1;
            if (!hits) {
                s->cur = child[slot0];
                prefetch(tr, s->cur);
                return 0;
            }
            if (!(hits & (hits - 1))) {
                const unsigned slot1 = (unsigned)__builtin_ctz(hits);
                const float enter0 = t_near[slot0], enter1 = t_near[slot1];
                prefetch(tr, child[slot0]);
                prefetch(tr, child[slot1]);
                const int first0 = enter0 <= enter1;
                s->stack[stack_len] = first0 ? child[slot1] : child[slot0];
                s->stack_t_near[stack_len] = first0 ? enter1 : enter0;
#if PROBE_BREAK != 1 /* 1, deliberately wrong: the farther child is never visited */
                ++stack_len;
#endif
                s->stack_len = stack_len;
                s->cur = first0 ? child[slot0] : child[slot1];
                return 0;
            }
            const unsigned hit_mask = hits | (1u << slot0);
            const uint32_t top = stack_len + (uint32_t)__builtin_popcount(hit_mask) - 1u;
            unsigned pending = hit_mask;
            do {
                const unsigned slot = (unsigned)__builtin_ctz(pending);
                pending &= pending - 1;
                const uint32_t at = top - rank(t_near, slot, hit_mask);
                s->stack[at] = child[slot];
                s->stack_t_near[at] = t_near[slot];
                prefetch(tr, child[slot]);
            } while (pending);
            s->stack_len = top;
            s->cur = s->stack[top];
            return 0;
        }
    } else {
        if (!s->tri_ready) {
            tri4_ray_init(&s->c.tri, s->r);
            s->tri_ready = 1;
        }
        leaf(tr, s->r, &s->c, cur, &s->best, &s->prim);
        s->best_s = s->best * tr->scale;
    }
    const float best_s = s->best_s;
    for (;;) {
        if (stack_len == 0) return 1;
        --stack_len;
        if (s->stack_t_near[stack_len] < best_s) {
            cur = s->stack[stack_len];
            break;
        }
    }
    s->cur = cur, s->stack_len = stack_len;
    prefetch(tr, cur); /* it was prefetched when pushed, maybe long ago */
    return 0;
}

/* The n rays of r, K at a time, round-robin one step each; answers to
 * t_out, prim_out at the rays' places. */
WINL void walk_k(const tree *tr, const sidx_ray *r, size_t n, float *t_out, uint32_t *prim_out, const unsigned K)
{
    static _Alignas(64) slot s[16];
    size_t next = 0;
    unsigned live = 0;
    for (unsigned k = 0; k < K && next < n; ++k, ++next) {
        slot_start(tr, &s[k], &r[next], next);
        live |= 1u << k;
    }
    unsigned k = 0;
    while (live) {
        if (live >> k & 1) {
            slot *sk = &s[k];
            if (step(tr, sk)) {
#if PROBE_BREAK == 2 /* deliberately wrong: rays 2i and 2i+1 swap answers */
                const size_t at = (sk->idx ^ 1u) < n ? sk->idx ^ 1u : sk->idx;
#else
                const size_t at = sk->idx;
#endif
                t_out[at] = sk->prim == SIDX_NO_HIT ? INFINITY : sk->best;
                prim_out[at] = sk->prim;
                if (next < n) slot_start(tr, sk, &r[next], next), ++next;
                else live &= ~(1u << k);
            }
        }
        k = k + 1 == K ? 0 : k + 1;
    }
}

static __attribute__((noinline)) void walk_k2(const tree *tr, const sidx_ray *r, size_t n, float *t, uint32_t *p)
{
    walk_k(tr, r, n, t, p, 2);
}
static __attribute__((noinline)) void walk_k4(const tree *tr, const sidx_ray *r, size_t n, float *t, uint32_t *p)
{
    walk_k(tr, r, n, t, p, 4);
}
static __attribute__((noinline)) void walk_k8(const tree *tr, const sidx_ray *r, size_t n, float *t, uint32_t *p)
{
    walk_k(tr, r, n, t, p, 8);
}
static __attribute__((noinline)) void walk_k16(const tree *tr, const sidx_ray *r, size_t n, float *t, uint32_t *p)
{
    walk_k(tr, r, n, t, p, 16);
}

#define WALKS 5 /* single, K = 2, 4, 8, 16; WALKS: the library */
static const char *const walk_name[WALKS + 1] = {"single", "K=2", "K=4", "K=8", "K=16", "library"};

/* Walk `which` over the n rays of r, answers to t, p. */
static void run(int which, const tree *tr, const sidx_ray *r, size_t n, float *t, uint32_t *p)
{
    switch (which) {
    case 0:
        for (size_t i = 0; i < n; ++i) walk1(tr, &r[i], &t[i], &p[i]);
        break;
    case 1: walk_k2(tr, r, n, t, p); break;
    case 2: walk_k4(tr, r, n, t, p); break;
    case 3: walk_k8(tr, r, n, t, p); break;
    case 4: walk_k16(tr, r, n, t, p); break;
    default:
        for (size_t i = 0; i < n; ++i) {
            sidx_hit h;
            sidx_accel_intersect(tr->a, &r[i], NULL, &h);
            t[i] = h.t, p[i] = h.prim;
        }
    }
}

/* ---- measuring ----------------------------------------------------------------- */

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_d(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: %s D|FILE primary|diffuse time [ROUNDS] | check | cg\n", argv[0]);
        return 2;
    }
    char *end;
    const unsigned long d = strtoul(argv[1], &end, 10);
    const int diffuse = !strcmp(argv[2], "diffuse");
    const char *mode = argv[3];
    sidx_mesh m;
    sidx_error err;
    /* the scale command's height field (the built-in scene heightfield:D), or a mesh file */
    const sidx_status st = *end == '\0' && d > 0 ? sidx_scene_make("heightfield", (uint32_t)d, &m, &err)
                                                 : sidx_mesh_load(argv[1], &m, &err);
    if (st != SIDX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    sidx_accel *a = NULL;
    if (sidx_accel_build("bvh8", &m, NULL, &a, &err) != SIDX_OK) {
        fprintf(stderr, "%s\n", err.message);
        return 1;
    }
    const wide_bvh *w = a->impl;
    if (w->width != 8 || a->opt.box != SIDX_BOX_ROBUST || a->opt.tri != SIDX_TRI_WATERTIGHT) {
        fprintf(stderr, "expected bvh8 with robust boxes and the watertight test\n");
        return 1;
    }
    const tree tr = {a, w, SIDX_ROBUST_TFAR_SCALE};
    const size_t N = 100000;
    tk_rayrec *all = malloc(N * sizeof *all);
    sidx_ray *r = malloc(N * sizeof *r);
    float *t = malloc(N * sizeof *t), *t_lib = malloc(N * sizeof *t_lib);
    uint32_t *p = malloc(N * sizeof *p), *p_lib = malloc(N * sizeof *p_lib);
    if (!all || !r || !t || !t_lib || !p || !p_lib) return 1;
    tk_make_rays(&m, diffuse ? TK_RAYS_DIFFUSE : TK_RAYS_PRIMARY, N, 7, all);
    for (size_t i = 0; i < N; ++i)
        sidx_ray_init(&r[i], sidx_v3(all[i].o[0], all[i].o[1], all[i].o[2]), sidx_v3(all[i].d[0], all[i].d[1], all[i].d[2]),
                      all[i].tmin, all[i].tmax);
    if (!strcmp(mode, "cg")) {
        /* per walk: 20000 other rays of the set warm the caches (every 5th,
         * offset 2: never a counted one), then 2000 rays (every 50th) are
         * counted and dumped as their own part */
        const size_t n_warm = 20000, n_cg = 2000;
        sidx_ray *warm = malloc(n_warm * sizeof *warm), *counted = malloc(n_cg * sizeof *counted);
        if (!warm || !counted) return 1;
        for (size_t i = 0; i < n_warm; ++i) warm[i] = r[5 * i + 2];
        for (size_t i = 0; i < n_cg; ++i) counted[i] = r[i * (N / n_cg)];
        float s = 0.0f;
        for (int which = 0; which < WALKS; ++which) {
            CALLGRIND_START_INSTRUMENTATION;
            run(which, &tr, warm, n_warm, t, p);
            CALLGRIND_ZERO_STATS;
            run(which, &tr, counted, n_cg, t, p);
            CALLGRIND_DUMP_STATS_AT(walk_name[which]);
            CALLGRIND_STOP_INSTRUMENTATION;
            for (size_t i = 0; i < n_cg; ++i) s += t[i];
        }
        printf("%s %s: %g\n", argv[1], argv[2], (double)s);
        return 0;
    }
    /* the hit check: every ray, every probe walk against the library */
    run(WALKS, &tr, r, N, t_lib, p_lib);
    size_t bad = 0;
    for (int which = 0; which < WALKS; ++which) {
        memset(t, 0, N * sizeof *t);
        memset(p, 0, N * sizeof *p);
        run(which, &tr, r, N, t, p);
        for (size_t i = 0; i < N; ++i) {
            uint32_t tb, hb;
            memcpy(&tb, &t[i], 4);
            memcpy(&hb, &t_lib[i], 4);
            if (tb != hb || p[i] != p_lib[i]) {
                if (bad < 10)
                    printf("MISMATCH ray %zu %s walk: t %a prim %u, library t %a prim %u\n", i, walk_name[which],
                           (double)t[i], p[i], (double)t_lib[i], p_lib[i]);
                ++bad;
            }
        }
    }
    printf("%s (%u tris), %s: %u nodes, %.1f MB of nodes; hit check over %zu rays, %d walks: %zu mismatches\n", argv[1],
           m.num_triangles, argv[2], w->num_inner, w->num_inner * 256.0 / 1048576, N, WALKS, bad);
    if (bad) return 1;
    if (strcmp(mode, "time")) return 0;
    /* time: rounds; in each a warm-up pass of every walk, then 5 passes
     * of each in turn (interleaved pass by pass, so a change in the
     * machine's load falls on all alike) */
    const int rounds = argc > 4 ? atoi(argv[4]) : 7;
    if (rounds < 1 || rounds > 64) return 2;
    static double ratio[WALKS + 1][64], rate[WALKS + 1][64];
    for (int rd = 0; rd < rounds; ++rd) {
        double ps[WALKS + 1][5], best[WALKS + 1];
        for (int which = 0; which <= WALKS; ++which) run(which, &tr, r, N, t, p);
        for (int k = 0; k < 5; ++k)
            for (int which = 0; which <= WALKS; ++which) {
                const double t0 = cpu_now();
                run(which, &tr, r, N, t, p);
                ps[which][k] = cpu_now() - t0;
            }
        printf("round %d: Mrays/s best", rd + 1);
        for (int which = 0; which <= WALKS; ++which) {
            qsort(ps[which], 5, sizeof(double), cmp_d);
            best[which] = ps[which][0];
            rate[which][rd] = N / best[which] * 1e-6;
            printf(" %s %.2f", walk_name[which], rate[which][rd]);
        }
        printf("; time / single");
        for (int which = 1; which <= WALKS; ++which) {
            ratio[which][rd] = best[which] / best[0];
            printf(" %s %.3f", walk_name[which], ratio[which][rd]);
        }
        printf("\n");
        fflush(stdout);
    }
    for (int which = 0; which <= WALKS; ++which) {
        qsort(rate[which], (size_t)rounds, sizeof(double), cmp_d);
        printf("%-8s Mrays/s median %.2f", walk_name[which], rate[which][rounds / 2]);
        if (which) {
            double *q = ratio[which];
            qsort(q, (size_t)rounds, sizeof(double), cmp_d);
            printf("; time / single over %d rounds, median [min..max]: %.3f [%.3f..%.3f]", rounds, q[rounds / 2], q[0],
                   q[rounds - 1]);
        }
        printf("\n");
    }
    return 0;
}
