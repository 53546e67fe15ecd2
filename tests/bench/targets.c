/* targets.c — `sidx-bench run`'s targets section: sidx's speed, build
 * time and memory targets against Embree 3, measured so that the ratio,
 * not the machine's load, decides PASS or FAIL:
 *
 *   speed (single rays, primary and diffuse, one thread):
 *     bvh    >= 0.5 x Embree rtcIntersect1 (build quality MEDIUM, the default)
 *     kdtree >= 0.8 x bvh
 *     bvh8   >= 1.0 x Embree
 *     bvh8   >= 1.2 x Embree HQ (build quality HIGH)
 *     bvh    >= Embree HQ x 0.75 on bunny primary, 1.1 on Sponza primary,
 *               0.45 on either's diffuse rays (where the fastest binary
 *               BVHs measured beside Embree HQ stand)
 *   build time (one thread, CPU time of the process):
 *     bvh  build <= 1.0 x Embree's build, bvh8 build <= 1.0 x Embree HQ's
 *   memory: bvh8 build peak <= 1.2 x Embree HQ's, mesh included in both
 *     (resident peak above the loaded mesh, plus the mesh's bytes); the
 *     verdict is on the largest target scene (`sidx-bench scale` prints
 *     the same ratio at its largest size)
 * on the bunny and Sponza.  The HQ targets are stricter than the MEDIUM
 * ones but against another peer, so both are kept.
 *
 * Why a section of its own: the table times every structure in its own
 * phase, seconds apart, and on a shared machine a phase can run 20% slow,
 * which swamps a 0.8x target.  Here the compared tracers run in
 * interleaved rounds (A, B, A, B, ...; the order reversed every other
 * round) on the same rays, and each round gives one ratio: a slow spell
 * hits both sides of the round it falls in.  Every timed pass follows an
 * untimed pass of the same tracer on the same rays, so what is timed is
 * steady-state throughput, as a renderer tracing millions of rays sees
 * it, and not the refill of the caches the previous tracer evicted (that
 * cold start costs Embree more than sidx: its structures are larger; the
 * figures are in docs/performance.md, "Benchmark method").  A tracer's
 * pass during which the thread was preempted (getrusage's involuntary
 * context switches went up: another process then ran on this core and
 * evicted our caches) is run again, up to TG_MAX_RETRIES times.  Retrying
 * whole rounds instead does not work on a shared 2-core machine: with 4
 * tracers a round takes ~0.3 s and rounds were preempted 9 times in a
 * row.  The line reports the median ratio over the rounds with its
 * min..max, so the spread is visible next to the verdict.
 *
 * "fair" timing does the work rtcIntersect1 does: the sidx side builds
 * each ray from the record (sidx_ray_init, as the Embree side fills an
 * RTCRayHit) and asks for t, prim, u, v and Ng (SIDX_QUERY_UV |
 * SIDX_QUERY_NORMAL), which rtcIntersect1 always returns.  "prep" is the
 * table's timing: rays prepared beforehand, no u, v, Ng.  The verdict is on
 * the fair ratio. */
#define _GNU_SOURCE /* RUSAGE_THREAD */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <dirent.h>

#include "bench.h"

#ifdef RUSAGE_THREAD
#define TG_RUSAGE RUSAGE_THREAD
#else
#define TG_RUSAGE RUSAGE_SELF
#endif

/* A pass preempted this many times in a row is kept anyway (and counted),
 * so a machine that never stays quiet still ends the section. */
#define TG_MAX_RETRIES 4

enum { TG_EMBREE, TG_EMBREE_HQ, TG_BVH, TG_KDTREE, TG_BVH8, TG_TRACERS };
static const char *const tracer_name[TG_TRACERS] = {"embree", "embree-hq", "bvh", "kdtree", "bvh8"};
static int is_embree(int t) { return t == TG_EMBREE || t == TG_EMBREE_HQ; }

/* Names as the output prints them: "bvh >= 0.5x Embree". */
static const char *const tracer_label[TG_TRACERS] = {"Embree", "Embree HQ", "bvh", "kdtree", "bvh8"};

/* What a target compares: single-ray speed (a / b >= goal), build time
 * or build peak memory (a / b <= goal). */
typedef enum { TG_SPEED, TG_BUILD, TG_MEMORY } tg_what;
static const char *const what_kind[3] = {NULL, "build", "memory"}; /* the "rays" column */

/* A goal for the cases whose scene name starts with scene (NULL: any) and
 * whose ray kind is kind (NULL: any); the first match counts. */
typedef struct tg_goal {
    const char *scene, *kind;
    double goal;
} tg_goal;

typedef struct target {
    tg_what what;
    int a, b;
    tg_goal goals[4]; /* goal 0 ends the list; a case no goal matches is not measured */
} target;
static const target targets[] = {
    {TG_SPEED, TG_BVH, TG_EMBREE, {{NULL, NULL, 0.5}}},
    {TG_SPEED, TG_KDTREE, TG_BVH, {{NULL, NULL, 0.8}}},
    {TG_SPEED, TG_BVH8, TG_EMBREE, {{NULL, NULL, 1.0}}},
    {TG_SPEED, TG_BVH8, TG_EMBREE_HQ, {{NULL, NULL, 1.2}}},
    {TG_SPEED, TG_BVH, TG_EMBREE_HQ,
     {{"bunny", "primary", 0.75}, {"sponza", "primary", 1.1}, {"bunny", "diffuse", 0.45}, {"sponza", "diffuse", 0.45}}},
    {TG_BUILD, TG_BVH, TG_EMBREE, {{NULL, NULL, 1.0}}},
    {TG_BUILD, TG_BVH8, TG_EMBREE_HQ, {{NULL, NULL, 1.0}}},
    {TG_MEMORY, TG_BVH8, TG_EMBREE_HQ, {{NULL, NULL, 1.2}}},
};
#define NTARGETS (sizeof targets / sizeof targets[0])

/* The goal of target t on scene and kind; 0 = none. */
static double goal_of(const target *t, const char *scene, const char *kind)
{
    for (size_t i = 0; i < sizeof t->goals / sizeof t->goals[0] && t->goals[i].goal > 0; ++i) {
        const tg_goal *g = &t->goals[i];
        if ((!g->scene || !strncmp(scene, g->scene, strlen(g->scene))) && (!g->kind || !strcmp(kind, g->kind)))
            return g->goal;
    }
    return 0;
}

static int uniform_goal(const target *t) { return !t->goals[0].scene && !t->goals[0].kind; }

/* "bvh >= 0.5x Embree", "bvh build <= 1.0x Embree", "bvh >= goal x Embree
 * HQ" (per-case goals) in text and CSV; "`bvh` ≥ 0.5× Embree" in Markdown. */
static void target_label(const target *t, int markdown, char *buf, size_t size)
{
    const char *q = markdown ? "`" : "";
    const char *qa = is_embree(t->a) ? "" : q, *qb = is_embree(t->b) ? "" : q;
    const char *what = t->what == TG_BUILD ? " build" : t->what == TG_MEMORY ? " peak" : "";
    const char *rel = t->what == TG_SPEED ? (markdown ? "≥" : ">=") : (markdown ? "≤" : "<=");
    char goal[32];
    if (uniform_goal(t)) snprintf(goal, sizeof goal, markdown ? "%.1f×" : "%.1fx", t->goals[0].goal);
    else snprintf(goal, sizeof goal, markdown ? "goal ×" : "goal x");
    snprintf(buf, size, "%s%s%s%s %s %s %s%s%s%s", qa, tracer_label[t->a], qa, what, rel, goal, qb, tracer_label[t->b],
             qb, what);
}

/* One scene's tracers. */
typedef struct tracers {
    bench_embree *embree[2];       /* [0] MEDIUM, [1] HIGH */
    sidx_accel *accel[TG_TRACERS]; /* [TG_EMBREE*] unused */
    int used[TG_TRACERS];
} tracers;

static long involuntary_switches(void)
{
    struct rusage ru;
    if (getrusage(TG_RUSAGE, &ru) != 0) return 0;
    return ru.ru_nivcsw;
}

/* The fair sidx trace: a sidx_ray from each record, then t, prim, u, v, Ng. */
static double trace_fair(const sidx_accel *a, const tk_rayrec *rec, size_t n, sidx_hit *hits)
{
    static const sidx_query q = {SIDX_QUERY_UV | SIDX_QUERY_NORMAL, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    const double t0 = bench_clock_ms();
    for (size_t i = 0; i < n; ++i) {
        sidx_ray r;
        if (tk_ray_from(&rec[i], &r) == SIDX_OK) sidx_accel_intersect(a, &r, &q, &hits[i]);
        else hits[i] = sidx_hit_none();
    }
    return bench_clock_ms() - t0;
}

/* One pass of tracer t, after an untimed one: fair ms, and for sidx
 * tracers the prep ms too.
 * Embree has one timing for both: rtcIntersect1 builds its ray per call,
 * and the table times it the same way. */
static void trace_once(const tracers *tr, int t, const tk_rayrec *rec, const bench_rays *br, sidx_hit *hits,
                       double *fair, double *prep)
{
    /* untimed: the same tracer's structure into the caches (see the top) */
    bench_embree *e = is_embree(t) ? tr->embree[t == TG_EMBREE_HQ] : NULL;
    if (e) (void)bench_embree_trace(e, rec, br->n, 0, 1, hits);
    else (void)trace_fair(tr->accel[t], rec, br->n, hits);
    if (e) {
        *fair = bench_embree_trace(e, rec, br->n, 0, 1, hits);
        *prep = *fair;
        return;
    }
    *fair = trace_fair(tr->accel[t], rec, br->n, hits);
    bench_trace(tr->accel[t], br, 0, br->n, NULL, 0, 1, 0.0, hits, prep);
}

static int cmp_double(const void *x, const void *y)
{
    const double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

typedef struct spread { double med, lo, hi; } spread;

static spread spread_of(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    spread s = {NAN, NAN, NAN};
    if (n <= 0) return s;
    s.med = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    s.lo = v[0];
    s.hi = v[n - 1];
    return s;
}

/* The result of one target on one scene and kind ("build", "memory" for
 * those targets), for the CSV. */
typedef struct tg_result {
    char scene[64];
    uint32_t tris;
    const char *kind;
    const target *t;
    double goal;
    spread fair, prep;       /* prep: speed targets only */
    double a_val, b_val;     /* median fair Mrays/s, build ms, or peak MB with the mesh */
    int rounds, retries, preempted, pass; /* retries, preempted: passes of one tracer */
} tg_result;

static const char *const unit_of[3] = {"Mr/s", "ms", "MB"};

/* One result line of the text output. */
static void print_result(FILE *f, const tg_result *res)
{
    char label[64], goal[16], prep[32];
    target_label(res->t, 0, label, sizeof label);
    snprintf(goal, sizeof goal, "%s%.2f", res->t->what == TG_SPEED ? ">=" : "<=", res->goal);
    if (res->t->what == TG_SPEED)
        snprintf(prep, sizeof prep, "%6.2f [%4.2f..%4.2f]", res->prep.med, res->prep.lo, res->prep.hi);
    else snprintf(prep, sizeof prep, "%6s", "-");
    fprintf(f, "%-34s %-8s %-8s %6s %6.2f [%4.2f..%4.2f] %-20s %8.2f %8.2f %-4s  %s\n", label, res->scene, res->kind,
            goal, res->fair.med, res->fair.lo, res->fair.hi, prep, res->a_val, res->b_val, unit_of[res->t->what],
            res->pass ? "PASS" : "FAIL");
}

static int mesh_file(const char *fname)
{
    const size_t len = strlen(fname);
    return len > 4 && (!strcmp(fname + len - 4, ".obj") || !strcmp(fname + len - 4, ".ply"));
}

/* The scene: NAME.obj or NAME.ply in scenes_dir, else the first (by name)
 * mesh file there whose name starts with NAME ("sponza" finds
 * sponza_dabrovic.obj), else NAME as a built-in scene or a path. */
/* A message snprintf cut short (n, what it returned, >= size) ends in
 * "..." so the reader sees it was cut.  Taking snprintf's result is also
 * what tells gcc's -Wformat-truncation (raised at -O0, -O1 and -Os) that
 * the cut is expected. */
static void mark_cut(char *msg, size_t size, int n)
{
    if (n >= 0 && (size_t)n >= size && size >= 4) memcpy(msg + size - 4, "...", 4);
}

static int open_scene(const char *name, const char *scenes_dir, sidx_mesh *m, char *msg, size_t msg_size)
{
    sidx_error err = {SIDX_OK, ""};
    char best[256] = "";
    DIR *d = scenes_dir ? opendir(scenes_dir) : NULL;
    const size_t nlen = strlen(name);
    for (struct dirent *de; d && (de = readdir(d));) {
        const char *fn = de->d_name;
        if (!mesh_file(fn) || strncmp(fn, name, nlen) != 0 || strlen(fn) >= sizeof best) continue;
        const int exact = strlen(fn) == nlen + 4;
        const int best_exact = best[0] && strlen(best) == nlen + 4;
        if (!best[0] || (exact && !best_exact) || (exact == best_exact && strcmp(fn, best) < 0))
            snprintf(best, sizeof best, "%s", fn);
    }
    if (d) closedir(d);
    if (best[0]) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", scenes_dir, best);
        if (sidx_scene_open(path, m, &err) == SIDX_OK) return 1;
        mark_cut(msg, msg_size, snprintf(msg, msg_size, "%s: %s", best, err.message));
        return 0;
    }
    if (sidx_scene_open(name, m, &err) == SIDX_OK) return 1;
    snprintf(msg, msg_size, "not found%s%s", scenes_dir ? " in " : " (no --scenes DIR)", scenes_dir ? scenes_dir : "");
    return 0;
}

/* Every round of one scene and kind: per-round ratios of each target. */
static void measure_kind(FILE *f, const bench_targets_opts *o, const char *scene, const sidx_mesh *m,
                         tracers *tr, const int *tgt_on, tk_ray_kind kind, tg_result *out, size_t *nout)
{
    const size_t n = o->rays;
    const int rounds = o->rounds;
    tk_rayrec *rec = malloc(n * sizeof *rec);
    sidx_hit *hits = malloc(n * sizeof *hits);
    double *fair = malloc((size_t)rounds * TG_TRACERS * sizeof *fair);
    double *prep = malloc((size_t)rounds * TG_TRACERS * sizeof *prep);
    double *tmp = malloc((size_t)rounds * sizeof *tmp);
    bench_rays br = {NULL, NULL, 0};
    if (!rec || !hits || !fair || !prep || !tmp) goto oom;
    tk_make_rays(m, kind, n, o->seed, rec);
    if (!bench_rays_prepare(rec, n, &br)) goto oom;
    int order[TG_TRACERS] = {0}, nt = 0;
    for (int t = 0; t < TG_TRACERS; ++t)
        if (tr->used[t]) order[nt++] = t;
    /* no separate warm-up: trace_once's untimed pass also takes the page
     * faults and Embree's lazy set-up before the first timed pass */
    int retries = 0, preempted = 0;
    for (int r = 0; r < rounds; ++r) {
        bench_progress("targets: %s %s round %d/%d", scene, tk_ray_kind_name(kind), r + 1, rounds);
        for (int j = 0; j < nt; ++j) {
            const int t = order[r % 2 ? nt - 1 - j : j];
            for (int attempt = 0;; ++attempt) {
                const long cs0 = involuntary_switches();
                trace_once(tr, t, rec, &br, hits, &fair[r * TG_TRACERS + t], &prep[r * TG_TRACERS + t]);
                if (involuntary_switches() == cs0) break;
                if (attempt == TG_MAX_RETRIES) {
                    ++preempted;
                    break;
                }
                ++retries;
            }
        }
    }
    bench_progress_done();
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        const target *t = &targets[ti];
        const double goal = goal_of(t, scene, tk_ray_kind_name(kind));
        if (!tgt_on[ti] || t->what != TG_SPEED || goal <= 0) continue;
        tg_result *res = &out[(*nout)++];
        memset(res, 0, sizeof *res);
        snprintf(res->scene, sizeof res->scene, "%s", scene);
        res->tris = m->num_triangles;
        res->kind = tk_ray_kind_name(kind);
        res->t = t;
        res->goal = goal;
        res->rounds = rounds;
        res->retries = retries;
        res->preempted = preempted;
        /* speed ratio a/b = time b / time a, round by round */
        for (int r = 0; r < rounds; ++r) tmp[r] = fair[r * TG_TRACERS + t->b] / fair[r * TG_TRACERS + t->a];
        res->fair = spread_of(tmp, rounds);
        for (int r = 0; r < rounds; ++r) tmp[r] = prep[r * TG_TRACERS + t->b] / prep[r * TG_TRACERS + t->a];
        res->prep = spread_of(tmp, rounds);
        for (int r = 0; r < rounds; ++r) tmp[r] = fair[r * TG_TRACERS + t->a];
        res->a_val = (double)n / (spread_of(tmp, rounds).med * 1e3);
        for (int r = 0; r < rounds; ++r) tmp[r] = fair[r * TG_TRACERS + t->b];
        res->b_val = (double)n / (spread_of(tmp, rounds).med * 1e3);
        res->pass = res->fair.med >= goal;
        print_result(f, res);
    }
    if (retries || preempted)
        fprintf(f, "%-34s %-8s %-8s (%d of %d passes run again after a context switch; %d kept after %d tries)\n",
                "", scene, tk_ray_kind_name(kind), retries, rounds * nt, preempted, TG_MAX_RETRIES + 1);
    fflush(f);
oom:
    if (!rec || !hits || !fair || !prep || !tmp || !br.r) fprintf(stderr, "sidx-bench run: targets: out of memory\n");
    bench_rays_free(&br);
    free(rec);
    free(hits);
    free(fair);
    free(prep);
    free(tmp);
}

/* The build rounds of one scene: each builder the build and memory
 * targets need builds the mesh once per round, in interleaved order
 * (reversed every other round), with its build clock (CPU time of the
 * process, as the table's builds) and its resident peak (bench_mem: the
 * rise above the loaded mesh; the mesh's bytes are added to both sides,
 * "mesh included in both").  Embree's build includes copying the vertices
 * and indices into its buffers, which its API needs.  At most
 * TG_BUILD_ROUNDS rounds: a build round of the 4 builders on a 70k-triangle
 * mesh takes ~0.3 s. */
#define TG_BUILD_ROUNDS 11
static void measure_builds(FILE *f, const bench_targets_opts *o, const char *scene, const sidx_mesh *m,
                           const int *tgt_on, tg_result *out, size_t *nout)
{
    int want[TG_TRACERS] = {0}, any = 0;
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        const target *t = &targets[ti];
        if (!tgt_on[ti] || t->what == TG_SPEED || goal_of(t, scene, what_kind[t->what]) <= 0) continue;
        want[t->a] = want[t->b] = any = 1;
    }
    if (!any) return;
    const int rounds = o->rounds < TG_BUILD_ROUNDS ? o->rounds : TG_BUILD_ROUNDS;
    double ms[TG_BUILD_ROUNDS][TG_TRACERS], mb[TG_BUILD_ROUNDS][TG_TRACERS], tmp[TG_BUILD_ROUNDS];
    int order[TG_TRACERS] = {0}, nt = 0;
    for (int t = 0; t < TG_TRACERS; ++t)
        if (want[t]) order[nt++] = t;
    const double mesh = (double)bench_mesh_bytes(m);
    for (int r = 0; r < rounds; ++r) {
        bench_progress("targets: %s builds round %d/%d", scene, r + 1, rounds);
        for (int j = 0; j < nt; ++j) {
            const int t = order[r % 2 ? nt - 1 - j : j];
            bench_mem mem;
            char msg[256] = "";
            double t_ms = 0;
            int ok;
            if (is_embree(t)) {
                bench_embree_cfg cfg;
                bench_embree_parse(tracer_name[t], &cfg);
                bench_embree *e = NULL;
                bench_mem_begin(&mem);
                ok = bench_embree_build(m, cfg, &e, &t_ms, msg, sizeof msg);
                mb[r][t] = (double)bench_mem_end(&mem);
                bench_embree_free(e);
            } else {
                sidx_accel *a = NULL;
                sidx_error err = {SIDX_OK, ""};
                bench_mem_begin(&mem);
                const double t0 = bench_build_clock_ms();
                ok = sidx_accel_build(tracer_name[t], m, NULL, &a, &err) == SIDX_OK;
                t_ms = bench_build_clock_ms() - t0;
                mb[r][t] = (double)bench_mem_end(&mem);
                if (!ok) mark_cut(msg, sizeof msg, snprintf(msg, sizeof msg, "%s", err.message));
                sidx_accel_destroy(a);
            }
            if (!ok) {
                bench_progress_done();
                fprintf(f, "(targets: %s: %s build failed: %s; build targets skipped)\n", scene, tracer_name[t], msg);
                return;
            }
            ms[r][t] = t_ms;
            mb[r][t] = mb[r][t] < 0 ? NAN : (mb[r][t] + mesh) / 1048576.0;
        }
    }
    bench_progress_done();
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        const target *t = &targets[ti];
        if (!tgt_on[ti] || t->what == TG_SPEED) continue;
        const double goal = goal_of(t, scene, what_kind[t->what]);
        if (goal <= 0) continue;
        double(*v)[TG_TRACERS] = t->what == TG_BUILD ? ms : mb;
        if (isnan(v[0][t->a]) || isnan(v[0][t->b])) {
            fprintf(f, "(targets: %s: resident peak not measurable here (needs /proc/self/clear_refs))\n", scene);
            continue;
        }
        tg_result *res = &out[(*nout)++];
        memset(res, 0, sizeof *res);
        snprintf(res->scene, sizeof res->scene, "%s", scene);
        res->tris = m->num_triangles;
        res->kind = what_kind[t->what];
        res->t = t;
        res->goal = goal;
        res->rounds = rounds;
        for (int r = 0; r < rounds; ++r) tmp[r] = v[r][t->a] / v[r][t->b];
        res->fair = spread_of(tmp, rounds);
        res->prep = (spread){NAN, NAN, NAN};
        for (int r = 0; r < rounds; ++r) tmp[r] = v[r][t->a];
        res->a_val = spread_of(tmp, rounds).med;
        for (int r = 0; r < rounds; ++r) tmp[r] = v[r][t->b];
        res->b_val = spread_of(tmp, rounds).med;
        res->pass = res->fair.med <= goal;
        print_result(f, res);
    }
    fflush(f);
}

static int write_csv(const char *path, const tg_result *r, size_t n)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    /* kind: a ray kind (speed: A/B speed >= goal), "build" (A/B build
     * time <= goal) or "memory" (A/B build peak with the mesh <= goal);
     * a_value, b_value in unit (Mr/s fair, ms, MB) */
    fprintf(f, "target,what,a,b,relation,goal,scene,tris,kind,fair_ratio_median,fair_ratio_min,fair_ratio_max,"
               "prep_ratio_median,prep_ratio_min,prep_ratio_max,a_value,b_value,unit,rounds,retried_passes,"
               "preempted_passes,pass\n");
    static const char *const what_name[3] = {"speed", "build", "memory"};
    for (size_t i = 0; i < n; ++i) {
        char label[64];
        target_label(r[i].t, 0, label, sizeof label);
        fprintf(f, "%s,%s,%s,%s,%s,%.2f,%s,%u,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%s,%d,%d,%d,%d\n", label,
                what_name[r[i].t->what], tracer_name[r[i].t->a], tracer_name[r[i].t->b],
                r[i].t->what == TG_SPEED ? ">=" : "<=", r[i].goal, r[i].scene, r[i].tris, r[i].kind, r[i].fair.med,
                r[i].fair.lo, r[i].fair.hi, r[i].prep.med, r[i].prep.lo, r[i].prep.hi, r[i].a_val, r[i].b_val,
                unit_of[r[i].t->what], r[i].rounds, r[i].retries, r[i].preempted, r[i].pass);
    }
    return fclose(f) == 0;
}

/* The bench:targets block of `sidx-bench run --markdown`: one row per
 * target, one column per scene and ray kind (and "build", "memory"), each
 * cell the fair median [min..max] and the verdict, with the goal in front
 * where the target's goal differs by case. */
static void write_markdown(FILE *md, const char *caption, int o_rounds, const tg_result *r, size_t n)
{
    /* the columns: (scene, kind) in the order they were measured */
    size_t col[2 * 64];
    size_t ncol = 0;
    for (size_t i = 0; i < n && ncol < sizeof col / sizeof col[0]; ++i) {
        size_t c = 0;
        while (c < ncol && !(strcmp(r[col[c]].scene, r[i].scene) == 0 && strcmp(r[col[c]].kind, r[i].kind) == 0)) ++c;
        if (c == ncol) col[ncol++] = i;
    }
    fprintf(md, "<!-- bench:targets begin -->\n%s; median of %d interleaved rounds (builds: %d), fair timing, "
                "[min..max] over the rounds; speed ratios A/B ≥ goal, build-time and memory ratios ≤ goal "
                "(memory: build peak with the mesh):\n\n| target |",
            caption ? caption : "", o_rounds, o_rounds < TG_BUILD_ROUNDS ? o_rounds : TG_BUILD_ROUNDS);
    for (size_t c = 0; c < ncol; ++c) fprintf(md, " %s %s |", r[col[c]].scene, r[col[c]].kind);
    fprintf(md, "\n|---|");
    for (size_t c = 0; c < ncol; ++c) fprintf(md, "---|");
    fprintf(md, "\n");
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        int any = 0;
        for (size_t i = 0; i < n; ++i) any |= r[i].t == &targets[ti];
        if (!any) continue;
        char label[80];
        target_label(&targets[ti], 1, label, sizeof label);
        fprintf(md, "| %s |", label);
        for (size_t c = 0; c < ncol; ++c) {
            const tg_result *x = NULL;
            for (size_t i = 0; i < n && !x; ++i)
                if (r[i].t == &targets[ti] && !strcmp(r[i].scene, r[col[c]].scene) && !strcmp(r[i].kind, r[col[c]].kind))
                    x = &r[i];
            if (x && !uniform_goal(x->t)) fprintf(md, " %s %.2f:", x->t->what == TG_SPEED ? "≥" : "≤", x->goal);
            if (x) fprintf(md, " %.2f [%.2f..%.2f] %s |", x->fair.med, x->fair.lo, x->fair.hi, x->pass ? "pass" : "**fail**");
            else fprintf(md, " – |");
        }
        fprintf(md, "\n");
    }
    fprintf(md, "\n<!-- bench:targets end -->\n\n");
}

/* "dir/table.csv" -> "dir/table-targets.csv" (".csv" added when missing). */
static void targets_csv_path(const char *csv, char *out, size_t size)
{
    const size_t len = strlen(csv);
    const size_t stem = len >= 4 && !strcmp(csv + len - 4, ".csv") ? len - 4 : len;
    snprintf(out, size, "%.*s-targets.csv", (int)stem, csv);
}

int bench_targets(FILE *f, const bench_targets_opts *o)
{
    /* which targets this run can measure: both sides selected by --accel
     * (and Embree not switched off), and the structure registered */
    int tgt_on[NTARGETS], any = 0;
    int want[TG_TRACERS] = {0}; /* tracers of the speed rounds */
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        const int sides[2] = {targets[ti].a, targets[ti].b};
        tgt_on[ti] = 1;
        for (int s = 0; s < 2; ++s) {
            const int t = sides[s];
            const int ok = is_embree(t) ? o->embree && bench_list_has(o->accel_list, tracer_name[t])
                                        : sidx_accel_is_registered(tracer_name[t]) &&
                                              bench_list_has(o->accel_list, tracer_name[t]);
            if (!ok) tgt_on[ti] = 0;
        }
        if (tgt_on[ti]) {
            if (targets[ti].what == TG_SPEED) want[targets[ti].a] = want[targets[ti].b] = 1;
            any = 1;
        }
    }
    fprintf(f, "\n== targets, one thread; %d interleaved rounds per scene and kind (builds: %d) on the same\n"
               "   %zu rays; speed: A/B >= goal, thread CPU time, each timed pass after an untimed one of the\n"
               "   same tracer (steady state; order reversed every other round; a tracer's pass with an\n"
               "   involuntary context switch is run again); median [min..max] of the per-round ratios.\n"
               "   fair: sidx_ray_init per ray and t, prim, u, v, Ng (what rtcIntersect1 returns); prep: rays\n"
               "   prepared beforehand, no u, v, Ng (the table's timing).  Verdict on the fair median.\n"
               "   build: A/B build time (CPU time of the process) <= goal; memory: A/B build peak <= goal,\n"
               "   mesh included in both (resident peak above the loaded mesh + the mesh's bytes), verdict\n"
               "   on the largest scene.  Embree = build quality MEDIUM (default), Embree HQ = HIGH.\n",
            o->rounds, o->rounds < TG_BUILD_ROUNDS ? o->rounds : TG_BUILD_ROUNDS, o->rays);
    if (!any) {
        /* nothing to measure is not a failure of the run (only a failed
         * structure or an unwritable output is) */
        fprintf(f, "(no target measurable: needs bvh, kdtree, bvh8, embree and embree-hq in --accel)\n");
        return 1;
    }
    fprintf(f, "%-34s %-8s %-8s %6s %-20s %-20s %8s %8s %-4s\n", "target (A vs goal x B)", "scene", "rays", "goal",
            "  fair A/B", "  prep A/B", "A", "B", "unit");
    const size_t maxres = 64 * NTARGETS * 4;
    tg_result *res = calloc(maxres, sizeof *res);
    if (!res) return 0;
    size_t nres = 0;
    const char *p = o->scene_list;
    while (p && *p) {
        const char *e = strchr(p, ',');
        char name[64];
        const size_t len = e ? (size_t)(e - p) : strlen(p);
        snprintf(name, sizeof name, "%.*s", (int)(len < 63 ? len : 63), p);
        p = e ? e + 1 : NULL;
        if (!name[0] || nres + 4 * NTARGETS > maxres) continue;
        sidx_mesh m = {0};
        char msg[256] = "";
        bench_progress("targets: %s: loading and building", name);
        if (!open_scene(name, o->scenes_dir, &m, msg, sizeof msg)) {
            bench_progress_done();
            fprintf(f, "(targets: %s: %s; skipped)\n", name, msg);
            continue;
        }
        tracers tr;
        memset(&tr, 0, sizeof tr);
        int ok = 1;
        for (int t = 0; t < TG_TRACERS && ok; ++t) {
            if (!want[t]) continue;
            double ms;
            if (is_embree(t)) {
                bench_embree_cfg cfg;
                bench_embree_parse(tracer_name[t], &cfg);
                ok = bench_embree_build(&m, cfg, &tr.embree[t == TG_EMBREE_HQ], &ms, msg, sizeof msg);
            } else {
                sidx_error err = {SIDX_OK, ""};
                ok = sidx_accel_build(tracer_name[t], &m, NULL, &tr.accel[t], &err) == SIDX_OK;
                if (!ok) mark_cut(msg, sizeof msg, snprintf(msg, sizeof msg, "%s: %s", tracer_name[t], err.message));
            }
            tr.used[t] = ok;
        }
        if (!ok) {
            bench_progress_done();
            fprintf(f, "(targets: %s: build failed: %s; skipped)\n", name, msg);
        } else {
            static const tk_ray_kind kinds[2] = {TK_RAYS_PRIMARY, TK_RAYS_DIFFUSE};
            for (int k = 0; k < 2; ++k) measure_kind(f, o, name, &m, &tr, tgt_on, kinds[k], res, &nres);
        }
        for (int i = 0; i < 2; ++i) bench_embree_free(tr.embree[i]);
        for (int t = 0; t < TG_TRACERS; ++t) sidx_accel_destroy(tr.accel[t]);
        /* the build rounds run with no other structure alive */
        if (ok) measure_builds(f, o, name, &m, tgt_on, res, &nres);
        sidx_mesh_free(&m);
    }
    /* one verdict per target over every scene and kind; memory: on the
     * largest scene only (memory at scale is what the target is about) */
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        if (!tgt_on[ti]) continue;
        uint32_t largest = 0;
        const char *largest_name = "";
        for (size_t i = 0; i < nres; ++i)
            if (res[i].t == &targets[ti] && res[i].tris > largest) {
                largest = res[i].tris;
                largest_name = res[i].scene;
            }
        const int only_largest = targets[ti].what == TG_MEMORY;
        int n = 0, pass = 0;
        double worst = NAN;
        for (size_t i = 0; i < nres; ++i) {
            if (res[i].t != &targets[ti] || (only_largest && res[i].tris != largest)) continue;
            ++n;
            pass += res[i].pass;
            /* the case furthest from its goal, as a ratio to the goal */
            const double m = targets[ti].what == TG_SPEED ? res[i].fair.med / res[i].goal : res[i].goal / res[i].fair.med;
            if (isnan(worst) || m < worst) worst = m;
        }
        if (n == 0) continue;
        char label[64];
        target_label(&targets[ti], 0, label, sizeof label);
        if (only_largest)
            fprintf(f, "target %s: %s (on the largest scene, %s, %u triangles; %.2f of the goal)\n", label,
                    pass == n ? "PASS" : "FAIL", largest_name, largest, worst);
        else
            fprintf(f, "target %s: %s (%d/%d cases; the furthest at %.2f of its goal)\n", label,
                    pass == n ? "PASS" : "FAIL", pass, n, worst);
    }
    if (o->md && nres) write_markdown(o->md, o->md_caption, o->rounds, res, nres);
    int rc = 1;
    if (o->csv && nres) {
        char path[1024];
        targets_csv_path(o->csv, path, sizeof path);
        if (!write_csv(path, res, nres)) {
            fprintf(stderr, "sidx-bench run: cannot write %s: %s\n", path, strerror(errno));
            rc = 0;
        }
    }
    free(res);
    return rc;
}
