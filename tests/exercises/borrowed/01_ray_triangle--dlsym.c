/* Borrowed by name at run time: the library's tests looked up with dlsym,
 * so that the source names neither.
 * expect: uses dlsym, which looks functions up at run time
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include "sidx/sidx.h"

typedef int (*plane_fn)(const sidx_ray *, sidx_vec3, float, float *);
typedef int (*tri_fn)(const sidx_ray *, sidx_vec3, sidx_vec3, sidx_vec3, float, float *, float *, float *);

int ray_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t)
{
    plane_fn f;
    void *p = dlsym(RTLD_DEFAULT, "sidx_intersect_" "plane");
    if (!p) return 0;
    *(void **)&f = p;
    return f(r, n, c, t);
}

int ray_triangle_two_step(const sidx_ray *r, sidx_vec3 p0, sidx_vec3 p1, sidx_vec3 p2, float tmax, float *t)
{
    tri_fn f;
    void *p = dlsym(RTLD_DEFAULT, "sidx_intersect_triangle_" "two_step");
    if (!p) return 0;
    *(void **)&f = p;
    return f(r, p0, p1, p2, tmax, t, NULL, NULL);
}
