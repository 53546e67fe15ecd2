/* simd_packet_avx2.h — the binary-BVH packet walk's box and triangle
 * kernels with AVX2: one box or one triangle against a group of 8 rays,
 * one lane per ray.  The same IEEE operations in the same order as
 * simd_packet_scalar.h (the reference; tri_lane there is also the
 * fallback of a lane whose edge function is exactly 0), so the same bits.
 *
 * Not a normal header: packet.c includes it after its types and
 * simd_packet_scalar.h, on x86 only; chosen at run time
 * (sidx__packet_have_avx2), inlined into the AVX2 copy of the walk. */
#include <immintrin.h>

__attribute__((target("avx2,fma"))) static unsigned box8_avx2(const packet *pkt, uint32_t group, const float planes[6])
{
    const uint32_t i = group * GROUP_LANES;
    const __m256 org_x = _mm256_load_ps(pkt->org_x + i), org_y = _mm256_load_ps(pkt->org_y + i),
                 org_z = _mm256_load_ps(pkt->org_z + i);
    const __m256 near_x =
        _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(planes[0]), org_x), _mm256_load_ps(pkt->inv_x + i));
    const __m256 near_y =
        _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(planes[1]), org_y), _mm256_load_ps(pkt->inv_y + i));
    const __m256 near_z =
        _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(planes[2]), org_z), _mm256_load_ps(pkt->inv_z + i));
    const __m256 far_x =
        _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(planes[3]), org_x), _mm256_load_ps(pkt->inv_far_x + i));
    const __m256 far_y =
        _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(planes[4]), org_y), _mm256_load_ps(pkt->inv_far_y + i));
    const __m256 far_z =
        _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(planes[5]), org_z), _mm256_load_ps(pkt->inv_far_z + i));
    __m256 t_enter = _mm256_max_ps(near_x, _mm256_load_ps(pkt->tmin + i)); /* slab value first: NaN never narrows */
    t_enter = _mm256_max_ps(near_y, t_enter);
    t_enter = _mm256_max_ps(near_z, t_enter);
    __m256 t_exit = _mm256_min_ps(far_x, _mm256_load_ps(pkt->best + i));
    t_exit = _mm256_min_ps(far_y, t_exit);
    t_exit = _mm256_min_ps(far_z, t_exit);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t_enter, t_exit, _CMP_LE_OQ));
}

/* The watertight test across 8 rays sharing kx, ky, kz: the triangle is
 * broadcast, each lane translates and shears it by its own ray. */
__attribute__((target("avx2,fma"))) static void tri8_avx2(const walkopt *walk, packet *pkt, uint32_t group,
                                                          const bvh_tri *tri, uint32_t prim)
{
    const uint32_t i = group * GROUP_LANES;
    const float *corner_a = sidx_v3_array(&tri->v[0]), *corner_b = sidx_v3_array(&tri->v[1]), *corner_c = sidx_v3_array(&tri->v[2]);
    const __m256 org_kx = _mm256_load_ps(pkt->org_kx + i), org_ky = _mm256_load_ps(pkt->org_ky + i),
                 org_kz = _mm256_load_ps(pkt->org_kz + i);
    const __m256 sx = _mm256_load_ps(pkt->sx + i), sy = _mm256_load_ps(pkt->sy + i), sz = _mm256_load_ps(pkt->sz + i);
    const __m256 ax = _mm256_sub_ps(_mm256_set1_ps(corner_a[pkt->kx]), org_kx),
                 ay = _mm256_sub_ps(_mm256_set1_ps(corner_a[pkt->ky]), org_ky),
                 az = _mm256_sub_ps(_mm256_set1_ps(corner_a[pkt->kz]), org_kz);
    const __m256 bx = _mm256_sub_ps(_mm256_set1_ps(corner_b[pkt->kx]), org_kx),
                 by = _mm256_sub_ps(_mm256_set1_ps(corner_b[pkt->ky]), org_ky),
                 bz = _mm256_sub_ps(_mm256_set1_ps(corner_b[pkt->kz]), org_kz);
    const __m256 cx = _mm256_sub_ps(_mm256_set1_ps(corner_c[pkt->kx]), org_kx),
                 cy = _mm256_sub_ps(_mm256_set1_ps(corner_c[pkt->ky]), org_ky),
                 cz = _mm256_sub_ps(_mm256_set1_ps(corner_c[pkt->kz]), org_kz);
    const __m256 Ax = _mm256_sub_ps(ax, _mm256_mul_ps(sx, az)), Ay = _mm256_sub_ps(ay, _mm256_mul_ps(sy, az));
    const __m256 Bx = _mm256_sub_ps(bx, _mm256_mul_ps(sx, bz)), By = _mm256_sub_ps(by, _mm256_mul_ps(sy, bz));
    const __m256 Cx = _mm256_sub_ps(cx, _mm256_mul_ps(sx, cz)), Cy = _mm256_sub_ps(cy, _mm256_mul_ps(sy, cz));
    const __m256 U = _mm256_sub_ps(_mm256_mul_ps(Cx, By), _mm256_mul_ps(Cy, Bx));
    const __m256 V = _mm256_sub_ps(_mm256_mul_ps(Ax, Cy), _mm256_mul_ps(Ay, Cx));
    const __m256 W = _mm256_sub_ps(_mm256_mul_ps(Bx, Ay), _mm256_mul_ps(By, Ax));
    const __m256 zero = _mm256_setzero_ps();
    const unsigned zero_lanes = (unsigned)_mm256_movemask_ps(_mm256_or_ps(
        _mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_EQ_OQ), _mm256_cmp_ps(V, zero, _CMP_EQ_OQ)),
        _mm256_cmp_ps(W, zero, _CMP_EQ_OQ)));
    const __m256 neg =
        _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_LT_OQ), _mm256_cmp_ps(V, zero, _CMP_LT_OQ)),
                     _mm256_cmp_ps(W, zero, _CMP_LT_OQ));
    const __m256 pos =
        _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_GT_OQ), _mm256_cmp_ps(V, zero, _CMP_GT_OQ)),
                     _mm256_cmp_ps(W, zero, _CMP_GT_OQ));
    const __m256 det = _mm256_add_ps(_mm256_add_ps(U, V), W);
    const __m256 T =
        _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(U, _mm256_mul_ps(sz, az)), _mm256_mul_ps(V, _mm256_mul_ps(sz, bz))),
                      _mm256_mul_ps(W, _mm256_mul_ps(sz, cz)));
    const __m256 t = _mm256_div_ps(T, det);
    const __m256 best = _mm256_load_ps(pkt->best + i);
    const __m256 ok = _mm256_andnot_ps(
        _mm256_and_ps(neg, pos),
        _mm256_and_ps(_mm256_cmp_ps(det, zero, _CMP_NEQ_UQ),
                      _mm256_and_ps(_mm256_cmp_ps(t, _mm256_load_ps(pkt->tmin + i), _CMP_GE_OQ),
                                    _mm256_cmp_ps(t, best, _CMP_LT_OQ))));
    unsigned hit_lanes = (unsigned)_mm256_movemask_ps(ok) & ~zero_lanes;
    if (hit_lanes) {
        _mm256_store_ps(pkt->best + i, _mm256_blendv_ps(best, pkt->anyhit ? _mm256_set1_ps(-INFINITY) : t, ok));
        /* ok lanes with a zero edge were blended too; they are redone below */
        while (hit_lanes) {
            pkt->prim[i + (uint32_t)__builtin_ctz(hit_lanes)] = prim;
            hit_lanes &= hit_lanes - 1;
        }
    }
    if (SIDX_UNLIKELY(zero_lanes)) {
        /* Exact zero edge function: the scalar test (double fallback) for
         * those lanes, from the bound they had before this triangle. */
        const float *old_best = (const float *)&best;
        for (unsigned zeros = zero_lanes; zeros; zeros &= zeros - 1) {
            const uint32_t lane = (uint32_t)__builtin_ctz(zeros);
            pkt->best[i + lane] = old_best[lane];
            tri_lane(walk, pkt, i + lane, tri, prim);
        }
    }
}
