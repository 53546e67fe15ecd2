/* simd_packet_scalar.h — the binary-BVH packet walk's kernels in plain C
 * (packet.c): one box or one triangle against a group of 8 rays, and the
 * frustum's two tests.  The reference: the AVX2 kernels
 * (simd_packet_avx2.h) and the SSE2 frustum kernels (simd_packet_sse.h)
 * do the same IEEE operations in the same order.
 *
 * Not a normal header: packet.c includes it after its types (packet,
 * walkopt).  The box and triangle kernels run whenever the CPU has no
 * AVX2 (or SIDX_SIMD asks for less); the frustum ones only where there
 * is no SSE2 (not on x86-64). */

/* ---- one box, 8 rays -------------------------------------------------------------- */

static unsigned box8_scalar(const packet *pkt, uint32_t group, const float planes[6])
{
    unsigned hits = 0;
    for (uint32_t lane = 0; lane < GROUP_LANES; ++lane) {
        const uint32_t i = group * GROUP_LANES + lane;
        const float org[3] = {pkt->org_x[i], pkt->org_y[i], pkt->org_z[i]},
                    inv[3] = {pkt->inv_x[i], pkt->inv_y[i], pkt->inv_z[i]},
                    inv_far[3] = {pkt->inv_far_x[i], pkt->inv_far_y[i], pkt->inv_far_z[i]};
        float t_enter = pkt->tmin[i], t_exit = pkt->best[i];
        for (int k = 0; k < 3; ++k) {
            const float near_k = (planes[k] - org[k]) * inv[k], far_k = (planes[3 + k] - org[k]) * inv_far[k];
            t_enter = near_k > t_enter ? near_k : t_enter;
            t_exit = far_k < t_exit ? far_k : t_exit;
        }
        hits |= (unsigned)(t_enter <= t_exit) << lane;
    }
    return hits;
}

/* ---- one triangle, 8 rays ----------------------------------------------------------- */

/* One lane, one triangle, the single-ray test; returns 1 on a hit (best updated). */
static int tri_lane(const walkopt *walk, packet *pkt, uint32_t i, const bvh_tri *tri, uint32_t prim)
{
    if (i >= pkt->n) return 0;
    float t;
    if (!sidx__tri_test(walk->a->opt.tri, &pkt->rays[i], tri->v[0], tri->v[1], tri->v[2], pkt->best[i], &t, NULL, NULL))
        return 0;
    pkt->prim[i] = prim;
    pkt->best[i] = pkt->anyhit ? -INFINITY : t; /* an occluded shadow ray is done */
    return 1;
}

static void tri8_scalar(const walkopt *walk, packet *pkt, uint32_t group, const bvh_tri *tri, uint32_t prim)
{
    for (uint32_t lane = 0; lane < GROUP_LANES; ++lane) tri_lane(walk, pkt, group * GROUP_LANES + lane, tri, prim);
}

/* ---- frustum ----------------------------------------------------------------------- */

/* Is the node box possibly inside the pyramid of the corner rays?  Per
 * plane, the box corner farthest along the inward normal decides; a
 * relative margin keeps the test conservative under rounding (see
 * frustum_setup, packet.c, for the bound). */
static SIDX_INLINE int frustum_overlap_scalar(const packet *pkt, const bvh_node *node)
{
    const float diag =
        (node->bmax[0] - node->bmin[0]) + (node->bmax[1] - node->bmin[1]) + (node->bmax[2] - node->bmin[2]);
    for (int plane = 0; plane < 4; ++plane) {
        const float *normal = pkt->plane_n[plane];
        float dot = 0.0f, mag = 0.0f;
        for (int k = 0; k < 3; ++k) {
            const float rel = (normal[k] >= 0.0f ? node->bmax[k] : node->bmin[k]) - pkt->apex[k];
            dot += normal[k] * rel;
            mag += fabsf(rel);
        }
        if (dot < (-1e-5f * pkt->plane_l1[plane]) * (mag + diag)) return 0;
    }
    return 1;
}

/* Do all n rays start at the apex and lie inside the 4 planes (len2: the
 * planes' squared normal lengths)?  n·d >= −1e-6 |n||d|, without a square
 * root per ray. */
static SIDX_INLINE int frustum_rays_inside_scalar(const packet *pkt, const sidx_ray *rays, uint32_t n,
                                                  const float len2[4])
{
    for (uint32_t i = 1; i < n; ++i)
        if (memcmp(&rays[i].org, &rays[0].org, sizeof rays[0].org)) return 0;
    for (int plane = 0; plane < 4; ++plane) {
        const sidx_vec3 normal = sidx_v3(pkt->plane_n[plane][0], pkt->plane_n[plane][1], pkt->plane_n[plane][2]);
        for (uint32_t i = 0; i < n; ++i) {
            const float dot = sidx_v3_dot(normal, rays[i].dir);
            if (dot < 0.0f && dot * dot > 1e-12f * len2[plane] * sidx_v3_dot(rays[i].dir, rays[i].dir)) return 0;
        }
    }
    return 1;
}
