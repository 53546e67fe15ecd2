/* sidx-lab — the web lab's entry layer (viz/lab.h) from the command line.
 *
 *   sidx-lab [SCRIPT]
 *
 * Runs a script of lab calls, one per line, and prints each call's status
 * and JSON answer: the answers the page (build/web/sidx-lab.html) gets
 * from the same calls in WebAssembly.  tests/run_web_module.sh runs one
 * script here and through the module in Node and compares the two.
 * Exit status: 0 ok (a call that fails is an answer, not a failure),
 * 1 the script or a file it names cannot be read (or written), 2 usage or a line that
 * is no command. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "lab.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: sidx-lab [SCRIPT]\n"
            "\n"
            "Runs the web lab's calls (viz/lab.h) natively, one per line of SCRIPT (or of\n"
            "stdin), and prints for each the line itself after '> ', then 'rc N message'\n"
            "and its JSON answer.  Commands ('#' starts a comment line):\n"
            "  scenes                              the built-in scenes\n"
            "  structures                          the structures, and which suit the scene\n"
            "  open NAME                           a built-in scene (teapot, kd-slide, name:detail)\n"
            "  obj FILE                            an OBJ (or .ply) file, read as the page reads a dropped one\n"
            "  saveobj FILE                        write the open scene as OBJ (exactly its floats)\n"
            "  build SLOT ACCEL [KNOBS]            build in slot 0 or 1; KNOBS a JSON object, e.g.\n"
            "                                      {\"bins\":16,\"mailbox\":false}\n"
            "  events SLOT                         the slot's build events with the SAH candidates\n"
            "  trace SLOT OX OY OZ DX DY DZ        trace a ray; prints the trace\n"
            "  diverge                             where the traces of slots 0 and 1 part\n"
            "  heat SLOT YAW PITCH ZOOM W H WHAT   heat map (WHAT 0 steps, 1 triangle tests): its\n"
            "                                      summary and an FNV-1a hash of the counts\n"
            "  camray YAW PITCH ZOOM W H PX PY     the camera ray through an image point\n"
            "  bench SLOT YAW PITCH ZOOM W H N     primary rays without a hook, N times: Mrays/s\n"
            "  -h, --help                          this help\n");
}

static void status_line(int rc)
{
    printf("rc %d %s\n", rc, sidx_lab_error());
}

/* The FNV-1a hash of the counts, byte by byte, little-endian. */
static unsigned long long fnv1a(const uint32_t *v, size_t n)
{
    unsigned long long h = 14695981039346656037ull;
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 4; ++k) {
            h ^= (v[i] >> (8 * k)) & 0xffu;
            h *= 1099511628211ull;
        }
    return h;
}

static char *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 65536, n = 0;
    char *buf = malloc(cap);
    while (buf) {
        n += fread(buf + n, 1, cap - n, f);
        if (n < cap) break;
        char *b = realloc(buf, cap * 2);
        if (!b) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = b;
        cap *= 2;
    }
    const int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return NULL;
    }
    *len = n;
    return buf;
}

/* Parses k numbers from p into v; the rest of the line after them, or NULL. */
static const char *numbers(const char *p, double *v, int k)
{
    for (int i = 0; i < k; ++i) {
        char *end;
        v[i] = strtod(p, &end);
        if (end == p) return NULL;
        p = end;
    }
    while (*p == ' ' || *p == '\t') ++p;
    return p;
}

/* Runs one line; 0 ok, 1 a file it names cannot be read, 2 not a command. */
static int run_line(char *line)
{
    size_t n = strlen(line);
    while (n && (line[n - 1] == '\n' || line[n - 1] == '\r' || line[n - 1] == ' ')) line[--n] = '\0';
    char *p = line;
    while (*p == ' ' || *p == '\t') ++p;
    if (!*p || *p == '#') return 0;
    printf("> %s\n", p);
    char cmd[16];
    int used = 0;
    if (sscanf(p, "%15s%n", cmd, &used) != 1) return 2;
    const char *rest = p + used;
    while (*rest == ' ' || *rest == '\t') ++rest;
    double v[8];
    if (!strcmp(cmd, "scenes") && !*rest) {
        printf("%s\n", sidx_lab_scenes());
    } else if (!strcmp(cmd, "structures") && !*rest) {
        printf("%s\n", sidx_lab_structures());
    } else if (!strcmp(cmd, "open") && *rest) {
        const int rc = sidx_lab_open_scene(rest);
        status_line(rc);
        printf("%s\n", sidx_lab_scene_json());
    } else if (!strcmp(cmd, "obj") && *rest) {
        size_t len = 0;
        char *bytes = read_file(rest, &len);
        if (!bytes) {
            fprintf(stderr, "sidx-lab: cannot read %s: %s\n", rest, strerror(errno));
            return 1;
        }
        const char *slash = strrchr(rest, '/');
        const int rc = sidx_lab_open_obj(bytes, (int)len, slash ? slash + 1 : rest);
        free(bytes);
        status_line(rc);
        printf("%s\n", sidx_lab_scene_json());
    } else if (!strcmp(cmd, "saveobj") && *rest) {
        FILE *o = fopen(rest, "wb");
        const char *text = sidx_lab_scene_obj();
        if (!o || fputs(text, o) < 0 || fclose(o) != 0) {
            fprintf(stderr, "sidx-lab: cannot write %s: %s\n", rest, strerror(errno));
            return 1;
        }
        printf("%zu bytes\n", strlen(text));
    } else if (!strcmp(cmd, "build") && *rest) {
        char accel[64];
        int slot, k = 0;
        if (sscanf(rest, "%d %63s%n", &slot, accel, &k) != 2) return 2;
        const char *knobs = rest + k;
        while (*knobs == ' ') ++knobs;
        const int rc = sidx_lab_build(slot, accel, knobs);
        status_line(rc);
        printf("%s\n", sidx_lab_build_json(slot));
    } else if (!strcmp(cmd, "events") && (rest = numbers(rest, v, 1)) && !*rest) {
        printf("%s\n", sidx_lab_build_events_json((int)v[0]));
    } else if (!strcmp(cmd, "trace") && (rest = numbers(rest, v, 7)) && !*rest) {
        const int rc = sidx_lab_trace((int)v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
        status_line(rc);
        printf("%s\n", sidx_lab_trace_json((int)v[0]));
    } else if (!strcmp(cmd, "diverge") && !*rest) {
        printf("%s\n", sidx_lab_diverge_json());
    } else if (!strcmp(cmd, "heat") && (rest = numbers(rest, v, 7)) && !*rest) {
        const int rc = sidx_lab_heatmap((int)v[0], v[1], v[2], v[3], (int)v[4], (int)v[5], (int)v[6]);
        status_line(rc);
        printf("%s\n", sidx_lab_heatmap_json());
        if (rc == 0) printf("hash %016llx\n", fnv1a(sidx_lab_heatmap_data(), (size_t)v[4] * (size_t)v[5]));
    } else if (!strcmp(cmd, "camray") && (rest = numbers(rest, v, 7)) && !*rest) {
        printf("%s\n", sidx_lab_camera_ray(v[0], v[1], v[2], (int)v[3], (int)v[4], v[5], v[6]));
    } else if (!strcmp(cmd, "bench") && (rest = numbers(rest, v, 7)) && !*rest) {
        printf("%s\n", sidx_lab_bench((int)v[0], v[1], v[2], v[3], (int)v[4], (int)v[5], (int)v[6]));
    } else {
        return 2;
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "sidx-lab: unknown option %s\n", argv[i]);
            usage(stderr);
            return 2;
        } else if (!path) {
            path = argv[i];
        } else {
            fprintf(stderr, "sidx-lab: one SCRIPT at most\n");
            return 2;
        }
    }
    FILE *f = path && strcmp(path, "-") ? fopen(path, "r") : stdin;
    if (!f) {
        fprintf(stderr, "sidx-lab: cannot read %s: %s\n", path, strerror(errno));
        return 1;
    }
    char line[4096];
    int rc = 0, lineno = 0;
    while (!rc && fgets(line, sizeof line, f)) {
        ++lineno;
        rc = run_line(line);
        if (rc == 2) fprintf(stderr, "sidx-lab: line %d: not a command (see --help): %s\n", lineno, line);
    }
    if (f != stdin) fclose(f);
    sidx_lab_reset();
    if (fflush(stdout) != 0 || ferror(stdout)) rc = 1;
    return rc;
}
