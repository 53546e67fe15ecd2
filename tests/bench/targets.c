/* targets.c — `sidx-bench run`'s targets section: sidx's speed targets
 * against Embree 3, measured so that the ratio, not the machine's load,
 * decides PASS or FAIL:
 *
 *   bvh    >= 0.5 x Embree rtcIntersect1
 *   kdtree >= 0.8 x bvh
 *   bvh8   >= 1.0 x Embree rtcIntersect1
 * on the bunny and Sponza, primary and diffuse rays, one thread.
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

enum { TG_EMBREE, TG_BVH, TG_KDTREE, TG_BVH8, TG_TRACERS };
static const char *const tracer_name[TG_TRACERS] = {"embree", "bvh", "kdtree", "bvh8"};

/* Names as the output prints them: "bvh >= 0.5x Embree". */
static const char *const tracer_label[TG_TRACERS] = {"Embree", "bvh", "kdtree", "bvh8"};

typedef struct target {
    int a, b;   /* speed of a / speed of b */
    double goal;
} target;
static const target targets[] = {
    {TG_BVH, TG_EMBREE, 0.5},
    {TG_KDTREE, TG_BVH, 0.8},
    {TG_BVH8, TG_EMBREE, 1.0},
};
#define NTARGETS (sizeof targets / sizeof targets[0])

/* "bvh >= 0.5x Embree" (text and CSV) or "`bvh` ≥ 0.5× Embree" (Markdown). */
static void target_label(const target *t, int markdown, char *buf, size_t size)
{
    const char *q = markdown ? "`" : "";
    const char *qa = t->a == TG_EMBREE ? "" : q, *qb = t->b == TG_EMBREE ? "" : q;
    snprintf(buf, size, markdown ? "%s%s%s ≥ %.1f× %s%s%s" : "%s%s%s >= %.1fx %s%s%s", qa,
             tracer_label[t->a], qa, t->goal, qb, tracer_label[t->b], qb);
}

/* One scene's tracers. */
typedef struct tracers {
    bench_embree *embree;
    sidx_accel *accel[TG_TRACERS]; /* [TG_EMBREE] unused */
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
    if (t == TG_EMBREE) (void)bench_embree_trace(tr->embree, rec, br->n, 0, 1, hits);
    else (void)trace_fair(tr->accel[t], rec, br->n, hits);
    if (t == TG_EMBREE) {
        *fair = bench_embree_trace(tr->embree, rec, br->n, 0, 1, hits);
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

/* The result of one target on one scene and kind, for the CSV. */
typedef struct tg_result {
    char scene[64];
    const char *kind;
    const target *t;
    spread fair, prep;
    double a_mrays, b_mrays; /* median fair Mrays/s */
    int rounds, retries, preempted, pass; /* retries, preempted: passes of one tracer */
} tg_result;

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
        if (!tgt_on[ti]) continue;
        const target *t = &targets[ti];
        tg_result *res = &out[(*nout)++];
        memset(res, 0, sizeof *res);
        snprintf(res->scene, sizeof res->scene, "%s", scene);
        res->kind = tk_ray_kind_name(kind);
        res->t = t;
        res->rounds = rounds;
        res->retries = retries;
        res->preempted = preempted;
        /* speed ratio a/b = time b / time a, round by round */
        for (int r = 0; r < rounds; ++r) tmp[r] = fair[r * TG_TRACERS + t->b] / fair[r * TG_TRACERS + t->a];
        res->fair = spread_of(tmp, rounds);
        for (int r = 0; r < rounds; ++r) tmp[r] = prep[r * TG_TRACERS + t->b] / prep[r * TG_TRACERS + t->a];
        res->prep = spread_of(tmp, rounds);
        for (int r = 0; r < rounds; ++r) tmp[r] = fair[r * TG_TRACERS + t->a];
        res->a_mrays = (double)n / (spread_of(tmp, rounds).med * 1e3);
        for (int r = 0; r < rounds; ++r) tmp[r] = fair[r * TG_TRACERS + t->b];
        res->b_mrays = (double)n / (spread_of(tmp, rounds).med * 1e3);
        res->pass = res->fair.med >= t->goal;
        char label[48];
        target_label(t, 0, label, sizeof label);
        fprintf(f, "%-26s %-8s %-8s %6.2f [%4.2f..%4.2f] %6.2f [%4.2f..%4.2f] %8.2f %8.2f  %s\n", label, scene,
                res->kind, res->fair.med, res->fair.lo, res->fair.hi, res->prep.med, res->prep.lo, res->prep.hi,
                res->a_mrays, res->b_mrays, res->pass ? "PASS" : "FAIL");
    }
    if (retries || preempted)
        fprintf(f, "%-26s %-8s %-8s (%d of %d passes run again after a context switch; %d kept after %d tries)\n",
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

static int write_csv(const char *path, const tg_result *r, size_t n)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fprintf(f, "target,a,b,goal,scene,kind,fair_ratio_median,fair_ratio_min,fair_ratio_max,prep_ratio_median,"
               "prep_ratio_min,prep_ratio_max,a_fair_mrays,b_fair_mrays,rounds,retried_passes,preempted_passes,"
               "pass\n");
    for (size_t i = 0; i < n; ++i) {
        char label[48];
        target_label(r[i].t, 0, label, sizeof label);
        fprintf(f, "%s,%s,%s,%.2f,%s,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%d,%d,%d\n", label,
                tracer_name[r[i].t->a], tracer_name[r[i].t->b], r[i].t->goal, r[i].scene, r[i].kind, r[i].fair.med,
                r[i].fair.lo, r[i].fair.hi, r[i].prep.med, r[i].prep.lo, r[i].prep.hi, r[i].a_mrays, r[i].b_mrays,
                r[i].rounds, r[i].retries, r[i].preempted, r[i].pass);
    }
    return fclose(f) == 0;
}

/* The bench:targets block of `sidx-bench run --markdown`: one row per
 * target, one column per scene and ray kind, each cell the fair median
 * [min..max] and the verdict. */
static void write_markdown(FILE *md, const char *caption, const tg_result *r, size_t n)
{
    /* the columns: (scene, kind) in the order they were measured */
    size_t col[2 * 64];
    size_t ncol = 0;
    for (size_t i = 0; i < n && ncol < sizeof col / sizeof col[0]; ++i) {
        size_t c = 0;
        while (c < ncol && !(strcmp(r[col[c]].scene, r[i].scene) == 0 && strcmp(r[col[c]].kind, r[i].kind) == 0)) ++c;
        if (c == ncol) col[ncol++] = i;
    }
    fprintf(md, "<!-- bench:targets begin -->\n%s; median of %d interleaved rounds, fair timing, [min..max] over "
                "the rounds:\n\n| target |",
            caption ? caption : "", r[0].rounds);
    for (size_t c = 0; c < ncol; ++c) fprintf(md, " %s %s |", r[col[c]].scene, r[col[c]].kind);
    fprintf(md, "\n|---|");
    for (size_t c = 0; c < ncol; ++c) fprintf(md, "---|");
    fprintf(md, "\n");
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        int any = 0;
        for (size_t i = 0; i < n; ++i) any |= r[i].t == &targets[ti];
        if (!any) continue;
        char label[64];
        target_label(&targets[ti], 1, label, sizeof label);
        fprintf(md, "| %s |", label);
        for (size_t c = 0; c < ncol; ++c) {
            const tg_result *x = NULL;
            for (size_t i = 0; i < n && !x; ++i)
                if (r[i].t == &targets[ti] && !strcmp(r[i].scene, r[col[c]].scene) && !strcmp(r[i].kind, r[col[c]].kind))
                    x = &r[i];
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
    int want[TG_TRACERS] = {0};
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        const int sides[2] = {targets[ti].a, targets[ti].b};
        tgt_on[ti] = 1;
        for (int s = 0; s < 2; ++s) {
            const int t = sides[s];
            const int ok = t == TG_EMBREE ? o->embree && bench_list_has(o->accel_list, "embree")
                                          : sidx_accel_is_registered(tracer_name[t]) &&
                                                bench_list_has(o->accel_list, tracer_name[t]);
            if (!ok) tgt_on[ti] = 0;
        }
        if (tgt_on[ti]) {
            want[targets[ti].a] = want[targets[ti].b] = 1;
            any = 1;
        }
    }
    fprintf(f, "\n== targets: speed of A / speed of B, one thread, thread CPU time; %d interleaved rounds per\n"
               "   scene and kind on the same %zu rays, each timed pass after an untimed one of the same tracer\n"
               "   (steady state; order reversed every other round; a tracer's pass with an involuntary context\n"
               "   switch is run again); median [min..max] of the per-round ratios.\n"
               "   fair: sidx_ray_init per ray and t, prim, u, v, Ng (what rtcIntersect1 returns); prep: rays\n"
               "   prepared beforehand, no u, v, Ng (the table's timing).  Verdict on the fair median.\n",
            o->rounds, o->rays);
    if (!any) {
        /* nothing to measure is not a failure of the run (only a failed
         * structure or an unwritable output is) */
        fprintf(f, "(no target measurable: needs bvh, kdtree, bvh8 and embree in --accel)\n");
        return 1;
    }
    fprintf(f, "%-26s %-8s %-8s %-20s %-20s %8s %8s\n", "target (A >= goal x B)", "scene", "rays", "  fair A/B",
            "  prep A/B", "A Mr/s", "B Mr/s");
    const size_t maxres = 64 * NTARGETS * 2;
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
        if (!name[0] || nres + 2 * NTARGETS > maxres) continue;
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
            if (t == TG_EMBREE) {
                bench_embree_cfg cfg;
                bench_embree_parse("embree", &cfg);
                ok = bench_embree_build(&m, cfg, &tr.embree, &ms, msg, sizeof msg);
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
        bench_embree_free(tr.embree);
        for (int t = 0; t < TG_TRACERS; ++t) sidx_accel_destroy(tr.accel[t]);
        sidx_mesh_free(&m);
    }
    /* one verdict per target over every scene and kind */
    for (size_t ti = 0; ti < NTARGETS; ++ti) {
        if (!tgt_on[ti]) continue;
        int n = 0, pass = 0;
        double worst = INFINITY;
        for (size_t i = 0; i < nres; ++i)
            if (res[i].t == &targets[ti]) {
                ++n;
                pass += res[i].pass;
                if (res[i].fair.med < worst) worst = res[i].fair.med;
            }
        if (n == 0) continue;
        char label[48];
        target_label(&targets[ti], 0, label, sizeof label);
        fprintf(f, "target %s: %s (%d/%d scene x ray kind, lowest median %.2f)\n", label,
                pass == n ? "PASS" : "FAIL", pass, n, worst);
    }
    if (o->md && nres) write_markdown(o->md, o->md_caption, res, nres);
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
