/* The render thread: determinism across thread counts, pass arithmetic, restarts, frames. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <time.h>
#include <stdlib.h>
#include <string.h>

#include "ao.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

static const char SCENE[] = "camera eye 0 1.5 4 target 0 0.5 0 fov 40\n"
                            "background 0.2 0.3 0.4\n"
                            "quad corner -5 0 -5 edge1 0 0 10 edge2 10 0 0 albedo 0.6\n"
                            "sphere center 0 0.5 0 radius 0.5 albedo 0.9 0.5 0.2\n"
                            "sphere center 1 0.25 0.5 radius 0.25\n";

struct counter {
    int calls;
    uint32_t last_pass, last_spp;
    uint32_t spppp[8];       /* of the first eight passes */
    struct ao_frame_info passes[2];   /* the first two passes' facts */
    int previews;
    int calls_before_preview;   /* passes published before the first preview; -1: no preview */
    struct ao_frame_info preview;   /* the first preview's facts */
};

static void count_preview(const struct ao_frame_info *info, void *user)
{
    struct counter *c = user;
    if (c->previews++ == 0) {
        c->calls_before_preview = c->calls;
        c->preview = *info;
    }
}

static void count_pass(const struct ao_frame_info *info, void *user)
{
    struct counter *c = user;
    if (c->calls < 2)
        c->passes[c->calls] = *info;
    if (c->calls < 8)
        c->spppp[c->calls] = info->spppp;
    c->calls++;
    c->last_pass = info->pass;
    c->last_spp = info->spp;
}

/* Renders scene_text with config (scene, tracer and callback filled in here) and settings (its
 * camera the scene's) to completion; returns a malloc'd copy of the final frame. */
static float *render_scene(const char *scene_text, struct ao_render_config config, struct ao_settings settings,
                           struct ao_frame_info *info, struct counter *counter)
{
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, scene_text, "render.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    config.scene = &scene;
    config.tracer = tracer;
    config.ao_distance = INFINITY;
    config.on_pass = count_pass;
    config.on_preview = count_preview;
    config.user = counter;
    settings.camera = scene.camera;
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_non_null(r);
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_non_null(frame);
    assert_null(ao_render_take_frame(r));
    size_t bytes = 3 * sizeof(float) * (size_t)settings.width * (size_t)settings.height;
    float *copy = malloc(bytes);
    memcpy(copy, frame->rgb, bytes);
    *info = frame->info;
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return copy;
}

/* Renders SCENE at 37x29, seed 5, to completion and returns a malloc'd copy of the final frame. */
static float *render_with(int threads, uint32_t spp, int spppp, bool aa, enum ao_sampling sampling,
                          enum ao_sequence sequence, struct ao_frame_info *info, struct counter *counter)
{
    struct ao_render_config config = {.threads = threads, .seed = 5,
                                      .target_spp = spp, .sequence = sequence};
    struct ao_settings settings = {.width = 37, .height = 29, .sampling = sampling, .aa = aa, .spppp = spppp};
    return render_scene(SCENE, config, settings, info, counter);
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
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    struct counter counter = {0};
    struct ao_render_config config = {.scene = &scene, .tracer = tracer,
                                      .threads = 2, .seed = 1, .target_spp = 8,
                                      .ao_distance = INFINITY, .on_pass = count_pass, .user = &counter};
    struct ao_settings settings = {.width = 16, .height = 16, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 8,
                                   .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_true(ao_render_wait(r));
    /* A sampling change restarts; the next finished frame says so and carries the new mode. */
    settings.sampling = AO_SAMPLING_UNIFORM;
    assert_true(ao_render_set_settings(r, &settings));
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_non_null(frame);
    assert_int_equal(frame->info.restarts, 1);
    assert_int_equal(frame->info.sampling, AO_SAMPLING_UNIFORM);
    assert_int_equal(frame->info.spp, 8);
    /* Changing spppp alone does not restart. */
    settings.spppp = 2;
    assert_false(ao_render_set_settings(r, &settings));
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
    /* The normals view and flat shading are other estimates: each restarts. */
    settings.output = AO_OUTPUT_NORMALS;
    assert_true(ao_render_set_settings(r, &settings));
    assert_true(ao_render_wait(r));
    frame = ao_render_take_frame(r);
    assert_int_equal(frame->info.restarts, 3);
    assert_int_equal(frame->info.output, AO_OUTPUT_NORMALS);
    settings.shading = AO_SHADING_FLAT;
    ao_render_set_settings(r, &settings);
    assert_true(ao_render_wait(r));
    frame = ao_render_take_frame(r);
    assert_int_equal(frame->info.restarts, 4);
    assert_int_equal(frame->info.shading, AO_SHADING_FLAT);
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

static void test_stop_ends_an_unfinished_render(void **state)
{
    (void)state;
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    struct ao_render_config config = {.scene = &scene, .tracer = tracer,
                                      .threads = 2, .seed = 1, .target_spp = 1u << 30,
                                      .ao_distance = INFINITY};
    struct ao_settings settings = {.width = 64, .height = 64, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 1,
                                   .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    ao_render_stop(r);
    assert_false(ao_render_wait(r));
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

/* Adaptive sampling with auto passes, at 128x96 with the given threads and sequence. */
static float *render_adaptive(int threads, enum ao_sequence sequence, struct ao_frame_info *info)
{
    struct counter counter = {0};
    struct ao_render_config config = {.threads = threads, .seed = 3,
                                      .target_spp = 200, .sequence = sequence};
    struct ao_settings settings = {.width = 128, .height = 96, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 0,
                                   .adaptive = true};
    return render_scene(SCENE, config, settings, info, &counter);
}

static void test_adaptive_auto_image_does_not_depend_on_threads(void **state)
{
    (void)state;
    for (int s = 0; s < 2; s++) {
        enum ao_sequence sequence = s ? AO_SEQUENCE_SOBOL : AO_SEQUENCE_RANDOM;
        struct ao_frame_info a, b;
        float *one = render_adaptive(1, sequence, &a);
        float *three = render_adaptive(3, sequence, &b);
        assert_memory_equal(one, three, 3 * sizeof(float) * 128 * 96);
        assert_int_equal(a.pass, b.pass);
        assert_true(a.mean_spp == b.mean_spp);
        /* Adaptive sampling left some tiles short of the maximum. */
        print_message("mean spp %g passes %u\n", a.mean_spp, a.pass);
        assert_true(a.mean_spp < 200.0);
        free(one);
        free(three);
    }
}

/* A consumer that takes every frame as it is published (from the render thread's pass callback),
 * keeping a copy of the last. */
struct taker {
    _Atomic(struct ao_render *) render;
    int taken;
    float *last;
    size_t bytes;
};

static void take_each(const struct ao_frame_info *info, void *user)
{
    (void)info;
    struct taker *t = user;
    struct ao_render *r = atomic_load(&t->render);
    const struct ao_frame *f = r ? ao_render_take_frame(r) : NULL;
    if (f) {
        memcpy(t->last, f->rgb, t->bytes);
        t->taken++;
    }
}

/* Frames are brought up to date in place, tile by tile, each from the stamp it had: whether the
 * consumer takes every frame (the three frames rotate) or none (the producer's two alternate), the
 * last adaptive frame is the same, bit for bit; a tile left stale in one frame's history would
 * stay so, since adaptive sampling stops changing the tiles that converged. */
static void test_frames_taken_or_not_end_alike(void **state)
{
    (void)state;
    struct ao_frame_info info;
    float *untaken = render_adaptive(2, AO_SEQUENCE_SOBOL, &info);
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    struct taker taker = {.bytes = 3 * sizeof(float) * 128 * 96};
    taker.last = malloc(taker.bytes);
    assert_non_null(taker.last);
    atomic_init(&taker.render, NULL);
    struct ao_render_config config = {.scene = &scene, .tracer = tracer, .threads = 2, .seed = 3, .target_spp = 200,
                                      .sequence = AO_SEQUENCE_SOBOL, .ao_distance = INFINITY,
                                      .on_pass = take_each, .user = &taker};
    struct ao_settings settings = {.width = 128, .height = 96, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .adaptive = true, .paused = true, .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_non_null(r);
    atomic_store(&taker.render, r);
    settings.paused = false;
    assert_false(ao_render_set_settings(r, &settings));   /* a pause lifted: no restart */
    assert_true(ao_render_wait(r));
    print_message("%d frames taken of %u passes\n", taker.taken, info.pass);
    assert_int_equal(taker.taken, (int)info.pass);
    assert_memory_equal(taker.last, untaken, taker.bytes);
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    free(taker.last);
    free(untaken);
}

static void test_auto_passes_start_at_eight_and_double_each_half(void **state)
{
    (void)state;
    struct counter counter = {0};
    struct ao_frame_info info;
    struct ao_render_config config = {.threads = 2, .seed = 5, .target_spp = 100};
    struct ao_settings settings = {.width = 37, .height = 29, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 0};
    free(render_scene(SCENE, config, settings, &info, &counter));
    /* Each half takes 8 and doubles what its sequence has given (37x29 pixels are far below the
     * cap): 8, 8, 8, 8, 16, 16, 32 make 96; the last 4 of 100 come in an 8th pass, whose samples
     * a pass are the schedule's 32 (before the target's cap). */
    static const uint32_t expected[] = {8, 8, 8, 8, 16, 16, 32, 32};
    assert_int_equal(counter.calls, 8);
    assert_memory_equal(counter.spppp, expected, sizeof expected);
    assert_int_equal(info.spp, 100);
    assert_true(info.mean_spp == 100.0);
}

/* A plane that nothing occludes, seen from above: cosine-sampled AO is rho with no variance, with
 * or without AA, so adaptive sampling stops every tile at the minimum (MIN_PASSES = 4 passes of 4
 * samples reach MIN_SPP = 16 in render.c). */
static void test_adaptive_stops_an_open_plane_after_the_minimum(void **state)
{
    (void)state;
    static const char plane[] = "camera eye 0 3 0.1 target 0 0 0 fov 40\n"
                                "quad corner -1e3 0 -1e3 edge1 0 0 2e3 edge2 2e3 0 0 albedo 0.7\n";
    struct counter counter = {0};
    struct ao_frame_info info;
    struct ao_render_config config = {.threads = 2, .seed = 5, .target_spp = 4096};
    struct ao_settings settings = {.width = 40, .height = 30, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 4,
                                   .adaptive = true};
    float *rgb = render_scene(plane, config, settings, &info, &counter);
    assert_true(info.done);
    assert_int_equal(info.pass, 4);
    assert_int_equal(info.spp, 16);
    assert_true(info.error == 0.0);
    assert_true(info.converged == 1.0);
    for (size_t k = 0; k < 3 * 40 * 30; k++)
        assert_true(fabsf(rgb[k] - 0.7f) < 1e-6f);
    free(rgb);
}

/* --target-error stops the run once the estimate reaches it, far short of --spp; the estimate
 * is a relative RMSE, so a few per cent takes some tens of samples here. */
static void test_target_error_stops_the_run(void **state)
{
    (void)state;
    for (int adaptive = 0; adaptive < 2; adaptive++) {
        struct counter counter = {0};
        struct ao_frame_info info;
        struct ao_render_config config = {.threads = 2, .seed = 9,
                                          .target_spp = 1u << 20, .target_error = 0.03};
        struct ao_settings settings = {.width = 64, .height = 48, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                       .spppp = 0, .adaptive = adaptive};
        free(render_scene(SCENE, config, settings, &info, &counter));
        assert_true(info.done);
        assert_true(info.error <= 0.03);
        assert_true(info.spp < 4096);
    }
}

/* --time: a run with a target it would take hours to reach stops at the first pass boundary after
 * the limit (passes of one sample at 64x48 take milliseconds; 5 s allows a loaded machine). */
static void test_time_limit_stops_the_run(void **state)
{
    (void)state;
    struct counter counter = {0};
    struct ao_frame_info info;
    struct ao_render_config config = {.threads = 2, .seed = 9,
                                      .target_spp = 1u << 30, .time_limit = 0.3};
    struct ao_settings settings = {.width = 64, .height = 48, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 1};
    free(render_scene(SCENE, config, settings, &info, &counter));
    assert_true(info.done);
    assert_true(info.time_limit == 0.3);
    assert_true(info.seconds >= 0.3 && info.seconds < 5.0);
    assert_true(info.spp < config.target_spp);
    assert_int_equal(counter.last_spp, info.spp);
}

/* A 2x2 quad (front side up) seen from straight above, over a coloured background. */
static const char QUAD_FROM_ABOVE[] = "camera eye 0 5 0 target 0 0 0 up 0 0 -1 fov 40\n"
                                      "background 0.2 0.3 0.4\n"
                                      "quad corner -1 0 -1 edge1 0 0 2 edge2 2 0 0 albedo 0.6\n";

/* The normals view: (n + 1) / 2 of the upward normal, (0.5, 1, 0.5), wherever the quad fills the
 * pixel (here the middle; it spans 2 / (2 * 5 tan 20 deg) = 55 % of the image), and black, not the
 * background, where the eye rays miss (the corners), with AA on and any number of passes. */
static void test_normals_view_of_a_quad_from_above(void **state)
{
    (void)state;
    struct counter counter = {0};
    struct ao_frame_info info;
    struct ao_render_config config = {.threads = 2, .seed = 4, .target_spp = 8};
    struct ao_settings settings = {.width = 32, .height = 32, .sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = 2,
                                   .output = AO_OUTPUT_NORMALS};
    float *rgb = render_scene(QUAD_FROM_ABOVE, config, settings, &info, &counter);
    assert_int_equal(info.output, AO_OUTPUT_NORMALS);
    assert_int_equal(info.shadow_rays, 0); /* no occlusion rays for normals */
    for (int j = 12; j < 20; j++)
        for (int i = 12; i < 20; i++) {
            const float *p = rgb + 3 * (j * 32 + i);
            assert_float_equal(p[0], 0.5f, 1e-6f);
            assert_float_equal(p[1], 1.0f, 1e-6f);
            assert_float_equal(p[2], 0.5f, 1e-6f);
        }
    int corners[] = {0, 31, 31 * 32, 32 * 32 - 1};
    for (int k = 0; k < 4; k++)
        for (int c = 0; c < 3; c++)
            assert_true(rgb[3 * corners[k] + c] == 0.0f);
    free(rgb);
}

/* A coarse sphere mesh: the unit octahedron, each vertex's normal its own direction, so that the
 * Phong normal at a point p of a face is p / |p| and the face normal (+-1, +-1, +-1) / sqrt 3. */
static const char OCTAHEDRON[] = "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
                                 "vn 1 0 0\nvn -1 0 0\nvn 0 1 0\nvn 0 -1 0\nvn 0 0 1\nvn 0 0 -1\n"
                                 "f 1//1 3//3 5//5\nf 5//5 3//3 2//2\nf 2//2 3//3 6//6\nf 6//6 3//3 1//1\n"
                                 "f 5//5 4//4 1//1\nf 2//2 4//4 5//5\nf 6//6 4//4 2//2\nf 1//1 4//4 6//6\n";

/* Writes OCTAHEDRON into a fresh directory and the scene text that looks down on it into text. */
static void octahedron_scene(char *dir, size_t dir_size, char *text, size_t text_size)
{
    snprintf(dir, dir_size, "/tmp/aoview-render-XXXXXX");
    assert_non_null(mkdtemp(dir));
    char path[128];
    snprintf(path, sizeof path, "%s/octahedron.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_true(fputs(OCTAHEDRON, f) >= 0);
    assert_int_equal(fclose(f), 0);
    snprintf(text, text_size, "camera eye 0 4 0 target 0 0 0 up 0 0 -1 fov 40\nmesh %s\n", path);
}

static void remove_octahedron(const char *dir)
{
    char path[128];
    snprintf(path, sizeof path, "%s/octahedron.obj", dir);
    assert_int_equal(remove(path), 0);
    assert_int_equal(remove(dir), 0);
}

/* Flat shading gives the face normal, Phong the interpolated one, at a known point; spheres keep
 * their exact normal either way. */
static void test_flat_is_the_face_normal_and_phong_interpolates(void **state)
{
    (void)state;
    char dir[64], text[256];
    octahedron_scene(dir, sizeof dir, text, sizeof text);
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, text, "octahedron.scene", NULL));
    remove_octahedron(dir);
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    ao_tracer_thread_init();
    /* Straight down onto (0.3, 0.5, 0.2) of the face x + y + z = 1. */
    struct ao_vec3 org = ao_vec3_make(0.3f, 5.0f, 0.2f), dir_down = ao_vec3_make(0.0f, -1.0f, 0.0f);
    struct ao_packet eye = {.count = 1, .org_x = {org.x}, .org_y = {org.y}, .org_z = {org.z},
                            .dir_x = {0.0f}, .dir_y = {-1.0f}, .dir_z = {0.0f}, .tfar = {INFINITY}};
    struct ao_hit hit;
    ao_tracer_intersect(tracer, &eye, &hit);
    assert_true(hit.t < INFINITY && !hit.sphere);
    struct ao_surface flat, phong;
    ao_surface_from_hit(&scene, AO_SHADING_FLAT, org, dir_down, &hit, &flat);
    ao_surface_from_hit(&scene, AO_SHADING_PHONG, org, dir_down, &hit, &phong);
    float third = 1.0f / sqrtf(3.0f), p = sqrtf(0.3f * 0.3f + 0.5f * 0.5f + 0.2f * 0.2f);
    assert_float_equal(flat.ns.x, third, 1e-5f);
    assert_float_equal(flat.ns.y, third, 1e-5f);
    assert_float_equal(flat.ns.z, third, 1e-5f);
    assert_true(flat.ns.x == flat.ng.x && flat.ns.y == flat.ng.y && flat.ns.z == flat.ng.z);
    assert_float_equal(phong.ns.x, 0.3f / p, 1e-5f);
    assert_float_equal(phong.ns.y, 0.5f / p, 1e-5f);
    assert_float_equal(phong.ns.z, 0.2f / p, 1e-5f);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

/* The normals view of the octahedron from above without AA: flat, every pixel is black (a miss) or
 * one of the four upper faces' colours; Phong, most of the hit pixels are neither, and the two
 * images differ by more than 0.02 on average over the hit pixels (the normals differ by up to
 * 55 degrees, and the colours by 0.1 or more over most of the faces). */
static void test_flat_and_phong_normals_views_differ(void **state)
{
    (void)state;
    char dir[64], text[256];
    octahedron_scene(dir, sizeof dir, text, sizeof text);
    float *image[2];
    for (int shading = 0; shading < 2; shading++) {
        struct counter counter = {0};
        struct ao_frame_info info;
        struct ao_render_config config = {.threads = 2, .seed = 4, .target_spp = 1};
        struct ao_settings settings = {.width = 24, .height = 24, .sampling = AO_SAMPLING_COSINE, .aa = false,
                                       .spppp = 1,
                                       .output = AO_OUTPUT_NORMALS, .shading = (enum ao_shading)shading};
        image[shading] = render_scene(text, config, settings, &info, &counter);
    }
    remove_octahedron(dir);
    const float *phong = image[AO_SHADING_PHONG], *flat = image[AO_SHADING_FLAT];
    float lo = 0.5f - 0.5f / sqrtf(3.0f), hi = 0.5f + 0.5f / sqrtf(3.0f), top = hi;
    int hits = 0, off_face = 0;
    double difference = 0.0;
    for (int k = 0; k < 24 * 24; k++) {
        const float *f = flat + 3 * k, *g = phong + 3 * k;
        if (f[0] == 0.0f && f[1] == 0.0f && f[2] == 0.0f) {
            assert_true(g[0] == 0.0f && g[1] == 0.0f && g[2] == 0.0f);
            continue;
        }
        hits++;
        assert_float_equal(f[1], top, 1e-5f);
        assert_true(fabsf(f[0] - lo) < 1e-5f || fabsf(f[0] - hi) < 1e-5f);
        assert_true(fabsf(f[2] - lo) < 1e-5f || fabsf(f[2] - hi) < 1e-5f);
        off_face += fabsf(g[1] - top) > 1e-3f;
        difference += (fabs((double)f[0] - g[0]) + fabs((double)f[1] - g[1]) + fabs((double)f[2] - g[2])) / 3.0;
    }
    assert_true(hits > 100);
    assert_true(off_face > hits / 2);
    assert_true(difference / hits > 0.02);
    free(image[0]);
    free(image[1]);
}

/* A size change restarts at the new size: the frame after it is the image a renderer started at
 * that size makes (max |d| = 0), and the RMSE is taken only while the reference has its size. */
static void test_resize_restarts_at_the_new_size(void **state)
{
    (void)state;
    struct counter counter = {0};
    struct ao_frame_info info;
    struct ao_render_config config = {.threads = 2, .seed = 5, .target_spp = 8};
    struct ao_settings settings = {.width = 50, .height = 20, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = 4};
    float *fresh = render_scene(SCENE, config, settings, &info, &counter);

    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    config = (struct ao_render_config){.scene = &scene, .tracer = tracer, .threads = 2, .seed = 5, .target_spp = 8,
                                       .ao_distance = INFINITY, .reference = fresh, .reference_width = 50,
                                       .reference_height = 20};
    settings.width = 37;
    settings.height = 29;
    settings.camera = scene.camera;
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_int_equal(frame->width, 37);
    assert_true(isnan(frame->info.rmse));
    settings.width = 50;
    settings.height = 20;
    assert_true(ao_render_set_settings(r, &settings));
    assert_true(ao_render_wait(r));
    frame = ao_render_take_frame(r);
    assert_int_equal(frame->width, 50);
    assert_int_equal(frame->height, 20);
    assert_int_equal(frame->block, 1);
    assert_int_equal(frame->info.restarts, 1);
    assert_int_equal(frame->tiles_x * frame->tiles_y, 4 * 2);
    assert_memory_equal(frame->rgb, fresh, 3 * sizeof(float) * 50 * 20);
    assert_true(frame->info.rmse == 0.0);
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    free(fresh);
}

/* The coarse view's ray through a cell's position is the image's through the same point of the
 * image (block times the cell position), within a few float roundings. */
static void test_coarse_view_rays_are_the_image_rays(void **state)
{
    (void)state;
    struct ao_camera camera = {.eye = {0.3f, 1.5f, 4.0f}, .target = {0.0f, 0.5f, 0.0f}, .up = {0, 1, 0}, .fov = 40};
    struct ao_view full, coarse;
    const int width = 1001, height = 601, block = 16;
    assert_true(ao_camera_view(&camera, width, height, &full));
    assert_true(ao_camera_view_coarse(&camera, width, height, block, &coarse));
    assert_int_equal(coarse.width, 63);
    assert_int_equal(coarse.height, 38);
    const float cells[][2] = {{0, 0}, {0.5f, 0.5f}, {62.5f, 37.5f}, {63, 38}, {31.25f, 7.75f}};
    for (size_t k = 0; k < sizeof cells / sizeof cells[0]; k++) {
        struct ao_vec3 a = ao_camera_ray(&coarse, cells[k][0], cells[k][1]);
        struct ao_vec3 b = ao_camera_ray(&full, block * cells[k][0], block * cells[k][1]);
        assert_true(fabsf(a.x - b.x) < 1e-6f && fabsf(a.y - b.y) < 1e-6f && fabsf(a.z - b.z) < 1e-6f);
    }
}

/* With previews a restart publishes a coarse frame before its first full pass, and the accumulated
 * image is the one without previews (max |d| = 0): they never enter the sums. 256x192 takes one
 * preview, of 4x4-pixel cells. */
static void test_previews_come_first_and_change_nothing(void **state)
{
    (void)state;
    float *image[2];
    struct counter counter[2] = {{.calls_before_preview = -1}, {.calls_before_preview = -1}};
    for (int previews = 0; previews < 2; previews++) {
        struct ao_frame_info info;
        struct ao_render_config config = {.threads = 2, .seed = 7, .target_spp = 64};
        struct ao_settings settings = {.width = 256, .height = 192, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                       .adaptive = true, .previews = previews};
        image[previews] = render_scene(SCENE, config, settings, &info, &counter[previews]);
    }
    assert_int_equal(counter[0].previews, 0);
    assert_int_equal(counter[1].previews, 1);
    assert_int_equal(counter[1].calls_before_preview, 0);
    assert_int_equal(counter[0].calls, counter[1].calls);
    assert_memory_equal(image[0], image[1], 3 * sizeof(float) * 256 * 192);
    free(image[0]);
    free(image[1]);
}

/* A preview's facts are those of a run that has measured nothing yet: no pass, no sample, no ray,
 * no render time, and its error, RMSE (a reference given), converged share and work left not known
 * (NAN), never 0. The first pass measures all but the error, which needs a pass in each half. */
static void test_previews_carry_no_measured_figures(void **state)
{
    (void)state;
    struct counter counter = {.calls_before_preview = -1};
    struct ao_frame_info info;
    static float reference[3 * 256 * 192];
    for (size_t k = 0; k < sizeof reference / sizeof reference[0]; k++)
        reference[k] = 0.5f;
    struct ao_render_config config = {.threads = 2, .seed = 7, .target_spp = 16, .reference = reference,
                                      .reference_width = 256, .reference_height = 192};
    struct ao_settings settings = {.width = 256, .height = 192, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .adaptive = true, .previews = true};
    free(render_scene(SCENE, config, settings, &info, &counter));
    assert_int_equal(counter.previews, 1);
    const struct ao_frame_info *p = &counter.preview;
    assert_int_equal(p->pass, 0);
    assert_int_equal(p->spp, 0);
    assert_int_equal(p->spppp, 0);
    assert_true(p->mean_spp == 0.0 && p->seconds == 0.0 && p->eye_rays == 0 && p->shadow_rays == 0);
    assert_true(isnan(p->error) && isnan(p->rmse) && isnan(p->converged) && p->pixels == 256 * 192);
    assert_false(p->done);
    const struct ao_frame_info *first = &counter.passes[0], *second = &counter.passes[1];
    assert_int_equal(first->pass, 1);
    assert_true(isnan(first->error));
    assert_true(isfinite(first->rmse) && first->rmse > 0.0 && isfinite(first->converged) &&
                first->pixels == 256 * 192 && first->seconds > 0.0);
    assert_true(isfinite(second->error) && second->error > 0.0);
}

/* A tile's error in a frame is NAN until both halves of it have a pass, then measured. */
static void test_tile_errors_are_not_known_before_both_halves(void **state)
{
    (void)state;
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    for (uint32_t spp = 1; spp <= 2; spp++) {
        struct ao_render_config config = {.scene = &scene, .tracer = tracer, .threads = 2, .seed = 3,
                                          .target_spp = spp, .ao_distance = INFINITY};
        struct ao_settings settings = {.width = 64, .height = 48, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                       .spppp = 1, .camera = scene.camera};
        struct ao_render *r = ao_render_create(&config, &settings);
        assert_non_null(r);
        assert_true(ao_render_wait(r));
        const struct ao_frame *f = ao_render_take_frame(r);
        assert_non_null(f);
        assert_int_equal(f->tiles_x * f->tiles_y, 4 * 3);
        int noisy = 0; /* tiles of sky alone are exact: measured as 0 */
        for (int t = 0; t < f->tiles_x * f->tiles_y; t++) {
            assert_true(spp == 1 ? isnan(f->tile_error[t]) : isfinite(f->tile_error[t]) && f->tile_error[t] >= 0.0f);
            noisy += f->tile_error[t] > 0.0f;
        }
        assert_true(spp == 1 || noisy > 0);
        ao_render_destroy(r);
    }
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

struct navigation {
    atomic_int previews, passes;
    atomic_uint_fast64_t restarts;   /* of the last frame */
};

static void navigation_preview(const struct ao_frame_info *info, void *user)
{
    struct navigation *n = user;
    atomic_fetch_add(&n->previews, 1);
    atomic_store(&n->restarts, info->restarts);
}

static void navigation_pass(const struct ao_frame_info *info, void *user)
{
    struct navigation *n = user;
    atomic_fetch_add(&n->passes, 1);
    atomic_store(&n->restarts, info->restarts);
}

/* While the camera is being moved the previews stop at cells of a quarter of the first's (1600x900:
 * cells of 32, 16 and 8 pixels, not 4) and the run waits, tracing nothing; cleared, the run goes on
 * from there, the finest preview and then passes, without a restart. */
static void test_navigation_holds_the_previews(void **state)
{
    (void)state;
    struct ao_scene scene;
    assert_true(ao_scene_parse(&scene, SCENE, "render.scene", NULL));
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    assert_non_null(tracer);
    struct navigation n = {0};
    struct ao_render_config config = {.scene = &scene, .tracer = tracer, .threads = 2, .seed = 1, .target_spp = 4,
                                      .ao_distance = INFINITY, .on_pass = navigation_pass,
                                      .on_preview = navigation_preview, .user = &n};
    struct ao_settings settings = {.width = 1600, .height = 900, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = 1, .previews = true, .navigating = true, .camera = scene.camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_non_null(r);
    const struct timespec tenth = {0, 100000000};
    for (int k = 0; k < 10 && atomic_load(&n.previews) < 3; k++)
        nanosleep(&tenth, NULL);
    nanosleep(&tenth, NULL); /* time for a fourth preview or a pass, were they traced */
    assert_int_equal(atomic_load(&n.previews), 3);
    assert_int_equal(atomic_load(&n.passes), 0);
    uint64_t run = atomic_load(&n.restarts);
    settings.navigating = false;
    assert_false(ao_render_set_settings(r, &settings));
    assert_true(ao_render_wait(r));
    assert_int_equal(atomic_load(&n.previews), 4);
    assert_int_equal(atomic_load(&n.passes), 4);
    assert_true(atomic_load(&n.restarts) == run);
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thread_count_does_not_change_the_image),
        cmocka_unit_test(test_passes_are_ceil_spp_over_spppp),
        cmocka_unit_test(test_frames_taken_or_not_end_alike),
        cmocka_unit_test(test_image_is_finite_and_background_where_missed),
        cmocka_unit_test(test_restart_resets_and_settings_apply),
        cmocka_unit_test(test_stop_ends_an_unfinished_render),
        cmocka_unit_test(test_adaptive_auto_image_does_not_depend_on_threads),
        cmocka_unit_test(test_auto_passes_start_at_eight_and_double_each_half),
        cmocka_unit_test(test_adaptive_stops_an_open_plane_after_the_minimum),
        cmocka_unit_test(test_target_error_stops_the_run),
        cmocka_unit_test(test_time_limit_stops_the_run),
        cmocka_unit_test(test_normals_view_of_a_quad_from_above),
        cmocka_unit_test(test_flat_is_the_face_normal_and_phong_interpolates),
        cmocka_unit_test(test_flat_and_phong_normals_views_differ),
        cmocka_unit_test(test_resize_restarts_at_the_new_size),
        cmocka_unit_test(test_coarse_view_rays_are_the_image_rays),
        cmocka_unit_test(test_previews_come_first_and_change_nothing),
        cmocka_unit_test(test_previews_carry_no_measured_figures),
        cmocka_unit_test(test_tile_errors_are_not_known_before_both_halves),
        cmocka_unit_test(test_navigation_holds_the_previews),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
