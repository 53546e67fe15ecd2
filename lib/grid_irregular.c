/* grid_irregular.c — the irregular grid (slides: "Irregular Grids";
 * Pérard-Gayot, Kalojanov, Slusallek 2017, "GPU Ray Tracing using
 * Irregular Grids").
 *
 * Idea: a fine base grid decides *where* triangles are; afterwards cells
 * are made as large as the geometry allows, so a ray takes few, long steps.
 *
 *  1. Base grid: uniform, power-of-two resolution per axis from the
 *     formula with a high density (the paper builds a two-level base grid;
 *     we keep it uniform — see "limits" below).  Triangles are binned into
 *     voxels with the exact overlap test; each voxel's list is sorted.
 *  2. Merge: neighbouring cells with the *same* set of triangles become one
 *     box ("as long as no change in set of primitives").  Sweeps along x,
 *     y, z merge a cell with the next one on that axis when their
 *     cross-sections match and their lists are equal, repeated until
 *     nothing changes.  A cell stays an axis-aligned box of voxels.
 *  3. Expand: each cell also gets a larger *expanded* box, grown one voxel
 *     layer at a time in each of the six directions while every voxel in
 *     the new layer belongs to a cell whose triangles are a subset of this
 *     cell's ("as long as neighbours contain only subset of cell's
 *     primitives").  Triangles are not added: the expanded box only tells
 *     the traversal how far it may jump.
 *
 * Traversal: find the voxel of the entry point, look its cell up in the
 * voxel map, test the cell's triangles, then jump to where the ray leaves
 * the cell's *expanded* box.  This is exact: every point the ray passes up
 * to that exit lies in cells whose triangles were all just tested (or in
 * earlier cells), so a hit at or before the exit is the closest one.  The
 * next voxel is the one across the exit face; on the other axes it is
 * where the exit point lies, never behind the current voxel (so the walk
 * always advances, whatever the rounding).
 *
 * Limits: the map holds one 32-bit cell id per voxel ("approach needs more
 * memory"); a uniform base grid does not adapt to the teapot in a stadium
 * the way the paper's hierarchical one does; expansion is capped at
 * IRR_MAX_EXPAND voxels per direction to bound build time. */
#include "grid_internal.h"

/* Voxels per triangle of the base grid (finer than grid.c's λ = 4: merging
 * removes the cost of the extra empty cells). */
#define IRR_DEFAULT_DENSITY 8.0f
#define IRR_MAX_RES 256u          /* per axis, a power of two; fits uint16 */
#define IRR_MAX_VOXELS (1u << 21) /* 8 MiB of map */
#define IRR_MAX_EXPAND 16u

typedef struct icell {
    uint16_t lo[3], hi[3];   /* own box in voxels, [lo, hi) */
    uint16_t elo[3], ehi[3]; /* expanded box in voxels */
    uint32_t begin, n;       /* references */
} icell;

typedef struct igrid {
    sidx__grid_geom g;       /* the base grid */
    uint32_t *map;           /* voxel -> cell */
    icell *cells;
    uint32_t *refs;
    uint32_t n_cells, n_refs, empty;
    int mailbox;
} igrid;

static void igrid_free(const sidx_accel *a, igrid *G)
{
    if (!G) return;
    sidx__free(a, G->map);
    sidx__free(a, G->cells);
    sidx__free(a, G->refs);
    sidx__free(a, G);
}

static uint32_t pow2_near(uint32_t r)
{
    /* The power of two nearest to r in log scale. */
    uint32_t p = 1;
    while (p * 2u <= r) p *= 2u;
    return ((double)r / p > (double)(2u * p) / r) ? 2u * p : p;
}

static SIDX_INLINE uint32_t vox_index(const uint32_t res[3], uint32_t x, uint32_t y, uint32_t z)
{
    return (z * res[1] + y) * res[0] + x;
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

static int same_set(const icell *c, const icell *n, const uint32_t *refs)
{
    return c->n == n->n && (c->n == 0 || memcmp(refs + c->begin, refs + n->begin, c->n * sizeof *refs) == 0);
}

/* Merge sweeps: see the file comment.  Cells are identified by their
 * origin voxel (merging only moves hi), so cell c is alive iff map[c] == c. */
static void merge_cells(icell *cells, uint32_t *map, const uint32_t res[3], const uint32_t *vrefs)
{
    const uint32_t nv = res[0] * res[1] * res[2];
    for (int changed = 1; changed;) {
        changed = 0;
        for (int ax = 0; ax < 3; ++ax) {
            const int b = (ax + 1) % 3, c2 = (ax + 2) % 3;
            for (uint32_t v = 0; v < nv; ++v) {
                if (map[v] != v) continue; /* not a live cell's origin */
                icell *c = &cells[v];
                while (c->hi[ax] < res[ax]) {
                    uint32_t p[3] = {c->lo[0], c->lo[1], c->lo[2]};
                    p[ax] = c->hi[ax];
                    const uint32_t nid = map[vox_index(res, p[0], p[1], p[2])];
                    const icell *n = &cells[nid];
                    if (n->lo[b] != c->lo[b] || n->hi[b] != c->hi[b] || n->lo[c2] != c->lo[c2] ||
                        n->hi[c2] != c->hi[c2] || !same_set(c, n, vrefs))
                        break;
                    for (uint32_t z = n->lo[2]; z < n->hi[2]; ++z)
                        for (uint32_t y = n->lo[1]; y < n->hi[1]; ++y)
                            for (uint32_t x = n->lo[0]; x < n->hi[0]; ++x) map[vox_index(res, x, y, z)] = v;
                    c->hi[ax] = n->hi[ax];
                    changed = 1;
                }
            }
        }
    }
}

/* Expansion of cell ci: grow its expanded box layer by layer. */
static void expand_cell(icell *cells, uint32_t ci, const uint32_t *map, const uint32_t res[3], const uint32_t *refs)
{
    icell *c = &cells[ci];
    for (int i = 0; i < 3; ++i) {
        c->elo[i] = c->lo[i];
        c->ehi[i] = c->hi[i];
    }
    for (int dir = 0; dir < 6; ++dir) {
        const int ax = dir >> 1, up = dir & 1;
        const int b = (ax + 1) % 3, c2 = (ax + 2) % 3;
        for (uint32_t grown = 0; grown < IRR_MAX_EXPAND; ++grown) {
            if (up ? c->ehi[ax] >= res[ax] : c->elo[ax] == 0) break;
            const uint32_t layer = up ? c->ehi[ax] : (uint32_t)c->elo[ax] - 1u;
            uint32_t last_ok = ci;
            int ok = 1;
            for (uint32_t u = c->elo[b]; u < c->ehi[b] && ok; ++u)
                for (uint32_t w = c->elo[c2]; w < c->ehi[c2] && ok; ++w) {
                    uint32_t p[3];
                    p[ax] = layer;
                    p[b] = u;
                    p[c2] = w;
                    const uint32_t k = map[vox_index(res, p[0], p[1], p[2])];
                    if (k == last_ok) continue;
                    if (!is_subset(refs + cells[k].begin, cells[k].n, refs + c->begin, c->n)) ok = 0;
                    else last_ok = k;
                }
            if (!ok) break;
            if (up) c->ehi[ax]++;
            else c->elo[ax]--;
        }
    }
}

static sidx_status igrid_build(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    const sidx_hook *hook = a->opt.hook;
    igrid *G = sidx__calloc(a, 1, sizeof *G);
    sidx_aabb *boxes = NULL;
    uint32_t *voff = NULL, *vrefs = NULL, *newid = NULL;
    icell *vcells = NULL;
    if (!G) return sidx__fail(err, SIDX_ERR_NOMEM, "grid-irregular: out of memory");
    G->mailbox = !a->opt.no_mailbox;
    if (m->num_triangles && sidx__prim_boxes(a, &boxes, NULL) != SIDX_OK) goto nomem;

    /* 1. The base grid. */
    const sidx_aabb scene = sidx_mesh_bounds(m);
    const sidx_aabb box = sidx__grid_box(scene);
    const float lambda = a->opt.grid_density > 0.0f ? a->opt.grid_density : IRR_DEFAULT_DENSITY;
    uint32_t res[3];
    sidx__grid_resolution(sidx_aabb_is_empty(scene) ? box : scene, (double)m->num_triangles, lambda, IRR_MAX_RES,
                          IRR_MAX_VOXELS, res);
    for (int i = 0; i < 3; ++i) res[i] = pow2_near(res[i]);
    while ((uint64_t)res[0] * res[1] * res[2] > IRR_MAX_VOXELS) {
        int big = res[1] > res[0] ? 1 : 0;
        if (res[2] > res[big]) big = 2;
        res[big] /= 2u;
    }
    for (int i = 0; i < 3; ++i)
        if (res[i] > IRR_MAX_RES) res[i] = IRR_MAX_RES;
    sidx__grid_geom_init(&G->g, box, res);
    const uint32_t nv = G->g.n_cells;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = box);
    SIDX_EMIT(1, hook, SIDX_EV_NOTE, e_.text = "irregular grid: power-of-two base grid (cell[] = R), then merge, expand";
              e_.cell[0] = (int32_t)res[0]; e_.cell[1] = (int32_t)res[1]; e_.cell[2] = (int32_t)res[2];
              e_.count = nv; e_.cost = lambda);

    voff = sidx__calloc(a, (size_t)nv + 1u, sizeof *voff);
    if (!voff) goto nomem;
    const uint64_t total = sidx__grid_bin(m, boxes, NULL, m->num_triangles, &G->g, 1, voff + 1, NULL);
    if (total > UINT32_MAX) {
        sidx__free(a, voff);
        sidx__free(a, boxes);
        igrid_free(a, G);
        return sidx__fail(err, SIDX_ERR_LIMIT, "grid-irregular: too many references");
    }
    for (uint32_t v = 0; v < nv; ++v) voff[v + 1] += voff[v];
    vrefs = sidx__alloc(a, total, sizeof *vrefs);
    if (!vrefs) goto nomem;
    sidx__grid_bin(m, boxes, NULL, m->num_triangles, &G->g, 1, voff, vrefs);
    memmove(voff + 1, voff, (size_t)nv * sizeof *voff);
    voff[0] = 0;
    sidx__free(a, boxes);
    boxes = NULL;

    /* 2. One cell per voxel, then merge. */
    vcells = sidx__alloc(a, nv, sizeof *vcells);
    G->map = sidx__alloc(a, nv, sizeof *G->map);
    if (!vcells || !G->map) goto nomem;
    for (uint32_t z = 0, v = 0; z < res[2]; ++z)
        for (uint32_t y = 0; y < res[1]; ++y)
            for (uint32_t x = 0; x < res[0]; ++x, ++v) {
                icell *c = &vcells[v];
                c->lo[0] = (uint16_t)x, c->lo[1] = (uint16_t)y, c->lo[2] = (uint16_t)z;
                c->hi[0] = (uint16_t)(x + 1), c->hi[1] = (uint16_t)(y + 1), c->hi[2] = (uint16_t)(z + 1);
                c->begin = voff[v];
                c->n = voff[v + 1] - voff[v];
                G->map[v] = v;
            }
    merge_cells(vcells, G->map, res, vrefs);

    /* Compact: live cells get consecutive ids; their lists are copied. */
    newid = sidx__alloc(a, nv, sizeof *newid);
    if (!newid) goto nomem;
    uint64_t live_refs = 0;
    for (uint32_t v = 0; v < nv; ++v)
        if (G->map[v] == v) {
            newid[v] = G->n_cells++;
            live_refs += vcells[v].n;
        }
    G->cells = sidx__alloc(a, G->n_cells, sizeof *G->cells);
    G->refs = sidx__alloc(a, live_refs, sizeof *G->refs);
    if (!G->cells || !G->refs) goto nomem;
    for (uint32_t v = 0; v < nv; ++v) {
        if (G->map[v] != v) continue;
        icell c = vcells[v];
        if (c.n) memcpy(G->refs + G->n_refs, vrefs + c.begin, (size_t)c.n * sizeof *vrefs);
        c.begin = G->n_refs;
        G->n_refs += c.n;
        G->empty += c.n == 0;
        G->cells[newid[v]] = c;
    }
    for (uint32_t v = 0; v < nv; ++v) G->map[v] = newid[G->map[v]];
    sidx__free(a, newid);
    sidx__free(a, vcells);
    sidx__free(a, vrefs);
    sidx__free(a, voff);
    newid = NULL, vcells = NULL, vrefs = NULL, voff = NULL;

    /* 3. Expand. */
    for (uint32_t c = 0; c < G->n_cells; ++c) expand_cell(G->cells, c, G->map, res, G->refs);

    if (sidx__hook_wants(hook, SIDX_EV_BUILD_NODE)) {
        for (uint32_t c = 0; c < G->n_cells; ++c) {
            const icell *ic = &G->cells[c];
            if (!ic->n) continue;
            sidx_aabb bb = sidx__grid_cell_bounds(&G->g, ic->lo[0], ic->lo[1], ic->lo[2]);
            bb.max = sidx__grid_cell_bounds(&G->g, ic->hi[0] - 1u, ic->hi[1] - 1u, ic->hi[2] - 1u).max;
            SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = c; e_.depth = 0; e_.count = ic->n; e_.bounds = bb;
                      e_.cell[0] = ic->lo[0]; e_.cell[1] = ic->lo[1]; e_.cell[2] = ic->lo[2]);
        }
    }
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_END, e_.node = G->n_cells; e_.count = G->n_refs; e_.depth = 0);
    a->impl = G;
    return SIDX_OK;
nomem:
    sidx__free(a, boxes);
    sidx__free(a, voff);
    sidx__free(a, vrefs);
    sidx__free(a, vcells);
    sidx__free(a, newid);
    igrid_free(a, G);
    return sidx__fail(err, SIDX_ERR_NOMEM, "grid-irregular: out of memory");
}

static SIDX_INLINE int igrid_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                  const int traced, const int any, const int use_mb)
{
    const igrid *G = a->impl;
    float t0, t1;
    if (!sidx__clip(a, r, &G->g.box, hit->t, &t0, &t1)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.t = hit->t; e_.count = 0);
        return 0;
    }
    const float *o = &r->org.x, *dir = &r->dir.x, *inv = &r->inv_dir.x;
    const float *bmin = &G->g.box.min.x, *vs = &G->g.cell.x, *ivs = &G->g.inv_cell.x;
    const uint32_t *res = G->g.res;
    float off[3];
    int32_t v[3];
    for (int i = 0; i < 3; ++i) {
        off[i] = bmin[i] - o[i];
        const float f = floorf((o[i] + t0 * dir[i] - bmin[i]) * ivs[i]);
        v[i] = !(f >= 0.0f) ? 0 : f >= (float)res[i] ? (int32_t)res[i] - 1 : (int32_t)f;
    }
    sidx__mailbox mb;
    if (use_mb) sidx__mailbox_clear(&mb);
    uint32_t visited = 0;
    float t = t0;
    int reason;
    for (;;) {
        const uint32_t ci = G->map[vox_index(res, (uint32_t)v[0], (uint32_t)v[1], (uint32_t)v[2])];
        const icell *c = &G->cells[ci];
        /* Exit of the expanded box: on each moving axis, the face ahead. */
        float t_exit = INFINITY;
        int k = 0;
        for (int i = 0; i < 3; ++i) {
            if (dir[i] == 0.0f) continue;
            const uint32_t face = dir[i] > 0.0f ? c->ehi[i] : c->elo[i];
            const float ti = ((float)face * vs[i] + off[i]) * inv[i];
            if (ti < t_exit) { t_exit = ti; k = i; }
        }
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = ci; e_.depth = 0;
                  e_.t_near = t; e_.t_far = t_exit; e_.cell[0] = v[0]; e_.cell[1] = v[1]; e_.cell[2] = v[2]);
        if (sidx__cell_prims(a, r, q, hit, G->refs + c->begin, c->n, ci, 0, &mb, use_mb, traced, any)) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.count = visited);
            return 1;
        }
        if (hit->t <= t_exit) {
            reason = hit->prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL : SIDX_TERM_LEFT_GRID;
            break;
        }
        /* The voxel across the exit face... */
        const int32_t nk = dir[k] > 0.0f ? (int32_t)c->ehi[k] : (int32_t)c->elo[k] - 1;
        if (nk < 0 || nk >= (int32_t)res[k]) {
            reason = SIDX_TERM_LEFT_GRID;
            break;
        }
        /* ...and on the other axes where the exit point lies, kept inside
         * the expanded box and never behind the current voxel. */
        for (int i = 0; i < 3; ++i) {
            if (i == k || dir[i] == 0.0f) continue;
            const float f = floorf((o[i] + t_exit * dir[i] - bmin[i]) * ivs[i]);
            int32_t n = !(f >= (float)c->elo[i]) ? (int32_t)c->elo[i]
                        : f >= (float)c->ehi[i] ? (int32_t)c->ehi[i] - 1
                                                : (int32_t)f;
            if (dir[i] > 0.0f ? n < v[i] : n > v[i]) n = v[i];
            v[i] = n;
        }
        v[k] = nk;
        if (t_exit > t) t = t_exit;
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = reason; e_.t = hit->t;
              e_.count = visited);
    (void)reason;
    (void)visited;
    (void)t1;
    return 0;
}

static void igrid_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    const igrid *G = a->impl;
    if (SIDX_QUERY_TRACED(q)) {
        if (G->mailbox) igrid_walk(a, r, q, hit, 1, 0, 1);
        else igrid_walk(a, r, q, hit, 1, 0, 0);
    } else {
        if (G->mailbox) igrid_walk(a, r, q, hit, 0, 0, 1);
        else igrid_walk(a, r, q, hit, 0, 0, 0);
    }
}

static int igrid_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    const igrid *G = a->impl;
    sidx_hit h = sidx_hit_none();
    h.t = r->tmax;
    if (SIDX_QUERY_TRACED(q))
        return G->mailbox ? igrid_walk(a, r, q, &h, 1, 1, 1) : igrid_walk(a, r, q, &h, 1, 1, 0);
    return G->mailbox ? igrid_walk(a, r, q, &h, 0, 1, 1) : igrid_walk(a, r, q, &h, 0, 1, 0);
}

static void igrid_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const igrid *G = a->impl;
    s->nodes = G->n_cells;
    s->leaves = G->n_cells;
    s->max_depth = 0;
    s->prim_refs = G->n_refs;
    s->bytes = sizeof *G + (size_t)G->g.n_cells * sizeof *G->map + (size_t)G->n_cells * sizeof *G->cells +
               (size_t)G->n_refs * sizeof *G->refs;
    s->empty_leaves = G->empty;
    const uint32_t full = G->n_cells - G->empty;
    s->mean_leaf_prims = full ? (double)G->n_refs / (double)full : 0.0;
    s->res[0] = G->g.res[0];
    s->res[1] = G->g.res[1];
    s->res[2] = G->g.res[2];
}

static void igrid_destroy(sidx_accel *a)
{
    igrid_free(a, a->impl);
    a->impl = NULL;
}

const sidx_accel_vtable sidx__grid_irregular_vtable = {igrid_build, igrid_intersect, igrid_occluded,
                                                       igrid_stats, igrid_destroy, NULL};
