/* view_draw.c — a tiny rasteriser on 32-bit ARGB pixels: blended pixels,
 * rectangles, lines (DDA), filled triangles (edge functions) and circles.
 * Everything is clipped to the canvas clip rectangle. */
#include <math.h>
#include "view.h"

void viz_canvas_from_surface(viz_canvas *cv, SDL_Surface *s)
{
    cv->px = (uint32_t *)s->pixels;
    cv->w = s->w;
    cv->h = s->h;
    cv->stride = s->pitch / 4;
    viz_clip(cv, 0, 0, 0, 0);
}

void viz_clip(viz_canvas *cv, int x, int y, int w, int h)
{
    if (w <= 0 || h <= 0) {
        cv->cx0 = 0;
        cv->cy0 = 0;
        cv->cx1 = cv->w;
        cv->cy1 = cv->h;
        return;
    }
    cv->cx0 = x < 0 ? 0 : x;
    cv->cy0 = y < 0 ? 0 : y;
    cv->cx1 = x + w > cv->w ? cv->w : x + w;
    cv->cy1 = y + h > cv->h ? cv->h : y + h;
}

uint32_t viz_rgba(int r, int g, int b, int a)
{
#define CLAMP8(v) ((uint32_t)((v) < 0 ? 0 : (v) > 255 ? 255 : (v)))
    return CLAMP8(a) << 24 | CLAMP8(r) << 16 | CLAMP8(g) << 8 | CLAMP8(b);
#undef CLAMP8
}

static inline uint32_t blend(uint32_t dst, uint32_t src)
{
    uint32_t a = src >> 24;
    if (a == 255) return src;
    if (a == 0) return dst;
    uint32_t ia = 255 - a;
    uint32_t r = (((src >> 16) & 255) * a + ((dst >> 16) & 255) * ia) / 255;
    uint32_t g = (((src >> 8) & 255) * a + ((dst >> 8) & 255) * ia) / 255;
    uint32_t b = ((src & 255) * a + (dst & 255) * ia) / 255;
    return 0xff000000u | r << 16 | g << 8 | b;
}

void viz_pixel(viz_canvas *cv, int x, int y, uint32_t color)
{
    if (x < cv->cx0 || y < cv->cy0 || x >= cv->cx1 || y >= cv->cy1) return;
    uint32_t *p = &cv->px[(size_t)y * (size_t)cv->stride + (size_t)x];
    *p = blend(*p, color);
}

void viz_clear(viz_canvas *cv, uint32_t color)
{
    for (int y = 0; y < cv->h; ++y)
        for (int x = 0; x < cv->w; ++x) cv->px[(size_t)y * (size_t)cv->stride + (size_t)x] = color | 0xff000000u;
}

void viz_fill_rect(viz_canvas *cv, int x, int y, int w, int h, uint32_t color)
{
    int x0 = x < cv->cx0 ? cv->cx0 : x, y0 = y < cv->cy0 ? cv->cy0 : y;
    int x1 = x + w > cv->cx1 ? cv->cx1 : x + w, y1 = y + h > cv->cy1 ? cv->cy1 : y + h;
    for (int yy = y0; yy < y1; ++yy) {
        uint32_t *row = &cv->px[(size_t)yy * (size_t)cv->stride];
        for (int xx = x0; xx < x1; ++xx) row[xx] = blend(row[xx], color);
    }
}

void viz_rect(viz_canvas *cv, int x, int y, int w, int h, uint32_t color)
{
    if (w <= 0 || h <= 0) return;
    viz_fill_rect(cv, x, y, w, 1, color);
    if (h > 1) viz_fill_rect(cv, x, y + h - 1, w, 1, color);
    if (h > 2) {
        viz_fill_rect(cv, x, y + 1, 1, h - 2, color);
        if (w > 1) viz_fill_rect(cv, x + w - 1, y + 1, 1, h - 2, color);
    }
}

/* Clips the segment to a generous box first so huge coordinates (a ray to
 * infinity) never make the DDA loop run long (Liang–Barsky). */
static int clip_segment(const viz_canvas *cv, float *x0, float *y0, float *x1, float *y1)
{
    const float xmin = (float)cv->cx0 - 2.0f, ymin = (float)cv->cy0 - 2.0f;
    const float xmax = (float)cv->cx1 + 2.0f, ymax = (float)cv->cy1 + 2.0f;
    if (!isfinite(*x0) || !isfinite(*y0) || !isfinite(*x1) || !isfinite(*y1)) return 0;
    float dx = *x1 - *x0, dy = *y1 - *y0, t0 = 0.0f, t1 = 1.0f;
    const float p[4] = {-dx, dx, -dy, dy};
    const float q[4] = {*x0 - xmin, xmax - *x0, *y0 - ymin, ymax - *y0};
    for (int i = 0; i < 4; ++i) {
        if (p[i] == 0.0f) {
            if (q[i] < 0.0f) return 0;
            continue;
        }
        float r = q[i] / p[i];
        if (p[i] < 0.0f) {
            if (r > t1) return 0;
            if (r > t0) t0 = r;
        } else {
            if (r < t0) return 0;
            if (r < t1) t1 = r;
        }
    }
    float ax = *x0 + t0 * dx, ay = *y0 + t0 * dy;
    *x1 = *x0 + t1 * dx;
    *y1 = *y0 + t1 * dy;
    *x0 = ax;
    *y0 = ay;
    return 1;
}

static void line_impl(viz_canvas *cv, float x0, float y0, float x1, float y1, int dash, uint32_t color)
{
    if (!clip_segment(cv, &x0, &y0, &x1, &y1)) return;
    float dx = x1 - x0, dy = y1 - y0;
    float len = fabsf(dx) > fabsf(dy) ? fabsf(dx) : fabsf(dy);
    int n = (int)ceilf(len);
    if (n < 1) n = 1;
    for (int i = 0; i <= n; ++i) {
        if (dash > 0 && (i / dash) % 2 == 1) continue;
        float t = (float)i / (float)n;
        viz_pixel(cv, (int)floorf(x0 + t * dx + 0.5f), (int)floorf(y0 + t * dy + 0.5f), color);
    }
}

void viz_line(viz_canvas *cv, float x0, float y0, float x1, float y1, uint32_t color)
{
    line_impl(cv, x0, y0, x1, y1, 0, color);
}

void viz_dashed_line(viz_canvas *cv, float x0, float y0, float x1, float y1, int dash, uint32_t color)
{
    line_impl(cv, x0, y0, x1, y1, dash, color);
}

void viz_thick_line(viz_canvas *cv, float x0, float y0, float x1, float y1, int width, uint32_t color)
{
    if (width <= 1) {
        viz_line(cv, x0, y0, x1, y1, color);
        return;
    }
    float dx = x1 - x0, dy = y1 - y0, len = sqrtf(dx * dx + dy * dy);
    if (!(len > 0.0f) || !isfinite(len)) {
        viz_fill_circle(cv, x0, y0, (float)width * 0.5f, color);
        return;
    }
    if (!clip_segment(cv, &x0, &y0, &x1, &y1)) return;
    float nx = -dy / len * (float)width * 0.5f, ny = dx / len * (float)width * 0.5f;
    /* two triangles: blended colours would double up on a shared edge, so
     * draw opaque quads as triangles and translucent ones as parallel lines */
    if ((color >> 24) == 255) {
        viz_fill_triangle(cv, x0 + nx, y0 + ny, x1 + nx, y1 + ny, x1 - nx, y1 - ny, color);
        viz_fill_triangle(cv, x0 + nx, y0 + ny, x1 - nx, y1 - ny, x0 - nx, y0 - ny, color);
    } else {
        for (int k = 0; k < width; ++k) {
            float f = ((float)k + 0.5f) / (float)width * 2.0f - 1.0f;
            viz_line(cv, x0 + nx * f, y0 + ny * f, x1 + nx * f, y1 + ny * f, color);
        }
    }
}

void viz_fill_triangle(viz_canvas *cv, float x0, float y0, float x1, float y1, float x2, float y2, uint32_t color)
{
    float area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
    if (area == 0.0f || !isfinite(area)) return;
    if (area < 0.0f) { /* make it counter-clockwise in screen space */
        float tx = x1, ty = y1;
        x1 = x2; y1 = y2;
        x2 = tx; y2 = ty;
    }
    float fxmin = fminf(x0, fminf(x1, x2)), fxmax = fmaxf(x0, fmaxf(x1, x2));
    float fymin = fminf(y0, fminf(y1, y2)), fymax = fmaxf(y0, fmaxf(y1, y2));
    if (fxmax < (float)cv->cx0 || fymax < (float)cv->cy0 || fxmin >= (float)cv->cx1 || fymin >= (float)cv->cy1) return;
    int xmin = (int)floorf(fxmin), xmax = (int)ceilf(fxmax), ymin = (int)floorf(fymin), ymax = (int)ceilf(fymax);
    if (xmin < cv->cx0) xmin = cv->cx0;
    if (ymin < cv->cy0) ymin = cv->cy0;
    if (xmax > cv->cx1 - 1) xmax = cv->cx1 - 1;
    if (ymax > cv->cy1 - 1) ymax = cv->cy1 - 1;
    for (int y = ymin; y <= ymax; ++y) {
        float py = (float)y + 0.5f;
        for (int x = xmin; x <= xmax; ++x) {
            float px = (float)x + 0.5f;
            float w0 = (x1 - x0) * (py - y0) - (y1 - y0) * (px - x0);
            float w1 = (x2 - x1) * (py - y1) - (y2 - y1) * (px - x1);
            float w2 = (x0 - x2) * (py - y2) - (y0 - y2) * (px - x2);
            if (w0 >= 0.0f && w1 >= 0.0f && w2 >= 0.0f) viz_pixel(cv, x, y, color);
        }
    }
}

void viz_fill_circle(viz_canvas *cv, float cx, float cy, float r, uint32_t color)
{
    if (!isfinite(cx) || !isfinite(cy) || !(r > 0.0f)) return;
    int x0 = (int)floorf(cx - r), x1 = (int)ceilf(cx + r), y0 = (int)floorf(cy - r), y1 = (int)ceilf(cy + r);
    if (x0 < cv->cx0) x0 = cv->cx0;
    if (y0 < cv->cy0) y0 = cv->cy0;
    if (x1 > cv->cx1 - 1) x1 = cv->cx1 - 1;
    if (y1 > cv->cy1 - 1) y1 = cv->cy1 - 1;
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            float dx = (float)x + 0.5f - cx, dy = (float)y + 0.5f - cy;
            if (dx * dx + dy * dy <= r * r) viz_pixel(cv, x, y, color);
        }
}

uint32_t viz_depth_color(uint32_t depth, int alpha)
{
    static const uint8_t pal[8][3] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44}, {214, 39, 40},
                                      {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {23, 190, 207}};
    const uint8_t *c = pal[depth % 8];
    return viz_rgba(c[0], c[1], c[2], alpha);
}

uint32_t viz_heat_color(float f)
{
    if (!(f > 0.0f)) return viz_rgba(0, 0, 0, 255);
    if (f > 1.0f) f = 1.0f;
    /* black → blue → magenta → red → yellow → white */
    static const float stops[6][3] = {{0, 0, 0}, {20, 40, 200}, {170, 30, 170}, {230, 40, 30}, {250, 220, 40},
                                      {255, 255, 255}};
    float s = f * 5.0f;
    int i = (int)s;
    if (i >= 5) i = 4;
    float u = s - (float)i;
    return viz_rgba((int)(stops[i][0] + u * (stops[i + 1][0] - stops[i][0])),
                    (int)(stops[i][1] + u * (stops[i + 1][1] - stops[i][1])),
                    (int)(stops[i][2] + u * (stops[i + 1][2] - stops[i][2])), 255);
}
