/* The render thread: its loop over passes (planned, traced, surveyed and published by pass.c, run
 * and published the way of its share: render_share.h), the previews after a restart, and the control the other
 * threads have over it (settings, restarts, stop); see render.h. */
#include "render.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "pass.h"
#include "phases.h"
#include "preview.h"
#include "render_share.h"
#include "text.h"
#include "tracer.h"

struct ao_render {
    struct ao_run run;                   /* what the passes read and write: render thread's */
    struct ao_run_share *share;          /* the solo share, or render_share.c's with the config's */

    /* Settings and control, under `lock`. */
    pthread_mutex_t lock;
    pthread_cond_t wake;                 /* render thread: settings changed, resume, stop */
    pthread_cond_t finished;             /* ao_render_wait: target reached or stopped */
    struct ao_settings settings;
    uint64_t restarts;
    bool done, stop;

    struct ao_preview preview;           /* the preview in flight */
    pthread_t thread;
    bool started;
    struct ao_frame_info last_info;      /* the render thread's facts when it stopped */
    const struct ao_text_sink *sink;     /* ao_render_create's caller's, the render thread's route */
};

/* ---- previews: run by the render thread between a restart and the first pass ---- */

/* ao_preview_trace's stop. */
static bool preview_stops(void *user)
{
    return ao_pass_aborted(user);
}

/* The team's job for a preview. */
static void preview_job(void *user, int self)
{
    (void)self;
    struct ao_render *r = user;
    ao_preview_trace(&r->preview, preview_stops, &r->run);
}

/* While the camera is being moved, no preview finer than cells of a quarter of the first's: each
 * move restarts the run before a finer one would be done (at 3840x2160, cells of 8 pixels take
 * some 30 ms, moves come every 16 ms), so that tracing it only takes cores from the window. Waits
 * while the settings say so and nothing restarts or stops the run; true when the previews may go
 * on. Render thread. */
static bool navigation_allows(struct ao_render *r, int first, int block)
{
    if (block >= first / 4)
        return true;
    pthread_mutex_lock(&r->lock);
    while (r->settings.navigating && !r->stop && r->restarts == r->run.pass.restarts)
        pthread_cond_wait(&r->wake, &r->lock);
    pthread_mutex_unlock(&r->lock);
    return !ao_pass_aborted(&r->run);
}

/* Traces and publishes the previews of the run that begins with info (pass 0) and camera, coarse
 * to fine, until the first full pass is due or a restart or stop aborts one; false when memory is
 * short. */
static bool preview(struct ao_render *r, const struct ao_camera *camera, const struct ao_frame_info *info)
{
    struct ao_run *run = &r->run;
    int first = ao_preview_first_block(run->width, run->height);
    for (int block = first; block > 1 && !ao_pass_aborted(run) && navigation_allows(r, first, block);
         block = ao_preview_next_block(block)) {
        struct ao_preview *p = &r->preview;
        if (!ao_preview_begin(p, &run->pass.ctx, camera, run->width, run->height, block))
            return true;
        struct ao_frame *f = ao_frames_back(&run->frames, p->width, p->height, 0);
        if (!f)
            return false;
        p->rgb = f->rgb;
        ao_pool_run(run->pass.pool, preview_job, r);
        if (ao_pass_aborted(run))
            break;
        f->tile = AO_TILE;
        f->tiles_x = f->tiles_y = 0;
        f->block = block;
        f->image_width = run->width;
        f->image_height = run->height;
        f->info = *info;
        ao_frames_publish(&run->frames);
        if (run->config.on_preview)
            run->config.on_preview(info, run->config.user);
    }
    return true;
}

/* ---- the render thread ---- */

/* True while there is no pass to run: paused, or done until the settings change (neither, when
 * the share paces the passes). Called with r->lock held. */
static bool idle(const struct ao_render *r, const struct ao_frame_info *info)
{
    return !r->share->paced && (r->settings.paused || (info->restarts == r->restarts && r->done));
}

/* Waits until there is a pass to run; false on stop. Called with r->lock held. */
static bool wait_for_work(struct ao_render *r, const struct ao_frame_info *info)
{
    while (!r->stop && idle(r, info))
        pthread_cond_wait(&r->wake, &r->lock);
    return !r->stop;
}

/* Whether a pass is due: one the share began already, or once there is work. Called with r->lock
 * held. */
static bool pass_due(struct ao_render *r, const struct ao_frame_info *info)
{
    return r->share->begun(r->share) || wait_for_work(r, info);
}

/* Takes the settings for the next pass and begins it (the share's: see struct ao_run_share); info:
 * the facts of the last pass. Called with r->lock held, which it releases; false when the share
 * ended the run. */
static bool take_pass(struct ao_render *r, struct ao_pass_start *p, const struct ao_frame_info *info)
{
    p->settings = r->settings;
    p->own = p->restarts = r->restarts;
    pthread_mutex_unlock(&r->lock);
    return r->share->begin(r->share, &r->run, p, info);
}

/* struct ao_run_loop's hooks, each under r->lock. */
static bool loop_paused(void *render)
{
    struct ao_render *r = render;
    pthread_mutex_lock(&r->lock);
    bool paused = r->settings.paused;
    pthread_mutex_unlock(&r->lock);
    return paused;
}

static bool loop_take(void *render, const struct ao_frame_info *info, struct ao_pass_start *p)
{
    struct ao_render *r = render;
    pthread_mutex_lock(&r->lock);
    bool due = !r->stop && !idle(r, info);
    if (due) {
        p->settings = r->settings;
        p->own = p->restarts = r->restarts;
    }
    pthread_mutex_unlock(&r->lock);
    return due;
}

static bool loop_rests(void *render, const struct ao_frame_info *info, bool finishes, uint64_t own)
{
    struct ao_render *r = render;
    pthread_mutex_lock(&r->lock);
    bool rests = !r->stop && ((finishes && own == r->restarts) || idle(r, info));
    pthread_mutex_unlock(&r->lock);
    return rests;
}

/* Starts a run of the settings s (restarts `restarts`) at their size, its facts in *info, and
 * traces its previews; false when memory is short. */
static bool start_run(struct ao_render *r, const struct ao_settings *s, uint64_t restarts, struct ao_frame_info *info)
{
    const struct ao_render_config *config = &r->run.config;
    if (!ao_pass_restart(&r->run, s->width, s->height))
        return false;
    /* Nothing measured yet: the previews carry these facts. */
    *info = (struct ao_frame_info){.restarts = restarts, .target_spp = config->target_spp,
                                   .target_error = config->target_error, .time_limit = config->time_limit,
                                   .pixels = (uint64_t)s->width * (uint64_t)s->height, .error = NAN,
                                   .converged = NAN, .rmse = NAN,
                                   .sampling = s->sampling, .aa = s->aa, .output = s->output, .shading = s->shading};
    return !s->previews || preview(r, &s->camera, info);
}

/* One pass of the loop, begun with start p: starts a run when p restarted it, plans the pass (from
 * every process's pixels), runs and surveys it, publishes and reports it (all three the share's
 * way); *finishes when it ends the run. False when the run must stop: memory short, or the share
 * ended it. Called without r->lock. */
static bool step(struct ao_render *r, const struct ao_pass_start *p, struct ao_frame_info *info, bool *finishes)
{
    struct ao_run *run = &r->run;
    struct ao_run_share *share = r->share;
    const struct ao_settings *s = &p->settings;
    run->pass.ctx.sampling = s->sampling;
    run->pass.ctx.aa = s->aa;
    run->pass.ctx.output = s->output;
    run->pass.ctx.shading = s->shading;
    run->pass.restarts = p->own;
    if (info->restarts != p->restarts && !start_run(r, s, p->restarts, info))
        return false;

    /* Plan the pass: its tiles, its samples (from every process's pixels). */
    uint64_t pixels;
    double planned = ao_phases_clock();
    ao_phases_begin();
    if (!ao_pass_plan(run, s->adaptive, &pixels))
        return false;
    struct ao_pass_result result = {.spppp = ao_pass_prepare(run, s, pixels)};
    ao_phases_add(AO_PHASE_PLAN, ao_phases_clock() - planned);

    /* Run it, unless nothing is left to sample (adaptive sampling was just turned on), and survey it. */
    bool counts = false;
    if (pixels) {
        double start = ao_clock_seconds();
        ao_camera_view(&s->camera, run->width, run->height, &run->pass.ctx.view);
        atomic_store(&run->pass.eye_rays, 0);
        atomic_store(&run->pass.shadow_rays, 0);
        result.finished = share->run(share, run);
        result.rays[0] = atomic_load(&run->pass.eye_rays);
        result.rays[1] = atomic_load(&run->pass.shadow_rays);
        result.seconds = ao_clock_seconds() - start;
        double surveyed = ao_phases_clock();
        if (!ao_pass_survey(run, info, s->adaptive, &result, &counts))
            return false;
        ao_phases_add(AO_PHASE_SURVEY, ao_phases_clock() - surveyed);
    }

    /* Publish and report it. */
    bool ending = false;
    if (counts) {
        double published = ao_phases_clock();
        if (!share->publish(share, run, s, info, &ending))
            return false;
        ao_phases_add(AO_PHASE_PUBLISH, ao_phases_clock() - published);
    }
    if (pixels)
        ao_phases_say(run->config.threads, info->pass, result.rays[0] + result.rays[1], result.seconds);
    if (ending)
        return false;

    /* Between passes nothing traces: the moment to start a better BVH's build (after the first
     * pass, published or cut short by a move, while there is more to render) and to move to it
     * once built, with no restart: the BVH never changes an image. */
    if (run->config.upgrade && pixels && !info->done)
        ao_tracer_switch(run->config.upgrade);

    /* Done: the image is finished until the settings change (unless the share paces the passes). */
    *finishes = (counts ? info->done : !pixels) && !share->paced;
    return share->rest(share, run, s, info, *finishes, p->own);
}

/* The render thread: pass after pass while there is work, until the renderer stops. Every way out
 * of the loop goes through one unwind: the stop (already asked for, or asked here when a pass
 * failed or the share ended the run), the facts kept for ao_render_resolve_stopped, and the
 * share's end. */
static void *render_main(void *arg)
{
    struct ao_render *r = arg;
    struct ao_frame_info info = {.restarts = UINT64_MAX};   /* the last pass's facts */
    ao_text_route(r->sink);
    ao_tracer_thread_init();
    pthread_mutex_lock(&r->lock);
    while (pass_due(r, &info)) {
        struct ao_pass_start p;
        bool finishes = false;
        if (!take_pass(r, &p, &info) || !step(r, &p, &info, &finishes)) {
            ao_render_stop(r);
            pthread_mutex_lock(&r->lock);
            break;
        }
        pthread_mutex_lock(&r->lock);
        if (finishes && p.own == r->restarts) {
            r->done = true;
            pthread_cond_broadcast(&r->finished);
        }
    }
    r->last_info = info;
    pthread_mutex_unlock(&r->lock);
    r->share->end(r->share);
    return NULL;
}

/* ---- life cycle and control ---- */

/* The context's cut: the pass in flight is aborted (an aoview-mpi share's has none: its loans are
 * traced to the end). */
static bool tile_cut(const void *run)
{
    return ao_pass_aborted(run);
}

struct ao_render *ao_render_create(const struct ao_render_config *config,
                                   const struct ao_settings *settings)
{
    struct ao_render *r = calloc(1, sizeof *r);
    if (!r) {
        ao_text_report("aoview: out of memory starting the renderer");
        return NULL;
    }
    struct ao_run *run = &r->run;
    run->config = *config;
    r->settings = *settings;
    run->width = settings->width;
    run->height = settings->height;
    ao_frames_init(&run->frames);
    run->pass.ctx = (struct ao_context){.scene = config->scene, .tracer = config->tracer,
                                   .ao_distance = config->ao_distance, .seed = config->seed,
                                   .sequence = config->sequence, .below = config->below,
                                   .cut = tile_cut, .cut_user = run};
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->wake, NULL);
    pthread_cond_init(&r->finished, NULL);
    run->pass.lanes = aligned_alloc(_Alignof(struct ao_lane), (size_t)config->threads * sizeof *run->pass.lanes);
    if (!run->pass.lanes) {
        ao_text_report("aoview: out of memory starting the renderer");
        ao_render_destroy(r);
        return NULL;
    }
    for (int k = 0; k < config->threads; k++)
        atomic_init(&run->pass.lanes[k].next, 0);
    /* The render thread works tiles too, so the team has threads - 1 workers besides it. */
    struct ao_run_loop loop = {.paused = loop_paused, .take = loop_take, .rests = loop_rests, .render = r};
    if (!ao_pass_allocate(run) || !(run->pass.pool = ao_pool_create(config->threads, ao_tracer_thread_init)) ||
        !(r->share = config->share ? ao_render_share_create(run, config->share, &loop) : ao_solo_share())) {
        ao_render_destroy(r);
        return NULL;
    }
    run->share = r->share;
    r->sink = ao_text_current();
    r->started = pthread_create(&r->thread, NULL, render_main, r) == 0;
    if (!r->started) {
        ao_text_report("aoview: could not start the render thread");
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
    struct ao_run *run = &render->run;
    struct ao_frame_info info = render->last_info;
    if (!run->accum.count)
        return NULL;
    return run->share->stopped(run->share, run, &info);
}

void ao_render_destroy(struct ao_render *render)
{
    if (!render)
        return;
    join_render_thread(render);
    ao_pool_destroy(render->run.pass.pool);
    if (render->share)
        render->share->destroy(render->share);
    pthread_cond_destroy(&render->finished);
    pthread_cond_destroy(&render->wake);
    pthread_mutex_destroy(&render->lock);
    ao_frames_finish(&render->run.frames);
    free(render->run.pass.lanes);
    ao_pass_free(&render->run);
    free(render);
}

uint32_t ao_render_first_pass_spp(uint32_t spppp)
{
    return spppp ? spppp : AO_AUTO_PER_RAY;
}

const struct ao_frame *ao_render_take_frame(struct ao_render *render)
{
    return ao_frames_take(&render->run.frames);
}

int ao_render_take_log(struct ao_render *render, struct ao_frame_info *out, int most)
{
    return ao_frames_take_log(&render->run.frames, out, most);
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
    atomic_store(&render->run.live_restarts, render->restarts);
    pthread_cond_broadcast(&render->wake);
}

bool ao_render_set_settings(struct ao_render *render, const struct ao_settings *settings)
{
    pthread_mutex_lock(&render->lock);
    const struct ao_settings *old = &render->settings;
    bool changes_estimate = old->width != settings->width || old->height != settings->height ||
                            old->sampling != settings->sampling || old->aa != settings->aa ||
                            old->output != settings->output || old->shading != settings->shading ||
                            memcmp(&old->camera, &settings->camera, sizeof old->camera) != 0;
    if (old->adaptive != settings->adaptive) /* what is left to sample changes */
        render->done = false;
    render->settings = *settings;
    if (changes_estimate)
        restart_locked(render);
    pthread_cond_broadcast(&render->wake);
    pthread_mutex_unlock(&render->lock);
    return changes_estimate;
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
    atomic_store(&render->run.live_stop, true);
    pthread_cond_broadcast(&render->wake);
    pthread_cond_broadcast(&render->finished);
    pthread_mutex_unlock(&render->lock);
}
