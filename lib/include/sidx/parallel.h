/* sidx/parallel.h — using every core: ray batches over threads, and the
 * parallel BVH build.
 *
 * The deck's "Parallelize it! Ray tracing is embarrassingly parallel":
 * rays are independent, a built structure is immutable, so threads only
 * need to agree on who traces which rays.  sidx_trace_parallel gives each
 * thread a contiguous share of the rays, traced in batches of
 * SIDX_PARALLEL_BATCH; a thread that finishes its share early steals
 * batches from the others' (lock-free, one atomic counter per share), so
 * an uneven scene (a few rays that cost 100x the others) does not leave a
 * core idle.  Contiguous shares keep coherent rays (image rows) on one
 * core, which keeps that core's cache warm.
 *
 * Building in parallel: sidx_build_options.threads > 1 makes the binned
 * SAH builder of "bvh" (and of "bvh4"/"bvh8", which collapse it) bin the
 * large top nodes on all threads and then build the subtrees below them
 * as independent tasks.  The tree is IDENTICAL to the one-thread build
 * (same splits, same node order, same box bits), only faster.  With a
 * build hook attached the build stays on one thread so events arrive in
 * order.
 *
 * Threads: the library starts its worker threads on first use and keeps
 * them (they sleep between calls; they are joined at exit, and a forked
 * child starts its own).  Calls from several application threads at once
 * are fine: one uses the workers, the others get threads of their own for
 * that call.
 *
 * Hooks: a traced query (q->hook set) runs on the calling thread alone, so
 * the hook sees the rays' events in order and is never called
 * concurrently. */
#ifndef SIDX_PARALLEL_H
#define SIDX_PARALLEL_H

#include <stddef.h>
#include <stdint.h>
#include "accel.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Rays per batch handed to a thread. */
#define SIDX_PARALLEL_BATCH 32u

/* Hardware threads online (at least 1). */
unsigned sidx_hardware_threads(void);

/* Closest hits of rays[0, n) into hits[0, n) on `threads` threads (0 = all
 * hardware threads; the calling thread is one of them).  Same results as
 * sidx_accel_intersect_n: ray ids are q->ray_id + i.  q may be NULL.
 * Fails on NULL arguments (SIDX_ERR_INVALID_ARG), and with SIDX_ERR_NOMEM
 * when a ray's query on a lazy tree did (sidx_accel_intersect); if threads cannot
 * be started the remaining work runs on the calling thread. */
sidx_status sidx_trace_parallel(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                sidx_hit *hits, unsigned threads);

/* Any-hit (shadow) queries: occluded[i] = 1 if ray i hits anything. */
sidx_status sidx_occluded_parallel(const sidx_accel *a, const sidx_ray *rays, size_t n, const sidx_query *q,
                                   uint8_t *occluded, unsigned threads);

#ifdef __cplusplus
}
#endif
#endif
