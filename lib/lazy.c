/* lazy.c — claim, wait, publish, failure and the counters of a lazily
 * built part (lazy.h). */
#include <sched.h>
#include "lazy.h"

_Thread_local unsigned char sidx__lazy_failed;
#include "simd_isa.h"

void sidx__lazy_init(sidx__lazy *L, sidx__lazy_part *parts, uint32_t n, sidx__lazy_expand_fn expand, void *owner)
{
    memset(L, 0, sizeof *L);
    L->parts = parts;
    L->num_parts = n;
    L->expand = expand;
    L->owner = owner;
}

void sidx__lazy_defer(sidx__lazy *L, uint32_t index, uint64_t refs)
{
    (void)index;
    __atomic_fetch_add(&L->counts.unbuilt, 1u, __ATOMIC_RELAXED);
    __atomic_fetch_add(&L->counts.unbuilt_refs, refs, __ATOMIC_RELAXED);
}

void sidx__lazy_atomic_max_u32(uint32_t *p, uint32_t v)
{
    uint32_t cur = __atomic_load_n(p, __ATOMIC_RELAXED);
    while (cur < v && !__atomic_compare_exchange_n(p, &cur, v, 1, __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
    }
}

/* The counters move from unbuilt to built by what the expansion made. */
static void count_built(sidx__lazy *L, const sidx__lazy_made *m)
{
    sidx__lazy_counts *c = &L->counts;
    __atomic_fetch_add(&c->built, 1u, __ATOMIC_RELAXED);
    __atomic_fetch_sub(&c->unbuilt, 1u, __ATOMIC_RELAXED);
    __atomic_fetch_add(&c->built_refs, m->refs, __ATOMIC_RELAXED);
    __atomic_fetch_sub(&c->unbuilt_refs, m->refs, __ATOMIC_RELAXED);
    __atomic_fetch_add(&c->built_bytes, m->bytes, __ATOMIC_RELAXED);
    sidx__lazy_atomic_max_u32(&c->max_depth, m->depth);
}

void sidx__lazy_built_now(sidx__lazy *L, uint32_t index, void *part, const sidx__lazy_made *made)
{
    sidx__lazy_part *p = &L->parts[index];
    __atomic_fetch_add(&L->counts.built, 1u, __ATOMIC_RELAXED);
    __atomic_fetch_add(&L->counts.built_refs, made->refs, __ATOMIC_RELAXED);
    __atomic_fetch_add(&L->counts.built_bytes, made->bytes, __ATOMIC_RELAXED);
    sidx__lazy_atomic_max_u32(&L->counts.max_depth, made->depth);
    p->built = part;
    __atomic_store_n(&p->state, SIDX__LAZY_BUILT, __ATOMIC_RELEASE);
}

void *sidx__lazy_claim(sidx__lazy *L, uint32_t index, const sidx_hook *hook)
{
    sidx__lazy_part *p = &L->parts[index];
    for (unsigned spins = 0;; ++spins) {
        uint32_t st = __atomic_load_n(&p->state, __ATOMIC_ACQUIRE);
        if (st == SIDX__LAZY_BUILT) return p->built;
        if (st == SIDX__LAZY_UNBUILT) {
            /* claim: only one thread moves it to busy */
            if (!__atomic_compare_exchange_n(&p->state, &st, SIDX__LAZY_BUSY, 0, __ATOMIC_ACQ_REL, __ATOMIC_ACQUIRE))
                continue;
            sidx__lazy_made made = {0, 0, 0};
            void *part = L->expand(L->owner, index, hook, &made);
            if (!part) {
                /* failure: nothing was kept; unbuilt again for a later query */
                __atomic_store_n(&p->state, SIDX__LAZY_UNBUILT, __ATOMIC_RELEASE);
                sidx__lazy_failed = 1;
                return NULL;
            }
            count_built(L, &made);
            /* publish: the pointer, then the state with release */
            p->built = part;
            __atomic_store_n(&p->state, SIDX__LAZY_BUILT, __ATOMIC_RELEASE);
            /* part is the expansion's own memory; &made only receives its counts */
            /* cppcheck-suppress returnDanglingLifetime */
            return part;
        }
        /* busy: another thread is building it; wait */
        if (spins < 64) SIDX_SPIN_PAUSE();
        else sched_yield();
    }
}

void *sidx__lazy_peek(const sidx__lazy *L, uint32_t index)
{
    const sidx__lazy_part *p = &L->parts[index];
    return __atomic_load_n(&p->state, __ATOMIC_ACQUIRE) == SIDX__LAZY_BUILT ? p->built : NULL;
}

sidx__lazy_counts sidx__lazy_counts_get(const sidx__lazy *L)
{
    const sidx__lazy_counts *c = &L->counts;
    sidx__lazy_counts o;
    o.built = __atomic_load_n(&c->built, __ATOMIC_RELAXED);
    o.unbuilt = __atomic_load_n(&c->unbuilt, __ATOMIC_RELAXED);
    o.built_refs = __atomic_load_n(&c->built_refs, __ATOMIC_RELAXED);
    o.unbuilt_refs = __atomic_load_n(&c->unbuilt_refs, __ATOMIC_RELAXED);
    o.built_bytes = __atomic_load_n(&c->built_bytes, __ATOMIC_RELAXED);
    o.max_depth = __atomic_load_n(&c->max_depth, __ATOMIC_RELAXED);
    return o;
}
