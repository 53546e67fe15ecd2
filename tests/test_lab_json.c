/* test_lab_json.c — the JSON the lab's pages read is JSON.
 *
 * The web lab parses every answer of viz/lab.c with JSON.parse, and
 * sidx-view --html's page holds the text of the same writer
 * (viz/json_write.c).  printf writes a NaN as "nan" or "-nan" and an
 * infinity as "inf": text no JSON reader takes (the page stopped with
 * "Uncaught SyntaxError" on a BVH of an OBJ with coordinates +-3e38, whose
 * SAH cost overflows to NaN).  Every float writer of json_write.c is fed
 * NaN, both infinities, -0, the largest and the smallest floats, every
 * event type with every float field non-finite; then the lab opens that
 * OBJ and every answer of every registered structure (build, build events,
 * traces, the walks' parting step, heat map, camera rays at bad camera
 * values, the timing run) goes through a strict RFC 8259 grammar check. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "sidx/sidx.h"
#include "../viz/json_write.h"
#include "../viz/lab.h"

/* ---- a strict JSON grammar check (RFC 8259), no values kept ---------------------------- */

typedef struct jp { const char *p; int depth; } jp;

static void ws(jp *j)
{
    while (*j->p == ' ' || *j->p == '\t' || *j->p == '\n' || *j->p == '\r') ++j->p;
}

static int value(jp *j);

static int number(jp *j)
{
    const char *p = j->p;
    if (*p == '-') ++p;
    if (*p == '0') ++p;
    else if (*p >= '1' && *p <= '9') while (*p >= '0' && *p <= '9') ++p;
    else return 0;
    if (*p == '.') {
        ++p;
        if (!(*p >= '0' && *p <= '9')) return 0;
        while (*p >= '0' && *p <= '9') ++p;
    }
    if (*p == 'e' || *p == 'E') {
        ++p;
        if (*p == '+' || *p == '-') ++p;
        if (!(*p >= '0' && *p <= '9')) return 0;
        while (*p >= '0' && *p <= '9') ++p;
    }
    j->p = p;
    return 1;
}

static int string(jp *j)
{
    if (*j->p != '"') return 0;
    for (const char *p = j->p + 1;; ++p) {
        const unsigned char c = (unsigned char)*p;
        if (c == '"') { j->p = p + 1; return 1; }
        if (c < 0x20) return 0; /* the end of the text, or a raw control character */
        if (c == '\\') {
            ++p;
            if (*p == 'u') {
                for (int k = 1; k <= 4; ++k)
                    if (!strchr("0123456789abcdefABCDEF", p[k]) || !p[k]) return 0;
                p += 4;
            } else if (!*p || !strchr("\"\\/bfnrt", *p)) {
                return 0;
            }
        }
    }
}

static int word(jp *j, const char *w)
{
    const size_t n = strlen(w);
    if (strncmp(j->p, w, n)) return 0;
    j->p += n;
    return 1;
}

static int value(jp *j)
{
    ws(j);
    if (++j->depth > 64) return 0;
    int ok = 0;
    if (*j->p == '{') {
        ++j->p;
        ws(j);
        if (*j->p == '}') { ++j->p; ok = 1; }
        else for (;;) {
            ws(j);
            if (!string(j)) break;
            ws(j);
            if (*j->p++ != ':' || !value(j)) break;
            ws(j);
            if (*j->p == ',') { ++j->p; continue; }
            if (*j->p == '}') { ++j->p; ok = 1; }
            break;
        }
    } else if (*j->p == '[') {
        ++j->p;
        ws(j);
        if (*j->p == ']') { ++j->p; ok = 1; }
        else for (;;) {
            if (!value(j)) break;
            ws(j);
            if (*j->p == ',') { ++j->p; continue; }
            if (*j->p == ']') { ++j->p; ok = 1; }
            break;
        }
    } else if (*j->p == '"') {
        ok = string(j);
    } else if (*j->p == '-' || (*j->p >= '0' && *j->p <= '9')) {
        ok = number(j);
    } else {
        ok = word(j, "true") || word(j, "false") || word(j, "null");
    }
    --j->depth;
    return ok;
}

/* 1 if text is one JSON value and nothing else. */
static int is_json(const char *text)
{
    jp j = {text, 0};
    if (!value(&j)) return 0;
    ws(&j);
    return *j.p == '\0';
}

static size_t checked;

static void want_json(const char *what, const char *text)
{
    assert_non_null(text);
    if (!is_json(text)) fail_msg("%s is not JSON: %.400s", what, text);
    ++checked;
}

/* The check itself can fail: what printf writes for the values the writers must avoid. */
static void grammar_refuses_printf_nonfinite(void **state)
{
    (void)state;
    char buf[64];
    const double bad[] = {NAN, -NAN, INFINITY, -INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(buf, sizeof buf, "{\"sah_cost\":%.6g}", bad[i]);
        assert_false(is_json(buf));
        snprintf(buf, sizeof buf, "[%.6g]", bad[i]);
        assert_false(is_json(buf));
    }
    assert_true(is_json("{\"a\":[1,-0,2.5e-3,1e999,-1e999,null,\"x\\u003c\"],\"b\":true}"));
    assert_false(is_json("[1,]"));
    assert_false(is_json("[01]"));
    assert_false(is_json("{\"a\":1} x"));
}

/* ---- every float writer of json_write.c --------------------------------------------- */

static const float specials[] = {NAN, -NAN, INFINITY, -INFINITY, -0.0f, 0.0f, FLT_MAX, -FLT_MAX, FLT_MIN,
                                 1e-45f, 3e38f, -3e38f, 1.0f};
#define NSPECIAL (sizeof specials / sizeof specials[0])

static void writers_put_json_for_every_float(void **state)
{
    (void)state;
    viz_json b = {NULL, 0, 0, 0};
    char what[96];
    for (size_t i = 0; i < NSPECIAL; ++i) {
        const float f = specials[i];
        b.n = 0;
        viz_json_put(&b, "[");
        viz_json_float(&b, f);
        viz_json_put(&b, ",");
        viz_json_double(&b, (double)f);
        viz_json_put(&b, ",");
        viz_json_double(&b, (double)f * 1e300); /* doubles past the float range too */
        viz_json_put(&b, ",");
        viz_json_xyz(&b, sidx_v3(f, 1.0f, f));
        viz_json_box(&b, (sidx_aabb){sidx_v3(f, f, f), sidx_v3(f, -f, 2.0f)});
        viz_json_put(&b, "]");
        assert_false(b.failed);
        snprintf(what, sizeof what, "the writers of %g", (double)f);
        want_json(what, b.s);
    }
    /* every event type, every float field set to each special value, both ways the pages write an event */
    for (int type = 0; type < SIDX_EV_COUNT; ++type)
        for (size_t i = 0; i < NSPECIAL; ++i) {
            const float f = specials[i];
            const uint32_t prims[2] = {0, 1};
            sidx_event e;
            memset(&e, 0, sizeof e);
            e.type = (sidx_event_type)type;
            e.structure = "bvh";
            e.node = 3;
            e.parent = 1;
            e.depth = 2;
            e.count = 2;
            e.aux = 1;
            e.prims = prims;
            e.t_near = f;
            e.t_far = -f;
            e.t = f;
            e.pos = f;
            e.cost = f;
            e.bounds = (sidx_aabb){sidx_v3(f, f, -f), sidx_v3(-f, f, f)};
            for (int axis = -1; axis <= 0; ++axis) {
                e.axis = axis;
                b.n = 0;
                viz_json_put(&b, "[");
                viz_json_build_event(&b, &e);
                viz_json_put(&b, ",");
                if (viz_json_trav_event_label(&b, &e, "L1") != 0) viz_json_put(&b, "null");
                viz_json_put(&b, "]");
                assert_false(b.failed);
                snprintf(what, sizeof what, "event type %d axis %d with %g", type, axis, (double)f);
                want_json(what, b.s);
            }
        }
    free(b.s);
}

/* ---- the lab's answers on a scene whose SAH cost overflows --------------------------- */

/* Two triangles spanning +-3e38: a box's surface area overflows to inf, and the SAH
 * cost of the BVH builders, inf/inf, is NaN. */
static const char huge_obj[] = "v -3e38 -3e38 -3e38\nv 3e38 -3e38 3e38\nv 3e38 3e38 -3e38\n"
                               "v -3e38 3e38 3e38\nv 0 0 3e38\nv 3e38 0 0\nf 1 2 3\nf 4 5 6\n";

static void lab_answers_are_json(void **state)
{
    (void)state;
    sidx_lab_reset();
    want_json("scenes", sidx_lab_scenes());
    assert_int_equal(sidx_lab_open_obj(huge_obj, (int)strlen(huge_obj), "huge.obj"), 0);
    want_json("scene", sidx_lab_scene_json());
    want_json("structures", sidx_lab_structures());
    int nonfinite_costs = 0;
    const char *knobs[] = {NULL, "{\"leaf_size\":1,\"c_trav\":1e30}"};
    const double rays[][6] = {{0, 0, -1e39, 0, 0, 1},  {-3e38, -3e38, -3e38, 1, 1, 1}, {1, 2, 3, 1e-30f, 0, 0},
                              {0, 0, 0, 1, 0, 0},      {3e38, 3e38, 3e38, -1, -1, -1}, {0, 0, 0, 0, 0, 0},
                              {NAN, 0, 0, 1, 0, 0},     {0, 0, 0, INFINITY, 1, 0}};
    for (size_t a = 0; a < sidx_accel_registered_count(); ++a) {
        const char *name = sidx_accel_registered_name(a);
        for (size_t k = 0; k < sizeof knobs / sizeof knobs[0]; ++k) {
            char what[128];
            snprintf(what, sizeof what, "%s%s: build", name, k ? " with knobs" : "");
            const int rc = sidx_lab_build((int)(a % 2), name, knobs[k]);
            const char *bj = sidx_lab_build_json((int)(a % 2));
            want_json(what, bj);
            if (rc != 0) continue;
            if (strstr(bj, "\"sah_cost\":null") || strstr(bj, "\"sah_cost\":1e999") ||
                strstr(bj, "\"sah_cost\":-1e999"))
                ++nonfinite_costs;
            want_json(what, sidx_lab_build_events_json((int)(a % 2)));
            for (size_t r = 0; r < sizeof rays / sizeof rays[0]; ++r) {
                const double *q = rays[r];
                sidx_lab_trace((int)(a % 2), q[0], q[1], q[2], q[3], q[4], q[5]);
                snprintf(what, sizeof what, "%s: trace %zu", name, r);
                want_json(what, sidx_lab_trace_json((int)(a % 2)));
                want_json("diverge", sidx_lab_diverge_json());
            }
            const double cams[][3] = {{0.6, 0.35, 1}, {0, 0, 0}, {NAN, 1, 1}, {0, INFINITY, 1e30}, {1e30, -2, -1}};
            for (size_t c = 0; c < sizeof cams / sizeof cams[0]; ++c) {
                sidx_lab_heatmap((int)(a % 2), cams[c][0], cams[c][1], cams[c][2], 8, 8, (int)(c % 2));
                want_json("heat map", sidx_lab_heatmap_json());
                want_json("camera ray", sidx_lab_camera_ray(cams[c][0], cams[c][1], cams[c][2], 8, 8, 4.5, 4.5));
                want_json("camera ray at a bad pixel", sidx_lab_camera_ray(cams[c][0], cams[c][1], cams[c][2], 8, 8,
                                                                           NAN, INFINITY));
            }
            const char *bench = sidx_lab_bench((int)(a % 2), 0.6, 0.35, 1, 4, 4, 1);
            want_json("bench", bench);
        }
    }
    /* the scene really makes a non-finite SAH cost: this suite saw what broke the page */
    assert_true(nonfinite_costs >= 1);
    print_message("lab answers: %zu JSON texts checked, %d with a non-finite SAH cost\n", checked, nonfinite_costs);
    sidx_lab_reset();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(grammar_refuses_printf_nonfinite),
        cmocka_unit_test(writers_put_json_for_every_float),
        cmocka_unit_test(lab_answers_are_json),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
