/* testkit.h — what the test suites and sidx-bench share (no cmocka here).
 *
 *  - a deterministic PRNG (splitmix64 seeding xoshiro256**), never rand();
 *  - the ray and hit files of sidx-bench: little-endian records of
 *    8 float32 (ox oy oz dx dy dz tmin tmax) and of 16 bytes
 *    (float32 t, int32 prim, float32 u, float32 v; miss = +inf, -1, 0, 0);
 *  - the ray sets of the benchmark (primary, diffuse, shadow, grazing, axis);
 *  - the reference: a double-precision watertight brute-force tracer;
 *  - the comparison rule every suite uses: two closest hits agree when both
 *    miss, or both hit and (same primitive, or |t - t_ref| <= 1e-5·max(1,|t|),
 *    i.e. coincident surfaces);
 *  - mesh helpers (transformed copies, meshes from literal arrays).
 *
 * tests/common/ is linked into every suite; tests/bench/kit.c compiles this
 * same file into sidx-bench. */
#ifndef SIDX_TESTKIT_H
#define SIDX_TESTKIT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "sidx/sidx.h"

/* ---- PRNG ---------------------------------------------------------------- */

typedef struct tk_rng { uint64_t s[4]; } tk_rng;
uint64_t tk_splitmix64(uint64_t *state);
void tk_rng_seed(tk_rng *r, uint64_t seed);
uint64_t tk_rng_next(tk_rng *r);
double tk_rng_unit(tk_rng *r);                /* [0, 1), 53 bits */
double tk_rng_range(tk_rng *r, double lo, double hi);
uint32_t tk_rng_below(tk_rng *r, uint32_t n); /* [0, n), n > 0 */
sidx_vec3 tk_rng_sphere(tk_rng *r);           /* uniform unit vector */
sidx_vec3 tk_rng_in_box(tk_rng *r, sidx_aabb b); /* uniform point of b (z drawn first, then y, x) */

/* ---- ray and hit files --------------------------------------------------- */

typedef struct tk_rayrec { float o[3], d[3], tmin, tmax; } tk_rayrec; /* 32 bytes on disk */
typedef struct tk_hitrec { float t; int32_t prim; float u, v; } tk_hitrec; /* 16 bytes on disk */
/* TK_UNDER_ASAN: 1 in a build with AddressSanitizer (gcc or clang), where
 * some checks read ASan's own report instead of the program's message. */
#if defined(__SANITIZE_ADDRESS__)
#define TK_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TK_UNDER_ASAN 1
#endif
#endif
#ifndef TK_UNDER_ASAN
#define TK_UNDER_ASAN 0
#endif

#define TK_RAY_BYTES 32u
#define TK_HIT_BYTES 16u

/* Read a whole file of records.  SIDX_ERR_IO if it cannot be read,
 * SIDX_ERR_PARSE if its size is not a multiple of the record size, or (hit
 * files) a record is not one a tracer writes: prim < -1, a miss (prim -1)
 * whose t is not +inf, a hit whose t is NaN.  Ray records are taken as they
 * are (tk_ray_from refuses unusable rays one by one).  On
 * success *out is malloc'ed (NULL when the file is empty) and *n set. */
sidx_status tk_read_rays(const char *path, tk_rayrec **out, size_t *n, sidx_error *err);
sidx_status tk_read_hits(const char *path, tk_hitrec **out, size_t *n, sidx_error *err);
/* The same from memory (for the reader tests). */
sidx_status tk_parse_rays(const void *data, size_t size, tk_rayrec **out, size_t *n, sidx_error *err);
sidx_status tk_parse_hits(const void *data, size_t size, tk_hitrec **out, size_t *n, sidx_error *err);
sidx_status tk_write_rays(const char *path, const tk_rayrec *r, size_t n, sidx_error *err);
sidx_status tk_write_hits(const char *path, const tk_hitrec *h, size_t n, sidx_error *err);

tk_hitrec tk_hitrec_from(const sidx_hit *h); /* miss -> (+inf, -1, 0, 0) */
tk_rayrec tk_rayrec_make(sidx_vec3 o, sidx_vec3 d, float tmin, float tmax);
/* sidx_ray_init on a record; SIDX_ERR_INVALID_ARG for an unusable ray. */
sidx_status tk_ray_from(const tk_rayrec *rec, sidx_ray *r);
/* 1 when h is a hit within float resolution of the ray's origin: at a
 * distance t · max|d| of at most 2^-20 (max|o| + scale), scale the size of
 * the scene.  The triangle tests' t is rounding there (an origin on a
 * surface, to float precision), so a structure may report that hit or
 * the next one; the fuzz oracles trace such rays but do not compare them
 * (docs/errors.md). */
int tk_hit_at_start(const sidx_hit *h, const sidx_ray *r, float scale);

/* ---- ray sets ------------------------------------------------------------- */

typedef enum tk_ray_kind {
    TK_RAYS_PRIMARY = 0, /* pinhole camera outside the scene box looking at its centre, image rows */
    TK_RAYS_DIFFUSE,     /* random origins inside the box, uniform random directions */
    TK_RAYS_SHADOW,      /* segments p1 -> p2 between random surface points, t in [eps, 1 - eps] */
    TK_RAYS_GRAZING,     /* aimed exactly at vertices and edge points; nearly parallel to triangles */
    TK_RAYS_AXIS,        /* axis-parallel directions with exact ±0 components */
    TK_RAYS_KIND_COUNT
} tk_ray_kind;
const char *tk_ray_kind_name(tk_ray_kind k);
int tk_ray_kind_parse(const char *name, tk_ray_kind *out); /* 1 on success */

/* Fill out[0..count) with rays of `kind` for mesh m (deterministic in seed).
 * A mesh without triangles falls back to diffuse rays. */
void tk_make_rays(const sidx_mesh *m, tk_ray_kind kind, size_t count, uint64_t seed, tk_rayrec *out);

/* Rays from `inside` aimed exactly at every edge midpoint and vertex of m
 * (up to max rays; returns how many were written).  For a closed mesh
 * around `inside` every one of them must hit. */
size_t tk_make_leak_rays(const sidx_mesh *m, sidx_vec3 inside, size_t max, tk_rayrec *out);

/* ---- reference ------------------------------------------------------------ */

/* The true closest hit in double precision: watertight (Woop et al. 2013)
 * with every step in double, hits in [tmin, tmax), ties to the lowest index.
 * prim = SIDX_NO_HIT and t = +inf on a miss; u, v are always filled. */
void tk_ref_intersect(const sidx_mesh *m, const tk_rayrec *ray, sidx_hit *out);
/* The same for every ray, split over `threads` pthreads (0 or 1 = this one). */
void tk_ref_intersect_all(const sidx_mesh *m, const tk_rayrec *rays, size_t n, sidx_hit *out, unsigned threads);

/* Threads racing into one structure: `threads` pthreads (at most 64) meet
 * at a barrier, then each traces rays[0, n) with sidx_accel_intersect into
 * hits + t * n.  SIDX_OK when every query of every thread returned it, else
 * the first other status (a thread that could not start: SIDX_ERR_NOMEM). */
sidx_status tk_race_intersect(const sidx_accel *a, const sidx_ray *rays, size_t n, unsigned threads, sidx_hit *hits);

/* ---- comparison ----------------------------------------------------------- */

#define TK_T_TOL 1e-5
/* The suites' rule: both miss, or both hit and (same prim or
 * |t - t_ref| <= TK_T_TOL·max(1, |t_ref|)). */
int tk_hits_agree(const sidx_hit *ref, const sidx_hit *got);
/* The same with the tolerance's floor given: |Δt| <= TK_T_TOL·max(t_floor, |t_ref|). */
int tk_hits_agree_scaled(const sidx_hit *ref, const sidx_hit *got, double t_floor);

/* Error against the reference, accumulated over rays. */
typedef struct tk_errstats {
    uint64_t rays;
    uint64_t false_miss;  /* reference hits, tested structure misses */
    uint64_t false_hit;   /* reference misses, tested structure hits */
    uint64_t wrong_prim;  /* both hit, different prim, t beyond tolerance */
    double max_rel_t;     /* max |t - t_ref| / max(1, |t_ref|) over rays hitting the same prim
                             (as the tolerance rule: ray sets put the scene at t ~ 1) */
} tk_errstats;
void tk_errstats_add(tk_errstats *e, const sidx_hit *ref, const sidx_hit *got);
uint64_t tk_errstats_errors(const tk_errstats *e);
double tk_errstats_rate(const tk_errstats *e);

/* ---- meshes ---------------------------------------------------------------- */

/* *out = (m · scale) + offset, a new mesh (free with sidx_mesh_free). */
sidx_status tk_mesh_transform(const sidx_mesh *m, double scale, sidx_vec3 offset, sidx_mesh *out);
/* m followed by a copy of its own triangles (coincident duplicates). */
sidx_status tk_mesh_duplicate_tris(const sidx_mesh *m, sidx_mesh *out);
/* Every vertex projected onto z = z0 (a flat scene). */
sidx_status tk_mesh_flatten(const sidx_mesh *m, float z0, sidx_mesh *out);

/* The programs' directory beside a suite's: BUILD/tests/NAME (argv0)
 * gives BUILD/bin in out; out is kept when argv0 names no directory. */
void tk_bin_dir(const char *argv0, char *out, size_t size);

/* 1 when the environment asks for fast tests (SIDX_FAST_TESTS=1: make test
 * SAN=1; 2: valgrind, ThreadSanitizer and every build but make test's in
 * .ci/run). */
int tk_fast_tests(void);
/* 1 when it asks for the smallest sizes (SIDX_FAST_TESTS=2, make valgrind:
 * memcheck runs every instruction some 40 times slower, and looks for
 * memory faults, which a few rays through each path find as well as many;
 * the same holds for the sanitizers; the clang and minimal builds of
 * .ci/run, which the full gcc run leaves only another compiler and
 * another configuration to find). */
int tk_tiny_tests(void);
/* 1 under valgrind (its preloaded libraries are in LD_PRELOAD): the few
 * builds that take minutes under memcheck are left out there, and kept at
 * every size elsewhere (the ASan run builds them). */
int tk_under_valgrind(void);
/* A count of rays (or cases) at the sizes asked for: full, a quarter of it
 * (fast), a sixteenth (tiny), rounded up. */
size_t tk_test_size(size_t full);
/* Monotonic wall-clock time in milliseconds. */
double tk_now_ms(void);
/* CPU time of the calling thread / of the whole process, in milliseconds:
 * what a single-threaded measurement should use on a shared, busy machine. */
double tk_thread_cpu_ms(void);
double tk_process_cpu_ms(void);

/* An allocator that succeeds `left` times, then fails every call, and
 * counts the blocks still live: for out-of-memory tests.
 *   tk_failing f = {k, 0};
 *   sidx_allocator al = tk_failing_allocator(&f); */
typedef struct tk_failing { long left; long live; } tk_failing;
sidx_allocator tk_failing_allocator(tk_failing *f);

/* Reads f to its end into a malloc'd, NUL-terminated string; NULL when
 * memory runs out.  The caller frees it (and closes f). */
char *tk_read_all(FILE *f);

#endif
