/* progress.c: the time left from the pass rate, a time limit and the error trend; its text. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "progress.h"

static void test_rate_toward_spp(void **state)
{
    (void)state;
    struct ao_progress p = {0};
    struct ao_frame_info info = {.spp = 10, .target_spp = 100, .seconds = 1.0, .error = NAN};
    assert_true(isnan(ao_progress_left(&p, &info)));   /* nothing fed yet */
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 9.0, 1e-9);   /* 90 spp at 10 spp/s */
    /* The next pass ran at 20 spp/s: the rate moves half way, to 15. */
    info.spp = 20;
    info.seconds = 1.5;
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 80.0 / 15.0, 1e-9);
    info.done = true;
    assert_true(ao_progress_left(&p, &info) == 0.0);
    /* A restart starts over from its own first frame. */
    info = (struct ao_frame_info){.restarts = 1, .spp = 50, .target_spp = 100, .seconds = 0.5, .error = NAN};
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 0.5, 1e-9);
}

static void test_time_limit_and_error_trend(void **state)
{
    (void)state;
    struct ao_progress p = {0};
    struct ao_frame_info info = {.spp = 10, .target_spp = 1000, .seconds = 2.0, .error = NAN, .time_limit = 3.0};
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 1.0, 1e-9);   /* the limit comes first */
    info.seconds = 4.0;
    assert_true(ao_progress_left(&p, &info) == 0.0);               /* past it: the pass ends it */
    /* Error 2 % toward 1 %: four times the samples, three times the time spent so far. */
    info = (struct ao_frame_info){.spp = 10, .target_spp = 1000, .seconds = 2.0, .error = 0.02,
                                  .target_error = 0.01};
    struct ao_progress q = {0};
    ao_progress_add(&q, &info);
    assert_float_equal(ao_progress_left(&q, &info), 6.0, 1e-9);
    info.error = 0.005;
    assert_true(ao_progress_left(&q, &info) == 0.0);
}

static void test_format(void **state)
{
    (void)state;
    char text[32];
    ao_progress_format(4.54, text, sizeof text);
    assert_string_equal(text, "~4.5 s left");
    ao_progress_format(123.4, text, sizeof text);
    assert_string_equal(text, "~123 s left");
    ao_progress_format(NAN, text, sizeof text);
    assert_string_equal(text, "");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rate_toward_spp),
        cmocka_unit_test(test_time_limit_and_error_trend),
        cmocka_unit_test(test_format),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
