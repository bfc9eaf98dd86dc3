/* How two renderers share the cores in a live comparison: by turns (compare.c: one side at a time
 * with all the threads) against at once (each with half the threads). The same configuration on
 * both sides, so that a fair share gives both the same spp; interleaved runs, medians.
 *   bench_compare SCENE [SECONDS [RUNS]]   (defaults 4 s, 5 runs; 320x240, cosine, Sobol, AA,
 * 4 samples a pass, adaptive sampling off) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_util.h"
#include "compare.h"
#include "program.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* The image, the threads in all (this machine's two cores), the samples per pass (small, so that
 * the spp of a side is not rounded to auto passes' sizes) and the most runs. */
enum { WIDTH = 320, HEIGHT = 240, THREADS = 2, SPPPP = 4, MAX_RUNS = 64 };

/* One run's facts: each side's spp and render seconds, and the samples traced per wall second. */
struct run {
    double spp_ratio, seconds_gap, samples_per_second;
};

/* Renders both sides for seconds each, by turns or at once, with threads in all. */
static struct run measure(const struct ao_scene *scene, const struct ao_tracer *tracer, double seconds, int threads,
                          bool turns)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer,
                                      .threads = turns ? threads : threads / 2, .seed = 1, .target_spp = 1u << 30,
                                      .time_limit = seconds, .ao_distance = scene->ao_distance,
                                      .sequence = AO_SEQUENCE_SOBOL};
    struct ao_settings settings = {.width = WIDTH, .height = HEIGHT, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = SPPPP, .camera = scene->camera};
    struct ao_frame_info info[2];
    double start = bench_now();
    if (turns) {
        struct ao_compare_side sides[2] = {{AO_SAMPLING_COSINE, AO_SEQUENCE_SOBOL, true},
                                           {AO_SAMPLING_COSINE, AO_SEQUENCE_SOBOL, true}};
        void *users[2] = {NULL, NULL};
        struct ao_compare *c = ao_compare_create(&config, &settings, sides, users);
        if (!c)
            exit(1);
        struct timespec ms = {0, 1000000};
        while (ao_compare_running(c))
            nanosleep(&ms, NULL);
        ao_compare_take_frames(c);
        for (int k = 0; k < 2; k++)
            info[k] = ao_compare_frame(c, k)->info;
        ao_compare_destroy(c);
    } else {
        struct ao_render *r[2];
        for (int k = 0; k < 2; k++)
            if (!(r[k] = ao_render_create(&config, &settings)))
                exit(1);
        for (int k = 0; k < 2; k++) {
            ao_render_wait(r[k]);
            info[k] = ao_render_take_frame(r[k])->info;
        }
        for (int k = 0; k < 2; k++)
            ao_render_destroy(r[k]);
    }
    double wall = bench_now() - start;
    printf("%-8s A %5u spp %6.3f s   B %5u spp %6.3f s   wall %6.3f s\n", turns ? "turns" : "at once", info[0].spp,
           info[0].seconds, info[1].spp, info[1].seconds, wall);
    return (struct run){(double)info[0].spp / info[1].spp,
                        fabs(info[0].seconds - info[1].seconds) / fmax(info[0].seconds, info[1].seconds),
                        (info[0].mean_spp + info[1].mean_spp) * WIDTH * HEIGHT / wall};
}

int main(int argc, char **argv)
{
    ao_program_init();
    if (argc < 2) {
        fprintf(stderr, "usage: bench_compare SCENE [SECONDS [RUNS]]\n");
        return 2;
    }
    double seconds = argc > 2 ? atof(argv[2]) : 4.0;
    int runs = argc > 3 ? atoi(argv[3]) : 5;
    runs = runs < 1 ? 1 : runs > MAX_RUNS ? MAX_RUNS : runs;
    struct ao_scene scene;
    if (!ao_scene_load(&scene, argv[1], NULL))
        return 1;
    struct ao_tracer *tracer = ao_tracer_create(&scene);
    if (!tracer)
        return 1;
    double ratio[2][MAX_RUNS], gap[2][MAX_RUNS], rate[2][MAX_RUNS];
    for (int i = 0; i < runs; i++)
        for (int turns = 0; turns < 2; turns++) {
            struct run r = measure(&scene, tracer, seconds, THREADS, turns);
            ratio[turns][i] = r.spp_ratio;
            gap[turns][i] = r.seconds_gap;
            rate[turns][i] = r.samples_per_second;
        }
    for (int turns = 0; turns < 2; turns++)
        printf("%-8s median: spp A/B %.3f, render seconds apart %.1f %%, %.1f M samples per wall second\n",
               turns ? "turns" : "at once", bench_median(ratio[turns], runs), 100 * bench_median(gap[turns], runs),
               bench_median(rate[turns], runs) / 1e6);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return 0;
}
