/* extras.c — `sidx-bench extras`: the rows `run`
 * cannot give, because they are not registered structures over one mesh:
 *
 *  instancing   N placements of one mesh's BVH in an aggregate (the deck's
 *               aggregate object): build time, Mrays/s for primary and
 *               diffuse rays, and memory against what one flattened BVH
 *               over N copies would need (an ESTIMATE: N x the single
 *               BVH's bytes, plus N x the mesh; nobody builds it);
 *  lightbuffer  shadow rays from the visible surface points of a camera
 *               image to a point light (Haines & Greenberg 1986): the
 *               light buffer against plain any-hit on the BVH, memory, and
 *               how often the cached last occluder answers;
 *  rayclass     ray classification (Arvo & Kirk 1987) at several depths
 *               against brute force and the BVH: preprocessing time and
 *               memory against per-ray gain, and how many rays it takes to
 *               repay the preprocessing — the deck's "poor trade-off",
 *               in numbers.
 *
 * Every row is also checked: instanced hits against a per-instance
 * reference computed here, light-buffer answers against the BVH's any-hit,
 * ray-classification hits against brute force.  A disagreement is printed
 * and makes the exit status 1.  Times are CPU time of this thread, best of
 * at least 3 repetitions. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench.h"
#include "sidx/instance.h"
#include "sidx/lightbuffer.h"
#include "sidx/rayclass.h"

typedef struct ex_opts {
    const char *scenes_dir, *parts, *rc_depths;
    uint32_t instances, lb_res;
    size_t rays, check;
    uint64_t seed;
    double budget_ms;
} ex_opts;

/* ---- small helpers -------------------------------------------------------------- */

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* `file` from --scenes when it is there, else the built-in `builtin`. */
static int load_scene(const ex_opts *o, const char *file, const char *builtin, sidx_mesh *m, char *name, size_t nsize)
{
    char path[4096];
    sidx_error err;
    if (o->scenes_dir && file) {
        snprintf(path, sizeof path, "%s/%s", o->scenes_dir, file);
        if (file_exists(path)) {
            if (sidx_scene_open(path, m, &err) != SIDX_OK) {
                fprintf(stderr, "sidx-bench extras: %s\n", err.message);
                return 0;
            }
            snprintf(name, nsize, "%.*s", (int)(strcspn(file, ".") < 40 ? strcspn(file, ".") : 40), file);
            return 1;
        }
    }
    if (!builtin) return 0;
    if (sidx_scene_open(builtin, m, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench extras: %s\n", err.message);
        return 0;
    }
    snprintf(name, nsize, "%s (built-in)", builtin);
    return 1;
}

static double mb(double bytes) { return bytes / 1048576.0; }
static double mesh_bytes(const sidx_mesh *m) { return 12.0 * m->num_vertices + 12.0 * m->num_triangles; }
static double mrays(size_t n, double ms) { return ms > 0 ? (double)n / ms / 1000.0 : 0.0; }

/* Best time of at least 3 runs of work(ctx), more while under budget. */
typedef void (*ex_work)(void *ctx);
static double time_best(ex_work w, void *ctx, double budget_ms)
{
    double best = INFINITY, spent = 0.0;
    for (int reps = 0; reps < 3 || (spent < budget_ms && reps < 30); ++reps) {
        const double t0 = bench_clock_ms();
        w(ctx);
        const double dt = bench_clock_ms() - t0;
        spent += dt;
        if (dt < best) best = dt;
    }
    return best;
}

typedef struct trace_ctx {
    const sidx_accel *a;
    const bench_rays *br;
    size_t n;
    int any_hit;
    sidx_hit *hits;
} trace_ctx;
static void trace_work(void *p)
{
    trace_ctx *c = p;
    bench_trace(c->a, c->br, 0, c->n, NULL, c->any_hit, 1, 0.0, c->hits, NULL);
}

static int make_rays(const sidx_mesh *m, tk_ray_kind kind, size_t n, uint64_t seed, bench_rays *out)
{
    tk_rayrec *rec = malloc((n ? n : 1) * sizeof *rec);
    if (!rec) return 0;
    tk_make_rays(m, kind, n, seed, rec);
    const int ok = bench_rays_prepare(rec, n, out);
    free(rec);
    return ok;
}

/* ---- instancing ------------------------------------------------------------------- */

/* random rotation (unit quaternion) · non-uniform scale in [0.5, 1.5] about
 * the mesh's centre c, then a translation in [-L, L]^3 */
static void random_placement(tk_rng *g, sidx_vec3 c, double L, float m[12])
{
    double q[4], n = 0.0;
    for (int i = 0; i < 4; ++i) { q[i] = tk_rng_range(g, -1, 1); n += q[i] * q[i]; }
    n = sqrt(n);
    const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    const double R[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                         2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                         2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
    double s[3]; /* one draw per statement: the order of an initializer list's evaluations is unspecified */
    for (int k = 0; k < 3; ++k) s[k] = tk_rng_range(g, 0.5, 1.5);
    for (int r = 0; r < 3; ++r) {
        double t = tk_rng_range(g, -L, L);
        for (int k = 0; k < 3; ++k) {
            m[4 * r + k] = (float)(R[3 * r + k] * s[k]);
            t -= (double)m[4 * r + k] * (k == 0 ? c.x : k == 1 ? c.y : c.z);
        }
        m[4 * r + 3] = (float)t;
    }
}

/* object -> world m to world -> object, in double (independent of instance.c) */
static int invert_placement(const float m[12], double inv[12])
{
    double a[9], b[9];
    for (int r = 0; r < 3; ++r) for (int c = 0; c < 3; ++c) a[3 * r + c] = m[4 * r + c];
    b[0] = a[4] * a[8] - a[5] * a[7]; b[1] = a[2] * a[7] - a[1] * a[8]; b[2] = a[1] * a[5] - a[2] * a[4];
    b[3] = a[5] * a[6] - a[3] * a[8]; b[4] = a[0] * a[8] - a[2] * a[6]; b[5] = a[2] * a[3] - a[0] * a[5];
    b[6] = a[3] * a[7] - a[4] * a[6]; b[7] = a[1] * a[6] - a[0] * a[7]; b[8] = a[0] * a[4] - a[1] * a[3];
    const double det = a[0] * b[0] + a[1] * b[3] + a[2] * b[6];
    if (!(fabs(det) > 0.0)) return 0;
    for (int r = 0; r < 3; ++r) {
        double t = 0.0;
        for (int c = 0; c < 3; ++c) {
            inv[4 * r + c] = b[3 * r + c] / det;
            t -= inv[4 * r + c] * m[4 * c + 3];
        }
        inv[4 * r + 3] = t;
    }
    return 1;
}

/* The definition of instancing, for the check: every placement, the one
 * structure, nearest t; prim flattened to instance·T + triangle. */
static sidx_hit per_instance_reference(const sidx_ray *r, const double (*inv)[12], uint32_t n, const sidx_accel *child,
                                       uint32_t T)
{
    sidx_hit best = sidx_hit_none();
    const double o[3] = {r->org.x, r->org.y, r->org.z}, d[3] = {r->dir.x, r->dir.y, r->dir.z};
    for (uint32_t i = 0; i < n; ++i) {
        const double *M = inv[i];
        float lo[3], ld[3];
        for (int k = 0; k < 3; ++k) {
            lo[k] = (float)(M[4 * k] * o[0] + M[4 * k + 1] * o[1] + M[4 * k + 2] * o[2] + M[4 * k + 3]);
            ld[k] = (float)(M[4 * k] * d[0] + M[4 * k + 1] * d[1] + M[4 * k + 2] * d[2]);
        }
        sidx_ray lr;
        if (sidx_ray_init(&lr, sidx_v3(lo[0], lo[1], lo[2]), sidx_v3(ld[0], ld[1], ld[2]), r->tmin,
                          best.t < INFINITY ? best.t : r->tmax) != SIDX_OK)
            continue;
        sidx_hit h;
        sidx_accel_intersect(child, &lr, NULL, &h);
        if (h.prim != SIDX_NO_HIT && h.t < best.t) {
            best = h;
            best.instance = i;
            best.prim = i * T + h.prim;
        }
    }
    return best;
}

static int part_instancing(const ex_opts *o)
{
    sidx_mesh m;
    char name[64];
    if (!load_scene(o, "bunny.obj", "teapot", &m, name, sizeof name)) return BENCH_FAIL;
    const uint32_t N = o->instances, T = m.num_triangles;
    int status = BENCH_OK;
    bench_progress("instancing: building the %s BVH", name);
    sidx_accel *child = NULL;
    sidx_error err;
    double t0 = bench_build_clock_ms();
    if (sidx_accel_build("bvh", &m, NULL, &child, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench extras: bvh on %s: %s\n", name, err.message);
        sidx_mesh_free(&m);
        return BENCH_FAIL;
    }
    const double child_ms = bench_build_clock_ms() - t0;
    sidx_accel_stats cs;
    sidx_accel_stats_get(child, &cs);

    /* placements over a cube 25 mesh diagonals wide: dense enough that a
     * ray passes near and behind many instances */
    const sidx_aabb mbox = sidx_mesh_bounds(&m);
    const double diag = sidx_v3_length(sidx_aabb_extent(mbox));
    sidx_instance *inst = malloc((size_t)N * sizeof *inst);
    double (*inv)[12] = malloc((size_t)N * sizeof *inv);
    if (!inst || !inv) {
        fprintf(stderr, "sidx-bench extras: out of memory\n");
        free(inst);
        free(inv);
        sidx_accel_destroy(child);
        sidx_mesh_free(&m);
        return BENCH_FAIL;
    }
    tk_rng g;
    tk_rng_seed(&g, o->seed);
    sidx_aabb world = sidx_aabb_empty();
    for (uint32_t i = 0; i < N; ++i) {
        inst[i].accel = child;
        random_placement(&g, sidx_aabb_centroid(mbox), 12.5 * diag, inst[i].xform);
        invert_placement(inst[i].xform, inv[i]);
        for (int c = 0; c < 8; ++c) {
            const sidx_vec3 p = sidx_v3(c & 1 ? mbox.max.x : mbox.min.x, c & 2 ? mbox.max.y : mbox.min.y,
                                        c & 4 ? mbox.max.z : mbox.min.z);
            const float *x = inst[i].xform;
            world = sidx_aabb_grow(world, sidx_v3(x[0] * p.x + x[1] * p.y + x[2] * p.z + x[3],
                                                  x[4] * p.x + x[5] * p.y + x[6] * p.z + x[7],
                                                  x[8] * p.x + x[9] * p.y + x[10] * p.z + x[11]));
        }
    }
    bench_progress("instancing: aggregate of %u instances", N);
    sidx_accel *agg = NULL;
    t0 = bench_build_clock_ms();
    if (sidx_aggregate_build(inst, N, NULL, &agg, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench extras: aggregate: %s\n", err.message);
        free(inst);
        free(inv);
        sidx_accel_destroy(child);
        sidx_mesh_free(&m);
        return BENCH_FAIL;
    }
    const double agg_ms = bench_build_clock_ms() - t0;
    sidx_aggregate_info info;
    sidx_aggregate_info_get(agg, &info);

    /* rays: the ray sets of `run`, framed on the cloud's box (a stand-in
     * mesh of its 12 faces: the sets only look at the bounds) */
    const float bx[24] = {world.min.x, world.min.y, world.min.z, world.max.x, world.min.y, world.min.z,
                          world.min.x, world.max.y, world.min.z, world.max.x, world.max.y, world.min.z,
                          world.min.x, world.min.y, world.max.z, world.max.x, world.min.y, world.max.z,
                          world.min.x, world.max.y, world.max.z, world.max.x, world.max.y, world.max.z};
    const uint32_t bi[36] = {0, 1, 3, 0, 3, 2, 4, 7, 5, 4, 6, 7, 0, 4, 5, 0, 5, 1,
                             2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3};
    sidx_mesh frame;
    if (sidx_mesh_from_arrays(&frame, bx, 8, bi, 12, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench extras: instancing: %s\n", err.message);
        sidx_accel_destroy(agg);
        free(inst);
        free(inv);
        sidx_accel_destroy(child);
        sidx_mesh_free(&m);
        return BENCH_FAIL;
    }
    const tk_ray_kind kinds[2] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE};
    double agg_mr[2] = {0, 0}, one_mr[2] = {0, 0};
    size_t agg_hits[2] = {0, 0}, checked = 0, bad = 0;
    sidx_hit *hits = malloc(o->rays * sizeof *hits);
    for (int k = 0; k < 2 && hits; ++k) {
        bench_rays br, br1;
        if (!make_rays(&frame, kinds[k], o->rays, o->seed + (uint64_t)k, &br)) break;
        if (!make_rays(&m, kinds[k], o->rays, o->seed + (uint64_t)k, &br1)) { bench_rays_free(&br); break; }
        bench_progress("instancing: %s rays", tk_ray_kind_name(kinds[k]));
        trace_ctx c = {agg, &br, br.n, 0, hits};
        agg_mr[k] = mrays(br.n, time_best(trace_work, &c, o->budget_ms));
        for (size_t i = 0; i < br.n; ++i) agg_hits[k] += hits[i].prim != SIDX_NO_HIT;
        trace_ctx c1 = {child, &br1, br1.n, 0, hits};
        one_mr[k] = mrays(br1.n, time_best(trace_work, &c1, o->budget_ms));
        /* check a spread subset against the per-instance reference */
        const size_t nc = o->check < br.n ? o->check : br.n;
        for (size_t j = 0; j < nc; ++j) {
            const size_t i = j * br.n / nc;
            if (!br.valid[i]) continue;
            bench_progress("instancing: checking %s ray %zu/%zu", tk_ray_kind_name(kinds[k]), j, nc);
            const sidx_hit ref = per_instance_reference(&br.r[i], (const double (*)[12])inv, N, child, T);
            sidx_hit got;
            sidx_accel_intersect(agg, &br.r[i], NULL, &got);
            if (got.prim != SIDX_NO_HIT) got.prim = got.instance * T + got.prim;
            ++checked;
            if (!tk_hits_agree(&ref, &got)) {
                ++bad;
                fprintf(stderr, "sidx-bench extras: instancing: %s ray %zu: reference prim %u t %.9g, aggregate prim %u t %.9g\n",
                        tk_ray_kind_name(kinds[k]), i, ref.prim, ref.t, got.prim, got.t);
            }
        }
        bench_rays_free(&br);
        bench_rays_free(&br1);
    }
    bench_progress_done();
    if (!hits) status = BENCH_FAIL;
    free(hits);

    const double own = (double)info.own_bytes, shared = (double)info.shared_bytes + mesh_bytes(&m);
    const double flat_est = (double)N * ((double)cs.bytes + mesh_bytes(&m));
    printf("== instancing: %u instances of %s (%u tris each, %.1f M in the scene), one shared bvh;\n"
           "   random rotation, scale 0.5-1.5 per axis, spread over a cube 25 diagonals wide; %zu rays per kind\n",
           N, name, T, (double)info.world_triangles / 1e6, o->rays);
    printf("%-34s %10s %10s %16s %16s %10s\n", "row", "build_ms", "MB", "primary Mrays/s", "diffuse Mrays/s", "hit % p/d");
    printf("%-34s %10.1f %10.2f %16.2f %16.2f %10s\n", "one mesh, bvh (reference speed)", child_ms,
           mb((double)cs.bytes + mesh_bytes(&m)), one_mr[0], one_mr[1], "-");
    char label[64];
    snprintf(label, sizeof label, "aggregate, %u instances", N);
    printf("%-34s %10.1f %10.2f %16.2f %16.2f %4.0f/%-5.0f\n", label, agg_ms, mb(own + shared), agg_mr[0], agg_mr[1],
           100.0 * agg_hits[0] / (double)(o->rays ? o->rays : 1), 100.0 * agg_hits[1] / (double)(o->rays ? o->rays : 1));
    printf("%-34s %10s %10.2f\n", "  of which instances + top BVH", "", mb(own));
    printf("%-34s %10s %10.2f\n", "  of which the one bvh + mesh", "", mb(shared));
    printf("%-34s %10s %10.0f   (ESTIMATE: %u x (bvh %.2f MB + mesh %.2f MB); not built)\n",
           "flattened bvh over every copy", "", mb(flat_est), N, mb((double)cs.bytes), mb(mesh_bytes(&m)));
    printf("memory ratio flattened/instanced: %.0fx (%.0f bytes per instance in the aggregate)\n",
           flat_est / (own + shared), own / (N ? N : 1));
    printf("check: %zu rays against a per-instance reference (every placement, ray carried into it by a double\n"
           "       inverse computed here, the one bvh traced): %zu disagree\n\n", checked, bad);
    if (bad) status = BENCH_FAIL;
    sidx_mesh_free(&frame);
    sidx_accel_destroy(agg);
    free(inst);
    free(inv);
    sidx_accel_destroy(child);
    sidx_mesh_free(&m);
    return status;
}

/* ---- light buffer -------------------------------------------------------------------- */

typedef struct lb_ctx {
    sidx_lightbuffer *lb;
    sidx_lightbuffer_cache *cache; /* NULL: no last-occluder cache */
    const sidx_vec3 *pts;
    size_t n;
    int *out;
} lb_ctx;
static void lb_work(void *p)
{
    lb_ctx *c = p;
    for (size_t i = 0; i < c->n; ++i) sidx_lightbuffer_occluded(c->lb, c->pts[i], 1e-4f, 1.0f - 1e-4f, c->cache, NULL, &c->out[i]);
}

static int lightbuffer_scene(const ex_opts *o, const char *file, const char *builtin, sidx_vec3 rel)
{
    sidx_mesh m;
    char name[64];
    if (!load_scene(o, file, builtin, &m, name, sizeof name)) return BENCH_FAIL;
    int status = BENCH_OK;
    sidx_accel *bvh = NULL;
    sidx_error err = {SIDX_OK, ""};
    const double tb = bench_build_clock_ms();
    if (sidx_accel_build("bvh", &m, NULL, &bvh, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-bench extras: bvh on %s: %s\n", name, err.message);
        sidx_mesh_free(&m);
        return BENCH_FAIL;
    }
    const double bvh_ms = bench_build_clock_ms() - tb;
    /* the surface points a camera sees, in image order (coherent, as
     * shadow rays of a rendered image are) */
    bench_rays br;
    sidx_vec3 *pts = malloc(o->rays * sizeof *pts);
    int *a = malloc(o->rays * sizeof *a), *b = malloc(o->rays * sizeof *b);
    bench_rays sh = {NULL, NULL, 0};
    size_t n = 0;
    if (pts && a && b && make_rays(&m, TK_RAYS_PRIMARY, o->rays, o->seed, &br)) {
        for (size_t i = 0; i < br.n; ++i) {
            sidx_hit h;
            if (!br.valid[i]) continue;
            sidx_accel_intersect(bvh, &br.r[i], NULL, &h);
            if (h.prim != SIDX_NO_HIT) pts[n++] = sidx_ray_at(&br.r[i], h.t);
        }
        bench_rays_free(&br);
    }
    const sidx_aabb box = sidx_mesh_bounds(&m);
    const sidx_vec3 light = sidx_v3_add(sidx_aabb_centroid(box), sidx_v3_mul(rel, sidx_aabb_extent(box)));
    sidx_lightbuffer *eager = NULL, *lazy = NULL;
    sidx_lightbuffer_cache c1 = {0}, c2 = {0};
    double eager_ms = 0, lazy_ms = 0;
    if (!n) { status = BENCH_FAIL; fprintf(stderr, "sidx-bench extras: %s: no visible points\n", name); goto done; }
    bench_progress("lightbuffer %s: building", name);
    double t0 = bench_build_clock_ms();
    if (sidx_lightbuffer_build(&m, light, o->lb_res, 1, NULL, &eager, &err) != SIDX_OK) goto fail;
    eager_ms = bench_build_clock_ms() - t0;
    t0 = bench_build_clock_ms();
    if (sidx_lightbuffer_build(&m, light, o->lb_res, 0, NULL, &lazy, &err) != SIDX_OK) goto fail;
    lazy_ms = bench_build_clock_ms() - t0;
    if (sidx_lightbuffer_cache_init(eager, &c1) != SIDX_OK || sidx_lightbuffer_cache_init(lazy, &c2) != SIDX_OK) goto fail;
    /* shadow rays for the BVH: the light buffer's own, so both answer the same question */
    sh.r = malloc(n * sizeof *sh.r);
    sh.valid = malloc(n);
    if (!sh.r || !sh.valid) goto fail;
    sh.n = n;
    for (size_t i = 0; i < n; ++i) {
        sh.valid[i] = sidx_lightbuffer_shadow_ray(eager, pts[i], 1e-4f, 1.0f - 1e-4f, &sh.r[i]) == SIDX_OK;
        if (!sh.valid[i]) memset(&sh.r[i], 0, sizeof sh.r[i]);
    }

    /* the lazy light buffer's first pass fills the cells: timed once, as is */
    bench_progress("lightbuffer %s: lazy first pass", name);
    lb_ctx lz = {lazy, &c2, pts, n, b};
    t0 = bench_clock_ms();
    lb_work(&lz);
    const double lazy_first_ms = bench_clock_ms() - t0;
    bench_progress("lightbuffer %s: timing", name);
    lb_ctx lc = {eager, &c1, pts, n, a};
    const double lb_ms = time_best(lb_work, &lc, o->budget_ms);
    lb_ctx ln = {eager, NULL, pts, n, a};
    const double lb_nc_ms = time_best(lb_work, &ln, o->budget_ms);
    sidx_hit *hits = malloc(n * sizeof *hits);
    if (!hits) goto fail;
    trace_ctx tc = {bvh, &sh, n, 1, hits};
    const double any_ms = time_best(trace_work, &tc, o->budget_ms);
    trace_ctx tc2 = {bvh, &sh, n, 0, hits};
    const double closest_ms = time_best(trace_work, &tc2, o->budget_ms);
    trace_work(&tc); /* any-hit answers in hits */
    bench_progress_done();
    size_t bad = 0, shadowed = 0;
    for (size_t i = 0; i < n; ++i) {
        const int ref = sh.valid[i] && hits[i].prim != SIDX_NO_HIT;
        shadowed += (size_t)ref;
        if (a[i] != ref || b[i] != ref) {
            if (bad < 5)
                fprintf(stderr, "sidx-bench extras: lightbuffer %s point %zu: bvh any-hit %d, eager %d, lazy %d\n",
                        name, i, ref, a[i], b[i]);
            ++bad;
        }
    }
    free(hits);
    /* the cache counters over one fresh pass in image order */
    sidx_lightbuffer_cache c3;
    if (sidx_lightbuffer_cache_init(eager, &c3) != SIDX_OK) goto fail;
    lb_ctx l3 = {eager, &c3, pts, n, a};
    lb_work(&l3);
    sidx_lightbuffer_stats se, sl;
    sidx_lightbuffer_stats_get(eager, &se);
    sidx_lightbuffer_stats_get(lazy, &sl);
    sidx_accel_stats bs;
    sidx_accel_stats_get(bvh, &bs);
    printf("%-22s %7u %7zu %5.0f%% | %8.1f %7.2f %8.2f %8.2f | %8.1f %7.2f %8.2f | %9.2f %9.2f | %5.0f%% %5.0f%% %6.1f | %4zu\n",
           name, m.num_triangles, n, 100.0 * shadowed / (double)n, eager_ms, mb((double)se.bytes), mrays(n, lb_ms),
           mrays(n, lb_nc_ms), lazy_ms, mb((double)sl.bytes), mrays(n, lazy_first_ms), mrays(n, any_ms),
           mrays(n, closest_ms), 100.0 * c3.cache_hits / (double)(c3.occluded ? c3.occluded : 1),
           100.0 * c3.cache_hits / (double)(c3.cache_tests ? c3.cache_tests : 1),
           (double)c3.tri_tests / (double)(c3.queries ? c3.queries : 1), bad);
    printf("%-22s %7s %7s %6s | bvh: build %.1f ms, %.2f MB; lazy filled %u of %u cells\n", "", "", "", "", bvh_ms,
           mb((double)bs.bytes), sl.cells_filled, sl.cells);
    sidx_lightbuffer_cache_free(&c3);
    if (bad) status = BENCH_FAIL;
    goto done;
fail:
    bench_progress_done();
    fprintf(stderr, "sidx-bench extras: lightbuffer on %s: %s\n", name, err.status != SIDX_OK ? err.message : "out of memory");
    status = BENCH_FAIL;
done:
    sidx_lightbuffer_cache_free(&c1);
    sidx_lightbuffer_cache_free(&c2);
    sidx_lightbuffer_destroy(eager);
    sidx_lightbuffer_destroy(lazy);
    free(sh.r);
    free(sh.valid);
    free(pts);
    free(a);
    free(b);
    sidx_accel_destroy(bvh);
    sidx_mesh_free(&m);
    return status;
}

static int part_lightbuffer(const ex_opts *o)
{
    printf("== light buffer: shadow rays from the surface points a camera sees (image order) to a point light;\n"
           "   res %u x %u cells per cube face; eager = every cell filled at build, lazy = on first use\n",
           o->lb_res, o->lb_res);
    printf("%-22s %7s %7s %6s | %-34s | %-25s | %-19s | %-19s | %4s\n", "", "", "", "", "light buffer (eager)",
           "light buffer (lazy)", "bvh, same rays", "cached occluder", "");
    printf("%-22s %7s %7s %6s | %8s %7s %8s %8s | %8s %7s %8s | %9s %9s | %6s %6s %6s | %4s\n", "scene", "tris", "rays",
           "shadow", "build_ms", "MB", "Mrays/s", "no-cache", "build_ms", "MB", "1st pass", "any-hit", "closest",
           "of occ", "of try", "tests", "bad");
    int status = BENCH_OK;
    /* lights: above and beside the object scenes; inside Sponza's atrium
     * (above its roof the whole floor would be in shadow) */
    struct { const char *file, *builtin; sidx_vec3 rel; } sc[3] = {
        {"bunny.obj", "icosphere", {0.2f, 1.2f, -0.1f}},
        {"sponza_dabrovic.obj", "stadium", {0.05f, 0.25f, 0.02f}},
        {"teapot.obj", "teapot", {0.2f, 1.2f, -0.1f}},
    };
    for (int i = 0; i < 3; ++i)
        if (lightbuffer_scene(o, sc[i].file, sc[i].builtin, sc[i].rel) != BENCH_OK) status = BENCH_FAIL;
    printf("columns: Mrays/s = shadow queries per second (one thread); no-cache = without the last-occluder cache;\n"
           "1st pass = the lazy buffer's first pass over the points, cell filling included; cached occluder: %% of\n"
           "occluded queries answered by the cell's last occluder, %% of cache tries that hit, triangle tests per\n"
           "query; bad = answers differing from the bvh's any-hit (must be 0)\n\n");
    return status;
}

/* ---- ray classification ----------------------------------------------------------------- */

typedef struct rc_row {
    char label[32];
    double build_ms, bytes, us[2];
    uint32_t leaves;
    double cand;
    size_t bad;
} rc_row;

static int rc_measure(const char *accel, uint32_t depth, const sidx_mesh *m, bench_rays *br, const sidx_hit *const *ref,
                      size_t nref, const ex_opts *o, rc_row *row)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.max_depth = depth;
    sidx_accel *a = NULL;
    sidx_error err;
    bench_progress("rayclass: building %s %u", accel, depth);
    const double t0 = bench_build_clock_ms();
    if (sidx_accel_build(accel, m, &bo, &a, &err) != SIDX_OK) {
        bench_progress_done();
        fprintf(stderr, "sidx-bench extras: %s: %s\n", accel, err.message);
        return 0;
    }
    row->build_ms = bench_build_clock_ms() - t0;
    sidx_accel_stats st;
    sidx_accel_stats_get(a, &st);
    row->bytes = (double)st.bytes;
    row->leaves = st.leaves;
    row->cand = st.mean_leaf_prims;
    if (depth) snprintf(row->label, sizeof row->label, "%s depth %u", accel, depth);
    else snprintf(row->label, sizeof row->label, "%s", accel);
    row->bad = 0;
    const size_t nmax = br[0].n > br[1].n ? br[0].n : br[1].n;
    sidx_hit *hits = malloc(nmax * sizeof *hits);
    if (!hits) { sidx_accel_destroy(a); return 0; }
    for (int k = 0; k < 2; ++k) {
        bench_progress("rayclass: timing %s", row->label);
        /* brute force is slow: its per-ray time from the first rays only */
        const size_t n = strcmp(accel, "brute") ? br[k].n : (br[k].n < 1000 ? br[k].n : 1000);
        trace_ctx c = {a, &br[k], n, 0, hits};
        row->us[k] = 1000.0 * time_best(trace_work, &c, o->budget_ms) / (double)n;
        if (ref) {
            const size_t nc = nref < n ? nref : n;
            for (size_t i = 0; i < nc; ++i) row->bad += !tk_hits_agree(&ref[k][i], &hits[i]);
        }
    }
    free(hits);
    sidx_accel_destroy(a);
    return 1;
}

static void print_repay(const rc_row *rc, const rc_row *other, int k, char *out, size_t size)
{
    const double gain = other->us[k] - rc->us[k];
    const double extra = rc->build_ms - other->build_ms;
    if (gain <= 0) snprintf(out, size, "never");
    else if (extra <= 0) snprintf(out, size, "at once");
    else snprintf(out, size, "%.3g", 1000.0 * extra / gain);
}

static int rayclass_scene(const ex_opts *o, const char *file, const char *builtin)
{
    sidx_mesh m;
    char name[64];
    if (!load_scene(o, file, builtin, &m, name, sizeof name)) return BENCH_FAIL;
    int status = BENCH_OK;
    bench_rays br[2] = {{NULL, NULL, 0}, {NULL, NULL, 0}};
    sidx_hit *ref[2] = {NULL, NULL};
    rc_row rows[16];
    int nrows = 0;
    if (!make_rays(&m, TK_RAYS_PRIMARY, o->rays, o->seed, &br[0]) ||
        !make_rays(&m, TK_RAYS_DIFFUSE, o->rays, o->seed + 1, &br[1])) {
        status = BENCH_FAIL;
        goto out;
    }
    /* brute force first: its hits are the reference for the check */
    if (!rc_measure("brute", 0, &m, br, NULL, 0, o, &rows[nrows])) { status = BENCH_FAIL; goto out; }
    ++nrows;
    const size_t nref = br[0].n < 1000 ? br[0].n : 1000;
    sidx_accel *brute = NULL;
    if (sidx_accel_build("brute", &m, NULL, &brute, NULL) != SIDX_OK) { status = BENCH_FAIL; goto out; }
    for (int k = 0; k < 2; ++k) {
        ref[k] = malloc(nref * sizeof *ref[k]);
        if (!ref[k]) { status = BENCH_FAIL; break; }
        bench_trace(brute, &br[k], 0, nref, NULL, 0, 1, 0.0, ref[k], NULL);
    }
    sidx_accel_destroy(brute);
    if (status != BENCH_OK) goto out;
    const sidx_hit *const refs[2] = {ref[0], ref[1]};
    if (rc_measure("bvh", 0, &m, br, refs, nref, o, &rows[nrows])) ++nrows;
    else status = BENCH_FAIL;
    for (const char *p = o->rc_depths; *p && nrows < 16;) {
        char *end;
        const unsigned long d = strtoul(p, &end, 10);
        if (rc_measure("rayclass", (uint32_t)d, &m, br, refs, nref, o, &rows[nrows])) ++nrows;
        else status = BENCH_FAIL;
        p = *end == ',' ? end + 1 : end;
    }
    bench_progress_done();
    printf("-- %s, %u triangles, %zu primary + %zu diffuse rays (brute force timed on 1000)\n", name, m.num_triangles,
           br[0].n, br[1].n);
    printf("%-20s %10s %9s %8s %9s %11s %11s %11s %11s %12s %12s %5s\n", "structure", "build_ms", "MB", "leaves",
           "cand/leaf", "primary us", "diffuse us", "prim Mr/s", "diff Mr/s", "repay/brute", "repay/bvh", "bad");
    for (int i = 0; i < nrows; ++i) {
        const rc_row *r = &rows[i];
        char rb[24] = "-", rv[24] = "-";
        if (i >= 1) print_repay(r, &rows[0], 1, rb, sizeof rb);
        if (i >= 2) print_repay(r, &rows[1], 1, rv, sizeof rv);
        printf("%-20s %10.1f %9.2f %8u %9.1f %11.3f %11.3f %11.2f %11.2f %12s %12s %5zu\n", r->label, r->build_ms,
               mb(r->bytes), r->leaves, r->cand, r->us[0], r->us[1], r->us[0] > 0 ? 1.0 / r->us[0] : 0.0,
               r->us[1] > 0 ? 1.0 / r->us[1] : 0.0, rb, rv, r->bad);
        if (r->bad) status = BENCH_FAIL;
    }
out:
    free(ref[0]);
    free(ref[1]);
    bench_rays_free(&br[0]);
    bench_rays_free(&br[1]);
    sidx_mesh_free(&m);
    return status;
}

static int part_rayclass(const ex_opts *o)
{
    printf("== ray classification (Arvo & Kirk 1987): preprocessing and memory against per-ray gain\n");
    int status = BENCH_OK;
    if (rayclass_scene(o, "teapot.obj", "teapot") != BENCH_OK) status = BENCH_FAIL;
    if (rayclass_scene(o, NULL, "cornell") != BENCH_OK) status = BENCH_FAIL;
    printf("repay = diffuse rays needed before the extra build time is paid back by faster tracing\n"
           "((build - build_other) / (us_other - us)); never = slower per ray; bad = hits differing from\n"
           "brute force on the first 1000 rays of each kind (must be 0)\n\n");
    return status;
}

/* ---- the command ----------------------------------------------------------------------- */

static void extras_usage(FILE *out)
{
    fprintf(out,
            "usage: sidx-bench extras [options]\n"
            "\n"
            "Rows beside the benchmark table for what is not a registered structure:\n"
            "  instancing   N instances of the bunny (built-in teapot without --scenes) sharing\n"
            "               one bvh in an aggregate: build ms, primary and diffuse Mrays/s,\n"
            "               MB against an ESTIMATE of one flattened bvh over every copy\n"
            "  lightbuffer  shadow rays to a point light on bunny, Sponza, teapot (built-in\n"
            "               icosphere, stadium, teapot without --scenes): light buffer against\n"
            "               any-hit on the bvh, MB, hit rate of the cached last occluder\n"
            "  rayclass     ray classification at several depths against brute force and the\n"
            "               bvh: build ms and MB against per-ray time, rays needed to repay it\n"
            "Every row is checked against a reference; a disagreement makes the exit status 1.\n"
            "options:\n"
            "  --scenes DIR       take bunny.obj, sponza_dabrovic.obj, teapot.obj from DIR\n"
            "  --only LIST        parts to run (default instancing,lightbuffer,rayclass)\n"
            "  --instances N      instances for the instancing part (default 10000)\n"
            "  --rays N           rays per kind (default 20000)\n"
            "  --check N          instanced rays per kind checked against the per-instance\n"
            "                     reference (default 200; each costs N instance traversals)\n"
            "  --depths LIST      ray-classification depths (default 6,8,10)\n"
            "  --lb-res N         light-buffer cells along a cube face's edge (default 32, at most 1024)\n"
            "  --seed S           placement and ray seed (default 1)\n"
            "  --time-budget MS   repeat each timing while under MS ms (default 300; at least 3 runs,\n"
            "                     the best counts)\n"
            "Times are CPU time of this thread. Progress goes to stderr when it is a terminal.\n"
            "Exit status: 0 ok, 1 failure or disagreement, 2 usage error.\n");
}

int bench_cmd_extras(int argc, char **argv)
{
    ex_opts o = {NULL, NULL, "6,8,10", 10000, 32, 20000, 200, 1, 300.0};
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            extras_usage(stdout);
            return BENCH_OK;
        }
        static const char *const known[] = {"--scenes", "--only", "--depths", "--instances", "--rays",
                                            "--check", "--seed", "--time-budget", "--lb-res", NULL};
        int is_known = 0;
        for (int k = 0; known[k]; ++k) is_known |= !strcmp(a, known[k]);
        if (a[0] == '-' && !is_known) {
            fprintf(stderr, "sidx-bench extras: unknown option '%s'\n", a);
            extras_usage(stderr);
            return BENCH_USAGE;
        }
        const char *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (a[0] != '-' || !val) {
            fprintf(stderr, "sidx-bench extras: unexpected '%s'%s\n", a, a[0] == '-' ? " (needs a value)" : "");
            extras_usage(stderr);
            return BENCH_USAGE;
        }
        ++i;
        char *end = NULL;
        if (!strcmp(a, "--scenes")) o.scenes_dir = val;
        else if (!strcmp(a, "--only")) o.parts = val;
        else if (!strcmp(a, "--depths")) {
            o.rc_depths = val;
            for (const char *p = val; *p; ++p)
                if (!((*p >= '0' && *p <= '9') || *p == ',')) goto bad_value;
            if (!*val) goto bad_value;
        } else if (!strcmp(a, "--instances")) {
            const unsigned long v = strtoul(val, &end, 10);
            if (*end || v == 0 || v > 10000000) goto bad_value;
            o.instances = (uint32_t)v;
        } else if (!strcmp(a, "--lb-res")) {
            const unsigned long v = strtoul(val, &end, 10);
            if (*end || v == 0 || v > 1024) goto bad_value;
            o.lb_res = (uint32_t)v;
        } else if (!strcmp(a, "--rays")) {
            o.rays = (size_t)strtoull(val, &end, 10);
            if (*end || o.rays == 0 || o.rays > 100000000) goto bad_value;
        } else if (!strcmp(a, "--check")) {
            o.check = (size_t)strtoull(val, &end, 10);
            if (*end) goto bad_value;
        } else if (!strcmp(a, "--seed")) {
            o.seed = strtoull(val, &end, 0);
            if (*end) goto bad_value;
        } else if (!strcmp(a, "--time-budget")) {
            o.budget_ms = strtod(val, &end);
            if (*end || !(o.budget_ms >= 0)) goto bad_value;
        } else {
            fprintf(stderr, "sidx-bench extras: unknown option '%s'\n", a);
            extras_usage(stderr);
            return BENCH_USAGE;
        }
        continue;
    bad_value:
        fprintf(stderr, "sidx-bench extras: bad value '%s' for %s\n", val, a);
        return BENCH_USAGE;
    }
    if (o.parts) {
        const char *p = o.parts;
        while (*p) {
            const size_t len = strcspn(p, ",");
            if (!((len == 10 && !strncmp(p, "instancing", 10)) || (len == 11 && !strncmp(p, "lightbuffer", 11)) ||
                  (len == 8 && !strncmp(p, "rayclass", 8)))) {
                fprintf(stderr, "sidx-bench extras: unknown part '%.*s' in --only (instancing lightbuffer rayclass)\n",
                        (int)len, p);
                return BENCH_USAGE;
            }
            p += len;
            if (*p == ',') ++p;
        }
    }
    if (!sidx_accel_is_registered("bvh") || !sidx_accel_is_registered("brute")) {
        fprintf(stderr, "sidx-bench extras: needs the bvh and brute structures\n");
        return BENCH_FAIL;
    }
    bench_cpu_time = 1;
    int status = BENCH_OK;
    if (bench_list_has(o.parts, "instancing") && part_instancing(&o) != BENCH_OK) status = BENCH_FAIL;
    if (bench_list_has(o.parts, "lightbuffer") && part_lightbuffer(&o) != BENCH_OK) status = BENCH_FAIL;
    if (bench_list_has(o.parts, "rayclass")) {
        if (!sidx_accel_is_registered("rayclass")) {
            fprintf(stderr, "sidx-bench extras: rayclass is not registered\n");
            status = BENCH_FAIL;
        } else if (part_rayclass(&o) != BENCH_OK) {
            status = BENCH_FAIL;
        }
    }
    return status;
}
