/* simd_tri4_sse.h — 4 triangles at once (watertight), one ray, with SSE2.
 *
 * Woop et al. 2013 on a leaf block's four lanes, SSE2 only so it inlines
 * into the SSE4.1 and AVX2 walks and the packet walk alike (the blend is
 * done with and/or).  The ray's lane-broadcast constants are set up once
 * per ray (tri4_ray_init).  Returns 1 with the smallest t in
 * [tmin, best) (lowest lane on ties), 0 for no hit, -1 when some lane's
 * edge function is exactly 0 and the block must take the scalar path
 * (tri4_lane_test, which redoes those in double).  When it returns 1 and
 * vw_det_out is not NULL, vw_det_out[0..3], [4..7], [8..11] receive the lanes'
 * V, W and det — the floats the scalar test computes too (no edge
 * function was 0, so it would not have switched to double) — from which
 * sidx__tri_watertight_uv forms the hit's u, v bit for bit.
 *
 * Included by tri4.h where SSE2 is there (every x86-64):
 * the wide walks (simd_wide_tri4.h), the wide packets (packet_wide.c) and
 * the kd-tree's leaf blocks use it.  The reference is the scalar
 * watertight test on each lane (tri4_lane_test, tri4.h);
 * the names are the paper's (a, b, c the corners relative to the origin,
 * A, B, C sheared, U, V, W the edge functions, T the scaled distance). */
#ifndef SIDX_SIMD_TRI4_SSE_H
#define SIDX_SIMD_TRI4_SSE_H

#include <immintrin.h>

typedef struct tri4_ray {
    __m128 org_kx, org_ky, org_kz; /* the origin on the permuted axes kx, ky, kz */
    __m128 sx, sy, sz, tmin;      /* the shear constants, tmin */
    uint32_t kx4, ky4, kz4; /* float offsets of the permuted axes inside a block's vertex */
} tri4_ray;

static SIDX_INLINE void tri4_ray_init(tri4_ray *ray, const sidx_ray *r)
{
    const float *o = sidx_v3_array(&r->org);
    ray->org_kx = _mm_set1_ps(o[r->kx]); ray->org_ky = _mm_set1_ps(o[r->ky]); ray->org_kz = _mm_set1_ps(o[r->kz]);
    ray->sx = _mm_set1_ps(r->sx); ray->sy = _mm_set1_ps(r->sy); ray->sz = _mm_set1_ps(r->sz);
    ray->tmin = _mm_set1_ps(r->tmin);
    ray->kx4 = 4u * r->kx; ray->ky4 = 4u * r->ky; ray->kz4 = 4u * r->kz;
}

/* The kernel on the ray's permuted axes of a block: row_x, row_y, row_z
 * point at vertex 0's kx, ky, kz row (vertex k's at +12k floats).
 * masked (a constant): only the lanes whose word in keep is all ones take
 * part, the others neither hit nor send the block to the scalar path (a
 * kd leaf's block holding a neighbouring leaf's references, tri4_test_lanes);
 * unmasked, the code is the kernel without those two ANDs. */
static SIDX_INLINE int tri4_kernel(const float *row_x, const float *row_y, const float *row_z, const tri4_ray *ray,
                                   float best, float *t_out, unsigned *lane_out, float *vw_det_out, const int masked,
                                   const __m128 keep)
{
    const __m128 ax = _mm_sub_ps(_mm_load_ps(row_x), ray->org_kx);
    const __m128 ay = _mm_sub_ps(_mm_load_ps(row_y), ray->org_ky);
    const __m128 az = _mm_sub_ps(_mm_load_ps(row_z), ray->org_kz);
    const __m128 bx = _mm_sub_ps(_mm_load_ps(row_x + 12), ray->org_kx);
    const __m128 by = _mm_sub_ps(_mm_load_ps(row_y + 12), ray->org_ky);
    const __m128 bz = _mm_sub_ps(_mm_load_ps(row_z + 12), ray->org_kz);
    const __m128 cx = _mm_sub_ps(_mm_load_ps(row_x + 24), ray->org_kx);
    const __m128 cy = _mm_sub_ps(_mm_load_ps(row_y + 24), ray->org_ky);
    const __m128 cz = _mm_sub_ps(_mm_load_ps(row_z + 24), ray->org_kz);
    const __m128 Ax = _mm_sub_ps(ax, _mm_mul_ps(ray->sx, az)), Ay = _mm_sub_ps(ay, _mm_mul_ps(ray->sy, az));
    const __m128 Bx = _mm_sub_ps(bx, _mm_mul_ps(ray->sx, bz)), By = _mm_sub_ps(by, _mm_mul_ps(ray->sy, bz));
    const __m128 Cx = _mm_sub_ps(cx, _mm_mul_ps(ray->sx, cz)), Cy = _mm_sub_ps(cy, _mm_mul_ps(ray->sy, cz));
    const __m128 U = _mm_sub_ps(_mm_mul_ps(Cx, By), _mm_mul_ps(Cy, Bx));
    const __m128 V = _mm_sub_ps(_mm_mul_ps(Ax, Cy), _mm_mul_ps(Ay, Cx));
    const __m128 W = _mm_sub_ps(_mm_mul_ps(Bx, Ay), _mm_mul_ps(By, Ax));
    const __m128 zero = _mm_setzero_ps();
    __m128 anyzero = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, zero), _mm_cmpeq_ps(V, zero)), _mm_cmpeq_ps(W, zero));
    if (masked) anyzero = _mm_and_ps(anyzero, keep);
    if (SIDX_UNLIKELY(_mm_movemask_ps(anyzero))) return -1;
    /* No edge function is ±0 now, so "some < 0 and some > 0" is "the sign
     * bits differ": two XORs instead of six compares.  Lanes whose det is
     * 0 or NaN (padding: NaN vertices) drop out through the ordered
     * compare; their t below would fail anyway.  Most blocks a ray reaches
     * are missed on every lane, and they stop here, before T and the
     * division (Embree's kernels defer the division the same way). */
    const __m128 mixed = _mm_castsi128_ps(
        _mm_srai_epi32(_mm_castps_si128(_mm_or_ps(_mm_xor_ps(U, V), _mm_xor_ps(U, W))), 31)); /* sign to all bits */
    const __m128 det = _mm_add_ps(_mm_add_ps(U, V), W);
    __m128 cand = _mm_andnot_ps(mixed, _mm_or_ps(_mm_cmplt_ps(det, zero), _mm_cmpgt_ps(det, zero)));
    if (masked) cand = _mm_and_ps(cand, keep);
    if (!_mm_movemask_ps(cand)) return 0;
    const __m128 T = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(U, _mm_mul_ps(ray->sz, az)), _mm_mul_ps(V, _mm_mul_ps(ray->sz, bz))),
        _mm_mul_ps(W, _mm_mul_ps(ray->sz, cz)));
    const __m128 t = _mm_div_ps(T, det);
    const __m128 ok = _mm_and_ps(cand, _mm_and_ps(_mm_cmpge_ps(t, ray->tmin), _mm_cmplt_ps(t, _mm_set1_ps(best))));
    const unsigned hit_lanes = (unsigned)_mm_movemask_ps(ok);
    if (!hit_lanes) return 0;
    const __m128 t_hit = _mm_or_ps(_mm_and_ps(ok, t), _mm_andnot_ps(ok, _mm_set1_ps(INFINITY))); /* SSE2 blend */
    __m128 t_min = _mm_min_ps(t_hit, _mm_shuffle_ps(t_hit, t_hit, _MM_SHUFFLE(1, 0, 3, 2)));
    t_min = _mm_min_ps(t_min, _mm_shuffle_ps(t_min, t_min, _MM_SHUFFLE(2, 3, 0, 1)));
    *lane_out = (unsigned)__builtin_ctz((unsigned)_mm_movemask_ps(_mm_cmpeq_ps(t_hit, t_min)) & hit_lanes);
    *t_out = _mm_cvtss_f32(t_min);
    if (vw_det_out) {
        _mm_storeu_ps(vw_det_out, V);
        _mm_storeu_ps(vw_det_out + 4, W);
        _mm_storeu_ps(vw_det_out + 8, det);
    }
    return 1;
}

static SIDX_INLINE int tri4_test_axes(const float *row_x, const float *row_y, const float *row_z,
                                      const tri4_ray *ray, float best, float *t_out, unsigned *lane_out,
                                      float *vw_det_out)
{
    return tri4_kernel(row_x, row_y, row_z, ray, best, t_out, lane_out, vw_det_out, 0, _mm_setzero_ps());
}

static SIDX_INLINE int tri4_test(const tri4_block *block, const tri4_ray *ray, float best, float *t_out,
                                      unsigned *lane_out, float *vw_det_out)
{
    const float *v = &block->v[0][0][0]; /* vertex k, axis x, lane l at v[12k + 4x + l] */
    return tri4_test_axes(v + ray->kx4, v + ray->ky4, v + ray->kz4, ray, best, t_out, lane_out, vw_det_out);
}

/* tri4_test on the lanes whose word in keep is all ones only: the same
 * arithmetic, so a lane's t is the unmasked kernel's bit for bit. */
static SIDX_INLINE int tri4_test_lanes(const tri4_block *block, const tri4_ray *ray, __m128 keep, float best,
                                       float *t_out, unsigned *lane_out)
{
    const float *v = &block->v[0][0][0];
    return tri4_kernel(v + ray->kx4, v + ray->ky4, v + ray->kz4, ray, best, t_out, lane_out, NULL, 1, keep);
}

/* A kd leaf's own lanes in the blocks it shares with its neighbours: its
 * count references start in lane offset mod 4 of its first block, so lane
 * l of the k-th block is reference 4k + l − (offset mod 4) of the leaf,
 * its own when that lies in [0, count): one unsigned compare per block
 * (sign bits flipped for SSE2's signed one).  Row r of the table: lane
 * l's index l − r, its sign bit flipped. */
static _Alignas(16) const uint32_t tri4_lane_index[4][4] = {
    {0x80000000u, 0x80000001u, 0x80000002u, 0x80000003u},
    {0x7FFFFFFFu, 0x80000000u, 0x80000001u, 0x80000002u},
    {0x7FFFFFFEu, 0x7FFFFFFFu, 0x80000000u, 0x80000001u},
    {0x7FFFFFFDu, 0x7FFFFFFEu, 0x7FFFFFFFu, 0x80000000u},
};

typedef struct tri4_own_lanes {
    __m128i index, limit;
} tri4_own_lanes;

static SIDX_INLINE tri4_own_lanes tri4_own_lanes_init(uint32_t offset, uint32_t count)
{
    tri4_own_lanes o;
    o.limit = _mm_set1_epi32((int)(count ^ 0x80000000u));
    o.index = _mm_load_si128((const __m128i *)(const void *)tri4_lane_index[offset & 3u]);
    return o;
}

/* The leaf's own references of the next block: tri4_test_lanes on them
 * (*kept: their lanes as bits, for a scalar retest), then on to the next
 * block. */
static SIDX_INLINE int tri4_test_own_lanes(const tri4_block *block, const tri4_ray *ray, tri4_own_lanes *own,
                                           float best, float *t_out, unsigned *lane_out, unsigned *kept)
{
    const __m128 keep = _mm_castsi128_ps(_mm_cmplt_epi32(own->index, own->limit));
    own->index = _mm_add_epi32(own->index, _mm_set1_epi32(4));
    *kept = (unsigned)_mm_movemask_ps(keep);
    return tri4_test_lanes(block, ray, keep, best, t_out, lane_out);
}

#endif
