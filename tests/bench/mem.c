/* mem.c — the memory a build needs, two ways:
 *
 *   resident peak  how far the process's resident set rose above where it
 *                  stood just before the build (mesh already loaded), at the
 *                  build's worst moment: the structure plus the builder's
 *                  temporaries plus whatever the library behind it copies
 *                  (Embree copies the vertices and indices into its own
 *                  buffers).  Linux: the peak (VmHWM) is reset to the
 *                  current resident set by writing 5 to /proc/self/clear_refs
 *                  before the build and read after it; glibc's free lists
 *                  are returned to the system first (malloc_trim), so freed
 *                  pages the build would reuse do not hide its growth.
 *   heap peak      the most bytes live at once through the build's
 *                  sidx_allocator (sidx structures only): a counting
 *                  allocator over malloc. */
#define _GNU_SOURCE
#include <stdatomic.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__GLIBC__) || defined(__linux__)
#include <malloc.h>
#endif

#include "bench.h"

/* "VmRSS:  1234 kB" -> bytes; -1 when /proc/self/status has no such line. */
static long long proc_status_bytes(const char *key)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return -1;
    char line[256];
    long long kb = -1;
    const size_t klen = strlen(key);
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, klen) && line[klen] == ':') {
            kb = strtoll(line + klen + 1, NULL, 10);
            break;
        }
    fclose(f);
    return kb < 0 ? -1 : kb * 1024;
}

void bench_mem_begin(bench_mem *m)
{
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
    m->base = -1;
    FILE *f = fopen("/proc/self/clear_refs", "w");
    if (!f) return;
    const int ok = fputs("5", f) >= 0;
    if (fclose(f) != 0 || !ok) return;
    m->base = proc_status_bytes("VmRSS");
}

long long bench_mem_end(const bench_mem *m)
{
    if (m->base < 0) return -1;
    const long long hwm = proc_status_bytes("VmHWM");
    if (hwm < 0) return -1;
    return hwm > m->base ? hwm - m->base : 0;
}

/* The counting allocator: a header of one max_align_t in front of each
 * block keeps malloc's alignment and remembers the size for free. */
typedef union heap_hdr {
    size_t size;
    max_align_t align;
} heap_hdr;

static void *heap_alloc(size_t size, void *user)
{
    bench_heap *h = user;
    if (size > (size_t)-1 - sizeof(heap_hdr)) return NULL;
    heap_hdr *p = malloc(sizeof *p + size);
    if (!p) return NULL;
    p->size = size;
    const size_t live = atomic_fetch_add(&h->live, size) + size;
    size_t peak = atomic_load(&h->peak);
    while (live > peak && !atomic_compare_exchange_weak(&h->peak, &peak, live)) {
    }
    return p + 1;
}

static void heap_free(void *ptr, void *user)
{
    if (!ptr) return;
    bench_heap *h = user;
    heap_hdr *p = (heap_hdr *)ptr - 1;
    atomic_fetch_sub(&h->live, p->size);
    free(p);
}

sidx_allocator bench_heap_allocator(bench_heap *h)
{
    atomic_init(&h->live, 0);
    atomic_init(&h->peak, 0);
    const sidx_allocator a = {heap_alloc, heap_free, h};
    return a;
}

size_t bench_mesh_bytes(const sidx_mesh *m)
{
    return (size_t)m->num_vertices * sizeof(sidx_vec3) + (size_t)m->num_triangles * 3 * sizeof(uint32_t);
}
