/* class_mode.c — sidx-check --class: every student's files of a class
 * directory checked, N at a time, and the lecturer's summaries written
 * (summary.md, summary.csv, one report per student; docs/exercises.md,
 * "Class mode").  Each file is checked as `sidx-check NAME FILE` checks it
 * (the front end's check function, in a child whose output becomes the
 * student's report); the runner's --summary line of each is read back. */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include "class_mode.h"

const ck_exercise ck_exercises[] = {
#define EX(n, t) {n, t},
#include "list.def"
#undef EX
};
const size_t ck_num_exercises = sizeof ck_exercises / sizeof ck_exercises[0];

typedef struct class_job {
    size_t student, ex;
    char report[2 * PATH_MAX + 64], summary[2 * PATH_MAX + 64];
    int rc;
    /* from the summary line */
    char result[16], case_name[200], detail[2400], hint[1024];
    char attempts[4096]; /* "NOT CONTAINED; write /tmp/x (refused: ...); ..." or "" */
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
        (void)next_field(&p); /* the diagnosis: the student's report has it in full */
        snprintf(j->attempts, sizeof j->attempts, "%s", next_field(&p));
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
    else if (!strcmp(j->result, "borrowed")) {
        char sym[200] = "";
        if (sscanf(j->detail, "%*s %199s", sym) == 1) sym[strcspn(sym, ",")] = '\0';
        snprintf(buf, size, "borrowed: %s", sym);
    }
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

int ck_class_mode(const char *dir, const char *out_arg, long jobs, char **pass, int npass, ck_check_fn check_one)
{
    int unsafe = 0;
    for (int k = 0; k < npass; ++k) unsafe |= !strcmp(pass[k], "--unsafe");
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
    class_job *job = calloc(ns * ck_num_exercises + 1, sizeof *job);
    size_t nj = 0;
    for (size_t s = 0; s < ns; ++s)
        for (size_t k = 0; k < ck_num_exercises; ++k) {
            char file[PATH_MAX];
            snprintf(file, sizeof file, "%s/%s/%s.c", dir, students[s], ck_exercises[k].name);
            if (access(file, F_OK) != 0) continue;
            class_job *j = &job[nj++];
            j->student = s;
            j->ex = k;
            snprintf(j->report, sizeof j->report, "%s/.%s--%s.txt", out, students[s], ck_exercises[k].name);
            snprintf(j->summary, sizeof j->summary, "%s/.%s--%s.sum", out, students[s], ck_exercises[k].name);
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
                snprintf(file, sizeof file, "%s/%s/%s.c", dir, students[j->student], ck_exercises[j->ex].name);
                printf("$ sidx-check %s %s\n", ck_exercises[j->ex].name, file);
                /* a failing case also as a page, STUDENT--NAME.html (written
                 * only when the check fails; the summary links it) */
                char page[2 * PATH_MAX + 64], *args[48];
                int na = 0;
                for (int k = 0; k < npass && na < 44; ++k) args[na++] = pass[k];
                snprintf(page, sizeof page, "%s/%s--%s.html", out, students[j->student], ck_exercises[j->ex].name);
                args[na++] = "--html";
                args[na++] = page;
                const int rc = check_one(j->ex, file, args, na, j->summary);
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
    fprintf(csv, "student,exercise,result,case,cases,step,case_name,detail,hint,report,outside\n");
    int used[sizeof ck_exercises / sizeof ck_exercises[0]] = {0};
    for (size_t k = 0; k < nj; ++k) used[job[k].ex] = 1;
    fprintf(md, "# sidx-check: class %s\n\n%zu students, %zu files checked%s.\n\n| student |", dir, ns, nj,
            unsafe ? ", NOT CONTAINED (--unsafe): the students' code ran with the lecturer's rights" : "");
    for (size_t x = 0; x < ck_num_exercises; ++x)
        if (used[x]) fprintf(md, " %s |", ck_exercises[x].name);
    fprintf(md, "\n|---|");
    for (size_t x = 0; x < ck_num_exercises; ++x)
        if (used[x]) fprintf(md, "---|");
    fprintf(md, "\n");
    for (size_t s = 0; s < ns; ++s) {
        fprintf(md, "| ");
        md_text(md, students[s]);
        fprintf(md, " |");
        for (size_t x = 0; x < ck_num_exercises; ++x) {
            if (!used[x]) continue;
            const class_job *j = NULL;
            for (size_t k = 0; k < nj && !j; ++k)
                if (job[k].student == s && job[k].ex == x) j = &job[k];
            char c[300];
            if (j) cell(j, c, sizeof c);
            else snprintf(c, sizeof c, "\u2013");
            /* tried outside its directory: marked, listed below */
            if (j && j->attempts[0] && strcmp(j->attempts, "NOT CONTAINED"))
                snprintf(c + strlen(c), sizeof c - strlen(c), " (escape attempt)");
            fprintf(md, " ");
            md_text(md, c);
            fprintf(md, " |");
        }
        fprintf(md, "\n");
    }
    fprintf(md, "\n| exercise | submitted | pass |\n|---|---|---|\n");
    for (size_t x = 0; x < ck_num_exercises; ++x) {
        if (!used[x]) continue;
        int sub = 0, ok = 0;
        for (size_t k = 0; k < nj; ++k)
            if (job[k].ex == x) {
                ++sub;
                ok += !strcmp(job[k].result, "pass");
            }
        fprintf(md, "| %s | %d | %d |\n", ck_exercises[x].name, sub, ok);
    }
    /* what tried to get out, and what took the library's answer: their own list */
    int listed = 0;
    for (size_t k = 0; k < nj; ++k) {
        const class_job *j = &job[k];
        const char *att = j->attempts;
        if (!strncmp(att, "NOT CONTAINED", 13)) att += 13 + strspn(att + 13, "; ");
        if (!att[0] && strcmp(j->result, "borrowed")) continue;
        if (!listed++) fprintf(md, "\n## Borrowed answers and attempts outside the sandbox\n\n");
        fprintf(md, "- **");
        md_text(md, students[j->student]);
        fprintf(md, "**, `%s`: ", ck_exercises[j->ex].name);
        if (!strcmp(j->result, "borrowed")) {
            fprintf(md, "borrowed answer: ");
            md_text(md, j->detail);
            if (att[0]) fprintf(md, "; ");
        }
        if (att[0]) {
            fprintf(md, "tried outside its directory: ");
            md_text(md, att);
        }
        fprintf(md, "\n");
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
        csv_field(csv, ck_exercises[j->ex].name, 0);
        csv_field(csv, j->result, 0);
        csv_field(csv, num[0], 0);
        csv_field(csv, num[1], 0);
        csv_field(csv, num[2], 0);
        csv_field(csv, j->case_name, 0);
        csv_field(csv, j->detail, 0);
        csv_field(csv, j->hint, 0);
        csv_field(csv, rep, 0);
        csv_field(csv, j->attempts, 1);
        if (!strcmp(j->result, "pass")) continue;
        fprintf(md, "- **");
        md_text(md, students[j->student]);
        fprintf(md, "**, `%s`: ", ck_exercises[j->ex].name);
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
        } else if (!strcmp(j->result, "borrowed")) {
            fprintf(md, "borrowed answer: your code ");
            md_text(md, j->detail);
        } else {
            if (j->case_) fprintf(md, "case %lu of %lu: ", j->case_, j->cases);
            fprintf(md, "your code ");
            md_text(md, j->detail);
        }
        fprintf(md, " ([report](");
        md_text(md, rep);
        char page[2 * PATH_MAX + 64];
        snprintf(page, sizeof page, "%s/%s--%s.html", out, students[j->student], ck_exercises[j->ex].name);
        if (access(page, R_OK) == 0) {
            fprintf(md, "), [page](");
            md_text(md, students[j->student]);
            fprintf(md, "--%s.html", ck_exercises[j->ex].name);
        }
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
