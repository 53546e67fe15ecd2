/* simd_stream_avx2.h — the stream entry's sort keys, 8 rays at a time
 * with AVX2: the same values as simd_stream_scalar.h (the same clamps,
 * the same truncation).
 *
 * Not a normal header: bvh_stream.c includes it once, on x86, and calls
 * it when the CPU has AVX2.  The rays are an array of structures, so each
 * group of 8 loads its fields lane by lane; what runs 8 wide is the
 * arithmetic: the sign tests, the quantisation, the Morton interleave. */
#include <immintrin.h>

#define STREAM_AVX2 __attribute__((target("avx2")))

/* Each ray's field loaded straight into its lane (no store and reload of
 * a temporary array, which stalls on store forwarding). */
STREAM_AVX2 static inline uint32_t stream_sign_word(const sidx_ray *r)
{
    uint32_t w;
    memcpy(&w, r->sign, sizeof w); /* sign[0..2] and kx */
    return w;
}
STREAM_AVX2 static inline __m256i stream_sign_words_avx2(const sidx_ray *rays, const uint32_t *idx)
{
    return _mm256_setr_epi32((int)stream_sign_word(&rays[idx[0]]), (int)stream_sign_word(&rays[idx[1]]),
                             (int)stream_sign_word(&rays[idx[2]]), (int)stream_sign_word(&rays[idx[3]]),
                             (int)stream_sign_word(&rays[idx[4]]), (int)stream_sign_word(&rays[idx[5]]),
                             (int)stream_sign_word(&rays[idx[6]]), (int)stream_sign_word(&rays[idx[7]]));
}

STREAM_AVX2 static inline __m256 stream_gather_avx2(const sidx_ray *rays, const uint32_t *idx, size_t field, int k)
{
#define STREAM_F(l) (((const float *)(const void *)((const char *)&rays[idx[l]] + field))[k])
    return _mm256_setr_ps(STREAM_F(0), STREAM_F(1), STREAM_F(2), STREAM_F(3), STREAM_F(4), STREAM_F(5), STREAM_F(6),
                          STREAM_F(7));
#undef STREAM_F
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
