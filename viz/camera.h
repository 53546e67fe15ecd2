/* camera.h — the pinhole camera of sidx-view's 3D and heat modes and of
 * the lab's heat map (viz/lab.c), and the heat map's per-pixel counts:
 * one definition of which ray goes through which pixel, so the viewer,
 * its screenshots and the web page shoot the same rays.  No SDL.  Not
 * installed. */
#ifndef SIDX_VIZ_CAMERA_H
#define SIDX_VIZ_CAMERA_H

#include <stdint.h>
#include "sidx/sidx.h"

typedef struct viz_camera { sidx_vec3 eye, fwd, right, up; float f, cx, cy; } viz_camera;

/* The camera orbiting the centre of `bounds` at yaw and pitch (radians),
 * 2.4 bounding radii away divided by zoom (at least 0.05), 45 degree
 * vertical field of view, for a w×h image. */
viz_camera viz_camera_make(sidx_aabb bounds, float yaw, float pitch, float zoom, int w, int h);
/* The ray through image point (px, py) (pixel x's centre is x + 0.5):
 * origin the eye, direction normalised. */
void viz_camera_ray(const viz_camera *c, float px, float py, sidx_vec3 *org, sidx_vec3 *dir);

/* The heat map's counts: for every ps-th pixel (x, y) of a w×h image the
 * events in `mask` the ray through its centre region (x + ps/2, y + ps/2)
 * emits in one closest-hit query on a, written to counts[y * w + x] (the
 * other pixels are left alone).  Returns the largest count. */
uint32_t viz_heat_counts(const sidx_accel *a, const viz_camera *c, int w, int h, int ps, uint32_t mask,
                         uint32_t *counts);

#endif
