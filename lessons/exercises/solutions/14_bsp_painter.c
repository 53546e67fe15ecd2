/* Reference solution of 14_bsp_painter (deck 000, "BSP Trees":
 * "enumerating objects in back to front order"; Fuchs, Kedem, Naylor
 * 1980). */
#include "sidx/sidx.h"
#include "sidx/bsp.h"
#include "sidx/exercise.h"

static void draw_pieces(const sidx_accel *bsp, uint32_t node, uint32_t count, const sidx_ex *ex)
{
    for (uint32_t i = 0; i < count; ++i) {
        sidx_bsp_piece p;
        if (sidx_bsp_node_piece(bsp, node, i, &p) == SIDX_OK) sidx_ex_prim_test(ex, p.tri, 1, 0.0f);
    }
}

static void paint(const sidx_accel *bsp, uint32_t node, uint32_t depth, sidx_vec3 eye, const sidx_ex *ex)
{
    sidx_bsp_node_view v;
    if (sidx_bsp_node_get(bsp, node, &v) != SIDX_OK) return;
    sidx_ex_node_enter(ex, node, depth, 0.0f, 0.0f);
    if (v.child[0] == UINT32_MAX) {
        draw_pieces(bsp, node, v.piece_count, ex);
        return;
    }
    const double dist = v.n[0] * eye.x + v.n[1] * eye.y + v.n[2] * eye.z - v.d;
    const int eye_side = dist >= 0.0 ? 0 : 1;
    paint(bsp, v.child[1 - eye_side], depth + 1, eye, ex); /* the far side first */
    draw_pieces(bsp, node, v.piece_count, ex);             /* then the plane's own pieces */
    paint(bsp, v.child[eye_side], depth + 1, eye, ex);     /* the eye's side last, over the rest */
}

void bsp_paint(const sidx_accel *bsp, sidx_vec3 eye, const sidx_ex *ex)
{
    paint(bsp, 0, 0, eye, ex);
}
