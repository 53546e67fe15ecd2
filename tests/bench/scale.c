/* scale.c — `sidx-bench scale`: build time and traversal steps per ray
 * against triangle count (1k … 4M, procedural), with growth exponents
 * fitted by least squares on log-log axes (n log n build shows as an
 * exponent a little above 1; log n steps as a small exponent, and as the
 * slope per doubling of n; n^(1/3) for uniform grids as about 0.33). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"

typedef struct scale_pt {
    int accel;     /* index into the structure list */
    double tris, build_ms, steps, prims, mrays;
} scale_pt;

static void scale_usage(FILE *out)
{
    fprintf(out,
            "usage: sidx-bench scale [options]\n"
            "\n"
            "Sweeps the triangle count of a procedural scene and reports, per structure, build\n"
            "time, steps per ray (NODE_ENTER events), primitive tests per ray and Mrays/s on\n"
            "primary rays, then the growth fitted by least squares on log-log axes.\n"
            "options:\n"
            "  --scene icosphere|grid|soup  icosphere: levels (1280 x 4^k triangles); grid: d x d\n"
            "                     quads (2 d^2); soup: random triangles of fixed size (default icosphere)\n"
            "  --accel LIST       structures (default: every registered one but brute)\n"
            "  --min-tris N       smallest size (default 1000)\n"
            "  --max-tris N       largest size (default 4200000)\n"
            "  --budget-ms MS     a structure whose build takes longer skips the larger sizes\n"
            "                     (default 20000)\n"
            "  --rays N           primary rays per size (default 20000; counters on 2000)\n"
            "  --csv FILE  --plot FILE.svg (build ms against triangles, log-log)\n");
}

/* Least squares slope and intercept of y on x. */
static int fit(const double *x, const double *y, int n, double *slope, double *icpt)
{
    if (n < 2) return 0;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i < n; ++i) {
        sx += x[i];
        sy += y[i];
        sxx += x[i] * x[i];
        sxy += x[i] * y[i];
    }
    const double den = n * sxx - sx * sx;
    if (den == 0) return 0;
    *slope = (n * sxy - sx * sy) / den;
    *icpt = (sy - *slope * sx) / n;
    return 1;
}

int bench_cmd_scale(int argc, char **argv)
{
    const char *scene = "icosphere", *accel_list = NULL, *csv = NULL, *plot = NULL;
    double min_tris = 1000, max_tris = 4200000, budget = 20000;
    size_t nrays = 20000;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            scale_usage(stdout);
            return BENCH_OK;
        }
        if (!val) {
            fprintf(stderr, "sidx-bench scale: unexpected '%s'\n", a);
            scale_usage(stderr);
            return BENCH_USAGE;
        }
        ++i;
        char *end = NULL;
        if (!strcmp(a, "--scene")) scene = val;
        else if (!strcmp(a, "--accel")) accel_list = val;
        else if (!strcmp(a, "--csv")) csv = val;
        else if (!strcmp(a, "--plot")) plot = val;
        else if (!strcmp(a, "--min-tris")) { min_tris = strtod(val, &end); if (*end || !(min_tris > 0)) goto bad; }
        else if (!strcmp(a, "--max-tris")) { max_tris = strtod(val, &end); if (*end || !(max_tris > 0)) goto bad; }
        else if (!strcmp(a, "--budget-ms")) { budget = strtod(val, &end); if (*end || !(budget > 0)) goto bad; }
        else if (!strcmp(a, "--rays")) {
            nrays = (size_t)strtoull(val, &end, 10);
            if (*end || nrays == 0 || nrays > 10000000) goto bad;
        } else {
            fprintf(stderr, "sidx-bench scale: unknown option '%s'\n", a);
            return BENCH_USAGE;
        }
        continue;
    bad:
        fprintf(stderr, "sidx-bench scale: bad value '%s' for %s\n", val, a);
        return BENCH_USAGE;
    }
    if (strcmp(scene, "icosphere") && strcmp(scene, "grid") && strcmp(scene, "soup")) {
        fprintf(stderr, "sidx-bench scale: --scene must be icosphere, grid or soup\n");
        return BENCH_USAGE;
    }
    /* the sizes: details of the scene */
    uint32_t details[32];
    int nsizes = 0;
    for (int k = 0; k < 32 && nsizes < 32; ++k) {
        double tris;
        uint32_t d;
        if (!strcmp(scene, "icosphere")) {
            d = (uint32_t)k;
            tris = 20.0 * pow(4.0, k);
        } else {
            tris = 1024.0 * pow(4.0, k);
            d = !strcmp(scene, "grid") ? (uint32_t)lround(sqrt(tris / 2)) : (uint32_t)tris;
            if (!strcmp(scene, "grid")) tris = 2.0 * d * d;
        }
        if (tris > max_tris) break;
        if (tris < min_tris) continue;
        details[nsizes] = d;
        ++nsizes;
    }
    const char *names[64];
    int na = 0;
    for (size_t i = 0; i < sidx_accel_registered_count() && na < 64; ++i) {
        const char *nm = sidx_accel_registered_name(i);
        if (accel_list ? bench_list_has(accel_list, nm) : strcmp(nm, "brute") != 0) names[na++] = nm;
    }
    if (na == 0) {
        fprintf(stderr, "sidx-bench scale: no structure selected\n");
        return BENCH_USAGE;
    }
    scale_pt *pts = calloc((size_t)na * (size_t)(nsizes ? nsizes : 1), sizeof *pts);
    int npts = 0;
    int skip[64] = {0};
    sidx_hit *hits = malloc(nrays * sizeof *hits);
    tk_rayrec *rec = malloc(nrays * sizeof *rec);
    if (!pts || !hits || !rec) {
        fprintf(stderr, "sidx-bench scale: out of memory\n");
        free(pts);
        free(hits);
        free(rec);
        return BENCH_FAIL;
    }
    bench_cpu_time = 1;
    FILE *f = stdout;
    fprintf(f, "sidx-bench scale: scene %s, %zu primary rays per size, build budget %.0f ms\n", scene, nrays, budget);
    fprintf(f, "%-14s %10s %10s %9s %8s %8s %9s\n", "accel", "tris", "build_ms", "Mrays/s", "steps", "prims", "MB");
    int rc = BENCH_OK;
    for (int si = 0; si < nsizes; ++si) {
        char spec[64];
        snprintf(spec, sizeof spec, "%s:%u", scene, details[si]);
        sidx_mesh m = {0};
        sidx_error err = {SIDX_OK, ""};
        bench_progress("scale: making %s", spec);
        if (sidx_scene_open(spec, &m, &err) != SIDX_OK) {
            bench_progress_done();
            fprintf(stderr, "sidx-bench scale: %s: %s\n", spec, err.message);
            rc = BENCH_FAIL;
            break;
        }
        tk_make_rays(&m, TK_RAYS_PRIMARY, nrays, 7, rec);
        bench_rays br;
        if (!bench_rays_prepare(rec, nrays, &br)) {
            sidx_mesh_free(&m);
            rc = BENCH_FAIL;
            break;
        }
        for (int ai = 0; ai < na; ++ai) {
            if (skip[ai]) continue;
            bench_progress("scale: %s on %u triangles", names[ai], m.num_triangles);
            sidx_accel *a = NULL;
            const double t0 = bench_build_clock_ms();
            if (sidx_accel_build(names[ai], &m, NULL, &a, &err) != SIDX_OK) {
                bench_progress_done();
                fprintf(stderr, "sidx-bench scale: %s on %s: %s\n", names[ai], spec, err.message);
                skip[ai] = 1;
                continue;
            }
            scale_pt *p = &pts[npts++];
            p->accel = ai;
            p->tris = m.num_triangles;
            p->build_ms = bench_build_clock_ms() - t0;
            double ms = 0;
            size_t done = bench_trace(a, &br, 0, nrays, NULL, 0, 1, 3000.0, hits, &ms);
            p->mrays = ms > 0 ? (double)done / (ms * 1e3) : 0;
            sidx_counters c;
            sidx_counters_init(&c);
            sidx_hook h = sidx_counters_hook(&c);
            sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &h, 0};
            const size_t nc = nrays < 2000 ? nrays : 2000;
            bench_rays sub = {br.r, br.valid, nc};
            bench_trace(a, &sub, 0, nc, &q, 0, 1, 0.0, hits, NULL);
            p->steps = (double)c.n[SIDX_EV_NODE_ENTER] / (double)nc;
            p->prims = (double)c.n[SIDX_EV_PRIM_TEST] / (double)nc;
            sidx_accel_stats st;
            sidx_accel_stats_get(a, &st);
            sidx_accel_destroy(a);
            bench_progress_done();
            fprintf(f, "%-14s %10.0f %10.2f %9.3f %8.1f %8.1f %9.2f\n", names[ai], p->tris, p->build_ms, p->mrays,
                    p->steps, p->prims, (double)st.bytes / 1048576.0);
            fflush(f);
            if (p->build_ms > budget) {
                fprintf(f, "%-14s build over budget: larger sizes skipped\n", names[ai]);
                skip[ai] = 1;
            }
        }
        bench_rays_free(&br);
        sidx_mesh_free(&m);
    }
    bench_progress_done();
    fprintf(f, "\n== growth (least squares on log-log: y ~ n^k; steps also as a + b log2 n)\n");
    fprintf(f, "%-14s %6s %10s %10s %14s %10s\n", "accel", "sizes", "build k", "steps k", "steps b/log2n",
              "prims k");
    for (int ai = 0; ai < na; ++ai) {
        double lx[32], lb[32], ls[32], lp[32], l2[32], st[32];
        int n = 0, ns = 0, np = 0;
        for (int i = 0; i < npts; ++i)
            if (pts[i].accel == ai && n < 32) {
                lx[n] = log(pts[i].tris);
                lb[n] = log(fmax(pts[i].build_ms, 1e-3));
                if (pts[i].steps > 0) { l2[ns] = log2(pts[i].tris); st[ns] = pts[i].steps; ls[ns++] = log(pts[i].steps); }
                if (pts[i].prims > 0) lp[np++] = log(pts[i].prims);
                ++n;
            }
        double kb = NAN, ks = NAN, kp = NAN, bs = NAN, c;
        fit(lx, lb, n, &kb, &c);
        if (ns == n) fit(lx, ls, ns, &ks, &c);
        if (ns >= 2) fit(l2, st, ns, &bs, &c);
        if (np == n) fit(lx, lp, np, &kp, &c);
        fprintf(f, "%-14s %6d %10.3f %10.3f %14.3f %10.3f\n", names[ai], n, kb, ks, bs, kp);
    }
    if (csv) {
        FILE *cf = fopen(csv, "w");
        if (!cf) {
            fprintf(stderr, "sidx-bench scale: %s: %s\n", csv, strerror(errno));
            rc = BENCH_FAIL;
        } else {
            fprintf(cf, "scene,accel,tris,build_ms,mrays_per_s,steps_per_ray,prims_per_ray\n");
            for (int i = 0; i < npts; ++i)
                fprintf(cf, "%s,%s,%.0f,%.3f,%.4f,%.3f,%.3f\n", scene, names[pts[i].accel], pts[i].tris,
                        pts[i].build_ms, pts[i].mrays, pts[i].steps, pts[i].prims);
            if (fclose(cf) != 0) rc = BENCH_FAIL;
        }
    }
    if (plot) {
        bench_point *bp = calloc((size_t)npts + 1, sizeof *bp);
        if (bp) {
            for (int i = 0; i < npts; ++i) {
                bp[i].x = pts[i].tris;
                bp[i].y = pts[i].build_ms;
                bp[i].label = names[pts[i].accel];
                bp[i].series = pts[i].accel;
            }
            char title[128];
            snprintf(title, sizeof title, "sidx: build time against triangle count (%s)", scene);
            if (!bench_svg_lines(plot, title, "triangles", "build ms (one thread)", bp, (size_t)npts, names, na))
                rc = BENCH_FAIL;
            free(bp);
        }
    }
    free(pts);
    free(hits);
    free(rec);
    return rc;
}
