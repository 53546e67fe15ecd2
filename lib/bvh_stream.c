/* bvh_stream.c — the stream entry of the BVH family: sidx_accel_intersect_n
 * and sidx_accel_occluded_n on a bvh-family tree (AABBs, built at once),
 * bvh4 or bvh8, untraced.
 *
 * A single query pays, per ray, for what does not depend on the ray: the
 * entry checks, the choice of walk (structure, query kind, triangle test,
 * instruction set) and two calls through function pointers.  A buffer
 * pays for them once: the walk is picked here, and one call of the
 * structure's stream walk (bvh_traverse.c, bvh_wide_walk.h) runs every
 * ray through the single-ray walk — the same code, so the same hits, bit
 * for bit — and sets up and finishes each hit beside it.
 *
 * Where the tree is out of cache, the closest-hit walks with the SIMD
 * watertight test keep 8 rays in flight instead (bvh_wide_walk.h, the
 * flight_ walks; the same hits, bit for bit): the build decides by tree
 * size (bvh_wide.c, want_inflight), this picks what it decided.
 *
 * What does not pay, measured (docs/performance.md, "The stream entry"):
 * the walk inlined into the loop over rays (its registers allocated
 * worse), and the rays' set-up (plane offsets from the signs, far
 * factors) done 8 rays at a time in SIMD ahead of the walks: the walk is
 * bound by the latency of its node loads, the set-up it does itself runs
 * in their shadow, and a separate pass only adds its instructions.
 *
 * Reordering (SIDX_QUERY_REORDER): rays walked sorted by direction octant,
 * then by a Morton code of the origin (the ray sorting of Garanzha and
 * Loop 2010, "Fast ray sorting and breadth-first packet traversal for GPU
 * ray tracing"), so that neighbours in the walk order start near each
 * other and go the same way and share nodes in cache; answers still go to
 * their input place.  The keys are computed 8 rays at a time
 * (simd_stream_avx2.h; simd_stream_scalar.h the reference).  The sort and
 * the scattered reads and writes it causes cost more than the cache gains
 * on the scenes measured, so it is off unless asked.
 *
 * A traced query, a lazy tree, bvh-obb and the naive / ordered walks go
 * ray by ray through sidx_accel_intersect / _occluded (accel.c): the
 * events then are exactly a single query's, ray after ray. */
#include "bvh_wide_internal.h"
#include "simd_stream_scalar.h"
#ifdef SIDX_WIDE_X86
#include "simd_stream_avx2.h"
#endif

/* Below this many rays a sort has nothing to gather. */
#define STREAM_REORDER_MIN 64u

#ifdef SIDX_WIDE_X86
/* 1 when the CPU has AVX2 for the sort keys. */
static int cpu_avx2(void)
{
    return __builtin_cpu_supports("avx2"); /* the CPU model is read at start-up */
}
#endif

/* What a call walks with. */
typedef struct stream_plan {
    bvh_stream_fn walk;
    /* sort keys 8 rays at a time with AVX2 where the CPU has it; 0 for a
     * wide tree built with its scalar kernels (SIDX_SIMD=scalar, how the
     * tests reach the portable copies): the scalar keys then too */
    int avx2;
} stream_plan;

static const wide_stream_kernels *wide_stream_for(const wide_bvh *w)
{
#ifdef SIDX_WIDE_X86
    if (w->isa == WIDE_ISA_AVX512) return &sidx__wide_stream_8_avx512;
    if (w->isa == WIDE_ISA_AVX2) return &sidx__wide_stream_8_avx2;
    if (w->isa == WIDE_ISA_SSE41) return &sidx__wide_stream_4_sse41;
#elif defined(SIDX_WIDE_WASM)
    if (w->isa == WIDE_ISA_SSE41) return &sidx__wide_stream_4_sse41;
#endif
    return w->width == 8 ? &sidx__wide_stream_8_scalar : &sidx__wide_stream_4_scalar;
}

/* 1 and *p set when the stream walk answers this query on `a`; 0 when it
 * goes ray by ray. */
static int plan_for(const sidx_accel *a, const sidx_query *q, int anyhit, stream_plan *p)
{
    if (a->lazy || SIDX_QUERY_TRACED(q)) return 0;
    p->avx2 = 1;
    if (a->vt == &sidx__bvh_vtable) {
        const bvh *b = a->impl;
        if (b->obbs || b->lazy || q->traversal == SIDX_TRAVERSE_NAIVE || q->traversal == SIDX_TRAVERSE_ORDERED)
            return 0;
        p->walk = anyhit ? sidx__bvh_stream_occl
                  : (q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)) ? sidx__bvh_stream_isect_attrs
                                                                      : sidx__bvh_stream_isect;
        return 1;
    }
    if (sidx__is_wide(a)) {
        const wide_bvh *w = a->impl;
        if (w->lazy) return 0;
        const wide_stream_kernels *k = wide_stream_for(w);
        if (w->isa == WIDE_ISA_SCALAR) p->avx2 = 0;
        /* the choice wide_intersect's walk table makes (bvh_wide.c, set_kernels) */
        const int simd_tri = a->opt.tri == SIDX_TRI_WATERTIGHT;
        if (anyhit) p->walk = simd_tri ? k->occl_simd : k->occl_other;
        else if (!simd_tri) p->walk = k->isect_other;
        else if (w->inflight) p->walk = (q->flags & SIDX_QUERY_UV) ? k->flight_simd_uv : k->flight_simd;
        else p->walk = (q->flags & SIDX_QUERY_UV) ? k->isect_simd_uv : k->isect_simd;
        return 1;
    }
    return 0;
}

/* ---- reordering --------------------------------------------------------------- */

/* The walk order of rays[0, n): sorted by key (octant, then Morton code
 * of the origin over the buffer's box of finite origins), a stable LSD
 * radix sort, 8 bits a pass, a pass skipped where every key has the same
 * digit.  NULL without the memory for it: then the input order (the hits
 * do not depend on the order). */
static uint32_t *reorder(const sidx_accel *a, const sidx_ray *rays, size_t n, int avx2)
{
    const sidx_allocator *al = &a->alloc;
    if (n > SIZE_MAX / (4u * sizeof(uint32_t))) return NULL;
    uint32_t *mem = al->alloc(4u * n * sizeof *mem, al->user);
    if (!mem) return NULL;
    uint32_t *key = mem, *key2 = mem + n, *ord = mem + 2 * n, *ord2 = mem + 3 * n;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; ++i) {
        const float *o = sidx_v3_array(&rays[i].org);
        for (int k = 0; k < 3; ++k)
            if (fabsf(o[k]) <= FLT_MAX) { /* finite */
                lo[k] = o[k] < lo[k] ? o[k] : lo[k];
                hi[k] = o[k] > hi[k] ? o[k] : hi[k];
            }
    }
    float scale[3];
    for (int k = 0; k < 3; ++k) {
        const float ext = hi[k] - lo[k];
        scale[k] = ext > 0.0f && ext <= FLT_MAX ? 511.0f / ext : 0.0f;
        if (!(lo[k] <= hi[k])) lo[k] = 0.0f; /* no finite origin on this axis */
    }
#ifdef SIDX_WIDE_X86
    if (avx2 && cpu_avx2()) stream_keys_avx2(rays, n, lo, scale, key);
    else
#else
    (void)avx2; /* no AVX2 kernel on this target */
#endif
        stream_keys_scalar(rays, n, lo, scale, key);
    for (size_t i = 0; i < n; ++i) ord[i] = (uint32_t)i;
    for (unsigned shift = 0; shift < 32; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; ++i) ++count[((key[i] >> shift) & 0xFFu) + 1];
        if (count[((key[0] >> shift) & 0xFFu) + 1] == n) continue; /* one digit: the pass changes nothing */
        for (int d = 0; d < 256; ++d) count[d + 1] += count[d];
        for (size_t i = 0; i < n; ++i) {
            const size_t at = count[(key[i] >> shift) & 0xFFu]++;
            key2[at] = key[i];
            ord2[at] = ord[i];
        }
        uint32_t *t = key; key = key2; key2 = t;
        t = ord; ord = ord2; ord2 = t;
    }
    /* the order at the front of the block, so that one free releases it */
    memmove(mem, ord, n * sizeof *mem);
    return mem;
}

/* ---- the entry ------------------------------------------------------------------ */

int sidx__bvh_stream(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q, sidx_hit *hits,
                     int *occluded)
{
    stream_plan plan;
    if (n > UINT32_MAX || !plan_for(a, q, hits == NULL, &plan)) return 0;
    uint32_t *order = (q->flags & SIDX_QUERY_REORDER) && n >= STREAM_REORDER_MIN ? reorder(a, rays, n, plan.avx2) : NULL;
    const bvh_stream_rays c = {rays, order, (uint32_t)n, hits, occluded};
    plan.walk(a, q, &c);
    if (order) a->alloc.free(order, a->alloc.user);
    return 1;
}
