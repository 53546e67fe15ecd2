/* Borrowed by walking the loaded program (dl_iterate_phdr) to find the
 * library's test: the source names it nowhere.
 * expect: uses dl_iterate_phdr, which looks functions up at run time
 */
#define _GNU_SOURCE
#include <link.h>
#include <stddef.h>
#include "sidx/sidx.h"

static int first(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size;
    *(ElfW(Addr) *)data = info->dlpi_addr;
    return 1;
}

int ray_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far)
{
    ElfW(Addr) base = 0;
    dl_iterate_phdr(first, &base);
    (void)r, (void)s, (void)tmin, (void)tmax, (void)t_near, (void)t_far;
    return base != 0 && 0;
}

int ray_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far)
{
    (void)r, (void)b, (void)tmin, (void)tmax, (void)t_near, (void)t_far;
    return 0;
}

int ray_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far)
{
    (void)r, (void)k, (void)tmin, (void)tmax, (void)t_near, (void)t_far;
    return 0;
}
