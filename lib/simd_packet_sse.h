/* simd_packet_sse.h — the frustum kernels of the binary-BVH packet walk
 * (packet.c) with SSE2, the 4 planes in the 4 lanes: the same operations
 * in the same order as simd_packet_scalar.h's, so the same answers.  SSE2
 * is baseline on x86-64, so these are chosen at compile time.
 *
 * Not a normal header: packet.c includes it after its types where SSE2
 * is there. */
#include <immintrin.h>

/* The node box against the 4 planes (frustum_overlap_scalar, one plane
 * per lane). */
static SIDX_INLINE int frustum_overlap_sse(const packet *pkt, const bvh_node *node)
{
    const float diag =
        (node->bmax[0] - node->bmin[0]) + (node->bmax[1] - node->bmin[1]) + (node->bmax[2] - node->bmin[2]);
    __m128 dot = _mm_setzero_ps(), mag = _mm_setzero_ps();
    const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
    for (int k = 0; k < 3; ++k) {
        const __m128 corner = _mm_or_ps(_mm_and_ps(pkt->plane_pos_lanes[k], _mm_set1_ps(node->bmax[k])),
                                     _mm_andnot_ps(pkt->plane_pos_lanes[k], _mm_set1_ps(node->bmin[k])));
        const __m128 rel = _mm_sub_ps(corner, _mm_set1_ps(pkt->apex[k]));
        dot = _mm_add_ps(dot, _mm_mul_ps(pkt->plane_n_lanes[k], rel));
        mag = _mm_add_ps(mag, _mm_and_ps(rel, absmask));
    }
    const __m128 limit =
        _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(-1e-5f), pkt->plane_l1_lanes), _mm_add_ps(mag, _mm_set1_ps(diag)));
    return _mm_movemask_ps(_mm_cmplt_ps(dot, limit)) == 0;
}

/* Every ray inside the 4 planes (frustum_rays_inside_scalar): one pass
 * over the rays, the 4 planes in the 4 lanes (the same products in the
 * same order as sidx_v3_dot). */
static SIDX_INLINE int frustum_rays_inside_sse(const packet *pkt, const sidx_ray *rays, uint32_t n, const float len2[4])
{
    const __m128 normal_x = _mm_setr_ps(pkt->plane_n[0][0], pkt->plane_n[1][0], pkt->plane_n[2][0], pkt->plane_n[3][0]);
    const __m128 normal_y = _mm_setr_ps(pkt->plane_n[0][1], pkt->plane_n[1][1], pkt->plane_n[2][1], pkt->plane_n[3][1]);
    const __m128 normal_z = _mm_setr_ps(pkt->plane_n[0][2], pkt->plane_n[1][2], pkt->plane_n[2][2], pkt->plane_n[3][2]);
    const __m128 tol = _mm_mul_ps(_mm_set1_ps(1e-12f), _mm_setr_ps(len2[0], len2[1], len2[2], len2[3]));
    __m128 bad = _mm_setzero_ps();
    for (uint32_t i = 0; i < n; ++i) {
        if (i && memcmp(&rays[i].org, &rays[0].org, sizeof rays[0].org)) return 0;
        const sidx_vec3 dir = rays[i].dir;
        const __m128 dots =
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(normal_x, _mm_set1_ps(dir.x)), _mm_mul_ps(normal_y, _mm_set1_ps(dir.y))),
                       _mm_mul_ps(normal_z, _mm_set1_ps(dir.z)));
        const __m128 dir_len2 = _mm_set1_ps(sidx_v3_dot(dir, dir));
        bad = _mm_or_ps(bad, _mm_and_ps(_mm_cmplt_ps(dots, _mm_setzero_ps()),
                                        _mm_cmpgt_ps(_mm_mul_ps(dots, dots), _mm_mul_ps(tol, dir_len2))));
    }
    return !_mm_movemask_ps(bad);
}

/* The planes once more, one per lane, for frustum_overlap_sse. */
static SIDX_INLINE void frustum_lanes_sse(packet *pkt)
{
    for (int k = 0; k < 3; ++k) {
        pkt->plane_n_lanes[k] =
            _mm_setr_ps(pkt->plane_n[0][k], pkt->plane_n[1][k], pkt->plane_n[2][k], pkt->plane_n[3][k]);
        pkt->plane_pos_lanes[k] = _mm_cmpge_ps(pkt->plane_n_lanes[k], _mm_setzero_ps());
    }
    pkt->plane_l1_lanes = _mm_setr_ps(pkt->plane_l1[0], pkt->plane_l1[1], pkt->plane_l1[2], pkt->plane_l1[3]);
}
