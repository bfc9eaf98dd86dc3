/* How a renderer renders (render.h): the scene and tracer, threads, seed, targets, the estimator's
 * fixed choices, the reference, the callbacks after each published frame and the share. Header
 * only: the renderer's files (render.c, pass.c) and its callers include it. */
#ifndef AO_RENDER_CONFIG_H
#define AO_RENDER_CONFIG_H

#include <stdint.h>

#include "frame.h"
#include "modes.h"

/* What the renderer reads through the config's pointers (share.h, scene.h, tracer.h). */
struct ao_render_share;
struct ao_scene;
struct ao_tracer;

/* How to render; scene, tracer, reference and share must outlive the renderer. The image size is
 * a setting (struct ao_settings). */
struct ao_render_config {
    const struct ao_scene *scene;
    const struct ao_tracer *tracer;
    struct ao_tracer *upgrade;   /* the tracer again when it has a better BVH to build beside
                                  * (ao_tracer_create_progressive): the render thread starts that
                                  * build after its first pass and switches to it between passes;
                                  * NULL: nothing to switch (and with two renderers on one tracer) */
    int threads;
    uint64_t seed;
    uint32_t target_spp;     /* per pixel; with adaptive sampling the most a pixel gets */
    double target_error;     /* stop when the estimated relative RMSE is at most this; 0: never */
    double time_limit;       /* stop at the first pass boundary after this many seconds; 0: never */
    float ao_distance;
    enum ao_sequence sequence;   /* random or Sobol numbers for jitter and directions */
    enum ao_below below;         /* directions below the geometric surface */
    const float *reference;  /* reference_width x reference_height x 3 linear floats, or NULL; the
                                RMSE is taken while the image has its size */
    int reference_width, reference_height;
    /* Called on the render thread after each published pass (stats rows, waking the GL thread). */
    void (*on_pass)(const struct ao_frame_info *info, void *user);
    /* Called on the render thread after each published preview, with the facts of the run it
     * begins (waking the GL thread); may be NULL. */
    void (*on_preview)(const struct ao_frame_info *info, void *user);
    void *user;
    const struct ao_render_share *share;   /* NULL: this process traces every tile */
};

#endif
