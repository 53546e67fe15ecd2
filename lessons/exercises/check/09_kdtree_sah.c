/* 09_kdtree_sah.c — checker driver: the kd-tree's SAH split choice (deck
 * 000, "Building good kD-trees": the cost, "Build a set of candidate
 * split locations — based on BBox of triangles (in/out events) ... Sort
 * the triangle events ... Walk through candidates to find minimum cost
 * split"; the empty-space bonus of "Cost-Optimized Split: produces large
 * chunks of empty space").  Reference: the library's "kdtree" build (the
 * event sweep of Wald & Havran 2006), whose BUILD_CANDIDATE and
 * BUILD_SPLIT events of one node are compared with the student's.  Cases:
 * the root of each scene, and its two children, whose straddling
 * triangles come clipped to the child's cell ("perfect splits", by the
 * build's own clipping) so the student's events start from the same
 * boxes. */
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "kdtree_internal.h"

void kd_split(const sidx_ex *ex, uint32_t node, sidx_aabb cell, const sidx_aabb *boxes, uint32_t n, float c_trav,
              float c_tri, float empty_bonus);

#define C_TRAV KD_DEFAULT_C_TRAV
#define C_TRI KD_DEFAULT_C_TRI
#define BONUS KD_DEFAULT_EMPTY_BONUS
#define NSCENES 6
static const char *const scene_names[NSCENES] = {"soup:80", "corner", "cornell", "menger:1", "flat2d:5", "icosphere:2"};
static const char *const scene_what[NSCENES] = {
    "random triangles", "a cluster in one corner of a large empty box (the empty-space bonus)",
    "axis-aligned walls (planar events)", "axis-aligned faces on shared planes (planar events)",
    "a flat scene: every triangle planar in z", "a sphere"};

typedef struct node_case {
    int scene;
    uint32_t node, n;
    sidx_aabb cell;
    sidx_aabb *boxes;
    sidx_event *ev; /* the node's CANDIDATE events and its SPLIT */
    size_t nev;
} node_case;
#define MAX_CASES (3 * NSCENES + 1)
static node_case cases[MAX_CASES];
static size_t ncases;

/* A cluster of 40 small triangles near one corner, and one triangle at
 * the far corner that makes the box ten times larger. */
static int make_corner(sidx_mesh *m)
{
    float xyz[41 * 9];
    uint32_t idx[41 * 3];
    uint32_t st = 9u;
    for (int t = 0; t < 40; ++t) {
        const float cx = 0.8f * ex_rand(&st), cy = 0.8f * ex_rand(&st), cz = 0.8f * ex_rand(&st);
        for (int v = 0; v < 3; ++v) {
            xyz[t * 9 + v * 3 + 0] = cx + 0.2f * ex_rand(&st);
            xyz[t * 9 + v * 3 + 1] = cy + 0.2f * ex_rand(&st);
            xyz[t * 9 + v * 3 + 2] = cz + 0.2f * ex_rand(&st);
        }
    }
    static const float far[9] = {10, 9.5f, 9.5f, 9.5f, 10, 9.5f, 9.5f, 9.5f, 10};
    memcpy(xyz + 40 * 9, far, sizeof far);
    for (uint32_t i = 0; i < 41 * 3; ++i) idx[i] = i;
    return sidx_mesh_from_arrays(m, xyz, 41 * 3, idx, 41, NULL) == SIDX_OK ? 0 : -1;
}

static sidx_aabb tri_box(const sidx_mesh *m, uint32_t i)
{
    sidx_aabb b = sidx_aabb_empty();
    for (int k = 0; k < 3; ++k) b = sidx_aabb_grow(b, sidx_mesh_vertex(m, i, k));
    return b;
}

/* Keeps node's events (its CANDIDATEs and its SPLIT) as a case, with the
 * boxes it starts from; 0 when the library did not split it. */
static int add_case(const ex_trace *rec, int scene, uint32_t node, sidx_aabb cell, sidx_aabb *boxes, uint32_t n)
{
    size_t first = rec->n, last = rec->n;
    for (size_t k = 0; k < rec->n; ++k) {
        if (rec->ev[k].node != node || rec->ev[k].type == SIDX_EV_BUILD_NODE) continue;
        if (rec->ev[k].type == SIDX_EV_BUILD_CANDIDATE && first == rec->n) first = k;
        if (rec->ev[k].type == SIDX_EV_BUILD_SPLIT) last = k;
    }
    if (first == rec->n || last == rec->n || ncases == MAX_CASES) {
        free(boxes);
        return 0;
    }
    node_case *c = &cases[ncases++];
    c->scene = scene;
    c->node = node;
    c->n = n;
    c->cell = cell;
    c->boxes = boxes;
    c->nev = last + 1 - first;
    c->ev = malloc(c->nev * sizeof *c->ev);
    if (!c->ev) exit(2);
    memcpy(c->ev, rec->ev + first, c->nev * sizeof *c->ev);
    return 1;
}

static int setup(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        sidx_mesh m;
        if (s == 1 ? make_corner(&m) != 0 : sidx_scene_open(scene_names[s], &m, NULL) != SIDX_OK) return -1;
        ex_trace rec = {NULL, 0, 0};
        const sidx_hook h = {ex_trace_hook_fn, &rec,
                             SIDX_EVMASK(SIDX_EV_BUILD_NODE) | SIDX_EVMASK(SIDX_EV_BUILD_CANDIDATE) |
                                 SIDX_EVMASK(SIDX_EV_BUILD_SPLIT)};
        sidx_build_options bo;
        memset(&bo, 0, sizeof bo);
        bo.hook = &h;
        bo.c_trav = C_TRAV;
        bo.c_tri = C_TRI;
        bo.empty_bonus = BONUS;
        sidx_accel *a = NULL;
        if (sidx_accel_build("kdtree", &m, &bo, &a, NULL) != SIDX_OK) return -1;
        sidx_accel_destroy(a);
        const uint32_t n = m.num_triangles;
        sidx_aabb *boxes = malloc(n * sizeof *boxes);
        if (!boxes || !rec.n || rec.ev[0].type != SIDX_EV_BUILD_NODE) return -1;
        for (uint32_t i = 0; i < n; ++i) boxes[i] = tri_box(&m, i);
        const sidx_aabb root = rec.ev[0].bounds;
        const sidx_event *sp = NULL;
        for (size_t k = 0; k < rec.n && !sp; ++k)
            if (rec.ev[k].type == SIDX_EV_BUILD_SPLIT && rec.ev[k].node == 0) sp = &rec.ev[k];
        if (sp) {
            /* The children: classify as the build does (end <= p left, start >= p right, planar in
             * the plane on the side that makes the split's count, the rest straddles and is
             * clipped to each child's cell). */
            const int k = sp->axis;
            const float p = sp->pos;
            uint32_t nl_noplanar = 0;
            for (uint32_t i = 0; i < n; ++i) {
                nl_noplanar += sidx_v3_get(boxes[i].min, k) < p; /* planar ones in the plane not counted */
            }
            const int planar_left = nl_noplanar != sp->count;
            sidx_aabb lcell = root, rcell = root;
            sidx_v3_set(&lcell.max, k, p);
            sidx_v3_set(&rcell.min, k, p);
            sidx_aabb *lb = malloc(n * sizeof *lb), *rb = malloc(n * sizeof *rb);
            if (!lb || !rb) return -1;
            uint32_t nl = 0, nr = 0;
            for (uint32_t i = 0; i < n; ++i) {
                const float lo = sidx_v3_get(boxes[i].min, k), hi = sidx_v3_get(boxes[i].max, k);
                const int planar = lo == hi;
                const int left = planar ? (lo < p || (lo == p && planar_left)) : hi <= p;
                const int right = planar ? !left : lo >= p;
                if (left) lb[nl++] = boxes[i];
                else if (right) rb[nr++] = boxes[i];
                else {
                    const kd_tri t = {sidx_mesh_vertex(&m, i, 0), sidx_mesh_vertex(&m, i, 1),
                                      sidx_mesh_vertex(&m, i, 2), i};
                    lb[nl++] = sidx__kd_clip_bounds(&t, lcell);
                    rb[nr++] = sidx__kd_clip_bounds(&t, rcell);
                }
            }
            add_case(&rec, s, 0, root, boxes, n);
            add_case(&rec, s, 1, lcell, lb, nl);
            add_case(&rec, s, 2, rcell, rb, nr);
        } else {
            free(boxes);
        }
        free(rec.ev);
        sidx_mesh_free(&m);
    }
    /* Three triangles whose boxes fill the whole cell: every event lies on
     * a face of the cell, no plane strictly inside, no candidate, no split. */
    if (ncases < MAX_CASES) {
        node_case *c = &cases[ncases];
        c->boxes = malloc(3 * sizeof *c->boxes);
        if (!c->boxes) return -1;
        const sidx_aabb unit = {{0, 0, 0}, {1, 1, 1}};
        for (int k = 0; k < 3; ++k) c->boxes[k] = unit;
        c->scene = -1;
        c->node = 0;
        c->n = 3;
        c->cell = unit;
        c->ev = NULL;
        c->nev = 0;
        ++ncases;
    }
    return ncases ? 0 : -1;
}

static void teardown(void)
{
    for (size_t i = 0; i < ncases; ++i) {
        free(cases[i].boxes);
        free(cases[i].ev);
    }
}

static size_t num_cases(void) { return ncases; }

#define HINT_EVENTS                                                                                        \
    "\"Build a set of candidate split locations based on BBox of triangles (in/out events)\": per axis a "    \
    "start event at each box's min and an end event at its max (one planar event for a flat box), sorted "  \
    "by position, ends before planars before starts at one position; one candidate per distinct position " \
    "strictly inside the cell, x then y then z"
#define HINT_ORDER                                                                                         \
    "at one position the ends come first, then the planars, then the starts: a triangle that ends at p and " \
    "one that starts at p lie on different sides, none on both"
#define HINT_COUNTS                                                                                        \
    "at a plane p: N_L = the triangles that start (or lie) before p, N_R = those that end after p; the "    \
    "plane's own end and planar events leave the right side before the cost is taken, its start events "   \
    "join the left side after"
#define HINT_PLANAR                                                                                        \
    "a triangle lying in the plane (planar event) is tried on either side: the cost with it left and with " \
    "it right, the cheaper one (left on a tie) is the candidate"
#define HINT_COST                                                                                          \
    "\"Cost(c) = C_trav + SA(L)/SA(c)·TriCount(L) + SA(R)/SA(c)·TriCount(R)\" (times C_tri), SA of the "     \
    "child CELLS (the cell cut at p), and when one side is empty the cost times (1 - empty bonus): cutting " \
    "off empty space \"produces large chunks of empty space\""
#define HINT_BONUS                                                                                         \
    "a plane with no triangle on one side (N_L = 0 or N_R = 0) cuts off empty space: its cost is "          \
    "multiplied by (1 - empty_bonus) (\"Cost-Optimized Split\")"
#define HINT_BEST                                                                                          \
    "\"Walk through candidates to find minimum cost split\": keep the first cheapest (strictly cheaper "      \
    "replaces it) and report it with sidx_ex_split"

/* The hand-out's promises (lessons/exercises/09_kdtree_sah.c). */
static const ex_rule rules[] = {
    {"events", "a start event at each box's min, an end at its max; a box flat on the axis gives one planar event",
     HINT_EVENTS},
    {"event-order", "at one position ends come first, then planars, then starts", HINT_ORDER},
    {"inside-cell", "a position is a candidate only strictly inside the cell", HINT_EVENTS},
    {"sweep-counts",
     "N_R loses the ends and planars at p before the cost; N_L gains the starts and planars at p after it",
     HINT_COUNTS},
    {"planar-side", "the triangles lying in the plane go to the cheaper side, left on a tie", HINT_PLANAR},
    {"sah-cost", "cost = C_trav + C_tri·(P_L·N_L + P_R·N_R), P the child cell's area over the cell's", HINT_COST},
    {"empty-bonus", "when N_L or N_R is 0 the cost is multiplied by (1 - empty_bonus)", HINT_BONUS},
    {"first-cheapest", "the split is the cheapest candidate, the first of equal ones", HINT_BEST},
};
enum { R_EVENTS, R_ORDER, R_INSIDE, R_COUNTS, R_PLANAR, R_COST, R_BONUS, R_BEST };

static const char *const hint_events = HINT_EVENTS;
static const char *const hint_counts = HINT_COUNTS;
static const char *const hint_planar = HINT_PLANAR;
static const char *const hint_cost = HINT_COST;
static const char *const hint_best = HINT_BEST;

/* 1 if a box of case c lies flat in the plane p of axis (a planar
 * event at p). */
static int planar_at(const node_case *c, int axis, float p)
{
    for (uint32_t k = 0; k < c->n; ++k)
        if (sidx_v3_get(c->boxes[k].min, axis) == p && sidx_v3_get(c->boxes[k].max, axis) == p) return 1;
    return 0;
}

/* 1 if a box of case c ends at p on axis and another starts there. */
static int touch_at(const node_case *c, int axis, float p)
{
    int ends = 0, starts = 0;
    for (uint32_t k = 0; k < c->n; ++k) {
        const float lo = sidx_v3_get(c->boxes[k].min, axis), hi = sidx_v3_get(c->boxes[k].max, axis);
        if (lo == hi) continue;
        ends |= hi == p;
        starts |= lo == p;
    }
    return ends && starts;
}

/* 1 if a box of case c is flat on some axis (a planar event). */
static int has_planar(const node_case *c)
{
    for (uint32_t k = 0; k < c->n; ++k)
        for (int a = 0; a < 3; ++a)
            if (sidx_v3_get(c->boxes[k].min, a) == sidx_v3_get(c->boxes[k].max, a)) return 1;
    return 0;
}

static void describe(size_t i, ex_case_info *out)
{
    const node_case *c = &cases[i];
    if (c->scene < 0)
        snprintf(out->name, sizeof out->name, "three triangles whose boxes fill the cell: no plane inside it");
    else
        snprintf(out->name, sizeof out->name, "scene %s (%s), node %u%s", scene_names[c->scene], scene_what[c->scene],
                 c->node, c->node ? " (a child: straddling triangles clipped to its cell)" : " (the root)");
    snprintf(out->what, sizeof out->what,
             "cell [%g %g %g]-[%g %g %g], %u triangles; C_trav = %g, C_tri = %g, empty bonus %g",
             (double)c->cell.min.x, (double)c->cell.min.y, (double)c->cell.min.z, (double)c->cell.max.x,
             (double)c->cell.max.y, (double)c->cell.max.z, c->n, (double)C_TRAV, (double)C_TRI, (double)BONUS);
    out->hint = hint_events;
    out->rules = c->scene < 0      ? "inside-cell events"
                 : has_planar(c) ? "events event-order inside-cell sweep-counts planar-side sah-cost empty-bonus "
                                   "first-cheapest"
                                 : "events event-order inside-cell sweep-counts sah-cost empty-bonus first-cheapest";
}

static void reference(size_t i, const sidx_hook *h)
{
    for (size_t k = 0; k < cases[i].nev; ++k) sidx_hook_emit(h, &cases[i].ev[k]);
}

static void student(size_t i, const sidx_hook *h)
{
    const node_case *c = &cases[i];
    sidx_ex ex;
    memset(&ex, 0, sizeof ex);
    ex.hook = h;
    ex.structure = "kdtree";
    kd_split(&ex, c->node, c->cell, c->boxes, c->n, C_TRAV, C_TRI, BONUS);
}

/* What differs decides: the split is the first-cheapest rule; another
 * plane the events; at the same plane the same counts the cost (or the
 * bonus, with an empty side); the same total on other sides the planar
 * rule; fewer in all at a flat box's plane the planar event; more in all
 * where boxes touch the order at one position; else the sweep's counts. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if ((ref && ref->type == SIDX_EV_BUILD_SPLIT) || (stu && stu->type == SIDX_EV_BUILD_SPLIT)) return hint_best;
    if (!ref || !stu || ref->axis != stu->axis || ref->pos != stu->pos) return hint_events;
    if (ref->count == stu->count && ref->aux == stu->aux)
        return ref->count == 0 || ref->aux == 0 ? rules[R_BONUS].hint : hint_cost; /* an empty side: the bonus */
    const uint32_t want = ref->count + ref->aux, got = stu->count + stu->aux;
    if (want == got) return hint_planar; /* same total: a planar on the other side */
    /* fewer in all at a flat box's plane: it was no planar event, on neither side */
    if (got < want && planar_at(&cases[i], ref->axis, ref->pos)) return hint_events;
    /* more in all where one box ends and another starts: the order at one position */
    if (got > want && touch_at(&cases[i], ref->axis, ref->pos)) return rules[R_ORDER].hint;
    return hint_counts;
}

const ex_driver ex_driver_this = {
    "09_kdtree_sah",
    "the kd-tree's SAH split: events, the sweep, planar triangles, the empty-space bonus",
    "deck 000, \"Building good kD-trees\" (SAH, candidate events, minimum cost split) and \"Cost-Optimized Split\"",
    setup, num_cases, describe, reference, student, hint, teardown, NULL, rules, sizeof rules / sizeof rules[0],
};
