/* octree.c — the octree and the quadtree (slides: "Octrees and
 * Quadtrees": "simplest hierarchical grid", each inner node a 2×2×2 grid,
 * "adaptive subdivision: adjust depth to local scene complexity").
 *
 * Build: start from the scene box; a node holding more than leaf_size
 * triangles (default 8) and above the depth limit is cut at its centre into
 * 8 equal children (4 for the quadtree: z is never cut, for 2D scenes such
 * as "flat2d"), and each triangle goes to every child it overlaps (exact
 * SAT test, as the grids).  Children are stored contiguously, so an inner
 * node is just the index of its first child.
 *
 * Traversal: front to back in ray order, with early termination when the
 * hit lies in the current leaf.  The child order comes from the ray itself
 * (in the spirit of Revelles, Ureña, Lastra 2000, "An Efficient Parametric
 * Algorithm for Octree Traversal"): at a node entered over [t_near, t_far]
 * the ray crosses the three mid-planes at t_x, t_y, t_z; it starts in the
 * child that holds the entry point and flips one bit of the child index
 * at each crossing inside (t_near, t_far), in increasing t — at most 4
 * children, each with its exact t interval, and no box test per child.  The children are
 * pushed far-to-near on a small explicit stack. */
#include <stddef.h>
#include "grid_internal.h"
#include "sidx/octree.h"

#define OCT_DEFAULT_LEAF 8u
/* The slides suggest ~10 levels; the teapot in a stadium needs more: the
 * teapot is 1/2000 of the scene, so at depth 10 a leaf is still twice its
 * size and holds all its triangles.  Depth only grows where triangles are
 * dense, so 16 costs nothing elsewhere. */
#define OCT_DEFAULT_DEPTH 16u
#define OCT_MAX_DEPTH 24u
/* Bounds (so no scene can blow the build up): besides the depth limit and
 * the duplication rule of build_node (which already keeps lesson 13's star
 * in one leaf), the tree never holds more than OCT_NODES_PER_TRI·n + 1
 * nodes; a node that would cross that budget stays a leaf (reported as
 * max_depth: the build's size limit, not the scene, ended it).  Memory is
 * then O(n) nodes and the build O(budget · n) triangle tests at worst;
 * the queries stay exact, only slower in the leaves it made.  Tested in
 * tests/test_octree.c: a star and a fan of slivers (the duplication rule
 * stops them at the root) and two pairs of specks that only separate 20+
 * levels down (the budget stops them). */
#define OCT_NODES_PER_TRI 64u

#define OCT_INNER 0xffffffffu

typedef struct onode {
    uint32_t a;  /* inner: first child; leaf: first reference */
    uint32_t n;  /* OCT_INNER, or the leaf's reference count */
} onode;

typedef struct octree {
    sidx_aabb box;
    onode *nodes;
    uint32_t *refs;
    uint32_t *scratch;                /* build only: triangle lists per level */
    size_t cap_nodes, cap_refs, cap_scratch;
    uint32_t n_nodes, n_refs, leaves, empty, depth_seen;
    uint32_t leaf_max, depth_max;
    uint64_t node_budget;             /* OCT_NODES_PER_TRI·n + 1 */
    int nsplit;                       /* axes cut: 3 (octree) or 2 (quadtree) */
    const sidx__walk_table *walks;    /* with or without the mailbox (build) */
    const sidx_aabb *tri_boxes;       /* build only */
} octree;

/* Its walk tables, without and with the mailbox (defined after the walk). */
static const sidx__walk_table octree_walks[2];

static void octree_free(const sidx_accel *a, octree *T)
{
    if (!T) return;
    sidx__free(a, T->nodes);
    sidx__free(a, T->refs);
    sidx__free(a, T->scratch);
    sidx__free(a, T);
}

/* The centre of a box: the same arithmetic in build and traversal, so the
 * mid-planes the ray crosses are exactly the ones the children were cut at. */
static SIDX_INLINE float mid(float lo, float hi) { return 0.5f * (lo + hi); }

/* Child `i` of box b: bit k of i set = upper half on axis k. */
static SIDX_INLINE sidx_aabb child_box(sidx_aabb b, uint32_t i, int nsplit)
{
    float *lo = sidx_v3_array_rw(&b.min), *hi = sidx_v3_array_rw(&b.max);
    for (int k = 0; k < nsplit; ++k) {
        const float m = mid(lo[k], hi[k]);
        if (i & (1u << k)) lo[k] = m;
        else hi[k] = m;
    }
    return b;
}

/* Makes node `node` a leaf holding scratch[s .. s+n). */
static sidx_status make_leaf(sidx_accel *a, octree *T, uint32_t node, size_t s, uint32_t n, uint32_t depth,
                             int reason)
{
    if ((uint64_t)T->n_refs + n >= UINT32_MAX) return SIDX_ERR_LIMIT;
    if (!sidx__grow(a, (void **)&T->refs, &T->cap_refs, (size_t)T->n_refs + n, sizeof *T->refs))
        return SIDX_ERR_NOMEM;
    if (n) memcpy(T->refs + T->n_refs, T->scratch + s, (size_t)n * sizeof *T->refs);
    T->nodes[node].a = T->n_refs;
    T->nodes[node].n = n;
    T->n_refs += n;
    T->leaves++;
    T->empty += n == 0;
    if (n == 0) reason = SIDX_LEAF_EMPTY;
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_LEAF, e_.node = node; e_.depth = depth; e_.count = n;
              e_.reason = reason; e_.prims = n ? T->refs + T->nodes[node].a : NULL);
    return SIDX_OK;
}

/* Node `node` over `box` holds scratch[s .. s+n); scratch from `top` on is
 * free.  The children's lists are computed first, all of them, so the
 * split can be refused when it does not separate anything: if the
 * children together hold more than OCT_MAX_DUP·n references, the
 * triangles are larger than the cells (or all meet at one vertex, or
 * stack up along the quadtree's uncut z) and cutting again only copies
 * them — the node stays a leaf (reason no_split).  A small dense object
 * in a big empty node (the teapot in the stadium) keeps the sum near n and
 * is refined as deep as it needs. */
#define OCT_MAX_DUP 2.5
static sidx_status build_node(sidx_accel *a, octree *T, uint32_t node, uint32_t parent, sidx_aabb box, size_t s,
                              uint32_t n, size_t top, uint32_t depth)
{
    const sidx_hook *hook = a->opt.hook;
    const sidx_mesh *m = a->mesh;
    if (depth > T->depth_seen) T->depth_seen = depth;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = node; e_.parent = parent; e_.depth = depth; e_.count = n;
              e_.bounds = box);
    if (n <= T->leaf_max) return make_leaf(a, T, node, s, n, depth, SIDX_LEAF_FEW_PRIMS);
    if (depth >= T->depth_max) return make_leaf(a, T, node, s, n, depth, SIDX_LEAF_MAX_DEPTH);
    if ((uint64_t)T->n_nodes + (1u << T->nsplit) > T->node_budget)
        return make_leaf(a, T, node, s, n, depth, SIDX_LEAF_MAX_DEPTH);
    {
        /* Children must stay well above the float spacing of the
         * coordinates (a scene at 1e6 has an ulp of 0.06). */
        const float *lo = sidx_v3_array(&box.min), *hi = sidx_v3_array(&box.max);
        for (int k = 0; k < T->nsplit; ++k) {
            const float mag = fabsf(lo[k]) > fabsf(hi[k]) ? fabsf(lo[k]) : fabsf(hi[k]);
            if (0.5f * (hi[k] - lo[k]) < 16.0f * FLT_EPSILON * mag)
                return make_leaf(a, T, node, s, n, depth, SIDX_LEAF_NO_SPLIT);
        }
    }
    const uint32_t nch = 1u << T->nsplit;
    size_t off[9];
    off[0] = top;
    for (uint32_t i = 0; i < nch; ++i) {
        const sidx_aabb cb = child_box(box, i, T->nsplit);
        if (!sidx__grow(a, (void **)&T->scratch, &T->cap_scratch, off[i] + n, sizeof *T->scratch))
            return SIDX_ERR_NOMEM;
        off[i + 1] = off[i] + sidx__clip_to_cell(m, T->tri_boxes, T->scratch + s, n, cb, T->scratch + off[i]);
    }
    if ((double)(off[nch] - top) > OCT_MAX_DUP * (double)n)
        return make_leaf(a, T, node, s, n, depth, SIDX_LEAF_NO_SPLIT);
    const uint32_t first = T->n_nodes;
    if ((uint64_t)first + nch >= UINT32_MAX) return SIDX_ERR_LIMIT;
    if (!sidx__grow(a, (void **)&T->nodes, &T->cap_nodes, (size_t)first + nch, sizeof *T->nodes))
        return SIDX_ERR_NOMEM;
    T->n_nodes += nch;
    T->nodes[node].a = first;
    T->nodes[node].n = OCT_INNER;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_SPLIT, e_.node = node; e_.depth = depth; e_.axis = -1; e_.bounds = box;
              e_.count = n; e_.aux = (uint32_t)(off[nch] - top));
    for (uint32_t i = 0; i < nch; ++i) {
        const sidx_status st = build_node(a, T, first + i, node, child_box(box, i, T->nsplit), off[i],
                                          (uint32_t)(off[i + 1] - off[i]), off[nch], depth + 1);
        if (st != SIDX_OK) return st;
    }
    return SIDX_OK;
}

static sidx_status octree_build(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    octree *T = sidx__calloc(a, 1, sizeof *T);
    sidx_aabb *boxes = NULL;
    if (!T) return sidx__fail(err, SIDX_ERR_NOMEM, "octree: out of memory");
    T->nsplit = a->variant == 1 ? 2 : 3;
    T->walks = &octree_walks[!a->opt.no_mailbox];
    T->leaf_max = a->opt.leaf_size ? a->opt.leaf_size : OCT_DEFAULT_LEAF;
    T->depth_max = a->opt.max_depth ? a->opt.max_depth : OCT_DEFAULT_DEPTH;
    if (T->depth_max > OCT_MAX_DEPTH) T->depth_max = OCT_MAX_DEPTH;
    T->node_budget = (uint64_t)OCT_NODES_PER_TRI * m->num_triangles + 1u;
    sidx_status st = SIDX_ERR_NOMEM;
    if (m->num_triangles && sidx__prim_boxes(a, &boxes, NULL) != SIDX_OK) goto fail;
    T->tri_boxes = boxes;
    T->box = sidx__grid_box(sidx_mesh_bounds(m));
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = T->box);
    if (!sidx__grow(a, (void **)&T->nodes, &T->cap_nodes, 1, sizeof *T->nodes)) goto fail;
    if (!sidx__grow(a, (void **)&T->scratch, &T->cap_scratch, (size_t)m->num_triangles + 1u, sizeof *T->scratch))
        goto fail;
    for (uint32_t i = 0; i < m->num_triangles; ++i) T->scratch[i] = i;
    T->n_nodes = 1;
    st = build_node(a, T, 0, UINT32_MAX, T->box, 0, m->num_triangles, m->num_triangles, 0);
    if (st != SIDX_OK) goto fail;
    sidx__free(a, T->scratch);
    T->scratch = NULL;
    T->cap_scratch = 0;
    T->tri_boxes = NULL;
    sidx__free(a, boxes);
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_END, e_.node = T->n_nodes; e_.count = T->n_refs;
              e_.depth = T->depth_seen);
    a->impl = T;
    return SIDX_OK;
fail:
    sidx__free(a, boxes);
    octree_free(a, T);
    return sidx__fail(err, st, st == SIDX_ERR_NOMEM ? "octree: out of memory" : "octree: too many nodes");
}

typedef struct oentry {
    sidx_aabb box;
    float t_near, t_far;
    uint32_t node, depth;
} oentry;

static SIDX_INLINE int octree_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                   const int traced, const int any, const int use_mb)
{
    const octree *T = a->impl;
    float t_near, t_far;
    if (!sidx__clip(a, r, &T->box, hit->t, &t_near, &t_far)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.t = hit->t; e_.count = 0);
        return 0;
    }
    const int nsplit = T->nsplit;
    const float *o = sidx_v3_array(&r->org), *dir = sidx_v3_array(&r->dir), *inv = sidx_v3_array(&r->inv_dir);
    /* Each level pushes at most 3 children beyond the one taken next. */
    oentry stack[3u * (OCT_MAX_DEPTH + 1u) + 4u];
    uint32_t stack_len = 0;
    stack[stack_len++] = (oentry){T->box, t_near, t_far, 0, 0};
    sidx__mailbox mb;
    if (use_mb) sidx__mailbox_clear(&mb);
    uint32_t visited = 0;
    int reason = SIDX_TERM_STACK_EMPTY;
    while (stack_len) {
        const oentry entry = stack[--stack_len];
        SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_POP, e_.ray_id = q->ray_id; e_.node = entry.node;
                  e_.depth = stack_len + 1; e_.t_near = entry.t_near; e_.t_far = entry.t_far);
        /* Front to back: everything left on the stack starts later. */
        if (entry.t_near > hit->t) {
            reason = hit->prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL : SIDX_TERM_STACK_EMPTY;
            break;
        }
        const onode node = T->nodes[entry.node];
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = entry.node;
                  e_.depth = entry.depth; e_.t_near = entry.t_near; e_.t_far = entry.t_far; e_.bounds = entry.box);
        if (node.n != OCT_INNER) {
            /* a tree without references has refs NULL: no offset on it (UBSan, fuzz_build) */
            if (sidx__cell_prims(a, r, q, hit, node.n ? T->refs + node.a : NULL, node.n, entry.node, entry.depth,
                                 &mb, use_mb, traced, any)) {
                SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                          e_.count = visited);
                return 1;
            }
            if (hit->t <= entry.t_far) {
                reason = hit->prim != SIDX_NO_HIT ? SIDX_TERM_HIT_IN_CELL : SIDX_TERM_STACK_EMPTY;
                break;
            }
            continue;
        }
        /* Mid-plane crossings and the entry child. */
        const float *lo = sidx_v3_array(&entry.box.min), *hi = sidx_v3_array(&entry.box.max);
        float t_mid[3];
        uint32_t child = 0;
        int order[3], n_cross = 0;
        for (int k = 0; k < nsplit; ++k) {
            const float mk = mid(lo[k], hi[k]);
            if (dir[k] == 0.0f) {
                /* Never crosses; the side is where the origin is (on the
                 * plane: the upper child, as the grids' floor does). */
                t_mid[k] = INFINITY;
                if (o[k] >= mk) child |= 1u << k;
                continue;
            }
            t_mid[k] = (mk - o[k]) * inv[k];
            const int crossed = t_mid[k] <= entry.t_near;
            if (crossed == (dir[k] > 0.0f)) child |= 1u << k;
            if (t_mid[k] > entry.t_near && t_mid[k] < entry.t_far) order[n_cross++] = k;
        }
        /* Sort the crossings inside (t_near, t_far) by t (at most 3). */
        for (int i = 1; i < n_cross; ++i)
            for (int j = i; j > 0 && t_mid[order[j]] < t_mid[order[j - 1]]; --j) {
                const int tmp = order[j];
                order[j] = order[j - 1];
                order[j - 1] = tmp;
            }
        /* Children in ray order: c_0 over [t_near, t_mid_0], c_1 = c_0 ^ bit over
         * [t_mid_0, t_mid_1], ...; pushed last-first so the first pops first. */
        uint32_t child_ids[4];
        float t_bounds[5];
        child_ids[0] = child;
        t_bounds[0] = entry.t_near;
        for (int i = 0; i < n_cross; ++i) {
            t_bounds[i + 1] = t_mid[order[i]];
            child_ids[i + 1] = child_ids[i] ^ (1u << order[i]);
        }
        t_bounds[n_cross + 1] = entry.t_far;
        for (int i = n_cross; i >= 0; --i) {
            const oentry c = {child_box(entry.box, child_ids[i], nsplit), t_bounds[i], t_bounds[i + 1],
                              node.a + child_ids[i], entry.depth + 1};
            stack[stack_len++] = c;
            SIDX_EMIT(traced, q->hook, SIDX_EV_STACK_PUSH, e_.ray_id = q->ray_id; e_.node = c.node;
                      e_.depth = stack_len; e_.t_near = c.t_near; e_.t_far = c.t_far);
        }
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = reason; e_.t = hit->t;
              e_.count = visited);
    (void)reason;
    (void)visited;
    return 0;
}

SIDX__GRID_WALK_TABLES(octree_walk, octree_walks);

static void octree_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    const octree *T = a->impl;
    sidx__walk_intersect(T->walks, a, r, q, hit);
}

static int octree_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    const octree *T = a->impl;
    return sidx__walk_occluded(T->walks, a, r, q);
}

static void octree_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const octree *T = a->impl;
    s->nodes = T->n_nodes;
    s->leaves = T->leaves;
    s->max_depth = T->depth_seen;
    s->prim_refs = T->n_refs;
    s->bytes = sizeof *T + T->cap_nodes * sizeof *T->nodes + T->cap_refs * sizeof *T->refs;
    s->empty_leaves = T->empty;
    const uint32_t full = T->leaves - T->empty;
    s->mean_leaf_prims = full ? (double)T->n_refs / (double)full : 0.0;
    /* The finest cells' resolution, as if the deepest level were a grid. */
    const uint32_t r = T->depth_seen < 31 ? 1u << T->depth_seen : 0x80000000u;
    s->res[0] = r;
    s->res[1] = r;
    s->res[2] = T->nsplit == 3 ? r : 1u;
}

static void octree_destroy(sidx_accel *a)
{
    octree_free(a, a->impl);
    a->impl = NULL;
}

const sidx_accel_vtable sidx__octree_vtable = {octree_build, octree_intersect, octree_occluded, octree_stats,
                                               octree_destroy, NULL};

/* ---- sidx/octree.h: the read-only view ----------------------------------- */

_Static_assert(sizeof(sidx_oct_node) == sizeof(onode) && offsetof(sidx_oct_node, a) == offsetof(onode, a) &&
                   offsetof(sidx_oct_node, n) == offsetof(onode, n) && SIDX_OCT_INNER == OCT_INNER,
               "sidx/octree.h's node is octree.c's node");

static sidx_status oct_view(const sidx_accel *a, const void *p, const void *q, sidx_error *err, const char *fn,
                            const octree **out)
{
    if (!a || !p || !q) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", fn);
    if (a->vt != &sidx__octree_vtable || !a->impl)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "%s: '%s' is not an octree", fn, a->name ? a->name : "?");
    *out = a->impl;
    return SIDX_OK;
}

sidx_status sidx_octree_nodes(const sidx_accel *a, const sidx_oct_node **nodes, uint32_t *count, sidx_error *err)
{
    const octree *T = NULL;
    const sidx_status s = oct_view(a, nodes, count, err, "sidx_octree_nodes", &T);
    if (s != SIDX_OK) return s;
    *nodes = (const sidx_oct_node *)T->nodes;
    *count = T->n_nodes;
    return SIDX_OK;
}

sidx_status sidx_octree_refs(const sidx_accel *a, const uint32_t **refs, uint32_t *count, sidx_error *err)
{
    const octree *T = NULL;
    const sidx_status s = oct_view(a, refs, count, err, "sidx_octree_refs", &T);
    if (s != SIDX_OK) return s;
    *refs = T->n_refs ? T->refs : NULL;
    *count = T->n_refs;
    return SIDX_OK;
}

sidx_status sidx_octree_info(const sidx_accel *a, sidx_aabb *root_box, int *axes_cut, sidx_error *err)
{
    const octree *T = NULL;
    const sidx_status s = oct_view(a, root_box, axes_cut, err, "sidx_octree_info", &T);
    if (s != SIDX_OK) return s;
    *root_box = T->box;
    *axes_cut = T->nsplit;
    return SIDX_OK;
}
