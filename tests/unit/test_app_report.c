/* The front ends' reports (app_report.c): the --stats file's header and rows, kept or removed as a
 * run leaves it, a failed write said once; the progress bar's text, redrawn at most every 0.1 s;
 * --compare's equal-time stop on a real renderer; the rate of rays. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app_fixture.h"
#include "app_load.h"
#include "app_report.h"
#include "clock.h"
#include "render.h"

/* A pass's facts: 4000 rays in 0.5 s (0.008 Mrays/s), 4 of 64 spp, error 10 %. */
static struct ao_frame_info pass_info(void)
{
    return (struct ao_frame_info){.pass = 1, .spp = 4, .target_spp = 64, .mean_spp = 4.0, .pixels = 100,
                                  .error = 0.1, .converged = 0.25, .seconds = 0.5, .eye_rays = 1000,
                                  .shadow_rays = 3000, .rmse = NAN, .output = AO_OUTPUT_AO};
}

static void test_mrays_per_second(void **state)
{
    (void)state;
    struct ao_frame_info info = pass_info();
    assert_true(ao_app_mrays_per_second(&info) == 0.008);   /* 8000 / 1e6, rounded once */
    info.eye_rays = 3000000, info.shadow_rays = 1000000, info.seconds = 2.0;
    assert_true(ao_app_mrays_per_second(&info) == 2.0);
    info.seconds = 0.0;   /* no time yet: no rate, not infinity */
    assert_true(ao_app_mrays_per_second(&info) == 0.0);
}

/* The header comes with the first row, then one row per pass; the file was created. */
static void test_stats_rows(void **state)
{
    (void)state;
    const char *path = scratch_path("rows.csv");
    struct ao_stats stats = {0};
    assert_true(ao_app_open_stats(&stats, path, false, false));
    struct ao_reporter rep = {.stats = &stats};
    struct ao_frame_info info = pass_info();
    ao_app_on_pass(&info, &rep);
    info.pass = 2, info.spp = 8, info.mean_spp = 7.5, info.seconds = 1.25, info.error = 0.0625, info.converged = NAN;
    ao_app_on_pass(&info, &rep);
    assert_true(ao_app_close_stats(&stats));
    char *text = read_file(path, NULL);
    assert_non_null(text);
    assert_string_equal(text, "pass,spp,seconds,eye_rays,shadow_rays,mrays_per_s,mean_spp,error,converged\n"
                              "1,4,0.500000,1000,3000,0.008,4.000,0.1,0.2500\n"
                              "2,8,1.250000,1000,3000,0.003,7.500,0.0625,nan\n");
    free(text);
}

/* --compare's side column first, --reference's RMSE after the rate. */
static void test_stats_side_and_rmse(void **state)
{
    (void)state;
    const char *path = scratch_path("sides.csv");
    struct ao_stats stats = {0};
    assert_true(ao_app_open_stats(&stats, path, true, true));
    struct ao_reporter rep = {.stats = &stats, .side = "B"};
    struct ao_frame_info info = pass_info();
    info.rmse = 0.0123;
    ao_app_on_pass(&info, &rep);
    assert_true(ao_app_close_stats(&stats));
    char *text = read_file(path, NULL);
    assert_non_null(text);
    assert_string_equal(text, "side,pass,spp,seconds,eye_rays,shadow_rays,mrays_per_s,rmse,mean_spp,error,converged\n"
                              "B,1,4,0.500000,1000,3000,0.008,0.0123,4.000,0.1,0.2500\n");
    free(text);
}

/* A run that finishes no pass leaves an existing file as it was and removes one it created; the
 * first row empties an existing file (longer than what replaces it: nothing of it is left). */
static void test_stats_without_rows(void **state)
{
    (void)state;
    const char *kept = scratch_path("kept.csv"), *made = scratch_path("made.csv");
    char older[1024];
    memset(older, '#', sizeof older - 16);
    snprintf(older + sizeof older - 16, 16, " older rows\n");
    assert_true(write_text(kept, older));
    struct ao_stats stats = {0};
    assert_true(ao_app_open_stats(&stats, kept, false, false));
    assert_true(ao_app_close_stats(&stats));
    char *text = read_file(kept, NULL);
    assert_string_equal(text, older);
    free(text);

    struct ao_stats fresh = {0};
    assert_true(ao_app_open_stats(&fresh, made, false, false));
    assert_int_equal(access(made, F_OK), 0);
    assert_true(ao_app_close_stats(&fresh));
    assert_int_not_equal(access(made, F_OK), 0);

    struct ao_stats again = {0};
    assert_true(ao_app_open_stats(&again, kept, false, false));
    struct ao_reporter rep = {.stats = &again};
    struct ao_frame_info info = pass_info();
    ao_app_on_pass(&info, &rep);
    assert_true(ao_app_close_stats(&again));
    text = read_file(kept, NULL);
    assert_string_equal(text, "pass,spp,seconds,eye_rays,shadow_rays,mrays_per_s,mean_spp,error,converged\n"
                              "1,4,0.500000,1000,3000,0.008,4.000,0.1,0.2500\n");
    free(text);
}

/* A full disk: one line, however many rows fail, and the close says so. A folder that is not
 * there: refused at the open, with the option and the path. */
static void test_stats_failures(void **state)
{
    (void)state;
    if (access("/dev/full", W_OK) != 0)
        skip();
    struct ao_stats stats = {0};
    assert_true(ao_app_open_stats(&stats, "/dev/full", false, false));
    struct ao_reporter rep = {.stats = &stats};
    struct ao_frame_info info = pass_info();
    stderr_begin();
    ao_app_on_pass(&info, &rep);
    ao_app_on_pass(&info, &rep);
    bool closed = ao_app_close_stats(&stats);
    assert_string_equal(stderr_end(), "/dev/full: write failed\n");
    assert_false(closed);

    struct ao_stats missing = {0};
    const char *path = scratch_path("no-such-folder/stats.csv");
    char expected[8192];
    snprintf(expected, sizeof expected, "--stats: cannot write %s: No such file or directory\n", path);
    stderr_begin();
    bool opened = ao_app_open_stats(&missing, path, false, false);
    assert_string_equal(stderr_end(), expected);
    assert_false(opened);
}

/* A pass of a 1000 x 1000 image at mean_spp of 64 spp, its AO rays one a sample and a quarter of an
 * eye ray a sample (16 + 64 rays a pixel at 64 spp), at 80 Mrays/s. */
static struct ao_frame_info bar_info(double mean_spp)
{
    struct ao_frame_info info = pass_info();
    info.pixels = 1000000, info.spp = (uint32_t)mean_spp, info.mean_spp = mean_spp;
    info.shadow_rays = (uint64_t)(mean_spp * 1e6), info.eye_rays = info.shadow_rays / 4;
    info.seconds = (double)(info.eye_rays + info.shadow_rays) / 80e6;
    return info;
}

/* The bar: filled by the share done, the samples, the error, seconds, time left and rate; the
 * normals view with the seconds only; a newline once done. */
static void test_progress_bar(void **state)
{
    (void)state;
    struct ao_reporter rep = {.progress = true};
    struct ao_frame_info info = bar_info(64.0);
    info.pass = 4, info.done = true, info.error = 0.0123;
    stderr_begin();
    ao_app_on_pass(&info, &rep);
    assert_string_equal(stderr_end(), "\r[##############################] 100 %  mean 64 spp, up to 64  error 1.23 %  "
                                      "1.0 s  ~0.0 s left  80.0 Mrays/s \033[K\n");

    struct ao_reporter normals = {.progress = true};
    info.output = AO_OUTPUT_NORMALS;
    stderr_begin();
    ao_app_on_pass(&info, &normals);
    assert_string_equal(stderr_end(),
                        "\r[##############################] 100 %  mean 64 spp, up to 64  1.0 s \033[K\n");
}

/* Half the samples in half a second at a steady rate: half a second left, half the bar; the error
 * not known yet: "--". A second pass within 0.1 s is not drawn; the pass that ends the run is. */
static void test_progress_bar_redraws(void **state)
{
    (void)state;
    struct ao_reporter rep = {.progress = true};
    struct ao_frame_info info = bar_info(32.0);
    info.error = NAN;
    stderr_begin();
    ao_app_on_pass(&info, &rep);
    assert_string_equal(stderr_end(), "\r[###############               ]  50 %  mean 32 spp, up to 64  error --  "
                                      "0.5 s  ~0.5 s left  80.0 Mrays/s \033[K");
    assert_true(rep.drawn_at > 0.0);

    info = bar_info(40.0);
    info.pass = 2;
    stderr_begin();
    rep.drawn_at = ao_clock_seconds();   /* as if drawn just now */
    ao_app_on_pass(&info, &rep);
    assert_string_equal(stderr_end(), "");

    info = bar_info(44.0);   /* 0.6875 s done, 0.3125 s left */
    info.pass = 3;
    stderr_begin();
    rep.drawn_at -= 0.2;   /* as if drawn 0.2 s ago */
    ao_app_on_pass(&info, &rep);
    assert_string_equal(stderr_end(), "\r[####################          ]  68 %  mean 44 spp, up to 64  error 10.00 %  "
                                      "0.7 s  ~0.3 s left  80.0 Mrays/s \033[K");

    info = bar_info(64.0);
    info.pass = 4, info.done = true;
    stderr_begin();
    ao_app_on_pass(&info, &rep);
    assert_string_equal(stderr_end(), "\r[##############################] 100 %  mean 64 spp, up to 64  error 10.00 %  "
                                      "1.0 s  ~0.0 s left  80.0 Mrays/s \033[K\n");
}

static int notified;
static void count_notify(void)
{
    notified++;
}

/* Each pass and each preview wakes the window; nothing else is reported without stats or a bar. */
static void test_notify(void **state)
{
    (void)state;
    struct ao_reporter rep = {.notify = count_notify};
    struct ao_frame_info info = pass_info();
    notified = 0;
    stderr_begin();
    ao_app_on_pass(&info, &rep);
    ao_app_on_preview(&info, &rep);
    ao_app_on_pass(&info, &rep);
    assert_string_equal(stderr_end(), "");
    assert_int_equal(notified, 3);
    assert_true(rep.pass_end == 0.5);
}

/* Equal time: a side ends at the pass end nearest stop_at, taking the next pass to last as long as
 * the last one: it stops once seconds + (seconds - pass_end) / 2 >= stop_at, and never at the run's
 * last pass. Real renderers, started paused so that none ends before the test says whether it
 * stopped it: the first, not stopped, finishes its 16 spp once unpaused; the second is stopped. */
static void test_equal_time_stop(void **state)
{
    (void)state;
    struct loaded l = {0};
    assert_int_equal(load_line(&l, "aoview --headless --quiet --size 32x24 --spp 16 --threads 1 %s",
                               source_path("assets/scenes/sphere-on-plane.scene")),
                     0);
    struct ao_app *app = &l.app;
    struct ao_render_config config = l.config;
    config.on_pass = NULL;
    config.on_preview = NULL;
    struct ao_settings paused = l.settings;
    paused.paused = true;

    struct ao_reporter rep = {.stop_at = 0.9, .pass_end = 0.2};
    assert_non_null(app->render = ao_render_create(&config, &paused));
    atomic_store(&rep.render, app->render);
    struct ao_frame_info info = pass_info();
    info.seconds = 0.5;   /* 0.5 + 0.15 < 0.9 */
    ao_app_on_pass(&info, &rep);
    info.seconds = 0.7;   /* 0.7 + 0.1 < 0.9 */
    ao_app_on_pass(&info, &rep);
    info.done = true, info.seconds = 1.0;   /* past it, but the run's last pass: nothing to stop */
    ao_app_on_pass(&info, &rep);
    assert_true(rep.pass_end == 1.0);
    ao_render_set_settings(app->render, &l.settings);
    assert_true(ao_render_wait(app->render));   /* finished: not stopped */
    ao_render_destroy(app->render);

    assert_non_null(app->render = ao_render_create(&config, &paused));
    atomic_store(&rep.render, app->render);
    info.done = false, info.seconds = 0.8, rep.pass_end = 0.7;   /* 0.8 + 0.05 < 0.9 */
    ao_app_on_pass(&info, &rep);
    info.seconds = 0.85;   /* 0.85 + 0.025 < 0.9 */
    ao_app_on_pass(&info, &rep);
    info.seconds = 0.9;    /* 0.9 + 0.025 >= 0.9: stop */
    ao_app_on_pass(&info, &rep);
    assert_false(ao_render_wait(app->render));   /* stopped while paused, before any pass */
    assert_int_equal(ao_app_finish(app, 0), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mrays_per_second),
        cmocka_unit_test(test_stats_rows),
        cmocka_unit_test(test_stats_side_and_rmse),
        cmocka_unit_test(test_stats_without_rows),
        cmocka_unit_test(test_stats_failures),
        cmocka_unit_test(test_progress_bar),
        cmocka_unit_test(test_progress_bar_redraws),
        cmocka_unit_test(test_notify),
        cmocka_unit_test(test_equal_time_stop),
    };
    return cmocka_run_group_tests(tests, app_fixture_setup, app_fixture_teardown);
}
