/* The front ends' output (app_output.c): text on stdout and its failure; -o written as PFM, EXR and
 * PNG (through OSMesa; the difference view's heat map), read back; a path that cannot be written
 * refused in one line; the lines an interrupted or finished run says, and what it leaves. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app_fixture.h"
#include "app_output.h"
#include "app_report.h"
#include "image.h"

enum { WIDTH = 8, HEIGHT = 6 };

static float pixels[WIDTH * HEIGHT * 3];

/* A frame of a finished pass: distinct pixel values, 8 spp in 0.5 s at 0.008 Mrays/s. */
static struct ao_frame frame_of(uint32_t pass)
{
    for (int i = 0; i < WIDTH * HEIGHT * 3; i++)
        pixels[i] = (float)i / (WIDTH * HEIGHT * 3);
    struct ao_frame_info info = {.pass = pass, .spp = 8 * pass, .target_spp = 64, .mean_spp = 8.0 * pass,
                                 .pixels = WIDTH * HEIGHT, .error = NAN, .converged = NAN, .seconds = 0.5,
                                 .eye_rays = 1000, .shadow_rays = 3000, .rmse = NAN, .output = AO_OUTPUT_AO};
    return (struct ao_frame){.info = info, .width = WIDTH, .height = HEIGHT, .rgb = pixels};
}

/* What path holds, read as a linear image of the frame's size, is the frame's pixels. */
static void assert_linear_frame(const char *path)
{
    float *back = NULL;
    assert_true(ao_image_read_linear_sized(path, WIDTH, HEIGHT, &back));
    assert_memory_equal(back, pixels, sizeof pixels);
    free(back);
}

/* Runs ao_app_print with stdout sent into path; returns what it returned. */
static bool print_into(const char *path, const char *text)
{
    fflush(stdout);
    int saved = dup(STDOUT_FILENO), fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(saved >= 0 && fd >= 0);
    dup2(fd, STDOUT_FILENO);
    close(fd);
    bool ok = ao_app_print(text);
    clearerr(stdout);
    fflush(stdout);
    dup2(saved, STDOUT_FILENO);
    close(saved);
    return ok;
}

static void test_print(void **state)
{
    (void)state;
    const char *path = scratch_path("stdout.txt");
    assert_true(print_into(path, "aoview 0.1.0\n"));
    char *text = read_file(path, NULL);
    assert_string_equal(text, "aoview 0.1.0\n");
    free(text);
    if (access("/dev/full", W_OK) != 0)
        skip();
    stderr_begin();
    bool ok = print_into("/dev/full", "usage\n");
    assert_string_equal(stderr_end(), "aoview: cannot write to standard output: No space left on device\n");
    assert_false(ok);
}

/* PFM and EXR hold the pixels bit for bit; a PNG is drawn (its signature), and the difference view
 * from a reference is another PNG. */
static void test_write_formats(void **state)
{
    (void)state;
    struct ao_frame frame = frame_of(1);
    stderr_begin();
    assert_true(ao_app_write_output(scratch_path("out.pfm"), &frame, "scene", 1, NULL));
    assert_true(ao_app_write_output(scratch_path("out.exr"), &frame, "scene", 1, NULL));
    assert_string_equal(stderr_end(), "");
    assert_linear_frame(scratch_path("out.pfm"));
    assert_linear_frame(scratch_path("out.exr"));

    float reference[WIDTH * HEIGHT * 3] = {0};
    assert_true(ao_app_write_output(scratch_path("out.png"), &frame, "scene", 1, NULL));
    assert_true(ao_app_write_output(scratch_path("difference.png"), &frame, "scene", 1, reference));
    size_t png_size, heat_size;
    char *png = read_file(scratch_path("out.png"), &png_size);
    char *heat = read_file(scratch_path("difference.png"), &heat_size);
    assert_non_null(png);
    assert_non_null(heat);
    assert_memory_equal(png, "\x89PNG\r\n\x1a\n", 8);
    assert_memory_equal(heat, "\x89PNG\r\n\x1a\n", 8);
    assert_true(png_size != heat_size || memcmp(png, heat, png_size) != 0);
    free(png);
    free(heat);
}

/* A folder that is not there: refused, one line naming the path, no file. */
static void test_write_refused(void **state)
{
    (void)state;
    struct ao_frame frame = frame_of(1);
    const char *path = scratch_path("no-such-folder/out.pfm");
    stderr_begin();
    bool ok = ao_app_write_output(path, &frame, "scene", 1, NULL);
    const char *said = stderr_end();
    assert_false(ok);
    assert_non_null(strstr(said, path));
    assert_int_equal(strchr(said, '\n') - said, strlen(said) - 1);   /* one line */
    assert_int_not_equal(access(path, F_OK), 0);
}

/* No display: one line saying where the run goes, or the refusal of an -o that cannot be written. */
static void test_go_headless(void **state)
{
    (void)state;
    struct ao_options opts = {.output = scratch_path("headless.pfm")};
    char expected[8192];
    snprintf(expected, sizeof expected, "aoview: no display available; rendering headless to %s\n", opts.output);
    stderr_begin();
    assert_true(ao_app_go_headless(&opts));
    assert_string_equal(stderr_end(), expected);

    opts.output = scratch_path("no-such-folder/headless.pfm");
    stderr_begin();
    bool ok = ao_app_go_headless(&opts);
    const char *said = stderr_end();
    assert_false(ok);
    assert_non_null(strstr(said, opts.output));
    assert_null(strstr(said, "rendering headless"));
}

/* Interrupted before the first pass ended: one line, the status given, nothing written. */
static void test_write_nothing_yet(void **state)
{
    (void)state;
    struct ao_app app = {0};
    struct ao_options opts = {.output = scratch_path("early.pfm")};
    struct ao_frame frame = frame_of(0);
    stderr_begin();
    int status = ao_app_write(&app, &opts, &frame, "interrupted by SIGINT", true, 130);
    assert_string_equal(stderr_end(), "aoview: interrupted by SIGINT before the first pass ended: nothing written\n");
    assert_int_equal(status, 130);
    assert_int_not_equal(access(opts.output, F_OK), 0);
}

/* Interrupted after a pass, the progress bar on screen: its line ended, what stopped the run and
 * at how many spp, the last --stats row, the output written and said; the signal watcher told that
 * the write began and how many had ended before it. */
static void test_write_interrupted(void **state)
{
    (void)state;
    struct ao_app app = {0};
    struct ao_options opts = {.output = scratch_path("late.pfm")};
    struct ao_frame frame = frame_of(2);
    const char *stats = scratch_path("late.csv");
    assert_true(ao_app_open_stats(&app.stats, stats, false, false));
    app.reporter.stats = &app.stats;
    app.reporter.drawn_at = 1.0;
    unsigned before = ao_image_written();
    char expected[8192];
    snprintf(expected, sizeof expected,
             "\naoview: interrupted by SIGTERM at 16 spp\naoview: wrote %s (16 spp, 0.50 s, 0.0 Mrays/s)\n",
             opts.output);
    stderr_begin();
    int status = ao_app_write(&app, &opts, &frame, "interrupted by SIGTERM", true, 143);
    assert_string_equal(stderr_end(), expected);
    assert_int_equal(status, 143);
    assert_true(atomic_load(&app.interrupt.writing));
    assert_int_equal(atomic_load(&app.interrupt.written_before), before);
    assert_int_equal(ao_image_written(), before + 1);
    assert_linear_frame(opts.output);
    assert_true(ao_app_close_stats(&app.stats));
    char *rows = read_file(stats, NULL);
    assert_non_null(strstr(rows, "\n2,16,0.500000,1000,3000,0.008,16.000,nan,nan\n"));
    free(rows);
}

/* A finished run: quiet, nothing said; no frame, or a write that fails: AO_EXIT_RUNTIME. */
static void test_write_finished(void **state)
{
    (void)state;
    struct ao_app app = {0};
    struct ao_options opts = {.output = scratch_path("done.pfm"), .quiet = true};
    struct ao_frame frame = frame_of(8);
    stderr_begin();
    assert_int_equal(ao_app_write(&app, &opts, &frame, NULL, false, 0), 0);
    assert_int_equal(ao_app_write(&app, &opts, NULL, NULL, false, 0), AO_EXIT_RUNTIME);
    assert_string_equal(stderr_end(), "");
    assert_linear_frame(opts.output);

    opts.output = scratch_path("no-such-folder/done.pfm");
    stderr_begin();
    int status = ao_app_write(&app, &opts, &frame, NULL, false, 0);
    assert_non_null(strstr(stderr_end(), opts.output));
    assert_int_equal(status, AO_EXIT_RUNTIME);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_print),
        cmocka_unit_test(test_write_formats),
        cmocka_unit_test(test_write_refused),
        cmocka_unit_test(test_go_headless),
        cmocka_unit_test(test_write_nothing_yet),
        cmocka_unit_test(test_write_interrupted),
        cmocka_unit_test(test_write_finished),
    };
    return cmocka_run_group_tests(tests, app_fixture_setup, app_fixture_teardown);
}
