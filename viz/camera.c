/* camera.c — the pinhole camera and the heat map's counts (camera.h). */
#include <math.h>
#include <string.h>
#include "camera.h"

/* cos, sin and tan in double, rounded once to float: the same floats from
 * glibc and from the WebAssembly build's libm (their float versions differ
 * in the last bit for some angles), so the page's camera rays are the
 * native ones. */
static float cos1(float x) { return (float)cos((double)x); }
static float sin1(float x) { return (float)sin((double)x); }

static sidx_vec3 v3norm(sidx_vec3 a)
{
    float l = sidx_v3_length(a);
    return l > 0.0f ? sidx_v3_scale(a, 1.0f / l) : a;
}

viz_camera viz_camera_make(sidx_aabb b, float yaw, float pitch, float zoom, int w, int h)
{
    viz_camera c;
    if (sidx_aabb_is_empty(b)) b.min = b.max = sidx_v3(0, 0, 0);
    sidx_vec3 target = sidx_aabb_centroid(b);
    float radius = 0.5f * sidx_v3_length(sidx_aabb_extent(b));
    if (!(radius > 0.0f)) radius = 1.0f;
    float dist = radius * 2.4f / (zoom > 0.05f ? zoom : 0.05f);
    float cp = cos1(pitch), sp = sin1(pitch);
    sidx_vec3 off = sidx_v3(cp * sin1(yaw), sp, cp * cos1(yaw));
    c.eye = sidx_v3_add(target, sidx_v3_scale(off, dist));
    c.fwd = v3norm(sidx_v3_sub(target, c.eye));
    sidx_vec3 world_up = sidx_v3(0, 1, 0);
    c.right = sidx_v3_cross(c.fwd, world_up);
    if (sidx_v3_length(c.right) < 1e-4f) c.right = sidx_v3(1, 0, 0);
    c.right = v3norm(c.right);
    c.up = sidx_v3_cross(c.right, c.fwd);
    c.f = (float)h * 0.5f / (float)tan((double)(0.5f * 45.0f * 3.14159265f / 180.0f));
    c.cx = (float)w * 0.5f;
    c.cy = (float)h * 0.5f;
    return c;
}

void viz_camera_ray(const viz_camera *c, float px, float py, sidx_vec3 *org, sidx_vec3 *dir)
{
    *org = c->eye;
    *dir = v3norm(sidx_v3_add(c->fwd, sidx_v3_add(sidx_v3_scale(c->right, (px - c->cx) / c->f),
                                                  sidx_v3_scale(c->up, -(py - c->cy) / c->f))));
}

typedef struct step_count { uint32_t n; } step_count;
static void count_fn(const sidx_event *ev, void *user)
{
    (void)ev;
    ((step_count *)user)->n++;
}

uint32_t viz_heat_counts(const sidx_accel *a, const viz_camera *c, int w, int h, int ps, uint32_t mask,
                         uint32_t *counts)
{
    step_count sc = {0};
    sidx_hook hook = {count_fn, &sc, mask};
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.flags = SIDX_QUERY_NORMAL;
    q.hook = &hook;
    if (ps < 1) ps = 1;
    uint32_t maxc = 0;
    for (int y = 0; y < h; y += ps)
        for (int x = 0; x < w; x += ps) {
            sidx_vec3 org, dir;
            viz_camera_ray(c, (float)x + 0.5f * (float)ps, (float)y + 0.5f * (float)ps, &org, &dir);
            sidx_ray r;
            sc.n = 0;
            if (a && sidx_ray_init(&r, org, dir, 0.0f, INFINITY) == SIDX_OK) {
                sidx_hit hit;
                sidx_accel_intersect(a, &r, &q, &hit);
            }
            if (sc.n > maxc) maxc = sc.n;
            counts[(size_t)y * (size_t)w + (size_t)x] = sc.n;
        }
    return maxc;
}
