/* exercise.c — sidx/exercise.h: the calls through which an exercise
 * reports its steps, each emitting the event a structure emits for the
 * same step (field for field as in docs/events.md). */
#include "sidx_internal.h"
#include "sidx/exercise.h"
#include "grid_internal.h"

_Static_assert(SIDX_EX_MAILBOX_SIZE == SIDX__MAILBOX_SIZE, "exercise 07 mailbox = the grids' mailbox");

static int ex_wants(const sidx_ex *ex, sidx_event_type type)
{
    return ex && sidx__hook_wants(ex->hook, type);
}

static sidx_event ex_event(const sidx_ex *ex, sidx_event_type type)
{
    sidx_event e = sidx_event_blank(type);
    e.structure = ex->structure ? ex->structure : "exercise";
    e.ray_id = ex->ray_id;
    return e;
}

void sidx_ex_box_test(const sidx_ex *ex, uint32_t node, const sidx_aabb *box, int result, float t_near, float t_far)
{
    if (!ex_wants(ex, SIDX_EV_BOX_TEST)) return;
    sidx_event e = ex_event(ex, SIDX_EV_BOX_TEST);
    e.node = node;
    if (box) e.bounds = *box;
    e.result = result ? 1 : 0;
    e.t_near = result ? t_near : NAN;
    e.t_far = result ? t_far : NAN;
    ex->hook->fn(&e, ex->hook->user);
}

void sidx_ex_node_enter(const sidx_ex *ex, uint32_t node, uint32_t depth, float t_near, float t_far)
{
    if (!ex_wants(ex, SIDX_EV_NODE_ENTER)) return;
    sidx_event e = ex_event(ex, SIDX_EV_NODE_ENTER);
    e.node = node;
    e.depth = depth;
    e.t_near = t_near;
    e.t_far = t_far;
    ex->hook->fn(&e, ex->hook->user);
}

void sidx_ex_cell_enter(const sidx_ex *ex, uint32_t cell_id, int x, int y, int z, float t_near, float t_far)
{
    if (!ex_wants(ex, SIDX_EV_NODE_ENTER)) return;
    sidx_event e = ex_event(ex, SIDX_EV_NODE_ENTER);
    e.node = cell_id;
    e.depth = 0;
    e.cell[0] = x;
    e.cell[1] = y;
    e.cell[2] = z;
    e.t_near = t_near;
    e.t_far = t_far;
    ex->hook->fn(&e, ex->hook->user);
}

static void ex_stack(const sidx_ex *ex, sidx_event_type type, uint32_t node, uint32_t size, float tn, float tf)
{
    if (!ex_wants(ex, type)) return;
    sidx_event e = ex_event(ex, type);
    e.node = node;
    e.depth = size;
    e.t_near = tn;
    e.t_far = tf;
    ex->hook->fn(&e, ex->hook->user);
}

void sidx_ex_push(const sidx_ex *ex, uint32_t node, uint32_t stack_size, float t_near, float t_far)
{
    ex_stack(ex, SIDX_EV_STACK_PUSH, node, stack_size, t_near, t_far);
}

void sidx_ex_pop(const sidx_ex *ex, uint32_t node, uint32_t stack_size, float t_near, float t_far)
{
    ex_stack(ex, SIDX_EV_STACK_POP, node, stack_size, t_near, t_far);
}

void sidx_ex_prim_test(const sidx_ex *ex, uint32_t prim, int result, float t)
{
    if (!ex_wants(ex, SIDX_EV_PRIM_TEST)) return;
    sidx_event e = ex_event(ex, SIDX_EV_PRIM_TEST);
    e.prim = prim;
    e.result = result ? 1 : 0;
    e.t = result ? t : INFINITY;
    ex->hook->fn(&e, ex->hook->user);
}

void sidx_ex_hit_update(const sidx_ex *ex, uint32_t prim, float t)
{
    if (!ex_wants(ex, SIDX_EV_HIT_UPDATE)) return;
    sidx_event e = ex_event(ex, SIDX_EV_HIT_UPDATE);
    e.prim = prim;
    e.t = t;
    ex->hook->fn(&e, ex->hook->user);
}

void sidx_ex_mailbox_hit(const sidx_ex *ex, uint32_t prim)
{
    if (!ex_wants(ex, SIDX_EV_MAILBOX_HIT)) return;
    sidx_event e = ex_event(ex, SIDX_EV_MAILBOX_HIT);
    e.prim = prim;
    ex->hook->fn(&e, ex->hook->user);
}

static void ex_plane(const sidx_ex *ex, sidx_event_type type, uint32_t node, int axis, float pos, float cost,
                     uint32_t nl, uint32_t nr)
{
    if (!ex_wants(ex, type)) return;
    sidx_event e = ex_event(ex, type);
    e.node = node;
    e.axis = axis;
    e.pos = pos;
    e.cost = cost;
    e.count = nl;
    e.aux = nr;
    ex->hook->fn(&e, ex->hook->user);
}

void sidx_ex_candidate(const sidx_ex *ex, uint32_t node, int axis, float pos, float cost, uint32_t n_left,
                       uint32_t n_right)
{
    ex_plane(ex, SIDX_EV_BUILD_CANDIDATE, node, axis, pos, cost, n_left, n_right);
}

void sidx_ex_split(const sidx_ex *ex, uint32_t node, int axis, float pos, float cost, uint32_t n_left,
                   uint32_t n_right)
{
    ex_plane(ex, SIDX_EV_BUILD_SPLIT, node, axis, pos, cost, n_left, n_right);
}

int sidx_ex_test_box(const sidx_ex *ex, uint32_t node, const sidx_aabb *box, float tmin, float tmax, float *t_near,
                     float *t_far)
{
    if (!ex || !ex->ray || !box) return 0;
    float tn = NAN, tf = NAN;
    const int hit = sidx__box_test(ex->box == SIDX_BOX_ROBUST, ex->ray, box, tmin, tmax, &tn, &tf);
    if (hit) {
        if (t_near) *t_near = tn;
        if (t_far) *t_far = tf;
    }
    sidx_ex_box_test(ex, node, box, hit, tn, tf);
    return hit;
}

int sidx_ex_test_triangle(const sidx_ex *ex, uint32_t prim, float tmax, float *t)
{
    if (!ex || !ex->ray || !ex->mesh || prim >= ex->mesh->num_triangles) return 0;
    float tt = INFINITY;
    const int hit = sidx__tri_test(ex->tri, ex->ray, sidx_mesh_vertex(ex->mesh, prim, 0),
                                   sidx_mesh_vertex(ex->mesh, prim, 1), sidx_mesh_vertex(ex->mesh, prim, 2), tmax,
                                   &tt, NULL, NULL);
    if (hit && t) *t = tt;
    sidx_ex_prim_test(ex, prim, hit, tt);
    return hit;
}

/* ---- references the checker compares with -------------------------------- */

int sidx_ex_reference_moller_cramer(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax,
                                    float *t_out, float *u_out, float *v_out)
{
    if (!r) return 0;
    /* deck 001, "Moller-Trumbore Algorithm": o + t·d = p0 + u·e1 + v·e2
     * solved by Cramer's rule, each unknown a determinant over D, term by
     * term as the slide writes it. */
    const sidx_vec3 e1 = sidx_v3_sub(p1, p0), e2 = sidx_v3_sub(p2, p0), s = sidx_v3_sub(r->org, p0);
    const sidx_vec3 e1xd = sidx_v3_cross(e1, r->dir), sxe2 = sidx_v3_cross(s, e2);
    const float D = sidx_v3_dot(e1xd, e2);
    if (D == 0.0f) return 0;
    const float u = -sidx_v3_dot(sxe2, r->dir) / D;
    const float v = sidx_v3_dot(e1xd, s) / D;
    const float t = -sidx_v3_dot(sxe2, e1) / D;
    if (!(u >= 0.0f && v >= 0.0f && u + v <= 1.0f)) return 0;
    if (!(t >= r->tmin && t < tmax)) return 0;
    if (t_out) *t_out = t;
    if (u_out) *u_out = u;
    if (v_out) *v_out = v;
    return 1;
}

float sidx_ex_reference_sah_cost(sidx_aabb parent, sidx_aabb left, uint32_t n_left, sidx_aabb right,
                                 uint32_t n_right, float c_trav, float c_tri)
{
    /* bvh_build.c's sah(): C_trav + C_tri·(A_L·N_L + A_R·N_R)·(1/A). */
    const float inv = 1.0f / sidx_aabb_area(parent);
    return c_trav + c_tri * (sidx_aabb_area(left) * (float)n_left + sidx_aabb_area(right) * (float)n_right) * inv;
}
