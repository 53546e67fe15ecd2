/* parallel.c — multi-core tracing and the parallel binned-SAH BVH build.
 *
 * Tracing (sidx_trace_parallel): the calling thread and threads − 1
 * pool workers each trace a contiguous share of the rays in batches of
 * SIDX_PARALLEL_BATCH and then steal batches from the shares of the others
 * until none are left.  Nothing else is shared: the structure is
 * read-only and each ray writes its own hit, so there is no lock and no
 * false sharing except at batch borders (a batch of 32 hits is 1.5 KB).
 *
 * Build (sidx__bvh_build_parallel, called by bvh_build.c): the same
 * decisions as the one-thread binned builder (Wald 2007), organised the
 * way Wald ("On fast construction of SAH-based bounding volume
 * hierarchies", 2007) and Embree's parallel builders do it:
 *
 *   1. top phase, on the calling thread: the nodes above n / (2·threads)
 *      triangles are split one after another, but their O(n) passes —
 *      the binning of all three axes, and the root's bounds — run on
 *      every thread over disjoint chunks, each thread filling private
 *      bins that are merged afterwards (box unions and counts are exact,
 *      so the merged bins equal sequential ones bit for bit).  The
 *      partition, which stays sequential, gathers both children's boxes
 *      on the way, so no node below the root needs a bounds pass;
 *   2. task phase: the subtrees the top phase reached are tasks.  The
 *      larger ones, "mid tasks", are top-phase subtrees in their own right:
 *      the threads build them at the same time, each cutting its own
 *      subtrees of at most n / (8·threads) triangles into further tasks —
 *      so the top of the tree is not one thread's work.  The threads
 *      take the largest ready task first (longest processing time first
 *      balances them), and build each straight into a region of the final
 *      node array reserved in pre-order;
 *   3. stitching: the regions are slid down over their unused tails in
 *      pre-order, the right-child indices shifted by the distance moved.

 * On one thread (threads = 0 or 1, no build hook) the same code runs
 * with no pool: the top phase, then every task on the caller.  Streaming
 * the packed references instead of gathering through idx[] makes it
 * cheaper than bvh_build.c's recursion, which is therefore kept only for
 * traced builds (docs/performance.md, Binary BVH, "The binned build on
 * one thread").

 * Every split sees the same triangles in the same index order as in the
 * sequential build (partitioning stays sequential and in place, the same
 * two-pointer loop), so the tree is identical — node for node — to the
 * one-thread tree; tests/test_parallel.c checks that. */
#include <pthread.h>
#include <stdatomic.h>
#include <unistd.h>
#include "bvh_internal.h"
#include "pool.h"
#include "sidx/parallel.h"

unsigned sidx_hardware_threads(void)
{
    const long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (unsigned)n : 1u;
}

/* Every run of work on several threads goes through the persistent pool
 * (pool.c): fn(ctx, t) for t in [0, nt), t = 0 on the caller. */
#define MAX_THREADS SIDX_POOL_MAX_THREADS
typedef sidx_pool_fn par_fn;
static void par_run(unsigned nt, par_fn fn, void *ctx) { sidx__pool_run(nt, fn, ctx); }

/* ---- tracing ------------------------------------------------------------------ */

/* Each thread starts on a contiguous share of the rays, n / threads of
 * them, taken SIDX_PARALLEL_BATCH at a time from the front through the
 * share's own counter; when its share is empty it steals batches from the
 * others' shares through their counters.  Compared with one counter for
 * everybody, a thread mostly walks its own run of consecutive (coherent)
 * rays and touches only its own counter, a cache line no other thread
 * writes until stealing starts — the shared counter bounced between the
 * cores at every batch.  Stealing keeps the balance of the single counter:
 * nobody idles while a batch is left.  So batches can be small (32 rays),
 * and the last one to finish is short. */
typedef struct trace_share {
    atomic_size_t next;
    size_t end;
    char pad[64 - sizeof(atomic_size_t) - sizeof(size_t)]; /* one cache line each */
} trace_share;

typedef struct trace_job {
    const sidx_accel *a;
    const sidx_ray *rays;
    size_t n;
    sidx_query q;
    sidx_hit *hits;
    uint8_t *occ;
    unsigned nt;
    atomic_int nomem; /* a lazy tree's expansion failed for some ray */
    trace_share share[MAX_THREADS];
} trace_job;

/* Trace batches from share s until it is empty. */
static void trace_share_drain(trace_job *j, trace_share *s, sidx_query *q, uint32_t base)
{
    for (;;) {
        const size_t b = atomic_fetch_add_explicit(&s->next, SIDX_PARALLEL_BATCH, memory_order_relaxed);
        if (b >= s->end) return;
        const size_t e = s->end - b > SIDX_PARALLEL_BATCH ? b + SIDX_PARALLEL_BATCH : s->end;
        for (size_t i = b; i < e; ++i) {
            q->ray_id = base + (uint32_t)i;
            sidx_status st;
            if (j->hits) {
                st = sidx_accel_intersect(j->a, &j->rays[i], q, &j->hits[i]);
            } else {
                int o = 0;
                st = sidx_accel_occluded(j->a, &j->rays[i], q, &o);
                j->occ[i] = (uint8_t)o;
            }
            if (SIDX_UNLIKELY(st != SIDX_OK)) atomic_store_explicit(&j->nomem, 1, memory_order_relaxed);
        }
    }
}

static void trace_worker(void *ctx, unsigned t)
{
    trace_job *j = ctx;
    sidx_query q = j->q;
    const uint32_t base = q.ray_id;
    for (unsigned k = 0; k < j->nt; ++k) trace_share_drain(j, &j->share[(t + k) % j->nt], &q, base);
}

static sidx_status trace_common(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                sidx_hit *hits, uint8_t *occ, unsigned threads)
{
    if (!a || (n && (!rays || (!hits && !occ)))) return SIDX_ERR_INVALID_ARG;
    trace_job j;
    j.a = a;
    j.rays = rays;
    j.n = n;
    if (q) j.q = *q;
    else memset(&j.q, 0, sizeof j.q);
    j.hits = hits;
    j.occ = occ;
    atomic_init(&j.nomem, 0);
    if (threads == 0) threads = sidx_hardware_threads();
    /* A traced query stays on this thread: ordered events, no concurrent hook calls. */
    if (j.q.hook && j.q.hook->fn) threads = 1;
    const size_t batches = (n + SIDX_PARALLEL_BATCH - 1) / SIDX_PARALLEL_BATCH;
    if (threads > batches) threads = batches ? (unsigned)batches : 1u;
    if (threads > MAX_THREADS) threads = MAX_THREADS;
    j.nt = threads;
    for (unsigned t = 0; t < threads; ++t) {
        /* share boundaries on whole batches, so only the last batch is short */
        const size_t lo = batches * t / threads * SIDX_PARALLEL_BATCH,
                     hi = batches * (t + 1) / threads * SIDX_PARALLEL_BATCH;
        atomic_init(&j.share[t].next, lo);
        j.share[t].end = hi < n ? hi : n;
    }
    par_run(threads, trace_worker, &j);
    return atomic_load_explicit(&j.nomem, memory_order_relaxed) ? SIDX_ERR_NOMEM : SIDX_OK;
}

sidx_status sidx_trace_parallel(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                sidx_hit *hits, unsigned threads)
{
    if (n && !hits) return SIDX_ERR_INVALID_ARG;
    return trace_common(a, rays, n, q, hits, NULL, threads);
}

sidx_status sidx_occluded_parallel(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                   uint8_t *occluded, unsigned threads)
{
    if (n && !occluded) return SIDX_ERR_INVALID_ARG;
    return trace_common(a, rays, n, q, NULL, occluded, threads);
}

/* ---- parallel build ------------------------------------------------------------- */

/* Nodes with at least this many triangles run their O(n) passes on all
 * threads: below it, starting threads costs more than the pass. */
#define PAR_PASS_MIN 16384u
/* The top phase stops at subtrees of at most n / (threads · TASK_SPLIT)
 * triangles, giving several tasks per thread to balance. */
#define TASK_SPLIT 8u
#define TASK_MIN 256u
/* The calling thread's top phase stops at subtrees of at most
 * n / (threads · MID_SPLIT) triangles: those are mid tasks, top-phase
 * subtrees that the threads build at the same time. */
#define MID_SPLIT 2u
/* Marks a top-phase node that is the root of a task (left_or_first = task). */
#define TASK_MARK 0xFFFFFFFFu

/* A primitive reference: its box and its id, 32 bytes.  The builder
 * partitions this array itself, not an index array into boxes and
 * centroids as bvh_build.c does: every pass over a node then streams
 * through contiguous memory instead of gathering from two tables at
 * random (Wald 2007 and Embree's PrimRef do the same).  The centroid is
 * recomputed as (lo + hi)·0.5, the expression sidx_aabb_centroid uses. */
typedef struct pref {
    float lo[3];
    uint32_t id;
    float hi[3];
    uint32_t pad;
} pref;
_Static_assert(sizeof(pref) <= sizeof(bvh_tri), "the references borrow the vertex copies' array");

typedef struct par_build {
    const sidx_accel *a;
    bvh_par_params params;
    pref *refs;
    unsigned threads;
} par_build;

/* One node array under construction, in pre-order. */
typedef struct nodebuf {
    bvh_node *nodes;
    uint32_t num, leaves, max_depth;
    uint32_t base; /* added to stored child indices: where nodes[0] sits in the final array */
} nodebuf;

/* A node's box and its centroids' box: what the recursion needs before it
 * can bin. */
typedef struct nodebox {
    sidx_aabb bb, cb;
} nodebox;

typedef struct task {
    uint32_t first, count, depth, top_node;
    int mid;     /* a mid task: a top-phase subtree of its own (see sidx__bvh_build_parallel) */
    int state;   /* TASK_WAITING (no region yet), TASK_READY, TASK_TAKEN; under taskset.mu */
    int has_box;
    nodebox box; /* the subtree root's boxes, when its parent's partition gathered them */
    uint32_t off; /* reserved region in the final array: 2·count − 1 nodes from here */
    nodebuf out;
} task;

enum { TASK_WAITING = 0, TASK_READY, TASK_TAKEN };
#define NO_TASK 0xFFFFFFFFu

/* Every task of one build, and what the threads need to hand them out. */
typedef struct taskset {
    task *tasks;
    uint32_t num, cap;
    uint32_t active_mids;  /* mid tasks not finished: they may still add tasks */
    pthread_mutex_t mu;
    pthread_cond_t cv;     /* a mid task finished: new tasks may be ready */
} taskset;

/* A new task slot, or NO_TASK when the array is full (the node is then
 * built where it is, which changes nothing but the balance). */
static uint32_t task_new(taskset *ts)
{
    pthread_mutex_lock(&ts->mu);
    uint32_t i = NO_TASK;
    if (ts->num < ts->cap) {
        i = ts->num++;
        ts->tasks[i].state = TASK_WAITING;
    }
    pthread_mutex_unlock(&ts->mu);
    return i;
}

/* A bin's box as two 4-float rows (x, y, z, unused), so that the binning
 * loop can grow it with one SSE min and one max: the SSE min of a and b
 * is a < b ? a : b lane by lane, exactly sidx_v3_min's expression (and max
 * sidx_v3_max's), so the boxes are bit for bit those of the scalar code
 * and of the sequential builder. */
typedef struct binbox {
    float lo[4], hi[4];
} binbox;

typedef struct bins3 {
    binbox box[3][1024];
    uint32_t count[3][1024];
} bins3;

static inline void binbox_empty(binbox *b)
{
    for (int k = 0; k < 4; ++k) {
        b->lo[k] = INFINITY;
        b->hi[k] = -INFINITY;
    }
}
static inline void binbox_union(binbox *d, const binbox *s)
{
    for (int k = 0; k < 4; ++k) {
        d->lo[k] = d->lo[k] < s->lo[k] ? d->lo[k] : s->lo[k];
        d->hi[k] = d->hi[k] > s->hi[k] ? d->hi[k] : s->hi[k];
    }
}


typedef struct binspec {
    float cmin[3], scale[3];
    int use[3];
    uint32_t nb;
} binspec;

static binspec make_binspec(const par_build *build, sidx_aabb cb)
{
    binspec s;
    s.nb = build->params.bins;
    for (int k = 0; k < 3; ++k) {
        s.cmin[k] = sidx_v3_get(cb.min, k);
        const float ext = sidx_v3_get(cb.max, k) - s.cmin[k];
        s.use[k] = ext > 0.0f; /* a flat axis has no plane between centroids */
        s.scale[k] = s.use[k] ? (float)s.nb / ext : 0.0f;
    }
    return s;
}

static void bins_clear(bins3 *b, uint32_t nb)
{
    for (int k = 0; k < 3; ++k)
        for (uint32_t i = 0; i < nb; ++i) {
            binbox_empty(&b->box[k][i]);
            b->count[k][i] = 0;
        }
}

/* ---- the kernels -----------------------------------------------------------------
 * All three axes in one pass over the references: one read of each box and
 * centroid instead of three (the sequential builder's axis loop).  With
 * SSE2 (every x86-64) the three axes go through one set of 4-lane
 * instructions — that is most of the build (docs/performance.md,
 * "Parallel build and trace") — else the reference; both bit for bit the
 * sequential builder's results.  bin_range, bounds_range, used_bins,
 * sweep_*, partition: */
#if defined(__SSE2__)
#include "simd_bin_sse.h"
#else
#include "simd_bin_scalar.h"
#endif

/* The parallel versions: each thread a contiguous chunk. */
typedef struct pass_ctx {
    const par_build *build;
    const binspec *s;
    uint32_t first, count;
    unsigned nt;
    bins3 *bins;         /* per thread */
    sidx_aabb *bb, *cb;  /* per thread */
} pass_ctx;

static void chunk(const pass_ctx *c, unsigned t, uint32_t *f, uint32_t *n)
{
    const uint64_t lo = (uint64_t)c->count * t / c->nt, hi = (uint64_t)c->count * (t + 1) / c->nt;
    *f = c->first + (uint32_t)lo;
    *n = (uint32_t)(hi - lo);
}
static void bounds_worker(void *ctx, unsigned t)
{
    pass_ctx *c = ctx;
    uint32_t f, n;
    chunk(c, t, &f, &n);
    bounds_range(c->build, f, n, &c->bb[t], &c->cb[t]);
}
static void bin_worker(void *ctx, unsigned t)
{
    pass_ctx *c = ctx;
    uint32_t f, n;
    chunk(c, t, &f, &n);
    bins_clear(&c->bins[t], c->s->nb);
    bin_range(c->build, c->s, f, n, &c->bins[t]);
}

typedef struct scratch {
    bins3 *bins;  /* [threads] for the top phase, [1] in tasks */
    float right_area[1024];
    uint32_t used[3][1024], nused[3]; /* non-empty bins of the last node, per axis */
} scratch;

typedef struct split {
    int axis;
    uint32_t nl, plane;
    float cost;
} split;

/* The sequential builder's find_binned: the same costs from the same float
 * expressions, the same tie rule (first minimum over axis, then plane) —
 * but only at planes right after a NON-EMPTY bin.  Behind an empty bin
 * the left box, the left count and the right box are all unchanged, so
 * the cost is bit-identical to the previous plane's and, ties going to
 * the first, can never win.  A node of 8 triangles has at most 8 of the
 * 32 bins filled: 7 planes per axis instead of 31, which is most of the
 * build time in the many small nodes near the leaves. */
static int best_split(const par_build *build, const bins3 *bn, uint32_t count, float inv_area, scratch *S, split *best)
{
    const uint32_t nb = build->params.bins;
    int found = 0;
    best->cost = INFINITY;
    for (int axis = 0; axis < 3; ++axis) {
        const binbox *box = bn->box[axis];
        const uint32_t *cnt = bn->count[axis];
        uint32_t *used = S->used[axis];
        const uint32_t k = used_bins(cnt, nb, used);
        S->nused[axis] = k;
        if (k < 2) continue; /* flat axis (not binned) or one bin: no plane */
        sweep_box acc = sweep_empty();
        for (uint32_t j = k; j-- > 1;) { /* right_area[j] = area of bins used[j..k) */
            acc = sweep_add(acc, &box[used[j]]);
            S->right_area[j] = sweep_area(acc);
        }
        acc = sweep_empty();
        uint32_t nl = 0;
        for (uint32_t j = 0; j + 1 < k; ++j) {
            acc = sweep_add(acc, &box[used[j]]);
            const float left_area = sweep_area(acc);
            nl += cnt[used[j]];
            const float cost =
                build->params.c_trav +
                build->params.c_tri * (left_area * (float)nl + S->right_area[j + 1] * (float)(count - nl)) * inv_area;
            if (cost < best->cost) {
                best->cost = cost;
                best->axis = axis;
                best->nl = nl;
                best->plane = used[j] + 1;
                found = 1;
            }
        }
    }
    return found;
}

/* One node and its subtree into out.  top: the top phase (parallel passes,
 * small subtrees become tasks) or 0 inside a task. */
typedef struct topctx {
    taskset *ts;
    uint32_t task_max; /* subtrees of at most this many triangles become tasks */
    uint32_t mid_max;  /* ... mid tasks above task_max and up to this (0: none) */
    int par_passes;    /* the caller's top phase: large nodes' passes on all threads */
} topctx;

static uint32_t build_rec(const par_build *build, scratch *S, nodebuf *out, topctx *top, uint32_t first, uint32_t count,
                          uint32_t depth, const nodebox *given)
{
    const uint32_t ni = out->num++;
    bvh_node *n = &out->nodes[ni];
    uint32_t ti;
    if (top && count <= (top->mid_max > top->task_max ? top->mid_max : top->task_max) &&
        count > build->params.leaf_size && depth < build->params.max_depth && (ti = task_new(top->ts)) != NO_TASK) {
        task *t = &top->ts->tasks[ti];
        t->mid = count > top->task_max;
        t->first = first;
        t->count = count;
        t->depth = depth;
        t->has_box = given != NULL;
        if (given) t->box = *given;
        t->top_node = ni;
        n->left_or_first = ti;
        n->count_axis = TASK_MARK;
        return ni;
    }
    const int par = top && top->par_passes && count >= PAR_PASS_MIN && build->threads > 1;
    sidx_aabb bb, cb;
    if (given) { /* gathered by the parent's partition */
        bb = given->bb;
        cb = given->cb;
    } else if (par) {
        sidx_aabb pbb[MAX_THREADS], pcb[MAX_THREADS];
        pass_ctx c = {build, NULL, first, count, build->threads, NULL, pbb, pcb};
        par_run(build->threads, bounds_worker, &c);
        bb = pbb[0];
        cb = pcb[0];
        for (unsigned t = 1; t < build->threads; ++t) {
            bb = sidx_aabb_union(bb, pbb[t]);
            cb = sidx_aabb_union(cb, pcb[t]);
        }
    } else {
        bounds_range(build, first, count, &bb, &cb);
    }
    n->bmin[0] = bb.min.x; n->bmin[1] = bb.min.y; n->bmin[2] = bb.min.z;
    n->bmax[0] = bb.max.x; n->bmax[1] = bb.max.y; n->bmax[2] = bb.max.z;
    if (depth > out->max_depth) out->max_depth = depth;

    const float area = sidx_aabb_area(bb);
    const float inv_area = area > 0.0f ? 1.0f / area : 0.0f;
    const float leaf_cost = (float)count * build->params.c_tri;
    int leaf = 0, axis = -1;
    uint32_t nl = 0;
    nodebox kids[2];
    int have_kids = 0;
    if (count <= build->params.leaf_size || depth >= build->params.max_depth) {
        leaf = 1;
    } else if (!(cb.max.x > cb.min.x) && !(cb.max.y > cb.min.y) && !(cb.max.z > cb.min.z)) {
        if (count > build->params.max_leaf) nl = count / 2; /* equal centroids: halve in index order */
        else leaf = 1;
    } else {
        const binspec s = make_binspec(build, cb);
        const bins3 *bn;
        if (par) {
            pass_ctx c = {build, &s, first, count, build->threads, S->bins, NULL, NULL};
            par_run(build->threads, bin_worker, &c);
            for (unsigned t = 1; t < build->threads; ++t)
                for (int k = 0; k < 3; ++k)
                    for (uint32_t j = 0; j < s.nb; ++j) {
                        S->bins[0].count[k][j] += S->bins[t].count[k][j];
                        binbox_union(&S->bins[0].box[k][j], &S->bins[t].box[k][j]);
                    }
        } else {
            bin_range(build, &s, first, count, &S->bins[0]); /* bins[0] is clean on entry */
        }
        bn = &S->bins[0];
        split sp = {0, 0, 0, INFINITY};
        const int found = best_split(build, bn, count, inv_area, S, &sp);
        /* Clean bins[0] for the next node by resetting only what was filled
         * (clearing all 3 x 32 boxes per node cost more than the binning
         * of a small node). */
        for (int k = 0; k < 3; ++k)
            for (uint32_t u = 0; u < S->nused[k]; ++u) {
                binbox_empty(&S->bins[0].box[k][S->used[k][u]]);
                S->bins[0].count[k][S->used[k][u]] = 0;
            }
        if (!found) {
            nl = count / 2; /* cannot happen with a non-flat centroid box */
        } else {
            /* Partitioned even when the SAH then keeps the node as a leaf,
             * as the sequential builder does: the leaf's triangle order
             * (and so its tie-breaking) stays the same. */
            axis = sp.axis;
            nl = partition(build, &s, first, count, sp.axis, sp.plane, &kids[0], &kids[1]);
            have_kids = 1;
            if (!(sp.cost < leaf_cost) && count <= build->params.max_leaf) leaf = 1;
        }
    }
    if (leaf) {
        n->left_or_first = first;
        n->count_axis = count;
        out->leaves++;
        return ni;
    }
    build_rec(build, S, out, top, first, nl, depth + 1, have_kids ? &kids[0] : NULL);
    const uint32_t right =
        build_rec(build, S, out, top, first + nl, count - nl, depth + 1, have_kids ? &kids[1] : NULL);
    n = &out->nodes[ni];
    n->left_or_first = right + out->base;
    n->count_axis = (uint32_t)(axis < 0 ? 0 : axis) << BVH_AXIS_SHIFT;
    return ni;
}

typedef struct task_job {
    const par_build *build;
    taskset *ts;
    uint32_t task_max;
    scratch *S; /* one per thread; allocated by the caller (a user allocator need not be thread-safe) */
    bvh_node *F; /* the final node array */
} task_job;

static void reserve(const nodebuf *top, task *tasks, uint32_t ti, uint32_t *off, bvh_node *F);

/* Take the largest ready task (longest processing time first balances
 * the threads), build it, repeat; wait while none is ready but a mid task
 * is still running (it will add some); stop when neither is left. */
static void task_worker(void *ctx, unsigned w)
{
    task_job *j = ctx;
    taskset *ts = j->ts;
    pthread_mutex_lock(&ts->mu);
    for (;;) {
        uint32_t best = NO_TASK;
        for (uint32_t i = 0; i < ts->num; ++i)
            if (ts->tasks[i].state == TASK_READY && (best == NO_TASK || ts->tasks[i].count > ts->tasks[best].count))
                best = i;
        if (best == NO_TASK) {
            if (ts->active_mids == 0) break;
            pthread_cond_wait(&ts->cv, &ts->mu);
            continue;
        }
        task *tk = &ts->tasks[best];
        tk->state = TASK_TAKEN;
        pthread_mutex_unlock(&ts->mu);
        const nodebox *box = tk->has_box ? &tk->box : NULL;
        if (tk->mid) {
            /* the top phase continued on this thread: its small subtrees become tasks */
            topctx tc = {ts, j->task_max, 0, 0};
            build_rec(j->build, &j->S[w], &tk->out, &tc, tk->first, tk->count, tk->depth, box);
            pthread_mutex_lock(&ts->mu);
            uint32_t off = tk->off;
            reserve(&tk->out, ts->tasks, 0, &off, j->F); /* its tasks get regions inside its own: ready */
            ts->active_mids--;
            pthread_cond_broadcast(&ts->cv);
        } else {
            build_rec(j->build, &j->S[w], &tk->out, NULL, tk->first, tk->count, tk->depth, box);
            pthread_mutex_lock(&ts->mu);
        }
    }
    pthread_mutex_unlock(&ts->mu);
}

/* Final layout without a second array: before the tasks run, every top
 * node gets one slot and every task a region of 2·count − 1 (the most
 * nodes a binary tree over count primitives can have) in pre-order — a
 * mid task, when its own top is built, lays out its nodes and its tasks'
 * regions the same way inside its region (1 + (2·l − 1) + (2·r − 1) =
 * 2·count − 1 for a split, so they fit); the tasks build straight into
 * their regions; then the regions are slid
 * down over the unused tails, in order (a region never moves up, so a
 * forward copy is safe).  Fresh memory costs page faults — in a virtual
 * machine as much as the building itself — so the nodes are written
 * once and moved once within the same pages. */
static void reserve(const nodebuf *top, task *tasks, uint32_t ti, uint32_t *off, bvh_node *F)
{
    const bvh_node *n = &top->nodes[ti];
    if (n->count_axis == TASK_MARK) {
        task *t = &tasks[n->left_or_first];
        t->off = *off;
        *off += 2u * t->count - 1u;
        if (F) { /* a mid task's: build straight into the final array */
            t->out.nodes = F + t->off;
            t->out.base = t->off;
            t->state = TASK_READY;
        }
        return;
    }
    *off += 1u;
    if (bvh_is_leaf(n)) return;
    reserve(top, tasks, ti + 1, off, F);
    reserve(top, tasks, n->left_or_first, off, F);
}

static uint32_t place(const nodebuf *top, const task *tasks, uint32_t ti, bvh_node *F, uint32_t *pos)
{
    const bvh_node *n = &top->nodes[ti];
    if (n->count_axis == TASK_MARK) {
        const task *t = &tasks[n->left_or_first];
        if (t->mid) return place(&t->out, tasks, 0, F, pos); /* its nodes are laid out like the top's */
        const uint32_t base = *pos, delta = t->off - base;
        for (uint32_t i = 0; i < t->out.num; ++i) {
            bvh_node c = F[t->off + i];
            if (!bvh_is_leaf(&c)) c.left_or_first -= delta;
            F[base + i] = c;
        }
        *pos += t->out.num;
        return base;
    }
    const uint32_t me = (*pos)++;
    F[me] = *n;
    if (bvh_is_leaf(n)) return me;
    place(top, tasks, ti + 1, F, pos);
    F[me].left_or_first = place(top, tasks, n->left_or_first, F, pos);
    return me;
}

/* The vertex copies in leaf order: a gather from the mesh, split in chunks. */
typedef struct fill_ctx {
    const sidx_mesh *m;
    bvh *b;
    uint32_t n;
    unsigned nt;
} fill_ctx;
static void fill_worker(void *ctx, unsigned t)
{
    fill_ctx *c = ctx;
    const uint32_t lo = (uint32_t)((uint64_t)c->n * t / c->nt), hi = (uint32_t)((uint64_t)c->n * (t + 1) / c->nt);
    for (uint32_t i = lo; i < hi; ++i)
        for (int k = 0; k < 3; ++k) c->b->tris[i].v[k] = sidx_mesh_vertex(c->m, c->b->prim_id[i], k);
}

/* The primitive references, split in chunks (a gather from the mesh that
 * the calling thread alone would otherwise do before any split). */
typedef struct pref_ctx {
    const sidx_mesh *m;
    pref *refs;
    uint32_t n;
    unsigned nt;
} pref_ctx;
static void pref_worker(void *ctx, unsigned t)
{
    pref_ctx *c = ctx;
    const uint32_t lo = (uint32_t)((uint64_t)c->n * t / c->nt), hi = (uint32_t)((uint64_t)c->n * (t + 1) / c->nt);
    for (uint32_t i = lo; i < hi; ++i) {
        sidx_aabb bb = sidx_aabb_empty(); /* as sidx__prim_boxes */
        for (int k = 0; k < 3; ++k) bb = sidx_aabb_grow(bb, sidx_mesh_vertex(c->m, i, k));
        pref *r = &c->refs[i];
        r->lo[0] = bb.min.x; r->lo[1] = bb.min.y; r->lo[2] = bb.min.z;
        r->hi[0] = bb.max.x; r->hi[1] = bb.max.y; r->hi[2] = bb.max.z;
        r->id = i;
        r->pad = 0;
    }
}

sidx_status sidx__bvh_build_parallel(sidx_accel *a, const bvh_par_params *p, sidx_error *err)
{
    const sidx_mesh *m = a->mesh;
    const uint32_t n = m->num_triangles;
    par_build build;
    build.refs = NULL;
    build.a = a;
    build.params = *p;
    build.threads = a->opt.threads > MAX_THREADS ? MAX_THREADS : a->opt.threads ? a->opt.threads : 1u;
    sidx_status s = SIDX_ERR_NOMEM;
    nodebuf top = {NULL, 0, 0, 0, 0};
    taskset ts;
    memset(&ts, 0, sizeof ts);
    int ts_init = 0;
    scratch *S = NULL, *wS = NULL;
    bins3 *bins = NULL, *wbins = NULL;
    bvh *b = sidx__calloc(a, 1, sizeof *b);
    if (!b) goto fail;
    b->num_prims = n;
    /* The references live in the vertex copies' array until the copies
     * are made: it is allocated anyway and is larger (36 bytes a triangle
     * against 32), and fresh pages cost a fault each — in a virtual
     * machine a good part of a build's time. */
    b->tris = sidx__alloc(a, n, sizeof *b->tris);
    b->prim_id = sidx__alloc(a, n, sizeof *b->prim_id);
    if (!b->tris || !b->prim_id) goto fail;
    build.refs = (pref *)(void *)b->tris;
    {
        pref_ctx pc = {m, build.refs, n, n >= PAR_PASS_MIN ? build.threads : 1u};
        par_run(pc.nt, pref_worker, &pc);
    }

    /* Top phase on this thread, down to the mid tasks. */
    topctx tc;
    tc.ts = &ts;
    tc.task_max = n / (build.threads * TASK_SPLIT);
    if (tc.task_max < TASK_MIN) tc.task_max = TASK_MIN;
    tc.mid_max = n / (build.threads * MID_SPLIT);
    tc.par_passes = 1;
    ts.cap = 2u * (n / tc.task_max + 1u) + 8u;
    ts.tasks = sidx__calloc(a, ts.cap, sizeof *ts.tasks);
    top.nodes = sidx__alloc(a, 2u * (size_t)n - 1u, sizeof *top.nodes);
    S = sidx__alloc(a, 1, sizeof *S);
    bins = sidx__alloc(a, build.threads, sizeof *bins);
    wS = sidx__calloc(a, build.threads, sizeof *wS);
    wbins = sidx__alloc(a, build.threads, sizeof *wbins);
    if (!ts.tasks || !top.nodes || !S || !bins || !wS || !wbins) goto fail;
    if (pthread_mutex_init(&ts.mu, NULL) != 0) goto fail;
    if (pthread_cond_init(&ts.cv, NULL) != 0) {
        pthread_mutex_destroy(&ts.mu);
        goto fail;
    }
    ts_init = 1;
    S->bins = bins;
    bins_clear(&bins[0], build.params.bins);
    build_rec(&build, S, &top, &tc, 0, n, 0, NULL);

    /* Regions in the final array for the top's tasks (a mid task's
     * region holds its own nodes and its tasks' regions); node buffers
     * for the mid tasks' own nodes after the top's, in the same array
     * (top nodes + 2·count − 1 per task never exceed its 2n − 1). */
    uint32_t reserved = 0;
    reserve(&top, ts.tasks, 0, &reserved, NULL);
    b->nodes_mem = sidx__alloc(a, (size_t)reserved + 2u, sizeof *b->nodes);
    if (!b->nodes_mem) goto fail;
    b->nodes = (bvh_node *)(void *)(((uintptr_t)b->nodes_mem + 63u) & ~(uintptr_t)63u);
    uint32_t mid_at = top.num;
    for (uint32_t i = 0; i < ts.num; ++i) {
        task *t = &ts.tasks[i];
        if (t->mid) {
            t->out.nodes = top.nodes + mid_at;
            t->out.base = 0;
            mid_at += 2u * t->count - 1u;
            ts.active_mids++;
        } else {
            t->out.nodes = b->nodes + t->off;
            t->out.base = t->off;
        }
        t->state = TASK_READY;
    }

    /* Task phase: mid and plain tasks on every thread, largest first. */
    for (unsigned t = 0; t < build.threads; ++t) {
        wS[t].bins = &wbins[t];
        bins_clear(&wbins[t], build.params.bins);
    }
    task_job j = {&build, &ts, tc.task_max, wS, b->nodes};
    par_run(ts.num ? build.threads : 1u, task_worker, &j);

    uint32_t total = top.num, leaves = top.leaves, maxd = top.max_depth;
    for (uint32_t i = 0; i < ts.num; ++i) {
        total += ts.tasks[i].out.num - 1u;
        leaves += ts.tasks[i].out.leaves;
        if (ts.tasks[i].out.max_depth > maxd) maxd = ts.tasks[i].out.max_depth;
    }
    uint32_t pos = 0;
    place(&top, ts.tasks, 0, b->nodes, &pos);
    b->num_nodes = total;
    for (uint32_t i = 0; i < n; ++i) b->prim_id[i] = build.refs[i].id; /* before the copies overwrite the references */
    b->num_leaves = leaves;
    b->max_depth = maxd;
    {
        fill_ctx fc = {m, b, n, n >= PAR_PASS_MIN ? build.threads : 1u};
        par_run(fc.nt, fill_worker, &fc);
    }
    /* The SAH cost exactly as bvh_build.c's tree_sah sums it. */
    {
        const double root = sidx_aabb_area(bvh_node_box(&b->nodes[0]));
        double sum = 0.0;
        if (!(root > 0.0)) {
            sum = (double)n * build.params.c_tri;
        } else {
            for (uint32_t i = 0; i < total; ++i) {
                const bvh_node *nd = &b->nodes[i];
                const double ar = sidx_aabb_area(bvh_node_box(nd)) / root;
                sum += bvh_is_leaf(nd) ? ar * build.params.c_tri * bvh_count(nd) : ar * build.params.c_trav;
            }
        }
        b->sah_cost = sum;
    }
    s = SIDX_OK;
    a->impl = b;
    /* as bvh_build.c: the walks fill u, v and the normal from the leaves'
     * triangle copies, so accel.c need not recompute them after each hit */
    a->fills_uv = a->fills_ng = 1;
    b = NULL;
fail:
    if (ts_init) {
        pthread_cond_destroy(&ts.cv);
        pthread_mutex_destroy(&ts.mu);
    }
    sidx__free(a, ts.tasks);
    sidx__free(a, top.nodes);
    sidx__free(a, S);
    sidx__free(a, bins);
    sidx__free(a, wS);
    sidx__free(a, wbins);
    if (b) {
        sidx__free(a, b->nodes_mem);
        sidx__free(a, b->prim_id);
        sidx__free(a, b->tris);
        sidx__free(a, b);
    }
    if (s != SIDX_OK) {
        a->impl = NULL;
        return sidx__fail(err, s, "%s: out of memory", a->name);
    }
    return SIDX_OK;
}
