/* class_mode.h — the exercises sidx-check knows and its class mode.
 *
 * sidx_check.c is the command-line front end of the checker kit: it
 * checks one file (builds it with the exercise's driver and the runner,
 * runs the result); class_mode.c runs that check over a whole class. */
#ifndef SIDX_CK_CLASS_MODE_H
#define SIDX_CK_CLASS_MODE_H

#include <stddef.h>

/* The exercises in lecture order (list.def): file name without .c, and
 * what it asks for. */
typedef struct ck_exercise {
    const char *name, *title;
} ck_exercise;
extern const ck_exercise ck_exercises[];
extern const size_t ck_num_exercises;

/* Checks FILE as exercise k, passing pass[0..npass) to the runner and
 * asking it for its --summary line in summary (or NULL); 0 pass,
 * 1 a divergence, 2 does not build, crashes, loops. */
typedef int (*ck_check_fn)(size_t k, const char *file, char **pass, int npass, const char *summary);

/* sidx-check --class DIR: checks every DIR/STUDENT/NAME.c, jobs at a time,
 * with check; writes OUT (default DIR/sidx-class-report)/summary.md,
 * summary.csv and STUDENT.txt and prints summary.md.  0 every submission
 * passes, 1 some does not, 2 a usage error or the reports could not be
 * written. */
int ck_class_mode(const char *dir, const char *out, long jobs, char **pass, int npass, ck_check_fn check);

#endif
