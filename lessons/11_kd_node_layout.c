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
 * What it shows: a kd-tree (default over the teapot) as its build events
 * describe it, and for the first few nodes the two 32-bit words of the
 * deck's compact node, bit by bit: the split position as an IEEE float,
 * and the child index shifted left by two with the axis (or 3 = leaf) in
 * the low bits.  The words are encoded here from the events, following
 * the layout documented in lib/kdtree_internal.h; what is checked is what
 * the layout relies on: both children of every inner node have
 * consecutive ids (so one index is enough), and the encoding decodes back
 * to the same node.  Then memory: 8 bytes per node against a node that
 * also stores its box, measured with sidx_accel_stats.
 *
 * Run:   build/lessons/11_kd_node_layout [SCENE]
 *        SCENE = a built-in scene name or .obj/.ply (default teapot)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: 11_kd_node_layout [--help] [SCENE]\n"
               "\n"
               "The kd-tree's compact 8-byte node: the bit layout of a few nodes, the side-by-side\n"
               "children it relies on, and the memory against a node that keeps its box.\n"
               "\n"
               "  SCENE   built-in scene name or .obj/.ply (default: teapot)\n");
}

static void bits32(uint32_t w, int groups)
{
    for (int b = 31; b >= 0; --b) {
        putchar((w >> b) & 1u ? '1' : '0');
        if (groups && b == 2) putchar('|');
    }
}

typedef struct {
    int seen, leaf, axis;
    uint32_t count, parent, first_child, nchild;
    float pos;
} node_info;

int main(int argc, char **argv)
{
    const char *scene = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) { usage(stdout); return 0; }
        if (argv[i][0] == '-' || scene) {
            fprintf(stderr, "11_kd_node_layout: unexpected argument '%s'\n", argv[i]);
            usage(stderr);
            return 2;
        }
        scene = argv[i];
    }
    if (!sidx_accel_is_registered("kdtree")) {
        fprintf(stderr, "11_kd_node_layout: structure 'kdtree' is not registered in this build\n");
        return 1;
    }
    const char *spec = scene ? scene : "teapot";
    sidx_mesh mesh;
    sidx_error err = {0};
    if (sidx_scene_open(spec, &mesh, &err) != SIDX_OK) {
        fprintf(stderr, "11_kd_node_layout: %s\n", err.message);
        return 1;
    }
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    const sidx_hook rh = sidx_recorder_hook(&rec);
    sidx_build_options opt = {0};
    opt.hook = &rh;
    sidx_accel *kd = NULL;
    if (mesh.num_triangles == 0 || sidx_accel_build("kdtree", &mesh, &opt, &kd, &err) != SIDX_OK) {
        fprintf(stderr, "11_kd_node_layout: %s\n", mesh.num_triangles ? err.message : "empty scene");
        sidx_recorder_free(&rec);
        sidx_mesh_free(&mesh);
        return 1;
    }
    sidx_accel_stats st;
    sidx_accel_stats_get(kd, &st);
    node_info *ni = calloc(st.nodes ? st.nodes : 1, sizeof *ni);
    if (!ni) return 1;
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        if (e->node >= st.nodes) continue;
        node_info *n = &ni[e->node];
        if (e->type == SIDX_EV_BUILD_NODE) {
            n->seen = 1;
            n->parent = e->parent;
            n->first_child = UINT32_MAX;
            if (e->parent < st.nodes) {
                node_info *p = &ni[e->parent];
                if (p->nchild == 0 || e->node < p->first_child) p->first_child = e->node;
                p->nchild++;
            }
        } else if (e->type == SIDX_EV_BUILD_SPLIT) {
            n->axis = e->axis;
            n->pos = e->pos;
        } else if (e->type == SIDX_EV_BUILD_LEAF) {
            n->leaf = 1;
            n->count = e->count;
        }
    }
    /* children side by side, and the leaves' offsets in leaf order */
    int side_by_side = 1, roundtrip = 1;
    uint32_t offset = 0, inner = 0;
    uint32_t *leaf_off = calloc(st.nodes ? st.nodes : 1, sizeof *leaf_off);
    if (!leaf_off) return 1;
    for (uint32_t i = 0; i < st.nodes; ++i) {
        if (!ni[i].seen) continue;
        if (ni[i].leaf) { leaf_off[i] = offset; offset += ni[i].count; continue; }
        ++inner;
        if (ni[i].nchild != 2) side_by_side = 0;
        /* the other child must be first_child + 1 */
        uint32_t other = UINT32_MAX;
        for (uint32_t j = ni[i].first_child + 1; j < st.nodes && j <= ni[i].first_child + 1; ++j)
            if (ni[j].seen && ni[j].parent == i) other = j;
        if (other == UINT32_MAX) side_by_side = 0;
    }
    printf("== '%s': kd-tree of %u nodes (%u inner, %u leaves), %llu triangle references\n", spec, st.nodes, inner,
           st.leaves, (unsigned long long)st.prim_refs);
    printf("\n== The first nodes, as two 32-bit words each\n"
           "   inner: word 0 = split position (float);  word 1 = left child << 2 | axis (0 x, 1 y, 2 z)\n"
           "   leaf:  word 0 = triangle count;          word 1 = offset into the reference array << 2 | 3\n\n");
    int shown = 0;
    for (uint32_t i = 0; i < st.nodes && shown < 8; ++i) {
        if (!ni[i].seen) continue;
        uint32_t w0, w1;
        if (ni[i].leaf) {
            w0 = ni[i].count;
            w1 = leaf_off[i] << 2 | 3u;
        } else {
            memcpy(&w0, &ni[i].pos, sizeof w0);
            w1 = ni[i].first_child << 2 | (uint32_t)ni[i].axis;
        }
        /* decode back */
        const int is_leaf = (w1 & 3u) == 3u;
        if (is_leaf != ni[i].leaf) roundtrip = 0;
        if (!is_leaf) {
            float p;
            memcpy(&p, &w0, sizeof p);
            if (p != ni[i].pos || (int)(w1 & 3u) != ni[i].axis || (w1 >> 2) != ni[i].first_child) roundtrip = 0;
        } else if (w0 != ni[i].count || (w1 >> 2) != leaf_off[i]) {
            roundtrip = 0;
        }
        printf("  node %u: ", i);
        if (ni[i].leaf)
            printf("leaf, %u triangles from reference %u\n", ni[i].count, leaf_off[i]);
        else
            printf("inner, split %c at %g, children %u and %u\n", "xyz"[ni[i].axis], ni[i].pos, ni[i].first_child,
                   ni[i].first_child + 1);
        printf("    word 0  0x%08x  ", w0);
        bits32(w0, 0);
        printf("\n    word 1  0x%08x  ", w1);
        bits32(w1, 1);
        printf("  (low 2 bits: %u = %s)\n", w1 & 3u, is_leaf ? "leaf" : (w1 & 3u) == 0 ? "x" : (w1 & 3u) == 1 ? "y" : "z");
        ++shown;
    }
    const double compact = 8.0 * st.nodes, boxed = (8.0 + 24.0) * st.nodes;
    printf("\n== Memory\n");
    printf("  nodes x 8 bytes                  %10.1f KiB\n", compact / 1024);
    printf("  nodes x 32 bytes (+ a 24-byte box) %8.1f KiB  (the slide's 4x explosion)\n", boxed / 1024);
    printf("  references x 4 bytes             %10.1f KiB\n", 4.0 * st.prim_refs / 1024);
    printf("  the whole structure (stats)      %10.1f KiB  (also triangle copies, allocation slack)\n", st.bytes / 1024.0);
    printf("  A node needs no box: the traversal knows its cell as the ray interval [t_near, t_far].\n");
    printf("  Both children of every inner node sit side by side (ids k and k+1): %s\n", side_by_side ? "yes" : "NO");
    printf("CHECK decoded_matches=%d\n", roundtrip);
    printf("CHECK children_side_by_side=%d\n", side_by_side && inner > 0);
    free(ni);
    free(leaf_off);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(kd);
    sidx_mesh_free(&mesh);
    return 0;
}
