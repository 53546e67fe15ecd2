/* simd_bin_scalar.h — the binning kernels of the parallel binned-SAH
 * build (parallel.c) in plain C: the reference simd_bin_sse.h matches bit
 * for bit, compiled where there is no SSE2 (not on x86-64).
 *
 * Not a normal header: parallel.c includes it (or simd_bin_sse.h) after
 * its types; both define the same names: bin_range, bounds_range,
 * used_bins, sweep_box / sweep_empty / sweep_add / sweep_area, partition. */

static inline sidx_aabb pref_box(const pref *r)
{
    sidx_aabb b = {{r->lo[0], r->lo[1], r->lo[2]}, {r->hi[0], r->hi[1], r->hi[2]}};
    return b;
}

/* Axis k of a reference's centroid, (lo + hi)·0.5 as sidx_aabb_centroid
 * computes it. */
static inline float pref_c(const pref *r, int k)
{
    return (r->lo[k] + r->hi[k]) * 0.5f;
}

static inline sidx_aabb binbox_get(const binbox *b)
{
    sidx_aabb r = {{b->lo[0], b->lo[1], b->lo[2]}, {b->hi[0], b->hi[1], b->hi[2]}};
    return r;
}

/* ---- binning and bounds, one pass over the references ----------------------------- */

static void bin_range(const par_build *build, const binspec *s, uint32_t first, uint32_t count, bins3 *out)
{
    const pref *refs = build->refs + first;
    for (uint32_t i = 0; i < count; ++i) {
        binbox ref_box;
        for (int k = 0; k < 3; ++k) {
            ref_box.lo[k] = refs[i].lo[k];
            ref_box.hi[k] = refs[i].hi[k];
        }
        ref_box.lo[3] = ref_box.hi[3] = 0.0f;
        for (int k = 0; k < 3; ++k) {
            if (!s->use[k]) continue;
            const uint32_t j = bin_of(pref_c(&refs[i], k), s->cmin[k], s->scale[k], s->nb);
            out->count[k][j]++;
            binbox_union(&out->box[k][j], &ref_box);
        }
    }
}

static void bounds_range(const par_build *build, uint32_t first, uint32_t count, sidx_aabb *bb, sidx_aabb *cb)
{
    const pref *refs = build->refs + first;
    sidx_aabb b = sidx_aabb_empty(), c = sidx_aabb_empty();
    for (uint32_t i = 0; i < count; ++i) {
        b = sidx_aabb_union(b, pref_box(&refs[i]));
        c = sidx_aabb_grow(c, sidx_v3(pref_c(&refs[i], 0), pref_c(&refs[i], 1), pref_c(&refs[i], 2)));
    }
    *bb = b;
    *cb = c;
}

/* ---- the SAH sweep over a node's bins --------------------------------------------- */

/* The non-empty bins of one axis into used[]; returns how many. */
static inline uint32_t used_bins(const uint32_t *cnt, uint32_t nb, uint32_t *used)
{
    uint32_t k = 0;
    for (uint32_t p = 0; p < nb; ++p)
        if (cnt[p]) used[k++] = p;
    return k;
}

/* The box a sweep grows. */
typedef sidx_aabb sweep_box;

static inline sweep_box sweep_empty(void) { return sidx_aabb_empty(); }
static inline sweep_box sweep_add(sweep_box acc, const binbox *b) { return sidx_aabb_union(acc, binbox_get(b)); }
static inline float sweep_area(sweep_box acc) { return sidx_aabb_area(acc); }

/* ---- partition ------------------------------------------------------------------- */

/* bvh_build.c's two-pointer loop, element for element, and while every
 * reference passes through the registers anyway, the children's boxes
 * (Wald 2007 gathers them the same way): the children then skip their own
 * pass over the references, a third of the memory traffic of a node.
 *
 * The boxes must be the bits the children's own pass would compute, and
 * min/max keep their SECOND operand on a tie (sidx_v3_min: a < b ? a : b),
 * which matters for -0.0 against +0.0: the pass keeps the LAST of equal
 * minima in index order.  The left side is finalised in index order (i
 * only grows), so it folds like the pass.  The right side is finalised in
 * REVERSE order (each element lands at --j), so it folds with the operands
 * swapped, min(x, acc): a tie then keeps the accumulator, which is the
 * element seen first in reverse, i.e. the last in index order.  (No NaN
 * can occur: coordinates are finite, so lo + hi is never inf − inf.) */
static uint32_t partition(const par_build *build, const binspec *s, uint32_t first, uint32_t count, int axis,
                          uint32_t plane, nodebox *left, nodebox *right)
{
    pref *refs = build->refs;
    uint32_t i = first, j = first + count;
    nodebox l = {sidx_aabb_empty(), sidx_aabb_empty()}, r = l;
    while (i < j) {
        const sidx_aabb b = pref_box(&refs[i]);
        const sidx_vec3 c = sidx_v3(pref_c(&refs[i], 0), pref_c(&refs[i], 1), pref_c(&refs[i], 2));
        if (bin_of(pref_c(&refs[i], axis), s->cmin[axis], s->scale[axis], s->nb) < plane) {
            l.bb = sidx_aabb_union(l.bb, b);
            l.cb = sidx_aabb_grow(l.cb, c);
            ++i;
        } else {
            r.bb = sidx_aabb_union(b, r.bb); /* swapped: see above */
            r.cb.min = sidx_v3_min(c, r.cb.min);
            r.cb.max = sidx_v3_max(c, r.cb.max);
            const pref t = refs[i];
            refs[i] = refs[--j];
            refs[j] = t;
        }
    }
    *left = l;
    *right = r;
    return i - first;
}
