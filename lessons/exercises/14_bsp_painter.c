/* Exercise 14 — the BSP tree's back-to-front order: the painter's algorithm.
 *
 * Slide: deck 000, "BSP Trees": "Binary Space Partition Tree (BSP) —
 * recursively split space with planes, arbitrary split positions,
 * arbitrary orientations — used for visibility computation, e.g. in games
 * (Doom!): enumerating objects in back to front order".
 *
 * The library has built the tree ("bsp", sidx/bsp.h).  Walk it from the
 * root (node 0) and draw every polygon piece, farthest first, as seen from
 * eye (Fuchs, Kedem, Naylor 1980).  Read a node with
 * sidx_bsp_node_get(bsp, node, &v) and its pieces with
 * sidx_bsp_node_piece(bsp, node, i, &piece), i = 0 .. v.piece_count − 1.
 * At every node:
 *   - report it: sidx_ex_node_enter(ex, node, depth, 0, 0) (root depth 0);
 *   - a leaf (v.child[0] == UINT32_MAX): draw its pieces;
 *   - an inner node with plane n·x = d: the eye is on the front side
 *     (v.child[0]) when n·eye − d >= 0 (compute it in double; an eye in
 *     the plane counts as in front), else on the back side (v.child[1]).
 *     First the whole subtree on the side the eye is NOT on, then the
 *     node's own pieces (they lie in its plane), then the eye's side.
 * Draw a piece by reporting it: sidx_ex_prim_test(ex, piece.tri, 1, 0).
 * A node's pieces go in their order i = 0, 1, ...
 *
 * Awkward cases the checker tries: eyes inside the scene and far away,
 * an eye exactly in a splitting plane, triangles cut into pieces by a
 * plane (the same triangle drawn twice, once per piece), the 2D scene of
 * the slide (flat2d, eye in the plane z = 0).
 *
 * Check with:   make exercise EX=14_bsp_painter
 * Only the function body is yours to write (add helpers as you like). */
#include "sidx/sidx.h"
#include "sidx/bsp.h"
#include "sidx/exercise.h"

void bsp_paint(const sidx_accel *bsp, sidx_vec3 eye, const sidx_ex *ex)
{
    (void)bsp;
    (void)eye;
    (void)ex;
}
