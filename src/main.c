/* aoview: wiring of options, scene, tracer, renderer and the window or headless output. The only
 * place that exits. */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "compare.h"
#include "config.h"
#include "headless.h"
#include "heatmap.h"
#include "image.h"
#include "notes.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "tracer.h"
#include "window.h"

enum { EXIT_RUNTIME = 1, EXIT_USAGE = 2 };

static double mrays_per_second(const struct ao_frame_info *info)
{
    return info->seconds > 0.0 ? (double)(info->eye_rays + info->shadow_rays) / info->seconds / 1e6 : 0.0;
}

/* The headless progress bar redraws at most this often (and once more at the end). */
static const double BAR_SECONDS = 0.1;

/* What the per-pass callback reports to. */
struct reporter {
    FILE *stats;
    const char *stats_path;
    const char *side;      /* --compare's "A" or "B": the stats rows' first column; NULL: none */
    struct ao_render *_Atomic render;   /* --compare: the side's renderer, stopped at stop_at */
    double stop_at;        /* --compare: seconds whose nearest pass end ends the side; 0: none */
    double pass_end;       /* seconds at the end of the previous pass */
    bool progress;         /* a progress bar on stderr (a terminal, not --quiet) */
    bool stats_failed;
    struct ao_progress eta;   /* the bar's time-left estimate */
    double drawn_at;          /* monotonic seconds of the bar's last redraw; 0: never */
};

static double monotonic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Redraws the progress bar: filled by the share of the run's time gone where the time left is
 * estimated, else by spp; at most every BAR_SECONDS, and at the end. */
static void draw_bar(struct reporter *rep, const struct ao_frame_info *info)
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
            info->seconds, left_text, mrays_per_second(info));
    if (info->done)
        fputc('\n', stderr);
}

/* Runs on the render thread after every published pass (and on main once after an interruption). */
static void on_pass(const struct ao_frame_info *info, void *user)
{
    struct reporter *rep = user;
    if (rep->stats && !rep->stats_failed) {
        if (rep->side)
            fprintf(rep->stats, "%s,", rep->side);
        fprintf(rep->stats, "%u,%u,%.6f,%llu,%llu,%.3f", info->pass, info->spp, info->seconds,
                (unsigned long long)info->eye_rays, (unsigned long long)info->shadow_rays,
                mrays_per_second(info));
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
    ao_window_notify();
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

/* Writes the final frame as PFM or EXR (linear; EXR with the settings in its header) or PNG
 * (through the display code; with a difference reference, the difference view's heat map). */
static bool write_output(const char *path, const struct ao_frame *frame, const char *scene,
                         uint64_t seed, const float *difference)
{
    if (ao_image_has_extension(path, ".png"))
        return difference ? write_difference_png(path, frame, difference)
                          : ao_headless_write_png(path, frame->rgb, frame->width, frame->height);
    struct ao_notes notes;
    ao_notes_make(&notes, &frame->info, scene, seed);
    return ao_image_write_linear(path, frame->rgb, frame->width, frame->height, notes.notes,
                                 notes.count);
}

/* SIGINT/SIGTERM during a headless render: the first stops the renderer at the next tile so that
 * main writes what it has; a second exits at once. The signals are blocked in every thread and
 * taken here with sigwait, so nothing runs in a signal handler. */
struct interrupt {
    sigset_t signals;
    struct ao_render *render;
    atomic_bool graceful;    /* headless: stop and write; in the window: exit as by default */
    atomic_int caught;
};

static void *watch_signals(void *arg)
{
    struct interrupt *in = arg;
    int sig;
    if (sigwait(&in->signals, &sig) != 0)
        return NULL;
    if (!atomic_load(&in->graceful))
        _exit(128 + sig);
    atomic_store(&in->caught, sig);
    ao_render_stop(in->render);
    if (sigwait(&in->signals, &sig) == 0)
        _exit(128 + sig);
    return NULL;
}

/* Blocks SIGINT and SIGTERM in the calling thread and every thread it starts from now on. Their
 * disposition goes back to default first: a shell starts background jobs with SIGINT ignored, and
 * an ignored signal never reaches sigwait. */
static void block_signals(struct interrupt *in)
{
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    sigemptyset(&in->signals);
    sigaddset(&in->signals, SIGINT);
    sigaddset(&in->signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &in->signals, NULL);
}

/* Starts the thread that takes the blocked signals; false when it cannot. */
static bool start_watcher(struct interrupt *in, struct ao_render *render)
{
    pthread_t thread;
    in->render = render;
    if (pthread_create(&thread, NULL, watch_signals, in) != 0) {
        fprintf(stderr, "aoview: could not start the signal watcher thread\n");
        return false;
    }
    pthread_detach(thread);
    return true;
}

/* Waits for the target spp (or an interruption) and writes the output; SPEC.md's headless path. */
static int run_headless(struct ao_render *render, const struct ao_options *opts, struct interrupt *in,
                        struct reporter *reporter, const char *scene, const float *reference)
{
    const char *output = opts->output ? opts->output : "aoview.png";
    bool finished = ao_render_wait(render);
    int sig = atomic_load(&in->caught);
    if (!finished && !sig)
        return EXIT_RUNTIME;
    const struct ao_frame *frame = finished ? ao_render_take_frame(render) : ao_render_resolve_stopped(render);
    if (!finished) {
        fprintf(stderr, "\naoview: interrupted by %s at %u spp\n", sig == SIGINT ? "SIGINT" : "SIGTERM",
                frame->info.spp);
        on_pass(&frame->info, reporter);
    }
    const float *difference = opts->view == AO_VIEW_MODE_DIFFERENCE ? reference : NULL;
    if (!frame || !write_output(output, frame, scene, opts->seed, difference))
        return EXIT_RUNTIME;
    if (!opts->quiet)
        fprintf(stderr, "aoview: wrote %s (%u spp, %.2f s, %.1f Mrays/s)\n", output, frame->info.spp,
                frame->info.seconds, mrays_per_second(&frame->info));
    return finished ? 0 : 128 + sig;
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

/* Everything main owns, released in one place. */
struct app {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    struct ao_render *render;
    float *reference;
    struct reporter reporter;
    struct reporter side_reporters[2];   /* the window's comparison: each side's stats rows */
    struct reporter mute;    /* the window's renderer under --compare, whose rows are the sides' */
    struct interrupt interrupt;
    float *sides[2];         /* --compare: each side's final image */
};

/* --compare's sides, as the stats rows, labels and file names call them. */
static const char *const side_names[2] = {"A", "B"};

/* --compare's output: path with "-A" or "-B" before its extension (which cli.c made 4 bytes);
 * false with one message when that does not fit in size. */
static bool side_path(const char *path, const char *side, char *out, size_t size)
{
    size_t stem = strlen(path) - 4;
    if ((size_t)snprintf(out, size, "%.*s-%s%s", (int)stem, path, side, path + stem) < size)
        return true;
    fprintf(stderr, "--output: %s: too long a name for --compare's -%s file\n", path, side);
    return false;
}

/* Writes both sides: one PNG twice the width with each side's label at its top, or a linear file
 * per side. */
static bool write_compare(const char *path, const struct app *app, const struct ao_options *opts,
                          const struct ao_frame_info info[2], int width, int height)
{
    if (!ao_image_has_extension(path, ".png")) {
        for (int k = 0; k < 2; k++) {
            char file[4096];
            struct ao_frame frame = {.info = info[k], .width = width, .height = height, .rgb = app->sides[k]};
            if (!side_path(path, side_names[k], file, sizeof file) ||
                !write_output(file, &frame, app->scene.name, opts->seed, NULL))
                return false;
        }
        return true;
    }
    size_t row = 2 * (size_t)width;
    float *both = malloc(3 * sizeof *both * row * (size_t)height);
    if (!both) {
        fprintf(stderr, "aoview: %s: out of memory\n", path);
        return false;
    }
    char text[2][160];
    struct ao_headless_label labels[2];
    ao_compare_compose(AO_COMPARE_SIDE_BY_SIDE, 0, app->sides[0], app->sides[1], width, height, both);
    for (int k = 0; k < 2; k++) {
        ao_compare_label(side_names[k], &opts->sides[k], &info[k], "\n", text[k], sizeof text[k]);
        labels[k] = (struct ao_headless_label){.text = text[k], .x = k * width + 4, .y = 4};
    }
    bool ok = ao_headless_write_labelled(path, both, (int)row, height, labels, 2);
    free(both);
    return ok;
}

/* --compare: renders each side in turn with all the threads (so that they do not compete for
 * cores) for --time seconds, ending at the pass end nearest it (on_pass), copies its image into
 * app->sides, and writes them. A signal exits at once: there is no half-compared image to write. */
static int run_compare(struct app *app, const struct ao_options *opts, const struct ao_render_config *config,
                       const struct ao_settings *settings)
{
    const char *output = opts->output ? opts->output : "aoview.png";
    int width = config->width, height = config->height;
    size_t floats = 3 * (size_t)width * (size_t)height;
    if (!(app->sides[0] = malloc(floats * sizeof(float))) || !(app->sides[1] = malloc(floats * sizeof(float)))) {
        fprintf(stderr, "aoview: out of memory for --compare's images\n");
        return EXIT_RUNTIME;
    }
    struct ao_frame_info info[2];
    for (int k = 0; k < 2; k++) {
        struct ao_render_config side_config = *config;
        struct ao_settings side_settings = *settings;
        side_config.sequence = opts->sides[k].sequence;
        side_settings.sampling = opts->sides[k].sampling;
        side_settings.aa = opts->sides[k].aa;
        app->reporter.side = side_names[k];
        app->reporter.drawn_at = 0.0;
        app->reporter.eta = (struct ao_progress){0};
        app->reporter.stop_at = config->time_limit;
        app->reporter.pass_end = 0.0;
        if (!(app->render = ao_render_create(&side_config, &side_settings)))
            return EXIT_RUNTIME;
        atomic_store(&app->reporter.render, app->render);
        bool done = ao_render_wait(app->render);
        atomic_store(&app->reporter.render, NULL);
        if (app->reporter.progress && !done)
            fputc('\n', stderr);
        const struct ao_frame *frame = ao_render_take_frame(app->render);
        if (!frame)
            return EXIT_RUNTIME;
        info[k] = frame->info;
        memcpy(app->sides[k], frame->rgb, floats * sizeof(float));
        ao_render_destroy(app->render);
        app->render = NULL;
        if (!opts->quiet) {
            char name[64];
            ao_cli_side_name(&opts->sides[k], name, sizeof name);
            fprintf(stderr, "aoview: %s %s: %u spp, %.2f s, %.1f Mrays/s\n", side_names[k], name, info[k].spp,
                    info[k].seconds, mrays_per_second(&info[k]));
        }
    }
    if (!write_compare(output, app, opts, info, width, height))
        return EXIT_RUNTIME;
    char a[4096], b[4096];
    if (!opts->quiet && ao_image_has_extension(output, ".png"))
        fprintf(stderr, "aoview: wrote %s\n", output);
    else if (!opts->quiet && side_path(output, side_names[0], a, sizeof a) && side_path(output, side_names[1], b, sizeof b))
        fprintf(stderr, "aoview: wrote %s and %s\n", a, b);
    return 0;
}

static int run(struct app *app, const struct ao_options *opts)
{
    /* Before any thread starts (Embree's included), so that they all inherit the mask. */
    block_signals(&app->interrupt);
    /* A write to a closed socket or pipe (an X server killed under the window, a --stats FIFO
     * whose reader left) then fails and is reported, instead of killing aoview silently. */
    signal(SIGPIPE, SIG_IGN);

    /* Scene, size, tracer. */
    if (!ao_scene_load(&app->scene, opts->scene_path ? opts->scene_path : AO_DEFAULT_SCENE))
        return EXIT_RUNTIME;
    int width = opts->width ? opts->width : app->scene.width ? app->scene.width : 640;
    int height = opts->height ? opts->height : app->scene.height ? app->scene.height : 480;
    if (opts->reference_path && !(app->reference = load_reference(opts->reference_path, width, height)))
        return EXIT_RUNTIME;
    if (!(app->tracer = ao_tracer_create(&app->scene)))
        return EXIT_RUNTIME;
    if (app->scene.degenerate_count && !opts->quiet)
        fprintf(stderr, "aoview: skipped %zu degenerate triangles\n", app->scene.degenerate_count);
    if (!opts->quiet)
        fprintf(stderr, "aoview: %s: %zu triangles, %zu spheres, traced by %s\n", app->scene.name,
                app->scene.triangle_count, app->scene.sphere_count, ao_tracer_backend(app->tracer));

    /* Stats file and progress bar. */
    app->reporter.stats_path = opts->stats_path;
    if (opts->stats_path) {
        if (!(app->reporter.stats = fopen(opts->stats_path, "w"))) {
            fprintf(stderr, "--stats: cannot write %s: %s\n", opts->stats_path, strerror(errno));
            return EXIT_RUNTIME;
        }
        fprintf(app->reporter.stats, "%spass,spp,seconds,eye_rays,shadow_rays,mrays_per_s%s,mean_spp,error,converged\n",
                opts->compare ? "side," : "", app->reference ? ",rmse" : "");
    }

    /* Renderer. */
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    struct ao_render_config config = {
        .scene = &app->scene, .tracer = app->tracer, .width = width, .height = height,
        .threads = opts->threads ? opts->threads : (cores > 0 ? (int)cores : 1),
        .seed = opts->seed, .target_spp = opts->spp, .target_error = opts->target_error,
        .time_limit = opts->time_limit,
        .ao_distance = isnan(opts->ao_distance) ? app->scene.ao_distance : opts->ao_distance,
        .sequence = opts->sequence, .below = opts->below,
        .reference = app->reference, .on_pass = on_pass, .user = &app->reporter};
    struct ao_settings settings = {.sampling = opts->sampling, .aa = opts->aa, .spppp = (int)opts->spppp,
                                   .adaptive = opts->adaptive, .camera = app->scene.camera,
                                   .output = opts->view == AO_VIEW_MODE_NORMALS ? AO_OUTPUT_NORMALS : AO_OUTPUT_AO,
                                   .shading = opts->shading};
    struct ao_view view;
    if (!ao_camera_view(&settings.camera, width, height, &view)) {
        fprintf(stderr, "%s: the camera cannot form an image\n", app->scene.name);
        return EXIT_RUNTIME;
    }
    bool window = !opts->headless;
    app->reporter.progress = !opts->quiet && !window && isatty(STDERR_FILENO);
    if (opts->compare && !window)
        return start_watcher(&app->interrupt, NULL) ? run_compare(app, opts, &config, &settings) : EXIT_RUNTIME;

    /* The window's renderer. With --compare it renders side A, paused while the window compares,
     * and the stats rows come from the sides; without, V's sides write none (the header has no
     * side column). */
    struct ao_render_config single = config;
    struct ao_settings first = settings;
    for (int k = 0; k < 2; k++) {
        app->side_reporters[k] = app->reporter;
        app->side_reporters[k].side = side_names[k];
        if (!opts->compare)
            app->side_reporters[k].stats = NULL;
    }
    if (opts->compare && window) {
        app->mute = app->reporter;
        app->mute.stats = NULL;
        single.user = &app->mute;
        single.sequence = opts->sides[0].sequence;
        first.sampling = opts->sides[0].sampling;
        first.aa = opts->sides[0].aa;
        first.paused = true;
    }
    if (!(app->render = ao_render_create(&single, &first)) || !start_watcher(&app->interrupt, app->render))
        return EXIT_RUNTIME;

    /* Window, or headless output (also where no window can be opened). */
    if (window) {
        struct ao_window_info info = {.scene_name = app->scene.name, .quiet = opts->quiet,
                                      .seed = opts->seed, .save_exr = opts->save_exr,
                                      .reference = app->reference,
                                      .difference = opts->view == AO_VIEW_MODE_DIFFERENCE,
                                      .config = &single, .compare = opts->compare != NULL,
                                      .sides = {opts->sides[0], opts->sides[1]},
                                      .users = {&app->side_reporters[0], &app->side_reporters[1]}};
        enum ao_window_result result = ao_window_run(app->render, &info);
        if (result != AO_WINDOW_NO_DISPLAY)
            return result == AO_WINDOW_OK ? 0 : EXIT_RUNTIME;
        fprintf(stderr, "aoview: no display available; rendering headless to %s\n",
                opts->output ? opts->output : "aoview.png");
        app->reporter.progress = !opts->quiet && isatty(STDERR_FILENO);
        if (opts->compare) {
            ao_render_destroy(app->render);
            app->render = NULL;
            return run_compare(app, opts, &config, &settings);
        }
    }
    atomic_store(&app->interrupt.graceful, true);
    return run_headless(app->render, opts, &app->interrupt, &app->reporter, app->scene.name, app->reference);
}

int main(int argc, char **argv)
{
    struct ao_options opts;
    char message[512];
    if (!ao_cli_parse(argc, argv, &opts, message, sizeof message)) {
        fprintf(stderr, "aoview: %s (try --help)\n", message);
        return EXIT_USAGE;
    }
    if (opts.help || opts.version) {
        fputs(opts.help ? ao_cli_usage() : "aoview " AO_VERSION "\n", stdout);
        return 0;
    }
    struct app app = {0};
    int status = run(&app, &opts);
    ao_render_destroy(app.render);
    bool stats_failed = app.reporter.stats_failed || app.side_reporters[0].stats_failed ||
                        app.side_reporters[1].stats_failed;
    if (app.reporter.stats && fclose(app.reporter.stats) != 0 && !stats_failed) {
        fprintf(stderr, "%s: write failed\n", opts.stats_path);
        stats_failed = true;
    }
    if (stats_failed && status == 0)
        status = EXIT_RUNTIME;
    ao_tracer_destroy(app.tracer);
    ao_scene_finish(&app.scene);
    free(app.reference);
    free(app.sides[0]);
    free(app.sides[1]);
    return status;
}
