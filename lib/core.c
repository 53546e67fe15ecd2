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

/* sidx_ray_init runs once per query — for an application that builds its
 * rays on the fly (as rtcIntersect1 callers do) it is part of every ray's
 * cost (docs/performance.md, "Ray set-up").  So it is written to be
 * cheap while giving exactly the bits and refusals of the plain
 * formulas:
 *
 *  - one finiteness test for all six components: x − x is +0 for every
 *    finite x and NaN for ±inf and NaN, and a NaN survives the adds
 *    (IEEE arithmetic: the library is built without -ffast-math, under
 *    which isfinite would not be trustworthy either);
 *  - the watertight axis choice (kz = axis of the largest |d|, ties to
 *    the lower axis) as selects instead of branches: a ray set with mixed
 *    directions would mispredict them about every other ray;
 *  - the zero direction is the one whose largest |d| is 0;
 *  - the five divisions (1/dx, 1/dy, 1/dz, d[kx]/d[kz], d[ky]/d[kz]) as two
 *    SSE divisions where SSE2 is available.  IEEE 754 rounds a SIMD
 *    division exactly like a scalar one, so the quotients are the same
 *    bits; the portable path divides one at a time.
 * The finiteness test, the signs and the divisions are the kernels of
 * simd_ray_sse.h and simd_ray_scalar.h (the reference). */
#include "simd_isa.h"
#ifdef SIDX_SIMD_SSE2
#include "simd_ray_sse.h"
#else
#include "simd_ray_scalar.h"
#endif

sidx_status sidx_ray_init(sidx_ray *r, sidx_vec3 org, sidx_vec3 dir, float tmin, float tmax)
{
    /* finite: all six components; signs: bit i set where dir[i] is
     * negative, -0.0 included (the near/far child order, sign[]). */
    int finite;
    unsigned signs;
    const ray_row row = ray_row_check(org, dir, &finite, &signs);
    /* tmin >= 0 excludes a NaN tmin; then tmin <= tmax fails exactly when
     * tmax is NaN or tmin > tmax. */
    if (!r || !finite || !(tmin >= 0.0f && tmin <= tmax)) return SIDX_ERR_INVALID_ARG;

    /* Watertight test set-up (Woop et al. 2013, section 3): kz is the axis
     * of largest |d|; swap kx, ky when d[kz] < 0 to keep the winding. */
    const float ax = fabsf(dir.x), ay = fabsf(dir.y), az = fabsf(dir.z);
    const int y_wins = ay > ax;
    const float axy = y_wins ? ay : ax;
    const float amax = az > axy ? az : axy;
    if (!(amax > 0.0f)) return SIDX_ERR_INVALID_ARG; /* dir is (±0, ±0, ±0) */
    const int z_wins = az > axy;
    const int kz = 2 * z_wins + y_wins * !z_wins; /* arithmetic, not a branch */
    const unsigned kz_neg = (signs >> kz) & 1u; /* d[kz] is not ±0: its sign bit says d[kz] < 0 */
    /* kx = kz + 1 (mod 3), or kz + 2 when d[kz] < 0; ky is the third axis. */
    static const uint8_t mod3[5] = {0, 1, 2, 0, 1};
    const int kx = mod3[kz + 1 + (int)kz_neg], ky = 3 - kz - kx;

    const float d[3] = {dir.x, dir.y, dir.z};
    r->org = org;
    r->dir = dir;
    r->tmin = tmin;
    r->tmax = tmax;
    /* 1/±0 = ±inf by IEEE 754: the sign of zero is the side the ray
     * "leans" to, which keeps near/far child order consistent. */
    ray_row_quotients(row, d, kx, ky, kz, r);
    r->sign[0] = (uint8_t)(signs & 1u);
    r->sign[1] = (uint8_t)(signs >> 1 & 1u);
    r->sign[2] = (uint8_t)(signs >> 2);
    r->kx = (uint8_t)kx;
    r->ky = (uint8_t)ky;
    r->kz = (uint8_t)kz;
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
