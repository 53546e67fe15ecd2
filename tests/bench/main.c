/* sidx-bench — speed and accuracy of every registered structure, with
 * Embree 3 as the peer.  Sub-commands: trace, rays, run, scale. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "bench.h"

const char *bench_argv0 = "sidx-bench";
int bench_cpu_time = 0;

double bench_clock_ms(void) { return bench_cpu_time ? tk_thread_cpu_ms() : tk_now_ms(); }
double bench_build_clock_ms(void) { return bench_cpu_time ? tk_process_cpu_ms() : tk_now_ms(); }

static void usage(FILE *out)
{
    fprintf(out,
            "usage: sidx-bench COMMAND [options]   (sidx-bench COMMAND --help for details)\n"
            "\n"
            "  trace --accel NAME SCENE RAYS.bin HITS.bin [--threads N] [--any-hit]\n"
            "        [--traversal default|stack|ordered|naive] [--tri watertight|moller|twostep]\n"
            "        [--box robust|plain] [--uv 0|1]\n"
            "        trace a ray file, write a hit file, print one JSON line\n"
            "  rays SCENE KIND COUNT SEED OUT.bin\n"
            "        write a ray set (KIND: primary diffuse shadow grazing axis)\n"
            "  run [--scenes DIR] [--accel LIST] [--kinds LIST] [--rays N] [--csv FILE] [--plot FILE.svg] ...\n"
            "        the benchmark table: every structure x scene x ray kind, Embree rows, errors\n"
            "  scale [--scene icosphere|grid|soup] [--accel LIST] [--max-tris N] [--budget-ms MS] ...\n"
            "        build time and steps per ray against triangle count, fitted growth exponents\n"
            "  extras [--scenes DIR] [--only instancing,lightbuffer,rayclass] [--instances N] ...\n"
            "        instanced scenes, the light buffer (shadow rays), ray classification's trade-off\n"
            "  lazy [--accel NAME] [--lazy-size N] [--size PX] [--frames N] [--rounds N] [SCENE ...]\n"
            "        time to the first image and over N frames, lazy build against eager\n"
            "  stream [--scenes DIR] [--scene LIST] [--kinds LIST] [--rays N] [--rounds R] [--passes P]\n"
            "        single queries against the stream entry (intersect_n, occluded_n), and Embree's\n"
            "        rtcIntersect1 against rtcIntersect1M, in interleaved rounds\n"
            "  list  registered structures and built-in scenes\n"
            "\n"
            "SCENE is a mesh file (.obj, .ply) or a built-in scene name[:detail].\n"
            "Exit status: 0 ok, 1 failure, 2 usage error.\n");
}

int bench_list_has(const char *list, const char *name)
{
    if (!list) return 1;
    const size_t n = strlen(name);
    const char *p = list;
    while (*p) {
        const char *e = strchr(p, ',');
        const size_t len = e ? (size_t)(e - p) : strlen(p);
        if (len == n && strncmp(p, name, n) == 0) return 1;
        if (!e) break;
        p = e + 1;
    }
    return 0;
}

int bench_progress_enabled(void) { return isatty(2); }

static int progress_shown;

void bench_progress(const char *fmt, ...)
{
    if (!bench_progress_enabled()) return;
    char buf[160];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\r\033[K%s", buf);
    fflush(stderr);
    progress_shown = 1;
}

void bench_progress_done(void)
{
    if (progress_shown && bench_progress_enabled()) fprintf(stderr, "\r\033[K");
    progress_shown = 0;
}

static int cmd_list(void)
{
    printf("structures:\n");
    for (size_t i = 0; i < sidx_accel_registered_count(); ++i)
        printf("  %-16s %s\n", sidx_accel_registered_name(i), sidx_accel_registered_description(i));
    printf("  %-16s %s\n", "auto", "picks a structure from the scene's statistics");
    printf("  %-16s %s\n", "embree[-robust][-hq]", "Embree 3 rtcIntersect1 (robust flag, HIGH build quality)");
    printf("built-in scenes:");
    for (const char *const *s = sidx_scene_names(); s && *s; ++s) printf(" %s", *s);
    printf("\n");
    return BENCH_OK;
}

int main(int argc, char **argv)
{
    if (argc > 0 && argv[0]) bench_argv0 = argv[0];
    if (argc < 2) {
        usage(stderr);
        return BENCH_USAGE;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        usage(stdout);
        return BENCH_OK;
    }
    if (!strcmp(cmd, "trace")) return bench_cmd_trace(argc - 1, argv + 1);
    if (!strcmp(cmd, "rays")) return bench_cmd_rays(argc - 1, argv + 1);
    if (!strcmp(cmd, "run")) return bench_cmd_run(argc - 1, argv + 1);
    if (!strcmp(cmd, "scale")) return bench_cmd_scale(argc - 1, argv + 1);
    if (!strcmp(cmd, "extras")) return bench_cmd_extras(argc - 1, argv + 1);
    if (!strcmp(cmd, "lazy")) return bench_cmd_lazy(argc - 1, argv + 1);
    if (!strcmp(cmd, "stream")) return bench_cmd_stream(argc - 1, argv + 1);
    if (!strcmp(cmd, "list")) return cmd_list();
    fprintf(stderr, "sidx-bench: unknown command '%s'\n", cmd);
    usage(stderr);
    return BENCH_USAGE;
}
