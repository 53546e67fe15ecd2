/* simd_bin_sse.h — the binning kernels of the parallel binned-SAH build
 * (parallel.c) with SSE2: a reference's box and centroid as 4-lane rows
 * (x, y, z, and the id's lane zeroed), so the three axes go through one
 * set of instructions (Wald 2007; Embree's binner does the same).  Every
 * result is bit for bit simd_bin_scalar.h's, which says how.  SSE2 is
 * baseline on x86-64, so this header is chosen at compile time.
 *
 * Not a normal header: parallel.c includes it (or simd_bin_scalar.h)
 * after its types; both define the same names: bin_range, bounds_range,
 * used_bins, sweep_box / sweep_empty / sweep_add / sweep_area, partition. */

#include <emmintrin.h>

/* ---- binning and bounds, one pass over the references ----------------------------- */

/* Centroid, bin coordinate and clamp for x, y, z at once, then one min and
 * one max per axis to grow the bin.  Bit-identical to bin_of: f = (c −
 * cmin)·scale in the same float operations; _mm_max_ps(f, 0) returns 0 for
 * a NaN f (the second operand), as bin_of's !(f > 0); min(f, nb − 1) then
 * truncation gives nb − 1 for f >= nb − 1, as bin_of's f >= nb test
 * followed by truncation does.  A flat axis (scale 0) puts every triangle
 * in bin 0, where best_split sees a single used bin and no plane, exactly
 * as if it had not been binned. */
static void bin_range(const par_build *build, const binspec *s, uint32_t first, uint32_t count, bins3 *out)
{
    const pref *refs = build->refs + first;
    const __m128 cmin = _mm_setr_ps(s->cmin[0], s->cmin[1], s->cmin[2], 0.0f);
    const __m128 scale = _mm_setr_ps(s->scale[0], s->scale[1], s->scale[2], 0.0f);
    const __m128 top = _mm_set1_ps((float)(s->nb - 1)), half = _mm_set1_ps(0.5f), zero = _mm_setzero_ps();
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)); /* lane 3 holds the id: zeroed */
    for (uint32_t i = 0; i < count; ++i) {
        const __m128 lo = _mm_and_ps(_mm_loadu_ps(refs[i].lo), xyz), hi = _mm_and_ps(_mm_loadu_ps(refs[i].hi), xyz);
        const __m128 c = _mm_mul_ps(_mm_add_ps(lo, hi), half);
        __m128 f = _mm_mul_ps(_mm_sub_ps(c, cmin), scale);
        f = _mm_min_ps(_mm_max_ps(f, zero), top);
        int32_t bin[4];
        _mm_storeu_si128((__m128i *)(void *)bin, _mm_cvttps_epi32(f));
        binbox *bin_x = &out->box[0][bin[0]], *bin_y = &out->box[1][bin[1]], *bin_z = &out->box[2][bin[2]];
        out->count[0][bin[0]]++;
        out->count[1][bin[1]]++;
        out->count[2][bin[2]]++;
        _mm_storeu_ps(bin_x->lo, _mm_min_ps(_mm_loadu_ps(bin_x->lo), lo));
        _mm_storeu_ps(bin_x->hi, _mm_max_ps(_mm_loadu_ps(bin_x->hi), hi));
        _mm_storeu_ps(bin_y->lo, _mm_min_ps(_mm_loadu_ps(bin_y->lo), lo));
        _mm_storeu_ps(bin_y->hi, _mm_max_ps(_mm_loadu_ps(bin_y->hi), hi));
        _mm_storeu_ps(bin_z->lo, _mm_min_ps(_mm_loadu_ps(bin_z->lo), lo));
        _mm_storeu_ps(bin_z->hi, _mm_max_ps(_mm_loadu_ps(bin_z->hi), hi));
    }
}

/* sidx_aabb_union / sidx_aabb_grow lane by lane (same operand order, same
 * results). */
static void bounds_range(const par_build *build, uint32_t first, uint32_t count, sidx_aabb *bb, sidx_aabb *cb)
{
    const pref *refs = build->refs + first;
    __m128 blo = _mm_set1_ps(INFINITY), bhi = _mm_set1_ps(-INFINITY), clo = blo, chi = bhi;
    const __m128 half = _mm_set1_ps(0.5f);
    /* lane 3 holds the id: zeroed, or as a float it would be a denormal (slow) */
    const __m128 xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    for (uint32_t i = 0; i < count; ++i) {
        const __m128 lo = _mm_and_ps(_mm_loadu_ps(refs[i].lo), xyz), hi = _mm_and_ps(_mm_loadu_ps(refs[i].hi), xyz);
        const __m128 c = _mm_mul_ps(_mm_add_ps(lo, hi), half);
        blo = _mm_min_ps(blo, lo);
        bhi = _mm_max_ps(bhi, hi);
        clo = _mm_min_ps(clo, c);
        chi = _mm_max_ps(chi, c);
    }
    float v[4][4];
    _mm_storeu_ps(v[0], blo);
    _mm_storeu_ps(v[1], bhi);
    _mm_storeu_ps(v[2], clo);
    _mm_storeu_ps(v[3], chi);
    *bb = (sidx_aabb){{v[0][0], v[0][1], v[0][2]}, {v[1][0], v[1][1], v[1][2]}};
    *cb = (sidx_aabb){{v[2][0], v[2][1], v[2][2]}, {v[3][0], v[3][1], v[3][2]}};
}

/* ---- the SAH sweep over a node's bins --------------------------------------------- */

/* The non-empty bins of one axis into used[] (a scan over all 32 bins
 * of every small node cost a large share of the build); returns how
 * many.  Each bin index is written and the count advanced by 0 or 1, with
 * no branch: SSE compares of 4 counts followed by a loop over the set
 * bits were slower, their exits mispredicted (docs/performance.md,
 * "Parallel build and trace"). */
static inline uint32_t used_bins(const uint32_t *cnt, uint32_t nb, uint32_t *used)
{
    uint32_t k = 0;
    for (uint32_t p = 0; p < nb; ++p) {
        used[k] = p; /* kept only if the bin is non-empty: no branch to mispredict */
        k += cnt[p] != 0;
    }
    return k;
}

/* sidx_aabb_area of a NON-EMPTY box held as two 4-lane rows (x, y, z, 0):
 * e = hi − lo, then 2·((e.x·e.y + e.y·e.z) + e.z·e.x) — the products in
 * one multiply, the sums in the scalar expression's order, so the result
 * is bit for bit sidx_aabb_area's. */
static inline float area_sse(__m128 lo, __m128 hi)
{
    const __m128 e = _mm_sub_ps(hi, lo);
    const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1))); /* x·y, y·z, z·x, 0 */
    __m128 sum = _mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 3, 3, 1)));
    sum = _mm_add_ss(sum, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 3, 3, 2)));
    return 2.0f * _mm_cvtss_f32(sum);
}

/* The box a sweep grows, in one register pair: one min and one max per bin
 * instead of six scalar selects, and the area without the empty-box test
 * (a union of non-empty bins is never empty, so the test always fails
 * there).  _mm_min_ps(acc, b) is sidx_v3_min(acc, b) lane by lane. */
typedef struct sweep_box {
    __m128 lo, hi;
} sweep_box;

static inline sweep_box sweep_empty(void)
{
    const sweep_box e = {_mm_set1_ps(INFINITY), _mm_set1_ps(-INFINITY)};
    return e;
}

static inline sweep_box sweep_add(sweep_box acc, const binbox *b)
{
    acc.lo = _mm_min_ps(acc.lo, _mm_loadu_ps(b->lo));
    acc.hi = _mm_max_ps(acc.hi, _mm_loadu_ps(b->hi));
    return acc;
}

static inline float sweep_area(sweep_box acc) { return area_sse(acc.lo, acc.hi); }

/* ---- partition ------------------------------------------------------------------- */

/* bvh_build.c's two-pointer loop, gathering the children's boxes on the
 * way; why the right side folds with its operands swapped:
 * simd_bin_scalar.h, partition.  It keeps its branch on the side: a
 * branch-free version was slower.  Rejected alternatives:
 * docs/performance.md, Binary BVH. */
static uint32_t partition(const par_build *build, const binspec *s, uint32_t first, uint32_t count, int axis,
                          uint32_t plane, nodebox *left, nodebox *right)
{
    pref *refs = build->refs;
    uint32_t i = first, j = first + count;
    const __m128 half = _mm_set1_ps(0.5f), xyz = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    __m128 lblo = _mm_set1_ps(INFINITY), lbhi = _mm_set1_ps(-INFINITY), lclo = lblo, lchi = lbhi;
    __m128 rblo = lblo, rbhi = lbhi, rclo = lblo, rchi = lbhi;
    /* the side: bin_range's bin of the centroid, bit for bit bin_of, below
     * the plane, read from lane axis (no scalar reload, no clamp branches) */
    const __m128 cmin = _mm_setr_ps(s->cmin[0], s->cmin[1], s->cmin[2], 0.0f);
    const __m128 scale = _mm_setr_ps(s->scale[0], s->scale[1], s->scale[2], 0.0f);
    const __m128 top = _mm_set1_ps((float)(s->nb - 1)), zero = _mm_setzero_ps();
    const __m128i planev = _mm_set1_epi32((int32_t)plane);
    const int lane = 1 << axis;
    while (i < j) {
        const __m128 lo = _mm_and_ps(_mm_loadu_ps(refs[i].lo), xyz), hi = _mm_and_ps(_mm_loadu_ps(refs[i].hi), xyz);
        const __m128 c = _mm_mul_ps(_mm_add_ps(lo, hi), half);
        const __m128 f = _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, cmin), scale), zero), top);
        if (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmplt_epi32(_mm_cvttps_epi32(f), planev))) & lane) {
            lblo = _mm_min_ps(lblo, lo);
            lbhi = _mm_max_ps(lbhi, hi);
            lclo = _mm_min_ps(lclo, c);
            lchi = _mm_max_ps(lchi, c);
            ++i;
        } else {
            rblo = _mm_min_ps(lo, rblo);
            rbhi = _mm_max_ps(hi, rbhi);
            rclo = _mm_min_ps(c, rclo);
            rchi = _mm_max_ps(c, rchi);
            const pref t = refs[i];
            refs[i] = refs[--j];
            refs[j] = t;
        }
    }
    float v[8][4];
    _mm_storeu_ps(v[0], lblo);
    _mm_storeu_ps(v[1], lbhi);
    _mm_storeu_ps(v[2], lclo);
    _mm_storeu_ps(v[3], lchi);
    _mm_storeu_ps(v[4], rblo);
    _mm_storeu_ps(v[5], rbhi);
    _mm_storeu_ps(v[6], rclo);
    _mm_storeu_ps(v[7], rchi);
    left->bb = (sidx_aabb){{v[0][0], v[0][1], v[0][2]}, {v[1][0], v[1][1], v[1][2]}};
    left->cb = (sidx_aabb){{v[2][0], v[2][1], v[2][2]}, {v[3][0], v[3][1], v[3][2]}};
    right->bb = (sidx_aabb){{v[4][0], v[4][1], v[4][2]}, {v[5][0], v[5][1], v[5][2]}};
    right->cb = (sidx_aabb){{v[6][0], v[6][1], v[6][2]}, {v[7][0], v[7][1], v[7][2]}};
    return i - first;
}
