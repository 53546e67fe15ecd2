/* view.h — internals of sidx-view shared by viz/view_*.c, viz/font.c, the
 * program and tests/test_viz.c.  Not installed.
 *
 * Drawing goes to a viz_canvas: the 32-bit ARGB pixels of an SDL_Surface,
 * written by the small rasteriser in view_draw.c (lines, boxes, triangles,
 * the built-in font).  The same pixels go to a window or, headless, to a
 * PNG, so a screenshot is exactly what the window shows. */
#ifndef SIDX_VIZ_VIEW_H
#define SIDX_VIZ_VIEW_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <SDL.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"

/* ---- canvas ---------------------------------------------------------------- */

typedef struct viz_canvas {
    uint32_t *px;      /* ARGB8888 */
    int w, h;
    int stride;        /* in pixels */
    int cx0, cy0, cx1, cy1; /* clip rectangle [cx0, cx1) × [cy0, cy1) */
} viz_canvas;

#define VIZ_FONT_W 6
#define VIZ_FONT_H 9

/* color: 0xAARRGGBB; alpha < 255 blends over what is there */
void viz_canvas_from_surface(viz_canvas *cv, SDL_Surface *s); /* s must be ARGB8888 and locked if needed */
void viz_clip(viz_canvas *cv, int x, int y, int w, int h);    /* w = 0: no clip */
void viz_clear(viz_canvas *cv, uint32_t color);
void viz_pixel(viz_canvas *cv, int x, int y, uint32_t color);
void viz_fill_rect(viz_canvas *cv, int x, int y, int w, int h, uint32_t color);
void viz_rect(viz_canvas *cv, int x, int y, int w, int h, uint32_t color);
void viz_line(viz_canvas *cv, float x0, float y0, float x1, float y1, uint32_t color);
void viz_thick_line(viz_canvas *cv, float x0, float y0, float x1, float y1, int width, uint32_t color);
void viz_dashed_line(viz_canvas *cv, float x0, float y0, float x1, float y1, int dash, uint32_t color);
void viz_fill_triangle(viz_canvas *cv, float x0, float y0, float x1, float y1, float x2, float y2, uint32_t color);
void viz_fill_circle(viz_canvas *cv, float x, float y, float r, uint32_t color);
uint32_t viz_rgba(int r, int g, int b, int a);
uint32_t viz_depth_color(uint32_t depth, int alpha);   /* a palette by tree depth */
uint32_t viz_heat_color(float f);                      /* 0..1 → black, blue, red, yellow, white */

const uint8_t *viz_font_glyph(int c);
int viz_text(viz_canvas *cv, int x, int y, int scale, uint32_t color, const char *s);
#if defined(__GNUC__)
__attribute__((format(printf, 6, 7)))
#endif
int viz_textf(viz_canvas *cv, int x, int y, int scale, uint32_t color, const char *fmt, ...);

/* ---- viewer state -------------------------------------------------------------- */

typedef enum view_mode { VIEW_2D = 0, VIEW_BUILD, VIEW_3D, VIEW_HEAT, VIEW_MODE_COUNT } view_mode;
const char *view_mode_name(view_mode m);          /* "2d", "build", "3d", "heat" */
int view_mode_parse(const char *s, view_mode *m);  /* 0 on success */

typedef struct view_stack_entry { uint32_t node; float t_near, t_far; } view_stack_entry;

/* What the traversal looks like after the first `step` events. */
typedef struct view_replay {
    uint32_t current;          /* tree index of the current node, SIDX_VIZ_NONE */
    uint32_t current_id;       /* its id (also for cells not in the tree) */
    sidx_aabb current_box;     /* bounds from the last NODE_ENTER / BOX_TEST, if any */
    float cur_t_near, cur_t_far;
    view_stack_entry stack[64];
    int stack_n, stack_more;   /* stack_more: entries beyond the 64 shown */
    uint32_t best_prim;
    float best_t;
    uint32_t prim_tests, box_tests, nodes_entered, mailbox_hits;
} view_replay;

typedef struct view_state {
    sidx_mesh mesh;
    char scene[128];
    char accel_name[32];
    sidx_accel *accel;
    sidx_aabb bounds;

    sidx_build_options knobs;  /* every build's options (its hook is the viewer's recorder) */
    sidx_recorder build;       /* the build's events */
    sidx_viz_tree tree;        /* rebuilt from them, if the structure emits a tree */
    int has_tree;
    char tree_msg[256];

    int has_ray;
    sidx_vec3 org, dir;
    sidx_recorder trav;        /* the ray's traversal events */
    char trace_path[256];      /* the file trav was read from (view_load_events); "" = recorded here */
    char *trace_store;         /* the strings of the events read from it */
    size_t step;               /* traversal events shown: 0..trav.count */
    size_t build_step;         /* build events shown (VIEW_BUILD): 0..build.count */

    view_mode mode;
    int show_help;
    int playing;

    /* 3D */
    float yaw, pitch, zoom;
    int level;                 /* boxes of tree level k; -1 = off */
    int pixel_step;            /* 3D render resolution: 1 = every pixel */
    uint32_t *image;           /* cached 3D / heat image (w × h) */
    int image_w, image_h, image_valid;
    view_mode image_mode;
    uint32_t heat_max;

    /* per-prim / per-node marks for the current step, sized mesh / tree */
    uint8_t *prim_mark;        /* 0 untested, 1 miss, 2 hit, 3 mailbox */
    uint8_t *node_mark;        /* 0 none, 1 entered, 2 box miss, 3 box hit */
} view_state;

/* Loads SCENE (file or built-in name), builds ACCEL with a recorder.  A
 * structure without a tree still opens (tree_msg says why).  Returns
 * SIDX_OK or the error, with err filled. */
sidx_status view_open(view_state *v, const char *scene, const char *accel, sidx_error *err);
/* Same, building this and every later structure with knobs (NULL = defaults). */
sidx_status view_open_knobs(view_state *v, const char *scene, const char *accel, const sidx_build_options *knobs,
                            sidx_error *err);
/* Same over a mesh the state takes over (moved: *mesh is zeroed). */
sidx_status view_open_mesh(view_state *v, sidx_mesh *mesh, const char *name, const char *accel, sidx_error *err);
void view_close(view_state *v);
/* Rebuilds with another structure (keeps scene and ray). */
sidx_status view_set_accel(view_state *v, const char *accel, sidx_error *err);
/* Traces org + t·dir with a recorder; step is set to `step` (clamped). */
sidx_status view_set_ray(view_state *v, sidx_vec3 org, sidx_vec3 dir, size_t step);
/* Replaces the traversal with the events of a JSON Lines trace (sidx-step
 * --json, sidx-check --trace): one event per non-blank line, read with
 * sidx_event_from_json, checked against the structure built here (only
 * traversal events; node ids below its node count, primitive ids below the
 * mesh's triangle count).  step is set to `step` (clamped).  On an error
 * err names the file, the line and what does not fit; trav is unchanged.
 * The trace stands until the next view_set_ray. */
sidx_status view_load_events(view_state *v, const char *path, size_t step, sidx_error *err);
/* The default 2D ray across the scene. */
void view_default_ray(const view_state *v, sidx_vec3 *org, sidx_vec3 *dir);
/* Replays the first `step` traversal events. */
void view_replay_run(const view_state *v, size_t step, view_replay *r);

/* Draws the current mode over the whole canvas. */
void view_render(view_state *v, viz_canvas *cv);
/* Renders into a new w×h ARGB surface (no window, no video driver needed). */
SDL_Surface *view_render_surface(view_state *v, int w, int h);
/* view_render_surface + IMG_SavePNG.  Returns 0 on success. */
int view_screenshot(view_state *v, const char *path, int w, int h, char *msg, size_t msg_size);

/* 3D camera ray through pixel (px, py) of a w×h image. */
void view_camera_ray(const view_state *v, float px, float py, int w, int h, sidx_vec3 *org, sidx_vec3 *dir);
/* The 2D panel split: scene area width for a canvas of width w. */
int view_scene_width(int w);
/* 2D mapping between screen and scene xy for a canvas of w×h. */
void view_2d_to_world(const view_state *v, int w, int h, float sx, float sy, float *x, float *y);

/* ---- input (view_input.c) ------------------------------------------------------- */

typedef struct view_input {
    int w, h;                  /* window size */
    int dragging, moved, press_x, press_y;
    char screenshot_path[256]; /* where 's' saves */
} view_input;

#define VIEW_INPUT_REDRAW 1
#define VIEW_INPUT_QUIT 2
void view_input_init(view_input *in, int w, int h);
/* Applies one SDL event; returns VIEW_INPUT_* flags. */
int view_handle_event(view_state *v, view_input *in, const SDL_Event *e);
/* One step of "play" (space): advance, stop at the end. */
void view_tick(view_state *v);

#endif
