/* Loading from the options, the checks around it, and the release; see app_load.h. */
#include "app_load.h"

#include <stdlib.h>

#include "app_report.h"
#include "app_signals.h"
#include "config.h"
#include "file.h"
#include "image.h"
#include "options.h"
#include "render.h"
#include "text.h"
#include "tracer.h"

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
        if (!ao_app_open_stats(&app->stats, opts->stats_path, opts->compare, opts->reference_path != NULL))
            return AO_EXIT_RUNTIME;
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
    /* A big scene traces a LOW BVH first where that is sooner: in the window, whose first image
     * comes at LOW's time while MEDIUM is built beside (unless two renderers share the tracer), and
     * in a one-pass headless run, which never starts that build; a longer headless run builds
     * MEDIUM alone, which ends it sooner (docs/formats.md). */
    bool one_pass = opts->spp <= ao_render_first_pass_spp(opts->spppp);
    bool progressive = app->scene.progressive && !opts->compare && (!opts->headless || one_pass);
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

int ao_app_finish(struct ao_app *app, int status)
{
    /* The watcher is joined before the renderer it may stop is destroyed. */
    ao_app_stop_watcher(&app->interrupt);
    ao_render_destroy(app->render);
    app->render = NULL;
    if (!ao_app_close_stats(&app->stats) && status == 0)
        status = AO_EXIT_RUNTIME;
    ao_tracer_destroy(app->tracer);
    ao_scene_finish(&app->scene);
    free(app->reference);
    return status;
}
