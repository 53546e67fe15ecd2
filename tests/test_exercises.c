/* test_exercises.c — lessons/exercises and sidx-check, end to end.
 *
 * For every exercise (lessons/exercises/NAME.c):
 *  - its reference solution (lessons/exercises/solutions/NAME.c) passes:
 *    exit 0;
 *  - the unmodified stub fails cleanly: exit 1 and a divergence report;
 *  - every planted mistake tests/exercises/NAME--*.c is caught as its
 *    header says: the exit status on its "EXPECT-EXIT:" line and every
 *    "EXPECT:" line's text in the report (the case, the step, the hint);
 *    crashing and endlessly looping variants exit 2 naming the case.
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

/* Runs sidx-check NAME FILE; returns its exit status and its output (malloc'd). */
static int check(const char *name, const char *file, char **out)
{
    char cmd[3 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "'%s' '%s' '%s' 2>&1", checker, name, file);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    assert_non_null(buf);
    size_t k;
    while ((k = fread(buf + n, 1, cap - n - 1, p)) > 0) {
        n += k;
        if (cap - n < 2) {
            cap *= 2;
            buf = realloc(buf, cap);
            assert_non_null(buf);
        }
    }
    buf[n] = '\0';
    const int st = pclose(p);
    *out = buf;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
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

static void solutions_pass(void **state)
{
    (void)state;
    char list[32][64];
    const int n = names(list, 32);
    assert_true(n >= 4);
    if (access("lessons/exercises/solutions", R_OK) != 0) {
        print_message("skipped: no lessons/exercises/solutions/ (a handout tree)\n");
        return;
    }
    for (int i = 0; i < n; ++i) {
        char file[PATH_MAX], *out;
        snprintf(file, sizeof file, "lessons/exercises/solutions/%s.c", list[i]);
        const int rc = check(list[i], file, &out);
        if (rc != 0) print_message("%s: exit %d\n%s", file, rc, out);
        assert_int_equal(rc, 0);
        assert_non_null(strstr(out, "pass"));
        free(out);
    }
}

static void stubs_fail_cleanly(void **state)
{
    (void)state;
    char list[32][64];
    const int n = names(list, 32);
    for (int i = 0; i < n; ++i) {
        char file[PATH_MAX], *out;
        snprintf(file, sizeof file, "lessons/exercises/%s.c", list[i]);
        const int rc = check(list[i], file, &out);
        if (rc != 1) print_message("%s: exit %d\n%s", file, rc, out);
        assert_int_equal(rc, 1);
        assert_non_null(strstr(out, "leaves the reference at step"));
        assert_non_null(strstr(out, "FAIL (exit 1)"));
        free(out);
    }
}

/* Every tests/exercises/NAME--what.c is caught as its header says. */
static void planted_mistakes_caught(void **state)
{
    (void)state;
    DIR *d = opendir("tests/exercises");
    if (!d) {
        print_message("skipped: no tests/exercises/ (a handout tree)\n");
        return;
    }
    struct dirent *e;
    int files = 0;
    while ((e = readdir(d))) {
        const char *dash = strstr(e->d_name, "--");
        const size_t len = strlen(e->d_name);
        if (!dash || len < 3 || strcmp(e->d_name + len - 2, ".c")) continue;
        char name[64], file[PATH_MAX];
        snprintf(name, sizeof name, "%.*s", (int)(dash - e->d_name), e->d_name);
        snprintf(file, sizeof file, "tests/exercises/%s", e->d_name);
        FILE *f = fopen(file, "r");
        assert_non_null(f);
        char line[512], expects[16][256];
        int nexp = 0, want_rc = -1;
        while (fgets(line, sizeof line, f)) {
            line[strcspn(line, "\n")] = '\0';
            const char *p;
            if ((p = strstr(line, "EXPECT-EXIT: "))) want_rc = atoi(p + 13);
            else if ((p = strstr(line, "EXPECT: ")) && nexp < 16) snprintf(expects[nexp++], 256, "%s", p + 8);
        }
        fclose(f);
        assert_true(want_rc == 1 || want_rc == 2);
        char *out;
        const int rc = check(name, file, &out);
        int ok = rc == want_rc;
        for (int k = 0; k < nexp; ++k)
            if (!strstr(out, expects[k])) {
                print_message("%s: the report lacks \"%s\"\n", file, expects[k]);
                ok = 0;
            }
        if (!ok) print_message("%s: exit %d (want %d)\n%s", file, rc, want_rc, out);
        assert_true(ok);
        free(out);
        ++files;
    }
    closedir(d);
    assert_true(files >= 8);
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

/* sidx-check --trace writes both traces; sidx-step --diff finds the same
 * first divergence (exit 1) and agrees with itself (exit 0). */
static void traces_and_diff(void **state)
{
    (void)state;
    char dir[] = "/tmp/sidx-test-ex-XXXXXX";
    assert_non_null(mkdtemp(dir));
    char cmd[4 * PATH_MAX], step[PATH_MAX + 32];
    snprintf(step, sizeof step, "%s", checker);
    char *slash = strrchr(step, '/');
    assert_non_null(slash);
    snprintf(slash + 1, sizeof step - (size_t)(slash + 1 - step), "sidx-step");
    if (access("tests/exercises/05_bvh_traversal--far-wrong-t.c", R_OK) != 0) {
        print_message("skipped: no tests/exercises/ (a handout tree)\n");
        rmdir(dir);
        return;
    }
    snprintf(cmd, sizeof cmd, "'%s' 05_bvh_traversal tests/exercises/05_bvh_traversal--far-wrong-t.c --trace %s >/dev/null",
             checker, dir);
    int st = system(cmd);
    assert_int_equal(WEXITSTATUS(st), 1);
    snprintf(cmd, sizeof cmd, "'%s' --diff %s/reference.jsonl %s/yours.jsonl >/dev/null", step, dir, dir);
    st = system(cmd);
    assert_int_equal(WEXITSTATUS(st), 1);
    snprintf(cmd, sizeof cmd, "'%s' --diff %s/reference.jsonl %s/reference.jsonl >/dev/null", step, dir, dir);
    st = system(cmd);
    assert_int_equal(WEXITSTATUS(st), 0);
    snprintf(cmd, sizeof cmd, "'%s' --diff %s/reference.jsonl >/dev/null 2>&1", step, dir);
    st = system(cmd);
    assert_int_equal(WEXITSTATUS(st), 2);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
