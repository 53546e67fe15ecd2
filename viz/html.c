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
#include "json_write.h"
#include "page.h"

#define PLACEHOLDER "\"@SIDX_PAGE_DATA@\""

static void page_data(const view_state *v, viz_json *b, view_mode mode, size_t step, int level)
{
    const int flat = viz_scene_is_flat(v->bounds);
    if (mode == VIEW_HEAT) mode = VIEW_3D; /* the page has no heat map */
    viz_json_put(b, "{\"scene\":");
    viz_json_string(b, v->scene);
    viz_json_put(b, ",\"accel\":");
    viz_json_string(b, v->accel_name);
    viz_json_printf(b, ",\"flat\":%s,\"mode\":", flat ? "true" : "false");
    viz_json_string(b, view_mode_name(mode));
    viz_json_put(b, ",\"step\":");
    if (step == SIZE_MAX)
        viz_json_put(b, "-1");
    else
        viz_json_printf(b, "%zu", step);
    viz_json_printf(b, ",\"level\":%d,\"has_tree\":%s,\"camera\":[", level, v->has_tree ? "true" : "false");
    viz_json_xyz(b, sidx_v3(v->yaw, v->pitch, v->zoom)); /* 3D: --yaw, --pitch, --zoom */
    viz_json_put(b, "]");
    if (v->has_tree)
        viz_json_printf(b, ",\"tree\":{\"nodes\":%zu,\"leaves\":%u,\"depth\":%u}", v->tree.count, v->tree.leaves,
                  v->tree.max_depth);
    viz_json_put(b, ",\"tree_msg\":");
    viz_json_string(b, v->tree_msg[0] ? v->tree_msg : "no tree");
    viz_json_put(b, ",\"bounds\":[0");
    viz_json_box(b, v->bounds); /* [0, box6]: the array form of BUILD_BEGIN's box */
    viz_json_put(b, "]");

    /* vertices and triangles */
    viz_json_put(b, ",\"pos\":[");
    for (uint32_t i = 0; i < v->mesh.num_vertices; ++i) {
        if (i) viz_json_put(b, ",");
        viz_json_xyz(b, v->mesh.positions[i]);
    }
    viz_json_put(b, "],\"idx\":[");
    for (uint32_t i = 0; i < 3u * v->mesh.num_triangles; ++i) viz_json_printf(b, i ? ",%u" : "%u", v->mesh.indices[i]);
    viz_json_put(b, "]");

    /* the ray */
    if (v->has_ray) {
        viz_json_put(b, ",\"ray\":{\"o\":[");
        viz_json_xyz(b, v->org);
        viz_json_put(b, "],\"d\":[");
        viz_json_xyz(b, v->dir);
        viz_json_put(b, "]}");
    } else {
        viz_json_put(b, ",\"ray\":null");
    }

    /* build events; SAH candidates only up to the budget */
    size_t cand_total = 0, cand_kept = 0;
    viz_json_put(b, ",\"build\":[");
    int first = 1;
    for (size_t i = 0; i < v->build.count; ++i) {
        const sidx_event *e = &v->build.events[i];
        if (e->type == SIDX_EV_BUILD_CANDIDATE) {
            ++cand_total;
            if (cand_kept >= VIEW_HTML_MAX_CANDIDATES) continue;
            ++cand_kept;
        }
        if (!first) viz_json_put(b, ",\n");
        first = 0;
        viz_json_build_event(b, e);
    }
    viz_json_printf(b, "],\"cand_total\":%zu,\"cand_kept\":%zu", cand_total, cand_kept);

    /* traversal events */
    viz_json_put(b, ",\"trav\":[");
    for (size_t i = 0; i < v->trav.count; ++i) {
        if (i) viz_json_put(b, ",\n");
        if (viz_json_trav_event(b, &v->trav.events[i]) != 0) b->failed = 1;
    }
    viz_json_put(b, "]}");
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
    viz_json data = {NULL, 0, 0, 0};
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
