/* dot.c — a structure's tree as a Graphviz graph, built with cgraph and
 * laid out and rendered with gvc.
 *
 * Inner nodes say what decided them (axis, split position, SAH cost,
 * primitive count); leaves their primitive count, leaf reason, the ids of
 * their primitives (from BUILD_LEAF; the first DOT_LEAF_IDS of a big leaf)
 * and, with a ray, the primitives the ray tested there.  With a ray, visited nodes are
 * filled along a yellow-to-red gradient in visit order and numbered, nodes
 * whose box test failed are greyed, the hit leaf gets a double red border.
 * Below max_depth each cut subtree becomes one summary node; siblings past the
 * width a level may hold fold into one "… N more" box, and the caption says
 * what was left out. */
#include <ctype.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if SIDX_HAVE_GRAPHVIZ
#include <graphviz/cgraph.h>
#include <graphviz/gvc.h>
#endif
#include "sidx/sinks.h"
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

#if SIDX_HAVE_GRAPHVIZ

/* Appends to a fixed buffer, truncating safely. */
typedef struct strbuf { char s[512]; size_t n; } strbuf;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void sb_add(strbuf *b, const char *fmt, ...)
{
    if (b->n >= sizeof b->s - 1) return;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->s + b->n, sizeof b->s - b->n, fmt, ap);
    va_end(ap);
    if (k > 0) b->n += (size_t)k;
    if (b->n > sizeof b->s - 1) b->n = sizeof b->s - 1;
}

static const char *axis_letter(int32_t a) { return a == 0 ? "x" : a == 1 ? "y" : a == 2 ? "z" : "?"; }

static void set(void *obj, const char *key, const char *value)
{
    /* cgraph's API takes char*; it copies both strings. */
    agsafeset(obj, (char *)key, (char *)value, (char *)"");
}

/* Visit-order gradient: pale yellow (first) to red (last). */
static void gradient(uint32_t order, uint32_t total, char out[16])
{
    double f = total > 1 ? (double)(order - 1) / (double)(total - 1) : 0.0;
    int r = 255;
    int g = (int)(236.0 - 190.0 * f);
    int b = (int)(150.0 - 120.0 * f);
    snprintf(out, 16, "#%02x%02x%02x", r, g, b);
}

#define DOT_LEAF_IDS 8  /* ids listed in a leaf's label; a bigger leaf ends with "+k" */
#define DOT_IDS_PER_LINE 4

/* A float the build computed as 0 comes out as -2.384e-07 after a subtraction: values within a
 * few ulps of the scale they were computed at print as 0: the scene's extent for positions, 4 for a
 * unit normal (a cross product of scene coordinates: its error is a few ulps of its inputs). */
static double snap0(float v, float scale)
{
    return fabsf(v) <= 8.0f * FLT_EPSILON * scale ? 0.0 : (double)v;
}

static void node_label(const sidx_viz_tree *t, const sidx_viz_node *nd, int with_ray, float scale,
                       const sidx_accel *labels, strbuf *b)
{
    if (nd->id == SIDX_VIZ_VIRTUAL_ROOT && t->virtual_root) {
        sb_add(b, "%s\\n%u top-level cells\\n%u prims", t->structure, nd->child_count, nd->count);
        return;
    }
    if (with_ray && nd->visit_order) sb_add(b, "#%u  ", nd->visit_order);
    const char *name = sidx_accel_node_label(labels, nd->id); /* the slide's name first: "L4 (leaf 7)" */
    if (name && nd->cell[0] < 0)
        sb_add(b, "%s (%s %u)", name, nd->is_leaf ? "leaf" : "node", nd->id);
    else if (nd->cell[0] >= 0)
        sb_add(b, "cell (%d,%d,%d)", (int)nd->cell[0], (int)nd->cell[1], (int)nd->cell[2]);
    else
        sb_add(b, "%s %u", nd->is_leaf ? "leaf" : "node", nd->id);
    sb_add(b, "  d%u\\n", nd->depth);
    if (!nd->is_leaf) {
        if (nd->has_split && nd->axis >= 0)
            sb_add(b, "split %s = %.4g\\n", axis_letter(nd->axis), snap0(nd->pos, scale));
        else if (nd->has_split && isnan(nd->pos)) { /* octree / quadtree: cut at the cell's centre */
            const sidx_vec3 ctr = sidx_aabb_centroid(nd->bounds);
            sb_add(b, "centre (%.4g,%.4g,%.4g)\\n", snap0(ctr.x, scale), snap0(ctr.y, scale), snap0(ctr.z, scale));
        }
        else if (nd->has_split)
            sb_add(b, "plane (%.3g,%.3g,%.3g)·p = %.4g\\n", snap0(nd->plane_n.x, 4.0f), snap0(nd->plane_n.y, 4.0f),
                   snap0(nd->plane_n.z, 4.0f), snap0(nd->pos, scale));
        /* An arbitrary plane (BSP) is not chosen by the SAH but by the node builders' score
         * |front - back| + w·cuts (lib/bsp.c); axis-aligned splits carry the SAH cost. */
        if (!isnan(nd->cost) && nd->has_split && nd->axis < 0)
            sb_add(b, "balance+cuts score %.4g\\n", (double)nd->cost);
        else if (!isnan(nd->cost))
            sb_add(b, "SAH %.4g\\n", (double)nd->cost);
        sb_add(b, "%u prims", nd->count);
        if (nd->has_split && !isnan(nd->pos) && nd->n_left != SIDX_VIZ_NONE && nd->n_right != SIDX_VIZ_NONE)
            sb_add(b, " (L %u | R %u)", nd->n_left, nd->n_right);
    } else {
        sb_add(b, "%u prims", nd->leaf_count);
        /* A BSP region with no piece of its own is an empty leaf, yet its ray list holds the
         * triangles of neighbouring regions that come within ε of its planes (lib/bsp.c). */
        if (nd->leaf_reason == SIDX_LEAF_EMPTY && nd->leaf_count)
            sb_add(b, " (empty region; near its planes)");
        else if (nd->leaf_reason != SIDX_LEAF_NONE)
            sb_add(b, " (%s)", sidx_leaf_reason_name(nd->leaf_reason));
        if (!isnan(nd->cost)) sb_add(b, "\\ncost %.4g", (double)nd->cost);
        if (nd->prims && nd->leaf_count) {
            const uint32_t k = nd->leaf_count < DOT_LEAF_IDS ? nd->leaf_count : DOT_LEAF_IDS;
            sb_add(b, "\\nprims:");
            for (uint32_t i = 0; i < k; ++i)
                sb_add(b, "%s%u", i && i % DOT_IDS_PER_LINE == 0 ? "\\n" : " ", nd->prims[i]);
            if (nd->leaf_count > k) sb_add(b, " +%u more", nd->leaf_count - k);
        }
        if (with_ray && nd->prims_tested) {
            sb_add(b, "\\ntested:");
            uint32_t k = nd->prims_tested < 4 ? nd->prims_tested : 4;
            for (uint32_t i = 0; i < k; ++i) sb_add(b, " %u", nd->tested_ids[i]);
            if (nd->prims_tested > k) sb_add(b, " +%u", nd->prims_tested - k);
        }
        if (nd->hit_leaf) sb_add(b, "\\nHIT prim %u t=%.4g", t->hit_prim, (double)t->hit_t);
    }
}

typedef struct dot_ctx {
    Agraph_t *g;
    const sidx_viz_tree *t;
    int with_ray;
    uint32_t cut_level; /* levels below the drawn root after which subtrees are summarised */
    uint32_t max_width; /* boxes across the drawing, at most (UINT32_MAX: no fold) */
    uint32_t max_nodes; /* boxes the drawing holds, about (UINT32_MAX: no limit) */
    float scale;        /* the scene's extent: split values within a few ulps of it print as 0 */
    const sidx_accel *labels; /* node labels, or NULL */
    /* per tree node, for the whole subtree below and including it */
    uint32_t *sub_nodes, *sub_visited;
    uint64_t *sub_prims;
    /* what the drawing leaves out */
    uint32_t drawn;                  /* boxes drawn */
    uint32_t summaries, cut_nodes;   /* subtrees cut at cut_level, and their nodes */
    uint32_t folds, folded_nodes;    /* "… N more" boxes for siblings past the width, and their nodes */
    uint32_t folded_top;             /* siblings folded (the N of the boxes, summed) */
    uint32_t closed, closed_nodes;   /* subtrees summarised to keep the width, and their nodes */
} dot_ctx;

/* Subtree sizes for every node in one pass: a breadth-first order (parents before children),
 * then the sums taken from the end of it. */
static int subtree_sums(dot_ctx *c)
{
    const sidx_viz_tree *t = c->t;
    uint32_t *order = malloc(t->count * sizeof *order);
    c->sub_nodes = calloc(t->count, sizeof *c->sub_nodes);
    c->sub_visited = calloc(t->count, sizeof *c->sub_visited);
    c->sub_prims = calloc(t->count, sizeof *c->sub_prims);
    if (!order || !c->sub_nodes || !c->sub_visited || !c->sub_prims) { free(order); return -1; }
    size_t n = 0, next = 0;
    order[n++] = t->root;
    while (next < n) {
        const sidx_viz_node *nd = &t->nodes[order[next++]];
        for (uint32_t k = 0; k < nd->child_count && n < t->count; ++k) order[n++] = t->children[nd->child_base + k];
    }
    for (size_t k = n; k-- > 0;) {
        const uint32_t i = order[k];
        const sidx_viz_node *nd = &t->nodes[i];
        c->sub_nodes[i] += 1;
        c->sub_visited[i] += nd->visit_order != 0;
        if (nd->is_leaf) c->sub_prims[i] += nd->leaf_count;
        if (nd->parent != SIDX_VIZ_NONE) {
            c->sub_nodes[nd->parent] += c->sub_nodes[i];
            c->sub_visited[nd->parent] += c->sub_visited[i];
            c->sub_prims[nd->parent] += c->sub_prims[i];
        }
    }
    free(order);
    return 0;
}

static Agnode_t *add_node(dot_ctx *c, uint32_t i)
{
    const sidx_viz_node *nd = &c->t->nodes[i];
    char name[32];
    snprintf(name, sizeof name, "n%u", nd->id);
    Agnode_t *n = agnode(c->g, name, 1);
    if (!n) return NULL;
    strbuf lb = {{0}, 0};
    node_label(c->t, nd, c->with_ray, c->scale, c->labels, &lb);
    set(n, "label", lb.s);
    set(n, "fillcolor", nd->is_leaf ? "#e3f1d8" : "#dce7f5");
    if (c->with_ray) {
        if (nd->visit_order) {
            char col[16];
            gradient(nd->visit_order, c->t->visited, col);
            set(n, "fillcolor", col);
        } else if (nd->box_result == 0) {
            set(n, "fillcolor", "#d0d0d0");
            set(n, "fontcolor", "#7a7a7a");
            set(n, "color", "#9a9a9a");
        } else {
            set(n, "fillcolor", "#f4f4f4");
            set(n, "fontcolor", "#7a7a7a");
        }
        if (nd->hit_leaf) {
            set(n, "color", "#d00000");
            set(n, "penwidth", "3");
            set(n, "peripheries", "2");
        }
    }
    ++c->drawn;
    return n;
}

/* Node states: not drawn, drawn and closed (a summary below it when it has children), drawn
 * and open (its children weighed; those not shown are in its "… more" box) */
enum { DOT_OUT = 0, DOT_CLOSED = 1, DOT_OPEN = 2 };
/* Why a box stands for children not drawn */
enum { DOT_FOLD, DOT_CUT, DOT_CLOSE };

/* One box under `parent` standing for the children of node p that are not drawn
 * (state[child] == DOT_OUT).  DOT_CUT: every child, below the depth cut; DOT_CLOSE: every
 * child, the subtree summarised to keep the width ("+N nodes, M prims", named cut<id>);
 * DOT_FOLD: the siblings past the width ("… N more cells (M empty)", named fold<id>). */
static int add_folded(dot_ctx *c, Agnode_t *parent, uint32_t p, const unsigned char *state, int why)
{
    const sidx_viz_tree *t = c->t;
    const sidx_viz_node *nd = &t->nodes[p];
    uint32_t nodes = 0, visited = 0, siblings = 0, empty = 0, cells = 1, any_kept = 0;
    uint64_t prims = 0;
    for (uint32_t k = 0; k < nd->child_count; ++k) {
        const uint32_t ch = t->children[nd->child_base + k];
        if (state[ch] != DOT_OUT) { any_kept = 1; continue; }
        nodes += c->sub_nodes[ch];
        prims += c->sub_prims[ch];
        visited += c->sub_visited[ch];
        ++siblings;
        empty += c->sub_prims[ch] == 0;
        cells &= t->nodes[ch].cell[0] >= 0;
    }
    if (!siblings) return 0;
    char name[40];
    strbuf lb = {{0}, 0};
    if (why != DOT_FOLD) {
        snprintf(name, sizeof name, "cut%u", nd->id);
        sb_add(&lb, "+%u nodes, %llu prims", nodes, (unsigned long long)prims);
        if (why == DOT_CUT) {
            c->summaries++;
            c->cut_nodes += nodes;
        } else {
            c->closed++;
            c->closed_nodes += nodes;
        }
    } else {
        snprintf(name, sizeof name, "fold%u", nd->id);
        const char *what = cells ? (siblings == 1 ? "cell" : "cells") : (siblings == 1 ? "node" : "nodes");
        sb_add(&lb, "\xe2\x80\xa6 %u %s%s", siblings, any_kept ? "more " : "", what);
        if (empty || cells) sb_add(&lb, " (%u empty)", empty);
        sb_add(&lb, "\\n%u nodes, %llu prims in all", nodes, (unsigned long long)prims);
        c->folds++;
        c->folded_nodes += nodes;
        c->folded_top += siblings;
    }
    if (visited) sb_add(&lb, "\\nray visited %u", visited);
    Agnode_t *s = agnode(c->g, name, 1);
    if (!s) return -1;
    set(s, "label", lb.s);
    set(s, "shape", "folder");
    set(s, "style", "filled,dashed");
    set(s, "fillcolor", visited ? "#ffe0b0" : "#f0f0f0");
    Agedge_t *e = agedge(c->g, parent, s, NULL, 1);
    if (!e) return -1;
    set(e, "style", "dashed");
    ++c->drawn;
    return 0;
}

/* Which nodes are drawn.
 *
 * dot lays a tree out about as wide as its bottom boxes: the drawn leaves, the "… more" boxes
 * and the summaries, at whatever depth they end.  So max_width bounds those boxes, the
 * frontier, and max_nodes all boxes.  The drawing starts as the root over one summary and
 * opens nodes best first — the ones the ray visited (in visit order), then the ones holding
 * the most primitives — while the frontier has room.  Opening a node shows its children in
 * the same order of interest, at most half the room left (and one at least), the rest folded
 * into one "… N more" box after them; a single sibling is shown rather than folded.  Nodes at
 * cut_level stay closed.  So a wide level becomes a few cells and a fold, and the page's width
 * goes to the deepest paths of interest rather than to one level. */
typedef struct cand { uint32_t node, visit; uint64_t prims; uint32_t nodes, order; } cand;

/* 1: a is more interesting than b */
static int before(const cand *a, const cand *b)
{
    const uint32_t va = a->visit ? a->visit : UINT32_MAX, vb = b->visit ? b->visit : UINT32_MAX;
    if (va != vb) return va < vb;
    if (a->prims != b->prims) return a->prims > b->prims;
    if (a->nodes != b->nodes) return a->nodes > b->nodes;
    return a->order < b->order;
}

static int cmp_cand(const void *x, const void *y)
{
    const cand *a = x, *b = y;
    return before(a, b) ? -1 : before(b, a) ? 1 : 0;
}

static cand cand_of(const dot_ctx *c, uint32_t i, uint32_t order)
{
    cand k = {i, c->t->nodes[i].visit_order, c->sub_prims[i], c->sub_nodes[i], order};
    return k;
}

/* A binary heap of the closed nodes that may be opened, best on top. */
typedef struct heap { cand *a; size_t n; } heap;

static void heap_push(heap *h, cand k)
{
    size_t i = h->n++;
    while (i && before(&k, &h->a[(i - 1) / 2])) {
        h->a[i] = h->a[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    h->a[i] = k;
}

static cand heap_pop(heap *h)
{
    cand top = h->a[0], last = h->a[--h->n];
    size_t i = 0;
    for (;;) {
        size_t l = 2 * i + 1, r = l + 1, m = i;
        const cand *best = &last;
        if (l < h->n && before(&h->a[l], best)) { m = l; best = &h->a[l]; }
        if (r < h->n && before(&h->a[r], best)) m = r;
        if (m == i) break;
        h->a[i] = h->a[m];
        i = m;
    }
    if (h->n) h->a[i] = last;
    return top;
}


static int choose(dot_ctx *c, unsigned char *state, uint32_t *level, cand *kids)
{
    const sidx_viz_tree *t = c->t;
    const uint64_t unlimited = UINT64_MAX / 4;
    const uint64_t max_width = c->max_width == UINT32_MAX ? unlimited : c->max_width;
    const uint64_t max_nodes = c->max_nodes == UINT32_MAX ? unlimited : c->max_nodes;
    heap h = {malloc(t->count * sizeof(cand)), 0};
    if (!h.a) return -1;
    const int root_inner = t->nodes[t->root].child_count > 0;
    uint64_t frontier = 1, boxes = 1 + (uint64_t)root_inner; /* the root and its summary */
    uint32_t order = 0;
    state[t->root] = DOT_CLOSED;
    level[t->root] = 0;
    if (root_inner && c->cut_level > 0) heap_push(&h, cand_of(c, t->root, order++));
    while (h.n) {
        const uint32_t p = heap_pop(&h).node;
        const sidx_viz_node *nd = &t->nodes[p];
        const uint32_t k = nd->child_count;
        for (uint32_t j = 0; j < k; ++j) kids[j] = cand_of(c, t->children[nd->child_base + j], j);
        qsort(kids, k, sizeof *kids, cmp_cand);
        /* the room the frontier has once p's summary gives its place up */
        const uint64_t room = max_width + 1 > frontier ? max_width + 1 - frontier : 0;
        uint64_t show = room / 2 > 1 ? room / 2 : 1;
        if (show + 1 >= k) show = k;  /* no "… 1 more": show it */
        /* fewer where all boxes would pass max_nodes (a closed inner child brings its summary) */
        uint64_t inner = 0;
        for (uint64_t j = 0; j < show; ++j) inner += t->nodes[kids[j].node].child_count > 0;
        uint64_t fold = show < k, new_boxes = boxes - 1 + show + inner + fold;
        while (show > 1 && new_boxes > max_nodes) {
            --show;
            inner -= t->nodes[kids[show].node].child_count > 0;
            fold = 1;
            new_boxes = boxes - 1 + show + inner + fold;
        }
        const uint64_t new_frontier = frontier - 1 + show + fold;
        if ((new_frontier > max_width && new_frontier > frontier) || new_boxes > max_nodes) continue;
        frontier = new_frontier;
        boxes = new_boxes;
        state[p] = DOT_OPEN;
        for (uint64_t j = 0; j < show; ++j) {
            const uint32_t ch = kids[j].node;
            state[ch] = DOT_CLOSED;
            level[ch] = level[p] + 1;
            if (t->nodes[ch].child_count && level[ch] < c->cut_level) heap_push(&h, cand_of(c, ch, order++));
        }
    }
    free(h.a);
    return 0;
}

static int build_graph(dot_ctx *c)
{
    const sidx_viz_tree *t = c->t;
    Agnode_t **made = calloc(t->count, sizeof *made);
    unsigned char *state = calloc(t->count, 1);
    uint32_t *level = malloc(t->count * sizeof *level), *stack = malloc(t->count * sizeof *stack);
    cand *kids = malloc(t->count * sizeof *kids);
    int rc = 0;
    if (!made || !state || !level || !stack || !kids || choose(c, state, level, kids) != 0) { rc = -1; goto out; }
    /* depth first, children left to right as the build made them */
    size_t sp = 0;
    stack[sp++] = t->root;
    while (sp && rc == 0) {
        const uint32_t i = stack[--sp];
        const sidx_viz_node *nd = &t->nodes[i];
        Agnode_t *n = made[i] = add_node(c, i);
        if (!n) { rc = -1; break; }
        if (nd->parent != SIDX_VIZ_NONE && made[nd->parent]) {
            Agedge_t *e = agedge(c->g, made[nd->parent], n, NULL, 1);
            if (!e) { rc = -1; break; }
            if (c->with_ray && nd->visit_order && t->nodes[nd->parent].visit_order) {
                set(e, "color", "#d04000");
                set(e, "penwidth", "2");
            }
        }
        for (uint32_t k = nd->child_count; k-- > 0;) {
            const uint32_t ch = t->children[nd->child_base + k];
            if (state[ch] != DOT_OUT) stack[sp++] = ch;
        }
    }
    /* then the boxes for what is not drawn: after the shown children (ordering=out keeps a
     * node's edges in the order they were made), so a "… more" box ends its row */
    for (uint32_t i = 0; i < t->count && rc == 0; ++i) {
        if (!made[i] || !t->nodes[i].child_count) continue;
        const int why = state[i] == DOT_OPEN ? DOT_FOLD : level[i] >= c->cut_level ? DOT_CUT : DOT_CLOSE;
        rc = add_folded(c, made[i], i, state, why);
    }
out:
    free(made);
    free(state);
    free(level);
    free(stack);
    free(kids);
    return rc;
}

#endif /* SIDX_HAVE_GRAPHVIZ */

/* Output format from the extension (or opt->format).  "dot" = text. */
static const char *format_of(const char *path, const char *forced)
{
    static const char *const known[] = {"dot", "gv", "svg", "png", "pdf", "canon", "plain", "json", NULL};
    const char *ext = forced;
    if (!ext && path && strcmp(path, "-") == 0) ext = "dot";
    if (!ext) {
        const char *dot = path ? strrchr(path, '.') : NULL;
        const char *slash = path ? strrchr(path, '/') : NULL;
        if (!dot || (slash && dot < slash)) return NULL;
        ext = dot + 1;
    }
    for (int i = 0; known[i]; ++i) {
        size_t n = strlen(known[i]);
        int same = strlen(ext) == n;
        for (size_t k = 0; same && k < n; ++k)
            if (tolower((unsigned char)ext[k]) != known[i][k]) same = 0;
        if (same) return known[i];
    }
    return NULL;
}

#if SIDX_HAVE_GRAPHVIZ
/* One Graphviz context for the whole process, made on first use and kept.
 * The pango text plugin caches a pointer to the last font name it measured,
 * and that name belongs to the context: a second context made after the
 * first was freed would compare against freed memory (AddressSanitizer
 * shows it in the tour, which draws several trees). */
static GVC_t *dot_context(void)
{
    static GVC_t *gvc;
    if (!gvc) gvc = gvContext();
    return gvc;
}
#endif

sidx_status sidx_dot_write_events(const sidx_event *build, size_t nbuild, const sidx_event *trav, size_t ntrav,
                                  const sidx_dot_options *opt, const char *path, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!path || (!build && nbuild)) return fail(err, SIDX_ERR_INVALID_ARG, "sidx_dot_write: NULL argument");
    sidx_dot_options o;
    memset(&o, 0, sizeof o);
    if (opt) o = *opt;
    const char *fmt = format_of(path, o.format);
    if (!fmt)
        return fail(err, SIDX_ERR_INVALID_ARG, "%s: unknown output format (use .dot, .gv, .svg, .png or .pdf)", path);
#if !SIDX_HAVE_GRAPHVIZ
    (void)trav;
    (void)ntrav;
    return fail(err, SIDX_ERR_UNSUPPORTED, "%s: sidx was built without Graphviz (install libgraphviz-dev, rebuild)",
                path);
#else
    const int text = !strcmp(fmt, "dot") || !strcmp(fmt, "gv");

    sidx_viz_tree t;
    sidx_status st = sidx_viz_tree_from_events(build, nbuild, &t, err);
    if (st != SIDX_OK) return st;
    const int with_ray = trav && ntrav;
    if (with_ray) sidx_viz_tree_apply_ray(&t, trav, ntrav);

    dot_ctx c;
    memset(&c, 0, sizeof c);
    c.t = &t;
    c.with_ray = with_ray;
    c.labels = o.labels;
    /* max_depth levels are drawn, depths 0 .. max_depth - 1; nodes at depth cut_level or more
     * are not opened */
    c.cut_level = (o.max_depth ? o.max_depth : SIDX_DOT_DEFAULT_DEPTH) - 1u;
    c.max_width = o.max_width ? o.max_width : SIDX_DOT_DEFAULT_WIDTH;
    c.max_nodes = o.max_nodes ? o.max_nodes : SIDX_DOT_DEFAULT_NODES;
    if (c.max_width < 2) c.max_width = 2; /* one drawn child and its "… more" box */
    if (c.max_nodes < 2) c.max_nodes = 2;
    if (subtree_sums(&c) != 0) {
        free(c.sub_nodes);
        free(c.sub_visited);
        free(c.sub_prims);
        sidx_viz_tree_free(&t);
        return fail(err, SIDX_ERR_NOMEM, "out of memory sizing the tree");
    }
    {
        const sidx_aabb rb = t.nodes[t.root].bounds;
        const float m[6] = {rb.min.x, rb.min.y, rb.min.z, rb.max.x, rb.max.y, rb.max.z};
        for (int k = 0; k < 6; ++k)
            if (isfinite(m[k]) && fabsf(m[k]) > c.scale) c.scale = fabsf(m[k]);
    }

    Agdesc_t desc = Agdirected;
    c.g = agopen((char *)"sidx", desc, NULL);
    if (!c.g) {
        free(c.sub_nodes);
        free(c.sub_visited);
        free(c.sub_prims);
        sidx_viz_tree_free(&t);
        return fail(err, SIDX_ERR_NOMEM, "cgraph: agopen failed");
    }
    set(c.g, "labelloc", "t");
    set(c.g, "fontname", "Helvetica");
    set(c.g, "ordering", "out");
    agattr(c.g, AGNODE, (char *)"shape", (char *)"box");
    agattr(c.g, AGNODE, (char *)"style", (char *)"rounded,filled");
    agattr(c.g, AGNODE, (char *)"fontname", (char *)"Helvetica");
    agattr(c.g, AGNODE, (char *)"fontsize", (char *)"10");
    agattr(c.g, AGEDGE, (char *)"arrowsize", (char *)"0.6");

    const int built = build_graph(&c);
    free(c.sub_nodes);
    free(c.sub_visited);
    free(c.sub_prims);
    if (built != 0) {
        agclose(c.g);
        sidx_viz_tree_free(&t);
        return fail(err, SIDX_ERR_NOMEM, "cgraph: out of memory building the graph");
    }
    char title[600];
    if (o.title)
        snprintf(title, sizeof title, "%s", o.title);
    else if (with_ray && t.hit_prim != SIDX_VIZ_NONE)
        snprintf(title, sizeof title, "%s: %zu nodes, %u leaves; ray visited %u, hit prim %u at t=%.4g", t.structure,
                 t.count, t.leaves, t.visited, t.hit_prim, (double)t.hit_t);
    else if (with_ray)
        snprintf(title, sizeof title, "%s: %zu nodes, %u leaves; ray visited %u, missed", t.structure, t.count,
                 t.leaves, t.visited);
    else
        snprintf(title, sizeof title, "%s: %zu nodes, %u leaves, depth %u", t.structure, t.count, t.leaves,
                 t.max_depth);
    /* the caption says what the drawing leaves out, and why */
    {
        size_t n = strlen(title);
        if ((c.folds || c.closed) && n < sizeof title)
            n += (size_t)snprintf(title + n, sizeof title - n, "\\nfolded to fit a page (about %u boxes across, %u in all):",
                                  c.max_width, c.max_nodes);
        if (c.folds && n < sizeof title)
            n += (size_t)snprintf(title + n, sizeof title - n, " %u siblings in %u \xe2\x80\xa6 boxes%s", c.folded_top,
                                  c.folds, c.closed ? "," : "");
        if (c.closed && n < sizeof title)
            n += (size_t)snprintf(title + n, sizeof title - n, " %u subtrees summarised", c.closed);
        if ((c.folds || c.closed) && n < sizeof title)
            n += (size_t)snprintf(title + n, sizeof title - n, "; %u nodes not drawn", c.folded_nodes + c.closed_nodes);
        if (c.summaries && n < sizeof title)
            snprintf(title + n, sizeof title - n, "\\n%u levels drawn: %u deeper subtrees summarised (%u nodes)",
                     c.cut_level + 1u, c.summaries, c.cut_nodes);
    }
    set(c.g, "label", title);
    if (o.progress && !text) {
        fprintf(o.progress, "laying out %u boxes with Graphviz dot...\n", c.drawn);
        fflush(o.progress);
    }


    FILE *f = strcmp(path, "-") == 0 ? stdout : fopen(path, "wb");
    if (!f) {
        agclose(c.g);
        sidx_viz_tree_free(&t);
        return fail(err, SIDX_ERR_IO, "%s: cannot open for writing", path);
    }
    int rc;
    if (text) {
        rc = agwrite(c.g, f);
    } else {
        GVC_t *gvc = dot_context();
        rc = gvc ? gvLayout(gvc, c.g, "dot") : -1;
        if (rc == 0) {
            rc = gvRender(gvc, c.g, fmt, f);
            gvFreeLayout(gvc, c.g);
        }
    }
    int close_rc = f == stdout ? fflush(f) : fclose(f);
    agclose(c.g);
    sidx_viz_tree_free(&t);
    if (rc != 0) return fail(err, SIDX_ERR_IO, "%s: graphviz could not write %s output", path, fmt);
    if (close_rc != 0) return fail(err, SIDX_ERR_IO, "%s: write failed", path);
    return SIDX_OK;
#endif /* SIDX_HAVE_GRAPHVIZ */
}

sidx_status sidx_dot_write(const sidx_mesh *mesh, const char *accel_name, const sidx_dot_options *opt,
                           const char *path, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!mesh || !accel_name || !path) return fail(err, SIDX_ERR_INVALID_ARG, "sidx_dot_write: NULL argument");
    sidx_ray ray;
    if (opt && opt->has_ray && sidx_ray_init(&ray, opt->ray_org, opt->ray_dir, 0.0f, INFINITY) != SIDX_OK)
        return fail(err, SIDX_ERR_INVALID_ARG, "sidx_dot_write: invalid ray");

    sidx_recorder brec, trec;
    sidx_recorder_init(&brec);
    sidx_recorder_init(&trec);
    sidx_hook bh = sidx_recorder_hook(&brec);
    bh.mask = SIDX_EVMASK_BUILD;
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    if (opt && opt->build) bo = *opt->build;
    bo.hook = &bh;
    sidx_accel *a = NULL;
    if (opt && opt->progress) {
        fprintf(opt->progress, "building %s over %u triangles...\n", accel_name, (unsigned)mesh->num_triangles);
        fflush(opt->progress);
    }
    sidx_status st = sidx_scene_accel_build(opt ? opt->scene : NULL, accel_name, mesh, &bo, &a, err);
    if (st == SIDX_OK && brec.overflow) st = fail(err, SIDX_ERR_NOMEM, "out of memory recording the build");
    if (st == SIDX_OK && opt && opt->has_ray) {
        sidx_hook th = sidx_recorder_hook(&trec);
        th.mask = SIDX_EVMASK_TRAVERSAL;
        sidx_query q;
        memset(&q, 0, sizeof q);
        q.traversal = opt->traversal;
        q.hook = &th;
        sidx_hit hit;
        sidx_accel_intersect(a, &ray, &q, &hit);
        if (trec.overflow) st = fail(err, SIDX_ERR_NOMEM, "out of memory recording the traversal");
    }
    sidx_dot_options o;
    memset(&o, 0, sizeof o);
    if (opt) o = *opt;
    o.labels = a;
    if (st == SIDX_OK)
        st = sidx_dot_write_events(brec.events, brec.count, opt && opt->has_ray ? trec.events : NULL, trec.count, &o,
                                   path, err);
    sidx_accel_destroy(a);
    sidx_recorder_free(&brec);
    sidx_recorder_free(&trec);
    return st;
}

#if defined(__SANITIZE_ADDRESS__)
/* Under `make SAN=1`: Graphviz keeps its parsed plugin configuration
 * (gvconfig, inside gvContext) and fontconfig / pango keep font caches for
 * the life of the process.  Those are the libraries' own one-time
 * allocations, not leaks of ours, so LeakSanitizer is told to skip them in
 * every program that renders with gvc.  With fast unwinding the stack of
 * the gvconfig buffer stops at libgvc's gmalloc, hence the module pattern. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
    return "leak:gvconfig\n"
           "leak:libgvc.so\n"
           "leak:libfontconfig.so\n"
           "leak:libpango\n"
           "leak:libglib-2.0.so\n"
           "leak:libcairo.so\n";
}
#endif
