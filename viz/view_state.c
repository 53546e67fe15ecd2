/* view_state.c — what the viewer knows: the scene, the structure built
 * with a recorder, the tree rebuilt from the build events, one ray's
 * recorded traversal, and the replay of its first N events. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "view.h"

static const char *const mode_names[VIEW_MODE_COUNT] = {"2d", "build", "3d", "heat"};

const char *view_mode_name(view_mode m) { return (unsigned)m < VIEW_MODE_COUNT ? mode_names[m] : "?"; }

int view_mode_parse(const char *s, view_mode *m)
{
    for (int i = 0; s && i < VIEW_MODE_COUNT; ++i)
        if (!strcmp(s, mode_names[i])) {
            *m = (view_mode)i;
            return 0;
        }
    return -1;
}

static void set_err(sidx_error *err, sidx_status s, const char *msg)
{
    if (!err) return;
    err->status = s;
    snprintf(err->message, sizeof err->message, "%s", msg);
}

static sidx_status build(view_state *v, const char *accel, sidx_error *err)
{
    sidx_accel_destroy(v->accel);
    v->accel = NULL;
    sidx_viz_tree_free(&v->tree);
    v->has_tree = 0;
    sidx_recorder_clear(&v->build);
    free(v->node_mark);
    v->node_mark = NULL;
    v->image_valid = 0;

    sidx_hook h = sidx_recorder_hook(&v->build);
    h.mask = SIDX_EVMASK_BUILD;
    sidx_build_options bo = v->knobs;
    bo.hook = &h;
    /* the scene's own tree where it has one (kd-slide: the slide's, labelled) */
    sidx_status s = sidx_scene_accel_build(v->scene, accel, &v->mesh, &bo, &v->accel, err);
    if (s != SIDX_OK) return s;
    snprintf(v->accel_name, sizeof v->accel_name, "%s", accel);
    sidx_error terr;
    if (sidx_viz_tree_from_events(v->build.events, v->build.count, &v->tree, &terr) == SIDX_OK) {
        v->has_tree = 1;
        v->tree_msg[0] = '\0';
        v->node_mark = calloc(v->tree.count ? v->tree.count : 1, 1);
        if (!v->node_mark) {
            set_err(err, SIDX_ERR_NOMEM, "out of memory");
            return SIDX_ERR_NOMEM;
        }
    } else {
        snprintf(v->tree_msg, sizeof v->tree_msg, "%s", terr.message);
    }
    v->build_step = v->build.count;
    if (v->has_ray) return view_set_ray(v, v->org, v->dir, SIZE_MAX);
    return SIDX_OK;
}

static sidx_status open_mesh(view_state *v, sidx_mesh *mesh, const char *name, const char *accel,
                             const sidx_build_options *knobs, sidx_error *err)
{
    memset(v, 0, sizeof *v);
    if (knobs) v->knobs = *knobs;
    v->knobs.hook = NULL;
    v->mesh = *mesh;
    memset(mesh, 0, sizeof *mesh);
    snprintf(v->scene, sizeof v->scene, "%s", name ? name : "mesh");
    sidx_recorder_init(&v->build);
    sidx_recorder_init(&v->trav);
    v->bounds = sidx_mesh_bounds(&v->mesh);
    v->yaw = 0.6f;
    v->pitch = 0.35f;
    v->zoom = 1.0f;
    v->level = -1;
    v->pixel_step = 1;
    v->prim_mark = calloc(v->mesh.num_triangles ? v->mesh.num_triangles : 1, 1);
    if (!v->prim_mark) {
        set_err(err, SIDX_ERR_NOMEM, "out of memory");
        return SIDX_ERR_NOMEM;
    }
    return build(v, accel, err);
}

sidx_status view_open_mesh(view_state *v, sidx_mesh *mesh, const char *name, const char *accel, sidx_error *err)
{
    return open_mesh(v, mesh, name, accel, NULL, err);
}

sidx_status view_open(view_state *v, const char *scene, const char *accel, sidx_error *err)
{
    return view_open_knobs(v, scene, accel, NULL, err);
}

sidx_status view_open_knobs(view_state *v, const char *scene, const char *accel, const sidx_build_options *knobs,
                            sidx_error *err)
{
    sidx_mesh m;
    memset(&m, 0, sizeof m);
    memset(v, 0, sizeof *v);
    sidx_recorder_init(&v->build);
    sidx_recorder_init(&v->trav);
    sidx_status s = sidx_scene_open(scene, &m, err);
    if (s != SIDX_OK) return s;
    return open_mesh(v, &m, scene, accel, knobs, err);
}

sidx_status view_set_accel(view_state *v, const char *accel, sidx_error *err) { return build(v, accel, err); }

void view_close(view_state *v)
{
    if (!v) return;
    sidx_accel_destroy(v->accel);
    sidx_viz_tree_free(&v->tree);
    sidx_recorder_free(&v->build);
    sidx_recorder_free(&v->trav);
    free(v->trace_store);
    sidx_mesh_free(&v->mesh);
    free(v->image);
    free(v->prim_mark);
    free(v->node_mark);
    memset(v, 0, sizeof *v);
}

sidx_status view_set_ray(view_state *v, sidx_vec3 org, sidx_vec3 dir, size_t step)
{
    sidx_ray r;
    if (sidx_ray_init(&r, org, dir, 0.0f, INFINITY) != SIDX_OK) return SIDX_ERR_INVALID_ARG;
    v->has_ray = 1;
    v->org = org;
    v->dir = dir;
    v->trace_path[0] = '\0';
    sidx_recorder_clear(&v->trav);
    if (!v->accel) return SIDX_OK;
    sidx_hook h = sidx_recorder_hook(&v->trav);
    h.mask = SIDX_EVMASK_TRAVERSAL;
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &h;
    sidx_hit hit;
    sidx_accel_intersect(v->accel, &r, &q, &hit);
    v->step = step > v->trav.count ? v->trav.count : step;
    return SIDX_OK;
}

/* Whether event e of a trace fits the structure built here; if not, why. */
static int event_fits(const view_state *v, const sidx_event *e, uint32_t nodes, char *why, size_t size)
{
    if (!(SIDX_EVMASK_TRAVERSAL & SIDX_EVMASK(e->type))) {
        snprintf(why, size, "a %s event: --events takes a traversal trace (sidx-step --json, sidx-check --trace)",
                 sidx_event_type_name(e->type));
        return 0;
    }
    /* kdtree-binned's walk names itself "kdtree": a name that begins the
     * other is the same family */
    const char *st = e->structure;
    const size_t sl = st ? strlen(st) : 0, al = strlen(v->accel_name);
    if (sl && strncmp(st, v->accel_name, sl < al ? sl : al) != 0) {
        snprintf(why, size, "a trace of %.40s, but the structure built here is %.40s (--accel)", st, v->accel_name);
        return 0;
    }
    const int has_node = e->type == SIDX_EV_NODE_ENTER || e->type == SIDX_EV_BOX_TEST ||
                         e->type == SIDX_EV_STACK_PUSH || e->type == SIDX_EV_STACK_POP;
    if (has_node && e->node != UINT32_MAX && nodes != UINT32_MAX && e->node >= nodes) {
        snprintf(why, size, "node %u is out of range: the %s built here has %u nodes (give the --scene, --accel "
                 "and build knobs the trace was recorded with)", (unsigned)e->node, v->accel_name, (unsigned)nodes);
        return 0;
    }
    const int has_prim = e->type == SIDX_EV_PRIM_TEST || e->type == SIDX_EV_HIT_UPDATE ||
                         e->type == SIDX_EV_MAILBOX_HIT || e->type == SIDX_EV_RAY_END;
    if (has_prim && e->prim != UINT32_MAX && e->prim >= v->mesh.num_triangles) {
        snprintf(why, size, "triangle %u is out of range: scene %.60s has %u triangles (give the --scene the trace "
                 "was recorded with)", (unsigned)e->prim, v->scene, (unsigned)v->mesh.num_triangles);
        return 0;
    }
    return 1;
}

sidx_status view_load_events(view_state *v, const char *path, size_t step, sidx_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        if (err) {
            err->status = SIDX_ERR_IO;
            snprintf(err->message, sizeof err->message, "cannot open %.200s", path);
        }
        return SIDX_ERR_IO;
    }
    /* the whole file, then one store for every line's strings: a line
     * needs at most 2 * its length + 16 bytes (sidx_event_from_json) */
    size_t size = 0, cap = 0;
    char *text = NULL;
    for (;;) {
        if (size + 4096 + 1 > cap) {
            cap = cap ? 2 * cap : 65536;
            char *grown = realloc(text, cap);
            if (!grown) break;
            text = grown;
        }
        const size_t got = fread(text + size, 1, cap - size - 1, f);
        size += got;
        if (got == 0) break;
    }
    const int read_error = ferror(f) || !text;
    fclose(f);
    size_t lines = 1;
    for (size_t i = 0; text && i < size; ++i) lines += text[i] == '\n';
    const size_t store_size = 2 * size + 16 * lines;
    char *store = read_error ? NULL : malloc(store_size);
    sidx_event *evs = read_error ? NULL : malloc(lines * sizeof *evs);
    sidx_status s = SIDX_OK;
    if (!store || !evs) {
        s = read_error ? SIDX_ERR_IO : SIDX_ERR_NOMEM;
        if (err) snprintf(err->message, sizeof err->message, "%.200s: %s", path,
                          read_error ? "cannot read" : "out of memory");
    }
    uint32_t nodes = UINT32_MAX; /* the node count the build reported, if it did */
    for (size_t k = 0; k < v->build.count; ++k)
        if (v->build.events[k].type == SIDX_EV_BUILD_END) nodes = v->build.events[k].node;
    size_t n = 0, used = 0, lineno = 0;
    char *line = text;
    if (text) text[size] = '\0';
    while (s == SIDX_OK && line && line < text + size) {
        ++lineno;
        char *end = strchr(line, '\n');
        if (end) *end = '\0';
        char *next = end ? end + 1 : NULL;
        size_t len = strlen(line);
        while (len && (line[len - 1] == '\r' || line[len - 1] == ' ' || line[len - 1] == '\t')) line[--len] = '\0';
        if (len) {
            size_t taken = 0;
            char why[240];
            sidx_error e2 = {SIDX_OK, ""};
            s = sidx_event_from_json(line, &evs[n], store + used, store_size - used, &taken, &e2);
            if (s != SIDX_OK) {
                if (err) snprintf(err->message, sizeof err->message, "%.80s:%zu: not a sidx event: %.140s", path, lineno,
                                  e2.message);
            } else if (!event_fits(v, &evs[n], nodes, why, sizeof why)) {
                s = SIDX_ERR_INVALID_ARG;
                if (err) snprintf(err->message, sizeof err->message, "%.60s:%zu: %.180s", path, lineno, why);
            }
            used += taken;
            ++n;
        }
        line = next;
    }
    if (s == SIDX_OK && n == 0) {
        s = SIDX_ERR_PARSE;
        if (err) snprintf(err->message, sizeof err->message, "%.200s: no events in the file", path);
    }
    free(text);
    if (s != SIDX_OK) {
        if (err) err->status = s;
        free(store);
        free(evs);
        return s;
    }
    sidx_recorder_free(&v->trav);
    free(v->trace_store);
    v->trace_store = store;
    v->trav.events = evs;
    v->trav.count = n;
    v->trav.capacity = lines;
    snprintf(v->trace_path, sizeof v->trace_path, "%s", path);
    v->step = step > n ? n : step;
    return SIDX_OK;
}

void view_default_ray(const view_state *v, sidx_vec3 *org, sidx_vec3 *dir)
{
    /* from the left edge, low, rising gently: it crosses most of a 2D
     * scene and so most of the structure (on flat2d it passes by the
     * first shapes' spines and hits far right, so a kd-tree pushes and
     * pops before it stops) */
    sidx_aabb b = v->bounds;
    if (sidx_aabb_is_empty(b)) b.min = b.max = sidx_v3(0, 0, 0);
    sidx_vec3 e = sidx_aabb_extent(b), c = sidx_aabb_centroid(b);
    *org = sidx_v3(b.min.x - 0.05f * e.x, b.min.y + 0.15f * e.y, c.z);
    *dir = sidx_v3(1.0f, e.x > 0.0f ? 0.35f * e.y / e.x : 0.3f, 0.0f);
}

void view_replay_run(const view_state *v, size_t step, view_replay *r)
{
    memset(r, 0, sizeof *r);
    r->current = SIDX_VIZ_NONE;
    r->current_id = SIDX_VIZ_NONE;
    r->current_box = sidx_aabb_empty();
    r->cur_t_near = r->cur_t_far = NAN;
    r->best_prim = SIDX_NO_HIT;
    r->best_t = INFINITY;
    if (v->prim_mark) memset(v->prim_mark, 0, v->mesh.num_triangles ? v->mesh.num_triangles : 1);
    if (v->node_mark) memset(v->node_mark, 0, v->tree.count ? v->tree.count : 1);
    if (step > v->trav.count) step = v->trav.count;
    for (size_t i = 0; i < step; ++i) {
        const sidx_event *e = &v->trav.events[i];
        uint32_t x = v->has_tree ? sidx_viz_tree_find(&v->tree, e->node) : SIDX_VIZ_NONE;
        switch (e->type) {
        case SIDX_EV_NODE_ENTER:
            r->current = x;
            r->current_id = e->node;
            r->current_box = !sidx_aabb_is_empty(e->bounds) ? e->bounds
                             : x != SIDX_VIZ_NONE          ? v->tree.nodes[x].bounds
                                                           : sidx_aabb_empty();
            if (sidx_aabb_is_empty(r->current_box) && x == SIDX_VIZ_NONE) /* cells of a structure without a tree */
                for (size_t k = 0; k < v->build.count; ++k)
                    if (v->build.events[k].type == SIDX_EV_BUILD_NODE && v->build.events[k].node == e->node) {
                        r->current_box = v->build.events[k].bounds;
                        break;
                    }
            r->cur_t_near = e->t_near;
            r->cur_t_far = e->t_far;
            r->nodes_entered++;
            if (x != SIDX_VIZ_NONE) v->node_mark[x] = 1;
            break;
        case SIDX_EV_BOX_TEST:
            r->box_tests++;
            if (x != SIDX_VIZ_NONE && v->node_mark[x] != 1) v->node_mark[x] = e->result == 1 ? 3 : 2;
            break;
        case SIDX_EV_STACK_PUSH:
            if (r->stack_n < 64) {
                view_stack_entry se = {e->node, e->t_near, e->t_far};
                r->stack[r->stack_n++] = se;
            } else {
                r->stack_more++;
            }
            break;
        case SIDX_EV_STACK_POP:
            if (r->stack_more > 0) {
                r->stack_more--;
            } else if (r->stack_n > 0) {
                /* the popped node is normally on top; search down to be safe */
                int k = r->stack_n - 1;
                while (k > 0 && r->stack[k].node != e->node) --k;
                if (r->stack[k].node != e->node) k = r->stack_n - 1;
                memmove(&r->stack[k], &r->stack[k + 1], (size_t)(r->stack_n - 1 - k) * sizeof r->stack[0]);
                r->stack_n--;
            }
            break;
        case SIDX_EV_PRIM_TEST:
            r->prim_tests++;
            if (e->prim < v->mesh.num_triangles) v->prim_mark[e->prim] = e->result == 1 ? 2 : 1;
            break;
        case SIDX_EV_MAILBOX_HIT:
            r->mailbox_hits++;
            if (e->prim < v->mesh.num_triangles && v->prim_mark[e->prim] == 0) v->prim_mark[e->prim] = 3;
            break;
        case SIDX_EV_HIT_UPDATE:
            r->best_prim = e->prim;
            r->best_t = e->t;
            break;
        case SIDX_EV_RAY_END:
            r->best_prim = e->prim;
            r->best_t = e->t;
            break;
        default:
            break;
        }
    }
}
