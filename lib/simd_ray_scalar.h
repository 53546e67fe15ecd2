/* simd_ray_scalar.h — sidx_ray_init's set-up (core.c) in plain C, the
 * reference of simd_ray_sse.h: the finiteness of the six components,
 * the direction's signs, and the five divisions one at a time.
 *
 * Not a normal header: core.c includes it (or simd_ray_sse.h). */

typedef struct ray_row {
    sidx_vec3 dir;
} ray_row;

/* finite: all six components (x − x is +0 for every finite x and NaN
 * for ±inf and NaN, and a NaN survives the adds); signs: bit i set where
 * dir[i] is negative, −0 included. */
static SIDX_INLINE ray_row ray_row_check(sidx_vec3 org, sidx_vec3 dir, int *finite, unsigned *signs)
{
    ray_row row;
    row.dir = dir;
    const float fin = ((org.x - org.x) + (org.y - org.y)) + ((org.z - org.z) + (dir.x - dir.x)) +
                      ((dir.y - dir.y) + (dir.z - dir.z));
    *finite = fin == 0.0f;
    *signs = (signbit(dir.x) ? 1u : 0u) | (signbit(dir.y) ? 2u : 0u) | (signbit(dir.z) ? 4u : 0u);
    return row;
}

/* r->inv_dir, and the shear r->sx, r->sy, r->sz = 1/d[kz] (inv_dir[kz],
 * already computed: one division fewer per ray). */
static SIDX_INLINE void ray_row_quotients(ray_row row, const float d[3], int kx, int ky, int kz, sidx_ray *r)
{
    r->inv_dir = sidx_v3(1.0f / row.dir.x, 1.0f / row.dir.y, 1.0f / row.dir.z);
    r->sx = d[kx] / d[kz];
    r->sy = d[ky] / d[kz];
    r->sz = (sidx_v3_array(&r->inv_dir))[kz];
}
