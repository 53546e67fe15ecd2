/* runner.c — the checker program sidx-check builds around a student's file.
 *
 *   run [--case K] [--trace DIR] [--viewer PATH] [--timeout SECONDS] [--verbose]
 *
 * For each case of the driver's battery: the reference trace is recorded
 * here, the student's function runs in a child process (fork) under a
 * time limit (alarm), reporting its events through a temporary file one
 * write at a time, so a crash or an endless loop loses nothing already
 * reported and cannot take the checker down.  The two traces are then
 * compared event by event; the first divergence is printed with the
 * case's input and a hint.  Exit status: 0 every case agrees, 1 a
 * divergence, 2 the student's code crashed or ran out of time (or the
 * checker could not run). */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#include "check.h"

/* More events than any case of any battery needs: a student walk past it
 * is going round in circles. */
#define EX_MAX_EVENTS 200000u

void ex_format_ray(char *buf, size_t size, const sidx_ray *r)
{
    snprintf(buf, size, "ray o=(%g, %g, %g) d=(%g, %g, %g) t in [%g, %g)", (double)r->org.x, (double)r->org.y,
             (double)r->org.z, (double)r->dir.x, (double)r->dir.y, (double)r->dir.z, (double)r->tmin,
             (double)r->tmax);
}

sidx_ray ex_ray(float ox, float oy, float oz, float dx, float dy, float dz, float tmin, float tmax)
{
    sidx_ray r;
    if (sidx_ray_init(&r, sidx_v3(ox, oy, oz), sidx_v3(dx, dy, dz), tmin, tmax) != SIDX_OK) {
        fprintf(stderr, "sidx-check: the battery holds an invalid ray\n");
        exit(2);
    }
    return r;
}

float ex_rand(uint32_t *state)
{
    *state = *state * 1664525u + 1013904223u;
    return (float)(*state >> 8) / 16777216.0f;
}

void ex_walk_begin(sidx_ex *ex, const sidx_hook *student_hook, const sidx_hook *h, const char *structure,
                   const sidx_ray *r, const sidx_mesh *m, sidx_tri_method tri, sidx_box_method box, sidx_hit *best)
{
    memset(ex, 0, sizeof *ex);
    ex->hook = student_hook;
    ex->structure = structure;
    ex->ray = r;
    ex->mesh = m;
    ex->tri = tri;
    ex->box = box;
    sidx_event e = sidx_event_blank(SIDX_EV_RAY_BEGIN);
    e.structure = structure;
    e.t_near = r->tmin;
    e.t_far = r->tmax;
    sidx_hook_emit(h, &e);
    *best = sidx_hit_none();
    best->t = r->tmax;
}

void ex_walk_end(const sidx_hook *h, const char *structure, const sidx_hit *best)
{
    sidx_event e = sidx_event_blank(SIDX_EV_RAY_END);
    e.structure = structure;
    e.prim = best->prim;
    e.t = best->prim == SIDX_NO_HIT ? INFINITY : best->t;
    e.result = best->prim != SIDX_NO_HIT;
    sidx_hook_emit(h, &e);
}

/* ---- traces ------------------------------------------------------------------ */

void ex_trace_hook_fn(const sidx_event *ev, void *user)
{
    ex_trace *t = user;
    if (t->n == t->cap) {
        size_t cap = t->cap ? 2 * t->cap : 256;
        sidx_event *p = realloc(t->ev, cap * sizeof *p);
        if (!p) {
            fprintf(stderr, "sidx-check: out of memory\n");
            exit(2);
        }
        t->ev = p;
        t->cap = cap;
    }
    sidx_event e = *ev;
    e.prims = NULL;
    e.text = NULL;
    /* a pop's or push's result (dropped, in the split plane) is the walk's
     * comment, which sidx_ex_push / sidx_ex_pop do not take: both traces
     * leave it blank, so that --diff compares what the exercise reports */
    if (e.type == SIDX_EV_STACK_PUSH || e.type == SIDX_EV_STACK_POP) e.result = -1;
    t->ev[t->n++] = e;
}

/* The child's hook: one write per event, straight to the file. */
typedef struct child_out {
    int fd;
    size_t n;
} child_out;

static void write_all(int fd, const void *p, size_t size)
{
    const char *c = p;
    while (size) {
        ssize_t k = write(fd, c, size);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) _exit(4);
        c += k;
        size -= (size_t)k;
    }
}

static void child_hook_fn(const sidx_event *ev, void *user)
{
    child_out *o = user;
    sidx_event e = *ev;
    e.prims = NULL;
    e.text = NULL; /* may point into the child's stack */
    write_all(o->fd, &e, sizeof e);
    if (++o->n >= EX_MAX_EVENTS) _exit(3);
}

static const char done_mark[8] = "EX-DONE";

typedef enum run_status { RUN_OK = 0, RUN_CRASH, RUN_TIMEOUT, RUN_TOO_MANY, RUN_ERROR } run_status;

static run_status run_student(size_t i, unsigned timeout, ex_trace *out, int *sig, int *code)
{
    char path[] = "/tmp/sidx-check-XXXXXX";
    int fd = mkstemp(path);
    if (fd < 0) return RUN_ERROR;
    unlink(path);
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) {
        close(fd);
        return RUN_ERROR;
    }
    if (pid == 0) {
        signal(SIGALRM, SIG_DFL);
        alarm(timeout);
        child_out o = {fd, 0};
        sidx_hook h = {child_hook_fn, &o, 0};
        ex_driver_this.student(i, &h);
        write_all(fd, done_mark, sizeof done_mark);
        fflush(stdout);
        _exit(0);
    }
    int st = 0;
    while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
    }
    struct stat sb;
    run_status rs = RUN_OK;
    if (fstat(fd, &sb) != 0) {
        close(fd);
        return RUN_ERROR;
    }
    size_t size = (size_t)sb.st_size;
    int done = 0;
    if (size >= sizeof done_mark && size % sizeof(sidx_event) == sizeof done_mark % sizeof(sidx_event)) {
        char mark[sizeof done_mark];
        if (pread(fd, mark, sizeof mark, (off_t)(size - sizeof mark)) == (ssize_t)sizeof mark &&
            memcmp(mark, done_mark, sizeof mark) == 0) {
            done = 1;
            size -= sizeof mark;
        }
    }
    size_t n = size / sizeof(sidx_event);
    out->n = 0;
    for (size_t k = 0; k < n; ++k) {
        sidx_event e;
        if (pread(fd, &e, sizeof e, (off_t)(k * sizeof e)) != (ssize_t)sizeof e) break;
        ex_trace_hook_fn(&e, out);
    }
    close(fd);
    *sig = 0;
    *code = 0;
    if (WIFSIGNALED(st)) {
        *sig = WTERMSIG(st);
        rs = *sig == SIGALRM ? RUN_TIMEOUT : RUN_CRASH;
    } else if (WIFEXITED(st) && WEXITSTATUS(st) == 3) {
        rs = RUN_TOO_MANY;
    } else if (!WIFEXITED(st) || WEXITSTATUS(st) != 0 || !done) {
        *code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
        rs = RUN_CRASH;
    }
    return rs;
}

/* ---- comparison ---------------------------------------------------------------- */

static int same_float(float a, float b)
{
    if (a == b) return 1;
    if (isnan(a) || isnan(b)) return isnan(a) && isnan(b);
    if (isinf(a) || isinf(b)) return 0;
    const float m = fabsf(a) > fabsf(b) ? fabsf(a) : fabsf(b);
    return fabsf(a - b) <= 1e-5f * m + 1e-7f;
}

/* The fields an event of its type carries (docs/events.md), structure
 * and ray id excepted: the student's events name the exercise. */
static int same_event(const sidx_event *a, const sidx_event *b)
{
    if (a->type != b->type) return 0;
    switch (a->type) {
    case SIDX_EV_BOX_TEST:
        return a->node == b->node && a->result == b->result &&
               (a->result != 1 || (same_float(a->t_near, b->t_near) && same_float(a->t_far, b->t_far)));
    case SIDX_EV_NODE_ENTER:
        return a->node == b->node && a->depth == b->depth && same_float(a->t_near, b->t_near) &&
               same_float(a->t_far, b->t_far) && a->cell[0] == b->cell[0] && a->cell[1] == b->cell[1] &&
               a->cell[2] == b->cell[2];
    case SIDX_EV_STACK_PUSH:
    case SIDX_EV_STACK_POP:
        return a->node == b->node && a->depth == b->depth && same_float(a->t_near, b->t_near) &&
               same_float(a->t_far, b->t_far);
    case SIDX_EV_PRIM_TEST:
        return a->prim == b->prim && a->result == b->result && (a->result != 1 || same_float(a->t, b->t));
    case SIDX_EV_HIT_UPDATE: return a->prim == b->prim && same_float(a->t, b->t);
    case SIDX_EV_MAILBOX_HIT: return a->prim == b->prim;
    case SIDX_EV_TERMINATE: return a->reason == b->reason && same_float(a->t, b->t) && a->count == b->count;
    case SIDX_EV_RAY_END: return a->prim == b->prim && same_float(a->t, b->t) && a->result == b->result;
    case SIDX_EV_RAY_BEGIN: return same_float(a->t_near, b->t_near) && same_float(a->t_far, b->t_far);
    case SIDX_EV_BUILD_CANDIDATE:
    case SIDX_EV_BUILD_SPLIT:
        return a->node == b->node && a->axis == b->axis && same_float(a->pos, b->pos) &&
               same_float(a->cost, b->cost) && a->count == b->count && a->aux == b->aux;
    case SIDX_EV_NOTE: /* a result the driver reports: cell[], count, t_near and t_far (its format callback prints it) */
        return a->cell[0] == b->cell[0] && a->cell[1] == b->cell[1] && a->cell[2] == b->cell[2] &&
               a->count == b->count && same_float(a->t_near, b->t_near) && same_float(a->t_far, b->t_far);
    default: return 1;
    }
}

static void print_event(FILE *f, const char *label, const sidx_event *e)
{
    char buf[512];
    if (!e) {
        fprintf(f, "  %-10s (nothing: the trace ends here)\n", label);
        return;
    }
    if (!ex_driver_this.format || !ex_driver_this.format(e, buf, sizeof buf)) sidx_event_format(e, buf, sizeof buf);
    const char *p = buf;
    while (*p == ' ') ++p; /* the printer's indentation means nothing out of context */
    fprintf(f, "  %-10s %s\n", label, p);
}

static int write_jsonl(const char *dir, const char *name, const ex_trace *t)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    /* --trace /tmp/tr should just work: make the directory (one level) */
    if (mkdir(dir, 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, "sidx-check: cannot make the directory %s: %s\n", dir, strerror(errno));
        return -1;
    }
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "sidx-check: cannot write %s: %s\n", path, strerror(errno));
        return -1;
    }
    char buf[1024];
    for (size_t k = 0; k < t->n; ++k) {
        sidx_event_to_json(&t->ev[k], buf, sizeof buf);
        fprintf(f, "%s\n", buf);
    }
    return fclose(f) == 0 ? 0 : -1;
}

/* The sidx-view commands that step through the two traces of DIR. */
static void print_view_commands(const char *viewer, const char *dir, const ex_case_info *info)
{
    char scene[4096];
    if (info->view_scene) {
        snprintf(scene, sizeof scene, "%s", info->view_scene);
    } else {
        snprintf(scene, sizeof scene, "%s/scene.obj", dir);
        sidx_error err;
        if (sidx_mesh_save_obj(info->view_mesh, scene, &err) != SIDX_OK) {
            printf("  view       (cannot write %s: %s)\n", scene, err.message);
            return;
        }
    }
    const sidx_ray *r = info->view_ray;
    for (int k = 0; k < 2; ++k)
        printf("  %-10s %s --accel %s%s%s --scene %s --ray %.9g,%.9g,%.9g,%.9g,%.9g,%.9g --events %s/%s\n",
               k ? "" : "view", viewer, info->view_accel, info->view_knobs ? " " : "",
               info->view_knobs ? info->view_knobs : "", scene, (double)r->org.x, (double)r->org.y,
               (double)r->org.z, (double)r->dir.x, (double)r->dir.y, (double)r->dir.z, dir,
               k ? "yours.jsonl" : "reference.jsonl");
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: (built by sidx-check) run [--case K] [--trace DIR] [--viewer PATH] [--timeout SECONDS]\n"
            "                                 [--verbose]\n"
            "  --case K        run only case K (1-based)\n"
            "  --trace DIR     write DIR/reference.jsonl and DIR/yours.jsonl for the first failing case\n"
            "                  (or for case K)\n"
            "  --viewer PATH   sidx-view, to print the commands that step through the traces\n"
            "  --timeout S     time limit per case (default 2 s)\n"
            "  --verbose       one line per case\n");
}

int main(int argc, char **argv)
{
    const ex_driver *d = &ex_driver_this;
    const char *trace_dir = NULL, *viewer = NULL;
    unsigned timeout = 2;
    long only = 0;
    int verbose = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--trace") && i + 1 < argc) {
            trace_dir = argv[++i];
        } else if (!strcmp(argv[i], "--viewer") && i + 1 < argc) {
            viewer = argv[++i];
        } else if (!strcmp(argv[i], "--timeout") && i + 1 < argc) {
            timeout = (unsigned)strtoul(argv[++i], NULL, 10);
            if (timeout == 0) timeout = 1;
        } else if (!strcmp(argv[i], "--case") && i + 1 < argc) {
            only = strtol(argv[++i], NULL, 10);
        } else if (!strcmp(argv[i], "--verbose")) {
            verbose = 1;
        } else if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        } else {
            usage(stderr);
            return 2;
        }
    }
    if (d->setup && d->setup() != 0) {
        fprintf(stderr, "sidx-check %s: the checker could not set up its scenes\n", d->name);
        return 2;
    }
    const size_t n = d->num_cases();
    if (only < 0 || (size_t)only > n) {
        fprintf(stderr, "sidx-check %s: --case wants 1..%zu\n", d->name, n);
        return 2;
    }
    ex_trace ref = {0}, stu = {0};
    int rc = 0;
    size_t steps = 0, ran = 0;
    for (size_t i = only ? (size_t)only - 1 : 0; i < (only ? (size_t)only : n); ++i) {
        ex_case_info info;
        memset(&info, 0, sizeof info);
        d->describe(i, &info);
        ref.n = 0;
        sidx_hook rh = {ex_trace_hook_fn, &ref, 0};
        d->reference(i, &rh);
        int sig = 0, code = 0;
        const run_status rs = run_student(i, timeout, &stu, &sig, &code);
        ++ran;
        if (rs == RUN_ERROR) {
            fprintf(stderr, "sidx-check %s: cannot run case %zu: %s\n", d->name, i + 1, strerror(errno));
            rc = 2;
            break;
        }
        if (rs != RUN_OK) {
            printf("sidx-check %s: case %zu of %zu, \"%s\":\n", d->name, i + 1, n, info.name);
            if (rs == RUN_TIMEOUT)
                printf("  your code did not finish within %u s (an endless loop?)\n", timeout);
            else if (rs == RUN_TOO_MANY)
                printf("  your code reported more than %u steps (an endless loop?)\n", EX_MAX_EVENTS);
            else if (sig)
                printf("  your code crashed: signal %d (%s)\n", sig, strsignal(sig));
            else
                printf("  your code crashed: it stopped with exit status %d before returning\n", code);
            printf("  %-10s %s\n", "input", info.what);
            if (stu.n) {
                printf("  the last steps your code reported (of %zu):\n", stu.n);
                for (size_t k = stu.n > 3 ? stu.n - 3 : 0; k < stu.n; ++k) print_event(stdout, "", &stu.ev[k]);
            } else {
                printf("  it reported no step before that\n");
            }
            printf("CRASH (exit 2)\n");
            rc = 2;
            break;
        }
        size_t k = 0;
        while (k < ref.n && k < stu.n && same_event(&ref.ev[k], &stu.ev[k])) ++k;
        steps += k;
        const int agree = k == ref.n && k == stu.n;
        int traces_written = 0;
        if (trace_dir && (!agree || only)) {
            if (write_jsonl(trace_dir, "reference.jsonl", &ref) != 0 || write_jsonl(trace_dir, "yours.jsonl", &stu) != 0)
                rc = 2;
            else
                traces_written = 1;
        }
        if (verbose) printf("case %3zu %-5s %s\n", i + 1, agree ? "ok" : "FAIL", info.name);
        if (agree) continue;
        const sidx_event *re = k < ref.n ? &ref.ev[k] : NULL, *se = k < stu.n ? &stu.ev[k] : NULL;
        const char *hint = d->hint ? d->hint(i, re, se) : NULL;
        if (!hint) hint = info.hint;
        printf("sidx-check %s: case %zu of %zu, \"%s\": your trace leaves the reference at step %zu\n", d->name,
               i + 1, n, info.name, k + 1);
        printf("  %-10s %s\n", "input", info.what);
        if (k > 0) {
            printf("  the steps before, which agree:\n");
            for (size_t j = k > 3 ? k - 3 : 0; j < k; ++j) print_event(stdout, "", &ref.ev[j]);
        }
        print_event(stdout, "reference", re);
        print_event(stdout, "yours", se);
        if (hint) printf("  %-10s %s\n", "hint", hint);
        printf("  %-10s %s\n", "slide", d->slide);
        if (traces_written) {
            printf("  traces     %s/reference.jsonl and %s/yours.jsonl (sidx-step --diff A B)\n", trace_dir, trace_dir);
            if (viewer && info.view_accel) print_view_commands(viewer, trace_dir, &info);
        } else if (trace_dir) {
            printf("  traces     not written (the message above says why)\n");
        } else {
            printf("  traces     add --trace DIR to write both as JSON Lines (sidx-step --diff A B%s)\n",
                   viewer && info.view_accel ? ", sidx-view --events" : "");
        }
        printf("FAIL (exit 1)\n");
        rc = 1;
        break;
    }
    if (rc == 0)
        printf("sidx-check %s: all %zu case%s pass (%zu steps compared)\n", d->name, ran, ran == 1 ? "" : "s", steps);
    free(ref.ev);
    free(stu.ev);
    if (d->teardown) d->teardown();
    return rc;
}
