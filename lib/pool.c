/* pool.c — persistent worker threads for sidx_trace_parallel and the
 * parallel build.
 *
 * Creating and joining a thread costs tens of microseconds (far more in a
 * virtual machine), and the parallel build hands work to the other cores
 * a dozen times per build: once per pass over each large top node.  So
 * the threads are started once, on first use, and then sleep between
 * runs (Embree's task scheduler and OpenMP runtimes do the same; the deck's
 * "Parallelize it!" assumes the workers already exist).
 *
 * One run at a time owns the pool (an atomic flag).  A second caller that
 * arrives while it is busy — another application thread, or a run started
 * from inside a worker — does not wait: it gets threads of its own for
 * that call, the pre-pool behaviour, so concurrent callers never block
 * each other and nesting cannot deadlock.
 *
 * Hand-over: the caller publishes (fn, ctx, nt), then bumps a generation
 * counter under the mutex and broadcasts; a worker that sees a new
 * generation runs its share if its id is below nt, and every worker
 * acknowledges by decrementing `pending`.  Both sides spin briefly before
 * sleeping on a condition variable: a build's passes come back to back,
 * and a futex wake-up is slower than the pass it would start.  The
 * generation is read under the mutex before sleeping and bumped under it,
 * so no wake-up is lost.
 *
 * fork(): the child has none of the parent's threads; a pthread_atfork
 * child handler forgets them (and re-creates the mutex and conditions,
 * which another thread may have held at the fork), so the child starts its
 * own pool on first use.  Exit: an atexit handler stops and joins the
 * workers (unless a run is in progress, then they simply end with the
 * process) and leaves the pool marked busy, so anything that runs later
 * uses threads of its own. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include "pool.h"
#include "simd_isa.h"
#define POOL_PAUSE() SIDX_SPIN_PAUSE()

/* Spin iterations before sleeping: a few microseconds. */
#define POOL_SPIN 4096

typedef struct pool {
    pthread_mutex_t mu;
    pthread_cond_t wake; /* workers wait here for a new generation */
    pthread_cond_t idle; /* the caller waits here for pending == 0 */
    pthread_t th[SIDX_POOL_MAX_THREADS];
    unsigned workers;    /* running workers, ids 1 .. workers */
    int quit;
    atomic_int busy;     /* a run owns the pool */
    atomic_uint gen;     /* bumped once per run */
    atomic_uint pending; /* workers that have not acknowledged the run */
    sidx_pool_fn fn;     /* the current run, published before gen */
    void *ctx;
    unsigned nt;
} pool;

static pool P = {.mu = PTHREAD_MUTEX_INITIALIZER, .wake = PTHREAD_COND_INITIALIZER, .idle = PTHREAD_COND_INITIALIZER};
static pthread_once_t P_once = PTHREAD_ONCE_INIT;

typedef struct worker_arg {
    unsigned id, seen;
} worker_arg;
static worker_arg P_args[SIDX_POOL_MAX_THREADS];

static void *worker_main(void *p)
{
    const unsigned id = ((worker_arg *)p)->id;
    unsigned seen = ((worker_arg *)p)->seen;
    for (;;) {
        unsigned g = atomic_load_explicit(&P.gen, memory_order_acquire);
        for (int s = 0; g == seen && s < POOL_SPIN; ++s) {
            POOL_PAUSE();
            g = atomic_load_explicit(&P.gen, memory_order_acquire);
        }
        if (g == seen) {
            pthread_mutex_lock(&P.mu);
            while ((g = atomic_load_explicit(&P.gen, memory_order_acquire)) == seen && !P.quit)
                pthread_cond_wait(&P.wake, &P.mu);
            const int quit = P.quit;
            pthread_mutex_unlock(&P.mu);
            if (quit) return NULL;
        }
        seen = g;
        if (id < P.nt) P.fn(P.ctx, id);
        if (atomic_fetch_sub_explicit(&P.pending, 1u, memory_order_acq_rel) == 1u) {
            pthread_mutex_lock(&P.mu);
            pthread_cond_signal(&P.idle);
            pthread_mutex_unlock(&P.mu);
        }
    }
}

/* In the child of a fork: the workers are the parent's, not ours. */
static void pool_after_fork_child(void)
{
    pthread_mutex_init(&P.mu, NULL);
    pthread_cond_init(&P.wake, NULL);
    pthread_cond_init(&P.idle, NULL);
    P.workers = 0;
    P.quit = 0;
    atomic_store(&P.pending, 0u);
    atomic_store(&P.busy, 0);
}

static void pool_at_exit(void)
{
    if (atomic_exchange(&P.busy, 1)) return; /* a run in progress: its threads end with the process */
    pthread_mutex_lock(&P.mu);
    P.quit = 1;
    pthread_cond_broadcast(&P.wake);
    pthread_mutex_unlock(&P.mu);
    for (unsigned w = 1; w <= P.workers; ++w) pthread_join(P.th[w], NULL);
    P.workers = 0; /* busy stays set: later runs use threads of their own */
}

static void pool_once(void)
{
    pthread_atfork(NULL, NULL, pool_after_fork_child);
    atexit(pool_at_exit);
}

/* ---- the fallback: threads for this call only ------------------------------- */

typedef struct own_arg {
    sidx_pool_fn fn;
    void *ctx;
    unsigned t;
} own_arg;
static void *own_main(void *p)
{
    own_arg *a = p;
    a->fn(a->ctx, a->t);
    return NULL;
}
static void run_own_threads(unsigned nt, sidx_pool_fn fn, void *ctx)
{
    pthread_t th[SIDX_POOL_MAX_THREADS];
    own_arg args[SIDX_POOL_MAX_THREADS];
    int started[SIDX_POOL_MAX_THREADS];
    for (unsigned t = 1; t < nt; ++t) {
        args[t] = (own_arg){fn, ctx, t};
        started[t] = pthread_create(&th[t], NULL, own_main, &args[t]) == 0;
    }
    fn(ctx, 0);
    for (unsigned t = 1; t < nt; ++t) {
        if (started[t]) pthread_join(th[t], NULL);
        else fn(ctx, t);
    }
}

void sidx__pool_run(unsigned nt, sidx_pool_fn fn, void *ctx)
{
    if (nt > SIDX_POOL_MAX_THREADS) nt = SIDX_POOL_MAX_THREADS;
    if (nt <= 1) {
        fn(ctx, 0);
        return;
    }
    pthread_once(&P_once, pool_once);
    if (atomic_exchange(&P.busy, 1)) {
        run_own_threads(nt, fn, ctx);
        return;
    }
    /* Grow the pool to nt − 1 workers; one that cannot start leaves its
     * share (and the higher ones) to the caller below. */
    while (P.workers + 1 < nt) {
        const unsigned w = P.workers + 1;
        P_args[w].id = w;
        P_args[w].seen = atomic_load(&P.gen);
        if (pthread_create(&P.th[w], NULL, worker_main, &P_args[w]) != 0) break;
        P.workers = w;
    }
    P.fn = fn;
    P.ctx = ctx;
    P.nt = nt;
    atomic_store_explicit(&P.pending, P.workers, memory_order_relaxed);
    pthread_mutex_lock(&P.mu);
    atomic_fetch_add_explicit(&P.gen, 1u, memory_order_release);
    pthread_cond_broadcast(&P.wake);
    pthread_mutex_unlock(&P.mu);

    fn(ctx, 0);
    for (unsigned t = P.workers + 1; t < nt; ++t) fn(ctx, t);

    for (int s = 0; atomic_load_explicit(&P.pending, memory_order_acquire) && s < POOL_SPIN; ++s) POOL_PAUSE();
    if (atomic_load_explicit(&P.pending, memory_order_acquire)) {
        pthread_mutex_lock(&P.mu);
        while (atomic_load_explicit(&P.pending, memory_order_acquire)) pthread_cond_wait(&P.idle, &P.mu);
        pthread_mutex_unlock(&P.mu);
    }
    atomic_store_explicit(&P.busy, 0, memory_order_release);
}
