/* lightbuffer.c — Haines & Greenberg's light buffer (1986): a direction
 * cube around a point light whose cells list the possible occluders, the
 * deck's "variation" of directional partitioning for shadow rays.
 *
 * Build (always): every triangle is clipped, in light-centred coordinates,
 * against each face's pyramid (|a| <= w, |b| <= w, w = ±x_k > 0) and the
 * clipped polygon is projected (u = a/w, v = b/w).  The bounding rectangle
 * of the projection, widened by a small margin, gives the range of cells
 * the triangle can be seen through — conservative, as the deck asks,
 * because the projection of a convex polygon lies inside the box of its
 * projected vertices.  A triangle that passes through the light covers
 * the whole face.  Per face, these (triangle, rectangle) entries are kept
 * sorted by the triangle's exact distance from the light.
 *
 * Cells: eagerly, every rectangle is scattered into its cells now; lazily
 * (the deck: "lazy and conservative evaluation"), a cell's list is made on
 * the first query that lands in it, by scanning its face's entries.  Both
 * produce the same lists, sorted by distance from the light.
 *
 * Query for a point p: cell of the direction p − light; then
 *   1. the cell's last found occluder, if any (the deck: "store last found
 *      occluder in directional structure; test entry first for next shadow
 *      test") — neighbouring shadow rays tend to be blocked by the same
 *      triangle;
 *   2. the list, nearest to the light first, until a triangle's distance
 *      from the light exceeds that of the farthest point of the shadow
 *      segment from it: nothing beyond can lie between p and the light.
 * Correct for any p because every point of the segment p → light has the
 * same direction from the light as p, i.e. lies in the same cell. */
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include "sidx_internal.h"
#include "sidx/lightbuffer.h"

#define SIDX_STRUCTURE_NAME "lightbuffer"

#define LB_DEFAULT_RES 32u
#define LB_MAX_RES 1024u
/* Widening of each face pyramid and of each rectangle (in face units,
 * [-1, 1] across a face): far above the rounding of the float cell lookup
 * (~1e-7) and of the clipping (double), so a direction on a cell or face
 * border finds the triangle on either side. */
#define LB_PYRAMID_WIDEN 1e-5
#define LB_RECT_MARGIN 1e-5

typedef struct lb_entry {
    double dist;            /* distance from the light to the triangle (exact, double) */
    uint32_t tri;
    uint16_t i0, i1, j0, j1; /* cell rectangle, inclusive */
} lb_entry;

typedef struct lb_cell {
    atomic_int ready;       /* 0: not filled yet; 1: list and count are valid (release/acquire) */
    uint32_t count;
    uint32_t *tris;         /* sorted by distance from the light */
    float *dist;
} lb_cell;

struct sidx_lightbuffer {
    sidx_accel base;        /* holds mesh, allocator, triangle method (not registered) */
    sidx_vec3 light;
    uint32_t res, cells_total;
    int eager;
    lb_entry *entries[6];   /* per face, sorted by dist */
    uint32_t num_entries[6];
    lb_cell *cells;
    uint32_t *eager_tris;   /* eager mode: one block for all lists */
    float *eager_dist;
    pthread_mutex_t fill_lock;
    atomic_uint cells_filled;
    atomic_ullong refs;
};

/* ---- geometry ------------------------------------------------------------ */

/* Axis k of face f and its two in-face axes (a, b): faces are +x, -x, +y, -y, +z, -z. */
static void face_axes(int f, int *k, int *a, int *b, double *sign)
{
    *k = f >> 1;
    *sign = (f & 1) ? -1.0 : 1.0;
    *a = (*k + 1) % 3;
    *b = (*k + 2) % 3;
}

/* Distance from point p to triangle (a, b, c): closest point by Voronoi
 * regions (Ericson, Real-Time Collision Detection, 5.1.5), in double. */
static double point_triangle_dist(const double p[3], const double a[3], const double b[3], const double c[3])
{
    double ab[3], ac[3], ap[3], q[3];
    for (int i = 0; i < 3; ++i) { ab[i] = b[i] - a[i]; ac[i] = c[i] - a[i]; ap[i] = p[i] - a[i]; }
#define DOT(x, y) ((x)[0] * (y)[0] + (x)[1] * (y)[1] + (x)[2] * (y)[2])
    const double d1 = DOT(ab, ap), d2 = DOT(ac, ap);
    if (d1 <= 0 && d2 <= 0) { for (int i = 0; i < 3; ++i) q[i] = a[i]; goto done; }
    double bp[3];
    for (int i = 0; i < 3; ++i) bp[i] = p[i] - b[i];
    const double d3 = DOT(ab, bp), d4 = DOT(ac, bp);
    if (d3 >= 0 && d4 <= d3) { for (int i = 0; i < 3; ++i) q[i] = b[i]; goto done; }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        for (int i = 0; i < 3; ++i) q[i] = a[i] + v * ab[i];
        goto done;
    }
    double cp[3];
    for (int i = 0; i < 3; ++i) cp[i] = p[i] - c[i];
    const double d5 = DOT(ab, cp), d6 = DOT(ac, cp);
    if (d6 >= 0 && d5 <= d6) { for (int i = 0; i < 3; ++i) q[i] = c[i]; goto done; }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        for (int i = 0; i < 3; ++i) q[i] = a[i] + w * ac[i];
        goto done;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int i = 0; i < 3; ++i) q[i] = b[i] + w * (c[i] - b[i]);
        goto done;
    }
    {
        const double den = va + vb + vc;
        if (den == 0.0) { for (int i = 0; i < 3; ++i) q[i] = a[i]; goto done; } /* degenerate */
        const double v = vb / den, w = vc / den;
        for (int i = 0; i < 3; ++i) q[i] = a[i] + ab[i] * v + ac[i] * w;
    }
done:;
    double d[3];
    for (int i = 0; i < 3; ++i) d[i] = p[i] - q[i];
    return sqrt(DOT(d, d));
#undef DOT
}

/* Clip polygon (x[], n) against a·x >= 0 (a plane through the light). */
static int clip_half(double (*in)[3], int n, double (*out)[3], const double pl[3])
{
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const double *p = in[i], *q = in[(i + 1) % n];
        const double dp = pl[0] * p[0] + pl[1] * p[1] + pl[2] * p[2];
        const double dq = pl[0] * q[0] + pl[1] * q[1] + pl[2] * q[2];
        if (dp >= 0) { for (int k = 0; k < 3; ++k) out[m][k] = p[k]; ++m; }
        if ((dp >= 0) != (dq >= 0)) {
            const double s = dp / (dp - dq);
            for (int k = 0; k < 3; ++k) out[m][k] = p[k] + s * (q[k] - p[k]);
            ++m;
        }
    }
    return m;
}

/* Cell rectangle of triangle v[3] (light-relative) on face f; 0 if the
 * triangle cannot be seen through that face. */
static int face_rect(const double v[3][3], int f, uint32_t res, lb_entry *e)
{
    int k, a, b;
    double s;
    face_axes(f, &k, &a, &b, &s);
    double buf0[8][3], buf1[8][3];
    int n = 3;
    for (int i = 0; i < 3; ++i) for (int c = 0; c < 3; ++c) buf0[i][c] = v[i][c];
    /* pyramid of the face: (1+δ)·w ± x_a >= 0, (1+δ)·w ± x_b >= 0 with w = s·x_k */
    const double wk = s * (1.0 + LB_PYRAMID_WIDEN);
    double planes[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    planes[0][k] = wk; planes[0][a] = 1;
    planes[1][k] = wk; planes[1][a] = -1;
    planes[2][k] = wk; planes[2][b] = 1;
    planes[3][k] = wk; planes[3][b] = -1;
    double (*in)[3] = buf0, (*out)[3] = buf1;
    for (int p = 0; p < 4 && n > 0; ++p) {
        n = clip_half(in, n, out, planes[p]);
        double (*tmp)[3] = in; in = out; out = tmp;
    }
    if (n == 0) return 0;
    double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
    for (int i = 0; i < n; ++i) {
        const double w = s * in[i][k];
        double u, vv;
        if (!(w > 0.0)) { u0 = v0 = -1.0; u1 = v1 = 1.0; break; } /* passes through the light: whole face */
        u = in[i][a] / w;
        vv = in[i][b] / w;
        if (u < u0) u0 = u;
        if (u > u1) u1 = u;
        if (vv < v0) v0 = vv;
        if (vv > v1) v1 = vv;
    }
    const double scale = 0.5 * res;
    double fi0 = floor((u0 + 1.0 - LB_RECT_MARGIN) * scale), fi1 = floor((u1 + 1.0 + LB_RECT_MARGIN) * scale);
    double fj0 = floor((v0 + 1.0 - LB_RECT_MARGIN) * scale), fj1 = floor((v1 + 1.0 + LB_RECT_MARGIN) * scale);
    const double hi = (double)res - 1.0;
    fi0 = fi0 < 0 ? 0 : fi0 > hi ? hi : fi0;
    fi1 = fi1 < 0 ? 0 : fi1 > hi ? hi : fi1;
    fj0 = fj0 < 0 ? 0 : fj0 > hi ? hi : fj0;
    fj1 = fj1 < 0 ? 0 : fj1 > hi ? hi : fj1;
    e->i0 = (uint16_t)fi0; e->i1 = (uint16_t)fi1;
    e->j0 = (uint16_t)fj0; e->j1 = (uint16_t)fj1;
    return 1;
}

/* Cell of direction d (from the light); returns the cell id. */
static uint32_t cell_of(const sidx_lightbuffer *lb, sidx_vec3 d, int *face, int *ci, int *cj)
{
    const float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
    int k = 0;
    if (ay > ax) k = 1;
    if (az > (k == 0 ? ax : ay)) k = 2;
    const float dk = sidx_v3_get(d, k);
    const int f = 2 * k + (dk < 0.0f ? 1 : 0);
    const float w = fabsf(dk);
    const float u = sidx_v3_get(d, (k + 1) % 3) / w, v = sidx_v3_get(d, (k + 2) % 3) / w;
    const float scale = 0.5f * (float)lb->res;
    int i = (int)floorf((u + 1.0f) * scale), j = (int)floorf((v + 1.0f) * scale);
    const int hi = (int)lb->res - 1;
    i = i < 0 ? 0 : i > hi ? hi : i;
    j = j < 0 ? 0 : j > hi ? hi : j;
    *face = f; *ci = i; *cj = j;
    return ((uint32_t)f * lb->res + (uint32_t)j) * lb->res + (uint32_t)i;
}

static int cmp_entry(const void *x, const void *y)
{
    const lb_entry *a = x, *b = y;
    if (a->dist < b->dist) return -1;
    if (a->dist > b->dist) return 1;
    return a->tri < b->tri ? -1 : a->tri > b->tri;
}

/* ---- build ----------------------------------------------------------------- */

void sidx_lightbuffer_destroy(sidx_lightbuffer *lb)
{
    if (!lb) return;
    const sidx_accel *a = &lb->base;
    for (int f = 0; f < 6; ++f) sidx__free(a, lb->entries[f]);
    if (lb->cells && !lb->eager)
        for (uint32_t c = 0; c < lb->cells_total; ++c) {
            sidx__free(a, lb->cells[c].tris);
            sidx__free(a, lb->cells[c].dist);
        }
    sidx__free(a, lb->cells);
    sidx__free(a, lb->eager_tris);
    sidx__free(a, lb->eager_dist);
    pthread_mutex_destroy(&lb->fill_lock);
    sidx_allocator al = a->alloc;
    al.free(lb, al.user);
}

static void *lb_default_alloc(size_t size, void *user) { (void)user; return malloc(size); }
static void lb_default_free(void *p, void *user) { (void)user; free(p); }

static sidx_status fill_eager(sidx_lightbuffer *lb)
{
    const sidx_accel *a = &lb->base;
    const uint32_t R = lb->res;
    uint64_t total = 0;
    /* count, then scatter in distance order (entries are sorted), so every list comes out sorted */
    for (int f = 0; f < 6; ++f)
        for (uint32_t e = 0; e < lb->num_entries[f]; ++e) {
            const lb_entry *en = &lb->entries[f][e];
            for (uint32_t j = en->j0; j <= en->j1; ++j)
                for (uint32_t i = en->i0; i <= en->i1; ++i) lb->cells[((uint32_t)f * R + j) * R + i].count++;
            total += (uint64_t)(en->i1 - en->i0 + 1) * (en->j1 - en->j0 + 1);
        }
    if (total > UINT32_MAX) return SIDX_ERR_LIMIT;
    lb->eager_tris = sidx__alloc(a, (size_t)total, sizeof *lb->eager_tris);
    lb->eager_dist = sidx__alloc(a, (size_t)total, sizeof *lb->eager_dist);
    if (!lb->eager_tris || !lb->eager_dist) return SIDX_ERR_NOMEM;
    uint32_t off = 0;
    for (uint32_t c = 0; c < lb->cells_total; ++c) {
        lb->cells[c].tris = lb->eager_tris + off;
        lb->cells[c].dist = lb->eager_dist + off;
        off += lb->cells[c].count;
        lb->cells[c].count = 0;
    }
    for (int f = 0; f < 6; ++f)
        for (uint32_t e = 0; e < lb->num_entries[f]; ++e) {
            const lb_entry *en = &lb->entries[f][e];
            for (uint32_t j = en->j0; j <= en->j1; ++j)
                for (uint32_t i = en->i0; i <= en->i1; ++i) {
                    lb_cell *cell = &lb->cells[((uint32_t)f * R + j) * R + i];
                    cell->tris[cell->count] = en->tri;
                    cell->dist[cell->count] = (float)en->dist;
                    cell->count++;
                }
        }
    for (uint32_t c = 0; c < lb->cells_total; ++c) atomic_store_explicit(&lb->cells[c].ready, 1, memory_order_relaxed);
    atomic_store(&lb->cells_filled, lb->cells_total);
    atomic_store(&lb->refs, total);
    return SIDX_OK;
}

sidx_status sidx_lightbuffer_build(const sidx_mesh *m, sidx_vec3 light, uint32_t res, int eager,
                                   const sidx_build_options *opt, sidx_lightbuffer **out, sidx_error *err)
{
    if (err) { err->status = SIDX_OK; err->message[0] = '\0'; }
    if (!out) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "lightbuffer: out is NULL");
    *out = NULL;
    if (!m || !sidx_v3_isfinite(light)) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "lightbuffer: no mesh or light not finite");
    if (res == 0) res = LB_DEFAULT_RES;
    if (res > LB_MAX_RES) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "lightbuffer: res %u > %u", res, LB_MAX_RES);
    if (opt && (unsigned)opt->tri >= SIDX_TRI_METHOD_COUNT)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "lightbuffer: unknown triangle test");
    sidx_status s = sidx_mesh_validate(m, err);
    if (s != SIDX_OK) return s;
    sidx_allocator al = {lb_default_alloc, lb_default_free, NULL};
    if (opt && opt->alloc) {
        if (!opt->alloc->alloc || !opt->alloc->free)
            return sidx__fail(err, SIDX_ERR_INVALID_ARG, "lightbuffer: allocator needs alloc and free");
        al = *opt->alloc;
    }
    sidx_lightbuffer *lb = al.alloc(sizeof *lb, al.user);
    if (!lb) return sidx__fail(err, SIDX_ERR_NOMEM, "lightbuffer: out of memory");
    memset(lb, 0, sizeof *lb);
    lb->base.name = "lightbuffer";
    lb->base.mesh = m;
    lb->base.alloc = al;
    if (opt) lb->base.opt.tri = opt->tri;
    lb->light = light;
    lb->res = res;
    lb->eager = eager ? 1 : 0;
    lb->cells_total = 6u * res * res;
    pthread_mutex_init(&lb->fill_lock, NULL);
    const sidx_accel *a = &lb->base;
    const sidx_hook *hook = opt ? opt->hook : NULL;

    SIDX_EMIT(1, hook, SIDX_EV_BUILD_BEGIN, e_.count = m->num_triangles; e_.bounds = sidx_mesh_bounds(m));
    lb->cells = sidx__calloc(a, lb->cells_total, sizeof *lb->cells);
    for (int f = 0; f < 6 && lb->cells; ++f) {
        lb->entries[f] = sidx__alloc(a, m->num_triangles, sizeof *lb->entries[f]);
        if (!lb->entries[f]) break;
    }
    if (!lb->cells || !lb->entries[5]) {
        sidx_lightbuffer_destroy(lb);
        return sidx__fail(err, SIDX_ERR_NOMEM, "lightbuffer: out of memory");
    }
    for (uint32_t c = 0; c < lb->cells_total; ++c) atomic_init(&lb->cells[c].ready, 0);
    const double L[3] = {light.x, light.y, light.z};
    for (uint32_t t = 0; t < m->num_triangles; ++t) {
        double v[3][3];
        for (int k = 0; k < 3; ++k) {
            const sidx_vec3 p = sidx_mesh_vertex(m, t, k);
            v[k][0] = (double)p.x - L[0];
            v[k][1] = (double)p.y - L[1];
            v[k][2] = (double)p.z - L[2];
        }
        const double origin[3] = {0, 0, 0};
        const double dist = point_triangle_dist(origin, v[0], v[1], v[2]);
        for (int f = 0; f < 6; ++f) {
            lb_entry e;
            if (!face_rect((const double(*)[3])v, f, res, &e)) continue;
            e.tri = t;
            e.dist = dist;
            lb->entries[f][lb->num_entries[f]++] = e;
        }
    }
    for (int f = 0; f < 6; ++f) {
        qsort(lb->entries[f], lb->num_entries[f], sizeof *lb->entries[f], cmp_entry);
        SIDX_EMIT(1, hook, SIDX_EV_BUILD_NODE, e_.node = (uint32_t)f; e_.depth = 0; e_.count = lb->num_entries[f]);
    }
    if (lb->eager) {
        s = fill_eager(lb);
        if (s != SIDX_OK) {
            sidx_lightbuffer_destroy(lb);
            return sidx__fail(err, s, "lightbuffer: %s filling the cells", sidx_status_str(s));
        }
    }
    SIDX_EMIT(1, hook, SIDX_EV_BUILD_END, e_.node = lb->cells_total; e_.count = (uint32_t)atomic_load(&lb->refs);
              e_.depth = 0);
    *out = lb;
    return SIDX_OK;
}

/* Lazy fill of one cell: scan its face's entries (already in distance
 * order).  Serialised by a mutex; the list is published by the release
 * store of `ready`, which readers pair with an acquire load.  Returns 0
 * on allocation failure (the caller then scans the face list itself). */
static int fill_cell(sidx_lightbuffer *lb, uint32_t cell_id, int f, int ci, int cj)
{
    lb_cell *cell = &lb->cells[cell_id];
    pthread_mutex_lock(&lb->fill_lock);
    int ok = 1;
    if (!atomic_load_explicit(&cell->ready, memory_order_relaxed)) {
        const lb_entry *en = lb->entries[f];
        uint32_t n = 0;
        for (uint32_t e = 0; e < lb->num_entries[f]; ++e)
            if (en[e].i0 <= ci && ci <= en[e].i1 && en[e].j0 <= cj && cj <= en[e].j1) ++n;
        uint32_t *tris = sidx__alloc(&lb->base, n, sizeof *tris);
        float *dist = sidx__alloc(&lb->base, n, sizeof *dist);
        if (!tris || !dist) {
            sidx__free(&lb->base, tris);
            sidx__free(&lb->base, dist);
            ok = 0;
        } else {
            uint32_t k = 0;
            for (uint32_t e = 0; e < lb->num_entries[f]; ++e)
                if (en[e].i0 <= ci && ci <= en[e].i1 && en[e].j0 <= cj && cj <= en[e].j1) {
                    tris[k] = en[e].tri;
                    dist[k] = (float)en[e].dist;
                    ++k;
                }
            cell->tris = tris;
            cell->dist = dist;
            cell->count = n;
            atomic_fetch_add(&lb->cells_filled, 1u);
            atomic_fetch_add(&lb->refs, (unsigned long long)n);
            atomic_store_explicit(&cell->ready, 1, memory_order_release);
        }
    }
    pthread_mutex_unlock(&lb->fill_lock);
    return ok;
}

/* ---- queries ------------------------------------------------------------------ */

sidx_status sidx_lightbuffer_cache_init(const sidx_lightbuffer *lb, sidx_lightbuffer_cache *c)
{
    if (!lb || !c) return SIDX_ERR_INVALID_ARG;
    memset(c, 0, sizeof *c);
    c->last = malloc((size_t)lb->cells_total * sizeof *c->last);
    if (!c->last) return SIDX_ERR_NOMEM;
    for (uint32_t i = 0; i < lb->cells_total; ++i) c->last[i] = SIDX_NO_HIT;
    c->cells = lb->cells_total;
    return SIDX_OK;
}

void sidx_lightbuffer_cache_free(sidx_lightbuffer_cache *c)
{
    if (!c) return;
    free(c->last);
    memset(c, 0, sizeof *c);
}

sidx_status sidx_lightbuffer_shadow_ray(const sidx_lightbuffer *lb, sidx_vec3 p, float tmin, float tmax,
                                        sidx_ray *out)
{
    if (!lb || !out) return SIDX_ERR_INVALID_ARG;
    return sidx_ray_init(out, p, sidx_v3_sub(lb->light, p), tmin, tmax);
}

/* The farthest a blocking triangle can lie from the light: a point at ray
 * parameter t is (1 - t)·|light - p| from it (+ margin for float distances). */
static SIDX_INLINE float lb_reach(const sidx_ray *r)
{
    const double seg = sqrt((double)r->dir.x * r->dir.x + (double)r->dir.y * r->dir.y + (double)r->dir.z * r->dir.z);
    return (float)((1.0 - (double)r->tmin) * seg * (1.0 + 1e-5) + 1e-30);
}

static SIDX_INLINE int lb_query(sidx_lightbuffer *lb, const sidx_ray *r, sidx_lightbuffer_cache *cache,
                                const sidx_query *q, const int traced)
{
    const sidx_mesh *m = lb->base.mesh;
    const sidx_tri_method method = lb->base.opt.tri;
    int f, ci, cj;
    const uint32_t cell_id = cell_of(lb, sidx_v3_scale(r->dir, -1.0f), &f, &ci, &cj);
    lb_cell *cell = &lb->cells[cell_id];
    int have_list = 1;
    if (!atomic_load_explicit(&cell->ready, memory_order_acquire)) {
        have_list = fill_cell(lb, cell_id, f, ci, cj);
        SIDX_EMIT(traced, q->hook, SIDX_EV_NOTE, e_.ray_id = q->ray_id; e_.node = cell_id;
                  e_.cell[0] = f; e_.cell[1] = ci; e_.cell[2] = cj; e_.count = have_list ? cell->count : 0;
                  e_.text = have_list ? "lightbuffer: cell list made lazily on its first query (count = triangles)"
                                      : "lightbuffer: out of memory filling a cell; scanning the face list instead");
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_NODE_ENTER, e_.ray_id = q->ray_id; e_.node = cell_id; e_.depth = 0;
              e_.cell[0] = f; e_.cell[1] = ci; e_.cell[2] = cj; e_.count = have_list ? cell->count : 0;
              e_.t_near = r->tmin; e_.t_far = r->tmax);
    uint32_t tests = 0;
    /* 1. the last occluder found in this cell */
    const uint32_t cached = cache ? cache->last[cell_id] : SIDX_NO_HIT;
    if (cached != SIDX_NO_HIT) {
        float t;
        const int h = sidx__mesh_tri_test(m, method, cached, r, r->tmax, &t);
        ++tests;
        cache->cache_tests++;
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.node = cell_id; e_.prim = cached;
                  e_.result = h; e_.t = h ? t : INFINITY; e_.aux = 1);
        if (h) {
            cache->cache_hits++;
            cache->tri_tests += tests;
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.t = t; e_.count = tests);
            return 1;
        }
    }
    /* 2. the list, nearest to the light first.  A point at ray parameter
     * t is (1 − t)·|light − p| from the light, so for t >= tmin no
     * triangle farther than (1 − tmin)·|light − p| can block (+ margin
     * for float distances). */
    const float reach = lb_reach(r);
    const uint32_t n = have_list ? cell->count : lb->num_entries[f];
    for (uint32_t k = 0; k < n; ++k) {
        uint32_t tri;
        float dist;
        if (have_list) {
            tri = cell->tris[k];
            dist = cell->dist[k];
        } else {
            const lb_entry *en = &lb->entries[f][k];
            if (!(en->i0 <= ci && ci <= en->i1 && en->j0 <= cj && cj <= en->j1)) continue;
            tri = en->tri;
            dist = (float)en->dist;
        }
        if (dist > reach) break;
        if (tri == cached) continue;
        float t;
        const int h = sidx__mesh_tri_test(m, method, tri, r, r->tmax, &t);
        ++tests;
        SIDX_EMIT(traced, q->hook, SIDX_EV_PRIM_TEST, e_.ray_id = q->ray_id; e_.node = cell_id; e_.prim = tri;
                  e_.result = h; e_.t = h ? t : INFINITY);
        if (h) {
            if (cache) { cache->last[cell_id] = tri; cache->tri_tests += tests; }
            SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_ANY_HIT;
                      e_.t = t; e_.count = tests);
            return 1;
        }
    }
    if (cache) cache->tri_tests += tests;
    SIDX_EMIT(traced, q->hook, SIDX_EV_TERMINATE, e_.ray_id = q->ray_id; e_.reason = SIDX_TERM_STACK_EMPTY;
              e_.count = tests);
    return 0;
}

sidx_status sidx_lightbuffer_occluded(const sidx_lightbuffer *lb, sidx_vec3 p, float tmin, float tmax,
                                      sidx_lightbuffer_cache *cache, const sidx_query *q, int *occluded)
{
    if (!lb || !occluded || (cache && cache->cells != lb->cells_total)) return SIDX_ERR_INVALID_ARG;
    sidx_ray r;
    const sidx_status s = sidx_lightbuffer_shadow_ray(lb, p, tmin, tmax, &r);
    if (s != SIDX_OK) return s;
    /* Lazy filling writes into the cells (under the lock); the structure
     * is logically const, as a memoising cache is. */
    sidx_lightbuffer *mlb = (sidx_lightbuffer *)(uintptr_t)lb;
    static const sidx_query none = {0, SIDX_TRAVERSE_DEFAULT, NULL, 0};
    if (!q) q = &none;
    const int traced = SIDX_QUERY_TRACED(q);
    SIDX_EMIT(traced, q->hook, SIDX_EV_RAY_BEGIN, e_.ray_id = q->ray_id; e_.t_near = r.tmin; e_.t_far = r.tmax);
    *occluded = traced ? lb_query(mlb, &r, cache, q, 1) : lb_query(mlb, &r, cache, q, 0);
    if (cache) {
        cache->queries++;
        cache->occluded += (uint64_t)*occluded;
    }
    SIDX_EMIT(traced, q->hook, SIDX_EV_RAY_END, e_.ray_id = q->ray_id; e_.result = *occluded);
    return SIDX_OK;
}

sidx_status sidx_lightbuffer_cell_get(const sidx_lightbuffer *lb, const sidx_ray *shadow_ray,
                                      sidx_lightbuffer_cell_view *out)
{
    if (!lb || !shadow_ray || !out) return SIDX_ERR_INVALID_ARG;
    sidx_lightbuffer *mlb = (sidx_lightbuffer *)(uintptr_t)lb;
    int f, ci, cj;
    const uint32_t id = cell_of(lb, sidx_v3_scale(shadow_ray->dir, -1.0f), &f, &ci, &cj);
    lb_cell *cell = &mlb->cells[id];
    if (!atomic_load_explicit(&cell->ready, memory_order_acquire) && !fill_cell(mlb, id, f, ci, cj))
        return SIDX_ERR_NOMEM;
    out->id = id;
    out->face = f;
    out->i = ci;
    out->j = cj;
    out->count = cell->count;
    out->tris = cell->tris;
    out->dist = cell->dist;
    out->reach = lb_reach(shadow_ray);
    return SIDX_OK;
}

sidx_status sidx_lightbuffer_stats_get(const sidx_lightbuffer *lb, sidx_lightbuffer_stats *s)
{
    if (!lb || !s) return SIDX_ERR_INVALID_ARG;
    memset(s, 0, sizeof *s);
    s->res = lb->res;
    s->cells = lb->cells_total;
    s->cells_filled = atomic_load(&((sidx_lightbuffer *)(uintptr_t)lb)->cells_filled);
    s->refs = atomic_load(&((sidx_lightbuffer *)(uintptr_t)lb)->refs);
    s->light = lb->light;
    size_t bytes = sizeof *lb + (size_t)lb->cells_total * sizeof *lb->cells;
    for (int f = 0; f < 6; ++f) s->face_entries += lb->num_entries[f];
    bytes += 6u * (size_t)lb->base.mesh->num_triangles * sizeof(lb_entry); /* allocated for the worst case */
    bytes += (size_t)s->refs * (sizeof(uint32_t) + sizeof(float));
    s->bytes = bytes;
    return SIDX_OK;
}
