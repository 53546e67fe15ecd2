/* test_exercises.c — lessons/exercises and sidx-check, end to end.
 *
 * For every exercise (lessons/exercises/NAME.c):
 *  - its reference solution (lessons/exercises/solutions/NAME.c) passes:
 *    exit 0;
 *  - the unmodified stub fails cleanly: exit 1 and a divergence report;
 *  - every planted mistake of tests/exercises/mistakes.txt (a solution
 *    with one line changed, written to a temporary file) is caught as its
 *    record says: its exit status and every "expect" text in the report
 *    (the case, the step, the hint); crashing and endlessly looping
 *    variants exit 2 naming the case;
 *  - the kd-tree walk of exercise 08, solved, gives the library's traced
 *    walk bit for bit;
 *  - every correct variant of tests/exercises/variants/ (NAME--SLUG.c: a
 *    solution organised differently, e.g. pbrt's near/far by the origin's
 *    side) passes;
 *  - a deterministic sample of the generated mutants
 *    (tests/exercises/mutants.sh --sample) is killed, or listed as
 *    equivalent in tests/exercises/equivalent.txt (the full run is make
 *    exercise-mutants).
 *  - CC may be a command of several words ("ccache gcc").
 * At the small and smallest sizes (SIDX_FAST_TESTS=1: the sanitizer run;
 * 2: the clang and minimal builds) the planted mistakes are a deterministic
 * share of them (every mistake that must exit 2, each exercise's first,
 * every FAST_MISTAKE_STEP-th) and no mutant is run: those runs look for
 * the checker's own faults under another compiler, a sanitizer or another
 * configuration, and make test's full run checks every record and the
 * sample of mutants.
 * sidx-check compiles each file, so this suite runs the compiler: it is
 * found through the build directory's bin/sidx-check (the sibling of this
 * binary's tests/), and it compiles with that build's sanitizer flags.
 * In a handout tree without solutions/ the solution checks are skipped.
 * Run from the repository root. */
#include <dirent.h>
#include <limits.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>
#include "common/testkit.h"

static char checker[PATH_MAX + 32];

static int find_checker(void)
{
    char exe[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) return -1;
    exe[n] = '\0';
    for (int k = 0; k < 2; ++k) {
        char *s = strrchr(exe, '/');
        if (!s) return -1;
        *s = '\0';
    }
    snprintf(checker, sizeof checker, "%s/bin/sidx-check", exe);
    return access(checker, X_OK);
}

/* Reads p to the end into a malloc'd string and closes it; returns the
 * command's exit status. */
static int drain(FILE *p, char **out)
{
    char *buf = tk_read_all(p);
    assert_non_null(buf);
    const int st = pclose(p);
    *out = buf;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static FILE *start_check(const char *name, const char *file)
{
    char cmd[3 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "'%s' '%s' '%s' 2>&1", checker, name, file);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    return p;
}

/* Runs sidx-check NAME FILE; returns its exit status and its output (malloc'd). */
static int check(const char *name, const char *file, char **out)
{
    return drain(start_check(name, file), out);
}

/* Runs sidx-check on n (name, file) pairs, CHECK_JOBS at a time (most of
 * a run is the compiler, and the checks are independent): rc[i], out[i]. */
#define CHECK_JOBS 4
static void check_all(int n, const char *const *name, const char *const *file, int *rc, char **out)
{
    for (int i = 0; i < n; i += CHECK_JOBS) {
        FILE *p[CHECK_JOBS];
        const int m = n - i < CHECK_JOBS ? n - i : CHECK_JOBS;
        for (int j = 0; j < m; ++j) p[j] = start_check(name[i + j], file[i + j]);
        for (int j = 0; j < m; ++j) rc[i + j] = drain(p[j], &out[i + j]);
    }
}

/* The exercise names: lessons/exercises/[0-9]*.c without .c, sorted. */
static int names(char list[][64], int max)
{
    DIR *d = opendir("lessons/exercises");
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < max) {
        const size_t len = strlen(e->d_name);
        if (e->d_name[0] < '0' || e->d_name[0] > '9' || len < 3 || len >= 64 || strcmp(e->d_name + len - 2, ".c"))
            continue;
        memcpy(list[n], e->d_name, len - 2);
        list[n][len - 2] = '\0';
        ++n;
    }
    closedir(d);
    qsort(list, (size_t)n, sizeof list[0], (int (*)(const void *, const void *))strcmp);
    return n;
}

/* Checks DIR/NAME.c for every exercise NAME: the exit status must be
 * want and the report must contain each of the texts in expect (NULL-ended). */
static void check_every(const char *dir, int want, const char *const *expect)
{
    char list[32][64];
    const int n = names(list, 32);
    assert_true(n >= 4);
    static char files[32][PATH_MAX];
    const char *names_[32] = {0}, *files_[32] = {0};
    char *out[32];
    int rc[32];
    for (int i = 0; i < n; ++i) {
        snprintf(files[i], sizeof files[i], "%s/%s.c", dir, list[i]);
        names_[i] = list[i];
        files_[i] = files[i];
    }
    check_all(n, names_, files_, rc, out);
    for (int i = 0; i < n; ++i) {
        if (rc[i] != want) print_message("%s: exit %d\n%s", files[i], rc[i], out[i]);
        assert_int_equal(rc[i], want);
        for (const char *const *e = expect; *e; ++e) assert_non_null(strstr(out[i], *e));
        free(out[i]);
    }
}

static void solutions_pass(void **state)
{
    (void)state;
    if (access("lessons/exercises/solutions", R_OK) != 0) {
        print_message("skipped: no lessons/exercises/solutions/ (a handout tree)\n");
        return;
    }
    static const char *const expect[] = {"pass", NULL};
    check_every("lessons/exercises/solutions", 0, expect);
}

static void stubs_fail_cleanly(void **state)
{
    (void)state;
    static const char *const expect[] = {"leaves the reference at step", "FAIL (exit 1)", NULL};
    check_every("lessons/exercises", 1, expect);
}

/* One planted mistake of tests/exercises/mistakes.txt; the file holds at
 * most MAX_MISTAKES of them. */
#define MAX_MISTAKES 512
typedef struct mistake {
    char name[64], slug[64], old[512], new_[512];
    int exit_;
    char expect[8][256];
    int nexp;
} mistake;

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    const long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *s = malloc((size_t)n + 1);
    if (s && fread(s, 1, (size_t)n, f) != (size_t)n) {
        free(s);
        s = NULL;
    }
    if (s) s[n] = '\0';
    fclose(f);
    return s;
}

/* Writes the solution of m->name with m->old replaced by m->new_ to
 * dir/NAME--SLUG.c (path in out); 0 on success. */
static int plant(const mistake *m, const char *dir, char *out, size_t size)
{
    char sol[PATH_MAX];
    snprintf(sol, sizeof sol, "lessons/exercises/solutions/%s.c", m->name);
    char *src = slurp(sol);
    if (!src) return -1;
    char *at = strstr(src, m->old);
    if (!at) {
        print_message("%s--%s: the line to replace is not in %s: %s\n", m->name, m->slug, sol, m->old);
        free(src);
        return -1;
    }
    snprintf(out, size, "%s/%s--%s.c", dir, m->name, m->slug);
    FILE *f = fopen(out, "w");
    if (!f) {
        free(src);
        return -1;
    }
    fprintf(f, "%.*s%s%s", (int)(at - src), src, m->new_, at + strlen(m->old));
    free(src);
    return fclose(f);
}

/* Reads the records of tests/exercises/mistakes.txt; returns their count,
 * -1 when the file is absent (a handout tree). */
static int read_mistakes(mistake *ms, int max)
{
    FILE *f = fopen("tests/exercises/mistakes.txt", "r");
    if (!f) return -1;
    char line[1024];
    int n = -1;
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        if (line[0] == '#' || line[0] == '\0') continue;
        char key[16];
        int off = 0;
        if (sscanf(line, "%15s %n", key, &off) != 1) continue;
        const char *val = line + off;
        if (!strcmp(key, "mistake")) {
            if (n + 1 >= max) break;
            mistake *m = &ms[++n];
            memset(m, 0, sizeof *m);
            if (sscanf(val, "%63s %63s", m->name, m->slug) != 2) n = max;
        } else if (n < 0 || n >= max) {
            continue;
        } else if (!strcmp(key, "old")) {
            snprintf(ms[n].old, sizeof ms[n].old, "%s", val);
        } else if (!strcmp(key, "new")) {
            snprintf(ms[n].new_, sizeof ms[n].new_, "%s", val);
        } else if (!strcmp(key, "exit")) {
            ms[n].exit_ = atoi(val);
        } else if (!strcmp(key, "expect") && ms[n].nexp < 8) {
            snprintf(ms[n].expect[ms[n].nexp++], 256, "%s", val);
        }
    }
    fclose(f);
    return n >= max ? -2 : n + 1;
}

/* At the small sizes: the records kept, in file order (see the header). */
#define FAST_MISTAKE_STEP 12
static int keep_fast(mistake *ms, int n)
{
    int kept = 0;
    char previous[64] = "";
    for (int i = 0; i < n; ++i) {
        const int first_of_exercise = strcmp(ms[i].name, previous) != 0;
        memcpy(previous, ms[i].name, sizeof previous);
        const int every_step = i % FAST_MISTAKE_STEP == 0;
        if (ms[i].exit_ == 2 || first_of_exercise || every_step) ms[kept++] = ms[i];
    }
    return kept;
}

/* Every planted mistake is caught as its record says. */
static void planted_mistakes_caught(void **state)
{
    (void)state;
    static mistake ms[MAX_MISTAKES];
    int n = read_mistakes(ms, MAX_MISTAKES);
    if (n == -1 || access("lessons/exercises/solutions", R_OK) != 0) {
        print_message("skipped: no tests/exercises/ or no solutions (a handout tree)\n");
        return;
    }
    assert_true(n >= 8);
    if (tk_fast_tests()) {
        const int all = n;
        n = keep_fast(ms, n);
        print_message("%s sizes: %d of the %d planted mistakes\n", tk_tiny_tests() ? "smallest" : "small", n, all);
    }
    char dir[] = "/tmp/sidx-test-ex-XXXXXX";
    assert_non_null(mkdtemp(dir));
    static char files[MAX_MISTAKES][PATH_MAX];
    const char *names_[MAX_MISTAKES] = {0}, *files_[MAX_MISTAKES] = {0};
    char *out[MAX_MISTAKES];
    int rc[MAX_MISTAKES];
    for (int i = 0; i < n; ++i) {
        assert_true(ms[i].exit_ == 1 || ms[i].exit_ == 2);
        assert_int_equal(plant(&ms[i], dir, files[i], sizeof files[i]), 0);
        names_[i] = ms[i].name;
        files_[i] = files[i];
    }
    check_all(n, names_, files_, rc, out);
    for (int i = 0; i < n; ++i) {
        const mistake *m = &ms[i];
        int ok = rc[i] == m->exit_;
        for (int k = 0; k < m->nexp; ++k)
            if (!strstr(out[i], m->expect[k])) {
                print_message("%s--%s: the report lacks \"%s\"\n", m->name, m->slug, m->expect[k]);
                ok = 0;
            }
        if (!ok) print_message("%s--%s: exit %d (want %d)\n%s", m->name, m->slug, rc[i], m->exit_, out[i]);
        assert_true(ok);
        free(out[i]);
        unlink(files[i]);
    }
    assert_int_equal(rmdir(dir), 0);
}

static void usage_and_errors(void **state)
{
    (void)state;
    char *out;
    assert_int_equal(check("no_such_exercise", "lessons/exercises/03_ray_box.c", &out), 2);
    assert_non_null(strstr(out, "no exercise named"));
    free(out);
    assert_int_equal(check("03_ray_box", "/nonexistent.c", &out), 2);
    free(out);
    /* a file that does not build: the stub of another exercise lacks ray_box */
    assert_int_equal(check("03_ray_box", "lessons/exercises/02_moller_trumbore.c", &out), 2);
    assert_non_null(strstr(out, "BUILD FAILED"));
    free(out);
}

/* sidx-step, the sibling of sidx-check in the build's bin/. */
static void step_path(char *step, size_t size)
{
    snprintf(step, size, "%s", checker);
    char *slash = strrchr(step, '/');
    assert_non_null(slash);
    snprintf(slash + 1, size - (size_t)(slash + 1 - step), "sidx-step");
}

/* sidx-check --trace writes both traces and the sidx-view commands that
 * open them; sidx-step --diff finds the same first divergence (exit 1) and
 * agrees with itself (exit 0). */
static void traces_and_diff(void **state)
{
    (void)state;
    char dir[] = "/tmp/sidx-test-ex-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char cmd[4 * PATH_MAX], step[PATH_MAX + 32];
    step_path(step, sizeof step);
    static mistake ms[MAX_MISTAKES];
    const int n = read_mistakes(ms, MAX_MISTAKES);
    int k = 0;
    while (k < n && strcmp(ms[k].slug, "far-wrong-t") != 0) ++k;
    char file[PATH_MAX];
    if (k >= n || access("lessons/exercises/solutions", R_OK) != 0) {
        print_message("skipped: no planted mistakes or no solutions (a handout tree)\n");
        rmdir(dir);
        return;
    }
    assert_int_equal(plant(&ms[k], dir, file, sizeof file), 0);
    /* a directory that cannot be made: the report says the traces were not written */
    snprintf(cmd, sizeof cmd, "'%s' 05_bvh_traversal %s --trace /proc/sidx-no-such/dir 2>&1", checker, file);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *out;
    assert_int_equal(drain(p, &out), 1);
    assert_non_null(strstr(out, "cannot make the directory /proc/sidx-no-such/dir"));
    assert_non_null(strstr(out, "traces     not written"));
    assert_null(strstr(out, "reference.jsonl and"));
    free(out);
    /* a directory that does not exist yet is made, with the ones above it */
    char tdir[sizeof dir + 16];
    snprintf(tdir, sizeof tdir, "%s/new/traces", dir);
    snprintf(cmd, sizeof cmd, "'%s' 05_bvh_traversal %s --trace %s", checker, file, tdir);
    p = popen(cmd, "r");
    assert_non_null(p);
    assert_int_equal(drain(p, &out), 1);
    /* with SDL2 the report names the two sidx-view commands, and each opens its trace */
    char viewer[PATH_MAX + 32];
    snprintf(viewer, sizeof viewer, "%s", step);
    snprintf(strrchr(viewer, '/') + 1, 16, "sidx-view");
    if (access(viewer, X_OK) == 0) {
        const char *const which[] = {"reference.jsonl\n", "yours.jsonl\n"};
        for (int w = 0; w < 2; ++w) {
            const char *end = strstr(out, which[w]), *start = end;
            assert_non_null(end);
            while (start > out && start[-1] != '\n') --start;
            while (*start == ' ' || (start[0] == 'v' && !strncmp(start, "view ", 5))) start += *start == ' ' ? 1 : 5;
            assert_true(!strncmp(start, viewer, strlen(viewer)));
            assert_non_null(strstr(start, " --accel bvh --scene flat2d --ray "));
            snprintf(cmd, sizeof cmd, "%.*s --screenshot %s/view.png --size 320x200 >/dev/null",
                     (int)(end + strlen(which[w]) - 1 - start), start, dir);
            if (system(cmd) != 0) fail_msg("failed: %s", cmd);
        }
    } else {
        print_message("no sidx-view (built without SDL2): the view commands are not checked\n");
    }
    free(out);
    int st;
    snprintf(cmd, sizeof cmd, "'%s' --diff %s/reference.jsonl %s/yours.jsonl >/dev/null", step, tdir, tdir);
    st = system(cmd);
    assert_int_equal(WEXITSTATUS(st), 1);
    snprintf(cmd, sizeof cmd, "'%s' --diff %s/reference.jsonl %s/reference.jsonl >/dev/null", step, tdir, tdir);
    st = system(cmd);
    assert_int_equal(WEXITSTATUS(st), 0);
    snprintf(cmd, sizeof cmd, "'%s' --diff %s/reference.jsonl >/dev/null 2>&1", step, tdir);
    st = system(cmd);
    assert_int_equal(WEXITSTATUS(st), 2);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

/* The reference solution of 08_kdtree_traversal retells the library's
 * traced kd walk bit for bit, not only within the checker's tolerance:
 * the same t_split, intervals and hits (sidx-step --diff --exact), on a
 * ray whose first hit lies beyond its cell and on one starting on a split
 * plane. */
static void kd_walk_bit_exact(void **state)
{
    (void)state;
    if (access("lessons/exercises/solutions/08_kdtree_traversal.c", R_OK) != 0) {
        print_message("skipped: no solutions (a handout tree)\n");
        return;
    }
    char dir[] = "/tmp/sidx-test-ex-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char cmd[4 * PATH_MAX], step[PATH_MAX + 32];
    step_path(step, sizeof step);
    static const int cases[] = {9, 21};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        snprintf(cmd, sizeof cmd,
                 "'%s' 08_kdtree_traversal lessons/exercises/solutions/08_kdtree_traversal.c --case %d --trace %s "
                 ">/dev/null",
                 checker, cases[k], dir);
        int st = system(cmd);
        assert_int_equal(WEXITSTATUS(st), 0);
        snprintf(cmd, sizeof cmd, "'%s' --diff --exact %s/reference.jsonl %s/yours.jsonl >/dev/null", step, dir, dir);
        st = system(cmd);
        assert_int_equal(WEXITSTATUS(st), 0);
    }
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

/* Every correct variant passes: tests/exercises/variants/NAME--SLUG.c is
 * checked as exercise NAME. */
static void variants_pass(void **state)
{
    (void)state;
    DIR *d = opendir("tests/exercises/variants");
    if (!d) {
        print_message("skipped: no tests/exercises/variants/ (a handout tree)\n");
        return;
    }
    static char names_buf[32][64], files[32][PATH_MAX];
    const char *names_[32] = {0}, *files_[32] = {0};
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n < 32) {
        const char *dash = strstr(e->d_name, "--");
        const size_t len = strlen(e->d_name);
        if (!dash || len < 3 || strcmp(e->d_name + len - 2, ".c") || (size_t)(dash - e->d_name) >= 64) continue;
        snprintf(names_buf[n], sizeof names_buf[n], "%.*s", (int)(dash - e->d_name), e->d_name);
        snprintf(files[n], sizeof files[n], "tests/exercises/variants/%s", e->d_name);
        names_[n] = names_buf[n];
        files_[n] = files[n];
        ++n;
    }
    closedir(d);
    assert_true(n >= 2);
    char *out[32];
    int rc[32];
    check_all(n, names_, files_, rc, out);
    for (int i = 0; i < n; ++i) {
        if (rc[i] != 0) print_message("%s: exit %d\n%s", files[i], rc[i], out[i]);
        assert_int_equal(rc[i], 0);
        free(out[i]);
    }
}

/* A sample of the generated mutants, every MUTANT_SAMPLE-th of each
 * exercise, is killed or listed as equivalent (mutants.sh exits 0); at the
 * small sizes the planted mistakes alone drive the checker's reports. */
#define MUTANT_SAMPLE "15"
static void mutant_sample_killed(void **state)
{
    (void)state;
    if (access("tests/exercises/mutants.sh", R_OK) != 0 || access("lessons/exercises/solutions", R_OK) != 0) {
        print_message("skipped: no tests/exercises/ or no solutions (a handout tree)\n");
        return;
    }
    if (tk_fast_tests()) {
        print_message("skipped at the small sizes: make test kills the sample\n");
        return;
    }
    char build[PATH_MAX + 32], cmd[2 * PATH_MAX + 128];
    snprintf(build, sizeof build, "%s", checker);
    for (int k = 0; k < 2; ++k) *strrchr(build, '/') = '\0';
    snprintf(cmd, sizeof cmd, "BUILD='%s' sh tests/exercises/mutants.sh --no-mistakes --jobs 4 --sample %s 2>&1", build,
             MUTANT_SAMPLE);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *out;
    const int rc = drain(p, &out);
    if (rc != 0) print_message("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "mutant run:"));
    free(out);
}

/* mutate.awk's field operator: a write to a struct field that is no
 * output of the other operators is dropped, or given 0, one mutant each;
 * an output (*t = E) is not mutated twice. */
static void mutate_field_writes(void **state)
{
    (void)state;
    if (access("tests/exercises/mutate.awk", R_OK) != 0) {
        print_message("skipped: no tests/exercises/ (a handout tree)\n");
        return;
    }
    char dir[] = "/tmp/sidx-mutate-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char src[PATH_MAX], cmd[3 * PATH_MAX];
    snprintf(src, sizeof src, "%s/f.c", dir);
    FILE *f = fopen(src, "w");
    assert_non_null(f);
    fputs("void f(node *n, node *nodes, float *t, float v)\n{\n    n->bmin[0] = v;\n    nodes[2].count = 0;\n"
          "    *t = v;\n}\n",
          f);
    fclose(f);
    snprintf(cmd, sizeof cmd, "awk -v out='%s' -v name=f -f tests/exercises/mutate.awk '%s' 2>&1", dir, src);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *out;
    assert_int_equal(drain(p, &out), 0);
    assert_non_null(strstr(out, "field dropped n->bmin[0] | n->bmin[0] = v;"));
    assert_non_null(strstr(out, "field n->bmin[0] = 0 | n->bmin[0] = v;"));
    assert_non_null(strstr(out, "field dropped nodes[2].count | nodes[2].count = 0;"));
    assert_null(strstr(out, "field nodes[2].count = 0")); /* already 0 */
    assert_null(strstr(out, "field *t"));
    free(out);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
}

/* CC may be a command of several words, as make's CC="ccache gcc" is:
 * "env CC" runs the same compiler through env.  The stub builds and fails
 * at step 1; the compiler's command taken as one program name would not
 * run at all (BUILD FAILED, exit 2). */
static void cc_of_several_words(void **state)
{
    (void)state;
    char cmd[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "CC=\"env ${CC:-cc}\" '%s' 03_ray_box lessons/exercises/03_ray_box.c 2>&1", checker);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *out;
    const int rc = drain(p, &out);
    if (rc != 1) print_message("%s\n", out);
    assert_int_equal(rc, 1);
    assert_non_null(strstr(out, "leaves the reference at step 1"));
    free(out);
}

int main(void)
{
    if (find_checker() != 0) {
        printf("test_exercises: skipped: no sidx-check beside this suite (build it with make build)\n");
        return 0;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(solutions_pass),
        cmocka_unit_test(stubs_fail_cleanly),
        cmocka_unit_test(planted_mistakes_caught),
        cmocka_unit_test(usage_and_errors),
        cmocka_unit_test(traces_and_diff),
        cmocka_unit_test(kd_walk_bit_exact),
        cmocka_unit_test(variants_pass),
        cmocka_unit_test(mutant_sample_killed),
        cmocka_unit_test(mutate_field_writes),
        cmocka_unit_test(cc_of_several_words),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
