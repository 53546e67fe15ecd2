/* simd_bin3_sse.h — the binned BVH builder's one pass over a node's
 * triangles for the bins of all three axes (bvh_build.c, find_binned)
 * with SSE2: the bin coordinates of x, y, z in one set of instructions and
 * each bin grown by one min and one max, as parallel.c's simd_bin_sse.h
 * does for packed references.  The coordinate is bin_of's bit for bit:
 * f = (c - cmin) * scale in the same float operations, _mm_max_ps(f, 0)
 * gives 0 for a NaN or negative f, min(f, nb - 1) then truncation gives
 * nb - 1 from nb - 1 up, as bin_of does; the bins' boxes are the same
 * unions.  So the bins equal simd_bin3_scalar.h's.  SSE2 is baseline on
 * x86-64, so this header is chosen at compile time.
 *
 * Not a normal header: bvh_build.c includes it (or simd_bin3_scalar.h)
 * after its builder type, bin_of and BIN_ONE_PASS_MAX; both define
 * bin_three_axes.  A flat axis (extent 0) is binned with scale 0 and
 * ignored by the caller. */

#include <emmintrin.h>

static void bin_three_axes(builder *B, uint32_t first, uint32_t count, sidx_aabb cb,
                           sidx_aabb box[3][BIN_ONE_PASS_MAX], uint32_t cnt[3][BIN_ONE_PASS_MAX])
{
    const uint32_t nb = B->bins;
    float cmin[3] = {0.0f, 0.0f, 0.0f}, scale[3] = {0.0f, 0.0f, 0.0f};
    for (int axis = 0; axis < 3; ++axis) {
        cmin[axis] = sidx_v3_get(cb.min, axis);
        const float ext = sidx_v3_get(cb.max, axis) - cmin[axis];
        scale[axis] = ext > 0.0f ? (float)nb / ext : 0.0f;
        for (uint32_t k = 0; k < nb; ++k) cnt[axis][k] = 0;
    }
    float lo4[3][BIN_ONE_PASS_MAX][4], hi4[3][BIN_ONE_PASS_MAX][4];
    for (int axis = 0; axis < 3; ++axis)
        for (uint32_t k = 0; k < nb; ++k) {
            _mm_storeu_ps(lo4[axis][k], _mm_set1_ps(INFINITY));
            _mm_storeu_ps(hi4[axis][k], _mm_set1_ps(-INFINITY));
        }
    const __m128 vmin = _mm_setr_ps(cmin[0], cmin[1], cmin[2], 0.0f);
    const __m128 vscale = _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f);
    const __m128 top = _mm_set1_ps((float)(nb - 1)), zero = _mm_setzero_ps();
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t id = B->idx[first + i];
        const sidx_vec3 c = B->cent[id];
        const float *pb = &B->pbox[id].min.x; /* min x, y, z, max x, y, z */
        const __m128 lo = _mm_loadu_ps(pb);   /* lane 3 (max.x) is never stored back: see below */
        const __m128 hi = _mm_shuffle_ps(_mm_loadu_ps(pb + 2), _mm_loadu_ps(pb + 2), _MM_SHUFFLE(3, 3, 2, 1));
        __m128 f = _mm_mul_ps(_mm_sub_ps(_mm_setr_ps(c.x, c.y, c.z, 0.0f), vmin), vscale);
        f = _mm_min_ps(_mm_max_ps(f, zero), top);
        int32_t k[4];
        _mm_storeu_si128((__m128i *)(void *)k, _mm_cvttps_epi32(f));
        for (int axis = 0; axis < 3; ++axis) {
            cnt[axis][k[axis]]++;
            _mm_storeu_ps(lo4[axis][k[axis]], _mm_min_ps(_mm_loadu_ps(lo4[axis][k[axis]]), lo));
            _mm_storeu_ps(hi4[axis][k[axis]], _mm_max_ps(_mm_loadu_ps(hi4[axis][k[axis]]), hi));
        }
    }
    /* lanes 0-2 only: lane 3 of lo carried max.x, of hi max.z again */
    for (int axis = 0; axis < 3; ++axis)
        for (uint32_t k = 0; k < nb; ++k)
            box[axis][k] = (sidx_aabb){{lo4[axis][k][0], lo4[axis][k][1], lo4[axis][k][2]},
                                       {hi4[axis][k][0], hi4[axis][k][1], hi4[axis][k][2]}};
}
