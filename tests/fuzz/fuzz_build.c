/* fuzz_build.c — libFuzzer target: build ONE registered structure over a
 * small mesh made of the input bytes, trace a few rays made of the input
 * bytes, and check each closest hit and any-hit answer against brute force
 * (one way for a direction that is an axis or a plane to within float
 * resolution: fuzz_oracle.h).
 *
 * Why one structure per input: building all ~25 of them (the ray
 * classification among them) for every input ran at ~1 exec/s; with a
 * selector byte each input costs one build, and the fuzzer's coverage
 * feedback still spreads the inputs over every structure (each one's code
 * is new coverage).
 *
 * Input layout (missing bytes read as 0):
 *   byte 0  structure: index into the registry (mod its size)
 *   byte 1  triangle count 1..24
 *   byte 2  ray count 1..16
 *   byte 3  bits 0-1 value mode, bit 2 indices from the input (shared and
 *           repeated vertices: degenerate triangles), bit 3 tmin/tmax from
 *           the input, bit 4 build options from the next 8 bytes,
 *           bits 5-6 traversal variant, bit 7 query u/v + normal and the
 *           n-ray entry point
 *   [8 option bytes]  when bit 4
 *   then values, then (bit 2) one index byte per corner.
 * Value modes: 0 raw float32 (every bit pattern: NaN, Inf, denormals, huge
 * values — builds must refuse or survive them), 1 a small grid of "nice"
 * coordinates so shared edges, coplanar and axis-parallel configurations
 * and ±0 are common, 2 and 3 a table of special values (NaN, ±Inf,
 * FLT_MAX, denormals, 1e±30, ±0, near-1) mixed with grid values. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "sidx/sidx.h"
#include "../common/testkit.h"
#include "fuzz_oracle.h"

/* The limits of the first version of this target (which built every
 * structure per input), so its regression inputs keep their meaning with a
 * selector byte put in front. */
#define FB_MAX_TRIS 24u
#define FB_MAX_RAYS 16u

typedef struct { const uint8_t *p; size_t n, at; int mode; } fb_reader;

static uint8_t fb_byte(fb_reader *r)
{
    uint8_t b = r->at < r->n ? r->p[r->at] : 0;
    r->at += 1;
    return b;
}

static float fb_grid(uint8_t b)
{
    /* 17 grid values in [-2, 2] plus -0 */
    if (b == 255) return -0.0f;
    return ((float)(b % 17) - 8.0f) * 0.25f;
}

static float fb_float(fb_reader *r)
{
    if (r->mode == 0) {
        float f = 0.0f;
        if (r->at + 4 <= r->n) memcpy(&f, r->p + r->at, 4);
        r->at += 4;
        return f;
    }
    const uint8_t b = fb_byte(r);
    if (r->mode == 1 || b < 128) return fb_grid(b);
    static const float special[] = {
        0.0f, -0.0f, 1.0f, -1.0f, 0.5f, 2.0f, 3.0f, 1e6f, -1e6f, 1e7f, 1e30f, -1e30f, 1e-30f, -1e-30f,
        1e-40f /* denormal */, -1e-40f, FLT_MIN, FLT_TRUE_MIN, -FLT_TRUE_MIN, FLT_MAX, -FLT_MAX,
        1.0000001f, 0.99999994f, 1e-7f, 16777216.0f, 16777217.0f, 0.1f, -0.1f,
        /* non-finite last: meshes refuse them, rays must be refused too */
        INFINITY, -INFINITY, NAN, -NAN};
    return special[(b - 128) % (sizeof special / sizeof special[0])];
}

/* Denormal (subnormal) magnitudes: the watertight test's products
 * underflow there, so brute force itself may report a hit at t = 0 for an
 * origin a few 1e-40 off the triangle's plane, where the structures' box
 * tests (exact at that scale) say miss.  Documented in docs/errors.md;
 * such inputs are traced (no crash, no sanitizer report) but not compared
 * (regress/build/bvh-t0-denormal.bin). */
static int fb_tiny(float x) { return x != 0.0f && fabsf(x) < FLT_MIN; }

static int fb_agree(const sidx_hit *a, const sidx_hit *b)
{
    if ((a->prim == SIDX_NO_HIT) != (b->prim == SIDX_NO_HIT)) return 0;
    if (a->prim == SIDX_NO_HIT || a->prim == b->prim) return 1;
    return fabsf(a->t - b->t) <= 1e-5f * fmaxf(1.0f, fabsf(a->t));
}

/* Build options from 8 bytes: small leaves, shallow or deep limits, few
 * bins, sparse or dense grids, mailboxing off — every value in range (the
 * out-of-range ones are tests/test_args.c's business). */
static void fb_options(fb_reader *rd, sidx_build_options *o)
{
    const uint8_t b[8] = {fb_byte(rd), fb_byte(rd), fb_byte(rd), fb_byte(rd),
                          fb_byte(rd), fb_byte(rd), fb_byte(rd), fb_byte(rd)};
    o->leaf_size = b[0] % 9u;                                   /* 0 = default, 1..8 */
    o->max_depth = b[1] < 200 ? b[1] % 48u : 0xFFFFFFFFu - (b[1] - 200u); /* 0, 1..47, or huge */
    o->bins = b[2] % 66u;                                       /* 0 = default, 1..65 */
    o->every_b = b[3] % 40u;
    o->grid_density = (float)(b[4] % 32u) * 0.25f;              /* 0 = default, 0.25..7.75 */
    o->empty_bonus = (float)(b[5] % 100u) * 0.01f;              /* [0, 0.99] */
    o->c_trav = (float)(b[6] % 8u) * 0.5f;
    o->c_tri = (float)(b[6] / 8u % 8u) * 0.5f;
    o->no_mailbox = b[7] & 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 4) return 0;
    const size_t nacc = sidx_accel_registered_count();
    const char *name = sidx_accel_registered_name(data[0] % nacc);
    const uint32_t ntri = 1u + data[1] % FB_MAX_TRIS, nray = 1u + data[2] % FB_MAX_RAYS;
    const uint8_t flags = data[3];
    fb_reader rd = {data, size, 4, flags & 3};
    sidx_build_options opt;
    memset(&opt, 0, sizeof opt);
    if (flags & 16) fb_options(&rd, &opt);
#ifndef FB_REPLAY
    /* Ray classification's 5D tree doubles per level: at its deepest (24,
     * leaf size 1) a handful of triangles fills its budgets (2^20 nodes,
     * 2^25 candidates), about 1 GB and 6 s per input under ASan, and the
     * fuzzer stops at its memory limit within minutes.  So while fuzzing it
     * stays at depth 12; the budgets have their own tests (test_rayclass.c,
     * and regress/build/rayclass-maxdepth-budget.bin, which
     * test_fuzz_regress replays with FB_REPLAY, uncapped). */
    if (!strcmp(name, "rayclass") && opt.max_depth > 12) opt.max_depth = 12;
#endif
    const sidx_traversal trav = (sidx_traversal)((flags >> 5) & 3);
    const int extras = (flags & 128) != 0;

    float xyz[FB_MAX_TRIS * 9];
    uint32_t idx[FB_MAX_TRIS * 3];
    for (uint32_t i = 0; i < ntri * 9; ++i) xyz[i] = fb_float(&rd);

    sidx_ray rays[FB_MAX_RAYS];
    uint32_t nr = 0;
    for (uint32_t i = 0; i < nray; ++i) {
        const sidx_vec3 o = {fb_float(&rd), fb_float(&rd), fb_float(&rd)};
        const sidx_vec3 d = {fb_float(&rd), fb_float(&rd), fb_float(&rd)};
        float tmin = 0.0f, tmax = INFINITY;
        if (flags & 8) {
            tmin = fb_float(&rd);
            tmax = fb_float(&rd);
        }
        if (sidx_ray_init(&rays[nr], o, d, tmin, tmax) == SIDX_OK) ++nr;
        else if (!(flags & 8) && sidx_v3_isfinite(o) && sidx_v3_isfinite(d) && (d.x != 0 || d.y != 0 || d.z != 0))
            abort(); /* a finite ray with a non-zero direction must be accepted */
    }
    for (uint32_t i = 0; i < ntri * 3; ++i) idx[i] = (flags & 4) ? fb_byte(&rd) % (ntri * 3) : i;

    sidx_mesh m;
    if (sidx_mesh_from_arrays(&m, xyz, ntri * 3, idx, ntri, NULL) != SIDX_OK) return 0;
    /* keep to magnitudes where float boxes are meaningful; beyond, only
     * "no crash, no sanitizer report" is checked */
    int sane = 1;
    for (uint32_t i = 0; i < m.num_vertices; ++i)
        if (fabsf(m.positions[i].x) > 1e6f || fabsf(m.positions[i].y) > 1e6f || fabsf(m.positions[i].z) > 1e6f ||
            fb_tiny(m.positions[i].x) || fb_tiny(m.positions[i].y) || fb_tiny(m.positions[i].z))
            sane = 0;
    for (uint32_t i = 0; i < nr; ++i)
        for (int k = 0; k < 3; ++k)
            if (fb_tiny(sidx_v3_get(rays[i].org, k)) || fb_tiny(sidx_v3_get(rays[i].dir, k)) ||
                fabsf(sidx_v3_get(rays[i].dir, k)) > 0x1p64f) /* see fuzz_rays.c */
                sane = 0;

    sidx_accel *ref = NULL, *a = NULL;
    if (sidx_accel_build("brute", &m, NULL, &ref, NULL) != SIDX_OK) abort(); /* a validated mesh always builds */
    sidx_error err;
    const sidx_status st = sidx_accel_build(name, &m, &opt, &a, &err);
    if (st != SIDX_OK) {
        /* A valid mesh with in-range options may only be refused for
         * exceeding a limit, and then with a message. */
        if (st != SIDX_ERR_LIMIT || err.message[0] == '\0' || a != NULL) {
            fprintf(stderr, "%s failed to build a valid mesh: %s (%s)\n", name, sidx_status_str(st), err.message);
            abort();
        }
    } else {
        const sidx_query q = {extras ? SIDX_QUERY_UV | SIDX_QUERY_NORMAL : 0u, trav, NULL, 0};
        sidx_hit hits[FB_MAX_RAYS];
        const sidx_aabb bb = sidx_mesh_bounds(&m); /* the scene's size, for tk_hit_at_start */
        float scale = 0.0f;
        for (int k = 0; k < 3; ++k)
            scale = fmaxf(scale, fmaxf(fabsf(sidx_v3_get(bb.min, k)), fabsf(sidx_v3_get(bb.max, k))));
        if (extras && sidx_accel_intersect_n(a, rays, nr, &q, hits) != SIDX_OK) abort();
        for (uint32_t i = 0; i < nr; ++i) {
            sidx_hit h, hr;
            int occ = 0, occ_ref = 0;
            sidx_accel_intersect(a, &rays[i], &q, &h);
            sidx_accel_intersect(ref, &rays[i], NULL, &hr);
            sidx_accel_occluded(a, &rays[i], &q, &occ);
            sidx_accel_occluded(ref, &rays[i], NULL, &occ_ref);
            if (extras && (hits[i].prim != h.prim || !(hits[i].t == h.t || (isnan(h.t) && isnan(hits[i].t))))) {
                fprintf(stderr, "%s: intersect_n and intersect disagree on ray %u\n", name, i);
                abort();
            }
            /* a hit within float resolution of the origin is not compared (see fuzz_rays.c) */
            const int at_start = tk_hit_at_start(&h, &rays[i], scale) || tk_hit_at_start(&hr, &rays[i], scale);
            /* a direction an axis or a plane to within float resolution:
             * compared one way only (fuzz_oracle.h) */
            const int one_way = fo_shear_underflows(rays[i].dir);
            if (sane && !at_start &&
                (one_way ? !fo_no_nearer(&h, &hr, occ, occ_ref) : !fb_agree(&h, &hr) || occ != occ_ref)) {
                fprintf(stderr, "%s disagrees with brute on ray %u: prim %u t %a vs prim %u t %a, occ %d vs %d%s\n",
                        name, i, h.prim, h.t, hr.prim, hr.t, occ, occ_ref, one_way ? " (one-way check)" : "");
                abort();
            }
        }
        sidx_accel_stats s;
        if (sidx_accel_stats_get(a, &s) != SIDX_OK) abort();
        sidx_accel_destroy(a);
    }
    sidx_accel_destroy(ref);
    sidx_mesh_free(&m);
    return 0;
}
