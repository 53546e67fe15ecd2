/* layout.c — what a bvh8 ray touches in memory on the height field of
 * `sidx-bench scale --scene heightfield` (docs/performance.md, "Node order
 * at scale").  Not part of the build; compile and run it by hand:
 *
 *   cc -std=gnu11 -O2 -Ilib/include -Ilib -Itests tests/bench/probe/layout.c \
 *      tests/common/testkit.c build/lib/libsidx.a -lm -pthread -o layout
 *   ./layout D primary|diffuse N        per ray: distinct 64-byte lines,
 *       4 KB pages and 2 MB pages of nodes and blocks (from the traced
 *       walk's NODE_ENTER ids, mapped to where they are stored)
 *   valgrind --tool=callgrind --cache-sim=yes --LL=33554432,16,64 \
 *       --instr-atstart=no ./layout D primary|diffuse N cg
 *       the untraced walk only: 20000 other rays of the set warm the
 *       caches, then N rays are counted (instructions, D1 and LL misses)
 *
 * D is the detail of the built-in scene heightfield (724: 1M, 1448:
 * 4.2M, 2896: 16.8M triangles); the rays are every (100000 / N)-th of the scale command's
 * 100000.  SIDX_WIDE_ORDER=depth-first|treelets picks the node order. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <valgrind/callgrind.h>
#include "sidx/sidx.h"
#include "bvh_wide_internal.h"
#include "common/testkit.h"
typedef struct probe {
    const wide_bvh *w;
    uint32_t *map; /* event id -> storage index (node) or first block (leaf) */
    uintptr_t *seen; size_t ns;
    uintptr_t *seen2; size_t ns2;
    uintptr_t *lines; size_t nl;
} probe;
static void add(uintptr_t *arr, size_t *n, uintptr_t v) { for (size_t i = 0; i < *n; ++i) if (arr[i] == v) return; arr[(*n)++] = v; }
static void touch(probe *p, const void *a, size_t bytes)
{
    for (uintptr_t x = (uintptr_t)a & ~(uintptr_t)63; x < (uintptr_t)a + bytes; x += 64) {
        add(p->lines, &p->nl, x); add(p->seen, &p->ns, x >> 12); add(p->seen2, &p->ns2, x >> 21);
    }
}
static void fn(const sidx_event *ev, void *u)
{
    probe *p = u;
    if (ev->type != SIDX_EV_NODE_ENTER) return;
    const wide_bvh *w = p->w;
    if (ev->node < w->num_inner) touch(p, wide_node(w, p->map[ev->node]), 8u * 8u * 4u);
    else {
        const wide_tri4 *b = w->blocks + p->map[ev->node];
        for (;; ++b) { touch(p, b, sizeof *b); if (b->prim[0] & WIDE_LAST_BLOCK) break; }
    }
}
int main(int argc, char **argv)
{
    const uint32_t d = (uint32_t)atoi(argv[1]);
    const int diffuse = argc > 2 && !strcmp(argv[2], "diffuse");
    const size_t n = argc > 3 ? (size_t)atol(argv[3]) : 2000;
    const int cg = argc > 4 && !strcmp(argv[4], "cg");
    sidx_mesh m; sidx_error err;
    /* the scale command's height field: the built-in scene heightfield:D */
    if (sidx_scene_make("heightfield", d, &m, &err) != SIDX_OK) { fprintf(stderr, "%s\n", err.message); return 1; }
    sidx_accel *a = NULL;
    if (sidx_accel_build("bvh8", &m, NULL, &a, &err) != SIDX_OK) { fprintf(stderr, "%s\n", err.message); return 1; }
    tk_rayrec *rec = malloc(n * sizeof *rec);
    /* the scale command's rays: 100000 of them, every 100000/n-th */
    const size_t N = 100000;
    tk_rayrec *all = malloc(N * sizeof *all);
    tk_make_rays(&m, diffuse ? TK_RAYS_DIFFUSE : TK_RAYS_PRIMARY, N, 7, all);
    for (size_t i = 0; i < n; ++i) rec[i] = all[i * (N / n)];
    sidx_ray *r = malloc(n * sizeof *r);
    for (size_t i = 0; i < n; ++i) sidx_ray_init(&r[i], sidx_v3(rec[i].o[0], rec[i].o[1], rec[i].o[2]), sidx_v3(rec[i].d[0], rec[i].d[1], rec[i].d[2]), rec[i].tmin, rec[i].tmax);
    const wide_bvh *w = a->impl;
    if (cg) {
        sidx_hit h; double s = 0;
        /* warm the caches with 20000 other rays of the same set (every 5th, offset 2: never a measured one) */
        sidx_ray *wr = malloc(20000 * sizeof *wr);
        for (size_t i = 0; i < 20000; ++i) sidx_ray_init(&wr[i], sidx_v3(all[5 * i + 2].o[0], all[5 * i + 2].o[1], all[5 * i + 2].o[2]), sidx_v3(all[5 * i + 2].d[0], all[5 * i + 2].d[1], all[5 * i + 2].d[2]), all[5 * i + 2].tmin, all[5 * i + 2].tmax);
        CALLGRIND_START_INSTRUMENTATION;
        for (size_t i = 0; i < 20000; ++i) { sidx_accel_intersect(a, &wr[i], NULL, &h); s += h.t; }
        CALLGRIND_ZERO_STATS;
        for (size_t i = 0; i < n; ++i) { sidx_accel_intersect(a, &r[i], NULL, &h); s += h.t; }
        CALLGRIND_STOP_INSTRUMENTATION;
        printf("%g\n", s);
        return 0;
    }
    probe p = {w, malloc(((size_t)w->num_inner + w->num_leaves) * 4), malloc(1 << 20), 0, malloc(1 << 20), 0, malloc(1 << 22), 0};
    p.map[0] = 0;
    for (uint32_t i = 0; i < w->num_inner; ++i) {
        const float *nd = wide_node(w, i);
        for (uint32_t s = 0; s < 8; ++s) {
            const uint32_t c = wide_child(nd, 8)[s];
            if (c == WIDE_EMPTY) continue;
            p.map[wide_id(nd, 8)[s]] = c & ~WIDE_LEAF_BIT;
        }
    }
    const sidx_hook hook = {fn, &p, 0};
    const sidx_query q = {0, SIDX_TRAVERSE_DEFAULT, &hook, 0};
    double pg = 0, pg2 = 0, ln = 0;
    for (size_t i = 0; i < n; ++i) {
        sidx_hit h;
        p.ns = p.ns2 = p.nl = 0;
        sidx_accel_intersect(a, &r[i], &q, &h);
        pg += p.ns; pg2 += p.ns2; ln += p.nl;
    }
    printf("inner %u blocks %u: per ray %.1f lines, %.2f 4K pages, %.2f 2M pages\n", w->num_inner, w->num_blocks, ln / n, pg / n, pg2 / n);
    return 0;
}
