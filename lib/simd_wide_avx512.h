/* simd_wide_avx512.h — the wide walk's kernels with AVX-512F/VL: the AVX2
 * kernels (simd_wide_avx2.h) on the same 8-lane ymm registers, so the same
 * operations in the same order and the same bits, but with 32 vector
 * registers instead of 16: the 8-wide walk holds 10 box constants and 6
 * triangle constants across its loop, which on AVX2 spill at every leaf.
 * One change: the near and far plane of each axis are picked by a blend
 * under the ray's sign mask (one per axis, in mask registers) instead of
 * by six offsets into the node — the offsets took general registers the
 * walk needs elsewhere, so GCC reloaded five of them from the stack at
 * every node.  The same planes, so the same bits (docs/performance.md,
 * "Wide BVHs").
 *
 * Not a normal header: bvh_wide_walk.h includes it for WALK_ISA 3 (W = 8),
 * compiled with __attribute__((target("avx2,fma,popcnt,avx512f,avx512vl")))
 * through WINL; names come out as boxes_8_avx512 and so on
 * (lib/README.md).  popc_ and rank_ are AVX2's (simd_wide_avx2.h), compiled
 * again here; the triangle blocks are simd_wide_tri4.h's, as for AVX2. */
#include <immintrin.h>

/* ---- per-ray constants ------------------------------------------------------ */

typedef struct WFN(ray_consts_) {
    __m256 org_x, org_y, org_z;     /* origin, in every lane */
    __m256 inv_x, inv_y, inv_z;     /* 1/d */
    __m256 far_x, far_y, far_z;     /* 1/d times the Ize factor (far planes) */
    __m256 tmin;
    __mmask8 neg_x, neg_y, neg_z;   /* all lanes set where the direction is negative: picks the planes in boxes_ */
    wide_tri_ray tri;               /* watertight triangle test, lane-broadcast (simd_tri4_sse.h) */
} WFN(ray_consts_);

WINL void WFN(ray_consts_init_)(WFN(ray_consts_) * consts, const sidx_ray *r, float scale)
{
    const float *o = sidx_v3_array(&r->org), *inv = sidx_v3_array(&r->inv_dir);
    consts->org_x = _mm256_set1_ps(o[0]); consts->org_y = _mm256_set1_ps(o[1]); consts->org_z = _mm256_set1_ps(o[2]);
    consts->inv_x = _mm256_set1_ps(inv[0]);
    consts->inv_y = _mm256_set1_ps(inv[1]);
    consts->inv_z = _mm256_set1_ps(inv[2]);
    consts->far_x = _mm256_set1_ps(inv[0] * scale); consts->far_y = _mm256_set1_ps(inv[1] * scale);
    consts->far_z = _mm256_set1_ps(inv[2] * scale);
    consts->tmin = _mm256_set1_ps(r->tmin);
    consts->neg_x = (__mmask8)(r->sign[0] ? 0xFF : 0); consts->neg_y = (__mmask8)(r->sign[1] ? 0xFF : 0);
    consts->neg_z = (__mmask8)(r->sign[2] ? 0xFF : 0);
}

WINL void WFN(tri_consts_init_)(WFN(ray_consts_) * consts, const sidx_ray *r) { wide_tri_ray_init(&consts->tri, r); }

/* ---- 8 boxes at once ---------------------------------------------------------- */
WINL unsigned WFN(boxes_)(const float *node, const WFN(ray_consts_) * consts, float best, float *t_near, float *t_far,
                          const int want_far)
{
    const __m256 lo_x = _mm256_load_ps(node), lo_y = _mm256_load_ps(node + 8), lo_z = _mm256_load_ps(node + 16);
    const __m256 hi_x = _mm256_load_ps(node + 24), hi_y = _mm256_load_ps(node + 32), hi_z = _mm256_load_ps(node + 40);
    const __m256 enter_x = _mm256_mask_blend_ps(consts->neg_x, lo_x, hi_x);
    const __m256 exit_x = _mm256_mask_blend_ps(consts->neg_x, hi_x, lo_x);
    const __m256 enter_y = _mm256_mask_blend_ps(consts->neg_y, lo_y, hi_y);
    const __m256 exit_y = _mm256_mask_blend_ps(consts->neg_y, hi_y, lo_y);
    const __m256 enter_z = _mm256_mask_blend_ps(consts->neg_z, lo_z, hi_z);
    const __m256 exit_z = _mm256_mask_blend_ps(consts->neg_z, hi_z, lo_z);
    const __m256 near_x = _mm256_mul_ps(_mm256_sub_ps(enter_x, consts->org_x), consts->inv_x);
    const __m256 near_y = _mm256_mul_ps(_mm256_sub_ps(enter_y, consts->org_y), consts->inv_y);
    const __m256 near_z = _mm256_mul_ps(_mm256_sub_ps(enter_z, consts->org_z), consts->inv_z);
    const __m256 far_x = _mm256_mul_ps(_mm256_sub_ps(exit_x, consts->org_x), consts->far_x);
    const __m256 far_y = _mm256_mul_ps(_mm256_sub_ps(exit_y, consts->org_y), consts->far_y);
    const __m256 far_z = _mm256_mul_ps(_mm256_sub_ps(exit_z, consts->org_z), consts->far_z);
    __m256 t_enter = _mm256_max_ps(near_x, consts->tmin);
    t_enter = _mm256_max_ps(near_y, t_enter);
    t_enter = _mm256_max_ps(near_z, t_enter);
    __m256 t_exit = _mm256_min_ps(far_x, _mm256_set1_ps(best));
    t_exit = _mm256_min_ps(far_y, t_exit);
    t_exit = _mm256_min_ps(far_z, t_exit);
    _mm256_store_ps(t_near, t_enter);
    if (want_far) _mm256_store_ps(t_far, t_exit);
    return (unsigned)_mm256_cmp_ps_mask(t_enter, t_exit, _CMP_LE_OQ);
}

/* ---- the order of the hit children: AVX2's ------------------------------------ */

WINL uint32_t WFN(popc_)(unsigned x) { return (uint32_t)__builtin_popcount(x); }

WINL uint32_t WFN(rank_)(const float *t_near, unsigned slot, unsigned hit_mask)
{
    const __m256 entries = _mm256_load_ps(t_near), own = _mm256_set1_ps(t_near[slot]);
    const unsigned nearer = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_LT_OQ));
    const unsigned as_near = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_EQ_OQ));
    return WFN(popc_)(hit_mask & (nearer | (as_near & ((1u << slot) - 1u))));
}

/* ---- triangle blocks: simd_wide_tri4.h ------------------------------------- */

#include "simd_wide_tri4.h"
