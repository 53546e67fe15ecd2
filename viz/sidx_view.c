/* sidx-view — watch a structure being built and a ray walking through it.
 *
 *   sidx-view [--accel NAME] [--scene S] [--mode 2d|build|3d|heat] [--ray R] [build knobs]
 *   sidx-view --screenshot out.png [--step N] [--mode ...] [--size WxH] ...
 *   sidx-view --html out.html [--step N] [--mode ...] ...
 *   sidx-view --events TRACE.jsonl [--scene S --accel NAME --ray R knobs] ...
 *
 * With --screenshot it renders one frame into an offscreen surface and
 * writes a PNG: no window, no display, no video driver.  With --html it
 * writes one web page stepping through the same build and traversal
 * (viz/html.c), without SDL at all.  F1 / h in the window lists the keys.
 * Without a display the window cannot open: sidx-view says so and exits 1.
 * Exit status: 0 ok, 1 failure, 2 usage. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <SDL.h>
#include <SDL_image.h>
#include "args.h"
#include "page.h"
#include "view.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: sidx-view [options]\n"
            "\n"
            "An SDL2 window over the hook events: the 2D lecture scene with the structure's\n"
            "boxes and a ray you drag, stepping through its traversal (Right/Left, Home/End,\n"
            "Space); the build step by step with the SAH candidate curve; a 3D view shaded\n"
            "by normal with the boxes of one tree level, and a heat map of traversal steps.\n"
            "Press F1 or h in the window for the keys.\n"
            "\n"
            "  --accel NAME        structure (default: bvh if registered, else brute; --list)\n"
            "  --scene S           scene file or built-in name (default flat2d: one triangle per\n"
            "                      2D shape; a ray in z = 0 hits it along the spine drawn in it)\n"
            "  --mode M            2d, build, 3d or heat (default 2d)\n"
            "  --ray R             ray ox,oy,oz,dx,dy,dz (default: across the scene, in z = 0)\n"
            "  --step N            show the first N events (default: all)\n"
            "  --events F.jsonl    step through the traversal trace in F (sidx-step --json,\n"
            "                      sidx-check --trace) instead of tracing the ray here; give the\n"
            "                      --scene, --accel, knobs and --ray it was recorded with\n"
            "  --level K           3D: draw the boxes of tree level K\n"
            "  --yaw A --pitch A   3D camera angles in radians; --zoom Z\n"
            "  --size WxH          window / screenshot size (default 1100x700)\n"
            "  --screenshot F.png  render one frame headless to F.png and exit\n"
            "  --html F.html       write one self-contained web page stepping through the\n"
            "                      build and the ray's traversal, and exit (no display)\n"
            "  --list              list the registered structures\n"
            "  -h, --help          this help\n"
            "\n"
            "The window needs a display (DISPLAY or WAYLAND_DISPLAY); without one, use\n"
            "--screenshot or --html.  SDL_VIDEODRIVER, when set, picks SDL's video driver.\n"
            "\n%s",
            sidx_viz_build_knobs_help());
}

static int parse_size(const char *s, int *w, int *h)
{
    char *end;
    long a = strtol(s, &end, 10);
    if (*end != 'x' || a < 64 || a > 8192) return -1;
    long b = strtol(end + 1, &end, 10);
    if (*end || b < 64 || b > 8192) return -1;
    *w = (int)a;
    *h = (int)b;
    return 0;
}

static int parse_float(const char *s, float *out)
{
    char *end;
    float f = strtof(s, &end);
    if (end == s || *end || !isfinite(f)) return -1;
    *out = f;
    return 0;
}

static const char *default_accel(void)
{
    return sidx_accel_is_registered("bvh") ? "bvh" : sidx_accel_registered_name(0);
}

/* ---- interactive ------------------------------------------------------------------------- */

/* The two ways to see a traversal without a window. */
static void no_window_hint(void)
{
    fputs("sidx-view: without a window: --screenshot out.png draws one frame, --html out.html writes a web page\n",
          stderr);
}

static int env_set(const char *name)
{
    const char *e = getenv(name);
    return e && *e;
}

/* Whether a window can be shown.  On Linux SDL reaches a screen through an
 * X server (DISPLAY) or a Wayland compositor (WAYLAND_DISPLAY); with
 * neither, SDL_Init still succeeds on its "offscreen" driver, and the
 * window then waits, unseen, for input that never comes.  SDL_VIDEODRIVER
 * set by hand picks a driver on purpose and is obeyed. */
static int display_reachable(void)
{
#ifdef __linux__
    if (!env_set("SDL_VIDEODRIVER") && !env_set("DISPLAY") && !env_set("WAYLAND_DISPLAY")) {
        fputs("sidx-view: no display (neither DISPLAY nor WAYLAND_DISPLAY is set): cannot open a window\n", stderr);
        no_window_hint();
        return 0;
    }
#endif
    return 1;
}

static int run_window(view_state *v, int w, int h)
{
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        fprintf(stderr, "sidx-view: cannot open a window: %s\n", SDL_GetError());
        no_window_hint();
        return 1;
    }
    /* a DISPLAY naming no server also ends on a driver that shows nothing */
    const char *driver = SDL_GetCurrentVideoDriver();
    if (!env_set("SDL_VIDEODRIVER") && driver && (!strcmp(driver, "offscreen") || !strcmp(driver, "dummy"))) {
        fprintf(stderr, "sidx-view: no display: SDL found only its '%s' video driver, which shows no window\n",
                driver);
        no_window_hint();
        SDL_Quit();
        return 1;
    }
    SDL_Window *win = SDL_CreateWindow("sidx-view", SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, w, h, 0);
    if (!win) {
        fprintf(stderr, "sidx-view: cannot open a window: %s\n", SDL_GetError());
        no_window_hint();
        SDL_Quit();
        return 1;
    }
    SDL_Surface *frame = SDL_CreateRGBSurfaceWithFormat(0, w, h, 32, SDL_PIXELFORMAT_ARGB8888);
    if (!frame) {
        fprintf(stderr, "sidx-view: %s\n", SDL_GetError());
        SDL_DestroyWindow(win);
        SDL_Quit();
        return 1;
    }
    view_input in;
    view_input_init(&in, w, h);
    int running = 1, dirty = 1;
    Uint32 last_play = SDL_GetTicks();
    while (running) {
        SDL_Event e;
        int got = dirty ? SDL_PollEvent(&e) : SDL_WaitEventTimeout(&e, v->playing ? 30 : 250);
        while (got) {
            int r = view_handle_event(v, &in, &e);
            if (r & VIEW_INPUT_QUIT) running = 0;
            if (r & VIEW_INPUT_REDRAW) dirty = 1;
            got = SDL_PollEvent(&e);
        }
        if (v->playing && SDL_GetTicks() - last_play > 120) {
            last_play = SDL_GetTicks();
            view_tick(v);
            dirty = 1;
        }
        if (!dirty) continue;
        dirty = 0;
        if (SDL_MUSTLOCK(frame)) SDL_LockSurface(frame);
        viz_canvas cv;
        viz_canvas_from_surface(&cv, frame);
        view_render(v, &cv);
        if (SDL_MUSTLOCK(frame)) SDL_UnlockSurface(frame);
        SDL_Surface *ws = SDL_GetWindowSurface(win);
        if (ws) {
            SDL_BlitSurface(frame, NULL, ws, NULL);
            SDL_UpdateWindowSurface(win);
        }
        if (!in.dragging && v->pixel_step != 1) { /* refine after orbiting */
            v->pixel_step = 1;
            v->image_valid = 0;
            dirty = 1;
        }
    }
    SDL_FreeSurface(frame);
    SDL_DestroyWindow(win);
    SDL_Quit();
    return 0;
}

int main(int argc, char **argv)
{
    const char *scene = "flat2d", *shot = NULL, *html = NULL, *events = NULL;
    int w = 1100, h = 700, has_step = 0, level = -1;
    long step = 0;
    float yaw = NAN, pitch = NAN, zoom = NAN;
    view_mode mode = VIEW_2D;
    sidx_build_options knobs;
    memset(&knobs, 0, sizeof knobs);
    viz_args args = {.prog = "sidx-view", .usage = usage, .build = &knobs, .scene_operand = 0};
    for (int i = 1; i < argc; ++i) {
        const int took = viz_arg(&args, argc, argv, &i);
        if (took == VIZ_ARG_TAKEN) continue;
        if (took != VIZ_ARG_OWN) return took;
        const char *a = argv[i];
        const int has_val = i + 1 < argc;
        if (!strcmp(a, "--scene") && has_val) {
            scene = argv[++i];
        } else if (!strcmp(a, "--events") && has_val) {
            events = argv[++i];
        } else if (!strcmp(a, "--screenshot") && has_val) {
            shot = argv[++i];
        } else if (!strcmp(a, "--html") && has_val) {
            html = argv[++i];
        } else if (!strcmp(a, "--mode") && has_val) {
            if (view_mode_parse(argv[++i], &mode) != 0) {
                fprintf(stderr, "sidx-view: --mode wants 2d, build, 3d or heat, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--size") && has_val) {
            if (parse_size(argv[++i], &w, &h) != 0) {
                fprintf(stderr, "sidx-view: --size wants WxH between 64 and 8192, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(a, "--step") && has_val) {
            char *end;
            step = strtol(argv[++i], &end, 10);
            if (*end || step < 0) {
                fprintf(stderr, "sidx-view: --step wants a number >= 0, not '%s'\n", argv[i]);
                return 2;
            }
            has_step = 1;
        } else if (!strcmp(a, "--level") && has_val) {
            char *end;
            long k = strtol(argv[++i], &end, 10);
            if (*end || k < -1 || k > 1000) {
                fprintf(stderr, "sidx-view: --level wants a number >= 0, not '%s'\n", argv[i]);
                return 2;
            }
            level = (int)k;
        } else if ((!strcmp(a, "--yaw") || !strcmp(a, "--pitch") || !strcmp(a, "--zoom")) && has_val) {
            float f;
            if (parse_float(argv[++i], &f) != 0 || (!strcmp(a, "--zoom") && !(f > 0.0f))) {
                fprintf(stderr, "sidx-view: %s wants a number, not '%s'\n", a, argv[i]);
                return 2;
            }
            if (!strcmp(a, "--yaw")) yaw = f;
            else if (!strcmp(a, "--pitch")) pitch = f;
            else zoom = f;
        } else {
            return viz_arg_unknown(&args, a);
        }
    }
    if (!args.accel) args.accel = default_accel();
    const int bad_accel = viz_arg_check_accel(&args);
    if (bad_accel) return bad_accel;
    const char *accel = args.accel;
    const int has_ray = args.ray_text != NULL;
    sidx_vec3 org = args.org, dir = args.dir;
    /* before the build: a window that cannot open is said at once */
    if (!html && !shot && !display_reachable()) return 1;

    char html_msg[300];
    if (html && view_html_check_scene(scene, html_msg, sizeof html_msg) != 0) {
        fprintf(stderr, "sidx-view: %s\n", html_msg);
        return 1;
    }
    view_state v;
    sidx_error err;
    if (view_open_knobs(&v, scene, accel, &knobs, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-view: %s\n", err.message);
        view_close(&v);
        return 1;
    }
    v.mode = mode;
    v.level = level;
    if (isfinite(yaw)) v.yaw = yaw;
    if (isfinite(pitch)) v.pitch = pitch;
    if (isfinite(zoom)) v.zoom = zoom;
    if (!has_ray) view_default_ray(&v, &org, &dir);
    /* in the 3D window without an explicit ray, show none (click a pixel for
     * one); a page always gets one; a trace read from a file has no ray but
     * the one given */
    if (has_ray || (!events && (html || mode == VIEW_2D || mode == VIEW_BUILD)))
        view_set_ray(&v, org, dir, has_step && mode != VIEW_BUILD ? (size_t)step : SIZE_MAX);
    if (events && view_load_events(&v, events, has_step && mode != VIEW_BUILD ? (size_t)step : SIZE_MAX, &err) != SIDX_OK) {
        fprintf(stderr, "sidx-view: %s\n", err.message);
        view_close(&v);
        return 1;
    }
    if (mode == VIEW_BUILD) v.build_step = has_step && (size_t)step < v.build.count ? (size_t)step : v.build.count;

    int rc;
    if (html) {
        rc = view_write_html(&v, html, mode, has_step ? (size_t)step : SIZE_MAX, level, html_msg, sizeof html_msg);
        if (rc)
            fprintf(stderr, "sidx-view: %s\n", html_msg);
        else
            printf("wrote %s (%s, %s, %zu build events, %zu traversal events)\n", html, v.scene, v.accel_name,
                   v.build.count, v.trav.count);
        rc = rc ? 1 : 0;
    } else if (shot) {
        char msg[300];
        rc = view_screenshot(&v, shot, w, h, msg, sizeof msg) == 0 ? 0 : 1;
        if (rc)
            fprintf(stderr, "sidx-view: %s\n", msg);
        else
            printf("wrote %s (%dx%d, %s mode, %s, step %zu/%zu)\n", shot, w, h, view_mode_name(v.mode), v.accel_name,
                   v.mode == VIEW_BUILD ? v.build_step : v.step, v.mode == VIEW_BUILD ? v.build.count : v.trav.count);
    } else {
        rc = run_window(&v, w, h);
    }
    view_close(&v);
    return rc;
}
