/* 06_grid_dda.c — checker driver: the uniform grid's resolution formula,
 * then the 3D-DDA cell walk (deck 000, "Uniform Grids" and "Uniform Grid
 * Traversal").  References: the library's resolution (grid_internal.h,
 * the function grid.c's build calls) and its traced walk over a
 * "grid-nomailbox" (NODE_ENTER per cell, PRIM_TEST, HIT_UPDATE,
 * TERMINATE), which the student's walk reproduces through sidx/grid.h. */
#include <math.h>
#include <string.h>
#include "check.h"
#include "grid_cases.h"
#include "grid_internal.h"

void grid_resolution(sidx_vec3 d, double n, double lambda, uint32_t res[3]);
void grid_walk(const sidx_ex *ex, const sidx_grid_cells *g, sidx_hit *best);

/* ---- part 1: R = d·∛(λn/V) ------------------------------------------------ */

typedef struct res_case {
    float d[3];
    double n, lambda;
    const char *name;
} res_case;

#define RES_FIXED 9
#define RES_RANDOM 10
#define RES_CASES (RES_FIXED + RES_RANDOM)
static res_case res_cases[RES_CASES] = {
    {{1, 1, 1}, 1000, 1, "a unit cube, n = 1000, λ = 1: 10 cells per axis"},
    {{4, 4, 4}, 4, 16, "the slanted scene: d = (4, 4, 4), n = 4, λ = 16"},
    {{8, 2, 1}, 500, 4, "a long flat box: d = (8, 2, 1)"},
    {{3, 3, 3}, 100, 2, "a cube where d·∛(λn/V) = 5.85: rounding, not truncating"},
    {{10, 10, 0}, 200, 2, "a flat scene (d_z = 0): one cell on that axis, the root over the other two"},
    {{0.5f, 6, 0}, 50, 4, "a flat, thin scene (d_z = 0)"},
    {{10, 0.01f, 0.01f}, 10, 1, "a needle: d = (10, 0.01, 0.01), under half a cell across: at least 1"},
    /* R = 10.4999999 in double (pow or cbrt alike), 10.500001 in float: 10 cells, not 11 */
    {{3, 3, 3}, 343, 3.3749999035714285, "a cube where R = 10.4999999: float arithmetic rounds it up to 11"},
    /* V = 3.3·2.7·1.9 is 16.9289998 in double, 16.9289989 in float: R_x = 10.4999999 or 10.5000001 */
    {{3.3f, 2.7f, 1.9f}, 500, 1.0906549669491397, "a box whose volume float rounds: R_x = 10.4999999 in double"},
};

#define HINT_FORMULA                                                                                       \
    "\"Usually R_{x,y,z} = d_{x,y,z}·∛(λn/V)\" with d the box's diagonal (its extent per axis), V = "         \
    "d_x·d_y·d_z the box's volume, n the number of objects, λ the density: compute in double, round to the " \
    "nearest integer, at least 1 cell"
#define HINT_FLAT                                                                                          \
    "an axis of zero extent (a flat scene) gets one cell, and the formula is taken over the other k axes: "  \
    "V is their product and the root is the k-th, R = d·(λn/V)^(1/k)"
#define HINT_DOUBLE                                                                                        \
    "compute R in double, not float: float keeps 7 digits, and a value just below k + 0.5 (10.4999999) "    \
    "comes out as k + 0.5 and rounds up a cell"
#define HINT_ROUND "round to the nearest integer (floor(x + 0.5)), do not truncate: 5.85 cells are 6"
#define HINT_MIN_ONE                                                                                       \
    "every axis gets at least 1 cell: an axis thinner than half a cell rounds to 0, which must become 1"
#define HINT_START                                                                                         \
    "clip the ray to the grid box (sidx_intersect_aabb over [tmin, best.t]); the first cell is the one "     \
    "holding o + t_enter·d, floor((p - box.min)·inv_cell) clamped to [0, res - 1], entered over [t_enter, " \
    "its first t_max]"
#define HINT_STEP                                                                                          \
    "3D-DDA: t_max per axis is the t of the next cell boundary, computed as ((c + up)·cell + (box.min - "    \
    "o))·(1/d); step along the axis with the smallest t_max (on a tie the later axis: z before y before x); " \
    "an axis with d = 0 never steps (t_max = inf)"
#define HINT_ZERO                                                                                          \
    "a direction component of ±0: that axis never steps, step = 0 and its t_max = +inf (do not compute "    \
    "(boundary - o)·inv_dir there: it is ±inf or NaN)"
#define HINT_TIE                                                                                           \
    "two boundaries at the same t (the ray through a cell edge or corner): on a tie step along the later "  \
    "axis, z before y before x, one axis per step"
#define HINT_INTERVAL                                                                                      \
    "each cell is entered over [t_in, t_out]: t_in is t_enter for the first cell and the previous cell's "  \
    "t_out after it; t_out is the smallest t_max"
#define HINT_STOP                                                                                          \
    "a hit ends the walk only if it lies in the current cell (t <= the cell's exit t_max): a triangle can "  \
    "stick out into later cells, where a nearer one may wait; without a hit the walk ends where it leaves " \
    "the grid"
#define HINT_PRIMS                                                                                         \
    "\"Intersect with primitives inside non-empty cells\": test each of the cell's triangles, "              \
    "refs[offsets[c] .. offsets[c+1]), against the best hit so far"

/* The hand-out's promises (lessons/exercises/06_grid_dda.c). */
static const ex_rule rules[] = {
    {"res-formula", "R_i = d_i·∛(λn/V), V = d_x·d_y·d_z", HINT_FORMULA},
    {"res-double", "R is computed in double", HINT_DOUBLE},
    {"res-round", "R is rounded to the nearest integer", HINT_ROUND},
    {"res-min-one", "every axis gets at least 1 cell", HINT_MIN_ONE},
    {"res-flat", "an axis of zero extent gets one cell; the formula runs over the other k axes, k-th root",
     HINT_FLAT},
    {"walk-start",
     "the ray is clipped to the grid box over [tmin, best->t] (a miss enters no cell); the first cell holds "
     "o + t0·d, clamped to [0, res - 1]",
     HINT_START},
    {"t-max", "t_max per axis is ((c + up)·cell + (box.min - o))·inv_dir, the next boundary's t", HINT_STEP},
    {"zero-dir", "an axis with a zero direction component has step 0 and t_max = +inf: it never steps",
     HINT_ZERO},
    {"tie-later-axis", "the walk steps along the smallest t_max, on a tie the later axis (z, then y, then x)",
     HINT_TIE},
    {"cell-interval", "a cell is reported over [t_in, t_out]: t_in = t0, then the previous t_out; t_out = min t_max",
     HINT_INTERVAL},
    {"cell-prims", "each cell's triangles refs[offsets[c] .. offsets[c+1]) are tested against best->t",
     HINT_PRIMS},
    {"stop-in-cell", "the walk stops when best->t <= t_out, or when the cell index leaves [0, res - 1]",
     HINT_STOP},
};
enum { R_RES, R_DOUBLE, R_ROUND, R_MIN_ONE, R_FLAT, R_START, R_TMAX, R_ZERO, R_TIE, R_INTERVAL, R_PRIMS, R_STOP };

static const char *const hint_formula = HINT_FORMULA;
static const char *const hint_flat = HINT_FLAT;

/* The rules a resolution case tests. */
static const char *const res_rules[RES_FIXED] = {
    "res-formula res-round", "res-formula", "res-formula res-round", "res-round", "res-flat", "res-flat res-round",
    "res-min-one", "res-double", "res-double"};
/* The rules of the walk's hand-made rays (grid_fixed, scene "slanted"), and of the others. */
static const char *const walk_rules[GRID_FIXED] = {
    "tie-later-axis cell-interval", "tie-later-axis cell-interval", "zero-dir", "zero-dir walk-start",
    "walk-start", "stop-in-cell cell-prims", "stop-in-cell cell-prims zero-dir", "t-max cell-interval",
    "t-max cell-interval", "walk-start", "stop-in-cell cell-prims zero-dir", "t-max cell-interval"};
static const char *const walk_rules_other = "walk-start t-max cell-interval cell-prims stop-in-cell";

static void res_setup(void)
{
    uint32_t st = 2024u;
    for (int i = RES_FIXED; i < RES_CASES; ++i) {
        res_case *c = &res_cases[i];
        for (int k = 0; k < 3; ++k) c->d[k] = 0.25f + 9.75f * ex_rand(&st);
        c->n = (double)(1u + (uint32_t)(5000.0f * ex_rand(&st)));
        c->lambda = 0.5 + 7.5 * (double)ex_rand(&st);
        c->name = "a random box";
    }
}

static void res_emit(const sidx_hook *h, const uint32_t res[3])
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "grid";
    e.text = "grid resolution R = d*cbrt(lambda*n/V) per axis (cell[] = R)";
    e.cell[0] = (int32_t)res[0];
    e.cell[1] = (int32_t)res[1];
    e.cell[2] = (int32_t)res[2];
    e.count = res[0] * res[1] * res[2];
    sidx_hook_emit(h, &e);
}

static void res_reference(int i, const sidx_hook *h)
{
    const res_case *c = &res_cases[i];
    sidx_aabb box = {{0, 0, 0}, {c->d[0], c->d[1], c->d[2]}};
    uint32_t res[3];
    sidx__grid_resolution(box, c->n, c->lambda, SIDX__GRID_MAX_RES, SIDX__GRID_MAX_CELLS, res);
    res_emit(h, res);
}

static void res_student(int i, const sidx_hook *h)
{
    const res_case *c = &res_cases[i];
    uint32_t res[3] = {0, 0, 0};
    grid_resolution(sidx_v3(c->d[0], c->d[1], c->d[2]), c->n, c->lambda, res);
    res_emit(h, res);
}

/* ---- part 2: the 3D-DDA walk ---------------------------------------------- */

#define WALK_CASES (GRID_NSCENES * GRID_RAYS)

static int setup(void)
{
    res_setup();
    return grid_setup("grid-nomailbox");
}

static size_t num_cases(void) { return RES_CASES + WALK_CASES; }

static const char *const hint_start = HINT_START;
static const char *const hint_step = HINT_STEP;
static const char *const hint_stop = HINT_STOP;
static const char *const hint_prims = HINT_PRIMS;

static void describe(size_t i, ex_case_info *out)
{
    if (i < RES_CASES) {
        const res_case *c = &res_cases[i];
        snprintf(out->name, sizeof out->name, "resolution: %s", c->name);
        snprintf(out->what, sizeof out->what, "d = (%g, %g, %g)  n = %g  lambda = %g", (double)c->d[0],
                 (double)c->d[1], (double)c->d[2], c->n, c->lambda);
        out->hint = c->d[2] == 0.0f ? hint_flat : hint_formula;
        out->rules = i < RES_FIXED ? res_rules[i] : "res-formula res-round";
        return;
    }
    i -= RES_CASES;
    const int s = (int)(i / GRID_RAYS), r = (int)(i % GRID_RAYS);
    const sidx_grid_cells *g = &grid_views[s];
    snprintf(out->name, sizeof out->name, "walk, scene %s (%u x %u x %u cells), ray %d (%s)", grid_scene_names[s],
             g->res[0], g->res[1], g->res[2], r + 1, grid_ray_kind[s][r]);
    ex_format_ray(out->what, sizeof out->what, &grid_rays[s][r]);
    out->hint = NULL;
    out->rules = s == 0 && r < GRID_FIXED ? walk_rules[r] : walk_rules_other;
    grid_view_case(s, r, "grid-nomailbox", out);
}

static void reference(size_t i, const sidx_hook *h)
{
    if (i < RES_CASES) {
        res_reference((int)i, h);
        return;
    }
    i -= RES_CASES;
    grid_reference_ray((int)(i / GRID_RAYS), (int)(i % GRID_RAYS), 0, h);
}

static void walk(const sidx_ex *ex, const sidx_grid_cells *g, sidx_hit *best, void *user)
{
    (void)user;
    grid_walk(ex, g, best);
}

static void student(size_t i, const sidx_hook *h)
{
    if (i < RES_CASES) {
        res_student((int)i, h);
        return;
    }
    i -= RES_CASES;
    grid_student_ray((int)(i / GRID_RAYS), (int)(i % GRID_RAYS), 0, h, "grid-nomailbox", walk, NULL);
}

/* What differs decides.  A resolution with an axis of 0 cells is the
 * minimum, one cell short on an axis the rounding (in a flat scene the
 * k-th root decides first: the case's hint).  A walk: a cell moved along an axis of zero direction, or
 * an exit no finite boundary gives on a ray with such an axis, is the
 * zero-direction rule; another first cell, or the first cell over another
 * interval, is the start (the clip and the cell holding the entry point);
 * later on, the same cell entered at another t is the cells' intervals,
 * another cell entered at the same t the tie, anything else the t_max
 * step; a stop
 * where the reference goes on (or the reverse) is the termination rule; a
 * triangle step is the cell's list. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if (i < RES_CASES) {
        /* an axis of 0 cells is the minimum; one cell short, the rounding */
        if (!ref || !stu) return NULL;
        for (int k = 0; k < 3; ++k)
            if (stu->cell[k] == 0 && ref->cell[k] != 0) return rules[R_MIN_ONE].hint;
        for (int k = 0; k < 3; ++k)
            if (stu->cell[k] == ref->cell[k] - 1 && res_cases[i].d[2] != 0.0f) return rules[R_ROUND].hint;
        if (i < RES_FIXED && strstr(res_rules[i], "res-double")) return rules[R_DOUBLE].hint; /* only float fails it */
        return NULL;
    }
    i -= RES_CASES;
    const int s = (int)(i / GRID_RAYS), r = (int)(i % GRID_RAYS);
    const sidx_ray *ray = &grid_rays[s][r];
    const float d[3] = {ray->dir.x, ray->dir.y, ray->dir.z};
    if (ref && stu && ref->type == SIDX_EV_NODE_ENTER && stu->type == SIDX_EV_NODE_ENTER) {
        /* a zero axis that moved */
        for (int k = 0; k < 3; ++k)
            if (d[k] == 0.0f && ref->cell[k] != stu->cell[k]) return rules[R_ZERO].hint;
        float t0 = NAN, t1 = NAN;
        const int in =
            sidx_intersect_aabb(SIDX_BOX_PLAIN, ray, &grid_views[s].box, ray->tmin, ray->tmax, &t0, &t1);
        /* an exit at -inf or NaN: a t_max taken on a zero axis */
        if ((d[0] == 0.0f || d[1] == 0.0f || d[2] == 0.0f) && (isnan(stu->t_far) || stu->t_far == -INFINITY))
            return rules[R_ZERO].hint;
        if (in && ref->t_near == t0) return hint_start; /* the first cell */
        if (ref->node == stu->node && ref->t_near != stu->t_near) return rules[R_INTERVAL].hint;
        /* Two cells entered at the same t from the same cell: the reference
         * stepped along axis a, the student along b.  b before a is the tie
         * taken by the earlier axis; b after a is no tie rule (the
         * reference would have taken the later axis): a t_max. */
        if (ref->node != stu->node && ref->t_near == stu->t_near) {
            int a = -1, b = -1;
            for (int k = 0; k < 3; ++k) {
                const int step = d[k] > 0.0f ? 1 : d[k] < 0.0f ? -1 : 0, diff = ref->cell[k] - stu->cell[k];
                if (step && diff == step) a = k;
                if (step && diff == -step) b = k;
            }
            if (a >= 0 && b >= 0 && b < a) return rules[R_TIE].hint;
        }
        return hint_step; /* a later cell */
    }
    if ((ref && ref->type == SIDX_EV_TERMINATE && ref->reason == SIDX_TERM_MISS_ROOT) ||
        (stu && stu->type == SIDX_EV_TERMINATE && stu->reason == SIDX_TERM_MISS_ROOT))
        return hint_start;
    if (ref && ref->type == SIDX_EV_NODE_ENTER && stu && stu->type == SIDX_EV_TERMINATE) return hint_stop;
    if (stu && stu->type == SIDX_EV_NODE_ENTER && ref && ref->type == SIDX_EV_TERMINATE) return hint_stop;
    if ((ref && ref->type == SIDX_EV_PRIM_TEST) || (stu && stu->type == SIDX_EV_PRIM_TEST)) return hint_prims;
    if ((ref && ref->type == SIDX_EV_HIT_UPDATE) || (stu && stu->type == SIDX_EV_HIT_UPDATE)) return hint_prims;
    return hint_start;
}

static void teardown(void) { grid_teardown(); }

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    snprintf(buf, size, "resolution %d x %d x %d = %u cells", (int)e->cell[0], (int)e->cell[1], (int)e->cell[2],
             (unsigned)e->count);
    return 1;
}

const ex_driver ex_driver_this = {
    "06_grid_dda",
    "the uniform grid: the resolution formula, then the 3D-DDA cell walk",
    "deck 000, \"Uniform Grids\" (Resolution) and \"Uniform Grid Traversal\" (3D-DDA)",
    setup, num_cases, describe, reference, student, hint, teardown, format, rules, sizeof rules / sizeof rules[0],
};
