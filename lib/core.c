/* core.c — statuses, rays, option names and the small helpers every
 * structure shares. */
#include <stdarg.h>
#include <stdio.h>
#include "sidx_internal.h"

const char *sidx_version(void) { return "0.1.0"; }

const char *sidx_status_str(sidx_status s)
{
    switch (s) {
    case SIDX_OK: return "ok";
    case SIDX_ERR_INVALID_ARG: return "invalid argument";
    case SIDX_ERR_NOMEM: return "out of memory";
    case SIDX_ERR_IO: return "input/output error";
    case SIDX_ERR_PARSE: return "malformed file";
    case SIDX_ERR_BAD_GEOMETRY: return "bad geometry (NaN/Inf coordinate or index out of range)";
    case SIDX_ERR_UNKNOWN_ACCEL: return "unknown acceleration structure";
    case SIDX_ERR_LIMIT: return "input exceeds a structure limit";
    case SIDX_ERR_UNSUPPORTED: return "operation not supported by this structure";
    default: return "unknown status";
    }
}

sidx_status sidx__fail(sidx_error *err, sidx_status s, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->status = s;
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return s;
}

sidx_status sidx_ray_init(sidx_ray *r, sidx_vec3 org, sidx_vec3 dir, float tmin, float tmax)
{
    if (!r || !sidx_v3_isfinite(org) || !sidx_v3_isfinite(dir) || !(tmin >= 0.0f) || isnan(tmax) || tmin > tmax)
        return SIDX_ERR_INVALID_ARG;
    if (dir.x == 0.0f && dir.y == 0.0f && dir.z == 0.0f) return SIDX_ERR_INVALID_ARG;
    r->org = org;
    r->dir = dir;
    r->tmin = tmin;
    r->tmax = tmax;
    const float *d = &dir.x;
    float *inv = &r->inv_dir.x;
    for (int i = 0; i < 3; ++i) {
        /* 1/±0 = ±inf by IEEE 754: the sign of zero is the side the ray
         * "leans" to, which keeps near/far child order consistent. */
        inv[i] = 1.0f / d[i];
        r->sign[i] = (uint8_t)(signbit(d[i]) ? 1 : 0);
    }
    /* Watertight test set-up (Woop et al. 2013, section 3): kz is the axis
     * of largest |d|; swap kx, ky when d[kz] < 0 to keep the winding. */
    int kz = 0;
    if (fabsf(d[1]) > fabsf(d[kz])) kz = 1;
    if (fabsf(d[2]) > fabsf(d[kz])) kz = 2;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0.0f) { int tmp = kx; kx = ky; ky = tmp; }
    r->kx = (uint8_t)kx;
    r->ky = (uint8_t)ky;
    r->kz = (uint8_t)kz;
    r->sx = d[kx] / d[kz];
    r->sy = d[ky] / d[kz];
    r->sz = inv[kz]; /* the same 1/d[kz], already computed: one division fewer per ray */
    return SIDX_OK;
}

static const char *const traversal_names[SIDX_TRAVERSE_COUNT] = {"default", "stack", "ordered", "naive"};

const char *sidx_traversal_name(sidx_traversal t)
{
    return ((unsigned)t < SIDX_TRAVERSE_COUNT) ? traversal_names[t] : NULL;
}

sidx_status sidx_traversal_parse(const char *name, sidx_traversal *out)
{
    if (!name || !out) return SIDX_ERR_INVALID_ARG;
    for (int i = 0; i < SIDX_TRAVERSE_COUNT; ++i)
        if (strcmp(name, traversal_names[i]) == 0) { *out = (sidx_traversal)i; return SIDX_OK; }
    return SIDX_ERR_INVALID_ARG;
}

int sidx__grow(const sidx_accel *a, void **buf, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return 1;
    size_t ncap = *cap ? *cap : 16;
    while (ncap < need) {
        if (ncap > SIZE_MAX / 2) return 0;
        ncap *= 2;
    }
    void *nb = sidx__alloc(a, ncap, size);
    if (!nb) return 0;
    if (*buf && *cap) memcpy(nb, *buf, *cap * size);
    sidx__free(a, *buf);
    *buf = nb;
    *cap = ncap;
    return 1;
}

sidx_status sidx__prim_boxes(const sidx_accel *a, sidx_aabb **boxes, sidx_vec3 **centroids)
{
    const sidx_mesh *m = a->mesh;
    sidx_aabb *b = sidx__alloc(a, m->num_triangles, sizeof *b);
    sidx_vec3 *c = centroids ? sidx__alloc(a, m->num_triangles, sizeof *c) : NULL;
    if (!b || (centroids && !c)) {
        sidx__free(a, b);
        sidx__free(a, c);
        return SIDX_ERR_NOMEM;
    }
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        sidx_aabb bb = sidx_aabb_empty();
        for (int k = 0; k < 3; ++k) bb = sidx_aabb_grow(bb, sidx_mesh_vertex(m, i, k));
        b[i] = bb;
        if (c) c[i] = sidx_aabb_centroid(bb);
    }
    *boxes = b;
    if (centroids) *centroids = c;
    return SIDX_OK;
}
