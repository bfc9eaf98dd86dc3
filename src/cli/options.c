/* The command line's options made into scene options, a size, a render config; see options.h. */
#include "options.h"

#include <math.h>
#include <stdio.h>
#include <unistd.h>

#include "text.h"

struct ao_scene_options ao_options_scene(const struct ao_options *opts)
{
    return (struct ao_scene_options){.budget = opts->scene_budget, .no_ground = !opts->ground, .bvh = opts->bvh,
                                     .crease = opts->crease, .crease_set = true, .sized = opts->width != 0};
}

void ao_options_size(const struct ao_options *opts, const struct ao_scene *scene, int *width, int *height)
{
    *width = opts->width ? opts->width : scene->width ? scene->width : 640;
    *height = opts->height ? opts->height : scene->height ? scene->height : 480;
}

bool ao_options_render(const struct ao_options *opts, const struct ao_scene *scene, const struct ao_tracer *tracer,
                       struct ao_render_config *config, struct ao_settings *settings)
{
    int width, height;
    ao_options_size(opts, scene, &width, &height);
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    *config = (struct ao_render_config){
        .scene = scene, .tracer = tracer,
        .threads = opts->threads ? opts->threads : (cores > 0 ? (int)cores : 1),
        .seed = opts->seed, .target_spp = opts->spp, .target_error = opts->target_error,
        .time_limit = opts->time_limit,
        .ao_distance = isnan(opts->ao_distance) ? scene->ao_distance : opts->ao_distance,
        .sequence = opts->sequence, .below = opts->below};
    *settings = (struct ao_settings){.width = width, .height = height, .sampling = opts->sampling, .aa = opts->aa,
                                     .spppp = (int)opts->spppp, .adaptive = opts->adaptive, .camera = scene->camera,
                                     .output = opts->view == AO_VIEW_MODE_NORMALS ? AO_OUTPUT_NORMALS : AO_OUTPUT_AO,
                                     .shading = opts->shading};
    struct ao_view view;
    if (ao_camera_view(&settings->camera, width, height, &view))
        return true;
    ao_text_report("%s: the camera cannot form an image", scene->name);
    return false;
}
