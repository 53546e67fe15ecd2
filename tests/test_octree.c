/* test_octree.c — the octree's build stays bounded on adversarial scenes.
 *
 * Lesson 13's "star" (n large triangles through one point, random planes)
 * is the octree's worst case: no node around the common point ever holds
 * fewer than leaf_size triangles, so an unbounded build cuts there until
 * the depth limit, 8 nodes per level per touched node.  The octree's rule
 * (lib/octree.c, "Bounds"): triangles that span a node do not count
 * towards splitting it, and the node count never exceeds
 * OCT_NODES_PER_TRI·n + 1 — past that, nodes become leaves (reason
 * max_depth).  Checked: node count within the documented budget,
 * identical hits to brute force, and an allocation failure anywhere is
 * reported, never a crash or a leak (the test kit's failing allocator).
 * The read-only view (sidx/octree.h): the cell of every node the traced
 * walk enters, cut from the root's box through the view's nodes, is the
 * box the walk reports, and every leaf's references lie in refs[]. */
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
#include "common/testkit.h"

/* Must match OCT_NODES_PER_TRI in lib/octree.c (the documented budget). */
#define NODES_PER_TRI 64u

static float lcg(uint32_t *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (float)(*s >> 8) / 16777216.0f;
}

/* n equilateral triangles of circumradius 1 around the origin, random planes. */
static void make_star(uint32_t n, sidx_mesh *out)
{
    float *xyz = malloc((size_t)n * 9 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * 3 * sizeof *idx);
    assert_non_null(xyz);
    assert_non_null(idx);
    uint32_t seed = 1234u;
    for (uint32_t i = 0; i < n; ++i) {
        const float z = 2 * lcg(&seed) - 1, ph = 6.2831853f * lcg(&seed), s = sqrtf(1 - z * z);
        const sidx_vec3 nrm = sidx_v3(s * cosf(ph), s * sinf(ph), z);
        sidx_vec3 a = sidx_v3_cross(nrm, fabsf(nrm.x) < 0.9f ? sidx_v3(1, 0, 0) : sidx_v3(0, 1, 0));
        a = sidx_v3_scale(a, 1.0f / sidx_v3_length(a));
        const sidx_vec3 b = sidx_v3_cross(nrm, a);
        const float rot = 6.2831853f * lcg(&seed);
        for (int k = 0; k < 3; ++k) {
            const float ang = rot + 2.0943951f * (float)k;
            const sidx_vec3 p = sidx_v3_add(sidx_v3_scale(a, cosf(ang)), sidx_v3_scale(b, sinf(ang)));
            xyz[9 * i + 3 * k] = p.x;
            xyz[9 * i + 3 * k + 1] = p.y;
            xyz[9 * i + 3 * k + 2] = p.z;
            idx[3 * i + (uint32_t)k] = 3 * i + (uint32_t)k;
        }
    }
    sidx_error err;
    assert_int_equal(sidx_mesh_from_arrays(out, xyz, 3 * n, idx, n, &err), SIDX_OK);
    free(xyz);
    free(idx);
}

/* n thin slivers from the origin, directions in a narrow cone around
 * (1, 1, 1): the node holding the apex keeps all n at every level, while
 * the slivers spread over few children (so the duplication rule does not
 * stop the cut) — without a budget, cut at every level to the limit. */
static void make_fan(uint32_t n, sidx_mesh *out)
{
    float *xyz = malloc((size_t)n * 9 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * 3 * sizeof *idx);
    assert_non_null(xyz);
    assert_non_null(idx);
    uint32_t seed = 77u;
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_vec3 d = sidx_v3(1.0f + 0.3f * lcg(&seed), 1.0f + 0.3f * lcg(&seed), 1.0f + 0.3f * lcg(&seed));
        const sidx_vec3 w = sidx_v3(1e-3f * lcg(&seed), -1e-3f * lcg(&seed), 1e-3f * lcg(&seed));
        const sidx_vec3 p[3] = {sidx_v3(0, 0, 0), d, sidx_v3_add(d, w)};
        for (int k = 0; k < 3; ++k) {
            xyz[9 * i + 3 * k] = p[k].x;
            xyz[9 * i + 3 * k + 1] = p[k].y;
            xyz[9 * i + 3 * k + 2] = p[k].z;
            idx[3 * i + (uint32_t)k] = 3 * i + (uint32_t)k;
        }
    }
    sidx_error err;
    assert_int_equal(sidx_mesh_from_arrays(out, xyz, 3 * n, idx, n, &err), SIDX_OK);
    free(xyz);
    free(idx);
}

static int have(const char *name) { return sidx_accel_is_registered(name); }

static void test_star_bounded(void **state)
{
    (void)state;
    if (!have("octree")) return;
    static const uint32_t ns[] = {128, 512, 2048, 128, 512, 2048};
    for (size_t k = 0; k < sizeof ns / sizeof ns[0]; ++k) {
        sidx_mesh m;
        const char *what = k < 3 ? "star" : "fan";
        if (k < 3) make_star(ns[k], &m);
        else make_fan(ns[k], &m);
        for (int depth = 0; depth < 2; ++depth) {
            sidx_build_options o;
            memset(&o, 0, sizeof o);
            o.max_depth = depth ? 24u : 0u; /* the default, and the largest allowed */
            sidx_accel *a = NULL, *ref = NULL;
            sidx_error err;
            assert_int_equal(sidx_accel_build("octree", &m, &o, &a, &err), SIDX_OK);
            assert_int_equal(sidx_accel_build("brute", &m, NULL, &ref, &err), SIDX_OK);
            sidx_accel_stats st;
            sidx_accel_stats_get(a, &st);
            fprintf(stderr, "octree on a %s of %u triangles (max_depth %u): %u nodes, %llu refs, depth %u\n",
                    what, ns[k], o.max_depth, st.nodes, (unsigned long long)st.prim_refs, st.max_depth);
            assert_true(st.nodes <= NODES_PER_TRI * ns[k] + 1u);
            /* References: every leaf holds at most n triangles. */
            assert_true(st.prim_refs <= (uint64_t)st.leaves * ns[k]);
            const size_t nr = 300;
            tk_rayrec *rays = malloc(nr * sizeof *rays);
            assert_non_null(rays);
            tk_make_rays(&m, TK_RAYS_DIFFUSE, nr, 11, rays);
            for (size_t i = 0; i < nr; ++i) {
                sidx_ray r;
                if (sidx_ray_init(&r, sidx_v3(rays[i].o[0], rays[i].o[1], rays[i].o[2]),
                                  sidx_v3(rays[i].d[0], rays[i].d[1], rays[i].d[2]), rays[i].tmin,
                                  rays[i].tmax) != SIDX_OK)
                    continue;
                sidx_hit h1, h2;
                sidx_accel_intersect(a, &r, NULL, &h1);
                sidx_accel_intersect(ref, &r, NULL, &h2);
                assert_true(h1.t == h2.t);
            }
            free(rays);
            sidx_accel_destroy(a);
            sidx_accel_destroy(ref);
        }
        sidx_mesh_free(&m);
    }
}

/* Where the budget itself binds: leaf_size 1, a pair of tiny triangles at
 * (±0.1, ±0.1, ±0.1) in each of the 8 octants, the two one float step
 * apart (they never separate), and two big triangles at opposite corners.
 * Below the root each pair costs 8 nodes per level until the float-spacing
 * stop (~21 levels): 1289 nodes without the budget
 * (measured with the budget raised), over 64·18 + 1 = 1153. */
static void test_specks_budget(void **state)
{
    (void)state;
    if (!have("octree")) return;
    enum { NT = 18 };
    float xyz[NT * 9];
    uint32_t idx[NT * 3];
    sidx_vec3 centre[16];
    for (int o = 0; o < 8; ++o)
        for (int p = 0; p < 2; ++p) {
            const float sx = o & 1 ? 1.0f : -1.0f, sy = o & 2 ? 1.0f : -1.0f, sz = o & 4 ? 1.0f : -1.0f;
            const float e = 0.1f + 1e-8f * (float)p;
            const sidx_vec3 c = sidx_v3(sx * e, sy * e, sz * e);
            centre[2 * o + p] = c;
            float *v = xyz + 9 * (2 * o + p);
            const float leg = 1e-7f;
            const float tri[9] = {c.x, c.y, c.z, c.x + leg, c.y, c.z, c.x, c.y + leg, c.z};
            memcpy(v, tri, sizeof tri);
        }
    const float far[18] = {1, 1, 1, 0.9f, 1, 1, 1, 0.9f, 1, -1, -1, -1, -0.9f, -1, -1, -1, -0.9f, -1};
    memcpy(xyz + 16 * 9, far, sizeof far);
    for (uint32_t i = 0; i < NT * 3; ++i) idx[i] = i;
    sidx_mesh m;
    sidx_error err;
    assert_int_equal(sidx_mesh_from_arrays(&m, xyz, NT * 3, idx, NT, &err), SIDX_OK);
    sidx_build_options o;
    memset(&o, 0, sizeof o);
    o.leaf_size = 1;
    o.max_depth = 24;
    sidx_accel *a = NULL, *ref = NULL;
    assert_int_equal(sidx_accel_build("octree", &m, &o, &a, &err), SIDX_OK);
    assert_int_equal(sidx_accel_build("brute", &m, NULL, &ref, &err), SIDX_OK);
    sidx_accel_stats st;
    sidx_accel_stats_get(a, &st);
    fprintf(stderr, "octree on 8 speck pairs (leaf 1, depth 24): %u nodes (budget %u), depth %u\n", st.nodes,
            NODES_PER_TRI * NT + 1u, st.max_depth);
    assert_true(st.nodes <= NODES_PER_TRI * NT + 1u);
    /* Rays down onto every speck: the same answer as brute force. */
    for (int i = 0; i < 16; ++i) {
        sidx_ray r;
        const sidx_vec3 c = centre[i];
        const sidx_vec3 t = sidx_v3(c.x + 2e-8f, c.y + 2e-8f, c.z);
        assert_int_equal(sidx_ray_init(&r, sidx_v3(t.x, t.y, 1.5f), sidx_v3(0, 0, -1), 0.0f, INFINITY), SIDX_OK);
        sidx_hit h1, h2;
        sidx_accel_intersect(a, &r, NULL, &h1);
        sidx_accel_intersect(ref, &r, NULL, &h2);
        assert_true(h1.t == h2.t);
        assert_int_equal(h1.prim, h2.prim);
    }
    sidx_accel_destroy(a);
    sidx_accel_destroy(ref);
    sidx_mesh_free(&m);
}

/* Cell of every node from the view: children a + c, bit k of c = the
 * upper half on axis k, cut at 0.5·(lo + hi). */
static void view_cells(const sidx_oct_node *nodes, uint32_t count, int axes, sidx_aabb *cells)
{
    for (uint32_t i = 0; i < count; ++i) {
        if (nodes[i].n != SIDX_OCT_INNER) continue;
        const uint32_t nch = 1u << axes;
        assert_true(nodes[i].a > i && nodes[i].a + nch <= count);
        for (uint32_t c = 0; c < nch; ++c) {
            const sidx_aabb parent = cells[i];
            float lo[3], hi[3];
            sidx_v3_to_array(parent.min, lo);
            sidx_v3_to_array(parent.max, hi);
            for (int k = 0; k < axes; ++k) {
                const float m = 0.5f * (lo[k] + hi[k]);
                if (c & (1u << k)) lo[k] = m;
                else hi[k] = m;
            }
            cells[nodes[i].a + c] = (sidx_aabb){sidx_v3(lo[0], lo[1], lo[2]), sidx_v3(hi[0], hi[1], hi[2])};
        }
    }
}

typedef struct enter_check {
    const sidx_aabb *cells;
    uint32_t count, entered;
} enter_check;

static void enter_fn(const sidx_event *ev, void *user)
{
    enter_check *c = user;
    if (ev->type != SIDX_EV_NODE_ENTER) return;
    assert_true(ev->node < c->count);
    const sidx_aabb *b = &c->cells[ev->node];
    assert_true(ev->bounds.min.x == b->min.x && ev->bounds.min.y == b->min.y && ev->bounds.min.z == b->min.z &&
                ev->bounds.max.x == b->max.x && ev->bounds.max.y == b->max.y && ev->bounds.max.z == b->max.z);
    ++c->entered;
}

static void test_view(void **state)
{
    (void)state;
    const char *const names[2] = {"octree", "quadtree"};
    const char *const scenes[2] = {"soup:300", "flat2d"};
    for (int s = 0; s < 2; ++s) {
        sidx_mesh m;
        sidx_accel *a = NULL;
        sidx_error err;
        assert_int_equal(sidx_scene_open(scenes[s], &m, &err), SIDX_OK);
        assert_int_equal(sidx_accel_build(names[s], &m, NULL, &a, &err), SIDX_OK);
        const sidx_oct_node *nodes = NULL;
        const uint32_t *refs = NULL;
        uint32_t count = 0, nrefs = 0;
        sidx_aabb root;
        int axes = 0;
        assert_int_equal(sidx_octree_nodes(a, &nodes, &count, &err), SIDX_OK);
        assert_int_equal(sidx_octree_refs(a, &refs, &nrefs, &err), SIDX_OK);
        assert_int_equal(sidx_octree_info(a, &root, &axes, &err), SIDX_OK);
        assert_int_equal(axes, s == 0 ? 3 : 2);
        assert_true(count > 1 && nodes[0].n == SIDX_OCT_INNER);
        for (uint32_t i = 0; i < count; ++i)
            if (nodes[i].n != SIDX_OCT_INNER) {
                assert_true((uint64_t)nodes[i].a + nodes[i].n <= nrefs);
                for (uint32_t j = 0; j < nodes[i].n; ++j) assert_true(refs[nodes[i].a + j] < m.num_triangles);
            }
        sidx_aabb *cells = malloc(count * sizeof *cells);
        assert_non_null(cells);
        cells[0] = root;
        view_cells(nodes, count, axes, cells);
        enter_check c = {cells, count, 0};
        sidx_hook h = {enter_fn, &c, 0};
        sidx_query q;
        memset(&q, 0, sizeof q);
        q.hook = &h;
        const sidx_aabb b = sidx_mesh_bounds(&m);
        uint32_t st = 5u;
        for (int r = 0; r < 50; ++r) {
            sidx_ray ray;
            /* From outside the scene box to a point inside it. */
            const sidx_vec3 p = sidx_v3(b.min.x + lcg(&st) * (b.max.x - b.min.x), b.min.y + lcg(&st) * (b.max.y - b.min.y),
                                        b.min.z + lcg(&st) * (b.max.z - b.min.z));
            const sidx_vec3 o = sidx_v3(b.min.x - 1.0f, b.min.y - 0.5f + lcg(&st), p.z);
            sidx_ray_init(&ray, o, sidx_v3_sub(p, o), 0.0f, INFINITY);
            sidx_hit hit;
            assert_int_equal(sidx_accel_intersect(a, &ray, &q, &hit), SIDX_OK);
        }
        assert_true(c.entered > 50);
        free(cells);
        sidx_accel *bvh = NULL;
        assert_int_equal(sidx_accel_build("bvh", &m, NULL, &bvh, &err), SIDX_OK);
        assert_int_equal(sidx_octree_nodes(bvh, &nodes, &count, &err), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_octree_refs(a, NULL, &nrefs, &err), SIDX_ERR_INVALID_ARG);
        assert_int_equal(sidx_octree_info(NULL, &root, &axes, &err), SIDX_ERR_INVALID_ARG);
        sidx_accel_destroy(bvh);
        sidx_accel_destroy(a);
        sidx_mesh_free(&m);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_star_bounded),
        cmocka_unit_test(test_specks_budget),
        cmocka_unit_test(test_view),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
