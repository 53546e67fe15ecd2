/* bvh_wide_walk.h — one ray through a wide BVH: the traversal template.
 *
 * Not a normal header: bvh_wide.c includes it once per (width, instruction
 * set) with WALK_W (4 or 8), WALK_ISA (0 scalar, 1 SSE4.1, 2 AVX2, 3 AVX2
 * code compiled for AVX-512F/VL) and
 * WALK_TARGET (the matching __attribute__((target(...))) or nothing)
 * defined.  Every function here carries WALK_TARGET, so the SIMD copies are
 * compiled for their instruction set while the library as a whole is built
 * for baseline x86-64, and picked at run time (bvh_wide.c).  The scalar copy
 * is the portable reference: the same operations in the same order, so it
 * returns bit-identical hits (see "identical results" below).
 *
 * The walk (closest hit) per node:
 *   1. slab-test all W child boxes at once against [tmin, best]
 *      (Kay & Kajiya 1986), t_far widened by 1 + 2γ₃ (Ize 2013) exactly as
 *      sidx__box_test does, and min/max written in the order that lets a
 *      NaN slab value (0·∞: origin on the plane of an axis the ray is
 *      parallel to) never narrow the interval: MAXPS/MINPS return their
 *      SECOND operand when either is NaN, so the slab value goes first and
 *      the running interval second — the SIMD twin of `x > y ? x : y`;
 *   2. one hit child: descend, no stack traffic (the common case deep in
 *      the tree); two: one compare; more: each goes straight to its stack
 *      slot by its rank in entry distance (rank_; the traced copy sorts
 *      by insertion, same order) — then descend into the nearest,
 *      deferring the others nearest-on-top, as Wald et al. 2008 and
 *      Embree do; every hit child is prefetched as it is handled;
 *   3. a leaf: its triangle blocks, 4 triangles per SSE pass with the
 *      watertight test (Woop, Benthin, Wald 2013) written lane-parallel;
 *   4. pop the next deferred child whose entry is still before the best hit.
 *
 * Identical results, SIMD or scalar: the slab and triangle arithmetic is
 * the same sequence of IEEE single-precision operations in every copy
 * (no FMA contraction: ISO C mode compiles with -ffp-contract=off, and the
 * intrinsics spell out mul then sub), min/max resolve NaNs the same way,
 * and a block's hits are reduced to the smallest t, ties to the lowest
 * lane — exactly what testing the 4 triangles one after another with a
 * shrinking bound accepts.  A lane whose edge function is exactly 0 sends
 * the whole block to the scalar test, which redoes it in double as the
 * paper prescribes.
 *
 * Events: the traced copy (traced = 1) emits NODE_ENTER, BOX_TEST per used
 * slot, STACK_PUSH / STACK_POP, PRIM_TEST and HIT_UPDATE per triangle (it
 * tests leaves one triangle at a time so the events say what was tested)
 * and TERMINATE; in the untraced copies every SIDX_EMIT is dead code. */

#if !defined(WALK_W) || !defined(WALK_ISA)
#error "bvh_wide_walk.h is included by bvh_wide.c with WALK_W and WALK_ISA defined"
#endif
#if (WALK_ISA >= 2 && WALK_W != 8) || (WALK_ISA == 1 && WALK_W != 4)
#error "AVX2 and AVX-512 kernels are 8 wide, SSE4.1 kernels 4 wide"
#endif

#define WJOIN_(a, b, c) a##b##_##c
#define WJOIN(a, b, c) WJOIN_(a, b, c)
#define WFN(name) WJOIN(name, WALK_W, WALK_ISA)
#ifndef WIDE_PREFETCH
#define WIDE_PREFETCH 1
#endif
#define WINL static inline __attribute__((always_inline)) WALK_TARGET

/* ---- per-ray constants ------------------------------------------------------ */

typedef struct WFN(wray_) {
#if WALK_ISA >= 2
    __m256 ox, oy, oz, ix, iy, iz, fx, fy, fz, tmin;
#if WALK_ISA == 3
    __mmask8 negx, negy, negz; /* all lanes set where the direction is negative: picks the planes in boxes_ */
#endif
#elif WALK_ISA == 1
    __m128 ox, oy, oz, ix, iy, iz, fx, fy, fz, tmin;
#else
    float o[3], inv[3], finv[3], tmin;
#endif
#if WALK_ISA >= 1
    wide_tri_ray tri; /* watertight triangle test, lane-broadcast (bvh_wide_internal.h) */
#endif
#if WALK_ISA != 3
    uint32_t no[3], fo[3];  /* float offsets of the near / far planes of each axis inside a node */
#endif
} WFN(wray_);

WINL void WFN(wray_init_)(WFN(wray_) * R, const sidx_ray *r, float scale)
{
    const float *o = &r->org.x, *inv = &r->inv_dir.x;
#if WALK_ISA != 3 /* the AVX-512 copy picks the planes with its sign masks instead */
    for (int k = 0; k < 3; ++k) {
        /* b[0..2] = lo, b[3..5] = hi: a negative direction enters through hi. */
        R->no[k] = (uint32_t)((r->sign[k] ? 3 + k : k) * WALK_W);
        R->fo[k] = (uint32_t)((r->sign[k] ? k : 3 + k) * WALK_W);
    }
#endif
#if WALK_ISA >= 2
    R->ox = _mm256_set1_ps(o[0]); R->oy = _mm256_set1_ps(o[1]); R->oz = _mm256_set1_ps(o[2]);
    R->ix = _mm256_set1_ps(inv[0]); R->iy = _mm256_set1_ps(inv[1]); R->iz = _mm256_set1_ps(inv[2]);
    R->fx = _mm256_set1_ps(inv[0] * scale); R->fy = _mm256_set1_ps(inv[1] * scale);
    R->fz = _mm256_set1_ps(inv[2] * scale);
    R->tmin = _mm256_set1_ps(r->tmin);
#if WALK_ISA == 3
    R->negx = (__mmask8)(r->sign[0] ? 0xFF : 0); R->negy = (__mmask8)(r->sign[1] ? 0xFF : 0);
    R->negz = (__mmask8)(r->sign[2] ? 0xFF : 0);
#endif
#elif WALK_ISA == 1
    R->ox = _mm_set1_ps(o[0]); R->oy = _mm_set1_ps(o[1]); R->oz = _mm_set1_ps(o[2]);
    R->ix = _mm_set1_ps(inv[0]); R->iy = _mm_set1_ps(inv[1]); R->iz = _mm_set1_ps(inv[2]);
    R->fx = _mm_set1_ps(inv[0] * scale); R->fy = _mm_set1_ps(inv[1] * scale); R->fz = _mm_set1_ps(inv[2] * scale);
    R->tmin = _mm_set1_ps(r->tmin);
#else
    for (int k = 0; k < 3; ++k) { R->o[k] = o[k]; R->inv[k] = inv[k]; R->finv[k] = inv[k] * scale; }
    R->tmin = r->tmin;
#endif
}

/* ---- W boxes at once ---------------------------------------------------------
 * The far planes use 1/d pre-multiplied by the Ize factor (as Embree's
 * robust mode does with its rdir_far): fl(fl(b − o)·fl(fl(1/d)·S)) carries
 * four roundings, like fl(fl(fl(b − o)·fl(1/d))·S) in sidx__box_test, so
 * the same 1 + 2γ₃ bound keeps it conservative, and a node costs three
 * multiplies fewer.  With the plain test S = 1 and the product is exact.
 * Returns the mask of children whose clipped interval is non-empty; tn[]
 * (and tf[] when want_tf) receive the intervals of all W slots. */
WINL unsigned WFN(boxes_)(const float *n, const WFN(wray_) * R, float best, float *tn, float *tf, const int want_tf)
{
#if WALK_ISA >= 2
#if WALK_ISA == 3
    /* The near and far plane of each axis picked by a blend under the
     * ray's sign mask (one per axis, in mask registers) instead of by six
     * offsets into the node: the six offsets took general registers the
     * walk needs elsewhere, so GCC reloaded five of them from the stack at
     * every node.  The same planes, so the same bits (docs/performance.md,
     * "Wide BVHs"). */
    const __m256 lx = _mm256_load_ps(n), ly = _mm256_load_ps(n + 8), lz = _mm256_load_ps(n + 16);
    const __m256 hx = _mm256_load_ps(n + 24), hy = _mm256_load_ps(n + 32), hz = _mm256_load_ps(n + 40);
    const __m256 px = _mm256_mask_blend_ps(R->negx, lx, hx), qx = _mm256_mask_blend_ps(R->negx, hx, lx);
    const __m256 py = _mm256_mask_blend_ps(R->negy, ly, hy), qy = _mm256_mask_blend_ps(R->negy, hy, ly);
    const __m256 pz = _mm256_mask_blend_ps(R->negz, lz, hz), qz = _mm256_mask_blend_ps(R->negz, hz, lz);
#else
    const __m256 px = _mm256_load_ps(n + R->no[0]), qx = _mm256_load_ps(n + R->fo[0]);
    const __m256 py = _mm256_load_ps(n + R->no[1]), qy = _mm256_load_ps(n + R->fo[1]);
    const __m256 pz = _mm256_load_ps(n + R->no[2]), qz = _mm256_load_ps(n + R->fo[2]);
#endif
    const __m256 nx = _mm256_mul_ps(_mm256_sub_ps(px, R->ox), R->ix);
    const __m256 ny = _mm256_mul_ps(_mm256_sub_ps(py, R->oy), R->iy);
    const __m256 nz = _mm256_mul_ps(_mm256_sub_ps(pz, R->oz), R->iz);
    const __m256 fx = _mm256_mul_ps(_mm256_sub_ps(qx, R->ox), R->fx);
    const __m256 fy = _mm256_mul_ps(_mm256_sub_ps(qy, R->oy), R->fy);
    const __m256 fz = _mm256_mul_ps(_mm256_sub_ps(qz, R->oz), R->fz);
    __m256 t0 = _mm256_max_ps(nx, R->tmin);
    t0 = _mm256_max_ps(ny, t0);
    t0 = _mm256_max_ps(nz, t0);
    __m256 t1 = _mm256_min_ps(fx, _mm256_set1_ps(best));
    t1 = _mm256_min_ps(fy, t1);
    t1 = _mm256_min_ps(fz, t1);
    _mm256_store_ps(tn, t0);
    if (want_tf) _mm256_store_ps(tf, t1);
#if WALK_ISA == 3
    return (unsigned)_mm256_cmp_ps_mask(t0, t1, _CMP_LE_OQ);
#else
    return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ));
#endif
#elif WALK_ISA == 1
    const __m128 nx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n + R->no[0]), R->ox), R->ix);
    const __m128 ny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n + R->no[1]), R->oy), R->iy);
    const __m128 nz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n + R->no[2]), R->oz), R->iz);
    const __m128 fx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n + R->fo[0]), R->ox), R->fx);
    const __m128 fy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n + R->fo[1]), R->oy), R->fy);
    const __m128 fz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(n + R->fo[2]), R->oz), R->fz);
    __m128 t0 = _mm_max_ps(nx, R->tmin);
    t0 = _mm_max_ps(ny, t0);
    t0 = _mm_max_ps(nz, t0);
    __m128 t1 = _mm_min_ps(fx, _mm_set1_ps(best));
    t1 = _mm_min_ps(fy, t1);
    t1 = _mm_min_ps(fz, t1);
    _mm_store_ps(tn, t0);
    if (want_tf) _mm_store_ps(tf, t1);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(t0, t1));
#else
    unsigned m = 0;
    for (uint32_t s = 0; s < WALK_W; ++s) {
        float t0 = R->tmin, t1 = best;
        for (int k = 0; k < 3; ++k) {
            const float a = (n[R->no[k] + s] - R->o[k]) * R->inv[k];
            const float b = (n[R->fo[k] + s] - R->o[k]) * R->finv[k];
            t0 = a > t0 ? a : t0;
            t1 = b < t1 ? b : t1;
        }
        tn[s] = t0;
        if (want_tf) tf[s] = t1;
        m |= (unsigned)(t0 <= t1) << s;
    }
    return m;
#endif
}

/* Start fetching a child that was hit: its node or first leaf block.
 * The walk is bound by the latency of these loads (perf: most samples sit
 * on the first load of a node or block), so every hit child is fetched
 * as soon as it is known, the nearest for now and the others for when
 * they are popped, inside the code that handles it anyway (a separate
 * loop over the hit mask, and a branch-free leaf/node choice, were
 * rejected: docs/performance.md, "Wide BVHs").  A node is 2 (bvh4) or
 * 4 (bvh8) cache lines, a leaf block 2.5; prefetching a leaf's 4th line
 * is harmless. */
WINL void WFN(prefetch_)(const wide_bvh *w, const float *nodes, uint32_t c)
{
    const uintptr_t leaf = (uintptr_t)w->blocks + (uintptr_t)(c & ~WIDE_LEAF_BIT) * sizeof(wide_tri4);
    const uintptr_t node = (uintptr_t)nodes + (uintptr_t)c * (8u * WALK_W * sizeof(float));
    const char *p = (const char *)((c & WIDE_LEAF_BIT) ? leaf : node);
    __builtin_prefetch(p);
    __builtin_prefetch(p + 64);
    __builtin_prefetch(p + 128);
    if (WALK_W == 8) __builtin_prefetch(p + 192);
}

/* Bits set in a slot mask (< 256).  The AVX2 and AVX-512 copies are
 * compiled with POPCNT; elsewhere __builtin_popcount would be a call into libgcc, so
 * three steps of adding neighbouring bit fields instead. */
WINL uint32_t WFN(popc_)(unsigned x)
{
#if WALK_ISA >= 2
    return (uint32_t)__builtin_popcount(x);
#else
    x = x - ((x >> 1) & 0x55u);
    x = (x & 0x33u) + ((x >> 2) & 0x33u);
    return (x + (x >> 4)) & 0x0Fu;
#endif
}

/* Where hit child s goes among the hit children hm: how many of them are
 * visited before it — nearer, or as near and in a lower slot.  This is
 * the order the insertion sort below produces (stable, so equal entries
 * keep slot order), computed for each child independently: two compares
 * of all W entries against s's, no data-dependent branches, where the
 * insertion sort's inner loop mispredicts (docs/performance.md, "Wide
 * BVHs").  Entry distances are never NaN (the max with tmin). */
WINL uint32_t WFN(rank_)(const float *tn, unsigned s, unsigned hm)
{
#if WALK_ISA >= 2
    const __m256 T = _mm256_load_ps(tn), d = _mm256_set1_ps(tn[s]);
    const unsigned lt = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(T, d, _CMP_LT_OQ));
    const unsigned eq = (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(T, d, _CMP_EQ_OQ));
#elif WALK_ISA == 1
    const __m128 T = _mm_load_ps(tn), d = _mm_set1_ps(tn[s]);
    const unsigned lt = (unsigned)_mm_movemask_ps(_mm_cmplt_ps(T, d));
    const unsigned eq = (unsigned)_mm_movemask_ps(_mm_cmpeq_ps(T, d));
#else
    unsigned lt = 0, eq = 0;
    for (unsigned k = 0; k < WALK_W; ++k) {
        lt |= (unsigned)(tn[k] < tn[s]) << k;
        eq |= (unsigned)(tn[k] == tn[s]) << k;
    }
#endif
    return WFN(popc_)(hm & (lt | (eq & ((1u << s) - 1u))));
}

/* One leaf: its blocks in order.  Returns 1 when an any-hit query may stop.
 *
 * Register pressure: the AVX2 walk holds the box constants (10 ymm) and
 * the triangle constants (6 xmm) across the node loop, so GCC stores 7 of
 * the ymm at every leaf entry and reloads them at the exit.  A leaf out
 * of line does not help (every xmm/ymm register is caller-saved in the
 * SysV ABI); more registers do: the AVX-512 copy keeps all the constants
 * in registers.  Figures, and the compiler tricks rejected:
 * docs/performance.md, "Wide BVHs". */
WINL int WFN(leaf_)(const sidx_accel *a, const wide_bvh *w, uint32_t first_block, const sidx_ray *r,
                    const WFN(wray_) * R, const sidx_query *q, uint32_t node_id, float *best, uint32_t *prim,
                    const wide_tri4 **hit_block, unsigned *hit_lane, float *hit_vwd, const int anyhit,
                    const int traced, const int simd_tri)
{
    (void)R;
    (void)node_id;
    const wide_tri4 *B = w->blocks + first_block;
#if WALK_ISA >= 1
    /* The block's rows on the ray's permuted axes, stepped a block at a
     * time: three pointers instead of nine hoisted offsets. */
    const float *px = &B->v[0][0][0] + R->tri.kx4, *py = &B->v[0][0][0] + R->tri.ky4,
                *pz = &B->v[0][0][0] + R->tri.kz4;
#endif
    for (;; ++B) {
        int scalar = 1;
#if WALK_ISA >= 1
        if (!traced && simd_tri) {
            float t;
            unsigned lane;
            const int h = wide_tri4_test_axes(px, py, pz, &R->tri, *best, &t, &lane, hit_vwd);
            if (h >= 0) {
                scalar = 0;
                if (h) {
                    *prim = B->prim[lane] & WIDE_PRIM_MASK;
                    if (anyhit) return 1;
                    *best = t;
                    *hit_block = B;
                    *hit_lane = lane;
                }
            }
        }
#else
        (void)simd_tri;
#endif
        if (scalar) {
            for (int l = 0; l < 4; ++l) {
                const uint32_t id = B->prim[l] & WIDE_PRIM_MASK;
                if (id == WIDE_PAD_PRIM) continue;
                float t;
                const int h = wide_lane_test(a, r, B, (unsigned)l, *best, &t, NULL, NULL);
                SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.node = node_id;
                          e_.prim = id; e_.result = h; e_.t = h ? t : INFINITY);
                if (h) {
                    *prim = id;
                    if (anyhit) return 1;
                    *best = t;
                    *hit_block = B;
                    *hit_lane = (unsigned)l;
                    if (hit_vwd) hit_vwd[8 + l] = NAN; /* no kernel values: uv_ computes u, v itself */
                    SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = id; e_.t = t);
                }
            }
        }
        if (B->prim[0] & WIDE_LAST_BLOCK) return 0;
#if WALK_ISA >= 1
        px += sizeof(wide_tri4) / sizeof(float);
        py += sizeof(wide_tri4) / sizeof(float);
        pz += sizeof(wide_tri4) / sizeof(float);
#endif
    }
}

/* u, v and ng of the final hit, from the leaf block's copy of the
 * triangle (so no index and vertex look-ups in the mesh, which a diffuse
 * ray mostly misses in cache): the same test and normal the core would
 * compute (accel.c finish_hit), on the same floats, so the same bits.
 * In the walk that keeps u, v (keep_uv, for queries asking for them) the
 * SIMD kernel left the accepted lane's V, W, det in vwd, and u, v are the
 * scalar test's last step on them (sidx__tri_watertight_uv).  A hit the
 * scalar test found has det = NaN there (a kernel's det never is); then,
 * and in the other walks, u, v come from the lane's edge functions
 * (wide_lane_hit_uv: no T, no t), or, when the lane has an exactly-0 edge
 * function or the test is not the watertight one, from the whole test
 * again, whose bound only has to exceed t, which was accepted below the
 * old best, so +inf does. */
WINL void WFN(uv_)(const sidx_accel *a, const sidx_ray *r, uint32_t flags, const wide_tri4 *B, unsigned l,
                   const float *vwd, sidx_hit *hit)
{
    /* The corners are read where they are used (the normal last), not
     * held in registers across the u, v step, which spilled them.  The
     * walks without vwd read them first: there the late reads made GCC
     * allocate the whole walk worse (docs/performance.md, "Wide BVHs"). */
    const int early = !vwd;
    sidx_vec3 p0 = {0.0f, 0.0f, 0.0f}, p1 = p0, p2 = p0;
    if (early) {
        p0 = wide_lane_vertex(B, 0, l);
        p1 = wide_lane_vertex(B, 1, l);
        p2 = wide_lane_vertex(B, 2, l);
    }
    if (flags & SIDX_QUERY_UV) {
        float u = 0.0f, v = 0.0f;
        if (vwd && !isnan(vwd[8 + l])) {
            sidx__tri_watertight_uv(vwd[l], vwd[4 + l], vwd[8 + l], &u, &v);
            hit->u = u;
            hit->v = v;
        } else if (wide_lane_hit_uv(a, r, B, l, &u, &v)) {
            hit->u = u;
            hit->v = v;
        }
    }
    if (flags & SIDX_QUERY_NORMAL) hit->ng = early ? sidx__tri_normal(p0, p1, p2) : wide_lane_normal(B, l);
}

/* ---- the walk ----------------------------------------------------------------- */

WINL int WFN(walk_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit, const int anyhit,
                    const int traced, const int simd_tri, const int keep_uv)
{
    const wide_bvh *w = a->impl;
    const float *nodes = w->nodes;
    float best = anyhit ? r->tmax : hit->t;
    uint32_t prim = SIDX_NO_HIT, visited = 0;
    const wide_tri4 *hit_block = NULL;
    unsigned hit_lane = 0;
    /* keep_uv: V, W, det of hit_block's lanes, which the SIMD kernel
     * stores when it accepts a hit (uv_ turns them into u, v).  A separate
     * instantiation, so the walk without u, v is the same code as before. */
    float vwd_[12];
    float *const hit_vwd = keep_uv ? vwd_ : NULL;
    if (w->num_inner == 0) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }
    WFN(wray_) R;
    /* Ize's factor also widens the best hit the boxes are clipped to (and
     * the pop test): a rounded entry an ulp beyond a hit must not drop a
     * box holding a triangle an ulp nearer (bvh_slab says more). */
    const float scale = a->opt.box == SIDX_BOX_ROBUST ? SIDX_ROBUST_TFAR_SCALE : 1.0f;
    WFN(wray_init_)(&R, r, scale);
    int tri_ready = 0;
    (void)tri_ready;
    float best_s = best * scale; /* the widened bound boxes are clipped to (see bvh_slab) */

    /* Deferred children and their entry distances; exit distance, depth
     * and event id only for the events (dead in the untraced copies). */
    uint32_t stk[WIDE_STACK];
    float stk_tn[WIDE_STACK];
    float stk_tf[WIDE_STACK];
    uint32_t stk_depth[WIDE_STACK], stk_id[WIDE_STACK];
    _Alignas(32) float tn[8];
    _Alignas(32) float tf[8];
    uint32_t sp = 0, cur = 0, cur_id = 0, depth = 0;
    float cur_tn = r->tmin, cur_tf = best;
    int root_hit = 0;
    (void)cur_tn;
    (void)cur_tf;
    (void)cur_id;
    for (;;) {
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = cur_id; e_.depth = depth;
                  e_.t_near = cur_tn; e_.t_far = cur_tf);
        if (!(cur & WIDE_LEAF_BIT)) {
            const float *n = nodes + (size_t)cur * (8u * WALK_W);
            const uint32_t *ch = wide_child(n, WALK_W);
            unsigned m = WFN(boxes_)(n, &R, best_s, tn, tf, traced);
            if (traced) {
                const uint32_t *ids = wide_id(n, WALK_W);
                for (uint32_t s = 0; s < WALK_W; ++s) {
                    if (ch[s] == WIDE_EMPTY) continue;
                    const int res = (int)((m >> s) & 1u);
                    SIDX_EMIT(traced, q->hook, SIDX_EV_BOX_TEST, e_.ray_id = q->ray_id; e_.node = ids[s];
                              e_.depth = depth + 1; e_.bounds = wide_slot_box(n, WALK_W, s); e_.result = res;
                              e_.t_near = res ? tn[s] : NAN; e_.t_far = res ? tf[s] : NAN);
                }
            }
            if (visited == 1) root_hit = m != 0;
            if (m) {
                const unsigned s0 = (unsigned)__builtin_ctz(m);
                m &= m - 1;
                if (!m) { /* one child: descend, no stack */
                    cur = ch[s0];
                    if (!traced && WIDE_PREFETCH) WFN(prefetch_)(w, nodes, cur);
                    if (traced) {
                        cur_tn = tn[s0];
                        cur_tf = tf[s0];
                        cur_id = wide_id(n, WALK_W)[s0];
                    }
                    ++depth;
                    continue;
                }
                if (!traced && !(m & (m - 1))) {
                    /* Two (the most common case of several): one compare,
                     * the farther waits; ties go to the lower slot. */
                    const unsigned s1 = (unsigned)__builtin_ctz(m);
                    const float d0 = tn[s0], d1 = tn[s1];
                    if (WIDE_PREFETCH) {
                        WFN(prefetch_)(w, nodes, ch[s0]);
                        WFN(prefetch_)(w, nodes, ch[s1]);
                    }
                    const int first0 = anyhit || d0 <= d1;
                    stk[sp] = first0 ? ch[s1] : ch[s0];
                    stk_tn[sp] = first0 ? d1 : d0;
                    ++sp;
                    cur = first0 ? ch[s0] : ch[s1];
                    ++depth;
                    continue;
                }
                if (!traced && !anyhit) {
                    /* Several, closest hit: each goes straight to its
                     * place, nearest on top (see rank_). */
                    const unsigned hm = m | (1u << s0);
                    const uint32_t top = sp + WFN(popc_)(hm) - 1u;
                    unsigned mm = hm;
                    do {
                        const unsigned s = (unsigned)__builtin_ctz(mm);
                        mm &= mm - 1;
                        const uint32_t at = top - WFN(rank_)(tn, s, hm);
                        stk[at] = ch[s];
                        stk_tn[at] = tn[s];
                        if (WIDE_PREFETCH) WFN(prefetch_)(w, nodes, ch[s]);
                    } while (mm);
                    sp = top; /* the nearest is visited now, the rest wait */
                    cur = stk[top];
                    ++depth;
                    continue;
                }
                /* Several: append them, then order nearest-on-top. */
                const uint32_t base = sp;
                unsigned s = s0;
                for (;;) {
                    stk[sp] = ch[s];
                    if (!traced && WIDE_PREFETCH) WFN(prefetch_)(w, nodes, ch[s]);
                    stk_tn[sp] = tn[s];
                    if (traced) {
                        stk_tf[sp] = tf[s];
                        stk_depth[sp] = depth + 1;
                        stk_id[sp] = wide_id(n, WALK_W)[s];
                    }
                    ++sp;
                    if (!m) break;
                    s = (unsigned)__builtin_ctz(m);
                    m &= m - 1;
                }
                if (!anyhit) {
                    /* Insertion sort, farthest at the bottom; stable, so
                     * equal entries keep slot order and the lower slot
                     * is visited first. */
                    for (uint32_t i = base + 1; i < sp; ++i) {
                        const uint32_t c = stk[i];
                        const float d = stk_tn[i];
                        float df = 0.0f;
                        uint32_t dd = 0, di = 0;
                        if (traced) { df = stk_tf[i]; dd = stk_depth[i]; di = stk_id[i]; }
                        uint32_t j = i;
                        while (j > base && stk_tn[j - 1] <= d) {
                            stk[j] = stk[j - 1];
                            stk_tn[j] = stk_tn[j - 1];
                            if (traced) {
                                stk_tf[j] = stk_tf[j - 1];
                                stk_depth[j] = stk_depth[j - 1];
                                stk_id[j] = stk_id[j - 1];
                            }
                            --j;
                        }
                        stk[j] = c;
                        stk_tn[j] = d;
                        if (traced) { stk_tf[j] = df; stk_depth[j] = dd; stk_id[j] = di; }
                    }
                }
                --sp; /* the nearest is visited now, the rest wait */
                for (uint32_t i = base; traced && i < sp; ++i)
                    SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id; e_.node = stk_id[i];
                              e_.depth = i + 1; e_.t_near = stk_tn[i]; e_.t_far = stk_tf[i]);
                cur = stk[sp];
                if (traced) {
                    cur_tn = stk_tn[sp];
                    cur_tf = stk_tf[sp];
                    cur_id = stk_id[sp];
                }
                ++depth;
                continue;
            }
        } else {
#if WALK_ISA >= 1
            if (!tri_ready) { /* the triangle constants, at the first leaf: a ray that reaches none needs none */
                wide_tri_ray_init(&R.tri, r);
                tri_ready = 1;
            }
#endif
            if (WFN(leaf_)(a, w, cur & ~WIDE_LEAF_BIT, r, &R, q, cur_id, &best, &prim, &hit_block, &hit_lane,
                           hit_vwd, anyhit, traced, simd_tri)) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                          e_.count = visited);
                return 1;
            }
            best_s = best * scale; /* best only changes in a leaf */
        }
        /* Pop the next deferred child that can still hold a closer hit. */
        for (;;) {
            if (sp == 0) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id;
                          e_.reason = root_hit ? SIDX_TERM_STACK_EMPTY : SIDX_TERM_MISS_ROOT; e_.t = best;
                          e_.count = visited);
                if (!anyhit && prim != SIDX_NO_HIT) {
                    hit->t = best;
                    hit->prim = prim;
                    if (q && (q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)))
                        WFN(uv_)(a, r, q->flags, hit_block, hit_lane, hit_vwd, hit);
                }
                return 0;
            }
            --sp;
            SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_POP, e_.ray_id = q->ray_id; e_.node = stk_id[sp];
                      e_.depth = sp + 1; e_.t_near = stk_tn[sp]; e_.t_far = stk_tf[sp]);
            if (stk_tn[sp] < best_s) {
                cur = stk[sp];
                if (traced) {
                    cur_tn = stk_tn[sp];
                    cur_tf = stk_tf[sp];
                    cur_id = stk_id[sp];
                    depth = stk_depth[sp];
                }
                break;
            }
        }
    }
}

/* Each instantiation is its own (not inlined) function, so the untraced
 * walks get the same code, registers and stack frame whether or not the
 * library is built with hooks: the hooks then cost one test per ray here
 * (the traced copy is much larger and would otherwise share a frame). */
#define WNOINL static __attribute__((noinline)) WALK_TARGET
WNOINL void WFN(isect_traced_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    WFN(walk_)(a, r, q, hit, 0, 1, 0, 0);
}
WNOINL void WFN(isect_simd_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    WFN(walk_)(a, r, q, hit, 0, 0, 1, 0);
}
#if WALK_ISA >= 1
WNOINL void WFN(isect_simd_uv_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    WFN(walk_)(a, r, q, hit, 0, 0, 1, 1);
}
#else
#define isect_simd_uv_ isect_simd_ /* no SIMD kernel, nothing to keep: the plain walk does */
#endif
WNOINL void WFN(isect_other_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    WFN(walk_)(a, r, q, hit, 0, 0, 0, 0);
}
WNOINL int WFN(occl_traced_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return WFN(walk_)(a, r, q, NULL, 1, 1, 0, 0);
}
WNOINL int WFN(occl_simd_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return WFN(walk_)(a, r, q, NULL, 1, 0, 1, 0);
}
WNOINL int WFN(occl_other_)(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return WFN(walk_)(a, r, q, NULL, 1, 0, 0, 0);
}
#undef WNOINL

/* bvh_wide.c picks the untraced pair for the structure's triangle test
 * once, at build, and calls the traced one when a query has a hook. */
const wide_kernels WFN(sidx__wide_kernels_) = {WFN(isect_traced_), WFN(isect_simd_), WFN(isect_simd_uv_),
                                               WFN(isect_other_),  WFN(occl_traced_), WFN(occl_simd_),
                                               WFN(occl_other_)};
#undef isect_simd_uv_

#undef WJOIN_
#undef WJOIN
#undef WFN
#undef WINL
