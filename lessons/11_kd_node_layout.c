/* 11_kd_node_layout.c — the kd-tree's 8-byte node.
 *
 * Slides (deck 000, "Spatial Index Structures"): "What's in a node?" ("Am
 * I a leaf? Split axis, split location, pointers to children"),
 * "Compact (8-byte) Nodes" ("Split location: 32 bit float — Always two
 * children, put them side-by-side: only one 32-bit pointer — Leaf flag +
 * split axis: 2 bits — Encode bits in lowest 2 bits of pointer"), "No
 * Bounding Box!" ("Would be 24 bytes: 4X explosion (!)"), "Memory Layout"
 * and "Other Data".
 *
 * What it shows: a kd-tree (default over the teapot) and, for the first
 * few nodes, the two 32-bit words of the deck's compact node, bit by bit,
 * read from the built tree's own memory (sidx_kdtree_nodes, sidx/kdtree.h):
 * the split position as an IEEE float, and the child index shifted left
 * by two with the axis (or 3 = leaf) in the low bits.  What is checked is
 * what the layout relies on, against what the build said it did (its
 * BUILD_* events, recorded): every word decodes to the split or leaf the
 * build reported for that node, and the two children of every inner node
 * are the nodes at ids k and k+1 (so one index is enough).  Then memory:
 * 8 bytes per node against a node that also stores its box, measured with
 * sidx_accel_stats.
 *
 * Read:  lib/kdtree_internal.h, kd_make_inner
 * Run:   build/lessons/11_kd_node_layout [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "lesson.h"
#include "sidx/kdtree.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 11_kd_node_layout [--help] [build knobs] [SCENE]\n"
               "\n"
               "The kd-tree's compact 8-byte node: the bit layout of a few nodes, the side-by-side\n"
               "children it relies on, and the memory against a node that keeps its box.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n"
               "The knobs below change the kd-tree whose nodes are decoded; the checks hold for\n"
               "the defaults.\n");
}

static void bits32(uint32_t w, int groups)
{
    for (int b = 31; b >= 0; --b) {
        putchar((w >> b) & 1u ? '1' : '0');
        if (groups && b == 2) putchar('|');
    }
}

/* What the build events say about one node. */
typedef struct {
    int seen, leaf, axis;
    uint32_t count, parent;
    float pos;
} node_info;

int main(int argc, char **argv)
{
    sidx_build_options knobs = {0};
    const lesson_option options[] = {LESSON_C_TRAV(knobs),    LESSON_C_TRI(knobs),       LESSON_LEAF_SIZE(knobs),
                                     LESSON_MAX_DEPTH(knobs), LESSON_EMPTY_BONUS(knobs), {0}};
    lesson_args args = {.name = "11_kd_node_layout", .usage = usage, .scene = "teapot", .options = options};
    lesson_parse(&args, argc, argv);
    lesson_need(&args, "kdtree");
    sidx_mesh mesh = lesson_open_scene(&args);
    sidx_error err = {0};
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook rh = sidx_recorder_hook(&rec);
    sidx_build_options opt = knobs;
    opt.hook = &rh;
    sidx_accel *kd = NULL;
    if (sidx_accel_build("kdtree", &mesh, &opt, &kd, &err) != SIDX_OK) {
        fprintf(stderr, "11_kd_node_layout: %s\n", err.message);
        sidx_recorder_free(&rec);
        sidx_mesh_free(&mesh);
        return 1;
    }
    sidx_accel_stats st;
    sidx_accel_stats_get(kd, &st);
    /* the tree's own node array: these are the bytes the traversal reads */
    const sidx_kd_node *nodes = NULL;
    uint32_t num_nodes = 0;
    if (sidx_kdtree_nodes(kd, &nodes, &num_nodes, &err) != SIDX_OK) {
        fprintf(stderr, "11_kd_node_layout: %s\n", err.message);
        return 1;
    }
    /* what the build reported, node by node */
    node_info *ni = calloc(num_nodes ? num_nodes : 1, sizeof *ni);
    if (!ni) return 1;
    int events_ok = !rec.overflow;
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        if (e->type != SIDX_EV_BUILD_NODE && e->type != SIDX_EV_BUILD_SPLIT && e->type != SIDX_EV_BUILD_LEAF) continue;
        if (e->node >= num_nodes) { events_ok = 0; continue; }
        node_info *n = &ni[e->node];
        if (e->type == SIDX_EV_BUILD_NODE) {
            n->seen = 1;
            n->parent = e->parent;
        } else if (e->type == SIDX_EV_BUILD_SPLIT) {
            n->axis = e->axis;
            n->pos = e->pos;
        } else {
            n->leaf = 1;
            n->count = e->count;
        }
    }
    /* decode every real node and compare with the events; an inner
     * node's children are read from its word, and the build must have
     * created exactly those two nodes as its children */
    int decoded = events_ok, side_by_side = events_ok;
    uint32_t inner = 0;
    for (uint32_t i = 0; i < num_nodes; ++i) {
        const uint32_t w0 = nodes[i].u.count, w1 = nodes[i].bits; /* word 0 read as raw bits */
        const int is_leaf = (w1 & 3u) == SIDX_KD_LEAF;
        if (!ni[i].seen || is_leaf != ni[i].leaf) { decoded = 0; continue; }
        if (is_leaf) {
            if (w0 != ni[i].count) decoded = 0;
            continue;
        }
        ++inner;
        float split;
        memcpy(&split, &w0, sizeof split);
        if (split != ni[i].pos || (int)(w1 & 3u) != ni[i].axis) decoded = 0;
        const uint32_t c = w1 >> 2;
        if (c + 1u >= num_nodes || !ni[c].seen || !ni[c + 1u].seen || ni[c].parent != i || ni[c + 1u].parent != i)
            side_by_side = 0;
    }
    printf("== '%s': kd-tree of %u nodes (%u inner, %u leaves), %llu triangle references\n", args.scene, num_nodes,
           inner, st.leaves, (unsigned long long)st.prim_refs);
    printf("\n== The first nodes, as the two 32-bit words stored in the tree (sidx_kdtree_nodes)\n"
           "   inner: word 0 = split position (float);  word 1 = left child << 2 | axis (0 x, 1 y, 2 z)\n"
           "   leaf:  word 0 = triangle count;          word 1 = offset into the reference array << 2 | 3\n\n");
    /* the first six nodes (the top of the tree: inner nodes), then the
     * first leaf holding triangles and the first empty leaf */
    uint32_t show[8], nshow = 0, full = UINT32_MAX, empty = UINT32_MAX;
    for (uint32_t i = 0; i < num_nodes && i < 6; ++i) show[nshow++] = i;
    for (uint32_t i = 0; i < num_nodes; ++i) {
        if ((nodes[i].bits & 3u) != SIDX_KD_LEAF) continue;
        if (nodes[i].u.count && full == UINT32_MAX) full = i;
        if (!nodes[i].u.count && empty == UINT32_MAX) empty = i;
    }
    if (full != UINT32_MAX && full >= 6) show[nshow++] = full;
    if (empty != UINT32_MAX && empty >= 6) show[nshow++] = empty;
    if (nshow == 8 && show[6] > show[7]) { const uint32_t t = show[6]; show[6] = show[7]; show[7] = t; }
    const uint32_t *refs = NULL;
    uint32_t num_refs = 0;
    if (sidx_kdtree_refs(kd, &refs, &num_refs, &err) != SIDX_OK) {
        fprintf(stderr, "11_kd_node_layout: %s\n", err.message);
        return 1;
    }
    for (uint32_t k = 0; k < nshow; ++k) {
        const uint32_t i = show[k];
        const uint32_t w0 = nodes[i].u.count, w1 = nodes[i].bits;
        const int is_leaf = (w1 & 3u) == SIDX_KD_LEAF;
        printf("  node %u (at byte %zu of the node array): ", i, (size_t)i * sizeof *nodes);
        if (is_leaf) {
            printf("leaf, %u triangles from reference %u", w0, w1 >> 2);
            if (w0 && (w1 >> 2) + w0 <= num_refs) {
                printf(": triangles");
                for (uint32_t j = 0; j < w0 && j < 6; ++j) printf(" %u", refs[(w1 >> 2) + j]);
                if (w0 > 6) printf(" ...");
            }
            printf("\n");
        } else {
            float split;
            memcpy(&split, &w0, sizeof split);
            printf("inner, split %c at %g, children %u and %u\n", "xyz"[w1 & 3u], split, w1 >> 2, (w1 >> 2) + 1u);
        }
        printf("    word 0  0x%08x  ", w0);
        bits32(w0, 0);
        printf("\n    word 1  0x%08x  ", w1);
        bits32(w1, 1);
        printf("  (low 2 bits: %u = %s)\n", w1 & 3u, is_leaf ? "leaf" : (w1 & 3u) == 0 ? "x" : (w1 & 3u) == 1 ? "y" : "z");
    }
    printf("\n  sizeof(sidx_kd_node) = %zu bytes\n", sizeof(sidx_kd_node));
    const double compact = 8.0 * st.nodes, boxed = (8.0 + 24.0) * st.nodes;
    printf("\n== Memory\n");
    printf("  nodes x 8 bytes                  %10.1f KiB\n", compact / 1024);
    printf("  nodes x 32 bytes (+ a 24-byte box) %8.1f KiB  (the slide's 4x explosion)\n", boxed / 1024);
    printf("  references x 4 bytes             %10.1f KiB\n", 4.0 * st.prim_refs / 1024);
    printf("  the whole structure (stats)      %10.1f KiB  (also triangle copies, allocation slack)\n", st.bytes / 1024.0);
    printf("  A node needs no box: the traversal knows its cell as the ray interval [t_near, t_far].\n");
    printf("  Every stored word decodes to the split or leaf the build reported: %s\n", decoded ? "yes" : "NO");
    printf("  Both children of every inner node sit side by side (ids k and k+1): %s\n", side_by_side ? "yes" : "NO");
    lesson_check("decoded_matches", decoded && num_nodes == st.nodes);
    lesson_check("children_side_by_side", side_by_side && inner > 0);
    free(ni);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(kd);
    sidx_mesh_free(&mesh);
    return 0;
}
