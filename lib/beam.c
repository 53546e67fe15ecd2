/* beam.c — cone and beam tracing against a BVH, with subdivision (see
 * sidx/beam.h for what is traced and why the results are candidates).
 *
 * A bundle is reduced to what culling needs: up to 5 half-spaces through
 * the apex (inside: n·(x − apex) >= 0) — the pyramid's 4 sides and the
 * plane behind the apex — plus, for a cone, the cone itself for the final
 * per-triangle sphere test.  The BVH is boxtree.c's median-split tree:
 * the registered "bvh" keeps its nodes private, and any BVH shows the
 * point (the counts). */
#include <stdio.h>
#include "sidx_internal.h"
#include "boxtree.h"
#include "sidx/beam.h"

#define SIDX_STRUCTURE_NAME "bundle"

struct sidx_bundle_tree {
    const sidx_mesh *mesh;
    sidx__boxtree tree;
    sidx_aabb *tri_box;
    sidx_allocator al;
};

typedef struct bundle {
    sidx_vec3 apex;
    sidx_vec3 n[5];
    int is_cone;
    sidx_vec3 axis;         /* unit (cone) */
    float cos_t, sin_t;     /* of the half angle (cone) */
} bundle;

/* ---- tree ----------------------------------------------------------------------- */

sidx_status sidx_bundle_tree_build(const sidx_mesh *m, const sidx_build_options *opt, sidx_bundle_tree **out,
                                   sidx_error *err)
{
    if (!out || !m) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "bundle tree: NULL argument");
    *out = NULL;
    sidx_status s = sidx_mesh_validate(m, err);
    if (s != SIDX_OK) return s;
    sidx_allocator al = (opt && opt->alloc && opt->alloc->alloc && opt->alloc->free) ? *opt->alloc
                                                                                     : sidx__default_allocator();
    sidx_bundle_tree *t = al.alloc(sizeof *t, al.user);
    if (!t) return sidx__fail(err, SIDX_ERR_NOMEM, "bundle tree: out of memory");
    memset(t, 0, sizeof *t);
    t->mesh = m;
    t->al = al;
    t->tri_box = al.alloc((m->num_triangles ? m->num_triangles : 1) * sizeof *t->tri_box, al.user);
    if (!t->tri_box) { al.free(t, al.user); return sidx__fail(err, SIDX_ERR_NOMEM, "bundle tree: out of memory"); }
    for (uint32_t i = 0; i < m->num_triangles; ++i) t->tri_box[i] = sidx_mesh_triangle_bounds(m, i);
    s = sidx__boxtree_build(&t->tree, t->tri_box, m->num_triangles, opt && opt->leaf_size ? opt->leaf_size : 4, &al);
    if (s != SIDX_OK) {
        al.free(t->tri_box, al.user);
        al.free(t, al.user);
        return sidx__fail(err, s, "bundle tree: out of memory");
    }
    *out = t;
    return SIDX_OK;
}

void sidx_bundle_tree_destroy(sidx_bundle_tree *t)
{
    if (!t) return;
    sidx__boxtree_free(&t->tree);
    sidx_allocator al = t->al;
    al.free(t->tri_box, al.user);
    al.free(t, al.user);
}

void sidx_bundle_result_free(sidx_bundle_result *r)
{
    if (!r) return;
    free(r->cands);
    memset(r, 0, sizeof *r);
}

/* ---- bundles ------------------------------------------------------------------------ */

static sidx_vec3 unit(sidx_vec3 v) { return sidx_v3_scale(v, 1.0f / sidx_v3_length(v)); }

static void basis(sidx_vec3 a, sidx_vec3 *p, sidx_vec3 *q)
{
    const sidx_vec3 h = fabsf(a.x) < 0.6f ? sidx_v3(1, 0, 0) : sidx_v3(0, 1, 0);
    *p = unit(sidx_v3_cross(a, h));
    *q = sidx_v3_cross(a, *p);
}

static int cone_ok(const sidx_cone *c)
{
    return c && sidx_v3_isfinite(c->apex) && sidx_v3_isfinite(c->axis) && sidx_v3_length(c->axis) > 0.0f &&
           c->half_angle > 0.0f && c->half_angle <= 1.5f;
}

static int beam_ok(const sidx_beam *b)
{
    if (!b || !sidx_v3_isfinite(b->apex)) return 0;
    for (int i = 0; i < 4; ++i)
        if (!sidx_v3_isfinite(b->dir[i]) || !(sidx_v3_length(b->dir[i]) > 0.0f)) return 0;
    return 1;
}

/* The cone's circumscribed square pyramid: the side plane tangent to the
 * cone towards e (one of ±p, ±q) has inward normal sinθ·a − cosθ·e. */
static void cone_bundle(const sidx_cone *c, bundle *b)
{
    const sidx_vec3 a = unit(c->axis);
    sidx_vec3 p, q;
    basis(a, &p, &q);
    b->apex = c->apex;
    b->is_cone = 1;
    b->axis = a;
    b->cos_t = cosf(c->half_angle);
    b->sin_t = sinf(c->half_angle);
    const sidx_vec3 e[4] = {p, sidx_v3_scale(p, -1), q, sidx_v3_scale(q, -1)};
    for (int i = 0; i < 4; ++i) b->n[i] = sidx_v3_sub(sidx_v3_scale(a, b->sin_t), sidx_v3_scale(e[i], b->cos_t));
    b->n[4] = a;
}

static int beam_bundle(const sidx_beam *bm, bundle *b)
{
    sidx_vec3 d[4], mean = sidx_v3(0, 0, 0);
    for (int i = 0; i < 4; ++i) { d[i] = unit(bm->dir[i]); mean = sidx_v3_add(mean, d[i]); }
    if (!(sidx_v3_length(mean) > 1e-6f)) return 0;
    b->apex = bm->apex;
    b->is_cone = 0;
    for (int i = 0; i < 4; ++i) {
        sidx_vec3 n = sidx_v3_cross(d[i], d[(i + 1) % 4]);
        if (!(sidx_v3_length(n) > 0.0f)) return 0;
        if (sidx_v3_dot(n, mean) < 0.0f) n = sidx_v3_scale(n, -1.0f); /* inward, whichever way round */
        b->n[i] = n;
    }
    b->n[4] = mean;
    return 1;
}

/* 1 if the box lies entirely outside one of the half-spaces */
static int box_culled(const bundle *b, const sidx_aabb *box)
{
    for (int i = 0; i < 5; ++i) {
        const sidx_vec3 n = b->n[i];
        const sidx_vec3 far = sidx_v3(n.x >= 0 ? box->max.x : box->min.x, n.y >= 0 ? box->max.y : box->min.y,
                                      n.z >= 0 ? box->max.z : box->min.z);
        if (sidx_v3_dot(n, sidx_v3_sub(far, b->apex)) < 0.0f) return 1;
    }
    return 0;
}

static int tri_candidate(const bundle *b, const sidx_mesh *m, uint32_t tri, const sidx_aabb *tbox)
{
    const sidx_vec3 v[3] = {sidx_mesh_vertex(m, tri, 0), sidx_mesh_vertex(m, tri, 1), sidx_mesh_vertex(m, tri, 2)};
    for (int i = 0; i < 5; ++i) {
        int out = 1;
        for (int k = 0; k < 3 && out; ++k) out = sidx_v3_dot(b->n[i], sidx_v3_sub(v[k], b->apex)) < 0.0f;
        if (out) return 0;
    }
    if (!b->is_cone) return 1;
    /* bounding sphere of the triangle's box against the cone: the sphere
     * (centre c, radius r) misses when the angle between axis and c − apex
     * exceeds θ + asin(r / |c − apex|) */
    const sidx_vec3 c = sidx_aabb_centroid(*tbox), w = sidx_v3_sub(c, b->apex);
    const float r = 0.5f * sidx_v3_length(sidx_aabb_extent(*tbox)) * 1.0001f;
    const float len = sidx_v3_length(w);
    if (len <= r) return 1;
    const float cos_phi = sidx_v3_dot(w, b->axis) / len;
    const float sin_s = r / len, cos_s = sqrtf(fmaxf(0.0f, 1.0f - sin_s * sin_s));
    /* cos(θ + s) = cosθ cos s − sinθ sin s; the sphere is out when φ > θ + s */
    const float lim = b->cos_t * cos_s - b->sin_t * sin_s;
    if (b->sin_t * cos_s + b->cos_t * sin_s <= 0.0f) return 1; /* θ + s beyond π: covers everything */
    return cos_phi >= lim - 1e-6f;
}

void sidx_cone_split(const sidx_cone *c, sidx_cone out[4])
{
    if (!c || !out) return; /* documented no-op (docs/errors.md) */
    /* planar picture: 4 discs of radius θ/√2 centred at (±θ/2, ±θ/2) cover
     * the disc of radius θ exactly; 0.78θ instead of 0.707θ leaves room
     * for the sphere's curvature (tested in tests/test_beam.c) */
    const sidx_vec3 a = unit(c->axis);
    sidx_vec3 p, q;
    basis(a, &p, &q);
    const float alpha = 0.70710678f * c->half_angle;
    for (int i = 0; i < 4; ++i) {
        const float sp = (i & 1) ? -1.0f : 1.0f, sq = (i & 2) ? -1.0f : 1.0f;
        const sidx_vec3 side = sidx_v3_scale(sidx_v3_add(sidx_v3_scale(p, sp), sidx_v3_scale(q, sq)), 0.70710678f);
        out[i].apex = c->apex;
        out[i].axis = sidx_v3_add(sidx_v3_scale(a, cosf(alpha)), sidx_v3_scale(side, sinf(alpha)));
        out[i].half_angle = 0.78f * c->half_angle;
    }
}

void sidx_beam_split(const sidx_beam *b, sidx_beam out[4])
{
    if (!b || !out) return; /* documented no-op (docs/errors.md) */
    /* bilinear split through the edge midpoints and the centre: the
     * shared faces are planes through the apex, so the 4 tile the parent */
    sidx_vec3 d[4];
    for (int i = 0; i < 4; ++i) d[i] = unit(b->dir[i]);
    const sidx_vec3 m01 = unit(sidx_v3_add(d[0], d[1])), m12 = unit(sidx_v3_add(d[1], d[2]));
    const sidx_vec3 m23 = unit(sidx_v3_add(d[2], d[3])), m30 = unit(sidx_v3_add(d[3], d[0]));
    const sidx_vec3 c = unit(sidx_v3_add(sidx_v3_add(d[0], d[1]), sidx_v3_add(d[2], d[3])));
    const sidx_vec3 q[4][4] = {{d[0], m01, c, m30}, {m01, d[1], m12, c}, {c, m12, d[2], m23}, {m30, c, m23, d[3]}};
    for (int i = 0; i < 4; ++i) {
        out[i].apex = b->apex;
        for (int k = 0; k < 4; ++k) out[i].dir[k] = q[i][k];
    }
}

/* ---- tracing ---------------------------------------------------------------------------- */

typedef struct trace_ctx {
    const sidx_bundle_tree *t;
    const sidx_hook *hook;
    uint32_t max_cands, max_levels;
    uint8_t *seen;          /* bitmap over triangles: in the union already */
    uint32_t *list;         /* one bundle's candidates */
    size_t cap;
    sidx_bundle_result *res;
    int failed;
} trace_ctx;

static uint32_t walk(trace_ctx *x, const bundle *b, uint32_t level)
{
    const sidx__boxtree *tr = &x->t->tree;
    uint32_t n = 0;
    uint32_t stack[SIDX_BOXTREE_STACK];
    int sp = 0;
    if (tr->num_nodes) stack[sp++] = 0;
    while (sp > 0) {
        const uint32_t node = stack[--sp];
        const sidx__btnode *nd = &tr->nodes[node];
        x->res->nodes_visited++;
        const int culled = box_culled(b, &nd->box);
        SIDX_EMIT(1, x->hook, SIDX_EV_BOX_TEST, e_.node = node; e_.depth = level; e_.bounds = nd->box;
                  e_.result = !culled);
        if (culled) { x->res->nodes_culled++; continue; }
        SIDX_EMIT(1, x->hook, SIDX_EV_NODE_ENTER, e_.node = node; e_.depth = level);
        if (nd->count == SIDX_BT_INNER) {
            if (sp + 2 <= SIDX_BOXTREE_STACK) { stack[sp++] = nd->first + 1; stack[sp++] = nd->first; }
            continue;
        }
        for (uint32_t k = 0; k < nd->count; ++k) {
            const uint32_t tri = tr->items[nd->first + k];
            x->res->tri_tests++;
            const int ok = tri_candidate(b, x->t->mesh, tri, &x->t->tri_box[tri]);
            SIDX_EMIT(1, x->hook, SIDX_EV_PRIM_TEST, e_.node = node; e_.prim = tri; e_.result = ok);
            if (!ok) continue;
            if (n == x->cap) {
                const size_t ncap = x->cap ? 2 * x->cap : 256;
                uint32_t *nl = realloc(x->list, ncap * sizeof *nl);
                if (!nl) { x->failed = 1; return n; }
                x->list = nl;
                x->cap = ncap;
            }
            x->list[n++] = tri;
        }
    }
    return n;
}

static void keep(trace_ctx *x, uint32_t n)
{
    x->res->bundles++;
    x->res->cand_refs += n;
    for (uint32_t i = 0; i < n; ++i) x->seen[x->list[i] >> 3] |= (uint8_t)(1u << (x->list[i] & 7));
}

static void trace_cone(trace_ctx *x, const sidx_cone *c, uint32_t level)
{
    bundle b;
    cone_bundle(c, &b);
    const uint32_t n = walk(x, &b, level);
    if (x->failed) return;
    if (x->max_cands && n > x->max_cands && level < x->max_levels) {
        x->res->subdivisions++;
        SIDX_EMIT(1, x->hook, SIDX_EV_NOTE, e_.depth = level; e_.count = n;
                  e_.text = "bundle: too many candidates (count): split into 4 smaller cones");
        sidx_cone sub[4];
        sidx_cone_split(c, sub);
        for (int i = 0; i < 4 && !x->failed; ++i) trace_cone(x, &sub[i], level + 1);
        return;
    }
    keep(x, n);
}

static void trace_beam(trace_ctx *x, const sidx_beam *bm, uint32_t level)
{
    bundle b;
    if (!beam_bundle(bm, &b)) return; /* a sub-beam cannot be degenerate if its parent was not */
    const uint32_t n = walk(x, &b, level);
    if (x->failed) return;
    if (x->max_cands && n > x->max_cands && level < x->max_levels) {
        x->res->subdivisions++;
        SIDX_EMIT(1, x->hook, SIDX_EV_NOTE, e_.depth = level; e_.count = n;
                  e_.text = "bundle: too many candidates (count): split into 4 smaller beams");
        sidx_beam sub[4];
        sidx_beam_split(bm, sub);
        for (int i = 0; i < 4 && !x->failed; ++i) trace_beam(x, &sub[i], level + 1);
        return;
    }
    keep(x, n);
}

static sidx_status finish(trace_ctx *x, uint32_t ntris)
{
    sidx_bundle_result *r = x->res;
    free(x->list);
    if (x->failed) { free(x->seen); sidx_bundle_result_free(r); return SIDX_ERR_NOMEM; }
    uint32_t n = 0;
    for (uint32_t i = 0; i < ntris; ++i) n += (x->seen[i >> 3] >> (i & 7)) & 1u;
    r->cands = malloc((n ? n : 1) * sizeof *r->cands);
    if (!r->cands) { free(x->seen); sidx_bundle_result_free(r); return SIDX_ERR_NOMEM; }
    for (uint32_t i = 0; i < ntris; ++i)
        if ((x->seen[i >> 3] >> (i & 7)) & 1u) r->cands[r->num_cands++] = i;
    free(x->seen);
    return SIDX_OK;
}

static sidx_status start(trace_ctx *x, const sidx_bundle_tree *t, uint32_t max_cands, uint32_t max_levels,
                         const sidx_hook *hook, sidx_bundle_result *out)
{
    memset(x, 0, sizeof *x);
    memset(out, 0, sizeof *out);
    x->t = t;
    x->hook = hook;
    x->max_cands = max_cands;
    x->max_levels = max_levels;
    x->res = out;
    x->seen = calloc((size_t)t->mesh->num_triangles / 8 + 1, 1);
    return x->seen ? SIDX_OK : SIDX_ERR_NOMEM;
}

sidx_status sidx_cone_trace(const sidx_bundle_tree *t, const sidx_cone *c, uint32_t max_candidates,
                            uint32_t max_levels, const sidx_hook *hook, sidx_bundle_result *out)
{
    if (!t || !out || !cone_ok(c)) return SIDX_ERR_INVALID_ARG;
    trace_ctx x;
    if (start(&x, t, max_candidates, max_levels, hook, out) != SIDX_OK) return SIDX_ERR_NOMEM;
    trace_cone(&x, c, 0);
    return finish(&x, t->mesh->num_triangles);
}

sidx_status sidx_beam_trace(const sidx_bundle_tree *t, const sidx_beam *b, uint32_t max_candidates,
                            uint32_t max_levels, const sidx_hook *hook, sidx_bundle_result *out)
{
    bundle tmp;
    if (!t || !out || !beam_ok(b) || !beam_bundle(b, &tmp)) return SIDX_ERR_INVALID_ARG;
    trace_ctx x;
    if (start(&x, t, max_candidates, max_levels, hook, out) != SIDX_OK) return SIDX_ERR_NOMEM;
    trace_beam(&x, b, 0);
    return finish(&x, t->mesh->num_triangles);
}

static sidx_status brute(const sidx_mesh *m, const bundle *b, sidx_bundle_result *out)
{
    memset(out, 0, sizeof *out);
    out->cands = malloc((m->num_triangles ? m->num_triangles : 1) * sizeof *out->cands);
    if (!out->cands) return SIDX_ERR_NOMEM;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        const sidx_aabb box = sidx_mesh_triangle_bounds(m, i);
        out->tri_tests++;
        if (tri_candidate(b, m, i, &box)) out->cands[out->num_cands++] = i;
    }
    out->bundles = 1;
    out->cand_refs = out->num_cands;
    return SIDX_OK;
}

sidx_status sidx_cone_candidates_brute(const sidx_mesh *m, const sidx_cone *c, sidx_bundle_result *out)
{
    if (!m || !out || !cone_ok(c)) return SIDX_ERR_INVALID_ARG;
    bundle b;
    cone_bundle(c, &b);
    return brute(m, &b, out);
}

sidx_status sidx_beam_candidates_brute(const sidx_mesh *m, const sidx_beam *bm, sidx_bundle_result *out)
{
    bundle b;
    if (!m || !out || !beam_ok(bm) || !beam_bundle(bm, &b)) return SIDX_ERR_INVALID_ARG;
    return brute(m, &b, out);
}
