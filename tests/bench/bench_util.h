/* Timing helpers and one render run, shared by the benchmark programs. Header only. */
#ifndef AO_BENCH_UTIL_H
#define AO_BENCH_UTIL_H

#include <stdlib.h>
#include <time.h>

#include "clock.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

/* Seconds on the monotonic clock (the renderer's own). */
static inline double bench_now(void)
{
    return ao_clock_seconds();
}

/* qsort's order of doubles. */
static inline int bench_by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of v[0..n) (sorts v in place). */
static inline double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, bench_by_value);
    return v[n / 2];
}

/* Loads the scene at path into *scene and builds its tracer; exits (after the loader's message)
 * when either fails. */
static inline struct ao_tracer *bench_load(const char *path, struct ao_scene *scene)
{
    if (!ao_scene_load(scene, path, NULL))
        exit(1);
    struct ao_tracer *tracer = ao_tracer_create(scene);
    if (!tracer)
        exit(1);
    return tracer;
}

/* Renders scene with 2 threads (seed 1, cosine, AA, its own camera) at width x height, spppp
 * samples a pass (0: auto), adaptive sampling and sequence as asked (aoview's defaults: 0, true,
 * Sobol), until target_spp or the estimated error target_error (0: none), switching to upgrade's
 * better BVH between passes (NULL: none); returns the last frame's facts, or exits. */
static inline struct ao_frame_info bench_render_until(const struct ao_scene *scene, const struct ao_tracer *tracer,
                                                      struct ao_tracer *upgrade, int width, int height, int spppp,
                                                      bool adaptive, enum ao_sequence sequence, uint32_t target_spp,
                                                      double target_error)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .upgrade = upgrade, .threads = 2, .seed = 1,
                                      .target_spp = target_spp, .target_error = target_error,
                                      .ao_distance = scene->ao_distance, .sequence = sequence};
    struct ao_settings settings = {.width = width, .height = height, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .spppp = spppp, .adaptive = adaptive, .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r || !ao_render_wait(r))
        exit(1);
    struct ao_frame_info info = ao_render_take_frame(r)->info;
    ao_render_destroy(r);
    return info;
}

/* bench_render_until with spppp samples a pass, no adaptive sampling, random numbers, to target_spp. */
static inline struct ao_frame_info bench_render(const struct ao_scene *scene, const struct ao_tracer *tracer,
                                                int width, int height, int spppp, uint32_t target_spp)
{
    return bench_render_until(scene, tracer, NULL, width, height, spppp, false, AO_SEQUENCE_RANDOM, target_spp, 0.0);
}

#endif
