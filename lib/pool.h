/* pool.h — the library's persistent worker threads (lib/pool.c).  Internal:
 * not part of the public interface. */
#ifndef SIDX_POOL_H
#define SIDX_POOL_H

/* Most threads one run uses (the caller included). */
#define SIDX_POOL_MAX_THREADS 64u

typedef void (*sidx_pool_fn)(void *ctx, unsigned t);

/* Run fn(ctx, t) for every t in [0, nt), t = 0 on the calling thread, and
 * return when all have returned.  The others run on the pool's persistent
 * workers; when the pool is busy (a second caller at the same time, or a
 * call from inside a worker) they run on threads created for this call,
 * and a share whose thread cannot be started runs on the caller.  nt is
 * clamped to [1, SIDX_POOL_MAX_THREADS]. */
void sidx__pool_run(unsigned nt, sidx_pool_fn fn, void *ctx);

#endif
