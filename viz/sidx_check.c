/* sidx-check — check a student's exercise against the library, step by step.
 *
 *   sidx-check NAME FILE.c [--trace DIR] [--timeout S] [--memory MB] [--case K] [--verbose]
 *   sidx-check --class DIR [--jobs N] [--out DIR2] [--timeout S] [--memory MB]
 *   sidx-check --list
 *
 * Builds FILE.c against the library together with the exercise's checker
 * driver (lessons/exercises/check/NAME.c) and the runner, then runs it: the
 * runner compares the student's trace with the reference on the exercise's
 * battery and reports the first divergence (docs/exercises.md).
 * The student's code runs contained (the runner's child: limits, a
 * temporary directory, its output capped; docs/exercises.md).
 * --class checks a whole class: DIR holds one folder per student with any
 * of the exercise files (NAME.c); every file is checked, N at a time, and
 * a Markdown and a CSV summary and one report per student are written.
 * Exit status: 0 every case passes, 1 a divergence, 2 FILE does not build,
 * crashes or runs out of time (or a usage error).  --class: 0 every
 * submission passes, 1 some does not, 2 a usage error or the reports could
 * not be written. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef SIDX_CHECK_SRCDIR
#define SIDX_CHECK_SRCDIR "."
#endif
#ifndef SIDX_CHECK_SANFLAGS
#define SIDX_CHECK_SANFLAGS ""
#endif

typedef struct ex_entry { const char *name, *title; } ex_entry;
static const ex_entry exercises[] = {
#define EX(n, t) {n, t},
#include "../lessons/exercises/check/list.def"
#undef EX
};
#define NEX (sizeof exercises / sizeof exercises[0])

static void usage(FILE *f)
{
    fprintf(f,
            "usage: sidx-check NAME FILE.c [--trace DIR] [--timeout S] [--memory MB] [--case K] [--verbose]\n"
            "                             [--html FILE]\n"
            "       sidx-check --rules NAME\n"
            "       sidx-check --class DIR [--jobs N] [--out DIR2] [--timeout S] [--memory MB]\n"
            "       sidx-check --list\n"
            "\n"
            "Builds FILE.c (your solution of exercise NAME, e.g. lessons/exercises/NAME.c) against\n"
            "the library, runs it and the library's reference on the exercise's cases and compares\n"
            "the two traces event by event.  At the first divergence it prints the step, what the\n"
            "reference did, what your code did, the input and a hint from the slides.\n"
            "\n"
            "  --list          the exercises\n"
            "  --rules NAME    the rules exercise NAME's hand-out states, one a line, tab-separated:\n"
            "                  id, statement, hint, the cases that test each\n"
            "  --html FILE     write the failing case as a web page: the reference's steps and yours\n"
            "                  side by side over the case's scene, up to where they part, with the hint\n"
            "  --trace DIR     write DIR/reference.jsonl and DIR/yours.jsonl for the failing case\n"
            "                  (or for case K) as JSON Lines: compare them with sidx-step --diff; for\n"
            "                  a walk the report also prints the two sidx-view --events commands\n"
            "                  that step through each over its scene and structure (DIR and the\n"
            "                  directories above it are made)\n"
            "  --timeout S     time limit per case, seconds of CPU time and of wall time (default 2)\n"
            "  --memory MB     memory limit per case (default 1024)\n"
            "  --case K        run only case K\n"
            "  --verbose       one line per case\n"
            "  -h, --help      this help\n"
            "\n"
            "Your code runs in a child process in a temporary directory, with limits on CPU time,\n"
            "memory, output and processes; the first lines it prints are shown, the rest counted.\n"
            "\n"
            "Class mode, for a lecturer:\n"
            "  --class DIR     DIR holds one folder per student, each with any of the exercise files\n"
            "                  (NAME.c); checks every file and writes DIR2/summary.md, DIR2/summary.csv\n"
            "                  and DIR2/STUDENT.txt (each student's full report); prints the summary\n"
            "  --jobs N        checks at a time (default: the number of cores)\n"
            "  --out DIR2      where the reports go (default DIR/sidx-class-report)\n"
            "\n"
            "Exit status: 0 every case passes, 1 a divergence, 2 FILE does not build, crashes or\n"
            "loops (or a usage error).  --class: 0 every submission passes, 1 some does not, 2 a\n"
            "usage error.  Guide: docs/exercises.md.\n");
}

/* Runs argv; returns its exit status, or -1 if it could not be run or was
 * killed.  A CPU-time limit guards against a file that keeps the compiler
 * busy for ever (#include "/dev/zero"). */
static int run(char *const argv[])
{
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        struct rlimit cpu = {120, 121};
        setrlimit(RLIMIT_CPU, &cpu);
        execvp(argv[0], argv);
        fprintf(stderr, "sidx-check: cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    int st;
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR) return -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The build directory: the one holding bin/sidx-check. */
static int build_dir(char *out, size_t size)
{
    char exe[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) return -1;
    exe[n] = '\0';
    for (int k = 0; k < 2; ++k) {
        char *slash = strrchr(exe, '/');
        if (!slash) return -1;
        *slash = '\0';
    }
    snprintf(out, size, "%s", exe);
    return 0;
}

/* Splits words (the compiler command, the sanitizer flags) at blanks into
 * argv[n..], at most max entries in all; returns the new count.  CC may be
 * a command of several words, such as "ccache gcc", as make's CC is. */
static int add_words(char **argv, int n, int max, char *words)
{
    for (char *w = strtok(words, " \t"); w && n < max; w = strtok(NULL, " \t")) argv[n++] = w;
    return n;
}

/* Makes the directories above DIR (mkdir -p of its parent), so that --trace a/b works when a/
 * does not exist; the runner makes DIR itself when it writes the traces, and says so if it
 * cannot.  A parent that cannot be made is left for that message. */
static void make_parents(const char *dir)
{
    char path[PATH_MAX];
    if (snprintf(path, sizeof path, "%s", dir) >= (int)sizeof path) return;
    char *last = strrchr(path, '/');
    if (!last || last == path) return;
    *last = '\0';
    for (char *p = path + 1; *p; ++p) {
        if (*p != '/') continue;
        *p = '\0';
        if (mkdir(path, 0777) != 0 && errno != EEXIST) return;
        *p = '/';
    }
    (void)mkdir(path, 0777);
}

/* Checks FILE as exercise k: builds it, runs the runner with pass[];
 * returns 0/1/2.  summary: the runner's --summary file, or NULL. */
static int check_one(size_t k, const char *file, char **pass, int npass, const char *summary)
{
    const char *name = exercises[k].name;
    char real[PATH_MAX];
    if (access(file, R_OK) != 0 || !realpath(file, real)) {
        fprintf(stderr, "sidx-check: cannot read %s: %s\n", file, strerror(errno));
        return 2;
    }
    char bdir[PATH_MAX], tmp[] = "/tmp/sidx-check-XXXXXX";
    if (build_dir(bdir, sizeof bdir) != 0 || !mkdtemp(tmp)) {
        fprintf(stderr, "sidx-check: cannot set up a build directory: %s\n", strerror(errno));
        return 2;
    }
    char inc[PATH_MAX + 32], obj[PATH_MAX + 32], exe[PATH_MAX + 32], driver[2 * PATH_MAX], runner[2 * PATH_MAX],
        lib[2 * PATH_MAX], san[256];
    snprintf(inc, sizeof inc, "-I%s/lib/include", SIDX_CHECK_SRCDIR);
    snprintf(obj, sizeof obj, "%s/student.o", tmp);
    snprintf(exe, sizeof exe, "%s/check", tmp);
    snprintf(driver, sizeof driver, "%s/obj/lessons/exercises/check/%s.o", bdir, name);
    snprintf(runner, sizeof runner, "%s/obj/lessons/exercises/check/runner.o", bdir);
    snprintf(lib, sizeof lib, "%s/lib/libsidx.a", bdir);
    snprintf(san, sizeof san, "%s", SIDX_CHECK_SANFLAGS);
    /* CC may be several words ("ccache gcc"); blank or unset: cc */
    char cc[1024];
    const char *env_cc = getenv("CC");
    snprintf(cc, sizeof cc, "%s", env_cc && env_cc[strspn(env_cc, " \t")] ? env_cc : "cc");
    int rc = 2;
    {
        char *cv[48], ccw[sizeof cc];
        memcpy(ccw, cc, sizeof cc);
        int n = add_words(cv, 0, 8, ccw);
        const char *fixed[] = {"-std=c11", "-g", "-O1", "-Wall", "-Wextra", "-ffp-contract=off", "-D_DEFAULT_SOURCE"};
        for (size_t j = 0; j < sizeof fixed / sizeof fixed[0]; ++j) cv[n++] = (char *)fixed[j];
        cv[n++] = inc;
        n = add_words(cv, n, 40, san);
        cv[n++] = "-c";
        cv[n++] = real; /* the debug information names the file by its real path: a crash's file:line */
        cv[n++] = "-o";
        cv[n++] = obj;
        cv[n] = NULL;
        if (run(cv) != 0) {
            printf("sidx-check %s: %s does not build (the compiler's messages are above)\nBUILD FAILED (exit 2)\n",
                   name, file);
            goto build_failed;
        }
    }
    {
        char *lv[48], ccw[sizeof cc];
        memcpy(ccw, cc, sizeof cc);
        int n = add_words(lv, 0, 8, ccw);
        snprintf(san, sizeof san, "%s", SIDX_CHECK_SANFLAGS);
        lv[n++] = obj;
        lv[n++] = driver;
        lv[n++] = runner;
        lv[n++] = lib;
        n = add_words(lv, n, 40, san);
        lv[n++] = "-pthread";
        lv[n++] = "-lm";
        lv[n++] = "-o";
        lv[n++] = exe;
        lv[n] = NULL;
        if (run(lv) != 0) {
            printf("sidx-check %s: %s does not link with the checker: does it define every function the "
                   "exercise asks for, with the stub's names? (the linker's messages are above)\n"
                   "BUILD FAILED (exit 2)\n",
                   name, file);
            goto build_failed;
        }
    }
    {
        char *rv[40], viewer[PATH_MAX + 32];
        int n = 0;
        rv[n++] = exe;
        for (int j = 0; j < npass; ++j) rv[n++] = pass[j];
        rv[n++] = "--source";
        rv[n++] = (char *)file;
        if (summary) {
            rv[n++] = "--summary";
            rv[n++] = (char *)summary;
        }
        snprintf(viewer, sizeof viewer, "%s/bin/sidx-view", bdir); /* built only with SDL2 */
        if (access(viewer, X_OK) == 0) {
            rv[n++] = "--viewer";
            rv[n++] = viewer;
        }
        rv[n] = NULL;
        const int st = run(rv);
        rc = (st >= 0 && st <= 2) ? st : 2;
        if (rc == 2 && summary) { /* the runner could not say why: a line all the same */
            struct stat sb;
            if (stat(summary, &sb) != 0 || sb.st_size == 0) {
                FILE *f = fopen(summary, "w");
                if (f) {
                    fprintf(f, "error\t0\t0\t0\t\tthe checker stopped with status %d\t\n", st);
                    fclose(f);
                }
            }
        }
    }
    goto done;
build_failed:
    if (summary) {
        FILE *f = fopen(summary, "w");
        if (f) {
            fprintf(f, "build\t0\t0\t0\t\tdoes not build\t\n");
            fclose(f);
        }
    }
done:
    unlink(obj);
    unlink(exe);
    rmdir(tmp);
    return rc;
}

/* ---- class mode ----------------------------------------------------------------- */

typedef struct class_job {
    size_t student, ex;
    char report[2 * PATH_MAX + 64], summary[2 * PATH_MAX + 64];
    int rc;
    /* from the summary line */
    char result[16], case_name[200], detail[2400], hint[1024];
    unsigned long case_, cases, step;
} class_job;

static int by_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static int mkdir_p(const char *path)
{
    char buf[PATH_MAX];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + 1; *p; ++p)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) return -1;
            *p = '/';
        }
    return mkdir(buf, 0777) != 0 && errno != EEXIST ? -1 : 0;
}

/* A field of the summary line, tab-separated (the last ends at the newline). */
static char *next_field(char **p)
{
    char *s = *p, *e = s + strcspn(s, "\t\n");
    *p = *e ? e + 1 : e;
    *e = '\0';
    return s;
}

static void read_summary(class_job *j)
{
    snprintf(j->result, sizeof j->result, "error");
    FILE *f = fopen(j->summary, "r");
    char line[8192];
    if (!f) return;
    if (fgets(line, sizeof line, f)) {
        char *p = line;
        snprintf(j->result, sizeof j->result, "%.15s", next_field(&p));
        j->case_ = strtoul(next_field(&p), NULL, 10);
        j->cases = strtoul(next_field(&p), NULL, 10);
        j->step = strtoul(next_field(&p), NULL, 10);
        snprintf(j->case_name, sizeof j->case_name, "%s", next_field(&p));
        snprintf(j->detail, sizeof j->detail, "%s", next_field(&p));
        snprintf(j->hint, sizeof j->hint, "%s", next_field(&p));
    }
    fclose(f);
    unlink(j->summary);
}

/* A short cell of the Markdown table. */
static void cell(const class_job *j, char *buf, size_t size)
{
    if (!strcmp(j->result, "pass")) snprintf(buf, size, "pass");
    else if (!strcmp(j->result, "fail")) snprintf(buf, size, "case %lu, step %lu", j->case_, j->step);
    else if (!strcmp(j->result, "build")) snprintf(buf, size, "build failed");
    else if (!strcmp(j->result, "timeout")) snprintf(buf, size, "time-out, case %lu", j->case_);
    else if (!strcmp(j->result, "memory")) snprintf(buf, size, "out of memory, case %lu", j->case_);
    else if (!strcmp(j->result, "output")) snprintf(buf, size, "too much output, case %lu", j->case_);
    else if (!strcmp(j->result, "crash")) {
        const char *at = strstr(j->detail, " at ");
        const char *slash = NULL;
        if (at) { /* the file's base name and line */
            char where[256];
            snprintf(where, sizeof where, "%s", at + 4);
            where[strcspn(where, ",")] = '\0';
            slash = strrchr(where, '/');
            snprintf(buf, size, "crash at %s, case %lu", slash ? slash + 1 : where, j->case_);
        } else {
            snprintf(buf, size, "crash, case %lu", j->case_);
        }
    } else snprintf(buf, size, "%s", j->result);
}

static void md_text(FILE *f, const char *s)
{
    for (; *s; ++s) {
        if (*s == '|') fputc('\\', f);
        fputc(*s, f);
    }
}

static void csv_field(FILE *f, const char *s, int last)
{
    fputc('"', f);
    for (; *s; ++s) {
        if (*s == '"') fputc('"', f);
        fputc(*s, f);
    }
    fputc('"', f);
    fputc(last ? '\n' : ',', f);
}

static int class_mode(const char *dir, const char *out_arg, long jobs, char **pass, int npass)
{
    char out[PATH_MAX], real_out[PATH_MAX], real_dir[PATH_MAX];
    if (out_arg) snprintf(out, sizeof out, "%s", out_arg);
    else snprintf(out, sizeof out, "%s/sidx-class-report", dir);
    DIR *d = opendir(dir);
    if (!d || !realpath(dir, real_dir)) {
        fprintf(stderr, "sidx-check: cannot read the class directory %s: %s\n", dir, strerror(errno));
        if (d) closedir(d);
        return 2;
    }
    if (mkdir_p(out) != 0 || !realpath(out, real_out)) {
        fprintf(stderr, "sidx-check: cannot make %s: %s\n", out, strerror(errno));
        closedir(d);
        return 2;
    }
    /* the students: DIR's folders, the report's own excepted */
    char **students = NULL;
    size_t ns = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char path[PATH_MAX], real[PATH_MAX];
        struct stat sb;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (stat(path, &sb) != 0 || !S_ISDIR(sb.st_mode) || !realpath(path, real) || !strcmp(real, real_out)) continue;
        char **grown = realloc(students, (ns + 1) * sizeof *students);
        if (!grown) break;
        students = grown;
        students[ns++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(students, ns, sizeof *students, by_name);
    class_job *job = calloc(ns * NEX + 1, sizeof *job);
    size_t nj = 0;
    for (size_t s = 0; s < ns; ++s)
        for (size_t k = 0; k < NEX; ++k) {
            char file[PATH_MAX];
            snprintf(file, sizeof file, "%s/%s/%s.c", dir, students[s], exercises[k].name);
            if (access(file, F_OK) != 0) continue;
            class_job *j = &job[nj++];
            j->student = s;
            j->ex = k;
            snprintf(j->report, sizeof j->report, "%s/.%s--%s.txt", out, students[s], exercises[k].name);
            snprintf(j->summary, sizeof j->summary, "%s/.%s--%s.sum", out, students[s], exercises[k].name);
        }
    fprintf(stderr, "sidx-check: %zu students, %zu files, %ld at a time\n", ns, nj, jobs);
    /* the checks, jobs at a time: each a child that runs check_one */
    size_t next = 0, running = 0, finished = 0;
    pid_t *pids = calloc(nj + 1, sizeof *pids);
    while (finished < nj) {
        if (running < (size_t)jobs && next < nj) {
            class_job *j = &job[next];
            fflush(stdout);
            fflush(stderr);
            const pid_t pid = fork();
            if (pid == 0) {
                const int fd = open(j->report, O_WRONLY | O_CREAT | O_TRUNC, 0644), null = open("/dev/null", O_RDONLY);
                if (fd < 0 || null < 0) _exit(2);
                dup2(null, 0);
                dup2(fd, 1);
                dup2(fd, 2);
                close(fd);
                close(null);
                char file[PATH_MAX];
                snprintf(file, sizeof file, "%s/%s/%s.c", dir, students[j->student], exercises[j->ex].name);
                printf("$ sidx-check %s %s\n", exercises[j->ex].name, file);
                const int rc = check_one(j->ex, file, pass, npass, j->summary);
                fflush(stdout);
                _exit(rc);
            }
            if (pid < 0) {
                j->rc = 2;
                ++finished;
            } else {
                pids[next] = pid;
                ++running;
            }
            ++next;
            continue;
        }
        int st;
        const pid_t pid = wait(&st);
        if (pid < 0) {
            if (errno == EINTR) continue;
            break;
        }
        for (size_t k = 0; k < next; ++k)
            if (pids[k] == pid) {
                job[k].rc = WIFEXITED(st) ? WEXITSTATUS(st) : 2;
                pids[k] = 0;
                --running;
                ++finished;
                fprintf(stderr, "\r  %zu of %zu checked", finished, nj);
            }
    }
    fprintf(stderr, "\n");
    int rc = 0;
    for (size_t k = 0; k < nj; ++k) {
        read_summary(&job[k]);
        if (strcmp(job[k].result, "pass") != 0) rc = 1;
    }
    /* each student's full report: their checks one after the other */
    for (size_t s = 0; s < ns; ++s) {
        char path[2 * PATH_MAX + 8];
        snprintf(path, sizeof path, "%s/%s.txt", out, students[s]);
        FILE *f = fopen(path, "w");
        if (!f) {
            fprintf(stderr, "sidx-check: cannot write %s: %s\n", path, strerror(errno));
            rc = 2;
            continue;
        }
        fprintf(f, "sidx-check report of %s\n\n", students[s]);
        int any = 0;
        for (size_t k = 0; k < nj; ++k) {
            if (job[k].student != s) continue;
            any = 1;
            FILE *r = fopen(job[k].report, "r");
            char buf[8192];
            size_t got;
            while (r && (got = fread(buf, 1, sizeof buf, r)) > 0) fwrite(buf, 1, got, f);
            if (r) fclose(r);
            unlink(job[k].report);
            fprintf(f, "\n");
        }
        if (!any) fprintf(f, "no exercise file (NAME.c) in this folder\n");
        fclose(f);
    }
    /* the summaries */
    char mdpath[PATH_MAX + 16], csvpath[PATH_MAX + 16];
    snprintf(mdpath, sizeof mdpath, "%s/summary.md", out);
    snprintf(csvpath, sizeof csvpath, "%s/summary.csv", out);
    FILE *md = fopen(mdpath, "w"), *csv = fopen(csvpath, "w");
    if (!md || !csv) {
        fprintf(stderr, "sidx-check: cannot write the summaries in %s: %s\n", out, strerror(errno));
        if (md) fclose(md);
        if (csv) fclose(csv);
        return 2;
    }
    fprintf(csv, "student,exercise,result,case,cases,step,case_name,detail,hint,report\n");
    int used[NEX] = {0};
    for (size_t k = 0; k < nj; ++k) used[job[k].ex] = 1;
    fprintf(md, "# sidx-check: class %s\n\n%zu students, %zu files checked.\n\n| student |", dir, ns, nj);
    for (size_t x = 0; x < NEX; ++x)
        if (used[x]) fprintf(md, " %s |", exercises[x].name);
    fprintf(md, "\n|---|");
    for (size_t x = 0; x < NEX; ++x)
        if (used[x]) fprintf(md, "---|");
    fprintf(md, "\n");
    for (size_t s = 0; s < ns; ++s) {
        fprintf(md, "| ");
        md_text(md, students[s]);
        fprintf(md, " |");
        for (size_t x = 0; x < NEX; ++x) {
            if (!used[x]) continue;
            const class_job *j = NULL;
            for (size_t k = 0; k < nj && !j; ++k)
                if (job[k].student == s && job[k].ex == x) j = &job[k];
            char c[300];
            if (j) cell(j, c, sizeof c);
            else snprintf(c, sizeof c, "\u2013");
            fprintf(md, " ");
            md_text(md, c);
            fprintf(md, " |");
        }
        fprintf(md, "\n");
    }
    fprintf(md, "\n| exercise | submitted | pass |\n|---|---|---|\n");
    for (size_t x = 0; x < NEX; ++x) {
        if (!used[x]) continue;
        int sub = 0, ok = 0;
        for (size_t k = 0; k < nj; ++k)
            if (job[k].ex == x) {
                ++sub;
                ok += !strcmp(job[k].result, "pass");
            }
        fprintf(md, "| %s | %d | %d |\n", exercises[x].name, sub, ok);
    }
    fprintf(md, "\n## What did not pass\n\n");
    for (size_t k = 0; k < nj; ++k) {
        const class_job *j = &job[k];
        char num[3][24];
        snprintf(num[0], sizeof num[0], "%lu", j->case_);
        snprintf(num[1], sizeof num[1], "%lu", j->cases);
        snprintf(num[2], sizeof num[2], "%lu", j->step);
        char rep[PATH_MAX + 8];
        snprintf(rep, sizeof rep, "%s.txt", students[j->student]);
        csv_field(csv, students[j->student], 0);
        csv_field(csv, exercises[j->ex].name, 0);
        csv_field(csv, j->result, 0);
        csv_field(csv, num[0], 0);
        csv_field(csv, num[1], 0);
        csv_field(csv, num[2], 0);
        csv_field(csv, j->case_name, 0);
        csv_field(csv, j->detail, 0);
        csv_field(csv, j->hint, 0);
        csv_field(csv, rep, 1);
        if (!strcmp(j->result, "pass")) continue;
        fprintf(md, "- **");
        md_text(md, students[j->student]);
        fprintf(md, "**, `%s`: ", exercises[j->ex].name);
        if (!strcmp(j->result, "fail")) {
            fprintf(md, "case %lu of %lu, \"", j->case_, j->cases);
            md_text(md, j->case_name);
            fprintf(md, "\": leaves the reference at step %lu", j->step);
            if (j->hint[0]) {
                fprintf(md, "; hint: ");
                md_text(md, j->hint);
            }
        } else if (!strcmp(j->result, "build")) {
            fprintf(md, "does not build");
        } else {
            if (j->case_) fprintf(md, "case %lu of %lu: ", j->case_, j->cases);
            fprintf(md, "your code ");
            md_text(md, j->detail);
        }
        fprintf(md, " ([report](");
        md_text(md, rep);
        fprintf(md, "))\n");
    }
    fclose(md);
    fclose(csv);
    /* the summary on stdout */
    FILE *f = fopen(mdpath, "r");
    char buf[8192];
    size_t got;
    while (f && (got = fread(buf, 1, sizeof buf, f)) > 0) fwrite(buf, 1, got, stdout);
    if (f) fclose(f);
    printf("\nreports: %s/summary.md, %s/summary.csv, %s/STUDENT.txt\n", out, out, out);
    for (size_t s = 0; s < ns; ++s) free(students[s]);
    free(students);
    free(job);
    free(pids);
    return rc;
}

int main(int argc, char **argv)
{
    const char *name = NULL, *file = NULL, *class_dir = NULL, *out = NULL, *summary = NULL, *rules = NULL;
    long jobs = sysconf(_SC_NPROCESSORS_ONLN);
    char *pass[20];
    int npass = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--list")) {
            for (size_t k = 0; k < NEX; ++k) printf("%-20s %s\n", exercises[k].name, exercises[k].title);
            return 0;
        } else if ((!strcmp(a, "--trace") || !strcmp(a, "--timeout") || !strcmp(a, "--case") || !strcmp(a, "--memory") ||
                    !strcmp(a, "--html") || !strcmp(a, "--rules-out")) &&
                   i + 1 < argc) {
            if (npass > 12) return 2;
            if (!strcmp(a, "--trace")) make_parents(argv[i + 1]);
            pass[npass++] = argv[i];
            pass[npass++] = argv[++i];
        } else if (!strcmp(a, "--verbose")) {
            if (npass > 12) return 2;
            pass[npass++] = argv[i];
        } else if (!strcmp(a, "--rules") && i + 1 < argc) {
            rules = argv[++i];
        } else if (!strcmp(a, "--class") && i + 1 < argc) {
            class_dir = argv[++i];
        } else if (!strcmp(a, "--out") && i + 1 < argc) {
            out = argv[++i];
        } else if (!strcmp(a, "--summary") && i + 1 < argc) {
            summary = argv[++i];
        } else if (!strcmp(a, "--jobs") && i + 1 < argc) {
            char *end;
            jobs = strtol(argv[++i], &end, 10);
            if (*end || jobs < 1 || jobs > 1024) {
                fprintf(stderr, "sidx-check: --jobs wants a number from 1 to 1024\n");
                return 2;
            }
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "sidx-check: unknown option or missing value: %s\n", a);
            usage(stderr);
            return 2;
        } else if (!name) {
            name = a;
        } else if (!file) {
            file = a;
        } else {
            fprintf(stderr, "sidx-check: too many arguments ('%s')\n", a);
            return 2;
        }
    }
    if (jobs < 1) jobs = 1;
    if (rules) { /* the rule table, from the checker built with the reference solution (else the stub) */
        if (name || file || class_dir) {
            fprintf(stderr, "sidx-check: --rules NAME takes no other NAME, FILE or --class\n");
            return 2;
        }
        size_t k = 0;
        while (k < NEX && strcmp(exercises[k].name, rules) != 0) ++k;
        if (k == NEX) {
            fprintf(stderr, "sidx-check: no exercise named '%s' (sidx-check --list)\n", rules);
            return 2;
        }
        char src[PATH_MAX];
        snprintf(src, sizeof src, "%s/lessons/exercises/solutions/%s.c", SIDX_CHECK_SRCDIR, rules);
        if (access(src, R_OK) != 0) snprintf(src, sizeof src, "%s/lessons/exercises/%s.c", SIDX_CHECK_SRCDIR, rules);
        char *rv[] = {"--rules"};
        return check_one(k, src, rv, 1, NULL);
    }
    if (class_dir) {
        if (name) {
            fprintf(stderr, "sidx-check: --class takes no NAME or FILE\n");
            return 2;
        }
        for (int j = 0; j < npass; ++j)
            if (!strcmp(pass[j], "--trace") || !strcmp(pass[j], "--case")) {
                fprintf(stderr, "sidx-check: --class checks whole files: no %s (check one student's file for that)\n",
                        pass[j]);
                return 2;
            }
        return class_mode(class_dir, out, jobs, pass, npass);
    }
    if (!name || !file) {
        fprintf(stderr, "sidx-check: NAME and FILE.c are required\n");
        usage(stderr);
        return 2;
    }
    size_t k = 0;
    while (k < NEX && strcmp(exercises[k].name, name) != 0) ++k;
    if (k == NEX) {
        fprintf(stderr, "sidx-check: no exercise named '%s'; the exercises are:\n", name);
        for (k = 0; k < NEX; ++k) fprintf(stderr, "  %s\n", exercises[k].name);
        return 2;
    }
    return check_one(k, file, pass, npass, summary);
}
