/* bvh_wide.c — "bvh4" and "bvh8": a binned-SAH BVH with spatial splits
 * collapsed into 4- and 8-wide nodes, traversed with SSE4.1 / AVX2 /
 * AVX-512 (bvh_wide_walk.h).
 *
 * Build = a binary build, then a collapse.  The binary tree is binned SAH
 * with spatial splits (bvh_spatial.c, Stich et al. 2009: a straddling
 * triangle may be referenced by both sides, so sibling boxes stop
 * overlapping), or with opt.no_spatial_splits the ordinary binned-SAH
 * build (bvh_build.c, Wald 2007).  Spatial splits pay where big
 * triangles overlap (Sponza), and cost nothing where they are small and
 * even (the bunny): docs/performance.md, "Spatial splits".
 *
 * The collapse picks, by dynamic programming on the SAH, which binary
 * nodes become wide nodes, which subtrees become leaves (runs of
 * 4-triangle blocks) and which dissolve into their parent's slots (see
 * "collapse" below; Ylitie et al. 2017).  It replaces the greedy rule of
 * Dammertz et al. 2008 and Embree's BVH4/8 builders (open the child of
 * largest surface area until W are there), which never weighs a fuller
 * node against a bigger leaf.
 *
 * The collapse keeps the binary tree's boxes, so the wide tree bounds
 * exactly what the binary one does; only the grouping changes.
 *
 * Kernels are chosen once, when the structure is built: for bvh8 the AVX2
 * walk compiled for AVX-512F/VL when the CPU has those (32 vector
 * registers: no spills at leaf entry; docs/performance.md, "Wide
 * BVHs"), else AVX2; SSE4.1 for bvh4; else the
 * scalar copy of the same walk (__builtin_cpu_supports).  In WebAssembly
 * with SIMD (`make web`) bvh4 takes the SSE4.1 walk, which emscripten maps
 * onto WebAssembly SIMD, and bvh8 the scalar one.  SIDX_SIMD in
 * the environment caps the choice: "scalar", "sse4.1" or "avx2" (the
 * tests compare every copy the CPU can run).  A NOTE event on the build
 * hook says which was picked. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "bvh_wide_internal.h"
#include "simd_isa.h"
#ifdef __linux__
#include <sys/mman.h>
#endif

#define SIDX_STRUCTURE_NAME (a->name)

/* sidx__wide_void_node (bvh_wide_internal.h): +inf lows, -inf highs,
 * WIDE_EMPTY children and ids, as bits; [0] bvh4's layout, [1] bvh8's. */
#define VOID4(x) x, x, x, x
#define VOID8(x) VOID4(x), VOID4(x)
#define VOID_NODE(R) {R(0x7F800000u), R(0x7F800000u), R(0x7F800000u), R(0xFF800000u), R(0xFF800000u), R(0xFF800000u), \
                      R(WIDE_EMPTY), R(UINT32_MAX)}
static _Alignas(64) const union { uint32_t u[32]; float f[32]; } void_node_4 = {.u = VOID_NODE(VOID4)};
static _Alignas(64) const union { uint32_t u[64]; float f[64]; } void_node_8 = {.u = VOID_NODE(VOID8)};
const float *const sidx__wide_void_node[2] = {void_node_4.f, void_node_8.f};
#undef VOID4
#undef VOID8
#undef VOID_NODE

/* ---- the traversal, instantiated per width and instruction set --------------
 * bvh_wide_walk.h is the walk; it includes the kernels of WALK_ISA
 * (simd_wide_scalar.h, simd_wide_sse.h, simd_wide_avx2.h,
 * simd_wide_avx512.h) and names every function after WALK_W and
 * WALK_ISA_NAME: walk_8_avx512, sidx__wide_kernels_4_sse41, ... (the full
 * list: lib/README.md, "Generated functions"). */

#define WALK_TARGET
#define WALK_ISA 0
#define WALK_ISA_NAME scalar
#define WALK_W 4
#include "bvh_wide_walk.h"
#undef WALK_W
#define WALK_W 8
#include "bvh_wide_walk.h"
#undef WALK_W
#undef WALK_ISA_NAME
#undef WALK_ISA
#undef WALK_TARGET

#if defined(SIDX_WIDE_X86) || defined(SIDX_WIDE_WASM)
#ifdef SIDX_WIDE_X86
#define WALK_TARGET __attribute__((target("sse4.1")))
#else
#define WALK_TARGET
#endif
#define WALK_ISA 1
#define WALK_ISA_NAME sse41
#define WALK_W 4
#include "bvh_wide_walk.h"
#undef WALK_W
#undef WALK_ISA_NAME
#undef WALK_ISA
#undef WALK_TARGET
#endif

#ifdef SIDX_WIDE_X86

#define WALK_TARGET __attribute__((target("avx2,fma,popcnt")))
#define WALK_ISA 2
#define WALK_ISA_NAME avx2
#define WALK_W 8
#include "bvh_wide_walk.h"
#undef WALK_W
#undef WALK_ISA_NAME
#undef WALK_ISA
#undef WALK_TARGET

/* The AVX2 walk again with 32 vector registers (simd_wide_avx512.h). */
#define WALK_TARGET __attribute__((target("avx2,fma,popcnt,avx512f,avx512vl")))
#define WALK_ISA 3
#define WALK_ISA_NAME avx512
#define WALK_W 8
#include "bvh_wide_walk.h"
#undef WALK_W
#undef WALK_ISA_NAME
#undef WALK_ISA
#undef WALK_TARGET
#endif

wide_isa sidx__wide_pick_isa(uint32_t width)
{
    const char *env = getenv("SIDX_SIMD");
    int allow = 3;
    if (env && (!strcmp(env, "scalar") || !strcmp(env, "0"))) allow = 0;
    else if (env && !strcmp(env, "sse4.1")) allow = 1;
    else if (env && !strcmp(env, "avx2")) allow = 2;
#ifdef SIDX_WIDE_X86
    __builtin_cpu_init();
    const int avx2 =
        __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("popcnt");
    if (width == 8 && allow >= 3 && avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl"))
        return WIDE_ISA_AVX512;
    if (width == 8 && allow >= 2 && avx2) return WIDE_ISA_AVX2;
    if (width == 4 && allow >= 1 && __builtin_cpu_supports("sse4.1")) return WIDE_ISA_SSE41;
#elif defined(SIDX_WIDE_WASM)
    if (width == 4 && allow >= 1) return WIDE_ISA_SSE41;
#else
    (void)width;
    (void)allow;
#endif
    return WIDE_ISA_SCALAR;
}

static void set_kernels(wide_bvh *w, sidx_tri_method tri)
{
    /* a lazy tree's walks are copies of their own (lazy = 1 in bvh_wide_walk.h);
     * the eager ones compile without any of their code */
    const wide_kernels *k = w->width == 8 ? &sidx__wide_kernels_8_scalar : &sidx__wide_kernels_4_scalar;
#ifdef SIDX_WIDE_X86
    if (w->isa == WIDE_ISA_AVX512) k = &sidx__wide_kernels_8_avx512;
    else if (w->isa == WIDE_ISA_AVX2) k = &sidx__wide_kernels_8_avx2;
    else if (w->isa == WIDE_ISA_SSE41) k = &sidx__wide_kernels_4_sse41;
#elif defined(SIDX_WIDE_WASM)
    if (w->isa == WIDE_ISA_SSE41) k = &sidx__wide_kernels_4_sse41;
#endif
    /* The triangle test is fixed at build: decide here, not per ray. */
    const int simd_tri = tri == SIDX_TRI_WATERTIGHT;
    if (w->lazy) {
        const wide_occl_fn occl = simd_tri ? k->lazy_occl_simd : k->lazy_occl_other;
        w->walks[0] = (sidx__walk_table){simd_tri ? k->lazy_isect_simd : k->lazy_isect_other, k->lazy_isect_traced,
                                         occl, k->lazy_occl_traced};
        w->walks[1] = (sidx__walk_table){simd_tri ? k->lazy_isect_simd_uv : k->lazy_isect_other,
                                         k->lazy_isect_traced, occl, k->lazy_occl_traced};
        return;
    }
    const wide_occl_fn occl = simd_tri ? k->occl_simd : k->occl_other;
    w->walks[0] = (sidx__walk_table){simd_tri ? k->isect_simd : k->isect_other, k->isect_traced, occl, k->occl_traced};
    w->walks[1] = (sidx__walk_table){simd_tri ? k->isect_simd_uv : k->isect_other, k->isect_traced, occl,
                                     k->occl_traced};
}

/* ---- collapse ------------------------------------------------------------------ */

/* Which binary subtrees become wide nodes, which become leaves and which
 * are dissolved into their parent's slots is chosen to minimise the SAH
 * cost of the wide tree, by dynamic programming over the binary tree
 * (Ylitie, Karras, Laine 2017, "Efficient incoherent ray traversal on GPUs
 * through compressed wide BVHs", sec. 4.1).  For every binary node n and
 * every slot budget j = 1..W, cost[n][j] is the cheapest way to stand for
 * n's subtree with at most j slots of the parent:
 *   one slot:  a leaf,  A(n)·C_BLOCK·⌈N/4⌉  (a block tests 4 triangles),
 *              or a wide node,  A(n)·C_NODE + split(n, W);
 *   j slots:   the one-slot answer, or split(n, j) = min over k of
 *              cost[left][k] + cost[right][j − k].
 * A(n) is the surface area of n's box (the SAH's hit probability, up to
 * the root's area, which is common to all terms).  Costs are per node
 * visit (one pass over W boxes) and per block (one pass over 4
 * triangles): both are one SIMD pass and a few cache lines, so 1 : 1,
 * as in Embree's builders.  This replaces a greedy "open the child of
 * largest area" rule: it fills nodes where that pays and keeps subtrees
 * of up to WIDE_MAX_LEAF triangles as multi-block leaves where that pays.
 * Other values of the three constants moved neither instruction counts
 * nor times beyond the noise: docs/performance.md, "Wide BVHs". */
#define WIDE_MAX_LEAF 8u
#define WIDE_C_NODE 1.0f
#define WIDE_C_BLOCK 1.0f

typedef struct collapse {
    const bvh *b;
    const sidx_mesh *mesh;                 /* leaves take their corners from here (the tree has no tris[]) */
    uint32_t W;
    const uint32_t *sub_count, *sub_first; /* per binary node: triangles below it and the first one */
    float *cost;                           /* [node][j − 1], W per node */
    uint8_t *how;                          /* [node][j − 1]: HOW_LEAF, HOW_NODE, HOW_LAZY, HOW_SPLIT + k (k slots left) */
    uint8_t *node_k;                       /* [node]: slots given to the left child when n is a wide node */
    float *nodes;
    uint32_t num_inner;
    wide_tri4 *blocks;
    uint32_t num_blocks, num_leaves, max_depth;
    wide_lazy_rec *lazy_recs;              /* lazy top: the records its unbuilt children fill in */
} collapse;

/* HOW_LAZY: a placeholder of a lazy build (bvh_spatial.c), one slot. */
enum { HOW_LEAF = 0, HOW_NODE = 1, HOW_LAZY = 2, HOW_SPLIT = 3 };

static SIDX_INLINE int is_placeholder(const bvh_node *n) { return (n->count_axis & BVH_LAZY_MARK) == BVH_LAZY_MARK; }

static void collapse_costs(collapse *C)
{
    const uint32_t W = C->W, nn = C->b->num_nodes;
    const bvh_node *bn = C->b->nodes;
    for (uint32_t i = nn; i-- > 0;) {
        float *c = C->cost + (size_t)i * W;
        uint8_t *h = C->how + (size_t)i * W;
        const float area = sidx_aabb_area(bvh_node_box(&bn[i]));
        const uint32_t N = C->sub_count[i];
        if (is_placeholder(&bn[i])) {
            /* Its subtree is not built, so its cost is not known: one
             * slot, at an estimate of a wide subtree over N triangles
             * (a node per level of log_W N, and a block).  The choices
             * above it are made on that estimate. */
            const float est = area * (WIDE_C_NODE * (1.0f + logf((float)N) / logf((float)W)) + WIDE_C_BLOCK);
            for (uint32_t j = 0; j < W; ++j) { c[j] = est; h[j] = HOW_LAZY; }
            C->node_k[i] = 0;
            continue;
        }
        const int is_leaf = bvh_is_leaf(&bn[i]);
        const float leaf = (is_leaf || N <= WIDE_MAX_LEAF) ? area * WIDE_C_BLOCK * (float)((N + 3u) / 4u) : INFINITY;
        if (is_leaf) {
            for (uint32_t j = 0; j < W; ++j) { c[j] = leaf; h[j] = HOW_LEAF; }
            C->node_k[i] = 0;
            continue;
        }
        const float *cl = C->cost + (size_t)(i + 1) * W, *cr = C->cost + (size_t)bn[i].left_or_first * W;
        float split[8] = {0}; /* [1, W) filled below, [W - 1] read */
        uint8_t split_k[8] = {0};
        for (uint32_t j = 2; j <= W; ++j) {
            split[j - 1] = INFINITY;
            split_k[j - 1] = 1;
            for (uint32_t k = 1; k < j; ++k) {
                const float s = cl[k - 1] + cr[j - k - 1];
                if (s < split[j - 1]) { split[j - 1] = s; split_k[j - 1] = (uint8_t)k; }
            }
        }
        C->node_k[i] = split_k[W - 1];
        const float node = area * WIDE_C_NODE + split[W - 1];
        const float one = leaf <= node ? leaf : node;
        const uint8_t one_how = leaf <= node ? HOW_LEAF : HOW_NODE;
        c[0] = one;
        h[0] = one_how;
        for (uint32_t j = 2; j <= W; ++j) {
            c[j - 1] = split[j - 1] < one ? split[j - 1] : one;
            h[j - 1] = split[j - 1] < one ? (uint8_t)(HOW_SPLIT + split_k[j - 1]) : one_how;
        }
    }
}

/* The slots binary node n stands for with budget j: (node, kind) pairs
 * in the binary tree's left-to-right order, kind KID_NODE, KID_LEAF or
 * KID_LAZY. */
enum { KID_NODE = 0, KID_LEAF = 1, KID_LAZY = 2 };
static void gather(const collapse *C, uint32_t n, uint32_t j, uint32_t *kids, uint8_t *leaf, uint32_t *k)
{
    const uint8_t h = C->how[(size_t)n * C->W + j - 1];
    if (h < HOW_SPLIT) {
        kids[*k] = n;
        leaf[*k] = h == HOW_LEAF ? KID_LEAF : h == HOW_LAZY ? KID_LAZY : KID_NODE;
        ++*k;
        return;
    }
    const uint32_t kl = h - HOW_SPLIT;
    gather(C, n + 1, kl, kids, leaf, k);
    gather(C, C->b->nodes[n].left_or_first, j - kl, kids, leaf, k);
}

/* Triangles [first, first + count) of the binary tree's order as a run of
 * blocks; returns the first block.  The corners come from the mesh, as
 * the binary builds copy them into their tris[] (the same floats). */
static uint32_t make_leaf(collapse *C, uint32_t first, uint32_t count)
{
    const uint32_t b0 = C->num_blocks, nb = (count + 3u) / 4u;
    for (uint32_t k = 0; k < nb; ++k) {
        wide_tri4 *block = &C->blocks[b0 + k];
        for (uint32_t l = 0; l < 4; ++l) {
            const uint32_t i = 4u * k + l;
            if (i < count) {
                const uint32_t prim = C->b->prim_id[first + i];
                const sidx_vec3 p[3] = {sidx_mesh_vertex(C->mesh, prim, 0), sidx_mesh_vertex(C->mesh, prim, 1),
                                        sidx_mesh_vertex(C->mesh, prim, 2)};
                wide_set_lane(block, l, p, prim);
            } else {
                wide_set_lane(block, l, NULL, 0);
            }
        }
    }
    C->blocks[b0 + nb - 1].prim[0] |= WIDE_LAST_BLOCK;
    C->num_blocks += nb;
    return b0;
}

static void set_slot(float *n, uint32_t W, uint32_t s, sidx_aabb bb)
{
    n[0 * W + s] = bb.min.x; n[1 * W + s] = bb.min.y; n[2 * W + s] = bb.min.z;
    n[3 * W + s] = bb.max.x; n[4 * W + s] = bb.max.y; n[5 * W + s] = bb.max.z;
}

/* The wide nodes and blocks make_node(C, n2, ...) will write, added to
 * *inner and *blocks: counted first so that the tree is written straight
 * into arrays of its exact size (no worst-case scratch copied at the end). */
static void count_node(const collapse *C, uint32_t n2, uint32_t *inner, uint32_t *blocks)
{
    const bvh_node *bn = C->b->nodes;
    ++*inner;
    uint32_t kids[8], k = 0;
    uint8_t is_leaf[8];
    if (is_placeholder(&bn[n2])) { /* a lazy root: one unbuilt child */
        kids[k] = n2;
        is_leaf[k++] = KID_LAZY;
    } else if (!bvh_is_leaf(&bn[n2])) {
        const uint32_t kl = C->node_k[n2];
        gather(C, n2 + 1, kl, kids, is_leaf, &k);
        gather(C, bn[n2].left_or_first, C->W - kl, kids, is_leaf, &k);
    } else {
        kids[k] = n2;
        is_leaf[k++] = KID_LEAF;
    }
    for (uint32_t s = 0; s < k; ++s) {
        if (is_leaf[s] == KID_LEAF) *blocks += (C->sub_count[kids[s]] + 3u) / 4u;
        else if (is_leaf[s] == KID_NODE) count_node(C, kids[s], inner, blocks);
    }
}

/* Wide node for binary node n2 (an inner node the costs made a wide node,
 * or the root whatever it is); nodes are numbered in pre-order, so a
 * child's index is above its parent's and refit can run backwards. */
static uint32_t make_node(collapse *C, uint32_t n2, uint32_t depth)
{
    const uint32_t W = C->W;
    const bvh_node *bn = C->b->nodes;
    const uint32_t idx = C->num_inner++;
    if (depth > C->max_depth) C->max_depth = depth;
    uint32_t kids[8], k = 0;
    uint8_t is_leaf[8];
    if (is_placeholder(&bn[n2])) { /* a lazy root: one unbuilt child */
        kids[k] = n2;
        is_leaf[k++] = KID_LAZY;
    } else if (!bvh_is_leaf(&bn[n2])) {
        const uint32_t kl = C->node_k[n2];
        gather(C, n2 + 1, kl, kids, is_leaf, &k);
        gather(C, bn[n2].left_or_first, W - kl, kids, is_leaf, &k);
    } else {
        kids[k] = n2;
        is_leaf[k++] = KID_LEAF;
    }
    float *n = C->nodes + (size_t)idx * 8u * W;
    uint32_t *ch = (uint32_t *)(void *)(n + 6u * W), *id = (uint32_t *)(void *)(n + 7u * W);
    for (uint32_t s = 0; s < W; ++s) {
        set_slot(n, W, s, sidx_aabb_empty());
        ch[s] = WIDE_EMPTY;
        id[s] = UINT32_MAX;
    }
    for (uint32_t s = 0; s < k; ++s) {
        set_slot(n, W, s, bvh_node_box(&bn[kids[s]]));
        if (is_leaf[s] == KID_LAZY) {
            const uint32_t r = bn[kids[s]].count_axis & BVH_COUNT_MASK;
            wide_lazy_rec *rec = &C->lazy_recs[r];
            rec->count = C->sub_count[kids[s]];
            rec->parent = idx;
            rec->depth = depth + 1;
            rec->box = bvh_node_box(&bn[kids[s]]);
            ch[s] = WIDE_LAZY_BIT | r;
            id[s] = r; /* + num_inner + num_leaves once those are known */
            if (depth + 1 > C->max_depth) C->max_depth = depth + 1;
        } else if (is_leaf[s] == KID_NODE) {
            const uint32_t c = make_node(C, kids[s], depth + 1);
            ch[s] = c;
            id[s] = c;
        } else {
            ch[s] = WIDE_LEAF_BIT | make_leaf(C, C->sub_first[kids[s]], C->sub_count[kids[s]]);
            id[s] = C->num_leaves++; /* + num_inner once that is known */
            if (depth + 1 > C->max_depth) C->max_depth = depth + 1;
        }
    }
    return idx;
}

/* ---- build events (after the fact, with the final ids) -------------------------- */

static uint32_t leaf_prims(const wide_bvh *w, uint32_t first_block)
{
    uint32_t c = 0;
    for (const wide_tri4 *block = w->blocks + first_block;; ++block) {
        for (int l = 0; l < 4; ++l) c += (block->prim[l] & WIDE_PRIM_MASK) != WIDE_PAD_PRIM;
        if (block->prim[0] & WIDE_LAST_BLOCK) return c;
    }
}

static sidx_aabb leaf_box(const wide_bvh *w, uint32_t first_block)
{
    sidx_aabb bb = sidx_aabb_empty();
    for (const wide_tri4 *block = w->blocks + first_block;; ++block) {
        for (int l = 0; l < 4; ++l) {
            if ((block->prim[l] & WIDE_PRIM_MASK) == WIDE_PAD_PRIM) continue;
            for (int v = 0; v < 3; ++v) bb = sidx_aabb_grow(bb, sidx_v3(block->v[v][0][l], block->v[v][1][l], block->v[v][2][l]));
        }
        if (block->prim[0] & WIDE_LAST_BLOCK) return bb;
    }
}


static sidx_aabb node_box(const wide_bvh *w, uint32_t i)
{
    const float *n = wide_node(w, i);
    sidx_aabb bb = sidx_aabb_empty();
    for (uint32_t s = 0; s < w->width; ++s)
        if (wide_child(n, w->width)[s] != WIDE_EMPTY) bb = sidx_aabb_union(bb, wide_slot_box(n, w->width, s));
    return bb;
}

/* me: node i's event id (its parent slot's id; the root's: root_id). */
static void emit_build(const sidx_accel *a, const sidx_hook *h, const wide_bvh *w, const uint32_t *count, uint32_t i,
                       uint32_t me, uint32_t parent, uint32_t depth)
{
    const uint32_t W = w->width;
    const float *n = wide_node(w, i);
    SIDX_EMIT(1, h, SIDX_EV_BUILD_NODE, e_.node = me; e_.parent = parent; e_.depth = depth;
              e_.bounds = node_box(w, i); e_.count = count[i]);
    for (uint32_t s = 0; s < W; ++s) {
        const uint32_t c = wide_child(n, W)[s], id = wide_id(n, W)[s];
        if (c == WIDE_EMPTY) continue;
        if (!(c & WIDE_LEAF_BIT) && (c & WIDE_LAZY_BIT)) { /* unbuilt: a node without a decision yet */
            SIDX_EMIT(1, h, SIDX_EV_BUILD_NODE, e_.node = id; e_.parent = me; e_.depth = depth + 1;
                      e_.bounds = wide_slot_box(n, W, s); e_.count = w->lazy->recs[c & ~WIDE_LAZY_BIT].count);
            continue;
        }
        if (!(c & WIDE_LEAF_BIT)) {
            emit_build(a, h, w, count, c, id, me, depth + 1);
            continue;
        }
        const uint32_t np = leaf_prims(w, c & ~WIDE_LEAF_BIT);
        const float cost = (float)np * (a->opt.c_tri > 0.0f ? a->opt.c_tri : 1.0f);
        SIDX_EMIT(1, h, SIDX_EV_BUILD_NODE, e_.node = id; e_.parent = me; e_.depth = depth + 1;
                  e_.bounds = wide_slot_box(n, W, s); e_.count = np);
        /* The event lists the leaf's ids in one run; the blocks interleave them with the
         * vertices, so they are gathered (this runs only with a hook; no memory: no list). */
        uint32_t *ids = sidx__alloc(a, np, sizeof *ids), nid = 0;
        for (const wide_tri4 *block = w->blocks + (c & ~WIDE_LEAF_BIT); ids; ++block) {
            for (int l = 0; l < 4; ++l)
                if ((block->prim[l] & WIDE_PRIM_MASK) != WIDE_PAD_PRIM && nid < np)
                    ids[nid++] = block->prim[l] & WIDE_PRIM_MASK;
            if (block->prim[0] & WIDE_LAST_BLOCK) break;
        }
        SIDX_EMIT(1, h, SIDX_EV_BUILD_LEAF, e_.node = id; e_.depth = depth + 1; e_.count = np; e_.cost = cost;
                  e_.reason = SIDX_LEAF_FEW_PRIMS; e_.bounds = wide_slot_box(n, W, s); e_.prims = ids);
        sidx__free(a, ids);
    }
}

/* Triangles below each inner node (children have higher indices). */
static void inner_counts(const wide_bvh *w, uint32_t *count)
{
    for (uint32_t i = w->num_inner; i-- > 0;) {
        const float *n = wide_node(w, i);
        uint32_t c = 0;
        for (uint32_t s = 0; s < w->width; ++s) {
            const uint32_t ch = wide_child(n, w->width)[s];
            if (ch == WIDE_EMPTY) continue;
            c += (ch & WIDE_LEAF_BIT)  ? leaf_prims(w, ch & ~WIDE_LEAF_BIT)
                 : (ch & WIDE_LAZY_BIT) ? w->lazy->recs[ch & ~WIDE_LAZY_BIT].count
                                        : count[ch];
        }
        count[i] = c;
    }
}

/* ---- SAH cost and refit ---------------------------------------------------------- */

static double wide_sah(const wide_bvh *w, float c_trav, float c_tri)
{
    const double root = sidx_aabb_area(w->bounds);
    if (!(root > 0.0)) return (double)w->num_prims * c_tri;
    double s = 0.0;
    for (uint32_t i = 0; i < w->num_inner; ++i) {
        const float *n = wide_node(w, i);
        s += c_trav * sidx_aabb_area(node_box(w, i)) / root;
        for (uint32_t k = 0; k < w->width; ++k) {
            const uint32_t ch = wide_child(n, w->width)[k];
            if (ch == WIDE_EMPTY || !(ch & WIDE_LEAF_BIT)) continue;
            s += c_tri * (double)leaf_prims(w, ch & ~WIDE_LEAF_BIT) * sidx_aabb_area(wide_slot_box(n, w->width, k)) /
                 root;
        }
    }
    return s;
}

static float opt_or(float v, float def) { return v > 0.0f ? v : def; }

static sidx_status wide_refit(sidx_accel *a, sidx_error *err)
{
    wide_bvh *w = a->impl;
    if (w && w->lazy) return sidx__fail(err, SIDX_ERR_UNSUPPORTED, "%s: a lazy tree cannot be refitted; rebuild it", a->name);
    if (!w || w->num_inner == 0) return SIDX_OK;
    const sidx_mesh *m = a->mesh;
    for (uint32_t k = 0; k < w->num_blocks; ++k) {
        wide_tri4 *block = &w->blocks[k];
        for (int l = 0; l < 4; ++l) {
            const uint32_t id = block->prim[l] & WIDE_PRIM_MASK;
            if (id == WIDE_PAD_PRIM) continue;
            for (int v = 0; v < 3; ++v) {
                const sidx_vec3 p = sidx_mesh_vertex(m, id, v);
                block->v[v][0][l] = p.x;
                block->v[v][1][l] = p.y;
                block->v[v][2][l] = p.z;
            }
        }
    }
    for (uint32_t i = w->num_inner; i-- > 0;) {
        float *n = w->nodes + (size_t)i * 8u * w->width;
        for (uint32_t s = 0; s < w->width; ++s) {
            const uint32_t ch = wide_child(n, w->width)[s];
            if (ch == WIDE_EMPTY) continue;
            set_slot(n, w->width, s, (ch & WIDE_LEAF_BIT) ? leaf_box(w, ch & ~WIDE_LEAF_BIT) : node_box(w, ch));
        }
    }
    w->bounds = node_box(w, 0);
    w->sah_cost = wide_sah(w, opt_or(a->opt.c_trav, 1.0f), opt_or(a->opt.c_tri, 1.0f));
    return SIDX_OK;
}

/* ---- build ------------------------------------------------------------------------ */

static void wide_free(const sidx_accel *a, wide_bvh *w)
{
    if (!w) return;
    if (w->lazy) {
        for (uint32_t r = 0; r < w->lazy->num_recs; ++r) wide_free(a, sidx__lazy_peek(&w->lazy->life, r));
        sidx__free(a, w->lazy->life.parts);
        sidx__free(a, w->lazy->recs);
        sidx__sbvh_lazy_free(a, w->lazy->sb);
        sidx__free(a, w->lazy);
    }
    sidx__free(a, w->nodes_mem);
    sidx__free(a, w->blocks_mem);
    sidx__free(a, w);
}

static void *aligned_in(void *mem, uintptr_t align)
{
    return (void *)(((uintptr_t)mem + align - 1u) & ~(align - 1u));
}

/* Node and block arrays of WIDE_HUGE_MIN bytes or more are whole 2 MB
 * pages, 2 MB-aligned, offered to the kernel as transparent huge pages
 * (madvise(MADV_HUGEPAGE), before the first write, so the pages are huge
 * from the first fault where the system allows it; elsewhere the advice
 * is ignored and nothing changes): at millions of triangles a diffuse
 * ray's nodes and blocks lie on pages far apart, and one 2 MB page maps
 * in one TLB entry what takes 512 small ones (docs/performance.md, "Wide
 * BVHs": 4M-triangle height field, diffuse rays).  Smaller arrays keep
 * 64-byte alignment (a node is whole cache lines) and small pages. */
#define WIDE_HUGE_PAGE ((size_t)2u << 20)
#define WIDE_HUGE_MIN ((size_t)8u << 20)

static void *alloc_array(const sidx_accel *a, size_t bytes, void **mem)
{
    const int huge = bytes >= WIDE_HUGE_MIN;
    const size_t align = huge ? WIDE_HUGE_PAGE : 64u;
    if (huge) bytes = (bytes + WIDE_HUGE_PAGE - 1u) & ~(WIDE_HUGE_PAGE - 1u); /* whole huge pages */
    *mem = sidx__alloc(a, bytes + align, 1);
    if (!*mem) return NULL;
    void *p = aligned_in(*mem, align);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (huge) (void)madvise(p, bytes, MADV_HUGEPAGE);
#endif
    return p;
}

/* Collapses binary tree b into w (width, isa and kernels already set):
 * its nodes, blocks, counts and bounds.  lazy_recs: a lazy top's records,
 * which its placeholders fill in (NULL for a tree without any).  Leaf
 * event ids follow the inner nodes', unbuilt children's the leaves'.  On
 * failure (SIDX_ERR_NOMEM) w's arrays are left for wide_free. */
static sidx_status collapse_into(const sidx_accel *a, const bvh *b, wide_bvh *w, wide_lazy_rec *lazy_recs)
{
    const uint32_t W = w->width, nn = b->num_nodes;
    if (nn == 0) return SIDX_OK;
    sidx_status s = SIDX_ERR_NOMEM;
    uint32_t *sub = sidx__alloc(a, 2u * (size_t)nn, sizeof *sub);
    float *dp_cost = sidx__alloc(a, (size_t)nn * W, sizeof *dp_cost);
    uint8_t *dp_how = sidx__alloc(a, (size_t)nn * (W + 1u), 1);
    if (!sub || !dp_cost || !dp_how) goto done;
    uint32_t *sub_count = sub, *sub_first = sub + nn;
    for (uint32_t i = nn; i-- > 0;) {
        const bvh_node *n = &b->nodes[i];
        if (is_placeholder(n)) {
            sub_count[i] = n->left_or_first;
            sub_first[i] = 0;
        } else if (bvh_is_leaf(n)) {
            sub_count[i] = bvh_count(n);
            sub_first[i] = n->left_or_first;
        } else {
            sub_count[i] = sub_count[i + 1] + sub_count[n->left_or_first];
            sub_first[i] = sub_first[i + 1];
        }
    }
    collapse C = {b,    a->mesh, W, sub_count, sub_first, dp_cost, dp_how, dp_how + (size_t)nn * W, NULL, 0, NULL, 0,
                  0,    0,       lazy_recs};
    collapse_costs(&C);
    sidx__free(a, dp_cost); /* the choices (how, node_k) are all the rest reads */
    dp_cost = NULL;
    uint32_t num_inner = 0, num_blocks = 0;
    count_node(&C, 0, &num_inner, &num_blocks);
    /* Exact-size, aligned arrays: a node is whole cache lines. */
    w->nodes = alloc_array(a, (size_t)num_inner * 8u * W * sizeof(float), &w->nodes_mem);
    w->blocks = alloc_array(a, (size_t)num_blocks * sizeof(wide_tri4), &w->blocks_mem);
    if (!w->nodes || (num_blocks && !w->blocks)) goto done;
    C.nodes = w->nodes;
    C.blocks = w->blocks;
    make_node(&C, 0, 0);
    w->num_inner = C.num_inner;
    w->num_blocks = C.num_blocks;
    w->num_leaves = C.num_leaves;
    w->max_depth = C.max_depth;
    /* Leaf event ids come after the inner nodes, unbuilt children's after the leaves. */
    for (uint32_t i = 0; i < w->num_inner; ++i) {
        float *n = w->nodes + (size_t)i * 8u * W;
        uint32_t *ch = (uint32_t *)(void *)(n + 6u * W), *id = (uint32_t *)(void *)(n + 7u * W);
        for (uint32_t k = 0; k < W; ++k) {
            if (ch[k] == WIDE_EMPTY) continue;
            if (ch[k] & WIDE_LEAF_BIT) id[k] += w->num_inner;
            else if (ch[k] & WIDE_LAZY_BIT) {
                id[k] += w->num_inner + w->num_leaves;
                lazy_recs[ch[k] & ~WIDE_LAZY_BIT].id = id[k];
            }
        }
    }
    w->bounds = node_box(w, 0);
    s = SIDX_OK;
done:
    sidx__free(a, sub);
    sidx__free(a, dp_cost);
    sidx__free(a, dp_how);
    return s;
}

/* ---- node order for large trees ---------------------------------------------------
 *
 * make_node stores the nodes depth-first: a node's first child follows
 * it, but its other children lie past whole subtrees, so at millions of
 * triangles a ray's path steps to a new 4 KB page (and DRAM row) at
 * almost every level.  wide_order regroups them into treelets of
 * WIDE_TREELET_BYTES (one 4 KB page): from a treelet's root it keeps
 * taking, among the children of the nodes taken, the one of largest
 * surface area (the most likely to be entered: the SAH's probability),
 * as in Yoon & Manocha 2006 ("Cache-efficient layouts of bounding volume
 * hierarchies"); the children left over root the next treelets, laid out
 * depth-first.  The leaf blocks then follow the new node order, in slot
 * order, so the leaves of a treelet share its pages too.  Only storage
 * moves: boxes, slots and event ids stay, so every hit and event is the
 * same; the order stays top-down (a child after its parent), which
 * refit and the event pass rely on.  In place (one cycle walk per
 * array): a second copy of a 16.8M-triangle tree would add its size to
 * the build's peak.
 *
 * Not the default: it cuts the 4 KB pages a ray touches by 17 to 26%,
 * but not one cache line, and with the arrays on 2 MB pages
 * (alloc_array) it bought no time at 1M, 4.2M or 16.8M triangles
 * (docs/performance.md, "Node order at scale").  SIDX_WIDE_ORDER=treelets
 * in the environment turns it on (measurements, tests). */
#define WIDE_TREELET_BYTES 4096u

/* Several rays in flight in the stream entry (bvh_wide_walk.h, the
 * flight_ walks): they pay where the walk waits on memory and cost where
 * the tree is in cache (docs/performance.md, "Several rays in flight"),
 * so they are taken for a tree whose nodes and blocks take at least
 * WIDE_INFLIGHT_BYTES.  Measured with bvh8, the crossover lies between
 * the trees of Sponza (4.7 MiB) and the bunny (3.6 MiB), whose primary
 * rays are slower in flight, and that of the 262k-triangle height field
 * (13.3 MiB), where both ray kinds are faster: 8 MiB between them, a few
 * times the L2 caches.  Only bvh8 was measured; bvh4 takes
 * them when asked.  SIDX_STREAM_INFLIGHT=on or off in the environment at
 * build forces the choice (tests, measurements). */
#define WIDE_INFLIGHT_BYTES (8u << 20)

static int want_inflight(const wide_bvh *w)
{
    const char *env = getenv("SIDX_STREAM_INFLIGHT");
    if (env && !strcmp(env, "on")) return 1;
    if (env && !strcmp(env, "off")) return 0;
    const size_t bytes = (size_t)w->num_inner * (8u * w->width * sizeof(float)) + (size_t)w->num_blocks * sizeof(wide_tri4);
    return w->width == 8 && bytes >= WIDE_INFLIGHT_BYTES;
}

static int want_order(void)
{
    const char *env = getenv("SIDX_WIDE_ORDER");
    return env && !strcmp(env, "treelets");
}

/* Moves the n items of `size` bytes in arr so that item i goes to
 * to[i]; done[] (n bytes, zero) marks the items placed; tmp holds two. */
static void permute(void *arr, size_t size, uint32_t n, const uint32_t *to, uint8_t *done, unsigned char *tmp)
{
    unsigned char *A = arr, *hold = tmp, *spare = tmp + size;
    for (uint32_t i = 0; i < n; ++i) {
        if (done[i] || to[i] == i) continue;
        memcpy(hold, A + (size_t)i * size, size);
        uint32_t j = i;
        do { /* hold is item j: put it at to[j], pick up what was there */
            const uint32_t d = to[j];
            memcpy(spare, A + (size_t)d * size, size);
            memcpy(A + (size_t)d * size, hold, size);
            done[j] = 1;
            unsigned char *t = hold;
            hold = spare;
            spare = t;
            j = d;
        } while (j != i);
    }
}

/* Reorders w's nodes into treelets and its blocks after them (above).
 * SIDX_ERR_NOMEM leaves w as it was. */
static sidx_status wide_order(const sidx_accel *a, wide_bvh *w)
{
    const uint32_t W = w->width, n = w->num_inner, nb = w->num_blocks;
    const uint32_t K = WIDE_TREELET_BYTES / (8u * W * (uint32_t)sizeof(float)); /* nodes per treelet */
    const size_t node_bytes = 8u * W * sizeof(float);
    uint32_t *to = sidx__alloc(a, (size_t)n + nb, sizeof *to), *stack = sidx__alloc(a, n, sizeof *stack);
    uint32_t *front = sidx__alloc(a, (size_t)K * W, sizeof *front);
    float *front_area = sidx__alloc(a, (size_t)K * W, sizeof *front_area);
    uint8_t *done = sidx__alloc(a, (size_t)(n > nb ? n : nb), 1);
    unsigned char *tmp = sidx__alloc(a, 2, node_bytes > sizeof(wide_tri4) ? node_bytes : sizeof(wide_tri4));
    if (!to || !stack || !front || !front_area || !done || !tmp) {
        sidx__free(a, to); sidx__free(a, stack); sidx__free(a, front); sidx__free(a, front_area);
        sidx__free(a, done); sidx__free(a, tmp);
        return SIDX_ERR_NOMEM;
    }
    uint32_t *bto = to + n;
    /* nodes: treelets, depth-first (a stack of treelet roots) */
    uint32_t next = 0, sp = 0, bnext = 0;
    stack[sp++] = 0;
    while (sp) {
        uint32_t nf = 1, taken = 0;
        front[0] = stack[--sp];
        front_area[0] = 0.0f; /* alone: taken whatever its area */
        while (nf && taken < K) {
            uint32_t best = 0; /* the frontier node of largest area */
            float best_area = -1.0f;
            for (uint32_t f = 0; f < nf; ++f)
                if (front_area[f] > best_area) { best_area = front_area[f]; best = f; }
            const uint32_t v = front[best];
            --nf;
            front[best] = front[nf];
            front_area[best] = front_area[nf];
            to[v] = next++;
            ++taken;
            const float *vn = wide_node(w, v);
            const uint32_t *ch = wide_child(vn, W);
            for (uint32_t s = 0; s < W; ++s)
                if (ch[s] != WIDE_EMPTY && !(ch[s] & (WIDE_LEAF_BIT | WIDE_LAZY_BIT))) {
                    front_area[nf] = sidx_aabb_area(wide_slot_box(vn, W, s)); /* the child's box */
                    front[nf++] = ch[s];
                }
        }
        /* the rest root treelets of their own; pushed last-first so the walk meets them in slot order */
        while (nf) stack[sp++] = front[--nf];
    }
    /* blocks: each leaf's run in the new node order, slot by slot */
    uint32_t *by_new = stack; /* old index of the node at each new place (the stack is empty now) */
    for (uint32_t i = 0; i < n; ++i) by_new[to[i]] = i;
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t *ch = wide_child(wide_node(w, by_new[k]), W);
        for (uint32_t s = 0; s < W; ++s) {
            if (ch[s] == WIDE_EMPTY || !(ch[s] & WIDE_LEAF_BIT)) continue;
            for (uint32_t b = ch[s] & ~WIDE_LEAF_BIT;; ++b) {
                bto[b] = bnext++;
                if (w->blocks[b].prim[0] & WIDE_LAST_BLOCK) break;
            }
        }
    }
    /* the children's references, then the two arrays */
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t *ch = (uint32_t *)(void *)(w->nodes + (size_t)i * 8u * W + 6u * W);
        for (uint32_t s = 0; s < W; ++s) {
            if (ch[s] == WIDE_EMPTY || (!(ch[s] & WIDE_LEAF_BIT) && (ch[s] & WIDE_LAZY_BIT))) continue;
            ch[s] = (ch[s] & WIDE_LEAF_BIT) ? WIDE_LEAF_BIT | bto[ch[s] & ~WIDE_LEAF_BIT] : to[ch[s]];
        }
    }
    memset(done, 0, n);
    permute(w->nodes, node_bytes, n, to, done, tmp);
    memset(done, 0, nb);
    permute(w->blocks, sizeof(wide_tri4), nb, bto, done, tmp);
    sidx__free(a, to); sidx__free(a, stack); sidx__free(a, front); sidx__free(a, front_area);
    sidx__free(a, done); sidx__free(a, tmp);
    return SIDX_OK;
}

static void bin_free(const sidx_accel *a, bvh *b)
{
    if (!b) return;
    sidx__free(a, b->nodes_mem);
    sidx__free(a, b->prim_id);
    sidx__free(a, b->tris);
    sidx__free(a, b);
}

static void *expand_part(void *owner, uint32_t r, const sidx_hook *hook, sidx__lazy_made *made);

static sidx_status wide_build(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    const uint32_t W = a->variant == 8 ? 8u : 4u;
    const sidx_hook *hook = a->opt.hook;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = sidx_mesh_bounds(m));

    /* Lazy (opt.lazy): the spatial-split tree stops at its subtrees of at
     * most opt.lazy references (see "lazy builds" below); the plain
     * binned tree (opt.no_spatial_splits) and an optimised one are built
     * whole. */
    const uint32_t lazy_max = a->opt.lazy == 1 ? SIDX_LAZY_DEFAULT : a->opt.lazy;
    const int want_lazy = lazy_max > WIDE_MAX_LEAF && !a->opt.no_spatial_splits && !(a->opt.optimize_ms > 0.0f) &&
                          m->num_triangles > 0;
    sidx__sbvh_lazy *sb = NULL;

    /* The binary tree, silently (its node ids are not ours), on
     * opt.threads threads either way (bvh_spatial.c, parallel.c). */
    sidx_accel bin = *a;
    bin.variant = BVH_BINNED;
    bin.opt.hook = NULL;
    bin.opt.lazy = 0;
    bin.impl = NULL;
    sidx_status s = a->opt.no_spatial_splits
                        ? sidx__bvh_vtable.build(&bin, err)
                        : sidx__bvh_build_spatial(&bin, want_lazy ? lazy_max : 0, WIDE_MAX_LEAF, &sb, err);
    if (s != SIDX_OK) return s;
    const int lazy = sidx__sbvh_lazy_count(sb) > 0;
    /* the plain build optimised its tree already (bvh_build.c) */
    if (!a->opt.no_spatial_splits && !lazy) sidx__bvh_optimize(&bin, bin.impl);
    bvh *b = bin.impl;
    /* The leaves take their corners from the mesh: a binary tree's copy of
     * them (bvh_build.c's tris[]) is not needed here. */
    sidx__free(&bin, b->tris);
    b->tris = NULL;

    s = SIDX_ERR_NOMEM;
    uint32_t *counts = NULL;
    wide_bvh *w = sidx__calloc(a, 1, sizeof *w);
    if (!w) goto fail;
    w->width = W;
    w->num_prims = b->num_prims;
    w->isa = sidx__wide_pick_isa(W);
    w->bounds = sidx_aabb_empty();
    if (lazy) {
        w->lazy = sidx__calloc(a, 1, sizeof *w->lazy);
        if (!w->lazy) goto fail;
        w->lazy->sb = sb;
        sb = NULL;
        w->lazy->recs = sidx__calloc(a, sidx__sbvh_lazy_count(w->lazy->sb), sizeof *w->lazy->recs);
        w->lazy->life.parts = sidx__calloc(a, sidx__sbvh_lazy_count(w->lazy->sb), sizeof *w->lazy->life.parts);
        if (!w->lazy->recs || !w->lazy->life.parts) goto fail;
        w->lazy->num_recs = sidx__sbvh_lazy_count(w->lazy->sb);
    }
    set_kernels(w, a->opt.tri);
    if ((s = collapse_into(a, b, w, lazy ? w->lazy->recs : NULL)) != SIDX_OK) goto fail;
    /* a lazy top stays depth-first: its unbuilt children are filled in by parent index */
    if (!lazy && w->num_inner && want_order() && (s = wide_order(a, w)) != SIDX_OK) goto fail;
    w->inflight = !lazy && want_inflight(w);
    s = SIDX_ERR_NOMEM;
    if (lazy) {
        wide_lazy *L = w->lazy;
        /* the parts' marks (WIDE_PART_BIT) need the top's indices below 2^29 */
        s = SIDX_ERR_LIMIT;
        if (w->num_inner >= WIDE_PART_BIT || w->num_blocks >= WIDE_PART_BIT) goto fail;
        s = SIDX_ERR_NOMEM;
        /* event ids: an unbuilt child has one until built (its part's root keeps it) */
        L->next_id = w->num_inner + w->num_leaves + L->num_recs;
        sidx__lazy_init(&L->life, L->life.parts, L->num_recs, expand_part, a);
        for (uint32_t r = 0; r < L->num_recs; ++r) sidx__lazy_defer(&L->life, r, L->recs[r].count);
        w->sah_cost = 0.0; /* not applicable until every subtree is built */
    } else {
        w->sah_cost = wide_sah(w, opt_or(a->opt.c_trav, 1.0f), opt_or(a->opt.c_tri, 1.0f));
    }
    if (hook && hook->fn && w->num_inner) {
        counts = sidx__alloc(a, w->num_inner, sizeof *counts);
        if (!counts) goto fail;
        inner_counts(w, counts);
        emit_build(a, hook, w, counts, 0, 0, UINT32_MAX, 0);
    }
    SIDX_EMIT(1, hook, SIDX_EV_NOTE,
              e_.text = w->isa == WIDE_ISA_AVX512 ? "wide BVH: AVX-512 kernels (8 boxes per pass, 4 triangles per pass)"
                        : w->isa == WIDE_ISA_AVX2  ? "wide BVH: AVX2 kernels (8 boxes per pass, 4 triangles per pass)"
                        : w->isa == WIDE_ISA_SSE41 ? "wide BVH: SSE4.1 kernels (4 boxes per pass, 4 triangles per pass)"
                                                   : "wide BVH: portable scalar kernels");
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_END, e_.node = w->num_inner + w->num_leaves; e_.count = w->num_prims;
              e_.depth = w->max_depth);
    sidx__free(a, counts);
    sidx__sbvh_lazy_free(a, sb); /* a lazy build that left nothing unbuilt: its empty record list */
    sidx__bvh_vtable.destroy(&bin);
    a->impl = w;
    a->lazy = (unsigned char)(lazy != 0);
    a->fills_uv = a->fills_ng = 1; /* the walk sets u, v, ng from its leaf blocks (bvh_wide_walk.h) */
    return SIDX_OK;

fail:
    sidx__free(a, counts);
    sidx__sbvh_lazy_free(a, sb);
    wide_free(a, w);
    sidx__bvh_vtable.destroy(&bin);
    a->impl = NULL;
    if (s == SIDX_ERR_LIMIT) return sidx__fail(err, s, "%s: the lazy tree's top is too large", a->name);
    return sidx__fail(err, s, "%s: out of memory", a->name);
}

/* ---- lazy builds ------------------------------------------------------------------ */

/* lazy.c's expand function (lazy.h): builds part r — record r's subtree,
 * the eager build's, as a wide tree of its own whose children are marked
 * WIDE_PART_BIT (bvh_wide_internal.h) — and returns it; NULL when memory
 * runs out (everything it took is given back).  Called once at a time per
 * part (lazy.c claims it). */
static void *expand_part(void *owner, uint32_t r, const sidx_hook *hook, sidx__lazy_made *made)
{
    const sidx_accel *a = owner;
    const wide_bvh *w = a->impl;
    wide_lazy *L = w->lazy;
    const wide_lazy_rec *rec = &L->recs[r];
    bvh *b = NULL;
    uint32_t *counts = NULL;
    wide_bvh *sub = sidx__calloc(a, 1, sizeof *sub);
    if (!sub || sidx__sbvh_lazy_build(a, L->sb, r, &b) != SIDX_OK) goto fail;
    sub->width = w->width;
    sub->isa = w->isa;
    sub->num_prims = b->num_prims;
    sub->bounds = sidx_aabb_empty();
    set_kernels(sub, a->opt.tri);
    if (collapse_into(a, b, sub, NULL) != SIDX_OK) goto fail;
    /* the marks need its indices below 2^29: far beyond any part's memory */
    if (sub->num_inner >= WIDE_PART_BIT || sub->num_blocks >= WIDE_PART_BIT) goto fail;
    if (hook && hook->fn && (hook->mask == 0 || (hook->mask & SIDX_EVMASK_BUILD))) {
        counts = sidx__alloc(a, sub->num_inner, sizeof *counts);
        if (!counts) goto fail;
    }
    bin_free(a, b);
    b = NULL;
    /* Event ids: the root is the unbuilt child it replaces, the rest are new. */
    const uint32_t base = __atomic_fetch_add(&L->next_id, sub->num_inner + sub->num_leaves, __ATOMIC_RELAXED);
    for (uint32_t i = 0; i < sub->num_inner; ++i) {
        float *n = sub->nodes + (size_t)i * 8u * sub->width;
        uint32_t *id = (uint32_t *)(void *)(n + 7u * sub->width);
        for (uint32_t k = 0; k < sub->width; ++k)
            if (wide_child(n, sub->width)[k] != WIDE_EMPTY) id[k] += base;
    }
    sub->sah_cost = wide_sah(sub, opt_or(a->opt.c_trav, 1.0f), opt_or(a->opt.c_tri, 1.0f));
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_LAZY_EXPAND, e_.node = rec->id; e_.parent = rec->parent; e_.depth = rec->depth;
              e_.count = rec->count; e_.bounds = rec->box);
    if (counts) {
        inner_counts(sub, counts);
        emit_build(a, hook, sub, counts, 0, rec->id, rec->parent, rec->depth);
        sidx__free(a, counts);
    }
    /* the marks, last: what the events above read is the plain tree */
    for (uint32_t i = 0; i < sub->num_inner; ++i) {
        uint32_t *ch = (uint32_t *)(void *)(sub->nodes + (size_t)i * 8u * sub->width + 6u * sub->width);
        for (uint32_t k = 0; k < sub->width; ++k)
            if (ch[k] != WIDE_EMPTY) ch[k] |= WIDE_PART_BIT;
    }
    sidx__sbvh_lazy_release(a, L->sb, r); /* its references are in the blocks now */
    __atomic_fetch_add(&L->part_leaves, sub->num_leaves, __ATOMIC_RELAXED);
    made->refs = rec->count;
    made->bytes = sizeof *sub + (size_t)sub->num_inner * 8u * sub->width * sizeof(float) +
                  (size_t)sub->num_blocks * sizeof(wide_tri4);
    made->depth = rec->depth + sub->max_depth;
    return sub;

fail:
    sidx__free(a, counts);
    bin_free(a, b);
    wide_free(a, sub);
    return NULL;
}

static void wide_destroy(sidx_accel *a)
{
    wide_free(a, a->impl);
    a->impl = NULL;
}

static void wide_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const wide_bvh *w = a->impl;
    if (!w) return;
    s->nodes = w->num_inner + w->num_leaves;
    s->leaves = w->num_leaves;
    s->max_depth = w->max_depth;
    if (w->lazy) {
        /* a part's root is the unbuilt child it replaces, counted already;
         * every other node it made took an event id */
        const wide_lazy *L = w->lazy;
        const sidx__lazy_counts c = sidx__lazy_counts_get(&L->life);
        s->nodes = __atomic_load_n(&L->next_id, __ATOMIC_RELAXED) - c.built;
        s->leaves += __atomic_load_n(&L->part_leaves, __ATOMIC_RELAXED);
        s->max_depth = c.max_depth > w->max_depth ? c.max_depth : w->max_depth;
        s->unbuilt = c.unbuilt;
        s->unbuilt_prims = c.unbuilt_refs;
    }
    s->prim_refs = w->num_prims;
    s->bytes = sizeof *w + (size_t)w->num_inner * 8u * w->width * sizeof(float) +
               (size_t)w->num_blocks * sizeof(wide_tri4);
    s->sah_cost = w->sah_cost;
    if (w->lazy) { /* the records and parts, and the subtrees built so far */
        s->bytes += sizeof *w->lazy + (size_t)w->lazy->num_recs * (sizeof *w->lazy->recs + sizeof *w->lazy->life.parts) +
                    sidx__lazy_counts_get(&w->lazy->life).built_bytes;
        for (uint32_t r = 0; r < w->lazy->num_recs; ++r) {
            const wide_bvh *sub = sidx__lazy_peek(&w->lazy->life, r);
            if (sub) s->prim_refs += sub->num_prims;
        }
    }
    s->mean_leaf_prims = s->leaves ? (double)s->prim_refs / s->leaves : 0.0;
    s->empty_leaves = 0;
}

static void wide_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    const wide_bvh *w = a->impl;
    sidx__walk_intersect(&w->walks[(q->flags & SIDX_QUERY_UV) != 0], a, r, q, hit);
}

static int wide_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    const wide_bvh *w = a->impl;
    return sidx__walk_occluded(&w->walks[0], a, r, q);
}

const sidx_accel_vtable sidx__wide_vtable = {wide_build, wide_intersect, wide_occluded,
                                             wide_stats, wide_destroy, wide_refit};

int sidx__is_wide(const sidx_accel *a) { return a && a->vt == &sidx__wide_vtable; }
