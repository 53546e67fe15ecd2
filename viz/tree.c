/* tree.c — rebuild a structure's tree from its BUILD_* events.
 *
 * The events are the only input: BUILD_NODE gives id, parent id, depth,
 * bounds and primitive count; BUILD_SPLIT and BUILD_LEAF say what was
 * decided at a node (a leaf's primitive ids are copied from its BUILD_LEAF,
 * since the events' lists may not outlive them); BUILD_CANDIDATE is
 * counted.  Node ids are looked up
 * through a sorted (id, index) table, so ids need not be dense. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/viz.h"

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static sidx_status fail(sidx_error *err, sidx_status s, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->status = s;
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return s;
}

static int cmp_u64(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

uint32_t sidx_viz_tree_find(const sidx_viz_tree *t, uint32_t id)
{
    if (!t || !t->lookup) return SIDX_VIZ_NONE;
    size_t lo = 0, hi = t->count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        uint32_t mid_id = (uint32_t)(t->lookup[mid] >> 32);
        if (mid_id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo < t->count && (uint32_t)(t->lookup[lo] >> 32) == id) return (uint32_t)(t->lookup[lo] & 0xffffffffu);
    return SIDX_VIZ_NONE;
}

void sidx_viz_tree_free(sidx_viz_tree *t)
{
    if (!t) return;
    free(t->nodes);
    free(t->children);
    free(t->prim_ids);
    free(t->lookup);
    memset(t, 0, sizeof *t);
}

static const char *structure_of(const sidx_event *ev, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (ev[i].structure && ev[i].structure[0]) return ev[i].structure;
    return "structure";
}

sidx_status sidx_viz_tree_from_events(const sidx_event *ev, size_t n, sidx_viz_tree *out, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!out) return fail(err, SIDX_ERR_INVALID_ARG, "sidx_viz_tree_from_events: out is NULL");
    memset(out, 0, sizeof *out);
    out->root = SIDX_VIZ_NONE;
    out->hit_prim = SIDX_VIZ_NONE;
    if (!ev && n) return fail(err, SIDX_ERR_INVALID_ARG, "sidx_viz_tree_from_events: events are NULL");
    const char *name = structure_of(ev, n);
    out->structure = name;

    size_t count = 0, roots = 0, linked = 0;
    for (size_t i = 0; i < n; ++i)
        if (ev[i].type == SIDX_EV_BUILD_NODE) {
            ++count;
            if (ev[i].parent == UINT32_MAX)
                ++roots;
            else
                ++linked;
        }
    if (count == 0)
        return fail(err, SIDX_ERR_UNSUPPORTED, "%s does not emit a tree (no build_node events)", name);
    if (roots > 1 && linked == 0)
        return fail(err, SIDX_ERR_UNSUPPORTED, "%s does not emit a tree (%lu cells, no parent links)", name,
                    (unsigned long)count);
    /* Several roots with children below them (a two-level grid's top cells):
     * hang them under one virtual root so the whole reads as a tree. */
    const int add_root = roots > 1;
    count += add_root ? 1u : 0u;
    if (count >= UINT32_MAX)
        return fail(err, SIDX_ERR_LIMIT, "%s: too many nodes (%lu)", name, (unsigned long)count);

    sidx_viz_tree t;
    memset(&t, 0, sizeof t);
    t.structure = name;
    t.root = SIDX_VIZ_NONE;
    t.hit_prim = SIDX_VIZ_NONE;
    t.nodes = calloc(count, sizeof *t.nodes);
    t.lookup = malloc(count * sizeof *t.lookup);
    t.children = malloc(count * sizeof *t.children);
    uint32_t *parent_id = malloc(count * sizeof *parent_id);
    uint32_t *fill = calloc(count, sizeof *fill);
    if (!t.nodes || !t.lookup || !t.children || !parent_id || !fill) {
        free(parent_id);
        free(fill);
        sidx_viz_tree_free(&t);
        return fail(err, SIDX_ERR_NOMEM, "%s: out of memory rebuilding the tree", name);
    }
    t.count = count;

    sidx_status st = SIDX_OK;
    size_t k = 0;
    for (size_t i = 0; i < n; ++i) {
        if (ev[i].type != SIDX_EV_BUILD_NODE) continue;
        sidx_viz_node *nd = &t.nodes[k];
        nd->id = ev[i].node;
        nd->parent = SIDX_VIZ_NONE;
        nd->depth = ev[i].depth == UINT32_MAX ? 0 : ev[i].depth;
        nd->count = ev[i].count == UINT32_MAX ? 0 : ev[i].count;
        nd->bounds = ev[i].bounds;
        memcpy(nd->cell, ev[i].cell, sizeof nd->cell);
        nd->axis = -1;
        nd->pos = NAN;
        nd->cost = NAN;
        nd->n_left = nd->n_right = SIDX_VIZ_NONE;
        nd->leaf_reason = SIDX_LEAF_NONE;
        nd->build_event = i;
        nd->box_result = -1;
        parent_id[k] = ev[i].parent;
        t.lookup[k] = ((uint64_t)nd->id << 32) | (uint64_t)k;
        ++k;
    }
    if (add_root) {
        sidx_viz_node *nd = &t.nodes[k];
        nd->id = SIDX_VIZ_VIRTUAL_ROOT;
        nd->parent = SIDX_VIZ_NONE;
        nd->bounds = sidx_aabb_empty();
        nd->cell[0] = nd->cell[1] = nd->cell[2] = -1;
        nd->axis = -1;
        nd->pos = NAN;
        nd->cost = NAN;
        nd->n_left = nd->n_right = SIDX_VIZ_NONE;
        nd->box_result = -1;
        nd->build_event = SIZE_MAX;
        parent_id[k] = UINT32_MAX;
        t.lookup[k] = ((uint64_t)nd->id << 32) | (uint64_t)k;
        for (size_t i = 0; i < k; ++i) {
            if (parent_id[i] != UINT32_MAX) continue;
            parent_id[i] = SIDX_VIZ_VIRTUAL_ROOT;
            nd->count += t.nodes[i].count;
            nd->bounds = sidx_aabb_union(nd->bounds, t.nodes[i].bounds);
        }
        t.virtual_root = 1;
        ++k;
    }
    qsort(t.lookup, count, sizeof *t.lookup, cmp_u64);
    for (size_t i = 1; i < count; ++i)
        if ((t.lookup[i] >> 32) == (t.lookup[i - 1] >> 32)) {
            st = fail(err, SIDX_ERR_UNSUPPORTED, "%s: node id %lu created twice", name,
                      (unsigned long)(t.lookup[i] >> 32));
            goto done;
        }

    /* parents, roots, children grouped by parent (in creation order) */
    for (size_t i = 0; i < count; ++i) {
        if (parent_id[i] == UINT32_MAX) {
            if (t.root != SIDX_VIZ_NONE) {
                st = fail(err, SIDX_ERR_UNSUPPORTED, "%s does not emit a tree (node %lu is a second root)", name,
                          (unsigned long)t.nodes[i].id);
                goto done;
            }
            t.root = (uint32_t)i;
            continue;
        }
        uint32_t p = sidx_viz_tree_find(&t, parent_id[i]);
        if (p == SIDX_VIZ_NONE || p == i) {
            st = fail(err, SIDX_ERR_UNSUPPORTED, "%s does not emit a tree (bad parent of node %lu)", name,
                      (unsigned long)t.nodes[i].id);
            goto done;
        }
        t.nodes[i].parent = p;
        t.nodes[p].child_count++;
    }
    if (t.root == SIDX_VIZ_NONE) {
        st = fail(err, SIDX_ERR_UNSUPPORTED, "%s does not emit a tree (no root)", name);
        goto done;
    }
    {
        uint32_t base = 0;
        for (size_t i = 0; i < count; ++i) {
            t.nodes[i].child_base = base;
            base += t.nodes[i].child_count;
        }
        for (size_t i = 0; i < count; ++i) {
            uint32_t p = t.nodes[i].parent;
            if (p == SIDX_VIZ_NONE) continue;
            t.children[t.nodes[p].child_base + fill[p]++] = (uint32_t)i;
        }
    }
    /* every node must hang below the root (no cycles): walk it */
    {
        uint32_t *stack = fill; /* reuse: at most count entries */
        size_t sp = 0, seen = 0;
        stack[sp++] = t.root;
        while (sp) {
            uint32_t i = stack[--sp];
            if (++seen > count) break;
            const sidx_viz_node *nd = &t.nodes[i];
            for (uint32_t c = 0; c < nd->child_count && sp < count; ++c) stack[sp++] = t.children[nd->child_base + c];
        }
        if (seen != count) {
            st = fail(err, SIDX_ERR_UNSUPPORTED, "%s does not emit a tree (%lu nodes not below the root)", name,
                      (unsigned long)(count > seen ? count - seen : seen - count));
            goto done;
        }
    }

    for (size_t i = 0; i < count; ++i)
        if (t.nodes[i].depth > t.max_depth) t.max_depth = t.nodes[i].depth;

    /* decisions; first the room for the leaves' primitive lists */
    {
        size_t total = 0;
        for (size_t i = 0; i < n; ++i)
            if (ev[i].type == SIDX_EV_BUILD_LEAF && ev[i].prims && ev[i].count != UINT32_MAX) {
                if (total > SIZE_MAX / sizeof(uint32_t) - ev[i].count) {
                    st = fail(err, SIDX_ERR_LIMIT, "%s: too many leaf primitives", name);
                    goto done;
                }
                total += ev[i].count;
            }
        if (total) {
            t.prim_ids = malloc(total * sizeof *t.prim_ids);
            if (!t.prim_ids) {
                st = fail(err, SIDX_ERR_NOMEM, "%s: out of memory copying the leaves' primitives", name);
                goto done;
            }
        }
    }
    for (size_t i = 0; i < n; ++i) {
        const sidx_event *e = &ev[i];
        if (e->type != SIDX_EV_BUILD_SPLIT && e->type != SIDX_EV_BUILD_LEAF && e->type != SIDX_EV_BUILD_CANDIDATE)
            continue;
        uint32_t x = sidx_viz_tree_find(&t, e->node);
        if (x == SIDX_VIZ_NONE) continue;
        sidx_viz_node *nd = &t.nodes[x];
        if (e->type == SIDX_EV_BUILD_CANDIDATE) {
            nd->candidates++;
        } else if (e->type == SIDX_EV_BUILD_SPLIT) {
            nd->has_split = 1;
            nd->axis = e->axis;
            nd->pos = e->pos;
            nd->cost = e->cost;
            nd->n_left = e->count;
            nd->n_right = e->aux;
            if (e->axis < 0) nd->plane_n = e->bounds.min;
        } else {
            nd->is_leaf = 1;
            nd->leaf_reason = e->reason;
            nd->leaf_count = e->count == UINT32_MAX ? nd->count : e->count;
            if (!isnan(e->cost)) nd->cost = e->cost;
            nd->prims = NULL;
            if (e->prims && e->count != UINT32_MAX && e->count) {
                uint32_t *dst = t.prim_ids + t.num_prim_ids;
                memcpy(dst, e->prims, (size_t)e->count * sizeof *dst);
                t.num_prim_ids += e->count;
                nd->prims = dst;
            }
        }
    }
    for (size_t i = 0; i < count; ++i) {
        /* a childless node without a leaf event is still a leaf */
        if (t.nodes[i].child_count == 0 && !t.nodes[i].is_leaf) {
            t.nodes[i].is_leaf = 1;
            t.nodes[i].leaf_count = t.nodes[i].count;
        }
        if (t.nodes[i].is_leaf) t.leaves++;
    }

done:
    free(parent_id);
    free(fill);
    if (st != SIDX_OK) {
        sidx_viz_tree_free(&t);
        return st;
    }
    *out = t;
    return SIDX_OK;
}

void sidx_viz_tree_apply_ray(sidx_viz_tree *t, const sidx_event *ev, size_t n)
{
    if (!t) return;
    for (size_t i = 0; i < t->count; ++i) {
        sidx_viz_node *nd = &t->nodes[i];
        nd->visit_order = 0;
        nd->box_result = -1;
        nd->hit_leaf = 0;
        nd->prims_tested = 0;
    }
    t->visited = 0;
    t->hit_prim = SIDX_VIZ_NONE;
    t->hit_t = INFINITY;
    uint32_t current = SIDX_VIZ_NONE, hit_node = SIDX_VIZ_NONE;
    for (size_t i = 0; ev && i < n; ++i) {
        const sidx_event *e = &ev[i];
        uint32_t x;
        switch (e->type) {
        case SIDX_EV_NODE_ENTER:
            x = sidx_viz_tree_find(t, e->node);
            if (x == SIDX_VIZ_NONE) break;
            current = x;
            if (t->nodes[x].visit_order == 0) t->nodes[x].visit_order = ++t->visited;
            break;
        case SIDX_EV_BOX_TEST:
            x = sidx_viz_tree_find(t, e->node);
            if (x != SIDX_VIZ_NONE) t->nodes[x].box_result = e->result == 1;
            break;
        case SIDX_EV_PRIM_TEST:
            if (current != SIDX_VIZ_NONE) {
                sidx_viz_node *nd = &t->nodes[current];
                if (nd->prims_tested < 4) nd->tested_ids[nd->prims_tested] = e->prim;
                nd->prims_tested++;
            }
            break;
        case SIDX_EV_HIT_UPDATE:
            hit_node = current;
            t->hit_prim = e->prim;
            t->hit_t = e->t;
            break;
        case SIDX_EV_TERMINATE:
            /* A space partition finds a hit in one leaf (a triangle reaching past its cell) and
             * stops in the leaf whose cell holds it ("hit in cell", deck 000 "kD-Tree
             * Traversal"): the walk ends there, so that leaf is the one outlined. */
            if (e->reason == SIDX_TERM_HIT_IN_CELL && current != SIDX_VIZ_NONE) hit_node = current;
            break;
        case SIDX_EV_RAY_END:
            t->hit_prim = e->prim;
            t->hit_t = e->t;
            break;
        default:
            break;
        }
    }
    if (t->hit_prim != SIDX_VIZ_NONE && hit_node != SIDX_VIZ_NONE) t->nodes[hit_node].hit_leaf = 1;
}

void sidx_viz_tree_subtree(const sidx_viz_tree *t, uint32_t i, uint32_t *nodes, uint64_t *prims)
{
    uint32_t nn = 0;
    uint64_t pp = 0;
    if (t && i < t->count) {
        uint32_t *stack = malloc(t->count * sizeof *stack);
        if (stack) {
            size_t sp = 0;
            stack[sp++] = i;
            while (sp) {
                const sidx_viz_node *nd = &t->nodes[stack[--sp]];
                ++nn;
                if (nd->is_leaf) pp += nd->leaf_count;
                for (uint32_t c = 0; c < nd->child_count && sp < t->count; ++c)
                    stack[sp++] = t->children[nd->child_base + c];
            }
            free(stack);
        }
    }
    if (nodes) *nodes = nn;
    if (prims) *prims = pp;
}

int sidx_viz_parse_ray(const char *s, sidx_vec3 *org, sidx_vec3 *dir)
{
    if (!s || !org || !dir) return -1;
    float v[6];
    const char *p = s;
    for (int i = 0; i < 6; ++i) {
        char *end;
        v[i] = strtof(p, &end);
        if (end == p || !isfinite(v[i])) return -1;
        p = end;
        while (*p == ' ') ++p;
        if (i < 5) {
            if (*p != ',') return -1;
            ++p;
        }
    }
    if (*p != '\0') return -1;
    *org = sidx_v3(v[0], v[1], v[2]);
    *dir = sidx_v3(v[3], v[4], v[5]);
    if (dir->x == 0.0f && dir->y == 0.0f && dir->z == 0.0f) return -1;
    return 0;
}
