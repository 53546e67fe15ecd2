/* stream.c — `sidx-bench stream`: the stream entry (sidx_accel_intersect_n,
 * _occluded_n; lib/bvh_stream.c) against single queries and against
 * Embree's single-ray and stream entries, in one run.
 *
 * Per scene and ray kind, every tracer runs in each of R rounds, in an
 * order rotated from round to round (interleaved: a slow spell of the
 * shared machine falls on every tracer alike): one warm-up pass, then P
 * timed passes, the round keeping the best.  Reported per tracer: Mrays/s
 * of the median round, and its speed ratio to Embree's rtcIntersect1 (and
 * stream / single for the same structure) as median [min..max] over the
 * rounds' ratios.  Thread CPU time, one thread.
 *
 * The sidx rows time the query alone (rays prepared with sidx_ray_init
 * beforehand, t and prim asked); the Embree rows build their RTCRay(Hit)
 * per ray inside the timed part, as sidx-bench run does, and Embree
 * always returns u, v and Ng.  Shadow rays are any-hit queries
 * (occluded, rtcOccluded1 / 1M).  Before timing, the stream's answers are
 * checked equal, byte for byte, to the single queries'. */
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include "bench.h"

#define MAX_ROUNDS 15
#define MAX_PASSES 15

enum { A_BVH, A_BVH4, A_BVH8, NACCEL };
static const char *const accel_names[NACCEL] = {"bvh", "bvh4", "bvh8"};
enum { M_SINGLE, M_STREAM, M_REORDER, NMODE };
static const char *const mode_names[NMODE] = {"single", "stream", "stream+reorder"};
#define NTRACER (NACCEL * NMODE + 2)
#define T_EMBREE1 (NACCEL * NMODE)
#define T_EMBREE1M (NACCEL * NMODE + 1)

typedef struct ctx {
    sidx_accel *a[NACCEL];
    bench_embree *e;
    const tk_rayrec *rec;
    const sidx_ray *rays;
    size_t n;
    int any_hit, coherent;
    sidx_hit *hits;
    int *occ;
    void *scratch;
} ctx;

static double run_tracer(ctx *c, int t)
{
    if (t == T_EMBREE1) return bench_embree_trace(c->e, c->rec, c->n, c->any_hit, 1, c->hits);
    if (t == T_EMBREE1M) return bench_embree_trace_stream(c->e, c->rec, c->n, c->any_hit, c->coherent, c->scratch, c->hits);
    const sidx_accel *a = c->a[t / NMODE];
    const int mode = t % NMODE;
    sidx_query q = {mode == M_REORDER ? SIDX_QUERY_REORDER : 0u, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    const double t0 = bench_clock_ms();
    if (mode == M_SINGLE) {
        if (c->any_hit)
            for (size_t i = 0; i < c->n; ++i) (void)sidx_accel_occluded(a, &c->rays[i], &q, &c->occ[i]);
        else
            for (size_t i = 0; i < c->n; ++i) (void)sidx_accel_intersect(a, &c->rays[i], &q, &c->hits[i]);
    } else if (c->any_hit) {
        (void)sidx_accel_occluded_n(a, c->rays, c->n, &q, c->occ);
    } else {
        (void)sidx_accel_intersect_n(a, c->rays, c->n, &q, c->hits);
    }
    return bench_clock_ms() - t0;
}

static int cmp_double(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}
static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
static void minmax(const double *v, int n, double *lo, double *hi)
{
    *lo = *hi = v[0];
    for (int i = 1; i < n; ++i) {
        if (v[i] < *lo) *lo = v[i];
        if (v[i] > *hi) *hi = v[i];
    }
}

/* The stream's answers equal the single queries', byte for byte. */
static int check_same(ctx *c)
{
    const size_t n = c->n;
    sidx_hit *one = malloc(n * sizeof *one), *many = malloc(n * sizeof *many);
    int *o1 = malloc(n * sizeof *o1), *on = malloc(n * sizeof *on), ok = one && many && o1 && on;
    for (int k = 0; ok && k < NACCEL; ++k)
        for (int reorder = 0; ok && reorder < 2; ++reorder) {
            sidx_query q = {reorder ? SIDX_QUERY_REORDER : 0u, SIDX_TRAVERSE_DEFAULT, NULL, 0};
            for (size_t i = 0; i < n; ++i) {
                (void)sidx_accel_intersect(c->a[k], &c->rays[i], &q, &one[i]);
                (void)sidx_accel_occluded(c->a[k], &c->rays[i], &q, &o1[i]);
            }
            (void)sidx_accel_intersect_n(c->a[k], c->rays, n, &q, many);
            (void)sidx_accel_occluded_n(c->a[k], c->rays, n, &q, on);
            ok = !memcmp(one, many, n * sizeof *one) && !memcmp(o1, on, n * sizeof *o1);
            if (!ok) fprintf(stderr, "stream: %s%s: the stream's answers differ from single queries\n",
                             accel_names[k], reorder ? " (reordered)" : "");
        }
    free(one);
    free(many);
    free(o1);
    free(on);
    return ok;
}

static int open_mesh(const char *name, const char *dir, sidx_mesh *m)
{
    sidx_error err = {SIDX_OK, ""};
    char best[256] = "";
    DIR *d = dir ? opendir(dir) : NULL;
    const size_t nl = strlen(name);
    for (struct dirent *de; d && (de = readdir(d));) {
        const size_t l = strlen(de->d_name);
        if (l > 4 && l < sizeof best && !strncmp(de->d_name, name, nl) &&
            (!strcmp(de->d_name + l - 4, ".obj") || !strcmp(de->d_name + l - 4, ".ply")) &&
            (!best[0] || strcmp(de->d_name, best) < 0))
            snprintf(best, sizeof best, "%s", de->d_name);
    }
    if (d) closedir(d);
    char path[1024];
    if (best[0]) snprintf(path, sizeof path, "%s/%s", dir, best);
    else snprintf(path, sizeof path, "%s", name);
    if (sidx_scene_open(path, m, &err) == SIDX_OK) return 1;
    fprintf(stderr, "stream: scene %s: %s\n", name, err.message);
    return 0;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: sidx-bench stream [--scenes DIR] [--scene LIST] [--kinds LIST] [--rays N] [--rounds R]\n"
               "                         [--passes P] [--seed S]\n"
               "  LIST comma-separated; defaults: --scene bunny,sponza --kinds primary,diffuse,shadow\n"
               "  --rays 100000 --rounds 5 --passes 3.  Scenes are looked up in DIR (NAME*.obj/.ply),\n"
               "  else taken as a built-in scene name or a path.\n");
}

int bench_cmd_stream(int argc, char **argv)
{
    const char *dir = NULL, *scene_list = "bunny,sponza", *kind_list = "primary,diffuse,shadow";
    size_t nrays = 100000;
    int rounds = 5, passes = 3;
    uint64_t seed = 1;
    for (int i = 1; i < argc; i += 2) { /* every option takes a value */
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(o, "--help") || !strcmp(o, "-h")) { usage(stdout); return BENCH_OK; }
        if (!v) { usage(stderr); return BENCH_USAGE; }
        if (!strcmp(o, "--scenes")) dir = v;
        else if (!strcmp(o, "--scene")) scene_list = v;
        else if (!strcmp(o, "--kinds")) kind_list = v;
        else if (!strcmp(o, "--rays")) nrays = (size_t)strtoull(v, NULL, 10);
        else if (!strcmp(o, "--rounds")) rounds = atoi(v);
        else if (!strcmp(o, "--passes")) passes = atoi(v);
        else if (!strcmp(o, "--seed")) seed = strtoull(v, NULL, 10);
        else { usage(stderr); return BENCH_USAGE; }
    }
    if (nrays == 0 || nrays > 100000000 || rounds < 1 || rounds > MAX_ROUNDS || passes < 1 || passes > MAX_PASSES) {
        usage(stderr);
        return BENCH_USAGE;
    }
    bench_cpu_time = 1;
    printf("sidx-bench stream: %zu rays, %d rounds of (1 warm-up + %d passes, best kept), thread CPU time;\n"
           "ratio = Embree rtcIntersect1's time / the row's time per round, median [min..max]\n\n",
           nrays, rounds, passes);
    printf("| scene | rays | tracer | Mrays/s | / Embree `rtcIntersect1` | stream / single |\n|---|---|---|---|---|---|\n");
    char scenes[256];
    snprintf(scenes, sizeof scenes, "%s", scene_list);
    int status = BENCH_OK;
    for (char *sv, *sn = strtok_r(scenes, ",", &sv); sn; sn = strtok_r(NULL, ",", &sv)) {
        sidx_mesh m;
        if (!open_mesh(sn, dir, &m)) { status = BENCH_FAIL; continue; }
        ctx c;
        memset(&c, 0, sizeof c);
        int built = 1;
        for (int k = 0; k < NACCEL; ++k) {
            sidx_error err;
            if (sidx_accel_build(accel_names[k], &m, NULL, &c.a[k], &err) != SIDX_OK) {
                fprintf(stderr, "stream: build %s: %s\n", accel_names[k], err.message);
                built = 0;
            }
        }
        char msg[256];
        double build_ms;
        if (built && !bench_embree_build(&m, (bench_embree_cfg){0, 2}, &c.e, &build_ms, msg, sizeof msg)) {
            fprintf(stderr, "stream: Embree: %s\n", msg);
            built = 0;
        }
        tk_rayrec *rec = malloc(nrays * sizeof *rec);
        sidx_ray *rays = malloc(nrays * sizeof *rays);
        c.hits = malloc(nrays * sizeof *c.hits);
        c.occ = malloc(nrays * sizeof *c.occ);
        c.scratch = aligned_alloc(64, (nrays * bench_embree_stream_scratch() + 63) / 64 * 64);
        if (!built || !rec || !rays || !c.hits || !c.occ || !c.scratch) status = BENCH_FAIL;
        char kinds[256];
        snprintf(kinds, sizeof kinds, "%s", kind_list);
        for (char *kv, *kn = strtok_r(kinds, ",", &kv); status == BENCH_OK && kn; kn = strtok_r(NULL, ",", &kv)) {
            tk_ray_kind kind;
            if (!tk_ray_kind_parse(kn, &kind)) { fprintf(stderr, "stream: unknown ray kind %s\n", kn); status = BENCH_USAGE; break; }
            tk_make_rays(&m, kind, nrays, seed, rec);
            size_t bad = 0;
            for (size_t i = 0; i < nrays; ++i)
                if (tk_ray_from(&rec[i], &rays[i]) != SIDX_OK) { /* refused: a ray that misses, on both sides */
                    rec[i] = tk_rayrec_make(sidx_v3(0, 0, 0), sidx_v3(1, 0, 0), 0.0f, 0.0f);
                    (void)tk_ray_from(&rec[i], &rays[i]);
                    ++bad;
                }
            c.rec = rec;
            c.rays = rays;
            c.n = nrays;
            c.any_hit = kind == TK_RAYS_SHADOW;
            c.coherent = kind == TK_RAYS_PRIMARY;
            if (!check_same(&c)) { status = BENCH_FAIL; break; }
            double best[NTRACER][MAX_ROUNDS];
            for (int r = 0; r < rounds; ++r)
                for (int j = 0; j < NTRACER; ++j) {
                    const int t = (j + r) % NTRACER; /* rotated: interleaved rounds */
                    (void)run_tracer(&c, t);         /* warm-up */
                    double b = 1e300;
                    for (int p = 0; p < passes; ++p) {
                        const double ms = run_tracer(&c, t);
                        if (ms < b) b = ms;
                    }
                    best[t][r] = b;
                }
            for (int t = 0; t < NTRACER; ++t) {
                double v[MAX_ROUNDS] = {0}, ratio[MAX_ROUNDS] = {0}, self[MAX_ROUNDS] = {0}, lo, hi, slo = 0, shi = 0;
                for (int r = 0; r < rounds; ++r) {
                    v[r] = best[t][r];
                    ratio[r] = best[T_EMBREE1][r] / best[t][r];
                    /* stream / single: the structure's single queries, or Embree's rtcIntersect1 */
                    self[r] = (t < T_EMBREE1 ? best[t - t % NMODE][r] : best[T_EMBREE1][r]) / best[t][r];
                }
                minmax(ratio, rounds, &lo, &hi);
                minmax(self, rounds, &slo, &shi);
                const double ms = median(v, rounds), rm = median(ratio, rounds), sm = median(self, rounds);
                char name[64];
                if (t == T_EMBREE1) snprintf(name, sizeof name, "Embree HIGH `rtc%s1`", c.any_hit ? "Occluded" : "Intersect");
                else if (t == T_EMBREE1M) snprintf(name, sizeof name, "Embree HIGH `rtc%s1M`", c.any_hit ? "Occluded" : "Intersect");
                else snprintf(name, sizeof name, "`%s` %s", accel_names[t / NMODE], mode_names[t % NMODE]);
                printf("| %s | %s%s | %s | %.2f | %.2f [%.2f..%.2f] |", sn, tk_ray_kind_name(kind), bad ? "*" : "", name,
                       bench_mrays(nrays, ms), rm, lo, hi);
                if (t % NMODE || t >= T_EMBREE1) printf(" %.2f [%.2f..%.2f] |\n", sm, slo, shi);
                else printf(" |\n");
            }
            fflush(stdout);
        }
        free(rec);
        free(rays);
        free(c.hits);
        free(c.occ);
        free(c.scratch);
        for (int k = 0; k < NACCEL; ++k) sidx_accel_destroy(c.a[k]);
        bench_embree_free(c.e);
        sidx_mesh_free(&m);
    }
    return status;
}
