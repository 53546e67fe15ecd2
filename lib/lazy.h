/* lazy.h — the life of a lazily built part (internal).
 *
 * A lazy structure builds its top now and leaves parts — a subtree of a
 * tree, an instance's whole structure in an aggregate — for the first ray
 * that reaches them.  Whatever the part is, its life is the same, and this
 * module owns it:
 *
 *   unbuilt --claim (CAS)--> busy --publish (release)--> built
 *                             |
 *                             +--failure (out of memory)--> unbuilt
 *
 *   claim    the first thread to reach an unbuilt part moves it to busy
 *            with a compare-and-swap and builds it; a thread that finds it
 *            busy waits (spins, then yields) until it leaves busy;
 *   build    the owner's expand function builds the part *in arrays of its
 *            own* (the model all lazy trees can share: nothing of the
 *            owner's arrays is written, so readers of the rest of the
 *            structure never see a half-built node) and returns it;
 *   publish  the part's pointer is stored, then the state is stored BUILT
 *            with release; a reader loads the state with acquire and, seeing
 *            BUILT, reads the pointer and everything the part holds (C11
 *            release / acquire: every write of the build happens before);
 *   failure  the expand function returns NULL having kept nothing (it frees
 *            what it had); the part goes back to unbuilt, so a later query
 *            may try again, and the query running on this thread is marked
 *            (sidx__lazy_failed below): it returns SIDX_ERR_NOMEM;
 *   counters parts built / unbuilt and the primitive references they hold,
 *            bytes built and the deepest part, for the stats: relaxed
 *            atomics, exact once the queries are over.
 *
 * A walk reaches a part through sidx__lazy_get: one acquire load and a
 * branch when the part is built, the claim / wait / build path in lazy.c
 * (a call) otherwise.  Every lazy structure lives on it: the aggregate's
 * instances (instance.c) and the trees (bvh_build.c, bvh_wide.c,
 * kdtree_build.c), one sidx__lazy_part per unbuilt node, reached by their
 * walks' node fetch (docs/architecture.md "Lazy builds"). */
#ifndef SIDX_LAZY_H
#define SIDX_LAZY_H

#include "sidx_internal.h"

enum { SIDX__LAZY_UNBUILT = 0, SIDX__LAZY_BUSY = 1, SIDX__LAZY_BUILT = 2 };

/* One part: its state (atomic) and, once built, what the expand function
 * returned.  Zero-initialised = unbuilt. */
typedef struct sidx__lazy_part {
    uint32_t state;
    void *built;
} sidx__lazy_part;

/* What an expansion tells the counters about the part it built. */
typedef struct sidx__lazy_made {
    uint64_t refs;   /* primitive references of the part (as counted when it was deferred) */
    uint64_t bytes;  /* memory the part holds */
    uint32_t depth;  /* the deepest level it reaches, in the owner's terms */
} sidx__lazy_made;

/* Builds part `index` of `owner` in arrays of its own and returns it, its
 * figures in *made; NULL when memory runs out, with nothing kept.  hook:
 * the query's, for the part's build events (NULL = none).  Called at most
 * once at a time per part, on the thread that claimed it. */
typedef void *(*sidx__lazy_expand_fn)(void *owner, uint32_t index, const sidx_hook *hook, sidx__lazy_made *made);

typedef struct sidx__lazy_counts {
    uint32_t built, unbuilt;            /* parts */
    uint64_t built_refs, unbuilt_refs;  /* their primitive references */
    uint64_t built_bytes;
    uint32_t max_depth;
} sidx__lazy_counts;

/* The owner's lazy state: its parts, its expand function, the counters. */
typedef struct sidx__lazy {
    sidx__lazy_part *parts;
    uint32_t num_parts;
    sidx__lazy_expand_fn expand;
    void *owner;
    sidx__lazy_counts counts; /* atomic fields */
} sidx__lazy;

/* Sets L up over parts[0..n) (zeroed by the caller: all unbuilt); the
 * counters start at zero: sidx__lazy_defer counts each part left for later. */
void sidx__lazy_init(sidx__lazy *L, sidx__lazy_part *parts, uint32_t n, sidx__lazy_expand_fn expand, void *owner);
/* At build time, before any query: part `index` waits for a ray, holding
 * refs primitive references. */
void sidx__lazy_defer(sidx__lazy *L, uint32_t index, uint64_t refs);

/* At build time, before any query: part `index` is built now (an eager
 * build through the same parts), published and counted as built. */
void sidx__lazy_built_now(sidx__lazy *L, uint32_t index, void *part, const sidx__lazy_made *made);

/* The slow path of sidx__lazy_get: claim, build and publish, or wait for
 * the thread that builds it.  NULL when this thread's build failed. */
void *sidx__lazy_claim(sidx__lazy *L, uint32_t index, const sidx_hook *hook);

/* Part `index`, built now if no ray reached it before.  NULL when the
 * memory for it could not be had (the query is marked: it returns
 * SIDX_ERR_NOMEM; the part stays unbuilt for a later query). */
static SIDX_INLINE void *sidx__lazy_get(sidx__lazy *L, uint32_t index, const sidx_hook *hook)
{
    sidx__lazy_part *p = &L->parts[index];
    if (SIDX_LIKELY(__atomic_load_n(&p->state, __ATOMIC_ACQUIRE) == SIDX__LAZY_BUILT)) return p->built;
    return sidx__lazy_claim(L, index, hook);
}

/* Part `index` if it is built, else NULL, without building it (stats,
 * destroy, read-only views). */
void *sidx__lazy_peek(const sidx__lazy *L, uint32_t index);

/* Set on this thread when an expansion could not get its memory.  The
 * query running on it (sidx_accel_intersect, _occluded, accel.c) clears
 * the mark before the walk and returns SIDX_ERR_NOMEM when it is set
 * after: a per-thread mark, because the walks return no status. */
extern _Thread_local unsigned char sidx__lazy_failed;

/* The counters as they stand (relaxed loads). */
sidx__lazy_counts sidx__lazy_counts_get(const sidx__lazy *L);

/* *p = max(*p, v), atomically (relaxed): the deepest-level counters. */
void sidx__lazy_atomic_max_u32(uint32_t *p, uint32_t v);

#endif
