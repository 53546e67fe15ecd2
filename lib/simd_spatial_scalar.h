/* simd_spatial_scalar.h — the spatial-split build's binning
 * (bvh_spatial.c) in plain C, the reference of simd_spatial_sse.h: the
 * centroid bounds, the object bins (left to bvh_spatial.c's loop), and a
 * reference's spatial bins with the bins' `other` boxes grown in place.
 *
 * Not a normal header: bvh_spatial.c includes it (or simd_spatial_sse.h)
 * after its types sref and sbin and sbin_of. */

static SIDX_INLINE sidx_aabb sb_centroid_bounds(const sref *refs, uint32_t n)
{
    sidx_aabb cb = sidx_aabb_empty();
    for (uint32_t i = 0; i < n; ++i) cb = sidx_aabb_grow(cb, sidx_aabb_centroid(refs[i].box));
    return cb;
}

/* Always 0: bvh_spatial.c's object_bin loop is the reference. */
static SIDX_INLINE int sb_object_bin_rows(const sref *refs, uint32_t i0, uint32_t i1, const float *lo,
                                          const float *scale, const int *use, sbin (*bins)[SB_BINS])
{
    (void)refs, (void)i0, (void)i1, (void)lo, (void)scale, (void)use, (void)bins;
    return 0;
}

typedef struct sb_rows {
    const float *lo, *scale;
    uint32_t nb;
} sb_rows;
typedef struct sb_box {
    sidx_aabb box;
} sb_box;

static SIDX_INLINE void sb_rows_init(sb_rows *R, const float *lo, const float *scale, uint32_t nb)
{
    R->lo = lo;
    R->scale = scale;
    R->nb = nb;
}

/* The bins of the reference's min and max on the three axes. */
static SIDX_INLINE sb_box sb_ref_bins(const sb_rows *R, const sref *ref, int32_t first[4], int32_t last[4])
{
    sb_box x;
    x.box = ref->box;
    for (int k = 0; k < 3; ++k) {
        first[k] = (int32_t)sbin_of(sidx_v3_get(x.box.min, k), R->lo[k], R->scale[k], R->nb);
        last[k] = (int32_t)sbin_of(sidx_v3_get(x.box.max, k), R->lo[k], R->scale[k], R->nb);
    }
    return x;
}

/* Bin b of axis k grows by the box, in place. */
static SIDX_INLINE void sb_rows_grow(sb_rows *R, int k, uint32_t b, const sb_box *x, sidx_aabb *other)
{
    (void)R, (void)k, (void)b;
    *other = sidx_aabb_union(*other, x->box);
}

/* Nothing to merge: sb_rows_grow grew the bins in place. */
static SIDX_INLINE void sb_rows_merge(const sb_rows *R, int k, uint32_t b, sidx_aabb *other)
{
    (void)R, (void)k, (void)b, (void)other;
}
