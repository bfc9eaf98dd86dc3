/* aoview-exact: writes the exact ambient-occlusion image of a scene that has a closed form
 * (exact_image.h), as a PFM to use as aoview's --reference; anything else is refused with one
 * line, exit 1. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "config.h"
#include "exact_image.h"
#include "file.h"
#include "image.h"
#include "options.h"
#include "program.h"
#include "scene.h"
#include "scene_load.h"
#include "tracer.h"

enum { EXIT_RUNTIME = 1, EXIT_USAGE = 2 };

static const char USAGE[] =
    "usage: aoview-exact [--size WxH] [--aa | --no-aa] [--spp N] [-o FILE.pfm] [-q] SCENE\n"
    "Writes the exact ambient occlusion of SCENE (a plane with at most one sphere over it, or a\n"
    "closed box around the camera) as a PFM for aoview --reference. With AA (the default) each\n"
    "pixel is the box-filtered value over a k x k sub-pixel grid, k = round(sqrt(N)), N = --spp\n"
    "(default 256: 16 x 16). --size, --aa/--no-aa and -o mean what they mean to aoview (default\n"
    "output exact.pfm); aoview's other options are accepted and have no effect.\n";


/* Everything main owns, released in one place. */
struct app {
    struct ao_scene scene;
    struct ao_tracer *tracer;
    float *rgb;
};

static int run(struct app *app, const struct ao_options *opts)
{
    const char *output = opts->output ? opts->output : "exact.pfm";
    size_t n = strlen(output);
    if (n < 4 || strcmp(output + n - 4, ".pfm") != 0) {
        fprintf(stderr, "aoview-exact: -o: the exact image is linear: expected a .pfm name, got '%s'\n", output);
        return EXIT_USAGE;
    }
    if (!opts->scene_path) {
        fprintf(stderr, "aoview-exact: no SCENE given (try --help)\n");
        return EXIT_USAGE;
    }
    /* -o is checked as aoview checks its outputs: writable, not the scene, then not a file the scene
     * reads (a mesh). */
    const struct ao_file_role files[] = {{"-o", output, true}, {"the scene", opts->scene_path, false}};
    if (!ao_image_check_output(output) || !ao_file_check_roles(files, 2))
        return EXIT_RUNTIME;
    ao_file_remember_inputs();
    struct ao_scene_options load = ao_options_scene(opts);
    if (!ao_scene_load(&app->scene, opts->scene_path, &load) || !ao_file_check_not_read("-o", output, -1))
        return EXIT_RUNTIME;
    int width, height;
    ao_options_size(opts, &app->scene, &width, &height);
    if (!(app->tracer = ao_tracer_create(&app->scene)))
        return EXIT_RUNTIME;
    if (!(app->rgb = malloc(3 * sizeof *app->rgb * (size_t)width * (size_t)height))) {
        fprintf(stderr, "aoview-exact: out of memory for a %dx%d image\n", width, height);
        return EXIT_RUNTIME;
    }
    int grid = opts->aa ? (int)lround(sqrt((double)opts->spp)) : 0;
    float ao_distance = isnan(opts->ao_distance) ? app->scene.ao_distance : opts->ao_distance;
    struct ao_exact_facts facts;
    char why[256];
    ao_tracer_thread_init();
    if (!ao_exact_render(&app->scene, app->tracer, ao_distance, width, height, grid, app->rgb, &facts, why,
                         sizeof why)) {
        fprintf(stderr, "aoview-exact: %s: %s\n", opts->scene_path, why);
        return EXIT_RUNTIME;
    }
    if (!ao_image_write_pfm(output, app->rgb, width, height))
        return EXIT_RUNTIME;
    if (!opts->quiet) {
        fprintf(stderr, "aoview-exact: wrote %s (%s", output, facts.kind);
        if (!isnan(facts.ground_error))
            fprintf(stderr, ", sphere points within %.1e of the finite ground's term", facts.ground_error);
        if (grid)
            fprintf(stderr, ", %dx%d sub-pixel grid", grid, grid);
        fprintf(stderr, ")\n");
    }
    return 0;
}

int main(int argc, char **argv)
{
    struct ao_options opts;
    char message[512];
    ao_program_init();
    if (!ao_cli_parse(argc, argv, &opts, message, sizeof message)) {
        fprintf(stderr, "aoview-exact: %s (try --help)\n", message);
        return EXIT_USAGE;
    }
    if (opts.help || opts.version) {
        fputs(opts.help ? USAGE : "aoview-exact " AO_VERSION "\n", stdout);
        return 0;
    }
    struct app app = {0};
    int status = run(&app, &opts);
    free(app.rgb);
    ao_tracer_destroy(app.tracer);
    ao_scene_finish(&app.scene);
    return status;
}
