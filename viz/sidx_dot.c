/* sidx-dot — a structure's tree as a Graphviz picture.
 *
 *   sidx-dot --accel NAME SCENE [--depth K] [--max-width N] [--max-nodes N] [--ray ox,oy,oz,dx,dy,dz]
 *            [build knobs] -o tree.{dot,gv,svg,png,pdf}
 *
 * Exit status: 0 written, 1 failure (build, no tree, I/O), 2 usage. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"
#include "args.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: sidx-dot --accel NAME SCENE [--depth K] [--max-width N] [--max-nodes N]\n"
            "                [--ray ox,oy,oz,dx,dy,dz] [build knobs] -o OUT\n"
            "\n"
            "Builds structure NAME over SCENE (a .obj/.ply file or a built-in scene such as\n"
            "teapot, flat2d, icosphere:2), rebuilds its tree from the build events and writes it\n"
            "with Graphviz.  The format follows OUT's extension: .dot/.gv (text, no layout),\n"
            ".svg, .png, .pdf; OUT '-' writes dot text to stdout.  kd-slide with --accel kdtree\n"
            "is the tree of deck 000 \"kD-Tree Example\", its nodes named A-D, L1-L5 as there.\n"
            "\n"
            "  --accel NAME     structure (see --list)\n"
            "  --depth K        draw K levels (the root's is the first); each deeper subtree\n"
            "                   becomes one summary node \"+N nodes, M prims\" (default %u; 0 = all)\n"
            "  --max-width N    about N boxes across the page (default %u; 0 = no limit).  Nodes\n"
            "                   open best first: those the ray visited, then those holding the\n"
            "                   most primitives; siblings past the width fold into one\n"
            "                   \"... N more cells (M empty)\" box, other subtrees into \"+N nodes\"\n"
            "                   summaries, and the caption says what was folded\n"
            "  --max-nodes N    about N boxes in all (default %u; 0 = no limit).  The two limits\n"
            "                   keep Graphviz's layout to a few seconds at any depth; on a\n"
            "                   terminal the stages (build, layout) are printed on stderr\n"
            "  --ray R          trace the ray ox,oy,oz,dx,dy,dz: visited nodes coloured in visit\n"
            "                   order and numbered, pruned ones grey, the leaf where the walk\n"
            "                   ends with its hit outlined red\n"
            "  -o, --output OUT output file\n"
            "  --list           list the registered structures\n"
            "  -h, --help       this help\n"
            "\n%s",
            SIDX_DOT_DEFAULT_DEPTH, SIDX_DOT_DEFAULT_WIDTH, SIDX_DOT_DEFAULT_NODES, sidx_viz_build_knobs_help());
}

int main(int argc, char **argv)
{
    const char *out = NULL;
    sidx_dot_options opt;
    sidx_build_options bo;
    memset(&opt, 0, sizeof opt);
    memset(&bo, 0, sizeof bo);
    viz_args args = {.prog = "sidx-dot", .usage = usage, .build = &bo, .scene_operand = 1};
    for (int i = 1; i < argc; ++i) {
        const int took = viz_arg(&args, argc, argv, &i);
        if (took == VIZ_ARG_TAKEN) continue;
        if (took != VIZ_ARG_OWN) return took;
        const char *a = argv[i];
        const int has_val = i + 1 < argc;
        if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_val) {
            out = argv[++i];
        } else if (!strcmp(a, "--depth") && has_val) {
            char *end;
            long k = strtol(argv[++i], &end, 10);
            if (*end || k < 0 || k > 100000) {
                fprintf(stderr, "sidx-dot: --depth wants a number >= 0, not '%s'\n", argv[i]);
                return 2;
            }
            opt.max_depth = k == 0 ? SIDX_DOT_ALL_DEPTHS : (uint32_t)k;
        } else if ((!strcmp(a, "--max-width") || !strcmp(a, "--max-nodes")) && has_val) {
            char *end;
            long k = strtol(argv[++i], &end, 10);
            const long least = !strcmp(a, "--max-width") ? 2 : 1;
            if (*end || end == argv[i] || (k != 0 && k < least) || k > 1000000) {
                fprintf(stderr, "sidx-dot: %s wants 0 (no limit) or a number from %ld to 1000000, not '%s'\n", a,
                        least, argv[i]);
                return 2;
            }
            const uint32_t v = k == 0 ? SIDX_DOT_UNLIMITED : (uint32_t)k;
            if (!strcmp(a, "--max-width"))
                opt.max_width = v;
            else
                opt.max_nodes = v;
        } else {
            return viz_arg_unknown(&args, a);
        }
    }
    const char *accel = args.accel, *scene = args.scene;
    if (!accel || !scene || !out) {
        fprintf(stderr, "sidx-dot: --accel, SCENE and -o are required\n");
        usage(stderr);
        return 2;
    }
    const int bad_accel = viz_arg_check_accel(&args);
    if (bad_accel) return bad_accel;
    opt.has_ray = args.ray_text != NULL;
    opt.ray_org = args.org;
    opt.ray_dir = args.dir;
    opt.build = &bo;
    /* on a terminal, say what takes time: the build of a big scene, Graphviz's layout */
    if (isatty(STDERR_FILENO)) opt.progress = stderr;
    opt.scene = scene; /* kd-slide with kdtree: the slide's tree, its nodes named as the slide names them */

    sidx_mesh mesh;
    sidx_error err;
    memset(&mesh, 0, sizeof mesh);
    if (sidx_scene_open(scene, &mesh, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-dot: %s\n", err.message);
        return 1;
    }
    sidx_status st = sidx_dot_write(&mesh, accel, &opt, out, &err);
    sidx_mesh_free(&mesh);
    if (st != SIDX_OK) {
        fprintf(stderr, "sidx-dot: %s\n", err.message[0] ? err.message : sidx_status_str(st));
        return 1;
    }
    if (strcmp(out, "-") != 0) printf("wrote %s\n", out);
    return 0;
}
