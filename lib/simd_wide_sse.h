/* simd_wide_sse.h — the wide walk's kernels with SSE4.1: 4 child boxes
 * per pass (bvh4), and the SSE2 4-triangle block kernel of simd_tri4_sse.h.
 * The same IEEE operations in the same order as simd_wide_scalar.h (the
 * reference, which lists what every kernel header defines), so the same
 * bits.
 *
 * Not a normal header: bvh_wide_walk.h includes it for WALK_ISA 1 (W = 4),
 * compiled with __attribute__((target("sse4.1"))) through WINL; names
 * come out as boxes_4_sse41 and so on (lib/README.md). */
#include <immintrin.h>

/* ---- per-ray constants ------------------------------------------------------ */

typedef struct WFN(ray_consts_) {
    __m128 org_x, org_y, org_z;     /* origin, in every lane */
    __m128 inv_x, inv_y, inv_z;     /* 1/d */
    __m128 far_x, far_y, far_z;     /* 1/d times the Ize factor (far planes) */
    __m128 tmin;
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
    consts->org_x = _mm_set1_ps(o[0]); consts->org_y = _mm_set1_ps(o[1]); consts->org_z = _mm_set1_ps(o[2]);
    consts->inv_x = _mm_set1_ps(inv[0]); consts->inv_y = _mm_set1_ps(inv[1]); consts->inv_z = _mm_set1_ps(inv[2]);
    consts->far_x = _mm_set1_ps(inv[0] * scale); consts->far_y = _mm_set1_ps(inv[1] * scale);
    consts->far_z = _mm_set1_ps(inv[2] * scale);
    consts->tmin = _mm_set1_ps(r->tmin);
}

WINL void WFN(tri_consts_init_)(WFN(ray_consts_) * consts, const sidx_ray *r) { wide_tri_ray_init(&consts->tri, r); }

/* ---- 4 boxes at once ----------------------------------------------------------
 * MAXPS / MINPS return their second operand when either is NaN, so the
 * slab value goes first and the running interval second. */
WINL unsigned WFN(boxes_)(const float *node, const WFN(ray_consts_) * consts, float best, float *t_near, float *t_far,
                          const int want_far)
{
    const __m128 near_x = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + consts->near_off[0]), consts->org_x), consts->inv_x);
    const __m128 near_y = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + consts->near_off[1]), consts->org_y), consts->inv_y);
    const __m128 near_z = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + consts->near_off[2]), consts->org_z), consts->inv_z);
    const __m128 far_x = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + consts->far_off[0]), consts->org_x), consts->far_x);
    const __m128 far_y = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + consts->far_off[1]), consts->org_y), consts->far_y);
    const __m128 far_z = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + consts->far_off[2]), consts->org_z), consts->far_z);
    __m128 t_enter = _mm_max_ps(near_x, consts->tmin);
    t_enter = _mm_max_ps(near_y, t_enter);
    t_enter = _mm_max_ps(near_z, t_enter);
    __m128 t_exit = _mm_min_ps(far_x, _mm_set1_ps(best));
    t_exit = _mm_min_ps(far_y, t_exit);
    t_exit = _mm_min_ps(far_z, t_exit);
    _mm_store_ps(t_near, t_enter);
    if (want_far) _mm_store_ps(t_far, t_exit);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(t_enter, t_exit));
}

/* ---- the order of the hit children ------------------------------------------- */

/* Bits set in a slot mask (< 256): no POPCNT in SSE4.1, so the bit-field
 * sum of the reference. */
WINL uint32_t WFN(popc_)(unsigned x)
{
    x = x - ((x >> 1) & 0x55u);
    x = (x & 0x33u) + ((x >> 2) & 0x33u);
    return (x + (x >> 4)) & 0x0Fu;
}

/* Where hit child `slot` goes among the hit children: the two compares of
 * simd_wide_scalar.h's rank_, all 4 entries at once. */
WINL uint32_t WFN(rank_)(const float *t_near, unsigned slot, unsigned hit_mask)
{
    const __m128 entries = _mm_load_ps(t_near), own = _mm_set1_ps(t_near[slot]);
    const unsigned nearer = (unsigned)_mm_movemask_ps(_mm_cmplt_ps(entries, own));
    const unsigned as_near = (unsigned)_mm_movemask_ps(_mm_cmpeq_ps(entries, own));
    return WFN(popc_)(hit_mask & (nearer | (as_near & ((1u << slot) - 1u))));
}

/* ---- triangle blocks: simd_wide_tri4.h ------------------------------------- */

#include "simd_wide_tri4.h"
