/* simd_packet_wide_scalar.h — the wide-BVH packet walk's kernels in plain
 * C (packet_wide.c): the packet's set-up (one sign class? the interval
 * bounds), the interval test of a node's W boxes, a ray against W boxes,
 * a box against a group of 8 rays, a ray against a leaf.  The reference:
 * the AVX2 kernels (simd_packet_wide_avx2.h) do the same IEEE operations
 * in the same order, so the same bits.
 *
 * Not a normal header: packet_wide.c includes it after its types
 * (wide_packet). */

/* ---- set-up ---------------------------------------------------------------------- */

/* Do all lanes share lane 0's sign class? */
static SIDX_INLINE int lanes_uniform_scalar(const wide_packet *pkt)
{
    const uint32_t n_lanes = pkt->ngroups * GROUP_LANES;
    const unsigned c0 = lane_class(pkt, 0);
    for (uint32_t i = 1; i < n_lanes; ++i)
        if (lane_class(pkt, i) != c0) return 0;
    return 1;
}

/* The interval bounds of the rays in `live` (tmn, tmx start
 * at +inf, −inf). */
static SIDX_INLINE void bounds_scalar(const wide_packet *pkt, uint64_t live, ray_bounds *out)
{
    out->tmin = INFINITY;
    out->tmax = -INFINITY;
    const float *const arr[3][2] = {{pkt->org_x, pkt->inv_x}, {pkt->org_y, pkt->inv_y}, {pkt->org_z, pkt->inv_z}};
    for (int k = 0; k < 3; ++k) {
        out->omin[k] = out->imin[k] = INFINITY;
        out->omax[k] = out->imax[k] = -INFINITY;
    }
    for (uint64_t rays_left = live; rays_left; rays_left &= rays_left - 1) {
        const uint32_t i = (uint32_t)__builtin_ctzll(rays_left);
        for (int k = 0; k < 3; ++k) {
            const float o = arr[k][0][i], v = arr[k][1][i];
            out->omin[k] = o < out->omin[k] ? o : out->omin[k];
            out->omax[k] = o > out->omax[k] ? o : out->omax[k];
            out->imin[k] = v < out->imin[k] ? v : out->imin[k];
            out->imax[k] = v > out->imax[k] ? v : out->imax[k];
        }
        out->tmin = pkt->tmin[i] < out->tmin ? pkt->tmin[i] : out->tmin;
        out->tmax = pkt->best_clip[i] > out->tmax ? pkt->best_clip[i] : out->tmax;
    }
}

/* ---- node and leaf ------------------------------------------------------------------ */

/* Interval test of the W child boxes; key[slot] receives the lower bound of
 * every ray's entry into slot s (the order of the children). */
static SIDX_INLINE unsigned ia_slots_scalar(const float *node, const uint32_t W, const wide_packet *pkt, float *key)
{
    unsigned hits = 0;
    for (uint32_t slot = 0; slot < W; ++slot) {
        float lower = pkt->ia_tmin, upper = pkt->ia_tmax;
        for (int k = 0; k < 3; ++k) {
            const float d_near = node[pkt->near_row[k] * W + slot] - pkt->ia_org_near[k],
                        d_far = node[pkt->far_row[k] * W + slot] - pkt->ia_org_far[k];
            const float a0 = d_near * pkt->ia_inv_lo[k], a1 = d_near * pkt->ia_inv_hi[k];
            const float b0 = d_far * pkt->ia_far_lo[k], b1 = d_far * pkt->ia_far_hi[k];
            const float lo = a0 < a1 ? a0 : a1, hi = b0 > b1 ? b0 : b1;
            lower = lo > lower ? lo : lower;
            upper = hi < upper ? hi : upper;
        }
        key[slot] = lower;
        hits |= (unsigned)(lower <= upper) << slot;
    }
    return hits;
}

/* Ray i against the W child boxes: the single-ray test of bvh_wide_walk.h
 * (slab value first, so a NaN one never narrows the interval). */
static SIDX_INLINE unsigned ray_slots_scalar(const float *node, const uint32_t W, const wide_packet *pkt, uint32_t i,
                                             float *t_near)
{
    const float org[3] = {pkt->org_x[i], pkt->org_y[i], pkt->org_z[i]},
                inv[3] = {pkt->inv_x[i], pkt->inv_y[i], pkt->inv_z[i]},
                inv_far[3] = {pkt->inv_far_x[i], pkt->inv_far_y[i], pkt->inv_far_z[i]};
    unsigned hits = 0;
    for (uint32_t slot = 0; slot < W; ++slot) {
        float t_enter = pkt->tmin[i], t_exit = pkt->best_clip[i];
        for (int k = 0; k < 3; ++k) {
            const float near_k = (node[pkt->near_row[k] * W + slot] - org[k]) * inv[k];
            const float far_k = (node[pkt->far_row[k] * W + slot] - org[k]) * inv_far[k];
            t_enter = near_k > t_enter ? near_k : t_enter;
            t_exit = far_k < t_exit ? far_k : t_exit;
        }
        if (t_near) t_near[slot] = t_enter;
        hits |= (unsigned)(t_enter <= t_exit) << slot;
    }
    return hits;
}

/* Slot s of a node against rays 8g .. 8g+7: bit l for ray 8g + l. */
static SIDX_INLINE unsigned group_slot_scalar(const float *node, const uint32_t W, uint32_t slot,
                                              const wide_packet *pkt, uint32_t group)
{
    unsigned hits = 0;
    for (uint32_t lane = 0; lane < GROUP_LANES; ++lane) {
        const uint32_t i = group * GROUP_LANES + lane;
        const float org[3] = {pkt->org_x[i], pkt->org_y[i], pkt->org_z[i]},
                    inv[3] = {pkt->inv_x[i], pkt->inv_y[i], pkt->inv_z[i]},
                    inv_far[3] = {pkt->inv_far_x[i], pkt->inv_far_y[i], pkt->inv_far_z[i]};
        float t_enter = pkt->tmin[i], t_exit = pkt->best_clip[i];
        for (int k = 0; k < 3; ++k) {
            const float near_k = (node[pkt->near_row[k] * W + slot] - org[k]) * inv[k];
            const float far_k = (node[pkt->far_row[k] * W + slot] - org[k]) * inv_far[k];
            t_enter = near_k > t_enter ? near_k : t_enter;
            t_exit = far_k < t_exit ? far_k : t_exit;
        }
        hits |= (unsigned)(t_enter <= t_exit) << lane;
    }
    return hits;
}

/* Ray i against one leaf (a run of blocks), one triangle after another
 * with a shrinking bound; returns 1 when an any-hit ray is done. */
static SIDX_INLINE int leaf_ray_scalar(const sidx_accel *a, const wide_tri4 *block, wide_packet *pkt, uint32_t i)
{
    const sidx_ray *r = pkt->ray[i];
    for (;; ++block) {
        for (int lane = 0; lane < 4; ++lane) {
            const uint32_t id = block->prim[lane] & WIDE_PRIM_MASK;
            if (id == WIDE_PAD_PRIM) continue;
            float t;
            if (wide_lane_test(a, r, block, (unsigned)lane, pkt->best[i], &t, NULL, NULL)) {
                pkt->prim[i] = id;
                if (pkt->anyhit) {
                    pkt->best[i] = pkt->best_clip[i] = -INFINITY; /* misses every box from now on */
                    return 1;
                }
                pkt->best[i] = t;
                pkt->best_clip[i] = t * pkt->scale;
            }
        }
        if (block->prim[0] & WIDE_LAST_BLOCK) return 0;
    }
}
