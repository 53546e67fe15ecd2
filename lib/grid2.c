/* grid2.c — the two-level grid (slides: "Nested Grids"; Kalojanov,
 * Billeter, Slusallek 2011, "Two-Level Grids for Ray Tracing on GPUs";
 * Kalojanov & Slusallek 2009 for the sort-based grid build).
 *
 * A uniform grid "cannot adapt to local density of objects": in the
 * teapot-in-a-stadium one resolution is either too coarse for the teapot
 * (thousands of triangles in a handful of cells) or too fine for the
 * stadium (millions of empty cells to walk).  The two-level grid lays a
 * coarse top grid over the scene (low density λ_top) and gives every
 * non-empty top cell its own uniform sub-grid whose resolution comes from
 * the same formula applied to that cell alone: R = d_cell·∛(λ·n_cell/V_cell).
 * Dense regions get fine cells, empty space stays coarse.
 *
 * Kalojanov et al. stop at two levels; the slides' nested grid lets "each
 * cell itself be a grid", and that is what the teapot in a stadium needs
 * (see GRID2_DEFAULT_DEPTH).  So a cell that still holds many triangles is
 * refined again, up to max_depth levels below the top (opt.max_depth = 1
 * is exactly the paper's two-level grid).
 *
 * Storage (flattened, as in the paper): one record per grid (box,
 * resolution, index of its first cell), one array of cells for all grids
 * (a reference range, or the index of the grid refining it), one array of
 * references.  Traversal: a 3D-DDA per level on a small stack; a cell that
 * is a grid starts a nested DDA from where the ray entered the cell, over
 * the cell's t range.  A hit inside the current leaf cell ends the walk.
 *
 * Event ids: node = index in the cell array (unique over all levels),
 * depth = level, cell[] = coordinates within that level's grid,
 * BUILD_NODE parent = the cell a grid refines. */
#include "grid_internal.h"

/* Densities.  The paper picks a sparse top level (well below one cell per
 * triangle) and a few leaf cells per triangle inside each top cell; here
 * λ_top = 1/8 and λ_leaf = 4 (the uniform grid's default), scaled
 * together by opt.grid_density.  Not tuned further. */
#define GRID2_TOP_DENSITY 0.125f
#define GRID2_LEAF_DENSITY 4.0f
/* A cell becomes a sub-grid when it holds more than this many triangles
 * (below it a sub-grid's extra visit costs more than the tests it saves). */
#define GRID2_LEAF_MAX 8u
/* Levels below the top grid.  Kalojanov et al. use exactly one (max_depth
 * = 1 reproduces that).  The slides' nested grid lets "each cell itself be
 * a grid"; the teapot in a stadium needs it: the teapot is 1/2000 of the
 * stadium, so after two levels of ~16 and ~23 cells per axis it still sits
 * in one or two cells with all its triangles.  Two more levels where (and
 * only where) a cell still holds many triangles fix that. */
#define GRID2_DEFAULT_DEPTH 3u
#define GRID2_MAX_DEPTH 6u
/* A sub-grid never exceeds this per axis, nor this many cells. */
#define GRID2_SUB_MAX_RES 64u
#define GRID2_SUB_MAX_CELLS (1u << 15)
/* Cells overall (8 bytes each). */
#define GRID2_MAX_CELLS (1u << 26)

/* One cell of any grid: a range of references, or a child grid. */
#define GRID2_CHILD 0x80000000u
typedef struct gcell {
    uint32_t begin;      /* first reference (leaf) or child grid index (GRID2_CHILD set in n) */
    uint32_t n;          /* reference count, or GRID2_CHILD */
} gcell;

typedef struct ngrid {
    sidx__grid_geom g;
    uint32_t first;      /* index of its cell (0,0,0) in the cell array */
    uint32_t parent;     /* the cell it refines; UINT32_MAX for the top grid */
    uint32_t level;
} ngrid;

typedef struct grid2 {
    ngrid *grids;
    gcell *cells;
    uint32_t *refs;
    uint32_t n_grids, n_cells, n_refs;
    size_t cap_grids, cap_cells, cap_refs;
    uint32_t empty, max_level, max_depth;
    float lambda, lambda_top;
    const sidx__walk_table *walks; /* with or without the mailbox (build) */
} grid2;

/* Its walk tables, without and with the mailbox (defined after the walk). */
static const sidx__walk_table grid2_walks[2];

static void grid2_free(const sidx_accel *a, grid2 *G)
{
    if (!G) return;
    sidx__free(a, G->grids);
    sidx__free(a, G->cells);
    sidx__free(a, G->refs);
    sidx__free(a, G);
}

/* The box of the grid that refines cell cb: cb grown by 2^-20 of its
 * coordinates' magnitude and extent on every side.  The parent DDA places
 * the ray in cb with cb's boundaries as it computes them (min + i·size),
 * the child DDA computes its own (cb.min + j·size'), and the two roundings
 * can leave a sliver of cb, an ulp thick, that no child cell covers: a ray
 * running inside it left the child grid at once and its hit was lost
 * (fuzz_build: a ray 1.2e-38 off a cell face, regress/build/grid2-
 * nested-gap.bin).  The grown child covers the whole parent cell; its
 * cells take the triangles that overlap them, so a few more references
 * near the faces, and no hit can fall between levels. */
static sidx_aabb child_box(sidx_aabb cb)
{
    float *lo = sidx_v3_array_rw(&cb.min), *hi = sidx_v3_array_rw(&cb.max);
    for (int k = 0; k < 3; ++k) {
        const float pad = (fabsf(lo[k]) + fabsf(hi[k]) + (hi[k] - lo[k])) * 0x1p-20f;
        lo[k] -= pad;
        hi[k] += pad;
    }
    return cb;
}

/* Builds the grid over `box` holding ids[0..n) at `level`, refining cell
 * `parent`; its cells and descendants are appended to G.  Returns the
 * status; *out = its index. */
static sidx_status build_level(sidx_accel *a, grid2 *G, const sidx_aabb *boxes, sidx_aabb box, const uint32_t *ids,
                               uint32_t n, uint32_t level, uint32_t parent, uint32_t *out)
{
    const sidx_mesh *m = a->mesh;
    const sidx_hook *hook = a->opt.hook;
    uint32_t res[3];
    if (level == 0) {
        sidx__grid_resolution(box, (double)n, G->lambda_top, SIDX__GRID_MAX_RES, SIDX__GRID_MAX_CELLS, res);
    } else {
        sidx__grid_resolution(box, (double)n, G->lambda, GRID2_SUB_MAX_RES, GRID2_SUB_MAX_CELLS, res);
    }
    const uint32_t gi = G->n_grids;
    if (!sidx__grow(a, (void **)&G->grids, &G->cap_grids, (size_t)gi + 1u, sizeof *G->grids)) return SIDX_ERR_NOMEM;
    ngrid *ng = &G->grids[gi];
    sidx__grid_geom_init(&ng->g, level == 0 ? sidx__grid_box(box) : box, res);
    const sidx__grid_geom geom = ng->g;
    const uint32_t nc = geom.n_cells;
    if ((uint64_t)G->n_cells + nc > GRID2_MAX_CELLS) return SIDX_ERR_LIMIT;
    if (!sidx__grow(a, (void **)&G->cells, &G->cap_cells, (size_t)G->n_cells + nc, sizeof *G->cells))
        return SIDX_ERR_NOMEM;
    ng->first = G->n_cells;
    ng->parent = parent;
    ng->level = level;
    G->n_grids = gi + 1;
    G->n_cells += nc;
    if (level > G->max_level) G->max_level = level;
    const uint32_t first = ng->first;
    if (level == 0) {
        SIDX_EMIT(1, hook, SIDX_EV_NOTE, e_.text = "grid2 top level: R = d*cbrt(lambda_top*n/V) (cell[] = R)";
                  e_.cell[0] = (int32_t)res[0]; e_.cell[1] = (int32_t)res[1]; e_.cell[2] = (int32_t)res[2];
                  e_.count = nc; e_.cost = G->lambda_top);
    }

    /* Bin this level's triangles (count, prefix-sum, fill) into scratch. */
    uint32_t *off = sidx__calloc(a, (size_t)nc + 1u, sizeof *off);
    if (!off) return SIDX_ERR_NOMEM;
    const uint64_t total = sidx__grid_bin(m, boxes, ids, n, &geom, 1, off + 1, NULL);
    if (total > UINT32_MAX) { sidx__free(a, off); return SIDX_ERR_LIMIT; }
    for (uint32_t c = 0; c < nc; ++c) off[c + 1] += off[c];
    uint32_t *local = sidx__alloc(a, total, sizeof *local);
    if (!local) { sidx__free(a, off); return SIDX_ERR_NOMEM; }
    sidx__grid_bin(m, boxes, ids, n, &geom, 1, off, local);
    memmove(off + 1, off, (size_t)nc * sizeof *off);
    off[0] = 0;

    sidx_status st = SIDX_OK;
    for (uint32_t c = 0; c < nc && st == SIDX_OK; ++c) {
        const uint32_t cnt = off[c + 1] - off[c];
        const uint32_t x = c % res[0], y = (c / res[0]) % res[1], z = c / (res[0] * res[1]);
        const sidx_aabb cb = sidx__grid_cell_bounds(&geom, x, y, z);
        if (cnt) {
            SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = first + c; e_.parent = parent; e_.depth = level;
                      e_.count = cnt; e_.bounds = cb; e_.cell[0] = (int32_t)x; e_.cell[1] = (int32_t)y;
                      e_.cell[2] = (int32_t)z);
        }
        uint32_t sr[3];
        int refine = cnt > GRID2_LEAF_MAX && level < G->max_depth;
        if (refine) {
            /* Only if the formula gives this cell more than one cell. */
            sidx__grid_resolution(cb, (double)cnt, G->lambda, GRID2_SUB_MAX_RES, GRID2_SUB_MAX_CELLS, sr);
            refine = sr[0] * sr[1] * sr[2] > 1;
        }
        if (refine) {
            uint32_t child;
            st = build_level(a, G, boxes, child_box(cb), local + off[c], cnt, level + 1, first + c, &child);
            G->cells[first + c].begin = child;
            G->cells[first + c].n = GRID2_CHILD;
        } else {
            if (!sidx__grow(a, (void **)&G->refs, &G->cap_refs, (size_t)G->n_refs + cnt, sizeof *G->refs)) {
                st = SIDX_ERR_NOMEM;
                break;
            }
            if ((uint64_t)G->n_refs + cnt > UINT32_MAX) { st = SIDX_ERR_LIMIT; break; }
            if (cnt) memcpy(G->refs + G->n_refs, local + off[c], (size_t)cnt * sizeof *local);
            G->cells[first + c].begin = G->n_refs;
            G->cells[first + c].n = cnt;
            G->n_refs += cnt;
            G->empty += cnt == 0;
            if (cnt) {
                SIDX_EMIT(1, hook, SIDX_EV_BUILD_LEAF, e_.node = first + c; e_.depth = level; e_.count = cnt;
                          e_.reason = level >= G->max_depth ? SIDX_LEAF_MAX_DEPTH : SIDX_LEAF_FEW_PRIMS;
                          e_.prims = local + off[c]);
            }
        }
    }
    sidx__free(a, local);
    sidx__free(a, off);
    *out = gi;
    return st;
}

static sidx_status grid2_build(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    grid2 *G = sidx__calloc(a, 1, sizeof *G);
    sidx_aabb *boxes = NULL;
    if (!G) return sidx__fail(err, SIDX_ERR_NOMEM, "grid2: out of memory");
    G->walks = &grid2_walks[!a->opt.no_mailbox];
    G->lambda = a->opt.grid_density > 0.0f ? a->opt.grid_density : GRID2_LEAF_DENSITY;
    G->lambda_top = GRID2_TOP_DENSITY * G->lambda / GRID2_LEAF_DENSITY;
    G->max_depth = a->opt.max_depth ? a->opt.max_depth : GRID2_DEFAULT_DEPTH;
    if (G->max_depth > GRID2_MAX_DEPTH) G->max_depth = GRID2_MAX_DEPTH;
    if (m->num_triangles && sidx__prim_boxes(a, &boxes, NULL) != SIDX_OK) {
        grid2_free(a, G);
        return sidx__fail(err, SIDX_ERR_NOMEM, "grid2: out of memory");
    }
    const sidx_aabb scene = sidx_mesh_bounds(m);
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles;
              e_.bounds = sidx__grid_box(scene));
    /* The top grid's resolution comes from the scene's own extents (a flat
     * axis stays one cell); build_level pads the box itself. */
    uint32_t top;
    sidx_status st = build_level(a, G, boxes, sidx_aabb_is_empty(scene) ? sidx__grid_box(scene) : scene, NULL,
                                 m->num_triangles, 0, UINT32_MAX, &top);
    sidx__free(a, boxes);
    if (st != SIDX_OK) {
        grid2_free(a, G);
        return sidx__fail(err, st, st == SIDX_ERR_NOMEM ? "grid2: out of memory" : "grid2: too many cells");
    }
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_END, e_.node = G->n_cells; e_.count = G->n_refs;
              e_.depth = G->max_level);
    a->impl = G;
    return SIDX_OK;
}

/* One level of the nested walk. */
typedef struct level_walk {
    sidx__dda d;
    const ngrid *g;
    uint32_t cell;        /* local cell index */
    int32_t move[3];      /* cell index change per step on each axis */
    float t_in;           /* where the ray entered the current cell */
    float limit;          /* the parent cell's exit: leaving it ends this level */
} level_walk;

static SIDX_INLINE void level_enter(level_walk *L, const sidx_ray *r, const ngrid *g, float t_in, float limit)
{
    L->g = g;
    sidx__dda_init(&L->d, r, &g->g, t_in);
    const int32_t stride[3] = {1, (int32_t)g->g.res[0], (int32_t)(g->g.res[0] * g->g.res[1])};
    for (int i = 0; i < 3; ++i) L->move[i] = L->d.step[i] * stride[i];
    L->cell = (uint32_t)(L->d.c[0] + L->d.c[1] * stride[1] + L->d.c[2] * stride[2]);
    L->t_in = t_in;
    L->limit = limit;
}

/* The walk: a 3D-DDA per level, kept on a small stack of levels.  A cell
 * that is a grid pushes a nested DDA starting where the ray entered the
 * cell; a nested DDA that leaves its grid (or passes the parent cell's
 * exit) pops, and the parent steps on. */
static SIDX_INLINE int grid2_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                  const int traced, const int any, const int use_mb)
{
    const grid2 *G = a->impl;
    const ngrid *root = &G->grids[0];
    float t0, t1;
    if (!sidx__clip(a, r, &root->g.box, hit->t, &t0, &t1)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.t = hit->t; e_.count = 0);
        return 0;
    }
    level_walk levels[GRID2_MAX_DEPTH + 1];
    int level = 0;
    level_enter(&levels[0], r, root, t0, INFINITY);
    sidx__mailbox mb;
    if (use_mb) sidx__mailbox_clear(&mb);
    uint32_t visited = 0;
    int reason;
    for (;;) {
        level_walk *L = &levels[level];
        const int axis = sidx__dda_axis(&L->d);
        const float t_out = L->d.t_max[axis];
        const uint32_t cell_index = L->g->first + L->cell;
        const gcell cell = G->cells[cell_index];
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = cell_index;
                  e_.depth = (uint32_t)level; e_.t_near = L->t_in; e_.t_far = t_out; e_.cell[0] = L->d.c[0];
                  e_.cell[1] = L->d.c[1]; e_.cell[2] = L->d.c[2]);
        if (cell.n == GRID2_CHILD) {
            ++level;
            level_enter(&levels[level], r, &G->grids[cell.begin], L->t_in, t_out);
            continue;
        }
        /* a grid without references has refs NULL: no offset on it (UBSan, fuzz_build) */
        if (sidx__cell_prims(a, r, q, hit, cell.n ? G->refs + cell.begin : NULL, cell.n, cell_index,
                             (uint32_t)level, &mb, use_mb, traced, any)) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.count = visited);
            return 1;
        }
        if (hit->t <= t_out) {
            reason = hit->prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL : SIDX_TERM_LEFT_GRID;
            break;
        }
        /* Step on; a level that runs out returns to its parent, whose
         * current cell then ends too. */
        for (;;) {
            L = &levels[level];
            const int ax = sidx__dda_axis(&L->d);
            const float out = L->d.t_max[ax];
            if (out < L->limit && sidx__dda_step(&L->d, ax)) {
                L->cell = (uint32_t)((int32_t)L->cell + L->move[ax]);
                L->t_in = out;
                break;
            }
            if (level == 0) {
                reason = SIDX_TERM_LEFT_GRID;
                goto done;
            }
            --level;
            const level_walk *P = &levels[level];
            if (hit->t <= P->d.t_max[sidx__dda_axis(&P->d)]) {
                reason = hit->prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL : SIDX_TERM_LEFT_GRID;
                goto done;
            }
        }
    }
done:
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = reason; e_.t = hit->t;
              e_.count = visited);
    (void)reason;
    (void)visited;
    (void)t1;
    return 0;
}

SIDX__GRID_WALK_TABLES(grid2_walk, grid2_walks);

static void grid2_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    const grid2 *G = a->impl;
    sidx__walk_intersect(G->walks, a, r, q, hit);
}

static int grid2_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    const grid2 *G = a->impl;
    return sidx__walk_occluded(G->walks, a, r, q);
}

static void grid2_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const grid2 *G = a->impl;
    uint32_t inner = 0;
    for (uint32_t c = 0; c < G->n_cells; ++c) inner += G->cells[c].n == GRID2_CHILD;
    s->nodes = G->n_cells;
    s->leaves = G->n_cells - inner;
    s->max_depth = G->max_level;
    s->prim_refs = G->n_refs;
    s->bytes = sizeof *G + G->cap_grids * sizeof *G->grids + G->cap_cells * sizeof *G->cells +
               G->cap_refs * sizeof *G->refs;
    s->empty_leaves = G->empty;
    const uint32_t full = s->leaves - G->empty;
    s->mean_leaf_prims = full ? (double)G->n_refs / (double)full : 0.0;
    s->res[0] = G->grids[0].g.res[0];
    s->res[1] = G->grids[0].g.res[1];
    s->res[2] = G->grids[0].g.res[2];
}

static void grid2_destroy(sidx_accel *a)
{
    grid2_free(a, a->impl);
    a->impl = NULL;
}

const sidx_accel_vtable sidx__grid2_vtable = {grid2_build, grid2_intersect, grid2_occluded, grid2_stats,
                                              grid2_destroy, NULL};
