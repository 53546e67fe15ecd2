/* grid_irregular.c — the irregular grid (slides: "Irregular Grids";
 * Pérard-Gayot, Kalojanov, Slusallek 2017, "GPU Ray Tracing using
 * Irregular Grids").
 *
 * Idea: a fine *virtual* grid decides where triangles are, but it is only
 * fine where the geometry is; afterwards cells are made as large as the
 * geometry allows, so a ray takes few, long steps.
 *
 *  1. Base (hierarchical, as in the paper): a top grid from the
 *     resolution formula (about one cell per triangle); inside every top cell a
 *     power-of-two subdivision adapted to the triangles there.  The paper
 *     gives each top cell one 2^k sub-grid from its own density; we choose
 *     the power of two per octant instead (a top cell is cut into 2×2×2
 *     while a part holds more than leaf_size triangles smaller than about
 *     the part itself), which is the same thing where the density is even
 *     and keeps going where it is not — the teapot in the stadium is
 *     1/2000 of the scene and lies in one top cell, whose own density says
 *     nothing about where in it the teapot sits.  Triangles as large as
 *     the part do not count: no cut separates them (the fan of triangles
 *     around a mesh vertex would otherwise be cut to the depth limit at
 *     every vertex of the bunny).  Every base cell is a box of the virtual grid of resolution
 *     R_top·2^D per axis (D = the deepest level allowed), triangles are
 *     put into the cells they overlap with the exact SAT test.
 *  2. Merge: neighbouring cells with the *same* set of triangles become one
 *     box ("as long as no change in set of primitives").  Sweeps along x,
 *     y, z join a cell with its neighbour on that axis when their
 *     cross-sections match and their lists are equal (union-find over the
 *     cell ids), repeated until nothing changes.  A cell stays a box.
 *  3. Expand: each cell gets a larger *expanded* box, grown in each of the
 *     six directions while every cell the new slab touches holds a subset
 *     of this cell's triangles ("as long as neighbours contain only subset
 *     of cell's primitives").  A step goes as far as the nearest far face
 *     of those cells, so large empty cells are crossed in one step.
 *     Triangles are not added: the expanded box only says how far a ray
 *     may jump.
 *
 * Traversal (the paper's): find the virtual voxel of the entry point, look
 * its cell up (top grid, then the octant bits of the voxel coordinates),
 * test the cell's triangles, then jump to where the ray leaves the cell's
 * *expanded* box.  Exact: every point the ray passes up to that exit lies
 * in cells whose triangles were all just tested (or in earlier cells), so
 * a hit at or before the exit is the closest one.  The next voxel is the
 * one across the exit face; on the other axes it is where the exit point
 * lies, never behind the current voxel (so the walk always advances,
 * whatever the rounding).
 *
 * Bounds (so an adversarial scene cannot blow the build up): at most
 * IRR_MAX_DEPTH levels below the top grid and a virtual resolution of at
 * most 2^20 per axis; a split is refused when the children would hold
 * more than IRR_MAX_DUP times the parent's references; at most
 * IRR_NODES_PER_TRI base nodes per triangle — past that, parts become
 * cells as they are (a coarser base, never a failure); expansion takes at
 * most IRR_MAX_EXPAND steps per direction and gives up a step whose slab
 * needs more than IRR_SLAB_CELLS cell look-ups (only a shorter jump).
 *
 * Trace (deck 000 "Construction (merge & expand)"): a build whose hook
 * asks for them reports each base cell (build_leaf), each merge
 * (build_merge) and each expansion step (build_expand), after merging so
 * that they carry the final cell ids; boxes are given in cells of the
 * finest level used, not in virtual voxels (docs/events.md).  Without such
 * a hook no log is kept and the untraced copy of expand_cell runs.
 *
 * Memory: 4 bytes per base node (top cells and octants: the look-up tree,
 * which replaces the paper's per-voxel map of the virtual grid — that one
 * would be 2^40 entries here), 32 bytes per merged cell (expanded box and
 * reference range), 4 bytes per reference.  opt.max_depth caps D. */
#include "grid_internal.h"

/* Top grid density λ (cells per triangle; opt.grid_density overrides).
 * The paper's top level is sparse; a denser top keeps the look-up short
 * (fewer octant levels).  A part is cut while more than leaf_size (opt,
 * default IRR_DEFAULT_LEAF) of its triangles are smaller than IRR_SPAN
 * times the part.  Both trade tests per ray against build time and
 * memory (figures: docs/performance.md, Grids). */
#define IRR_TOP_DENSITY 1.0f
#define IRR_DEFAULT_LEAF 4u
#define IRR_MAX_DEPTH 16u
#define IRR_MAX_VIRTUAL_BITS 20u /* virtual voxels per axis <= 2^20 */
#define IRR_MAX_TOP_CELLS (1u << 20)
#define IRR_MAX_DUP 2.5
#define IRR_SPAN 2.0f /* see build_node */
#define IRR_NODES_PER_TRI 64u
#define IRR_MAX_EXPAND 32u
#define IRR_SLAB_CELLS 1024u

#define IRR_LEAF 0x80000000u

/* Does the build's hook want events of this type?  (Never when hooks are
 * compiled out: a traced build's extra arrays are then not made.) */
#ifdef SIDX_NO_HOOKS
#define IRR_WANTS(hook, type) ((void)(hook), 0)
#else
#define IRR_WANTS(hook, type) sidx__hook_wants((hook), (type))
#endif

/* A cell as traversal sees it: its expanded box and its triangles. */
typedef struct icell {
    uint32_t elo[3], ehi[3]; /* expanded box in virtual voxels, [elo, ehi) */
    uint32_t begin, n;       /* references */
} icell;

typedef struct igrid {
    sidx_aabb box;
    uint32_t top[3];         /* top grid resolution */
    uint32_t vres[3];        /* virtual resolution = top << shift */
    uint32_t shift[3];       /* D on a subdivided axis, 0 on a flat one */
    uint32_t axes[3];        /* the subdivided axes, in order */
    uint32_t nsplit;         /* how many */
    float vs[3], ivs[3];     /* virtual voxel size and its inverse */
    uint32_t *node;          /* [0, top cells): roots; inner = first child, leaf = IRR_LEAF | cell */
    icell *cells;
    uint32_t *refs;
    uint32_t n_nodes, n_cells, n_refs, empty, base_cells, depth_seen;
    const sidx__walk_table *walks; /* with or without the mailbox (build) */
} igrid;

/* Its walk tables, without and with the mailbox (defined after the walk). */
static const sidx__walk_table igrid_walks[2];

/* Build-only state. */
typedef struct ibuild {
    igrid *G;
    const sidx_aabb *tri_boxes;
    uint32_t *scratch;               /* triangle lists, a stack by level */
    size_t cap_scratch, cap_nodes, cap_cells, cap_refs;
    uint32_t (*lo)[3], (*hi)[3];     /* own box per base cell */
    size_t cap_lo, cap_hi;
    uint32_t leaf_max, depth_max, node_budget;
} ibuild;

static void igrid_free(const sidx_accel *a, igrid *G)
{
    if (!G) return;
    sidx__free(a, G->node);
    sidx__free(a, G->cells);
    sidx__free(a, G->refs);
    sidx__free(a, G);
}

/* Float bounds of the virtual voxel range [lo, hi): bmin + k·size, the same
 * arithmetic the walk uses for its boundaries. */
static sidx_aabb vbox(const igrid *G, const uint32_t lo[3], const uint32_t hi[3])
{
    float mn[3], mx[3];
    const float *bmin = sidx_v3_array(&G->box.min);
    for (int i = 0; i < 3; ++i) {
        mn[i] = (float)lo[i] * G->vs[i] + bmin[i];
        mx[i] = (float)hi[i] * G->vs[i] + bmin[i];
    }
    const sidx_aabb b = {sidx_v3_from_array(mn), sidx_v3_from_array(mx)};
    return b;
}

/* What the trace shows of a box of virtual voxels [lo, hi): its corner and
 * its size in cells of the finest level the build used (depth_seen), not
 * of the virtual grid (2^IRR_MAX_DEPTH per top cell, numbers in the
 * hundred thousands).  Every cell face lies on that level, so the division
 * is exact. */
static void fine_box(const igrid *G, const uint32_t lo[3], const uint32_t hi[3], int32_t cell[3], uint32_t ext[3])
{
    for (int i = 0; i < 3; ++i) {
        const uint32_t s = G->shift[i] ? G->shift[i] - G->depth_seen : 0u;
        cell[i] = (int32_t)(lo[i] >> s);
        ext[i] = (hi[i] - lo[i]) >> s;
    }
}

/* The base cell holding virtual voxel v: top cell, then one octant bit per
 * subdivided axis per level. */
static SIDX_INLINE uint32_t lookup(const igrid *G, const uint32_t v[3])
{
    const uint32_t tx = v[0] >> G->shift[0], ty = v[1] >> G->shift[1], tz = v[2] >> G->shift[2];
    uint32_t k = (tz * G->top[1] + ty) * G->top[0] + tx;
    uint32_t s = G->shift[G->axes[0]];
    while (!(G->node[k] & IRR_LEAF)) {
        --s;
        uint32_t child = 0;
        for (uint32_t j = 0; j < G->nsplit; ++j) child |= ((v[G->axes[j]] >> s) & 1u) << j;
        k = G->node[k] + child;
    }
    return G->node[k] & ~IRR_LEAF;
}

/* Makes node k a base cell over [lo, lo + size) holding scratch[s, s+n). */
static sidx_status make_cell(sidx_accel *a, ibuild *B, uint32_t k, const uint32_t lo[3], const uint32_t size[3],
                             size_t s, uint32_t n)
{
    igrid *G = B->G;
    const uint32_t c = G->n_cells;
    if (c >= IRR_LEAF - 1u || (uint64_t)G->n_refs + n >= UINT32_MAX) return SIDX_ERR_LIMIT;
    if (!sidx__grow(a, (void **)&G->cells, &B->cap_cells, (size_t)c + 1u, sizeof *G->cells) ||
        !sidx__grow(a, (void **)&B->lo, &B->cap_lo, (size_t)c + 1u, sizeof *B->lo) ||
        !sidx__grow(a, (void **)&B->hi, &B->cap_hi, (size_t)c + 1u, sizeof *B->hi) ||
        !sidx__grow(a, (void **)&G->refs, &B->cap_refs, (size_t)G->n_refs + n, sizeof *G->refs))
        return SIDX_ERR_NOMEM;
    if (n) memcpy(G->refs + G->n_refs, B->scratch + s, (size_t)n * sizeof *G->refs);
    G->cells[c].begin = G->n_refs;
    G->cells[c].n = n;
    for (int i = 0; i < 3; ++i) {
        B->lo[c][i] = lo[i];
        B->hi[c][i] = lo[i] + size[i];
    }
    G->n_refs += n;
    G->n_cells = c + 1u;
    G->node[k] = IRR_LEAF | c;
    return SIDX_OK;
}

/* Node k over virtual box [lo, lo + size) holds scratch[s, s+n); scratch
 * from `top` on is free.  Cut into octants (along the subdivided axes)
 * while it holds more than leaf_max triangles, the depth and node budgets
 * allow, and the cut separates them (children's total <= IRR_MAX_DUP·n). */
static sidx_status build_node(sidx_accel *a, ibuild *B, uint32_t k, const uint32_t lo[3], const uint32_t size[3],
                              size_t s, uint32_t n, size_t top, uint32_t depth)
{
    igrid *G = B->G;
    const sidx_mesh *m = a->mesh;
    if (depth > G->depth_seen) G->depth_seen = depth;
    const uint32_t nch = 1u << G->nsplit;
    if (n <= B->leaf_max || depth >= B->depth_max || G->nsplit == 0 || G->n_nodes + nch > B->node_budget)
        return make_cell(a, B, k, lo, size, s, n);
    {
        /* Only triangles smaller than the node count: a cut cannot separate
         * triangles that span the node (the fan around a mesh vertex, the
         * star of lesson 13), it only copies them into more cells. */
        float ext = 0.0f;
        for (uint32_t j = 0; j < G->nsplit; ++j) {
            const float e = (float)size[G->axes[j]] * G->vs[G->axes[j]];
            if (e > ext) ext = e;
        }
        uint32_t small = 0;
        for (uint32_t t = 0; t < n && small <= B->leaf_max; ++t) {
            const sidx_aabb tb = B->tri_boxes[B->scratch[s + t]];
            const float *tl = sidx_v3_array(&tb.min), *th = sidx_v3_array(&tb.max);
            float te = 0.0f;
            for (uint32_t j = 0; j < G->nsplit; ++j) {
                const float e = th[G->axes[j]] - tl[G->axes[j]];
                if (e > te) te = e;
            }
            small += te < IRR_SPAN * ext;
        }
        if (small <= B->leaf_max) return make_cell(a, B, k, lo, size, s, n);
    }
    uint32_t csize[3] = {size[0], size[1], size[2]};
    for (uint32_t j = 0; j < G->nsplit; ++j) csize[G->axes[j]] >>= 1;
    size_t off[9];
    off[0] = top;
    uint32_t clo[8][3];
    for (uint32_t i = 0; i < nch; ++i) {
        for (int ax = 0; ax < 3; ++ax) clo[i][ax] = lo[ax];
        for (uint32_t j = 0; j < G->nsplit; ++j)
            if (i & (1u << j)) clo[i][G->axes[j]] += csize[G->axes[j]];
        const uint32_t chi[3] = {clo[i][0] + csize[0], clo[i][1] + csize[1], clo[i][2] + csize[2]};
        const sidx_aabb cb = vbox(G, clo[i], chi);
        if (!sidx__grow(a, (void **)&B->scratch, &B->cap_scratch, off[i] + n, sizeof *B->scratch))
            return SIDX_ERR_NOMEM;
        off[i + 1] = off[i] + sidx__clip_to_cell(m, B->tri_boxes, B->scratch + s, n, cb, B->scratch + off[i]);
    }
    if ((double)(off[nch] - top) > IRR_MAX_DUP * (double)n) return make_cell(a, B, k, lo, size, s, n);
    const uint32_t first = G->n_nodes;
    if (!sidx__grow(a, (void **)&G->node, &B->cap_nodes, (size_t)first + nch, sizeof *G->node))
        return SIDX_ERR_NOMEM;
    G->n_nodes = first + nch;
    G->node[k] = first;
    for (uint32_t i = 0; i < nch; ++i) {
        const sidx_status st =
            build_node(a, B, first + i, clo[i], csize, off[i], (uint32_t)(off[i + 1] - off[i]), off[nch], depth + 1);
        if (st != SIDX_OK) return st;
    }
    return SIDX_OK;
}

/* Union-find over base cells: merged cells point at the cell they joined. */
static uint32_t find(uint32_t *parent, uint32_t c)
{
    uint32_t r = c;
    while (parent[r] != r) r = parent[r];
    while (parent[c] != r) {
        const uint32_t next = parent[c];
        parent[c] = r;
        c = next;
    }
    return r;
}

static int same_set(const icell *c, const icell *n, const uint32_t *refs)
{
    return c->n == n->n && (c->n == 0 || memcmp(refs + c->begin, refs + n->begin, c->n * sizeof *refs) == 0);
}

/* Is the sorted list b[0..nb) a subset of the sorted list a[0..na)? */
static int is_subset(const uint32_t *b, uint32_t nb, const uint32_t *a, uint32_t na)
{
    if (nb > na) return 0;
    uint32_t i = 0;
    for (uint32_t j = 0; j < nb; ++j) {
        while (i < na && a[i] < b[j]) ++i;
        if (i == na || a[i] != b[j]) return 0;
        ++i;
    }
    return 1;
}

/* A traced build's record of the merges, emitted once the cells have
 * their final ids (BUILD_MERGE names the cell a merge ends up in). */
typedef struct merge_rec {
    uint32_t cell, axis, face, n;
    uint32_t lo[3], hi[3]; /* the box after this merge */
} merge_rec;
typedef struct merge_log {
    merge_rec *rec;
    size_t n, cap;
    int failed;
} merge_log;

/* Merge sweeps (see the file comment).  A live cell c (find(c) == c) tries
 * its neighbour across its upper face on each axis: the cell holding the
 * voxel just past hi[ax] at c's lower corner.  log is NULL unless traced. */
static void merge_cells(sidx_accel *a, ibuild *B, uint32_t *parent, merge_log *log)
{
    igrid *G = B->G;
    for (int changed = 1; changed;) {
        changed = 0;
        for (int ax = 0; ax < 3; ++ax) {
            const int b = (ax + 1) % 3, c2 = (ax + 2) % 3;
            for (uint32_t c = 0; c < G->n_cells; ++c) {
                if (parent[c] != c) continue;
                while (B->hi[c][ax] < G->vres[ax]) {
                    uint32_t p[3] = {B->lo[c][0], B->lo[c][1], B->lo[c][2]};
                    p[ax] = B->hi[c][ax];
                    const uint32_t nb = find(parent, lookup(G, p));
                    if (B->lo[nb][b] != B->lo[c][b] || B->hi[nb][b] != B->hi[c][b] || B->lo[nb][c2] != B->lo[c][c2] ||
                        B->hi[nb][c2] != B->hi[c][c2] || !same_set(&G->cells[c], &G->cells[nb], G->refs))
                        break;
                    parent[nb] = c;
                    const uint32_t face = B->hi[c][ax];
                    B->hi[c][ax] = B->hi[nb][ax];
                    changed = 1;
                    if (log && !log->failed) {
                        if (!sidx__grow(a, (void **)&log->rec, &log->cap, log->n + 1u, sizeof *log->rec)) {
                            log->failed = 1;
                            continue;
                        }
                        merge_rec *m = &log->rec[log->n++];
                        m->cell = c;
                        m->axis = (uint32_t)ax;
                        m->face = face;
                        m->n = G->cells[c].n;
                        memcpy(m->lo, B->lo[c], sizeof m->lo);
                        memcpy(m->hi, B->hi[c], sizeof m->hi);
                    }
                }
            }
        }
    }
}

/* Expansion scan of the one-voxel slab just past a face of cell `self`
 * (along axis ax, upwards when up): the slab's cross-section [u0, u1) ×
 * [w0, w1) (axes b, c2) is tiled by the cells found there.  Look up the
 * cell at the lower corner; it covers the corner up to its own far faces
 * on b and c2; the rest of the rectangle is two smaller rectangles (the
 * strip beyond it on b, and the part above it on c2).  So the work is the
 * number of cells the slab touches, not the number of voxels or base
 * cells in it.  Fails (returns 0) at the first cell whose triangles are
 * not a subset of self's, or after IRR_SLAB_CELLS look-ups; else lowers
 * S->reach to the nearest far face (along ax) of the cells seen. */
typedef struct slab_scan {
    const ibuild *B;
    uint32_t self, last_ok, seen, ax, b, c2, up, face, layer, reach;
} slab_scan;

static int scan_rect(slab_scan *S, uint32_t u0, uint32_t u1, uint32_t w0, uint32_t w1)
{
    const igrid *G = S->B->G;
    while (u0 < u1 && w0 < w1) {
        uint32_t p[3];
        p[S->ax] = S->layer;
        p[S->b] = u0;
        p[S->c2] = w0;
        const uint32_t c = lookup(G, p);
        if (++S->seen > IRR_SLAB_CELLS) return 0;
        if (c != S->self && c != S->last_ok) {
            const icell *me = &G->cells[S->self], *it = &G->cells[c];
            if (!is_subset(G->refs + it->begin, it->n, G->refs + me->begin, me->n)) return 0;
            S->last_ok = c;
        }
        const uint32_t r = S->up ? S->B->hi[c][S->ax] - S->face : S->face - S->B->lo[c][S->ax];
        if (r < S->reach) S->reach = r;
        const uint32_t ue = S->B->hi[c][S->b] < u1 ? S->B->hi[c][S->b] : u1;
        const uint32_t we = S->B->hi[c][S->c2] < w1 ? S->B->hi[c][S->c2] : w1;
        if (!scan_rect(S, ue, u1, w0, w1)) return 0;
        u1 = ue;
        w0 = we;
    }
    return 1;
}

/* Grows cell c's expanded box, direction by direction.  A traced build
 * (a constant: two copies) reports each step and each refusal; the edge of
 * the grid and the step limit end a direction without an event. */
static SIDX_INLINE void expand_cell(const sidx_accel *a, const ibuild *B, uint32_t c, const sidx_hook *hook,
                                    const int traced)
{
    (void)a; /* SIDX_STRUCTURE_NAME */
    icell *ic = &B->G->cells[c];
    const uint32_t *vres = B->G->vres;
    for (int i = 0; i < 3; ++i) {
        ic->elo[i] = B->lo[c][i];
        ic->ehi[i] = B->hi[c][i];
    }
    for (uint32_t dir = 0; dir < 6; ++dir) {
        const uint32_t ax = dir >> 1, up = dir & 1u;
        for (uint32_t step = 0; step < IRR_MAX_EXPAND; ++step) {
            if (up ? ic->ehi[ax] >= vres[ax] : ic->elo[ax] == 0) break;
            const uint32_t face = up ? ic->ehi[ax] : ic->elo[ax];
            const uint32_t b = (ax + 1u) % 3u, c2 = (ax + 2u) % 3u;
            slab_scan S = {B, c, c, 0, ax, b, c2, up, face, up ? face : face - 1u, UINT32_MAX};
            if (!scan_rect(&S, ic->elo[b], ic->ehi[b], ic->elo[c2], ic->ehi[c2])) {
                SIDX_EMIT(traced, hook, SIDX_EV_BUILD_EXPAND, e_.node = c; e_.axis = (int32_t)ax; e_.aux = up;
                          e_.result = 0; e_.count = 0; e_.reason = S.seen > IRR_SLAB_CELLS;
                          fine_box(B->G, ic->elo, ic->ehi, e_.cell, e_.extent);
                          e_.bounds = vbox(B->G, ic->elo, ic->ehi));
                break;
            }
            if (S.reach == 0 || S.reach == UINT32_MAX) break;
            if (up) ic->ehi[ax] += S.reach;
            else ic->elo[ax] -= S.reach;
            SIDX_EMIT(traced, hook, SIDX_EV_BUILD_EXPAND, e_.node = c; e_.axis = (int32_t)ax; e_.aux = up;
                      e_.result = 1; fine_box(B->G, ic->elo, ic->ehi, e_.cell, e_.extent);
                      e_.count = S.reach >> (B->G->shift[ax] ? B->G->shift[ax] - B->G->depth_seen : 0u);
                      e_.bounds = vbox(B->G, ic->elo, ic->ehi));
        }
    }
}

/* A traced build's base cells, as BUILD_LEAF events (a base cell is a leaf
 * of the octant hierarchy), once merging has given them their final ids:
 * node = the cell the base cell became part of, prims = its triangles (the
 * same set: only equal sets merge), depth = its octant level. */
static void emit_base_cells(const sidx_accel *a, const ibuild *B, uint32_t (*lo)[3], uint32_t (*hi)[3],
                            uint32_t *parent, const uint32_t *newid)
{
    const igrid *G = B->G;
    const sidx_hook *hook = a->opt.hook;
    for (uint32_t c = 0; c < G->base_cells; ++c) {
        const uint32_t d = newid[find(parent, c)];
        const icell *ic = &G->cells[d];
        uint32_t level = 0;
        if (G->nsplit) {
            const uint32_t ax = G->axes[0];
            level = G->shift[ax];
            for (uint32_t sz = hi[c][ax] - lo[c][ax]; sz > 1u; sz >>= 1) --level;
        }
        const int reason = ic->n == 0              ? SIDX_LEAF_EMPTY
                           : ic->n <= B->leaf_max  ? SIDX_LEAF_FEW_PRIMS
                           : level >= B->depth_max ? SIDX_LEAF_MAX_DEPTH
                                                   : SIDX_LEAF_NO_SPLIT; /* no cut separates them */
        SIDX_EMIT(1, hook, SIDX_EV_BUILD_LEAF, e_.node = d; e_.depth = level; e_.count = ic->n;
                  e_.prims = ic->n ? G->refs + ic->begin : NULL; e_.reason = reason;
                  fine_box(G, lo[c], hi[c], e_.cell, e_.extent); e_.bounds = vbox(G, lo[c], hi[c]));
    }
}

static uint32_t log2_ceil(uint32_t x)
{
    uint32_t b = 0;
    while ((1u << b) < x) ++b;
    return b;
}

static sidx_status igrid_build(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    const sidx_hook *hook = a->opt.hook;
    ibuild B;
    memset(&B, 0, sizeof B);
    igrid *G = sidx__calloc(a, 1, sizeof *G);
    sidx_aabb *boxes = NULL;
    uint32_t *toff = NULL, *parent = NULL, *newid = NULL, *nrefs = NULL;
    icell *ncells = NULL;
    uint32_t (*base_lo)[3] = NULL, (*base_hi)[3] = NULL;
    merge_log mlog = {NULL, 0, 0, 0};
    sidx_status st = SIDX_ERR_NOMEM;
    if (!G) return sidx__fail(err, SIDX_ERR_NOMEM, "grid-irregular: out of memory");
    B.G = G;
    G->walks = &igrid_walks[!a->opt.no_mailbox];
    if (m->num_triangles && sidx__prim_boxes(a, &boxes, NULL) != SIDX_OK) goto fail;
    B.tri_boxes = boxes;
    B.leaf_max = a->opt.leaf_size ? a->opt.leaf_size : IRR_DEFAULT_LEAF;

    /* 1a. The top grid, from the formula; axes of negligible extent (one
     *     cell there) are not subdivided either, so a flat scene gets a
     *     quadtree-like base. */
    const sidx_aabb scene = sidx_mesh_bounds(m);
    G->box = sidx__grid_box(scene);
    const float lambda = a->opt.grid_density > 0.0f ? a->opt.grid_density : IRR_TOP_DENSITY;
    sidx__grid_resolution(sidx_aabb_is_empty(scene) ? G->box : scene, (double)m->num_triangles, lambda,
                          SIDX__GRID_MAX_RES, IRR_MAX_TOP_CELLS, G->top);
    const sidx_vec3 sext = sidx_aabb_is_empty(scene) ? sidx_v3(0, 0, 0) : sidx_aabb_extent(scene);
    const float *se = sidx_v3_array(&sext);
    const float emax = se[0] > se[1] ? (se[0] > se[2] ? se[0] : se[2]) : (se[1] > se[2] ? se[1] : se[2]);
    uint32_t topbits = 0;
    for (int i = 0; i < 3; ++i) {
        const uint32_t b = log2_ceil(G->top[i]);
        if (b > topbits) topbits = b;
    }
    uint32_t D = a->opt.max_depth ? a->opt.max_depth : IRR_MAX_DEPTH;
    if (D > IRR_MAX_DEPTH) D = IRR_MAX_DEPTH;
    if (D + topbits > IRR_MAX_VIRTUAL_BITS) D = IRR_MAX_VIRTUAL_BITS - topbits;
    B.depth_max = D;
    for (int i = 0; i < 3; ++i) {
        const int split = se[i] > 1e-5f * emax;
        G->shift[i] = split ? D : 0u;
        if (split) G->axes[G->nsplit++] = (uint32_t)i;
        G->vres[i] = G->top[i] << G->shift[i];
    }
    if (G->nsplit == 0) B.depth_max = 0;
    {
        const sidx_vec3 e = sidx_aabb_extent(G->box);
        const float *ep = sidx_v3_array(&e);
        for (int i = 0; i < 3; ++i) {
            G->vs[i] = ep[i] / (float)G->vres[i];
            G->ivs[i] = 1.0f / G->vs[i];
        }
    }
    const uint32_t ntop = G->top[0] * G->top[1] * G->top[2];
    {
        const uint64_t budget = (uint64_t)ntop + (uint64_t)IRR_NODES_PER_TRI * m->num_triangles;
        B.node_budget = budget > (IRR_LEAF >> 1) ? (IRR_LEAF >> 1) : (uint32_t)budget;
    }
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = G->box);
    SIDX_EMIT(1, hook, SIDX_EV_NOTE,
              e_.text = "irregular grid: top grid (cell[] = R_top), each top cell cut in octants while dense";
              e_.cell[0] = (int32_t)G->top[0]; e_.cell[1] = (int32_t)G->top[1]; e_.cell[2] = (int32_t)G->top[2];
              e_.count = ntop; e_.cost = lambda);

    /* 1b. Bin into the top grid (count, prefix sum, fill); the top cells'
     *     lists come out sorted by triangle id, and stay so below. */
    sidx__grid_geom tg;
    sidx__grid_geom_init(&tg, G->box, G->top);
    toff = sidx__calloc(a, (size_t)ntop + 1u, sizeof *toff);
    if (!toff) goto fail;
    const uint64_t total = sidx__grid_bin(m, boxes, NULL, m->num_triangles, &tg, 1, toff + 1, NULL);
    if (total > UINT32_MAX / 2u) {
        st = SIDX_ERR_LIMIT;
        goto fail;
    }
    for (uint32_t c = 0; c < ntop; ++c) toff[c + 1] += toff[c];
    if (!sidx__grow(a, (void **)&B.scratch, &B.cap_scratch, (size_t)total + 1u, sizeof *B.scratch)) goto fail;
    sidx__grid_bin(m, boxes, NULL, m->num_triangles, &tg, 1, toff, B.scratch);
    memmove(toff + 1, toff, (size_t)ntop * sizeof *toff);
    toff[0] = 0;

    /* 1c. The octants of every top cell: nodes [0, ntop) are the roots. */
    if (!sidx__grow(a, (void **)&G->node, &B.cap_nodes, ntop, sizeof *G->node)) goto fail;
    G->n_nodes = ntop;
    {
        const uint32_t size[3] = {1u << G->shift[0], 1u << G->shift[1], 1u << G->shift[2]};
        for (uint32_t z = 0, t = 0; z < G->top[2]; ++z)
            for (uint32_t y = 0; y < G->top[1]; ++y)
                for (uint32_t x = 0; x < G->top[0]; ++x, ++t) {
                    const uint32_t lo[3] = {x << G->shift[0], y << G->shift[1], z << G->shift[2]};
                    st = build_node(a, &B, t, lo, size, toff[t], toff[t + 1] - toff[t], total, 0);
                    if (st != SIDX_OK) goto fail;
                }
    }
    sidx__free(a, toff);
    toff = NULL;
    sidx__free(a, B.scratch);
    B.scratch = NULL;
    sidx__free(a, boxes);
    boxes = NULL;
    G->base_cells = G->n_cells;
    SIDX_EMIT(1, hook, SIDX_EV_NOTE,
              e_.text = "irregular grid: base cells (count), octant levels (depth), finest-level resolution (cell[])";
              e_.count = G->base_cells; e_.depth = G->depth_seen; const uint32_t zero[3] = {0, 0, 0};
              fine_box(G, zero, G->vres, e_.cell, e_.extent); memcpy(e_.cell, e_.extent, sizeof e_.cell);
              memset(e_.extent, 0, sizeof e_.extent));

    /* 2. Merge, then compact: live cells get consecutive ids.  A traced
     *    build keeps the base boxes and a log of the merges to report them
     *    with the final ids. */
    parent = sidx__alloc(a, G->n_cells, sizeof *parent);
    newid = sidx__alloc(a, G->n_cells, sizeof *newid);
    if (!parent || !newid) goto fail;
    if (IRR_WANTS(hook, SIDX_EV_BUILD_LEAF)) {
        base_lo = sidx__alloc(a, G->n_cells, sizeof *base_lo);
        base_hi = sidx__alloc(a, G->n_cells, sizeof *base_hi);
        if (!base_lo || !base_hi) goto fail;
        memcpy(base_lo, B.lo, (size_t)G->n_cells * sizeof *base_lo);
        memcpy(base_hi, B.hi, (size_t)G->n_cells * sizeof *base_hi);
    }
    for (uint32_t c = 0; c < G->n_cells; ++c) parent[c] = c;
    merge_cells(a, &B, parent, IRR_WANTS(hook, SIDX_EV_BUILD_MERGE) ? &mlog : NULL);
    if (mlog.failed) goto fail;
    uint32_t live = 0;
    uint64_t live_refs = 0;
    for (uint32_t c = 0; c < G->n_cells; ++c)
        if (parent[c] == c) {
            newid[c] = live++;
            live_refs += G->cells[c].n;
        }
    ncells = sidx__alloc(a, live, sizeof *ncells);
    nrefs = sidx__alloc(a, live_refs, sizeof *nrefs);
    if (!ncells || !nrefs) goto fail;
    uint32_t w = 0;
    for (uint32_t c = 0; c < G->n_cells; ++c) {
        if (parent[c] != c) continue;
        icell ic = G->cells[c];
        if (ic.n) memcpy(nrefs + w, G->refs + ic.begin, (size_t)ic.n * sizeof *nrefs);
        ic.begin = w;
        w += ic.n;
        G->empty += ic.n == 0;
        const uint32_t d = newid[c];
        ncells[d] = ic;
        /* Own boxes move down to the new ids (d <= c, in order: safe). */
        memcpy(B.lo[d], B.lo[c], sizeof B.lo[d]);
        memcpy(B.hi[d], B.hi[c], sizeof B.hi[d]);
    }
    for (uint32_t k = 0; k < G->n_nodes; ++k)
        if (G->node[k] & IRR_LEAF) G->node[k] = IRR_LEAF | newid[find(parent, G->node[k] & ~IRR_LEAF)];
    sidx__free(a, G->cells);
    sidx__free(a, G->refs);
    G->cells = ncells;
    G->refs = nrefs;
    ncells = NULL;
    nrefs = NULL;
    G->n_cells = live;
    G->n_refs = w;
    if (base_lo) emit_base_cells(a, &B, base_lo, base_hi, parent, newid);
    for (size_t i = 0; i < mlog.n; ++i) {
        const merge_rec *mr = &mlog.rec[i];
        SIDX_EMIT(1, hook, SIDX_EV_BUILD_MERGE, e_.node = newid[find(parent, mr->cell)]; e_.axis = (int32_t)mr->axis;
                  e_.count = mr->n; fine_box(G, mr->lo, mr->hi, e_.cell, e_.extent);
                  e_.aux = mr->face >> (G->shift[mr->axis] ? G->shift[mr->axis] - G->depth_seen : 0u);
                  e_.bounds = vbox(G, mr->lo, mr->hi));
    }
    sidx__free(a, mlog.rec);
    sidx__free(a, base_lo);
    sidx__free(a, base_hi);
    mlog.rec = NULL;
    base_lo = base_hi = NULL;
    sidx__free(a, parent);
    sidx__free(a, newid);
    parent = newid = NULL;

    /* The merged cells that hold triangles, in their own boxes. */
    if (sidx__hook_wants(hook, SIDX_EV_BUILD_NODE)) {
        for (uint32_t c = 0; c < G->n_cells; ++c) {
            if (!G->cells[c].n) continue;
            SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = c; e_.depth = 0; e_.count = G->cells[c].n;
                      e_.bounds = vbox(G, B.lo[c], B.hi[c]); fine_box(G, B.lo[c], B.hi[c], e_.cell, e_.extent));
        }
    }

    /* 3. Expand. */
    if (IRR_WANTS(hook, SIDX_EV_BUILD_EXPAND))
        for (uint32_t c = 0; c < G->n_cells; ++c) expand_cell(a, &B, c, hook, 1);
    else
        for (uint32_t c = 0; c < G->n_cells; ++c) expand_cell(a, &B, c, NULL, 0);
    sidx__free(a, B.lo);
    sidx__free(a, B.hi);
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_END, e_.node = G->n_cells; e_.count = G->n_refs; e_.depth = G->depth_seen);
    a->impl = G;
    return SIDX_OK;
fail:
    sidx__free(a, mlog.rec);
    sidx__free(a, base_lo);
    sidx__free(a, base_hi);
    sidx__free(a, boxes);
    sidx__free(a, toff);
    sidx__free(a, parent);
    sidx__free(a, newid);
    sidx__free(a, ncells);
    sidx__free(a, nrefs);
    sidx__free(a, B.scratch);
    sidx__free(a, B.lo);
    sidx__free(a, B.hi);
    igrid_free(a, G);
    return sidx__fail(err, st, st == SIDX_ERR_LIMIT ? "grid-irregular: too many references or cells"
                                                    : "grid-irregular: out of memory");
}

static SIDX_INLINE int igrid_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                  const int traced, const int any, const int use_mb)
{
    const igrid *G = a->impl;
    float t0, t1;
    if (!sidx__clip(a, r, &G->box, hit->t, &t0, &t1)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.t = hit->t; e_.count = 0);
        return 0;
    }
    const float *o = sidx_v3_array(&r->org), *dir = sidx_v3_array(&r->dir), *inv = sidx_v3_array(&r->inv_dir);
    const float *bmin = sidx_v3_array(&G->box.min), *vs = G->vs, *ivs = G->ivs;
    const uint32_t *res = G->vres;
    float off[3];
    uint32_t voxel[3];
    for (int i = 0; i < 3; ++i) {
        off[i] = bmin[i] - o[i];
        const float f = floorf((o[i] + t0 * dir[i] - bmin[i]) * ivs[i]);
        voxel[i] = !(f >= 0.0f) ? 0u : f >= (float)res[i] ? res[i] - 1u : (uint32_t)f;
    }
    sidx__mailbox mb;
    if (use_mb) sidx__mailbox_clear(&mb);
    uint32_t visited = 0;
    float t = t0;
    int reason;
    for (;;) {
        const uint32_t cell_index = lookup(G, voxel);
        const icell *cell = &G->cells[cell_index];
        /* Exit of the expanded box: on each moving axis, the face ahead. */
        float t_exit = INFINITY;
        int exit_axis = 0;
        for (int i = 0; i < 3; ++i) {
            if (dir[i] == 0.0f) continue;
            const uint32_t face = dir[i] > 0.0f ? cell->ehi[i] : cell->elo[i];
            const float ti = ((float)face * vs[i] + off[i]) * inv[i];
            if (ti < t_exit) { t_exit = ti; exit_axis = i; }
        }
        ++visited;
        /* The trace names the step by the expanded box it jumps across,
         * in finest-level cells (fine_box). */
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = cell_index; e_.depth = 0;
                  e_.t_near = t; e_.t_far = t_exit; fine_box(G, cell->elo, cell->ehi, e_.cell, e_.extent);
                  e_.bounds = vbox(G, cell->elo, cell->ehi));
        if (sidx__cell_prims(a, r, q, hit, G->refs + cell->begin, cell->n, cell_index, 0, &mb, use_mb, traced, any)) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.count = visited);
            return 1;
        }
        if (hit->t <= t_exit) {
            reason = hit->prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL : SIDX_TERM_LEFT_GRID;
            break;
        }
        /* The voxel across the exit face... */
        if (dir[exit_axis] > 0.0f ? cell->ehi[exit_axis] >= res[exit_axis] : cell->elo[exit_axis] == 0) {
            reason = SIDX_TERM_LEFT_GRID;
            break;
        }
        const uint32_t next = dir[exit_axis] > 0.0f ? cell->ehi[exit_axis] : cell->elo[exit_axis] - 1u;
        /* ...and on the other axes where the exit point lies, kept inside
         * the expanded box and never behind the current voxel. */
        for (int i = 0; i < 3; ++i) {
            if (i == exit_axis || dir[i] == 0.0f) continue;
            const float f = floorf((o[i] + t_exit * dir[i] - bmin[i]) * ivs[i]);
            uint32_t vi = !(f >= (float)cell->elo[i])  ? cell->elo[i]
                          : f >= (float)cell->ehi[i] ? cell->ehi[i] - 1u
                                                     : (uint32_t)f;
            if (dir[i] > 0.0f ? vi < voxel[i] : vi > voxel[i]) vi = voxel[i];
            voxel[i] = vi;
        }
        voxel[exit_axis] = next;
        if (t_exit > t) t = t_exit;
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = reason; e_.t = hit->t;
              e_.count = visited);
    (void)reason;
    (void)visited;
    (void)t1;
    return 0;
}

SIDX__GRID_WALK_TABLES(igrid_walk, igrid_walks);

static void igrid_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    const igrid *G = a->impl;
    sidx__walk_intersect(G->walks, a, r, q, hit);
}

static int igrid_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    const igrid *G = a->impl;
    return sidx__walk_occluded(G->walks, a, r, q);
}

static void igrid_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const igrid *G = a->impl;
    s->nodes = G->n_cells;
    s->leaves = G->n_cells;
    s->max_depth = G->depth_seen;
    s->prim_refs = G->n_refs;
    s->bytes = sizeof *G + (size_t)G->n_nodes * sizeof *G->node + (size_t)G->n_cells * sizeof *G->cells +
               (size_t)G->n_refs * sizeof *G->refs;
    s->empty_leaves = G->empty;
    const uint32_t full = G->n_cells - G->empty;
    s->mean_leaf_prims = full ? (double)G->n_refs / (double)full : 0.0;
    s->res[0] = G->vres[0];
    s->res[1] = G->vres[1];
    s->res[2] = G->vres[2];
}

static void igrid_destroy(sidx_accel *a)
{
    igrid_free(a, a->impl);
    a->impl = NULL;
}

const sidx_accel_vtable sidx__grid_irregular_vtable = {igrid_build, igrid_intersect, igrid_occluded,
                                                       igrid_stats, igrid_destroy, NULL};
