/* The render thread: determinism across thread counts, pass arithmetic, restarts, frames. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "render.h"
#include "scene.h"
#include "tracer.h"

static const char SCENE[] = "camera eye 0 1.5 4 target 0 0.5 0 fov 40\n"
                            "background 0.2 0.3 0.4\n"
                            "quad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0 albedo 0.6\n"
                            "sphere center 0 0.5 0 radius 0.5 albedo 0.9 0.5 0.2\n"
                            "sphere center 1 0.25 0.5 radius 0.25\n";

struct counter {
    int calls;
    uint32_t last_pass, last_spp;
};

static void count_pass(const struct ao_frame_info *info, void *user)
{
    struct counter *c = user;
    c->calls++;
    c->last_pass = info->pass;
    c->last_spp = info->spp;
}

/* Renders SCENE to completion and returns a malloc'd copy of the final frame. */
static float *render_with(int threads, uint32_t spp, int spppp, bool aa, enum ao_sampling sampling,
                          enum ao_sequence sequence, struct ao_frame_info *info, struct counter *counter)
{
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene"));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    struct ao_render_config config = {.scene = &scene, .tracer = tracer, .width = 37, .height = 29,
                                      .threads = threads, .seed = 5, .target_spp = spp,
                                      .ao_distance = INFINITY, .sequence = sequence,
                                      .on_pass = count_pass, .user = counter};
    struct ao_settings settings = {.sampling = sampling, .aa = aa, .spppp = spppp, .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_non_null(r);
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_non_null(frame);
    assert_null(ao_render_take_frame(r));
    size_t bytes = 3 * sizeof(float) * 37 * 29;
    float *copy = malloc(bytes);
    memcpy(copy, frame->rgb, bytes);
    *info = frame->info;
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return copy;
}

/* render_with random numbers. */
static float *render(int threads, uint32_t spp, int spppp, bool aa, enum ao_sampling sampling,
                     struct ao_frame_info *info, struct counter *counter)
{
    return render_with(threads, spp, spppp, aa, sampling, AO_SEQUENCE_RANDOM, info, counter);
}

static void test_thread_count_does_not_change_the_image(void **state)
{
    (void)state;
    struct ao_frame_info a, b, c;
    struct counter ca = {0}, cb = {0}, cc = {0};
    float *one = render(1, 12, 3, true, AO_SAMPLING_UNIFORM, &a, &ca);
    float *two = render(2, 12, 3, true, AO_SAMPLING_UNIFORM, &b, &cb);
    float *five = render(5, 12, 3, true, AO_SAMPLING_UNIFORM, &c, &cc);
    assert_memory_equal(one, two, 3 * sizeof(float) * 37 * 29);
    assert_memory_equal(one, five, 3 * sizeof(float) * 37 * 29);
    assert_int_equal(a.shadow_rays, b.shadow_rays);
    free(one);
    free(two);
    free(five);
    /* Sobol numbers likewise. */
    one = render_with(1, 12, 3, true, AO_SAMPLING_COSINE, AO_SEQUENCE_SOBOL, &a, &ca);
    two = render_with(2, 12, 3, true, AO_SAMPLING_COSINE, AO_SEQUENCE_SOBOL, &b, &cb);
    assert_memory_equal(one, two, 3 * sizeof(float) * 37 * 29);
    free(one);
    free(two);
}

static void test_passes_are_ceil_spp_over_spppp(void **state)
{
    (void)state;
    struct ao_frame_info info;
    struct counter counter = {0};
    free(render(2, 10, 4, false, AO_SAMPLING_COSINE, &info, &counter));
    assert_int_equal(info.pass, 3);
    assert_int_equal(info.spp, 10);
    assert_true(info.done);
    assert_int_equal(counter.calls, 3);
    assert_int_equal(counter.last_spp, 10);
    /* One eye ray per pixel per pass. */
    assert_int_equal(info.eye_rays, 3 * 37 * 29);
    assert_true(isnan(info.rmse));
}

static void test_image_is_finite_and_background_where_missed(void **state)
{
    (void)state;
    struct ao_frame_info info;
    struct counter counter = {0};
    float *rgb = render(2, 4, 4, false, AO_SAMPLING_HEMISPHERE, &info, &counter);
    for (size_t k = 0; k < 3 * 37 * 29; k++)
        assert_true(isfinite(rgb[k]) && rgb[k] >= 0.0f);
    /* The top-left pixel looks over the ground quad into the background. */
    assert_true(rgb[0] == 0.2f && rgb[1] == 0.3f && rgb[2] == 0.4f);
    free(rgb);
}

static void test_restart_resets_and_settings_apply(void **state)
{
    (void)state;
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene"));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    struct counter counter = {0};
    struct ao_render_config config = {.scene = &scene, .tracer = tracer, .width = 16, .height = 16,
                                      .threads = 2, .seed = 1, .target_spp = 8,
                                      .ao_distance = INFINITY, .on_pass = count_pass, .user = &counter};
    struct ao_settings settings = {.sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 8, .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_true(ao_render_wait(r));
    /* A sampling change restarts; the next finished frame says so and carries the new mode. */
    settings.sampling = AO_SAMPLING_UNIFORM;
    ao_render_set_settings(r, &settings);
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_non_null(frame);
    assert_int_equal(frame->info.restarts, 1);
    assert_int_equal(frame->info.sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(frame->info.spp, 8);
    /* Changing spppp alone does not restart. */
    settings.spppp = 2;
    ao_render_set_settings(r, &settings);
    struct ao_settings now;
    ao_render_get_settings(r, &now);
    assert_int_equal(now.spppp, 2);
    assert_true(ao_render_wait(r));
    assert_null(ao_render_take_frame(r));
    ao_render_restart(r);
    assert_true(ao_render_wait(r));
    frame = ao_render_take_frame(r);
    assert_int_equal(frame->info.restarts, 2);
    assert_int_equal(frame->info.pass, 4);
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

static void test_stop_ends_an_unfinished_render(void **state)
{
    (void)state;
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene"));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    struct ao_render_config config = {.scene = &scene, .tracer = tracer, .width = 64, .height = 64,
                                      .threads = 2, .seed = 1, .target_spp = 1u << 30,
                                      .ao_distance = INFINITY};
    struct ao_settings settings = {.sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 1, .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    ao_render_stop(r);
    assert_false(ao_render_wait(r));
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thread_count_does_not_change_the_image),
        cmocka_unit_test(test_passes_are_ceil_spp_over_spppp),
        cmocka_unit_test(test_image_is_finite_and_background_where_missed),
        cmocka_unit_test(test_restart_resets_and_settings_apply),
        cmocka_unit_test(test_stop_ends_an_unfinished_render),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
