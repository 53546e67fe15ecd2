/* 14_bsp_painter.c — checker driver: the BSP tree's back-to-front order
 * (deck 000, "BSP Trees": "enumerating objects in back to front order").
 * Reference: the library's sidx_bsp_paint(SIDX_BSP_BACK_TO_FRONT) over its
 * own "bsp" tree, whose NODE_ENTER and PRIM_TEST events (one per piece)
 * are reported through sidx/exercise.h as the student's are: node and
 * depth per node entered, the piece's triangle per piece drawn. */
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
    int on_plane; /* the eye is moved into an axis-aligned splitting plane in setup */
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
};
#define NCASES (sizeof cases / sizeof cases[0])

static const char *const hint_order =
    "\"enumerating objects in back to front order\": at each node first the whole subtree on the side the eye is "
    "NOT on, then the node's own pieces (in its plane), then the eye's side; the eye is in front when n·eye - d >= 0";
static const char *const hint_pieces =
    "a node's own pieces lie in its plane: draw them between the far side and the near side, not before entering "
    "the children nor after both";
static const char *const hint_all =
    "every node is entered once and every piece drawn once, a leaf's pieces too, in their order i = 0 .. "
    "piece_count - 1 (a cut triangle has a piece on each side: it is drawn twice)";
static const char *const hint_plane =
    "an eye exactly in a splitting plane (n·eye - d == 0) counts as on the front side (v.child[0]): dist >= 0";

static int setup(void)
{
    for (int s = 0; s < NSCENES; ++s) {
        if (sidx_scene_open(scene_names[s], &meshes[s], NULL) != SIDX_OK) return -1;
        if (sidx_accel_build("bsp", &meshes[s], NULL, &trees[s], NULL) != SIDX_OK) return -1;
    }
    for (size_t i = 0; i < NCASES; ++i) {
        bp_case *c = &cases[i];
        if (!c->on_plane) continue;
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
    out->hint = c->on_plane ? hint_plane : hint_order;
}

static void ex_init(sidx_ex *ex, const sidx_hook *h, size_t i)
{
    memset(ex, 0, sizeof *ex);
    ex->hook = h;
    ex->structure = "bsp";
    ex->mesh = &meshes[cases[i].scene];
}

typedef struct relay { sidx_ex ex; } relay;

static void relay_fn(const sidx_event *e, void *user)
{
    const relay *r = user;
    if (e->type == SIDX_EV_NODE_ENTER) sidx_ex_node_enter(&r->ex, e->node, e->depth, 0.0f, 0.0f);
    else if (e->type == SIDX_EV_PRIM_TEST) sidx_ex_prim_test(&r->ex, e->prim, 1, 0.0f);
}

static int draw_nothing(const sidx_bsp_piece *p, void *user)
{
    (void)p;
    (void)user;
    return 0;
}

static void reference(size_t i, const sidx_hook *h)
{
    relay r;
    ex_init(&r.ex, h, i);
    const sidx_hook lib = {relay_fn, &r, SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST)};
    (void)sidx_bsp_paint(trees[cases[i].scene], cases[i].eye, SIDX_BSP_BACK_TO_FRONT, draw_nothing, NULL, &lib);
}

static void student(size_t i, const sidx_hook *h)
{
    sidx_ex ex;
    ex_init(&ex, h, i);
    bsp_paint(trees[cases[i].scene], cases[i].eye, &ex);
}

/* The hint by what differs: another node entered (the order of the two
 * sides, or the eye in the plane), a piece where the reference enters a
 * node or the reverse (the node's own pieces between the sides), another
 * piece or a trace that ends early or goes on (every node and piece once). */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    if (!ref || !stu) return hint_all;
    if (ref->type == SIDX_EV_NODE_ENTER && stu->type == SIDX_EV_NODE_ENTER)
        return cases[i].on_plane ? hint_plane : hint_order;
    if (ref->type != stu->type) return hint_pieces;
    return hint_all;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type == SIDX_EV_NODE_ENTER) snprintf(buf, size, "node %u enter  depth %u", e->node, e->depth);
    else if (e->type == SIDX_EV_PRIM_TEST) snprintf(buf, size, "draw a piece of triangle %u", e->prim);
    else return 0;
    return 1;
}

const ex_driver ex_driver_this = {
    "14_bsp_painter",
    "the BSP tree's back-to-front order: the painter's algorithm from any eye",
    "deck 000, \"BSP Trees\" (\"enumerating objects in back to front order\")",
    setup, num_cases, describe, reference, student, hint, teardown, format, NULL, 0,
};
