/* exact_image.c: the exact AO images of the scenes with a closed form (assets/scenes: an open plane
 * and a closed box, where aoview's cosine estimator is exact and its image must be the same bytes; a
 * sphere over a plane) and the one-line refusal of the others. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "exact_image.h"
#include "options.h"
#include "render.h"
#include "scene_load.h"
#include "tracer.h"
#include "unit_main.h"

enum { W = 40, H = 30 };


struct exact {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    float rgb[3 * W * H];
    struct ao_exact_facts facts;
    char why[256];
};

/* Loads assets/scenes/NAME.scene and renders its exact image at W x H with `grid` (false: why). */
static bool exact_render(struct exact *e, const char *name, float ao_distance, int grid)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/assets/scenes/%s.scene", getenv("AO_SOURCE_ROOT"), name);
    assert_true(ao_scene_load(&e->scene, path, NULL));
    e->tracer = ao_tracer_create(&e->scene);
    assert_non_null(e->tracer);
    ao_tracer_thread_init();
    e->why[0] = '\0';
    return ao_exact_render(&e->scene, e->tracer, ao_distance, W, H, grid, e->rgb, &e->facts, e->why, sizeof e->why);
}

static void exact_finish(struct exact *e)
{
    ao_tracer_destroy(e->tracer);
    ao_scene_finish(&e->scene);
}

/* aoview's image of e's scene at W x H without AA, cosine sampling, from the command line's words
 * (`--spp N ...`) after those. */
static float *aoview_image(const struct exact *e, const char *const *words, int count)
{
    char *argv[16] = {"aoview", "--no-aa", "--size", "40x30", "--sampling", "cosine"}, msg[256];
    assert_true(count <= 9);
    for (int i = 0; i < count; i++)
        argv[6 + i] = (char *)words[i];
    argv[6 + count] = "x.scene";
    struct ao_options opts;
    assert_true(ao_cli_parse(7 + count, argv, &opts, msg, sizeof msg));
    struct ao_render_config config;
    struct ao_settings settings;
    assert_true(ao_options_render(&opts, &e->scene, e->tracer, &config, &settings));
    struct ao_render *r = ao_render_create(&config, &settings);
    assert_non_null(r);
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_non_null(frame);
    float *copy = malloc(sizeof e->rgb);
    assert_non_null(copy);
    memcpy(copy, frame->rgb, sizeof e->rgb);
    ao_render_destroy(r);
    return copy;
}

/* Where the estimator is exact (every cosine sample of an open plane is its albedo, of a closed box
 * 0), aoview's image is the exact one, bit for bit; the values are the albedo or the background
 * (the plane) and 0 (the box); no ground term. */
static void test_exact_where_the_estimator_is(void **state)
{
    (void)state;
    static const struct {
        const char *name, *kind;
        float values[2];
    } cases[] = {{"open-plane", "open plane", {0.7f, 1.0f}}, {"closed-box", "closed box", {0.0f, 0.0f}}};
    for (size_t c = 0; c < 2; c++) {
        struct exact *e = malloc(sizeof *e);
        assert_non_null(e);
        assert_true(exact_render(e, cases[c].name, INFINITY, 0));
        assert_string_equal(e->facts.kind, cases[c].kind);
        assert_true(isnan(e->facts.ground_error));
        for (size_t k = 0; k < 3 * W * H; k++)
            assert_true(fabsf(e->rgb[k] - cases[c].values[0]) < 1e-6f || e->rgb[k] == cases[c].values[1]);
        float *aoview = aoview_image(e, (const char *[]){"--spp", "16", "--spppp", "16"}, 4);
        assert_memory_equal(aoview, e->rgb, sizeof e->rgb);
        free(aoview);
        exact_finish(e);
        free(e);
    }
}

/* A sphere on a plane: a finite bound on the ground's residual; the sky is the background, every
 * other value within [0, albedo 0.8], darkest in the contact under the sphere; with a 4 x 4 grid
 * per pixel the image is the pixel-centre one within what an edge can move. aoview's unbiased
 * estimate agrees with it: each of its n = W H pixels is rho K / N, K binomial over N = 1024
 * independent random samples (the random sampler, no adaptive sampling), of variance at most
 * rho^2 / (4 N); the pixels are independent (their own streams), so the mean over the image has a
 * standard deviation of at most rho / (2 sqrt(N n)) = 3.6e-4 for rho = 0.8; the exact image's ground
 * residual moves its mean by at most ground_error. Bound: 4 standard deviations plus that. */
static void test_sphere_over_a_plane(void **state)
{
    (void)state;
    struct exact *e = malloc(sizeof *e), *aa = malloc(sizeof *aa);
    assert_non_null(e);
    assert_non_null(aa);
    assert_true(exact_render(e, "sphere-on-plane", INFINITY, 0));
    assert_string_equal(e->facts.kind, "sphere over a plane");
    assert_true(isfinite(e->facts.ground_error) && e->facts.ground_error >= 0.0 && e->facts.ground_error < 1e-3);
    float darkest = 1.0f;
    double sum = 0.0;
    for (size_t k = 0; k < 3 * W * H; k++) {
        assert_true(e->rgb[k] == 1.0f || (e->rgb[k] >= 0.0f && e->rgb[k] <= 0.8f + 1e-6f));
        darkest = fminf(darkest, e->rgb[k]);
        sum += e->rgb[k];
    }
    assert_true(darkest < 0.2f);
    float *aoview = aoview_image(e, (const char *[]){"--spp", "1024", "--spppp", "256", "--sampler", "random",
                                                     "--adaptive", "off"}, 8);
    double aoview_sum = 0.0;
    for (size_t k = 0; k < 3 * W * H; k++)
        aoview_sum += aoview[k];
    free(aoview);
    double bias = fabs(aoview_sum - sum) / (3 * W * H);
    assert_true(bias < 4 * 0.8 / (2 * sqrt(1024.0 * W * H)) + e->facts.ground_error);
    assert_true(exact_render(aa, "sphere-on-plane", INFINITY, 4));
    double aa_sum = 0.0;
    for (size_t k = 0; k < 3 * W * H; k++)
        aa_sum += aa->rgb[k];
    assert_true(fabs(aa_sum - sum) / (3 * W * H) < 0.02);
    assert_memory_not_equal(aa->rgb, e->rgb, sizeof e->rgb);
    exact_finish(aa);
    exact_finish(e);
    free(aa);
    free(e);
}

/* Scenes without a closed form, a finite AO distance and a camera that cannot form the image: false
 * with the one line that says why. */
static void test_refusals(void **state)
{
    (void)state;
    struct exact *e = malloc(sizeof *e);
    assert_non_null(e);
    assert_false(exact_render(e, "spheres", INFINITY, 0));
    assert_non_null(strstr(e->why, "no closed form: "));
    assert_non_null(strstr(e->why, "spheres (at most one"));
    exact_finish(e);
    assert_false(exact_render(e, "bunny", INFINITY, 0));
    assert_memory_equal(e->why, "no closed form: ", 16);
    assert_non_null(strstr(e->why, "triangles"));
    exact_finish(e);
    assert_false(exact_render(e, "open-plane", 2.0f, 0));
    assert_string_equal(e->why, "no closed form: the closed forms need an infinite AO distance, not 2");
    exact_finish(e);
    assert_true(exact_render(e, "open-plane", INFINITY, 0));
    e->scene.camera.up = ao_vec3_sub(e->scene.camera.target, e->scene.camera.eye);
    assert_false(ao_exact_render(&e->scene, e->tracer, INFINITY, W, H, 0, e->rgb, &e->facts, e->why, sizeof e->why));
    assert_string_equal(e->why, "the camera cannot form an image");
    exact_finish(e);
    free(e);
}

SOURCE_TEST_MAIN("test_exact_image", cmocka_unit_test(test_exact_where_the_estimator_is),
                 cmocka_unit_test(test_sphere_over_a_plane), cmocka_unit_test(test_refusals))
