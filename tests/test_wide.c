/* test_wide.c — bvh4 and bvh8, the wide BVHs with SIMD kernels.
 *
 * What the registry-wide suite does not check:
 *  - the SIMD kernels (SSE4.1 / AVX2 / AVX-512, those this CPU has; the
 *    AVX2 copy also on an AVX-512 CPU, via SIDX_SIMD=avx2) and the
 *    portable scalar copy (SIDX_SIMD=scalar) return BIT-IDENTICAL hits
 *    (prim, t, and u, v) and any-hit answers on random, grazing and
 *    axis-parallel (±0 direction) rays, for every triangle / box test;
 *  - closest hits agree with brute force (same prim, or same t within
 *    1e-5 relative) on the built-in scenes, traced and untraced alike;
 *  - zero leaks from inside the icosphere at every vertex and edge midpoint;
 *  - the collapsed tree is well formed: every triangle in exactly one
 *    leaf lane, child boxes inside their slot, pre-order numbering, padding
 *    lanes and empty slots as documented;
 *  - traversal events use the ids the build announced; refit equals a
 *    rebuild; allocation failures at every step leak nothing. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sidx/sidx.h"
#include "bvh_wide_internal.h"
#include "common/testkit.h"

static const char *const wides[] = {"bvh4", "bvh8"};
#define NWIDES 2
static const char *const scenes[] = {"icosphere", "teapot", "soup", "menger", "stadium", "cornell"};
#define NSCENES (sizeof scenes / sizeof scenes[0])

static sidx_mesh scene(const char *name)
{
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make(name, 0, &m, &err) != SIDX_OK) fail_msg("scene %s: %s", name, err.message);
    return m;
}

/* Kernel choices: 0 the scalar copy forced, 1 the best this CPU has, 2
 * at most AVX2 (on an AVX-512 CPU the AVX2 copy, else the same as 1). */
#define NSIMD 3
static const char *const simd_cap[NSIMD] = {"scalar", NULL, "avx2"};

static sidx_accel *build(const char *name, const sidx_mesh *m, const sidx_build_options *opt, int simd)
{
    if (simd_cap[simd]) setenv("SIDX_SIMD", simd_cap[simd], 1);
    sidx_accel *a = NULL;
    sidx_error err;
    const sidx_status s = sidx_accel_build(name, m, opt, &a, &err);
    unsetenv("SIDX_SIMD");
    if (s != SIDX_OK) fail_msg("build %s: %s", name, err.message);
    const wide_isa isa = ((const wide_bvh *)a->impl)->isa;
    if (simd == 0) assert_int_equal(isa, WIDE_ISA_SCALAR);
    if (simd == 2) assert_true(isa <= WIDE_ISA_AVX2);
    return a;
}

/* 1 (and a destroyed) when the kernels of a, built for the next choice,
 * are those of the previous build (an AVX2 machine, or valgrind's CPU:
 * choice 2 is choice 1 there), so its checks would repeat; else 0 and
 * *previous = its kernels. */
static int same_kernels_again(sidx_accel *a, wide_isa *previous)
{
    const wide_isa isa = ((const wide_bvh *)a->impl)->isa;
    if (isa != WIDE_ISA_SCALAR && isa == *previous) {
        sidx_accel_destroy(a);
        return 1;
    }
    *previous = isa;
    return 0;
}

static size_t make_rays(const sidx_mesh *m, size_t per_kind, uint64_t seed, sidx_ray **out)
{
    const tk_ray_kind kinds[] = {TK_RAYS_DIFFUSE, TK_RAYS_GRAZING, TK_RAYS_AXIS, TK_RAYS_PRIMARY, TK_RAYS_SHADOW};
    const size_t nk = sizeof kinds / sizeof kinds[0];
    tk_rayrec *rec = malloc(per_kind * sizeof *rec);
    sidx_ray *rays = malloc(nk * per_kind * sizeof *rays);
    assert_non_null(rec);
    assert_non_null(rays);
    size_t n = 0;
    for (size_t k = 0; k < nk; ++k) {
        tk_make_rays(m, kinds[k], per_kind, seed + k, rec);
        for (size_t i = 0; i < per_kind; ++i)
            if (tk_ray_from(&rec[i], &rays[n]) == SIDX_OK) ++n;
    }
    free(rec);
    *out = rays;
    return n;
}

static size_t per_kind(size_t normal) { return tk_test_size(normal); }

static void count_fn(const sidx_event *ev, void *user)
{
    (void)ev;
    ++*(uint64_t *)user;
}

/* ---- SIMD == scalar, bit for bit ------------------------------------------------ */

static void test_simd_equals_scalar(void **state)
{
    (void)state;
    for (size_t si = 0; si < NSCENES; ++si) {
        sidx_mesh m = scene(scenes[si]);
        sidx_ray *rays;
        const size_t n = make_rays(&m, per_kind(300), 11, &rays);
        for (int w = 0; w < NWIDES; ++w)
            for (int tri = 0; tri < SIDX_TRI_METHOD_COUNT; ++tri)
                for (int box = 0; box < SIDX_BOX_METHOD_COUNT; ++box) {
                    /* the smallest sizes (valgrind): half the pairs of tests on each
                     * scene and width, the other half on the next */
                    if (tk_tiny_tests() && (si + (size_t)w + (size_t)tri + (size_t)box) % 2 != 0) continue;
                    sidx_build_options o;
                    memset(&o, 0, sizeof o);
                    o.tri = (sidx_tri_method)tri;
                    o.box = (sidx_box_method)box;
                    sidx_accel *ref = build(wides[w], &m, &o, 0);
                    wide_isa previous = WIDE_ISA_SCALAR;
                    for (int simd = 1; simd < NSIMD; ++simd) {
                        sidx_accel *fast = build(wides[w], &m, &o, simd);
                        if (same_kernels_again(fast, &previous)) continue;
                        const sidx_query q = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, NULL, 0};
                        for (size_t i = 0; i < n; ++i) {
                            sidx_hit a, b;
                            int oa, ob;
                            sidx_accel_intersect(fast, &rays[i], &q, &a);
                            sidx_accel_intersect(ref, &rays[i], &q, &b);
                            sidx_accel_occluded(fast, &rays[i], &q, &oa);
                            sidx_accel_occluded(ref, &rays[i], &q, &ob);
                            if (a.prim != b.prim || memcmp(&a.t, &b.t, sizeof a.t) ||
                                memcmp(&a.u, &b.u, sizeof a.u) || memcmp(&a.v, &b.v, sizeof a.v) || oa != ob)
                                fail_msg("%s %s tri %d box %d simd %d ray %zu: simd prim %u t %.9g occ %d, scalar prim %u "
                                         "t %.9g occ %d",
                                         scenes[si], wides[w], tri, box, simd, i, a.prim, (double)a.t, oa, b.prim,
                                         (double)b.t, ob);
                        }
                        sidx_accel_destroy(fast);
                    }
                    sidx_accel_destroy(ref);
                }
        free(rays);
        sidx_mesh_free(&m);
    }
}

/* ---- against brute force, traced and untraced ----------------------------------- */

static void test_match_brute(void **state)
{
    (void)state;
    for (size_t si = 0; si < NSCENES; ++si) {
        sidx_mesh m = scene(scenes[si]);
        sidx_ray *rays;
        const size_t n = make_rays(&m, per_kind(200), 5, &rays);
        sidx_accel *brute = NULL;
        assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
        for (int w = 0; w < NWIDES; ++w)
            for (int simd = 0; simd < NSIMD + 1; ++simd) {
                /* the last round: the best kernels on the tree without spatial splits */
                sidx_build_options o;
                memset(&o, 0, sizeof o);
                o.no_spatial_splits = simd == NSIMD;
                sidx_accel *a = build(wides[w], &m, &o, simd == NSIMD ? 1 : simd);
                uint64_t events = 0;
                const sidx_hook hook = {count_fn, &events, 0};
                const sidx_query traced = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
                for (size_t i = 0; i < n; ++i) {
                    sidx_hit ref, h, ht;
                    int oref, o, ot;
                    sidx_accel_intersect(brute, &rays[i], NULL, &ref);
                    sidx_accel_occluded(brute, &rays[i], NULL, &oref);
                    sidx_accel_intersect(a, &rays[i], NULL, &h);
                    sidx_accel_intersect(a, &rays[i], &traced, &ht);
                    sidx_accel_occluded(a, &rays[i], NULL, &o);
                    sidx_accel_occluded(a, &rays[i], &traced, &ot);
                    if (!tk_hits_agree(&ref, &h))
                        fail_msg("%s/%s simd %d ray %zu: prim %u t %.9g, brute prim %u t %.9g", scenes[si], wides[w],
                                 simd, i, h.prim, (double)h.t, ref.prim, (double)ref.t);
                    assert_int_equal(h.prim, ht.prim);
                    assert_true(h.t == ht.t || (isinf(h.t) && isinf(ht.t)));
                    assert_int_equal(o, oref);
                    assert_int_equal(ot, oref);
                }
                assert_true(events > 0);
                sidx_accel_destroy(a);
            }
        sidx_accel_destroy(brute);
        free(rays);
        sidx_mesh_free(&m);
    }
}

/* ---- u, v from the leaf blocks ----------------------------------------------------
 * The wide walk sets u, v itself from its block's copy of the triangle
 * (a->fills_uv), so the core skips its re-test on the mesh; the numbers
 * must be the core's, bit for bit: compare with brute force, whose u, v
 * the core computes from the mesh, on every ray both hit on the same
 * triangle, for the SIMD and the scalar kernels, traced and untraced. */

static void test_uv_matches_core(void **state)
{
    (void)state;
    for (size_t si = 0; si < NSCENES; ++si) {
        sidx_mesh m = scene(scenes[si]);
        sidx_ray *rays;
        const size_t n = make_rays(&m, per_kind(200), 23, &rays);
        sidx_hit *refs = malloc(n * sizeof *refs);
        assert_non_null(refs);
        for (int tri = 0; tri < SIDX_TRI_METHOD_COUNT; ++tri) {
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.tri = (sidx_tri_method)tri;
            sidx_accel *brute = NULL;
            assert_int_equal(sidx_accel_build("brute", &m, &o, &brute, NULL), SIDX_OK);
            /* the core's answers, once per triangle test, for every build below */
            const sidx_query qr = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
            for (size_t i = 0; i < n; ++i) sidx_accel_intersect(brute, &rays[i], &qr, &refs[i]);
            for (int w = 0; w < NWIDES; ++w) {
                /* the smallest sizes: one width per triangle test, the other on the next scene */
                if (tk_tiny_tests() && (si + (size_t)w + (size_t)tri) % 2 != 0) continue;
                wide_isa previous = WIDE_ISA_SCALAR;
                for (int simd = 0; simd < NSIMD; ++simd) {
                    sidx_accel *a = build(wides[w], &m, &o, simd);
                    if (same_kernels_again(a, &previous)) continue;
                    uint64_t events = 0;
                    const sidx_hook hook = {count_fn, &events, 0};
                    const sidx_query q = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
                    const sidx_query qt = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, &hook, 0};
                    size_t same = 0;
                    for (size_t i = 0; i < n; ++i) {
                        sidx_hit h, ht;
                        const sidx_hit ref = refs[i];
                        sidx_accel_intersect(a, &rays[i], &q, &h);
                        sidx_accel_intersect(a, &rays[i], &qt, &ht);
                        assert_memory_equal(&h, &ht, sizeof h);
                        if (h.prim == SIDX_NO_HIT || h.prim != ref.prim) continue;
                        ++same;
                        if (memcmp(&h.t, &ref.t, sizeof h.t) || memcmp(&h.u, &ref.u, sizeof h.u) ||
                            memcmp(&h.v, &ref.v, sizeof h.v) || memcmp(&h.ng, &ref.ng, sizeof h.ng))
                            fail_msg("%s %s tri %d simd %d ray %zu prim %u: u %.9g v %.9g, core u %.9g v %.9g",
                                     scenes[si], wides[w], tri, simd, i, h.prim, (double)h.u, (double)h.v,
                                     (double)ref.u, (double)ref.v);
                    }
                    assert_true(same > n / 10); /* the comparison really ran */
                    assert_true(events > 0);
                    sidx_accel_destroy(a);
                }
            }
            sidx_accel_destroy(brute);
        }
        free(refs);
        free(rays);
        sidx_mesh_free(&m);
    }
}

/* ---- zero leaks ----------------------------------------------------------------- */

static void test_no_leaks_icosphere(void **state)
{
    (void)state;
    for (uint32_t detail = 1; detail <= 4; ++detail) {
        sidx_mesh m;
        assert_int_equal(sidx_scene_make("icosphere", detail, &m, NULL), SIDX_OK);
        const sidx_aabb bb = sidx_mesh_bounds(&m);
        const sidx_vec3 e = sidx_aabb_extent(bb);
        const sidx_vec3 in = sidx_v3_add(sidx_aabb_centroid(bb), sidx_v3(0.0123f * e.x, -0.0071f * e.y, 0.0031f * e.z));
        const size_t max = 6u * m.num_triangles;
        tk_rayrec *rec = malloc(max * sizeof *rec);
        assert_non_null(rec);
        const size_t n = tk_make_leak_rays(&m, in, max, rec);
        for (int w = 0; w < NWIDES; ++w)
            for (int simd = 0; simd < NSIMD; ++simd) {
                sidx_accel *a = build(wides[w], &m, NULL, simd);
                for (size_t i = 0; i < n; ++i) {
                    sidx_ray r;
                    assert_int_equal(tk_ray_from(&rec[i], &r), SIDX_OK);
                    sidx_hit h;
                    int occ;
                    sidx_accel_intersect(a, &r, NULL, &h);
                    sidx_accel_occluded(a, &r, NULL, &occ);
                    if (h.prim == SIDX_NO_HIT || !occ)
                        fail_msg("leak: icosphere:%u %s simd %d ray %zu", detail, wides[w], simd, i);
                }
                sidx_accel_destroy(a);
            }
        free(rec);
        sidx_mesh_free(&m);
    }
}

/* ---- structure -------------------------------------------------------------------- */

static int box_inside(sidx_aabb outer, sidx_aabb inner) { return sidx_aabb_contains(outer, inner); }

/* One leaf reference: its triangle and the box of the slot holding it. */
typedef struct leafref {
    uint32_t prim;
    sidx_aabb box;
} leafref;

typedef struct walkstate {
    int whole;         /* no spatial splits: every triangle in exactly one leaf, inside its box */
    uint32_t ntris;    /* the mesh's triangles */
    uint32_t *seen;    /* references per triangle */
    leafref *refs;     /* every reference (spatial splits) */
    size_t nrefs, cap;
    uint32_t leaves;
    int treelets;      /* nodes stored in treelets (SIDX_WIDE_ORDER): slot ids need not be indices */
} walkstate;

static void check_node(const wide_bvh *w, uint32_t i, uint32_t depth, walkstate *ws)
{
    const uint32_t W = w->width;
    const float *n = wide_node(w, i);
    int used = 0, gap = 0;
    assert_true(depth <= w->max_depth);
    for (uint32_t s = 0; s < W; ++s) {
        const uint32_t c = wide_child(n, W)[s];
        const sidx_aabb sb = wide_slot_box(n, W, s);
        if (c == WIDE_EMPTY) {
            gap = 1; /* empty slots come last */
            assert_true(sb.min.x == INFINITY && sb.max.x == -INFINITY);
            continue;
        }
        assert_false(gap);
        ++used;
        if (c & WIDE_LEAF_BIT) {
            ++ws->leaves;
            assert_true(wide_id(n, W)[s] >= w->num_inner);
            const wide_tri4 *B = w->blocks + (c & ~WIDE_LEAF_BIT);
            for (;; ++B) {
                assert_true(B < w->blocks + w->num_blocks);
                for (int l = 0; l < 4; ++l) {
                    const uint32_t id = B->prim[l] & WIDE_PRIM_MASK;
                    if (id == WIDE_PAD_PRIM) {
                        assert_true(isnan(B->v[0][0][l]));
                        continue;
                    }
                    assert_true(id < ws->ntris); /* an original triangle index */
                    if (ws->whole) {
                        assert_int_equal(ws->seen[id], 0);
                        for (int v = 0; v < 3; ++v) {
                            const sidx_vec3 p = {B->v[v][0][l], B->v[v][1][l], B->v[v][2][l]};
                            if (!box_inside(sb, (sidx_aabb){p, p}))
                                fail_msg("node %u slot %u: triangle %u corner %d (%g %g %g) outside its leaf box "
                                         "(%g %g %g)-(%g %g %g)", i, s, id, v, (double)p.x, (double)p.y, (double)p.z,
                                         (double)sb.min.x, (double)sb.min.y, (double)sb.min.z, (double)sb.max.x,
                                         (double)sb.max.y, (double)sb.max.z);
                        }
                    } else {
                        if (ws->nrefs == ws->cap) {
                            ws->cap = ws->cap ? 2 * ws->cap : 1024;
                            ws->refs = realloc(ws->refs, ws->cap * sizeof *ws->refs);
                            assert_non_null(ws->refs);
                        }
                        ws->refs[ws->nrefs++] = (leafref){id, sb};
                    }
                    ws->seen[id]++;
                }
                if (B->prim[0] & WIDE_LAST_BLOCK) break;
            }
        } else {
            assert_true(c > i && c < w->num_inner); /* top-down: refit runs backwards */
            if (ws->treelets) assert_true(wide_id(n, W)[s] > 0 && wide_id(n, W)[s] < w->num_inner);
            else assert_int_equal(wide_id(n, W)[s], c); /* pre-order */
            const float *cn = wide_node(w, c);
            for (uint32_t k = 0; k < W; ++k)
                if (wide_child(cn, W)[k] != WIDE_EMPTY) assert_true(box_inside(sb, wide_slot_box(cn, W, k)));
            check_node(w, c, depth + 1, ws);
        }
    }
    assert_true(used >= 1);
}

static int by_prim(const void *a, const void *b)
{
    const uint32_t x = ((const leafref *)a)->prim, y = ((const leafref *)b)->prim;
    return (x > y) - (x < y);
}

/* With spatial splits a triangle's references each bound only a part of
 * it; together they must cover it, or a ray could pass through the gap.
 * Points spread over the triangle (corners, edge points, inner points on
 * a barycentric grid) must each lie in the box of one of its references. */
static void check_coverage(const sidx_mesh *m, walkstate *ws)
{
    qsort(ws->refs, ws->nrefs, sizeof *ws->refs, by_prim);
    size_t r = 0;
    for (uint32_t t = 0; t < m->num_triangles; ++t) {
        const size_t r0 = r;
        while (r < ws->nrefs && ws->refs[r].prim == t) ++r;
        assert_true(r > r0);
        const sidx_vec3 a = sidx_mesh_vertex(m, t, 0), b = sidx_mesh_vertex(m, t, 1), c = sidx_mesh_vertex(m, t, 2);
        enum { G = 8 };
        for (int i = 0; i <= G; ++i)
            for (int j = 0; i + j <= G; ++j) {
                const float u = (float)i / G, v = (float)j / G;
                const sidx_vec3 p = sidx_v3_add(a, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(b, a), u),
                                                               sidx_v3_scale(sidx_v3_sub(c, a), v)));
                int in = 0;
                for (size_t k = r0; k < r && !in; ++k) {
                    /* the point is computed with rounding: allow a relative 2^-20 */
                    const sidx_aabb bx = ws->refs[k].box;
                    const float e = 0x1p-20f * (fabsf(p.x) + fabsf(p.y) + fabsf(p.z)) + 1e-30f;
                    in = p.x >= bx.min.x - e && p.x <= bx.max.x + e && p.y >= bx.min.y - e && p.y <= bx.max.y + e &&
                         p.z >= bx.min.z - e && p.z <= bx.max.z + e;
                }
                if (!in) fail_msg("triangle %u: point (%d, %d)/%d in none of its %zu references", t, i, j, G, r - r0);
            }
    }
}

/* Both binary trees bvh4/bvh8 can collapse: with spatial splits (the
 * default) and without.  The scenes with long triangles (the stadium's
 * stands, the random soup) must get some split references, or the
 * default would silently be the plain tree. */
static void test_structure(void **state)
{
    (void)state;
    for (size_t si = 0; si < NSCENES; ++si) {
        sidx_mesh m = scene(scenes[si]);
        for (int whole = 0; whole < 2; ++whole)
            for (int w = 0; w < NWIDES; ++w) {
                sidx_build_options o;
                memset(&o, 0, sizeof o);
                o.no_spatial_splits = whole;
                sidx_accel *a = build(wides[w], &m, &o, 1);
                const wide_bvh *wb = a->impl;
                assert_int_equal(wb->width, w ? 8u : 4u);
                walkstate ws = {whole, m.num_triangles, calloc(m.num_triangles, sizeof(uint32_t)), NULL, 0, 0, 0, 0};
                assert_non_null(ws.seen);
                check_node(wb, 0, 0, &ws);
                uint64_t refs = 0;
                for (uint32_t t = 0; t < m.num_triangles; ++t) {
                    if (whole) assert_int_equal(ws.seen[t], 1);
                    else assert_true(ws.seen[t] >= 1);
                    refs += ws.seen[t];
                }
                if (!whole) check_coverage(&m, &ws);
                assert_int_equal(ws.leaves, wb->num_leaves);
                sidx_accel_stats st;
                sidx_accel_stats_get(a, &st);
                assert_int_equal(st.nodes, wb->num_inner + wb->num_leaves);
                assert_int_equal(st.prim_refs, refs);
                if (whole) assert_int_equal(st.prim_refs, m.num_triangles);
                if (!whole && (strcmp(scenes[si], "soup") == 0 || strcmp(scenes[si], "stadium") == 0))
                    assert_true(st.prim_refs > m.num_triangles);
                assert_true(st.sah_cost > 0.0);
                free(ws.seen);
                free(ws.refs);
                sidx_accel_destroy(a);
            }
        sidx_mesh_free(&m);
    }
}

/* ---- events ------------------------------------------------------------------------ */

typedef struct idrec {
    uint8_t *built;
    uint32_t cap;
    uint64_t enters, boxes, prims, terminates, bad;
} idrec;

static void id_fn(const sidx_event *ev, void *user)
{
    idrec *r = user;
    switch (ev->type) {
    case SIDX_EV_BUILD_NODE:
        if (ev->node < r->cap) r->built[ev->node] = 1;
        else r->bad++;
        break;
    case SIDX_EV_NODE_ENTER:
        r->enters++;
        if (ev->node >= r->cap || !r->built[ev->node]) r->bad++;
        break;
    case SIDX_EV_BOX_TEST:
        r->boxes++;
        if (ev->node >= r->cap || !r->built[ev->node]) r->bad++;
        break;
    case SIDX_EV_PRIM_TEST: r->prims++; break;
    case SIDX_EV_TERMINATE: r->terminates++; break;
    default: break;
    }
}

static void test_event_ids(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    for (int w = 0; w < NWIDES; ++w) {
        idrec r;
        memset(&r, 0, sizeof r);
        r.cap = 4u * m.num_triangles + 16u;
        r.built = calloc(r.cap, 1);
        assert_non_null(r.built);
        const sidx_hook hook = {id_fn, &r, 0};
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        o.hook = &hook;
        sidx_accel *a = build(wides[w], &m, &o, 1);
        sidx_ray *rays;
        const size_t n = make_rays(&m, 20, 3, &rays);
        const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
        for (size_t i = 0; i < n; ++i) {
            sidx_hit h;
            sidx_accel_intersect(a, &rays[i], &q, &h);
        }
        assert_int_equal(r.bad, 0);
        assert_int_equal(r.terminates, n);
        assert_true(r.enters >= n && r.boxes > r.enters && r.prims > 0);
        free(rays);
        free(r.built);
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

/* ---- node order ------------------------------------------------------------------- */

/* Every event of a build and of traced walks, folded into one hash (FNV-1a
 * over the fields the events carry), and how many there were. */
typedef struct evhash {
    uint64_t h, n;
} evhash;

static void hash_bytes(evhash *e, const void *p, size_t len)
{
    const unsigned char *b = p;
    for (size_t i = 0; i < len; ++i) e->h = (e->h ^ b[i]) * 1099511628211ull;
}

static void hash_fn(const sidx_event *ev, void *user)
{
    evhash *e = user;
    const uint32_t f[5] = {(uint32_t)ev->type, ev->node, ev->parent, ev->depth, ev->count};
    hash_bytes(e, f, sizeof f);
    hash_bytes(e, &ev->bounds, sizeof ev->bounds);
    const float t[3] = {ev->t_near, ev->t_far, ev->t};
    hash_bytes(e, t, sizeof t);
    e->n++;
}

/* The treelet order (SIDX_WIDE_ORDER=treelets) moves nodes and blocks but
 * nothing a caller sees: the storage must differ from the depth-first
 * one while hits (with u, v, Ng), shadow answers and every build and
 * walk event are the same. */
static void test_treelet_order(void **state)
{
    (void)state;
    sidx_mesh m = scene("soup");
    for (int w = 0; w < NWIDES; ++w) {
        sidx_accel *a[2];
        evhash eh[2] = {{14695981039346656037ull, 0}, {14695981039346656037ull, 0}};
        sidx_ray *rays;
        const size_t n = make_rays(&m, per_kind(400), 11, &rays);
        sidx_hit *hits[2];
        for (int k = 0; k < 2; ++k) {
            setenv("SIDX_WIDE_ORDER", k ? "treelets" : "depth-first", 1);
            const sidx_hook hook = {hash_fn, &eh[k], 0};
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.hook = &hook;
            a[k] = build(wides[w], &m, &o, 1);
            hits[k] = calloc(2 * n, sizeof *hits[k]);
            assert_non_null(hits[k]);
            const sidx_query traced = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
            const sidx_query uv = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, NULL, 0};
            for (size_t i = 0; i < n; ++i) {
                sidx_accel_intersect(a[k], &rays[i], i % 4 ? &uv : &traced, &hits[k][i]);
                int occ = -1;
                assert_int_equal(sidx_accel_occluded(a[k], &rays[i], i % 4 ? NULL : &traced, &occ), SIDX_OK);
                hits[k][n + i].prim = (uint32_t)occ;
            }
        }
        unsetenv("SIDX_WIDE_ORDER");
        const wide_bvh *d = a[0]->impl, *t = a[1]->impl;
        assert_int_equal(d->num_inner, t->num_inner);
        assert_int_equal(d->num_blocks, t->num_blocks);
        assert_true(d->num_inner > 64u); /* several treelets */
        const size_t nb = (size_t)d->num_inner * 8u * d->width * sizeof(float);
        assert_true(memcmp(d->nodes, t->nodes, nb) != 0);
        assert_true(memcmp(d->blocks, t->blocks, (size_t)d->num_blocks * sizeof *d->blocks) != 0);
        walkstate ws = {0, m.num_triangles, calloc(m.num_triangles, sizeof(uint32_t)), NULL, 0, 0, 0, 1};
        assert_non_null(ws.seen);
        check_node(t, 0, 0, &ws);
        check_coverage(&m, &ws);
        assert_int_equal(ws.leaves, t->num_leaves);
        assert_memory_equal(hits[0], hits[1], 2 * n * sizeof *hits[0]);
        assert_true(eh[0].n > n && eh[0].n == eh[1].n);
        assert_true(eh[0].h == eh[1].h);
        free(ws.seen);
        free(ws.refs);
        for (int k = 0; k < 2; ++k) {
            free(hits[k]);
            sidx_accel_destroy(a[k]);
        }
        free(rays);
    }
    sidx_mesh_free(&m);
}

/* ---- refit ------------------------------------------------------------------------- */

static void test_refit_matches_rebuild(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    sidx_ray *rays;
    const size_t n = make_rays(&m, per_kind(100), 9, &rays);
    for (int w = 0; w < NWIDES; ++w) {
        sidx_accel *a = build(wides[w], &m, NULL, 1);
        /* squash y and shift: same topology, new boxes */
        for (uint32_t i = 0; i < m.num_vertices; ++i) {
            m.positions[i].y = 0.5f * m.positions[i].y + 0.25f;
            m.positions[i].x += 0.1f;
        }
        assert_int_equal(sidx_accel_refit(a, NULL), SIDX_OK);
        sidx_accel *brute = NULL;
        assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
        for (size_t i = 0; i < n; ++i) {
            sidx_hit h, ref;
            sidx_accel_intersect(a, &rays[i], NULL, &h);
            sidx_accel_intersect(brute, &rays[i], NULL, &ref);
            if (!tk_hits_agree(&ref, &h)) fail_msg("refit %s ray %zu", wides[w], i);
        }
        sidx_accel_destroy(brute);
        sidx_accel_destroy(a);
    }
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- allocation failures ------------------------------------------------------------ */

typedef struct failing { int countdown, live; } failing;
static void *f_alloc(size_t size, void *user)
{
    failing *f = user;
    if (f->countdown-- == 0) return NULL;
    f->live++;
    return malloc(size);
}
static void f_free(void *p, void *user)
{
    failing *f = user;
    if (p) f->live--;
    free(p);
}

static void test_alloc_failures(void **state)
{
    (void)state;
    sidx_mesh m = scene("icosphere");
    for (int w = 0; w < NWIDES; ++w)
        for (int k = 0;; ++k) {
            failing f = {k, 0};
            const sidx_allocator al = {f_alloc, f_free, &f};
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.alloc = &al;
            sidx_accel *a = NULL;
            const sidx_status s = sidx_accel_build(wides[w], &m, &o, &a, NULL);
            if (s == SIDX_OK) {
                sidx_accel_destroy(a);
                assert_int_equal(f.live, 0);
                break;
            }
            assert_int_equal(s, SIDX_ERR_NOMEM);
            assert_null(a);
            assert_int_equal(f.live, 0);
            assert_true(k < 100);
        }
    sidx_mesh_free(&m);
}

/* ---- tiny and degenerate inputs ---------------------------------------------------- */

static void test_tiny_and_empty(void **state)
{
    (void)state;
    const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5};
    const uint32_t one[] = {0, 1, 2}, degen[] = {3, 3, 3};
    sidx_mesh m1, m0, md;
    assert_int_equal(sidx_mesh_from_arrays(&m1, xyz, 4, one, 1, NULL), SIDX_OK);
    assert_int_equal(sidx_mesh_from_arrays(&m0, xyz, 4, one, 0, NULL), SIDX_OK);
    assert_int_equal(sidx_mesh_from_arrays(&md, xyz, 4, degen, 1, NULL), SIDX_OK);
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, -1), sidx_v3(0, 0, 1), 0.0f, INFINITY), SIDX_OK);
    for (int w = 0; w < NWIDES; ++w)
        for (int simd = 0; simd < NSIMD; ++simd) {
            sidx_accel *a = build(wides[w], &m1, NULL, simd);
            sidx_hit h;
            sidx_accel_intersect(a, &r, NULL, &h);
            assert_int_equal(h.prim, 0);
            assert_true(fabsf(h.t - 1.0f) < 1e-6f);
            sidx_accel_destroy(a);
            a = build(wides[w], &m0, NULL, simd);
            sidx_accel_intersect(a, &r, NULL, &h);
            assert_int_equal(h.prim, SIDX_NO_HIT);
            sidx_accel_destroy(a);
            a = build(wides[w], &md, NULL, simd);
            sidx_accel_intersect(a, &r, NULL, &h);
            assert_int_equal(h.prim, SIDX_NO_HIT);
            sidx_accel_destroy(a);
        }
    sidx_mesh_free(&m1);
    sidx_mesh_free(&m0);
    sidx_mesh_free(&md);
}

/* ---- large arrays on 2 MB pages ------------------------------------------------------
 * A height field big enough that the leaf blocks pass WIDE_HUGE_MIN: the
 * block array starts on a 2 MB boundary (bvh_wide.c, alloc_array), the
 * small node array of a small scene does not have to, and the walk over
 * the large tree still agrees with brute force, closest and any hit. */

static void test_huge_arrays(void **state)
{
    (void)state;
    if (tk_under_valgrind()) { /* the build alone runs for minutes under memcheck */
        print_message("skipped under valgrind: a 352,800-triangle build (the sanitizer run checks it)\n");
        return;
    }
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make("grid", 420, &m, &err) != SIDX_OK) fail_msg("grid: %s", err.message);
    sidx_accel *a = build("bvh8", &m, NULL, 1), *brute = NULL;
    const wide_bvh *w = a->impl;
    const uintptr_t page = (uintptr_t)2u << 20;
    assert_true((size_t)w->num_blocks * sizeof(wide_tri4) >= ((size_t)8u << 20));
    assert_int_equal((uintptr_t)w->blocks & (page - 1u), 0);
    assert_true((uintptr_t)w->blocks >= (uintptr_t)w->blocks_mem);
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &brute, NULL), SIDX_OK);
    sidx_ray *rays;
    const size_t n = make_rays(&m, per_kind(40), 11, &rays);
    for (size_t i = 0; i < n; ++i) {
        sidx_hit ref, h;
        int oref, o;
        sidx_accel_intersect(brute, &rays[i], NULL, &ref);
        sidx_accel_intersect(a, &rays[i], NULL, &h);
        sidx_accel_occluded(brute, &rays[i], NULL, &oref);
        sidx_accel_occluded(a, &rays[i], NULL, &o);
        if (!tk_hits_agree(&ref, &h))
            fail_msg("ray %zu: prim %u t %.9g, brute prim %u t %.9g", i, h.prim, (double)h.t, ref.prim, (double)ref.t);
        assert_int_equal(o, oref);
    }
    free(rays);
    sidx_accel_destroy(brute);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_simd_equals_scalar), cmocka_unit_test(test_match_brute),
        cmocka_unit_test(test_uv_matches_core),
        cmocka_unit_test(test_no_leaks_icosphere), cmocka_unit_test(test_structure),
        cmocka_unit_test(test_event_ids),          cmocka_unit_test(test_treelet_order),          cmocka_unit_test(test_refit_matches_rebuild),
        cmocka_unit_test(test_alloc_failures),     cmocka_unit_test(test_tiny_and_empty),
        cmocka_unit_test(test_huge_arrays),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
