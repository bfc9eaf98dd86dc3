/* The front ends' shared parts; see app.h. */
#include "app.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "config.h"
#include "headless.h"
#include "heatmap.h"
#include "image.h"
#include "notes.h"

/* The headless progress bar redraws at most this often (and once more at the end). */
static const double BAR_SECONDS = 0.1;

double ao_app_mrays_per_second(const struct ao_frame_info *info)
{
    return info->seconds > 0.0 ? (double)(info->eye_rays + info->shadow_rays) / info->seconds / 1e6 : 0.0;
}

static double monotonic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Redraws the progress bar: filled by the share of the run's time gone where the time left is
 * estimated, else by spp; at most every BAR_SECONDS, and at the end. */
static void draw_bar(struct ao_reporter *rep, const struct ao_frame_info *info)
{
    ao_progress_add(&rep->eta, info);
    double now = monotonic_seconds();
    if (!info->done && rep->drawn_at > 0.0 && now - rep->drawn_at < BAR_SECONDS)
        return;
    rep->drawn_at = now;
    double left = ao_progress_left(&rep->eta, info);
    double share = !isnan(left) && info->seconds + left > 0.0 ? info->seconds / (info->seconds + left)
                                                              : (double)info->spp / info->target_spp;
    int filled = (int)(30.0 * (share < 1.0 ? share : 1.0));
    char left_text[32];
    ao_progress_format(left, left_text, sizeof left_text);
    fprintf(stderr, "\r[%.*s%*s] spp %u/%u  error %.2f %%  %.1f s  %s  %.1f Mrays/s \033[K", filled,
            "##############################", 30 - filled, "", info->spp, info->target_spp, 100.0 * info->error,
            info->seconds, left_text, ao_app_mrays_per_second(info));
    if (info->done)
        fputc('\n', stderr);
}

void ao_app_on_pass(const struct ao_frame_info *info, void *user)
{
    struct ao_reporter *rep = user;
    if (rep->stats && !rep->stats_failed) {
        if (rep->side)
            fprintf(rep->stats, "%s,", rep->side);
        fprintf(rep->stats, "%u,%u,%.6f,%llu,%llu,%.3f", info->pass, info->spp, info->seconds,
                (unsigned long long)info->eye_rays, (unsigned long long)info->shadow_rays,
                ao_app_mrays_per_second(info));
        if (!isnan(info->rmse))
            fprintf(rep->stats, ",%.9g", info->rmse);
        fprintf(rep->stats, ",%.3f,%.6g,%.4f\n", info->mean_spp, info->error, info->converged);
        if (fflush(rep->stats) != 0) {
            fprintf(stderr, "%s: write failed\n", rep->stats_path);
            rep->stats_failed = true;
        }
    }
    if (rep->progress)
        draw_bar(rep, info);
    /* Equal time: end the side at the pass end nearest stop_at, taking the next pass to last as
     * long as this one (time_limit ends it at the first end past stop_at otherwise). */
    struct ao_render *render = atomic_load(&rep->render);
    if (render && rep->stop_at > 0.0 && !info->done &&
        info->seconds + 0.5 * (info->seconds - rep->pass_end) >= rep->stop_at)
        ao_render_stop(render);
    rep->pass_end = info->seconds;
    if (rep->notify)
        rep->notify();
}

/* The difference view of frame from reference as a heat map PNG with its colour bar. */
static bool write_difference_png(const char *path, const struct ao_frame *frame, const float *reference)
{
    float *heat = malloc(3 * sizeof *heat * (size_t)frame->width * (size_t)frame->height);
    if (!heat) {
        fprintf(stderr, "aoview: %s: out of memory for the difference image\n", path);
        return false;
    }
    ao_heatmap_pixels(frame->rgb, reference, frame->width, frame->height, heat);
    bool ok = ao_headless_write_heatmap(path, heat, frame->width, frame->height, &ao_heatmap_difference,
                                        "|image - reference|");
    free(heat);
    return ok;
}

bool ao_app_write_output(const char *path, const struct ao_frame *frame, const char *scene, uint64_t seed,
                         const float *difference)
{
    if (ao_image_has_extension(path, ".png"))
        return difference ? write_difference_png(path, frame, difference)
                          : ao_headless_write_png(path, frame->rgb, frame->width, frame->height);
    struct ao_notes notes;
    ao_notes_make(&notes, &frame->info, scene, seed);
    return ao_image_write_linear(path, frame->rgb, frame->width, frame->height, notes.notes,
                                 notes.count);
}

static void *watch_signals(void *arg)
{
    struct ao_interrupt *in = arg;
    int sig;
    if (sigwait(&in->signals, &sig) != 0)
        return NULL;
    if (!atomic_load(&in->graceful))
        _exit(128 + sig);
    atomic_store(&in->caught, sig);
    if (in->render)
        ao_render_stop(in->render);
    if (sigwait(&in->signals, &sig) == 0)
        _exit(128 + sig);
    return NULL;
}

/* Their disposition goes back to default first: a shell starts background jobs with SIGINT
 * ignored, and an ignored signal never reaches sigwait. */
void ao_app_block_signals(struct ao_app *app)
{
    struct ao_interrupt *in = &app->interrupt;
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    sigemptyset(&in->signals);
    sigaddset(&in->signals, SIGINT);
    sigaddset(&in->signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &in->signals, NULL);
    /* A write to a closed socket or pipe (an X server killed under the window, a --stats FIFO
     * whose reader left) then fails and is reported, instead of killing aoview silently. */
    signal(SIGPIPE, SIG_IGN);
}

bool ao_app_start_watcher(struct ao_app *app, struct ao_render *render)
{
    pthread_t thread;
    app->interrupt.render = render;
    if (pthread_create(&thread, NULL, watch_signals, &app->interrupt) != 0) {
        fprintf(stderr, "aoview: could not start the signal watcher thread\n");
        return false;
    }
    pthread_detach(thread);
    return true;
}

/* Reads --reference and checks it matches the image size. */
static float *load_reference(const char *path, int width, int height)
{
    float *rgb = NULL;
    int w, h;
    if (!ao_image_read_linear(path, &rgb, &w, &h))
        return NULL;
    if (w != width || h != height) {
        fprintf(stderr, "--reference: %s is %dx%d but the image is %dx%d\n", path, w, h, width, height);
        free(rgb);
        return NULL;
    }
    return rgb;
}

int ao_app_load(struct ao_app *app, const struct ao_options *opts, struct ao_render_config *config,
                struct ao_settings *settings)
{
    /* Scene, size, tracer. */
    if (!ao_scene_load_budget(&app->scene, opts->scene_path ? opts->scene_path : AO_DEFAULT_SCENE, opts->scene_budget))
        return AO_EXIT_RUNTIME;
    int width = opts->width ? opts->width : app->scene.width ? app->scene.width : 640;
    int height = opts->height ? opts->height : app->scene.height ? app->scene.height : 480;
    if (opts->reference_path && !(app->reference = load_reference(opts->reference_path, width, height)))
        return AO_EXIT_RUNTIME;
    if (!(app->tracer = ao_tracer_create(&app->scene)))
        return AO_EXIT_RUNTIME;
    if (app->scene.degenerate_count && !opts->quiet)
        fprintf(stderr, "aoview: skipped %zu degenerate triangles\n", app->scene.degenerate_count);
    if (!opts->quiet)
        fprintf(stderr, "aoview: %s: %zu triangles, %zu spheres, traced by %s\n", app->scene.name,
                app->scene.triangle_count, app->scene.sphere_count, ao_tracer_backend(app->tracer));

    /* Stats file. */
    app->reporter.stats_path = opts->stats_path;
    if (opts->stats_path) {
        if (!(app->reporter.stats = fopen(opts->stats_path, "w"))) {
            fprintf(stderr, "--stats: cannot write %s: %s\n", opts->stats_path, strerror(errno));
            return AO_EXIT_RUNTIME;
        }
        fprintf(app->reporter.stats, "%spass,spp,seconds,eye_rays,shadow_rays,mrays_per_s%s,mean_spp,error,converged\n",
                opts->compare ? "side," : "", app->reference ? ",rmse" : "");
    }

    /* Renderer. */
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    *config = (struct ao_render_config){
        .scene = &app->scene, .tracer = app->tracer, .width = width, .height = height,
        .threads = opts->threads ? opts->threads : (cores > 0 ? (int)cores : 1),
        .seed = opts->seed, .target_spp = opts->spp, .target_error = opts->target_error,
        .time_limit = opts->time_limit,
        .ao_distance = isnan(opts->ao_distance) ? app->scene.ao_distance : opts->ao_distance,
        .sequence = opts->sequence, .below = opts->below,
        .reference = app->reference, .on_pass = ao_app_on_pass, .user = &app->reporter};
    *settings = (struct ao_settings){.sampling = opts->sampling, .aa = opts->aa, .spppp = (int)opts->spppp,
                                     .adaptive = opts->adaptive, .camera = app->scene.camera,
                                     .output = opts->view == AO_VIEW_MODE_NORMALS ? AO_OUTPUT_NORMALS : AO_OUTPUT_AO,
                                     .shading = opts->shading};
    struct ao_view view;
    if (!ao_camera_view(&settings->camera, width, height, &view)) {
        fprintf(stderr, "%s: the camera cannot form an image\n", app->scene.name);
        return AO_EXIT_RUNTIME;
    }
    return 0;
}

bool ao_app_run_window(struct ao_app *app, const struct ao_options *opts, const struct ao_window_info *info,
                       int *status)
{
    enum ao_window_result result = ao_window_run(app->render, info);
    if (result != AO_WINDOW_NO_DISPLAY) {
        *status = result == AO_WINDOW_OK ? 0 : AO_EXIT_RUNTIME;
        return true;
    }
    fprintf(stderr, "aoview: no display available; rendering headless to %s\n",
            opts->output ? opts->output : "aoview.png");
    return false;
}

bool ao_app_wait(struct ao_app *app, int *sig)
{
    bool finished = ao_render_wait(app->render);
    *sig = atomic_load(&app->interrupt.caught);
    return finished;
}

int ao_app_write(struct ao_app *app, const struct ao_options *opts, const struct ao_frame *frame, const char *why,
                 bool last_row, int status)
{
    const char *output = opts->output ? opts->output : "aoview.png";
    if (why && frame) {
        fprintf(stderr, "\naoview: %s at %u spp\n", why, frame->info.spp);
        if (last_row)
            ao_app_on_pass(&frame->info, &app->reporter);
    }
    const float *difference = opts->view == AO_VIEW_MODE_DIFFERENCE ? app->reference : NULL;
    if (!frame || !ao_app_write_output(output, frame, app->scene.name, opts->seed, difference))
        return AO_EXIT_RUNTIME;
    if (!opts->quiet)
        fprintf(stderr, "aoview: wrote %s (%u spp, %.2f s, %.1f Mrays/s)\n", output, frame->info.spp,
                frame->info.seconds, ao_app_mrays_per_second(&frame->info));
    return status;
}

int ao_app_finish(struct ao_app *app, const struct ao_options *opts, int status)
{
    ao_render_destroy(app->render);
    app->render = NULL;
    if (app->reporter.stats && fclose(app->reporter.stats) != 0 && !app->reporter.stats_failed) {
        fprintf(stderr, "%s: write failed\n", opts->stats_path);
        app->reporter.stats_failed = true;
    }
    if (app->reporter.stats_failed && status == 0)
        status = AO_EXIT_RUNTIME;
    ao_tracer_destroy(app->tracer);
    ao_scene_finish(&app->scene);
    free(app->reference);
    return status;
}
