/* 07_grid_mailbox.c — checker driver: mailboxing on the uniform grid, the
 * per-ray cache of object IDs (deck 000, "Uniform Grid Traversal":
 * "Mailboxing ... Per-ray cache of object IDs — data local to a ray
 * (better!)").  Reference: the library's traced walk over a "grid" (the
 * mailboxed variant) for three rays in a row; the student's per-cell loop
 * runs inside the library's own 3D-DDA (grid_internal.h), with one
 * mailbox for the three rays, so a cache that is not cleared between
 * rays shows. */
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "grid_cases.h"

void mailbox_new_ray(sidx_ex_mailbox *mb);
void cell_prims(const sidx_ex *ex, sidx_ex_mailbox *mb, const uint32_t *refs, uint32_t n, sidx_hit *best);

#define PER_CASE 3 /* rays traced in a row with one mailbox */
#define CASES_PER_SCENE (GRID_RAYS / PER_CASE)

/* The last case traces one ray three times in a row: every triangle the
 * first pass tests is tested again by the next, whichever slot it lands
 * in.  The ray is the first of scene soup:120 that tests a triangle of
 * the last slot (prim mod 32 = 31), so a slot left stale shows. */
static int same_scene = 1, same_ray = 0;

static int tests_last_slot(int s, int r)
{
    ex_trace t = {NULL, 0, 0};
    const sidx_hook h = {ex_trace_hook_fn, &t, 0};
    grid_reference_ray(s, r, 0, &h);
    int found = 0;
    for (size_t k = 0; k < t.n; ++k)
        found |= t.ev[k].type == SIDX_EV_PRIM_TEST && t.ev[k].prim % SIDX_EX_MAILBOX_SIZE == SIDX_EX_MAILBOX_SIZE - 1;
    free(t.ev);
    return found;
}

static int setup(void)
{
    if (grid_setup("grid") != 0) return -1;
    for (int r = 0; r < GRID_RAYS; ++r)
        if (tests_last_slot(same_scene, r)) {
            same_ray = r;
            break;
        }
    return 0;
}
static void teardown(void) { grid_teardown(); }
static size_t num_cases(void) { return GRID_NSCENES * CASES_PER_SCENE + 1; }
static int is_same_case(size_t i) { return i == GRID_NSCENES * CASES_PER_SCENE; }

#define HINT_CLEAR                                                                                         \
    "the cache is per ray (\"data local to a ray\"): clear every slot when a new ray starts, or a triangle "  \
    "tested by an earlier ray is skipped for this one"
#define HINT_SKIP                                                                                          \
    "\"Single primitive can be referenced in many cells — avoid multiple intersections\": before testing a " \
    "triangle look in its slot (prim mod 32); if it holds prim, report sidx_ex_mailbox_hit and skip it, "   \
    "else write prim into the slot and test"
#define HINT_STAMP                                                                                         \
    "\"Keep track of intersection tests\": record every triangle you test, hit or miss, and only after "    \
    "comparing with what the slot held"
#define HINT_AGAIN                                                                                         \
    "\"Single primitive can be referenced in many cells — avoid multiple intersections\": this triangle was " \
    "tested already for this ray, in an earlier cell; look in its slot (prim mod 32) before testing, and "  \
    "record every triangle you test, hit or miss, so the next cell finds it there"
#define HINT_COLLISION                                                                                     \
    "a collision overwrites the slot: write prim into its slot even when the slot holds another triangle "  \
    "(that one is re-tested later if it comes again, never answered wrongly); the newest test is the one "  \
    "the next cell asks about"

/* The hand-out's promises (lessons/exercises/07_grid_mailbox.c). */
static const ex_rule rules[] = {
    {"clear-per-ray", "mailbox_new_ray forgets every triangle of the previous ray (every slot)", HINT_CLEAR},
    {"check-slot",
     "before testing a triangle look in its slot mb->id[prim % 32]; if it holds prim, report "
     "sidx_ex_mailbox_hit and skip it",
     HINT_AGAIN},
    {"record-every-test", "every triangle tested is written into its slot, hit or miss", HINT_AGAIN},
    {"record-after-check", "the slot is written only after comparing with what it held", HINT_STAMP},
    {"collision-overwrites", "a collision overwrites the slot (a re-test later, never a wrong answer)",
     HINT_COLLISION},
};
enum { R_CLEAR, R_CHECK, R_RECORD, R_AFTER, R_COLLISION };

static const char *const hint_clear = HINT_CLEAR;
static const char *const hint_skip = HINT_SKIP;
static const char *const hint_stamp = HINT_STAMP;

static void describe(size_t i, ex_case_info *out)
{
    if (is_same_case(i)) {
        snprintf(out->name, sizeof out->name, "scene %s, ray %d traced three times in a row (every slot reused)",
                 grid_scene_names[same_scene], same_ray + 1);
        ex_format_ray(out->what, sizeof out->what, &grid_rays[same_scene][same_ray]);
        out->hint = NULL;
        out->rules = "clear-per-ray check-slot record-every-test record-after-check collision-overwrites";
        grid_view_case(same_scene, same_ray, "grid", out);
        return;
    }
    const int s = (int)(i / CASES_PER_SCENE), r = (int)(i % CASES_PER_SCENE) * PER_CASE;
    const sidx_grid_cells *g = &grid_views[s];
    snprintf(out->name, sizeof out->name, "scene %s (%u x %u x %u cells), rays %d-%d in a row (%s, ...)",
             grid_scene_names[s], g->res[0], g->res[1], g->res[2], r + 1, r + PER_CASE, grid_ray_kind[s][r]);
    int n = 0;
    for (int k = 0; k < PER_CASE && n < (int)sizeof out->what - 1; ++k) {
        char buf[200];
        ex_format_ray(buf, sizeof buf, &grid_rays[s][r + k]);
        n += snprintf(out->what + n, sizeof out->what - (size_t)n, "%s%s", k ? "\n             " : "", buf);
    }
    out->hint = NULL;
    out->rules = "clear-per-ray check-slot record-every-test record-after-check collision-overwrites";
    grid_view_case(s, r, "grid", out);
}

static void reference(size_t i, const sidx_hook *h)
{
    if (is_same_case(i)) {
        for (int k = 0; k < PER_CASE; ++k) grid_reference_ray(same_scene, same_ray, (uint32_t)k, h);
        return;
    }
    const int s = (int)(i / CASES_PER_SCENE), r = (int)(i % CASES_PER_SCENE) * PER_CASE;
    for (int k = 0; k < PER_CASE; ++k) grid_reference_ray(s, r + k, (uint32_t)k, h);
}

static void cell(const sidx_ex *ex, const uint32_t *refs, uint32_t n, sidx_hit *best, void *user)
{
    cell_prims(ex, user, refs, n, best);
}

static void walk(const sidx_ex *ex, const sidx_grid_cells *g, sidx_hit *best, void *user)
{
    mailbox_new_ray(user);
    grid_dda_walk(ex, g, best, cell, user);
}

static void student(size_t i, const sidx_hook *h)
{
    const int s = (int)(i / CASES_PER_SCENE), r = (int)(i % CASES_PER_SCENE) * PER_CASE;
    sidx_ex_mailbox mb;
    memset(&mb, 0xA5, sizeof mb); /* whatever the memory held: no triangle's id */
    if (is_same_case(i)) {
        for (int k = 0; k < PER_CASE; ++k) grid_student_ray(same_scene, same_ray, (uint32_t)k, h, "grid", walk, &mb);
        return;
    }
    for (int k = 0; k < PER_CASE; ++k) grid_student_ray(s, r + k, (uint32_t)k, h, "grid", walk, &mb);
}

static const char *const hint_again = HINT_AGAIN;

/* A triangle the reference skips and the student tests again, on ray k
 * of case i: a collision the student did not let overwrite the slot when
 * the ray skipped other triangles before (its lookups work) and, before
 * this triangle's first test, tested another one of the same slot; else
 * the check or the recording. */
static const char *again_or_collision(size_t i, uint32_t k, uint32_t prim)
{
    int s = same_scene, r = same_ray;
    if (!is_same_case(i)) {
        s = (int)(i / CASES_PER_SCENE);
        r = (int)(i % CASES_PER_SCENE) * PER_CASE + (int)k;
    }
    if (k >= PER_CASE) return hint_again;
    ex_trace t = {NULL, 0, 0};
    const sidx_hook h = {ex_trace_hook_fn, &t, SIDX_EVMASK(SIDX_EV_PRIM_TEST) | SIDX_EVMASK(SIDX_EV_MAILBOX_HIT)};
    grid_reference_ray(s, r, k, &h);
    size_t first_skip = t.n, skip = t.n, test = t.n;
    for (size_t q = 0; q < t.n; ++q) {
        if (t.ev[q].type == SIDX_EV_MAILBOX_HIT && first_skip == t.n) first_skip = q;
        if (t.ev[q].type == SIDX_EV_MAILBOX_HIT && t.ev[q].prim == prim && skip == t.n) skip = q;
        if (t.ev[q].type == SIDX_EV_PRIM_TEST && t.ev[q].prim == prim && test == t.n) test = q;
    }
    int collided = 0;
    for (size_t q = 0; q < test && q < t.n; ++q)
        collided |= t.ev[q].type == SIDX_EV_PRIM_TEST && t.ev[q].prim != prim &&
                    t.ev[q].prim % SIDX_EX_MAILBOX_SIZE == prim % SIDX_EX_MAILBOX_SIZE;
    free(t.ev);
    return skip != first_skip && collided ? rules[R_COLLISION].hint : hint_again;
}

/* 1 if the reference tests prim more than once on ray k of case i: it
 * does so only when a collision overwrote prim's slot in between. */
static int retested(size_t i, uint32_t k, uint32_t prim)
{
    int s = same_scene, r = same_ray;
    if (!is_same_case(i)) {
        s = (int)(i / CASES_PER_SCENE);
        r = (int)(i % CASES_PER_SCENE) * PER_CASE + (int)k;
    }
    if (k >= PER_CASE) return 0;
    ex_trace t = {NULL, 0, 0};
    const sidx_hook h = {ex_trace_hook_fn, &t, SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    grid_reference_ray(s, r, k, &h);
    int n = 0;
    for (size_t q = 0; q < t.n; ++q) n += t.ev[q].prim == prim;
    free(t.ev);
    return n > 1;
}

/* What differs decides: a triangle skipped that the reference tests
 * again after a collision overwrote its slot is the collision rule; one
 * skipped that this ray has not tested is a stale cache (a later ray: the clearing) or a slot written before
 * the check (the first ray); a triangle tested again that the ray has
 * tested is the mailbox check and the recording, or a collision that
 * did not overwrite the slot; anything else is the check's order. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if (stu && stu->type == SIDX_EV_MAILBOX_HIT && ref && ref->type == SIDX_EV_PRIM_TEST) {
        if (retested(i, ref->ray_id, ref->prim)) return rules[R_COLLISION].hint;
        return stu->ray_id > 0 ? hint_clear : hint_stamp; /* the first ray has a fresh cache */
    }
    if (ref && ref->type == SIDX_EV_MAILBOX_HIT && stu && stu->type == SIDX_EV_PRIM_TEST && stu->prim == ref->prim)
        return again_or_collision(i, stu->ray_id, stu->prim);
    if (ref && ref->type == SIDX_EV_MAILBOX_HIT) return hint_stamp;
    return hint_skip;
}

const ex_driver ex_driver_this = {
    "07_grid_mailbox",
    "mailboxing on the uniform grid: the per-ray cache of object IDs",
    "deck 000, \"Uniform Grid Traversal\" (Mailboxing: per-ray cache of object IDs)",
    setup, num_cases, describe, reference, student, hint, teardown, NULL, rules, sizeof rules / sizeof rules[0],
};
