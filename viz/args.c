/* args.c — the options the programs share (args.h). */
#include <string.h>
#include "args.h"
#include "sidx/viz.h"

int viz_arg(viz_args *a, int argc, char **argv, int *i)
{
    const char *arg = argv[*i];
    const int has_val = *i + 1 < argc;
    char msg[160];
    const int knob = sidx_viz_build_knob(arg, has_val ? argv[*i + 1] : NULL, a->build, msg, sizeof msg);
    if (knob < 0) {
        fprintf(stderr, "%s: %s\n", a->prog, msg);
        return 2;
    }
    if (knob > 0) {
        *i += knob - 1;
        return VIZ_ARG_TAKEN;
    }
    if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
        a->usage(stdout);
        return 0;
    }
    if (!strcmp(arg, "--list")) {
        for (size_t k = 0; k < sidx_accel_registered_count(); ++k)
            printf("%-14s %s\n", sidx_accel_registered_name(k), sidx_accel_registered_description(k));
        return 0;
    }
    if (!strcmp(arg, "--accel") && has_val) {
        a->accel = argv[++*i];
        return VIZ_ARG_TAKEN;
    }
    if (!strcmp(arg, "--ray") && has_val) {
        a->ray_text = argv[++*i];
        if (sidx_viz_parse_ray(a->ray_text, &a->org, &a->dir) != 0) {
            fprintf(stderr, "%s: --ray wants ox,oy,oz,dx,dy,dz (finite, non-zero direction), not '%s'\n", a->prog,
                    a->ray_text);
            return 2;
        }
        return VIZ_ARG_TAKEN;
    }
    /* an operand: a word, or '-' alone */
    if (a->scene_operand && (arg[0] != '-' || arg[1] == '\0')) {
        if (a->scene) {
            fprintf(stderr, "%s: more than one SCENE ('%s', '%s')\n", a->prog, a->scene, arg);
            return 2;
        }
        a->scene = arg;
        return VIZ_ARG_TAKEN;
    }
    return VIZ_ARG_OWN;
}

int viz_arg_unknown(const viz_args *a, const char *arg)
{
    fprintf(stderr, "%s: unknown option or missing value: %s\n", a->prog, arg);
    a->usage(stderr);
    return 2;
}

int viz_arg_check_accel(const viz_args *a)
{
    if (sidx_accel_is_registered(a->accel)) return 0;
    fprintf(stderr, "%s: no structure named '%s' (try --list)\n", a->prog, a->accel);
    return 2;
}
