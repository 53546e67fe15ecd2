/* Borrowed: the library's own painter walk, its events relayed through
 * the exercise's calls (without the check it passes every case).
 * expect: uses sidx_bsp_paint, which this exercise asks you to write
 */
#include "sidx/sidx.h"
#include "sidx/bsp.h"
#include "sidx/exercise.h"

static void relay(const sidx_event *e, void *user)
{
    const sidx_ex *ex = user;
    if (e->type == SIDX_EV_NODE_ENTER) sidx_ex_node_enter(ex, e->node, e->depth, 0.0f, 0.0f);
    else if (e->type == SIDX_EV_PRIM_TEST) sidx_ex_prim_test(ex, e->prim, 1, 0.0f);
}

static int draw(const sidx_bsp_piece *piece, void *user)
{
    (void)piece;
    (void)user;
    return 0;
}

void bsp_paint(const sidx_accel *bsp, sidx_vec3 eye, const sidx_ex *ex)
{
    sidx_hook h = {relay, (void *)ex, SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    sidx_bsp_paint(bsp, eye, SIDX_BSP_BACK_TO_FRONT, draw, NULL, &h);
}
