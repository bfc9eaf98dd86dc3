/* Benchmark: the bunny and spheres scenes at 512x512, fixed seed, cosine sampling, per thread count
 * and samples per pass: Mrays/s (eye + shadow), ms per pass, and peak memory. Prints figures; it
 * asserts nothing (speed lives here, not in the tests). Run: meson test -C build --benchmark -v */
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>

#include "render.h"
#include "scene.h"
#include "tracer.h"

enum { SIZE = 512, REPEATS = 3 };

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Renders `passes` passes and returns the run's frame facts. */
static struct ao_frame_info run(const struct ao_scene *scene, const struct ao_tracer *tracer, int threads,
                                int spppp, int passes)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .width = SIZE, .height = SIZE,
                                      .threads = threads, .seed = 1, .target_spp = (uint32_t)(spppp * passes),
                                      .ao_distance = scene->ao_distance};
    struct ao_settings settings = {.sampling = AO_SAMPLING_COSINE, .aa = true, .spppp = spppp,
                                   .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r || !ao_render_wait(r))
        exit(1);
    struct ao_frame_info info = ao_render_take_frame(r)->info;
    ao_render_destroy(r);
    return info;
}

static void bench_scene(const char *path)
{
    struct ao_scene scene;
    if (!ao_scene_load(&scene, path))
        exit(1);
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    if (!tracer)
        exit(1);
    printf("%s: %zu triangles, %zu spheres\n", scene.name, scene.triangle_count, scene.sphere_count);
    printf("%-8s %-6s %12s %12s %10s\n", "threads", "spppp", "Mrays/s", "ms/pass", "passes");
    static const int spppps[] = {1, 4, 16, 64};
    double single[4] = {0};
    for (int threads = 1; threads <= 2; threads++) {
        for (int s = 0; s < 4; s++) {
            int passes = 128 / spppps[s] < 8 ? 8 : 128 / spppps[s];
            double mrays[REPEATS], ms[REPEATS];
            for (int k = 0; k < REPEATS; k++) {
                struct ao_frame_info info = run(&scene, tracer, threads, spppps[s], passes);
                mrays[k] = (double)(info.eye_rays + info.shadow_rays) / info.seconds / 1e6;
                ms[k] = 1e3 * info.seconds / info.pass;
            }
            qsort(mrays, REPEATS, sizeof *mrays, by_value);
            qsort(ms, REPEATS, sizeof *ms, by_value);
            printf("%-8d %-6d %12.2f %12.2f %10d", threads, spppps[s], mrays[REPEATS / 2], ms[REPEATS / 2], passes);
            if (threads == 1)
                single[s] = mrays[REPEATS / 2];
            else
                printf("   scaling %.2fx", mrays[REPEATS / 2] / single[s]);
            putchar('\n');
        }
    }
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
}

int main(int argc, char **argv)
{
    for (int k = 1; k < argc; k++)
        bench_scene(argv[k]);
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    printf("peak RSS %.1f MiB (medians of %d runs each)\n", usage.ru_maxrss / 1024.0, REPEATS);
    return 0;
}
