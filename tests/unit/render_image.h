/* For the cmocka tests: one render run to its target, its final linear image copied out. Header
 * only; include after cmocka.h. */
#ifndef AO_TEST_RENDER_IMAGE_H
#define AO_TEST_RENDER_IMAGE_H

#include <stdlib.h>
#include <string.h>

#include "render.h"
#include "scene.h"
#include "tracer.h"

/* Renders with config and settings until the target spp and returns a malloc'd copy of the final
 * frame's RGB floats (settings->width x settings->height). */
static inline float *render_image(const struct ao_render_config *config, const struct ao_settings *settings)
{
    struct ao_render *r = ao_render_create(config, settings);
    assert_non_null(r);
    assert_true(ao_render_wait(r));
    const struct ao_frame *frame = ao_render_take_frame(r);
    assert_non_null(frame);
    size_t bytes = 3 * sizeof(float) * (size_t)settings->width * (size_t)settings->height;
    float *copy = malloc(bytes);
    assert_non_null(copy);
    memcpy(copy, frame->rgb, bytes);
    ao_render_destroy(r);
    return copy;
}

#endif
