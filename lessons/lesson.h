/* lesson.h — what every lesson does the same way: its command line, its
 * scene and its CHECK lines, so that a lesson's main reads parse, open,
 * build, show, check:
 *
 *     int main(int argc, char **argv)
 *     {
 *         lesson_args args = {.name = "07_uniform_grid", .usage = usage, .scene = "teapot"};
 *         lesson_parse(&args, argc, argv);
 *         lesson_need(&args, "grid");
 *         sidx_mesh mesh = lesson_open_scene(&args);
 *         ... build, show ...
 *         lesson_check("mailbox_saves_tests", saved);
 *     }
 *
 * lesson_parse       -h or --help: args.usage(stdout), exit 0.  One SCENE
 *                    argument (a built-in scene, "teapot" or "name:detail",
 *                    or an .obj/.ply file) replaces args.scene and sets
 *                    args.scene_given; with args.scene_flag set (the tour's
 *                    "--scene") SCENE is that option's value instead.  An
 *                    option not in args.options, a bad option value or a
 *                    second SCENE: one line and the usage on stderr, exit 2.
 * lesson_need        the structure is not registered in this build: exit 1.
 * lesson_open_scene  loads args.scene (lesson_open: any other scene); one
 *                    that cannot be loaded or has no triangles: exit 1.
 * lesson_fail        "NAME: message" on stderr, exit 1.
 * lesson_check       prints "CHECK name=value", the lines tests/run_lessons.sh
 *                    compares with what the lesson must find.
 *
 * Options are one table entry each, naming the field the option fills;
 * the build knobs below fill a sidx_build_options the lesson then builds
 * with.  Untouched fields stay 0, which is every structure's default, so
 * a run without options is the run without the table:
 *
 *     sidx_build_options knobs = {0};
 *     const lesson_option options[] = {LESSON_BINS(knobs), LESSON_NO_MAILBOX(knobs), {0}};
 *     lesson_args args = {.name = ..., .usage = ..., .scene = ..., .options = options};
 *
 * LESSON_KNOBS(knobs) is all eight.  The knobs are the programs' own
 * (sidx_viz_build_knob, sidx/viz.h: the same flags, values and messages
 * as sidx-step, sidx-dot and sidx-view).  Every lesson knows all eight:
 * --help ends with the lines of those its table takes, and a knob it does
 * not take is refused (exit 2) with a line saying the lesson builds with
 * the defaults (or args.refused: why, in one line), rather than reported
 * as an unknown option.  The lesson's
 * usage text says what a knob changes in what the lesson builds; its CHECK
 * lines are only asserted with the defaults.
 *
 * Shared measuring helpers (the later lessons use them):
 * lesson_seconds     wall clock, for printed times (never checked)
 * lesson_random      a reproducible uniform number in [0, 1)
 * lesson_rays_into_box  random rays from around a box into it
 * lesson_count_rays  the events of closest-hit queries, counted, and their hits
 * lesson_us_per_ray  best-of-N microseconds per untraced query
 * lesson_camera_*    a pinhole camera looking at a box, and its image's rays
 * lesson_partition11 the eleven triangles of deck 001 "Building Partitions
 *                    Example" (lessons 03 and 04)
 */
#ifndef LESSON_H
#define LESSON_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"

/* One option and the one field it fills: exactly one pointer is set. */
typedef struct lesson_option {
    const char *flag;          /* "--bins"; NULL ends the table */
    uint32_t *count;           /* --flag N: a whole number >= 1 */
    float *number;             /* --flag X: a finite number >= 0 */
    int *on;                   /* --flag: sets it to 1 */
    const char **text;         /* --flag S: the string itself */
    sidx_build_options *build; /* a build knob: the field sidx_viz_build_knob fills for flag */
} lesson_option;

/* The build knobs, each filling one field of the sidx_build_options b. */
#define LESSON_BINS(b) {"--bins", .build = &(b)}
#define LESSON_C_TRAV(b) {"--c-trav", .build = &(b)}
#define LESSON_C_TRI(b) {"--c-tri", .build = &(b)}
#define LESSON_LEAF_SIZE(b) {"--leaf-size", .build = &(b)}
#define LESSON_MAX_DEPTH(b) {"--max-depth", .build = &(b)}
#define LESSON_LAMBDA(b) {"--lambda", .build = &(b)}
#define LESSON_NO_MAILBOX(b) {"--no-mailbox", .build = &(b)}
#define LESSON_EMPTY_BONUS(b) {"--empty-bonus", .build = &(b)}
/* The five a BVH reads (the lessons that build only BVHs take these). */
#define LESSON_BVH_KNOBS(b)                                                                                  \
    LESSON_BINS(b), LESSON_C_TRAV(b), LESSON_C_TRI(b), LESSON_LEAF_SIZE(b), LESSON_MAX_DEPTH(b)
#define LESSON_BVH_ONLY "no grid or kd-tree is built here, only BVHs" /* their args.refused */
#define LESSON_KNOBS(b)                                                                                      \
    LESSON_BINS(b), LESSON_C_TRAV(b), LESSON_C_TRI(b), LESSON_LEAF_SIZE(b), LESSON_MAX_DEPTH(b),             \
        LESSON_LAMBDA(b), LESSON_NO_MAILBOX(b), LESSON_EMPTY_BONUS(b)

typedef struct lesson_args {
    const char *name;             /* the program's name: every message starts with it */
    void (*usage)(FILE *f);       /* prints the --help text */
    const char *scene;            /* the default scene (NULL: the lesson makes its own), then the one to use */
    const char *scene_flag;       /* NULL: SCENE is a plain argument; else the option that takes it */
    const lesson_option *options; /* NULL, or a table ended by {0} */
    const char *refused;          /* NULL, or one line: why the knobs not in options are refused */
    int scene_given;              /* set by lesson_parse: SCENE was on the command line */
} lesson_args;

static inline _Noreturn void lesson_fail(const lesson_args *a, const char *message)
{
    fprintf(stderr, "%s: %s\n", a->name, message);
    exit(1);
}

/* A command line the lesson cannot run: say what, show the usage, exit 2. */
static inline _Noreturn void lesson__usage_error(const lesson_args *a, const char *what, const char *arg)
{
    fprintf(stderr, "%s: %s '%s'\n", a->name, what, arg);
    a->usage(stderr);
    exit(2);
}

/* The value after option argv[*i]; moves *i onto it. */
static inline const char *lesson__value(const lesson_args *a, int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) lesson__usage_error(a, "missing value after", argv[*i]);
    return argv[++*i];
}

/* A build knob from table entry o: how many arguments after the flag it
 * took (0 or 1), or exit 2 saying what it wants. */
static inline int lesson__knob(const lesson_args *a, const lesson_option *o, const char *value)
{
    char msg[160];
    const int took = sidx_viz_build_knob(o->flag, value, o->build, msg, sizeof msg);
    if (took == 0) lesson__usage_error(a, "the option table names no build knob", o->flag);
    if (took < 0) {
        fprintf(stderr, "%s: %s\n", a->name, msg);
        a->usage(stderr);
        exit(2);
    }
    return took - 1;
}

/* Fills the option's field from value, or exits 2 saying what it wants. */
static inline void lesson__set(const lesson_args *a, const lesson_option *o, const char *value)
{
    char *end = NULL;
    char what[96];
    if (o->text) {
        *o->text = value;
        return;
    }

    if (o->count) {
        const unsigned long long n = value[0] >= '0' && value[0] <= '9' ? strtoull(value, &end, 10) : 0;
        if (end && !*end && n >= 1 && n <= UINT32_MAX) {
            *o->count = (uint32_t)n;
            return;
        }
        snprintf(what, sizeof what, "%s wants a whole number >= 1, not", o->flag);
    } else {
        const float x = strtof(value, &end);
        if (end != value && !*end && isfinite(x) && x >= 0.0f) {
            *o->number = x;
            return;
        }
        snprintf(what, sizeof what, "%s wants a number >= 0, not", o->flag);
    }
    lesson__usage_error(a, what, value);
}

static inline const lesson_option *lesson__find(const lesson_args *a, const char *flag)
{
    const lesson_option *o = a->options;
    while (o && o->flag && strcmp(o->flag, flag)) ++o;
    return o && o->flag ? o : NULL;
}

/* After the lesson's usage: the help lines of the knobs it takes, or one
 * line saying it takes none. */
static inline void lesson__knobs_help(const lesson_args *a, FILE *f)
{
    const char *p = sidx_viz_build_knobs_help();
    int taken = 0;
    for (const char *line = strstr(p, "\n  --"); line; line = strstr(line + 1, "\n  --")) {
        char flag[32];
        if (sscanf(line + 3, "%31s", flag) != 1) continue;
        const lesson_option *o = lesson__find(a, flag);
        if (!o || !o->build) continue;
        if (!taken++) fprintf(f, "\nbuild knobs (left out = the structure's default):\n");
        fprintf(f, "%.*s\n", (int)strcspn(line + 1, "\n"), line + 1);
    }
    if (!taken && a->refused)
        fprintf(f, "\nThe build knobs of sidx-step (--bins, --c-trav, --c-tri, --leaf-size, --max-depth,\n"
                   "--lambda, --no-mailbox, --empty-bonus) are refused:\n  %s.\n", a->refused);
    else if (!taken)
        fprintf(f, "\nThe build knobs of sidx-step (--bins, --c-trav, --c-tri, --leaf-size, --max-depth,\n"
                   "--lambda, --no-mailbox, --empty-bonus) are refused: this lesson builds with the\n"
                   "defaults its figures are about.\n");
    else if (a->refused)
        fprintf(f, "The other build knobs are refused:\n  %s.\n", a->refused);
}

static inline void lesson_parse(lesson_args *a, int argc, char **argv)
{
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
            a->usage(stdout);
            lesson__knobs_help(a, stdout);
            exit(0);
        }
        if (a->scene_flag ? !strcmp(arg, a->scene_flag) : arg[0] != '-') {
            if (a->scene_given && !a->scene_flag) lesson__usage_error(a, "unexpected argument", arg);
            a->scene = a->scene_flag ? lesson__value(a, argc, argv, &i) : arg;
            a->scene_given = 1;
            continue;
        }
        const lesson_option *o = lesson__find(a, arg);
        if (!o) {
            sidx_build_options scratch = {0};
            if (sidx_viz_build_knob(arg, NULL, &scratch, NULL, 0) != 0) {
                int takes = 0;
                for (const lesson_option *k = a->options; k && k->flag; ++k) takes |= k->build != NULL;
                if (a->refused) fprintf(stderr, "%s: this lesson takes no %s: %s\n", a->name, arg, a->refused);
                else
                    fprintf(stderr,
                            takes ? "%s: this lesson takes no %s (--help lists the knobs it takes)\n"
                                  : "%s: this lesson builds with the default knobs and takes no %s\n",
                            a->name, arg);
                exit(2);
            }
            lesson__usage_error(a, "unexpected argument", arg);
        }
        if (o->build) i += lesson__knob(a, o, i + 1 < argc ? argv[i + 1] : NULL);
        else if (o->on) *o->on = 1;
        else lesson__set(a, o, lesson__value(a, argc, argv, &i));
    }
}

static inline void lesson_need(const lesson_args *a, const char *accel)
{
    if (sidx_accel_is_registered(accel)) return;
    fprintf(stderr, "%s: structure '%s' is not registered in this build\n", a->name, accel);
    exit(1);
}

static inline sidx_mesh lesson_open(const lesson_args *a, const char *spec)
{
    sidx_mesh mesh;
    sidx_error err = {0};
    memset(&mesh, 0, sizeof mesh);
    if (sidx_scene_open(spec, &mesh, &err) != SIDX_OK) lesson_fail(a, err.message);
    if (mesh.num_triangles == 0) {
        fprintf(stderr, "%s: scene '%s' has no triangles\n", a->name, spec);
        sidx_mesh_free(&mesh);
        exit(1);
    }
    return mesh;
}

static inline sidx_mesh lesson_open_scene(const lesson_args *a) { return lesson_open(a, a->scene); }

static inline void lesson_check(const char *name, long value) { printf("CHECK %s=%ld\n", name, value); }

/* ---- shared by the later lessons: clock, random rays, counted work ---- */

/* Wall-clock seconds (CLOCK_MONOTONIC); times are printed, never checked. */
static inline double lesson_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A uniform number in [0, 1) from a 32-bit LCG: the same sequence on every
 * machine, so the lessons' counts are reproducible. */
static inline float lesson_random(uint32_t *seed)
{
    *seed = *seed * 1664525u + 1013904223u;
    return (float)(*seed >> 8) / 16777216.0f;
}

/* n rays from random points on the sphere around box (radius = its
 * diagonal) to random points inside it: "ordinary" rays that all cross
 * the scene, from every direction. */
static inline void lesson_rays_into_box(sidx_aabb box, sidx_ray *rays, size_t n, uint32_t seed)
{
    const sidx_vec3 ext = sidx_aabb_extent(box), ctr = sidx_aabb_centroid(box);
    const float R = sidx_v3_length(ext);
    for (size_t i = 0; i < n; ++i) {
        float f[5];
        for (int j = 0; j < 5; ++j) f[j] = lesson_random(&seed);
        const float z = 2 * f[0] - 1, ang = 6.2831853f * f[1], s = sqrtf(1 - z * z);
        const sidx_vec3 o = sidx_v3_add(ctr, sidx_v3(R * s * cosf(ang), R * s * sinf(ang), R * z));
        const sidx_vec3 t = sidx_v3(box.min.x + f[2] * ext.x, box.min.y + f[3] * ext.y, box.min.z + f[4] * ext.z);
        sidx_ray_init(&rays[i], o, sidx_v3_sub(t, o), 0.0f, INFINITY);
    }
}

/* A pinhole camera at box centre + R (ex, ey, ez), R = the box's
 * diagonal, looking at the centre, y up.  Every ray starts at the eye, so
 * the rays of an image tile lie inside the pyramid of its corner rays. */
typedef struct lesson_camera {
    sidx_vec3 eye, fwd, right, up;
} lesson_camera;

static inline lesson_camera lesson_camera_at(sidx_aabb box, float ex, float ey, float ez)
{
    const sidx_vec3 ctr = sidx_aabb_centroid(box);
    const float R = sidx_v3_length(sidx_aabb_extent(box));
    lesson_camera c;
    c.eye = sidx_v3(ctr.x + ex * R, ctr.y + ey * R, ctr.z + ez * R);
    c.fwd = sidx_v3_scale(sidx_v3_sub(ctr, c.eye), 1.0f / sidx_v3_length(sidx_v3_sub(ctr, c.eye)));
    c.right = sidx_v3_cross(c.fwd, sidx_v3(0, 1, 0));
    c.right = sidx_v3_scale(c.right, 1.0f / sidx_v3_length(c.right));
    c.up = sidx_v3_cross(c.right, c.fwd);
    return c;
}

/* The direction through screen point (u, v): u to the right, v up. */
static inline sidx_vec3 lesson_camera_dir(const lesson_camera *c, float u, float v)
{
    return sidx_v3_add(c->fwd, sidx_v3_add(sidx_v3_scale(c->right, u), sidx_v3_scale(c->up, v)));
}

/* A w x h image, row by row, through the pixel centres; the screen spans
 * u in [-su, su], v in [-sv, sv]. */
static inline void lesson_camera_rays(const lesson_camera *c, int w, int h, float su, float sv, sidx_ray *rays)
{
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float u = (2.0f * ((float)x + 0.5f) / (float)w - 1.0f) * su;
            const float v = (1.0f - 2.0f * ((float)y + 0.5f) / (float)h) * sv;
            sidx_ray_init(&rays[y * w + x], c->eye, lesson_camera_dir(c, u, v), 0.0f, INFINITY);
        }
}

/* The events of n closest-hit queries, counted (c) and their hits (hits,
 * may be NULL). */
static inline void lesson_count_rays(const sidx_accel *a, const sidx_ray *rays, size_t n, sidx_counters *c,
                                     sidx_hit *hits)
{
    sidx_counters_init(c);
    const sidx_hook h = sidx_counters_hook(c);
    for (size_t i = 0; i < n; ++i) {
        const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &h, (uint32_t)i};
        sidx_hit hit;
        sidx_accel_intersect(a, &rays[i], &q, &hit);
        if (hits) hits[i] = hit;
    }
}

/* Best of `passes` untraced passes over the rays: microseconds per ray. */
static inline double lesson_us_per_ray(const sidx_accel *a, const sidx_ray *rays, size_t n, int passes)
{
    double best = INFINITY;
    for (int p = 0; p < passes; ++p) {
        const double t0 = lesson_seconds();
        for (size_t i = 0; i < n; ++i) {
            sidx_hit hit;
            sidx_accel_intersect(a, &rays[i], NULL, &hit);
        }
        const double dt = lesson_seconds() - t0;
        if (dt < best) best = dt;
    }
    return 1e6 * best / (double)n;
}

/* ---- the slides' eleven primitives ---- */

/* Deck 001 "Building Partitions Example": eleven triangles in z = 0 whose
 * binned SAH candidates (4 bins per axis, 3 planes) have the slide's counts
 * and normalised areas (child box area / parent box area) to 2 decimals:
 *   x: 3|8 (0.15, 0.87)  6|5 (0.38, 0.43)  9|2 (0.81, 0.18)
 *   y: 3|8 (0.19, 0.91)  6|5 (0.32, 0.36)  9|2 (0.94, 0.13)
 * Each row is a triangle's box x0 x1 y0 y1 in tenths (the areas' ratios do
 * not depend on the unit); the triangle is (x0, y0) (x1, y0) (mid x, y1),
 * so its bounding box is exactly that box and its centroid the box centre.  The thin ones
 * stand for the slide's long shapes.  The boxes were found by a search for
 * the twelve numbers, then snapped to whole tenths.  Lesson 03 recomputes the
 * numbers from the build's events and checks them against the slide. */
static inline sidx_status lesson_partition11(sidx_mesh *out, sidx_error *err)
{
    static const short box[11][4] = {
        {78, 176, 198, 262}, {0, 1, 24, 187}, {46, 47, 154, 246}, {5, 29, 49, 66},
        {148, 219, 256, 262}, {105, 119, 102, 120}, {35, 83, 41, 129}, {163, 265, 156, 203},
        {54, 84, 96, 184}, {34, 107, 0, 84}, {97, 215, 148, 238},
    };
    float xyz[11 * 9];
    uint32_t idx[33];
    for (int i = 0; i < 11; ++i) {
        const float x0 = 0.1f * box[i][0], x1 = 0.1f * box[i][1], y0 = 0.1f * box[i][2], y1 = 0.1f * box[i][3];
        const float v[9] = {x0, y0, 0.0f, x1, y0, 0.0f, 0.5f * (x0 + x1), y1, 0.0f};
        for (int k = 0; k < 9; ++k) xyz[9 * i + k] = v[k];
        for (int k = 0; k < 3; ++k) idx[3 * i + k] = (uint32_t)(3 * i + k);
    }
    return sidx_mesh_from_arrays(out, xyz, 33, idx, 11, err);
}

#endif
