/* 11_bvh_build.c — checker driver: the recursive BVH build (deck 001,
 * "BVH Partitioning", "Recurse with each child node", "After re-indexing
 * (sorting) based on leaf nodes", "Edge Cases").  Reference: the
 * library's "bvh-middle" over the same mesh and leaf size, its nodes and
 * primitive order read through sidx/bvh.h.  The student's function fills
 * a node array poisoned beforehand (NaN boxes, 0xDEADBEEF words), so a
 * field it does not write shows; after it returns, every node is
 * compared in array order (depth-first pre-order, the order the nodes
 * are made in), each as NOTEs:
 *   cell[2] 0..2  its box on axis k: [t_near, t_far] = [bmin[k], bmax[k]],
 *                 count = the triangles under it (from the array's
 *                 pre-order, not the links: a marker when the nodes
 *                 make no tree or the leaves' ranges do not tile prims[])
 *   cell[2] 3     its kind: cell[1] = count_axis, count = first (a leaf)
 *   cell[2] 4     a leaf's triangle j: cell[1] = j, count = prims[first + j]
 * then every inner node's right child (cell[2] 5, count = left_or_first)
 * and last the node count and the returned root (cell[2] 6).  The
 * pre-order sequence of leaf and inner nodes fixes the tree's shape, so
 * the links come last: a node with other triangles shows first. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "sidx/bvh.h"

uint32_t bvh_build(sidx_bvh_node *nodes, uint32_t *num_nodes, uint32_t *prims, uint32_t first, uint32_t count,
                   const sidx_aabb *boxes, const sidx_vec3 *cents, uint32_t leaf_size, uint32_t max_leaf);

#define NSCENES 9
#define NLEAF 3
#define POISON 0xDEADBEEFu
#define MAX_LEAF 16u /* the library's: a node of equal centroids above it is split */
static const uint32_t leaf_sizes[NLEAF] = {3, 1, 8};
static const char *const scene_names[NSCENES] = {
    "one triangle",
    "20 triangles of five sizes, one centroid",
    "16 coincident triangles",
    "17 triangles of one centroid among 12 in a row",
    "centroids on the middle (x = 0, 2, 4, 6, 8)",
    "centroid bounds a cube (ties between axes)",
    "flat2d",
    "soup:80",
    "cornell"};

typedef struct build_case {
    sidx_mesh mesh;
    sidx_aabb *boxes;
    sidx_vec3 *cents;
    sidx_bvh_node *nodes; /* the library's tree */
    uint32_t *prims;
    uint32_t *under;      /* triangles under each node */
    uint32_t *parent;     /* each node's parent, UINT32_MAX for the root */
    uint32_t num_nodes;
    uint32_t leaf_size;
} build_case;

static build_case cases[NSCENES * NLEAF];

/* A triangle whose bounding box is centred on c: half-size s on each axis. */
static void put_tri(float *xyz, uint32_t t, float cx, float cy, float cz, float s)
{
    const float v[9] = {cx - s, cy - s, cz - s, cx + s, cy - s, cz + s, cx, cy + s, cz};
    memcpy(xyz + 9 * t, v, sizeof v);
}

static int from_tris(sidx_mesh *m, float *xyz, uint32_t n)
{
    uint32_t idx[3 * 64];
    for (uint32_t k = 0; k < 3 * n; ++k) idx[k] = k;
    return sidx_mesh_from_arrays(m, xyz, 3 * n, idx, n, NULL) == SIDX_OK ? 0 : -1;
}

static int open_scene(int s, sidx_mesh *m)
{
    float xyz[9 * 64];
    uint32_t n = 0;
    switch (s) {
    case 0: put_tri(xyz, n++, 0, 0, 0, 0.5f); break;
    case 1:
        for (int i = 0; i < 20; ++i) put_tri(xyz, n++, 5, 5, 0, 0.5f + 0.25f * (float)(i % 5));
        break;
    case 2:
        for (int i = 0; i < 16; ++i) put_tri(xyz, n++, 1, 2, 3, 1);
        break;
    case 3:
        for (int i = 0; i < 29; ++i) {
            if (i % 2 == 0 && i / 2 < 12) put_tri(xyz, n++, (float)(i / 2), 0, 0, 0.25f);
            else put_tri(xyz, n++, 20, 4, 1, 0.25f + 0.125f * (float)(i % 4));
        }
        break;
    case 4:
        for (int i = 0; i < 10; ++i) put_tri(xyz, n++, (float)(2 * (i % 5)), 0.25f * (float)(i / 5), 0, 0.5f);
        break;
    case 5: {
        const float c[8][3] = {{0, 0, 0}, {2, 2, 2}, {1, 0, 2}, {0, 2, 1}, {2, 0, 0}, {0, 1, 2}, {2, 1, 0}, {1, 2, 1}};
        for (int i = 0; i < 8; ++i) put_tri(xyz, n++, c[i][0], c[i][1], c[i][2], 0.25f);
        break;
    }
    default: return sidx_scene_open(scene_names[s], m, NULL) == SIDX_OK ? 0 : -1;
    }
    return from_tris(m, xyz, n);
}

/* Triangles under each node, from the array alone (not the links): the
 * pre-order sequence of leaves and inner nodes fixes each subtree, and
 * in pre-order the leaves' ranges tile prims[0 .. np).  Returns the index
 * after node i's subtree, or UINT32_MAX when the array ends inside it. */
static uint32_t parse(const sidx_bvh_node *nd, uint32_t n, uint32_t i, uint32_t *under, uint32_t depth)
{
    if (i >= n || depth > n) return UINT32_MAX;
    if (nd[i].count_axis & SIDX_BVH_COUNT_MASK) {
        under[i] = nd[i].count_axis & SIDX_BVH_COUNT_MASK;
        return i + 1;
    }
    const uint32_t r = parse(nd, n, i + 1, under, depth + 1);
    const uint32_t end = r == UINT32_MAX ? UINT32_MAX : parse(nd, n, r, under, depth + 1);
    if (end != UINT32_MAX) under[i] = under[i + 1] + under[r];
    return end;
}

#define UNDER_NO_TREE UINT32_MAX       /* the nodes do not make one tree */
#define UNDER_NO_TILE (UINT32_MAX - 1) /* the leaves' ranges do not tile prims[] */
#define UNDER_NO_ORDER (UINT32_MAX - 2) /* they do, but not in the order the nodes are made */

/* under[i] for the n nodes (the markers above when it is not defined). */
static void count_under(const sidx_bvh_node *nd, uint32_t n, uint32_t np, uint32_t *under)
{
    for (uint32_t i = 0; i < n; ++i) under[i] = UNDER_NO_TREE;
    if (n == 0 || parse(nd, n, 0, under, 0) != n) {
        for (uint32_t i = 0; i < n; ++i) under[i] = UNDER_NO_TREE;
        return;
    }
    uint64_t next = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (!(nd[i].count_axis & SIDX_BVH_COUNT_MASK)) continue;
        if (nd[i].left_or_first != next) next = UINT64_MAX;
        if (next != UINT64_MAX) next += nd[i].count_axis & SIDX_BVH_COUNT_MASK;
    }
    if (next == np) return;
    /* Not in pre-order: do the ranges, taken by first, still tile prims[]?
     * (then the children were made in another order) */
    uint64_t at = 0;
    for (int found = 1; found && at < np;) {
        found = 0;
        for (uint32_t i = 0; i < n && !found; ++i)
            if ((nd[i].count_axis & SIDX_BVH_COUNT_MASK) && nd[i].left_or_first == at) {
                at += nd[i].count_axis & SIDX_BVH_COUNT_MASK;
                found = 1;
            }
    }
    for (uint32_t i = 0; i < n; ++i) under[i] = at == np ? UNDER_NO_ORDER : UNDER_NO_TILE;
}

static void *dup(const void *p, size_t n)
{
    void *q = malloc(n ? n : 1);
    if (q && n) memcpy(q, p, n);
    return q;
}

static int setup(void)
{
    for (int s = 0; s < NSCENES; ++s)
        for (int l = 0; l < NLEAF; ++l) {
            build_case *c = &cases[s * NLEAF + l];
            if (open_scene(s, &c->mesh) != 0) return -1;
            const uint32_t n = c->mesh.num_triangles;
            c->leaf_size = leaf_sizes[l];
            c->boxes = malloc(n * sizeof *c->boxes);
            c->cents = malloc(n * sizeof *c->cents);
            if (!c->boxes || !c->cents) return -1;
            for (uint32_t i = 0; i < n; ++i) {
                c->boxes[i] = sidx_mesh_triangle_bounds(&c->mesh, i);
                c->cents[i] = sidx_aabb_centroid(c->boxes[i]);
            }
            sidx_build_options bo;
            memset(&bo, 0, sizeof bo);
            bo.leaf_size = c->leaf_size;
            bo.threads = 1;
            sidx_accel *a = NULL;
            if (sidx_accel_build("bvh-middle", &c->mesh, &bo, &a, NULL) != SIDX_OK) return -1;
            const sidx_bvh_node *nd;
            const uint32_t *pr;
            uint32_t np = 0;
            if (sidx_bvh_nodes(a, &nd, &c->num_nodes, NULL) != SIDX_OK ||
                sidx_bvh_prims(a, &pr, &np, NULL) != SIDX_OK) {
                sidx_accel_destroy(a);
                return -1;
            }
            c->nodes = dup(nd, c->num_nodes * sizeof *nd);
            c->prims = dup(pr, np * sizeof *pr);
            c->under = malloc(c->num_nodes * sizeof *c->under);
            c->parent = malloc(c->num_nodes * sizeof *c->parent);
            sidx_accel_destroy(a);
            if (!c->nodes || !c->prims || !c->under || !c->parent) return -1;
            count_under(c->nodes, c->num_nodes, n, c->under);
            c->parent[0] = UINT32_MAX;
            for (uint32_t k = 0; k < c->num_nodes; ++k)
                if (!sidx_bvh_is_leaf(&c->nodes[k])) c->parent[k + 1] = c->parent[c->nodes[k].left_or_first] = k;
        }
    return 0;
}

static void teardown(void)
{
    for (size_t i = 0; i < NSCENES * NLEAF; ++i) {
        free(cases[i].boxes);
        free(cases[i].cents);
        free(cases[i].nodes);
        free(cases[i].prims);
        free(cases[i].under);
        free(cases[i].parent);
        sidx_mesh_free(&cases[i].mesh);
    }
}

static size_t num_cases(void) { return NSCENES * NLEAF; }

static const char *case_rules(size_t i);

static void describe(size_t i, ex_case_info *out)
{
    const build_case *c = &cases[i];
    snprintf(out->name, sizeof out->name, "scene %s, leaf size %u", scene_names[i / NLEAF], c->leaf_size);
    snprintf(out->what, sizeof out->what,
             "%u triangles, leaf_size = %u, max_leaf = %u; the library's tree has %u nodes", c->mesh.num_triangles,
             c->leaf_size, MAX_LEAF, c->num_nodes);
    out->hint = NULL;
    out->rules = case_rules(i);
}

static void note(const sidx_hook *h, int32_t node, int32_t c1, int32_t kind, uint32_t count, float lo, float hi)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.structure = "bvh";
    e.cell[0] = node;
    e.cell[1] = c1;
    e.cell[2] = kind;
    e.count = count;
    e.t_near = lo;
    e.t_far = hi;
    sidx_hook_emit(h, &e);
}

/* The tree as the NOTEs above; n nodes, prims of np entries, root as returned. */
static void emit(const sidx_hook *h, const sidx_bvh_node *nd, uint32_t n, const uint32_t *prims, uint32_t np,
                 uint32_t root)
{
    uint32_t *under = malloc((n ? n : 1) * sizeof *under);
    if (!under) return;
    count_under(nd, n, np, under);
    for (uint32_t i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) note(h, (int32_t)i, 0, k, under[i], nd[i].bmin[k], nd[i].bmax[k]);
        const uint32_t ca = nd[i].count_axis, cnt = ca & SIDX_BVH_COUNT_MASK, first = nd[i].left_or_first;
        note(h, (int32_t)i, (int32_t)ca, 3, cnt ? first : 0, 0, 0);
        for (uint32_t j = 0; j < cnt && j < np; ++j)
            note(h, (int32_t)i, (int32_t)j, 4, first < np && j < np - first ? prims[first + j] : UINT32_MAX, 0, 0);
    }
    for (uint32_t i = 0; i < n; ++i)
        if (!(nd[i].count_axis & SIDX_BVH_COUNT_MASK)) note(h, (int32_t)i, 0, 5, nd[i].left_or_first, 0, 0);
    note(h, -1, (int32_t)root, 6, n, 0, 0);
    free(under);
}

static void reference(size_t i, const sidx_hook *h)
{
    const build_case *c = &cases[i];
    emit(h, c->nodes, c->num_nodes, c->prims, c->mesh.num_triangles, 0);
}

static void student(size_t i, const sidx_hook *h)
{
    const build_case *c = &cases[i];
    const uint32_t np = c->mesh.num_triangles, cap = 2 * np - 1;
    sidx_bvh_node *nd = malloc(cap * sizeof *nd);
    uint32_t *prims = malloc(np * sizeof *prims);
    if (!nd || !prims) {
        free(nd);
        free(prims);
        return;
    }
    for (uint32_t k = 0; k < cap; ++k) {
        for (int a = 0; a < 3; ++a) nd[k].bmin[a] = nd[k].bmax[a] = NAN;
        nd[k].left_or_first = nd[k].count_axis = POISON;
    }
    for (uint32_t k = 0; k < np; ++k) prims[k] = k;
    uint32_t n = 0;
    const uint32_t root = bvh_build(nd, &n, prims, 0, np, c->boxes, c->cents, c->leaf_size, MAX_LEAF);
    emit(h, nd, n > cap ? cap : n, prims, np, root);
    free(nd);
    free(prims);
}

/* The hand-out's rules, in its order. */
enum { R_LAYOUT, R_BOX, R_LEAF, R_EQ_LEAF, R_EQ_HALVE, R_AXIS, R_MIDDLE, R_WALK, R_RANGE, R_LINKS, NRULES };
static const ex_rule rules[NRULES] = {
    {"node-layout", "each node takes nodes[*num_nodes] and counts it before its children (depth-first pre-order); "
     "count_axis is a leaf's count, or an inner node's axis << 30; the root's index is returned",
     "\"Recurse with each child node\": each node takes the slot nodes[*num_nodes] and counts it (++*num_nodes) "
     "before its children are built; a leaf's count_axis is its count, an inner node's axis << 30 (a count of "
     "0); return the index of the subtree's root"},
    {"box-union", "a node's box is the union of its triangles' boxes",
     "a node's box is the union of its triangles' boxes (boxes[prims[i]] for i in first .. first + count), "
     "not of their centroids: bmin[] and bmax[] on all three axes"},
    {"leaf-inclusive", "a leaf when count <= leaf_size",
     "a node becomes a leaf when it holds count <= leaf_size triangles (at or below the leaf size), and only "
     "then (or for equal centroids): left_or_first = first, count_axis = count"},
    {"equal-leaf", "every centroid equal (no extent on any axis) and count <= max_leaf: a leaf",
     "\"Edge Cases: primitives with same centroid\": no plane separates equal centroids; with count <= max_leaf "
     "the node is a leaf"},
    {"equal-halve", "every centroid equal and count > max_leaf: prims[first .. first + count/2) to the left, as it "
     "stands (axis 0)",
     "\"Edge Cases: primitives with same centroid\": no plane separates them, so with count > max_leaf the range "
     "is split in half as it stands: prims[first .. first + count/2) left, the rest right, axis 0"},
    {"axis-largest", "the split axis is the centroid bounds' axis of largest extent (sidx_aabb_max_axis: a tie goes "
     "to x, then y)",
     "the split axis is the one of largest extent of the centroid bounds (sidx_aabb_max_axis: ties go to x, "
     "then y), stored as axis << 30 with a count of 0"},
    {"split-middle", "the split at pos = 0.5f * (min + max) of the centroid bounds; a centroid < pos goes left",
     "\"Split in the middle\": partition prims[first .. first + count) in place at pos = 0.5f * (min + max) of the "
     "CENTROID bounds on their axis of largest extent: centroid < pos stays on the left (++i), any other is "
     "swapped with prims[--j]; the left child gets prims[first .. i), the right child the rest"},
    {"partition-walk", "one walk from the front: i = first, j = first + count; < pos stays (++i), any other is "
     "swapped with prims[--j]",
     "\"After re-indexing (sorting) based on leaf nodes\": the leaf's triangles are prims[first .. first + count) "
     "as the partition leaves them: one walk from the front, a triangle going right swapped with prims[--j]"},
    {"leaf-range", "a leaf stores left_or_first = first and count_axis = count",
     "\"Only need to store 2 integers per leaf node!\": a leaf stores left_or_first = first, its first index into "
     "prims[], and count_axis = count, so that the leaves, in the order they are made, cover prims[0 .. n) one "
     "after another"},
    {"child-links", "the left child is built first (the node after its parent), then the right one, whose index "
     "goes in left_or_first",
     "\"Recurse with each child node\": the node takes its slot before its children, the left child is built first "
     "and is the next node (i + 1), and the inner node stores the index its right child's build returned in "
     "left_or_first"},
};

/* Whether node i of the library's tree holds triangles of one centroid. */
static int equal_centroids(const build_case *c, uint32_t i, uint32_t first)
{
    sidx_aabb cb = sidx_aabb_empty();
    for (uint32_t k = 0; k < c->under[i]; ++k) cb = sidx_aabb_grow(cb, c->cents[c->prims[first + k]]);
    return !(cb.max.x > cb.min.x) && !(cb.max.y > cb.min.y) && !(cb.max.z > cb.min.z);
}

/* The first triangle index under node i of the library's tree. */
static uint32_t first_under(const build_case *c, uint32_t i)
{
    while (!sidx_bvh_is_leaf(&c->nodes[i])) i = i + 1;
    return c->nodes[i].left_or_first;
}

/* The rules case i tests, from the library's tree: always the layout, the
 * boxes and the leaves' ranges; a leaf of exactly leaf_size triangles;
 * a leaf or an inner node of equal centroids; an inner node split by a
 * plane (its axis, the middle, the walk, the links). */
static const char *case_rules(size_t i)
{
    static char ids[NSCENES * NLEAF][200];
    const build_case *c = &cases[i];
    if (ids[i][0]) return ids[i];
    int has[NRULES] = {0};
    has[R_LAYOUT] = has[R_BOX] = has[R_RANGE] = 1;
    for (uint32_t k = 0; k < c->num_nodes; ++k) {
        const int eq = equal_centroids(c, k, first_under(c, k));
        if (sidx_bvh_is_leaf(&c->nodes[k])) {
            has[R_LEAF] |= c->under[k] == c->leaf_size;
            has[R_EQ_LEAF] |= eq && c->under[k] > c->leaf_size;
        } else if (eq) {
            has[R_EQ_HALVE] = has[R_LINKS] = 1;
        } else {
            has[R_AXIS] = has[R_MIDDLE] = has[R_WALK] = has[R_LINKS] = 1;
        }
    }
    for (int r = 0; r < NRULES; ++r)
        if (has[r]) {
            const size_t len = strlen(ids[i]);
            snprintf(ids[i] + len, sizeof ids[i] - len, "%s%s", len ? " " : "", rules[r].id);
        }
    return ids[i];
}

/* What differs decides: other triangles under a node (the parent's
 * partition), another box over the same ones, another kind of node (the
 * leaf rule or the equal-centroid rule, by what the library's node is),
 * another axis, the leaf's range or order, the links, the count. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const build_case *c = &cases[i];
    if (!ref || !stu) return rules[R_LAYOUT].hint;
    if (ref->cell[2] == 6 || stu->cell[2] == 6 || ref->cell[0] != stu->cell[0]) return rules[R_LAYOUT].hint;
    const uint32_t node = (uint32_t)ref->cell[0];
    if (node >= c->num_nodes) return rules[R_LAYOUT].hint;
    switch (ref->cell[2]) {
    case 0:
    case 1:
    case 2:
        if (stu->count == UNDER_NO_TREE) return rules[R_LAYOUT].hint;
        if (stu->count == UNDER_NO_TILE) return rules[R_RANGE].hint;
        if (stu->count == UNDER_NO_ORDER) return rules[R_LINKS].hint;
        if (stu->count == ref->count) return rules[R_BOX].hint;
        /* other triangles: the parent's split put them there */
        if (c->parent[node] != UINT32_MAX && equal_centroids(c, c->parent[node], first_under(c, c->parent[node])))
            return rules[R_EQ_HALVE].hint;
        return rules[R_MIDDLE].hint;
    case 3: {
        const uint32_t sca = (uint32_t)stu->cell[1], rca = (uint32_t)ref->cell[1];
        const int sleaf = (sca & SIDX_BVH_COUNT_MASK) != 0, rleaf = (rca & SIDX_BVH_COUNT_MASK) != 0;
        const int eq = equal_centroids(c, node, first_under(c, node));
        if (rleaf && sleaf) return rules[R_RANGE].hint;
        if (rleaf) return c->under[node] <= c->leaf_size ? rules[R_LEAF].hint : rules[R_EQ_LEAF].hint;
        if (sleaf) return eq ? rules[R_EQ_HALVE].hint : rules[R_LEAF].hint;
        return eq ? rules[R_EQ_HALVE].hint : rules[R_AXIS].hint;
    }
    case 4: return rules[R_WALK].hint;
    case 5: return rules[R_LINKS].hint;
    default: return rules[R_LAYOUT].hint;
    }
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    const uint32_t ca = (uint32_t)e->cell[1];
    switch (e->cell[2]) {
    case 0:
    case 1:
    case 2:
        if (e->count >= UNDER_NO_ORDER)
            snprintf(buf, size, "node %d  %c in [%g, %g]  (%s)", e->cell[0], "xyz"[e->cell[2]], (double)e->t_near,
                     (double)e->t_far,
                     e->count == UNDER_NO_TILE    ? "the leaves' (first, count) do not tile prims[] in order"
                     : e->count == UNDER_NO_ORDER ? "the leaves tile prims[], but not in the order the nodes are made"
                                               : "the nodes in pre-order do not make one tree");
        else
            snprintf(buf, size, "node %d  %c in [%g, %g]  (%u triangles under it)", e->cell[0], "xyz"[e->cell[2]],
                     (double)e->t_near, (double)e->t_far, e->count);
        return 1;
    case 3:
        if (ca == POISON)
            snprintf(buf, size, "node %d  count_axis never written (0x%08X)", e->cell[0], ca);
        else if (ca & SIDX_BVH_COUNT_MASK)
            snprintf(buf, size, "node %d  leaf: first %u, count %u", e->cell[0], e->count, ca & SIDX_BVH_COUNT_MASK);
        else
            snprintf(buf, size, "node %d  inner: split on %c", e->cell[0], "xyzw"[(ca >> 30) & 3]);
        return 1;
    case 4: snprintf(buf, size, "node %d  leaf triangle %d: prims[first + %d] = %u", e->cell[0], e->cell[1], e->cell[1],
                     e->count); return 1;
    case 5: snprintf(buf, size, "node %d  inner: children %d and %u", e->cell[0], e->cell[0] + 1, e->count); return 1;
    case 6: snprintf(buf, size, "%u nodes written, root %d returned", e->count, e->cell[1]); return 1;
    default: return 0;
    }
}

const ex_driver ex_driver_this = {
    "11_bvh_build",
    "the recursive BVH build: partition in the middle, leaves, equal centroids",
    "deck 001, \"BVH Partitioning\" (\"Split in the middle\"), \"Recurse with each child node\", \"Edge Cases\" "
    "(\"primitives with same centroid\")",
    setup, num_cases, describe, reference, student, hint, teardown, format, rules, NRULES,
};
