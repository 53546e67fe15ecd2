/* html.c — sidx-view --html: the viewer's state as one web page.
 *
 * The page is the template viz/page.html (compiled into the program) with
 * its placeholder replaced by one JSON object: the scene's vertices and
 * triangles, the build events in a compact array form (the page replays
 * them for the build mode and draws the boxes from BUILD_NODE, as the
 * viewer's 2D mode does), and the ray's traversal events as sidx-step
 * --json writes them, each with the printer's line for the event list.
 * The page replays the first k traversal events exactly as
 * view_replay_run does, so what it shows at step k is what the SDL viewer
 * shows.  No SDL call here: it works without a display. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "page.h"

#define PLACEHOLDER "\"@SIDX_PAGE_DATA@\""

/* ---- a growing string ------------------------------------------------------------ */

typedef struct sbuf { char *s; size_t n, cap; int failed; } sbuf;

static void sb_grow(sbuf *b, size_t extra)
{
    if (b->failed || b->n + extra + 1 <= b->cap) return;
    size_t cap = b->cap ? b->cap : 4096;
    while (cap < b->n + extra + 1) cap *= 2;
    char *s = realloc(b->s, cap);
    if (!s) {
        b->failed = 1;
        return;
    }
    b->s = s;
    b->cap = cap;
}

static void sb_put(sbuf *b, const char *s)
{
    size_t n = strlen(s);
    sb_grow(b, n);
    if (b->failed) return;
    memcpy(b->s + b->n, s, n + 1);
    b->n += n;
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void sb_printf(sbuf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0) {
        b->failed = 1;
        return;
    }
    sb_grow(b, (size_t)n);
    if (b->failed) return;
    va_start(ap, fmt);
    vsnprintf(b->s + b->n, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->n += (size_t)n;
}

/* A JSON string; '<' as \u003c so no text can close the page's <script>. */
static void sb_string(sbuf *b, const char *s)
{
    sb_put(b, "\"");
    for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; ++p) {
        if (*p == '"' || *p == '\\')
            sb_printf(b, "\\%c", *p);
        else if (*p < 0x20 || *p == '<')
            sb_printf(b, "\\u%04x", (unsigned)*p);
        else
            sb_printf(b, "%c", *p);
    }
    sb_put(b, "\"");
}

/* Floats: 6 significant digits are plenty for drawing; JSON has no inf. */
static void sb_float(sbuf *b, float f)
{
    if (isfinite(f))
        sb_printf(b, "%.6g", (double)f);
    else
        sb_put(b, isnan(f) ? "null" : f > 0 ? "1e999" : "-1e999");
}

static void sb_xyz(sbuf *b, sidx_vec3 p)
{
    sb_float(b, p.x);
    sb_put(b, ",");
    sb_float(b, p.y);
    sb_put(b, ",");
    sb_float(b, p.z);
}

static void sb_id(sbuf *b, uint32_t id)
{
    if (id == UINT32_MAX)
        sb_put(b, "-1");
    else
        sb_printf(b, "%u", id);
}

static void sb_box(sbuf *b, sidx_aabb box)
{
    sb_put(b, ",");
    sb_xyz(b, box.min);
    sb_put(b, ",");
    sb_xyz(b, box.max);
}

/* ---- the data ------------------------------------------------------------------------ */

/* One build event as an array, its fields by type (viz/page.html reads them
 * back in the same order):
 *   BUILD_BEGIN      [0, count, box6]
 *   BUILD_NODE       [1, node, parent, depth, count, box6]
 *   CANDIDATE/SPLIT  [2|3, node, axis, pos, cost, n_left, n_right (, plane normal xyz if axis < 0)]
 *   BUILD_LEAF       [4, node, depth, count, cost, reason, [prims] or null]
 *   BUILD_END        [5, nodes, references, depth]
 *   others           [type, node] */
static void build_event(sbuf *b, const sidx_event *e)
{
    sb_printf(b, "[%d", (int)e->type);
    switch (e->type) {
    case SIDX_EV_BUILD_BEGIN:
        sb_printf(b, ",%u", e->count);
        sb_box(b, e->bounds);
        break;
    case SIDX_EV_BUILD_NODE:
        sb_printf(b, ",%u,", e->node);
        sb_id(b, e->parent);
        sb_put(b, ",");
        sb_id(b, e->depth);
        sb_printf(b, ",%u", e->count);
        sb_box(b, e->bounds);
        break;
    case SIDX_EV_BUILD_CANDIDATE:
    case SIDX_EV_BUILD_SPLIT:
        sb_put(b, ",");
        sb_id(b, e->node);
        sb_printf(b, ",%d,", (int)e->axis);
        sb_float(b, e->pos);
        sb_put(b, ",");
        sb_float(b, e->cost);
        sb_printf(b, ",%u,%u", e->count, e->aux);
        if (e->axis < 0) { /* BSP: the plane's normal */
            sb_put(b, ",");
            sb_xyz(b, e->bounds.min);
        }
        break;
    case SIDX_EV_BUILD_LEAF:
        sb_put(b, ",");
        sb_id(b, e->node);
        sb_put(b, ",");
        sb_id(b, e->depth);
        sb_printf(b, ",%u,", e->count);
        sb_float(b, e->cost);
        sb_put(b, ",");
        sb_string(b, sidx_leaf_reason_name(e->reason));
        if (e->prims && e->count != UINT32_MAX) {
            sb_put(b, ",[");
            for (uint32_t i = 0; i < e->count; ++i) sb_printf(b, i ? ",%u" : "%u", e->prims[i]);
            sb_put(b, "]");
        } else {
            sb_put(b, ",null");
        }
        break;
    case SIDX_EV_BUILD_END:
        sb_printf(b, ",%u,%u,%u", e->node, e->count, e->depth);
        break;
    default:
        sb_put(b, ",");
        sb_id(b, e->node);
        break;
    }
    sb_put(b, "]");
}

/* One traversal event: sidx-step --json's object (sidx_event_to_json), plus
 * the node's box where NODE_ENTER carries one (the replay's current box)
 * and "line", the printer's text of the event (the viewer's event list). */
static int trav_event(sbuf *b, const sidx_event *e)
{
    char json[1024], line[512];
    int n = sidx_event_to_json(e, json, sizeof json);
    if (n < 2 || (size_t)n >= sizeof json) return -1;
    json[n - 1] = '\0'; /* drop the closing brace */
    sb_put(b, json);
    if (e->type == SIDX_EV_NODE_ENTER && !sidx_aabb_is_empty(e->bounds)) {
        sb_put(b, ",\"box\":[0");
        sb_box(b, e->bounds);
        sb_put(b, "]");
    }
    if (sidx_event_format(e, line, sizeof line) < 0) snprintf(line, sizeof line, "?");
    sb_put(b, ",\"line\":");
    sb_string(b, line);
    sb_put(b, "}");
    return 0;
}

/* A scene that is flat in z (the 2D lecture scene) opens in the 2D view;
 * anything else also gets the 3D view first. */
static int scene_is_flat(const view_state *v)
{
    sidx_vec3 e = sidx_aabb_extent(v->bounds);
    float m = e.x > e.y ? e.x : e.y;
    return !(e.z > 0.05f * m);
}

static void page_data(const view_state *v, sbuf *b, view_mode mode, size_t step, int level)
{
    const int flat = scene_is_flat(v);
    if (mode == VIEW_HEAT) mode = VIEW_3D; /* the page has no heat map */
    sb_put(b, "{\"scene\":");
    sb_string(b, v->scene);
    sb_put(b, ",\"accel\":");
    sb_string(b, v->accel_name);
    sb_printf(b, ",\"flat\":%s,\"mode\":", flat ? "true" : "false");
    sb_string(b, view_mode_name(mode));
    sb_put(b, ",\"step\":");
    if (step == SIZE_MAX)
        sb_put(b, "-1");
    else
        sb_printf(b, "%zu", step);
    sb_printf(b, ",\"level\":%d,\"has_tree\":%s,\"camera\":[", level, v->has_tree ? "true" : "false");
    sb_xyz(b, sidx_v3(v->yaw, v->pitch, v->zoom)); /* 3D: --yaw, --pitch, --zoom */
    sb_put(b, "]");
    if (v->has_tree)
        sb_printf(b, ",\"tree\":{\"nodes\":%zu,\"leaves\":%u,\"depth\":%u}", v->tree.count, v->tree.leaves,
                  v->tree.max_depth);
    sb_put(b, ",\"tree_msg\":");
    sb_string(b, v->tree_msg[0] ? v->tree_msg : "no tree");
    sb_put(b, ",\"bounds\":[0");
    sb_box(b, v->bounds); /* [0, box6]: the array form of BUILD_BEGIN's box */
    sb_put(b, "]");

    /* vertices and triangles */
    sb_put(b, ",\"pos\":[");
    for (uint32_t i = 0; i < v->mesh.num_vertices; ++i) {
        if (i) sb_put(b, ",");
        sb_xyz(b, v->mesh.positions[i]);
    }
    sb_put(b, "],\"idx\":[");
    for (uint32_t i = 0; i < 3u * v->mesh.num_triangles; ++i) sb_printf(b, i ? ",%u" : "%u", v->mesh.indices[i]);
    sb_put(b, "]");

    /* the ray */
    if (v->has_ray) {
        sb_put(b, ",\"ray\":{\"o\":[");
        sb_xyz(b, v->org);
        sb_put(b, "],\"d\":[");
        sb_xyz(b, v->dir);
        sb_put(b, "]}");
    } else {
        sb_put(b, ",\"ray\":null");
    }

    /* build events; SAH candidates only up to the budget */
    size_t cand_total = 0, cand_kept = 0;
    sb_put(b, ",\"build\":[");
    int first = 1;
    for (size_t i = 0; i < v->build.count; ++i) {
        const sidx_event *e = &v->build.events[i];
        if (e->type == SIDX_EV_BUILD_CANDIDATE) {
            ++cand_total;
            if (cand_kept >= VIEW_HTML_MAX_CANDIDATES) continue;
            ++cand_kept;
        }
        if (!first) sb_put(b, ",\n");
        first = 0;
        build_event(b, e);
    }
    sb_printf(b, "],\"cand_total\":%zu,\"cand_kept\":%zu", cand_total, cand_kept);

    /* traversal events */
    sb_put(b, ",\"trav\":[");
    for (size_t i = 0; i < v->trav.count; ++i) {
        if (i) sb_put(b, ",\n");
        if (trav_event(b, &v->trav.events[i]) != 0) b->failed = 1;
    }
    sb_put(b, "]}");
}

/* ---- public ---------------------------------------------------------------------------- */

int view_html_check_scene(const char *scene, char *msg, size_t msg_size)
{
    sidx_mesh m;
    sidx_error err;
    memset(&m, 0, sizeof m);
    if (sidx_scene_open(scene, &m, &err) != SIDX_OK) {
        snprintf(msg, msg_size, "%s", err.message);
        return -1;
    }
    const uint32_t n = m.num_triangles;
    sidx_mesh_free(&m);
    if (n > VIEW_HTML_MAX_TRIANGLES) {
        snprintf(msg, msg_size,
                 "--html: scene '%s' has %u triangles; a page holds at most %u (it draws them all at every step)",
                 scene, n, VIEW_HTML_MAX_TRIANGLES);
        return -1;
    }
    return 0;
}

int view_write_html(const view_state *v, const char *path, view_mode mode, size_t step, int level, char *msg,
                    size_t msg_size)
{
    const char *tpl = (const char *)sidx_page_html;
    const char *hole = strstr(tpl, PLACEHOLDER);
    if (!hole) {
        snprintf(msg, msg_size, "the page template has no %s placeholder", PLACEHOLDER);
        return -1;
    }
    if (v->mesh.num_triangles > VIEW_HTML_MAX_TRIANGLES) {
        snprintf(msg, msg_size, "--html: scene '%s' has %u triangles; a page holds at most %u", v->scene,
                 v->mesh.num_triangles, VIEW_HTML_MAX_TRIANGLES);
        return -1;
    }
    sbuf data = {NULL, 0, 0, 0};
    page_data(v, &data, mode, step, level);
    if (data.failed) {
        free(data.s);
        snprintf(msg, msg_size, "out of memory writing the page");
        return -1;
    }
    const size_t head = (size_t)(hole - tpl), tail = sidx_page_html_len - head - strlen(PLACEHOLDER);
    const size_t total = head + data.n + tail;
    if (total > VIEW_HTML_MAX_BYTES) {
        free(data.s);
        snprintf(msg, msg_size, "--html: the page would be %zu bytes, over the limit of %u bytes (%u MiB)", total,
                 VIEW_HTML_MAX_BYTES, VIEW_HTML_MAX_BYTES / (1024u * 1024u));
        return -1;
    }
    FILE *f = fopen(path, "wb");
    if (!f) {
        free(data.s);
        snprintf(msg, msg_size, "cannot write %s: %s", path, strerror(errno));
        return -1;
    }
    int ok = fwrite(tpl, 1, head, f) == head && fwrite(data.s, 1, data.n, f) == data.n &&
             fwrite(hole + strlen(PLACEHOLDER), 1, tail, f) == tail;
    int e = errno;
    if (fclose(f) != 0 && ok) {
        ok = 0;
        e = errno;
    }
    free(data.s);
    if (!ok) {
        snprintf(msg, msg_size, "cannot write %s: %s", path, strerror(e));
        remove(path);
        return -1;
    }
    return 0;
}
