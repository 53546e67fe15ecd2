/* 25_kd_slide_example.c — the slides' own kd-tree, walked as the slides walk it.
 *
 * Slides (deck 000, "Spatial Index Structures"): "kD-Tree Example
 * (1)-(7)" (a 2D scene cut by the planes A, B, C, D into the leaves L1 to
 * L5) and "kD-Tree Traversal (1)-(11)" (one ray through it, the figure
 * reading after each step "Current: ... Stack: ...": A; B with C on the
 * stack; L2; C; D with L3; L4 with L5 L3; the triangles △ ▽ tested in L4,
 * Result △; then "CANNOT terminate !!!").
 *
 * What it shows, on the built-in scene "kd-slide" (lib/scenes.c: eight
 * triangles placed as the figure places them):
 *   1. the tree, split by split, with the slide's names.  The SAH would
 *      not cut eight triangles this way, so the scene comes with its tree
 *      (sidx_scene_accel_build, sidx_kdtree_build_from_splits) and the
 *      nodes carry the slide's names (sidx_accel_node_label) — the same
 *      tree and names `sidx-step --accel kdtree kd-slide`, `sidx-dot` and
 *      `sidx-view` show;
 *   2. the library's traversal of the slide's ray, from its events, in
 *      the slide's compact form: one row per node entered and one per
 *      leaf's triangle tests (folded into one line), with the slide's row
 *      beside it and where the walk CANNOT terminate;
 *   3. what the SAH kd-tree makes of the same eight triangles.
 * The CHECK lines compare the rows with the slide's.
 *
 * Read:  lib/kdtree_build.c, sidx_kdtree_build_from_splits;
 *        lib/kdtree_traverse.c, kd_walk_slide
 * Run:   build/lessons/25_kd_slide_example [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default kd-slide); other
 *        scenes get their SAH tree, their node ids and a ray through the middle
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "lesson.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 25_kd_slide_example [--help] [build knobs] [SCENE]\n"
               "\n"
               "The kd-tree of deck 000 \"kD-Tree Example\" and its traversal \"kD-Tree Traversal\n"
               "(1)-(11)\": the slide's Current / Stack table, one row per step, next to the slide's.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: kd-slide, the slide's figure)\n"
               "The slide's tree is given split by split, so the knobs below change only the SAH\n"
               "tree printed at the end (and the cost figures); the checks hold for kd-slide.\n");
}

#define MAX_ROWS 64
#define ROW_NAMES 6

/* One row of the table: the node entered, or a leaf's tests and the result so far. */
typedef struct row {
    char current[96], result[16], stack[96], note[128];
    int leaf_tests; /* 1: the row of a leaf's tests */
    int ntests;     /* its tests; the first ROW_NAMES are named */
} row;

typedef struct table {
    row rows[MAX_ROWS];
    int n;
    int cannot_terminate; /* rows saying so */
    char ended_in[16];    /* the leaf the walk stopped in, "" if it ran out of cells */
} table;

/* The slide's names of the kd-slide triangles (lib/scenes.c), ids elsewhere. */
static const char *prim_name(int slide, uint32_t prim, char buf[16])
{
    static const char *const names[8] = {"t0", "t1", "t2", "t3", "△", "▽", "t6", "t7"};
    if (slide && prim < 8) return names[prim];
    snprintf(buf, 16, "%u", prim);
    return buf;
}

static const char *node_name(const sidx_accel *a, uint32_t node, char buf[16])
{
    const char *label = sidx_accel_node_label(a, node);
    if (label) return label;
    snprintf(buf, 16, "%u", node);
    return buf;
}

/* ---- 1. the tree ------------------------------------------------------------------ */

static void print_tree(const sidx_accel *a, const sidx_kd_node *nodes, const uint32_t *refs, uint32_t node,
                       int depth, int slide)
{
    const sidx_kd_node *n = &nodes[node];
    char id[16], pb[16];
    printf("  %*s%-3s (node %u)  ", 2 * depth, "", node_name(a, node, id), node);
    if ((n->bits & 3u) != SIDX_KD_LEAF) {
        printf("split %c = %g\n", "xyz"[n->bits & 3u], (double)n->u.split);
        print_tree(a, nodes, refs, n->bits >> 2, depth + 1, slide);
        print_tree(a, nodes, refs, (n->bits >> 2) + 1, depth + 1, slide);
        return;
    }
    printf("leaf:");
    for (uint32_t i = 0; i < n->u.count; ++i) printf(" %s", prim_name(slide, refs[(n->bits >> 2) + i], pb));
    printf("%s\n", n->u.count ? "" : " (empty)");
}

/* Is `node` an inner node on `axis` whose children are labelled l and r? */
static int inner_is(const sidx_accel *a, const sidx_kd_node *nodes, uint32_t node, uint32_t axis, const char *l,
                    const char *r)
{
    const sidx_kd_node *n = &nodes[node];
    if ((n->bits & 3u) != axis) return 0;
    const char *ln = sidx_accel_node_label(a, n->bits >> 2), *rn = sidx_accel_node_label(a, (n->bits >> 2) + 1);
    return ln && rn && !strcmp(ln, l) && !strcmp(rn, r);
}

/* Node id of the node labelled `label`, or UINT32_MAX. */
static uint32_t find_label(const sidx_accel *a, uint32_t count, const char *label)
{
    for (uint32_t i = 0; i < count; ++i) {
        const char *l = sidx_accel_node_label(a, i);
        if (l && !strcmp(l, label)) return i;
    }
    return UINT32_MAX;
}

/* The slide's tree: A splits x into B and C, B splits y into L1 and L2, C
 * splits x into D and L3, D splits y into L4 and L5; L4 holds △ and ▽. */
static int is_slide_tree(const sidx_accel *a, const sidx_kd_node *nodes, const uint32_t *refs, uint32_t count)
{
    const char *root = sidx_accel_node_label(a, 0);
    const uint32_t B = find_label(a, count, "B"), C = find_label(a, count, "C"), D = find_label(a, count, "D");
    const uint32_t L4 = find_label(a, count, "L4");
    if (!root || strcmp(root, "A") || B == UINT32_MAX || C == UINT32_MAX || D == UINT32_MAX || L4 == UINT32_MAX)
        return 0;
    const sidx_kd_node *l4 = &nodes[L4];
    return inner_is(a, nodes, 0, 0, "B", "C") && inner_is(a, nodes, B, 1, "L1", "L2") &&
           inner_is(a, nodes, C, 0, "D", "L3") && inner_is(a, nodes, D, 1, "L4", "L5") &&
           (l4->bits & 3u) == SIDX_KD_LEAF && l4->u.count == 2 && refs[l4->bits >> 2] == 4 &&
           refs[(l4->bits >> 2) + 1] == 5;
}

/* ---- 2. the traversal as the slide's table ------------------------------------------ */

static row *add_row(table *t)
{
    if (t->n == MAX_ROWS) return NULL;
    row *r = &t->rows[t->n++];
    memset(r, 0, sizeof *r);
    return r;
}

static void stack_text(const sidx_accel *a, const uint32_t *stack, int n, char *out, size_t size)
{
    char id[16];
    size_t off = 0;
    out[0] = '\0';
    for (int k = n - 1; k >= 0 && off < size; --k) { /* top first, as the slide writes it */
        const int w = snprintf(out + off, size - off, "%s%s", off ? " " : "", node_name(a, stack[k], id));
        if (w < 0) break;
        off += (size_t)w;
    }
}

/* Replays the traversal's events into rows: a row when a node is entered,
 * and one for each leaf's tests (PRIM_TEST, MAILBOX_HIT), closed when the
 * walk leaves the leaf: by a pop, which means the best hit lies beyond the
 * leaf's cell ("CANNOT terminate"), or by TERMINATE. */
static void make_table(const sidx_accel *a, const sidx_recorder *rec, int slide, table *t)
{
    uint32_t stack[64];
    int sn = 0;
    row *tests = NULL;               /* the open leaf's test row */
    char leaf[16] = "", best[16] = "", id[16], pb[16];
    float leaf_far = INFINITY, best_t = INFINITY;
    memset(t, 0, sizeof *t);
    for (size_t i = 0; i < rec->count; ++i) {
        const sidx_event *e = &rec->events[i];
        if (e->type == SIDX_EV_STACK_POP || e->type == SIDX_EV_TERMINATE) {
            if (tests && e->type == SIDX_EV_STACK_POP && best[0]) {
                snprintf(tests->note, sizeof tests->note, "CANNOT terminate: %s at t=%.3g lies beyond %s (t <= %.3g)",
                         best, (double)best_t, leaf, (double)leaf_far);
                t->cannot_terminate++;
            }
            if (e->type == SIDX_EV_TERMINATE && e->reason == SIDX_TERM_HIT_IN_CELL) {
                snprintf(t->ended_in, sizeof t->ended_in, "%s", node_name(a, e->node, id));
                if (tests)
                    snprintf(tests->note, sizeof tests->note, "terminate: %s at t=%.3g lies in %s (t <= %.3g)", best,
                             (double)best_t, leaf, (double)leaf_far);
            }
            tests = NULL;
            if (e->type == SIDX_EV_STACK_POP && sn) --sn;
            continue;
        }
        switch (e->type) {
        case SIDX_EV_STACK_PUSH:
            if (sn < 64) stack[sn++] = e->node;
            break;
        case SIDX_EV_NODE_ENTER: {
            row *r = add_row(t);
            if (!r) return;
            tests = NULL;
            snprintf(r->current, sizeof r->current, "%s", node_name(a, e->node, id));
            snprintf(r->result, sizeof r->result, "%s", best);
            stack_text(a, stack, sn, r->stack, sizeof r->stack);
            snprintf(leaf, sizeof leaf, "%.*s", (int)sizeof leaf - 1, r->current); /* the leaf's name, cut to fit */
            leaf_far = e->t_far;
            break;
        }
        case SIDX_EV_PRIM_TEST:
        case SIDX_EV_MAILBOX_HIT: {
            if (!tests) {
                if (!(tests = add_row(t))) return;
                tests->leaf_tests = 1;
                stack_text(a, stack, sn, tests->stack, sizeof tests->stack);
            }
            const size_t len = strlen(tests->current);
            if (tests->ntests++ < ROW_NAMES)
                snprintf(tests->current + len, sizeof tests->current - len, "%s%s%s", len ? " " : "",
                         prim_name(slide, e->prim, pb), e->type == SIDX_EV_MAILBOX_HIT ? " (mailbox)" : "");
            else if (tests->ntests == ROW_NAMES + 1)
                snprintf(tests->current + len, sizeof tests->current - len, " ...");
            snprintf(tests->result, sizeof tests->result, "%s", best[0] ? best : "-");
            break;
        }
        case SIDX_EV_HIT_UPDATE:
            snprintf(best, sizeof best, "%s", prim_name(slide, e->prim, pb));
            best_t = e->t;
            if (tests) snprintf(tests->result, sizeof tests->result, "%s", best);
            break;
        default:
            break;
        }
    }
}

/* The slide's rows (1)-(9), as its text gives them: Current, Result, Stack.
 * (4) and (8) show the leaf's triangles as pictures, lost in the text. */
typedef struct slide_row {
    const char *number, *current, *result, *stack;
} slide_row;
static const slide_row slide_rows[] = {
    {"(1)", "A", "", ""},        {"(2)", "B", "", "C"},           {"(3)", "L2", "", "C"},
    {"(4)", "(tests)", "", "C"}, {"(5)", "C", "", ""},            {"(6)", "D", "", "L3"},
    {"(7)", "L4", "", "L5 L3"},  {"(8)-(9)", "△ ▽", "△", "L5 L3"},
};
#define SLIDE_ROWS (sizeof slide_rows / sizeof slide_rows[0])

/* Does row i say what the slide's row i says?  A test row is compared by
 * its stack only where the slide shows pictures (4). */
static int row_matches(const row *r, const slide_row *s)
{
    if (strcmp(r->stack, s->stack) != 0) return 0;
    if (!strcmp(s->current, "(tests)")) return r->leaf_tests;
    return !strcmp(r->current, s->current) && (!s->result[0] || !strcmp(r->result, s->result));
}

/* printf's %-*s counts bytes; △ and ▽ are three bytes and one column. */
static void print_cell(const char *s, int width)
{
    int cols = 0;
    for (const unsigned char *p = (const unsigned char *)s; *p; ++p) cols += (*p & 0xc0u) != 0x80u;
    printf("%s%*s", s, width > cols ? width - cols : 1, "");
}

int main(int argc, char **argv)
{
    sidx_build_options knobs;
    memset(&knobs, 0, sizeof knobs);
    const lesson_option options[] = {LESSON_KNOBS(knobs), {0}};
    lesson_args args = {.name = "25_kd_slide_example", .usage = usage, .scene = "kd-slide", .options = options};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "kdtree");
    sidx_mesh mesh = lesson_open_scene(&args);
    const int slide = !strcmp(args.scene, "kd-slide");
    sidx_error err;

    printf("== 25: the slides' kd-tree example (deck 000, \"kD-Tree Example\", \"kD-Tree Traversal (1)-(11)\")\n\n");
    sidx_accel *a = NULL;
    if (sidx_scene_accel_build(args.scene, "kdtree", &mesh, &knobs, &a, &err) != SIDX_OK) lesson_fail(&args, err.message);
    const sidx_kd_node *nodes;
    const uint32_t *refs;
    uint32_t num_nodes, num_refs;
    if (sidx_kdtree_nodes(a, &nodes, &num_nodes, &err) != SIDX_OK || sidx_kdtree_refs(a, &refs, &num_refs, &err) != SIDX_OK)
        lesson_fail(&args, err.message);

    /* ---- 1 */
    printf("1. The tree (\"kD-Tree Example (1)-(7)\": each split cuts its cell in two), %u triangles,\n"
           "   %u nodes, %u triangle references (%s crosses C's plane: in L4 and in L3):\n\n",
           mesh.num_triangles, num_nodes, num_refs, slide ? "△" : "a triangle");
    if (num_nodes <= 64) print_tree(a, nodes, refs, 0, 0, slide);
    else printf("  (%u nodes: not printed)\n", num_nodes);
    const int slide_tree = slide && is_slide_tree(a, nodes, refs, num_nodes);

    /* ---- 2 */
    sidx_vec3 org = sidx_v3(0.0f, 4.2f, 0.0f), dir = sidx_v3(1.0f, 0.15f, 0.0f);
    if (!slide) { /* across the middle of the box, in its mid z plane */
        const sidx_aabb b = sidx_mesh_bounds(&mesh);
        const sidx_vec3 e = sidx_aabb_extent(b), c = sidx_aabb_centroid(b);
        org = sidx_v3(b.min.x - 0.05f * e.x, b.min.y + 0.3f * e.y, c.z);
        dir = sidx_v3(1.0f, e.x > 0.0f ? 0.35f * e.y / e.x : 0.3f, 0.0f);
    }
    sidx_ray ray;
    sidx_ray_init(&ray, org, dir, 0.0f, INFINITY);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook hook = sidx_recorder_hook(&rec);
    hook.mask = SIDX_EVMASK_TRAVERSAL;
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &hook;
    sidx_hit traced, plain;
    sidx_accel_intersect(a, &ray, &q, &traced);
    sidx_accel_intersect(a, &ray, NULL, &plain);
    if (rec.overflow) lesson_fail(&args, "out of memory recording the traversal");
    static table t;
    make_table(a, &rec, slide, &t);

    printf("\n2. The ray (%g, %g, %g) + t*(%g, %g, %g)%s, as the library walks it: one row per\n"
           "   node entered, one per leaf's triangle tests; Stack top first, as on the slide.\n\n",
           (double)org.x, (double)org.y, (double)org.z, (double)dir.x, (double)dir.y, (double)dir.z,
           slide ? " (t = x)" : "");
    printf("  %-4s %-22s %-7s %-10s %-9s %s\n", "row", "Current", "Result", "Stack", "slide", "");
    int matched = 0;
    for (int i = 0; i < t.n; ++i) {
        const row *r = &t.rows[i];
        const slide_row *s = slide && (size_t)i < SLIDE_ROWS ? &slide_rows[i] : NULL;
        const int ok = s && row_matches(r, s);
        matched += ok;
        printf("  %-4d ", i + 1);
        print_cell(r->current, 23);
        print_cell(r->result, 8);
        print_cell(r->stack[0] ? r->stack : "-", 11);
        printf("%-9s %s\n", s ? s->number : slide ? "(10)-(11)" : "", r->note);
        if (s && !ok) printf("       the slide: Current %s  Result %s  Stack %s\n", s->current, s->result, s->stack);
    }
    char pb[16];
    printf("\n   Hit: %s at t=%.4g.\n", traced.prim == SIDX_NO_HIT ? "none" : prim_name(slide, traced.prim, pb),
           (double)traced.t);
    if (slide)
        printf("   Found in L4 (row 8) but lying beyond L4's cell, it cannot end the walk (\"CANNOT\n"
               "   terminate !!!\", slides (10) and (11)): a triangle in a later cell could be nearer.\n"
               "   L5's t6 is missed, so the walk cannot end there either; in L3 the mailbox knows △\n"
               "   (tested in L4) and the hit lies inside L3's interval, so the walk stops.\n");

    /* ---- 3 */
    /* The decks name the constants but give them no values: deck 000 ("Building good kD-trees")
     * writes Cost(c) = C_trav + SA(L)/SA(c) * TriCount(L) + SA(R)/SA(c) * TriCount(R), a
     * triangle counted as 1 and C_trav left a symbol; deck 001 ("Surface Area Heuristic") names
     * C_trav and C_tri only.  So the lesson sets two values of its own: the library's default
     * (a dear step) and a cheap step, 1 : 1.5, to show the cost deciding the depth. */
    sidx_accel *sah = NULL, *cheap = NULL;
    sidx_build_options cheap_knobs = knobs;
    cheap_knobs.c_trav = 1.0f;
    cheap_knobs.c_tri = 1.5f;
    if (sidx_accel_build("kdtree", &mesh, &knobs, &sah, &err) != SIDX_OK) lesson_fail(&args, err.message);
    if (sidx_accel_build("kdtree", &mesh, &cheap_knobs, &cheap, &err) != SIDX_OK) lesson_fail(&args, err.message);
    sidx_accel_stats s1, s2, s0;
    sidx_accel_stats_get(a, &s0);
    sidx_accel_stats_get(sah, &s1);
    sidx_accel_stats_get(cheap, &s2);
    printf("\n3. What the SAH kd-tree makes of the same triangles (sidx_accel_build(\"kdtree\")):\n"
           "   %-21s %3u nodes, %u leaves, depth %u\n"
           "   SAH, the library's C_trav : C_tri = %g : %g   %3u nodes, %u leaves, depth %u\n"
           "   SAH, a cheap step, C_trav : C_tri = %g : %g   %3u nodes, %u leaves, depth %u\n"
           "   The decks give the SAH's constants no values (deck 000 counts a triangle as 1 and\n"
           "   leaves C_trav a symbol; deck 001 names C_trav and C_tri), so both ratios are this\n"
           "   lesson's.  The cost decides how deep the SAH cuts (a dear step: shallower; a cheap\n"
           "   one: deeper), and neither draws the slide's planes: the slide picks them to\n"
           "   show the walk, so the scene comes with them.\n",
           slide ? "the slide's tree" : "the tree above", s0.nodes, s0.leaves, s0.max_depth, (double)(knobs.c_trav > 0 ? knobs.c_trav : 16.0f),
           (double)(knobs.c_tri > 0 ? knobs.c_tri : 1.0f), s1.nodes, s1.leaves, s1.max_depth,
           (double)cheap_knobs.c_trav, (double)cheap_knobs.c_tri, s2.nodes, s2.leaves, s2.max_depth);

    /* brute force agrees */
    sidx_accel *brute = NULL;
    sidx_hit bh;
    if (sidx_accel_build("brute", &mesh, NULL, &brute, &err) != SIDX_OK) lesson_fail(&args, err.message);
    sidx_accel_intersect(brute, &ray, NULL, &bh);
    const int same_hit = traced.prim == plain.prim && traced.t == plain.t && bh.prim == plain.prim && bh.t == plain.t;

    printf("\n");
    lesson_check("slide_tree", slide_tree);
    lesson_check("rows_match_slide", slide && matched == (int)SLIDE_ROWS);
    lesson_check("cannot_terminate_rows", t.cannot_terminate);
    lesson_check("ends_in_L3", !strcmp(t.ended_in, "L3"));
    lesson_check("same_hit", same_hit);
    lesson_check("cheap_step_deeper", s2.max_depth > s1.max_depth);

    sidx_accel_destroy(brute);
    sidx_accel_destroy(cheap);
    sidx_accel_destroy(sah);
    sidx_accel_destroy(a);
    sidx_recorder_free(&rec);
    sidx_mesh_free(&mesh);
    return 0;
}
