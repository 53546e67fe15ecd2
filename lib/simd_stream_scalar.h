/* simd_stream_scalar.h — the stream entry's sort keys in plain C: the
 * portable reference simd_stream_avx2.h matches value for value.
 *
 * Not a normal header: bvh_stream.c includes it once.  It defines
 * stream_keys_scalar, the sort key of each ray for reordering: its
 * direction octant (bit k: sign[k] != 0, as the walks read it) above a
 * Morton code of its origin quantised to 9 bits per axis over
 * [olo, olo + 511 / oscale]. */

/* 9 bits spread to every third bit (bit b to bit 3b). */
static inline uint32_t stream_spread3(uint32_t x)
{
    x &= 0x3FFu;
    x = (x | (x << 16)) & 0x030000FFu;
    x = (x | (x << 8)) & 0x0300F00Fu;
    x = (x | (x << 4)) & 0x030C30C3u;
    x = (x | (x << 2)) & 0x09249249u;
    return x;
}

/* Quantised coordinate: NaN and below-range to 0, above to 511 (clamped
 * in float first: converting NaN or a huge float to an integer is
 * undefined). */
static inline uint32_t stream_quant(float o, float olo, float oscale)
{
    float f = (o - olo) * oscale;
    f = f > 0.0f ? f : 0.0f;
    f = f < 511.0f ? f : 511.0f;
    return (uint32_t)f;
}

static inline void stream_keys_scalar(const sidx_ray *rays, size_t n, const float olo[3], const float oscale[3],
                                      uint32_t *key)
{
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray *r = &rays[i];
        const uint32_t oct = (r->sign[0] ? 1u : 0u) | (r->sign[1] ? 2u : 0u) | (r->sign[2] ? 4u : 0u);
        const uint32_t mx = stream_spread3(stream_quant(r->org.x, olo[0], oscale[0]));
        const uint32_t my = stream_spread3(stream_quant(r->org.y, olo[1], oscale[1]));
        const uint32_t mz = stream_spread3(stream_quant(r->org.z, olo[2], oscale[2]));
        key[i] = oct << 27 | mx | my << 1 | mz << 2;
    }
}
