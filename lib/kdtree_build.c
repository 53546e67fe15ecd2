/* kdtree_build.c — building kd-trees, the deck's way and the good way.
 *
 * The deck ("Building kD-trees"): given a cell and the primitives touching
 * it, pick an axis-aligned plane, sift the geometry into two batches (with
 * some duplication), recurse, and know when to stop.  Four builders share
 * the node allocation, leaf writing and event emission below:
 *
 *   kdtree          SAH ("Building good kD-trees": C_trav + SA(L)/SA(c)·N_L·C_tri
 *                   + SA(R)/SA(c)·N_R·C_tri) over every candidate plane, with the
 *                   O(n log n) event sweep of Wald & Havran 2006, "On building
 *                   fast kd-trees for ray tracing, and on doing that in
 *                   O(N log N)": events are sorted once at the root and each
 *                   node's sorted lists are split for its children in linear
 *                   time; only the few straddling triangles get new events,
 *                   which are sorted (small) and merged in.
 *   kdtree-binned   SAH evaluated at opt.bins fixed planes per axis ("or
 *                   predefined locations (fixed number of bins across bbox axis)").
 *   kdtree-median   the deck's "intuitive" build: largest extent, median of geometry.
 *   kdtree-middle   the same with the middle of the extent.
 *   (given)         the caller's splits, node by node
 *                   (sidx_kdtree_build_from_splits: a slide's tree as drawn).
 *
 * All of them use "perfect splits" (Havran 2000; Wald & Havran 2006 §4.3):
 * a triangle that straddles a plane is clipped to each child cell
 * (Sutherland–Hodgman on the triangle polygon) and its candidate planes in
 * the child come from the clipped box, not from the triangle's full box. */
#include <stdio.h>
#include "kdtree_internal.h"

#define SIDX_STRUCTURE_NAME "kdtree"

/* Look-ahead of the SAH termination ("Threshold of cost improvement — but
 * stretch decision over multiple levels, to avoid local minima"): a path may
 * take this many splits that do not beat the leaf cost before giving up,
 * pbrt-v3's badRefines (Pharr, Jakob, Humphreys, 4.4.2). */
#define KD_LOOKAHEAD 3u

/* ---- builder state ------------------------------------------------------ */

/* The caller's tree (sidx_kdtree_build_from_splits): its depth-first list,
 * the next entry to read, and the node id each entry became. */
typedef struct kd_given {
    const sidx_kd_split *splits;
    uint32_t count, next;
    uint32_t *ids;
    char msg[160]; /* why the list was refused */
} kd_given;

typedef struct kd_builder {
    const sidx_accel *a;
    const sidx_hook *hook;
    const char *name;
    const kd_tri *tris;
    kd_node *nodes;
    size_t nodes_cap;
    uint32_t num_nodes;
    uint32_t *prims;
    size_t prims_cap;
    uint32_t num_refs;
    uint8_t *cls;           /* WH06 per-triangle classification scratch */
    kd_given *given;        /* KD_VARIANT_GIVEN: the caller's splits */
    float c_trav, c_tri, lambda; /* lambda = 1 − empty bonus */
    uint32_t leaf_size, max_depth, bins;
    int variant;
    float inv_root_area;
    uint32_t leaves, empty_leaves, depth;
    double sah;
    /* lazy trees (kd_lazy): the top build records nodes of at most
     * lazy_max references (0 = build everything) in lazy->recs (recs_cap
     * allocated); an expansion builds one such node's subtree, its node 0
     * being the unbuilt node, whose BUILD_NODE came with the build */
    kd_lazy *lazy;
    uint32_t lazy_max;
    size_t recs_cap;
    int expanding;
    uint32_t root_id, id_base; /* event ids of the nodes, as kd_id */
} kd_builder;

/* The event id of node idx (kd_id). */
static uint32_t bid(const kd_builder *b, uint32_t idx) { return idx ? b->id_base + idx - 1u : b->root_id; }

static float axis_of(sidx_vec3 v, uint32_t k) { return k == 0 ? v.x : k == 1 ? v.y : v.z; }
static void set_axis(sidx_vec3 *v, uint32_t k, float x)
{
    if (k == 0) v->x = x;
    else if (k == 1) v->y = x;
    else v->z = x;
}

/* Probability of a random ray through the node hitting it, relative to
 * the root ("proportional to surface area ... not the volume"). */
static double rel_area(const kd_builder *b, uint32_t idx, sidx_aabb cell)
{
    return idx == 0 && !b->expanding ? 1.0 : (double)sidx_aabb_area(cell) * b->inv_root_area;
}

static sidx_status alloc_pair(kd_builder *b, uint32_t *child)
{
    if (b->num_nodes > KD_INDEX_LIMIT - 2u) return SIDX_ERR_LIMIT;
    void *p = b->nodes;
    if (!sidx__grow(b->a, &p, &b->nodes_cap, (size_t)b->num_nodes + 2u, sizeof(kd_node))) return SIDX_ERR_NOMEM;
    b->nodes = p;
    *child = b->num_nodes;
    b->num_nodes += 2u;
    return SIDX_OK;
}

/* Reserve n slots of the primitive-index array for a leaf. */
static sidx_status leaf_reserve(kd_builder *b, uint32_t n, uint32_t *offset)
{
    if (n > KD_INDEX_LIMIT - 1u - b->num_refs) return SIDX_ERR_LIMIT;
    void *p = b->prims;
    if (n && !sidx__grow(b->a, &p, &b->prims_cap, (size_t)b->num_refs + n, sizeof(uint32_t)))
        return SIDX_ERR_NOMEM;
    b->prims = p;
    *offset = b->num_refs;
    b->num_refs += n;
    return SIDX_OK;
}

static void leaf_finish(kd_builder *b, uint32_t idx, uint32_t depth, sidx_aabb cell, uint32_t n, uint32_t offset,
                        int reason)
{
    b->nodes[idx] = kd_make_leaf(n, n ? offset : 0u);
    b->leaves++;
    if (n == 0) b->empty_leaves++;
    if (depth > b->depth) b->depth = depth;
    const float cost = b->c_tri * (float)n;
    b->sah += rel_area(b, idx, cell) * cost;
    SIDX_EMIT(1, b->hook, SIDX_EV_BUILD_LEAF, e_.structure = b->name; e_.node = bid(b, idx); e_.depth = depth; e_.count = n;
              e_.cost = cost; e_.reason = reason; e_.bounds = cell; e_.prims = n ? b->prims + offset : NULL);
}

static void inner_finish(kd_builder *b, uint32_t idx, uint32_t depth, sidx_aabb cell, uint32_t axis, float pos,
                         uint32_t child, float cost, uint32_t nl, uint32_t nr)
{
    b->nodes[idx] = kd_make_inner(axis, pos, child);
    if (depth > b->depth) b->depth = depth;
    b->sah += rel_area(b, idx, cell) * b->c_trav;
    SIDX_EMIT(1, b->hook, SIDX_EV_BUILD_SPLIT, e_.structure = b->name; e_.node = bid(b, idx); e_.depth = depth;
              e_.axis = (int32_t)axis; e_.pos = pos; e_.cost = cost; e_.count = nl; e_.aux = nr; e_.bounds = cell);
}

static void emit_node(kd_builder *b, uint32_t idx, uint32_t parent, uint32_t depth, sidx_aabb cell, uint32_t n)
{
    if (b->expanding && idx == 0) return; /* the unbuilt node: its BUILD_NODE came with the build */
    SIDX_EMIT(1, b->hook, SIDX_EV_BUILD_NODE, e_.structure = b->name; e_.node = bid(b, idx);
              e_.parent = parent == UINT32_MAX ? parent : bid(b, parent); e_.depth = depth; e_.bounds = cell; e_.count = n);
}

static void split_cell(sidx_aabb cell, uint32_t axis, float pos, sidx_aabb *l, sidx_aabb *r)
{
    *l = cell;
    *r = cell;
    set_axis(&l->max, axis, pos);
    set_axis(&r->min, axis, pos);
}

/* Lazy trees: whether node idx waits for a ray instead of being built now
 * (kd_lazy): it holds at most lazy_max references and would not be made a
 * leaf before any split is priced. */
static int lazy_wait(const kd_builder *b, uint32_t n, uint32_t depth)
{
    return b->lazy_max && n <= b->lazy_max && n > b->leaf_size && depth < b->max_depth;
}

/* Writes node idx as unbuilt, its record holding what the build would
 * recurse with; `input` then belongs to the record (on failure, still to
 * the caller). */
static sidx_status lazy_defer(kd_builder *b, uint32_t idx, uint32_t parent, uint32_t depth, sidx_aabb cell,
                              uint32_t n, uint32_t bad, void *input, const size_t cnt[3])
{
    kd_lazy *L = b->lazy;
    if (L->num_recs >= KD_INDEX_LIMIT - 1u) return SIDX_ERR_LIMIT;
    void *p = L->recs;
    if (!sidx__grow(b->a, &p, &b->recs_cap, (size_t)L->num_recs + 1u, sizeof *L->recs)) return SIDX_ERR_NOMEM;
    L->recs = p;
    const uint32_t r = L->num_recs++;
    kd_lazy_rec *rec = &L->recs[r];
    memset(rec, 0, sizeof *rec);
    rec->node = idx;
    rec->parent = parent;
    rec->depth = depth;
    rec->count = n;
    rec->bad = bad;
    rec->cell = cell;
    rec->input = input;
    if (cnt) memcpy(rec->cnt, cnt, sizeof rec->cnt);
    b->nodes[idx] = kd_make_unbuilt(r);
    return SIDX_OK;
}

/* The SAH of one candidate (the deck's formula), with the empty-space
 * bonus of Wald & Havran 2006 (λ = 1 − bonus when one side is empty): a
 * split that cuts off empty space lets rays skip it cheaply and, in a
 * kd-tree, lets them terminate early, which the plain SAH does not see. */
static float sah_cost(const kd_builder *b, sidx_aabb cell, float inv_area, uint32_t axis, float pos, uint32_t nl,
                      uint32_t nr)
{
    const float lo = axis_of(cell.min, axis), hi = axis_of(cell.max, axis);
    const sidx_vec3 e = sidx_aabb_extent(cell);
    const float ea = axis == 0 ? e.y : e.x, eb = axis == 2 ? e.y : e.z;
    const float cross = ea * eb, perim = ea + eb;
    const float pl = 2.0f * (cross + (pos - lo) * perim) * inv_area;
    const float pr = 2.0f * (cross + (hi - pos) * perim) * inv_area;
    float c = b->c_trav + b->c_tri * (pl * (float)nl + pr * (float)nr);
    if (nl == 0 || nr == 0) c *= b->lambda;
    return c;
}

/* ---- perfect splits: clip a triangle to a cell --------------------------- */

#define CLIP_CAP 24

/* Bounds of triangle ∩ cell (Sutherland–Hodgman against the six planes).
 * The result is grown by a few ulps and then clamped to both the
 * triangle's own box and the cell: rounding in the clipped vertices must
 * never make the box smaller than the true intersection, or a triangle
 * could miss a cell it pokes into (a leak).  If rounding clips everything
 * away the caller already knows the triangle straddles, so we fall back to
 * the always-conservative triangle box ∩ cell. */
static sidx_aabb clip_bounds(const kd_tri *t, sidx_aabb cell)
{
    sidx_vec3 buf[2][CLIP_CAP];
    int n = 3, cur = 0;
    buf[0][0] = t->v0;
    buf[0][1] = t->v1;
    buf[0][2] = t->v2;
    sidx_aabb tb = sidx_aabb_empty();
    tb = sidx_aabb_grow(sidx_aabb_grow(sidx_aabb_grow(tb, t->v0), t->v1), t->v2);
    int ok = 1;
    for (uint32_t k = 0; k < 3 && ok; ++k) {
        for (int side = 0; side < 2 && ok; ++side) {
            const float plane = side ? axis_of(cell.max, k) : axis_of(cell.min, k);
            const sidx_vec3 *in = buf[cur];
            sidx_vec3 *out = buf[cur ^ 1];
            int m = 0;
            if (n > CLIP_CAP / 2) { ok = 0; break; }
            for (int i = 0; i < n; ++i) {
                const sidx_vec3 p = in[i], q = in[(i + 1) % n];
                const float dp = side ? plane - axis_of(p, k) : axis_of(p, k) - plane;
                const float dq = side ? plane - axis_of(q, k) : axis_of(q, k) - plane;
                if (dp >= 0.0f) out[m++] = p;
                if ((dp >= 0.0f) != (dq >= 0.0f)) {
                    const float s = dp / (dp - dq);
                    sidx_vec3 v = sidx_v3_add(p, sidx_v3_scale(sidx_v3_sub(q, p), s));
                    set_axis(&v, k, plane);
                    out[m++] = v;
                }
            }
            n = m;
            cur ^= 1;
            if (n == 0) ok = 0;
        }
    }
    sidx_aabb r = sidx_aabb_empty();
    if (ok) {
        for (int i = 0; i < n; ++i) r = sidx_aabb_grow(r, buf[cur][i]);
        for (uint32_t k = 0; k < 3; ++k) {
            const float lo = axis_of(r.min, k), hi = axis_of(r.max, k);
            const float eps = (fabsf(lo) + fabsf(hi)) * 0x1p-21f;
            set_axis(&r.min, k, lo - eps);
            set_axis(&r.max, k, hi + eps);
        }
    } else {
        r = tb;
    }
    /* clamp to triangle box and cell; a collapsed axis becomes a point
     * inside both (never an empty interval). */
    for (uint32_t k = 0; k < 3; ++k) {
        float lo = axis_of(r.min, k), hi = axis_of(r.max, k);
        const float clo = fmaxf(axis_of(tb.min, k), axis_of(cell.min, k));
        const float chi = fminf(axis_of(tb.max, k), axis_of(cell.max, k));
        lo = fmaxf(lo, clo);
        hi = fminf(hi, chi);
        if (lo > hi) { lo = clo; hi = chi; }
        if (lo > hi) lo = hi = fminf(fmaxf(axis_of(tb.min, k), axis_of(cell.min, k)), axis_of(cell.max, k));
        set_axis(&r.min, k, lo);
        set_axis(&r.max, k, hi);
    }
    return r;
}

sidx_aabb sidx__kd_clip_bounds(const kd_tri *t, sidx_aabb cell) { return clip_bounds(t, cell); }

/* ==== the SAH builder: Wald & Havran 2006 event sweep ===================== */

/* An event is one 64-bit key: the position as an order-preserving 32-bit
 * integer, then the type, then the primitive.  Sorting the keys as
 * integers gives exactly the paper's order: by position, and at equal
 * positions ends before planars before starts (so the sweep sees a plane's
 * "p−" events before its "p+" ones). */
typedef uint64_t kd_event;
enum { EV_END = 0, EV_PLANAR = 1, EV_START = 2 };
#define EV_PRIM_MASK (KD_INDEX_LIMIT - 1u)

static uint32_t float_key(float f)
{
    uint32_t u;
    f += 0.0f; /* −0 → +0: one plane, one key */
    memcpy(&u, &f, sizeof u);
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}
static float key_float(uint32_t k)
{
    const uint32_t u = (k & 0x80000000u) ? (k & 0x7fffffffu) : ~k;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
static kd_event make_event(float pos, uint32_t type, uint32_t prim)
{
    return ((uint64_t)float_key(pos) << 32) | ((uint64_t)type << 30) | prim;
}
static uint32_t ev_key(kd_event e) { return (uint32_t)(e >> 32); }
static uint32_t ev_type(kd_event e) { return (uint32_t)(e >> 30) & 3u; }
static uint32_t ev_prim(kd_event e) { return (uint32_t)e & EV_PRIM_MASK; }

static void sort_events(kd_event *a, size_t n)
{
    /* Quicksort (median of three, Hoare partition, loop on the larger
     * half) with insertion sort below 16: keys are unique, so no
     * three-way partition is needed. */
    while (n > 16) {
        const size_t m = n / 2;
        kd_event t;
        if (a[m] < a[0]) { t = a[m]; a[m] = a[0]; a[0] = t; }
        if (a[n - 1] < a[0]) { t = a[n - 1]; a[n - 1] = a[0]; a[0] = t; }
        if (a[n - 1] < a[m]) { t = a[n - 1]; a[n - 1] = a[m]; a[m] = t; }
        const kd_event p = a[m];
        ptrdiff_t i = -1, j = (ptrdiff_t)n;
        for (;;) {
            do ++i; while (a[i] < p);
            do --j; while (a[j] > p);
            if (i >= j) break;
            t = a[i]; a[i] = a[j]; a[j] = t;
        }
        const size_t nl = (size_t)j + 1, nr = n - nl;
        if (nl < nr) {
            sort_events(a, nl);
            a += nl;
            n = nr;
        } else {
            sort_events(a + nl, nr);
            n = nl;
        }
    }
    for (size_t i = 1; i < n; ++i) {
        const kd_event x = a[i];
        size_t j = i;
        while (j > 0 && a[j - 1] > x) { a[j] = a[j - 1]; --j; }
        a[j] = x;
    }
}

/* Events of box `bx` on axis k: a planar event for a flat extent, else a
 * start and an end.  Returns how many were written. */
static size_t box_events(kd_event *out, sidx_aabb bx, uint32_t k, uint32_t prim)
{
    const float lo = axis_of(bx.min, k), hi = axis_of(bx.max, k);
    if (lo == hi) {
        out[0] = make_event(lo, EV_PLANAR, prim);
        return 1;
    }
    out[0] = make_event(lo, EV_START, prim);
    out[1] = make_event(hi, EV_END, prim);
    return 2;
}

enum { CLS_BOTH = 0, CLS_LEFT = 1, CLS_RIGHT = 2 };

typedef struct sah_best {
    float cost;
    float pos;
    uint32_t axis;
    int planar_left;
    uint32_t nl, nr;
} sah_best;

/* The sweep over one axis's sorted events (WH06 Alg. 4): N_L, N_P, N_R are
 * updated plane by plane; planar triangles lying in the plane are tried on
 * either side and put on the cheaper one.  Only planes strictly inside the
 * cell are candidates: a plane on the cell's face separates nothing. */
static void sweep_axis(kd_builder *b, uint32_t idx, sidx_aabb cell, float inv_area, uint32_t k, const kd_event *E,
                       size_t m, uint32_t n, sah_best *best)
{
    const float lo = axis_of(cell.min, k), hi = axis_of(cell.max, k);
    uint32_t nl = 0, nr = n;
    size_t i = 0;
    while (i < m) {
        const uint32_t key = ev_key(E[i]);
        const float p = key_float(key);
        uint32_t pe = 0, pp = 0, ps = 0;
        while (i < m && ev_key(E[i]) == key && ev_type(E[i]) == EV_END) { ++pe; ++i; }
        while (i < m && ev_key(E[i]) == key && ev_type(E[i]) == EV_PLANAR) { ++pp; ++i; }
        while (i < m && ev_key(E[i]) == key && ev_type(E[i]) == EV_START) { ++ps; ++i; }
        nr -= pe + pp;
        if (p > lo && p < hi) {
            const float cl = sah_cost(b, cell, inv_area, k, p, nl + pp, nr);
            const float cr = pp ? sah_cost(b, cell, inv_area, k, p, nl, nr + pp) : cl;
            const int left = cl <= cr;
            const float c = left ? cl : cr;
            const uint32_t cnl = left ? nl + pp : nl, cnr = left ? nr : nr + pp;
            SIDX_EMIT(1, b->hook, SIDX_EV_BUILD_CANDIDATE, e_.structure = b->name; e_.node = bid(b, idx);
                      e_.axis = (int32_t)k; e_.pos = p; e_.cost = c; e_.count = cnl; e_.aux = cnr);
            if (c < best->cost) {
                best->cost = c;
                best->pos = p;
                best->axis = k;
                best->planar_left = left;
                best->nl = cnl;
                best->nr = cnr;
            }
        }
        nl += ps + pp;
    }
}

/* One node.  `ev` holds the node's three sorted event lists back to back
 * (lengths cnt[0..2]) and is owned (freed) here. */
static sidx_status sah_node(kd_builder *b, uint32_t idx, uint32_t parent, uint32_t depth, sidx_aabb cell,
                            kd_event *ev, const size_t cnt[3], uint32_t n, uint32_t bad)
{
    sidx_status s = SIDX_OK;
    const kd_event *E[3] = {ev, ev + cnt[0], ev + cnt[0] + cnt[1]};
    emit_node(b, idx, parent, depth, cell, n);
    if (lazy_wait(b, n, depth)) {
        s = lazy_defer(b, idx, parent, depth, cell, n, bad, ev, cnt);
        if (s != SIDX_OK) sidx__free(b->a, ev);
        return s;
    }

    int reason = SIDX_LEAF_NONE;
    sah_best best = {INFINITY, 0.0f, 0, 1, 0, 0};
    const float leaf_cost = b->c_tri * (float)n;
    if (n == 0) reason = SIDX_LEAF_EMPTY;
    else if (n <= b->leaf_size) reason = SIDX_LEAF_FEW_PRIMS;
    else if (depth >= b->max_depth) reason = SIDX_LEAF_MAX_DEPTH;
    else {
        const float area = sidx_aabb_area(cell);
        if (area > 0.0f) {
            const float inv_area = 1.0f / area;
            for (uint32_t k = 0; k < 3; ++k) sweep_axis(b, idx, cell, inv_area, k, E[k], cnt[k], n, &best);
        }
        if (best.cost == INFINITY) reason = SIDX_LEAF_NO_SPLIT;
        else if (best.cost >= leaf_cost) {
            /* Not better than a leaf here; maybe one or two levels down
             * (the look-ahead).  pbrt's extra rule: a much worse split on
             * few triangles is not worth exploring at all. */
            ++bad;
            if (bad >= KD_LOOKAHEAD || (best.cost > 4.0f * leaf_cost && n < 16)) reason = SIDX_LEAF_NO_GAIN;
        }
    }

    if (reason != SIDX_LEAF_NONE) {
        uint32_t off = 0;
        s = leaf_reserve(b, n, &off);
        if (s == SIDX_OK) {
            /* every primitive has exactly one start or planar event per axis */
            uint32_t w = 0;
            for (size_t i = 0; i < cnt[0]; ++i)
                if (ev_type(E[0][i]) != EV_END) b->prims[off + w++] = ev_prim(E[0][i]);
            leaf_finish(b, idx, depth, cell, n, off, reason);
        }
        sidx__free(b->a, ev);
        return s;
    }

    /* ---- classify (WH06 Alg. 5) ---- */
    const uint32_t k = best.axis;
    const float p = best.pos;
    const kd_event *Ek = E[k];
    for (size_t i = 0; i < cnt[k]; ++i) b->cls[ev_prim(Ek[i])] = CLS_BOTH;
    for (size_t i = 0; i < cnt[k]; ++i) {
        const uint32_t t = ev_type(Ek[i]);
        const float q = key_float(ev_key(Ek[i]));
        const uint32_t pr = ev_prim(Ek[i]);
        if (t == EV_END && q <= p) b->cls[pr] = CLS_LEFT;
        else if (t == EV_START && q >= p) b->cls[pr] = CLS_RIGHT;
        else if (t == EV_PLANAR) {
            if (q < p || (q == p && best.planar_left)) b->cls[pr] = CLS_LEFT;
            else b->cls[pr] = CLS_RIGHT;
        }
    }
    uint32_t nboth = 0, nl = 0, nr = 0;
    for (size_t i = 0; i < cnt[k]; ++i) {
        if (ev_type(Ek[i]) == EV_END) continue;
        const uint8_t c = b->cls[ev_prim(Ek[i])];
        nboth += c == CLS_BOTH;
        nl += c != CLS_RIGHT;
        nr += c != CLS_LEFT;
    }

    /* ---- straddlers: clip to both children, new events ---- */
    sidx_aabb lcell, rcell;
    split_cell(cell, k, p, &lcell, &rcell);
    uint32_t *both = NULL;
    sidx_aabb *bl = NULL, *br = NULL;
    kd_event *scratch = NULL, *evl = NULL, *evr = NULL;
    if (nboth) {
        both = sidx__alloc(b->a, nboth, sizeof *both);
        bl = sidx__alloc(b->a, (size_t)nboth * 2u, sizeof *bl);
        scratch = sidx__alloc(b->a, (size_t)nboth * 2u, sizeof *scratch);
        if (!both || !bl || !scratch) { s = SIDX_ERR_NOMEM; goto fail; }
        br = bl + nboth;
        uint32_t w = 0;
        for (size_t i = 0; i < cnt[k]; ++i)
            if (ev_type(Ek[i]) != EV_END && b->cls[ev_prim(Ek[i])] == CLS_BOTH) both[w++] = ev_prim(Ek[i]);
        for (uint32_t i = 0; i < nboth; ++i) {
            bl[i] = clip_bounds(&b->tris[both[i]], lcell);
            br[i] = clip_bounds(&b->tris[both[i]], rcell);
        }
    }

    /* ---- split the sorted lists in one pass each, merge the new events ---- */
    size_t lc[3] = {0, 0, 0}, rc[3] = {0, 0, 0};
    for (uint32_t a = 0; a < 3; ++a) {
        for (size_t i = 0; i < cnt[a]; ++i) {
            const uint8_t c = b->cls[ev_prim(E[a][i])];
            lc[a] += c == CLS_LEFT;
            rc[a] += c == CLS_RIGHT;
        }
        for (uint32_t i = 0; i < nboth; ++i) {
            lc[a] += axis_of(bl[i].min, a) == axis_of(bl[i].max, a) ? 1u : 2u;
            rc[a] += axis_of(br[i].min, a) == axis_of(br[i].max, a) ? 1u : 2u;
        }
    }
    evl = sidx__alloc(b->a, lc[0] + lc[1] + lc[2], sizeof *evl);
    evr = sidx__alloc(b->a, rc[0] + rc[1] + rc[2], sizeof *evr);
    if (!evl || !evr) { s = SIDX_ERR_NOMEM; goto fail; }
    {
        kd_event *dl = evl, *dr = evr;
        for (uint32_t a = 0; a < 3; ++a) {
            size_t ol = 0, or_ = 0;
            for (size_t i = 0; i < cnt[a]; ++i) {
                const uint8_t c = b->cls[ev_prim(E[a][i])];
                if (c == CLS_LEFT) dl[ol++] = E[a][i];
                else if (c == CLS_RIGHT) dr[or_++] = E[a][i];
            }
            for (int side = 0; side < 2; ++side) {
                kd_event *d = side ? dr : dl;
                size_t old = side ? or_ : ol;
                const sidx_aabb *bx = side ? br : bl;
                size_t nn = 0;
                for (uint32_t i = 0; i < nboth; ++i) nn += box_events(scratch + nn, bx[i], a, both[i]);
                sort_events(scratch, nn);
                /* merge from the back, in place */
                size_t o = old + nn;
                ptrdiff_t ii = (ptrdiff_t)old - 1, jj = (ptrdiff_t)nn - 1;
                while (jj >= 0) {
                    if (ii >= 0 && d[ii] > scratch[jj]) d[--o] = d[ii--];
                    else d[--o] = scratch[jj--];
                }
            }
            dl += lc[a];
            dr += rc[a];
        }
    }
    sidx__free(b->a, both);
    sidx__free(b->a, bl);
    sidx__free(b->a, scratch);
    both = NULL;
    bl = NULL;
    scratch = NULL;

    uint32_t child;
    s = alloc_pair(b, &child);
    if (s != SIDX_OK) goto fail;
    inner_finish(b, idx, depth, cell, k, p, child, best.cost, nl, nr);
    sidx__free(b->a, ev);
    ev = NULL;
    s = sah_node(b, child, idx, depth + 1, lcell, evl, lc, nl, bad);
    evl = NULL;
    if (s != SIDX_OK) goto fail;
    s = sah_node(b, child + 1, idx, depth + 1, rcell, evr, rc, nr, bad);
    return s;

fail:
    sidx__free(b->a, both);
    sidx__free(b->a, bl);
    sidx__free(b->a, scratch);
    sidx__free(b->a, evl);
    sidx__free(b->a, evr);
    sidx__free(b->a, ev);
    return s;
}

static sidx_status build_sah(kd_builder *b, sidx_aabb root)
{
    const uint32_t n = b->a->mesh->num_triangles;
    size_t cnt[3] = {0, 0, 0};
    sidx_aabb *boxes = NULL;
    sidx_status s = sidx__prim_boxes(b->a, &boxes, NULL);
    if (s != SIDX_OK) return s;
    for (uint32_t k = 0; k < 3; ++k)
        for (uint32_t i = 0; i < n; ++i) cnt[k] += axis_of(boxes[i].min, k) == axis_of(boxes[i].max, k) ? 1u : 2u;
    kd_event *ev = sidx__alloc(b->a, cnt[0] + cnt[1] + cnt[2], sizeof *ev);
    b->cls = sidx__alloc(b->a, n, 1);
    if (!ev || !b->cls) {
        sidx__free(b->a, boxes);
        sidx__free(b->a, ev);
        return SIDX_ERR_NOMEM;
    }
    kd_event *d = ev;
    for (uint32_t k = 0; k < 3; ++k) {
        size_t w = 0;
        for (uint32_t i = 0; i < n; ++i) w += box_events(d + w, boxes[i], k, i);
        sort_events(d, w); /* the one and only full sort */
        d += w;
    }
    sidx__free(b->a, boxes);
    return sah_node(b, 0, UINT32_MAX, 0, root, ev, cnt, n, 0);
}

/* ==== reference-list builders: binned SAH, median, middle ================= */

typedef struct kd_ref {
    sidx_aabb box; /* the triangle's box clipped to the current cell */
    uint32_t prim;
} kd_ref;

/* k-th smallest of v[0..n) (Hoare's selection), partially reorders v. */
static float select_kth(float *v, ptrdiff_t n, ptrdiff_t kth)
{
    ptrdiff_t lo = 0, hi = n - 1;
    while (lo < hi) {
        const float p = v[lo + (hi - lo) / 2];
        ptrdiff_t i = lo, j = hi;
        while (i <= j) {
            while (v[i] < p) ++i;
            while (v[j] > p) --j;
            if (i <= j) {
                const float t = v[i];
                v[i++] = v[j];
                v[j--] = t;
            }
        }
        /* now v[lo..j] <= p <= v[i..hi] and everything between equals p */
        if (kth <= j) hi = j;
        else if (kth >= i) lo = i;
        else break;
    }
    return v[kth];
}

/* Binned SAH: B equal bins per axis; a primitive counts on the left of
 * plane i if its box starts in a bin left of it, on the right if it ends
 * in a bin at or right of it. */
static sidx_status binned_choice(kd_builder *b, uint32_t idx, sidx_aabb cell, const kd_ref *refs, uint32_t n,
                                 sah_best *best)
{
    const uint32_t B = b->bins;
    uint32_t *cnt = sidx__calloc(b->a, (size_t)B * 2u, sizeof *cnt);
    if (!cnt) return SIDX_ERR_NOMEM;
    const float area = sidx_aabb_area(cell);
    if (!(area > 0.0f)) { sidx__free(b->a, cnt); return SIDX_OK; }
    const float inv_area = 1.0f / area;
    for (uint32_t k = 0; k < 3; ++k) {
        const float lo = axis_of(cell.min, k), hi = axis_of(cell.max, k);
        if (!(hi > lo)) continue;
        uint32_t *start = cnt, *end = cnt + B;
        memset(cnt, 0, (size_t)B * 2u * sizeof *cnt);
        const float scale = (float)B / (hi - lo);
        for (uint32_t i = 0; i < n; ++i) {
            /* clamp in float: when hi - lo overflows, scale is 0 and
             * inf·0 = NaN, which no int holds (found by fuzz_build) */
            const float f0 = (axis_of(refs[i].box.min, k) - lo) * scale;
            const float f1 = (axis_of(refs[i].box.max, k) - lo) * scale;
            const int s0 = f0 > 0.0f ? (f0 < (float)B ? (int)f0 : (int)B - 1) : 0;
            const int s1 = f1 > 0.0f ? (f1 < (float)B ? (int)f1 : (int)B - 1) : 0;
            start[s0]++;
            end[s1]++;
        }
        uint32_t nl = 0, nr = n;
        for (uint32_t i = 1; i < B; ++i) {
            nl += start[i - 1];
            nr -= end[i - 1];
            const float p = lo + (hi - lo) * (float)i / (float)B;
            if (!(p > lo && p < hi)) continue;
            const float c = sah_cost(b, cell, inv_area, k, p, nl, nr);
            SIDX_EMIT(1, b->hook, SIDX_EV_BUILD_CANDIDATE, e_.structure = b->name; e_.node = bid(b, idx);
                      e_.axis = (int32_t)k; e_.pos = p; e_.cost = c; e_.count = nl; e_.aux = nr);
            if (c < best->cost) {
                best->cost = c;
                best->pos = p;
                best->axis = k;
                best->nl = nl;
                best->nr = nr;
            }
        }
    }
    sidx__free(b->a, cnt);
    return SIDX_OK;
}

/* The given tree's next node: a leaf (reason "given", or "empty" when no
 * triangle reaches its cell) or a split, checked against the cell. */
static sidx_status given_choice(kd_given *g, uint32_t idx, uint32_t depth, sidx_aabb cell, uint32_t n, int *reason,
                                sah_best *best)
{
    if (g->next >= g->count) {
        snprintf(g->msg, sizeof g->msg, "the list of %u nodes ends before the tree does (node %u has none)", g->count,
                 idx);
        return SIDX_ERR_INVALID_ARG;
    }
    const uint32_t i = g->next++;
    const sidx_kd_split sp = g->splits[i];
    g->ids[i] = idx;
    if (sp.axis == SIDX_KD_LEAF) {
        *reason = n ? SIDX_LEAF_GIVEN : SIDX_LEAF_EMPTY;
        return SIDX_OK;
    }
    if (sp.axis > 2) {
        snprintf(g->msg, sizeof g->msg, "entry %u: axis %u (0, 1, 2 split x, y, z; %u is a leaf)", i, sp.axis,
                 SIDX_KD_LEAF);
        return SIDX_ERR_INVALID_ARG;
    }
    const float lo = axis_of(cell.min, sp.axis), hi = axis_of(cell.max, sp.axis);
    if (!(sp.pos > lo && sp.pos < hi)) {
        snprintf(g->msg, sizeof g->msg, "entry %u: split %c = %g is not inside its cell (%g, %g)", i, "xyz"[sp.axis],
                 (double)sp.pos, (double)lo, (double)hi);
        return SIDX_ERR_INVALID_ARG;
    }
    if (depth + 1u > KD_MAX_DEPTH) {
        snprintf(g->msg, sizeof g->msg, "entry %u: deeper than %u levels (the traversal stack)", i, KD_MAX_DEPTH);
        return SIDX_ERR_LIMIT;
    }
    best->axis = sp.axis;
    best->pos = sp.pos;
    return SIDX_OK;
}

static sidx_status refs_node(kd_builder *b, uint32_t idx, uint32_t parent, uint32_t depth, sidx_aabb cell,
                             kd_ref *refs, uint32_t n, uint32_t bad)
{
    sidx_status s = SIDX_OK;
    emit_node(b, idx, parent, depth, cell, n);
    if (!b->given && lazy_wait(b, n, depth)) {
        s = lazy_defer(b, idx, parent, depth, cell, n, bad, refs, NULL);
        if (s != SIDX_OK) sidx__free(b->a, refs);
        return s;
    }
    int reason = SIDX_LEAF_NONE;
    sah_best best = {INFINITY, 0.0f, 0, 1, 0, 0};
    const float leaf_cost = b->c_tri * (float)n;
    kd_ref *lr = NULL, *rr = NULL;
    uint32_t nl = 0, nr = 0;

    if (b->given) {
        s = given_choice(b->given, idx, depth, cell, n, &reason, &best);
        if (s != SIDX_OK) goto done;
    } else if (n == 0) reason = SIDX_LEAF_EMPTY;
    else if (n <= b->leaf_size) reason = SIDX_LEAF_FEW_PRIMS;
    else if (depth >= b->max_depth) reason = SIDX_LEAF_MAX_DEPTH;
    else if (b->variant == KD_VARIANT_BINNED) {
        s = binned_choice(b, idx, cell, refs, n, &best);
        if (s != SIDX_OK) goto done;
        if (best.cost == INFINITY) reason = SIDX_LEAF_NO_SPLIT;
        else if (best.cost >= leaf_cost) {
            ++bad;
            if (bad >= KD_LOOKAHEAD || (best.cost > 4.0f * leaf_cost && n < 16)) reason = SIDX_LEAF_NO_GAIN;
        }
    } else {
        /* the deck's "intuitive" choices: largest extent, then the middle
         * of the extent or the median of the geometry */
        const uint32_t k = (uint32_t)sidx_aabb_max_axis(cell);
        const float lo = axis_of(cell.min, k), hi = axis_of(cell.max, k);
        float p = lo + 0.5f * (hi - lo);
        if (b->variant == KD_VARIANT_MEDIAN) {
            float *c = sidx__alloc(b->a, n, sizeof *c);
            if (!c) { s = SIDX_ERR_NOMEM; goto done; }
            for (uint32_t i = 0; i < n; ++i)
                c[i] = 0.5f * (axis_of(refs[i].box.min, k) + axis_of(refs[i].box.max, k));
            const float med = select_kth(c, (ptrdiff_t)n, (ptrdiff_t)(n / 2));
            sidx__free(b->a, c);
            if (med > lo && med < hi) p = med;
        }
        if (!(p > lo && p < hi)) reason = SIDX_LEAF_NO_SPLIT;
        else {
            best.axis = k;
            best.pos = p;
        }
    }

    if (reason == SIDX_LEAF_NONE) {
        const uint32_t k = best.axis;
        const float p = best.pos;
        for (uint32_t i = 0; i < n; ++i) {
            const float lo = axis_of(refs[i].box.min, k), hi = axis_of(refs[i].box.max, k);
            nl += lo < p || hi <= p; /* a flat box in the plane goes left */
            nr += hi > p;
        }
        if (b->variant >= KD_VARIANT_MEDIAN) { /* intuitive or given: no sweep priced it */
            const float area = sidx_aabb_area(cell);
            best.cost = area > 0.0f ? sah_cost(b, cell, 1.0f / area, k, p, nl, nr) : 0.0f;
            SIDX_EMIT(1, b->hook, SIDX_EV_BUILD_CANDIDATE, e_.structure = b->name; e_.node = bid(b, idx);
                      e_.axis = (int32_t)k; e_.pos = p; e_.cost = best.cost; e_.count = nl; e_.aux = nr);
            /* a plane that separates nothing only duplicates: stop (a given tree is kept as given) */
            if (nl == n && nr == n && !b->given) reason = SIDX_LEAF_NO_SPLIT;
        }
    }

    if (reason != SIDX_LEAF_NONE) {
        uint32_t off = 0;
        s = leaf_reserve(b, n, &off);
        if (s != SIDX_OK) goto done;
        for (uint32_t i = 0; i < n; ++i) b->prims[off + i] = refs[i].prim;
        leaf_finish(b, idx, depth, cell, n, off, reason);
        goto done;
    }

    {
        const uint32_t k = best.axis;
        const float p = best.pos;
        sidx_aabb lcell, rcell;
        split_cell(cell, k, p, &lcell, &rcell);
        lr = sidx__alloc(b->a, nl, sizeof *lr);
        rr = sidx__alloc(b->a, nr, sizeof *rr);
        if (!lr || !rr) { s = SIDX_ERR_NOMEM; goto done; }
        uint32_t wl = 0, wr = 0;
        for (uint32_t i = 0; i < n; ++i) {
            const float lo = axis_of(refs[i].box.min, k), hi = axis_of(refs[i].box.max, k);
            const int L = lo < p || hi <= p, R = hi > p;
            if (L && R) {
                lr[wl].prim = rr[wr].prim = refs[i].prim;
                lr[wl++].box = clip_bounds(&b->tris[refs[i].prim], lcell);
                rr[wr++].box = clip_bounds(&b->tris[refs[i].prim], rcell);
            } else if (L) lr[wl++] = refs[i];
            else rr[wr++] = refs[i];
        }
        uint32_t child;
        s = alloc_pair(b, &child);
        if (s != SIDX_OK) goto done;
        inner_finish(b, idx, depth, cell, k, p, child, best.cost, nl, nr);
        sidx__free(b->a, refs);
        refs = NULL;
        s = refs_node(b, child, idx, depth + 1, lcell, lr, nl, bad);
        lr = NULL;
        if (s == SIDX_OK) {
            s = refs_node(b, child + 1, idx, depth + 1, rcell, rr, nr, bad);
            rr = NULL;
        }
    }
done:
    sidx__free(b->a, lr);
    sidx__free(b->a, rr);
    sidx__free(b->a, refs);
    return s;
}

static sidx_status build_refs(kd_builder *b, sidx_aabb root)
{
    const uint32_t n = b->a->mesh->num_triangles;
    kd_ref *refs = sidx__alloc(b->a, n, sizeof *refs);
    if (!refs) return SIDX_ERR_NOMEM;
    for (uint32_t i = 0; i < n; ++i) {
        const kd_tri *t = &b->tris[i];
        refs[i].prim = i;
        refs[i].box = sidx_aabb_grow(sidx_aabb_grow(sidx_aabb_grow(sidx_aabb_empty(), t->v0), t->v1), t->v2);
    }
    return refs_node(b, 0, UINT32_MAX, 0, root, refs, n, 0);
}

/* ==== entry point ========================================================== */

/* Copy an over-allocated array into one of exact size (keeps the old one
 * if that allocation fails: smaller is nicer, not required). */
static void *shrink(const sidx_accel *a, void *p, size_t count, size_t size, size_t cap)
{
    if (!p || count == cap) return p;
    void *q = sidx__alloc(a, count, size);
    if (!q) return p;
    if (count) memcpy(q, p, count * size);
    sidx__free(a, p);
    return q;
}

/* The nodes in an exact-size copy placed so that node 1 starts a 64-byte
 * cache line.  Children come in pairs (1, 2), (3, 4), ... (alloc_pair) of
 * 16 bytes, so then no pair straddles two lines and both children of a
 * node cost one miss at most; at malloc's 16-byte alignment one pair in
 * four is split.  Out of memory: the build's array stays as it is. */
static void align_nodes(const sidx_accel *a, kd_tree *kd)
{
    kd_node *mem = sidx__alloc(a, (size_t)kd->num_nodes + 8u, sizeof *mem);
    if (!mem) return;
    kd_node *nodes = (kd_node *)(void *)((((uintptr_t)(mem + 1) + 63u) & ~(uintptr_t)63u) - sizeof *mem);
    memcpy(nodes, kd->nodes, (size_t)kd->num_nodes * sizeof *nodes);
    sidx__free(a, kd->nodes_mem);
    kd->nodes_mem = mem;
    kd->nodes = nodes;
}

static void kd_free(const sidx_accel *a, kd_tree *kd)
{
    if (!kd) return;
    kd_lazy *L = kd->lazy;
    if (L) {
        for (uint32_t r = 0; r < L->num_recs; ++r) {
            sidx__free(a, L->recs[r].input);
            if (L->parts) kd_free(a, sidx__lazy_peek(&L->life, r));
        }
        sidx__free(a, L->parts);
        sidx__free(a, L->recs);
        sidx__free(a, L->tris);
        sidx__free(a, L);
    }
    sidx__free(a, kd->nodes_mem);
    sidx__free(a, kd->prims);
    sidx__free(a, kd->blocks_mem);
    sidx__free(a, kd);
}

/* One copy of each reference's triangle, four references to a block in
 * structure-of-arrays form, in reference order (kdtree_internal.h).  The
 * lanes past the last reference get NaN vertices (no comparison on them
 * is true, so the SIMD test never reports them) and TRI4_PAD_PRIM. */
sidx_status sidx__kd_make_blocks(const sidx_accel *a, kd_tree *kd, const sidx_mesh *m)
{
    sidx__free(a, kd->blocks_mem);
    kd->blocks = NULL;
    kd->blocks_mem = NULL;
    const uint32_t nb = (kd->num_refs + 3u) / 4u;
    kd->num_blocks = nb;
    kd->blocks_mem = sidx__alloc(a, (size_t)(nb ? nb : 1u) * sizeof(tri4_block) + 64u, 1);
    if (!kd->blocks_mem) return SIDX_ERR_NOMEM;
    kd->blocks = (tri4_block *)(void *)(((uintptr_t)kd->blocks_mem + 63u) & ~(uintptr_t)63u);
    for (uint32_t i = 0; i < 4u * nb; ++i) {
        tri4_block *B = &kd->blocks[i / 4u];
        const uint32_t l = i % 4u;
        if (i < kd->num_refs) {
            const sidx_vec3 p[3] = {sidx_mesh_vertex(m, kd->prims[i], 0), sidx_mesh_vertex(m, kd->prims[i], 1),
                                    sidx_mesh_vertex(m, kd->prims[i], 2)};
            tri4_set_lane(B, l, p, kd->prims[i]);
        } else {
            tri4_set_lane(B, l, NULL, 0);
        }
    }
    return SIDX_OK;
}

static void *kd_expand(void *owner, uint32_t r, const sidx_hook *hook, sidx__lazy_made *made);

static sidx_status kd_build(sidx_accel *a, kd_given *given, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    const uint32_t n = m->num_triangles;
    a->impl = NULL;
    if (n >= KD_INDEX_LIMIT)
        return sidx__fail(err, SIDX_ERR_LIMIT, "%s: %u triangles exceed the 8-byte node encoding (< 2^30)", a->name,
                          n);
    const sidx_aabb root = sidx_mesh_bounds(m);
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_BEGIN, e_.structure = a->name; e_.count = n; e_.bounds = root);
    if (given)
        SIDX_EMIT(1, a->opt.hook, SIDX_EV_NOTE, e_.structure = a->name;
                  e_.text = "kdtree: the splits are given (sidx_kdtree_build_from_splits), no cost chose them");

    kd_tree *kd = sidx__calloc(a, 1, sizeof *kd);
    if (!kd) return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory", a->name);
    /* the builder's copy of the triangles (clipping reads them) */
    kd_tri *tris = sidx__alloc(a, n ? n : 1u, sizeof *tris);
    if (!tris) { kd_free(a, kd); return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory", a->name); }
    for (uint32_t i = 0; i < n; ++i) {
        tris[i].v0 = sidx_mesh_vertex(m, i, 0);
        tris[i].v1 = sidx_mesh_vertex(m, i, 1);
        tris[i].v2 = sidx_mesh_vertex(m, i, 2);
        tris[i].prim = i;
    }
    kd->bounds = root;
    kd->root_id = 0;
    kd->id_base = 1;
    const uint32_t lazy_max = a->opt.lazy == 1 ? SIDX_LAZY_DEFAULT : a->opt.lazy;
    if (lazy_max && !given && n > 0) {
        kd->lazy = sidx__calloc(a, 1, sizeof *kd->lazy);
        if (!kd->lazy) {
            sidx__free(a, tris);
            kd_free(a, kd);
            return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory", a->name);
        }
    }

    kd_builder b;
    memset(&b, 0, sizeof b);
    b.lazy = kd->lazy;
    b.lazy_max = kd->lazy ? lazy_max : 0u;
    b.root_id = 0;
    b.id_base = 1;
    b.a = a;
    b.hook = a->opt.hook;
    b.name = a->name;
    b.tris = tris;
    b.variant = a->variant;
    b.given = given;
    /* The defaults and why: kdtree_internal.h. */
    b.c_trav = a->opt.c_trav > 0.0f ? a->opt.c_trav : KD_DEFAULT_C_TRAV;
    b.c_tri = a->opt.c_tri > 0.0f ? a->opt.c_tri : KD_DEFAULT_C_TRI;
    const float bonus = a->opt.empty_bonus > 0.0f ? a->opt.empty_bonus : KD_DEFAULT_EMPTY_BONUS;
    b.lambda = 1.0f - bonus;
    b.leaf_size = a->opt.leaf_size ? a->opt.leaf_size
                  : a->variant >= KD_VARIANT_MEDIAN ? KD_DEFAULT_LEAF_INTUITIVE : KD_DEFAULT_LEAF_SAH;
    /* pbrt's depth limit 8 + 1.3·log2(n): deep enough for "typical depth
     * of 50-100" only on huge scenes, shallow enough to bound duplication. */
    uint32_t md = a->opt.max_depth;
    if (md == 0) md = (uint32_t)lrint(8.0 + 1.3 * log2((double)(n ? n : 1)));
    b.max_depth = md < KD_MAX_DEPTH ? md : KD_MAX_DEPTH;
    b.bins = a->opt.bins ? a->opt.bins : 32u;
    if (b.bins < 2u) b.bins = 2u;
    const float ra = sidx_aabb_area(root);
    b.inv_root_area = ra > 0.0f ? 1.0f / ra : 0.0f;

    sidx_status s = SIDX_OK;
    uint32_t child;
    s = alloc_pair(&b, &child); /* slot 0 = root; slot 1 is reused as the first child */
    if (s == SIDX_OK) {
        b.num_nodes = 1;
        if (n == 0 && !given) {
            uint32_t off = 0;
            s = leaf_reserve(&b, 0, &off);
            if (s == SIDX_OK) leaf_finish(&b, 0, 0, root, 0, 0, SIDX_LEAF_EMPTY);
        } else if (a->variant == KD_VARIANT_SAH) {
            s = build_sah(&b, root);
        } else {
            s = build_refs(&b, root);
        }
    }
    sidx__free(a, b.cls);
    if (kd->lazy) kd->lazy->tris = tris; /* the expansions clip with them */
    else sidx__free(a, tris);
    kd->nodes = kd->nodes_mem = b.nodes;
    kd->prims = b.prims;
    if (s == SIDX_OK && given && given->next != given->count) {
        snprintf(given->msg, sizeof given->msg, "the tree ends after %u of the list's %u nodes", given->next,
                 given->count);
        s = SIDX_ERR_INVALID_ARG;
    }
    if (s != SIDX_OK) {
        kd_free(a, kd);
        if (given && given->msg[0]) return sidx__fail(err, s, "%s: given splits: %s", a->name, given->msg);
        if (s == SIDX_ERR_LIMIT)
            return sidx__fail(err, s, "%s: the tree outgrows the 8-byte node encoding (2^30 nodes/references)",
                              a->name);
        return sidx__fail(err, s, "%s: out of memory", a->name);
    }
    kd->num_nodes = b.num_nodes;
    kd->num_refs = b.num_refs;
    align_nodes(a, kd);
    kd->prims = shrink(a, kd->prims, kd->num_refs, sizeof *kd->prims, b.prims_cap);
    s = sidx__kd_make_blocks(a, kd, m);
    if (s != SIDX_OK) {
        kd_free(a, kd);
        return sidx__fail(err, s, "%s: out of memory", a->name);
    }
    kd->leaves = b.leaves;
    kd->empty_leaves = b.empty_leaves;
    kd->max_depth = b.depth;
    kd->sah_cost = b.sah;
    kd->c_trav = b.c_trav;
    kd->c_tri = b.c_tri;
    kd->empty_bonus = bonus;
    if (kd->lazy) {
        /* one part of lazy.c per unbuilt node, each waiting for a ray */
        kd_lazy *L = kd->lazy;
        L->parts = sidx__calloc(a, L->num_recs ? L->num_recs : 1u, sizeof *L->parts);
        if (!L->parts) {
            kd_free(a, kd);
            return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory", a->name);
        }
        sidx__lazy_init(&L->life, L->parts, L->num_recs, kd_expand, a);
        for (uint32_t r = 0; r < L->num_recs; ++r) sidx__lazy_defer(&L->life, r, L->recs[r].count);
        L->leaf_size = b.leaf_size;
        L->max_depth = b.max_depth;
        L->bins = b.bins;
        L->next_id = kd->num_nodes;
        kd->sah_cost = 0.0; /* the SAH of a tree not yet whole: not given (sidx_accel_stats) */
        a->lazy = 1;
    }
    a->impl = kd;
    a->fills_uv = a->fills_ng = 1; /* from the leaves' triangle copies (kdtree_traverse.c) */
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_END, e_.structure = a->name; e_.node = kd->num_nodes;
              e_.count = kd->num_refs; e_.depth = kd->max_depth);
    return SIDX_OK;
}

sidx_status sidx__kd_build(sidx_accel *a, sidx_error *err) { return kd_build(a, NULL, err); }

static sidx_status given_build(sidx_accel *a, void *arg, sidx_error *err) { return kd_build(a, arg, err); }

sidx_status sidx_kdtree_build_from_splits(const sidx_mesh *mesh, const sidx_kd_split *splits, uint32_t count,
                                          const sidx_build_options *opt, sidx_accel **out, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_kdtree_build_from_splits: out is NULL");
    *out = NULL;
    if (!mesh || !splits || count == 0)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_kdtree_build_from_splits: no mesh or no splits");
    for (uint32_t i = 0; i < count; ++i)
        if (splits[i].label && strlen(splits[i].label) >= SIDX_LABEL_MAX)
            return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_kdtree_build_from_splits: entry %u: label too long", i);
    kd_given g;
    memset(&g, 0, sizeof g);
    g.splits = splits;
    g.count = count;
    g.ids = malloc((size_t)count * sizeof *g.ids);
    if (!g.ids) return sidx__fail(err, SIDX_ERR_NOMEM, "sidx_kdtree_build_from_splits: out of memory");
    sidx_accel *a = NULL;
    sidx_status s = sidx__accel_build_with("kdtree", &sidx__kdtree_vtable, KD_VARIANT_GIVEN, mesh, opt, given_build,
                                           &g, &a, err);
    for (uint32_t i = 0; s == SIDX_OK && i < count; ++i)
        if (splits[i].label && splits[i].label[0]) s = sidx_accel_set_node_label(a, g.ids[i], splits[i].label, err);
    free(g.ids);
    if (s != SIDX_OK) {
        sidx_accel_destroy(a);
        return s;
    }
    *out = a;
    return SIDX_OK;
}

void sidx__kd_destroy(sidx_accel *a)
{
    kd_free(a, a->impl);
    a->impl = NULL;
}

void sidx__kd_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const kd_tree *kd = a->impl;
    if (!kd) return;
    s->nodes = kd->num_nodes;
    s->leaves = kd->leaves;
    s->empty_leaves = kd->empty_leaves;
    s->max_depth = kd->max_depth;
    s->prim_refs = kd->num_refs;
    const uint32_t full = kd->leaves - kd->empty_leaves;
    s->mean_leaf_prims = full ? (double)kd->num_refs / (double)full : 0.0;
    s->bytes = sizeof *kd + (size_t)kd->num_nodes * sizeof(kd_node) + (size_t)kd->num_refs * sizeof(uint32_t) +
               (size_t)kd->num_blocks * sizeof(tri4_block);
    s->sah_cost = kd->sah_cost;
    const kd_lazy *L = kd->lazy;
    if (L) {
        /* the top tree and the subtrees built so far (each replaces the
         * unbuilt node it was counted as); lazy.c's counters for the rest */
        const sidx__lazy_counts c = sidx__lazy_counts_get(&L->life);
        for (uint32_t r = 0; r < L->num_recs; ++r) {
            const kd_tree *sub = sidx__lazy_peek(&L->life, r);
            if (!sub) continue;
            s->nodes += sub->num_nodes - 1u;
            s->leaves += sub->leaves;
            s->empty_leaves += sub->empty_leaves;
            s->prim_refs += sub->num_refs;
        }
        if (c.max_depth > s->max_depth) s->max_depth = c.max_depth;
        s->unbuilt = c.unbuilt;
        s->unbuilt_prims = c.unbuilt_refs;
        const uint32_t built_full = s->leaves - s->empty_leaves;
        s->mean_leaf_prims = built_full ? (double)s->prim_refs / (double)built_full : 0.0;
        /* the subtrees built, the records and parts, the triangle copies and the unbuilt nodes' inputs */
        s->bytes += c.built_bytes + sizeof *L + (size_t)L->num_recs * (sizeof *L->recs + sizeof *L->parts) +
                    (size_t)a->mesh->num_triangles * sizeof *L->tris +
                    (size_t)s->unbuilt_prims * (a->variant == KD_VARIANT_SAH ? 6u * sizeof(kd_event) : sizeof(kd_ref));
    }
}

/* ==== lazy expansion (kdtree_internal.h, kd_lazy) ========================== */

/* Builds record rec's subtree into arrays of its own with the build's
 * recursion and parameters, node ids as kd_id with (rec->node, id_base).
 * The record's input is copied, so that a failure leaves it as it was.
 * NULL when memory runs out (nothing of the subtree is kept). */
static kd_tree *expand_once(const sidx_accel *a, const kd_tree *kd, const kd_lazy_rec *rec, const sidx_hook *hook,
                            uint32_t id_base)
{
    const kd_lazy *L = kd->lazy;
    kd_builder b;
    memset(&b, 0, sizeof b);
    b.a = a;
    b.hook = hook;
    b.name = a->name;
    b.tris = L->tris;
    b.variant = a->variant;
    b.c_trav = kd->c_trav;
    b.c_tri = kd->c_tri;
    b.lambda = 1.0f - kd->empty_bonus;
    b.leaf_size = L->leaf_size;
    b.max_depth = L->max_depth;
    b.bins = L->bins;
    const float ra = sidx_aabb_area(kd->bounds);
    b.inv_root_area = ra > 0.0f ? 1.0f / ra : 0.0f;
    b.expanding = 1;
    b.root_id = rec->node;
    b.id_base = id_base;
    const int sah = a->variant == KD_VARIANT_SAH;
    const size_t in_size = sah ? (rec->cnt[0] + rec->cnt[1] + rec->cnt[2]) * sizeof(kd_event)
                               : (size_t)rec->count * sizeof(kd_ref);
    kd_tree *sub = sidx__calloc(a, 1, sizeof *sub);
    void *input = sidx__alloc(a, in_size ? in_size : 1u, 1);
    if (sah) b.cls = sidx__alloc(a, a->mesh->num_triangles, 1);
    uint32_t child;
    sidx_status s = !sub || !input || (sah && !b.cls) ? SIDX_ERR_NOMEM : alloc_pair(&b, &child);
    if (s == SIDX_OK) {
        memcpy(input, rec->input, in_size);
        b.num_nodes = 1;
        if (sah) s = sah_node(&b, 0, rec->parent, rec->depth, rec->cell, input, rec->cnt, rec->count, rec->bad);
        else s = refs_node(&b, 0, rec->parent, rec->depth, rec->cell, input, rec->count, rec->bad);
        input = NULL; /* the recursion owns it */
    }
    sidx__free(a, input);
    sidx__free(a, b.cls);
    if (!sub) {
        sidx__free(a, b.nodes);
        sidx__free(a, b.prims);
        return NULL;
    }
    sub->nodes = sub->nodes_mem = b.nodes;
    sub->prims = b.prims;
    if (s == SIDX_OK) {
        sub->num_nodes = b.num_nodes;
        sub->num_refs = b.num_refs;
        align_nodes(a, sub);
        sub->prims = shrink(a, sub->prims, sub->num_refs, sizeof *sub->prims, b.prims_cap);
        s = sidx__kd_make_blocks(a, sub, a->mesh);
    }
    if (s != SIDX_OK) {
        kd_free(a, sub);
        return NULL;
    }
    sub->bounds = rec->cell;
    sub->leaves = b.leaves;
    sub->empty_leaves = b.empty_leaves;
    sub->max_depth = b.depth;
    sub->c_trav = kd->c_trav;
    sub->c_tri = kd->c_tri;
    sub->empty_bonus = kd->empty_bonus;
    sub->root_id = rec->node;
    sub->id_base = id_base;
    return sub;
}

/* The expand function of the tree's parts (lazy.h): part r is the subtree
 * of record r, its event ids taken once its size is known; for a query
 * with a build hook the same build once more with those ids, for the
 * events (kd_lazy).  lazy.c calls it on the one thread that claimed the
 * part and publishes what it returns; NULL (out of memory) keeps nothing
 * and leaves the record's input as it was, for a later try. */
static void *kd_expand(void *owner, uint32_t r, const sidx_hook *hook, sidx__lazy_made *made)
{
    const sidx_accel *a = owner;
    kd_tree *kd = a->impl;
    kd_lazy *L = kd->lazy;
    kd_lazy_rec *rec = &L->recs[r];
    kd_tree *sub = expand_once(a, kd, rec, NULL, 0);
    if (!sub) return NULL;
    const uint32_t id_base = __atomic_fetch_add(&L->next_id, sub->num_nodes - 1u, __ATOMIC_RELAXED);
    sub->id_base = id_base;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_LAZY_EXPAND, e_.structure = a->name; e_.node = rec->node;
              e_.parent = rec->parent; e_.depth = rec->depth; e_.count = rec->count; e_.bounds = rec->cell);
    if (hook && hook->fn && (hook->mask == 0 || (hook->mask & (SIDX_EVMASK_BUILD & ~SIDX_EVMASK(SIDX_EV_BUILD_LAZY_EXPAND)))))
        kd_free(a, expand_once(a, kd, rec, hook, id_base)); /* events only; without memory they stop short */
    sidx__free(a, rec->input); /* built: no later expansion reads it */
    rec->input = NULL;
    made->refs = rec->count;
    made->bytes = sizeof *sub + (size_t)sub->num_nodes * sizeof(kd_node) + (size_t)sub->num_refs * sizeof(uint32_t) +
                  (size_t)sub->num_blocks * sizeof(tri4_block);
    made->depth = sub->max_depth;
    return sub;
}

/* ==== the read-only view (sidx/kdtree.h) =================================== */

/* Every registry name of the family shares the one vtable (kdtree_traverse.c,
 * declared through accel_registry.def), so the vtable identifies a kd-tree
 * whatever builder made it. */

static sidx_status kd_view(const sidx_accel *a, const void *p, const void *q, sidx_error *err, const char *fn,
                           const kd_tree **out)
{
    if (!a || !p || !q) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", fn);
    if (a->vt != &sidx__kdtree_vtable || !a->impl)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: '%s' is not a kd-tree", fn, a->name ? a->name : "?");
    if (((const kd_tree *)a->impl)->lazy)
        return sidx__fail(err, SIDX_ERR_UNSUPPORTED, "%s: a lazy tree is built as rays arrive; build it with lazy = 0",
                          fn);
    *out = a->impl;
    return SIDX_OK;
}

sidx_status sidx_kdtree_nodes(const sidx_accel *a, const sidx_kd_node **nodes, uint32_t *count, sidx_error *err)
{
    const kd_tree *kd = NULL;
    const sidx_status s = kd_view(a, nodes, count, err, "sidx_kdtree_nodes", &kd);
    if (s != SIDX_OK) return s;
    *nodes = kd->nodes;
    *count = kd->num_nodes;
    return SIDX_OK;
}

sidx_status sidx_kdtree_refs(const sidx_accel *a, const uint32_t **refs, uint32_t *count, sidx_error *err)
{
    const kd_tree *kd = NULL;
    const sidx_status s = kd_view(a, refs, count, err, "sidx_kdtree_refs", &kd);
    if (s != SIDX_OK) return s;
    *refs = kd->prims;
    *count = kd->num_refs;
    return SIDX_OK;
}
