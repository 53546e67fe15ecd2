/* tri4.h — a block of four triangles in structure-of-arrays form, the
 * leaf storage shared by the wide BVHs ("bvh4", "bvh8", bvh_wide_internal.h,
 * which keeps its own wide_* names for them)
 * and the kd-tree (kdtree_internal.h).
 *
 * The layout is Embree's Triangle4: the x, y and z of each corner of the
 * four triangles side by side, so one SSE pass runs the watertight test on
 * all four (tri4_test, simd_tri4_sse.h, included below where SSE2 is
 * there).  Each lane keeps its triangle's original index in prim[]; the
 * wide BVH marks a leaf's last block with WIDE_LAST_BLOCK in prim[0].
 * Unused lanes have NaN vertices (every comparison on them is false, so
 * they never hit and never trigger the double-precision fallback) and
 * prim = TRI4_PAD_PRIM.
 *
 * The lane helpers below read one lane as a plain triangle: its corners,
 * its normal, the scalar reference test on it (bit-identical t, u, v to
 * the brute force) and the u, v of a final hit. */
#ifndef SIDX_TRI4_H
#define SIDX_TRI4_H

#include "sidx_internal.h"

#define WIDE_LAST_BLOCK 0x80000000u
#define WIDE_PRIM_MASK 0x7FFFFFFFu
#define TRI4_PAD_PRIM 0x7FFFFFFFu

typedef struct tri4_block {
    float v[3][3][4];  /* [vertex][axis][lane] */
    uint32_t prim[4];  /* original triangle index (WIDE_PRIM_MASK bits); prim[0] also carries WIDE_LAST_BLOCK */
} tri4_block;
_Static_assert(sizeof(tri4_block) == 160, "tri4_block is 9 float4 + 4 ids");

/* Lane l of a block: the triangle with corners p[0], p[1], p[2] and
 * original index prim, or padding (NaN corners, TRI4_PAD_PRIM) when p is
 * NULL.  Both block layouts (bvh4/bvh8 leaves, kd-tree references) are
 * filled by it. */
static inline void tri4_set_lane(tri4_block *block, unsigned lane, const sidx_vec3 *p, uint32_t prim)
{
    for (int v = 0; v < 3; ++v) {
        const sidx_vec3 c = p ? p[v] : sidx_v3(NAN, NAN, NAN);
        block->v[v][0][lane] = c.x;
        block->v[v][1][lane] = c.y;
        block->v[v][2][lane] = c.z;
    }
    block->prim[lane] = p ? prim : TRI4_PAD_PRIM;
}

/* Corner k (0, 1, 2) of lane lane of a block. */
static SIDX_INLINE sidx_vec3 tri4_lane_vertex(const tri4_block *block, int k, unsigned lane)
{
    return (sidx_vec3){block->v[k][0][lane], block->v[k][1][lane], block->v[k][2][lane]};
}

/* The geometric normal of lane lane (sidx__tri_normal: the mesh finish's bits). */
static SIDX_INLINE sidx_vec3 tri4_lane_normal(const tri4_block *block, unsigned lane)
{
    return sidx__tri_normal(tri4_lane_vertex(block, 0, lane), tri4_lane_vertex(block, 1, lane),
                            tri4_lane_vertex(block, 2, lane));
}

/* The scalar reference test on lane lane of a block: the same sidx__tri_test
 * brute force runs, on the block's copy of the vertices (bit-identical t,
 * u, v).  Used where a SIMD kernel is unavailable or declines (an exact
 * zero edge function). */
static SIDX_INLINE int tri4_lane_test(const sidx_accel *a, const sidx_ray *r, const tri4_block *block, unsigned lane,
                                      float best, float *t, float *u, float *v)
{
    return sidx__tri_test(a->opt.tri, r, tri4_lane_vertex(block, 0, lane), tri4_lane_vertex(block, 1, lane),
                          tri4_lane_vertex(block, 2, lane), best, t, u, v);
}

/* u, v of the final hit on lane lane, whatever the triangle test: the
 * lane's corners at stride 4 given to sidx__tri_hit_uv_at (the watertight
 * test's own last step on its float edge functions, else the whole test
 * again).  Returns 0, leaving u, v alone, if the test misses. */
static SIDX_INLINE int tri4_lane_hit_uv(const sidx_accel *a, const sidx_ray *r, const tri4_block *block, unsigned lane,
                                        float *u, float *v)
{
    return sidx__tri_hit_uv_at(a->opt.tri, r, &block->v[0][0][lane], &block->v[1][0][lane], &block->v[2][0][lane], 4,
                               u, v);
}

#include "simd_isa.h"
#ifdef SIDX_SIMD_SSE2 /* x86 with SSE2, or WebAssembly SIMD (simd_isa.h) */
#define SIDX_TRI4_SSE 1
#include "simd_tri4_sse.h" /* 4 triangles at once (watertight), one ray */
#else
#define SIDX_TRI4_SSE 0
#endif

#endif
