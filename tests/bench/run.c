/* run.c — `sidx-bench run`: the benchmark table.
 *
 * For each scene x ray kind x structure: build ms, Mrays/s (one thread),
 * memory (the structure's bytes, the build's resident peak and, for sidx,
 * its allocator's heap peak: mem.c), nodes, mean traversal steps (NODE_ENTER events) and primitive
 * tests (PRIM_TEST events) per ray from a sidx_counters hook on a ray
 * subset, and the error against the double-precision watertight
 * brute-force reference (tk_ref_intersect) on a subset: false misses,
 * false hits, wrong primitive (different prim with t beyond tolerance),
 * max relative t error.  Embree 3 rows trace the same rays.  Then: a
 * per-(structure, triangle test, box test) summary and its SVG plot
 * (Mrays/s against error rate), auto's pick against the best structure
 * per scene, and the hook-overhead rows (this binary with no hook attached
 * against sidx-bench-nohooks, the library built with -DSIDX_NO_HOOKS).
 * --markdown FILE also writes the headline figures as Markdown blocks
 * between marker comments (<!-- bench:NAME begin --> ... end -->), which
 * docs/bench_refresh.sh copies into docs/benchmark.md and README.md. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bench.h"
#include "sidx/packet.h"
#include "sidx/parallel.h"
#include <pthread.h>
#include <stdatomic.h>

typedef struct run_opts {
    const char *scenes_dir, *accel_list, *kinds_list, *builtin_list, *csv, *plot, *method_scenes;
    size_t rays;
    uint64_t seed;
    double ref_budget;   /* ray x triangle tests for the reference, per scene x kind */
    double time_budget;  /* ms per timed trace */
    double build_budget; /* skip a structure whose predicted build exceeds this (ms) */
    uint32_t brute_max;  /* brute force only on scenes up to this many triangles */
    int embree, methods, hooks, packets;
    double timeout_ms;   /* per structure and scene, in a child process; 0 = in process */
    unsigned long mem_limit_mb;
    unsigned ref_threads;
    /* the targets section (targets.c) */
    const char *target_scenes;
    int targets, rounds;
    /* --markdown: the file, the revision measured, the command to cite */
    const char *markdown, *revision, *md_command;
    int passes; /* warm passes per timed row (bench_time_passes) */
} run_opts;

typedef struct row {
    char scene[64], kind[16], accel[40];
    sidx_tri_method tri;
    sidx_box_method box;
    int embree;      /* 1 for Embree rows */
    int packet;      /* Embree packet width (4, 8, 16) for rtcIntersectN rows, else 0 */
    int builtin;     /* scene is a built-in */
    uint32_t tris;
    double build_ms, trace_ms;   /* trace_ms: the best warm pass (bench_time_passes) */
    double cold_ms, median_ms;   /* the cold pass, the median warm pass */
    int passes;                  /* warm passes timed */
    size_t rays_timed, rays_req; /* rays per pass */
    size_t bytes;
    long long peak;      /* build's resident peak above the level before it (mesh not included); -1 = unknown */
    long long heap;      /* most bytes live at once through the build's sidx_allocator; -1 = not sidx */
    uint32_t nodes;
    uint32_t depth;      /* deepest leaf (sidx_accel_stats.max_depth); 0 = not reported */
    double leaf_prims;   /* mean primitives per non-empty leaf; 0 = not reported */
    double dup;          /* primitive references / triangles (duplication); 0 = not reported */
    double steps, prims; /* per ray; < 0 when not measured */
    tk_errstats err;
} row;

typedef struct rows {
    row *v;
    size_t n, cap;
} rows;

/* Truncating string copy (snprintf("%s") trips -Wformat-truncation). */
static void copy_str(char *dst, size_t size, const char *src)
{
    size_t n = strlen(src);
    if (n >= size) n = size - 1;
    memcpy(dst, src, n);
    dst[n] = '\0';
}

static row *rows_add(rows *r)
{
    if (r->n == r->cap) {
        size_t cap = r->cap ? 2 * r->cap : 256;
        row *nv = realloc(r->v, cap * sizeof *nv);
        if (!nv) return NULL;
        r->v = nv;
        r->cap = cap;
    }
    row *x = &r->v[r->n++];
    memset(x, 0, sizeof *x);
    x->steps = x->prims = -1;
    x->peak = x->heap = -1;
    return x;
}

static double row_mrays(const row *r) { return r->trace_ms > 0 ? (double)r->rays_timed / (r->trace_ms * 1e3) : 0; }

static void row_timing(row *r, const bench_timing *tm)
{
    r->trace_ms = tm->best_ms;
    r->cold_ms = tm->cold_ms;
    r->median_ms = tm->median_ms;
    r->passes = tm->passes;
}

/* One ray set of one scene, prepared once for every structure. */
typedef struct kind_data {
    tk_ray_kind kind;
    tk_rayrec *rec;
    bench_rays br;
    size_t nsub;        /* reference subset: rays sub[0..nsub) */
    tk_rayrec *sub;
    bench_rays sub_br;
    sidx_hit *ref;
    sidx_hit *hits;     /* scratch, rays */
} kind_data;

static void kind_data_free(kind_data *k)
{
    free(k->rec);
    free(k->sub);
    free(k->ref);
    free(k->hits);
    bench_rays_free(&k->br);
    bench_rays_free(&k->sub_br);
    memset(k, 0, sizeof *k);
}

static int kind_data_make(const sidx_mesh *m, tk_ray_kind kind, const run_opts *o, kind_data *k)
{
    memset(k, 0, sizeof *k);
    k->kind = kind;
    const size_t n = o->rays;
    size_t nsub = m->num_triangles ? (size_t)(o->ref_budget / m->num_triangles) : n;
    if (nsub < 500) nsub = 500;
    if (nsub > 20000) nsub = 20000;
    if (nsub > n) nsub = n;
    k->nsub = nsub;
    k->rec = malloc((n ? n : 1) * sizeof *k->rec);
    k->sub = malloc((nsub ? nsub : 1) * sizeof *k->sub);
    k->ref = malloc((nsub ? nsub : 1) * sizeof *k->ref);
    k->hits = malloc((n ? n : 1) * sizeof *k->hits);
    if (!k->rec || !k->sub || !k->ref || !k->hits) return 0;
    tk_make_rays(m, kind, n, o->seed, k->rec);
    /* strided subset, so it covers the whole image for primary rays */
    for (size_t i = 0; i < nsub; ++i) k->sub[i] = k->rec[i * n / nsub];
    if (!bench_rays_prepare(k->rec, n, &k->br) || !bench_rays_prepare(k->sub, nsub, &k->sub_br)) return 0;
    tk_ref_intersect_all(m, k->sub, nsub, k->ref, o->ref_threads);
    return 1;
}

typedef struct scene_spec {
    char name[64];   /* shown in the table */
    char spec[512];  /* for sidx_scene_open */
    int builtin;
} scene_spec;

/* What the Markdown blocks need of one scene beyond its table rows: the
 * packet and thread figures (0 = not measured). */
typedef struct md_scene {
    int packets, threads;       /* measured on this scene */
    uint32_t image_w, image_h;  /* the primary image the packets traced */
    double tile8[3][2];         /* 8x8 tiles over bvh, bvh4, bvh8: [plain, frustum] Mrays/s */
    double embree_packet;       /* Embree's fastest rtcIntersectN, Mrays/s */
    int embree_packet_width;
    double bvh_build[2], embree_build[2], bvh8_build[2], embree_hq_build[2]; /* ms on 1 and 2 threads */
    double trace_eff, embree_trace_eff, twin_ceiling;                         /* percent */
} md_scene;

/* The hook-overhead rows, for the Markdown block. */
typedef struct md_hook_row {
    char accel[40];
    double hooks_mrays, nohooks_mrays;
} md_hook_row;

typedef struct md_hooks {
    char scene[64];
    size_t rays;
    md_hook_row row[128];
    size_t n;
} md_hooks;

/* The thread rows (below), called from packet_parallel_rows */
static void parallel_rows(FILE *f, const run_opts *o, const scene_spec *sc, const sidx_mesh *m, const kind_data *k,
                          const sidx_accel *a, const sidx_hit *ref, sidx_hit *got, size_t N, double single,
                          md_scene *ms);

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Built-ins first, then the .obj/.ply files of dir, sorted. */
static size_t collect_scenes(const run_opts *o, scene_spec *out, size_t max)
{
    size_t n = 0;
    static const char *const defaults[] = {"teapot", "stadium", "icosphere", "soup", "menger", "cornell", "flat2d",
                                           "grid"};
    if (o->builtin_list) {
        const char *p = o->builtin_list;
        while (*p && n < max) {
            const char *e = strchr(p, ',');
            size_t len = e ? (size_t)(e - p) : strlen(p);
            if (len && len < sizeof out[n].spec) {
                memcpy(out[n].spec, p, len);
                out[n].spec[len] = '\0';
                copy_str(out[n].name, sizeof out[n].name, out[n].spec);
                out[n].builtin = 1;
                ++n;
            }
            if (!e) break;
            p = e + 1;
        }
    } else {
        for (size_t i = 0; i < sizeof defaults / sizeof defaults[0] && n < max; ++i) {
            copy_str(out[n].spec, sizeof out[n].spec, defaults[i]);
            copy_str(out[n].name, sizeof out[n].name, defaults[i]);
            out[n].builtin = 1;
            ++n;
        }
    }
    if (o->scenes_dir) {
        DIR *d = opendir(o->scenes_dir);
        if (!d) {
            fprintf(stderr, "sidx-bench run: --scenes %s: %s\n", o->scenes_dir, strerror(errno));
            return (size_t)-1;
        }
        char *names[256] = {NULL};
        size_t nn = 0;
        struct dirent *de;
        while ((de = readdir(d)) && nn < 256) {
            const size_t len = strlen(de->d_name);
            if (len > 4 && (!strcmp(de->d_name + len - 4, ".obj") || !strcmp(de->d_name + len - 4, ".ply")))
                names[nn++] = strdup(de->d_name);
        }
        closedir(d);
        qsort(names, nn, sizeof names[0], cmp_str);
        for (size_t i = 0; i < nn; ++i) {
            if (names[i] && n < max) {
                snprintf(out[n].spec, sizeof out[n].spec, "%s/%s", o->scenes_dir, names[i]);
                copy_str(out[n].name, sizeof out[n].name, names[i]);
                out[n].builtin = 0;
                ++n;
            }
            free(names[i]);
        }
    }
    return n;
}

/* Counters hook on up to max rays spread over the subset: steps =
 * NODE_ENTER, prims = PRIM_TEST events per ray. */
static void measure_counts(const sidx_accel *a, const kind_data *k, size_t max, row *r)
{
    sidx_counters c;
    sidx_counters_init(&c);
    sidx_hook h = sidx_counters_hook(&c);
    h.mask = SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST);
    const size_t n = k->nsub < max ? k->nsub : max;
    size_t used = 0;
    for (size_t j = 0; j < n; ++j) {
        const size_t i = j * k->nsub / n;
        if (!k->sub_br.valid[i]) continue;
        sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &h, (uint32_t)i};
        sidx_hit hit;
        sidx_accel_intersect(a, &k->sub_br.r[i], &q, &hit);
        ++used;
    }
    if (used == 0) return;
    r->steps = (double)c.n[SIDX_EV_NODE_ENTER] / (double)used;
    r->prims = (double)c.n[SIDX_EV_PRIM_TEST] / (double)used;
}

/* Errors on up to max rays spread over the subset.  full_hits: the hits of
 * every ray when all were traced (no tracing needed), else NULL. */
static void measure_errors(const sidx_accel *a, const kind_data *k, const sidx_hit *full_hits, size_t max, row *r)
{
    memset(&r->err, 0, sizeof r->err);
    const size_t n = full_hits || k->nsub < max ? k->nsub : max;
    for (size_t j = 0; j < n; ++j) {
        const size_t i = j * k->nsub / n;
        sidx_hit h;
        if (full_hits) h = full_hits[i * k->br.n / k->nsub];
        else if (!k->sub_br.valid[i]) h = sidx_hit_none();
        else sidx_accel_intersect(a, &k->sub_br.r[i], NULL, &h);
        tk_errstats_add(&r->err, &k->ref[i], &h);
    }
}

/* Milliseconds per ray, estimated on 64 rays spread over the set (the
 * faster of two passes: the first one also pays for cold caches). */
static double probe_cost(const sidx_accel *a, const kind_data *k, size_t n)
{
    const size_t m = n < 64 ? n : 64;
    if (m == 0) return 0;
    double best = INFINITY;
    for (int pass = 0; pass < 2; ++pass) {
        const double t0 = bench_clock_ms();
        for (size_t j = 0; j < m; ++j) {
            const size_t i = j * n / m;
            sidx_hit h;
            if (k->br.valid[i]) sidx_accel_intersect(a, &k->br.r[i], NULL, &h);
        }
        const double t = (bench_clock_ms() - t0) / (double)m;
        if (t < best) best = t;
    }
    return best;
}

/* Timed trace of up to n rays within about budget ms: all of them, or,
 * for a slow structure, 8 contiguous blocks spread evenly over the set
 * (coherent primary rays stay coherent, the whole image is covered).
 * Either way timed as every row is (bench_time_passes): a cold pass, then
 * up to `passes` warm passes while they stay within the budget, the best
 * counting (a preempted pass on a busy machine does not decide the
 * figure).  Returns the rays per pass; *all = 1 when k->hits holds every
 * ray. */
typedef struct blocks_pass {
    const sidx_accel *a;
    const kind_data *k;
    size_t blocks, per;
} blocks_pass;

static double blocks_pass_run(void *ctx, int cold)
{
    (void)cold;
    const blocks_pass *p = ctx;
    double sum = 0;
    for (size_t b = 0; b < p->blocks; ++b) {
        const size_t begin = b * p->k->br.n / p->blocks;
        double t;
        bench_trace(p->a, &p->k->br, begin, begin + p->per, NULL, 0, 1, 0.0, p->k->hits, &t);
        sum += t;
    }
    return sum;
}

static size_t timed_trace(const sidx_accel *a, const kind_data *k, size_t n, double budget, double ms_per_ray,
                          int passes, bench_timing *tm, int *all)
{
    const size_t total = k->br.n;
    size_t want = ms_per_ray > 0 ? (size_t)(budget / ms_per_ray) : n;
    if (want < 256) want = 256;
    if (want > n) want = n;
    *all = 0;
    if (want >= total) {
        bench_trace_timed(a, &k->br, 0, n, NULL, 0, 1, passes, budget, k->hits, tm);
        *all = n == k->br.n;
        return n;
    }
    /* fewer rays than the set (slow structure, or a ray limit) */
    blocks_pass p = {a, k, 8, want / 8};
    bench_buf bufs[8 * 3];
    for (size_t b = 0; b < p.blocks; ++b) {
        const size_t begin = b * total / p.blocks;
        bufs[3 * b] = (bench_buf){k->hits + begin, p.per * sizeof *k->hits, 1};
        bufs[3 * b + 1] = (bench_buf){k->br.r + begin, p.per * sizeof *k->br.r, 0};
        bufs[3 * b + 2] = (bench_buf){k->br.valid + begin, p.per, 0};
    }
    bench_time_passes(blocks_pass_run, &p, bufs, (int)(3 * p.blocks), passes, budget, tm);
    return p.per * p.blocks;
}

/* One structure (with one tri/box method) on one scene, every kind.
 * Returns the build time in ms, < 0 when the build failed. */
static double bench_structure(const char *name, const sidx_mesh *m, const scene_spec *sc, kind_data *kinds, int nk,
                              sidx_tri_method tri, sidx_box_method box, size_t ray_limit, double budget,
                              int passes, rows *out)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.tri = tri;
    bo.box = box;
    bench_heap heap;
    const sidx_allocator al = bench_heap_allocator(&heap);
    bo.alloc = &al;
    sidx_accel *a = NULL;
    sidx_error err = {SIDX_OK, ""};
    bench_mem mem;
    bench_mem_begin(&mem);
    const double t0 = bench_build_clock_ms();
    sidx_status s = sidx_accel_build(name, m, &bo, &a, &err);
    const double build_ms = bench_build_clock_ms() - t0;
    const long long peak = bench_mem_end(&mem);
    if (s != SIDX_OK) {
        fprintf(stderr, "sidx-bench run: %s on %s: %s\n", name, sc->name, err.message);
        return -1;
    }
    sidx_accel_stats st;
    sidx_accel_stats_get(a, &st);
    for (int ki = 0; ki < nk; ++ki) {
        kind_data *k = &kinds[ki];
        row *r = rows_add(out);
        if (!r) break;
        copy_str(r->scene, sizeof r->scene, sc->name);
        copy_str(r->kind, sizeof r->kind, tk_ray_kind_name(k->kind));
        copy_str(r->accel, sizeof r->accel, name);
        r->tri = tri;
        r->box = box;
        r->builtin = sc->builtin;
        r->tris = m->num_triangles;
        r->build_ms = build_ms;
        r->bytes = st.bytes;
        r->peak = peak;
        r->heap = (long long)atomic_load(&heap.peak);
        r->nodes = st.nodes;
        r->depth = st.max_depth;
        r->leaf_prims = st.mean_leaf_prims;
        r->dup = m->num_triangles ? (double)st.prim_refs / m->num_triangles : 0.0;
        const size_t n = k->br.n < ray_limit ? k->br.n : ray_limit;
        const double cost = probe_cost(a, k, n);
        int all = 0;
        r->rays_req = n;
        bench_timing tm;
        r->rays_timed = timed_trace(a, k, n, budget, cost, passes, &tm, &all);
        row_timing(r, &tm);
        size_t max = cost > 0 ? (size_t)(budget / cost) : k->nsub;
        if (max < 200) max = 200;
        measure_errors(a, k, all ? k->hits : NULL, max, r);
        measure_counts(a, k, max / 4 < 1000 ? (max / 4 < 50 ? 50 : max / 4) : 1000, r);
    }
    sidx_accel_destroy(a);
    return build_ms;
}

/* ---- isolation: each structure runs in a child process ---------------------- */

/* A structure under development may hang, explode in memory or crash on
 * some scene.  Each structure's rows are produced in a forked child
 * (address space capped, wall-clock timeout) and sent back through a
 * pipe; a failure costs that row, not the run. */
typedef struct job {
    const char *name;
    const sidx_mesh *m;
    const scene_spec *sc;
    kind_data *kd;
    int nk;
    int sweep; /* 0: watertight/robust on every ray; 1: the other tri/box tests on 1/4 of the rays */
    const run_opts *o;
} job;

static double job_run(const job *j, rows *out)
{
    if (!j->sweep)
        return bench_structure(j->name, j->m, j->sc, j->kd, j->nk, SIDX_TRI_WATERTIGHT, SIDX_BOX_ROBUST, (size_t)-1,
                               j->o->time_budget, j->o->passes, out);
    for (int t = 0; t < SIDX_TRI_METHOD_COUNT; ++t)
        for (int b = 0; b < SIDX_BOX_METHOD_COUNT; ++b) {
            if (t == SIDX_TRI_WATERTIGHT && b == SIDX_BOX_ROBUST) continue;
            if (!strcmp(j->name, "brute") && b != SIDX_BOX_ROBUST) continue; /* brute has no boxes */
            bench_structure(j->name, j->m, j->sc, j->kd, j->nk, (sidx_tri_method)t, (sidx_box_method)b,
                            j->o->rays / 4 + 1, j->o->time_budget / 2, j->o->passes, out);
        }
    return 0;
}

static int write_all(int fd, const void *p, size_t n)
{
    const char *c = p;
    while (n) {
        ssize_t w = write(fd, c, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return 0;
        c += w;
        n -= (size_t)w;
    }
    return 1;
}

/* Returns the build ms (job_run's result), or < 0 with *why set. */
static double job_isolated(const job *j, rows *out, char *why, size_t why_size)
{
    why[0] = '\0';
    if (j->o->timeout_ms <= 0) return job_run(j, out);
    int fd[2];
    if (pipe(fd) != 0) return job_run(j, out);
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        return job_run(j, out);
    }
    if (pid == 0) {
        close(fd[0]);
        struct rlimit rl = {(rlim_t)j->o->mem_limit_mb << 20, (rlim_t)j->o->mem_limit_mb << 20};
        setrlimit(RLIMIT_AS, &rl);
        rows mine = {NULL, 0, 0};
        double build_ms = job_run(j, &mine);
        int ok = write_all(fd[1], &build_ms, sizeof build_ms) && write_all(fd[1], &mine.n, sizeof mine.n) &&
                 (mine.n == 0 || write_all(fd[1], mine.v, mine.n * sizeof *mine.v));
        _exit(ok ? 0 : 3);
    }
    close(fd[1]);
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap);
    const double t0 = tk_now_ms();
    int timed_out = 0;
    for (;;) {
        const double left = j->o->timeout_ms - (tk_now_ms() - t0);
        if (left <= 0) {
            timed_out = 1;
            break;
        }
        struct pollfd pfd = {fd[0], POLLIN, 0};
        int pr = poll(&pfd, 1, left > 1000 ? 1000 : (int)left + 1);
        if (pr < 0 && errno == EINTR) continue;
        if (pr <= 0) continue;
        if (buf && len == cap) {
            char *nb = realloc(buf, cap * 2);
            if (!nb) break;
            buf = nb;
            cap *= 2;
        }
        ssize_t r = read(fd[0], buf ? buf + len : (char[1]){0}, buf ? cap - len : 1);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) break;
        len += (size_t)r;
    }
    close(fd[0]);
    if (timed_out) kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    double result = -1;
    if (timed_out) snprintf(why, why_size, "timed out after %.0f s (--timeout)", j->o->timeout_ms / 1e3);
    else if (WIFSIGNALED(status))
        snprintf(why, why_size, "crashed (signal %d%s)", WTERMSIG(status),
                 WTERMSIG(status) == SIGABRT || WTERMSIG(status) == SIGSEGV ? "; out of memory or a bug" : "");
    else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !buf || len < sizeof(double) + sizeof(size_t))
        snprintf(why, why_size, "child failed (exit %d)", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    else {
        size_t n;
        memcpy(&result, buf, sizeof result);
        memcpy(&n, buf + sizeof result, sizeof n);
        if (len != sizeof result + sizeof n + n * sizeof(row)) {
            snprintf(why, why_size, "child sent a truncated result");
            result = -1;
        } else {
            const row *rv = (const row *)(void *)(buf + sizeof result + sizeof n);
            for (size_t i = 0; i < n; ++i) {
                row *r = rows_add(out);
                if (r) memcpy(r, &rv[i], sizeof *r);
            }
        }
    }
    free(buf);
    return result;
}

static void bench_embree_rows(const char *name, bench_embree_cfg cfg, const sidx_mesh *m, const scene_spec *sc,
                              kind_data *kinds, int nk, const run_opts *o, rows *out)
{
    bench_embree *e = NULL;
    double build_ms = 0;
    char msg[256];
    bench_mem mem;
    bench_mem_begin(&mem);
    const int built = bench_embree_build(m, cfg, &e, &build_ms, msg, sizeof msg);
    const long long peak = bench_mem_end(&mem);
    if (!built) {
        fprintf(stderr, "sidx-bench run: %s on %s: %s\n", name, sc->name, msg);
        return;
    }
    const int packets[4] = {1, 4, 8, 16};
    for (int ki = 0; ki < nk; ++ki) {
        kind_data *k = &kinds[ki];
        for (int p = 0; p < (o->packets && k->kind == TK_RAYS_PRIMARY ? 4 : 1); ++p) {
            row *r = rows_add(out);
            if (!r) break;
            copy_str(r->scene, sizeof r->scene, sc->name);
            copy_str(r->kind, sizeof r->kind, tk_ray_kind_name(k->kind));
            if (packets[p] == 1) copy_str(r->accel, sizeof r->accel, name);
            else snprintf(r->accel, sizeof r->accel, "%.30s-p%d", name, packets[p]);
            r->embree = 1;
            r->packet = packets[p] > 1 ? packets[p] : 0;
            r->builtin = sc->builtin;
            r->tris = m->num_triangles;
            r->build_ms = build_ms;
            r->bytes = bench_embree_bytes(e);
            r->peak = peak;
            r->rays_timed = r->rays_req = k->br.n;
            bench_timing tm;
            bench_embree_trace_timed(e, k->rec, k->br.n, 0, packets[p], o->passes, o->time_budget, k->hits, &tm);
            row_timing(r, &tm);
            measure_errors(NULL, k, k->hits, k->nsub, r);
        }
    }
    bench_embree_free(e);
}

/* ---- packets and threads ------------------------------------------------------- */

/* Packet and thread figures on the primary rays of one scene, beside Embree's:
 *   packets  sidx_trace_tiles (4x4, 8x8, plain and frustum) over "bvh",
 *            "bvh8" and "bvh4", each against single rays through the
 *            same structure, hits checked equal, and Embree's
 *            rtcIntersect4/8/16 on the same image; the ratio line takes
 *            the fastest sidx row of all.  Embree gets the rays reordered
 *            into 4x4 tiles (outside the timing), so each of its packets
 *            is as compact as sidx's; sidx reads its tiles in place
 *            (wide BVHs) or gathers them (bvh) inside the timed call.
 *            Times: thread CPU time, best of --passes warm passes
 *            after a cold one (bench_time_passes), like the table.
 *   threads  the "bvh" build on 1 and 2 threads against Embree's on a
 *            "threads=1" and a "threads=2" device, and sidx_trace_parallel
 *            on 1 and 2 threads: wall-clock, best of 5, so they mean
 *            something only on a quiet machine (efficiency = T1 / (2·T2)). */
static double pp_wall_build(const char *accel, const sidx_mesh *m, uint32_t threads, uint32_t *nodes)
{
    double best = INFINITY;
    for (int rep = 0; rep < 5; ++rep) {
        sidx_build_options bo;
        memset(&bo, 0, sizeof bo);
        bo.threads = threads;
        sidx_accel *a = NULL;
        const double t0 = tk_now_ms();
        const sidx_status s = sidx_accel_build(accel, m, &bo, &a, NULL);
        const double t = tk_now_ms() - t0;
        if (s != SIDX_OK) return -1;
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        *nodes = st.nodes;
        sidx_accel_destroy(a);
        if (t < best) best = t;
    }
    return best;
}

/* Embree's build (cfg: "embree", "embree-hq") on a threads=1 and a
 * threads=2 device, best of 5 wall-clock ms into ms[0], ms[1] (left as
 * they are if a build fails). */
static void pp_embree_build(const char *cfg_name, const sidx_mesh *m, double ms[2])
{
    for (unsigned t = 1; t <= 2; ++t)
        for (int rep = 0; rep < 5; ++rep) {
            bench_embree_cfg cfg;
            bench_embree_parse(cfg_name, &cfg);
            bench_embree *e = NULL;
            double t_ms;
            char msg[256];
            if (!bench_embree_build_threads(m, cfg, t, &e, &t_ms, msg, sizeof msg)) break;
            bench_embree_free(e);
            if (t_ms < ms[t - 1]) ms[t - 1] = t_ms;
        }
}

static size_t pp_mismatches(const sidx_hit *a, const sidx_hit *b, size_t n)
{
    size_t bad = 0;
    for (size_t i = 0; i < n; ++i)
        if (a[i].prim != b[i].prim || (a[i].prim != SIDX_NO_HIT && a[i].t != b[i].t)) ++bad;
    return bad;
}

/* One pass of the packet section: sidx_trace_tiles (tile > 0; stats of
 * the cold pass into *st) or single rays (tile = 0), timed by
 * bench_time_passes like every row. */
typedef struct pp_pass {
    const sidx_accel *a;
    const sidx_ray *r;
    uint32_t W, H, tile;
    sidx_packet_options po;
    sidx_hit *out;
    sidx_packet_stats *st;
} pp_pass;

static double pp_pass_run(void *ctx, int cold)
{
    const pp_pass *p = ctx;
    const size_t N = (size_t)p->W * p->H;
    sidx_packet_stats scratch;
    memset(&scratch, 0, sizeof scratch);
    const double t0 = bench_clock_ms();
    if (p->tile) sidx_trace_tiles(p->a, p->r, p->W, p->H, p->tile, &p->po, p->out, cold ? p->st : &scratch);
    else
        for (size_t i = 0; i < N; ++i) sidx_accel_intersect(p->a, &p->r[i], NULL, &p->out[i]);
    return bench_clock_ms() - t0;
}

static double pp_time(const pp_pass *p, int passes)
{
    const size_t N = (size_t)p->W * p->H;
    const bench_buf bufs[2] = {{p->out, N * sizeof *p->out, 1}, {p->r, N * sizeof *p->r, 0}};
    bench_timing tm;
    bench_time_passes(pp_pass_run, (void *)(uintptr_t)p, bufs, 2, passes, 0.0, &tm);
    return tm.best_ms;
}

/* Packet rows of one structure: sidx_trace_tiles in 4x4 and 8x8 tiles,
 * plain and frustum, hits checked against that structure's single rays
 * (ref, traced in single_ms); the fastest row so far lands in *best
 * (name: "structure tile-mode"), and the 8x8 rows' Mrays/s in tile8[plain,
 * frustum].  Rows over "bvh" are named sidx-8x8-plain ..., the others name
 * their structure (sidx-bvh8-8x8-plain). */
static void pp_packet_rows(FILE *f, const scene_spec *sc, const char *accel, const sidx_accel *a, const kind_data *k,
                           uint32_t W, uint32_t H, const sidx_hit *ref, double single_ms, sidx_hit *got, double *best_mr,
                           char *best_name, size_t best_size, double tile8[2], int passes)
{
    const size_t N = (size_t)W * H;
    const int wide = strcmp(accel, "bvh") != 0;
    static const char *const pname[2] = {"plain", "frustum"};
    for (uint32_t tile = 4; tile <= 8; tile += 4) {
        uint64_t plain_boxes = 0;
        for (int mode = 0; mode < 2; ++mode) {
            const sidx_packet_options po = {mode ? SIDX_PACKET_FRUSTUM : SIDX_PACKET_PLAIN, 0, 0};
            sidx_packet_stats ps;
            memset(&ps, 0, sizeof ps);
            const pp_pass pass = {a, k->br.r, W, H, tile, po, got, &ps};
            const double best = pp_time(&pass, passes);
            const double mr = (double)N / (best * 1e3);
            const size_t bad = pp_mismatches(ref, got, N);
            if (tile == 8 && !bad) tile8[mode] = mr;
            if (!mode) plain_boxes = ps.box_tests;
            char label[40];
            snprintf(label, sizeof label, "%s%s%ux%u-%s", wide ? accel : "", wide ? "-" : "", tile, tile, pname[mode]);
            fprintf(f, "packet sidx-%-17s %-12s %9.3f Mrays/s  %.2fx single  boxes/ray %.2f", label, sc->name, mr,
                    single_ms / best, (double)ps.box_tests / (double)N);
            if (wide)
                fprintf(f, " + interval %.2f (%.0f%% culled)", (double)ps.interval_tests / (double)N,
                        ps.interval_tests ? 100.0 * (double)ps.interval_culls / (double)ps.interval_tests : 0.0);
            else if (mode)
                fprintf(f, " + frustum %.2f (%+.0f%% box tests vs plain, %.0f%% culled)",
                        (double)ps.frustum_tests / (double)N,
                        plain_boxes ? 100.0 * ((double)ps.box_tests - (double)plain_boxes) / (double)plain_boxes : 0.0,
                        ps.frustum_tests ? 100.0 * (double)ps.frustum_culls / (double)ps.frustum_tests : 0.0);
            fprintf(f, "  tris/ray %.2f%s\n", (double)ps.prim_tests / (double)N,
                    bad ? "  ** hits differ from single rays **" : "");
            if (bad) fprintf(f, "   (%zu of %zu hits differ)\n", bad, N);
            if (mr > *best_mr) {
                *best_mr = mr;
                snprintf(best_name, best_size, "%s %ux%u-%s", accel, tile, tile, pname[mode]);
            }
        }
    }
}

static void packet_parallel_rows(FILE *f, const run_opts *o, const scene_spec *sc, const sidx_mesh *m,
                                 const kind_data *k, md_scene *ms)
{
    const size_t n = k->br.n;
    size_t w = (size_t)ceil(sqrt((double)n)); /* tk_make_rays' primary image width */
    if (w == 0) w = 1;
    const uint32_t W = (uint32_t)w, H = (uint32_t)(n / w); /* whole rows only */
    const size_t N = (size_t)W * H;
    if (N < 64) return;
    sidx_accel *a = NULL;
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    if (sidx_accel_build("bvh", m, &bo, &a, NULL) != SIDX_OK) return;
    sidx_hit *ref = malloc(N * sizeof *ref), *got = malloc(N * sizeof *got);
    tk_rayrec *tiled = malloc(N * sizeof *tiled);
    sidx_hit *eh = malloc(N * sizeof *eh);
    if (!ref || !got || !tiled || !eh) goto done;

    /* single rays: the reference hits and the time to beat */
    const sidx_packet_options no_po = {SIDX_PACKET_PLAIN, 0, 0};
    const pp_pass single_pass = {a, k->br.r, W, H, 0, no_po, ref, NULL};
    const double single = pp_time(&single_pass, o->passes);
    fprintf(f, "\npackets %s: %ux%u primary rays, \"bvh\"; single rays %.3f Mrays/s (thread CPU time, best of %d "
               "warm passes after a cold one)\n",
            sc->name, W, H, (double)N / (single * 1e3), o->passes);
    double best_sidx = 0;
    char best_sidx_name[48] = "";
    ms->packets = 1;
    ms->image_w = W;
    ms->image_h = H;
    pp_packet_rows(f, sc, "bvh", a, k, W, H, ref, single, got, &best_sidx, best_sidx_name, sizeof best_sidx_name,
                   ms->tile8[0], o->passes);
    /* the same over the wide BVHs (packet_wide.c), against their own single rays */
    static const char *const wide_names[2] = {"bvh8", "bvh4"};
    for (int wi = 0; wi < 2; ++wi) {
        sidx_accel *wa = NULL;
        sidx_hit *wref = malloc(N * sizeof *wref);
        if (wref && sidx_accel_build(wide_names[wi], m, &bo, &wa, NULL) == SIDX_OK) {
            const pp_pass wsingle_pass = {wa, k->br.r, W, H, 0, no_po, wref, NULL};
            const double wsingle = pp_time(&wsingle_pass, o->passes);
            fprintf(f, "packets %s: \"%s\" single rays %.3f Mrays/s\n", sc->name, wide_names[wi],
                    (double)N / (wsingle * 1e3));
            pp_packet_rows(f, sc, wide_names[wi], wa, k, W, H, wref, wsingle, got, &best_sidx, best_sidx_name,
                           sizeof best_sidx_name, ms->tile8[wi ? 1 : 2], o->passes);
        }
        sidx_accel_destroy(wa);
        free(wref);
    }
    if (o->embree) {
        /* the same image in 4x4 tiles (rows of whole tiles only) */
        const uint32_t TW = W / 4 * 4, TH = H / 4 * 4;
        size_t nt = 0;
        for (uint32_t y0 = 0; y0 < TH; y0 += 4)
            for (uint32_t x0 = 0; x0 < TW; x0 += 4)
                for (uint32_t y = 0; y < 4; ++y)
                    for (uint32_t x = 0; x < 4; ++x) tiled[nt++] = k->rec[(size_t)(y0 + y) * W + x0 + x];
        bench_embree_cfg cfg;
        bench_embree_parse("embree", &cfg);
        bench_embree *e = NULL;
        double bms;
        char msg[256];
        if (bench_embree_build(m, cfg, &e, &bms, msg, sizeof msg)) {
            double best_e = 0;
            int best_p = 0;
            static const int widths[4] = {1, 4, 8, 16};
            for (int p = 0; p < 4; ++p) {
                bench_timing tm;
                bench_embree_trace_timed(e, tiled, nt, 0, widths[p], o->passes, 0.0, eh, &tm);
                const double best = tm.best_ms;
                const double mr = (double)nt / (best * 1e3);
                fprintf(f, "packet embree-p%-2d(4x4 tiles) %-12s %9.3f Mrays/s\n", widths[p], sc->name, mr);
                if (widths[p] > 1 && mr > best_e) {
                    best_e = mr;
                    best_p = widths[p];
                }
            }
            fprintf(f, "packet ratio %-12s best sidx (%s) / best Embree packet (p%d) = %.2f  (target >= 1.0)\n",
                    sc->name, best_sidx_name, best_p, best_e > 0 ? best_sidx / best_e : 0.0);
            ms->embree_packet = best_e;
            ms->embree_packet_width = best_p;
            bench_embree_free(e);
        } else {
            fprintf(stderr, "sidx-bench run: embree on %s: %s\n", sc->name, msg);
        }
    }

    parallel_rows(f, o, sc, m, k, a, ref, got, N, single, ms);
done:
    free(ref);
    free(got);
    free(tiled);
    free(eh);
    sidx_accel_destroy(a);
}

/* ---- threads ---------------------------------------------------------------------- */

/* The thread figures on the primary rays of one scene:
 *   build   the "bvh" build on 1 and 2 threads against Embree's on a
 *           "threads=1" and a "threads=2" device (wall-clock, best of 5);
 *   trace   sidx_trace_parallel on 1 and 2 threads, and Embree's peer: the
 *           same rays through rtcIntersect1 from 1 and from 2 application
 *           threads (contiguous halves) — Embree has no parallel trace call,
 *           this is how an application uses it.  Efficiency = T1 / (2·T2),
 *           wall-clock, best of 5 interleaved rounds (1 thread, then 2);
 *           the CPU efficiency T1 / (CPU time of the 2-thread run) leaves
 *           out time a thread waited for a core, so it stays meaningful
 *           on a busy machine;
 *   twin    the machine's own limit: one thread tracing the rays alone
 *           against the same thread beside a twin doing the same work on
 *           the other core.  The two share nothing in software (no
 *           counter, no pool, separate hit arrays), so whatever slows the
 *           pair — shared memory bandwidth and caches, or two hardware
 *           threads of one core (SMT) — caps any 2-thread efficiency: the
 *           "ceiling" alone / beside is the figure sidx_trace_parallel's
 *           efficiency should be judged against.  Wall-clock and thread
 *           CPU time, best of 5. */
typedef struct pr_thread {
    const sidx_accel *a;       /* sidx twin, or NULL */
    bench_embree *e;           /* Embree half, or NULL */
    const sidx_ray *rays;
    const tk_rayrec *rec;
    size_t lo, hi;
    int passes;
    sidx_hit *hits;
    pthread_barrier_t *start;
    double wall, cpu;
} pr_thread;

static void *pr_thread_main(void *p)
{
    pr_thread *t = p;
    if (t->start) pthread_barrier_wait(t->start);
    const double w0 = tk_now_ms(), c0 = tk_thread_cpu_ms();
    for (int pass = 0; pass < t->passes; ++pass) {
        if (t->e)
            bench_embree_trace(t->e, t->rec + t->lo, t->hi - t->lo, 0, 1, t->hits + t->lo);
        else
            for (size_t i = t->lo; i < t->hi; ++i) sidx_accel_intersect(t->a, &t->rays[i], NULL, &t->hits[i]);
    }
    t->wall = tk_now_ms() - w0;
    t->cpu = tk_thread_cpu_ms() - c0;
    return NULL;
}

/* Run nt (1 or 2) copies of job at once, the first on this thread;
 * returns 0 if a thread could not be started. */
static int pr_run(pr_thread *t, int nt)
{
    pthread_barrier_t bar;
    if (pthread_barrier_init(&bar, NULL, (unsigned)nt) != 0) return 0;
    pthread_t th;
    for (int i = 0; i < nt; ++i) t[i].start = &bar;
    int ok = nt < 2 || pthread_create(&th, NULL, pr_thread_main, &t[1]) == 0;
    if (!ok) {
        pthread_barrier_destroy(&bar);
        return 0;
    }
    pr_thread_main(&t[0]);
    if (nt > 1) pthread_join(th, NULL);
    pthread_barrier_destroy(&bar);
    return 1;
}

static void parallel_rows(FILE *f, const run_opts *o, const scene_spec *sc, const sidx_mesh *m, const kind_data *k,
                          const sidx_accel *a, const sidx_hit *ref, sidx_hit *got, size_t N, double single,
                          md_scene *ms)
{
    ms->threads = 1;
    /* threads: builds */
    uint32_t n1 = 0, n2 = 0;
    const double b1 = pp_wall_build("bvh", m, 1, &n1), b2 = pp_wall_build("bvh", m, 2, &n2);
    fprintf(f, "parallel %s build \"bvh\": 1 thread %.2f ms, 2 threads %.2f ms (%.2fx)%s; wall-clock, best of 5\n",
            sc->name, b1, b2, b2 > 0 ? b1 / b2 : 0.0, n1 == n2 ? "" : "  ** node counts differ **");
    ms->bvh_build[0] = b1 > 0 ? b1 : 0.0;
    ms->bvh_build[1] = b2 > 0 ? b2 : 0.0;
    double eb[2] = {INFINITY, INFINITY}, ehq[2] = {INFINITY, INFINITY};
    if (o->embree) {
        pp_embree_build("embree", m, eb);
        fprintf(f, "parallel %s build embree: threads=1 %.2f ms, threads=2 %.2f ms; sidx/embree at 1 thread %.2f, "
                   "at 2 threads %.2f (target <= 1.5)\n",
                sc->name, eb[0], eb[1], b1 / eb[0], b2 / eb[1]);
        pp_embree_build("embree-hq", m, ehq); /* the spatial-split build, for the bvh8 row below */
        for (int t = 0; t < 2; ++t) {
            ms->embree_build[t] = isfinite(eb[t]) ? eb[t] : 0.0;
            ms->embree_hq_build[t] = isfinite(ehq[t]) ? ehq[t] : 0.0;
        }
    }
    /* bvh8 builds its binary tree with spatial splits (bvh_spatial.c), its
     * subtrees on the threads; no target, a figure to set beside Embree HQ */
    uint32_t w1 = 0, w2 = 0;
    const double c1 = pp_wall_build("bvh8", m, 1, &w1), c2 = pp_wall_build("bvh8", m, 2, &w2);
    fprintf(f, "parallel %s build \"bvh8\" (spatial splits): 1 thread %.2f ms, 2 threads %.2f ms (%.2fx)%s", sc->name,
            c1, c2, c2 > 0 ? c1 / c2 : 0.0, w1 == w2 ? "" : "  ** node counts differ **");
    if (o->embree) fprintf(f, "; embree-hq threads=1 %.2f ms, threads=2 %.2f ms", ehq[0], ehq[1]);
    fprintf(f, "; wall-clock, best of 5\n");
    ms->bvh8_build[0] = c1 > 0 ? c1 : 0.0;
    ms->bvh8_build[1] = c2 > 0 ? c2 : 0.0;
    /* threads: tracing (single rays, batches over threads), repeated to ~100 ms per run,
     * 1 and 2 threads interleaved so that a change in the machine's load hits both */
    const int reps = single > 0 ? (int)(100.0 / single) + 1 : 1;
    {
        double t1 = INFINITY, t2 = INFINITY, c1 = INFINITY, c2 = INFINITY, cpu2 = 0;
        for (int rep = 0; rep < 5; ++rep)
            for (unsigned th = 1; th <= 2; ++th) {
                const double c0 = tk_process_cpu_ms(), t0 = tk_now_ms();
                for (int r = 0; r < reps; ++r) sidx_trace_parallel(a, k->br.r, N, NULL, got, th);
                const double t = tk_now_ms() - t0, c = tk_process_cpu_ms() - c0;
                if (th == 1 && t < t1) t1 = t;
                if (th == 1 && c < c1) c1 = c;
                if (th == 2 && c < c2) c2 = c;
                if (th == 2 && t < t2) {
                    t2 = t;
                    cpu2 = c;
                }
            }
        const size_t bad = pp_mismatches(ref, got, N);
        fprintf(f, "parallel %s trace \"bvh\" primary: 1 thread %.2f ms, 2 threads %.2f ms (CPU/wall %.2f): "
                   "efficiency %.0f%% (target >= 90%%), CPU efficiency %.0f%%; wall-clock, best of 5, %d passes%s\n",
                sc->name, t1, t2, t2 > 0 ? cpu2 / t2 : 0.0, t2 > 0 ? 100.0 * t1 / (2.0 * t2) : 0.0,
                c2 > 0 ? 100.0 * c1 / c2 : 0.0, reps, bad ? "  ** hits differ **" : "");
        if (t2 > 0 && !bad) ms->trace_eff = 100.0 * t1 / (2.0 * t2);
    }
    /* Embree's peer: rtcIntersect1 from 1 and from 2 application threads */
    if (o->embree) {
        bench_embree_cfg cfg;
        bench_embree_parse("embree", &cfg);
        bench_embree *e = NULL;
        double bms;
        char msg[256];
        sidx_hit *eh = malloc(N * sizeof *eh);
        if (eh && bench_embree_build(m, cfg, &e, &bms, msg, sizeof msg)) {
            double t1 = INFINITY, t2 = INFINITY;
            int ok = 1;
            for (int rep = 0; rep < 5 && ok; ++rep)
                for (int nt = 1; nt <= 2 && ok; ++nt) {
                    pr_thread t[2];
                    for (int i = 0; i < nt; ++i)
                        t[i] = (pr_thread){NULL, e, NULL, k->rec, N * (size_t)i / (size_t)nt,
                                           N * (size_t)(i + 1) / (size_t)nt, reps, eh, NULL, 0, 0};
                    const double t0 = tk_now_ms();
                    ok = pr_run(t, nt);
                    const double w = tk_now_ms() - t0;
                    if (nt == 1 && w < t1) t1 = w;
                    if (nt == 2 && w < t2) t2 = w;
                }
            if (ok) {
                fprintf(f, "parallel %s trace embree rtcIntersect1 primary: 1 thread %.2f ms, 2 threads %.2f ms: "
                           "efficiency %.0f%%; wall-clock, best of 5, %d passes\n",
                        sc->name, t1, t2, t2 > 0 ? 100.0 * t1 / (2.0 * t2) : 0.0, reps);
                if (t2 > 0) ms->embree_trace_eff = 100.0 * t1 / (2.0 * t2);
            }
        } else if (eh) {
            fprintf(stderr, "sidx-bench run: embree on %s: %s\n", sc->name, msg);
        }
        bench_embree_free(e);
        free(eh);
    }
    /* the machine's own 2-thread limit: one thread alone, then beside a twin */
    {
        sidx_hit *h2 = malloc(N * sizeof *h2);
        double aw = INFINITY, ac = INFINITY, bw = INFINITY, bc = INFINITY;
        int ok = h2 != NULL;
        for (int rep = 0; rep < 5 && ok; ++rep)
            for (int nt = 1; nt <= 2 && ok; ++nt) {
                pr_thread t[2];
                for (int i = 0; i < nt; ++i)
                    t[i] = (pr_thread){a, NULL, k->br.r, NULL, 0, N, reps, i ? h2 : got, NULL, 0, 0};
                ok = pr_run(t, nt);
                if (nt == 1) {
                    if (t[0].wall < aw) aw = t[0].wall;
                    if (t[0].cpu < ac) ac = t[0].cpu;
                } else {
                    const double w = 0.5 * (t[0].wall + t[1].wall), c = 0.5 * (t[0].cpu + t[1].cpu);
                    if (w < bw) bw = w;
                    if (c < bc) bc = c;
                }
            }
        if (ok) {
            fprintf(f, "parallel %s twin: one thread alone %.2f ms (thread CPU %.2f), beside a twin %.2f ms "
                       "(thread CPU %.2f): the machine's 2-thread ceiling %.0f%% (wall) / %.0f%% (CPU)%s\n",
                    sc->name, aw, ac, bw, bc, bw > 0 ? 100.0 * aw / bw : 0.0, bc > 0 ? 100.0 * ac / bc : 0.0,
                    pp_mismatches(ref, h2, N) ? "  ** hits differ **" : "");
            if (bw > 0) ms->twin_ceiling = 100.0 * aw / bw;
        }
        free(h2);
    }
}

/* ---- output ------------------------------------------------------------------ */

static void print_header(FILE *f)
{
    fprintf(f, "%-10s %-8s %-18s %9s %9s %8s %8s %8s %8s %5s %5s %5s %7s %8s %7s %6s %6s %6s %9s\n", "scene",
            "kind", "accel", "build_ms", "Mrays/s", "MB", "peak_MB", "heap_MB", "nodes", "depth", "leaf", "dup", "steps", "prims", "checked",
            "fmiss", "fhit", "wrong", "max_rel_t");
}

/* Bytes as MB with two decimals, "-" when not measured (< 0). */
static void mb_cell(char *buf, size_t size, long long bytes)
{
    if (bytes >= 0) snprintf(buf, size, "%.2f", (double)bytes / 1048576.0);
    else snprintf(buf, size, "-");
}

static void print_row(FILE *f, const row *r)
{
    char steps[16], prims[16], depth[16], leaf[16], dup[16];
    if (r->depth > 0) snprintf(depth, sizeof depth, "%u", r->depth); else snprintf(depth, sizeof depth, "-");
    if (r->leaf_prims > 0) snprintf(leaf, sizeof leaf, "%.1f", r->leaf_prims); else snprintf(leaf, sizeof leaf, "-");
    if (r->dup > 0) snprintf(dup, sizeof dup, "%.2f", r->dup); else snprintf(dup, sizeof dup, "-");
    if (r->steps >= 0) snprintf(steps, sizeof steps, "%.1f", r->steps); else snprintf(steps, sizeof steps, "-");
    if (r->prims >= 0) snprintf(prims, sizeof prims, "%.1f", r->prims); else snprintf(prims, sizeof prims, "-");
    char peak[16], heap[16];
    mb_cell(peak, sizeof peak, r->peak);
    mb_cell(heap, sizeof heap, r->heap);
    char name[64];
    if (r->tri != SIDX_TRI_WATERTIGHT || r->box != SIDX_BOX_ROBUST)
        snprintf(name, sizeof name, "%.39s/%.12s/%.8s", r->accel, sidx_tri_method_name(r->tri), sidx_box_method_name(r->box));
    else copy_str(name, sizeof name, r->accel);
    fprintf(f, "%-10.10s %-8s %-18s %9.2f %9.3f %8.2f %8s %8s %8u %5s %5s %5s %7s %8s %7llu %6llu %6llu %6llu %9.2e%s\n",
            r->scene, r->kind, name, r->build_ms, row_mrays(r), (double)r->bytes / 1048576.0, peak, heap, r->nodes,
            depth, leaf,
            dup, steps, prims,
            (unsigned long long)r->err.rays, (unsigned long long)r->err.false_miss,
            (unsigned long long)r->err.false_hit, (unsigned long long)r->err.wrong_prim, r->err.max_rel_t,
            r->rays_timed < r->rays_req ? "  (time budget: partial)" : "");
}

static int write_csv(const char *path, const rows *rs)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fprintf(f, "scene,tris,kind,accel,tri,box,embree,build_ms,trace_ms,rays_timed,mrays_per_s,bytes,"
               "build_peak_bytes,build_heap_peak_bytes,nodes,"
               "depth,mean_leaf_prims,dup_factor,steps_per_ray,prims_per_ray,checked,false_miss,false_hit,wrong_prim,max_rel_t,error_rate,"
               "mrays_median,mrays_cold,passes\n");
    for (size_t i = 0; i < rs->n; ++i) {
        const row *r = &rs->v[i];
        fprintf(f, "%s,%u,%s,%s,%s,%s,%d,%.3f,%.3f,%zu,%.4f,%zu,%lld,%lld,%u,%u,%.3f,%.4f,%.3f,%.3f,%llu,%llu,%llu,%llu,%.3e,%.3e,%.4f,%.4f,%d\n",
                r->scene, r->tris, r->kind, r->accel, r->embree ? "embree" : sidx_tri_method_name(r->tri),
                r->embree ? "embree" : sidx_box_method_name(r->box), r->embree, r->build_ms, r->trace_ms,
                r->rays_timed, row_mrays(r), r->bytes, r->peak, r->heap, r->nodes, r->depth, r->leaf_prims, r->dup, r->steps, r->prims,
                (unsigned long long)r->err.rays, (unsigned long long)r->err.false_miss,
                (unsigned long long)r->err.false_hit, (unsigned long long)r->err.wrong_prim, r->err.max_rel_t,
                tk_errstats_rate(&r->err), bench_mrays(r->rays_timed, r->median_ms),
                bench_mrays(r->rays_timed, r->cold_ms), r->passes);
    }
    return fclose(f) == 0;
}

/* Per (accel, tri, box): geometric mean of Mrays/s over scene x kind, and
 * the error rate over every checked ray. */
typedef struct summary {
    char accel[40];
    sidx_tri_method tri;
    sidx_box_method box;
    int embree;
    double log_sum;
    int count;
    tk_errstats err;
} summary;

static size_t summarize(const rows *rs, const char *scenes, summary *out, size_t max)
{
    size_t n = 0;
    for (size_t i = 0; i < rs->n; ++i) {
        const row *r = &rs->v[i];
        if (r->trace_ms <= 0 || r->rays_timed == 0 || r->packet) continue;
        if (scenes && !bench_list_has(scenes, r->scene)) continue;
        size_t j = 0;
        while (j < n && !(strcmp(out[j].accel, r->accel) == 0 && out[j].tri == r->tri && out[j].box == r->box)) ++j;
        if (j == n) {
            if (n == max) continue;
            memset(&out[n], 0, sizeof out[n]);
            copy_str(out[n].accel, sizeof out[n].accel, r->accel);
            out[n].tri = r->tri;
            out[n].box = r->box;
            out[n].embree = r->embree;
            ++n;
        }
        summary *s = &out[j];
        s->log_sum += log(row_mrays(r));
        s->count++;
        s->err.rays += r->err.rays;
        s->err.false_miss += r->err.false_miss;
        s->err.false_hit += r->err.false_hit;
        s->err.wrong_prim += r->err.wrong_prim;
        if (r->err.max_rel_t > s->err.max_rel_t) s->err.max_rel_t = r->err.max_rel_t;
    }
    return n;
}

static const char *method_label(const summary *s, char *buf, size_t size)
{
    if (s->embree) snprintf(buf, size, "%s", s->accel);
    else snprintf(buf, size, "%.39s %.12s/%.8s", s->accel, sidx_tri_method_name(s->tri), sidx_box_method_name(s->box));
    return buf;
}

static void print_summary(FILE *f, const char *scenes, const summary *s, size_t n)
{
    fprintf(f, "\n== run time against error on scenes %s x every kind (geometric mean Mrays/s over scene x kind;\n"
               "   errors over all checked rays; max_rel_t = max |t - t_ref| / max(1, |t_ref|) on the same prim)\n",
            scenes ? scenes : "(all)");
    fprintf(f, "%-36s %9s %6s %9s %7s %7s %7s %10s %9s\n", "accel tri/box", "Mrays/s", "rows", "checked", "fmiss",
            "fhit", "wrong", "err_rate", "max_rel_t");
    for (size_t i = 0; i < n; ++i) {
        char lab[96];
        fprintf(f, "%-36s %9.3f %6d %9llu %7llu %7llu %7llu %10.3e %9.2e\n", method_label(&s[i], lab, sizeof lab),
                exp(s[i].log_sum / s[i].count), s[i].count, (unsigned long long)s[i].err.rays,
                (unsigned long long)s[i].err.false_miss, (unsigned long long)s[i].err.false_hit,
                (unsigned long long)s[i].err.wrong_prim, tk_errstats_rate(&s[i].err), s[i].err.max_rel_t);
    }
}

static int write_plot(const char *path, const summary *s, size_t n)
{
    bench_point *pts = calloc(n + 1, sizeof *pts);
    char (*labels)[96] = calloc(n + 1, sizeof *labels);
    const char *series[16];
    char series_buf[16][40];
    int nseries = 0;
    if (!pts || !labels) {
        free(pts);
        free(labels);
        return 0;
    }
    for (size_t i = 0; i < n; ++i) {
        /* colour by structure family: the name up to the first '-' */
        char fam[40];
        copy_str(fam, sizeof fam, s[i].accel);
        char *dash = strchr(fam, '-');
        if (dash && !s[i].embree) *dash = '\0';
        if (s[i].embree) snprintf(fam, sizeof fam, "embree");
        int k = 0;
        while (k < nseries && strcmp(series_buf[k], fam)) ++k;
        if (k == nseries && nseries < 16) {
            copy_str(series_buf[nseries], sizeof series_buf[0], fam);
            series[nseries] = series_buf[nseries];
            ++nseries;
        }
        pts[i].x = tk_errstats_rate(&s[i].err);
        pts[i].y = exp(s[i].log_sum / s[i].count);
        pts[i].label = method_label(&s[i], labels[i], sizeof labels[i]);
        pts[i].series = k < 16 ? k : 15;
        pts[i].shape = s[i].embree ? 0 : (int)s[i].tri;
        pts[i].hollow = !s[i].embree && s[i].box == SIDX_BOX_PLAIN;
        /* label the default (watertight/robust) points and Embree; the rest by marker */
        pts[i].show_label = s[i].embree || (s[i].tri == SIDX_TRI_WATERTIGHT && s[i].box == SIDX_BOX_ROBUST);
    }
    static const char *const shapes[6] = {"watertight / robust box", "watertight / plain box",
                                          "moller / robust box",     "moller / plain box",
                                          "twostep / robust box",    "twostep / plain box"};
    int ok = bench_svg_scatter(path, "sidx: run time against error (every structure x triangle test / box test)",
                               "error rate vs double-precision reference (false misses + false hits + wrong prim)",
                               "Mrays/s (geometric mean, one thread)", 1, 1, pts, n, series, nseries, shapes, 6);
    free(pts);
    free(labels);
    return ok;
}

/* ---- hook overhead: this binary vs sidx-bench-nohooks ------------------------ */

static int self_path(char *buf, size_t size);

static int nohooks_path(char *buf, size_t size)
{
    char self[4096];
    if (!self_path(self, sizeof self)) return 0;
    char *slash = strrchr(self, '/');
    if (slash) *slash = '\0';
    else snprintf(self, sizeof self, ".");
    if ((size_t)snprintf(buf, size, "%s/sidx-bench-nohooks", self) >= size) return 0;
    return access(buf, X_OK) == 0;
}

/* This executable (rebuilt while running: /proc/self/exe ends in " (deleted)"). */
static int self_path(char *buf, size_t size)
{
    ssize_t len = readlink("/proc/self/exe", buf, size - 1);
    if (len <= 0) return snprintf(buf, size, "%s", bench_argv0) < (int)size;
    buf[len] = '\0';
    static const char deleted[] = " (deleted)";
    const size_t dl = sizeof deleted - 1;
    if ((size_t)len > dl && !strcmp(buf + len - dl, deleted)) buf[len - dl] = '\0';
    return 1;
}

/* Runs prog trace ..., returns trace_ms from its JSON line, < 0 on failure. */
static double run_trace(const char *prog, const char *accel, const char *scene, const char *rays, const char *hits)
{
    int fd[2];
    if (pipe(fd) != 0) return -1;
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        return -1;
    }
    if (pid == 0) {
        dup2(fd[1], 1);
        close(fd[0]);
        close(fd[1]);
        int devnull = open("/dev/null", O_WRONLY);
        if (devnull >= 0) dup2(devnull, 2);
        execl(prog, prog, "trace", "--accel", accel, scene, rays, hits, "--uv", "0", "--cpu-time", (char *)NULL);
        _exit(127);
    }
    close(fd[1]);
    char out[2048];
    size_t n = 0;
    ssize_t got;
    while (n < sizeof out - 1 && (got = read(fd[0], out + n, sizeof out - 1 - n)) > 0) n += (size_t)got;
    out[n] = '\0';
    close(fd[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
    const char *p = strstr(out, "\"trace_ms\":");
    return p ? strtod(p + 11, NULL) : -1;
}

static void hook_rows(FILE *f, const run_opts *o, const scene_spec *sc, md_hooks *mh)
{
    char twin[4096], self[4096];
    fprintf(f, "\n== hook overhead: no hook attached (hooks compiled in) vs hooks compiled out (-DSIDX_NO_HOOKS)\n");
    if (!nohooks_path(twin, sizeof twin) || !self_path(self, sizeof self)) {
        fprintf(f, "(skipped: %s not found; `make build` builds it)\n", "sidx-bench-nohooks");
        return;
    }
    sidx_mesh m = {0};
    sidx_error err = {SIDX_OK, ""};
    if (sidx_scene_open(sc->spec, &m, &err) != SIDX_OK) {
        fprintf(f, "(skipped: %s)\n", err.message);
        return;
    }
    char dir[] = "/tmp/sidx-bench-XXXXXX";
    if (!mkdtemp(dir)) {
        fprintf(f, "(skipped: mkdtemp: %s)\n", strerror(errno));
        sidx_mesh_free(&m);
        return;
    }
    char rays[64], hits[64];
    snprintf(rays, sizeof rays, "%s/rays.bin", dir);
    snprintf(hits, sizeof hits, "%s/hits.bin", dir);
    const size_t n = 100000;
    tk_rayrec *rec = malloc(n * sizeof *rec);
    if (rec) {
        tk_make_rays(&m, TK_RAYS_DIFFUSE, n, o->seed, rec);
        tk_write_rays(rays, rec, n, NULL);
        free(rec);
    }
    fprintf(f, "scene %s, %zu diffuse rays, best of 3 runs each\n", sc->name, n);
    copy_str(mh->scene, sizeof mh->scene, sc->name);
    mh->rays = n;
    fprintf(f, "%-18s %12s %12s %9s\n", "accel", "hooks Mrays", "no-hooks", "overhead");
    for (size_t i = 0; i < sidx_accel_registered_count(); ++i) {
        const char *name = sidx_accel_registered_name(i);
        if (!bench_list_has(o->accel_list, name)) continue;
        if (!strcmp(name, "brute") && m.num_triangles > 1000) continue;
        bench_progress("hooks: %s", name);
        double best[2] = {INFINITY, INFINITY};
        for (int rep = 0; rep < 3; ++rep)
            for (int w = 0; w < 2; ++w) {
                double ms = run_trace(w ? twin : self, name, sc->spec, rays, hits);
                if (ms > 0 && ms < best[w]) best[w] = ms;
            }
        if (!isfinite(best[0]) || !isfinite(best[1])) {
            fprintf(f, "%-18s %12s %12s %9s\n", name, "failed", "failed", "-");
            continue;
        }
        fprintf(f, "%-18s %12.3f %12.3f %8.1f%%\n", name, (double)n / (best[0] * 1e3), (double)n / (best[1] * 1e3),
                100.0 * (best[0] - best[1]) / best[1]);
        if (mh->n < sizeof mh->row / sizeof mh->row[0]) {
            md_hook_row *hr = &mh->row[mh->n++];
            copy_str(hr->accel, sizeof hr->accel, name);
            hr->hooks_mrays = (double)n / (best[0] * 1e3);
            hr->nohooks_mrays = (double)n / (best[1] * 1e3);
        }
    }
    bench_progress_done();
    unlink(rays);
    unlink(hits);
    rmdir(dir);
    sidx_mesh_free(&m);
}

/* ---- auto -------------------------------------------------------------------- */

/* Time per ray summed over the kinds (the structure's cost on this scene). */
static double scene_cost(const rows *rs, size_t from, const char *scene, const char *accel)
{
    double cost = 0;
    int found = 0;
    for (size_t i = from; i < rs->n; ++i) {
        const row *r = &rs->v[i];
        if (r->embree || strcmp(r->scene, scene) || strcmp(r->accel, accel) || r->tri != SIDX_TRI_WATERTIGHT ||
            r->box != SIDX_BOX_ROBUST)
            continue;
        if (r->rays_timed == 0) return INFINITY;
        cost += r->trace_ms / (double)r->rays_timed;
        found = 1;
    }
    return found ? cost : -1;
}

/* Head to head: auto's pick against the 3 fastest structures of the
 * table on this scene, every kind, interleaved over 5 rounds with the
 * fastest round kept, so a busy machine does not decide the ratio. */
static void auto_line(FILE *f, const rows *rs, size_t from, const scene_spec *sc, const sidx_mesh *m,
                      kind_data *kd, int nk)
{
    sidx_accel *picked_a = NULL;
    if (sidx_accel_auto(m, NULL, &picked_a, NULL) != SIDX_OK) {
        fprintf(f, "auto: %s: build failed\n", sc->name);
        return;
    }
    const char *picked = sidx_accel_name(picked_a);
    sidx_accel_destroy(picked_a);
    enum { MAXC = 4 };
    const char *cand[MAXC];
    double table_cost[MAXC];
    int nc = 0;
    cand[nc] = picked;
    table_cost[nc++] = scene_cost(rs, from, sc->name, picked);
    for (size_t i = 0; i < sidx_accel_registered_count(); ++i) {
        const char *name = sidx_accel_registered_name(i);
        if (!strcmp(name, picked)) continue;
        const double c = scene_cost(rs, from, sc->name, name);
        if (!(c > 0) || !isfinite(c)) continue;
        /* keep the 3 cheapest besides the pick */
        if (nc < MAXC) {
            cand[nc] = name;
            table_cost[nc++] = c;
        } else {
            int worst = 1;
            for (int j = 2; j < nc; ++j)
                if (table_cost[j] > table_cost[worst]) worst = j;
            if (c < table_cost[worst]) {
                cand[worst] = name;
                table_cost[worst] = c;
            }
        }
    }
    if (!(table_cost[0] > 0)) {
        fprintf(f, "auto: %-10s picked %-12s (not measured in this run)\n", sc->name, picked);
        return;
    }
    sidx_accel *acc[MAXC] = {NULL};
    for (int j = 0; j < nc; ++j)
        if (sidx_accel_build(cand[j], m, NULL, &acc[j], NULL) != SIDX_OK) acc[j] = NULL;
    double best_ms[MAXC][TK_RAYS_KIND_COUNT];
    for (int j = 0; j < nc; ++j)
        for (int k = 0; k < nk; ++k) best_ms[j][k] = INFINITY;
    for (int round = 0; round < 5; ++round)
        for (int k = 0; k < nk; ++k)
            for (int j = 0; j < nc; ++j) {
                if (!acc[j]) continue;
                double ms;
                bench_trace(acc[j], &kd[k].br, 0, kd[k].br.n, NULL, 0, 1, 0.0, kd[k].hits, &ms);
                if (ms < best_ms[j][k]) best_ms[j][k] = ms;
            }
    double cost[MAXC];
    int best = -1;
    for (int j = 0; j < nc; ++j) {
        cost[j] = 0;
        for (int k = 0; k < nk; ++k) cost[j] += best_ms[j][k];
        if (acc[j] && (best < 0 || cost[j] < cost[best])) best = j;
        sidx_accel_destroy(acc[j]);
    }
    if (!acc[0] || best < 0) {
        fprintf(f, "auto: %-10s picked %-12s (could not rebuild it)\n", sc->name, picked);
        return;
    }
    if (getenv("SIDX_BENCH_DEBUG")) for (int j = 0; j < nc; ++j) fprintf(stderr, "h2h %s %s %.3f ms\n", sc->name, cand[j], cost[j]);
    const double ratio = cost[best] / cost[0];
    fprintf(f, "auto: %-10s picked %-12s best %-12s ratio %.2f (head to head, 5 rounds, every ray)%s\n",
            sc->name, picked, cand[best], ratio, ratio >= 0.9 ? "" : "  ** auto more than 10% slower **");
}

/* ---- Markdown (--markdown FILE) ---------------------------------------------- */

/* Each block stands alone (the README takes one of them): it opens with
 * when, where and how it was measured, and sits between
 * <!-- bench:NAME begin --> and <!-- bench:NAME end -->, the markers
 * docs/bench_refresh.sh looks for in the documents it refreshes. */

/* "model name" of the first processor in /proc/cpuinfo. */
static void md_cpu_model(char *buf, size_t size)
{
    copy_str(buf, size, "an unknown CPU");
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (!f) return;
    char line[512];
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "model name", 10) != 0) continue;
        const char *p = strchr(line, ':');
        if (!p) continue;
        for (++p; *p == ' ' || *p == '\t'; ++p) {}
        char *end = line + strlen(line);
        while (end > p && (end[-1] == '\n' || end[-1] == ' ')) *--end = '\0';
        if (*p) copy_str(buf, size, p);
        break;
    }
    fclose(f);
}

/* The kernels a wide BVH picked on this machine, from the NOTE its build
 * emits ("wide BVH: AVX-512 kernels (...)" -> "AVX-512 kernels"). */
typedef struct md_note { char text[64]; } md_note;

static void md_note_hook(const sidx_event *ev, void *user)
{
    md_note *n = user;
    static const char prefix[] = "wide BVH: ";
    if (ev->type != SIDX_EV_NOTE || !ev->text || strncmp(ev->text, prefix, sizeof prefix - 1) != 0) return;
    copy_str(n->text, sizeof n->text, ev->text + sizeof prefix - 1);
    char *paren = strstr(n->text, " (");
    if (paren) *paren = '\0';
}

static void md_wide_kernels(const char *accel, char *buf, size_t size)
{
    copy_str(buf, size, "");
    sidx_mesh m = {0};
    if (!sidx_accel_is_registered(accel) || sidx_scene_open("cornell", &m, NULL) != SIDX_OK) return;
    md_note note = {""};
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    const sidx_hook hook = {md_note_hook, &note, SIDX_EVMASK(SIDX_EV_NOTE)};
    bo.hook = &hook;
    sidx_accel *a = NULL;
    if (sidx_accel_build(accel, &m, &bo, &a, NULL) == SIDX_OK) copy_str(buf, size, note.text);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

/* 20000 -> "20,000" */
static void md_count(size_t n, char *buf, size_t size)
{
    char digits[32];
    snprintf(digits, sizeof digits, "%zu", n);
    const size_t len = strlen(digits);
    size_t j = 0;
    for (size_t i = 0; i < len && j + 2 < size; ++i) {
        if (i > 0 && (len - i) % 3 == 0) buf[j++] = ',';
        buf[j++] = digits[i];
    }
    buf[j] = '\0';
}

/* Is this option one that changes no figure (where the output goes, what
 * the Markdown cites)?  Such options are left out of the command cited. */
static int md_output_option(const char *a)
{
    return !strcmp(a, "--csv") || !strcmp(a, "--plot") || !strcmp(a, "--markdown") || !strcmp(a, "--revision") ||
           !strcmp(a, "--md-command");
}

/* "Measured 2026-12-02 at commit abc1234 on <CPU> (2 cores; `bvh8` on
 * AVX-512 kernels, `bvh4` on SSE4.1 kernels) with `make bench`, Embree
 * 3.13.5, 20,000 rays per scene and ray kind" */
static void md_caption(const run_opts *o, int argc, char **argv, char *buf, size_t size)
{
    char date[32] = "(no date)", cpu[256], k8[64], k4[64], cmd[1024], rays[32];
    const time_t now = time(NULL);
    struct tm tmv;
    if (localtime_r(&now, &tmv)) strftime(date, sizeof date, "%Y-%m-%d", &tmv);
    md_cpu_model(cpu, sizeof cpu);
    md_wide_kernels("bvh8", k8, sizeof k8);
    md_wide_kernels("bvh4", k4, sizeof k4);
    if (o->md_command && o->md_command[0]) {
        copy_str(cmd, sizeof cmd, o->md_command);
    } else {
        size_t len = (size_t)snprintf(cmd, sizeof cmd, "sidx-bench run");
        for (int i = 1; i < argc && len < sizeof cmd; ++i) {
            if (md_output_option(argv[i])) {
                ++i;
                continue;
            }
            const int quote = strchr(argv[i], ' ') != NULL;
            len += (size_t)snprintf(cmd + len, sizeof cmd - len, quote ? " '%s'" : " %s", argv[i]);
        }
    }
    char kernels[200] = "";
    const char *simd = getenv("SIDX_SIMD");
    if (k8[0] || k4[0])
        snprintf(kernels, sizeof kernels, "; %s%s%s%s%s%s%s%s", k8[0] ? "`bvh8` on " : "", k8, k8[0] && k4[0] ? ", " : "",
                 k4[0] ? "`bvh4` on " : "", k4, simd ? " (SIDX_SIMD=" : "", simd ? simd : "", simd ? ")" : "");
    md_count(o->rays, rays, sizeof rays);
    const long cores = sysconf(_SC_NPROCESSORS_ONLN);
    const int n = snprintf(buf, size, "Measured %s%s%s on %s (%ld core%s%s) with `%s`, Embree %s, %s rays per scene and ray kind",
                           date, o->revision && o->revision[0] ? " at commit " : "", o->revision ? o->revision : "", cpu,
                           cores, cores == 1 ? "" : "s", kernels, cmd, bench_embree_version(), rays);
    if (n >= 0 && (size_t)n >= size && size >= 4) memcpy(buf + size - 4, "...", 4);
}

/* "bunny.obj" with 69451 triangles -> "bunny 69k"; "sponza_dabrovic.obj" -> "sponza 66k" */
static void md_scene_label(const char *name, uint32_t tris, char *buf, size_t size)
{
    char stem[64];
    copy_str(stem, sizeof stem, name);
    stem[strcspn(stem, "._")] = '\0';
    if (tris >= 1000) snprintf(buf, size, "%.60s %uk", stem, (tris + 500) / 1000);
    else snprintf(buf, size, "%.60s %u", stem, tris);
}

/* The scenes of the headline table: each --target-scenes name found among
 * the run's scenes (a built-in by its name, a file by its name's start, as
 * the targets section finds them); every scene when none is. */
static size_t md_headline_scenes(const run_opts *o, const scene_spec *scenes, size_t ns, size_t *out)
{
    size_t n = 0;
    const char *p = o->target_scenes;
    while (p && *p && n < ns) {
        const char *e = strchr(p, ',');
        const size_t len = e ? (size_t)(e - p) : strlen(p);
        for (size_t i = 0; i < ns; ++i) {
            const char *nm = scenes[i].name;
            const int match = scenes[i].builtin ? strlen(nm) == len && !strncmp(nm, p, len)
                                                : !strncmp(nm, p, len) && strchr("._-", nm[len]) && nm[len];
            if (!match) continue;
            size_t j = 0;
            while (j < n && out[j] != i) ++j;
            if (j == n) out[n++] = i;
            break;
        }
        p = e ? e + 1 : NULL;
    }
    if (n == 0)
        for (size_t i = 0; i < ns; ++i) out[n++] = i;
    return n;
}

static const row *md_find(const rows *rs, const char *scene, const char *kind, const char *accel)
{
    for (size_t i = 0; i < rs->n; ++i) {
        const row *r = &rs->v[i];
        if (!r->packet && r->tri == SIDX_TRI_WATERTIGHT && r->box == SIDX_BOX_ROBUST && !strcmp(r->scene, scene) &&
            !strcmp(r->kind, kind) && !strcmp(r->accel, accel))
            return r;
    }
    return NULL;
}

/* bench:table — bvh, bvh4, bvh8, kdtree, Embree and Embree HQ on the
 * headline scenes' primary and diffuse rays, the build times, and the
 * errors of those rows. */
static void md_write_table(FILE *md, const char *caption, const rows *rs, const scene_spec *scenes, const size_t *hs,
                           size_t nh, int passes)
{
    static const char *const accel[] = {"bvh", "bvh4", "bvh8", "kdtree", "embree", "embree-hq"};
    static const char *const head[] = {"`bvh`", "`bvh4`", "`bvh8`", "`kdtree`", "Embree `rtcIntersect1`", "Embree HQ"};
    enum { NA = sizeof accel / sizeof accel[0] };
    static const char *const kinds[] = {"primary", "diffuse"};
    int have[NA] = {0};
    for (size_t h = 0; h < nh; ++h)
        for (size_t k = 0; k < 2; ++k)
            for (int a = 0; a < NA; ++a) have[a] |= md_find(rs, scenes[hs[h]].name, kinds[k], accel[a]) != NULL;
    const int ratio = have[2] && have[4];
    fprintf(md, "<!-- bench:table begin -->\n%s; Mrays/s on one thread (CPU time of the tracing thread, the best of "
                "up to %d warm passes after a cold one), builds in ms (CPU time of the process):\n\n| scene, rays |",
            caption, passes);
    int ncol = 0;
    for (int a = 0; a < NA; ++a)
        if (have[a]) {
            fprintf(md, " %s |", head[a]);
            ++ncol;
        }
    if (ratio) fprintf(md, " `bvh8` / Embree |");
    fprintf(md, "\n|---|");
    for (int c = 0; c < ncol + ratio; ++c) fprintf(md, "---|");
    fprintf(md, "\n");
    for (size_t h = 0; h < nh; ++h) {
        const scene_spec *sc = &scenes[hs[h]];
        for (size_t k = 0; k < 2; ++k) {
            const row *r[NA];
            double best = 0;
            int any = 0;
            uint32_t tris = 0;
            for (int a = 0; a < NA; ++a) {
                r[a] = have[a] ? md_find(rs, sc->name, kinds[k], accel[a]) : NULL;
                if (r[a] && row_mrays(r[a]) > best) best = row_mrays(r[a]);
                if (r[a]) {
                    any = 1;
                    tris = r[a]->tris;
                }
            }
            if (!any) continue;
            char label[80];
            md_scene_label(sc->name, tris, label, sizeof label);
            fprintf(md, "| %s, %s |", label, kinds[k]);
            for (int a = 0; a < NA; ++a) {
                if (!have[a]) continue;
                if (!r[a]) fprintf(md, " – |");
                else if (row_mrays(r[a]) == best) fprintf(md, " **%.1f** |", row_mrays(r[a]));
                else fprintf(md, " %.1f |", row_mrays(r[a]));
            }
            if (ratio) {
                if (r[2] && r[4] && row_mrays(r[4]) > 0) fprintf(md, " %.2f |", row_mrays(r[2]) / row_mrays(r[4]));
                else fprintf(md, " – |");
            }
            fprintf(md, "\n");
        }
    }
    /* the per-structure rows: "bunny / sponza build, ms | 61 / 51 | ...",
     * then the structure's MB and the build's resident peak above the
     * loaded mesh (MB; "–" when not measured) */
    static const char *const per_row[3] = {" build, ms |", " structure, MB |", " build peak, MB |"};
    for (int w = 0; w < 3; ++w) {
        fprintf(md, "| ");
        for (size_t h = 0; h < nh; ++h) {
            char stem[64];
            copy_str(stem, sizeof stem, scenes[hs[h]].name);
            stem[strcspn(stem, "._")] = '\0';
            fprintf(md, "%s%s", h ? " / " : "", stem);
        }
        fprintf(md, "%s", per_row[w]);
        for (int a = 0; a < NA; ++a) {
            if (!have[a]) continue;
            fprintf(md, " ");
            for (size_t h = 0; h < nh; ++h) {
                const row *r = md_find(rs, scenes[hs[h]].name, "primary", accel[a]);
                if (!r) r = md_find(rs, scenes[hs[h]].name, "diffuse", accel[a]);
                const double v = !r ? -1 : w == 0 ? r->build_ms : w == 1 ? (double)r->bytes : (double)r->peak;
                if (v < 0) fprintf(md, "%s–", h ? " / " : "");
                else if (w == 0) fprintf(md, "%s%.0f", h ? " / " : "", v);
                else fprintf(md, "%s%.1f", h ? " / " : "", v / 1048576.0);
            }
            fprintf(md, " |");
        }
        if (ratio) fprintf(md, " |");
        fprintf(md, "\n");
    }
    fprintf(md, "\n");
    /* the errors of the rows above */
    unsigned long long bad = 0;
    fprintf(md, "Errors against the reference on these rows (rays checked per row:");
    for (size_t h = 0; h < nh; ++h) {
        unsigned long long checked = 0;
        for (size_t k = 0; k < 2; ++k)
            for (int a = 0; a < NA; ++a) {
                const row *r = have[a] ? md_find(rs, scenes[hs[h]].name, kinds[k], accel[a]) : NULL;
                if (!r) continue;
                if (r->err.rays > checked) checked = r->err.rays;
                bad += r->err.false_miss + r->err.false_hit + r->err.wrong_prim;
            }
        char stem[64];
        copy_str(stem, sizeof stem, scenes[hs[h]].name);
        stem[strcspn(stem, "._")] = '\0';
        fprintf(md, "%s %llu on %s", h ? "," : "", checked, stem);
    }
    fprintf(md, "): %s", bad ? "" : "no false miss, no false hit, no wrong primitive.\n");
    if (bad) {
        int first = 1;
        for (size_t h = 0; h < nh; ++h)
            for (size_t k = 0; k < 2; ++k)
                for (int a = 0; a < NA; ++a) {
                    const row *r = have[a] ? md_find(rs, scenes[hs[h]].name, kinds[k], accel[a]) : NULL;
                    if (!r || r->err.false_miss + r->err.false_hit + r->err.wrong_prim == 0) continue;
                    fprintf(md, "%s%s on %s %s %llu / %llu / %llu", first ? "" : "; ", accel[a], r->scene, r->kind,
                            (unsigned long long)r->err.false_miss, (unsigned long long)r->err.false_hit,
                            (unsigned long long)r->err.wrong_prim);
                    first = 0;
                }
        fprintf(md, " (false misses / false hits / wrong primitives).\n");
    }
    fprintf(md, "\n<!-- bench:table end -->\n\n");
}

/* A cell of Mrays/s or ms; "–" when not measured. */
static void md_cell(FILE *md, double v, const char *fmt)
{
    if (v > 0 && isfinite(v)) {
        fprintf(md, " ");
        fprintf(md, fmt, v);
        fprintf(md, " |");
    } else {
        fprintf(md, " – |");
    }
}

static void md_pair(FILE *md, const double v[2], const char *fmt)
{
    char a[32] = "–", b[32] = "–";
    if (v[0] > 0 && isfinite(v[0])) snprintf(a, sizeof a, fmt, v[0]);
    if (v[1] > 0 && isfinite(v[1])) snprintf(b, sizeof b, fmt, v[1]);
    fprintf(md, " %s / %s |", a, b);
}

static void md_write_packets(FILE *md, const char *caption, const scene_spec *scenes, const md_scene *all,
                             const size_t *hs, size_t ns, const rows *rs, int passes)
{
    size_t first = ns;
    for (size_t h = 0; h < ns && first == ns; ++h)
        if (all[hs[h]].packets) first = hs[h];
    if (first == ns) return;
    fprintf(md, "<!-- bench:packets begin -->\n%s; `sidx_trace_tiles` on the %u×%u primary image in 8×8 tiles, "
                "the faster of plain and frustum tiles, against Embree's fastest packet call (`rtcIntersect4/8/16`) "
                "on the same image in 4×4 tiles; Mrays/s on one thread (CPU time of the thread, best of %d warm "
                "passes after a cold one):\n\n"
                "| scene | `bvh` 8×8 | `bvh4` 8×8 | `bvh8` 8×8 | Embree, best packet | `bvh8` 8×8 / Embree |\n"
                "|---|---|---|---|---|---|\n",
            caption, all[first].image_w, all[first].image_h, passes);
    for (size_t h = 0; h < ns; ++h) {
        const size_t i = hs[h];
        const md_scene *ms = &all[i];
        if (!ms->packets) continue;
        uint32_t tris = 0;
        for (size_t r = 0; r < rs->n && !tris; ++r)
            if (!strcmp(rs->v[r].scene, scenes[i].name)) tris = rs->v[r].tris;
        char label[80];
        md_scene_label(scenes[i].name, tris, label, sizeof label);
        fprintf(md, "| %s |", label);
        double best8 = 0;
        for (int s = 0; s < 3; ++s) {
            const double *t = ms->tile8[s];
            const int fr = t[1] > t[0];
            const double v = fr ? t[1] : t[0];
            if (s == 2) best8 = v;
            if (v > 0) fprintf(md, " %.1f (%s) |", v, fr ? "frustum" : "plain");
            else fprintf(md, " – |");
        }
        if (ms->embree_packet > 0)
            fprintf(md, " %.1f (`rtcIntersect%d`) |", ms->embree_packet, ms->embree_packet_width);
        else
            fprintf(md, " – |");
        md_cell(md, best8 > 0 && ms->embree_packet > 0 ? best8 / ms->embree_packet : 0, "%.2f");
        fprintf(md, "\n");
    }
    fprintf(md, "\n<!-- bench:packets end -->\n\n");
}

static void md_write_threads(FILE *md, const char *caption, const scene_spec *scenes, const md_scene *all,
                             const size_t *hs, size_t ns, const rows *rs)
{
    int any = 0;
    for (size_t h = 0; h < ns; ++h) any |= all[hs[h]].threads;
    if (!any) return;
    fprintf(md, "<!-- bench:threads begin -->\n%s; builds and traces on 1 and 2 threads, wall-clock, best of 5 (the "
                "figures mean something on a quiet machine only); efficiency = T1 / (2 T2) on the primary rays:\n\n"
                "| scene | `bvh` build, ms, 1 / 2 threads | Embree build | `bvh` / Embree, 2 threads "
                "| `bvh8` build (spatial splits) | Embree HQ build | `sidx_trace_parallel`, 2 threads "
                "| Embree `rtcIntersect1` from 2 threads | the machine's 2-thread ceiling |\n"
                "|---|---|---|---|---|---|---|---|---|\n",
            caption);
    for (size_t h = 0; h < ns; ++h) {
        const size_t i = hs[h];
        const md_scene *ms = &all[i];
        if (!ms->threads) continue;
        uint32_t tris = 0;
        for (size_t r = 0; r < rs->n && !tris; ++r)
            if (!strcmp(rs->v[r].scene, scenes[i].name)) tris = rs->v[r].tris;
        char label[80];
        md_scene_label(scenes[i].name, tris, label, sizeof label);
        fprintf(md, "| %s |", label);
        md_pair(md, ms->bvh_build, "%.1f");
        md_pair(md, ms->embree_build, "%.1f");
        md_cell(md, ms->embree_build[1] > 0 ? ms->bvh_build[1] / ms->embree_build[1] : 0, "%.2f");
        md_pair(md, ms->bvh8_build, "%.1f");
        md_pair(md, ms->embree_hq_build, "%.1f");
        md_cell(md, ms->trace_eff, "%.0f%%");
        md_cell(md, ms->embree_trace_eff, "%.0f%%");
        md_cell(md, ms->twin_ceiling, "%.0f%%");
        fprintf(md, "\n");
    }
    fprintf(md, "\n<!-- bench:threads end -->\n\n");
}

static void md_write_hooks(FILE *md, const char *caption, const md_hooks *mh)
{
    if (mh->n == 0) return;
    char rays[32];
    md_count(mh->rays, rays, sizeof rays);
    fprintf(md, "<!-- bench:hooks begin -->\n%s; `sidx-bench` with no hook attached against `sidx-bench-nohooks` "
                "(the library built with `-DSIDX_NO_HOOKS`), %s, %s diffuse rays, best of 3 runs each (CPU time of "
                "the tracing thread); the difference is in time, negative when the build with hooks is the faster:"
                "\n\n| structure | hooks compiled in, Mrays/s | compiled out, Mrays/s | difference |\n|---|---|---|---|\n",
            caption, mh->scene, rays);
    for (size_t i = 0; i < mh->n; ++i) {
        const md_hook_row *r = &mh->row[i];
        /* time difference: (t_in - t_out) / t_out = out/in - 1 in speeds */
        const double diff = r->hooks_mrays > 0 ? 100.0 * (r->nohooks_mrays / r->hooks_mrays - 1.0) : 0.0;
        fprintf(md, "| `%s` | %.2f | %.2f | %s%.1f%% |\n", r->accel, r->hooks_mrays, r->nohooks_mrays,
                diff < 0 ? "−" : "+", fabs(diff));
    }
    fprintf(md, "\n<!-- bench:hooks end -->\n\n");
}

/* ---- the command ------------------------------------------------------------- */

static void run_usage(FILE *out)
{
    fprintf(out,
            "usage: sidx-bench run [options]\n"
            "\n"
            "The benchmark table: every registered structure (brute force only on scenes of at\n"
            "most --brute-max triangles) on every scene and ray kind, with Embree 3 rows on the\n"
            "same rays, the error against a double-precision watertight brute-force reference, a\n"
            "run-time-against-error summary over triangle/box tests, auto's pick per scene, and\n"
            "the hook-overhead rows.\n"
            "options:\n"
            "  --scenes DIR       also every .obj/.ply file in DIR\n"
            "  --builtin LIST     built-in scenes (default teapot,stadium,icosphere,soup,menger,\n"
            "                     cornell,flat2d,grid); name:detail allowed; \"none\" for none\n"
            "  --accel LIST       structures (default: every registered one) and/or embree,\n"
            "                     embree-robust, embree-hq, embree-robust-hq\n"
            "  --kinds LIST       ray kinds (default primary,diffuse,shadow,grazing,axis)\n"
            "  --rays N           rays per scene and kind (default 20000)\n"
            "  --seed S           ray seed (default 1)\n"
            "  --ref-budget N     ray x triangle tests for the reference per scene and kind\n"
            "                     (default 1.5e8; the subset has at least 500 rays)\n"
            "  --time-budget MS   time about MS ms of tracing per row (default 100): a slow structure\n"
            "                     traces 8 blocks of contiguous rays spread over the set, a fast one\n"
            "                     every ray; either way a cold pass (reported in the CSV) and then\n"
            "                     warm passes while within MS, the fastest counting\n"
            "  --passes N         at most N warm passes per row (default 5; at least 1 runs)\n"
            "  --build-budget MS  skip a structure whose predicted build exceeds MS (default 8000)\n"
            "  --method-scenes L  built-in scenes for the triangle/box test sweep (default cornell,icosphere)\n"
            "  --timeout S        each structure runs per scene in a child process, killed after S\n"
            "                     seconds (default 60; 0 = in this process, no protection)\n"
            "  --mem-limit MB     address-space limit of that child (default 4096)\n"
            "  --brute-max N      brute force only up to N triangles (default 5000)\n"
            "  --no-embree --no-methods --no-hooks --no-packets --no-targets   skip those parts\n"
            "                     (methods: the 5 other triangle/box test pairs, on 1/4 of the rays)\n"
            "  --target-scenes L  scenes of the targets section (default bunny,sponza): NAME.obj or\n"
            "                     NAME.ply in --scenes DIR (else the first NAME*.obj/.ply there),\n"
            "                     else a built-in scene\n"
            "  --rounds N         interleaved rounds per scene and ray kind in the targets section\n"
            "                     (default 21)\n"
            "  --csv FILE         every row as CSV; the targets section goes to FILE-targets.csv\n"
            "                     (FILE without its .csv)\n"
            "  --plot FILE.svg    Mrays/s against error rate, one point per (structure, tri/box test)\n");
    fprintf(out,
            "  --markdown FILE.md the headline figures as Markdown blocks between marker comments\n"
            "                     (<!-- bench:NAME begin --> ... end -->: table, packets, threads, hooks,\n"
            "                     targets), each opened by the date, CPU, cores, the SIMD kernels the\n"
            "                     wide BVHs picked and the command; docs/bench_refresh.sh copies them\n"
            "                     into the documents (make bench: docs/benchmark.md, README.md)\n"
            "  --revision REV     what was measured (e.g. a commit), cited in the Markdown blocks\n"
            "  --md-command CMD   the command the Markdown blocks cite (default: this command line\n"
            "                     without its output options)\n"
            "Columns: build_ms, Mrays/s (one thread), MB (structure memory: sidx_accel_stats.bytes,\n"
            "Embree's memory monitor), peak_MB (the build's resident peak: how far the process's\n"
            "resident set rose above its level just before the build, with the mesh loaded, so the\n"
            "mesh is not included; Embree's includes its copy of the vertices and indices; \"-\" where\n"
            "/proc/self/clear_refs is missing), heap_MB (sidx: the most bytes live at once through\n"
            "the build's sidx_allocator), nodes, depth (deepest\n"
            "leaf), leaf (mean primitives per non-empty leaf or cell), dup (primitive references per\n"
            "triangle: the duplication factor of spatial subdivisions), steps (NODE_ENTER\n"
            "events per ray) and prims (PRIM_TEST events per ray) on up to 1000 rays, then on the\n"
            "reference subset: checked rays, false misses, false hits, wrong primitive (different\n"
            "prim and |t - t_ref| > 1e-5 max(1,|t_ref|)), max relative t error.\n"
            "Embree rows: rtcIntersect1 on one thread (device \"threads=1\"), scene flags none or\n"
            "ROBUST, build quality MEDIUM (HIGH for -hq); -p4/-p8/-p16 rows use rtcIntersect4/8/16\n"
            "on primary rays.\n"
            "Packets and threads (primary rays, \"bvh\" in --accel; --no-packets skips them):\n"
            "sidx_trace_tiles 4x4/8x8 plain/frustum over bvh, bvh8, bvh4 vs single rays and vs\n"
            "Embree rtcIntersect4/8/16\n"
            "on the same image in 4x4 tiles (thread CPU time); the bvh build on 1 and 2 threads vs\n"
            "Embree on threads=1/2 devices; sidx_trace_parallel 1 vs 2 threads (efficiency\n"
            "T1/(2 T2), and a CPU efficiency that leaves out waiting for a core) vs Embree's\n"
            "rtcIntersect1 called from 1 and 2 threads; a \"twin\" row: one thread tracing alone vs\n"
            "beside a twin doing the same on the other core, the machine's own 2-thread ceiling\n"
            "(memory bandwidth, SMT) to judge the efficiencies by.  Wall-clock figures mean\n"
            "something on a quiet machine only.\n");
    fprintf(out,
            "Targets (last section), on each --target-scenes scene: speed on primary and diffuse\n"
            "rays: bvh >= 0.5x Embree, kdtree >= 0.8x bvh, bvh8 >= 1.0x Embree, bvh8 >= 1.2x Embree\n"
            "HQ, bvh >= Embree HQ x 0.75 (bunny primary), 1.1 (Sponza primary), 0.45 (diffuse);\n"
            "build time: bvh <= 1.0x Embree's, bvh8 <= 1.0x Embree HQ's; memory: bvh8 build peak\n"
            "<= 1.2x Embree HQ's, mesh included in both, verdict on the largest scene.\n"
            "For speed the tracers run in interleaved rounds on the same warm rays (order reversed\n"
            "every other round; a tracer's pass with an involuntary context switch, from getrusage,\n"
            "is run again), and each\n"
            "target prints the median [min..max] of the per-round speed ratios and PASS/FAIL.\n"
            "\"fair\" times what rtcIntersect1 returns: sidx_ray_init per ray and t, prim, u, v, Ng\n"
            "(SIDX_QUERY_UV|SIDX_QUERY_NORMAL); \"prep\" is the table's timing (rays prepared\n"
            "beforehand, no u, v, Ng).  The verdict is on the fair median.  Builds: each builder\n"
            "builds once per round (at most 11 rounds), interleaved likewise, CPU time of the\n"
            "process, with its resident peak.  A target runs when both sides are in --accel\n"
            "(embree, embree-hq: not --no-embree).\n"
            "Exit status: 1 when a structure failed (build error, crash, timeout) or an output\n"
            "could not be written; a target's FAIL, or no target measurable, leaves it 0.\n");
}

int bench_cmd_run(int argc, char **argv)
{
    run_opts o = {NULL, NULL, NULL, NULL, NULL, NULL, "cornell,icosphere", 20000, 1, 1.5e8, 100.0, 8000.0, 5000,
                  1, 1, 1, 1, 60000.0, 4096, 2, "bunny,sponza", 1, 21, NULL, NULL, NULL, BENCH_PASSES};
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *val = (i + 1 < argc) ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            run_usage(stdout);
            return BENCH_OK;
        }
        if (!strcmp(a, "--no-embree")) { o.embree = 0; continue; }
        if (!strcmp(a, "--no-methods")) { o.methods = 0; continue; }
        if (!strcmp(a, "--no-hooks")) { o.hooks = 0; continue; }
        if (!strcmp(a, "--no-packets")) { o.packets = 0; continue; }
        if (!strcmp(a, "--no-targets")) { o.targets = 0; continue; }
        if (a[0] != '-' || !val) {
            fprintf(stderr, "sidx-bench run: unexpected '%s'%s\n", a, a[0] == '-' ? " (needs a value)" : "");
            run_usage(stderr);
            return BENCH_USAGE;
        }
        ++i;
        char *end = NULL;
        if (!strcmp(a, "--scenes")) o.scenes_dir = val;
        else if (!strcmp(a, "--accel")) o.accel_list = val;
        else if (!strcmp(a, "--kinds")) o.kinds_list = val;
        else if (!strcmp(a, "--builtin")) o.builtin_list = val;
        else if (!strcmp(a, "--csv")) o.csv = val;
        else if (!strcmp(a, "--plot")) o.plot = val;
        else if (!strcmp(a, "--method-scenes")) o.method_scenes = val;
        else if (!strcmp(a, "--target-scenes")) o.target_scenes = val;
        else if (!strcmp(a, "--markdown")) o.markdown = val;
        else if (!strcmp(a, "--revision")) o.revision = val;
        else if (!strcmp(a, "--md-command")) o.md_command = val;
        else if (!strcmp(a, "--rounds")) {
            const long v = strtol(val, &end, 10);
            if (*end || v < 1 || v > 1001) goto bad_value;
            o.rounds = (int)v;
        }
        else if (!strcmp(a, "--passes")) {
            const long v = strtol(val, &end, 10);
            if (*end || end == val || v < 1 || v > 1000) goto bad_value;
            o.passes = (int)v;
        }
        else if (!strcmp(a, "--timeout")) {
            o.timeout_ms = strtod(val, &end) * 1e3;
            if (*end || !(o.timeout_ms >= 0)) goto bad_value;
        } else if (!strcmp(a, "--mem-limit")) {
            o.mem_limit_mb = strtoul(val, &end, 10);
            if (*end || o.mem_limit_mb < 64) goto bad_value;
        }
        else if (!strcmp(a, "--build-budget")) {
            o.build_budget = strtod(val, &end);
            if (*end || !(o.build_budget > 0)) goto bad_value;
        }
        else if (!strcmp(a, "--rays")) {
            o.rays = (size_t)strtoull(val, &end, 10);
            if (*end || o.rays == 0 || o.rays > 100000000) goto bad_value;
        } else if (!strcmp(a, "--seed")) {
            o.seed = strtoull(val, &end, 0);
            if (*end) goto bad_value;
        } else if (!strcmp(a, "--ref-budget")) {
            o.ref_budget = strtod(val, &end);
            if (*end || !(o.ref_budget > 0)) goto bad_value;
        } else if (!strcmp(a, "--time-budget")) {
            o.time_budget = strtod(val, &end);
            if (*end || !(o.time_budget > 0)) goto bad_value;
        } else if (!strcmp(a, "--brute-max")) {
            o.brute_max = (uint32_t)strtoul(val, &end, 10);
            if (*end) goto bad_value;
        } else {
            fprintf(stderr, "sidx-bench run: unknown option '%s'\n", a);
            run_usage(stderr);
            return BENCH_USAGE;
        }
        continue;
    bad_value:
        fprintf(stderr, "sidx-bench run: bad value '%s' for %s\n", val, a);
        return BENCH_USAGE;
    }
    if (o.builtin_list && !strcmp(o.builtin_list, "none")) o.builtin_list = "";
    bench_cpu_time = 1;
    /* validate lists */
    tk_ray_kind kinds[TK_RAYS_KIND_COUNT];
    int nk = 0;
    for (int k = 0; k < TK_RAYS_KIND_COUNT; ++k)
        if (bench_list_has(o.kinds_list, tk_ray_kind_name((tk_ray_kind)k))) kinds[nk++] = (tk_ray_kind)k;
    if (nk == 0) {
        fprintf(stderr, "sidx-bench run: --kinds selects no ray kind (primary diffuse shadow grazing axis)\n");
        return BENCH_USAGE;
    }
    if (o.accel_list) {
        const char *p = o.accel_list;
        while (*p) {
            const char *e = strchr(p, ',');
            char nm[64];
            size_t len = e ? (size_t)(e - p) : strlen(p);
            snprintf(nm, sizeof nm, "%.*s", (int)(len < 63 ? len : 63), p);
            if (!sidx_accel_is_registered(nm) && !bench_embree_parse(nm, NULL)) {
                fprintf(stderr, "sidx-bench run: unknown structure '%s' in --accel\n", nm);
                return BENCH_USAGE;
            }
            if (!e) break;
            p = e + 1;
        }
    }
    scene_spec scenes[64];
    size_t ns = collect_scenes(&o, scenes, 64);
    if (ns == (size_t)-1) return BENCH_USAGE;
    FILE *md = NULL;
    char caption[2048] = "";
    md_scene *mds = calloc(ns ? ns : 1, sizeof *mds);
    md_hooks *mdh = calloc(1, sizeof *mdh);
    if (!mds || !mdh) {
        fprintf(stderr, "sidx-bench run: out of memory\n");
        free(mds);
        free(mdh);
        return BENCH_FAIL;
    }
    if (o.markdown) {
        md = fopen(o.markdown, "w");
        if (!md) {
            fprintf(stderr, "sidx-bench run: cannot write %s: %s\n", o.markdown, strerror(errno));
            free(mds);
            free(mdh);
            return BENCH_USAGE;
        }
        md_caption(&o, argc, argv, caption, sizeof caption);
        fprintf(md, "<!-- Written by sidx-bench run --markdown.  docs/bench_refresh.sh copies each block into the\n"
                    "     documents that have its markers (make bench does: docs/benchmark.md, README.md). -->\n\n");
    }

    rows rs = {NULL, 0, 0};
    FILE *f = stdout;
    fprintf(f, "sidx-bench run: %zu rays per scene x kind (seed %llu), one thread; Embree %s; "
               "reference: double-precision watertight brute force;\n"
               "times are CPU time of the tracing thread (builds: of the process), not wall-clock;\n"
               "Mrays/s: the best of up to %d warm passes after a cold one (the CSV has the cold and median)\n",
            o.rays, (unsigned long long)o.seed, bench_embree_version(), o.passes);
    const double t_start = tk_now_ms();
    int failures = 0;
    double ms_per_tri[128] = {0};
    for (size_t si = 0; si < ns; ++si) {
        const scene_spec *sc = &scenes[si];
        sidx_mesh m = {0};
        sidx_error err = {SIDX_OK, ""};
        const double scene_t0 = tk_now_ms();
        bench_progress("%s: loading", sc->name);
        if (sidx_scene_open(sc->spec, &m, &err) != SIDX_OK) {
            bench_progress_done();
            fprintf(stderr, "sidx-bench run: %s: %s\n", sc->spec, err.message);
            ++failures;
            continue;
        }
        kind_data kd[TK_RAYS_KIND_COUNT];
        int ok = 1;
        for (int k = 0; k < nk; ++k) {
            bench_progress("%s: rays and reference (%s)", sc->name, tk_ray_kind_name(kinds[k]));
            if (!kind_data_make(&m, kinds[k], &o, &kd[k])) ok = 0;
        }
        if (!ok) {
            fprintf(stderr, "sidx-bench run: out of memory preparing rays for %s\n", sc->name);
            for (int k = 0; k < nk; ++k) kind_data_free(&kd[k]);
            sidx_mesh_free(&m);
            ++failures;
            continue;
        }
        const size_t first = rs.n;
        for (size_t i = 0; i < sidx_accel_registered_count() && i < 128; ++i) {
            const char *name = sidx_accel_registered_name(i);
            if (!bench_list_has(o.accel_list, name)) continue;
            if (!strcmp(name, "brute") && m.num_triangles > o.brute_max) continue;
            /* a build cannot be interrupted: skip what would blow the budget,
             * predicted from the slowest ms per triangle seen so far */
            const double predicted = ms_per_tri[i] * m.num_triangles * 1.5;
            if (predicted > o.build_budget) {
                fprintf(f, "(%s: %s skipped: predicted build %.0f ms > --build-budget %.0f)\n", sc->name, name,
                        predicted, o.build_budget);
                continue;
            }
            bench_progress("%s: %s", sc->name, name);
            char why[160];
            job jb = {name, &m, sc, kd, nk, 0, &o};
            const double bms = job_isolated(&jb, &rs, why, sizeof why);
            if (bms < 0) {
                fprintf(f, "(%s: %s failed: %s)\n", sc->name, name, why[0] ? why : "build error");
                fprintf(stderr, "sidx-bench run: %s on %s: %s\n", name, sc->name, why[0] ? why : "build error");
                ++failures;
                ms_per_tri[i] = INFINITY; /* do not try it on bigger scenes */
                continue;
            }
            if (m.num_triangles >= 1000 && bms / m.num_triangles > ms_per_tri[i])
                ms_per_tri[i] = bms / m.num_triangles;
            if (!o.methods || !sc->builtin || !bench_list_has(o.method_scenes, sc->spec)) continue;
            /* the other triangle / box tests, on a quarter of the rays (for the plot) */
            bench_progress("%s: %s, other triangle/box tests", sc->name, name);
            jb.sweep = 1;
            if (job_isolated(&jb, &rs, why, sizeof why) < 0)
                fprintf(f, "(%s: %s, other triangle/box tests failed: %s)\n", sc->name, name, why);
        }
        if (o.embree) {
            static const char *const en[] = {"embree", "embree-robust", "embree-hq", "embree-robust-hq"};
            for (size_t e = 0; e < sizeof en / sizeof en[0]; ++e) {
                bench_embree_cfg cfg;
                if (o.accel_list && !bench_list_has(o.accel_list, en[e])) continue;
                bench_embree_parse(en[e], &cfg);
                bench_progress("%s: %s", sc->name, en[e]);
                bench_embree_rows(en[e], cfg, &m, sc, kd, nk, &o, &rs);
            }
        }
        bench_progress_done();
        fprintf(f, "\n== %s: %u triangles (%.1f s)\n", sc->name, m.num_triangles, (tk_now_ms() - scene_t0) / 1e3);
        print_header(f);
        for (int k = 0; k < nk; ++k)
            for (size_t i = first; i < rs.n; ++i)
                if (!strcmp(rs.v[i].kind, tk_ray_kind_name(kinds[k])) && rs.v[i].tri == SIDX_TRI_WATERTIGHT &&
                    rs.v[i].box == SIDX_BOX_ROBUST)
                    print_row(f, &rs.v[i]);
        auto_line(f, &rs, first, sc, &m, kd, nk);
        for (int k = 0; k < nk; ++k) /* packets and threads: primary rays over "bvh" */
            if (o.packets && kinds[k] == TK_RAYS_PRIMARY && bench_list_has(o.accel_list, "bvh"))
                packet_parallel_rows(f, &o, sc, &m, &kd[k], &mds[si]);
        fflush(f);
        for (int k = 0; k < nk; ++k) kind_data_free(&kd[k]);
        sidx_mesh_free(&m);
    }
    summary sums[512];
    const char *sum_scenes = o.methods ? o.method_scenes : NULL;
    const size_t nsum = summarize(&rs, sum_scenes, sums, 512);
    print_summary(f, sum_scenes, sums, nsum);
    /* Embree packets, primary rays only */
    for (size_t i = 0; i < rs.n; ++i)
        if (rs.v[i].packet && (!sum_scenes || bench_list_has(sum_scenes, rs.v[i].scene)))
            fprintf(f, "packet %-26s %-12s primary %9.3f Mrays/s\n", rs.v[i].accel, rs.v[i].scene, row_mrays(&rs.v[i]));
    if (o.hooks && ns > 0) {
        size_t pick = 0;
        for (size_t i = 0; i < ns; ++i)
            if (!strcmp(scenes[i].spec, "teapot")) pick = i;
        hook_rows(f, &o, &scenes[pick], mdh);
    }
    if (md) {
        size_t hs[64];
        const size_t nh = md_headline_scenes(&o, scenes, ns, hs);
        md_write_table(md, caption, &rs, scenes, hs, nh, o.passes);
        md_write_packets(md, caption, scenes, mds, hs, nh, &rs, o.passes);
        md_write_threads(md, caption, scenes, mds, hs, nh, &rs);
        md_write_hooks(md, caption, mdh);
        fflush(md);
    }
    int targets_ok = 1;
    if (o.targets) {
        const bench_targets_opts to = {o.scenes_dir, o.target_scenes, o.accel_list, o.csv, o.embree,
                                       o.rounds, o.rays, o.seed, md, caption};
        targets_ok = bench_targets(f, &to);
    }
    fprintf(f, "\ntotal %.1f s wall-clock, %.1f s CPU in this process (children not counted)\n",
            (tk_now_ms() - t_start) / 1e3, tk_process_cpu_ms() / 1e3);
    int rc = failures || !targets_ok ? BENCH_FAIL : BENCH_OK;
    if (o.csv && !write_csv(o.csv, &rs)) {
        fprintf(stderr, "sidx-bench run: cannot write %s: %s\n", o.csv, strerror(errno));
        rc = BENCH_FAIL;
    }
    if (o.plot && !write_plot(o.plot, sums, nsum)) {
        fprintf(stderr, "sidx-bench run: cannot write %s: %s\n", o.plot, strerror(errno));
        rc = BENCH_FAIL;
    }
    if (md && fclose(md) != 0) {
        fprintf(stderr, "sidx-bench run: cannot write %s: %s\n", o.markdown, strerror(errno));
        rc = BENCH_FAIL;
    }
    free(mds);
    free(mdh);
    free(rs.v);
    return rc;
}
