/* What the command line's options (cli.h) make of a scene: the options its loading takes, the image
 * size, and the renderer's config and first settings, for every front end that takes options (the
 * programs, the Python module). Pure; no I/O but the one message of a camera that cannot form an
 * image. */
#ifndef AO_OPTIONS_H
#define AO_OPTIONS_H

#include <stdbool.h>

#include "cli.h"
#include "frame.h"
#include "render_config.h"
#include "scene.h"
#include "scene_load.h"

/* The scene loading options that opts say (budget, ground, BVH, crease angle, a --size given). */
struct ao_scene_options ao_options_scene(const struct ao_options *opts);

/* The image size: --size, else the scene's `image` line, else 640x480. */
void ao_options_size(const struct ao_options *opts, const struct ao_scene *scene, int *width, int *height);

/* Fills *config (no callbacks, no reference, no share: the caller sets those) and *settings (the
 * scene's camera, the size ao_options_size says) from opts for the scene and its tracer; false
 * after one line naming the scene when its camera cannot form an image of that size. */
bool ao_options_render(const struct ao_options *opts, const struct ao_scene *scene, const struct ao_tracer *tracer,
                       struct ao_render_config *config, struct ao_settings *settings);

#endif
