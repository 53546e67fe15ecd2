/* json_write.h — the JSON writer shared by sidx-view --html (viz/html.c)
 * and the lab's entry layer (viz/lab.c): one growing string and the
 * writers of the values and events both put into their JSON, so the page
 * of a recorded walk and the live lab describe an event in the same
 * words.  No SDL, no file.  Not installed. */
#ifndef SIDX_VIZ_JSON_WRITE_H
#define SIDX_VIZ_JSON_WRITE_H

#include <stddef.h>
#include <stdint.h>
#include "sidx/sidx.h"

/* A growing string.  {NULL, 0, 0, 0} is empty; an allocation failure sets
 * failed and later writes do nothing (the caller checks failed once at
 * the end).  s is NUL-terminated once anything was written; free(s). */
typedef struct viz_json { char *s; size_t n, cap; int failed; } viz_json;

void viz_json_put(viz_json *b, const char *s);
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
void viz_json_printf(viz_json *b, const char *fmt, ...);
/* A JSON string; '<' as \u003c so no text can close a page's <script>. */
void viz_json_string(viz_json *b, const char *s);
/* %.6g; JSON has no inf or NaN: 1e999, -1e999 (which a JSON reader takes
 * for +-infinity), null.  Every number either writes is valid JSON. */
void viz_json_float(viz_json *b, float f);
void viz_json_double(viz_json *b, double d);
void viz_json_xyz(viz_json *b, sidx_vec3 p);     /* x,y,z */
void viz_json_id(viz_json *b, uint32_t id);      /* UINT32_MAX as -1 */
void viz_json_box(viz_json *b, sidx_aabb box);   /* ,minx,miny,minz,maxx,maxy,maxz (leading comma) */

/* One build event as an array, its fields by type (viz/page.html reads them
 * back in the same order):
 *   BUILD_BEGIN      [0, count, box6]
 *   BUILD_NODE       [1, node, parent, depth, count, box6]
 *   CANDIDATE/SPLIT  [2|3, node, axis, pos, cost, n_left, n_right (, plane normal xyz if axis < 0)]
 *   BUILD_LEAF       [4, node, depth, count, cost, reason, [prims] or null]
 *   BUILD_END        [5, nodes, references, depth]
 *   others           [type, node] */
void viz_json_build_event(viz_json *b, const sidx_event *e);
/* One traversal event: sidx-step --json's object (sidx_event_to_json), plus
 * "box": [0, box6] where NODE_ENTER carries a box and "line", the
 * printer's text of the event (sidx_event_format).  -1 (and nothing
 * written) if the event's JSON does not fit 1 KiB. */
int viz_json_trav_event(viz_json *b, const sidx_event *e);
/* The same with "  [label]" after the line where label is not NULL: the
 * node's name on the slide, as sidx-step prints it. */
int viz_json_trav_event_label(viz_json *b, const sidx_event *e, const char *label);

/* 1 for a scene flat in z (the 2D lecture scenes: z extent at most 5% of
 * the larger of x and y), which the pages open in their 2D view. */
int viz_scene_is_flat(sidx_aabb bounds);

#endif
