/* test_lazy.c — lazy builds (sidx_build_options.lazy) against the eager
 * tree of the same structure.
 *
 *  - hits bit-identical (t, prim, u, v, normal, by their bits) to the
 *    eager tree's on every built-in scene and on the stress scenes of
 *    test_accel_suite (translated, scaled, duplicated, flattened), for
 *    every ray kind of the test kit, on a fresh lazy tree per query kind:
 *    single rays (each traversal, with and without u, v), any-hit, n rays
 *    at once, packets, image tiles, threads, traced queries.  bvh4, bvh8:
 *    or, where the ray hits two triangles at exactly the same t, the other
 *    one (is_tie); kd-trees: or a hit up to rounding (kd_close_hit), and
 *    the lazy tree's own hits the same bits whatever was built first;
 *  - the same tree: with every unbuilt node entered, the lazy build's
 *    splits and leaves (from its events and its expansions') are the eager
 *    build's, and so are the node, leaf and depth counts (the wide BVHs:
 *    the same references in their leaves);
 *  - build_lazy_expand events: one per node built for a ray, carrying the
 *    subtree's size; sidx_accel_stats counts what is left;
 *  - several threads racing into the same unbuilt node (run under
 *    ThreadSanitizer by `make test-tsan`);
 *  - out of memory during an expansion: the query (single ray, any hit,
 *    packet, threads) returns SIDX_ERR_NOMEM, nothing is half built, a later
 *    query with memory builds the node and gets the eager hit, and nothing
 *    leaks.
 * SIDX_FAST_TESTS=1 shrinks ray counts, tries one subtree size per query
 * kind in turn and one transform per stress scene; 2 (valgrind,
 * ThreadSanitizer) also compares the hits and runs out of memory with one
 * structure per family only (bvh, bvh8, kdtree), and compares the expanded
 * trees of each structure and size on every other scene. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sidx/sidx.h"
#include "common/testkit.h"

/* The structures with lazy builds, and the subtree sizes tried: small
 * enough that the small scenes have unbuilt nodes, and the default. */
static const char *const lazy_accels[] = {"bvh",        "bvh-sweep", "bvh-everyb",    "bvh-median",
                                          "bvh-middle", "bvh8",      "bvh4",          "kdtree",
                                          "kdtree-binned", "kdtree-median", "kdtree-middle"};
#define NACCELS (sizeof lazy_accels / sizeof lazy_accels[0])

static int is_kd(const char *name) { return !strncmp(name, "kdtree", 6); }
static int is_wide(const char *name) { return !strcmp(name, "bvh8") || !strcmp(name, "bvh4"); }
/* The structure each family's checks keep at the smallest sizes (the
 * builders of a family share its lazy code). */
static int family_first(const char *name) { return !strcmp(name, "bvh") || !strcmp(name, "bvh8") || !strcmp(name, "kdtree"); }

/* The default leaf size: an unbuilt node holds more references than that. */
static uint32_t leaf_size_of(const char *name)
{
    if (is_wide(name)) return 8;
    if (!is_kd(name)) return 3;
    return !strcmp(name, "kdtree") || !strcmp(name, "kdtree-binned") ? 1 : 4;
}
static const uint32_t lazy_sizes[] = {4, 32, 1};
#define NSIZES (sizeof lazy_sizes / sizeof lazy_sizes[0])
/* a wide tree leaves unbuilt only subtrees bigger than its largest leaf (8) */
static const uint32_t wide_sizes[] = {16, 32, 1};
static const uint32_t *sizes_of(size_t accel) { return is_wide(lazy_accels[accel]) ? wide_sizes : lazy_sizes; }

static size_t nrays(size_t full) { return tk_test_size(full); }

static uint32_t small_detail(const char *name)
{
    static const struct { const char *name; uint32_t detail; } d[] = {
        {"icosphere", 2}, {"teapot", 8}, {"stadium", 8}, {"soup", 300}, {"menger", 1}, {"flat2d", 4}, {"grid", 8},
        {"heightfield", 8},
    };
    for (size_t i = 0; i < sizeof d / sizeof d[0]; ++i)
        if (!strcmp(d[i].name, name)) return d[i].detail;
    return 0;
}

static int same_bits(float a, float b) { return memcmp(&a, &b, sizeof a) == 0; }

/* A wide lazy tree's top is collapsed around its unbuilt subtrees (their
 * cost is not known when it is built), so its wide nodes group the binary
 * tree's nodes otherwise than the eager tree's above them, and where a ray
 * hits two triangles at exactly the same t it may reach the other one
 * first.  Such a hit is accepted only as that: the same t, bit for bit,
 * and the triangle reported really hit by the ray at exactly that t. */
static int same_t(float a, float b)
{
    /* A hit at t = 0 (a ray starting on a triangle) comes out of the wide
     * walk's 4-triangle block test as -0 and out of its one-triangle test
     * as +0, and which test a triangle gets depends on the other triangles
     * of its block, which the two trees group otherwise. */
    return same_bits(a, b) || (a == 0.0f && b == 0.0f);
}

static int is_tie(const sidx_mesh *m, const sidx_ray *r, const sidx_hit *want, const sidx_hit *got)
{
    if (!same_t(want->t, got->t) || got->prim == SIDX_NO_HIT || want->prim == SIDX_NO_HIT ||
        got->prim >= m->num_triangles)
        return 0;
    float t, u, v;
    if (!sidx_intersect_triangle_watertight(r, sidx_mesh_vertex(m, got->prim, 0), sidx_mesh_vertex(m, got->prim, 1),
                                            sidx_mesh_vertex(m, got->prim, 2), INFINITY, &t, &u, &v))
        return 0;
    return same_t(t, got->t);
}

/* Bit-identical hits: what the suites mean by "the same hit". */
static int same_hit(const sidx_hit *a, const sidx_hit *b)
{
    return a->prim == b->prim && same_bits(a->t, b->t) && same_bits(a->u, b->u) && same_bits(a->v, b->v) &&
           same_bits(a->ng.x, b->ng.x) && same_bits(a->ng.y, b->ng.y) && same_bits(a->ng.z, b->ng.z);
}

static sidx_accel *build(const char *name, const sidx_mesh *m, uint32_t lazy, const sidx_hook *hook,
                         const sidx_allocator *al)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.lazy = lazy;
    bo.hook = hook;
    bo.alloc = al;
    sidx_accel *a = NULL;
    sidx_error err;
    if (sidx_accel_build(name, m, &bo, &a, &err) != SIDX_OK) fail_msg("%s: %s", name, err.message);
    return a;
}

/* ---- hits: every query kind on a fresh lazy tree ----------------------------- */

typedef struct rayset {
    sidx_ray *rays;
    size_t n;
    uint32_t w, h; /* the first w·h rays are a primary image, row-major */
} rayset;

static void make_rayset(const sidx_mesh *m, rayset *rs)
{
    static const tk_ray_kind kinds[] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE, TK_RAYS_SHADOW, TK_RAYS_GRAZING,
                                        TK_RAYS_AXIS};
    const size_t per = nrays(144);
    tk_rayrec *rec = malloc(5 * per * sizeof *rec);
    rs->rays = malloc(5 * per * sizeof *rs->rays);
    assert_true(rec && rs->rays);
    for (int k = 0; k < 5; ++k) tk_make_rays(m, kinds[k], per, 77 + (uint64_t)k, rec + (size_t)k * per);
    rs->n = 5 * per;
    for (size_t i = 0; i < rs->n; ++i) assert_int_equal(tk_ray_from(&rec[i], &rs->rays[i]), SIDX_OK);
    rs->w = 12;
    rs->h = (uint32_t)(per / 12);
    free(rec);
}

typedef enum { Q_STACK, Q_STACK_UV, Q_ORDERED, Q_NAIVE, Q_OCCLUDED, Q_N, Q_PACKET, Q_TILES, Q_THREADS, Q_TRACED,
               Q_COUNT } qkind;
static const char *const qnames[Q_COUNT] = {"stack", "stack+uv", "ordered", "naive", "occluded",
                                             "intersect_n", "packets", "tiles", "threads", "traced"};

/* Counts the events of a traced query and checks each build_lazy_expand. */
typedef struct expand_log {
    uint32_t expands, lazy_max, bad, leaf_size;
} expand_log;

static void on_event(const sidx_event *ev, void *user)
{
    expand_log *l = user;
    if (ev->type != SIDX_EV_BUILD_LAZY_EXPAND) return;
    l->expands++;
    /* an unbuilt node holds more than a leaf's primitives and at most the lazy size */
    if (!(ev->count > l->leaf_size && ev->count <= l->lazy_max)) l->bad++;
}

/* A kd-tree's leaves test whole blocks of four references, a neighbouring
 * leaf's lanes included (lib/kdtree_internal.h), and what those extra
 * lanes find decides ties and, through the early stop, which of two hits
 * an ulp or two apart is kept.  A lazy subtree's references start a block
 * of their own, so its leaves meet other neighbours: its hits are the
 * eager tree's up to rounding, not bit for bit.  This is such a hit: both
 * miss, or both hit at t no more than 1e-6·t apart (the traversal's 2γ₃
 * window) and the ray hits the lazy tree's triangle at exactly its t. */
static int kd_close_hit(const sidx_mesh *m, const sidx_ray *r, const sidx_hit *want, const sidx_hit *got)
{
    if (want->prim == SIDX_NO_HIT || got->prim == SIDX_NO_HIT) return want->prim == got->prim;
    if (got->prim >= m->num_triangles || !(fabsf(want->t - got->t) <= 1e-6f * fabsf(want->t))) return 0;
    float t, u, v;
    if (!sidx_intersect_triangle_watertight(r, sidx_mesh_vertex(m, got->prim, 0), sidx_mesh_vertex(m, got->prim, 1),
                                            sidx_mesh_vertex(m, got->prim, 2), INFINITY, &t, &u, &v))
        return 0;
    return t == got->t;
}

/* Hits of query kind k for every ray of rs on a. */
static sidx_status run_queries(const sidx_accel *a, const rayset *rs, qkind k, sidx_hit *hits, expand_log *log)
{
    sidx_status st = SIDX_OK;
    sidx_query q;
    memset(&q, 0, sizeof q);
    switch (k) {
    case Q_STACK_UV: q.flags = SIDX_QUERY_UV | SIDX_QUERY_NORMAL; break;
    case Q_ORDERED: q.traversal = SIDX_TRAVERSE_ORDERED; break;
    case Q_NAIVE: q.traversal = SIDX_TRAVERSE_NAIVE; break;
    default: break;
    }
    sidx_hook hook = {on_event, log, 0};
    if (k == Q_TRACED) q.hook = &hook;
    if (k == Q_N) return sidx_accel_intersect_n(a, rs->rays, rs->n, &q, hits);
    if (k == Q_THREADS) return sidx_trace_parallel(a, rs->rays, rs->n, &q, hits, 4);
    if (k == Q_TILES) {
        st = sidx_trace_tiles(a, rs->rays, rs->w, rs->h, 4, NULL, hits, NULL);
        const size_t img = (size_t)rs->w * rs->h;
        for (size_t i = img; i < rs->n; ++i)
            if (sidx_accel_intersect(a, &rs->rays[i], &q, &hits[i]) != SIDX_OK) st = SIDX_ERR_NOMEM;
        return st;
    }
    if (k == Q_PACKET) {
        for (size_t i = 0; i < rs->n; i += SIDX_PACKET_MAX) {
            const uint32_t c = (uint32_t)(rs->n - i < SIDX_PACKET_MAX ? rs->n - i : SIDX_PACKET_MAX);
            const sidx_status s = sidx_packet_intersect(a, rs->rays + i, c, 0, NULL, hits + i, NULL);
            if (s != SIDX_OK) st = s;
        }
        return st;
    }
    for (size_t i = 0; i < rs->n; ++i) {
        sidx_status s;
        if (k == Q_OCCLUDED) {
            int o = 0;
            s = sidx_accel_occluded(a, &rs->rays[i], &q, &o);
            hits[i] = sidx_hit_none();
            hits[i].prim = (uint32_t)o;
        } else {
            s = sidx_accel_intersect(a, &rs->rays[i], &q, &hits[i]);
        }
        if (s != SIDX_OK) st = s;
    }
    return st;
}

static unsigned compare_scene(const char *label, const sidx_mesh *m)
{
    unsigned failures = 0;
    size_t close = 0;
    rayset rs;
    make_rayset(m, &rs);
    sidx_hit *want = malloc(rs.n * sizeof *want), *got = malloc(rs.n * sizeof *got),
             *single = malloc(rs.n * sizeof *single), *again = malloc(rs.n * sizeof *again);
    assert_true(want && got && single && again);
    for (size_t s = 0; s < NACCELS; ++s) {
        /* the smallest sizes: one structure of each family (the builders
         * share its lazy code) */
        if (tk_tiny_tests() && !family_first(lazy_accels[s])) continue;
        sidx_accel *eager = build(lazy_accels[s], m, 0, NULL, NULL);
        expand_log elog = {0, 0, 0, 0};
        assert_int_equal(run_queries(eager, &rs, Q_STACK, single, &elog), SIDX_OK);
        for (int k = 0; k < Q_COUNT; ++k) {
            assert_int_equal(run_queries(eager, &rs, (qkind)k, want, &elog), SIDX_OK);
            /* Packets over a lazy tree go ray by ray (the packet walk reads
             * nodes as built), so they give the eager single-ray walk's
             * hits; the eager packet walk may take another triangle at
             * exactly the same t (coplanar triangles): same t bits then
             * (for the wide trees, a hit at t = 0 may be -0 or +0: same_t). */
            if (k == Q_PACKET || k == Q_TILES) {
                for (size_t i = 0; i < rs.n; ++i)
                    if (!same_bits(want[i].t, single[i].t) && !(is_wide(lazy_accels[s]) && same_t(want[i].t, single[i].t)))
                        fail_msg("%s, %s eager, %s: ray %zu t %a, single ray t %a", label, lazy_accels[s], qnames[k],
                                 i, (double)want[i].t, (double)single[i].t);
                memcpy(want, single, rs.n * sizeof *want);
            }
            for (size_t z = 0; z < NSIZES; ++z) {
                /* the small sizes: one subtree size per query kind, in turn (every size
                 * meets every query kind over the structures of a family) */
                if (tk_fast_tests() && z != (s + (size_t)k) % NSIZES) continue;
                const uint32_t size = sizes_of(s)[z];
                sidx_accel *lazy = build(lazy_accels[s], m, size, NULL, NULL);
                sidx_accel_stats before, after;
                sidx_accel_stats_get(lazy, &before);
                expand_log log = {0, size == 1 ? SIDX_LAZY_DEFAULT : size, 0, leaf_size_of(lazy_accels[s])};
                const sidx_status st = run_queries(lazy, &rs, (qkind)k, got, &log);
                sidx_accel_stats_get(lazy, &after);
                size_t bad = 0, first = 0;
                for (size_t i = 0; i < rs.n; ++i) {
                    if (same_hit(&want[i], &got[i])) continue;
                    if (is_wide(lazy_accels[s]) && k != Q_OCCLUDED && is_tie(m, &rs.rays[i], &want[i], &got[i]))
                        continue;
                    if (is_kd(lazy_accels[s]) && k != Q_OCCLUDED && kd_close_hit(m, &rs.rays[i], &want[i], &got[i])) {
                        close++;
                        continue;
                    }
                    if (bad++ == 0) first = i;
                }
                if (is_kd(lazy_accels[s])) {
                    /* the lazy tree's own hits do not depend on what was built when: the same
                     * queries again, every subtree they need built now, give the same bits */
                    const sidx_status st2 = run_queries(lazy, &rs, (qkind)k, again, &log);
                    for (size_t i = 0; i < rs.n; ++i)
                        if ((st2 != SIDX_OK || !same_hit(&again[i], &got[i])) && bad++ == 0) first = i;
                }
                if (st != SIDX_OK || bad || log.bad ||
                    (k == Q_TRACED && log.expands != before.unbuilt - after.unbuilt)) {
                    if (failures++ < 8)
                        print_message("%s, %s lazy %u, %s: status %d, %zu of %zu hits differ (first: ray %zu, "
                                      "prim %u t %a against %u t %a), %u expansions for %u nodes built, %u bad\n",
                                      label, lazy_accels[s], (unsigned)size, qnames[k], (int)st, bad, rs.n,
                                      first, got[first].prim, (double)got[first].t, want[first].prim,
                                      (double)want[first].t, log.expands, before.unbuilt - after.unbuilt, log.bad);
                }
                sidx_accel_destroy(lazy);
            }
        }
        sidx_accel_destroy(eager);
    }
    if (close) print_message("%s: %zu kd-tree hits the eager tree's up to rounding only\n", label, close);
    free(again);
    free(want);
    free(got);
    free(single);
    free(rs.rays);
    return failures;
}

static void hits_equal_on_builtin_scenes(void **state)
{
    (void)state;
    unsigned failures = 0;
    for (const char *const *s = sidx_scene_names(); *s; ++s) {
        sidx_mesh m;
        assert_int_equal(sidx_scene_make(*s, small_detail(*s), &m, NULL), SIDX_OK);
        failures += compare_scene(*s, &m);
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

static void hits_equal_on_stress_scenes(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const char *const scenes[] = {"teapot", "icosphere", "menger", "soup"};
    static const char *const transforms[] = {"x100 at +1e6", "x1e-6", "duplicated", "flattened"};
    for (size_t s = 0; s < sizeof scenes / sizeof scenes[0]; ++s) {
        sidx_mesh m, t;
        assert_int_equal(sidx_scene_make(scenes[s], small_detail(scenes[s]), &m, NULL), SIDX_OK);
        for (size_t x = 0; x < 4; ++x) {
            if (tk_fast_tests() && x != s % 4) continue; /* the small sizes: one transform per scene */
            sidx_status st;
            switch (x) {
            case 0: st = tk_mesh_transform(&m, 100.0, sidx_v3(1e6f, 1e6f, -1e6f), &t); break;
            case 1: st = tk_mesh_transform(&m, 1e-6, sidx_v3(0, 0, 0), &t); break;
            case 2: st = tk_mesh_duplicate_tris(&m, &t); break;
            default: st = tk_mesh_flatten(&m, 0.5f, &t); break;
            }
            assert_int_equal(st, SIDX_OK);
            char label[64];
            snprintf(label, sizeof label, "%s %s", scenes[s], transforms[x]);
            failures += compare_scene(label, &t);
            sidx_mesh_free(&t);
        }
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* ---- the same tree ------------------------------------------------------------ */

/* A build's decisions, node ids left out (the lazy tree numbers its nodes
 * otherwise): splits as (depth, axis, pos, cost, left, right), leaves as
 * (depth, count, their primitive ids in order). */
typedef struct decisions {
    char **items;
    size_t n, cap;
    /* BUILD_NODE boxes by node id, and whether a split or leaf followed */
    sidx_aabb *box;
    uint32_t *depth;
    unsigned char *decided, *seen;
    uint32_t nodes_cap;
} decisions;

static void add_item(decisions *d, const char *s)
{
    if (d->n == d->cap) {
        d->cap = d->cap ? 2 * d->cap : 256;
        d->items = realloc(d->items, d->cap * sizeof *d->items);
        assert_non_null(d->items);
    }
    d->items[d->n] = malloc(strlen(s) + 1);
    assert_non_null(d->items[d->n]);
    strcpy(d->items[d->n++], s);
}

static void on_decision(const sidx_event *ev, void *user)
{
    decisions *d = user;
    char buf[4096];
    if (ev->node != UINT32_MAX && ev->node >= d->nodes_cap) return;
    if (ev->type == SIDX_EV_BUILD_NODE) {
        d->box[ev->node] = ev->bounds;
        d->depth[ev->node] = ev->depth;
        d->seen[ev->node] = 1;
    } else if (ev->type == SIDX_EV_BUILD_SPLIT) {
        d->decided[ev->node] = 1;
        snprintf(buf, sizeof buf, "split d%u axis %d pos %a cost %a %u|%u", d->depth[ev->node], ev->axis,
                 (double)ev->pos, (double)ev->cost, ev->count, ev->aux);
        add_item(d, buf);
    } else if (ev->type == SIDX_EV_BUILD_LEAF) {
        d->decided[ev->node] = 1;
        int at = snprintf(buf, sizeof buf, "leaf d%u n%u reason %d:", ev->depth, ev->count, ev->reason);
        for (uint32_t i = 0; i < ev->count && at < (int)sizeof buf - 16; ++i)
            at += snprintf(buf + at, sizeof buf - (size_t)at, " %u", ev->prims[i]);
        add_item(d, buf);
    }
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static void decisions_init(decisions *d, uint32_t nodes_cap)
{
    memset(d, 0, sizeof *d);
    d->nodes_cap = nodes_cap;
    d->box = calloc(nodes_cap, sizeof *d->box);
    d->depth = calloc(nodes_cap, sizeof *d->depth);
    d->decided = calloc(nodes_cap, 1);
    d->seen = calloc(nodes_cap, 1);
    assert_true(d->box && d->depth && d->decided && d->seen);
}

static void decisions_free(decisions *d)
{
    for (size_t i = 0; i < d->n; ++i) free(d->items[i]);
    free(d->items);
    free(d->box);
    free(d->depth);
    free(d->decided);
    free(d->seen);
}

/* One traced ray from the centre of box, in direction d, through the lazy
 * tree: it starts inside that box and every box above it. */
static void shoot_from_box(const sidx_accel *lazy, sidx_aabb box, sidx_vec3 d, sidx_traversal walk, const sidx_hook *hook)
{
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_aabb_centroid(box), d, 0.0f, INFINITY), SIDX_OK);
    const sidx_query q = {0, walk, hook, 0};
    sidx_hit h;
    assert_int_equal(sidx_accel_intersect(lazy, &r, &q, &h), SIDX_OK);
}

/* Before any ray: prim_refs counts the references in built leaves only,
 * unbuilt_prims those of the unbuilt subtrees, so that the fraction built
 * P / (P + U) lies in [0, 1].  The expansions only add references (kd-tree
 * and spatial splits duplicate), so P + U is at most the eager tree's
 * count, and P is below it while something is unbuilt. */
static unsigned refs_split_case(const char *label, const char *name, uint32_t lazy_size, const sidx_accel_stats *s0,
                                const sidx_accel_stats *se)
{
    if (s0->prim_refs + s0->unbuilt_prims <= se->prim_refs && !(s0->unbuilt && s0->prim_refs >= se->prim_refs))
        return 0;
    print_message("%s, %s lazy %u: before any ray %llu references built + %llu unbuilt, eager %llu\n", label, name,
                  (unsigned)lazy_size, (unsigned long long)s0->prim_refs, (unsigned long long)s0->unbuilt_prims,
                  (unsigned long long)se->prim_refs);
    return 1;
}

static unsigned same_tree_case(const char *label, const char *name, const sidx_mesh *m, uint32_t lazy_size)
{
    /* node ids stay below 2·triangles + 2 (the BVH's slots) and below the
     * eager tree's node count (a kd-tree's may exceed 2·triangles) */
    sidx_accel *count_it = build(name, m, 0, NULL, NULL);
    sidx_accel_stats sc;
    sidx_accel_stats_get(count_it, &sc);
    sidx_accel_destroy(count_it);
    const uint32_t cap = sc.nodes > 2 * m->num_triangles ? sc.nodes + 2 : 2 * m->num_triangles + 2;
    decisions de, dl;
    decisions_init(&de, cap);
    decisions_init(&dl, cap);
    sidx_hook he = {on_decision, &de, SIDX_EVMASK_BUILD}, hl = {on_decision, &dl, SIDX_EVMASK_BUILD};
    sidx_accel *eager = build(name, m, 0, &he, NULL), *lazy = build(name, m, lazy_size, &hl, NULL);
    sidx_accel_stats se, sl;
    sidx_accel_stats_get(lazy, &sl);
    unsigned failures = 0;
    if (sl.unbuilt == 0 && lazy_size >= 32) {
        print_message("%s, %s lazy %u: nothing left unbuilt\n", label, name, (unsigned)lazy_size);
        failures++;
    }
    sidx_accel_stats_get(eager, &se);
    failures += refs_split_case(label, name, lazy_size, &sl, &se);
    /* Enter every unbuilt node: a ray from its box's centre starts inside
     * it and inside every box above it, and the naive walk enters every
     * box it starts in, even after a hit at t = 0 (the centre of a flat
     * box may lie on a triangle).  An expansion builds its whole subtree. */
    for (uint32_t i = 0; i < cap; ++i)
        if (dl.seen[i] && !dl.decided[i]) shoot_from_box(lazy, dl.box[i], sidx_v3(0.3f, 0.5f, 0.7f), SIDX_TRAVERSE_NAIVE, &hl);
    sidx_accel_stats_get(eager, &se);
    sidx_accel_stats_get(lazy, &sl);
    qsort(de.items, de.n, sizeof *de.items, cmp_str);
    qsort(dl.items, dl.n, sizeof *dl.items, cmp_str);
    int same = de.n == dl.n;
    for (size_t i = 0; same && i < de.n; ++i) same = !strcmp(de.items[i], dl.items[i]);
    if (!same || sl.unbuilt != 0 || sl.unbuilt_prims != 0 || se.nodes != sl.nodes || se.leaves != sl.leaves ||
        se.max_depth != sl.max_depth || se.prim_refs != sl.prim_refs || se.empty_leaves != sl.empty_leaves) {
        print_message("%s, %s lazy %u: %zu decisions against %zu eager (%s), %u unbuilt left, nodes %u/%u leaves "
                      "%u/%u empty %u/%u depth %u/%u references %llu/%llu\n",
                      label, name, (unsigned)lazy_size, dl.n, de.n, same ? "same" : "different", sl.unbuilt,
                      sl.nodes, se.nodes, sl.leaves, se.leaves, sl.empty_leaves, se.empty_leaves, sl.max_depth,
                      se.max_depth, (unsigned long long)sl.prim_refs, (unsigned long long)se.prim_refs);
        failures++;
    }
    sidx_accel_destroy(eager);
    sidx_accel_destroy(lazy);
    decisions_free(&de);
    decisions_free(&dl);
    return failures;
}

/* The wide trees: every leaf's references (their triangles, a triangle
 * in several leaves after spatial splits), from the build's events and the
 * expansions', as one sorted list. */
typedef struct leaf_refs {
    uint32_t *prim;
    size_t n, cap;
    sidx_aabb *box;
    unsigned char *seen, *leaf;
    uint32_t nodes_cap, expands;
} leaf_refs;

static void on_leaf(const sidx_event *ev, void *user)
{
    leaf_refs *l = user;
    if (ev->type == SIDX_EV_BUILD_LAZY_EXPAND) l->expands++;
    if (ev->node == UINT32_MAX || ev->node >= l->nodes_cap) return;
    if (ev->type == SIDX_EV_BUILD_NODE) {
        l->box[ev->node] = ev->bounds;
        l->seen[ev->node] = 1;
    } else if (ev->type == SIDX_EV_BUILD_LEAF) {
        l->leaf[ev->node] = 1;
        for (uint32_t i = 0; i < ev->count; ++i) {
            if (l->n == l->cap) {
                l->cap = l->cap ? 2 * l->cap : 1024;
                l->prim = realloc(l->prim, l->cap * sizeof *l->prim);
                assert_non_null(l->prim);
            }
            l->prim[l->n++] = ev->prims[i];
        }
    }
}

static int cmp_u32(const void *a, const void *b)
{
    const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static unsigned same_refs_case(const char *label, const char *name, const sidx_mesh *m, uint32_t lazy_size)
{
    const uint32_t cap = 4 * m->num_triangles + 16;
    leaf_refs le, ll;
    memset(&le, 0, sizeof le);
    memset(&ll, 0, sizeof ll);
    ll.nodes_cap = le.nodes_cap = cap;
    le.box = calloc(cap, sizeof *le.box);
    ll.box = calloc(cap, sizeof *ll.box);
    le.seen = calloc(cap, 1);
    ll.seen = calloc(cap, 1);
    le.leaf = calloc(cap, 1);
    ll.leaf = calloc(cap, 1);
    assert_true(le.box && ll.box && le.seen && ll.seen && le.leaf && ll.leaf);
    sidx_hook he = {on_leaf, &le, SIDX_EVMASK_BUILD}, hl = {on_leaf, &ll, SIDX_EVMASK_BUILD};
    sidx_accel *eager = build(name, m, 0, &he, NULL), *lazy = build(name, m, lazy_size, &hl, NULL);
    sidx_accel_stats se, sl, s0;
    sidx_accel_stats_get(lazy, &s0);
    unsigned failures = 0;
    if (s0.unbuilt == 0) {
        print_message("%s, %s lazy %u: nothing left unbuilt\n", label, name, (unsigned)lazy_size);
        failures++;
    }
    sidx_accel_stats_get(eager, &se);
    failures += refs_split_case(label, name, lazy_size, &s0, &se);
    /* Enter every unbuilt child: rays from the centre of every node that
     * is not a leaf, in a few directions (a wide walk stops at a hit at
     * t = 0 on a triangle through the centre, so one may not be enough). */
    static const float dirs[4][3] = {{0.3f, 0.5f, 0.7f}, {-0.6f, 0.2f, -0.4f}, {0.1f, -0.9f, 0.3f}, {-0.2f, -0.3f, -0.8f}};
    for (int d = 0; d < 4; ++d) {
        sidx_accel_stats_get(lazy, &sl);
        if (sl.unbuilt == 0) break;
        for (uint32_t i = 0; i < cap; ++i)
            if (ll.seen[i] && !ll.leaf[i])
                shoot_from_box(lazy, ll.box[i], sidx_v3(dirs[d][0], dirs[d][1], dirs[d][2]), SIDX_TRAVERSE_DEFAULT, &hl);
    }
    sidx_accel_stats_get(eager, &se);
    sidx_accel_stats_get(lazy, &sl);
    qsort(le.prim, le.n, sizeof *le.prim, cmp_u32);
    qsort(ll.prim, ll.n, sizeof *ll.prim, cmp_u32);
    const int same = le.n == ll.n && (le.n == 0 || !memcmp(le.prim, ll.prim, le.n * sizeof *le.prim));
    if (!same || sl.unbuilt != 0 || sl.unbuilt_prims != 0 || se.prim_refs != sl.prim_refs ||
        ll.expands != s0.unbuilt) {
        print_message("%s, %s lazy %u: %zu leaf references against %zu eager (%s), %u unbuilt left, references "
                      "%llu/%llu, %u expansions for %u unbuilt\n",
                      label, name, (unsigned)lazy_size, ll.n, le.n, same ? "same" : "different", sl.unbuilt,
                      (unsigned long long)sl.prim_refs, (unsigned long long)se.prim_refs, ll.expands, s0.unbuilt);
        failures++;
    }
    sidx_accel_destroy(eager);
    sidx_accel_destroy(lazy);
    free(le.prim);
    free(ll.prim);
    free(le.box);
    free(ll.box);
    free(le.seen);
    free(ll.seen);
    free(le.leaf);
    free(ll.leaf);
    return failures;
}

static void expanded_tree_is_the_eager_tree(void **state)
{
    (void)state;
    unsigned failures = 0;
    static const char *const scenes[] = {"teapot", "stadium", "soup", "menger", "grid"};
    for (size_t s = 0; s < sizeof scenes / sizeof scenes[0]; ++s) {
        sidx_mesh m;
        assert_int_equal(sidx_scene_make(scenes[s], small_detail(scenes[s]), &m, NULL), SIDX_OK);
        /* the smallest sizes: each structure and size on every other scene */
        for (size_t a = 0; a < NACCELS; ++a)
            if (!is_wide(lazy_accels[a]))
                for (size_t z = 0; z < 2; ++z)
                    if (!tk_tiny_tests() || (s + a + z) % 2 == 0)
                        failures += same_tree_case(scenes[s], lazy_accels[a], &m, lazy_sizes[z]);
        /* the wide trees: the binary tree under them is the eager one, so
         * their leaves hold the same references (the grouping above the
         * unbuilt subtrees differs: see is_tie) */
        for (size_t a = 0; a < NACCELS; ++a)
            if (is_wide(lazy_accels[a]))
                for (size_t z = 0; z < 2; ++z)
                    failures += same_refs_case(scenes[s], lazy_accels[a], &m, wide_sizes[z]);
        sidx_mesh_free(&m);
    }
    assert_int_equal(failures, 0);
}

/* A tree whose every node is unbuilt but the root's children: the root
 * is expanded, then its... (the root alone when the size covers the scene). */
static void root_unbuilt_and_stats(void **state)
{
    (void)state;
    sidx_mesh m;
    assert_int_equal(sidx_scene_make("teapot", 8, &m, NULL), SIDX_OK);
    for (size_t a = 0; a < NACCELS; ++a) {
        /* a wide tree: a root node with the unbuilt subtree as its one child */
        const uint32_t top = is_wide(lazy_accels[a]) ? 2 : 1;
        sidx_accel *lazy = build(lazy_accels[a], &m, m.num_triangles, NULL, NULL);
        sidx_accel_stats s;
        sidx_accel_stats_get(lazy, &s);
        assert_int_equal(s.unbuilt, 1);
        assert_int_equal(s.unbuilt_prims, m.num_triangles);
        assert_int_equal(s.nodes, top);
        assert_int_equal(s.leaves, 0);
        sidx_ray r;
        const sidx_aabb b = sidx_mesh_bounds(&m);
        assert_int_equal(sidx_ray_init(&r, sidx_aabb_centroid(b), sidx_v3(0, 0, 1), 0.0f, INFINITY), SIDX_OK);
        expand_log log = {0, m.num_triangles, 0, leaf_size_of(lazy_accels[a])};
        sidx_hook hook = {on_event, &log, SIDX_EVMASK(SIDX_EV_BUILD_LAZY_EXPAND)};
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
        sidx_hit h;
        assert_int_equal(sidx_accel_intersect(lazy, &r, &q, &h), SIDX_OK);
        assert_int_equal(log.expands, 1);
        assert_int_equal(log.bad, 0);
        sidx_accel_stats_get(lazy, &s);
        assert_int_equal(s.unbuilt, 0);
        assert_int_equal(s.unbuilt_prims, 0);
        assert_true(s.nodes > top);
        if (is_wide(lazy_accels[a])) { /* the subtree is the whole eager tree, under the root node */
            sidx_accel *eager = build(lazy_accels[a], &m, 0, NULL, NULL);
            sidx_accel_stats se;
            sidx_accel_stats_get(eager, &se);
            assert_int_equal(s.nodes, se.nodes + 1);
            assert_int_equal(s.leaves, se.leaves);
            assert_int_equal(s.prim_refs, se.prim_refs);
            assert_int_equal(s.max_depth, se.max_depth + 1);
            sidx_accel_destroy(eager);
        }
        /* a second ray builds nothing more */
        assert_int_equal(sidx_accel_intersect(lazy, &r, &q, &h), SIDX_OK);
        assert_int_equal(log.expands, 1);
        /* the node arrays of a lazy tree change under the caller: not handed out */
        const sidx_bvh_node *nodes;
        const sidx_kd_node *kd_nodes;
        const uint32_t *kd_refs;
        uint32_t count;
        if (is_kd(lazy_accels[a])) {
            assert_int_equal(sidx_kdtree_nodes(lazy, &kd_nodes, &count, NULL), SIDX_ERR_UNSUPPORTED);
            assert_int_equal(sidx_kdtree_refs(lazy, &kd_refs, &count, NULL), SIDX_ERR_UNSUPPORTED);
        } else if (!is_wide(lazy_accels[a])) {
            assert_int_equal(sidx_bvh_nodes(lazy, &nodes, &count, NULL), SIDX_ERR_UNSUPPORTED);
        }
        sidx_accel_destroy(lazy);
    }
    sidx_mesh_free(&m);
}

/* ---- threads racing into one unbuilt node -------------------------------------- */

#define RACERS 4

static void threads_race_into_the_same_node(void **state)
{
    (void)state;
    sidx_mesh m;
    assert_int_equal(sidx_scene_make("teapot", 0, &m, NULL), SIDX_OK);
    rayset rs;
    make_rayset(&m, &rs);
    sidx_hit *want = malloc(rs.n * sizeof *want), *got = malloc(RACERS * rs.n * sizeof *got);
    assert_true(want && got);
    const int rounds = tk_fast_tests() ? 3 : 10;
    static const char *const racers[] = {"bvh", "bvh-sweep", "bvh4", "bvh8", "kdtree"};
    for (size_t a = 0; a < sizeof racers / sizeof racers[0]; ++a) {
        sidx_accel *eager = build(racers[a], &m, 0, NULL, NULL);
        assert_int_equal(sidx_accel_intersect_n(eager, rs.rays, rs.n, NULL, want), SIDX_OK);
        /* the whole scene in one unbuilt root, then a tree of small unbuilt nodes */
        for (int round = 0; round < rounds; ++round) {
            const uint32_t size = round & 1 ? 16 : m.num_triangles;
            if (is_kd(racers[a])) {
                /* a lazy kd-tree's hits are the eager one's up to rounding (kd_close_hit),
                 * and its own on one thread, bit for bit */
                sidx_accel *one = build(racers[a], &m, size, NULL, NULL);
                assert_int_equal(sidx_accel_intersect_n(one, rs.rays, rs.n, NULL, want), SIDX_OK);
                sidx_accel_destroy(one);
            }
            sidx_accel *lazy = build(racers[a], &m, size, NULL, NULL);
            /* every thread starts on the same ray, then goes its own way through the set */
            assert_int_equal(tk_race_intersect(lazy, rs.rays, rs.n, RACERS, got), SIDX_OK);
            for (int t = 0; t < RACERS; ++t) {
                for (size_t i = 0; i < rs.n; ++i)
                    if (!same_hit(&want[i], &got[(size_t)t * rs.n + i]) &&
                        !(is_wide(racers[a]) && is_tie(&m, &rs.rays[i], &want[i], &got[(size_t)t * rs.n + i])))
                        fail_msg("%s round %d thread %d ray %zu: prim %u t %a against %u t %a", racers[a], round,
                                 t, i, got[(size_t)t * rs.n + i].prim, (double)got[(size_t)t * rs.n + i].t,
                                 want[i].prim, (double)want[i].t);
            }
            sidx_accel_destroy(lazy);
        }
        sidx_accel_destroy(eager);
    }
    free(want);
    free(got);
    free(rs.rays);
    sidx_mesh_free(&m);
}

/* ---- out of memory during an expansion ------------------------------------------ */

static void out_of_memory_is_the_query_s_error(void **state)
{
    (void)state;
    sidx_mesh m;
    assert_int_equal(sidx_scene_make("teapot", 8, &m, NULL), SIDX_OK);
    const sidx_aabb b = sidx_mesh_bounds(&m);
    sidx_ray r, rays[16];
    assert_int_equal(sidx_ray_init(&r, sidx_v3(b.min.x - 1, sidx_aabb_centroid(b).y, sidx_aabb_centroid(b).z),
                                   sidx_v3(1, 0.01f, 0.02f), 0.0f, INFINITY),
                     SIDX_OK);
    for (int i = 0; i < 16; ++i) rays[i] = r;
    for (size_t a = 0; a < NACCELS; ++a) {
        if (tk_tiny_tests() && !family_first(lazy_accels[a])) continue;
        /* a wide tree: a root node with the unbuilt subtree as its one child;
         * its expansion makes a binary and a wide tree, so more allocations */
        const uint32_t top = is_wide(lazy_accels[a]) ? 2 : 1;
        const long most = is_wide(lazy_accels[a]) ? 64 : 7;
        sidx_accel *eager = build(lazy_accels[a], &m, 0, NULL, NULL);
        sidx_hit want;
        int want_occ;
        assert_int_equal(sidx_accel_intersect(eager, &r, NULL, &want), SIDX_OK);
        assert_int_equal(sidx_accel_occluded(eager, &r, NULL, &want_occ), SIDX_OK);
        assert_int_not_equal(want.prim, SIDX_NO_HIT);
        /* the k-th allocation of the expansion fails, for every k it makes (a
         * kd-tree's expansion makes one or more per node: k grows by steps) */
        const int kd = is_kd(lazy_accels[a]);
        for (long k = 0; k < (kd ? 1000000 : most + 1); k += kd ? 1 + k / 4 : 1) {
            tk_failing f = {1000000, 0};
            sidx_allocator al = tk_failing_allocator(&f);
            sidx_accel *lazy = build(lazy_accels[a], &m, m.num_triangles, NULL, &al);
            f.left = k;
            const long live = f.live;
            sidx_hit h;
            int occ = -1;
            uint8_t pocc[16];
            sidx_hit ph[16];
            const sidx_status s1 = sidx_accel_intersect(lazy, &r, NULL, &h);
            sidx_accel_stats st;
            sidx_accel_stats_get(lazy, &st);
            if (s1 == SIDX_OK) {
                /* k allocations were enough: built, and the eager hit */
                assert_int_equal(st.unbuilt, 0);
                assert_true(same_hit(&h, &want));
                assert_true(k > 0);
                sidx_accel_destroy(lazy);
                assert_int_equal(f.live, 0);
                break;
            }
            assert_int_equal(s1, SIDX_ERR_NOMEM);
            /* nothing half built, no scratch left behind */
            assert_int_equal(st.unbuilt, 1);
            assert_int_equal(st.nodes, top);
            assert_int_equal(f.live, live);
            f.left = k; /* the same failure for every other query kind */
            assert_int_equal(sidx_accel_occluded(lazy, &r, NULL, &occ), SIDX_ERR_NOMEM);
            f.left = k;
            assert_int_equal(sidx_accel_intersect_n(lazy, rays, 16, NULL, ph), SIDX_ERR_NOMEM);
            f.left = k;
            assert_int_equal(sidx_packet_intersect(lazy, rays, 16, 4, NULL, ph, NULL), SIDX_ERR_NOMEM);
            f.left = k;
            assert_int_equal(sidx_packet_occluded(lazy, rays, 16, 4, NULL, pocc, NULL), SIDX_ERR_NOMEM);
            f.left = k;
            assert_int_equal(sidx_trace_tiles(lazy, rays, 4, 4, 4, NULL, ph, NULL), SIDX_ERR_NOMEM);
            f.left = k;
            assert_int_equal(sidx_trace_parallel(lazy, rays, 16, NULL, ph, 2), SIDX_ERR_NOMEM);
            f.left = k;
            assert_int_equal(sidx_occluded_parallel(lazy, rays, 16, NULL, pocc, 2), SIDX_ERR_NOMEM);
            sidx_accel_stats_get(lazy, &st);
            assert_int_equal(st.unbuilt, 1);
            assert_int_equal(f.live, live);
            /* with memory again: built now, the eager hit */
            f.left = 1000000;
            assert_int_equal(sidx_accel_intersect(lazy, &r, NULL, &h), SIDX_OK);
            assert_true(same_hit(&h, &want));
            assert_int_equal(sidx_accel_occluded(lazy, &r, NULL, &occ), SIDX_OK);
            assert_int_equal(occ, want_occ);
            sidx_accel_stats_get(lazy, &st);
            assert_int_equal(st.unbuilt, 0);
            sidx_accel_destroy(lazy);
            assert_int_equal(f.live, 0);
            if (!kd) assert_true(k < most); /* an expansion makes fewer than `most` allocations */
        }
        sidx_accel_destroy(eager);
    }
    sidx_mesh_free(&m);
}

/* ---- the build itself ---------------------------------------------------------------- */

static void build_out_of_memory_leaks_nothing(void **state)
{
    (void)state;
    sidx_mesh m;
    assert_int_equal(sidx_scene_make("teapot", 8, &m, NULL), SIDX_OK);
    for (size_t a = 0; a < NACCELS; ++a) {
        const int kd = is_kd(lazy_accels[a]);
        for (long k = 0;; k += kd ? 1 + k / 8 : 1) {
            tk_failing f = {k, 0};
            sidx_allocator al = tk_failing_allocator(&f);
            sidx_build_options bo;
            memset(&bo, 0, sizeof bo);
            bo.lazy = 16;
            bo.alloc = &al;
            sidx_accel *acc = NULL;
            const sidx_status s = sidx_accel_build(lazy_accels[a], &m, &bo, &acc, NULL);
            if (s == SIDX_OK) {
                sidx_accel_destroy(acc);
                assert_int_equal(f.live, 0);
                break;
            }
            assert_int_equal(s, SIDX_ERR_NOMEM);
            assert_null(acc);
            assert_int_equal(f.live, 0);
            assert_true(k < (kd ? 100000 : 64));
        }
    }
    sidx_mesh_free(&m);
    /* a lazy build that leaves nothing unbuilt (8 triangles: one wide
     * leaf, no subtree worth waiting for) gives back all it took too */
    assert_int_equal(sidx_scene_make("kd-slide", 0, &m, NULL), SIDX_OK);
    assert_true(m.num_triangles <= 8);
    for (size_t a = 0; a < NACCELS; ++a) {
        tk_failing f = {1000000, 0};
        sidx_allocator al = tk_failing_allocator(&f);
        sidx_accel *acc = build(lazy_accels[a], &m, 16, NULL, &al);
        sidx_accel_stats st;
        sidx_accel_stats_get(acc, &st);
        if (is_wide(lazy_accels[a])) assert_int_equal(st.unbuilt, 0);
        sidx_accel_destroy(acc);
        if (f.live != 0) fail_msg("%s: %ld allocations not given back", lazy_accels[a], f.live);
    }
    sidx_mesh_free(&m);
}

int main(void)
{
    /* a walk into a half-built node may loop: a hang fails the suite (SIGALRM) */
    alarm(1800);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(hits_equal_on_builtin_scenes),
        cmocka_unit_test(hits_equal_on_stress_scenes),
        cmocka_unit_test(expanded_tree_is_the_eager_tree),
        cmocka_unit_test(root_unbuilt_and_stats),
        cmocka_unit_test(threads_race_into_the_same_node),
        cmocka_unit_test(out_of_memory_is_the_query_s_error),
        cmocka_unit_test(build_out_of_memory_leaks_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
