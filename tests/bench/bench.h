/* bench.h — the pieces of sidx-bench (trace, rays, run, scale). */
#ifndef SIDX_BENCH_H
#define SIDX_BENCH_H

#include <stdint.h>
#include <stdio.h>
#include "sidx/sidx.h"
#include "../common/testkit.h"

/* Exit codes of every sub-command. */
#define BENCH_OK 0
#define BENCH_FAIL 1
#define BENCH_USAGE 2

extern const char *bench_argv0; /* path of this executable (for the no-hooks twin) */
/* 1: single-threaded traces and builds are timed in CPU time of the thread
 * (process for builds), not wall-clock, so other load on the machine does
 * not count (run and scale set it; trace keeps wall-clock). */
extern int bench_cpu_time;
double bench_clock_ms(void);       /* trace clock: thread CPU time or wall-clock */
double bench_build_clock_ms(void); /* build clock: process CPU time or wall-clock */

/* Rays prepared once for tracing (sidx_ray_init outside the timed loop).
 * A record sidx_ray_init rejects (zero direction, NaN, tmin > tmax) stays
 * invalid and always misses. */
typedef struct bench_rays {
    sidx_ray *r;
    uint8_t *valid;
    size_t n;
} bench_rays;
int bench_rays_prepare(const tk_rayrec *rec, size_t n, bench_rays *out); /* 0 on out of memory */
void bench_rays_free(bench_rays *br);

/* Traces rays[begin, end) into hits with `threads` pthreads (0/1 = the
 * calling thread).  any_hit: hits[i].prim = 0 for occluded, SIDX_NO_HIT
 * otherwise.  Stops early (single thread only) once budget_ms is spent,
 * when budget_ms > 0; returns the number of rays traced and the elapsed
 * milliseconds in *ms. */
size_t bench_trace(const sidx_accel *a, const bench_rays *br, size_t begin, size_t end, const sidx_query *q,
                   int any_hit, unsigned threads, double budget_ms, sidx_hit *hits, double *ms);

/* How every traced row is timed (bench_time_passes): one cold pass (the
 * first one: caches cold, and the pages of a fresh hit array faulted in by
 * its writes), then every buffer touched (the hit array written, the rays
 * read), then up to `passes` warm passes; the figure a row reports is the
 * best warm pass, the median is printed beside it, the cold pass apart. */
#define BENCH_PASSES 5 /* default warm passes */
typedef struct bench_timing {
    double cold_ms;   /* the first pass */
    double best_ms;   /* the fastest warm pass */
    double median_ms; /* the median warm pass */
    int passes;       /* warm passes timed (>= 1) */
} bench_timing;
/* A buffer to touch before the warm passes: write = 1 for an output (each
 * page written, its contents kept), 0 for an input (each page read). */
typedef struct bench_buf {
    const void *p;
    size_t bytes;
    int write;
} bench_buf;
void bench_touch(const bench_buf *bufs, int nbufs);
/* pass(ctx, cold) runs one pass and returns its milliseconds (cold = 1 for
 * the first).  Warm passes stop early once they have spent budget_ms
 * (budget_ms <= 0: no limit); at least one always runs. */
void bench_time_passes(double (*pass)(void *ctx, int cold), void *ctx, const bench_buf *bufs, int nbufs,
                       int passes, double budget_ms, bench_timing *out);
/* Mrays/s of rays traced in ms (0 when ms <= 0). */
double bench_mrays(size_t rays, double ms);
/* bench_trace timed the bench_time_passes way (one thread or several,
 * every ray of [begin, end), no budget per pass). */
void bench_trace_timed(const sidx_accel *a, const bench_rays *br, size_t begin, size_t end, const sidx_query *q,
                       int any_hit, unsigned threads, int passes, double budget_ms, sidx_hit *hits, bench_timing *t);

/* Embree 3 as the peer. */
typedef struct bench_embree bench_embree;
typedef struct bench_embree_cfg {
    int robust;  /* RTC_SCENE_FLAG_ROBUST */
    int quality; /* RTC_BUILD_QUALITY_LOW/MEDIUM/HIGH = 0/1/2 */
} bench_embree_cfg;
/* Parses "embree", "embree-robust", "embree-hq", "embree-robust-hq"; 1 if it is one. */
int bench_embree_parse(const char *name, bench_embree_cfg *cfg);
int bench_embree_build(const sidx_mesh *m, bench_embree_cfg cfg, bench_embree **out, double *build_ms, char *msg,
                       size_t msg_size);
/* The same on a "threads=N" device, build timed in wall-clock (parallel-build comparison). */
int bench_embree_build_threads(const sidx_mesh *m, bench_embree_cfg cfg, unsigned threads, bench_embree **out,
                               double *build_ms, char *msg, size_t msg_size);
size_t bench_embree_bytes(const bench_embree *e);
/* rtcIntersect1 / rtcOccluded1, one thread; packet = 1, 4, 8 or 16
 * (rtcIntersectN).  Returns elapsed ms.  u, v and ng are filled. */
double bench_embree_trace(bench_embree *e, const tk_rayrec *rays, size_t n, int any_hit, int packet, sidx_hit *hits);
/* The same timed the bench_time_passes way. */
void bench_embree_trace_timed(bench_embree *e, const tk_rayrec *rays, size_t n, int any_hit, int packet, int passes,
                              double budget_ms, sidx_hit *hits, bench_timing *t);
/* rtcIntersect1M / rtcOccluded1M over the buffer (embree.c); scratch holds
 * n * bench_embree_stream_scratch() bytes, 16-byte aligned. */
double bench_embree_trace_stream(bench_embree *e, const tk_rayrec *rays, size_t n, int any_hit, int coherent,
                                 void *scratch, sidx_hit *hits);
size_t bench_embree_stream_scratch(void);
void bench_embree_free(bench_embree *e);
const char *bench_embree_version(void);

/* A tiny SVG scatter plot. */
typedef struct bench_point {
    double x, y;
    const char *label; /* tooltip; also drawn next to the marker when show_label */
    int series;        /* colour index */
    int shape;         /* scatter: 0 circle, 1 square, 2 triangle */
    int hollow;        /* scatter: outline only */
    int show_label;
} bench_point;
int bench_svg_scatter(const char *path, const char *title, const char *xlabel, const char *ylabel, int xlog,
                      int ylog, const bench_point *pts, size_t n, const char *const *series_names, int nseries,
                      const char *const *shape_names, int nshapes);
/* Line plot: one polyline per series (points sorted by x within series). */
int bench_svg_lines(const char *path, const char *title, const char *xlabel, const char *ylabel,
                    const bench_point *pts, size_t n, const char *const *series_names, int nseries);

/* `sidx-bench run`'s targets section (targets.c): bvh >= 0.5x Embree,
 * kdtree >= 0.8x bvh, bvh8 >= 1.0x Embree on the listed scenes, primary and
 * diffuse rays, in interleaved rounds.  Writes CSV-targets.csv when csv is
 * set, and the bench:targets block to md when md is set.  Returns 0 when
 * the CSV could not be written; a FAIL verdict is reported, not returned
 * (speed depends on the machine). */
typedef struct bench_targets_opts {
    const char *scenes_dir;  /* NAME.obj/.ply, else NAME*.obj/.ply, looked up here; NULL: built-in scenes only */
    const char *scene_list;  /* comma-separated, e.g. "bunny,sponza" */
    const char *accel_list;  /* run's --accel (NULL = all): a target needs both its sides */
    const char *csv;         /* run's --csv, or NULL */
    int embree;              /* 0: --no-embree, targets against Embree skipped */
    int rounds;
    size_t rays;
    uint64_t seed;
    FILE *md;                /* run's --markdown file, or NULL */
    const char *md_caption;  /* date, machine and command, opening the Markdown block */
} bench_targets_opts;
int bench_targets(FILE *f, const bench_targets_opts *o);

/* Sub-commands. */
int bench_cmd_trace(int argc, char **argv);
int bench_cmd_rays(int argc, char **argv);
int bench_cmd_run(int argc, char **argv);
int bench_cmd_scale(int argc, char **argv);
int bench_cmd_lazy(int argc, char **argv);
int bench_cmd_stream(int argc, char **argv); /* stream.c */
int bench_cmd_extras(int argc, char **argv); /* extras.c */

/* The memory of a build (mem.c).  bench_mem_begin just before the build,
 * bench_mem_end just after: bytes the resident set rose above its level
 * at begin, at its peak during the build (-1: not measurable here, needs
 * Linux's /proc/self/clear_refs). */
typedef struct bench_mem {
    long long base; /* resident bytes at begin; -1 = not measurable */
} bench_mem;
void bench_mem_begin(bench_mem *m);
long long bench_mem_end(const bench_mem *m);
/* A counting allocator for sidx_build_options.alloc: peak = the most bytes
 * live at once through it (the build's heap peak). */
typedef struct bench_heap {
    _Atomic size_t live, peak;
} bench_heap;
sidx_allocator bench_heap_allocator(bench_heap *h);
/* The mesh's positions and indices, the bytes every build starts from. */
size_t bench_mesh_bytes(const sidx_mesh *m);

/* Comma-separated list helpers. */
int bench_list_has(const char *list, const char *name); /* NULL list = everything */
int bench_progress_enabled(void);                        /* stderr is a terminal */
void bench_progress(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
void bench_progress_done(void);

#endif
