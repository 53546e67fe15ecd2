/* test_kdtree.c — the kd-tree family: kdtree (exact SAH, Wald & Havran
 * 2006), kdtree-binned, kdtree-median, kdtree-middle.
 *
 *  - the 8-byte node: size, bit layout, encode/decode, and the structural
 *    invariants of built trees (children side by side after their parent,
 *    leaves inside the reference array);
 *  - closest hits identical to brute force on every built-in scene and ray
 *    kind (incl. axis-parallel rays with exact ±0 components), for every
 *    builder and for the naive traversal; any-hit agrees with closest-hit;
 *  - no leaks from inside a closed icosphere aimed at vertices and edges;
 *  - the deck's "CANNOT terminate" case, on a hand-built tree;
 *  - rays starting exactly on split planes, with ±0 direction components;
 *  - teapot in a stadium: the SAH isolates the teapot in a few levels;
 *  - Menger sponge (coplanar faces) builds and traces correctly;
 *  - mailboxing: same hits, fewer tests, MAILBOX_HIT events;
 *  - the slide walk (traced queries, naive traversal) and the fast walk
 *    (untraced) return the same hits bit for bit, on random rays and on
 *    rays on, inside and across split planes;
 *  - exact build and traversal event sequences on a two-triangle scene;
 *  - the public view (sidx/kdtree.h): the tree's own node words decode to
 *    the splits and leaves the build events reported; errors for NULL
 *    arguments and for a structure that is not a kd-tree;
 *  - allocation failures at every point of every build: clean NOMEM. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "sidx/sidx.h"
#include "sidx/kdtree.h"
#include "common/testkit.h"
#include "kdtree_internal.h"

/* The kd-tree's leaf blocks come from the neutral tri4.h, not from the
 * wide BVH's layout: the kd-tree does not depend on bvh4/bvh8. */
#ifdef SIDX_BVH_WIDE_INTERNAL_H
#error "kdtree_internal.h reaches into bvh_wide_internal.h"
#endif
#ifndef SIDX_TRI4_H
#error "kdtree_internal.h does not use tri4.h"
#endif

static const char *const builders[] = {"kdtree", "kdtree-binned", "kdtree-median", "kdtree-middle"};
#define N_BUILDERS (sizeof builders / sizeof builders[0])

static const char *const scenes[] = {"icosphere", "teapot", "soup", "menger", "stadium", "cornell", "flat2d"};
#define N_SCENES (sizeof scenes / sizeof scenes[0])

static sidx_accel *build(const char *name, const sidx_mesh *m, const sidx_build_options *opt)
{
    sidx_accel *a = NULL;
    sidx_error err;
    const sidx_status s = sidx_accel_build(name, m, opt, &a, &err);
    if (s != SIDX_OK) fprintf(stderr, "build %s: %s\n", name, err.message);
    assert_int_equal(s, SIDX_OK);
    assert_non_null(a);
    return a;
}

static const kd_tree *tree_of(const sidx_accel *a) { return (const kd_tree *)a->impl; }

static void make_scene(const char *name, uint32_t detail, sidx_mesh *m)
{
    sidx_error err;
    assert_int_equal(sidx_scene_make(name, detail, m, &err), SIDX_OK);
}

static sidx_ray ray_of(const tk_rayrec *rec)
{
    sidx_ray r;
    assert_int_equal(tk_ray_from(rec, &r), SIDX_OK);
    return r;
}

/* ---- the node -------------------------------------------------------------- */

static void test_node_layout(void **state)
{
    (void)state;
    /* _Static_assert(sizeof(kd_node) == 8) lives in kdtree_internal.h; this
     * repeats it at run time and checks where each field sits. */
    assert_int_equal(sizeof(kd_node), 8);
    assert_int_equal(offsetof(kd_node, u), 0);
    assert_int_equal(offsetof(kd_node, bits), 4);

    kd_node n = kd_make_inner(2, 1.5f, 12345u);
    assert_false(kd_is_leaf(&n));
    assert_int_equal(kd_axis(&n), 2);
    assert_int_equal(kd_child(&n), 12345u);
    assert_true(n.u.split == 1.5f);
    assert_int_equal(n.bits, (12345u << 2) | 2u);
    uint32_t raw[2];
    memcpy(raw, &n, sizeof raw);
    float f;
    memcpy(&f, &raw[0], sizeof f);
    assert_true(f == 1.5f);           /* word 0: the split, a plain float */
    assert_int_equal(raw[1] & 3u, 2); /* word 1, low 2 bits: the axis */
    assert_int_equal(raw[1] >> 2, 12345u);

    for (uint32_t ax = 0; ax < 3; ++ax) {
        const kd_node m = kd_make_inner(ax, -0.25f, KD_INDEX_LIMIT - 2u);
        assert_false(kd_is_leaf(&m));
        assert_int_equal(kd_axis(&m), ax);
        assert_int_equal(kd_child(&m), KD_INDEX_LIMIT - 2u);
    }

    const kd_node l = kd_make_leaf(7u, 99u);
    assert_true(kd_is_leaf(&l));
    assert_false(kd_is_empty(&l));
    assert_int_equal(kd_axis(&l), KD_LEAF_FLAG);
    assert_int_equal(kd_count(&l), 7u);
    assert_int_equal(kd_offset(&l), 99u);
    memcpy(raw, &l, sizeof raw);
    assert_int_equal(raw[0], 7u);
    assert_int_equal(raw[1], (99u << 2) | 3u);
    const kd_node e = kd_make_leaf(0u, 0u);
    assert_true(kd_is_empty(&e));
}

/* Every node but the root is a child exactly once; children come after
 * their parent (depth-first); leaves address valid references; the
 * per-reference vertex copies match the mesh. */
static void check_structure(const sidx_accel *a, const sidx_mesh *m)
{
    const kd_tree *kd = tree_of(a);
    assert_non_null(kd);
    uint8_t *seen = calloc(kd->num_nodes, 1);
    assert_non_null(seen);
    uint32_t leaves = 0, empty = 0;
    uint64_t refs = 0;
    for (uint32_t i = 0; i < kd->num_nodes; ++i) {
        const kd_node *n = &kd->nodes[i];
        if (kd_is_leaf(n)) {
            ++leaves;
            empty += kd_count(n) == 0;
            refs += kd_count(n);
            assert_true((uint64_t)kd_offset(n) + kd_count(n) <= kd->num_refs);
            continue;
        }
        const uint32_t c = kd_child(n);
        assert_true(c > i);
        assert_true(c + 1u < kd->num_nodes);
        assert_false(seen[c]);
        assert_false(seen[c + 1u]);
        seen[c] = seen[c + 1u] = 1;
        const float lo = sidx_v3_get(kd->bounds.min, (int)kd_axis(n));
        const float hi = sidx_v3_get(kd->bounds.max, (int)kd_axis(n));
        assert_true(n->u.split > lo && n->u.split < hi);
    }
    for (uint32_t i = 1; i < kd->num_nodes; ++i) assert_true(seen[i]);
    free(seen);
    assert_int_equal(kd->num_nodes, 2u * leaves - 1u);
    assert_int_equal(refs, kd->num_refs);
    assert_int_equal(kd->num_blocks, (kd->num_refs + 3u) / 4u);
    assert_int_equal((uintptr_t)kd->blocks % 64u, 0);
    for (uint32_t i = 0; i < 4u * kd->num_blocks; ++i) {
        const tri4_block *B = &kd->blocks[i / 4u];
        const uint32_t l = i % 4u;
        if (i >= kd->num_refs) { /* padding: NaN vertices never hit */
            assert_int_equal(B->prim[l], TRI4_PAD_PRIM);
            assert_true(B->v[0][0][l] != B->v[0][0][l]);
            continue;
        }
        assert_true(kd->prims[i] < m->num_triangles);
        assert_int_equal(B->prim[l], kd->prims[i]);
        for (uint32_t v = 0; v < 3; ++v) {
            const sidx_vec3 p = m->positions[m->indices[3u * kd->prims[i] + v]];
            assert_true(B->v[v][0][l] == p.x && B->v[v][1][l] == p.y && B->v[v][2][l] == p.z);
        }
    }
    sidx_accel_stats s;
    assert_int_equal(sidx_accel_stats_get(a, &s), SIDX_OK);
    assert_int_equal(s.nodes, kd->num_nodes);
    assert_int_equal(s.leaves, leaves);
    assert_int_equal(s.empty_leaves, empty);
    assert_int_equal(s.prim_refs, kd->num_refs);
    assert_true(s.prim_refs >= m->num_triangles); /* every triangle is somewhere */
    assert_true(s.bytes >= (size_t)kd->num_nodes * 8u);
    assert_true(s.sah_cost > 0.0);
    assert_true(s.max_depth <= KD_MAX_DEPTH);
    if (leaves > empty) assert_true(s.mean_leaf_prims >= 1.0);
}

/* ---- against brute force ---------------------------------------------------- */

/* Closest hits of a against the references ref_hits (brute force, computed
 * once per ray set), and any-hit against closest-hit. */
static void check_hits(const sidx_hit *ref_hits, const sidx_accel *a, const tk_rayrec *rays, size_t n,
                       const char *scene, const char *kind, sidx_traversal trav)
{
    const sidx_query q = {0, trav, NULL, 0};
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray r = ray_of(&rays[i]);
        const sidx_hit hr = ref_hits[i];
        sidx_hit hg;
        assert_int_equal(sidx_accel_intersect(a, &r, &q, &hg), SIDX_OK);
        if (!tk_hits_agree(&hr, &hg)) {
            fprintf(stderr,
                    "%s (%s) on %s, %s ray %zu: o=(%.9g %.9g %.9g) d=(%.9g %.9g %.9g) brute prim %u t %.9g, got "
                    "prim %u t %.9g\n",
                    sidx_accel_name(a), sidx_traversal_name(trav), scene, kind, i, (double)r.org.x,
                    (double)r.org.y, (double)r.org.z, (double)r.dir.x, (double)r.dir.y, (double)r.dir.z, hr.prim,
                    (double)hr.t, hg.prim, (double)hg.t);
            fail();
        }
        int occ = -1;
        assert_int_equal(sidx_accel_occluded(a, &r, NULL, &occ), SIDX_OK);
        if (occ != (hr.prim != SIDX_NO_HIT)) {
            fprintf(stderr, "%s on %s, %s ray %zu: occluded %d but closest hit prim %u\n", sidx_accel_name(a),
                    scene, kind, i, occ, hr.prim);
            fail();
        }
    }
}

static void ref_hits_of(const sidx_accel *ref, const tk_rayrec *rays, size_t n, sidx_hit *out)
{
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray r = ray_of(&rays[i]);
        assert_int_equal(sidx_accel_intersect(ref, &r, NULL, &out[i]), SIDX_OK);
    }
}

static void check_rays(const sidx_accel *ref, const sidx_accel *a, const tk_rayrec *rays, size_t n,
                       const char *scene, const char *kind, sidx_traversal trav)
{
    sidx_hit *h = malloc((n ? n : 1) * sizeof *h);
    assert_non_null(h);
    ref_hits_of(ref, rays, n, h);
    check_hits(h, a, rays, n, scene, kind, trav);
    free(h);
}

static void test_against_brute(void **state)
{
    (void)state;
    const size_t per_kind = tk_tiny_tests() ? 12 : tk_fast_tests() ? 40 : 100;
    const size_t nk = TK_RAYS_KIND_COUNT + 1; /* + one diffuse set for the naive traversal */
    tk_rayrec *rays = malloc(per_kind * nk * sizeof *rays);
    sidx_hit *ref_hits = malloc(per_kind * nk * sizeof *ref_hits);
    assert_non_null(rays);
    assert_non_null(ref_hits);
    for (size_t s = 0; s < N_SCENES; ++s) {
        sidx_mesh m;
        make_scene(scenes[s], 0, &m);
        sidx_accel *ref = build("brute", &m, NULL);
        for (size_t kind = 0; kind < nk; ++kind) {
            const tk_ray_kind kk = kind < TK_RAYS_KIND_COUNT ? (tk_ray_kind)kind : TK_RAYS_DIFFUSE;
            tk_make_rays(&m, kk, per_kind, 4242 + s + 100 * kind, rays + kind * per_kind);
        }
        ref_hits_of(ref, rays, per_kind * nk, ref_hits);
        for (size_t k = 0; k < N_BUILDERS; ++k) {
            sidx_accel *a = build(builders[k], &m, NULL);
            check_structure(a, &m);
            for (size_t kind = 0; kind < nk; ++kind) {
                const tk_ray_kind kk = kind < TK_RAYS_KIND_COUNT ? (tk_ray_kind)kind : TK_RAYS_DIFFUSE;
                /* the last set goes through the naive traversal (no
                 * ordering, no early exit): it must find the same */
                check_hits(ref_hits + kind * per_kind, a, rays + kind * per_kind, per_kind, scenes[s],
                           tk_ray_kind_name(kk), kind < TK_RAYS_KIND_COUNT ? SIDX_TRAVERSE_DEFAULT : SIDX_TRAVERSE_NAIVE);
            }
            sidx_accel_destroy(a);
        }
        sidx_accel_destroy(ref);
        sidx_mesh_free(&m);
    }
    free(ref_hits);
    free(rays);
}

/* Other constants, tiny leaves, shallow depth limits, few bins. */
static void test_against_brute_options(void **state)
{
    (void)state;
    const size_t n = 150;
    tk_rayrec *rays = malloc(2 * n * sizeof *rays);
    sidx_hit *ref_hits = malloc(2 * n * sizeof *ref_hits);
    assert_non_null(rays);
    assert_non_null(ref_hits);
    const char *const sc[] = {"teapot", "flat2d"};
    for (size_t s = 0; s < 2; ++s) {
        sidx_mesh m;
        make_scene(sc[s], 0, &m);
        sidx_accel *ref = build("brute", &m, NULL);
        tk_make_rays(&m, TK_RAYS_DIFFUSE, n, 99 + s, rays);
        tk_make_rays(&m, TK_RAYS_AXIS, n, 7 + s, rays + n);
        ref_hits_of(ref, rays, 2 * n, ref_hits);
        for (size_t k = 0; k < N_BUILDERS; ++k)
            for (int d = 0; d < 3; ++d) {
                /* pbrt's 1:80 with bonus 0.5; the deck's 1:1.5 with depth
                 * limit 20 and 4 bins; huge leaves with depth limit 3 */
                sidx_build_options opt;
                memset(&opt, 0, sizeof opt);
                opt.c_trav = d == 0 ? 1.0f : d == 1 ? 1.0f : 0.0f;
                opt.c_tri = d == 0 ? 80.0f : d == 1 ? 1.5f : 0.0f;
                opt.empty_bonus = d == 0 ? 0.5f : 0.0f;
                opt.leaf_size = d == 2 ? 16 : 0;
                opt.max_depth = d == 2 ? 3 : d == 1 ? 20 : 0;
                opt.bins = d == 1 ? 4 : 0;
                sidx_accel *a = build(builders[k], &m, &opt);
                check_structure(a, &m);
                if (d == 2) {
                    sidx_accel_stats st;
                    sidx_accel_stats_get(a, &st);
                    assert_true(st.max_depth <= 3);
                }
                check_hits(ref_hits, a, rays, n, sc[s], "diffuse", SIDX_TRAVERSE_DEFAULT);
                check_hits(ref_hits + n, a, rays + n, n, sc[s], "axis", SIDX_TRAVERSE_DEFAULT);
                sidx_accel_destroy(a);
            }
        sidx_accel_destroy(ref);
        sidx_mesh_free(&m);
    }
    free(ref_hits);
    free(rays);
}

/* ---- leaks -------------------------------------------------------------------- */

static void test_no_leaks_icosphere(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("icosphere", 0, &m);
    const size_t max = (size_t)m.num_triangles * 6u;
    tk_rayrec *rays = malloc(max * sizeof *rays);
    assert_non_null(rays);
    const sidx_vec3 inside[] = {{0.0f, 0.0f, 0.0f}, {0.1f, -0.2f, 0.3f}, {-0.5f, 0.25f, 0.125f}};
    for (size_t o = 0; o < 3; ++o) {
        const size_t n = tk_make_leak_rays(&m, inside[o], max, rays);
        assert_true(n > 1000);
        for (size_t k = 0; k < N_BUILDERS; ++k) {
            sidx_accel *a = build(builders[k], &m, NULL);
            size_t leaks = 0;
            for (size_t i = 0; i < n; ++i) {
                const sidx_ray r = ray_of(&rays[i]);
                sidx_hit h;
                sidx_accel_intersect(a, &r, NULL, &h);
                int occ = 0;
                sidx_accel_occluded(a, &r, NULL, &occ);
                leaks += (h.prim == SIDX_NO_HIT) + (occ == 0);
            }
            if (leaks) fprintf(stderr, "%s: %zu leaks of %zu rays\n", builders[k], leaks, n);
            assert_int_equal(leaks, 0);
            sidx_accel_destroy(a);
        }
    }
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- a tiny recorder (the sinks are not this suite's business) ---------------- */

typedef struct rec {
    sidx_event ev[256];
    size_t n;
} rec;

static void rec_fn(const sidx_event *e, void *user)
{
    rec *r = user;
    if (r->n < 256) r->ev[r->n] = *e;
    r->n++;
}

static size_t count_type(const rec *r, sidx_event_type t)
{
    size_t c = 0;
    for (size_t i = 0; i < r->n && i < 256; ++i) c += r->ev[i].type == t;
    return c;
}

/* ---- the deck's "CANNOT terminate" case ------------------------------------------ */

/* A hand-made tree: root split at x = 0.5; the left leaf holds the big
 * slanted triangle A, the right leaf holds A again and the small triangle
 * B.  The ray runs along +x at y = z = 0 from x = -2:
 *
 *        left cell          | right cell
 *   x:  -0.5 ............. 0.5 ......... 1.0 (B) .... 1.5 (A hit) ... 3.5
 *
 * A is tested first (left leaf) and hit at x = 1.5, beyond the left cell's
 * t_far: stopping there ("hit found, done") would answer A.  The right
 * cell then finds B at x = 1.0, closer: the right answer. */
static void make_cannot_terminate_mesh(sidx_mesh *m)
{
    const float xyz[] = {
        -0.5f, -1.0f, -1.0f, -0.5f, -1.0f, 1.0f, 3.5f, 1.0f, 0.0f, /* A: plane x = 1.5 + 2y */
        1.0f,  -0.5f, -0.5f, 1.0f,  0.5f,  -0.5f, 1.0f, 0.0f, 0.7f, /* B: plane x = 1 */
    };
    const uint32_t idx[] = {0, 1, 2, 3, 4, 5};
    assert_int_equal(sidx_mesh_from_arrays(m, xyz, 6, idx, 2, NULL), SIDX_OK);
}

/* Replace a built tree's arrays by a hand-written one (default allocator
 * = malloc, so the structure frees them normally). */
static void hand_tree(sidx_accel *a, const sidx_mesh *m, const kd_node *nodes, uint32_t nn, const uint32_t *prims,
                      uint32_t np)
{
    kd_tree *kd = a->impl;
    free(kd->nodes_mem); /* kd->nodes lies inside it (cache-line placement) */
    free(kd->prims);
    kd->nodes = malloc(nn * sizeof *nodes);
    kd->nodes_mem = kd->nodes;
    kd->prims = malloc(np * sizeof *prims);
    assert_non_null(kd->nodes);
    assert_non_null(kd->prims);
    memcpy(kd->nodes, nodes, nn * sizeof *nodes);
    memcpy(kd->prims, prims, np * sizeof *prims);
    kd->num_nodes = nn;
    kd->num_refs = np;
    assert_int_equal(sidx__kd_make_blocks(a, kd, m), SIDX_OK); /* the leaves' triangle copies */
}

static void test_cannot_terminate(void **state)
{
    (void)state;
    sidx_mesh m;
    make_cannot_terminate_mesh(&m);
    for (int mb = 0; mb < 2; ++mb) {
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.no_mailbox = mb;
        sidx_accel *a = build("kdtree", &m, &opt);
        /* left: A (reference 4); right: A, B (references 0, 1).  The
         * leaves sit in different blocks of four, so that the left leaf's
         * block does not test B on the way (kd_test_leaf); references 2, 3
         * fill the right leaf's block and belong to no leaf. */
        const kd_node nodes[3] = {kd_make_inner(0, 0.5f, 1u), kd_make_leaf(1u, 4u), kd_make_leaf(2u, 0u)};
        const uint32_t prims[5] = {0u, 1u, 1u, 1u, 0u};
        hand_tree(a, &m, nodes, 3, prims, 5);

        sidx_ray r;
        assert_int_equal(sidx_ray_init(&r, sidx_v3(-2.0f, 0.0f, 0.0f), sidx_v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY),
                         SIDX_OK);
        sidx_hit h;
        sidx_accel_intersect(a, &r, NULL, &h);
        assert_int_equal(h.prim, 1u); /* B, not A */
        assert_true(fabsf(h.t - 3.0f) < 1e-5f);

        /* the same, traced: A is hit first, beyond the left cell, and does
         * not end the walk; the right cell's B does */
        rec rc;
        rc.n = 0;
        const sidx_hook hook = {rec_fn, &rc, 0};
        const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
        sidx_accel_intersect(a, &r, &q, &h);
        assert_int_equal(h.prim, 1u);
        int saw_a = 0, a_beyond = 0, term = 0;
        float left_far = 0.0f;
        uint32_t current = UINT32_MAX;
        for (size_t i = 0; i < rc.n; ++i) {
            const sidx_event *e = &rc.ev[i];
            if (e->type == SIDX_EV_NODE_ENTER) current = e->node;
            if (e->type == SIDX_EV_NODE_ENTER && e->node == 1u) left_far = e->t_far;
            if (e->type == SIDX_EV_HIT_UPDATE && e->prim == 0u) {
                saw_a = 1;
                a_beyond = e->t > left_far;
            }
            if (e->type == SIDX_EV_HIT_UPDATE && e->prim == 1u) assert_int_equal(current, 2u); /* B in the right cell */
            if (e->type == SIDX_EV_TERMINATE) {
                term = 1;
                assert_int_equal(e->reason, SIDX_TERM_HIT_IN_CELL);
                assert_true(fabsf(e->t - 3.0f) < 1e-5f);
            }
        }
        assert_true(saw_a);
        assert_true(a_beyond);
        assert_true(term);
        assert_int_equal(count_type(&rc, SIDX_EV_MAILBOX_HIT), mb ? 0u : 1u); /* A again on the right */
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

/* ---- ±0 directions, origins on split planes ---------------------------------------- */

static void test_zero_dirs_and_origin_on_split(void **state)
{
    (void)state;
    const char *const sc[] = {"menger", "cornell", "teapot"};
    const uint32_t detail[] = {1, 0, 12};
    for (size_t s = 0; s < 3; ++s) {
        sidx_mesh m;
        make_scene(sc[s], detail[s], &m);
        sidx_accel *ref = build("brute", &m, NULL);
        for (size_t k = 0; k < N_BUILDERS; ++k) {
            sidx_accel *a = build(builders[k], &m, NULL);
            const kd_tree *kd = tree_of(a);
            tk_rng rng;
            tk_rng_seed(&rng, 5 + s);
            const sidx_aabb bb = kd->bounds;
            size_t tested = 0;
            for (uint32_t i = 0; i < kd->num_nodes && tested < 150; i += 1u + kd->num_nodes / 29u) {
                const kd_node *n = &kd->nodes[i];
                if (kd_is_leaf(n)) continue;
                const int ax = (int)kd_axis(n);
                for (int rep = 0; rep < 6; ++rep, ++tested) {
                    float o[3], d[3];
                    for (int c = 0; c < 3; ++c)
                        o[c] = (float)tk_rng_range(&rng, sidx_v3_get(bb.min, c), sidx_v3_get(bb.max, c));
                    o[ax] = n->u.split; /* exactly on the plane */
                    const sidx_vec3 u = tk_rng_sphere(&rng);
                    d[0] = u.x;
                    d[1] = u.y;
                    d[2] = u.z;
                    /* rep 0,1: in the plane (d[ax] = ±0); rep 2,3: axis-parallel
                     * along another axis (two ±0 components); rep 4,5: general
                     * direction leaving the plane */
                    if (rep < 2) d[ax] = rep ? -0.0f : 0.0f;
                    else if (rep < 4) {
                        const int keep = (ax + 1 + (rep & 1)) % 3;
                        for (int c = 0; c < 3; ++c)
                            if (c != keep) d[c] = (rep & 1) ? -0.0f : 0.0f;
                        if (d[keep] == 0.0f) d[keep] = 1.0f;
                    }
                    const tk_rayrec rr = tk_rayrec_make(sidx_v3(o[0], o[1], o[2]), sidx_v3(d[0], d[1], d[2]), 0.0f,
                                                        INFINITY);
                    check_rays(ref, a, &rr, 1, sc[s], "on-split", SIDX_TRAVERSE_DEFAULT);
                }
            }
            assert_true(tested > 0);
            sidx_accel_destroy(a);
        }
        sidx_accel_destroy(ref);
        sidx_mesh_free(&m);
    }
}

/* The NaN case by hand: the ray lies inside the root's split plane and
 * hits a triangle that only touches that plane from the far side. */
static void test_ray_inside_split_plane(void **state)
{
    (void)state;
    /* T0 lies left of x = 0.5 and touches it with an edge; T1 lies right
     * of it and touches it with a vertex that the ray passes through. */
    const float xyz[] = {
        0.0f, 0.0f, -1.0f, 0.5f, 0.0f, -1.0f, 0.5f, 0.0f, 1.0f, /* T0 in y = 0, edge on x = 0.5 */
        0.5f, 2.0f, -1.0f, 1.0f, 2.0f, 1.0f,  1.0f, 2.0f, -1.0f, /* T1 in y = 2 */
        0.5f, 3.0f, -1.0f, 0.5f, 3.0f, 1.0f,  1.0f, 3.0f, 0.0f,  /* T2 in y = 3, edge on x = 0.5 */
    };
    const uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 9, idx, 3, NULL), SIDX_OK);
    sidx_accel *a = build("kdtree", &m, NULL);
    /* left leaf: T0; right leaf: T1, T2 */
    const kd_node nodes[3] = {kd_make_inner(0, 0.5f, 1u), kd_make_leaf(1u, 0u), kd_make_leaf(2u, 1u)};
    const uint32_t prims[3] = {0u, 1u, 2u};
    hand_tree(a, &m, nodes, 3, prims, 3);
    sidx_accel *ref = build("brute", &m, NULL);
    const float dirs[][3] = {{0.0f, 1.0f, 0.0f}, {-0.0f, 1.0f, 0.0f}, {0.0f, 1.0f, 0.25f}, {-0.0f, 1.0f, -0.0f}};
    for (int i = 0; i < 4; ++i) {
        sidx_ray r;
        assert_int_equal(sidx_ray_init(&r, sidx_v3(0.5f, -1.0f, 0.0f), sidx_v3(dirs[i][0], dirs[i][1], dirs[i][2]),
                                       0.0f, INFINITY),
                         SIDX_OK);
        sidx_hit hr, hg;
        sidx_accel_intersect(ref, &r, NULL, &hr);
        sidx_accel_intersect(a, &r, NULL, &hg);
        assert_true(hr.prim != SIDX_NO_HIT);
        assert_true(tk_hits_agree(&hr, &hg));
    }
    sidx_accel_destroy(ref);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* ---- what the traced walk says at its stack -------------------------------------------- */

/* Replays one traced query's events: every pop says whether the node is
 * entered (the next event enters it) or dropped (its t_near lies beyond
 * the best hit, and nothing enters it); an entry pushed with the ray in
 * the split plane says so at its push and again at its pop.  Counts what
 * it saw in seen[result][pop]; sets *after_hit when an in-plane pop comes
 * after a hit (the walk goes on where it would have stopped). */
static void check_stack_events(const sidx_recorder *rec, int naive, int seen[3][2], int *after_hit)
{
    uint32_t node[KD_MAX_DEPTH + 2];
    int in_plane[KD_MAX_DEPTH + 2];
    size_t n = 0;
    float best = INFINITY;
    assert_false(rec->overflow);
    for (size_t i = 0; i < rec->count; ++i) {
        const sidx_event *e = &rec->events[i];
        if (e->type == SIDX_EV_HIT_UPDATE) best = e->t;
        if (e->type == SIDX_EV_STACK_PUSH) {
            assert_true(e->result == -1 || e->result == SIDX_STACK_IN_PLANE);
            assert_true(n < KD_MAX_DEPTH + 2);
            node[n] = e->node;
            in_plane[n++] = e->result == SIDX_STACK_IN_PLANE;
            if (e->result == SIDX_STACK_IN_PLANE) seen[SIDX_STACK_IN_PLANE][0] = 1;
        }
        if (e->type != SIDX_EV_STACK_POP) continue;
        assert_true(n > 0);
        --n;
        assert_int_equal(e->node, node[n]);
        const int enter = naive || e->t_near <= best;
        const sidx_event *next = i + 1 < rec->count ? &rec->events[i + 1] : NULL;
        const int entered = next && next->type == SIDX_EV_NODE_ENTER && next->node == e->node;
        assert_int_equal(entered, enter);
        const int want = !enter ? SIDX_STACK_DROPPED : in_plane[n] ? SIDX_STACK_IN_PLANE : SIDX_STACK_ENTERED;
        if (e->result != want)
            fail_msg("pop of node %u t=[%g, %g], best %g: result %d, want %d", e->node, (double)e->t_near,
                     (double)e->t_far, (double)best, e->result, want);
        seen[want][1] = 1;
        if (want == SIDX_STACK_IN_PLANE && best < INFINITY) *after_hit = 1;
    }
}

/* The teapot ray of the stepper's example runs inside the root's split
 * plane x = 0: both children span [3, 7], so after the hit in the first
 * the walk goes on through the second, and the push and pop of that
 * child say why; pops beyond the hit say they are dropped (a walk that
 * stops at a hit in its cell drops only there).  Rays off the planes
 * never say "in plane"; the naive walk drops nothing. */
static void test_stack_events_say_why(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", 0, &m);
    sidx_accel *a = build("kdtree", &m, NULL);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook hook = sidx_recorder_hook(&rec);
    for (int naive = 0; naive < 2; ++naive) {
        const sidx_query q = {0, naive ? SIDX_TRAVERSE_NAIVE : SIDX_TRAVERSE_DEFAULT, &hook, 0};
        sidx_ray r;
        assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0.5f, 5), sidx_v3(0, 0, -1), 0, INFINITY), SIDX_OK);
        sidx_hit hit;
        sidx_recorder_clear(&rec);
        assert_int_equal(sidx_accel_intersect(a, &r, &q, &hit), SIDX_OK);
        assert_true(hit.prim != SIDX_NO_HIT);
        int seen[3][2] = {{0}}, after_hit = 0;
        check_stack_events(&rec, naive, seen, &after_hit);
        assert_true(seen[SIDX_STACK_IN_PLANE][0] && seen[SIDX_STACK_IN_PLANE][1] && after_hit);
        assert_int_equal(seen[SIDX_STACK_DROPPED][1], !naive);

        /* off the planes: entered or dropped, never "in plane" */
        const size_t nrays = 300;
        tk_rayrec *rays = malloc(nrays * sizeof *rays);
        assert_non_null(rays);
        tk_make_rays(&m, TK_RAYS_DIFFUSE, nrays, 4242, rays);
        int any[3][2] = {{0}};
        for (size_t i = 0; i < nrays; ++i) {
            r = ray_of(&rays[i]);
            sidx_recorder_clear(&rec);
            assert_int_equal(sidx_accel_intersect(a, &r, &q, &hit), SIDX_OK);
            int ah = 0;
            check_stack_events(&rec, naive, any, &ah);
        }
        assert_false(any[SIDX_STACK_IN_PLANE][0] || any[SIDX_STACK_IN_PLANE][1]);
        assert_true(any[SIDX_STACK_ENTERED][1]);
        if (naive) assert_false(any[SIDX_STACK_DROPPED][1]);
        free(rays);
    }
    sidx_recorder_free(&rec);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* ---- teapot in a stadium -------------------------------------------------------------- */

typedef struct walk_ctx {
    const kd_tree *kd;
    const uint8_t *is_teapot;
    uint32_t leaves_with_teapot, max_teapot_leaf_depth, lca, lca_depth;
    sidx_aabb lca_cell;
} walk_ctx;

/* Returns how many teapot references lie in the subtree; records the
 * deepest node whose subtree holds all of them. */
static uint32_t walk(walk_ctx *w, uint32_t node, uint32_t depth, sidx_aabb cell, uint32_t total)
{
    const kd_node *n = &w->kd->nodes[node];
    uint32_t c = 0;
    if (kd_is_leaf(n)) {
        for (uint32_t i = 0; i < kd_count(n); ++i) c += w->is_teapot[w->kd->prims[kd_offset(n) + i]];
        if (c) {
            w->leaves_with_teapot++;
            if (depth > w->max_teapot_leaf_depth) w->max_teapot_leaf_depth = depth;
        }
    } else {
        sidx_aabb l = cell, r = cell;
        const uint32_t ax = kd_axis(n);
        if (ax == 0) { l.max.x = n->u.split; r.min.x = n->u.split; }
        else if (ax == 1) { l.max.y = n->u.split; r.min.y = n->u.split; }
        else { l.max.z = n->u.split; r.min.z = n->u.split; }
        c = walk(w, kd_child(n), depth + 1, l, total) + walk(w, kd_child(n) + 1, depth + 1, r, total);
    }
    /* post-order: the first node found holding all of them is the deepest */
    if (c == total && w->lca == UINT32_MAX) {
        w->lca = node;
        w->lca_depth = depth;
        w->lca_cell = cell;
    }
    return c;
}

static void test_stadium_isolates_teapot(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("stadium", 0, &m);
    uint8_t *is_teapot = calloc(m.num_triangles, 1);
    assert_non_null(is_teapot);
    sidx_aabb teapot = sidx_aabb_empty();
    for (uint32_t i = 0; i < m.num_triangles; ++i) {
        const sidx_aabb b = sidx_mesh_triangle_bounds(&m, i);
        /* the teapot is ~1 unit at the origin; the stadium spans ±1100 */
        if (b.max.x - b.min.x < 5.0f && fabsf(b.min.x) < 5.0f && fabsf(b.min.z) < 5.0f && b.max.y < 5.0f) {
            is_teapot[i] = 1;
            teapot = sidx_aabb_union(teapot, b);
        }
    }
    uint32_t total_tp = 0;
    for (uint32_t i = 0; i < m.num_triangles; ++i) total_tp += is_teapot[i];
    assert_true(total_tp > 100);

    const char *const names[] = {"kdtree", "kdtree-middle"};
    double per_leaf[2] = {0.0, 0.0};
    for (int k = 0; k < 2; ++k) {
        sidx_accel *a = build(names[k], &m, NULL);
        const kd_tree *kd = tree_of(a);
        uint32_t refs_tp = 0;
        for (uint32_t i = 0; i < kd->num_refs; ++i) refs_tp += is_teapot[kd->prims[i]];
        walk_ctx w = {kd, is_teapot, 0, 0, UINT32_MAX, 0, sidx_aabb_empty()};
        walk(&w, 0, 0, kd->bounds, refs_tp);
        assert_true(w.lca != UINT32_MAX);
        assert_true(w.leaves_with_teapot > 0);
        per_leaf[k] = (double)refs_tp / (double)w.leaves_with_teapot;
        if (k == 0) {
            /* The SAH's empty-space cuts carve the ~1-unit teapot out of a
             * ~2200-unit scene within a handful of levels: the smallest
             * cell holding all of it is no bigger than twice the teapot's
             * own box on every axis and sits at depth <= 8 (measured: 5);
             * below it the tree spends at least 10 more levels on the
             * teapot's detail, down to small leaves. */
            const sidx_vec3 ce = sidx_aabb_extent(w.lca_cell), te = sidx_aabb_extent(teapot);
            assert_true(ce.x <= 2.0f * te.x && ce.y <= 2.0f * te.y && ce.z <= 2.0f * te.z);
            assert_true(w.lca_depth <= 8);
            assert_true(w.max_teapot_leaf_depth >= w.lca_depth + 10);
            /* leaves of about C_trav / C_tri references: past that a
             * split costs less than testing them (measured: 17 at 16 : 1) */
            assert_true(per_leaf[0] < 2.0 * KD_DEFAULT_C_TRAV / KD_DEFAULT_C_TRI);
        }
        sidx_accel_destroy(a);
    }
    /* The middle split halves a 2200-unit box: it runs out of depth long
     * before cells are teapot-sized and leaves the teapot in a handful of
     * huge leaves (the deck: "All of these techniques are NOT very clever"). */
    assert_true(per_leaf[1] > 10.0 * per_leaf[0]);
    free(is_teapot);
    sidx_mesh_free(&m);
}

/* ---- Menger sponge ------------------------------------------------------------------------- */

static void test_menger(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("menger", 2, &m);
    sidx_accel *ref = build("brute", &m, NULL);
    const size_t n = tk_fast_tests() ? 60 : 120;
    const tk_ray_kind kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_AXIS, TK_RAYS_GRAZING, TK_RAYS_SHADOW};
    tk_rayrec *rays = malloc(4 * n * sizeof *rays);
    sidx_hit *ref_hits = malloc(4 * n * sizeof *ref_hits);
    assert_non_null(rays);
    assert_non_null(ref_hits);
    for (int i = 0; i < 4; ++i) tk_make_rays(&m, kinds[i], n, 31 + (uint64_t)i, rays + (size_t)i * n);
    ref_hits_of(ref, rays, 4 * n, ref_hits);
    for (size_t k = 0; k < N_BUILDERS; ++k) {
        sidx_accel *a = build(builders[k], &m, NULL);
        check_structure(a, &m);
        for (int i = 0; i < 4; ++i)
            check_hits(ref_hits + (size_t)i * n, a, rays + (size_t)i * n, n, "menger", tk_ray_kind_name(kinds[i]),
                       SIDX_TRAVERSE_DEFAULT);
        sidx_accel_destroy(a);
    }
    /* the SAH tree separates the sponge's cubes: small leaves */
    sidx_accel *a = build("kdtree", &m, NULL);
    sidx_accel_stats st;
    sidx_accel_stats_get(a, &st);
    assert_true(st.mean_leaf_prims < 16.0);
    assert_true(st.leaves > m.num_triangles / 16u);
    sidx_accel_destroy(a);
    free(ref_hits);
    free(rays);
    sidx_accel_destroy(ref);
    sidx_mesh_free(&m);
}

/* ---- mailboxing ------------------------------------------------------------------------------- */

static void count_fn(const sidx_event *e, void *user) { ((uint64_t *)user)[e->type]++; }

static void test_mailbox(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("stadium", 0, &m);
    const size_t n = tk_fast_tests() ? 200 : 800;
    tk_rayrec *rays = malloc(n * sizeof *rays);
    assert_non_null(rays);
    tk_make_rays(&m, TK_RAYS_DIFFUSE, n, 17, rays);
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    sidx_accel *on = build("kdtree", &m, &opt);
    opt.no_mailbox = 1;
    sidx_accel *off = build("kdtree", &m, &opt);
    sidx_accel_stats st;
    sidx_accel_stats_get(on, &st);
    assert_true(st.prim_refs > m.num_triangles); /* there is duplication to skip */
    uint64_t c_on[SIDX_EV_COUNT], c_off[SIDX_EV_COUNT];
    memset(c_on, 0, sizeof c_on);
    memset(c_off, 0, sizeof c_off);
    const sidx_hook h_on = {count_fn, c_on, 0}, h_off = {count_fn, c_off, 0};
    const sidx_query q_on = {0, SIDX_TRAVERSE_DEFAULT, &h_on, 0}, q_off = {0, SIDX_TRAVERSE_DEFAULT, &h_off, 0};
    for (size_t i = 0; i < n; ++i) {
        const sidx_ray r = ray_of(&rays[i]);
        sidx_hit a, b, c;
        sidx_accel_intersect(on, &r, &q_on, &a);
        sidx_accel_intersect(off, &r, &q_off, &b);
        sidx_accel_intersect(on, &r, NULL, &c); /* untraced instance agrees with the traced one */
        assert_int_equal(a.prim, b.prim);
        assert_true(a.t == b.t || (isinf(a.t) && isinf(b.t)));
        assert_int_equal(a.prim, c.prim);
        int oa = 0, ob = 0;
        sidx_accel_occluded(on, &r, NULL, &oa);
        sidx_accel_occluded(off, &r, NULL, &ob);
        assert_int_equal(oa, ob);
    }
    assert_true(c_on[SIDX_EV_MAILBOX_HIT] > 0);
    assert_int_equal(c_off[SIDX_EV_MAILBOX_HIT], 0);
    /* every skipped test is one test fewer */
    assert_int_equal(c_on[SIDX_EV_PRIM_TEST] + c_on[SIDX_EV_MAILBOX_HIT], c_off[SIDX_EV_PRIM_TEST]);
    sidx_accel_destroy(on);
    sidx_accel_destroy(off);
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- exact event sequences ------------------------------------------------------------------- */

/* Two triangles in the plane z = y, one in x ∈ [0,1], one in x ∈ [3,4]. */
static void two_tris(sidx_mesh *m)
{
    const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 1, 3, 0, 0, 4, 0, 0, 3, 1, 1};
    const uint32_t idx[] = {0, 1, 2, 3, 4, 5};
    assert_int_equal(sidx_mesh_from_arrays(m, xyz, 6, idx, 2, NULL), SIDX_OK);
}

static void expect(const sidx_event *e, sidx_event_type t, uint32_t node)
{
    if (e->type != t || e->node != node)
        fprintf(stderr, "expected %s node %u, got %s node %u\n", sidx_event_type_name(t), node,
                sidx_event_type_name(e->type), e->node);
    assert_int_equal(e->type, t);
    assert_int_equal(e->node, node);
}

static void test_event_sequence(void **state)
{
    (void)state;
    sidx_mesh m;
    two_tris(&m);
    rec rc;
    rc.n = 0;
    const sidx_hook hook = {rec_fn, &rc, 0};
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    opt.hook = &hook;
    opt.c_trav = 1.0f;
    opt.c_tri = 4.0f;
    sidx_accel *a = build("kdtree", &m, &opt);

    /* Build.  Cell [0,4]×[0,1]×[0,1]; y and z extents of both triangles
     * equal the cell's, so the only candidates are x = 1 and x = 3 (x = 0
     * and x = 4 are the cell's faces).  Both cost 1 + 4·(SA(L)+SA(R))/SA
     * = 1 + 4·20/18; the first wins; its children hold one triangle each:
     * leaves (leaf size 1). */
    assert_int_equal(rc.n, 10);
    const sidx_event *e = rc.ev;
    expect(&e[0], SIDX_EV_BUILD_BEGIN, UINT32_MAX);
    assert_int_equal(e[0].count, 2);
    expect(&e[1], SIDX_EV_BUILD_NODE, 0);
    assert_int_equal(e[1].parent, UINT32_MAX);
    assert_int_equal(e[1].count, 2);
    assert_true(e[1].bounds.max.x == 4.0f && e[1].bounds.max.y == 1.0f);
    expect(&e[2], SIDX_EV_BUILD_CANDIDATE, 0);
    assert_int_equal(e[2].axis, 0);
    assert_true(e[2].pos == 1.0f);
    assert_int_equal(e[2].count, 1);
    assert_int_equal(e[2].aux, 1);
    assert_true(fabsf(e[2].cost - (1.0f + 4.0f * 20.0f / 18.0f)) < 1e-4f);
    expect(&e[3], SIDX_EV_BUILD_CANDIDATE, 0);
    assert_true(e[3].pos == 3.0f);
    expect(&e[4], SIDX_EV_BUILD_SPLIT, 0);
    assert_int_equal(e[4].axis, 0);
    assert_true(e[4].pos == 1.0f);
    assert_int_equal(e[4].count, 1);
    assert_int_equal(e[4].aux, 1);
    expect(&e[5], SIDX_EV_BUILD_NODE, 1);
    assert_int_equal(e[5].parent, 0);
    assert_int_equal(e[5].depth, 1);
    assert_true(e[5].bounds.max.x == 1.0f);
    expect(&e[6], SIDX_EV_BUILD_LEAF, 1);
    assert_int_equal(e[6].reason, SIDX_LEAF_FEW_PRIMS);
    assert_int_equal(e[6].count, 1);
    expect(&e[7], SIDX_EV_BUILD_NODE, 2);
    assert_true(e[7].bounds.min.x == 1.0f);
    expect(&e[8], SIDX_EV_BUILD_LEAF, 2);
    expect(&e[9], SIDX_EV_BUILD_END, 3);
    assert_int_equal(e[9].count, 2);
    assert_int_equal(e[9].depth, 1);

    /* Traversal 1: along +x at y = 0.5, z = 0.9 (parallel to both planes:
     * no hit).  Root [1, 5]; the plane x = 1 at t = 2: both children. */
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 7};
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(-1.0f, 0.5f, 0.9f), sidx_v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY),
                     SIDX_OK);
    rc.n = 0;
    sidx_hit h;
    sidx_accel_intersect(a, &r, &q, &h);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    const sidx_event_type seq1[] = {SIDX_EV_RAY_BEGIN, SIDX_EV_NODE_ENTER, SIDX_EV_STACK_PUSH, SIDX_EV_NODE_ENTER,
                                    SIDX_EV_PRIM_TEST, SIDX_EV_STACK_POP,  SIDX_EV_NODE_ENTER, SIDX_EV_PRIM_TEST,
                                    SIDX_EV_TERMINATE, SIDX_EV_RAY_END};
    const uint32_t node1[] = {UINT32_MAX, 0, 2, 1, 1, 2, 2, 2, UINT32_MAX, UINT32_MAX};
    assert_int_equal(rc.n, 10);
    for (size_t i = 0; i < 10; ++i) {
        expect(&rc.ev[i], seq1[i], node1[i]);
        assert_int_equal(rc.ev[i].ray_id, 7);
    }
    assert_true(fabsf(rc.ev[1].t_near - 1.0f) < 1e-5f && fabsf(rc.ev[1].t_far - 5.0f) < 1e-5f);
    assert_true(fabsf(rc.ev[2].t_near - 2.0f) < 1e-5f && fabsf(rc.ev[2].t_far - 5.0f) < 1e-5f);
    assert_int_equal(rc.ev[2].depth, 1); /* stack size after the push */
    assert_true(fabsf(rc.ev[3].t_near - 1.0f) < 1e-5f && fabsf(rc.ev[3].t_far - 2.0f) < 1e-5f);
    assert_int_equal(rc.ev[3].depth, 1); /* tree depth */
    assert_int_equal(rc.ev[4].prim, 0);
    assert_int_equal(rc.ev[4].result, 0);
    assert_int_equal(rc.ev[5].depth, 1); /* stack size before the pop */
    assert_int_equal(rc.ev[7].prim, 1);
    assert_int_equal(rc.ev[8].reason, SIDX_TERM_STACK_EMPTY);
    assert_int_equal(rc.ev[8].count, 3); /* nodes visited */

    /* Traversal 2: straight down (-z, so x and y components are +0) at
     * x = 3.2, y = 0.2: t_split = (1 − 3.2)·(+inf) = −inf → far child only;
     * T1 is hit at z = 0.2 (t = 4.8) inside the leaf → early exit. */
    assert_int_equal(sidx_ray_init(&r, sidx_v3(3.2f, 0.2f, 5.0f), sidx_v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY),
                     SIDX_OK);
    rc.n = 0;
    sidx_accel_intersect(a, &r, &q, &h);
    assert_int_equal(h.prim, 1);
    assert_true(fabsf(h.t - 4.8f) < 1e-5f);
    const sidx_event_type seq2[] = {SIDX_EV_RAY_BEGIN, SIDX_EV_NODE_ENTER, SIDX_EV_NODE_ENTER, SIDX_EV_PRIM_TEST,
                                    SIDX_EV_HIT_UPDATE, SIDX_EV_TERMINATE, SIDX_EV_RAY_END};
    const uint32_t node2[] = {UINT32_MAX, 0, 2, 2, 2, 2, UINT32_MAX};
    assert_int_equal(rc.n, 7);
    for (size_t i = 0; i < 7; ++i) expect(&rc.ev[i], seq2[i], node2[i]);
    assert_int_equal(rc.ev[3].prim, 1);
    assert_int_equal(rc.ev[3].result, 1);
    assert_int_equal(rc.ev[5].reason, SIDX_TERM_HIT_IN_CELL);

    /* Any-hit on the same ray ends at the first hit. */
    rc.n = 0;
    int occ = 0;
    sidx_accel_occluded(a, &r, &q, &occ);
    assert_int_equal(occ, 1);
    assert_int_equal(rc.ev[rc.n - 2].type, SIDX_EV_TERMINATE);
    assert_int_equal(rc.ev[rc.n - 2].reason, SIDX_TERM_ANY_HIT);

    /* A ray missing the scene box. */
    assert_int_equal(sidx_ray_init(&r, sidx_v3(-1.0f, 5.0f, 5.0f), sidx_v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY),
                     SIDX_OK);
    rc.n = 0;
    sidx_accel_intersect(a, &r, &q, &h);
    assert_int_equal(rc.n, 3);
    assert_int_equal(rc.ev[1].type, SIDX_EV_TERMINATE);
    assert_int_equal(rc.ev[1].reason, SIDX_TERM_MISS_ROOT);

    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* Every builder emits a well-formed build stream: nodes announced before
 * they split or become leaves, parents before children, ids = array
 * indices, every candidate on a node being decided. */
static void test_build_stream(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("icosphere", 1, &m);
    for (size_t k = 0; k < N_BUILDERS; ++k) {
        uint64_t c[SIDX_EV_COUNT];
        memset(c, 0, sizeof c);
        const sidx_hook hook = {count_fn, c, SIDX_EVMASK_BUILD};
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.hook = &hook;
        sidx_accel *a = build(builders[k], &m, &opt);
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        assert_int_equal(c[SIDX_EV_BUILD_BEGIN], 1);
        assert_int_equal(c[SIDX_EV_BUILD_END], 1);
        assert_int_equal(c[SIDX_EV_BUILD_NODE], st.nodes);
        assert_int_equal(c[SIDX_EV_BUILD_LEAF], st.leaves);
        assert_int_equal(c[SIDX_EV_BUILD_SPLIT], st.nodes - st.leaves);
        assert_true(c[SIDX_EV_BUILD_CANDIDATE] >= c[SIDX_EV_BUILD_SPLIT]);
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

/* ---- the public view (sidx/kdtree.h) ------------------------------------------------------------ */

/* sidx_kdtree_nodes / _refs hand out the tree's own arrays, and the words
 * decode to exactly the splits and leaves the build events reported. */
static void test_public_view(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("teapot", 0, &m);
    for (size_t k = 0; k < N_BUILDERS; ++k) {
        sidx_recorder rec;
        sidx_recorder_init(&rec);
        const sidx_hook hook = sidx_recorder_hook(&rec);
        sidx_build_options opt;
        memset(&opt, 0, sizeof opt);
        opt.hook = &hook;
        sidx_accel *a = build(builders[k], &m, &opt);
        assert_false(rec.overflow);
        const sidx_kd_node *nodes = NULL;
        const uint32_t *refs = NULL;
        uint32_t nn = 0, nr = 0;
        sidx_error err;
        assert_int_equal(sidx_kdtree_nodes(a, &nodes, &nn, &err), SIDX_OK);
        assert_int_equal(sidx_kdtree_refs(a, &refs, &nr, &err), SIDX_OK);
        /* the real memory, not a copy */
        assert_ptr_equal(nodes, tree_of(a)->nodes);
        assert_ptr_equal(refs, tree_of(a)->prims);
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        assert_int_equal(nn, st.nodes);
        assert_int_equal(nr, st.prim_refs);
        assert_true(nn > 1);

        uint32_t *parent = malloc(nn * sizeof *parent);
        assert_non_null(parent);
        for (uint32_t i = 0; i < nn; ++i) parent[i] = UINT32_MAX - 1u;
        uint32_t splits = 0, leaves = 0, refs_seen = 0;
        for (size_t i = 0; i < rec.count; ++i) {
            const sidx_event *e = &rec.events[i];
            if (e->type == SIDX_EV_BUILD_NODE) {
                assert_true(e->node < nn);
                parent[e->node] = e->parent;
            } else if (e->type == SIDX_EV_BUILD_SPLIT) {
                assert_true(e->node < nn);
                const sidx_kd_node *n = &nodes[e->node];
                assert_int_equal(n->bits & 3u, (uint32_t)e->axis);
                assert_true(n->u.split == e->pos);
                ++splits;
            } else if (e->type == SIDX_EV_BUILD_LEAF) {
                assert_true(e->node < nn);
                const sidx_kd_node *n = &nodes[e->node];
                assert_int_equal(n->bits & 3u, SIDX_KD_LEAF);
                assert_int_equal(n->u.count, e->count);
                const uint32_t off = n->bits >> 2;
                assert_true(off + n->u.count <= nr);
                if (n->u.count == 0) assert_int_equal(off, 0);
                for (uint32_t j = 0; j < n->u.count; ++j) {
                    assert_true(refs[off + j] < m.num_triangles);
                    if (e->prims) assert_int_equal(refs[off + j], e->prims[j]);
                }
                refs_seen += n->u.count;
                ++leaves;
            }
        }
        assert_int_equal(splits + leaves, nn);
        assert_int_equal(refs_seen, nr);
        /* every inner node's children, decoded from its word, are the
         * nodes the build reported as its children */
        assert_int_equal(parent[0], UINT32_MAX);
        for (uint32_t i = 0; i < nn; ++i) {
            if ((nodes[i].bits & 3u) == SIDX_KD_LEAF) continue;
            const uint32_t c = nodes[i].bits >> 2;
            assert_true(c + 1u < nn);
            assert_int_equal(parent[c], i);
            assert_int_equal(parent[c + 1u], i);
        }
        free(parent);
        sidx_recorder_free(&rec);
        sidx_accel_destroy(a);
    }

    /* errors: NULL arguments, and a structure that is not a kd-tree */
    sidx_accel *kd = build("kdtree", &m, NULL);
    sidx_accel *bvh = build("bvh", &m, NULL);
    const sidx_kd_node *nodes = (const sidx_kd_node *)&m; /* sentinels: must stay untouched */
    const uint32_t *refs = (const uint32_t *)&m;
    uint32_t count = 12345u;
    sidx_error err;
    memset(&err, 0, sizeof err);
    assert_int_equal(sidx_kdtree_nodes(bvh, &nodes, &count, &err), SIDX_ERR_INVALID_ARG);
    assert_int_equal(err.status, SIDX_ERR_INVALID_ARG);
    assert_non_null(strstr(err.message, "not a kd-tree"));
    assert_int_equal(sidx_kdtree_refs(bvh, &refs, &count, &err), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_kdtree_nodes(NULL, &nodes, &count, &err), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_kdtree_nodes(kd, NULL, &count, &err), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_kdtree_nodes(kd, &nodes, NULL, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_kdtree_refs(kd, NULL, &count, NULL), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_kdtree_refs(kd, &refs, NULL, &err), SIDX_ERR_INVALID_ARG);
    assert_ptr_equal(nodes, (const sidx_kd_node *)&m);
    assert_ptr_equal(refs, (const uint32_t *)&m);
    assert_int_equal(count, 12345u);
    sidx_accel_destroy(kd);
    sidx_accel_destroy(bvh);
    sidx_mesh_free(&m);
}

/* ---- the slide walk and the fast walk give the same hits ------------------------------------------ */

/* A hook that only counts NODE_ENTER events on empty leaves, so that the
 * test can show the slide walk took the path the fast walk skips. */
typedef struct slide_count {
    const kd_tree *kd;
    uint64_t events, empty_leaf_enters;
} slide_count;

static void slide_fn(const sidx_event *e, void *user)
{
    slide_count *c = user;
    c->events++;
    if (e->type == SIDX_EV_NODE_ENTER && kd_is_empty(&c->kd->nodes[e->node])) c->empty_leaf_enters++;
}

/* Same prim, t, u, v and normal, bit for bit — except the sign of a zero
 * t (a ray starting on the triangle): the SSE kernel reports +0 where the
 * scalar test reports −0 (simd_tri4_sse.h), which is not the walks'. */
static int same_bits(const sidx_hit *x, const sidx_hit *y)
{
    const int same_t = memcmp(&x->t, &y->t, sizeof x->t) == 0 || (x->t == 0.0f && y->t == 0.0f);
    return x->prim == y->prim && same_t && memcmp(&x->u, &y->u, sizeof x->u) == 0 &&
           memcmp(&x->v, &y->v, sizeof x->v) == 0 && memcmp(&x->ng, &y->ng, sizeof x->ng) == 0;
}

/* One ray: traced (slide walk) against untraced (fast walk) for the
 * closest hit — t, prim, u, v and normal bit for bit — and for any-hit;
 * the naive traversal traced against untraced too.  Returns 1 if all agree. */
static int walks_agree(const sidx_accel *a, const sidx_ray *r, const sidx_hook *hook, const char *what, size_t i)
{
    const uint32_t flags = SIDX_QUERY_UV | SIDX_QUERY_NORMAL;
    for (int naive = 0; naive < 2; ++naive) {
        const sidx_traversal trav = naive ? SIDX_TRAVERSE_NAIVE : SIDX_TRAVERSE_DEFAULT;
        const sidx_query q_fast = {flags, trav, NULL, 0}, q_slide = {flags, trav, hook, 0};
        for (int with_attrs = 0; with_attrs < 2; ++with_attrs) {
            sidx_query qf = q_fast, qs = q_slide;
            if (!with_attrs) qf.flags = qs.flags = 0;
            sidx_hit hf, hs;
            assert_int_equal(sidx_accel_intersect(a, r, &qf, &hf), SIDX_OK);
            assert_int_equal(sidx_accel_intersect(a, r, &qs, &hs), SIDX_OK);
            if (!same_bits(&hf, &hs)) {
                fprintf(stderr,
                        "%s (%s), %s ray %zu: o=(%a %a %a) d=(%a %a %a) untraced prim %u t %a, traced prim %u t %a\n",
                        sidx_accel_name(a), sidx_traversal_name(trav), what, i, (double)r->org.x, (double)r->org.y,
                        (double)r->org.z, (double)r->dir.x, (double)r->dir.y, (double)r->dir.z, hf.prim, (double)hf.t,
                        hs.prim, (double)hs.t);
                return 0;
            }
        }
    }
    int occ_fast = -1, occ_slide = -2;
    const sidx_query q_slide = {0, SIDX_TRAVERSE_DEFAULT, hook, 0};
    assert_int_equal(sidx_accel_occluded(a, r, NULL, &occ_fast), SIDX_OK);
    assert_int_equal(sidx_accel_occluded(a, r, &q_slide, &occ_slide), SIDX_OK);
    if (occ_fast != occ_slide) {
        fprintf(stderr, "%s any-hit, %s ray %zu: untraced %d, traced %d\n", sidx_accel_name(a), what, i, occ_fast,
                occ_slide);
        return 0;
    }
    return 1;
}

/* Awkward rays from the tree itself: origins exactly on split planes
 * (directions in the plane with d[axis] = ±0, axis-parallel along another
 * axis, general), and axis-parallel rays along the split axis from outside
 * the box through a mesh vertex (SAH planes sit at vertex coordinates). */
static size_t split_plane_rays(const sidx_mesh *m, const kd_tree *kd, tk_rng *rng, size_t max, tk_rayrec *out)
{
    size_t n = 0;
    const sidx_aabb bb = kd->bounds;
    const uint32_t stride = 1u + kd->num_nodes / 97u;
    for (uint32_t i = 0; i < kd->num_nodes && n + 8 <= max; i += stride) {
        const kd_node *node = &kd->nodes[i];
        if (kd_is_leaf(node)) continue;
        const int ax = (int)kd_axis(node);
        for (int rep = 0; rep < 8; ++rep) {
            float o[3], d[3];
            for (int c = 0; c < 3; ++c) o[c] = (float)tk_rng_range(rng, sidx_v3_get(bb.min, c), sidx_v3_get(bb.max, c));
            const sidx_vec3 u = tk_rng_sphere(rng);
            d[0] = u.x;
            d[1] = u.y;
            d[2] = u.z;
            if (rep < 6) o[ax] = node->u.split; /* on the plane */
            if (rep < 2) {
                d[ax] = rep ? -0.0f : 0.0f; /* inside it */
            } else if (rep < 4 || rep >= 6) {
                const int keep = rep >= 6 ? ax : (ax + 1 + (rep & 1)) % 3;
                for (int c = 0; c < 3; ++c) d[c] = (rep & 1) ? -0.0f : 0.0f;
                d[keep] = (rep & 1) ? -1.0f : 1.0f;
                if (rep >= 6) {
                    const sidx_vec3 v = m->positions[tk_rng_below(rng, m->num_vertices)];
                    o[0] = v.x;
                    o[1] = v.y;
                    o[2] = v.z;
                    o[ax] = (rep & 1) ? sidx_v3_get(bb.max, ax) + 1.0f : sidx_v3_get(bb.min, ax) - 1.0f;
                }
            }
            out[n++] = tk_rayrec_make(sidx_v3(o[0], o[1], o[2]), sidx_v3(d[0], d[1], d[2]), 0.0f, INFINITY);
        }
    }
    return n;
}

static void test_slide_walk_equals_fast_walk(void **state)
{
    (void)state;
    const char *const sc[] = {"flat2d", "cornell", "menger", "teapot", "stadium", "icosphere"};
    const uint32_t detail[] = {0, 0, 1, 0, 0, 0};
    const size_t per_kind = tk_tiny_tests() ? 16 : tk_fast_tests() ? 60 : 200;
    const size_t max_split = tk_tiny_tests() ? 200 : 800, leak_rays = tk_tiny_tests() ? 1500 : 6000;
    tk_rayrec *rays = malloc((per_kind * TK_RAYS_KIND_COUNT + max_split + leak_rays) * sizeof *rays);
    assert_non_null(rays);
    uint64_t empty_enters = 0, checked = 0;
    for (size_t s = 0; s < sizeof sc / sizeof sc[0]; ++s) {
        sidx_mesh m;
        make_scene(sc[s], detail[s], &m);
        for (size_t k = 0; k < N_BUILDERS + 2; ++k) {
            /* every builder with its defaults; then the SAH tree without
             * the mailbox, and with Möller–Trumbore (scalar leaves in both walks);
             * at the smallest sizes (valgrind) each on every other scene */
            if (tk_tiny_tests() && (s + k) % 2 != 0) continue;
            sidx_build_options opt;
            memset(&opt, 0, sizeof opt);
            opt.no_mailbox = k == N_BUILDERS;
            opt.tri = k == N_BUILDERS + 1 ? SIDX_TRI_MOLLER_TRUMBORE : SIDX_TRI_WATERTIGHT;
            sidx_accel *a = build(k < N_BUILDERS ? builders[k] : "kdtree", &m, &opt);
            const kd_tree *kd = tree_of(a);
            size_t n = 0;
            for (int kind = 0; kind < TK_RAYS_KIND_COUNT; ++kind, n += per_kind)
                tk_make_rays(&m, (tk_ray_kind)kind, per_kind, 31 + s * 7 + k * 101 + (uint64_t)kind, rays + n);
            tk_rng rng;
            tk_rng_seed(&rng, 77 + s + 13 * k);
            n += split_plane_rays(&m, kd, &rng, max_split, rays + n);
            if (!strcmp(sc[s], "icosphere")) n += tk_make_leak_rays(&m, sidx_v3(0.1f, -0.2f, 0.3f), leak_rays, rays + n);
            slide_count cnt = {kd, 0, 0};
            const sidx_hook hook = {slide_fn, &cnt, 0};
            for (size_t i = 0; i < n; ++i) {
                sidx_ray r;
                if (tk_ray_from(&rays[i], &r) != SIDX_OK) continue;
                if (!walks_agree(a, &r, &hook, sc[s], i)) fail();
                ++checked;
            }
            assert_true(cnt.events > 0);
            empty_enters += cnt.empty_leaf_enters;
            sidx_accel_destroy(a);
        }
        sidx_mesh_free(&m);
    }
    assert_true(checked > (tk_tiny_tests() ? 2000u : 10000u));
    assert_true(empty_enters > 0); /* the slide walk's own path was taken */
    free(rays);
}

/* ---- a trace reports the test behind each hit ------------------------------------------------- */

/* Per ray: the (prim, t) pairs of the PRIM_TEST hits and the prims tested
 * so far.  A HIT_UPDATE must repeat a PRIM_TEST hit (same prim, same t
 * bits) reported before it, and a MAILBOX_HIT name a prim tested before:
 * a trace never shows a closest hit no test produced. */
typedef struct test_trail {
    uint32_t prim[512];
    float t[512];
    int hit[512];
    size_t n;
    unsigned orphans, updates;
} test_trail;

static void trail_fn(const sidx_event *e, void *user)
{
    test_trail *tr = user;
    if (e->type == SIDX_EV_RAY_BEGIN) tr->n = 0;
    if (e->type == SIDX_EV_PRIM_TEST && tr->n < 512) {
        tr->prim[tr->n] = e->prim;
        tr->t[tr->n] = e->t;
        tr->hit[tr->n++] = e->result == 1;
    }
    if (e->type == SIDX_EV_HIT_UPDATE || e->type == SIDX_EV_MAILBOX_HIT) {
        int found = 0;
        for (size_t i = 0; i < tr->n && !found; ++i)
            found = tr->prim[i] == e->prim &&
                    (e->type == SIDX_EV_MAILBOX_HIT || (tr->hit[i] && memcmp(&tr->t[i], &e->t, sizeof e->t) == 0));
        tr->orphans += !found;
        tr->updates += e->type == SIDX_EV_HIT_UPDATE;
    }
}

static void test_trace_shows_each_hit_test(void **state)
{
    (void)state;
    const char *const sc[] = {"kd-slide", "flat2d", "teapot"};
    const size_t per_kind = tk_tiny_tests() ? 20 : tk_fast_tests() ? 80 : 300;
    tk_rayrec *rays = malloc(per_kind * 3 * sizeof *rays);
    assert_non_null(rays);
    for (size_t s = 0; s < sizeof sc / sizeof sc[0]; ++s) {
        sidx_mesh m;
        make_scene(sc[s], 0, &m);
        for (int kind = 0; kind < 3; ++kind) /* primary, diffuse, shadow */
            tk_make_rays(&m, (tk_ray_kind)kind, per_kind, 501 + s + (uint64_t)kind, rays + (size_t)kind * per_kind);
        for (size_t k = 0; k < N_BUILDERS; ++k) {
            sidx_accel *a = NULL;
            assert_int_equal(sidx_scene_accel_build(sc[s], builders[k], &m, NULL, &a, NULL), SIDX_OK);
            test_trail tr;
            memset(&tr, 0, sizeof tr);
            const sidx_hook hook = {trail_fn, &tr, 0};
            sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
            for (size_t i = 0; i < per_kind * 3; ++i) {
                sidx_ray r;
                if (tk_ray_from(&rays[i], &r) != SIDX_OK) continue;
                sidx_hit h = sidx_hit_none();
                assert_int_equal(sidx_accel_intersect(a, &r, &q, &h), SIDX_OK);
            }
            if (tr.orphans) print_message("%s on %s: %u of %u closest-hit updates without their test\n", builders[k],
                                          sc[s], tr.orphans, tr.updates);
            assert_int_equal(tr.orphans, 0);
            assert_true(tr.updates > 0);
            sidx_accel_destroy(a);
        }
        sidx_mesh_free(&m);
    }
    free(rays);
}

/* ---- allocation failures ------------------------------------------------------------------------ */

typedef struct fail_alloc {
    int budget; /* allocations left before failing; < 0 = never fail */
    int live;
} fail_alloc;

static void *fa_alloc(size_t size, void *user)
{
    fail_alloc *f = user;
    if (f->budget == 0) return NULL;
    if (f->budget > 0) f->budget--;
    void *p = malloc(size);
    if (p) f->live++;
    return p;
}
static void fa_free(void *p, void *user)
{
    fail_alloc *f = user;
    if (p) f->live--;
    free(p);
}

static void test_alloc_failures(void **state)
{
    (void)state;
    sidx_mesh m;
    make_scene("icosphere", 1, &m);
    for (size_t k = 0; k < N_BUILDERS; ++k) {
        int ok = 0;
        for (int budget = 0; budget < 100000 && !ok; budget += budget < 64 ? 1 : 17) {
            fail_alloc f = {budget, 0};
            const sidx_allocator al = {fa_alloc, fa_free, &f};
            sidx_build_options opt;
            memset(&opt, 0, sizeof opt);
            opt.alloc = &al;
            sidx_accel *a = NULL;
            sidx_error err;
            const sidx_status s = sidx_accel_build(builders[k], &m, &opt, &a, &err);
            if (s == SIDX_OK) {
                ok = 1;
                assert_non_null(a);
                sidx_accel_destroy(a);
            } else {
                assert_int_equal(s, SIDX_ERR_NOMEM);
                assert_null(a);
            }
            assert_int_equal(f.live, 0);
        }
        assert_true(ok);
    }
    sidx_mesh_free(&m);
}

/* An empty mesh builds and misses. */
static void test_empty_mesh(void **state)
{
    (void)state;
    sidx_mesh m;
    memset(&m, 0, sizeof m);
    for (size_t k = 0; k < N_BUILDERS; ++k) {
        sidx_accel *a = build(builders[k], &m, NULL);
        sidx_ray r;
        assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0, 0), sidx_v3(1, 0, 0), 0.0f, INFINITY), SIDX_OK);
        sidx_hit h;
        sidx_accel_intersect(a, &r, NULL, &h);
        assert_int_equal(h.prim, SIDX_NO_HIT);
        int occ = 1;
        sidx_accel_occluded(a, &r, NULL, &occ);
        assert_int_equal(occ, 0);
        sidx_accel_destroy(a);
    }
}

/* sidx_kdtree_build_from_splits: the kd-slide tree node by node, its
 * labels, leaves with reason "given", and the lists it refuses. */
static void build_events_leaf_reasons(const sidx_event *ev, void *user)
{
    if (ev->type == SIDX_EV_BUILD_LEAF) {
        int *given = user;
        if (ev->reason == SIDX_LEAF_GIVEN) ++*given;
    }
}

static void test_build_from_splits(void **state)
{
    (void)state;
    sidx_mesh m;
    sidx_error err;
    assert_int_equal(sidx_scene_make("kd-slide", 0, &m, &err), SIDX_OK);
    assert_int_equal(m.num_triangles, 8);
    int given = 0;
    sidx_hook h = {build_events_leaf_reasons, &given, 0};
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.hook = &h;
    sidx_accel *a = NULL;
    assert_int_equal(sidx_scene_accel_build("kd-slide", "kdtree", &m, &bo, &a, &err), SIDX_OK);
    assert_string_equal(sidx_accel_name(a), "kdtree");
    assert_int_equal(given, 5);
    const sidx_kd_node *nodes;
    uint32_t count;
    assert_int_equal(sidx_kdtree_nodes(a, &nodes, &count, &err), SIDX_OK);
    assert_int_equal(count, 9);
    /* node ids: depth first with sibling pairs (A 0; B, C 1, 2; L1, L2 3, 4; D, L3 5, 6; L4, L5 7, 8) */
    static const char *const names[9] = {"A", "B", "C", "L1", "L2", "D", "L3", "L4", "L5"};
    for (uint32_t i = 0; i < 9; ++i) assert_string_equal(sidx_accel_node_label(a, i), names[i]);
    assert_int_equal(nodes[0].bits & 3u, 0);
    assert_true(nodes[0].u.split == 4.0f);
    assert_int_equal(nodes[5].bits & 3u, 1);
    assert_true(nodes[5].u.split == 5.0f);
    /* the same hit as brute force on the slide's ray and a few others */
    sidx_accel *b = NULL;
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &b, &err), SIDX_OK);
    for (int k = 0; k < 40; ++k) {
        sidx_ray r;
        sidx_ray_init(&r, sidx_v3(0.0f, 0.5f + 0.18f * (float)k, 0.0f), sidx_v3(1.0f, 0.15f - 0.01f * (float)k, 0.0f),
                      0.0f, INFINITY);
        sidx_hit ha, hb;
        sidx_accel_intersect(a, &r, NULL, &ha);
        sidx_accel_intersect(b, &r, NULL, &hb);
        assert_int_equal(ha.prim, hb.prim);
        if (ha.prim != SIDX_NO_HIT) assert_true(ha.t == hb.t);
    }
    sidx_accel_destroy(b);
    sidx_accel_destroy(a);
    /* any other structure, or another scene, is sidx_accel_build's */
    assert_int_equal(sidx_scene_accel_build("kd-slide", "kdtree-binned", &m, NULL, &a, &err), SIDX_OK);
    assert_null(sidx_accel_node_label(a, 0));
    sidx_accel_destroy(a);

    /* refused lists */
    const sidx_kd_split leaf = {SIDX_KD_LEAF, 0.0f, NULL};
    const sidx_kd_split short_list[] = {{0, 4.0f, "A"}, leaf};
    const sidx_kd_split long_list[] = {leaf, leaf};
    const sidx_kd_split bad_axis[] = {{5, 4.0f, NULL}, leaf, leaf};
    const sidx_kd_split outside[] = {{0, 12.0f, NULL}, leaf, leaf};
    const sidx_kd_split long_label[] = {{SIDX_KD_LEAF, 0.0f, "a label far longer than thirty-one bytes"}};
    const struct { const sidx_kd_split *s; uint32_t n; } bad[] = {
        {short_list, 2}, {long_list, 2}, {bad_axis, 3}, {outside, 3}, {long_label, 1}, {short_list, 0},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        a = (sidx_accel *)&m; /* must come back NULL */
        assert_int_equal(sidx_kdtree_build_from_splits(&m, bad[i].s, bad[i].n, NULL, &a, &err), SIDX_ERR_INVALID_ARG);
        assert_null(a);
        assert_true(err.message[0] != '\0');
    }
    /* one leaf is a whole tree */
    assert_int_equal(sidx_kdtree_build_from_splits(&m, &leaf, 1, NULL, &a, &err), SIDX_OK);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* sidx_accel_set_node_label / sidx_accel_node_label: copies, removal, bad ids. */
static void test_node_labels(void **state)
{
    (void)state;
    sidx_mesh m;
    sidx_error err;
    assert_int_equal(sidx_scene_make("icosphere", 1, &m, &err), SIDX_OK);
    sidx_accel *a = NULL;
    assert_int_equal(sidx_accel_build("kdtree", &m, NULL, &a, &err), SIDX_OK);
    sidx_accel_stats st;
    sidx_accel_stats_get(a, &st);
    assert_true(st.nodes > 3);
    char text[8] = "first";
    assert_int_equal(sidx_accel_set_node_label(a, 2, text, &err), SIDX_OK);
    assert_int_equal(sidx_accel_set_node_label(a, 0, "root", &err), SIDX_OK);
    assert_int_equal(sidx_accel_set_node_label(a, st.nodes - 1, "last", &err), SIDX_OK);
    text[0] = 'F'; /* the structure keeps its own copy */
    assert_string_equal(sidx_accel_node_label(a, 2), "first");
    assert_string_equal(sidx_accel_node_label(a, 0), "root");
    assert_string_equal(sidx_accel_node_label(a, st.nodes - 1), "last");
    assert_null(sidx_accel_node_label(a, 1));
    assert_int_equal(sidx_accel_set_node_label(a, 2, "again", &err), SIDX_OK);
    assert_string_equal(sidx_accel_node_label(a, 2), "again");
    assert_int_equal(sidx_accel_set_node_label(a, 2, NULL, &err), SIDX_OK);
    assert_null(sidx_accel_node_label(a, 2));
    assert_string_equal(sidx_accel_node_label(a, 0), "root");
    assert_int_equal(sidx_accel_set_node_label(a, st.nodes, "out", &err), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_accel_set_node_label(a, 1, "a label far longer than thirty-one bytes", &err),
                     SIDX_ERR_INVALID_ARG);
    assert_null(sidx_accel_node_label(a, 1));
    assert_int_equal(sidx_accel_set_node_label(NULL, 0, "x", &err), SIDX_ERR_INVALID_ARG);
    assert_null(sidx_accel_node_label(NULL, 0));
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_node_layout),
        cmocka_unit_test(test_event_sequence),
        cmocka_unit_test(test_build_stream),
        cmocka_unit_test(test_public_view),
        cmocka_unit_test(test_cannot_terminate),
        cmocka_unit_test(test_ray_inside_split_plane),
        cmocka_unit_test(test_stack_events_say_why),
        cmocka_unit_test(test_zero_dirs_and_origin_on_split),
        cmocka_unit_test(test_against_brute),
        cmocka_unit_test(test_against_brute_options),
        cmocka_unit_test(test_no_leaks_icosphere),
        cmocka_unit_test(test_stadium_isolates_teapot),
        cmocka_unit_test(test_menger),
        cmocka_unit_test(test_mailbox),
        cmocka_unit_test(test_slide_walk_equals_fast_walk),
        cmocka_unit_test(test_trace_shows_each_hit_test),
        cmocka_unit_test(test_alloc_failures),
        cmocka_unit_test(test_empty_mesh),
        cmocka_unit_test(test_build_from_splits),
        cmocka_unit_test(test_node_labels),
    };
    /* KD_TEST=pattern runs only the matching tests (cmocka's filter) */
    if (getenv("KD_TEST")) cmocka_set_test_filter(getenv("KD_TEST"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
