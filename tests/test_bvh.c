/* test_bvh.c — the BVH: five builders, three traversals, refit, OBBs.
 *
 * What the registry-wide suite cannot know about the BVH:
 *  - every builder × traversal returns brute force's closest hit (same
 *    primitive, or the same t within 1e-5 relative on coincident surfaces)
 *    and agrees on any-hit, traced and untraced alike;
 *  - no leaks: rays from inside a closed icosphere aimed exactly at its
 *    vertices and edge midpoints all hit;
 *  - the flattened tree is well formed (each primitive in exactly one leaf,
 *    children inside parents, pre-order layout, bounded depth);
 *  - degenerate input (all centroids equal) builds and terminates;
 *  - refit after moving vertices answers like a rebuild;
 *  - the exact event sequence of a two-triangle scene;
 *  - allocation failures at every step leak nothing.
 * Includes the BVH's private header to walk the node array. */
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
#include "bvh_internal.h"

static const char *const builders[] = {"bvh",        "bvh-sweep", "bvh-everyb", "bvh-median",
                                       "bvh-middle", "bvh-obb",   "bvh-sbvh"};
#define NBUILDERS (sizeof builders / sizeof builders[0])
static const char *const scenes[] = {"icosphere", "teapot", "soup", "menger", "stadium", "cornell"};
#define NSCENES (sizeof scenes / sizeof scenes[0])

/* ---- small helpers --------------------------------------------------------- */

static uint64_t rng_state;
static void rng_seed(uint64_t s) { rng_state = s * 0x9E3779B97F4A7C15ull + 1; }
static float rng_unit(void) /* xorshift64*, [0, 1) */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (float)((rng_state * 0x2545F4914F6CDD1Dull) >> 40) / 16777216.0f;
}

static sidx_mesh scene(const char *name)
{
    sidx_mesh m;
    sidx_error err;
    if (sidx_scene_make(name, 0, &m, &err) != SIDX_OK) fail_msg("scene %s: %s", name, err.message);
    return m;
}

static sidx_accel *build(const char *name, const sidx_mesh *m, const sidx_build_options *opt)
{
    sidx_accel *a = NULL;
    sidx_error err;
    if (sidx_accel_build(name, m, opt, &a, &err) != SIDX_OK) fail_msg("build %s: %s", name, err.message);
    return a;
}

/* Random rays: half from anywhere around the scene in random directions,
 * half aimed at a random point of a random triangle so most of them hit. */
static void make_rays(const sidx_mesh *m, sidx_ray *rays, int n, uint64_t seed)
{
    rng_seed(seed);
    const sidx_aabb b = sidx_mesh_bounds(m);
    const sidx_vec3 c = sidx_aabb_centroid(b), e = sidx_aabb_extent(b);
    for (int i = 0; i < n; ++i) {
        /* One draw per statement, z first: C leaves the order of a call's
         * arguments open, and this is the order gcc drew them in. */
        const float oz = rng_unit(), oy = rng_unit(), ox = rng_unit();
        const sidx_vec3 o = sidx_v3(c.x + e.x * 1.4f * (ox - 0.5f), c.y + e.y * 1.4f * (oy - 0.5f),
                                    c.z + e.z * 1.4f * (oz - 0.5f));
        const float dz = rng_unit(), dy = rng_unit(), dx = rng_unit();
        sidx_vec3 d = sidx_v3(dx - 0.5f, dy - 0.5f, dz - 0.5f);
        if (i % 2 && m->num_triangles) {
            const uint32_t t = (uint32_t)(rng_unit() * (float)m->num_triangles) % m->num_triangles;
            float u = rng_unit(), v = rng_unit();
            if (u + v > 1.0f) { u = 1.0f - u; v = 1.0f - v; }
            const sidx_vec3 p0 = sidx_mesh_vertex(m, t, 0), p1 = sidx_mesh_vertex(m, t, 1),
                            p2 = sidx_mesh_vertex(m, t, 2);
            const sidx_vec3 p = sidx_v3_add(p0, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(p1, p0), u),
                                                            sidx_v3_scale(sidx_v3_sub(p2, p0), v)));
            d = sidx_v3_sub(p, o);
        }
        if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) d = sidx_v3(0.0f, 0.0f, 1.0f);
        assert_int_equal(sidx_ray_init(&rays[i], o, d, 0.0f, INFINITY), SIDX_OK);
    }
}

/* The suites' comparison rule. */
static int hits_agree(const sidx_hit *h, const sidx_hit *ref)
{
    if (h->prim == SIDX_NO_HIT || ref->prim == SIDX_NO_HIT) return h->prim == ref->prim;
    if (h->prim == ref->prim) return h->t == ref->t;
    const float scale = fabsf(ref->t) > 1.0f ? fabsf(ref->t) : 1.0f;
    return fabsf(h->t - ref->t) <= 1e-5f * scale;
}

/* A hook that only counts, to force the traced instantiation. */
static void count_fn(const sidx_event *ev, void *user)
{
    (void)ev;
    ++*(uint64_t *)user;
}

/* ---- every builder × traversal against brute force ---------------------------- */

#define RAYS_PER_SCENE 160

static void check_against_brute(const sidx_mesh *m, const char *scene_name, const sidx_build_options *opt)
{
    sidx_ray rays[RAYS_PER_SCENE];
    sidx_hit ref[RAYS_PER_SCENE];
    int ref_occ[RAYS_PER_SCENE];
    make_rays(m, rays, RAYS_PER_SCENE, 7);
    sidx_accel *brute = build("brute", m, opt);
    for (int i = 0; i < RAYS_PER_SCENE; ++i) {
        assert_int_equal(sidx_accel_intersect(brute, &rays[i], NULL, &ref[i]), SIDX_OK);
        assert_int_equal(sidx_accel_occluded(brute, &rays[i], NULL, &ref_occ[i]), SIDX_OK);
    }
    sidx_accel_destroy(brute);
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        sidx_accel *a = build(builders[bi], m, opt);
        for (int tr = 0; tr < SIDX_TRAVERSE_COUNT; ++tr) {
            uint64_t events = 0;
            const sidx_hook hook = {count_fn, &events, 0};
            const sidx_query plain = {0, (sidx_traversal)tr, NULL, 0};
            const sidx_query traced = {0, (sidx_traversal)tr, &hook, 0};
            for (int i = 0; i < RAYS_PER_SCENE; ++i) {
                sidx_hit h, ht;
                int occ, occt;
                sidx_accel_intersect(a, &rays[i], &plain, &h);
                sidx_accel_intersect(a, &rays[i], &traced, &ht);
                sidx_accel_occluded(a, &rays[i], &plain, &occ);
                sidx_accel_occluded(a, &rays[i], &traced, &occt);
                if (!hits_agree(&h, &ref[i]))
                    fail_msg("%s/%s/%s ray %d: prim %u t %.9g, brute prim %u t %.9g", scene_name, builders[bi],
                             sidx_traversal_name((sidx_traversal)tr), i, h.prim, (double)h.t, ref[i].prim,
                             (double)ref[i].t);
                /* traced and untraced are the same code: identical answers */
                assert_int_equal(h.prim, ht.prim);
                assert_true(h.t == ht.t || (isinf(h.t) && isinf(ht.t)));
                assert_int_equal(occ, ref_occ[i]);
                assert_int_equal(occt, occ);
                assert_int_equal(occ, ref[i].prim != SIDX_NO_HIT); /* tmax = inf: any hit iff closest hit */
            }
            assert_true(events > 0);
        }
        sidx_accel_destroy(a);
    }
}

static void test_builders_match_brute(void **state)
{
    (void)state;
    for (size_t s = 0; s < NSCENES; ++s) {
        sidx_mesh m = scene(scenes[s]);
        check_against_brute(&m, scenes[s], NULL);
        sidx_mesh_free(&m);
    }
}

/* The other tests and box methods, other SAH constants and leaf sizes. */
static void test_options_match_brute(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.box = SIDX_BOX_PLAIN;
    o.tri = SIDX_TRI_MOLLER_TRUMBORE;
    check_against_brute(&m, "teapot(plain,moller)", &o);
    memset(&o, 0, sizeof o);
    o.tri = SIDX_TRI_TWO_STEP;
    o.c_trav = 4.0f;
    o.leaf_size = 1;
    o.bins = 4;
    o.every_b = 3;
    o.max_depth = 6;
    check_against_brute(&m, "teapot(twostep,ctrav4,leaf1,bins4,b3,depth6)", &o);
    sidx_mesh_free(&m);
}

/* Far from the origin and at tiny and huge scales: float spacing grows
 * with magnitude, so the slab tests and the OBB padding must cope. */
static void test_translated_and_scaled(void **state)
{
    (void)state;
    const float shift[][4] = {{1e6f, -2e5f, 3e4f, 1.0f}, {0.0f, 0.0f, 0.0f, 1e-4f}, {-5e3f, 0.0f, 0.0f, 1e4f}};
    for (size_t k = 0; k < sizeof shift / sizeof shift[0]; ++k) {
        sidx_mesh m = scene("teapot");
        for (uint32_t v = 0; v < m.num_vertices; ++v) {
            const sidx_vec3 p = m.positions[v];
            m.positions[v] = sidx_v3(p.x * shift[k][3] + shift[k][0], p.y * shift[k][3] + shift[k][1],
                                     p.z * shift[k][3] + shift[k][2]);
        }
        check_against_brute(&m, "teapot(moved)", NULL);
        sidx_mesh_free(&m);
    }
}

/* ---- zero leaks ---------------------------------------------------------------- */

static void test_no_leaks_icosphere(void **state)
{
    (void)state;
    sidx_mesh m = scene("icosphere");
    const sidx_aabb bb = sidx_mesh_bounds(&m);
    /* Slightly off the centre so no ray is special by symmetry. */
    const sidx_vec3 e = sidx_aabb_extent(bb);
    const sidx_vec3 in = sidx_v3_add(sidx_aabb_centroid(bb), sidx_v3(0.0123f * e.x, -0.0071f * e.y, 0.0031f * e.z));
    const uint32_t nt = m.num_triangles;
    sidx_ray *rays = malloc(sizeof *rays * (size_t)nt * 6u);
    assert_non_null(rays);
    size_t n = 0;
    for (uint32_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            const sidx_vec3 p = sidx_mesh_vertex(&m, t, k), q = sidx_mesh_vertex(&m, t, (k + 1) % 3);
            const sidx_vec3 mid = sidx_v3_scale(sidx_v3_add(p, q), 0.5f);
            assert_int_equal(sidx_ray_init(&rays[n++], in, sidx_v3_sub(p, in), 0.0f, INFINITY), SIDX_OK);
            assert_int_equal(sidx_ray_init(&rays[n++], in, sidx_v3_sub(mid, in), 0.0f, INFINITY), SIDX_OK);
        }
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        for (int box = 0; box < SIDX_BOX_METHOD_COUNT; ++box) {
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.box = (sidx_box_method)box;
            sidx_accel *a = build(builders[bi], &m, &o);
            for (int tr = 0; tr < SIDX_TRAVERSE_COUNT; ++tr) {
                const sidx_query q = {0, (sidx_traversal)tr, NULL, 0};
                for (size_t i = 0; i < n; ++i) {
                    sidx_hit h;
                    int occ;
                    sidx_accel_intersect(a, &rays[i], &q, &h);
                    sidx_accel_occluded(a, &rays[i], &q, &occ);
                    /* the plain slab test may lose grazing hits on a box
                     * face (that is why robust is the default); the
                     * watertight triangle test itself never leaks */
                    if (box == SIDX_BOX_ROBUST && (h.prim == SIDX_NO_HIT || !occ))
                        fail_msg("leak: %s/%s ray %zu", builders[bi], sidx_traversal_name((sidx_traversal)tr), i);
                }
            }
            sidx_accel_destroy(a);
        }
    }
    free(rays);
    sidx_mesh_free(&m);
}

/* ---- structure ------------------------------------------------------------------ */

static int box_inside(const bvh_node *outer, const bvh_node *inner)
{
    for (int k = 0; k < 3; ++k)
        if (inner->bmin[k] < outer->bmin[k] || inner->bmax[k] > outer->bmax[k]) return 0;
    return 1;
}

/* Points of triangle p (its corners, edge and inner points on a grid of
 * barycentric steps of 1/COVER_STEPS), which some leaf box listing p must
 * contain: with spatial splits a leaf holds a part of p, and its box
 * bounds only that part, but together they must cover all of p. */
#define COVER_STEPS 6
#define COVER_POINTS ((COVER_STEPS + 1) * (COVER_STEPS + 2) / 2)
static void cover_points(const sidx_mesh *m, uint32_t p, sidx_vec3 *out)
{
    const sidx_vec3 a = sidx_mesh_vertex(m, p, 0), b = sidx_mesh_vertex(m, p, 1), c = sidx_mesh_vertex(m, p, 2);
    /* clamped to the triangle's box: rounding may put a computed point an ulp outside
     * (a corner at 1.4e-8, a point at 1.5e-8), where no reference need reach */
    const sidx_vec3 lo = sidx_v3_min(a, sidx_v3_min(b, c)), hi = sidx_v3_max(a, sidx_v3_max(b, c));
    int k = 0;
    for (int i = 0; i <= COVER_STEPS; ++i)
        for (int j = 0; i + j <= COVER_STEPS; ++j) {
            const float u = (float)i / COVER_STEPS, v = (float)j / COVER_STEPS;
            const sidx_vec3 x = i == 0 && j == 0 ? a
                                : i == COVER_STEPS ? b
                                : j == COVER_STEPS ? c
                                                   : sidx_v3_add(a, sidx_v3_add(sidx_v3_scale(sidx_v3_sub(b, a), u),
                                                                                sidx_v3_scale(sidx_v3_sub(c, a), v)));
            out[k++] = sidx_v3_min(hi, sidx_v3_max(lo, x));
        }
}

/* Is x (double) in node n's box, within tol? */
static int in_box_d(const bvh_node *n, const double *x, double tol)
{
    for (int k = 0; k < 3; ++k)
        if (x[k] < (double)n->bmin[k] - tol || x[k] > (double)n->bmax[k] + tol) return 0;
    return 1;
}

/* The exact edges of the parts (bvh_spatial.c, "Robustness"): where an
 * edge of triangle p crosses a plane of a leaf box listing it, the
 * crossing, computed in double, lies in a leaf box listing p.  A
 * reference box built from the float crossing without its widening
 * misses it by an ulp (~1e-7 relative), far above the tolerance here
 * (1e-11 relative: double rounding). */
static void check_crossings(const bvh *b, const sidx_mesh *m)
{
    uint32_t *owner = malloc((b->num_prims + 1u) * sizeof *owner); /* leaf node of each reference */
    uint32_t *start = calloc(m->num_triangles + 2u, sizeof *start), *slot = malloc((b->num_prims + 1u) * sizeof *slot);
    assert_true(owner && start && slot);
    for (uint32_t i = 0; i < b->num_nodes; ++i)
        if (bvh_is_leaf(&b->nodes[i]))
            for (uint32_t j = b->nodes[i].left_or_first; j < b->nodes[i].left_or_first + bvh_count(&b->nodes[i]); ++j)
                owner[j] = i;
    for (uint32_t j = 0; j < b->num_prims; ++j) start[b->prim_id[j] + 2u]++;
    for (uint32_t p = 0; p < m->num_triangles; ++p) start[p + 2u] += start[p + 1u];
    for (uint32_t j = 0; j < b->num_prims; ++j) slot[start[b->prim_id[j] + 1u]++] = j; /* start[p]..start[p+1] */
    for (uint32_t p = 0; p < m->num_triangles; ++p) {
        double v[3][3], mag = 0.0;
        for (int i = 0; i < 3; ++i) {
            const sidx_vec3 c = sidx_mesh_vertex(m, p, i);
            v[i][0] = c.x; v[i][1] = c.y; v[i][2] = c.z;
            for (int k = 0; k < 3; ++k) mag = fabs(v[i][k]) > mag ? fabs(v[i][k]) : mag;
        }
        const double tol = 1e-11 * mag;
        for (uint32_t s = start[p]; s < start[p + 1u]; ++s) {
            const bvh_node *n = &b->nodes[owner[slot[s]]];
            for (int f = 0; f < 6; ++f) {
                const int k = f % 3;
                const double plane = f < 3 ? (double)n->bmin[k] : (double)n->bmax[k];
                for (int e = 0; e < 3; ++e) {
                    const double *a = v[e], *c = v[(e + 1) % 3];
                    if (!((a[k] < plane && c[k] > plane) || (a[k] > plane && c[k] < plane))) continue;
                    const double t = (plane - a[k]) / (c[k] - a[k]);
                    double x[3];
                    for (int j = 0; j < 3; ++j) x[j] = j == k ? plane : a[j] + (c[j] - a[j]) * t;
                    int hit = 0;
                    for (uint32_t s2 = start[p]; s2 < start[p + 1u] && !hit; ++s2)
                        hit = in_box_d(&b->nodes[owner[slot[s2]]], x, tol);
                    if (!hit)
                        fail_msg("triangle %u: its edge %d crosses plane %d of leaf %u at (%.9g %.9g %.9g), in no leaf "
                                 "box listing it", p, e, f, owner[slot[s]], x[0], x[1], x[2]);
                }
            }
        }
    }
    free(owner);
    free(start);
    free(slot);
}

/* Walks the flat array from the root: pre-order (left child = index + 1,
 * subtree sizes add up), children inside parents, leaves covering [0, n)
 * exactly once in order, leaf boxes containing their triangles, the
 * triangle copies equal to the mesh, depth within the limit.  bvh-sbvh
 * lists references: every triangle at least once, and the boxes of the
 * leaves that list it cover it (cover_points). */
static void check_structure(const sidx_accel *acc, const sidx_mesh *m)
{
    const bvh *b = acc->impl;
    assert_non_null(b);
    const int refs = strcmp(sidx_accel_name(acc), "bvh-sbvh") == 0;
    if (refs) assert_true(b->num_prims >= m->num_triangles);
    else assert_int_equal(b->num_prims, m->num_triangles);
    if (m->num_triangles == 0) {
        assert_int_equal(b->num_nodes, 0);
        return;
    }
    assert_true(((uintptr_t)b->nodes & 63u) == 0);
    uint8_t *seen = calloc(m->num_triangles, 1);
    uint8_t *covered = refs ? calloc((size_t)m->num_triangles * COVER_POINTS, 1) : NULL;
    assert_non_null(seen);
    assert_true(!refs || covered);
    uint32_t stack[2 * BVH_DEPTH_LIMIT + 2], depth_of[2 * BVH_DEPTH_LIMIT + 2];
    uint32_t sp = 0, next = 0, next_prim = 0, leaves = 0, visited = 0, max_depth = 0;
    stack[sp] = 0;
    depth_of[sp++] = 0;
    while (sp) {
        --sp;
        const uint32_t i = stack[sp], d = depth_of[sp];
        /* pre-order: nodes are met in index order when the right child is pushed first */
        assert_int_equal(i, next);
        ++next;
        ++visited;
        assert_true(i < b->num_nodes);
        assert_true(d <= BVH_DEPTH_LIMIT);
        if (d > max_depth) max_depth = d;
        const bvh_node *n = &b->nodes[i];
        if (bvh_is_leaf(n)) {
            ++leaves;
            assert_int_equal(n->left_or_first, next_prim); /* leaves in order, contiguous */
            next_prim += bvh_count(n);
            assert_true(next_prim <= b->num_prims);
            for (uint32_t j = n->left_or_first; j < n->left_or_first + bvh_count(n); ++j) {
                const uint32_t p = b->prim_id[j];
                assert_true(p < m->num_triangles);
                if (!refs) assert_int_equal(seen[p], 0);
                seen[p] = 1;
                for (int k = 0; k < 3; ++k) {
                    const sidx_vec3 v = sidx_mesh_vertex(m, p, k);
                    assert_memory_equal(&b->tris[j].v[k], &v, sizeof v);
                    if (refs) continue;
                    assert_true(v.x >= n->bmin[0] && v.y >= n->bmin[1] && v.z >= n->bmin[2]);
                    assert_true(v.x <= n->bmax[0] && v.y <= n->bmax[1] && v.z <= n->bmax[2]);
                }
                if (refs) {
                    sidx_vec3 pts[COVER_POINTS];
                    cover_points(m, p, pts);
                    for (int k = 0; k < COVER_POINTS; ++k) {
                        const sidx_vec3 v = pts[k];
                        if (v.x >= n->bmin[0] && v.y >= n->bmin[1] && v.z >= n->bmin[2] && v.x <= n->bmax[0] &&
                            v.y <= n->bmax[1] && v.z <= n->bmax[2])
                            covered[(size_t)p * COVER_POINTS + (size_t)k] = 1;
                    }
                }
            }
        } else {
            const uint32_t l = i + 1, r = n->left_or_first;
            assert_true(r > l && r < b->num_nodes);
            assert_true(box_inside(n, &b->nodes[l]));
            assert_true(box_inside(n, &b->nodes[r]));
            assert_true(sp + 2 <= 2 * BVH_DEPTH_LIMIT + 2);
            stack[sp] = r;
            depth_of[sp++] = d + 1;
            stack[sp] = l;
            depth_of[sp++] = d + 1;
        }
    }
    assert_int_equal(visited, b->num_nodes);
    assert_int_equal(next_prim, b->num_prims);
    for (uint32_t p = 0; p < m->num_triangles; ++p) {
        assert_int_equal(seen[p], 1);
        for (int k = 0; refs && k < COVER_POINTS; ++k)
            if (!covered[(size_t)p * COVER_POINTS + (size_t)k])
                fail_msg("%s: point %d of triangle %u is in no leaf box listing it", sidx_accel_name(acc), k, p);
    }
    free(covered);
    if (refs) check_crossings(b, m);
    assert_int_equal(leaves, b->num_leaves);
    assert_int_equal(b->num_nodes, 2 * leaves - 1);
    assert_int_equal(max_depth, b->max_depth);
    sidx_accel_stats st;
    assert_int_equal(sidx_accel_stats_get(acc, &st), SIDX_OK);
    assert_int_equal(st.nodes, b->num_nodes);
    assert_int_equal(st.leaves, leaves);
    assert_int_equal(st.max_depth, max_depth);
    assert_true(st.prim_refs == b->num_prims);
    assert_true(st.sah_cost > 0.0 && st.bytes > 0);
    free(seen);
}

static void test_structure(void **state)
{
    (void)state;
    for (size_t s = 0; s < NSCENES; ++s) {
        sidx_mesh m = scene(scenes[s]);
        for (size_t bi = 0; bi < NBUILDERS; ++bi) {
            sidx_accel *a = build(builders[bi], &m, NULL);
            check_structure(a, &m);
            sidx_accel_destroy(a);
        }
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        o.max_depth = 5;
        sidx_accel *a = build("bvh-sweep", &m, &o);
        check_structure(a, &m);
        assert_true(((const bvh *)a->impl)->max_depth <= 5);
        sidx_accel_destroy(a);
        sidx_mesh_free(&m);
    }
}

/* ---- degenerate input ------------------------------------------------------------ */

typedef struct leaf_log {
    uint32_t leaves, max_count, reasons[SIDX_LEAF_REASON_COUNT];
} leaf_log;
static void leaf_fn(const sidx_event *ev, void *user)
{
    leaf_log *l = user;
    if (ev->type != SIDX_EV_BUILD_LEAF) return;
    l->leaves++;
    if (ev->count > l->max_count) l->max_count = ev->count;
    if (ev->reason >= 0 && ev->reason < SIDX_LEAF_REASON_COUNT) l->reasons[ev->reason]++;
}

/* Slides "Edge Cases: primitives with same centroid": 1000 copies of one
 * triangle.  No plane separates them: the range is halved in index order
 * until at most BVH_MAX_LEAF remain, which become NO_SPLIT leaves. */
static void test_equal_centroids(void **state)
{
    (void)state;
    enum { N = 1000 };
    const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t *idx = malloc(sizeof *idx * 3 * N);
    assert_non_null(idx);
    for (uint32_t i = 0; i < 3 * N; ++i) idx[i] = i % 3;
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 3, idx, N, NULL), SIDX_OK);
    free(idx);
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        leaf_log log;
        memset(&log, 0, sizeof log);
        const sidx_hook hook = {leaf_fn, &log, SIDX_EVMASK(SIDX_EV_BUILD_LEAF)};
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        o.hook = &hook;
        sidx_accel *a = build(builders[bi], &m, &o);
        check_structure(a, &m);
        assert_true(log.max_count <= BVH_MAX_LEAF);
        assert_true(log.reasons[SIDX_LEAF_NO_SPLIT] > 0);
        assert_true(((const bvh *)a->impl)->max_depth < 16);
        sidx_ray r;
        sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, 1.0f), sidx_v3(0, 0, -1), 0.0f, INFINITY);
        for (int tr = 0; tr < SIDX_TRAVERSE_COUNT; ++tr) {
            const sidx_query q = {0, (sidx_traversal)tr, NULL, 0};
            sidx_hit h;
            sidx_accel_intersect(a, &r, &q, &h);
            assert_true(h.prim < N);
            assert_true(fabsf(h.t - 1.0f) < 1e-6f);
        }
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

/* Degenerate (zero-area, collinear, point) triangles and a zero-area root. */
static void test_degenerate_and_empty(void **state)
{
    (void)state;
    const float xyz[] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 2, 2, 2};
    const uint32_t idx[] = {0, 1, 2, 0, 1, 2, 0, 3, 4, 2, 3, 4, 1, 0, 2, 3, 3, 3};
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 5, idx, 6, NULL), SIDX_OK);
    sidx_ray r;
    sidx_ray_init(&r, sidx_v3(1, 0, 0), sidx_v3(-1, 1, 0), 0.0f, INFINITY);
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        sidx_build_options o;
        memset(&o, 0, sizeof o);
        o.leaf_size = 1;
        sidx_accel *a = build(builders[bi], &m, &o);
        check_structure(a, &m);
        sidx_hit h;
        sidx_accel_intersect(a, &r, NULL, &h);
        assert_int_equal(h.prim, SIDX_NO_HIT); /* degenerate triangles are misses */
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);

    /* no triangles at all: builds, every ray misses, every traversal */
    sidx_mesh empty;
    memset(&empty, 0, sizeof empty);
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        sidx_accel *a = build(builders[bi], &empty, NULL);
        check_structure(a, &empty);
        for (int tr = 0; tr < SIDX_TRAVERSE_COUNT; ++tr) {
            const sidx_query q = {0, (sidx_traversal)tr, NULL, 0};
            sidx_hit h;
            int occ;
            sidx_accel_intersect(a, &r, &q, &h);
            sidx_accel_occluded(a, &r, &q, &occ);
            assert_int_equal(h.prim, SIDX_NO_HIT);
            assert_int_equal(occ, 0);
        }
        sidx_accel_destroy(a);
    }
}

/* ---- refit ------------------------------------------------------------------------ */

static void test_refit_matches_rebuild(void **state)
{
    (void)state;
    const char *const names[] = {"teapot", "icosphere"};
    for (size_t s = 0; s < 2; ++s) {
        sidx_mesh m = scene(names[s]);
        for (size_t bi = 0; bi < NBUILDERS; ++bi) {
            sidx_accel *a = build(builders[bi], &m, NULL);
            /* move every vertex in place: a twist, a stretch and a shift */
            for (uint32_t v = 0; v < m.num_vertices; ++v) {
                const sidx_vec3 p = m.positions[v];
                const float ang = 0.3f * p.y, c = cosf(ang), sn = sinf(ang);
                m.positions[v] = sidx_v3(1.5f * (c * p.x - sn * p.z) + 0.25f, p.y * 0.8f - 0.1f, sn * p.x + c * p.z);
            }
            assert_int_equal(sidx_accel_refit(a, NULL), SIDX_OK);
            check_structure(a, &m);
            sidx_accel *fresh = build(builders[bi], &m, NULL);
            sidx_ray rays[RAYS_PER_SCENE];
            make_rays(&m, rays, RAYS_PER_SCENE, 11 + s);
            for (int tr = 0; tr < SIDX_TRAVERSE_COUNT; ++tr) {
                const sidx_query q = {0, (sidx_traversal)tr, NULL, 0};
                for (int i = 0; i < RAYS_PER_SCENE; ++i) {
                    sidx_hit h1, h2;
                    int o1, o2;
                    sidx_accel_intersect(a, &rays[i], &q, &h1);
                    sidx_accel_intersect(fresh, &rays[i], &q, &h2);
                    sidx_accel_occluded(a, &rays[i], &q, &o1);
                    sidx_accel_occluded(fresh, &rays[i], &q, &o2);
                    if (!hits_agree(&h1, &h2))
                        fail_msg("refit %s/%s ray %d: %u %g vs rebuild %u %g", names[s], builders[bi], i, h1.prim,
                                 (double)h1.t, h2.prim, (double)h2.t);
                    assert_int_equal(o1, o2);
                }
            }
            sidx_accel_destroy(fresh);
            sidx_accel_destroy(a);
            /* restore for the next builder */
            sidx_mesh_free(&m);
            m = scene(names[s]);
        }
        sidx_mesh_free(&m);
    }
}

/* ---- exact events on a tiny scene --------------------------------------------------- */

#define MAX_EVENTS 64
typedef struct rec {
    sidx_event ev[MAX_EVENTS];
    int n;
} rec;
static void rec_fn(const sidx_event *ev, void *user)
{
    rec *r = user;
    if (r->n < MAX_EVENTS) r->ev[r->n] = *ev;
    r->n++;
}

/* Two unit right triangles stacked along z: T0 in z = 0, T1 in z = 2. */
static sidx_mesh two_tris(void)
{
    const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 2, 1, 0, 2, 0, 1, 2};
    const uint32_t idx[] = {0, 1, 2, 3, 4, 5};
    sidx_mesh m;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, 6, idx, 2, NULL), SIDX_OK);
    return m;
}

static void expect(const rec *r, int i, sidx_event_type type, uint32_t node)
{
    assert_true(i < r->n);
    if (r->ev[i].type != type || r->ev[i].node != node)
        fail_msg("event %d: got %s node %u, expected %s node %u", i, sidx_event_type_name(r->ev[i].type),
                 r->ev[i].node, sidx_event_type_name(type), node);
}

/* The build of two_tris() with leaf_size 1: begin, the root split on z into
 * one triangle a side, two leaves, end.  bvh-median reports its candidate
 * plane (with_candidate); bvh-sbvh costs its planes on bins and reports
 * none, so its sequence is one event shorter. */
static void expect_two_tri_build(const rec *r, const char *structure, int with_candidate)
{
    const uint32_t X = UINT32_MAX;
    const int c = with_candidate ? 1 : 0;
    assert_int_equal(r->n, 8 + c);
    expect(r, 0, SIDX_EV_BUILD_BEGIN, X);
    assert_int_equal(r->ev[0].count, 2);
    expect(r, 1, SIDX_EV_BUILD_NODE, 0);
    assert_int_equal(r->ev[1].parent, X);
    assert_int_equal(r->ev[1].count, 2);
    if (with_candidate) expect(r, 2, SIDX_EV_BUILD_CANDIDATE, 0);
    expect(r, 2 + c, SIDX_EV_BUILD_SPLIT, 0);
    assert_int_equal(r->ev[2 + c].axis, 2);
    assert_int_equal(r->ev[2 + c].count, 1);
    assert_int_equal(r->ev[2 + c].aux, 1);
    expect(r, 3 + c, SIDX_EV_BUILD_NODE, 1);
    assert_int_equal(r->ev[3 + c].parent, 0);
    assert_int_equal(r->ev[3 + c].depth, 1);
    expect(r, 4 + c, SIDX_EV_BUILD_LEAF, 1);
    assert_int_equal(r->ev[4 + c].reason, SIDX_LEAF_FEW_PRIMS);
    expect(r, 5 + c, SIDX_EV_BUILD_NODE, 2);
    assert_int_equal(r->ev[5 + c].parent, 0);
    expect(r, 6 + c, SIDX_EV_BUILD_LEAF, 2);
    expect(r, 7 + c, SIDX_EV_BUILD_END, 3); /* node = node count */
    assert_int_equal(r->ev[7 + c].count, 2);
    assert_int_equal(r->ev[7 + c].depth, 1);
    for (int i = 0; i < r->n; ++i) assert_string_equal(r->ev[i].structure, structure);
}

static void test_build_events(void **state)
{
    (void)state;
    sidx_mesh m = two_tris();
    rec r;
    memset(&r, 0, sizeof r);
    const sidx_hook hook = {rec_fn, &r, 0};
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.hook = &hook;
    o.leaf_size = 1;
    sidx_accel *a = build("bvh-median", &m, &o);
    expect_two_tri_build(&r, "bvh-median", 1);
    assert_int_equal(r.ev[2].axis, 2); /* largest centroid extent: z */
    sidx_accel_destroy(a);

    /* SAH builders: the same tree for this scene, and SAH termination. */
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        memset(&r, 0, sizeof r);
        a = build(builders[bi], &m, &o);
        assert_int_equal(((const bvh *)a->impl)->num_nodes, 3);
        /* bvh-sbvh costs its planes on bins without BUILD_CANDIDATE events: 8 */
        assert_true(r.n >= (strcmp(builders[bi], "bvh-sbvh") ? 9 : 8) && r.n <= MAX_EVENTS);
        sidx_accel_destroy(a);
    }
    /* with a huge traversal cost no split pays: one NO_GAIN leaf */
    memset(&r, 0, sizeof r);
    o.c_trav = 100.0f;
    a = build("bvh", &m, &o);
    assert_int_equal(((const bvh *)a->impl)->num_nodes, 1);
    int saw_no_gain = 0;
    for (int i = 0; i < r.n && i < MAX_EVENTS; ++i)
        if (r.ev[i].type == SIDX_EV_BUILD_LEAF) saw_no_gain = r.ev[i].reason == SIDX_LEAF_NO_GAIN;
    assert_true(saw_no_gain);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* bvh-sbvh's build events: on the two triangles the exact sequence, and on
 * the stadium (long thin triangles, spatial splits) node ids in pre-order
 * equal to the final indices, parents, a NOTE before every spatial split
 * whose count is the references it added, and leaves listing exactly the
 * tree's prim_id[] — the same tree as an untraced build. */
typedef struct sbvh_log {
    uint32_t next_node, nodes, leaves, splits, spatial, added, note_node, bad;
    uint32_t *leaf_prims;
    size_t nprims;
    const bvh *ref;
} sbvh_log;
static void sbvh_fn(const sidx_event *ev, void *user)
{
    sbvh_log *l = user;
    switch (ev->type) {
    case SIDX_EV_BUILD_NODE:
        l->bad += ev->node != l->next_node++;
        l->bad += ev->node == 0 ? ev->parent != UINT32_MAX : ev->parent >= ev->node;
        l->nodes++;
        break;
    case SIDX_EV_NOTE:
        l->spatial++;
        l->added += ev->count;
        l->note_node = ev->node;
        break;
    case SIDX_EV_BUILD_SPLIT:
        l->splits++;
        if (l->note_node == ev->node) l->note_node = UINT32_MAX;
        break;
    case SIDX_EV_BUILD_LEAF:
        l->leaves++;
        for (uint32_t i = 0; i < ev->count; ++i) l->leaf_prims[l->nprims++] = ev->prims[i];
        break;
    default: break;
    }
}

static void test_sbvh_build_events(void **state)
{
    (void)state;
    sidx_mesh m = two_tris();
    rec r;
    memset(&r, 0, sizeof r);
    const sidx_hook hook = {rec_fn, &r, 0};
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.hook = &hook;
    o.leaf_size = 1;
    sidx_accel *a = build("bvh-sbvh", &m, &o);
    expect_two_tri_build(&r, "bvh-sbvh", 0);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);

    m = scene("stadium");
    sidx_accel *plain = build("bvh-sbvh", &m, NULL);
    const bvh *pb = plain->impl;
    assert_true(pb->num_prims > m.num_triangles); /* the stadium makes spatial splits */
    sbvh_log l;
    memset(&l, 0, sizeof l);
    l.note_node = UINT32_MAX;
    l.leaf_prims = malloc(pb->num_prims * sizeof *l.leaf_prims);
    assert_non_null(l.leaf_prims);
    const sidx_hook h2 = {sbvh_fn, &l, 0};
    o.hook = &h2;
    o.leaf_size = 0;
    a = build("bvh-sbvh", &m, &o);
    const bvh *b = a->impl;
    assert_int_equal(l.bad, 0);
    assert_int_equal(l.note_node, UINT32_MAX); /* every NOTE followed by its node's split */
    assert_int_equal(l.nodes, b->num_nodes);
    assert_int_equal(l.leaves, b->num_leaves);
    assert_int_equal(l.splits, b->num_nodes - b->num_leaves);
    assert_true(l.spatial > 0);
    assert_int_equal(l.added, b->num_prims - m.num_triangles);
    assert_int_equal(l.nprims, b->num_prims);
    assert_memory_equal(l.leaf_prims, b->prim_id, b->num_prims * sizeof *b->prim_id);
    /* traced or not, the same tree */
    assert_int_equal(b->num_nodes, pb->num_nodes);
    assert_memory_equal(b->nodes, pb->nodes, b->num_nodes * sizeof *b->nodes);
    assert_memory_equal(b->prim_id, pb->prim_id, b->num_prims * sizeof *b->prim_id);
    free(l.leaf_prims);
    sidx_accel_destroy(a);
    sidx_accel_destroy(plain);
    sidx_mesh_free(&m);
}

static void test_stack_traversal_events(void **state)
{
    (void)state;
    sidx_mesh m = two_tris();
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.leaf_size = 1;
    sidx_accel *a = build("bvh-median", &m, &o);
    rec r;
    memset(&r, 0, sizeof r);
    const sidx_hook hook = {rec_fn, &r, 0};
    const sidx_query q = {0, SIDX_TRAVERSE_STACK, &hook, 42};
    sidx_ray ray;
    sidx_ray_init(&ray, sidx_v3(0.25f, 0.25f, 5.0f), sidx_v3(0, 0, -1), 0.0f, INFINITY);
    sidx_hit h;
    sidx_accel_intersect(a, &ray, &q, &h);
    assert_int_equal(h.prim, 1);
    assert_true(h.t == 3.0f);
    const uint32_t X = UINT32_MAX;
    /* root box; enter root; both children hit, T1's (node 2, z = 2) is
     * nearer so node 1 is pushed; T1 hits at t = 3; node 1 is popped but
     * its entry t = 5 is behind the hit, so it is dropped. */
    assert_int_equal(r.n, 12);
    expect(&r, 0, SIDX_EV_RAY_BEGIN, X);
    expect(&r, 1, SIDX_EV_BOX_TEST, 0);
    assert_int_equal(r.ev[1].result, 1);
    expect(&r, 2, SIDX_EV_NODE_ENTER, 0);
    assert_int_equal(r.ev[2].depth, 0);
    expect(&r, 3, SIDX_EV_BOX_TEST, 1);
    assert_int_equal(r.ev[3].result, 1);
    assert_true(fabsf(r.ev[3].t_near - 5.0f) < 1e-5f);
    expect(&r, 4, SIDX_EV_BOX_TEST, 2);
    assert_true(fabsf(r.ev[4].t_near - 3.0f) < 1e-5f);
    expect(&r, 5, SIDX_EV_STACK_PUSH, 1);
    assert_int_equal(r.ev[5].depth, 1);
    expect(&r, 6, SIDX_EV_NODE_ENTER, 2);
    assert_int_equal(r.ev[6].depth, 1);
    expect(&r, 7, SIDX_EV_PRIM_TEST, 2);
    assert_int_equal(r.ev[7].prim, 1);
    assert_int_equal(r.ev[7].result, 1);
    expect(&r, 8, SIDX_EV_HIT_UPDATE, X);
    assert_int_equal(r.ev[8].prim, 1);
    assert_true(r.ev[8].t == 3.0f);
    expect(&r, 9, SIDX_EV_STACK_POP, 1);
    assert_int_equal(r.ev[9].depth, 1);
    expect(&r, 10, SIDX_EV_TERMINATE, X);
    assert_int_equal(r.ev[10].reason, SIDX_TERM_STACK_EMPTY);
    assert_int_equal(r.ev[10].count, 2);
    expect(&r, 11, SIDX_EV_RAY_END, X);
    for (int i = 0; i < r.n; ++i) assert_int_equal(r.ev[i].ray_id, 42);

    /* any hit: stops at T1 */
    memset(&r, 0, sizeof r);
    int occ;
    sidx_accel_occluded(a, &ray, &q, &occ);
    assert_int_equal(occ, 1);
    assert_int_equal(r.n, 10);
    expect(&r, 7, SIDX_EV_PRIM_TEST, 2);
    expect(&r, 8, SIDX_EV_TERMINATE, X);
    assert_int_equal(r.ev[8].reason, SIDX_TERM_ANY_HIT);

    /* a miss of the root box */
    memset(&r, 0, sizeof r);
    sidx_ray_init(&ray, sidx_v3(5, 5, 5), sidx_v3(0, 0, -1), 0.0f, INFINITY);
    sidx_accel_intersect(a, &ray, &q, &h);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    assert_int_equal(r.n, 4);
    expect(&r, 1, SIDX_EV_BOX_TEST, 0);
    assert_int_equal(r.ev[1].result, 0);
    expect(&r, 2, SIDX_EV_TERMINATE, X);
    assert_int_equal(r.ev[2].reason, SIDX_TERM_MISS_ROOT);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* The deck's two recursive traversals on the same scene: the naive one
 * visits the far child too, the ordered one skips it. */
static void test_recursive_traversal_events(void **state)
{
    (void)state;
    sidx_mesh m = two_tris();
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.leaf_size = 1;
    sidx_accel *a = build("bvh-median", &m, &o);
    sidx_ray ray;
    sidx_ray_init(&ray, sidx_v3(0.25f, 0.25f, 5.0f), sidx_v3(0, 0, -1), 0.0f, INFINITY);
    int enters[SIDX_TRAVERSE_COUNT] = {0}, prims[SIDX_TRAVERSE_COUNT] = {0};
    for (int tr = 0; tr < SIDX_TRAVERSE_COUNT; ++tr) {
        rec r;
        memset(&r, 0, sizeof r);
        const sidx_hook hook = {rec_fn, &r, 0};
        const sidx_query q = {0, (sidx_traversal)tr, &hook, 0};
        sidx_hit h;
        sidx_accel_intersect(a, &ray, &q, &h);
        assert_int_equal(h.prim, 1);
        for (int i = 0; i < r.n; ++i) {
            enters[tr] += r.ev[i].type == SIDX_EV_NODE_ENTER;
            prims[tr] += r.ev[i].type == SIDX_EV_PRIM_TEST;
        }
        assert_int_equal(r.ev[r.n - 2].type, SIDX_EV_TERMINATE);
    }
    /* naive: left child (T0, farther) first, both tested: 3 nodes, 2 prims
     * (T0 at t = 5 first, then T1 at t = 3 replaces it) */
    assert_int_equal(enters[SIDX_TRAVERSE_NAIVE], 3);
    assert_int_equal(prims[SIDX_TRAVERSE_NAIVE], 2);
    assert_int_equal(enters[SIDX_TRAVERSE_ORDERED], 2);
    assert_int_equal(prims[SIDX_TRAVERSE_ORDERED], 1);
    assert_int_equal(enters[SIDX_TRAVERSE_STACK], 2);
    assert_int_equal(enters[SIDX_TRAVERSE_DEFAULT], 2);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* Build events name the same node ids traversal events use. */
static void test_event_ids_consistent(void **state)
{
    (void)state;
    sidx_mesh m = scene("teapot");
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        sidx_accel *a = build(builders[bi], &m, NULL);
        const bvh *b = a->impl;
        rec r;
        memset(&r, 0, sizeof r);
        const sidx_hook hook = {rec_fn, &r, SIDX_EVMASK(SIDX_EV_NODE_ENTER)};
        const sidx_query q = {0, SIDX_TRAVERSE_STACK, &hook, 0};
        sidx_ray rays[32];
        make_rays(&m, rays, 32, 3);
        for (int i = 0; i < 32; ++i) {
            sidx_hit h;
            r.n = 0;
            sidx_accel_intersect(a, &rays[i], &q, &h);
            for (int k = 0; k < r.n && k < MAX_EVENTS; ++k) assert_true(r.ev[k].node < b->num_nodes);
        }
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&m);
}

/* ---- allocation failures ------------------------------------------------------------ */

typedef struct failing { int countdown, allocs, live; } failing;
static void *f_alloc(size_t size, void *user)
{
    failing *f = user;
    if (f->countdown-- == 0) return NULL;
    f->allocs++;
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
    for (size_t bi = 0; bi < NBUILDERS; ++bi) {
        for (int k = 0;; ++k) {
            failing f = {k, 0, 0};
            const sidx_allocator al = {f_alloc, f_free, &f};
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.alloc = &al;
            sidx_accel *a = NULL;
            sidx_error err;
            const sidx_status s = sidx_accel_build(builders[bi], &m, &o, &a, &err);
            if (s == SIDX_OK) {
                assert_non_null(a);
                sidx_accel_destroy(a);
                assert_int_equal(f.live, 0);
                break;
            }
            assert_int_equal(s, SIDX_ERR_NOMEM);
            assert_null(a);
            assert_int_equal(f.live, 0);
            assert_true(k < 100);
        }
    }
    sidx_mesh_free(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_builders_match_brute),
        cmocka_unit_test(test_options_match_brute),
        cmocka_unit_test(test_translated_and_scaled),
        cmocka_unit_test(test_no_leaks_icosphere),
        cmocka_unit_test(test_structure),
        cmocka_unit_test(test_equal_centroids),
        cmocka_unit_test(test_degenerate_and_empty),
        cmocka_unit_test(test_refit_matches_rebuild),
        cmocka_unit_test(test_build_events),
        cmocka_unit_test(test_sbvh_build_events),
        cmocka_unit_test(test_stack_traversal_events),
        cmocka_unit_test(test_recursive_traversal_events),
        cmocka_unit_test(test_event_ids_consistent),
        cmocka_unit_test(test_alloc_failures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
