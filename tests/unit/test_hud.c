/* hud.c's status text: every figure it shows is measured; a preview says so and shows none of the
 * average's. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "hud.h"

/* The facts of a run's first frame, a preview (render.c's start_run): nothing measured yet. */
static struct ao_frame_info preview_info(void)
{
    return (struct ao_frame_info){.restarts = 3, .target_spp = 256, .spp_left = NAN, .error = NAN,
                                  .converged = NAN, .rmse = NAN, .sampling = AO_SAMPLING_COSINE, .aa = true};
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
    assert_non_null(strstr(text, "bunny.scene | 640x480 preview, 4 px cells | cosine | AA on | spp 0 of 256"));
    const char *none[] = {"error", "RMSE", "left", "Mrays", "converged", "mean", "0.3s"};
    assert_absent(text, none, sizeof none / sizeof none[0]);
}

static void test_the_first_passes_say_what_is_not_known(void **state)
{
    (void)state;
    struct ao_frame_info info = preview_info();
    info.pass = 1;
    info.spp = info.spppp = 1;
    info.mean_spp = 1.0;
    info.spp_left = 255.0;
    info.converged = 0.0;
    info.seconds = 0.5;
    info.eye_rays = 1000000;
    info.shadow_rays = 1000000;
    info.rmse = 0.25;
    struct ao_hud_status s = {.scene = "bunny.scene", .info = info, .width = 640, .height = 480, .block = 1,
                              .seconds = 0.5, .seconds_left = NAN, .adaptive = true};
    char text[512];
    ao_hud_format(&s, " | ", "-", text, sizeof text);
    assert_non_null(strstr(text, "| spp 1 of 256 | error - | 0.5s | 4.0 Mrays/s | pass 1 | auto 1 spp/pass | "
                                 "adaptive: 0 % converged | mean 1 spp | RMSE 0.25"));
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_preview_shows_no_figure),
        cmocka_unit_test(test_the_first_passes_say_what_is_not_known),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
