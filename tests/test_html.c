/* test_html.c — sidx-view --html in a real browser.
 *
 * Writes pages with the built sidx-view and opens them in headless
 * Chromium (Debian's chromium): --dump-dom reads the page's #state (status,
 * step count, current node, stack, script errors), --screenshot takes
 * pictures at two steps.  The step count is checked against sidx-step
 * --json's trace of the same ray, the stack against view_replay_run.
 * Without chromium or without SDL2 (no sidx-view) the browser tests are
 * skipped with a message.  Runs from the repository root. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>
#include "sidx/sidx.h"
#include "sidx/viz.h"
#if SIDX_HAVE_SDL
#include "../viz/page.h"
#include "../viz/view.h"
#endif

static char bin_dir[512] = "build/bin";
static char tmp_dir[256];
static const char *chromium;

#define RAY "0,1.8,0,1,0.35,0"
#define MISS_RAY "0,3.1,0,-1,0,0"

/* ---- helpers ------------------------------------------------------------------------------ */

/* Runs cmd through the shell; returns its exit status (-1 if it did not exit). */
static int run(const char *cmd)
{
    int st = system(cmd);
    return st != -1 && WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

#if SIDX_HAVE_SDL
/* The whole output of cmd (malloc'd, NUL-terminated), or NULL. */
static char *output_of(const char *cmd)
{
    FILE *p = popen(cmd, "r");
    if (!p) return NULL;
    size_t n = 0, cap = 1 << 16;
    char *s = malloc(cap);
    size_t got;
    while (s && (got = fread(s + n, 1, cap - n - 1, p)) > 0) {
        n += got;
        if (cap - n < 4096) {
            char *t = realloc(s, cap * 2);
            if (!t) {
                free(s);
                s = NULL;
                break;
            }
            s = t;
            cap *= 2;
        }
    }
    pclose(p);
    if (s) s[n] = '\0';
    return s;
}

static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

/* Chromium, headless, with the flags a closed machine needs (no network
 * look-ups, no sandbox as root, a fresh profile), stopped after 60 s if it
 * hangs. */
static void browser_cmd(char *buf, size_t size, const char *args)
{
    snprintf(buf, size,
             "timeout 60 %s --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking "
             "--disable-component-update --disable-sync --hide-scrollbars --user-data-dir=%s/profile %s 2>/dev/null",
             chromium, tmp_dir, args);
}

/* The page's DOM at url as the browser left it after its scripts ran (malloc'd). */
static char *page_dom(const char *url)
{
    char args[1024], cmd[2048];
    snprintf(args, sizeof args, "--dump-dom '%s'", url);
    browser_cmd(cmd, sizeof cmd, args);
    return output_of(cmd);
}

/* A copy of what stands between open and close in s (malloc'd), or NULL. */
static char *between(const char *s, const char *open, const char *close)
{
    const char *a = s ? strstr(s, open) : NULL;
    const char *b = a ? strstr(a + strlen(open), close) : NULL;
    if (!a || !b) {
        print_message("no %s...%s in the page's DOM:\n%.400s\n", open, close, s ? s : "(none)");
        return NULL;
    }
    a += strlen(open);
    char *out = malloc((size_t)(b - a) + 1);
    if (!out) return NULL;
    memcpy(out, a, (size_t)(b - a));
    out[b - a] = '\0';
    return out;
}

static void expect_state(const char *state, const char *key, const char *want);

/* The #state of a page whose script ran to the end without an error (malloc'd). */
static char *ready_state(const char *dom)
{
    char *st = between(dom, "<pre id=\"state\">", "</pre>");
    assert_non_null(st);
    expect_state(st, "status", "ready");
    expect_state(st, "errors", "0");
    return st;
}

/* The value of "key=" in a state text, copied to out ("" if absent). */
static void state_get(const char *state, const char *key, char *out, size_t size)
{
    char k[64];
    snprintf(k, sizeof k, "%s=", key);
    out[0] = '\0';
    for (const char *p = state; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : NULL)
        if (!strncmp(p, k, strlen(k))) {
            const char *v = p + strlen(k);
            size_t n = strcspn(v, "\n");
            if (n >= size) n = size - 1;
            memcpy(out, v, n);
            out[n] = '\0';
            return;
        }
}

/* Asserts that the state text has key=want. */
static void expect_state(const char *state, const char *key, const char *want)
{
    char val[512];
    state_get(state, key, val, sizeof val);
    if (strcmp(val, want) != 0) print_message("#state %s=%s, expected %s\n", key, val, want);
    assert_string_equal(val, want);
}

/* Writes tmp_dir/NAME.html with sidx-view ARGS --html; its path in page. */
static void write_page(const char *name, const char *args, char *page, size_t size)
{
    char cmd[2048];
    snprintf(page, size, "%s/%s.html", tmp_dir, name);
    snprintf(cmd, sizeof cmd, "%s/sidx-view %s --html %s >/dev/null", bin_dir, args, page);
    assert_int_equal(run(cmd), 0);
}

static int have_browser(void)
{
    if (!chromium) {
        print_message("chromium is not installed (apt-get install chromium): the browser tests are skipped\n");
        return 0;
    }
    return 1;
}

static int have_viewer(void)
{
    char path[600];
    snprintf(path, sizeof path, "%s/sidx-view", bin_dir);
    if (access(path, X_OK) != 0) {
        print_message("built without SDL2: no sidx-view, skipped\n");
        return 0;
    }
    return 1;
}

/* ---- tests -------------------------------------------------------------------------------- */

/* The page at step k shows what the recorder's replay says; it has as many
 * steps as sidx-step's JSON Lines trace has lines; its pictures at k and
 * k + 1 differ; no script error. */
static void page_steps_like_the_recorder(void **state)
{
    (void)state;
    if (!have_viewer() || !have_browser()) skip();
    char page[400], cmd[4096];
    write_page("flat2d", "--accel bvh --ray " RAY, page, sizeof page);
    long size = file_size(page);
    print_message("flat2d bvh page: %ld bytes\n", size);
    assert_true(size > 0 && size < 300 * 1024);

    /* the same ray in-process: the replay the SDL viewer draws */
    view_state v;
    sidx_error err;
    assert_int_equal(view_open(&v, "flat2d", "bvh", &err), SIDX_OK);
    sidx_vec3 org, dir;
    assert_int_equal(sidx_viz_parse_ray(RAY, &org, &dir), 0);
    assert_int_equal(view_set_ray(&v, org, dir, SIZE_MAX), SIDX_OK);
    /* a step with at least two entries on the stack */
    size_t k = 0;
    view_replay r;
    for (size_t s = 1; s <= v.trav.count && !k; ++s) {
        view_replay_run(&v, s, &r);
        if (r.stack_n >= 2) k = s;
    }
    assert_true(k > 0 && k < v.trav.count);
    view_replay_run(&v, k, &r);
    /* the state's id list and the panel's lines, top first, as the viewer prints them */
    char want_stack[512] = "", want_cur[32], want_panel[2048] = "";
    for (int i = r.stack_n - 1; i >= 0; --i) {
        snprintf(want_stack + strlen(want_stack), sizeof want_stack - strlen(want_stack), "%s%u",
                 i == r.stack_n - 1 ? "" : ",", r.stack[i].node);
        snprintf(want_panel + strlen(want_panel), sizeof want_panel - strlen(want_panel),
                 "<li data-node=\"%u\">node %u  t=[%.3g, %.3g]</li>", r.stack[i].node, r.stack[i].node,
                 (double)r.stack[i].t_near, (double)r.stack[i].t_far);
    }
    snprintf(want_cur, sizeof want_cur, "%u", r.current_id);

    /* sidx-step's trace of the same ray */
    snprintf(cmd, sizeof cmd, "%s/sidx-step --accel bvh flat2d --ray %s --json --all </dev/null | wc -l", bin_dir, RAY);
    char *lines = output_of(cmd);
    assert_non_null(lines);
    const long jsonl = strtol(lines, NULL, 10);
    free(lines);
    assert_int_equal(jsonl, (long)v.trav.count);

    char url[600], val[64];
    snprintf(url, sizeof url, "file://%s#step=%zu", page, k);
    char *dom = page_dom(url);
    char *st = ready_state(dom);
    char *panel = between(dom, "<ol id=\"stack\">", "</ol>");
    free(dom);
    assert_non_null(panel);
    print_message("stack panel: %s\n", panel);
    assert_string_equal(panel, want_panel);
    free(panel);
    snprintf(val, sizeof val, "%ld", jsonl);
    expect_state(st, "steps", val);
    snprintf(val, sizeof val, "%zu", k);
    expect_state(st, "step", val);
    expect_state(st, "current", want_cur);
    print_message("step %zu: current %s, stack (top first) %s\n", k, want_cur, want_stack);
    expect_state(st, "stack", want_stack);
    free(st);
    view_close(&v);

    /* two pictures one step apart differ */
    char shot[2][400], args[2048];
    for (int i = 0; i < 2; ++i) {
        snprintf(shot[i], sizeof shot[i], "%s/step%d.png", tmp_dir, i);
        snprintf(args, sizeof args, "--window-size=1100,700 --screenshot=%s 'file://%s#step=%zu' >/dev/null", shot[i],
                 page, k + (size_t)i);
        browser_cmd(cmd, sizeof cmd, args);
        assert_int_equal(run(cmd), 0);
        assert_true(file_size(shot[i]) > 1000);
    }
    snprintf(cmd, sizeof cmd, "cmp -s %s %s", shot[0], shot[1]);
    assert_int_not_equal(run(cmd), 0);
}

/* Keys and buttons: a script added after the page's own presses them and
 * writes the steps it sees into <pre id="keys">. */
static void page_keys_and_buttons(void **state)
{
    (void)state;
    if (!have_viewer() || !have_browser()) skip();
    char page[400], pressed[400];
    write_page("keys", "--accel kdtree --ray " RAY, page, sizeof page);
    snprintf(pressed, sizeof pressed, "%s/keys-pressed.html", tmp_dir);
    static const char script[] =
        "<script>(function () {\n"
        "  var out = [];\n"
        "  function key(k) { document.dispatchEvent(new KeyboardEvent('keydown', { key: k, bubbles: true })); }\n"
        "  function st(name) { var m = new RegExp('\\n' + name + '=([^\\n]*)').exec(document.getElementById('state').textContent);\n"
        "                      return m ? m[1] : '?'; }\n"
        "  key('Home'); out.push(st('step'));\n"
        "  key('ArrowRight'); key('ArrowRight'); out.push(st('step'));\n"
        "  key('End'); out.push(st('step'));\n"
        "  key('ArrowLeft'); out.push(st('step'));\n"
        "  document.getElementById('b-first').click(); out.push(st('step'));\n"
        "  document.getElementById('evtype').value = 'stack_push';\n"
        "  document.getElementById('b-nexttype').click(); out.push(st('step'));\n"
        "  key('t'); out.push(st('step'));\n"
        "  key('T'); out.push(st('step')); out.push(location.hash);\n"
        "  key('2'); out.push(st('mode')); key('Home'); out.push(st('build_step')); out.push(location.hash);\n"
        "  key(' '); out.push(document.getElementById('b-play').textContent);\n"
        "  key(' '); out.push(document.getElementById('b-play').textContent);\n"
        "  document.body.insertAdjacentHTML('beforeend', '<pre id=\"' + 'keys\">' + out.join(' ') + '</pre>');\n"
        "})();</script>\n";
    /* the page with the script before </body> */
    FILE *in = fopen(page, "rb"), *out = fopen(pressed, "wb");
    assert_non_null(in);
    assert_non_null(out);
    char line[4096];
    while (fgets(line, sizeof line, in)) {
        if (!strcmp(line, "</body>\n")) fputs(script, out);
        fputs(line, out);
    }
    fclose(in);
    fclose(out);

    view_state v;
    sidx_error err;
    sidx_vec3 org, dir;
    assert_int_equal(view_open(&v, "flat2d", "kdtree", &err), SIDX_OK);
    assert_int_equal(sidx_viz_parse_ray(RAY, &org, &dir), 0);
    assert_int_equal(view_set_ray(&v, org, dir, SIZE_MAX), SIDX_OK);
    size_t push[2] = {0, 0}, np = 0;
    for (size_t i = 0; i < v.trav.count && np < 2; ++i)
        if (v.trav.events[i].type == SIDX_EV_STACK_PUSH) push[np++] = i + 1;
    assert_int_equal(np, 2);
    char want[512];
    snprintf(want, sizeof want, "0 2 %zu %zu 0 %zu %zu %zu #step=%zu build 0 #mode=build&amp;step=0 pause play",
             v.trav.count, v.trav.count - 1, push[0], push[1], push[0], push[0]);
    view_close(&v);

    char url[600];
    snprintf(url, sizeof url, "file://%s", pressed);
    char *dom = page_dom(url);
    char *got = between(dom, "<pre id=\"keys\">", "</pre>");
    free(ready_state(dom));
    free(dom);
    assert_non_null(got);
    print_message("keys: %s\n", got);
    assert_string_equal(got, want);
    free(got);
}

/* A page with `script` inserted before </body> (the page's own scripts run first), written to
 * tmp_dir/NAME.html; its path in out. */
static void page_with_script(const char *page, const char *name, const char *script, char *out, size_t size)
{
    snprintf(out, size, "%s/%s.html", tmp_dir, name);
    FILE *in = fopen(page, "rb"), *o = fopen(out, "wb");
    assert_non_null(in);
    assert_non_null(o);
    char line[4096];
    while (fgets(line, sizeof line, in)) {
        if (!strcmp(line, "</body>\n")) fputs(script, o);
        fputs(line, o);
    }
    fclose(in);
    fclose(o);
}

/* At the step whose event reads "prim N test: hit" the panel's best hit is prim N (the
 * structure records it as the closest hit in the next event), and at 1280×800 every event
 * line fits the panel's width: long lines wrap instead of being cut. */
static void page_best_hit_and_lines_fit(void **state)
{
    (void)state;
    if (!have_viewer() || !have_browser()) skip();
    char page[400], measured[400];
    write_page("fit", "--accel kdtree --ray " RAY, page, sizeof page);
    static const char script[] =
        "<script>(function () {\n"
        "  var cut = 0, lines = document.querySelectorAll('#events div');\n"
        "  for (var i = 0; i < lines.length; ++i) if (lines[i].scrollWidth > lines[i].clientWidth + 1) ++cut;\n"
        "  var p = document.getElementById('panel');\n"
        "  var out = lines.length + ' ' + cut + ' ' + (p.scrollWidth > p.clientWidth + 1 ? 1 : 0) + ' ' + window.innerWidth;\n"
        "  out += '|' + document.getElementById('info').textContent;\n"
        "  document.body.insertAdjacentHTML('beforeend', '<pre id=\"' + 'fit\">' + out + '</pre>');\n"
        "})();</script>\n";
    page_with_script(page, "fit-measured", script, measured, sizeof measured);

    /* the first triangle test that hits, and the closest-hit event after it */
    view_state v;
    sidx_error err;
    sidx_vec3 org, dir;
    assert_int_equal(view_open(&v, "flat2d", "kdtree", &err), SIDX_OK);
    assert_int_equal(sidx_viz_parse_ray(RAY, &org, &dir), 0);
    assert_int_equal(view_set_ray(&v, org, dir, SIZE_MAX), SIDX_OK);
    size_t k = 0;
    uint32_t prim = 0;
    for (size_t i = 0; i + 1 < v.trav.count && !k; ++i) {
        const sidx_event *e = &v.trav.events[i];
        if (e->type == SIDX_EV_PRIM_TEST && e->result == 1 && v.trav.events[i + 1].type == SIDX_EV_HIT_UPDATE) {
            k = i + 1;
            prim = e->prim;
        }
    }
    view_close(&v);
    assert_true(k > 0);

    char url[600], args[1024], cmd[2048], want[64];
    snprintf(url, sizeof url, "file://%s#step=%zu", measured, k);
    snprintf(args, sizeof args, "--window-size=1280,800 --dump-dom '%s'", url);
    browser_cmd(cmd, sizeof cmd, args);
    char *dom = output_of(cmd);
    char *st = ready_state(dom);
    char *fit = between(dom, "<pre id=\"fit\">", "</pre>");
    free(dom);
    assert_non_null(fit);
    print_message("step %zu (prim %u test: hit): %s\n", k, prim, fit);
    char best[64];
    state_get(st, "best", best, sizeof best);
    snprintf(want, sizeof want, "%u@", prim);
    assert_true(!strncmp(best, want, strlen(want)));
    snprintf(want, sizeof want, "best hit: prim %u ", prim);
    assert_non_null(strstr(fit, want));
    unsigned lines = 0, cut = 1, wide = 1, width = 0;
    assert_int_equal(sscanf(fit, "%u %u %u %u", &lines, &cut, &wide, &width), 4);
    assert_int_equal(width, 1280);
    assert_true(lines > 10);
    assert_int_equal(cut, 0);
    assert_int_equal(wide, 0);
    free(fit);
    free(st);

    /* one step earlier the hit is not there yet */
    snprintf(url, sizeof url, "file://%s#step=%zu", page, k - 1);
    dom = page_dom(url);
    st = ready_state(dom);
    free(dom);
    expect_state(st, "best", "none");
    free(st);
}

/* A ray that hits nothing: the page says so. */
static void page_says_the_ray_misses(void **state)
{
    (void)state;
    if (!have_viewer() || !have_browser()) skip();
    char page[400], url[600];
    write_page("miss", "--accel kdtree --ray " MISS_RAY, page, sizeof page);
    snprintf(url, sizeof url, "file://%s", page);
    char *dom = page_dom(url);
    assert_non_null(dom);
    assert_non_null(strstr(dom, "The ray misses"));
    char *st = ready_state(dom);
    free(dom);
    expect_state(st, "miss", "1");
    free(st);
}

/* The teapot's traversal and build in one page under 2 MB, opening in 3D
 * without a script error. */
static void teapot_page_is_small(void **state)
{
    (void)state;
    if (!have_viewer()) skip();
    char page[400];
    write_page("teapot", "--accel bvh --scene teapot --ray 0,0.6,4,0,-0.05,-1 --mode 3d --level 3", page, sizeof page);
    long size = file_size(page);
    print_message("teapot bvh page: %ld bytes\n", size);
    assert_true(size > 0 && size < 2 * 1024 * 1024);
    if (!have_browser()) return;
    char url[600];
    snprintf(url, sizeof url, "file://%s#step=20", page);
    char *dom = page_dom(url);
    char *st = ready_state(dom);
    free(dom);
    expect_state(st, "mode", "3d");
    free(st);
}

/* An unwritable path and a scene too large for a page: exit 1 and a
 * message that says why (the limit, for the scene). */
static void bad_input(void **state)
{
    (void)state;
    if (!have_viewer()) skip();
    char cmd[2048], out[400];
    snprintf(out, sizeof out, "%s/err.txt", tmp_dir);
    snprintf(cmd, sizeof cmd, "%s/sidx-view --html /nonexistent-dir/page.html 2>%s >/dev/null", bin_dir, out);
    assert_int_equal(run(cmd), 1);
    snprintf(cmd, sizeof cmd, "grep -q 'cannot write /nonexistent-dir/page.html' %s", out);
    assert_int_equal(run(cmd), 0);

    /* a 160 x 160 grid of quads: 50562 triangles, over VIEW_HTML_MAX_TRIANGLES */
    char obj[400];
    snprintf(obj, sizeof obj, "%s/big.obj", tmp_dir);
    FILE *f = fopen(obj, "w");
    assert_non_null(f);
    const int n = 160;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) fprintf(f, "v %d %d 0\n", x, y);
    for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
            int a = y * n + x + 1;
            fprintf(f, "f %d %d %d\nf %d %d %d\n", a, a + 1, a + n, a + 1, a + n + 1, a + n);
        }
    fclose(f);
    char page[400];
    snprintf(page, sizeof page, "%s/big.html", tmp_dir);
    snprintf(cmd, sizeof cmd, "%s/sidx-view --scene %s --html %s 2>%s >/dev/null", bin_dir, obj, page, out);
    assert_int_equal(run(cmd), 1);
    snprintf(cmd, sizeof cmd, "grep -q 'has 50562 triangles; a page holds at most %u' %s", VIEW_HTML_MAX_TRIANGLES, out);
    assert_int_equal(run(cmd), 0);
    assert_int_equal(file_size(page), -1);
}
#else
static void skip_without_sdl(void **state)
{
    (void)state;
    print_message("built without SDL2: no sidx-view, skipped\n");
    skip();
}
#endif

int main(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    /* this program is BUILD/tests/test_html; the programs are in BUILD/bin */
    char self[400];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n > 0) {
        self[n] = '\0';
        char *tests = strstr(self, "/tests/test_html");
        if (tests) {
            *tests = '\0';
            snprintf(bin_dir, sizeof bin_dir, "%s/bin", self);
        }
    }
    if (run("command -v chromium >/dev/null 2>&1") == 0)
        chromium = "chromium";
    else if (run("command -v chromium-browser >/dev/null 2>&1") == 0)
        chromium = "chromium-browser";
    snprintf(tmp_dir, sizeof tmp_dir, "/tmp/sidx_html_XXXXXX");
    if (!mkdtemp(tmp_dir)) {
        perror("mkdtemp");
        return 1;
    }
    const struct CMUnitTest tests[] = {
#if SIDX_HAVE_SDL
        cmocka_unit_test(page_steps_like_the_recorder),
        cmocka_unit_test(page_keys_and_buttons),
        cmocka_unit_test(page_says_the_ray_misses),
        cmocka_unit_test(page_best_hit_and_lines_fit),
        cmocka_unit_test(teapot_page_is_small),
        cmocka_unit_test(bad_input),
#else
        cmocka_unit_test(skip_without_sdl),
#endif
    };
    int rc = cmocka_run_group_tests_name("html", tests, NULL, NULL);
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_dir);
    if (run(cmd) != 0) fprintf(stderr, "test_html: could not remove %s\n", tmp_dir);
    return rc;
}
