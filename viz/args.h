/* args.h — the opening of the programs' main: the options sidx-dot,
 * sidx-step and sidx-view share, parsed one argument at a time.  Not
 * installed.
 *
 * Shared: the build knobs (sidx_viz_build_knob), -h/--help, --list,
 * --accel NAME, --ray ox,oy,oz,dx,dy,dz and, where the program takes one,
 * the SCENE operand.  A program loops over argv, hands each argument to
 * viz_arg first and looks at it itself only when viz_arg leaves it:
 *
 *     for (int i = 1; i < argc; ++i) {
 *         const int took = viz_arg(&args, argc, argv, &i);
 *         if (took == VIZ_ARG_TAKEN) continue;
 *         if (took != VIZ_ARG_OWN) return took;
 *         ... the program's own options ...
 *         else return viz_arg_unknown(&args, argv[i]);
 *     }
 *
 * Every message starts with the program's name; the exit statuses are
 * those the programs document: 0 after --help or --list, 2 for a usage
 * error. */
#ifndef SIDX_VIZ_ARGS_H
#define SIDX_VIZ_ARGS_H

#include <stdio.h>
#include "sidx/sidx.h"

typedef struct viz_args {
    /* set by the program */
    const char *prog;          /* "sidx-dot": the start of every message */
    void (*usage)(FILE *f);    /* the program's help */
    sidx_build_options *build; /* what the build knobs fill */
    int scene_operand;         /* 1: a word that is no option is SCENE (one at most) */
    /* filled by viz_arg */
    const char *accel;         /* --accel NAME, or NULL */
    const char *scene;         /* SCENE, or NULL */
    const char *ray_text;      /* --ray R as given, or NULL when there was none */
    sidx_vec3 org, dir;        /* --ray R, parsed */
} viz_args;

/* What viz_arg returns besides an exit status (>= 0). */
enum {
    VIZ_ARG_TAKEN = -1, /* argv[*i] was a shared option: *i is on its last value */
    VIZ_ARG_OWN = -2    /* argv[*i] is none of them: the program's own, or unknown */
};

/* Looks at argv[*i] (and the value after it).  Returns VIZ_ARG_TAKEN,
 * VIZ_ARG_OWN, or the status main exits with: 0 after --help (the usage on
 * stdout) or --list (the registered structures), 2 for a bad value, a
 * second SCENE or a knob without its value (the message on stderr). */
int viz_arg(viz_args *a, int argc, char **argv, int *i);

/* An argument neither viz_arg nor the program takes: says so with the
 * usage on stderr; returns 2. */
int viz_arg_unknown(const viz_args *a, const char *arg);

/* After the loop: 0 if a->accel names a registered structure, else 2
 * with "no structure named ..." on stderr. */
int viz_arg_check_accel(const viz_args *a);

#endif
