/* aoview: wiring of options, scene, tracer, renderer and the window or headless output; main
 * returns the exit status (docs/contract.md). Nothing else ends the process but the handlers
 * where no way back is sound (docs/style.md). */
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app_load.h"
#include "app_output.h"
#include "app_report.h"
#include "app_signals.h"
#include "cli.h"
#include "compare.h"
#include "config.h"
#include "headless.h"
#include "image.h"
#include "program.h"
#include "text.h"
#include "window.h"

/* Everything main owns, released in one place. */
struct app {
    struct ao_app base;
    struct ao_reporter side_reporters[2];   /* the window's comparison: each side's stats rows */
    struct ao_reporter mute; /* the window's renderer under --compare, whose rows are the sides' */
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
    char name[AO_TEXT_SIZE];
    fprintf(stderr, "--output: %s: too long a name for --compare's -%s file\n", ao_text_escape(path, name, sizeof name),
            side);
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
                !ao_app_write_output(file, &frame, app->base.scene.name, opts->seed, NULL))
                return false;
        }
        return true;
    }
    size_t row = 2 * (size_t)width;
    float *both = malloc(3 * sizeof *both * row * (size_t)height);
    if (!both) {
        char name[AO_TEXT_SIZE];
        fprintf(stderr, "aoview: %s: out of memory\n", ao_text_escape(path, name, sizeof name));
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
    int width = settings->width, height = settings->height;
    size_t floats = 3 * (size_t)width * (size_t)height;
    if (!(app->sides[0] = malloc(floats * sizeof(float))) || !(app->sides[1] = malloc(floats * sizeof(float)))) {
        fprintf(stderr, "aoview: out of memory for --compare's images\n");
        return AO_EXIT_RUNTIME;
    }
    struct ao_frame_info info[2];
    for (int k = 0; k < 2; k++) {
        struct ao_render_config side_config = *config;
        struct ao_settings side_settings = *settings;
        side_config.sequence = opts->sides[k].sequence;
        side_settings.sampling = opts->sides[k].sampling;
        side_settings.aa = opts->sides[k].aa;
        app->base.reporter.side = side_names[k];
        app->base.reporter.drawn_at = 0.0;
        app->base.reporter.eta = (struct ao_progress){0};
        app->base.reporter.stop_at = config->time_limit;
        app->base.reporter.pass_end = 0.0;
        if (!(app->base.render = ao_render_create(&side_config, &side_settings)))
            return AO_EXIT_RUNTIME;
        atomic_store(&app->base.reporter.render, app->base.render);
        bool done = ao_render_wait(app->base.render);
        atomic_store(&app->base.reporter.render, NULL);
        if (app->base.reporter.progress && !done)
            fputc('\n', stderr);
        const struct ao_frame *frame = ao_render_take_frame(app->base.render);
        if (!frame)
            return AO_EXIT_RUNTIME;
        info[k] = frame->info;
        memcpy(app->sides[k], frame->rgb, floats * sizeof(float));
        ao_render_destroy(app->base.render);
        app->base.render = NULL;
        if (!opts->quiet) {
            char name[64];
            ao_cli_side_name(&opts->sides[k], name, sizeof name);
            fprintf(stderr, "aoview: %s %s: %u spp, %.2f s, %.1f Mrays/s\n", side_names[k], name, info[k].spp,
                    info[k].seconds, ao_app_mrays_per_second(&info[k]));
        }
    }
    if (!write_compare(output, app, opts, info, width, height))
        return AO_EXIT_RUNTIME;
    char a[4096], b[4096], shown[2][AO_TEXT_SIZE];
    if (!opts->quiet && ao_image_has_extension(output, ".png"))
        fprintf(stderr, "aoview: wrote %s\n", ao_text_escape(output, shown[0], sizeof shown[0]));
    else if (!opts->quiet && side_path(output, side_names[0], a, sizeof a) && side_path(output, side_names[1], b, sizeof b))
        fprintf(stderr, "aoview: wrote %s and %s\n", ao_text_escape(a, shown[0], sizeof shown[0]),
                ao_text_escape(b, shown[1], sizeof shown[1]));
    return 0;
}

/* The files -o names (--compare's linear output: each side's) can be written (headless) and are
 * none that the run reads or writes otherwise (whenever given), checked before loading, so that a
 * run never renders for nothing; false after one line. */
static bool check_outputs(const struct ao_options *opts)
{
    const char *output = opts->output ? opts->output : "aoview.png";
    char files[2][4096];
    const char *names[2] = {output, NULL};
    size_t count = opts->output || opts->headless ? 1 : 0;
    if (count && opts->compare && !ao_image_has_extension(output, ".png")) {
        for (int k = 0; k < 2; k++)
            if (!side_path(output, side_names[k], files[k], sizeof files[k]))
                return false;
        names[0] = files[0], names[1] = files[1], count = 2;
    }
    for (size_t k = 0; opts->headless && k < count; k++)
        if (!ao_image_check_output(names[k]))
            return false;
    return ao_app_check_files(opts, names, count);
}

/* Headless: waits for the render (stopped early by a signal) and writes what it made. */
static int finish_headless(struct ao_app *base, const struct ao_options *opts, const struct ao_settings *settings)
{
    /* A PNG that could not be drawn is refused now rather than after the render. */
    const char *output = opts->output ? opts->output : "aoview.png";
    if (ao_image_has_extension(output, ".png") && !ao_headless_check_room(output, settings->width, settings->height))
        return AO_EXIT_RUNTIME;
    atomic_store(&base->interrupt.graceful, true);
    int sig;
    bool finished = ao_app_wait(base, &sig);
    if (!finished && !sig)
        return AO_EXIT_RUNTIME;
    char why[64];
    snprintf(why, sizeof why, "interrupted by %s", ao_app_signal_name(sig));
    const struct ao_frame *frame = finished ? ao_render_take_frame(base->render) : ao_render_resolve_stopped(base->render);
    return ao_app_write(base, opts, frame, finished ? NULL : why, true, finished ? 0 : 128 + sig);
}

static int run(struct app *app, const struct ao_options *opts)
{
    struct ao_app *base = &app->base;
    ao_app_block_signals(base);
    if (!ao_app_start_watcher(base, false) || !check_outputs(opts))
        return AO_EXIT_RUNTIME;
    struct ao_render_config config;
    struct ao_settings settings;
    int status = ao_app_load(base, opts, &config, &settings);
    if (status)
        return status;
    bool window = !opts->headless;
    base->reporter.progress = !opts->quiet && !window && isatty(STDERR_FILENO);
    base->reporter.notify = ao_window_notify;
    if (opts->compare && !window) {
        ao_app_watch(base, NULL);
        return run_compare(app, opts, &config, &settings);
    }

    /* The window's renderer. With --compare it renders side A, paused while the window compares,
     * and the stats rows come from the sides; without, V's sides write none (the header has no
     * side column). */
    struct ao_render_config single = config;
    struct ao_settings first = settings;
    for (int k = 0; k < 2; k++) {
        app->side_reporters[k] = base->reporter;
        app->side_reporters[k].side = side_names[k];
        if (!opts->compare)
            app->side_reporters[k].stats = NULL;
    }
    if (opts->compare && window) {
        app->mute = base->reporter;
        app->mute.stats = NULL;
        single.user = &app->mute;
        single.sequence = opts->sides[0].sequence;
        first.sampling = opts->sides[0].sampling;
        first.aa = opts->sides[0].aa;
    }
    /* The window's renderer waits for the window to open (ao_window_info's resume), which then
     * has the cores to itself; --compare's stays paused while the window compares. */
    first.paused = window;
    if (!(base->render = ao_render_create(&single, &first)))
        return AO_EXIT_RUNTIME;
    /* Headless, a signal from now on stops the render and writes what it has (or says that there is
     * nothing yet), also while the PNG's room is checked below. */
    atomic_store(&base->interrupt.graceful, !window);
    ao_app_watch(base, base->render);

    /* Window, or headless output (also where no window can be opened). */
    if (window) {
        struct ao_window_info info = {.scene_name = base->scene.name, .quiet = opts->quiet,
                                      .seed = opts->seed, .save_exr = opts->save_exr,
                                      .reference = base->reference,
                                      .reference_width = base->reference_width,
                                      .reference_height = base->reference_height,
                                      .pixel_size = opts->pixel_size,
                                      .difference = opts->view == AO_VIEW_MODE_DIFFERENCE,
                                      .config = &single, .compare = opts->compare != NULL,
                                      .resume = !opts->compare,
                                      .sides = {opts->sides[0], opts->sides[1]},
                                      .users = {&app->side_reporters[0], &app->side_reporters[1]}};
        enum ao_window_result result = ao_window_run(base->render, &info);
        if (result != AO_WINDOW_NO_DISPLAY)
            return result == AO_WINDOW_OK ? 0 : AO_EXIT_RUNTIME;
        if (!ao_app_go_headless(opts))
            return AO_EXIT_RUNTIME;
        base->reporter.progress = !opts->quiet && isatty(STDERR_FILENO);
        if (opts->compare) {
            ao_render_destroy(base->render);
            base->render = NULL;
            return run_compare(app, opts, &config, &settings);
        }
        ao_render_set_settings(base->render, &settings);   /* unpaused: nothing was rendered yet */
    }
    return finish_headless(base, opts, &settings);
}

int main(int argc, char **argv)
{
    struct ao_options opts;
    char message[512];
    ao_program_init();
    if (!ao_app_begin())
        return AO_EXIT_RUNTIME;
    if (!ao_cli_parse(argc, argv, &opts, message, sizeof message)) {
        fprintf(stderr, "aoview: %s (try --help)\n", message);
        return AO_EXIT_USAGE;
    }
    if (opts.help || opts.version)
        return ao_app_print(opts.help ? ao_cli_usage() : "aoview " AO_VERSION "\n") ? 0 : AO_EXIT_RUNTIME;
    struct app app = {0};
    int status = run(&app, &opts);
    status = ao_app_finish(&app.base, status);
    free(app.sides[0]);
    free(app.sides[1]);
    return status;
}
