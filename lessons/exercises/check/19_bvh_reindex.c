/* 19_bvh_reindex.c — checker driver: the BVH's leaf re-indexing (deck
 * 001, "What About Ordering?", "After re-indexing (sorting) based on leaf
 * nodes").  Reference: the library's own layout of a built binary BVH
 * (sidx_bvh_nodes, sidx_bvh_prims: the build and the reinsertion pass
 * both leave each leaf's triangles contiguous, leaf after leaf in node
 * order).  The student gets the same tree whose leaves point at their
 * triangle lists in `lists`, one block per leaf, stored in another order
 * (reversed, breadth first, shuffled, with unused slots); the driver
 * moves whole blocks, it never computes a layout.  Compared, node by node
 * in array order: the node's fields (NOTE kind 0: cell[1] = count_axis,
 * count = left_or_first), its box (kinds 1-3, one per axis: [t_near,
 * t_far] = [bmin, bmax]), for a leaf the triangle in each of its slots
 * (kind 4: cell[1] = the slot's place in the leaf, count = the
 * triangle); then the number of slots written past the end of prims,
 * which must be 0 (kind 5), and the return value (kind 6). */
#include <stdlib.h>
#include <string.h>
#include "check.h"
#include "sidx/bvh.h"

uint32_t bvh_reindex(sidx_bvh_node *nodes, uint32_t num_nodes, const uint32_t *lists, uint32_t *prims);

#define NTREES 6
#define NARR 5
#define UNUSED 0xfffffffeu /* an unused slot of lists */
#define UNTOUCHED 0xffffffffu /* prims before the student writes */

static const char *const tree_builder[NTREES] = {"bvh", "bvh", "bvh", "bvh", "bvh-median", "bvh"};
static const char *const tree_scene[NTREES] = {"one triangle", "flat2d", "soup:200", "cornell", "icosphere:2",
                                               "soup:200"};
static const char *const tree_what[NTREES] = {"the root is a leaf", "binned SAH", "binned SAH",
                                              "binned SAH, equal centroids", "median splits",
                                              "one triangle per leaf, reinsertion pass"};
static const char *const arr_names[NARR] = {"lists already in leaf order", "lists in reverse leaf order",
                                            "lists breadth first (level by level)", "lists shuffled",
                                            "lists shuffled, unused slots between them"};

typedef struct reindex_case {
    sidx_bvh_node *before, *after; /* the tree as given; the library's layout */
    uint32_t *lists, *prims;       /* the blocks as given; the library's prims */
    uint32_t num_nodes, num_prims, num_lists;
} reindex_case;

static reindex_case cases[NTREES * NARR];

static int open_scene(int s, sidx_mesh *m)
{
    if (s == 0) {
        const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        const uint32_t idx[3] = {0, 1, 2};
        return sidx_mesh_from_arrays(m, xyz, 3, idx, 1, NULL) == SIDX_OK ? 0 : -1;
    }
    return sidx_scene_open(tree_scene[s], m, NULL) == SIDX_OK ? 0 : -1;
}

static void *dup(const void *p, size_t n)
{
    void *q = malloc(n ? n : 1);
    if (q && n) memcpy(q, p, n);
    return q;
}

/* The leaves of nodes[] in the order arrangement a stores their blocks. */
static uint32_t block_order(const sidx_bvh_node *nodes, uint32_t nn, int a, uint32_t *out, uint32_t *st)
{
    uint32_t nl = 0;
    if (a == 2) { /* breadth first: a queue of nodes, children left then right */
        uint32_t *queue = malloc(nn * sizeof *queue), head = 0, tail = 0;
        if (!queue) return 0;
        queue[tail++] = 0;
        while (head < tail) {
            const uint32_t i = queue[head++];
            if (sidx_bvh_is_leaf(&nodes[i])) {
                out[nl++] = i;
            } else if (tail + 2 <= nn) {
                queue[tail++] = i + 1;
                queue[tail++] = nodes[i].left_or_first;
            }
        }
        free(queue);
        return nl;
    }
    for (uint32_t i = 0; i < nn; ++i)
        if (sidx_bvh_is_leaf(&nodes[i])) out[nl++] = i;
    if (a == 1)
        for (uint32_t k = 0; k < nl / 2; ++k) {
            const uint32_t tmp = out[k];
            out[k] = out[nl - 1 - k];
            out[nl - 1 - k] = tmp;
        }
    if (a >= 3) /* Fisher-Yates with the battery's generator */
        for (uint32_t k = nl; k > 1; --k) {
            const uint32_t j = (uint32_t)(ex_rand(st) * (float)k) % k;
            const uint32_t tmp = out[k - 1];
            out[k - 1] = out[j];
            out[j] = tmp;
        }
    return nl;
}

static int setup(void)
{
    for (int s = 0; s < NTREES; ++s) {
        sidx_mesh m;
        if (open_scene(s, &m) != 0) return -1;
        sidx_build_options bo;
        memset(&bo, 0, sizeof bo);
        if (s == 5) {
            bo.leaf_size = 1;
            bo.optimize_ms = 1e6f; /* a budget the pass never reaches: the same tree every time */
        }
        sidx_accel *acc = NULL;
        const sidx_bvh_node *nodes;
        const uint32_t *prims;
        uint32_t nn = 0, np = 0;
        if (sidx_accel_build(tree_builder[s], &m, &bo, &acc, NULL) != SIDX_OK ||
            sidx_bvh_nodes(acc, &nodes, &nn, NULL) != SIDX_OK || sidx_bvh_prims(acc, &prims, &np, NULL) != SIDX_OK) {
            sidx_accel_destroy(acc);
            sidx_mesh_free(&m);
            return -1;
        }
        for (int a = 0; a < NARR; ++a) {
            reindex_case *c = &cases[s * NARR + a];
            uint32_t st = 1919u + 7u * (uint32_t)(s * NARR + a);
            c->num_nodes = nn;
            c->num_prims = np;
            c->after = dup(nodes, nn * sizeof *nodes);
            c->prims = dup(prims, np * sizeof *prims);
            c->before = dup(nodes, nn * sizeof *nodes);
            uint32_t *order = malloc((nn + 1) * sizeof *order);
            /* room for up to 3 unused slots before each block, and slack past the end */
            c->lists = malloc((4 * (size_t)np + 8) * sizeof *c->lists);
            if (!c->after || !c->prims || !c->before || !order || !c->lists) {
                free(order);
                return -1;
            }
            const uint32_t nl = block_order(nodes, nn, a, order, &st);
            uint32_t at = 0;
            for (uint32_t b = 0; b < nl; ++b) {
                const sidx_bvh_node *leaf = &nodes[order[b]];
                if (a == 4)
                    for (uint32_t gap = 1 + (uint32_t)(ex_rand(&st) * 3.0f) % 3; gap > 0; --gap) c->lists[at++] = UNUSED;
                c->before[order[b]].left_or_first = at;
                memcpy(c->lists + at, prims + leaf->left_or_first, sidx_bvh_count(leaf) * sizeof *prims);
                at += sidx_bvh_count(leaf);
            }
            for (int k = 0; k < 8; ++k) c->lists[at + (uint32_t)k] = UNUSED;
            c->num_lists = at;
            free(order);
        }
        sidx_accel_destroy(acc);
        sidx_mesh_free(&m);
    }
    return 0;
}

static void teardown(void)
{
    for (size_t i = 0; i < NTREES * NARR; ++i) {
        free(cases[i].before);
        free(cases[i].after);
        free(cases[i].lists);
        free(cases[i].prims);
    }
}

static size_t num_cases(void) { return NTREES * NARR; }

static void describe(size_t i, ex_case_info *out)
{
    const reindex_case *c = &cases[i];
    const int s = (int)(i / NARR), a = (int)(i % NARR);
    snprintf(out->name, sizeof out->name, "%s over %s (%s), %s", tree_builder[s], tree_scene[s], tree_what[s],
             arr_names[a]);
    uint32_t leaves = 0;
    for (uint32_t k = 0; k < c->num_nodes; ++k) leaves += sidx_bvh_is_leaf(&c->before[k]) ? 1u : 0u;
    snprintf(out->what, sizeof out->what, "%u nodes, %u leaves, %u triangle references in %u slots of lists",
             c->num_nodes, leaves, c->num_prims, c->num_lists);
    out->hint = NULL;
    /* one triangle: the root is a leaf, no inner node to leave alone */
    out->rules = s == 0 ? "array-order copy-block leaf-own-order first-running-sum count-kept boxes-kept return-count "
                          "nothing-past"
                        : "array-order copy-block leaf-own-order first-running-sum count-kept boxes-kept "
                          "inner-untouched return-count nothing-past";
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

/* Every node in array order, then the slots written past prims[n - 1]
 * and the return value.  prims has `size` entries, n of them in use; a
 * leaf's slots are read at its own (first, count), within the size. */
static void emit(const sidx_hook *h, const sidx_bvh_node *nodes, uint32_t nn, const uint32_t *prims, uint32_t n,
                 size_t size, uint32_t ret)
{
    for (uint32_t i = 0; i < nn; ++i) {
        const sidx_bvh_node *d = &nodes[i];
        note(h, (int32_t)i, (int32_t)d->count_axis, 0, d->left_or_first, 0.0f, 0.0f);
        for (int k = 0; k < 3; ++k) note(h, (int32_t)i, 0, 1 + k, 0, d->bmin[k], d->bmax[k]);
        if (!sidx_bvh_is_leaf(d)) continue;
        for (uint32_t k = 0; k < sidx_bvh_count(d); ++k) {
            const uint64_t at = (uint64_t)d->left_or_first + k;
            note(h, (int32_t)i, (int32_t)k, 4, at < size ? prims[at] : UNTOUCHED, 0.0f, 0.0f);
        }
    }
    uint32_t past = 0;
    for (size_t k = n; k < size; ++k) past += prims[k] != UNTOUCHED;
    note(h, -1, 0, 5, past, 0.0f, 0.0f);
    note(h, -1, 0, 6, ret, 0.0f, 0.0f);
}

static void reference(size_t i, const sidx_hook *h)
{
    const reindex_case *c = &cases[i];
    uint32_t *prims = malloc(((size_t)c->num_prims + 1) * sizeof *prims);
    if (!prims) return;
    memcpy(prims, c->prims, c->num_prims * sizeof *prims);
    prims[c->num_prims] = UNTOUCHED;
    emit(h, c->after, c->num_nodes, prims, c->num_prims, (size_t)c->num_prims + 1, c->num_prims);
    free(prims);
}

/* The student's tree is followed by one spare node, a leaf of one
 * triangle (lists[0]), and prims by as many spare slots as lists has
 * (and 8 more): a walk past num_nodes, a copy past a leaf's count or a
 * copy to a leaf's old place writes where the check sees it. */
static void student(size_t i, const sidx_hook *h)
{
    const reindex_case *c = &cases[i];
    sidx_bvh_node *nodes = malloc(((size_t)c->num_nodes + 1) * sizeof *nodes);
    const size_t size = (size_t)c->num_prims + c->num_lists + 8;
    uint32_t *prims = malloc(size * sizeof *prims);
    uint32_t *lists = dup(c->lists, ((size_t)c->num_lists + 8) * sizeof *lists);
    if (nodes && prims && lists) {
        memcpy(nodes, c->before, c->num_nodes * sizeof *nodes);
        memset(&nodes[c->num_nodes], 0, sizeof *nodes);
        nodes[c->num_nodes].count_axis = 1;
        for (size_t k = 0; k < size; ++k) prims[k] = UNTOUCHED;
        const uint32_t ret = bvh_reindex(nodes, c->num_nodes, lists, prims);
        emit(h, nodes, c->num_nodes, prims, c->num_prims, size, ret);
    }
    free(nodes);
    free(prims);
    free(lists);
}

/* The hand-out's rules, in its order. */
enum { R_ORDER, R_COPY, R_OWN, R_FIRST, R_COUNT, R_BOX, R_LEAF, R_RETURN, R_PAST, NRULES };
static const ex_rule rules[NRULES] = {
    {"array-order", "the nodes are walked in array order 0, 1, 2, ...: the leaves' layout order",
     "walk the nodes in array order, 0, 1, 2, ... (the order the leaves are laid out, and the order a depth-first "
     "traversal meets them): the first leaf of the array gets prims[0 ..]"},
    {"copy-block", "each leaf's block lists[old first .. old first + count) goes to the next free slots of prims",
     "walk the nodes in array order (the leaves' layout order) and copy each leaf's block, lists[old first .. "
     "old first + count), to the next free slots of prims"},
    {"leaf-own-order", "a leaf's triangles are copied in the leaf's own order",
     "copy each leaf's triangles in the leaf's own order: prims[first + k] = lists[old first + k]"},
    {"first-running-sum", "a leaf's new left_or_first is the number of triangles of the leaves before it",
     "\"After re-indexing (sorting) based on leaf nodes ... Only need to store 2 integers per leaf node!\": a "
     "leaf's new first is where its block starts in prims, the number of triangles of the leaves before it in "
     "the node array (a running sum of their counts)"},
    {"count-kept", "a leaf's count (count_axis) stays", "a leaf keeps its count (count_axis): only its first changes"},
    {"boxes-kept", "every node's box (bmin, bmax) stays",
     "re-indexing moves triangle references, not boxes: bmin and bmax stay"},
    {"inner-untouched", "only leaves (sidx_bvh_is_leaf) change; an inner node's left_or_first stays the right "
     "child's index",
     "the inner nodes stay as they are: their left_or_first is the right child's index, not a first; only a "
     "leaf (sidx_bvh_is_leaf, which masks count_axis: an inner node's count_axis holds its axis << 30, not 0) "
     "gets a new first"},
    {"return-count", "the return value is the number of entries written to prims, the sum of the leaves' counts",
     "return the number of entries written to prims: the sum of the leaves' counts"},
    {"nothing-past", "nothing is written past prims[sum of the counts - 1]",
     "write exactly one slot per triangle reference, prims[0 .. sum of the counts): nothing past the end"},
};

/* What differs decides: a node's index fields are the first rule (or the
 * untouched inner nodes and counts), a box the untouched boxes, a slot
 * holding another triangle of the same leaf its own order, any other
 * triangle the copy, then the end of prims and the return value. */
static const char *hint(size_t i, const sidx_event *ref, const sidx_event *stu)
{
    const reindex_case *c = &cases[i];
    if (!ref || !stu || ref->type != SIDX_EV_NOTE || stu->type != SIDX_EV_NOTE) return rules[R_COPY].hint;
    const int kind = ref->cell[2];
    const int32_t node = ref->cell[0];
    if (kind == 0) {
        if (node >= 0 && (uint32_t)node < c->num_nodes && !sidx_bvh_is_leaf(&c->before[node])) return rules[R_LEAF].hint;
        if (ref->cell[1] != stu->cell[1]) return rules[R_COUNT].hint;
        /* the first of a walk from the other end: the leaves after it */
        uint32_t after = 0;
        for (uint32_t k = (uint32_t)node + 1; k < c->num_nodes; ++k)
            if (sidx_bvh_is_leaf(&c->before[k])) after += sidx_bvh_count(&c->before[k]);
        if (after != ref->count && stu->count == after) return rules[R_ORDER].hint;
        return rules[R_FIRST].hint;
    }
    if (kind >= 1 && kind <= 3) return rules[R_BOX].hint;
    if (kind == 4 && node >= 0 && (uint32_t)node < c->num_nodes) {
        const sidx_bvh_node *d = &c->after[node];
        for (uint32_t k = 0; k < sidx_bvh_count(d); ++k)
            if (c->prims[d->left_or_first + k] == stu->count) return rules[R_OWN].hint;
        return rules[R_COPY].hint;
    }
    return kind == 5 ? rules[R_PAST].hint : kind == 6 ? rules[R_RETURN].hint : rules[R_COPY].hint;
}

static int format(const sidx_event *e, char *buf, size_t size)
{
    if (e->type != SIDX_EV_NOTE) return 0;
    const uint32_t ca = (uint32_t)e->cell[1];
    switch (e->cell[2]) {
    case 0:
        if (ca & SIDX_BVH_COUNT_MASK)
            snprintf(buf, size, "node %d (leaf): first %u, count %u", e->cell[0], e->count, ca & SIDX_BVH_COUNT_MASK);
        else
            snprintf(buf, size, "node %d (inner): children %d and %u, axis %u", e->cell[0], e->cell[0] + 1, e->count,
                     ca >> 30);
        return 1;
    case 1:
    case 2:
    case 3:
        snprintf(buf, size, "node %d box  %c in [%g, %g]", e->cell[0], "xyz"[e->cell[2] - 1], (double)e->t_near,
                 (double)e->t_far);
        return 1;
    case 4:
        if (e->count == UNTOUCHED)
            snprintf(buf, size, "node %d, its triangle %d: (a slot not written, or past the end of prims)", e->cell[0],
                     e->cell[1]);
        else if (e->count == UNUSED)
            snprintf(buf, size, "node %d, its triangle %d: an unused slot of lists", e->cell[0], e->cell[1]);
        else
            snprintf(buf, size, "node %d, its triangle %d: triangle %u", e->cell[0], e->cell[1], e->count);
        return 1;
    case 5: snprintf(buf, size, "slots written past the end of prims: %u", e->count); return 1;
    case 6: snprintf(buf, size, "returned %u", e->count); return 1;
    default: return 0;
    }
}

const ex_driver ex_driver_this = {
    "19_bvh_reindex",
    "BVH leaf re-indexing: each leaf's triangles contiguous, in the order the leaves are laid out",
    "deck 001, \"What About Ordering?\" and \"After re-indexing (sorting) based on leaf nodes\" (\"Only need to "
    "store 2 integers per leaf node!\")",
    setup, num_cases, describe, reference, student, hint, teardown, format, rules, NRULES,
};
