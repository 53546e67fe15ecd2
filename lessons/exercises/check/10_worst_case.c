/* 10_worst_case.c — checker driver: the deck's private exercise (deck
 * 000, "Spatial index structures": "Can reduce complexity to O(log n) on
 * average — worst case complexity is still O(n). Private exercise: come
 * up with a worst case example").
 *
 * The student writes a scene of n triangles per structure; the checker
 * builds the library's structure on it for n = 64, 256 and 1024, shoots
 * rays at the scene's own triangles (each aimed at one triangle's centre
 * from a random direction outside the scene) and counts the triangle
 * tests per ray (PRIM_TEST events).  A worst case makes them grow like n:
 * at every n at least n/2 tests per ray.  There is no library trace to
 * follow here: the reference is the criterion, one NOTE per n (cell[0] =
 * n, cell[1] = triangles, count = 1 when met), and the student's NOTE
 * carries the measurement. */
#include <string.h>
#include "check.h"

void worst_case_scene(const char *structure, uint32_t n, sidx_mesh *out);

#define NSTRUCT 3
#define NSIZES 3
#define RAYS 24
static const char *const structures[NSTRUCT] = {"bvh", "grid", "kdtree"};
static const uint32_t sizes[NSIZES] = {64, 256, 1024};

static size_t num_cases(void) { return NSTRUCT * NSIZES; }

#define HINT_BVH                                                                                           \
    "a BVH separates objects, not space: make every triangle's box (nearly) the whole scene's box, e.g. "   \
    "long thin slivers all crossing the scene, so no split separates them and every ray enters every leaf"
#define HINT_GRID                                                                                          \
    "a grid's cells all have one size (\"cannot adapt to non-uniform distribution of geometry\"): put "      \
    "nearly all triangles into ONE cell (a teapot in a stadium) and keep the box large with a far-away "     \
    "triangle"
#define HINT_KD                                                                                            \
    "a kd-tree splits space, and cannot separate triangles that all straddle every plane: slivers crossing " \
    "the whole scene end in one leaf (or in every leaf)"
#define HINT_COUNT                                                                                         \
    "worst_case_scene(structure, n, out) must give a valid mesh of exactly n triangles: n·3 vertices, n "   \
    "index triples each naming vertices that exist, passed to sidx_mesh_from_arrays with n triangles"
#define HINT_VALID                                                                                         \
    "sidx_mesh_from_arrays refused your arrays (or the mesh is invalid), so the scene is empty: n index "   \
    "triples each naming vertices that exist (every index < the number of vertices you pass)"

/* The hand-out's promises (lessons/exercises/10_worst_case.c). */
static const ex_rule rules[] = {
    {"exact-n", "the scene has exactly n triangles", HINT_COUNT},
    {"valid-mesh", "the scene is a valid mesh written with sidx_mesh_from_arrays", HINT_VALID},
    {"bvh-grows", "on \"bvh\" the rays need at least n/2 triangle tests each, at every n", HINT_BVH},
    {"grid-grows", "on \"grid\" the rays need at least n/2 triangle tests each, at every n", HINT_GRID},
    {"kdtree-grows", "on \"kdtree\" the rays need at least n/2 triangle tests each, at every n", HINT_KD},
};
enum { R_COUNT, R_VALID, R_BVH, R_GRID, R_KD };

static const char *const hint_bvh = HINT_BVH;
static const char *const hint_grid = HINT_GRID;
static const char *const hint_kd = HINT_KD;
static const char *const hint_count = HINT_COUNT;

static void describe(size_t i, ex_case_info *out)
{
    const int s = (int)(i / NSIZES);
    const uint32_t n = sizes[i % NSIZES];
    snprintf(out->name, sizeof out->name, "%s, n = %u: triangle tests per ray must grow like n (at least n/2 = %u)",
             structures[s], n, n / 2);
    snprintf(out->what, sizeof out->what,
             "worst_case_scene(\"%s\", %u), %d rays each aimed at a triangle's centre from outside", structures[s], n,
             RAYS);
    out->hint = s == 0 ? hint_bvh : s == 1 ? hint_grid : hint_kd;
    out->rules = s == 0   ? "exact-n valid-mesh bvh-grows"
                 : s == 1 ? "exact-n valid-mesh grid-grows"
                          : "exact-n valid-mesh kdtree-grows";
}

/* aux = 1 marks the criterion (the reference), 0 a measurement. */
static void note(const sidx_hook *h, uint32_t n, uint32_t tris, int met, float tests, uint32_t criterion)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "exercise";
    e.cell[0] = (int32_t)n;
    e.cell[1] = (int32_t)tris;
    e.count = (uint32_t)met;
    e.cost = tests;
    e.aux = criterion;
    sidx_hook_emit(h, &e);
}

static void reference(size_t i, const sidx_hook *h)
{
    const uint32_t n = sizes[i % NSIZES];
    note(h, n, n, 1, (float)n / 2.0f, 1);
}

static void count_fn(const sidx_event *ev, void *user)
{
    if (ev->type == SIDX_EV_PRIM_TEST) ++*(uint64_t *)user;
}

/* The mean number of triangle tests per ray of `structure` on m. */
static float tests_per_ray(const char *structure, const sidx_mesh *m)
{
    sidx_accel *a = NULL;
    if (sidx_accel_build(structure, m, NULL, &a, NULL) != SIDX_OK) return -1.0f;
    const sidx_aabb b = sidx_mesh_bounds(m);
    const float diag = sidx_v3_length(sidx_aabb_extent(b)) + 1.0f;
    uint64_t tests = 0;
    const sidx_hook h = {count_fn, &tests, SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &h;
    uint32_t st = 77u;
    for (int r = 0; r < RAYS; ++r) {
        const uint32_t t = (uint32_t)(((uint64_t)r * 7919u + 13u) % m->num_triangles);
        const sidx_vec3 c = sidx_aabb_centroid(sidx_mesh_triangle_bounds(m, t));
        sidx_vec3 d;
        do {
            d = sidx_v3(2 * ex_rand(&st) - 1, 2 * ex_rand(&st) - 1, 2 * ex_rand(&st) - 1);
        } while (sidx_v3_length(d) < 0.1f);
        d = sidx_v3_scale(d, 2.0f * diag / sidx_v3_length(d));
        const sidx_vec3 o = sidx_v3_add(c, d);
        const sidx_ray ray = ex_ray(o.x, o.y, o.z, -d.x, -d.y, -d.z, 0, INFINITY);
        sidx_hit hit;
        sidx_accel_intersect(a, &ray, &q, &hit);
    }
    sidx_accel_destroy(a);
    return (float)tests / (float)RAYS;
}

static void student(size_t i, const sidx_hook *h)
{
    const int s = (int)(i / NSIZES);
    const uint32_t n = sizes[i % NSIZES];
    sidx_mesh m;
    memset(&m, 0, sizeof m);
    worst_case_scene(structures[s], n, &m);
    if (sidx_mesh_validate(&m, NULL) != SIDX_OK) {
        note(h, n, (uint32_t)-1, 0, -1.0f, 0); /* cell[1] = -1: an invalid mesh */
    } else if (m.num_triangles != n) {
        note(h, n, m.num_triangles, 0, -1.0f, 0);
    } else {
        const float t = tests_per_ray(structures[s], &m);
        note(h, n, n, t >= (float)n / 2.0f, t, 0);
    }
    sidx_mesh_free(&m);
}

/* What differs decides: an empty or invalid mesh is the validity rule
 * (sidx_mesh_from_arrays refuses an index past the vertices), a scene of
 * another size the size rule, too few tests per ray the structure's own
 * weakness (the case's hint). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    (void)i;
    if (ref && stu && stu->type == SIDX_EV_NOTE && stu->cell[1] != ref->cell[1])
        return stu->cell[1] <= 0 ? rules[R_VALID].hint : hint_count;
    return NULL;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    if (e->cell[1] < 0)
        snprintf(buf, size, "n = %d: an invalid mesh (sidx_mesh_validate fails)", (int)e->cell[0]);
    else if (e->cell[0] != e->cell[1])
        snprintf(buf, size, "n = %d: a scene of %d triangles; n wanted", (int)e->cell[0], (int)e->cell[1]);
    else if (e->aux == 1)
        snprintf(buf, size, "n = %d: at least %g triangle tests per ray (n/2: O(n))", (int)e->cell[0], (double)e->cost);
    else
        snprintf(buf, size, "n = %d: %.1f triangle tests per ray%s", (int)e->cell[0], (double)e->cost,
                 e->count ? "" : " (fewer than n/2)");
    return 1;
}

const ex_driver ex_driver_this = {
    "10_worst_case",
    "the private exercise: a worst-case scene, where tests per ray grow like n",
    "deck 000, \"Spatial index structures\" (\"worst case complexity is still O(n). Private exercise: come up "
    "with a worst case example\")",
    NULL, num_cases, describe, reference, student, hint, NULL, format, rules, sizeof rules / sizeof rules[0],
};
