/* packet_wide.c — coherent ray packets over the 4- and 8-wide BVHs
 * ("bvh4", "bvh8"; layout in bvh_wide_internal.h).
 *
 * packet.c walks the binary BVH the way Wald, Boulos, Shirley 2007 do: a
 * node is one box, tested against the packet group by group.  A wide node
 * holds W = 4 or 8 child boxes, so the question at a node becomes "which
 * rays hit which child" — a W x 64 table of bits.  The walk here fills it
 * in the cheapest of three ways and keeps, per child, the mask of rays
 * that hit it (the packet's active mask below that child; Wald, Benthin,
 * Boulos 2008 "Getting rid of packets" and Embree's hybrid traversal keep
 * the same per-child masks):
 *
 *   1. interval arithmetic (Boulos et al. 2007, "Packet-based Whitted and
 *      distribution ray tracing"; Wald et al. 2006 "Ray tracing animated
 *      scenes using coherent grid traversal"): the packet's rays are
 *      bounded by a box of origins [omin, omax] and of inverse directions
 *      [imin, imax] (the rays share direction signs, so each axis has one
 *      sign).  From it one pass over the W child boxes gives, per child, a
 *      lower bound of every ray's entry distance and an upper bound of
 *      every ray's exit distance; a child whose bounds do not overlap is
 *      missed by every ray and is dropped before any per-ray work.  The
 *      same lower bound orders the surviving children near to far.
 *   2. few active rays (<= THIN): each ray tests all W boxes in one SIMD
 *      pass, exactly as a single ray does in bvh_wide_walk.h, and its W
 *      result bits are scattered into the children's masks; with very
 *      few (<= SOLO) the interval test is skipped and the first ray's
 *      entry distances order the children;
 *   3. many active rays: each surviving child box is tested against the
 *      rays 8 at a time (one AVX pass per group of 8), over every group
 *      without branching on which groups are active — the result is
 *      masked instead.
 *
 * Leaves are the wide tree's runs of 4-triangle blocks: each active ray
 * runs the 4-triangle watertight test of the single-ray walk on each block
 * (the leaf is small and the block's vertices stay in cache across rays).
 *
 * Why the interval test is conservative in floating point: every per-ray
 * slab value is fl(fl(p − o)·inv), and rounding is monotone, so evaluating
 * the same two operations on the interval ends (origin end chosen by the
 * axis' sign, min / max over the two inverse-direction ends) bounds every
 * ray's value from the correct side; the far planes use 1/d·S (S the Ize
 * factor) as the rays do.  It needs finite inverse directions: a packet
 * with a ±0 direction component (inv = ±inf, where 0·inf would be NaN)
 * skips the interval test and relies on the per-ray tests.
 *
 * Results equal the single-ray walk's: the per-ray box test is the same
 * robust slab test against the ray's own [tmin, best], the triangle test
 * is the same 4-lane watertight kernel (same operations in the same order,
 * smallest t per block, ties to the lowest lane; a lane with an edge
 * function of exactly 0 sends the block to the scalar test), so the same t
 * and prim come out; only on an exact tie of two triangles in different
 * blocks may the packet, visiting them in another order, keep the other.
 *
 * A tile whose rays do not all share direction signs (it straddles an
 * axis of the camera) is walked once per sign class present, each class
 * a packet of its own (its own near planes and interval bounds), instead
 * of ray by ray as packet.c does on the binary tree.
 *
 * No events: the packet calls take no query and no hook, so there is
 * nothing to emit; a traced query goes through sidx_accel_intersect and
 * the traced copy of the single-ray walk (bvh_wide_walk.h).
 *
 * Like packet.c the walk is written once and instantiated per width and
 * instruction set: AVX2 (8-lane ray groups; 8 boxes per pass for bvh8, 4
 * with SSE for bvh4; the SSE2 triangle kernel) and a scalar copy doing
 * the same arithmetic in loops — the readable reference, run by the tests
 * with SIDX_SIMD=scalar.  The kernels are in simd_packet_wide_scalar.h
 * (the reference) and simd_packet_wide_avx2.h. */
#include "bvh_wide_internal.h"
#include "packet_internal.h"
#include "hit.h"
#include "simd_isa.h"
#if defined(SIDX_SIMD_X86) && defined(SIDX_SIMD_SSE2)
#define PW_X86 1 /* SSE2 (the set-up, the triangle blocks) always; AVX2 chosen at run time */
#endif

#define GROUP_LANES 8u                      /* rays per group (one AVX register) */
#define NLANES SIDX_PACKET_MAX     /* 64: the active mask is one uint64_t */
#define THIN 16u                   /* at most this many active rays: per-ray W-box tests */
/* At most this many active rays: no interval test either.  The bounds
 * are the whole packet's, so with few rays left they cull little and
 * cost a pass; per-ray entry distances order the children better
 * (the values tried: docs/performance.md, "Packets and frustums"). */
#define SOLO 6u
#ifndef PW_PREFETCH
#define PW_PREFETCH 1
#endif

_Static_assert(SIDX_PACKET_MAX == 64, "active ray masks are 64-bit");

/* The packet: rays in structure-of-arrays form, padded to whole groups of
 * 8; a padding lane has tmin = +inf and best = −inf, so it misses every
 * box.  The rays themselves are read in place (ray[i] points into the
 * caller's image) for the triangle tests. */
typedef struct wide_packet {
    _Alignas(32) float org_x[NLANES], org_y[NLANES], org_z[NLANES];
    _Alignas(32) float inv_x[NLANES], inv_y[NLANES], inv_z[NLANES];             /* 1/d */
    _Alignas(32) float inv_far_x[NLANES], inv_far_y[NLANES], inv_far_z[NLANES]; /* 1/d · Ize factor (far planes) */
    _Alignas(32) float tmin[NLANES], best[NLANES];
    /* best · Ize factor: what boxes are clipped to.  A rounded entry an ulp
     * beyond the best hit must not drop a box holding a triangle an ulp
     * nearer (bvh_slab, bvh_internal.h, says more); hits still need t < best. */
    _Alignas(32) float best_clip[NLANES];
    float scale;
    uint32_t prim[NLANES];
    const sidx_ray *ray[NLANES];
    uint64_t live;         /* the real rays: bits 0 .. n−1 */
    uint64_t done;         /* any-hit: rays already occluded */
    uint32_t n, ngroups;
    uint32_t near_row[3],
        far_row[3]; /* near / far plane row of each axis in a node (k or 3 + k), from the common signs */
    int anyhit;
    /* interval arithmetic: ia_usable = 0 when some inverse direction is not finite */
    int ia_usable;
    float ia_org_near[3], ia_org_far[3]; /* origin end giving the smallest entry / the largest exit */
    float ia_inv_lo[3], ia_inv_hi[3];    /* inverse direction range */
    float ia_far_lo[3], ia_far_hi[3];    /* the same times the Ize factor */
    float ia_tmin, ia_tmax;              /* smallest tmin, largest tmax */
} wide_packet;

/* Work counters, in locals during the walk (see packet.c: through the
 * stats pointer each would cost a load and a store per node). */
typedef struct wcount {
    uint64_t visits, boxes, prims, ia_tests, ia_culls, split;
} wcount;

/* ---- set-up ---------------------------------------------------------------------- */

/* The rays into the packet's arrays, a plain copy (the arithmetic comes
 * in packet_bounds), row by row from the caller's image.  Padding lanes
 * repeat ray 0 (so they never widen the interval bounds nor change the
 * sign class) with tmin = +inf, best = −inf (so they miss every box). */
static SIDX_INLINE void packet_load(wide_packet *pkt, const sidx_ray *rays, uint32_t n, uint32_t w, size_t stride,
                                    int anyhit)
{
    pkt->n = n;
    pkt->ngroups = (n + GROUP_LANES - 1) / GROUP_LANES;
    pkt->anyhit = anyhit;
    pkt->done = 0;
    uint32_t i = 0;
    for (const sidx_ray *row = rays; i < n; row += stride)
        for (uint32_t x = 0; x < w; ++x, ++i) {
            const sidx_ray *r = row + x;
            pkt->ray[i] = r;
            pkt->org_x[i] = r->org.x; pkt->org_y[i] = r->org.y; pkt->org_z[i] = r->org.z;
            pkt->inv_x[i] = r->inv_dir.x; pkt->inv_y[i] = r->inv_dir.y; pkt->inv_z[i] = r->inv_dir.z;
            pkt->tmin[i] = r->tmin;
            pkt->best[i] = r->tmax;
            pkt->best_clip[i] = r->tmax * pkt->scale;
            pkt->prim[i] = SIDX_NO_HIT;
        }
    for (; i < pkt->ngroups * GROUP_LANES; ++i) {
        pkt->ray[i] = rays;
        pkt->org_x[i] = pkt->org_x[0]; pkt->org_y[i] = pkt->org_y[0]; pkt->org_z[i] = pkt->org_z[0];
        pkt->inv_x[i] = pkt->inv_x[0]; pkt->inv_y[i] = pkt->inv_y[0]; pkt->inv_z[i] = pkt->inv_z[0];
        pkt->tmin[i] = INFINITY;
        pkt->best[i] = pkt->best_clip[i] = -INFINITY;
        pkt->prim[i] = SIDX_NO_HIT;
    }
}

/* Direction-sign class of lane i: bit k set when d_k < 0 (−0 included:
 * 1/−0 = −inf keeps the sign, as sidx_ray.sign does). */
static SIDX_INLINE unsigned lane_class(const wide_packet *pkt, uint32_t i)
{
    return (unsigned)(signbit(pkt->inv_x[i]) != 0) | (unsigned)(signbit(pkt->inv_y[i]) != 0) << 1 |
           (unsigned)(signbit(pkt->inv_z[i]) != 0) << 2;
}

/* The interval bounds of a set of rays: origins, inverse directions, the
 * smallest tmin and the largest clipped best. */
typedef struct ray_bounds {
    float omin[3], omax[3], imin[3], imax[3], tmin, tmax;
} ray_bounds;

/* ---- kernels ---------------------------------------------------------------------
 * One header per instruction set: simd_packet_wide_scalar.h (the
 * reference) and simd_packet_wide_avx2.h (AVX2 and SSE, chosen at run
 * time: avx = 1).  Elsewhere than x86 the reference stands in for the
 * AVX2 names, which the walk mentions only in branches on avx (always 0
 * there). */

#include "simd_packet_wide_scalar.h"
#ifdef PW_X86
#include "simd_packet_wide_avx2.h"
#else
#define lanes_uniform_sse lanes_uniform_scalar
#define bounds_sse(pkt, out) bounds_scalar(pkt, pkt->live, out)
#define ia_slots_avx ia_slots_scalar
#define ray_slots_avx ray_slots_scalar
#define group_slot_avx group_slot_scalar
#define leaf_ray_sse leaf_ray_scalar
#endif

/* Do all lanes share lane 0's sign class? */
static SIDX_INLINE int packet_uniform(const wide_packet *pkt, const int avx)
{
    if (avx) return lanes_uniform_sse(pkt);
    return lanes_uniform_scalar(pkt);
}

/* Far-plane factors 1/d·S for every lane, and the interval bounds of the
 * rays in `live` (all of them share sign class c). */
static SIDX_INLINE void packet_bounds(wide_packet *pkt, uint64_t live, unsigned cls, float scale, const int avx)
{
    pkt->live = live;
    const uint32_t n_lanes = pkt->ngroups * GROUP_LANES;
    for (uint32_t i = 0; i < n_lanes; ++i) {
        pkt->inv_far_x[i] = pkt->inv_x[i] * scale;
        pkt->inv_far_y[i] = pkt->inv_y[i] * scale;
        pkt->inv_far_z[i] = pkt->inv_z[i] * scale;
    }
    const uint64_t real = pkt->n == 64 ? ~0ull : (1ull << pkt->n) - 1u;
    ray_bounds bounds;
    if (avx && live == real) bounds_sse(pkt, &bounds);
    else bounds_scalar(pkt, live, &bounds);
    int finite = 1;
    for (int k = 0; k < 3; ++k) {
        const int neg = (int)(cls >> k) & 1;
        /* rows of a node: 0..2 lo, 3..5 hi; a negative direction enters through hi */
        pkt->near_row[k] = (uint32_t)(neg ? 3 + k : k);
        pkt->far_row[k] = (uint32_t)(neg ? k : 3 + k);
        /* The entry t = (p − o)·inv is smallest for the largest p − o when
         * inv < 0 (o = omin), for the smallest when inv > 0 (o = omax); the
         * exit the other way round.  x·S is monotone, so the far factors'
         * range is the ends times S. */
        pkt->ia_org_near[k] = neg ? bounds.omin[k] : bounds.omax[k];
        pkt->ia_org_far[k] = neg ? bounds.omax[k] : bounds.omin[k];
        pkt->ia_inv_lo[k] = bounds.imin[k];
        pkt->ia_inv_hi[k] = bounds.imax[k];
        pkt->ia_far_lo[k] = bounds.imin[k] * scale;
        pkt->ia_far_hi[k] = bounds.imax[k] * scale;
        /* an infinite inverse direction would be at one of the ends */
        finite &= isfinite(pkt->ia_far_lo[k]) && isfinite(pkt->ia_far_hi[k]);
    }
    pkt->ia_tmin = bounds.tmin;
    pkt->ia_tmax = bounds.tmax;
    pkt->ia_usable = finite;
}

/* ---- the walk ---------------------------------------------------------------------- */

/* A deferred child: its reference (node index, or WIDE_LEAF_BIT | first
 * block) and the rays that hit its box. */
typedef struct wstack {
    uint32_t ref;
    uint64_t rays;
} wstack;

/* Written once, instantiated for W = 4, 8 and avx = 0, 1 (constants, so
 * every branch on them folds away: walk8_avx, walk4_avx, walk8_scalar,
 * walk4_scalar below); simd_tri: the watertight SIMD kernel applies (the
 * structure's triangle test is the watertight one). */
static SIDX_INLINE void wide_walk_impl(const sidx_accel *a, wide_packet *pkt, wcount *counts, const uint32_t W,
                                       const int avx, const int simd_tri)
{
    const wide_bvh *wide = a->impl;
    (void)avx; /* only read by the x86 kernels */
    if (wide->num_inner == 0) return;
    const float *nodes = wide->nodes;
    const unsigned all_slots = (1u << W) - 1u;
    wstack stack[WIDE_STACK];
    uint32_t stack_len = 0, ref = 0;
    uint64_t active = pkt->live;
    uint64_t visits = 0, boxes = 0, prims = 0, ia_tests = 0, ia_culls = 0;
    for (;;) {
        if (!(ref & WIDE_LEAF_BIT)) {
            const float *node = nodes + (size_t)ref * 8u * W;
            const uint32_t *child = wide_child(node, W);
            _Alignas(32) float key[8];
            uint64_t child_rays[8];
            ++visits;
            unsigned hit_slots = 0;
            if ((uint32_t)__builtin_popcountll(active) <= SOLO) {
                /* One ray (or very few) left: their own W-box tests, as in
                 * the single-ray walk; the first one's entry distances
                 * order the children (the packet's interval bounds would
                 * only cost here). */
                for (uint32_t slot = 0; slot < W; ++slot) child_rays[slot] = 0;
                float *key_out = key;
                for (uint64_t rays_left = active; rays_left; rays_left &= rays_left - 1) {
                    const uint32_t i = (uint32_t)__builtin_ctzll(rays_left);
                    unsigned slots =
                        avx ? ray_slots_avx(node, W, pkt, i, key_out) : ray_slots_scalar(node, W, pkt, i, key_out);
                    key_out = NULL;
                    hit_slots |= slots;
                    for (; slots; slots &= slots - 1) child_rays[__builtin_ctz(slots)] |= 1ull << i;
                    boxes += W;
                }
                goto children;
            }
            /* 1. the interval test: children no ray can hit */
            unsigned cand = all_slots;
            if (pkt->ia_usable) {
                cand = avx ? ia_slots_avx(node, W, pkt, key) : ia_slots_scalar(node, W, pkt, key);
                ia_tests += W;
                ia_culls += (uint64_t)(W - (uint32_t)__builtin_popcount(cand));
            } else {
                for (uint32_t slot = 0; slot < W; ++slot) key[slot] = (float)slot;
            }
            if (cand) {
                /* Per-ray or per-group tests, whichever costs fewer SIMD
                 * passes: a ray's pass covers all W boxes, a group's pass
                 * one box for 8 rays (groups without an active ray are
                 * skipped). */
                const uint32_t n_active = (uint32_t)__builtin_popcountll(active);
                uint64_t group_bits = active | active >> 4; /* bit 8g: group g has an active ray */
                group_bits |= group_bits >> 2;
                group_bits |= group_bits >> 1;
                group_bits &= 0x0101010101010101ull;
                const uint32_t ncand = (uint32_t)__builtin_popcount(cand);
                if (n_active <= THIN && n_active < ncand * (uint32_t)__builtin_popcountll(group_bits)) {
                    /* 2. few rays: each tests the W boxes at once */
                    for (uint32_t slot = 0; slot < W; ++slot) child_rays[slot] = 0;
                    for (uint64_t rays_left = active; rays_left; rays_left &= rays_left - 1) {
                        const uint32_t i = (uint32_t)__builtin_ctzll(rays_left);
                        unsigned slots =
                            avx ? ray_slots_avx(node, W, pkt, i, NULL) : ray_slots_scalar(node, W, pkt, i, NULL);
                        slots &= cand;
                        hit_slots |= slots;
                        for (; slots; slots &= slots - 1) child_rays[__builtin_ctz(slots)] |= 1ull << i;
                    }
                    boxes += (uint64_t)n_active * W;
                } else {
                    /* 3. many rays: each candidate box against the groups of 8 */
                    for (unsigned cands = cand; cands; cands &= cands - 1) {
                        const uint32_t slot = (uint32_t)__builtin_ctz(cands);
                        uint64_t rays_left = 0;
                        for (uint64_t groups_left = group_bits; groups_left; groups_left &= groups_left - 1) {
                            const uint32_t g = (uint32_t)__builtin_ctzll(groups_left) / GROUP_LANES;
                            const unsigned slots =
                                avx ? group_slot_avx(node, W, slot, pkt, g) : group_slot_scalar(node, W, slot, pkt, g);
                            rays_left |= (uint64_t)slots << (g * GROUP_LANES);
                        }
                        rays_left &= active;
                        child_rays[slot] = rays_left;
                        hit_slots |= (unsigned)(rays_left != 0) << slot;
                    }
                    boxes += (uint64_t)ncand * (uint64_t)__builtin_popcountll(group_bits) * GROUP_LANES;
                }
            }
        children:
#if PW_PREFETCH
            /* Several children hit: start fetching them all (a node is 4
             * cache lines, a block 3), as the single-ray walk does — the
             * nearest is needed next, the others when popped; not the lone
             * child (docs/performance.md, "Packets and frustums"). */
            for (unsigned fetch = hit_slots & (hit_slots - 1) ? hit_slots : 0; fetch; fetch &= fetch - 1) {
                const uint32_t c = child[__builtin_ctz(fetch)];
                const char *p = (c & WIDE_LEAF_BIT) ? (const char *)(wide->blocks + (c & ~WIDE_LEAF_BIT))
                                                    : (const char *)(nodes + (size_t)c * 8u * W);
                __builtin_prefetch(p);
                __builtin_prefetch(p + 64);
                __builtin_prefetch(p + 128);
                if (!(c & WIDE_LEAF_BIT) && W == 8) __builtin_prefetch(p + 192);
            }
#endif
            if (hit_slots) {
                const uint32_t slot0 = (uint32_t)__builtin_ctz(hit_slots);
                if (!(hit_slots & (hit_slots - 1))) { /* one child: descend, no stack */
                    ref = child[slot0];
                    active = child_rays[slot0];
                    continue;
                }
                const unsigned rest = hit_slots & (hit_slots - 1);
                if (!(rest & (rest - 1))) {
                    /* Two (the common case of several): one compare, the
                     * farther waits; ties go to the lower slot. */
                    const uint32_t slot1 = (uint32_t)__builtin_ctz(rest);
                    const int first0 = pkt->anyhit || key[slot0] <= key[slot1];
                    const uint32_t near_slot = first0 ? slot0 : slot1, far_slot = first0 ? slot1 : slot0;
                    stack[stack_len++] = (wstack){child[far_slot], child_rays[far_slot]};
                    ref = child[near_slot];
                    active = child_rays[near_slot];
                    continue;
                }
                /* More: order the slots farthest first (insertion sort on
                 * the entry key, stable, so equal keys keep slot order and
                 * the lower slot is visited first), defer all but the
                 * nearest, descend into it. */
                uint32_t order[8], n_order = 0;
                for (unsigned pending = hit_slots; pending; pending &= pending - 1) {
                    const uint32_t slot = (uint32_t)__builtin_ctz(pending);
                    uint32_t j = n_order++;
                    if (!pkt->anyhit)
                        /* order[0, j) was written by earlier passes (j < n_order) */
                        /* cppcheck-suppress uninitvar */
                        while (j > 0 && key[order[j - 1]] <= key[slot]) {
                            order[j] = order[j - 1];
                            --j;
                        }
                    order[j] = slot;
                }
                for (uint32_t k = 0; k + 1 < n_order; ++k)
                    stack[stack_len++] = (wstack){child[order[k]], child_rays[order[k]]};
                /* cppcheck-suppress uninitvar ; n_order >= 2 here, every slot written above */
                ref = child[order[n_order - 1]];
                active = child_rays[order[n_order - 1]];
                continue;
            }
        } else {
            /* a leaf: each ray of the mask against its blocks */
            const wide_tri4 *block = wide->blocks + (ref & ~WIDE_LEAF_BIT);
            uint32_t n_blocks = 1;
            for (const wide_tri4 *next = block; !(next->prim[0] & WIDE_LAST_BLOCK); ++next) ++n_blocks;
            if (avx && simd_tri) {
                for (uint64_t rays_left = active; rays_left; rays_left &= rays_left - 1) {
                    const uint32_t i = (uint32_t)__builtin_ctzll(rays_left);
                    pkt->done |= (uint64_t)leaf_ray_sse(a, block, pkt, i) << i;
                }
            } else {
                for (uint64_t rays_left = active; rays_left; rays_left &= rays_left - 1) {
                    const uint32_t i = (uint32_t)__builtin_ctzll(rays_left);
                    pkt->done |= (uint64_t)leaf_ray_scalar(a, block, pkt, i) << i;
                }
            }
            prims += (uint64_t)__builtin_popcountll(active) * n_blocks * 4u;
            if (pkt->anyhit && !(pkt->live & ~pkt->done)) break;
        }
        /* Pop the next deferred child that still has rays to trace.
         * Rejected alternative: docs/performance.md, "Packets and frustums". */
        for (;;) {
            if (stack_len == 0) goto out;
            --stack_len;
            ref = stack[stack_len].ref;
            active = stack[stack_len].rays & ~pkt->done;
            if (active) break;
        }
    }
out:
    counts->visits += visits;
    counts->boxes += boxes;
    counts->prims += prims;
    counts->ia_tests += ia_tests;
    counts->ia_culls += ia_culls;
}

/* Load a tile, then one walk per direction-sign class present (a tile
 * straddling an axis of the camera holds 2 or 4; each class is its own
 * packet with its own near planes and interval bounds). */
static SIDX_INLINE void wide_packet_impl(const sidx_accel *a, wide_packet *pkt, wcount *counts, const sidx_ray *rays,
                                         uint32_t n, uint32_t w, size_t stride, int anyhit, const uint32_t W,
                                         const int avx, const int simd_tri)
{
    const float scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    pkt->scale = scale;
    packet_load(pkt, rays, n, w, stride, anyhit);
    const uint64_t real = n == 64 ? ~0ull : (1ull << n) - 1u;
    if (packet_uniform(pkt, avx)) {
        packet_bounds(pkt, real, lane_class(pkt, 0), scale, avx);
        wide_walk_impl(a, pkt, counts, W, avx, simd_tri);
        return;
    }
    uint64_t live[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (uint32_t i = 0; i < n; ++i) live[lane_class(pkt, i)] |= 1ull << i;
    counts->split++;
    for (unsigned cls = 0; cls < 8; ++cls) {
        if (!live[cls]) continue;
        packet_bounds(pkt, live[cls], cls, scale, avx);
        wide_walk_impl(a, pkt, counts, W, avx, simd_tri);
    }
}

/* The four copies of the walk: 8- and 4-wide, AVX2 (flatten: every
 * kernel inlined) and the reference. */
#ifdef PW_X86
__attribute__((target("avx2,fma"), flatten)) static void walk8_avx(const sidx_accel *a, wide_packet *pkt,
                                                                   wcount *counts, const sidx_ray *rays, uint32_t n,
                                                                   uint32_t w, size_t stride, int anyhit, int simd_tri)
{
    if (simd_tri) wide_packet_impl(a, pkt, counts, rays, n, w, stride, anyhit, 8, 1, 1);
    else wide_packet_impl(a, pkt, counts, rays, n, w, stride, anyhit, 8, 1, 0);
}
__attribute__((target("avx2,fma"), flatten)) static void walk4_avx(const sidx_accel *a, wide_packet *pkt,
                                                                   wcount *counts, const sidx_ray *rays, uint32_t n,
                                                                   uint32_t w, size_t stride, int anyhit, int simd_tri)
{
    if (simd_tri) wide_packet_impl(a, pkt, counts, rays, n, w, stride, anyhit, 4, 1, 1);
    else wide_packet_impl(a, pkt, counts, rays, n, w, stride, anyhit, 4, 1, 0);
}
#endif
static void walk8_scalar(const sidx_accel *a, wide_packet *pkt, wcount *counts, const sidx_ray *rays, uint32_t n,
                         uint32_t w, size_t stride, int anyhit)
{
    wide_packet_impl(a, pkt, counts, rays, n, w, stride, anyhit, 8, 0, 0);
}
static void walk4_scalar(const sidx_accel *a, wide_packet *pkt, wcount *counts, const sidx_ray *rays, uint32_t n,
                         uint32_t w, size_t stride, int anyhit)
{
    wide_packet_impl(a, pkt, counts, rays, n, w, stride, anyhit, 4, 0, 0);
}

/* ---- entry (from packet.c) ----------------------------------------------------------- */

void sidx__packet_wide(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w, size_t stride,
                      const sidx_packet_options *opt, sidx_hit *hits, uint8_t *occ, sidx_packet_stats *stats, int avx)
{
    const wide_bvh *wide = a->impl;
    const int anyhit = hits == NULL;
    wide_packet pkt;
    wcount counts = {0, 0, 0, 0, 0, 0};
#ifdef PW_X86
    if (avx) {
        const int simd_tri = a->opt.tri == SIDX_TRI_WATERTIGHT;
        if (wide->width == 8) walk8_avx(a, &pkt, &counts, rays, n, w, stride, anyhit, simd_tri);
        else walk4_avx(a, &pkt, &counts, rays, n, w, stride, anyhit, simd_tri);
    } else
#else
    (void)avx;
#endif
    {
        if (wide->width == 8) walk8_scalar(a, &pkt, &counts, rays, n, w, stride, anyhit);
        else walk4_scalar(a, &pkt, &counts, rays, n, w, stride, anyhit);
    }
    stats->node_visits += counts.visits;
    stats->box_tests += counts.boxes;
    stats->prim_tests += counts.prims;
    stats->interval_tests += counts.ia_tests;
    stats->interval_culls += counts.ia_culls;
    stats->split_packets += counts.split;
    const uint32_t flags = opt ? opt->flags : 0;
    if (anyhit) {
        for (uint32_t i = 0; i < n; ++i) occ[i] = pkt.prim[i] != SIDX_NO_HIT;
        return;
    }
    uint32_t i = 0;
    for (sidx_hit *row = hits; i < n; row += stride)
        for (uint32_t x = 0; x < w; ++x, ++i) {
            sidx_hit *hit = row + x;
            *hit = sidx_hit_none();
            if (pkt.prim[i] == SIDX_NO_HIT) continue;
            hit->t = pkt.best[i];
            hit->prim = pkt.prim[i];
            if (flags & SIDX__PACKET_FINISH) /* a call only when asked */
                sidx__hit_finish(a->mesh, a->opt.tri, pkt.ray[i], flags & SIDX__PACKET_FINISH, 0u, hit);
        }
}
