/* packet.c — coherent ray packets and frustum culling over the binary BVH
 * (sidx/packet.h explains the method and cites the papers).
 *
 * Layout: a packet holds its rays in structure-of-arrays form, padded to
 * groups of 8 lanes; a padding lane has best = −inf so every box and every
 * triangle misses it.  The kernels that test one box or one triangle
 * against a group of 8 rays exist twice: a scalar loop, the reference
 * (simd_packet_scalar.h), and AVX2 doing the same arithmetic
 * (simd_packet_avx2.h; target attribute, chosen at run time); the
 * frustum's kernels are SSE2 (simd_packet_sse.h) with the same
 * reference.  The walk is written once and compiled twice
 * (packet_walk_avx2, packet_walk_generic); in the generic copy the kernels
 * are called per group, which costs a few cycles against 8 slab tests.
 *
 * Correctness is the single-ray walk's: each lane keeps its own best t,
 * box tests are the robust slab test of bvh_slab (far planes times the
 * Ize factor) against that lane's [tmin, best], triangles the watertight
 * test with that lane's shear constants, and a group whose edge function
 * hits exactly 0 in some lane redoes that lane with the scalar test (which
 * recomputes it in double). */
#include "bvh_internal.h"
#include "hit.h"
#include "bvh_wide_internal.h"
#include "packet_internal.h"
#include "simd_isa.h"
#ifdef SIDX_SIMD_X86
#define PKT_X86 1
#endif

#define GROUP_LANES 8u                             /* rays per group */
#define MAX_GROUPS (SIDX_PACKET_MAX / GROUP_LANES) /* groups per packet */
#define STACK (2u * BVH_DEPTH_LIMIT + 2u)

typedef struct packet {
    _Alignas(32) float org_x[SIDX_PACKET_MAX], org_y[SIDX_PACKET_MAX], org_z[SIDX_PACKET_MAX];
    _Alignas(32) float inv_x[SIDX_PACKET_MAX], inv_y[SIDX_PACKET_MAX], inv_z[SIDX_PACKET_MAX]; /* 1/d */
    _Alignas(32) float inv_far_x[SIDX_PACKET_MAX], inv_far_y[SIDX_PACKET_MAX],
        inv_far_z[SIDX_PACKET_MAX]; /* 1/d · Ize */
    _Alignas(32) float tmin[SIDX_PACKET_MAX], best[SIDX_PACKET_MAX];
    /* watertight test, permuted by the (common) kx, ky, kz */
    _Alignas(32) float org_kx[SIDX_PACKET_MAX], org_ky[SIDX_PACKET_MAX], org_kz[SIDX_PACKET_MAX];
    _Alignas(32) float sx[SIDX_PACKET_MAX], sy[SIDX_PACKET_MAX], sz[SIDX_PACKET_MAX];
    uint32_t prim[SIDX_PACKET_MAX];
    uint32_t n, ngroups;
    int kx, ky, kz, uniform_k;
    uint32_t near_i[3], far_i[3]; /* plane indices in a bvh_node read as float[8], from the common signs */
    uint8_t sign[3];
    int anyhit;
    const sidx_ray *rays;
    /* frustum: 4 inward plane normals through the common origin, the apex */
    int frustum;
    float apex[3], plane_n[4][3], plane_l1[4]; /* plane normals and their L1 norms */
#ifdef SIDX_SIMD_SSE2
    /* the same, one plane per lane (simd_packet_sse.h); plane_pos_lanes: normal component >= 0 */
    sidx__f32x4 plane_n_lanes[3], plane_pos_lanes[3], plane_l1_lanes;
#endif
} packet;

typedef struct walkopt {
    const sidx_accel *a;
    const bvh *b;
    float scale;
    int avx, simd_tri, frustum;
    uint32_t frustum_depth;
    sidx_packet_stats *stats;
} walkopt;

/* A deferred node: its index, the first group of rays that may hit it
 * (the groups before it missed its parent) and its depth. */
typedef struct pstack {
    uint32_t node, first_group, depth;
} pstack;

/* ---- kernels: one box / one triangle against 8 rays; the frustum ----------------
 * One header per instruction set: simd_packet_scalar.h (the reference),
 * simd_packet_sse.h (the frustum, SSE2), simd_packet_avx2.h (box and
 * triangle, AVX2).  The choice is made here, once. */

#include "simd_packet_scalar.h"
#ifdef SIDX_SIMD_SSE2
#include "simd_packet_sse.h"
#endif
#ifdef PKT_X86
#include "simd_packet_avx2.h"
#else
/* No AVX2 kernels here, and avx is always 0: the walk's avx branches,
 * which name them, are dead; the reference stands in. */
static unsigned box8_avx2(const packet *pkt, uint32_t group, const float planes[6])
{
    return box8_scalar(pkt, group, planes);
}
static void tri8_avx2(const walkopt *walk, packet *pkt, uint32_t group, const bvh_tri *tri, uint32_t prim)
{
    tri8_scalar(walk, pkt, group, tri, prim);
}
#endif

/* The frustum's kernels: SSE2 wherever it is there (every x86-64). */
#ifdef SIDX_SIMD_SSE2
static int frustum_overlap(const packet *pkt, const bvh_node *n) { return frustum_overlap_sse(pkt, n); }
static SIDX_INLINE int frustum_rays_inside(const packet *pkt, const sidx_ray *rays, uint32_t n, const float len2[4])
{
    return frustum_rays_inside_sse(pkt, rays, n, len2);
}
static SIDX_INLINE void frustum_lanes(packet *pkt) { frustum_lanes_sse(pkt); }
#else
static int frustum_overlap(const packet *pkt, const bvh_node *n) { return frustum_overlap_scalar(pkt, n); }
static SIDX_INLINE int frustum_rays_inside(const packet *pkt, const sidx_ray *rays, uint32_t n, const float len2[4])
{
    return frustum_rays_inside_scalar(pkt, rays, n, len2);
}
static SIDX_INLINE void frustum_lanes(packet *pkt) { (void)pkt; /* the reference reads the planes as they are */ }
#endif

/* ---- frustum ---------------------------------------------------------------------- */

/* Planes through the common origin spanned by neighbouring corner rays,
 * oriented inward; kept only if every ray of the packet lies inside them
 * (n·d >= −1e-6 |n||d|), which the margin in frustum_overlap (1e-5 times
 * distance plus box size) then covers: a culled box is at least that far
 * outside, a ray at most 1e-6 of its distance. */
static void frustum_setup(packet *pkt, const sidx_ray *rays, uint32_t n, uint32_t w)
{
    pkt->frustum = 0;
    if (w == 0 || n % w || n < 4 || w < 2 || n / w < 2) return;
    const sidx_vec3 corner[4] = {rays[0].dir, rays[w - 1].dir, rays[n - 1].dir, rays[n - w].dir}; /* around the tile */
    const sidx_vec3 mid = sidx_v3_add(sidx_v3_add(corner[0], corner[1]), sidx_v3_add(corner[2], corner[3]));
    float len2[4];
    for (int plane = 0; plane < 4; ++plane) {
        sidx_vec3 normal = sidx_v3_cross(corner[plane], corner[(plane + 1) % 4]);
        if (sidx_v3_dot(normal, mid) < 0.0f) normal = sidx_v3_scale(normal, -1.0f);
        const float len = sidx_v3_length(normal);
        if (!(len > 0.0f) || !isfinite(len)) return;
        len2[plane] = len * len;
        pkt->plane_n[plane][0] = normal.x;
        pkt->plane_n[plane][1] = normal.y;
        pkt->plane_n[plane][2] = normal.z;
        pkt->plane_l1[plane] = fabsf(normal.x) + fabsf(normal.y) + fabsf(normal.z);
    }
    /* Every ray must start at the apex and lie inside the 4 planes:
     * n·d >= −1e-6 |n||d|, without a square root per ray.  One pass over
     * the rays with the 4 planes in the 4 SSE lanes (the same products in
     * the same order as sidx_v3_dot): done plane by plane, this check is
     * most of the set-up (docs/performance.md, "Packets and frustums"). */
    if (!frustum_rays_inside(pkt, rays, n, len2)) return;
    pkt->apex[0] = rays[0].org.x;
    pkt->apex[1] = rays[0].org.y;
    pkt->apex[2] = rays[0].org.z;
    frustum_lanes(pkt);
    pkt->frustum = 1;
}

/* ---- set-up ----------------------------------------------------------------------- */

/* 0 when the packet is not coherent enough (direction signs differ). */
static int pkt_setup(packet *pkt, const sidx_ray *rays, uint32_t n, float scale, int anyhit)
{
    pkt->n = n;
    pkt->ngroups = (n + GROUP_LANES - 1) / GROUP_LANES;
    pkt->rays = rays;
    pkt->anyhit = anyhit;
    for (int k = 0; k < 3; ++k) pkt->sign[k] = rays[0].sign[k];
    pkt->kx = rays[0].kx;
    pkt->ky = rays[0].ky;
    pkt->kz = rays[0].kz;
    pkt->uniform_k = 1;
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_ray *r = &rays[i];
        if (r->sign[0] != pkt->sign[0] || r->sign[1] != pkt->sign[1] || r->sign[2] != pkt->sign[2]) return 0;
        if (r->kx != pkt->kx || r->ky != pkt->ky || r->kz != pkt->kz) pkt->uniform_k = 0;
    }
    for (uint32_t i = 0; i < pkt->ngroups * GROUP_LANES; ++i) {
        if (i < n) {
            const sidx_ray *r = &rays[i];
            const float *o = sidx_v3_array(&r->org);
            pkt->org_x[i] = r->org.x; pkt->org_y[i] = r->org.y; pkt->org_z[i] = r->org.z;
            pkt->inv_x[i] = r->inv_dir.x; pkt->inv_y[i] = r->inv_dir.y; pkt->inv_z[i] = r->inv_dir.z;
            pkt->inv_far_x[i] = r->inv_dir.x * scale;
            pkt->inv_far_y[i] = r->inv_dir.y * scale;
            pkt->inv_far_z[i] = r->inv_dir.z * scale;
            pkt->tmin[i] = r->tmin;
            pkt->best[i] = r->tmax;
            pkt->org_kx[i] = o[pkt->kx]; pkt->org_ky[i] = o[pkt->ky]; pkt->org_kz[i] = o[pkt->kz];
            pkt->sx[i] = r->sx; pkt->sy[i] = r->sy; pkt->sz[i] = r->sz;
        } else { /* padding: misses everything */
            pkt->org_x[i] = pkt->org_y[i] = pkt->org_z[i] = 0.0f;
            pkt->inv_x[i] = pkt->inv_y[i] = pkt->inv_z[i] = pkt->inv_far_x[i] = pkt->inv_far_y[i] = pkt->inv_far_z[i] =
                1.0f;
            pkt->org_kx[i] = pkt->org_ky[i] = pkt->org_kz[i] = pkt->sx[i] = pkt->sy[i] = 0.0f;
            pkt->sz[i] = 1.0f;
            pkt->tmin[i] = INFINITY;
            pkt->best[i] = -INFINITY;
        }
        pkt->prim[i] = SIDX_NO_HIT;
    }
    for (int k = 0; k < 3; ++k) {
        pkt->near_i[k] = (uint32_t)(pkt->sign[k] ? 4 + k : k);
        pkt->far_i[k] = (uint32_t)(pkt->sign[k] ? k : 4 + k);
    }
    return 1;
}

/* The adaptive switch generalised (Embree's hybrid traversal does the
 * same): below SWITCH_DEPTH, when at most SWITCH_RAYS rays of the whole
 * packet still hit an inner node, they finish its subtree alone.  Finding
 * that out costs the box tests of the remaining groups, which pays only
 * deep in the tree, where rays have parted (the values tried:
 * docs/performance.md, "Packets and frustums"). */
#define SWITCH_DEPTH 8u
#define SWITCH_RAYS 2u

/* ---- the walks --------------------------------------------------------------------- */

/* One ray alone through the subtree at root (the adaptive switch). */
static void single_subtree(const walkopt *walk, packet *pkt, uint32_t i, uint32_t root)
{
    const bvh *b = walk->b;
    const sidx_ray *r = &pkt->rays[i];
    bvh_ray bray;
    bvh_ray_setup(&bray, r);
    uint32_t stack[BVH_DEPTH_LIMIT + 1], stack_len = 0;
    stack[stack_len++] = root;
    walk->stats->switched_rays++;
    while (stack_len) {
        const uint32_t node_i = stack[--stack_len];
        const bvh_node *node = &b->nodes[node_i];
        float t_near, t_far;
        walk->stats->box_tests++;
        if (!bvh_slab(&bray, node, walk->scale, r->tmin, pkt->best[i], &t_near, &t_far)) continue;
        if (bvh_is_leaf(node)) {
            for (uint32_t k = node->left_or_first; k < node->left_or_first + bvh_count(node); ++k) {
                walk->stats->prim_tests++;
                if (tri_lane(walk, pkt, i, &b->tris[k], b->prim_id[k]) && pkt->anyhit) return;
            }
            continue;
        }
        const uint32_t left = node_i + 1, right = node->left_or_first;
        const int neg = r->sign[bvh_axis(node)];
        stack[stack_len++] = neg ? left : right; /* far first, near on top */
        stack[stack_len++] = neg ? right : left;
    }
}

static int all_done(const packet *pkt)
{
    for (uint32_t i = 0; i < pkt->n; ++i)
        if (pkt->best[i] != -INFINITY) return 0;
    return 1;
}

/* The walk, written once and instantiated twice (packet_walk_avx2,
 * packet_walk_generic): with avx = 1 it is compiled for AVX2 so the 8-ray
 * kernels are inlined into it, and the planes of a node are broadcast
 * straight from the node (read as float[8], as bvh_slab does) instead of
 * going through a copy.  The hot counters live in locals and are added to
 * the stats once per packet: through the stats pointer every node visit
 * cost a load and a store per counter, the compiler being unable to prove
 * that the pointer does not alias the packet. */
static SIDX_INLINE void packet_walk_impl(const walkopt *walk, packet *pkt, const int avx)
{
    const bvh *b = walk->b;
    if (b->num_nodes == 0) return;
    sidx_packet_stats *stats = walk->stats;
    uint64_t visits = 0, boxes = 0, frustum_tests = 0, frustum_culls = 0, prims = 0;
    pstack stack[STACK];
    uint32_t stack_len = 0;
    stack[stack_len++] = (pstack){0, 0, 0};
    while (stack_len) {
        const pstack entry = stack[--stack_len];
        const uint32_t node_i = entry.node, first_group = entry.first_group, depth = entry.depth;
        const bvh_node *node = &b->nodes[node_i];
        const float *node_words = (const float *)(const void *)node;
        ++visits;
        float planes[6];
        for (int k = 0; k < 3; ++k) {
            planes[k] = node_words[pkt->near_i[k]];
            planes[3 + k] = node_words[pkt->far_i[k]];
        }
        /* First group of rays with a hit; the ones before it miss.  The
         * order of Wald et al. 2007: the first active group first (if it
         * hits, nothing can cull the node), then the frustum, then the
         * remaining groups one by one. */
        uint32_t hit_group = first_group;
        unsigned hits = 0;
        for (; hit_group < pkt->ngroups; ++hit_group) {
            /* The frustum only where it can replace two group tests or
             * more: against one it can never save work (a 4x4 tile has
             * only 2 groups, so it never uses the frustum). */
            if (hit_group == first_group + 1 && hit_group + 2 <= pkt->ngroups && walk->frustum &&
                (walk->frustum_depth == 0 || depth < walk->frustum_depth)) {
                ++frustum_tests;
                if (!frustum_overlap(pkt, node)) {
                    ++frustum_culls;
                    hit_group = pkt->ngroups;
                    break;
                }
            }
            boxes += GROUP_LANES;
            hits = avx ? box8_avx2(pkt, hit_group, planes) : box8_scalar(pkt, hit_group, planes);
            if (hits) break;
        }
        if (hit_group == pkt->ngroups) continue; /* no ray hits: early exit */
        if (bvh_is_leaf(node)) {
            const uint32_t first = node->left_or_first, count = bvh_count(node);
            for (uint32_t group = hit_group; group < pkt->ngroups; ++group) {
                if (group != hit_group) {
                    boxes += GROUP_LANES;
                    if (!(avx ? box8_avx2(pkt, group, planes) : box8_scalar(pkt, group, planes))) continue;
                }
                prims += (uint64_t)GROUP_LANES * count;
                for (uint32_t k = first; k < first + count; ++k) {
                    if (avx && walk->simd_tri) tri8_avx2(walk, pkt, group, &b->tris[k], b->prim_id[k]);
                    else tri8_scalar(walk, pkt, group, &b->tris[k], b->prim_id[k]);
                }
            }
            if (pkt->anyhit && all_done(pkt)) break;
            continue;
        }
        /* Adaptive switch: only 1 or 2 rays of the last group still want
         * this subtree — they finish it alone instead of dragging the
         * packet'neg bookkeeping through it. */
        if (hit_group + 1 == pkt->ngroups &&
            (hits & (hits - 1) & ((hits & (hits - 1)) - 1)) == 0) { /* at most 2 bits set */
            for (unsigned rays = hits; rays; rays &= rays - 1)
                single_subtree(walk, pkt, hit_group * GROUP_LANES + (uint32_t)__builtin_ctz(rays), node_i);
            if (pkt->anyhit && all_done(pkt)) break;
            continue;
        }
        if (depth >= SWITCH_DEPTH && hit_group + 1 < pkt->ngroups &&
            (hits & (hits - 1) & ((hits & (hits - 1)) - 1)) == 0) {
            unsigned group_hits[MAX_GROUPS];
            uint32_t total = (uint32_t)__builtin_popcount(hits);
            group_hits[hit_group] = hits;
            for (uint32_t group = hit_group + 1; group < pkt->ngroups && total <= SWITCH_RAYS; ++group) {
                boxes += GROUP_LANES;
                group_hits[group] = avx ? box8_avx2(pkt, group, planes) : box8_scalar(pkt, group, planes);
                total += (uint32_t)__builtin_popcount(group_hits[group]);
            }
            if (total <= SWITCH_RAYS) {
                for (uint32_t group = hit_group; group < pkt->ngroups; ++group)
                    for (unsigned rays = group_hits[group]; rays; rays &= rays - 1)
                        single_subtree(walk, pkt, group * GROUP_LANES + (uint32_t)__builtin_ctz(rays), node_i);
                if (pkt->anyhit && all_done(pkt)) break;
                continue;
            }
        }
        /* The packet shares direction signs: the near child along the
         * split axis is the same for every ray. */
        const uint32_t left = node_i + 1, right = node->left_or_first;
        const int neg = pkt->sign[bvh_axis(node)];
        stack[stack_len++] = (pstack){neg ? left : right, hit_group, depth + 1};
        stack[stack_len++] = (pstack){neg ? right : left, hit_group, depth + 1};
    }
    stats->node_visits += visits;
    stats->box_tests += boxes;
    stats->frustum_tests += frustum_tests;
    stats->frustum_culls += frustum_culls;
    stats->prim_tests += prims;
}

#ifdef PKT_X86
/* flatten: every kernel inlined into this AVX2 copy of the walk. */
__attribute__((target("avx2,fma"), flatten)) static void packet_walk_avx2(const walkopt *walk, packet *pkt)
{
    packet_walk_impl(walk, pkt, 1);
}
#endif
static void packet_walk_generic(const walkopt *walk, packet *pkt) { packet_walk_impl(walk, pkt, 0); }

static void packet_walk(const walkopt *walk, packet *pkt)
{
#ifdef PKT_X86
    if (walk->avx) {
        packet_walk_avx2(walk, pkt);
        return;
    }
#endif
    packet_walk_generic(walk, pkt);
}

/* ---- entry points ---------------------------------------------------------------------- */

static int packet_capable(const sidx_accel *a)
{
    if (a->vt != &sidx__bvh_vtable) return 0;
    const bvh *b = a->impl;
    /* a lazy tree is traced ray by ray: its walk builds what the rays enter */
    return b && b->obbs == NULL && b->lazy == NULL;
}

/* Checked per call (a getenv and a cached cpuid bit), so SIDX_SIMD=scalar
 * can be switched on between calls; sidx_trace_tiles asks once per image. */
int sidx__packet_have_avx2(void)
{
#ifdef PKT_X86
    const char *env = getenv("SIDX_SIMD");
    if (env && (!strcmp(env, "scalar") || !strcmp(env, "0") || !strcmp(env, "sse4.1"))) return 0;
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
#else
    return 0;
#endif
}

/* avx: 1 / 0 as decided by the caller, or −1 to ask have_avx2. */
static sidx_status run_packet(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w,
                              const sidx_packet_options *opt, sidx_hit *hits, uint8_t *occ, sidx_packet_stats *stats,
                              int avx)
{
    if (!a || (n && (!rays || (!hits && !occ))) || n > SIDX_PACKET_MAX) return SIDX_ERR_INVALID_ARG;
    sidx_packet_options o;
    memset(&o, 0, sizeof o);
    if (opt) o = *opt;
    sidx_packet_stats dummy;
    memset(&dummy, 0, sizeof dummy);
    if (!stats) stats = &dummy;
    stats->packets++;
    const int anyhit = hits == NULL;
    const float scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    if (avx < 0) avx = sidx__packet_have_avx2();
    /* The wide BVHs have their own packet walk (packet_wide.c); a lazy
     * one is traced ray by ray, its walk building what the rays reach. */
    if (o.mode != SIDX_PACKET_SINGLE && n && sidx__is_wide(a) && !a->lazy) {
        sidx__packet_wide(a, rays, n, n, n, &o, hits, occ, stats, avx);
        return SIDX_OK;
    }
    packet pkt;
    if (o.mode == SIDX_PACKET_SINGLE || !packet_capable(a) || n == 0 || !pkt_setup(&pkt, rays, n, scale, anyhit)) {
        stats->single_packets++;
        const sidx_query q = {o.flags, SIDX_TRAVERSE_DEFAULT, NULL, 0};
        sidx_status st = SIDX_OK; /* SIDX_ERR_NOMEM from a lazy tree's expansion */
        for (uint32_t i = 0; i < n; ++i) {
            if (anyhit) {
                int occluded = 0;
                if (sidx_accel_occluded(a, &rays[i], &q, &occluded) != SIDX_OK) st = SIDX_ERR_NOMEM;
                occ[i] = (uint8_t)occluded;
            } else {
                if (sidx_accel_intersect(a, &rays[i], &q, &hits[i]) != SIDX_OK) st = SIDX_ERR_NOMEM;
            }
        }
        return st;
    }
    walkopt walk;
    walk.a = a;
    walk.b = a->impl;
    walk.scale = scale;
    walk.avx = avx;
    walk.simd_tri = a->opt.tri == SIDX_TRI_WATERTIGHT && pkt.uniform_k;
    walk.stats = stats;
    if (o.mode == SIDX_PACKET_FRUSTUM && pkt.ngroups >= 3) frustum_setup(&pkt, rays, n, w); /* see packet_walk_impl */
    else pkt.frustum = 0;
    walk.frustum = pkt.frustum;
    walk.frustum_depth = o.frustum_depth;
    packet_walk(&walk, &pkt);
    for (uint32_t i = 0; i < n; ++i) {
        if (anyhit) {
            occ[i] = pkt.prim[i] != SIDX_NO_HIT;
            continue;
        }
        hits[i] = sidx_hit_none();
        if (pkt.prim[i] != SIDX_NO_HIT) {
            hits[i].t = pkt.best[i];
            hits[i].prim = pkt.prim[i];
            if (o.flags & SIDX__PACKET_FINISH) /* a call only when asked */
                sidx__hit_finish(a->mesh, a->opt.tri, &rays[i], o.flags & SIDX__PACKET_FINISH, 0u, &hits[i]);
        }
    }
    return SIDX_OK;
}

sidx_status sidx_packet_intersect(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w,
                                  const sidx_packet_options *opt, sidx_hit *hits, sidx_packet_stats *stats)
{
    if (n && !hits) return SIDX_ERR_INVALID_ARG;
    return run_packet(a, rays, n, w, opt, hits, NULL, stats, -1);
}

sidx_status sidx_packet_occluded(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w,
                                 const sidx_packet_options *opt, uint8_t *occluded, sidx_packet_stats *stats)
{
    if (n && !occluded) return SIDX_ERR_INVALID_ARG;
    return run_packet(a, rays, n, w, opt, NULL, occluded, stats, -1);
}

sidx_status sidx_trace_tiles(const sidx_accel *a, const sidx_ray *rays, uint32_t W, uint32_t H, uint32_t tile,
                             const sidx_packet_options *opt, sidx_hit *hits, sidx_packet_stats *stats)
{
    if (!a || (W && H && (!rays || !hits)) || tile == 0 || tile > SIDX_PACKET_MAX / tile)
        return SIDX_ERR_INVALID_ARG;
    sidx_ray pr[SIDX_PACKET_MAX];
    sidx_hit ph[SIDX_PACKET_MAX];
    const int avx =
        sidx__packet_have_avx2(); /* once per image: getenv scans the environment (docs/performance.md, Packets) */
    const int wide = sidx__is_wide(a) && !a->lazy && !(opt && opt->mode == SIDX_PACKET_SINGLE);
    sidx_packet_stats dummy;
    memset(&dummy, 0, sizeof dummy);
    if (!stats) stats = &dummy;
    for (uint32_t y0 = 0; y0 < H; y0 += tile)
        for (uint32_t x0 = 0; x0 < W; x0 += tile) {
            const uint32_t tw = W - x0 < tile ? W - x0 : tile, th = H - y0 < tile ? H - y0 : tile;
            /* Wide BVHs: the tile is read and written in place. */
            const size_t at = (size_t)y0 * W + x0;
            if (wide) {
                stats->packets++;
                sidx__packet_wide(a, rays + at, tw * th, tw, W, opt, hits + at, NULL, stats, avx);
                continue;
            }
            for (uint32_t y = 0; y < th; ++y)
                memcpy(&pr[y * tw], &rays[(size_t)(y0 + y) * W + x0], tw * sizeof *pr);
            const sidx_status s = run_packet(a, pr, tw * th, tw, opt, ph, NULL, stats, avx);
            if (s != SIDX_OK) return s;
            for (uint32_t y = 0; y < th; ++y)
                memcpy(&hits[(size_t)(y0 + y) * W + x0], &ph[y * tw], tw * sizeof *ph);
        }
    return SIDX_OK;
}
