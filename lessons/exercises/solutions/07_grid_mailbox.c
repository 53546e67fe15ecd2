/* Reference solution of 07_grid_mailbox (deck 000, "Uniform Grid
 * Traversal": mailboxing, the per-ray cache of object IDs). */
#include "sidx/sidx.h"
#include "sidx/exercise.h"

void mailbox_new_ray(sidx_ex_mailbox *mb)
{
    for (uint32_t k = 0; k < SIDX_EX_MAILBOX_SIZE; ++k) mb->id[k] = UINT32_MAX;
}

void cell_prims(const sidx_ex *ex, sidx_ex_mailbox *mb, const uint32_t *refs, uint32_t n, sidx_hit *best)
{
    for (uint32_t k = 0; k < n; ++k) {
        const uint32_t prim = refs[k];
        uint32_t *slot = &mb->id[prim % SIDX_EX_MAILBOX_SIZE];
        if (*slot == prim) { /* tested already for this ray */
            sidx_ex_mailbox_hit(ex, prim);
            continue;
        }
        *slot = prim; /* recorded whether it hits or not */
        float t;
        if (sidx_ex_test_triangle(ex, prim, best->t, &t)) {
            best->t = t;
            best->prim = prim;
            sidx_ex_hit_update(ex, prim, t);
        }
    }
}
