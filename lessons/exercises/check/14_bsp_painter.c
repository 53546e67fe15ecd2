/* 14_bsp_painter.c — checker driver: the BSP tree's back-to-front order
 * (deck 000, "BSP Trees": "enumerating objects in back to front order").
 * Reference: the library's sidx_bsp_paint(SIDX_BSP_BACK_TO_FRONT) over its
 * own "bsp" tree, whose NODE_ENTER and PRIM_TEST events (one per piece)
 * are reported through sidx/exercise.h as the student's are: node and
 * depth per node entered, the piece's triangle per piece drawn. */
#include <math.h>
#include <string.h>
#include "check.h"
#include "sidx/bsp.h"

void bsp_paint(const sidx_accel *bsp, sidx_vec3 eye, const sidx_ex *ex);

#define NSCENES 4
static const char *const scene_names[NSCENES] = {"flat2d", "cornell", "soup:60", "kd-slide"};
static sidx_mesh meshes[NSCENES];
static sidx_accel *trees[NSCENES];

typedef struct bp_case {
    const char *name;
    int scene;
    sidx_vec3 eye;
    int on_plane; /* setup moves the eye: 1 into an axis-aligned splitting plane, 2 next to an oblique one where
                     n·eye - d in float has the other sign than in double */
} bp_case;

static bp_case cases[] = {
    {"flat2d (the slide's 2D scene), eye left of the scene, in z = 0", 0, {-12, 0.5f, 0}, 0},
    {"flat2d, eye right of the scene, in z = 0", 0, {12, -0.25f, 0}, 0},
    {"flat2d, eye above, in z = 0", 0, {0.3f, 11, 0}, 0},
    {"flat2d, eye in the middle of the scene, in z = 0", 0, {0.1f, 0.2f, 0}, 0},
    {"flat2d, eye in front (z > 0)", 0, {0.5f, 0.5f, 20}, 0},
    {"flat2d, eye behind (z < 0)", 0, {-0.5f, 0.25f, -20}, 0},
    {"cornell, eye at the camera", 1, {2.78f, 2.73f, -8.0f}, 0},
    {"cornell, eye inside the room", 1, {2.5f, 2.5f, 2.5f}, 0},
    {"cornell, eye between the blocks, low", 1, {2.6f, 0.5f, 2.0f}, 0},
    {"cornell, eye behind the back wall", 1, {2.78f, 2.73f, 12.0f}, 0},
    {"cornell, eye above the ceiling", 1, {2.0f, 9.0f, 3.0f}, 0},
    {"cornell, eye in an axis-aligned splitting plane (counts as in front)", 1, {2.5f, 2.5f, 2.5f}, 1},
    {"soup:60, eye outside, corner", 2, {-9, -9, -9}, 0},
    {"soup:60, eye outside, other corner", 2, {9, 8, 7}, 0},
    {"soup:60, eye inside the soup", 2, {0.1f, -0.2f, 0.3f}, 0},
    {"soup:60, eye inside, elsewhere", 2, {-0.4f, 0.45f, -0.3f}, 0},
    {"kd-slide, eye in front", 3, {5, 4, 10}, 0},
    {"kd-slide, eye behind", 3, {5, 4, -10}, 0},
    {"kd-slide, eye in the plane z = 0, left", 3, {-3, 4, 0}, 0},
    {"kd-slide, eye in the plane z = 0, inside", 3, {5.3f, 3.1f, 0}, 0},
    {"soup:60, eye a hair from an oblique plane (float puts it on the other side)", 2, {0.1f, -0.2f, 0.3f}, 2},
};
#define NCASES (sizeof cases / sizeof cases[0])

/* The hand-out's rules, in its order. */
enum { R_REPORT, R_LEAF, R_FAR, R_OWN, R_DOUBLE, R_ON_PLANE, R_PIECE_ORDER, NRULES };
static const ex_rule rules[NRULES] = {
    {"node-report", "every node reported on entry, sidx_ex_node_enter(ex, node, depth, 0, 0): the root at depth 0, a "
     "child at its parent's depth + 1",
     "report every node as you enter it with sidx_ex_node_enter(ex, node, depth, 0, 0): the root (node 0) has "
     "depth 0, a child its parent's depth + 1"},
    {"leaf-draws", "a leaf (child[0] == UINT32_MAX) draws its pieces; every node entered once, every piece drawn once",
     "every node is entered once and every piece drawn once, a leaf's pieces too, in their order i = 0 .. "
     "piece_count - 1 (a cut triangle has a piece on each side: it is drawn twice)"},
    {"far-side-first", "first the whole subtree on the side the eye is NOT on, the eye's side last",
     "\"enumerating objects in back to front order\": at each node first the whole subtree on the side the eye is "
     "NOT on, then the node's own pieces (in its plane), then the eye's side; the eye is in front when n·eye - d >= 0"},
    {"own-pieces-between", "an inner node's own pieces are drawn after the far subtree, before the eye's side",
     "a node's own pieces lie in its plane: draw them between the far side and the near side, not before entering "
     "the children nor after both"},
    {"side-in-double", "the eye's side from n·eye - d computed in double",
     "compute n·eye - d in double (v.n[] and v.d are double): in float an eye a hair from an oblique plane can land "
     "on the wrong side of it"},
    {"on-plane-front", "an eye exactly in a splitting plane (n·eye - d == 0) counts as in front (child[0])",
     "an eye exactly in a splitting plane (n·eye - d == 0) counts as on the front side (v.child[0]): dist >= 0"},
    {"piece-order", "a node's pieces go in their order i = 0, 1, ..., piece_count - 1",
     "draw a node's pieces in their order, sidx_bsp_node_piece(bsp, node, i, ...) for i = 0, 1, ..., "
     "piece_count - 1 (the order the tree keeps them in)"},
};

/* Which rules a case tests: every case the walk's rules; the eye cases
 * their own. */
#define WALK_RULES "node-report leaf-draws far-side-first own-pieces-between piece-order"

/* n·e - d in float, as a student who does not follow "compute it in double" would. */
static float dist_float(const sidx_bsp_node_view *v, sidx_vec3 e)
{
    return (float)v->n[0] * e.x + (float)v->n[1] * e.y + (float)v->n[2] * e.z - (float)v->d;
}

/* Moves c->eye next to the first oblique plane (depth first) to a float
 * point where n·eye - d has one sign in double and the other in float:
 * the eye projected onto the plane, then stepped a float at a time in x. */
static int near_oblique(bp_case *c)
{
    const sidx_accel *t = trees[c->scene];
    sidx_bsp_info info;
    if (sidx_bsp_info_get(t, &info) != SIDX_OK) return -1;
    for (uint32_t nd = 0; nd < info.nodes; ++nd) {
        sidx_bsp_node_view v;
        if (sidx_bsp_node_get(t, nd, &v) != SIDX_OK || v.child[0] == UINT32_MAX) continue;
        if (v.n[0] == 0.0 || v.n[1] == 0.0 || v.n[2] == 0.0) continue;
        const double dd = v.n[0] * c->eye.x + v.n[1] * c->eye.y + v.n[2] * c->eye.z - v.d;
        sidx_vec3 e = sidx_v3((float)(c->eye.x - dd * v.n[0]), (float)(c->eye.y - dd * v.n[1]),
                              (float)(c->eye.z - dd * v.n[2]));
        for (int k = 0; k < 64; ++k) {
            const double d2 = v.n[0] * e.x + v.n[1] * e.y + v.n[2] * e.z - v.d;
            const float f2 = dist_float(&v, e);
            if ((d2 >= 0.0) != (f2 >= 0.0f)) {
                c->eye = e;
                return 0;
            }
            e.x = nextafterf(e.x, k % 2 ? INFINITY : -INFINITY);
            if (k % 2) e.x = nextafterf(e.x, INFINITY);
        }
    }
    return -1;
}

static int setup(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        if (sidx_scene_open(scene_names[s], &meshes[s], NULL) != SIDX_OK) return -1;
        if (sidx_accel_build("bsp", &meshes[s], NULL, &trees[s], NULL) != SIDX_OK) return -1;
    }
    for (size_t i = 0; i < NCASES; ++i) {
        bp_case *c = &cases[i];
        if (!c->on_plane) continue;
        if (c->on_plane == 2) {
            if (near_oblique(c) != 0) return -1;
            continue;
        }
        /* the first inner node (depth-first) with an axis-aligned plane at a float offset */
        sidx_bsp_info info;
        if (sidx_bsp_info_get(trees[c->scene], &info) != SIDX_OK) return -1;
        int done = 0;
        for (uint32_t nd = 0; nd < info.nodes && !done; ++nd) {
            sidx_bsp_node_view v;
            if (sidx_bsp_node_get(trees[c->scene], nd, &v) != SIDX_OK || v.child[0] == UINT32_MAX) continue;
            for (int k = 0; k < 3 && !done; ++k) {
                if (v.n[k] != 1.0 || (double)(float)v.d != v.d) continue;
                if (v.n[(k + 1) % 3] != 0.0 || v.n[(k + 2) % 3] != 0.0) continue;
                float e[3] = {c->eye.x, c->eye.y, c->eye.z};
                e[k] = (float)v.d;
                c->eye = sidx_v3(e[0], e[1], e[2]);
                done = 1;
            }
        }
        if (!done) return -1;
    }
    return 0;
}

static void teardown(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        sidx_accel_destroy(trees[s]);
        sidx_mesh_free(&meshes[s]);
    }
}

static size_t num_cases(void) { return NCASES; }

static void describe(size_t i, ex_case_info *out)
{
    const bp_case *c = &cases[i];
    sidx_bsp_info info;
    memset(&info, 0, sizeof info);
    (void)sidx_bsp_info_get(trees[c->scene], &info);
    snprintf(out->name, sizeof out->name, "%s", c->name);
    snprintf(out->what, sizeof out->what, "eye=(%.9g, %.9g, %.9g); bsp over %s: %u nodes, %u pieces (%u cuts)",
             (double)c->eye.x, (double)c->eye.y, (double)c->eye.z, scene_names[c->scene], info.nodes, info.pieces,
             info.splits);
    out->hint = rules[c->on_plane == 1 ? R_ON_PLANE : c->on_plane == 2 ? R_DOUBLE : R_FAR].hint;
    out->rules = c->on_plane == 1 ? WALK_RULES " on-plane-front" : c->on_plane == 2 ? WALK_RULES " side-in-double" : WALK_RULES;
}

static void ex_init(sidx_ex *ex, const sidx_hook *h, size_t i)
{
    memset(ex, 0, sizeof *ex);
    ex->hook = h;
    ex->structure = "bsp";
    ex->mesh = &meshes[cases[i].scene];
}

/* The library's walk relayed; a leaf's pieces (the piece_count draws
 * right after entering it) carry aux = the leaf + 1, which the comparison
 * ignores and the hint reads. */
typedef struct relay {
    const sidx_hook *h;
    const sidx_accel *tree;
    uint32_t leaf, leaf_left;
} relay;

static void relay_fn(const sidx_event *e, void *user)
{
    relay *r = user;
    sidx_event o = sidx_event_blank(e->type);
    o.structure = "bsp";
    if (e->type == SIDX_EV_NODE_ENTER) {
        sidx_bsp_node_view v;
        r->leaf = e->node;
        r->leaf_left = sidx_bsp_node_get(r->tree, e->node, &v) == SIDX_OK && v.child[0] == UINT32_MAX ? v.piece_count
                                                                                                      : 0;
        o.node = e->node;
        o.depth = e->depth;
        o.t_near = o.t_far = 0.0f;
    } else if (e->type == SIDX_EV_PRIM_TEST) {
        o.prim = e->prim;
        o.result = 1;
        o.t = 0.0f;
        o.aux = r->leaf_left > 0 ? r->leaf + 1 : 0;
        if (r->leaf_left) --r->leaf_left;
    } else {
        return;
    }
    sidx_hook_emit(r->h, &o);
}

static int draw_nothing(const sidx_bsp_piece *p, void *user)
{
    (void)p;
    (void)user;
    return 0;
}

static void reference(size_t i, const sidx_hook *h)
{
    relay r = {h, trees[cases[i].scene], 0, 0};
    const sidx_hook lib = {relay_fn, &r, SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    (void)sidx_bsp_paint(trees[cases[i].scene], cases[i].eye, SIDX_BSP_BACK_TO_FRONT, draw_nothing, NULL, &lib);
}

static void student(size_t i, const sidx_hook *h)
{
    sidx_ex ex;
    ex_init(&ex, h, i);
    bsp_paint(trees[cases[i].scene], cases[i].eye, &ex);
}

/* The hint by what differs: the same node at another depth (or with
 * other t); another node entered (the order of the two sides, the eye in
 * the plane, the side in float); a leaf's piece where the student goes on
 * (the leaf draws); a piece where the reference enters a node or the
 * reverse (the node's own pieces between the sides); another piece (their
 * order). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const int on = cases[i].on_plane;
    if (ref && ref->type == SIDX_EV_PRIM_TEST && ref->aux) {
        /* a leaf's piece: another of the same leaf is their order */
        if (stu && stu->type == SIDX_EV_PRIM_TEST) {
            sidx_bsp_node_view v;
            const uint32_t leaf = ref->aux - 1;
            if (sidx_bsp_node_get(trees[cases[i].scene], leaf, &v) == SIDX_OK)
                for (uint32_t k = 0; k < v.piece_count; ++k) {
                    sidx_bsp_piece p;
                    if (sidx_bsp_node_piece(trees[cases[i].scene], leaf, k, &p) == SIDX_OK && p.tri == stu->prim)
                        return rules[R_PIECE_ORDER].hint;
                }
        }
        return rules[R_LEAF].hint;
    }
    if (!ref || !stu) return rules[R_LEAF].hint;
    if (ref->type == SIDX_EV_NODE_ENTER && stu->type == SIDX_EV_NODE_ENTER) {
        if (ref->node == stu->node) return rules[R_REPORT].hint;
        return rules[on == 1 ? R_ON_PLANE : on == 2 ? R_DOUBLE : R_FAR].hint;
    }
    if (ref->type != stu->type) return rules[R_OWN].hint;
    return rules[R_PIECE_ORDER].hint;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type == SIDX_EV_NODE_ENTER && (e->t_near != 0.0f || e->t_far != 0.0f))
        snprintf(buf, size, "node %u enter  depth %u  t_near %g, t_far %g (report 0, 0)", e->node, e->depth,
                 (double)e->t_near, (double)e->t_far);
    else if (e->type == SIDX_EV_NODE_ENTER) snprintf(buf, size, "node %u enter  depth %u", e->node, e->depth);
    else if (e->type == SIDX_EV_PRIM_TEST) snprintf(buf, size, "draw a piece of triangle %u", e->prim);
    else return 0;
    return 1;
}

const ex_driver ex_driver_this = {
    "14_bsp_painter",
    "the BSP tree's back-to-front order: the painter's algorithm from any eye",
    "deck 000, \"BSP Trees\" (\"enumerating objects in back to front order\")",
    setup, num_cases, describe, reference, student, hint, teardown, format, rules, NRULES,
};
