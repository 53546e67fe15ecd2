/* 07_grid_mailbox.c — checker driver: mailboxing on the uniform grid, the
 * per-ray cache of object IDs (deck 000, "Uniform Grid Traversal":
 * "Mailboxing ... Per-ray cache of object IDs — data local to a ray
 * (better!)").  Reference: the library's traced walk over a "grid" (the
 * mailboxed variant) for three rays in a row; the student's per-cell loop
 * runs inside the library's own 3D-DDA (grid_internal.h), with one
 * mailbox for the three rays, so a cache that is not cleared between
 * rays shows. */
#include <string.h>
#include "check.h"
#include "grid_cases.h"

void mailbox_new_ray(sidx_ex_mailbox *mb);
void cell_prims(const sidx_ex *ex, sidx_ex_mailbox *mb, const uint32_t *refs, uint32_t n, sidx_hit *best);

#define PER_CASE 3 /* rays traced in a row with one mailbox */
#define CASES_PER_SCENE (GRID_RAYS / PER_CASE)

static int setup(void) { return grid_setup("grid"); }
static void teardown(void) { grid_teardown(); }
static size_t num_cases(void) { return GRID_NSCENES * CASES_PER_SCENE; }

static const char *const hint_clear =
    "the cache is per ray (\"data local to a ray\"): clear every slot when a new ray starts, or a triangle "
    "tested by an earlier ray is skipped for this one";
static const char *const hint_skip =
    "\"Single primitive can be referenced in many cells — avoid multiple intersections\": before testing a "
    "triangle look in its slot (prim mod 32); if it holds prim, report sidx_ex_mailbox_hit and skip it, "
    "else write prim into the slot and test";
static const char *const hint_stamp =
    "\"Keep track of intersection tests\": record every triangle you test, hit or miss, and only after "
    "comparing with what the slot held";

static void describe(size_t i, ex_case_info *out)
{
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
    grid_view_case(s, r, "grid", out);
}

static void reference(size_t i, const sidx_hook *h)
{
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
    for (int k = 0; k < PER_CASE; ++k) grid_student_ray(s, r + k, (uint32_t)k, h, "grid", walk, &mb);
}

static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    (void)i;
    if (stu && stu->type == SIDX_EV_MAILBOX_HIT && ref && ref->type == SIDX_EV_PRIM_TEST)
        return stu->ray_id > 0 ? hint_clear : hint_stamp; /* the first ray has a fresh cache */
    if (ref && ref->type == SIDX_EV_MAILBOX_HIT) return hint_stamp;
    return hint_skip;
}

const ex_driver ex_driver_this = {
    "07_grid_mailbox",
    "mailboxing on the uniform grid: the per-ray cache of object IDs",
    "deck 000, \"Uniform Grid Traversal\" (Mailboxing: per-ray cache of object IDs)",
    setup, num_cases, describe, reference, student, hint, teardown, NULL,
};
