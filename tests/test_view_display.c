/* test_view_display.c — sidx-view without a display: it says so and exits 1.
 *
 * The window mode needs an X server or a Wayland compositor.  Without one,
 * SDL still starts on its "offscreen" driver and a window nobody sees
 * would wait for input forever; sidx-view instead names the problem and
 * the two ways that need no display (--screenshot, --html).  Each run has
 * a time limit (timeout 60) that only catches a hang: the program answers
 * at once.  Runs from the repository root. */
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
#include "common/testkit.h"

static char bin_dir[512] = "build/bin";

#if SIDX_HAVE_SDL
/* Runs `env ENV timeout 60 sidx-view ARGS`, stdin from /dev/null, and
 * returns its stdout and stderr together; *status is the exit status
 * (124 when the time limit ended it, -1 when it did not exit). */
static char *run_view(const char *env, const char *args, int *status)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "env -u DISPLAY -u WAYLAND_DISPLAY -u SDL_VIDEODRIVER -u XDG_RUNTIME_DIR %s "
             "timeout 60 %s/sidx-view %s </dev/null 2>&1", env, bin_dir, args);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    char *out = tk_read_all(p);
    assert_non_null(out);
    const int rc = pclose(p);
    *status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
    return out;
}

static void expect_refusal(const char *env, const char *args, const char *reason)
{
    int status;
    char *out = run_view(env, args, &status);
    if (status == 124) fail_msg("sidx-view %s (%s) did not end within 60 s:\n%s", args, env, out);
    if (status != 1) fail_msg("sidx-view %s (%s) exited %d, not 1:\n%s", args, env, status, out);
    if (!strstr(out, reason)) fail_msg("sidx-view %s (%s) does not say '%s':\n%s", args, env, reason, out);
    if (!strstr(out, "--screenshot out.png") || !strstr(out, "--html out.html"))
        fail_msg("sidx-view %s (%s) does not point to --screenshot and --html:\n%s", args, env, out);
    free(out);
}

/* Neither DISPLAY nor WAYLAND_DISPLAY: refused before SDL starts, so SDL
 * prints nothing of its own. */
static void no_display_variables(void **state)
{
    (void)state;
    expect_refusal("", "--accel kdtree", "no display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
    int status;
    char *out = run_view("", "--accel kdtree", &status);
    if (strstr(out, "XDG_RUNTIME_DIR")) fail_msg("SDL started without a display:\n%s", out);
    free(out);
}

/* A DISPLAY naming no X server: SDL falls back to its offscreen driver. */
static void display_without_server(void **state)
{
    (void)state;
    struct stat st;
    if (stat("/dev/dri", &st) == 0) {
        /* SDL's KMS/DRM driver may show a real window on this machine */
        print_message("/dev/dri exists: skipped\n");
        skip();
    }
    expect_refusal("DISPLAY=:97", "--accel kdtree --scene flat2d", "no display: SDL found only its");
}

/* SDL_VIDEODRIVER picks a driver that does not exist: SDL_Init fails. */
static void video_driver_missing(void **state)
{
    (void)state;
    expect_refusal("SDL_VIDEODRIVER=no-such-driver", "--accel kdtree", "cannot open a window");
}

/* --screenshot and --html need no display. */
static void headless_outputs_still_work(void **state)
{
    (void)state;
    char png[128], page[128], args[400];
    snprintf(png, sizeof png, "/tmp/sidx_view_display_%ld.png", (long)getpid());
    snprintf(page, sizeof page, "/tmp/sidx_view_display_%ld.html", (long)getpid());
    snprintf(args, sizeof args, "--accel kdtree --size 160x100 --screenshot %s", png);
    int status;
    char *out = run_view("", args, &status);
    if (status != 0) fail_msg("sidx-view %s exited %d:\n%s", args, status, out);
    free(out);
    snprintf(args, sizeof args, "--accel kdtree --html %s", page);
    out = run_view("", args, &status);
    if (status != 0) fail_msg("sidx-view %s exited %d:\n%s", args, status, out);
    free(out);
    assert_int_equal(unlink(png), 0);
    assert_int_equal(unlink(page), 0);
}
#else
static void skip_without_sdl(void) { print_message("built without SDL2: no sidx-view, skipped\n"); skip(); }
static void no_display_variables(void **state) { (void)state; skip_without_sdl(); }
static void display_without_server(void **state) { (void)state; skip_without_sdl(); }
static void video_driver_missing(void **state) { (void)state; skip_without_sdl(); }
static void headless_outputs_still_work(void **state) { (void)state; skip_without_sdl(); }
#endif

int main(int argc, char **argv)
{
    (void)argc;
    /* BUILD/tests/test_view_display -> BUILD/bin */
    tk_bin_dir(argv[0], bin_dir, sizeof bin_dir);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(no_display_variables),
        cmocka_unit_test(display_without_server),
        cmocka_unit_test(video_driver_missing),
        cmocka_unit_test(headless_outputs_still_work),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
