/* sidx-step — step through one ray's traversal (or a build) event by event.
 *
 *   sidx-step --accel NAME SCENE --ray ox,oy,oz,dx,dy,dz [--all] [--json] [--build]
 *
 * One event per line, indented by depth (sidx_event_format, the printer's
 * layout), or JSON Lines with --json.  When stdin and stdout are both a
 * terminal it waits for Enter after each line ('a' + Enter prints the rest,
 * 'q' + Enter stops); otherwise, or with --all, it prints everything.
 * Exit status: 0 ok, 1 failure, 2 usage. */
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

int main(int argc, char **argv)
{
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
