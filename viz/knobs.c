/* knobs.c — the build knobs on a command line.
 *
 * sidx-step, sidx-dot, sidx-view and the lessons (lessons/lesson.h) take
 * the same eleven options, each filling one sidx_build_options field, so
 * one table says what each flag fills and what values it takes.  The
 * ranges are those sidx_accel_build accepts, minus the 0 that means "the
 * structure's default" (leave the flag out for that). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/viz.h"

typedef enum { KNOB_COUNT, KNOB_POSITIVE, KNOB_FRACTION, KNOB_FLAG } knob_kind;

typedef struct knob {
    const char *flag;
    knob_kind kind;
    size_t offset; /* of the field in sidx_build_options */
    uint32_t min;  /* KNOB_COUNT: the smallest value taken */
} knob;

static const knob knobs[] = {
    {"--bins", KNOB_COUNT, offsetof(sidx_build_options, bins), 2},
    {"--c-trav", KNOB_POSITIVE, offsetof(sidx_build_options, c_trav), 0},
    {"--c-tri", KNOB_POSITIVE, offsetof(sidx_build_options, c_tri), 0},
    {"--leaf-size", KNOB_COUNT, offsetof(sidx_build_options, leaf_size), 1},
    {"--max-depth", KNOB_COUNT, offsetof(sidx_build_options, max_depth), 1},
    {"--lambda", KNOB_POSITIVE, offsetof(sidx_build_options, grid_density), 0},
    {"--no-mailbox", KNOB_FLAG, offsetof(sidx_build_options, no_mailbox), 0},
    {"--empty-bonus", KNOB_FRACTION, offsetof(sidx_build_options, empty_bonus), 0},
    {"--optimize", KNOB_POSITIVE, offsetof(sidx_build_options, optimize_ms), 0},
    {"--lazy", KNOB_FLAG, offsetof(sidx_build_options, lazy), 0},
    {"--lazy-size", KNOB_COUNT, offsetof(sidx_build_options, lazy), 2},
};
#define NKNOBS (sizeof knobs / sizeof knobs[0])

/* Counts above this are typing mistakes, not experiments. */
#define KNOB_COUNT_MAX 1000000ul

static int bad(char *msg, size_t size, const char *flag, const char *wants, const char *value)
{
    if (msg && size) {
        if (value) snprintf(msg, size, "%s wants %s, not '%s'", flag, wants, value);
        else snprintf(msg, size, "%s wants %s after it", flag, wants);
    }
    return -1;
}

int sidx_viz_build_knob(const char *flag, const char *value, sidx_build_options *bo, char *msg, size_t size)
{
    if (msg && size) msg[0] = '\0';
    if (!flag || !bo) return bad(msg, size, flag ? flag : "(null)", "a flag and options to fill", NULL);
    const knob *k = knobs;
    while (k < knobs + NKNOBS && strcmp(k->flag, flag)) ++k;
    if (k == knobs + NKNOBS) return 0;
    char *field = (char *)bo + k->offset;
    if (k->kind == KNOB_FLAG) {
        const int on = 1;
        memcpy(field, &on, sizeof on); /* the field's type is the knob's kind: int (lazy: uint32_t, 1 the same) */
        return 1;
    }
    char *end = NULL;
    if (k->kind == KNOB_COUNT) {
        char wants[64];
        snprintf(wants, sizeof wants, "a whole number from %u to %lu", k->min, KNOB_COUNT_MAX);
        if (!value || value[0] < '0' || value[0] > '9') return bad(msg, size, flag, wants, value);
        const unsigned long n = strtoul(value, &end, 10);
        if (*end || n < k->min || n > KNOB_COUNT_MAX) return bad(msg, size, flag, wants, value);
        const uint32_t count = (uint32_t)n;
        memcpy(field, &count, sizeof count);
        return 2;
    }
    const char *wants = k->kind == KNOB_FRACTION ? "a number >= 0 and < 1" : "a number > 0";
    if (!value) return bad(msg, size, flag, wants, value);
    const float x = strtof(value, &end);
    const int ok = end != value && !*end && isfinite(x) &&
                   (k->kind == KNOB_FRACTION ? x >= 0.0f && x < 1.0f : x > 0.0f);
    if (!ok) return bad(msg, size, flag, wants, value);
    memcpy(field, &x, sizeof x);
    return 2;
}

const char *sidx_viz_build_knobs_help(void)
{
    return "build knobs (sidx_build_options; left out = the structure's default):\n"
           "  --bins N           binned SAH builders (bvh, kdtree-binned): N >= 2 bins (32)\n"
           "  --c-trav X         SAH cost of a traversal step, X > 0\n"
           "  --c-tri X          SAH cost of a triangle test, X > 0\n"
           "  --leaf-size N      make a leaf at or below N primitives (N >= 1)\n"
           "  --max-depth N      depth limit of the trees (N >= 1)\n"
           "  --lambda X         grids: cells per triangle (the density of the resolution formula), X > 0\n"
           "  --no-mailbox       grids, kd-tree: no mailbox (a triangle in k cells is tested k times)\n"
           "  --empty-bonus X    kd-tree SAH bonus for cutting off empty space, 0 <= X < 1\n"
           "  --optimize MS      BVHs: improve the binary tree by reinsertion for at most MS ms, MS > 0\n"
           "  --lazy             bvh, kd-tree families: build subtrees of at most 1024 primitives\n"
           "                     when a ray first enters them (build_lazy_expand events on the query's hook)\n"
           "  --lazy-size N      the same, subtrees of at most N primitives (N >= 2)\n";
}
