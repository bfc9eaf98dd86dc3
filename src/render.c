/* The render thread and its workers; see render.h and DESIGN.md's "Threads". */
#include "render.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "accum.h"
#include "ao.h"

/* Tiles are TILE x TILE pixels (AO_TILE_PIXELS); FRESH marks a frame the consumer has not seen. */
enum { TILE = 16, FRESH = 4 };
_Static_assert(TILE * TILE <= AO_TILE_PIXELS, "a tile must fit ao_estimate_tile");

/* A thread's share of a pass: the tile rows k, k + threads, k + 2 threads, ... for thread k, row
 * by row, taken in order from `next`. Each thread keeps the same pixels pass after pass, so their
 * sums stay in its own cache (handed round between threads, they crossed caches on every pass);
 * a thread that has finished its share helps with the others'. */
struct share {
    _Alignas(64) atomic_int next;        /* a line of its own: the other threads take from it too */
};

struct ao_render {
    struct ao_render_config config;
    struct ao_accum accum;               /* render thread (and its workers, pixel-disjoint) only */

    /* Triple buffer: the render thread owns frames[back], the consumer frames[front]; `middle`
     * holds the third index, with FRESH set while it is newer than what the consumer has. */
    struct ao_frame frames[3];
    int back, front;
    atomic_uint middle;

    /* Settings and control, under `lock`. */
    pthread_mutex_t lock;
    pthread_cond_t wake;                 /* render thread: settings changed, resume, stop */
    pthread_cond_t finished;             /* ao_render_wait: target reached or stopped */
    struct ao_settings settings;
    uint64_t restarts;
    bool done, stop;
    atomic_uint_fast64_t live_restarts;  /* copies of restarts and stop for the tile loop */
    atomic_bool live_stop;

    /* The pass in flight: written by the render thread before it starts the workers. */
    pthread_mutex_t pass_lock;
    pthread_cond_t pass_start, pass_end;
    uint64_t pass_serial;                /* bumped to start a pass */
    int busy;                            /* workers still in the pass */
    bool quit;                           /* workers exit */
    struct ao_context ctx;
    uint64_t pass, first_sample, pass_restarts;
    int samples, tiles_x, tiles_y;
    struct share *shares;                /* one per thread, the render thread's first */
    atomic_uint_fast64_t eye_rays, shadow_rays;

    pthread_t thread;
    bool started;
    struct ao_frame_info last_info;      /* the render thread's facts when it stopped */
    pthread_t *workers;
    int worker_count;
    atomic_int workers_started;          /* numbers the workers' shares */
};

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static bool aborted(struct ao_render *r)
{
    return atomic_load_explicit(&r->live_stop, memory_order_relaxed) ||
           atomic_load_explicit(&r->live_restarts, memory_order_relaxed) != r->pass_restarts;
}

/* ---- tiles: run by the render thread and every worker ---- */

/* The tiles in thread k's share (see struct share). */
static int share_size(const struct ao_render *r, int k)
{
    int threads = r->config.threads;
    return r->tiles_x * ((r->tiles_y - k + threads - 1) / threads);
}

/* Traces one tile and adds its sums to the accumulation. */
static void render_tile(struct ao_render *r, int column, int row, uint64_t *eye, uint64_t *shadow)
{
    const struct ao_context *ctx = &r->ctx;
    int width = ctx->view.width, height = ctx->view.height;
    struct ao_tile t = {.x0 = column * TILE, .y0 = row * TILE};
    t.x1 = t.x0 + TILE < width ? t.x0 + TILE : width;
    t.y1 = t.y0 + TILE < height ? t.y0 + TILE : height;
    struct ao_vec3 sums[AO_TILE_PIXELS];
    ao_estimate_tile(ctx, &t, r->pass, r->first_sample, r->samples, sums, eye, shadow);
    for (int j = t.y0; j < t.y1; j++)
        for (int i = t.x0; i < t.x1; i++)
            ao_accum_add(&r->accum, (size_t)j * (size_t)width + (size_t)i,
                         sums[(j - t.y0) * (t.x1 - t.x0) + (i - t.x0)], (uint32_t)r->samples);
}

/* Thread `self`'s part of a pass: its own share, then what is left of the others'. */
static void render_tiles(struct ao_render *r, int self)
{
    int threads = r->config.threads;
    uint64_t eye = 0, shadow = 0;
    for (int v = 0; v < threads && !aborted(r); v++) {
        int k = (self + v) % threads, size = share_size(r, k);
        for (;;) {
            int n = atomic_fetch_add_explicit(&r->shares[k].next, 1, memory_order_relaxed);
            if (n >= size || aborted(r))
                break;
            render_tile(r, n % r->tiles_x, k + threads * (n / r->tiles_x), &eye, &shadow);
        }
    }
    atomic_fetch_add_explicit(&r->eye_rays, eye, memory_order_relaxed);
    atomic_fetch_add_explicit(&r->shadow_rays, shadow, memory_order_relaxed);
}

static void *worker_main(void *arg)
{
    struct ao_render *r = arg;
    uint64_t seen = 0;
    int self = 1 + atomic_fetch_add(&r->workers_started, 1);
    ao_tracer_thread_init();
    pthread_mutex_lock(&r->pass_lock);
    for (;;) {
        while (r->pass_serial == seen && !r->quit)
            pthread_cond_wait(&r->pass_start, &r->pass_lock);
        if (r->quit)
            break;
        seen = r->pass_serial;
        pthread_mutex_unlock(&r->pass_lock);
        render_tiles(r, self);
        pthread_mutex_lock(&r->pass_lock);
        if (--r->busy == 0)
            pthread_cond_signal(&r->pass_end);
    }
    pthread_mutex_unlock(&r->pass_lock);
    return NULL;
}

/* Runs one pass on all threads; false when it was aborted by a restart or stop. */
static bool run_pass(struct ao_render *r)
{
    pthread_mutex_lock(&r->pass_lock);
    for (int k = 0; k < r->config.threads; k++)
        atomic_store(&r->shares[k].next, 0);
    r->busy = r->worker_count;
    r->pass_serial++;
    pthread_cond_broadcast(&r->pass_start);
    pthread_mutex_unlock(&r->pass_lock);
    render_tiles(r, 0);
    pthread_mutex_lock(&r->pass_lock);
    while (r->busy > 0)
        pthread_cond_wait(&r->pass_end, &r->pass_lock);
    pthread_mutex_unlock(&r->pass_lock);
    return !aborted(r);
}

/* ---- publishing ---- */

static double rmse(const float *image, const float *reference, size_t count)
{
    double sum = 0.0;
    for (size_t k = 0; k < count; k++) {
        double d = (double)image[k] - (double)reference[k];
        sum += d * d;
    }
    return sqrt(sum / (double)count);
}

/* Resolves the running average into the back frame, fills in info's RMSE, and swaps the frame
 * into the middle slot. */
static void publish(struct ao_render *r, struct ao_frame_info *info)
{
    struct ao_frame *f = &r->frames[r->back];
    size_t count = 3 * (size_t)f->width * (size_t)f->height;
    ao_accum_resolve(&r->accum, f->rgb);
    info->rmse = r->config.reference ? rmse(f->rgb, r->config.reference, count) : NAN;
    f->info = *info;
    unsigned previous = atomic_exchange(&r->middle, (unsigned)r->back | FRESH);
    r->back = (int)(previous & ~(unsigned)FRESH);
}

const struct ao_frame *ao_render_take_frame(struct ao_render *render)
{
    if (!(atomic_load(&render->middle) & FRESH))
        return NULL;
    unsigned previous = atomic_exchange(&render->middle, (unsigned)render->front);
    render->front = (int)(previous & ~(unsigned)FRESH);
    return &render->frames[render->front];
}

/* ---- the render thread ---- */

/* Waits until there is a pass to run; false on stop. Called with r->lock held. */
static bool wait_for_work(struct ao_render *r, const struct ao_frame_info *info)
{
    while (!r->stop && (r->settings.paused || (info->restarts == r->restarts && r->done)))
        pthread_cond_wait(&r->wake, &r->lock);
    return !r->stop;
}

static void *render_main(void *arg)
{
    struct ao_render *r = arg;
    struct ao_frame_info info = {.restarts = UINT64_MAX};
    ao_tracer_thread_init();
    pthread_mutex_lock(&r->lock);
    while (wait_for_work(r, &info)) {
        /* Take the settings; a restart clears the sums. */
        struct ao_settings s = r->settings;
        if (info.restarts != r->restarts) {
            ao_accum_reset(&r->accum);
            info = (struct ao_frame_info){.restarts = r->restarts, .target_spp = r->config.target_spp};
            r->done = false;
        }
        pthread_mutex_unlock(&r->lock);

        /* Run one pass. */
        double start = now_seconds();
        r->ctx.sampling = s.sampling;
        r->ctx.aa = s.aa;
        ao_camera_view(&s.camera, r->config.width, r->config.height, &r->ctx.view);
        r->pass = info.pass;
        r->first_sample = info.spp;
        r->pass_restarts = info.restarts;
        uint32_t left = info.target_spp - info.spp;
        r->samples = (uint32_t)s.spppp < left ? s.spppp : (int)left;
        atomic_store(&r->eye_rays, 0);
        atomic_store(&r->shadow_rays, 0);
        bool complete = run_pass(r);
        info.eye_rays += atomic_load(&r->eye_rays);
        info.shadow_rays += atomic_load(&r->shadow_rays);
        info.seconds += now_seconds() - start;
        info.sampling = s.sampling;
        info.aa = s.aa;

        /* Publish it. */
        if (complete) {
            info.pass++;
            info.spp += (uint32_t)r->samples;
            info.done = info.spp >= info.target_spp;
            publish(r, &info);
            if (r->config.on_pass)
                r->config.on_pass(&info, r->config.user);
        }
        pthread_mutex_lock(&r->lock);
        if (complete && info.done && info.restarts == r->restarts) {
            r->done = true;
            pthread_cond_broadcast(&r->finished);
        }
    }
    r->last_info = info;
    pthread_mutex_unlock(&r->lock);
    return NULL;
}

/* ---- life cycle and control ---- */

static bool allocate(struct ao_render *r)
{
    size_t floats = 3 * (size_t)r->config.width * (size_t)r->config.height;
    if (!ao_accum_init(&r->accum, r->config.width, r->config.height))
        return false;
    for (int k = 0; k < 3; k++) {
        r->frames[k].width = r->config.width;
        r->frames[k].height = r->config.height;
        r->frames[k].rgb = calloc(floats, sizeof(float));
        if (!r->frames[k].rgb) {
            fprintf(stderr, "aoview: out of memory for %dx%d frames\n", r->config.width, r->config.height);
            return false;
        }
    }
    r->workers = calloc((size_t)r->config.threads, sizeof *r->workers);
    r->shares = aligned_alloc(_Alignof(struct share), (size_t)r->config.threads * sizeof *r->shares);
    if (!r->workers || !r->shares) {
        fprintf(stderr, "aoview: out of memory starting the renderer\n");
        return false;
    }
    for (int k = 0; k < r->config.threads; k++)
        atomic_init(&r->shares[k].next, 0);
    return true;
}

struct ao_render *ao_render_create(const struct ao_render_config *config,
                                   const struct ao_settings *settings)
{
    struct ao_render *r = calloc(1, sizeof *r);
    if (!r) {
        fprintf(stderr, "aoview: out of memory starting the renderer\n");
        return NULL;
    }
    r->config = *config;
    r->settings = *settings;
    r->back = 0;
    atomic_init(&r->middle, 1u);
    atomic_init(&r->workers_started, 0);
    r->front = 2;
    r->ctx = (struct ao_context){.scene = config->scene, .tracer = config->tracer,
                                 .ao_distance = config->ao_distance, .seed = config->seed,
                                 .sequence = config->sequence, .below = config->below};
    r->tiles_x = (config->width + TILE - 1) / TILE;
    r->tiles_y = (config->height + TILE - 1) / TILE;
    pthread_mutex_init(&r->lock, NULL);
    pthread_mutex_init(&r->pass_lock, NULL);
    pthread_cond_init(&r->wake, NULL);
    pthread_cond_init(&r->finished, NULL);
    pthread_cond_init(&r->pass_start, NULL);
    pthread_cond_init(&r->pass_end, NULL);
    if (!allocate(r)) {
        ao_render_destroy(r);
        return NULL;
    }
    /* The render thread works tiles too, so threads - 1 workers join it. */
    while (r->worker_count + 1 < config->threads &&
           pthread_create(&r->workers[r->worker_count], NULL, worker_main, r) == 0)
        r->worker_count++;
    r->started = r->worker_count + 1 == config->threads &&
                 pthread_create(&r->thread, NULL, render_main, r) == 0;
    if (!r->started) {
        fprintf(stderr, "aoview: could not start %d render threads\n", config->threads);
        ao_render_destroy(r);
        return NULL;
    }
    return r;
}

/* Stops the render thread and waits for it; the accumulation is then main's to read. */
static void join_render_thread(struct ao_render *render)
{
    ao_render_stop(render);
    if (render->started)
        pthread_join(render->thread, NULL);
    render->started = false;
}

const struct ao_frame *ao_render_resolve_stopped(struct ao_render *render)
{
    join_render_thread(render);
    struct ao_frame *f = &render->frames[render->back];
    size_t pixels = (size_t)f->width * (size_t)f->height;
    uint32_t fewest = UINT32_MAX;
    for (size_t p = 0; p < pixels; p++)
        fewest = render->accum.count[p] < fewest ? render->accum.count[p] : fewest;
    struct ao_frame_info info = render->last_info;
    info.spp = fewest;
    info.done = false;
    ao_accum_resolve(&render->accum, f->rgb);
    info.rmse = render->config.reference ? rmse(f->rgb, render->config.reference, 3 * pixels) : NAN;
    f->info = info;
    return f;
}

void ao_render_destroy(struct ao_render *render)
{
    if (!render)
        return;
    join_render_thread(render);
    pthread_mutex_lock(&render->pass_lock);
    render->quit = true;
    pthread_cond_broadcast(&render->pass_start);
    pthread_mutex_unlock(&render->pass_lock);
    for (int k = 0; k < render->worker_count; k++)
        pthread_join(render->workers[k], NULL);
    pthread_cond_destroy(&render->pass_end);
    pthread_cond_destroy(&render->pass_start);
    pthread_cond_destroy(&render->finished);
    pthread_cond_destroy(&render->wake);
    pthread_mutex_destroy(&render->pass_lock);
    pthread_mutex_destroy(&render->lock);
    for (int k = 0; k < 3; k++)
        free(render->frames[k].rgb);
    free(render->workers);
    free(render->shares);
    ao_accum_finish(&render->accum);
    free(render);
}

void ao_render_get_settings(struct ao_render *render, struct ao_settings *out)
{
    pthread_mutex_lock(&render->lock);
    *out = render->settings;
    pthread_mutex_unlock(&render->lock);
}

/* Bumps the restart counter so that the pass in flight aborts. Called with render->lock held. */
static void restart_locked(struct ao_render *render)
{
    render->restarts++;
    render->done = false;
    atomic_store(&render->live_restarts, render->restarts);
    pthread_cond_broadcast(&render->wake);
}

void ao_render_set_settings(struct ao_render *render, const struct ao_settings *settings)
{
    pthread_mutex_lock(&render->lock);
    const struct ao_settings *old = &render->settings;
    bool changes_estimate = old->sampling != settings->sampling || old->aa != settings->aa ||
                            memcmp(&old->camera, &settings->camera, sizeof old->camera) != 0;
    render->settings = *settings;
    if (changes_estimate)
        restart_locked(render);
    pthread_cond_broadcast(&render->wake);
    pthread_mutex_unlock(&render->lock);
}

void ao_render_restart(struct ao_render *render)
{
    pthread_mutex_lock(&render->lock);
    restart_locked(render);
    pthread_mutex_unlock(&render->lock);
}

bool ao_render_wait(struct ao_render *render)
{
    pthread_mutex_lock(&render->lock);
    while (!render->done && !render->stop)
        pthread_cond_wait(&render->finished, &render->lock);
    bool done = render->done;
    pthread_mutex_unlock(&render->lock);
    return done;
}

void ao_render_stop(struct ao_render *render)
{
    pthread_mutex_lock(&render->lock);
    render->stop = true;
    atomic_store(&render->live_stop, true);
    pthread_cond_broadcast(&render->wake);
    pthread_cond_broadcast(&render->finished);
    pthread_mutex_unlock(&render->lock);
}
