/* trace.c — `sidx-bench trace` and `sidx-bench rays`, and the threaded
 * tracing loop every command times. */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"

int bench_rays_prepare(const tk_rayrec *rec, size_t n, bench_rays *out)
{
    out->n = n;
    out->r = malloc((n ? n : 1) * sizeof *out->r);
    out->valid = malloc(n ? n : 1);
    if (!out->r || !out->valid) {
        bench_rays_free(out);
        return 0;
    }
    for (size_t i = 0; i < n; ++i) {
        out->valid[i] = tk_ray_from(&rec[i], &out->r[i]) == SIDX_OK;
        if (!out->valid[i]) memset(&out->r[i], 0, sizeof out->r[i]);
    }
    return 1;
}

void bench_rays_free(bench_rays *br)
{
    free(br->r);
    free(br->valid);
    br->r = NULL;
    br->valid = NULL;
    br->n = 0;
}

typedef struct trace_job {
    const sidx_accel *a;
    const bench_rays *br;
    size_t begin, end, done;
    const sidx_query *q;
    int any_hit;
    double budget_ms, t0;
    sidx_hit *hits;
} trace_job;

static void trace_range(trace_job *j)
{
    sidx_query q = *j->q;
    const uint32_t base = q.ray_id;
    size_t i = j->begin;
    while (i < j->end) {
        size_t stop = j->end;
        if (j->budget_ms > 0 && stop - i > 256) stop = i + 256;
        for (; i < stop; ++i) {
            sidx_hit *h = &j->hits[i];
            if (!j->br->valid[i]) {
                *h = sidx_hit_none();
                continue;
            }
            q.ray_id = base + (uint32_t)i;
            if (j->any_hit) {
                int occ = 0;
                sidx_accel_occluded(j->a, &j->br->r[i], &q, &occ);
                *h = sidx_hit_none();
                if (occ) {
                    h->prim = 0;
                    h->t = 0.0f;
                }
            } else {
                sidx_accel_intersect(j->a, &j->br->r[i], &q, h);
            }
        }
        if (j->budget_ms > 0 && bench_clock_ms() - j->t0 > j->budget_ms) break;
    }
    j->done = i - j->begin;
}

static void *trace_worker(void *p)
{
    trace_range(p);
    return NULL;
}

size_t bench_trace(const sidx_accel *a, const bench_rays *br, size_t begin, size_t end, const sidx_query *q,
                   int any_hit, unsigned threads, double budget_ms, sidx_hit *hits, double *ms)
{
    static const sidx_query none = {0, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    if (!q) q = &none;
    if (threads < 1) threads = 1;
    if (threads > 256) threads = 256;
    const size_t n = end - begin;
    if ((size_t)threads > n) threads = n ? (unsigned)n : 1;
    trace_job jobs[256] = {0};
    pthread_t tid[256];
    int started[256];
    /* one thread: its CPU time (bench_cpu_time); several: wall-clock */
    double (*clock_ms)(void) = threads == 1 ? bench_clock_ms : tk_now_ms;
    const double t0 = clock_ms();
    for (unsigned t = 0; t < threads; ++t) {
        jobs[t] = (trace_job){a, br, begin + n * t / threads, begin + n * (t + 1) / threads, 0, q, any_hit,
                              threads == 1 ? budget_ms : 0.0, t0, hits};
        started[t] = t > 0 && pthread_create(&tid[t], NULL, trace_worker, &jobs[t]) == 0;
    }
    trace_range(&jobs[0]);
    size_t done = jobs[0].done;
    for (unsigned t = 1; t < threads; ++t) {
        if (started[t]) pthread_join(tid[t], NULL);
        else trace_range(&jobs[t]);
        done += jobs[t].done;
    }
    if (ms) *ms = clock_ms() - t0;
    return done;
}

/* ---- timing: a cold pass, then the best and median of warm passes ------------ */

double bench_mrays(size_t rays, double ms) { return ms > 0 ? (double)rays / (ms * 1e3) : 0.0; }

void bench_touch(const bench_buf *bufs, int nbufs)
{
    enum { PAGE = 4096 };
    unsigned sum = 0;
    for (int b = 0; b < nbufs; ++b) {
        volatile unsigned char *c = (volatile unsigned char *)(uintptr_t)bufs[b].p;
        const size_t bytes = bufs[b].bytes;
        if (!c || !bytes) continue;
        /* each page, and the last byte; a write puts back the byte read */
        for (size_t i = 0; i < bytes + PAGE - 1; i += PAGE) {
            const size_t at = i < bytes ? i : bytes - 1;
            const unsigned char v = c[at];
            if (bufs[b].write) c[at] = v;
            else sum += v;
        }
    }
    volatile unsigned sink = sum; /* the reads are not optimised away */
    (void)sink;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void bench_time_passes(double (*pass)(void *ctx, int cold), void *ctx, const bench_buf *bufs, int nbufs,
                       int passes, double budget_ms, bench_timing *out)
{
    enum { MAX_PASSES = 1000 };
    double ms[MAX_PASSES];
    if (passes < 1) passes = 1;
    if (passes > MAX_PASSES) passes = MAX_PASSES;
    out->cold_ms = pass(ctx, 1);
    bench_touch(bufs, nbufs);
    ms[0] = pass(ctx, 0);
    double spent = ms[0];
    int n = 1;
    while (n < passes && (budget_ms <= 0 || spent < budget_ms)) {
        ms[n] = pass(ctx, 0);
        spent += ms[n++];
    }
    qsort(ms, (size_t)n, sizeof ms[0], cmp_double);
    out->best_ms = ms[0];
    out->median_ms = n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
    out->passes = n;
}

typedef struct sidx_pass {
    const sidx_accel *a;
    const bench_rays *br;
    size_t begin, end;
    const sidx_query *q;
    int any_hit;
    unsigned threads;
    sidx_hit *hits;
} sidx_pass;

static double sidx_pass_run(void *ctx, int cold)
{
    (void)cold;
    const sidx_pass *p = ctx;
    double ms = 0;
    bench_trace(p->a, p->br, p->begin, p->end, p->q, p->any_hit, p->threads, 0.0, p->hits, &ms);
    return ms;
}

void bench_trace_timed(const sidx_accel *a, const bench_rays *br, size_t begin, size_t end, const sidx_query *q,
                       int any_hit, unsigned threads, int passes, double budget_ms, sidx_hit *hits, bench_timing *t)
{
    sidx_pass p = {a, br, begin, end, q, any_hit, threads, hits};
    const bench_buf bufs[3] = {{hits + begin, (end - begin) * sizeof *hits, 1},
                               {br->r + begin, (end - begin) * sizeof *br->r, 0},
                               {br->valid + begin, end - begin, 0}};
    bench_time_passes(sidx_pass_run, &p, bufs, 3, passes, budget_ms, t);
}

/* ---- trace ------------------------------------------------------------------ */

static void trace_usage(FILE *out)
{
    fprintf(out,
            "usage: sidx-bench trace --accel NAME SCENE RAYS.bin HITS.bin [options]\n"
            "\n"
            "Builds structure NAME (a registered name, \"auto\", or embree, embree-robust,\n"
            "embree-hq, embree-robust-hq) over SCENE (mesh file or built-in name[:detail]),\n"
            "traces every ray of RAYS.bin and writes HITS.bin.\n"
            "\n"
            "  RAYS.bin   little-endian records of 8 float32: ox oy oz dx dy dz tmin tmax\n"
            "             (directions need not be normalized; t is in units of |d|)\n"
            "  HITS.bin   16-byte records: float32 t, int32 prim, float32 u, float32 v;\n"
            "             a miss is (+inf, -1, 0, 0); prim = triangle index in file order\n"
            "             after fan triangulation; u, v = barycentrics of the 2nd and 3rd vertex.\n"
            "             With --any-hit an occluded ray is (0, 0, 0, 0), a free one the miss record.\n"
            "options:\n"
            "  --threads N                    pthreads splitting the ray array (default 1)\n"
            "  --any-hit                      occlusion queries (sidx_accel_occluded)\n"
            "  --traversal default|stack|ordered|naive\n"
            "  --tri watertight|moller|twostep  triangle test (default watertight)\n"
            "  --box robust|plain             box test (default robust)\n"
            "  --uv 0|1                       compute u, v (default 1)\n"
            "  --precise-t                    refine the closest hit's t on its plane (SIDX_QUERY_PRECISE_T)\n"
            "  --optimize MS                  bvh, bvh4, bvh8: reinsertion pass over the binary tree,\n"
            "                                 at most MS ms (sidx_build_options.optimize_ms; default off)\n"
            "  --cpu-time                     time one-thread traces in thread CPU time, builds in\n"
            "                                 process CPU time (default: wall-clock)\n"
            "  --passes N                     warm passes timed after the cold one (default %d)\n"
            "Timing: the first pass runs cold (caches cold, the hit array's pages faulted in as\n"
            "it is written) and is reported apart; then the hit array is written and the rays\n"
            "read once more, untimed, and N warm passes are timed.  Embree is timed the same way.\n"
            "Prints one JSON line: accel, tris, rays, build_ms, trace_ms and mrays_per_s (the best\n"
            "warm pass, the headline figure), mrays_best (the same), mrays_median (the median warm\n"
            "pass), mrays_cold and cold_ms (the first pass), passes, hits, nodes, bytes.\n"
            "Exit status: 0 ok, 1 failure (I/O, build), 2 usage (bad option, unknown accel,\n"
            "a file whose size is not a multiple of its record size).\n",
            BENCH_PASSES);
}

int bench_cmd_trace(int argc, char **argv)
{
    const char *accel = NULL, *pos[3] = {NULL, NULL, NULL};
    int npos = 0, any_hit = 0, uv = 1, passes = BENCH_PASSES;
    unsigned threads = 1;
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *val = (i + 1 < argc) ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            trace_usage(stdout);
            return BENCH_OK;
        } else if (!strcmp(a, "--any-hit")) {
            any_hit = 1;
        } else if (!strcmp(a, "--precise-t")) {
            q.flags |= SIDX_QUERY_PRECISE_T;
        } else if (!strcmp(a, "--cpu-time")) {
            bench_cpu_time = 1;
        } else if (!strcmp(a, "--accel") || !strcmp(a, "--threads") || !strcmp(a, "--traversal") ||
                   !strcmp(a, "--tri") || !strcmp(a, "--box") || !strcmp(a, "--uv") || !strcmp(a, "--optimize") ||
                   !strcmp(a, "--passes")) {
            if (!val) {
                fprintf(stderr, "sidx-bench trace: %s needs a value\n", a);
                return BENCH_USAGE;
            }
            ++i;
            if (!strcmp(a, "--accel")) accel = val;
            else if (!strcmp(a, "--threads")) {
                char *end;
                long t = strtol(val, &end, 10);
                if (*end || t < 1 || t > 256) {
                    fprintf(stderr, "sidx-bench trace: --threads must be 1..256, not '%s'\n", val);
                    return BENCH_USAGE;
                }
                threads = (unsigned)t;
            } else if (!strcmp(a, "--passes")) {
                char *end;
                long v = strtol(val, &end, 10);
                if (*end || end == val || v < 1 || v > 1000) {
                    fprintf(stderr, "sidx-bench trace: --passes must be 1..1000, not '%s'\n", val);
                    return BENCH_USAGE;
                }
                passes = (int)v;
            } else if (!strcmp(a, "--optimize")) {
                char *end;
                const float ms = strtof(val, &end);
                if (*end || end == val || !(ms >= 0.0f)) {
                    fprintf(stderr, "sidx-bench trace: --optimize wants milliseconds >= 0, not '%s'\n", val);
                    return BENCH_USAGE;
                }
                bo.optimize_ms = ms;
            } else if (!strcmp(a, "--traversal")) {
                if (sidx_traversal_parse(val, &q.traversal) != SIDX_OK) {
                    fprintf(stderr, "sidx-bench trace: unknown traversal '%s' (default, stack, ordered, naive)\n",
                            val);
                    return BENCH_USAGE;
                }
            } else if (!strcmp(a, "--tri")) {
                if (sidx_tri_method_parse(val, &bo.tri) != SIDX_OK) {
                    fprintf(stderr, "sidx-bench trace: unknown triangle test '%s' (watertight, moller, twostep)\n",
                            val);
                    return BENCH_USAGE;
                }
            } else if (!strcmp(a, "--box")) {
                if (sidx_box_method_parse(val, &bo.box) != SIDX_OK) {
                    fprintf(stderr, "sidx-bench trace: unknown box test '%s' (robust, plain)\n", val);
                    return BENCH_USAGE;
                }
            } else {
                if (strcmp(val, "0") && strcmp(val, "1")) {
                    fprintf(stderr, "sidx-bench trace: --uv takes 0 or 1\n");
                    return BENCH_USAGE;
                }
                uv = val[0] == '1';
            }
        } else if (a[0] == '-' && a[1] == '-') {
            fprintf(stderr, "sidx-bench trace: unknown option '%s'\n", a);
            return BENCH_USAGE;
        } else {
            if (npos == 3) {
                fprintf(stderr, "sidx-bench trace: too many arguments ('%s')\n", a);
                return BENCH_USAGE;
            }
            pos[npos++] = a;
        }
    }
    if (!accel || npos != 3) {
        fprintf(stderr, "sidx-bench trace: need --accel NAME SCENE RAYS.bin HITS.bin\n");
        trace_usage(stderr);
        return BENCH_USAGE;
    }
    bench_embree_cfg ecfg;
    const int is_embree = bench_embree_parse(accel, &ecfg);
    if (!is_embree && !sidx_accel_is_registered(accel)) {
        fprintf(stderr, "sidx-bench trace: unknown structure '%s'; registered:", accel);
        for (size_t i = 0; i < sidx_accel_registered_count(); ++i)
            fprintf(stderr, " %s", sidx_accel_registered_name(i));
        fprintf(stderr, " auto embree embree-robust embree-hq embree-robust-hq\n");
        return BENCH_USAGE;
    }
    sidx_error err = {SIDX_OK, ""};
    tk_rayrec *rec = NULL;
    size_t n = 0;
    sidx_status s = tk_read_rays(pos[1], &rec, &n, &err);
    if (s != SIDX_OK) {
        fprintf(stderr, "sidx-bench trace: %s\n", err.message);
        return s == SIDX_ERR_PARSE ? BENCH_USAGE : BENCH_FAIL;
    }
    sidx_mesh mesh = {0};
    s = sidx_scene_open(pos[0], &mesh, &err);
    if (s != SIDX_OK) {
        fprintf(stderr, "sidx-bench trace: %s\n", err.message);
        free(rec);
        return s == SIDX_ERR_INVALID_ARG ? BENCH_USAGE : BENCH_FAIL;
    }
    int rc = BENCH_FAIL;
    sidx_hit *hits = malloc((n ? n : 1) * sizeof *hits);
    tk_hitrec *out = malloc((n ? n : 1) * sizeof *out);
    bench_rays br = {0};
    sidx_accel *acc = NULL;
    bench_embree *emb = NULL;
    if (!hits || !out || !bench_rays_prepare(rec, n, &br)) {
        fprintf(stderr, "sidx-bench trace: out of memory for %zu rays\n", n);
        goto done;
    }
    double build_ms = 0;
    bench_timing tm = {0, 0, 0, 0};
    uint32_t nodes = 0;
    size_t bytes = 0;
    const char *picked = accel;
    if (is_embree) {
        char msg[256];
        if (!bench_embree_build(&mesh, ecfg, &emb, &build_ms, msg, sizeof msg)) {
            fprintf(stderr, "sidx-bench trace: %s\n", msg);
            goto done;
        }
        if (threads > 1) fprintf(stderr, "sidx-bench trace: embree rows trace on one thread\n");
        bench_embree_trace_timed(emb, rec, n, any_hit, 1, passes, 0.0, hits, &tm);
        bytes = bench_embree_bytes(emb);
    } else {
        const double t0 = bench_build_clock_ms();
        s = sidx_accel_build(accel, &mesh, &bo, &acc, &err);
        build_ms = bench_build_clock_ms() - t0;
        if (s != SIDX_OK) {
            fprintf(stderr, "sidx-bench trace: building %s: %s\n", accel, err.message);
            goto done;
        }
        picked = sidx_accel_name(acc);
        if (uv) q.flags |= SIDX_QUERY_UV;
        bench_trace_timed(acc, &br, 0, n, &q, any_hit, threads, passes, 0.0, hits, &tm);
        sidx_accel_stats st;
        sidx_accel_stats_get(acc, &st);
        nodes = st.nodes;
        bytes = st.bytes;
    }
    size_t nhits = 0;
    for (size_t i = 0; i < n; ++i) {
        out[i] = tk_hitrec_from(&hits[i]);
        nhits += hits[i].prim != SIDX_NO_HIT;
    }
    s = tk_write_hits(pos[2], out, n, &err);
    if (s != SIDX_OK) {
        fprintf(stderr, "sidx-bench trace: %s\n", err.message);
        goto done;
    }
    printf("{\"accel\":\"%s\",\"picked\":\"%s\",\"tris\":%u,\"rays\":%zu,\"build_ms\":%.3f,\"trace_ms\":%.3f,"
           "\"mrays_per_s\":%.4f,\"mrays_best\":%.4f,\"mrays_median\":%.4f,\"mrays_cold\":%.4f,\"cold_ms\":%.3f,"
           "\"passes\":%d,\"hits\":%zu,\"nodes\":%u,\"bytes\":%zu,\"threads\":%u,\"any_hit\":%s,"
           "\"tri\":\"%s\",\"box\":\"%s\",\"traversal\":\"%s\"}\n",
           accel, picked, mesh.num_triangles, n, build_ms, tm.best_ms, bench_mrays(n, tm.best_ms),
           bench_mrays(n, tm.best_ms), bench_mrays(n, tm.median_ms), bench_mrays(n, tm.cold_ms), tm.cold_ms,
           tm.passes, nhits, nodes, bytes, is_embree ? 1u : threads,
           any_hit ? "true" : "false", sidx_tri_method_name(bo.tri), sidx_box_method_name(bo.box),
           sidx_traversal_name(q.traversal));
    rc = BENCH_OK;
done:
    bench_embree_free(emb);
    sidx_accel_destroy(acc);
    bench_rays_free(&br);
    free(hits);
    free(out);
    free(rec);
    sidx_mesh_free(&mesh);
    return rc;
}

/* ---- rays ------------------------------------------------------------------- */

static void rays_usage(FILE *out)
{
    fprintf(out,
            "usage: sidx-bench rays SCENE KIND COUNT SEED OUT.bin\n"
            "\n"
            "Writes COUNT rays (the benchmark's ray sets, deterministic in SEED) for SCENE.\n"
            "KIND:\n"
            "  primary  pinhole camera outside the scene box looking at its centre, image rows\n"
            "  diffuse  random origins inside the box, uniform random directions\n"
            "  shadow   segments between random surface points: d = p2 - p1, t in [1e-3, 1 - 1e-3]\n"
            "  grazing  aimed exactly at vertices and edge midpoints; nearly parallel to triangles\n"
            "  axis     axis-parallel directions with exact +-0 components, some through vertices\n"
            "Directions are scaled to the scene's size, so t is about 1 at the scene.\n"
            "PRNG: xoshiro256** seeded by splitmix64(SEED).\n");
}

static int parse_u64(const char *s, uint64_t *out)
{
    char *end;
    errno = 0;
    if (!s || !*s || *s == '-') return 0;
    unsigned long long v = strtoull(s, &end, 0);
    if (*end || errno) return 0;
    *out = v;
    return 1;
}

int bench_cmd_rays(int argc, char **argv)
{
    for (int i = 1; i < argc; ++i)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            rays_usage(stdout);
            return BENCH_OK;
        }
    if (argc != 6) {
        rays_usage(stderr);
        return BENCH_USAGE;
    }
    tk_ray_kind kind;
    uint64_t count, seed;
    if (!tk_ray_kind_parse(argv[2], &kind)) {
        fprintf(stderr, "sidx-bench rays: unknown kind '%s' (primary diffuse shadow grazing axis)\n", argv[2]);
        return BENCH_USAGE;
    }
    if (!parse_u64(argv[3], &count) || count > (1ull << 31)) {
        fprintf(stderr, "sidx-bench rays: COUNT must be a number up to 2^31, not '%s'\n", argv[3]);
        return BENCH_USAGE;
    }
    if (!parse_u64(argv[4], &seed)) {
        fprintf(stderr, "sidx-bench rays: SEED must be a non-negative number, not '%s'\n", argv[4]);
        return BENCH_USAGE;
    }
    sidx_error err = {SIDX_OK, ""};
    sidx_mesh mesh = {0};
    sidx_status s = sidx_scene_open(argv[1], &mesh, &err);
    if (s != SIDX_OK) {
        fprintf(stderr, "sidx-bench rays: %s\n", err.message);
        return s == SIDX_ERR_INVALID_ARG ? BENCH_USAGE : BENCH_FAIL;
    }
    tk_rayrec *r = malloc((count ? count : 1) * sizeof *r);
    if (!r) {
        fprintf(stderr, "sidx-bench rays: out of memory\n");
        sidx_mesh_free(&mesh);
        return BENCH_FAIL;
    }
    tk_make_rays(&mesh, kind, (size_t)count, seed, r);
    s = tk_write_rays(argv[5], r, (size_t)count, &err);
    free(r);
    sidx_mesh_free(&mesh);
    if (s != SIDX_OK) {
        fprintf(stderr, "sidx-bench rays: %s\n", err.message);
        return BENCH_FAIL;
    }
    printf("{\"scene\":\"%s\",\"kind\":\"%s\",\"rays\":%llu,\"seed\":%llu,\"file\":\"%s\"}\n", argv[1],
           tk_ray_kind_name(kind), (unsigned long long)count, (unsigned long long)seed, argv[5]);
    return BENCH_OK;
}
