/* simd_stream_avx2.h — the stream entry's preparation of rays, 8 at a
 * time with AVX2: the same values as simd_stream_scalar.h (integer
 * offsets, one IEEE multiply per far factor, the same clamps).
 *
 * Not a normal header: bvh_stream.c includes it once, on x86, and calls
 * it when the CPU has AVX2.  The rays are an array of structures, so each
 * group of 8 gathers its fields with scalar loads; what runs 8 wide is the
 * arithmetic: the sign tests and offset choices, the far factors, and
 * for the sort keys the quantisation and the Morton interleave. */
#include <immintrin.h>

#define STREAM_AVX2 __attribute__((target("avx2")))

STREAM_AVX2 static inline __m256i stream_sign_words_avx2(const sidx_ray *rays, const uint32_t *idx)
{
    uint32_t w[8];
    for (int l = 0; l < 8; ++l) memcpy(&w[l], rays[idx[l]].sign, sizeof w[l]); /* sign[0..2] and kx */
    return _mm256_loadu_si256((const __m256i *)(const void *)w);
}

STREAM_AVX2 static inline __m256 stream_gather_avx2(const sidx_ray *rays, const uint32_t *idx, size_t field, int k)
{
    float v[8];
    for (int l = 0; l < 8; ++l) v[l] = ((const float *)(const void *)((const char *)&rays[idx[l]] + field))[k];
    return _mm256_loadu_ps(v);
}

STREAM_AVX2 static void stream_prep_avx2(const sidx_ray *rays, const uint32_t *idx, uint32_t count, const uint32_t lo[3],
                                         const uint32_t hi[3], float scale, bvh_stream_prep *p)
{
    const __m256 s = _mm256_set1_ps(scale);
    const __m256i byte = _mm256_set1_epi32(0xFF), zero = _mm256_setzero_si256();
    uint32_t i = 0;
    for (; i + 8 <= count; i += 8) {
        const __m256i sw = stream_sign_words_avx2(rays, idx + i);
        for (int k = 0; k < 3; ++k) {
            /* all ones where sign[k] == 0: the direction is not negative */
            const __m256i pos = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_srli_epi32(sw, 8 * k), byte), zero);
            const __m256i vlo = _mm256_set1_epi32((int)lo[k]), vhi = _mm256_set1_epi32((int)hi[k]);
            _mm256_storeu_si256((__m256i *)(void *)&p->near_off[k][i], _mm256_blendv_epi8(vhi, vlo, pos));
            _mm256_storeu_si256((__m256i *)(void *)&p->far_off[k][i], _mm256_blendv_epi8(vlo, vhi, pos));
            const __m256 inv = stream_gather_avx2(rays, idx + i, offsetof(sidx_ray, inv_dir), k);
            _mm256_storeu_ps(&p->far[k][i], _mm256_mul_ps(inv, s));
        }
    }
    /* the tail, at most 7 rays, in place */
    for (; i < count; ++i) {
        const sidx_ray *r = &rays[idx[i]];
        const float *inv = sidx_v3_array(&r->inv_dir);
        for (int k = 0; k < 3; ++k) {
            p->near_off[k][i] = r->sign[k] ? hi[k] : lo[k];
            p->far_off[k][i] = r->sign[k] ? lo[k] : hi[k];
            p->far[k][i] = inv[k] * scale;
        }
    }
}

STREAM_AVX2 static inline __m256i stream_spread3_avx2(__m256i x)
{
    x = _mm256_and_si256(x, _mm256_set1_epi32(0x3FF));
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi32(x, 16)), _mm256_set1_epi32(0x030000FF));
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi32(x, 8)), _mm256_set1_epi32(0x0300F00F));
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi32(x, 4)), _mm256_set1_epi32(0x030C30C3));
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi32(x, 2)), _mm256_set1_epi32(0x09249249));
    return x;
}

/* MAXPS returns its second operand when either is NaN: the value goes
 * first, so a NaN coordinate quantises to 0 as in stream_quant. */
STREAM_AVX2 static inline __m256i stream_quant_avx2(__m256 o, float olo, float oscale)
{
    __m256 f = _mm256_mul_ps(_mm256_sub_ps(o, _mm256_set1_ps(olo)), _mm256_set1_ps(oscale));
    f = _mm256_max_ps(f, _mm256_setzero_ps());
    f = _mm256_min_ps(f, _mm256_set1_ps(511.0f));
    return _mm256_cvttps_epi32(f);
}

STREAM_AVX2 static void stream_keys_avx2(const sidx_ray *rays, size_t n, const float olo[3], const float oscale[3],
                                         uint32_t *key)
{
    static const uint32_t iota[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    const __m256i byte = _mm256_set1_epi32(0xFF), zero = _mm256_setzero_si256();
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        const sidx_ray *g = rays + i;
        const __m256i sw = stream_sign_words_avx2(g, iota);
        __m256i oct = zero;
        for (int k = 0; k < 3; ++k) {
            const __m256i neg = _mm256_andnot_si256(
                _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_srli_epi32(sw, 8 * k), byte), zero), _mm256_set1_epi32(1 << k));
            oct = _mm256_or_si256(oct, neg);
        }
        const __m256i mx = stream_spread3_avx2(stream_quant_avx2(stream_gather_avx2(g, iota, offsetof(sidx_ray, org), 0), olo[0], oscale[0]));
        const __m256i my = stream_spread3_avx2(stream_quant_avx2(stream_gather_avx2(g, iota, offsetof(sidx_ray, org), 1), olo[1], oscale[1]));
        const __m256i mz = stream_spread3_avx2(stream_quant_avx2(stream_gather_avx2(g, iota, offsetof(sidx_ray, org), 2), olo[2], oscale[2]));
        __m256i k = _mm256_or_si256(_mm256_slli_epi32(oct, 27), mx);
        k = _mm256_or_si256(k, _mm256_or_si256(_mm256_slli_epi32(my, 1), _mm256_slli_epi32(mz, 2)));
        _mm256_storeu_si256((__m256i *)(void *)&key[i], k);
    }
    if (i < n) stream_keys_scalar(rays + i, n - i, olo, oscale, key + i);
}
#undef STREAM_AVX2
