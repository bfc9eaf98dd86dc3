/* options.c: what the command line's options make of a scene (its loading options, the image size,
 * the renderer's config and first settings), through the parser as the programs call it. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>
#include <unistd.h>

#include "capture.h"
#include "options.h"
#include "scene_load.h"
#include "tracer.h"
#include "unit_main.h"

/* A scene with an image line and an AO distance, and one without either. */
static const char SIZED[] = "camera eye 0 1 3 target 0 0 0 up 0 1 0 fov 40\nimage 320 200\nao-distance 2.5\n"
                            "quad corner -1 0 -1 edge1 0 0 2 edge2 2 0 0 albedo 0.7\n";
static const char BARE[] = "camera eye 0 1 3 target 0 0 0 up 0 1 0 fov 40\n"
                           "quad corner -1 0 -1 edge1 0 0 2 edge2 2 0 0 albedo 0.7\n";

/* Parses the words (after the program's name) into *opts; they must be good. */
static void parse(struct ao_options *opts, const char *const *words, int count)
{
    char *argv[32] = {"aoview"}, msg[512];
    assert_true(count < 31);
    for (int i = 0; i < count; i++)
        argv[i + 1] = (char *)words[i];
    if (!ao_cli_parse(count + 1, argv, opts, msg, sizeof msg))
        fail_msg("%s", msg);
}

/* parse over the words listed. */
#define PARSE(opts, ...) \
    parse(opts, (const char *[]){__VA_ARGS__}, (int)(sizeof (const char *[]){__VA_ARGS__} / sizeof(const char *)))

static void test_scene_options(void **state)
{
    (void)state;
    struct ao_options opts;
    PARSE(&opts, "x.obj");
    struct ao_scene_options load = ao_options_scene(&opts);
    assert_false(load.no_ground);
    assert_false(load.sized);
    assert_true(load.crease_set);
    assert_true(load.crease == opts.crease);
    assert_int_equal(load.bvh, AO_BVH_AUTO);
    assert_true(load.budget == opts.scene_budget);
    PARSE(&opts, "--ground", "off", "--bvh", "compact", "--crease-angle", "30", "--size", "64x48",
          "--scene-budget", "3M", "x.obj");
    load = ao_options_scene(&opts);
    assert_true(load.no_ground);
    assert_true(load.sized);
    assert_true(load.crease_set);
    assert_true(load.crease == 30.0);
    assert_int_equal(load.bvh, AO_BVH_COMPACT);
    assert_true(load.budget == 3u << 20);
}

/* --size, else the scene's image line, else 640x480. */
static void test_size(void **state)
{
    (void)state;
    struct ao_scene sized, bare;
    assert_true(ao_scene_parse(&sized, SIZED, "sized.scene", NULL));
    assert_true(ao_scene_parse(&bare, BARE, "bare.scene", NULL));
    struct ao_options opts;
    int w, h;
    PARSE(&opts, "x.scene");
    ao_options_size(&opts, &sized, &w, &h);
    assert_true(w == 320 && h == 200);
    ao_options_size(&opts, &bare, &w, &h);
    assert_true(w == 640 && h == 480);
    PARSE(&opts, "--size", "64x48", "x.scene");
    ao_options_size(&opts, &sized, &w, &h);
    assert_true(w == 64 && h == 48);
    ao_options_size(&opts, &bare, &w, &h);
    assert_true(w == 64 && h == 48);
    ao_scene_finish(&sized);
    ao_scene_finish(&bare);
}

/* A scene parsed from text, its tracer, and what ao_options_render makes of them. */
struct rendered {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_options opts;
    struct ao_render_config config;
    struct ao_settings settings;
};

static void rendered_begin(struct rendered *r, const char *text, const char *name)
{
    assert_true(ao_scene_parse(&r->scene, text, name, NULL));
    r->tracer = ao_tracer_create(&r->scene);
    assert_non_null(r->tracer);
}

static void rendered_finish(struct rendered *r)
{
    ao_tracer_destroy(r->tracer);
    ao_scene_finish(&r->scene);
}

/* The config and settings: the options' values where given, the scene's or the machine's where not. */
static void test_render_config(void **state)
{
    (void)state;
    struct rendered r;
    rendered_begin(&r, SIZED, "sized.scene");
    PARSE(&r.opts, "x.scene");
    assert_true(ao_options_render(&r.opts, &r.scene, r.tracer, &r.config, &r.settings));
    assert_ptr_equal(r.config.scene, &r.scene);
    assert_ptr_equal(r.config.tracer, r.tracer);
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    assert_int_equal(r.config.threads, cores > 0 ? cores : 1);
    assert_true(r.config.ao_distance == 2.5f);   /* the scene's */
    assert_true(r.config.seed == 1 && r.config.target_spp == 256);
    assert_null(r.config.reference);
    assert_true(r.settings.width == 320 && r.settings.height == 200);
    assert_int_equal(r.settings.output, AO_OUTPUT_AO);
    assert_int_equal(r.settings.sampling, AO_SAMPLING_COSINE);
    assert_true(r.settings.aa);
    assert_memory_equal(&r.settings.camera, &r.scene.camera, sizeof r.scene.camera);

    PARSE(&r.opts, "--threads", "3", "--seed", "7", "--spp", "16", "--ao-distance", "0.5", "--size", "40x30",
          "--view", "normals", "--sampling", "uniform", "--no-aa", "--spppp", "4", "x.scene");
    assert_true(ao_options_render(&r.opts, &r.scene, r.tracer, &r.config, &r.settings));
    assert_int_equal(r.config.threads, 3);
    assert_true(r.config.seed == 7 && r.config.target_spp == 16);
    assert_true(r.config.ao_distance == 0.5f);
    assert_true(r.settings.width == 40 && r.settings.height == 30);
    assert_int_equal(r.settings.output, AO_OUTPUT_NORMALS);
    assert_int_equal(r.settings.sampling, AO_SAMPLING_UNIFORM);
    assert_false(r.settings.aa);
    assert_int_equal(r.settings.spppp, 4);
    rendered_finish(&r);
}

/* A camera that cannot form an image (looking along its up): false, after one line naming the scene. */
static void test_camera_refused(void **state)
{
    (void)state;
    struct rendered r;
    rendered_begin(&r, BARE, "bare.scene");
    r.scene.camera.up = ao_vec3_sub(r.scene.camera.target, r.scene.camera.eye);
    PARSE(&r.opts, "x.scene");
    struct capture c;
    char err[512];
    capture_begin(&c);
    assert_false(ao_options_render(&r.opts, &r.scene, r.tracer, &r.config, &r.settings));
    capture_end(&c, err, sizeof err);
    assert_string_equal(err, "bare.scene: the camera cannot form an image\n");
    rendered_finish(&r);
}

UNIT_TEST_MAIN(cmocka_unit_test(test_scene_options), cmocka_unit_test(test_size), cmocka_unit_test(test_render_config),
               cmocka_unit_test(test_camera_refused))
