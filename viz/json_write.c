/* json_write.c — the JSON text of sidx-view --html's page data and of the
 * lab's answers (viz/lab.c): a growing string, JSON strings and floats,
 * one build event in the compact array form viz/page.html reads, one
 * traversal event as sidx-step --json writes it plus the printer's line.
 * No SDL, no file: the web build compiles it too. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "json_write.h"

/* ---- a growing string ------------------------------------------------------------ */

static void viz_json_grow(viz_json *b, size_t extra)
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

void viz_json_put(viz_json *b, const char *s)
{
    size_t n = strlen(s);
    viz_json_grow(b, n);
    if (b->failed) return;
    memcpy(b->s + b->n, s, n + 1);
    b->n += n;
}

/* One vsnprintf where the text fits in the room left (the common case), a
 * second after growing where it does not. */
void viz_json_printf(viz_json *b, const char *fmt, ...)
{
    if (b->failed) return;
    va_list ap;
    if (b->cap < b->n + 64) viz_json_grow(b, 64);
    if (b->failed) return;
    const size_t room = b->cap - b->n;
    va_start(ap, fmt);
    int n = vsnprintf(b->s + b->n, room, fmt, ap);
    va_end(ap);
    if (n < 0) {
        b->failed = 1;
        return;
    }
    if ((size_t)n >= room) {
        viz_json_grow(b, (size_t)n);
        if (b->failed) return;
        va_start(ap, fmt);
        vsnprintf(b->s + b->n, (size_t)n + 1, fmt, ap);
        va_end(ap);
    }
    b->n += (size_t)n;
}

/* A whole number in decimal, as printf's "%u" writes it (without printf:
 * a build's answer holds tens of thousands of them). */
static void put_u32(viz_json *b, uint32_t v)
{
    char d[11];
    int k = (int)sizeof d;
    do {
        d[--k] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v);
    viz_json_grow(b, sizeof d - (size_t)k);
    if (b->failed) return;
    memcpy(b->s + b->n, d + k, sizeof d - (size_t)k);
    b->n += sizeof d - (size_t)k;
    b->s[b->n] = '\0';
}

/* A JSON string; '<' as \u003c so no text can close the page's <script>. */
void viz_json_string(viz_json *b, const char *s)
{
    viz_json_put(b, "\"");
    for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; ++p) {
        if (*p == '"' || *p == '\\')
            viz_json_printf(b, "\\%c", *p);
        else if (*p < 0x20 || *p == '<')
            viz_json_printf(b, "\\u%04x", (unsigned)*p);
        else
            viz_json_printf(b, "%c", *p);
    }
    viz_json_put(b, "\"");
}

/* Floats: 6 significant digits are plenty for drawing; JSON has no inf. */
void viz_json_float(viz_json *b, float f)
{
    if (isfinite(f))
        viz_json_printf(b, "%.6g", (double)f);
    else
        viz_json_put(b, isnan(f) ? "null" : f > 0 ? "1e999" : "-1e999");
}

/* The same for a double (a structure's SAH cost): %.6g of the double
 * itself, so a finite value prints as it did before it was checked. */
void viz_json_double(viz_json *b, double d)
{
    if (isfinite(d))
        viz_json_printf(b, "%.6g", d);
    else
        viz_json_put(b, isnan(d) ? "null" : d > 0 ? "1e999" : "-1e999");
}

void viz_json_xyz(viz_json *b, sidx_vec3 p)
{
    viz_json_float(b, p.x);
    viz_json_put(b, ",");
    viz_json_float(b, p.y);
    viz_json_put(b, ",");
    viz_json_float(b, p.z);
}

void viz_json_id(viz_json *b, uint32_t id)
{
    if (id == UINT32_MAX)
        viz_json_put(b, "-1");
    else
        put_u32(b, id);
}

void viz_json_box(viz_json *b, sidx_aabb box)
{
    viz_json_put(b, ",");
    viz_json_xyz(b, box.min);
    viz_json_put(b, ",");
    viz_json_xyz(b, box.max);
}

/* ---- events -------------------------------------------------------------------------- */

/* The compact array form: json_write.h lists the fields by type. */
void viz_json_build_event(viz_json *b, const sidx_event *e)
{
    viz_json_printf(b, "[%d", (int)e->type);
    switch (e->type) {
    case SIDX_EV_BUILD_BEGIN:
        viz_json_printf(b, ",%u", e->count);
        viz_json_box(b, e->bounds);
        break;
    case SIDX_EV_BUILD_NODE:
        viz_json_printf(b, ",%u,", e->node);
        viz_json_id(b, e->parent);
        viz_json_put(b, ",");
        viz_json_id(b, e->depth);
        viz_json_printf(b, ",%u", e->count);
        viz_json_box(b, e->bounds);
        break;
    case SIDX_EV_BUILD_CANDIDATE:
    case SIDX_EV_BUILD_SPLIT:
        viz_json_put(b, ",");
        viz_json_id(b, e->node);
        viz_json_printf(b, ",%d,", (int)e->axis);
        viz_json_float(b, e->pos);
        viz_json_put(b, ",");
        viz_json_float(b, e->cost);
        viz_json_printf(b, ",%u,%u", e->count, e->aux);
        if (e->axis < 0) { /* BSP: the plane's normal */
            viz_json_put(b, ",");
            viz_json_xyz(b, e->bounds.min);
        }
        break;
    case SIDX_EV_BUILD_LEAF:
        viz_json_put(b, ",");
        viz_json_id(b, e->node);
        viz_json_put(b, ",");
        viz_json_id(b, e->depth);
        viz_json_printf(b, ",%u,", e->count);
        viz_json_float(b, e->cost);
        viz_json_put(b, ",");
        viz_json_string(b, sidx_leaf_reason_name(e->reason));
        if (e->prims && e->count != UINT32_MAX) {
            viz_json_put(b, ",[");
            for (uint32_t i = 0; i < e->count; ++i) {
                if (i) viz_json_put(b, ",");
                put_u32(b, e->prims[i]);
            }
            viz_json_put(b, "]");
        } else {
            viz_json_put(b, ",null");
        }
        break;
    case SIDX_EV_BUILD_END:
        viz_json_printf(b, ",%u,%u,%u", e->node, e->count, e->depth);
        break;
    default:
        viz_json_put(b, ",");
        viz_json_id(b, e->node);
        break;
    }
    viz_json_put(b, "]");
}

/* One traversal event: sidx-step --json's object (sidx_event_to_json), plus
 * the node's box where NODE_ENTER carries one (the replay's current box)
 * and "line", the printer's text of the event (the viewer's event list),
 * with "  [label]" after it where label is not NULL. */
int viz_json_trav_event(viz_json *b, const sidx_event *e) { return viz_json_trav_event_label(b, e, NULL); }

int viz_json_trav_event_label(viz_json *b, const sidx_event *e, const char *label)
{
    char json[1024], line[512];
    int n = sidx_event_to_json(e, json, sizeof json);
    if (n < 2 || (size_t)n >= sizeof json) return -1;
    json[n - 1] = '\0'; /* drop the closing brace */
    viz_json_put(b, json);
    if (e->type == SIDX_EV_NODE_ENTER && !sidx_aabb_is_empty(e->bounds)) {
        viz_json_put(b, ",\"box\":[0");
        viz_json_box(b, e->bounds);
        viz_json_put(b, "]");
    }
    const int k = sidx_event_format(e, line, sizeof line);
    if (k < 0) snprintf(line, sizeof line, "?");
    else if (label && (size_t)k < sizeof line) snprintf(line + k, sizeof line - (size_t)k, "  [%s]", label);
    viz_json_put(b, ",\"line\":");
    viz_json_string(b, line);
    viz_json_put(b, "}");
    return 0;
}

int viz_scene_is_flat(sidx_aabb bounds)
{
    sidx_vec3 e = sidx_aabb_extent(bounds);
    float m = e.x > e.y ? e.x : e.y;
    return !(e.z > 0.05f * m);
}
