/* Benchmark: the same scene instanced and flattened (scene.h's ao_instancing), interleaved round by
 * round: load time, Embree build time, what Embree holds, and AO rays a second (512x512, cosine,
 * AA, 2 threads, 16 samples a pixel a pass, 8 passes after one to warm up), medians of the rounds.
 * Asserts nothing; docs/performance.md has the figures and the command.
 * Run: build/tests/bench_instances [--rounds N] SCENE... */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"

enum { SIZE = 512, SPPPP = 16, PASSES = 8, MAX_ROUNDS = 21, MAX_FILES = 8 };

/* Mrays/s (eye and AO rays over the render time) of PASSES passes after a first one. */
static double rate(const struct ao_scene *scene, const struct ao_tracer *tracer)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .threads = 2, .seed = 1,
                                      .target_spp = SPPPP * (PASSES + 1), .ao_distance = scene->ao_distance};
    struct ao_settings settings = {.width = SIZE, .height = SIZE, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = SPPPP, .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r || !ao_render_wait(r))
        exit(1);
    struct ao_frame_info info = ao_render_take_frame(r)->info;
    ao_render_destroy(r);
    return (double)(info.eye_rays + info.shadow_rays) / info.seconds / 1e6;
}

int main(int argc, char **argv)
{
    int first = 1, rounds = 5;
    if (argc > 2 && strcmp(argv[1], "--rounds") == 0)
        rounds = atoi(argv[2]), first = 3;
    int files = argc - first;
    if (files < 1 || files > MAX_FILES || rounds < 1 || rounds > MAX_ROUNDS) {
        fprintf(stderr, "usage: bench_instances [--rounds 1..%d] SCENE... (at most %d)\n", MAX_ROUNDS, MAX_FILES);
        return 2;
    }
    static const enum ao_instancing modes[2] = {AO_INSTANCING_ALWAYS, AO_INSTANCING_NEVER};
    static const char *const names[2] = {"instanced", "flattened"};
    static double load[MAX_FILES][2][MAX_ROUNDS], build[MAX_FILES][2][MAX_ROUNDS], mrays[MAX_FILES][2][MAX_ROUNDS];
    static double embree[MAX_FILES][2];
    static size_t triangles[MAX_FILES], instanced[MAX_FILES][2];
    for (int r = 0; r < rounds; r++)
        for (int f = 0; f < files; f++)
            for (int m = 0; m < 2; m++) {
                struct ao_scene scene;
                struct ao_scene_options options = {.budget = (uint64_t)1 << 40, .ground = true, .instancing = modes[m]};
                double start = bench_now();
                if (!ao_scene_load_with(&scene, argv[first + f], &options))
                    return 1;
                double loaded = bench_now();
                struct ao_tracer *tracer = ao_tracer_create_with(&scene, AO_BACKEND_EMBREE);
                if (!tracer)
                    return 1;
                double built = bench_now();
                struct ao_tracer_stats stats;
                ao_tracer_describe(tracer, &stats);
                load[f][m][r] = loaded - start;
                build[f][m][r] = built - loaded;
                mrays[f][m][r] = rate(&scene, tracer);
                embree[f][m] = (double)stats.embree_bytes;
                triangles[f] = scene.triangle_count;
                instanced[f][m] = stats.instances;
                ao_tracer_destroy(tracer);
                ao_scene_finish(&scene);
            }
    printf("%-32s %-10s %12s %10s %9s %9s %11s %8s\n", "scene", "", "triangles", "instances", "load s", "build s",
           "Embree MB", "Mrays/s");
    for (int f = 0; f < files; f++)
        for (int m = 0; m < 2; m++)
            printf("%-32s %-10s %12zu %10zu %9.3f %9.3f %11.1f %8.2f\n", m ? "" : argv[first + f], names[m], triangles[f],
                   instanced[f][m], bench_median(load[f][m], rounds), bench_median(build[f][m], rounds), embree[f][m] / 1e6,
                   bench_median(mrays[f][m], rounds));
    return 0;
}
