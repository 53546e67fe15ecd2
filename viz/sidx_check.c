/* sidx-check — check a student's exercise against the library, step by step.
 *
 *   sidx-check NAME FILE.c [--trace DIR] [--timeout S] [--case K] [--verbose]
 *   sidx-check --list
 *
 * Builds FILE.c against the library together with the exercise's checker
 * driver (lessons/exercises/check/NAME.c) and the runner, then runs it: the
 * runner compares the student's trace with the reference on the exercise's
 * battery and reports the first divergence (docs/exercises.md).
 * Exit status: 0 every case passes, 1 a divergence, 2 FILE does not build,
 * crashes or runs out of time (or a usage error). */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
            "usage: sidx-check NAME FILE.c [--trace DIR] [--timeout S] [--case K] [--verbose]\n"
            "       sidx-check --list\n"
            "\n"
            "Builds FILE.c (your solution of exercise NAME, e.g. lessons/exercises/NAME.c) against\n"
            "the library, runs it and the library's reference on the exercise's cases and compares\n"
            "the two traces event by event.  At the first divergence it prints the step, what the\n"
            "reference did, what your code did, the input and a hint from the slides.\n"
            "\n"
            "  --list          the exercises\n"
            "  --trace DIR     write DIR/reference.jsonl and DIR/yours.jsonl for the failing case\n"
            "                  (or for case K) as JSON Lines: compare them with sidx-step --diff; for\n"
            "                  a walk the report also prints the two sidx-view --events commands\n"
            "                  that step through each over its scene and structure (DIR and the\n"
            "                  directories above it are made)\n"
            "  --timeout S     time limit per case, seconds (default 2)\n"
            "  --case K        run only case K\n"
            "  --verbose       one line per case\n"
            "  -h, --help      this help\n"
            "\n"
            "Exit status: 0 every case passes, 1 a divergence, 2 FILE does not build, crashes or\n"
            "loops (or a usage error).  Guide: docs/exercises.md.\n");
}

/* Runs argv; returns its exit status, or -1 if it could not be run or was killed. */
static int run(char *const argv[])
{
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
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

/* Splits the sanitizer flags the library was built with into argv. */
static int add_words(char **argv, int n, char *words)
{
    for (char *w = strtok(words, " "); w; w = strtok(NULL, " ")) argv[n++] = w;
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

int main(int argc, char **argv)
{
    const char *name = NULL, *file = NULL;
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
        } else if ((!strcmp(a, "--trace") || !strcmp(a, "--timeout") || !strcmp(a, "--case")) && i + 1 < argc) {
            if (npass > 12) return 2;
            if (!strcmp(a, "--trace")) make_parents(argv[i + 1]);
            pass[npass++] = argv[i];
            pass[npass++] = argv[++i];
        } else if (!strcmp(a, "--verbose")) {
            if (npass > 12) return 2;
            pass[npass++] = argv[i];
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
    if (access(file, R_OK) != 0) {
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
    const char *cc = getenv("CC");
    if (!cc || !*cc) cc = "cc";
    int rc = 2;
    {
        char *cv[32];
        int n = 0;
        cv[n++] = (char *)cc;
        const char *fixed[] = {"-std=c11", "-g", "-O1", "-Wall", "-Wextra", "-ffp-contract=off", "-D_DEFAULT_SOURCE"};
        for (size_t j = 0; j < sizeof fixed / sizeof fixed[0]; ++j) cv[n++] = (char *)fixed[j];
        cv[n++] = inc;
        n = add_words(cv, n, san);
        cv[n++] = "-c";
        cv[n++] = (char *)file;
        cv[n++] = "-o";
        cv[n++] = obj;
        cv[n] = NULL;
        if (run(cv) != 0) {
            printf("sidx-check %s: %s does not build (the compiler's messages are above)\nBUILD FAILED (exit 2)\n",
                   name, file);
            goto done;
        }
    }
    {
        char *lv[32];
        int n = 0;
        snprintf(san, sizeof san, "%s", SIDX_CHECK_SANFLAGS);
        lv[n++] = (char *)cc;
        lv[n++] = obj;
        lv[n++] = driver;
        lv[n++] = runner;
        lv[n++] = lib;
        n = add_words(lv, n, san);
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
            goto done;
        }
    }
    {
        char *rv[24], viewer[PATH_MAX + 32];
        int n = 0;
        rv[n++] = exe;
        for (int j = 0; j < npass; ++j) rv[n++] = pass[j];
        snprintf(viewer, sizeof viewer, "%s/bin/sidx-view", bdir); /* built only with SDL2 */
        if (access(viewer, X_OK) == 0) {
            rv[n++] = "--viewer";
            rv[n++] = viewer;
        }
        rv[n] = NULL;
        const int st = run(rv);
        rc = (st >= 0 && st <= 2) ? st : 2;
    }
done:
    unlink(obj);
    unlink(exe);
    rmdir(tmp);
    return rc;
}
