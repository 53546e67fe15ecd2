/* fuzz_rays.c — libFuzzer target: the ray-file and hit-file readers of
 * sidx-bench (tk_parse_rays, tk_parse_hits in tests/common/testkit.c) on
 * arbitrary bytes, and the rays such a file yields traced through a small
 * closed scene.
 *
 * Every input is read both as a ray file and as a hit file.  Checked:
 *  - a size that is not a multiple of the record is refused with
 *    SIDX_ERR_PARSE, a message, *out = NULL and *n = 0; otherwise the
 *    parse succeeds (ray records may hold anything: unusable rays are
 *    refused later, one by one, by tk_ray_from);
 *  - parsed records re-encode to exactly the input bytes (little-endian,
 *    no field lost or reordered);
 *  - a hit file's records obey the documented form (prim >= -1; a miss is
 *    t = +inf; a hit's t is not NaN), else the parse fails;
 *  - tk_ray_from accepts exactly the rays sidx_ray_init accepts, and every
 *    accepted ray traced through one registered structure (picked by the
 *    input size, so the corpus covers them all) agrees with brute force on
 *    closest hit and any-hit; a ray whose direction is an axis or a plane
 *    to within float resolution only one way (fuzz_oracle.h). */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "../common/testkit.h"
#include "fuzz_oracle.h"

#define FR_MAX_TRACED 32u

static uint32_t fr_le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint32_t fr_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

static int fr_agree(const sidx_hit *a, const sidx_hit *b)
{
    if ((a->prim == SIDX_NO_HIT) != (b->prim == SIDX_NO_HIT)) return 0;
    if (a->prim == SIDX_NO_HIT || a->prim == b->prim) return 1;
    return fabsf(a->t - b->t) <= 1e-5f * fmaxf(1.0f, fabsf(a->t));
}

/* A closed cube [-1,1]^3 (12 triangles, shared vertices) and one
 * triangle inside it. */
static sidx_status fr_scene(sidx_mesh *m)
{
    static const float xyz[] = {-1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1, -1, -1, 1, 1, -1, 1, 1, 1, 1, -1, 1, 1,
                                -0.5f, -0.5f, 0, 0.5f, -0.5f, 0, 0, 0.5f, 0};
    static const uint32_t idx[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                   3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5, 8, 9, 10};
    return sidx_mesh_from_arrays(m, xyz, 11, idx, 13, NULL);
}

static void fr_check_rays(const uint8_t *data, size_t size)
{
    tk_rayrec *r = (tk_rayrec *)(uintptr_t)1; /* must be overwritten */
    size_t n = 12345;
    sidx_error err = {SIDX_OK, ""};
    const sidx_status s = tk_parse_rays(data, size, &r, &n, &err);
    if (size % TK_RAY_BYTES) {
        if (s != SIDX_ERR_PARSE || r || n || !err.message[0]) abort();
        return;
    }
    if (s != SIDX_OK || n != size / TK_RAY_BYTES || (n == 0) != (r == NULL)) abort();
    for (size_t i = 0; i < n; ++i) {
        const uint8_t *p = data + i * TK_RAY_BYTES;
        const float f[8] = {r[i].o[0], r[i].o[1], r[i].o[2], r[i].d[0], r[i].d[1], r[i].d[2], r[i].tmin, r[i].tmax};
        for (int k = 0; k < 8; ++k)
            if (fr_bits(f[k]) != fr_le32(p + 4 * k)) abort();
    }

    sidx_mesh m;
    sidx_accel *a = NULL, *ref = NULL;
    if (fr_scene(&m) != SIDX_OK) abort();
    const char *name = sidx_accel_registered_name(size / TK_RAY_BYTES % sidx_accel_registered_count());
    if (sidx_accel_build(name, &m, NULL, &a, NULL) != SIDX_OK || sidx_accel_build("brute", &m, NULL, &ref, NULL))
        abort();
    for (size_t i = 0; i < n && i < FR_MAX_TRACED; ++i) {
        sidx_ray ray, ray2;
        const sidx_status rs = tk_ray_from(&r[i], &ray);
        const sidx_status rs2 = sidx_ray_init(&ray2, sidx_v3(r[i].o[0], r[i].o[1], r[i].o[2]),
                                              sidx_v3(r[i].d[0], r[i].d[1], r[i].d[2]), r[i].tmin, r[i].tmax);
        if (rs != rs2 || (rs != SIDX_OK && rs != SIDX_ERR_INVALID_ARG)) abort();
        if (rs != SIDX_OK) continue;
        sidx_hit h, hr;
        int occ = -1, occ_ref = -1;
        sidx_accel_intersect(a, &ray, NULL, &h);
        sidx_accel_intersect(ref, &ray, NULL, &hr);
        sidx_accel_occluded(a, &ray, NULL, &occ);
        sidx_accel_occluded(ref, &ray, NULL, &occ_ref);
        /* beyond 1e6 the scene is below float resolution of the ray: only
         * "no crash" is checked there.  (tmin < 0 is refused by sidx_ray_init:
         * regress/rays/negative-tmin.bin, where the robust box test's
         * 1 + 2γ factor shrank a negative t_far and the BVHs lost hits.) */
        /* denormal components: not compared either — the watertight
         * test's products underflow (regress/rays/denormal-dir.bin: brute
         * force hit at t = 0 a ray 1 ulp outside a face; docs/errors.md) */
        int sane = fabsf(r[i].o[0]) < 1e6f && fabsf(r[i].o[1]) < 1e6f && fabsf(r[i].o[2]) < 1e6f;
        for (int k = 0; k < 3; ++k)
            if ((r[i].o[k] != 0.0f && fabsf(r[i].o[k]) < FLT_MIN) || (r[i].d[k] != 0.0f && fabsf(r[i].d[k]) < FLT_MIN))
                sane = 0;
        /* nor a direction longer than 2^64: t of the scene's distances then
         * nears the denormal range (regress/rays/huge-dir.bin: d.z = 6.8e38,
         * brute force hit the cube at t = 1.2e-38 a ray that leaves it at
         * once, by 7.6e-35 · t in x; every box test said miss) */
        for (int k = 0; k < 3; ++k)
            if (fabsf(r[i].d[k]) > 0x1p64f) sane = 0;
        /* nor a hit within float resolution of the origin, by either
         * (regress/rays/hit-at-start-*.bin: origins in a flat triangle's
         * plane, or 7.6e-38 off it, where brute force hit at t = 4e-8 or
         * t = 0 — rounding — and bvh's exact box test of the flat leaf
         * said miss) */
        if (tk_hit_at_start(&h, &ray, 1.0f) || tk_hit_at_start(&hr, &ray, 1.0f)) sane = 0;
        /* a direction component below FLT_MIN of the largest: the
         * triangle test's shear drops it, the box tests keep it — compared
         * one way only (fuzz_oracle.h; regress/rays/edge-lean-shear-underflow.bin:
         * a ray along the cube's edge, leaning out by 2^-151 of its length,
         * that brute force hit at the corner and the grid missed) */
        const int one_way = fo_shear_underflows(ray.dir);
        if (sane && (one_way ? !fo_no_nearer(&h, &hr, occ, occ_ref) : !fr_agree(&h, &hr) || occ != occ_ref)) {
            fprintf(stderr, "%s disagrees with brute on ray %zu: prim %u t %a vs prim %u t %a, occ %d vs %d%s\n", name,
                    i, h.prim, h.t, hr.prim, hr.t, occ, occ_ref, one_way ? " (one-way check)" : "");
            abort();
        }
        /* the record written for this hit must read back as the same hit */
        const tk_hitrec hrec = tk_hitrec_from(&h);
        if ((h.prim == SIDX_NO_HIT) != (hrec.prim == -1)) abort();
    }
    sidx_accel_destroy(a);
    sidx_accel_destroy(ref);
    sidx_mesh_free(&m);
    free(r);
}

static void fr_check_hits(const uint8_t *data, size_t size)
{
    tk_hitrec *h = (tk_hitrec *)(uintptr_t)1;
    size_t n = 12345;
    sidx_error err = {SIDX_OK, ""};
    const sidx_status s = tk_parse_hits(data, size, &h, &n, &err);
    /* the documented form of every record */
    int wellformed = size % TK_HIT_BYTES == 0;
    for (size_t i = 0; wellformed && i < size / TK_HIT_BYTES; ++i) {
        const uint8_t *p = data + i * TK_HIT_BYTES;
        const int32_t prim = (int32_t)fr_le32(p + 4);
        float t;
        const uint32_t tb = fr_le32(p);
        memcpy(&t, &tb, 4);
        if (prim < -1 || (prim == -1 && !(isinf(t) && t > 0)) || (prim >= 0 && isnan(t))) wellformed = 0;
    }
    if (!wellformed) {
        if (s != SIDX_ERR_PARSE || h || n || !err.message[0]) abort();
        return;
    }
    if (s != SIDX_OK || n != size / TK_HIT_BYTES || (n == 0) != (h == NULL)) abort();
    for (size_t i = 0; i < n; ++i) {
        const uint8_t *p = data + i * TK_HIT_BYTES;
        if (fr_bits(h[i].t) != fr_le32(p) || (uint32_t)h[i].prim != fr_le32(p + 4) ||
            fr_bits(h[i].u) != fr_le32(p + 8) || fr_bits(h[i].v) != fr_le32(p + 12))
            abort();
    }
    free(h);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fr_check_rays(data, size);
    fr_check_hits(data, size);
    return 0;
}
