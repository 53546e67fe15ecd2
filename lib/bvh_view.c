/* bvh_view.c — sidx/bvh.h: the binary BVH's node and index arrays handed
 * out read-only (exercises and tools read the nodes the walk reads). */
#include "bvh_internal.h"
#include "sidx/bvh.h"

#include <stddef.h>

/* The public node is the private one, field for field. */
_Static_assert(sizeof(sidx_bvh_node) == sizeof(bvh_node), "sidx_bvh_node mirrors bvh_node");
_Static_assert(offsetof(sidx_bvh_node, left_or_first) == offsetof(bvh_node, left_or_first), "layout");
_Static_assert(offsetof(sidx_bvh_node, bmax) == offsetof(bvh_node, bmax), "layout");
_Static_assert(offsetof(sidx_bvh_node, count_axis) == offsetof(bvh_node, count_axis), "layout");
_Static_assert(SIDX_BVH_COUNT_MASK == BVH_COUNT_MASK, "same leaf count mask");

static sidx_status bvh_view(const sidx_accel *a, const void *p, const void *q, sidx_error *err, const char *fn,
                            const bvh **out)
{
    if (!a || !p || !q) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", fn);
    if (a->vt != &sidx__bvh_vtable || !a->impl)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: '%s' is not a binary BVH", fn, a->name ? a->name : "?");
    if (((const bvh *)a->impl)->lazy)
        return sidx__fail(err, SIDX_ERR_UNSUPPORTED, "%s: a lazy tree's nodes change as rays enter them", fn);
    *out = a->impl;
    return SIDX_OK;
}

sidx_status sidx_bvh_nodes(const sidx_accel *a, const sidx_bvh_node **nodes, uint32_t *count, sidx_error *err)
{
    const bvh *b = NULL;
    const sidx_status s = bvh_view(a, nodes, count, err, "sidx_bvh_nodes", &b);
    if (s != SIDX_OK) return s;
    *nodes = (const sidx_bvh_node *)(const void *)b->nodes;
    *count = b->num_nodes;
    return SIDX_OK;
}

sidx_status sidx_bvh_prims(const sidx_accel *a, const uint32_t **prims, uint32_t *count, sidx_error *err)
{
    const bvh *b = NULL;
    const sidx_status s = bvh_view(a, prims, count, err, "sidx_bvh_prims", &b);
    if (s != SIDX_OK) return s;
    *prims = b->prim_id;
    *count = b->num_prims;
    return SIDX_OK;
}
