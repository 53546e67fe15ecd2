/* intersect.c — the elementary tests as public functions, and bounding
 * volumes (sphere, AABB, OBB, slabs) with their fitting.
 *
 * The triangle and box bodies live in sidx_internal.h as static inline
 * functions so every structure's hot loop inlines them; these wrappers are
 * what lessons, tests and users call. */
#include "sidx_internal.h"

static const char *const tri_names[SIDX_TRI_METHOD_COUNT] = {"watertight", "moller", "twostep"};
static const char *const box_names[SIDX_BOX_METHOD_COUNT] = {"robust", "plain"};

const char *sidx_tri_method_name(sidx_tri_method m)
{
    return ((unsigned)m < SIDX_TRI_METHOD_COUNT) ? tri_names[m] : NULL;
}
const char *sidx_box_method_name(sidx_box_method m)
{
    return ((unsigned)m < SIDX_BOX_METHOD_COUNT) ? box_names[m] : NULL;
}
sidx_status sidx_tri_method_parse(const char *name, sidx_tri_method *out)
{
    if (!name || !out) return SIDX_ERR_INVALID_ARG;
    for (int i = 0; i < SIDX_TRI_METHOD_COUNT; ++i)
        if (strcmp(name, tri_names[i]) == 0) { *out = (sidx_tri_method)i; return SIDX_OK; }
    return SIDX_ERR_INVALID_ARG;
}
sidx_status sidx_box_method_parse(const char *name, sidx_box_method *out)
{
    if (!name || !out) return SIDX_ERR_INVALID_ARG;
    for (int i = 0; i < SIDX_BOX_METHOD_COUNT; ++i)
        if (strcmp(name, box_names[i]) == 0) { *out = (sidx_box_method)i; return SIDX_OK; }
    return SIDX_ERR_INVALID_ARG;
}

/* ---- planes and triangles --------------------------------------------- */

int sidx_intersect_plane(const sidx_ray *r, sidx_vec3 n, float c, float *t)
{
    if (!r) return 0;
    const float nd = sidx_v3_dot(n, r->dir);
    if (nd == 0.0f) return 0; /* parallel: no unique solution (or the ray lies in the plane) */
    const float tt = (c - sidx_v3_dot(n, r->org)) / nd;
    if (!(tt >= r->tmin && tt < r->tmax)) return 0;
    if (t) *t = tt;
    return 1;
}

/* The outputs are optional: a test needs t, u, v locals to write into. */
#define TRI_WRAPPER(fn, body)                                                                          \
    int fn(const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float tmax, float *t, float *u, float *v) \
    {                                                                                                  \
        float tt, uu, vv;                                                                              \
        if (!r || !body(r, a, b, c, tmax, &tt, &uu, &vv)) return 0;                                    \
        if (t) *t = tt;                                                                                \
        if (u) *u = uu;                                                                                \
        if (v) *v = vv;                                                                                \
        return 1;                                                                                      \
    }
TRI_WRAPPER(sidx_intersect_triangle_watertight, sidx__tri_watertight)
TRI_WRAPPER(sidx_intersect_triangle_moller, sidx__tri_moller)
TRI_WRAPPER(sidx_intersect_triangle_two_step, sidx__tri_two_step)

int sidx_intersect_triangle(sidx_tri_method m, const sidx_ray *r, sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float tmax,
                            float *t, float *u, float *v)
{
    switch (m) {
    case SIDX_TRI_WATERTIGHT: return sidx_intersect_triangle_watertight(r, a, b, c, tmax, t, u, v);
    case SIDX_TRI_MOLLER_TRUMBORE: return sidx_intersect_triangle_moller(r, a, b, c, tmax, t, u, v);
    case SIDX_TRI_TWO_STEP: return sidx_intersect_triangle_two_step(r, a, b, c, tmax, t, u, v);
    default: return 0;
    }
}

/* ---- boxes ---------------------------------------------------------------- */

int sidx_intersect_aabb(sidx_box_method m, const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax,
                        float *t_near, float *t_far)
{
    if (!r || !box || (unsigned)m >= SIDX_BOX_METHOD_COUNT) return 0;
    float tn, tf;
    if (!sidx__box_test(m == SIDX_BOX_ROBUST, r, box, tmin, tmax, &tn, &tf)) return 0;
    if (t_near) *t_near = tn;
    if (t_far) *t_far = tf;
    return 1;
}

/* Clip [*t0, *t1] by the slab lo <= n·x <= hi along the ray (n need not be
 * unit length).  Returns 0 when the interval becomes empty. */
static int clip_slab(const sidx_ray *r, sidx_vec3 n, float lo, float hi, float *t0, float *t1)
{
    const float nd = sidx_v3_dot(n, r->dir), no = sidx_v3_dot(n, r->org);
    if (nd == 0.0f) return no >= lo && no <= hi; /* parallel: inside the slab or never */
    float a = (lo - no) / nd, b = (hi - no) / nd;
    if (a > b) { float tmp = a; a = b; b = tmp; }
    if (a > *t0) *t0 = a;
    if (b < *t1) *t1 = b;
    return *t0 <= *t1;
}

int sidx_intersect_sphere(const sidx_ray *r, const sidx_sphere *s, float tmin, float tmax, float *t_near, float *t_far)
{
    if (!r || !s) return 0;
    /* |o + t d − c|² = R²  →  a t² + 2 b t + k = 0.  The discriminant is
     * formed from the distance of the centre to the ray line, which loses
     * less precision for far-away spheres than b² − a·k (Haines et al.,
     * Ray Tracing Gems ch. 7). */
    const sidx_vec3 f = sidx_v3_sub(r->org, s->center);
    const float a = sidx_v3_dot(r->dir, r->dir);
    const float b = -sidx_v3_dot(f, r->dir);
    const sidx_vec3 l = sidx_v3_add(f, sidx_v3_scale(r->dir, b / a));
    const float disc = a * (s->radius * s->radius - sidx_v3_dot(l, l));
    if (disc < 0.0f) return 0;
    const float sq = sqrtf(disc);
    float t0 = (b - sq) / a, t1 = (b + sq) / a;
    if (t0 < tmin) t0 = tmin;
    if (t1 > tmax) t1 = tmax;
    if (t0 > t1) return 0;
    if (t_near) *t_near = t0;
    if (t_far) *t_far = t1;
    return 1;
}

int sidx_intersect_obb(const sidx_ray *r, const sidx_obb *b, float tmin, float tmax, float *t_near, float *t_far)
{
    if (!r || !b) return 0;
    float t0 = tmin, t1 = tmax;
    const float *h = sidx_v3_array(&b->half);
    for (int i = 0; i < 3; ++i) {
        const float c = sidx_v3_dot(b->axis[i], b->center);
        if (!clip_slab(r, b->axis[i], c - h[i], c + h[i], &t0, &t1)) return 0;
    }
    if (t_near) *t_near = t0;
    if (t_far) *t_far = t1;
    return 1;
}

sidx_vec3 sidx_kdop_axis(int i)
{
    static const float ax[SIDX_KDOP_AXES][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1},
                                                {1, 1, 1}, {1, -1, 1}, {1, 1, -1}, {1, -1, -1}};
    if (i < 0 || i >= SIDX_KDOP_AXES) return sidx_v3(0, 0, 0);
    return sidx_v3(ax[i][0], ax[i][1], ax[i][2]);
}

int sidx_intersect_kdop(const sidx_ray *r, const sidx_kdop *k, float tmin, float tmax, float *t_near, float *t_far)
{
    if (!r || !k) return 0;
    float t0 = tmin, t1 = tmax;
    for (int i = 0; i < SIDX_KDOP_AXES; ++i)
        if (!clip_slab(r, sidx_kdop_axis(i), k->lo[i], k->hi[i], &t0, &t1)) return 0;
    if (t_near) *t_near = t0;
    if (t_far) *t_far = t1;
    return 1;
}

/* ---- fitting ---------------------------------------------------------------- */

sidx_status sidx_aabb_fit(const sidx_vec3 *p, uint32_t n, sidx_aabb *out)
{
    if (!p || !n || !out) return SIDX_ERR_INVALID_ARG;
    sidx_aabb b = sidx_aabb_empty();
    for (uint32_t i = 0; i < n; ++i) b = sidx_aabb_grow(b, p[i]);
    *out = b;
    return SIDX_OK;
}

/* Ritter 1990: start from a far-apart pair, then grow the sphere just
 * enough to take in each point outside it.  Two passes over the points. */
sidx_status sidx_sphere_fit(const sidx_vec3 *p, uint32_t n, sidx_sphere *out)
{
    if (!p || !n || !out) return SIDX_ERR_INVALID_ARG;
    uint32_t ia = 0, ib = 0;
    float best = 0.0f;
    for (uint32_t i = 0; i < n; ++i) {
        sidx_vec3 d = sidx_v3_sub(p[i], p[0]);
        if (sidx_v3_dot(d, d) > best) { best = sidx_v3_dot(d, d); ia = i; }
    }
    best = 0.0f;
    for (uint32_t i = 0; i < n; ++i) {
        sidx_vec3 d = sidx_v3_sub(p[i], p[ia]);
        if (sidx_v3_dot(d, d) > best) { best = sidx_v3_dot(d, d); ib = i; }
    }
    sidx_vec3 c = sidx_v3_scale(sidx_v3_add(p[ia], p[ib]), 0.5f);
    float rad = 0.5f * sqrtf(best);
    for (uint32_t i = 0; i < n; ++i) {
        const sidx_vec3 d = sidx_v3_sub(p[i], c);
        const float dist = sidx_v3_length(d);
        if (dist > rad) {
            const float nr = 0.5f * (rad + dist);
            c = sidx_v3_add(c, sidx_v3_scale(d, (nr - rad) / dist));
            rad = nr;
        }
    }
    /* Rounding can leave a point a hair outside: pad by a few ulps. */
    float worst = 0.0f;
    for (uint32_t i = 0; i < n; ++i) {
        const float dist = sidx_v3_length(sidx_v3_sub(p[i], c));
        if (dist > worst) worst = dist;
    }
    out->center = c;
    out->radius = (worst > rad ? worst : rad) * (1.0f + 4.0f * FLT_EPSILON);
    return SIDX_OK;
}

/* Eigenvectors of a symmetric 3×3 matrix by cyclic Jacobi rotations. */
static void jacobi3(double m[3][3], double v[3][3])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) v[i][j] = (i == j);
    for (int sweep = 0; sweep < 50; ++sweep) {
        double off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
        if (off < 1e-30) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (fabs(m[p][q]) < 1e-300) continue;
                const double theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; ++k) { /* m = Jᵀ m J */
                    const double mkp = m[k][p], mkq = m[k][q];
                    m[k][p] = c * mkp - s * mkq;
                    m[k][q] = s * mkp + c * mkq;
                }
                for (int k = 0; k < 3; ++k) {
                    const double mpk = m[p][k], mqk = m[q][k];
                    m[p][k] = c * mpk - s * mqk;
                    m[q][k] = s * mpk + c * mqk;
                }
                for (int k = 0; k < 3; ++k) {
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
}

sidx_status sidx_obb_fit(const sidx_vec3 *p, uint32_t n, sidx_obb *out)
{
    if (!p || !n || !out) return SIDX_ERR_INVALID_ARG;
    double mean[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n; ++i) { mean[0] += p[i].x; mean[1] += p[i].y; mean[2] += p[i].z; }
    for (int k = 0; k < 3; ++k) mean[k] /= n;
    double cov[3][3] = {{0}};
    for (uint32_t i = 0; i < n; ++i) {
        const double d[3] = {p[i].x - mean[0], p[i].y - mean[1], p[i].z - mean[2]};
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) cov[a][b] += d[a] * d[b];
    }
    double v[3][3];
    jacobi3(cov, v);
    sidx_obb o;
    for (int k = 0; k < 3; ++k) {
        double len = sqrt(v[0][k] * v[0][k] + v[1][k] * v[1][k] + v[2][k] * v[2][k]);
        if (len < 1e-12) len = 1.0;
        o.axis[k] = sidx_v3((float)(v[0][k] / len), (float)(v[1][k] / len), (float)(v[2][k] / len));
    }
    /* Make the frame right-handed and exactly orthogonal in float. */
    o.axis[2] = sidx_v3_cross(o.axis[0], o.axis[1]);
    o.axis[2] = sidx_v3_scale(o.axis[2], 1.0f / sidx_v3_length(o.axis[2]));
    o.axis[1] = sidx_v3_cross(o.axis[2], o.axis[0]);
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) { lo[k] = INFINITY; hi[k] = -INFINITY; }
    for (uint32_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const float d = sidx_v3_dot(o.axis[k], p[i]);
            if (d < lo[k]) lo[k] = d;
            if (d > hi[k]) hi[k] = d;
        }
    sidx_vec3 c = sidx_v3(0, 0, 0);
    float h[3];
    for (int k = 0; k < 3; ++k) {
        /* pad by a few ulps of the magnitude so rounding keeps points inside */
        const float pad = 4.0f * FLT_EPSILON * (fabsf(lo[k]) > fabsf(hi[k]) ? fabsf(lo[k]) : fabsf(hi[k]));
        lo[k] -= pad;
        hi[k] += pad;
        c = sidx_v3_add(c, sidx_v3_scale(o.axis[k], 0.5f * (lo[k] + hi[k])));
        h[k] = 0.5f * (hi[k] - lo[k]);
    }
    o.center = c;
    o.half = sidx_v3_from_array(h);
    *out = o;
    return SIDX_OK;
}

sidx_status sidx_kdop_fit(const sidx_vec3 *p, uint32_t n, sidx_kdop *out)
{
    if (!p || !n || !out) return SIDX_ERR_INVALID_ARG;
    for (int k = 0; k < SIDX_KDOP_AXES; ++k) {
        const sidx_vec3 ax = sidx_kdop_axis(k);
        float lo = INFINITY, hi = -INFINITY;
        for (uint32_t i = 0; i < n; ++i) {
            const float d = sidx_v3_dot(ax, p[i]);
            if (d < lo) lo = d;
            if (d > hi) hi = d;
        }
        const float pad = 4.0f * FLT_EPSILON * (fabsf(lo) > fabsf(hi) ? fabsf(lo) : fabsf(hi));
        out->lo[k] = lo - pad;
        out->hi[k] = hi + pad;
    }
    return SIDX_OK;
}

float sidx_sphere_area(const sidx_sphere *s) { return s ? 4.0f * 3.14159265f * s->radius * s->radius : 0.0f; }

float sidx_obb_area(const sidx_obb *b)
{
    if (!b) return 0.0f;
    const float x = 2 * b->half.x, y = 2 * b->half.y, z = 2 * b->half.z;
    return 2.0f * (x * y + y * z + z * x);
}
