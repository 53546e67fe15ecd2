/* sidx-check — check a student's exercise against the library, step by step.
 *
 *   sidx-check NAME FILE.c [--trace DIR] [--timeout S] [--memory MB] [--case K] [--verbose] [--unsafe]
 *   sidx-check --class DIR [--jobs N] [--out DIR2] [--timeout S] [--memory MB] [--unsafe]
 *   sidx-check --list
 *
 * Builds FILE.c against the library together with the exercise's checker
 * driver (lessons/exercises/check/NAME.c), the runner, the sandbox and the
 * watch of calls outside (sandbox.c, watch.c, linked with --wrap), then
 * runs it: the runner compares the student's trace with the reference on
 * the exercise's battery and reports the first divergence
 * (docs/exercises.md).  Before linking, the object's symbols are checked
 * against what the exercise lets it call (borrowed.c, symbols.def).
 * The student's code runs contained (the runner's child: limits, a
 * temporary directory as its root, Linux namespaces, its output capped;
 * docs/exercises.md).  --class (class_mode.c) checks a whole class: DIR
 * holds one folder per student with any of the exercise files (NAME.c);
 * every file is checked, N at a time, and a Markdown and a CSV summary
 * and one report per student are written; it runs only where the sandbox
 * can be set up, unless --unsafe.
 * Exit status: 0 every case passes, 1 a divergence or a borrowed answer,
 * 2 FILE does not build, crashes or runs out of time (or a usage error).
 * --class: 0 every submission passes, 1 some does not, 2 a usage error,
 * no sandbox, or the reports could not be written. */
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
#include "borrowed.h"
#include "sandbox.h"
#include "class_mode.h"

#ifndef SIDX_CHECK_SRCDIR
#define SIDX_CHECK_SRCDIR "."
#endif
#ifndef SIDX_CHECK_SANFLAGS
#define SIDX_CHECK_SANFLAGS ""
#endif


static void usage(FILE *f)
{
    fprintf(f,
            "usage: sidx-check NAME FILE.c [--trace DIR] [--timeout S] [--memory MB] [--case K] [--verbose]\n"
            "                             [--html FILE] [--unsafe]\n"
            "       sidx-check --rules NAME\n"
            "       sidx-check --class DIR [--jobs N] [--out DIR2] [--timeout S] [--memory MB] [--unsafe]\n"
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
            "  --unsafe        run the code without the sandbox (the limits only); --class: run the\n"
            "                  class even where the sandbox cannot be set up\n"
            "  -h, --help      this help\n"
            "\n"
            "Your code runs in a child process in a temporary directory, with limits on CPU time,\n"
            "memory, output and processes, in a sandbox (Linux namespaces: no file outside the\n"
            "directory, no network, root or not); its attempts outside are listed; the first lines\n"
            "it prints are shown, the rest counted.\n"
            "\n"
            "Class mode, for a lecturer:\n"
            "  --class DIR     DIR holds one folder per student, each with any of the exercise files\n"
            "                  (NAME.c); checks every file and writes DIR2/summary.md, DIR2/summary.csv\n"
            "                  and DIR2/STUDENT.txt (each student's full report); prints the summary\n"
            "  --jobs N        checks at a time (default: the number of cores)\n"
            "  --out DIR2      where the reports go (default DIR/sidx-class-report)\n"
            "\n"
            "Exit status: 0 every case passes, 1 a divergence or a borrowed answer (a call of the\n"
            "library's own answer: docs/exercises.md), 2 FILE does not build, crashes or\n"
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
    const char *name = ck_exercises[k].name;
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
        lib[2 * PATH_MAX], san[256], sandbox[2 * PATH_MAX], watch[2 * PATH_MAX];
    snprintf(inc, sizeof inc, "-I%s/lib/include", SIDX_CHECK_SRCDIR);
    snprintf(obj, sizeof obj, "%s/student.o", tmp);
    snprintf(exe, sizeof exe, "%s/check", tmp);
    snprintf(driver, sizeof driver, "%s/obj/lessons/exercises/check/%s.o", bdir, name);
    snprintf(runner, sizeof runner, "%s/obj/lessons/exercises/check/runner.o", bdir);
    snprintf(sandbox, sizeof sandbox, "%s/obj/lessons/exercises/check/sandbox.o", bdir);
    snprintf(watch, sizeof watch, "%s/obj/lessons/exercises/check/watch.o", bdir);
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
        /* No borrowed answers: the object's symbols against symbols.def,
         * before anything runs (borrowed.c) */
        char first[1024], *lines = NULL;
        size_t len = 0;
        FILE *mem = open_memstream(&lines, &len);
        const int nb = mem ? ck_borrowed(name, obj, mem, first, sizeof first) : -1;
        if (mem) fclose(mem);
        if (nb < 0) {
            printf("sidx-check %s: cannot read the symbols of the compiled %s (not ELF, and no nm to ask)\n"
                   "BUILD FAILED (exit 2)\n", name, file);
            free(lines);
            goto build_failed;
        }
        if (nb > 0) {
            printf("sidx-check %s: your code %s\n", name, first);
            if (nb > 1) {
                printf("  and:\n");
                const char *p = strchr(lines, '\n');
                for (p = p ? p + 1 : ""; *p;) {
                    const size_t w = strcspn(p, "\n");
                    printf("    %.*s\n", (int)w, p);
                    p += w + (p[w] == '\n');
                }
            }
            const ck_symbols *sy = ck_symbols_of(name);
            printf("  of the library this exercise lets your code call %s%s (and the C library);\n"
                   "  what it asks you to write is yours to write (docs/exercises.md, \"No borrowed answers\";\n"
                   "  decided on the compiled object: every function it calls, however the source names it)\n"
                   "BORROWED (exit 1)\n",
                   sy && sy->may_call[0] ? "only: " : "nothing but the headers' inline helpers",
                   sy && sy->may_call[0] ? sy->may_call : "");
            if (summary) {
                FILE *f = fopen(summary, "w");
                if (f) {
                    for (char *c = first; *c; ++c)
                        if (*c == '\t') *c = ' ';
                    fprintf(f, "borrowed\t0\t0\t0\t\t%s\t\n", first);
                    fclose(f);
                }
            }
            free(lines);
            rc = 1;
            goto done;
        }
        free(lines);
    }
    {
        char *lv[48], ccw[sizeof cc];
        memcpy(ccw, cc, sizeof cc);
        int n = add_words(lv, 0, 8, ccw);
        snprintf(san, sizeof san, "%s", SIDX_CHECK_SANFLAGS);
        lv[n++] = obj;
        lv[n++] = driver;
        lv[n++] = runner;
        lv[n++] = sandbox;
        lv[n++] = watch;
        lv[n++] = lib;
        /* every call of these, the student's included, goes through watch.c,
         * which notes the ones that reach outside the case's directory */
        lv[n++] = "-Wl,--wrap=open,--wrap=open64,--wrap=openat,--wrap=openat64,--wrap=creat,--wrap=creat64,"
                  "--wrap=fopen,--wrap=fopen64,--wrap=freopen,--wrap=mkdir,--wrap=unlink,--wrap=remove,"
                  "--wrap=rmdir,--wrap=rename,--wrap=link,--wrap=symlink,--wrap=truncate,--wrap=chmod,"
                  "--wrap=connect,--wrap=fork,--wrap=system,--wrap=popen,--wrap=execve,--wrap=execv,"
                  "--wrap=execvp,--wrap=kill,--wrap=malloc,--wrap=calloc,--wrap=realloc";
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

int main(int argc, char **argv)
{
    const char *name = NULL, *file = NULL, *class_dir = NULL, *out = NULL, *summary = NULL, *rules = NULL;
    int unsafe = 0;
    long jobs = sysconf(_SC_NPROCESSORS_ONLN);
    char *pass[20];
    int npass = 0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--list")) {
            for (size_t k = 0; k < ck_num_exercises; ++k) printf("%-20s %s\n", ck_exercises[k].name, ck_exercises[k].title);
            return 0;
        } else if ((!strcmp(a, "--trace") || !strcmp(a, "--timeout") || !strcmp(a, "--case") || !strcmp(a, "--memory") ||
                    !strcmp(a, "--html") || !strcmp(a, "--rules-out")) &&
                   i + 1 < argc) {
            if (npass > 12) return 2;
            if (!strcmp(a, "--trace")) make_parents(argv[i + 1]);
            pass[npass++] = argv[i];
            pass[npass++] = argv[++i];
        } else if (!strcmp(a, "--verbose") || !strcmp(a, "--unsafe")) {
            if (npass > 12) return 2;
            if (!strcmp(a, "--unsafe")) unsafe = 1;
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
        while (k < ck_num_exercises && strcmp(ck_exercises[k].name, rules) != 0) ++k;
        if (k == ck_num_exercises) {
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
        /* A class is checked contained or, by the lecturer's choice, not at all */
        char why[300];
        if (!unsafe && ck_sandbox_probe(why, sizeof why) != 0) {
            fprintf(stderr,
                    "sidx-check: the sandbox cannot be set up here (%s): the students' code would run with your\n"
                    "rights, free to read, write and connect wherever you can.  Check the class where user\n"
                    "namespaces work (docs/exercises.md), or give --unsafe to run it with the limits only.\n",
                    why);
            return 2;
        }
        return ck_class_mode(class_dir, out, jobs, pass, npass, check_one);
    }
    if (!name || !file) {
        fprintf(stderr, "sidx-check: NAME and FILE.c are required\n");
        usage(stderr);
        return 2;
    }
    size_t k = 0;
    while (k < ck_num_exercises && strcmp(ck_exercises[k].name, name) != 0) ++k;
    if (k == ck_num_exercises) {
        fprintf(stderr, "sidx-check: no exercise named '%s'; the exercises are:\n", name);
        for (k = 0; k < ck_num_exercises; ++k) fprintf(stderr, "  %s\n", ck_exercises[k].name);
        return 2;
    }
    return check_one(k, file, pass, npass, summary);
}
