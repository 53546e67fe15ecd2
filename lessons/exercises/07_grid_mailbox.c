/* Exercise 07 — mailboxing on the uniform grid.
 *
 * Slides: deck 000, "Uniform Grid Traversal": "Mailboxing — single
 * primitive can be referenced in many cells; avoid multiple
 * intersections; keep track of intersection tests ... Per-ray cache of
 * object IDs — data local to a ray (better!)".
 *
 * The checker walks the cells with the library's 3D-DDA (exercise 06) and
 * calls your code; it traces several rays in a row with ONE mailbox.
 * The mailbox is the library's: SIDX_EX_MAILBOX_SIZE (32) slots,
 * direct-mapped, the slot of triangle prim is mb->id[prim % 32]; a
 * collision just overwrites the slot (a re-test later, never a wrong
 * answer).
 *
 * 1. mailbox_new_ray — called when a ray starts: the cache is the ray's,
 *    so forget every triangle of the previous ray (a value no triangle
 *    has, e.g. UINT32_MAX).
 * 2. cell_prims — the triangles refs[0 .. n) of one cell, in order.  For
 *    each: if its slot holds it, it was tested already for this ray:
 *    report sidx_ex_mailbox_hit(ex, prim) and skip it.  Otherwise write it
 *    into its slot and test it: sidx_ex_test_triangle(ex, prim, best->t,
 *    &t); on a hit update best and call sidx_ex_hit_update(ex, prim, t).
 *    Skipping is exact: a triangle tested earlier against a bound at least
 *    as large either became the best hit or lies beyond it.
 *
 * Check with:   make exercise EX=07_grid_mailbox
 * Only the two function bodies are yours to write. */
#include "sidx/sidx.h"
#include "sidx/exercise.h"

void mailbox_new_ray(sidx_ex_mailbox *mb)
{
    (void)mb;
}

void cell_prims(const sidx_ex *ex, sidx_ex_mailbox *mb, const uint32_t *refs, uint32_t n, sidx_hit *best)
{
    (void)ex;
    (void)mb;
    (void)refs;
    (void)n;
    (void)best;
}
