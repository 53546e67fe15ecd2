/* simd_wide_scalar.h — the wide walk's kernels in plain C: the portable
 * reference the SSE4.1, AVX2 and AVX-512 kernels (simd_wide_sse.h,
 * simd_wide_avx2.h, simd_wide_avx512.h) must match bit for bit.
 *
 * Not a normal header: bvh_wide_walk.h includes it for WALK_ISA 0 (once
 * per width W = WALK_W), after defining WFN (which pastes the width and
 * the instruction set into each name: ray_consts_8_scalar, boxes_8_scalar,
 * ...; lib/README.md lists them) and WINL.  Every kernel header defines
 * the same set:
 *
 *   WFN(ray_consts_)    what one ray needs at every node, set up once;
 *   WFN(ray_consts_init_), WFN(tri_consts_init_)
 *                       its box constants / its triangle constants (the
 *                       latter at the first leaf: a ray that reaches no
 *                       leaf needs none);
 *   WFN(boxes_)         the ray against the W child boxes of a node;
 *   WFN(popc_), WFN(rank_)  bits in a slot mask; a hit child's stack place;
 *   WFN(block_rows_), WFN(tri4_)  the 4-triangle block kernel and the row
 *                       pointers it steps through a leaf;
 *   WALK_TRI4           1 when tri4_ is a real SIMD kernel. */

#define WALK_TRI4 0

/* ---- per-ray constants ------------------------------------------------------ */

typedef struct WFN(ray_consts_) {
    float org[3], inv[3], inv_far[3], tmin; /* origin, 1/d, 1/d times the Ize factor (far planes), tmin */
    uint32_t near_off[3], far_off[3];       /* float offsets of the near / far planes of each axis inside a node */
} WFN(ray_consts_);

WINL void WFN(ray_consts_init_)(WFN(ray_consts_) * consts, const sidx_ray *r, float scale)
{
    const float *o = sidx_v3_array(&r->org), *inv = sidx_v3_array(&r->inv_dir);
    for (int k = 0; k < 3; ++k) {
        /* b[0..2] = lo, b[3..5] = hi: a negative direction enters through hi. */
        consts->near_off[k] = (uint32_t)((r->sign[k] ? 3 + k : k) * WALK_W);
        consts->far_off[k] = (uint32_t)((r->sign[k] ? k : 3 + k) * WALK_W);
    }
    for (int k = 0; k < 3; ++k) { consts->org[k] = o[k]; consts->inv[k] = inv[k]; consts->inv_far[k] = inv[k] * scale; }
    consts->tmin = r->tmin;
}

/* No triangle constants: every block takes the scalar test. */
WINL void WFN(tri_consts_init_)(WFN(ray_consts_) * consts, const sidx_ray *r)
{
    (void)consts;
    (void)r;
}

/* ---- W boxes, one after another ----------------------------------------------
 * The slab test of sidx__box_test per child (Kay & Kajiya 1986), with the
 * far planes multiplied by 1/d times the Ize factor (bvh_wide_walk.h says
 * why that is as conservative): max and min written `x > y ? x : y` with
 * the slab value first, so a NaN slab value never narrows the interval.
 * Returns the mask of children whose clipped interval is non-empty;
 * t_near[] (and t_far[] when want_far) receive the intervals of all W
 * slots. */
WINL unsigned WFN(boxes_)(const float *node, const WFN(ray_consts_) * consts, float best, float *t_near, float *t_far,
                          const int want_far)
{
    unsigned hits = 0;
    for (uint32_t slot = 0; slot < WALK_W; ++slot) {
        float t_enter = consts->tmin, t_exit = best;
        for (int k = 0; k < 3; ++k) {
            const float near_k = (node[consts->near_off[k] + slot] - consts->org[k]) * consts->inv[k];
            const float far_k = (node[consts->far_off[k] + slot] - consts->org[k]) * consts->inv_far[k];
            t_enter = near_k > t_enter ? near_k : t_enter;
            t_exit = far_k < t_exit ? far_k : t_exit;
        }
        t_near[slot] = t_enter;
        if (want_far) t_far[slot] = t_exit;
        hits |= (unsigned)(t_enter <= t_exit) << slot;
    }
    return hits;
}

/* ---- the order of the hit children ------------------------------------------- */

/* Bits set in a slot mask (< 256): three steps of adding neighbouring bit
 * fields (without POPCNT, __builtin_popcount would be a call into libgcc). */
WINL uint32_t WFN(popc_)(unsigned x)
{
    x = x - ((x >> 1) & 0x55u);
    x = (x & 0x33u) + ((x >> 2) & 0x33u);
    return (x + (x >> 4)) & 0x0Fu;
}

/* Where hit child `slot` goes among the hit children hit_mask: how many
 * of them are visited before it — nearer, or as near and in a lower slot
 * (bvh_wide_walk.h, walk_, says why it is computed so). */
WINL uint32_t WFN(rank_)(const float *t_near, unsigned slot, unsigned hit_mask)
{
    unsigned nearer = 0, as_near = 0;
    for (unsigned k = 0; k < WALK_W; ++k) {
        nearer |= (unsigned)(t_near[k] < t_near[slot]) << k;
        as_near |= (unsigned)(t_near[k] == t_near[slot]) << k;
    }
    return WFN(popc_)(hit_mask & (nearer | (as_near & ((1u << slot) - 1u))));
}

/* ---- triangle blocks ------------------------------------------------------------ */

/* No SIMD kernel: tri4_ declines every block (-1), which sends it to the
 * scalar test lane by lane; the row pointers are never read. */
WINL void WFN(block_rows_)(const WFN(ray_consts_) * consts, const wide_tri4 *block, const float **row_x,
                           const float **row_y, const float **row_z)
{
    (void)consts;
    *row_x = *row_y = *row_z = &block->v[0][0][0];
}

WINL int WFN(tri4_)(const float *row_x, const float *row_y, const float *row_z, const WFN(ray_consts_) * consts,
                    float best, float *t_out, unsigned *lane_out, float *vw_det_out)
{
    (void)row_x;
    (void)row_y;
    (void)row_z;
    (void)consts;
    (void)best;
    (void)t_out;
    (void)lane_out;
    (void)vw_det_out;
    return -1;
}
