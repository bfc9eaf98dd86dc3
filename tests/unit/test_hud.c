/* hud.c's status text: every figure it shows is measured and true of the view; a preview says so
 * and shows none of the average's; the normals view none of the AO estimate's. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "hud.h"
#include "unit_main.h"

/* The facts of a run's first frame, a preview (render.c's start_run): nothing measured yet. */
static struct ao_frame_info preview_info(void)
{
    return (struct ao_frame_info){.restarts = 3, .target_spp = 256, .pixels = 640 * 480, .error = NAN,
                                  .converged = NAN, .rmse = NAN, .sampling = AO_SAMPLING_COSINE, .aa = true};
}

/* The facts of pass `pass` of that run, with mean_spp samples a pixel after `seconds`. */
static struct ao_frame_info pass_info(uint32_t pass, double mean_spp, double seconds)
{
    struct ao_frame_info info = preview_info();
    info.pass = pass;
    info.spp = (uint32_t)ceil(mean_spp);
    info.mean_spp = mean_spp;
    info.seconds = seconds;
    return info;
}

static void assert_absent(const char *text, const char *const *words, size_t count)
{
    for (size_t k = 0; k < count; k++)
        if (strstr(text, words[k]))
            fail_msg("\"%s\" in \"%s\"", words[k], text);
}

static void test_a_preview_shows_no_figure(void **state)
{
    (void)state;
    struct ao_hud_status s = {.scene = "bunny.scene", .info = preview_info(), .width = 640, .height = 480,
                              .block = 4, .seconds = 0.3, .seconds_left = NAN, .adaptive = true};
    char text[512];
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "bunny.scene | 640x480 preview, 4 px cells | cosine | AA on | pass 0"));
    const char *none[] = {"error", "RMSE", "left", "Mrays", "converged", "mean", "0.3s", "spp 0", "up to"};
    assert_absent(text, none, sizeof none / sizeof none[0]);
}

static void test_the_first_passes_say_what_is_not_known(void **state)
{
    (void)state;
    struct ao_frame_info info = preview_info();
    info.pass = 1;
    info.spp = info.spppp = 1;
    info.mean_spp = 1.0;
    info.converged = 0.0;
    info.seconds = 0.5;
    info.eye_rays = 1000000;
    info.shadow_rays = 1000000;
    info.rmse = 0.25;
    struct ao_hud_status s = {.scene = "bunny.scene", .info = info, .width = 640, .height = 480, .block = 1,
                              .seconds = 0.5, .seconds_left = NAN, .adaptive = true};
    char text[512];
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "| mean 1 spp, up to 256 | error - | 0.5s | 4.0 Mrays/s | pass 1 | "
                                 "auto 1 spp/pass | adaptive: 0 % converged | RMSE 0.25"));
    const char *none[] = {"left", "nan", "inf"};
    assert_absent(text, none, sizeof none / sizeof none[0]);
    /* The second pass estimates the error; a rate gives the time left. */
    s.info.error = 0.0123;
    s.seconds_left = 2.0;
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "| error 1.23 % | 0.5s | ~2.0 s left | 4.0 Mrays/s |"));
    /* A preview kept on screen over the average: the run's progress, none of the average's figures. */
    s.block = 4;
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "| 640x480 preview, 4 px cells |"));
    assert_non_null(strstr(text, "| 0.5s | ~2.0 s left | 4.0 Mrays/s | pass 1 |"));
    const char *average[] = {"error", "RMSE", "converged", "mean"};
    assert_absent(text, average, sizeof average / sizeof average[0]);
}

/* The samples: the mean rounded down, so that "256, up to 256" comes only once every pixel has 256
 * (the last pass of a run without adaptive sampling); adaptive sampling ends its runs sooner. */
static void test_the_samples_are_the_mean(void **state)
{
    (void)state;
    struct ao_hud_status s = {.scene = "bunny.scene", .info = pass_info(30, 255.999, 2.0), .width = 640,
                              .height = 480, .block = 1, .seconds = 2.0, .seconds_left = 0.1};
    char text[512];
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "| mean 255 spp, up to 256 |"));
    s.info.mean_spp = 256.0;
    s.info.done = true;
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "| mean 256 spp, up to 256 |"));
    assert_non_null(strstr(text, "| 2.0s | finished |"));
    assert_null(strstr(text, "left"));
}

/* The normals view: no AO error, time left, rate or RMSE against an AO reference. */
static void test_the_normals_view_shows_no_ao_figure(void **state)
{
    (void)state;
    struct ao_hud_status s = {.scene = "bunny.scene", .info = pass_info(5, 33.0, 0.25), .width = 640,
                              .height = 480, .block = 1, .seconds = 0.25, .seconds_left = 1.5, .adaptive = true};
    s.info.spppp = 8;
    s.info.error = 0.0042;
    s.info.converged = 0.5;
    s.info.eye_rays = 1000000;
    s.info.rmse = 0.25;
    s.info.output = AO_OUTPUT_NORMALS;
    char text[512];
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "| AA on | normals | mean 33 spp, up to 256 | 0.2s | pass 5 | auto 8 spp/pass | "
                                 "adaptive: 50 % converged"));
    const char *none[] = {"error", "RMSE", "left", "Mrays"};
    assert_absent(text, none, sizeof none / sizeof none[0]);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_a_preview_shows_no_figure),
               cmocka_unit_test(test_the_first_passes_say_what_is_not_known),
               cmocka_unit_test(test_the_samples_are_the_mean),
               cmocka_unit_test(test_the_normals_view_shows_no_ao_figure))
