/* scenes.c — built-in procedural scenes, so every test and lesson runs
 * without files.
 *
 * Every scene is built through a small growable builder and is
 * deterministic: no rand(), no clock, no hash-order dependence; the random
 * soup uses a local splitmix64.  Closed objects are built with shared
 * vertices (never duplicated positions), so each edge belongs to exactly
 * two triangles, wound consistently with outward normals (counter-clockwise
 * seen from outside).  Y is up, except flat2d, which lies in the xy plane
 * and is viewed from +z. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sidx_internal.h"

/* ---- builder --------------------------------------------------------------- */

typedef struct {
    sidx_vec3 *pos;
    size_t nv, cap_v;
    uint32_t *idx;
    size_t nt, cap_t;
    int failed; /* an allocation failed: later calls do nothing */
} builder;

static int reserve(void **p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return 1;
    size_t n = *cap ? *cap : 64;
    while (n < need) {
        if (n > SIZE_MAX / 2) return 0;
        n *= 2;
    }
    if (n > SIZE_MAX / size) return 0;
    void *q = realloc(*p, n * size);
    if (!q) return 0;
    *p = q;
    *cap = n;
    return 1;
}

static uint32_t vtx(builder *b, float x, float y, float z)
{
    if (b->failed) return 0;
    if (b->nv >= UINT32_MAX || !reserve((void **)&b->pos, &b->cap_v, b->nv + 1, sizeof *b->pos)) {
        b->failed = 1;
        return 0;
    }
    b->pos[b->nv] = sidx_v3(x, y, z);
    return (uint32_t)b->nv++;
}

static uint32_t vtxv(builder *b, sidx_vec3 p) { return vtx(b, p.x, p.y, p.z); }

static void tri(builder *b, uint32_t i0, uint32_t i1, uint32_t i2)
{
    if (b->failed) return;
    if (b->nt >= UINT32_MAX || !reserve((void **)&b->idx, &b->cap_t, b->nt + 1, 3 * sizeof *b->idx)) {
        b->failed = 1;
        return;
    }
    uint32_t *t = b->idx + 3 * b->nt++;
    t[0] = i0;
    t[1] = i1;
    t[2] = i2;
}

/* Quad a b c d (counter-clockwise) as (a b c), (a c d). */
static void quad(builder *b, uint32_t a, uint32_t bb, uint32_t c, uint32_t d)
{
    tri(b, a, bb, c);
    tri(b, a, c, d);
}

static void builder_free(builder *b)
{
    free(b->pos);
    free(b->idx);
    memset(b, 0, sizeof *b);
}

static sidx_status builder_finish(builder *b, const char *name, sidx_mesh *out, sidx_error *err)
{
    if (!b->failed && !b->pos) reserve((void **)&b->pos, &b->cap_v, 1, sizeof *b->pos);
    if (!b->failed && !b->idx) reserve((void **)&b->idx, &b->cap_t, 1, 3 * sizeof *b->idx);
    if (b->failed || !b->pos || !b->idx) {
        builder_free(b);
        return sidx__fail(err, SIDX_ERR_NOMEM, "scene %s: out of memory", name);
    }
    sidx_mesh m = {b->pos, b->idx, (uint32_t)b->nv, (uint32_t)b->nt};
    sidx_status s = sidx_mesh_validate(&m, err);
    if (s != SIDX_OK) { /* a bug in a generator, not a user error */
        builder_free(b);
        return s;
    }
    *out = m;
    memset(b, 0, sizeof *b);
    return SIDX_OK;
}

/* Adds triangle (a b c) of freshly added vertices, flipped if needed so its
 * normal points away from `inside` (for boxes whose winding is easier to
 * state by "which side is out" than by hand). */
static void tri_facing_away(builder *b, sidx_vec3 a, sidx_vec3 bb, sidx_vec3 c, uint32_t ia, uint32_t ib, uint32_t ic,
                            sidx_vec3 inside)
{
    const sidx_vec3 n = sidx_v3_cross(sidx_v3_sub(bb, a), sidx_v3_sub(c, a));
    if (sidx_v3_dot(n, sidx_v3_sub(a, inside)) >= 0.0f) tri(b, ia, ib, ic);
    else tri(b, ia, ic, ib);
}

/* Deterministic PRNG (splitmix64): same stream on every machine. */
static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
/* Uniform in [0, 1): the top 24 bits, so the float is exact. */
static float rnd01(uint64_t *state) { return (float)(splitmix64(state) >> 40) * (1.0f / 16777216.0f); }

static const float PI_F = 3.14159265358979323846f;

/* Sine and cosine of an angle, the same bits on every platform.  Libms
 * round sinf and cosf differently in the last bit (glibc and the musl of
 * the WebAssembly build disagree on about one angle in forty of the
 * teapot's), and a built-in scene must be one set of vertices wherever it
 * is built, so a trace on the web page equals sidx-step's.  The angle is
 * reduced by π/2 in double (π/2 in two parts, Cody and Waite 1980), both
 * Taylor series run to degree 17/18 on |r| <= π/4 (error below 1e-17),
 * and the result is rounded to float once.  Only + and * in double: with
 * no contraction (-ffp-contract=off) every compiler gives these bits. */
static void scene_sincos(float angle, float *sine, float *cosine)
{
    static const double factorial[19] = {1.0, 1.0, 2.0, 6.0, 24.0, 120.0, 720.0, 5040.0, 40320.0, 362880.0,
                                         3628800.0, 39916800.0, 479001600.0, 6227020800.0, 87178291200.0,
                                         1307674368000.0, 20922789888000.0, 355687428096000.0,
                                         6402373705728000.0};
    const double half_pi_hi = 1.57079632679489655800e+00, half_pi_lo = 6.12323399573676603587e-17;
    const double x = (double)angle;
    const double quarter_turns = nearbyint(x / half_pi_hi);
    const double r = (x - quarter_turns * half_pi_hi) - quarter_turns * half_pi_lo;
    const double r2 = r * r;
    /* sin r = r (1 - r²/3! + r⁴/5! - ...), cos r = 1 - r²/2! + r⁴/4! - ... */
    double sin_series = 1.0 / factorial[17], cos_series = 1.0 / factorial[18];
    for (int k = 15; k >= 1; k -= 2) sin_series = sin_series * -r2 + 1.0 / factorial[k];
    for (int k = 16; k >= 0; k -= 2) cos_series = cos_series * -r2 + 1.0 / factorial[k];
    const double sin_r = r * sin_series, cos_r = cos_series;
    /* sin(r + qπ/2), cos(r + qπ/2) by the quarter turn q mod 4 */
    double s, c;
    switch ((int)((long long)quarter_turns & 3)) {
    case 0: s = sin_r; c = cos_r; break;
    case 1: s = cos_r; c = -sin_r; break;
    case 2: s = -sin_r; c = -cos_r; break;
    default: s = -cos_r; c = sin_r; break;
    }
    *sine = (float)s;
    *cosine = (float)c;
}

/* ---- icosphere --------------------------------------------------------------- */

/* Midpoint cache: open addressing on the edge (lo, hi), so an edge shared
 * by two triangles gets one new vertex, and the sphere stays closed. */
typedef struct {
    uint64_t *keys; /* (lo << 32 | hi) + 1; 0 = empty */
    uint32_t *vals;
    size_t mask;
} edge_map;

static uint32_t midpoint(builder *b, edge_map *em, uint32_t i0, uint32_t i1)
{
    const uint32_t lo = i0 < i1 ? i0 : i1, hi = i0 < i1 ? i1 : i0;
    const uint64_t key = ((uint64_t)lo << 32 | hi) + 1;
    size_t h = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 17) & em->mask;
    while (em->keys[h] && em->keys[h] != key) h = (h + 1) & em->mask;
    if (em->keys[h]) return em->vals[h];
    if (b->failed) return 0;
    /* Both triangles ask with the same (lo, hi), but the sum is computed
     * in that fixed order anyway, then pushed out to the unit sphere. */
    const sidx_vec3 m = sidx_v3_add(b->pos[lo], b->pos[hi]);
    const float inv = 1.0f / sidx_v3_length(m);
    const uint32_t v = vtxv(b, sidx_v3_scale(m, inv));
    em->keys[h] = key;
    em->vals[h] = v;
    return v;
}

static void make_icosphere(builder *b, unsigned levels)
{
    /* The 12 vertices of an icosahedron: cyclic permutations of
     * (0, ±1, ±phi), normalized. */
    const float t = 1.61803398874989484820f;
    const float raw[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    static const uint32_t faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                          {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                          {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                          {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int i = 0; i < 12; ++i) {
        const sidx_vec3 p = sidx_v3(raw[i][0], raw[i][1], raw[i][2]);
        vtxv(b, sidx_v3_scale(p, 1.0f / sidx_v3_length(p)));
    }
    for (int i = 0; i < 20; ++i) tri(b, faces[i][0], faces[i][1], faces[i][2]);

    for (unsigned level = 0; level < levels && !b->failed; ++level) {
        /* Each triangle becomes four; the new triangles go to a fresh index
         * array and replace the old one. */
        const size_t nt = b->nt;
        uint32_t *old = b->idx;
        b->idx = NULL;
        b->nt = b->cap_t = 0;
        if (!reserve((void **)&b->idx, &b->cap_t, 4 * nt, 3 * sizeof *b->idx)) b->failed = 1;
        if (!reserve((void **)&b->pos, &b->cap_v, b->nv + 3 * nt / 2, sizeof *b->pos)) b->failed = 1;
        edge_map em = {NULL, NULL, 0};
        size_t slots = 16;
        while (slots < 3 * nt) slots *= 2; /* 3nt/2 edges, load <= 1/2 */
        em.keys = calloc(slots, sizeof *em.keys);
        em.vals = malloc(slots * sizeof *em.vals);
        em.mask = slots - 1;
        if (!em.keys || !em.vals) b->failed = 1;
        for (size_t i = 0; i < nt && !b->failed; ++i) {
            const uint32_t a = old[3 * i], c1 = old[3 * i + 1], c2 = old[3 * i + 2];
            const uint32_t ab = midpoint(b, &em, a, c1), bc = midpoint(b, &em, c1, c2), ca = midpoint(b, &em, c2, a);
            tri(b, a, ab, ca);
            tri(b, c1, bc, ab);
            tri(b, c2, ca, bc);
            tri(b, ab, bc, ca);
        }
        free(em.keys);
        free(em.vals);
        free(old);
    }
}

/* ---- teapot -------------------------------------------------------------------- */

/* Catmull–Rom through profile points (r, y): smooth, and passes through
 * every key point, so the silhouette is what the table says. */
static float catmull_rom1(float p0, float p1, float p2, float p3, float t)
{
    const float t2 = t * t, t3 = t2 * t;
    return 0.5f * (2.0f * p1 + (-p0 + p2) * t + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * t2 +
                   (-p0 + 3.0f * p1 - 3.0f * p2 + p3) * t3);
}

static void catmull_rom(const float (*k)[2], int n, int seg, float t, float *r, float *y)
{
    const int i0 = seg > 0 ? seg - 1 : 0, i1 = seg, i2 = seg + 1, i3 = seg + 2 < n ? seg + 2 : n - 1;
    *r = catmull_rom1(k[i0][0], k[i1][0], k[i2][0], k[i3][0], t);
    *y = catmull_rom1(k[i0][1], k[i1][1], k[i2][1], k[i3][1], t);
}

/* Surface of revolution about the y axis (plus translation `at`, scale s),
 * closed at both ends by pole vertices: body and lid in one piece.  The
 * profile runs from the bottom pole to the top pole. */
static void revolve(builder *b, const float (*key)[2], int nkey, int per_seg, int around, sidx_vec3 at, float s)
{
    const uint32_t bottom = vtx(b, at.x, at.y + s * key[0][1], at.z);
    uint32_t first_ring = 0;
    int rings = 0;
    for (int seg = 0; seg + 1 < nkey; ++seg) {
        for (int j = 0; j < per_seg; ++j) {
            if (seg == 0 && j == 0) continue; /* the bottom pole */
            float r, y;
            catmull_rom(key, nkey, seg, (float)j / (float)per_seg, &r, &y);
            if (r < 1e-3f) r = 1e-3f; /* only the poles sit on the axis */
            /* the spline overshoots a little near the poles: keep a flat
             * bottom (a teapot stands on its floor) and a knob top */
            if (y < key[0][1]) y = key[0][1];
            if (y > key[nkey - 1][1]) y = key[nkey - 1][1];
            for (int k = 0; k < around; ++k) {
                const float phi = 2.0f * PI_F * (float)k / (float)around;
                float sin_phi, cos_phi;
                scene_sincos(phi, &sin_phi, &cos_phi);
                const uint32_t v = vtx(b, at.x + s * r * cos_phi, at.y + s * y, at.z + s * r * sin_phi);
                if (rings == 0 && k == 0) first_ring = v;
            }
            ++rings;
        }
    }
    const uint32_t top = vtx(b, at.x, at.y + s * key[nkey - 1][1], at.z);
    /* Winding: with the profile rising and phi increasing, (ring i, k),
     * (ring i+1, k), (ring i+1, k+1) faces outward. */
    for (int k = 0; k < around; ++k) {
        const uint32_t k1 = (uint32_t)((k + 1) % around);
        tri(b, bottom, first_ring + (uint32_t)k, first_ring + k1);
    }
    for (int i = 0; i + 1 < rings; ++i) {
        const uint32_t r0 = first_ring + (uint32_t)(i * around), r1 = r0 + (uint32_t)around;
        for (int k = 0; k < around; ++k) {
            const uint32_t k1 = (uint32_t)((k + 1) % around);
            quad(b, r0 + (uint32_t)k, r1 + (uint32_t)k, r1 + k1, r0 + k1);
        }
    }
    const uint32_t last = first_ring + (uint32_t)((rings - 1) * around);
    for (int k = 0; k < around; ++k) {
        const uint32_t k1 = (uint32_t)((k + 1) % around);
        tri(b, last + (uint32_t)k, top, last + k1);
    }
}

/* A closed tube of circular section swept along a path in the xy plane
 * (spout, handle), capped at both ends.  path(u) gives centre and radius
 * for u in [0, 1]. */
typedef void (*path_fn)(float u, sidx_vec3 *centre, float *radius);

static void sweep(builder *b, path_fn path, int along, int around, sidx_vec3 at, float s)
{
    uint32_t first = 0;
    for (int i = 0; i <= along; ++i) {
        const float u = (float)i / (float)along;
        sidx_vec3 c, c0, c1;
        float r, r_unused;
        path(u, &c, &r);
        /* Tangent by central difference; N = z × T, B = z, so (T, N, B) is
         * right-handed and the section circle cos·N + sin·B turns
         * counter-clockwise about T. */
        path(u > 0.001f ? u - 0.001f : 0.0f, &c0, &r_unused);
        path(u < 0.999f ? u + 0.001f : 1.0f, &c1, &r_unused);
        const sidx_vec3 d = sidx_v3_sub(c1, c0);
        const float len = sqrtf(d.x * d.x + d.y * d.y);
        const sidx_vec3 n = sidx_v3(-d.y / len, d.x / len, 0.0f);
        for (int k = 0; k < around; ++k) {
            const float th = 2.0f * PI_F * (float)k / (float)around;
            float sin_th, cos_th;
            scene_sincos(th, &sin_th, &cos_th);
            const float cn = r * cos_th, sn = r * sin_th;
            const sidx_vec3 p = sidx_v3(c.x + cn * n.x, c.y + cn * n.y, c.z + sn);
            const uint32_t v = vtx(b, at.x + s * p.x, at.y + s * p.y, at.z + s * p.z);
            if (i == 0 && k == 0) first = v;
        }
    }
    sidx_vec3 c;
    float r;
    path(0.0f, &c, &r);
    const uint32_t cap0 = vtx(b, at.x + s * c.x, at.y + s * c.y, at.z + s * c.z);
    path(1.0f, &c, &r);
    const uint32_t cap1 = vtx(b, at.x + s * c.x, at.y + s * c.y, at.z + s * c.z);
    /* The surface normal is (along) × (around) = inward for this frame, so
     * the quads take the other order. */
    for (int i = 0; i < along; ++i) {
        const uint32_t r0 = first + (uint32_t)(i * around), r1 = r0 + (uint32_t)around;
        for (int k = 0; k < around; ++k) {
            const uint32_t k1 = (uint32_t)((k + 1) % around);
            quad(b, r0 + (uint32_t)k, r0 + k1, r1 + k1, r1 + (uint32_t)k);
        }
    }
    const uint32_t last = first + (uint32_t)(along * around);
    for (int k = 0; k < around; ++k) {
        const uint32_t k1 = (uint32_t)((k + 1) % around);
        tri(b, cap0, first + k1, first + (uint32_t)k); /* faces -T */
        tri(b, cap1, last + (uint32_t)k, last + k1);   /* faces +T */
    }
}

/* Spout: a quadratic Bézier from inside the body up and out to the tip,
 * tapering. */
static void spout_path(float u, sidx_vec3 *c, float *r)
{
    const float p0x = 1.3f, p0y = 0.75f, p1x = 2.75f, p1y = 0.75f, p2x = 3.25f, p2y = 2.25f;
    const float a = (1 - u) * (1 - u), m = 2 * u * (1 - u), z = u * u;
    *c = sidx_v3(a * p0x + m * p1x + z * p2x, a * p0y + m * p1y + z * p2y, 0.0f);
    *r = 0.42f - 0.25f * u;
}

/* Handle: most of a torus around (-1.9, 1.3), both ends inside the body. */
static void handle_path(float u, sidx_vec3 *c, float *r)
{
    const float a0 = 40.0f * PI_F / 180.0f, a1 = 320.0f * PI_F / 180.0f;
    const float a = a0 + (a1 - a0) * u;
    float sin_a, cos_a;
    scene_sincos(a, &sin_a, &cos_a);
    *c = sidx_v3(-1.9f + 0.75f * cos_a, 1.3f + 0.75f * sin_a, 0.0f);
    *r = 0.13f;
}

/* Profile of body and lid (r, y), bottom pole to knob top; the Utah
 * teapot is about 2 wide at the belly and 3.15 tall with the knob. */
static const float teapot_profile[][2] = {
    {0.00f, 0.00f}, {1.20f, 0.00f}, {1.50f, 0.08f}, {1.85f, 0.45f}, {2.00f, 0.95f}, {1.90f, 1.50f},
    {1.65f, 1.95f}, {1.45f, 2.20f}, {1.52f, 2.30f}, {1.40f, 2.36f}, {1.00f, 2.45f}, {0.50f, 2.60f},
    {0.18f, 2.72f}, {0.34f, 2.86f}, {0.28f, 3.02f}, {0.00f, 3.10f},
};

/* detail = segments around the body (default 40, ~3.3k triangles). */
static void make_teapot(builder *b, unsigned detail, sidx_vec3 at, float s)
{
    const int around = (int)detail;
    const int nkey = (int)(sizeof teapot_profile / sizeof teapot_profile[0]);
    const int per_seg = around / 20 > 1 ? around / 20 : 1;
    revolve(b, teapot_profile, nkey, per_seg, around, at, s);
    const int tube_around = around / 3 > 6 ? around / 3 : 6;
    sweep(b, spout_path, around / 2 > 4 ? around / 2 : 4, tube_around, at, s);
    sweep(b, handle_path, around / 2 > 4 ? around / 2 : 4, tube_around, at, s);
}

/* ---- stadium ---------------------------------------------------------------------- */

/* The "teapot in a stadium" problem: a ~1-unit teapot at the centre of a
 * ~1000-unit stadium, so a uniform grid sized by the whole scene puts the
 * teapot in one cell. */
static void make_stadium(builder *b, unsigned detail)
{
    /* The teapot spans x in [-2.7, 3.5]: scale 1/6 makes it ~1 wide.  It
     * stands 1 mm (scene units: 0.001) above the floor, so its bottom is
     * not coplanar with it. */
    make_teapot(b, 40, sidx_v3(0.0f, 0.001f, 0.0f), 1.0f / 6.0f);

    const float F = 1100.0f;
    const uint32_t f0 = vtx(b, -F, 0, -F), f1 = vtx(b, -F, 0, F), f2 = vtx(b, F, 0, F), f3 = vtx(b, F, 0, -F);
    quad(b, f0, f1, f2, f3); /* normal +y */

    /* Stands: a bowl of revolution, inner edge r = 800 on the floor rising
     * to r = 1000, h = 200, then a vertical outer wall to h = 260. */
    const float prof[][2] = {{800.0f, 0.0f}, {900.0f, 100.0f}, {1000.0f, 200.0f}, {1000.0f, 260.0f}};
    const int np = 4, around = (int)detail;
    const uint32_t base = (uint32_t)b->nv;
    for (int i = 0; i < np; ++i)
        for (int k = 0; k < around; ++k) {
            const float phi = 2.0f * PI_F * (float)k / (float)around;
            float sin_phi, cos_phi;
            scene_sincos(phi, &sin_phi, &cos_phi);
            vtx(b, prof[i][0] * cos_phi, prof[i][1], prof[i][0] * sin_phi);
        }
    /* Facing the centre (the side the teapot sees). */
    for (int i = 0; i + 1 < np; ++i)
        for (int k = 0; k < around; ++k) {
            const uint32_t k1 = (uint32_t)((k + 1) % around);
            const uint32_t r0 = base + (uint32_t)(i * around), r1 = r0 + (uint32_t)around;
            quad(b, r0 + (uint32_t)k, r0 + k1, r1 + k1, r1 + (uint32_t)k);
        }
}

/* ---- soup ------------------------------------------------------------------------------ */

/* detail random triangles: centres uniform in the unit cube, corners
 * within ±0.05 of the centre (clamped to the cube), fixed seed. */
static void make_soup(builder *b, unsigned count)
{
    uint64_t st = 0x5EED5EED2024ull;
    for (unsigned i = 0; i < count && !b->failed; ++i) {
        const float cx = rnd01(&st), cy = rnd01(&st), cz = rnd01(&st);
        uint32_t v[3];
        for (int k = 0; k < 3; ++k) {
            float p[3] = {cx + 0.1f * (rnd01(&st) - 0.5f), cy + 0.1f * (rnd01(&st) - 0.5f),
                          cz + 0.1f * (rnd01(&st) - 0.5f)};
            for (int a = 0; a < 3; ++a) p[a] = p[a] < 0.0f ? 0.0f : p[a] > 1.0f ? 1.0f : p[a];
            v[k] = vtx(b, p[0], p[1], p[2]);
        }
        tri(b, v[0], v[1], v[2]);
    }
}

/* ---- boxes (menger, cornell) ------------------------------------------------------------ */

/* Axis-aligned closed box, 8 shared vertices, 12 outward triangles. */
static void box(builder *b, sidx_vec3 lo, sidx_vec3 hi)
{
    uint32_t v[8];
    for (int i = 0; i < 8; ++i)
        v[i] = vtx(b, (i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
    /* Corner bits: 1 = +x, 2 = +y, 4 = +z.  Each face counter-clockwise
     * seen from outside. */
    quad(b, v[0], v[4], v[6], v[2]); /* -x */
    quad(b, v[1], v[3], v[7], v[5]); /* +x */
    quad(b, v[0], v[1], v[5], v[4]); /* -y */
    quad(b, v[2], v[6], v[7], v[3]); /* +y */
    quad(b, v[0], v[2], v[3], v[1]); /* -z */
    quad(b, v[4], v[5], v[7], v[6]); /* +z */
}

/* Menger sponge of level L in [-1, 1]^3: cell (i, j, k) of the 3^L grid is
 * solid unless, at some base-3 digit, two or more of i, j, k have a 1.
 * Solid cells become separate cubes, so neighbours share coplanar faces. */
static void make_menger(builder *b, unsigned level)
{
    uint32_t n = 1;
    for (unsigned i = 0; i < level; ++i) n *= 3;
    const float step = 2.0f / (float)n;
    for (uint32_t i = 0; i < n && !b->failed; ++i)
        for (uint32_t j = 0; j < n; ++j)
            for (uint32_t k = 0; k < n; ++k) {
                uint32_t a = i, bb = j, c = k;
                int solid = 1;
                for (unsigned d = 0; d < level && solid; ++d) {
                    if ((a % 3 == 1) + (bb % 3 == 1) + (c % 3 == 1) >= 2) solid = 0;
                    a /= 3;
                    bb /= 3;
                    c /= 3;
                }
                if (!solid) continue;
                box(b, sidx_v3(-1.0f + step * (float)i, -1.0f + step * (float)j, -1.0f + step * (float)k),
                    sidx_v3(-1.0f + step * (float)(i + 1), -1.0f + step * (float)(j + 1),
                            -1.0f + step * (float)(k + 1)));
            }
}

/* A closed box given by its top quad (4 corners in any winding) and the
 * heights of its bottom and top: the Cornell blocks are rotated. */
static void slanted_block(builder *b, const float (*xz)[2], float y0, float y1)
{
    sidx_vec3 p[8], mid = sidx_v3(0, 0.5f * (y0 + y1), 0);
    uint32_t v[8];
    for (int i = 0; i < 4; ++i) {
        p[i] = sidx_v3(xz[i][0], y0, xz[i][1]);
        p[i + 4] = sidx_v3(xz[i][0], y1, xz[i][1]);
        mid.x += 0.25f * xz[i][0];
        mid.z += 0.25f * xz[i][1];
    }
    for (int i = 0; i < 8; ++i) v[i] = vtxv(b, p[i]);
    /* bottom, top, 4 sides; orientation fixed against the block centre */
    const int faces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
    for (int f = 0; f < 6; ++f) {
        const int *q = faces[f];
        tri_facing_away(b, p[q[0]], p[q[1]], p[q[2]], v[q[0]], v[q[1]], v[q[2]], mid);
        tri_facing_away(b, p[q[0]], p[q[2]], p[q[3]], v[q[0]], v[q[2]], v[q[3]], mid);
    }
}

/* Quad facing towards `toward` (walls face into the room). */
static void wall(builder *b, const float (*c)[3], sidx_vec3 toward)
{
    sidx_vec3 p[4];
    uint32_t v[4];
    for (int i = 0; i < 4; ++i) {
        p[i] = sidx_v3(c[i][0], c[i][1], c[i][2]);
        v[i] = vtxv(b, p[i]);
    }
    /* "facing away from a point behind the wall" = facing the room */
    const sidx_vec3 n = sidx_v3_cross(sidx_v3_sub(p[1], p[0]), sidx_v3_sub(p[2], p[0]));
    const int keep = sidx_v3_dot(n, sidx_v3_sub(toward, p[0])) >= 0.0f;
    if (keep) quad(b, v[0], v[1], v[2], v[3]);
    else quad(b, v[0], v[3], v[2], v[1]);
}

/* The Cornell box from the published measurements (millimetres), scaled to
 * metres-ish units (x 0.01): 5 walls, light, short and tall blocks, 36
 * triangles. */
static void make_cornell(builder *b)
{
    const float S = 0.01f;
    const float walls[5][4][3] = {
        {{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}},                             /* floor */
        {{556.0f, 548.8f, 0}, {556.0f, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}},         /* ceiling */
        {{549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}},         /* back */
        {{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}},                             /* green */
        {{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0}},         /* red */
    };
    const sidx_vec3 centre = sidx_v3(278.0f * S, 274.4f * S, 279.6f * S);
    for (int w = 0; w < 5; ++w) {
        float c[4][3];
        for (int i = 0; i < 4; ++i)
            for (int a = 0; a < 3; ++a) c[i][a] = S * walls[w][i][a];
        wall(b, (const float (*)[3])c, centre);
    }
    /* The light, 1 mm below the ceiling so the two are not coplanar. */
    const float light[4][3] = {{343.0f * S, 547.8f * S, 227.0f * S},
                               {343.0f * S, 547.8f * S, 332.0f * S},
                               {213.0f * S, 547.8f * S, 332.0f * S},
                               {213.0f * S, 547.8f * S, 227.0f * S}};
    wall(b, light, sidx_v3(278.0f * S, 0.0f, 279.6f * S)); /* facing down */
    const float short_top[4][2] = {{130.0f * S, 65.0f * S}, {82.0f * S, 225.0f * S}, {240.0f * S, 272.0f * S},
                                   {290.0f * S, 114.0f * S}};
    const float tall_top[4][2] = {{423.0f * S, 247.0f * S}, {265.0f * S, 296.0f * S}, {314.0f * S, 456.0f * S},
                                  {472.0f * S, 406.0f * S}};
    slanted_block(b, short_top, 0.0f, 165.0f * S);
    slanted_block(b, tall_top, 0.0f, 330.0f * S);
}

/* ---- flat2d ---------------------------------------------------------------------------- */

/* 2D triangles in [0, 10]^2 for drawing 2D structures on the board: big,
 * small, slivers and clusters, so quadtrees and BVHs have something to
 * split.  More than the 16 hand-placed ones come from the PRNG. */
static const float flat_tris[16][6] = {
    {0.5f, 0.5f, 3.5f, 0.8f, 1.2f, 3.0f},   {4.0f, 0.5f, 5.0f, 0.5f, 4.5f, 1.4f},   {6.0f, 0.3f, 9.6f, 1.0f, 7.0f, 2.6f},
    {0.4f, 4.0f, 1.4f, 4.2f, 0.6f, 5.2f},   {2.2f, 3.6f, 4.8f, 3.2f, 3.0f, 6.2f},   {5.6f, 3.4f, 6.2f, 3.4f, 5.9f, 3.9f},
    {6.4f, 3.9f, 6.9f, 4.0f, 6.6f, 4.5f},   {7.0f, 4.6f, 7.4f, 4.6f, 7.2f, 5.0f},   {8.0f, 3.0f, 9.8f, 3.2f, 9.0f, 6.4f},
    {0.2f, 7.0f, 3.0f, 6.6f, 1.6f, 9.8f},   {3.6f, 7.2f, 9.4f, 7.6f, 3.8f, 7.9f},   {4.6f, 8.4f, 5.4f, 8.2f, 5.0f, 9.6f},
    {5.8f, 8.6f, 6.3f, 8.6f, 6.05f, 9.1f},  {7.0f, 8.4f, 9.8f, 8.2f, 8.6f, 9.9f},   {4.0f, 5.0f, 5.2f, 4.6f, 4.9f, 6.3f},
    {6.0f, 5.4f, 7.8f, 5.8f, 6.4f, 6.9f},
};

/* One 2D triangle as one 3D triangle.  A ray in the plane of a flat
 * triangle never meets it (the test sees it edge-on), so the triangle is
 * tilted: the corner opposite its shortest side stays at z = 0, the next
 * corner (in the given order) goes to z = +0.05 and the last to -0.05.
 * Seen from +z it is the drawn triangle, with the same xy bounds, so 2D
 * structures cut the same boxes; it crosses z = 0 along the segment from
 * that corner to the shortest side's midpoint: its longest median, the
 * longest chord through the centroid.  A ray in the plane z = 0 (a 2D ray)
 * hits the triangle where it crosses this "spine" and misses it if it only
 * clips a corner the spine does not reach, or runs along the spine. */
static void board_tri(builder *b, const float t[6])
{
    float len2[3]; /* len2[k]: squared length of the side opposite corner k */
    for (int k = 0; k < 3; ++k) {
        const float *p = &t[2 * ((k + 1) % 3)], *q = &t[2 * ((k + 2) % 3)];
        len2[k] = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]);
    }
    int c = 0; /* the spine's corner: opposite the shortest side (first on ties) */
    for (int k = 1; k < 3; ++k)
        if (len2[k] < len2[c]) c = k;
    float z[3];
    z[c] = 0.0f;
    z[(c + 1) % 3] = 0.05f;
    z[(c + 2) % 3] = -0.05f;
    uint32_t v[3];
    for (int k = 0; k < 3; ++k) v[k] = vtx(b, t[2 * k], t[2 * k + 1], z[k]);
    tri(b, v[0], v[1], v[2]);
}

static void make_flat2d(builder *b, unsigned count)
{
    uint64_t st = 0xF1A72Dull;
    for (unsigned i = 0; i < count && !b->failed; ++i) {
        if (i < 16) {
            board_tri(b, flat_tris[i]);
            continue;
        }
        /* extras: small triangles, size 0.2 .. 1.0, inside [0, 10]^2 */
        const float size = 0.2f + 0.8f * rnd01(&st);
        const float x = 0.1f + (9.8f - size) * rnd01(&st), y = 0.1f + (9.8f - size) * rnd01(&st);
        /* drawn in this order since the shapes were first made (last corner first) */
        const float r5 = rnd01(&st), r4 = rnd01(&st), r3 = rnd01(&st), r2 = rnd01(&st);
        const float t[6] = {x, y, x + size * r2 + 0.1f * size, y + 0.1f * size * r3, x + size * r4,
                            y + size * (0.5f + 0.5f * r5)};
        board_tri(b, t);
    }
}

/* ---- kd-slide -------------------------------------------------------------------------------- */

/* Deck 000, "kD-Tree Example (1)-(7)" and "kD-Tree Traversal (1)-(11)":
 * eight 2D triangles in the xy plane, seen from +z, placed so that the
 * slide's tree (kd_slide_tree below) holds them as the figure does and
 * the ray (0, 4.2, 0) + t·(1, 0.15, 0) (t = x) walks it as the slide's
 * table says: A, B, L2, C, D, L4 (where it tests △ and ▽ and finds △
 * beyond L4's cell: "CANNOT terminate"), L5, L3.
 *
 *   y 7.5 +------------+--------------+-----------+
 *         | L2  t2  t3 | L5     t6    |           |
 *     5   |            +--------------+    L3     |
 *     4   +------------+ L4           |  △ (hit)  |
 *         | L1  t0  t1 |   ▽    △     |    t7     |
 *   y 0.5 +------------+--------------+-----------+
 *        x 1        A: x = 4      C: x = 7.5     9.5
 *   (B: y = 4 on the left of A, D: y = 5 between A and C; △ reaches
 *   over C's plane into L3, where the ray meets it.)
 *
 * L1 and L2 hold two triangles each so that L4's references start a
 * block of four (the leaf layout, kdtree_internal.h): a leaf's SSE pass
 * also tests its block's neighbouring lanes, and △ in a block of L2
 * would be found there, before the slide finds it in L4.
 *
 * A ray in the plane of a flat triangle never meets it (the test sees an
 * edge-on triangle), and extruding each one into a prism makes 8
 * triangles of every shape on the slide.  So each slide triangle is one
 * triangle tilted about the vertical line through its centroid: vertex z
 * = 0.05·(x − c_x) / max|x − c_x|.  Seen from +z it is the slide's
 * triangle, and a ray in the plane z = 0 meets it where it crosses the
 * line x = c_x; the counts a student reads (8 triangles, 2 tests in L4)
 * are the figure's. */
static const float kd_slide_tris[8][6] = {
    {1.0f, 1.0f, 3.0f, 1.0f, 2.0f, 3.0f},   /* t0, in L1 */
    {3.2f, 0.8f, 3.8f, 0.8f, 3.5f, 1.6f},   /* t1, in L1 */
    {1.0f, 6.0f, 3.0f, 6.0f, 2.0f, 7.5f},   /* t2, in L2: above the ray */
    {3.0f, 5.0f, 3.8f, 5.0f, 3.4f, 5.8f},   /* t3, in L2: above the ray */
    {6.5f, 3.5f, 9.5f, 3.5f, 9.0f, 6.5f},   /* △, in L4 and L3: the ray meets it in L3 */
    {4.5f, 3.0f, 6.5f, 3.0f, 5.5f, 1.0f},   /* ▽, in L4: below the ray */
    {5.0f, 6.5f, 6.5f, 6.5f, 5.75f, 7.5f},  /* t6, in L5: above the ray */
    {8.0f, 0.5f, 9.5f, 0.5f, 8.75f, 2.0f},  /* t7, in L3: below the ray */
};

static void make_kd_slide(builder *b)
{
    for (int i = 0; i < 8; ++i) {
        const float *t = kd_slide_tris[i];
        const float cx = (t[0] + t[2] + t[4]) / 3.0f;
        const float s = fmaxf(fabsf(t[0] - cx), fmaxf(fabsf(t[2] - cx), fabsf(t[4] - cx)));
        uint32_t v[3];
        for (int k = 0; k < 3; ++k) v[k] = vtx(b, t[2 * k], t[2 * k + 1], 0.05f * (t[2 * k] - cx) / s);
        tri(b, v[0], v[1], v[2]);
    }
}

/* The slide's tree, depth first: A splits x (left B, right C), B splits y
 * (L1 below, L2 above), C splits x (D, L3), D splits y (L4 below, L5
 * above).  The SAH would not cut eight triangles this way (the lesson says
 * what it makes of them), so the tree is given (sidx_kdtree_build_from_splits). */
static const sidx_kd_split kd_slide_tree[] = {
    {0, 4.0f, "A"},         {1, 4.0f, "B"},         {SIDX_KD_LEAF, 0.0f, "L1"}, {SIDX_KD_LEAF, 0.0f, "L2"},
    {0, 7.5f, "C"},         {1, 5.0f, "D"},         {SIDX_KD_LEAF, 0.0f, "L4"}, {SIDX_KD_LEAF, 0.0f, "L5"},
    {SIDX_KD_LEAF, 0.0f, "L3"},
};

/* ---- grid ---------------------------------------------------------------------------------- */

/* detail x detail quads on y = 0, x and z in [-1, 1], normal +y. */
static void make_grid(builder *b, unsigned n)
{
    for (unsigned j = 0; j <= n; ++j)
        for (unsigned i = 0; i <= n; ++i)
            vtx(b, -1.0f + 2.0f * (float)i / (float)n, 0.0f, -1.0f + 2.0f * (float)j / (float)n);
    for (unsigned j = 0; j < n; ++j)
        for (unsigned i = 0; i < n; ++i) {
            const uint32_t v00 = j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
            quad(b, v00, v01, v11, v10); /* (+z) x (+x) = +y */
        }
}

/* ---- height field ----------------------------------------------------------------------- */

/* detail x detail quads over x, z in [-1, 1], y a sum of two sine waves
 * (|y| <= 0.1), two triangles per quad: a terrain-like mesh of any size
 * (2 detail^2 triangles, (detail + 1)^2 vertices), the surface of
 * `sidx-bench scale --scene heightfield` and `sidx-bench lazy`.  The
 * waves come from scene_sincos, as the teapot's circles do, so the mesh is
 * the same floats natively and in the WebAssembly lab. */
static void make_heightfield(builder *b, unsigned n)
{
    /* exact sizes up front: at detail 8192 the doubling builder would
     * hold up to twice the 2.4 GB the mesh needs */
    const size_t nv = ((size_t)n + 1) * ((size_t)n + 1), nt = 2 * (size_t)n * n;
    b->pos = malloc(nv * sizeof *b->pos);
    b->idx = malloc(nt * 3 * sizeof *b->idx);
    b->cap_v = b->pos ? nv : 0;
    b->cap_t = b->idx ? nt : 0;
    for (size_t j = 0; j <= n; ++j)
        for (size_t i = 0; i <= n; ++i) {
            const float x = (float)(-1.0 + 2.0 * (double)i / n), z = (float)(-1.0 + 2.0 * (double)j / n);
            float s1, c1, s2, c2, s3, c3;
            scene_sincos(7.0f * x + 1.3f, &s1, &c1);
            scene_sincos(5.0f * z, &s2, &c2);
            scene_sincos(23.0f * (x + z), &s3, &c3);
            vtx(b, x, 0.06f * s1 * c2 + 0.04f * s3, z);
        }
    for (unsigned j = 0; j < n; ++j)
        for (unsigned i = 0; i < n; ++i) {
            const uint32_t v00 = j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
            quad(b, v00, v01, v11, v10); /* (+z) x (+x) = +y, as grid */
        }
}

/* ---- city ---------------------------------------------------------------------------------------- */

/* One building of the city, in its own space (footprint centred on the
 * origin, ground at y = 0), from its own seed: a prism of k = 4..8 sides,
 * radius 4..9, height 12..72, tapered (top 0.55..1 of the base) and
 * twisted (up to ±0.35 rad) with height; every side is detail columns by
 * detail floors of quads, every other one set back 2 % (windows), under a
 * flat roof fanned from its centre.  2·k·detail² + k·detail triangles:
 * 10,512 at the default detail 36 with k = 4. */
static void make_building(builder *b, uint64_t seed, unsigned detail)
{
    uint64_t st = seed;
    const unsigned k = 4u + (unsigned)(rnd01(&st) * 5.0f);
    const float radius = 4.0f + 5.0f * rnd01(&st), height = 12.0f + 60.0f * rnd01(&st);
    const float taper = 0.55f + 0.45f * rnd01(&st), twist = 0.7f * (rnd01(&st) - 0.5f);
    const float phase = 2.0f * PI_F * rnd01(&st);
    const unsigned ring = k * detail;
    for (unsigned f = 0; f <= detail; ++f) {
        const float h = (float)f / (float)detail;
        const float sc = radius * (1.0f + (taper - 1.0f) * h), rot = phase + twist * h;
        for (unsigned p = 0; p < ring; ++p) {
            /* on side p / detail, a fraction of the way from its corner to the next */
            const unsigned side = p / detail;
            const float w = (float)(p % detail) / (float)detail;
            float s0, c0, s1, c1;
            scene_sincos(rot + 2.0f * PI_F * (float)side / (float)k, &s0, &c0);
            scene_sincos(rot + 2.0f * PI_F * (float)(side + 1u) / (float)k, &s1, &c1);
            const float inset = (p % 2u == 1u && f % 2u == 1u && f < detail) ? 0.98f : 1.0f;
            const float x = sc * inset * (c0 + w * (c1 - c0)), z = sc * inset * (s0 + w * (s1 - s0));
            vtx(b, x, height * h, z);
        }
    }
    for (unsigned f = 0; f < detail; ++f)
        for (unsigned p = 0; p < ring; ++p) {
            const uint32_t q = (p + 1u) % ring;
            /* (+y) x (along the ring) = outward */
            quad(b, f * ring + p, (f + 1u) * ring + p, (f + 1u) * ring + q, f * ring + q);
        }
    const uint32_t top = detail * ring, centre = vtx(b, 0.0f, height, 0.0f);
    for (unsigned p = 0; p < ring; ++p) tri(b, centre, top + (p + 1u) % ring, top + p);
}

/* Where building i of n stands: a square grid of blocks 24 apart, streets
 * between them along x and z, each building turned about y by its own
 * angle.  Row-major 3x4 object-to-world. */
static void city_place(uint32_t i, uint32_t n, float m[12])
{
    uint32_t cols = 1;
    while (cols * cols < n) ++cols;
    const float spacing = 24.0f;
    const float x = ((float)(i % cols) - 0.5f * (float)(cols - 1u)) * spacing, z = (float)(i / cols) * spacing;
    uint64_t st = 0xC17ull * 1000003ull + i;
    float sn, cs;
    scene_sincos(2.0f * PI_F * rnd01(&st), &sn, &cs);
    const float r[12] = {cs, 0, sn, x, 0, 1, 0, 0, -sn, 0, cs, z};
    memcpy(m, r, sizeof r);
}

static uint64_t city_seed(uint32_t i) { return 0xB111D1A6ull + 0x9E3779B97F4A7C15ull * (uint64_t)(i + 1u); }

sidx_status sidx_city_make(uint32_t n, uint32_t detail, sidx_city *out, sidx_error *err)
{
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "city: out is NULL");
    memset(out, 0, sizeof *out);
    if (n == 0 || n > 65536) return sidx__fail(err, n ? SIDX_ERR_LIMIT : SIDX_ERR_INVALID_ARG, "city: %u buildings (1 to 65536)", n);
    const unsigned d = detail ? detail : 36u;
    if (d > 256) return sidx__fail(err, SIDX_ERR_LIMIT, "city: detail %u out of range [1, 256]", d);
    out->meshes = calloc(n, sizeof *out->meshes);
    out->instances = calloc(n, sizeof *out->instances);
    if (!out->meshes || !out->instances) {
        sidx_city_free(out);
        return sidx__fail(err, SIDX_ERR_NOMEM, "city: out of memory");
    }
    for (uint32_t i = 0; i < n; ++i) {
        builder b = {0};
        make_building(&b, city_seed(i), d);
        const sidx_status s = builder_finish(&b, "city", &out->meshes[i], err);
        if (s != SIDX_OK) {
            sidx_city_free(out);
            return s;
        }
        out->n = i + 1u;
        out->instances[i].mesh = &out->meshes[i];
        city_place(i, n, out->instances[i].xform);
    }
    /* at eye height in the middle of the first street along z, between the
     * two middle columns, looking down it; the sun high to one side */
    uint32_t cols = 1;
    while (cols * cols < n) ++cols;
    const float street_x = cols > 1 ? 12.0f * (float)(cols % 2u) : 12.0f;
    out->eye = sidx_v3(street_x, 1.7f, -14.0f);
    out->at = sidx_v3(street_x, 6.0f, 86.0f);
    out->light = sidx_v3(street_x + 300.0f, 800.0f, 200.0f);
    return SIDX_OK;
}

void sidx_city_free(sidx_city *c)
{
    if (!c) return;
    for (uint32_t i = 0; c->meshes && i < c->n; ++i) sidx_mesh_free(&c->meshes[i]);
    free(c->meshes);
    free(c->instances);
    memset(c, 0, sizeof *c);
}

/* "city": the buildings of sidx_city_make(detail, 8) flattened into one
 * mesh (world space), for the programs that take one mesh. */
static void make_city(builder *b, unsigned n)
{
    for (uint32_t i = 0; i < n && !b->failed; ++i) {
        builder one = {0};
        make_building(&one, city_seed(i), 8u);
        float m[12];
        city_place(i, n, m);
        const uint32_t base = (uint32_t)b->nv;
        for (size_t v = 0; v < one.nv && !one.failed; ++v) {
            const sidx_vec3 p = one.pos[v];
            vtx(b, m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
                m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
        }
        for (size_t t = 0; t < one.nt && !one.failed; ++t)
            tri(b, base + one.idx[3 * t], base + one.idx[3 * t + 1], base + one.idx[3 * t + 2]);
        b->failed |= one.failed;
        builder_free(&one);
    }
}

/* ---- the table -------------------------------------------------------------------------------- */

typedef struct {
    const char *name;
    unsigned def, min, max; /* detail: default, and the accepted range */
} scene_info;

/* max keeps every scene well under 2^32 triangles and a few GB; cornell
 * has one size and ignores detail.  city's default is one building: the
 * suites that run every built-in scene with every structure stay cheap;
 * city:N asks for more. */
static const scene_info scenes[] = {
    {"icosphere", 3, 0, 10},    {"teapot", 40, 8, 1024},   {"stadium", 128, 8, 65536}, {"soup", 2000, 1, 1u << 26},
    {"menger", 2, 0, 5},        {"flat2d", 16, 1, 100000}, {"cornell", 1, 0, UINT32_MAX},       {"grid", 64, 1, 4096},
    {"kd-slide", 1, 0, UINT32_MAX}, {"city", 1, 1, 4096},     {"heightfield", 32, 1, 8192},
};
#define NUM_SCENES (sizeof scenes / sizeof scenes[0])

const char *const *sidx_scene_names(void)
{
    static const char *const names[NUM_SCENES + 1] = {"icosphere", "teapot",  "stadium", "soup",     "menger",
                                                      "flat2d",    "cornell", "grid",    "kd-slide", "city",
                                                      "heightfield", NULL};
    return names;
}

sidx_status sidx_scene_make(const char *name, uint32_t detail, sidx_mesh *out, sidx_error *err)
{
    if (!name || !out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "scene name or out is NULL");
    const scene_info *si = NULL;
    for (size_t i = 0; i < NUM_SCENES; ++i)
        if (strcmp(scenes[i].name, name) == 0) si = &scenes[i];
    if (!si)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG,
                          "no built-in scene '%s' (try icosphere, teapot, stadium, soup, menger, flat2d, cornell, grid, kd-slide, city, heightfield)",
                          name);
    const unsigned d = detail ? detail : si->def;
    if (d < si->min || d > si->max)
        return sidx__fail(err, d > si->max ? SIDX_ERR_LIMIT : SIDX_ERR_INVALID_ARG,
                          "scene %s: detail %u out of range [%u, %u]", name, d, si->min, si->max);
    builder b = {0};
    switch ((int)(si - scenes)) {
    case 0: make_icosphere(&b, d); break;
    case 1: make_teapot(&b, d, sidx_v3(0, 0, 0), 1.0f); break;
    case 2: make_stadium(&b, d); break;
    case 3: make_soup(&b, d); break;
    case 4: make_menger(&b, d); break;
    case 5: make_flat2d(&b, d); break;
    case 6: make_cornell(&b); break;
    case 8: make_kd_slide(&b); break;
    case 9: make_city(&b, d); break;
    case 10: make_heightfield(&b, d); break;
    default: make_grid(&b, d); break;
    }
    return builder_finish(&b, name, out, err);
}

sidx_status sidx_scene_open(const char *spec, sidx_mesh *out, sidx_error *err)
{
    if (!spec || !out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "scene spec or out is NULL");
    FILE *f = fopen(spec, "rb");
    if (f) {
        fclose(f);
        return sidx_mesh_load(spec, out, err);
    }
    const int open_errno = errno;
    /* "name" or "name:detail" */
    char name[32];
    const char *colon = strchr(spec, ':');
    const size_t n = colon ? (size_t)(colon - spec) : strlen(spec);
    int is_scene = 0;
    for (size_t i = 0; i < NUM_SCENES; ++i)
        if (strlen(scenes[i].name) == n && memcmp(scenes[i].name, spec, n) == 0) is_scene = 1;
    if (!is_scene) {
        /* Looks like a path: report why it could not be opened. */
        if (strchr(spec, '/') || strchr(spec, '.'))
            return sidx__fail(err, SIDX_ERR_IO, "%s: %s", spec, strerror(open_errno));
        return sidx__fail(err, SIDX_ERR_INVALID_ARG,
                          "'%s' is neither a file nor a built-in scene (icosphere, teapot, stadium, soup, menger, "
                          "flat2d, cornell, grid, kd-slide, city, heightfield; optionally name:detail)",
                          spec);
    }
    memcpy(name, spec, n);
    name[n] = '\0';
    uint32_t detail = 0;
    if (colon) {
        const char *p = colon + 1;
        uint64_t v = 0;
        if (*p == '\0') return sidx__fail(err, SIDX_ERR_INVALID_ARG, "'%s': missing detail after ':'", spec);
        for (; *p; ++p) {
            if (*p < '0' || *p > '9' || v > UINT32_MAX)
                return sidx__fail(err, SIDX_ERR_INVALID_ARG, "'%s': detail must be a number up to %lu", spec,
                                  (unsigned long)UINT32_MAX);
            v = v * 10 + (uint64_t)(*p - '0');
        }
        if (v > UINT32_MAX)
            return sidx__fail(err, SIDX_ERR_INVALID_ARG, "'%s': detail must be a number up to %lu", spec,
                              (unsigned long)UINT32_MAX);
        detail = (uint32_t)v;
    }
    return sidx_scene_make(name, detail, out, err);
}

/* Is `spec` the built-in scene `name` ("name" or "name:detail", no such file)? */
static int spec_is_scene(const char *spec, const char *name)
{
    const size_t n = strlen(name);
    if (!spec || strncmp(spec, name, n) != 0 || (spec[n] != '\0' && spec[n] != ':')) return 0;
    FILE *f = fopen(spec, "rb"); /* sidx_scene_open prefers a file of that name */
    if (f) fclose(f);
    return f == NULL;
}

sidx_status sidx_scene_accel_build(const char *scene, const char *name, const sidx_mesh *mesh,
                                   const sidx_build_options *opt, sidx_accel **out, sidx_error *err)
{
    if (name && !strcmp(name, "kdtree") && spec_is_scene(scene, "kd-slide"))
        return sidx_kdtree_build_from_splits(mesh, kd_slide_tree, sizeof kd_slide_tree / sizeof kd_slide_tree[0],
                                             opt, out, err);
    return sidx_accel_build(name, mesh, opt, out, err);
}
