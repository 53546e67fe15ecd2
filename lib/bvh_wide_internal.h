/* bvh_wide_internal.h — the 4- and 8-wide BVH ("bvh4", "bvh8"): data
 * layout shared by bvh_wide.c (collapse, dispatch), bvh_wide_walk.h (the
 * traversal, compiled once per instruction set) and packet.c.
 *
 * Why wide nodes: a binary BVH tests one box per node visit with scalar
 * code, so three quarters of an SSE register and seven eighths of an AVX
 * register sit idle.  Collapsing the binary tree so each node holds the
 * boxes of its 4 or 8 "grandchildren" (Dammertz, Hanika, Keller 2008,
 * "Shallow bounding volume hierarchies for fast SIMD ray tracing of
 * incoherent rays"; Ernst & Greiner 2008, "Multi bounding volume
 * hierarchies"; Wald, Benthin, Boulos 2008, "Getting rid of packets") lets
 * one ray test all of them in one pass of SIMD instructions — the deck's
 * "traverse one ray, but intersect with many BVs (needs wide BVH!)".
 *
 * Node (W = 4 or 8 lanes, 8·W 32-bit words = 128 or 256 bytes, so a node
 * is whole cache lines when the array is 64-byte aligned):
 *
 *   float    b[6][W]   child boxes, structure of arrays: lo_x, lo_y, lo_z,
 *                      hi_x, hi_y, hi_z — one SIMD load per plane;
 *   uint32_t child[W]  inner child: its node index;  leaf: WIDE_LEAF_BIT |
 *                      first triangle block;  unused slot: WIDE_EMPTY;
 *   uint32_t id[W]     the child's node id in events (inner: its index;
 *                      leaf: num_inner + leaf number), only read when traced.
 *
 * An unused slot has lo = +inf, hi = -inf: every ray's slab interval for
 * it comes out as [+inf, -inf] (for either sign of the direction, and for
 * a ±0 direction too), so it is a miss without a per-slot valid mask.
 *
 * Leaves hold their triangles in blocks of 4 (structure of arrays, the
 * layout Embree's Triangle4 uses) so one SSE pass runs the watertight test
 * on 4 triangles; a leaf is a run of consecutive blocks, the last marked by
 * WIDE_LAST_BLOCK in prim[0].  Unused lanes have NaN vertices (every
 * comparison on them is false, so they never hit and never trigger the
 * double-precision fallback) and prim = WIDE_PAD_PRIM.
 *
 * Plain float nodes and two separate arrays: quantized nodes, huge pages
 * and leaves stored beside their parents were measured and rejected
 * (docs/performance.md, "Wide BVHs"). */
#ifndef SIDX_BVH_WIDE_INTERNAL_H
#define SIDX_BVH_WIDE_INTERNAL_H

#include "bvh_internal.h"

#define WIDE_LEAF_BIT 0x80000000u
#define WIDE_EMPTY 0xFFFFFFFFu
#define WIDE_LAST_BLOCK 0x80000000u
#define WIDE_PRIM_MASK 0x7FFFFFFFu
#define WIDE_PAD_PRIM 0x7FFFFFFFu

/* Closest-hit traversal pushes at most W − 1 deferred children per level
 * and the tree is at most BVH_DEPTH_LIMIT deep: 64 · 7 + 1 < 512. */
#define WIDE_STACK 512

/* Instruction sets of the kernels (chosen when the structure is built).
 * AVX-512 is the AVX2 code (8 lanes in ymm registers) compiled with
 * AVX-512F/VL: the same operations in the same order, so the same bits,
 * but 32 vector registers instead of 16 — the 8-wide walk holds 10 box
 * constants and 6 triangle constants across its loop, which on AVX2
 * spill at every leaf (see leaf_ in bvh_wide_walk.h). */
typedef enum wide_isa { WIDE_ISA_SCALAR = 0, WIDE_ISA_SSE41 = 1, WIDE_ISA_AVX2 = 2, WIDE_ISA_AVX512 = 3 } wide_isa;

typedef struct wide_tri4 {
    float v[3][3][4];  /* [vertex][axis][lane] */
    uint32_t prim[4];  /* original triangle index (WIDE_PRIM_MASK bits); prim[0] also carries WIDE_LAST_BLOCK */
} wide_tri4;
_Static_assert(sizeof(wide_tri4) == 160, "wide_tri4 is 9 float4 + 4 ids");

/* Lane l of a block: the triangle with corners p[0], p[1], p[2] and
 * original index prim, or padding (NaN corners, WIDE_PAD_PRIM) when p is
 * NULL.  Both block layouts (bvh4/bvh8 leaves, kd-tree references) are
 * filled by it. */
static inline void wide_set_lane(wide_tri4 *B, unsigned l, const sidx_vec3 *p, uint32_t prim)
{
    for (int v = 0; v < 3; ++v) {
        const sidx_vec3 c = p ? p[v] : sidx_v3(NAN, NAN, NAN);
        B->v[v][0][l] = c.x;
        B->v[v][1][l] = c.y;
        B->v[v][2][l] = c.z;
    }
    B->prim[l] = p ? prim : WIDE_PAD_PRIM;
}

/* Corner k (0, 1, 2) of lane l of a block. */
static SIDX_INLINE sidx_vec3 wide_lane_vertex(const wide_tri4 *B, int k, unsigned l)
{
    return (sidx_vec3){B->v[k][0][l], B->v[k][1][l], B->v[k][2][l]};
}

/* The geometric normal of lane l (sidx__tri_normal: the mesh finish's bits). */
static SIDX_INLINE sidx_vec3 wide_lane_normal(const wide_tri4 *B, unsigned l)
{
    return sidx__tri_normal(wide_lane_vertex(B, 0, l), wide_lane_vertex(B, 1, l), wide_lane_vertex(B, 2, l));
}

/* The scalar reference test on lane l of a block: the same sidx__tri_test
 * brute force runs, on the block's copy of the vertices (bit-identical t,
 * u, v).  Used where a SIMD kernel is unavailable or declines (an exact
 * zero edge function). */
static SIDX_INLINE int wide_lane_test(const sidx_accel *a, const sidx_ray *r, const wide_tri4 *B, unsigned l,
                                      float best, float *t, float *u, float *v)
{
    return sidx__tri_test(a->opt.tri, r, wide_lane_vertex(B, 0, l), wide_lane_vertex(B, 1, l),
                          wide_lane_vertex(B, 2, l), best, t, u, v);
}

/* u, v of the final hit on lane l, whatever the triangle test: the
 * lane's corners at stride 4 given to sidx__tri_hit_uv_at (the watertight
 * test's own last step on its float edge functions, else the whole test
 * again).  Returns 0, leaving u, v alone, if the test misses. */
static SIDX_INLINE int wide_lane_hit_uv(const sidx_accel *a, const sidx_ray *r, const wide_tri4 *B, unsigned l,
                                        float *u, float *v)
{
    return sidx__tri_hit_uv_at(a->opt.tri, r, &B->v[0][0][l], &B->v[1][0][l], &B->v[2][0][l], 4, u, v);
}

struct wide_bvh;
typedef void (*wide_isect_fn)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit);
typedef int (*wide_occl_fn)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q);

/* The walks of one (width, instruction set): traced, untraced with the
 * SIMD watertight triangle test (and its copy that keeps what u, v need,
 * for queries asking for them), untraced with another triangle test. */
typedef struct wide_kernels {
    wide_isect_fn isect_traced, isect_simd, isect_simd_uv, isect_other;
    wide_occl_fn occl_traced, occl_simd, occl_other;
} wide_kernels;

typedef struct wide_bvh {
    uint32_t width;        /* W: 4 or 8 */
    wide_isa isa;          /* kernels in use */
    float *nodes;          /* num_inner nodes of 8·W words, 64-byte aligned inside nodes_mem */
    void *nodes_mem;
    uint32_t num_inner, num_leaves, max_depth, num_prims;
    wide_tri4 *blocks;     /* 64-byte aligned inside blocks_mem */
    void *blocks_mem;
    uint32_t num_blocks;
    double sah_cost;
    sidx_aabb bounds;      /* scene box (union of the root's slots) */
    wide_isect_fn isect, isect_uv, isect_traced; /* untraced walk for the structure's triangle test (and for
                                                    queries with SIDX_QUERY_UV); traced walk */
    wide_occl_fn occl, occl_traced;
} wide_bvh;

static SIDX_INLINE const float *wide_node(const wide_bvh *w, uint32_t i) { return w->nodes + (size_t)i * 8u * w->width; }
static SIDX_INLINE const uint32_t *wide_child(const float *n, uint32_t W)
{
    return (const uint32_t *)(const void *)(n + 6u * W);
}
static SIDX_INLINE const uint32_t *wide_id(const float *n, uint32_t W)
{
    return (const uint32_t *)(const void *)(n + 7u * W);
}
static inline sidx_aabb wide_slot_box(const float *n, uint32_t W, uint32_t s)
{
    sidx_aabb b = {{n[0 * W + s], n[1 * W + s], n[2 * W + s]}, {n[3 * W + s], n[4 * W + s], n[5 * W + s]}};
    return b;
}

/* Traversal entry points, one set per width and instruction set
 * (bvh_wide.c instantiates bvh_wide_walk.h for each). */
extern const wide_kernels sidx__wide_kernels_4_0, sidx__wide_kernels_8_0;
#if defined(__x86_64__) || defined(__i386__)
#define SIDX_WIDE_X86 1
extern const wide_kernels sidx__wide_kernels_4_1, sidx__wide_kernels_8_2, sidx__wide_kernels_8_3;
#endif

#if defined(SIDX_WIDE_X86) && defined(__SSE2__)
#include <immintrin.h>
/* ---- 4 triangles at once (watertight), one ray --------------------------------
 * Woop et al. 2013 on a leaf block's four lanes, SSE2 only so it inlines
 * into the SSE4.1 and AVX2 walks and the packet walk alike (the blend is
 * done with and/or).  The ray's lane-broadcast constants are set up once
 * per ray (wide_tri_ray_init).  Returns 1 with the smallest t in
 * [tmin, best) (lowest lane on ties), 0 for no hit, -1 when some lane's
 * edge function is exactly 0 and the block must take the scalar path
 * (wide_lane_test, which redoes those in double).  When it returns 1 and
 * vwd_out is not NULL, vwd_out[0..3], [4..7], [8..11] receive the lanes'
 * V, W and det — the floats the scalar test computes too (no edge
 * function was 0, so it would not have switched to double) — from which
 * sidx__tri_watertight_uv forms the hit's u, v bit for bit. */
typedef struct wide_tri_ray {
    __m128 okx, oky, okz, sx, sy, sz, ttmin;
    uint32_t kx4, ky4, kz4; /* float offsets of the permuted axes inside a block's vertex */
} wide_tri_ray;

static SIDX_INLINE void wide_tri_ray_init(wide_tri_ray *T, const sidx_ray *r)
{
    const float *o = &r->org.x;
    T->okx = _mm_set1_ps(o[r->kx]); T->oky = _mm_set1_ps(o[r->ky]); T->okz = _mm_set1_ps(o[r->kz]);
    T->sx = _mm_set1_ps(r->sx); T->sy = _mm_set1_ps(r->sy); T->sz = _mm_set1_ps(r->sz);
    T->ttmin = _mm_set1_ps(r->tmin);
    T->kx4 = 4u * r->kx; T->ky4 = 4u * r->ky; T->kz4 = 4u * r->kz;
}

/* The kernel on the ray's permuted axes of a block: px, py, pz point at
 * vertex 0's kx, ky, kz row (vertex k's at +12k floats). */
static SIDX_INLINE int wide_tri4_test_axes(const float *px, const float *py, const float *pz, const wide_tri_ray *R,
                                           float best, float *t_out, unsigned *lane_out, float *vwd_out)
{
    const __m128 ax = _mm_sub_ps(_mm_load_ps(px), R->okx);
    const __m128 ay = _mm_sub_ps(_mm_load_ps(py), R->oky);
    const __m128 az = _mm_sub_ps(_mm_load_ps(pz), R->okz);
    const __m128 bx = _mm_sub_ps(_mm_load_ps(px + 12), R->okx);
    const __m128 by = _mm_sub_ps(_mm_load_ps(py + 12), R->oky);
    const __m128 bz = _mm_sub_ps(_mm_load_ps(pz + 12), R->okz);
    const __m128 cx = _mm_sub_ps(_mm_load_ps(px + 24), R->okx);
    const __m128 cy = _mm_sub_ps(_mm_load_ps(py + 24), R->oky);
    const __m128 cz = _mm_sub_ps(_mm_load_ps(pz + 24), R->okz);
    const __m128 Ax = _mm_sub_ps(ax, _mm_mul_ps(R->sx, az)), Ay = _mm_sub_ps(ay, _mm_mul_ps(R->sy, az));
    const __m128 Bx = _mm_sub_ps(bx, _mm_mul_ps(R->sx, bz)), By = _mm_sub_ps(by, _mm_mul_ps(R->sy, bz));
    const __m128 Cx = _mm_sub_ps(cx, _mm_mul_ps(R->sx, cz)), Cy = _mm_sub_ps(cy, _mm_mul_ps(R->sy, cz));
    const __m128 U = _mm_sub_ps(_mm_mul_ps(Cx, By), _mm_mul_ps(Cy, Bx));
    const __m128 V = _mm_sub_ps(_mm_mul_ps(Ax, Cy), _mm_mul_ps(Ay, Cx));
    const __m128 W = _mm_sub_ps(_mm_mul_ps(Bx, Ay), _mm_mul_ps(By, Ax));
    const __m128 zero = _mm_setzero_ps();
    const __m128 anyzero = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, zero), _mm_cmpeq_ps(V, zero)), _mm_cmpeq_ps(W, zero));
    if (SIDX_UNLIKELY(_mm_movemask_ps(anyzero))) return -1;
    /* No edge function is ±0 now, so "some < 0 and some > 0" is "the sign
     * bits differ": two XORs instead of six compares.  Lanes whose det is
     * 0 or NaN (padding: NaN vertices) drop out through the ordered
     * compare; their t below would fail anyway.  Most blocks a ray reaches
     * are missed on every lane, and they stop here, before T and the
     * division (Embree's kernels defer the division the same way). */
    const __m128 mixed = _mm_castsi128_ps(
        _mm_srai_epi32(_mm_castps_si128(_mm_or_ps(_mm_xor_ps(U, V), _mm_xor_ps(U, W))), 31)); /* sign to all bits */
    const __m128 det = _mm_add_ps(_mm_add_ps(U, V), W);
    const __m128 cand = _mm_andnot_ps(mixed, _mm_or_ps(_mm_cmplt_ps(det, zero), _mm_cmpgt_ps(det, zero)));
    if (!_mm_movemask_ps(cand)) return 0;
    const __m128 T = _mm_add_ps(_mm_add_ps(_mm_mul_ps(U, _mm_mul_ps(R->sz, az)), _mm_mul_ps(V, _mm_mul_ps(R->sz, bz))),
                                _mm_mul_ps(W, _mm_mul_ps(R->sz, cz)));
    const __m128 t = _mm_div_ps(T, det);
    const __m128 ok = _mm_and_ps(cand, _mm_and_ps(_mm_cmpge_ps(t, R->ttmin), _mm_cmplt_ps(t, _mm_set1_ps(best))));
    const unsigned m = (unsigned)_mm_movemask_ps(ok);
    if (!m) return 0;
    const __m128 tt = _mm_or_ps(_mm_and_ps(ok, t), _mm_andnot_ps(ok, _mm_set1_ps(INFINITY))); /* SSE2 blend */
    __m128 mn = _mm_min_ps(tt, _mm_shuffle_ps(tt, tt, _MM_SHUFFLE(1, 0, 3, 2)));
    mn = _mm_min_ps(mn, _mm_shuffle_ps(mn, mn, _MM_SHUFFLE(2, 3, 0, 1)));
    *lane_out = (unsigned)__builtin_ctz((unsigned)_mm_movemask_ps(_mm_cmpeq_ps(tt, mn)) & m);
    *t_out = _mm_cvtss_f32(mn);
    if (vwd_out) {
        _mm_storeu_ps(vwd_out, V);
        _mm_storeu_ps(vwd_out + 4, W);
        _mm_storeu_ps(vwd_out + 8, det);
    }
    return 1;
}

static SIDX_INLINE int wide_tri4_test(const wide_tri4 *B, const wide_tri_ray *R, float best, float *t_out,
                                      unsigned *lane_out, float *vwd_out)
{
    const float *v = &B->v[0][0][0]; /* vertex k, axis x, lane l at v[12k + 4x + l] */
    return wide_tri4_test_axes(v + R->kx4, v + R->ky4, v + R->kz4, R, best, t_out, lane_out, vwd_out);
}
#endif

/* The instruction set bvh4/bvh8 pick on this machine: the best the CPU
 * has, unless the environment variable SIDX_SIMD (scalar, sse4.1, avx2)
 * asks for less — that is how the tests run the other copies. */
wide_isa sidx__wide_pick_isa(uint32_t width);

/* Is `a` a bvh4 / bvh8 (for packet.c)? */
int sidx__is_wide(const sidx_accel *a);

#endif
