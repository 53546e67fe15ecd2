/* runner.c — the checker program sidx-check builds around a student's file.
 *
 *   run [--case K] [--trace DIR] [--viewer PATH] [--timeout SECONDS] [--verbose]
 *       [--source FILE] [--memory MB] [--summary FILE]
 *
 * For each case of the driver's battery: the reference trace is recorded
 * here, the student's function runs in a child process (fork), contained
 * (limits, its own directory, its output captured: "containment" below),
 * reporting its events through a temporary file one
 * write at a time, so a crash or an endless loop loses nothing already
 * reported and cannot take the checker down.  The two traces are then
 * compared event by event; the first divergence is printed with the
 * case's input and a hint.  Exit status: 0 every case agrees, 1 a
 * divergence, 2 the student's code crashed or ran out of time (or the
 * checker could not run). */
#define _GNU_SOURCE /* REG_RIP, dl_iterate_phdr */
#include <dirent.h>
#include <errno.h>
#include <execinfo.h>
#include <fcntl.h>
#include <ftw.h>
#include <grp.h>
#include <limits.h>
#include <link.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <time.h>
#include <ucontext.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#include "check.h"
#include "sandbox.h"

/* More events than any case of any battery needs: a student walk past it
 * is going round in circles. */
#define EX_MAX_EVENTS 200000u

void ex_format_ray(char *buf, size_t size, const sidx_ray *r)
{
    snprintf(buf, size, "ray o=(%g, %g, %g) d=(%g, %g, %g) t in [%g, %g)", (double)r->org.x, (double)r->org.y,
             (double)r->org.z, (double)r->dir.x, (double)r->dir.y, (double)r->dir.z, (double)r->tmin,
             (double)r->tmax);
}

void ex_describe_walk(ex_case_info *out, const sidx_ray *r, const char *accel, const char *knobs, const char *scene,
                      const sidx_mesh *m)
{
    ex_format_ray(out->what, sizeof out->what, r);
    out->view_accel = accel;
    out->view_knobs = knobs;
    out->view_scene = scene;
    out->view_mesh = m;
    out->view_ray = r;
    out->hint = NULL;
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

const char *ex_walk_hint(const sidx_event *ref, const sidx_event *stu, const ex_walk_hints *h)
{
    const int ref_stop = ref && ref->type == SIDX_EV_TERMINATE && ref->reason == SIDX_TERM_HIT_IN_CELL;
    const int stu_stop = stu && stu->type == SIDX_EV_TERMINATE && stu->reason == SIDX_TERM_HIT_IN_CELL;
    if (stu_stop && !ref_stop) return stu->prim == SIDX_NO_HIT ? h->stop_nohit : h->cannot;
    if (ref_stop && !stu_stop) return h->stop;
    if (ref && ref->type == SIDX_EV_NODE_ENTER && ref->node == 0 && (!stu || stu->type != SIDX_EV_NODE_ENTER))
        return h->start;
    if ((ref && (ref->type == SIDX_EV_PRIM_TEST || ref->type == SIDX_EV_HIT_UPDATE)) ||
        (stu && (stu->type == SIDX_EV_PRIM_TEST || stu->type == SIDX_EV_HIT_UPDATE)))
        return h->leaf;
    return NULL;
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

/* ---- containment -------------------------------------------------------------- */

/* The student's code runs in a child process, one per case, in a fresh
 * temporary directory (removed after the case) under limits: CPU time
 * (RLIMIT_CPU) and wall time (the parent's deadline), memory
 * (RLIMIT_AS, beyond what the checker itself holds), the size of any file
 * it writes (RLIMIT_FSIZE), no new process (RLIMIT_NPROC = 0: a fork bomb
 * gets EAGAIN) and no core file.  The child also enters the sandbox
 * (sandbox.c), for root and for any user: new user (unless root), mount,
 * network, IPC and PID namespaces, the case's directory as its root
 * (chroot), no privilege left (root becomes nobody).  So it writes and
 * reads nothing outside the directory, reaches no network, and its
 * kill(-1) reaches only its own processes: the child is its PID
 * namespace's first process (init), for which the signals that end a
 * process elsewhere go through handlers (init_exit).  Every call that reaches outside the directory
 * (watch.c, linked in with --wrap) is noted in a file the parent reads
 * after the case: the report lists them.  Where the sandbox cannot be set
 * up (no user namespaces for ordinary users) the verdict's first line
 * says so, and the code runs with the limits only; --unsafe asks for
 * that.  Its stdout and stderr go to a pipe the parent reads:
 * the first lines are kept to be shown before the verdict, the rest only
 * counted, and a case writing more than EX_MAX_OUTPUT bytes is stopped.
 * A crash writes the faulting address and the backtrace to a file; the
 * parent names the student's file:line with addr2line (the student's file
 * is compiled with -g). */

#define EX_SHOW_LINES 20             /* lines of the student's output shown */
#define EX_SHOW_WIDTH 160            /* characters kept of each shown line */
#define EX_MAX_OUTPUT (1u << 20)     /* bytes of output per case */
#define EX_MEMORY_MB 1024ul          /* memory per case beyond the checker's own */
#define EX_CRASH_FRAMES 48
#define EX_MAX_ATTEMPTS 12           /* distinct attempts outside listed in the report */

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define EX_SANITIZED 1 /* the sanitizers reserve terabytes of address space: no RLIMIT_AS */
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define EX_SANITIZED 1
#endif
#endif
#ifndef EX_SANITIZED
#define EX_SANITIZED 0
#endif

static struct containment {
    char dir[64];                /* this run's temporary directory */
    const char *source;          /* the student's file, as given */
    char source_real[PATH_MAX];  /* and its real path, as the debug information names it */
    char exe[PATH_MAX];          /* this program */
    unsigned long memory_mb;
    /* the student's output over all cases */
    char shown[EX_SHOW_LINES][EX_SHOW_WIDTH + 1];
    unsigned char cut[EX_SHOW_LINES]; /* the line was longer than EX_SHOW_WIDTH */
    size_t nshown, shown_len;
    int in_line, line_shown;
    unsigned long long more_lines;
    /* the last crash: "at FILE:LINE in f()" or "" */
    char where[2200];
    int where_is_student;
    int recursion;      /* frames of the crashing student function in the backtrace */
    int locate;         /* name a crash's place (addr2line); off for the cases run for the diagnosis */
    double wall_cap;    /* > 0: a case's wall time limit below --timeout (the cases run for the diagnosis) */
    /* the sandbox: 0 contained; 1 not (--unsafe, or it cannot be set up:
     * why says why) */
    int unsafe;
    char why[300];
    /* the calls that reached outside (watch.c), distinct ones over all cases */
    struct attempt {
        char kind[12], result[96], what[320];
        size_t case_;
        unsigned long count;
    } att[EX_MAX_ATTEMPTS];
    size_t natt;
    unsigned long more_att;
    char alloc_failed[80]; /* this case: the first allocation that failed, "malloc(8589934592)", or "" */
} cx = {.memory_mb = EX_MEMORY_MB, .locate = 1};

/* Shared with the case's processes (MAP_SHARED, made before the first
 * fork): the PID namespace's first process writes here the wait status of
 * the process that ran the student's code, and the child why it could not
 * enter the sandbox. */
static struct case_shared {
    int have_status, status;
    char why[256];
} *shared;

extern int ck_watch_fd; /* watch.c */

static int crash_fd = -1;

static void init_exit(int sig);

static void crash_handler(int sig, siginfo_t *si, void *ucv)
{
    (void)si;
    void *pc[EX_CRASH_FRAMES + 1];
    int n = 0;
    const ucontext_t *uc = ucv;
#if defined(__x86_64__)
    pc[n++] = (void *)uc->uc_mcontext.gregs[REG_RIP];
#elif defined(__aarch64__)
    pc[n++] = (void *)uc->uc_mcontext.pc;
#else
    (void)uc;
    pc[n++] = NULL;
#endif
    n += backtrace(pc + n, EX_CRASH_FRAMES);
    /* Out of memory?  Under RLIMIT_AS a mapping of a quarter of the limit
     * fails when the student's allocations have used the rest up (a NULL
     * from malloc is a usual cause of the crash). */
    const size_t probe = (size_t)cx.memory_mb << 18;
    void *m = mmap(NULL, probe, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    const char oom = m == MAP_FAILED;
    if (!oom) munmap(m, probe);
    if (write(crash_fd, &oom, 1) < 0 || write(crash_fd, pc, (size_t)n * sizeof pc[0]) < 0) {
    }
    if (getpid() == 1) init_exit(sig); /* the sandbox's init: a raise would be ignored */
    raise(sig); /* SA_RESETHAND: delivered with the default action once the handler returns */
}

/* The first process of a PID namespace (the case's child, in the sandbox)
 * is not killed by a signal it has no handler for, unless the kernel
 * forces it (a fault): the signals that would end it elsewhere end it
 * here through the handlers, which hand the status they stand for to the
 * parent on the shared page. */
static void init_exit(int sig)
{
    shared->status = sig; /* a wait status "killed by sig" */
    shared->have_status = 1;
    _exit(128 + sig);
}

static void init_signal(int sig) { init_exit(sig); }

/* In the child, before the student's code: the directory, the limits, the
 * crash handler. */
static void contain_child(const char *casedir, unsigned timeout, int out_fd, int fd_crash)
{
    setpgid(0, 0);
    const int null = open("/dev/null", O_RDONLY);
    if (null >= 0) {
        dup2(null, 0);
        close(null);
    }
    dup2(out_fd, 1);
    dup2(out_fd, 2);
    close(out_fd);
    setvbuf(stdout, NULL, _IOLBF, 0); /* a crash loses no line already printed */
    crash_fd = fd_crash;
    static char altstack[1 << 16]; /* the handler runs even on a stack overflow */
    stack_t ss = {.ss_sp = altstack, .ss_size = sizeof altstack};
    sigaltstack(&ss, NULL);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = crash_handler;
    sa.sa_flags = SA_SIGINFO | SA_ONSTACK | SA_RESETHAND;
    const int sigs[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP};
    for (size_t k = 0; k < sizeof sigs / sizeof sigs[0]; ++k) sigaction(sigs[k], &sa, NULL);
    unsigned long pages = 0; /* the checker's own address space, read before /proc is out of reach */
    FILE *statm = fopen("/proc/self/statm", "r");
    if (statm) {
        if (fscanf(statm, "%lu", &pages) != 1) pages = 0;
        fclose(statm);
    }
    if (!cx.unsafe) {
        if (ck_sandbox_enter(casedir, shared->why, sizeof shared->why) != 0) _exit(5);
    } else if (chdir(casedir) != 0) {
        snprintf(shared->why, sizeof shared->why, "chdir: %s", strerror(errno));
        _exit(5);
    }
    struct rlimit rl;
    rl.rlim_cur = timeout;
    rl.rlim_max = timeout + 1;
    setrlimit(RLIMIT_CPU, &rl);
    rl.rlim_cur = rl.rlim_max = (rlim_t)EX_MAX_EVENTS * sizeof(sidx_event) + (16u << 20);
    setrlimit(RLIMIT_FSIZE, &rl);
    rl.rlim_cur = rl.rlim_max = 0;
    setrlimit(RLIMIT_CORE, &rl);
    if (!EX_SANITIZED) {
        rl.rlim_cur = rl.rlim_max = (rlim_t)pages * (rlim_t)sysconf(_SC_PAGESIZE) + (rlim_t)cx.memory_mb * (1u << 20);
        setrlimit(RLIMIT_AS, &rl);
    }
    signal(SIGXCPU, SIG_DFL);
    signal(SIGXFSZ, SIG_DFL);
    if (!cx.unsafe) { /* init of its PID namespace: SIGXCPU and SIGXFSZ act only through a handler */
        sa.sa_handler = init_signal;
        sa.sa_flags = 0;
        sigaction(SIGXCPU, &sa, NULL);
        sigaction(SIGXFSZ, &sa, NULL);
    }
    rl.rlim_cur = rl.rlim_max = 0;
    setrlimit(RLIMIT_NPROC, &rl);
}

/* Keeps the first lines of the student's output, counts the rest. */
static void take_output(const char *p, size_t n)
{
    for (size_t k = 0; k < n; ++k) {
        if (!cx.in_line) {
            cx.in_line = 1;
            cx.line_shown = cx.nshown < EX_SHOW_LINES;
            cx.shown_len = 0;
            if (!cx.line_shown) ++cx.more_lines;
        }
        if (p[k] == '\n') {
            cx.in_line = 0;
            if (cx.line_shown) cx.shown[cx.nshown++][cx.shown_len] = '\0';
        } else if (cx.line_shown && cx.shown_len < EX_SHOW_WIDTH) {
            const unsigned char c = (unsigned char)p[k];
            cx.shown[cx.nshown][cx.shown_len++] = (c < 32 && c != '\t') || c == 127 ? '?' : (char)c;
        } else if (cx.line_shown) {
            cx.cut[cx.nshown] = 1;
        }
    }
}

/* 19950 -> "19,950" */
static const char *thousands(unsigned long long v, char *buf, size_t size)
{
    char raw[32];
    const int n = snprintf(raw, sizeof raw, "%llu", v);
    size_t o = 0;
    for (int k = 0; k < n && o + 2 < size; ++k) {
        if (k && (n - k) % 3 == 0) buf[o++] = ',';
        buf[o++] = raw[k];
    }
    buf[o] = '\0';
    return buf;
}

/* The student's output so far, before the verdict. */
static void print_student_output(void)
{
    if (cx.in_line && cx.line_shown) { /* a last line without its newline */
        cx.shown[cx.nshown++][cx.shown_len] = '\0';
        cx.in_line = 0;
    }
    if (!cx.nshown) return;
    char num[40];
    printf("your output%s:\n", cx.more_lines ? " (the first lines)" : "");
    for (size_t k = 0; k < cx.nshown; ++k) printf("  | %s%s\n", cx.shown[k], cx.cut[k] ? "\u2026" : "");
    if (cx.more_lines)
        printf("  \u2026 %s more line%s of your output not shown\n", thousands(cx.more_lines, num, sizeof num),
               cx.more_lines == 1 ? "" : "s");
}

static int remove_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb;
    (void)flag;
    (void)ftw;
    return remove(path) == 0 ? 0 : 0; /* remove what can be removed */
}

static void remove_tree(const char *dir) { nftw(dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS); }

/* This program's load bias (a PIE: an address minus the bias is the one
 * addr2line reads in the file) and the addresses its segments span. */
typedef struct exe_span {
    uintptr_t bias, lo, hi;
} exe_span;

static int span_cb(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size;
    exe_span *s = data;
    s->bias = (uintptr_t)info->dlpi_addr;
    s->lo = UINTPTR_MAX;
    s->hi = 0;
    for (int k = 0; k < info->dlpi_phnum; ++k) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[k];
        if (ph->p_type != PT_LOAD) continue;
        const uintptr_t a = s->bias + (uintptr_t)ph->p_vaddr, b = a + (uintptr_t)ph->p_memsz;
        if (a < s->lo) s->lo = a;
        if (b > s->hi) s->hi = b;
    }
    return 1; /* the first object is the program */
}

/* Names the crash's place from the addresses in fd: the first frame in
 * the student's file, else the innermost frame with a known line. */
static void locate_crash(int fd)
{
    cx.where[0] = '\0';
    cx.where_is_student = 0;
    void *pc[EX_CRASH_FRAMES + 1];
    const ssize_t got = pread(fd, pc, sizeof pc, 1); /* after the out-of-memory byte */
    if (got < (ssize_t)sizeof pc[0]) return;
    const int n = (int)(got / (ssize_t)sizeof pc[0]);
    exe_span span = {0, 0, 0};
    dl_iterate_phdr(span_cb, &span);
    char *argv[EX_CRASH_FRAMES + 8];
    char addr[EX_CRASH_FRAMES + 1][32];
    int a = 0;
    argv[a++] = "addr2line";
    argv[a++] = "-f";
    argv[a++] = "-e";
    argv[a++] = cx.exe;
    /* pc[0] is the faulting instruction; the frames after the signal
     * frame are return addresses, whose call lies one byte before */
    int past_signal = 0;
    for (int k = 0; k < n; ++k) {
        uintptr_t p = (uintptr_t)pc[k];
        if (k > 0 && !past_signal) {
            if (p == (uintptr_t)pc[0]) past_signal = 1;
            continue;
        }
        if (p < span.lo || p >= span.hi) continue; /* in a shared library: libc's abort, ... */
        if (k > 0) --p;
        snprintf(addr[a - 4], sizeof addr[0], "%#jx", (uintmax_t)(p - span.bias));
        argv[a] = addr[a - 4];
        ++a;
    }
    argv[a] = NULL;
    if (a == 4) return;
    int pfd[2];
    if (pipe(pfd) != 0) return;
    fflush(stdout);
    const pid_t pid = fork();
    if (pid < 0) {
        close(pfd[0]);
        close(pfd[1]);
        return;
    }
    if (pid == 0) {
        dup2(pfd[1], 1);
        close(pfd[0]);
        close(pfd[1]);
        const int null = open("/dev/null", O_WRONLY);
        if (null >= 0) dup2(null, 2);
        execvp(argv[0], argv);
        _exit(127);
    }
    close(pfd[1]);
    FILE *f = fdopen(pfd[0], "r");
    char fn[512], loc[PATH_MAX + 64], first[sizeof cx.where] = "", student_fn[512] = "";
    cx.recursion = 0;
    while (f && fgets(fn, sizeof fn, f) && fgets(loc, sizeof loc, f)) {
        fn[strcspn(fn, "\n")] = '\0';
        loc[strcspn(loc, " \n")] = '\0'; /* drops " (discriminator N)" */
        char *colon = strrchr(loc, ':');
        if (!colon || loc[0] == '?' || colon[1] == '?' || colon[1] == '0') continue;
        *colon = '\0';
        if (!strcmp(loc, cx.source_real)) {
            /* the innermost frame in the student's file names the place; the
             * frames of that same function below it count the recursion */
            if (!cx.where_is_student) {
                snprintf(cx.where, sizeof cx.where, "%.2000s:%.16s, in %.120s()", cx.source, colon + 1, fn);
                snprintf(student_fn, sizeof student_fn, "%s", fn);
                cx.where_is_student = 1;
            }
            if (!strcmp(fn, student_fn)) ++cx.recursion;
            continue;
        }
        if (!first[0]) snprintf(first, sizeof first, "%.2000s:%.16s, in %.120s()", loc, colon + 1, fn);
    }
    if (f) fclose(f);
    int st;
    while (waitpid(pid, &st, 0) < 0 && errno == EINTR) {
    }
    if (!cx.where_is_student) snprintf(cx.where, sizeof cx.where, "%s", first);
}

static const char done_mark[8] = "EX-DONE";

typedef enum run_status {
    RUN_OK = 0,
    RUN_CRASH,
    RUN_TIMEOUT,    /* CPU time (an endless loop) or wall time (sleeping) */
    RUN_TOO_MANY,
    RUN_OUTPUT,     /* more than EX_MAX_OUTPUT bytes of output, or a file past RLIMIT_FSIZE */
    RUN_MEMORY,     /* out of memory */
    RUN_ERROR
} run_status;

/* Adds the attempts the case's processes wrote to fd (watch.c's lines). */
static void take_attempts(int fd, size_t case_)
{
    char buf[8192];
    const ssize_t n = pread(fd, buf, sizeof buf - 1, 0);
    if (n <= 0) return;
    buf[n] = '\0';
    for (char *line = buf, *next; *line; line = next) {
        next = line + strcspn(line, "\n");
        if (*next) *next++ = '\0';
        char *kind = line, *result = strchr(kind, '\t'), *what = result ? strchr(result + 1, '\t') : NULL;
        if (!what) continue;
        *result++ = '\0';
        *what++ = '\0';
        if (!strcmp(kind, "memory")) { /* not an attempt outside: a failed allocation (watch.c) */
            if (!cx.alloc_failed[0]) snprintf(cx.alloc_failed, sizeof cx.alloc_failed, "%.79s", what);
            continue;
        }
        size_t k = 0;
        while (k < cx.natt && (strcmp(cx.att[k].kind, kind) || strcmp(cx.att[k].what, what))) ++k;
        if (k < cx.natt) {
            ++cx.att[k].count;
        } else if (cx.natt < EX_MAX_ATTEMPTS) {
            struct attempt *a = &cx.att[cx.natt++];
            snprintf(a->kind, sizeof a->kind, "%.11s", kind);
            snprintf(a->result, sizeof a->result, "%.95s", result);
            snprintf(a->what, sizeof a->what, "%.319s", what);
            a->case_ = case_;
            a->count = 1;
        } else {
            ++cx.more_att;
        }
    }
}

/* The attempts, before the verdict: each with the first case and what it got. */
static void print_attempts(void)
{
    if (!cx.natt) return;
    printf("your code tried to reach outside its directory%s:\n",
           cx.unsafe ? " (NOT contained: what says \"done\" was done)" : " (the sandbox kept it in)");
    for (size_t k = 0; k < cx.natt; ++k) {
        const struct attempt *a = &cx.att[k];
        char times[48] = "";
        if (a->count > 1) snprintf(times, sizeof times, ", %lu times", a->count);
        /* contained, a call that succeeded stayed inside: the sandbox's / is the case's directory */
        printf("  %-8s %s  (case %zu%s: %s)\n", a->kind, a->what, a->case_, times,
               strcmp(a->result, "ok") ? a->result : cx.unsafe ? "done" : "done inside its own directory");
    }
    if (cx.more_att) printf("  \u2026 and %lu more\n", cx.more_att);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The CPU seconds so far of every process in process group pgrp (a
 * case's processes: the sandbox's first one and the student's below it),
 * from /proc/PID/stat: utime and stime, fields 14 and 15, in clock ticks;
 * 0 where /proc cannot be read. */
static double group_cpu_seconds(pid_t pgrp)
{
    DIR *d = opendir("/proc");
    if (!d) return 0;
    const double tick = (double)sysconf(_SC_CLK_TCK);
    double total = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] < '1' || e->d_name[0] > '9') continue;
        char path[64], line[1024];
        snprintf(path, sizeof path, "/proc/%.20s/stat", e->d_name);
        FILE *f = fopen(path, "r");
        if (!f) continue;
        const size_t n = fread(line, 1, sizeof line - 1, f);
        fclose(f);
        line[n] = '\0';
        /* after the command's closing parenthesis: state ppid pgrp ... */
        const char *p = strrchr(line, ')');
        long group = 0;
        unsigned long long ut = 0, stt = 0;
        if (p && sscanf(p + 1, " %*c %*d %ld %*d %*d %*d %*u %*u %*u %*u %*u %llu %llu", &group, &ut, &stt) == 3 &&
            group == (long)pgrp && tick > 0)
            total += (double)(ut + stt) / tick;
    }
    closedir(d);
    return total;
}

/* *cpu: the time-out was spent computing (an endless loop), not waiting. */
/* The mark the child writes after each case of a run of several (its
 * node: the case's index): no event type of the library has this value. */
#define EX_CASE_END ((sidx_event_type)0x4558)

/* Runs the student's cases i..last (last = i: one case) in one child; a
 * run of several writes EX_CASE_END after each case. */
static run_status run_student(size_t i, size_t last, unsigned timeout, ex_trace *out, int *sig, int *code, int *cpu)
{
    char casedir[sizeof cx.dir + 16], path[sizeof cx.dir + 16], cpath[sizeof cx.dir + 16], wpath[sizeof cx.dir + 16];
    snprintf(casedir, sizeof casedir, "%s/case-XXXXXX", cx.dir);
    snprintf(path, sizeof path, "%s/ev-XXXXXX", cx.dir);
    snprintf(cpath, sizeof cpath, "%s/bt-XXXXXX", cx.dir);
    snprintf(wpath, sizeof wpath, "%s/wa-XXXXXX", cx.dir);
    int pfd[2] = {-1, -1};
    if (!mkdtemp(casedir)) return RUN_ERROR;
    chmod(casedir, 0777); /* the child runs as nobody */
    const int fd = mkstemp(path), cfd = mkstemp(cpath), wfd = mkstemp(wpath);
    if (fd >= 0) unlink(path);
    if (cfd >= 0) unlink(cpath);
    if (wfd >= 0) {
        unlink(wpath);
        fcntl(wfd, F_SETFL, O_APPEND); /* the case's processes write whole lines, one after the other */
    }
    if (fd < 0 || cfd < 0 || wfd < 0 || pipe(pfd) != 0) {
        if (fd >= 0) close(fd);
        if (cfd >= 0) close(cfd);
        if (wfd >= 0) close(wfd);
        remove_tree(casedir);
        return RUN_ERROR;
    }
    shared->have_status = 0;
    shared->why[0] = '\0';
    fflush(stdout);
    fflush(stderr);
    const pid_t pid = cx.unsafe ? fork() : ck_sandbox_fork(shared->why, sizeof shared->why);
    if (pid < 0) {
        if (!cx.unsafe) fprintf(stderr, "sidx-check: cannot contain the case: %s\n", shared->why);
        close(fd);
        close(cfd);
        close(wfd);
        close(pfd[0]);
        close(pfd[1]);
        remove_tree(casedir);
        return RUN_ERROR;
    }
    if (pid == 0) {
        close(pfd[0]);
        contain_child(casedir, timeout, pfd[1], cfd);
        child_out o = {fd, 0};
        sidx_hook h = {child_hook_fn, &o, 0};
        ck_watch_fd = wfd;
        for (size_t c = i; c <= last; ++c) {
            o.n = 0;
            ex_driver_this.student(c, &h);
            if (last > i) {
                sidx_event m = sidx_event_blank(SIDX_EV_NOTE);
                m.type = EX_CASE_END;
                m.node = (uint32_t)c;
                write_all(fd, &m, sizeof m);
            }
        }
        write_all(fd, done_mark, sizeof done_mark);
        fflush(stdout);
        _exit(0);
    }
    close(pfd[1]);
    /* Reads the output until the child closes it, within the time limit;
     * stops a child that writes too much or runs out of time. */
    const double deadline = now_s() + (cx.wall_cap > 0 && cx.wall_cap < timeout ? cx.wall_cap : timeout);
    size_t bytes = 0;
    int killed_output = 0, killed_time = 0, open_ = 1, st = 0, reaped = 0, busy = 0;
    double group_cpu = 0;
    char buf[65536];
    while (!reaped) {
        const double left = deadline - now_s();
        if (left <= 0) {
            /* before the kill: the student's process is a grandchild (the
             * sandbox's first process stands between), whose CPU time no
             * wait of ours would count once the group is killed */
            group_cpu = group_cpu_seconds(pid);
            kill(-pid, SIGKILL);
            kill(pid, SIGKILL);
            killed_time = 1;
            break;
        }
        if (open_) {
            struct pollfd p = {pfd[0], POLLIN, 0};
            const int r = poll(&p, 1, (int)(left * 1000) + 1);
            if (r < 0 && errno != EINTR) break;
            if (r <= 0) continue;
            const ssize_t k = read(pfd[0], buf, sizeof buf);
            if (k < 0 && errno == EINTR) continue;
            if (k <= 0) {
                open_ = 0;
                continue;
            }
            take_output(buf, (size_t)k);
            bytes += (size_t)k;
            if (bytes > EX_MAX_OUTPUT) {
                kill(-pid, SIGKILL);
                kill(pid, SIGKILL);
                killed_output = 1;
                break;
            }
        } else {
            const pid_t w = waitpid(pid, &st, WNOHANG);
            if (w == pid) reaped = 1;
            else if (w < 0 && errno != EINTR) break;
            else poll(NULL, 0, 1); /* it has closed its output: it is exiting */
        }
    }
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    if (!reaped)
        while (wait4(pid, &st, 0, &ru) < 0 && errno == EINTR) {
        }
    /* out of time: computing (an endless loop) if it used a fiftieth of
     * the time on the CPU (on a busy machine, a class checked two at a
     * time beside other work, a loop may get a tenth of a core), else
     * waiting (sleep, a read: a millisecond or two) */
    if (killed_time)
        busy = group_cpu + (double)ru.ru_utime.tv_sec + (double)ru.ru_stime.tv_sec +
                   1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) > 0.02 * timeout;
    kill(-pid, SIGKILL); /* whatever it left behind */
    close(pfd[0]);
    remove_tree(casedir);
    cx.alloc_failed[0] = '\0';
    take_attempts(wfd, i + 1);
    close(wfd);
    if (!killed_output && !killed_time && WIFEXITED(st) && WEXITSTATUS(st) == 5 && !shared->have_status &&
        shared->why[0]) {
        /* the child could not enter its directory or the sandbox */
        close(fd);
        close(cfd);
        fprintf(stderr, "sidx-check: cannot contain the case: %s\n", shared->why[0] ? shared->why : "?");
        errno = EPERM;
        return RUN_ERROR;
    }
    if (shared->have_status) st = shared->status; /* a signal the sandbox's init stood for */
    struct stat sb;
    run_status rs = RUN_OK;
    if (fstat(fd, &sb) != 0) {
        close(fd);
        close(cfd);
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
    *cpu = 0;
    cx.where[0] = '\0';
    if (killed_output) {
        rs = RUN_OUTPUT;
    } else if (killed_time) {
        rs = RUN_TIMEOUT;
        *cpu = busy;
    } else if (WIFSIGNALED(st)) {
        *sig = WTERMSIG(st);
        if (*sig == SIGALRM || *sig == SIGXCPU || *sig == SIGKILL) {
            rs = RUN_TIMEOUT;
            *cpu = *sig == SIGXCPU;
        } else if (*sig == SIGXFSZ) {
            rs = RUN_OUTPUT;
        } else {
            rs = RUN_CRASH;
            if (cx.locate) locate_crash(cfd);
        }
    } else if (WIFEXITED(st) && WEXITSTATUS(st) == 3) {
        rs = RUN_TOO_MANY;
    } else if (WIFEXITED(st) && WEXITSTATUS(st) == 4) {
        rs = RUN_OUTPUT; /* the events file refused a write: past RLIMIT_FSIZE */
    } else if (!WIFEXITED(st) || WEXITSTATUS(st) != 0 || !done) {
        *code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
        rs = RUN_CRASH;
    }
    char oom = 0;
    if (rs == RUN_CRASH && !EX_SANITIZED && pread(cfd, &oom, 1, 0) == 1 && oom) rs = RUN_MEMORY;
    if (rs == RUN_CRASH && cx.alloc_failed[0]) rs = RUN_MEMORY; /* a NULL from malloc, then written to */
    close(cfd);
    return rs;
}

/* ---- comparison ---------------------------------------------------------------- */

/* Appends to buf (size bytes, o used): the text is cut at the end of buf. */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
static void appendf(char *buf, size_t size, size_t *o, const char *fmt, ...)
{
    if (*o + 1 >= size) return;
    va_list ap;
    va_start(ap, fmt);
    const int w = vsnprintf(buf + *o, size - *o, fmt, ap);
    va_end(ap);
    if (w > 0) *o = *o + (size_t)w < size ? *o + (size_t)w : size - 1;
}

/* An id as the printer shows it: "none" for UINT32_MAX. */
static const char *u32_text(uint32_t v, char *buf)
{
    if (v == UINT32_MAX) return "none";
    snprintf(buf, 16, "%u", v);
    return buf;
}

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

/* The fields same_event compares that differ between a and b (events of
 * one type), as "t_near 0.5 vs 0.50000006, depth 0 vs 1": what tells two
 * diverging events apart when the printer shows them alike (it prints t
 * to 6 digits, and not every field).  Floats to 9 digits, enough to tell
 * any two floats apart.  Empty when the types differ. */
static void diff_fields(const sidx_event *a, const sidx_event *b, char *buf, size_t size)
{
    size_t o = 0;
    buf[0] = '\0';
    if (!a || !b || a->type != b->type) return;
#define DIFF_PUT(...) appendf(buf, size, &o, __VA_ARGS__)
#define DIFF_U(f)                                                                                                \
    if (a->f != b->f) DIFF_PUT("%s" #f " %s vs %s", o ? ", " : "", u32_text(a->f, ta), u32_text(b->f, tb))
#define DIFF_I(f)                                                                                                \
    if (a->f != b->f) DIFF_PUT("%s" #f " %d vs %d", o ? ", " : "", (int)a->f, (int)b->f)
#define DIFF_F(f)                                                                                                \
    if (!same_float(a->f, b->f)) DIFF_PUT("%s" #f " %.9g vs %.9g", o ? ", " : "", (double)a->f, (double)b->f)
#define DIFF_CELL()                                                                                              \
    if (a->cell[0] != b->cell[0] || a->cell[1] != b->cell[1] || a->cell[2] != b->cell[2])                        \
    DIFF_PUT("%scell (%d, %d, %d) vs (%d, %d, %d)", o ? ", " : "", a->cell[0], a->cell[1], a->cell[2], b->cell[0], \
             b->cell[1], b->cell[2])
    char ta[16], tb[16];
    switch (a->type) {
    case SIDX_EV_BOX_TEST:
        DIFF_U(node);
        DIFF_I(result);
        if (a->result == 1 && b->result == 1) {
            DIFF_F(t_near);
            DIFF_F(t_far);
        }
        break;
    case SIDX_EV_NODE_ENTER:
        DIFF_U(node);
        DIFF_U(depth);
        DIFF_F(t_near);
        DIFF_F(t_far);
        DIFF_CELL();
        break;
    case SIDX_EV_STACK_PUSH:
    case SIDX_EV_STACK_POP:
        DIFF_U(node);
        DIFF_U(depth);
        DIFF_F(t_near);
        DIFF_F(t_far);
        break;
    case SIDX_EV_PRIM_TEST:
        DIFF_U(prim);
        DIFF_I(result);
        if (a->result == 1 && b->result == 1) DIFF_F(t);
        break;
    case SIDX_EV_HIT_UPDATE:
        DIFF_U(prim);
        DIFF_F(t);
        break;
    case SIDX_EV_MAILBOX_HIT: DIFF_U(prim); break;
    case SIDX_EV_TERMINATE:
        DIFF_I(reason);
        DIFF_F(t);
        DIFF_U(count);
        break;
    case SIDX_EV_RAY_END:
        DIFF_U(prim);
        DIFF_F(t);
        DIFF_I(result);
        break;
    case SIDX_EV_RAY_BEGIN:
        DIFF_F(t_near);
        DIFF_F(t_far);
        break;
    case SIDX_EV_BUILD_CANDIDATE:
    case SIDX_EV_BUILD_SPLIT:
        DIFF_U(node);
        DIFF_I(axis);
        DIFF_F(pos);
        DIFF_F(cost);
        DIFF_U(count);
        DIFF_U(aux);
        break;
    case SIDX_EV_NOTE:
        DIFF_CELL();
        DIFF_U(count);
        DIFF_F(t_near);
        DIFF_F(t_far);
        break;
    default: break;
    }
#undef DIFF_PUT
#undef DIFF_U
#undef DIFF_I
#undef DIFF_F
#undef DIFF_CELL
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
            "                                 [--verbose] [--html FILE] | --rules\n"
            "  --case K        run only case K (1-based)\n"
            "  --trace DIR     write DIR/reference.jsonl and DIR/yours.jsonl for the first failing case\n"
            "                  (or for case K)\n"
            "  --html FILE     write the first failing case as a web page: both walks side by side\n"
            "  --viewer PATH   sidx-view, to print the commands that step through the traces\n"
            "  --timeout S     time limit per case (default 2 s)\n"
            "  --verbose       one line per case\n"
            "  --source FILE   the student's file (to name a crash's FILE:LINE)\n"
            "  --memory MB     memory per case (default %lu MiB)\n"
            "  --summary FILE  write the verdict as one tab-separated line: result, case, cases, step,\n"
            "                  case name, detail, hint, diagnosis, containment and attempts outside\n"
            "  --rules         print the exercise's rule table, one rule a line, tab-separated: id,\n"
            "                  statement, hint, the cases that test it (1-based, blank-separated)\n"
            "  --rules-out FILE  write that table to FILE, and check\n"
            "  --unsafe        run the code without the sandbox (the limits only)\n",
            EX_MEMORY_MB);
}

/* The verdict as one line of --summary FILE (for sidx-check --class). */
static const char *summary_path;

/* last: 1 ends the line, 0 a field, -1 neither */
static void put_field(FILE *f, const char *s, int last)
{
    for (; s && *s; ++s) fputc(*s == '\t' || *s == '\n' || *s == '\r' ? ' ' : *s, f);
    if (last >= 0) fputc(last ? '\n' : '\t', f);
}

/* The eighth field: the containment and the attempts outside, "" if
 * contained and none: "NOT CONTAINED; write /tmp/x (refused: ...); ...". */
static void put_attempts(FILE *f)
{
    if (cx.unsafe) fprintf(f, "NOT CONTAINED%s", cx.natt ? "; " : "");
    for (size_t k = 0; k < cx.natt; ++k) {
        char one[600];
        snprintf(one, sizeof one, "%s %s (%s%s)%s", cx.att[k].kind, cx.att[k].what,
                 strcmp(cx.att[k].result, "ok") ? "refused: " : cx.unsafe ? "done" : "kept inside",
                 strcmp(cx.att[k].result, "ok") ? cx.att[k].result : "",
                 k + 1 < cx.natt || cx.more_att ? "; " : "");
        put_field(f, one, -1);
    }
    if (cx.more_att) fprintf(f, "and %lu more", cx.more_att);
    fputc('\n', f);
}

static void write_summary(const char *result, size_t case_, size_t cases, size_t step, const char *name,
                          const char *detail, const char *hint, const char *diagnosis)
{
    if (!summary_path) return;
    FILE *f = fopen(summary_path, "w");
    if (!f) return;
    fprintf(f, "%s\t%zu\t%zu\t%zu\t", result, case_, cases, step);
    put_field(f, name, 0);
    put_field(f, detail, 0);
    put_field(f, hint, 0);
    put_field(f, diagnosis, 0);
    put_attempts(f);
    fclose(f);
}

/* ---- the rules and the diagnosis ------------------------------------------------------ */

/* After the first failing case the runner goes on through the battery, so
 * that the hint comes from the pattern of all failing cases (which rules'
 * cases fail) rather than from the first.  Those further cases run in one
 * child, one after another (run_rest), and cost at most EX_DIAG_CPU
 * seconds of CPU for the whole run, the runner and its children (a
 * passing check runs every case anyway, a child each); the run stops after
 * EX_DIAG_CRASHES of them crash or time out. */
#define EX_DIAG_CPU 1.2
#define EX_DIAG_MIN_WALL 0.2
#define EX_DIAG_CRASHES 8
/* A crash with this many frames of the crashing function in its backtrace
 * (of EX_CRASH_FRAMES) is a recursion that never reached its base case. */
#define EX_RECURSION_FRAMES 8

static double cpu_used(void)
{
    struct rusage a, b;
    getrusage(RUSAGE_SELF, &a);
    getrusage(RUSAGE_CHILDREN, &b);
    return (double)(a.ru_utime.tv_sec + a.ru_stime.tv_sec + b.ru_utime.tv_sec + b.ru_stime.tv_sec) +
           1e-6 * (double)(a.ru_utime.tv_usec + a.ru_stime.tv_usec + b.ru_utime.tv_usec + b.ru_stime.tv_usec);
}

/* The index of the rule named by the len characters at id, or -1. */
static long rule_index(const ex_driver *d, const char *id, size_t len)
{
    for (size_t r = 0; r < d->num_rules; ++r)
        if (strlen(d->rules[r].id) == len && !strncmp(d->rules[r].id, id, len)) return (long)r;
    return -1;
}

/* Marks in member[] (num_rules entries) the rules a case's list names;
 * returns 0, or -1 with the unknown id in bad. */
static int case_rules(const ex_driver *d, const char *list, unsigned char *member, char *bad, size_t bad_size)
{
    memset(member, 0, d->num_rules ? d->num_rules : 1);
    for (const char *p = list; p && *p;) {
        p += strspn(p, " \t,");
        const size_t len = strcspn(p, " \t,");
        if (!len) break;
        const long r = rule_index(d, p, len);
        if (r < 0) {
            snprintf(bad, bad_size, "%.*s", (int)(len < 100 ? len : 100), p);
            return -1;
        }
        member[r] = 1;
        p += len;
    }
    return 0;
}

typedef struct rule_count {
    size_t cases, run, failed;
} rule_count;

/* The rule that best explains the failing cases: the largest product of
 * the share of its cases that fail and the share of the failures that are
 * its cases (a rule whose every case fails and that accounts for every
 * failure scores 1); ties go to the rule with more failing cases, then to
 * the first in the table.  -1 when no failing case tests a rule. */
static long best_rule(const ex_driver *d, const rule_count *rc, size_t failed)
{
    long best = -1;
    double best_score = 0;
    for (size_t r = 0; r < d->num_rules; ++r) {
        if (!rc[r].failed || !rc[r].run) continue;
        const double score = ((double)rc[r].failed / (double)rc[r].run) * ((double)rc[r].failed / (double)failed);
        if (best < 0 || score > best_score + 1e-12 ||
            (score > best_score - 1e-12 && rc[r].failed > rc[best].failed)) {
            best = (long)r;
            best_score = score;
        }
    }
    return best;
}

/* One line: which rules' cases fail and how many, e.g.
 * rule tmin-inclusive ("t = tmin is a hit"): fails 4 of its 4 cases; 0 of the 83 other cases fail */
static void diagnosis_text(const ex_driver *d, const rule_count *rc, long best, size_t failed, size_t ran, size_t n,
                           long only, char *buf, size_t size)
{
    size_t o = 0;
#define DIAG_PUT(...) appendf(buf, size, &o, __VA_ARGS__)
    buf[0] = '\0';
    if (best >= 0) {
        const rule_count *b = &rc[best];
        DIAG_PUT("rule %s (\"%s\"): fails %zu of its %zu case%s; %zu of the %zu other cases fail", d->rules[best].id,
                 d->rules[best].statement, b->failed, b->run, b->run == 1 ? "" : "s", failed - b->failed,
                 ran - b->run);
        int also = 0;
        for (size_t r = 0; r < d->num_rules; ++r) {
            if ((long)r == best || !rc[r].failed) continue;
            if (also == 3) {
                DIAG_PUT(", ...");
                break;
            }
            DIAG_PUT("%s rule %s: %zu of %zu", also ? "," : "; also", d->rules[r].id, rc[r].failed, rc[r].run);
            ++also;
        }
    } else {
        DIAG_PUT("fails %zu of the %zu case%s run%s", failed, ran, ran == 1 ? "" : "s",
                 d->num_rules ? "; none of the failing cases tests a rule of the hand-out" : "");
    }
    if (only)
        DIAG_PUT(" (case %ld alone: --case)", only);
    else if (ran < n)
        DIAG_PUT(" (cases 1 to %zu of %zu run: past the first failure the checker stops after %d crashes or "
                 "time-outs, or %.1f s of CPU)",
                 ran, n, EX_DIAG_CRASHES, EX_DIAG_CPU);
#undef DIAG_PUT
}

/* --rules: the table, tab-separated, with the cases that test each rule;
 * exit 2 when a case names a rule the table lacks. */
static int print_rules(const ex_driver *d, FILE *out)
{
    const size_t n = d->num_cases();
    unsigned char *member = malloc(d->num_rules ? d->num_rules : 1);
    char **cases = calloc(d->num_rules ? d->num_rules : 1, sizeof *cases);
    size_t *len = calloc(d->num_rules ? d->num_rules : 1, sizeof *len);
    if (!member || !cases || !len) return 2;
    int rc = 0;
    for (size_t i = 0; i < n && rc == 0; ++i) {
        ex_case_info info;
        memset(&info, 0, sizeof info);
        d->describe(i, &info);
        char bad[128];
        if (case_rules(d, info.rules, member, bad, sizeof bad) != 0) {
            fprintf(stderr, "sidx-check %s: case %zu names the rule '%s', which the exercise's rule table lacks\n",
                    d->name, i + 1, bad);
            rc = 2;
            break;
        }
        for (size_t r = 0; r < d->num_rules; ++r) {
            if (!member[r]) continue;
            char num[24];
            const int w = snprintf(num, sizeof num, "%s%zu", len[r] ? " " : "", i + 1);
            char *grown = realloc(cases[r], len[r] + (size_t)w + 1);
            if (!grown) {
                rc = 2;
                break;
            }
            memcpy(grown + len[r], num, (size_t)w + 1);
            cases[r] = grown;
            len[r] += (size_t)w;
        }
    }
    for (size_t r = 0; r < d->num_rules && rc == 0; ++r) {
        put_field(out, d->rules[r].id, 0);
        put_field(out, d->rules[r].statement, 0);
        put_field(out, d->rules[r].hint, 0);
        put_field(out, cases[r] ? cases[r] : "", 1);
    }
    for (size_t r = 0; r < d->num_rules; ++r) free(cases[r]);
    free(cases);
    free(len);
    free(member);
    return rc;
}

/* ---- a case that does not return -------------------------------------------------------- */

/* The detail of a run that did not return (the report's "your code ..."
 * line) and its --summary result. */
static const char *failure_detail(run_status rs, int sig, int code, int cpu, unsigned timeout, const char *where,
                                  int where_is_student, const char *alloc_failed, char *detail, size_t size)
{
    if (rs == RUN_TIMEOUT && cpu) {
        snprintf(detail, size, "did not finish within %u s: it kept computing (an endless loop?)", timeout);
        return "timeout";
    }
    if (rs == RUN_TIMEOUT) {
        snprintf(detail, size, "did not finish within %u s: it was waiting (sleep? reading input?)", timeout);
        return "timeout";
    }
    if (rs == RUN_TOO_MANY) {
        snprintf(detail, size, "reported more than %u steps (an endless loop?)", EX_MAX_EVENTS);
        return "timeout";
    }
    if (rs == RUN_OUTPUT) {
        snprintf(detail, size,
                 "wrote too much: more than %u MiB of output in one case (a print in an endless loop?)",
                 EX_MAX_OUTPUT >> 20);
        return "output";
    }
    if (rs == RUN_MEMORY) {
        snprintf(detail, size, "ran out of memory (the limit is %lu MiB per case%s%s%s)%s%s%s%s", cx.memory_mb,
                 alloc_failed[0] ? "; " : "", alloc_failed, alloc_failed[0] ? " returned NULL" : "", sig ? ": " : "",
                 sig ? strsignal(sig) : "", where[0] ? " at " : "", where);
        return "memory";
    }
    if (sig && where[0])
        snprintf(detail, size, "crashed: signal %d (%s) at %s%s", sig, strsignal(sig), where,
                 where_is_student ? "" : " (outside your file)");
    else if (sig)
        snprintf(detail, size, "crashed: signal %d (%s)", sig, strsignal(sig));
    else
        snprintf(detail, size, "crashed: it stopped with exit status %d before returning", code);
    return "crash";
}

/* The hint for the kind of failure, or NULL when the kind says nothing
 * beyond the place (a fault at a line: the rules' and the case's hints
 * say more). */
static const char *failure_hint(run_status rs, int sig, int cpu, int recursion)
{
    switch (rs) {
    case RUN_TIMEOUT:
        return cpu ? "an endless loop: does every loop end? A stack that empties, an index that reaches its bound, "
                     "a walk that moves on to the next node or cell after each step"
                   : "your code waited: it must not sleep or read input";
    case RUN_TOO_MANY:
        return "far more steps than any case needs: the walk visits the same nodes or cells again and again "
               "(is each child pushed once? does each step move on?)";
    case RUN_OUTPUT:
        return "a print in a loop that does not end, or one on every step: print less, or run one case (--case K)";
    case RUN_MEMORY:
        return "an allocation beyond the limit: check the count given to malloc (negative, unset, or growing "
               "without end) and what your code does when malloc returns NULL";
    case RUN_CRASH:
        if (recursion >= EX_RECURSION_FRAMES)
            return "endless recursion (the stack overflowed): does the recursion reach its base case? Each call "
                   "must work on a smaller part (a child, a range that shrinks) and stop at a leaf";
        if (sig == SIGFPE) return "an integer division by zero at that line: which count is 0 in this case?";
        return NULL;
    default: return NULL;
    }
}

/* ---- the page of the first failing case (--html) --------------------------------------- */

/* viz/check_page.html with viz/page_common.js spliced in, as bytes
 * (sidx_check_page_html[], the Makefile writes it from the page). */
#include "check_page_html.inc"

#define EX_PAGE_DATA "\"@SIDX_CHECK_DATA@\""
#define EX_PAGE_MAX_TRIANGLES 20000u

/* s as a JSON string; '<' escaped, so no text closes the page's script. */
static void json_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; ++p) {
        if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
        else if (*p == '\n') fputs("\\n", f);
        else if (*p < 32 || *p == '<' || *p == 127) fprintf(f, "\\u%04x", *p);
        else fputc(*p, f);
    }
    fputc('"', f);
}

static void json_num(FILE *f, float v)
{
    if (isnan(v)) fputs("\"nan\"", f);
    else if (isinf(v)) fputs(v > 0 ? "\"inf\"" : "\"-inf\"", f);
    else fprintf(f, "%.9g", (double)v);
}

static void json_id(FILE *f, uint32_t v)
{
    if (v == UINT32_MAX) fputs("null", f);
    else fprintf(f, "%u", v);
}

static void event_line(const sidx_event *e, char *buf, size_t size)
{
    if (!ex_driver_this.format || !ex_driver_this.format(e, buf, size)) sidx_event_format(e, buf, size);
    size_t k = strspn(buf, " ");
    memmove(buf, buf + k, strlen(buf + k) + 1);
}

static void json_trace(FILE *f, const ex_trace *t)
{
    fputc('[', f);
    for (size_t k = 0; k < t->n; ++k) {
        const sidx_event *e = &t->ev[k];
        char line[512];
        event_line(e, line, sizeof line);
        fprintf(f, "%s\n{\"type\":", k ? "," : "");
        json_str(f, sidx_event_type_name(e->type));
        fputs(",\"node\":", f);
        json_id(f, e->node);
        fputs(",\"prim\":", f);
        json_id(f, e->prim);
        fprintf(f, ",\"result\":%d,\"t\":", (int)e->result);
        json_num(f, e->t);
        fputs(",\"t_near\":", f);
        json_num(f, e->t_near);
        fputs(",\"t_far\":", f);
        json_num(f, e->t_far);
        const sidx_aabb *b = &e->bounds;
        if (b->min.x <= b->max.x && b->min.y <= b->max.y && b->min.z <= b->max.z && isfinite(b->min.x) &&
            isfinite(b->max.x) && isfinite(b->min.y) && isfinite(b->max.y)) {
            const float v[6] = {b->min.x, b->min.y, b->min.z, b->max.x, b->max.y, b->max.z};
            fputs(",\"box\":[", f);
            for (int j = 0; j < 6; ++j) {
                if (j) fputc(',', f);
                json_num(f, v[j]);
            }
            fputc(']', f);
        }
        fputs(",\"line\":", f);
        json_str(f, line);
        fputc('}', f);
    }
    fputc(']', f);
}

typedef struct page_text {
    const char *result, *detail, *hint, *hint2, *hint2_label, *diagnosis, *differs;
    size_t case_, cases, step;
} page_text;

/* Writes the page of the first failing case: the template with its data
 * placeholder replaced by one JSON object (the case, both traces with
 * their printed lines, the step where they part, the hint, the scene's
 * triangles and the ray when the case has them).  0, or -1 with a
 * message on stderr. */
static int write_html(const char *path, const ex_case_info *info, const ex_trace *ref, const ex_trace *stu,
                      const page_text *pt)
{
    const char *tpl = (const char *)sidx_check_page_html;
    const char *hole = strstr(tpl, EX_PAGE_DATA);
    FILE *f = hole ? fopen(path, "w") : NULL;
    if (!f) {
        fprintf(stderr, "sidx-check: cannot write %s: %s\n", path, hole ? strerror(errno) : "no page template");
        return -1;
    }
    const ex_driver *d = &ex_driver_this;
    fwrite(tpl, 1, (size_t)(hole - tpl), f);
    fputs("{\"exercise\":", f);
    json_str(f, d->name);
    fputs(",\"title\":", f);
    json_str(f, d->title);
    fputs(",\"slide\":", f);
    json_str(f, d->slide);
    fprintf(f, ",\"case\":%zu,\"cases\":%zu,\"step\":%zu,\"result\":", pt->case_, pt->cases, pt->step);
    json_str(f, pt->result);
    fputs(",\"name\":", f);
    json_str(f, info->name);
    fputs(",\"input\":", f);
    json_str(f, info->what);
    fputs(",\"detail\":", f);
    json_str(f, pt->detail);
    fputs(",\"hint\":", f);
    json_str(f, pt->hint);
    fputs(",\"hint2\":", f);
    json_str(f, pt->hint2);
    fputs(",\"hint2_label\":", f);
    json_str(f, pt->hint2_label);
    fputs(",\"diagnosis\":", f);
    json_str(f, pt->diagnosis);
    fputs(",\"differs\":", f);
    json_str(f, pt->differs);
    fputs(",\"ray\":", f);
    if (info->view_ray) {
        const sidx_ray *r = info->view_ray;
        const float v[8] = {r->org.x, r->org.y, r->org.z, r->dir.x, r->dir.y, r->dir.z, r->tmin, r->tmax};
        fputc('[', f);
        for (int j = 0; j < 8; ++j) {
            if (j) fputc(',', f);
            json_num(f, v[j]);
        }
        fputc(']', f);
    } else {
        fputs("null", f);
    }
    /* the scene: the case's mesh, or its built-in scene */
    sidx_mesh opened;
    memset(&opened, 0, sizeof opened);
    const sidx_mesh *m = info->view_mesh;
    if (!m && info->view_scene) {
        sidx_error err;
        if (sidx_scene_open(info->view_scene, &opened, &err) == SIDX_OK) m = &opened;
    }
    fputs(",\"pos\":[", f);
    if (m && m->num_triangles <= EX_PAGE_MAX_TRIANGLES)
        for (uint32_t v = 0; v < m->num_vertices; ++v) {
            if (v) fputc(',', f);
            json_num(f, m->positions[v].x);
            fputc(',', f);
            json_num(f, m->positions[v].y);
            fputc(',', f);
            json_num(f, m->positions[v].z);
        }
    fputs("],\"idx\":[", f);
    if (m && m->num_triangles <= EX_PAGE_MAX_TRIANGLES)
        for (uint32_t k = 0; k < 3u * m->num_triangles; ++k) fprintf(f, k ? ",%u" : "%u", m->indices[k]);
    fputs("]", f);
    if (m == &opened) sidx_mesh_free(&opened);
    fputs(",\"ref\":", f);
    json_trace(f, ref);
    fputs(",\"yours\":", f);
    json_trace(f, stu);
    fputs("}", f);
    const char *rest = hole + strlen(EX_PAGE_DATA);
    fwrite(rest, 1, strlen(rest), f);
    if (fclose(f) != 0) {
        fprintf(stderr, "sidx-check: cannot write %s: %s\n", path, strerror(errno));
        return -1;
    }
    return 0;
}

/* How many events from the start agree: ref against stu's events
 * [from, to). */
static size_t agree_prefix(const ex_trace *ref, const ex_trace *stu, size_t from, size_t to)
{
    size_t k = 0;
    while (k < ref->n && from + k < to && same_event(&ref->ev[k], &stu->ev[from + k])) ++k;
    return k;
}

static size_t g_nr; /* the driver's num_rules, as count_case indexes member[] */

static void count_case(const unsigned char *member, rule_count *rcount, size_t i, int fails)
{
    for (size_t r = 0; r < g_nr; ++r)
        if (member[i * g_nr + r]) {
            ++rcount[r].run;
            rcount[r].failed += fails != 0;
        }
}

/* The cases from i on after the first failure, for the diagnosis: one
 * child runs them one after another (a child per case would cost most of
 * the time: fork's copy of the checker's memory), within the CPU left.
 * Each case that returns is compared with the reference; a crash ends the
 * run there (that case fails, the next run starts after it); a time-out
 * ends it without counting the case, which may only have been cut short by
 * the budget.  Returns the case to go on with (n: all done). */
static size_t run_rest(size_t i, size_t n, unsigned timeout, double left, ex_trace *stu, ex_trace *ref,
                       const unsigned char *member, rule_count *rcount, size_t *ran, size_t *failed,
                       size_t *crashes, int verbose)
{
    const ex_driver *d = &ex_driver_this;
    int sig = 0, code = 0, cpu = 0;
    cx.wall_cap = left < EX_DIAG_MIN_WALL ? EX_DIAG_MIN_WALL : left;
    const run_status rs = run_student(i, n - 1, timeout, stu, &sig, &code, &cpu);
    if (rs == RUN_ERROR) return n;
    size_t from = 0;
    for (size_t e = 0; e < stu->n && i < n; ++e) {
        if (stu->ev[e].type != EX_CASE_END) continue;
        if (stu->ev[e].node != i) return n; /* not the mark expected: the student's code wrote over the file */
        ref->n = 0;
        sidx_hook rh = {ex_trace_hook_fn, ref, 0};
        d->reference(i, &rh);
        const size_t k = agree_prefix(ref, stu, from, e);
        const int agree = k == ref->n && from + k == e;
        count_case(member, rcount, i, !agree);
        *failed += !agree;
        ++*ran;
        if (verbose) {
            ex_case_info info;
            memset(&info, 0, sizeof info);
            d->describe(i, &info);
            printf("case %3zu %-5s %s\n", i + 1, agree ? "ok" : "FAIL", info.name);
        }
        from = e + 1;
        ++i;
    }
    if (rs == RUN_OK || i >= n) return n;
    ++*crashes;
    if (rs == RUN_TIMEOUT) return n; /* cut short: case i is not counted, and the budget is spent */
    count_case(member, rcount, i, 1); /* a crash, out of memory, too many steps or too much output */
    ++*failed;
    ++*ran;
    if (verbose) printf("case %3zu CRASH\n", i + 1);
    return i + 1;
}

/* ---- main ------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    const ex_driver *d = &ex_driver_this;
    const char *trace_dir = NULL, *viewer = NULL, *html_path = NULL, *rules_out = NULL;
    unsigned timeout = 2;
    long only = 0;
    int verbose = 0, rules_only = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--trace") && i + 1 < argc) {
            trace_dir = argv[++i];
        } else if (!strcmp(argv[i], "--viewer") && i + 1 < argc) {
            viewer = argv[++i];
        } else if (!strcmp(argv[i], "--html") && i + 1 < argc) {
            html_path = argv[++i];
        } else if (!strcmp(argv[i], "--timeout") && i + 1 < argc) {
            timeout = (unsigned)strtoul(argv[++i], NULL, 10);
            if (timeout == 0) timeout = 1;
        } else if (!strcmp(argv[i], "--case") && i + 1 < argc) {
            only = strtol(argv[++i], NULL, 10);
        } else if (!strcmp(argv[i], "--verbose")) {
            verbose = 1;
        } else if (!strcmp(argv[i], "--rules")) {
            rules_only = 1;
        } else if (!strcmp(argv[i], "--rules-out") && i + 1 < argc) {
            rules_out = argv[++i];
        } else if (!strcmp(argv[i], "--unsafe")) {
            cx.unsafe = 1;
            snprintf(cx.why, sizeof cx.why, "--unsafe");
        } else if (!strcmp(argv[i], "--source") && i + 1 < argc) {
            cx.source = argv[++i];
        } else if (!strcmp(argv[i], "--summary") && i + 1 < argc) {
            summary_path = argv[++i];
        } else if (!strcmp(argv[i], "--memory") && i + 1 < argc) {
            cx.memory_mb = strtoul(argv[++i], NULL, 10);
            if (cx.memory_mb == 0) cx.memory_mb = EX_MEMORY_MB;
        } else if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        } else {
            usage(stderr);
            return 2;
        }
    }
    if (rules_only) {
        if (d->setup && d->setup() != 0) {
            fprintf(stderr, "sidx-check %s: the checker could not set up its scenes\n", d->name);
            return 2;
        }
        const int rc = print_rules(d, stdout);
        if (d->teardown) d->teardown();
        return rc;
    }
    if (cx.source && !realpath(cx.source, cx.source_real)) cx.source_real[0] = '\0';
    const ssize_t len = readlink("/proc/self/exe", cx.exe, sizeof cx.exe - 1);
    cx.exe[len > 0 ? len : 0] = '\0';
    snprintf(cx.dir, sizeof cx.dir, "/tmp/sidx-check-run-XXXXXX");
    if (!mkdtemp(cx.dir)) {
        fprintf(stderr, "sidx-check %s: cannot make a temporary directory: %s\n", d->name, strerror(errno));
        return 2;
    }
    chmod(cx.dir, 0711); /* the child, as nobody, reaches its case directory only */
    shared = mmap(NULL, sizeof *shared, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (shared == MAP_FAILED) {
        fprintf(stderr, "sidx-check %s: cannot map a shared page: %s\n", d->name, strerror(errno));
        return 2;
    }
    /* The sandbox, tried once before any case: where it cannot be set up
     * the verdict says so first */
    if (!cx.unsafe && (ck_sandbox_probe(cx.why, sizeof cx.why) != 0 || ck_sandbox_init(cx.why, sizeof cx.why) != 0))
        cx.unsafe = 1;
    if (cx.unsafe)
        printf("sidx-check %s: NOT CONTAINED: %s%s: your code runs with your own rights (it can read, write and "
               "connect wherever you can); only the time, memory, output and process limits hold\n",
               d->name, strcmp(cx.why, "--unsafe") ? "the sandbox cannot be set up here: " : "", cx.why);
    {
        void *warm[2]; /* loads the unwinder now: the crash handler runs where it cannot load it */
        (void)backtrace(warm, 2);
    }
    if (d->setup && d->setup() != 0) {
        fprintf(stderr, "sidx-check %s: the checker could not set up its scenes\n", d->name);
        return 2;
    }
    if (rules_out) { /* the table as --rules prints it, beside the check (the tests read it) */
        FILE *f = fopen(rules_out, "w");
        const int bad = !f || print_rules(d, f) != 0;
        if ((f && fclose(f) != 0) || bad) {
            fprintf(stderr, "sidx-check %s: cannot write the rule table to %s\n", d->name, rules_out);
            return 2;
        }
    }
    const size_t n = d->num_cases();
    if (only < 0 || (size_t)only > n) {
        fprintf(stderr, "sidx-check %s: --case wants 1..%zu\n", d->name, n);
        return 2;
    }
    /* which rules each case tests; a case naming a rule the table lacks is the checker's own fault */
    const size_t nr = d->num_rules;
    g_nr = nr;
    unsigned char *member = calloc(n * (nr ? nr : 1) + 1, 1);
    rule_count *rcount = calloc(nr ? nr : 1, sizeof *rcount);
    if (!member || !rcount) {
        fprintf(stderr, "sidx-check %s: out of memory\n", d->name);
        return 2;
    }
    for (size_t i = 0; i < n; ++i) {
        ex_case_info info;
        memset(&info, 0, sizeof info);
        d->describe(i, &info);
        char bad[128];
        if (case_rules(d, info.rules, member + i * (nr ? nr : 1), bad, sizeof bad) != 0) {
            fprintf(stderr, "sidx-check %s: case %zu names the rule '%s', which the exercise's rule table lacks\n",
                    d->name, i + 1, bad);
            return 2;
        }
        for (size_t r = 0; r < nr; ++r) rcount[r].cases += member[i * nr + r];
    }

    ex_trace ref = {0}, stu = {0}, fref = {0}, fstu = {0};
    int rc = 0;
    size_t steps = 0, ran = 0, failed = 0, diag_crashes = 0;
    /* the first failing case, reported in full */
    size_t first = SIZE_MAX, first_k = 0;
    run_status first_rs = RUN_OK;
    int first_sig = 0, first_code = 0, first_cpu = 0, first_where_is_student = 0, first_recursion = 0;
    char first_where[sizeof cx.where] = "";
    char first_alloc[sizeof cx.alloc_failed] = "";
    int traces_written = 0;
    for (size_t i = only ? (size_t)only - 1 : 0; i < (only ? (size_t)only : n);) {
        if (first != SIZE_MAX) { /* the rest, for the diagnosis */
            const double left = EX_DIAG_CPU - cpu_used();
            if (left <= 0 || diag_crashes >= EX_DIAG_CRASHES) break;
            i = run_rest(i, n, timeout, left, &stu, &ref, member, rcount, &ran, &failed, &diag_crashes, verbose);
            continue;
        }
        ex_case_info info;
        memset(&info, 0, sizeof info);
        d->describe(i, &info);
        ref.n = 0;
        sidx_hook rh = {ex_trace_hook_fn, &ref, 0};
        d->reference(i, &rh);
        int sig = 0, code = 0;
        int cpu = 0;
        const run_status rs = run_student(i, i, timeout, &stu, &sig, &code, &cpu);
        if (rs == RUN_ERROR) {
            fprintf(stderr, "sidx-check %s: cannot run case %zu: %s\n", d->name, i + 1, strerror(errno));
            rc = 2;
            break;
        }
        ++ran;
        size_t k = 0;
        int agree = 0;
        if (rs == RUN_OK) {
            k = agree_prefix(&ref, &stu, 0, stu.n);
            agree = k == ref.n && k == stu.n;
            steps += k;
        }
        count_case(member, rcount, i, !agree);
        if (verbose)
            printf("case %3zu %-5s %s\n", i + 1, agree ? "ok" : rs == RUN_OK ? "FAIL" : "CRASH", info.name);
        if (trace_dir && rs == RUN_OK && (!agree || only)) {
            /* not written: the report says so (write_jsonl said why) */
            traces_written = write_jsonl(trace_dir, "reference.jsonl", &ref) == 0 &&
                             write_jsonl(trace_dir, "yours.jsonl", &stu) == 0;
        }
        ++i;
        if (agree) continue;
        ++failed;
        /* the first failing case: keep its traces and what the run said */
        first = i - 1;
        first_k = k;
        first_rs = rs;
        first_sig = sig;
        first_code = code;
        first_cpu = cpu;
        first_recursion = cx.recursion;
        first_where_is_student = cx.where_is_student;
        snprintf(first_where, sizeof first_where, "%s", cx.where);
        snprintf(first_alloc, sizeof first_alloc, "%s", cx.alloc_failed);
        ex_trace t = fref;
        fref = ref;
        ref = t;
        t = fstu;
        fstu = stu;
        stu = t;
        cx.locate = 0;
    }
    if (rc == 0 && first != SIZE_MAX) {
        const size_t i = first, k = first_k;
        ex_case_info info;
        memset(&info, 0, sizeof info);
        d->describe(i, &info);
        /* the diagnosis, and the hints in their order (docs/exercises.md,
         * "Hints"): for a crash or time-out its kind's hint, else the hint
         * of the rule the failing cases point to; for a divergence the
         * rule's hint first when the rule accounts for every failing case,
         * else the driver's hint for the divergence (or the case's) first */
        const long best = best_rule(d, rcount, failed);
        char diagnosis[2048];
        diagnosis_text(d, rcount, best, failed, ran, n, only, diagnosis, sizeof diagnosis);
        const char *rule_hint = best >= 0 ? d->rules[best].hint : NULL;
        const int explains_all = best >= 0 && rcount[best].failed == failed;
        const sidx_event *re = k < fref.n ? &fref.ev[k] : NULL, *se = k < fstu.n ? &fstu.ev[k] : NULL;
        const char *hint = NULL, *hint2 = NULL, *hint2_label = NULL;
        char detail[sizeof cx.where + 200] = "", differs[1024] = "";
        const char *result = "fail";
        if (first_rs != RUN_OK) {
            result = failure_detail(first_rs, first_sig, first_code, first_cpu, timeout, first_where,
                                    first_where_is_student, first_alloc, detail, sizeof detail);
            const char *kind = failure_hint(first_rs, first_sig, first_cpu, first_recursion);
            /* a fault at a line: the rule of this case's that the pattern points to, else the case's own */
            const char *why = rule_hint && member[i * (nr ? nr : 1) + (size_t)best] ? rule_hint : NULL;
            for (size_t r = 0; !why && r < nr; ++r)
                if (member[i * nr + r]) why = d->rules[r].hint;
            if (!why) why = rule_hint ? rule_hint : info.hint;
            hint = kind ? kind : why;
            if (kind && why) {
                hint2 = why;
                hint2_label = "rule";
            }
        } else {
            const char *step_hint = d->hint ? d->hint(i, re, se) : NULL;
            if (!step_hint) step_hint = info.hint;
            if (explains_all || !step_hint) {
                hint = rule_hint ? rule_hint : step_hint;
                hint2 = rule_hint ? step_hint : NULL;
                hint2_label = "this step";
            } else {
                hint = step_hint;
                hint2 = rule_hint;
                hint2_label = "rule";
            }
            if (hint2 && hint && !strcmp(hint, hint2)) hint2 = NULL;
            /* the fields that differ, when the two events print alike */
            if (re && se) {
                char a[512], b[512];
                event_line(re, a, sizeof a);
                event_line(se, b, sizeof b);
                if (!strcmp(a, b)) diff_fields(re, se, differs, sizeof differs);
            }
        }
        print_student_output();
        print_attempts();
        if (first_rs != RUN_OK) {
            write_summary(result, i + 1, n, fstu.n, info.name, detail, hint, diagnosis);
            printf("sidx-check %s: case %zu of %zu, \"%s\":\n", d->name, i + 1, n, info.name);
            printf("  your code %s\n", detail);
            printf("  %-10s %s\n", "input", info.what);
            if (fstu.n) {
                printf("  the last steps your code reported (of %zu):\n", fstu.n);
                for (size_t j = fstu.n > 3 ? fstu.n - 3 : 0; j < fstu.n; ++j) print_event(stdout, "", &fstu.ev[j]);
            } else {
                printf("  it reported no step before that\n");
            }
        } else {
            write_summary("fail", i + 1, n, k + 1, info.name, info.what, hint, diagnosis);
            printf("sidx-check %s: case %zu of %zu, \"%s\": your trace leaves the reference at step %zu\n", d->name,
                   i + 1, n, info.name, k + 1);
            printf("  %-10s %s\n", "input", info.what);
            if (k > 0) {
                printf("  the steps before, which agree:\n");
                for (size_t j = k > 3 ? k - 3 : 0; j < k; ++j) print_event(stdout, "", &fref.ev[j]);
            }
            print_event(stdout, "reference", re);
            print_event(stdout, "yours", se);
            if (differs[0]) printf("  %-10s %s (reference vs yours)\n", "differs", differs);
        }
        printf("  %-10s %s\n", "diagnosis", diagnosis);
        if (hint) printf("  %-10s %s\n", "hint", hint);
        if (hint2) printf("  %-10s %s\n", hint2_label, hint2);
        printf("  %-10s %s\n", "slide", d->slide);
        if (first_rs == RUN_OK) {
            if (traces_written) {
                printf("  traces     %s/reference.jsonl and %s/yours.jsonl (sidx-step --diff A B)\n", trace_dir,
                       trace_dir);
                if (viewer && info.view_accel) print_view_commands(viewer, trace_dir, &info);
            } else if (trace_dir) {
                printf("  traces     not written (the message above says why)\n");
            } else {
                printf("  traces     add --trace DIR to write both as JSON Lines (sidx-step --diff A B%s)\n",
                       viewer && info.view_accel ? ", sidx-view --events" : "");
            }
        }
        if (html_path) {
            const page_text pt = {result, detail, hint, hint2, hint2_label, diagnosis, differs,
                                  i + 1, n, first_rs == RUN_OK ? k + 1 : fstu.n + 1}; /* a crash: the step that never came */
            if (write_html(html_path, &info, &fref, &fstu, &pt) == 0) printf("  %-10s %s\n", "page", html_path);
        }
        if (first_rs != RUN_OK) {
            printf("CRASH (exit 2)\n");
            rc = 2;
        } else {
            printf("FAIL (exit 1)\n");
            rc = 1;
        }
    }
    if (rc == 0) {
        print_student_output();
        print_attempts();
        write_summary("pass", 0, n, 0, "", "", NULL, NULL);
    }
    remove_tree(cx.dir);
    if (rc == 0)
        printf("sidx-check %s: all %zu case%s pass (%zu steps compared)\n", d->name, ran, ran == 1 ? "" : "s", steps);
    free(ref.ev);
    free(stu.ev);
    free(fref.ev);
    free(fstu.ev);
    free(member);
    free(rcount);
    if (d->teardown) d->teardown();
    return rc;
}
