/* packet.c — coherent ray packets and frustum culling over the binary BVH
 * (sidx/packet.h explains the method and cites the papers).
 *
 * Layout: a packet holds its rays in structure-of-arrays form, padded to
 * groups of 8 lanes; a padding lane has best = −inf so every box and every
 * triangle misses it.  The kernels that test one box or one triangle
 * against a group of 8 rays exist twice: AVX2 (target attribute, chosen
 * at run time) and a scalar loop doing the same arithmetic.  They are
 * called per group, not inlined into the walk, which keeps one walk for
 * both instruction sets; a call costs a few cycles against 8 slab tests.
 *
 * Correctness is the single-ray walk's: each lane keeps its own best t,
 * box tests are the robust slab test of bvh_slab (far planes times the
 * Ize factor) against that lane's [tmin, best], triangles the watertight
 * test with that lane's shear constants, and a group whose edge function
 * hits exactly 0 in some lane redoes that lane with the scalar test (which
 * recomputes it in double). */
#include "bvh_internal.h"
#include "bvh_wide_internal.h"
#include "packet_internal.h"
#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define PKT_X86 1
#endif

#define GL 8u                      /* lanes per group */
#define NG (SIDX_PACKET_MAX / GL)  /* groups per packet */
#define STACK (2u * BVH_DEPTH_LIMIT + 2u)

typedef struct pkt {
    _Alignas(32) float ox[SIDX_PACKET_MAX], oy[SIDX_PACKET_MAX], oz[SIDX_PACKET_MAX];
    _Alignas(32) float ix[SIDX_PACKET_MAX], iy[SIDX_PACKET_MAX], iz[SIDX_PACKET_MAX];
    _Alignas(32) float fx[SIDX_PACKET_MAX], fy[SIDX_PACKET_MAX], fz[SIDX_PACKET_MAX]; /* 1/d · Ize factor */
    _Alignas(32) float tmin[SIDX_PACKET_MAX], best[SIDX_PACKET_MAX];
    /* watertight test, permuted by the (common) kx, ky, kz */
    _Alignas(32) float okx[SIDX_PACKET_MAX], oky[SIDX_PACKET_MAX], okz[SIDX_PACKET_MAX];
    _Alignas(32) float sx[SIDX_PACKET_MAX], sy[SIDX_PACKET_MAX], sz[SIDX_PACKET_MAX];
    uint32_t prim[SIDX_PACKET_MAX];
    uint32_t n, ngroups;
    int kx, ky, kz, uniform_k;
    uint32_t near_i[3], far_i[3]; /* plane indices in a bvh_node read as float[8], from the common signs */
    uint8_t sign[3];
    int anyhit;
    const sidx_ray *rays;
    /* frustum: 4 inward plane normals through the common origin */
    int frustum;
    float fo[3], fn[4][3], fl1[4]; /* plane normals and their L1 norms */
#if defined(__SSE2__)
    __m128 fnv[3], fpos[3], fl1v; /* the same, one plane per lane; fpos: normal component >= 0 */
#endif
} pkt;

typedef struct walkopt {
    const sidx_accel *a;
    const bvh *b;
    float scale;
    int avx, simd_tri, frustum;
    uint32_t frustum_depth;
    sidx_packet_stats *st;
} walkopt;

/* A deferred node: its index, the first group of rays that may hit it
 * (the groups before it missed its parent) and its depth. */
typedef struct pstack {
    uint32_t node, g, depth;
} pstack;

/* ---- kernels: one box / one triangle against 8 rays -------------------------------- */

static unsigned box8_scalar(const pkt *P, uint32_t g, const float pl[6])
{
    unsigned m = 0;
    for (uint32_t l = 0; l < GL; ++l) {
        const uint32_t i = g * GL + l;
        const float o[3] = {P->ox[i], P->oy[i], P->oz[i]}, inv[3] = {P->ix[i], P->iy[i], P->iz[i]},
                    fin[3] = {P->fx[i], P->fy[i], P->fz[i]};
        float t0 = P->tmin[i], t1 = P->best[i];
        for (int k = 0; k < 3; ++k) {
            const float a = (pl[k] - o[k]) * inv[k], b = (pl[3 + k] - o[k]) * fin[k];
            t0 = a > t0 ? a : t0;
            t1 = b < t1 ? b : t1;
        }
        m |= (unsigned)(t0 <= t1) << l;
    }
    return m;
}

#ifdef PKT_X86
__attribute__((target("avx2,fma"))) static unsigned box8_avx2(const pkt *P, uint32_t g, const float pl[6])
{
    const uint32_t i = g * GL;
    const __m256 ox = _mm256_load_ps(P->ox + i), oy = _mm256_load_ps(P->oy + i), oz = _mm256_load_ps(P->oz + i);
    const __m256 nx = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(pl[0]), ox), _mm256_load_ps(P->ix + i));
    const __m256 ny = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(pl[1]), oy), _mm256_load_ps(P->iy + i));
    const __m256 nz = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(pl[2]), oz), _mm256_load_ps(P->iz + i));
    const __m256 fx = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(pl[3]), ox), _mm256_load_ps(P->fx + i));
    const __m256 fy = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(pl[4]), oy), _mm256_load_ps(P->fy + i));
    const __m256 fz = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(pl[5]), oz), _mm256_load_ps(P->fz + i));
    __m256 t0 = _mm256_max_ps(nx, _mm256_load_ps(P->tmin + i)); /* slab value first: NaN never narrows */
    t0 = _mm256_max_ps(ny, t0);
    t0 = _mm256_max_ps(nz, t0);
    __m256 t1 = _mm256_min_ps(fx, _mm256_load_ps(P->best + i));
    t1 = _mm256_min_ps(fy, t1);
    t1 = _mm256_min_ps(fz, t1);
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ));
}
#endif

/* One lane, one triangle, the single-ray test; returns 1 on a hit (best updated). */
static int tri_lane(const walkopt *W, pkt *P, uint32_t i, const bvh_tri *T, uint32_t prim)
{
    if (i >= P->n) return 0;
    float t;
    if (!sidx__tri_test(W->a->opt.tri, &P->rays[i], T->v[0], T->v[1], T->v[2], P->best[i], &t, NULL, NULL))
        return 0;
    P->prim[i] = prim;
    P->best[i] = P->anyhit ? -INFINITY : t; /* an occluded shadow ray is done */
    return 1;
}

static void tri8_scalar(const walkopt *W, pkt *P, uint32_t g, const bvh_tri *T, uint32_t prim)
{
    for (uint32_t l = 0; l < GL; ++l) tri_lane(W, P, g * GL + l, T, prim);
}

#ifdef PKT_X86
/* The watertight test across 8 rays sharing kx, ky, kz: the triangle is
 * broadcast, each lane translates and shears it by its own ray. */
__attribute__((target("avx2,fma"))) static void tri8_avx2(const walkopt *W, pkt *P, uint32_t g, const bvh_tri *T,
                                                          uint32_t prim)
{
    const uint32_t i = g * GL;
    const float *pa = &T->v[0].x, *pb = &T->v[1].x, *pc = &T->v[2].x;
    const __m256 okx = _mm256_load_ps(P->okx + i), oky = _mm256_load_ps(P->oky + i), okz = _mm256_load_ps(P->okz + i);
    const __m256 sx = _mm256_load_ps(P->sx + i), sy = _mm256_load_ps(P->sy + i), sz = _mm256_load_ps(P->sz + i);
    const __m256 ax = _mm256_sub_ps(_mm256_set1_ps(pa[P->kx]), okx), ay = _mm256_sub_ps(_mm256_set1_ps(pa[P->ky]), oky),
                 az = _mm256_sub_ps(_mm256_set1_ps(pa[P->kz]), okz);
    const __m256 bx = _mm256_sub_ps(_mm256_set1_ps(pb[P->kx]), okx), by = _mm256_sub_ps(_mm256_set1_ps(pb[P->ky]), oky),
                 bz = _mm256_sub_ps(_mm256_set1_ps(pb[P->kz]), okz);
    const __m256 cx = _mm256_sub_ps(_mm256_set1_ps(pc[P->kx]), okx), cy = _mm256_sub_ps(_mm256_set1_ps(pc[P->ky]), oky),
                 cz = _mm256_sub_ps(_mm256_set1_ps(pc[P->kz]), okz);
    const __m256 Ax = _mm256_sub_ps(ax, _mm256_mul_ps(sx, az)), Ay = _mm256_sub_ps(ay, _mm256_mul_ps(sy, az));
    const __m256 Bx = _mm256_sub_ps(bx, _mm256_mul_ps(sx, bz)), By = _mm256_sub_ps(by, _mm256_mul_ps(sy, bz));
    const __m256 Cx = _mm256_sub_ps(cx, _mm256_mul_ps(sx, cz)), Cy = _mm256_sub_ps(cy, _mm256_mul_ps(sy, cz));
    const __m256 U = _mm256_sub_ps(_mm256_mul_ps(Cx, By), _mm256_mul_ps(Cy, Bx));
    const __m256 V = _mm256_sub_ps(_mm256_mul_ps(Ax, Cy), _mm256_mul_ps(Ay, Cx));
    const __m256 Wv = _mm256_sub_ps(_mm256_mul_ps(Bx, Ay), _mm256_mul_ps(By, Ax));
    const __m256 zero = _mm256_setzero_ps();
    const unsigned zm = (unsigned)_mm256_movemask_ps(_mm256_or_ps(
        _mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_EQ_OQ), _mm256_cmp_ps(V, zero, _CMP_EQ_OQ)),
        _mm256_cmp_ps(Wv, zero, _CMP_EQ_OQ)));
    const __m256 neg = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_LT_OQ), _mm256_cmp_ps(V, zero, _CMP_LT_OQ)),
                                    _mm256_cmp_ps(Wv, zero, _CMP_LT_OQ));
    const __m256 pos = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_GT_OQ), _mm256_cmp_ps(V, zero, _CMP_GT_OQ)),
                                    _mm256_cmp_ps(Wv, zero, _CMP_GT_OQ));
    const __m256 det = _mm256_add_ps(_mm256_add_ps(U, V), Wv);
    const __m256 Tt = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(U, _mm256_mul_ps(sz, az)), _mm256_mul_ps(V, _mm256_mul_ps(sz, bz))),
                                    _mm256_mul_ps(Wv, _mm256_mul_ps(sz, cz)));
    const __m256 t = _mm256_div_ps(Tt, det);
    const __m256 best = _mm256_load_ps(P->best + i);
    const __m256 ok = _mm256_andnot_ps(
        _mm256_and_ps(neg, pos),
        _mm256_and_ps(_mm256_cmp_ps(det, zero, _CMP_NEQ_UQ),
                      _mm256_and_ps(_mm256_cmp_ps(t, _mm256_load_ps(P->tmin + i), _CMP_GE_OQ),
                                    _mm256_cmp_ps(t, best, _CMP_LT_OQ))));
    unsigned m = (unsigned)_mm256_movemask_ps(ok) & ~zm;
    if (m) {
        _mm256_store_ps(P->best + i, _mm256_blendv_ps(best, P->anyhit ? _mm256_set1_ps(-INFINITY) : t, ok));
        /* ok lanes with a zero edge were blended too; they are redone below */
        while (m) {
            P->prim[i + (uint32_t)__builtin_ctz(m)] = prim;
            m &= m - 1;
        }
    }
    if (SIDX_UNLIKELY(zm)) {
        /* Exact zero edge function: the scalar test (double fallback) for
         * those lanes, from the bound they had before this triangle. */
        const float *bp = (const float *)&best;
        for (unsigned z = zm; z; z &= z - 1) {
            const uint32_t l = (uint32_t)__builtin_ctz(z);
            P->best[i + l] = bp[l];
            tri_lane(W, P, i + l, T, prim);
        }
    }
}
#endif

/* ---- frustum ---------------------------------------------------------------------- */

/* Is the node box possibly inside the pyramid of the corner rays?  Per
 * plane, the box corner farthest along the inward normal decides; a
 * relative margin keeps the test conservative under rounding (see
 * frustum_setup for the bound). */
static int frustum_overlap(const pkt *P, const bvh_node *n)
{
    const float diag = (n->bmax[0] - n->bmin[0]) + (n->bmax[1] - n->bmin[1]) + (n->bmax[2] - n->bmin[2]);
#if defined(__SSE2__)
    /* The 4 planes in the 4 lanes of SSE2 (baseline x86-64): the same
     * operations in the same order as the scalar loop below. */
    __m128 dot = _mm_setzero_ps(), mag = _mm_setzero_ps();
    const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
    for (int k = 0; k < 3; ++k) {
        const __m128 sel = _mm_or_ps(_mm_and_ps(P->fpos[k], _mm_set1_ps(n->bmax[k])),
                                     _mm_andnot_ps(P->fpos[k], _mm_set1_ps(n->bmin[k])));
        const __m128 c = _mm_sub_ps(sel, _mm_set1_ps(P->fo[k]));
        dot = _mm_add_ps(dot, _mm_mul_ps(P->fnv[k], c));
        mag = _mm_add_ps(mag, _mm_and_ps(c, absmask));
    }
    const __m128 lim = _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(-1e-5f), P->fl1v), _mm_add_ps(mag, _mm_set1_ps(diag)));
    return _mm_movemask_ps(_mm_cmplt_ps(dot, lim)) == 0;
#else
    for (int p = 0; p < 4; ++p) {
        const float *nn = P->fn[p];
        float dot = 0.0f, mag = 0.0f;
        for (int k = 0; k < 3; ++k) {
            const float c = (nn[k] >= 0.0f ? n->bmax[k] : n->bmin[k]) - P->fo[k];
            dot += nn[k] * c;
            mag += fabsf(c);
        }
        if (dot < (-1e-5f * P->fl1[p]) * (mag + diag)) return 0;
    }
    return 1;
#endif
}

/* Planes through the common origin spanned by neighbouring corner rays,
 * oriented inward; kept only if every ray of the packet lies inside them
 * (n·d >= −1e-6 |n||d|), which the margin in frustum_overlap (1e-5 times
 * distance plus box size) then covers: a culled box is at least that far
 * outside, a ray at most 1e-6 of its distance. */
static void frustum_setup(pkt *P, const sidx_ray *rays, uint32_t n, uint32_t w)
{
    P->frustum = 0;
    if (w == 0 || n % w || n < 4 || w < 2 || n / w < 2) return;
    const sidx_vec3 c[4] = {rays[0].dir, rays[w - 1].dir, rays[n - 1].dir, rays[n - w].dir}; /* around the tile */
    const sidx_vec3 mid = sidx_v3_add(sidx_v3_add(c[0], c[1]), sidx_v3_add(c[2], c[3]));
    float len2[4];
    for (int p = 0; p < 4; ++p) {
        sidx_vec3 nn = sidx_v3_cross(c[p], c[(p + 1) % 4]);
        if (sidx_v3_dot(nn, mid) < 0.0f) nn = sidx_v3_scale(nn, -1.0f);
        const float len = sidx_v3_length(nn);
        if (!(len > 0.0f) || !isfinite(len)) return;
        len2[p] = len * len;
        P->fn[p][0] = nn.x;
        P->fn[p][1] = nn.y;
        P->fn[p][2] = nn.z;
        P->fl1[p] = fabsf(nn.x) + fabsf(nn.y) + fabsf(nn.z);
    }
    /* Every ray must start at the apex and lie inside the 4 planes:
     * n·d >= −1e-6 |n||d|, without a square root per ray.  One pass over
     * the rays with the 4 planes in the 4 SSE lanes (the same products in
     * the same order as sidx_v3_dot): done plane by plane, this check was
     * most of the set-up (docs/performance.md, "Packets and frustums"). */
#if defined(__SSE2__)
    const __m128 nx = _mm_setr_ps(P->fn[0][0], P->fn[1][0], P->fn[2][0], P->fn[3][0]);
    const __m128 ny = _mm_setr_ps(P->fn[0][1], P->fn[1][1], P->fn[2][1], P->fn[3][1]);
    const __m128 nz = _mm_setr_ps(P->fn[0][2], P->fn[1][2], P->fn[2][2], P->fn[3][2]);
    const __m128 tol = _mm_mul_ps(_mm_set1_ps(1e-12f), _mm_setr_ps(len2[0], len2[1], len2[2], len2[3]));
    __m128 bad = _mm_setzero_ps();
    for (uint32_t i = 0; i < n; ++i) {
        if (i && memcmp(&rays[i].org, &rays[0].org, sizeof rays[0].org)) return;
        const sidx_vec3 d = rays[i].dir;
        const __m128 dd = _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, _mm_set1_ps(d.x)), _mm_mul_ps(ny, _mm_set1_ps(d.y))),
                                     _mm_mul_ps(nz, _mm_set1_ps(d.z)));
        const __m128 d2 = _mm_set1_ps(sidx_v3_dot(d, d));
        bad = _mm_or_ps(bad, _mm_and_ps(_mm_cmplt_ps(dd, _mm_setzero_ps()),
                                        _mm_cmpgt_ps(_mm_mul_ps(dd, dd), _mm_mul_ps(tol, d2))));
    }
    if (_mm_movemask_ps(bad)) return;
#else
    for (uint32_t i = 1; i < n; ++i)
        if (memcmp(&rays[i].org, &rays[0].org, sizeof rays[0].org)) return;
    for (int p = 0; p < 4; ++p) {
        const sidx_vec3 nn = sidx_v3(P->fn[p][0], P->fn[p][1], P->fn[p][2]);
        for (uint32_t i = 0; i < n; ++i) {
            const float dd = sidx_v3_dot(nn, rays[i].dir);
            if (dd < 0.0f && dd * dd > 1e-12f * len2[p] * sidx_v3_dot(rays[i].dir, rays[i].dir)) return;
        }
    }
#endif
    P->fo[0] = rays[0].org.x;
    P->fo[1] = rays[0].org.y;
    P->fo[2] = rays[0].org.z;
#if defined(__SSE2__)
    for (int k = 0; k < 3; ++k) {
        P->fnv[k] = _mm_setr_ps(P->fn[0][k], P->fn[1][k], P->fn[2][k], P->fn[3][k]);
        P->fpos[k] = _mm_cmpge_ps(P->fnv[k], _mm_setzero_ps());
    }
    P->fl1v = _mm_setr_ps(P->fl1[0], P->fl1[1], P->fl1[2], P->fl1[3]);
#endif
    P->frustum = 1;
}

/* ---- set-up ----------------------------------------------------------------------- */

/* 0 when the packet is not coherent enough (direction signs differ). */
static int pkt_setup(pkt *P, const sidx_ray *rays, uint32_t n, float scale, int anyhit)
{
    P->n = n;
    P->ngroups = (n + GL - 1) / GL;
    P->rays = rays;
    P->anyhit = anyhit;
    for (int k = 0; k < 3; ++k) P->sign[k] = rays[0].sign[k];
    P->kx = rays[0].kx;
    P->ky = rays[0].ky;
    P->kz = rays[0].kz;
    P->uniform_k = 1;
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_ray *r = &rays[i];
        if (r->sign[0] != P->sign[0] || r->sign[1] != P->sign[1] || r->sign[2] != P->sign[2]) return 0;
        if (r->kx != P->kx || r->ky != P->ky || r->kz != P->kz) P->uniform_k = 0;
    }
    for (uint32_t i = 0; i < P->ngroups * GL; ++i) {
        if (i < n) {
            const sidx_ray *r = &rays[i];
            const float *o = &r->org.x;
            P->ox[i] = r->org.x; P->oy[i] = r->org.y; P->oz[i] = r->org.z;
            P->ix[i] = r->inv_dir.x; P->iy[i] = r->inv_dir.y; P->iz[i] = r->inv_dir.z;
            P->fx[i] = r->inv_dir.x * scale; P->fy[i] = r->inv_dir.y * scale; P->fz[i] = r->inv_dir.z * scale;
            P->tmin[i] = r->tmin;
            P->best[i] = r->tmax;
            P->okx[i] = o[P->kx]; P->oky[i] = o[P->ky]; P->okz[i] = o[P->kz];
            P->sx[i] = r->sx; P->sy[i] = r->sy; P->sz[i] = r->sz;
        } else { /* padding: misses everything */
            P->ox[i] = P->oy[i] = P->oz[i] = 0.0f;
            P->ix[i] = P->iy[i] = P->iz[i] = P->fx[i] = P->fy[i] = P->fz[i] = 1.0f;
            P->okx[i] = P->oky[i] = P->okz[i] = P->sx[i] = P->sy[i] = 0.0f;
            P->sz[i] = 1.0f;
            P->tmin[i] = INFINITY;
            P->best[i] = -INFINITY;
        }
        P->prim[i] = SIDX_NO_HIT;
    }
    for (int k = 0; k < 3; ++k) {
        P->near_i[k] = (uint32_t)(P->sign[k] ? 4 + k : k);
        P->far_i[k] = (uint32_t)(P->sign[k] ? k : 4 + k);
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
static void single_subtree(const walkopt *W, pkt *P, uint32_t i, uint32_t root)
{
    const bvh *b = W->b;
    const sidx_ray *r = &P->rays[i];
    bvh_ray br;
    bvh_ray_setup(&br, r);
    uint32_t stk[BVH_DEPTH_LIMIT + 1], sp = 0;
    stk[sp++] = root;
    W->st->switched_rays++;
    while (sp) {
        const uint32_t ni = stk[--sp];
        const bvh_node *n = &b->nodes[ni];
        float tn, tf;
        W->st->box_tests++;
        if (!bvh_slab(&br, n, W->scale, r->tmin, P->best[i], &tn, &tf)) continue;
        if (bvh_is_leaf(n)) {
            for (uint32_t k = n->left_or_first; k < n->left_or_first + bvh_count(n); ++k) {
                W->st->prim_tests++;
                if (tri_lane(W, P, i, &b->tris[k], b->prim_id[k]) && P->anyhit) return;
            }
            continue;
        }
        const uint32_t l = ni + 1, rc = n->left_or_first;
        const int s = r->sign[bvh_axis(n)];
        stk[sp++] = s ? l : rc; /* far first, near on top */
        stk[sp++] = s ? rc : l;
    }
}

static int all_done(const pkt *P)
{
    for (uint32_t i = 0; i < P->n; ++i)
        if (P->best[i] != -INFINITY) return 0;
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
static SIDX_INLINE void packet_walk_impl(const walkopt *W, pkt *P, const int avx)
{
    const bvh *b = W->b;
    if (b->num_nodes == 0) return;
    sidx_packet_stats *st = W->st;
    uint64_t visits = 0, boxes = 0, ftests = 0, fculls = 0, prims = 0;
    pstack stk[STACK];
    uint32_t sp = 0;
    stk[sp++] = (pstack){0, 0, 0};
    while (sp) {
        const pstack e = stk[--sp];
        const uint32_t ni = e.node, g0 = e.g, depth = e.depth;
        const bvh_node *n = &b->nodes[ni];
        const float *nf = (const float *)(const void *)n;
        ++visits;
        float pl[6];
        for (int k = 0; k < 3; ++k) {
            pl[k] = nf[P->near_i[k]];
            pl[3 + k] = nf[P->far_i[k]];
        }
        /* First group of rays with a hit; the ones before it miss.  The
         * order of Wald et al. 2007: the first active group first (if it
         * hits, nothing can cull the node), then the frustum, then the
         * remaining groups one by one. */
        uint32_t g = g0;
        unsigned m = 0;
        for (; g < P->ngroups; ++g) {
            /* The frustum only where it can replace two group tests or
             * more: against one it can never save work (a 4x4 tile has
             * only 2 groups, so it never uses the frustum). */
            if (g == g0 + 1 && g + 2 <= P->ngroups && W->frustum &&
                (W->frustum_depth == 0 || depth < W->frustum_depth)) {
                ++ftests;
                if (!frustum_overlap(P, n)) {
                    ++fculls;
                    g = P->ngroups;
                    break;
                }
            }
            boxes += GL;
#ifdef PKT_X86
            m = avx ? box8_avx2(P, g, pl) : box8_scalar(P, g, pl);
#else
            m = box8_scalar(P, g, pl);
#endif
            if (m) break;
        }
        if (g == P->ngroups) continue; /* no ray hits: early exit */
        if (bvh_is_leaf(n)) {
            const uint32_t first = n->left_or_first, cnt = bvh_count(n);
            for (uint32_t gg = g; gg < P->ngroups; ++gg) {
                if (gg != g) {
                    boxes += GL;
#ifdef PKT_X86
                    if (!(avx ? box8_avx2(P, gg, pl) : box8_scalar(P, gg, pl))) continue;
#else
                    if (!box8_scalar(P, gg, pl)) continue;
#endif
                }
                prims += (uint64_t)GL * cnt;
                for (uint32_t k = first; k < first + cnt; ++k) {
#ifdef PKT_X86
                    if (avx && W->simd_tri) tri8_avx2(W, P, gg, &b->tris[k], b->prim_id[k]);
                    else tri8_scalar(W, P, gg, &b->tris[k], b->prim_id[k]);
#else
                    tri8_scalar(W, P, gg, &b->tris[k], b->prim_id[k]);
#endif
                }
            }
            if (P->anyhit && all_done(P)) break;
            continue;
        }
        /* Adaptive switch: only 1 or 2 rays of the last group still want
         * this subtree — they finish it alone instead of dragging the
         * packet's bookkeeping through it. */
        if (g + 1 == P->ngroups && (m & (m - 1) & ((m & (m - 1)) - 1)) == 0) { /* at most 2 bits set */
            for (unsigned mm = m; mm; mm &= mm - 1) single_subtree(W, P, g * GL + (uint32_t)__builtin_ctz(mm), ni);
            if (P->anyhit && all_done(P)) break;
            continue;
        }
        if (depth >= SWITCH_DEPTH && g + 1 < P->ngroups && (m & (m - 1) & ((m & (m - 1)) - 1)) == 0) {
            unsigned mg[NG];
            uint32_t total = (uint32_t)__builtin_popcount(m);
            mg[g] = m;
            for (uint32_t gg = g + 1; gg < P->ngroups && total <= SWITCH_RAYS; ++gg) {
                boxes += GL;
#ifdef PKT_X86
                mg[gg] = avx ? box8_avx2(P, gg, pl) : box8_scalar(P, gg, pl);
#else
                mg[gg] = box8_scalar(P, gg, pl);
#endif
                total += (uint32_t)__builtin_popcount(mg[gg]);
            }
            if (total <= SWITCH_RAYS) {
                for (uint32_t gg = g; gg < P->ngroups; ++gg)
                    for (unsigned mm = mg[gg]; mm; mm &= mm - 1)
                        single_subtree(W, P, gg * GL + (uint32_t)__builtin_ctz(mm), ni);
                if (P->anyhit && all_done(P)) break;
                continue;
            }
        }
        /* The packet shares direction signs: the near child along the
         * split axis is the same for every ray. */
        const uint32_t l = ni + 1, rc = n->left_or_first;
        const int s = P->sign[bvh_axis(n)];
        stk[sp++] = (pstack){s ? l : rc, g, depth + 1};
        stk[sp++] = (pstack){s ? rc : l, g, depth + 1};
    }
    st->node_visits += visits;
    st->box_tests += boxes;
    st->frustum_tests += ftests;
    st->frustum_culls += fculls;
    st->prim_tests += prims;
}

#ifdef PKT_X86
/* flatten: every kernel inlined into this AVX2 copy of the walk. */
__attribute__((target("avx2,fma"), flatten)) static void packet_walk_avx2(const walkopt *W, pkt *P)
{
    packet_walk_impl(W, P, 1);
}
#endif
static void packet_walk_generic(const walkopt *W, pkt *P) { packet_walk_impl(W, P, 0); }

static void packet_walk(const walkopt *W, pkt *P)
{
#ifdef PKT_X86
    if (W->avx) {
        packet_walk_avx2(W, P);
        return;
    }
#endif
    packet_walk_generic(W, P);
}

/* ---- entry points ---------------------------------------------------------------------- */

static int packet_capable(const sidx_accel *a)
{
    if (a->vt != &sidx__bvh_vtable) return 0;
    const bvh *b = a->impl;
    return b && b->obbs == NULL;
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

void sidx__packet_finish(const sidx_accel *a, const sidx_ray *r, uint32_t flags, sidx_hit *h)
{
    if (h->prim == SIDX_NO_HIT) {
        *h = sidx_hit_none();
        return;
    }
    /* never touch the mesh unless asked; the packet walks keep no u, v */
    const uint32_t need = flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL);
    if (need) sidx__hit_attrs_from_mesh(a, r, need, h);
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
    /* The wide BVHs have their own packet walk (packet_wide.c). */
    if (o.mode != SIDX_PACKET_SINGLE && n && sidx__is_wide(a)) {
        sidx__packet_wide(a, rays, n, n, n, &o, hits, occ, stats, avx);
        return SIDX_OK;
    }
    pkt P;
    if (o.mode == SIDX_PACKET_SINGLE || !packet_capable(a) || n == 0 || !pkt_setup(&P, rays, n, scale, anyhit)) {
        stats->single_packets++;
        const sidx_query q = {o.flags, SIDX_TRAVERSE_DEFAULT, NULL, 0};
        for (uint32_t i = 0; i < n; ++i) {
            if (anyhit) {
                int oc = 0;
                sidx_accel_occluded(a, &rays[i], &q, &oc);
                occ[i] = (uint8_t)oc;
            } else {
                sidx_accel_intersect(a, &rays[i], &q, &hits[i]);
            }
        }
        return SIDX_OK;
    }
    walkopt W;
    W.a = a;
    W.b = a->impl;
    W.scale = scale;
    W.avx = avx;
    W.simd_tri = a->opt.tri == SIDX_TRI_WATERTIGHT && P.uniform_k;
    W.st = stats;
    if (o.mode == SIDX_PACKET_FRUSTUM && P.ngroups >= 3) frustum_setup(&P, rays, n, w); /* see packet_walk_impl */
    else P.frustum = 0;
    W.frustum = P.frustum;
    W.frustum_depth = o.frustum_depth;
    packet_walk(&W, &P);
    for (uint32_t i = 0; i < n; ++i) {
        if (anyhit) {
            occ[i] = P.prim[i] != SIDX_NO_HIT;
            continue;
        }
        hits[i] = sidx_hit_none();
        if (P.prim[i] != SIDX_NO_HIT) {
            hits[i].t = P.best[i];
            hits[i].prim = P.prim[i];
            if (o.flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)) /* a call only when asked */
                sidx__packet_finish(a, &rays[i], o.flags, &hits[i]);
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
    const int avx = sidx__packet_have_avx2(); /* once per image: getenv scans the environment (a third of an empty tile) */
    const int wide = sidx__is_wide(a) && !(opt && opt->mode == SIDX_PACKET_SINGLE);
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
