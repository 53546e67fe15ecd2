/* rayclass.c — ray classification (Arvo & Kirk 1987, "Fast ray tracing by
 * ray classification"): partition the 5D space of rays, origin (x, y, z)
 * × direction (cube face + (u, v) on it), and give every 5D cell the set
 * of triangles some ray of the cell can hit.  The deck: "partitioning of
 * space and direction", "roughly pre-computes visibility for the entire
 * scene".
 *
 * A ray of origin o and direction d belongs to direction face (k, s) with
 * k the axis of largest |d_k| and s its sign, at u = d_a/|d_k|,
 * v = d_b/|d_k| ((a, b) the other two axes): the direction cube.  Origins
 * are restricted to the scene box (a ray starting outside is first moved
 * to where it enters the box; nothing lies before that).
 *
 * Build: eager, to a fixed depth (Arvo & Kirk subdivide lazily; a lazy
 * build would have to lock, since built structures are queried from many
 * threads at once — an eager build keeps queries read-only, and the
 * memory it costs is exactly what the deck warns about).  For each of the
 * 6 faces a binary tree bisects the 5D cell, cycling u, v, x, y, z, until
 * a cell holds at most leaf_size candidates or max_depth is reached.  A
 * child's candidates are the parent's that pass the beam test:
 *
 *   the beam of a cell is { o + t·d : o in the origin box, d in the
 *   direction pyramid of the (u, v) rectangle, t >= 0 }.  A triangle box T
 *   meets it iff some x − o, x in T, o in the origin box, lies in the
 *   pyramid, i.e. iff the box of differences T ⊖ O = [T.min − O.max,
 *   T.max − O.min] meets the pyramid (a convex cone).  The cone is the
 *   intersection of 5 half-spaces through the origin (w >= 0 and the four
 *   u0·w <= d_a <= u1·w, v0·w <= d_b <= v1·w); the box is rejected when it
 *   lies outside one of them.  Conservative: a box outside the cone only
 *   near one of its edges is kept.
 *
 * Query: find the leaf by descending the face's tree with (o', u, v), then
 * test its candidates sorted by where they begin along the face axis
 * (s·T.min_k, Arvo & Kirk's "sorted by distance"): once a hit is found at
 * s·x_k = c, a candidate whose box begins beyond c cannot hold an earlier
 * hit, and the search stops. */
#include <stdio.h>
#include "sidx_internal.h"
#include "sidx/rayclass.h"

#define SIDX_STRUCTURE_NAME "rayclass"

#define RC_DEFAULT_LEAF 8u
#define RC_DEFAULT_DEPTH 8u
#define RC_MAX_DEPTH 24u
/* Budgets that bound memory and build time whatever the options: a 5D
 * tree doubles per level, so max_depth 24 on a handful of large triangles
 * asks for 6·2^25 nodes (fuzz_build: over 2 GB for 24 triangles).  Past
 * either budget the build stops with SIDX_ERR_LIMIT and says which option
 * to lower; the defaults (depth 8) stay far below both on any scene. */
#define RC_NODE_BUDGET (1u << 20)  /* nodes: 16 MB (depth 16 needs at most 6·2^17) */
#define RC_CAND_BUDGET (1u << 25)  /* candidate references: 256 MB */
#define RC_LEAF UINT32_MAX

typedef struct rc_node {
    float split;            /* inner: coordinate value of the bisection */
    uint32_t dim;           /* inner: 0..2 origin x, y, z; 3 u; 4 v.  RC_LEAF for leaves */
    uint32_t first;         /* inner: left child (right = first + 1); leaf: first candidate */
    uint32_t count;         /* leaf: number of candidates */
} rc_node;

typedef struct rc_tree {
    rc_node *nodes;
    uint32_t num_nodes;
    uint32_t roots[6];
    uint32_t *cand;         /* triangle ids, leaf by leaf, sorted by key */
    float *key;             /* s·T.min_k of each candidate's triangle box, for the early stop */
    uint32_t num_cand;
    sidx_aabb box;          /* the scene box, padded: origins live here */
    sidx_rayclass_info info;
} rc_tree;

typedef struct rc_build {
    sidx_accel *a;
    rc_tree *t;
    const sidx_aabb *tri_box;
    size_t cap_nodes, cap_cand, cap_key;
    uint32_t leaf_size, max_depth;
    double margin;          /* slack of the beam test, relative to the scene size */
    int failed;
    int over_budget;        /* failed because of RC_NODE_BUDGET / RC_CAND_BUDGET, not memory */
} rc_build;

/* 5D cell: lo/hi over x, y, z, u, v */
typedef struct rc_cell { double lo[5], hi[5]; } rc_cell;

static const int rc_order[5] = {3, 4, 0, 1, 2}; /* u, v, x, y, z */

/* Does triangle box T meet the beam of cell c on face (k, s)? */
static int beam_meets(const rc_build *b, const rc_cell *c, int k, double s, const sidx_aabb *T)
{
    const int a = (k + 1) % 3, bb = (k + 2) % 3;
    double dmin[3], dmax[3];
    for (int i = 0; i < 3; ++i) {
        dmin[i] = (double)sidx_v3_get(T->min, i) - c->hi[i];
        dmax[i] = (double)sidx_v3_get(T->max, i) - c->lo[i];
    }
    /* half-spaces n·d >= 0 of the cone */
    double n[5][3] = {{0}};
    n[0][k] = s;                                   /* w = s·d_k >= 0 */
    n[1][a] = 1.0;  n[1][k] = -c->lo[3] * s;       /* d_a − u0·w >= 0 */
    n[2][a] = -1.0; n[2][k] = c->hi[3] * s;        /* u1·w − d_a >= 0 */
    n[3][bb] = 1.0; n[3][k] = -c->lo[4] * s;       /* d_b − v0·w >= 0 */
    n[4][bb] = -1.0; n[4][k] = c->hi[4] * s;       /* v1·w − d_b >= 0 */
    for (int h = 0; h < 5; ++h) {
        double mx = 0.0;
        for (int i = 0; i < 3; ++i) mx += n[h][i] >= 0.0 ? n[h][i] * dmax[i] : n[h][i] * dmin[i];
        if (mx < -b->margin) return 0;
    }
    return 1;
}

static float face_key(const sidx_aabb *T, int k, double s)
{
    return s > 0 ? sidx_v3_get(T->min, k) : -sidx_v3_get(T->max, k);
}

typedef struct rc_keyed { float key; uint32_t tri; } rc_keyed;

static int cmp_keyed(const void *x, const void *y)
{
    const rc_keyed *a = x, *b = y;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    return a->tri < b->tri ? -1 : a->tri > b->tri;
}

static uint32_t rc_new_node(rc_build *b)
{
    if (b->t->num_nodes >= RC_NODE_BUDGET) {
        b->failed = b->over_budget = 1;
        return UINT32_MAX;
    }
    if (!sidx__grow(b->a, (void **)&b->t->nodes, &b->cap_nodes, (size_t)b->t->num_nodes + 1, sizeof *b->t->nodes)) {
        b->failed = 1;
        return UINT32_MAX;
    }
    return b->t->num_nodes++;
}

static void build_cell(rc_build *b, uint32_t id, const rc_cell *c, int k, double s, const uint32_t *cand, uint32_t n,
                       uint32_t parent, uint32_t depth)
{
    rc_tree *t = b->t;
    SIDX_EMIT(1, b->a->opt.hook, SIDX_EV_BUILD_NODE, e_.node = id; e_.parent = parent; e_.depth = depth; e_.count = n;
              e_.bounds.min = sidx_v3((float)c->lo[0], (float)c->lo[1], (float)c->lo[2]);
              e_.bounds.max = sidx_v3((float)c->hi[0], (float)c->hi[1], (float)c->hi[2]));
    if (depth > t->info.max_depth) t->info.max_depth = depth;
    if (n <= b->leaf_size || depth >= b->max_depth) {
        const size_t need = (size_t)t->num_cand + n;
        if (need > RC_CAND_BUDGET) {
            b->failed = b->over_budget = 1;
            return;
        }
        if (need > UINT32_MAX || !sidx__grow(b->a, (void **)&t->cand, &b->cap_cand, need, sizeof *t->cand) ||
            !sidx__grow(b->a, (void **)&t->key, &b->cap_key, need, sizeof *t->key)) {
            b->failed = 1;
            return;
        }
        rc_node *nd = &t->nodes[id];
        nd->dim = RC_LEAF;
        nd->first = t->num_cand;
        nd->count = n;
        rc_keyed *tmp = sidx__alloc(b->a, n, sizeof *tmp);
        if (!tmp) { b->failed = 1; return; }
        for (uint32_t i = 0; i < n; ++i) {
            tmp[i].key = face_key(&b->tri_box[cand[i]], k, s);
            tmp[i].tri = cand[i];
        }
        qsort(tmp, n, sizeof *tmp, cmp_keyed);
        for (uint32_t i = 0; i < n; ++i) {
            t->cand[t->num_cand + i] = tmp[i].tri;
            t->key[t->num_cand + i] = tmp[i].key;
        }
        sidx__free(b->a, tmp);
        t->num_cand += n;
        t->info.leaves++;
        if (n > t->info.max_candidates) t->info.max_candidates = n;
        SIDX_EMIT(1, b->a->opt.hook, SIDX_EV_BUILD_LEAF, e_.node = id; e_.depth = depth; e_.count = n;
                  e_.cost = (float)n; e_.reason = n <= b->leaf_size ? (n ? SIDX_LEAF_FEW_PRIMS : SIDX_LEAF_EMPTY)
                                                                      : SIDX_LEAF_MAX_DEPTH;
                  e_.prims = n ? t->cand + nd->first : NULL);
        return;
    }
    const int dim = rc_order[depth % 5];
    const double mid = 0.5 * (c->lo[dim] + c->hi[dim]);
    rc_cell ch[2] = {*c, *c};
    ch[0].hi[dim] = mid;
    ch[1].lo[dim] = mid;
    uint32_t *lists[2] = {NULL, NULL};
    uint32_t counts[2] = {0, 0};
    for (int side = 0; side < 2; ++side) {
        lists[side] = sidx__alloc(b->a, n, sizeof *lists[side]);
        if (!lists[side]) { b->failed = 1; break; }
        for (uint32_t i = 0; i < n; ++i)
            if (beam_meets(b, &ch[side], k, s, &b->tri_box[cand[i]])) lists[side][counts[side]++] = cand[i];
        t->info.beam_tests += n;
    }
    const uint32_t left = b->failed ? UINT32_MAX : rc_new_node(b);
    const uint32_t right = b->failed ? UINT32_MAX : rc_new_node(b);
    if (!b->failed) {
        rc_node *nd = &t->nodes[id];
        nd->dim = (uint32_t)dim;
        nd->split = (float)mid;
        nd->first = left;
        nd->count = 0;
        SIDX_EMIT(1, b->a->opt.hook, SIDX_EV_BUILD_SPLIT, e_.node = id; e_.depth = depth;
                  e_.axis = dim < 3 ? dim : -1; e_.pos = (float)mid; e_.count = counts[0]; e_.aux = counts[1];
                  e_.text = dim == 3 ? "rayclass: direction split (u)" : dim == 4 ? "rayclass: direction split (v)"
                                                                              : NULL);
        /* both children must be consecutive: the right one was allocated just after the left */
        build_cell(b, left, &ch[0], k, s, lists[0], counts[0], id, depth + 1);
        if (!b->failed) build_cell(b, right, &ch[1], k, s, lists[1], counts[1], id, depth + 1);
    }
    sidx__free(b->a, lists[0]);
    sidx__free(b->a, lists[1]);
}

static void rc_free_tree(const sidx_accel *a, rc_tree *t)
{
    if (!t) return;
    sidx__free(a, t->nodes);
    sidx__free(a, t->cand);
    sidx__free(a, t->key);
    sidx__free(a, t);
}

static sidx_status rc_build_fn(sidx_accel *a, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    rc_tree *t = sidx__calloc(a, 1, sizeof *t);
    if (!t) return sidx__fail(err, SIDX_ERR_NOMEM, "rayclass: out of memory");
    rc_build b;
    memset(&b, 0, sizeof b);
    b.a = a;
    b.t = t;
    b.leaf_size = a->opt.leaf_size ? a->opt.leaf_size : RC_DEFAULT_LEAF;
    b.max_depth = a->opt.max_depth ? a->opt.max_depth : RC_DEFAULT_DEPTH;
    if (b.max_depth > RC_MAX_DEPTH) b.max_depth = RC_MAX_DEPTH;
    sidx_aabb box = sidx_mesh_bounds(m);
    if (sidx_aabb_is_empty(box)) box.min = box.max = sidx_v3(0, 0, 0);
    /* Pad the origin box so every hit point lies strictly inside it: a ray
     * clipped to it then cannot start past a triangle on the scene's
     * boundary (the Cornell box's walls are its bounding box). */
    const sidx_vec3 ext = sidx_aabb_extent(box);
    float scale = fmaxf(fmaxf(ext.x, ext.y), ext.z);
    const float amax = fmaxf(fmaxf(fmaxf(fabsf(box.min.x), fabsf(box.min.y)), fmaxf(fabsf(box.min.z), fabsf(box.max.x))),
                             fmaxf(fabsf(box.max.y), fabsf(box.max.z)));
    const float pad = 1e-4f * fmaxf(scale, 1e-3f * amax) + 1e-6f * amax + 1e-30f;
    box.min = sidx_v3_sub(box.min, sidx_v3(pad, pad, pad));
    box.max = sidx_v3_add(box.max, sidx_v3(pad, pad, pad));
    t->box = box;
    b.margin = 1e-6 * ((double)scale + amax);
    sidx_aabb *tri_box = NULL;
    uint32_t *all = sidx__alloc(a, m->num_triangles, sizeof *all);
    if (!all || sidx__prim_boxes(a, &tri_box, NULL) != SIDX_OK) {
        sidx__free(a, all);
        rc_free_tree(a, t);
        return sidx__fail(err, SIDX_ERR_NOMEM, "rayclass: out of memory");
    }
    b.tri_box = tri_box;
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = box);
    for (int f = 0; f < 6 && !b.failed; ++f) {
        const int k = f >> 1;
        const double s = (f & 1) ? -1.0 : 1.0;
        rc_cell c;
        c.lo[0] = box.min.x; c.lo[1] = box.min.y; c.lo[2] = box.min.z;
        c.hi[0] = box.max.x; c.hi[1] = box.max.y; c.hi[2] = box.max.z;
        c.lo[3] = c.lo[4] = -1.0;
        c.hi[3] = c.hi[4] = 1.0;
        uint32_t n = 0;
        for (uint32_t i = 0; i < m->num_triangles; ++i)
            if (beam_meets(&b, &c, k, s, &tri_box[i])) all[n++] = i;
        t->info.beam_tests += m->num_triangles;
        const uint32_t root = rc_new_node(&b);
        if (b.failed) break;
        t->roots[f] = root;
        build_cell(&b, root, &c, k, s, all, n, UINT32_MAX, 0);
    }
    sidx__free(a, all);
    sidx__free(a, tri_box);
    if (b.failed) {
        rc_free_tree(a, t);
        if (b.over_budget)
            return sidx__fail(err, SIDX_ERR_LIMIT,
                              "rayclass: the 5D tree would exceed %u nodes or %u candidate references "
                              "(max_depth %u, leaf_size %u); lower max_depth or raise leaf_size",
                              RC_NODE_BUDGET, RC_CAND_BUDGET, b.max_depth, b.leaf_size);
        return sidx__fail(err, SIDX_ERR_NOMEM, "rayclass: out of memory");
    }
    t->info.nodes = t->num_nodes;
    t->info.candidates = t->num_cand;
    t->info.mean_candidates = t->info.leaves ? (double)t->num_cand / t->info.leaves : 0.0;
    t->info.bytes = sizeof *t + (size_t)t->num_nodes * sizeof *t->nodes +
                    (size_t)t->num_cand * (sizeof *t->cand + sizeof *t->key);
    SIDX_EMIT(1, a->opt.hook, SIDX_EV_BUILD_END, e_.node = t->num_nodes; e_.count = t->num_cand;
              e_.depth = t->info.max_depth);
    a->impl = t;
    return SIDX_OK;
}

/* ---- query ------------------------------------------------------------------- */

static SIDX_INLINE int rc_query(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                const int any_hit, const int traced)
{
    const rc_tree *t = a->impl;
    const sidx_mesh *m = a->mesh;
    float tmax = any_hit ? r->tmax : hit->t;
    float te, tx;
    if (!sidx__box_test(1, r, &t->box, r->tmin, tmax, &te, &tx)) {
        SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_MISS_ROOT;
                  e_.count = 0);
        return 0;
    }
    /* origin moved to where the ray enters the box, clamped into it */
    float p[5];
    const sidx_vec3 o = sidx_ray_at(r, te);
    p[0] = fminf(fmaxf(o.x, t->box.min.x), t->box.max.x);
    p[1] = fminf(fmaxf(o.y, t->box.min.y), t->box.max.y);
    p[2] = fminf(fmaxf(o.z, t->box.min.z), t->box.max.z);
    const float *d = sidx_v3_array(&r->dir);
    int k = 0;
    if (fabsf(d[1]) > fabsf(d[k])) k = 1;
    if (fabsf(d[2]) > fabsf(d[k])) k = 2;
    const int neg = d[k] < 0.0f;
    const float w = fabsf(d[k]);
    p[3] = d[(k + 1) % 3] / w;
    p[4] = d[(k + 2) % 3] / w;
    uint32_t node = t->roots[2 * k + neg], depth = 0;
    for (;;) {
        const rc_node *nd = &t->nodes[node];
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node; e_.depth = depth;
                  e_.t_near = te; e_.t_far = tx);
        if (nd->dim == RC_LEAF) break;
        node = nd->first + (p[nd->dim] < nd->split ? 0u : 1u);
        ++depth;
    }
    const rc_node *leaf = &t->nodes[node];
    const float s = neg ? -1.0f : 1.0f;
    const float ok = r->org.x * (k == 0) + r->org.y * (k == 1) + r->org.z * (k == 2);
    float stop = INFINITY; /* s·x_k of the best hit so far */
    uint32_t tests = 0;
    for (uint32_t i = 0; i < leaf->count; ++i) {
        if (t->key[leaf->first + i] > stop) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_HIT_IN_CELL;
                      e_.t = hit->t; e_.count = tests);
            return 1;
        }
        const uint32_t tri = t->cand[leaf->first + i];
        float th;
        const int h = sidx__mesh_tri_test(m, a->opt.tri, tri, r, tmax, &th);
        ++tests;
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.node = node; e_.prim = tri;
                  e_.result = h; e_.t = h ? th : INFINITY);
        if (!h) continue;
        if (any_hit) {
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.t = th; e_.count = tests);
            return 1;
        }
        tmax = th;
        hit->t = th;
        hit->prim = tri;
        /* the hit point's coordinate along the face axis, rounded up a
         * little so float error never stops the search too early */
        const float c = s * (ok + th * d[k]);
        stop = c + 1e-5f * (fabsf(c) + fabsf(ok) + fabsf(th * d[k]));
        SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = tri; e_.t = th);
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_STACK_EMPTY;
              e_.t = any_hit ? INFINITY : hit->t; e_.count = tests);
    return hit->prim != SIDX_NO_HIT;
}

static void rc_intersect_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    (void)rc_query(a, r, q, hit, 0, 0);
}
static void rc_intersect_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    (void)rc_query(a, r, q, hit, 0, 1);
}
static int rc_occluded_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    sidx_hit dummy = sidx_hit_none();
    return rc_query(a, r, q, &dummy, 1, 0);
}
static int rc_occluded_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    sidx_hit dummy = sidx_hit_none();
    return rc_query(a, r, q, &dummy, 1, 1);
}

/* The walk table (sidx_internal.h): the same for every build. */
static const sidx__walk_table rc_walks = {rc_intersect_plain, rc_intersect_traced, rc_occluded_plain,
                                            rc_occluded_traced};

static void rc_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    sidx__walk_intersect(&rc_walks, a, r, q, hit);
}

static int rc_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return sidx__walk_occluded(&rc_walks, a, r, q);
}

static void rc_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const rc_tree *t = a->impl;
    s->nodes = t->num_nodes;
    s->leaves = t->info.leaves;
    s->max_depth = t->info.max_depth;
    s->prim_refs = t->num_cand;
    s->bytes = t->info.bytes;
    uint32_t nonempty = 0;
    for (uint32_t i = 0; i < t->num_nodes; ++i)
        if (t->nodes[i].dim == RC_LEAF) {
            if (t->nodes[i].count) ++nonempty;
            else s->empty_leaves++;
        }
    s->mean_leaf_prims = nonempty ? (double)t->num_cand / nonempty : 0.0;
}

static void rc_destroy(sidx_accel *a)
{
    rc_free_tree(a, a->impl);
    a->impl = NULL;
}

const sidx_accel_vtable sidx__rayclass_vtable = {rc_build_fn, rc_intersect, rc_occluded, rc_stats, rc_destroy, NULL};

sidx_status sidx_rayclass_info_get(const sidx_accel *a, sidx_rayclass_info *out)
{
    if (!a || !out || a->vt != &sidx__rayclass_vtable || !a->impl) return SIDX_ERR_INVALID_ARG;
    *out = ((const rc_tree *)a->impl)->info;
    return SIDX_OK;
}
