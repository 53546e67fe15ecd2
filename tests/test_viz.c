/* test_viz.c — the visualisation layer: the tree rebuilt from events, the
 * Graphviz output (parsed back with cgraph), the viewer's headless render
 * and sidx-step's trace against checked-in expected output.
 *
 * Runs from the repository root (tests/data/viz/...).  The expected traces
 * are tests/data/viz/step_<accel>.txt; regenerate them after a deliberate
 * change of a structure's events with SIDX_UPDATE_EXPECTED=1. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>
#include <graphviz/cgraph.h>
#include <SDL.h>
#include <SDL_image.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"
#include "../viz/view.h"

static char bin_dir[512] = "build/bin";

#define TINY_SCENE "tests/data/viz/tiny.obj"
#define TINY_RAY "8,0.2,0.2,-1,0,0"

/* ---- a synthetic event stream -------------------------------------------------- */
/*
 *            0 (split x=1)
 *          /   \
 *        1       2 (split y=0.5)
 *      leaf     /   \
 *              3     4
 *            leaf   leaf
 * The ray enters 0, tests boxes 1 (miss) and 2 (hit), enters 2, tests 3
 * (hit) and 4 (hit), enters 3, tests prims 5 and 6 (6 hits), enters 4.
 */
typedef struct evbuf { sidx_event ev[64]; size_t n; } evbuf;

static sidx_event *add(evbuf *b, sidx_event_type type)
{
    sidx_event *e = &b->ev[b->n++];
    *e = sidx_event_blank(type);
    e->structure = "fake";
    return e;
}

static sidx_aabb box(float x0, float y0, float x1, float y1)
{
    sidx_aabb b = {{x0, y0, 0.0f}, {x1, y1, 1.0f}};
    return b;
}

static void node(evbuf *b, uint32_t id, uint32_t parent, uint32_t depth, uint32_t count, sidx_aabb bounds)
{
    sidx_event *e = add(b, SIDX_EV_BUILD_NODE);
    e->node = id;
    e->parent = parent;
    e->depth = depth;
    e->count = count;
    e->bounds = bounds;
}

static void split(evbuf *b, uint32_t id, int axis, float pos, float cost)
{
    sidx_event *e = add(b, SIDX_EV_BUILD_SPLIT);
    e->node = id;
    e->axis = axis;
    e->pos = pos;
    e->cost = cost;
    e->count = 2;
    e->aux = 2;
}

static void leaf(evbuf *b, uint32_t id, uint32_t count)
{
    sidx_event *e = add(b, SIDX_EV_BUILD_LEAF);
    e->node = id;
    e->count = count;
    e->reason = SIDX_LEAF_FEW_PRIMS;
}

static void fake_build(evbuf *b)
{
    b->n = 0;
    add(b, SIDX_EV_BUILD_BEGIN)->count = 4;
    node(b, 0, UINT32_MAX, 0, 4, box(0, 0, 2, 1));
    split(b, 0, 0, 1.0f, 3.5f);
    node(b, 1, 0, 1, 1, box(0, 0, 1, 1));
    leaf(b, 1, 1);
    node(b, 2, 0, 1, 3, box(1, 0, 2, 1));
    split(b, 2, 1, 0.5f, 2.5f);
    node(b, 3, 2, 2, 2, box(1, 0, 2, 0.5f));
    leaf(b, 3, 2);
    node(b, 4, 2, 2, 1, box(1, 0.5f, 2, 1));
    leaf(b, 4, 1);
    add(b, SIDX_EV_BUILD_END)->node = 5;
}

static void fake_ray(evbuf *b)
{
    b->n = 0;
    add(b, SIDX_EV_RAY_BEGIN);
    add(b, SIDX_EV_NODE_ENTER)->node = 0;
    sidx_event *e = add(b, SIDX_EV_BOX_TEST);
    e->node = 1;
    e->result = 0;
    e = add(b, SIDX_EV_BOX_TEST);
    e->node = 2;
    e->result = 1;
    add(b, SIDX_EV_NODE_ENTER)->node = 2;
    e = add(b, SIDX_EV_BOX_TEST);
    e->node = 3;
    e->result = 1;
    e = add(b, SIDX_EV_BOX_TEST);
    e->node = 4;
    e->result = 1;
    e = add(b, SIDX_EV_STACK_PUSH);
    e->node = 4;
    e->depth = 1;
    add(b, SIDX_EV_NODE_ENTER)->node = 3;
    e = add(b, SIDX_EV_PRIM_TEST);
    e->prim = 5;
    e->result = 0;
    e = add(b, SIDX_EV_PRIM_TEST);
    e->prim = 6;
    e->result = 1;
    e->t = 0.75f;
    e = add(b, SIDX_EV_HIT_UPDATE);
    e->prim = 6;
    e->t = 0.75f;
    e = add(b, SIDX_EV_STACK_POP);
    e->node = 4;
    e->depth = 1;
    add(b, SIDX_EV_NODE_ENTER)->node = 4;
    e = add(b, SIDX_EV_RAY_END);
    e->prim = 6;
    e->t = 0.75f;
}

/* ---- tree model ------------------------------------------------------------------------ */

static void tree_from_synthetic_events(void **state)
{
    (void)state;
    evbuf b;
    fake_build(&b);
    sidx_viz_tree t;
    sidx_error err;
    assert_int_equal(sidx_viz_tree_from_events(b.ev, b.n, &t, &err), SIDX_OK);
    assert_int_equal(t.count, 5);
    assert_int_equal(t.leaves, 3);
    assert_int_equal(t.max_depth, 2);
    assert_string_equal(t.structure, "fake");
    assert_int_equal(t.nodes[t.root].id, 0);
    assert_int_equal(t.nodes[t.root].child_count, 2);
    uint32_t n2 = sidx_viz_tree_find(&t, 2);
    assert_int_not_equal(n2, SIDX_VIZ_NONE);
    assert_int_equal(t.nodes[n2].has_split, 1);
    assert_int_equal(t.nodes[n2].axis, 1);
    assert_true(t.nodes[n2].pos == 0.5f);
    assert_int_equal(t.nodes[n2].child_count, 2);
    assert_int_equal(t.nodes[t.children[t.nodes[n2].child_base]].id, 3);
    assert_int_equal(sidx_viz_tree_find(&t, 99), SIDX_VIZ_NONE);
    uint32_t nn;
    uint64_t pp;
    sidx_viz_tree_subtree(&t, t.root, &nn, &pp);
    assert_int_equal(nn, 5);
    assert_int_equal(pp, 4);

    evbuf r;
    fake_ray(&r);
    sidx_viz_tree_apply_ray(&t, r.ev, r.n);
    assert_int_equal(t.visited, 4);
    assert_int_equal(t.nodes[sidx_viz_tree_find(&t, 0)].visit_order, 1);
    assert_int_equal(t.nodes[sidx_viz_tree_find(&t, 3)].visit_order, 3);
    assert_int_equal(t.nodes[sidx_viz_tree_find(&t, 1)].box_result, 0);
    assert_int_equal(t.nodes[sidx_viz_tree_find(&t, 1)].visit_order, 0);
    assert_int_equal(t.nodes[sidx_viz_tree_find(&t, 3)].hit_leaf, 1);
    assert_int_equal(t.nodes[sidx_viz_tree_find(&t, 3)].prims_tested, 2);
    assert_int_equal(t.nodes[sidx_viz_tree_find(&t, 4)].hit_leaf, 0);
    assert_int_equal(t.hit_prim, 6);
    sidx_viz_tree_free(&t);
}

static void tree_errors(void **state)
{
    (void)state;
    sidx_viz_tree t;
    sidx_error err;
    evbuf b;
    b.n = 0;
    add(&b, SIDX_EV_BUILD_BEGIN);
    add(&b, SIDX_EV_BUILD_END);
    assert_int_equal(sidx_viz_tree_from_events(b.ev, b.n, &t, &err), SIDX_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.message, "fake does not emit a tree"));
    assert_null(t.nodes);

    /* cells without parent links: a uniform grid */
    b.n = 0;
    for (uint32_t i = 0; i < 4; ++i) node(&b, i, UINT32_MAX, 0, 1, box((float)i, 0, (float)i + 1, 1));
    assert_int_equal(sidx_viz_tree_from_events(b.ev, b.n, &t, &err), SIDX_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.message, "does not emit a tree"));

    /* a parent that never existed */
    b.n = 0;
    node(&b, 0, UINT32_MAX, 0, 2, box(0, 0, 1, 1));
    node(&b, 1, 7, 1, 1, box(0, 0, 1, 1));
    assert_int_equal(sidx_viz_tree_from_events(b.ev, b.n, &t, &err), SIDX_ERR_UNSUPPORTED);

    /* a duplicate id */
    b.n = 0;
    node(&b, 0, UINT32_MAX, 0, 2, box(0, 0, 1, 1));
    node(&b, 0, 0, 1, 1, box(0, 0, 1, 1));
    assert_int_equal(sidx_viz_tree_from_events(b.ev, b.n, &t, &err), SIDX_ERR_UNSUPPORTED);

    /* two top cells with children (a two-level grid): one virtual root */
    b.n = 0;
    node(&b, 0, UINT32_MAX, 0, 2, box(0, 0, 1, 1));
    node(&b, 1, UINT32_MAX, 0, 1, box(1, 0, 2, 1));
    node(&b, 10, 0, 1, 1, box(0, 0, 0.5f, 1));
    node(&b, 11, 0, 1, 1, box(0.5f, 0, 1, 1));
    assert_int_equal(sidx_viz_tree_from_events(b.ev, b.n, &t, &err), SIDX_OK);
    assert_int_equal(t.virtual_root, 1);
    assert_int_equal(t.count, 5);
    assert_int_equal(t.nodes[t.root].id, SIDX_VIZ_VIRTUAL_ROOT);
    assert_int_equal(t.nodes[t.root].child_count, 2);
    assert_int_equal(t.nodes[t.root].count, 3);
    sidx_viz_tree_free(&t);

    sidx_vec3 o, d;
    assert_int_equal(sidx_viz_parse_ray("1,2,3,0,0,-1", &o, &d), 0);
    assert_true(o.y == 2.0f && d.z == -1.0f);
    assert_int_not_equal(sidx_viz_parse_ray("1,2,3,0,0,0", &o, &d), 0);
    assert_int_not_equal(sidx_viz_parse_ray("1,2,3,0,0", &o, &d), 0);
    assert_int_not_equal(sidx_viz_parse_ray("1,2,3,0,0,1,5", &o, &d), 0);
    assert_int_not_equal(sidx_viz_parse_ray("1,2,nan,0,0,1", &o, &d), 0);
}

/* ---- Graphviz ------------------------------------------------------------------------------ */

static Agraph_t *read_graph(const char *path)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    Agraph_t *g = agread(f, NULL);
    fclose(f);
    assert_non_null(g);
    return g;
}

static const char *node_attr(Agraph_t *g, const char *name, const char *attr)
{
    Agnode_t *n = agnode(g, (char *)name, 0);
    assert_non_null(n);
    char *v = agget(n, (char *)attr);
    return v ? v : "";
}

static void tmp_path(char *buf, size_t size, const char *ext)
{
    snprintf(buf, size, "/tmp/sidx_test_viz_%ld.%s", (long)getpid(), ext);
}

static void dot_synthetic_parses_back(void **state)
{
    (void)state;
    evbuf b, r;
    fake_build(&b);
    fake_ray(&r);
    char path[128];
    tmp_path(path, sizeof path, "dot");
    sidx_error err;
    sidx_dot_options opt;
    memset(&opt, 0, sizeof opt);

    /* whole tree */
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, path, &err), SIDX_OK);
    Agraph_t *g = read_graph(path);
    assert_int_equal(agnnodes(g), 5);
    assert_int_equal(agnedges(g), 4);
    assert_non_null(strstr(node_attr(g, "n0", "label"), "split x = 1"));
    assert_non_null(strstr(node_attr(g, "n0", "label"), "SAH 3.5"));
    assert_non_null(strstr(node_attr(g, "n3", "label"), "2 prims"));
    agclose(g);

    /* cut below depth 1: root, its two children and one summary under 2 */
    opt.max_depth = 1;
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, path, &err), SIDX_OK);
    g = read_graph(path);
    assert_int_equal(agnnodes(g), 4);
    assert_int_equal(agnedges(g), 3);
    assert_non_null(strstr(node_attr(g, "cut2", "label"), "+2 nodes, 3 prims"));
    agclose(g);

    /* with the ray: order numbers, pruned node grey, hit leaf outlined */
    opt.max_depth = 0;
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, r.ev, r.n, &opt, path, &err), SIDX_OK);
    g = read_graph(path);
    assert_int_equal(agnnodes(g), 5);
    assert_non_null(strstr(node_attr(g, "n0", "label"), "#1"));
    assert_non_null(strstr(node_attr(g, "n3", "label"), "#3"));
    assert_non_null(strstr(node_attr(g, "n3", "label"), "HIT prim 6"));
    assert_string_equal(node_attr(g, "n3", "peripheries"), "2");
    assert_string_equal(node_attr(g, "n1", "fillcolor"), "#d0d0d0");
    assert_string_not_equal(node_attr(g, "n4", "fillcolor"), "#d0d0d0");
    agclose(g);

    /* bad extension, brute has no tree */
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, "/tmp/x.unknown", &err), SIDX_ERR_INVALID_ARG);
    unlink(path);
}

static int load_tiny(sidx_mesh *m)
{
    sidx_error err;
    memset(m, 0, sizeof *m);
    return sidx_scene_open(TINY_SCENE, m, &err) == SIDX_OK ? 0 : -1;
}

/* The first registered structure that emits a tree, or NULL. */
static const char *tree_accel(const sidx_mesh *m)
{
    static const char *const prefer[] = {"bvh", "kdtree", "octree", "bsp"};
    for (size_t i = 0; i < sizeof prefer / sizeof prefer[0]; ++i) {
        if (!sidx_accel_is_registered(prefer[i])) continue;
        char path[128];
        tmp_path(path, sizeof path, "probe.dot");
        sidx_status s = sidx_dot_write(m, prefer[i], NULL, path, NULL);
        unlink(path);
        if (s == SIDX_OK) return prefer[i];
    }
    return NULL;
}

static void dot_real_structure(void **state)
{
    (void)state;
    sidx_mesh m;
    assert_int_equal(load_tiny(&m), 0);
    char path[128];
    tmp_path(path, sizeof path, "dot");
    sidx_error err;

    /* brute force builds no tree: a clear error */
    assert_int_equal(sidx_dot_write(&m, "brute", NULL, path, &err), SIDX_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.message, "brute does not emit a tree"));
    assert_int_equal(sidx_dot_write(&m, "no-such-structure", NULL, path, &err), SIDX_ERR_UNKNOWN_ACCEL);

    const char *name = tree_accel(&m);
    if (!name) {
        print_message("no tree structure registered: skipping the real-structure dot checks\n");
        sidx_mesh_free(&m);
        return;
    }
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.leaf_size = 1;
    sidx_dot_options opt;
    memset(&opt, 0, sizeof opt);
    opt.build = &bo;
    opt.max_depth = SIDX_DOT_ALL_DEPTHS;
    opt.has_ray = 1;
    assert_int_equal(sidx_viz_parse_ray(TINY_RAY, &opt.ray_org, &opt.ray_dir), 0);
    assert_int_equal(sidx_dot_write(&m, name, &opt, path, &err), SIDX_OK);

    sidx_accel *a;
    assert_int_equal(sidx_accel_build(name, &m, &bo, &a, &err), SIDX_OK);
    sidx_accel_stats st;
    sidx_accel_stats_get(a, &st);
    sidx_accel_destroy(a);

    Agraph_t *g = read_graph(path);
    assert_int_equal(agnnodes(g), (int)st.nodes);
    assert_int_equal(agnedges(g), (int)st.nodes - 1);
    /* the root was visited first, and some leaf holds the hit */
    int hit_leaves = 0;
    for (Agnode_t *n = agfstnode(g); n; n = agnxtnode(g, n))
        if (strstr(agget(n, (char *)"label"), "HIT prim 6")) ++hit_leaves;
    assert_int_equal(hit_leaves, 1);
    agclose(g);

    /* laid out and rendered by gvc.  Not under `make valgrind`
     * (SIDX_FAST_TESTS): gvc's plugin configuration and the fontconfig /
     * pango caches its text layout fills are one-time allocations those
     * libraries never free, which memcheck reports as lost. */
    if (getenv("SIDX_FAST_TESTS")) {
        unlink(path);
        sidx_mesh_free(&m);
        return;
    }
    char svg[128];
    tmp_path(svg, sizeof svg, "svg");
    opt.max_depth = 2;
    assert_int_equal(sidx_dot_write(&m, name, &opt, svg, &err), SIDX_OK);
    FILE *f = fopen(svg, "r");
    assert_non_null(f);
    char buf[4096];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    assert_non_null(strstr(buf, "<svg"));
    unlink(svg);
    unlink(path);
    sidx_mesh_free(&m);
}

/* ---- viewer ---------------------------------------------------------------------------------- */

static size_t differing_pixels(SDL_Surface *a, SDL_Surface *b)
{
    size_t diff = 0;
    for (int y = 0; y < a->h; ++y)
        for (int x = 0; x < a->w; ++x) {
            uint32_t pa = ((uint32_t *)((uint8_t *)a->pixels + (size_t)y * (size_t)a->pitch))[x];
            uint32_t pb = ((uint32_t *)((uint8_t *)b->pixels + (size_t)y * (size_t)b->pitch))[x];
            diff += pa != pb;
        }
    return diff;
}

static SDL_Surface *load_png(const char *path)
{
    SDL_Surface *s = IMG_Load(path);
    assert_non_null(s);
    SDL_Surface *c = SDL_ConvertSurfaceFormat(s, SDL_PIXELFORMAT_ARGB8888, 0);
    SDL_FreeSurface(s);
    assert_non_null(c);
    return c;
}

static void view_screenshots_differ_between_steps(void **state)
{
    (void)state;
    const char *accel = sidx_accel_is_registered("bvh") ? "bvh" : "brute";
    view_state v;
    sidx_error err;
    assert_int_equal(view_open(&v, "flat2d", accel, &err), SIDX_OK);
    sidx_vec3 o, d;
    view_default_ray(&v, &o, &d);
    assert_int_equal(view_set_ray(&v, o, d, 1), SIDX_OK);
    assert_true(v.trav.count > 4);
    assert_int_equal(v.step, 1);

    char p1[128], p2[128], msg[256];
    snprintf(p1, sizeof p1, "/tmp/sidx_test_view_%ld_a.png", (long)getpid());
    snprintf(p2, sizeof p2, "/tmp/sidx_test_view_%ld_b.png", (long)getpid());
    assert_int_equal(view_screenshot(&v, p1, 640, 400, msg, sizeof msg), 0);
    v.step = v.trav.count;
    assert_int_equal(view_screenshot(&v, p2, 640, 400, msg, sizeof msg), 0);

    SDL_Surface *a = load_png(p1), *b = load_png(p2);
    assert_int_equal(a->w, 640);
    assert_int_equal(a->h, 400);
    assert_int_equal(b->w, 640);
    assert_int_equal(b->h, 400);
    assert_true(differing_pixels(a, b) > 100);
    SDL_FreeSurface(a);
    SDL_FreeSurface(b);

    /* every mode renders, and the render is deterministic */
    for (int m = 0; m < VIEW_MODE_COUNT; ++m) {
        v.mode = (view_mode)m;
        v.show_help = m == VIEW_3D;
        v.level = 1;
        SDL_Surface *s1 = view_render_surface(&v, 320, 200);
        SDL_Surface *s2 = view_render_surface(&v, 320, 200);
        assert_non_null(s1);
        assert_non_null(s2);
        assert_int_equal(differing_pixels(s1, s2), 0);
        SDL_FreeSurface(s1);
        SDL_FreeSurface(s2);
    }
    /* replay: the stack empties and the best hit is the final one */
    view_replay r;
    view_replay_run(&v, v.trav.count, &r);
    assert_int_equal(r.stack_n, 0);
    unlink(p1);
    unlink(p2);
    view_close(&v);
}

static int key(view_state *v, view_input *in, SDL_Keycode k)
{
    SDL_Event e;
    memset(&e, 0, sizeof e);
    e.type = SDL_KEYDOWN;
    e.key.keysym.sym = k;
    return view_handle_event(v, in, &e);
}

static void mouse(view_state *v, view_input *in, Uint32 type, int x, int y)
{
    SDL_Event e;
    memset(&e, 0, sizeof e);
    e.type = type;
    if (type == SDL_MOUSEMOTION) {
        e.motion.x = x;
        e.motion.y = y;
        e.motion.xrel = 5;
    } else {
        e.button.button = SDL_BUTTON_LEFT;
        e.button.x = x;
        e.button.y = y;
    }
    view_handle_event(v, in, &e);
}

static void view_keys_and_mouse(void **state)
{
    (void)state;
    view_state v;
    sidx_error err;
    assert_int_equal(view_open(&v, "flat2d", sidx_accel_registered_name(0), &err), SIDX_OK);
    view_input in;
    view_input_init(&in, 800, 500);

    /* drag in 2D: a ray from the press point to the release point, stepped from 0 */
    mouse(&v, &in, SDL_MOUSEBUTTONDOWN, 20, 250);
    mouse(&v, &in, SDL_MOUSEMOTION, 200, 240);
    mouse(&v, &in, SDL_MOUSEBUTTONUP, 300, 230);
    assert_int_equal(v.has_ray, 1);
    assert_true(v.dir.x > 0.0f && v.dir.z == 0.0f);
    assert_int_equal(v.step, 0);
    assert_true(v.trav.count > 2);

    assert_int_equal(key(&v, &in, SDLK_RIGHT), VIEW_INPUT_REDRAW);
    assert_int_equal(key(&v, &in, SDLK_RIGHT), VIEW_INPUT_REDRAW);
    assert_int_equal(v.step, 2);
    key(&v, &in, SDLK_LEFT);
    assert_int_equal(v.step, 1);
    key(&v, &in, SDLK_END);
    assert_int_equal(v.step, v.trav.count);
    key(&v, &in, SDLK_RIGHT);
    assert_int_equal(v.step, v.trav.count);
    key(&v, &in, SDLK_HOME);
    assert_int_equal(v.step, 0);
    key(&v, &in, SDLK_SPACE);
    assert_int_equal(v.playing, 1);
    for (size_t i = 0; i <= v.trav.count; ++i) view_tick(&v);
    assert_int_equal(v.step, v.trav.count);
    assert_int_equal(v.playing, 0);

    /* build mode steps the build events */
    key(&v, &in, SDLK_2);
    assert_int_equal(v.mode, VIEW_BUILD);
    key(&v, &in, SDLK_HOME);
    assert_int_equal(v.build_step, 0);
    key(&v, &in, SDLK_RIGHT);
    assert_int_equal(v.build_step, 1);
    assert_int_equal(v.step, v.trav.count);

    /* help opens and any key closes it */
    key(&v, &in, SDLK_h);
    assert_int_equal(v.show_help, 1);
    key(&v, &in, SDLK_RIGHT);
    assert_int_equal(v.show_help, 0);
    assert_int_equal(v.build_step, 1);

    /* 3D: a click without moving picks that pixel's ray */
    key(&v, &in, SDLK_3);
    assert_int_equal(v.mode, VIEW_3D);
    sidx_vec3 old_org = v.org;
    mouse(&v, &in, SDL_MOUSEBUTTONDOWN, 250, 250);
    mouse(&v, &in, SDL_MOUSEBUTTONUP, 250, 250);
    assert_true(v.org.z != old_org.z || v.org.x != old_org.x);
    assert_int_equal(v.step, 0);
    key(&v, &in, SDLK_TAB);
    assert_int_equal(v.mode, VIEW_HEAT);
    assert_int_equal(key(&v, &in, SDLK_q), VIEW_INPUT_QUIT);
    view_close(&v);
}

/* ---- sidx-step -------------------------------------------------------------------------------- */

static char *run_capture(const char *cmd)
{
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    assert_non_null(buf);
    size_t k;
    while ((k = fread(buf + n, 1, cap - n - 1, p)) > 0) {
        n += k;
        if (cap - n < 2) {
            cap *= 2;
            buf = realloc(buf, cap);
            assert_non_null(buf);
        }
    }
    buf[n] = '\0';
    int rc = pclose(p);
    assert_int_equal(rc, 0);
    return buf;
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)size + 1);
    assert_non_null(buf);
    size_t n = fread(buf, 1, (size_t)size, f);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

static void step_matches_expected(void **state)
{
    (void)state;
    static const char *const names[] = {"brute", "bvh", "kdtree"};
    const int update = getenv("SIDX_UPDATE_EXPECTED") != NULL;
    int checked = 0;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        if (!sidx_accel_is_registered(names[i])) continue;
        char cmd[1024], expected_path[256];
        snprintf(cmd, sizeof cmd, "%s/sidx-step --accel %s %s --ray %s --leaf-size 1 --all </dev/null", bin_dir,
                 names[i], TINY_SCENE, TINY_RAY);
        snprintf(expected_path, sizeof expected_path, "tests/data/viz/step_%s.txt", names[i]);
        char *got = run_capture(cmd);
        if (update) {
            FILE *f = fopen(expected_path, "wb");
            assert_non_null(f);
            fputs(got, f);
            fclose(f);
        }
        char *want = read_text(expected_path);
        if (!want) {
            print_message("no %s: skipping %s\n", expected_path, names[i]);
            free(got);
            continue;
        }
        if (strcmp(got, want) != 0)
            print_message("%s differs from\n%s\n(regenerate with SIDX_UPDATE_EXPECTED=1 if intended)\n", expected_path,
                          got);
        assert_string_equal(got, want);
        ++checked;
        free(got);
        free(want);
    }
    assert_true(checked >= 1);

    /* --json: one object per line, first ray_begin, last ray_end */
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel brute %s --ray %s --json </dev/null", bin_dir, TINY_SCENE,
             TINY_RAY);
    char *json = run_capture(cmd);
    assert_true(json[0] == '{');
    assert_non_null(strstr(json, "ray_begin"));
    assert_non_null(strstr(json, "ray_end"));
    for (char *p = strchr(json, '\n'); p && p[1]; p = strchr(p + 1, '\n')) assert_true(p[1] == '{');
    free(json);

    /* usage errors exit 2, --help exits 0 */
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel brute %s >/dev/null 2>&1", bin_dir, TINY_SCENE);
    int rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
    snprintf(cmd, sizeof cmd, "%s/sidx-step --help >/dev/null", bin_dir);
    rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 0);
    snprintf(cmd, sizeof cmd, "%s/sidx-dot --accel brute %s -o /tmp/sidx_never.dot 2>/dev/null", bin_dir, TINY_SCENE);
    rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
}

int main(int argc, char **argv)
{
    (void)argc;
    /* build/tests/test_viz -> build/bin (also build/san/...) */
    if (argv[0] && strchr(argv[0], '/')) {
        snprintf(bin_dir, sizeof bin_dir, "%s", argv[0]);
        char *slash = strrchr(bin_dir, '/');
        *slash = '\0';
        slash = strrchr(bin_dir, '/');
        if (slash)
            snprintf(slash + 1, sizeof bin_dir - (size_t)(slash + 1 - bin_dir), "bin");
        else
            snprintf(bin_dir, sizeof bin_dir, "bin");
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(tree_from_synthetic_events),
        cmocka_unit_test(tree_errors),
        cmocka_unit_test(dot_synthetic_parses_back),
        cmocka_unit_test(dot_real_structure),
        cmocka_unit_test(view_screenshots_differ_between_steps),
        cmocka_unit_test(view_keys_and_mouse),
        cmocka_unit_test(step_matches_expected),
    };
    return cmocka_run_group_tests_name("viz", tests, NULL, NULL);
}
