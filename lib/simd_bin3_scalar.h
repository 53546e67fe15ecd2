/* simd_bin3_scalar.h — the binned BVH builder's one pass over a node's
 * triangles for the bins of all three axes (bvh_build.c, find_binned) in
 * plain C: the reference simd_bin3_sse.h matches bin for bin.
 *
 * Not a normal header: bvh_build.c includes it (or simd_bin3_sse.h) after
 * its builder type, bin_of and BIN_ONE_PASS_MAX; both define
 * bin_three_axes.  A flat axis (extent 0) is binned with scale 0 and
 * ignored by the caller. */

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
    for (int axis = 0; axis < 3; ++axis)
        for (uint32_t k = 0; k < nb; ++k) box[axis][k] = sidx_aabb_empty();
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t id = B->idx[first + i];
        const sidx_vec3 c = B->cent[id];
        const sidx_aabb pb = B->pbox[id];
        for (int axis = 0; axis < 3; ++axis) {
            const uint32_t k = bin_of(sidx_v3_get(c, axis), cmin[axis], scale[axis], nb);
            cnt[axis][k]++;
            box[axis][k] = sidx_aabb_union(box[axis][k], pb);
        }
    }
}
