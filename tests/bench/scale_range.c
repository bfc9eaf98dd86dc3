/* The measurement behind docs/stability.md's "Sizes" table: a scene loaded at its own size, then
 * scaled in place by 2^k (every position, sphere and the camera; exact in float), bypassing
 * scene_place.c's range check, rendered with the same seed and compared value by value with the scene
 * at its own size. Run by hand: build/tests/scale_range KIND BACKEND K...; KIND 0 is a sphere of
 * radius 1 on a ground quad 2^15 wide, 1 the default scene on a ground quad 2^7 wide; BACKEND 0
 * the direct loops, 1 Embree. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "program.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

enum { W = 80, H = 60, SPP = 64 };

/* The scene of text scaled by 2^k after loading, rendered; a malloc'd linear image or NULL. */
static float *render_scaled(const char *text, const char *path, int k, enum ao_backend backend)
{
    struct ao_scene scene;
    if (!ao_scene_parse(&scene, text, path, NULL))
        return NULL;
    float s = ldexpf(1.0f, k);
    for (size_t m = 0; m < scene.mesh_count; m++)   /* the scenes it scales are flat */
        for (size_t i = 0; i < scene.meshes[m].vertex_count; i++)
            scene.meshes[m].positions[i] = ao_vec3_scale(scene.meshes[m].positions[i], s);
    for (size_t i = 0; i < scene.sphere_count; i++) {
        scene.spheres[i].center = ao_vec3_scale(scene.spheres[i].center, s);
        scene.spheres[i].radius *= s;
    }
    scene.camera.eye = ao_vec3_scale(scene.camera.eye, s);
    scene.camera.target = ao_vec3_scale(scene.camera.target, s);
    struct ao_tracer *tracer = ao_tracer_create_with(&scene, backend);
    float *copy = malloc(3 * sizeof(float) * W * H);
    struct ao_render *r = NULL;
    if (tracer && copy) {
        struct ao_render_config config = {.scene = &scene, .tracer = tracer, .threads = 1, .seed = 9,
                                          .target_spp = SPP, .ao_distance = INFINITY};
        struct ao_settings settings = {.width = W, .height = H, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                       .spppp = 16, .camera = scene.camera};
        r = ao_render_create(&config, &settings);
    }
    if (r && ao_render_wait(r))
        memcpy(copy, ao_render_take_frame(r)->rgb, 3 * sizeof(float) * W * H);
    else {
        free(copy);
        copy = NULL;
    }
    ao_render_destroy(r);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return copy;
}

int main(int argc, char **argv)
{
    ao_program_init();
    const char *root = getenv("AO_SOURCE_ROOT");
    if (argc < 4) {
        fprintf(stderr, "usage: AO_SOURCE_ROOT=DIR scale_range KIND(0|1) BACKEND(0 direct|1 embree) K...\n");
        return 2;
    }
    int kind = atoi(argv[1]);
    enum ao_backend backend = atoi(argv[2]) ? AO_BACKEND_EMBREE : AO_BACKEND_DIRECT;
    char text[4096], path[4096];
    snprintf(path, sizeof path, "%s/assets/scenes/scaled.scene", root ? root : ".");
    if (kind == 0)
        snprintf(text, sizeof text, "camera eye 0 3.2 6.4 target 0 0.7 0 fov 40\n"
                 "quad corner -16384 0 -16384 edge1 0 0 32768 edge2 32768 0 0 albedo 0.8\n"
                 "sphere center 0 1 0 radius 1 albedo 0.8\n");
    else
        snprintf(text, sizeof text, "camera eye 0.5 1 2.5 target 0 0.42 0 up 0 1 0 fov 35\nbackground 1\n"
                 "mesh ../bunny.obj albedo 0.8 0.75 0.7 scale 0.1 translate 0 0.0003 0\n"
                 "quad corner -64 0 -64 edge1 0 0 128 edge2 128 0 0 albedo 0.8\n");
    float *own = render_scaled(text, path, 0, backend);
    if (!own)
        return 1;
    double own_mean = 0.0;
    for (int p = 0; p < 3 * W * H; p++)
        own_mean += own[p] / (3 * W * H);
    for (int a = 3; a < argc; a++) {
        int k = atoi(argv[a]), differ = 0;
        float *rgb = render_scaled(text, path, k, backend);
        if (!rgb)
            return 1;
        double mean = 0.0;
        for (int p = 0; p < 3 * W * H; p++) {
            differ += rgb[p] != own[p];
            mean += rgb[p] / (3 * W * H);
        }
        printf("%s, %s, %.3g across: %d of %d values differ (%.1f %%), mean %.3f against %.3f\n",
               kind ? "default scene" : "sphere on ground", backend == AO_BACKEND_EMBREE ? "embree" : "direct",
               ldexp(kind ? 128.0 : 32768.0, k), differ, 3 * W * H, 100.0 * differ / (3 * W * H), mean, own_mean);
        free(rgb);
    }
    free(own);
    return 0;
}
