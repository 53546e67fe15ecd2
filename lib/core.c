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
 * cost, about a tenth of a diffuse bunny ray through bvh8 when it was a
 * chain of branches and five scalar divisions.  So it is written to be
 * cheap while giving exactly the bits (and refusals) it always gave:
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
 *    bits; the portable path divides one at a time. */
#if defined(__SSE2__) && (defined(__x86_64__) || defined(__i386__))
#include <emmintrin.h>
#define SIDX_RAY_INIT_SSE2 1
#endif

sidx_status sidx_ray_init(sidx_ray *r, sidx_vec3 org, sidx_vec3 dir, float tmin, float tmax)
{
    /* finite: all six components; signs: bit i set where dir[i] is
     * negative, -0.0 included (the near/far child order, sign[]). */
#ifdef SIDX_RAY_INIT_SSE2
    /* lane 3 is a harmless 1: finite, positive, and a quotient that raises no flag */
    const __m128 o4 = _mm_setr_ps(org.x, org.y, org.z, 1.0f), d4 = _mm_setr_ps(dir.x, dir.y, dir.z, 1.0f);
    const __m128 fin4 = _mm_add_ps(_mm_sub_ps(o4, o4), _mm_sub_ps(d4, d4));
    const int finite = _mm_movemask_ps(_mm_cmpeq_ps(fin4, _mm_setzero_ps())) == 0xF;
    const unsigned signs = (unsigned)_mm_movemask_ps(d4) & 7u;
#else
    const float fin = ((org.x - org.x) + (org.y - org.y)) + ((org.z - org.z) + (dir.x - dir.x)) +
                      ((dir.y - dir.y) + (dir.z - dir.z));
    const int finite = fin == 0.0f;
    const unsigned signs = (signbit(dir.x) ? 1u : 0u) | (signbit(dir.y) ? 2u : 0u) | (signbit(dir.z) ? 4u : 0u);
#endif
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
#ifdef SIDX_RAY_INIT_SSE2
    float inv[4], shear[4];
    _mm_storeu_ps(inv, _mm_div_ps(_mm_set1_ps(1.0f), d4));
    _mm_storeu_ps(shear, _mm_div_ps(_mm_setr_ps(d[kx], d[ky], 1.0f, 1.0f), _mm_set1_ps(d[kz])));
    r->inv_dir = sidx_v3(inv[0], inv[1], inv[2]);
    r->sx = shear[0];
    r->sy = shear[1];
    r->sz = shear[2]; /* 1/d[kz]: the same bits as inv[kz] */
#else
    r->inv_dir = sidx_v3(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    r->sx = d[kx] / d[kz];
    r->sy = d[ky] / d[kz];
    r->sz = (sidx_v3_array(&r->inv_dir))[kz]; /* the same 1/d[kz], already computed: one division fewer per ray */
#endif
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
