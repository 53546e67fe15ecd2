/* sidx-step — step through one ray's traversal (or a build) event by event.
 *
 *   sidx-step --accel NAME SCENE --ray ox,oy,oz,dx,dy,dz [--all] [--json] [--build]
 *   sidx-step --diff A.jsonl B.jsonl [--exact] [--notes]
 *
 * One event per line, indented by depth (sidx_event_format, the printer's
 * layout), or JSON Lines with --json.  When stdin and stdout are both a
 * terminal it waits for Enter after each line ('a' + Enter prints the rest,
 * 'q' + Enter stops); otherwise, or with --all, it prints everything.
 * --diff aligns two JSON Lines traces (as --json and sidx-check --trace
 * write them) event by event, prints the first divergence and the count of
 * each event type on both sides.
 * Exit status: 0 ok (--diff: the traces agree), 1 failure (--diff: they
 * part), 2 usage. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: sidx-step --accel NAME SCENE [--ray ox,oy,oz,dx,dy,dz] [--build] [--all] [--json]\n"
            "       sidx-step --diff A.jsonl B.jsonl [--exact] [--notes]\n"
            "\n"
            "Builds structure NAME over SCENE (a .obj/.ply file or a built-in scene such as\n"
            "teapot, flat2d) and prints the ray's traversal one event per line, indented by\n"
            "depth.  On a terminal it waits for Enter between steps (a = all, q = quit).\n"
            "\n"
            "  --accel NAME       structure (see --list)\n"
            "  --ray R            the ray: origin ox,oy,oz and direction dx,dy,dz\n"
            "  --build            print the build decisions (before the traversal, if --ray)\n"
            "  --traversal KIND   default, stack, ordered or naive\n"
            "  --leaf-size N      build option: leaf at or below N primitives\n"
            "  --bounds           also print node boxes\n"
            "  --all              do not wait between steps\n"
            "  --json             JSON Lines (one object per event) instead of text\n"
            "  --list             list the registered structures\n"
            "  --diff A B         compare two JSON Lines traces event by event: the first\n"
            "                     divergence and the events of each type on both sides\n"
            "                     (exit 0 agree, 1 they part); floats agree within 1e-5\n"
            "                     relative unless --exact; note events are skipped unless --notes\n"
            "  -h, --help         this help\n");
}

typedef struct step_out {
    int json, bounds, interactive, stop;
    FILE *in;
} step_out;

static void print_event(step_out *o, const sidx_event *ev)
{
    char small[512];
    char *buf = small;
    int n = o->json ? sidx_event_to_json(ev, buf, sizeof small) : sidx_event_format(ev, buf, sizeof small);
    if (n < 0) return;
    if ((size_t)n >= sizeof small) {
        buf = malloc((size_t)n + 1);
        if (!buf) return;
        n = o->json ? sidx_event_to_json(ev, buf, (size_t)n + 1) : sidx_event_format(ev, buf, (size_t)n + 1);
    }
    if (!o->json && o->bounds && (ev->type == SIDX_EV_NODE_ENTER || ev->type == SIDX_EV_BUILD_NODE ||
                                  ev->type == SIDX_EV_BOX_TEST) && !sidx_aabb_is_empty(ev->bounds))
        printf("%s  box [(%g, %g, %g), (%g, %g, %g)]\n", buf, (double)ev->bounds.min.x, (double)ev->bounds.min.y,
               (double)ev->bounds.min.z, (double)ev->bounds.max.x, (double)ev->bounds.max.y,
               (double)ev->bounds.max.z);
    else
        printf("%s\n", buf);
    if (buf != small) free(buf);
    fflush(stdout);
    if (o->interactive) {
        char line[64];
        if (!fgets(line, sizeof line, o->in)) {
            o->interactive = 0; /* EOF: print the rest */
        } else if (line[0] == 'q') {
            o->stop = 1;
        } else if (line[0] == 'a') {
            o->interactive = 0;
        }
    }
}

static void print_all(step_out *o, const sidx_recorder *r)
{
    for (size_t i = 0; i < r->count && !o->stop; ++i) print_event(o, &r->events[i]);
}

/* ---- --diff: two JSON Lines traces side by side ------------------------------- */

/* One trace line: its top-level "key":value pairs, values kept as text
 * (numbers, "strings", null, [arrays], {objects}).  The lines are sidx's
 * own (sidx_event_to_json), so a flat scanner is enough. */
#define DIFF_MAX_FIELDS 32
typedef struct diff_ev {
    char *line;                     /* the line as read (kept for printing) */
    char *copy;                     /* scanned copy the fields point into */
    int n;
    const char *key[DIFF_MAX_FIELDS], *val[DIFF_MAX_FIELDS];
    size_t lineno;
} diff_ev;

typedef struct diff_trace {
    diff_ev *ev;
    size_t n, cap;
} diff_trace;

static char *scan_value(char *p)
{
    if (*p == '"') {
        for (++p; *p && *p != '"'; ++p)
            if (*p == '\\' && p[1]) ++p;
        return *p ? p + 1 : p;
    }
    if (*p == '[' || *p == '{') {
        int depth = 0;
        for (; *p; ++p) {
            if (*p == '"') {
                p = scan_value(p) - 1;
                continue;
            }
            if (*p == '[' || *p == '{') ++depth;
            if ((*p == ']' || *p == '}') && --depth == 0) return p + 1;
        }
        return p;
    }
    while (*p && *p != ',' && *p != '}') ++p;
    return p;
}

static int parse_line(diff_ev *e)
{
    char *p = e->copy;
    while (*p == ' ') ++p;
    if (*p != '{') return -1;
    ++p;
    e->n = 0;
    while (*p && *p != '}') {
        if (*p == ',' || *p == ' ') {
            ++p;
            continue;
        }
        if (*p != '"' || e->n == DIFF_MAX_FIELDS) return -1;
        char *k = p + 1, *ke = strchr(k, '"');
        if (!ke || ke[1] != ':') return -1;
        *ke = '\0';
        char *v = ke + 2, *ve = scan_value(v);
        const char c = *ve;
        *ve = '\0';
        e->key[e->n] = k;
        e->val[e->n] = v;
        ++e->n;
        p = c ? ve + 1 : ve;
        if (c == '}') break;
    }
    return 0;
}

static const char *ev_get(const diff_ev *e, const char *key)
{
    for (int i = 0; i < e->n; ++i)
        if (!strcmp(e->key[i], key)) return e->val[i];
    return NULL;
}

static int read_trace(const char *path, diff_trace *t, int notes)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "sidx-step: cannot open %s: %s\n", path, strerror(errno));
        return -1;
    }
    char *line = NULL;
    size_t cap = 0, lineno = 0;
    ssize_t len;
    int rc = 0;
    while ((len = getline(&line, &cap, f)) >= 0) {
        ++lineno;
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = '\0';
        if (len == 0) continue;
        if (t->n == t->cap) {
            const size_t nc = t->cap ? 2 * t->cap : 256;
            diff_ev *ne = realloc(t->ev, nc * sizeof *ne);
            if (!ne) {
                rc = -1;
                break;
            }
            t->ev = ne;
            t->cap = nc;
        }
        diff_ev *e = &t->ev[t->n];
        e->line = strdup(line);
        e->copy = strdup(line);
        e->lineno = lineno;
        if (!e->line || !e->copy || parse_line(e) != 0 || !ev_get(e, "type")) {
            fprintf(stderr, "sidx-step: %s:%zu: not a sidx event (JSON object with a \"type\")\n", path, lineno);
            free(e->line);
            free(e->copy);
            rc = -1;
            break;
        }
        if (!notes && !strcmp(ev_get(e, "type"), "\"note\"")) {
            free(e->line);
            free(e->copy);
            continue;
        }
        ++t->n;
    }
    free(line);
    fclose(f);
    return rc;
}

static void free_trace(diff_trace *t)
{
    for (size_t i = 0; i < t->n; ++i) {
        free(t->ev[i].line);
        free(t->ev[i].copy);
    }
    free(t->ev);
}

/* A float as sidx writes it: a number or "inf", "-inf", "nan". */
static int as_float(const char *v, double *out)
{
    if (!strcmp(v, "\"inf\"")) *out = INFINITY;
    else if (!strcmp(v, "\"-inf\"")) *out = -INFINITY;
    else if (!strcmp(v, "\"nan\"")) *out = NAN;
    else {
        char *end;
        *out = strtod(v, &end);
        return end != v && *end == '\0';
    }
    return 1;
}

static int same_value(const char *a, const char *b, int exact)
{
    if (!strcmp(a, b)) return 1;
    double x, y;
    if (exact || !as_float(a, &x) || !as_float(b, &y)) return 0;
    if (isnan(x) || isnan(y)) return isnan(x) && isnan(y);
    if (isinf(x) || isinf(y)) return x == y;
    const double m = fabs(x) > fabs(y) ? fabs(x) : fabs(y);
    return fabs(x - y) <= 1e-5 * m + 1e-7;
}

/* The fields of a and b that differ ("structure" and "ray" name the
 * producer, not the step, and are not compared); 0 if none. */
static int diff_fields(const diff_ev *a, const diff_ev *b, int exact, char *why, size_t size)
{
    int n = 0;
    size_t off = 0;
    why[0] = '\0';
    for (int pass = 0; pass < 2; ++pass) {
        const diff_ev *x = pass ? b : a, *y = pass ? a : b;
        for (int i = 0; i < x->n; ++i) {
            const char *k = x->key[i];
            if (!strcmp(k, "structure") || !strcmp(k, "ray")) continue;
            const char *other = ev_get(y, k);
            if (pass && other) continue; /* both have it: compared in the first pass */
            if (other && same_value(x->val[i], other, exact)) continue;
            const char *va = pass ? (other ? other : "absent") : x->val[i];
            const char *vb = pass ? x->val[i] : (other ? other : "absent");
            if (off < size) off += (size_t)snprintf(why + off, size - off, "%s%s: %s vs %s", n ? ", " : "", k, va, vb);
            ++n;
        }
    }
    return n;
}

static int diff_main(int argc, char **argv)
{
    const char *pa = NULL, *pb = NULL;
    int exact = 0, notes = 0;
    for (int i = 2; i < argc; ++i) {
        if (!strcmp(argv[i], "--exact")) exact = 1;
        else if (!strcmp(argv[i], "--notes")) notes = 1;
        else if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "sidx-step: unknown option for --diff: %s\n", argv[i]);
            return 2;
        } else if (!pa) pa = argv[i];
        else if (!pb) pb = argv[i];
        else {
            fprintf(stderr, "sidx-step: --diff takes two files\n");
            return 2;
        }
    }
    if (!pa || !pb) {
        fprintf(stderr, "sidx-step: --diff wants two JSON Lines files: sidx-step --diff A.jsonl B.jsonl\n");
        return 2;
    }
    diff_trace a = {0}, b = {0};
    int rc = 2;
    if (read_trace(pa, &a, notes) != 0 || read_trace(pb, &b, notes) != 0) goto out;
    size_t i = 0;
    char why[1024];
    while (i < a.n && i < b.n && diff_fields(&a.ev[i], &b.ev[i], exact, why, sizeof why) == 0) ++i;
    if (i == a.n && i == b.n) {
        printf("the traces agree: %zu events\n", a.n);
        rc = 0;
    } else {
        printf("the traces part at event %zu", i + 1);
        if (i < a.n && i < b.n) printf(" (%s line %zu, %s line %zu)", pa, a.ev[i].lineno, pb, b.ev[i].lineno);
        printf("\n");
        for (size_t k = i > 3 ? i - 3 : 0; k < i; ++k) printf("  same  %s\n", a.ev[k].line);
        printf("  A     %s\n", i < a.n ? a.ev[i].line : "(the trace ends here)");
        printf("  B     %s\n", i < b.n ? b.ev[i].line : "(the trace ends here)");
        if (i < a.n && i < b.n) printf("  differ: %s\n", why);
        rc = 1;
    }
    /* events of each type on both sides, in the order types first appear */
    const char *types[64];
    size_t ca[64], cb[64], nt = 0;
    for (int side = 0; side < 2; ++side) {
        const diff_trace *t = side ? &b : &a;
        for (size_t k = 0; k < t->n; ++k) {
            const char *ty = ev_get(&t->ev[k], "type");
            size_t j = 0;
            while (j < nt && strcmp(types[j], ty)) ++j;
            if (j == nt) {
                if (nt == 64) continue;
                types[nt] = ty;
                ca[nt] = cb[nt] = 0;
                ++nt;
            }
            ++*(side ? &cb[j] : &ca[j]);
        }
    }
    printf("%-20s %8s %8s\n", "events", "A", "B");
    for (size_t j = 0; j < nt; ++j) {
        char name[64];
        snprintf(name, sizeof name, "%.*s", (int)strlen(types[j]) - 2, types[j] + 1);
        printf("  %-18s %8zu %8zu%s\n", name, ca[j], cb[j], ca[j] != cb[j] ? "  *" : "");
    }
    printf("  %-18s %8zu %8zu\n", "total", a.n, b.n);
out:
    free_trace(&a);
    free_trace(&b);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "--diff")) return diff_main(argc, argv);
    const char *accel = NULL, *scene = NULL;
    int all = 0, json = 0, build = 0, has_ray = 0, bounds = 0;
    sidx_vec3 org = {0, 0, 0}, dir = {0, 0, 0};
    sidx_traversal trav = SIDX_TRAVERSE_DEFAULT;
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const int has_val = i + 1 < argc;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--list")) {
            for (size_t k = 0; k < sidx_accel_registered_count(); ++k)
                printf("%-14s %s\n", sidx_accel_registered_name(k), sidx_accel_registered_description(k));
            return 0;
        } else if (!strcmp(a, "--all")) {
            all = 1;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--build")) {
            build = 1;
        } else if (!strcmp(a, "--bounds")) {
            bounds = 1;
        } else if (!strcmp(a, "--accel") && has_val) {
            accel = argv[++i];
        } else if (!strcmp(a, "--traversal") && has_val) {
            if (sidx_traversal_parse(argv[++i], &trav) != SIDX_OK) {
                fprintf(stderr, "sidx-step: --traversal wants default, stack, ordered or naive, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--leaf-size") && has_val) {
            char *end;
            long k = strtol(argv[++i], &end, 10);
            if (*end || k < 1 || k > 1000000) {
                fprintf(stderr, "sidx-step: --leaf-size wants a number >= 1, not '%s'\n", argv[i]);
                return 2;
            }
            bo.leaf_size = (uint32_t)k;
        } else if (!strcmp(a, "--ray") && has_val) {
            if (sidx_viz_parse_ray(argv[++i], &org, &dir) != 0) {
                fprintf(stderr, "sidx-step: --ray wants ox,oy,oz,dx,dy,dz (finite, non-zero direction), not '%s'\n",
                        argv[i]);
                return 2;
            }
            has_ray = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "sidx-step: unknown option or missing value: %s\n", a);
            usage(stderr);
            return 2;
        } else if (!scene) {
            scene = a;
        } else {
            fprintf(stderr, "sidx-step: more than one SCENE ('%s', '%s')\n", scene, a);
            return 2;
        }
    }
    if (!accel || !scene || (!has_ray && !build)) {
        fprintf(stderr, "sidx-step: --accel, SCENE and --ray (or --build) are required\n");
        usage(stderr);
        return 2;
    }
    if (!sidx_accel_is_registered(accel)) {
        fprintf(stderr, "sidx-step: no structure named '%s' (try --list)\n", accel);
        return 2;
    }

    sidx_mesh mesh;
    sidx_error err;
    memset(&mesh, 0, sizeof mesh);
    if (sidx_scene_open(scene, &mesh, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-step: %s\n", err.message);
        return 1;
    }
    sidx_recorder brec, trec;
    sidx_recorder_init(&brec);
    sidx_recorder_init(&trec);
    sidx_hook bh = sidx_recorder_hook(&brec);
    bh.mask = SIDX_EVMASK_BUILD | SIDX_EVMASK(SIDX_EV_NOTE);
    if (build) bo.hook = &bh;
    sidx_accel *acc = NULL;
    int rc = 0;
    if (sidx_accel_build(accel, &mesh, &bo, &acc, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-step: building %s: %s\n", accel, err.message);
        rc = 1;
        goto done;
    }
    if (has_ray) {
        sidx_ray ray;
        if (sidx_ray_init(&ray, org, dir, 0.0f, INFINITY) != SIDX_OK) {
            fprintf(stderr, "sidx-step: invalid ray\n");
            rc = 2;
            goto done;
        }
        sidx_hook th = sidx_recorder_hook(&trec);
        th.mask = SIDX_EVMASK_TRAVERSAL;
        sidx_query q;
        memset(&q, 0, sizeof q);
        q.traversal = trav;
        q.hook = &th;
        sidx_hit hit;
        sidx_accel_intersect(acc, &ray, &q, &hit);
    }
    if (brec.overflow || trec.overflow) {
        fprintf(stderr, "sidx-step: out of memory recording the events\n");
        rc = 1;
        goto done;
    }
    {
        step_out o = {json, bounds, !all && isatty(STDIN_FILENO) && isatty(STDOUT_FILENO), 0, stdin};
        if (o.interactive) fprintf(stderr, "(Enter: next step   a Enter: all   q Enter: quit)\n");
        if (build) print_all(&o, &brec);
        if (has_ray) print_all(&o, &trec);
    }
    if (fflush(stdout) != 0 || ferror(stdout)) rc = 1;
done:
    sidx_accel_destroy(acc);
    sidx_recorder_free(&brec);
    sidx_recorder_free(&trec);
    sidx_mesh_free(&mesh);
    return rc;
}
