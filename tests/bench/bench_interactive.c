/* Benchmark: how interactive the window's renderer is at 640x480, 1920x1080 and 3840x2160, through
 * the render API with previews on (as the window runs it), 2 threads, no GL. Per size, one line:
 *   WxH: first frame A ms, first full frame B ms, orbit F frames/s, ...
 * A and B: medians over 21 camera changes of the time from the change to the first frame published
 * for it (a preview) and to its first full-resolution frame; F: during a scripted 2-second orbit
 * (the camera moved every 16 ms), the cameras per second that reached a published frame before the
 * next one was set, and the median cell size of the frame a window would show as each change came
 * (the newest published). Then the previews' cost per restart against the first full pass, and the
 * time to 1 % estimated error at 640x480 with previews on and off. Asserts nothing.
 * Run: ./build/tests/bench_interactive [SCENE] (default: the bunny) */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_util.h"
#include "config.h"
#include "program.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"

enum { CHANGES = 21, THREADS = 2, ROUNDS = 5 };
static const double ORBIT_SECONDS = 2.0, ORBIT_STEP = 0.016;

/* What the callbacks record of the run that the last camera change began (restarts `run`). */
struct watch {
    atomic_uint_fast64_t run;
    _Atomic double first, last_preview, full;   /* monotonic seconds; 0: not yet */
    atomic_int frames;                           /* frames of the run published */
};

static void seen(struct watch *w, const struct ao_frame_info *info, bool full)
{
    if (info->restarts != atomic_load(&w->run))
        return;
    double now = bench_now(), zero = 0.0;
    atomic_compare_exchange_strong(&w->first, &zero, now);
    if (full) {
        zero = 0.0;
        atomic_compare_exchange_strong(&w->full, &zero, now);
    } else {
        atomic_store(&w->last_preview, now);
    }
    atomic_fetch_add(&w->frames, 1);
}

static void on_pass(const struct ao_frame_info *info, void *user)
{
    seen(user, info, true);
}

static void on_preview(const struct ao_frame_info *info, void *user)
{
    seen(user, info, false);
}

/* Begins watching run `run`. */
static void watch(struct watch *w, uint64_t run)
{
    atomic_store(&w->first, 0.0);
    atomic_store(&w->last_preview, 0.0);
    atomic_store(&w->full, 0.0);
    atomic_store(&w->frames, 0);
    atomic_store(&w->run, run);
}

static void sleep_seconds(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - floor(s)) * 1e9)};
    nanosleep(&ts, NULL);
}

static struct ao_render *start(const struct ao_scene *scene, const struct ao_tracer *tracer, int width, int height,
                               bool previews, double target_error, struct watch *w)
{
    struct ao_render_config config = {.scene = scene, .tracer = tracer, .threads = THREADS, .seed = 1,
                                      .target_spp = 256, .target_error = target_error,
                                      .ao_distance = scene->ao_distance,
                                      .on_pass = on_pass, .on_preview = on_preview, .user = w};
    struct ao_settings settings = {.width = width, .height = height, .sampling = AO_SAMPLING_COSINE, .aa = true,
                                   .adaptive = true, .previews = previews, .camera = scene->camera};
    struct ao_render *r = ao_render_create(&config, &settings);
    if (!r)
        exit(1);
    return r;
}

/* Orbits the camera by a small step: a restart. */
static void nudge(struct ao_render *r)
{
    struct ao_settings s;
    ao_render_get_settings(r, &s);
    ao_camera_orbit(&s.camera, 0.01f, 0.0f);
    ao_render_set_settings(r, &s);
}

static void interactive(const struct ao_scene *scene, const struct ao_tracer *tracer, int width, int height)
{
    struct watch w = {0};
    watch(&w, 0);
    struct ao_render *r = start(scene, tracer, width, height, true, 0.0, &w);
    while (atomic_load(&w.full) == 0.0)
        sleep_seconds(0.001);

    /* Camera changes, each waited out to its first full frame. */
    double first[CHANGES], full[CHANGES], previews[CHANGES], pass[CHANGES];
    uint64_t run = 0;
    for (int k = 0; k < CHANGES; k++) {
        watch(&w, ++run);
        double t0 = bench_now();
        nudge(r);
        while (atomic_load(&w.full) == 0.0)
            sleep_seconds(0.0002);
        first[k] = 1e3 * (atomic_load(&w.first) - t0);
        full[k] = 1e3 * (atomic_load(&w.full) - t0);
        double last = atomic_load(&w.last_preview);
        previews[k] = last > 0.0 ? 1e3 * (last - t0) : 0.0;
        pass[k] = 1e3 * (atomic_load(&w.full) - (last > 0.0 ? last : t0));
    }

    /* The orbit: a change every ORBIT_STEP seconds; a camera counts when a frame of it was
     * published before the next change. */
    int shown = 0, steps = 0, taken = 0;
    double begin = bench_now(), blocks[(int)(ORBIT_SECONDS / ORBIT_STEP) + 1];
    const struct ao_frame *newest = NULL;
    for (double next = begin; next - begin < ORBIT_SECONDS; next += ORBIT_STEP, steps++) {
        sleep_seconds(fmax(0.0, next - bench_now()));
        shown += steps > 0 && atomic_load(&w.frames) > 0;
        const struct ao_frame *f = ao_render_take_frame(r);
        newest = f ? f : newest;
        if (steps > 0 && newest)
            blocks[taken++] = newest->block;
        watch(&w, ++run);
        nudge(r);
    }
    sleep_seconds(fmax(0.0, begin + steps * ORBIT_STEP - bench_now()));
    shown += atomic_load(&w.frames) > 0;
    double orbit = shown / (bench_now() - begin);
    ao_render_destroy(r);

    double preview_ms = bench_median(previews, CHANGES), pass_ms = bench_median(pass, CHANGES);
    int block = taken ? (int)bench_median(blocks, taken) : 0;
    printf("%dx%d: first frame %.1f ms, first full frame %.1f ms, orbit %.0f frames/s (shown: %dx%d cells); "
           "previews %.1f ms a restart, %.0f %% of the first full pass (%.1f ms)\n",
           width, height, bench_median(first, CHANGES), bench_median(full, CHANGES), orbit,
           block ? (width + block - 1) / block : 0, block ? (height + block - 1) / block : 0, preview_ms,
           100.0 * preview_ms / pass_ms, pass_ms);
    fflush(stdout);
}

/* Seconds to the estimated 1 % error at width x height, previews on and off in turns (medians). */
static void time_to_error(const struct ao_scene *scene, const struct ao_tracer *tracer, int width, int height)
{
    double seconds[2][ROUNDS];
    for (int round = 0; round < ROUNDS; round++)
        for (int previews = 0; previews < 2; previews++) {
            struct watch w = {0};
            watch(&w, 0);
            double t0 = bench_now();
            struct ao_render *r = start(scene, tracer, width, height, previews, 0.01, &w);
            if (!ao_render_wait(r))
                exit(1);
            seconds[previews][round] = bench_now() - t0;
            ao_render_destroy(r);
        }
    double off = bench_median(seconds[0], ROUNDS), on = bench_median(seconds[1], ROUNDS);
    printf("%dx%d: time to 1 %% estimated error %.3f s with previews, %.3f s without (%+.1f %%), medians of %d\n",
           width, height, on, off, 100.0 * (on / off - 1.0), ROUNDS);
}

int main(int argc, char **argv)
{
    ao_program_init();
    const char *path = argc > 1 ? argv[1] : AO_DEFAULT_SCENE;
    struct ao_scene scene;
    struct ao_tracer *tracer = bench_load(path, &scene);
    printf("%s, %d threads\n", scene.name, THREADS);
    const int sizes[][2] = {{640, 480}, {1920, 1080}, {3840, 2160}};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++)
        interactive(&scene, tracer, sizes[k][0], sizes[k][1]);
    time_to_error(&scene, tracer, 640, 480);
    ao_tracer_destroy(tracer);
    ao_scene_finish(&scene);
    return 0;
}
