/* check.h — what an exercise's checker driver tells the runner.
 *
 * sidx-check links three things: the student's file, one driver
 * (lessons/exercises/check/NAME.c, which defines ex_driver_this) and the
 * runner (runner.c: main, the per-case child process, the comparison and
 * the report).  A driver describes a fixed battery of cases; for each it
 * emits the reference trace (the library's own walk, or the library's
 * elementary test) and runs the student's function, which emits the
 * student's trace through sidx/exercise.h.  The runner compares the two
 * event by event. */
#ifndef SIDX_EX_CHECK_H
#define SIDX_EX_CHECK_H

#include <stddef.h>
#include "sidx/sidx.h"
#include "sidx/exercise.h"

/* One promise of the exercise's hand-out (its contract): a range, a tie,
 * a special value, an output left untouched on refusal, the order of the
 * checks, what a miss returns.  Every rule has at least one case that
 * tests it and one planted mistake that breaks exactly it
 * (tests/exercises/mistakes.txt, its `rule` line); docs/exercises.md
 * lists the same table, and `sidx-check --rules NAME` prints it. */
typedef struct ex_rule {
    const char *id;        /* short and stable, a word or two joined by '-': "tmin-inclusive" */
    const char *statement; /* the hand-out's promise, in its words */
    const char *hint;      /* what a student whose code breaks it is told */
} ex_rule;

typedef struct ex_case_info {
    char name[160];      /* what the case is about: "ray parallel to the plane (N·d = 0)" */
    char what[512];      /* the input: the ray, the node, ... */
    const char *hint;    /* the case's hint in the slide's words, or NULL */
    /* The ids of the rules (ex_driver.rules) this case tests, separated by
     * spaces ("tmin-inclusive parallel-miss"), or NULL: a case of the
     * exercise's general algorithm only. */
    const char *rules;
    /* For sidx-view --events (the runner prints the command with the
     * traces): the structure and its build knobs as sidx-view options
     * ("kdtree", "--no-mailbox" or NULL), the scene (a built-in name, or
     * NULL: the runner writes view_mesh to DIR/scene.obj) and the ray.
     * view_accel NULL: the case is no walk sidx-view can show. */
    const char *view_accel, *view_knobs, *view_scene;
    const sidx_mesh *view_mesh;
    const sidx_ray *view_ray;
} ex_case_info;

typedef struct ex_driver {
    const char *name;    /* the exercise file name without .c */
    const char *title;   /* one line */
    const char *slide;   /* deck and slide title the exercise follows */
    int (*setup)(void);  /* builds the scenes; 0 on success */
    size_t (*num_cases)(void);
    void (*describe)(size_t i, ex_case_info *out);
    void (*reference)(size_t i, const sidx_hook *h);
    void (*student)(size_t i, const sidx_hook *h);
    /* A hint for the first divergence (ref or stu may be NULL when that
     * trace ended); NULL = the case's hint. */
    const char *(*hint)(size_t i, const sidx_event *ref, const sidx_event *stu);
    void (*teardown)(void);
    /* Prints an event the library's printer cannot (a NOTE, whose text
     * stays in the child): 1 if it wrote buf, 0 for the default; or NULL. */
    int (*format)(const sidx_event *e, char *buf, size_t size);
    /* The hand-out's rules, num_rules of them (NULL, 0: none listed). */
    const ex_rule *rules;
    size_t num_rules;
} ex_driver;

extern const ex_driver ex_driver_this;

/* "o=(x, y, z) d=(x, y, z) t in [tmin, tmax)" */
void ex_format_ray(char *buf, size_t size, const sidx_ray *r);
/* A walk case's input for the report, the ray r, and its sidx-view
 * command: structure accel with knobs (or NULL) over scene (a built-in
 * name, or NULL: mesh m is written out); no case hint.  The driver
 * writes out->name. */
void ex_describe_walk(ex_case_info *out, const sidx_ray *r, const char *accel, const char *knobs, const char *scene,
                      const sidx_mesh *m);
/* A ray from components, checked (aborts the driver on an invalid ray). */
sidx_ray ex_ray(float ox, float oy, float oz, float dx, float dy, float dz, float tmin, float tmax);
/* A growing array of events; ex_trace_hook_fn (a hook's fn, user = the
 * ex_trace) appends a copy of each event without its pointers (prims,
 * text).  Free ev when done. */
typedef struct ex_trace {
    sidx_event *ev;
    size_t n, cap;
} ex_trace;
void ex_trace_hook_fn(const sidx_event *ev, void *user);

/* A small deterministic generator for the random part of a battery. */
float ex_rand(uint32_t *state);

/* What a library query does around a structure's walk, for a driver whose
 * student writes the walk.  ex_walk_begin sets *ex up for ray r over mesh
 * m (events to student_hook, named structure, the tests tri and box),
 * emits RAY_BEGIN (the ray's [tmin, tmax]) to h and starts *best as "no
 * hit, t = tmax"; ex_walk_end emits RAY_END of *best (SIDX_NO_HIT and +inf
 * on a miss). */
void ex_walk_begin(sidx_ex *ex, const sidx_hook *student_hook, const sidx_hook *h, const char *structure,
                   const sidx_ray *r, const sidx_mesh *m, sidx_tri_method tri, sidx_box_method box, sidx_hit *best);
void ex_walk_end(const sidx_hook *h, const char *structure, const sidx_hit *best);

/* The hints of a front-to-back walk that stops once the best hit lies in
 * the current cell (the kd-tree's, the octree's), in the slide's words. */
typedef struct ex_walk_hints {
    const char *stop;       /* the reference stops there (hit_in_cell), the student goes on */
    const char *cannot;     /* the student stops with a hit beyond the cell */
    const char *stop_nohit; /* the student stops with no hit at all */
    const char *start;      /* the student does not enter the root first */
    const char *leaf;       /* a triangle test or a closer hit differs */
} ex_walk_hints;
/* The hint for a first divergence (ref or stu NULL where that trace
 * ended) about the stop rule, the start or a leaf, from h; NULL when it
 * is about none of them (the driver's own rules decide then). */
const char *ex_walk_hint(const sidx_event *ref, const sidx_event *stu, const ex_walk_hints *h);

#endif
