/* hook.c — event names, blank events and the traced elementary tests. */
#include "sidx_internal.h"

#define SIDX_STRUCTURE_NAME "intersect"

sidx_event sidx_event_blank(sidx_event_type type)
{
    sidx_event e;
    memset(&e, 0, sizeof e);
    e.type = type;
    e.structure = "";
    e.node = UINT32_MAX;
    e.parent = UINT32_MAX;
    e.prim = UINT32_MAX;
    e.count = UINT32_MAX;
    e.aux = UINT32_MAX;
    e.axis = -1;
    e.result = -1;
    e.cell[0] = e.cell[1] = e.cell[2] = -1;
    e.pos = NAN;
    e.cost = NAN;
    e.t_near = NAN;
    e.t_far = NAN;
    e.t = INFINITY;
    e.bounds = sidx_aabb_empty();
    e.text = NULL;
    e.prims = NULL;
    return e;
}

static const char *const event_names[SIDX_EV_COUNT] = {
    "build_begin", "build_node", "build_candidate", "build_split", "build_leaf", "build_end",
    "ray_begin", "node_enter", "box_test", "stack_push", "stack_pop", "prim_test",
    "hit_update", "mailbox_hit", "terminate", "ray_end", "note", "build_merge", "build_expand",
    "build_reinsert", "build_lazy_expand",
};

const char *sidx_event_type_name(sidx_event_type t)
{
    return ((unsigned)t < SIDX_EV_COUNT) ? event_names[t] : "unknown";
}

const char *sidx_leaf_reason_name(int reason)
{
    static const char *const names[SIDX_LEAF_REASON_COUNT] = {"none", "few_prims", "no_gain", "max_depth",
                                                              "no_split", "empty", "given"};
    return (reason >= 0 && reason < SIDX_LEAF_REASON_COUNT) ? names[reason] : "unknown";
}

const char *sidx_term_reason_name(int reason)
{
    static const char *const names[SIDX_TERM_REASON_COUNT] = {"none", "miss_root", "stack_empty",
                                                              "hit_in_cell", "any_hit", "left_grid"};
    return (reason >= 0 && reason < SIDX_TERM_REASON_COUNT) ? names[reason] : "unknown";
}

void sidx_hook_emit(const sidx_hook *hook, const sidx_event *ev)
{
    if (ev && sidx__hook_wants(hook, ev->type)) hook->fn(ev, hook->user);
}

int sidx_trace_triangle(const sidx_hook *hook, sidx_tri_method m, uint32_t prim, const sidx_ray *r,
                        sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float tmax, float *t, float *u, float *v)
{
    float tt = INFINITY, uu = 0.0f, vv = 0.0f;
    int hit = r ? sidx__tri_test(m, r, a, b, c, tmax, &tt, &uu, &vv) : 0;
    if (hit) {
        if (t) *t = tt;
        if (u) *u = uu;
        if (v) *v = vv;
    }
    /* These exist to trace, so they emit even in a -DSIDX_NO_HOOKS build. */
    if (sidx__hook_wants(hook, SIDX_EV_PRIM_TEST)) {
        sidx_event e = sidx_event_blank(SIDX_EV_PRIM_TEST);
        e.structure = SIDX_STRUCTURE_NAME;
        e.prim = prim;
        e.result = hit;
        e.t = hit ? tt : INFINITY;
        hook->fn(&e, hook->user);
    }
    return hit;
}

int sidx_trace_aabb(const sidx_hook *hook, sidx_box_method m, uint32_t node, const sidx_ray *r,
                    const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far)
{
    float tn = NAN, tf = NAN;
    int hit = (r && box) ? sidx__box_test(m == SIDX_BOX_ROBUST, r, box, tmin, tmax, &tn, &tf) : 0;
    if (hit) {
        if (t_near) *t_near = tn;
        if (t_far) *t_far = tf;
    }
    if (sidx__hook_wants(hook, SIDX_EV_BOX_TEST)) {
        sidx_event e = sidx_event_blank(SIDX_EV_BOX_TEST);
        e.structure = SIDX_STRUCTURE_NAME;
        e.node = node;
        if (box) e.bounds = *box;
        e.result = hit;
        e.t_near = tn;
        e.t_far = tf;
        hook->fn(&e, hook->user);
    }
    return hit;
}
