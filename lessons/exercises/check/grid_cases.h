/* grid_cases.h — the uniform-grid battery shared by the 3D-DDA walk
 * (06_grid_dda) and mailboxing (07_grid_mailbox): the scenes, their grids
 * (the library's, read through sidx/grid.h), the rays, and what the
 * library's query does around a walk (RAY_BEGIN, TERMINATE, RAY_END).
 *
 * Scene "slanted" is built here on integer coordinates over [0, 4]^3 with
 * λ chosen so the grid has 4 × 4 × 4 cells of size 1: its awkward rays
 * (through cell corners, along a cell face, with a ±0 component, starting
 * inside) cross cell boundaries at exact t, so the order of a student's
 * arithmetic does not matter there. */
#ifndef SIDX_EX_GRID_CASES_H
#define SIDX_EX_GRID_CASES_H

#include <string.h>
#include "check.h"
#include "sidx/grid.h"
#include "grid_internal.h"

#define GRID_NSCENES 4
#define GRID_FIXED 12 /* hand-made rays of scene 0 */
#define GRID_RAYS 24  /* rays per scene */
static const char *const grid_scene_names[GRID_NSCENES] = {"slanted", "soup:120", "cornell", "icosphere:1"};
static sidx_mesh grid_meshes[GRID_NSCENES];
static sidx_accel *grid_accels[GRID_NSCENES];
static sidx_grid_cells grid_views[GRID_NSCENES];
static sidx__grid_geom grid_geoms[GRID_NSCENES]; /* the views' geometry, for the library's DDA */
static sidx_ray grid_rays[GRID_NSCENES][GRID_RAYS];
static const char *grid_ray_kind[GRID_NSCENES][GRID_RAYS];

/* Four triangles over [0, 4]^3: two planes across the whole box (x+y+z = 4
 * and x+y+z = 8, each in many cells: a hit found in one cell often lies
 * in a later one), a small one near the far corner and one lying in the
 * cell face z = 2. */
static int grid_slanted(sidx_mesh *m)
{
    static const float xyz[] = {0, 0, 4, 4, 0, 0, 0, 4, 0,    4, 4, 0, 4, 0, 4, 0, 4, 4,
                                3, 3, 3.5f, 3.875f, 3, 3.5f, 3, 3.875f, 3.5f,  1, 1, 2, 3, 1, 2, 1, 3, 2};
    static const uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    return sidx_mesh_from_arrays(m, xyz, 12, idx, 4, NULL) == SIDX_OK ? 0 : -1;
}

static const struct { float o[3], d[3]; const char *kind; } grid_fixed[GRID_FIXED] = {
    {{-1, -1, 0.5f}, {1, 1, 0}, "through cell corners (x and y boundaries at the same t)"},
    {{-1, 0.5f, -1}, {1, 0, 1}, "through cell edges (x and z boundaries at the same t)"},
    {{0.5f, 4.5f, 3.5f}, {0, -1, 0}, "a ±0 direction component: one row of cells"},
    {{2, -1, 1.5f}, {0, 1, 0.25f}, "along the cell face x = 2"},
    {{2.5f, 1.5f, 0.5f}, {-1, 0.25f, 0.75f}, "starting inside the grid"},
    {{3.5f, 3.5f, 5}, {0, 0, -1}, "down onto the small triangle, past the big ones"},
    {{-1, 2.5f, 2.5f}, {1, 0, 0}, "a hit that sticks out of the cell it is found in"},
    {{5, 5, 5}, {-1, -1, -1}, "down the diagonal, against the direction of every axis"},
    {{-2, 0.5f, 0.5f}, {1, 2, 3}, "steep: several y and z steps per x step"},
    {{5, 5, 0.5f}, {1, 0.25f, 0}, "missing the grid box"},
    {{1.5f, 1.5f, 5}, {0, 0, -1}, "onto the triangle lying in the cell face z = 2"},
    {{0.25f, 0.5f, -1}, {0.5f, 0.25f, 1}, "upwards, slowly across x and y"},
};

/* sidx-view --events of ray r of scene s over `structure` (check.h):
 * scene "slanted" is no built-in, the runner writes it out. */
static void grid_view_case(int s, int r, const char *structure, ex_case_info *out)
{
    out->view_accel = structure;
    out->view_knobs = s == 0 ? "--lambda 16" : NULL;
    out->view_scene = s == 0 ? NULL : grid_scene_names[s];
    out->view_mesh = &grid_meshes[s];
    out->view_ray = &grid_rays[s][r];
}

static int grid_setup(const char *structure)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.box = SIDX_BOX_PLAIN;
    for (int s = 0; s < GRID_NSCENES; ++s) {
        if (s == 0 ? grid_slanted(&grid_meshes[s]) != 0
                   : sidx_scene_open(grid_scene_names[s], &grid_meshes[s], NULL) != SIDX_OK)
            return -1;
        bo.grid_density = s == 0 ? 16.0f : 0.0f; /* slanted: R = 4·∛(16·4/64) = 4 per axis */
        if (sidx_accel_build(structure, &grid_meshes[s], &bo, &grid_accels[s], NULL) != SIDX_OK) return -1;
        if (sidx_grid_cells_get(grid_accels[s], &grid_views[s], NULL) != SIDX_OK) return -1;
        sidx__grid_geom_init(&grid_geoms[s], grid_views[s].box, grid_views[s].res);
        const sidx_aabb b = sidx_mesh_bounds(&grid_meshes[s]);
        const sidx_vec3 c = sidx_aabb_centroid(b), e = sidx_aabb_extent(b);
        uint32_t st = 7u + (uint32_t)s;
        for (int i = 0; i < GRID_RAYS; ++i) {
            if (s == 0 && i < GRID_FIXED) {
                grid_rays[s][i] = ex_ray(grid_fixed[i].o[0], grid_fixed[i].o[1], grid_fixed[i].o[2], grid_fixed[i].d[0],
                                         grid_fixed[i].d[1], grid_fixed[i].d[2], 0, INFINITY);
                grid_ray_kind[s][i] = grid_fixed[i].kind;
                continue;
            }
            const float u = ex_rand(&st), v = ex_rand(&st), w = ex_rand(&st);
            const sidx_vec3 p = sidx_v3(b.min.x + u * e.x, b.min.y + v * e.y, b.min.z + w * e.z);
            sidx_vec3 o, d;
            if (i % 3 == 0) {
                const float a = ex_rand(&st) * 6.2831853f;
                o = sidx_v3(c.x + cosf(a) * e.x, c.y + sinf(a) * e.y, p.z);
                d = sidx_v3_sub(p, o);
                grid_ray_kind[s][i] = "across the scene";
            } else if (i % 3 == 1) {
                o = p;
                d = sidx_v3(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f);
                grid_ray_kind[s][i] = "starting inside";
            } else {
                o = sidx_v3(p.x, p.y, b.max.z + e.z);
                d = sidx_v3((ex_rand(&st) - 0.5f) * 0.3f, (ex_rand(&st) - 0.5f) * 0.3f, -1.0f);
                grid_ray_kind[s][i] = "from above";
            }
            if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) d.x = 1.0f;
            grid_rays[s][i] = ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0, INFINITY);
        }
    }
    return 0;
}

static void grid_teardown(void)
{
    for (int s = 0; s < GRID_NSCENES; ++s) {
        sidx_grid_cells_free(&grid_views[s]);
        sidx_accel_destroy(grid_accels[s]);
        sidx_mesh_free(&grid_meshes[s]);
    }
}

static void grid_reference_ray(int s, int r, uint32_t ray_id, const sidx_hook *h)
{
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = h;
    q.ray_id = ray_id;
    sidx_hit hit;
    sidx_accel_intersect(grid_accels[s], &grid_rays[s][r], &q, &hit);
}

/* Counts the student's cells (TERMINATE's count) and keeps the last
 * cell's exit on the way to the runner's hook. */
typedef struct grid_counting {
    const sidx_hook *inner;
    uint32_t entered;
    float t_out;
} grid_counting;

static void grid_counting_fn(const sidx_event *ev, void *user)
{
    grid_counting *c = user;
    if (ev->type == SIDX_EV_NODE_ENTER) {
        ++c->entered;
        c->t_out = ev->t_far;
    }
    sidx_hook_emit(c->inner, ev);
}

typedef void (*grid_walk_fn)(const sidx_ex *ex, const sidx_grid_cells *g, sidx_hit *best, void *user);

/* What the library's query and walk do around the cell loop: RAY_BEGIN,
 * the walk, TERMINATE (no cell: the grid box was missed; a hit at or
 * before the last cell's exit: hit in cell; else the walk left the grid),
 * RAY_END. */
static void grid_student_ray(int s, int r, uint32_t ray_id, const sidx_hook *h, const char *structure,
                             grid_walk_fn walk, void *user)
{
    const sidx_ray *ray = &grid_rays[s][r];
    grid_counting c = {h, 0, -INFINITY};
    const sidx_hook ch = {grid_counting_fn, &c, 0};
    sidx_ex ex;
    memset(&ex, 0, sizeof ex);
    ex.hook = &ch;
    ex.structure = structure;
    ex.ray_id = ray_id;
    ex.ray = ray;
    ex.mesh = &grid_meshes[s];
    ex.tri = SIDX_TRI_WATERTIGHT;
    ex.box = SIDX_BOX_PLAIN;
    sidx_event e = sidx_event_blank(SIDX_EV_RAY_BEGIN);
    e.structure = structure;
    e.ray_id = ray_id;
    e.t_near = ray->tmin;
    e.t_far = ray->tmax;
    sidx_hook_emit(h, &e);
    sidx_hit best = sidx_hit_none();
    best.t = ray->tmax;
    walk(&ex, &grid_views[s], &best, user);
    e = sidx_event_blank(SIDX_EV_TERMINATE);
    e.structure = structure;
    e.ray_id = ray_id;
    e.reason = c.entered == 0                                         ? SIDX_TERM_MISS_ROOT
               : best.t <= c.t_out && best.prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL
                                                               : SIDX_TERM_LEFT_GRID;
    e.t = best.t;
    e.count = c.entered;
    sidx_hook_emit(h, &e);
    e = sidx_event_blank(SIDX_EV_RAY_END);
    e.structure = structure;
    e.ray_id = ray_id;
    e.prim = best.prim;
    e.t = best.prim == SIDX_NO_HIT ? INFINITY : best.t;
    e.result = best.prim != SIDX_NO_HIT;
    sidx_hook_emit(h, &e);
}

/* The library's 3D-DDA (grid_internal.h) over a view's cells, reporting
 * each cell; `cell` tests the cell's triangles.  Stops as grid.c's walk
 * does: at a hit inside the current cell, or when the walk leaves. */
typedef void (*grid_cell_fn)(const sidx_ex *ex, const uint32_t *refs, uint32_t n, sidx_hit *best, void *user);

static inline void grid_dda_walk(const sidx_ex *ex, const sidx_grid_cells *g, sidx_hit *best, grid_cell_fn cell,
                          void *user)
{
    float t0, t1;
    if (!sidx_intersect_aabb(SIDX_BOX_PLAIN, ex->ray, &g->box, ex->ray->tmin, best->t, &t0, &t1)) return;
    sidx__dda d;
    sidx__dda_init(&d, ex->ray, &grid_geoms[g - grid_views], t0);
    float t_in = t0;
    for (;;) {
        const int axis = sidx__dda_axis(&d);
        const float t_out = d.t_max[axis];
        const uint32_t id = (uint32_t)d.c[0] + g->res[0] * ((uint32_t)d.c[1] + g->res[1] * (uint32_t)d.c[2]);
        sidx_ex_cell_enter(ex, id, d.c[0], d.c[1], d.c[2], t_in, t_out);
        cell(ex, g->refs + g->offsets[id], g->offsets[id + 1] - g->offsets[id], best, user);
        if (best->t <= t_out || !sidx__dda_step(&d, axis)) return;
        t_in = t_out;
    }
}

#endif
