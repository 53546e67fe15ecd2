/* test_instance.c — aggregates and instancing: 10,000 instances of one
 * icosphere BVH trace like the flattened scene (every instance's triangles
 * transformed and copied into one mesh) for random rays, with one copy of
 * the sphere's structure in memory; the issue's own case, 10,000 instances
 * of the Stanford bunny's BVH (when $SIDX_SCENES names the directory of
 * bunny.obj; skipped otherwise) against a per-instance reference; nested
 * aggregates; u, v and world normals; events; argument errors. */
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
#include "sidx/instance.h"
#include "common/testkit.h"

static const char *child_structure(void) { return sidx_accel_is_registered("bvh") ? "bvh" : "brute"; }

/* random rotation (unit quaternion), non-uniform scale in [0.5, 1.5], translation in [-L, L]^3 */
static void random_xform(tk_rng *g, float L, float m[12])
{
    double q[4], n = 0.0;
    for (int i = 0; i < 4; ++i) { q[i] = tk_rng_range(g, -1, 1); n += q[i] * q[i]; }
    n = sqrt(n);
    for (int i = 0; i < 4; ++i) q[i] /= n;
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                         2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
    double s[3]; /* one draw per statement: an initializer list's order is unspecified too */
    for (int k = 0; k < 3; ++k) s[k] = tk_rng_range(g, 0.5, 1.5);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m[4 * r + c] = (float)(R[3 * r + c] * s[c]); /* R·S */
        m[4 * r + 3] = (float)tk_rng_range(g, -L, L);
    }
}

static sidx_vec3 apply(const float m[12], sidx_vec3 p)
{
    return sidx_v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                   m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}

/* The flattened scene: leaf instance i's triangles at i·T .. i·T + T − 1. */
static void flatten(const sidx_accel *agg, const sidx_mesh *obj, sidx_mesh *out)
{
    const uint32_t n = sidx_aggregate_leaf_count(agg), V = obj->num_vertices, T = obj->num_triangles;
    float *xyz = malloc((size_t)n * V * 3 * sizeof *xyz);
    uint32_t *idx = malloc((size_t)n * T * 3 * sizeof *idx);
    assert_true(xyz && idx);
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_accel *leaf;
        float m[12];
        assert_int_equal(sidx_aggregate_leaf(agg, i, &leaf, m), SIDX_OK);
        assert_ptr_equal(sidx_accel_mesh(leaf), obj);
        for (uint32_t v = 0; v < V; ++v) {
            const sidx_vec3 p = apply(m, obj->positions[v]);
            xyz[3 * ((size_t)i * V + v) + 0] = p.x;
            xyz[3 * ((size_t)i * V + v) + 1] = p.y;
            xyz[3 * ((size_t)i * V + v) + 2] = p.z;
        }
        for (uint32_t k = 0; k < 3 * T; ++k) idx[(size_t)i * 3 * T + k] = obj->indices[k] + i * V;
    }
    assert_int_equal(sidx_mesh_from_arrays(out, xyz, n * V, idx, n * T, NULL), SIDX_OK);
    free(xyz);
    free(idx);
}

/* rays: half aimed at random leaf instances' centres, half random */
static void make_rays(tk_rng *g, const sidx_aabb world, const sidx_accel *agg, size_t n, sidx_ray *rays)
{
    const sidx_vec3 c = sidx_aabb_centroid(world), e = sidx_aabb_extent(world);
    const uint32_t leaves = sidx_aggregate_leaf_count(agg);
    for (size_t i = 0; i < n; ++i) {
        /* one draw per statement, z first: the order gcc evaluated the
         * arguments in (C leaves it open) */
        const float rz = (float)tk_rng_range(g, -0.8, 0.8), ry = (float)tk_rng_range(g, -0.8, 0.8),
                    rx = (float)tk_rng_range(g, -0.8, 0.8);
        sidx_vec3 o = sidx_v3_add(c, sidx_v3(rx * e.x, ry * e.y, rz * e.z));
        if (i % 4 == 0) o = sidx_v3_add(c, sidx_v3_scale(tk_rng_sphere(g), 1.5f * sidx_v3_length(e))); /* from outside */
        sidx_vec3 d;
        if (i % 2 == 0) {
            const sidx_accel *leaf;
            float m[12];
            sidx_aggregate_leaf(agg, tk_rng_below(g, leaves), &leaf, m);
            d = sidx_v3_sub(sidx_v3(m[3], m[7], m[11]), o);
        } else {
            d = tk_rng_sphere(g);
        }
        d = sidx_v3_scale(d, (float)tk_rng_range(g, 0.3, 3.0)); /* any length: t must not care */
        assert_int_equal(sidx_ray_init(&rays[i], o, d, 0.0f, INFINITY), SIDX_OK);
    }
}

static void compare(const sidx_accel *agg, const sidx_accel *flat, const sidx_ray *rays, size_t n, uint32_t T,
                    size_t *hits_out)
{
    size_t hits = 0;
    for (size_t i = 0; i < n; ++i) {
        sidx_hit ref, got;
        sidx_accel_intersect(flat, &rays[i], NULL, &ref);
        sidx_accel_intersect(agg, &rays[i], NULL, &got);
        sidx_hit g2 = got;
        if (got.prim != SIDX_NO_HIT) g2.prim = got.instance * T + got.prim;
        else assert_int_equal(got.instance, SIDX_NO_HIT);
        if (!tk_hits_agree(&ref, &g2))
            fprintf(stderr, "ray %zu: flattened prim %u t %.9g; instanced instance %u prim %u t %.9g\n", i, ref.prim,
                    ref.t, got.instance, got.prim, got.t);
        assert_true(tk_hits_agree(&ref, &g2));
        int o1, o2;
        sidx_accel_occluded(flat, &rays[i], NULL, &o1);
        sidx_accel_occluded(agg, &rays[i], NULL, &o2);
        assert_int_equal(o1, o2);
        hits += ref.prim != SIDX_NO_HIT;
    }
    if (hits_out) *hits_out = hits;
}

static void ten_thousand_instances(void **state)
{
    (void)state;
    const uint32_t N = 10000;
    sidx_mesh sphere;
    assert_int_equal(sidx_scene_make("icosphere", 1, &sphere, NULL), SIDX_OK); /* 80 triangles */
    sidx_accel *child = NULL;
    assert_int_equal(sidx_accel_build(child_structure(), &sphere, NULL, &child, NULL), SIDX_OK);
    sidx_instance *inst = malloc(N * sizeof *inst);
    assert_non_null(inst);
    tk_rng g;
    tk_rng_seed(&g, 2024);
    for (uint32_t i = 0; i < N; ++i) {
        inst[i].accel = child;
        random_xform(&g, 40.0f, inst[i].xform);
    }
    sidx_accel *agg = NULL;
    sidx_error err;
    double t0 = tk_now_ms();
    assert_int_equal(sidx_aggregate_build(inst, N, NULL, &agg, &err), SIDX_OK);
    const double agg_ms = tk_now_ms() - t0;
    assert_int_equal(sidx_aggregate_leaf_count(agg), N);
    sidx_mesh flat_mesh;
    flatten(agg, &sphere, &flat_mesh);
    sidx_accel *flat = NULL, *flat_brute = NULL;
    t0 = tk_now_ms();
    /* the reference over 800k triangles: the middle-split BVH builds
     * fastest (this suite must stay quick under the sanitizers) */
    const char *flat_name = sidx_accel_is_registered("bvh-middle") ? "bvh-middle" : child_structure();
    assert_int_equal(sidx_accel_build(flat_name, &flat_mesh, NULL, &flat, NULL), SIDX_OK);
    const double flat_ms = tk_now_ms() - t0;
    assert_int_equal(sidx_accel_build("brute", &flat_mesh, NULL, &flat_brute, NULL), SIDX_OK);

    const size_t nrays = tk_tiny_tests() ? 80 : tk_fast_tests() ? 300 : 2000;
    sidx_ray *rays = malloc(nrays * sizeof *rays);
    assert_non_null(rays);
    make_rays(&g, sidx_mesh_bounds(&flat_mesh), agg, nrays, rays);
    size_t hits;
    compare(agg, flat, rays, nrays, sphere.num_triangles, &hits);
    assert_true(hits > nrays / 4);
    compare(agg, flat_brute, rays, 12, sphere.num_triangles, NULL); /* the real reference, on a few */

    /* memory: one copy of the sphere's structure */
    sidx_aggregate_info info;
    assert_int_equal(sidx_aggregate_info_get(agg, &info), SIDX_OK);
    sidx_accel_stats cs, fs;
    sidx_accel_stats_get(child, &cs);
    sidx_accel_stats_get(flat, &fs);
    assert_int_equal(info.instances, N);
    assert_int_equal(info.distinct_children, 1);
    assert_int_equal(info.shared_bytes, cs.bytes);
    assert_int_equal(info.world_triangles, (uint64_t)N * sphere.num_triangles);
    const size_t inst_total = info.own_bytes + info.shared_bytes + (size_t)sphere.num_vertices * 12 + sphere.num_triangles * 12;
    const size_t flat_total = fs.bytes + (size_t)flat_mesh.num_vertices * 12 + (size_t)flat_mesh.num_triangles * 12;
    assert_true(inst_total < flat_total / 4);
    printf("  %u instances of a %u-triangle sphere (%s): instanced %zu KiB (top level %zu KiB + one %zu KiB %s + mesh)"
           " vs flattened %zu KiB (%s %zu KiB + %u-triangle mesh); build %.1f ms vs %.1f ms\n",
           N, sphere.num_triangles, child_structure(), inst_total / 1024, info.own_bytes / 1024, cs.bytes / 1024,
           child_structure(), flat_total / 1024, flat_name, fs.bytes / 1024, flat_mesh.num_triangles, agg_ms,
           flat_ms);
    /* speed, for the record */
    sidx_hit h;
    t0 = tk_now_ms();
    for (size_t i = 0; i < nrays; ++i) sidx_accel_intersect(agg, &rays[i], NULL, &h);
    const double ti = tk_now_ms() - t0;
    t0 = tk_now_ms();
    for (size_t i = 0; i < nrays; ++i) sidx_accel_intersect(flat, &rays[i], NULL, &h);
    const double tf = tk_now_ms() - t0;
    printf("  per ray: instanced %.2f us, flattened %.2f us\n", 1000.0 * ti / nrays, 1000.0 * tf / nrays);

    free(rays);
    sidx_accel_destroy(flat_brute);
    sidx_accel_destroy(flat);
    sidx_mesh_free(&flat_mesh);
    sidx_accel_destroy(agg);
    free(inst);
    sidx_accel_destroy(child);
    sidx_mesh_free(&sphere);
}

/* ---- 10,000 bunnies ------------------------------------------------------------------
 *
 * Flattening is no reference here (694 million triangles), so the reference
 * is the definition of instancing, computed independently of instance.c:
 * for every ray and every one of the 10,000 placements, invert the
 * transform in double precision here, carry the ray into the bunny's space
 * and ask the one bunny BVH, keeping the nearest t (the direction is not
 * renormalized, so t is comparable across instances).  That reference is
 * itself spot-checked against the double-precision brute-force tracer of
 * testkit on the bunny's triangles. */

/* counts what the aggregate build allocates: it must be O(instances), not a copy of the bunny */
typedef struct counting { size_t live, peak, total; } counting;
typedef struct counted_hdr { size_t size; max_align_t pad; } counted_hdr;
static void *counting_alloc(size_t size, void *user)
{
    counting *c = user;
    counted_hdr *h = malloc(sizeof *h + size);
    if (!h) return NULL;
    h->size = size;
    c->live += size;
    c->total += size;
    if (c->live > c->peak) c->peak = c->live;
    return h + 1;
}
static void counting_free(void *p, void *user)
{
    if (!p) return;
    counting *c = user;
    counted_hdr *h = (counted_hdr *)p - 1;
    c->live -= h->size;
    free(h);
}

/* world -> object for m (object -> world), in double */
static void invert_affine(const float m[12], double inv[12])
{
    double a[9];
    for (int r = 0; r < 3; ++r) for (int c = 0; c < 3; ++c) a[3 * r + c] = m[4 * r + c];
    double b[9];
    b[0] = a[4] * a[8] - a[5] * a[7]; b[1] = a[2] * a[7] - a[1] * a[8]; b[2] = a[1] * a[5] - a[2] * a[4];
    b[3] = a[5] * a[6] - a[3] * a[8]; b[4] = a[0] * a[8] - a[2] * a[6]; b[5] = a[2] * a[3] - a[0] * a[5];
    b[6] = a[3] * a[7] - a[4] * a[6]; b[7] = a[1] * a[6] - a[0] * a[7]; b[8] = a[0] * a[4] - a[1] * a[3];
    const double det = a[0] * b[0] + a[1] * b[3] + a[2] * b[6];
    assert_true(fabs(det) > 1e-12);
    for (int r = 0; r < 3; ++r) {
        double t = 0.0;
        for (int c = 0; c < 3; ++c) {
            inv[4 * r + c] = b[3 * r + c] / det;
            t -= inv[4 * r + c] * m[4 * c + 3];
        }
        inv[4 * r + 3] = t;
    }
}

static tk_rayrec local_ray(const double inv[12], const sidx_ray *r, float tmax)
{
    const double o[3] = {r->org.x, r->org.y, r->org.z}, d[3] = {r->dir.x, r->dir.y, r->dir.z};
    float lo[3], ld[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = (float)(inv[4 * k] * o[0] + inv[4 * k + 1] * o[1] + inv[4 * k + 2] * o[2] + inv[4 * k + 3]);
        ld[k] = (float)(inv[4 * k] * d[0] + inv[4 * k + 1] * d[1] + inv[4 * k + 2] * d[2]);
    }
    return tk_rayrec_make(sidx_v3(lo[0], lo[1], lo[2]), sidx_v3(ld[0], ld[1], ld[2]), r->tmin, tmax);
}

/* does the local ray come within the (padded) box at all?  double slabs */
static int local_ray_meets_box(const tk_rayrec *lr, sidx_aabb b)
{
    const double pad = 1e-3 * sidx_v3_length(sidx_aabb_extent(b));
    const double lo[3] = {b.min.x - pad, b.min.y - pad, b.min.z - pad}, hi[3] = {b.max.x + pad, b.max.y + pad, b.max.z + pad};
    double t0 = 0.0, t1 = INFINITY;
    for (int k = 0; k < 3; ++k) {
        if (lr->d[k] == 0.0f) {
            if (lr->o[k] < lo[k] || lr->o[k] > hi[k]) return 0;
            continue;
        }
        double a = (lo[k] - lr->o[k]) / lr->d[k], c = (hi[k] - lr->o[k]) / lr->d[k];
        if (a > c) { const double t = a; a = c; c = t; }
        if (a > t0) t0 = a;
        if (c < t1) t1 = c;
    }
    return t0 <= t1;
}

/* The reference: every instance, the one bunny structure `bunny` (a BVH, or
 * NULL for testkit's brute force with a box cull), nearest t.  prim is
 * reported flattened: instance·T + triangle. */
static sidx_hit instanced_reference(const sidx_ray *r, const double (*inv)[12], uint32_t n, const sidx_accel *bunny,
                                    const sidx_mesh *m)
{
    sidx_hit best = sidx_hit_none();
    const sidx_aabb mb = sidx_mesh_bounds(m);
    for (uint32_t i = 0; i < n; ++i) {
        const tk_rayrec lr = local_ray(inv[i], r, best.t < INFINITY ? best.t : r->tmax);
        sidx_hit h = sidx_hit_none();
        if (bunny) {
            sidx_ray ray;
            if (tk_ray_from(&lr, &ray) != SIDX_OK) continue;
            sidx_accel_intersect(bunny, &ray, NULL, &h);
        } else {
            if (!local_ray_meets_box(&lr, mb)) continue;
            tk_ref_intersect(m, &lr, &h);
        }
        if (h.prim != SIDX_NO_HIT && h.t < best.t) {
            best = h;
            best.instance = i;
            best.prim = i * m->num_triangles + h.prim;
        }
    }
    return best;
}

static void ten_thousand_bunnies(void **state)
{
    (void)state;
    const char *dir = getenv("SIDX_SCENES");
    if (!dir || !*dir) {
        printf("  SKIPPED ten_thousand_bunnies: set SIDX_SCENES to the directory holding bunny.obj\n");
        return;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/bunny.obj", dir);
    sidx_mesh bunny;
    sidx_error err;
    const sidx_status st = sidx_scene_open(path, &bunny, &err);
    if (st != SIDX_OK) fprintf(stderr, "%s\n", err.message);
    assert_int_equal(st, SIDX_OK);
    const uint32_t N = 10000, T = bunny.num_triangles;
    sidx_accel *child = NULL;
    assert_int_equal(sidx_accel_build(child_structure(), &bunny, NULL, &child, &err), SIDX_OK);

    /* placements: random rotation about the bunny's centre, scale, and a
     * translation spreading them over a cube 25 bunny diagonals wide (dense
     * enough that rays pass through and behind many of them) */
    const sidx_aabb bb = sidx_mesh_bounds(&bunny);
    const sidx_vec3 ctr = sidx_aabb_centroid(bb);
    const float diag = sidx_v3_length(sidx_aabb_extent(bb));
    sidx_instance *inst = malloc(N * sizeof *inst);
    double (*inv)[12] = malloc(N * sizeof *inv);
    assert_true(inst && inv);
    tk_rng g;
    tk_rng_seed(&g, 10000);
    for (uint32_t i = 0; i < N; ++i) {
        float *m = inst[i].xform;
        inst[i].accel = child;
        random_xform(&g, 12.5f * diag, m);
        /* world = R·S·(p − ctr) + t: fold −R·S·ctr into the translation */
        for (int r = 0; r < 3; ++r) m[4 * r + 3] -= m[4 * r] * ctr.x + m[4 * r + 1] * ctr.y + m[4 * r + 2] * ctr.z;
        invert_affine(m, inv[i]);
    }
    counting cnt = {0, 0, 0};
    sidx_allocator al = {counting_alloc, counting_free, &cnt};
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.alloc = &al;
    sidx_accel *agg = NULL;
    const double t0 = tk_now_ms();
    assert_int_equal(sidx_aggregate_build(inst, N, &bo, &agg, &err), SIDX_OK);
    const double build_ms = tk_now_ms() - t0;

    /* memory: one bunny BVH, plus instance records and the top tree */
    sidx_aggregate_info info;
    assert_int_equal(sidx_aggregate_info_get(agg, &info), SIDX_OK);
    sidx_accel_stats cs;
    sidx_accel_stats_get(child, &cs);
    assert_int_equal(info.instances, N);
    assert_int_equal(info.leaf_instances, N);
    assert_int_equal(info.distinct_children, 1);
    assert_int_equal(info.shared_bytes, cs.bytes);
    assert_int_equal(info.world_triangles, (uint64_t)N * T);
    /* what the aggregate holds is what it allocated (the build's
     * temporaries are gone), and it is a few hundred bytes per instance,
     * independent of the bunny's size */
    assert_int_equal(cnt.live, info.own_bytes);
    assert_true(cnt.peak < (size_t)N * 512);
    assert_true(info.own_bytes < (size_t)N * 256);
    assert_true(info.own_bytes + info.shared_bytes < cs.bytes + (size_t)N * 256);
    const double flat_est = (double)N * ((double)cs.bytes + 12.0 * bunny.num_vertices + 12.0 * T);
    printf("  %u bunnies (%u tris each, %.0f M in the scene): aggregate %.2f MB (%zu B/instance) + one %s of %.2f MB"
           " + one mesh %.2f MB; 10,000 copies would be about %.0f MB; aggregate build %.1f ms\n",
           N, T, (double)info.world_triangles / 1e6, info.own_bytes / 1048576.0, info.own_bytes / N, child_structure(),
           cs.bytes / 1048576.0, (12.0 * bunny.num_vertices + 12.0 * T) / 1048576.0, flat_est / 1048576.0, build_ms);

    /* rays: a quarter from outside the cloud, the rest from inside it; half
     * aimed at a random bunny's centre (they hit often), half random */
    const sidx_aabb world = {sidx_v3(-13.5f * diag, -13.5f * diag, -13.5f * diag), sidx_v3(13.5f * diag, 13.5f * diag, 13.5f * diag)};
    const size_t nrays = tk_tiny_tests() ? 60 : tk_fast_tests() ? 200 : 2000;
    sidx_ray *rays = malloc(nrays * sizeof *rays);
    assert_non_null(rays);
    for (size_t i = 0; i < nrays; ++i) {
        sidx_vec3 o = tk_rng_in_box(&g, world);
        if (i % 4 == 0) o = sidx_v3_scale(tk_rng_sphere(&g), 30.0f * diag);
        sidx_vec3 d = tk_rng_sphere(&g);
        if (i % 2 == 0) {
            const float *m = inst[tk_rng_below(&g, N)].xform;
            d = sidx_v3_sub(sidx_v3(m[3], m[7], m[11]), o); /* the translation is where ctr went */
        }
        d = sidx_v3_scale(d, (float)tk_rng_range(&g, 0.5, 2.0));
        assert_int_equal(sidx_ray_init(&rays[i], o, d, 0.0f, INFINITY), SIDX_OK);
    }

    /* the reference, spot-checked against brute force on the bunny: the
     * first few aimed rays (even i) and one random ray */
    const size_t spot = tk_fast_tests() ? 2 : 8;
    size_t spot_hits = 0;
    for (size_t k = 0; k <= spot; ++k) {
        const size_t i = k < spot ? 2 * k : 1;
        const sidx_hit a = instanced_reference(&rays[i], (const double (*)[12])inv, N, child, &bunny);
        const sidx_hit b = instanced_reference(&rays[i], (const double (*)[12])inv, N, NULL, &bunny);
        if (!tk_hits_agree(&b, &a))
            fprintf(stderr, "ray %zu: brute instance %u prim %u t %.9g; bvh reference instance %u prim %u t %.9g\n", i,
                    b.instance, b.prim, b.t, a.instance, a.prim, a.t);
        assert_true(tk_hits_agree(&b, &a));
        spot_hits += b.prim != SIDX_NO_HIT;
    }
    assert_true(spot_hits >= 1);

    /* the aggregate against the reference, closest hit and any-hit */
    size_t hits = 0, ref_instances = 0;
    double agg_ms = 0.0;
    for (size_t i = 0; i < nrays; ++i) {
        const sidx_hit ref = instanced_reference(&rays[i], (const double (*)[12])inv, N, child, &bunny);
        const double ta = tk_now_ms();
        sidx_hit got;
        sidx_accel_intersect(agg, &rays[i], NULL, &got);
        agg_ms += tk_now_ms() - ta;
        sidx_hit g2 = got;
        if (got.prim != SIDX_NO_HIT) {
            assert_true(got.instance < N);
            assert_true(got.prim < T);
            g2.prim = got.instance * T + got.prim;
        }
        if (!tk_hits_agree(&ref, &g2))
            fprintf(stderr, "ray %zu: reference instance %u prim %u t %.9g; aggregate instance %u prim %u t %.9g\n", i,
                    ref.instance, ref.prim == SIDX_NO_HIT ? ref.prim : ref.prim % T, ref.t, got.instance, got.prim,
                    got.t);
        assert_true(tk_hits_agree(&ref, &g2));
        ref_instances += ref.prim != SIDX_NO_HIT && got.instance == ref.instance;
        int occ;
        sidx_accel_occluded(agg, &rays[i], NULL, &occ);
        assert_int_equal(occ, ref.prim != SIDX_NO_HIT);
        hits += ref.prim != SIDX_NO_HIT;
    }
    assert_true(hits > nrays / 5);
    printf("  %zu rays: %zu hit (%zu on the reference's own instance), one BVH reference walk per instance per ray;"
           " aggregate %.2f us/ray\n", nrays, hits, ref_instances, 1000.0 * agg_ms / (double)nrays);

    free(rays);
    sidx_accel_destroy(agg);
    assert_int_equal(cnt.live, 0);
    free(inv);
    free(inst);
    sidx_accel_destroy(child);
    sidx_mesh_free(&bunny);
}

/* An aggregate of aggregates: 4 groups of 25 spheres, placed 40 times. */
static void nested_aggregates(void **state)
{
    (void)state;
    sidx_mesh sphere;
    assert_int_equal(sidx_scene_make("icosphere", 1, &sphere, NULL), SIDX_OK);
    sidx_accel *child = NULL;
    assert_int_equal(sidx_accel_build(child_structure(), &sphere, NULL, &child, NULL), SIDX_OK);
    tk_rng g;
    tk_rng_seed(&g, 7);
    sidx_accel *groups[4];
    sidx_instance gi[25];
    for (int k = 0; k < 4; ++k) {
        for (int i = 0; i < 25; ++i) {
            gi[i].accel = child;
            random_xform(&g, 6.0f, gi[i].xform);
        }
        assert_int_equal(sidx_aggregate_build(gi, 25, NULL, &groups[k], NULL), SIDX_OK);
    }
    sidx_instance top[40];
    for (int i = 0; i < 40; ++i) {
        top[i].accel = groups[i % 4];
        random_xform(&g, 30.0f, top[i].xform);
    }
    sidx_accel *agg = NULL;
    assert_int_equal(sidx_aggregate_build(top, 40, NULL, &agg, NULL), SIDX_OK);
    assert_int_equal(sidx_aggregate_leaf_count(agg), 1000);
    sidx_aggregate_info info;
    sidx_aggregate_info_get(agg, &info);
    assert_int_equal(info.distinct_children, 4);
    assert_int_equal(info.world_triangles, 1000u * sphere.num_triangles);
    sidx_mesh flat_mesh;
    flatten(agg, &sphere, &flat_mesh);
    sidx_accel *flat = NULL;
    assert_int_equal(sidx_accel_build("brute", &flat_mesh, NULL, &flat, NULL), SIDX_OK);
    sidx_ray rays[150];
    make_rays(&g, sidx_mesh_bounds(&flat_mesh), agg, 150, rays);
    size_t hits;
    compare(agg, flat, rays, 150, sphere.num_triangles, &hits);
    assert_true(hits > 30);

    /* u, v and the world normal agree with the flattened triangle's */
    const sidx_query q = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    int checked = 0;
    for (int i = 0; i < 150; ++i) {
        sidx_hit a, b;
        sidx_accel_intersect(agg, &rays[i], &q, &a);
        sidx_accel_intersect(flat, &rays[i], &q, &b);
        if (a.prim == SIDX_NO_HIT || a.instance * sphere.num_triangles + a.prim != b.prim) continue;
        assert_float_equal(a.u, b.u, 2e-3f);
        assert_float_equal(a.v, b.v, 2e-3f);
        const float cosang = sidx_v3_dot(a.ng, b.ng) / (sidx_v3_length(a.ng) * sidx_v3_length(b.ng));
        assert_true(cosang > 0.9999f);
        ++checked;
    }
    assert_true(checked > 20);
    sidx_accel_destroy(flat);
    sidx_mesh_free(&flat_mesh);
    sidx_accel_destroy(agg);
    for (int k = 0; k < 4; ++k) sidx_accel_destroy(groups[k]);
    sidx_accel_destroy(child);
    sidx_mesh_free(&sphere);
}

static void events_and_errors(void **state)
{
    (void)state;
    sidx_mesh sphere;
    assert_int_equal(sidx_scene_make("icosphere", 1, &sphere, NULL), SIDX_OK);
    sidx_accel *child = NULL;
    assert_int_equal(sidx_accel_build("brute", &sphere, NULL, &child, NULL), SIDX_OK);
    sidx_instance in[2] = {{child, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}}, {child, {2, 0, 0, 5, 0, 2, 0, 0, 0, 0, 2, 0}}};
    sidx_accel *agg = NULL;
    assert_int_equal(sidx_aggregate_build(in, 2, NULL, &agg, NULL), SIDX_OK);
    assert_true(sidx_accel_is_aggregate(agg));
    assert_false(sidx_accel_is_aggregate(child));
    /* a ray along +x through both: the first sphere (radius 1 at 0) is hit at x = -1 */
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook hook = sidx_recorder_hook(&rec);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 5};
    sidx_ray r;
    sidx_ray_init(&r, sidx_v3(-10, 0.01f, 0.02f), sidx_v3(2, 0, 0), 0, INFINITY);
    sidx_hit h;
    sidx_accel_intersect(agg, &r, &q, &h);
    assert_int_equal(h.instance, 0);
    assert_float_equal(h.t, 4.5f, 0.02f);
    int notes = 0, child_events = 0;
    for (size_t i = 0; i < rec.count; ++i) {
        if (rec.events[i].type == SIDX_EV_NOTE && !strcmp(rec.events[i].structure, "aggregate")) ++notes;
        if (!strcmp(rec.events[i].structure, "brute")) ++child_events;
    }
    assert_true(notes >= 1);
    assert_true(child_events > 0);
    /* from the far side it is the big one (instance 1) */
    sidx_ray_init(&r, sidx_v3(20, 0.01f, 0.02f), sidx_v3(-1, 0, 0), 0, INFINITY);
    sidx_accel_intersect(agg, &r, NULL, &h);
    assert_int_equal(h.instance, 1);
    assert_float_equal(h.t, 13.0f, 0.1f);
    /* errors */
    sidx_accel *bad = NULL;
    sidx_instance sing = {child, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0}};
    assert_int_equal(sidx_aggregate_build(&sing, 1, NULL, &bad, NULL), SIDX_ERR_INVALID_ARG);
    sidx_instance none = {NULL, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}};
    assert_int_equal(sidx_aggregate_build(&none, 1, NULL, &bad, NULL), SIDX_ERR_INVALID_ARG);
    assert_null(bad);
    const sidx_accel *leaf;
    float m[12];
    assert_int_equal(sidx_aggregate_leaf(agg, 2, &leaf, m), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_aggregate_leaf(child, 0, &leaf, m), SIDX_ERR_INVALID_ARG);
    /* an empty aggregate misses everything */
    sidx_accel *empty = NULL;
    assert_int_equal(sidx_aggregate_build(NULL, 0, NULL, &empty, NULL), SIDX_OK);
    sidx_accel_intersect(empty, &r, NULL, &h);
    assert_int_equal(h.prim, SIDX_NO_HIT);
    sidx_accel_destroy(empty);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(agg);
    sidx_accel_destroy(child);
    sidx_mesh_free(&sphere);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(events_and_errors),
        cmocka_unit_test(nested_aggregates),
        cmocka_unit_test(ten_thousand_instances),
        cmocka_unit_test(ten_thousand_bunnies),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
