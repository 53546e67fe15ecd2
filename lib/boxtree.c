/* boxtree.c — object-median bounding-box tree (see boxtree.h for why it
 * exists next to the real BVH). */
#include "boxtree.h"

static void *bt_malloc(size_t size, void *user) { (void)user; return malloc(size); }
static void bt_free(void *p, void *user) { (void)user; free(p); }

sidx_allocator sidx__default_allocator(void)
{
    sidx_allocator al = {bt_malloc, bt_free, NULL};
    return al;
}

static float centroid_on(const sidx_aabb *b, int axis)
{
    return 0.5f * (sidx_v3_get(b->min, axis) + sidx_v3_get(b->max, axis));
}

/* Quickselect with a three-way partition (< pivot, == pivot, > pivot):
 * afterwards items[lo..k) have centroids <= the k-th and items(k..hi)
 * >= it — the object median, in expected O(n).  The == band is never
 * empty, so every round shrinks the range even with many equal keys. */
static void select_median(uint32_t *items, uint32_t lo, uint32_t hi, uint32_t k, const sidx_aabb *boxes, int axis)
{
    while (hi - lo > 1) {
        const float pivot = centroid_on(&boxes[items[lo + (hi - lo) / 2]], axis);
        uint32_t lt = lo, i = lo, gt = hi;
        while (i < gt) {
            const float c = centroid_on(&boxes[items[i]], axis);
            if (c < pivot) {
                uint32_t tmp = items[i]; items[i] = items[lt]; items[lt] = tmp;
                ++lt; ++i;
            } else if (c > pivot) {
                --gt;
                uint32_t tmp = items[i]; items[i] = items[gt]; items[gt] = tmp;
            } else {
                ++i;
            }
        }
        if (k < lt) hi = lt;
        else if (k >= gt) lo = gt;
        else return;
    }
}

sidx_status sidx__boxtree_build(sidx__boxtree *t, const sidx_aabb *boxes, uint32_t n, uint32_t leaf_size,
                                const sidx_allocator *al)
{
    memset(t, 0, sizeof *t);
    t->al = al ? *al : sidx__default_allocator();
    if (leaf_size == 0) leaf_size = 1;
    const size_t max_nodes = 2u * (size_t)(n ? n : 1);
    t->nodes = t->al.alloc(max_nodes * sizeof *t->nodes, t->al.user);
    t->items = t->al.alloc((n ? n : 1) * sizeof *t->items, t->al.user);
    if (!t->nodes || !t->items) { sidx__boxtree_free(t); return SIDX_ERR_NOMEM; }
    for (uint32_t i = 0; i < n; ++i) t->items[i] = i;
    t->num_items = n;

    struct { uint32_t node, lo, hi, depth; } stack[SIDX_BOXTREE_STACK];
    int sp = 0;
    t->num_nodes = 1;
    stack[sp].node = 0; stack[sp].lo = 0; stack[sp].hi = n; stack[sp].depth = 0; ++sp;
    while (sp > 0) {
        --sp;
        const uint32_t node = stack[sp].node, lo = stack[sp].lo, hi = stack[sp].hi, depth = stack[sp].depth;
        if (depth > t->depth) t->depth = depth;
        sidx_aabb box = sidx_aabb_empty(), cbox = sidx_aabb_empty();
        for (uint32_t i = lo; i < hi; ++i) {
            box = sidx_aabb_union(box, boxes[t->items[i]]);
            cbox = sidx_aabb_grow(cbox, sidx_aabb_centroid(boxes[t->items[i]]));
        }
        sidx__btnode *nd = &t->nodes[node];
        nd->box = box;
        if (hi - lo <= leaf_size || sp + 2 > SIDX_BOXTREE_STACK) {
            nd->first = lo;
            nd->count = hi - lo; /* 0 only for the root of an empty tree */
            continue;
        }
        const int axis = sidx_aabb_max_axis(cbox);
        const uint32_t mid = lo + (hi - lo) / 2;
        select_median(t->items, lo, hi, mid, boxes, axis);
        const uint32_t left = t->num_nodes;
        t->num_nodes += 2;
        nd->first = left;
        nd->count = SIDX_BT_INNER;
        stack[sp].node = left + 1; stack[sp].lo = mid; stack[sp].hi = hi; stack[sp].depth = depth + 1; ++sp;
        stack[sp].node = left; stack[sp].lo = lo; stack[sp].hi = mid; stack[sp].depth = depth + 1; ++sp;
    }
    return SIDX_OK;
}

void sidx__boxtree_free(sidx__boxtree *t)
{
    if (!t) return;
    if (t->nodes) t->al.free(t->nodes, t->al.user);
    if (t->items) t->al.free(t->items, t->al.user);
    t->nodes = NULL;
    t->items = NULL;
    t->num_nodes = t->num_items = 0;
}

size_t sidx__boxtree_bytes(const sidx__boxtree *t)
{
    return (size_t)t->num_nodes * sizeof *t->nodes + (size_t)t->num_items * sizeof *t->items;
}
