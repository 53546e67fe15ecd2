/* test_fuzz_regress.c — every input the fuzzers ever crashed on (kept in
 * tests/fuzz/regress/<target>/) and the seed corpus, replayed through the
 * same fuzz target code on every `make test`, so a fixed bug stays fixed.
 * A target aborts on a failed check, which fails this test. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define LLVMFuzzerTestOneInput fuzz_build_one
#define FB_REPLAY 1 /* every input as found: no fuzzing-only caps (fuzz_build.c) */
#include "fuzz/fuzz_build.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_obj_one
#include "fuzz/fuzz_obj.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_ply_one
#include "fuzz/fuzz_ply.c"
#undef LLVMFuzzerTestOneInput
#define LLVMFuzzerTestOneInput fuzz_rays_one
#include "fuzz/fuzz_rays.c"
#undef LLVMFuzzerTestOneInput

typedef int (*target_fn)(const uint8_t *, size_t);

/* Runs fn over every file in dir; returns how many it ran. */
static int replay_dir(const char *dir, target_fn fn)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.') continue;
        char path[512];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        FILE *f = fopen(path, "rb");
        assert_non_null(f);
        fseek(f, 0, SEEK_END);
        long size = ftell(f);
        fseek(f, 0, SEEK_SET);
        /* exactly sized heap copy, so ASan sees any read past the end */
        uint8_t *buf = malloc(size > 0 ? (size_t)size : 1);
        assert_non_null(buf);
        assert_int_equal(fread(buf, 1, (size_t)size, f), (size_t)size);
        fclose(f);
        fn(buf, (size_t)size);
        free(buf);
        ++n;
    }
    closedir(d);
    return n;
}

static void replay(const char *target, target_fn fn)
{
    char dir[256];
    snprintf(dir, sizeof dir, "tests/fuzz/regress/%s", target);
    const int regress = replay_dir(dir, fn);
    snprintf(dir, sizeof dir, "tests/fuzz/corpus/%s", target);
    const int seeds = replay_dir(dir, fn);
    print_message("%s: %d regression inputs, %d seeds replayed\n", target, regress, seeds);
    assert_true(seeds > 0); /* run from the repository root */
}

/* fuzz_build's first byte picks the structure by registry index; an input
 * is replayed with every index, so it keeps testing the structure it was
 * found on when structures are added or reordered, and tests all others. */
static int fuzz_build_every_structure(const uint8_t *data, size_t size)
{
    if (size == 0) return fuzz_build_one(data, size);
    uint8_t *copy = malloc(size);
    assert_non_null(copy);
    memcpy(copy, data, size);
    for (size_t s = 0; s < sidx_accel_registered_count(); ++s) {
        copy[0] = (uint8_t)s;
        fuzz_build_one(copy, size);
    }
    free(copy);
    return 0;
}

static void build_and_trace_inputs(void **state) { (void)state; replay("build", fuzz_build_every_structure); }
static void obj_inputs(void **state) { (void)state; replay("obj", fuzz_obj_one); }
static void ply_inputs(void **state) { (void)state; replay("ply", fuzz_ply_one); }
static void ray_and_hit_file_inputs(void **state) { (void)state; replay("rays", fuzz_rays_one); }

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(build_and_trace_inputs),
        cmocka_unit_test(obj_inputs),
        cmocka_unit_test(ply_inputs),
        cmocka_unit_test(ray_and_hit_file_inputs),
    };
    return cmocka_run_group_tests_name("fuzz regressions", tests, NULL, NULL);
}
