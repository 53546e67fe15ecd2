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
 * the traced copy of the single-ray walk (bvh_wide_walk.h), as before.
 *
 * Like packet.c the walk is written once and instantiated per width and
 * instruction set: AVX2 (8-lane ray groups; 8 boxes per pass for bvh8, 4
 * with SSE for bvh4; the SSE4.1 triangle kernel) and a scalar copy doing
 * the same arithmetic in loops — the readable reference, run by the tests
 * with SIDX_SIMD=scalar. */
#include "bvh_wide_internal.h"
#include "packet_internal.h"
#if (defined(__x86_64__) || defined(__i386__)) && defined(__SSE2__)
#include <immintrin.h>
#define PW_X86 1 /* SSE2 (the set-up, the triangle blocks) always; AVX2 chosen at run time */
#endif

#define GL 8u                      /* rays per group (one AVX register) */
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
typedef struct wpk {
    _Alignas(32) float ox[NLANES], oy[NLANES], oz[NLANES];
    _Alignas(32) float ix[NLANES], iy[NLANES], iz[NLANES];
    _Alignas(32) float fx[NLANES], fy[NLANES], fz[NLANES]; /* 1/d · Ize factor (far planes) */
    _Alignas(32) float tmin[NLANES], best[NLANES];
    /* best · Ize factor: what boxes are clipped to.  A rounded entry an ulp
     * beyond the best hit must not drop a box holding a triangle an ulp
     * nearer (bvh_slab, bvh_internal.h, says more); hits still need t < best. */
    _Alignas(32) float bbest[NLANES];
    float scale;
    uint32_t prim[NLANES];
    const sidx_ray *ray[NLANES];
    uint64_t live;         /* the real rays: bits 0 .. n−1 */
    uint64_t done;         /* any-hit: rays already occluded */
    uint32_t n, ngroups;
    uint32_t no[3], fo[3]; /* near / far plane row of each axis in a node (k or 3 + k), from the common signs */
    int anyhit;
    /* interval arithmetic: ia = 0 when some inverse direction is not finite */
    int ia;
    float ia_on[3], ia_of[3];  /* origin end giving the smallest entry / the largest exit */
    float ia_i0[3], ia_i1[3];  /* inverse direction range */
    float ia_f0[3], ia_f1[3];  /* the same times the Ize factor */
    float ia_tmin, ia_tmax;    /* smallest tmin, largest tmax */
} wpk;

/* Work counters, in locals during the walk (see packet.c: through the
 * stats pointer each would cost a load and a store per node). */
typedef struct wcount {
    uint64_t visits, boxes, prims, ia_tests, ia_culls, split;
} wcount;

/* ---- set-up ---------------------------------------------------------------------- */

/* The rays into the packet's arrays, a plain copy (the arithmetic comes
 * in wpk_bounds), row by row from the caller's image.  Padding lanes
 * repeat ray 0 (so they never widen the interval bounds nor change the
 * sign class) with tmin = +inf, best = −inf (so they miss every box). */
static SIDX_INLINE void wpk_load(wpk *P, const sidx_ray *rays, uint32_t n, uint32_t w, size_t stride, int anyhit)
{
    P->n = n;
    P->ngroups = (n + GL - 1) / GL;
    P->anyhit = anyhit;
    P->done = 0;
    uint32_t i = 0;
    for (const sidx_ray *row = rays; i < n; row += stride)
        for (uint32_t x = 0; x < w; ++x, ++i) {
            const sidx_ray *r = row + x;
            P->ray[i] = r;
            P->ox[i] = r->org.x; P->oy[i] = r->org.y; P->oz[i] = r->org.z;
            P->ix[i] = r->inv_dir.x; P->iy[i] = r->inv_dir.y; P->iz[i] = r->inv_dir.z;
            P->tmin[i] = r->tmin;
            P->best[i] = r->tmax;
            P->bbest[i] = r->tmax * P->scale;
            P->prim[i] = SIDX_NO_HIT;
        }
    for (; i < P->ngroups * GL; ++i) {
        P->ray[i] = rays;
        P->ox[i] = P->ox[0]; P->oy[i] = P->oy[0]; P->oz[i] = P->oz[0];
        P->ix[i] = P->ix[0]; P->iy[i] = P->iy[0]; P->iz[i] = P->iz[0];
        P->tmin[i] = INFINITY;
        P->best[i] = P->bbest[i] = -INFINITY;
        P->prim[i] = SIDX_NO_HIT;
    }
}

/* Direction-sign class of lane i: bit k set when d_k < 0 (−0 included:
 * 1/−0 = −inf keeps the sign, as sidx_ray.sign does). */
static SIDX_INLINE unsigned lane_class(const wpk *P, uint32_t i)
{
    return (unsigned)(signbit(P->ix[i]) != 0) | (unsigned)(signbit(P->iy[i]) != 0) << 1 |
           (unsigned)(signbit(P->iz[i]) != 0) << 2;
}

/* Do all lanes share lane 0's sign class?  (With SSE: the sign bits of 4
 * lanes per movemask.) */
static SIDX_INLINE int wpk_uniform(const wpk *P, const int avx)
{
    const uint32_t nl = P->ngroups * GL;
#ifdef PW_X86
    if (avx) {
        const float *const arr[3] = {P->ix, P->iy, P->iz};
        unsigned bad = 0;
        for (int k = 0; k < 3; ++k) {
            const unsigned want = signbit(arr[k][0]) ? 0xFu : 0u;
            for (uint32_t i = 0; i < nl; i += 4) bad |= (unsigned)_mm_movemask_ps(_mm_load_ps(arr[k] + i)) ^ want;
        }
        return bad == 0;
    }
#else
    (void)avx;
#endif
    const unsigned c0 = lane_class(P, 0);
    for (uint32_t i = 1; i < nl; ++i)
        if (lane_class(P, i) != c0) return 0;
    return 1;
}

/* Far-plane factors 1/d·S for every lane, and the interval bounds of the
 * rays in `live` (all of them share sign class c). */
static SIDX_INLINE void wpk_bounds(wpk *P, uint64_t live, unsigned c, float scale, const int avx)
{
    float omin[3], omax[3], imin[3], imax[3], tmn = INFINITY, tmx = -INFINITY;
    P->live = live;
    const uint32_t nl = P->ngroups * GL;
    for (uint32_t i = 0; i < nl; ++i) {
        P->fx[i] = P->ix[i] * scale;
        P->fy[i] = P->iy[i] * scale;
        P->fz[i] = P->iz[i] * scale;
    }
    const float *const arr[3][2] = {{P->ox, P->ix}, {P->oy, P->iy}, {P->oz, P->iz}};
    const uint64_t real = P->n == 64 ? ~0ull : (1ull << P->n) - 1u;
#ifdef PW_X86
    if (avx && live == real) {
        /* every lane counts (padding repeats ray 0): 4 lanes at a time */
        for (int k = 0; k < 3; ++k) {
            __m128 o0 = _mm_load_ps(arr[k][0]), o1 = o0, i0 = _mm_load_ps(arr[k][1]), i1 = i0;
            for (uint32_t i = 4; i < nl; i += 4) {
                const __m128 o = _mm_load_ps(arr[k][0] + i), v = _mm_load_ps(arr[k][1] + i);
                o0 = _mm_min_ps(o, o0); o1 = _mm_max_ps(o, o1);
                i0 = _mm_min_ps(v, i0); i1 = _mm_max_ps(v, i1);
            }
            o0 = _mm_min_ps(o0, _mm_shuffle_ps(o0, o0, _MM_SHUFFLE(1, 0, 3, 2)));
            o0 = _mm_min_ps(o0, _mm_shuffle_ps(o0, o0, _MM_SHUFFLE(2, 3, 0, 1)));
            o1 = _mm_max_ps(o1, _mm_shuffle_ps(o1, o1, _MM_SHUFFLE(1, 0, 3, 2)));
            o1 = _mm_max_ps(o1, _mm_shuffle_ps(o1, o1, _MM_SHUFFLE(2, 3, 0, 1)));
            i0 = _mm_min_ps(i0, _mm_shuffle_ps(i0, i0, _MM_SHUFFLE(1, 0, 3, 2)));
            i0 = _mm_min_ps(i0, _mm_shuffle_ps(i0, i0, _MM_SHUFFLE(2, 3, 0, 1)));
            i1 = _mm_max_ps(i1, _mm_shuffle_ps(i1, i1, _MM_SHUFFLE(1, 0, 3, 2)));
            i1 = _mm_max_ps(i1, _mm_shuffle_ps(i1, i1, _MM_SHUFFLE(2, 3, 0, 1)));
            omin[k] = _mm_cvtss_f32(o0); omax[k] = _mm_cvtss_f32(o1);
            imin[k] = _mm_cvtss_f32(i0); imax[k] = _mm_cvtss_f32(i1);
        }
        /* padding lanes (tmin +inf, best −inf) change neither */
        __m128 t0 = _mm_load_ps(P->tmin), t1 = _mm_load_ps(P->bbest);
        for (uint32_t i = 4; i < nl; i += 4) {
            t0 = _mm_min_ps(_mm_load_ps(P->tmin + i), t0);
            t1 = _mm_max_ps(_mm_load_ps(P->bbest + i), t1);
        }
        t0 = _mm_min_ps(t0, _mm_shuffle_ps(t0, t0, _MM_SHUFFLE(1, 0, 3, 2)));
        t0 = _mm_min_ps(t0, _mm_shuffle_ps(t0, t0, _MM_SHUFFLE(2, 3, 0, 1)));
        t1 = _mm_max_ps(t1, _mm_shuffle_ps(t1, t1, _MM_SHUFFLE(1, 0, 3, 2)));
        t1 = _mm_max_ps(t1, _mm_shuffle_ps(t1, t1, _MM_SHUFFLE(2, 3, 0, 1)));
        tmn = _mm_cvtss_f32(t0);
        tmx = _mm_cvtss_f32(t1);
    } else
#else
    (void)avx;
    (void)real;
#endif
    {
        for (int k = 0; k < 3; ++k) {
            omin[k] = imin[k] = INFINITY;
            omax[k] = imax[k] = -INFINITY;
        }
        for (uint64_t mm = live; mm; mm &= mm - 1) {
            const uint32_t i = (uint32_t)__builtin_ctzll(mm);
            for (int k = 0; k < 3; ++k) {
                const float o = arr[k][0][i], v = arr[k][1][i];
                omin[k] = o < omin[k] ? o : omin[k];
                omax[k] = o > omax[k] ? o : omax[k];
                imin[k] = v < imin[k] ? v : imin[k];
                imax[k] = v > imax[k] ? v : imax[k];
            }
            tmn = P->tmin[i] < tmn ? P->tmin[i] : tmn;
            tmx = P->bbest[i] > tmx ? P->bbest[i] : tmx;
        }
    }
    int finite = 1;
    for (int k = 0; k < 3; ++k) {
        const int s = (int)(c >> k) & 1;
        /* rows of a node: 0..2 lo, 3..5 hi; a negative direction enters through hi */
        P->no[k] = (uint32_t)(s ? 3 + k : k);
        P->fo[k] = (uint32_t)(s ? k : 3 + k);
        /* The entry t = (p − o)·inv is smallest for the largest p − o when
         * inv < 0 (o = omin), for the smallest when inv > 0 (o = omax); the
         * exit the other way round.  x·S is monotone, so the far factors'
         * range is the ends times S. */
        P->ia_on[k] = s ? omin[k] : omax[k];
        P->ia_of[k] = s ? omax[k] : omin[k];
        P->ia_i0[k] = imin[k];
        P->ia_i1[k] = imax[k];
        P->ia_f0[k] = imin[k] * scale;
        P->ia_f1[k] = imax[k] * scale;
        /* an infinite inverse direction would be at one of the ends */
        finite &= isfinite(P->ia_f0[k]) && isfinite(P->ia_f1[k]);
    }
    P->ia_tmin = tmn;
    P->ia_tmax = tmx;
    P->ia = finite;
}

/* ---- kernels: the portable reference ---------------------------------------------- */

/* Interval test of the W child boxes; key[s] receives the lower bound of
 * every ray's entry into slot s (the order of the children). */
static SIDX_INLINE unsigned ia_slots_scalar(const float *nd, const uint32_t W, const wpk *P, float *key)
{
    unsigned m = 0;
    for (uint32_t s = 0; s < W; ++s) {
        float L = P->ia_tmin, U = P->ia_tmax;
        for (int k = 0; k < 3; ++k) {
            const float dn = nd[P->no[k] * W + s] - P->ia_on[k], df = nd[P->fo[k] * W + s] - P->ia_of[k];
            const float a0 = dn * P->ia_i0[k], a1 = dn * P->ia_i1[k];
            const float b0 = df * P->ia_f0[k], b1 = df * P->ia_f1[k];
            const float lo = a0 < a1 ? a0 : a1, hi = b0 > b1 ? b0 : b1;
            L = lo > L ? lo : L;
            U = hi < U ? hi : U;
        }
        key[s] = L;
        m |= (unsigned)(L <= U) << s;
    }
    return m;
}

/* Ray i against the W child boxes: the single-ray test of bvh_wide_walk.h
 * (slab value first, so a NaN one never narrows the interval). */
static SIDX_INLINE unsigned ray_slots_scalar(const float *nd, const uint32_t W, const wpk *P, uint32_t i, float *tn)
{
    const float o[3] = {P->ox[i], P->oy[i], P->oz[i]}, inv[3] = {P->ix[i], P->iy[i], P->iz[i]},
                fin[3] = {P->fx[i], P->fy[i], P->fz[i]};
    unsigned m = 0;
    for (uint32_t s = 0; s < W; ++s) {
        float t0 = P->tmin[i], t1 = P->bbest[i];
        for (int k = 0; k < 3; ++k) {
            const float a = (nd[P->no[k] * W + s] - o[k]) * inv[k];
            const float b = (nd[P->fo[k] * W + s] - o[k]) * fin[k];
            t0 = a > t0 ? a : t0;
            t1 = b < t1 ? b : t1;
        }
        if (tn) tn[s] = t0;
        m |= (unsigned)(t0 <= t1) << s;
    }
    return m;
}

/* Slot s of a node against rays 8g .. 8g+7: bit l for ray 8g + l. */
static SIDX_INLINE unsigned group_slot_scalar(const float *nd, const uint32_t W, uint32_t s, const wpk *P, uint32_t g)
{
    unsigned m = 0;
    for (uint32_t l = 0; l < GL; ++l) {
        const uint32_t i = g * GL + l;
        const float o[3] = {P->ox[i], P->oy[i], P->oz[i]}, inv[3] = {P->ix[i], P->iy[i], P->iz[i]},
                    fin[3] = {P->fx[i], P->fy[i], P->fz[i]};
        float t0 = P->tmin[i], t1 = P->bbest[i];
        for (int k = 0; k < 3; ++k) {
            const float a = (nd[P->no[k] * W + s] - o[k]) * inv[k];
            const float b = (nd[P->fo[k] * W + s] - o[k]) * fin[k];
            t0 = a > t0 ? a : t0;
            t1 = b < t1 ? b : t1;
        }
        m |= (unsigned)(t0 <= t1) << l;
    }
    return m;
}

/* Ray i against one leaf (a run of blocks), one triangle after another
 * with a shrinking bound; returns 1 when an any-hit ray is done. */
static SIDX_INLINE int leaf_ray_scalar(const sidx_accel *a, const wide_tri4 *B, wpk *P, uint32_t i)
{
    const sidx_ray *r = P->ray[i];
    for (;; ++B) {
        for (int l = 0; l < 4; ++l) {
            const uint32_t id = B->prim[l] & WIDE_PRIM_MASK;
            if (id == WIDE_PAD_PRIM) continue;
            float t;
            if (wide_lane_test(a, r, B, (unsigned)l, P->best[i], &t, NULL, NULL)) {
                P->prim[i] = id;
                if (P->anyhit) {
                    P->best[i] = P->bbest[i] = -INFINITY; /* misses every box from now on */
                    return 1;
                }
                P->best[i] = t;
                P->bbest[i] = t * P->scale;
            }
        }
        if (B->prim[0] & WIDE_LAST_BLOCK) return 0;
    }
}

/* ---- kernels: AVX2 (and SSE for 4-wide nodes and triangle blocks) ------------------ */

#ifdef PW_X86
/* Not always_inline: the scalar walks mention these calls in branches that
 * fold away, and an always_inline AVX2 callee there would not compile;
 * the flatten attribute of the AVX2 walks inlines them. */
#define AVX __attribute__((target("avx2,fma"))) static inline

AVX unsigned ia_slots_avx(const float *nd, const uint32_t W, const wpk *P, float *key)
{
    if (W == 8) {
        __m256 L = _mm256_set1_ps(P->ia_tmin), U = _mm256_set1_ps(P->ia_tmax);
        for (int k = 0; k < 3; ++k) {
            const __m256 dn = _mm256_sub_ps(_mm256_load_ps(nd + P->no[k] * 8u), _mm256_set1_ps(P->ia_on[k]));
            const __m256 df = _mm256_sub_ps(_mm256_load_ps(nd + P->fo[k] * 8u), _mm256_set1_ps(P->ia_of[k]));
            const __m256 lo = _mm256_min_ps(_mm256_mul_ps(dn, _mm256_set1_ps(P->ia_i0[k])),
                                            _mm256_mul_ps(dn, _mm256_set1_ps(P->ia_i1[k])));
            const __m256 hi = _mm256_max_ps(_mm256_mul_ps(df, _mm256_set1_ps(P->ia_f0[k])),
                                            _mm256_mul_ps(df, _mm256_set1_ps(P->ia_f1[k])));
            L = _mm256_max_ps(lo, L);
            U = _mm256_min_ps(hi, U);
        }
        _mm256_storeu_ps(key, L);
        return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(L, U, _CMP_LE_OQ));
    }
    __m128 L = _mm_set1_ps(P->ia_tmin), U = _mm_set1_ps(P->ia_tmax);
    for (int k = 0; k < 3; ++k) {
        const __m128 dn = _mm_sub_ps(_mm_load_ps(nd + P->no[k] * 4u), _mm_set1_ps(P->ia_on[k]));
        const __m128 df = _mm_sub_ps(_mm_load_ps(nd + P->fo[k] * 4u), _mm_set1_ps(P->ia_of[k]));
        const __m128 lo = _mm_min_ps(_mm_mul_ps(dn, _mm_set1_ps(P->ia_i0[k])), _mm_mul_ps(dn, _mm_set1_ps(P->ia_i1[k])));
        const __m128 hi = _mm_max_ps(_mm_mul_ps(df, _mm_set1_ps(P->ia_f0[k])), _mm_mul_ps(df, _mm_set1_ps(P->ia_f1[k])));
        L = _mm_max_ps(lo, L);
        U = _mm_min_ps(hi, U);
    }
    _mm_storeu_ps(key, L);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(L, U));
}

AVX unsigned ray_slots_avx(const float *nd, const uint32_t W, const wpk *P, uint32_t i, float *tn)
{
    if (W == 8) {
        const __m256 ox = _mm256_broadcast_ss(P->ox + i), oy = _mm256_broadcast_ss(P->oy + i),
                     oz = _mm256_broadcast_ss(P->oz + i);
        const __m256 nx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(nd + P->no[0] * 8u), ox), _mm256_broadcast_ss(P->ix + i));
        const __m256 ny = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(nd + P->no[1] * 8u), oy), _mm256_broadcast_ss(P->iy + i));
        const __m256 nz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(nd + P->no[2] * 8u), oz), _mm256_broadcast_ss(P->iz + i));
        const __m256 fx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(nd + P->fo[0] * 8u), ox), _mm256_broadcast_ss(P->fx + i));
        const __m256 fy = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(nd + P->fo[1] * 8u), oy), _mm256_broadcast_ss(P->fy + i));
        const __m256 fz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(nd + P->fo[2] * 8u), oz), _mm256_broadcast_ss(P->fz + i));
        __m256 t0 = _mm256_max_ps(nx, _mm256_broadcast_ss(P->tmin + i));
        t0 = _mm256_max_ps(ny, t0);
        t0 = _mm256_max_ps(nz, t0);
        __m256 t1 = _mm256_min_ps(fx, _mm256_broadcast_ss(P->bbest + i));
        t1 = _mm256_min_ps(fy, t1);
        t1 = _mm256_min_ps(fz, t1);
        if (tn) _mm256_storeu_ps(tn, t0);
        return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ));
    }
    const __m128 ox = _mm_broadcast_ss(P->ox + i), oy = _mm_broadcast_ss(P->oy + i), oz = _mm_broadcast_ss(P->oz + i);
    const __m128 nx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(nd + P->no[0] * 4u), ox), _mm_broadcast_ss(P->ix + i));
    const __m128 ny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(nd + P->no[1] * 4u), oy), _mm_broadcast_ss(P->iy + i));
    const __m128 nz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(nd + P->no[2] * 4u), oz), _mm_broadcast_ss(P->iz + i));
    const __m128 fx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(nd + P->fo[0] * 4u), ox), _mm_broadcast_ss(P->fx + i));
    const __m128 fy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(nd + P->fo[1] * 4u), oy), _mm_broadcast_ss(P->fy + i));
    const __m128 fz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(nd + P->fo[2] * 4u), oz), _mm_broadcast_ss(P->fz + i));
    __m128 t0 = _mm_max_ps(nx, _mm_broadcast_ss(P->tmin + i));
    t0 = _mm_max_ps(ny, t0);
    t0 = _mm_max_ps(nz, t0);
    __m128 t1 = _mm_min_ps(fx, _mm_broadcast_ss(P->bbest + i));
    t1 = _mm_min_ps(fy, t1);
    t1 = _mm_min_ps(fz, t1);
    if (tn) _mm_storeu_ps(tn, t0);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(t0, t1));
}

AVX unsigned group_slot_avx(const float *nd, const uint32_t W, uint32_t s, const wpk *P, uint32_t g)
{
    const uint32_t i = g * GL;
    const __m256 ox = _mm256_load_ps(P->ox + i), oy = _mm256_load_ps(P->oy + i), oz = _mm256_load_ps(P->oz + i);
    const __m256 nx = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(nd + P->no[0] * W + s), ox), _mm256_load_ps(P->ix + i));
    const __m256 ny = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(nd + P->no[1] * W + s), oy), _mm256_load_ps(P->iy + i));
    const __m256 nz = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(nd + P->no[2] * W + s), oz), _mm256_load_ps(P->iz + i));
    const __m256 fx = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(nd + P->fo[0] * W + s), ox), _mm256_load_ps(P->fx + i));
    const __m256 fy = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(nd + P->fo[1] * W + s), oy), _mm256_load_ps(P->fy + i));
    const __m256 fz = _mm256_mul_ps(_mm256_sub_ps(_mm256_broadcast_ss(nd + P->fo[2] * W + s), oz), _mm256_load_ps(P->fz + i));
    __m256 t0 = _mm256_max_ps(nx, _mm256_load_ps(P->tmin + i));
    t0 = _mm256_max_ps(ny, t0);
    t0 = _mm256_max_ps(nz, t0);
    __m256 t1 = _mm256_min_ps(fx, _mm256_load_ps(P->bbest + i));
    t1 = _mm256_min_ps(fy, t1);
    t1 = _mm256_min_ps(fz, t1);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ));
}

/* Ray i against one leaf, a block per SSE pass; a block with a zero edge
 * function goes through the scalar loop (on that block only). */
static SIDX_INLINE int leaf_ray_sse(const sidx_accel *a, const wide_tri4 *B, wpk *P, uint32_t i)
{
    const sidx_ray *r = P->ray[i];
    wide_tri_ray T; /* the shared kernel of bvh_wide_internal.h, set up once per leaf */
    wide_tri_ray_init(&T, r);
    for (;; ++B) {
        float t;
        unsigned lane;
        const int h = wide_tri4_test(B, &T, P->best[i], &t, &lane, NULL);
        if (h > 0) {
            P->prim[i] = B->prim[lane] & WIDE_PRIM_MASK;
            if (P->anyhit) {
                P->best[i] = P->bbest[i] = -INFINITY;
                return 1;
            }
            P->best[i] = t;
            P->bbest[i] = t * P->scale;
        } else if (SIDX_UNLIKELY(h < 0)) {
            for (int l = 0; l < 4; ++l) {
                const uint32_t id = B->prim[l] & WIDE_PRIM_MASK;
                if (id == WIDE_PAD_PRIM) continue;
                if (wide_lane_test(a, r, B, (unsigned)l, P->best[i], &t, NULL, NULL)) {
                    P->prim[i] = id;
                    if (P->anyhit) {
                        P->best[i] = P->bbest[i] = -INFINITY;
                        return 1;
                    }
                    P->best[i] = t;
                    P->bbest[i] = t * P->scale;
                }
            }
        }
        if (B->prim[0] & WIDE_LAST_BLOCK) return 0;
    }
}
#undef AVX
#endif

/* ---- the walk ---------------------------------------------------------------------- */

/* A deferred child: its reference (node index, or WIDE_LEAF_BIT | first
 * block) and the rays that hit its box. */
typedef struct wstack {
    uint32_t ref;
    uint64_t rays;
} wstack;

/* Written once, instantiated for W = 4, 8 and avx = 0, 1 (constants, so
 * every branch on them folds away); simd_tri: the watertight SIMD kernel
 * applies (the structure's triangle test is the watertight one). */
static SIDX_INLINE void wide_walk_impl(const sidx_accel *a, wpk *P, wcount *C, const uint32_t W, const int avx,
                                       const int simd_tri)
{
    const wide_bvh *wb = a->impl;
    (void)avx; /* only read by the x86 kernels */
    if (wb->num_inner == 0) return;
    const float *nodes = wb->nodes;
    const unsigned all_slots = (1u << W) - 1u;
    wstack stk[WIDE_STACK];
    uint32_t sp = 0, ref = 0;
    uint64_t M = P->live;
    uint64_t visits = 0, boxes = 0, prims = 0, ia_tests = 0, ia_culls = 0;
    for (;;) {
        if (!(ref & WIDE_LEAF_BIT)) {
            const float *nd = nodes + (size_t)ref * 8u * W;
            const uint32_t *ch = wide_child(nd, W);
            _Alignas(32) float key[8];
            uint64_t cm[8];
            ++visits;
            unsigned hitm = 0;
            if ((uint32_t)__builtin_popcountll(M) <= SOLO) {
                /* One ray (or very few) left: their own W-box tests, as in
                 * the single-ray walk; the first one's entry distances
                 * order the children (the packet's interval bounds would
                 * only cost here). */
                for (uint32_t s = 0; s < W; ++s) cm[s] = 0;
                float *kp = key;
                for (uint64_t mm = M; mm; mm &= mm - 1) {
                    const uint32_t i = (uint32_t)__builtin_ctzll(mm);
#ifdef PW_X86
                    unsigned r = avx ? ray_slots_avx(nd, W, P, i, kp) : ray_slots_scalar(nd, W, P, i, kp);
#else
                    unsigned r = ray_slots_scalar(nd, W, P, i, kp);
#endif
                    kp = NULL;
                    hitm |= r;
                    for (; r; r &= r - 1) cm[__builtin_ctz(r)] |= 1ull << i;
                    boxes += W;
                }
                goto children;
            }
            /* 1. the interval test: children no ray can hit */
            unsigned cand = all_slots;
            if (P->ia) {
#ifdef PW_X86
                cand = avx ? ia_slots_avx(nd, W, P, key) : ia_slots_scalar(nd, W, P, key);
#else
                cand = ia_slots_scalar(nd, W, P, key);
#endif
                ia_tests += W;
                ia_culls += (uint64_t)(W - (uint32_t)__builtin_popcount(cand));
            } else {
                for (uint32_t s = 0; s < W; ++s) key[s] = (float)s;
            }
            if (cand) {
                /* Per-ray or per-group tests, whichever costs fewer SIMD
                 * passes: a ray's pass covers all W boxes, a group's pass
                 * one box for 8 rays (groups without an active ray are
                 * skipped). */
                const uint32_t active = (uint32_t)__builtin_popcountll(M);
                uint64_t gb = M | M >> 4; /* bit 8g: group g has an active ray */
                gb |= gb >> 2;
                gb |= gb >> 1;
                gb &= 0x0101010101010101ull;
                const uint32_t ncand = (uint32_t)__builtin_popcount(cand);
                if (active <= THIN && active < ncand * (uint32_t)__builtin_popcountll(gb)) {
                    /* 2. few rays: each tests the W boxes at once */
                    for (uint32_t s = 0; s < W; ++s) cm[s] = 0;
                    for (uint64_t mm = M; mm; mm &= mm - 1) {
                        const uint32_t i = (uint32_t)__builtin_ctzll(mm);
#ifdef PW_X86
                        unsigned r = avx ? ray_slots_avx(nd, W, P, i, NULL) : ray_slots_scalar(nd, W, P, i, NULL);
#else
                        unsigned r = ray_slots_scalar(nd, W, P, i, NULL);
#endif
                        r &= cand;
                        hitm |= r;
                        for (; r; r &= r - 1) cm[__builtin_ctz(r)] |= 1ull << i;
                    }
                    boxes += (uint64_t)active * W;
                } else {
                    /* 3. many rays: each candidate box against the groups of 8 */
                    for (unsigned cc = cand; cc; cc &= cc - 1) {
                        const uint32_t s = (uint32_t)__builtin_ctz(cc);
                        uint64_t mm = 0;
                        for (uint64_t gg = gb; gg; gg &= gg - 1) {
                            const uint32_t g = (uint32_t)__builtin_ctzll(gg) / GL;
#ifdef PW_X86
                            const unsigned r = avx ? group_slot_avx(nd, W, s, P, g) : group_slot_scalar(nd, W, s, P, g);
#else
                            const unsigned r = group_slot_scalar(nd, W, s, P, g);
#endif
                            mm |= (uint64_t)r << (g * GL);
                        }
                        mm &= M;
                        cm[s] = mm;
                        hitm |= (unsigned)(mm != 0) << s;
                    }
                    boxes += (uint64_t)ncand * (uint64_t)__builtin_popcountll(gb) * GL;
                }
            }
        children:
#if PW_PREFETCH
            /* Several children hit: start fetching them all (a node is 4
             * cache lines, a block 3), as the single-ray walk does — the
             * nearest is needed next, the others when popped; not the lone
             * child (docs/performance.md, "Packets and frustums"). */
            for (unsigned pm = hitm & (hitm - 1) ? hitm : 0; pm; pm &= pm - 1) {
                const uint32_t c = ch[__builtin_ctz(pm)];
                const char *p = (c & WIDE_LEAF_BIT) ? (const char *)(wb->blocks + (c & ~WIDE_LEAF_BIT))
                                                    : (const char *)(nodes + (size_t)c * 8u * W);
                __builtin_prefetch(p);
                __builtin_prefetch(p + 64);
                __builtin_prefetch(p + 128);
                if (!(c & WIDE_LEAF_BIT) && W == 8) __builtin_prefetch(p + 192);
            }
#endif
            if (hitm) {
                const uint32_t s0 = (uint32_t)__builtin_ctz(hitm);
                if (!(hitm & (hitm - 1))) { /* one child: descend, no stack */
                    ref = ch[s0];
                    M = cm[s0];
                    continue;
                }
                const unsigned rest = hitm & (hitm - 1);
                if (!(rest & (rest - 1))) {
                    /* Two (the common case of several): one compare, the
                     * farther waits; ties go to the lower slot. */
                    const uint32_t s1 = (uint32_t)__builtin_ctz(rest);
                    const int first0 = P->anyhit || key[s0] <= key[s1];
                    const uint32_t nr = first0 ? s0 : s1, fr = first0 ? s1 : s0;
                    stk[sp++] = (wstack){ch[fr], cm[fr]};
                    ref = ch[nr];
                    M = cm[nr];
                    continue;
                }
                /* More: order the slots farthest first (insertion sort on
                 * the entry key, stable, so equal keys keep slot order and
                 * the lower slot is visited first), defer all but the
                 * nearest, descend into it. */
                uint32_t ord[8], no = 0;
                for (unsigned hh = hitm; hh; hh &= hh - 1) {
                    const uint32_t s = (uint32_t)__builtin_ctz(hh);
                    uint32_t j = no++;
                    if (!P->anyhit)
                        while (j > 0 && key[ord[j - 1]] <= key[s]) {
                            ord[j] = ord[j - 1];
                            --j;
                        }
                    ord[j] = s;
                }
                for (uint32_t k = 0; k + 1 < no; ++k) stk[sp++] = (wstack){ch[ord[k]], cm[ord[k]]};
                ref = ch[ord[no - 1]];
                M = cm[ord[no - 1]];
                continue;
            }
        } else {
            /* a leaf: each ray of the mask against its blocks */
            const wide_tri4 *B = wb->blocks + (ref & ~WIDE_LEAF_BIT);
            uint32_t nb = 1;
            for (const wide_tri4 *b = B; !(b->prim[0] & WIDE_LAST_BLOCK); ++b) ++nb;
#ifdef PW_X86
            if (avx && simd_tri) {
                for (uint64_t mm = M; mm; mm &= mm - 1) {
                    const uint32_t i = (uint32_t)__builtin_ctzll(mm);
                    P->done |= (uint64_t)leaf_ray_sse(a, B, P, i) << i;
                }
            } else
#else
            (void)simd_tri;
#endif
            {
                for (uint64_t mm = M; mm; mm &= mm - 1) {
                    const uint32_t i = (uint32_t)__builtin_ctzll(mm);
                    P->done |= (uint64_t)leaf_ray_scalar(a, B, P, i) << i;
                }
            }
            prims += (uint64_t)__builtin_popcountll(M) * nb * 4u;
            if (P->anyhit && !(P->live & ~P->done)) break;
        }
        /* Pop the next deferred child that still has rays to trace.
         * Rejected alternative: docs/performance.md, "Packets and frustums". */
        for (;;) {
            if (sp == 0) goto out;
            --sp;
            ref = stk[sp].ref;
            M = stk[sp].rays & ~P->done;
            if (M) break;
        }
    }
out:
    C->visits += visits;
    C->boxes += boxes;
    C->prims += prims;
    C->ia_tests += ia_tests;
    C->ia_culls += ia_culls;
}

/* Load a tile, then one walk per direction-sign class present (a tile
 * straddling an axis of the camera holds 2 or 4; each class is its own
 * packet with its own near planes and interval bounds). */
static SIDX_INLINE void wide_packet_impl(const sidx_accel *a, wpk *P, wcount *C, const sidx_ray *rays, uint32_t n,
                                         uint32_t w, size_t stride, int anyhit, const uint32_t W, const int avx,
                                         const int simd_tri)
{
    const float scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    P->scale = scale;
    wpk_load(P, rays, n, w, stride, anyhit);
    const uint64_t real = n == 64 ? ~0ull : (1ull << n) - 1u;
    if (wpk_uniform(P, avx)) {
        wpk_bounds(P, real, lane_class(P, 0), scale, avx);
        wide_walk_impl(a, P, C, W, avx, simd_tri);
        return;
    }
    uint64_t live[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (uint32_t i = 0; i < n; ++i) live[lane_class(P, i)] |= 1ull << i;
    C->split++;
    for (unsigned c = 0; c < 8; ++c) {
        if (!live[c]) continue;
        wpk_bounds(P, live[c], c, scale, avx);
        wide_walk_impl(a, P, C, W, avx, simd_tri);
    }
}

#ifdef PW_X86
#define PW_AVX_WALK(name, Wd)                                                                                          \
    __attribute__((target("avx2,fma"), flatten)) static void name(const sidx_accel *a, wpk *P, wcount *C,              \
                                                                  const sidx_ray *rays, uint32_t n, uint32_t w,        \
                                                                  size_t stride, int anyhit, int simd_tri)             \
    {                                                                                                                  \
        if (simd_tri) wide_packet_impl(a, P, C, rays, n, w, stride, anyhit, Wd, 1, 1);                               \
        else wide_packet_impl(a, P, C, rays, n, w, stride, anyhit, Wd, 1, 0);                                        \
    }
PW_AVX_WALK(walk8_avx, 8)
PW_AVX_WALK(walk4_avx, 4)
#undef PW_AVX_WALK
#endif
static void walk8_scalar(const sidx_accel *a, wpk *P, wcount *C, const sidx_ray *rays, uint32_t n, uint32_t w,
                         size_t stride, int anyhit)
{
    wide_packet_impl(a, P, C, rays, n, w, stride, anyhit, 8, 0, 0);
}
static void walk4_scalar(const sidx_accel *a, wpk *P, wcount *C, const sidx_ray *rays, uint32_t n, uint32_t w,
                         size_t stride, int anyhit)
{
    wide_packet_impl(a, P, C, rays, n, w, stride, anyhit, 4, 0, 0);
}

/* ---- entry (from packet.c) ----------------------------------------------------------- */

void sidx__packet_wide(const sidx_accel *a, const sidx_ray *rays, uint32_t n, uint32_t w, size_t stride,
                      const sidx_packet_options *opt, sidx_hit *hits, uint8_t *occ, sidx_packet_stats *stats, int avx)
{
    const wide_bvh *wb = a->impl;
    const int anyhit = hits == NULL;
    wpk P;
    wcount C = {0, 0, 0, 0, 0, 0};
#ifdef PW_X86
    if (avx) {
        const int st = a->opt.tri == SIDX_TRI_WATERTIGHT;
        if (wb->width == 8) walk8_avx(a, &P, &C, rays, n, w, stride, anyhit, st);
        else walk4_avx(a, &P, &C, rays, n, w, stride, anyhit, st);
    } else
#else
    (void)avx;
#endif
    {
        if (wb->width == 8) walk8_scalar(a, &P, &C, rays, n, w, stride, anyhit);
        else walk4_scalar(a, &P, &C, rays, n, w, stride, anyhit);
    }
    stats->node_visits += C.visits;
    stats->box_tests += C.boxes;
    stats->prim_tests += C.prims;
    stats->interval_tests += C.ia_tests;
    stats->interval_culls += C.ia_culls;
    stats->split_packets += C.split;
    const uint32_t flags = opt ? opt->flags : 0;
    if (anyhit) {
        for (uint32_t i = 0; i < n; ++i) occ[i] = P.prim[i] != SIDX_NO_HIT;
        return;
    }
    uint32_t i = 0;
    for (sidx_hit *row = hits; i < n; row += stride)
        for (uint32_t x = 0; x < w; ++x, ++i) {
            sidx_hit *h = row + x;
            *h = sidx_hit_none();
            if (P.prim[i] == SIDX_NO_HIT) continue;
            h->t = P.best[i];
            h->prim = P.prim[i];
            if (flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)) sidx__packet_finish(a, P.ray[i], flags, h);
        }
}
