/* bvh_optimize.c — improving a built binary BVH by reinsertion.
 *
 * A top-down build decides each split once, greedily, looking only at the
 * primitives below it; nothing corrects a choice that a later split made
 * poor.  Reinsertion (Bittner, Hapala & Havran 2013, "Fast
 * insertion-based optimization of bounding volume hierarchies") takes a
 * subtree N out of the tree and puts it back where it costs least:
 *
 *   remove   N's parent P disappears, N's sibling S takes P's place, and
 *            the boxes above shrink: the inner nodes' area falls by
 *            d_remove = A(P) + Σ_ancestors (A_before − A_after);
 *   search   putting N beside a node X creates an inner node of area
 *            A(X ∪ N) and grows every ancestor of X by A(anc ∪ N) − A(anc).
 *            The best X is found by branch and bound from the root with a
 *            priority queue ordered by that "induced" growth: no node
 *            below X can cost less than induced(X) + A(N), so the search
 *            stops when the cheapest queued bound reaches the best found;
 *   insert   P is reused as the new inner node over X and N, and the boxes
 *            above it are refitted.
 * The SAH (deck 000, "Surface Area Heuristic") of a tree is
 * Σ_inner C_trav·A/A(root) + Σ_leaves C_tri·N·A/A(root); the leaves never
 * change here (same boxes, same primitives) and neither does the root box,
 * so a move lowers the SAH by C_trav·(d_remove − best)/A(root).  A move is
 * made only when that gain is positive; otherwise N goes back exactly
 * where it was (the boxes are unions, so the refit restores them bit for
 * bit).
 *
 * Order: each pass visits every node once, largest area first (Bittner et
 * al. pick nodes by such measures; the largest nodes near the root move
 * the most area), in one fixed order, so the result depends only on the
 * tree, not on the time it takes.  Passes repeat until one gains less than
 * 0.1 % of the inner nodes' area, or OPT_MAX_PASSES.  The time budget
 * (opt.optimize_ms) is looked at every OPT_CLOCK_EVERY nodes: a budget
 * that cuts the pass short gives a tree that depends on the machine's
 * speed (still valid, never worse than the input).
 *
 * Depth: the traversal's stack is sized by BVH_DEPTH_LIMIT, so a position
 * is refused if it would put a leaf deeper than the build's depth limit.
 *
 * Layout afterwards: re-flattened in depth-first pre-order (left child =
 * id + 1), prim_id[]/tris[] rewritten leaf by leaf in the new order.
 * Inner nodes a move created get the axis along which their children's
 * box centres lie farthest apart, with the lower child on the left (what
 * the viewers read from the axis bits: the split direction); untouched
 * inner nodes keep their axis and child order.
 *
 * Rejected alternatives and figures: docs/performance.md, Binary BVH. */
#include <time.h>
#include "bvh_internal.h"

#define SIDX_STRUCTURE_NAME (a->name)

#define OPT_NONE UINT32_MAX
#define OPT_MAX_PASSES 16
#define OPT_CLOCK_EVERY 64u
/* A pass that lowers the inner nodes' summed area by less than this
 * fraction ends the optimisation. */
#define OPT_MIN_PASS_GAIN 1e-3
/* A move must win more than this fraction of the root's area: float
 * rounding must not turn a tie into an endless swap. */
#define OPT_MIN_MOVE_GAIN 1e-7

typedef struct onode {
    sidx_aabb box;
    uint32_t parent;
    uint32_t child[2];  /* OPT_NONE, OPT_NONE for a leaf */
    uint32_t first;     /* leaf: its range in the input prim_id[]/tris[] */
    uint32_t count;     /* leaf: primitives; inner: 0 */
    uint16_t height;    /* edges from here to the deepest leaf below */
    uint8_t axis;       /* inner: split axis (input's, or chosen when touched) */
    uint8_t touched;    /* created by a move: axis and child order to choose */
} onode;

typedef struct qentry {
    double bound;       /* induced cost of the node's ancestors */
    uint32_t node, depth;
} qentry;

typedef struct otree {
    onode *n;
    uint32_t root, max_depth;
    qentry *heap;
    uint32_t heap_size;
} otree;

static double area_d(sidx_aabb b)
{
    const double dx = (double)b.max.x - b.min.x, dy = (double)b.max.y - b.min.y, dz = (double)b.max.z - b.min.z;
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

/* Box and height of x from its children, then of every ancestor. */
static void refit_up(otree *T, uint32_t x)
{
    for (; x != OPT_NONE; x = T->n[x].parent) {
        onode *o = &T->n[x];
        const onode *l = &T->n[o->child[0]], *r = &T->n[o->child[1]];
        o->box = sidx_aabb_union(l->box, r->box);
        o->height = (uint16_t)(1u + (l->height > r->height ? l->height : r->height));
    }
}

static void replace_child(otree *T, uint32_t parent, uint32_t old, uint32_t now)
{
    if (parent == OPT_NONE) {
        T->root = now;
    } else {
        onode *p = &T->n[parent];
        p->child[p->child[0] == old ? 0 : 1] = now;
    }
    T->n[now].parent = parent;
}

/* ---- the priority queue (binary min-heap on bound) ------------------------ */

static void heap_push(otree *T, double bound, uint32_t node, uint32_t depth)
{
    uint32_t i = T->heap_size++;
    while (i > 0) {
        const uint32_t up = (i - 1) / 2;
        if (!(bound < T->heap[up].bound)) break;
        T->heap[i] = T->heap[up];
        i = up;
    }
    T->heap[i] = (qentry){bound, node, depth};
}

static qentry heap_pop(otree *T)
{
    const qentry top = T->heap[0], last = T->heap[--T->heap_size];
    uint32_t i = 0;
    for (;;) {
        uint32_t c = 2 * i + 1;
        if (c >= T->heap_size) break;
        if (c + 1 < T->heap_size && T->heap[c + 1].bound < T->heap[c].bound) ++c;
        if (!(T->heap[c].bound < last.bound)) break;
        T->heap[i] = T->heap[c];
        i = c;
    }
    if (T->heap_size > 0) T->heap[i] = last;
    return top;
}

/* Branch and bound: the node beside which N costs least (area added to
 * the inner nodes), among positions keeping leaves within the depth
 * limit.  N is out of the tree. */
static uint32_t best_position(otree *T, uint32_t N, double *best_cost, uint32_t *best_depth)
{
    const sidx_aabb nb = T->n[N].box;
    const double an = area_d(nb);
    const uint32_t hn = T->n[N].height;
    double best = INFINITY;
    uint32_t best_x = OPT_NONE;
    T->heap_size = 0;
    heap_push(T, 0.0, T->root, 0);
    while (T->heap_size > 0) {
        const qentry q = heap_pop(T);
        if (!(q.bound + an < best)) break; /* nothing queued can beat the best */
        const onode *x = &T->n[q.node];
        const double au = area_d(sidx_aabb_union(x->box, nb));
        const double direct = q.bound + au;
        const uint32_t h = hn > x->height ? hn : x->height;
        if (direct < best && q.depth + 1u + h <= T->max_depth) {
            best = direct;
            best_x = q.node;
            *best_depth = q.depth + 1u;
        }
        if (x->count == 0) {
            const double induced = q.bound + au - area_d(x->box);
            if (induced + an < best) {
                heap_push(T, induced, x->child[0], q.depth + 1u);
                heap_push(T, induced, x->child[1], q.depth + 1u);
            }
        }
    }
    *best_cost = best;
    return best_x;
}

/* Try to move N; returns the area gained (0 when N stays). */
static double try_move(const sidx_accel *a, otree *T, uint32_t N, int traced, double sah_scale, uint32_t pass)
{
    const uint32_t P = T->n[N].parent;
    if (P == OPT_NONE || T->n[P].parent == OPT_NONE) return 0.0; /* the root, or a child of it */
    const uint32_t G = T->n[P].parent;
    const int k = T->n[P].child[0] == N ? 0 : 1;
    const uint32_t S = T->n[P].child[1 - k];

    /* remove: S takes P's place, the boxes above shrink */
    double d_remove = area_d(T->n[P].box);
    replace_child(T, G, P, S);
    for (uint32_t x = G; x != OPT_NONE; x = T->n[x].parent) d_remove += area_d(T->n[x].box);
    refit_up(T, G);
    for (uint32_t x = G; x != OPT_NONE; x = T->n[x].parent) d_remove -= area_d(T->n[x].box);

    double cost;
    uint32_t depth = 0;
    uint32_t X = best_position(T, N, &cost, &depth);
    const double gain = d_remove - cost;
    const int move = X != OPT_NONE && X != S && gain > OPT_MIN_MOVE_GAIN * area_d(T->n[T->root].box);
    if (!move) X = S; /* back where it was, same side */

    onode *p = &T->n[P];
    replace_child(T, T->n[X].parent, X, P);
    p->child[k] = N;
    p->child[1 - k] = X;
    T->n[N].parent = P;
    T->n[X].parent = P;
    if (move) p->touched = 1;
    refit_up(T, P);
    if (!move) return 0.0;
    SIDX_EMIT(traced, a->opt.hook, SIDX_EV_BUILD_REINSERT, e_.node = N; e_.parent = P; e_.aux = X;
              e_.depth = depth; e_.count = pass; e_.cost = (float)(gain * sah_scale); e_.bounds = T->n[N].box);
    return gain;
}

static double elapsed_ms(const struct timespec *t0)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)(t.tv_sec - t0->tv_sec) * 1e3 + (double)(t.tv_nsec - t0->tv_nsec) * 1e-6;
}

/* Pass order: largest area first, ties by id. */
typedef struct okey {
    double area;
    uint32_t id;
} okey;

static int okey_cmp(const void *pa, const void *pb)
{
    const okey *x = pa, *y = pb;
    if (x->area != y->area) return x->area > y->area ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

/* The pre-order array again; input arrays are read, the new ones written. */
static void flatten(otree *T, const bvh *b, bvh_node *out, uint32_t *prim_id, bvh_tri *tris, uint32_t *max_depth)
{
    struct { uint32_t node, depth, patch; } stack[2 * BVH_DEPTH_LIMIT + 4];
    uint32_t sp = 0, k = 0, cursor = 0;
    *max_depth = 0;
    stack[sp++].node = T->root;
    stack[0].depth = 0;
    stack[0].patch = OPT_NONE;
    while (sp > 0) {
        const uint32_t x = stack[--sp].node, depth = stack[sp].depth, patch = stack[sp].patch;
        const uint32_t i = k++;
        if (patch != OPT_NONE) out[patch].left_or_first = i;
        onode *o = &T->n[x];
        bvh_node *d = &out[i];
        d->bmin[0] = o->box.min.x; d->bmin[1] = o->box.min.y; d->bmin[2] = o->box.min.z;
        d->bmax[0] = o->box.max.x; d->bmax[1] = o->box.max.y; d->bmax[2] = o->box.max.z;
        if (depth > *max_depth) *max_depth = depth;
        if (o->count > 0) {
            memcpy(prim_id + cursor, b->prim_id + o->first, o->count * sizeof *prim_id);
            if (tris) memcpy(tris + cursor, b->tris + o->first, o->count * sizeof *tris);
            d->left_or_first = cursor;
            d->count_axis = o->count;
            cursor += o->count;
            continue;
        }
        if (o->touched) {
            /* the axis of widest centre separation; the lower child left */
            const sidx_aabb l = T->n[o->child[0]].box, r = T->n[o->child[1]].box;
            const float dc[3] = {(r.min.x + r.max.x) - (l.min.x + l.max.x), (r.min.y + r.max.y) - (l.min.y + l.max.y),
                                 (r.min.z + r.max.z) - (l.min.z + l.max.z)};
            int ax = 0;
            for (int j = 1; j < 3; ++j)
                if (fabsf(dc[j]) > fabsf(dc[ax])) ax = j;
            o->axis = (uint8_t)ax;
            if (dc[ax] < 0.0f) {
                const uint32_t t = o->child[0];
                o->child[0] = o->child[1];
                o->child[1] = t;
            }
        }
        d->count_axis = (uint32_t)o->axis << BVH_AXIS_SHIFT;
        stack[sp].node = o->child[1];
        stack[sp].depth = depth + 1;
        stack[sp++].patch = i;
        stack[sp].node = o->child[0];
        stack[sp].depth = depth + 1;
        stack[sp++].patch = OPT_NONE;
    }
}

uint32_t sidx__bvh_optimize(const sidx_accel *a, bvh *b)
{
    const float budget = a->opt.optimize_ms;
    if (!(budget > 0.0f) || !b || b->num_nodes < 5) return 0;
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    const uint32_t nn = b->num_nodes;
    const bvh_par_params pp = bvh_params(a);
    const sidx_hook *hook = a->opt.hook;
    const int traced = hook && hook->fn; /* looked at once: untraced, every emit is one test of 0 */

    /* One block for the pointer tree, the queue and the pass order. */
    const size_t bytes = (size_t)nn * (sizeof(onode) + sizeof(qentry) + sizeof(okey));
    void *mem = sidx__alloc(a, bytes, 1);
    bvh_node *nodes_mem = sidx__alloc(a, (size_t)nn + 2u, sizeof *b->nodes);
    uint32_t *prim_id = sidx__alloc(a, b->num_prims ? b->num_prims : 1u, sizeof *prim_id);
    /* the spatial-split tree keeps no corner copy (bvh_spatial.c): none to move */
    bvh_tri *tris = b->tris ? sidx__alloc(a, b->num_prims ? b->num_prims : 1u, sizeof *tris) : NULL;
    if (!mem || !nodes_mem || !prim_id || (b->tris && !tris)) { /* no memory to improve it: the tree stays as built */
        sidx__free(a, mem);
        sidx__free(a, nodes_mem);
        sidx__free(a, prim_id);
        sidx__free(a, tris);
        return 0;
    }
    otree T;
    T.n = mem;
    T.heap = (qentry *)(void *)(T.n + nn);
    okey *order = (okey *)(void *)(T.heap + nn);
    T.root = 0;
    T.max_depth = pp.max_depth;
    T.heap_size = 0;

    for (uint32_t i = 0; i < nn; ++i) {
        const bvh_node *s = &b->nodes[i];
        onode *o = &T.n[i];
        o->box = bvh_node_box(s);
        o->touched = 0;
        o->height = 0;
        if (i == 0) o->parent = OPT_NONE;
        if (bvh_is_leaf(s)) {
            o->child[0] = o->child[1] = OPT_NONE;
            o->first = s->left_or_first;
            o->count = bvh_count(s);
            o->axis = 0;
        } else {
            o->child[0] = i + 1;
            o->child[1] = s->left_or_first;
            o->first = 0;
            o->count = 0;
            o->axis = (uint8_t)bvh_axis(s);
            T.n[i + 1].parent = T.n[s->left_or_first].parent = i;
        }
    }
    for (uint32_t i = nn; i-- > 0;) /* children follow their parent: heights bottom-up */
        if (T.n[i].count == 0) {
            const uint16_t hl = T.n[T.n[i].child[0]].height, hr = T.n[T.n[i].child[1]].height;
            T.n[i].height = (uint16_t)(1u + (hl > hr ? hl : hr));
        }
    /* A tree deeper than the limit (possible for input not from our
     * builders) could not be checked by the search: leave it. */
    uint32_t moves = 0;
    const double root_area = area_d(T.n[0].box);
    if (T.n[0].height <= T.max_depth && root_area > 0.0) {
        const double sah_scale = pp.c_trav / root_area;
        int out_of_time = 0;
        uint32_t tick = 0;
        for (uint32_t pass = 1; pass <= OPT_MAX_PASSES && !out_of_time; ++pass) {
            double inner = 0.0, gained = 0.0;
            for (uint32_t i = 0; i < nn; ++i) {
                order[i].area = area_d(T.n[i].box);
                order[i].id = i;
                if (T.n[i].count == 0) inner += order[i].area;
            }
            qsort(order, nn, sizeof *order, okey_cmp);
            for (uint32_t i = 0; i < nn; ++i) {
                if (++tick % OPT_CLOCK_EVERY == 0 && elapsed_ms(&t0) > (double)budget) {
                    out_of_time = 1;
                    break;
                }
                const double g = try_move(a, &T, order[i].id, traced, sah_scale, pass);
                if (g > 0.0) {
                    gained += g;
                    ++moves;
                }
            }
            if (gained < OPT_MIN_PASS_GAIN * inner) break;
        }
    }
    if (moves > 0) {
        bvh_node *nodes = (bvh_node *)(void *)(((uintptr_t)nodes_mem + 63u) & ~(uintptr_t)63u);
        uint32_t depth = 0;
        flatten(&T, b, nodes, prim_id, tris, &depth);
        sidx__free(a, b->nodes_mem);
        sidx__free(a, b->prim_id);
        sidx__free(a, b->tris);
        b->nodes_mem = nodes_mem;
        b->nodes = nodes;
        b->prim_id = prim_id;
        b->tris = tris;
        b->max_depth = depth;
        b->sah_cost = sidx__bvh_tree_sah(b, pp.c_trav, pp.c_tri);
        if (b->obbs) (void)sidx__bvh_fit_obbs(a, b); /* reuses its array: cannot fail */
    } else {
        sidx__free(a, nodes_mem);
        sidx__free(a, prim_id);
        sidx__free(a, tris);
    }
    sidx__free(a, mem);
    return moves;
}
