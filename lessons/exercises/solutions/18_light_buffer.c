/* Reference solution of 18_light_buffer (deck 000, "Directional
 * Partitioning": "Variation: Light buffer (for shadow rays)"; Haines and
 * Greenberg 1986). */
#include "sidx/sidx.h"
#include "sidx/exercise.h"

int lb_shadow_test(const sidx_lightbuffer_cell_view *cell, uint32_t *last, const sidx_ex *ex)
{
    const float tmax = ex->ray->tmax;
    const uint32_t cached = *last;
    float t;
    if (cached != SIDX_NO_HIT) {
        if (sidx_ex_test_triangle(ex, cached, tmax, &t)) return 1; /* the last occluder first */
    }
    for (uint32_t k = 0; k < cell->count; ++k) {
        if (cell->dist[k] > cell->reach) break; /* beyond the segment's reach: nothing left can block */
        if (cell->tris[k] == cached) continue;  /* tested already */
        if (sidx_ex_test_triangle(ex, cell->tris[k], tmax, &t)) {
            *last = cell->tris[k]; /* remember it for the next shadow ray of this cell */
            return 1;
        }
    }
    return 0;
}
