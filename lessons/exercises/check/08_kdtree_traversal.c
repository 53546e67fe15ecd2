/* 08_kdtree_traversal.c — checker driver: the kd-tree's front-to-back
 * walk with a stack (deck 000, "kD-Tree Traversal Operation", "kD-Tree
 * Traversal: Inner Loop").  Reference: the library's traced kd-tree query
 * (kd_walk_slide, the slide's loop as written), over a "kdtree" built
 * with the slides' Möller–Trumbore test and no mailbox, so that a leaf's
 * events are one PRIM_TEST per reference. */
#include <string.h>
#include "check.h"
#include "sidx/kdtree.h"

int kd_walk(const sidx_ex *ex, const sidx_kd_node *nodes, const uint32_t *refs, float t_near, float t_far,
            sidx_hit *best);

#define NSCENES 3
#define RAYS 43
/* flat2d: the slide's 2D scene (tilted triangles), walked by rays in its
 * middle plane as on the slides' pictures, and from the front; soup: overlapping
 * triangles straddling cells ("CANNOT terminate"); cornell: walls on the
 * split planes. */
static const char *const scene_names[NSCENES] = {"flat2d", "soup:200", "cornell"};
static sidx_mesh meshes[NSCENES];
static sidx_accel *accels[NSCENES];
static sidx_ray rays[NSCENES][RAYS];
static const char *ray_kind[NSCENES][RAYS];

enum { K_OUTSIDE = 0, K_BEYOND = 8, K_INSIDE = 12, K_ON_PLANE = 20, K_TFAR_TIE = 24, K_NEG_ZERO = 28, K_IN_PLANE = 32,
       K_TMAX = 36, K_TMIN_TIE = 40, K_ULP = 41, K_EXIT = 42 };

/* The root's split, or a split met deeper down on the way to point p
 * (depth levels at most): *axis, *pos. */
static void split_on_way(const sidx_kd_node *nodes, sidx_vec3 p, int levels, uint32_t *axis, float *pos)
{
    const float c[3] = {p.x, p.y, p.z};
    uint32_t node = 0;
    *axis = 0;
    *pos = c[0];
    for (int l = 0; l <= levels && (nodes[node].bits & 3u) != SIDX_KD_LEAF; ++l) {
        *axis = nodes[node].bits & 3u;
        *pos = nodes[node].u.split;
        node = (nodes[node].bits >> 2) + (c[*axis] > *pos ? 1u : 0u);
    }
}

/* Whether the library's walk of ray r finds a hit in a leaf and goes on
 * because the hit lies beyond that leaf's cell ("CANNOT terminate !!!"). */
typedef struct beyond_state {
    int pending, found;
} beyond_state;

static void beyond_fn(const sidx_event *ev, void *user)
{
    beyond_state *b = user;
    if (ev->type == SIDX_EV_HIT_UPDATE) b->pending = 1;
    else if (ev->type == SIDX_EV_TERMINATE && ev->reason == SIDX_TERM_HIT_IN_CELL) b->pending = 0;
    else if ((ev->type == SIDX_EV_STACK_POP || ev->type == SIDX_EV_TERMINATE) && b->pending) b->found = 1;
}

static int hit_beyond_cell(const sidx_accel *a, const sidx_ray *r)
{
    beyond_state b = {0, 0};
    const sidx_hook h = {beyond_fn, &b, 0};
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &h;
    sidx_hit hit;
    sidx_accel_intersect(a, r, &q, &hit);
    return b.found;
}

static int setup(void)
{
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.tri = SIDX_TRI_MOLLER_TRUMBORE;
    bo.no_mailbox = 1;
    for (int s = 0; s < NSCENES; ++s) {
        if (sidx_scene_open(scene_names[s], &meshes[s], NULL) != SIDX_OK) return -1;
        if (sidx_accel_build("kdtree", &meshes[s], &bo, &accels[s], NULL) != SIDX_OK) return -1;
        const sidx_kd_node *nodes = NULL;
        uint32_t nn = 0;
        if (sidx_kdtree_nodes(accels[s], &nodes, &nn, NULL) != SIDX_OK) return -1;
        const sidx_aabb b = sidx_mesh_bounds(&meshes[s]);
        const sidx_vec3 c = sidx_aabb_centroid(b), e = sidx_aabb_extent(b);
        const int flat = e.z < 0.05f * fminf(e.x, e.y); /* flat2d: triangles 0.1 high */
        uint32_t st = 808u + (uint32_t)s;
        for (int i = 0, tries = 0; i < RAYS; ++i) {
            const float u = ex_rand(&st), v = ex_rand(&st), w = ex_rand(&st);
            sidx_vec3 p = sidx_v3(b.min.x + u * e.x, b.min.y + v * e.y, b.min.z + w * e.z);
            sidx_vec3 o, d = sidx_v3(ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f, ex_rand(&st) - 0.5f);
            float tmin = 0.0f, tmax = INFINITY;
            int in_plane = flat; /* flat2d: the ray in the scene's plane, d.z = ±0 */
            if (i < K_INSIDE) { /* from outside, towards a point of the scene */
                const float a = ex_rand(&st) * 6.2831853f;
                o = sidx_v3(c.x + 1.5f * cosf(a) * e.x, c.y + 1.5f * sinf(a) * e.y, p.z + (flat ? 0.0f : e.z));
                d = sidx_v3_sub(p, o);
                ray_kind[s][i] = "from outside, front to back";
            } else if (i < K_ON_PLANE) {
                o = p;
                ray_kind[s][i] = "starting inside";
            } else if (i < K_TFAR_TIE) { /* t_split = t_near = 0 */
                uint32_t axis;
                float pos;
                split_on_way(nodes, p, i - K_ON_PLANE, &axis, &pos);
                if (axis == 0) p.x = pos;
                else if (axis == 1) p.y = pos;
                else p.z = pos;
                o = p;
                ray_kind[s][i] = "starting on a split plane (t_split = t_near)";
            } else if (i < K_NEG_ZERO) { /* tmax = the root's t_split, computed as the walk does */
                const uint32_t axis = nodes[0].bits & 3u;
                const float oc[3] = {p.x, p.y, p.z};
                float dc[3] = {d.x, d.y, d.z};
                if ((dc[axis] > 0.0f) != (oc[axis] < nodes[0].u.split)) dc[axis] = -dc[axis];
                if (dc[axis] == 0.0f) dc[axis] = oc[axis] < nodes[0].u.split ? 1.0f : -1.0f;
                o = p;
                d = sidx_v3(dc[0], dc[1], dc[2]);
                if (flat) d.z = 0.0f;
                const sidx_ray tmp = ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0, INFINITY);
                const float inv[3] = {tmp.inv_dir.x, tmp.inv_dir.y, tmp.inv_dir.z};
                tmax = (nodes[0].u.split - oc[axis]) * inv[axis];
                in_plane = 0;
                ray_kind[s][i] = "ending on the root's split plane (t_split = t_far)";
            } else if (i < K_IN_PLANE) { /* along one axis, -0 on the others */
                const int k = i - K_NEG_ZERO;
                const float sgn = (k & 1) ? -1.0f : 1.0f;
                o = p;
                d = sidx_v3(-0.0f, -0.0f, -0.0f);
                if (k % 3 == 0) d.x = sgn;
                else if (k % 3 == 1) d.y = sgn;
                else d.z = flat ? -0.0f : sgn;
                if (flat && k % 3 == 2) d.x = -1.0f;
                in_plane = 0;
                ray_kind[s][i] = "axis-parallel, -0 components (inv_dir = -inf)";
            } else if (i < K_TMAX) { /* inside the root's split plane: t_split = 0 * inf = NaN */
                const uint32_t axis = nodes[0].bits & 3u;
                if (axis == 0) { p.x = nodes[0].u.split; d.x = (i & 1) ? -0.0f : 0.0f; }
                else if (axis == 1) { p.y = nodes[0].u.split; d.y = (i & 1) ? -0.0f : 0.0f; }
                else { p.z = nodes[0].u.split; d.z = (i & 1) ? -0.0f : 0.0f; }
                o = p;
                ray_kind[s][i] = "running inside the root's split plane (t_split = NaN)";
            } else if (i == K_EXIT) { /* on the root's plane and on the scene box's exit face: the cell is [0, 0] */
                const uint32_t axis = nodes[0].bits & 3u, other = flat ? 1u - (axis & 1u) : (axis + 1u) % 3u;
                float oc[3] = {p.x, p.y, p.z}, dc[3] = {0.2f * d.x, 0.2f * d.y, flat ? 0.0f : 0.2f * d.z};
                const float hi[3] = {b.max.x, b.max.y, b.max.z};
                oc[axis] = nodes[0].u.split;
                oc[other] = hi[other];
                dc[other] = 1.0f;
                if (dc[axis] == 0.0f) dc[axis] = 0.25f;
                o = sidx_v3(oc[0], oc[1], oc[2]);
                d = sidx_v3(dc[0], dc[1], dc[2]);
                ray_kind[s][i] = "leaving from the root's plane on the scene's face (t_split = t_near = t_far = 0)";
            } else if (i >= K_TMIN_TIE) { /* along the root's axis, reaching its plane at tmin or just past it */
                const uint32_t axis = nodes[0].bits & 3u;
                const float split = nodes[0].u.split, sgn = (i & 1) ? -1.0f : 1.0f;
                float oc[3] = {p.x, p.y, p.z}, dc[3] = {0.25f * d.x, 0.25f * d.y, flat ? 0.0f : 0.25f * d.z};
                dc[axis] = sgn;
                /* K_TMIN_TIE: the origin a unit before the plane and tmin = t_split > 0 (a tie at t_near > 0);
                 * K_ULP: the origin one float past the plane (t_split = -ulp, just behind t_near = 0) */
                oc[axis] = i == K_TMIN_TIE ? split - sgn : nextafterf(split, sgn * INFINITY);
                o = sidx_v3(oc[0], oc[1], oc[2]);
                d = sidx_v3(dc[0], dc[1], dc[2]);
                in_plane = 0;
                if (flat) o.z = c.z;
                if (i == K_TMIN_TIE) {
                    const sidx_ray tmp = ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0, INFINITY);
                    const float inv[3] = {tmp.inv_dir.x, tmp.inv_dir.y, tmp.inv_dir.z};
                    tmin = (split - oc[axis]) * inv[axis];
                    ray_kind[s][i] = "starting before the root's plane, tmin on it (t_split = t_near > 0)";
                } else {
                    ray_kind[s][i] = "starting one float past the root's plane (t_split = -ulp)";
                }
            } else if (flat) { /* flat2d from the front: one cell, hits */
                o = sidx_v3(p.x, p.y, 5.0f);
                d = sidx_v3((ex_rand(&st) - 0.5f) * 0.2f, (ex_rand(&st) - 0.5f) * 0.2f, -1.0f);
                in_plane = 0;
                ray_kind[s][i] = "from the front of the plane";
            } else { /* tmax cutting the scene */
                o = sidx_v3(c.x - e.x, p.y, p.z);
                d = sidx_v3(1.0f, (ex_rand(&st) - 0.5f) * 0.3f, (ex_rand(&st) - 0.5f) * 0.3f);
                tmax = e.x;
                ray_kind[s][i] = "with a finite tmax";
            }
            if (in_plane) {
                o.z = c.z;
                d.z = (i & 1) ? -0.0f : 0.0f;
            }
            if (d.x == 0.0f && d.y == 0.0f && d.z == 0.0f) d.x = 1.0f;
            rays[s][i] = ex_ray(o.x, o.y, o.z, d.x, d.y, d.z, tmin, tmax);
            if (i >= K_BEYOND && i < K_INSIDE) { /* search for a ray the slide's "CANNOT terminate" is about */
                if (hit_beyond_cell(accels[s], &rays[s][i])) ray_kind[s][i] = "a hit beyond its cell: CANNOT terminate";
                else if (++tries < 1000) --i; /* the same slot again */
            }
        }
    }
    return 0;
}

static void teardown(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        sidx_accel_destroy(accels[s]);
        sidx_mesh_free(&meshes[s]);
    }
}

static size_t num_cases(void) { return NSCENES * RAYS; }

#define HINT_DIRECTION                                                                                     \
    "\"Near and far depend on direction of ray!\": the near child is the left one (below the plane) for a "   \
    "positive direction on the split axis, the right one for a negative direction, whichever side the "    \
    "origin is on"
#define HINT_ZERO                                                                                          \
    "\"Near and far depend on direction of ray!\": a -0 direction component is negative too (ray->sign, not " \
    "d < 0): inv_dir = -inf, and t_split = +-inf keeps the ray on its origin's side"
#define HINT_TIE                                                                                           \
    "\"Three cases\": only a plane strictly before the cell (t_split < t_near) or strictly beyond it "        \
    "(t_split > t_far) rules a child out; a tie, t_split == t_near or t_split == t_far, goes to both children " \
    "(push the far one)"
#define HINT_NAN                                                                                           \
    "a ray inside the split plane (t_split = NaN) belongs to both cells: go to both over the whole "        \
    "interval, and no early exit for the rest of the ray"
#define HINT_STOP                                                                                          \
    "\"Traversal can be terminated as soon as surface intersection is found in the current node\": after a " \
    "leaf, stop if the best hit lies in this cell, inside it by more than a rounding error (best->t < t_far - "  \
    "|t_far|*KD_EPS)"
#define HINT_CANNOT                                                                                        \
    "\"CANNOT terminate !!!\": a hit beyond the current cell (best->t > t_far) may be hidden by a triangle in " \
    "a cell still on the stack; keep it as the best so far and go on"
#define HINT_POP                                                                                           \
    "pop the cell last pushed (\"Maintain stack of sub-trees still to traverse\"), and skip a popped cell "  \
    "whose t_near lies beyond best->t (by more than |best->t|*KD_EPS): it cannot hold a closer hit"
#define HINT_LEAF                                                                                          \
    "a leaf tests each of its triangles refs[first .. first + count) against the best hit so far, "         \
    "sidx_ex_test_triangle(ex, prim, best->t, &t), and reports a closer one with sidx_ex_hit_update"
#define HINT_STOP_NOHIT                                                                                    \
    "\"Traversal can be terminated as soon as surface intersection is found in the current node\": only a "  \
    "hit stops the walk; with no hit (best->prim == SIDX_NO_HIT) pop the next cell, and return 0 when the "  \
    "stack is empty"
#define HINT_START                                                                                         \
    "the loop is \"given (node, t_near, t_far)\": start at the root, sidx_ex_node_enter(ex, 0, 0, t_near, "   \
    "t_far), and report every cell you enter"
#define HINT_NEAR_INTERVAL                                                                                 \
    "the same child with another interval: when the plane cuts the cell, \"continue with (near child, "      \
    "t_near, t_split)\" (t_far becomes t_split), and when it lies beyond the cell the near child keeps "     \
    "(t_near, t_far)"
#define HINT_FAR_INTERVAL                                                                                  \
    "the same far child with another interval: it is pushed as (far child, t_split, t_far), and when the "  \
    "plane lies before the cell the far child keeps (t_near, t_far)"
#define HINT_DEPTH                                                                                         \
    "the same cell at another depth: the root has depth 0, a child its parent's depth + 1, and a popped "   \
    "cell the depth it was pushed with (keep it on the stack with the node)"
#define HINT_STACK_SIZE                                                                                    \
    "the stack size a step reports: sidx_ex_push gives the size AFTER the push (1 for the first), "         \
    "sidx_ex_pop the size BEFORE the pop"
/* The hand-out's promises (lessons/exercises/08_kdtree_traversal.c). */
static const ex_rule rules[] = {
    {"start-root", "the walk starts at the root (node 0, depth 0) over the [t_near, t_far] it is given",
     HINT_START},
    {"depth", "a child has its parent's depth + 1; a popped cell gets back the depth it was pushed with",
     HINT_DEPTH},
    {"near-by-direction", "the near child is the left one unless the direction is negative on the split axis",
     HINT_DIRECTION},
    {"neg-zero", "a -0 direction component counts as negative (ray->sign)", HINT_ZERO},
    {"tie-both", "t_split == t_near or t_split == t_far goes to both children", HINT_TIE},
    {"push-far",
     "when both children are visited, the far one is pushed with sidx_ex_push(ex, far, stack size after the "
     "push, t_split, t_far); a pop reports the size before it",
     HINT_STACK_SIZE},
    {"child-intervals",
     "the near child gets (t_near, t_split), the far one (t_split, t_far), t_split clamped into [t_near, "
     "t_far]; a child alone keeps (t_near, t_far)",
     HINT_NEAR_INTERVAL},
    {"nan-both", "a NaN t_split goes to both children over the whole interval, and no early exit follows",
     HINT_NAN},
    {"leaf-tests", "a leaf tests refs[first .. first + count) against best->t and reports a closer hit",
     HINT_LEAF},
    {"stop-in-cell", "after a leaf the walk returns 1 if the best hit lies in this cell", HINT_STOP},
    {"cannot-terminate", "a hit beyond the current cell does not end the walk", HINT_CANNOT},
    {"pop-skip", "a popped cell whose t_near lies beyond best->t is skipped (pop the next)", HINT_POP},
};
enum { R_START, R_DEPTH, R_DIRECTION, R_ZERO, R_TIE, R_PUSH, R_INTERVALS, R_NAN, R_LEAF, R_STOP, R_CANNOT, R_POP };

static const char *const hint_direction = HINT_DIRECTION;
static const char *const hint_zero = HINT_ZERO;
static const char *const hint_tie = HINT_TIE;
static const char *const hint_nan = HINT_NAN;
static const char *const hint_stop = HINT_STOP;
static const char *const hint_cannot = HINT_CANNOT;
static const char *const hint_pop = HINT_POP;
static const char *const hint_leaf = HINT_LEAF;
static const char *const hint_stop_nohit = HINT_STOP_NOHIT;
static const char *const hint_start = HINT_START;
static const char *const hint_near_interval = HINT_NEAR_INTERVAL;
static const char *const hint_far_interval = HINT_FAR_INTERVAL;

/* The rules a ray of each kind tests (beyond those of every walk:
 * start-root depth near-by-direction leaf-tests push-far child-intervals
 * stop-in-cell pop-skip). */
static const char *kind_rules(int r)
{
    if (r >= K_BEYOND && r < K_INSIDE) return "cannot-terminate stop-in-cell near-by-direction leaf-tests";
    if (r >= K_ON_PLANE && r < K_TFAR_TIE) return "tie-both child-intervals push-far";
    if (r >= K_TFAR_TIE && r < K_NEG_ZERO) return "tie-both child-intervals";
    if (r >= K_NEG_ZERO && r < K_IN_PLANE) return "neg-zero near-by-direction";
    if (r >= K_IN_PLANE && r < K_TMAX) return "nan-both pop-skip";
    if (r == K_TMIN_TIE) return "tie-both child-intervals";
    if (r == K_ULP || r == K_EXIT) return "tie-both child-intervals";
    if (r >= K_TMAX) return "stop-in-cell";
    return "start-root depth near-by-direction leaf-tests push-far child-intervals stop-in-cell pop-skip";
}

static void describe(size_t i, ex_case_info *out)
{
    const int s = (int)(i / RAYS), r = (int)(i % RAYS);
    snprintf(out->name, sizeof out->name, "scene %s, ray %d (%s)", scene_names[s], r + 1, ray_kind[s][r]);
    ex_describe_walk(out, &rays[s][r], "kdtree", "--no-mailbox", scene_names[s], &meshes[s]);
    out->rules = kind_rules(r);
}

/* The library's walk also tells, at an inner node, its plane, t_split
 * and the case taken (docs/events.md); a student reports the visit alone
 * (sidx_ex_node_enter: node, depth, interval), so the reference's trace
 * keeps what both report and leaves those fields blank. */
static void visit_only(const sidx_event *e, void *user)
{
    const sidx_hook *h = user;
    if (e->type != SIDX_EV_NODE_ENTER) {
        h->fn(e, h->user);
        return;
    }
    const sidx_event blank = sidx_event_blank(SIDX_EV_NODE_ENTER);
    sidx_event visit = *e;
    visit.axis = blank.axis;
    visit.pos = blank.pos;
    visit.t = blank.t;
    visit.result = blank.result;
    h->fn(&visit, h->user);
}

static void reference(size_t i, const sidx_hook *h)
{
    const int s = (int)(i / RAYS), r = (int)(i % RAYS);
    const sidx_hook visits = {visit_only, (void *)h, h->mask};
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &visits;
    sidx_hit hit;
    sidx_accel_intersect(accels[s], &rays[s][r], &q, &hit);
}

/* The hint follows what differs at the first divergence: a stop where
 * the reference goes on (or the reverse) is the termination rule; the
 * root not entered is the start; another triangle step is the leaf; a
 * push where the reference enters (or the reverse) is the three cases; the
 * same cell with another interval is the interval the slide gives that
 * child; another cell entered or pushed is near/far (the -0 rule on the
 * axis-parallel rays, the NaN rule inside the plane); a pop is the stack. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const int r = (int)(i % RAYS);
    /* a stop with a hit beyond the cell, on a ray inside a split plane, is the NaN rule */
    const ex_walk_hints walk = {hint_stop, r >= K_IN_PLANE && r < K_TMAX ? hint_nan : hint_cannot, hint_stop_nohit,
                                hint_start, hint_leaf};
    const char *w = ex_walk_hint(ref, stu, &walk);
    if (w) return w;
    /* the same step but for its depth: a cell's depth, or the stack's size */
    if (ref && stu && ref->type == stu->type && ref->node == stu->node && ref->depth != stu->depth &&
        ref->t_near == stu->t_near && ref->t_far == stu->t_far)
        return ref->type == SIDX_EV_NODE_ENTER ? rules[R_DEPTH].hint : rules[R_PUSH].hint;
    if ((ref && ref->type == SIDX_EV_STACK_POP) || (stu && stu->type == SIDX_EV_STACK_POP)) return hint_pop;
    if (ref && ref->type == SIDX_EV_TERMINATE && stu && stu->type == SIDX_EV_NODE_ENTER) return hint_pop;
    if (ref && stu && (ref->type == SIDX_EV_STACK_PUSH) != (stu->type == SIDX_EV_STACK_PUSH))
        return r >= K_IN_PLANE && r < K_TMAX ? hint_nan : hint_tie;
    if (ref && stu && ref->type == stu->type && ref->node == stu->node &&
        (ref->type == SIDX_EV_NODE_ENTER || ref->type == SIDX_EV_STACK_PUSH))
        return ref->type == SIDX_EV_NODE_ENTER ? hint_near_interval : hint_far_interval;
    if (r >= K_NEG_ZERO && r < K_IN_PLANE) return hint_zero;
    if (r >= K_IN_PLANE && r < K_TMAX) return hint_nan;
    return hint_direction;
}

/* Counts the student's NODE_ENTER events and keeps the last one (the
 * cell a TERMINATE names) on the way to the runner's hook. */
typedef struct counting {
    const sidx_hook *inner;
    uint32_t entered, node;
    float t_near, t_far;
} counting;

static void counting_fn(const sidx_event *ev, void *user)
{
    counting *c = user;
    if (ev->type == SIDX_EV_NODE_ENTER) {
        ++c->entered;
        c->node = ev->node;
        c->t_near = ev->t_near;
        c->t_far = ev->t_far;
    }
    sidx_hook_emit(c->inner, ev);
}

/* What the library's query does around the walk: RAY_BEGIN, the ray
 * clipped to the root's cell (the scene box, no event; TERMINATE
 * miss_root if it misses), the walk, TERMINATE (hit_in_cell when kd_walk
 * returns 1, stack_empty when it returns 0), RAY_END. */
static void student(size_t i, const sidx_hook *h)
{
    const int s = (int)(i / RAYS), r = (int)(i % RAYS);
    const sidx_ray *ray = &rays[s][r];
    const sidx_kd_node *nodes = NULL;
    const uint32_t *refs = NULL;
    uint32_t nn = 0, nr = 0;
    sidx_kdtree_nodes(accels[s], &nodes, &nn, NULL);
    sidx_kdtree_refs(accels[s], &refs, &nr, NULL);
    counting c = {h, 0, 0, 0.0f, 0.0f};
    const sidx_hook ch = {counting_fn, &c, 0};
    sidx_ex ex;
    sidx_hit best;
    ex_walk_begin(&ex, &ch, h, "kdtree", ray, &meshes[s], SIDX_TRI_MOLLER_TRUMBORE, SIDX_BOX_ROBUST, &best);
    sidx_ex quiet = ex;
    quiet.hook = NULL;
    const sidx_aabb root = sidx_mesh_bounds(&meshes[s]);
    float tn = 0.0f, tf = 0.0f;
    sidx_event e = sidx_event_blank(SIDX_EV_TERMINATE);
    e.structure = "kdtree";
    if (nr == 0 || !sidx_ex_test_box(&quiet, 0, &root, ray->tmin, best.t, &tn, &tf)) {
        e.reason = SIDX_TERM_MISS_ROOT;
        e.count = 0;
    } else if (kd_walk(&ex, nodes, refs, tn, tf, &best)) {
        e.reason = SIDX_TERM_HIT_IN_CELL;
        e.t = best.t;
        e.prim = best.prim; /* not compared: the hint tells a stop with no hit */
        e.count = c.entered;
        e.node = c.node;
        e.t_near = c.t_near;
        e.t_far = c.t_far;
    } else {
        e.reason = SIDX_TERM_STACK_EMPTY;
        e.t = best.prim != SIDX_NO_HIT ? best.t : INFINITY;
        e.count = c.entered;
    }
    sidx_hook_emit(h, &e);
    ex_walk_end(h, "kdtree", &best);
}

const ex_driver ex_driver_this = {
    "08_kdtree_traversal",
    "kd-tree traversal: front to back, with a stack of (node, t_near, t_far)",
    "deck 000, \"kD-Tree Traversal\", \"kD-Tree Traversal (1)-(11)\", \"kD-Tree Traversal Operation\" and "
    "\"kD-Tree Traversal: Inner Loop\"",
    setup, num_cases, describe, reference, student, hint, teardown, NULL, rules, sizeof rules / sizeof rules[0],
};
