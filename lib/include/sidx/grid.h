/* sidx/grid.h — a read-only view of a built uniform grid's cells.
 *
 * The uniform grid ("grid", "grid-nomailbox", "grid-boxonly") lays res[0]
 * × res[1] × res[2] equal cells over a box (the scene box, a flat axis
 * padded to a thin slab) and references every triangle from each cell it
 * overlaps.  The view gives the same cells the walk reads, stored as in
 * the structure: cell (x, y, z) has the id c = x + res[0]·(y + res[1]·z)
 * and holds the triangles refs[offsets[c] .. offsets[c + 1]).
 *
 * Cell geometry, computed exactly as the build and the 3D-DDA compute it:
 *   cell (x, y, z) spans  box.min + x·cell  ..  box.min + (x + 1)·cell
 *                         (per axis, as (float)x * cell + box.min)
 *   the cell holding point p on axis i: floor((p − box.min)·inv_cell),
 *                         clamped to [0, res − 1]
 * The view is a copy made by the library's own grid code (geometry and
 * binning), checked against the structure's statistics; free it with
 * sidx_grid_cells_free. */
#ifndef SIDX_GRID_H
#define SIDX_GRID_H

#include <stdint.h>
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sidx_grid_cells {
    sidx_aabb box;          /* the grid box */
    uint32_t res[3];        /* cells per axis */
    uint32_t num_cells;     /* res[0]·res[1]·res[2] */
    float cell[3];          /* cell size per axis: extent / res */
    float inv_cell[3];      /* 1 / cell */
    const uint32_t *offsets; /* num_cells + 1 */
    const uint32_t *refs;    /* offsets[num_cells] triangle indices of the mesh */
    uint32_t num_refs;
} sidx_grid_cells;

/* Fills *out with the cells of the built uniform grid `a`.
 * SIDX_ERR_INVALID_ARG if an argument is NULL or `a` is not a uniform
 * grid; SIDX_ERR_NOMEM.  On success free with sidx_grid_cells_free. */
sidx_status sidx_grid_cells_get(const sidx_accel *a, sidx_grid_cells *out, sidx_error *err);
void sidx_grid_cells_free(sidx_grid_cells *g);

#ifdef __cplusplus
}
#endif

#endif
