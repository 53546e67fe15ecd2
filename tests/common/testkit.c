/* testkit.c — PRNG, ray/hit files, ray sets, the double-precision
 * reference tracer and the comparison rule (see testkit.h). */
#include "testkit.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* ---- PRNG: splitmix64 seeds xoshiro256** (Blackman & Vigna) ------------- */

uint64_t tk_splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

void tk_rng_seed(tk_rng *r, uint64_t seed)
{
    uint64_t s = seed;
    for (int i = 0; i < 4; ++i) r->s[i] = tk_splitmix64(&s);
}

static uint64_t rotl64(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t tk_rng_next(tk_rng *r)
{
    uint64_t *s = r->s;
    const uint64_t result = rotl64(s[1] * 5u, 7) * 9u;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl64(s[3], 45);
    return result;
}

double tk_rng_unit(tk_rng *r) { return (double)(tk_rng_next(r) >> 11) * 0x1.0p-53; }
double tk_rng_range(tk_rng *r, double lo, double hi) { return lo + (hi - lo) * tk_rng_unit(r); }
uint32_t tk_rng_below(tk_rng *r, uint32_t n) { return (uint32_t)(((tk_rng_next(r) >> 32) * (uint64_t)n) >> 32); }

sidx_vec3 tk_rng_sphere(tk_rng *r)
{
    const double z = tk_rng_range(r, -1.0, 1.0), phi = tk_rng_range(r, 0.0, 6.283185307179586);
    const double s = sqrt(fmax(0.0, 1.0 - z * z));
    return sidx_v3((float)(s * cos(phi)), (float)(s * sin(phi)), (float)z);
}

/* ---- files --------------------------------------------------------------- */

static uint32_t get_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static void put_le32(unsigned char *p, uint32_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
    p[2] = (unsigned char)(v >> 16);
    p[3] = (unsigned char)(v >> 24);
}
static float get_f32(const unsigned char *p)
{
    uint32_t u = get_le32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}
static void put_f32(unsigned char *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_le32(p, u);
}

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
static sidx_status fail(sidx_error *err, sidx_status s, const char *fmt, ...)
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

static sidx_status read_file(const char *path, unsigned char **data, size_t *size, sidx_error *err)
{
    *data = NULL;
    *size = 0;
    if (!path) return fail(err, SIDX_ERR_INVALID_ARG, "%s: no path", "(null)");
    FILE *f = fopen(path, "rb");
    if (!f) {
        if (err) {
            err->status = SIDX_ERR_IO;
            snprintf(err->message, sizeof err->message, "%s: %s", path, strerror(errno));
        }
        return SIDX_ERR_IO;
    }
    size_t cap = 1 << 16, n = 0;
    unsigned char *buf = malloc(cap);
    if (!buf) { fclose(f); return fail(err, SIDX_ERR_NOMEM, "%s: out of memory", path); }
    for (;;) {
        if (n == cap) {
            unsigned char *nb = realloc(buf, cap * 2);
            if (!nb) { free(buf); fclose(f); return fail(err, SIDX_ERR_NOMEM, "%s: out of memory", path); }
            buf = nb;
            cap *= 2;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) break;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) { free(buf); return fail(err, SIDX_ERR_IO, "%s: read error", path); }
    *data = buf;
    *size = n;
    return SIDX_OK;
}

static sidx_status check_size(size_t size, size_t rec, const char *what, sidx_error *err)
{
    if (size % rec != 0)
        return fail(err, SIDX_ERR_PARSE, "%s: size %zu bytes is not a multiple of the %zu-byte record", what, size,
                    rec);
    return SIDX_OK;
}

sidx_status tk_parse_rays(const void *data, size_t size, tk_rayrec **out, size_t *n, sidx_error *err)
{
    if (!out || !n || (size && !data)) return fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", "rays");
    *out = NULL;
    *n = 0;
    sidx_status s = check_size(size, TK_RAY_BYTES, "ray file", err);
    if (s != SIDX_OK) return s;
    const size_t count = size / TK_RAY_BYTES;
    if (count == 0) return SIDX_OK;
    tk_rayrec *r = malloc(count * sizeof *r);
    if (!r) return fail(err, SIDX_ERR_NOMEM, "out of memory for %zu rays", count);
    const unsigned char *p = data;
    for (size_t i = 0; i < count; ++i, p += TK_RAY_BYTES) {
        for (int k = 0; k < 3; ++k) {
            r[i].o[k] = get_f32(p + 4 * k);
            r[i].d[k] = get_f32(p + 12 + 4 * k);
        }
        r[i].tmin = get_f32(p + 24);
        r[i].tmax = get_f32(p + 28);
    }
    *out = r;
    *n = count;
    return SIDX_OK;
}

sidx_status tk_parse_hits(const void *data, size_t size, tk_hitrec **out, size_t *n, sidx_error *err)
{
    if (!out || !n || (size && !data)) return fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", "hits");
    *out = NULL;
    *n = 0;
    sidx_status s = check_size(size, TK_HIT_BYTES, "hit file", err);
    if (s != SIDX_OK) return s;
    const size_t count = size / TK_HIT_BYTES;
    if (count == 0) return SIDX_OK;
    tk_hitrec *h = malloc(count * sizeof *h);
    if (!h) return fail(err, SIDX_ERR_NOMEM, "out of memory for %zu hits", count);
    const unsigned char *p = data;
    for (size_t i = 0; i < count; ++i, p += TK_HIT_BYTES) {
        h[i].t = get_f32(p);
        h[i].prim = (int32_t)get_le32(p + 4);
        h[i].u = get_f32(p + 8);
        h[i].v = get_f32(p + 12);
        /* Refuse records no tracer writes, so a consumer never indexes a
         * mesh with a negative primitive or compares a NaN distance. */
        const char *bad = h[i].prim < -1                                  ? "primitive index below -1"
                          : h[i].prim == -1 && !(isinf(h[i].t) && h[i].t > 0) ? "miss (prim -1) with t != +inf"
                          : h[i].prim >= 0 && isnan(h[i].t)                  ? "hit with t = NaN"
                                                                             : NULL;
        if (bad) {
            free(h);
            return fail(err, SIDX_ERR_PARSE, "hit file: record %zu (byte %zu): %s", i, i * TK_HIT_BYTES, bad);
        }
    }
    *out = h;
    *n = count;
    return SIDX_OK;
}

static sidx_status read_records(const char *path, int rays, void **out, size_t *n, sidx_error *err)
{
    unsigned char *data;
    size_t size;
    if (!out || !n) return fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", path ? path : "?");
    *out = NULL;
    *n = 0;
    sidx_status s = read_file(path, &data, &size, err);
    if (s != SIDX_OK) return s;
    s = check_size(size, rays ? TK_RAY_BYTES : TK_HIT_BYTES, path, err);
    if (s == SIDX_OK)
        s = rays ? tk_parse_rays(data, size, (tk_rayrec **)out, n, err)
                 : tk_parse_hits(data, size, (tk_hitrec **)out, n, err);
    free(data);
    return s;
}

sidx_status tk_read_rays(const char *path, tk_rayrec **out, size_t *n, sidx_error *err)
{
    void *p = NULL;
    sidx_status s = read_records(path, 1, &p, n, err);
    if (out) *out = p;
    return s;
}

sidx_status tk_read_hits(const char *path, tk_hitrec **out, size_t *n, sidx_error *err)
{
    void *p = NULL;
    sidx_status s = read_records(path, 0, &p, n, err);
    if (out) *out = p;
    return s;
}

static sidx_status write_bytes(const char *path, const unsigned char *buf, size_t size, sidx_error *err)
{
    FILE *f = fopen(path, "wb");
    if (!f) {
        if (err) {
            err->status = SIDX_ERR_IO;
            snprintf(err->message, sizeof err->message, "%s: %s", path, strerror(errno));
        }
        return SIDX_ERR_IO;
    }
    size_t w = size ? fwrite(buf, 1, size, f) : 0;
    int bad = (w != size) | (fclose(f) != 0);
    return bad ? fail(err, SIDX_ERR_IO, "%s: write error (%zu of %zu bytes)", path, w, size) : SIDX_OK;
}

sidx_status tk_write_rays(const char *path, const tk_rayrec *r, size_t n, sidx_error *err)
{
    if (!path || (n && !r)) return fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", "rays");
    unsigned char *buf = malloc(n ? n * TK_RAY_BYTES : 1);
    if (!buf) return fail(err, SIDX_ERR_NOMEM, "%s: out of memory", path);
    for (size_t i = 0; i < n; ++i) {
        unsigned char *p = buf + i * TK_RAY_BYTES;
        for (int k = 0; k < 3; ++k) {
            put_f32(p + 4 * k, r[i].o[k]);
            put_f32(p + 12 + 4 * k, r[i].d[k]);
        }
        put_f32(p + 24, r[i].tmin);
        put_f32(p + 28, r[i].tmax);
    }
    sidx_status s = write_bytes(path, buf, n * TK_RAY_BYTES, err);
    free(buf);
    return s;
}

sidx_status tk_write_hits(const char *path, const tk_hitrec *h, size_t n, sidx_error *err)
{
    if (!path || (n && !h)) return fail(err, SIDX_ERR_INVALID_ARG, "%s: NULL argument", "hits");
    unsigned char *buf = malloc(n ? n * TK_HIT_BYTES : 1);
    if (!buf) return fail(err, SIDX_ERR_NOMEM, "%s: out of memory", path);
    for (size_t i = 0; i < n; ++i) {
        unsigned char *p = buf + i * TK_HIT_BYTES;
        put_f32(p, h[i].t);
        put_le32(p + 4, (uint32_t)h[i].prim);
        put_f32(p + 8, h[i].u);
        put_f32(p + 12, h[i].v);
    }
    sidx_status s = write_bytes(path, buf, n * TK_HIT_BYTES, err);
    free(buf);
    return s;
}

tk_hitrec tk_hitrec_from(const sidx_hit *h)
{
    tk_hitrec r = {INFINITY, -1, 0.0f, 0.0f};
    if (h && h->prim != SIDX_NO_HIT) {
        r.t = h->t;
        r.prim = (int32_t)h->prim;
        r.u = h->u;
        r.v = h->v;
    }
    return r;
}

tk_rayrec tk_rayrec_make(sidx_vec3 o, sidx_vec3 d, float tmin, float tmax)
{
    tk_rayrec r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, tmin, tmax};
    return r;
}

sidx_status tk_ray_from(const tk_rayrec *rec, sidx_ray *r)
{
    return sidx_ray_init(r, sidx_v3(rec->o[0], rec->o[1], rec->o[2]), sidx_v3(rec->d[0], rec->d[1], rec->d[2]),
                         rec->tmin, rec->tmax);
}

int tk_hit_at_start(const sidx_hit *h, const sidx_ray *r, float scale)
{
    if (h->prim == SIDX_NO_HIT) return 0;
    const float dmax = fmaxf(fabsf(r->dir.x), fmaxf(fabsf(r->dir.y), fabsf(r->dir.z)));
    const float omax = fmaxf(fabsf(r->org.x), fmaxf(fabsf(r->org.y), fabsf(r->org.z)));
    return h->t * dmax <= 0x1p-20f * (omax + scale);
}

/* ---- ray sets -------------------------------------------------------------- */

static const char *const kind_names[TK_RAYS_KIND_COUNT] = {"primary", "diffuse", "shadow", "grazing", "axis"};

const char *tk_ray_kind_name(tk_ray_kind k) { return (unsigned)k < TK_RAYS_KIND_COUNT ? kind_names[k] : NULL; }

int tk_ray_kind_parse(const char *name, tk_ray_kind *out)
{
    for (int k = 0; name && k < TK_RAYS_KIND_COUNT; ++k)
        if (strcmp(name, kind_names[k]) == 0) {
            if (out) *out = (tk_ray_kind)k;
            return 1;
        }
    return 0;
}

typedef struct scene_frame {
    sidx_aabb box;
    sidx_vec3 c;  /* centre */
    float radius; /* half diagonal, > 0 */
} scene_frame;

static scene_frame frame_of(const sidx_mesh *m)
{
    scene_frame f;
    f.box = m->num_triangles ? sidx_mesh_bounds(m) : sidx_aabb_empty();
    if (sidx_aabb_is_empty(f.box)) f.box = (sidx_aabb){{-1, -1, -1}, {1, 1, 1}};
    f.c = sidx_aabb_centroid(f.box);
    f.radius = 0.5f * sidx_v3_length(sidx_aabb_extent(f.box));
    if (!(f.radius > 0.0f)) f.radius = fmaxf(1e-3f, fabsf(f.c.x) + fabsf(f.c.y) + fabsf(f.c.z)) * 1e-3f;
    return f;
}

static sidx_vec3 v3_normalize(sidx_vec3 v)
{
    const double l = sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z);
    return l > 0 ? sidx_v3((float)(v.x / l), (float)(v.y / l), (float)(v.z / l)) : v;
}

/* Every draw from the generator is a statement of its own: the order in
 * which a function's arguments are evaluated is unspecified in C (gcc on
 * x86-64 goes right to left, clang left to right), so two draws in one
 * argument list gave each compiler different rays.  The draws run in the
 * order gcc ran them, so the rays every recorded figure was measured on
 * are unchanged. */
sidx_vec3 tk_rng_in_box(tk_rng *g, sidx_aabb b)
{
    const float z = (float)tk_rng_range(g, b.min.z, b.max.z);
    const float y = (float)tk_rng_range(g, b.min.y, b.max.y);
    const float x = (float)tk_rng_range(g, b.min.x, b.max.x);
    return sidx_v3(x, y, z);
}

/* Cumulative triangle areas, for area-uniform surface points. */
static double *area_cdf(const sidx_mesh *m)
{
    double *cdf = malloc((m->num_triangles ? m->num_triangles : 1) * sizeof *cdf);
    if (!cdf) return NULL;
    double acc = 0;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        const sidx_vec3 a = sidx_mesh_vertex(m, i, 0), b = sidx_mesh_vertex(m, i, 1), c = sidx_mesh_vertex(m, i, 2);
        const double e1[3] = {(double)b.x - a.x, (double)b.y - a.y, (double)b.z - a.z};
        const double e2[3] = {(double)c.x - a.x, (double)c.y - a.y, (double)c.z - a.z};
        const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                             e1[0] * e2[1] - e1[1] * e2[0]};
        acc += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        cdf[i] = acc;
    }
    return cdf;
}

static uint32_t pick_triangle(tk_rng *g, const sidx_mesh *m, const double *cdf)
{
    const uint32_t n = m->num_triangles;
    if (!cdf || !(cdf[n - 1] > 0)) return tk_rng_below(g, n);
    const double x = tk_rng_unit(g) * cdf[n - 1];
    uint32_t lo = 0, hi = n - 1;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (cdf[mid] > x) hi = mid; else lo = mid + 1;
    }
    return lo;
}

static sidx_vec3 point_in_triangle(tk_rng *g, const sidx_mesh *m, uint32_t t)
{
    const sidx_vec3 a = sidx_mesh_vertex(m, t, 0), b = sidx_mesh_vertex(m, t, 1), c = sidx_mesh_vertex(m, t, 2);
    const double r1 = sqrt(tk_rng_unit(g)), r2 = tk_rng_unit(g);
    const double wa = 1 - r1, wb = r1 * (1 - r2), wc = r1 * r2;
    return sidx_v3((float)(wa * a.x + wb * b.x + wc * c.x), (float)(wa * a.y + wb * b.y + wc * c.y),
                   (float)(wa * a.z + wb * b.z + wc * c.z));
}

static int is_zero(sidx_vec3 v) { return v.x == 0.0f && v.y == 0.0f && v.z == 0.0f; }

static sidx_vec3 edge_midpoint(const sidx_mesh *m, uint32_t t, int e)
{
    const sidx_vec3 a = sidx_mesh_vertex(m, t, e), b = sidx_mesh_vertex(m, t, (e + 1) % 3);
    return sidx_v3_scale(sidx_v3_add(a, b), 0.5f);
}

static tk_rayrec diffuse_ray(tk_rng *g, const scene_frame *f)
{
    const sidx_vec3 d = sidx_v3_scale(tk_rng_sphere(g), f->radius); /* drawn before the origin: see tk_rng_in_box */
    return tk_rayrec_make(tk_rng_in_box(g, f->box), d, 0.0f, INFINITY);
}

/* A ray from a random origin (half outside the bounding sphere, half in
 * the box) through `target` exactly: t = 1 at the target. */
static tk_rayrec aimed_ray(tk_rng *g, const scene_frame *f, sidx_vec3 target)
{
    for (int tries = 0; tries < 8; ++tries) {
        sidx_vec3 o = (tk_rng_next(g) & 1) ? sidx_v3_add(f->c, sidx_v3_scale(tk_rng_sphere(g), 2.0f * f->radius))
                                           : tk_rng_in_box(g, f->box);
        sidx_vec3 d = sidx_v3_sub(target, o);
        if (!is_zero(d) && sidx_v3_isfinite(d)) return tk_rayrec_make(o, d, 0.0f, INFINITY);
    }
    return diffuse_ray(g, f);
}

static tk_rayrec grazing_ray(tk_rng *g, const sidx_mesh *m, const scene_frame *f)
{
    const uint32_t t = tk_rng_below(g, m->num_triangles);
    const double sel = tk_rng_unit(g);
    if (sel < 0.35) return aimed_ray(g, f, sidx_mesh_vertex(m, t, (int)tk_rng_below(g, 3)));
    if (sel < 0.70) return aimed_ray(g, f, edge_midpoint(m, t, (int)tk_rng_below(g, 3)));
    /* Nearly parallel to the triangle's plane, through a point inside it. */
    const sidx_vec3 a = sidx_mesh_vertex(m, t, 0), b = sidx_mesh_vertex(m, t, 1), c = sidx_mesh_vertex(m, t, 2);
    const sidx_vec3 e1 = sidx_v3_sub(b, a), e2 = sidx_v3_sub(c, a);
    const sidx_vec3 n = sidx_v3_cross(e1, e2);
    if (is_zero(n) || !sidx_v3_isfinite(n)) return aimed_ray(g, f, a);
    const double w1 = tk_rng_range(g, -1, 1), w2 = tk_rng_range(g, -1, 1);
    sidx_vec3 in_plane = v3_normalize(sidx_v3_add(sidx_v3_scale(e1, (float)w1), sidx_v3_scale(e2, (float)w2)));
    if (is_zero(in_plane)) in_plane = v3_normalize(e1);
    static const float tilts[4] = {1e-2f, 1e-4f, 1e-6f, 0.0f};
    const float tilt = tilts[tk_rng_below(g, 4)] * ((tk_rng_next(g) & 1) ? 1.0f : -1.0f);
    sidx_vec3 d = sidx_v3_add(in_plane, sidx_v3_scale(v3_normalize(n), tilt));
    d = sidx_v3_scale(d, f->radius);
    const sidx_vec3 p = point_in_triangle(g, m, t);
    const sidx_vec3 o = sidx_v3_sub(p, d);
    if (is_zero(d)) return aimed_ray(g, f, p);
    return tk_rayrec_make(o, d, 0.0f, INFINITY);
}

static tk_rayrec axis_ray(tk_rng *g, const sidx_mesh *m, const scene_frame *f)
{
    const int axis = (int)tk_rng_below(g, 3);
    const int neg = (int)(tk_rng_next(g) & 1);
    float d[3], o[3];
    for (int k = 0; k < 3; ++k) d[k] = (tk_rng_next(g) & 1) ? -0.0f : 0.0f;
    d[axis] = neg ? -f->radius : f->radius;
    if ((tk_rng_next(g) & 1) || m->num_triangles == 0) {
        const sidx_vec3 p = tk_rng_in_box(g, f->box);
        o[0] = p.x; o[1] = p.y; o[2] = p.z;
    } else {
        /* Through a vertex or an edge midpoint exactly, from outside the box. */
        const uint32_t t = tk_rng_below(g, m->num_triangles);
        const int e = (int)tk_rng_below(g, 3);
        const sidx_vec3 p = (tk_rng_next(g) & 1) ? sidx_mesh_vertex(m, t, e) : edge_midpoint(m, t, e);
        o[0] = p.x; o[1] = p.y; o[2] = p.z;
        const float lo = sidx_v3_get(f->box.min, axis), hi = sidx_v3_get(f->box.max, axis);
        o[axis] = neg ? hi + 0.5f * f->radius : lo - 0.5f * f->radius;
    }
    return tk_rayrec_make(sidx_v3(o[0], o[1], o[2]), sidx_v3(d[0], d[1], d[2]), 0.0f, INFINITY);
}

void tk_make_rays(const sidx_mesh *m, tk_ray_kind kind, size_t count, uint64_t seed, tk_rayrec *out)
{
    tk_rng g;
    tk_rng_seed(&g, seed ^ ((uint64_t)kind << 56));
    const scene_frame f = frame_of(m);
    if (m->num_triangles == 0 && kind != TK_RAYS_PRIMARY) kind = TK_RAYS_DIFFUSE;
    if (kind == TK_RAYS_PRIMARY) {
        size_t w = (size_t)ceil(sqrt((double)count));
        if (w == 0) w = 1;
        const size_t h = (count + w - 1) / w;
        const sidx_vec3 view = v3_normalize(sidx_v3(0.45f, 0.35f, 1.0f));
        const sidx_vec3 eye = sidx_v3_add(f.c, sidx_v3_scale(view, 2.5f * f.radius));
        const sidx_vec3 fwd = sidx_v3_scale(view, -1.0f);
        const sidx_vec3 right = v3_normalize(sidx_v3_cross(fwd, sidx_v3(0, 1, 0)));
        const sidx_vec3 up = sidx_v3_cross(right, fwd);
        const double tan_half = 0.44;
        for (size_t i = 0; i < count; ++i) {
            const size_t px = i % w, py = i / w;
            const double x = ((px + 0.5) / (double)w * 2.0 - 1.0) * tan_half;
            const double y = (1.0 - (py + 0.5) / (double)h * 2.0) * tan_half;
            sidx_vec3 d = sidx_v3_add(fwd, sidx_v3_add(sidx_v3_scale(right, (float)x), sidx_v3_scale(up, (float)y)));
            out[i] = tk_rayrec_make(eye, sidx_v3_scale(d, f.radius), 0.0f, INFINITY);
        }
        return;
    }
    double *cdf = kind == TK_RAYS_SHADOW ? area_cdf(m) : NULL;
    for (size_t i = 0; i < count; ++i) {
        switch (kind) {
        case TK_RAYS_SHADOW: {
            const float eps = 1e-3f;
            tk_rayrec r = diffuse_ray(&g, &f);
            for (int tries = 0; tries < 8; ++tries) {
                const sidx_vec3 p1 = point_in_triangle(&g, m, pick_triangle(&g, m, cdf));
                const sidx_vec3 p2 = point_in_triangle(&g, m, pick_triangle(&g, m, cdf));
                const sidx_vec3 d = sidx_v3_sub(p2, p1);
                if (!is_zero(d) && sidx_v3_isfinite(d)) {
                    r = tk_rayrec_make(p1, d, eps, 1.0f - eps);
                    break;
                }
            }
            out[i] = r;
            break;
        }
        case TK_RAYS_GRAZING: out[i] = grazing_ray(&g, m, &f); break;
        case TK_RAYS_AXIS: out[i] = axis_ray(&g, m, &f); break;
        default: out[i] = diffuse_ray(&g, &f); break;
        }
    }
    free(cdf);
}

size_t tk_make_leak_rays(const sidx_mesh *m, sidx_vec3 inside, size_t max, tk_rayrec *out)
{
    size_t n = 0;
    for (uint32_t t = 0; t < m->num_triangles && n < max; ++t)
        for (int e = 0; e < 3 && n < max; ++e) {
            const sidx_vec3 targets[2] = {edge_midpoint(m, t, e), sidx_mesh_vertex(m, t, e)};
            for (int k = 0; k < 2 && n < max; ++k) {
                const sidx_vec3 d = sidx_v3_sub(targets[k], inside);
                if (!is_zero(d)) out[n++] = tk_rayrec_make(inside, d, 0.0f, INFINITY);
            }
        }
    return n;
}

/* ---- reference ----------------------------------------------------------- */

void tk_ref_intersect(const sidx_mesh *m, const tk_rayrec *ray, sidx_hit *out)
{
    *out = sidx_hit_none();
    const double o[3] = {ray->o[0], ray->o[1], ray->o[2]};
    const double d[3] = {ray->d[0], ray->d[1], ray->d[2]};
    int kz = 0;
    if (fabs(d[1]) > fabs(d[kz])) kz = 1;
    if (fabs(d[2]) > fabs(d[kz])) kz = 2;
    if (d[kz] == 0.0) return;
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if (d[kz] < 0.0) { int tmp = kx; kx = ky; ky = tmp; }
    const double sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1.0 / d[kz];
    const double tmin = ray->tmin;
    double best = ray->tmax;
    if (!(tmin <= best)) return;
    for (uint32_t i = 0; i < m->num_triangles; ++i) {
        const uint32_t *ix = m->indices + 3u * i;
        const float *pa = sidx_v3_array(&m->positions[ix[0]]), *pb = sidx_v3_array(&m->positions[ix[1]]), *pc = sidx_v3_array(&m->positions[ix[2]]);
        const double az = pa[kz] - o[kz], bz = pb[kz] - o[kz], cz = pc[kz] - o[kz];
        const double Ax = (pa[kx] - o[kx]) - sx * az, Ay = (pa[ky] - o[ky]) - sy * az;
        const double Bx = (pb[kx] - o[kx]) - sx * bz, By = (pb[ky] - o[ky]) - sy * bz;
        const double Cx = (pc[kx] - o[kx]) - sx * cz, Cy = (pc[ky] - o[ky]) - sy * cz;
        const double U = Cx * By - Cy * Bx, V = Ax * Cy - Ay * Cx, W = Bx * Ay - By * Ax;
        if ((U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0)) continue;
        const double det = U + V + W;
        if (det == 0.0) continue;
        const double t = (U * az + V * bz + W * cz) * sz / det;
        if (!(t >= tmin && t < best)) continue;
        best = t;
        out->t = (float)t;
        out->prim = i;
        out->u = (float)(V / det);
        out->v = (float)(W / det);
    }
    if (out->prim != SIDX_NO_HIT) out->instance = SIDX_NO_HIT;
}

typedef struct ref_job {
    const sidx_mesh *m;
    const tk_rayrec *rays;
    sidx_hit *out;
    size_t begin, end;
} ref_job;

static void *ref_worker(void *p)
{
    ref_job *j = p;
    for (size_t i = j->begin; i < j->end; ++i) tk_ref_intersect(j->m, &j->rays[i], &j->out[i]);
    return NULL;
}

void tk_ref_intersect_all(const sidx_mesh *m, const tk_rayrec *rays, size_t n, sidx_hit *out, unsigned threads)
{
    if (threads < 1) threads = 1;
    if (threads > 64) threads = 64;
    ref_job jobs[64] = {0};
    pthread_t tid[64];
    int started[64] = {0};
    for (unsigned t = 0; t < threads; ++t) {
        jobs[t] = (ref_job){m, rays, out, n * t / threads, n * (t + 1) / threads};
        if (t > 0) started[t] = pthread_create(&tid[t], NULL, ref_worker, &jobs[t]) == 0;
    }
    ref_worker(&jobs[0]);
    for (unsigned t = 1; t < threads; ++t) {
        if (started[t]) pthread_join(tid[t], NULL);
        else ref_worker(&jobs[t]);
    }
}

/* ---- comparison -------------------------------------------------------------- */

int tk_hits_agree_scaled(const sidx_hit *ref, const sidx_hit *got, double t_floor)
{
    const int rh = ref->prim != SIDX_NO_HIT, gh = got->prim != SIDX_NO_HIT;
    if (rh != gh) return 0;
    if (!rh) return 1;
    if (ref->prim == got->prim) return 1;
    return fabs((double)got->t - (double)ref->t) <= TK_T_TOL * fmax(t_floor, fabs((double)ref->t));
}

int tk_hits_agree(const sidx_hit *ref, const sidx_hit *got) { return tk_hits_agree_scaled(ref, got, 1.0); }

void tk_errstats_add(tk_errstats *e, const sidx_hit *ref, const sidx_hit *got)
{
    e->rays++;
    const int rh = ref->prim != SIDX_NO_HIT, gh = got->prim != SIDX_NO_HIT;
    if (rh && !gh) e->false_miss++;
    else if (!rh && gh) e->false_hit++;
    else if (rh && gh) {
        if (!tk_hits_agree(ref, got)) e->wrong_prim++;
        if (ref->prim == got->prim) {
            const double rel = fabs((double)got->t - (double)ref->t) / fmax(fabs((double)ref->t), 1.0);
            if (rel > e->max_rel_t) e->max_rel_t = rel;
        }
    }
}

uint64_t tk_errstats_errors(const tk_errstats *e) { return e->false_miss + e->false_hit + e->wrong_prim; }
double tk_errstats_rate(const tk_errstats *e) { return e->rays ? (double)tk_errstats_errors(e) / (double)e->rays : 0.0; }

/* ---- meshes ----------------------------------------------------------------- */

static sidx_status mesh_with_positions(const float *xyz, uint32_t nv, const uint32_t *idx, uint32_t nt,
                                       sidx_mesh *out)
{
    memset(out, 0, sizeof *out);
    return sidx_mesh_from_arrays(out, xyz, nv, idx, nt, NULL);
}

sidx_status tk_mesh_transform(const sidx_mesh *m, double scale, sidx_vec3 offset, sidx_mesh *out)
{
    float *xyz = malloc(3 * (size_t)(m->num_vertices ? m->num_vertices : 1) * sizeof *xyz);
    if (!xyz) return SIDX_ERR_NOMEM;
    for (uint32_t i = 0; i < m->num_vertices; ++i) {
        xyz[3 * i + 0] = (float)(m->positions[i].x * scale + offset.x);
        xyz[3 * i + 1] = (float)(m->positions[i].y * scale + offset.y);
        xyz[3 * i + 2] = (float)(m->positions[i].z * scale + offset.z);
    }
    sidx_status s = mesh_with_positions(xyz, m->num_vertices, m->indices, m->num_triangles, out);
    free(xyz);
    return s;
}

sidx_status tk_mesh_duplicate_tris(const sidx_mesh *m, sidx_mesh *out)
{
    const size_t nt = m->num_triangles;
    uint32_t *idx = malloc(6 * (nt ? nt : 1) * sizeof *idx);
    if (!idx) return SIDX_ERR_NOMEM;
    memcpy(idx, m->indices, 3 * nt * sizeof *idx);
    memcpy(idx + 3 * nt, m->indices, 3 * nt * sizeof *idx);
    sidx_status s = mesh_with_positions(m->num_vertices ? sidx_v3_array(&m->positions[0]) : NULL, m->num_vertices, idx, (uint32_t)(2 * nt), out);
    free(idx);
    return s;
}

sidx_status tk_mesh_flatten(const sidx_mesh *m, float z0, sidx_mesh *out)
{
    float *xyz = malloc(3 * (size_t)(m->num_vertices ? m->num_vertices : 1) * sizeof *xyz);
    if (!xyz) return SIDX_ERR_NOMEM;
    for (uint32_t i = 0; i < m->num_vertices; ++i) {
        xyz[3 * i + 0] = m->positions[i].x;
        xyz[3 * i + 1] = m->positions[i].y;
        xyz[3 * i + 2] = z0;
    }
    sidx_status s = mesh_with_positions(xyz, m->num_vertices, m->indices, m->num_triangles, out);
    free(xyz);
    return s;
}

int tk_fast_tests(void)
{
    const char *e = getenv("SIDX_FAST_TESTS");
    return e && *e && strcmp(e, "0") != 0;
}

int tk_tiny_tests(void)
{
    const char *e = getenv("SIDX_FAST_TESTS");
    return e && strcmp(e, "2") == 0;
}

int tk_under_valgrind(void)
{
    const char *e = getenv("LD_PRELOAD");
    return e && strstr(e, "vgpreload") != NULL;
}

size_t tk_test_size(size_t full)
{
    const size_t part = tk_tiny_tests() ? 16 : tk_fast_tests() ? 4 : 1;
    return (full + part - 1) / part; /* rounded up: 1 or more when full is */
}

double tk_thread_cpu_ms(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return tk_now_ms();
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

double tk_process_cpu_ms(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) return tk_now_ms();
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

double tk_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* ---- failing allocator ------------------------------------------------- */

static void *tk_fail_alloc(size_t size, void *user)
{
    tk_failing *f = user;
    if (f->left-- <= 0) return NULL;
    f->live++;
    return malloc(size);
}

static void tk_fail_free(void *p, void *user)
{
    tk_failing *f = user;
    if (p) f->live--;
    free(p);
}

sidx_allocator tk_failing_allocator(tk_failing *f)
{
    sidx_allocator al = {tk_fail_alloc, tk_fail_free, f};
    return al;
}

char *tk_read_all(FILE *f)
{
    size_t cap = 4096, n = 0, k;
    char *buf = malloc(cap);
    if (!buf) return NULL;
    while ((k = fread(buf + n, 1, cap - n - 1, f)) > 0) {
        n += k;
        if (cap - n < 2) {
            char *grown = realloc(buf, cap * 2);
            if (!grown) {
                free(buf);
                return NULL;
            }
            buf = grown;
            cap *= 2;
        }
    }
    buf[n] = '\0';
    return buf;
}

void tk_bin_dir(const char *argv0, char *out, size_t size)
{
    if (!argv0 || !strchr(argv0, '/')) return;
    snprintf(out, size, "%s", argv0);
    char *slash = strrchr(out, '/');
    *slash = '\0';
    slash = strrchr(out, '/');
    if (slash)
        snprintf(slash + 1, size - (size_t)(slash + 1 - out), "bin");
    else
        snprintf(out, size, "bin");
}

/* ---- threads racing into one structure ------------------------------------ */

typedef struct tk_racer {
    const sidx_accel *a;
    const sidx_ray *rays;
    size_t n;
    sidx_hit *hits;
    pthread_barrier_t *start;
    sidx_status st;
} tk_racer;

static void *tk_race(void *arg)
{
    tk_racer *r = arg;
    pthread_barrier_wait(r->start);
    r->st = SIDX_OK;
    for (size_t i = 0; i < r->n; ++i) {
        const sidx_status st = sidx_accel_intersect(r->a, &r->rays[i], NULL, &r->hits[i]);
        if (st != SIDX_OK && r->st == SIDX_OK) r->st = st;
    }
    return NULL;
}

sidx_status tk_race_intersect(const sidx_accel *a, const sidx_ray *rays, size_t n, unsigned threads, sidx_hit *hits)
{
    enum { MAX_RACERS = 64 };
    if (threads == 0 || threads > MAX_RACERS) return SIDX_ERR_INVALID_ARG;
    pthread_barrier_t start;
    pthread_barrier_init(&start, NULL, threads);
    pthread_t th[MAX_RACERS];
    tk_racer rc[MAX_RACERS];
    sidx_status st = SIDX_OK;
    unsigned started = 0;
    for (unsigned t = 0; t < threads; ++t) {
        rc[t] = (tk_racer){a, rays, n, hits + (size_t)t * n, &start, SIDX_ERR_NOMEM};
        if (pthread_create(&th[t], NULL, tk_race, &rc[t]) != 0) break;
        ++started;
    }
    if (started < threads) {
        /* the barrier waits for `threads`: without them, nobody may start */
        fprintf(stderr, "tk_race_intersect: only %u of %u threads started\n", started, threads);
        abort();
    }
    for (unsigned t = 0; t < threads; ++t) pthread_join(th[t], NULL);
    pthread_barrier_destroy(&start);
    for (unsigned t = 0; t < threads; ++t)
        if (rc[t].st != SIDX_OK && st == SIDX_OK) st = rc[t].st;
    return st;
}
