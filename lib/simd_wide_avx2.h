/* simd_wide_avx2.h — the wide walk's kernels with AVX2: 8 child boxes per
 * pass (bvh8), POPCNT for the slot masks, and the SSE2 4-triangle block
 * kernel of simd_tri4_sse.h.  The same IEEE operations in the same order
 * as simd_wide_scalar.h (the reference, which lists what every kernel
 * header defines), so the same bits.
 *
 * Not a normal header: bvh_wide_walk.h includes it for WALK_ISA 2 (W = 8),
 * compiled with __attribute__((target("avx2,fma,popcnt"))) through WINL;
 * names come out as boxes_8_avx2 and so on (lib/README.md).  The AVX-512
 * copy (simd_wide_avx512.h) is this code with the planes picked another
 * way. */
#include <immintrin.h>

/* ---- per-ray constants ------------------------------------------------------ */

typedef struct WFN(ray_consts_) {
    __m256 org_x, org_y, org_z;     /* origin, in every lane */
    __m256 inv_x, inv_y, inv_z;     /* 1/d */
    __m256 far_x, far_y, far_z;     /* 1/d times the Ize factor (far planes) */
    __m256 tmin;
    wide_tri_ray tri;               /* watertight triangle test, lane-broadcast (simd_tri4_sse.h) */
    uint32_t near_off[3], far_off[3]; /* float offsets of the near / far planes of each axis inside a node */
} WFN(ray_consts_);

WINL void WFN(ray_consts_init_)(WFN(ray_consts_) * consts, const sidx_ray *r, float scale)
{
    const float *o = sidx_v3_array(&r->org), *inv = sidx_v3_array(&r->inv_dir);
    for (int k = 0; k < 3; ++k) {
        /* b[0..2] = lo, b[3..5] = hi: a negative direction enters through hi. */
        consts->near_off[k] = (uint32_t)((r->sign[k] ? 3 + k : k) * WALK_W);
        consts->far_off[k] = (uint32_t)((r->sign[k] ? k : 3 + k) * WALK_W);
    }
    consts->org_x = _mm256_set1_ps(o[0]); consts->org_y = _mm256_set1_ps(o[1]); consts->org_z = _mm256_set1_ps(o[2]);
    consts->inv_x = _mm256_set1_ps(inv[0]);
    consts->inv_y = _mm256_set1_ps(inv[1]);
    consts->inv_z = _mm256_set1_ps(inv[2]);
    consts->far_x = _mm256_set1_ps(inv[0] * scale); consts->far_y = _mm256_set1_ps(inv[1] * scale);
    consts->far_z = _mm256_set1_ps(inv[2] * scale);
    consts->tmin = _mm256_set1_ps(r->tmin);
}

WINL void WFN(tri_consts_init_)(WFN(ray_consts_) * consts, const sidx_ray *r) { wide_tri_ray_init(&consts->tri, r); }

/* ---- 8 boxes at once ----------------------------------------------------------
 * MAXPS / MINPS return their second operand when either is NaN, so the
 * slab value goes first and the running interval second. */
WINL unsigned WFN(boxes_)(const float *node, const WFN(ray_consts_) * consts, float best, float *t_near, float *t_far,
                          const int want_far)
{
    const __m256 lo_x = _mm256_load_ps(node + consts->near_off[0]), hi_x = _mm256_load_ps(node + consts->far_off[0]);
    const __m256 lo_y = _mm256_load_ps(node + consts->near_off[1]), hi_y = _mm256_load_ps(node + consts->far_off[1]);
    const __m256 lo_z = _mm256_load_ps(node + consts->near_off[2]), hi_z = _mm256_load_ps(node + consts->far_off[2]);
    const __m256 near_x = _mm256_mul_ps(_mm256_sub_ps(lo_x, consts->org_x), consts->inv_x);
    const __m256 near_y = _mm256_mul_ps(_mm256_sub_ps(lo_y, consts->org_y), consts->inv_y);
    const __m256 near_z = _mm256_mul_ps(_mm256_sub_ps(lo_z, consts->org_z), consts->inv_z);
    const __m256 far_x = _mm256_mul_ps(_mm256_sub_ps(hi_x, consts->org_x), consts->far_x);
    const __m256 far_y = _mm256_mul_ps(_mm256_sub_ps(hi_y, consts->org_y), consts->far_y);
    const __m256 far_z = _mm256_mul_ps(_mm256_sub_ps(hi_z, consts->org_z), consts->far_z);
    __m256 t_enter = _mm256_max_ps(near_x, consts->tmin);
    t_enter = _mm256_max_ps(near_y, t_enter);
    t_enter = _mm256_max_ps(near_z, t_enter);
    __m256 t_exit = _mm256_min_ps(far_x, _mm256_set1_ps(best));
    t_exit = _mm256_min_ps(far_y, t_exit);
    t_exit = _mm256_min_ps(far_z, t_exit);
    _mm256_store_ps(t_near, t_enter);
    if (want_far) _mm256_store_ps(t_far, t_exit);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ));
}

/* ---- the order of the hit children ------------------------------------------- */

WINL uint32_t WFN(popc_)(unsigned x) { return (uint32_t)__builtin_popcount(x); }

/* Where hit child `slot` goes among the hit children: the two compares of
 * simd_wide_scalar.h's rank_, all 8 entries at once. */
WINL uint32_t WFN(rank_)(const float *t_near, unsigned slot, unsigned hit_mask)
{
    const __m256 entries = _mm256_load_ps(t_near), own = _mm256_set1_ps(t_near[slot]);
    const unsigned nearer = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_LT_OQ));
    const unsigned as_near = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(entries, own, _CMP_EQ_OQ));
    return WFN(popc_)(hit_mask & (nearer | (as_near & ((1u << slot) - 1u))));
}

/* ---- triangle blocks: simd_wide_tri4.h ------------------------------------- */

#include "simd_wide_tri4.h"
