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
 * Leaves hold their triangles in blocks of 4 (wide_tri4, tri4.h) so one
 * SSE pass runs the watertight test on 4 triangles; a leaf is a run of
 * consecutive blocks, the last marked by WIDE_LAST_BLOCK in prim[0].
 *
 * Plain float nodes and two separate arrays, on 2 MB pages when they are
 * large (bvh_wide.c, alloc_array): quantized nodes and leaves stored
 * beside their parents were measured and rejected (docs/performance.md,
 * "Wide BVHs"). */
#ifndef SIDX_BVH_WIDE_INTERNAL_H
#define SIDX_BVH_WIDE_INTERNAL_H

#include "bvh_internal.h"
#include "tri4.h" /* the leaves' blocks of four triangles */

/* The wide BVH's names for the shared block and its kernel (tri4.h). */
typedef tri4_block wide_tri4;
#if SIDX_TRI4_SSE
typedef tri4_ray wide_tri_ray;
#endif
#define WIDE_PAD_PRIM TRI4_PAD_PRIM
#define wide_set_lane tri4_set_lane
#define wide_lane_vertex tri4_lane_vertex
#define wide_lane_normal tri4_lane_normal
#define wide_lane_test tri4_lane_test
#define wide_lane_hit_uv tri4_lane_hit_uv
#define wide_tri_ray_init tri4_ray_init
#define wide_tri4_test tri4_test
#define wide_tri4_test_axes tri4_test_axes

#define WIDE_LEAF_BIT 0x80000000u
#define WIDE_EMPTY 0xFFFFFFFFu
/* Lazy trees (opt.lazy; bvh_wide.c, "lazy builds"): a child WIDE_LAZY_BIT | r
 * is a subtree not built until a ray reaches it, lazy part r; a child
 * marked WIDE_PART_BIT (inner: WIDE_PART_BIT | i, leaf: WIDE_LEAF_BIT |
 * WIDE_PART_BIT | b) is node i or block b of such a part once built, in
 * arrays of its own.  A lazy tree's node and block indices stay below
 * 2^29 (the builds check it). */
#define WIDE_LAZY_BIT 0x40000000u
#define WIDE_PART_BIT 0x20000000u

/* Closest-hit traversal pushes at most W − 1 deferred children per level
 * and the tree is at most BVH_DEPTH_LIMIT deep: 64 · 7 + 1 < 512. */
#define WIDE_STACK 512

/* Instruction sets of the kernels (chosen when the structure is built),
 * one kernel header each: simd_wide_scalar.h, simd_wide_sse.h,
 * simd_wide_avx2.h, simd_wide_avx512.h (the AVX2 code compiled with
 * AVX-512F/VL: the same bits, 32 vector registers instead of 16). */
typedef enum wide_isa { WIDE_ISA_SCALAR = 0, WIDE_ISA_SSE41 = 1, WIDE_ISA_AVX2 = 2, WIDE_ISA_AVX512 = 3 } wide_isa;

struct wide_bvh;
typedef void (*wide_isect_fn)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit);
typedef int (*wide_occl_fn)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q);

/* What a walk copy is (bvh_wide_walk.h, walk_'s `kind`, a compile-time
 * constant in each copy): any hit or closest hit, traced, with the SIMD
 * watertight triangle test, keeping what u, v need, over a lazy tree. */
enum {
    WIDE_WALK_ANYHIT = 1,
    WIDE_WALK_TRACED = 2,
    WIDE_WALK_SIMD_TRI = 4,
    WIDE_WALK_KEEP_UV = 8,
    WIDE_WALK_LAZY = 16
};

/* The walks of one (width, instruction set): traced, untraced with the
 * SIMD watertight triangle test (and its copy that keeps what u, v need,
 * for queries asking for them), untraced with another triangle test. */
typedef struct wide_kernels {
    wide_isect_fn isect_traced, isect_simd, isect_simd_uv, isect_other;
    wide_occl_fn occl_traced, occl_simd, occl_other;
    /* the same for lazy trees */
    wide_isect_fn lazy_isect_traced, lazy_isect_simd, lazy_isect_simd_uv, lazy_isect_other;
    wide_occl_fn lazy_occl_traced, lazy_occl_simd, lazy_occl_other;
} wide_kernels;

/* The stream walks of one (width, instruction set) over a buffer of rays
 * (bvh_stream.c, bvh_internal.h): closest hit with the SIMD watertight
 * test, the same keeping what u, v need, with another test; any hit. */
typedef struct wide_stream_kernels {
    bvh_stream_fn isect_simd, isect_simd_uv, isect_other, occl_simd, occl_other;
    /* isect_simd and isect_simd_uv with several rays in flight (bvh_wide_walk.h) */
    bvh_stream_fn flight_simd, flight_simd_uv;
} wide_stream_kernels;

/* Lazy trees.  The build stops at every subtree of the binary tree of
 * more than WIDE_MAX_LEAF and at most opt.lazy references
 * (sidx__bvh_build_spatial's placeholders), the collapse makes each one
 * child of its own, WIDE_LAZY_BIT | r, and record r says what building it
 * takes.  Its life — claim, wait, publish, failure, the counters — is
 * lazy.c's (lazy.h), one sidx__lazy_part per record: the first ray to
 * reach it builds the binary subtree (the eager build's, node for node)
 * and collapses it into a wide tree of its own, its part, whose children
 * are marked WIDE_PART_BIT.  The lazy walks reach it through their node
 * fetch (bvh_wide_walk.h, fetch_node_): the unbuilt child's place is taken
 * by the part's root, and a marked child is read from the part's arrays,
 * so one walk goes on through it as through the eager tree; when its
 * memory cannot be had, by sidx__wide_void_node (every slot empty) and the
 * query reports SIDX_ERR_NOMEM. */
typedef struct wide_lazy_rec {
    uint32_t count, parent, depth, id; /* references, parent wide node, depth, event id of the child */
    sidx_aabb box;
} wide_lazy_rec;

typedef struct wide_lazy {
    sidx__lazy life;                /* one part per record, its wide_bvh (lazy.c) */
    wide_lazy_rec *recs;
    uint32_t num_recs;
    sidx__sbvh_lazy *sb;            /* the binary build's records (bvh_spatial.c) */
    uint32_t next_id;               /* atomic: event ids handed out */
    uint32_t part_leaves;           /* atomic: leaves the expansions made */
} wide_lazy;

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
    /* The walk tables (sidx_internal.h): [0] for queries without u, v,
     * [1] for SIDX_QUERY_UV; the untraced walks use the structure's
     * triangle test, fixed at build. */
    sidx__walk_table walks[2];
    wide_lazy *lazy;       /* lazy trees only; NULL when every node is built at once */
    int inflight;          /* the stream entry walks several rays in flight (bvh_wide.c, want_inflight) */
} wide_bvh;

/* A node whose every slot is empty (lo = +inf, hi = -inf, WIDE_EMPTY):
 * where a lazy walk stands when a part could not be built.  8·8 words,
 * 64-byte aligned; bvh4 reads the first 8·4 as its own (bvh_wide.c). */
extern const float *const sidx__wide_void_node[2];

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
extern const wide_kernels sidx__wide_kernels_4_scalar, sidx__wide_kernels_8_scalar;
extern const wide_stream_kernels sidx__wide_stream_4_scalar, sidx__wide_stream_8_scalar;
#if defined(__x86_64__) || defined(__i386__)
#define SIDX_WIDE_X86 1
extern const wide_kernels sidx__wide_kernels_4_sse41, sidx__wide_kernels_8_avx2, sidx__wide_kernels_8_avx512;
extern const wide_stream_kernels sidx__wide_stream_4_sse41, sidx__wide_stream_8_avx2, sidx__wide_stream_8_avx512;
#elif defined(SIDX_SIMD_SSE2)
/* WebAssembly SIMD (simd_isa.h): bvh4's SSE4.1 walk, compiled for it and
 * taken without a run-time test; bvh8's AVX2 walk has no counterpart */
#define SIDX_WIDE_WASM 1
extern const wide_kernels sidx__wide_kernels_4_sse41;
extern const wide_stream_kernels sidx__wide_stream_4_sse41;
#endif

/* The instruction set bvh4/bvh8 pick on this machine: the best the CPU
 * has, unless the environment variable SIDX_SIMD (scalar, sse4.1, avx2)
 * asks for less — that is how the tests run the other copies. */
wide_isa sidx__wide_pick_isa(uint32_t width);

/* Is `a` a bvh4 / bvh8 (for packet.c)? */
int sidx__is_wide(const sidx_accel *a);

#endif
