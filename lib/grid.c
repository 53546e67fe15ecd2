/* grid.c — the uniform grid (slides: "Uniform Grids"), and the pieces the
 * other grids and the octree share (grid_internal.h).
 *
 * Build: R = d·∛(λn/V) cells per axis, every triangle referenced from each
 * cell it overlaps, stored compactly as n_cells + 1 offsets into one array
 * of triangle indices (count, prefix-sum, fill — no per-cell lists).
 * Traversal: clip the ray to the grid box, then walk the cells it pierces
 * in order with the 3D-DDA (Amanatides & Woo 1987), testing each cell's
 * triangles; a hit that lies inside the current cell ends the walk (slides,
 * spatial vs primitive partitioning: "[+] can terminate on first hit").
 *
 * Variants (registry): 0 "grid" (exact SAT insertion, mailbox),
 * 1 "grid-nomailbox", 2 "grid-boxonly" (insert by triangle bounding box). */
#include "grid_internal.h"

#define GRID_VARIANT_NOMAILBOX 1
#define GRID_VARIANT_BOXONLY 2

/* λ, cells per triangle: denser grids test fewer triangles per ray but
 * walk more empty cells, and above λ ≈ 8 the cells cost more than the
 * tests they save; 4 was the fastest on the bunny (figures:
 * docs/performance.md, Grids). */
#define GRID_DEFAULT_DENSITY 4.0f

/* ---- shared geometry (grid_internal.h §1) ------------------------------- */

sidx_aabb sidx__grid_box(sidx_aabb scene)
{
    if (sidx_aabb_is_empty(scene)) scene.min = scene.max = sidx_v3(0.0f, 0.0f, 0.0f);
    const sidx_vec3 e = sidx_aabb_extent(scene);
    float emax = fmaxf(e.x, fmaxf(e.y, e.z));
    const float mag = fmaxf(fmaxf(fabsf(scene.min.x), fabsf(scene.max.x)),
                            fmaxf(fmaxf(fabsf(scene.min.y), fabsf(scene.max.y)),
                                  fmaxf(fabsf(scene.min.z), fabsf(scene.max.z))));
    /* A flat axis gets a slab 1e-3 of the largest extent thick (or of the
     * coordinates' size for a scene collapsed to a point), never thinner
     * than a few ulps of the coordinates. */
    float pad = emax > 0.0f ? 1e-3f * emax : (mag > 0.0f ? 1e-3f * mag : 1.0f);
    if (pad < 1e-5f * mag) pad = 1e-5f * mag;
    float *lo = sidx_v3_array_rw(&scene.min), *hi = sidx_v3_array_rw(&scene.max);
    for (int i = 0; i < 3; ++i)
        if (hi[i] - lo[i] <= 1e-6f * emax || hi[i] - lo[i] <= 8.0f * FLT_EPSILON * mag) {
            lo[i] -= pad;
            hi[i] += pad;
        }
    return scene;
}

void sidx__grid_resolution(sidx_aabb box, double n, double lambda, uint32_t max_res, uint32_t max_cells,
                           uint32_t res[3])
{
    const sidx_vec3 ev = sidx_aabb_extent(box);
    const double e[3] = {ev.x, ev.y, ev.z};
    const double emax = fmax(e[0], fmax(e[1], e[2]));
    /* Cells must stay well above the float spacing of the coordinates
     * (a scene at 1e6 has an ulp of 0.06): cells of at least ~32 ulps. */
    const double mag = fmax(fmax(fmax(fabs(box.min.x), fabs(box.max.x)), fmax(fabs(box.min.y), fabs(box.max.y))),
                            fmax(fabs(box.min.z), fabs(box.max.z)));
    const double min_cell = 16.0 * FLT_EPSILON * mag;
    /* Axes thinner than 1e-6 of the largest are "flat": one cell, and the
     * volume is measured over the others (V_k, k-th root). */
    double vol = 1.0;
    int dims = 0;
    for (int i = 0; i < 3; ++i)
        if (e[i] > 1e-6 * emax) { vol *= e[i]; ++dims; }
    double s = (dims > 0 && vol > 0.0 && n > 0.0) ? pow(lambda * n / vol, 1.0 / dims) : 0.0;
    for (;;) {
        double total = 1.0;
        for (int i = 0; i < 3; ++i) {
            double r = (e[i] > 1e-6 * emax) ? floor(e[i] * s + 0.5) : 1.0;
            if (min_cell > 0.0 && r > e[i] / min_cell) r = floor(e[i] / min_cell);
            if (!(r >= 1.0)) r = 1.0;
            if (r > (double)max_res) r = (double)max_res;
            res[i] = (uint32_t)r;
            total *= r;
        }
        if (total <= (double)max_cells) break;
        /* Too many cells: shrink the density uniformly and try again. */
        s *= cbrt((double)max_cells / total) * 0.999;
    }
}

void sidx__grid_geom_init(sidx__grid_geom *g, sidx_aabb box, const uint32_t res[3])
{
    g->box = box;
    const sidx_vec3 e = sidx_aabb_extent(box);
    g->res[0] = res[0];
    g->res[1] = res[1];
    g->res[2] = res[2];
    g->cell = sidx_v3(e.x / (float)res[0], e.y / (float)res[1], e.z / (float)res[2]);
    g->inv_cell = sidx_v3(1.0f / g->cell.x, 1.0f / g->cell.y, 1.0f / g->cell.z);
    g->n_cells = res[0] * res[1] * res[2];
}

sidx_aabb sidx__grid_cell_bounds(const sidx__grid_geom *g, uint32_t x, uint32_t y, uint32_t z)
{
    sidx_aabb b;
    b.min = sidx_v3((float)x * g->cell.x + g->box.min.x, (float)y * g->cell.y + g->box.min.y,
                    (float)z * g->cell.z + g->box.min.z);
    b.max = sidx_v3((float)(x + 1) * g->cell.x + g->box.min.x, (float)(y + 1) * g->cell.y + g->box.min.y,
                    (float)(z + 1) * g->cell.z + g->box.min.z);
    return b;
}

/* ---- triangle–box overlap (grid_internal.h §2) ------------------------- */

static SIDX_INLINE sidx_vec3 pad_half(sidx_vec3 c, sidx_vec3 h)
{
    const float hmax = h.x > h.y ? (h.x > h.z ? h.x : h.z) : (h.y > h.z ? h.y : h.z);
    const float ax = fabsf(c.x), ay = fabsf(c.y), az = fabsf(c.z);
    const float mag = (ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az)) + hmax;
    /* 1e-4 of the cell covers the DDA's boundary rounding; 1e-6 of the
     * coordinates covers the rounding of the projections below. */
    const float eps = 1e-4f * hmax + 1e-6f * mag;
    return sidx_v3(h.x + eps, h.y + eps, h.z + eps);
}

/* Plain min/max: the inputs are finite, so fminf's NaN rules (and its
 * libm call at -O2) are not needed. */
static SIDX_INLINE float min3(float a, float b, float c)
{
    const float m = a < b ? a : b;
    return m < c ? m : c;
}
static SIDX_INLINE float max3(float a, float b, float c)
{
    const float m = a > b ? a : b;
    return m > c ? m : c;
}

sidx_vec3 sidx__overlap_pad(sidx_vec3 c, sidx_vec3 h) { return pad_half(c, h); }

/* One of the nine edge axes: does it separate the triangle (projected to
 * p0, p1, p2) from the box (projected radius rad)? */
static SIDX_INLINE int separated(float p0, float p1, float p2, float rad)
{
    return min3(p0, p1, p2) > rad || max3(p0, p1, p2) < -rad;
}

static SIDX_INLINE int tri_box_overlap(sidx_vec3 c, sidx_vec3 h, sidx_vec3 v0, sidx_vec3 v1, sidx_vec3 v2)
{
    /* Move the box to the origin. */
    const sidx_vec3 a = sidx_v3_sub(v0, c), b = sidx_v3_sub(v1, c), d = sidx_v3_sub(v2, c);
    /* 3 box normals = the triangle's bounding box against the box. */
    if (min3(a.x, b.x, d.x) > h.x || max3(a.x, b.x, d.x) < -h.x) return 0;
    if (min3(a.y, b.y, d.y) > h.y || max3(a.y, b.y, d.y) < -h.y) return 0;
    if (min3(a.z, b.z, d.z) > h.z || max3(a.z, b.z, d.z) < -h.z) return 0;
    /* 9 axes e_i × f_j (box axis × triangle edge).  For the x axis and edge
     * f the axis is (0, −f.z, f.y); its box radius h.y|f.z| + h.z|f.y|. */
    const sidx_vec3 f[3] = {sidx_v3_sub(b, a), sidx_v3_sub(d, b), sidx_v3_sub(a, d)};
    for (int j = 0; j < 3; ++j) {
        const sidx_vec3 e = f[j];
        const float fx = fabsf(e.x), fy = fabsf(e.y), fz = fabsf(e.z);
        /* x × f = (0, −f.z, f.y) */
        if (separated(-e.z * a.y + e.y * a.z, -e.z * b.y + e.y * b.z, -e.z * d.y + e.y * d.z, h.y * fz + h.z * fy))
            return 0;
        /* y × f = (f.z, 0, −f.x) */
        if (separated(e.z * a.x - e.x * a.z, e.z * b.x - e.x * b.z, e.z * d.x - e.x * d.z, h.x * fz + h.z * fx))
            return 0;
        /* z × f = (−f.y, f.x, 0) */
        if (separated(-e.y * a.x + e.x * a.y, -e.y * b.x + e.x * b.y, -e.y * d.x + e.x * d.y, h.x * fy + h.y * fx))
            return 0;
    }
    /* The triangle's plane n·x = n·a against the box: the box's projected
     * radius on n is h·|n|. */
    const sidx_vec3 n = sidx_v3_cross(f[0], f[1]);
    const float dist = sidx_v3_dot(n, a);
    const float rad = h.x * fabsf(n.x) + h.y * fabsf(n.y) + h.z * fabsf(n.z);
    return fabsf(dist) <= rad;
}

int sidx__tri_box_overlap(sidx_vec3 c, sidx_vec3 h, sidx_vec3 v0, sidx_vec3 v1, sidx_vec3 v2)
{
    return tri_box_overlap(c, h, v0, v1, v2);
}

uint32_t sidx__clip_to_cell(const sidx_mesh *m, const sidx_aabb *tri_boxes, const uint32_t *in, uint32_t n,
                            sidx_aabb cell, uint32_t *out)
{
    const sidx_vec3 c = sidx_aabb_centroid(cell);
    const sidx_vec3 half = sidx__overlap_pad(c, sidx_v3_scale(sidx_aabb_extent(cell), 0.5f));
    uint32_t w = 0;
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t prim = in[k];
        const sidx_aabb tb = tri_boxes[prim];
        if (tb.min.x > c.x + half.x || tb.max.x < c.x - half.x || tb.min.y > c.y + half.y ||
            tb.max.y < c.y - half.y || tb.min.z > c.z + half.z || tb.max.z < c.z - half.z)
            continue;
        if (!sidx__tri_box_overlap(c, half, sidx_mesh_vertex(m, prim, 0), sidx_mesh_vertex(m, prim, 1),
                                   sidx_mesh_vertex(m, prim, 2)))
            continue;
        out[w++] = prim;
    }
    return w;
}

/* ---- binning (grid_internal.h §3) ------------------------------------- */

static int32_t clamp_cell(float f, uint32_t res)
{
    if (!(f >= 0.0f)) return 0;
    if (f >= (float)res) return (int32_t)res - 1;
    return (int32_t)f;
}

uint64_t sidx__grid_bin(const sidx_mesh *m, const sidx_aabb *tri_boxes, const uint32_t *ids, uint32_t n,
                        const sidx__grid_geom *g, int exact, uint32_t *counts, uint32_t *refs)
{
    uint64_t total = 0;
    const float *gmin = sidx_v3_array(&g->box.min), *ic = sidx_v3_array(&g->inv_cell), *cs = sidx_v3_array(&g->cell);
    const sidx_vec3 half = sidx_v3_scale(g->cell, 0.5f);
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t prim = ids ? ids[k] : k;
        const sidx_aabb tb = tri_boxes[prim];
        const float *bl = sidx_v3_array(&tb.min), *bh = sidx_v3_array(&tb.max);
        int32_t lo[3], hi[3];
        for (int i = 0; i < 3; ++i) {
            /* A box touching a boundary (within 1e-4 of a cell) goes on
             * both sides, as the exact test's padding would. */
            const float slack = 1e-4f * cs[i];
            lo[i] = clamp_cell(floorf((bl[i] - gmin[i] - slack) * ic[i]), g->res[i]);
            hi[i] = clamp_cell(floorf((bh[i] - gmin[i] + slack) * ic[i]), g->res[i]);
        }
        /* A triangle inside a single cell needs no exact test. */
        const int single = lo[0] == hi[0] && lo[1] == hi[1] && lo[2] == hi[2];
        sidx_vec3 v0 = {0, 0, 0}, v1 = v0, v2 = v0;
        if (exact && !single) {
            v0 = sidx_mesh_vertex(m, prim, 0);
            v1 = sidx_mesh_vertex(m, prim, 1);
            v2 = sidx_mesh_vertex(m, prim, 2);
        }
        for (int32_t z = lo[2]; z <= hi[2]; ++z)
            for (int32_t y = lo[1]; y <= hi[1]; ++y)
                for (int32_t x = lo[0]; x <= hi[0]; ++x) {
                    if (exact && !single) {
                        const sidx_aabb cb = sidx__grid_cell_bounds(g, (uint32_t)x, (uint32_t)y, (uint32_t)z);
                        const sidx_vec3 c = sidx_aabb_centroid(cb);
                        if (!tri_box_overlap(c, pad_half(c, half), v0, v1, v2)) continue;
                    }
                    const uint32_t cell = ((uint32_t)z * g->res[1] + (uint32_t)y) * g->res[0] + (uint32_t)x;
                    if (refs) refs[counts[cell]++] = prim;
                    else if (counts) counts[cell]++;
                    ++total;
                }
    }
    return total;
}

/* ---- the uniform grid ------------------------------------------------- */

typedef struct grid {
    sidx__grid_geom g;
    uint32_t *offsets;  /* n_cells + 1: cell c holds refs[offsets[c] .. offsets[c+1]) */
    uint32_t *refs;     /* original triangle indices */
    uint32_t n_refs;
    uint32_t empty;     /* cells without triangles */
    const sidx__walk_table *walks; /* with or without the mailbox (build) */
} grid;

/* Its walk tables, without and with the mailbox (defined after the walk). */
static const sidx__walk_table grid_walks[2];

static void grid_free(const sidx_accel *a, grid *G)
{
    if (!G) return;
    sidx__free(a, G->offsets);
    sidx__free(a, G->refs);
    sidx__free(a, G);
}

static sidx_status grid_build(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    const sidx_hook *hook = a->opt.hook;
    const int exact = !(a->variant & GRID_VARIANT_BOXONLY);
    grid *G = sidx__calloc(a, 1, sizeof *G);
    sidx_aabb *boxes = NULL;
    if (!G) return sidx__fail(err, SIDX_ERR_NOMEM, "grid: out of memory");
    G->walks = &grid_walks[!(a->variant & GRID_VARIANT_NOMAILBOX) && !a->opt.no_mailbox];
    if (m->num_triangles && sidx__prim_boxes(a, &boxes, NULL) != SIDX_OK) goto nomem;

    const sidx_aabb scene = sidx_mesh_bounds(m);
    const sidx_aabb box = sidx__grid_box(scene);
    const float lambda = a->opt.grid_density > 0.0f ? a->opt.grid_density : GRID_DEFAULT_DENSITY;
    uint32_t res[3];
    /* The formula sees the scene's own extents: a flat axis must stay flat
     * (the padding only gives its single cell a thickness). */
    sidx__grid_resolution(sidx_aabb_is_empty(scene) ? box : scene, (double)m->num_triangles, lambda,
                          SIDX__GRID_MAX_RES, SIDX__GRID_MAX_CELLS, res);
    sidx__grid_geom_init(&G->g, box, res);
    const uint32_t nc = G->g.n_cells;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = box);
    SIDX_EMIT(1, hook, SIDX_EV_NOTE, e_.text = "grid resolution R = d*cbrt(lambda*n/V) per axis (cell[] = R)";
              e_.cell[0] = (int32_t)res[0]; e_.cell[1] = (int32_t)res[1]; e_.cell[2] = (int32_t)res[2];
              e_.count = nc; e_.cost = lambda);

    /* Pass 1: count references per cell into offsets[c + 1]. */
    G->offsets = sidx__calloc(a, (size_t)nc + 1u, sizeof *G->offsets);
    if (!G->offsets) goto nomem;
    const uint64_t total = sidx__grid_bin(m, boxes, NULL, m->num_triangles, &G->g, exact, G->offsets + 1, NULL);
    if (total > UINT32_MAX) {
        sidx__free(a, boxes);
        grid_free(a, G);
        return sidx__fail(err, SIDX_ERR_LIMIT, "grid: %llu references exceed 2^32", (unsigned long long)total);
    }
    /* Prefix sum: offsets[c] = first slot of cell c. */
    for (uint32_t c = 0; c < nc; ++c) G->offsets[c + 1] += G->offsets[c];
    G->n_refs = (uint32_t)total;
    G->refs = sidx__alloc(a, total, sizeof *G->refs);
    if (!G->refs) goto nomem;
    /* Pass 2: fill, using offsets[c] as cell c's cursor; afterwards it
     * points at the end of c = the start of c + 1, so shift back by one. */
    sidx__grid_bin(m, boxes, NULL, m->num_triangles, &G->g, exact, G->offsets, G->refs);
    memmove(G->offsets + 1, G->offsets, (size_t)nc * sizeof *G->offsets);
    G->offsets[0] = 0;
    sidx__free(a, boxes);

    for (uint32_t c = 0; c < nc; ++c) G->empty += G->offsets[c] == G->offsets[c + 1];
    if (sidx__hook_wants(hook, SIDX_EV_BUILD_NODE)) {
        /* One event per non-empty cell: a viewer draws the occupied cells. */
        for (uint32_t c = 0; c < nc; ++c) {
            const uint32_t cnt = G->offsets[c + 1] - G->offsets[c];
            if (!cnt) continue;
            const uint32_t x = c % res[0], y = (c / res[0]) % res[1], z = c / (res[0] * res[1]);
            (void)x, (void)y, (void)z;
            SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = c; e_.depth = 0; e_.count = cnt;
                      e_.bounds = sidx__grid_cell_bounds(&G->g, x, y, z); e_.cell[0] = (int32_t)x;
                      e_.cell[1] = (int32_t)y; e_.cell[2] = (int32_t)z);
        }
    }
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_END, e_.node = nc; e_.count = G->n_refs; e_.depth = 0);
    a->impl = G;
    return SIDX_OK;
nomem:
    sidx__free(a, boxes);
    grid_free(a, G);
    return sidx__fail(err, SIDX_ERR_NOMEM, "grid: out of memory");
}

/* The walk, closest hit (any = 0) or any hit (any = 1). */
static SIDX_INLINE int grid_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                 const int traced, const int any, const int use_mb)
{
    const grid *G = a->impl;
    float t0, t1;
    if (!sidx__clip(a, r, &G->g.box, hit->t, &t0, &t1)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.t = hit->t; e_.count = 0);
        return 0;
    }
    sidx__dda d;
    sidx__dda_init(&d, r, &G->g, t0);
    sidx__mailbox mb;
    if (use_mb) sidx__mailbox_clear(&mb);
    const int32_t stride[3] = {1, (int32_t)G->g.res[0], (int32_t)(G->g.res[0] * G->g.res[1])};
    const int32_t move[3] = {d.step[0] * stride[0], d.step[1] * stride[1], d.step[2] * stride[2]};
    uint32_t cell = (uint32_t)(d.c[0] * stride[0] + d.c[1] * stride[1] + d.c[2] * stride[2]);
    const uint32_t *off = G->offsets, *refs = G->refs;
    uint32_t visited = 0;
    float t_in = t0;
    int reason;
    (void)t_in;
    for (;;) {
        const int axis = sidx__dda_axis(&d);
        const float t_out = d.t_max[axis];
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = cell; e_.depth = 0;
                  e_.t_near = t_in; e_.t_far = t_out; e_.cell[0] = d.c[0]; e_.cell[1] = d.c[1];
                  e_.cell[2] = d.c[2]);
        const uint32_t first = off[cell];
        if (sidx__cell_prims(a, r, q, hit, refs + first, off[cell + 1] - first, cell, 0, &mb, use_mb, traced, any)) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.count = visited);
            return 1;
        }
        /* A hit at or before this cell's exit is final: every cell the ray
         * crossed before it has been searched.  A hit beyond the exit
         * (the triangle sticks out into later cells) stays a candidate. */
        if (hit->t <= t_out) {
            reason = hit->prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL : SIDX_TERM_LEFT_GRID;
            break;
        }
        if (!sidx__dda_step(&d, axis)) {
            reason = SIDX_TERM_LEFT_GRID;
            break;
        }
        cell = (uint32_t)((int32_t)cell + move[axis]);
        t_in = t_out;
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = reason; e_.t = hit->t;
              e_.count = visited);
    (void)reason;
    (void)visited;
    return 0;
}

SIDX__GRID_WALK_TABLES(grid_walk, grid_walks);

static void grid_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    const grid *G = a->impl;
    sidx__walk_intersect(G->walks, a, r, q, hit);
}

static int grid_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    const grid *G = a->impl;
    return sidx__walk_occluded(G->walks, a, r, q);
}

static void grid_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const grid *G = a->impl;
    const uint32_t nc = G->g.n_cells;
    s->nodes = nc;
    s->leaves = nc;
    s->max_depth = 0;
    s->prim_refs = G->n_refs;
    s->bytes = sizeof *G + ((size_t)nc + 1u) * sizeof *G->offsets + (size_t)G->n_refs * sizeof *G->refs;
    s->empty_leaves = G->empty;
    s->mean_leaf_prims = nc > G->empty ? (double)G->n_refs / (double)(nc - G->empty) : 0.0;
    s->res[0] = G->g.res[0];
    s->res[1] = G->g.res[1];
    s->res[2] = G->g.res[2];
}

static void grid_destroy(sidx_accel *a)
{
    grid_free(a, a->impl);
    a->impl = NULL;
}

const sidx_accel_vtable sidx__grid_vtable = {grid_build, grid_intersect, grid_occluded, grid_stats, grid_destroy,
                                             NULL};
