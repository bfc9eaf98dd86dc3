/* The front ends' shared parts; see app.h. */
#include "app.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "clock.h"
#include "config.h"
#include "file.h"
#include "headless.h"
#include "heatmap.h"
#include "image.h"
#include "notes.h"
#include "options.h"
#include "text.h"

/* The headless progress bar redraws at most this often (and once more at the end). */
static const double BAR_SECONDS = 0.1;

double ao_app_mrays_per_second(const struct ao_frame_info *info)
{
    return info->seconds > 0.0 ? (double)(info->eye_rays + info->shadow_rays) / info->seconds / 1e6 : 0.0;
}

/* Redraws the progress bar: filled, and its percentage, by the share of the run done
 * (ao_progress_share: never back, full only once done), the samples (ao_progress_format_spp), the
 * error ("--" while not known), the seconds, the time left and the rate, the normals view without
 * the AO estimate's error, time left and rate (as the window's status); at most every
 * BAR_SECONDS, and at the end. */
static void draw_bar(struct ao_reporter *rep, const struct ao_frame_info *info)
{
    ao_progress_add(&rep->eta, info);
    double share = ao_progress_share(&rep->eta, info), now = ao_clock_seconds();
    if (!info->done && rep->drawn_at > 0.0 && now - rep->drawn_at < BAR_SECONDS)
        return;
    rep->drawn_at = now;
    int filled = (int)(30.0 * share);
    char spp[64], figures[128] = "";
    ao_progress_format_spp(info, spp, sizeof spp);
    if (info->output != AO_OUTPUT_NORMALS) {
        char left[32], error[32] = "--";
        ao_progress_format(ao_progress_left(&rep->eta, info), left, sizeof left);
        if (!isnan(info->error))
            snprintf(error, sizeof error, "%.2f %%", 100.0 * info->error);
        snprintf(figures, sizeof figures, "  error %s  %.1f s  %s  %.1f Mrays/s", error, info->seconds, left,
                 ao_app_mrays_per_second(info));
    } else {
        snprintf(figures, sizeof figures, "  %.1f s", info->seconds);
    }
    fprintf(stderr, "\r[%.*s%*s] %3d %%  %s%s \033[K", filled, "##############################", 30 - filled, "",
            (int)(100.0 * share), spp, figures);
    if (info->done)
        fputc('\n', stderr);
}

/* Says once that writing --stats failed. */
static void stats_failed(struct ao_stats *st)
{
    char name[AO_TEXT_SIZE];
    if (!st->failed)
        fprintf(stderr, "%s: write failed\n", ao_text_escape(st->path, name, sizeof name));
    st->failed = true;
}

/* Before the first row: empties a regular file (a FIFO or device has nothing to empty) and writes
 * the header. */
static void start_stats(struct ao_stats *st)
{
    struct stat status;
    int fd = fileno(st->file);
    if (fstat(fd, &status) != 0 || (S_ISREG(status.st_mode) && ftruncate(fd, 0) != 0) ||
        fputs(st->header, st->file) < 0)
        stats_failed(st);
}

void ao_app_on_pass(const struct ao_frame_info *info, void *user)
{
    struct ao_reporter *rep = user;
    struct ao_stats *st = rep->stats;
    if (st && !atomic_exchange(&st->started, true))
        start_stats(st);
    if (st && !st->failed) {
        if (rep->side)
            fprintf(st->file, "%s,", rep->side);
        fprintf(st->file, "%u,%u,%.6f,%llu,%llu,%.3f", info->pass, info->spp, info->seconds,
                (unsigned long long)info->eye_rays, (unsigned long long)info->shadow_rays,
                ao_app_mrays_per_second(info));
        if (!isnan(info->rmse))
            fprintf(st->file, ",%.9g", info->rmse);
        fprintf(st->file, ",%.3f,%.6g,%.4f\n", info->mean_spp, info->error, info->converged);
        if (fflush(st->file) != 0)
            stats_failed(st);
        else
            atomic_store(&st->wrote, true);
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

void ao_app_on_preview(const struct ao_frame_info *info, void *user)
{
    (void)info;
    struct ao_reporter *rep = user;
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

bool ao_app_begin(void)
{
    /* A write to a closed socket or pipe (an X server killed under the window, a --stats FIFO
     * whose reader left, stderr read by a program that quit) then fails and is reported, instead
     * of killing aoview silently. */
    signal(SIGPIPE, SIG_IGN);
    for (int fd = 0; fd <= 2; fd++) {
        if (fcntl(fd, F_GETFD) >= 0 || errno != EBADF)
            continue;
        int null = open("/dev/null", fd == 0 ? O_WRONLY : O_RDONLY); /* the lowest free: fd */
        if (null != fd) {
            fprintf(stderr, "aoview: cannot open /dev/null: %s\n", strerror(errno));
            return false;
        }
    }
    return true;
}

bool ao_app_print(const char *text)
{
    if (fputs(text, stdout) >= 0 && fflush(stdout) == 0)
        return true;
    fprintf(stderr, "aoview: cannot write to standard output: %s\n", strerror(errno));
    return false;
}

const char *ao_app_signal_name(int sig)
{
    return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "a signal";
}

/* What a signal that ends the process at once says. */
enum ending { ENDING_SILENT, ENDING_LOADING, ENDING_NOTHING_WRITTEN, ENDING_SECOND };

/* Ends the process at once with 128 + sig: removes the temporary files of writes in progress and
 * a --stats file this run created and got no row into; then says, in one line, what the ending
 * left (write(2): the main thread may hold stderr's lock): for a second signal whether -o was
 * written, which the count of finished writes tells, now that none can begin or end. */
static void end_at_once(const struct ao_interrupt *in, int sig, enum ending ending)
{
    ao_image_discard_temporaries();
    const struct ao_stats *st = in->stats;
    if (st && atomic_load(&st->created) && !atomic_load(&st->wrote))
        unlink(st->path);
    char line[AO_TEXT_SIZE + 128], name[AO_TEXT_SIZE];
    const char *what = ao_app_signal_name(sig);
    int n = 0;
    if (ending == ENDING_LOADING)
        n = snprintf(line, sizeof line, "aoview: interrupted by %s before rendering: nothing written\n", what);
    else if (ending == ENDING_NOTHING_WRITTEN)
        n = snprintf(line, sizeof line, "aoview: interrupted by %s: nothing written\n", what);
    else if (ending == ENDING_SECOND)
        n = snprintf(line, sizeof line, atomic_load(&in->writing) && ao_image_written() >
                                                                           atomic_load(&in->written_before)
                                            ? "aoview: a second %s ended the run once %s was written\n"
                                            : "aoview: a second %s ended the run: %s not written\n",
                     what, ao_text_escape(in->output ? in->output : "aoview.png", name, sizeof name));
    if (ending != ENDING_SILENT && !in->silent && write(STDERR_FILENO, line, (size_t)n) < 0) {
        /* nowhere left to say it */
    }
    _exit(128 + sig);
}

static void *watch_signals(void *arg)
{
    struct ao_interrupt *in = arg;
    int sig;
    if (sigwait(&in->signals, &sig) != 0 || atomic_load(&in->closing))
        return NULL;
    struct ao_render *render = atomic_load(&in->render);
    if (!atomic_load(&in->rendering))
        end_at_once(in, sig, ENDING_LOADING);
    if (!render)
        end_at_once(in, sig, ENDING_NOTHING_WRITTEN);
    if (!atomic_load(&in->graceful))
        end_at_once(in, sig, ENDING_SILENT);
    atomic_store(&in->caught, sig);
    ao_render_stop(render);
    if (sigwait(&in->signals, &sig) == 0 && !atomic_load(&in->closing))
        end_at_once(in, sig, ENDING_SECOND);
    return NULL;
}

/* Their disposition goes back to default first: a shell starts background jobs with SIGINT
 * ignored, and an ignored signal never reaches sigwait. SIGHUP ignored stays so: nohup asked for
 * the run to outlive the terminal. */
void ao_app_block_signals(struct ao_app *app)
{
    struct ao_interrupt *in = &app->interrupt;
    struct sigaction hup;
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    sigemptyset(&in->signals);
    sigaddset(&in->signals, SIGINT);
    sigaddset(&in->signals, SIGTERM);
    if (sigaction(SIGHUP, NULL, &hup) == 0 && hup.sa_handler != SIG_IGN)
        sigaddset(&in->signals, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &in->signals, NULL);
}

bool ao_app_start_watcher(struct ao_app *app, bool silent)
{
    app->interrupt.silent = silent;
    app->interrupt.stats = &app->stats;
    if (pthread_create(&app->interrupt.watcher, NULL, watch_signals, &app->interrupt) != 0) {
        fprintf(stderr, "aoview: could not start the signal watcher thread\n");
        return false;
    }
    app->interrupt.watching = true;
    return true;
}

void ao_app_watch(struct ao_app *app, struct ao_render *render)
{
    atomic_store(&app->interrupt.render, render);
    atomic_store(&app->interrupt.rendering, true);
}

bool ao_app_check_files(const struct ao_options *opts, const char *const *outputs, size_t count)
{
    /* The outputs first, then what is only read. */
    struct ao_file_role files[6];
    size_t n = 0;
    for (size_t i = 0; i < count && n < 2; i++)
        files[n++] = (struct ao_file_role){"-o", outputs[i], true};
    if (opts->stats_path)
        files[n++] = (struct ao_file_role){"--stats", opts->stats_path, true};
    files[n++] = (struct ao_file_role){"the scene", opts->scene_path ? opts->scene_path : AO_DEFAULT_SCENE, false};
    if (opts->reference_path)
        files[n++] = (struct ao_file_role){"--reference", opts->reference_path, false};
    return ao_file_check_roles(files, n);
}

/* After loading: -o and --stats are none of the files the scene read (meshes, glTF buffers), which
 * ao_app_check_files could not know of; false after one line. */
static bool check_written_not_read(const struct ao_app *app, const struct ao_options *opts)
{
    const char *output = opts->output ? opts->output : opts->headless ? "aoview.png" : NULL;
    return (!output || ao_file_check_not_read("-o", output, -1)) &&
           (!app->stats.file || ao_file_check_not_read("--stats", opts->stats_path, fileno(app->stats.file)));
}

int ao_app_load(struct ao_app *app, const struct ao_options *opts, struct ao_render_config *config,
                struct ao_settings *settings)
{
    /* Stats file, before the scene: one that cannot be written is refused before a long load. */
    if (opts->stats_path) {
        bool created;
        if (!(app->stats.file = ao_file_open_output(opts->stats_path, "--stats", &created)))
            return AO_EXIT_RUNTIME;
        app->stats.path = opts->stats_path;
        atomic_store(&app->stats.created, created);
        snprintf(app->stats.header, sizeof app->stats.header,
                 "%spass,spp,seconds,eye_rays,shadow_rays,mrays_per_s%s,mean_spp,error,converged\n",
                 opts->compare ? "side," : "", opts->reference_path ? ",rmse" : "");
        app->reporter.stats = &app->stats;
    }

    /* Scene, size, tracer. */
    app->interrupt.output = opts->output ? opts->output : "aoview.png";
    ao_file_remember_inputs();
    char name[AO_TEXT_SIZE];
    struct ao_scene_options load = ao_options_scene(opts);
    if (!ao_scene_load(&app->scene, opts->scene_path ? opts->scene_path : AO_DEFAULT_SCENE, &load) ||
        !check_written_not_read(app, opts))
        return AO_EXIT_RUNTIME;
    int width, height;
    ao_options_size(opts, &app->scene, &width, &height);
    if (opts->reference_path && !ao_image_read_linear_sized(opts->reference_path, width, height, &app->reference))
        return AO_EXIT_RUNTIME;
    app->reference_width = width;
    app->reference_height = height;
    /* A big scene traces a LOW BVH while its MEDIUM one is built, unless two renderers share it. */
    bool progressive = app->scene.progressive && !opts->compare;
    if (!(app->tracer = progressive ? ao_tracer_create_progressive(&app->scene) : ao_tracer_create(&app->scene)))
        return AO_EXIT_RUNTIME;
    if (!opts->quiet)
        ao_scene_say_notes(&app->scene);
    ao_text_escape(app->scene.name, name, sizeof name);
    struct ao_tracer_stats built;
    ao_tracer_describe(app->tracer, &built);
    char instances[64] = "";
    if (built.instances)
        snprintf(instances, sizeof instances, " (%zu instances of meshes built once)", built.instances);
    if (!opts->quiet)
        fprintf(stderr, "aoview: %s: %zu triangles%s, %zu spheres, traced by %s\n", name, app->scene.triangle_count,
                instances, app->scene.sphere_count, ao_tracer_backend(app->tracer));

    /* Renderer. */
    if (!ao_options_render(opts, &app->scene, app->tracer, config, settings))
        return AO_EXIT_RUNTIME;
    config->reference = app->reference;
    config->reference_width = app->reference_width;
    config->reference_height = app->reference_height;
    config->on_pass = ao_app_on_pass;
    config->on_preview = ao_app_on_preview;
    config->user = &app->reporter;
    config->upgrade = progressive ? app->tracer : NULL;
    return 0;
}

bool ao_app_go_headless(const struct ao_options *opts)
{
    const char *output = opts->output ? opts->output : "aoview.png";
    char name[AO_TEXT_SIZE];
    if (!ao_image_check_output(output))
        return false;
    fprintf(stderr, "aoview: no display available; rendering headless to %s\n",
            ao_text_escape(output, name, sizeof name));
    return true;
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
    const char *bar = app->reporter.drawn_at > 0.0 ? "\n" : ""; /* ends the progress bar's line */
    if (why && frame && frame->info.pass == 0) {
        fprintf(stderr, "%saoview: %s before the first pass ended: nothing written\n", bar, why);
        return status;
    }
    if (why && frame) {
        fprintf(stderr, "%saoview: %s at %u spp\n", bar, why, frame->info.spp);
        if (last_row)
            ao_app_on_pass(&frame->info, &app->reporter);
    }
    const float *difference = opts->view == AO_VIEW_MODE_DIFFERENCE ? app->reference : NULL;
    atomic_store(&app->interrupt.written_before, ao_image_written());
    atomic_store(&app->interrupt.writing, true);
    if (!frame || !ao_app_write_output(output, frame, app->scene.name, opts->seed, difference))
        return AO_EXIT_RUNTIME;
    char name[AO_TEXT_SIZE];
    if (!opts->quiet)
        fprintf(stderr, "aoview: wrote %s (%u spp, %.2f s, %.1f Mrays/s)\n", ao_text_escape(output, name, sizeof name),
                frame->info.spp, frame->info.seconds, ao_app_mrays_per_second(&frame->info));
    return status;
}

/* Wakes the watcher with a signal of its set sent to it alone, which it reads as the end; it is
 * joined before the renderer it may stop is destroyed. */
static void stop_watcher(struct ao_interrupt *in)
{
    if (!in->watching)
        return;
    atomic_store(&in->closing, true);
    pthread_kill(in->watcher, SIGTERM);
    pthread_join(in->watcher, NULL);
    in->watching = false;
}

int ao_app_finish(struct ao_app *app, int status)
{
    stop_watcher(&app->interrupt);
    ao_render_destroy(app->render);
    app->render = NULL;
    struct ao_stats *st = &app->stats;
    if (st->file && fclose(st->file) != 0)
        stats_failed(st);
    if (st->file && atomic_load(&st->created) && !atomic_load(&st->wrote))   /* none, or none whole: a full disk */
        unlink(st->path);
    st->file = NULL;
    if (st->failed && status == 0)
        status = AO_EXIT_RUNTIME;
    ao_tracer_destroy(app->tracer);
    ao_scene_finish(&app->scene);
    free(app->reference);
    return status;
}
