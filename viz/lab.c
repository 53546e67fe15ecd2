/* lab.c — the lab's entry layer (lab.h): open a scene, build up to two
 * structures with the programs' knobs, trace a ray with a recorder, compare
 * two walks, count a heat map.  Every answer is JSON from json_write.c.
 * The web build (`make web`) compiles this file with the library's sources
 * for the page; sidx-lab runs the same calls natively, so the two can be
 * compared answer for answer. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "camera.h"
#include "json_write.h"
#include "lab.h"
#include "sidx/sidx.h"
#include "sidx/viz.h"

typedef struct lab_slot {
    sidx_accel *accel;
    sidx_recorder build;      /* the build's events */
    sidx_traversal traversal;
    char args[256];           /* the knobs as sidx-step flags */
    double build_ms;
    size_t cand_total;        /* SAH candidates the build proposed (the first SIDX_LAB_MAX_CANDIDATES kept) */
    sidx_recorder trace;      /* the last ray's events */
    int has_trace, truncated;
    double trace_ms;          /* the recorded query's wall time */
    sidx_vec3 org, dir;
    sidx_hit hit;
} lab_slot;

static struct lab {
    int has_scene;
    sidx_mesh mesh;
    char name[128];           /* the scene's name (a built-in's spec, or the file's name) */
    int builtin;              /* 1: name is a built-in scene spec (sidx_scene_accel_build uses it) */
    lab_slot slot[SIDX_LAB_SLOTS];
    char error[320];
    viz_json out[10];          /* one answer per kind, valid until that kind is asked again */
    uint32_t *heat;
    size_t heat_cap;
} lab;

enum { OUT_SCENES, OUT_STRUCTS, OUT_SCENE, OUT_OBJ, OUT_BUILD, OUT_TRACE, OUT_DIVERGE, OUT_HEAT, OUT_MISC, OUT_EVENTS };

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

static int fail(int status, const char *msg)
{
    snprintf(lab.error, sizeof lab.error, "%s", msg);
    return status;
}

static int ok(void)
{
    lab.error[0] = '\0';
    return 0;
}

/* Starts answer `k` afresh. */
static viz_json *answer(int k)
{
    viz_json *b = &lab.out[k];
    b->n = 0;
    b->failed = 0;
    if (b->s) b->s[0] = '\0';
    return b;
}

/* The answer's text; "null" if writing it ran out of memory (error says so). */
static const char *done(viz_json *b)
{
    if (b->failed || !b->s) {
        if (b->failed) fail(SIDX_ERR_NOMEM, "out of memory writing the answer");
        return "null";
    }
    return b->s;
}

static const char *null_answer(int k)
{
    viz_json *b = answer(k);
    viz_json_put(b, "null");
    return done(b);
}

/* 9 significant digits: a float printed so that strtof reads it back exactly. */
static void put_exact(viz_json *b, float f)
{
    if (isfinite(f)) viz_json_printf(b, "%.9g", (double)f);
    else viz_json_float(b, f);
}

static void put_exact3(viz_json *b, sidx_vec3 v)
{
    put_exact(b, v.x);
    viz_json_put(b, ",");
    put_exact(b, v.y);
    viz_json_put(b, ",");
    put_exact(b, v.z);
}

static void put_ray(viz_json *b, sidx_vec3 o, sidx_vec3 d)
{
    viz_json_put(b, "\"o\":[");
    put_exact3(b, o);
    viz_json_put(b, "],\"d\":[");
    put_exact3(b, d);
    viz_json_printf(b, "],\"ray_arg\":\"%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\"", (double)o.x, (double)o.y, (double)o.z,
                    (double)d.x, (double)d.y, (double)d.z);
}

static int mesh_dims(const sidx_mesh *m)
{
    return viz_scene_is_flat(sidx_mesh_bounds(m)) ? 2 : 3;
}

static void slot_clear(lab_slot *s)
{
    sidx_accel_destroy(s->accel);
    s->accel = NULL;
    sidx_recorder_free(&s->build);
    sidx_recorder_free(&s->trace);
    s->has_trace = s->truncated = 0;
    s->args[0] = '\0';
    s->build_ms = 0.0;
    s->cand_total = 0;
}

static void drop_scene(void)
{
    for (int i = 0; i < SIDX_LAB_SLOTS; ++i) slot_clear(&lab.slot[i]);
    if (lab.has_scene) sidx_mesh_free(&lab.mesh);
    memset(&lab.mesh, 0, sizeof lab.mesh);
    lab.has_scene = 0;
    lab.name[0] = '\0';
}

void sidx_lab_reset(void)
{
    drop_scene();
    for (size_t i = 0; i < sizeof lab.out / sizeof lab.out[0]; ++i) free(lab.out[i].s);
    free(lab.heat);
    memset(&lab, 0, sizeof lab);
}

const char *sidx_lab_error(void) { return lab.error; }

/* ---- scenes ------------------------------------------------------------------------------- */

const char *sidx_lab_scenes(void)
{
    viz_json *b = answer(OUT_SCENES);
    viz_json_printf(b, "{\"limit\":%u,\"scenes\":[", SIDX_LAB_MAX_TRIANGLES);
    const char *const *names = sidx_scene_names();
    for (size_t i = 0; names[i]; ++i) {
        sidx_mesh m;
        memset(&m, 0, sizeof m);
        if (sidx_scene_make(names[i], 0, &m, NULL) != SIDX_OK) continue;
        viz_json_put(b, i ? ",{\"name\":" : "{\"name\":");
        viz_json_string(b, names[i]);
        viz_json_printf(b, ",\"dims\":%d,\"triangles\":%u}", mesh_dims(&m), m.num_triangles);
        sidx_mesh_free(&m);
    }
    viz_json_put(b, "]}");
    ok();
    return done(b);
}

/* Takes over m (zeroed on success) as the open scene, or refuses it. */
static int take_scene(sidx_mesh *m, const char *name, int builtin)
{
    if (m->num_triangles > SIDX_LAB_MAX_TRIANGLES) {
        snprintf(lab.error, sizeof lab.error,
                 "scene '%s' has %u triangles; the page holds at most %u (it draws them all at every step)", name,
                 m->num_triangles, SIDX_LAB_MAX_TRIANGLES);
        sidx_mesh_free(m);
        return SIDX_ERR_LIMIT;
    }
    drop_scene();
    lab.mesh = *m;
    memset(m, 0, sizeof *m);
    lab.has_scene = 1;
    lab.builtin = builtin;
    snprintf(lab.name, sizeof lab.name, "%s", name);
    return ok();
}

int sidx_lab_open_scene(const char *name)
{
    if (!name || !name[0]) return fail(SIDX_ERR_INVALID_ARG, "no scene name");
    /* built-in scenes only: the page has no file system (a file comes as bytes) */
    const char *colon = strchr(name, ':');
    const size_t n = colon ? (size_t)(colon - name) : strlen(name);
    int known = 0;
    for (const char *const *s = sidx_scene_names(); *s; ++s)
        if (strlen(*s) == n && !strncmp(*s, name, n)) known = 1;
    if (!known) {
        snprintf(lab.error, sizeof lab.error, "no built-in scene '%s' (sidx_lab_scenes lists them)", name);
        return SIDX_ERR_INVALID_ARG;
    }
    sidx_mesh m;
    sidx_error err;
    memset(&m, 0, sizeof m);
    sidx_status st = sidx_scene_open(name, &m, &err);
    if (st != SIDX_OK) return fail(st, err.message);
    return take_scene(&m, name, 1);
}

static int ends_with(const char *s, const char *suffix)
{
    const size_t n = strlen(s), k = strlen(suffix);
    if (n < k) return 0;
    for (size_t i = 0; i < k; ++i) {
        char c = s[n - k + i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != suffix[i]) return 0;
    }
    return 1;
}

int sidx_lab_open_obj(const char *bytes, int len, const char *file_name)
{
    if (!bytes || len < 0) return fail(SIDX_ERR_INVALID_ARG, "no file contents");
    const char *name = file_name && file_name[0] ? file_name : "scene.obj";
    sidx_mesh m;
    sidx_error err;
    memset(&m, 0, sizeof m);
    sidx_status st = ends_with(name, ".ply") ? sidx_mesh_parse_ply(bytes, (size_t)len, name, &m, &err)
                                             : sidx_mesh_parse_obj(bytes, (size_t)len, name, &m, &err);
    if (st != SIDX_OK) return fail(st, err.message);
    if (m.num_triangles == 0) {
        sidx_mesh_free(&m);
        snprintf(lab.error, sizeof lab.error, "%s: no triangles", name);
        return SIDX_ERR_PARSE;
    }
    return take_scene(&m, name, 0);
}

const char *sidx_lab_scene_json(void)
{
    if (!lab.has_scene) return null_answer(OUT_SCENE);
    viz_json *b = answer(OUT_SCENE);
    const sidx_mesh *m = &lab.mesh;
    viz_json_put(b, "{\"name\":");
    viz_json_string(b, lab.name);
    viz_json_printf(b, ",\"dims\":%d,\"vertices\":%u,\"triangles\":%u,\"bounds\":[", mesh_dims(m), m->num_vertices,
                    m->num_triangles);
    const sidx_aabb box = sidx_mesh_bounds(m);
    viz_json_xyz(b, box.min);
    viz_json_put(b, ",");
    viz_json_xyz(b, box.max);
    viz_json_put(b, "],\"pos\":[");
    for (uint32_t i = 0; i < m->num_vertices; ++i) {
        if (i) viz_json_put(b, ",");
        viz_json_xyz(b, m->positions[i]);
    }
    viz_json_put(b, "],\"idx\":[");
    for (uint32_t i = 0; i < 3u * m->num_triangles; ++i) viz_json_printf(b, i ? ",%u" : "%u", m->indices[i]);
    viz_json_put(b, "]}");
    return done(b);
}

int sidx_lab_scene_triangles(void) { return lab.has_scene ? (int)lab.mesh.num_triangles : -1; }

const char *sidx_lab_scene_obj(void)
{
    viz_json *b = answer(OUT_OBJ);
    viz_json_put(b, "");
    if (!lab.has_scene) return done(b);
    const sidx_mesh *m = &lab.mesh;
    viz_json_put(b, "# ");
    viz_json_put(b, lab.name);
    viz_json_put(b, "\n");
    for (uint32_t i = 0; i < m->num_vertices; ++i)
        viz_json_printf(b, "v %.9g %.9g %.9g\n", (double)m->positions[i].x, (double)m->positions[i].y,
                        (double)m->positions[i].z);
    for (uint32_t i = 0; i < m->num_triangles; ++i)
        viz_json_printf(b, "f %u %u %u\n", m->indices[3 * i] + 1, m->indices[3 * i + 1] + 1, m->indices[3 * i + 2] + 1);
    return done(b);
}

/* quadtree never splits z: it suits a flat scene only; the rest suit any. */
static int suits(const char *accel, int dims)
{
    return strcmp(accel, "quadtree") != 0 || dims == 2;
}

const char *sidx_lab_structures(void)
{
    viz_json *b = answer(OUT_STRUCTS);
    const int dims = lab.has_scene ? mesh_dims(&lab.mesh) : 3;
    viz_json_put(b, "{\"structures\":[");
    for (size_t i = 0; i < sidx_accel_registered_count(); ++i) {
        const char *name = sidx_accel_registered_name(i);
        viz_json_put(b, i ? ",{\"name\":" : "{\"name\":");
        viz_json_string(b, name);
        viz_json_put(b, ",\"description\":");
        viz_json_string(b, sidx_accel_registered_description(i));
        viz_json_printf(b, ",\"suits\":%s}", suits(name, dims) ? "true" : "false");
    }
    viz_json_put(b, "]}");
    return done(b);
}

/* ---- knobs -------------------------------------------------------------------------------- */

typedef struct knob_key { const char *key, *flag; } knob_key;
static const knob_key knob_keys[] = {
    {"bins", "--bins"},           {"c_trav", "--c-trav"},     {"c_tri", "--c-tri"},
    {"leaf_size", "--leaf-size"}, {"max_depth", "--max-depth"}, {"lambda", "--lambda"},
    {"empty_bonus", "--empty-bonus"}, {"optimize", "--optimize"},
};

static const char *skip_ws(const char *p)
{
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') ++p;
    return p;
}

/* A JSON string without escapes into out; the character after it, or NULL. */
static const char *read_string(const char *p, char *out, size_t size)
{
    if (*p != '"') return NULL;
    size_t n = 0;
    for (++p; *p && *p != '"'; ++p) {
        if (*p == '\\' || n + 1 >= size) return NULL;
        out[n++] = *p;
    }
    if (*p != '"') return NULL;
    out[n] = '\0';
    return p + 1;
}

/* Parses knobs_json into bo, traversal and args (the sidx-step flags). */
static int parse_knobs(const char *json, sidx_build_options *bo, sidx_traversal *trav, char *args, size_t args_size)
{
    args[0] = '\0';
    if (!json) return 0;
    const char *p = skip_ws(json);
    if (!*p) return 0;
    if (*p != '{') return fail(SIDX_ERR_INVALID_ARG, "knobs: want a JSON object such as {\"bins\":16}");
    p = skip_ws(p + 1);
    if (*p == '}') return *skip_ws(p + 1) ? fail(SIDX_ERR_INVALID_ARG, "knobs: text after the object") : 0;
    for (;;) {
        char key[32], value[64];
        p = read_string(skip_ws(p), key, sizeof key);
        if (!p) return fail(SIDX_ERR_INVALID_ARG, "knobs: want a key in double quotes");
        p = skip_ws(p);
        if (*p != ':') return fail(SIDX_ERR_INVALID_ARG, "knobs: want ':' after a key");
        p = skip_ws(p + 1);
        int is_string = 0;
        if (*p == '"') {
            p = read_string(p, value, sizeof value);
            if (!p) return fail(SIDX_ERR_INVALID_ARG, "knobs: a string value too long or with escapes");
            is_string = 1;
        } else {
            size_t n = 0;
            while (*p && *p != ',' && *p != '}' && *p != ' ' && *p != '\n' && n + 1 < sizeof value) value[n++] = *p++;
            value[n] = '\0';
        }
        const int is_null = !is_string && !strcmp(value, "null");
        char msg[200];
        if (!strcmp(key, "mailbox")) {
            if (is_string || (strcmp(value, "true") && strcmp(value, "false") && !is_null))
                return fail(SIDX_ERR_INVALID_ARG, "knobs: mailbox wants true or false");
            if (!strcmp(value, "false")) {
                sidx_viz_build_knob("--no-mailbox", NULL, bo, msg, sizeof msg);
                snprintf(args + strlen(args), args_size - strlen(args), "%s--no-mailbox", args[0] ? " " : "");
            }
        } else if (!strcmp(key, "traversal")) {
            if (!is_null && sidx_traversal_parse(value, trav) != SIDX_OK)
                return fail(SIDX_ERR_INVALID_ARG, "knobs: traversal wants default, stack, ordered or naive");
            if (!is_null && *trav != SIDX_TRAVERSE_DEFAULT)
                snprintf(args + strlen(args), args_size - strlen(args), "%s--traversal %s", args[0] ? " " : "",
                         value);
        } else {
            const knob_key *k = knob_keys;
            const knob_key *end = knob_keys + sizeof knob_keys / sizeof knob_keys[0];
            while (k < end && strcmp(k->key, key)) ++k;
            if (k == end) {
                snprintf(lab.error, sizeof lab.error,
                         "knobs: no knob '%s' (bins, c_trav, c_tri, leaf_size, max_depth, lambda, mailbox, "
                         "empty_bonus, optimize, traversal)",
                         key);
                return SIDX_ERR_INVALID_ARG;
            }
            if (!is_null) {
                if (sidx_viz_build_knob(k->flag, value, bo, msg, sizeof msg) < 0) {
                    snprintf(lab.error, sizeof lab.error, "knobs: %s", msg);
                    return SIDX_ERR_INVALID_ARG;
                }
                snprintf(args + strlen(args), args_size - strlen(args), "%s%s %s", args[0] ? " " : "", k->flag,
                         value);
            }
        }
        p = skip_ws(p);
        if (*p == ',') {
            p = skip_ws(p + 1);
            continue;
        }
        if (*p == '}' && !*skip_ws(p + 1)) return 0;
        return fail(SIDX_ERR_INVALID_ARG, "knobs: want ',' or '}' after a value");
    }
}

/* ---- build -------------------------------------------------------------------------------- */

static lab_slot *get_slot(int slot)
{
    return slot >= 0 && slot < SIDX_LAB_SLOTS ? &lab.slot[slot] : NULL;
}

/* The build's hook: the recorder, less the SAH candidates past the JSON's
 * budget (a kd-tree build of the teapot proposes hundreds of thousands;
 * copying them all would cost more than the build). */
typedef struct build_sink { sidx_hook rec; size_t candidates; } build_sink;
static void build_sink_fn(const sidx_event *e, void *user)
{
    build_sink *b = user;
    if (e->type == SIDX_EV_BUILD_CANDIDATE && b->candidates++ >= SIDX_LAB_MAX_CANDIDATES) return;
    b->rec.fn(e, b->rec.user);
}

int sidx_lab_build(int slot, const char *accel, const char *knobs_json)
{
    lab_slot *s = get_slot(slot);
    if (!s) return fail(SIDX_ERR_INVALID_ARG, "slot must be 0 or 1");
    if (!lab.has_scene) return fail(SIDX_ERR_INVALID_ARG, "no scene is open");
    if (!accel || !sidx_accel_is_registered(accel)) {
        snprintf(lab.error, sizeof lab.error, "no structure named '%s'", accel ? accel : "(null)");
        return SIDX_ERR_UNKNOWN_ACCEL;
    }
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    sidx_traversal trav = SIDX_TRAVERSE_DEFAULT;
    char args[256];
    int rc = parse_knobs(knobs_json, &bo, &trav, args, sizeof args);
    slot_clear(s);
    if (rc) return rc;
    sidx_recorder_init(&s->build);
    build_sink sink = {sidx_recorder_hook(&s->build), 0};
    sidx_hook bh = {build_sink_fn, &sink, SIDX_EVMASK_BUILD | SIDX_EVMASK(SIDX_EV_NOTE)};
    bo.hook = &bh;
    sidx_error err;
    const double t0 = now_ms();
    /* the scene's own tree where it has one (kd-slide: the slide's, labelled), as sidx-step builds */
    sidx_status st = sidx_scene_accel_build(lab.builtin ? lab.name : NULL, accel, &lab.mesh, &bo, &s->accel, &err);
    s->build_ms = now_ms() - t0;
    if (st != SIDX_OK) {
        slot_clear(s);
        snprintf(lab.error, sizeof lab.error, "building %s: %s", accel, err.message);
        return st;
    }
    if (s->build.overflow) {
        slot_clear(s);
        return fail(SIDX_ERR_NOMEM, "out of memory recording the build");
    }
    s->traversal = trav;
    s->cand_total = sink.candidates;
    snprintf(s->args, sizeof s->args, "%s", args);
    return ok();
}

/* The slot's build events in the compact array form, the SAH candidates
 * (the first SIDX_LAB_MAX_CANDIDATES) with them or not; the kept ones counted. */
static size_t put_build_events(viz_json *b, const lab_slot *s, int with_candidates)
{
    size_t cand_kept = 0;
    int first = 1;
    viz_json_put(b, "[");
    for (size_t i = 0; i < s->build.count; ++i) {
        const sidx_event *e = &s->build.events[i];
        if (e->type == SIDX_EV_NOTE) continue;
        if (e->type == SIDX_EV_BUILD_CANDIDATE) {
            ++cand_kept;
            if (!with_candidates) continue;
        }
        if (!first) viz_json_put(b, ",");
        first = 0;
        viz_json_build_event(b, e);
    }
    viz_json_put(b, "]");
    return cand_kept;
}

const char *sidx_lab_build_json(int slot)
{
    const lab_slot *s = get_slot(slot);
    if (!s || !s->accel) return null_answer(OUT_BUILD);
    viz_json *b = answer(OUT_BUILD);
    sidx_accel_stats st;
    memset(&st, 0, sizeof st);
    sidx_accel_stats_get(s->accel, &st);
    viz_json_printf(b, "{\"slot\":%d,\"accel\":", slot);
    viz_json_string(b, sidx_accel_name(s->accel));
    viz_json_put(b, ",\"args\":");
    viz_json_string(b, s->args);
    /* sah_cost through viz_json_double: a scene of huge coordinates (+-3e38)
     * overflows the surface areas and gives NaN, which printf writes as
     * "-nan", no JSON at all */
    viz_json_printf(b, ",\"stats\":{\"nodes\":%u,\"leaves\":%u,\"max_depth\":%u,\"sah_cost\":", st.nodes,
                    st.leaves, st.max_depth);
    viz_json_double(b, st.sah_cost);
    viz_json_printf(b, ",\"bytes\":%zu,\"prim_refs\":%llu,\"build_ms\":%.3f}", st.bytes,
                    (unsigned long long)st.prim_refs, s->build_ms);
    viz_json_put(b, ",\"build\":");
    const size_t cand_kept = put_build_events(b, s, 0);
    viz_json_printf(b, ",\"cand_total\":%zu,\"cand_kept\":%zu,\"labels\":{", s->cand_total, cand_kept);
    int first = 1;
    for (uint32_t i = 0; i < st.nodes; ++i) {
        const char *label = sidx_accel_node_label(s->accel, i);
        if (!label) continue;
        viz_json_printf(b, first ? "\"%u\":" : ",\"%u\":", i);
        viz_json_string(b, label);
        first = 0;
    }
    viz_json_put(b, "}}");
    return done(b);
}

const char *sidx_lab_build_events_json(int slot)
{
    const lab_slot *s = get_slot(slot);
    if (!s || !s->accel) return null_answer(OUT_EVENTS);
    viz_json *b = answer(OUT_EVENTS);
    viz_json_printf(b, "{\"slot\":%d,\"build\":", slot);
    const size_t cand_kept = put_build_events(b, s, 1);
    viz_json_printf(b, ",\"cand_total\":%zu,\"cand_kept\":%zu}", s->cand_total, cand_kept);
    return done(b);
}

/* ---- trace -------------------------------------------------------------------------------- */

int sidx_lab_trace(int slot, double ox, double oy, double oz, double dx, double dy, double dz)
{
    lab_slot *s = get_slot(slot);
    if (!s) return fail(SIDX_ERR_INVALID_ARG, "slot must be 0 or 1");
    if (!s->accel) return fail(SIDX_ERR_INVALID_ARG, "nothing is built in this slot");
    const sidx_vec3 org = sidx_v3((float)ox, (float)oy, (float)oz), dir = sidx_v3((float)dx, (float)dy, (float)dz);
    sidx_ray ray;
    if (!isfinite(org.x) || !isfinite(org.y) || !isfinite(org.z) ||
        sidx_ray_init(&ray, org, dir, 0.0f, INFINITY) != SIDX_OK)
        return fail(SIDX_ERR_INVALID_ARG, "the ray wants a finite origin and a finite, non-zero direction");
    sidx_recorder_free(&s->trace);
    sidx_recorder_init(&s->trace);
    s->trace.limit = SIDX_LAB_MAX_EVENTS;
    sidx_hook th = sidx_recorder_hook(&s->trace);
    th.mask = SIDX_EVMASK_TRAVERSAL;
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.traversal = s->traversal;
    q.hook = &th;
    const double t0 = now_ms();
    sidx_accel_intersect(s->accel, &ray, &q, &s->hit);
    s->trace_ms = now_ms() - t0;
    s->org = org;
    s->dir = dir;
    s->has_trace = 1;
    s->truncated = s->trace.overflow;
    return ok();
}

/* The label of the node an event names ("A", "L4": the slide's names of
 * kd-slide's kd-tree), for the events whose line sidx-step labels; else NULL. */
static const char *event_label(const lab_slot *s, const sidx_event *e)
{
    switch (e->type) {
    case SIDX_EV_NODE_ENTER: case SIDX_EV_BOX_TEST: case SIDX_EV_STACK_PUSH: case SIDX_EV_STACK_POP:
    case SIDX_EV_TERMINATE:
        return e->node != UINT32_MAX ? sidx_accel_node_label(s->accel, e->node) : NULL;
    default:
        return NULL;
    }
}

const char *sidx_lab_trace_json(int slot)
{
    const lab_slot *s = get_slot(slot);
    if (!s || !s->accel || !s->has_trace) return null_answer(OUT_TRACE);
    viz_json *b = answer(OUT_TRACE);
    viz_json_printf(b, "{\"slot\":%d,\"accel\":", slot);
    viz_json_string(b, sidx_accel_name(s->accel));
    viz_json_put(b, ",\"ray\":{");
    put_ray(b, s->org, s->dir);
    viz_json_put(b, "},\"hit\":");
    if (s->hit.prim != SIDX_NO_HIT) {
        viz_json_printf(b, "{\"prim\":%u,\"t\":", s->hit.prim);
        put_exact(b, s->hit.t);
        viz_json_put(b, "}");
    } else {
        viz_json_put(b, "null");
    }
    uint64_t n[SIDX_EV_COUNT] = {0};
    for (size_t i = 0; i < s->trace.count; ++i) n[s->trace.events[i].type]++;
    viz_json_printf(b,
                    ",\"counts\":{\"nodes\":%llu,\"boxes\":%llu,\"triangles\":%llu,\"mailbox\":%llu,\"events\":%zu},"
                    "\"truncated\":%s,\"ms\":%.3f,\"events\":[",
                    (unsigned long long)n[SIDX_EV_NODE_ENTER], (unsigned long long)n[SIDX_EV_BOX_TEST],
                    (unsigned long long)n[SIDX_EV_PRIM_TEST], (unsigned long long)n[SIDX_EV_MAILBOX_HIT],
                    s->trace.count, s->truncated ? "true" : "false", s->trace_ms);
    for (size_t i = 0; i < s->trace.count; ++i) {
        if (i) viz_json_put(b, ",\n");
        const sidx_event *e = &s->trace.events[i];
        if (viz_json_trav_event_label(b, e, event_label(s, e)) != 0) viz_json_put(b, "null");
    }
    viz_json_put(b, "]}");
    return done(b);
}

/* An event's JSON with the structure's name left out (two structures' walks
 * are compared step by step). */
static int event_key(const sidx_event *e, char *buf, size_t size)
{
    sidx_event c = *e;
    c.structure = NULL;
    const int n = sidx_event_to_json(&c, buf, size);
    return n >= 0 && (size_t)n < size ? 0 : -1;
}

const char *sidx_lab_diverge_json(void)
{
    const lab_slot *a = &lab.slot[0], *c = &lab.slot[1];
    if (!a->accel || !c->accel || !a->has_trace || !c->has_trace) return null_answer(OUT_DIVERGE);
    viz_json *b = answer(OUT_DIVERGE);
    const size_t na = a->trace.count, nc = c->trace.count, n = na < nc ? na : nc;
    size_t i = 0;
    for (; i < n; ++i) {
        char ka[1024], kc[1024];
        if (event_key(&a->trace.events[i], ka, sizeof ka) || event_key(&c->trace.events[i], kc, sizeof kc) ||
            strcmp(ka, kc))
            break;
    }
    if (i == n && na == nc) {
        viz_json_printf(b, "{\"step\":0,\"same\":%zu,\"a\":null,\"b\":null}", n);
        return done(b);
    }
    viz_json_printf(b, "{\"step\":%zu,\"same\":%zu,\"a\":", i + 1, i);
    if (i < na) viz_json_trav_event_label(b, &a->trace.events[i], event_label(a, &a->trace.events[i]));
    else viz_json_put(b, "null");
    viz_json_put(b, ",\"b\":");
    if (i < nc) viz_json_trav_event_label(b, &c->trace.events[i], event_label(c, &c->trace.events[i]));
    else viz_json_put(b, "null");
    viz_json_put(b, "}");
    return done(b);
}

/* ---- heat map, camera, speed -------------------------------------------------------------- */

static struct { int valid, w, h, what; uint32_t max; uint64_t total; double ms; } heat_meta;

int sidx_lab_heatmap(int slot, double yaw, double pitch, double zoom, int w, int h, int what)
{
    const lab_slot *s = get_slot(slot);
    if (!s) return fail(SIDX_ERR_INVALID_ARG, "slot must be 0 or 1");
    if (!s->accel) return fail(SIDX_ERR_INVALID_ARG, "nothing is built in this slot");
    if (w < 1 || h < 1 || (uint64_t)w * (uint64_t)h > SIDX_LAB_MAX_PIXELS)
        return fail(SIDX_ERR_INVALID_ARG, "the heat map wants 1 to 2048x2048 pixels");
    if (what != 0 && what != 1) return fail(SIDX_ERR_INVALID_ARG, "what: 0 steps, 1 triangle tests");
    const size_t npx = (size_t)w * (size_t)h;
    if (npx > lab.heat_cap) {
        uint32_t *p = realloc(lab.heat, npx * sizeof *p);
        if (!p) return fail(SIDX_ERR_NOMEM, "out of memory for the heat map");
        lab.heat = p;
        lab.heat_cap = npx;
    }
    const double t0 = now_ms();
    const viz_camera cam = viz_camera_make(sidx_mesh_bounds(&lab.mesh), (float)yaw, (float)pitch, (float)zoom, w, h);
    const uint32_t mask = what == 1 ? SIDX_EVMASK(SIDX_EV_PRIM_TEST)
                                    : SIDX_EVMASK(SIDX_EV_NODE_ENTER) | SIDX_EVMASK(SIDX_EV_PRIM_TEST);
    heat_meta.max = viz_heat_counts(s->accel, &cam, w, h, 1, mask, lab.heat);
    heat_meta.ms = now_ms() - t0;
    heat_meta.total = 0;
    for (size_t i = 0; i < npx; ++i) heat_meta.total += lab.heat[i];
    heat_meta.valid = 1;
    heat_meta.w = w;
    heat_meta.h = h;
    heat_meta.what = what;
    return ok();
}

const uint32_t *sidx_lab_heatmap_data(void) { return heat_meta.valid ? lab.heat : NULL; }

const char *sidx_lab_heatmap_json(void)
{
    if (!heat_meta.valid) return null_answer(OUT_HEAT);
    viz_json *b = answer(OUT_HEAT);
    viz_json_printf(b, "{\"w\":%d,\"h\":%d,\"what\":%d,\"max\":%u,\"total\":%llu,\"ms\":%.3f}", heat_meta.w,
                    heat_meta.h, heat_meta.what, heat_meta.max, (unsigned long long)heat_meta.total, heat_meta.ms);
    return done(b);
}

const char *sidx_lab_camera_ray(double yaw, double pitch, double zoom, int w, int h, double px, double py)
{
    if (!lab.has_scene || w < 1 || h < 1) return null_answer(OUT_MISC);
    const viz_camera cam = viz_camera_make(sidx_mesh_bounds(&lab.mesh), (float)yaw, (float)pitch, (float)zoom, w, h);
    sidx_vec3 org, dir;
    viz_camera_ray(&cam, (float)px, (float)py, &org, &dir);
    viz_json *b = answer(OUT_MISC);
    viz_json_put(b, "{");
    put_ray(b, org, dir);
    viz_json_put(b, "}");
    return done(b);
}

const char *sidx_lab_bench(int slot, double yaw, double pitch, double zoom, int w, int h, int repeat)
{
    const lab_slot *s = get_slot(slot);
    if (!s || !s->accel || w < 1 || h < 1 || repeat < 1) {
        fail(SIDX_ERR_INVALID_ARG, "bench wants a built slot, w, h and repeat >= 1");
        return null_answer(OUT_MISC);
    }
    const viz_camera cam = viz_camera_make(sidx_mesh_bounds(&lab.mesh), (float)yaw, (float)pitch, (float)zoom, w, h);
    sidx_ray *rays = malloc((size_t)w * (size_t)h * sizeof *rays);
    if (!rays) {
        fail(SIDX_ERR_NOMEM, "out of memory for the rays");
        return null_answer(OUT_MISC);
    }
    size_t n = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            sidx_vec3 org, dir;
            viz_camera_ray(&cam, (float)x + 0.5f, (float)y + 0.5f, &org, &dir);
            if (sidx_ray_init(&rays[n], org, dir, 0.0f, INFINITY) == SIDX_OK) ++n;
        }
    uint64_t hits = 0, prim_sum = 0;
    struct timespec c0, c1;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
    const double t0 = now_ms();
    for (int k = 0; k < repeat; ++k)
        for (size_t i = 0; i < n; ++i) {
            sidx_hit hit;
            sidx_accel_intersect(s->accel, &rays[i], NULL, &hit);
            if (k == 0 && hit.prim != SIDX_NO_HIT) {
                ++hits;
                prim_sum += hit.prim;
            }
        }
    const double ms = now_ms() - t0;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
    const double cpu_ms = (double)(c1.tv_sec - c0.tv_sec) * 1e3 + (double)(c1.tv_nsec - c0.tv_nsec) * 1e-6;
    free(rays);
    viz_json *b = answer(OUT_MISC);
    const double total = (double)n * (double)repeat;
    viz_json_printf(b,
                    "{\"rays\":%.0f,\"hits\":%llu,\"prim_sum\":%llu,\"ms\":%.3f,\"cpu_ms\":%.3f,\"mrays_per_s\":%.3f}",
                    total, (unsigned long long)hits, (unsigned long long)prim_sum, ms, cpu_ms,
                    ms > 0.0 ? total / ms / 1e3 : 0.0);
    ok();
    return done(b);
}
