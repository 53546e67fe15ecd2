/* simd_spatial_sse.h — the spatial-split build's binning (bvh_spatial.c)
 * with SSE2: a reference's box as two 4-lane rows (x, y, z, and a lane 3
 * zeroed), the three axes' centroid, bin numbers and growth in one set of
 * instructions (as simd_bin_sse.h does for the parallel build).  Bit for
 * bit the reference's results (simd_spatial_scalar.h): the centroid is
 * (min + max)·0.5 and the bin coordinate (c − lo)·scale in the same float
 * operations; max(f, 0) gives 0 for a NaN f and min(f, nb − 1) then
 * truncation gives sbin_of's clamp; the SSE min of a bin and a box is
 * sidx_aabb_union's `bin < box ? bin : box`.
 *
 * Not a normal header: bvh_spatial.c includes it (or
 * simd_spatial_scalar.h) after its types sref and sbin and sbin_of. */
#include <emmintrin.h>

/* Below this many references, moving the bins in and out of rows costs
 * more than it saves: the scalar loop bins them. */
#define SB_SSE_MIN 24u

/* lane 3 of a box row is max.x, or the id: zeroed */
static SIDX_INLINE __m128 sb_row_xyz(void) { return _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)); }

/* The bounds of the references' box centroids (sidx_aabb_grow of each
 * centroid, as rows: the same operations, the same bits). */
static SIDX_INLINE sidx_aabb sb_centroid_bounds(const sref *refs, uint32_t n)
{
    const __m128 xyz = sb_row_xyz(), half = _mm_set1_ps(0.5f);
    __m128 clo = _mm_set1_ps(INFINITY), chi = _mm_set1_ps(-INFINITY);
    for (uint32_t i = 0; i < n; ++i) {
        const __m128 mn = _mm_and_ps(_mm_loadu_ps(&refs[i].box.min.x), xyz);
        const __m128 mx = _mm_and_ps(_mm_loadu_ps(&refs[i].box.max.x), xyz);
        const __m128 c = _mm_mul_ps(_mm_add_ps(mn, mx), half);
        clo = _mm_min_ps(clo, c);
        chi = _mm_max_ps(chi, c);
    }
    float l[4], h[4];
    _mm_storeu_ps(l, clo);
    _mm_storeu_ps(h, chi);
    return (sidx_aabb){{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
}

/* The object bins of references [i0, i1) on the axes with use[k].  The
 * bins come in cleared (object_clear), so only those it fills go back. */
static void sb_object_bin_sse(const sref *refs, uint32_t i0, uint32_t i1, const float *lo, const float *scale,
                              const int *use, sbin (*bins)[SB_BINS])
{
    __m128 blo[3][SB_BINS], bhi[3][SB_BINS];
    uint32_t cnt[3][SB_BINS] = {{0}};
    const __m128 inf = _mm_set1_ps(INFINITY), ninf = _mm_set1_ps(-INFINITY);
    for (int k = 0; k < 3; ++k)
        for (uint32_t b = 0; b < SB_BINS; ++b) {
            blo[k][b] = inf;
            bhi[k][b] = ninf;
        }
    const __m128 vlo = _mm_setr_ps(lo[0], lo[1], lo[2], 0.0f), vscale = _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f);
    const __m128 top = _mm_set1_ps((float)(SB_BINS - 1u)), half = _mm_set1_ps(0.5f), zero = _mm_setzero_ps();
    const __m128 xyz = sb_row_xyz();
    for (uint32_t i = i0; i < i1; ++i) {
        const __m128 mn = _mm_and_ps(_mm_loadu_ps(&refs[i].box.min.x), xyz);
        const __m128 mx = _mm_and_ps(_mm_loadu_ps(&refs[i].box.max.x), xyz);
        __m128 f = _mm_mul_ps(_mm_sub_ps(_mm_mul_ps(_mm_add_ps(mn, mx), half), vlo), vscale);
        f = _mm_min_ps(_mm_max_ps(f, zero), top);
        int32_t bin[4];
        _mm_storeu_si128((__m128i *)(void *)bin, _mm_cvttps_epi32(f));
        for (int k = 0; k < 3; ++k) {
            blo[k][bin[k]] = _mm_min_ps(blo[k][bin[k]], mn);
            bhi[k][bin[k]] = _mm_max_ps(bhi[k][bin[k]], mx);
            cnt[k][bin[k]]++;
        }
    }
    for (int k = 0; k < 3; ++k) {
        if (!use[k]) continue;
        for (uint32_t b = 0; b < SB_BINS; ++b) {
            if (!cnt[k][b]) continue;
            float l[4], h[4];
            _mm_storeu_ps(l, blo[k][b]);
            _mm_storeu_ps(h, bhi[k][b]);
            bins[k][b].box = (sidx_aabb){{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
            bins[k][b].enter += cnt[k][b];
            bins[k][b].exit += cnt[k][b];
        }
    }
}

/* 1 when the object bins of [i0, i1) were filled here; 0 leaves them to
 * the scalar loop (few references). */
static SIDX_INLINE int sb_object_bin_rows(const sref *refs, uint32_t i0, uint32_t i1, const float *lo,
                                          const float *scale, const int *use, sbin (*bins)[SB_BINS])
{
    if (i1 - i0 < SB_SSE_MIN) return 0;
    sb_object_bin_sse(refs, i0, i1, lo, scale, use, bins);
    return 1;
}

/* The spatial bins' `other` boxes grown as rows held here, one min and
 * one max per part (sidx_aabb_union's operand order: the same bits),
 * merged into the bins at the end (sb_rows_merge). */
typedef struct sb_rows {
    __m128 lo[3][SB_BINS], hi[3][SB_BINS];
    __m128 xyz, vlo, vscale, top, zero;
} sb_rows;
typedef struct sb_box {
    __m128 mn, mx;
} sb_box;

static SIDX_INLINE void sb_rows_init(sb_rows *R, const float *lo, const float *scale, uint32_t nb)
{
    for (int k = 0; k < 3; ++k)
        for (uint32_t b = 0; b < nb; ++b) {
            R->lo[k][b] = _mm_set1_ps(INFINITY);
            R->hi[k][b] = _mm_set1_ps(-INFINITY);
        }
    R->xyz = sb_row_xyz();
    R->vlo = _mm_setr_ps(lo[0], lo[1], lo[2], 0.0f);
    R->vscale = _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f);
    R->top = _mm_set1_ps((float)(nb - 1u));
    R->zero = _mm_setzero_ps();
}

/* A reference's box as rows, and the bins of its min and max on the
 * three axes (first, last), clamped as sbin_of does. */
static SIDX_INLINE sb_box sb_ref_bins(const sb_rows *R, const sref *ref, int32_t first[4], int32_t last[4])
{
    sb_box x;
    x.mn = _mm_and_ps(_mm_loadu_ps(&ref->box.min.x), R->xyz);
    x.mx = _mm_and_ps(_mm_loadu_ps(&ref->box.max.x), R->xyz);
    const __m128 f0 = _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(x.mn, R->vlo), R->vscale), R->zero), R->top);
    const __m128 f1 = _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(x.mx, R->vlo), R->vscale), R->zero), R->top);
    _mm_storeu_si128((__m128i *)(void *)first, _mm_cvttps_epi32(f0));
    _mm_storeu_si128((__m128i *)(void *)last, _mm_cvttps_epi32(f1));
    return x;
}

/* Bin b of axis k grows by the box (`other`, the bin's box, is grown
 * later, by sb_rows_merge). */
static SIDX_INLINE void sb_rows_grow(sb_rows *R, int k, uint32_t b, const sb_box *x, sidx_aabb *other)
{
    (void)other;
    R->lo[k][b] = _mm_min_ps(R->lo[k][b], x->mn);
    R->hi[k][b] = _mm_max_ps(R->hi[k][b], x->mx);
}

static SIDX_INLINE void sb_rows_merge(const sb_rows *R, int k, uint32_t b, sidx_aabb *other)
{
    float l[4], h[4];
    _mm_storeu_ps(l, R->lo[k][b]);
    _mm_storeu_ps(h, R->hi[k][b]);
    *other = sidx_aabb_union(*other, (sidx_aabb){{l[0], l[1], l[2]}, {h[0], h[1], h[2]}});
}
