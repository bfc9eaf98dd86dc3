/* The ground quad added under a bare mesh (scene_load.c): a flat model on it renders unoccluded, a
 * resting model keeps its contact shadow, and --ground off (ao_scene_options.ground) leaves it out.
 * Seeds are fixed and the numbers random (not Sobol), so that the binomial variances below hold. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "render.h"
#include "render_image.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* The albedo of a bare mesh and of its ground (scene_load.c). */
static const float MODEL_RHO = 0.8f, GROUND_RHO = 0.5f;

static char temp_dir[] = "/tmp/aoview-ground-XXXXXX";

/* Writes text to name in the scratch directory; returns its path (a static buffer per call site's use). */
static const char *temp_file(const char *name, const char *text, char *path, size_t size)
{
    snprintf(path, size, "%s/%s", temp_dir, name);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, strlen(text), f), strlen(text));
    assert_int_equal(fclose(f), 0);
    return path;
}

/* Loads path as aoview does, with or without the ground. */
static void load(struct ao_scene *scene, const char *path, bool ground)
{
    struct ao_scene_options options = {.budget = 1u << 30, .no_ground = !ground};
    assert_true(ao_scene_load(scene, path, &options));
}

/* Renders scene (cosine sampling, AA, one sample a pass, no adaptive sampling, two threads, seed 5)
 * and returns a malloc'd copy of the linear image; output picks AO or the normals view. */
static float *render(const struct ao_scene *scene, enum ao_backend backend, int width, int height, uint32_t spp,
                     enum ao_output output)
{
    struct ao_tracer *tracer = ao_tracer_create_with(scene, backend);
    assert_non_null(tracer);
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .threads = 2, .seed = 5, .target_spp = spp,
                                      .ao_distance = INFINITY, .sequence = AO_SEQUENCE_RANDOM};
    struct ao_settings settings = {.width = width, .height = height, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = 1, .output = output, .camera = scene->camera};
    float *copy = render_image(&config, &settings);
    ao_tracer_destroy(tracer);
    return copy;
}

/* A flat model, as OBJ (a 2 x 2 square at y = 0 whose winding faces down) and as glTF (the same
 * square facing up, under a node that lifts it to y = 3), with the ground added under it: on both
 * tracers, every pixel that sees only the model renders as rho. Those pixels are the ones exactly
 * rho without the ground (--ground off: nothing else in the scene, every eye ray of the pixel met
 * the open model). With cosine sampling each sample is rho V (V = 1 when the occlusion ray escapes;
 * README's table: variance 0 on an open plane), and nothing lies above the model's top, so each
 * such pixel is exactly rho: the bound 0.9 rho at 64 spp is no noise allowance. A pixel
 * below it has at least 7 of its 64 samples occluded, or 18 eye rays that met the ground (0.5)
 * instead of the model; with the ground at the model's height (before) 1853 of the square's 1859
 * pixels were below it. Without the ground, no pixel is the ground's unoccluded 0.5; with it,
 * the open ground far from the model is. */
static void test_flat_models_render_unoccluded(void **state)
{
    (void)state;
    char obj_path[256], gltf_path[256];
    temp_file("square.obj", "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 2 3 4\n", obj_path, sizeof obj_path);
    temp_file("plane.gltf",
              "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 0, \"translation\": [0, 3, 0]}],\n"
              " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1}]}],\n"
              " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\"},\n"
              "               {\"bufferView\": 0, \"byteOffset\": 48, \"componentType\": 5121, \"count\": 6,"
              " \"type\": \"SCALAR\"}],\n"
              " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": 56}],\n"
              " \"buffers\": [{\"byteLength\": 56, \"uri\": \"data:application/gltf-buffer;base64,"
              "AACAvwAAAAAAAIC/AACAPwAAAAAAAIC/AACAPwAAAAAAAIA/AACAvwAAAAAAAIA/AAIBAAMCAAA=\"}]}\n",
              gltf_path, sizeof gltf_path);
    const char *paths[2] = {obj_path, gltf_path};
    const enum ao_backend backends[2] = {AO_BACKEND_DIRECT, AO_BACKEND_EMBREE};
    enum { W = 160, H = 120, SPP = 64 };
    for (int f = 0; f < 2; f++) {
        struct ao_scene bare, grounded;
        load(&bare, paths[f], false);
        load(&grounded, paths[f], true);
        assert_int_equal(bare.triangle_count, 2);
        assert_int_equal(grounded.triangle_count, 4);
        for (int b = 0; b < 2; b++) {
            float *off = render(&bare, backends[b], W, H, SPP, AO_OUTPUT_AO);
            float *on = render(&grounded, backends[b], W, H, SPP, AO_OUTPUT_AO);
            int model = 0, below = 0, ground_off = 0, ground_on = 0;
            float least = INFINITY;
            for (int i = 0; i < W * H; i++) {
                ground_off += off[3 * i] == GROUND_RHO;
                ground_on += on[3 * i] == GROUND_RHO;
                if (off[3 * i] != MODEL_RHO)
                    continue;
                model++;
                below += on[3 * i] < 0.9f * MODEL_RHO;
                least = fminf(least, on[3 * i]);
            }
            printf("%s, %s: %d pixels of the model alone, the least %.4f with the ground, %d below 0.9 rho; "
                   "%d pixels of open ground\n", strrchr(paths[f], '/') + 1, b ? "embree" : "direct", model,
                   (double)least, below, ground_on);
            assert_true(model > W * H / 20);   /* the model fills a good part of the frame */
            assert_int_equal(below, 0);
            assert_int_equal(ground_off, 0);
            assert_true(ground_on > W * H / 4);
            free(off);
            free(on);
        }
        ao_scene_finish(&bare);
        ao_scene_finish(&grounded);
    }
    unlink(obj_path);
    unlink(gltf_path);
}

/* The bunny resting on the added ground keeps its contact shadow: rendered with the ground where
 * scene_load.c puts it (AO_SCENE_GROUND_GAP of its size below its lowest point) and with the same scene's
 * ground raised to that point (where it was before the gap), same seed and samples. The shadow is
 * the pixels that see only the ground in both (the normals view gives exactly the ground's normal
 * colour) and are below 0.9 of the ground's albedo with the ground at the lowest point. A pixel is
 * the mean of N samples rho V, V in {0, 1}: its variance is rho^2 p (1 - p) / N with p = value / rho.
 * The mean over the shadow's pixels, were the two renders independent, would differ by noise of
 * deviation sigma = sqrt(2 sum of those variances) / count; the same samples make the true noise
 * smaller, so |difference| <= 4 sigma says that the gap changes the contact shadow by less than the
 * Monte Carlo noise of its mean. At this size that passes a gap of 1e-4 and 3e-3 and fails 1e-2 of
 * the bunny's size (measured: 0.3 % darker contact shadow at 1e-3, 3 % at 1e-2, at 640x480). */
static void test_contact_shadow_is_kept(void **state)
{
    (void)state;
    const char *root = getenv("AO_SOURCE_ROOT");
    if (!root) {
        print_message("AO_SOURCE_ROOT not set (run through meson test)\n");
        skip();
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/assets/bunny.obj", root);
    struct ao_scene gap, touching;
    load(&gap, path, true);
    load(&touching, path, true);
    /* The ground is the last instance's mesh (the bunny, placed once, is flat); raise its 4 vertices
     * to the lowest vertex of the bunny. */
    assert_int_equal(touching.instance_count, 2);
    assert_true(touching.instances[0].flat && touching.instances[1].flat);
    struct ao_mesh *bunny = &touching.meshes[touching.instances[0].mesh];
    struct ao_mesh *ground = &touching.meshes[touching.instances[1].mesh];
    assert_int_equal(ground->vertex_count, 4);
    float lowest = INFINITY;
    for (size_t i = 0; i < bunny->vertex_count; i++)
        lowest = fminf(lowest, bunny->positions[i].y);
    assert_true(ground->positions[0].y < lowest);
    for (size_t i = 0; i < 4; i++)
        ground->positions[i].y = lowest;

    enum { W = 320, H = 240, SPP = 64 };
    float *a = render(&gap, AO_BACKEND_AUTO, W, H, SPP, AO_OUTPUT_AO);
    float *b = render(&touching, AO_BACKEND_AUTO, W, H, SPP, AO_OUTPUT_AO);
    float *na = render(&gap, AO_BACKEND_AUTO, W, H, 16, AO_OUTPUT_NORMALS);
    float *nb = render(&touching, AO_BACKEND_AUTO, W, H, 16, AO_OUTPUT_NORMALS);
    double sum_a = 0.0, sum_b = 0.0, variance = 0.0;
    int count = 0;
    for (int i = 0; i < W * H; i++) {
        bool ground = na[3 * i] == 0.5f && na[3 * i + 1] == 1.0f && na[3 * i + 2] == 0.5f &&
                      nb[3 * i] == 0.5f && nb[3 * i + 1] == 1.0f && nb[3 * i + 2] == 0.5f;
        if (!ground || !(b[3 * i] < 0.9f * GROUND_RHO))
            continue;
        double p = b[3 * i] / GROUND_RHO;
        sum_a += a[3 * i];
        sum_b += b[3 * i];
        variance += (double)GROUND_RHO * GROUND_RHO * p * (1.0 - p) / SPP;
        count++;
    }
    double difference = (sum_a - sum_b) / count, sigma = sqrt(2.0 * variance) / count;
    printf("contact shadow: %d pixels, mean %.5f with the gap, %.5f touching: difference %+.6f, sigma %.6f\n",
           count, sum_a / count, sum_b / count, difference, sigma);
    assert_true(count > 5000);   /* the shadow is there: about 10000 pixels at this size */
    assert_true(fabs(difference) <= 4.0 * sigma);
    free(a);
    free(b);
    free(na);
    free(nb);
    ao_scene_finish(&gap);
    ao_scene_finish(&touching);
}

int main(void)
{
    if (!mkdtemp(temp_dir)) {
        perror("mkdtemp");
        return 1;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_models_render_unoccluded),
        cmocka_unit_test(test_contact_shadow_is_kept),
    };
    int failed = cmocka_run_group_tests(tests, NULL, NULL);
    rmdir(temp_dir);
    return failed;
}
