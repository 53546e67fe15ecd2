/* instance.c — the aggregate object and instancing (see sidx/instance.h).
 *
 * Build: invert every transform (the ray goes into object space, not the
 * geometry into world space), transform the child's bounds into a world
 * box (the 8 corners: an affine map of a box is bounded by the box of its
 * corners), and build a small BVH over the world boxes (boxtree.c) — the
 * issue's "top level is a BVH over instances".
 *
 * Query: walk the top BVH nearer child first, skipping boxes that begin
 * beyond the best hit; at an instance, o' = M⁻¹·o, d' = M⁻¹₃·d (not
 * renormalized, so the t of a hit is the same in both spaces) and the
 * child's own traversal runs with the best t so far as its bound.  Events
 * of the child flow to the same hook, bracketed by a NOTE naming the
 * instance.
 *
 * Mesh instances (sidx_aggregate_build_meshes): the aggregate builds each
 * distinct (mesh, structure, options) itself — all at once, or lazily, the
 * first time a ray enters an instance's world box, through lazy.c (claim,
 * wait, publish, failure, counters).  Their top level holds one instance
 * per leaf, so the box the top walk tests before reaching an instance is
 * that instance's own, lazy or eager alike: the two walks are one. */
#include <stdio.h>
#include "sidx_internal.h"
#include "hit.h"
#include "boxtree.h"
#include "lazy.h"
#include "sidx/instance.h"

#define SIDX_STRUCTURE_NAME "aggregate"

/* What an aggregate's hit is finished with (sidx__hit_finish, hit.c):
 * t refined, u, v and the normal.  An instanced hit carries no point:
 * its triangle lies in the child's space, not in a->mesh. */
#define AGG_FINISH (SIDX__QUERY_REFINE_T | SIDX_QUERY_UV | SIDX_QUERY_NORMAL)

typedef struct agg_inst {
    const sidx_accel *accel; /* NULL for a lazy mesh instance: its structure is part `part` of agg_impl.lazy */
    float m[12];            /* object to world */
    float inv[12];          /* world to object */
    uint32_t leaf_base;     /* first leaf instance id */
    uint32_t part;          /* mesh instances: its structure's index in agg_impl.src; UINT32_MAX otherwise */
    int nested;             /* child is an aggregate */
} agg_inst;

/* A structure a mesh aggregate builds (sidx_mesh_instance): what to build
 * and, for the BUILD_LAZY_EXPAND event, where its first instance stands. */
typedef struct agg_src {
    const sidx_mesh *mesh;
    char name[32];           /* registry name (copied: the caller's string need not outlive the build) */
    sidx_build_options opt;  /* hook and alloc replaced at build */
    uint32_t uses;           /* instances placing it */
    uint32_t first;          /* its first instance */
    sidx_aabb box;           /* that instance's world box */
} agg_src;

typedef struct agg_impl {
    agg_inst *inst;
    uint32_t n;
    uint32_t leaves;        /* leaf instances in total */
    sidx__boxtree tree;
    size_t node_slots;      /* nodes allocated for tree (>= tree.num_nodes) */
    sidx_aabb box;
    /* mesh instances only: the structures to build, one lazy part each
     * (eager: all built and published before the aggregate is returned) */
    agg_src *src;
    sidx__lazy_part *parts;
    sidx__lazy *lazy;
    uint32_t num_src;
} agg_impl;

static const sidx_mesh agg_no_mesh = {NULL, NULL, 0, 0};
extern const sidx_accel_vtable sidx__aggregate_vtable;

int sidx_accel_is_aggregate(const sidx_accel *a) { return a && a->vt == &sidx__aggregate_vtable; }

/* ---- affine helpers ------------------------------------------------------------ */

static sidx_vec3 xf_point(const float *m, sidx_vec3 p)
{
    return sidx_v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                   m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}
static sidx_vec3 xf_vector(const float *m, sidx_vec3 v)
{
    return sidx_v3(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
                   m[8] * v.x + m[9] * v.y + m[10] * v.z);
}
/* normals go by the inverse transpose: n_world = (M⁻¹)ᵀ·n */
static sidx_vec3 xf_normal(const float *inv, sidx_vec3 n)
{
    return sidx_v3(inv[0] * n.x + inv[4] * n.y + inv[8] * n.z, inv[1] * n.x + inv[5] * n.y + inv[9] * n.z,
                   inv[2] * n.x + inv[6] * n.y + inv[10] * n.z);
}
/* a∘b (apply b first), both 3×4 */
static void xf_compose(const float *a, const float *b, float *out)
{
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) {
            double s = c == 3 ? a[4 * r + 3] : 0.0;
            for (int k = 0; k < 3; ++k) s += (double)a[4 * r + k] * b[4 * k + c];
            out[4 * r + c] = (float)s;
        }
    }
}
/* Inverse of an affine 3×4 in double; 0 if singular or not finite. */
static int xf_invert(const float *m, float *inv)
{
    double a[9];
    for (int r = 0; r < 3; ++r) for (int c = 0; c < 3; ++c) a[3 * r + c] = m[4 * r + c];
    const double c0 = a[4] * a[8] - a[5] * a[7], c1 = a[5] * a[6] - a[3] * a[8], c2 = a[3] * a[7] - a[4] * a[6];
    const double det = a[0] * c0 + a[1] * c1 + a[2] * c2;
    if (!(fabs(det) > 0.0) || !isfinite(det)) return 0;
    const double id = 1.0 / det;
    double b[9] = {c0 * id, (a[2] * a[7] - a[1] * a[8]) * id, (a[1] * a[5] - a[2] * a[4]) * id,
                   c1 * id, (a[0] * a[8] - a[2] * a[6]) * id, (a[2] * a[3] - a[0] * a[5]) * id,
                   c2 * id, (a[1] * a[6] - a[0] * a[7]) * id, (a[0] * a[4] - a[1] * a[3]) * id};
    for (int r = 0; r < 3; ++r) {
        double t = 0.0;
        for (int k = 0; k < 3; ++k) t -= b[3 * r + k] * m[4 * k + 3];
        for (int c = 0; c < 3; ++c) inv[4 * r + c] = (float)b[3 * r + c];
        inv[4 * r + 3] = (float)t;
    }
    for (int i = 0; i < 12; ++i) if (!isfinite(inv[i])) return 0;
    return 1;
}

static sidx_aabb child_bounds(const sidx_accel *c)
{
    if (sidx_accel_is_aggregate(c)) return ((const agg_impl *)c->impl)->box;
    return sidx_mesh_bounds(c->mesh);
}

static sidx_aabb xf_box(const float *m, sidx_aabb b)
{
    sidx_aabb out = sidx_aabb_empty();
    if (sidx_aabb_is_empty(b)) return out;
    for (int i = 0; i < 8; ++i) {
        const sidx_vec3 p = sidx_v3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
        out = sidx_aabb_grow(out, xf_point(m, p));
    }
    return out;
}

/* ---- build ------------------------------------------------------------------------ */

static void agg_destroy(sidx_accel *a)
{
    agg_impl *g = a->impl;
    if (!g) return;
    if (g->lazy && g->lazy->parts)
        for (uint32_t p = 0; p < g->num_src; ++p) sidx_accel_destroy(sidx__lazy_peek(g->lazy, p));
    sidx__free(a, g->lazy);
    sidx__free(a, g->parts);
    sidx__free(a, g->src);
    sidx__boxtree_free(&g->tree);
    sidx__free(a, g->inst);
    sidx__free(a, g);
    a->impl = NULL;
}

static void *agg_malloc(size_t size, void *user) { (void)user; return malloc(size); }
static void agg_mfree(void *p, void *user) { (void)user; free(p); }

/* The aggregate's shell: the allocator resolved, the structure, its impl,
 * the instance array and a box per instance (freed by agg_finish). */
static sidx_status agg_new(uint32_t n, const sidx_build_options *opt, sidx_accel **out, sidx_aabb **boxes,
                           sidx_error *err)
{
    sidx_allocator al = {agg_malloc, agg_mfree, NULL};
    if (opt && opt->alloc) {
        if (!opt->alloc->alloc || !opt->alloc->free)
            return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: allocator needs alloc and free");
        al = *opt->alloc;
    }
    sidx_accel *a = al.alloc(sizeof *a, al.user);
    if (!a) return sidx__fail(err, SIDX_ERR_NOMEM, "aggregate: out of memory");
    memset(a, 0, sizeof *a);
    a->vt = &sidx__aggregate_vtable;
    a->name = "aggregate";
    a->mesh = &agg_no_mesh;
    a->alloc = al;
    if (opt) { a->opt = *opt; a->opt.hook = NULL; a->opt.alloc = NULL; }
    agg_impl *g = sidx__calloc(a, 1, sizeof *g);
    *boxes = NULL;
    if (g) {
        a->impl = g;
        g->inst = sidx__alloc(a, n, sizeof *g->inst);
        *boxes = sidx__alloc(a, n, sizeof **boxes);
    }
    if (!g || !g->inst || !*boxes) {
        sidx__free(a, *boxes);
        *boxes = NULL;
        agg_destroy(a);
        al.free(a, al.user);
        return sidx__fail(err, SIDX_ERR_NOMEM, "aggregate: out of memory");
    }
    g->n = n;
    g->box = sidx_aabb_empty();
    *out = a;
    return SIDX_OK;
}

/* The top level over the instances' world boxes (leaves of at most
 * leaf_size instances) and the build events; frees boxes, and a on failure. */
static sidx_status agg_finish(sidx_accel *a, sidx_aabb *boxes, uint32_t leaf_size, const sidx_hook *hook,
                              sidx_error *err)
{
    agg_impl *g = a->impl;
    const uint32_t n = g->n;
    const sidx_allocator al = a->alloc;
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_BEGIN, e_.count = n; e_.bounds = g->box);
    const sidx_status s = sidx__boxtree_build(&g->tree, boxes, n, leaf_size, &al);
    sidx__free(a, boxes);
    if (s != SIDX_OK) {
        agg_destroy(a);
        al.free(a, al.user);
        return sidx__fail(err, s, "aggregate: out of memory");
    }
    /* boxtree.c allocates room for 2n nodes; a tree with leaves of up to 2
     * instances uses about n.  Give the rest back, so that what an
     * aggregate holds is what its stats report (the bytes per instance are
     * the point of instancing).  If the smaller block cannot be had, keep
     * the big one: nothing is lost but memory. */
    g->node_slots = 2u * (size_t)(n ? n : 1);
    if (g->tree.num_nodes < g->node_slots) {
        sidx__btnode *fit = al.alloc((size_t)g->tree.num_nodes * sizeof *fit, al.user);
        if (fit) {
            memcpy(fit, g->tree.nodes, (size_t)g->tree.num_nodes * sizeof *fit);
            al.free(g->tree.nodes, al.user);
            g->tree.nodes = fit;
            g->node_slots = g->tree.num_nodes;
        }
    }
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = 0; e_.parent = UINT32_MAX; e_.depth = 0; e_.count = n;
              e_.bounds = g->tree.nodes[0].box);
    for (uint32_t i = 0; i < g->tree.num_nodes; ++i) {
        const sidx__btnode *nd = &g->tree.nodes[i];
        if (nd->count == SIDX_BT_INNER) {
            SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = nd->first; e_.parent = i; e_.bounds = g->tree.nodes[nd->first].box);
            SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = nd->first + 1; e_.parent = i;
                      e_.bounds = g->tree.nodes[nd->first + 1].box);
        } else {
            SIDX_EMIT(1, hook, SIDX_EV_BUILD_LEAF, e_.node = i; e_.count = nd->count; e_.reason = SIDX_LEAF_FEW_PRIMS;
                      e_.prims = nd->count ? g->tree.items + nd->first : NULL);
        }
    }
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_END, e_.node = g->tree.num_nodes; e_.count = n; e_.depth = g->tree.depth);
    return SIDX_OK;
}

sidx_status sidx_aggregate_build(const sidx_instance *instances, uint32_t n, const sidx_build_options *opt,
                                 sidx_accel **out, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: out is NULL");
    *out = NULL;
    if (n && !instances) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: instances is NULL");
    uint64_t leaves = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (!instances[i].accel) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: instance %u has no structure", i);
        float inv[12];
        if (!xf_invert(instances[i].xform, inv))
            return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: instance %u has a singular or non-finite transform", i);
        leaves += sidx_aggregate_leaf_count(instances[i].accel);
    }
    if (leaves >= UINT32_MAX - 1) return sidx__fail(err, SIDX_ERR_LIMIT, "aggregate: too many leaf instances");
    sidx_accel *a = NULL;
    sidx_aabb *boxes = NULL;
    sidx_status s = agg_new(n, opt, &a, &boxes, err);
    if (s != SIDX_OK) return s;
    agg_impl *g = a->impl;
    uint32_t base = 0;
    const sidx_accel *last_child = NULL;
    sidx_aabb last_box = sidx_aabb_empty();
    for (uint32_t i = 0; i < n; ++i) {
        agg_inst *in = &g->inst[i];
        in->accel = instances[i].accel;
        memcpy(in->m, instances[i].xform, sizeof in->m);
        xf_invert(in->m, in->inv);
        in->nested = sidx_accel_is_aggregate(in->accel);
        in->part = UINT32_MAX;
        in->leaf_base = base;
        base += sidx_aggregate_leaf_count(in->accel);
        /* a lazy child: the queries must say when its expansion failed */
        if (in->accel->lazy) a->lazy = 1;
        if (in->accel != last_child) { last_child = in->accel; last_box = child_bounds(in->accel); }
        boxes[i] = xf_box(in->m, last_box);
        g->box = sidx_aabb_union(g->box, boxes[i]);
    }
    g->leaves = base;
    s = agg_finish(a, boxes, 2, opt ? opt->hook : NULL, err);
    if (s == SIDX_OK) *out = a;
    return s;
}

/* ---- mesh instances -------------------------------------------------------------------- */

/* The structure of src, built over its mesh with its options, the
 * aggregate's allocator and the given hook.  NULL on failure (the build
 * keeps nothing: sidx_accel_build). */
static sidx_status src_build(const sidx_accel *a, const agg_src *src, const sidx_hook *hook, sidx_accel **c,
                             sidx_error *err)
{
    sidx_build_options o = src->opt;
    o.hook = hook;
    o.alloc = &a->alloc;
    return sidx_accel_build(src->name, src->mesh, &o, c, err);
}

static void src_made(const agg_src *src, const sidx_accel *c, sidx__lazy_made *made)
{
    sidx_accel_stats st;
    sidx_accel_stats_get(c, &st);
    made->refs = src->uses;
    made->bytes = st.bytes;
    made->depth = 0;
}

/* The expand function (lazy.h): part p is the structure of agg_src p,
 * built on the query's thread, its events on the query's hook. */
static void *agg_expand(void *owner, uint32_t p, const sidx_hook *hook, sidx__lazy_made *made)
{
    const sidx_accel *a = owner;
    const agg_impl *g = a->impl;
    const agg_src *src = &g->src[p];
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_LAZY_EXPAND, e_.structure = a->name; e_.node = src->first;
              e_.parent = UINT32_MAX; e_.depth = 0; e_.count = src->mesh->num_triangles; e_.bounds = src->box);
    sidx_accel *c = NULL;
    if (src_build(a, src, hook, &c, NULL) == SIDX_OK) src_made(src, c, made);
    return c;
}

/* Instances i and j build the same structure. */
static int same_src(const sidx_mesh_instance *x, const sidx_mesh_instance *y)
{
    return x->mesh == y->mesh && x->opt == y->opt && !strcmp(x->accel ? x->accel : "bvh", y->accel ? y->accel : "bvh");
}

static size_t src_hash(const sidx_mesh_instance *x)
{
    uint64_t h = (uint64_t)(uintptr_t)x->mesh * 0x9E3779B97F4A7C15ull ^ (uint64_t)(uintptr_t)x->opt * 0xC2B2AE3D27D4EB4Full;
    return (size_t)(h ^ (h >> 29));
}

/* The options each structure will be built with, checked now on one
 * triangle, so that a lazy build fails at a query only for want of memory. */
static sidx_status src_check(const sidx_accel *a, const agg_src *src, sidx_error *err)
{
    sidx_vec3 pos[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    uint32_t idx[3] = {0, 1, 2};
    const sidx_mesh one = {pos, idx, 3, 1};
    agg_src t = *src;
    t.mesh = &one;
    sidx_accel *c = NULL;
    const sidx_status s = src_build(a, &t, NULL, &c, err);
    sidx_accel_destroy(c);
    return s;
}

sidx_status sidx_aggregate_build_meshes(const sidx_mesh_instance *instances, uint32_t n, const sidx_build_options *opt,
                                        sidx_accel **out, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: out is NULL");
    *out = NULL;
    if (n && !instances) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: instances is NULL");
    if (n >= UINT32_MAX - 1) return sidx__fail(err, SIDX_ERR_LIMIT, "aggregate: too many leaf instances");
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_mesh_instance *x = &instances[i];
        if (!x->mesh) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: instance %u has no mesh", i);
        const char *name = x->accel ? x->accel : "bvh";
        if (!sidx_accel_is_registered(name) || strlen(name) >= sizeof(((agg_src *)0)->name))
            return sidx__fail(err, SIDX_ERR_UNKNOWN_ACCEL, "aggregate: instance %u: no structure named '%s'", i, name);
        float inv[12];
        if (!xf_invert(x->xform, inv))
            return sidx__fail(err, SIDX_ERR_INVALID_ARG, "aggregate: instance %u has a singular or non-finite transform", i);
    }
    const int lazy = opt && opt->lazy;
    sidx_accel *a = NULL;
    sidx_aabb *boxes = NULL;
    sidx_status s = agg_new(n, opt, &a, &boxes, err);
    if (s != SIDX_OK) return s;
    agg_impl *g = a->impl;
    /* the distinct structures: an open-addressing table over (mesh, options, name) */
    size_t cap = 16;
    while (cap < 2u * (size_t)n) cap *= 2;
    uint32_t *table = sidx__alloc(a, cap, sizeof *table);
    g->src = sidx__alloc(a, n ? n : 1u, sizeof *g->src);
    g->lazy = sidx__calloc(a, 1, sizeof *g->lazy);
    if (!table || !g->src || !g->lazy) {
        s = sidx__fail(err, SIDX_ERR_NOMEM, "aggregate: out of memory");
        goto fail;
    }
    memset(table, 0xFF, cap * sizeof *table);
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_mesh_instance *x = &instances[i];
        agg_inst *in = &g->inst[i];
        size_t h = src_hash(x) & (cap - 1);
        while (table[h] != UINT32_MAX && !same_src(&instances[g->src[table[h]].first], x)) h = (h + 1) & (cap - 1);
        memcpy(in->m, x->xform, sizeof in->m);
        xf_invert(in->m, in->inv);
        in->accel = NULL;
        in->nested = 0;
        in->leaf_base = i;
        boxes[i] = xf_box(in->m, sidx_mesh_bounds(x->mesh));
        g->box = sidx_aabb_union(g->box, boxes[i]);
        if (table[h] == UINT32_MAX) {
            agg_src *src = &g->src[g->num_src];
            memset(src, 0, sizeof *src);
            src->mesh = x->mesh;
            strcpy(src->name, x->accel ? x->accel : "bvh");
            if (x->opt) src->opt = *x->opt;
            src->first = i;
            src->box = boxes[i];
            table[h] = g->num_src++;
        }
        in->part = table[h];
        g->src[in->part].uses++;
    }
    g->leaves = n;
    sidx__free(a, table);
    table = NULL;
    for (uint32_t p = 0; p < g->num_src; ++p) {
        s = sidx_mesh_validate(g->src[p].mesh, err);
        if (s == SIDX_OK && lazy) s = src_check(a, &g->src[p], err);
        if (s != SIDX_OK) goto fail;
    }
    g->parts = sidx__calloc(a, g->num_src ? g->num_src : 1u, sizeof *g->parts);
    if (!g->parts) {
        s = sidx__fail(err, SIDX_ERR_NOMEM, "aggregate: out of memory");
        goto fail;
    }
    sidx__lazy_init(g->lazy, g->parts, g->num_src, agg_expand, a);
    for (uint32_t p = 0; p < g->num_src; ++p) {
        const agg_src *src = &g->src[p];
        if (lazy) {
            sidx__lazy_defer(g->lazy, p, src->uses);
            continue;
        }
        sidx_accel *c = NULL;
        s = src_build(a, src, opt ? opt->hook : NULL, &c, err);
        if (s != SIDX_OK) goto fail;
        sidx__lazy_made made;
        src_made(src, c, &made);
        sidx__lazy_built_now(g->lazy, p, c, &made);
    }
    for (uint32_t i = 0; i < n; ++i) {
        agg_inst *in = &g->inst[i];
        /* eager: the walk reads the structure straight from the instance */
        if (!lazy) in->accel = sidx__lazy_peek(g->lazy, in->part);
    }
    if (lazy) a->lazy = 1;
    for (uint32_t p = 0; p < g->num_src && !lazy; ++p)
        if (((const sidx_accel *)sidx__lazy_peek(g->lazy, p))->lazy) a->lazy = 1; /* lazy trees inside */
    /* one instance per leaf: the box the top walk tests last is the instance's own */
    s = agg_finish(a, boxes, 1, opt ? opt->hook : NULL, err);
    if (s == SIDX_OK) *out = a;
    return s;
fail:
    sidx__free(a, table);
    sidx__free(a, boxes);
    {
        const sidx_allocator al = a->alloc;
        agg_destroy(a);
        al.free(a, al.user);
    }
    return s;
}

uint32_t sidx_aggregate_leaf_count(const sidx_accel *a)
{
    if (!a) return 0;
    return sidx_accel_is_aggregate(a) ? ((const agg_impl *)a->impl)->leaves : 1u;
}

sidx_status sidx_aggregate_leaf(const sidx_accel *a, uint32_t leaf_id, const sidx_accel **leaf, float xform[12])
{
    if (!sidx_accel_is_aggregate(a) || !leaf || !xform) return SIDX_ERR_INVALID_ARG;
    float acc[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    for (;;) {
        const agg_impl *g = a->impl;
        if (leaf_id >= g->leaves) return SIDX_ERR_INVALID_ARG;
        /* the instance whose id range holds leaf_id: binary search on leaf_base */
        uint32_t lo = 0, hi = g->n;
        while (hi - lo > 1) {
            const uint32_t mid = lo + (hi - lo) / 2;
            if (g->inst[mid].leaf_base <= leaf_id) lo = mid;
            else hi = mid;
        }
        const agg_inst *in = &g->inst[lo];
        float tmp[12];
        xf_compose(acc, in->m, tmp);
        memcpy(acc, tmp, sizeof acc);
        if (!in->nested) {
            *leaf = in->accel ? in->accel : sidx__lazy_peek(g->lazy, in->part);
            memcpy(xform, acc, sizeof acc);
            return SIDX_OK;
        }
        leaf_id -= in->leaf_base;
        a = in->accel;
    }
}

/* ---- queries ------------------------------------------------------------------------ */

/* One walk for both queries.  Returns 1 on a hit (any_hit: at the first). */
static SIDX_INLINE int agg_walk(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit,
                                const int any_hit, const int traced)
{
    const agg_impl *g = a->impl;
    const int robust = a->opt.box == SIDX_BOX_ROBUST;
    float best = any_hit ? r->tmax : hit->t;
    uint32_t best_inst = UINT32_MAX;
    const sidx_accel *best_acc = NULL;
    sidx_hit best_hit = sidx_hit_none();
    sidx_ray best_local;
    memset(&best_local, 0, sizeof best_local);
    struct { uint32_t node; float t_near; } stack[SIDX_BOXTREE_STACK];
    int stack_len = 0;
    uint32_t visited = 0;
    float t_near, t_far;
    if (g->n && sidx__box_test(robust, r, &g->tree.nodes[0].box, r->tmin, best, &t_near, &t_far)) {
        stack[0].node = 0;
        stack[0].t_near = t_near;
        stack_len = 1;
    }
    while (stack_len > 0) {
        --stack_len;
        if (stack[stack_len].t_near > best) continue;
        const uint32_t node = stack[stack_len].node;
        const sidx__btnode *nd = &g->tree.nodes[node];
        ++visited;
        SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = node;
                  e_.t_near = stack[stack_len].t_near);
        if (nd->count == SIDX_BT_INNER) {
            float child_t_near[2], child_t_far[2];
            int h[2];
            for (int c = 0; c < 2; ++c) {
                h[c] = sidx__box_test(robust, r, &g->tree.nodes[nd->first + c].box, r->tmin, best, &child_t_near[c],
                                      &child_t_far[c]);
                SIDX_EMIT(traced, q->hook, SIDX_EV_BOX_TEST, e_.ray_id = q->ray_id; e_.node = nd->first + (uint32_t)c;
                          e_.bounds = g->tree.nodes[nd->first + c].box; e_.result = h[c];
                          e_.t_near = h[c] ? child_t_near[c] : NAN; e_.t_far = h[c] ? child_t_far[c] : NAN);
            }
            /* push the farther first so the nearer is walked first */
            const int near_child = (h[0] && h[1]) ? (child_t_near[1] < child_t_near[0] ? 1 : 0) : (h[0] ? 0 : 1);
            for (int k = 1; k >= 0; --k) {
                const int c = k ? 1 - near_child : near_child;
                if (h[c] && stack_len < SIDX_BOXTREE_STACK) {
                    stack[stack_len].node = nd->first + (uint32_t)c;
                    stack[stack_len].t_near = child_t_near[c];
                    ++stack_len;
                }
            }
            continue;
        }
        for (uint32_t k = 0; k < nd->count; ++k) {
            const uint32_t i = g->tree.items[nd->first + k];
            const agg_inst *in = &g->inst[i];
            const sidx_accel *c = in->accel;
            if (SIDX_UNLIKELY(!c)) {
                /* a lazy instance: the ray has entered its box (the leaf's,
                 * one instance per leaf); built now if it is the first */
                c = sidx__lazy_get(g->lazy, in->part, q->hook);
                if (!c) continue; /* no memory: the query reports it */
            }
            sidx_ray lr;
            if (sidx_ray_init(&lr, xf_point(in->inv, r->org), xf_vector(in->inv, r->dir), r->tmin, best) != SIDX_OK)
                continue; /* direction collapsed to 0 by rounding: nothing to see */
            SIDX_EMIT(traced, q->hook, SIDX_EV_NOTE, e_.ray_id = q->ray_id; e_.node = node; e_.count = i;
                      e_.aux = in->leaf_base; e_.text = "aggregate: ray enters instance (count = instance)");
            if (any_hit) {
                if (c->vt->occluded(c, &lr, q)) {
                    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                              e_.count = visited);
                    return 1;
                }
                continue;
            }
            sidx_hit h = sidx_hit_none();
            h.t = best;
            c->vt->intersect(c, &lr, q, &h);
            if (h.prim == SIDX_NO_HIT || !(h.t < best)) continue;
            best = h.t;
            best_inst = i;
            best_acc = c;
            best_hit = h;
            best_local = lr;
            SIDX_EMIT(traced, q->hook, SIDX_EV_HIT_UPDATE, e_.ray_id = q->ray_id; e_.prim = h.prim; e_.t = h.t;
                      e_.count = in->leaf_base + (in->nested ? h.instance : 0u));
        }
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_STACK_EMPTY;
              e_.t = best_inst == UINT32_MAX ? INFINITY : best; e_.count = visited);
    if (any_hit || best_inst == UINT32_MAX) return 0;
    const agg_inst *in = &g->inst[best_inst];
    hit->t = best_hit.t;
    hit->prim = best_hit.prim;
    hit->instance = in->leaf_base + (in->nested ? best_hit.instance : 0u);
    if (in->nested) {
        /* the child aggregate finished its hit in its own world space */
        if (q->flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL)) {
            hit->u = best_hit.u;
            hit->v = best_hit.v;
            hit->ng = xf_normal(in->inv, best_hit.ng);
        }
    } else if (q->flags & AGG_FINISH) {
        /* finished on the child's mesh and the local ray (the same t along
         * the world ray), then the normal taken to world space */
        sidx__hit_finish(best_acc->mesh, best_acc->opt.tri, &best_local, q->flags & AGG_FINISH, 0u, hit);
        if (q->flags & SIDX_QUERY_NORMAL) hit->ng = xf_normal(in->inv, hit->ng);
    }
    return 1;
}

static void agg_intersect_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    (void)agg_walk(a, r, q, hit, 0, 0);
}
static void agg_intersect_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    (void)agg_walk(a, r, q, hit, 0, 1);
}
static int agg_occluded_plain(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    sidx_hit dummy = sidx_hit_none();
    return agg_walk(a, r, q, &dummy, 1, 0);
}
static int agg_occluded_traced(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    sidx_hit dummy = sidx_hit_none();
    return agg_walk(a, r, q, &dummy, 1, 1);
}

/* The walk table (sidx_internal.h): the same for every build. */
static const sidx__walk_table agg_walks = {agg_intersect_plain, agg_intersect_traced, agg_occluded_plain,
                                            agg_occluded_traced};

static void agg_intersect(const sidx_accel *a, const sidx_ray *r, const sidx_query *q, sidx_hit *hit)
{
    sidx__walk_intersect(&agg_walks, a, r, q, hit);
}

static int agg_occluded(const sidx_accel *a, const sidx_ray *r, const sidx_query *q)
{
    return sidx__walk_occluded(&agg_walks, a, r, q);
}

static size_t own_bytes(const sidx_accel *a)
{
    const agg_impl *g = a->impl;
    /* the tree's node slots as allocated (sidx__boxtree_bytes counts the used ones) */
    const size_t mesh_inst = g->lazy ? sizeof *g->lazy + (size_t)g->num_src * (sizeof *g->src + sizeof *g->parts) : 0;
    return sizeof *a + sizeof *g + (size_t)g->n * sizeof *g->inst + sidx__boxtree_bytes(&g->tree) +
           (g->node_slots - g->tree.num_nodes) * sizeof *g->tree.nodes + mesh_inst;
}

static void agg_stats(const sidx_accel *a, sidx_accel_stats *s)
{
    const agg_impl *g = a->impl;
    s->nodes = g->tree.num_nodes;
    s->leaves = 0;
    for (uint32_t i = 0; i < g->tree.num_nodes; ++i) s->leaves += g->tree.nodes[i].count != SIDX_BT_INNER;
    s->max_depth = g->tree.depth;
    s->prim_refs = g->n;
    if (g->lazy) { /* mesh instances: the structures no ray has reached, the instances waiting on them */
        const sidx__lazy_counts c = sidx__lazy_counts_get(g->lazy);
        s->unbuilt = c.unbuilt;
        s->unbuilt_prims = c.unbuilt_refs;
    }
    s->bytes = own_bytes(a); /* the children are shared: see sidx_aggregate_info_get */
    s->mean_leaf_prims = s->leaves ? (double)g->n / s->leaves : 0.0;
}

sidx_status sidx_aggregate_info_get(const sidx_accel *a, sidx_aggregate_info *out)
{
    if (!sidx_accel_is_aggregate(a) || !out) return SIDX_ERR_INVALID_ARG;
    const agg_impl *g = a->impl;
    memset(out, 0, sizeof *out);
    out->instances = g->n;
    out->leaf_instances = g->leaves;
    out->own_bytes = own_bytes(a);
    if (g->lazy) {
        /* mesh instances: the structures it builds, each counted once */
        const sidx__lazy_counts c = sidx__lazy_counts_get(g->lazy);
        out->distinct_children = g->num_src;
        out->mesh_structures = g->num_src;
        out->built_structures = c.built;
        out->built_instances = (uint32_t)c.built_refs;
        out->shared_bytes = (size_t)c.built_bytes;
        for (uint32_t i = 0; i < g->n; ++i) out->world_triangles += g->src[g->inst[i].part].mesh->num_triangles;
        return SIDX_OK;
    }
    for (uint32_t i = 0; i < g->n; ++i) {
        const sidx_accel *c = g->inst[i].accel;
        if (sidx_accel_is_aggregate(c)) {
            sidx_aggregate_info ci;
            sidx_aggregate_info_get(c, &ci);
            out->world_triangles += ci.world_triangles;
        } else {
            out->world_triangles += c->mesh->num_triangles;
        }
        /* distinct: first occurrence (quadratic only in the number of distinct children seen so far) */
        int seen = 0;
        for (uint32_t j = 0; j < i && !seen; ++j) seen = g->inst[j].accel == c;
        if (seen) continue;
        out->distinct_children++;
        if (sidx_accel_is_aggregate(c)) {
            sidx_aggregate_info ci;
            sidx_aggregate_info_get(c, &ci);
            out->shared_bytes += ci.own_bytes + ci.shared_bytes;
        } else {
            sidx_accel_stats st;
            sidx_accel_stats_get(c, &st);
            out->shared_bytes += st.bytes;
        }
    }
    return SIDX_OK;
}

static sidx_status agg_build_unused(sidx_accel *a, sidx_error *err)
{
    (void)a;
    return sidx__fail(err, SIDX_ERR_UNSUPPORTED, "aggregates are built with sidx_aggregate_build");
}

const sidx_accel_vtable sidx__aggregate_vtable = {agg_build_unused, agg_intersect, agg_occluded, agg_stats, agg_destroy,
                                                  NULL};
