/* view_render.c — drawing the viewer's modes onto a canvas.
 *
 *  2D     the scene seen from +z, the structure's boxes / cells from the
 *         BUILD_NODE events, the ray and the replayed traversal: current
 *         node, stack with t_near/t_far, tested primitives, best hit.
 *  build  the build events one by one: nodes appear, the current node and
 *         its split are highlighted, candidate SAH costs plotted as curves.
 *  3D     pinhole camera, shaded by the geometric normal; boxes of tree
 *         level k; a picked pixel's ray.
 *  heat   traversal steps (nodes entered + primitive tests) per pixel. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <SDL_image.h>
#include "camera.h"
#include "view.h"

#define PANEL_BG 0xff1f232bu
#define PANEL_FG 0xffe6e6e6u
#define PANEL_DIM 0xff9aa3b0u
#define PANEL_HI 0xffffc14du
#define SCENE_BG 0xfff7f6f0u

int view_scene_width(int w)
{
    int panel = w >= 900 ? 340 : w / 3;
    return w - panel;
}

/* ---- 2D mapping ----------------------------------------------------------------- */

typedef struct map2d { float sx, ox, oy; int h; } map2d;

static map2d make_map(const view_state *v, int sw, int h)
{
    map2d m;
    sidx_aabb b = v->bounds;
    if (sidx_aabb_is_empty(b)) b.min = b.max = sidx_v3(0, 0, 0);
    float ex = b.max.x - b.min.x, ey = b.max.y - b.min.y;
    if (!(ex > 0.0f)) ex = 1.0f;
    if (!(ey > 0.0f)) ey = 1.0f;
    const float pad = 0.06f;
    float s1 = (float)sw / (ex * (1.0f + 2.0f * pad)), s2 = (float)h / (ey * (1.0f + 2.0f * pad));
    m.sx = s1 < s2 ? s1 : s2;
    float cx = 0.5f * (b.min.x + b.max.x), cy = 0.5f * (b.min.y + b.max.y);
    m.ox = (float)sw * 0.5f - cx * m.sx;
    m.oy = (float)h * 0.5f + cy * m.sx;
    m.h = h;
    return m;
}
static inline float mx(const map2d *m, float x) { return m->ox + x * m->sx; }
static inline float my(const map2d *m, float y) { return m->oy - y * m->sx; }

void view_2d_to_world(const view_state *v, int w, int h, float sx, float sy, float *x, float *y)
{
    map2d m = make_map(v, view_scene_width(w), h);
    *x = (sx - m.ox) / m.sx;
    *y = (m.oy - sy) / m.sx;
}

static void box2d(viz_canvas *cv, const map2d *m, sidx_aabb b, uint32_t color, int fill)
{
    if (sidx_aabb_is_empty(b)) return;
    float x0 = mx(m, b.min.x), x1 = mx(m, b.max.x), y0 = my(m, b.max.y), y1 = my(m, b.min.y);
    if (!isfinite(x0) || !isfinite(x1) || !isfinite(y0) || !isfinite(y1)) return;
    int ix = (int)floorf(x0), iy = (int)floorf(y0);
    int iw = (int)ceilf(x1) - ix + 1, ih = (int)ceilf(y1) - iy + 1;
    if (fill)
        viz_fill_rect(cv, ix, iy, iw, ih, color);
    else
        viz_rect(cv, ix, iy, iw, ih, color);
}

static void dashed_box2d(viz_canvas *cv, const map2d *m, sidx_aabb b, uint32_t color)
{
    if (sidx_aabb_is_empty(b)) return;
    float x0 = mx(m, b.min.x), x1 = mx(m, b.max.x), y0 = my(m, b.max.y), y1 = my(m, b.min.y);
    viz_dashed_line(cv, x0, y0, x1, y0, 4, color);
    viz_dashed_line(cv, x1, y0, x1, y1, 4, color);
    viz_dashed_line(cv, x1, y1, x0, y1, 4, color);
    viz_dashed_line(cv, x0, y1, x0, y0, 4, color);
}

static void thick_box2d(viz_canvas *cv, const map2d *m, sidx_aabb b, int width, uint32_t color)
{
    if (sidx_aabb_is_empty(b)) return;
    float x0 = mx(m, b.min.x), x1 = mx(m, b.max.x), y0 = my(m, b.max.y), y1 = my(m, b.min.y);
    viz_thick_line(cv, x0, y0, x1, y0, width, color);
    viz_thick_line(cv, x1, y0, x1, y1, width, color);
    viz_thick_line(cv, x1, y1, x0, y1, width, color);
    viz_thick_line(cv, x0, y1, x0, y0, width, color);
}

/* The height at which a 2D scene's shapes are cut for their spines: the
 * ray's plane if the ray stays in one z plane, else the scene's middle.
 * NAN for a scene that is not flat (z extent under 5% of x and y). */
static float spine_height(const view_state *v)
{
    const sidx_vec3 e = sidx_aabb_extent(v->bounds);
    if (sidx_aabb_is_empty(v->bounds) || !(e.z > 0.0f) || !(e.z < 0.05f * fminf(e.x, e.y))) return NAN;
    return v->has_ray && v->dir.z == 0.0f ? v->org.z : 0.5f * (v->bounds.min.z + v->bounds.max.z);
}

/* The segment where triangle (a, b, c) crosses the plane z = z0: what a
 * ray in that plane can hit (flat2d tilts each shape so this is its
 * longest median, lib/scenes.c).  0 if it does not cross in a segment. */
static int spine(sidx_vec3 a, sidx_vec3 b, sidx_vec3 c, float z0, float seg[4])
{
    const sidx_vec3 p[3] = {a, b, c};
    int n = 0;
    for (int k = 0; k < 3 && n <= 2; ++k) {
        const sidx_vec3 u = p[k], w = p[(k + 1) % 3];
        const float du = u.z - z0, dw = w.z - z0;
        float x, y;
        if (du == 0.0f) {
            x = u.x;
            y = u.y;
        } else if ((du < 0.0f) != (dw < 0.0f) && dw != 0.0f) {
            const float s = du / (du - dw);
            x = u.x + s * (w.x - u.x);
            y = u.y + s * (w.y - u.y);
        } else {
            continue;
        }
        if (n < 2) {
            seg[2 * n] = x;
            seg[2 * n + 1] = y;
        }
        ++n;
    }
    return n == 2 && (seg[0] != seg[2] || seg[1] != seg[3]);
}

/* Triangles seen from +z; in a 2D scene each with its spine, the segment
 * a ray in the plane actually hits, so a ray that only clips a corner is
 * seen to miss.  Edge-on triangles are drawn as segments. */
static void draw_triangles(const view_state *v, viz_canvas *cv, const map2d *m, int marked_pass)
{
    static const uint32_t fill[4] = {0xffc9d3e0u, 0xff8fb3e8u, 0xff5cb85cu, 0xffc49ae8u};
    static const uint32_t edge[4] = {0xff8792a3u, 0xff3f6fb8u, 0xff1e7b1eu, 0xff7d3fb8u};
    static const uint32_t spine_col[4] = {0xff4b5566u, 0xff1f4f98u, 0xff0e5b0eu, 0xff5d1f98u};
    const float z0 = spine_height(v);
    for (uint32_t t = 0; t < v->mesh.num_triangles; ++t) {
        int mark = v->prim_mark ? v->prim_mark[t] : 0;
        if ((mark != 0) != (marked_pass != 0)) continue;
        sidx_vec3 a = sidx_mesh_vertex(&v->mesh, t, 0), b = sidx_mesh_vertex(&v->mesh, t, 1),
                  c = sidx_mesh_vertex(&v->mesh, t, 2);
        float ax = mx(m, a.x), ay = my(m, a.y), bx = mx(m, b.x), by = my(m, b.y), cx = mx(m, c.x), cy = my(m, c.y);
        float area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
        if (fabsf(area) > 0.5f) {
            viz_fill_triangle(cv, ax, ay, bx, by, cx, cy, fill[mark]);
            viz_line(cv, ax, ay, bx, by, edge[mark]);
            viz_line(cv, bx, by, cx, cy, edge[mark]);
            viz_line(cv, cx, cy, ax, ay, edge[mark]);
            float seg[4];
            if (isfinite(z0) && spine(a, b, c, z0, seg))
                viz_thick_line(cv, mx(m, seg[0]), my(m, seg[1]), mx(m, seg[2]), my(m, seg[3]), 2, spine_col[mark]);
        } else if (mark) {
            int w = mark == 2 ? 4 : 3;
            viz_thick_line(cv, ax, ay, bx, by, w, edge[mark]);
            viz_thick_line(cv, bx, by, cx, cy, w, edge[mark]);
            viz_thick_line(cv, cx, cy, ax, ay, w, edge[mark]);
        }
    }
}

/* t where the ray leaves the (padded) scene box, for drawing it. */
static float ray_draw_end(const view_state *v)
{
    sidx_aabb b = v->bounds;
    sidx_vec3 e = sidx_aabb_extent(b);
    float pad = 0.5f * (e.x + e.y + e.z) + 1.0f;
    b.min = sidx_v3_sub(b.min, sidx_v3(pad, pad, pad));
    b.max = sidx_v3_add(b.max, sidx_v3(pad, pad, pad));
    float tfar = INFINITY;
    const float o[3] = {v->org.x, v->org.y, v->org.z}, d[3] = {v->dir.x, v->dir.y, v->dir.z};
    const float lo[3] = {b.min.x, b.min.y, b.min.z}, hi[3] = {b.max.x, b.max.y, b.max.z};
    for (int i = 0; i < 3; ++i) {
        if (d[i] == 0.0f) continue;
        float t1 = (lo[i] - o[i]) / d[i], t2 = (hi[i] - o[i]) / d[i];
        float tf = t1 > t2 ? t1 : t2;
        if (tf < tfar) tfar = tf;
    }
    return isfinite(tfar) && tfar > 0.0f ? tfar : 1.0f;
}

/* ---- text panel ------------------------------------------------------------------- */

typedef struct panel { viz_canvas *cv; int x, y, w, y_end; } panel;

static void pline(panel *p, uint32_t color, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static void pline(panel *p, uint32_t color, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    int max_chars = (p->w - 12) / VIZ_FONT_W;
    if (max_chars < 4) max_chars = 4;
    /* wrap long lines */
    const char *s = buf;
    size_t len = strlen(s);
    int first = 1;
    while ((len > 0 || first) && p->y + VIZ_FONT_H <= p->y_end) {
        char part[256];
        size_t n = len > (size_t)max_chars ? (size_t)max_chars : len;
        if (!first && n > (size_t)max_chars - 2) n = (size_t)max_chars - 2;
        if (n >= sizeof part - 3) n = sizeof part - 3;
        snprintf(part, sizeof part, "%s%.*s", first ? "" : "  ", (int)n, s);
        viz_text(p->cv, p->x + 6, p->y, 1, color, part);
        p->y += VIZ_FONT_H;
        s += n;
        len -= n;
        first = 0;
    }
}

static void pgap(panel *p) { p->y += 4; }

static void event_text(const sidx_event *ev, char *buf, size_t size)
{
    if (sidx_event_format(ev, buf, size) < 0) snprintf(buf, size, "?");
}

/* The events around index cur (cur = index of the current event, or -1). */
static void event_log(panel *p, const sidx_event *ev, size_t count, long cur, int lines)
{
    if (count == 0 || lines <= 0) return;
    long first = cur - lines / 2;
    if (first + lines > (long)count) first = (long)count - lines;
    if (first < 0) first = 0;
    int max_chars = (p->w - 12) / VIZ_FONT_W;
    for (long i = first; i < first + lines && i < (long)count; ++i) {
        if (p->y + VIZ_FONT_H > p->y_end) break;
        char buf[256], line[300];
        event_text(&ev[i], buf, sizeof buf);
        size_t lead = strspn(buf, " "); /* deep trees: keep at most 8 levels of indentation */
        const char *txt = lead > 16 ? buf + (lead - 16) : buf;
        snprintf(line, sizeof line, "%4ld %s", i + 1, txt);
        if ((int)strlen(line) > max_chars && max_chars > 0) line[max_chars] = '\0';
        if (i == cur) viz_fill_rect(p->cv, p->x + 2, p->y - 1, p->w - 4, VIZ_FONT_H, 0xff3a4454u);
        viz_text(p->cv, p->x + 6, p->y, 1, i == cur ? PANEL_HI : i < cur ? PANEL_FG : PANEL_DIM, line);
        p->y += VIZ_FONT_H;
    }
}

static void legend_swatch(panel *p, uint32_t color, const char *label, int col)
{
    int x = p->x + 6 + col * (p->w / 2);
    viz_fill_rect(p->cv, x, p->y, 10, 7, color);
    viz_text(p->cv, x + 14, p->y, 1, PANEL_FG, label);
}

static void tree_summary(const view_state *v, panel *p)
{
    if (v->has_tree)
        pline(p, PANEL_FG, "accel: %s  %zu nodes, %u leaves, depth %u", v->accel_name, v->tree.count, v->tree.leaves,
              v->tree.max_depth);
    else {
        pline(p, PANEL_FG, "accel: %s", v->accel_name);
        pline(p, PANEL_DIM, "(%s)", v->tree_msg[0] ? v->tree_msg : "no tree");
    }
}

/* " (L4)" for a node the structure labels (sidx_accel_node_label: a slide's names), else "". */
static const char *node_tag(const view_state *v, uint32_t id, char tag[48])
{
    const char *label = sidx_accel_node_label(v->accel, id);
    tag[0] = '\0';
    if (label) snprintf(tag, 48, " (%s)", label);
    return tag;
}

static void traversal_panel(const view_state *v, panel *p, const view_replay *r)
{
    char tag[48];
    if (!v->has_ray && !v->trace_path[0]) {
        pline(p, PANEL_DIM, "no ray: drag with the mouse to shoot one");
        return;
    }
    if (v->trace_path[0]) pline(p, PANEL_FG, "events of %s", v->trace_path);
    if (v->has_ray) {
        pline(p, PANEL_FG, "ray o=(%.3g, %.3g, %.3g)", (double)v->org.x, (double)v->org.y, (double)v->org.z);
        pline(p, PANEL_FG, "    d=(%.3g, %.3g, %.3g)", (double)v->dir.x, (double)v->dir.y, (double)v->dir.z);
    } else {
        pline(p, PANEL_DIM, "ray not given (--ray draws it)");
    }
    pline(p, PANEL_HI, "step %zu / %zu%s", v->step, v->trav.count, v->playing ? "  (playing)" : "");
    pgap(p);
    if (r->best_prim != SIDX_NO_HIT)
        pline(p, 0xff7ee07eu, "best hit: prim %u  t=%.4g", r->best_prim, (double)r->best_t);
    else
        pline(p, PANEL_FG, "best hit: none yet");
    pline(p, PANEL_FG, "entered %u  boxes %u  prims %u  mailbox %u", r->nodes_entered, r->box_tests, r->prim_tests,
          r->mailbox_hits);
    if (r->current_id != SIDX_VIZ_NONE)
        pline(p, PANEL_FG, "current node %u%s  t=[%.3g, %.3g]", r->current_id, node_tag(v, r->current_id, tag),
              (double)r->cur_t_near, (double)r->cur_t_far);
    pgap(p);
    pline(p, PANEL_HI, "stack (top first): %d", r->stack_n + r->stack_more);
    for (int i = r->stack_n - 1, shown = 0; i >= 0 && shown < 8; --i, ++shown)
        pline(p, PANEL_FG, "  node %u%s  t=[%.3g, %.3g]", r->stack[i].node, node_tag(v, r->stack[i].node, tag),
              (double)r->stack[i].t_near, (double)r->stack[i].t_far);
    if (r->stack_n > 8) pline(p, PANEL_DIM, "  ... %d more", r->stack_n - 8 + r->stack_more);
    pgap(p);
    pline(p, PANEL_HI, "events");
    int room = (p->y_end - p->y - 40) / VIZ_FONT_H;
    event_log(p, v->trav.events, v->trav.count, (long)v->step - 1, room > 30 ? 30 : room);
}

/* ---- 2D and build modes ----------------------------------------------------------- */

/* A BSP plane n·p = d seen from +z: the segment of n.x·x + n.y·y = d inside box. */
static void plane2d(viz_canvas *cv, const map2d *m, sidx_vec3 n, float d, sidx_aabb b, int width, uint32_t color)
{
    if (sidx_aabb_is_empty(b) || fabsf(n.z) > 0.99f * sidx_v3_length(n)) return;
    const float zc = 0.5f * (b.min.z + b.max.z);
    const float dd = d - n.z * zc; /* the plane's trace at the box's middle z */
    float px[4], py[4];
    int k = 0;
    if (n.y != 0.0f) {
        const float xs[2] = {b.min.x, b.max.x};
        for (int i = 0; i < 2; ++i) {
            float y = (dd - n.x * xs[i]) / n.y;
            if (y >= b.min.y && y <= b.max.y) { px[k] = xs[i]; py[k] = y; ++k; }
        }
    }
    if (n.x != 0.0f) {
        const float ys[2] = {b.min.y, b.max.y};
        for (int i = 0; i < 2; ++i) {
            float x = (dd - n.y * ys[i]) / n.x;
            if (x >= b.min.x && x <= b.max.x) { px[k] = x; py[k] = ys[i]; ++k; }
        }
    }
    if (k >= 2) viz_thick_line(cv, mx(m, px[0]), my(m, py[0]), mx(m, px[k - 1]), my(m, py[k - 1]), width, color);
}

static void draw_structure_2d(const view_state *v, viz_canvas *cv, const map2d *m, size_t limit)
{
    if (v->has_tree) /* BSP: the arbitrary planes, clipped to their node */
        for (size_t i = 0; i < v->tree.count; ++i) {
            const sidx_viz_node *nd = &v->tree.nodes[i];
            if (nd->has_split && nd->axis < 0 && nd->build_event < limit)
                plane2d(cv, m, nd->plane_n, nd->pos, nd->bounds, 1, 0xff404040u);
        }
    /* every BUILD_NODE box, also when the events do not form a tree (grid cells) */
    for (size_t i = 0; i < limit && i < v->build.count; ++i) {
        const sidx_event *e = &v->build.events[i];
        /* the irregular grid's construction as it goes: base cells (thin),
         * then each merged box (a box given with its extent) */
        if ((e->type == SIDX_EV_BUILD_LEAF || e->type == SIDX_EV_BUILD_MERGE) && e->extent[0] > 0)
            box2d(cv, m, e->bounds, e->type == SIDX_EV_BUILD_LEAF ? 0x60a0a0a0u : 0xff40a0ffu, 0);
        if (e->type != SIDX_EV_BUILD_NODE) continue;
        uint32_t d = e->depth == UINT32_MAX ? 0 : e->depth;
        box2d(cv, m, e->bounds, viz_depth_color(d, d == 0 ? 200 : 150), 0);
    }
}

/* The labels of labelled nodes, as the slide writes them: a leaf's in the
 * middle of its cell, an inner node's at the top or left end of its split
 * line; only nodes the build has made by `limit` events. */
static void labels_2d(const view_state *v, viz_canvas *cv, const map2d *m, size_t limit)
{
    if (!v->has_tree || !v->accel) return;
    for (size_t i = 0; i < v->tree.count; ++i) {
        const sidx_viz_node *nd = &v->tree.nodes[i];
        const char *label = sidx_accel_node_label(v->accel, nd->id);
        if (!label || nd->build_event >= limit || sidx_aabb_is_empty(nd->bounds)) continue;
        const sidx_aabb b = nd->bounds;
        float x = 0.5f * (b.min.x + b.max.x), y = 0.5f * (b.min.y + b.max.y);
        if (nd->has_split && nd->axis == 0) x = nd->pos, y = b.max.y;
        else if (nd->has_split && nd->axis == 1) x = b.min.x, y = nd->pos;
        const int sx = (int)mx(m, x) + (nd->has_split ? 4 : -8), sy = (int)my(m, y) + (nd->has_split ? 4 : -8);
        viz_text(cv, sx, sy, 2, nd->is_leaf ? 0xff206020u : 0xff202080u, label);
    }
}

static void sah_plot(const view_state *v, panel *p, uint32_t node_id, size_t upto)
{
    int x0 = p->x + 8, w = p->w - 16, h = 120;
    if (p->y + h + 16 > p->y_end) return;
    int y0 = p->y;
    float pmin = INFINITY, pmax = -INFINITY, cmin = INFINITY, cmax = -INFINITY;
    size_t n = 0;
    const sidx_event *split = NULL;
    for (size_t i = 0; i < upto && i < v->build.count; ++i) {
        const sidx_event *e = &v->build.events[i];
        if (e->node != node_id) continue;
        if (e->type == SIDX_EV_BUILD_SPLIT) split = e;
        if (e->type != SIDX_EV_BUILD_CANDIDATE || !isfinite(e->pos) || !isfinite(e->cost)) continue;
        pmin = fminf(pmin, e->pos);
        pmax = fmaxf(pmax, e->pos);
        cmin = fminf(cmin, e->cost);
        cmax = fmaxf(cmax, e->cost);
        ++n;
    }
    pline(p, PANEL_HI, "SAH cost over split position (node %u)", node_id);
    y0 = p->y;
    viz_fill_rect(p->cv, x0, y0, w, h, 0xff2a2f39u);
    viz_rect(p->cv, x0, y0, w, h, 0xff55606eu);
    if (n == 0) {
        viz_text(p->cv, x0 + 6, y0 + 6, 1, PANEL_DIM, "no candidates for this node");
        p->y = y0 + h + 4;
        return;
    }
    if (!(pmax > pmin)) { pmin -= 0.5f; pmax += 0.5f; }
    if (!(cmax > cmin)) { cmin -= 0.5f; cmax += 0.5f; }
    static const uint32_t axis_col[3] = {0xffff6b6bu, 0xff6bdc6bu, 0xff6ba8ffu};
    float last_x[3] = {NAN, NAN, NAN}, last_y[3] = {NAN, NAN, NAN};
    for (size_t i = 0; i < upto && i < v->build.count; ++i) {
        const sidx_event *e = &v->build.events[i];
        if (e->node != node_id || e->type != SIDX_EV_BUILD_CANDIDATE || !isfinite(e->pos) || !isfinite(e->cost))
            continue;
        int a = e->axis >= 0 && e->axis < 3 ? e->axis : 0;
        float px = (float)x0 + 4.0f + (e->pos - pmin) / (pmax - pmin) * (float)(w - 8);
        float py = (float)(y0 + h - 4) - (e->cost - cmin) / (cmax - cmin) * (float)(h - 8);
        if (isfinite(last_x[a])) viz_line(p->cv, last_x[a], last_y[a], px, py, axis_col[a]);
        viz_fill_circle(p->cv, px, py, 1.6f, axis_col[a]);
        last_x[a] = px;
        last_y[a] = py;
    }
    if (split && isfinite(split->pos) && split->pos >= pmin && split->pos <= pmax) {
        float px = (float)x0 + 4.0f + (split->pos - pmin) / (pmax - pmin) * (float)(w - 8);
        viz_dashed_line(p->cv, px, (float)y0 + 2.0f, px, (float)(y0 + h - 2), 3, PANEL_HI);
    }
    p->y = y0 + h + 3;
    pline(p, PANEL_DIM, "pos %.3g..%.3g  cost %.3g..%.3g  (x red, y green, z blue)", (double)pmin, (double)pmax,
          (double)cmin, (double)cmax);
}

static void render_2d(view_state *v, viz_canvas *cv, int build_mode)
{
    const int sw = view_scene_width(cv->w), h = cv->h;
    map2d m = make_map(v, sw, h);
    view_replay r;
    view_replay_run(v, build_mode ? 0 : v->step, &r);

    viz_clip(cv, 0, 0, sw, h);
    viz_fill_rect(cv, 0, 0, sw, h, SCENE_BG);
    draw_triangles(v, cv, &m, 0);

    const size_t limit = build_mode ? v->build_step : v->build.count;
    draw_structure_2d(v, cv, &m, limit);

    uint32_t cur_build_node = SIDX_VIZ_NONE;
    const sidx_event *cur_ev = NULL;
    if (build_mode && v->build_step > 0 && v->build_step <= v->build.count) {
        cur_ev = &v->build.events[v->build_step - 1];
        cur_build_node = cur_ev->node;
        uint32_t x = v->has_tree ? sidx_viz_tree_find(&v->tree, cur_build_node) : SIDX_VIZ_NONE;
        sidx_aabb b = x != SIDX_VIZ_NONE ? v->tree.nodes[x].bounds : cur_ev->bounds;
        if (cur_ev->type == SIDX_EV_BUILD_BEGIN) b = cur_ev->bounds;
        box2d(cv, &m, b, 0x40ff9900u, 1);
        thick_box2d(cv, &m, b, 3, 0xffff7f00u);
        if ((cur_ev->type == SIDX_EV_BUILD_SPLIT || cur_ev->type == SIDX_EV_BUILD_CANDIDATE) && cur_ev->axis < 0 &&
            isfinite(cur_ev->pos))
            plane2d(cv, &m, cur_ev->bounds.min, cur_ev->pos, b, 3,
                    cur_ev->type == SIDX_EV_BUILD_SPLIT ? 0xffd00000u : 0xc0d08000u);
        if ((cur_ev->type == SIDX_EV_BUILD_SPLIT || cur_ev->type == SIDX_EV_BUILD_CANDIDATE) &&
            (cur_ev->axis == 0 || cur_ev->axis == 1) && !sidx_aabb_is_empty(b) && isfinite(cur_ev->pos)) {
            uint32_t col = cur_ev->type == SIDX_EV_BUILD_SPLIT ? 0xffd00000u : 0xc0d08000u;
            if (cur_ev->axis == 0)
                viz_thick_line(cv, mx(&m, cur_ev->pos), my(&m, b.min.y), mx(&m, cur_ev->pos), my(&m, b.max.y), 3, col);
            else
                viz_thick_line(cv, mx(&m, b.min.x), my(&m, cur_ev->pos), mx(&m, b.max.x), my(&m, cur_ev->pos), 3, col);
        }
        /* a leaf just made: its primitives, as the event lists them */
        if (cur_ev->type == SIDX_EV_BUILD_LEAF && cur_ev->prims && v->prim_mark) {
            for (uint32_t i = 0; i < cur_ev->count; ++i)
                if (cur_ev->prims[i] < v->mesh.num_triangles) v->prim_mark[cur_ev->prims[i]] = 2;
            draw_triangles(v, cv, &m, 1);
        }
    }

    if (!build_mode && v->has_ray) {
        /* visited and pruned nodes */
        if (v->has_tree)
            for (size_t i = 0; i < v->tree.count; ++i) {
                const sidx_viz_node *nd = &v->tree.nodes[i];
                if (v->node_mark[i] == 1) /* outlines: nested fills would turn everything yellow */
                    thick_box2d(cv, &m, nd->bounds, 2, 0xffe0b000u);
                else if (v->node_mark[i] == 2)
                    dashed_box2d(cv, &m, nd->bounds, 0xffd02020u);
            }
        draw_triangles(v, cv, &m, 1);
        if (!sidx_aabb_is_empty(r.current_box)) {
            box2d(cv, &m, r.current_box, 0x50ff9900u, 1);
            thick_box2d(cv, &m, r.current_box, 3, 0xffff7f00u);
        }
        /* the ray, its current interval and the best hit */
        float tend = ray_draw_end(v);
        sidx_vec3 a = v->org, b = sidx_v3_add(v->org, sidx_v3_scale(v->dir, tend));
        viz_thick_line(cv, mx(&m, a.x), my(&m, a.y), mx(&m, b.x), my(&m, b.y), 2, 0xffa01010u);
        if (isfinite(r.cur_t_near) && isfinite(r.cur_t_far)) {
            sidx_vec3 p0 = sidx_v3_add(v->org, sidx_v3_scale(v->dir, r.cur_t_near));
            sidx_vec3 p1 = sidx_v3_add(v->org, sidx_v3_scale(v->dir, r.cur_t_far));
            viz_thick_line(cv, mx(&m, p0.x), my(&m, p0.y), mx(&m, p1.x), my(&m, p1.y), 6, 0xc0ff7f00u);
        }
        viz_fill_circle(cv, mx(&m, a.x), my(&m, a.y), 5.0f, 0xffa01010u);
        if (r.best_prim != SIDX_NO_HIT && isfinite(r.best_t)) {
            sidx_vec3 hp = sidx_v3_add(v->org, sidx_v3_scale(v->dir, r.best_t));
            viz_fill_circle(cv, mx(&m, hp.x), my(&m, hp.y), 7.0f, 0xff000000u);
            viz_fill_circle(cv, mx(&m, hp.x), my(&m, hp.y), 5.0f, 0xffff2020u);
            viz_textf(cv, (int)mx(&m, hp.x) + 9, (int)my(&m, hp.y) - 14, 1, 0xff000000u, "t=%.3g", (double)r.best_t);
        }
    }
    labels_2d(v, cv, &m, limit); /* on top of cells, triangles and the ray */
    viz_textf(cv, 8, 8, 2, 0xff333333u, "%s: %s", build_mode ? "build" : "2D", v->accel_name);

    /* panel */
    viz_clip(cv, sw, 0, cv->w - sw, h);
    viz_fill_rect(cv, sw, 0, cv->w - sw, h, PANEL_BG);
    panel p = {cv, sw, 8, cv->w - sw, h - 8};
    pline(&p, PANEL_HI, "sidx-view  %s mode", build_mode ? "build" : "2D");
    pline(&p, PANEL_FG, "scene: %s  (%u triangles)", v->scene, v->mesh.num_triangles);
    tree_summary(v, &p);
    pgap(&p);
    if (build_mode) {
        pline(&p, PANEL_HI, "build step %zu / %zu%s", v->build_step, v->build.count, v->playing ? "  (playing)" : "");
        if (cur_ev) {
            char buf[256];
            event_text(cur_ev, buf, sizeof buf);
            pline(&p, PANEL_FG, "%s", buf);
        }
        pgap(&p);
        int room = (p.y_end - p.y - 170) / VIZ_FONT_H;
        event_log(&p, v->build.events, v->build.count, (long)v->build_step - 1, room > 28 ? 28 : room);
        pgap(&p);
        if (cur_build_node != SIDX_VIZ_NONE) sah_plot(v, &p, cur_build_node, v->build_step);
    } else {
        traversal_panel(v, &p, &r);
        p.y = p.y_end - 3 * VIZ_FONT_H - 4;
        legend_swatch(&p, 0xffff7f00u, "current node", 0);
        legend_swatch(&p, 0xffd02020u, "box test missed", 1);
        p.y += VIZ_FONT_H;
        legend_swatch(&p, 0xff8fb3e8u, "prim tested", 0);
        legend_swatch(&p, 0xff5cb85cu, "prim hit", 1);
        p.y += VIZ_FONT_H;
        legend_swatch(&p, 0xffc49ae8u, "mailbox skip", 0);
        legend_swatch(&p, 0xffe0b000u, "visited", 1);
    }
    viz_clip(cv, 0, 0, 0, 0);
}

/* ---- 3D ------------------------------------------------------------------------------ */

typedef viz_camera camera;

static sidx_vec3 v3norm(sidx_vec3 a)
{
    float l = sidx_v3_length(a);
    return l > 0.0f ? sidx_v3_scale(a, 1.0f / l) : a;
}

/* The camera of viz/camera.c, shared with the web page's heat map. */
static camera make_camera(const view_state *v, int w, int h)
{
    return viz_camera_make(v->bounds, v->yaw, v->pitch, v->zoom, w, h);
}

void view_camera_ray(const view_state *v, float px, float py, int w, int h, sidx_vec3 *org, sidx_vec3 *dir)
{
    camera c = make_camera(v, w, h);
    viz_camera_ray(&c, px, py, org, dir);
}

static int project(const camera *c, sidx_vec3 p, float *sx, float *sy)
{
    sidx_vec3 d = sidx_v3_sub(p, c->eye);
    float z = sidx_v3_dot(d, c->fwd);
    if (z < 1e-3f) return 0;
    *sx = c->cx + sidx_v3_dot(d, c->right) / z * c->f;
    *sy = c->cy - sidx_v3_dot(d, c->up) / z * c->f;
    return 1;
}

static void box3d(viz_canvas *cv, const camera *c, sidx_aabb b, int width, uint32_t color)
{
    if (sidx_aabb_is_empty(b)) return;
    sidx_vec3 p[8];
    for (int i = 0; i < 8; ++i)
        p[i] = sidx_v3(i & 1 ? b.max.x : b.min.x, i & 2 ? b.max.y : b.min.y, i & 4 ? b.max.z : b.min.z);
    static const int edges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                     {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (int i = 0; i < 12; ++i) {
        float x0, y0, x1, y1;
        if (project(c, p[edges[i][0]], &x0, &y0) && project(c, p[edges[i][1]], &x1, &y1))
            viz_thick_line(cv, x0, y0, x1, y1, width, color);
    }
}

/* The heat map's colour for n steps when the busiest pixel took max: on a log scale,
 * log(1 + n) / log(1 + max).  Steps per pixel span three or four decades (a few dozen through
 * a tree, thousands in the one grid cell that holds the teapot in the stadium): on a linear
 * scale everything but the busiest pixels would be black. */
static float heat_fraction(uint32_t n, uint32_t max)
{
    return max ? (float)(log1p((double)n) / log1p((double)max)) : 0.0f;
}

static int render_image(view_state *v, int w, int h, view_mode mode)
{
    if (v->image && v->image_valid && v->image_w == w && v->image_h == h && v->image_mode == mode) return 0;
    uint32_t *img = realloc(v->image, (size_t)w * (size_t)h * sizeof *img);
    if (!img) return -1;
    v->image = img;
    v->image_w = w;
    v->image_h = h;
    v->image_mode = mode;
    camera c = make_camera(v, w, h);
    if (mode == VIEW_HEAT) {
        uint32_t *counts = calloc((size_t)w * (size_t)h, sizeof *counts);
        if (!counts) return -1;
        /* steps per pixel: nodes entered + primitive tests (viz/camera.c) */
        const uint32_t mask = SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST);
        const int ps = v->pixel_step > 0 ? v->pixel_step : 1;
        const uint32_t maxc = v->accel ? viz_heat_counts(v->accel, &c, w, h, ps, mask, counts) : 0;
        v->heat_max = maxc;
        for (int y = 0; y < h; y += ps)
            for (int x = 0; x < w; x += ps) {
                uint32_t n = counts[(size_t)y * (size_t)w + (size_t)x];
                uint32_t col = viz_heat_color(heat_fraction(n, maxc));
                for (int yy = y; yy < y + ps && yy < h; ++yy)
                    for (int xx = x; xx < x + ps && xx < w; ++xx) img[(size_t)yy * (size_t)w + (size_t)xx] = col;
            }
        free(counts);
        v->image_valid = 1;
        return 0;
    }
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.flags = SIDX_QUERY_NORMAL;
    const int ps = v->pixel_step > 0 ? v->pixel_step : 1;
    const sidx_vec3 light = v3norm(sidx_v3_add(sidx_v3_scale(c.up, 0.6f), sidx_v3_sub(c.right, c.fwd)));
    for (int y = 0; y < h; y += ps)
        for (int x = 0; x < w; x += ps) {
            sidx_vec3 org, dir;
            viz_camera_ray(&c, (float)x + 0.5f * (float)ps, (float)y + 0.5f * (float)ps, &org, &dir);
            sidx_ray r;
            uint32_t col = 0xff30343cu;
            if (v->accel && sidx_ray_init(&r, org, dir, 0.0f, INFINITY) == SIDX_OK) {
                sidx_hit hit;
                sidx_accel_intersect(v->accel, &r, &q, &hit);
                if (hit.prim != SIDX_NO_HIT) {
                    sidx_vec3 n = v3norm(hit.ng);
                    if (sidx_v3_dot(n, dir) > 0.0f) n = sidx_v3_scale(n, -1.0f);
                    float lam = 0.35f + 0.65f * fmaxf(0.0f, sidx_v3_dot(n, light));
                    col = viz_rgba((int)((0.5f + 0.5f * n.x) * 255.0f * lam), (int)((0.5f + 0.5f * n.y) * 255.0f * lam),
                                   (int)((0.5f + 0.5f * n.z) * 255.0f * lam), 255);
                }
            }
            for (int yy = y; yy < y + ps && yy < h; ++yy)
                for (int xx = x; xx < x + ps && xx < w; ++xx) img[(size_t)yy * (size_t)w + (size_t)xx] = col;
        }
    v->image_valid = 1;
    return 0;
}

static void render_3d(view_state *v, viz_canvas *cv, int heat)
{
    const int sw = view_scene_width(cv->w), h = cv->h;
    viz_clip(cv, 0, 0, sw, h);
    if (render_image(v, sw, h, heat ? VIEW_HEAT : VIEW_3D) == 0) {
        for (int y = 0; y < h; ++y) memcpy(&cv->px[(size_t)y * (size_t)cv->stride], &v->image[(size_t)y * (size_t)sw],
                                           (size_t)sw * sizeof(uint32_t));
    } else {
        viz_fill_rect(cv, 0, 0, sw, h, 0xff400000u);
        viz_text(cv, 10, 40, 2, 0xffffffffu, "out of memory");
    }
    camera c = make_camera(v, sw, h);
    if (v->level >= 0 && v->has_tree) {
        for (size_t i = 0; i < v->tree.count; ++i)
            if (v->tree.nodes[i].depth == (uint32_t)v->level)
                box3d(cv, &c, v->tree.nodes[i].bounds, 1, viz_depth_color((uint32_t)i, 200));
    }
    view_replay r;
    view_replay_run(v, v->step, &r);
    if (v->has_ray) {
        if (v->has_tree)
            for (size_t i = 0; i < v->tree.count; ++i)
                if (v->node_mark[i] == 1 && (uint32_t)i != r.current) box3d(cv, &c, v->tree.nodes[i].bounds, 1, 0x90ffd000u);
        if (!sidx_aabb_is_empty(r.current_box)) box3d(cv, &c, r.current_box, 3, 0xffff7f00u);
        float t_end = isfinite(r.best_t) ? r.best_t : ray_draw_end(v);
        float x0, y0, x1, y1;
        sidx_vec3 a = sidx_v3_add(v->org, sidx_v3_scale(v->dir, 1e-3f));
        sidx_vec3 b = sidx_v3_add(v->org, sidx_v3_scale(v->dir, t_end));
        if (project(&c, a, &x0, &y0) && project(&c, b, &x1, &y1)) viz_thick_line(cv, x0, y0, x1, y1, 2, 0xffff3030u);
        if (isfinite(r.best_t) && project(&c, b, &x1, &y1)) viz_fill_circle(cv, x1, y1, 5.0f, 0xffff2020u);
    }
    viz_textf(cv, 8, 8, 2, 0xffffffffu, "%s: %s", heat ? "heat" : "3D", v->accel_name);
    if (heat) {
        /* colour bar, log scale, ticked at 1, 10, 100, ... */
        for (int i = 0; i < 200; ++i) viz_fill_rect(cv, 10 + i, h - 30, 1, 12, viz_heat_color((float)i / 199.0f));
        viz_textf(cv, 10, h - 44, 1, 0xffffffffu, "steps per pixel (nodes + prim tests), log scale: 0 .. %u",
                  v->heat_max);
        int last_label = -100;
        for (uint32_t tick = 1; v->heat_max && tick <= v->heat_max; tick *= 10) {
            const int x = 10 + (int)lroundf(199.0f * heat_fraction(tick, v->heat_max));
            viz_fill_rect(cv, x, h - 18, 1, 4, 0xffffffffu);
            if (x - last_label >= 30) {
                viz_textf(cv, x - 2, h - 12, 1, 0xffffffffu, "%u", tick);
                last_label = x;
            }
            if (tick > UINT32_MAX / 10) break;
        }
    }

    viz_clip(cv, sw, 0, cv->w - sw, h);
    viz_fill_rect(cv, sw, 0, cv->w - sw, h, PANEL_BG);
    panel p = {cv, sw, 8, cv->w - sw, h - 8};
    pline(&p, PANEL_HI, "sidx-view  %s mode", heat ? "heat" : "3D");
    pline(&p, PANEL_FG, "scene: %s  (%u triangles)", v->scene, v->mesh.num_triangles);
    tree_summary(v, &p);
    pline(&p, PANEL_FG, "camera yaw %.2f pitch %.2f zoom %.2f", (double)v->yaw, (double)v->pitch, (double)v->zoom);
    if (v->level >= 0)
        pline(&p, PANEL_FG, "boxes of level %d shown", v->level);
    else
        pline(&p, PANEL_DIM, "level boxes off (+/- to choose a level)");
    pgap(&p);
    if (v->has_ray)
        traversal_panel(v, &p, &r);
    else
        pline(&p, PANEL_DIM, "click a pixel to step through its ray");
    viz_clip(cv, 0, 0, 0, 0);
}

/* ---- help --------------------------------------------------------------------------- */

static void render_help(viz_canvas *cv)
{
    static const char *const lines[] = {
        "sidx-view keys",
        "",
        "F1 / h        this help (any key closes)",
        "1 2 3 4       2D, build, 3D, heat map",
        "Tab           next mode",
        "Right / Left  one event forward / back",
        "Home / End    first / last event",
        "Space         play / pause",
        "n             next structure",
        "+ / -         3D: tree level of the boxes (- below 0: off)",
        "r             reset the ray / camera",
        "s             save a screenshot (sidx-view.png)",
        "q / Esc       quit",
        "",
        "mouse, 2D     drag to shoot a ray from the press point",
        "mouse, 3D     drag to orbit, wheel to zoom,",
        "              click a pixel to step through its ray",
    };
    const int n = (int)(sizeof lines / sizeof lines[0]);
    int bw = 560, bh = n * 2 * VIZ_FONT_H + 30;
    int x = (cv->w - bw) / 2, y = (cv->h - bh) / 2;
    viz_fill_rect(cv, 0, 0, cv->w, cv->h, 0x80000000u);
    viz_fill_rect(cv, x, y, bw, bh, 0xf0262b35u);
    viz_rect(cv, x, y, bw, bh, PANEL_HI);
    for (int i = 0; i < n; ++i) viz_text(cv, x + 16, y + 14 + i * 2 * VIZ_FONT_H, 2, i == 0 ? PANEL_HI : PANEL_FG, lines[i]);
}

void view_render(view_state *v, viz_canvas *cv)
{
    switch (v->mode) {
    case VIEW_BUILD: render_2d(v, cv, 1); break;
    case VIEW_3D: render_3d(v, cv, 0); break;
    case VIEW_HEAT: render_3d(v, cv, 1); break;
    default: render_2d(v, cv, 0); break;
    }
    if (v->show_help) render_help(cv);
}

SDL_Surface *view_render_surface(view_state *v, int w, int h)
{
    SDL_Surface *s = SDL_CreateRGBSurfaceWithFormat(0, w, h, 32, SDL_PIXELFORMAT_ARGB8888);
    if (!s) return NULL;
    if (SDL_MUSTLOCK(s)) SDL_LockSurface(s);
    viz_canvas cv;
    viz_canvas_from_surface(&cv, s);
    viz_clear(&cv, 0xff000000u);
    view_render(v, &cv);
    if (SDL_MUSTLOCK(s)) SDL_UnlockSurface(s);
    return s;
}

int view_screenshot(view_state *v, const char *path, int w, int h, char *msg, size_t msg_size)
{
    SDL_Surface *s = view_render_surface(v, w, h);
    if (!s) {
        snprintf(msg, msg_size, "cannot create a %dx%d surface: %s", w, h, SDL_GetError());
        return -1;
    }
    int rc = IMG_SavePNG(s, path);
    if (rc != 0) snprintf(msg, msg_size, "%s: %s", path, IMG_GetError());
    SDL_FreeSurface(s);
    return rc;
}
