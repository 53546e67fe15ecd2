/* hit.c — finishing a closest hit, once the walk has found it: its t
 * refined on the triangle's plane, its u, v and geometric normal from
 * the mesh, and its point with an error bound.  Every query path calls
 * sidx__hit_finish once per hit ray: the single-ray query (accel.c), the
 * packet walks (packet.c, packet_wide.c) and the aggregate (instance.c).
 * Nothing here runs inside a traversal. */
#include "sidx_internal.h"
#include "hit.h"

/* The closest hit's t recomputed on the triangle's plane in double,
 * t = n·(p0 − o) / n·d with n = (p1 − p0) × (p2 − p0): from float inputs
 * the differences are exact in double and the products nearly so, and t is
 * rounded to float once.  Kept only within 2^-12 (|p0 − o|₁ + |e1|₁ +
 * |e2|₁) / |d|₁ of the test's t, far above the test's own error: a ray
 * that grazes a triangle and is accepted on an edge has no meaningful
 * plane t (a thin prism's apex: 3.26 for the edge's 0.976).  Clamped to
 * [tmin, the float below tmax], where the walk accepted the test's t. */
static SIDX_NOINLINE void refine_t_plane(const sidx_mesh *m, const sidx_ray *r, sidx_hit *hit)
{
    const sidx_vec3 p0 = sidx_mesh_vertex(m, hit->prim, 0), p1 = sidx_mesh_vertex(m, hit->prim, 1),
                    p2 = sidx_mesh_vertex(m, hit->prim, 2);
    const double ax = (double)p1.x - p0.x, ay = (double)p1.y - p0.y, az = (double)p1.z - p0.z;
    const double bx = (double)p2.x - p0.x, by = (double)p2.y - p0.y, bz = (double)p2.z - p0.z;
    const double wx = (double)p0.x - r->org.x, wy = (double)p0.y - r->org.y, wz = (double)p0.z - r->org.z;
    const double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
    const double den = nx * r->dir.x + ny * r->dir.y + nz * r->dir.z;
    if (den == 0.0) return;
    const double tr = (nx * wx + ny * wy + nz * wz) / den;
    const double dist = fabs(wx) + fabs(wy) + fabs(wz) + fabs(ax) + fabs(ay) + fabs(az) + fabs(bx) + fabs(by) + fabs(bz);
    const double dlen = fabs((double)r->dir.x) + fabs((double)r->dir.y) + fabs((double)r->dir.z);
    if (!(fabs(tr - hit->t) * dlen <= 0x1p-12 * dist)) return;
    float t = (float)tr;
    if (t < r->tmin) t = r->tmin;
    if (!(t < r->tmax)) t = nextafterf(r->tmax, -INFINITY);
    hit->t = t;
}

/* The closest hit's t, as precise as the triangle's plane gives it.  The
 * watertight test (Woop, Benthin & Wald 2013) forms t = T/det from the
 * vertices sheared into the ray's frame in float, each off by about ε
 * times its distance from the origin: when the triangle reaches along the
 * ray far beyond the hit (a short bounce onto a long thin neighbour,
 * Sponza), t loses up to 1e-3 of itself.  The vertices' spread along the
 * ray's dominant axis measures it: when |az| + |bz| + |cz| exceeds 4 t |d_kz|
 * (a few hits of a scene of small even triangles, many of one with long
 * thin ones), t is recomputed on the plane in double (refine_t_plane);
 * otherwise the test's t stands.  Which triangle is closest and its u, v
 * stay the test's (watertightness is the test's), only t changes.  Bound:
 * docs/spawning.md, "Precision of t"; figures: docs/performance.md,
 * "Precision of the closest hit's t". */
static SIDX_INLINE void refine_t(const sidx_mesh *m, const sidx_ray *r, sidx_hit *hit)
{
    const uint32_t *ix = m->indices + 3u * hit->prim;
    const int kz = r->kz;
    const float oz = sidx_v3_array(&r->org)[kz];
    const float spread = fabsf(sidx_v3_array(&m->positions[ix[0]])[kz] - oz) +
                         fabsf(sidx_v3_array(&m->positions[ix[1]])[kz] - oz) +
                         fabsf(sidx_v3_array(&m->positions[ix[2]])[kz] - oz);
    if (SIDX_UNLIKELY(spread > 4.0f * hit->t * fabsf(sidx_v3_array(&r->dir)[kz]))) refine_t_plane(m, r, hit);
}

/* u, v (by test method tri on ray r) and the geometric normal of the
 * hit, from the mesh, as `need` (SIDX_QUERY_UV | SIDX_QUERY_NORMAL) asks. */
static SIDX_INLINE void hit_attrs(const sidx_mesh *m, sidx_tri_method tri, const sidx_ray *r, uint32_t need,
                                  sidx_hit *hit)
{
    const sidx_vec3 p0 = sidx_mesh_vertex(m, hit->prim, 0), p1 = sidx_mesh_vertex(m, hit->prim, 1),
                    p2 = sidx_mesh_vertex(m, hit->prim, 2);
    if (need & SIDX_QUERY_UV) {
        /* the accepting test's own floats (sidx__tri_hit_uv_at), so its bits */
        float u = 0.0f, v = 0.0f;
        if (sidx__tri_hit_uv_at(tri, r, sidx_v3_array(&p0), sidx_v3_array(&p1), sidx_v3_array(&p2), 1, &u, &v)) {
            hit->u = u;
            hit->v = v;
        }
    }
    if (need & SIDX_QUERY_NORMAL) hit->ng = sidx__tri_normal(p0, p1, p2);
}

/* SIDX_QUERY_POINT: u, v and ng first, where `need` says they are
 * missing, then the point and its error bound.  A triangle refused by
 * sidx_triangle_point (spawn.c) leaves p and p_err zero, which
 * sidx_ray_spawn then refuses.  Out of line: the plain queries' finish
 * stays short. */
static SIDX_NOINLINE void hit_point(const sidx_mesh *m, sidx_tri_method tri, const sidx_ray *r, uint32_t need,
                                    sidx_hit *hit)
{
    if (need) hit_attrs(m, tri, r, need, hit);
    sidx_vec3 p, e;
    if (sidx_triangle_point(sidx_mesh_vertex(m, hit->prim, 0), sidx_mesh_vertex(m, hit->prim, 1),
                            sidx_mesh_vertex(m, hit->prim, 2), hit->u, hit->v, &p, &e) == SIDX_OK) {
        hit->p = p;
        hit->p_err = e;
    }
}

void sidx__hit_finish(const sidx_mesh *m, sidx_tri_method tri, const sidx_ray *r, uint32_t flags, uint32_t own,
                      sidx_hit *hit)
{
    /* t first: u, v below come from the test's edge functions, which do
     * not depend on t, so the order changes no bit of them. */
    if (flags & SIDX__QUERY_REFINE_T) refine_t(m, r, hit);
    /* The point is made from u, v and ng, so asking for it asks for them;
     * what the structure filled itself counts only when the query asked
     * it to. */
    if (SIDX_UNLIKELY(flags & SIDX_QUERY_POINT)) {
        hit_point(m, tri, r, (SIDX_QUERY_UV | SIDX_QUERY_NORMAL) & ~(own & flags), hit);
        return;
    }
    const uint32_t need = flags & (SIDX_QUERY_UV | SIDX_QUERY_NORMAL) & ~own;
    if (need) hit_attrs(m, tri, r, need, hit);
}
