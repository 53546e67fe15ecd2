/* fuzz_build.c — libFuzzer target: build every registered structure over a
 * small mesh made of the input bytes, trace rays made of the input bytes,
 * and check each closest hit and any-hit answer against brute force.
 *
 * Input layout: byte 0 = triangle count (1..24), byte 1 = ray count
 * (1..16), byte 2 = value mode, then float32 values.  Mode 0 uses the
 * bytes as raw floats (NaN, Inf, denormals, huge values: the builds must
 * refuse or survive them); mode 1 maps each byte pair to a small grid of
 * "nice" coordinates so shared edges, coplanar and degenerate triangles and
 * axis-parallel rays with ±0 components are common. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"

typedef struct { const uint8_t *p; size_t n, at; int mode; } reader;

static float next_float(reader *r)
{
    if (r->mode == 0) {
        float f = 0.0f;
        if (r->at + 4 <= r->n) memcpy(&f, r->p + r->at, 4);
        r->at += 4;
        return f;
    }
    uint8_t b = r->at < r->n ? r->p[r->at] : 0;
    r->at += 1;
    /* 16 grid values in [-2, 2] plus the two zeros */
    if (b == 255) return -0.0f;
    return ((float)(b % 17) - 8.0f) * 0.25f;
}

static int agree(const sidx_hit *a, const sidx_hit *b)
{
    if ((a->prim == SIDX_NO_HIT) != (b->prim == SIDX_NO_HIT)) return 0;
    if (a->prim == SIDX_NO_HIT || a->prim == b->prim) return 1;
    return fabsf(a->t - b->t) <= 1e-5f * fmaxf(1.0f, fabsf(a->t));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 3) return 0;
    const uint32_t ntri = 1u + data[0] % 24u, nray = 1u + data[1] % 16u;
    reader rd = {data, size, 3, data[2] & 1};
    float xyz[24 * 9];
    uint32_t idx[24 * 3];
    for (uint32_t i = 0; i < ntri * 9; ++i) xyz[i] = next_float(&rd);
    for (uint32_t i = 0; i < ntri * 3; ++i) idx[i] = i;
    sidx_mesh m;
    if (sidx_mesh_from_arrays(&m, xyz, ntri * 3, idx, ntri, NULL) != SIDX_OK) return 0;
    /* keep to magnitudes where float boxes are meaningful; beyond, only
     * "no crash" is checked */
    int sane = 1;
    for (uint32_t i = 0; i < m.num_vertices; ++i)
        if (fabsf(m.positions[i].x) > 1e6f || fabsf(m.positions[i].y) > 1e6f || fabsf(m.positions[i].z) > 1e6f)
            sane = 0;

    sidx_ray rays[16];
    uint32_t nr = 0;
    for (uint32_t i = 0; i < nray; ++i) {
        sidx_vec3 o = {next_float(&rd), next_float(&rd), next_float(&rd)};
        sidx_vec3 d = {next_float(&rd), next_float(&rd), next_float(&rd)};
        if (sidx_ray_init(&rays[nr], o, d, 0.0f, INFINITY) == SIDX_OK) ++nr;
        else if (sidx_v3_isfinite(o) && sidx_v3_isfinite(d) && (d.x != 0 || d.y != 0 || d.z != 0)) abort();
    }
    sidx_accel *ref = NULL;
    if (sidx_accel_build("brute", &m, NULL, &ref, NULL) != SIDX_OK) abort(); /* a validated mesh always builds */
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s) {
        sidx_accel *a = NULL;
        sidx_status st = sidx_accel_build(sidx_accel_registered_name(s), &m, NULL, &a, NULL);
        if (st != SIDX_OK) {
            if (st != SIDX_ERR_LIMIT) {
                fprintf(stderr, "%s failed to build a valid mesh: %s\n", sidx_accel_registered_name(s),
                        sidx_status_str(st));
                abort();
            }
            continue;
        }
        for (uint32_t i = 0; i < nr; ++i) {
            sidx_hit h, hr;
            int occ = 0, occ_ref = 0;
            sidx_accel_intersect(a, &rays[i], NULL, &h);
            sidx_accel_intersect(ref, &rays[i], NULL, &hr);
            sidx_accel_occluded(a, &rays[i], NULL, &occ);
            sidx_accel_occluded(ref, &rays[i], NULL, &occ_ref);
            if (sane && (!agree(&h, &hr) || occ != occ_ref)) {
                fprintf(stderr, "%s disagrees with brute on ray %u: prim %u t %a vs prim %u t %a, occ %d vs %d\n",
                        sidx_accel_registered_name(s), i, h.prim, h.t, hr.prim, hr.t, occ, occ_ref);
                abort();
            }
        }
        sidx_accel_destroy(a);
    }
    sidx_accel_destroy(ref);
    sidx_mesh_free(&m);
    return 0;
}
