/* simd_wide_tri4.h — the leaf kernel of the SSE4.1, AVX2 and AVX-512
 * walks: the SSE2 4-triangle watertight test of simd_tri4_sse.h on one
 * block (so all three copies run the same instructions on triangles), and
 * the row pointers it steps through a leaf's blocks.  simd_wide_scalar.h
 * has the reference (no kernel: every block lane by lane).
 *
 * Not a normal header: included at the end of simd_wide_sse.h,
 * simd_wide_avx2.h and simd_wide_avx512.h, with their ray_consts_. */

#define WALK_TRI4 1

/* The block's rows on the ray's permuted axes, stepped a block at a time
 * by the leaf: three pointers instead of nine hoisted offsets. */
WINL void WFN(block_rows_)(const WFN(ray_consts_) * consts, const wide_tri4 *block, const float **row_x,
                           const float **row_y, const float **row_z)
{
    *row_x = &block->v[0][0][0] + consts->tri.kx4;
    *row_y = &block->v[0][0][0] + consts->tri.ky4;
    *row_z = &block->v[0][0][0] + consts->tri.kz4;
}

/* 1 with the smallest t in [tmin, best) (lowest lane on ties), 0 for no
 * hit, -1 when the block must take the scalar test (simd_tri4_sse.h). */
WINL int WFN(tri4_)(const float *row_x, const float *row_y, const float *row_z, const WFN(ray_consts_) * consts,
                    float best, float *t_out, unsigned *lane_out, float *vw_det_out)
{
    return wide_tri4_test_axes(row_x, row_y, row_z, &consts->tri, best, t_out, lane_out, vw_det_out);
}
