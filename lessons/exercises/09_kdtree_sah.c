/* Exercise 09 — the kd-tree's SAH split: candidate events, the sweep,
 * planar triangles, the empty-space bonus.
 *
 * Slides: deck 000, "Building good kD-trees" ("Cost(c) = C_trav +
 * SA(L)/SA(c)·TriCount(L) + SA(R)/SA(c)·TriCount(R)"; "Build a set of
 * candidate split locations — based on BBox of triangles (in/out events);
 * one can show that SAH cannot have minima unless #triangles changes ...
 * Sort the triangle events ... Walk through candidates to find minimum
 * cost split") and "Cost-Optimized Split" ("produces large chunks of
 * empty space").
 *
 * kd_split gets one node: its cell and the boxes of its n triangles,
 * already clipped to the cell ("perfect splits": a triangle straddling
 * the parent's plane comes with the box of its part inside this cell, so
 * its events are where it really is).  For each axis x, y, z:
 *   - events: a start at each box's min and an end at its max; a box flat
 *     on the axis gives one planar event instead;
 *   - sort them by position; at one position ends come first, then
 *     planars, then starts;
 *   - sweep with N_L = 0, N_R = n; at each distinct position p: N_R loses
 *     the ends and planars at p; if p lies strictly inside the cell, p is a
 *     candidate: the triangles lying in the plane (planars at p) are tried
 *     left (N_L + planars, N_R) and right (N_L, N_R + planars), the
 *     cheaper wins (left on a tie); report it with sidx_ex_candidate(ex,
 *     node, axis, p, cost, n_left, n_right); then N_L gains the starts and
 *     planars at p;
 *   - cost = C_trav + C_tri·(P_L·N_L + P_R·N_R), P = SA(child)/SA(cell),
 *     L and R the cell cut at p; when N_L or N_R is 0 the cost is
 *     multiplied by (1 - empty_bonus).  So that your costs agree with the
 *     library's to the last bit (a plane in the middle of the cell makes
 *     P_L = P_R, and only exact arithmetic picks the side of a planar
 *     triangle as the library does), compute, with ea, eb the cell's
 *     extents on the two other axes (x: y, z; y: x, z; z: x, y) and
 *     inv = 1 / sidx_aabb_area(cell):
 *         P_L = 2·(ea·eb + (p - cell.min)·(ea + eb))·inv,
 *         P_R = 2·(ea·eb + (cell.max - p)·(ea + eb))·inv,
 *         cost = C_trav + C_tri·(P_L·N_L + P_R·N_R), then ·(1 - bonus).
 * Finally report the cheapest candidate (the first of equal ones) with
 * sidx_ex_split(ex, node, axis, pos, cost, n_left, n_right).
 *
 * Check with:   make exercise EX=09_kdtree_sah
 * Only the function body is yours to write (helpers are fine). */
#include <stdlib.h>
#include "sidx/sidx.h"
#include "sidx/exercise.h"

void kd_split(const sidx_ex *ex, uint32_t node, sidx_aabb cell, const sidx_aabb *boxes, uint32_t n, float c_trav,
              float c_tri, float empty_bonus)
{
    (void)ex;
    (void)node;
    (void)cell;
    (void)boxes;
    (void)n;
    (void)c_trav;
    (void)c_tri;
    (void)empty_bonus;
}
