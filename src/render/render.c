/* The render thread: its loop over passes (planned, traced, surveyed and published by pass.c, or
 * with a share by render_share.c), the previews after a restart, and the control the other
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
    while (r->settings.navigating && !r->stop && r->restarts == r->run.pass_restarts)
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
        if (!ao_preview_begin(p, &run->ctx, camera, run->width, run->height, block))
            return true;
        struct ao_frame *f = ao_frames_back(&run->frames, p->width, p->height, 0);
        if (!f)
            return false;
        p->rgb = f->rgb;
        ao_pool_run(run->pool, preview_job, r);
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

/* True while there is no pass to run: paused, or done until the settings change. Called with
 * r->lock held. */
static bool idle(const struct ao_render *r, const struct ao_frame_info *info)
{
    return r->settings.paused || (info->restarts == r->restarts && r->done);
}

/* Waits until there is a pass to run; false on stop. Called with r->lock held. */
static bool wait_for_work(struct ao_render *r, const struct ao_frame_info *info)
{
    while (!r->stop && idle(r, info))
        pthread_cond_wait(&r->wake, &r->lock);
    return !r->stop;
}

/* What a pass is rendered with: the settings, and (with a share, the leader's) restarts, the
 * generation of the sums; `own` counts this process's restarts, which abort its pass. */
struct pass_start {
    struct ao_settings settings;
    uint64_t own, restarts;
};

/* What the render thread carries from one pass to the next: the facts of the last pass (restarts
 * UINT64_MAX before the first run), the next pass's start, and whether the leader of a share began
 * that pass before it published the last (it has taken its settings already). */
struct loop {
    struct ao_frame_info info;
    struct pass_start next;
    bool begun;
};

/* Takes the settings for the next pass and, with a share, begins it on every process (another
 * process than the leader takes part in the leader's gathers while it waits); info: the facts of
 * the last pass. Called with r->lock held, which it releases; false when the share ended the run. */
static bool take_pass(struct ao_render *r, struct pass_start *p, const struct ao_frame_info *info)
{
    p->settings = r->settings;
    p->own = p->restarts = r->restarts;
    pthread_mutex_unlock(&r->lock);
    const struct ao_render_share *share = r->run.config.share;
    if (!share)
        return true;
    for (;;) {
        enum ao_share_step step = share->begin(share->user, AO_SHARE_PASS, &p->settings, &p->restarts);
        if (step != AO_SHARE_GATHER)
            return step == AO_SHARE_PASS;
        if (!ao_render_share_gather(&r->run, info, false))
            return false;
    }
}

/* Whether a pass is due: one the leader began already, or (another process of a share) until the
 * run stops, or once there is work. Called with r->lock held. */
static bool pass_due(struct ao_render *r, struct loop *l)
{
    const struct ao_render_share *share = r->run.config.share;
    return l->begun || (share && share->follows ? !r->stop : wait_for_work(r, &l->info));
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
    return !s->previews || config->share || preview(r, &s->camera, info);
}

/* The leader of a share after a pass that counts: gathers a frame when one is due (for the last
 * pass, when it pauses, or by the share's clock), and begins the next pass before it publishes
 * this one (the others wait for it). False when the share stops or memory is short; *ending when
 * the share ended the run as the next pass was begun (this pass is still reported). */
static bool lead(struct ao_render *r, struct loop *l, bool *ending)
{
    const struct ao_render_share *share = r->run.config.share;
    r->run.ungathered = true;
    pthread_mutex_lock(&r->lock);
    bool pausing = r->settings.paused;
    pthread_mutex_unlock(&r->lock);
    if ((l->info.done || pausing || share->due(share->user)) &&
        !ao_render_share_frame(&r->run, &l->next.settings, &l->info))
        return false;
    if (!l->info.done) {
        pthread_mutex_lock(&r->lock);
        if (r->stop || idle(r, &l->info))
            pthread_mutex_unlock(&r->lock);
        else if (!(l->begun = take_pass(r, &l->next, &l->info)))
            *ending = true;
    }
    return true;
}

/* One pass of the loop, its settings taken (l->next): starts a run when they restarted it, plans
 * the pass (from every process's pixels), runs and surveys it (with a share, every process's
 * tiles), publishes it (with a share the leader gathers frames, the others keep none) and reports
 * it; *finishes when it ends the run, `own` the restarts it ran at. False when the run must stop:
 * memory short, or the share ended it. Called without r->lock. */
static bool step(struct ao_render *r, struct loop *l, bool *finishes, uint64_t *own)
{
    struct ao_run *run = &r->run;
    const struct ao_render_share *share = run->config.share;
    bool follows = share && share->follows, leads = share && !follows;
    struct ao_settings s = l->next.settings;
    uint64_t restarts = l->next.restarts;
    *own = l->next.own;
    l->begun = false;
    run->ctx.sampling = s.sampling;
    run->ctx.aa = s.aa;
    run->ctx.output = s.output;
    run->ctx.shading = s.shading;
    run->pass_restarts = *own;
    if (l->info.restarts != restarts && !start_run(r, &s, restarts, &l->info))
        return false;

    /* Plan the pass: its tiles, its samples (from every process's pixels). */
    uint64_t pixels;
    double planned = ao_phases_clock();
    ao_phases_begin();
    if (!ao_pass_plan(run, s.adaptive, &pixels))
        return false;
    uint32_t spppp = ao_pass_prepare(run, &s, pixels);
    ao_phases_add(AO_PHASE_PLAN, ao_phases_clock() - planned);

    /* Run it, unless nothing is left to sample (adaptive sampling was just turned on), and survey it. */
    bool counts = false;
    uint64_t rays[2] = {0, 0};
    double seconds = 0.0;
    if (pixels) {
        double start = ao_clock_seconds();
        ao_camera_view(&s.camera, run->width, run->height, &run->ctx.view);
        atomic_store(&run->eye_rays, 0);
        atomic_store(&run->shadow_rays, 0);
        bool finished = share ? ao_render_share_pass(run) : ao_pass_run(run);
        rays[0] = atomic_load(&run->eye_rays);
        rays[1] = atomic_load(&run->shadow_rays);
        seconds = ao_clock_seconds() - start;
        double surveyed = ao_phases_clock();
        if (!ao_pass_survey(run, &l->info, s.adaptive, finished, rays, seconds, spppp, &counts))
            return false;
        ao_phases_add(AO_PHASE_SURVEY, ao_phases_clock() - surveyed);
    }

    /* Publish and report it. */
    bool ending = false;
    if (counts && !follows) {
        double published = ao_phases_clock();
        if (leads ? !lead(r, l, &ending) : !ao_pass_publish(run, &l->info))
            return false;
        if (run->config.on_pass)
            run->config.on_pass(&l->info, run->config.user);
        ao_phases_add(AO_PHASE_PUBLISH, ao_phases_clock() - published);
    }
    if (pixels)
        ao_phases_say(run->config.threads, l->info.pass, rays[0] + rays[1], seconds);
    if (ending)
        return false;

    /* Between passes nothing traces: the moment to start a better BVH's build (after the first
     * pass, published or cut short by a move, while there is more to render) and to move to it
     * once built, with no restart: the BVH never changes an image. */
    if (run->config.upgrade && pixels && !l->info.done)
        ao_tracer_switch(run->config.upgrade);

    /* Done: the image is finished until the settings change (the leader gathers what it has not
     * before it idles); another process's run goes on until the leader ends it. */
    *finishes = (counts ? l->info.done : !pixels) && !follows;
    if (leads && run->ungathered && !l->begun) {
        pthread_mutex_lock(&r->lock);
        bool idles = !r->stop && ((*finishes && *own == r->restarts) || idle(r, &l->info));
        pthread_mutex_unlock(&r->lock);
        if (idles && !ao_render_share_frame(run, &s, &l->info))
            return false;
    }
    return true;
}

/* The render thread: pass after pass while there is work, until the renderer stops. Every way out
 * of the loop goes through one unwind: the stop (already asked for, or asked here when a pass
 * failed or the share ended the run), the facts kept for ao_render_resolve_stopped, and with a
 * share the end told to the other processes. */
static void *render_main(void *arg)
{
    struct ao_render *r = arg;
    struct loop l = {.info = {.restarts = UINT64_MAX}};
    ao_text_route(r->sink);
    ao_tracer_thread_init();
    pthread_mutex_lock(&r->lock);
    while (pass_due(r, &l)) {
        bool finishes = false, taken = l.begun || take_pass(r, &l.next, &l.info);
        uint64_t own = 0;
        if (l.begun)
            pthread_mutex_unlock(&r->lock);
        if (!taken || !step(r, &l, &finishes, &own)) {
            ao_render_stop(r);
            pthread_mutex_lock(&r->lock);
            break;
        }
        pthread_mutex_lock(&r->lock);
        if (finishes && own == r->restarts) {
            r->done = true;
            pthread_cond_broadcast(&r->finished);
        }
    }
    r->last_info = l.info;
    pthread_mutex_unlock(&r->lock);
    const struct ao_render_share *share = r->run.config.share;
    if (share)
        share->end(share->user);
    return NULL;
}

/* ---- life cycle and control ---- */

/* The context's cut: the pass in flight is aborted (without a share, whose loans are traced to the
 * end). */
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
    run->ctx = (struct ao_context){.scene = config->scene, .tracer = config->tracer,
                                   .ao_distance = config->ao_distance, .seed = config->seed,
                                   .sequence = config->sequence, .below = config->below,
                                   .cut = config->share ? NULL : tile_cut, .cut_user = run};
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->wake, NULL);
    pthread_cond_init(&r->finished, NULL);
    run->lanes = aligned_alloc(_Alignof(struct ao_lane), (size_t)config->threads * sizeof *run->lanes);
    if (!run->lanes) {
        ao_text_report("aoview: out of memory starting the renderer");
        ao_render_destroy(r);
        return NULL;
    }
    for (int k = 0; k < config->threads; k++)
        atomic_init(&run->lanes[k].next, 0);
    /* The render thread works tiles too, so the team has threads - 1 workers besides it. */
    if (!ao_pass_allocate(run) || !(run->pool = ao_pool_create(config->threads, ao_tracer_thread_init))) {
        ao_render_destroy(r);
        return NULL;
    }
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

/* The RMSE of count values of image against reference. */
static double rmse(const float *image, const float *reference, size_t count)
{
    double sum = 0.0;
    for (size_t k = 0; k < count; k++) {
        double d = (double)image[k] - (double)reference[k];
        sum += d * d;
    }
    return sqrt(sum / (double)count);
}

const struct ao_frame *ao_render_resolve_stopped(struct ao_render *render)
{
    join_render_thread(render);
    struct ao_run *run = &render->run;
    struct ao_frame_info info = render->last_info;
    if (!run->accum.count)
        return NULL;
    if (run->config.share) { /* every process's tiles, not traced in this run black */
        if (!ao_render_share_gather(run, &info, true) || run->config.share->follows)
            return NULL;
        /* the frame gather filled, still the back one (already that size) */
        struct ao_frame *f = ao_frames_back(&run->frames, run->width, run->height, run->tiles_x * run->tiles_y);
        f->info.done = false;
        return f;
    }
    for (int t = 0; t < run->tiles_x * run->tiles_y; t++)
        if (run->tiles[t].passes == 0) /* not traced in this run: sums of an earlier one */
            ao_pass_clear_tile(run, t);
    struct ao_frame *f = ao_pass_resolve(run, &info);
    if (!f)
        return NULL;
    size_t pixels = (size_t)f->width * (size_t)f->height;
    uint32_t most = 0;
    uint64_t samples = 0;
    for (size_t p = 0; p < pixels; p++) {
        most = run->accum.count[p] > most ? run->accum.count[p] : most;
        samples += run->accum.count[p];
    }
    f->info.spp = most;
    f->info.mean_spp = (double)samples / (double)pixels;
    f->info.done = false;
    f->info.rmse = ao_pass_has_reference(run) ? rmse(f->rgb, run->config.reference, 3 * pixels) : NAN;
    return f;
}

void ao_render_destroy(struct ao_render *render)
{
    if (!render)
        return;
    join_render_thread(render);
    ao_pool_destroy(render->run.pool);
    pthread_cond_destroy(&render->finished);
    pthread_cond_destroy(&render->wake);
    pthread_mutex_destroy(&render->lock);
    ao_frames_finish(&render->run.frames);
    free(render->run.lanes);
    ao_pass_free(&render->run);
    free(render);
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
