/* bvh_build.c — building a bounding volume hierarchy, five ways.
 *
 * One recursive top-down builder; what differs is how a node's primitives
 * are split in two (slides "BVH Partitioning" / "Building Partitions"):
 *
 *   bvh-median  equal counts: the median centroid on the axis of largest
 *               centroid extent ("Split at the Median: makes the L & R
 *               costs equal, pays no attention to the L & R
 *               probabilities"), found by quickselect, O(n) per node;
 *   bvh-middle  the middle of the centroid extent on that axis ("Split in
 *               the middle: makes the L & R probabilities equal, pays no
 *               attention to the L & R costs"); if every centroid falls on
 *               one side, the median instead;
 *   bvh-sweep   the surface area heuristic evaluated at EVERY position of
 *               the centroid order on all three axes (the deck's first
 *               "Building Partitions" loop), with prefix/suffix boxes so
 *               one axis costs a sort plus O(n), not O(n²);
 *   bvh-everyb  the same sweep evaluated only at every B-th position (the
 *               deck's "check every B primitives (B = 32)");
 *   bvh         binned SAH (Wald 2007, "On fast construction of SAH-based
 *               bounding volume hierarchies"): 32 bins over the centroid
 *               bounds, O(n) per node, no sorting (the deck's last loop);
 *   bvh-obb     the binned topology, then one oriented box per node
 *               (bvh_obb.c).
 *
 * The SAH (slides "Surface Area Heuristic"):
 *     C = C_trav + A_L/A · N_L · C_tri + A_R/A · N_R · C_tri
 * against the cost of not splitting, N · C_tri.
 *
 * Termination, in this order:
 *   count <= leaf_size (default 3: the deck's "< 4")     -> FEW_PRIMS
 *   depth == max_depth (default and cap 64)              -> MAX_DEPTH
 *   all centroids equal (zero-extent centroid bounds): no plane separates
 *     them, and the deck's "pick a random partition" is made deterministic:
 *     count > BVH_MAX_LEAF: split the index range in half in its current
 *     order; otherwise                                    -> NO_SPLIT
 *   SAH builders: best split not cheaper than the leaf and
 *     count <= BVH_MAX_LEAF (above it the split is forced) -> NO_GAIN
 * Every split leaves both sides non-empty and the depth is bounded, so the
 * recursion always ends (at most 65 frames).
 *
 * Nodes are written in depth-first pre-order straight into their final
 * slots, so the id in every BUILD_* event is the node's index in the final
 * array and its left child is always id + 1. */
#include "bvh_internal.h"

/* Events carry the registered name ("bvh-sweep", ...). */
#define SIDX_STRUCTURE_NAME (B->a->name)

typedef struct sweep_key {
    float key;   /* centroid coordinate on the current axis */
    uint32_t id; /* original triangle index: breaks ties, so every order is deterministic */
} sweep_key;

typedef struct bvh_split {
    int axis;      /* -1: equal-centroid split in index order */
    uint32_t nl;   /* primitives on the left; idx[first, first+nl) after partitioning */
    float pos;     /* plane position (for events) */
    float cost;    /* SAH cost of the split */
} bvh_split;

typedef struct builder {
    const sidx_accel *a;
    const sidx_hook *hook;
    bvh_builder kind;
    const sidx_aabb *pbox;   /* per-triangle bounds */
    const sidx_vec3 *cent;   /* per-triangle centroids (of the bounds) */
    uint32_t *idx;           /* triangle indices, partitioned in place */
    bvh_node *nodes;
    uint32_t num_nodes, num_leaves, max_depth_seen;
    uint32_t leaf_size, max_leaf, max_depth, bins, every_b;
    float c_trav, c_tri;
    sweep_key *keys[2];      /* sweep / median scratch, n each */
    float *right_area;       /* sweep: suffix areas, n; binned: per bin */
    sidx_aabb *bin_box;      /* binned: per bin */
    uint32_t *bin_count;
    /* lazy trees: nodes of at most lazy_max primitives (and more than a
     * leaf's) are left unbuilt, one record each in lazy->recs (up to
     * lazy_cap); 0 = build everything.  An expansion builds node
     * expand_root's subtree, writing that node itself into *root_out (its
     * part, bvh_internal.h) and skipping its BUILD_NODE event (sent with
     * the build); UINT32_MAX otherwise */
    uint32_t lazy_max, lazy_cap, expand_root;
    bvh_lazy *lazy;
    bvh_node *root_out;
} builder;

static SIDX_INLINE bvh_node *node_at(builder *B, uint32_t ni)
{
    return ni == B->expand_root ? B->root_out : &B->nodes[ni];
}

static inline float sah(const builder *B, float al, uint32_t nl, float ar, uint32_t nr, float inv_area)
{
    return B->c_trav + B->c_tri * (al * (float)nl + ar * (float)nr) * inv_area;
}

/* Cost of an already partitioned range, for the splits that do not search
 * by the SAH (median, middle, equal centroids): shown in their events so
 * the lessons can compare them with the SAH builders. */
static float range_cost(const builder *B, uint32_t first, uint32_t nl, uint32_t count, float inv_area)
{
    sidx_aabb l = sidx_aabb_empty(), r = sidx_aabb_empty();
    for (uint32_t i = 0; i < nl; ++i) l = sidx_aabb_union(l, B->pbox[B->idx[first + i]]);
    for (uint32_t i = nl; i < count; ++i) r = sidx_aabb_union(r, B->pbox[B->idx[first + i]]);
    return sah(B, sidx_aabb_area(l), nl, sidx_aabb_area(r), count - nl, inv_area);
}

/* ---- binned SAH (Wald 2007) ------------------------------------------ */

/* bin_of (bvh_internal.h) maps a centroid to its bin. */

/* Up to this many bins per axis, the three axes are binned in one pass
 * over the node's triangles (their boxes and centroids gathered once, not
 * three times: the pass is memory bound on large nodes, the top of a lazy
 * tree above all); more bins, one pass per axis.  The bins, and so every
 * decision and event, are the same either way (unions and counts). */
#define BIN_ONE_PASS_MAX 64u

/* bin_three_axes: the bins of all three axes in one pass over the node's
 * triangles (nb <= BIN_ONE_PASS_MAX).  With SSE2 (every x86-64) the three
 * bin coordinates in one set of 4-lane instructions, else the reference;
 * the same bins either way. */
#if defined(__SSE2__)
#include "simd_bin3_sse.h"
#else
#include "simd_bin3_scalar.h"
#endif

static SIDX_NOINLINE int find_binned(builder *B, uint32_t node, uint32_t first, uint32_t count, sidx_aabb cb,
                                     float inv_area, bvh_split *best)
{
    const uint32_t nb = B->bins;
    int found = 0;
    uint32_t best_plane = 0;
    best->cost = INFINITY;
    sidx_aabb box3[3][BIN_ONE_PASS_MAX];
    uint32_t cnt3[3][BIN_ONE_PASS_MAX];
    const int one_pass = nb <= BIN_ONE_PASS_MAX;
    if (one_pass) bin_three_axes(B, first, count, cb, box3, cnt3);
    for (int axis = 0; axis < 3; ++axis) {
        const float cmin = sidx_v3_get(cb.min, axis), ext = sidx_v3_get(cb.max, axis) - cmin;
        if (!(ext > 0.0f)) continue; /* a flat axis has no plane between centroids */
        const sidx_aabb *bin_box = box3[axis];
        const uint32_t *bin_count = cnt3[axis];
        if (!one_pass) {
            const float scale = (float)nb / ext;
            for (uint32_t k = 0; k < nb; ++k) {
                B->bin_box[k] = sidx_aabb_empty();
                B->bin_count[k] = 0;
            }
            for (uint32_t i = 0; i < count; ++i) {
                const uint32_t id = B->idx[first + i];
                const uint32_t k = bin_of(sidx_v3_get(B->cent[id], axis), cmin, scale, nb);
                B->bin_count[k]++;
                B->bin_box[k] = sidx_aabb_union(B->bin_box[k], B->pbox[id]);
            }
            bin_box = B->bin_box;
            bin_count = B->bin_count;
        }
        /* Suffix areas right to left, then one left-to-right pass over the
         * nb − 1 planes between bins: "add bins to partitions instead of
         * triangles". */
        sidx_aabb acc = sidx_aabb_empty();
        for (uint32_t p = nb - 1; p >= 1; --p) {
            acc = sidx_aabb_union(acc, bin_box[p]);
            B->right_area[p] = sidx_aabb_area(acc);
        }
        acc = sidx_aabb_empty();
        uint32_t nl = 0;
        for (uint32_t p = 1; p < nb; ++p) {
            acc = sidx_aabb_union(acc, bin_box[p - 1]);
            nl += bin_count[p - 1];
            if (nl == 0 || nl == count) continue; /* one side empty: not a split */
            const float cost = sah(B, sidx_aabb_area(acc), nl, B->right_area[p], count - nl, inv_area);
            const float pos = cmin + ext * (float)p / (float)nb;
            SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_CANDIDATE, e_.node = node; e_.axis = axis; e_.pos = pos;
                      e_.cost = cost; e_.count = nl; e_.aux = count - nl);
            if (cost < best->cost) {
                best->cost = cost;
                best->axis = axis;
                best->nl = nl;
                best->pos = pos;
                best_plane = p;
                found = 1;
            }
        }
    }
    if (!found) return 0;
    /* Partition in place: bins below the plane go left. */
    const int axis = best->axis;
    const float cmin = sidx_v3_get(cb.min, axis), scale = (float)nb / (sidx_v3_get(cb.max, axis) - cmin);
    uint32_t i = first, j = first + count;
    while (i < j) {
        const uint32_t id = B->idx[i];
        if (bin_of(sidx_v3_get(B->cent[id], axis), cmin, scale, nb) < best_plane) {
            ++i;
        } else {
            B->idx[i] = B->idx[--j];
            B->idx[j] = id;
        }
    }
    best->nl = i - first; /* equals the binned count: same bin_of */
    return 1;
}

/* ---- SAH sweep over sorted centroids ---------------------------------- */

static int key_cmp(const void *pa, const void *pb)
{
    const sweep_key *x = pa, *y = pb;
    if (x->key < y->key) return -1;
    if (x->key > y->key) return 1;
    return (x->id > y->id) - (x->id < y->id);
}

/* step = 1: the full sweep; step = B: the deck's every-B sweep.  The step
 * is never coarser than half the node, so a small node still gets a
 * candidate (at the median) instead of none. */
static SIDX_NOINLINE int find_sweep(builder *B, uint32_t node, uint32_t first, uint32_t count, sidx_aabb cb,
                                    float inv_area, uint32_t step, bvh_split *best)
{
    sweep_key *cur = B->keys[0], *bestk = B->keys[1];
    if (step > count / 2) step = count / 2;
    if (step < 1) step = 1;
    int found = 0;
    best->cost = INFINITY;
    for (int axis = 0; axis < 3; ++axis) {
        if (!(sidx_v3_get(cb.max, axis) > sidx_v3_get(cb.min, axis))) continue;
        for (uint32_t i = 0; i < count; ++i) {
            const uint32_t id = B->idx[first + i];
            cur[i].key = sidx_v3_get(B->cent[id], axis);
            cur[i].id = id;
        }
        qsort(cur, count, sizeof *cur, key_cmp);
        /* right_area[i] = area of the boxes of cur[i .. count): the suffix
         * pass that turns the deck's bbox(primitives[i,n]) into O(1). */
        sidx_aabb acc = sidx_aabb_empty();
        for (uint32_t i = count - 1; i >= 1; --i) {
            acc = sidx_aabb_union(acc, B->pbox[cur[i].id]);
            B->right_area[i] = sidx_aabb_area(acc);
        }
        acc = sidx_aabb_empty();
        int improved = 0;
        for (uint32_t i = 1; i < count; ++i) {
            acc = sidx_aabb_union(acc, B->pbox[cur[i - 1].id]);
            if (i % step) continue;
            const float cost = sah(B, sidx_aabb_area(acc), i, B->right_area[i], count - i, inv_area);
            const float pos = 0.5f * (cur[i - 1].key + cur[i].key);
            SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_CANDIDATE, e_.node = node; e_.axis = axis; e_.pos = pos;
                      e_.cost = cost; e_.count = i; e_.aux = count - i);
            if (cost < best->cost) {
                best->cost = cost;
                best->axis = axis;
                best->nl = i;
                best->pos = pos;
                improved = 1;
                found = 1;
            }
        }
        if (improved) { /* keep this axis's order: it is the one to partition by */
            sweep_key *t = cur;
            cur = bestk;
            bestk = t;
        }
    }
    if (!found) return 0;
    for (uint32_t i = 0; i < count; ++i) B->idx[first + i] = bestk[i].id;
    return 1;
}

/* ---- median (quickselect) and middle ---------------------------------- */

static inline int key_less(sweep_key x, sweep_key y) { return x.key < y.key || (x.key == y.key && x.id < y.id); }

/* nth_element: afterwards k[nth] is the element a full sort would put
 * there, everything before it is smaller and everything after larger.
 * Hoare partitioning around a median of three; expected O(n). */
static void select_nth(sweep_key *k, int64_t n, int64_t nth)
{
    int64_t lo = 0, hi = n - 1;
    while (hi > lo) {
        const int64_t mid = lo + (hi - lo) / 2;
        sweep_key t;
        if (key_less(k[mid], k[lo])) { t = k[mid]; k[mid] = k[lo]; k[lo] = t; }
        if (key_less(k[hi], k[lo])) { t = k[hi]; k[hi] = k[lo]; k[lo] = t; }
        if (key_less(k[hi], k[mid])) { t = k[hi]; k[hi] = k[mid]; k[mid] = t; }
        const sweep_key pivot = k[mid];
        int64_t i = lo, j = hi;
        while (i <= j) {
            while (key_less(k[i], pivot)) ++i;
            while (key_less(pivot, k[j])) --j;
            if (i <= j) {
                t = k[i]; k[i] = k[j]; k[j] = t;
                ++i;
                --j;
            }
        }
        if (nth <= j) hi = j;
        else if (nth >= i) lo = i;
        else return; /* j < nth < i: k[nth] equals the pivot and is in place */
    }
}

static SIDX_NOINLINE void split_median(builder *B, uint32_t node, uint32_t first, uint32_t count, sidx_aabb cb,
                                       float inv_area, bvh_split *sp)
{
    const int axis = sidx_aabb_max_axis(cb);
    sweep_key *k = B->keys[0];
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t id = B->idx[first + i];
        k[i].key = sidx_v3_get(B->cent[id], axis);
        k[i].id = id;
    }
    const uint32_t mid = count / 2;
    select_nth(k, count, mid);
    for (uint32_t i = 0; i < count; ++i) B->idx[first + i] = k[i].id;
    sp->axis = axis;
    sp->nl = mid;
    sp->pos = k[mid].key;
    sp->cost = range_cost(B, first, mid, count, inv_area);
    SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_CANDIDATE, e_.node = node; e_.axis = axis; e_.pos = sp->pos;
              e_.cost = sp->cost; e_.count = mid; e_.aux = count - mid);
}

static SIDX_NOINLINE void split_middle(builder *B, uint32_t node, uint32_t first, uint32_t count, sidx_aabb cb,
                                       float inv_area, bvh_split *sp)
{
    const int axis = sidx_aabb_max_axis(cb);
    const float pos = 0.5f * (sidx_v3_get(cb.min, axis) + sidx_v3_get(cb.max, axis));
    uint32_t i = first, j = first + count;
    while (i < j) {
        const uint32_t id = B->idx[i];
        if (sidx_v3_get(B->cent[id], axis) < pos) {
            ++i;
        } else {
            B->idx[i] = B->idx[--j];
            B->idx[j] = id;
        }
    }
    const uint32_t nl = i - first;
    if (nl == 0 || nl == count) {
        /* Rounding put every centroid on one side (a tiny extent): fall
         * back to the median so the node still splits. */
        SIDX_EMIT(1, B->hook, SIDX_EV_NOTE, e_.node = node;
                  e_.text = "bvh-middle: one side empty, falling back to the median");
        split_median(B, node, first, count, cb, inv_area, sp);
        return;
    }
    sp->axis = axis;
    sp->nl = nl;
    sp->pos = pos;
    sp->cost = range_cost(B, first, nl, count, inv_area);
    SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_CANDIDATE, e_.node = node; e_.axis = axis; e_.pos = pos;
              e_.cost = sp->cost; e_.count = nl; e_.aux = count - nl);
}

/* ---- the recursion ------------------------------------------------------ */

static uint32_t build_node(builder *B, uint32_t first, uint32_t count, uint32_t parent, uint32_t depth)
{
    const uint32_t ni = B->num_nodes++;
    sidx_aabb bb = sidx_aabb_empty(), cb = sidx_aabb_empty();
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t id = B->idx[first + i];
        bb = sidx_aabb_union(bb, B->pbox[id]);
        cb = sidx_aabb_grow(cb, B->cent[id]);
    }
    {
        bvh_node *n = node_at(B, ni);
        n->bmin[0] = bb.min.x; n->bmin[1] = bb.min.y; n->bmin[2] = bb.min.z;
        n->bmax[0] = bb.max.x; n->bmax[1] = bb.max.y; n->bmax[2] = bb.max.z;
    }
    if (depth > B->max_depth_seen) B->max_depth_seen = depth;
    if (ni != B->expand_root)
        SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_NODE, e_.node = ni; e_.parent = parent; e_.depth = depth;
                  e_.bounds = bb; e_.count = count);
    if (B->lazy_max && count <= B->lazy_max && count > B->leaf_size && B->lazy->num_recs < B->lazy_cap) {
        /* Lazy: the node waits for a ray, holding idx[first, first + count)
         * in the order this build has them now, and the slots its subtree
         * may need (bvh_internal.h, bvh_lazy); lazy.c counts it when
         * the build is done (sidx__lazy_defer). */
        const uint32_t r = B->lazy->num_recs++;
        bvh_lazy_rec *rec = &B->lazy->recs[r];
        rec->node = ni;
        rec->parent = parent;
        rec->depth = depth;
        rec->first = first;
        rec->count = count;
        B->nodes[ni].left_or_first = first;
        B->nodes[ni].count_axis = BVH_LAZY_MARK | r;
        B->num_nodes += 2u * count - 2u;
        return ni;
    }

    const float area = sidx_aabb_area(bb);
    /* A zero-area node (all triangles degenerate and coincident) makes
     * every split cost C_trav: it splits while it can, which ends. */
    const float inv_area = area > 0.0f ? 1.0f / area : 0.0f;
    const float leaf_cost = (float)count * B->c_tri;
    int reason = SIDX_LEAF_NONE;
    bvh_split sp = {-1, 0, NAN, INFINITY};

    if (count <= B->leaf_size) {
        reason = SIDX_LEAF_FEW_PRIMS;
    } else if (depth >= B->max_depth) {
        reason = SIDX_LEAF_MAX_DEPTH;
    } else if (!(cb.max.x > cb.min.x) && !(cb.max.y > cb.min.y) && !(cb.max.z > cb.min.z)) {
        /* Slides "Edge Cases: primitives with same centroid": no plane
         * separates them; the deck picks a random partition, we halve the
         * index range in its current order, deterministically. */
        if (count > B->max_leaf) {
            sp.axis = -1;
            sp.nl = count / 2;
            sp.cost = range_cost(B, first, sp.nl, count, inv_area);
        } else {
            reason = SIDX_LEAF_NO_SPLIT;
        }
    } else {
        int ok = 1;
        switch (B->kind) {
        case BVH_SWEEP: ok = find_sweep(B, ni, first, count, cb, inv_area, 1, &sp); break;
        case BVH_EVERYB: ok = find_sweep(B, ni, first, count, cb, inv_area, B->every_b, &sp); break;
        case BVH_MEDIAN: split_median(B, ni, first, count, cb, inv_area, &sp); break;
        case BVH_MIDDLE: split_middle(B, ni, first, count, cb, inv_area, &sp); break;
        default: ok = find_binned(B, ni, first, count, cb, inv_area, &sp); break;
        }
        /* Binning can find no plane when rounding puts every centroid in
         * one bin (tiny extents far from the origin): split at the median. */
        if (!ok) split_median(B, ni, first, count, cb, inv_area, &sp);
        const int sah_builder = B->kind != BVH_MEDIAN && B->kind != BVH_MIDDLE;
        if (sah_builder && !(sp.cost < leaf_cost) && count <= B->max_leaf) reason = SIDX_LEAF_NO_GAIN;
    }

    if (reason != SIDX_LEAF_NONE) {
        node_at(B, ni)->left_or_first = first;
        node_at(B, ni)->count_axis = count;
        B->num_leaves++;
        SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_LEAF, e_.node = ni; e_.depth = depth; e_.count = count;
                  e_.cost = leaf_cost; e_.reason = reason; e_.bounds = bb; e_.prims = B->idx + first);
        return ni;
    }
    SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_SPLIT, e_.node = ni; e_.depth = depth; e_.axis = sp.axis; e_.pos = sp.pos;
              e_.cost = sp.cost; e_.count = sp.nl; e_.aux = count - sp.nl);
    build_node(B, first, sp.nl, ni, depth + 1); /* lands at ni + 1 */
    const uint32_t right = build_node(B, first + sp.nl, count - sp.nl, ni, depth + 1);
    node_at(B, ni)->left_or_first = right;
    node_at(B, ni)->count_axis = (uint32_t)(sp.axis < 0 ? 0 : sp.axis) << BVH_AXIS_SHIFT;
    return ni;
}

static void fill_tris(const sidx_mesh *m, bvh *b)
{
    for (uint32_t i = 0; i < b->num_prims; ++i)
        for (int k = 0; k < 3; ++k) b->tris[i].v[k] = sidx_mesh_vertex(m, b->prim_id[i], k);
}

static void bvh_free(const sidx_accel *a, bvh *b)
{
    if (!b) return;
    if (b->lazy) {
        for (uint32_t r = 0; r < b->lazy->num_recs; ++r) sidx__free(a, sidx__lazy_peek(&b->lazy->life, r));
        sidx__free(a, b->lazy->life.parts);
        sidx__free(a, b->lazy->recs);
        sidx__free(a, b->lazy->pbox);
        sidx__free(a, b->lazy->cent);
        sidx__free(a, b->lazy);
    }
    sidx__free(a, b->nodes_mem);
    sidx__free(a, b->prim_id);
    sidx__free(a, b->tris);
    sidx__free(a, b->obbs);
    sidx__free(a, b);
}

static void *expand_part(void *owner, uint32_t r, const sidx_hook *hook, sidx__lazy_made *made);

static sidx_status build_tree(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    const uint32_t n = m->num_triangles;
    builder Bs;
    builder *B = &Bs;
    memset(B, 0, sizeof *B);
    B->a = a;
    B->hook = a->opt.hook;
    B->kind = (a->variant >= 0 && a->variant < BVH_BUILDER_COUNT) ? (bvh_builder)a->variant : BVH_BINNED;
    const bvh_par_params pp = bvh_params(a);
    B->leaf_size = pp.leaf_size;
    B->max_leaf = pp.max_leaf;
    B->max_depth = pp.max_depth;
    B->bins = pp.bins;
    B->every_b = a->opt.every_b ? a->opt.every_b : 32u;
    B->c_trav = pp.c_trav;
    B->c_tri = pp.c_tri;

    if (n > BVH_COUNT_MASK)
        return sidx__fail(err, SIDX_ERR_LIMIT, "%s: %u triangles exceed the BVH's limit of %u", a->name, n,
                          BVH_COUNT_MASK);
    B->expand_root = UINT32_MAX;
    const uint32_t lazy_max = a->opt.lazy == 1 ? SIDX_LAZY_DEFAULT : a->opt.lazy;
    const int lazy = lazy_max > 0 && B->kind != BVH_OBB && !(a->opt.optimize_ms > 0.0f) && n > 0;
    if (B->kind == BVH_BINNED && !(B->hook && B->hook->fn) && n > 0 && !lazy) {
        /* Untraced "bvh" builds, on one thread or several, go through
         * parallel.c: the same decisions on packed references that stream
         * (Wald 2007), faster on one thread than this recursion over idx[]
         * (docs/performance.md, Binary BVH).  A build hook keeps
         * this builder, the one whose events the lessons print. */
        return sidx__bvh_build_parallel(a, &pp, err);
    }
    SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_BEGIN, e_.count = n; e_.bounds = sidx_mesh_bounds(m));

    sidx_status s = SIDX_ERR_NOMEM;
    sidx_aabb *pbox = NULL;
    sidx_vec3 *cent = NULL;
    bvh *b = sidx__calloc(a, 1, sizeof *b);
    if (!b) goto fail;
    b->num_prims = n;
    if (n == 0) goto done; /* an empty tree: every ray misses */

    if (sidx__prim_boxes(a, &pbox, &cent) != SIDX_OK) goto fail;
    B->pbox = pbox;
    B->cent = cent;
    /* a lazy tree's prim_id[n] and tris[n]: void_leaf's triangle (bvh_lazy) */
    b->prim_id = B->idx = sidx__alloc(a, lazy ? n + 1u : n, sizeof *B->idx);
    if (lazy) {
        /* Every slot a subtree may take, in the final aligned array: the
         * expansions build in place (bvh_lazy). */
        b->nodes_mem = sidx__alloc(a, 2u * (size_t)n + 1u, sizeof *b->nodes);
        b->lazy = sidx__calloc(a, 1, sizeof *b->lazy);
        B->lazy_cap = n / (B->leaf_size + 1u) + 1u;
        if (B->lazy_cap > BVH_LAZY_MAX_RECS) B->lazy_cap = BVH_LAZY_MAX_RECS;
        if (!b->nodes_mem || !b->lazy) goto fail;
        b->lazy->recs = sidx__alloc(a, B->lazy_cap, sizeof *b->lazy->recs);
        b->lazy->life.parts = sidx__calloc(a, B->lazy_cap, sizeof *b->lazy->life.parts);
        if (!b->lazy->recs || !b->lazy->life.parts) goto fail;
        b->nodes = (bvh_node *)(void *)(((uintptr_t)b->nodes_mem + 63u) & ~(uintptr_t)63u);
        B->nodes = b->nodes;
        B->lazy = b->lazy;
        B->lazy_max = lazy_max;
    } else {
        B->nodes = sidx__alloc(a, 2u * (size_t)n - 1u, sizeof *B->nodes); /* a binary tree over n leaves or fewer */
    }
    if (!B->idx || !B->nodes) goto fail;
    for (uint32_t i = 0; i < n; ++i) B->idx[i] = i;
    if (B->kind == BVH_SWEEP || B->kind == BVH_EVERYB || B->kind == BVH_MEDIAN || B->kind == BVH_MIDDLE) {
        B->keys[0] = sidx__alloc(a, n, sizeof(sweep_key));
        B->keys[1] = sidx__alloc(a, n, sizeof(sweep_key));
        B->right_area = sidx__alloc(a, n, sizeof(float));
        if (!B->keys[0] || !B->keys[1] || !B->right_area) goto fail;
    } else {
        /* The binned builder falls back to the median split when binning
         * finds no plane (all centroids in one bin after rounding, found by
         * fuzzing), and the median needs its key array. */
        B->keys[0] = sidx__alloc(a, n, sizeof(sweep_key));
        if (!B->keys[0]) goto fail;
        B->bin_box = sidx__alloc(a, B->bins, sizeof *B->bin_box);
        B->bin_count = sidx__alloc(a, B->bins, sizeof *B->bin_count);
        B->right_area = sidx__alloc(a, B->bins, sizeof(float));
        if (!B->bin_box || !B->bin_count || !B->right_area) goto fail;
    }

    build_node(B, 0, n, UINT32_MAX, 0);

    if (lazy) {
        bvh_lazy *L = b->lazy;
        b->tris = sidx__alloc(a, n + 1u, sizeof *b->tris);
        if (!b->tris) goto fail;
        b->num_nodes = B->num_nodes; /* the slots in use or reserved */
        b->num_leaves = B->num_leaves;
        b->max_depth = B->max_depth_seen;
        /* every node made so far is built, the unbuilt ones included (each
         * stays one node, its part's root, once built) */
        L->top_nodes = B->num_nodes;
        for (uint32_t r = 0; r < L->num_recs; ++r) L->top_nodes -= 2u * L->recs[r].count - 2u;
        L->top_leaves = B->num_leaves;
        L->pbox = pbox;
        L->cent = cent;
        pbox = NULL;
        cent = NULL;
        /* The triangle copies of the leaves built here only: an expansion
         * writes its own range's after reordering it (expand_build), so
         * copying the unbuilt ranges now would be done twice, and would
         * touch every page of tris[] before a ray needs it.  The records
         * are in pre-order, so their ranges come in increasing order. */
        for (uint32_t r = 0, i = 0; r <= L->num_recs; ++r) {
            const uint32_t end = r < L->num_recs ? L->recs[r].first : n;
            for (; i < end; ++i)
                for (int k = 0; k < 3; ++k) b->tris[i].v[k] = sidx_mesh_vertex(m, b->prim_id[i], k);
            if (r < L->num_recs) i = end + L->recs[r].count;
        }
        memset(&b->tris[n], 0, sizeof b->tris[n]);
        b->prim_id[n] = SIDX_NO_HIT;
        L->void_leaf = (bvh_node){{INFINITY, INFINITY, INFINITY}, n, {-INFINITY, -INFINITY, -INFINITY}, 1u};
        sidx__lazy_init(&L->life, L->life.parts, L->num_recs, expand_part, a);
        for (uint32_t r = 0; r < L->num_recs; ++r) sidx__lazy_defer(&L->life, r, L->recs[r].count);
        B->nodes = NULL; /* b's own */
        a->lazy = 1;
        goto done;
    }

    /* Keep only the nodes used (typically ~n/2 of the 2n − 1 reserved),
     * 64-byte aligned: malloc's 16-byte alignment would let every other
     * 32-byte node straddle two cache lines, two misses for one box. */
    b->nodes_mem = sidx__alloc(a, (size_t)B->num_nodes + 2u, sizeof *b->nodes);
    b->tris = sidx__alloc(a, n, sizeof *b->tris);
    if (!b->nodes_mem || !b->tris) goto fail;
    b->nodes = (bvh_node *)(void *)(((uintptr_t)b->nodes_mem + 63u) & ~(uintptr_t)63u);
    memcpy(b->nodes, B->nodes, (size_t)B->num_nodes * sizeof *b->nodes);
    b->num_nodes = B->num_nodes;
    b->num_leaves = B->num_leaves;
    b->max_depth = B->max_depth_seen;
    fill_tris(m, b);
    b->sah_cost = sidx__bvh_tree_sah(b, B->c_trav, B->c_tri);
    if (B->kind == BVH_OBB && (s = sidx__bvh_fit_obbs(a, b)) != SIDX_OK) goto fail;

done:
    sidx__free(a, B->nodes);
    sidx__free(a, B->keys[0]);
    sidx__free(a, B->keys[1]);
    sidx__free(a, B->right_area);
    sidx__free(a, B->bin_box);
    sidx__free(a, B->bin_count);
    sidx__free(a, pbox);
    sidx__free(a, cent);
    a->impl = b;
    a->fills_uv = a->fills_ng = 1; /* from the leaves' triangle copies (bvh_traverse.c) */
    SIDX_EMIT(1, B->hook, SIDX_EV_BUILD_END, e_.node = b->num_nodes; e_.count = n; e_.depth = b->max_depth);
    return SIDX_OK;

fail:
    if (!lazy) sidx__free(a, B->nodes); /* lazy: b's nodes_mem */
    sidx__free(a, B->keys[0]);
    sidx__free(a, B->keys[1]);
    sidx__free(a, B->right_area);
    sidx__free(a, B->bin_box);
    sidx__free(a, B->bin_count);
    sidx__free(a, pbox);
    sidx__free(a, cent);
    bvh_free(a, b);
    a->impl = NULL;
    if (s == SIDX_ERR_NOMEM) return sidx__fail(err, s, "%s: out of memory", a->name);
    return s;
}

/* ---- lazy expansion (bvh_internal.h, bvh_lazy) ------------------------------ */

/* lazy.c's expand function (lazy.h): builds part r — record r's subtree,
 * with the build's own recursion and parameters — and returns its root,
 * the rest of it in the slots and the run of prim_id / tris the unbuilt
 * node reserved.  NULL when memory runs out: every allocation comes first,
 * so nothing is written then.  Called once at a time per part (lazy.c
 * claims it). */
static void *expand_part(void *owner, uint32_t r, const sidx_hook *hook, sidx__lazy_made *made)
{
    const sidx_accel *a = owner;
    bvh *b = a->impl;
    const bvh_lazy_rec *rec = &b->lazy->recs[r];
    builder Bs;
    builder *B = &Bs;
    memset(B, 0, sizeof *B);
    B->a = a;
    B->hook = hook;
    B->kind = (a->variant >= 0 && a->variant < BVH_BUILDER_COUNT) ? (bvh_builder)a->variant : BVH_BINNED;
    const bvh_par_params pp = bvh_params(a);
    B->leaf_size = pp.leaf_size;
    B->max_leaf = pp.max_leaf;
    B->max_depth = pp.max_depth;
    B->bins = pp.bins;
    B->every_b = a->opt.every_b ? a->opt.every_b : 32u;
    B->c_trav = pp.c_trav;
    B->c_tri = pp.c_tri;
    B->pbox = b->lazy->pbox;
    B->cent = b->lazy->cent;
    B->idx = b->prim_id;
    B->nodes = b->nodes;
    B->expand_root = rec->node;
    B->num_nodes = rec->node;
    B->root_out = sidx__alloc(a, 1, sizeof *B->root_out);
    const uint32_t c = rec->count;
    int ok;
    if (B->kind == BVH_BINNED) {
        B->keys[0] = sidx__alloc(a, c, sizeof(sweep_key));
        B->bin_box = sidx__alloc(a, B->bins, sizeof *B->bin_box);
        B->bin_count = sidx__alloc(a, B->bins, sizeof *B->bin_count);
        B->right_area = sidx__alloc(a, B->bins, sizeof(float));
        ok = B->keys[0] && B->bin_box && B->bin_count && B->right_area;
    } else {
        B->keys[0] = sidx__alloc(a, c, sizeof(sweep_key));
        B->keys[1] = sidx__alloc(a, c, sizeof(sweep_key));
        B->right_area = sidx__alloc(a, c, sizeof(float));
        ok = B->keys[0] && B->keys[1] && B->right_area;
    }
    ok = ok && B->root_out;
    if (ok) {
        SIDX_EMIT(1, hook, SIDX_EV_BUILD_LAZY_EXPAND, e_.node = rec->node; e_.parent = rec->parent;
                  e_.depth = rec->depth; e_.count = c; e_.bounds = bvh_node_box(&b->nodes[rec->node]));
        build_node(B, rec->first, c, rec->parent, rec->depth); /* its root into *root_out */
    }
    sidx__free(a, B->keys[0]);
    sidx__free(a, B->keys[1]);
    sidx__free(a, B->right_area);
    sidx__free(a, B->bin_box);
    sidx__free(a, B->bin_count);
    if (!ok) {
        sidx__free(a, B->root_out);
        return NULL;
    }
    for (uint32_t i = rec->first; i < rec->first + c; ++i)
        for (int k = 0; k < 3; ++k) b->tris[i].v[k] = sidx_mesh_vertex(a->mesh, b->prim_id[i], k);
    __atomic_fetch_add(&b->lazy->part_leaves, B->num_leaves, __ATOMIC_RELAXED);
    made->refs = c;
    made->bytes = sizeof *B->root_out;
    made->depth = B->max_depth_seen;
    return B->root_out;
}

static void bvh_destroy(sidx_accel *a)
{
    bvh_free(a, a->impl);
    a->impl = NULL;
}

static void bvh_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const bvh *b = a->impl;
    if (!b) return;
    s->nodes = b->num_nodes;
    s->leaves = b->num_leaves;
    s->max_depth = b->max_depth;
    if (b->lazy) {
        /* a part of L leaves has 2·L − 1 nodes, its root the unbuilt node counted already */
        const bvh_lazy *L = b->lazy;
        const sidx__lazy_counts c = sidx__lazy_counts_get(&L->life);
        const uint32_t part_leaves = __atomic_load_n(&L->part_leaves, __ATOMIC_RELAXED);
        s->nodes = L->top_nodes + 2u * part_leaves - 2u * c.built;
        s->leaves = L->top_leaves + part_leaves;
        s->max_depth = c.max_depth > b->max_depth ? c.max_depth : b->max_depth;
        s->unbuilt = c.unbuilt;
        s->unbuilt_prims = c.unbuilt_refs;
    }
    /* lazy: the references of the built leaves, as the wide BVH and the
     * kd-tree count them; the rest are in unbuilt_prims */
    s->prim_refs = b->num_prims - s->unbuilt_prims;
    s->bytes = sizeof *b + ((size_t)b->num_nodes + 2u) * sizeof *b->nodes +
               (size_t)b->num_prims * (sizeof *b->prim_id + sizeof *b->tris) +
               (b->obbs ? (size_t)b->num_nodes * sizeof *b->obbs : 0);
    if (b->lazy) /* every slot reserved, the records and parts, the parts' roots, the boxes and centroids kept */
        s->bytes += sizeof *b->lazy + (size_t)b->lazy->num_recs * (sizeof *b->lazy->recs + sizeof *b->lazy->life.parts) +
                    sidx__lazy_counts_get(&b->lazy->life).built_bytes + sizeof *b->tris + sizeof *b->prim_id +
                    (size_t)b->num_prims * (sizeof *b->lazy->pbox + sizeof *b->lazy->cent);
    s->sah_cost = b->sah_cost; /* lazy: 0 (not applicable until every node is built) */
    s->mean_leaf_prims = s->leaves ? (double)(b->num_prims - s->unbuilt_prims) / s->leaves : 0.0;
    s->empty_leaves = 0; /* object partitioning: every leaf holds at least one triangle */
}

/* Refit: same topology, new boxes.  Children always follow their parent
 * in the array (pre-order), so one backward pass sees both children of a
 * node before the node itself: O(nodes), no recursion, no allocation. */
static sidx_status bvh_refit(sidx_accel *a, sidx_error *err)
{
    bvh *b = a->impl;
    if (b && b->lazy) return sidx__fail(err, SIDX_ERR_UNSUPPORTED, "%s: a lazy tree cannot be refitted; rebuild it", a->name);
    if (!b || b->num_nodes == 0) return SIDX_OK;
    fill_tris(a->mesh, b);
    for (uint32_t i = b->num_nodes; i-- > 0;) {
        bvh_node *n = &b->nodes[i];
        sidx_aabb bb = sidx_aabb_empty();
        if (bvh_is_leaf(n)) {
            const bvh_tri *t = b->tris + n->left_or_first;
            for (uint32_t j = 0; j < bvh_count(n); ++j)
                for (int k = 0; k < 3; ++k) bb = sidx_aabb_grow(bb, t[j].v[k]);
        } else {
            bb = sidx_aabb_union(bvh_node_box(&b->nodes[i + 1]), bvh_node_box(&b->nodes[n->left_or_first]));
        }
        n->bmin[0] = bb.min.x; n->bmin[1] = bb.min.y; n->bmin[2] = bb.min.z;
        n->bmax[0] = bb.max.x; n->bmax[1] = bb.max.y; n->bmax[2] = bb.max.z;
    }
    const bvh_par_params pp = bvh_params(a);
    b->sah_cost = sidx__bvh_tree_sah(b, pp.c_trav, pp.c_tri);
    if (b->obbs) return sidx__bvh_fit_obbs(a, b); /* reuses its array: cannot fail */
    return SIDX_OK;
}

/* The tree (on one thread or several), optimised if asked
 * (bvh_optimize.c), then the walks that fit it. */
static sidx_status bvh_build(sidx_accel *a, sidx_error *err)
{
    /* bvh-sbvh: the spatial-split build (bvh_spatial.c), never lazy */
    const sidx_status s = a->variant == BVH_SBVH ? sidx__bvh_build_sbvh(a, err) : build_tree(a, err);
    if (s == SIDX_OK && !a->lazy) sidx__bvh_optimize(a, a->impl);
    if (s == SIDX_OK) sidx__bvh_pick_walks(a->impl);
    return s;
}

const sidx_accel_vtable sidx__bvh_vtable = {bvh_build, sidx__bvh_intersect, sidx__bvh_occluded,
                                            bvh_stats, bvh_destroy, bvh_refit};
