/* dot.c — a structure's tree as a Graphviz graph, built with cgraph and
 * laid out and rendered with gvc.
 *
 * Inner nodes say what decided them (axis, split position, SAH cost,
 * primitive count); leaves their primitive count, leaf reason, the ids of
 * their primitives (from BUILD_LEAF; the first DOT_LEAF_IDS of a big leaf)
 * and, with a ray, the primitives the ray tested there.  With a ray, visited nodes are
 * filled along a yellow-to-red gradient in visit order and numbered, nodes
 * whose box test failed are greyed, the hit leaf gets a double red border.
 * Below max_depth each cut subtree becomes one summary node. */
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
    uint32_t summaries;
    float scale;        /* the scene's extent: split values within a few ulps of it print as 0 */
    const sidx_accel *labels; /* node labels, or NULL */
} dot_ctx;

/* Wide trees (grid2's hundreds of top-level cells, the octree's eight children per node) drawn
 * level by level make strips tens of thousands of points wide.  Two remedies keep a page:
 *  - children past DOT_ROW of one parent wrap into further rows (invisible edges stack row k
 *    under row k-1; the parent's edges to them do not constrain the ranks);
 *  - without an explicit depth, the cut level is the deepest (up to SIDX_DOT_DEFAULT_DEPTH) at
 *    which the drawing holds at most DOT_NODE_BUDGET nodes. */
#define DOT_ROW 8u
#define DOT_NODE_BUDGET 160u
#define DOT_WIDTH_BUDGET 32u

/* Nodes drawn when cutting after `level` levels: the nodes of levels 0..level plus one summary
 * per inner node of the last level. */
static uint32_t auto_cut_level(const sidx_viz_tree *t, uint32_t max_level)
{
    uint32_t *cur = malloc(t->count * sizeof *cur), *next = malloc(t->count * sizeof *next);
    uint32_t best = 1, drawn = 1, ncur = 1;
    if (!cur || !next) { free(cur); free(next); return max_level; }
    cur[0] = t->root;
    for (uint32_t level = 1; level <= max_level && ncur; ++level) {
        uint32_t nnext = 0;
        for (uint32_t i = 0; i < ncur; ++i) {
            const sidx_viz_node *nd = &t->nodes[cur[i]];
            for (uint32_t k = 0; k < nd->child_count; ++k) next[nnext++] = t->children[nd->child_base + k];
        }
        /* the widest rank of this level: each parent's children wrapped into rows of DOT_ROW */
        uint32_t width = 0;
        for (uint32_t i = 0; i < ncur; ++i) {
            const uint32_t k = t->nodes[cur[i]].child_count;
            width += k < DOT_ROW ? k : DOT_ROW;
        }
        drawn += nnext;
        uint32_t inner = 0;
        for (uint32_t i = 0; i < nnext; ++i) inner += t->nodes[next[i]].child_count > 0;
        if (level > 1 && (drawn + inner > DOT_NODE_BUDGET || width > DOT_WIDTH_BUDGET)) break;
        best = level;
        uint32_t *tmp = cur;
        cur = next;
        next = tmp;
        ncur = nnext;
    }
    free(cur);
    free(next);
    return best;
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
    return n;
}

static int add_summary(dot_ctx *c, Agnode_t *parent, uint32_t i)
{
    const sidx_viz_tree *t = c->t;
    const sidx_viz_node *nd = &t->nodes[i];
    uint32_t nodes = 0, visited = 0;
    uint64_t prims = 0;
    for (uint32_t k = 0; k < nd->child_count; ++k) {
        uint32_t nn;
        uint64_t pp;
        sidx_viz_tree_subtree(t, t->children[nd->child_base + k], &nn, &pp);
        nodes += nn;
        prims += pp;
    }
    if (c->with_ray) {
        /* visited nodes below: walk the subtree */
        uint32_t *stack = malloc(t->count * sizeof *stack);
        if (!stack) return -1;
        size_t sp = 0;
        for (uint32_t k = 0; k < nd->child_count; ++k) stack[sp++] = t->children[nd->child_base + k];
        while (sp) {
            const sidx_viz_node *x = &t->nodes[stack[--sp]];
            if (x->visit_order) ++visited;
            for (uint32_t k = 0; k < x->child_count && sp < t->count; ++k) stack[sp++] = t->children[x->child_base + k];
        }
        free(stack);
    }
    char name[40], label[96];
    snprintf(name, sizeof name, "cut%u", nd->id);
    if (visited)
        snprintf(label, sizeof label, "+%u nodes, %llu prims\\nray visited %u", nodes, (unsigned long long)prims,
                 visited);
    else
        snprintf(label, sizeof label, "+%u nodes, %llu prims", nodes, (unsigned long long)prims);
    Agnode_t *s = agnode(c->g, name, 1);
    if (!s) return -1;
    set(s, "label", label);
    set(s, "shape", "folder");
    set(s, "style", "filled,dashed");
    set(s, "fillcolor", visited ? "#ffe0b0" : "#f0f0f0");
    Agedge_t *e = agedge(c->g, parent, s, NULL, 1);
    if (!e) return -1;
    set(e, "style", "dashed");
    c->summaries++;
    return 0;
}

static int build_graph(dot_ctx *c)
{
    const sidx_viz_tree *t = c->t;
    Agnode_t **made = calloc(t->count, sizeof *made);
    uint32_t *stack = malloc(t->count * sizeof *stack), *level = malloc(t->count * sizeof *level);
    int rc = 0;
    if (!made || !stack || !level) { rc = -1; goto out; }
    size_t sp = 0;
    stack[sp++] = t->root;
    level[t->root] = 0;
    while (sp && rc == 0) {
        uint32_t i = stack[--sp];
        const sidx_viz_node *nd = &t->nodes[i];
        Agnode_t *n = add_node(c, i);
        if (!n) { rc = -1; break; }
        made[i] = n;
        if (nd->parent != SIDX_VIZ_NONE && made[nd->parent]) {
            /* a wrapped child (past DOT_ROW of its parent's children) hangs from the sibling one
             * row above by a dotted line, two ranks down (room for that sibling's summary): an
             * edge from the parent, routed around the rows, would widen the drawing again */
            const sidx_viz_node *p = &t->nodes[nd->parent];
            uint32_t k = 0;
            while (k < p->child_count && t->children[p->child_base + k] != i) ++k;
            Agnode_t *from = made[nd->parent];
            if (k >= DOT_ROW && k < p->child_count) from = made[t->children[p->child_base + k - DOT_ROW]];
            Agedge_t *e = from ? agedge(c->g, from, n, NULL, 1) : NULL;
            if (!e) { rc = -1; break; }
            if (from != made[nd->parent]) {
                set(e, "style", "dotted");
                set(e, "color", "#9a9a9a");
                set(e, "arrowhead", "none");
                set(e, "weight", "100");
                set(e, "minlen", level[i] < c->cut_level ? "1" : "2");
            } else if (c->with_ray && nd->visit_order && p->visit_order) {
                set(e, "color", "#d04000");
                set(e, "penwidth", "2");
            }
        }
        if (nd->child_count == 0) continue;
        if (level[i] >= c->cut_level) {
            rc = add_summary(c, n, i);
            continue;
        }
        /* push in reverse so children are created left to right */
        for (uint32_t k = nd->child_count; k-- > 0;) {
            const uint32_t ch = t->children[nd->child_base + k];
            level[ch] = level[i] + 1;
            stack[sp++] = ch;
        }
    }
out:
    free(made);
    free(stack);
    free(level);
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
    c.cut_level = o.max_depth ? o.max_depth : auto_cut_level(&t, SIDX_DOT_DEFAULT_DEPTH);
    {
        const sidx_aabb rb = t.nodes[t.root].bounds;
        const float m[6] = {rb.min.x, rb.min.y, rb.min.z, rb.max.x, rb.max.y, rb.max.z};
        for (int k = 0; k < 6; ++k)
            if (isfinite(m[k]) && fabsf(m[k]) > c.scale) c.scale = fabsf(m[k]);
    }

    Agdesc_t desc = Agdirected;
    c.g = agopen((char *)"sidx", desc, NULL);
    if (!c.g) {
        sidx_viz_tree_free(&t);
        return fail(err, SIDX_ERR_NOMEM, "cgraph: agopen failed");
    }
    char title[200];
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
    set(c.g, "label", title);
    set(c.g, "labelloc", "t");
    set(c.g, "fontname", "Helvetica");
    set(c.g, "ordering", "out");
    agattr(c.g, AGNODE, (char *)"shape", (char *)"box");
    agattr(c.g, AGNODE, (char *)"style", (char *)"rounded,filled");
    agattr(c.g, AGNODE, (char *)"fontname", (char *)"Helvetica");
    agattr(c.g, AGNODE, (char *)"fontsize", (char *)"10");
    agattr(c.g, AGEDGE, (char *)"arrowsize", (char *)"0.6");

    if (build_graph(&c) != 0) {
        agclose(c.g);
        sidx_viz_tree_free(&t);
        return fail(err, SIDX_ERR_NOMEM, "cgraph: out of memory building the graph");
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
        GVC_t *gvc = gvContext();
        rc = gvc ? gvLayout(gvc, c.g, "dot") : -1;
        if (rc == 0) {
            rc = gvRender(gvc, c.g, fmt, f);
            gvFreeLayout(gvc, c.g);
        }
        if (gvc) gvFreeContext(gvc);
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
