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

/* Where the checks write each exercise's rule table (--rules-out
 * DIR/NAME.rules) while solutions_pass runs them, or "": the tables come
 * with the solutions' checks at no extra build (load_tables). */
static char rules_dir[64];

static FILE *start_check(const char *name, const char *file)
{
    char cmd[3 * PATH_MAX + 256], extra[256] = "";
    if (rules_dir[0]) snprintf(extra, sizeof extra, " --rules-out '%s/%.63s.rules'", rules_dir, name);
    snprintf(cmd, sizeof cmd, "'%s' '%s' '%s'%s 2>&1", checker, name, file, extra);
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

static void load_tables(void);

static void solutions_pass(void **state)
{
    (void)state;
    if (access("lessons/exercises/solutions", R_OK) != 0) {
        print_message("skipped: no lessons/exercises/solutions/ (a handout tree)\n");
        return;
    }
    static const char *const expect[] = {"pass", NULL};
    char dir[] = "/tmp/sidx-test-rules-XXXXXX";
    assert_non_null(mkdtemp(dir));
    snprintf(rules_dir, sizeof rules_dir, "%s", dir);
    check_every("lessons/exercises/solutions", 0, expect);
    load_tables(); /* from the files the checks wrote */
    char cmd[sizeof dir + 16];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
    rules_dir[0] = '\0';
}

static void stubs_fail_cleanly(void **state)
{
    (void)state;
    static const char *const expect[] = {"leaves the reference at step", "FAIL (exit 1)", NULL};
    check_every("lessons/exercises", 1, expect);
}

/* One planted mistake of tests/exercises/mistakes.txt; the file holds at
 * most MAX_MISTAKES of them. */
#define MAX_MISTAKES 1024
typedef struct mistake {
    char name[64], slug[64], old[512], new_[512];
    int exit_;
    char expect[8][256];
    int nexp;
    char rule[64]; /* the rule of the exercise's table it breaks, or "" */
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
        } else if (!strcmp(key, "rule")) {
            snprintf(ms[n].rule, sizeof ms[n].rule, "%s", val);
        } else if (!strcmp(key, "expect") && ms[n].nexp < 8) {
            snprintf(ms[n].expect[ms[n].nexp++], 256, "%s", val);
        }
    }
    fclose(f);
    return n >= max ? -2 : n + 1;
}

/* ---- the rule tables ------------------------------------------------------------------ */

/* One rule of `sidx-check --rules NAME`: id, statement, hint and the cases
 * that test it (blank-separated case numbers). */
#define MAX_RULES 64
typedef struct rule_row {
    char id[64], hint[1024], cases[1024];
} rule_row;
typedef struct rule_table {
    char name[64];
    int rc, n; /* the exit status of --rules; the rules */
    rule_row row[MAX_RULES];
} rule_table;

/* A field of a tab-separated line: copies up to the next tab (or the end) into out. */
static const char *tab_field(const char *p, char *out, size_t size)
{
    const size_t len = strcspn(p, "\t\n");
    snprintf(out, size, "%.*s", (int)len, p);
    return p[len] == '\t' ? p + len + 1 : p + len;
}

static void parse_rules(rule_table *t, const char *text)
{
    t->n = 0;
    for (const char *p = text; *p && t->n < MAX_RULES;) {
        const char *end = p + strcspn(p, "\n");
        if (end > p) {
            rule_row *r = &t->row[t->n++];
            char statement[1024];
            const char *q = tab_field(p, r->id, sizeof r->id);
            q = tab_field(q, statement, sizeof statement);
            q = tab_field(q, r->hint, sizeof r->hint);
            tab_field(q, r->cases, sizeof r->cases);
        }
        p = *end ? end + 1 : end;
    }
}

/* Every exercise's table from sidx-check --rules (each builds that
 * exercise's checker: CHECK_JOBS at a time), read once. */
static rule_table tables[32];
static int ntables = -1;

static void load_tables(void)
{
    if (ntables >= 0) return;
    char list[32][64];
    const int n = names(list, 32);
    for (int i = 0; i < n; i += CHECK_JOBS) {
        FILE *p[CHECK_JOBS];
        const int m = n - i < CHECK_JOBS ? n - i : CHECK_JOBS;
        for (int j = 0; j < m; ++j) {
            char cmd[sizeof checker + 256];
            if (rules_dir[0]) /* written by solutions_pass's checks */
                snprintf(cmd, sizeof cmd, "cat '%s/%.63s.rules' 2>&1", rules_dir, list[i + j]);
            else
                snprintf(cmd, sizeof cmd, "'%s' --rules %.63s 2>&1", checker, list[i + j]);
            p[j] = popen(cmd, "r");
            assert_non_null(p[j]);
        }
        for (int j = 0; j < m; ++j) {
            rule_table *t = &tables[i + j];
            char *out;
            snprintf(t->name, sizeof t->name, "%.63s", list[i + j]);
            t->rc = drain(p[j], &out);
            if (t->rc == 0) parse_rules(t, out);
            else print_message("sidx-check --rules %s: exit %d\n%s", t->name, t->rc, out);
            free(out);
        }
    }
    ntables = n;
}

static const rule_row *find_rule(const char *name, const char *id)
{
    load_tables();
    for (int i = 0; i < ntables; ++i) {
        if (strcmp(tables[i].name, name) != 0) continue;
        for (int r = 0; r < tables[i].n; ++r)
            if (!strcmp(tables[i].row[r].id, id)) return &tables[i].row[r];
    }
    return NULL;
}

/* The rule ids docs/exercises.md lists for exercise name: the first
 * column, in backticks, of the table under its "### NAME" heading in the
 * section "The rules each hand-out states"; their count, -1 without the
 * heading. */
static int doc_rule_ids(const char *doc, const char *name, char ids[][64], int max)
{
    const char *sec = strstr(doc, "\n## The rules each hand-out states");
    if (!sec) return -1;
    const char *end = strstr(sec + 1, "\n## ");
    char head[96];
    snprintf(head, sizeof head, "\n### %.63s\n", name);
    const char *h = strstr(sec, head);
    if (!h || (end && h > end)) return -1;
    const char *stop = strstr(h + strlen(head), "\n#");
    int n = 0;
    for (const char *p = h + strlen(head); *p && (!stop || p < stop);) {
        const char *eol = p + strcspn(p, "\n");
        if (p[0] == '|' && p[strspn(p, "| ")] == '`') {
            const char *a = strchr(p, '`') + 1, *b = strchr(a, '`');
            if (b && b < eol && n < max) snprintf(ids[n++], 64, "%.*s", (int)(b - a), a);
        }
        p = *eol ? eol + 1 : eol;
    }
    return n;
}

/* Every exercise's rule table agrees with docs/exercises.md (the same ids),
 * every case names only rules of the table (--rules exits 0), every rule
 * has a case and a planted mistake, and every mistake's rule is in its
 * exercise's table.  A table still empty passes. */
static void rule_tables_agree(void **state)
{
    (void)state;
    static mistake ms[MAX_MISTAKES];
    const int nm = read_mistakes(ms, MAX_MISTAKES);
    char *doc = slurp("docs/exercises.md");
    assert_non_null(doc);
    load_tables();
    assert_true(ntables >= 4);
    int bad = 0, rules = 0;
    { /* sidx-check --rules NAME prints what the check wrote with --rules-out (the exercise with most rules) */
        int w = 0;
        for (int i = 1; i < ntables; ++i)
            if (tables[i].n > tables[w].n) w = i;
        char cmd[sizeof checker + 128], *out;
        snprintf(cmd, sizeof cmd, "'%s' --rules %.63s 2>&1", checker, tables[w].name);
        FILE *p = popen(cmd, "r");
        assert_non_null(p);
        assert_int_equal(drain(p, &out), 0);
        static rule_table again;
        parse_rules(&again, out);
        free(out);
        assert_int_equal(again.n, tables[w].n);
        for (int r = 0; r < again.n; ++r) {
            assert_string_equal(again.row[r].id, tables[w].row[r].id);
            assert_string_equal(again.row[r].hint, tables[w].row[r].hint);
            assert_string_equal(again.row[r].cases, tables[w].row[r].cases);
        }
    }
    for (int i = 0; i < ntables; ++i) {
        const rule_table *t = &tables[i];
        if (t->rc != 0) {
            ++bad;
            continue;
        }
        static char ids[MAX_RULES][64];
        const int nd = doc_rule_ids(doc, t->name, ids, MAX_RULES);
        if (nd < 0) {
            print_message("docs/exercises.md: no \"### %s\" under \"The rules each hand-out states\"\n", t->name);
            ++bad;
        }
        for (int d = 0; d < nd; ++d)
            if (!find_rule(t->name, ids[d])) {
                print_message("%s: docs/exercises.md lists the rule %s, which sidx-check --rules lacks\n", t->name, ids[d]);
                ++bad;
            }
        for (int r = 0; r < t->n; ++r) {
            const rule_row *row = &t->row[r];
            ++rules;
            int in_doc = 0, mistakes = 0;
            for (int d = 0; d < nd; ++d) in_doc |= !strcmp(ids[d], row->id);
            for (int k = 0; k < nm; ++k) mistakes += !strcmp(ms[k].name, t->name) && !strcmp(ms[k].rule, row->id);
            if (!in_doc) print_message("%s: the rule %s is not in docs/exercises.md\n", t->name, row->id);
            if (!row->cases[0]) print_message("%s: no case tests the rule %s\n", t->name, row->id);
            if (nm >= 0 && !mistakes) print_message("%s: no planted mistake breaks the rule %s\n", t->name, row->id);
            if (!row->hint[0]) print_message("%s: the rule %s has no hint\n", t->name, row->id);
            bad += !in_doc + !row->cases[0] + (nm >= 0 && !mistakes) + !row->hint[0];
        }
    }
    for (int k = 0; k < nm; ++k)
        if (ms[k].rule[0] && !find_rule(ms[k].name, ms[k].rule)) {
            print_message("%s--%s: the rule %s is not in the exercise's table\n", ms[k].name, ms[k].slug, ms[k].rule);
            ++bad;
        }
    print_message("%d exercises, %d rules\n", ntables, rules);
    free(doc);
    assert_int_equal(bad, 0);
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
/* Two diverging steps never print alike: the report's "reference" and
 * "yours" lines differ, or a "differs" line names the field. */
static int diverging_steps_told_apart(const char *report)
{
    const char *ref = strstr(report, "\n  reference  "), *yours = strstr(report, "\n  yours      ");
    if (!ref || !yours) return 1; /* no divergence printed (a crash, a build failure) */
    ref += 14;
    yours += 14;
    const size_t nr = strcspn(ref, "\n"), ny = strcspn(yours, "\n");
    if (nr != ny || strncmp(ref, yours, nr) != 0) return 1;
    return strstr(report, "\n  differs    ") != NULL;
}

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
        if (m->rule[0]) { /* the hint of the rule it breaks */
            const rule_row *r = find_rule(m->name, m->rule);
            if (!r) print_message("%s--%s: no rule %s in sidx-check --rules %s\n", m->name, m->slug, m->rule, m->name);
            else if (!strstr(out[i], r->hint))
                print_message("%s--%s: the report lacks the hint of the rule %s: \"%s\"\n", m->name, m->slug, m->rule,
                              r->hint);
            ok = ok && r && strstr(out[i], r->hint);
        }
        if (!diverging_steps_told_apart(out[i])) {
            print_message("%s--%s: the reference's step and yours print alike, with no \"differs\" line\n", m->name,
                          m->slug);
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

/* The text after "label" on the report's line that starts with it
 * ("  reference  ..."), or NULL. */
static char *report_line(const char *report, const char *label)
{
    char key[64];
    snprintf(key, sizeof key, "\n  %-10s ", label);
    const char *a = strstr(report, key);
    if (!a) return NULL;
    a += strlen(key);
    return strndup(a, strcspn(a, "\n"));
}

/* The page sidx-check --html wrote (path) opens in headless Chromium from
 * file:// without a script error, and the step it highlights first is the
 * report's: the step number and the two events' lines.  Without chromium
 * it says so and returns. */
static void page_agrees(const char *path, const char *report)
{
    const char *browser = system("command -v chromium >/dev/null 2>&1") == 0          ? "chromium"
                          : system("command -v chromium-browser >/dev/null 2>&1") == 0 ? "chromium-browser"
                                                                                        : NULL;
    if (!browser) {
        print_message("no chromium: the --html page is not opened\n");
        return;
    }
    char real[PATH_MAX], cmd[4 * PATH_MAX + 512];
    assert_non_null(realpath(path, real));
    snprintf(cmd, sizeof cmd,
             "timeout 60 %s --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
             "--disable-background-networking --disable-component-update --disable-sync "
             "--user-data-dir=%s.profile --dump-dom 'file://%s' 2>/dev/null; rm -rf '%s.profile'",
             browser, real, real, real);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *dom;
    drain(p, &dom);
    char *st = strstr(dom, "<pre id=\"state\">"), *end = st ? strstr(st, "</pre>") : NULL;
    if (end) *end = '\0'; /* #state alone */
    if (!end || strstr(st, "error=")) print_message("the page's DOM:\n%.2000s\n", dom);
    assert_non_null(end);
    assert_null(strstr(st, "error="));
    assert_non_null(strstr(st, "status=ready"));
    /* the step: "leaves the reference at step K" */
    const char *at = strstr(report, "leaves the reference at step ");
    assert_non_null(at);
    char want[96];
    snprintf(want, sizeof want, "\npart=%ld\n", strtol(at + strlen("leaves the reference at step "), NULL, 10));
    assert_non_null(strstr(st, want));
    const char *const labels[] = {"reference", "yours"};
    for (int k = 0; k < 2; ++k) {
        char *line = report_line(report, labels[k]);
        assert_non_null(line);
        char key[600];
        snprintf(key, sizeof key, "\n%s=%s\n", labels[k], line);
        /* the DOM escapes nothing in these lines but &, < and > */
        if (!strstr(st, key)) print_message("the page's first highlighted step lacks \"%s\":\n%.600s\n", key + 1, st);
        assert_non_null(strstr(st, key));
        free(line);
    }
    free(dom);
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
    char page[sizeof dir + 16];
    snprintf(page, sizeof page, "%s/case.html", dir);
    snprintf(cmd, sizeof cmd, "'%s' 05_bvh_traversal %s --trace %s --html %s", checker, file, tdir, page);
    p = popen(cmd, "r");
    assert_non_null(p);
    assert_int_equal(drain(p, &out), 1);
    page_agrees(page, out);
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

/* Runs sidx-check NAME on NAME's solution with old replaced by new (and
 * extra arguments); returns its exit status and report. */
static int check_planted(const char *name, const char *old, const char *new_, const char *extra, char **out)
{
    mistake m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    snprintf(m.slug, sizeof m.slug, "inline");
    snprintf(m.old, sizeof m.old, "%s", old);
    snprintf(m.new_, sizeof m.new_, "%s", new_);
    char dir[] = "/tmp/sidx-test-ex-XXXXXX", file[PATH_MAX], cmd[3 * PATH_MAX];
    assert_non_null(mkdtemp(dir));
    assert_int_equal(plant(&m, dir, file, sizeof file), 0);
    snprintf(cmd, sizeof cmd, "'%s' %s '%s' %s 2>&1", checker, name, file, extra);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    const int rc = drain(p, out);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
    return rc;
}

/* The report's diagnosis and hints: two diverging events that print
 * alike (a plane hit at t = 5 and one a few ulps later) show the field
 * that differs; a painter that reports node 0 over [0, inf] (the
 * reference over [0, 0]) fails every case, and the diagnosis line
 * counts the failing cases, also in --summary's last field; a recursion
 * that never reaches its base case is told so. */
static void diagnosis_and_differs(void **state)
{
    (void)state;
    if (access("lessons/exercises/solutions", R_OK) != 0) {
        print_message("skipped: no solutions (a handout tree)\n");
        return;
    }
    char *out, summary[] = "/tmp/sidx-test-sum-XXXXXX", extra[64];
    const int fd = mkstemp(summary);
    assert_true(fd >= 0);
    close(fd);
    snprintf(extra, sizeof extra, "--summary %s", summary);
    int rc = check_planted("14_bsp_painter", "sidx_ex_node_enter(ex, node, depth, 0.0f, 0.0f);",
                           "sidx_ex_node_enter(ex, node, depth, 0.0f, INFINITY);", extra, &out);
    if (rc != 1 || !strstr(out, "  yours      node 0 enter  depth 0  t_near 0, t_far inf")) print_message("%s", out);
    assert_int_equal(rc, 1);
    /* the painter's driver prints the interval a node is reported with */
    assert_non_null(strstr(out, "  reference  node 0 enter  depth 0\n  yours      node 0 enter  depth 0  t_near 0, t_far inf"));
    char *diag = report_line(out, "diagnosis");
    assert_non_null(diag);
    assert_non_null(strstr(diag, "fails 21 of its 21 cases"));
    char *sum = slurp(summary);
    assert_non_null(sum);
    /* the eighth field is the diagnosis (the ninth, the containment) */
    const char *field = sum;
    for (int f = 1; f < 8 && field; ++f) {
        field = strchr(field, '\t');
        if (field) ++field;
    }
    assert_non_null(field);
    assert_true(!strncmp(field, diag, strlen(diag)));
    assert_int_equal(field[strlen(diag)], '\t');
    free(sum);
    free(diag);
    free(out);
    unlink(summary);
    /* a leaf never reached: the node's own range is split again and again */
    rc = check_planted("11_bvh_build", "    if (nl == 0) {\n", "    if (nl == 0 && count == 0) {\n", "", &out);
    if (rc != 2 || (!TK_UNDER_ASAN && !strstr(out, "does the recursion reach its base case?"))) print_message("%s", out);
    assert_int_equal(rc, 2);
    /* Under AddressSanitizer the student's code is instrumented too, and
     * this mistake's first out-of-bounds write ends it before the stack
     * overflows: the report is ASan's, with no recursion to tell of. */
    if (!TK_UNDER_ASAN) {
        assert_non_null(strstr(out, "crashed: signal 11"));
        assert_non_null(strstr(out, "endless recursion (the stack overflowed)"));
    }
    free(out);
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
    if (getenv("EX_TEST")) cmocka_set_test_filter(getenv("EX_TEST")); /* EX_TEST=rule_tables_agree: that test alone */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(solutions_pass),
        cmocka_unit_test(stubs_fail_cleanly),
        cmocka_unit_test(rule_tables_agree),
        cmocka_unit_test(planted_mistakes_caught),
        cmocka_unit_test(usage_and_errors),
        cmocka_unit_test(traces_and_diff),
        cmocka_unit_test(diagnosis_and_differs),
        cmocka_unit_test(kd_walk_bit_exact),
        cmocka_unit_test(variants_pass),
        cmocka_unit_test(mutant_sample_killed),
        cmocka_unit_test(mutate_field_writes),
        cmocka_unit_test(cc_of_several_words),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
