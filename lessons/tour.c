/* tour.c — the guided tour of sidx (`make demo`, build/bin/sidx-tour).
 *
 * For every registered structure, on one built-in scene: build it and print
 * its first build decisions, trace one ray and print every event the
 * traversal produced (the first lines of it, unless --full), then the
 * summary counters; tree structures also get a Graphviz drawing written to
 * a path it names.  New structures join the tour by being registered.
 *
 *   sidx-tour [--scene NAME|FILE] [--accel a,b,...] [--full] [--out DIR]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"
#include "lesson.h"

typedef struct {
    sidx_printer printer;
    sidx_hook inner;
    long shown, skipped, limit;
} limited_printer;

/* Prints the first `limit` events, then only counts the rest. */
static void limited_fn(const sidx_event *ev, void *user)
{
    limited_printer *lp = user;
    if (lp->limit < 0 || lp->shown < lp->limit) {
        lp->inner.fn(ev, lp->inner.user);
        lp->shown++;
    } else {
        lp->skipped++;
    }
}

static void usage(FILE *f)
{
    fprintf(f, "usage: sidx-tour [--scene NAME|FILE] [--accel LIST] [--full] [--out DIR]\n"
               "\n"
               "A guided tour: for each registered structure, build it on a scene, print its build\n"
               "decisions and every traversal event of one ray, then the event counters; trees are\n"
               "drawn with Graphviz into DIR (default build/tour).\n"
               "\n"
               "  --scene S    built-in scene name (see below) or an .obj/.ply file (default: teapot)\n"
               "  --accel L    comma-separated structures (default: all registered)\n"
               "  --full       print every event instead of the first 40 of each phase\n"
               "  --out DIR    where the .svg trees go (default: build/tour)\n"
               "\nbuilt-in scenes:");
    for (const char *const *n = sidx_scene_names(); *n; ++n) fprintf(f, " %s", *n);
    fprintf(f, "\nstructures:");
    for (size_t i = 0; i < sidx_accel_registered_count(); ++i) fprintf(f, " %s", sidx_accel_registered_name(i));
    fprintf(f, "\n");
}

static int wanted(const char *list, const char *name)
{
    if (!list) return 1;
    size_t n = strlen(name);
    for (const char *p = list; (p = strstr(p, name)) != NULL; p += n)
        if ((p == list || p[-1] == ',') && (p[n] == ',' || p[n] == '\0')) return 1;
    return 0;
}

int main(int argc, char **argv)
{
    const char *accels = NULL, *outdir = "build/tour";
    int full = 0;
    const lesson_option options[] = {
        {"--accel", .text = &accels}, {"--out", .text = &outdir}, {"--full", .on = &full}, {0}};
    lesson_args args = {.name = "sidx-tour", .usage = usage, .scene = "teapot", .scene_flag = "--scene",
                        .options = options};
    lesson_parse(&args, argc, argv);
    const long limit = full ? -1 : 40;
    if (accels)
        for (const char *p = accels; *p;) {
            char name[64];
            size_t n = strcspn(p, ",");
            if (n >= sizeof name) n = sizeof name - 1;
            memcpy(name, p, n);
            name[n] = '\0';
            if (!sidx_accel_is_registered(name)) {
                fprintf(stderr, "sidx-tour: unknown structure '%s'\n", name);
                return 2;
            }
            p += strcspn(p, ",");
            if (*p == ',') ++p;
        }

    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    const sidx_aabb box = sidx_mesh_bounds(&mesh);
    const sidx_vec3 c = sidx_aabb_centroid(box), e = sidx_aabb_extent(box);
    printf("sidx %s — guided tour\n\n", sidx_version());
    printf("Scene '%s': %u triangles, %u vertices, box (%g %g %g) – (%g %g %g)\n", args.scene, mesh.num_triangles,
           mesh.num_vertices, box.min.x, box.min.y, box.min.z, box.max.x, box.max.y, box.max.z);

    /* One ray from in front of the scene, slightly off-centre so it passes
     * several nodes before it hits. */
    sidx_ray ray;
    const sidx_vec3 org = sidx_v3(c.x + 0.11f * e.x, c.y + 0.07f * e.y, box.max.z + 1.5f * (e.x + e.y + e.z));
    sidx_ray_init(&ray, org, sidx_v3_sub(sidx_v3(c.x + 0.05f * e.x, c.y + 0.1f * e.y, c.z), org), 0.0f, INFINITY);
    printf("Ray: origin (%g %g %g) direction (%g %g %g)\n", ray.org.x, ray.org.y, ray.org.z, ray.dir.x, ray.dir.y,
           ray.dir.z);
    mkdir("build", 0755);
    mkdir(outdir, 0755);

    int failures = 0;
    for (size_t i = 0; i < sidx_accel_registered_count(); ++i) {
        const char *name = sidx_accel_registered_name(i);
        if (!wanted(accels, name)) continue;
        printf("\n================ %s — %s\n", name, sidx_accel_registered_description(i));

        /* build, printing the first decisions and counting all */
        limited_printer lp = {.limit = limit};
        sidx_printer_init(&lp.printer, stdout);
        lp.inner = sidx_printer_hook(&lp.printer);
        sidx_counters build_counts;
        sidx_counters_init(&build_counts);
        /* Candidates are counted, not printed: the lessons plot them. */
        sidx_tee tee = {{{limited_fn, &lp, (SIDX_EVMASK_BUILD & ~SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE)) | SIDX_EVMASK(SIDX_EV_NOTE)},
                         sidx_counters_hook(&build_counts)},
                        2};
        sidx_hook build_hook = sidx_tee_hook(&tee);
        sidx_build_options opt = {0};
        opt.hook = &build_hook;
        sidx_accel *a = NULL;
        if (limit < 0)
            printf("-- build (every decision)\n");
        else
            printf("-- build (first %ld decisions)\n", limit);
        if (sidx_accel_build(name, &mesh, &opt, &a, &err) != SIDX_OK) {
            printf("build failed: %s\n", err.message);
            ++failures;
            continue;
        }
        if (lp.skipped) printf("   ... %ld more build decisions\n", lp.skipped);
        printf("-- %llu split candidates evaluated, %llu splits, %llu leaves\n",
               (unsigned long long)build_counts.n[SIDX_EV_BUILD_CANDIDATE],
               (unsigned long long)build_counts.n[SIDX_EV_BUILD_SPLIT],
               (unsigned long long)build_counts.n[SIDX_EV_BUILD_LEAF]);
        sidx_accel_stats st;
        sidx_accel_stats_get(a, &st);
        printf("-- built: %u nodes, %u leaves, depth %u, %llu primitive references, %zu bytes, SAH cost %.2f\n",
               st.nodes, st.leaves, st.max_depth, (unsigned long long)st.prim_refs, st.bytes, st.sah_cost);

        /* trace the ray, printing every event */
        limited_printer tp = {.limit = limit};
        sidx_printer_init(&tp.printer, stdout);
        tp.inner = sidx_printer_hook(&tp.printer);
        sidx_counters counts;
        sidx_counters_init(&counts);
        sidx_tee ttee = {{{limited_fn, &tp, 0}, sidx_counters_hook(&counts)}, 2};
        sidx_hook trace_hook = sidx_tee_hook(&ttee);
        sidx_query q = {SIDX_QUERY_UV, SIDX_TRAVERSE_DEFAULT, &trace_hook, 0};
        sidx_hit hit;
        printf("-- trace one ray\n");
        sidx_accel_intersect(a, &ray, &q, &hit);
        if (tp.skipped) printf("   ... %ld more traversal events (--full shows them)\n", tp.skipped);
        if (hit.prim != SIDX_NO_HIT)
            printf("-- hit triangle %u at t = %g (u = %g, v = %g)\n", hit.prim, hit.t, hit.u, hit.v);
        else
            printf("-- miss\n");
        printf("-- counters:\n");
        sidx_counters_print(&counts, stdout);

        /* a drawing of the tree, when the structure builds one */
        char path[512];
        snprintf(path, sizeof path, "%s/%s.svg", outdir, name);
        /* About 100 nodes stay readable: 6 levels of a binary tree, fewer
         * for wide ones (branching estimated from the node counts). */
        double branching = st.nodes > st.leaves ? (double)(st.nodes - 1) / (double)(st.nodes - st.leaves) : 2.0;
        if (branching < 2.0) branching = 2.0;
        uint32_t depth = (uint32_t)(log(100.0) / log(branching));
        if (depth < 1) depth = 1;
        if (depth > 6) depth = 6;
        sidx_dot_options dopt = {0};
        dopt.max_depth = depth;
        dopt.has_ray = 1;
        dopt.ray_org = ray.org;
        dopt.ray_dir = ray.dir;
        sidx_error derr = {0};
        sidx_status ds = sidx_dot_write(&mesh, name, &dopt, path, &derr);
        if (ds == SIDX_OK) printf("-- tree drawn (%u levels, ray path coloured): %s\n", depth, path);
        else if (ds != SIDX_ERR_UNSUPPORTED) printf("-- drawing failed: %s\n", derr.message);
        sidx_accel_destroy(a);
    }
    sidx_mesh_free(&mesh);
    return failures ? 1 : 0;
}
