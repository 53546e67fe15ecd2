/* simd_packet_wide_avx2.h — the wide-BVH packet walk's kernels with AVX2
 * (packet_wide.c): 8 boxes per pass for bvh8, 4 with SSE for bvh4, a box
 * against a group of 8 rays, and the SSE2 4-triangle block kernel of
 * simd_tri4_sse.h; with them the SSE2 set-up (sign classes, interval
 * bounds, 4 lanes at a time).  The same IEEE operations in the same order
 * as simd_packet_wide_scalar.h, the reference, so the same bits.
 *
 * Not a normal header: packet_wide.c includes it after its types and the
 * reference, on x86 with SSE2; chosen at run time (avx = 1), inlined into
 * the AVX2 copies of the walk (walk8_avx, walk4_avx). */
#include <immintrin.h>

/* ---- set-up (SSE2) ---------------------------------------------------------------- */

/* Do all lanes share lane 0's sign class?  The sign bits of 4 lanes per
 * movemask. */
static SIDX_INLINE int lanes_uniform_sse(const wide_packet *pkt)
{
    const uint32_t n_lanes = pkt->ngroups * GROUP_LANES;
    const float *const arr[3] = {pkt->inv_x, pkt->inv_y, pkt->inv_z};
    unsigned bad = 0;
    for (int k = 0; k < 3; ++k) {
        const unsigned want = signbit(arr[k][0]) ? 0xFu : 0u;
        for (uint32_t i = 0; i < n_lanes; i += 4) bad |= (unsigned)_mm_movemask_ps(_mm_load_ps(arr[k] + i)) ^ want;
    }
    return bad == 0;
}

/* The interval bounds when every lane counts (padding repeats ray 0). */
static SIDX_INLINE void bounds_sse(const wide_packet *pkt, ray_bounds *out)
{
    const uint32_t n_lanes = pkt->ngroups * GROUP_LANES;
    const float *const arr[3][2] = {{pkt->org_x, pkt->inv_x}, {pkt->org_y, pkt->inv_y}, {pkt->org_z, pkt->inv_z}};
    /* every lane counts (padding repeats ray 0): 4 lanes at a time */
    for (int k = 0; k < 3; ++k) {
        __m128 org_lo = _mm_load_ps(arr[k][0]), org_hi = org_lo, inv_lo = _mm_load_ps(arr[k][1]), inv_hi = inv_lo;
        for (uint32_t i = 4; i < n_lanes; i += 4) {
            const __m128 org = _mm_load_ps(arr[k][0] + i), inv = _mm_load_ps(arr[k][1] + i);
            org_lo = _mm_min_ps(org, org_lo); org_hi = _mm_max_ps(org, org_hi);
            inv_lo = _mm_min_ps(inv, inv_lo); inv_hi = _mm_max_ps(inv, inv_hi);
        }
        org_lo = _mm_min_ps(org_lo, _mm_shuffle_ps(org_lo, org_lo, _MM_SHUFFLE(1, 0, 3, 2)));
        org_lo = _mm_min_ps(org_lo, _mm_shuffle_ps(org_lo, org_lo, _MM_SHUFFLE(2, 3, 0, 1)));
        org_hi = _mm_max_ps(org_hi, _mm_shuffle_ps(org_hi, org_hi, _MM_SHUFFLE(1, 0, 3, 2)));
        org_hi = _mm_max_ps(org_hi, _mm_shuffle_ps(org_hi, org_hi, _MM_SHUFFLE(2, 3, 0, 1)));
        inv_lo = _mm_min_ps(inv_lo, _mm_shuffle_ps(inv_lo, inv_lo, _MM_SHUFFLE(1, 0, 3, 2)));
        inv_lo = _mm_min_ps(inv_lo, _mm_shuffle_ps(inv_lo, inv_lo, _MM_SHUFFLE(2, 3, 0, 1)));
        inv_hi = _mm_max_ps(inv_hi, _mm_shuffle_ps(inv_hi, inv_hi, _MM_SHUFFLE(1, 0, 3, 2)));
        inv_hi = _mm_max_ps(inv_hi, _mm_shuffle_ps(inv_hi, inv_hi, _MM_SHUFFLE(2, 3, 0, 1)));
        out->omin[k] = _mm_cvtss_f32(org_lo); out->omax[k] = _mm_cvtss_f32(org_hi);
        out->imin[k] = _mm_cvtss_f32(inv_lo); out->imax[k] = _mm_cvtss_f32(inv_hi);
    }
    /* padding lanes (tmin +inf, best −inf) change neither */
    __m128 tmin_lo = _mm_load_ps(pkt->tmin), best_hi = _mm_load_ps(pkt->best_clip);
    for (uint32_t i = 4; i < n_lanes; i += 4) {
        tmin_lo = _mm_min_ps(_mm_load_ps(pkt->tmin + i), tmin_lo);
        best_hi = _mm_max_ps(_mm_load_ps(pkt->best_clip + i), best_hi);
    }
    tmin_lo = _mm_min_ps(tmin_lo, _mm_shuffle_ps(tmin_lo, tmin_lo, _MM_SHUFFLE(1, 0, 3, 2)));
    tmin_lo = _mm_min_ps(tmin_lo, _mm_shuffle_ps(tmin_lo, tmin_lo, _MM_SHUFFLE(2, 3, 0, 1)));
    best_hi = _mm_max_ps(best_hi, _mm_shuffle_ps(best_hi, best_hi, _MM_SHUFFLE(1, 0, 3, 2)));
    best_hi = _mm_max_ps(best_hi, _mm_shuffle_ps(best_hi, best_hi, _MM_SHUFFLE(2, 3, 0, 1)));
    out->tmin = _mm_cvtss_f32(tmin_lo);
    out->tmax = _mm_cvtss_f32(best_hi);
}

/* ---- node and leaf (AVX2, SSE) ------------------------------------------------------ */

/* Not always_inline: the scalar walks mention these calls in branches that
 * fold away, and an always_inline AVX2 callee there would not compile;
 * the flatten attribute of the AVX2 walks inlines them. */
#define AVX __attribute__((target("avx2,fma"))) static inline

AVX unsigned ia_slots_avx(const float *node, const uint32_t W, const wide_packet *pkt, float *key)
{
    if (W == 8) {
        __m256 lower = _mm256_set1_ps(pkt->ia_tmin), upper = _mm256_set1_ps(pkt->ia_tmax);
        for (int k = 0; k < 3; ++k) {
            const __m256 d_near =
                _mm256_sub_ps(_mm256_load_ps(node + pkt->near_row[k] * 8u), _mm256_set1_ps(pkt->ia_org_near[k]));
            const __m256 d_far =
                _mm256_sub_ps(_mm256_load_ps(node + pkt->far_row[k] * 8u), _mm256_set1_ps(pkt->ia_org_far[k]));
            const __m256 lo = _mm256_min_ps(_mm256_mul_ps(d_near, _mm256_set1_ps(pkt->ia_inv_lo[k])),
                                            _mm256_mul_ps(d_near, _mm256_set1_ps(pkt->ia_inv_hi[k])));
            const __m256 hi = _mm256_max_ps(_mm256_mul_ps(d_far, _mm256_set1_ps(pkt->ia_far_lo[k])),
                                            _mm256_mul_ps(d_far, _mm256_set1_ps(pkt->ia_far_hi[k])));
            lower = _mm256_max_ps(lo, lower);
            upper = _mm256_min_ps(hi, upper);
        }
        _mm256_storeu_ps(key, lower);
        return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(lower, upper, _CMP_LE_OQ));
    }
    __m128 lower = _mm_set1_ps(pkt->ia_tmin), upper = _mm_set1_ps(pkt->ia_tmax);
    for (int k = 0; k < 3; ++k) {
        const __m128 d_near = _mm_sub_ps(_mm_load_ps(node + pkt->near_row[k] * 4u), _mm_set1_ps(pkt->ia_org_near[k]));
        const __m128 d_far = _mm_sub_ps(_mm_load_ps(node + pkt->far_row[k] * 4u), _mm_set1_ps(pkt->ia_org_far[k]));
        const __m128 lo = _mm_min_ps(_mm_mul_ps(d_near, _mm_set1_ps(pkt->ia_inv_lo[k])),
                                     _mm_mul_ps(d_near, _mm_set1_ps(pkt->ia_inv_hi[k])));
        const __m128 hi = _mm_max_ps(_mm_mul_ps(d_far, _mm_set1_ps(pkt->ia_far_lo[k])),
                                     _mm_mul_ps(d_far, _mm_set1_ps(pkt->ia_far_hi[k])));
        lower = _mm_max_ps(lo, lower);
        upper = _mm_min_ps(hi, upper);
    }
    _mm_storeu_ps(key, lower);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(lower, upper));
}

AVX unsigned ray_slots_avx(const float *node, const uint32_t W, const wide_packet *pkt, uint32_t i, float *t_near)
{
    if (W == 8) {
        const __m256 org_x = _mm256_broadcast_ss(pkt->org_x + i), org_y = _mm256_broadcast_ss(pkt->org_y + i),
                     org_z = _mm256_broadcast_ss(pkt->org_z + i);
        const __m256 near_x = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node + pkt->near_row[0] * 8u), org_x),
                                            _mm256_broadcast_ss(pkt->inv_x + i));
        const __m256 near_y = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node + pkt->near_row[1] * 8u), org_y),
                                            _mm256_broadcast_ss(pkt->inv_y + i));
        const __m256 near_z = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node + pkt->near_row[2] * 8u), org_z),
                                            _mm256_broadcast_ss(pkt->inv_z + i));
        const __m256 far_x = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node + pkt->far_row[0] * 8u), org_x),
                                           _mm256_broadcast_ss(pkt->inv_far_x + i));
        const __m256 far_y = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node + pkt->far_row[1] * 8u), org_y),
                                           _mm256_broadcast_ss(pkt->inv_far_y + i));
        const __m256 far_z = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(node + pkt->far_row[2] * 8u), org_z),
                                           _mm256_broadcast_ss(pkt->inv_far_z + i));
        __m256 t_enter = _mm256_max_ps(near_x, _mm256_broadcast_ss(pkt->tmin + i));
        t_enter = _mm256_max_ps(near_y, t_enter);
        t_enter = _mm256_max_ps(near_z, t_enter);
        __m256 t_exit = _mm256_min_ps(far_x, _mm256_broadcast_ss(pkt->best_clip + i));
        t_exit = _mm256_min_ps(far_y, t_exit);
        t_exit = _mm256_min_ps(far_z, t_exit);
        if (t_near) _mm256_storeu_ps(t_near, t_enter);
        return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ));
    }
    const __m128 org_x = _mm_broadcast_ss(pkt->org_x + i), org_y = _mm_broadcast_ss(pkt->org_y + i),
                 org_z = _mm_broadcast_ss(pkt->org_z + i);
    const __m128 near_x =
        _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + pkt->near_row[0] * 4u), org_x), _mm_broadcast_ss(pkt->inv_x + i));
    const __m128 near_y =
        _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + pkt->near_row[1] * 4u), org_y), _mm_broadcast_ss(pkt->inv_y + i));
    const __m128 near_z =
        _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + pkt->near_row[2] * 4u), org_z), _mm_broadcast_ss(pkt->inv_z + i));
    const __m128 far_x =
        _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + pkt->far_row[0] * 4u), org_x), _mm_broadcast_ss(pkt->inv_far_x + i));
    const __m128 far_y =
        _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + pkt->far_row[1] * 4u), org_y), _mm_broadcast_ss(pkt->inv_far_y + i));
    const __m128 far_z =
        _mm_mul_ps(_mm_sub_ps(_mm_load_ps(node + pkt->far_row[2] * 4u), org_z), _mm_broadcast_ss(pkt->inv_far_z + i));
    __m128 t_enter = _mm_max_ps(near_x, _mm_broadcast_ss(pkt->tmin + i));
    t_enter = _mm_max_ps(near_y, t_enter);
    t_enter = _mm_max_ps(near_z, t_enter);
    __m128 t_exit = _mm_min_ps(far_x, _mm_broadcast_ss(pkt->best_clip + i));
    t_exit = _mm_min_ps(far_y, t_exit);
    t_exit = _mm_min_ps(far_z, t_exit);
    if (t_near) _mm_storeu_ps(t_near, t_enter);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(t_enter, t_exit));
}

AVX unsigned group_slot_avx(const float *node, const uint32_t W, uint32_t slot, const wide_packet *pkt, uint32_t group)
{
    const uint32_t i = group * GROUP_LANES;
    const __m256 org_x = _mm256_load_ps(pkt->org_x + i), org_y = _mm256_load_ps(pkt->org_y + i),
                 org_z = _mm256_load_ps(pkt->org_z + i);
    const __m256 near_x = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(node + pkt->near_row[0] * W + slot), org_x),
                                        _mm256_load_ps(pkt->inv_x + i));
    const __m256 near_y = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(node + pkt->near_row[1] * W + slot), org_y),
                                        _mm256_load_ps(pkt->inv_y + i));
    const __m256 near_z = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(node + pkt->near_row[2] * W + slot), org_z),
                                        _mm256_load_ps(pkt->inv_z + i));
    const __m256 far_x = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(node + pkt->far_row[0] * W + slot), org_x),
                                       _mm256_load_ps(pkt->inv_far_x + i));
    const __m256 far_y = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(node + pkt->far_row[1] * W + slot), org_y),
                                       _mm256_load_ps(pkt->inv_far_y + i));
    const __m256 far_z = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(node + pkt->far_row[2] * W + slot), org_z),
                                       _mm256_load_ps(pkt->inv_far_z + i));
    __m256 t_enter = _mm256_max_ps(near_x, _mm256_load_ps(pkt->tmin + i));
    t_enter = _mm256_max_ps(near_y, t_enter);
    t_enter = _mm256_max_ps(near_z, t_enter);
    __m256 t_exit = _mm256_min_ps(far_x, _mm256_load_ps(pkt->best_clip + i));
    t_exit = _mm256_min_ps(far_y, t_exit);
    t_exit = _mm256_min_ps(far_z, t_exit);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ));
}

/* Ray i against one leaf, a block per SSE pass; a block with a zero edge
 * function goes through the scalar loop (on that block only). */
static SIDX_INLINE int leaf_ray_sse(const sidx_accel *a, const wide_tri4 *block, wide_packet *pkt, uint32_t i)
{
    const sidx_ray *r = pkt->ray[i];
    wide_tri_ray tri; /* the shared kernel of bvh_wide_internal.h, set up once per leaf */
    wide_tri_ray_init(&tri, r);
    for (;; ++block) {
        float t;
        unsigned lane;
        const int hit = wide_tri4_test(block, &tri, pkt->best[i], &t, &lane, NULL);
        if (hit > 0) {
            pkt->prim[i] = block->prim[lane] & WIDE_PRIM_MASK;
            if (pkt->anyhit) {
                pkt->best[i] = pkt->best_clip[i] = -INFINITY;
                return 1;
            }
            pkt->best[i] = t;
            pkt->best_clip[i] = t * pkt->scale;
        } else if (SIDX_UNLIKELY(hit < 0)) {
            for (int lane = 0; lane < 4; ++lane) {
                const uint32_t id = block->prim[lane] & WIDE_PRIM_MASK;
                if (id == WIDE_PAD_PRIM) continue;
                if (wide_lane_test(a, r, block, (unsigned)lane, pkt->best[i], &t, NULL, NULL)) {
                    pkt->prim[i] = id;
                    if (pkt->anyhit) {
                        pkt->best[i] = pkt->best_clip[i] = -INFINITY;
                        return 1;
                    }
                    pkt->best[i] = t;
                    pkt->best_clip[i] = t * pkt->scale;
                }
            }
        }
        if (block->prim[0] & WIDE_LAST_BLOCK) return 0;
    }
}
#undef AVX
