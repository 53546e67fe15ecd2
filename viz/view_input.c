/* view_input.c — what sidx-view does with keys and the mouse, apart from
 * the window so that tests can feed it synthetic SDL events. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "view.h"

void view_input_init(view_input *in, int w, int h)
{
    memset(in, 0, sizeof in[0]);
    in->w = w;
    in->h = h;
    snprintf(in->screenshot_path, sizeof in->screenshot_path, "sidx-view.png");
}

static size_t *cur_step(view_state *v) { return v->mode == VIEW_BUILD ? &v->build_step : &v->step; }
static size_t cur_count(const view_state *v) { return v->mode == VIEW_BUILD ? v->build.count : v->trav.count; }

void view_tick(view_state *v)
{
    if (*cur_step(v) < cur_count(v))
        ++*cur_step(v);
    else
        v->playing = 0;
}

static void next_accel(view_state *v)
{
    size_t n = sidx_accel_registered_count(), k = 0;
    for (size_t i = 0; i < n; ++i)
        if (!strcmp(sidx_accel_registered_name(i), v->accel_name)) k = i;
    for (size_t j = 1; j <= n; ++j) {
        const char *name = sidx_accel_registered_name((k + j) % n);
        sidx_error err;
        if (view_set_accel(v, name, &err) == SIDX_OK) return;
        fprintf(stderr, "sidx-view: %s: %s\n", name, err.message);
    }
}

static int handle_key(view_state *v, view_input *in, SDL_Keycode k)
{
    if (v->show_help && k != SDLK_F1) {
        v->show_help = 0; /* any key closes the help */
        return VIEW_INPUT_REDRAW;
    }
    switch (k) {
    case SDLK_ESCAPE:
    case SDLK_q: return VIEW_INPUT_QUIT;
    case SDLK_F1:
    case SDLK_h: v->show_help = !v->show_help; break;
    case SDLK_RIGHT:
        if (*cur_step(v) < cur_count(v)) ++*cur_step(v);
        break;
    case SDLK_LEFT:
        if (*cur_step(v) > 0) --*cur_step(v);
        break;
    case SDLK_HOME: *cur_step(v) = 0; break;
    case SDLK_END: *cur_step(v) = cur_count(v); break;
    case SDLK_SPACE:
        v->playing = !v->playing;
        if (v->playing && *cur_step(v) >= cur_count(v)) *cur_step(v) = 0;
        break;
    case SDLK_TAB: v->mode = (view_mode)((v->mode + 1) % VIEW_MODE_COUNT); break;
    case SDLK_1:
    case SDLK_2:
    case SDLK_3:
    case SDLK_4: v->mode = (view_mode)(k - SDLK_1); break;
    case SDLK_n: next_accel(v); break;
    case SDLK_PLUS:
    case SDLK_EQUALS:
    case SDLK_KP_PLUS:
        if (v->level < (int)v->tree.max_depth) v->level++;
        break;
    case SDLK_MINUS:
    case SDLK_KP_MINUS:
        if (v->level >= 0) v->level--;
        break;
    case SDLK_r: {
        sidx_vec3 o, d;
        view_default_ray(v, &o, &d);
        view_set_ray(v, o, d, 0);
        v->yaw = 0.6f;
        v->pitch = 0.35f;
        v->zoom = 1.0f;
        v->image_valid = 0;
        break;
    }
    case SDLK_s: {
        char msg[256];
        if (view_screenshot(v, in->screenshot_path, in->w, in->h, msg, sizeof msg) == 0)
            printf("wrote %s\n", in->screenshot_path);
        else
            fprintf(stderr, "sidx-view: %s\n", msg);
        break;
    }
    default: return 0;
    }
    return VIEW_INPUT_REDRAW;
}

int view_handle_event(view_state *v, view_input *in, const SDL_Event *e)
{
    const int sw = view_scene_width(in->w), h = in->h;
    const int is3d = v->mode == VIEW_3D || v->mode == VIEW_HEAT;
    switch (e->type) {
    case SDL_QUIT: return VIEW_INPUT_QUIT;
    case SDL_KEYDOWN: return handle_key(v, in, e->key.keysym.sym);
    case SDL_MOUSEBUTTONDOWN:
        if (e->button.button == SDL_BUTTON_LEFT && e->button.x < sw) {
            in->dragging = 1;
            in->moved = 0;
            in->press_x = e->button.x;
            in->press_y = e->button.y;
        }
        return 0;
    case SDL_MOUSEMOTION:
        if (!in->dragging) return 0;
        in->moved |= abs(e->motion.x - in->press_x) + abs(e->motion.y - in->press_y) > 3;
        if (is3d && in->moved) {
            v->yaw -= (float)e->motion.xrel * 0.01f;
            v->pitch += (float)e->motion.yrel * 0.01f;
            if (v->pitch > 1.5f) v->pitch = 1.5f;
            if (v->pitch < -1.5f) v->pitch = -1.5f;
            v->pixel_step = 4; /* coarse while orbiting */
            v->image_valid = 0;
            return VIEW_INPUT_REDRAW;
        }
        return 0;
    case SDL_MOUSEBUTTONUP:
        if (e->button.button != SDL_BUTTON_LEFT || !in->dragging) return 0;
        in->dragging = 0;
        if (!is3d) {
            if (in->moved) { /* a ray from the press point towards the release point, in the scene's middle z */
                float x0, y0, x1, y1;
                view_2d_to_world(v, in->w, h, (float)in->press_x, (float)in->press_y, &x0, &y0);
                view_2d_to_world(v, in->w, h, (float)e->button.x, (float)e->button.y, &x1, &y1);
                float z = 0.5f * (v->bounds.min.z + v->bounds.max.z);
                if (view_set_ray(v, sidx_v3(x0, y0, z), sidx_v3(x1 - x0, y1 - y0, 0.0f), 0) == SIDX_OK)
                    v->mode = VIEW_2D;
            }
        } else if (!in->moved) { /* a click: that pixel's camera ray, stepped from the start */
            sidx_vec3 o, d;
            view_camera_ray(v, (float)e->button.x + 0.5f, (float)e->button.y + 0.5f, sw, h, &o, &d);
            view_set_ray(v, o, d, 0);
        } else {
            v->pixel_step = 1;
            v->image_valid = 0;
        }
        return VIEW_INPUT_REDRAW;
    case SDL_MOUSEWHEEL:
        if (!is3d || e->wheel.y == 0) return 0;
        v->zoom *= e->wheel.y > 0 ? 1.15f : 1.0f / 1.15f;
        v->image_valid = 0;
        return VIEW_INPUT_REDRAW;
    case SDL_WINDOWEVENT: return VIEW_INPUT_REDRAW;
    default: return 0;
    }
}
