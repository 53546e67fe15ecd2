/* simd_ray_sse.h — sidx_ray_init's set-up (core.c) with SSE2: the
 * finiteness of the six components and the direction's signs in one
 * compare and two movemasks, and the five divisions (1/dx, 1/dy, 1/dz,
 * d[kx]/d[kz], d[ky]/d[kz]) as two 4-lane divisions.  IEEE 754 rounds a
 * SIMD division exactly like a scalar one, so the quotients are the bits
 * of simd_ray_scalar.h, the reference.
 *
 * Not a normal header: core.c includes it (or simd_ray_scalar.h). */
#include <emmintrin.h>

/* the direction as a row; lane 3 is a harmless 1: finite, positive, and
 * a quotient that raises no flag */
typedef struct ray_row {
    __m128 d4;
} ray_row;

/* finite: all six components (x − x is +0 for every finite x and NaN
 * for ±inf and NaN, and a NaN survives the adds); signs: bit i set where
 * dir[i] is negative, −0 included. */
static SIDX_INLINE ray_row ray_row_check(sidx_vec3 org, sidx_vec3 dir, int *finite, unsigned *signs)
{
    ray_row row;
    const __m128 o4 = _mm_setr_ps(org.x, org.y, org.z, 1.0f);
    row.d4 = _mm_setr_ps(dir.x, dir.y, dir.z, 1.0f);
    const __m128 fin4 = _mm_add_ps(_mm_sub_ps(o4, o4), _mm_sub_ps(row.d4, row.d4));
    *finite = _mm_movemask_ps(_mm_cmpeq_ps(fin4, _mm_setzero_ps())) == 0xF;
    *signs = (unsigned)_mm_movemask_ps(row.d4) & 7u;
    return row;
}

/* r->inv_dir, and the shear r->sx, r->sy, r->sz = 1/d[kz] (the same bits
 * as inv_dir[kz]). */
static SIDX_INLINE void ray_row_quotients(ray_row row, const float d[3], int kx, int ky, int kz, sidx_ray *r)
{
    float inv[4], shear[4];
    _mm_storeu_ps(inv, _mm_div_ps(_mm_set1_ps(1.0f), row.d4));
    _mm_storeu_ps(shear, _mm_div_ps(_mm_setr_ps(d[kx], d[ky], 1.0f, 1.0f), _mm_set1_ps(d[kz])));
    r->inv_dir = sidx_v3(inv[0], inv[1], inv[2]);
    r->sx = shear[0];
    r->sy = shear[1];
    r->sz = shear[2];
}
