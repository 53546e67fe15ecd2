/* bvh_spatial.c — the binary BVH with spatial splits (SBVH: Stich,
 * Friedrich, Dietrich 2009, "Spatial splits in bounding volume
 * hierarchies"), the tree that bvh4 and bvh8 collapse.
 *
 * Why: an object split sends every triangle whole to one side, so long
 * triangles (Sponza's floors, walls and columns) make sibling boxes
 * overlap, and a ray crossing the overlap must visit both.  A spatial
 * split cuts space instead, as a kd-tree does: a triangle that straddles
 * the plane goes to both sides as two references, each bounded by the
 * part of the triangle on its side, and the siblings do not overlap.
 * More references, fewer visits.  Per node the SAH picks the cheapest of
 *
 *   - a leaf                                 ⌈N⌉ · C_tri
 *   - the best binned object split           C_trav + C_tri (A_L ⌈N_L⌉ + A_R ⌈N_R⌉) / A
 *                                             (bvh_build.c's binning, on the
 *                                             references' box centroids)
 *   - the best binned spatial split          the same, N_L and N_R counting
 *                                             straddlers on both sides,
 *
 * with ⌈N⌉ = N rounded up to whole blocks of four (SB_BLOCK) for the wide
 * trees' leaves, and N itself for the binary "bvh-sbvh" (one triangle
 * test at a time), and
 * trying spatial splits only where the object split's children overlap
 * by more than α of the root's area (the paper's α = 10⁻⁵), and never
 * adding more than SB_BUDGET · n references in all.
 *
 * The result is an ordinary `bvh` (bvh_internal.h) whose prim_id[] holds
 * references, a triangle possibly in several leaves (without tris[] or
 * aligned nodes: the collapse in bvh_wide.c, its only reader, takes the
 * corners from the mesh), and the wide walks need no change: a hit on a
 * reference is a hit on its whole triangle, a true hit wherever it lies.
 * Registered as the binary "bvh-sbvh" too (sidx__bvh_build_sbvh below):
 * the same build with block 1, then tris[] filled from the references and
 * the nodes aligned, so bvh_traverse.c's walks run on it unchanged; with a
 * build hook it runs on one thread and reports its nodes, splits and
 * leaves as bvh_build.c does.
 *
 * Robustness: a reference's box must contain the whole part of its
 * triangle inside it, or a ray could slip through the gap.  The part on
 * one side of a plane is the convex polygon of the vertices on that side
 * and the edges' crossings with the plane.  A crossing is computed with
 * rounding in the two other axes, so it is widened there by 2⁻¹⁸ (|a| + |b|)
 * for an edge from a to b: eight times the bound on what the subtractions,
 * division, multiply and add can round off, 6u (|a| + |b|) with u = 2⁻²⁴.
 * Then it is cut to the reference's current box (which contains the true
 * part by the same argument one split up).  On the
 * split axis the plane itself bounds both sides exactly. */
#include <pthread.h>
#include <stdatomic.h>
#include "bvh_internal.h"
#include "pool.h"
#include "simd_isa.h"

#define SB_BINS 32u          /* object and spatial bins per axis (Wald 2007; Stich et al. use 32-256) */
#define SB_ALPHA 1e-5f       /* try spatial splits when sibling overlap > α · root area (Stich et al.) */
#define SB_SPATIAL_MIN 8u   /* spatial bins of a node of n references: n / SB_SPATIAL_DIV, */
#define SB_SPATIAL_DIV 4u   /* clamped to SB_SPATIAL_MIN..SB_BINS (see spatial_bins) */
/* The wide leaves test triangles in blocks of four, so 1 to 4 triangles
 * cost one pass: the SAH here counts a side's triangles rounded up to a
 * whole block (as Embree's builders do with their block size), and the
 * tree prefers sides the collapse can pack into full blocks: fewer
 * leaves, a smaller tree and faster rays than plain counts
 * (docs/performance.md, "Spatial splits"). */
#define SB_BLOCK 4u
#define SB_BUDGET 1.0        /* spatial splits may add at most this many references per triangle, in all */

typedef struct sref {
    sidx_aabb box;  /* bounds the part of the triangle this reference stands for */
    uint32_t prim;  /* original triangle index */
} sref;

typedef struct sbuild {
    const sidx_accel *a;
    const sidx_mesh *mesh;  /* split_ref reads the triangles' corners here (no copy of them) */
    float c_trav, c_tri, min_overlap;
    uint32_t leaf_size, max_leaf, max_depth;
    uint32_t block;         /* SAH counts rounded up to multiples of this: SB_BLOCK (wide), 1 (bvh-sbvh) */
    const sidx_hook *hook;  /* build events (bvh-sbvh; NULL for the wide trees' silent build) */
    uint32_t parent;        /* the node whose child build() makes next (its BUILD_NODE parent) */
    uint64_t budget;        /* references spatial splits may still add below the node being split */
    bvh_node *nodes;        /* pre-order, as bvh_build.c writes them */
    size_t num_nodes, cap_nodes;
    uint32_t *out;          /* the leaf references' triangles, in leaf order (all the collapse reads) */
    size_t num_out, cap_out;
    sref *pool;             /* the references of the nodes still to build, a stack (see "the recursion") */
    size_t top, cap_pool;
    uint32_t num_leaves, max_depth_seen;
    struct stasks *par;     /* parallel build: where subtrees of at most `frontier` references */
    uint32_t frontier;      /* go as tasks (0: build everything here) */
    struct sidx__sbvh_lazy *lazy; /* lazy build: where subtrees of more than lazy_min and at most */
    uint32_t lazy_max, lazy_min;  /* lazy_max references wait for a ray (NULL: build everything) */
} sbuild;

typedef struct sbin {
    sidx_aabb box;
    uint32_t enter, exit;   /* references starting / ending in the bin (object bins: both the
                               references whose centroid falls in it) */
} sbin;

typedef struct ssplit {
    int kind;               /* 0 none, 1 object, 2 spatial */
    int axis;
    uint32_t plane;         /* bin boundary: bins [0, plane) go left */
    float lo, scale;        /* object: the centroid binning of the axis (the partition bins again) */
    float pos;              /* spatial: the plane's position */
    float cost;
    uint32_t nl, nr;        /* spatial: references on each side, straddlers in both */
    sidx_aabb left, right;  /* object: the children's boxes (for the overlap test) */
} ssplit;

static sidx_aabb box_and(sidx_aabb a, sidx_aabb b)
{
    sidx_aabb r = {sidx_v3_max(a.min, b.min), sidx_v3_min(a.max, b.max)};
    return r;
}

/* ---- clipping a reference at a plane ---------------------------------------- */

#define MINF(x, y) ((x) < (y) ? (x) : (y)) /* one MINSS: fminf is a libm call without -ffast-math */
#define MAXF(x, y) ((x) > (y) ? (x) : (y))

/* The boxes of reference r's parts on either side of the plane x_k = p,
 * each cut to r's box; a part may come out empty.  See "Robustness". */
static void split_ref(const sidx_mesh *m, const sref *r, int k, float p, sidx_aabb *L, sidx_aabb *R)
{
    float v[3][3];
    for (int i = 0; i < 3; ++i) {
        const sidx_vec3 c = sidx_mesh_vertex(m, r->prim, i);
        v[i][0] = c.x;
        v[i][1] = c.y;
        v[i][2] = c.z;
    }
    float l0[3] = {INFINITY, INFINITY, INFINITY}, l1[3] = {-INFINITY, -INFINITY, -INFINITY};
    float r0[3] = {INFINITY, INFINITY, INFINITY}, r1[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 3; ++i) {
        const float *a = v[i], *b = v[i == 2 ? 0 : i + 1];
        const float ak = a[k], bk = b[k];
        if (ak <= p)
            for (int j = 0; j < 3; ++j) { l0[j] = MINF(l0[j], a[j]); l1[j] = MAXF(l1[j], a[j]); }
        if (ak >= p)
            for (int j = 0; j < 3; ++j) { r0[j] = MINF(r0[j], a[j]); r1[j] = MAXF(r1[j], a[j]); }
        if ((ak < p && bk > p) || (ak > p && bk < p)) {
            const float t = (p - ak) / (bk - ak);
            for (int j = 0; j < 3; ++j) {
                float lo = p, hi = p;
                if (j != k) {
                    const float x = a[j] + (b[j] - a[j]) * t, slack = (fabsf(a[j]) + fabsf(b[j])) * 0x1p-18f;
                    lo = x - slack;
                    hi = x + slack;
                }
                l0[j] = MINF(l0[j], lo); l1[j] = MAXF(l1[j], hi);
                r0[j] = MINF(r0[j], lo); r1[j] = MAXF(r1[j], hi);
            }
        }
    }
    const sidx_aabb l = {{l0[0], l0[1], l0[2]}, {l1[0], l1[1], l1[2]}};
    const sidx_aabb rr = {{r0[0], r0[1], r0[2]}, {r1[0], r1[1], r1[2]}};
    *L = box_and(l, r->box);
    *R = box_and(rr, r->box);
}

/* ---- finding splits ------------------------------------------------------------ */

/* n rounded up to whole leaf blocks (see SB_BLOCK). */
static uint32_t sb_round(const sbuild *S, uint32_t n) { return (n + S->block - 1u) / S->block * S->block; }

static float sah(const sbuild *S, float al, uint32_t nl, float ar, uint32_t nr, float inv_area)
{
    return S->c_trav + S->c_tri * (al * (float)nl + ar * (float)nr) * inv_area;
}

/* Bin of x, clamped to [0, nb); compared before it is converted, since
 * a float beyond the range of uint32_t (a tiny extent makes scale +inf)
 * has no defined conversion (UBSan, fuzz_build). */
static uint32_t sbin_of(float x, float lo, float scale, uint32_t nb)
{
    const float f = (x - lo) * scale;
    if (!(f > 0.0f)) return 0;
    return f < (float)nb ? (uint32_t)f : nb - 1u;
}

/* The binning kernels: the centroid bounds, the object bins, a
 * reference's spatial bins and the bins' growth.  SSE2 wherever it is
 * there (every x86-64), bit for bit the reference's results. */
#ifdef SIDX_SIMD_SSE2
#include "simd_spatial_sse.h"
#else
#include "simd_spatial_scalar.h"
#endif

/* The plane between spatial bins p − 1 and p of nb over [lo, lo + ext]. */
static float spatial_plane(float lo, float ext, uint32_t p, uint32_t nb) { return lo + ext * ((float)p / (float)nb); }

/* The SAH sweep over one axis's nb bins, shared by both kinds of split:
 * a reference counts on the left from the bin it enters, on the right
 * from the bin it leaves (an object bin's references enter and leave in
 * it, so nl + nr = n; a straddler of a spatial plane counts on both
 * sides).  A plane qualifies when both sides are non-empty and smaller
 * than the node (so the recursion makes progress) and its duplicates fit
 * the budget; the cheapest goes to *best with the children's boxes. */
static void sweep(const sbuild *S, const sbin *bins, uint32_t nb, uint32_t n, float inv_area, int kind, int k,
                  float lo, float scale, float ext, ssplit *best)
{
    /* Only the bins that hold something: a plane next to an empty bin
     * splits the references exactly as the plane before that bin does, at
     * the same cost, and the first of equal candidates wins, so the sweep
     * over the used bins alone picks the same plane (small nodes fill few
     * of the 32 bins, and this sweep ran six times per node). */
    uint32_t used[SB_BINS], m = 0;
    for (uint32_t b = 0; b < nb; ++b)
        if (bins[b].enter | bins[b].exit || !sidx_aabb_is_empty(bins[b].box)) used[m++] = b;
    float right_area[SB_BINS];
    uint32_t right_n[SB_BINS] = {0}; /* filled for j >= 1 below; zeroed so no reader wonders about [0] */
    sidx_aabb right_box[SB_BINS];
    sidx_aabb acc = sidx_aabb_empty();
    uint32_t nr = 0;
    for (uint32_t j = m; j-- > 1;) {
        acc = sidx_aabb_union(acc, bins[used[j]].box);
        nr += bins[used[j]].exit;
        right_box[j] = acc;
        right_area[j] = sidx_aabb_area(acc);
        right_n[j] = nr;
    }
    acc = sidx_aabb_empty();
    uint32_t nl = 0;
    for (uint32_t j = 1; j < m; ++j) {
        acc = sidx_aabb_union(acc, bins[used[j - 1]].box);
        nl += bins[used[j - 1]].enter;
        if (nl == 0 || right_n[j] == 0 || nl >= n || right_n[j] >= n) continue;
        if ((uint64_t)nl + right_n[j] - n > S->budget) continue;
        const float c = sah(S, sidx_aabb_area(acc), sb_round(S, nl), right_area[j], sb_round(S, right_n[j]), inv_area);
        if (c < best->cost) {
            const uint32_t p = used[j - 1] + 1u; /* the first plane with these two sides */
            best->kind = kind;
            best->axis = k;
            best->plane = p;
            best->lo = lo;
            best->scale = scale;
            best->pos = kind == 2 ? spatial_plane(lo, ext, p, nb) : 0.0f;
            best->cost = c;
            best->nl = nl;
            best->nr = right_n[j];
            best->left = acc;
            best->right = right_box[j];
        }
    }
}

/* The object bins of references [i0, i1) on the axes with use[k], one
 * pass (a centroid is computed once for all three axes). */
static void object_bin(const sref *refs, uint32_t i0, uint32_t i1, const float *lo, const float *scale,
                       const int *use, sbin (*bins)[SB_BINS])
{
    if (sb_object_bin_rows(refs, i0, i1, lo, scale, use, bins)) return;
    for (uint32_t i = i0; i < i1; ++i) {
        const sidx_vec3 c = sidx_aabb_centroid(refs[i].box);
        for (int k = 0; k < 3; ++k) {
            if (!use[k]) continue;
            sbin *bn = &bins[k][sbin_of(sidx_v3_get(c, k), lo[k], scale[k], SB_BINS)];
            bn->box = sidx_aabb_union(bn->box, refs[i].box);
            bn->enter++;
            bn->exit++;
        }
    }
}

static void object_clear(sbin (*bins)[SB_BINS])
{
    for (int k = 0; k < 3; ++k)
        for (uint32_t b = 0; b < SB_BINS; ++b) {
            bins[k][b].box = sidx_aabb_empty();
            bins[k][b].enter = bins[k][b].exit = 0;
        }
}

/* bvh_spatial's top levels on several threads: the binning below, run on
 * every thread over its own part of the references ("several threads") */
struct sspatial;
static void par_bin(const sbuild *S, const sref *refs, uint32_t n, int kind, const float *lo, const float *scale,
                    const int *use, uint32_t nb, float (*plane)[SB_BINS + 1], sbin (*obins)[SB_BINS],
                    struct sspatial *sbins);

/* Binned SAH over the references' box centroids, every axis. */
static void object_split(const sbuild *S, const sref *refs, uint32_t n, float inv_area, ssplit *best)
{
    const sidx_aabb cb = sb_centroid_bounds(refs, n);
    float lo[3], ext[3], scale[3];
    int use[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = sidx_v3_get(cb.min, k);
        ext[k] = sidx_v3_get(cb.max, k) - lo[k];
        use[k] = ext[k] > 0.0f;
        scale[k] = use[k] ? (float)SB_BINS * (1.0f - 1e-6f) / ext[k] : 0.0f;
    }
    sbin bins[3][SB_BINS];
    if (S->par) { /* the top of a build on several threads: bin on all of them */
        par_bin(S, refs, n, 1, lo, scale, use, SB_BINS, NULL, bins, NULL);
    } else {
        object_clear(bins);
        object_bin(refs, 0, n, lo, scale, use, bins);
    }
    for (int k = 0; k < 3; ++k)
        if (use[k]) sweep(S, bins[k], SB_BINS, n, inv_area, 1, k, lo[k], scale[k], ext[k], best);
}

/* Spatial bins for a node of n references: each reference is chopped into
 * every bin it spans, and deep in the tree a triangle spans a good part of
 * its node, so the chopping (not the sweep) is the build's cost.  Fewer
 * bins for small nodes: a faster build for the same SAH cost
 * (docs/performance.md, "Spatial splits"). */
static uint32_t spatial_bins(uint32_t n)
{
    const uint32_t nb = n / SB_SPATIAL_DIV;
    return nb < SB_SPATIAL_MIN ? SB_SPATIAL_MIN : nb > SB_BINS ? SB_BINS : nb;
}

/* Binned spatial split: each reference is chopped into the bins it spans
 * (its parts' boxes grow those bins), and counted as entering its first
 * bin and leaving its last.  The chopping here only estimates the SAH of
 * each plane, so it cuts the reference's box at the bin planes instead of
 * clipping the triangle (split_ref, which the chosen split then does for
 * real): a shorter build for the same SAH cost and speed
 * (docs/performance.md, "Spatial splits").
 *
 * A part cut from box B at planes on axis k is B on the two other axes
 * and a piece of B's range on k.  So a bin keeps two things apart: the
 * union of the whole boxes B of its parts (`other`, whose k range is
 * ignored) and the union of its parts' k ranges (`klo`, `khi`); its box
 * is the first with the second's range on k — the same box as the union
 * of the parts, without cutting a box and testing two for emptiness per
 * part, and the planes are computed once per axis, not once per part.
 * With the sweep over used bins only, the same trees build faster.
 * Rejected alternatives: docs/performance.md, "Spatial splits". */

/* One axis's spatial bins while references are chopped into them. */
typedef struct sspatial {
    sidx_aabb other[SB_BINS];
    float klo[SB_BINS], khi[SB_BINS];
    uint32_t enter[SB_BINS], exit[SB_BINS];
} sspatial;

static void spatial_clear(sspatial *A)
{
    for (uint32_t b = 0; b < SB_BINS; ++b) {
        A->other[b] = sidx_aabb_empty();
        A->klo[b] = INFINITY;
        A->khi[b] = -INFINITY;
        A->enter[b] = A->exit[b] = 0;
    }
}

/* References [i0, i1) chopped into the nb bins of every axis with use[k],
 * one pass (a box is read once for the three axes; each axis's bins grow
 * in reference order, as in a pass per axis). */
static void spatial_bin(const sref *refs, uint32_t i0, uint32_t i1, const int *use, const float *lo,
                        const float *scale, uint32_t nb, float (*plane)[SB_BINS + 1], sspatial *A)
{
    sb_rows rows; /* the bins' `other` boxes as the kernel grows them (simd_spatial_*.h) */
    sb_rows_init(&rows, lo, scale, nb);
    for (uint32_t i = i0; i < i1; ++i) {
        const sidx_aabb box = refs[i].box;
        int32_t first[4], last[4];
        const sb_box x = sb_ref_bins(&rows, &refs[i], first, last);
        for (int k = 0; k < 3; ++k) {
            if (!use[k]) continue;
            sspatial *Ak = &A[k];
            const float bmin = sidx_v3_get(box.min, k), bmax = sidx_v3_get(box.max, k);
            const uint32_t b0 = (uint32_t)first[k], b1 = (uint32_t)last[k];
            Ak->enter[b0]++;
            Ak->exit[b1]++;
            /* the part in bin b spans [from, plane[b + 1]] on k; the last
             * one, or the one after which nothing of the box is left, [from, bmax] */
            float from = bmin;
            uint32_t b = b0;
            for (; b < b1; ++b) {
                const float p = plane[k][b + 1];
                if (from <= p) { /* the part is not empty */
                    sb_rows_grow(&rows, k, b, &x, &Ak->other[b]);
                    Ak->klo[b] = MINF(Ak->klo[b], from);
                    Ak->khi[b] = MAXF(Ak->khi[b], p);
                }
                if (p > bmax) break; /* nothing of the box beyond this plane: the rest goes to bin b1 whole */
                from = p;
            }
            sb_rows_grow(&rows, k, b1, &x, &Ak->other[b1]);
            Ak->klo[b1] = MINF(Ak->klo[b1], from);
            Ak->khi[b1] = MAXF(Ak->khi[b1], bmax);
        }
    }
    for (int k = 0; k < 3; ++k) {
        if (!use[k]) continue;
        for (uint32_t b = 0; b < nb; ++b) sb_rows_merge(&rows, k, b, &A[k].other[b]);
    }
}

static void spatial_split(const sbuild *S, const sref *refs, uint32_t n, sidx_aabb box, float inv_area, ssplit *best)
{
    const uint32_t nb = spatial_bins(n);
    float lo[3], ext[3], scale[3], plane[3][SB_BINS + 1];
    int use[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = sidx_v3_get(box.min, k);
        ext[k] = sidx_v3_get(box.max, k) - lo[k];
        use[k] = ext[k] > 0.0f;
        scale[k] = use[k] ? (float)nb / ext[k] : 0.0f;
        for (uint32_t b = 0; b < nb; ++b) plane[k][b + 1] = spatial_plane(lo[k], ext[k], b + 1u, nb);
    }
    sspatial acc[3];
    if (S->par) { /* the top of a build on several threads: chop on all of them */
        par_bin(S, refs, n, 2, lo, scale, use, nb, plane, NULL, acc);
    } else {
        for (int k = 0; k < 3; ++k) spatial_clear(&acc[k]);
        spatial_bin(refs, 0, n, use, lo, scale, nb, plane, acc);
    }
    for (int k = 0; k < 3; ++k) {
        if (!use[k]) continue;
        sbin bins[SB_BINS];
        for (uint32_t b = 0; b < nb; ++b) {
            const sspatial *A = &acc[k];
            bins[b].box = A->other[b];
            if (A->klo[b] <= A->khi[b]) {
                (sidx_v3_array_rw(&bins[b].box.min))[k] = A->klo[b];
                (sidx_v3_array_rw(&bins[b].box.max))[k] = A->khi[b];
            }
            bins[b].enter = A->enter[b];
            bins[b].exit = A->exit[b];
        }
        sweep(S, bins, nb, n, inv_area, 2, k, lo[k], scale[k], ext[k], best);
    }
}

/* ---- the recursion -------------------------------------------------------------- */

static int push_node(sbuild *S, uint32_t *idx)
{
    if (!sidx__grow(S->a, (void **)&S->nodes, &S->cap_nodes, S->num_nodes + 1u, sizeof *S->nodes)) return 0;
    *idx = (uint32_t)S->num_nodes++;
    return 1;
}

static void set_box(bvh_node *nd, sidx_aabb b)
{
    nd->bmin[0] = b.min.x; nd->bmin[1] = b.min.y; nd->bmin[2] = b.min.z;
    nd->bmax[0] = b.max.x; nd->bmax[1] = b.max.y; nd->bmax[2] = b.max.z;
}

/* Events carry the registered name ("bvh-sbvh"). */
#define SIDX_STRUCTURE_NAME (S->a->name)

static sidx_status make_leaf(sbuild *S, uint32_t idx, size_t off, uint32_t n, uint32_t depth, int reason)
{
    if (!sidx__grow(S->a, (void **)&S->out, &S->cap_out, S->num_out + n, sizeof *S->out)) return SIDX_ERR_NOMEM;
    bvh_node *nd = &S->nodes[idx];
    nd->left_or_first = (uint32_t)S->num_out;
    nd->count_axis = n;
    for (uint32_t i = 0; i < n; ++i) S->out[S->num_out + i] = S->pool[off + i].prim;
    SIDX_EMIT(1, S->hook, SIDX_EV_BUILD_LEAF, e_.node = idx; e_.depth = depth; e_.count = n;
              e_.cost = S->c_tri * (float)n; e_.reason = reason; e_.bounds = bvh_node_box(nd);
              e_.prims = S->out + S->num_out);
    S->num_out += n;
    S->num_leaves++;
    return SIDX_OK;
}

/* Room for `need` more references on top of the pool (it may move: the
 * recursion holds offsets, not pointers). */
/* The pool's first size, in references per triangle: the root on top
 * (n) and a spatial split's two sides above it (2n), so that it does not
 * grow (growing copies it whole). */
#define SB_POOL_RESERVE 3u

static int pool_reserve(sbuild *S, size_t need)
{
    return sidx__grow(S->a, (void **)&S->pool, &S->cap_pool, S->top + need, sizeof *S->pool);
}

static sidx_status build(sbuild *S, size_t off, uint32_t n, sidx_aabb box, uint32_t depth, uint64_t budget);
static sidx_status defer(sbuild *S, size_t off, uint32_t n, sidx_aabb box, uint32_t depth, uint64_t budget);
static sidx_status defer_lazy(sbuild *S, size_t off, uint32_t n, sidx_aabb box, uint32_t depth, uint64_t budget);

/* The pool is a stack whose top segment is the node being built: its n
 * references at [off, off + n), top = off + n.  A split leaves its
 * children in the same place as [right nr | left nl] (nl + nr > n after
 * spatial splits: the node is on top, so it may grow), the left child on
 * top; once the left subtree is built, top drops to off + nr and the right
 * child is on top.  So the pool holds the node on the path plus the right
 * siblings still waiting, about n + the spatial duplicates (children
 * copied above their parent would keep every dead parent on the path
 * below them: about 3n).  Every child keeps its references in the parent's order
 * (stable partitions), so each node sees exactly the references, in the
 * order, it saw before: the same tree (docs/performance.md, "Build
 * memory").
 *
 * Both children of node idx, laid out as above.  The references spatial
 * splits may still add below the node are shared by the children
 * in proportion to their references, so a subtree's budget is fixed
 * before it is built: the same tree whichever thread builds which
 * subtree, in whatever order.  (Stich et al. keep one global budget,
 * spent in build order; this share gives trees as good:
 * docs/performance.md, "Spatial splits".) */
static sidx_status children(sbuild *S, uint32_t idx, int axis, size_t off, uint32_t nl, uint32_t nr, uint32_t depth,
                            uint64_t budget)
{
    sidx_aabb lb = sidx_aabb_empty(), rb = sidx_aabb_empty();
    for (uint32_t i = 0; i < nl; ++i) lb = sidx_aabb_union(lb, S->pool[off + nr + i].box);
    for (uint32_t i = 0; i < nr; ++i) rb = sidx_aabb_union(rb, S->pool[off + i].box);
    S->nodes[idx].count_axis = (uint32_t)axis << BVH_AXIS_SHIFT;
    S->top = off + nr + nl;
    const uint64_t bl = budget * nl / ((uint64_t)nl + nr);
    S->parent = idx;
    sidx_status s = build(S, off + nr, nl, lb, depth + 1u, bl); /* the left child is idx + 1 */
    if (s == SIDX_OK) {
        S->nodes[idx].left_or_first = (uint32_t)S->num_nodes;
        S->top = off + nr;
        S->parent = idx;
        s = build(S, off, nr, rb, depth + 1u, budget - bl);
    }
    S->top = off;
    return s;
}

/* Node for the n references at pool[off] (the top of the pool), whose
 * union is box; spatial splits may add `budget` references below it. */
static sidx_status build(sbuild *S, size_t off, uint32_t n, sidx_aabb box, uint32_t depth, uint64_t budget)
{
    const int leaf = n <= S->leaf_size || depth >= S->max_depth;
    if (!leaf && S->lazy && n <= S->lazy_max && n > S->lazy_min)
        return defer_lazy(S, off, n, box, depth, budget);
    if (!leaf && n <= S->frontier) return defer(S, off, n, box, depth, budget);
    uint32_t idx;
    if (!push_node(S, &idx)) return SIDX_ERR_NOMEM;
    set_box(&S->nodes[idx], box);
    if (depth > S->max_depth_seen) S->max_depth_seen = depth;
    SIDX_EMIT(1, S->hook, SIDX_EV_BUILD_NODE, e_.node = idx; e_.parent = S->parent; e_.depth = depth;
              e_.bounds = box; e_.count = n);
    if (leaf) return make_leaf(S, idx, off, n, depth, n <= S->leaf_size ? SIDX_LEAF_FEW_PRIMS : SIDX_LEAF_MAX_DEPTH);
    S->budget = budget; /* what the sweeps may spend here */

    const float area = sidx_aabb_area(box);
    const float inv_area = area > 0.0f ? 1.0f / area : 0.0f;
    ssplit best = {0, 0, 0, 0.0f, 0.0f, 0.0f, INFINITY, 0, 0, sidx_aabb_empty(), sidx_aabb_empty()};
    object_split(S, S->pool + off, n, inv_area, &best);
    const int try_spatial = S->budget > 0 && area > 0.0f &&
                            (best.kind == 0 || sidx_aabb_area(box_and(best.left, best.right)) > S->min_overlap);
    if (try_spatial) spatial_split(S, S->pool + off, n, box, inv_area, &best);

    if (best.kind == 0 || (best.cost >= S->c_tri * (float)sb_round(S, n) && n <= S->max_leaf)) {
        if (best.kind != 0 || n <= S->max_leaf)
            return make_leaf(S, idx, off, n, depth, best.kind != 0 ? SIDX_LEAF_NO_GAIN : SIDX_LEAF_NO_SPLIT);
        /* no plane separates them (all centroids equal) and too many for
         * one leaf: halve in index order, as bvh_build.c does (the first
         * half is the left child: moved above the second) */
        const uint32_t nl = n / 2u, nr = n - nl;
        if (!pool_reserve(S, nl)) return SIDX_ERR_NOMEM;
        sref *refs = S->pool + off, *tmp = S->pool + S->top;
        memcpy(tmp, refs, (size_t)nl * sizeof *refs);
        memmove(refs, refs + nl, (size_t)nr * sizeof *refs);
        memcpy(refs + nr, tmp, (size_t)nl * sizeof *refs);
        SIDX_EMIT(1, S->hook, SIDX_EV_BUILD_SPLIT, e_.node = idx; e_.depth = depth; e_.axis = -1; e_.pos = NAN;
                  e_.cost = best.cost; e_.count = nl; e_.aux = nr);
        return children(S, idx, sidx_aabb_max_axis(box), off, nl, nr, depth, budget);
    }

    const int k = best.axis;
    uint32_t nl = 0, nr = 0;
    if (best.kind == 1) {
        /* Stable, in place but for the left side: a right reference moves
         * down to refs[nr] (nr <= i), a left one to the space above the
         * top, and the left side then follows the right. */
        if (!pool_reserve(S, n)) return SIDX_ERR_NOMEM;
        sref *refs = S->pool + off, *L = S->pool + S->top;
        for (uint32_t i = 0; i < n; ++i) {
            if (sbin_of(sidx_v3_get(sidx_aabb_centroid(refs[i].box), k), best.lo, best.scale, SB_BINS) < best.plane)
                L[nl++] = refs[i];
            else
                refs[nr++] = refs[i];
        }
        memcpy(refs + nr, L, (size_t)nl * sizeof *L);
    } else {
        /* The plane exactly as binning placed it; a reference wholly on one
         * side goes there, a straddler is split in two (or goes whole to the
         * one side its clipped part survives on).  Both sides are written
         * above the top (each is at most n), then moved down. */
        if (!pool_reserve(S, 2u * (size_t)n)) return SIDX_ERR_NOMEM;
        const sref *refs = S->pool + off;
        sref *L = S->pool + S->top, *R = L + n;
        const float p = best.pos;
        for (uint32_t i = 0; i < n; ++i) {
            const sref *r = &refs[i];
            if (sidx_v3_get(r->box.max, k) <= p) { L[nl++] = *r; continue; }
            if (sidx_v3_get(r->box.min, k) >= p) { R[nr++] = *r; continue; }
            sidx_aabb lb, rb;
            split_ref(S->mesh, r, k, p, &lb, &rb);
            const int hl = !sidx_aabb_is_empty(lb), hr = !sidx_aabb_is_empty(rb);
            if (hl) { L[nl] = *r; L[nl++].box = lb; }
            if (hr) { R[nr] = *r; R[nr++].box = rb; }
            if (!hl && !hr) L[nl++] = *r; /* cannot happen for a straddler; kept whole, never lost */
        }
        const uint64_t added = (uint64_t)nl + nr - n;
        budget = added < budget ? budget - added : 0;
        if (nl == 0 || nr == 0) /* rounding put all on one side: no progress */
            return make_leaf(S, idx, off, n, depth, SIDX_LEAF_NO_SPLIT);
        sref *dst = S->pool + off;
        memcpy(dst, R, (size_t)nr * sizeof *R);       /* below the top: no overlap */
        memmove(dst + nr, L, (size_t)nl * sizeof *L); /* may overlap when duplicates were added */
        SIDX_EMIT(1, S->hook, SIDX_EV_NOTE, e_.node = idx; e_.depth = depth; e_.axis = k; e_.pos = best.pos;
                  e_.count = nl + nr - n;
                  e_.text = "spatial split: the plane cuts triangles, each cut one goes to both sides");
    }
    /* pos: the spatial plane, or for an object split the bin boundary its centroids were sorted by */
    SIDX_EMIT(1, S->hook, SIDX_EV_BUILD_SPLIT, e_.node = idx; e_.depth = depth; e_.axis = k;
              e_.pos = best.kind == 2 ? best.pos : best.lo + (float)best.plane / best.scale; e_.cost = best.cost;
              e_.count = nl; e_.aux = nr);
    return children(S, idx, k, off, nl, nr, depth, budget);
}

/* ---- several threads --------------------------------------------------------------- */

/* With opt.threads > 1 the calling thread builds the top of the tree and
 * stops at every subtree of at most n / (SB_TASKS_PER_THREAD · threads)
 * references (SB_TASK_MIN at least): that subtree becomes a task, with a
 * copy of its references and its share of the budget, and a placeholder
 * node.  The threads then build the tasks, largest first (longest
 * processing time first balances them), each with builder state of its
 * own, and the calling thread stitches the tasks' nodes and references
 * into the placeholders in pre-order.  Every node sees the same references in the same order and
 * the same budget as in the one-thread build, so the tree is identical
 * (tests/test_parallel.c compares them word for word).  The top nodes'
 * binning passes (object and spatial bins, the build's main cost) also
 * run on every thread, each over its own part of the references
 * (par_bin); their partitions stay on the calling thread.  Below ~8000
 * triangles the whole build is on one thread.  Speed-ups on 2 threads:
 * docs/performance.md, "Spatial splits". */
#define SB_PAR_MIN 8192u          /* fewer triangles: one thread (a task is not worth its set-up) */
#define SB_TASKS_PER_THREAD 4u
#define SB_TASK_MIN 1024u         /* but no task under this many references (many threads, small scenes) */
#define SB_TASK_NODE 0x3FFFFFFFu  /* count_axis of a placeholder; left_or_first = its task (never a leaf count:
                                     n is at most BVH_COUNT_MASK / 2) */

typedef struct stask {
    uint32_t n, depth;
    sidx_aabb box;
    uint64_t budget;
    sbuild build;           /* the task's own pool (its references at 0..n), nodes and leaf references */
    sidx_status status;
} stask;

/* A user allocator need not be thread-safe, and the tasks' arrays grow
 * while they are built: the workers allocate through this lock. */
typedef struct locked_alloc {
    sidx_allocator real;
    pthread_mutex_t mu;
} locked_alloc;

static void *locked_alloc_fn(size_t size, void *user)
{
    locked_alloc *L = user;
    pthread_mutex_lock(&L->mu);
    void *p = L->real.alloc(size, L->real.user);
    pthread_mutex_unlock(&L->mu);
    return p;
}

static void locked_free_fn(void *p, void *user)
{
    locked_alloc *L = user;
    pthread_mutex_lock(&L->mu);
    L->real.free(p, L->real.user);
    pthread_mutex_unlock(&L->mu);
}

typedef struct stasks {
    stask *task;
    size_t count, cap;
    uint32_t *order;        /* task indices, largest first */
    atomic_size_t next;     /* the next entry of order[] to build */
    sidx_accel shadow;      /* the accel with the locked allocator, for the tasks' builders */
    locked_alloc lock;
    /* the top levels' binning passes (par_bin): one set of bins per
     * thread, and the pass being run */
    unsigned threads;
    sbin (*tobj)[3][SB_BINS];
    sspatial (*tspat)[3];
    const sref *refs;
    uint32_t n, nb;
    int kind;
    const float *lo, *scale;
    const int *use;
    float (*plane)[SB_BINS + 1];
} stasks;

/* Thread t's part of a binning pass, into its own bins. */
static void bin_part(void *ctx, unsigned t)
{
    const stasks *P = ctx;
    const uint32_t i0 = (uint32_t)((uint64_t)P->n * t / P->threads);
    const uint32_t i1 = (uint32_t)((uint64_t)P->n * (t + 1u) / P->threads);
    if (P->kind == 1) {
        object_clear(P->tobj[t]);
        object_bin(P->refs, i0, i1, P->lo, P->scale, P->use, P->tobj[t]);
        return;
    }
    for (int k = 0; k < 3; ++k) spatial_clear(&P->tspat[t][k]);
    spatial_bin(P->refs, i0, i1, P->use, P->lo, P->scale, P->nb, P->plane, P->tspat[t]);
}

/* A binning pass on all threads, the threads' bins merged in thread
 * order: unions and counts are exact in any order, so the merged bins are
 * the one-thread pass's, bit for bit. */
static void par_bin(const sbuild *S, const sref *refs, uint32_t n, int kind, const float *lo, const float *scale,
                    const int *use, uint32_t nb, float (*plane)[SB_BINS + 1], sbin (*obins)[SB_BINS],
                    struct sspatial *sbins)
{
    stasks *P = S->par;
    P->refs = refs;
    P->n = n;
    P->kind = kind;
    P->lo = lo;
    P->scale = scale;
    P->use = use;
    P->nb = nb;
    P->plane = plane;
    sidx__pool_run(P->threads, bin_part, P);
    if (kind == 1) {
        object_clear(obins);
        for (unsigned t = 0; t < P->threads; ++t)
            for (int k = 0; k < 3; ++k)
                for (uint32_t b = 0; b < SB_BINS; ++b) {
                    const sbin *src = &P->tobj[t][k][b];
                    obins[k][b].box = sidx_aabb_union(obins[k][b].box, src->box);
                    obins[k][b].enter += src->enter;
                    obins[k][b].exit += src->exit;
                }
        return;
    }
    for (int k = 0; k < 3; ++k) {
        spatial_clear(&sbins[k]);
        for (unsigned t = 0; t < P->threads; ++t)
            for (uint32_t b = 0; b < SB_BINS; ++b) {
                const sspatial *src = &P->tspat[t][k];
                sbins[k].other[b] = sidx_aabb_union(sbins[k].other[b], src->other[b]);
                sbins[k].klo[b] = MINF(sbins[k].klo[b], src->klo[b]);
                sbins[k].khi[b] = MAXF(sbins[k].khi[b], src->khi[b]);
                sbins[k].enter[b] += src->enter[b];
                sbins[k].exit[b] += src->exit[b];
            }
    }
}

/* A placeholder for the subtree of the n references at pool[off], and its
 * task (on the calling thread, which may allocate directly). */
static sidx_status defer(sbuild *S, size_t off, uint32_t n, sidx_aabb box, uint32_t depth, uint64_t budget)
{
    stasks *P = S->par;
    uint32_t idx;
    if (!push_node(S, &idx) || !sidx__grow(S->a, (void **)&P->task, &P->cap, P->count + 1u, sizeof *P->task))
        return SIDX_ERR_NOMEM;
    stask *t = &P->task[P->count];
    memset(t, 0, sizeof *t);
    t->n = n;
    t->depth = depth;
    t->box = box;
    t->budget = budget;
    /* the build's parameters; arrays, counts, par and frontier start empty (memset) */
    t->build.a = &P->shadow;
    t->build.mesh = S->mesh;
    t->build.c_trav = S->c_trav;
    t->build.c_tri = S->c_tri;
    t->build.min_overlap = S->min_overlap;
    t->build.leaf_size = S->leaf_size;
    t->build.max_leaf = S->max_leaf;
    t->build.max_depth = S->max_depth;
    t->build.block = S->block;
    t->build.parent = UINT32_MAX;
    P->count++; /* counted now, so the clean-up frees its arrays even if they cannot all be made */
    /* sized as the entry sizes the whole build's, so they rarely grow */
    if (!pool_reserve(&t->build, SB_POOL_RESERVE * (size_t)n) ||
        !sidx__grow(S->a, (void **)&t->build.nodes, &t->build.cap_nodes, n, sizeof *t->build.nodes) ||
        !sidx__grow(S->a, (void **)&t->build.out, &t->build.cap_out, n + n / 2u, sizeof *t->build.out))
        return SIDX_ERR_NOMEM;
    memcpy(t->build.pool, S->pool + off, (size_t)n * sizeof *S->pool);
    t->build.top = n;
    set_box(&S->nodes[idx], box);
    S->nodes[idx].left_or_first = (uint32_t)(P->count - 1u);
    S->nodes[idx].count_axis = SB_TASK_NODE;
    return SIDX_OK;
}

static void run_tasks(void *ctx, unsigned thread)
{
    (void)thread;
    stasks *P = ctx;
    for (;;) {
        const size_t i = atomic_fetch_add(&P->next, 1);
        if (i >= P->count) return;
        stask *t = &P->task[P->order[i]];
        t->status = build(&t->build, 0, t->n, t->box, t->depth, t->budget);
    }
}

static void free_tasks(const sidx_accel *a, stasks *P)
{
    sidx__free(a, P->tobj);
    sidx__free(a, P->tspat);
    for (size_t i = 0; i < P->count; ++i) {
        sidx__free(a, P->task[i].build.pool);
        sidx__free(a, P->task[i].build.nodes);
        sidx__free(a, P->task[i].build.out);
    }
    sidx__free(a, P->task);
    sidx__free(a, P->order);
}

/* Copies top node i's subtree into nodes/out in pre-order, a placeholder
 * replaced by its task's nodes (right-child indices and leaf starts
 * shifted); returns the subtree root's index in nodes. */
static uint32_t stitch(const sbuild *S, const stasks *P, uint32_t i, bvh_node *nodes, size_t *nn, uint32_t *out,
                       size_t *no)
{
    const bvh_node *src = &S->nodes[i];
    const uint32_t me = (uint32_t)*nn;
    if (src->count_axis == SB_TASK_NODE) {
        const sbuild *task_build = &P->task[src->left_or_first].build;
        for (size_t j = 0; j < task_build->num_nodes; ++j) {
            bvh_node d = task_build->nodes[j];
            d.left_or_first += bvh_is_leaf(&d) ? (uint32_t)*no : me;
            nodes[me + j] = d;
        }
        memcpy(out + *no, task_build->out, task_build->num_out * sizeof *out);
        *nn += task_build->num_nodes;
        *no += task_build->num_out;
        return me;
    }
    nodes[me] = *src;
    *nn += 1;
    if (bvh_is_leaf(src)) {
        memcpy(out + *no, S->out + src->left_or_first, (size_t)bvh_count(src) * sizeof *out);
        nodes[me].left_or_first = (uint32_t)*no;
        *no += bvh_count(src);
        return me;
    }
    stitch(S, P, i + 1u, nodes, nn, out, no);
    nodes[me].left_or_first = stitch(S, P, src->left_or_first, nodes, nn, out, no);
    return me;
}

/* Builds the tasks on `threads` threads and stitches them into S. */
static sidx_status finish_tasks(sbuild *S, stasks *P, unsigned threads)
{
    if (P->count == 0) return SIDX_OK;
    P->order = sidx__alloc(S->a, P->count, sizeof *P->order);
    if (!P->order) return SIDX_ERR_NOMEM;
    for (size_t i = 0; i < P->count; ++i) { /* insertion sort, largest first; ties by index */
        size_t j = i;
        while (j > 0 && P->task[P->order[j - 1]].n < P->task[i].n) {
            P->order[j] = P->order[j - 1];
            --j;
        }
        P->order[j] = (uint32_t)i;
    }
    atomic_store(&P->next, 0);
    sidx__pool_run(threads, run_tasks, P);
    size_t nn = S->num_nodes - P->count, no = S->num_out;
    for (size_t i = 0; i < P->count; ++i) {
        const stask *t = &P->task[i];
        if (t->status != SIDX_OK) return t->status;
        nn += t->build.num_nodes;
        no += t->build.num_out;
        S->num_leaves += t->build.num_leaves;
        if (t->build.max_depth_seen > S->max_depth_seen) S->max_depth_seen = t->build.max_depth_seen;
    }
    bvh_node *nodes = sidx__alloc(S->a, nn, sizeof *nodes);
    uint32_t *out = sidx__alloc(S->a, no, sizeof *out);
    if (!nodes || !out) {
        sidx__free(S->a, nodes);
        sidx__free(S->a, out);
        return SIDX_ERR_NOMEM;
    }
    size_t at_node = 0, at_out = 0;
    stitch(S, P, 0, nodes, &at_node, out, &at_out);
    sidx__free(S->a, S->nodes);
    sidx__free(S->a, S->out);
    S->nodes = nodes;
    S->num_nodes = S->cap_nodes = nn;
    S->out = out;
    S->num_out = S->cap_out = no;
    return SIDX_OK;
}

/* ---- lazy builds -------------------------------------------------------------------- */

/* With a->opt.lazy (bvh_wide.c) the build stops at every subtree of more
 * than lazy_min and at most lazy_max references: the node becomes a
 * placeholder (count_axis = BVH_LAZY_MARK | r, left_or_first = its
 * reference count) and record r keeps what building it needs — a copy of
 * its references in the build's order, its box, depth and share of the
 * spatial-split budget.  A node's subtree depends on nothing else (see
 * "several threads" above), so sidx__sbvh_lazy_build, run when a ray first
 * reaches the node, builds the very subtree the eager build has there. */
typedef struct slazy_rec {
    sref *refs;             /* NULL once built */
    uint32_t n, depth;
    sidx_aabb box;
    uint64_t budget;
} slazy_rec;

struct sidx__sbvh_lazy {
    slazy_rec *rec;
    size_t count, cap;
    sbuild params;          /* the top build's parameters (arrays empty) */
};

static sidx_status defer_lazy(sbuild *S, size_t off, uint32_t n, sidx_aabb box, uint32_t depth, uint64_t budget)
{
    sidx__sbvh_lazy *L = S->lazy;
    uint32_t idx;
    if (L->count >= BVH_LAZY_MAX_RECS) { /* no record left: built now */
        sidx__sbvh_lazy *keep = L;
        S->lazy = NULL;
        const sidx_status s = build(S, off, n, box, depth, budget);
        S->lazy = keep;
        return s;
    }
    if (!push_node(S, &idx) || !sidx__grow(S->a, (void **)&L->rec, &L->cap, L->count + 1u, sizeof *L->rec))
        return SIDX_ERR_NOMEM;
    slazy_rec *r = &L->rec[L->count];
    r->refs = sidx__alloc(S->a, n, sizeof *r->refs);
    if (!r->refs) return SIDX_ERR_NOMEM;
    memcpy(r->refs, S->pool + off, (size_t)n * sizeof *r->refs);
    r->n = n;
    r->depth = depth;
    r->box = box;
    r->budget = budget;
    set_box(&S->nodes[idx], box);
    S->nodes[idx].left_or_first = n;
    S->nodes[idx].count_axis = BVH_LAZY_MARK | (uint32_t)L->count;
    L->count++;
    if (depth > S->max_depth_seen) S->max_depth_seen = depth;
    return SIDX_OK;
}

void sidx__sbvh_lazy_free(const sidx_accel *a, sidx__sbvh_lazy *L)
{
    if (!L) return;
    for (size_t i = 0; i < L->count; ++i) sidx__free(a, L->rec[i].refs);
    sidx__free(a, L->rec);
    sidx__free(a, L);
}

uint32_t sidx__sbvh_lazy_count(const sidx__sbvh_lazy *L) { return L ? (uint32_t)L->count : 0u; }

sidx_status sidx__sbvh_lazy_build(const sidx_accel *a, sidx__sbvh_lazy *L, uint32_t r, bvh **out)
{
    slazy_rec *rec = &L->rec[r];
    const uint32_t n = rec->n;
    *out = NULL;
    sbuild S = L->params;
    S.a = a;
    S.mesh = a->mesh;
    sidx_status s = SIDX_ERR_NOMEM;
    bvh *b = sidx__calloc(a, 1, sizeof *b);
    if (!b || !pool_reserve(&S, SB_POOL_RESERVE * (size_t)n) ||
        !sidx__grow(a, (void **)&S.nodes, &S.cap_nodes, n, sizeof *S.nodes) ||
        !sidx__grow(a, (void **)&S.out, &S.cap_out, n + n / 2u, sizeof *S.out))
        goto fail;
    memcpy(S.pool, rec->refs, (size_t)n * sizeof *S.pool);
    S.top = n;
    if ((s = build(&S, 0, n, rec->box, rec->depth, rec->budget)) != SIDX_OK) goto fail;
    sidx__free(a, S.pool);
    b->nodes_mem = b->nodes = S.nodes;
    b->prim_id = S.out;
    b->num_nodes = (uint32_t)S.num_nodes;
    b->num_leaves = S.num_leaves;
    b->max_depth = S.max_depth_seen;
    b->num_prims = (uint32_t)S.num_out;
    *out = b;
    return SIDX_OK;

fail:
    sidx__free(a, S.pool);
    sidx__free(a, S.nodes);
    sidx__free(a, S.out);
    sidx__free(a, b);
    return s;
}

void sidx__sbvh_lazy_release(const sidx_accel *a, sidx__sbvh_lazy *L, uint32_t r)
{
    sidx__free(a, L->rec[r].refs);
    L->rec[r].refs = NULL;
}

/* ---- entry -------------------------------------------------------------------------- */

/* Builds the reference tree into a->impl (a bvh, freed by the bvh
 * vtable's destroy).  Reads a->opt: c_trav, c_tri, leaf_size, max_depth
 * as bvh_build.c does, and threads (see "several threads" above; one
 * thread when a hook takes the events, so that they come in build order
 * with final node ids).  block: see SB_BLOCK. */
static sidx_status build_spatial(sidx_accel *a, uint32_t block, const sidx_hook *hook, uint32_t lazy_max,
                                 uint32_t lazy_min, sidx__sbvh_lazy **lazy, sidx_error *err)
{
    if (lazy) *lazy = NULL;
    const sidx_mesh *m = a->mesh;
    const uint32_t n = m->num_triangles;
    a->impl = NULL;
    if (n > BVH_COUNT_MASK / 2u)
        return sidx__fail(err, SIDX_ERR_LIMIT, "%s: %u triangles exceed the spatial-split BVH's limit of %u",
                          a->name, n, BVH_COUNT_MASK / 2u);
    sbuild S;
    memset(&S, 0, sizeof S);
    S.a = a;
    const bvh_par_params pp = bvh_params(a); /* bvh_build.c's reading of a->opt (its bins aside: SB_BINS) */
    S.c_trav = pp.c_trav;
    S.c_tri = pp.c_tri;
    S.leaf_size = pp.leaf_size;
    S.max_leaf = pp.max_leaf;
    S.max_depth = pp.max_depth;
    S.block = block;
    S.hook = hook && hook->fn ? hook : NULL;
    S.parent = UINT32_MAX;
    const unsigned threads = a->opt.threads > SIDX_POOL_MAX_THREADS ? SIDX_POOL_MAX_THREADS : a->opt.threads;
    stasks P;
    memset(&P, 0, sizeof P);
    /* a lazy top is built on the calling thread (it is small) */
    const int parallel = threads > 1 && n >= SB_PAR_MIN && !(lazy && lazy_max) && !S.hook;
    if (parallel) {
        if (pthread_mutex_init(&P.lock.mu, NULL) != 0)
            return sidx__fail(err, SIDX_ERR_NOMEM, "%s: cannot create a mutex", a->name);
        P.lock.real = a->alloc;
        P.shadow = *a;
        P.shadow.alloc = (sidx_allocator){locked_alloc_fn, locked_free_fn, &P.lock};
        S.par = &P;
        P.threads = threads;
        P.tobj = sidx__alloc(a, threads, sizeof *P.tobj);
        P.tspat = sidx__alloc(a, threads, sizeof *P.tspat);
        S.frontier = n / (SB_TASKS_PER_THREAD * threads);
        if (S.frontier < SB_TASK_MIN) S.frontier = SB_TASK_MIN;
    }

    sidx_status s = SIDX_ERR_NOMEM;
    bvh *b = sidx__calloc(a, 1, sizeof *b);
    if (!b || (parallel && (!P.tobj || !P.tspat))) goto fail;
    if (lazy && lazy_max && n > 0) {
        S.lazy = sidx__calloc(a, 1, sizeof *S.lazy);
        if (!S.lazy) goto fail;
        S.lazy_max = lazy_max;
        S.lazy_min = lazy_min;
    }
    if (n > 0) {
        /* Sized for a typical build, so the arrays rarely grow (growing
         * copies them whole); pages never written cost no memory. */
        if (!pool_reserve(&S, SB_POOL_RESERVE * (size_t)n) ||
            !sidx__grow(a, (void **)&S.nodes, &S.cap_nodes, n, sizeof *S.nodes) ||
            !sidx__grow(a, (void **)&S.out, &S.cap_out, n + n / 2u, sizeof *S.out))
            goto fail;
        S.mesh = m;
        sidx_aabb root = sidx_aabb_empty();
        for (uint32_t i = 0; i < n; ++i) {
            sidx_aabb bb = sidx_aabb_empty();
            for (int k = 0; k < 3; ++k) bb = sidx_aabb_grow(bb, sidx_mesh_vertex(m, i, k));
            S.pool[i].box = bb;
            S.pool[i].prim = i;
            root = sidx_aabb_union(root, bb);
        }
        S.top = n;
        S.min_overlap = SB_ALPHA * sidx_aabb_area(root);
        if (S.lazy) {
            S.lazy->params = S; /* the parameters; the arrays are the expansion's own */
            S.lazy->params.pool = NULL;
            S.lazy->params.nodes = NULL;
            S.lazy->params.out = NULL;
            S.lazy->params.lazy = NULL;
            S.lazy->params.top = S.lazy->params.cap_pool = S.lazy->params.num_nodes = S.lazy->params.cap_nodes = 0;
            S.lazy->params.num_out = S.lazy->params.cap_out = 0;
            S.lazy->params.num_leaves = S.lazy->params.max_depth_seen = 0;
        }
        if ((s = build(&S, 0, n, root, 0, (uint64_t)((double)n * SB_BUDGET))) != SIDX_OK ||
            (s = finish_tasks(&S, &P, threads)) != SIDX_OK)
            goto fail;
        /* The builder's arrays become the tree's, not copied: the collapse
         * (bvh_wide.c) is this tree's only reader, reads the triangles'
         * corners from the mesh (no tris[]) and needs no aligned nodes. */
        sidx__free(a, S.pool);
        S.pool = NULL;
        b->nodes_mem = b->nodes = S.nodes;
        b->prim_id = S.out;
        S.nodes = NULL;
        S.out = NULL;
        b->num_nodes = (uint32_t)S.num_nodes;
        b->num_leaves = S.num_leaves;
        b->max_depth = S.max_depth_seen;
        b->num_prims = (uint32_t)S.num_out;
    }
    sidx__free(a, S.pool);
    sidx__free(a, S.nodes);
    sidx__free(a, S.out);
    if (parallel) {
        free_tasks(a, &P);
        pthread_mutex_destroy(&P.lock.mu);
    }
    if (lazy) *lazy = S.lazy;
    a->impl = b;
    return SIDX_OK;

fail:
    sidx__free(a, S.pool);
    sidx__free(a, S.nodes);
    sidx__free(a, S.out);
    if (parallel) {
        free_tasks(a, &P);
        pthread_mutex_destroy(&P.lock.mu);
    }
    sidx__sbvh_lazy_free(a, S.lazy);
    if (b) {
        sidx__free(a, b->nodes_mem);
        sidx__free(a, b->prim_id);
        sidx__free(a, b);
    }
    if (s == SIDX_ERR_NOMEM) return sidx__fail(err, s, "%s: out of memory", a->name);
    return s;
}

sidx_status sidx__bvh_build_spatial(sidx_accel *a, uint32_t lazy_max, uint32_t lazy_min, sidx__sbvh_lazy **lazy,
                                    sidx_error *err)
{
    return build_spatial(a, SB_BLOCK, NULL, lazy_max, lazy_min, lazy, err);
}

/* "bvh-sbvh": the same tree for a binary walk.  Its leaves test one
 * triangle at a time, so the SAH counts references one by one (block 1);
 * then the walk's layout (bvh_internal.h): nodes 64-byte aligned and
 * tris[] filled from the references, a triangle's corners copied once per
 * leaf that holds it.  A hit on a reference is a hit on its whole
 * triangle (the leaf tests the triangle, not the part in its box), so the
 * closest hit is exact and a duplicate found again at the same t changes
 * nothing.  Not lazy (opt.lazy is ignored): an expansion would need the
 * references' clipped boxes kept for every unbuilt node. */
#undef SIDX_STRUCTURE_NAME
#define SIDX_STRUCTURE_NAME (a->name)
sidx_status sidx__bvh_build_sbvh(sidx_accel *a, sidx_error *err)
{
    const sidx_hook *hook = a->opt.hook;
    const sidx_mesh *m = a->mesh;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles;
              e_.bounds = sidx_mesh_bounds(m));
    sidx_status s = build_spatial(a, 1u, hook, 0, 0, NULL, err);
    if (s != SIDX_OK) return s;
    bvh *b = a->impl;
    if (b->num_nodes > 0) {
        void *mem = sidx__alloc(a, (size_t)b->num_nodes + 2u, sizeof *b->nodes);
        b->tris = sidx__alloc(a, b->num_prims, sizeof *b->tris);
        if (!mem || !b->tris) {
            sidx__free(a, mem);
            sidx__free(a, b->nodes_mem);
            sidx__free(a, b->prim_id);
            sidx__free(a, b->tris);
            sidx__free(a, b);
            a->impl = NULL;
            return sidx__fail(err, SIDX_ERR_NOMEM, "%s: out of memory", a->name);
        }
        bvh_node *nodes = (bvh_node *)(void *)(((uintptr_t)mem + 63u) & ~(uintptr_t)63u);
        memcpy(nodes, b->nodes, (size_t)b->num_nodes * sizeof *nodes);
        sidx__free(a, b->nodes_mem);
        b->nodes_mem = mem;
        b->nodes = nodes;
        for (uint32_t i = 0; i < b->num_prims; ++i)
            for (int k = 0; k < 3; ++k) b->tris[i].v[k] = sidx_mesh_vertex(m, b->prim_id[i], k);
        const bvh_par_params pp = bvh_params(a);
        b->sah_cost = sidx__bvh_tree_sah(b, pp.c_trav, pp.c_tri);
    }
    a->fills_uv = a->fills_ng = 1; /* from the leaves' triangle copies (bvh_traverse.c) */
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_END, e_.node = b->num_nodes; e_.count = b->num_prims;
              e_.depth = b->max_depth);
    return SIDX_OK;
}
