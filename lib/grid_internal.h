/* grid_internal.h — what the space-partitioning family shares (not public):
 * grid.c (uniform grid), grid2.c (two-level grid), grid_irregular.c
 * (irregular grid) and octree.c (octree / quadtree).
 *
 *  1. the resolution formula of the slides, R = d·∛(λn/V) per axis;
 *  2. the exact triangle–box overlap test (Akenine-Möller 2001);
 *  3. binning triangles into the cells of a uniform grid (count, then fill);
 *  4. the 3D-DDA of Amanatides & Woo 1987;
 *  5. the per-ray mailbox and the primitive loop every cell runs;
 *  6. the walk tables: each structure's walk, copied per query kind.
 *
 * SIDX_STRUCTURE_NAME is defined here for the whole family as `(a->name)`,
 * the registered name (static), so "grid" and "grid-nomailbox" report
 * themselves apart.  Every function that emits needs `a` in scope. */
#ifndef SIDX_GRID_INTERNAL_H
#define SIDX_GRID_INTERNAL_H

#include "sidx_internal.h"

#define SIDX_STRUCTURE_NAME (a->name)

/* ---- 1. geometry of a uniform grid ------------------------------------ */

/* Per-axis resolution cap and total-cell cap.  A cell costs 4 bytes of
 * offsets even when empty, so 2^24 cells = 64 MiB is where we stop. */
#define SIDX__GRID_MAX_RES 512u
#define SIDX__GRID_MAX_CELLS (1u << 24)

typedef struct sidx__grid_geom {
    sidx_aabb box;          /* the grid box (flat axes padded, see sidx__grid_box) */
    sidx_vec3 cell;         /* cell size per axis */
    sidx_vec3 inv_cell;     /* 1 / cell size */
    uint32_t res[3];
    uint32_t n_cells;
} sidx__grid_geom;

/* The box a grid is laid over: the scene box, with every axis of (nearly)
 * zero extent padded so a flat scene still has cells of non-zero size and
 * the DDA never divides by zero. */
sidx_aabb sidx__grid_box(sidx_aabb scene);

/* The slides' formula R_i = d_i·∛(λn/V), rounded to nearest, clamped to
 * [1, max_res] and scaled down until the product is <= max_cells.  Axes of
 * negligible extent get one cell and the root is taken over the remaining
 * k axes (R_i = d_i·(λn/V_k)^(1/k)), the same formula in k dimensions. */
void sidx__grid_resolution(sidx_aabb box, double n, double lambda, uint32_t max_res, uint32_t max_cells,
                           uint32_t res[3]);

/* Fills g from a box and a resolution. */
void sidx__grid_geom_init(sidx__grid_geom *g, sidx_aabb box, const uint32_t res[3]);

/* Bounds of cell (x, y, z): computed as min + i·size, the same arithmetic
 * the DDA uses for its boundaries. */
sidx_aabb sidx__grid_cell_bounds(const sidx__grid_geom *g, uint32_t x, uint32_t y, uint32_t z);

/* ---- 2. triangle–box overlap ------------------------------------------ */

/* Akenine-Möller 2001, "Fast 3D Triangle-Box Overlap Testing": the
 * separating axis theorem with 13 axes — the 3 box normals, the triangle
 * normal, and the 9 cross products of box axes with triangle edges.  If no
 * axis separates the projections, they overlap.  `half` should already be
 * padded (sidx__overlap_pad) so the float test errs on the side of overlap:
 * a missed overlap would be a missed hit, an extra one only a wasted test. */
int sidx__tri_box_overlap(sidx_vec3 center, sidx_vec3 half, sidx_vec3 v0, sidx_vec3 v1, sidx_vec3 v2);

/* Half-size padded by a relative epsilon of the cell and of the
 * coordinates' magnitude (rounding in v − c grows with |c|). */
sidx_vec3 sidx__overlap_pad(sidx_vec3 center, sidx_vec3 half);

/* Copies to out[] those of in[0..n) (triangle ids of m, boxes in
 * tri_boxes) that overlap `cell`: the cheap box rejection first, then the
 * exact test above on the padded cell.  Returns how many were kept.  in
 * and out must not overlap.  Shared by the octree and the irregular grid,
 * which both distribute a cell's triangles over its children. */
uint32_t sidx__clip_to_cell(const sidx_mesh *m, const sidx_aabb *tri_boxes, const uint32_t *in, uint32_t n,
                            sidx_aabb cell, uint32_t *out);

/* ---- 3. binning ------------------------------------------------------- */

/* Inserts triangles ids[0..n) (ids NULL = 0..n-1) into every cell of grid g
 * their box overlaps, and when `exact` only into those the triangle itself
 * overlaps (the SAT test above).
 * counts != NULL and refs == NULL: counts[cell]++ per reference (pass 1);
 * refs != NULL: refs[counts[cell]++] = prim, counts holding each cell's
 * write cursor (pass 2).  Returns the number of references. */
uint64_t sidx__grid_bin(const sidx_mesh *m, const sidx_aabb *tri_boxes, const uint32_t *ids, uint32_t n,
                        const sidx__grid_geom *g, int exact, uint32_t *counts, uint32_t *refs);

/* ---- 4. the 3D-DDA ------------------------------------------------------ */

/* Amanatides & Woo 1987, "A Fast Voxel Traversal Algorithm for Ray
 * Tracing".  Per axis: step = ±1 (0 for a ±0 direction component),
 * t_max = the t at which the ray crosses the next cell boundary on that
 * axis, t_delta = size·|1/d| = the t it takes to cross one cell.  Each step
 * moves along the axis whose t_max is smallest.
 *
 * Instead of accumulating t_max += t_delta (one rounding per step, drifting
 * over a 512-cell walk, and with cancellation for rays starting inside),
 * boundary k is reached at t = (k·size + (min − o))·(1/d): the boundary's
 * position is computed exactly as the build computed the cell boxes, so the
 * DDA and the overlap test agree on where a cell ends, up to one rounding
 * of the coordinates (which the overlap test's padding absorbs).  Same cost:
 * one multiply-add and one multiply per step. */
typedef struct sidx__dda {
    int32_t c[3];         /* current cell */
    int32_t step[3];      /* +1, -1, or 0 (never step on an axis the ray does not move along) */
    int32_t stop[3];      /* the cell index one past the grid in the step direction */
    int32_t up[3];        /* 1 when stepping up: the next boundary is c + 1, else c */
    float t_max[3];       /* t of the next boundary per axis; +inf for a ±0 component */
    float off[3];         /* min − o per axis */
    float size[3];        /* cell size per axis */
    float inv[3];         /* 1/d per axis */
} sidx__dda;

/* Sets up the walk from parameter t_enter (the clipped entry into g.box, or
 * tmin for a ray starting inside).  The start cell is the one holding the
 * point o + t_enter·d, clamped into the grid (rounding at the entry face).
 * A ±0 component gives step 0 and t_max = +inf: the slab never changes,
 * and no 0·inf = NaN ever enters a comparison. */
static SIDX_INLINE void sidx__dda_init(sidx__dda *d, const sidx_ray *r, const sidx__grid_geom *g, float t_enter)
{
    const float *o = sidx_v3_array(&r->org), *dir = sidx_v3_array(&r->dir), *inv = sidx_v3_array(&r->inv_dir);
    const float *bmin = sidx_v3_array(&g->box.min), *cs = sidx_v3_array(&g->cell), *ic = sidx_v3_array(&g->inv_cell);
    for (int i = 0; i < 3; ++i) {
        const int32_t res = (int32_t)g->res[i];
        const float p = o[i] + t_enter * dir[i];
        float fc = floorf((p - bmin[i]) * ic[i]);
        /* !(fc >= 0) also catches NaN, never cast to int. */
        int32_t c = !(fc >= 0.0f) ? 0 : fc >= (float)res ? res - 1 : (int32_t)fc;
        d->c[i] = c;
        if (dir[i] == 0.0f) {
            d->step[i] = 0;
            d->stop[i] = -2; /* never reached */
            d->up[i] = 0;
            d->off[i] = d->size[i] = d->inv[i] = 0.0f;
            d->t_max[i] = INFINITY;
        } else {
            const int pos = dir[i] > 0.0f;
            d->step[i] = pos ? 1 : -1;
            d->stop[i] = pos ? res : -1;
            d->up[i] = pos;
            d->off[i] = bmin[i] - o[i];
            d->size[i] = cs[i];
            d->inv[i] = inv[i];
            d->t_max[i] = ((float)(c + pos) * cs[i] + d->off[i]) * inv[i];
        }
    }
}

/* Axis of the smallest t_max: the face the ray leaves the cell through. */
static SIDX_INLINE int sidx__dda_axis(const sidx__dda *d)
{
    return d->t_max[0] < d->t_max[1] ? (d->t_max[0] < d->t_max[2] ? 0 : 2) : (d->t_max[1] < d->t_max[2] ? 1 : 2);
}

/* Moves one cell along `axis`; returns 0 when the walk left the grid. */
static SIDX_INLINE int sidx__dda_step(sidx__dda *d, int axis)
{
    const int32_t c = d->c[axis] + d->step[axis];
    if (c == d->stop[axis]) return 0;
    d->c[axis] = c;
    d->t_max[axis] = ((float)(c + d->up[axis]) * d->size[axis] + d->off[axis]) * d->inv[axis];
    return 1;
}

/* ---- 5. mailbox and the per-cell primitive loop ------------------------- */

/* Mailboxing (slides: "Per-ray cache of object IDs — data local to a ray
 * (better!)").  A triangle spanning k cells would otherwise be tested up to
 * k times by one ray.  The classic variant (Amanatides & Woo) stores in
 * every *triangle* the id of the last ray that tested it; with several
 * threads tracing at once, two rays overwrite each other's id in the shared
 * triangle (a write to shared memory per test, and lost skips or cache-line
 * ping-pong), and the structure stops being immutable.  The slides' fix:
 * keep the cache with the ray.  Ours is a small direct-mapped table on the
 * stack, indexed by prim mod size: no allocation, a collision only evicts
 * an entry (a re-test, never a wrong answer).  Skipping is exact: a
 * triangle tested earlier against a larger or equal bound either became the
 * current hit or lies beyond it. */
#define SIDX__MAILBOX_SIZE 32u /* power of two; 128 bytes per ray */
typedef struct sidx__mailbox { uint32_t id[SIDX__MAILBOX_SIZE]; } sidx__mailbox;

static SIDX_INLINE void sidx__mailbox_clear(sidx__mailbox *mb) { memset(mb->id, 0xff, sizeof mb->id); }

/* 1 if prim was tested for this ray already; else records it. */
static SIDX_INLINE int sidx__mailbox_seen(sidx__mailbox *mb, uint32_t prim)
{
    uint32_t *slot = &mb->id[prim & (SIDX__MAILBOX_SIZE - 1u)];
    if (*slot == prim) return 1;
    *slot = prim;
    return 0;
}

/* Tests refs[0..n) of cell `node`.  Closest hit (any = 0): updates *hit
 * (accepting t < hit->t) and returns 0.  Any hit (any = 1): returns 1 at
 * the first hit.  use_mb selects mailboxing. */
static SIDX_INLINE int sidx__cell_prims(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                        const uint32_t *refs, uint32_t n, uint32_t node, uint32_t depth,
                                        sidx__mailbox *mb, const int use_mb, const int traced, const int any)
{
    const sidx_mesh *m = a->mesh;
    const sidx_tri_method method = a->opt.tri;
    (void)node; /* event fields only */
    (void)depth;
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t prim = refs[k];
        if (use_mb && sidx__mailbox_seen(mb, prim)) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_MAILBOX_HIT, e_.ray_id = q->ray_id; e_.prim = prim; e_.node = node;
                      e_.depth = depth);
            continue;
        }
        float t;
        const int h = sidx__mesh_tri_test(m, method, prim, r, hit->t, &t);
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.prim = prim; e_.node = node;
                  e_.depth = depth; e_.result = h; e_.t = h ? t : INFINITY);
        if (h) {
            if (any) return 1;
            hit->t = t;
            hit->prim = prim;
            SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = prim; e_.node = node;
                      e_.depth = depth; e_.t = t);
        }
    }
    return 0;
}

/* Clips the ray segment [tmin, tmax] to a box with the build's box test. */
static SIDX_INLINE int sidx__clip(const sidx_accel *a, const sidx_ray *r, const sidx_aabb *box, float tmax,
                                  float *t0, float *t1)
{
    return sidx__box_test(a->opt.box == SIDX_BOX_ROBUST, r, box, r->tmin, tmax, t0, t1);
}

/* ---- 6. walk tables (sidx_internal.h §1) ------------------------------- */

/* Each structure of the family writes its walk once,
 *   static SIDX_INLINE int WALK(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
 *                               const int traced, const int any, const int use_mb)
 * — closest hit (any = 0: updates *hit) or any hit (any = 1: returns 1 at
 * the first hit), with or without the mailbox — and
 * SIDX__GRID_WALK_TABLES(WALK, TABLES) makes its eight copies and
 * `TABLES[2]`, the walk tables without (0) and with (1) the mailbox.  The
 * build stores a pointer to TABLES[mailbox]; a query then only picks the
 * traced or the plain copy.  An any-hit copy starts from a blank hit bounded by tmax.
 * Like every walk, none tests q for NULL. */
#define SIDX__GRID_WALK_INTERSECT(name_, walk_, traced_, use_mb_)                                              \
    static void name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)             \
    {                                                                                                           \
        (void)walk_(a, r, q, hit, traced_, 0, use_mb_);                                                         \
    }
#define SIDX__GRID_WALK_OCCLUDED(name_, walk_, traced_, use_mb_)                                               \
    static int name_(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)                              \
    {                                                                                                           \
        sidx_hit h = sidx_hit_none();                                                                           \
        h.t = r->tmax;                                                                                          \
        return walk_(a, r, q, &h, traced_, 1, use_mb_);                                                         \
    }
#define SIDX__GRID_WALK_TABLES(walk_, tables_)                                                                 \
    SIDX__GRID_WALK_INTERSECT(walk_##_intersect, walk_, 0, 0)                                                  \
    SIDX__GRID_WALK_INTERSECT(walk_##_intersect_traced, walk_, 1, 0)                                           \
    SIDX__GRID_WALK_OCCLUDED(walk_##_occluded, walk_, 0, 0)                                                    \
    SIDX__GRID_WALK_OCCLUDED(walk_##_occluded_traced, walk_, 1, 0)                                             \
    SIDX__GRID_WALK_INTERSECT(walk_##_intersect_mb, walk_, 0, 1)                                               \
    SIDX__GRID_WALK_INTERSECT(walk_##_intersect_mb_traced, walk_, 1, 1)                                        \
    SIDX__GRID_WALK_OCCLUDED(walk_##_occluded_mb, walk_, 0, 1)                                                 \
    SIDX__GRID_WALK_OCCLUDED(walk_##_occluded_mb_traced, walk_, 1, 1)                                          \
    static const sidx__walk_table tables_[2] = {                                                                \
        {walk_##_intersect, walk_##_intersect_traced, walk_##_occluded, walk_##_occluded_traced},               \
        {walk_##_intersect_mb, walk_##_intersect_mb_traced, walk_##_occluded_mb, walk_##_occluded_mb_traced},   \
    }

#endif
