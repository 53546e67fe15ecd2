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
#include <signal.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"
#include "common/testkit.h"
#if SIDX_HAVE_GRAPHVIZ
#include <graphviz/cgraph.h>
#endif
#if SIDX_HAVE_SDL
#include <SDL.h>
#include <SDL_image.h>
#include "../viz/view.h"
#endif

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

/* The leaves' primitive lists (node 1: prim 0; node 3: prims 5, 6; node 4: prim 2). */
static const uint32_t fake_prims[5][2] = {{0, 0}, {0, 0}, {0, 0}, {5, 6}, {2, 0}};

static void leaf(evbuf *b, uint32_t id, uint32_t count)
{
    sidx_event *e = add(b, SIDX_EV_BUILD_LEAF);
    e->node = id;
    e->count = count;
    e->reason = SIDX_LEAF_FEW_PRIMS;
    e->prims = fake_prims[id];
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
    /* the leaves keep their lists, copied: the events may go away */
    const sidx_viz_node *l3 = &t.nodes[sidx_viz_tree_find(&t, 3)];
    assert_int_equal(l3->leaf_count, 2);
    assert_non_null(l3->prims);
    assert_true(l3->prims != fake_prims[3]);
    assert_int_equal(l3->prims[0], 5);
    assert_int_equal(l3->prims[1], 6);
    assert_int_equal(t.num_prim_ids, 4);
    assert_null(t.nodes[t.root].prims);

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

#if SIDX_HAVE_GRAPHVIZ
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
    assert_non_null(strstr(node_attr(g, "n3", "label"), "prims: 5 6"));
    assert_non_null(strstr(node_attr(g, "n1", "label"), "prims: 0"));
    assert_null(strstr(node_attr(g, "n0", "label"), "prims:")); /* inner nodes list none */
    agclose(g);

    /* a big leaf is cut after a few ids, with the rest counted */
    {
        static uint32_t many[20];
        for (uint32_t i = 0; i < 20; ++i) many[i] = 100 + i;
        evbuf big;
        big.n = 0;
        node(&big, 0, UINT32_MAX, 0, 20, box(0, 0, 1, 1));
        sidx_event *e = add(&big, SIDX_EV_BUILD_LEAF);
        e->node = 0;
        e->count = 20;
        e->prims = many;
        assert_int_equal(sidx_dot_write_events(big.ev, big.n, NULL, 0, &opt, path, &err), SIDX_OK);
        g = read_graph(path);
        const char *lb = node_attr(g, "n0", "label");
        assert_non_null(strstr(lb, "prims: 100 101 102 103"));
        assert_non_null(strstr(lb, "107 +12 more"));
        assert_null(strstr(lb, "108"));
        agclose(g);
    }

    /* --depth 2 draws two levels: root, its two children and one summary under 2 */
    opt.max_depth = 2;
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, path, &err), SIDX_OK);
    g = read_graph(path);
    assert_int_equal(agnnodes(g), 4);
    assert_int_equal(agnedges(g), 3);
    assert_non_null(strstr(node_attr(g, "cut2", "label"), "+2 nodes, 3 prims"));
    assert_non_null(strstr(agget(g, "label"), "2 levels drawn"));
    agclose(g);
    /* --depth 1: the root alone, its subtree summarised */
    opt.max_depth = 1;
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, path, &err), SIDX_OK);
    g = read_graph(path);
    assert_int_equal(agnnodes(g), 2);
    assert_int_equal(agnedges(g), 1);
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

    /* a space partition's walk: the hit is found in leaf 3 (the triangle reaches past its
     * cell), the walk goes on into leaf 4, skips the triangle there (mailbox) and stops in
     * that cell: leaf 4 is outlined, where the walk ends, and leaf 3 is not */
    {
        evbuf k = r;
        k.n--; /* drop RAY_END: the walk into leaf 4 goes on */
        sidx_event *e = add(&k, SIDX_EV_MAILBOX_HIT);
        e->prim = 6;
        e = add(&k, SIDX_EV_TERMINATE);
        e->reason = SIDX_TERM_HIT_IN_CELL;
        e->t = 0.75f;
        e = add(&k, SIDX_EV_RAY_END);
        e->prim = 6;
        e->t = 0.75f;
        assert_int_equal(sidx_dot_write_events(b.ev, b.n, k.ev, k.n, &opt, path, &err), SIDX_OK);
        g = read_graph(path);
        assert_non_null(strstr(node_attr(g, "n4", "label"), "HIT prim 6"));
        assert_string_equal(node_attr(g, "n4", "peripheries"), "2");
        assert_null(strstr(node_attr(g, "n3", "label"), "HIT"));
        assert_string_not_equal(node_attr(g, "n3", "peripheries"), "2");
        agclose(g);
    }

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

/* The width attribute of a rendered SVG, in points. */
static double svg_width_pt(const char *path)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char buf[4096];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    const char *w = strstr(buf, "<svg width=\"");
    assert_non_null(w);
    return strtod(w + strlen("<svg width=\""), NULL);
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
    opt.max_width = SIDX_DOT_UNLIMITED; /* every node, as the structure counts them */
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
    assert_true(svg_width_pt(svg) > 0.0);
    unlink(svg);
    unlink(path);
    sidx_mesh_free(&m);
}

/* Labels say what each structure decided: a BSP plane is scored by balance and cuts, not the
 * SAH; an octree cuts at the centre (no NaN plane); a BSP region with no piece of its own but a
 * ray list is not "N prims (empty)"; a value computed as 0 prints as 0, not -2.384e-07. */
static void dot_labels_say_the_structure(void **state)
{
    (void)state;
    static const char *const cases[][2] = {{"bsp", "flat2d"}, {"bsp", "teapot"}, {"octree", "teapot"}, {"bvh", "teapot"}};
    for (size_t ci = 0; ci < sizeof cases / sizeof cases[0]; ++ci) {
        if (!sidx_accel_is_registered(cases[ci][0])) continue;
        sidx_mesh m;
        sidx_error err;
        assert_int_equal(sidx_scene_open(cases[ci][1], &m, &err), SIDX_OK);
        char path[128];
        tmp_path(path, sizeof path, "labels.dot");
        sidx_dot_options opt;
        memset(&opt, 0, sizeof opt);
        opt.max_depth = SIDX_DOT_ALL_DEPTHS;
        assert_int_equal(sidx_dot_write(&m, cases[ci][0], &opt, path, &err), SIDX_OK);
        Agraph_t *g = read_graph(path);
        int planes = 0;
        for (Agnode_t *n = agfstnode(g); n; n = agnxtnode(g, n)) {
            const char *l = agget(n, (char *)"label");
            assert_non_null(l);
            if (!strcmp(cases[ci][0], "bsp")) {
                assert_null(strstr(l, "SAH"));
                if (strstr(l, "plane (")) ++planes;
            }
            assert_null(strstr(l, "nan"));
            assert_null(strstr(l, "e-07"));
            assert_null(strstr(l, "e-08"));
            const char *e = strstr(l, " prims (empty)");
            if (e) assert_true(e >= l + 2 && e[-1] == '0' && (e - 1 == l || e[-2] == 'n'));
        }
        if (!strcmp(cases[ci][0], "bsp")) assert_true(planes > 0);
        agclose(g);
        unlink(path);
        sidx_mesh_free(&m);
    }
}

/* Wide trees fit a page by default: grid2 on the teapot (185 top-level cells) and the octree
 * (eight children a node) fold the siblings past the page's width. */
static void dot_wide_trees_fit_a_page(void **state)
{
    (void)state;
    if (getenv("SIDX_FAST_TESTS")) {
        print_message("gvc layout not run under SIDX_FAST_TESTS: skipped\n");
        return;
    }
#if defined(__SANITIZE_ADDRESS__)
    /* Laying out these labels, Graphviz's pango plugin reads past a buffer
     * that harfbuzz allocated (strcmp in libgvplugin_pango on a shape-plan
     * cache entry): a fault inside those libraries, which AddressSanitizer
     * stops at.  The check runs in every build without it. */
    print_message("not run under AddressSanitizer (Graphviz's text layout reads past a harfbuzz buffer): skipped\n");
    return;
#endif
    static const char *const names[] = {"grid2", "octree"};
    sidx_mesh m;
    sidx_error err;
    assert_int_equal(sidx_scene_open("teapot", &m, &err), SIDX_OK);
    for (size_t i = 0; i < 2; ++i) {
        if (!sidx_accel_is_registered(names[i])) continue;
        char svg[128];
        tmp_path(svg, sizeof svg, "svg");
        assert_int_equal(sidx_dot_write(&m, names[i], NULL, svg, &err), SIDX_OK);
        const double w = svg_width_pt(svg);
        print_message("%s on teapot: svg width %.0f pt\n", names[i], w);
        assert_true(w > 0.0 && w < 2500.0); /* 20,000-1,000,000 pt drawn level by level, unfolded */
        unlink(svg);
    }
    sidx_mesh_free(&m);
}

/* A wide level folds: a root over 20 grid cells, every fourth empty, drawn at most 6 boxes
 * across.  The cells the ray visited are drawn first (an empty one too), then the fullest;
 * the rest fold into one "… N more cells (M empty)" box, and the caption says so. */
static void wide_cells(evbuf *b)
{
    b->n = 0;
    node(b, 0, UINT32_MAX, 0, 150, box(0, 0, 20, 1));
    for (uint32_t k = 1; k <= 20; ++k) {
        node(b, k, 0, 1, k % 4 ? k : 0, box((float)k - 1, 0, (float)k, 1));
        b->ev[b->n - 1].cell[0] = (int32_t)k - 1;
        b->ev[b->n - 1].cell[1] = b->ev[b->n - 1].cell[2] = 0;
        sidx_event *e = add(b, SIDX_EV_BUILD_LEAF);
        e->node = k;
        e->count = k % 4 ? k : 0;
        e->reason = k % 4 ? SIDX_LEAF_FEW_PRIMS : SIDX_LEAF_EMPTY;
    }
}

static void dot_folds_wide_levels(void **state)
{
    (void)state;
    evbuf b, r;
    wide_cells(&b);
    r.n = 0;
    add(&r, SIDX_EV_RAY_BEGIN);
    add(&r, SIDX_EV_NODE_ENTER)->node = 0;
    add(&r, SIDX_EV_NODE_ENTER)->node = 17;
    add(&r, SIDX_EV_NODE_ENTER)->node = 20; /* an empty cell */
    add(&r, SIDX_EV_RAY_END);
    char path[128];
    tmp_path(path, sizeof path, "fold.dot");
    sidx_error err;
    sidx_dot_options opt;
    memset(&opt, 0, sizeof opt);
    opt.max_width = 6;

    /* with the ray: its two cells, then the fullest (19); 17 folded, 4 of them empty
     * (4, 8, 12, 16), holding 150 - 17 - 19 = 114 prims */
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, r.ev, r.n, &opt, path, &err), SIDX_OK);
    Agraph_t *g = read_graph(path);
    assert_int_equal(agnnodes(g), 5); /* root, 3 cells, the fold */
    assert_non_null(agnode(g, (char *)"n17", 0));
    assert_non_null(agnode(g, (char *)"n20", 0));
    assert_non_null(agnode(g, (char *)"n19", 0));
    assert_null(agnode(g, (char *)"n18", 0));
    const char *fold = node_attr(g, "fold0", "label");
    assert_non_null(strstr(fold, "\xe2\x80\xa6 17 more cells (4 empty)"));
    assert_non_null(strstr(fold, "17 nodes, 114 prims in all"));
    assert_null(strstr(fold, "ray visited"));
    const char *caption = agget(g, (char *)"label");
    assert_non_null(caption);
    assert_non_null(strstr(caption, "folded to fit a page (about 6 boxes across"));
    assert_non_null(strstr(caption, "17 siblings in 1 \xe2\x80\xa6 boxes"));
    agclose(g);

    /* without it: the three fullest, 19 18 17; five empty cells folded */
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, path, &err), SIDX_OK);
    g = read_graph(path);
    assert_non_null(agnode(g, (char *)"n18", 0));
    assert_null(agnode(g, (char *)"n20", 0));
    assert_non_null(strstr(node_attr(g, "fold0", "label"), "17 more cells (5 empty)"));
    agclose(g);

    /* no limit: all 21 nodes, no fold, no caption */
    opt.max_width = SIDX_DOT_UNLIMITED;
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, path, &err), SIDX_OK);
    g = read_graph(path);
    assert_int_equal(agnnodes(g), 21);
    assert_null(agnode(g, (char *)"fold0", 0));
    assert_null(strstr(agget(g, (char *)"label"), "folded"));
    agclose(g);

    /* a limit on all boxes folds too */
    opt.max_width = 0;
    opt.max_nodes = 4;
    assert_int_equal(sidx_dot_write_events(b.ev, b.n, NULL, 0, &opt, path, &err), SIDX_OK);
    g = read_graph(path);
    assert_true(agnnodes(g) <= 4);
    assert_non_null(agnode(g, (char *)"fold0", 0));
    agclose(g);
    unlink(path);
}

/* A hang detector, not a benchmark: every structure on every built-in scene, drawn to the
 * bottom (--depth 1000), is laid out by Graphviz within a generous 20 s, at most about 3,000 pt
 * wide; a drawing that leaves nodes out says so in its caption. */
static const char *dot_hang_case = "";
static void dot_hang_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "\nsidx_dot_write did not finish within 20 s: ";
    if (write(STDERR_FILENO, msg, sizeof msg - 1) < 0 || write(STDERR_FILENO, dot_hang_case, strlen(dot_hang_case)) < 0 ||
        write(STDERR_FILENO, "\n", 1) < 0)
        _exit(1);
    _exit(1);
}

static void dot_every_structure_and_scene_finishes(void **state)
{
    (void)state;
    if (getenv("SIDX_FAST_TESTS")) {
        print_message("gvc layout not run under SIDX_FAST_TESTS: skipped\n");
        return;
    }
#if defined(__SANITIZE_ADDRESS__)
    print_message("not run under AddressSanitizer (Graphviz's text layout reads past a harfbuzz buffer): skipped\n");
    return;
#endif
    char svg[128], name[160];
    tmp_path(svg, sizeof svg, "all.svg");
    signal(SIGALRM, dot_hang_alarm);
    unsigned drawn = 0, folded = 0, cells_folded = 0;
    for (const char *const *sc = sidx_scene_names(); *sc; ++sc) {
        sidx_mesh m;
        sidx_error err;
        assert_int_equal(sidx_scene_open(*sc, &m, &err), SIDX_OK);
        for (size_t i = 0; i < sidx_accel_registered_count(); ++i) {
            const char *accel = sidx_accel_registered_name(i);
            snprintf(name, sizeof name, "%s on %s", accel, *sc);
            dot_hang_case = name;
            sidx_dot_options opt;
            memset(&opt, 0, sizeof opt);
            opt.max_depth = 1000;
            opt.scene = *sc;
            alarm(20);
            const sidx_status st = sidx_dot_write(&m, accel, &opt, svg, &err);
            alarm(0);
            if (st == SIDX_ERR_UNSUPPORTED) continue; /* no tree: brute, grid, ... */
            if (st != SIDX_OK) print_message("%s: %s\n", name, err.message);
            assert_int_equal(st, SIDX_OK);
            ++drawn;
            FILE *f = fopen(svg, "r");
            assert_non_null(f);
            static char text[1 << 20];
            const size_t n = fread(text, 1, sizeof text - 1, f);
            text[n] = '\0';
            fclose(f);
                    /* the title: "<structure>: <N> nodes, ..."; the boxes: class="node" */
            const char *title = strstr(text, " nodes, ");
            assert_non_null(title);
            while (title > text && title[-1] >= '0' && title[-1] <= '9') --title;
            const unsigned long nodes = strtoul(title, NULL, 10);
            unsigned long boxes = 0;
            for (const char *p = text; (p = strstr(p, "class=\"node\"")) != NULL; ++p) ++boxes;
            const double width = svg_width_pt(svg);
            if (width >= 3000.0) print_message("%s: %.0f pt wide\n", name, width);
            assert_true(width < 3000.0);
            if (boxes < nodes) {
                if (!strstr(text, "folded to fit a page")) print_message("%s: %lu of %lu nodes drawn, no caption\n",
                                                                          name, boxes, nodes);
                assert_non_null(strstr(text, "folded to fit a page"));
                ++folded;
            }
            cells_folded += strstr(text, " more cells (") != NULL;
        }
        sidx_mesh_free(&m);
    }
    signal(SIGALRM, SIG_DFL);
    print_message("%u drawings, %u folded (%u with a \"more cells\" box)\n", drawn, folded, cells_folded);
    assert_true(folded > 0 && cells_folded > 0);
    unlink(svg);
}

#else
/* Built without Graphviz (HAVE_GRAPHVIZ=0, or libgraphviz-dev missing): sidx_dot_write
 * answers SIDX_ERR_UNSUPPORTED (test_args checks it) and these are skipped. */
static void skip_without_graphviz(void) { print_message("built without Graphviz: no drawings, skipped\n"); skip(); }
static void dot_synthetic_parses_back(void **state) { (void)state; skip_without_graphviz(); }
static void dot_folds_wide_levels(void **state) { (void)state; skip_without_graphviz(); }
static void dot_every_structure_and_scene_finishes(void **state) { (void)state; skip_without_graphviz(); }
static void dot_real_structure(void **state) { (void)state; skip_without_graphviz(); }
#endif /* SIDX_HAVE_GRAPHVIZ */

/* ---- leaf primitive lists from real builds --------------------------------------------------- */

/* Object partitioning puts every triangle in exactly one leaf; space
 * partitioning in at least one (straddlers are referenced from every cell
 * they overlap). */
/* The binary BVHs; bvh-sbvh is the tree with spatial splits
 * (bvh_spatial.c) that bvh4 and bvh8 collapse, where a triangle may be in
 * several leaves. */
static int is_object_partitioning(const char *name)
{
    return strncmp(name, "bvh", 3) == 0 && strcmp(name, "bvh4") != 0 && strcmp(name, "bvh8") != 0 &&
           strcmp(name, "bvh-sbvh") != 0;
}

/* Every leaf of every tree structure lists its primitives, and the lists are
 * the ones traversal uses: each primitive tested right after entering a
 * leaf is in that leaf's list. */
static void leaf_prims_from_real_builds(void **state)
{
    (void)state;
    static const char *const names[] = {"bvh",      "bvh-sweep", "bvh-median",    "bvh-middle", "bvh-obb",
                                        "bvh-sbvh", "bvh4",      "bvh8",          "kdtree",     "kdtree-binned",
                                        "octree",   "quadtree",  "bsp",           "grid2",      "rayclass"};
    static const char *const scenes[] = {"flat2d", "icosphere"};
    int structures = 0, subset_checks = 0;
    for (size_t si = 0; si < sizeof scenes / sizeof scenes[0]; ++si) {
        sidx_mesh m;
        sidx_error err;
        assert_int_equal(sidx_scene_open(scenes[si], &m, &err), SIDX_OK);
        const uint32_t nt = m.num_triangles;
        uint32_t *seen = calloc(nt, sizeof *seen);
        assert_non_null(seen);
        for (size_t k = 0; k < sizeof names / sizeof names[0]; ++k) {
            if (!sidx_accel_is_registered(names[k])) continue;
            sidx_recorder rec, trav;
            sidx_recorder_init(&rec);
            sidx_recorder_init(&trav);
            sidx_hook h = sidx_recorder_hook(&rec);
            h.mask = SIDX_EVMASK_BUILD;
            sidx_build_options bo;
            memset(&bo, 0, sizeof bo);
            bo.hook = &h;
            sidx_accel *a = NULL;
            if (sidx_accel_build(names[k], &m, &bo, &a, &err) != SIDX_OK) fail_msg("%s: %s", names[k], err.message);
            assert_int_equal(rec.overflow, 0);
            memset(seen, 0, nt * sizeof *seen);
            size_t leaves = 0;
            for (size_t i = 0; i < rec.count; ++i) {
                const sidx_event *e = &rec.events[i];
                if (e->type != SIDX_EV_BUILD_LEAF || e->count == 0) continue;
                ++leaves;
                if (!e->prims) fail_msg("%s on %s: leaf %u lists no primitives", names[k], scenes[si], e->node);
                for (uint32_t j = 0; j < e->count; ++j) {
                    assert_true(e->prims[j] < nt);
                    for (uint32_t q = 0; q < j; ++q) /* no triangle twice in one leaf */
                        if (e->prims[q] == e->prims[j])
                            fail_msg("%s: prim %u twice in leaf %u", names[k], e->prims[j], e->node);
                    seen[e->prims[j]]++;
                }
            }
            assert_true(leaves > 0);
            for (uint32_t i = 0; i < nt; ++i) {
                if (is_object_partitioning(names[k]) && seen[i] != 1)
                    fail_msg("%s on %s: triangle %u is in %u leaves, not 1", names[k], scenes[si], i, seen[i]);
                if (!is_object_partitioning(names[k]) && seen[i] == 0)
                    fail_msg("%s on %s: triangle %u is in no leaf", names[k], scenes[si], i);
            }

            /* rays through the scene: prim tests inside a leaf use its list */
            const int checks_before = subset_checks;
            sidx_aabb b = sidx_mesh_bounds(&m);
            sidx_vec3 c = sidx_aabb_centroid(b), e3 = sidx_aabb_extent(b);
            for (int r = 0; r < 16; ++r) {
                const float a0 = 0.4f * (float)r;
                sidx_vec3 dir = sidx_v3(cosf(a0), sinf(a0), scenes[si][0] == 'f' ? 0.0f : 0.3f * cosf(1.7f * a0));
                float reach = e3.x + e3.y + e3.z + 1.0f;
                sidx_vec3 org = sidx_v3(c.x - reach * dir.x + 0.05f * e3.x * sinf(3.0f * a0),
                                        c.y - reach * dir.y + 0.05f * e3.y * cosf(2.0f * a0), c.z - reach * dir.z);
                sidx_ray ray;
                assert_int_equal(sidx_ray_init(&ray, org, dir, 0.0f, INFINITY), SIDX_OK);
                sidx_recorder_clear(&trav);
                sidx_hook th = sidx_recorder_hook(&trav);
                th.mask = SIDX_EVMASK_TRAVERSAL;
                sidx_query q;
                memset(&q, 0, sizeof q);
                q.hook = &th;
                sidx_hit hit;
                sidx_accel_intersect(a, &ray, &q, &hit);
                const sidx_event *leaf = NULL;
                for (size_t i = 0; i < trav.count; ++i) {
                    const sidx_event *e = &trav.events[i];
                    if (e->type == SIDX_EV_NODE_ENTER) {
                        leaf = NULL;
                        for (size_t j = 0; j < rec.count; ++j)
                            if (rec.events[j].type == SIDX_EV_BUILD_LEAF && rec.events[j].node == e->node) {
                                leaf = &rec.events[j];
                                break;
                            }
                    } else if (e->type == SIDX_EV_PRIM_TEST && leaf) {
                        int found = 0;
                        for (uint32_t j = 0; j < leaf->count && !found; ++j) found = leaf->prims[j] == e->prim;
                        if (!found)
                            fail_msg("%s: prim %u tested in leaf %u, which does not list it", names[k], e->prim,
                                     leaf->node);
                        ++subset_checks;
                    }
                }
            }
            if (subset_checks == checks_before)
                fail_msg("%s on %s: no ray tested a primitive inside a listed leaf", names[k], scenes[si]);
            ++structures;
            sidx_accel_destroy(a);
            sidx_recorder_free(&rec);
            sidx_recorder_free(&trav);
        }
        free(seen);
        sidx_mesh_free(&m);
    }
    if (structures == 0) {
        print_message("no tree structure registered: nothing to check\n");
        return;
    }
    assert_true(subset_checks > 0);
}

#if SIDX_HAVE_GRAPHVIZ
/* The Graphviz labels of a real BVH name each leaf's primitives, and
 * together they name every triangle exactly once. */
static void dot_real_leaf_labels(void **state)
{
    (void)state;
    if (!sidx_accel_is_registered("bvh")) {
        print_message("bvh not registered: skipped\n");
        return;
    }
    sidx_mesh m;
    assert_int_equal(load_tiny(&m), 0);
    char path[128];
    tmp_path(path, sizeof path, "leaves.dot");
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.leaf_size = 2; /* small leaves: every label lists all its ids */
    sidx_dot_options opt;
    memset(&opt, 0, sizeof opt);
    opt.build = &bo;
    opt.max_depth = SIDX_DOT_ALL_DEPTHS;
    sidx_error err;
    assert_int_equal(sidx_dot_write(&m, "bvh", &opt, path, &err), SIDX_OK);
    Agraph_t *g = read_graph(path);
    uint32_t *seen = calloc(m.num_triangles, sizeof *seen);
    assert_non_null(seen);
    int leaves = 0;
    for (Agnode_t *n = agfstnode(g); n; n = agnxtnode(g, n)) {
        const char *lb = agget(n, (char *)"label");
        const char *p = strstr(lb, "prims:");
        if (strncmp(lb, "leaf", 4) != 0) {
            assert_null(p);
            continue;
        }
        assert_non_null(p);
        ++leaves;
        unsigned listed = 0, count = 0;
        assert_int_equal(sscanf(strstr(lb, "\\n") + 2, "%u prims", &count), 1);
        for (p += 6; *p == ' ' || (*p >= '0' && *p <= '9') || (p[0] == '\\' && p[1] == 'n');) {
            if (*p == '\\') { p += 2; continue; }
            if (*p == ' ') { ++p; continue; }
            char *end;
            unsigned long id = strtoul(p, &end, 10);
            assert_true(id < m.num_triangles);
            seen[id]++;
            ++listed;
            p = end;
        }
        assert_int_equal(listed, count);
    }
    assert_true(leaves > 1);
    for (uint32_t i = 0; i < m.num_triangles; ++i) assert_int_equal(seen[i], 1);
    free(seen);
    agclose(g);
    unlink(path);
    sidx_mesh_free(&m);
}

#else
static void dot_real_leaf_labels(void **state) { (void)state; skip_without_graphviz(); }
static void dot_labels_say_the_structure(void **state) { (void)state; skip_without_graphviz(); }
static void dot_wide_trees_fit_a_page(void **state) { (void)state; skip_without_graphviz(); }
#endif /* SIDX_HAVE_GRAPHVIZ */

#if SIDX_HAVE_SDL
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

/* The heat map reads at a glance: steps per pixel span decades (the teapot in the stadium:
 * ~10 on the stadium's floor, thousands in the grid cell that holds the teapot), so the
 * colours follow a log scale.  On a linear one the floor is black; here most pixels under the
 * horizon must show colour (at least a third of the scene's area, its top being sky). */
static void view_heat_map_log_scale(void **state)
{
    (void)state;
    if (!sidx_accel_is_registered("grid")) return;
    view_state v;
    sidx_error err;
    assert_int_equal(view_open(&v, "stadium", "grid", &err), SIDX_OK);
    v.mode = VIEW_HEAT;
    v.zoom = 3.0f;
    const int w = 550, h = 350, sw = view_scene_width(w);
    SDL_Surface *s = view_render_surface(&v, w, h);
    assert_non_null(s);
    size_t coloured = 0, dark = 0;
    for (int y = 20; y < h - 50; ++y) /* below the title, above the legend */
        for (int x = 0; x < sw; ++x) {
            const uint32_t p = ((uint32_t *)((uint8_t *)s->pixels + (size_t)y * (size_t)s->pitch))[x];
            const int r = (int)((p >> 16) & 255), g = (int)((p >> 8) & 255), b = (int)(p & 255);
            if (r + g + b > 120) ++coloured; else ++dark;
        }
    print_message("heat map of grid on stadium: %zu of %zu pixels coloured, max %u steps\n", coloured,
                  coloured + dark, v.heat_max);
    assert_true(v.heat_max > 1000); /* the teapot's cell */
    assert_true(coloured * 3 > coloured + dark);
    SDL_FreeSurface(s);
    view_close(&v);
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

/* ---- the viewer over a real recording ----------------------------------------------------------- */

/* What the first `step` recorded traversal events say, worked out here
 * independently of view_replay_run: the last node entered and the stack
 * after the pushes and pops so far (a pop takes the top entry). */
typedef struct replay_expect {
    uint32_t current_id;
    size_t enters;
    uint32_t node[256];
    float t_near[256], t_far[256];
    int n;
} replay_expect;

static void expect_after(const sidx_recorder *trav, size_t step, replay_expect *x)
{
    memset(x, 0, sizeof *x);
    x->current_id = SIDX_VIZ_NONE;
    for (size_t i = 0; i < step; ++i) {
        const sidx_event *e = &trav->events[i];
        if (e->type == SIDX_EV_NODE_ENTER) {
            x->current_id = e->node;
            x->enters++;
        } else if (e->type == SIDX_EV_STACK_PUSH) {
            assert_true(x->n < 256);
            x->node[x->n] = e->node;
            x->t_near[x->n] = e->t_near;
            x->t_far[x->n] = e->t_far;
            x->n++;
        } else if (e->type == SIDX_EV_STACK_POP) {
            assert_true(x->n > 0);
            if (x->node[x->n - 1] != e->node)
                fail_msg("event %zu pops node %u but %u is on top", i, e->node, x->node[x->n - 1]);
            x->n--;
        }
    }
}

static void check_step(const view_state *v, const char *accel)
{
    replay_expect x;
    expect_after(&v->trav, v->step, &x);
    view_replay r;
    view_replay_run(v, v->step, &r);
    if (r.current_id != x.current_id)
        fail_msg("%s step %zu: highlighted node %u, the recording says %u", accel, v->step, r.current_id,
                 x.current_id);
    assert_int_equal(r.nodes_entered, x.enters);
    /* the highlighted node is the tree's node of that id, marked as entered */
    if (x.current_id != SIDX_VIZ_NONE && v->has_tree) {
        uint32_t ti = sidx_viz_tree_find(&v->tree, x.current_id);
        assert_int_equal(r.current, ti);
        if (ti != SIDX_VIZ_NONE) assert_int_equal(v->node_mark[ti], 1);
    }
    assert_int_equal(r.stack_more, 0);
    if (r.stack_n != x.n) fail_msg("%s step %zu: stack of %d shown, %d recorded", accel, v->step, r.stack_n, x.n);
    for (int k = 0; k < x.n; ++k) {
        assert_int_equal(r.stack[k].node, x.node[k]);
        assert_true(r.stack[k].t_near == x.t_near[k] || (isnan(r.stack[k].t_near) && isnan(x.t_near[k])));
        assert_true(r.stack[k].t_far == x.t_far[k] || (isnan(r.stack[k].t_far) && isnan(x.t_far[k])));
    }
}

/* One key press through SDL's own event queue (dummy video driver) when it
 * is available, else handed straight to the viewer. */
static int press(view_state *v, view_input *in, SDL_Keycode k, int sdl_ok)
{
    SDL_Event e;
    memset(&e, 0, sizeof e);
    e.type = SDL_KEYDOWN;
    e.key.keysym.sym = k;
    if (!sdl_ok) return view_handle_event(v, in, &e);
    assert_int_equal(SDL_PushEvent(&e), 1);
    int flags = 0, got = 0;
    SDL_Event out;
    while (SDL_PollEvent(&out))
        if (out.type == SDL_KEYDOWN) {
            flags |= view_handle_event(v, in, &out);
            ++got;
        }
    assert_int_equal(got, 1);
    return flags;
}

static int png_pixels_differ(const char *a_path, const char *b_path, size_t *diff)
{
    SDL_Surface *a = load_png(a_path), *b = load_png(b_path);
    assert_int_equal(a->w, b->w);
    assert_int_equal(a->h, b->h);
    *diff = differing_pixels(a, b);
    SDL_FreeSurface(a);
    SDL_FreeSurface(b);
    return *diff > 0;
}

/* The viewer fed a real build and a real traced ray (not synthetic events):
 * stepping forward and back moves the highlight through the recorded
 * NODE_ENTER sequence, the stack list follows the pushes and pops, and
 * sidx-view --screenshot draws two different pictures for two steps. */
static void view_steps_real_recording(void **state)
{
    (void)state;
    const int sdl_ok = setenv("SDL_VIDEODRIVER", "dummy", 1) == 0 && SDL_Init(SDL_INIT_VIDEO) == 0;
    if (!sdl_ok) print_message("SDL dummy video unavailable (%s): keys go straight to the viewer\n", SDL_GetError());
    static const char *const names[] = {"bvh", "kdtree"};
    int checked = 0;
    for (size_t k = 0; k < sizeof names / sizeof names[0]; ++k) {
        if (!sidx_accel_is_registered(names[k])) continue;
        view_state v;
        sidx_error err;
        assert_int_equal(view_open(&v, "flat2d", names[k], &err), SIDX_OK);
        assert_int_equal(v.has_tree, 1);
        sidx_vec3 o, d;
        view_default_ray(&v, &o, &d);
        assert_int_equal(view_set_ray(&v, o, d, 0), SIDX_OK);
        /* the recorded sequence of entered nodes, and that the ray does use the stack */
        uint32_t enters[512];
        size_t ne = 0, pushes = 0, pops = 0;
        for (size_t i = 0; i < v.trav.count; ++i) {
            if (v.trav.events[i].type == SIDX_EV_NODE_ENTER && ne < 512) enters[ne++] = v.trav.events[i].node;
            pushes += v.trav.events[i].type == SIDX_EV_STACK_PUSH;
            pops += v.trav.events[i].type == SIDX_EV_STACK_POP;
        }
        if (ne < 3 || pushes == 0 || pops == 0)
            fail_msg("%s: the default flat2d ray enters %zu nodes, pushes %zu, pops %zu: too little to step through",
                     names[k], ne, pushes, pops);

        view_input in;
        view_input_init(&in, 800, 500);
        /* forward, one event per key: the highlight walks the NODE_ENTER list in order */
        size_t next_enter = 0;
        int max_stack = 0;
        check_step(&v, names[k]);
        while (v.step < v.trav.count) {
            const size_t before = v.step;
            assert_int_equal(press(&v, &in, SDLK_RIGHT, sdl_ok), VIEW_INPUT_REDRAW);
            assert_int_equal(v.step, before + 1);
            check_step(&v, names[k]);
            const sidx_event *e = &v.trav.events[v.step - 1];
            if (e->type == SIDX_EV_NODE_ENTER) {
                view_replay r;
                view_replay_run(&v, v.step, &r);
                assert_true(next_enter < ne);
                assert_int_equal(r.current_id, enters[next_enter]);
                ++next_enter;
                if (r.stack_n > max_stack) max_stack = r.stack_n;
            }
        }
        assert_int_equal(next_enter, ne);
        assert_true(max_stack > 0);
        /* back to the start, one key at a time: the same states in reverse */
        while (v.step > 0) {
            const size_t before = v.step;
            press(&v, &in, SDLK_LEFT, sdl_ok);
            assert_int_equal(v.step, before - 1);
            check_step(&v, names[k]);
        }
        press(&v, &in, SDLK_END, sdl_ok);
        assert_int_equal(v.step, v.trav.count);
        check_step(&v, names[k]);

        /* sidx-view --screenshot at the second and the last node entered */
        size_t step_a = 0, step_b = 0, seen = 0;
        for (size_t i = 0; i < v.trav.count; ++i)
            if (v.trav.events[i].type == SIDX_EV_NODE_ENTER) {
                if (++seen == 2) step_a = i + 1;
                step_b = i + 1;
            }
        assert_true(step_a > 0 && step_b > step_a);
        char pa[128], pb[128], cmd[2048];
        snprintf(pa, sizeof pa, "/tmp/sidx_test_view_real_%ld_a.png", (long)getpid());
        snprintf(pb, sizeof pb, "/tmp/sidx_test_view_real_%ld_b.png", (long)getpid());
        snprintf(cmd, sizeof cmd,
                 "%s/sidx-view --accel %s --scene flat2d --size 480x300 --step %zu --screenshot %s >/dev/null && "
                 "%s/sidx-view --accel %s --scene flat2d --size 480x300 --step %zu --screenshot %s >/dev/null",
                 bin_dir, names[k], step_a, pa, bin_dir, names[k], step_b, pb);
        int rc = system(cmd);
        if (!(WIFEXITED(rc) && WEXITSTATUS(rc) == 0)) fail_msg("failed: %s", cmd);
        size_t diff;
        assert_true(png_pixels_differ(pa, pb, &diff));
        assert_true(diff > 100);
        unlink(pa);
        unlink(pb);
        view_close(&v);
        ++checked;
    }
    if (sdl_ok) SDL_Quit();
    if (!checked) print_message("neither bvh nor kdtree registered: skipped\n");
}

#else
/* Built without SDL2 (HAVE_SDL=0, or libsdl2-dev missing): the viewer is not built. */
static void skip_without_sdl(void) { print_message("built without SDL2: the viewer is not built, skipped\n"); skip(); }
static void view_screenshots_differ_between_steps(void **state) { (void)state; skip_without_sdl(); }
static void view_keys_and_mouse(void **state) { (void)state; skip_without_sdl(); }
static void view_heat_map_log_scale(void **state) { (void)state; skip_without_sdl(); }
static void view_steps_real_recording(void **state) { (void)state; skip_without_sdl(); }
#endif /* SIDX_HAVE_SDL */

/* ---- sidx-step -------------------------------------------------------------------------------- */

static char *run_capture(const char *cmd)
{
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *buf = tk_read_all(p);
    assert_non_null(buf);
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

#if SIDX_HAVE_SDL
/* sidx-view --events: a JSON Lines trace read back steps as the recording
 * it was written from (one step per line); a trace that does not fit the
 * structure is refused with the line and the reason, in the library call
 * and in the program (exit 1). */
static void view_events_from_file(void **state)
{
    (void)state;
    view_state v;
    sidx_error err;
    assert_int_equal(view_open(&v, "flat2d", "kdtree", &err), SIDX_OK);
    sidx_vec3 o, d;
    view_default_ray(&v, &o, &d);
    assert_int_equal(view_set_ray(&v, o, d, SIZE_MAX), SIDX_OK);
    const size_t n = v.trav.count;
    assert_true(n > 10);
    char path[128], bad[128], png[128], line[2048], again[2048], cmd[1024];
    snprintf(path, sizeof path, "/tmp/sidx_test_view_events_%ld.jsonl", (long)getpid());
    snprintf(bad, sizeof bad, "/tmp/sidx_test_view_events_%ld_bad.jsonl", (long)getpid());
    snprintf(png, sizeof png, "/tmp/sidx_test_view_events_%ld.png", (long)getpid());
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    for (size_t i = 0; i < n; ++i) {
        sidx_event_to_json(&v.trav.events[i], line, sizeof line);
        fprintf(f, "%s\n", line);
    }
    assert_int_equal(fclose(f), 0);
    char *want = read_text(path);
    assert_non_null(want);

    /* read back: the same events, one step per line, the trace named */
    view_state w;
    assert_int_equal(view_open(&w, "flat2d", "kdtree", &err), SIDX_OK);
    assert_int_equal(view_load_events(&w, path, 4, &err), SIDX_OK);
    assert_int_equal(w.trav.count, n);
    assert_int_equal(w.step, 4);
    assert_string_equal(w.trace_path, path);
    for (size_t i = 0; i < n; ++i) {
        sidx_event_to_json(&v.trav.events[i], line, sizeof line);
        sidx_event_to_json(&w.trav.events[i], again, sizeof again);
        assert_string_equal(line, again);
    }
    view_replay r;
    view_replay_run(&w, n, &r);
    assert_true(r.nodes_entered > 0);
    SDL_Surface *s = view_render_surface(&w, 480, 300);
    assert_non_null(s);
    SDL_FreeSurface(s);

    /* a node the structure does not have, a build event, not JSON: refused, the trace kept */
    static const char *const bad_lines[] = {
        "{\"type\":\"node_enter\",\"structure\":\"kdtree\",\"ray\":0,\"node\":99999,\"depth\":0,\"t_near\":0,\"t_far\":1}",
        "{\"type\":\"build_end\",\"structure\":\"kdtree\",\"ray\":0,\"node\":3,\"count\":1,\"depth\":1}",
        "{\"type\":\"prim_test\",\"structure\":\"kdtree\",\"ray\":0,\"prim\":128,\"result\":0}",
        "{\"type\":\"prim_test\",\"structure\":\"bvh\",\"ray\":0,\"prim\":1,\"result\":0}",
        "{\"type\":\"prim_test\",\"structure\":\"kdtree\",\"ray\":0,\"prim\":1,\"result\":0",
    };
    static const char *const why[] = {"node 99999 is out of range", "build_end", "triangle 128 is out of range",
                                      "a trace of bvh", "not a sidx event"};
    for (size_t k = 0; k < sizeof bad_lines / sizeof bad_lines[0]; ++k) {
        f = fopen(bad, "w");
        assert_non_null(f);
        fprintf(f, "%s%s\n", want, bad_lines[k]);
        assert_int_equal(fclose(f), 0);
        assert_int_not_equal(view_load_events(&w, bad, 0, &err), SIDX_OK);
        if (!strstr(err.message, why[k])) fail_msg("'%s' does not say '%s'", err.message, why[k]);
        char at[32];
        snprintf(at, sizeof at, ":%zu:", n + 1);
        assert_non_null(strstr(err.message, at)); /* the line */
        assert_int_equal(w.trav.count, n);
    }

    /* the program: step N / N with N the number of lines; exit 1 with the message */
    snprintf(cmd, sizeof cmd, "%s/sidx-view --accel kdtree --scene flat2d --events %s --size 480x300 --screenshot %s",
             bin_dir, path, png);
    char *out = run_capture(cmd);
    snprintf(line, sizeof line, "step %zu/%zu)", n, n);
    if (!strstr(out, line)) fail_msg("'%s' does not say '%s'", out, line);
    free(out);
    snprintf(cmd, sizeof cmd, "%s/sidx-view --accel kdtree --scene flat2d --events %s --screenshot %s 2>&1", bin_dir,
             bad, png);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    out = tk_read_all(p);
    const int rc = pclose(p);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
    assert_non_null(strstr(out, "not a sidx event"));
    free(out);
    free(want);
    unlink(path);
    unlink(bad);
    unlink(png);
    view_close(&w);
    view_close(&v);
}
#else
static void view_events_from_file(void **state) { (void)state; skip(); }
#endif

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
#if SIDX_HAVE_GRAPHVIZ
    snprintf(cmd, sizeof cmd, "%s/sidx-dot --accel brute %s -o /tmp/sidx_never.dot 2>/dev/null", bin_dir, TINY_SCENE);
    rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
    /* the width and box limits: 0 = none, a width below 2 or a non-number is a usage error */
    snprintf(cmd, sizeof cmd, "%s/sidx-dot --accel bvh %s --max-width 1 -o - >/dev/null 2>&1", bin_dir, TINY_SCENE);
    rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
    snprintf(cmd, sizeof cmd, "%s/sidx-dot --accel bvh %s --max-nodes x -o - >/dev/null 2>&1", bin_dir, TINY_SCENE);
    rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 2);
    snprintf(cmd, sizeof cmd, "%s/sidx-dot --accel bvh %s --leaf-size 1 --max-width 2 -o - 2>&1", bin_dir, TINY_SCENE);
    char *folded = run_capture(cmd);
    assert_non_null(strstr(folded, "folded to fit a page (about 2 boxes across"));
    free(folded);
    snprintf(cmd, sizeof cmd, "%s/sidx-dot --accel bvh %s --leaf-size 1 --max-width 0 --max-nodes 0 -o - 2>&1", bin_dir,
             TINY_SCENE);
    folded = run_capture(cmd);
    assert_null(strstr(folded, "folded"));
    free(folded);
#endif
}

/* The build knobs: each fills its field, bad values are refused with the
 * options untouched, and a knob reaches the structure sidx-step builds. */
static void build_knobs_fill_options(void **state)
{
    (void)state;
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    char msg[160];
    assert_int_equal(sidx_viz_build_knob("--bins", "8", &bo, msg, sizeof msg), 2);
    assert_int_equal(sidx_viz_build_knob("--c-trav", "1.5", &bo, msg, sizeof msg), 2);
    assert_int_equal(sidx_viz_build_knob("--c-tri", "2", &bo, msg, sizeof msg), 2);
    assert_int_equal(sidx_viz_build_knob("--leaf-size", "3", &bo, msg, sizeof msg), 2);
    assert_int_equal(sidx_viz_build_knob("--max-depth", "12", &bo, msg, sizeof msg), 2);
    assert_int_equal(sidx_viz_build_knob("--lambda", "0.5", &bo, msg, sizeof msg), 2);
    assert_int_equal(sidx_viz_build_knob("--no-mailbox", "8", &bo, msg, sizeof msg), 1);
    assert_int_equal(sidx_viz_build_knob("--empty-bonus", "0.25", &bo, msg, sizeof msg), 2);
    assert_int_equal(bo.bins, 8);
    assert_true(bo.c_trav == 1.5f && bo.c_tri == 2.0f && bo.grid_density == 0.5f && bo.empty_bonus == 0.25f);
    assert_int_equal(bo.leaf_size, 3);
    assert_int_equal(bo.max_depth, 12);
    assert_int_equal(bo.no_mailbox, 1);

    const sidx_build_options before = bo;
    static const char *const bad[][2] = {
        {"--bins", "1"},         {"--bins", "-3"},      {"--bins", "8x"},       {"--leaf-size", "0"},
        {"--max-depth", ""},     {"--c-trav", "0"},     {"--c-tri", "nan"},     {"--lambda", "inf"},
        {"--lambda", "-1"},      {"--empty-bonus", "1"}, {"--empty-bonus", "-0.1"}, {"--bins", NULL},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        msg[0] = '\0';
        assert_int_equal(sidx_viz_build_knob(bad[i][0], bad[i][1], &bo, msg, sizeof msg), -1);
        assert_non_null(strstr(msg, bad[i][0]));
        assert_memory_equal(&bo, &before, sizeof bo);
    }
    assert_int_equal(sidx_viz_build_knob("--accel", "bvh", &bo, msg, sizeof msg), 0);
    assert_int_equal(sidx_viz_build_knob("--bin", "8", &bo, msg, sizeof msg), 0);

    /* every program says so in --help and exits 2 on a bad value */
    static const char *const progs[] = {"sidx-step", "sidx-dot", "sidx-view"};
    for (size_t i = 0; i < sizeof progs / sizeof progs[0]; ++i) {
        char cmd[1024], path[600];
        snprintf(path, sizeof path, "%s/%s", bin_dir, progs[i]);
        if (access(path, X_OK) != 0) continue; /* sidx-dot, sidx-view: optional parts */
        snprintf(cmd, sizeof cmd, "%s --help", path);
        char *help = run_capture(cmd);
        for (const char *const *k = (const char *const[]){"--bins", "--c-trav", "--c-tri", "--leaf-size",
                                                          "--max-depth", "--lambda", "--no-mailbox",
                                                          "--empty-bonus", NULL};
             *k; ++k)
            if (!strstr(help, *k)) fail_msg("%s --help does not list %s", progs[i], *k);
        free(help);
        /* the knob first: each program reads its arguments in order */
        snprintf(cmd, sizeof cmd, "%s --bins 1 --accel bvh >/dev/null 2>&1", path);
        const int rc = system(cmd);
        if (!WIFEXITED(rc) || WEXITSTATUS(rc) != 2) fail_msg("%s --bins 1 did not exit 2", progs[i]);
        snprintf(cmd, sizeof cmd, "%s --bins 1 --accel bvh 2>&1 >/dev/null || true", path);
        char *err = run_capture(cmd);
        if (!strstr(err, "--bins wants a whole number from 2")) fail_msg("%s --bins 1 said: %s", progs[i], err);
        free(err);
    }

    /* --leaf-size 8 makes the tiny scene's kd-tree one leaf: the ray enters only the root */
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel kdtree %s --ray %s --leaf-size 8 --all </dev/null", bin_dir,
             TINY_SCENE, TINY_RAY);
    if (sidx_accel_is_registered("kdtree")) {
        char *out = run_capture(cmd);
        assert_non_null(strstr(out, "node 0 enter"));
        assert_null(strstr(out, "push node"));
        free(out);
    }
}

/* Without a terminal: --panel adds the Current / Stack columns (deck 000,
 * kD-Tree Traversal), --step K prints K steps, --break TYPE stops on the
 * first TYPE event (exit 1 if there is none, 2 for no such type). */
/* --panel lines fit 100 columns on deep trees with long stacks (the teapot's) and on the
 * slide's scene with its t_split lines: long events wrap, long stacks keep their top entries
 * and count the rest; no word of the event is lost. */
static void step_panel_fits_100_columns(void **state)
{
    (void)state;
    static const char *const runs[][2] = {
        {"kdtree", "kd-slide --ray 10,5.5,0,-1,-0.15,0"},
        {"kdtree", "kd-slide --ray 0,4.2,0,1,0.15,0"},
        {"kdtree", "teapot --ray 0.3,1.5,5,0,0,-1"},
        {"bvh", "teapot --ray 0.3,1.5,5,0,0,-1"},
        {"octree", "teapot --ray 0.3,1.5,5,0,0,-1"},
        {"kdtree", "flat2d --ray -0.28,5.78,0,1,0.225,0"},
    };
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; ++i) {
        if (!sidx_accel_is_registered(runs[i][0])) continue;
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "%s/sidx-step --accel %s %s --panel --all </dev/null", bin_dir, runs[i][0],
                 runs[i][1]);
        char *out = run_capture(cmd);
        size_t longest = 0, words = 0;
        for (const char *p = out; *p;) {
            const char *e = strchr(p, '\n');
            const size_t n = e ? (size_t)(e - p) : strlen(p);
            if (n > longest) longest = n;
            p += n + (e != NULL);
        }
        if (longest > 100) fail_msg("sidx-step --accel %s %s --panel: a line of %zu columns", runs[i][0], runs[i][1], longest);
        /* the kd-tree's case text is all there, though wrapped */
        for (const char *p = out; (p = strstr(p, "t_split=")) != NULL; ++p) words++;
        if (!strcmp(runs[i][0], "kdtree") && words == 0) fail_msg("%s: no t_split in:\n%s", runs[i][1], out);
        free(out);
    }
    if (sidx_accel_is_registered("kdtree")) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "%s/sidx-step --accel kdtree kd-slide --ray 10,5.5,0,-1,-0.15,0 --panel </dev/null",
                 bin_dir);
        char *out = run_capture(cmd);
        assert_non_null(strstr(out, "both: near then far"));
        free(out);
    }
}

static void step_panel_step_break(void **state)
{
    (void)state;
    if (!sidx_accel_is_registered("bvh")) skip();
    char cmd[1024];
    const char *base = "--accel bvh " TINY_SCENE " --ray " TINY_RAY " --leaf-size 1";
    snprintf(cmd, sizeof cmd, "%s/sidx-step %s --panel </dev/null", bin_dir, base);
    char *out = run_capture(cmd);
    /* the two pushes, then both on the stack (top first) while leaf 7 is visited;
     * both popped and dropped (they start beyond the hit at t = 2): nothing current */
    assert_non_null(strstr(out, "push node 2  t=[6, 8]  (stack 0 -> 1)                  | 1 [2, 8]             | 2 [6, 8]\n"));
    assert_non_null(strstr(out, "node 7 enter  depth 3  t=[2, 2]                  | 7 leaf [2, 2]        | 6 [4, 4]  2 [6, 8]\n"));
    /* an event too long for its column goes on below it, the panel beside its first line */
    assert_non_null(strstr(out, "pop node 2  t=[6, 8]  (stack 1 -> 0)                   |                      |\n"
                                "    dropped: t_near beyond the best hit                  |                      |\n"));
    free(out);

    snprintf(cmd, sizeof cmd, "%s/sidx-step %s --step 4 </dev/null", bin_dir, base);
    out = run_capture(cmd);
    size_t lines = 0;
    for (const char *p = out; *p; ++p) lines += *p == '\n';
    assert_int_equal(lines, 4);
    assert_non_null(strstr(out, "box node 1 hit  t=[2, 8]\n"));
    free(out);

    static const char *const breaks[][2] = {
        {"push", "  push node 2  t=[6, 8]  (stack 0 -> 1)\n"},
        {"stack_pop", "  pop node 6  t=[4, 4]  (stack 2 -> 1)  dropped: t_near beyond the best hit\n"},
        {"leaf", "        node 7 enter  depth 3  t=[2, 2]\n"},
        {"prim", "    prim 6 test: hit t=2\n"},
        {"terminate", "terminate: stack_empty  visited 4  best t=2\n"},
    };
    for (size_t i = 0; i < sizeof breaks / sizeof breaks[0]; ++i) {
        snprintf(cmd, sizeof cmd, "%s/sidx-step %s --break %s </dev/null", bin_dir, base, breaks[i][0]);
        out = run_capture(cmd);
        const size_t n = strlen(out), m = strlen(breaks[i][1]);
        if (n < m || strcmp(out + n - m, breaks[i][1]) != 0)
            fail_msg("--break %s: the output does not end on '%s' but:\n%s", breaks[i][0], breaks[i][1], out);
        free(out);
    }
    /* from step 11 on, the next push is node 6's */
    snprintf(cmd, sizeof cmd, "%s/sidx-step %s --step 11 --break push </dev/null | tail -n 1", bin_dir, base);
    out = run_capture(cmd);
    assert_string_equal(out, "  push node 6  t=[4, 4]  (stack 1 -> 2)\n");
    free(out);

    snprintf(cmd, sizeof cmd, "%s/sidx-step %s --break mailbox </dev/null >/dev/null 2>&1", bin_dir, base);
    int rc = system(cmd);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 1);
    static const char *const refused[] = {"--break test", "--break nothing", "--step 0", "--step x"};
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; ++i) {
        snprintf(cmd, sizeof cmd, "%s/sidx-step %s %s </dev/null >/dev/null 2>&1", bin_dir, base, refused[i]);
        rc = system(cmd);
        if (!WIFEXITED(rc) || WEXITSTATUS(rc) != 2) fail_msg("sidx-step %s did not exit 2", refused[i]);
    }
}

/* The stepper's kd-tree example ray runs inside the root's split plane
 * x = 0: the push of the second child and its pop after the hit say why
 * the walk goes on; the pops beyond the hit say they are dropped, and the
 * Current column shows nothing for them (a dropped node is never entered). */
static void step_kdtree_says_why(void **state)
{
    (void)state;
    if (!sidx_accel_is_registered("kdtree")) skip();
    char cmd[1024];
    /* the lines as they are (--panel wraps them into its column) */
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel kdtree teapot --ray 0,0.5,5,0,0,-1 </dev/null", bin_dir);
    char *out = run_capture(cmd);
    assert_non_null(strstr(out, "  push node 2  t=[3, 7]  (stack 0 -> 1)  the ray lies in the split plane: both "
                                "children are near\n"));
    const char *hit = strstr(out, "closest hit -> prim 459 t=3.1284");
    assert_non_null(hit);
    assert_non_null(strstr(hit, "  pop node 2  t=[3, 7]  (stack 1 -> 0)  the ray lies in the split plane: both "
                                "children are near, so a hit in the other does not end the walk\n"));
    assert_non_null(strstr(out, "pop node 447  t=[3.35164, 3.97861]  (stack 4 -> 3)  dropped: t_near beyond the best "
                                "hit"));
    size_t dropped = 0;
    for (const char *d = out; (d = strstr(d, "dropped: t_near beyond the best hit")) != NULL; ++d) dropped++;
    free(out);
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel kdtree teapot --ray 0,0.5,5,0,0,-1 --panel </dev/null", bin_dir);
    out = run_capture(cmd);
    /* the popped node is current */
    hit = strstr(out, "closest hit -> prim 459 t=3.1284");
    assert_non_null(hit);
    const char *pop = strstr(hit, "  pop node 2  t=[3, 7]  (stack 1 -> 0)");
    assert_non_null(pop);
    const char *eol = strchr(pop, '\n'), *cur = strstr(pop, "| 2 [3, 7]");
    assert_true(cur && eol && cur < eol);
    /* a pop's first line: its Current column is empty exactly when the pop is dropped (as many
     * as the plain lines say "dropped") */
    size_t blank = 0;
    for (const char *line = out; *line; line = strchr(line, '\n') + 1) {
        const char *end = strchr(line, '\n');
        assert_non_null(end);
        const char *pop = strstr(line, "  pop node ");
        if (!pop || pop > end) continue;
        const char *bar = strstr(pop, " | ");
        assert_true(bar && bar < end);
        int empty = 1;
        for (const char *c = bar + 3; *c != '|'; ++c) empty &= *c == ' ';
        blank += (size_t)empty;
    }
    assert_true(dropped >= 3);
    assert_int_equal(blank, dropped);
    free(out);
}

/* kd-slide with kdtree is deck 000's tree, and the programs name its nodes
 * as the slide does ("kD-Tree Traversal (1)-(11)": Current L4, Stack L5 L3). */
static void kd_slide_programs_show_labels(void **state)
{
    (void)state;
    if (!sidx_accel_is_registered("kdtree")) skip();
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel kdtree kd-slide --ray 0,4.2,0,1,0.15,0 --panel </dev/null",
             bin_dir);
    char *out = run_capture(cmd);
    /* the columns name the nodes */
    assert_non_null(strstr(out, "| A [1, 9.5]           |\n"));
    assert_non_null(strstr(out, "| B [1, 4]             | C [4, 9.5]\n"));
    assert_non_null(strstr(out, "| L4 leaf [4, 5.33333] | L5 [5.33333, 7.5]  L3 [7.5, 9.5]\n"));
    free(out);
    /* without them, the lines do */
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel kdtree kd-slide --ray 0,4.2,0,1,0.15,0 </dev/null", bin_dir);
    out = run_capture(cmd);
    assert_non_null(strstr(out, "  node 0 enter  depth 0  t=[1, 9.5]  x=4 at t_split=4: both: near then far  [A]"));
    assert_non_null(strstr(out, "terminate: hit_in_cell  visited 8  best t=8.33333  [L3]"));
    free(out);
    /* the build: the note, and the leaves' reason */
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel kdtree kd-slide --build </dev/null", bin_dir);
    out = run_capture(cmd);
    assert_non_null(strstr(out, "note: kdtree: the splits are given"));
    assert_non_null(strstr(out, "leaf node 7  prims 2: 4 5  cost 2  (given)  [L4]"));
    free(out);
#if SIDX_HAVE_GRAPHVIZ
    char path[128];
    tmp_path(path, sizeof path, "kdslide.dot");
    snprintf(cmd, sizeof cmd, "%s/sidx-dot --accel kdtree kd-slide --ray 0,4.2,0,1,0.15,0 -o %s >/dev/null", bin_dir,
             path);
    assert_int_equal(system(cmd), 0);
    char *dot = read_text(path);
    assert_non_null(dot);
    assert_non_null(strstr(dot, "A (node 0)"));
    assert_non_null(strstr(dot, "L4 (leaf 7)"));
    assert_non_null(strstr(dot, "L3 (leaf 6)"));
    free(dot);
    remove(path);
#endif
#if SIDX_HAVE_SDL
    view_state v;
    sidx_error err;
    assert_int_equal(view_open(&v, "kd-slide", "kdtree", &err), SIDX_OK);
    assert_string_equal(sidx_accel_node_label(v.accel, 7), "L4");
    view_close(&v);
#endif
}

int main(int argc, char **argv)
{
    (void)argc;
    /* build/tests/test_viz -> build/bin (also build/san/...) */
    tk_bin_dir(argv[0], bin_dir, sizeof bin_dir);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(tree_from_synthetic_events),
        cmocka_unit_test(tree_errors),
        cmocka_unit_test(dot_synthetic_parses_back),
        cmocka_unit_test(dot_real_structure),
        cmocka_unit_test(view_screenshots_differ_between_steps),
        cmocka_unit_test(view_keys_and_mouse),
        cmocka_unit_test(view_heat_map_log_scale),
        cmocka_unit_test(view_steps_real_recording),
        cmocka_unit_test(view_events_from_file),
        cmocka_unit_test(leaf_prims_from_real_builds),
        cmocka_unit_test(dot_real_leaf_labels),
        cmocka_unit_test(dot_labels_say_the_structure),
        cmocka_unit_test(dot_wide_trees_fit_a_page),
        cmocka_unit_test(dot_folds_wide_levels),
        cmocka_unit_test(dot_every_structure_and_scene_finishes),
        cmocka_unit_test(step_matches_expected),
        cmocka_unit_test(build_knobs_fill_options),
        cmocka_unit_test(step_panel_step_break),
        cmocka_unit_test(step_panel_fits_100_columns),
        cmocka_unit_test(kd_slide_programs_show_labels),
        cmocka_unit_test(step_kdtree_says_why),
    };
    return cmocka_run_group_tests_name("viz", tests, NULL, NULL);
}
