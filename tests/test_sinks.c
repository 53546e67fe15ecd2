/* test_sinks.c — the ready-made hooks of sinks.h, fed hand-made events.
 *
 * Each test builds events with sidx_event_blank plus the fields the type
 * carries (as an emitter would), pushes them through a sink and checks the
 * result exactly: printer text byte for byte, JSON through a small
 * validating parser, recorder / counter contents, tee and hook masks. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "sidx/sidx.h"

/* ---- event builders ------------------------------------------------------ */

static sidx_aabb box(float x0, float y0, float z0, float x1, float y1, float z1)
{
    sidx_aabb b = {{x0, y0, z0}, {x1, y1, z1}};
    return b;
}

static sidx_event ev_ray_begin(uint32_t ray, float t0, float t1)
{
    sidx_event e = sidx_event_blank(SIDX_EV_RAY_BEGIN);
    e.structure = "bvh";
    e.ray_id = ray;
    e.t_near = t0;
    e.t_far = t1;
    return e;
}

static sidx_event ev_node_enter(uint32_t node, uint32_t depth, float t0, float t1)
{
    sidx_event e = sidx_event_blank(SIDX_EV_NODE_ENTER);
    e.structure = "bvh";
    e.node = node;
    e.depth = depth;
    e.t_near = t0;
    e.t_far = t1;
    return e;
}

static sidx_event ev_box(uint32_t node, uint32_t depth, int hit, float t0, float t1)
{
    sidx_event e = sidx_event_blank(SIDX_EV_BOX_TEST);
    e.structure = "bvh";
    e.node = node;
    e.depth = depth;
    e.result = hit;
    e.bounds = box(0, 0, 0, 1, 2, 3);
    if (hit) {
        e.t_near = t0;
        e.t_far = t1;
    }
    return e;
}

static sidx_event ev_prim(uint32_t prim, int hit, float t)
{
    sidx_event e = sidx_event_blank(SIDX_EV_PRIM_TEST);
    e.structure = "bvh";
    e.prim = prim;
    e.result = hit;
    e.t = hit ? t : INFINITY;
    return e;
}

/* ---- output capture ------------------------------------------------------ */

/* Whole contents of f (rewound), NUL-terminated; caller frees. */
static char *slurp(FILE *f)
{
    assert_int_equal(fflush(f), 0);
    long n = ftell(f);
    assert_true(n >= 0);
    rewind(f);
    char *s = malloc((size_t)n + 1);
    assert_non_null(s);
    size_t got = fread(s, 1, (size_t)n, f);
    assert_int_equal(got, (size_t)n);
    s[n] = '\0';
    return s;
}

static void expect_format(const sidx_event *e, const char *want)
{
    char buf[512];
    int n = sidx_event_format(e, buf, sizeof buf);
    assert_string_equal(buf, want);
    assert_int_equal(n, (int)strlen(want));
}

/* ---- a tiny JSON checker --------------------------------------------------
 * Validates one JSON value (objects, arrays, strings with escapes, numbers,
 * true/false/null) and records the keys of the top-level object. */

typedef struct json_check {
    const char *p;
    int depth;
    char keys[32][24];
    int nkeys;
} json_check;

static void js_ws(json_check *j)
{
    while (*j->p == ' ' || *j->p == '\t' || *j->p == '\n' || *j->p == '\r') j->p++;
}

/* Parses a string; copies its raw contents into out (if given). */
static int js_string(json_check *j, char *out, size_t outsz)
{
    size_t n = 0;
    if (*j->p != '"') return 0;
    j->p++;
    while (*j->p != '"') {
        unsigned char c = (unsigned char)*j->p;
        if (c == '\0' || c < 0x20) return 0; /* unterminated or raw control char */
        if (c == '\\') {
            j->p++;
            if (*j->p == 'u') {
                for (int i = 1; i <= 4; ++i)
                    if (!strchr("0123456789abcdefABCDEF", j->p[i]) || j->p[i] == '\0') return 0;
                j->p += 4;
            } else if (!strchr("\"\\/bfnrt", *j->p) || *j->p == '\0') {
                return 0;
            }
        }
        if (out && n + 1 < outsz) out[n++] = *j->p;
        j->p++;
    }
    j->p++;
    if (out) out[n] = '\0';
    return 1;
}

static int js_number(json_check *j)
{
    const char *s = j->p;
    if (*s == '-') s++;
    if (*s == '0') s++;
    else if (*s >= '1' && *s <= '9') while (*s >= '0' && *s <= '9') s++;
    else return 0;
    if (*s == '.') {
        s++;
        if (!(*s >= '0' && *s <= '9')) return 0;
        while (*s >= '0' && *s <= '9') s++;
    }
    if (*s == 'e' || *s == 'E') {
        s++;
        if (*s == '+' || *s == '-') s++;
        if (!(*s >= '0' && *s <= '9')) return 0;
        while (*s >= '0' && *s <= '9') s++;
    }
    j->p = s;
    return 1;
}

static int js_value(json_check *j);

static int js_object(json_check *j)
{
    const int top = j->depth == 0;
    j->depth++;
    j->p++; /* '{' */
    js_ws(j);
    if (*j->p == '}') { j->p++; j->depth--; return 1; }
    for (;;) {
        char key[24];
        js_ws(j);
        if (!js_string(j, key, sizeof key)) return 0;
        if (top) {
            if (j->nkeys >= 32) return 0;
            for (int i = 0; i < j->nkeys; ++i)
                if (strcmp(j->keys[i], key) == 0) return 0; /* duplicate key */
            strcpy(j->keys[j->nkeys++], key);
        }
        js_ws(j);
        if (*j->p != ':') return 0;
        j->p++;
        if (!js_value(j)) return 0;
        js_ws(j);
        if (*j->p == ',') { j->p++; continue; }
        if (*j->p == '}') { j->p++; j->depth--; return 1; }
        return 0;
    }
}

static int js_array(json_check *j)
{
    j->depth++;
    j->p++; /* '[' */
    js_ws(j);
    if (*j->p == ']') { j->p++; j->depth--; return 1; }
    for (;;) {
        if (!js_value(j)) return 0;
        js_ws(j);
        if (*j->p == ',') { j->p++; continue; }
        if (*j->p == ']') { j->p++; j->depth--; return 1; }
        return 0;
    }
}

static int js_value(json_check *j)
{
    js_ws(j);
    switch (*j->p) {
    case '{': return js_object(j);
    case '[': return js_array(j);
    case '"': return js_string(j, NULL, 0);
    case 't': if (strncmp(j->p, "true", 4) == 0) { j->p += 4; return 1; } return 0;
    case 'f': if (strncmp(j->p, "false", 5) == 0) { j->p += 5; return 1; } return 0;
    case 'n': if (strncmp(j->p, "null", 4) == 0) { j->p += 4; return 1; } return 0;
    default: return js_number(j);
    }
}

/* Parses a whole line that must be exactly one JSON object. */
static json_check json_parse_line(const char *line)
{
    json_check j;
    memset(&j, 0, sizeof j);
    j.p = line;
    js_ws(&j);
    assert_int_equal(*j.p, '{');
    assert_true(js_value(&j));
    assert_int_equal(j.depth, 0);
    js_ws(&j);
    assert_int_equal(*j.p, '\0');
    return j;
}

static int json_has(const json_check *j, const char *key)
{
    for (int i = 0; i < j->nkeys; ++i)
        if (strcmp(j->keys[i], key) == 0) return 1;
    return 0;
}

/* JSON of ev must be valid and have exactly the keys in `want` (NULL-ended). */
static void expect_json_keys(const sidx_event *ev, const char *const *want)
{
    char buf[1024];
    int n = sidx_event_to_json(ev, buf, sizeof buf);
    assert_true(n > 0 && (size_t)n < sizeof buf);
    assert_int_equal((size_t)n, strlen(buf));
    json_check j = json_parse_line(buf);
    int nwant = 0;
    for (; want[nwant]; ++nwant) {
        if (!json_has(&j, want[nwant])) fail_msg("key \"%s\" missing in %s", want[nwant], buf);
    }
    if (j.nkeys != nwant) fail_msg("expected %d keys, got %d in %s", nwant, j.nkeys, buf);
}

/* ---- printer ------------------------------------------------------------- */

static void test_format_traversal(void **state)
{
    (void)state;
    sidx_event e = ev_ray_begin(0, 0.0f, INFINITY);
    expect_format(&e, "ray 0 begin (bvh)  t=[0, inf]");

    e = ev_node_enter(3, 2, 0.5f, 1.25f);
    expect_format(&e, "      node 3 enter  depth 2  t=[0.5, 1.25]");

    e = ev_box(5, 1, 1, 0.5f, 1.0f);
    expect_format(&e, "    box node 5 hit  t=[0.5, 1]");
    e = ev_box(6, 1, 0, 0, 0);
    expect_format(&e, "    box node 6 miss");

    e = sidx_event_blank(SIDX_EV_STACK_PUSH);
    e.node = 7;
    e.depth = 2;
    e.t_near = 0.5f;
    e.t_far = 2.0f;
    expect_format(&e, "  push node 7  t=[0.5, 2]  (stack 1 -> 2)");
    e.type = SIDX_EV_STACK_POP;
    expect_format(&e, "  pop node 7  t=[0.5, 2]  (stack 2 -> 1)");
    e.result = 0; /* the BVH stack walk drops it: it starts beyond the best hit */
    expect_format(&e, "  pop node 7  t=[0.5, 2]  (stack 2 -> 1)  dropped: t_near beyond the best hit");
    e.result = SIDX_STACK_ENTERED;
    expect_format(&e, "  pop node 7  t=[0.5, 2]  (stack 2 -> 1)");
    /* a kd-tree ray inside a split plane: both children are near, said at the push and at the pop */
    e.result = SIDX_STACK_IN_PLANE;
    expect_format(&e, "  pop node 7  t=[0.5, 2]  (stack 2 -> 1)  the ray lies in the split plane: both children are "
                      "near, so a hit in the other does not end the walk");
    e.type = SIDX_EV_STACK_PUSH;
    expect_format(&e, "  push node 7  t=[0.5, 2]  (stack 1 -> 2)  the ray lies in the split plane: both children are "
                      "near");

    e = ev_prim(42, 1, 0.734f);
    expect_format(&e, "    prim 42 test: hit t=0.734");
    e = ev_prim(43, 0, 0);
    expect_format(&e, "    prim 43 test: miss");
    e.depth = 3; /* an emitter that knows the leaf's depth nests the test under it */
    expect_format(&e, "          prim 43 test: miss");

    e = sidx_event_blank(SIDX_EV_HIT_UPDATE);
    e.prim = 42;
    e.t = 0.734f;
    expect_format(&e, "    closest hit -> prim 42 t=0.734");

    e = sidx_event_blank(SIDX_EV_MAILBOX_HIT);
    e.prim = 42;
    expect_format(&e, "    mailbox: prim 42 already tested, skipped");

    e = sidx_event_blank(SIDX_EV_TERMINATE);
    e.reason = SIDX_TERM_STACK_EMPTY;
    e.count = 12;
    e.t = 0.734f;
    expect_format(&e, "terminate: stack_empty  visited 12  best t=0.734");

    e = sidx_event_blank(SIDX_EV_RAY_END);
    e.ray_id = 4;
    e.prim = 42;
    e.t = 0.734f;
    expect_format(&e, "ray 4 end: hit prim 42 t=0.734");
    e.prim = SIDX_NO_HIT;
    e.t = INFINITY;
    expect_format(&e, "ray 4 end: miss");
    e.result = 1; /* occlusion queries report a hit without a primitive */
    expect_format(&e, "ray 4 end: occluded");
}

static void test_format_grid_cell(void **state)
{
    (void)state;
    sidx_event e = ev_node_enter(17, 0, 1.0f, 1.5f);
    e.structure = "grid";
    e.cell[0] = 3;
    e.cell[1] = 1;
    e.cell[2] = 0;
    expect_format(&e, "  cell (3,1,0) enter  t=[1, 1.5]");

    /* The blank event has no cell: cell[0] is -1. */
    sidx_event b = sidx_event_blank(SIDX_EV_NODE_ENTER);
    assert_int_equal(b.cell[0], -1);
}

static void test_format_build(void **state)
{
    (void)state;
    sidx_event e = sidx_event_blank(SIDX_EV_BUILD_BEGIN);
    e.structure = "bvh";
    e.count = 12;
    e.bounds = box(-1, 0, 0, 1, 1, 2.5f);
    expect_format(&e, "build begin (bvh): 12 prims  box [(-1, 0, 0), (1, 1, 2.5)]");

    e = sidx_event_blank(SIDX_EV_BUILD_NODE);
    e.node = 4;
    e.parent = 1;
    e.depth = 2;
    e.count = 37;
    e.bounds = box(0, 0, 0, 1, 1, 1);
    expect_format(&e, "      build node 4  depth 2  prims 37  (parent 1)");
    e.node = 0;
    e.parent = UINT32_MAX;
    e.depth = 0;
    expect_format(&e, "  build node 0  depth 0  prims 37  (root)");

    e = sidx_event_blank(SIDX_EV_BUILD_CANDIDATE);
    e.node = 4;
    e.depth = 2;
    e.axis = 0;
    e.pos = 0.25f;
    e.cost = 12.5f;
    e.count = 10;
    e.aux = 27;
    expect_format(&e, "        candidate axis x at 0.25  cost 12.5  (L 10 | R 27)");
    e.type = SIDX_EV_BUILD_SPLIT;
    e.axis = 2;
    expect_format(&e, "        split node 4 axis z at 0.25  cost 12.5  (L 10 | R 27)");
    /* BSP: no axis, the plane normal travels in bounds.min */
    e.axis = -1;
    e.bounds.min = sidx_v3(0, 1, 0);
    e.depth = 0;
    expect_format(&e, "    split node 4 plane n=(0, 1, 0) d=0.25  cost 12.5  (L 10 | R 27)");

    e = sidx_event_blank(SIDX_EV_BUILD_LEAF);
    e.node = 9;
    e.depth = 1;
    e.count = 3;
    e.reason = SIDX_LEAF_FEW_PRIMS;
    expect_format(&e, "      leaf node 9  prims 3  (few_prims)"); /* cost left blank (NaN): not shown */
    e.cost = 3.0f;
    e.reason = SIDX_LEAF_NO_GAIN;
    expect_format(&e, "      leaf node 9  prims 3  cost 3  (no_gain)");
    /* with its primitive list: the first few ids, then how many more */
    const uint32_t ids[7] = {4, 17, 52, 60, 61, 90, 3};
    e.prims = ids;
    expect_format(&e, "      leaf node 9  prims 3: 4 17 52  cost 3  (no_gain)");
    e.count = 4;
    expect_format(&e, "      leaf node 9  prims 4: 4 17 52 60  cost 3  (no_gain)");
    e.count = 7;
    expect_format(&e, "      leaf node 9  prims 7: 4 17 52 60 ... +3 more  cost 3  (no_gain)");
    e.count = 0; /* an empty leaf lists nothing, whatever the pointer */
    expect_format(&e, "      leaf node 9  prims 0  cost 3  (no_gain)");

    e = sidx_event_blank(SIDX_EV_BUILD_END);
    e.structure = "bvh";
    e.node = 17;
    e.count = 40;
    e.depth = 5;
    expect_format(&e, "build end (bvh): 17 nodes  40 prim refs  max depth 5");

    e = sidx_event_blank(SIDX_EV_NOTE);
    e.text = "auto: \"bvh\" because\nthe scene is small";
    expect_format(&e, "  note: auto: \"bvh\" because the scene is small");
}

static void test_format_snprintf_semantics(void **state)
{
    (void)state;
    sidx_event e = ev_ray_begin(0, 0.0f, INFINITY);
    const char *want = "ray 0 begin (bvh)  t=[0, inf]";
    const int len = (int)strlen(want);

    assert_int_equal(sidx_event_format(&e, NULL, 0), len); /* count only */

    char small[8];
    memset(small, 'X', sizeof small);
    assert_int_equal(sidx_event_format(&e, small, sizeof small), len);
    assert_string_equal(small, "ray 0 b"); /* truncated, NUL-terminated */

    char one[1] = {'X'};
    assert_int_equal(sidx_event_format(&e, one, 1), len);
    assert_int_equal(one[0], '\0');

    assert_int_equal(sidx_event_format(NULL, small, sizeof small), -1);

    /* same for JSON */
    char full[256];
    int n = sidx_event_to_json(&e, full, sizeof full);
    assert_int_equal(sidx_event_to_json(&e, NULL, 0), n);
    assert_int_equal(sidx_event_to_json(&e, small, sizeof small), n);
    assert_memory_equal(small, full, sizeof small - 1);
    assert_int_equal(small[sizeof small - 1], '\0');
}

static void test_printer_sink(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    sidx_printer p;
    sidx_printer_init(&p, f);
    assert_int_equal(p.mask, 0);
    assert_int_equal(p.show_bounds, 0);
    sidx_hook h = sidx_printer_hook(&p);

    sidx_event seq[5];
    seq[0] = ev_ray_begin(0, 0.0f, INFINITY);
    seq[1] = ev_node_enter(0, 0, 0.0f, 4.0f);
    seq[2] = ev_box(1, 1, 1, 1.0f, 2.0f);
    seq[3] = ev_prim(2, 0, 0);
    seq[4] = sidx_event_blank(SIDX_EV_RAY_END);
    for (int i = 0; i < 5; ++i) sidx_hook_emit(&h, &seq[i]);
    assert_int_equal(p.lines, 5);

    /* only boxes, and with their bounds */
    p.mask = SIDX_EVMASK(SIDX_EV_BOX_TEST);
    p.show_bounds = 1;
    h = sidx_printer_hook(&p);
    assert_int_equal(h.mask, SIDX_EVMASK(SIDX_EV_BOX_TEST));
    for (int i = 0; i < 5; ++i) sidx_hook_emit(&h, &seq[i]);
    /* the printer's own mask holds even when called directly */
    h.fn(&seq[0], h.user);
    assert_int_equal(p.lines, 6);

    char *got = slurp(f);
    assert_string_equal(got, "ray 0 begin (bvh)  t=[0, inf]\n"
                             "  node 0 enter  depth 0  t=[0, 4]\n"
                             "    box node 1 hit  t=[1, 2]\n"
                             "    prim 2 test: miss\n"
                             "ray 0 end: miss\n"
                             "    box node 1 hit  t=[1, 2]  box [(0, 0, 0), (1, 2, 3)]\n");
    free(got);
    fclose(f);
}

/* A line longer than the printer's stack buffer streams in pieces. */
static void test_printer_long_line(void **state)
{
    (void)state;
    enum { N = 3000 };
    char *text = malloc(N + 1);
    assert_non_null(text);
    for (int i = 0; i < N; ++i) text[i] = (char)('a' + i % 26);
    text[N] = '\0';
    text[100] = '\t';

    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.text = text;

    FILE *f = tmpfile();
    assert_non_null(f);
    sidx_printer p;
    sidx_printer_init(&p, f);
    sidx_hook h = sidx_printer_hook(&p);
    h.fn(&e, h.user);

    char *got = slurp(f);
    assert_int_equal(strlen(got), 2 + 6 + N + 1);
    assert_memory_equal(got, "  note: ", 8);
    assert_int_equal(got[8 + 100], ' ');
    assert_memory_equal(got + 8 + 101, text + 101, N - 101);
    assert_int_equal(got[8 + N], '\n');
    int n = sidx_event_format(&e, NULL, 0);
    assert_int_equal(n, 8 + N);
    free(got);
    fclose(f);

    /* and the JSON sink too, with every character kept */
    f = tmpfile();
    assert_non_null(f);
    sidx_jsonl j;
    sidx_jsonl_init(&j, f);
    h = sidx_jsonl_hook(&j);
    h.fn(&e, h.user);
    got = slurp(f);
    size_t len = strlen(got);
    assert_int_equal(got[len - 1], '\n');
    got[len - 1] = '\0';
    json_check jc = json_parse_line(got);
    assert_true(json_has(&jc, "text"));
    assert_non_null(strstr(got, "\\t"));
    free(got);
    fclose(f);
    free(text);
}

/* ---- JSON Lines ---------------------------------------------------------- */

static void test_json_fields_per_type(void **state)
{
    (void)state;
    sidx_event e;

    e = sidx_event_blank(SIDX_EV_BUILD_BEGIN);
    e.count = 3;
    e.bounds = box(0, 0, 0, 1, 1, 1);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "count", "bounds", NULL});

    e = sidx_event_blank(SIDX_EV_BUILD_NODE);
    e.node = 1;
    e.parent = 0;
    e.depth = 1;
    e.count = 2;
    e.bounds = box(0, 0, 0, 1, 1, 1);
    expect_json_keys(&e,
                     (const char *const[]){"type", "structure", "ray", "node", "parent", "depth", "count", "bounds", NULL});

    e = sidx_event_blank(SIDX_EV_BUILD_CANDIDATE);
    e.node = 1;
    e.axis = 1;
    e.pos = 0.5f;
    e.cost = 2;
    e.count = 1;
    e.aux = 1;
    const char *const cand[] = {"type", "structure", "ray", "node", "axis", "pos", "cost", "count", "aux", NULL};
    expect_json_keys(&e, cand);
    e.type = SIDX_EV_BUILD_SPLIT;
    expect_json_keys(&e, cand);
    e.axis = -1; /* BSP plane: the normal comes along in bounds */
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "axis", "pos", "cost", "count",
                                               "aux", "bounds", NULL});

    e = sidx_event_blank(SIDX_EV_BUILD_LEAF);
    e.node = 2;
    e.count = 1;
    e.reason = SIDX_LEAF_MAX_DEPTH;
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "depth", "count", "cost", "reason",
                                               NULL});

    const uint32_t one = 7;
    e.prims = &one; /* the list comes along when the structure gives it */
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "depth", "count", "cost", "reason",
                                               "prims", NULL});

    e = sidx_event_blank(SIDX_EV_BUILD_END);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "count", "depth", NULL});

    e = ev_ray_begin(1, 0, INFINITY);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "t_near", "t_far", NULL});

    e = ev_node_enter(1, 1, 0, 1);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "depth", "t_near", "t_far", NULL});
    e.cell[0] = 1;
    e.cell[1] = 2;
    e.cell[2] = 3;
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "depth", "t_near", "t_far", "cell",
                                               NULL});

    e = ev_box(1, 0, 1, 0, 1);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "result", "bounds", "t_near",
                                               "t_far", NULL});
    e = ev_box(1, 0, 0, 0, 0); /* a miss has no interval */
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "node", "result", "bounds", NULL});

    const char *const stack[] = {"type", "structure", "ray", "node", "depth", "t_near", "t_far", NULL};
    e = sidx_event_blank(SIDX_EV_STACK_PUSH);
    expect_json_keys(&e, stack);
    e = sidx_event_blank(SIDX_EV_STACK_POP);
    expect_json_keys(&e, stack);
    /* a result where the walk gives one: dropped, or the kd-tree's ray inside a split plane */
    const char *const stack_result[] = {"type", "structure", "ray", "node", "depth", "t_near", "t_far", "result", NULL};
    e.result = SIDX_STACK_DROPPED;
    expect_json_keys(&e, stack_result);
    e = sidx_event_blank(SIDX_EV_STACK_PUSH);
    e.result = SIDX_STACK_IN_PLANE;
    expect_json_keys(&e, stack_result);

    e = ev_prim(1, 1, 2.0f);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "prim", "result", "t", NULL});
    e = ev_prim(1, 0, 0);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "prim", "result", NULL});

    e = sidx_event_blank(SIDX_EV_HIT_UPDATE);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "prim", "t", NULL});
    e = sidx_event_blank(SIDX_EV_MAILBOX_HIT);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "prim", NULL});
    e = sidx_event_blank(SIDX_EV_TERMINATE);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "reason", "t", "count", NULL});
    e = sidx_event_blank(SIDX_EV_RAY_END);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "prim", "t", "result", NULL});
    e = sidx_event_blank(SIDX_EV_NOTE);
    expect_json_keys(&e, (const char *const[]){"type", "structure", "ray", "text", NULL});
}

static void test_json_values(void **state)
{
    (void)state;
    char buf[512];

    sidx_event e = ev_ray_begin(7, 0.0f, INFINITY);
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_string_equal(buf, "{\"type\":\"ray_begin\",\"structure\":\"bvh\",\"ray\":7,\"t_near\":0,\"t_far\":\"inf\"}");

    /* -inf, nan and ids left blank */
    e = sidx_event_blank(SIDX_EV_STACK_POP);
    e.t_near = -INFINITY;
    e.structure = NULL;
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_string_equal(buf, "{\"type\":\"stack_pop\",\"structure\":null,\"ray\":0,\"node\":null,\"depth\":0,"
                             "\"t_near\":\"-inf\",\"t_far\":\"nan\"}");
    e.result = 0; /* a pop the walk drops says so */
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_string_equal(buf, "{\"type\":\"stack_pop\",\"structure\":null,\"ray\":0,\"node\":null,\"depth\":0,"
                             "\"t_near\":\"-inf\",\"t_far\":\"nan\",\"result\":0}");

    /* floats: shortest text that reads back as the same float */
    e = ev_prim(42, 1, 0.734f);
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_string_equal(buf, "{\"type\":\"prim_test\",\"structure\":\"bvh\",\"ray\":0,\"prim\":42,\"result\":1,"
                             "\"t\":0.734}");
    e.t = 1.0f / 3.0f;
    sidx_event_to_json(&e, buf, sizeof buf);
    const char *t = strstr(buf, "\"t\":");
    assert_non_null(t);
    assert_true(strtof(t + 4, NULL) == 1.0f / 3.0f);
    e.t = 1e-30f;
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_non_null(strstr(buf, "\"t\":1e-30}"));
    json_parse_line(buf);

    /* reasons by name, cells as arrays, bounds as min/max */
    e = sidx_event_blank(SIDX_EV_TERMINATE);
    e.structure = "grid";
    e.reason = SIDX_TERM_LEFT_GRID;
    e.count = 5;
    e.cell[0] = 4;
    e.cell[1] = 0;
    e.cell[2] = 2;
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_string_equal(buf, "{\"type\":\"terminate\",\"structure\":\"grid\",\"ray\":0,\"reason\":\"left_grid\","
                             "\"t\":\"inf\",\"count\":5,\"cell\":[4,0,2]}");

    e = sidx_event_blank(SIDX_EV_BUILD_BEGIN);
    e.count = 2;
    e.bounds = box(-1.5f, 0, 0, 1, 2, 3);
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_string_equal(buf, "{\"type\":\"build_begin\",\"structure\":\"\",\"ray\":0,\"count\":2,"
                             "\"bounds\":{\"min\":[-1.5,0,0],\"max\":[1,2,3]}}");

    /* text needing escapes */
    e = sidx_event_blank(SIDX_EV_NOTE);
    e.text = "say \"hi\"\\ back\n\x01";
    sidx_event_to_json(&e, buf, sizeof buf);
    assert_string_equal(buf, "{\"type\":\"note\",\"structure\":\"\",\"ray\":0,"
                             "\"text\":\"say \\\"hi\\\"\\\\ back\\n\\u0001\"}");
    json_parse_line(buf);
}

static void test_jsonl_sink(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    sidx_jsonl j;
    sidx_jsonl_init(&j, f);
    sidx_hook h = sidx_jsonl_hook(&j);

    /* one of every type */
    for (int t = 0; t < SIDX_EV_COUNT; ++t) {
        sidx_event e = sidx_event_blank((sidx_event_type)t);
        e.structure = "kd\"tree"; /* a quote to escape on every line */
        e.text = t == SIDX_EV_NOTE ? "a \"quoted\" note" : NULL;
        sidx_hook_emit(&h, &e);
    }
    assert_int_equal(j.lines, SIDX_EV_COUNT);

    char *all = slurp(f);
    int lines = 0;
    for (char *line = all, *nl; (nl = strchr(line, '\n')); line = nl + 1) {
        *nl = '\0';
        json_check jc = json_parse_line(line);
        assert_true(json_has(&jc, "type") && json_has(&jc, "structure") && json_has(&jc, "ray"));
        char want[64];
        snprintf(want, sizeof want, "{\"type\":\"%s\",", sidx_event_type_name((sidx_event_type)lines));
        assert_memory_equal(line, want, strlen(want));
        ++lines;
    }
    assert_int_equal(lines, SIDX_EV_COUNT);
    free(all);
    fclose(f);
}

/* Reads back "count" and the "prims" array of a build_leaf JSON line.
 * Returns the number of ids read into ids (at most cap), -1 without a list. */
static long json_leaf_prims(const char *line, uint32_t *count, uint32_t *ids, size_t cap)
{
    const char *c = strstr(line, "\"count\":");
    assert_non_null(c);
    *count = (uint32_t)strtoul(c + 8, NULL, 10);
    const char *p = strstr(line, "\"prims\":[");
    if (!p) return -1;
    p += 9;
    long n = 0;
    while (*p != ']') {
        char *end;
        unsigned long v = strtoul(p, &end, 10);
        assert_true(end != p);
        if ((size_t)n < cap) ids[n] = (uint32_t)v;
        ++n;
        p = end;
        if (*p == ',') ++p;
    }
    return n;
}

/* A leaf's list survives the trip through the JSONL sink: every id, in
 * order, as many as count says, even when the line outgrows the sink's
 * stack buffer. */
static void test_jsonl_leaf_prims_round_trip(void **state)
{
    (void)state;
    FILE *f = tmpfile();
    assert_non_null(f);
    sidx_jsonl j;
    sidx_jsonl_init(&j, f);
    sidx_hook h = sidx_jsonl_hook(&j);

    enum { BIG = 300 }; /* ~2 KB of ids: longer than one stack-formatted line */
    static uint32_t big[BIG];
    for (uint32_t i = 0; i < BIG; ++i) big[i] = 4000000000u - 7u * i; /* large and unordered enough */
    const uint32_t small[3] = {5, 0, 11};
    sidx_event e = sidx_event_blank(SIDX_EV_BUILD_LEAF);
    e.structure = "bvh";
    e.node = 3;
    e.count = 3;
    e.prims = small;
    sidx_hook_emit(&h, &e);
    e.count = BIG;
    e.prims = big;
    sidx_hook_emit(&h, &e);
    e.count = 2;
    e.prims = NULL; /* a structure that does not list them: no key at all */
    sidx_hook_emit(&h, &e);

    char *all = slurp(f);
    char *l1 = all, *l2 = strchr(l1, '\n');
    assert_non_null(l2);
    *l2++ = '\0';
    char *l3 = strchr(l2, '\n');
    assert_non_null(l3);
    *l3++ = '\0';
    assert_non_null(strchr(l3, '\n'));
    *strchr(l3, '\n') = '\0';
    json_parse_line(l1);
    json_parse_line(l2);
    json_parse_line(l3);

    uint32_t count, got[BIG];
    assert_int_equal(json_leaf_prims(l1, &count, got, BIG), 3);
    assert_int_equal(count, 3);
    assert_memory_equal(got, small, sizeof small);
    assert_int_equal(json_leaf_prims(l2, &count, got, BIG), BIG);
    assert_int_equal(count, BIG);
    assert_memory_equal(got, big, sizeof big);
    assert_int_equal(json_leaf_prims(l3, &count, got, BIG), -1);
    assert_int_equal(count, 2);
    free(all);
    fclose(f);
}

/* ---- recorder ------------------------------------------------------------ */

/* The recorder keeps its own copy of each leaf's list: the emitter's array
 * may be reused as soon as the callback returns, and the copies must stay
 * put while thousands more leaves arrive. */
static void test_recorder_copies_leaf_prims(void **state)
{
    (void)state;
    sidx_recorder r;
    sidx_recorder_init(&r);
    sidx_hook h = sidx_recorder_hook(&r);
    enum { LEAVES = 3000 }; /* 3000 leaves of up to 9 ids: several chunks of the store */
    uint32_t scratch[9];
    const uint32_t *first_copy = NULL;
    for (uint32_t l = 0; l < LEAVES; ++l) {
        sidx_event e = sidx_event_blank(SIDX_EV_BUILD_LEAF);
        e.node = l;
        e.count = l % 10; /* 0..9, so some leaves are empty */
        for (uint32_t k = 0; k < e.count; ++k) scratch[k] = l * 10u + k;
        e.prims = scratch;
        sidx_hook_emit(&h, &e);
        if (l == 1) first_copy = r.events[r.count - 1].prims;
        memset(scratch, 0xff, sizeof scratch); /* the emitter reuses its array */
        /* and an event without a list stays without one */
        sidx_event n = sidx_event_blank(SIDX_EV_BUILD_NODE);
        sidx_hook_emit(&h, &n);
    }
    assert_int_equal(r.count, 2 * LEAVES);
    assert_int_equal(r.overflow, 0);
    assert_ptr_equal(r.events[2].prims, first_copy); /* never moved */
    for (uint32_t l = 0; l < LEAVES; ++l) {
        const sidx_event *e = &r.events[2 * l];
        assert_int_equal(e->count, l % 10);
        if (e->count == 0) {
            assert_null(e->prims);
        } else {
            assert_non_null(e->prims);
            assert_true(e->prims != scratch);
            for (uint32_t k = 0; k < e->count; ++k) assert_int_equal(e->prims[k], l * 10u + k);
        }
        assert_null(r.events[2 * l + 1].prims);
    }
    /* clear drops the copies with the events; recording starts afresh */
    sidx_recorder_clear(&r);
    assert_null(r.prim_store);
    const uint32_t two[2] = {8, 9};
    sidx_event e = sidx_event_blank(SIDX_EV_BUILD_LEAF);
    e.count = 2;
    e.prims = two;
    sidx_hook_emit(&h, &e);
    assert_int_equal(r.count, 1);
    assert_int_equal(r.events[0].prims[1], 9);
    sidx_recorder_free(&r);
    assert_null(r.prim_store);
}

static void test_recorder(void **state)
{
    (void)state;
    sidx_recorder r;
    sidx_recorder_init(&r);
    assert_null(r.events);
    assert_int_equal(r.count, 0);
    sidx_hook h = sidx_recorder_hook(&r);

    /* enough to grow several times */
    for (uint32_t i = 0; i < 1000; ++i) {
        sidx_event e = ev_prim(i, (int)(i & 1), (float)i);
        sidx_hook_emit(&h, &e);
    }
    assert_int_equal(r.count, 1000);
    assert_true(r.capacity >= 1000);
    assert_int_equal(r.overflow, 0);
    for (uint32_t i = 0; i < 1000; ++i) {
        assert_int_equal(r.events[i].type, SIDX_EV_PRIM_TEST);
        assert_int_equal(r.events[i].prim, i);
        assert_int_equal(r.events[i].result, (int)(i & 1));
    }
    assert_string_equal(r.events[3].structure, "bvh");

    /* clear keeps the memory */
    sidx_event *mem = r.events;
    size_t cap = r.capacity;
    sidx_recorder_clear(&r);
    assert_int_equal(r.count, 0);
    assert_ptr_equal(r.events, mem);
    assert_int_equal(r.capacity, cap);

    /* limit: the first `limit` events are kept, the rest dropped and flagged */
    r.limit = 3;
    for (uint32_t i = 0; i < 5; ++i) {
        sidx_event e = ev_prim(100 + i, 0, 0);
        sidx_hook_emit(&h, &e);
    }
    assert_int_equal(r.count, 3);
    assert_int_equal(r.overflow, 1);
    assert_int_equal(r.events[2].prim, 102);

    /* once something was dropped nothing more is recorded, even below the limit */
    r.limit = 0;
    sidx_event e = ev_prim(999, 0, 0);
    sidx_hook_emit(&h, &e);
    assert_int_equal(r.count, 3);

    sidx_recorder_clear(&r);
    assert_int_equal(r.overflow, 0);
    sidx_hook_emit(&h, &e);
    assert_int_equal(r.count, 1);

    sidx_recorder_free(&r);
    assert_null(r.events);
    assert_int_equal(r.count, 0);
    assert_int_equal(r.capacity, 0);
    sidx_recorder_free(&r); /* twice is fine */
    sidx_recorder_clear(NULL);
    sidx_recorder_free(NULL);
}

/* When the array cannot grow the recorder flags overflow instead of
 * crashing.  (The capacity is faked at the largest size a realloc could
 * ever be asked for, so no allocation is attempted.) */
static void test_recorder_cannot_grow(void **state)
{
    (void)state;
    sidx_recorder r;
    sidx_recorder_init(&r);
    sidx_hook h = sidx_recorder_hook(&r);
    sidx_event e = ev_prim(1, 0, 0);
    sidx_hook_emit(&h, &e);
    assert_int_equal(r.count, 1);

    sidx_event *real = r.events;
    size_t real_count = r.count, real_cap = r.capacity;
    r.count = r.capacity = SIZE_MAX / sizeof(sidx_event);
    sidx_hook_emit(&h, &e);
    assert_int_equal(r.overflow, 1);
    assert_ptr_equal(r.events, real);

    r.count = real_count;
    r.capacity = real_cap;
    sidx_recorder_free(&r);
}

/* ---- counters ------------------------------------------------------------ */

static void test_counters(void **state)
{
    (void)state;
    sidx_counters c;
    sidx_counters_init(&c);
    sidx_hook h = sidx_counters_hook(&c);

    sidx_event seq[] = {
        ev_ray_begin(0, 0, INFINITY), ev_node_enter(0, 0, 0, 1), ev_box(1, 1, 1, 0, 1), ev_box(2, 1, 0, 0, 0),
        ev_box(3, 1, 1, 0, 2),        ev_prim(1, 0, 0),          ev_prim(2, 1, 1.0f),   sidx_event_blank(SIDX_EV_RAY_END),
        ev_ray_begin(1, 0, INFINITY),
    };
    for (size_t i = 0; i < sizeof seq / sizeof seq[0]; ++i) sidx_hook_emit(&h, &seq[i]);

    assert_int_equal(c.n[SIDX_EV_RAY_BEGIN], 2);
    assert_int_equal(c.n[SIDX_EV_NODE_ENTER], 1);
    assert_int_equal(c.n[SIDX_EV_BOX_TEST], 3);
    assert_int_equal(c.n[SIDX_EV_PRIM_TEST], 2);
    assert_int_equal(c.n[SIDX_EV_RAY_END], 1);
    assert_int_equal(c.n[SIDX_EV_BUILD_NODE], 0);
    assert_int_equal(c.box_hits, 2);
    assert_int_equal(c.prim_hits, 1);
    assert_int_equal(c.rays, 2);

    /* an out-of-range type is ignored, not counted out of bounds */
    sidx_event bad = sidx_event_blank(SIDX_EV_NOTE);
    bad.type = SIDX_EV_COUNT;
    h.fn(&bad, h.user);

    FILE *f = tmpfile();
    assert_non_null(f);
    sidx_counters_print(&c, f);
    char *got = slurp(f);
    assert_string_equal(got, "ray_begin: 2\n"
                             "node_enter: 1\n"
                             "box_test: 3\n"
                             "prim_test: 2\n"
                             "ray_end: 1\n"
                             "prim_hits: 1\n"
                             "box_hits: 2\n"
                             "rays: 2\n");
    free(got);
    fclose(f);

    /* nothing counted: nothing printed */
    sidx_counters_init(&c);
    f = tmpfile();
    assert_non_null(f);
    sidx_counters_print(&c, f);
    got = slurp(f);
    assert_string_equal(got, "");
    free(got);
    fclose(f);
}

/* ---- tee and masks ------------------------------------------------------- */

static void test_tee(void **state)
{
    (void)state;
    sidx_counters all, boxes, prims;
    sidx_counters_init(&all);
    sidx_counters_init(&boxes);
    sidx_counters_init(&prims);
    sidx_recorder rec;
    sidx_recorder_init(&rec);

    sidx_tee t;
    memset(&t, 0, sizeof t);
    t.hooks[0] = sidx_counters_hook(&all);
    t.hooks[1] = sidx_counters_hook(&boxes);
    t.hooks[1].mask = SIDX_EVMASK(SIDX_EV_BOX_TEST);
    t.hooks[2] = sidx_counters_hook(&prims);
    t.hooks[2].mask = SIDX_EVMASK(SIDX_EV_PRIM_TEST) | SIDX_EVMASK(SIDX_EV_HIT_UPDATE);
    t.hooks[3] = sidx_recorder_hook(&rec);
    t.hooks[3].mask = SIDX_EVMASK_BUILD;
    t.n = 4;
    sidx_hook h = sidx_tee_hook(&t);
    assert_int_equal(h.mask, 0); /* hooks[0] wants everything */

    sidx_event seq[] = {ev_ray_begin(0, 0, INFINITY), ev_box(1, 0, 1, 0, 1), ev_prim(3, 1, 0.5f),
                        sidx_event_blank(SIDX_EV_BUILD_LEAF), sidx_event_blank(SIDX_EV_HIT_UPDATE)};
    for (size_t i = 0; i < sizeof seq / sizeof seq[0]; ++i) sidx_hook_emit(&h, &seq[i]);

    assert_int_equal(all.n[SIDX_EV_RAY_BEGIN] + all.n[SIDX_EV_BOX_TEST] + all.n[SIDX_EV_PRIM_TEST] +
                         all.n[SIDX_EV_BUILD_LEAF] + all.n[SIDX_EV_HIT_UPDATE],
                     5);
    assert_int_equal(boxes.n[SIDX_EV_BOX_TEST], 1);
    assert_int_equal(boxes.n[SIDX_EV_RAY_BEGIN] + boxes.n[SIDX_EV_PRIM_TEST], 0);
    assert_int_equal(prims.n[SIDX_EV_PRIM_TEST], 1);
    assert_int_equal(prims.n[SIDX_EV_HIT_UPDATE], 1);
    assert_int_equal(prims.n[SIDX_EV_BOX_TEST] + prims.rays, 0);
    assert_int_equal(rec.count, 1);
    assert_int_equal(rec.events[0].type, SIDX_EV_BUILD_LEAF);

    /* without the catch-all hook the tee's mask is the union of the others */
    t.hooks[0].fn = NULL;
    h = sidx_tee_hook(&t);
    assert_int_equal(h.mask, SIDX_EVMASK(SIDX_EV_BOX_TEST) | SIDX_EVMASK(SIDX_EV_PRIM_TEST) |
                                 SIDX_EVMASK(SIDX_EV_HIT_UPDATE) | SIDX_EVMASK_BUILD);
    sidx_hook_emit(&h, &seq[0]); /* nobody wants ray_begin: filtered before the tee */
    assert_int_equal(all.rays, 1);
    assert_int_equal(rec.count, 1);

    /* fewer hooks than slots, and a bogus n, are handled */
    t.n = 1;
    h = sidx_tee_hook(&t);
    sidx_hook_emit(&h, &seq[1]); /* hooks[0] has no fn: nothing happens */
    assert_int_equal(boxes.n[SIDX_EV_BOX_TEST], 1);
    t.n = 99;
    t.hooks[0] = sidx_counters_hook(&all);
    h = sidx_tee_hook(&t);
    sidx_hook_emit(&h, &seq[1]);
    assert_int_equal(all.n[SIDX_EV_BOX_TEST], 2);
    assert_int_equal(boxes.n[SIDX_EV_BOX_TEST], 2);
    t.n = -1;
    h = sidx_tee_hook(&t);
    sidx_hook_emit(&h, &seq[1]);
    assert_int_equal(all.n[SIDX_EV_BOX_TEST], 2);

    /* a tee inside a tee */
    sidx_tee inner;
    memset(&inner, 0, sizeof inner);
    inner.hooks[0] = sidx_counters_hook(&prims);
    inner.n = 1;
    sidx_tee outer;
    memset(&outer, 0, sizeof outer);
    outer.hooks[0] = sidx_tee_hook(&inner);
    outer.hooks[0].mask = SIDX_EVMASK(SIDX_EV_MAILBOX_HIT);
    outer.n = 1;
    h = sidx_tee_hook(&outer);
    sidx_event mb = sidx_event_blank(SIDX_EV_MAILBOX_HIT);
    sidx_hook_emit(&h, &mb);
    sidx_hook_emit(&h, &seq[2]);
    assert_int_equal(prims.n[SIDX_EV_MAILBOX_HIT], 1);
    assert_int_equal(prims.n[SIDX_EV_PRIM_TEST], 1);

    sidx_recorder_free(&rec);
}

static void count_calls(const sidx_event *ev, void *user)
{
    (void)ev;
    ++*(int *)user;
}

static void test_hook_emit_mask(void **state)
{
    (void)state;
    int calls = 0;
    sidx_hook h = {count_calls, &calls, 0};
    sidx_event box_ev = ev_box(1, 0, 1, 0, 1), prim_ev = ev_prim(1, 0, 0);

    sidx_hook_emit(&h, &box_ev); /* mask 0: everything */
    sidx_hook_emit(&h, &prim_ev);
    assert_int_equal(calls, 2);

    h.mask = SIDX_EVMASK(SIDX_EV_PRIM_TEST);
    sidx_hook_emit(&h, &box_ev);
    sidx_hook_emit(&h, &prim_ev);
    assert_int_equal(calls, 3);

    h.mask = SIDX_EVMASK_BUILD;
    sidx_hook_emit(&h, &prim_ev);
    assert_int_equal(calls, 3);
    h.mask = SIDX_EVMASK_TRAVERSAL;
    sidx_hook_emit(&h, &prim_ev);
    assert_int_equal(calls, 4);

    /* no hook, no function, no event: no call, no crash */
    sidx_hook_emit(NULL, &prim_ev);
    h.fn = NULL;
    sidx_hook_emit(&h, &prim_ev);
    h.fn = count_calls;
    sidx_hook_emit(&h, NULL);
    assert_int_equal(calls, 4);
}

/* The traced elementary tests deliver events any sink can print. */
static void test_traced_tests_through_printer(void **state)
{
    (void)state;
#ifdef SIDX_NO_HOOKS
    skip(); /* the traced tests emit through SIDX_EMIT, compiled out in this build */
#endif
    FILE *f = tmpfile();
    assert_non_null(f);
    sidx_printer p;
    sidx_printer_init(&p, f);
    sidx_hook h = sidx_printer_hook(&p);

    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0.25f, 0.25f, -1), sidx_v3(0, 0, 1), 0, INFINITY), SIDX_OK);
    float t = 0, u = 0, v = 0;
    assert_int_equal(sidx_trace_triangle(&h, SIDX_TRI_WATERTIGHT, 7, &r, sidx_v3(0, 0, 0), sidx_v3(1, 0, 0),
                                         sidx_v3(0, 1, 0), INFINITY, &t, &u, &v),
                     1);
    sidx_aabb b = box(2, 2, 2, 3, 3, 3);
    float tn = 0, tf = 0;
    assert_int_equal(sidx_trace_aabb(&h, SIDX_BOX_ROBUST, 5, &r, &b, 0, INFINITY, &tn, &tf), 0);

    char *got = slurp(f);
    assert_string_equal(got, "    prim 7 test: hit t=1\n"
                             "  box node 5 miss\n");
    free(got);
    fclose(f);
}

/* ---- reading JSON back (sidx_event_from_json) ----------------------------- */

/* json -> event -> json gives the same line; returns the event read. */
static sidx_event json_round_trip(const sidx_event *e, char *store, size_t store_size)
{
    char a[4096], b[4096];
    const int n = sidx_event_to_json(e, a, sizeof a);
    assert_true(n > 0 && (size_t)n < sizeof a);
    sidx_event back;
    sidx_error err = {SIDX_OK, ""};
    size_t used = 0;
    const sidx_status s = sidx_event_from_json(a, &back, store, store_size, &used, &err);
    if (s != SIDX_OK) fail_msg("%s: %s", a, err.message);
    assert_true(used <= 2 * (size_t)n + 16);
    sidx_event_to_json(&back, b, sizeof b);
    assert_string_equal(a, b);
    assert_int_equal(back.type, e->type);
    return back;
}

/* Every event type, with the awkward values each field can hold. */
static void test_json_read_round_trip(void **state)
{
    (void)state;
    char store[8192];
    static const uint32_t ids[] = {0, 7, 4294967294u, 12};
    static const float floats[] = {0.0f, -0.0f, 0.734f, 1.0f / 3.0f, 1e-30f, 1.4e-45f /* subnormal */,
                                   3.4028235e38f, -2.5f, INFINITY, -INFINITY, NAN};
    const size_t nf = sizeof floats / sizeof floats[0];
    for (int t = 0; t < SIDX_EV_COUNT; ++t) {
        for (size_t v = 0; v < nf; ++v) {
            sidx_event e = sidx_event_blank((sidx_event_type)t);
            e.structure = v % 3 == 0 ? "bvh" : v % 3 == 1 ? "" : NULL;
            e.ray_id = v == 2 ? UINT32_MAX : (uint32_t)v;
            e.node = v % 2 ? UINT32_MAX : (uint32_t)(v * 3);
            e.parent = v % 4 ? (uint32_t)v : UINT32_MAX;
            e.depth = v % 5 ? (uint32_t)v : UINT32_MAX;
            e.prim = v % 2 ? (uint32_t)v + 100u : UINT32_MAX;
            e.count = (uint32_t)(sizeof ids / sizeof ids[0]);
            e.aux = v == 3 ? UINT32_MAX : (uint32_t)v;
            e.axis = (int32_t)(v % 4) - 1; /* -1 (a BSP plane) .. 2 */
            e.result = v % 3 == 0 ? 1 : v % 3 == 1 ? 0 : -1;
            e.reason = (int32_t)(v % (t == SIDX_EV_BUILD_LEAF ? SIDX_LEAF_REASON_COUNT : SIDX_TERM_REASON_COUNT));
            if (v % 2) {
                e.cell[0] = (int32_t)v;
                e.cell[1] = INT32_MAX;
                e.cell[2] = 0;
            }
            e.pos = floats[v];
            e.cost = floats[(v + 1) % nf];
            e.t_near = floats[(v + 2) % nf];
            e.t_far = floats[(v + 3) % nf];
            e.t = floats[(v + 4) % nf];
            e.bounds = box(floats[v], -1, 2, floats[(v + 5) % nf], 3, 4);
            e.text = v % 2 ? "a \"quoted\" tab\there, a back\\slash, a line\nbreak, \x01, caf\xc3\xa9" : NULL;
            e.prims = v % 2 ? ids : NULL;
            const sidx_event back = json_round_trip(&e, store, sizeof store);
            if (t == SIDX_EV_NOTE && e.text) assert_string_equal(back.text, e.text);
            if (t == SIDX_EV_BUILD_LEAF && e.prims) assert_memory_equal(back.prims, ids, sizeof ids);
            if (e.structure) assert_string_equal(back.structure, e.structure);
            else assert_null(back.structure);
        }
    }
    /* a leaf with an empty prims list, and a real traversal */
    sidx_event leaf = sidx_event_blank(SIDX_EV_BUILD_LEAF);
    leaf.count = 0;
    leaf.prims = ids;
    json_round_trip(&leaf, store, sizeof store);
    sidx_mesh m;
    sidx_accel *a = NULL;
    assert_int_equal(sidx_scene_open("flat2d", &m, NULL), SIDX_OK);
    sidx_recorder rec;
    sidx_recorder_init(&rec);
    sidx_hook h = sidx_recorder_hook(&rec);
    sidx_build_options bo;
    memset(&bo, 0, sizeof bo);
    bo.hook = &h;
    assert_int_equal(sidx_accel_build("kdtree", &m, &bo, &a, NULL), SIDX_OK);
    sidx_ray r;
    assert_int_equal(sidx_ray_init(&r, sidx_v3(-1, 0.5f, 0.05f), sidx_v3(1, 0.2f, 0), 0, INFINITY), SIDX_OK);
    sidx_query q;
    memset(&q, 0, sizeof q);
    q.hook = &h;
    sidx_hit hit;
    sidx_accel_intersect(a, &r, &q, &hit);
    assert_true(rec.count > 10);
    for (size_t i = 0; i < rec.count; ++i) json_round_trip(&rec.events[i], store, sizeof store);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);

    /* a kd-tree ray inside the root's split plane x = 0: pushes and pops
     * that say so, and pops dropped beyond the best hit, read back alike */
    assert_int_equal(sidx_scene_open("teapot", &m, NULL), SIDX_OK);
    sidx_recorder_init(&rec);
    h = sidx_recorder_hook(&rec);
    assert_int_equal(sidx_accel_build("kdtree", &m, NULL, &a, NULL), SIDX_OK);
    assert_int_equal(sidx_ray_init(&r, sidx_v3(0, 0.5f, 5), sidx_v3(0, 0, -1), 0, INFINITY), SIDX_OK);
    q.hook = &h;
    sidx_accel_intersect(a, &r, &q, &hit);
    int seen[3][2] = {{0}}; /* [result][pop] */
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event *e = &rec.events[i];
        const sidx_event back = json_round_trip(e, store, sizeof store);
        assert_int_equal(back.result, e->result);
        if ((e->type == SIDX_EV_STACK_PUSH || e->type == SIDX_EV_STACK_POP) && e->result >= 0 && e->result < 3)
            seen[e->result][e->type == SIDX_EV_STACK_POP] = 1;
    }
    assert_true(seen[SIDX_STACK_IN_PLANE][0] && seen[SIDX_STACK_IN_PLANE][1] && seen[SIDX_STACK_DROPPED][1]);
    sidx_recorder_free(&rec);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);

    /* a tree optimisation's build_reinsert events, as the pass emits them */
    assert_int_equal(sidx_scene_open("teapot", &m, NULL), SIDX_OK);
    sidx_recorder_init(&rec);
    h = sidx_recorder_hook(&rec);
    h.mask = SIDX_EVMASK(SIDX_EV_BUILD_REINSERT);
    bo.optimize_ms = 1e6f;
    assert_int_equal(sidx_accel_build("bvh", &m, &bo, &a, NULL), SIDX_OK);
    assert_true(rec.count > 0);
    for (size_t i = 0; i < rec.count; ++i) {
        const sidx_event back = json_round_trip(&rec.events[i], store, sizeof store);
        assert_int_equal(back.node, rec.events[i].node);
        assert_int_equal(back.aux, rec.events[i].aux);
        assert_memory_equal(&back.cost, &rec.events[i].cost, sizeof back.cost);
    }
    sidx_recorder_free(&rec);
    sidx_accel_destroy(a);
    sidx_mesh_free(&m);
}

static sidx_status read_line(const char *line, sidx_error *err)
{
    char store[256];
    sidx_event e = sidx_event_blank(SIDX_EV_NOTE);
    e.node = 77;
    err->message[0] = '\0';
    const sidx_status s = sidx_event_from_json(line, &e, store, sizeof store, NULL, err);
    if (s != SIDX_OK) assert_int_equal(e.node, 77); /* untouched on error */
    return s;
}

/* Malformed lines are errors with a message, never a crash. */
static void test_json_read_errors(void **state)
{
    (void)state;
    static const char *const bad[] = {
        "",
        "   ",
        "[]",
        "{}",
        "null",
        "{\"type\":\"node_enter\"",                                                 /* truncated */
        "{\"type\":\"nodes_enter\",\"structure\":\"bvh\",\"ray\":0}",               /* unknown event name */
        "{\"type\":7,\"structure\":\"bvh\",\"ray\":0}",                             /* type not a string */
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0}",               /* prim missing */
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":\"3\"}", /* wrong type */
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":-3}",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3.5}",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":4294967296}", /* huge */
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":99999999999999999999999}",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":03}",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":1}", /* extra field */
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"prim\":3}",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"colour\":1}",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3} x",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,}",
        "{\"type\":\"mailbox_hit\",\"structure\":\"bvh\",\"ray\":null,\"prim\":3}", /* ray is never null */
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":NaN}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":nan}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":\"NaN\"}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":Infinity}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":1e39}", /* beyond float */
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":-1e999}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":0x10}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":1.}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":.5}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":1e}",
        "{\"type\":\"hit_update\",\"structure\":\"bvh\",\"ray\":0,\"prim\":3,\"t\":null}",
        "{\"type\":\"terminate\",\"structure\":\"bvh\",\"ray\":0,\"reason\":\"bored\",\"t\":1,\"count\":2}",
        "{\"type\":\"terminate\",\"structure\":\"bvh\",\"ray\":0,\"reason\":2,\"t\":1,\"count\":2}",
        "{\"type\":\"build_end\",\"structure\":\"bvh\",\"ray\":0,\"node\":null,\"count\":1,\"depth\":0}",
        "{\"type\":\"box_test\",\"structure\":\"bvh\",\"ray\":0,\"node\":1,\"result\":0,"
        "\"bounds\":{\"min\":[0,0,0],\"max\":[1,1,1]},\"t_near\":0,\"t_far\":1}", /* a miss has no interval */
        "{\"type\":\"box_test\",\"structure\":\"bvh\",\"ray\":0,\"node\":1,\"result\":1,"
        "\"bounds\":{\"min\":[0,0,0],\"max\":[1,1,1]}}", /* a hit needs one */
        "{\"type\":\"box_test\",\"structure\":\"bvh\",\"ray\":0,\"node\":1,\"result\":0,"
        "\"bounds\":{\"min\":[0,0],\"max\":[1,1,1]}}",
        "{\"type\":\"box_test\",\"structure\":\"bvh\",\"ray\":0,\"node\":1,\"result\":0,"
        "\"bounds\":{\"min\":[0,0,0],\"min\":[1,1,1]}}",
        "{\"type\":\"build_leaf\",\"structure\":\"bvh\",\"ray\":0,\"node\":1,\"depth\":0,\"count\":3,"
        "\"cost\":1,\"reason\":\"few_prims\",\"prims\":[1,2]}", /* fewer ids than count */
        "{\"type\":\"build_leaf\",\"structure\":\"bvh\",\"ray\":0,\"node\":1,\"depth\":0,\"count\":1,"
        "\"cost\":1,\"reason\":\"few_prims\",\"prims\":[1,-2]}",
        "{\"type\":\"note\",\"structure\":\"bvh\",\"ray\":0,\"text\":\"unterminated}",
        "{\"type\":\"note\",\"structure\":\"bvh\",\"ray\":0,\"text\":\"bad \\q escape\"}",
        "{\"type\":\"note\",\"structure\":\"bvh\",\"ray\":0,\"text\":\"nul \\u0000 inside\"}",
        "{\"type\":\"note\",\"structure\":\"bvh\",\"ray\":0,\"text\":\"lone \\udc00 surrogate\"}",
        "{\"type\":\"note\",\"structure\":\"bvh\",\"ray\":0,\"text\":\"raw\ttab\"}",
        "{\"type\":\"node_enter\",\"structure\":\"grid\",\"ray\":0,\"node\":1,\"depth\":0,\"t_near\":0,"
        "\"t_far\":1,\"cell\":[1,2]}",
    };
    sidx_error err = {SIDX_OK, ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        const sidx_status s = read_line(bad[i], &err);
        if (s == SIDX_OK) fail_msg("accepted: %s", bad[i]);
        assert_int_equal(s, SIDX_ERR_PARSE);
        assert_int_equal(err.status, SIDX_ERR_PARSE);
        assert_true(strlen(err.message) > 0);
    }
    /* blanks between tokens, another key order and a trailing newline are fine */
    assert_int_equal(read_line(" { \"prim\" : 3 , \"ray\":0, \"type\":\"mailbox_hit\",\"structure\":\"bvh\" }\n", &err),
                     SIDX_OK);
    /* every truncation of a good line is an error */
    sidx_event e = ev_prim(42, 1, 0.734f);
    e.cell[0] = 1;
    e.cell[1] = 2;
    e.cell[2] = 3;
    char line[256], cut[256];
    const int n = sidx_event_to_json(&e, line, sizeof line);
    for (int k = 0; k < n; ++k) {
        memcpy(cut, line, (size_t)k);
        cut[k] = '\0';
        assert_int_equal(read_line(cut, &err), SIDX_ERR_PARSE);
    }
    assert_int_equal(read_line(line, &err), SIDX_OK);
    /* every single-byte change either reads back to a valid line or fails cleanly */
    for (int k = 0; k < n; ++k)
        for (int c = 1; c < 256; c += 7) {
            memcpy(cut, line, (size_t)n + 1);
            cut[k] = (char)c;
            read_line(cut, &err);
        }
    /* a store too small, NULL arguments */
    char tiny[4];
    sidx_event back;
    assert_int_equal(sidx_event_from_json(line, &back, tiny, sizeof tiny, NULL, &err), SIDX_ERR_LIMIT);
    assert_int_equal(sidx_event_from_json(line, &back, NULL, 0, NULL, NULL), SIDX_ERR_LIMIT);
    assert_int_equal(sidx_event_from_json(NULL, &back, tiny, sizeof tiny, NULL, &err), SIDX_ERR_INVALID_ARG);
    assert_int_equal(sidx_event_from_json(line, NULL, tiny, sizeof tiny, NULL, NULL), SIDX_ERR_INVALID_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_format_traversal),
        cmocka_unit_test(test_format_grid_cell),
        cmocka_unit_test(test_format_build),
        cmocka_unit_test(test_format_snprintf_semantics),
        cmocka_unit_test(test_printer_sink),
        cmocka_unit_test(test_printer_long_line),
        cmocka_unit_test(test_json_fields_per_type),
        cmocka_unit_test(test_json_values),
        cmocka_unit_test(test_json_read_round_trip),
        cmocka_unit_test(test_json_read_errors),
        cmocka_unit_test(test_jsonl_sink),
        cmocka_unit_test(test_recorder),
        cmocka_unit_test(test_recorder_copies_leaf_prims),
        cmocka_unit_test(test_jsonl_leaf_prims_round_trip),
        cmocka_unit_test(test_recorder_cannot_grow),
        cmocka_unit_test(test_counters),
        cmocka_unit_test(test_tee),
        cmocka_unit_test(test_hook_emit_mask),
        cmocka_unit_test(test_traced_tests_through_printer),
    };
    return cmocka_run_group_tests_name("sinks", tests, NULL, NULL);
}
