/* grid_view.c — sidx/grid.h: the uniform grid's cells, read-only.
 *
 * The grid's own arrays are private to grid.c; the view rebuilds them
 * with the same shared code the build runs (grid_internal.h: the padded
 * box, the geometry from the structure's resolution, the count-then-fill
 * binning), so its cells are the structure's cell for cell, and checks
 * the reference count against the structure's statistics. */
#include "grid_internal.h"
#include "sidx/grid.h"

#include <stdlib.h>
#include <string.h>

sidx_status sidx_grid_cells_get(const sidx_accel *a, sidx_grid_cells *out, sidx_error *err)
{
    if (!a || !out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_grid_cells_get: NULL argument");
    if (a->vt != &sidx__grid_vtable || !a->impl || !a->mesh)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_grid_cells_get: '%s' is not a uniform grid",
                          a->name ? a->name : "?");
    sidx_accel_stats st;
    memset(&st, 0, sizeof st);
    a->vt->stats(a, &st);
    const sidx_mesh *m = a->mesh;
    sidx__grid_geom g;
    sidx__grid_geom_init(&g, sidx__grid_box(sidx_mesh_bounds(m)), st.res);
    const int exact = strcmp(a->name, "grid-boxonly") != 0;
    sidx_aabb *boxes = malloc((m->num_triangles ? m->num_triangles : 1u) * sizeof *boxes);
    uint32_t *off = calloc((size_t)g.n_cells + 1u, sizeof *off);
    uint32_t *refs = NULL;
    if (!boxes || !off) goto nomem;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        sidx_aabb b = sidx_aabb_empty();
        for (int k = 0; k < 3; ++k) b = sidx_aabb_grow(b, sidx_mesh_vertex(m, i, k));
        boxes[i] = b;
    }
    const uint64_t total = sidx__grid_bin(m, boxes, NULL, m->num_triangles, &g, exact, off + 1, NULL);
    if (total != st.prim_refs) {
        free(boxes);
        free(off);
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_grid_cells_get: '%s' does not match its own statistics",
                          a->name);
    }
    for (uint32_t c = 0; c < g.n_cells; ++c) off[c + 1] += off[c];
    refs = malloc((total ? (size_t)total : 1u) * sizeof *refs);
    if (!refs) goto nomem;
    sidx__grid_bin(m, boxes, NULL, m->num_triangles, &g, exact, off, refs);
    memmove(off + 1, off, (size_t)g.n_cells * sizeof *off);
    off[0] = 0;
    free(boxes);
    memset(out, 0, sizeof *out);
    out->box = g.box;
    for (int i = 0; i < 3; ++i) out->res[i] = g.res[i];
    out->num_cells = g.n_cells;
    out->cell[0] = g.cell.x, out->cell[1] = g.cell.y, out->cell[2] = g.cell.z;
    out->inv_cell[0] = g.inv_cell.x, out->inv_cell[1] = g.inv_cell.y, out->inv_cell[2] = g.inv_cell.z;
    out->offsets = off;
    out->refs = refs;
    out->num_refs = (uint32_t)total;
    return SIDX_OK;
nomem:
    free(boxes);
    free(off);
    free(refs);
    return sidx__fail(err, SIDX_ERR_NOMEM, "sidx_grid_cells_get: out of memory");
}

void sidx_grid_cells_free(sidx_grid_cells *g)
{
    if (!g) return;
    free((void *)(uintptr_t)g->offsets);
    free((void *)(uintptr_t)g->refs);
    g->offsets = g->refs = NULL;
}
