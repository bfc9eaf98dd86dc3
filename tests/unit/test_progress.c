/* progress.c: the time left from the work left and the sample rate, a time limit and the error
 * trend; the share done; its text; and the work left of a real adaptive run. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "progress.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

static void test_rate_toward_the_work_left(void **state)
{
    (void)state;
    struct ao_progress p = {0};
    struct ao_frame_info info = {.pass = 1, .spp = 10, .target_spp = 100, .mean_spp = 10, .spp_left = 90,
                                 .seconds = 1.0, .error = NAN};
    assert_true(isnan(ao_progress_left(&p, &info)));   /* nothing fed yet */
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 9.0, 1e-9);   /* 90 spp at 10 spp/s */
    /* The next pass ran at 20 spp/s: the rate moves half way, to 15. */
    info.pass = 2;
    info.spp = info.mean_spp = 20;
    info.spp_left = 80;
    info.seconds = 1.5;
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 80.0 / 15.0, 1e-9);
    /* Adaptive sampling: the busiest pixel at the target, but tiles still short of it. */
    info.pass = 3;
    info.spp = 100;
    info.mean_spp = 35;
    info.spp_left = 30;
    info.seconds = 2.5;
    ao_progress_add(&p, &info);   /* 15 spp/s: the rate stays 15 */
    assert_float_equal(ao_progress_left(&p, &info), 2.0, 1e-9);
    assert_float_equal(ao_progress_share(&p, &info), 2.5 / 4.5, 1e-9);
    info.done = true;
    assert_true(ao_progress_left(&p, &info) == 0.0);
    assert_true(ao_progress_share(&p, &info) == 1.0);
    /* A restart starts over from its own first frame; its preview (pass 0) tells nothing. */
    info = (struct ao_frame_info){.restarts = 1, .target_spp = 100, .spp_left = NAN, .error = NAN};
    ao_progress_add(&p, &info);
    assert_true(isnan(ao_progress_left(&p, &info)));
    assert_true(ao_progress_share(&p, &info) == 0.0);
    info = (struct ao_frame_info){.restarts = 1, .pass = 1, .spp = 50, .target_spp = 100, .mean_spp = 50,
                                  .spp_left = 50, .seconds = 0.5, .error = NAN};
    assert_true(isnan(ao_progress_left(&p, &info)));   /* the old run's rate does not count */
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 0.5, 1e-9);
}

static void test_time_limit_and_error_trend(void **state)
{
    (void)state;
    struct ao_progress p = {0};
    struct ao_frame_info info = {.pass = 1, .spp = 10, .target_spp = 1000, .mean_spp = 10, .spp_left = 990,
                                 .seconds = 2.0, .error = NAN, .time_limit = 3.0};
    ao_progress_add(&p, &info);
    assert_float_equal(ao_progress_left(&p, &info), 1.0, 1e-9);   /* the limit comes first */
    info.seconds = 4.0;
    assert_true(ao_progress_left(&p, &info) == 0.0);               /* past it: the pass ends it */
    assert_true(ao_progress_share(&p, &info) < 1.0);               /* but the run has not ended */
    /* Error 2 % toward 1 %: four times the samples, three times the time spent so far. */
    info = (struct ao_frame_info){.pass = 4, .spp = 10, .target_spp = 1000, .mean_spp = 10, .spp_left = 990,
                                  .seconds = 2.0, .error = 0.02, .target_error = 0.01};
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
    ao_progress_format(0.04, text, sizeof text);
    assert_string_equal(text, "<0.1 s left");
    ao_progress_format(0.0, text, sizeof text);
    assert_string_equal(text, "~0.0 s left");
    ao_progress_format(NAN, text, sizeof text);
    assert_string_equal(text, "");
}

/* Every pass of a run, as on_pass sees them. */
struct passes {
    int count;
    struct ao_frame_info info[4096];
};

static void record(const struct ao_frame_info *info, void *user)
{
    struct passes *p = user;
    if (p->count < 4096)
        p->info[p->count++] = *info;
}

/* An adaptive run of the default estimator: its busiest pixels reach --spp passes before the run
 * ends (the 19-22 % of a run its progress used to spend "done"), but the work left (spp_left),
 * and with it the time left and the share done, reaches 0 (and 1) on the last pass alone. */
static void test_adaptive_work_left_ends_with_the_run(void **state)
{
    (void)state;
    static const char text[] = "camera eye 0 1.5 4 target 0 0.5 0 fov 40\n"
                               "background 1\n"
                               "quad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0 albedo 0.6\n"
                               "sphere center 0 0.5 0 radius 0.5 albedo 0.9 0.5 0.2\n"
                               "sphere center 1 0.25 0.5 radius 0.25\n";
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, text, "progress.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    struct passes *passes = calloc(1, sizeof *passes);
    assert_non_null(passes);
    struct ao_render_config config = {.scene = &scene, .tracer = tracer, .threads = 2, .seed = 1, .target_spp = 256,
                                      .ao_distance = INFINITY, .on_pass = record, .user = passes};
    struct ao_settings settings = {.width = 96, .height = 64, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .adaptive = true, .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_non_null(r);
    assert_true(ao_render_wait(r));
    ao_render_destroy(r);

    int n = passes->count, first_full = -1;
    assert_true(n > 2 && n < 4096);
    struct ao_progress progress = {0};
    for (int k = 0; k < n; k++) {
        const struct ao_frame_info *info = &passes->info[k];
        ao_progress_add(&progress, info);
        if (info->spp == 256 && first_full < 0)
            first_full = k;
        bool last = k == n - 1;
        assert_true(info->done == last);
        if (last) {
            assert_true(info->spp_left == 0.0);
            assert_true(ao_progress_left(&progress, info) == 0.0 && ao_progress_share(&progress, info) == 1.0);
        } else {
            assert_true(info->spp_left > 0.0);
            assert_true(ao_progress_left(&progress, info) > 0.0 && ao_progress_share(&progress, info) < 1.0);
        }
    }
    /* the case this guards: the busiest pixels at the target well before the end */
    assert_true(first_full >= 0 && first_full < n - 2);
    free(passes);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rate_toward_the_work_left),
        cmocka_unit_test(test_time_limit_and_error_trend),
        cmocka_unit_test(test_format),
        cmocka_unit_test(test_adaptive_work_left_ends_with_the_run),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
